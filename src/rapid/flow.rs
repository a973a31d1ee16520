//! Which value a frame (a work object or a tool) holds where a motion uses it, when the program
//! gives the frame one other value than its declaration (docs/design.md, "Frames the program
//! assigns").
//!
//! Asked only of such a frame (most programs give no frame a value), over the modules' skeleton
//! trees: their branches and statements' leaves ([`walked`]), which the parse that reads the
//! targets keeps for a module that gives a frame a value (and a module that gives none is
//! parsed again for it, when another one does). Nothing gives the
//! frame its declared value back (a program that does is refused before this is asked), so
//! along one path the frame holds the value given once the path has passed an assignment of
//! it, and the declared one before. Over every path that may reach a motion, the value given is
//! the only one there when every such path passes an assignment first: a must-analysis, the
//! meet of two paths being the lesser [`Holds`].
//!
//! What may reach a point: program order in the routine, with its `IF`, `TEST`, loops (which
//! may run no pass or come round again), `GOTO` and its labels, `RETURN`, `EXIT` and `RAISE`;
//! the `ERROR` handler, entered from any statement of the body that may raise an error (a call
//! included: an error of a routine without a handler of its own goes to its caller's), and left
//! by `RETRY` (back to that statement, with at least the value it raised with: nothing lowers
//! it) or `TRYNEXT` (to the one after it, skipping what that statement would have given); a
//! call, after which the value given holds if it held before or the routine called gives it on
//! every way back. A routine starts with the meet of its calls' states. One the program may
//! start or enter from outside starts with the declared value possible: `main` (which the
//! controller runs again and again: a motion before the assignment runs with the declared value
//! the first time only, and with the value given after), a routine no statement calls (or only
//! routines that no such one reaches), a `TRAP` or a `FUNC` (called from expressions, which are
//! not followed), and every `PROC` when a call names its routine only at run time (`%name%`,
//! `CallByVar`).

use crate::names::{NameKey, NameMap};
use crate::rapid::tree::NodeKind;

type Node = crate::rapid::Node;

/// What the frame may hold at a point, ordered for the meet of two paths (the lesser).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
enum Holds {
    /// Its declared value, on some path: the program may not have given it the other yet.
    Declared,
    /// The value the program gives it, on every path.
    Given,
    /// No path reaches the point.
    #[default]
    Nothing,
}

impl Holds {
    fn meet(self, other: Holds) -> Holds {
        self.min(other)
    }

