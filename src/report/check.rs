//! What `check` reports: per file the parser's diagnostics, a failed round trip and the lints
//! of the position model, and the batch's one-line summary.

use std::fmt;

use crate::position::{Config, Orientation, ParsedFile, Program};
use crate::syntax::{Diagnostic, Severity, Span};

/// How far `|q|` may stray from 1 before `check` calls a quaternion non-normalised. Six written
/// decimals give about 1e-6; RobotStudio's own output stays well inside 1e-4.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-4;

/// Everything `check` says about a file: the parser's diagnostics, a failed round trip, and the
/// lints of the model (non-normalised quaternions, a target used with two work objects).
/// Sorted by position.
pub fn lints(file: &ParsedFile) -> Vec<Diagnostic> {
    let mut out = file.diagnostics.clone();
    if file.source.iter().all(u8::is_ascii_whitespace) {
        out.push(
            Diagnostic::warning(Span::new(0, 0), "the file is empty: it holds no program")
                .with_hint("a truncated copy? restore it from the controller's backup"),
        );
    }
    out.extend(round_trip_error(file));
    if let Some(at) = file.lines.first_control_byte() {
        let n = file
            .source
            .iter()
            .filter(|&&b| crate::syntax::is_control_byte(b))
            .count();
        out.push(
            Diagnostic::warning(
                Span::new(at, at + 1),
                format!(
                    "control character {:#04x} in the text ({n} in the file): the controller may reject it, a terminal may run it",
                    file.source[at]
                ),
            )
            .with_hint("delete it; trackfix shows such bytes escaped, as \\x1b"),
        );
    }
    // Only the orientation and the configuration of each target are read (the lints look at
    // nothing else), only where the verdict kept with it says they could find something
    // (`values_pass_lints`), and its name only for a finding. A target whose verdict passes,
    // whose text the dialect finds nothing in and that is used with one work object at most
    // has nothing to report: its head is read no further than its span and verdict.
    let list = &file.positions;
    for i in 0..list.len() {
        let Some((span, verdict)) = list.span_and_verdict(i) else {
            continue;
        };
        let in_text = crate::transform::policy::implausible_text(file, span);
        let one_wobj = list.usage(i).is_none_or(|u| u.other_wobjs().is_empty());
        if verdict && in_text.is_none() && one_wobj {
            continue;
        }
        let Some(target) = list.for_lints(i, &file.source) else {
            continue;
        };
        let label = || crate::position::label(target.name(), target.kind);
        #[cfg(debug_assertions)]
        if target.values.is_none() {
            let t = list.orientation_and_config(i, &file.source);
            debug_assert!(t.is_some_and(|t| values_pass_lints(t.orient.as_ref(), &t.config)));
        }
        let problem = match &target.values {
            None => in_text,
            Some((orient, config)) => {
                out.extend(quaternion_finding(span, orient.as_ref(), label));
                in_text.or_else(|| {
                    crate::transform::policy::implausible_values(orient.as_ref(), config)
                })
            }
        };
        if let Some(problem) = problem {
            out.push(
                Diagnostic::warning(span, format!("`{}` {problem}", label())).with_hint(
                    "a typo or a placeholder: transforms refuse the target until it is fixed",
                ),
            );
        }
        let Some(usage) = list.usage(i) else { continue };
        if !usage.other_wobjs().is_empty() {
            let already = file.diagnostics.iter().any(|d| {
                d.span.start <= span.start
                    && span.start < d.span.end.max(d.span.start + 1)
                    && d.message.contains("work object")
            });
            if !already {
                let what = file.language.dialect().vocabulary().frames;
                let all: Vec<&str> = usage.work_objects().collect();
                out.push(
                    Diagnostic::warning(
                        span,
                        format!(
                            "`{}` is used with {} {what}: {}",
                            label(),
                            crate::transform::policy::frame_count(all.len()),
                            all.join(", ")
                        ),
                    )
                    .with_hint("a transform cannot move one target for two frames; declare one target per frame"),
                );
            }
        }
    }
    out.sort_by_key(|d| (d.span.start, d.span.end));
    out
}

use crate::transform::policy::quaternion_norm as norm;

