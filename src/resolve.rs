//! Usage resolution for every language, over language-neutral facts that each language's
//! extractor reports: the declarations of each file (name, scope, kind), its routines and their
//! parameters, the instructions that use targets (the frame, tool and stationary-tool mode they
//! move with, the arguments they pass, the references they make) and the values the program
//! computes when it runs. This pass looks the references up among the program's declarations,
//! follows targets through routine parameters, and records each target's [`Usage`].
//!
//! A language finds its facts in its own syntax (RAPID reads the frame from `\WObj:=`, KRL
//! from program order: `$BASE=…`, `FDAT_ACT`, `BAS(#BASE,n)`) and says how its names reach
//! declarations ([`Naming`]: the array bracket, when an element reference reaches the whole
//! array, whether a file's own declarations hide the others').
//!
//! [`Usage`]: crate::position::Usage

use crate::names::{FirstLetters, NameIndex, NameKey, NameMap, fold, fold_into};
use crate::position::{FrameDecl, FrameName, RunTimeValue, UseLine};
use crate::syntax::Span;

/// How many calls deep a routine's effects on its callers are followed (a target passed on
/// through RAPID routine parameters, a KRL subroutine that sets the base): deeper chains and
/// cycles stop here.
pub(crate) const CALL_DEPTH: usize = 16;

/// How a language's references reach its declarations.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Naming {
    /// The brackets of an array index (`{`…`}` RAPID, `[`…`]` KRL).
    pub(crate) open: char,
    /// See [`open`](Naming::open).
    pub(crate) close: char,
    /// When a reference reaches every element of an array.
    pub(crate) arrays: ArrayReach,
}

/// When a reference reaches every element of an array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ArrayReach {
    /// A name not declared as written (the whole array `pArr`, an element chosen at run time
    /// `pArr{i}`) reaches every element of the array it names or indexes (RAPID).
    WhenUndeclared,
    /// A name reaches its declaration, and an index that is not a literal (`P[I]`, `P[I+1,2]`)
    /// every element of the array as well (KRL).
    WhenIndexComputed,
}

/// What a declared name is, as far as finding a motion's arguments goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DeclKind {
    /// A tool (RAPID `tooldata`).
    Tool,
    /// A zone (RAPID `zonedata`).
    Zone,
    /// A speed (RAPID `speeddata`).
    Speed,
    /// Anything else (a routine, a number, a target).
    Other,
}

/// The declarations of a file, recorded as each is read: the names of a kind that finds a
/// motion's arguments (tools, zones, speeds) and the names declared twice at file level. A
/// name is hashed when it is declared, while its bytes are at hand: a pass over a module's
/// 100,000 declared names afterwards read each from the source again, a cache miss apiece
/// (8 ms of a 20 MB module's `check`, where the 2 MB module's took 0.4).
#[derive(Debug, Default)]
pub(crate) struct Declared {
    /// Names of a kind other than [`DeclKind::Other`], in file order.
    kinds: Vec<(crate::syntax::Span32, DeclKind)>,
    /// The file-level names seen so far, with their hashes (so the table grows without
    /// reading a name again).
    seen: hashbrown::HashTable<(u64, crate::syntax::Span32)>,
    /// (the second declaration, the first) of each name declared twice at file level.
    twice: Vec<(Span, Span)>,
}

impl Declared {
    /// Records the declaration of `name` (in `src`) as `kind`, at file level when
    /// `file_scope`.
    pub(crate) fn declare(
        &mut self,
        src: &[u8],
        name: crate::syntax::Span32,
        kind: DeclKind,
        file_scope: bool,
    ) {
        use hashbrown::hash_table::Entry;
        use std::hash::BuildHasher as _;
        if kind != DeclKind::Other {
            self.kinds.push((name, kind));
        }
        if !file_scope {
            return;
        }
        let key = NameKey(name.span().slice(src));
        let hash =
            std::hash::BuildHasherDefault::<crate::names::NameHasher>::default().hash_one(key);
        let entry = self.seen.entry(
            hash,
            |&(h, first)| h == hash && NameKey(first.span().slice(src)) == key,
            |&(h, _)| h,
        );
        match entry {
            Entry::Occupied(e) => self.twice.push((name.span(), e.get().1.span())),
            Entry::Vacant(e) => {
                e.insert((hash, name));
            }
        }
    }
}

/// A name declared twice at file level.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Duplicate {
    /// The file.
    pub(crate) file: usize,
    /// The second declaration.
    pub(crate) again: Span,
    /// The first.
    pub(crate) first: Span,
}

/// The kinds of the program's declared names (names compared as the languages compare them),
/// and the names a file declares twice at file level. `files` gives each file's source and
/// declarations, in program order; a later declaration of a kind other than
/// [`DeclKind::Other`] wins.
pub(crate) fn declarations<'s, 'd>(
    files: impl IntoIterator<Item = (&'s [u8], &'d Declared)>,
) -> (NameMap<NameKey<'s>, DeclKind>, Vec<Duplicate>) {
    let mut kinds: NameMap<NameKey<'s>, DeclKind> = NameMap::default();
    let mut twice = Vec::new();
    for (file, (src, declared)) in files.into_iter().enumerate() {
        for &(name, kind) in &declared.kinds {
            kinds.insert(NameKey(name.span().slice(src)), kind);
        }
        twice.extend(
            declared
                .twice
                .iter()
                .map(|&(again, first)| Duplicate { file, again, first }),
        );
    }
    (kinds, twice)
}

/// A routine of a file that takes targets through its required parameters.
#[derive(Clone, Debug)]
pub(crate) struct Routine {
    /// Its name in the file's source.
    pub(crate) name: Span,
    /// Private to its file (RAPID `LOCAL`).
    pub(crate) local: bool,
    /// Its required parameters' names, in the order a call's positional arguments bind to them.
    pub(crate) params: Vec<Span>,
    /// Its optional parameters' names (RAPID `\\wo`), which no positional argument binds.
    pub(crate) optional: Vec<Span>,
}

impl Routine {
    /// The index among its required parameters of the one named `name` (its declaration's
    /// spans point into `src`).
    #[inline]
    pub(crate) fn required_named(&self, src: &[u8], name: &[u8]) -> Option<usize> {
        self.params
            .iter()
            .position(|p| NameKey(p.slice(src)) == NameKey(name))
    }

    /// The index of its parameter named `name`, required or optional: a required one's
    /// position, an optional one's after every required one (how [`ParamAt`] numbers them).
    pub(crate) fn any_named(&self, src: &[u8], name: &[u8]) -> Option<usize> {
        self.params
            .iter()
            .chain(&self.optional)
            .position(|p| NameKey(p.slice(src)) == NameKey(name))
    }

    /// Whether `name` is one of its parameters, required or optional.
    #[inline]
    pub(crate) fn has_parameter(&self, src: &[u8], name: &[u8]) -> bool {
        // Asked of every motion's frame and tool: most routines take no parameter.
        if self.params.is_empty() && self.optional.is_empty() {
            return false;
        }
        self.params
            .iter()
            .chain(&self.optional)
            .any(|p| NameKey(p.slice(src)) == NameKey(name))
    }
}