    /// After a call of a routine that returns with `callee` when entered with the declared
    /// value: nothing gives the declared value back, so the value given holds after the call
    /// if it held before or the routine gives it.
    fn after_call(self, callee: Holds) -> Holds {
        match (self, callee) {
            (Holds::Nothing, _) | (_, Holds::Nothing) => Holds::Nothing,
            (a, b) => a.max(b),
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
        let mut kinds = Vec::new();
        let mut names: Vec<&'s [u8]> = Vec::new();
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
                    from_outside: false,
                });
                kinds.push(kind);
                names.push(name);
            }
        }
        let mut task = Task {
            modules,
            routines,
            by_name,
            callers: Vec::new(),
        };
        // Who calls whom, as written; and whether a call names its routine at run time.
        let mut callers = vec![Vec::new(); task.routines.len()];
        let mut late = false;
        for (r, routine) in task.routines.iter().enumerate() {
            let Some((src, nodes)) = task.modules.get(routine.module) else {
                continue;
            };
            let end = nodes
                .get(routine.node)
                .map_or(routine.node, |n| n.subtree_end as usize);
            for n in nodes.get(routine.node..end).unwrap_or_default() {
                match n.kind {
                    NodeKind::LateCall => late = true,
                    NodeKind::Call => {
                        let name = first_word(n.span().slice(src));
                        if name.eq_ignore_ascii_case(b"CallByVar") {
                            late = true;
                        } else if let Some(list) = task
                            .callee(routine.module, name)
                            .and_then(|callee| callers.get_mut(callee))
                            && !list.contains(&r)
                        {
                            list.push(r);
                        }
                    }
                    _ => {}
                }
            }
        }
        for (r, routine) in task.routines.iter_mut().enumerate() {
            let kind = kinds.get(r).copied().unwrap_or(Kind::Trap);
            let name = names.get(r).copied().unwrap_or_default();
            routine.from_outside = kind != Kind::Proc
                || late
                || name.eq_ignore_ascii_case(b"main")
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
        task
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
        // (A source is below 4 GiB, and so is the count of its uses.)
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
        let given = per_module(given);
        let use_at = per_module(uses);
        let frame = Frame {
            given: &given,
            uses: &use_at,
        };
        let n = self.routines.len();
        // What each routine returns with when entered with the declared value: a greatest
        // fixpoint, every routine first taken to return with nothing, one walked again when a
        // routine it calls turns out to return with less.
        let mut returns = vec![Holds::Nothing; n];
        let mut queued = vec![true; n];
        let mut work: Vec<usize> = (0..n).rev().collect();
        while let Some(r) = work.pop() {
            if let Some(q) = queued.get_mut(r) {
                *q = false;
            }
            // (Its uses are not asked for here: a summary only.)
            let summary = Frame { uses: &[], ..frame };
            let exit = self.walk(r, Holds::Declared, &summary, &returns).exit;
            if returns.get(r).is_some_and(|&x| x != exit) {
                if let Some(x) = returns.get_mut(r) {
                    *x = exit;
                }
                for &c in self.callers.get(r).into_iter().flatten() {
                    if let Some(q) = queued.get_mut(c).filter(|q| !**q) {
                        *q = true;
                        work.push(c);
                    }
                }
            }
        }
        // What each routine starts with: the meet of the states its calls are made in, and the
        // declared value for one the program may start or enter from outside.
        let outside = |r: usize| {
            if self.routines.get(r).is_some_and(|x| x.from_outside) {
                Holds::Declared
            } else {
                Holds::Nothing
            }
        };
        let mut entry: Vec<Holds> = (0..n).map(outside).collect();
        let mut queued: Vec<bool> = entry.iter().map(|&e| e != Holds::Nothing).collect();
        let mut work: Vec<usize> = (0..n).filter(|&r| queued[r]).rev().collect();
        // Per routine, its uses as its last walk found them: with the entry it keeps, since a
        // routine is walked again whenever its entry is lowered.
        let mut last_uses: Vec<Option<Vec<(u32, Holds)>>> = vec![None; n];
        while let Some(r) = work.pop() {
            if let Some(q) = queued.get_mut(r) {
                *q = false;
            }
            let e = entry.get(r).copied().unwrap_or(Holds::Declared);
            let walked = self.walk(r, e, &frame, &returns);
            // The states only ever get lower: a callee's entry is lowered by each call.
            for (callee, h) in walked.calls {
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
        // a use in no routine, as the declared value.
        let mut at_use: Vec<Option<Holds>> = vec![None; uses.len()];
        for (r, walked) in last_uses.into_iter().enumerate() {
            let walked =
                walked.unwrap_or_else(|| self.walk(r, Holds::Nothing, &frame, &returns).uses);
            for (k, h) in walked {
                if let Some(slot) = at_use.get_mut(k as usize) {
                    *slot = Some(slot.map_or(h, |x| x.meet(h)));
                }
            }
        }
        at_use
            .into_iter()
            .map(|h| h.is_none_or(|h| h == Holds::Declared))
            .collect()
    }

    /// Walks routine `r` entered with `entry`, to a fixpoint of its labels and its error
    /// handler's ways back into the body.
    fn walk(&self, r: usize, entry: Holds, frame: &Frame<'_>, returns: &[Holds]) -> Walked<'s> {
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
            given: frame.given.get(routine.module).map_or(&[], Vec::as_slice),
            uses: frame.uses.get(routine.module).map_or(&[], Vec::as_slice),
            returns,
            labels: Vec::new(),
            trynext: Holds::Nothing,
            in_handler: false,
            out: Walked::default(),
            last_callee: None,
        };
        w.trynext = w.skipped(routine.node);
        // Each pass but the last lowers the state at a label (three states each), so the passes
        // are bounded; the bound is only a guard.
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
        // Not settled: every use and call of the routine as reached with the declared value.
        let mut out = std::mem::take(&mut w.out);
        out.exit = Holds::Declared;
        let uses = out.uses.iter_mut().map(|(_, h)| h);
        for h in uses.chain(out.calls.iter_mut().map(|(_, h)| h)) {
            *h = Holds::Declared;
        }
        out
    }
}

/// Passes over one routine before its labels are taken as not settling.
const PASSES: usize = 1000;

/// The frame's assignments and uses in each module: (first byte, index among all), sorted.
#[derive(Clone, Copy)]
struct Frame<'f> {
    given: &'f [Vec<(u32, u32)>],
    uses: &'f [Vec<(u32, u32)>],
}