/// Whether a quaternion of this length passes the lints: not `[0,0,0,0]` and normalised
/// (written so that a NaN length does not pass).
fn norm_passes_lints(norm: f64) -> bool {
    norm != 0.0 && (norm - 1.0).abs() <= QUATERNION_NORM_TOLERANCE
}

/// What the lints say of a written quaternion: a note for `[0,0,0,0]`, a warning when it is
/// not normalised. `label` names the target.
fn quaternion_finding(
    span: Span,
    orient: Option<&Orientation>,
    label: impl Fn() -> String,
) -> Option<Diagnostic> {
    let q = orient.and_then(Orientation::written_quaternion)?;
    let norm = norm(q);
    if norm == 0.0 {
        // Unused slots of PERS robtarget arrays are written this way by controllers: worth
        // knowing, not a defect of the program.
        Some(
            Diagnostic::note(
                span,
                format!("`{}` has the quaternion [0,0,0,0]: an unset slot", label()),
            )
            .with_hint("transforms leave it as written and report it"),
        )
    } else if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        Some(
            Diagnostic::warning(
                span,
                format!(
                    "quaternion of `{}` is not normalised (|q| = {norm:.6})",
                    label()
                ),
            )
            .with_hint(
                "the controller rejects it; `trackfix correct` writes normalised quaternions",
            ),
        )
    } else {
        None
    }
}

/// Whether the lints that look at a target's values (the quaternion's length, the
/// plausibility of the orientation and the configuration) find nothing in these: worked out
/// once as the target is packed, so that [`lints`] reads the values again only of the few
/// targets where they may find something.
pub fn values_pass_lints(orient: Option<&Orientation>, config: &Config) -> bool {
    let quaternion_passes = orient
        .and_then(Orientation::written_quaternion)
        .is_none_or(|q| norm_passes_lints(norm(q)));
    quaternion_passes && crate::transform::policy::implausible_values(orient, config).is_none()
}

/// [`values_pass_lints`] of a robtarget that writes all four quaternion components and all
/// four of `cf1, cf4, cf6, cfx`, from the values alone: what the parser's fast path packs,
/// once per target of a file (the general function cost about as much as the reading saved).
pub(crate) fn robtarget_values_pass_lints(q: [f64; 4], cf: [f64; 4]) -> bool {
    use crate::transform::policy::{plausible_cf, plausible_quaternion_norm};
    let norm = norm(q);
    norm_passes_lints(norm) && plausible_quaternion_norm(norm) && cf.into_iter().all(plausible_cf)
}

/// A failed round trip, as an error.
fn round_trip_error(file: &ParsedFile) -> Option<Diagnostic> {
    (!file.round_trip).then(|| {
        Diagnostic::error(
            Span::new(0, 0),
            "printing the parsed file does not give back its bytes",
        )
        .with_hint("this is a trackfix bug: please report it with the file attached")
    })
}

/// The errors among [`lints`]: the parser's and a failed round trip (every lint of the model
/// is a warning or a note), without decoding a position. Sorted by position.
pub fn errors(file: &ParsedFile) -> Vec<Diagnostic> {
    let mut out: Vec<Diagnostic> = file
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .cloned()
        .collect();
    out.extend(round_trip_error(file));
    out.sort_by_key(|d| (d.span.start, d.span.end));
    out
}

/// The findings of one file: its diagnostics of at least warning severity.
pub fn findings(file: &ParsedFile) -> Vec<Diagnostic> {
    lints(file)
        .into_iter()
        .filter(|d| d.severity >= Severity::Warning)
        .collect()
}

/// The counts `check` ends with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CheckSummary {
    /// Files read.
    pub files: usize,
    /// Files that print back byte for byte.
    pub round_trips: usize,
    /// Warnings and errors over all files.
    pub findings: usize,
    /// Files with at least one finding.
    pub files_with_findings: usize,
    /// Files skipped with a note (binary, RobotStudio XML).
    pub skipped: usize,
    /// Files that could not be read.
    pub unreadable: usize,
}

impl CheckSummary {
    /// Counts one program's files with their findings.
    pub fn add(&mut self, program: &Program) {
        for file in &program.files {
            self.add_file(file, findings(file).len());
        }
    }

    /// Counts one file with `findings` findings.
    pub fn add_file(&mut self, file: &ParsedFile, findings: usize) {
        self.files += 1;
        self.round_trips += usize::from(file.round_trip);
        self.findings += findings;
        self.files_with_findings += usize::from(findings > 0);
    }
}

