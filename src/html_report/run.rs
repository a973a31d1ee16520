//! The run report of `correct`, `zero`, `mirror` or `transfer`: per file and target what
//! changed (old and new text, how far each target moved along the skid), what was refused
//! with its reason and location, and the cell and profile used, with their hashes.
//!
//! Its model is plain data so that a command builds it from its results in a few lines:
//! [`RunFile::from_result`] takes a transform's [`FileResult`], [`RunInput`] a file it read.

use std::fmt::Write as _;

use super::html::{Cell, Page, Row, Section, definitions, escape, table};
use super::svg::{Chart, Span, fmt_fixed};
use super::track::DataTable;
use crate::digest::sha256_hex;
use crate::syntax::latin1;
use crate::transform::{ChangeRef, FileResult, Refusal};

/// Headings of the run report's fixed sections, in page order.
pub mod headings {
    /// The headline figures and outcome.
    pub const SUMMARY: &str = "Summary";
    /// The cell, profiles and programs read, with their hashes.
    pub const INPUTS: &str = "Cell, profiles and programs";
    /// The correction each target got, over its skid position.
    pub const ALONG_SKID: &str = "Correction along the skid";
    /// Followed by the file's path.
    pub const FILE_PREFIX: &str = "Changes in ";
    /// The targets left unchanged, with why and what to do.
    pub const REFUSALS: &str = "Refused targets";
    /// Reach, joint limit and configuration checks.
    pub const CHECKS: &str = "Kinematics checks";
}

/// At most this many changed lines are listed per file; the rest are counted.
pub const MAX_LISTED_LINES: usize = 400;

/// A file the run read besides the programs: the cell, a profile.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInput {
    /// What it is (`cell`, `profile r1`), plain text.
    pub role: String,
    /// The path as given, plain text.
    pub path: String,
    /// SHA-256 of the bytes read, hex: ties the report to the exact file.
    pub sha256: String,
    /// Anything worth recording (`8 m, 17 knots, extrapolate error`), plain text.
    pub detail: String,
}

impl RunInput {
    /// Records a file read, hashing `bytes`.
    pub fn new(role: &str, path: &str, bytes: &[u8], detail: &str) -> RunInput {
        RunInput {
            role: role.to_owned(),
            path: path.to_owned(),
            sha256: sha256_hex(bytes),
            detail: detail.to_owned(),
        }
    }
}

/// One changed target.
#[derive(Clone, Debug, PartialEq)]
pub struct RunTarget {
    /// Its name, when the transform reports it.
    pub name: Option<String>,
    /// 1-based line, when the transform reports it.
    pub line: Option<usize>,
    /// The skid value it was transformed at.
    pub skid: Option<f64>,
    /// Translation change, mm.
    pub mm: f64,
    /// Rotation change, degrees.
    pub deg: f64,
    /// A joint target whose move is not known (no arm kinematics): its largest axis change,
    /// degrees; `mm` and `deg` are then no move.
    pub axes_deg: Option<f64>,
}

impl From<ChangeRef<'_>> for RunTarget {
    fn from(c: ChangeRef<'_>) -> RunTarget {
        RunTarget {
            name: c.name.map(str::to_owned),
            line: Some(c.line),
            skid: c.skid,
            mm: c.mm,
            deg: c.deg,
            axes_deg: c.axes_deg,
        }
    }
}

/// One line whose text changed: old and new (either empty when a line was only removed or
/// only added).
#[derive(Clone, Debug, PartialEq)]
pub struct ChangedLine {
    /// 1-based line in the input (in the output for an added line).
    pub line: usize,
    /// The line before the change (empty when added).
    pub old: String,
    /// The line after the change (empty when removed).
    pub new: String,
}

/// One refused target, located.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRefusal {
    /// 1-based line of the target.
    pub line: usize,
    /// 1-based column of the target.
    pub column: usize,
    /// The target's name.
    pub target: String,
    /// The reason's key (`joint-target`, `skid-out-of-range`).
    pub kind: String,
    /// What is wrong, plain text.
    pub message: String,
    /// What to do about it, plain text.
    pub hint: String,
}

