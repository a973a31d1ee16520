//! What may hold where a statement runs, asked of the modules' routines with their calls
//! followed: whether a frame (a work object or a tool) the program gives one other value than
//! its declaration may still hold its declared value where a motion uses it (docs/design.md,
//! "Frames the program assigns"), and whether a program displacement or an external axes
//! offset may be active there ("Program displacement and axes offset").
//!
//! Asked only of such a program (most give no frame a value and displace nothing), over the
//! modules' skeleton trees: their branches and statements' leaves ([`walked`]), which the parse
//! that reads the targets keeps for a module that gives a frame a value (any other module is
//! parsed again for it).
//!
//! One question: the condition holds from a statement that sets it (`PDispSet`, `PDispOn`) to
//! one that clears it (`PDispOff`; for a frame, the assignment of its value given: nothing gives
//! the declared value back, a program that does being refused before this is asked), and at the
//! start of a routine the program may start or enter from outside when the question says so
//! (a frame holds its declared value there; no displacement is active when the program starts).
//! Over every path that may reach a statement, it may hold there when it holds on one of them: a
//! may-analysis, the meet of two paths being the lesser [`Holds`], which also names one
//! instruction whose setting may reach the statement.
//!
//! What may reach a point: program order in the routine, with its `IF`, `TEST`, loops (which
//! may run no pass or come round again), `GOTO` and its labels, `RETURN`, `EXIT` and `RAISE`;
//! the `ERROR` handler, entered from any statement of the body that may raise an error, with
//! what held there (a call included, with whatever held anywhere in the routine called: an
//! error of a routine without a handler of its own goes to its caller's), and left by `RETRY`
//! (back to that statement, with what the handler leaves) or `TRYNEXT` (to the one after it,
//! likewise); a call, after which holds what the routine called leaves entered with what held
//! before; a call of a routine no module given defines (an instruction of the controller, or a
//! routine of a module not given), which changes nothing (a displacement active before it stays
//! active; docs/design.md says why none is taken to start there); a call that names its routine
//! only at run time (`%name%`, `CallByVar`), which may run the `PROC` its name written whole
//! names (`%"Seam_2"%`), one whose name starts with the literal that begins it
//! (`%"Seam_"+ValToStr(n)%`; `CallByVar "Seam_",n` if digits follow it) or, its name not
//! written so, any `PROC` of the task, and (but for a whole name given) one no module given
//! defines, so it leaves the meet of what each leaves; and `ExitCycle`, which starts `main`
//! again with what holds there. A routine starts with the meet of its calls' states; `main`
//! also with what holds at its end (the controller runs it again and again). One the program
//! may start or enter from outside: `main`, a routine no statement calls (or only routines that
//! no such one reaches), a `PROC` a call naming its routine at run time may run, a `TRAP` (an
//! interrupt runs it between any two statements) or a `FUNC` (called from expressions, which
//! are not followed): the last two start with the condition possible.

use crate::names::{NameKey, NameMap};
use crate::rapid::tree::NodeKind;

type Node = crate::rapid::Node;

/// What may hold at a point, ordered for the meet of two paths (the lesser).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
enum Holds {
    /// On some path the condition holds: the frame may hold its declared value; the
    /// displacement set by the question's set `k` (an index, [`ENTRY`] while a routine is
    /// walked for what it leaves: whatever set its caller's) may be active.
    Maybe(u32),
    /// On every path reaching the point, it does not hold.
    No,
    /// No path reaches the point.
    #[default]
    Unreached,
}

/// In `Holds::Maybe(ENTRY)`: the set that held where the routine walked was entered.
const ENTRY: u32 = u32::MAX;

/// In [`Points::changes`], a statement that clears the condition (another is a set: its index).
const CLEARS: u32 = u32::MAX;

impl Holds {
    fn meet(self, other: Holds) -> Holds {
        self.min(other)
    }
}

/// What a routine (or its error handler) leaves as a function of what it is entered with.
/// Each statement leaves what it was entered with or a value of its own, and the meet of such
/// functions is one too, so what it leaves entered with `No` and with `Maybe(ENTRY)` gives it
/// for every entry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Effect {
    /// What it leaves entered with `Maybe(ENTRY)`.
    maybe: Holds,
    /// What it leaves entered with `No`.
    no: Holds,
}

impl Effect {
    /// What it leaves entered with `s`: with `Maybe(k)`, `Maybe(k)` where the entry's set
    /// reaches the end, else the set that does.
    fn of(self, s: Holds) -> Holds {
        match s {
            Holds::Unreached => Holds::Unreached,
            Holds::No => self.no,
            Holds::Maybe(k) => match self.maybe {
                Holds::Maybe(ENTRY) => Holds::Maybe(k),
                left => left,
            },
        }
    }

    fn meet(self, other: Effect) -> Effect {
        Effect {
            maybe: self.maybe.meet(other.maybe),
            no: self.no.meet(other.no),
        }
    }
}

/// What a routine leaves as a function of its entry: at its returns, and the meet of
/// everything that holds anywhere in it while it runs (what an error it passes on to its
/// caller is raised with).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Summary {
    exit: Effect,
    seen: Effect,
}

impl Summary {
    fn meet(self, other: Summary) -> Summary {
        Summary {
            exit: self.exit.meet(other.exit),
            seen: self.seen.meet(other.seen),
        }
    }
}

/// A routine's kind: a `FUNC` is called in expressions, a `TRAP` by an interrupt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Proc,
    Func,
    Trap,
}

/// A routine of the task.
struct Routine {
    module: usize,
    /// Its `Routine` node in the module's tree.
    node: usize,
    kind: Kind,
    /// It is `main`, which the controller starts and runs again once it ends.
    main: bool,
    /// The routine may run without a call the program makes (see the module's comment).
    from_outside: bool,
}

/// The routines of one task and how they call each other, read from the modules' trees.
pub(crate) struct Task<'s> {
    /// Per module: its source and its tree's nodes.
    modules: Vec<(&'s [u8], Vec<Node>)>,
    routines: Vec<Routine>,
    /// Routines by name: (routine, module, `LOCAL`), in module order.
    by_name: NameMap<NameKey<'s>, Vec<(usize, usize, bool)>>,
    /// Per routine, the routines that call it.
    callers: Vec<Vec<usize>>,
    /// The routines with a call that names its routine at run time and may run any `PROC`.
    late_callers: Vec<usize>,
    /// Per module, its calls that name their routine at run time (first byte, what each may
    /// run), in order.
    late_calls: Vec<Vec<(u32, LateRuns)>>,
}

/// What a call that names its routine at run time may run, read from how it writes the name.
#[derive(Clone, Debug, PartialEq, Eq)]
enum LateRuns {
    /// Any `PROC` of the task, or a routine no module given defines: the name is not read.
    Any,
    /// The routine of that name (`%"Seam_2"%`); `None`: one no module given defines.
    Named(Option<usize>),
    /// One of the `PROC`s whose names start with a literal (`%"Seam_"+ValToStr(n)%`;
    /// `CallByVar "Seam_",n`: then digits), or one no module given defines.
    Among(Vec<usize>),
}