/// An instruction that uses targets: a motion (or a call that passes targets on) with the frame
/// and tool it moves with. It borrows what it references: a language builds one as it goes and
/// hands it to [`Binder::bind`].
#[derive(Clone, Debug, Default)]
pub(crate) struct Use<'a> {
    /// 1-based line of the instruction.
    pub(crate) line: usize,
    /// The routine it is written in (index into the file's routines).
    pub(crate) routine: Option<usize>,
    /// The routine it calls, by name in the file's source; a routine of the program takes the
    /// arguments its parameters bind to.
    pub(crate) callee: Option<Span>,
    /// The work object or base, as the language names it (`wobj0`, `BASE_DATA[3]`): a shared
    /// handle, which a language makes once per distinct name (100,000 targets used with `wCar`
    /// hold one `wCar`, and a use costs no copy of the text).
    pub(crate) frame: Option<FrameName>,
    /// The tool, as the language names it (shared like [`frame`](Use::frame)).
    pub(crate) tool: Option<FrameName>,
    /// A stationary-tool motion (RAPID `robhold TRUE`, KRL `IPO_FRAME #TCP`).
    pub(crate) stationary: bool,
    /// The frame is computed when the program runs: every target reached is, too.
    pub(crate) run_time: Option<RunTimeValue>,
    /// The frame or tool is a parameter of the use's routine, whatever each caller passes:
    /// every target reached is used with one trackfix cannot tell.
    pub(crate) passed: Option<std::sync::Arc<PassedFrames>>,
    /// The use may run while its work object (or its tool) holds its declared value, the
    /// program giving the frame another: every target reached is moved to in both. One for
    /// each of the two frames at most.
    pub(crate) two_values: Option<std::sync::Arc<[TwoValuesAt]>>,
    /// Positional arguments, in order, that are plain references (`None` for any other
    /// expression), in the file's source (as a RAPID call record keeps them).
    pub(crate) args: &'a [Option<crate::syntax::Span32>],
    /// Further references in the file's source (RAPID `Offs`/`RelTool` first arguments).
    pub(crate) refs: &'a [Span],
    /// Further references already [`fold`]ed (KRL: a motion's target and what it was copied
    /// from).
    pub(crate) folded: &'a [&'a str],
    /// Targets of the same file reached directly (inline literals), by index.
    pub(crate) targets: &'a [usize],
    /// The use writes what it names (a search's found position): a copy of a target
    /// ([`FileFacts::copies`]) is written, not the target it was copied from.
    pub(crate) writes: bool,
}

/// One file of a program as this pass sees it.
pub(crate) struct FileFacts<'a> {
    /// The file's name, as a message on a target of another file names it
    /// ([`UseLine::file_name`](crate::position::UseLine::file_name)).
    pub(crate) name: std::sync::Arc<str>,
    /// The module the file belongs to, an index shared by its files: a reference sees the
    /// declarations of its own module first, and of the others' only the exported ones
    /// (RAPID: a module is a file, its routine and `LOCAL` data private to it; KRL: a module
    /// is a `.src` and its `.dat`, and only what is declared `GLOBAL` and `$config.dat`'s is
    /// seen from elsewhere).
    pub(crate) module: usize,
    /// The bytes every span of the file's facts points into.
    pub(crate) src: &'a [u8],
    /// Its targets (their usage is recorded here).
    pub(crate) positions: &'a mut crate::position::PositionList,
    /// Per target, whether other files see it (`None`: all are seen).
    pub(crate) exported: Option<&'a [bool]>,
    /// Its frame declarations.
    pub(crate) frames: &'a [FrameDecl],
    /// Its routines.
    pub(crate) routines: &'a [Routine],
    /// Its run-time assignments.
    pub(crate) assignments: &'a [Assignment],
    /// Its copies of one name's value into another (RAPID `pv := p10;`, `buf{1} := p10;`,
    /// `pv := Offs(p10, 0, 0, 10);`, a function's `RETURN p;`): a use of the copy is a use of
    /// what the source reaches.
    pub(crate) copies: &'a [CopyFact],
}

/// A name's value copied into another, or computed from it: `copy := …source…`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CopyFact {
    /// What is written, as written (`pv`, `buf{1}`, `rec.p`, a function's name for its
    /// `RETURN`).
    pub(crate) copy: Span,
    /// A name the value is read from, as written (`p10`, `buf{i}`, a parameter).
    pub(crate) source: Span,
    /// The routine the copy is written in: a source naming one of its parameters is what the
    /// callers pass there.
    pub(crate) routine: Option<usize>,
}

/// An argument of a call that the positional binding of [`Use::args`] does not bind: one that
/// is not a plain name (`mv Offs(p10, 0, 0, 10);`, `mv getP();`) or one given by its
/// parameter's name (`mv \p:=p10;`). Rare: kept apart from the uses and bound by
/// [`Binder::bind_passed`].
#[derive(Clone, Debug)]
pub(crate) struct PassedArg {
    /// 1-based line of the call.
    pub(crate) line: usize,
    /// The routine the call is written in.
    pub(crate) routine: Option<usize>,
    /// The routine called, by name in the file's source.
    pub(crate) callee: Span,
    /// The parameter: by position among the required ones, else by name.
    pub(crate) param: PassedTo,
    /// The names the argument's value reads (each a copy of it or a part): a range of
    /// [`PassedArgs::names`].
    pub(crate) names: std::ops::Range<u32>,
}

/// A file's [`PassedArg`]s and the names they read, in one list shared by all of them: a
/// module passes a composed argument in every tenth call or so, and a vector of names each
/// was an allocation per argument.
#[derive(Debug, Default)]
pub(crate) struct PassedArgs {
    pub(crate) args: Vec<PassedArg>,
    pub(crate) names: Vec<Span>,
}

impl PassedArgs {
    /// Each argument with the names it reads.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (&PassedArg, &[Span])> + '_ {
        self.args.iter().map(|a| {
            let names = a.names.start as usize..a.names.end as usize;
            (a, self.names.get(names).unwrap_or_default())
        })
    }
}

/// Which parameter a [`PassedArg`] is given to.
#[derive(Clone, Copy, Debug)]
pub(crate) enum PassedTo {
    /// The required parameter at this position.
    Position(usize),
    /// The parameter of this name (in the file's source).
    Named(Span),
}

impl FileFacts<'_> {
    /// Whether other files see target `i` (`exported` `None`: every target is seen).
    pub(crate) fn exports(&self, i: usize) -> bool {
        self.exported
            .is_none_or(|e| e.get(i).copied().unwrap_or(false))
    }
}

/// Where a target is: (file, index into its positions).
type TargetAt = (usize, usize);

/// A [`TargetAt`] as a name index keeps it, in 32 bits each: the index holds one per declared
/// target and is built while every position of the program is held.
type Indexed = (u32, u32);

