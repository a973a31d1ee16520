//! What a transform reports per file after writing: how many targets changed, the largest
//! change, the skid range they were at, what was refused, and where the result went.

use std::fmt;
use std::path::PathBuf;

use crate::transform::FileResult;

/// The summary line of one transformed file.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FileSummary {
    /// The file, as named on input.
    pub path: PathBuf,
    /// Targets whose text changed.
    pub changed: usize,
    /// Largest translation change of any target whose move is known, mm.
    pub largest_mm: f64,
    /// Largest rotation change of any target whose move is known, degrees.
    pub largest_deg: f64,
    /// Joint targets changed whose move is not known (mirrored without the arm's kinematics),
    /// left out of `largest_mm` and `largest_deg`.
    pub moves_not_known: usize,
    /// Their largest change of one axis, degrees.
    pub largest_axes_deg: Option<f64>,
    /// Smallest and largest skid of the changed targets.
    pub skid_range: Option<(f64, f64)>,
    /// Targets left unchanged because the transform refused them.
    pub refused: usize,
    /// Where the file was written; `None` if it was not.
    pub written_to: Option<PathBuf>,
    /// The file actually replaced when the destination is a symbolic link.
    pub link_target: Option<PathBuf>,
    /// The backup of the file it replaced.
    pub backup: Option<PathBuf>,
    /// The change is a move (a mirror moves points by metres), not a correction.
    pub is_move: bool,
    /// The largest expanded uncertainty (k = 2, mm) of a corrected TCP, when the profile
    /// carries uncertainties.
    pub largest_uncertainty_mm: Option<f64>,
    /// Targets whose correction is smaller than its own expanded uncertainty, by name (or
    /// `line N`): the correction is within the doubt of the measurement.
    pub below_uncertainty: Vec<String>,
    /// The output differs from the input: with no target changed, offsets or frames were
    /// rewritten.
    pub edited: bool,
}

impl FileSummary {
    /// The summary of `file`, not yet written anywhere.
    ///
    /// Its figures from one reading of the change records, where the largest change, the skid
    /// range, the largest uncertainty and the targets below theirs each read them all (a
    /// record read back costs about 170 instructions, and the four readings were 7.7 M on the
    /// 2 MB bench module's 10,000 targets).
    pub fn new(file: &FileResult, is_move: bool) -> FileSummary {
        let (mut largest_mm, mut largest_deg) = (0.0, 0.0);
        let mut skid_range: Option<(f64, f64)> = None;
        let mut largest_uncertainty_mm: Option<f64> = None;
        let mut below_uncertainty = Vec::new();
        let (mut moves_not_known, mut largest_axes_deg) = (0, None);
        for c in file.changes.iter() {
            match c.axes_deg {
                None => {
                    (largest_mm, largest_deg) =
                        (f64::max(largest_mm, c.mm), f64::max(largest_deg, c.deg));
                }
                Some(a) => {
                    moves_not_known += 1;
                    largest_axes_deg = Some(largest_axes_deg.map_or(a, |m| f64::max(m, a)));
                }
            }
            if let Some(s) = c.skid {
                skid_range = Some(match skid_range {
                    None => (s, s),
                    Some((lo, hi)) => (f64::min(lo, s), f64::max(hi, s)),
                });
            }
            if let Some(u) = c.uncertainty_mm {
                largest_uncertainty_mm = Some(largest_uncertainty_mm.map_or(u, |m| f64::max(m, u)));
                if c.mm < u {
                    below_uncertainty.push(
                        c.name
                            .map_or_else(|| format!("line {}", c.line), str::to_owned),
                    );
                }
            }
        }
        FileSummary {
            path: file.path.clone(),
            changed: file.changes.len(),
            largest_mm,
            largest_deg,
            moves_not_known,
            largest_axes_deg,
            skid_range,
            refused: file.refusals.len(),
            written_to: None,
            link_target: None,
            backup: None,
            is_move,
            largest_uncertainty_mm,
            below_uncertainty,
            edited: file.changed(),
        }
    }
}

fn mm(v: f64) -> String {
    format!("{v:.3}")
}