impl From<&Refusal> for RunRefusal {
    fn from(r: &Refusal) -> RunRefusal {
        RunRefusal {
            line: r.line,
            column: r.column,
            target: r.target.clone(),
            kind: serde_json::to_value(r.kind)
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default(),
            message: r.message.clone(),
            hint: r.hint.clone(),
        }
    }
}

/// One program file of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunFile {
    /// The program path as given.
    pub path: String,
    /// SHA-256 of the input, hex.
    pub input_sha256: String,
    /// SHA-256 of the output, hex (equal to the input's when nothing changed).
    pub output_sha256: String,
    /// Each corrected target with its correction.
    pub targets: Vec<RunTarget>,
    /// The changed lines, at most `MAX_LISTED_LINES`.
    pub lines: Vec<ChangedLine>,
    /// The targets left unchanged in this file.
    pub refusals: Vec<RunRefusal>,
}

impl RunFile {
    /// From a transform's result for one file.
    pub fn from_result(r: &FileResult) -> RunFile {
        RunFile::from_parts(
            &r.path.display().to_string(),
            &r.original,
            &r.output,
            r.changes.iter().map(RunTarget::from).collect(),
            r.refusals.iter().map(RunRefusal::from).collect(),
        )
    }

    /// From the bytes before and after, the changed targets and the refusals.
    pub fn from_parts(
        path: &str,
        original: &[u8],
        output: &[u8],
        targets: Vec<RunTarget>,
        refusals: Vec<RunRefusal>,
    ) -> RunFile {
        RunFile {
            path: path.to_owned(),
            input_sha256: sha256_hex(original),
            output_sha256: sha256_hex(output),
            targets,
            lines: changed_lines(original, output),
            refusals,
        }
    }

    /// Whether the output differs from the input.
    pub fn changed(&self) -> bool {
        self.input_sha256 != self.output_sha256
    }
}

/// The lines that differ, old paired with new in order within each changed block.
pub fn changed_lines(original: &[u8], output: &[u8]) -> Vec<ChangedLine> {
    // The run's diff, which is linear in the file (a whole-file Myers diff took 80 s on a
    // 20 MB module whose declarations were all corrected).
    let (old_lines, new_lines, ops) = crate::output::diff::line_ops(original, output);
    let text = |line: Option<&&[u8]>| {
        line.map(|l| latin1(l).trim_end_matches(['\n', '\r']).to_owned())
            .unwrap_or_default()
    };
    let mut out = Vec::new();
    for op in ops {
        let (tag, o, n) = op.as_tag_tuple();
        if tag == similar::DiffTag::Equal {
            continue;
        }
        let count = o.len().max(n.len());
        for i in 0..count {
            let old_line = o.start + i;
            let new_line = n.start + i;
            out.push(ChangedLine {
                line: if i < o.len() { old_line } else { new_line } + 1,
                old: text(old_lines.get(old_line).filter(|_| i < o.len())),
                new: text(new_lines.get(new_line).filter(|_| i < n.len())),
            });
        }
    }
    out
}

/// Everything a run report shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunReport {
    /// `correct`, `zero`, `mirror`, `transfer`.
    pub command: String,
    /// The command line as given, plain text.
    pub arguments: String,
    /// What happened to the outputs (`written to out/`, `refused: nothing written`).
    pub outcome: String,
    /// The cell, profiles and other files read besides the programs.
    pub inputs: Vec<RunInput>,
    /// Each program the run read.
    pub files: Vec<RunFile>,
    /// Kinematics checks (reach, joint limits, configuration), when the run made them.
    pub checks: Vec<DataTable>,
}