/// A target's place as a name index keeps it; `None` past 2^32 files or targets (no input has
/// that many).
fn indexed((m, i): TargetAt) -> Option<Indexed> {
    Some((u32::try_from(m).ok()?, u32::try_from(i).ok()?))
}

/// A routine's required parameter: (file, routine, parameter index).
type ParamAt = (usize, usize, usize);

/// `BASEPOS` for `BASEPOS[I]`, `P[I+1,2]`: an element chosen at run time, which may be any
/// element of the array. `None` for a name or a literal index (`P[3]`).
fn computed_index_array<'k>(naming: &Naming, key: &'k str) -> Option<&'k str> {
    let (array, rest) = key.split_once(naming.open)?;
    let index = rest.strip_suffix(naming.close)?;
    let literal = index.bytes().all(|b| b.is_ascii_digit() || b == b',');
    (!literal).then_some(array)
}

/// What the program's copies reach, by the folded name they are read under: keyed program-wide
/// (a copy into a `PERS` in one module moved to in another; two routines' locals of one name
/// are taken as one, which can only refuse more), by the name before any index or component,
/// each holding its full names (`buf{1}`, `rec.p`) with what a reference to it reaches.
#[derive(Debug, Default)]
struct Copies {
    by_root: std::collections::HashMap<String, Vec<CopyReach>>,
}

/// One name copies are written into, and what a reference to it reaches: targets, and the
/// parameters a copy of a parameter stands for (what every caller passes there).
#[derive(Debug, Default)]
struct CopyReach {
    key: String,
    targets: Vec<TargetAt>,
    params: Vec<ParamAt>,
}

/// The name a folded reference starts with (`BUF` of `BUF{I}.P`).
fn root_of(key: &str) -> &str {
    key.split(['{', '.', '[']).next().unwrap_or(key)
}

/// The parts of a folded reference after its root: `{…}` indexes and `.field` components.
fn parts_of(key: &str) -> Vec<&str> {
    let rest = key.get(root_of(key).len()..).unwrap_or_default();
    let (mut parts, mut depth, mut from) = (Vec::new(), 0usize, 0usize);
    for (i, c) in rest.char_indices() {
        match c {
            '{' | '[' if depth == 0 => {
                parts.extend(rest.get(from..i).filter(|p| !p.is_empty()));
                from = i;
                depth = 1;
            }
            '{' | '[' => depth += 1,
            '}' | ']' => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    parts.extend(rest.get(from..=i));
                    from = i + 1;
                }
            }
            '.' if depth == 0 => {
                parts.extend(rest.get(from..i).filter(|p| !p.is_empty()));
                from = i;
            }
            _ => {}
        }
    }
    parts.extend(rest.get(from..).filter(|p| !p.is_empty()));
    parts
}

/// Whether two folded references of one root may name overlapping data: one is a part of the
/// other (`rec` and `rec.p`, `arr` and `arr{2}`), or they differ only where an index is
/// computed at run time (`arr{i}` and `arr{2}`).
fn may_overlap(a: &str, b: &str) -> bool {
    let computed = |p: &str| {
        p.starts_with(['{', '['])
            && !p
                .trim_matches(['{', '}', '[', ']'])
                .bytes()
                .all(|c| c.is_ascii_digit() || c == b',')
    };
    parts_of(a)
        .into_iter()
        .zip(parts_of(b))
        .all(|(x, y)| x == y || (x.starts_with(['{', '[']) && (computed(x) || computed(y))))
}

impl Copies {
    /// What a reference written as `key` (folded) reaches through the copies: every copy into
    /// data it may overlap, added to `targets` and `params`.
    fn reach(&self, key: &str, targets: &mut Vec<TargetAt>, params: &mut Vec<ParamAt>) {
        let Some(all) = self.by_root.get(root_of(key)) else {
            return;
        };
        for c in all.iter().filter(|c| may_overlap(key, &c.key)) {
            targets.extend(&c.targets);
            params.extend(&c.params);
        }
    }

    fn is_empty(&self) -> bool {
        self.by_root.is_empty()
    }
}