/// What a walk of a routine finds.
#[derive(Default)]
struct Walked<'s> {
    /// The frame as the routine returns (at `ENDPROC`, a `RETURN`, or the end of its `ERROR`
    /// handler).
    exit: Holds,
    /// Its calls of routines of the task, with the state before each.
    calls: Vec<(usize, Holds)>,
    /// Its uses (index among all), with the state before each.
    uses: Vec<(u32, Holds)>,
    /// The meet of the states at the `GOTO`s of each label.
    gotos: Vec<(NameKey<'s>, Holds)>,
    /// The meet of the states at the statements of the body that may raise an error.
    raised: Holds,
    /// The meet of the states at the error handler's `TRYNEXT`s.
    trynext: Holds,
}

struct Walker<'w, 's> {
    task: &'w Task<'s>,
    module: usize,
    src: &'s [u8],
    nodes: &'w [Node],
    given: &'w [(u32, u32)],
    uses: &'w [(u32, u32)],
    returns: &'w [Holds],
    /// The state at each label's `GOTO`s, as the last pass found it.
    labels: Vec<(NameKey<'s>, Holds)>,
    /// What the error handler leaves at its `TRYNEXT`s when it starts with the declared value
    /// (`Nothing`: it has none).
    trynext: Holds,
    in_handler: bool,
    out: Walked<'s>,
    /// The last callee looked up, as written, and the routine it names.
    last_callee: Option<(&'s [u8], Option<usize>)>,
}

impl<'s> Walker<'_, 's> {
    fn text(&self, n: &Node) -> &'s [u8] {
        n.span().slice(self.src)
    }