impl fmt::Display for FileSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut target = String::new();
        if let Some(p) = &self.written_to {
            target = format!(" → {}", p.display());
            if let Some(r) = &self.link_target {
                target.push_str(&format!(" (the link's target {})", r.display()));
            }
            if let Some(b) = &self.backup {
                target.push_str(&format!(", backup {}", b.display()));
            }
        }
        let refused = match self.refused {
            0 => String::new(),
            n => format!(", {n} refused (left unchanged)"),
        };
        if self.changed == 0 {
            let what = if self.edited {
                "no target changed, offsets or frames rewritten"
            } else {
                "unchanged"
            };
            return write!(f, "{}: {what}{refused}{target}", self.path.display());
        }
        let skid = match self.skid_range {
            Some((lo, hi)) => format!(", skid {}…{} mm", mm(lo), mm(hi)),
            None => String::new(),
        };
        let largest = if self.is_move {
            "largest move"
        } else {
            "largest correction"
        };
        let uncertainty = match self.largest_uncertainty_mm {
            Some(u) => format!(", U (k=2) up to {} mm", mm(u)),
            None => String::new(),
        };
        let mut sizes = Vec::new();
        if self.changed > self.moves_not_known {
            sizes.push(format!(
                "{largest} {} mm / {:.4}°{uncertainty}",
                mm(self.largest_mm),
                self.largest_deg
            ));
        }
        // Never a move of 0 mm for what is not known.
        if let (n @ 1.., Some(a)) = (self.moves_not_known, self.largest_axes_deg) {
            sizes.push(format!(
                "{n} joint target(s) with axes changed by up to {a:.4}° (their move in mm is not known without the arm's kinematics)"
            ));
        }
        write!(
            f,
            "{}: {} target(s) changed, {}{skid}{refused}{target}",
            self.path.display(),
            self.changed,
            sizes.join(", "),
        )?;
        if let Some(first) = self.below_uncertainty.first() {
            write!(
                f,
                "\n{}: warning: {} target(s) are corrected by less than their own uncertainty (e.g. `{first}`): the correction is within the measurement's doubt; measure the track more densely or with less noise there",
                self.path.display(),
                self.below_uncertainty.len()
            )?;
        }
        Ok(())
    }
}