/// The run report page.
pub fn run_report(r: &RunReport) -> String {
    Page {
        title: format!("trackfix {} report", r.command),
        subtitle: if r.arguments.is_empty() {
            format!("{} file(s).", r.files.len())
        } else {
            format!("trackfix {}", r.arguments)
        },
        sections: run_sections(r),
    }
    .render()
}

/// The run report's sections, in page order.
pub fn run_sections(r: &RunReport) -> Vec<Section> {
    let mut out = vec![summary_section(r), inputs_section(r), along_skid_section(r)];
    for (i, f) in r.files.iter().enumerate() {
        out.push(file_section(i, f));
    }
    out.push(refusals_section(r));
    if !r.checks.is_empty() {
        let mut sec = Section::new("checks", headings::CHECKS);
        for t in &r.checks {
            sec.raw(&t.to_html());
        }
        out.push(sec);
    }
    out
}

fn all_targets(r: &RunReport) -> impl Iterator<Item = &RunTarget> {
    r.files.iter().flat_map(|f| &f.targets)
}

fn summary_section(r: &RunReport) -> Section {
    let mut sec = Section::new("summary", headings::SUMMARY);
    let targets = all_targets(r).count();
    let refusals: usize = r.files.iter().map(|f| f.refusals.len()).sum();
    let changed = r.files.iter().filter(|f| f.changed()).count();
    let mm = all_targets(r).map(|t| t.mm).fold(0.0, f64::max);
    let deg = all_targets(r).map(|t| t.deg).fold(0.0, f64::max);
    let mut items = vec![
        ("command", r.command.clone()),
        (
            "files",
            format!("{} read, {changed} changed", r.files.len()),
        ),
        ("targets changed", targets.to_string()),
        ("targets refused", refusals.to_string()),
        ("largest change", format!("{mm:.3} mm, {deg:.4} deg")),
    ];
    if !r.outcome.is_empty() {
        items.push(("outcome", r.outcome.clone()));
    }
    sec.raw(&definitions(&items));
    if refusals > 0 {
        sec.para_class(
            "warn",
            &format!(
                "{refusals} target(s) were not changed: see {} for each one's reason and location.",
                headings::REFUSALS
            ),
        );
    }
    sec
}

fn inputs_section(r: &RunReport) -> Section {
    let mut sec = Section::new("inputs", headings::INPUTS);
    let rows: Vec<Row> = r
        .inputs
        .iter()
        .map(|i| {
            Row::new(vec![
                Cell::text(i.role.clone()),
                Cell::code(i.path.clone()),
                Cell::code(i.sha256.clone()),
                Cell::text(i.detail.clone()),
            ])
        })
        .collect();
    if rows.is_empty() {
        sec.para("No cell or profile file was read.");
    } else {
        sec.raw(&table(&["input", "file", "sha256", "details"], &rows));
    }
    sec.sub("Programs");
    let rows: Vec<Row> = r
        .files
        .iter()
        .map(|f| {
            Row::new(vec![
                Cell::code(f.path.clone()),
                Cell::code(f.input_sha256.clone()),
                Cell::code(if f.changed() {
                    f.output_sha256.clone()
                } else {
                    "unchanged".to_owned()
                }),
                Cell::num(f.targets.len().to_string()),
                Cell::num(f.refusals.len().to_string()),
            ])
        })
        .collect();
    sec.raw(&table(
        &[
            "file",
            "sha256 before",
            "sha256 after",
            "targets changed",
            "refused",
        ],
        &rows,
    ));
    sec
}