/// What the program's copies reach: each source's targets seen from its file, or the
/// parameter of the copy's routine it names, joined with what the copies it reads reach in
/// turn (`pw := pv; pv := p10;`, followed to a fixed point, so the order of the statements
/// does not matter). Copies that reach nothing are dropped: most programs' assignments
/// (`reg1 := reg1 + 1`) then cost their motions nothing.
fn copies_reached(
    files: &[FileFacts<'_>],
    naming: &Naming,
    index: &NameIndex<Indexed>,
    modules: &[usize],
) -> Copies {
    let exported = |(m, i): TargetAt| files.get(m).is_some_and(|f| f.exports(i));
    let mut buf = String::new();
    // (copy, source, what the source reaches itself).
    let mut all: Vec<(String, String, CopyReach)> = Vec::new();
    for (m, f) in files.iter().enumerate() {
        for c in f.copies {
            let source = fold_into(&mut buf, c.source.slice(f.src)).to_owned();
            let mut reach = CopyReach::default();
            let param = c.routine.and_then(|rt| {
                let k = f
                    .routines
                    .get(rt)?
                    .any_named(f.src, root_of(&source).as_bytes())?;
                Some((m, rt, k))
            });
            match param {
                Some(p) => reach.params.push(p),
                None => lookup(
                    naming,
                    index,
                    &exported,
                    (m, modules),
                    &source,
                    &mut reach.targets,
                ),
            }
            let copy = fold_into(&mut buf, c.copy.slice(f.src)).to_owned();
            all.push((copy, source, reach));
        }
    }
    // The copies of each root, so that a source is compared with its own root's only.
    let mut of_root: std::collections::HashMap<String, Vec<usize>> = Default::default();
    for (i, (copy, ..)) in all.iter().enumerate() {
        of_root.entry(root_of(copy).to_owned()).or_default().push(i);
    }
    // Each pass carries what one more copy back reaches; a chain of n copies takes n passes.
    for _ in 0..=all.len() {
        let mut changed = false;
        for i in 0..all.len() {
            let Some((_, source, _)) = all.get(i) else {
                continue;
            };
            let (mut targets, mut params): (Vec<TargetAt>, Vec<ParamAt>) = (Vec::new(), Vec::new());
            for &j in of_root.get(root_of(source)).into_iter().flatten() {
                if let Some((copy, _, r)) = all.get(j)
                    && may_overlap(source, copy)
                {
                    targets.extend(&r.targets);
                    params.extend(&r.params);
                }
            }
            let Some((_, _, r)) = all.get_mut(i) else {
                continue;
            };
            let (nt, np) = (r.targets.len(), r.params.len());
            r.targets.extend(targets);
            r.targets.sort_unstable();
            r.targets.dedup();
            r.params.extend(params);
            r.params.sort_unstable();
            r.params.dedup();
            changed |= r.targets.len() != nt || r.params.len() != np;
        }
        if !changed {
            break;
        }
    }
    let mut out = Copies::default();
    for (copy, _, r) in all {
        if r.targets.is_empty() && r.params.is_empty() {
            continue;
        }
        let same = out.by_root.entry(root_of(&copy).to_owned()).or_default();
        match same.iter_mut().find(|c| c.key == copy) {
            Some(c) => {
                c.targets.extend(r.targets);
                c.params.extend(r.params);
            }
            None => same.push(CopyReach { key: copy, ..r }),
        }
    }
    out
}

/// Where a folded reference in `file` points among `index`'s names, added to `out`
/// (`exported` says whether a target is seen outside its file).
fn lookup(
    naming: &Naming,
    index: &NameIndex<Indexed>,
    exported: &dyn Fn(TargetAt) -> bool,
    (file, modules): (usize, &[usize]),
    key: &str,
    out: &mut Vec<TargetAt>,
) {
    let (named, elements) = match naming.arrays {
        ArrayReach::WhenUndeclared => (index.exact_else_elements(key), &[][..]),
        ArrayReach::WhenIndexComputed => (
            index.exact(key),
            computed_index_array(naming, key).map_or(&[][..], |a| index.elements(a)),
        ),
    };
    keep_seen(exported, (file, modules), named, elements, out);
}

/// [`lookup`] of a reference written as `raw` in `file`'s source, read as it is where its
/// bytes fold one by one (see [`NameIndex::exact_else_elements_raw`]), else [`fold`]ed into
/// `buf`.
fn lookup_raw(
    naming: &Naming,
    index: &NameIndex<Indexed>,
    exported: &dyn Fn(TargetAt) -> bool,
    (file, modules): (usize, &[usize]),
    raw: &[u8],
    buf: &mut String,
    out: &mut Vec<TargetAt>,
) {
    if naming.arrays == ArrayReach::WhenUndeclared
        && let Some(named) = index.exact_else_elements_raw(raw)
    {
        return keep_seen(exported, (file, modules), named, &[], out);
    }
    lookup(
        naming,
        index,
        exported,
        (file, modules),
        fold_into(buf, raw),
        out,
    );
}

/// The declarations found, `named` then `elements`, that `file` sees, added to `out`.
/// `modules` gives each file's module (files of one module see each other's declarations as
/// their own: a KRL `.src` and its `.dat`); a file past its end is a module of its own.
fn keep_seen(
    exported: &dyn Fn(TargetAt) -> bool,
    (file, modules): (usize, &[usize]),
    named: &[Indexed],
    elements: &[Indexed],
    out: &mut Vec<TargetAt>,
) {
    let module = |f: usize| modules.get(f).copied().unwrap_or(f);
    let own_module = module(file);
    let own = |h: TargetAt| h.0 == file || module(h.0) == own_module;
    // Nearly every reference names one declaration: seen if it is the module's own, else if
    // exported (what the general filter below keeps of one hit).
    if let ([(hm, hi)], []) = (named, elements) {
        let h = (*hm as usize, *hi as usize);
        if own(h) || exported(h) {
            out.push(h);
        }
        return;
    }
    let hits = named
        .iter()
        .chain(elements)
        .map(|&(m, i)| (m as usize, i as usize));
    let any_own = hits.clone().any(own);
    out.extend(hits.filter(|&h| if any_own { own(h) } else { exported(h) }));
}

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
    /// The value is written out (`wArr{2} := [FALSE, …];`, `w.uframe.trans.x := 5;`): the
    /// program gives the name another value, which it does not compute.
    pub(crate) literal: bool,
}

/// The parameters of its routine a use names as its frame and tool.
#[derive(Clone, Debug, Default)]
pub(crate) struct PassedFrames {
    /// The frame parameter, as written.
    pub(crate) frame: Option<String>,
    /// The tool parameter, as written.
    pub(crate) tool: Option<String>,
}

/// A use that may run while its work object or tool holds its declared value, the program
/// giving the frame another (see [`TwoValues`](crate::position::TwoValues)): each line as
/// (file, line).
#[derive(Clone, Debug)]
pub(crate) struct TwoValuesAt {
    /// A work object's or a tool's.
    pub(crate) kind: crate::position::FrameKind,
    /// The frame's name as declared.
    pub(crate) frame: String,
    pub(crate) declared: (usize, usize),
    /// The (first) assignment of the other value.
    pub(crate) given: (usize, usize),
    /// The use.
    pub(crate) motion: (usize, usize),
}

/// What a use gives the targets it reaches: the frame and tool it moves with.
#[derive(Clone, Debug)]
struct MovesWith {
    /// The file the use is in.
    from: usize,
    frame: Option<FrameName>,
    tool: Option<FrameName>,
    stationary: bool,
    run_time: Option<RunTimeValue>,
    passed: Option<std::sync::Arc<PassedFrames>>,
    two_values: Option<std::sync::Arc<[TwoValuesAt]>>,
}

impl MovesWith {
    fn of(from: usize, u: &Use<'_>) -> MovesWith {
        MovesWith {
            from,
            frame: u.frame.clone(),
            tool: u.tool.clone(),
            stationary: u.stationary,
            run_time: u.run_time.clone(),
            passed: u.passed.clone(),
            two_values: u.two_values.clone(),
        }
    }
}

/// What one use records in each target it reaches, borrowed from the use.
struct Recorded<'u> {
    frame: Option<&'u FrameName>,
    tool: Option<&'u FrameName>,
    stationary: bool,
    run_time: Option<&'u RunTimeValue>,
    passed: Option<&'u PassedFrames>,
    two_values: Option<&'u [TwoValuesAt]>,
    /// 1-based line of the use.
    line: usize,
}