/// How a call that names its routine at run time writes the name, where a string literal
/// begins it: the whole name, or its start.
enum Written<'s> {
    Name(&'s [u8]),
    Prefix(&'s [u8]),
    /// `CallByVar`'s: the start, then the number's digits.
    PrefixAndNumber(&'s [u8]),
}

/// The first word of `text` (letters, digits and `_`), its case as written.
fn first_word(text: &[u8]) -> &[u8] {
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    let rest = text.get(start..).unwrap_or_default();
    let end = rest
        .iter()
        .position(|b| !(b.is_ascii_alphanumeric() || *b == b'_'))
        .unwrap_or(rest.len());
    rest.get(..end).unwrap_or_default()
}

/// `text` after its first word and the blanks after it.
fn after_first_word(text: &[u8]) -> &[u8] {
    let word = first_word(text);
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    let rest = text.get(start + word.len()..).unwrap_or_default();
    let blanks = rest
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(rest.len());
    rest.get(blanks..).unwrap_or_default()
}

fn is_word(text: &[u8], word: &str) -> bool {
    first_word(text).eq_ignore_ascii_case(word.as_bytes())
}

/// A routine head's kind, name and whether it is `LOCAL`: `[LOCAL] PROC name(…)`, `[LOCAL] FUNC
/// type name(…)`, `[LOCAL] TRAP name`.
fn routine_head(head: &[u8]) -> Option<(Kind, &[u8], bool)> {
    let local = is_word(head, "LOCAL");
    let head = if local { after_first_word(head) } else { head };
    let kind = match first_word(head).to_ascii_uppercase().as_slice() {
        b"PROC" => Kind::Proc,
        b"FUNC" => Kind::Func,
        b"TRAP" => Kind::Trap,
        _ => return None,
    };
    let mut rest = after_first_word(head);
    if kind == Kind::Func {
        rest = after_first_word(rest);
    }
    let name = first_word(rest);
    (!name.is_empty()).then_some((kind, name, local))
}

/// The leaves a walk reads: statements, the heads and parts of routines and blocks. Gaps and
/// declarations, most of a module's leaves, are not kept.
pub(crate) fn walked(kind: NodeKind) -> bool {
    !matches!(
        kind,
        NodeKind::Trivia
            | NodeKind::Header
            | NodeKind::ModuleHead
            | NodeKind::ModuleEnd
            | NodeKind::DataDecl
            | NodeKind::RecordHead
            | NodeKind::RecordField
            | NodeKind::RecordEnd
            | NodeKind::RoutineEnd
    )
}

/// The children of node `at`: each one's index, stepping over their subtrees.
fn children(nodes: &[Node], at: usize) -> impl Iterator<Item = usize> + '_ {
    let end = nodes.get(at).map_or(at, |n| n.subtree_end as usize);
    let mut i = at + 1;
    std::iter::from_fn(move || {
        if i >= end {
            return None;
        }
        let here = i;
        i = nodes
            .get(i)
            .map_or(end, |n| (n.subtree_end as usize).max(i + 1));
        Some(here)
    })
}

/// Whether call statement `n`, its first word `word`, names its routine only at run time:
/// `%name%`, `CallByVar`.
fn is_late_call(n: &Node, word: &[u8]) -> bool {
    n.kind == NodeKind::LateCall
        || (n.kind == NodeKind::Call && word.eq_ignore_ascii_case(b"CallByVar"))
}

/// How late call `n` (its text `text`) writes its routine's name, where it reads: `%"name"%`;
/// `%"start" + …%`; `CallByVar "start", …` (which runs the procedure named by the string
/// followed by the number). A literal that is not a plain name (a doubled quote, an escape) is
/// not read.
fn written_name<'s>(n: &Node, text: &'s [u8]) -> Option<Written<'s>> {
    let late = n.kind == NodeKind::LateCall;
    let rest = if late {
        text.trim_ascii_start().strip_prefix(b"%")?
    } else {
        after_first_word(text)
    };
    let rest = rest.trim_ascii_start().strip_prefix(b"\"")?;
    let end = rest.iter().position(|&b| b == b'"')?;
    let literal = rest.get(..end)?;
    if !literal
        .iter()
        .all(|b| b.is_ascii_alphanumeric() || *b == b'_')
    {
        return None;
    }
    match rest.get(end + 1..)?.trim_ascii_start().first()? {
        b'+' => Some(Written::Prefix(literal)),
        b'%' if late => Some(Written::Name(literal)),
        b',' if !late => Some(Written::PrefixAndNumber(literal)),
        _ => None,
    }
}

/// One question asked of the task: where its condition starts and stops holding, where it is
/// asked, and what a `PROC` the program may start or enter from outside starts with.
struct Question<'q> {
    /// Each (module, first byte of the statement), in task order: a statement that sets it.
    sets: &'q [(usize, usize)],
    /// A statement that clears it.
    clears: &'q [(usize, usize)],
    /// A statement it is asked at.
    uses: &'q [(usize, usize)],
    outside_proc: Holds,
}