    fn label(&self, name: NameKey<'_>) -> Holds {
        self.labels
            .iter()
            .find(|(l, _)| *l == name)
            .map_or(Holds::Nothing, |&(_, h)| h)
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
            // `BACKWARD` run with whatever the routine held, its entry's at the least.
            let mut s = if error { raised } else { entry };
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
                    if self
                        .nodes
                        .get(c)
                        .is_some_and(|n| n.kind != NodeKind::CompactIfHead)
                    {
                        then = self.statement(c, then);
                    }
                }
                s.meet(then)
            }
            NodeKind::While | NodeKind::For => self.looped(at, s),
            _ => s,
        }
    }

    /// A statement that is one leaf.
    fn leaf(&mut self, n: &Node, s: Holds) -> Holds {
        // The assignment of the value given (which raises no error).
        if n.kind == NodeKind::Assign && Self::within(n, self.given).next().is_some() {
            return if s == Holds::Nothing { s } else { Holds::Given };
        }
        let mut s = s;
        if !self.in_handler && s != Holds::Nothing {
            self.out.raised = self.out.raised.meet(s);
        }
        let before = s;
        for k in Self::within(n, self.uses) {
            self.out.uses.push((k, s));
        }
        if s == Holds::Nothing {
            return s;
        }
        let text = self.text(n);
        let word = first_word(text);
        match n.kind {
            NodeKind::Call => {
                // Call after call names one instruction (`MoveL`): its lookup is kept.
                let callee = match self.last_callee {
                    Some((name, found)) if name == word => found,
                    _ => {
                        let found = self.task.callee(self.module, word);
                        self.last_callee = Some((word, found));
                        found
                    }
                };
                if let Some(callee) = callee {
                    self.out.calls.push((callee, s));
                    let returns = self.returns.get(callee).copied();
                    s = s.after_call(returns.unwrap_or(Holds::Declared));
                }
            }
            NodeKind::Jump => match word.to_ascii_uppercase().as_slice() {
                b"GOTO" => {
                    let label = NameKey(first_word(after_first_word(text)));
                    match self.out.gotos.iter_mut().find(|(l, _)| *l == label) {
                        Some((_, h)) => *h = h.meet(s),
                        None => self.out.gotos.push((label, s)),
                    }
                    return Holds::Nothing;
                }
                b"RETURN" => {
                    self.out.exit = self.out.exit.meet(s);
                    return Holds::Nothing;
                }
                // `RAISE` goes to the error handler (the body's state is met above) or, from
                // the handler, to the caller's; `EXIT` ends the program.
                b"EXIT" | b"RAISE" => return Holds::Nothing,
                // Back to the statement that raised, with at least what it raised with.
                b"RETRY" => return Holds::Nothing,
                b"TRYNEXT" => {
                    self.out.trynext = self.out.trynext.meet(s);
                    return Holds::Nothing;
                }
                _ => {}
            },
            _ => {}
        }
        if !self.in_handler {
            // `TRYNEXT` goes on after the statement that raised, with what it raised with and
            // what the handler gives.
            s = s.meet(before.after_call(self.trynext));
        }
        s
    }

    /// What the error handlers of routine `node` leave at their `TRYNEXT`s when they start with
    /// the declared value.
    fn skipped(&mut self, node: usize) -> Holds {
        let nodes = self.nodes;
        let kept = std::mem::take(&mut self.out);
        self.in_handler = true;
        for h in children(nodes, node) {
            if !self.is_error_handler(h) {
                continue;
            }
            let mut s = Holds::Declared;
            for c in children(nodes, h) {
                s = self.statement(c, s);
            }
        }
        self.in_handler = false;
        let out = std::mem::replace(&mut self.out, kept);
        out.trynext
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
        let mut out = Holds::Nothing;
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
                let part = self
                    .nodes
                    .get(c)
                    .is_some_and(|n| matches!(n.kind, NodeKind::WhilePart | NodeKind::ForPart));
                if !part {
                    body = self.statement(c, body);
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

    /// For each `MoveL` of the modules, in order, whether the declared value may reach it, the
    /// program giving `wA` its other value at each `wA :=`.
    fn declared_at_motions(modules: &[&str]) -> Vec<bool> {
        let sources: Vec<&[u8]> = modules.iter().map(|m| m.as_bytes()).collect();
        let find = |pattern: &str| -> Vec<(usize, usize)> {
            modules
                .iter()
                .enumerate()
                .flat_map(|(m, src)| src.match_indices(pattern).map(move |(at, _)| (m, at)))
                .collect()
        };
        let sources = sources.into_iter().map(|s| (s, None)).collect();
        Task::new(sources).declared_may_reach(&find("wA :="), &find("MoveL"))
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
        // time.
        let m = module(&format!(
            "  PROC main()\n    {GIVE}\n    mv;\n  ENDPROC\n  PROC mv()\n    MoveL p1;\n  ENDPROC\n  PROC lone()\n    MoveL p2;\n  ENDPROC\n  TRAP t\n    MoveL p3;\n  ENDTRAP\n"
        ));
        assert_eq!(declared_at_motions(&[&m]), [false, true, true]);
        let late = m.replace(
            "    mv;\n  ENDPROC\n  PROC mv",
            "    mv;\n    %\"lo\"+\"ne\"%;\n  ENDPROC\n  PROC mv",
        );
        assert_eq!(declared_at_motions(&[&late]), [true, true, true]);
        let by_var = m.replace(
            "    mv;\n  ENDPROC\n  PROC mv",
            "    mv;\n    CallByVar \"lo\", 1;\n  ENDPROC\n  PROC mv",
        );
        assert_eq!(declared_at_motions(&[&by_var]), [true, true, true]);
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
}