/// Records use `u`, in file `from`, in target `at`; the run-time value's line is named with
/// file `from` when the target is another file's.
fn record(files: &mut [FileFacts<'_>], from: usize, (m, i): TargetAt, u: &Recorded<'_>) {
    let elsewhere = match (u.run_time, u.passed) {
        (None, None) => None,
        _ if from != m => files.get(from).map(|f| f.name.clone()),
        _ => None,
    };
    // Each line of the other value's finding, named with its file when not the target's.
    // (Rare: most uses have none, and pass here once for every target they reach.)
    if let Some(list) = u.two_values {
        let at = |(file, line): (usize, usize)| UseLine {
            line,
            file: (file != m)
                .then(|| files.get(file).map(|f| f.name.clone()))
                .flatten(),
        };
        let value = |t: &TwoValuesAt| crate::position::TwoValues {
            kind: t.kind,
            frame: t.frame.clone(),
            declared: at(t.declared),
            given: at(t.given),
            motion: at(t.motion),
        };
        let values: Vec<crate::position::TwoValues> = list.iter().map(value).collect();
        if let Some(usage) = files.get_mut(m).and_then(|f| f.positions.usage_mut(i)) {
            for t in values {
                usage.mark_two_values(t);
            }
        }
    }
    if let Some(usage) = files.get_mut(m).and_then(|f| f.positions.usage_mut(i)) {
        usage.record_shared(u.frame, u.tool, u.stationary, u.line);
        if let Some(passed) = u.passed {
            let why = |name: &String| crate::position::UnresolvedFrame {
                at: UseLine {
                    line: u.line,
                    file: elsewhere.clone(),
                },
                cause: crate::position::UnresolvedCause::Parameter(name.clone()),
            };
            if let Some(w) = &passed.frame {
                usage.mark_unresolved_frame(why(w));
            }
            if let Some(t) = &passed.tool {
                usage.mark_unresolved_tool(why(t));
            }
        }
        if let Some(why) = u.run_time {
            let mut why = why.clone();
            if elsewhere.is_some() {
                why.at_mut().file = elsewhere;
            }
            usage.set_run_time(why);
        }
    }
}

/// Binds the uses of a program (its files in `files`) to the targets they reach and records
/// their [`Usage`](crate::position::Usage), one use at a time ([`Binder::bind`]), so a
/// language that finds its uses in order need not keep them; [`Binder::finish`] then follows
/// the targets passed to routine parameters.
///
/// A reference is looked up as the [`Naming`] says; an argument bound to a required parameter
/// of a routine of the program makes the target used as that routine uses the parameter
/// (directly, through a reference, or passed on to another routine: followed [`CALL_DEPTH`]
/// calls deep, cycles cut). A routine is found among the file's own first, else among the
/// other files' that are not local.
pub(crate) struct Binder<'f, 'a> {
    files: &'f mut [FileFacts<'a>],
    /// Each file's [`FileFacts::module`].
    modules: Vec<usize>,
    naming: Naming,
    index: NameIndex<Indexed>,
    param_uses: std::collections::HashMap<ParamAt, Vec<MovesWith>>,
    param_edges: std::collections::HashMap<ParamAt, Vec<ParamAt>>,
    bindings: Vec<(TargetAt, ParamAt, usize)>,
    buf: String,
    targets: Vec<TargetAt>,
    params: Vec<ParamAt>,
    hits: Vec<TargetAt>,
    /// The routines of each name: (file, index, local), in file order and each file's order.
    /// A call's routine was found by scanning every routine of the program, per call:
    /// quadratic in a task of many routines calling each other (3,000 routines: 4 G
    /// instructions). Only names some routine of which takes parameters are kept: a call of
    /// any other binds no argument to a parameter, as a call of no routine of the program,
    /// so a program whose routines take no targets (most) looks no callee up.
    routines: NameMap<NameKey<'a>, Vec<(usize, usize, bool)>>,
    /// The first letters of the targets' names: a reference starting with none of them is
    /// not looked up.
    first_letters: FirstLetters,
    /// The callee last looked up (file, name as written) and what it found: a module's motions
    /// call the same instruction one after another.
    last_callee: Option<LastCallee<'a>>,
    /// What the program's copies reach ([`FileFacts::copies`], [`copies_reached`]); a
    /// reference to data a copy may have written reaches these too. Empty in nearly every
    /// program: then no reference is looked up in it.
    copies: Copies,
    /// While collecting ([`Binder::collect_reached`]), the targets and routine parameters the
    /// uses bound since reached directly.
    collected: Option<Reached>,
}

/// What uses reached directly: targets (file, index) and parameters of their routines (file,
/// routine, index).
pub(crate) type Reached = (Vec<TargetAt>, Vec<ParamAt>);

/// A callee's name as written in a file, and the routine it names there (file, index), if any.
type LastCallee<'a> = (usize, &'a [u8], Option<(usize, usize)>);