impl<'s> Task<'s> {
    /// The routines of the modules (each one's source, and its skeleton tree of [`walked`]
    /// leaves when the first parse kept it), read from their trees.
    pub(crate) fn new(sources: Vec<(&'s [u8], Option<Vec<Node>>)>) -> Task<'s> {
        let modules: Vec<(&'s [u8], Vec<Node>)> = sources
            .into_iter()
            .map(|(src, kept)| {
                let nodes = kept.unwrap_or_else(|| {
                    let mut none = crate::syntax::NoSink;
                    crate::rapid::parser::parse_streamed(src, &mut none, walked)
                        .tree
                        .nodes
                });
                (src, nodes)
            })
            .collect();
        let mut routines = Vec::new();
        let mut by_name: NameMap<NameKey<'s>, Vec<(usize, usize, bool)>> = NameMap::default();
        for (m, (src, nodes)) in modules.iter().enumerate() {
            for (i, n) in nodes.iter().enumerate() {
                if n.kind != NodeKind::Routine {
                    continue;
                }
                let head = children(nodes, i)
                    .filter_map(|c| nodes.get(c))
                    .find(|c| c.kind == NodeKind::RoutineHead);
                let Some((kind, name, local)) =
                    head.and_then(|h| routine_head(h.span().slice(src)))
                else {
                    continue;
                };
                by_name
                    .entry(NameKey(name))
                    .or_default()
                    .push((routines.len(), m, local));
                routines.push(Routine {
                    module: m,
                    node: i,
                    kind,
                    main: kind == Kind::Proc && name.eq_ignore_ascii_case(b"main"),
                    from_outside: false,
                });
            }
        }
        let mut task = Task {
            modules,
            routines,
            by_name,
            callers: Vec::new(),
            late_callers: Vec::new(),
            late_calls: Vec::new(),
        };
        // Who calls whom, as written; which routines call one named at run time, and which
        // routines such a call may run (a call that may run one of them is taken as a call of
        // each).
        let mut callers: Vec<Vec<usize>> = vec![Vec::new(); task.routines.len()];
        let mut late_callers = Vec::new();
        let mut late_calls = vec![Vec::new(); task.modules.len()];
        let mut run_late = vec![false; task.routines.len()];
        for (r, routine) in task.routines.iter().enumerate() {
            let Some((src, nodes)) = task.modules.get(routine.module) else {
                continue;
            };
            let end = nodes
                .get(routine.node)
                .map_or(routine.node, |n| n.subtree_end as usize);
            for n in nodes.get(routine.node..end).unwrap_or_default() {
                let text = n.span().slice(src);
                if is_late_call(n, first_word(text)) {
                    let runs = task.late_runs(routine.module, n, text);
                    let callees = match &runs {
                        LateRuns::Any => {
                            if late_callers.last() != Some(&r) {
                                late_callers.push(r);
                            }
                            &[][..]
                        }
                        LateRuns::Named(named) => named.as_slice(),
                        LateRuns::Among(among) => among.as_slice(),
                    };
                    for &callee in callees {
                        if let Some(seen) = run_late.get_mut(callee) {
                            *seen = true;
                        }
                        if let Some(list) = callers.get_mut(callee).filter(|l| !l.contains(&r)) {
                            list.push(r);
                        }
                    }
                    if let Some(list) = late_calls.get_mut(routine.module) {
                        list.push((n.start, runs));
                    }
                } else if n.kind == NodeKind::Call
                    && let Some(list) = task
                        .callee(routine.module, first_word(n.span().slice(src)))
                        .and_then(|callee| callers.get_mut(callee))
                    && !list.contains(&r)
                {
                    list.push(r);
                }
            }
        }
        let late_any = !late_callers.is_empty();
        for (r, routine) in task.routines.iter_mut().enumerate() {
            routine.from_outside = routine.kind != Kind::Proc
                || late_any
                || run_late.get(r).copied().unwrap_or(false)
                || routine.main
                || callers.get(r).is_none_or(|c| c.iter().all(|&c| c == r));
        }
        // Routines that call only each other, none of them reached from a routine the program
        // starts or enters from outside: whatever runs them runs them from outside too.
        let mut callees = vec![Vec::new(); callers.len()];
        for (callee, from) in callers.iter().enumerate() {
            for &c in from {
                if let Some(list) = callees.get_mut(c) {
                    list.push(callee);
                }
            }
        }
        let mut reached: Vec<bool> = task.routines.iter().map(|r| r.from_outside).collect();
        let mut work: Vec<usize> = (0..reached.len()).filter(|&r| reached[r]).collect();
        while let Some(r) = work.pop() {
            for &callee in callees.get(r).into_iter().flatten() {
                if let Some(seen) = reached.get_mut(callee).filter(|seen| !**seen) {
                    *seen = true;
                    work.push(callee);
                }
            }
        }
        for (routine, reached) in task.routines.iter_mut().zip(reached) {
            routine.from_outside |= !reached;
        }
        task.callers = callers;
        task.late_callers = late_callers;
        task.late_calls = late_calls;
        task
    }

    /// What late call `n` (its text `text`) in module `m` may run: by a name written whole, the
    /// routine a call of it runs, if a `PROC`; by the start of one, the `PROC`s it sees (its
    /// module's, the others' not `LOCAL`) whose names start so, ignoring case as names do.
    fn late_runs(&self, m: usize, n: &Node, text: &[u8]) -> LateRuns {
        let is_proc = |r: &usize| self.routines.get(*r).is_some_and(|x| x.kind == Kind::Proc);
        match written_name(n, text) {
            None => LateRuns::Any,
            Some(Written::Name(name)) => LateRuns::Named(self.callee(m, name).filter(is_proc)),
            Some(written @ (Written::Prefix(prefix) | Written::PrefixAndNumber(prefix))) => {
                // A procedure's name has no sign or point: `CallByVar`'s number adds digits.
                let number = matches!(written, Written::PrefixAndNumber(_));
                let rest_fits = |name: &NameKey| {
                    !number
                        || name
                            .0
                            .get(prefix.len()..)
                            .is_some_and(|d| !d.is_empty() && d.iter().all(u8::is_ascii_digit))
                };
                let mut among: Vec<usize> = self
                    .by_name
                    .iter()
                    .filter(|(name, _)| name.starts_with(prefix) && rest_fits(name))
                    .flat_map(|(_, all)| all)
                    .filter(|&&(_, rm, local)| rm == m || !local)
                    .map(|&(r, ..)| r)
                    .filter(is_proc)
                    .collect();
                among.sort_unstable();
                LateRuns::Among(among)
            }
        }
    }

    /// What the late call at first byte `at` of module `m` may run.
    fn late_runs_at(&self, m: usize, at: u32) -> Option<&LateRuns> {
        let calls = self.late_calls.get(m)?;
        let k = calls.binary_search_by_key(&at, |&(start, _)| start).ok()?;
        calls.get(k).map(|(_, runs)| runs)
    }

    /// The routine a call named `name` in module `m` runs: the module's own, else one of
    /// another module that is not `LOCAL` (the first), as the binder finds a callee.
    fn callee(&self, m: usize, name: &[u8]) -> Option<usize> {
        let all = self.by_name.get(&NameKey(name))?;
        all.iter()
            .find(|&&(_, rm, _)| rm == m)
            .or_else(|| all.iter().find(|&&(_, rm, local)| rm != m && !local))
            .map(|&(r, ..)| r)
    }

    /// For each of `uses` (module, first byte of the instruction), whether it may run while the
    /// frame holds its declared value, the program giving it the other value at `given`
    /// (module, first byte of the name assigned). A use in no routine may; one no path
    /// reaches runs with neither.
    pub(crate) fn declared_may_reach(
        &self,
        given: &[(usize, usize)],
        uses: &[(usize, usize)],
    ) -> Vec<bool> {
        let question = Question {
            sets: &[],
            clears: given,
            uses,
            outside_proc: Holds::Maybe(0),
        };
        self.ask(&question)
            .0
            .into_iter()
            .map(|h| matches!(h, Holds::Maybe(_)))
            .collect()
    }

    /// For each of `uses` (module, first byte of the instruction), the displacement that may
    /// be active where it runs: the index among `sets` (module, first byte of each instruction
    /// that activates it, in task order) of one whose displacement may reach it, the program
    /// deactivating it at `clears`; `None` where no path reaches it with one active. A use in
    /// no routine may run with the first; every use does when a `TRAP` or a `FUNC` may leave
    /// one active (neither's callers are followed).
    pub(crate) fn active_at(
        &self,
        sets: &[(usize, usize)],
        clears: &[(usize, usize)],
        uses: &[(usize, usize)],
    ) -> Vec<Option<usize>> {
        let question = Question {
            sets,
            clears,
            uses,
            outside_proc: Holds::No,
        };
        let (at_uses, summaries) = self.ask(&question);
        let anywhere = self
            .routines
            .iter()
            .zip(&summaries)
            .filter(|(r, _)| r.kind != Kind::Proc)
            .map(|(_, s)| s.exit.no)
            .min()
            .filter(|h| matches!(h, Holds::Maybe(_)));
        at_uses
            .into_iter()
            .map(|h| match h.meet(anywhere.unwrap_or(Holds::Unreached)) {
                Holds::Maybe(k) => Some(if k == ENTRY { 0 } else { k as usize }),
                _ => None,
            })
            .collect()
    }

    /// What holds at each of the question's uses, and what each routine leaves.
    fn ask(&self, q: &Question<'_>) -> (Vec<Holds>, Vec<Summary>) {
        // (A source is below 4 GiB, and so is the count of its statements.)
        let per_module = |list: &[(usize, usize)]| {
            let mut out: Vec<Vec<(u32, u32)>> = vec![Vec::new(); self.modules.len()];
            for (k, &(m, at)) in list.iter().enumerate() {
                if let Some(v) = out.get_mut(m) {
                    v.push((at as u32, k as u32));
                }
            }
            for v in &mut out {
                v.sort_unstable();
            }
            out
        };
        // What each statement that sets or clears it gives, in one list (a set its index).
        let mut changes = per_module(q.sets);
        for (v, clears) in changes.iter_mut().zip(per_module(q.clears)) {
            v.extend(clears.into_iter().map(|(at, _)| (at, CLEARS)));
            v.sort_unstable();
        }
        let use_at = per_module(q.uses);
        let points = Points {
            changes: &changes,
            uses: &use_at,
        };
        let n = self.routines.len();
        let is_proc = |r: usize| self.routines.get(r).is_some_and(|x| x.kind == Kind::Proc);
        // What each routine leaves: a greatest fixpoint, every routine first taken to return
        // with nothing, one walked again when a routine it calls turns out to leave less.
        let mut summaries = vec![Summary::default(); n];
        // What a call named at run time, its name not read, leaves: the meet of every `PROC`'s,
        // and of nothing changed (a routine no module given defines).
        let identity = Effect {
            maybe: Holds::Maybe(ENTRY),
            no: Holds::No,
        };
        let mut late = Summary {
            exit: identity,
            seen: identity,
        };
        // Only what a call leaves is asked for: of a routine some statement calls (a call
        // named at run time, of each it may run), of every `PROC` when such a call's name is
        // not read, of a `TRAP` or `FUNC` (whether it leaves the condition holding wherever it
        // runs): a large `main`, which nothing calls, is walked for what holds in it only.
        let late_calls = !self.late_callers.is_empty();
        let needed: Vec<bool> = (0..n)
            .map(|r| {
                self.callers.get(r).is_some_and(|c| !c.is_empty()) || late_calls || !is_proc(r)
            })
            .collect();
        let mut queued = needed.clone();
        let mut work: Vec<usize> = (0..n).filter(|&r| needed[r]).rev().collect();
        // (Its uses are not asked for here: a summary only.)
        let summary_points = Points {
            uses: &[],
            ..points
        };
        while let Some(r) = work.pop() {
            if let Some(q) = queued.get_mut(r) {
                *q = false;
            }
            let walks = [Holds::Maybe(ENTRY), Holds::No]
                .map(|entry| self.walk(r, entry, &summary_points, &summaries, late));
            let [maybe, no] = walks;
            let summary = Summary {
                exit: Effect {
                    maybe: maybe.exit,
                    no: no.exit,
                },
                seen: Effect {
                    maybe: maybe.seen,
                    no: no.seen,
                },
            };
            if summaries.get(r).is_some_and(|&x| x != summary) {
                if let Some(x) = summaries.get_mut(r) {
                    *x = summary;
                }
                let late_callers = if is_proc(r) {
                    late = late.meet(summary);
                    self.late_callers.as_slice()
                } else {
                    &[]
                };
                let callers = self.callers.get(r).map_or(&[][..], Vec::as_slice);
                for &c in callers.iter().chain(late_callers) {
                    if !needed.get(c).copied().unwrap_or(false) {
                        continue;
                    }
                    if let Some(q) = queued.get_mut(c).filter(|q| !**q) {
                        *q = true;
                        work.push(c);
                    }
                }
            }
        }
        // What each routine starts with: the meet of the states its calls are made in, and
        // what the question says for one the program may start or enter from outside.
        let outside = |r: usize| match self.routines.get(r) {
            Some(x) if !x.from_outside => Holds::Unreached,
            Some(x) if x.kind == Kind::Proc => q.outside_proc,
            _ => Holds::Maybe(0),
        };
        let mut entry: Vec<Holds> = (0..n).map(outside).collect();
        let mut queued: Vec<bool> = entry.iter().map(|&e| e != Holds::Unreached).collect();
        let mut work: Vec<usize> = (0..n).filter(|&r| queued[r]).rev().collect();
        let mains: Vec<usize> = (0..n)
            .filter(|&r| self.routines.get(r).is_some_and(|x| x.main))
            .collect();
        let procs: Vec<usize> = (0..n).filter(|&r| is_proc(r)).collect();
        // Per routine, its uses as its last walk found them: with the entry it keeps, since a
        // routine is walked again whenever its entry is lowered.
        let mut last_uses: Vec<Option<Vec<(u32, Holds)>>> = vec![None; n];
        while let Some(r) = work.pop() {
            if let Some(q) = queued.get_mut(r) {
                *q = false;
            }
            let e = entry.get(r).copied().unwrap_or(Holds::Maybe(0));
            let walked = self.walk(r, e, &points, &summaries, late);
            // The states only ever get lower: a callee's entry is lowered by each call; every
            // `PROC`'s by a call named at run time; `main`'s by its own end and `ExitCycle`.
            let main_again = if self.routines.get(r).is_some_and(|x| x.main) {
                walked.exit.meet(walked.restart)
            } else {
                walked.restart
            };
            let late_calls = walked.late;
            let lowered = walked
                .calls
                .iter()
                .copied()
                .chain(
                    procs
                        .iter()
                        .filter(|_| late_calls != Holds::Unreached)
                        .map(|&p| (p, late_calls)),
                )
                .chain(
                    mains
                        .iter()
                        .filter(|_| main_again != Holds::Unreached)
                        .map(|&m| (m, main_again)),
                );
            for (callee, h) in lowered {
                let Some(x) = entry.get_mut(callee) else {
                    continue;
                };
                if h < *x {
                    *x = h;
                    if let Some(q) = queued.get_mut(callee).filter(|q| !**q) {
                        *q = true;
                        work.push(callee);
                    }
                }
            }
            if let Some(slot) = last_uses.get_mut(r) {
                *slot = Some(walked.uses);
            }
        }
        // Each use as every path reaches it (a routine never walked above is reached by none);
        // a use in no routine, as the condition possible.
        let mut at_use: Vec<Option<Holds>> = vec![None; q.uses.len()];
        for (r, walked) in last_uses.into_iter().enumerate() {
            let walked = walked.unwrap_or_else(|| {
                self.walk(r, Holds::Unreached, &points, &summaries, late)
                    .uses
            });
            for (k, h) in walked {
                if let Some(slot) = at_use.get_mut(k as usize) {
                    *slot = Some(slot.map_or(h, |x| x.meet(h)));
                }
            }
        }
        let at_use = at_use
            .into_iter()
            .map(|h| h.unwrap_or(Holds::Maybe(0)))
            .collect();
        (at_use, summaries)
    }

    /// Walks routine `r` entered with `entry`, to a fixpoint of its labels and its error
    /// handler's ways back into the body.
    fn walk(
        &self,
        r: usize,
        entry: Holds,
        points: &Points<'_>,
        summaries: &[Summary],
        late: Summary,
    ) -> Walked<'s> {
        let Some(routine) = self.routines.get(r) else {
            return Walked::default();
        };
        let Some((src, nodes)) = self.modules.get(routine.module) else {
            return Walked::default();
        };
        let mut w = Walker {
            task: self,
            module: routine.module,
            src,
            nodes,
            changes: in_module(points.changes, routine.module),
            uses: in_module(points.uses, routine.module),
            summaries,
            late,
            labels: Vec::new(),
            trynext: Effect::default(),
            retry: Effect::default(),
            handled: false,
            in_handler: false,
            out: Walked::default(),
            last_callee: None,
        };
        if let Some((trynext, retry)) = w.handler_effects(routine.node) {
            (w.trynext, w.retry, w.handled) = (trynext, retry, true);
        }
        // Each pass but the last lowers the state at a label, so the passes are bounded; the
        // bound is only a guard.
        for _ in 0..PASSES {
            w.out = Walked::default();
            w.routine(routine.node, entry);
            let settled = w.out.gotos.len() == w.labels.len()
                && w.out.gotos.iter().all(|&(l, h)| w.label(l) == h);
            if settled {
                return w.out;
            }
            w.labels = w.out.gotos.clone();
        }
        // Not settled: the condition taken to hold at every use and call of the routine, and
        // wherever it leaves.
        let mut out = std::mem::take(&mut w.out);
        let possible = Holds::Maybe(0);
        (out.exit, out.seen, out.late, out.restart) = (possible, possible, possible, possible);
        let uses = out.uses.iter_mut().map(|(_, h)| h);
        for h in uses.chain(out.calls.iter_mut().map(|(_, h)| h)) {
            *h = possible;
        }
        out
    }
}

/// Passes over one routine before its labels are taken as not settling.
const PASSES: usize = 1000;

/// The question's statements in each module: (first byte, index among all), sorted.
#[derive(Clone, Copy)]
struct Points<'f> {
    /// The statements that set it ([`CLEARS`]: that clear it).
    changes: &'f [Vec<(u32, u32)>],
    uses: &'f [Vec<(u32, u32)>],
}

/// Module `m`'s part of one of [`Points`]' lists.
fn in_module(list: &[Vec<(u32, u32)>], m: usize) -> &[(u32, u32)] {
    list.get(m).map_or(&[], Vec::as_slice)
}

/// What a walk of a routine finds.
#[derive(Default)]
struct Walked<'s> {
    /// What holds as the routine returns (at `ENDPROC`, a `RETURN`, or the end of its `ERROR`
    /// handler).
    exit: Holds,
    /// The meet of what holds anywhere in it.
    seen: Holds,
    /// Its calls of routines of the task, with the state before each.
    calls: Vec<(usize, Holds)>,
    /// The meet of the states before its calls named at run time.
    late: Holds,
    /// The meet of the states at its `ExitCycle`s.
    restart: Holds,
    /// Its uses (index among all), with the state before each.
    uses: Vec<(u32, Holds)>,
    /// The meet of the states at the `GOTO`s of each label.
    gotos: Vec<(NameKey<'s>, Holds)>,
    /// The meet of the states at the statements of the body that may raise an error.
    raised: Holds,
    /// The meet of the states at the error handler's `TRYNEXT`s.
    trynext: Holds,
    /// The meet of the states at the error handler's `RETRY`s.
    retry: Holds,
}

/// What a call statement runs.
#[derive(Clone, Copy)]
enum Runs<'w> {
    /// A routine of the task.
    Routine(usize),
    /// One of these routines of the task, or one no module given defines: named at run time,
    /// by a name that starts with a literal.
    Among(&'w [usize]),
    /// A routine named at run time: any `PROC`, or one no module given defines.
    Late,
    /// `ExitCycle`: `main` again, from its start.
    Restart,
    /// An instruction (or a routine no module given defines).
    Other,
}

struct Walker<'w, 's> {
    task: &'w Task<'s>,
    module: usize,
    src: &'s [u8],
    nodes: &'w [Node],
    changes: &'w [(u32, u32)],
    uses: &'w [(u32, u32)],
    summaries: &'w [Summary],
    late: Summary,
    /// The state at each label's `GOTO`s, as the last pass found it.
    labels: Vec<(NameKey<'s>, Holds)>,
    /// What the error handler leaves at its `TRYNEXT`s, and at its `RETRY`s (`Unreached`: it
    /// has none).
    trynext: Effect,
    retry: Effect,
    /// The routine has an `ERROR` handler: what its statements raise with matters.
    handled: bool,
    in_handler: bool,
    out: Walked<'s>,
    /// The last callee looked up, as written, and the routine it names.
    last_callee: Option<(&'s [u8], Option<usize>)>,
}

impl<'w, 's> Walker<'w, 's> {
    fn text(&self, n: &Node) -> &'s [u8] {
        n.span().slice(self.src)
    }

    fn label(&self, name: NameKey<'_>) -> Holds {
        self.labels
            .iter()
            .find(|(l, _)| *l == name)
            .map_or(Holds::Unreached, |&(_, h)| h)
    }

    /// The indices of the entries of `list` whose first byte lies in leaf `n`.
    fn within<'a>(n: &Node, list: &'a [(u32, u32)]) -> impl Iterator<Item = u32> + 'a {
        let (start, end) = (n.start, n.end);
        let from = list.partition_point(|&(at, _)| at < start);
        list.get(from..)
            .unwrap_or_default()
            .iter()
            .take_while(move |&&(at, _)| at < end)
            .map(|&(_, k)| k)
    }