/// `, 2 skipped`, or nothing for zero.
pub(crate) fn count_suffix(n: usize, what: &str) -> String {
    if n == 0 {
        String::new()
    } else {
        format!(", {n} {what}")
    }
}

impl fmt::Display for CheckSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "checked {} files: {} round-trip byte for byte, {} findings in {} files{}{}",
            self.files,
            self.round_trips,
            self.findings,
            self.files_with_findings,
            count_suffix(self.skipped, "skipped"),
            count_suffix(self.unreadable, "unreadable")
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::position::{Config, Orientation};

    /// The lint names the first control byte, where it is, and how many the file holds: the
    /// first as the index's pass noted it, a word boundary (8 bytes) away from the line start
    /// or not, in RAPID and KRL alike.
    #[test]
    fn a_control_byte_is_reported_at_the_first_with_the_count() {
        for pad in 0..10 {
            let spaces = " ".repeat(pad);
            let rapid = format!("MODULE m\r\n{spaces}! a\x1bb\x07\r\nENDMODULE\r\n");
            let krl = format!("DEF m()\r\n{spaces};a\x1bb\x07\r\nEND\r\n");
            let files = [
                crate::rapid::parse_file(std::path::Path::new("m.mod"), rapid.into_bytes()),
                crate::krl::parse_file(std::path::Path::new("m.src"), krl.into_bytes()),
            ];
            for file in files {
                let at = file.source.iter().position(|&b| b == 0x1b).unwrap();
                let found: Vec<_> = super::lints(&file)
                    .into_iter()
                    .filter(|d| d.message.starts_with("control character"))
                    .collect();
                assert_eq!(found.len(), 1, "{pad}");
                assert_eq!(found[0].span, crate::syntax::Span::new(at, at + 1), "{pad}");
                assert!(
                    found[0]
                        .message
                        .contains("0x1b in the text (2 in the file)"),
                    "{}",
                    found[0].message
                );
            }
        }
    }

    /// The verdict kept with each packed target says "pass" exactly where the lints of a file
    /// holding only that target find nothing in its values: a target that passes is never
    /// looked at again, so a wrong "pass" would hide a finding.
    #[test]
    fn the_packed_verdict_is_what_the_lints_find() {
        let cases = [
            ("[0,0.707107,0.707107,0]", "[0,0,-1,0]", true),
            ("[1,0,0,0]", "[-1,2,0,1]", true),
            ("[0,0,0,0]", "[0,0,0,0]", false),
            ("[1.0002,0,0,0]", "[0,0,0,0]", false),
            ("[1.00009,0,0,0]", "[0,0,0,0]", true),
            ("[1.5,0,0,0]", "[0,0,0,0]", false),
            ("[1,0,0,0]", "[0,1.5,0,0]", false),
            ("[1,0,0,0]", "[0,0,9E9,0]", false),
        ];
        for (q, cf, passes) in cases {
            let text = format!(
                "MODULE m\n  CONST robtarget p:=[[1,2,3],{q},{cf},[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n"
            );
            let file = crate::rapid::parse_file(std::path::Path::new("m.mod"), text.into_bytes());
            let p = file.positions.get(0, &file.source).unwrap();
            let orient = p.cartesian.as_ref().and_then(|c| c.orient.as_ref());
            assert_eq!(
                super::values_pass_lints(orient, &p.config),
                passes,
                "{q} {cf}"
            );
            let values = |f: &[Option<crate::position::NumField>]| -> [f64; 4] {
                std::array::from_fn(|k| f[k].unwrap().value())
            };
            let (Some(Orientation::Quaternion(qf)), Config::Quadrants(cff)) = (orient, &p.config)
            else {
                panic!("a robtarget");
            };
            assert_eq!(
                super::robtarget_values_pass_lints(values(qf), values(cff)),
                passes,
                "{q} {cf}"
            );
            let target = file.positions.for_lints(0, &file.source).unwrap();
            assert_eq!(target.values.is_none(), passes, "{q} {cf}");
            let found = super::lints(&file)
                .iter()
                .any(|d| d.message.contains("`p`"));
            assert_eq!(found, !passes, "{q} {cf}");
        }
    }
}