impl<'f, 'a> Binder<'f, 'a> {
    /// A binder over the targets of `files` (indexed once).
    pub(crate) fn new(files: &'f mut [FileFacts<'a>], naming: &Naming) -> Binder<'f, 'a> {
        let total: usize = files.iter().map(|f| f.positions.len()).sum();
        let mut index = NameIndex::builder(naming.open, total);
        let mut first_letters = FirstLetters::new();
        for (m, f) in files.iter().enumerate() {
            for i in 0..f.positions.len() {
                if let (Some(n), Some(at)) = (f.positions.name_bytes(i), indexed((m, i))) {
                    index.insert_utf8(n, at);
                    first_letters.insert_utf8(n);
                }
            }
        }
        let index = index.build();
        let mut routines: NameMap<NameKey<'a>, Vec<(usize, usize, bool)>> = NameMap::default();
        for (m, f) in files.iter().enumerate() {
            for (r, routine) in f.routines.iter().enumerate() {
                routines
                    .entry(NameKey(routine.name.slice(f.src)))
                    .or_default()
                    .push((m, r, routine.local));
            }
        }
        routines.retain(|_, all| {
            all.iter().any(|&(m, r, _)| {
                files
                    .get(m)
                    .and_then(|f| f.routines.get(r))
                    .is_some_and(|r| !r.params.is_empty() || !r.optional.is_empty())
            })
        });
        let modules: Vec<usize> = files.iter().map(|f| f.module).collect();
        let copies = copies_reached(files, naming, &index, &modules);
        Binder {
            files,
            modules,
            naming: *naming,
            index,
            param_uses: Default::default(),
            param_edges: Default::default(),
            bindings: Vec::new(),
            buf: String::new(),
            targets: Vec::new(),
            params: Vec::new(),
            hits: Vec::new(),
            routines,
            first_letters,
            last_callee: None,
            copies,
            collected: None,
        }
    }

    /// The targets of file `file`, as the binder sees them, and the source they point into.
    pub(crate) fn positions(&self, file: usize) -> Option<(&crate::position::PositionList, &[u8])> {
        self.files.get(file).map(|f| (&*f.positions, f.src))
    }

    /// Binds use `u` of file `m`: records it in every target it reaches now, and keeps what it
    /// passes to routine parameters for [`Binder::finish`]. [`Binder::reached_cartesian`]
    /// then says whether it reached a Cartesian target directly.
    pub(crate) fn bind(&mut self, m: usize, u: &Use<'_>) {
        let Binder {
            files,
            modules,
            naming,
            index,
            param_uses,
            param_edges,
            bindings,
            buf,
            targets,
            params,
            hits,
            routines,
            first_letters,
            last_callee,
            copies,
            collected,
        } = self;
        let naming = &*naming;
        targets.clear();
        params.clear();
        targets.extend(u.targets.iter().map(|&i| (m, i)));
        {
            let files: &[FileFacts<'a>] = files;
            let Some(f) = files.get(m) else {
                return;
            };
            let src = f.src;
            let exported = |(m, i): TargetAt| files.get(m).is_some_and(|f| f.exports(i));
            // Routines by name: the file's own first, else those of the program that are not
            // local (the first file that has one).
            let routine_of = |name: NameKey<'a>| -> Option<(usize, usize)> {
                let all = routines.get(&name)?;
                all.iter()
                    .find(|&&(m2, ..)| m2 == m)
                    .or_else(|| all.iter().find(|&&(m2, _, local)| m2 != m && !local))
                    .map(|&(m2, r, _)| (m2, r))
            };
            // The parameter of the enclosing routine a reference names, if any (an optional
            // one numbered after the required ones).
            let own = u.routine.and_then(|rt| f.routines.get(rt));
            let own_params = own.map_or(&[][..], |r| &r.params);
            let own_optional = own.map_or(&[][..], |r| &r.optional);
            let param_of = |key: &str| -> Option<ParamAt> {
                // Most routines take no target: nothing to look for.
                if own_params.is_empty() && own_optional.is_empty() {
                    return None;
                }
                let rt = u.routine?;
                let base = index.array_of(key).unwrap_or(key);
                own_params
                    .iter()
                    .chain(own_optional)
                    .position(|&name| NameKey(name.slice(src)) == NameKey(base.as_bytes()))
                    .map(|k| (m, rt, k))
            };
            let reach =
                |key: &str, targets: &mut Vec<TargetAt>, params: &mut Vec<ParamAt>| match param_of(
                    key,
                ) {
                    Some(p) => params.push(p),
                    None => lookup(naming, index, &exported, (m, modules), key, targets),
                };
            // `reach` of a reference written as `raw` in the file, looked up only when it
            // may reach something: a parameter, or a target whose name starts as it does.
            let reach_raw = |raw: &'a [u8],
                             buf: &mut String,
                             targets: &mut Vec<TargetAt>,
                             params: &mut Vec<ParamAt>| {
                if !(own_params.is_empty() && own_optional.is_empty())
                    && let Some(p) = param_of(fold_into(buf, raw))
                {
                    params.push(p);
                    return;
                }
                if first_letters.may_start(raw) {
                    lookup_raw(naming, index, &exported, (m, modules), raw, buf, targets);
                }
            };
            let callee = u.callee.filter(|_| !routines.is_empty()).and_then(|c| {
                let name = c.slice(src);
                match *last_callee {
                    Some((lm, last, found)) if lm == m && last == name => found,
                    _ => {
                        let found = routine_of(NameKey(name));
                        *last_callee = Some((m, name, found));
                        found
                    }
                }
            });
            for (i, sp) in u.args.iter().enumerate() {
                let Some(sp) = *sp else { continue };
                let raw = sp.span().slice(src);
                match callee {
                    // An argument bound to a parameter of a routine of the program: used as
                    // that routine uses the parameter.
                    Some((cm, cr))
                        if files
                            .get(cm)
                            .and_then(|c| c.routines.get(cr))
                            .is_some_and(|r| i < r.params.len()) =>
                    {
                        let to = (cm, cr, i);
                        let key = fold_into(buf, raw);
                        match param_of(key) {
                            Some(p) => param_edges.entry(p).or_default().push(to),
                            None => {
                                hits.clear();
                                lookup(naming, index, &exported, (m, modules), key, hits);
                                // A RAPID component passed (`bump pp.trans.z;`): what the
                                // routine does with it, it does to the target.
                                if hits.is_empty()
                                    && naming.arrays == ArrayReach::WhenUndeclared
                                    && let Some((whole, _)) = key.split_once('.')
                                {
                                    lookup(naming, index, &exported, (m, modules), whole, hits);
                                }
                                bindings.extend(hits.iter().map(|&t| (t, to, u.line)));
                            }
                        }
                    }
                    // What `reach_raw` would find nothing for (a motion's speed, zone and
                    // tool), told before calling it: the closure is not inlined, and the call
                    // per argument was 0.65 M of `check`'s 95 M.
                    _ if own_params.is_empty()
                        && own_optional.is_empty()
                        && !first_letters.may_start(raw) => {}
                    _ => reach_raw(raw, buf, targets, params),
                }
            }
            for &sp in u.refs {
                reach_raw(sp.slice(src), buf, targets, params);
            }
            for &key in u.folded {
                reach(key, targets, params);
            }
            if !copies.is_empty() && !u.writes {
                let written = u
                    .args
                    .iter()
                    .flatten()
                    .map(|a| a.span())
                    .chain(u.refs.iter().copied());
                for sp in written {
                    copies.reach(fold_into(buf, sp.slice(src)), targets, params);
                }
                for &key in u.folded {
                    copies.reach(key, targets, params);
                }
            }
        }
        if targets.is_empty() && params.is_empty() {
            return;
        }
        targets.sort_unstable();
        targets.dedup();
        if let Some((t, p)) = collected {
            t.extend_from_slice(targets);
            p.extend_from_slice(params);
        }
        let recorded = Recorded {
            frame: u.frame.as_ref(),
            tool: u.tool.as_ref(),
            stationary: u.stationary,
            run_time: u.run_time.as_ref(),
            passed: u.passed.as_deref(),
            two_values: u.two_values.as_deref(),
            line: u.line,
        };
        for &t in targets.iter() {
            record(files, m, t, &recorded);
        }
        for &p in params.iter() {
            param_uses.entry(p).or_default().push(MovesWith::of(m, u));
        }
    }

    /// The targets a reference written as `raw` in file `m` names, as a motion of that file
    /// reaches them (its module's own, else those other modules see; every element of an
    /// array indexed by a computed value; what a copy of that name copies), added to `out`.
    /// A routine's parameter of that name is the caller's to look past.
    pub(crate) fn targets_named(&mut self, m: usize, raw: &[u8], out: &mut Vec<TargetAt>) {
        let Binder {
            files,
            modules,
            naming,
            index,
            buf,
            copies,
            ..
        } = self;
        let files: &[FileFacts<'a>] = files;
        let exported = |(m, i): TargetAt| files.get(m).is_some_and(|f| f.exports(i));
        lookup_raw(naming, index, &exported, (m, modules), raw, buf, out);
        // A copy (`pv := p10;`, a function's `RETURN p10;`) reaches what it copies; one of a
        // parameter, what the calls pass there.
        let mut params = Vec::new();
        if !copies.is_empty() {
            copies.reach(fold_into(buf, raw), out, &mut params);
        }
        for p in params {
            self.targets_bound_to(p, out);
        }
    }

    /// Applies `mark` to the usage of each of `targets`, with the name of file `from` when the
    /// target is another file's.
    pub(crate) fn mark(
        &mut self,
        from: usize,
        targets: &[TargetAt],
        mut mark: impl FnMut(Option<&std::sync::Arc<str>>, &mut crate::position::Usage),
    ) {
        let from_name = self.files.get(from).map(|f| f.name.clone());
        for &(m, i) in targets {
            if let Some(u) = self.files.get_mut(m).and_then(|f| f.positions.usage_mut(i)) {
                mark(from_name.as_ref().filter(|_| m != from), u);
            }
        }
    }

    /// The targets the calls bound so far pass to parameter `k` of routine `routine` of file
    /// `m`: directly, or through a parameter of the caller passed on (followed [`CALL_DEPTH`]
    /// calls back), added to `out`. What a reference to the parameter inside the routine may
    /// stand for.
    pub(crate) fn targets_bound_to(&self, (m, routine, k): ParamAt, out: &mut Vec<TargetAt>) {
        let mut params: Vec<ParamAt> = vec![(m, routine, k)];
        let mut from = 0;
        for _ in 0..CALL_DEPTH {
            let next: Vec<ParamAt> = self
                .param_edges
                .iter()
                .filter(|(p, tos)| {
                    !params.contains(p)
                        && tos
                            .iter()
                            .any(|t| params.get(from..).is_some_and(|new| new.contains(t)))
                })
                .map(|(&p, _)| p)
                .collect();
            if next.is_empty() {
                break;
            }
            from = params.len();
            params.extend(next);
        }
        out.extend(
            self.bindings
                .iter()
                .filter(|(_, to, _)| params.contains(to))
                .map(|&(t, ..)| t),
        );
        out.sort_unstable();
        out.dedup();
    }

    /// Binds argument `a` of a call in file `m` that positional binding does not see
    /// ([`PassedArg`]) to the parameter of the routine called that it is given to: each
    /// target its names reach (directly or through copies) is used as the routine uses the
    /// parameter, and a parameter of the caller passed on, a copy of one, is followed there.
    pub(crate) fn bind_passed(&mut self, m: usize, a: &PassedArg, names: &[Span]) {
        let Some(f) = self.files.get(m) else { return };
        let src = f.src;
        let routine_of = |name: NameKey<'_>| -> Option<(usize, usize)> {
            let all = self.routines.get(&name)?;
            all.iter()
                .find(|&&(m2, ..)| m2 == m)
                .or_else(|| all.iter().find(|&&(m2, _, local)| m2 != m && !local))
                .map(|&(m2, r, _)| (m2, r))
        };
        let Some((cm, cr)) = routine_of(NameKey(a.callee.slice(src))) else {
            return;
        };
        let Some(callee) = self.files.get(cm).and_then(|c| c.routines.get(cr)) else {
            return;
        };
        let k = match a.param {
            PassedTo::Position(i) => Some(i).filter(|&i| i < callee.params.len()),
            PassedTo::Named(label) => self
                .files
                .get(cm)
                .and_then(|c| callee.any_named(c.src, label.slice(src))),
        };
        let Some(k) = k else { return };
        let to = (cm, cr, k);
        let own = a.routine.and_then(|rt| f.routines.get(rt).map(|r| (rt, r)));
        let (mut targets, mut params) = (Vec::new(), Vec::new());
        for sp in names {
            let raw = sp.slice(src);
            let base = raw.split(|&b| b == b'{' || b == b'.').next().unwrap_or(raw);
            if let Some((rt, r)) = own
                && let Some(p) = r.any_named(src, base)
            {
                params.push((m, rt, p));
                continue;
            }
            let files: &[FileFacts<'a>] = self.files;
            let exported = |(m, i): TargetAt| files.get(m).is_some_and(|f| f.exports(i));
            let key = fold_into(&mut self.buf, raw);
            lookup(
                &self.naming,
                &self.index,
                &exported,
                (m, &self.modules),
                key,
                &mut targets,
            );
            self.copies.reach(key, &mut targets, &mut params);
        }
        for p in params {
            self.param_edges.entry(p).or_default().push(to);
        }
        self.bindings
            .extend(targets.into_iter().map(|t| (t, to, a.line)));
    }

    /// Binds a computed value given to parameter `param` (its name in file `m`'s source) of
    /// routine `routine` on `line` (RAPID `pOut := CRobT();`, KRL `pOut = $POS_ACT`): a use of
    /// the parameter with that value, which [`Binder::finish`] hands on to the targets the
    /// routine's calls pass there.
    pub(crate) fn bind_computed_parameter(
        &mut self,
        m: usize,
        routine: usize,
        param: crate::syntax::Span32,
        line: usize,
    ) {
        self.bind(
            m,
            &Use {
                line,
                routine: Some(routine),
                run_time: Some(RunTimeValue::Target {
                    at: UseLine::new(line),
                }),
                args: &[Some(param)],
                ..Default::default()
            },
        );
    }

    /// Whether the use last bound reached a Cartesian target directly (a joint target moves
    /// the same whatever the frame). Asked only by a language that warns about it: reading
    /// each target's fields for the answer was a tenth of binding a RAPID motion.
    pub(crate) fn reached_cartesian(&self) -> bool {
        self.targets.iter().any(|&(m, i)| {
            self.files
                .get(m)
                .is_some_and(|f| f.positions.has_cartesian(i))
        })
    }

    /// Collects, until [`Binder::collected`], the targets and routine parameters every use
    /// bound reaches directly (a statement may be bound as several uses).
    pub(crate) fn collect_reached(&mut self) {
        self.collected = Some(Default::default());
    }

    /// What the uses bound since [`Binder::collect_reached`] reached directly: targets
    /// (file, index) and parameters of their routines (file, routine, index); collecting ends.
    pub(crate) fn collected(&mut self) -> Reached {
        self.collected.take().unwrap_or_default()
    }

    /// The targets the use last bound reached directly: (file, index).
    pub(crate) fn reached(&self) -> &[TargetAt] {
        &self.targets
    }

    /// Applies `mark` to the usage of every target the use last bound (in file `from`) reached
    /// directly, with the name of file `from` when the target is another file's.
    pub(crate) fn mark_reached(
        &mut self,
        from: usize,
        mark: impl FnMut(Option<&std::sync::Arc<str>>, &mut crate::position::Usage),
    ) {
        let targets = std::mem::take(&mut self.targets);
        self.mark(from, &targets, mark);
        self.targets = targets;
    }

    /// Records, in every target passed to a routine parameter, every use reachable from that
    /// parameter, with the line of the call that passes the target.
    pub(crate) fn finish(self) {
        let Binder {
            files,
            param_uses,
            param_edges,
            bindings,
            ..
        } = self;
        for (t, to, line) in bindings {
            for w in uses_through_parameters(to, &param_uses, &param_edges) {
                let recorded = Recorded {
                    frame: w.frame.as_ref(),
                    tool: w.tool.as_ref(),
                    stationary: w.stationary,
                    run_time: w.run_time.as_ref(),
                    passed: w.passed.as_deref(),
                    two_values: w.two_values.as_deref(),
                    line,
                };
                record(files, w.from, t, &recorded);
            }
        }
    }
}