    /// Records the uses written in leaf `n`, run with `s`.
    fn record_uses(&mut self, n: &Node, s: Holds) {
        for k in Self::within(n, self.uses) {
            self.out.uses.push((k, s));
        }
    }

    fn saw(&mut self, h: Holds) {
        self.out.seen = self.out.seen.meet(h);
    }

    fn routine(&mut self, node: usize, entry: Holds) {
        let nodes = self.nodes;
        let mut s = entry;
        let mut body_out = None;
        let mut handlers = Vec::new();
        for c in children(nodes, node) {
            let Some(n) = nodes.get(c) else { continue };
            match n.kind {
                NodeKind::Handler => {
                    body_out.get_or_insert(s);
                    handlers.push(c);
                }
                NodeKind::RoutineEnd => {
                    body_out.get_or_insert(s);
                }
                _ => s = self.statement(c, s),
            }
        }
        self.out.exit = self.out.exit.meet(body_out.unwrap_or(s));
        let raised = self.out.raised;
        for h in handlers {
            let error = self.is_error_handler(h);
            // An error handler starts with the state of whatever raised the error; `UNDO` and
            // `BACKWARD` run with whatever the routine held.
            let mut s = if error {
                raised
            } else {
                entry.meet(self.out.seen)
            };
            self.in_handler = true;
            for c in children(nodes, h) {
                s = self.statement(c, s);
            }
            self.in_handler = false;
            if error {
                // Its end taken as a return, as a `RETURN` in it is.
                self.out.exit = self.out.exit.meet(s);
            }
        }
    }