fn along_skid_section(r: &RunReport) -> Section {
    let mut sec = Section::new("along-skid", headings::ALONG_SKID);
    // A target whose move is not known has no point to plot.
    let with_skid: Vec<&RunTarget> = all_targets(r)
        .filter(|t| t.skid.is_some() && t.axes_deg.is_none())
        .collect();
    let without = all_targets(r).count() - with_skid.len();
    if with_skid.is_empty() {
        sec.para("No changed target has a skid value: nothing to plot along the track.");
        return sec;
    }
    let skids = || with_skid.iter().filter_map(|t| t.skid);
    let xs = Span::padded(skids());
    sec.raw("<div class=\"grid\">");
    for (what, unit, value) in [
        (
            "translation",
            "mm",
            (|t: &RunTarget| t.mm) as fn(&RunTarget) -> f64,
        ),
        ("rotation", "deg", |t: &RunTarget| t.deg),
    ] {
        let ys = Span::padded(with_skid.iter().map(|t| value(t))).including(0.0);
        let mut ch = Chart::new(520.0, 260.0, xs, ys)
            .title(&format!("Change of each target: {what} [{unit}]"))
            .labels("skid [mm]", &format!("{what} [{unit}]"));
        for t in &with_skid {
            let skid = t.skid.unwrap_or(0.0);
            let name = t.name.as_deref().unwrap_or("target");
            ch.dot(
                skid,
                value(t),
                3.0,
                "knot",
                Some(&format!(
                    "{name} at skid {skid} mm: {} {unit}",
                    fmt_fixed(value(t), if unit == "mm" { 3 } else { 4 })
                )),
            );
        }
        sec.raw(&ch.render());
    }
    sec.raw("</div>");
    if without > 0 {
        sec.para_class(
            "note",
            &format!("{without} changed target(s) have no skid value or no known move and are not plotted."),
        );
    }
    sec
}

fn file_section(i: usize, f: &RunFile) -> Section {
    let mut sec = Section::new(
        &format!("file-{}", i + 1),
        &format!("{}{}", headings::FILE_PREFIX, f.path),
    );
    if !f.changed() {
        sec.para("Unchanged: no byte of this file differs.");
    }
    if !f.targets.is_empty() {
        sec.sub("Changed targets");
        // Name and line columns only when the transform reports them.
        let names = f.targets.iter().any(|t| t.name.is_some());
        let lines = f.targets.iter().any(|t| t.line.is_some());
        let rows: Vec<Row> = f
            .targets
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let mut cells = vec![Cell::num((k + 1).to_string())];
                if names {
                    cells.push(Cell::text(t.name.clone().unwrap_or_default()));
                }
                if lines {
                    cells.push(Cell::num(t.line.map(|l| l.to_string()).unwrap_or_default()));
                }
                let (mm, deg) = match t.axes_deg {
                    None => (format!("{:.3}", t.mm), format!("{:.4}", t.deg)),
                    Some(a) => (
                        "not known (no kinematics)".to_owned(),
                        format!("axes up to {a:.4}"),
                    ),
                };
                cells.extend([
                    Cell::num(t.skid.map(|s| format!("{s}")).unwrap_or_default()),
                    Cell::num(mm),
                    Cell::num(deg),
                ]);
                Row::new(cells)
            })
            .collect();
        let mut headers = vec!["#"];
        if names {
            headers.push("target");
        }
        if lines {
            headers.push("line");
        }
        headers.extend(["skid [mm]", "moved [mm]", "turned [deg]"]);
        sec.raw(&table(&headers, &rows));
    }
    if !f.lines.is_empty() {
        sec.sub("Old and new text");
        let mut s = String::from(
            "<table class=\"lines\">\n<thead><tr><th>line</th><th>old</th><th>new</th></tr></thead>\n<tbody>\n",
        );
        for l in f.lines.iter().take(MAX_LISTED_LINES) {
            let _ = writeln!(
                s,
                "<tr><td class=\"n\">{}</td><td><code>{}</code></td><td><code>{}</code></td></tr>",
                l.line,
                escape(&l.old),
                escape(&l.new)
            );
        }
        s.push_str("</tbody>\n</table>\n");
        sec.raw(&s);
        if f.lines.len() > MAX_LISTED_LINES {
            sec.para_class(
                "note",
                &format!(
                    "{} more changed line(s) not listed; the sha256 above identifies the output.",
                    f.lines.len() - MAX_LISTED_LINES
                ),
            );
        }
    }
    sec
}

