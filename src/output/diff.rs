//! The unified diff of a run's changes, in time linear in the file.
//!
//! A transform splices a few literals into a file that otherwise stays byte for byte, so the
//! two versions agree almost everywhere. The diff walks both files line by line in step; where
//! they part, it finds the nearest point where they agree again (a few lines in a row) and runs
//! Myers' algorithm on that small block only. A diff of the whole file at once (what the
//! `similar` crate does for a text) is quadratic when the changes are spread over a large
//! file: 332 s for a 20 MB module.
//!
//! A block too large for Myers (a module whose 100,000 declarations were all rewritten: 80 s)
//! is a block rewritten in place: its end is found along the few diagonals near the one it
//! starts on, and its lines are paired old with new in order.
//!
//! The output is the format `similar` writes (`--- a/…`, `+++ b/…`, hunks with one line of
//! context), so diffs read as before.

use std::hash::{Hash as _, Hasher as _};
use std::io::Write as _;
use std::path::Path;

use similar::{Algorithm, DiffOp, capture_diff_deadline, group_diff_ops};

/// Lines of unchanged context around each change.
const CONTEXT: usize = 1;
/// Equal lines in a row that count as the two files agreeing again.
const RESYNC: usize = 3;
/// The largest block (old + new lines) searched for a point of agreement in every direction;
/// beyond it the search follows the diagonals of a block rewritten in place.
const MAX_BLOCK: usize = 4000;
/// How many more lines one side of a block rewritten in place may have (lines a transform
/// added, such as a stamp), for the search beyond [`MAX_BLOCK`].
const MAX_SHIFT: usize = 8;

/// Lines as `diff` and `patch` split them: after each `\n` (a `\r\n` line keeps its `\r`, and
/// a lone `\r` is part of its line, so that the diff applies with `patch`).
fn lines(text: &[u8]) -> Vec<&[u8]> {
    text.split_inclusive(|&b| b == b'\n').collect()
}

fn hash(line: &[u8]) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    line.hash(&mut h);
    h.finish()
}

/// One side of the diff: its lines and their hashes (so that a comparison is one integer
/// compare almost always).
struct Side<'a> {
    lines: Vec<&'a [u8]>,
    hashes: Vec<u64>,
}

impl<'a> Side<'a> {
    fn new(text: &'a [u8]) -> Side<'a> {
        let lines = lines(text);
        let hashes = lines.iter().map(|l| hash(l)).collect();
        Side { lines, hashes }
    }

    fn len(&self) -> usize {
        self.lines.len()
    }
}

fn same(a: &Side<'_>, i: usize, b: &Side<'_>, j: usize) -> bool {
    a.hashes[i] == b.hashes[j] && a.lines[i] == b.lines[j]
}

/// Whether the files agree from `i`/`j` on: `RESYNC` equal lines, or equal to both ends.
fn agree(a: &Side<'_>, i: usize, b: &Side<'_>, j: usize) -> bool {
    for t in 0..RESYNC {
        match (i + t < a.len(), j + t < b.len()) {
            (true, true) if same(a, i + t, b, j + t) => {}
            (false, false) => return true,
            _ => return false,
        }
    }
    true
}

/// The nearest point after `i`/`j` where the files agree again. Tried in order of the larger
/// side skipped, and for each first as many old lines as new (a transform rewrites lines in
/// place far more often than it adds or drops one).
fn resync(a: &Side<'_>, i: usize, b: &Side<'_>, j: usize) -> (usize, usize) {
    let reach = (a.len() - i).max(b.len() - j).min(MAX_BLOCK);
    for m in 1..=reach {
        for short in (0..=m).rev() {
            for (x, y) in [(m, short), (short, m)] {
                if i + x <= a.len() && j + y <= b.len() && agree(a, i + x, b, j + y) {
                    return (i + x, j + y);
                }
            }
        }
    }
    far_resync(a, i, b, j).unwrap_or((a.len(), b.len()))
}

/// Beyond [`MAX_BLOCK`]: the nearest point of agreement on the diagonals at most
/// [`MAX_SHIFT`] lines off the one from `i`/`j`, in time linear in the block. `None` if the
/// files do not agree again there.
fn far_resync(a: &Side<'_>, i: usize, b: &Side<'_>, j: usize) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    let diagonals = std::iter::once((0, 0)).chain((1..=MAX_SHIFT).flat_map(|s| [(s, 0), (0, s)]));
    for (dx, dy) in diagonals {
        let (mut x, mut y) = (i + dx, j + dy);
        while x <= a.len() && y <= b.len() {
            if best.is_some_and(|(bx, by)| x + y >= bx + by) {
                break;
            }
            if (x, y) != (i, j) && agree(a, x, b, y) {
                best = Some((x, y));
                break;
            }
            x += 1;
            y += 1;
        }
    }
    best
}