    fn statement(&mut self, at: usize, s: Holds) -> Holds {
        let Some(n) = self.nodes.get(at).copied() else {
            return s;
        };
        match n.kind {
            NodeKind::Call
            | NodeKind::LateCall
            | NodeKind::Assign
            | NodeKind::Jump
            | NodeKind::Placeholder
            | NodeKind::Opaque => self.leaf(&n, s),
            NodeKind::Label => {
                let text = self.text(&n);
                let name = text.split(|&b| b == b':').next().unwrap_or(text);
                s.meet(self.label(NameKey(name.trim_ascii())))
            }
            NodeKind::If => self.branches(at, s, NodeKind::IfPart),
            NodeKind::Test => self.branches(at, s, NodeKind::TestPart),
            NodeKind::CompactIf => {
                let mut then = s;
                for c in children(self.nodes, at) {
                    match self.nodes.get(c).copied() {
                        Some(head) if head.kind == NodeKind::CompactIfHead => {
                            self.record_uses(&head, s);
                        }
                        _ => then = self.statement(c, then),
                    }
                }
                s.meet(then)
            }
            NodeKind::While | NodeKind::For => self.looped(at, s),
            _ => s,
        }
    }

    /// What call statement `n` (its first word `word`) runs.
    fn runs(&mut self, n: &Node, word: &'s [u8]) -> Runs<'w> {
        if is_late_call(n, word) {
            let task = self.task;
            return match task.late_runs_at(self.module, n.start) {
                Some(LateRuns::Named(Some(r))) => Runs::Routine(*r),
                Some(LateRuns::Named(None)) => Runs::Other,
                Some(LateRuns::Among(among)) => Runs::Among(among),
                Some(LateRuns::Any) | None => Runs::Late,
            };
        }
        if n.kind != NodeKind::Call {
            return Runs::Other;
        }
        // Call after call names one instruction (`MoveL`): its lookup is kept.
        let callee = match self.last_callee {
            Some((name, found)) if name == word => found,
            _ => {
                let found = self.task.callee(self.module, word);
                self.last_callee = Some((word, found));
                found
            }
        };
        match callee {
            Some(r) => Runs::Routine(r),
            None if word.eq_ignore_ascii_case(b"ExitCycle") => Runs::Restart,
            None => Runs::Other,
        }
    }

    /// What statement `runs` raises an error with, run with `s`: a routine's error is raised
    /// wherever it runs.
    fn raised_by(&self, runs: Runs<'_>, s: Holds) -> Holds {
        let seen_in = |r: usize| {
            self.summaries
                .get(r)
                .map_or(Holds::Maybe(0), |x| x.seen.of(s))
        };
        let seen = match runs {
            Runs::Routine(r) => seen_in(r),
            Runs::Among(among) => among.iter().fold(s, |h, &r| h.meet(seen_in(r))),
            Runs::Late => self.late.seen.of(s),
            Runs::Restart | Runs::Other => s,
        };
        s.meet(seen)
    }

    /// A statement that is one leaf.
    fn leaf(&mut self, n: &Node, s: Holds) -> Holds {
        if s == Holds::Unreached {
            self.record_uses(n, s);
            return s;
        }
        // What the statement gives the condition, if anything.
        let given = Self::within(n, self.changes).next().map(|k| match k {
            CLEARS => Holds::No,
            k => Holds::Maybe(k),
        });
        // The assignment of a frame's value given raises no error.
        if n.kind == NodeKind::Assign
            && let Some(to) = given
        {
            self.saw(s);
            self.saw(to);
            return to;
        }
        let text = self.text(n);
        let word = first_word(text);
        let runs = match n.kind {
            NodeKind::Call | NodeKind::LateCall => self.runs(n, word),
            _ => Runs::Other,
        };
        let mut s = s;
        if self.handled && !self.in_handler {
            // `RETRY` runs the statement that raised again, with what the handler leaves.
            loop {
                let again = s.meet(self.retry.of(self.raised_by(runs, s)));
                if again == s {
                    break;
                }
                s = again;
            }
            self.out.raised = self.out.raised.meet(self.raised_by(runs, s));
        }
        self.record_uses(n, s);
        self.saw(s);
        let mut after = match (given, runs) {
            (Some(to), _) => to,
            (None, Runs::Routine(callee)) => {
                self.out.calls.push((callee, s));
                let summary = self.summaries.get(callee).copied().unwrap_or_default();
                self.saw(summary.seen.of(s));
                summary.exit.of(s)
            }
            (None, Runs::Among(among)) => {
                // Each entered with what holds here, and nothing changed where it runs a
                // routine no module given defines.
                let mut left = s;
                for &callee in among {
                    self.out.calls.push((callee, s));
                    let summary = self.summaries.get(callee).copied().unwrap_or_default();
                    self.saw(summary.seen.of(s));
                    left = left.meet(summary.exit.of(s));
                }
                left
            }
            (None, Runs::Late) => {
                self.out.late = self.out.late.meet(s);
                self.saw(self.late.seen.of(s));
                s.meet(self.late.exit.of(s))
            }
            (None, Runs::Restart) => {
                self.out.restart = self.out.restart.meet(s);
                s
            }
            (None, Runs::Other) => s,
        };
        if n.kind == NodeKind::Jump {
            match word.to_ascii_uppercase().as_slice() {
                b"GOTO" => {
                    let label = NameKey(first_word(after_first_word(text)));
                    match self.out.gotos.iter_mut().find(|(l, _)| *l == label) {
                        Some((_, h)) => *h = h.meet(s),
                        None => self.out.gotos.push((label, s)),
                    }
                    return Holds::Unreached;
                }
                b"RETURN" => {
                    self.out.exit = self.out.exit.meet(s);
                    return Holds::Unreached;
                }
                // `RAISE` goes to the error handler (the body's state is met above), which may
                // go on after it, or, from the handler, to the caller's; `EXIT` ends the
                // program.
                b"RAISE" => after = Holds::Unreached,
                b"EXIT" => return Holds::Unreached,
                b"RETRY" => {
                    self.out.retry = self.out.retry.meet(s);
                    return Holds::Unreached;
                }
                b"TRYNEXT" => {
                    self.out.trynext = self.out.trynext.meet(s);
                    return Holds::Unreached;
                }
                _ => {}
            }
        }
        if self.handled && !self.in_handler {
            // `TRYNEXT` goes on after the statement that raised, with what the handler leaves.
            after = after.meet(self.trynext.of(self.raised_by(runs, s)));
        }
        self.saw(after);
        after
    }

    /// What the error handler of routine `node` leaves at its `TRYNEXT`s and its `RETRY`s, if
    /// it has one.
    fn handler_effects(&mut self, node: usize) -> Option<(Effect, Effect)> {
        let nodes = self.nodes;
        let h = children(nodes, node).find(|&h| self.is_error_handler(h))?;
        let kept = std::mem::take(&mut self.out);
        self.in_handler = true;
        let mut left = [(Holds::Unreached, Holds::Unreached); 2];
        for (entry, out) in [Holds::Maybe(ENTRY), Holds::No].into_iter().zip(&mut left) {
            self.out = Walked::default();
            let mut s = entry;
            for c in children(nodes, h) {
                s = self.statement(c, s);
            }
            *out = (self.out.trynext, self.out.retry);
        }
        self.in_handler = false;
        self.out = kept;
        let [(trynext_maybe, retry_maybe), (trynext_no, retry_no)] = left;
        Some((
            Effect {
                maybe: trynext_maybe,
                no: trynext_no,
            },
            Effect {
                maybe: retry_maybe,
                no: retry_no,
            },
        ))
    }

    /// Whether node `at` is an `ERROR` handler.
    fn is_error_handler(&self, at: usize) -> bool {
        let nodes = self.nodes;
        nodes.get(at).is_some_and(|n| n.kind == NodeKind::Handler)
            && children(nodes, at)
                .filter_map(|c| nodes.get(c))
                .find(|c| c.kind == NodeKind::HandlerHead)
                .is_some_and(|c| is_word(self.text(c), "ERROR"))
    }

    /// An `IF` (parts `IF`, `ELSEIF`, `ELSE`, `ENDIF`) or a `TEST` (`TEST`, `CASE`, `DEFAULT`,
    /// `ENDTEST`): the meet of its branches, and of the state before when no `ELSE` or
    /// `DEFAULT` catches the rest.
    fn branches(&mut self, at: usize, s: Holds, part: NodeKind) -> Holds {
        let mut out = Holds::Unreached;
        let mut branch: Option<Holds> = None;
        let mut catches_all = false;
        for c in children(self.nodes, at) {
            let Some(n) = self.nodes.get(c).copied() else {
                continue;
            };
            if n.kind != part {
                if let Some(b) = branch {
                    branch = Some(self.statement(c, b));
                }
                continue;
            }
            if let Some(b) = branch.take() {
                out = out.meet(b);
            }
            // Its conditions and cases are read with the state before it.
            self.record_uses(&n, s);
            let word = first_word(self.text(&n)).to_ascii_uppercase();
            match word.as_slice() {
                b"ENDIF" | b"ENDTEST" | b"TEST" => {}
                b"ELSE" | b"DEFAULT" => {
                    catches_all = true;
                    branch = Some(s);
                }
                _ => branch = Some(s),
            }
        }
        if let Some(b) = branch {
            out = out.meet(b);
        }
        if catches_all { out } else { out.meet(s) }
    }

    /// A `WHILE` or `FOR`: its body entered with the state before and with the state its last
    /// pass leaves, to a fixpoint; left at its condition, with either.
    fn looped(&mut self, at: usize, s: Holds) -> Holds {
        let mut top = s;
        loop {
            let mut body = top;
            for c in children(self.nodes, at) {
                match self.nodes.get(c).copied() {
                    // Its condition (or bounds) read with the state at the top.
                    Some(part) if matches!(part.kind, NodeKind::WhilePart | NodeKind::ForPart) => {
                        self.record_uses(&part, top);
                    }
                    _ => body = self.statement(c, body),
                }
            }
            let next = s.meet(body);
            if next == top {
                return top;
            }
            top = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Task;

    /// The skeleton the parse keeps is the whole tree's branches and [`super::walked`] leaves,
    /// each branch's subtree ending where its last kept descendant does: over every RAPID
    /// sample and test file.
    #[test]
    fn the_skeleton_is_the_whole_tree_without_its_gaps_and_declarations() {
        let mut files = 0;
        for dir in [
            "samples/rapid",
            "samples/robotstudio_backup",
            "tests/data/rapid",
        ] {
            let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
            let mut stack = vec![root];
            while let Some(d) = stack.pop() {
                for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
                    let path = e.path();
                    if path.is_dir() {
                        stack.push(path);
                        continue;
                    }
                    let ext = path.extension().and_then(|x| x.to_str()).unwrap_or("");
                    if !["mod", "modx", "sys", "sysx", "prg"].contains(&ext.to_lowercase().as_str())
                    {
                        continue;
                    }
                    let src = std::fs::read(&path).unwrap();
                    let whole = crate::rapid::parse_tree(&src).tree.nodes;
                    // Kept: each node's new index, by its old one (one past the end too).
                    let kept: Vec<bool> = whole
                        .iter()
                        .map(|n| n.kind.is_branch() || super::walked(n.kind))
                        .collect();
                    let mut new_index = Vec::with_capacity(whole.len() + 1);
                    let mut count = 0u32;
                    for &k in &kept {
                        new_index.push(count);
                        count += u32::from(k);
                    }
                    new_index.push(count);
                    let expected: Vec<_> = whole
                        .iter()
                        .zip(&kept)
                        .filter(|(_, k)| **k)
                        .map(|(n, _)| crate::rapid::Node {
                            subtree_end: new_index[n.subtree_end as usize],
                            ..*n
                        })
                        .collect();
                    let mut none = crate::syntax::NoSink;
                    let skeleton =
                        crate::rapid::parser::parse_streamed(&src, &mut none, super::walked);
                    assert!(skeleton.round_trip, "{}", path.display());
                    assert_eq!(skeleton.tree.nodes, expected, "{}", path.display());
                    assert!(expected.len() < whole.len(), "{}", path.display());
                    files += 1;
                }
            }
        }
        assert!(files >= 20, "{files} files");
    }

    /// The task of the modules, and where each of the patterns asked is written in them
    /// (module, first byte), in order.
    fn task_of<'s>(modules: &[&'s str]) -> (Task<'s>, impl Fn(&str) -> Vec<(usize, usize)>) {
        let sources = modules.iter().map(|m| (m.as_bytes(), None)).collect();
        let modules = modules.to_vec();
        let find = move |pattern: &str| -> Vec<(usize, usize)> {
            modules
                .iter()
                .enumerate()
                .flat_map(|(m, src)| src.match_indices(pattern).map(move |(at, _)| (m, at)))
                .collect()
        };
        (Task::new(sources), find)
    }