fn refusals_section(r: &RunReport) -> Section {
    let mut sec = Section::new("refusals", headings::REFUSALS);
    let rows: Vec<Row> = r
        .files
        .iter()
        .flat_map(|f| {
            f.refusals.iter().map(move |x| {
                Row::new(vec![
                    Cell::code(format!("{}:{}:{}", f.path, x.line, x.column)),
                    Cell::text(x.target.clone()),
                    Cell::text(x.kind.clone()),
                    Cell::text(x.message.clone()),
                    Cell::text(x.hint.clone()),
                ])
                .with_class("outlier")
            })
        })
        .collect();
    if rows.is_empty() {
        sec.para("None: every target the command applies to was changed.");
    } else {
        sec.raw(&table(
            &["location", "target", "reason", "message", "what to do"],
            &rows,
        ));
    }
    sec
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_lines_pair_old_and_new() {
        let a = b"A\r\nx := 1.5;\r\nB\r\ny := 2;\r\n";
        let b = b"A\r\nx := 1.625;\r\nB\r\ny := 2.25;\r\n";
        let l = changed_lines(a, b);
        assert_eq!(
            l,
            vec![
                ChangedLine {
                    line: 2,
                    old: "x := 1.5;".into(),
                    new: "x := 1.625;".into()
                },
                ChangedLine {
                    line: 4,
                    old: "y := 2;".into(),
                    new: "y := 2.25;".into()
                },
            ]
        );
        assert!(changed_lines(a, a).is_empty());
    }

    #[test]
    fn checks_section_only_with_checks_and_refusals_always() {
        let mut r = RunReport {
            command: "mirror".into(),
            files: vec![RunFile::from_parts("a.mod", b"x\n", b"x\n", vec![], vec![])],
            ..RunReport::default()
        };
        let headings = |r: &RunReport| -> Vec<String> {
            run_sections(r).into_iter().map(|s| s.heading).collect()
        };
        assert_eq!(
            headings(&r),
            [
                headings::SUMMARY,
                headings::INPUTS,
                headings::ALONG_SKID,
                "Changes in a.mod",
                headings::REFUSALS
            ]
        );
        let html = run_report(&r);
        assert!(html.contains("Unchanged: no byte of this file differs."));
        assert!(html.contains("None: every target the command applies to was changed."));
        assert!(html.contains("No changed target has a skid value"));
        r.checks.push(DataTable {
            title: "Reach".into(),
            columns: vec!["target".into(), "reach [mm]".into()],
            rows: vec![vec!["p10".into(), "1820.5".into()]],
            note: None,
        });
        assert_eq!(
            headings(&r).last().map(String::as_str),
            Some(headings::CHECKS)
        );
    }

    #[test]
    fn report_escapes_names_and_lists_refusals_with_locations() {
        let r = RunReport {
            command: "correct".into(),
            arguments: "correct <x>.mod".into(),
            outcome: String::new(),
            inputs: vec![RunInput::new("cell", "c&d.toml", b"x", "")],
            files: vec![RunFile::from_parts(
                "<p>.mod",
                b"a\n",
                b"b\n",
                vec![RunTarget {
                    name: Some("p<10>".into()),
                    line: Some(1),
                    skid: Some(500.0),
                    mm: 0.5,
                    deg: 0.01,
                    axes_deg: None,
                }],
                vec![RunRefusal {
                    line: 3,
                    column: 7,
                    target: "jt<1>".into(),
                    kind: "joint-target".into(),
                    message: "a joint target".into(),
                    hint: "skip".into(),
                }],
            )],
            checks: vec![],
        };
        let html = run_report(&r);
        assert!(!html.contains("<p>.mod") && html.contains("&lt;p&gt;.mod:3:7"));
        assert!(html.contains("p&lt;10&gt;") && html.contains("jt&lt;1&gt;"));
        assert!(html.contains("c&amp;d.toml"));
        assert!(html.contains(&sha256_hex(b"x")));
    }
}