/// The operations of a block rewritten in place: its lines paired old with new in order (equal
/// pairs are kept as equal), and the lines one side has more deleted or inserted at its end.
/// Linear where Myers' algorithm would be quadratic in the block.
fn paired(
    a: &Side<'_>,
    old: std::ops::Range<usize>,
    b: &Side<'_>,
    new: std::ops::Range<usize>,
    ops: &mut Vec<DiffOp>,
) {
    let n = old.len().min(new.len());
    let mut k = 0;
    while k < n {
        let equal = same(a, old.start + k, b, new.start + k);
        let run = (k..n)
            .take_while(|&t| same(a, old.start + t, b, new.start + t) == equal)
            .count();
        let (old_index, new_index) = (old.start + k, new.start + k);
        if equal {
            push_equal(ops, old_index, new_index, run);
        } else {
            ops.push(DiffOp::Replace {
                old_index,
                old_len: run,
                new_index,
                new_len: run,
            });
        }
        k += run;
    }
    if old.len() > n {
        ops.push(DiffOp::Delete {
            old_index: old.start + n,
            old_len: old.len() - n,
            new_index: new.start + n,
        });
    }
    if new.len() > n {
        ops.push(DiffOp::Insert {
            old_index: old.start + n,
            new_index: new.start + n,
            new_len: new.len() - n,
        });
    }
}

/// Appends `len` equal lines from `i`/`j`, merged into the equal run before them.
fn push_equal(ops: &mut Vec<DiffOp>, i: usize, j: usize, len: usize) {
    if len == 0 {
        return;
    }
    if let Some(DiffOp::Equal {
        old_index, len: l, ..
    }) = ops.last_mut()
        && *old_index + *l == i
    {
        *l += len;
        return;
    }
    ops.push(DiffOp::Equal {
        old_index: i,
        new_index: j,
        len,
    });
}

/// The line operations turning `old` into `new`, in order.
fn ops(a: &Side<'_>, b: &Side<'_>) -> Vec<DiffOp> {
    let mut ops: Vec<DiffOp> = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let start = (i, j);
        while i < a.len() && j < b.len() && same(a, i, b, j) {
            i += 1;
            j += 1;
        }
        push_equal(&mut ops, start.0, start.1, i - start.0);
        if i == a.len() && j == b.len() {
            break;
        }
        let (ei, ej) = resync(a, i, b, j);
        if (ei - i) + (ej - j) > 2 * MAX_BLOCK {
            paired(a, i..ei, b, j..ej, &mut ops);
            (i, j) = (ei, ej);
            continue;
        }
        for op in capture_diff_deadline(Algorithm::Myers, &a.lines, i..ei, &b.lines, j..ej, None) {
            match op {
                DiffOp::Equal {
                    old_index,
                    new_index,
                    len,
                } => push_equal(&mut ops, old_index, new_index, len),
                op => ops.push(op),
            }
        }
        (i, j) = (ei, ej);
    }
    ops
}

/// The lines of `old` and `new` (each with its line ending) and the operations turning one
/// into the other, in order: the diff [`unified_diff`] prints, for other views of a change.
pub(crate) fn line_ops<'a>(
    old: &'a [u8],
    new: &'a [u8],
) -> (Vec<&'a [u8]>, Vec<&'a [u8]>, Vec<DiffOp>) {
    let (a, b) = (Side::new(old), Side::new(new));
    let ops = ops(&a, &b);
    (a.lines, b.lines, ops)
}