    /// For each `MoveL` of the modules, in order, whether the declared value may reach it, the
    /// program giving `wA` its other value at each `wA :=`.
    fn declared_at_motions(modules: &[&str]) -> Vec<bool> {
        let (task, find) = task_of(modules);
        task.declared_may_reach(&find("wA :="), &find("MoveL"))
    }

    /// For each `MoveL` of the modules, in order, the `PDispSet` (its index among them) whose
    /// displacement may be active where it runs, `PDispOff` ending it.
    fn displaced_at_motions(modules: &[&str]) -> Vec<Option<usize>> {
        let (task, find) = task_of(modules);
        task.active_at(&find("PDispSet"), &find("PDispOff"), &find("MoveL"))
    }

    fn module(body: &str) -> String {
        format!(
            "MODULE M\n  PERS wobjdata wA:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n{body}ENDMODULE\n"
        )
    }

    const GIVE: &str = "wA := [FALSE,TRUE,\"\",[[1,2,3],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];";

    #[test]
    fn a_motion_before_the_assignment_in_program_order_may_run_with_the_declared_value() {
        // After it in its routine: the value given only. Before it: the declared value the
        // first time `main` runs.
        let m = module(&format!(
            "  PROC main()\n    MoveL p1;\n    {GIVE}\n    MoveL p2;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true, false]);
        // Given on one branch only: after the IF, either.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n    MoveL p1;\n  ENDPROC\n  PROC other()\n    IF x THEN\n      {GIVE}\n    ELSEIF y THEN\n      {GIVE}\n    ENDIF\n    MoveL p2;\n    IF x THEN\n      {GIVE}\n    ELSE\n      {GIVE}\n    ENDIF\n    MoveL p3;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false, true, false]);
        // In a loop, given after the motion: the next pass moves with it, the first not.
        let m = module(&format!(
            "  PROC main()\n    WHILE TRUE DO\n      MoveL p1;\n      {GIVE}\n    ENDWHILE\n    MoveL p2;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true, true]);
    }

    #[test]
    fn calls_carry_the_value_into_routines_and_back() {
        // `init` gives it on every way back; `mv` is called before and after.
        let m = module(&format!(
            "  PROC init()\n    {GIVE}\n  ENDPROC\n  PROC mv()\n    MoveL p1;\n  ENDPROC\n  PROC only_after()\n    MoveL p2;\n  ENDPROC\n  PROC main()\n    init;\n    only_after;\n    MoveL p3;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true, false, false]);
        let m = module(&format!(
            "  PROC init()\n    {GIVE}\n  ENDPROC\n  PROC mv()\n    MoveL p1;\n  ENDPROC\n  PROC main()\n    mv;\n    init;\n    mv;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true]);
        // An `init` that may return without giving it (a RETURN before, one branch).
        let m = module(&format!(
            "  PROC init()\n    IF x RETURN;\n    {GIVE}\n  ENDPROC\n  PROC main()\n    init;\n    MoveL p1;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true]);
        // Across modules: another module's routine that is not LOCAL.
        let a = module(&format!("  PROC init()\n    {GIVE}\n  ENDPROC\n"));
        let b = "MODULE B\n  PROC main()\n    init;\n    MoveL p1;\n  ENDPROC\nENDMODULE\n";
        assert_eq!(declared_at_motions(&[&a, b]), [false]);
        let a = a.replace("PROC init", "LOCAL PROC init");
        assert_eq!(declared_at_motions(&[&a, b]), [true]);
    }

    #[test]
    fn routines_entered_from_outside_start_with_the_declared_value() {
        // A routine nothing calls, a TRAP, and any PROC once a call names its routine at run
        // time by a name not written as a literal; by one that is, the PROCs it names.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n    mv;\n  ENDPROC\n  PROC mv()\n    MoveL p1;\n  ENDPROC\n  PROC lone()\n    MoveL p2;\n  ENDPROC\n  TRAP t\n    MoveL p3;\n  ENDTRAP\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false, true, true]);
        let late = |call: &str| {
            m.replace(
                "    mv;\n  ENDPROC\n  PROC mv",
                &format!("    mv;\n    {call};\n  ENDPROC\n  PROC mv"),
            )
        };
        for any in ["%pname%", "CallByVar pname, 1"] {
            assert_eq!(
                declared_at_motions(&[&late(any)]),
                [true, true, true],
                "{any}"
            );
        }
        for named in ["%\"lo\"+\"ne\"%", "%\"LONE\"%", "CallByVar \"lo\", 1"] {
            assert_eq!(
                declared_at_motions(&[&late(named)]),
                [false, true, true],
                "{named}"
            );
        }
        // A routine a late call runs by its whole name is entered from outside too.
        let only_late = late("%\"mv\"%").replace("    mv;\n    %", "    %");
        assert_eq!(declared_at_motions(&[&only_late]), [true, true, true]);
        // Two routines that call only each other: whatever runs them runs them from outside.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n  ENDPROC\n  PROC a()\n    MoveL p1;\n    b;\n  ENDPROC\n  PROC b()\n    a;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true]);
    }

    #[test]
    fn the_error_handler_and_its_ways_back() {
        // Given in the handler, then RETRY: the motion runs again with it, the first time with
        // the declared value.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n    MoveL p1;\n  ERROR\n    RETRY;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false]);
        let m = module(&format!(
            "  PROC mv()\n    MoveL p1;\n  ERROR\n    {GIVE}\n    RETRY;\n  ENDPROC\n  PROC main()\n    mv;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true]);
        // A call that raises before it gives the value, skipped by TRYNEXT: the motion after
        // it may run with the declared value.
        let m = module(&format!(
            "  PROC init()\n    MoveL p1;\n    {GIVE}\n  ENDPROC\n  PROC main()\n    {GIVE}\n    MoveL p2;\n  ENDPROC\n  PROC other()\n    init;\n    MoveL p3;\n  ERROR\n    TRYNEXT;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true, false, true]);
        let retry = m.replace("TRYNEXT", "RETRY");
        assert_eq!(declared_at_motions(&[&retry]), [true, false, false]);
    }

    #[test]
    fn goto_and_labels() {
        // Jumping back above the assignment, and over it.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n  again:\n    MoveL p1;\n    IF x GOTO again;\n  ENDPROC\n  PROC other()\n    IF x GOTO past;\n    {GIVE}\n  past:\n    MoveL p2;\n  ENDPROC\n  PROC third()\n  top:\n    MoveL p3;\n    {GIVE}\n    GOTO top;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false, true, true]);
        // After EXIT or RETURN: no path reaches it, so no value.
        let m = module(&format!(
            "  PROC main()\n    EXIT;\n    MoveL p1;\n  ENDPROC\n  PROC b()\n    {GIVE}\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false]);
    }

    #[test]
    fn test_cases_without_default_keep_the_value_before() {
        let m = module(&format!(
            "  PROC main()\n    TEST k\n    CASE 1:\n      {GIVE}\n    CASE 2:\n      {GIVE}\n    ENDTEST\n    MoveL p1;\n    TEST k\n    CASE 1:\n      {GIVE}\n    DEFAULT:\n      {GIVE}\n    ENDTEST\n    MoveL p2;\n  ENDPROC\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [true, false]);
    }

    #[test]
    fn a_displacement_is_active_from_its_set_to_its_end_on_every_path() {
        // Each motion named with the set that reaches it.
        let m = module(
            "  PROC a()\n    PDispSet d1;\n    MoveL p1;\n    PDispOff;\n  ENDPROC\n  PROC b()\n    PDispSet d2;\n    MoveL p2;\n    PDispOff;\n  ENDPROC\n  PROC main()\n    MoveL p3;\n    a;\n    b;\n  ENDPROC\n",
        );
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), Some(1), None]);
        // Jumping back above the set: the motion there may run displaced.
        let m = module(
            "  PROC main()\n  again:\n    MoveL p1;\n    PDispSet d;\n    MoveL p2;\n    IF x GOTO again;\n    PDispOff;\n  ENDPROC\n",
        );
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), Some(0)]);
        let m = m.replace("    IF x GOTO again;\n", "");
        assert_eq!(displaced_at_motions(&[&m]), [None, Some(0)]);
        // `ExitCycle` starts `main` again with what is active there.
        let m = m.replace("    PDispOff;", "    IF x ExitCycle;\n    PDispOff;");
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), Some(0)]);
    }

    #[test]
    fn the_error_handler_may_displace_what_it_goes_back_to() {
        // Set in the handler, then RETRY: the statement that raised runs again displaced;
        // TRYNEXT: the one after it.
        let m = module(
            "  PROC other()\n    MoveL p1;\n    MoveL p2;\n  ERROR\n    PDispSet d;\n    RETRY;\n  ENDPROC\n  PROC main()\n    other;\n    PDispOff;\n    MoveL p3;\n  ENDPROC\n",
        );
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), Some(0), None]);
        let trynext = m.replace("RETRY", "TRYNEXT");
        assert_eq!(displaced_at_motions(&[&trynext]), [None, Some(0), None]);
        // An error a routine raises while its displacement is active goes to its caller's
        // handler with it active, and TRYNEXT goes on after the call so.
        let m = module(
            "  PROC inner()\n    PDispSet d;\n    MoveL p1;\n    PDispOff;\n  ENDPROC\n  PROC main()\n    inner;\n    MoveL p2;\n  ENDPROC\n",
        );
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), None]);
        let m = m.replace("    MoveL p2;\n", "    MoveL p2;\n  ERROR\n    TRYNEXT;\n");
        assert_eq!(displaced_at_motions(&[&m]), [Some(0), Some(0)]);
    }
}
