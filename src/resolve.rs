//! The part of usage resolution that both languages share, over language-neutral facts that
//! each language's extractor reports: how deep calls are followed, and which targets and frames
//! the program computes when it runs (and so no offline transform can correct).
//!
//! A language finds its facts in its own syntax (RAPID `p10 := CRobT()`, KRL `XP1 = $POS_ACT`);
//! this pass looks them up among the program's declarations (array elements under the array's
//! name, a file's own declarations before the other files') and marks the targets' [`Usage`].
//!
//! [`Usage`]: crate::position::Usage

use crate::names::{NameIndex, fold};
use crate::position::{FrameDecl, Position, RunTimeValue};

/// How many calls deep a routine's effects on its callers are followed (a target passed on
/// through RAPID routine parameters, a KRL subroutine that sets the base): deeper chains and
/// cycles stop here.
pub(crate) const CALL_DEPTH: usize = 16;

/// The uses reached from routine parameter `from`: its own uses, then those of every parameter
/// it is passed on to (`edges`: an argument of a call in the routine that names the parameter),
/// followed [`CALL_DEPTH`] calls deep, each parameter once (a recursion stops).
pub(crate) fn uses_through_parameters<'u, P, U>(
    from: P,
    uses: &'u std::collections::HashMap<P, Vec<U>>,
    edges: &std::collections::HashMap<P, Vec<P>>,
) -> Vec<&'u U>
where
    P: Copy + Eq + std::hash::Hash,
{
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![(from, 0usize)];
    let mut found = Vec::new();
    while let Some((at, depth)) = stack.pop() {
        if depth >= CALL_DEPTH || !seen.insert(at) {
            continue;
        }
        found.extend(uses.get(&at).into_iter().flatten());
        stack.extend(
            edges
                .get(&at)
                .into_iter()
                .flatten()
                .map(|&next| (next, depth + 1)),
        );
    }
    found
}

/// A value the program computes at run time and gives a declared name: a language-neutral
/// fact. Literal values (`rdkWObj := [FALSE,TRUE,"",[[2100,…]]…]`) are not reported: they are
/// known offline.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Assignment {
    /// The name assigned to, as written, without a component: `pArr{i}`, `P[I]`, `wobj1`.
    pub(crate) name: String,
    /// 1-based line of the assignment.
    pub(crate) line: usize,
}

/// One file of a program as this pass sees it: its targets (marked here), its frame
/// declarations and its run-time assignments.
pub(crate) struct FileFacts<'a> {
    pub(crate) positions: &'a mut [Position],
    pub(crate) frames: &'a [FrameDecl],
    pub(crate) assignments: &'a [Assignment],
}

/// Where a folded reference points among `index`'s names: the declaration itself, else (an
/// element chosen at run time `pArr{i}`, or the whole array `pArr`) every element of the
/// array; the file's own declarations hide the other files'.
fn lookup(index: &NameIndex<(usize, usize)>, file: usize, key: &str) -> Vec<(usize, usize)> {
    let hits = match index.exact(key) {
        [] => index.elements(index.array_of(key).unwrap_or(key)),
        hits => hits,
    };
    let own = hits.iter().any(|h| h.0 == file);
    hits.iter()
        .copied()
        .filter(|h| !own || h.0 == file)
        .collect()
}

/// Marks [`Usage::run_time`](crate::position::Usage) of every target of the program (its
/// files in `files`) whose pose is only known at run time: a target the program assigns a
/// computed value, then a target a motion uses with a work object or base the program
/// assigns one. `open` is the bracket of an array index (`{` RAPID, `[` KRL).
pub(crate) fn mark_run_time(files: &mut [FileFacts<'_>], open: char) {
    if files.iter().all(|f| f.assignments.is_empty()) {
        return;
    }
    let mut targets: NameIndex<(usize, usize)> = NameIndex::new(open, 0);
    let mut frames: NameIndex<(usize, usize)> = NameIndex::new(open, 0);
    for (fi, f) in files.iter().enumerate() {
        for (i, p) in f.positions.iter().enumerate() {
            if let Some(n) = &p.name {
                targets.insert(n, (fi, i));
            }
        }
        for (i, d) in f.frames.iter().enumerate() {
            frames.insert(&d.name, (fi, i));
        }
    }
    let mut assigned_targets = Vec::new();
    // Folded frame name → (name as declared, line of the first assignment).
    let mut assigned_frames: crate::names::NameMap<String, (String, usize)> = Default::default();
    for (fi, f) in files.iter().enumerate() {
        for a in f.assignments {
            let key = fold(&a.name);
            for (tf, ti) in lookup(&targets, fi, &key) {
                assigned_targets.push((tf, ti, a.line));
            }
            for (df, di) in lookup(&frames, fi, &key) {
                if let Some(d) = files.get(df).and_then(|f| f.frames.get(di)) {
                    assigned_frames
                        .entry(fold(&d.name))
                        .or_insert_with(|| (d.name.clone(), a.line));
                }
            }
        }
    }
    for (tf, ti, line) in assigned_targets {
        if let Some(p) = files.get_mut(tf).and_then(|f| f.positions.get_mut(ti)) {
            p.usage.set_run_time(RunTimeValue::Target { line });
        }
    }
    if assigned_frames.is_empty() {
        return;
    }
    for f in files.iter_mut() {
        for p in f.positions.iter_mut() {
            let frame = p
                .usage
                .wobj
                .iter()
                .chain(&p.usage.other_wobjs)
                .find_map(|w| assigned_frames.get(&fold(w)));
            if let Some((name, line)) = frame {
                let why = RunTimeValue::Frame {
                    name: Some(name.clone()),
                    line: *line,
                };
                p.usage.set_run_time(why);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn parameters_are_followed_transitively_once_each_and_only_so_deep() {
        // 0 → 1 → 2 → 0 (a cycle), 1 has a use, 2 has one; a chain 10 → 11 → … beyond the depth.
        let uses: HashMap<u32, Vec<&str>> = [
            (1, vec!["a"]),
            (2, vec!["b"]),
            (10 + CALL_DEPTH as u32, vec!["deep"]),
        ]
        .into();
        let mut edges: HashMap<u32, Vec<u32>> = [(0, vec![1]), (1, vec![2]), (2, vec![0])].into();
        for k in 10..10 + CALL_DEPTH as u32 {
            edges.insert(k, vec![k + 1]);
        }
        let mut found = uses_through_parameters(0, &uses, &edges);
        found.sort();
        assert_eq!(found, [&"a", &"b"]);
        assert!(uses_through_parameters(10, &uses, &edges).is_empty());
        assert_eq!(uses_through_parameters(11, &uses, &edges), [&"deep"]);
    }
}