/// A unified diff of one file (empty if unchanged), as `diff -u` writes it: the lines' bytes as
/// they are in the files (a Latin-1 comment, a BOM, a UTF-8 name), so that `patch` applies it.
pub fn unified_diff(path: &Path, old: &[u8], new: &[u8]) -> Vec<u8> {
    if old == new {
        return Vec::new();
    }
    let a = Side::new(old);
    let b = Side::new(new);
    let name = path.display().to_string();
    let name = name.trim_start_matches('/');
    let mut out = Vec::new();
    for (n, group) in group_diff_ops(ops(&a, &b), CONTEXT).iter().enumerate() {
        if n == 0 {
            // A name with a blank ends with a tab, as `diff` and `git` end it, so that `patch`
            // reads it whole.
            let end = if name.contains([' ', '\t']) { "\t" } else { "" };
            let _ = writeln!(out, "--- a/{name}{end}\n+++ b/{name}{end}");
        }
        let (first, last) = (group[0], group[group.len() - 1]);
        let _ = writeln!(
            out,
            "@@ -{} +{} @@",
            Range(first.old_range().start, last.old_range().end),
            Range(first.new_range().start, last.new_range().end)
        );
        for op in group {
            let (old_lines, new_lines) = (op.old_range(), op.new_range());
            match op {
                DiffOp::Equal { .. } => line_block(&mut out, b' ', &a.lines[old_lines]),
                DiffOp::Delete { .. } => line_block(&mut out, b'-', &a.lines[old_lines]),
                DiffOp::Insert { .. } => line_block(&mut out, b'+', &b.lines[new_lines]),
                DiffOp::Replace { .. } => {
                    line_block(&mut out, b'-', &a.lines[old_lines]);
                    line_block(&mut out, b'+', &b.lines[new_lines]);
                }
            }
        }
    }
    out
}

fn line_block(out: &mut Vec<u8>, tag: u8, lines: &[&[u8]]) {
    for line in lines {
        out.push(tag);
        out.extend_from_slice(line);
        if !line.ends_with(b"\n") {
            out.extend_from_slice(b"\n\\ No newline at end of file\n");
        }
    }
}

/// A hunk's line range as unified diffs write it: `start,len` (1-based), `start` alone for
/// one line, and the line before for an empty range.
struct Range(usize, usize);