/// Marks [`Usage::run_time`](crate::position::Usage) of every target of the program (its
/// files in `files`) whose pose is only known at run time: a target the program assigns a
/// computed value, then a target a motion uses with a work object or base the program
/// assigns one. An assignment reaches a declaration of its name, else every element of the
/// array it names or indexes, the file's own declarations first (whether exported or not: the
/// assignment changes the data wherever it is declared), in `naming`'s array brackets.
pub(crate) fn mark_run_time(files: &mut [FileFacts<'_>], naming: &Naming) {
    if files.iter().all(|f| f.assignments.is_empty()) {
        return;
    }
    let naming = Naming {
        arrays: ArrayReach::WhenUndeclared,
        ..*naming
    };
    let seen = |_: TargetAt| true;
    let modules: Vec<usize> = files.iter().map(|f| f.module).collect();
    let mut hits = Vec::new();
    let mut targets = NameIndex::builder(naming.open, 0);
    let mut frames = NameIndex::builder(naming.open, 0);
    for (fi, f) in files.iter().enumerate() {
        for i in 0..f.positions.len() {
            if let (Some(n), Some(at)) = (f.positions.name_bytes(i), indexed((fi, i))) {
                targets.insert_utf8(n, at);
            }
        }
        for (i, d) in f.frames.iter().enumerate() {
            if let Some(at) = indexed((fi, i)) {
                frames.insert(&d.name, at);
            }
        }
    }
    let (targets, frames): (NameIndex<Indexed>, NameIndex<Indexed>) =
        (targets.build(), frames.build());
    // (target's file, its index, the assignment's line and file).
    let mut assigned_targets = Vec::new();
    // Folded frame name → (name as declared, line and file of the first assignment, whether
    // that assignment writes its value out).
    let mut assigned_frames: crate::names::NameMap<String, (String, usize, usize, bool)> =
        Default::default();
    for (fi, f) in files.iter().enumerate() {
        for a in f.assignments {
            let key = fold(&a.name);
            hits.clear();
            lookup(&naming, &targets, &seen, (fi, &modules), &key, &mut hits);
            assigned_targets.extend(hits.iter().map(|&(tf, ti)| (tf, ti, a.line, fi)));
            hits.clear();
            lookup(&naming, &frames, &seen, (fi, &modules), &key, &mut hits);
            for &(df, di) in &hits {
                if let Some(d) = files.get(df).and_then(|f| f.frames.get(di)) {
                    assigned_frames
                        .entry(fold(&d.name))
                        .or_insert_with(|| (d.name.clone(), a.line, fi, a.literal));
                }
            }
        }
    }
    let names: Vec<std::sync::Arc<str>> = files.iter().map(|f| f.name.clone()).collect();
    let at = |line: usize, from: usize, target: usize| match names.get(from) {
        Some(name) => UseLine::of(line, from, target, name),
        None => UseLine::new(line),
    };
    for (tf, ti, line, fi) in assigned_targets {
        if let Some(usage) = files.get_mut(tf).and_then(|f| f.positions.usage_mut(ti)) {
            usage.set_run_time(RunTimeValue::Target {
                at: at(line, fi, tf),
            });
        }
    }
    if assigned_frames.is_empty() {
        return;
    }
    for (tf, f) in files.iter_mut().enumerate() {
        for usage in f.positions.usages_mut() {
            // The tool too: the joints a target is reached with, and so its reach and
            // configuration, depend on it.
            let frame = usage
                .work_objects()
                .chain(usage.tools())
                .find_map(|w| assigned_frames.get(&fold(w)));
            if let Some((name, line, fi, literal)) = frame {
                let (name, at) = (name.clone(), at(*line, *fi, tf));
                usage.set_run_time(if *literal {
                    RunTimeValue::FrameAssigned { name, at }
                } else {
                    RunTimeValue::Frame {
                        name: Some(name),
                        at,
                    }
                });
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

    #[test]
    fn each_naming_reaches_arrays_and_other_files_as_its_language_does() {
        // File 0 declares `P{1}`, `P{2}` (RAPID) / `P[1]`, `P[2]` (KRL) and `X`; file 1 declares
        // `X` and `Y`; file 2 (the one looking) declares nothing.
        let index = |open: char| {
            let mut index = NameIndex::builder(open, 0);
            let close = if open == '{' { '}' } else { ']' };
            for (i, n) in [
                format!("p{open}1{close}"),
                format!("p{open}2{close}"),
                "x".into(),
            ]
            .iter()
            .enumerate()
            {
                index.insert(n, (0, i as u32));
            }
            index.insert("x", (1, 0));
            index.insert("y", (1, 1));
            index.build()
        };
        let rapid = Naming {
            open: '{',
            close: '}',
            arrays: ArrayReach::WhenUndeclared,
        };
        let krl = Naming {
            open: '[',
            close: ']',
            arrays: ArrayReach::WhenIndexComputed,
        };
        let reach_in =
            |naming: &Naming, exported: &dyn Fn(TargetAt) -> bool, file, modules: &[usize], key| {
                let mut out = Vec::new();
                lookup(
                    naming,
                    &index(naming.open),
                    exported,
                    (file, modules),
                    key,
                    &mut out,
                );
                out
            };
        // Each file a module of its own (RAPID).
        let reach = |naming: &Naming, exported: &dyn Fn(TargetAt) -> bool, file, key| {
            reach_in(naming, exported, file, &[], key)
        };
        // Files 0 and 1 one module (a KRL `.src` and its `.dat`), file 2 another.
        let pair = [0, 0, 2];
        let all = |_: TargetAt| true;
        let only_y = |t: TargetAt| t == (1, 1);
        // RAPID: the whole array, an element chosen at run time, an undeclared element.
        assert_eq!(reach(&rapid, &all, 0, "P"), [(0, 0), (0, 1)]);
        assert_eq!(reach(&rapid, &all, 0, "P{I}"), [(0, 0), (0, 1)]);
        assert_eq!(reach(&rapid, &all, 0, "P{9}"), [(0, 0), (0, 1)]);
        assert_eq!(reach(&rapid, &all, 0, "P{2}"), [(0, 1)]);
        // The file's own `X` hides file 1's; from file 2, only exported declarations are seen.
        assert_eq!(reach(&rapid, &all, 0, "X"), [(0, 2)]);
        assert_eq!(reach(&rapid, &all, 2, "X"), [(0, 2), (1, 0)]);
        assert_eq!(reach(&rapid, &only_y, 2, "X"), Vec::<TargetAt>::new());
        assert_eq!(reach(&rapid, &only_y, 2, "Y"), [(1, 1)]);
        // KRL: a literal index is that element only, a computed one every element; the whole
        // array is no declaration; both files of the module see each other's `X`, another
        // module only an exported one.
        assert_eq!(
            reach_in(&krl, &all, 0, &pair, "P[9]"),
            Vec::<TargetAt>::new()
        );
        assert_eq!(reach_in(&krl, &all, 0, &pair, "P[I+1]"), [(0, 0), (0, 1)]);
        assert_eq!(reach_in(&krl, &all, 0, &pair, "P"), Vec::<TargetAt>::new());
        assert_eq!(reach_in(&krl, &all, 0, &pair, "X"), [(0, 2), (1, 0)]);
        assert_eq!(reach_in(&krl, &all, 1, &pair, "X"), [(0, 2), (1, 0)]);
        assert_eq!(
            reach_in(&krl, &only_y, 2, &pair, "X"),
            Vec::<TargetAt>::new()
        );
        assert_eq!(reach_in(&krl, &only_y, 2, &pair, "Y"), [(1, 1)]);
    }
}