/// The line a dry run (nothing written) prints for a file that would change.
pub fn would_change(file: &FileResult) -> Option<String> {
    file.changed().then(|| match file.changes.len() {
        0 => format!(
            "{}: no target would change, offsets or frames would",
            file.path.display()
        ),
        n => format!("{}: {n} target(s) would change", file.path.display()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::TargetChange;

    fn result(changes: Vec<TargetChange>) -> FileResult {
        FileResult {
            path: PathBuf::from("a.mod"),
            original: b"x".to_vec().into(),
            output: b"y".to_vec(),
            refusals: Vec::new(),
            notes: Vec::new(),
            changes: changes.into_iter().collect(),
            widened: None,
            kept: Vec::new(),
        }
    }

    #[test]
    fn summary_lines_say_count_largest_change_and_skid_range() {
        let c = |mm, deg, skid| TargetChange {
            mm,
            deg,
            skid,
            name: None,
            line: 1,
            uncertainty_mm: None,
            axes_deg: None,
        };
        let f = result(vec![
            c(0.25, 0.001, Some(3000.0)),
            c(1.5, 0.02, Some(500.0)),
        ]);
        let mut s = FileSummary::new(&f, false);
        s.written_to = Some(PathBuf::from("a.mod"));
        s.backup = Some(PathBuf::from("a.mod.orig"));
        assert_eq!(
            s.to_string(),
            "a.mod: 2 target(s) changed, largest correction 1.500 mm / 0.0200°, skid 500.000…3000.000 mm → a.mod, backup a.mod.orig"
        );
        let moved = FileSummary::new(&f, true).to_string();
        assert!(moved.contains("largest move 1.500 mm"), "{moved}");
        let mut same = result(Vec::new());
        same.output = same.original.to_vec();
        assert_eq!(
            FileSummary::new(&same, false).to_string(),
            "a.mod: unchanged"
        );
        // Offsets or frames rewritten, no target: not "unchanged".
        let other = result(Vec::new());
        assert_eq!(
            FileSummary::new(&other, false).to_string(),
            "a.mod: no target changed, offsets or frames rewritten"
        );
        assert_eq!(
            would_change(&other).as_deref(),
            Some("a.mod: no target would change, offsets or frames would")
        );
        assert_eq!(would_change(&same), None);
        assert_eq!(
            would_change(&f).as_deref(),
            Some("a.mod: 2 target(s) would change")
        );
    }

    /// A joint target mirrored without the arm's kinematics has no known move: the summary
    /// says so with its largest axis change, and leaves it out of the largest move, where it
    /// was a move of 0 mm ("largest move 0.000 mm / 0.0000°" for joint targets alone).
    #[test]
    fn a_joint_target_whose_move_is_not_known_is_said_so_not_as_0_mm() {
        let c = |mm, deg, axes_deg| TargetChange {
            mm,
            deg,
            skid: None,
            name: None,
            line: 1,
            uncertainty_mm: None,
            axes_deg,
        };
        let joints = result(vec![c(0.0, 0.0, Some(10.0)), c(0.0, 0.0, Some(60.5))]);
        let mut s = FileSummary::new(&joints, true);
        s.written_to = Some(PathBuf::from("b.mod"));
        assert_eq!(
            s.to_string(),
            "a.mod: 2 target(s) changed, 2 joint target(s) with axes changed by up to 60.5000° (their move in mm is not known without the arm's kinematics) → b.mod"
        );
        assert_eq!((s.moves_not_known, s.largest_axes_deg), (2, Some(60.5)));
        let both = result(vec![c(0.0, 0.0, Some(10.0)), c(531.47, 104.39181, None)]);
        assert_eq!(
            FileSummary::new(&both, true).to_string(),
            "a.mod: 2 target(s) changed, largest move 531.470 mm / 104.3918°, 1 joint target(s) with axes changed by up to 10.0000° (their move in mm is not known without the arm's kinematics)"
        );
    }

    /// The one reading of the records gives what the separate folds over them give: the
    /// largest change and the skid range, the largest uncertainty by `reduce`,
    /// the targets below theirs by a filter; with NaNs, negative zeros and absent parts.
    #[test]
    fn the_summary_reads_the_records_once_as_the_folds_do() {
        let values = [0.5, -0.0, 0.0, f64::NAN, 2.25, -3.0, 0.1, f64::INFINITY];
        let pick = |i: usize, k: usize| values[(i * k + i / 3) % values.len()];
        let changes: Vec<TargetChange> = (0..200)
            .map(|i| TargetChange {
                mm: pick(i, 3),
                deg: pick(i, 5),
                skid: (i % 4 != 1).then(|| pick(i, 7)),
                name: (i % 3 == 0).then(|| format!("p{i}").into()),
                line: i + 1,
                uncertainty_mm: (i % 5 != 2).then(|| pick(i, 11)),
                axes_deg: None,
            })
            .collect();
        for n in [0, 1, 2, 7, 50, 200] {
            let f = result(changes[..n].to_vec());
            let s = FileSummary::new(&f, false);
            let bits = |v: f64| v.to_bits();
            let (mm, deg) = f.changes.iter().fold((0.0, 0.0), |(mm, deg), c| {
                (f64::max(mm, c.mm), f64::max(deg, c.deg))
            });
            assert_eq!(
                (bits(s.largest_mm), bits(s.largest_deg)),
                (bits(mm), bits(deg))
            );
            let skids = f.changes.iter().filter_map(|c| c.skid);
            let skid_range = skids.fold(None, |acc, s| match acc {
                None => Some((s, s)),
                Some((lo, hi)) => Some((f64::min(lo, s), f64::max(hi, s))),
            });
            let range = |r: Option<(f64, f64)>| r.map(|(lo, hi)| (bits(lo), bits(hi)));
            assert_eq!(range(s.skid_range), range(skid_range));
            let largest = f
                .changes
                .iter()
                .filter_map(|c| c.uncertainty_mm)
                .reduce(f64::max);
            assert_eq!(s.largest_uncertainty_mm.map(bits), largest.map(bits));
            let below: Vec<String> = f
                .changes
                .iter()
                .filter(|c| c.uncertainty_mm.is_some_and(|u| c.mm < u))
                .map(|c| {
                    c.name
                        .map_or_else(|| format!("line {}", c.line), str::to_owned)
                })
                .collect();
            assert_eq!(s.below_uncertainty, below);
            assert_eq!(s.changed, n);
        }
    }

    #[test]
    fn a_correction_below_its_uncertainty_is_a_warning_naming_the_target() {
        let c = |mm, name: &str, u| TargetChange {
            mm,
            deg: 0.0,
            skid: Some(100.0),
            name: Some(name.into()),
            line: 3,
            uncertainty_mm: Some(u),
            axes_deg: None,
        };
        let f = result(vec![c(0.5, "p1", 0.2), c(0.1, "p2", 0.25)]);
        let s = FileSummary::new(&f, false);
        assert_eq!(s.largest_uncertainty_mm, Some(0.25));
        assert_eq!(s.below_uncertainty, ["p2"]);
        let text = s.to_string();
        assert!(text.contains("U (k=2) up to 0.250 mm"), "{text}");
        assert!(
            text.contains(
                "1 target(s) are corrected by less than their own uncertainty (e.g. `p2`)"
            ),
            "{text}"
        );
    }
}