impl std::fmt::Display for Range {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let len = self.1.saturating_sub(self.0);
        match len {
            1 => write!(f, "{}", self.0 + 1),
            0 => write!(f, "{},0", self.0),
            _ => write!(f, "{},{}", self.0 + 1, len),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::latin1;
    use proptest::prelude::*;

    /// The diff as text, each byte one Latin-1 letter (as the reference reads the files).
    fn diff_text(path: &Path, old: &[u8], new: &[u8]) -> String {
        latin1(&unified_diff(path, old, new))
    }

    /// The whole-file diff of `similar`, which this one must reproduce.
    fn reference(path: &Path, old: &[u8], new: &[u8]) -> String {
        if old == new {
            return String::new();
        }
        let (old, new) = (latin1(old), latin1(new));
        let name = path.display().to_string();
        similar::TextDiff::from_lines(&old, &new)
            .unified_diff()
            .context_radius(1)
            .header(&format!("a/{name}"), &format!("b/{name}"))
            .to_string()
    }

    #[test]
    fn a_name_with_a_blank_ends_with_a_tab() {
        let d = diff_text(Path::new("b dir/m.mod"), b"a\n", b"b\n");
        assert!(
            d.starts_with("--- a/b dir/m.mod\t\n+++ b/b dir/m.mod\t\n"),
            "{d}"
        );
        let d = diff_text(Path::new("m.mod"), b"a\n", b"b\n");
        assert!(d.starts_with("--- a/m.mod\n+++ b/m.mod\n"), "{d}");
    }

    #[test]
    fn shows_only_changed_lines() {
        let d = diff_text(Path::new("m.mod"), b"a\nb\nc\nd\n", b"a\nB\nc\nd\n");
        assert_eq!(
            d,
            "--- a/m.mod\n+++ b/m.mod\n@@ -1,3 +1,3 @@\n a\n-b\n+B\n c\n"
        );
    }

    #[test]
    fn marks_a_missing_final_newline_and_handles_insertions() {
        for (old, new) in [
            (&b"a\nb"[..], &b"a\nc"[..]),
            (b"a\nb\n", b"a\n! stamp\nb\n"),
            (b"x\r\ny\r\n", b"x\r\nY\r\n"),
            (b"", b"new\n"),
            (b"old\n", b""),
        ] {
            let p = Path::new("m.mod");
            assert_eq!(
                diff_text(p, old, new),
                reference(p, old, new),
                "{old:?} → {new:?}"
            );
        }
    }

    #[test]
    fn is_linear_on_a_large_file_with_spread_changes() {
        // 200,000 lines with every 50th changed: a whole-file Myers diff takes minutes.
        let old: String = (0..200_000)
            .map(|i| format!("  x{} := {i};\n", i % 7))
            .collect();
        let new: String = (0..200_000)
            .map(|i| match i % 50 {
                0 => format!("  x{} := {}.5;\n", i % 7, i),
                _ => format!("  x{} := {i};\n", i % 7),
            })
            .collect();
        let t = std::time::Instant::now();
        let d = diff_text(Path::new("big.mod"), old.as_bytes(), new.as_bytes());
        assert!(t.elapsed().as_secs_f64() < 20.0, "{:?}", t.elapsed());
        assert_eq!(d.matches("\n@@ ").count(), 4000);
    }

    /// The new text rebuilt from the old one and the operations: any correct diff gives it.
    fn rebuilt(old: &[u8], new: &[u8]) -> Vec<u8> {
        let (a, b, ops) = line_ops(old, new);
        let mut out = Vec::new();
        for op in ops {
            match op {
                DiffOp::Equal { .. } => a[op.old_range()].iter().for_each(|l| out.extend(*l)),
                DiffOp::Delete { .. } => {}
                DiffOp::Insert { .. } | DiffOp::Replace { .. } => {
                    b[op.new_range()].iter().for_each(|l| out.extend(*l))
                }
            }
        }
        out
    }

    #[test]
    fn a_large_block_rewritten_in_place_is_paired_line_by_line() {
        // 30,000 declarations all rewritten, a stamp line added above them and one line
        // dropped in the middle: far beyond what Myers' algorithm is run on.
        let old: String = std::iter::once("MODULE m\n".to_owned())
            .chain((0..30_000).map(|i| format!("  CONST robtarget p{i}:=[[{i},0,0]];\n")))
            .chain(["ENDMODULE\n".to_owned()])
            .collect();
        let new: String = ["MODULE m\n".to_owned(), "! stamp\n".to_owned()]
            .into_iter()
            .chain(
                (0..30_000)
                    .filter(|&i| i != 15_000)
                    .map(|i| format!("  CONST robtarget p{i}:=[[{i}.5,0,0]];\n")),
            )
            .chain(["ENDMODULE\n".to_owned()])
            .collect();
        assert_eq!(rebuilt(old.as_bytes(), new.as_bytes()), new.as_bytes());
        let d = diff_text(Path::new("m.mod"), old.as_bytes(), new.as_bytes());
        assert_eq!(
            d.lines()
                .filter(|l| l.starts_with('-') && !l.starts_with("---"))
                .count(),
            30_000
        );
        assert_eq!(
            d.lines()
                .filter(|l| l.starts_with('+') && !l.starts_with("+++"))
                .count(),
            30_000
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Sparse edits of a text whose lines are mostly distinct, with repeated ones (like
        /// ENDPROC) among them: the same diff as `similar`'s whole-file one.
        #[test]
        fn equals_the_whole_file_diff(
            repeated in proptest::collection::vec(any::<bool>(), 0..60),
            edits in proptest::collection::vec((0usize..60, 0u8..4), 0..6),
            final_newline in any::<bool>(),
        ) {
            let old: Vec<String> = repeated
                .iter()
                .enumerate()
                .map(|(i, &r)| if r && i % 3 == 0 { "ENDPROC".to_owned() } else { format!("line {i}") })
                .collect();
            let mut new = old.clone();
            for (n, (at, kind)) in edits.into_iter().enumerate() {
                let at = at.min(new.len());
                match kind {
                    0 if at < new.len() => new[at] = format!("changed {n}"),
                    1 => new.insert(at, format!("inserted {n}")),
                    2 if at < new.len() => { new.remove(at); }
                    _ => {}
                }
            }
            let join = |v: &[String]| {
                let mut s = v.join("\n");
                if final_newline && !s.is_empty() { s.push('\n'); }
                s
            };
            let (old, new) = (join(&old), join(&new));
            let p = Path::new("m.mod");
            prop_assert_eq!(diff_text(p, old.as_bytes(), new.as_bytes()), reference(p, old.as_bytes(), new.as_bytes()));
        }
    }
}
