//! Targets, frames and offsets of a RAPID module, into the shared position model.
//!
//! The parser hands every statement to [`Extractor`] while the statement's expressions are still
//! in the arena. Declarations give named targets and frames; any expression may hold inline
//! robtarget/jointtarget literals and `Offs`/`RelTool` calls; procedure calls give usage (work
//! object and tool). Usage is resolved at the end, because RAPID lets a routine use data declared
//! further down the module.

use super::expr::{Arena, ExprKind, ExprNode};
use super::parser::{MovedCall, PlainArgs, RobtargetLiteral, Statement, Stmt, Storage};
use crate::names::{NameKey, NameMap, same_bytes};
use crate::position::{
    Axes, CartesianFields, Config, FrameDecl, FrameKind, FrameName, FrameScope, FrameStorage, Name,
    NonPosition, NonPositionRole, NumField, OffsetCall, OffsetKind, Orientation, Position,
    PositionKind, PositionList, ReadAgainTarget, RunTimeValue, UnresolvedCause, Usage, UseLine,
};
use crate::resolve::DeclKind;
use crate::syntax::{Diagnostic, LineCursor, LineIndex, NumLit, Span, Span32, latin1};
use std::sync::Arc;

/// RAPID instructions that take targets as other than positions, and which: by positional
/// argument (switches not counted), with the parameter's name. The world zones take joint
/// targets as a tolerance or as limits (`WZHomeJointDef [\Inside]|[\Outside] Shape
/// MiddleJointVal DeltaJointVal`; `WZLimJointDef [\Inside]|[\Outside] Shape LowJointVal
/// HighJointVal`). The searches `SearchL [\Stop]… Signal [\Flanks]… SearchPoint ToPoint …`
/// (`SearchC`: `… SearchPoint CirPoint ToPoint …`, `SearchExtJ`: `… SearchJointPos
/// ToJointPos …`) write the position where the signal came into the search point, an `INOUT`
/// argument: what the program later moves to there is measured, not taught.
const NON_POSITION_ARGUMENTS: [NonPositionArguments; 5] = [
    ("SearchL", &[(1, "SearchPoint", NonPositionRole::Found)]),
    ("SearchC", &[(1, "SearchPoint", NonPositionRole::Found)]),
    (
        "SearchExtJ",
        &[(1, "SearchJointPos", NonPositionRole::Found)],
    ),
    (
        "WZHomeJointDef",
        &[(2, "DeltaJointVal", NonPositionRole::Tolerance)],
    ),
    (
        "WZLimJointDef",
        &[
            (1, "LowJointVal", NonPositionRole::Limit),
            (2, "HighJointVal", NonPositionRole::Limit),
        ],
    ),
];

/// An instruction and its arguments that are not positions.
type NonPositionArguments = (
    &'static str,
    &'static [(usize, &'static str, NonPositionRole)],
);

/// The instruction `callee` names, if it is one of [`NON_POSITION_ARGUMENTS`] (names compared
/// without case). Asked of every call: one compare of its first two letters answers most.
fn non_position_arguments(callee: &[u8]) -> Option<NonPositionArguments> {
    let two = callee.get(..2)?;
    if !two.eq_ignore_ascii_case(b"wz") && !two.eq_ignore_ascii_case(b"se") {
        return None;
    }
    NON_POSITION_ARGUMENTS
        .into_iter()
        .find(|(name, _)| callee.eq_ignore_ascii_case(name.as_bytes()))
}

/// Binds `call` of module `m`, one of [`NON_POSITION_ARGUMENTS`]: its arguments that are no positions
/// apart, each target they reach marked as its [`NonPosition`], the rest as any call's.
fn bind_non_positions(
    binder: &mut crate::resolve::Binder<'_, '_>,
    m: usize,
    call: &crate::resolve::Use<'_>,
    (instruction, arguments): NonPositionArguments,
) {
    let mut rest = call.args.to_vec();
    for &(k, ..) in arguments {
        if let Some(a) = rest.get_mut(k) {
            *a = None;
        }
    }
    binder.bind(
        m,
        &crate::resolve::Use {
            args: &rest,
            ..call.clone()
        },
    );
    for &(k, parameter, role) in arguments {
        let Some(arg) = call.args.get(k).copied().flatten() else {
            continue;
        };
        // Not bound to a routine's parameter: the instruction is the controller's.
        binder.bind(
            m,
            &crate::resolve::Use {
                callee: None,
                args: &[Some(arg)],
                refs: &[],
                targets: &[],
                writes: role == NonPositionRole::Found,
                ..call.clone()
            },
        );
        binder.mark_reached(m, |elsewhere, usage| {
            usage.set_non_position(NonPosition {
                instruction,
                parameter,
                role,
                at: UseLine {
                    line: call.line,
                    file: elsewhere.cloned(),
                },
            });
        });
    }
}

/// RAPID's instructions that move the motions after them by a value the program gives when it
/// runs: the external axes' offset (`EOffsSet eax_offset;`, `EOffsOn \ExeP:=p, p;`, ended by
/// `EOffsOff`) and the program displacement (`PDispSet disp_frame;`, `PDispOn \ExeP:=p, p,
/// tool;`, ended by `PDispOff`).
const DISPLACING: [(&str, Displacement); 4] = [
    ("EOffsSet", Displacement::Axes),
    ("EOffsOn", Displacement::Axes),
    ("PDispSet", Displacement::Program),
    ("PDispOn", Displacement::Program),
];
/// The instructions that end what a [`DISPLACING`] one activates.
const ENDING: [(&str, Displacement); 2] = [
    ("EOffsOff", Displacement::Axes),
    ("PDispOff", Displacement::Program),
];

/// What a [`DISPLACING`] instruction moves.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Displacement {
    /// The external axes: the track stands at the written position plus the offset.
    Axes,
    /// The program: every Cartesian motion is reached in the work object displaced.
    Program,
}

impl Displacement {
    /// Whether the instruction's argument (the statement's text after its name) is a literal
    /// that moves nothing: an axes offset of 0 (or 9E9, an axis not there) for every axis, a
    /// displacement of `[[0,0,0],[1,0,0,0]]`.
    fn moves_nothing(self, args: &[u8]) -> bool {
        let text = crate::syntax::latin1(args);
        let values: Option<Vec<f64>> = text
            .trim()
            .split(',')
            .map(|v| v.trim_matches(|c: char| c == '[' || c == ']' || c.is_whitespace()))
            .map(|v| v.parse::<f64>().ok())
            .collect();
        let Some(values) = values else {
            return false;
        };
        match self {
            Displacement::Axes => {
                values.len() == 6
                    && values
                        .iter()
                        .all(|&x| x == 0.0 || x >= crate::position::NOT_CONNECTED)
            }
            Displacement::Program => values == [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
        }
    }

    fn why(self, instruction: &'static str, at: UseLine) -> RunTimeValue {
        match self {
            Displacement::Axes => RunTimeValue::AxesOffset { instruction, at },
            Displacement::Program => RunTimeValue::ProgramDisplacement { instruction, at },
        }
    }

    /// Whether a motion written as `name` (its text after the name `args`) ignores the
    /// displacement: every `MoveAbsJ` the program displacement, a `MoveAbsJ …\NoEOffs` the
    /// axes offset.
    fn ignored_by(self, name: &[u8], args: impl FnOnce() -> bool) -> bool {
        name.eq_ignore_ascii_case(b"MoveAbsJ")
            && match self {
                Displacement::Program => true,
                Displacement::Axes => args(),
            }
    }
}

/// The [`DISPLACING`] or [`ENDING`] instruction a call names (`name`, its name in `src`): its
/// name as RAPID spells it, what it displaces, and whether it displaces (rather than ends).
#[inline]
fn displacing_call(src: &[u8], name: Span) -> Option<(&'static str, Displacement, bool)> {
    // Most calls are motions (`MoveL`): told apart by their length and first letter, before
    // their name is read.
    if !matches!(name.end.wrapping_sub(name.start), 7 | 8)
        || !matches!(src.get(name.start), Some(b'P' | b'p' | b'E' | b'e'))
    {
        return None;
    }
    let name = name.slice(src);
    let found = |list: &[(&'static str, Displacement)], sets: bool| {
        list.iter()
            .find(|(n, _)| name.eq_ignore_ascii_case(n.as_bytes()))
            .map(|&(n, what)| (n, what, sets))
    };
    found(&DISPLACING, true).or_else(|| found(&ENDING, false))
}

/// A call of the task that activates or ends a displacement.
struct Displacing {
    what: Displacement,
    name: &'static str,
    /// Its module, and the first byte of its name there.
    at: (usize, usize),
    line: usize,
    /// It activates a displacement that moves something: not an [`ENDING`] instruction, nor
    /// a literal that moves nothing (which ends any displacement active before it, as one of
    /// its kind).
    moves: bool,
}

/// The calls of the task that activate or end a displacement, in task order.
fn displacing(calls: &[Calls], rest: &[Kept<'_>]) -> Vec<Displacing> {
    let mut out = Vec::new();
    for (m, (module_calls, r)) in calls.iter().zip(rest).enumerate() {
        let src = r.6;
        for u in &module_calls.uses {
            let name = u.name.span();
            let Some((instruction, what, sets)) = displacing_call(src, name) else {
                continue;
            };
            out.push(Displacing {
                what,
                name: instruction,
                at: (m, name.start),
                line: u.line as usize,
                moves: sets && !what.moves_nothing(statement_text(src, name.end)),
            });
        }
    }
    out
}

/// The calls of the task that may run while a displacement is active (docs/design.md,
/// "Program displacement and axes offset"), by (module, first byte of the callee's name): for
/// each kind displaced, the instruction (an index into `instructions`) whose displacement may
/// be active there. A call that ignores a kind (a `MoveAbsJ`) is not displaced by it; one that
/// activates a displacement is, by itself (its targets give the displacement's value).
fn displaced_calls(
    instructions: &[Displacing],
    calls: &[Calls],
    rest: &[Kept<'_>],
    task: &super::flow::Task<'_>,
) -> std::collections::HashMap<(usize, usize), Vec<usize>> {
    let mut out: std::collections::HashMap<(usize, usize), Vec<usize>> = Default::default();
    // The kinds in the order their first displacement is written: a target both move is
    // named with the first.
    let mut kinds: Vec<Displacement> = Vec::new();
    for d in instructions.iter().filter(|d| d.moves) {
        if !kinds.contains(&d.what) {
            kinds.push(d.what);
        }
    }
    for what in kinds {
        let of_kind = || {
            instructions
                .iter()
                .enumerate()
                .filter(|(_, d)| d.what == what)
        };
        let sets: Vec<usize> = of_kind().filter(|(_, d)| d.moves).map(|(i, _)| i).collect();
        let at = |list: &[usize]| -> Vec<(usize, usize)> {
            list.iter()
                .filter_map(|&i| instructions.get(i))
                .map(|d| d.at)
                .collect()
        };
        let clears: Vec<usize> = of_kind()
            .filter(|(_, d)| !d.moves)
            .map(|(i, _)| i)
            .collect();
        let mut uses: Vec<(usize, usize)> = Vec::new();
        for (m, (module_calls, r)) in calls.iter().zip(rest).enumerate() {
            let src = r.6;
            for u in &module_calls.uses {
                let name = u.name.span();
                let args = || contains_ignoring_case(statement_text(src, name.end), b"\\NoEOffs");
                if !what.ignored_by(name.slice(src), args) {
                    uses.push((m, name.start));
                }
            }
        }
        let active = task.active_at(&at(&sets), &at(&clears), &uses);
        let by_itself = sets
            .iter()
            .filter_map(|&i| Some((instructions.get(i)?.at, i)));
        let displaced = uses.into_iter().zip(active).filter_map(|(call, k)| {
            let set = sets.get(k?)?;
            Some((call, *set))
        });
        for (call, i) in by_itself.chain(displaced) {
            let list = out.entry(call).or_default();
            let of_this_kind = |&j: &usize| instructions.get(j).is_some_and(|d| d.what == what);
            if !list.iter().any(of_this_kind) {
                list.push(i);
            }
        }
    }
    out
}

/// Marks each target a displaced call reaches as moved with the displacement of the
/// instruction named with it (an index into `instructions`), the instruction and its line
/// named.
fn mark_displaced(
    facts: &mut [crate::resolve::FileFacts<'_>],
    instructions: &[Displacing],
    reached: &[(usize, Vec<(usize, usize)>)],
) {
    for (i, targets) in reached {
        let Some(d) = instructions.get(*i) else {
            continue;
        };
        let (from, _) = d.at;
        let Some(name) = facts.get(from).map(|f| f.name.clone()) else {
            continue;
        };
        for &(m, t) in targets {
            if let Some(usage) = facts.get_mut(m).and_then(|f| f.positions.usage_mut(t)) {
                usage.set_run_time(d.what.why(d.name, UseLine::of(d.line, from, m, &name)));
            }
        }
    }
}

/// Gives each target literal assigned to a name (`pv := [[…]];`, `literals`: per module, the
/// name's span and the literal's index) the usage of the declaration the name reaches: the
/// module's own, else the first another module exports. The motions that move to `pv` move to
/// whichever value it holds, so the literal is corrected with their work object and tool, as
/// the declaration is; a name that reaches no declaration leaves the literal unused.
fn share_assigned_usage(
    facts: &mut [crate::resolve::FileFacts<'_>],
    literals: &[Vec<(Span, usize)>],
) {
    if literals.iter().all(Vec::is_empty) {
        return;
    }
    // Names folded into one buffer: every position's name is compared, and a string each was
    // an allocation per target of the task.
    let mut buf = String::new();
    // The names assigned, then every declaration of them (module, index), in program order.
    let mut declared: NameMap<String, Vec<(usize, usize)>> = NameMap::default();
    for (m, list) in literals.iter().enumerate() {
        let Some(f) = facts.get(m) else { continue };
        for &(name, _) in list {
            declared
                .entry(crate::names::fold_into(&mut buf, name.slice(f.src)).to_owned())
                .or_default();
        }
    }
    for (m, f) in facts.iter().enumerate() {
        for i in 0..f.positions.len() {
            if let Some(found) = f
                .positions
                .name_bytes(i)
                .and_then(|n| declared.get_mut(crate::names::fold_into(&mut buf, n)))
            {
                found.push((m, i));
            }
        }
    }
    for (m, list) in literals.iter().enumerate() {
        for &(name, literal) in list {
            let Some(f) = facts.get(m) else { continue };
            let Some(all) = declared.get(crate::names::fold_into(&mut buf, name.slice(f.src)))
            else {
                continue;
            };
            let exported = |(dm, di): (usize, usize)| facts.get(dm).is_some_and(|d| d.exports(di));
            let Some(&(dm, di)) = all
                .iter()
                .find(|&&(dm, _)| dm == m)
                .or_else(|| all.iter().find(|&&at| exported(at)))
            else {
                continue;
            };
            let usage = facts.get(dm).and_then(|d| d.positions.usage(di)).cloned();
            if let (Some(usage), Some(to)) = (
                usage,
                facts
                    .get_mut(m)
                    .and_then(|f| f.positions.usage_mut(literal)),
            ) {
                *to = usage;
            }
        }
    }
}

/// The text of the statement whose callee ends at `from`, to its `;` (or at most 4 KiB).
fn statement_text(src: &[u8], from: usize) -> &[u8] {
    let rest = src.get(from..).unwrap_or_default();
    let rest = rest.get(..rest.len().min(4096)).unwrap_or(rest);
    rest.split(|&b| b == b';').next().unwrap_or_default()
}

fn contains_ignoring_case(text: &[u8], word: &[u8]) -> bool {
    text.windows(word.len())
        .any(|w| w.eq_ignore_ascii_case(word))
}

/// Instruction name prefixes that move the robot (or set up a move): their targets get the
/// default work object `wobj0` when no `\WObj` is given.
const MOTION_PREFIXES: &[&str] = &[
    "move", "search", "trigg", "arc", "spot", "paint", "cap", "disp", "laser", "glue", "nut", "sm",
    "trigl", "trigj", "trigc", "contact",
];

/// How RAPID references reach declarations: `pArr{i}` or `pArr` reaches every element of
/// `pArr`; a module's own data (routine data, `LOCAL` data) hides the task's, and of the other
/// modules only the module data that is not `LOCAL` is seen.
const NAMING: crate::resolve::Naming = crate::resolve::Naming {
    open: '{',
    close: '}',
    arrays: crate::resolve::ArrayReach::WhenUndeclared,
};

/// A procedure call, kept until every declaration has been read: the frame and tool it moves
/// with are found then, and it is bound as a [`Use`](crate::resolve::Use). Its arguments,
/// references and inline literals are ranges of the extractor's shared lists (one list each,
/// not three vectors per call), from the `*_start` given here to the next call's.
#[derive(Clone, Copy, Debug)]
struct CallUse {
    name: Span32,
    line: u32,
    /// The routine the call is written in (index into the module's routines), plus one: four
    /// bytes, where an `Option<u32>` is eight (a module has a call per target).
    routine: Option<std::num::NonZeroU32>,
    /// `\WObj:=` value.
    wobj: Option<Span32>,
    /// `\Tool:=` (or `tool:=`) value.
    tool: Option<Span32>,
    /// Start in [`Extractor::call_args`]: positional arguments that are plain references
    /// (`p10`, `pArr{3}`).
    args_start: u32,
    /// Start in [`Extractor::call_refs`]: targets referenced through `Offs`/`RelTool` first
    /// arguments.
    refs_start: u32,
    /// Start in [`Extractor::call_inline`]: inline literals written in the call's arguments
    /// (indices into `positions`).
    inline_start: u32,
}

/// A module holds a call per target: a layout change that grows the record fails the build.
const _: () = assert!(std::mem::size_of::<CallUse>() == 44);

/// A module's call records and the shared lists their ranges index.
struct Calls {
    uses: Vec<CallUse>,
    args: Vec<Option<Span32>>,
    refs: Vec<Span>,
    inline: Vec<usize>,
}

impl Calls {
    /// Each call with its positional arguments, references and inline literals.
    fn iter(&self) -> impl Iterator<Item = (&CallUse, &[Option<Span32>], &[Span], &[usize])> + '_ {
        // One call's part of a shared list: from its start to the next call's (or the end).
        fn part<T>(list: &[T], start: u32, next: Option<u32>) -> &[T] {
            let end = next.map_or(list.len(), |n| n as usize);
            list.get(start as usize..end).unwrap_or_default()
        }
        self.uses.iter().enumerate().map(move |(k, u)| {
            let next = self.uses.get(k + 1);
            (
                u,
                part(&self.args, u.args_start, next.map(|n| n.args_start)),
                part(&self.refs, u.refs_start, next.map(|n| n.refs_start)),
                part(&self.inline, u.inline_start, next.map(|n| n.inline_start)),
            )
        })
    }
}

/// A whole literal value given to a name in a routine (`wobj1 := [FALSE,TRUE,"",…];`), read
/// as a work object and as a tool: which it is shows when the name's declaration is found.
struct AssignedValue {
    name: Span,
    as_wobj: FrameDecl,
    as_tool: FrameDecl,
}

impl AssignedValue {
    /// The value read as a frame of `decl`'s kind.
    fn as_kind_of(&self, decl: &FrameDecl) -> &FrameDecl {
        match decl.kind {
            FrameKind::Tool => &self.as_tool,
            _ => &self.as_wobj,
        }
    }
}

/// Which declaration a frame's name means where it is used, by the rule a motion looks it up
/// with: the routine's own, else its module's, else one every module sees (not `LOCAL`).
/// Built only when some name could mean two (declared twice in the task, or in a routine):
/// otherwise empty, and nothing is asked of it.
struct FrameScopes {
    /// Per module, its frames' folded names with their scopes.
    modules: Vec<Vec<(String, FrameScope)>>,
}

/// The declaration a frame's name means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Bound {
    module: usize,
    index: usize,
    /// A routine's own frame: a transform, which looks frames up by name, never finds it.
    routine: bool,
}

impl FrameScopes {
    fn new<'f>(modules: impl Iterator<Item = &'f [FrameDecl]>) -> FrameScopes {
        let modules: Vec<Vec<(String, FrameScope)>> = modules
            .map(|frames| {
                frames
                    .iter()
                    .map(|f| (f.name.to_ascii_lowercase(), f.scope))
                    .collect()
            })
            .collect();
        let mut seen = std::collections::HashSet::new();
        let twice = modules
            .iter()
            .flatten()
            .any(|(n, s)| matches!(s, FrameScope::Routine(_)) || !seen.insert(n.as_str()));
        FrameScopes {
            modules: if twice { modules } else { Vec::new() },
        }
    }

    fn is_empty(&self) -> bool {
        self.modules.is_empty()
    }

    /// The declaration `name` means in routine `routine` of module `m` (`None`: outside any
    /// routine, as a target's own module sees it).
    fn seen_from(&self, m: usize, routine: Option<usize>, name: &str) -> Option<Bound> {
        let named = |(_, (n, _)): &(usize, &(String, FrameScope))| n.eq_ignore_ascii_case(name);
        let own = self.modules.get(m)?;
        let in_routine = routine.and_then(|r| {
            own.iter()
                .enumerate()
                .filter(named)
                .find(|(_, (_, s))| *s == FrameScope::Routine(r))
        });
        if let Some((index, _)) = in_routine {
            return Some(Bound {
                module: m,
                index,
                routine: true,
            });
        }
        let module_level =
            |(_, (_, s)): &(usize, &(String, FrameScope))| !matches!(s, FrameScope::Routine(_));
        if let Some((index, _)) = own.iter().enumerate().filter(named).find(module_level) {
            return Some(Bound {
                module: m,
                index,
                routine: false,
            });
        }
        self.modules.iter().enumerate().find_map(|(k, frames)| {
            let (index, _) = frames
                .iter()
                .enumerate()
                .filter(named)
                .find(|(_, (_, s))| *s == FrameScope::Program)?;
            Some(Bound {
                module: k,
                index,
                routine: false,
            })
        })
    }
}

/// The frames a call (in module `m`, to `callee`, with positional arguments `args`) passes to
/// parameters its routine gives a value (`PROC setw(INOUT wobjdata wx) wx := …`, `setw w1;`):
/// each frame's name as written, the routine's module and the assignment's line.
fn frames_written_through(
    routines: &[(&[u8], &[crate::resolve::Routine])],
    writes: &[Vec<(usize, Span32, usize)>],
    (m, callee, args): (usize, &[u8], &[Option<Span32>]),
    scopes: &FrameScopes,
) -> Vec<(String, usize, usize)> {
    let called = |k: usize, own: bool| {
        let (src, list) = routines.get(k)?;
        let r = list
            .iter()
            .position(|r| (own || !r.local) && r.name.slice(src).eq_ignore_ascii_case(callee))?;
        Some((k, r))
    };
    let Some((k, r)) =
        called(m, true).or_else(|| (0..routines.len()).find_map(|k| called(k, false)))
    else {
        return Vec::new();
    };
    let (Some((src, list)), Some(caller)) = (routines.get(k), routines.get(m)) else {
        return Vec::new();
    };
    let Some(routine) = list.get(r) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for &(wr, param, line) in writes.get(k).into_iter().flatten() {
        if wr != r {
            continue;
        }
        let position = routine
            .params
            .iter()
            .position(|p| p.slice(src).eq_ignore_ascii_case(param.span().slice(src)));
        let Some(arg) = position.and_then(|i| args.get(i).copied().flatten()) else {
            continue;
        };
        // A component passed (`bump wA.uframe.trans.x;`) changes the frame it is part of.
        let name = latin1(trim_latin1(
            written_name(caller.0, arg.span()).slice(caller.0),
        ));
        if scopes.is_empty() || scopes.seen_from(m, None, &name).is_some() {
            out.push((name, k, line));
        }
    }
    out
}

/// The uses of work object or tool `f` (declared at `at`: module, index among its frames) that
/// may run while it holds its declared value, the program giving it another at `given`
/// (module, first byte of the name assigned), in module and file order: (module, the use). A
/// use names the frame where its name means that declaration, not a parameter of the use's
/// routine: as its `\WObj:=`, or as its tool (`kinds` finds it).
#[allow(clippy::too_many_arguments)]
fn run_before_given<'c, 's>(
    f: &FrameDecl,
    at: (usize, usize),
    given: &[(usize, usize)],
    calls: &'c [Calls],
    routines: &[(&'s [u8], &[crate::resolve::Routine])],
    scopes: &FrameScopes,
    kinds: &ArgKinds<'_, 's>,
    task: &super::flow::Task<'_>,
) -> Vec<(usize, &'c CallUse)> {
    let frame = NameKey(f.name.as_bytes());
    let declared = Bound {
        module: at.0,
        index: at.1,
        routine: false,
    };
    let mut uses = Vec::new();
    for (m, (module_calls, &(src, list))) in calls.iter().zip(routines).enumerate() {
        for (u, args, ..) in module_calls.iter() {
            let named = match f.kind {
                FrameKind::Tool => kinds.tool_of(u, args, src),
                _ => u.wobj.map(|w| trim_latin1(w.span().slice(src))),
            };
            let Some(name) = named else { continue };
            if NameKey(name) != frame {
                continue;
            }
            let routine = u.routine.map(|r| r.get() as usize - 1);
            if routine
                .and_then(|r| list.get(r))
                .is_some_and(|r| r.has_parameter(src, name))
            {
                continue;
            }
            if !scopes.is_empty() && scopes.seen_from(m, routine, &latin1(name)) != Some(declared) {
                continue;
            }
            uses.push((m, u));
        }
    }
    let at_uses: Vec<(usize, usize)> = uses
        .iter()
        .map(|&(m, u)| (m, u.name.span().start))
        .collect();
    let declared = task.declared_may_reach(given, &at_uses);
    uses.into_iter()
        .zip(declared)
        .filter_map(|(u, d)| d.then_some(u))
        .collect()
}

/// What the frames given a whole literal value in a routine come to: the warnings and errors at
/// the assignments (per module), the frames whose value the flow decides (frame, kind, module,
/// line), the one other value that stands for a frame (module, index, the value), the
/// assignments of a frame's own value, and the motions that may run while a work object or tool
/// so given still holds its declared value (docs/design.md, "Frames the program assigns").
struct FramesGiven {
    notes: Vec<Vec<Diagnostic>>,
    reassigned: Vec<(String, FrameKind, usize, usize)>,
    replaced: Vec<(usize, usize, FrameDecl)>,
    own_values: Vec<(usize, FrameDecl)>,
    declared_first: std::collections::HashMap<(usize, usize), Arc<[crate::resolve::TwoValuesAt]>>,
}

/// What each module keeps to the end of [`finish_task`]: its frames, offset calls, literal
/// values given to names, computed assignments, routines, which targets other modules see, its
/// source and its copies.
type Kept<'s> = (
    Vec<FrameDecl>,
    Vec<OffsetCall>,
    Vec<AssignedValue>,
    Vec<crate::resolve::Assignment>,
    Vec<crate::resolve::Routine>,
    Vec<bool>,
    &'s [u8],
    Vec<crate::resolve::CopyFact>,
);

/// The task's routines as `rapid::flow` reads them, built from the modules' skeleton trees
/// (kept by the first parse, or parsed again) when a question first needs them.
struct Flow<'s> {
    skeletons: Vec<Option<Vec<super::Node>>>,
    task: Option<super::flow::Task<'s>>,
}

impl<'s> Flow<'s> {
    fn task(&mut self, rest: &[Kept<'s>]) -> &super::flow::Task<'s> {
        self.task.get_or_insert_with(|| {
            let kept = std::mem::take(&mut self.skeletons);
            super::flow::Task::new(rest.iter().map(|r| r.6).zip(kept).collect())
        })
    }
}

/// [`FramesGiven`] of the task's modules (`rest`, with their routines' flow, their calls and
/// routines; `kinds` finds a call's tool).
fn frames_given<'s>(
    rest: &[Kept<'s>],
    flow: &mut Flow<'s>,
    calls: &[Calls],
    routine_lists: &[(&'s [u8], &[crate::resolve::Routine])],
    scopes: &FrameScopes,
    kinds: &ArgKinds<'_, 's>,
    module_names: &[Arc<str>],
) -> FramesGiven {
    // The uses that may run while their work object or tool holds its declared value, the
    // program giving it one other value, by (module, first byte of the instruction).
    let mut declared_first: std::collections::HashMap<
        (usize, usize),
        Vec<crate::resolve::TwoValuesAt>,
    > = Default::default();
    let mut buf = String::new();
    // A frame given a whole value in a routine (docs/design.md, "Frames the program assigns").
    // Each assignment: (the frame's module and index, the assignment's module and index).
    let mut given: Vec<((usize, usize), (usize, usize))> = Vec::new();
    // (element, kind, module, line) of each frame an assignment to its whole array gives a
    // value.
    let mut whole_arrays: Vec<(String, FrameKind, usize, usize)> = Vec::new();
    for (m, r) in rest.iter().enumerate() {
        for (k, a) in r.2.iter().enumerate() {
            let key = key_into(&mut buf, r.6, a.name);
            // The frames matching `named` the assigning module sees: its own first, as a
            // motion's frame resolves, else those every module sees.
            let seen = |named: &dyn Fn(&FrameDecl) -> bool| -> Vec<(usize, usize)> {
                let own = |f: &FrameDecl| !matches!(f.scope, FrameScope::Routine(_));
                let every = |f: &FrameDecl| f.scope == FrameScope::Program;
                let matching = |fm: usize, fr: &[FrameDecl], scope: &dyn Fn(&FrameDecl) -> bool| {
                    let hits = fr.iter().enumerate().filter(|(_, f)| scope(f) && named(f));
                    hits.map(|(i, _)| (fm, i)).collect::<Vec<_>>()
                };
                let mine = matching(m, &r.0, &own);
                if !mine.is_empty() {
                    return mine;
                }
                rest.iter()
                    .enumerate()
                    .flat_map(|(fm, fr)| matching(fm, &fr.0, &every))
                    .collect()
            };
            if let Some(&at) = seen(&|f| f.name.eq_ignore_ascii_case(key)).first() {
                given.push((at, (m, k)));
                continue;
            }
            // A whole array of frames given a value (`wArr := [w1, w2];`): which element holds
            // what depends on the literal's shape and the flow; its elements' motions are
            // refused as given a value (an element's own assignment is read as above).
            let element = |f: &FrameDecl| {
                f.name.len() > key.len()
                    && f.name.as_bytes().get(key.len()) == Some(&b'{')
                    && f.name
                        .get(..key.len())
                        .is_some_and(|n| n.eq_ignore_ascii_case(key))
            };
            let elements = seen(&element)
                .into_iter()
                .filter_map(|(fm, i)| rest.get(fm)?.0.get(i));
            for f in elements {
                whole_arrays.push((f.name.clone(), f.kind, m, a.as_wobj.line));
            }
        }
    }
    let mut assigned_notes: Vec<Vec<Diagnostic>> = vec![Vec::new(); rest.len()];
    // (frame, kind, module, line) of each frame whose value the flow decides.
    let mut reassigned: Vec<(String, FrameKind, usize, usize)> = whole_arrays;
    // A frame declared in two modules of the task for every module to see, with two values:
    // one object at run time (a `PERS` keeps the value of the module loaded first; a
    // `CONST` or `VAR` twice does not load), so which value the motions run with is not in
    // the text.
    // (Only when some frame name is declared twice in the task: `scopes` is built then.)
    for (m, r) in rest.iter().enumerate().filter(|_| !scopes.is_empty()) {
        for f in r.0.iter().filter(|f| f.scope == FrameScope::Program) {
            let first = rest.iter().enumerate().take(m).find_map(|(fm, fr)| {
                let d = fr.0.iter().find(|d| {
                    d.scope == FrameScope::Program
                        && d.kind == f.kind
                        && d.name.eq_ignore_ascii_case(&f.name)
                })?;
                Some((fm, d))
            });
            let Some((fm, d)) = first.filter(|(_, d)| !d.same_value(f)) else {
                continue;
            };
            let (Some(notes), Some(there)) = (assigned_notes.get_mut(m), module_names.get(fm))
            else {
                continue;
            };
            notes.push(
                Diagnostic::warning(
                    f.span,
                    format!(
                        "`{}` is declared here and in {there} (line {}) with another value: the task has one `{}`, whose value the text does not decide",
                        f.name, d.line, f.name
                    ),
                )
                .with_hint("declare it in one module, or give both declarations one value")
                // The refusal of its targets names this declaration: say why there too.
                .shaping_transforms(),
            );
            reassigned.push((f.name.clone(), f.kind, m, f.line));
        }
    }
    // (module, index, the value) of each frame the program gives one other value.
    let mut replaced: Vec<(usize, usize, FrameDecl)> = Vec::new();
    // (module, the value) of each assignment of a frame's own value.
    let mut own_values: Vec<(usize, FrameDecl)> = Vec::new();
    let mut frames_seen: Vec<(usize, usize)> = Vec::new();
    for &(at, _) in &given {
        if frames_seen.contains(&at) {
            continue;
        }
        frames_seen.push(at);
        let Some(f) = rest.get(at.0).and_then(|r| r.0.get(at.1)) else {
            continue;
        };
        let all: Vec<(usize, &AssignedValue)> = given
            .iter()
            .filter(|g| g.0 == at)
            .filter_map(|&(_, (m, k))| Some((m, rest.get(m)?.2.get(k)?)))
            .collect();
        let values: Vec<(usize, &AssignedValue)> = all
            .iter()
            .copied()
            .filter(|(_, a)| !f.same_value(a.as_kind_of(f)))
            .collect();
        // Each assignment as a frame of its module, named as the frame is.
        let as_frame = |&(m, a): &(usize, &AssignedValue)| {
            let value = FrameDecl {
                name: f.name.clone(),
                assigned: true,
                ..a.as_kind_of(f).clone()
            };
            (m, value)
        };
        let Some(&(first_m, first)) = values.first() else {
            // Every value given is the declaration's: rewritten with it.
            own_values.extend(all.iter().map(as_frame));
            continue;
        };
        let what = match f.kind {
            FrameKind::Tool => "tool",
            _ => "work object",
        };
        let value = first.as_kind_of(f);
        if f.storage == crate::position::FrameStorage::Constant {
            for &(m, a) in &values {
                if let Some(notes) = assigned_notes.get_mut(m) {
                    notes.push(
                        Diagnostic::error(
                            a.name,
                            format!(
                                "{what} `{}` is a CONST (line {}): the controller does not let a program give it a value",
                                f.name, f.line
                            ),
                        )
                        .with_hint("declare it PERS (or VAR), or remove the assignment"),
                    );
                }
            }
            continue;
        }
        // One other value, given in the frame's own module, with numbers, to a PERS: the value
        // the motions run with once the program has set it (a generated program sets its
        // frames before it moves; a `PERS` keeps the last value given, where a `VAR` starts
        // from its declaration whenever the program starts), so the targets are transformed
        // with it, and a mirror of the frame is written into the assignment.
        let persistent = f.storage == crate::position::FrameStorage::Persistent;
        // Whether the robot holds the tool was read from the declaration when the motions were
        // bound: a value that changes it is not taken.
        let same_holder = value.held_by_robot == f.held_by_robot;
        let one = persistent
            && same_holder
            && all.iter().all(|&(m, a)| {
                m == at.0 && value.same_value(a.as_kind_of(f)) && value.pose().is_some()
            });
        // The motions with the work object or tool that may run while its declared value still
        // holds: their targets are moved to in both values.
        let before = if one {
            let given: Vec<(usize, usize)> = all.iter().map(|&(m, a)| (m, a.name.start)).collect();
            let task = flow.task(rest);
            run_before_given(f, at, &given, calls, routine_lists, scopes, kinds, task)
        } else {
            Vec::new()
        };
        let given_at = (first_m, first.as_wobj.line);
        for &(m, u) in &before {
            let why = crate::resolve::TwoValuesAt {
                kind: f.kind,
                frame: f.name.clone(),
                declared: (at.0, f.line),
                given: given_at,
                motion: (m, u.line as usize),
            };
            let whys = declared_first.entry((m, u.name.span().start)).or_default();
            // A motion names one work object and one tool.
            if whys.iter().all(|w| w.kind != why.kind) {
                whys.push(why);
            }
        }
        // What trackfix does with a target moved to in both values.
        let left = match f.kind {
            FrameKind::Tool => "left as written where the tool matters (the robot's kinematics)",
            // A mirror in the work object's own plane is the same in both values: it goes ahead.
            _ => "left as written, but by a mirror in the work object's own plane",
        };
        for &(m, a) in &values {
            let (message, hint) = if let Some(&(bm, u)) = before.first() {
                let motion = module_names.get(bm).map_or_else(
                    || UseLine::new(u.line as usize),
                    |name| UseLine::of(u.line as usize, bm, m, name),
                );
                let more = match before.len() {
                    1 => String::new(),
                    2 => " (and one more)".to_owned(),
                    n => format!(" (and {} more)", n - 1),
                };
                (
                    format!(
                        "{what} `{}` is given another value here than its declaration on line {}: trackfix uses this value, but the motion on {motion}{more} may run before it, while the declared one holds: the targets moved there are {left}",
                        f.name, f.line
                    ),
                    format!(
                        "give the {what} this value before every motion that moves with it, or declare it with this value, so that one value holds"
                    ),
                )
            } else if one {
                (
                    format!(
                        "{what} `{}` is given another value here than its declaration on line {}: trackfix uses this value, which the program gives it before every motion that moves with it",
                        f.name, f.line
                    ),
                    "declare the frame with the value the program gives it, so that one value holds"
                        .to_owned(),
                )
            } else {
                (
                    format!(
                        "{what} `{}` is given another value here than its declaration on line {}, {}: the targets moved with it are left as written",
                        f.name,
                        f.line,
                        if !persistent {
                            "a VAR, which starts from its declaration whenever the program starts"
                        } else if all.iter().any(|&(m, _)| m != at.0) {
                            "by a module that does not declare it"
                        } else if value.pose().is_none() {
                            "with fields that are not numbers"
                        } else if !same_holder {
                            "one that changes whether the robot holds the tool (robhold)"
                        } else {
                            "and other values elsewhere"
                        }
                    ),
                    "give the frame one value: declare it with the value the program gives it"
                        .to_owned(),
                )
            };
            if let Some(notes) = assigned_notes.get_mut(m) {
                let d = Diagnostic::warning(a.name, message).with_hint(hint);
                notes.push(if one { d.shaping_transforms() } else { d });
            }
        }
        if one {
            // The first stands for the frame; the others give its value again.
            let mut each = all.iter().map(as_frame);
            if let Some((_, value)) = each.next() {
                replaced.push((at.0, at.1, value));
            }
            own_values.extend(each);
            // The declaration is rewritten as the value is: a motion that may run before the
            // assignment moves with it, and a mirror in the work object's own plane moves such
            // a motion's targets (the same in both values) rather than refusing them.
            own_values.push((at.0, f.clone()));
        } else {
            reassigned.push((f.name.clone(), f.kind, first_m, first.as_wobj.line));
        }
    }
    FramesGiven {
        notes: assigned_notes,
        reassigned,
        replaced,
        own_values,
        declared_first: declared_first
            .into_iter()
            .map(|(at, whys)| (at, Arc::from(whys)))
            .collect(),
    }
}

/// A `RECORD` declared in the module: its name and components (type, name).
#[derive(Clone, Debug)]
struct RecordDecl {
    name: Span,
    fields: Vec<(Span, Span)>,
}

/// How long the lists a call's record adds to are ([`Extractor::recorded_as_read`]).
#[cfg(debug_assertions)]
struct RecordLens {
    uses: usize,
    call_args: usize,
    call_refs: usize,
    call_inline: usize,
    positions: usize,
    passed_args: usize,
    passed_names: usize,
    misshapen: usize,
    copies: usize,
    computed: usize,
    named_at_run_time: usize,
    param_writes: usize,
    param_assignments: usize,
}

#[cfg(debug_assertions)]
impl RecordLens {
    fn of(e: &Extractor<'_>) -> RecordLens {
        RecordLens {
            uses: e.uses.len(),
            call_args: e.call_args.len(),
            call_refs: e.call_refs.len(),
            call_inline: e.call_inline.len(),
            positions: e.positions.len(),
            passed_args: e.passed.args.len(),
            passed_names: e.passed.names.len(),
            misshapen: e.misshapen.len(),
            copies: e.copies.len(),
            computed: e.computed.len(),
            named_at_run_time: e.named_at_run_time.len(),
            param_writes: e.param_writes.len(),
            param_assignments: e.param_assignments.len(),
        }
    }

    /// Cuts every list of `e` back to these lengths.
    fn cut_back(&self, e: &mut Extractor<'_>) {
        e.uses.truncate(self.uses);
        e.call_args.truncate(self.call_args);
        e.call_refs.truncate(self.call_refs);
        e.call_inline.truncate(self.call_inline);
        while e.positions.len() > self.positions {
            e.positions.remove(e.positions.len() - 1);
        }
        e.passed.args.truncate(self.passed_args);
        e.passed.names.truncate(self.passed_names);
        e.misshapen.truncate(self.misshapen);
        e.copies.truncate(self.copies);
        e.computed.truncate(self.computed);
        e.named_at_run_time.truncate(self.named_at_run_time);
        e.param_writes.truncate(self.param_writes);
        e.param_assignments.truncate(self.param_assignments);
    }
}

/// Collects positions, frames, offsets and usage from the parsed statements.
pub struct Extractor<'l> {
    records: Vec<RecordDecl>,
    lines: &'l LineIndex,
    positions: PositionList,
    frames: Vec<FrameDecl>,
    offsets: Vec<OffsetCall>,
    /// Per offset call: the routine it is written in and the reference its offset is taken
    /// from (see [`offset_reference`]), for the usage pass to resolve into
    /// [`OffsetCall::bases`].
    offset_refs: Vec<(Option<usize>, Option<Span>)>,
    /// Every name declared, routines included (spans into the source: no copy per
    /// declaration).
    declared: crate::resolve::Declared,
    uses: Vec<CallUse>,
    /// The calls' positional arguments, call after call (see [`CallUse`]); `None` for an
    /// argument that is not a plain reference.
    call_args: Vec<Option<Span32>>,
    /// The calls' `Offs`/`RelTool` first arguments, call after call.
    call_refs: Vec<Span>,
    /// The calls' inline literals, call after call.
    call_inline: Vec<usize>,
    /// Whole-value assignments `name := [...]` of literal aggregates (a frame given a new
    /// value that is known offline) to module data (not to a routine's parameter or own data).
    assigned: Vec<AssignedValue>,
    /// The module's skeleton tree ([`super::flow::walked`]), kept when it gives a frame a
    /// whole value ([`Extractor::keep_skeleton`]).
    skeleton: Option<Vec<super::Node>>,
    /// Assignments of any value, whole or in part, to a routine's parameter: (routine,
    /// parameter, line). A frame a call passes there is given a value when the program runs.
    param_writes: Vec<(usize, Span32, usize)>,
    /// Of those, the ones whose literal is a target (`pv := [[700,-100,400],…];`): the name
    /// assigned and the literal's index in `positions`. The literal is a value of the name,
    /// used by the motions that use it.
    assigned_literals: Vec<(Span, usize)>,
    /// Computed values given to a parameter of the routine they are written in (`pOut :=
    /// CRobT();` in `PROC Remember(INOUT robtarget pOut)`): the routine, the parameter's name
    /// as written, the line. The target a call passes there is what the program computes.
    param_assignments: Vec<(usize, Span32, usize)>,
    /// Copies of one name's value into another (`pv := p10;`, `buf{1} := p10;`, `pv :=
    /// Offs(p10, 0, 0, 10);`, `RETURN p;`). A motion to the copy moves to the source's value.
    copies: Vec<crate::resolve::CopyFact>,
    /// Call arguments the positional binding does not see: not a plain name, or given by
    /// their parameter's name (rare; bound once every use is).
    passed: crate::resolve::PassedArgs,
    /// Calls that name their data or routine only when the program runs: (the call as
    /// written, its line, whether only the targets its arguments name are at stake (a late
    /// call `%pn% p10;`: those names) or every target of the program (`None`)).
    named_at_run_time: Vec<(Span, usize, Option<Vec<Span>>)>,
    /// Target literals whose parts do not have the sizes of their type (`[[1,2,3,4],…]` for a
    /// robtarget): errors, so the file is not transformed (the controller does not load it).
    misshapen: Vec<Diagnostic>,
    /// Assignments of values computed at run time (`p := CRobT()`, `wobj.uframe := …`).
    computed: Vec<crate::resolve::Assignment>,
    routines: Vec<crate::resolve::Routine>,
    /// The routine being read (`None` at module level).
    current: Option<usize>,
    /// Positions declared in a scope other modules see (module data without `LOCAL`); inline
    /// literals and routine data are private to their module.
    exported: Vec<bool>,
    /// A number field of the position being built was not scanned by the numeric-aggregate
    /// path, so the list checks its fields (see [`Extractor::push`]).
    read_elsewhere: std::cell::Cell<bool>,
    /// The line of the last statement or target placed: they come in file order.
    line_cursor: LineCursor,
    /// Where the call the last of [`Extractor::uses`] records starts, when it had plain
    /// arguments and its record is that use alone: no argument passed by name, no data
    /// written by name (see [`Extractor::call_like_last`]).
    last_plain_call: Option<usize>,
}

/// What [`Extractor::finish`] returns.
pub struct Extracted {
    /// The targets declared or written inline, in source order.
    pub positions: PositionList,
    /// The work object, tool and base declarations.
    pub frames: Vec<FrameDecl>,
    /// Assignments of a frame's own value (see [`ParsedFile::frame_values`]).
    ///
    /// [`ParsedFile::frame_values`]: crate::position::ParsedFile::frame_values
    pub frame_values: Vec<FrameDecl>,
    /// The `Offs`/`RelTool` calls, for the offset rules.
    pub offsets: Vec<OffsetCall>,
    /// What was deliberately not read as a target, and why.
    pub diagnostics: Vec<Diagnostic>,
}

fn text_of(src: &[u8], span: Span) -> String {
    latin1(span.slice(src))
}

/// `bytes` without the blanks [`str::trim`] takes off their Latin-1 text: ASCII white space and
/// the two Latin-1 ones, NEL (0x85) and NO-BREAK SPACE (0xA0). `latin1(trim_latin1(b))` is
/// `latin1(b).trim()`, without making the untrimmed text first.
fn trim_latin1(bytes: &[u8]) -> &[u8] {
    let blank = |b: &u8| matches!(b, b'\t'..=b'\r' | b' ' | 0x85 | 0xA0);
    let start = bytes.iter().position(|b| !blank(b)).unwrap_or(bytes.len());
    let end = bytes
        .iter()
        .rposition(|b| !blank(b))
        .map_or(start, |e| e + 1);
    bytes.get(start..end).unwrap_or_default()
}

/// A frame or tool name as the usage pass gives it to targets: the shared handle, and whether
/// the work object of that name holds the tool (`robhold`: a stationary-tool motion).
#[derive(Clone)]
struct FrameText {
    name: FrameName,
    robhold: bool,
}

/// The frame and tool names the calls of a task are written with, made once per distinct
/// text: a module's 100,000 calls name a handful of frames and tools, so a call's `\WObj:=wCar`
/// costs a lookup of the bytes, not a `String` and the hashing of its text into a shared set.
/// Keyed by the exact bytes: a target keeps the spelling of its first use.
struct FrameTexts<'s, 'r> {
    known: NameMap<&'s [u8], FrameText>,
    robhold: &'r NameMap<NameKey<'r>, bool>,
    /// The last two names asked for, the older one next to be replaced: call after call
    /// names the same tool and work object, which these answer without hashing the bytes
    /// (the map's lookups were 2.9 M instructions of 11,000 calls).
    recent: [Option<(&'s [u8], FrameText)>; 2],
    older: usize,
}

impl<'s, 'r> FrameTexts<'s, 'r> {
    fn new(robhold: &'r NameMap<NameKey<'r>, bool>) -> FrameTexts<'s, 'r> {
        FrameTexts {
            known: NameMap::default(),
            robhold,
            recent: [None, None],
            older: 0,
        }
    }

    /// The name written as `bytes` (its Latin-1 text).
    fn get(&mut self, bytes: &'s [u8]) -> FrameText {
        for (k, slot) in self.recent.iter().enumerate() {
            if let Some((b, t)) = slot
                && same_bytes(b, bytes)
            {
                self.older = 1 - k;
                return t.clone();
            }
        }
        let t = self.get_known(bytes);
        if let Some(slot) = self.recent.get_mut(self.older) {
            *slot = Some((bytes, t.clone()));
        }
        self.older = 1 - self.older;
        t
    }

    /// [`FrameTexts::get`] through the map of every name asked for.
    fn get_known(&mut self, bytes: &'s [u8]) -> FrameText {
        if let Some(t) = self.known.get(bytes) {
            return t.clone();
        }
        let text = latin1(bytes);
        let t = FrameText {
            robhold: self.robhold.get(&NameKey(text.as_bytes())) == Some(&true),
            name: FrameName::from(text.as_str()),
        };
        self.known.insert(bytes, t.clone());
        t
    }
}

/// What a call's arguments are declared as, for finding its tool: the task's declared
/// tools, zones and speeds by name (see [`crate::resolve::declarations`]).
struct ArgKinds<'t, 's> {
    type_of: &'t NameMap<NameKey<'s>, DeclKind>,
    /// By the first byte of a name past blanks (either case), the kinds it may be ([`TOOL`],
    /// [`ZONE`], [`SPEED`]): those of the names in `type_of` that start with it, and of the
    /// built-in names (`tool0`; `fine`, `z10`; `vmax`, `v1000`). A call's target (`p10`) is
    /// no kind, and its speed and zone no tool: each is told by one load, where asking each
    /// argument whether it is `tool0`, then a declared tool, was half of finding a tool.
    may_be: [u8; 256],
    /// The last arguments looked up in `type_of`, as written, and their kinds there: call
    /// after call passes the same tool, which is then one compare of its bytes, not a hash.
    /// A few are kept because a speed, a zone and a tool declared with the same first byte
    /// (RoboDK's `rdkSpeed, rdkZone, rdkTool`) all pass [`ArgKinds::may_be`] and are looked
    /// up in turn, where one remembered was a hash each, every call. Each is taken in turn
    /// ([`ArgKinds::next`]), so a program's one tool stays in the first.
    last: [std::cell::Cell<Option<ArgKind<'s>>>; RECENT_ARGS],
    /// The entry of [`ArgKinds::last`] the next name looked up takes.
    next: std::cell::Cell<usize>,
}

/// How many names [`ArgKinds::last`] remembers.
const RECENT_ARGS: usize = 4;

/// A name as written and its kind in [`ArgKinds::type_of`] (`None`: not declared there).
type ArgKind<'s> = (&'s [u8], Option<DeclKind>);

/// The kinds of [`ArgKinds::may_be`].
const TOOL: u8 = 1;
const ZONE: u8 = 2;
const SPEED: u8 = 4;

impl<'t, 's> ArgKinds<'t, 's> {
    fn new(type_of: &'t NameMap<NameKey<'s>, DeclKind>) -> ArgKinds<'t, 's> {
        let mut may_be = [0; 256];
        let mut mark = |b: u8, kind: u8| {
            for b in [b.to_ascii_lowercase(), b.to_ascii_uppercase()] {
                if let Some(m) = may_be.get_mut(usize::from(b)) {
                    *m |= kind;
                }
            }
        };
        for (b, kind) in [(b't', TOOL), (b'f', ZONE), (b'z', ZONE), (b'v', SPEED)] {
            mark(b, kind);
        }
        for (n, kind) in type_of {
            let kind = match kind {
                DeclKind::Tool => TOOL,
                DeclKind::Zone => ZONE,
                DeclKind::Speed => SPEED,
                DeclKind::Other => 0,
            };
            // A name of blanks only is no byte's: `may_be` lets every such name through.
            if let Some(&b) = n.0.iter().find(|b| !b.is_ascii_whitespace()) {
                mark(b, kind);
            }
        }
        ArgKinds {
            type_of,
            may_be,
            last: Default::default(),
            next: std::cell::Cell::new(0),
        }
    }

    /// Whether `n` may be of `kind` (one of [`TOOL`], [`ZONE`], [`SPEED`]), by its first byte.
    fn may_be(&self, n: NameKey<'s>, kind: u8) -> bool {
        match n.0.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(&b) => self
                .may_be
                .get(usize::from(b))
                .is_some_and(|m| m & kind != 0),
            None => true,
        }
    }

    fn declared(&self, n: NameKey<'s>, kind: DeclKind) -> bool {
        let seen = self
            .last
            .iter()
            .find_map(|l| l.get().filter(|&(bytes, _)| same_bytes(bytes, n.0)));
        let found = match seen {
            Some((_, found)) => found,
            None => {
                let found = self.type_of.get(&n).copied();
                let k = self.next.get();
                if let Some(l) = self.last.get(k) {
                    l.set(Some((n.0, found)));
                }
                self.next.set((k + 1) % RECENT_ARGS);
                found
            }
        };
        found == Some(kind)
    }

    /// The tool call `u` (of a module with source `src`, `args` its positional arguments)
    /// names, as written: its `\Tool:=` argument, else the positional one [`tool_index`]
    /// finds.
    ///
    /// [`tool_index`]: ArgKinds::tool_index
    fn tool_of(&self, u: &CallUse, args: &[Option<Span32>], src: &'s [u8]) -> Option<&'s [u8]> {
        match u.tool {
            Some(sp) => Some(trim_latin1(sp.span().slice(src))),
            None => {
                let call = NameKey(u.name.span().slice(src));
                let i = self.tool_index(&call, args, src)?;
                let sp = args.get(i).copied().flatten()?;
                Some(sp.span().slice(src))
            }
        }
    }

    fn is_tool(&self, n: NameKey<'s>) -> bool {
        self.may_be(n, TOOL) && (n.is(b"tool0") || self.declared(n, DeclKind::Tool))
    }

    fn is_zone(&self, n: NameKey<'s>) -> bool {
        self.may_be(n, ZONE)
            && (n.is(b"fine") || n.numbered(b'z') || self.declared(n, DeclKind::Zone))
    }

    fn is_speed(&self, n: NameKey<'s>) -> bool {
        self.may_be(n, SPEED)
            && (n.is(b"vmax") || n.numbered(b'v') || self.declared(n, DeclKind::Speed))
    }

    /// The positional argument (of `args`, in `src`) that gives call `call`'s tool: one of
    /// the task's tools, else the argument after the zone (a search's after its speed, when
    /// it has no zone).
    fn tool_index(&self, call: &NameKey, args: &[Option<Span32>], src: &'s [u8]) -> Option<usize> {
        let first = |is: &dyn Fn(NameKey<'s>) -> bool| {
            args.iter()
                .position(|a| a.is_some_and(|sp| is(NameKey(sp.span().slice(src)))))
        };
        if let Some(i) = first(&|n| self.is_tool(n)) {
            return Some(i);
        }
        let after = first(&|n| self.is_zone(n)).or_else(|| {
            call.starts_with(b"search")
                .then(|| first(&|n| self.is_speed(n)))
                .flatten()
        })?;
        Some(after + 1)
    }
}

/// A reference as a lookup key ([`fold`](crate::names::fold) of its text), written into a
/// reused buffer.
fn key_into<'b>(buf: &'b mut String, src: &[u8], span: Span) -> &'b str {
    crate::names::fold_into(buf, span.slice(src))
}

impl<'l> Extractor<'l> {
    /// An extractor of the file whose lines `lines` indexes.
    pub fn new(lines: &'l LineIndex) -> Extractor<'l> {
        Extractor {
            records: Vec::new(),
            lines,
            // Not sized ahead: counting the file's `[[` for it was a pass over the whole
            // source (1.7 M of `check`'s 95 M instructions on a 2 MB module), and the lists
            // grow by doubling in place (`mremap`), their unused tail never touched.
            positions: PositionList::new(),
            frames: Vec::new(),
            offsets: Vec::new(),
            offset_refs: Vec::new(),
            declared: crate::resolve::Declared::default(),
            uses: Vec::new(),
            call_args: Vec::new(),
            call_refs: Vec::new(),
            call_inline: Vec::new(),
            assigned: Vec::new(),
            skeleton: None,
            param_writes: Vec::new(),
            assigned_literals: Vec::new(),
            param_assignments: Vec::new(),
            copies: Vec::new(),
            passed: crate::resolve::PassedArgs::default(),
            named_at_run_time: Vec::new(),
            misshapen: Vec::new(),
            computed: Vec::new(),
            routines: Vec::new(),
            current: None,
            exported: Vec::new(),
            read_elsewhere: std::cell::Cell::new(false),
            line_cursor: LineCursor::default(),
            last_plain_call: None,
        }
    }

    /// Appends position `p` as [`Extractor::position`] just built it. Its number fields came
    /// from the numeric-aggregate scan, which read each with `NumLit::parse_prefix` at its
    /// start, unless one took the general path: then the list checks each field itself.
    fn push(&mut self, p: Position, src: &[u8]) {
        let check = self.read_elsewhere.replace(false);
        self.positions.push_checking(p, src, check);
    }

    fn num(&self, src: &[u8], arena: &Arena, id: u32) -> Option<NumField> {
        let n = arena.get(id)?;
        if n.kind != ExprKind::Num {
            return None;
        }
        let span = n.span();
        let lit = match arena.lit(n) {
            Some(lit) => lit,
            None => {
                self.read_elsewhere.set(true);
                NumLit::parse(span.slice(src))?
            }
        };
        NumField::new(span, lit)
    }

    /// The first `N` elements of an aggregate as numeric fields (`None` where not a literal).
    fn nums<const N: usize>(
        &self,
        src: &[u8],
        arena: &Arena,
        id: Option<u32>,
    ) -> [Option<NumField>; N] {
        let mut out: [Option<NumField>; N] = std::array::from_fn(|_| None);
        if let Some(id) =
            id.filter(|&id| arena.get(id).is_some_and(|n| n.kind == ExprKind::Aggregate))
        {
            for (slot, child) in out.iter_mut().zip(arena.children(id)) {
                *slot = self.num(src, arena, child);
            }
        }
        out
    }

    fn nums_vec(&self, src: &[u8], arena: &Arena, id: Option<u32>) -> Vec<Option<NumField>> {
        match id.filter(|&id| arena.get(id).is_some_and(|n| n.kind == ExprKind::Aggregate)) {
            Some(id) => {
                // Sized exactly: collecting from the linked children grew the vector twice per
                // target (a quarter of the allocated bytes on a 250,000-target module).
                let mut out = Vec::with_capacity(arena.children(id).count());
                out.extend(arena.children(id).map(|c| self.num(src, arena, c)));
                out
            }
            None => Vec::new(),
        }
    }

    /// The external axes aggregate's elements as numeric fields, in place (see [`Axes`]).
    fn axes(&self, src: &[u8], arena: &Arena, id: Option<u32>) -> Axes {
        match id.filter(|&id| arena.get(id).is_some_and(|n| n.kind == ExprKind::Aggregate)) {
            Some(id) => arena
                .children(id)
                .map(|c| self.num(src, arena, c))
                .collect(),
            None => Axes::new(),
        }
    }

    /// `[[x,y,z],[q1,q2,q3,q4]]` (a pose) as Cartesian fields.
    fn pose_fields(&self, src: &[u8], arena: &Arena, id: Option<u32>) -> Option<CartesianFields> {
        let id = id?;
        if arena.get(id)?.kind != ExprKind::Aggregate {
            return None;
        }
        let mut parts = arena.children(id);
        let trans = parts.next();
        let rot = parts.next();
        Some(CartesianFields {
            trans: self.nums::<3>(src, arena, trans),
            orient: Some(Orientation::Quaternion(self.nums::<4>(src, arena, rot))),
        })
    }

    fn agg_len(arena: &Arena, id: u32) -> Option<usize> {
        let n = arena.get(id)?;
        (n.kind == ExprKind::Aggregate).then(|| arena.children(id).count())
    }

    /// The kind of target an aggregate literal is, by shape: robtarget `[[3],[4],[4],eax]`,
    /// jointtarget `[[6],eax]`, where `eax` is an aggregate or any expression.
    fn literal_kind(arena: &Arena, id: u32) -> Option<PositionKind> {
        let mut lens = [None; 5];
        let mut count = 0;
        for (slot, c) in lens.iter_mut().zip(arena.children(id)) {
            *slot = Some(Self::agg_len(arena, c));
            count += 1;
        }
        // The external axes may be a variable (generators write `rdkExtJoints`), so only the
        // robot part decides the shape.
        match (count, lens) {
            (4, [Some(Some(3)), Some(Some(4)), Some(Some(4)), Some(_), _]) => {
                Some(PositionKind::Robtarget)
            }
            (2, [Some(Some(6)), Some(_), ..]) => Some(PositionKind::Jointtarget),
            _ => None,
        }
    }

    /// What is wrong with the shape of the `kind` literal at `id`, if anything: the number of its
    /// parts, or of the values of a part written as a literal (a part written as a name or an
    /// expression, `rdkExtJoints`, is read at run time and has any shape).
    fn shape_problem(arena: &Arena, id: u32, kind: PositionKind) -> Option<String> {
        let parts: &[(usize, &str)] = match kind {
            PositionKind::Robtarget => &[
                (3, "its position [x,y,z]"),
                (4, "its orientation [q1,q2,q3,q4]"),
                (4, "its configuration [cf1,cf4,cf6,cfx]"),
                (6, "its external axes [eax_a,…,eax_f]"),
            ],
            PositionKind::Jointtarget => &[
                (6, "its robot axes [rax_1,…,rax_6]"),
                (6, "its external axes [eax_a,…,eax_f]"),
            ],
            _ => return None,
        };
        let count = arena.children(id).count();
        if count != parts.len() {
            return Some(format!(
                "it has {count} parts where a {} has {}",
                kind.as_str(),
                parts.len()
            ));
        }
        arena
            .children(id)
            .zip(parts)
            .find_map(|(part, &(want, what))| {
                let got = Self::agg_len(arena, part).filter(|&n| n != want)?;
                let values = if got == 1 { "value" } else { "values" };
                Some(format!(
                    "{what} has {got} {values} where a {} takes {want}",
                    kind.as_str()
                ))
            })
    }

    /// Notes an error for the `kind` literal at `id` (named `name`, or inline) when its shape is
    /// not its type's ([`Extractor::shape_problem`]).
    fn check_shape(&mut self, arena: &Arena, id: u32, kind: PositionKind, name: Option<&str>) {
        let (Some(problem), Some(n)) = (Self::shape_problem(arena, id, kind), arena.get(id)) else {
            return;
        };
        let what = match name {
            Some(name) => format!("{} `{name}`", kind.as_str()),
            None => format!("inline {}", kind.as_str()),
        };
        self.misshapen.push(
            Diagnostic::error(n.span(), format!("{what}: {problem}")).with_hint(MISSHAPEN_HINT),
        );
    }

    fn position(
        &self,
        src: &[u8],
        arena: &Arena,
        id: u32,
        kind: PositionKind,
        name: Option<String>,
    ) -> Option<Position> {
        self.read_elsewhere.set(false);
        let n = arena.get(id)?;
        if n.kind != ExprKind::Aggregate {
            return None;
        }
        let span = n.span();
        let (line, column) = self.lines.line_col(span.start);
        let mut parts = arena.children(id);
        let (cartesian, joints, config, extax) = match kind {
            PositionKind::Jointtarget => {
                let rax = parts.next();
                let eax = parts.next();
                (
                    None,
                    self.nums_vec(src, arena, rax),
                    Config::None,
                    self.axes(src, arena, eax),
                )
            }
            _ => {
                let trans = parts.next();
                let rot = parts.next();
                let conf = parts.next();
                let eax = parts.next();
                (
                    Some(CartesianFields {
                        trans: self.nums::<3>(src, arena, trans),
                        orient: Some(Orientation::Quaternion(self.nums::<4>(src, arena, rot))),
                    }),
                    Vec::new(),
                    Config::Quadrants(self.nums::<4>(src, arena, conf)),
                    self.axes(src, arena, eax),
                )
            }
        };
        Some(Position {
            name: name.map(Name::from),
            kind,
            span,
            line,
            column,
            cartesian,
            joints,
            config,
            extax,
            usage: Usage::default(),
        })
    }

    /// Packs the scalar robtarget `[[x,y,z],[q1..q4],[cf1..cfx],[eax..]]` at `id` declared as
    /// `name` straight from the arena, when it has these four parts, its fields are all
    /// literals the numeric scan read that fit the compact form, and its name is ASCII: what
    /// [`Extractor::position`] and [`Extractor::push`] give for it, without building a
    /// [`Position`]. `false` (nothing pushed) for any other shape, which the general path reads.
    fn push_read_again(&mut self, src: &[u8], arena: &Arena, id: u32, name: Span) -> bool {
        if !name.slice(src).is_ascii() {
            return false;
        }
        let Some(literal) = Self::literal_in(arena, id) else {
            return false;
        };
        self.push_literal(src, &literal, name);
        // Every test run holds the packed target to what the general path reads.
        #[cfg(debug_assertions)]
        self.assert_read_as_general(src, arena, id, name);
        true
    }

    /// The robtarget literal at `id` as [`Parser::robtarget_literal`](super::parser) reads
    /// it, from the arena: four parts, all literals the numeric scan read that pack.
    fn literal_in(arena: &Arena, id: u32) -> Option<RobtargetLiteral> {
        let n = arena.get(id).filter(|n| n.kind == ExprKind::Aggregate)?;
        // Each child of `part` a literal read while scanning, that packs: their starts.
        let starts = |part: Option<u32>, out: &mut [usize]| -> Option<usize> {
            let part = arena.get(part?).filter(|n| n.kind == ExprKind::Aggregate)?;
            let mut count = 0;
            let mut next = part.first;
            while let Some(c) = arena.get(next) {
                let lit = arena.lit(c).filter(|_| c.kind == ExprKind::Num)?;
                lit.pack(c.span().len())?;
                *out.get_mut(count)? = c.start as usize;
                count += 1;
                next = c.next;
            }
            Some(count)
        };
        let mut literal = RobtargetLiteral::EMPTY;
        let mut parts = arena.children(id);
        // Six external axes, as the type has: any other count is read (and reported) by the
        // general path.
        let (Some(3), Some(4), Some(4), Some(axes @ 6), None) = (
            starts(parts.next(), &mut literal.trans),
            starts(parts.next(), &mut literal.quaternion),
            starts(parts.next(), &mut literal.quadrants),
            starts(parts.next(), &mut literal.extax),
            parts.next(),
        ) else {
            return None;
        };
        // The values the lints' verdict reads, of the four literals of a part just read (read
        // here rather than while gathering the starts, which slowed every part's loop more).
        let values = |part: Option<u32>, out: &mut [f64; 4]| {
            for (o, c) in out
                .iter_mut()
                .zip(part.map(|p| arena.children(p)).into_iter().flatten())
            {
                *o = arena
                    .get(c)
                    .and_then(|n| arena.lit(n))
                    .map_or(f64::NAN, |l| l.value());
            }
        };
        let mut parts = arena.children(id).skip(1);
        values(parts.next(), &mut literal.q);
        values(parts.next(), &mut literal.cf);
        literal.axes = axes;
        literal.span = n.span();
        Some(literal)
    }

    /// Packs robtarget `literal` declared as `name` (ASCII).
    fn push_literal(&mut self, src: &[u8], literal: &RobtargetLiteral, name: Span) {
        self.push_literal_named(literal, Some(name.slice(src)));
    }

    /// The robtarget `literal` the parser read as a call's first argument: packed as a
    /// declaration's is, with no name, and one of the call's inline targets when it has a
    /// record (`of_call`, as the general path finds it in the call's expressions). Debug
    /// builds hold it to what the general path reads of the arena's aggregate of its span
    /// (the parser's reading of the call again).
    fn push_inline_literal(
        &mut self,
        src: &[u8],
        arena: &Arena,
        literal: &RobtargetLiteral,
        of_call: bool,
    ) {
        if of_call {
            self.call_inline.push(self.positions.len());
        }
        self.push_literal_named(literal, None);
        #[cfg(debug_assertions)]
        {
            let id = arena
                .nodes
                .iter()
                .position(|n| n.kind == ExprKind::Aggregate && n.span() == literal.span);
            let id = id.expect("a debug build's arena holds the general path's reading");
            assert_eq!(
                Self::literal_kind(arena, id as u32),
                Some(PositionKind::Robtarget)
            );
            assert_eq!(
                Self::shape_problem(arena, id as u32, PositionKind::Robtarget),
                None
            );
            self.assert_read_as_general_named(src, arena, id as u32, None);
        }
        #[cfg(not(debug_assertions))]
        let _ = (src, arena);
    }

    /// Packs robtarget `literal`, declared as `name` (ASCII) or written inline.
    fn push_literal_named(&mut self, literal: &RobtargetLiteral, name: Option<&[u8]>) {
        let (line, column) = self
            .lines
            .line_col_from(&mut self.line_cursor, literal.span.start);
        self.positions.push_read_again(&ReadAgainTarget {
            span: literal.span,
            kind: PositionKind::Robtarget,
            name,
            line,
            column,
            trans: literal.trans,
            quaternion: literal.quaternion,
            quadrants: literal.quadrants,
            extax: &literal.extax[..literal.axes],
            values_pass_lints: crate::report::check::robtarget_values_pass_lints(
                literal.q, literal.cf,
            ),
        });
    }

    /// Asserts that the target last pushed is what the general path reads of the robtarget
    /// at `id` declared as `name`.
    #[cfg(debug_assertions)]
    fn assert_read_as_general(&mut self, src: &[u8], arena: &Arena, id: u32, name: Span) {
        self.assert_read_as_general_named(src, arena, id, Some(name));
    }

    /// [`Extractor::assert_read_as_general`] of a robtarget declared as `name` or, `None`,
    /// written inline.
    #[cfg(debug_assertions)]
    fn assert_read_as_general_named(
        &mut self,
        src: &[u8],
        arena: &Arena,
        id: u32,
        name: Option<Span>,
    ) {
        let name = name.map(|n| text_of(src, n));
        let general = self.position(src, arena, id, PositionKind::Robtarget, name);
        assert!(!self.read_elsewhere.replace(false));
        let last = self.positions.len() - 1;
        assert_eq!(self.positions.get(last, src), general);
    }

    /// The elements of a declared value with `dims` array dimensions, with their 1-based
    /// indices (`[]` for a scalar).
    fn elements(
        arena: &Arena,
        id: u32,
        dims: u8,
        prefix: &mut Vec<usize>,
        out: &mut Vec<(String, u32)>,
    ) {
        if dims == 0 {
            let suffix = if prefix.is_empty() {
                String::new()
            } else {
                let idx: Vec<String> = prefix.iter().map(usize::to_string).collect();
                format!("{{{}}}", idx.join(","))
            };
            out.push((suffix, id));
            return;
        }
        if arena.get(id).is_some_and(|n| n.kind == ExprKind::Aggregate) {
            for (k, child) in arena.children(id).enumerate() {
                prefix.push(k + 1);
                Self::elements(arena, child, dims - 1, prefix, out);
                prefix.pop();
            }
        }
    }

    fn bool_of(src: &[u8], arena: &Arena, id: Option<u32>) -> Option<bool> {
        let n = arena.get(id?)?;
        if n.kind != ExprKind::Ident {
            return None;
        }
        let t = n.span().slice(src);
        if t.eq_ignore_ascii_case(b"TRUE") {
            Some(true)
        } else if t.eq_ignore_ascii_case(b"FALSE") {
            Some(false)
        } else {
            None
        }
    }

    fn frame(
        &self,
        src: &[u8],
        arena: &Arena,
        id: Option<u32>,
        kind: FrameKind,
        name: String,
        decl_span: Span,
    ) -> FrameDecl {
        let agg = id.filter(|&i| arena.get(i).is_some_and(|n| n.kind == ExprKind::Aggregate));
        let span = agg
            .and_then(|i| arena.get(i))
            .map_or(decl_span, |n| n.span());
        let mut f = FrameDecl {
            name,
            kind,
            span,
            line: self.lines.line(span.start),
            held_by_robot: None,
            fixed: None,
            moved_by: None,
            frame: None,
            oframe: None,
            scope: FrameScope::Program,
            storage: FrameStorage::Persistent,
            assigned: false,
        };
        let Some(agg) = agg else {
            return f;
        };
        let parts: Vec<u32> = arena.children(agg).take(5).collect();
        let part = |i: usize| parts.get(i).copied();
        f.held_by_robot = Self::bool_of(src, arena, part(0));
        match kind {
            FrameKind::WorkObject => {
                f.fixed = Self::bool_of(src, arena, part(1));
                f.moved_by = part(2)
                    .and_then(|i| arena.get(i))
                    .filter(|n| n.kind == ExprKind::Str)
                    .map(|n| {
                        let t = text_of(src, n.span());
                        t.trim_matches('"').replace("\"\"", "\"")
                    });
                f.frame = self.pose_fields(src, arena, part(3));
                f.oframe = self.pose_fields(src, arena, part(4));
            }
            _ => f.frame = self.pose_fields(src, arena, part(1)),
        }
        f
    }

    /// Inline target literals and `Offs`/`RelTool` calls anywhere in the statement's
    /// expressions. Returns the indices of the positions added.
    fn scan(&mut self, src: &[u8], arena: &Arena, literals: bool) -> (Vec<usize>, Vec<Span>) {
        let mut added = Vec::new();
        let mut refs = Vec::new();
        let mut skip_until = 0u32;
        for (i, n) in arena.nodes.iter().enumerate() {
            let i = i as u32;
            match n.kind {
                ExprKind::Aggregate if literals && i >= skip_until => {
                    if let Some(kind) = Self::literal_kind(arena, i)
                        && let Some(p) = self.position(src, arena, i, kind, None)
                    {
                        self.check_shape(arena, i, kind, None);
                        added.push(self.positions.len());
                        self.push(p, src);
                        skip_until = n.subtree_end;
                    }
                }
                ExprKind::Call => {
                    let name = n.name_span().slice(src);
                    if name.eq_ignore_ascii_case(b"StrToVal") {
                        // `ok := StrToVal(text, pp);` reads a value into its second argument.
                        self.value_read_into(src, arena, i);
                        continue;
                    }
                    if name.eq_ignore_ascii_case(b"CalcJointT") {
                        // The joints that reach the target in the work object given: a use of
                        // the target there, as a motion to it is.
                        self.expression_call_use(src, arena, i);
                        continue;
                    }
                    let kind = if name.eq_ignore_ascii_case(b"Offs") {
                        OffsetKind::Offs
                    } else if name.eq_ignore_ascii_case(b"RelTool") {
                        OffsetKind::RelTool
                    } else {
                        continue;
                    };
                    let mut positional = Vec::new();
                    let mut rot: [Option<NumField>; 3] = [None, None, None];
                    let mut rot_expression = [false; 3];
                    for a in arena.children(i) {
                        let Some(arg) = arena.get(a) else { continue };
                        let value = arena
                            .arg_value(a)
                            .filter(|_| arg.first != super::expr::NONE);
                        if arg.switch {
                            let nm = arg.name_span().slice(src);
                            let slot = if nm.eq_ignore_ascii_case(b"Rx") {
                                0
                            } else if nm.eq_ignore_ascii_case(b"Ry") {
                                1
                            } else if nm.eq_ignore_ascii_case(b"Rz") {
                                2
                            } else {
                                continue;
                            };
                            if let (Some(v), Some(r)) = (value, rot.get_mut(slot)) {
                                *r = self.num(src, arena, v);
                            }
                            if let (Some(e), Some(r)) =
                                (rot_expression.get_mut(slot), rot.get(slot))
                            {
                                *e = value.is_some() && r.is_none();
                            }
                        } else if let Some(v) = value {
                            positional.push(v);
                        }
                    }
                    let target = positional
                        .first()
                        .and_then(|&v| arena.get(v))
                        .map(|v| text_of(src, v.span()))
                        .unwrap_or_default();
                    if let Some(v) = positional.first().and_then(|&v| arena.get(v))
                        && matches!(v.kind, ExprKind::Ident | ExprKind::Access)
                    {
                        refs.push(v.span());
                    }
                    let delta =
                        [1, 2, 3].map(|k| positional.get(k).and_then(|&v| self.num(src, arena, v)));
                    let span = n.span();
                    self.offset_refs
                        .push((self.current, offset_reference(arena, positional.first())));
                    self.offsets.push(OffsetCall {
                        kind,
                        span,
                        line: self.lines.line(span.start),
                        target,
                        delta,
                        rot,
                        rot_expression,
                        bases: Vec::new(),
                    });
                }
                _ => {}
            }
        }
        (added, refs)
    }

    /// Resolves usage and lints of one module on its own; consumes the extractor.
    pub fn finish(self, src: &[u8]) -> Extracted {
        // One module: no use is in another file, so its name is never shown.
        finish_task(vec![(self, src, Arc::from(""))])
            .pop()
            .unwrap_or(Extracted {
                positions: PositionList::new(),
                frames: Vec::new(),
                frame_values: Vec::new(),
                offsets: Vec::new(),
                diagnostics: Vec::new(),
            })
    }
}

/// The reference an `Offs`/`RelTool` call's offset is taken from, given the call's first
/// argument: the argument when it is a name (`p10`, `pGrid{r,c}`), else the first argument of
/// the call written there (`Offs(RelTool(pBed, …), …)`), and so on in; a function called
/// without one (`Offs(getP(), …)`) by its name, which reaches what the function returns; `None`
/// for anything else (an expression the program computes).
fn offset_reference(arena: &Arena, first: Option<&u32>) -> Option<Span> {
    let mut at = *first?;
    loop {
        let n = arena.get(at)?;
        match n.kind {
            ExprKind::Ident | ExprKind::Access => return Some(n.span()),
            // A child's index is past its parent's: the walk ends.
            ExprKind::Call => {
                match arena
                    .children(at)
                    .filter(|&a| arena.get(a).is_some_and(|arg| !arg.switch))
                    .find_map(|a| arena.arg_value(a))
                {
                    Some(first) => at = first,
                    None => return Some(n.name_span()),
                }
            }
            _ => return None,
        }
    }
}

/// Whether expression `id` is a literal known offline: numbers, strings, `TRUE`/`FALSE` and
/// aggregates of them (no name, call or operator).
/// The hint of an error about a target literal's shape ([`Extractor::check_shape`]).
const MISSHAPEN_HINT: &str = "the controller does not load the module: write the value with the parts of its type; trackfix transforms no file with an error";

/// Whether the text at `span` names a value whole: a name, or an element of an array
/// (`p10`, `buf{i}`), not a part of one (`p10.trans`) nor a computed value.
fn is_reference(src: &[u8], span: Span) -> bool {
    let text = span.slice(src);
    let name = text
        .iter()
        .position(|b| !(b.is_ascii_alphanumeric() || *b == b'_'))
        .unwrap_or(text.len());
    let rest = text.get(name..).unwrap_or_default();
    name > 0
        && text.first().is_some_and(|b| !b.is_ascii_digit())
        && (rest.is_empty() || (rest.first() == Some(&b'{') && rest.last() == Some(&b'}')))
        && !rest.contains(&b'.')
}

/// Whether a call statement of this name reads or writes data other than through its
/// arguments' values (`GetDataVal`, `SetDataVal`, `SetAllDataVal`, `Add`, `Incr`, `Decr`,
/// `Clear`) or calls a routine named at run time (`%pn%`): told by its first letter first, as
/// a module's motions (`Move…`) pass here.
#[inline(always)]
fn writes_data_by_name(name: &[u8]) -> bool {
    match name.first().map(u8::to_ascii_uppercase) {
        Some(b'%') => true,
        Some(b'G' | b'S' | b'A' | b'I' | b'D' | b'C') => {
            DATA_WRITERS.iter().any(|w| name.eq_ignore_ascii_case(w))
        }
        _ => false,
    }
}

const DATA_WRITERS: [&[u8]; 7] = [
    b"GetDataVal",
    b"SetDataVal",
    b"SetAllDataVal",
    b"Add",
    b"Incr",
    b"Decr",
    b"Clear",
];

/// The text inside a string literal's quotes (`p10` of `"p10"`).
fn string_inside(src: &[u8], span: Span) -> Option<Span> {
    let text = span.slice(src);
    (text.len() >= 2 && text.first() == Some(&b'"') && text.last() == Some(&b'"'))
        .then(|| Span::new(span.start + 1, span.end - 1))
}

/// The name a write into `span` gives a value, without a component (`pp` of `pp.trans.z`,
/// `arr{i}` of `arr{i}.trans`).
fn written_name(src: &[u8], span: Span) -> Span {
    let text = span.slice(src);
    let end = text.iter().position(|&b| b == b'.').unwrap_or(text.len());
    let mut end = span.start + end;
    while end > span.start && src.get(end - 1).is_some_and(u8::is_ascii_whitespace) {
        end -= 1;
    }
    Span::new(span.start, end)
}

/// Whether `span` is a name with indexes and components (`rec.p`, `arr{i}.where`): data a
/// value can be written into.
fn is_path(src: &[u8], span: Span) -> bool {
    let text = span.slice(src);
    text.first()
        .is_some_and(|b| b.is_ascii_alphabetic() || *b == b'_')
        && !text.contains(&b'(')
        && !text.contains(&b'"')
        && !text.contains(&b':')
}

/// The names an expression's text reads (`Offs(p10,0,0,dz)`: `Offs`, `p10`, `dz`), each
/// from its start to the end of its word, without components (`.trans`), argument labels
/// (`\WObj`), numbers or strings, nor what a `CalcJointT` reads: what a value computed from
/// the expression may copy.
fn names_in(src: &[u8], span: Span, out: &mut Vec<Span>) {
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut i = span.start;
    let mut before = 0u8;
    while i < span.end {
        let Some(&b) = src.get(i) else { break };
        if b == b'"' {
            i += 1;
            while i < span.end && src.get(i) != Some(&b'"') {
                i += 1;
            }
            i += 1;
            before = b'"';
            continue;
        }
        if word(b) {
            let start = i;
            while i < span.end && src.get(i).copied().is_some_and(word) {
                i += 1;
            }
            let name = Span::new(start, i);
            if name.slice(src).eq_ignore_ascii_case(b"CalcJointT") {
                // Joints, the same whatever the work object a motion to them names: its own
                // use is recorded where it is written (`Extractor::expression_call_use`).
                let mut depth = 0usize;
                while i < span.end {
                    match src.get(i) {
                        Some(b'(') => depth += 1,
                        Some(b')') if depth <= 1 => break,
                        Some(b')') => depth -= 1,
                        _ => {}
                    }
                    i += 1;
                }
                i += 1;
                before = b')';
                continue;
            }
            if !b.is_ascii_digit() && before != b'.' && before != b'\\' {
                out.push(name);
            }
            before = b'a';
            continue;
        }
        if !b.is_ascii_whitespace() {
            before = b;
        }
        i += 1;
    }
}

fn is_literal(src: &[u8], arena: &Arena, id: u32) -> bool {
    let Some(n) = arena.get(id) else {
        return false;
    };
    match n.kind {
        ExprKind::Num | ExprKind::Str => true,
        ExprKind::Ident => {
            let t = n.span().slice(src);
            t.eq_ignore_ascii_case(b"TRUE") || t.eq_ignore_ascii_case(b"FALSE")
        }
        ExprKind::Aggregate => arena.children(id).all(|c| is_literal(src, arena, c)),
        _ => false,
    }
}

/// Resolves usage over the modules of one task (one RAPID program), in the order given, with
/// the shared pass (`resolve::Binder`): this finds the facts it binds in RAPID's terms
/// (a call's work object `\WObj:=` or `wobj0`, its tool `\Tool:=` or the argument after the
/// zone, a stationary tool from the work object's `robhold`), and reports the names declared
/// twice in a module. Returns one [`Extracted`] per module, in order.
pub fn finish_task(modules: Vec<(Extractor<'_>, &[u8], Arc<str>)>) -> Vec<Extracted> {
    let mut diagnostics: Vec<Vec<Diagnostic>> = vec![Vec::new(); modules.len()];
    // The types of all names in the task; duplicate module-scope names, per module.
    let (type_of, twice) =
        crate::resolve::declarations(modules.iter().map(|(x, src, _)| (*src, &x.declared)));
    for t in twice {
        let (Some((x, src, _)), Some(d)) = (modules.get(t.file), diagnostics.get_mut(t.file))
        else {
            continue;
        };
        let line = x.lines.line(t.first.start);
        d.push(
            Diagnostic::warning(
                t.again,
                format!(
                    "`{}` is declared twice in the module (first on line {line})",
                    text_of(src, t.again)
                ),
            )
            .with_hint("rename or remove one declaration; RAPID names are case-insensitive"),
        );
    }
    let kinds = ArgKinds::new(&type_of);
    let mut positions: Vec<PositionList> = Vec::with_capacity(modules.len());
    let mut calls: Vec<Calls> = Vec::with_capacity(modules.len());
    let mut rest = Vec::with_capacity(modules.len());
    let mut names = Vec::with_capacity(modules.len());
    let mut assigned_literals = Vec::with_capacity(modules.len());
    let mut param_assignments = Vec::with_capacity(modules.len());
    let mut param_writes = Vec::with_capacity(modules.len());
    let mut offset_refs = Vec::with_capacity(modules.len());
    let mut passed = Vec::with_capacity(modules.len());
    let mut named_at_run_time = Vec::with_capacity(modules.len());
    let mut skeletons = Vec::with_capacity(modules.len());
    for (m, (x, src, name)) in modules.into_iter().enumerate() {
        if let Some(d) = diagnostics.get_mut(m) {
            d.extend(x.misshapen);
        }
        names.push(name);
        assigned_literals.push(x.assigned_literals);
        param_assignments.push(x.param_assignments);
        param_writes.push(x.param_writes);
        offset_refs.push(x.offset_refs);
        passed.push(x.passed);
        named_at_run_time.push(x.named_at_run_time);
        skeletons.push(x.skeleton);
        calls.push(Calls {
            uses: x.uses,
            args: x.call_args,
            refs: x.call_refs,
            inline: x.call_inline,
        });
        positions.push(x.positions);
        rest.push((
            x.frames, x.offsets, x.assigned, x.computed, x.routines, x.exported, src, x.copies,
        ));
    }
    let robhold: NameMap<NameKey, bool> = rest
        .iter()
        .flat_map(|r| &r.0)
        .filter(|f| f.kind == FrameKind::WorkObject)
        .filter_map(|f| Some((NameKey(f.name.as_bytes()), f.held_by_robot?)))
        .collect();
    // The modules' file names, for a message on one module's target about another's line.
    let module_names: Vec<Arc<str>> = names.clone();
    let mut facts: Vec<crate::resolve::FileFacts<'_>> = positions
        .iter_mut()
        .zip(&rest)
        .zip(names)
        .enumerate()
        .map(|(m, ((ps, r), name))| crate::resolve::FileFacts {
            name,
            // A RAPID module is one file.
            module: m,
            src: r.6,
            positions: ps,
            exported: Some(&r.5),
            frames: &r.0,
            routines: &r.4,
            assignments: &r.3,
            copies: &r.7,
        })
        .collect();
    let mut binder = crate::resolve::Binder::new(&mut facts, &NAMING);
    // Two modules may each declare a `LOCAL` work object of one name, one holding the tool and
    // the other not: such a module's motions see its own (a map of their own, in the rare
    // task that has one).
    let own_robhold: Vec<Option<NameMap<NameKey, bool>>> = rest
        .iter()
        .map(|r| {
            let own: Vec<(NameKey, bool)> =
                r.0.iter()
                    .filter(|f| f.kind == FrameKind::WorkObject)
                    .filter_map(|f| Some((NameKey(f.name.as_bytes()), f.held_by_robot?)))
                    .collect();
            own.iter()
                .any(|(k, v)| robhold.get(k) != Some(v))
                .then(|| robhold.clone().into_iter().chain(own).collect())
        })
        .collect();
    let mut frame_texts = FrameTexts::new(&robhold);
    let wobj0 = frame_texts.get(b"wobj0");
    let scopes = FrameScopes::new(rest.iter().map(|r| r.0.as_slice()));
    let routine_lists: Vec<(&[u8], &[crate::resolve::Routine])> =
        rest.iter().map(|r| (r.6, r.4.as_slice())).collect();
    // (module, target, line, the motion's module) of each target a motion reaches with a frame
    // its name means another declaration of for the target's module (a `LOCAL` or a routine's
    // own frame).
    let mut unresolved: Vec<(usize, usize, usize, usize, String)> = Vec::new();
    // (frame, module, line) of each frame a call passes to a routine's parameter that the
    // routine gives a value.
    let mut written_through_parameters: Vec<(String, usize, usize)> = Vec::new();
    let any_param_writes = param_writes.iter().any(|w| !w.is_empty());
    let mut flow = Flow {
        skeletons,
        task: None,
    };
    // The frames the program gives a whole value (docs/design.md, "Frames the program
    // assigns"): what each motion's targets are moved to in is known before they are bound.
    let FramesGiven {
        notes: mut assigned_notes,
        reassigned,
        replaced,
        own_values,
        declared_first,
    } = frames_given(
        &rest,
        &mut flow,
        &calls,
        &routine_lists,
        &scopes,
        &kinds,
        &module_names,
    );
    // The instructions that activate or end a displacement, and the calls that may run while
    // one is active (docs/design.md, "Program displacement and axes offset"); per displaced
    // call, the instruction named and the targets and routine parameters its binding reaches.
    let displacements = displacing(&calls, &rest);
    let displaced = if displacements.iter().any(|d| d.moves) {
        displaced_calls(&displacements, &calls, &rest, flow.task(&rest))
    } else {
        Default::default()
    };
    // (The routines' trees are read no further.)
    drop(flow);
    let mut displaced_reach: Vec<(usize, crate::resolve::Reached)> = Vec::new();
    for (m, (module_calls, r)) in calls.iter().zip(&rest).enumerate() {
        let src = r.6;
        let mut own_texts = own_robhold
            .get(m)
            .and_then(Option::as_ref)
            .map(FrameTexts::new);
        let frame_texts = own_texts.as_mut().unwrap_or(&mut frame_texts);
        for (u, call_args, refs, inline) in module_calls.iter() {
            let call = NameKey(u.name.span().slice(src));
            // A frame or tool named by a parameter of the motion's routine is the caller's: no
            // declaration of that name is it (the motion's targets are refused as used with
            // a frame that cannot be resolved).
            let routine = u.routine.and_then(|rt| r.4.get(rt.get() as usize - 1));
            let a_parameter = |text: &[u8]| routine.is_some_and(|rt| rt.has_parameter(src, text));
            let tool = kinds.tool_of(u, call_args, src);
            let tool_named = tool.is_some();
            // (Each asked once: a motion's routine is asked for every motion.)
            let (tool, tool_parameter) = match tool {
                Some(t) if a_parameter(t) => (None, Some(t)),
                t => (t, None),
            };
            let tool = tool.map(|t| frame_texts.get(t));
            // A motion without `\WObj` moves in `wobj0` (asked only then: most name theirs).
            let motion = || {
                MOTION_PREFIXES
                    .iter()
                    .any(|p| call.starts_with(p.as_bytes()))
            };
            let mut wobj_parameter = None;
            let wobj = match u.wobj {
                Some(sp) => {
                    let w = trim_latin1(sp.span().slice(src));
                    if a_parameter(w) {
                        wobj_parameter = Some(w);
                        None
                    } else {
                        Some(frame_texts.get(w))
                    }
                }
                None => (tool_named || motion()).then(|| wobj0.clone()),
            };
            let stationary = wobj.as_ref().is_some_and(|w| w.robhold);
            let call_use = crate::resolve::Use {
                line: u.line as usize,
                routine: u.routine.map(|r| r.get() as usize - 1),
                callee: Some(u.name.span()),
                stationary,
                frame: wobj.map(|w| w.name),
                tool: tool.map(|t| t.name),
                run_time: None,
                two_values: (!declared_first.is_empty())
                    .then(|| declared_first.get(&(m, u.name.span().start)).cloned())
                    .flatten(),
                passed: (wobj_parameter.is_some() || tool_parameter.is_some()).then(|| {
                    let text = |t: &[u8]| String::from_utf8_lossy(t).into_owned();
                    std::sync::Arc::new(crate::resolve::PassedFrames {
                        frame: wobj_parameter.map(text),
                        tool: tool_parameter.map(text),
                    })
                }),
                args: call_args,
                refs,
                folded: &[],
                targets: inline,
                writes: false,
            };
            let displacements = (!displaced.is_empty())
                .then(|| displaced.get(&(m, u.name.span().start)))
                .flatten();
            if displacements.is_some() {
                binder.collect_reached();
            }
            match non_position_arguments(call.0) {
                None => binder.bind(m, &call_use),
                Some(zone) => bind_non_positions(&mut binder, m, &call_use, zone),
            }
            if let Some(list) = displacements {
                let reached = binder.collected();
                for &i in list {
                    displaced_reach.push((i, reached.clone()));
                }
            }
            if !scopes.is_empty() {
                let routine = call_use.routine;
                for name in [&call_use.frame, &call_use.tool].into_iter().flatten() {
                    let Some(bound) = scopes.seen_from(m, routine, name) else {
                        continue;
                    };
                    for &(tm, i) in binder.reached() {
                        if bound.routine || scopes.seen_from(tm, None, name) != Some(bound) {
                            unresolved.push((tm, i, call_use.line, m, name.to_string()));
                        }
                    }
                }
            }
            if any_param_writes {
                let callee = u.name.span().slice(src);
                written_through_parameters.extend(frames_written_through(
                    &routine_lists,
                    &param_writes,
                    (m, callee, call_args),
                    &scopes,
                ));
            }
        }
    }
    // Arguments positional binding does not see: composed (`mv Offs(p10, 0, 0, 10);`) or
    // named (`mv \p:=p10;`).
    for (m, list) in passed.iter().enumerate() {
        for (a, names) in list.iter() {
            binder.bind_passed(m, a, names);
        }
    }
    // Each offset call's bases: the targets its reference names where the call is written, or,
    // for a parameter of its routine, those the calls pass there.
    let mut offset_bases: Vec<Vec<Vec<(usize, usize)>>> = Vec::with_capacity(rest.len());
    for (m, (refs, r)) in offset_refs.iter().zip(&rest).enumerate() {
        let (src, routines) = (r.6, &r.4);
        let mut bases = Vec::with_capacity(refs.len());
        for &(routine, reference) in refs {
            let mut found = Vec::new();
            if let Some(raw) = reference.map(|sp| sp.slice(src)) {
                let name = raw
                    .split(|&b| b == b'{')
                    .next()
                    .unwrap_or(raw)
                    .trim_ascii_end();
                let parameter = routine.and_then(|rt| {
                    let k = routines.get(rt)?.required_named(src, name)?;
                    Some((m, rt, k))
                });
                match parameter {
                    Some(at) => binder.targets_bound_to(at, &mut found),
                    None => binder.targets_named(m, raw, &mut found),
                }
            }
            bases.push(found);
        }
        offset_bases.push(bases);
    }
    // A late call's arguments go to a routine chosen at run time, in any work object: each
    // target they name is refused naming the call.
    let mut every_target: Option<(usize, usize, Span)> = None;
    for (m, list) in named_at_run_time.iter().enumerate() {
        let src = rest.get(m).map_or(&[][..], |r| r.6);
        for (call, line, names) in list {
            let Some(names) = names else {
                every_target.get_or_insert((m, *line, *call));
                continue;
            };
            let mut found = Vec::new();
            for sp in names {
                binder.targets_named(m, sp.slice(src), &mut found);
            }
            let call = latin1(call.slice(src));
            binder.mark(m, &found, |file, usage| {
                usage.set_run_time(RunTimeValue::NamedAtRunTime {
                    call: call.clone(),
                    at: UseLine {
                        line: *line,
                        file: file.cloned(),
                    },
                });
            });
        }
    }
    // A computed value given to a parameter: a use of it with that value, which the binder
    // hands on to the targets the routine's calls pass there.
    for (m, list) in param_assignments.iter().enumerate() {
        for &(routine, param, line) in list {
            binder.bind_computed_parameter(m, routine, param, line);
        }
    }
    // A displaced motion to a routine's parameter moves to the targets its calls pass there.
    let displaced_reach: Vec<(usize, Vec<(usize, usize)>)> = displaced_reach
        .into_iter()
        .map(|(i, (mut targets, params))| {
            for p in params {
                binder.targets_bound_to(p, &mut targets);
            }
            (i, targets)
        })
        .collect();
    binder.finish();
    crate::resolve::mark_run_time(&mut facts, &NAMING);
    mark_displaced(&mut facts, &displacements, &displaced_reach);
    share_assigned_usage(&mut facts, &assigned_literals);
    drop(facts);
    // Data named at run time (`SetDataVal name, …` with `name` computed): any target of the
    // program may be read or given a value there, and any work object.
    if let Some((m, line, call)) = every_target
        && let Some((from, r)) = module_names.get(m).zip(rest.get(m))
    {
        let call = latin1(call.slice(r.6));
        for (tm, ps) in positions.iter_mut().enumerate() {
            for usage in ps.usages_mut() {
                usage.set_run_time(RunTimeValue::NamedAtRunTime {
                    call: call.clone(),
                    at: UseLine::of(line, m, tm, from),
                });
            }
        }
    }
    for (m, i, value) in replaced {
        if let Some(f) = rest.get_mut(m).and_then(|r| r.0.get_mut(i)) {
            *f = value;
        }
    }
    for (tm, i, line, m, frame) in unresolved {
        if let (Some(u), Some(from)) = (
            positions.get_mut(tm).and_then(|ps| ps.usage_mut(i)),
            module_names.get(m),
        ) {
            u.mark_unresolved_frame(crate::position::UnresolvedFrame {
                at: crate::position::UseLine::of(line, m, tm, from),
                cause: UnresolvedCause::Shadowed(frame),
            });
        }
    }
    let marked = !reassigned.is_empty() || !written_through_parameters.is_empty();
    for (tm, ps) in positions.iter_mut().enumerate().filter(|_| marked) {
        for usage in ps.usages_mut() {
            let used = |&&(ref name, kind, ..): &&(String, FrameKind, usize, usize)| match kind {
                FrameKind::Tool => usage.tools().any(|t| t.eq_ignore_ascii_case(name)),
                _ => usage.work_objects().any(|w| w.eq_ignore_ascii_case(name)),
            };
            if let Some((name, _, m, line)) = reassigned.iter().find(used)
                && let Some(from) = module_names.get(*m)
            {
                usage.set_run_time(RunTimeValue::FrameAssigned {
                    name: name.clone(),
                    at: crate::position::UseLine::of(*line, *m, tm, from),
                });
            }
            // A frame a routine's parameter gives a value: computed when the program runs.
            let passed = written_through_parameters.iter().find(|(name, ..)| {
                usage
                    .work_objects()
                    .chain(usage.tools())
                    .any(|w| w.eq_ignore_ascii_case(name))
            });
            if let Some((name, m, line)) = passed
                && let Some(from) = module_names.get(*m)
            {
                usage.set_run_time(RunTimeValue::Frame {
                    name: Some(name.clone()),
                    at: crate::position::UseLine::of(*line, *m, tm, from),
                });
            }
        }
    }
    let mut out = Vec::with_capacity(rest.len());
    for (m, (((frames, mut offsets, .., src, _), ps), bases)) in rest
        .into_iter()
        .zip(positions)
        .zip(offset_bases)
        .enumerate()
    {
        for (call, bases) in offsets.iter_mut().zip(bases) {
            call.bases = bases;
        }
        let mut d = diagnostics
            .get_mut(m)
            .map(std::mem::take)
            .unwrap_or_default();
        d.extend(
            assigned_notes
                .get_mut(m)
                .map(std::mem::take)
                .unwrap_or_default(),
        );
        let twice_used = ps
            .usages()
            .enumerate()
            .filter(|(_, u)| !u.other_wobjs().is_empty());
        for p in twice_used.filter_map(|(i, _)| ps.get(i, src)) {
            let all: Vec<&str> = p.usage.work_objects().collect();
            let lines: Vec<String> = p.usage.lines.iter().map(u32::to_string).collect();
            d.push(
                Diagnostic::warning(
                    p.span,
                    format!(
                        "target `{}` is used with {} work objects ({}) on lines {}",
                        p.label(),
                        all.len(),
                        all.join(", "),
                        lines.join(", ")
                    ),
                )
                .with_hint(
                    "a transform cannot move it for both; declare one target per work object",
                ),
            );
        }
        for p in ps
            .usages()
            .enumerate()
            .filter(|(_, u)| !u.every_two_values().is_empty())
            .filter_map(|(i, _)| ps.get(i, src))
        {
            for t in p.usage.every_two_values() {
                // A track correction is the same in both values of a tool; what the tool
                // places is the flange, so the joints.
                let hint = match t.kind {
                    FrameKind::Tool => {
                        "its joints differ in the two values, so a transform that checks them or mirrors the tool cannot take it for both; give the tool its value before every motion to the target"
                    }
                    _ => {
                        "a transform cannot move it for both values; give the work object its value before every motion to the target"
                    }
                };
                d.push(
                    Diagnostic::warning(
                        p.span,
                        format!("target `{}` is moved to with {t}", p.label()),
                    )
                    .with_hint(hint),
                );
            }
        }
        let frame_values = own_values
            .iter()
            .filter(|(vm, _)| *vm == m)
            .map(|(_, v)| v.clone())
            .collect();
        out.push(Extracted {
            positions: ps,
            frames,
            frame_values,
            offsets,
            diagnostics: d,
        });
    }
    out
}

impl Extractor<'_> {
    /// Keeps the module's skeleton tree, read by the flow of a frame the program gives a value
    /// (`rapid::flow`), when the module gives one; a module that gives none drops it before
    /// the task's usage is resolved, where memory peaks (and is parsed again for the flow of a
    /// displacement: looking for one here cost every module 0.3 % of `check`).
    pub(super) fn keep_skeleton(&mut self, nodes: Vec<super::Node>) {
        if !self.assigned.is_empty() {
            self.skeleton = Some(nodes);
        }
    }

    pub(super) fn statement(&mut self, statement: Statement<'_>) {
        let Statement {
            src,
            arena,
            stmt,
            span,
            literal,
            plain_args,
            moved,
        } = statement;
        match *stmt {
            Stmt::Decl {
                storage,
                type_name,
                name,
                dims,
                init,
                module_scope,
                local,
            } => {
                if module_scope {
                    self.current = None;
                }
                let before = self.positions.len();
                let frames_before = self.frames.len();
                self.statement_decl(
                    src,
                    arena,
                    type_name,
                    name,
                    dims,
                    init,
                    literal,
                    module_scope,
                );
                let exported = module_scope && !local;
                self.exported.resize(before, false);
                self.exported.resize(self.positions.len(), exported);
                let scope = match (module_scope, self.current) {
                    (false, Some(r)) => FrameScope::Routine(r),
                    _ if local => FrameScope::Module,
                    _ => FrameScope::Program,
                };
                let storage = match storage {
                    Storage::Const => FrameStorage::Constant,
                    Storage::Var => FrameStorage::Variable,
                    Storage::Pers | Storage::Alias => FrameStorage::Persistent,
                };
                for f in self.frames.get_mut(frames_before..).into_iter().flatten() {
                    f.scope = scope;
                    f.storage = storage;
                }
            }
            Stmt::Routine { name, local } => {
                // Past 4 GiB a name has no 32-bit span: no input is this large (see `Span32`).
                if let Some(n) = Span32::of(name) {
                    self.declared.declare(src, n, DeclKind::Other, true);
                }
                self.current = Some(self.routines.len());
                self.routines.push(crate::resolve::Routine {
                    name,
                    local,
                    params: Vec::new(),
                    optional: Vec::new(),
                });
            }
            Stmt::Param { name, optional } => {
                if let Some(r) = self.current.and_then(|r| self.routines.get_mut(r)) {
                    if optional {
                        r.optional.push(name);
                    } else {
                        r.params.push(name);
                    }
                }
            }
            Stmt::Record { name } => self.records.push(RecordDecl {
                name,
                fields: Vec::new(),
            }),
            Stmt::RecordField { type_name, name } => {
                if let Some(r) = self.records.last_mut() {
                    r.fields.push((type_name, name));
                }
            }
            Stmt::Call { name, args } => {
                // Every test run records a call a fast path read (taken from the call before,
                // or with a literal) from its arguments first, plain or (with a literal, a
                // debug build's `args`) the general path's reading, and holds the fast path's
                // record to that one: everything the record adds to any list.
                #[cfg(debug_assertions)]
                let read = (moved.is_some() || literal.is_some()).then(|| {
                    let plain = plain_args.filter(|_| literal.is_none());
                    self.recorded_as_read(src, arena, name, args, plain, span)
                });
                // A call taken from the one before records its use alone, as that one did.
                let use_alone = moved.is_some_and(|m| self.call_like_last(src, name, &m, span))
                    || self.statement_call(src, arena, name, args, plain_args, literal, span);
                #[cfg(debug_assertions)]
                if let Some((since, read)) = read {
                    let fast = self.recorded_since(src, &since);
                    assert_eq!(fast, read, "a call a fast path read");
                }
                // A call read as this one copies its use and its arguments: only a call whose
                // record is those alone may be copied, not one that passes an argument by
                // name or writes data by name. A call with a literal is none a call read from
                // it repeats (the parser moves no call's arguments from it).
                self.last_plain_call =
                    (plain_args.is_some() && literal.is_none() && use_alone).then_some(span.start);
            }
            Stmt::Assign { target, value } => {
                let before = self.positions.len();
                self.scan(src, arena, true);
                let literal = is_literal(src, arena, value);
                let whole = target
                    .slice(src)
                    .iter()
                    .all(|b| b.is_ascii_alphanumeric() || *b == b'_');
                let aggregate = arena.get(value).filter(|v| v.kind == ExprKind::Aggregate);
                // The routine's own parameter or data of the name hides module data of it: an
                // assignment to a parameter gives the caller's argument its value.
                let text = text_of(src, target);
                let head = text.split(['.', '{']).next().unwrap_or_default().trim();
                let key = NameKey(head.as_bytes());
                let own_param = self.current.and_then(|r| {
                    let routine = self.routines.get(r)?;
                    let p = routine.params.get(routine.required_named(src, key.0)?)?;
                    Some((r, Span32::of(*p)?))
                });
                let routine_data = self.current.is_some_and(|r| {
                    self.frames.iter().any(|f| {
                        f.scope == FrameScope::Routine(r) && NameKey(f.name.as_bytes()) == key
                    })
                });
                if let Some((r, p)) = own_param {
                    self.param_writes.push((r, p, self.lines.line(span.start)));
                }
                if whole && literal && aggregate.is_some() {
                    if own_param.is_none() && !routine_data {
                        let read =
                            |kind| self.frame(src, arena, Some(value), kind, String::new(), span);
                        self.assigned.push(AssignedValue {
                            name: target,
                            as_wobj: read(FrameKind::WorkObject),
                            as_tool: read(FrameKind::Tool),
                        });
                    }
                    // The whole value one target literal: a value of the name.
                    let spans = (before..self.positions.len()).map(|i| self.positions.span(i));
                    if let (Some(v), [Some(only)]) =
                        (aggregate, spans.collect::<Vec<_>>().as_slice())
                        && *only == v.span()
                    {
                        self.assigned_literals.push((target, before));
                    }
                } else if !literal || !whole {
                    // A name's value copied into another (`pv := p10;`, `buf{1} := p10;`,
                    // `rec.p := p10;`), or computed from names (`pv := Offs(p10, 0, 0, 10);`,
                    // `pv := getP();`, a function's value copying what it returns): a motion
                    // to the copy moves to what they hold, in the copy's work object.
                    if let Some(v) = arena.get(value)
                        && is_path(src, target)
                    {
                        self.copy_of(src, target, v);
                    }
                    // `p10.trans.z := 20` changes part of the value: run time as well; a
                    // tool's load (`tGrip.tload := loadPart;`, `.tload.mass`) places nothing.
                    let text = text_of(src, target);
                    let mut path = text.split('.');
                    let name = path.next().unwrap_or_default().trim();
                    if path
                        .next()
                        .is_some_and(|c| c.trim().eq_ignore_ascii_case("tload"))
                    {
                        return;
                    }
                    let line = self.lines.line(span.start);
                    let param = self.own_param(src, name.as_bytes());
                    match param {
                        // The routine's own parameter hides module data of its name.
                        Some((r, p)) => self.param_assignments.push((r, p, line)),
                        None => self.computed.push(crate::resolve::Assignment {
                            name: name.to_owned(),
                            line,
                            literal,
                        }),
                    }
                }
            }
            Stmt::Other => {
                self.scan(src, arena, true);
                self.returned_copy(src, span);
            }
        }
    }

    /// Records `copy := value` as a copy of each name `value` reads: the name itself when the
    /// value is one (`buf{1}`, kept whole), else every name in the expression.
    fn copy_of(&mut self, src: &[u8], copy: Span, value: &ExprNode) {
        let routine = self.current;
        let mut sources = Vec::new();
        if matches!(value.kind, ExprKind::Ident | ExprKind::Access) && is_path(src, value.span()) {
            sources.push(value.span());
        } else if !matches!(value.kind, ExprKind::Aggregate) {
            names_in(src, value.span(), &mut sources);
        }
        self.copies
            .extend(sources.into_iter().map(|source| crate::resolve::CopyFact {
                copy,
                source,
                routine,
            }));
    }

    /// `RETURN p10;` in a function: a call of the function, `MoveL getP(), …`, moves to what
    /// `p10` reaches, a copy of it under the function's name; `RETURN Offs(p, 0, 0, 100);`
    /// returns a copy of each name it reads (a parameter: what the callers pass there).
    fn returned_copy(&mut self, src: &[u8], span: Span) {
        let text = span.slice(src);
        let keyword = b"RETURN";
        let Some(head) = text.get(..keyword.len()) else {
            return;
        };
        if !head.eq_ignore_ascii_case(keyword) {
            return;
        }
        let Some(routine) = self.current.and_then(|r| self.routines.get(r)) else {
            return;
        };
        let mut start = span.start + keyword.len();
        let mut end = span.end;
        while start < end && src.get(start).is_some_and(u8::is_ascii_whitespace) {
            start += 1;
        }
        while end > start
            && src
                .get(end - 1)
                .is_some_and(|b| b.is_ascii_whitespace() || *b == b';')
        {
            end -= 1;
        }
        let value = Span::new(start, end);
        // `RETURN` followed by a value, not `RETURNS` nor `RETURN;`.
        if start == span.start + keyword.len() || start >= end {
            return;
        }
        let name = routine.name;
        let mut sources = Vec::new();
        if is_reference(src, value) {
            sources.push(value);
        } else {
            names_in(src, value, &mut sources);
        }
        let routine = self.current;
        self.copies
            .extend(sources.into_iter().map(|source| crate::resolve::CopyFact {
                copy: name,
                source,
                routine,
            }));
    }

    /// Records the call `name` at `span` from the call before, which it repeats with its
    /// offsets moved as `m` says (the parser took its arguments from that call's, with no
    /// label changed): the frame, the tool and the positional references are that call's,
    /// moved. `false`, recording nothing, unless the last call recorded is that one and its
    /// record was its use alone ([`Extractor::last_plain_call`]), and this one writes no data
    /// by name (its callee may be the name changed).
    fn call_like_last(&mut self, src: &[u8], name: Span, m: &MovedCall, span: Span) -> bool {
        let Some(last) = self
            .uses
            .last()
            .copied()
            .filter(|_| self.last_plain_call == Some(m.from))
        else {
            return false;
        };
        // The last call wrote no data by name: this one neither, unless its callee is the
        // name changed.
        if m.changed_by(last.name.span().end) && writes_data_by_name(name.slice(src)) {
            return false;
        }
        let moved = |s: Span32| {
            let s = s.span();
            Span32::of(Span::new(m.moved(s.start), m.moved(s.end)))
        };
        let from = last.args_start as usize;
        let Some(u) = self
            .call_head(name, span)
            .filter(|_| from <= self.call_args.len())
        else {
            return false;
        };
        self.call_args.extend_from_within(from..);
        if let Some(args) = self.call_args.get_mut(u.args_start as usize..) {
            for a in args {
                *a = a.and_then(moved);
            }
        }
        self.uses.push(CallUse {
            wobj: last.wobj.and_then(moved),
            tool: last.tool.and_then(moved),
            ..u
        });
        true
    }

    /// What recording the call `name` at `span` from its arguments records (`plain`, else the
    /// arena's `args`), and how long the lists were before it, to which they are cut back.
    #[cfg(debug_assertions)]
    fn recorded_as_read(
        &mut self,
        src: &[u8],
        arena: &Arena,
        name: Span,
        args: u32,
        plain: Option<&PlainArgs>,
        span: Span,
    ) -> (RecordLens, String) {
        let since = RecordLens::of(self);
        self.statement_call(src, arena, name, args, plain, None, span);
        let record = self.recorded_since(src, &since);
        since.cut_back(self);
        (since, record)
    }

    /// Everything a call's record added to the lists since `since`, as text.
    #[cfg(debug_assertions)]
    fn recorded_since(&self, src: &[u8], since: &RecordLens) -> String {
        let uses: Vec<_> = self.uses[since.uses..]
            .iter()
            .map(|u| (u.name, u.line, u.routine, u.wobj, u.tool))
            .collect();
        let targets: Vec<_> = (since.positions..self.positions.len())
            .map(|i| self.positions.get(i, src))
            .collect();
        let inline: Vec<_> = self.call_inline[since.call_inline..]
            .iter()
            .map(|&i| i.checked_sub(since.positions))
            .collect();
        format!(
            "{uses:?}\n{:?}\n{:?}\n{inline:?}\n{targets:?}\n{:?}\n{:?}\n{:?}\n{:?}\n{:?}\n{:?}\n{:?}",
            &self.call_args[since.call_args..],
            &self.call_refs[since.call_refs..],
            &self.passed.args[since.passed_args..],
            &self.passed.names[since.passed_names..],
            &self.misshapen[since.misshapen..],
            &self.copies[since.copies..],
            &self.computed[since.computed..],
            &self.named_at_run_time[since.named_at_run_time..],
            (
                &self.param_writes[since.param_writes..],
                &self.param_assignments[since.param_assignments..]
            ),
        )
    }

    /// The record of the call `name` at `span` before its arguments are read: its line and
    /// routine, and where its ranges of the shared lists start. `None` past 4 GiB: no input
    /// is this large (see `Span32`).
    fn call_head(&mut self, name: Span, span: Span) -> Option<CallUse> {
        let line = self
            .lines
            .line_col_from(&mut self.line_cursor, span.start)
            .0;
        Some(CallUse {
            name: Span32::of(name)?,
            line: u32::try_from(line).ok()?,
            routine: self
                .current
                .and_then(|r| u32::try_from(r + 1).ok())
                .and_then(std::num::NonZeroU32::new),
            wobj: None,
            tool: None,
            args_start: u32::try_from(self.call_args.len()).ok()?,
            refs_start: u32::try_from(self.call_refs.len()).ok()?,
            inline_start: u32::try_from(self.call_inline.len()).ok()?,
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn statement_decl(
        &mut self,
        src: &[u8],
        arena: &Arena,
        type_name: Span,
        name: Span,
        dims: u8,
        init: Option<u32>,
        literal: Option<&RobtargetLiteral>,
        module_scope: bool,
    ) {
        {
            {
                if let Some(literal) = literal {
                    // A robtarget the parser's fast path read (which the arena's value, debug
                    // builds only, must match): its type is none of those compared below, one
                    // compare each.
                    debug_assert!(type_name.slice(src).eq_ignore_ascii_case(b"robtarget"));
                    if let Some(n) = Span32::of(name) {
                        self.declared.declare(src, n, DeclKind::Other, module_scope);
                    }
                    if literal.axes != 6 {
                        // The fast path reads the three other parts at their sizes only.
                        self.misshapen.push(
                            Diagnostic::error(
                                literal.span,
                                format!(
                                    "robtarget `{}`: its external axes [eax_a,…,eax_f] has {} value{} where a robtarget takes 6",
                                    text_of(src, name),
                                    literal.axes,
                                    if literal.axes == 1 { "" } else { "s" }
                                ),
                            )
                            .with_hint(MISSHAPEN_HINT),
                        );
                    }
                    self.push_literal(src, literal, name);
                    #[cfg(debug_assertions)]
                    if let Some(id) = init {
                        self.assert_read_as_general(src, arena, id, name);
                    }
                    return;
                }
                let ty = type_name.slice(src);
                let is = |t: &[u8]| ty.eq_ignore_ascii_case(t);
                let kind = if is(b"tooldata") {
                    DeclKind::Tool
                } else if is(b"zonedata") {
                    DeclKind::Zone
                } else if is(b"speeddata") {
                    DeclKind::Speed
                } else {
                    DeclKind::Other
                };
                if let Some(n) = Span32::of(name) {
                    self.declared.declare(src, n, kind, module_scope);
                }
                let target_kind = if is(b"robtarget") {
                    Some(PositionKind::Robtarget)
                } else if is(b"jointtarget") {
                    Some(PositionKind::Jointtarget)
                } else {
                    None
                };
                let frame_kind = if is(b"wobjdata") {
                    Some(FrameKind::WorkObject)
                } else if is(b"tooldata") {
                    Some(FrameKind::Tool)
                } else {
                    None
                };
                if target_kind == Some(PositionKind::Robtarget)
                    && dims == 0
                    && init.is_some_and(|id| self.push_read_again(src, arena, id, name))
                {
                    // The statement's expressions are that literal's numbers and brackets:
                    // no call for `scan` to find.
                    #[cfg(debug_assertions)]
                    {
                        let offsets = self.offsets.len();
                        self.scan(src, arena, false);
                        assert_eq!(self.offsets.len(), offsets);
                    }
                    return;
                }
                let name_text = text_of(src, name);
                let mut elements = Vec::new();
                if let Some(init) = init {
                    Self::elements(arena, init, dims, &mut Vec::new(), &mut elements);
                }
                if let Some(kind) = target_kind {
                    let mut scalar_name = Some(name_text);
                    for (suffix, id) in &elements {
                        let full = match (suffix.is_empty(), scalar_name.take()) {
                            (true, Some(n)) => n,
                            _ => format!("{}{suffix}", text_of(src, name)),
                        };
                        self.check_shape(arena, *id, kind, Some(&full));
                        if let Some(p) = self.position(src, arena, *id, kind, Some(full)) {
                            self.push(p, src);
                        }
                    }
                    self.scan(src, arena, false);
                } else if let Some(kind) = frame_kind {
                    if elements.is_empty() {
                        let f = self.frame(src, arena, None, kind, name_text.clone(), name);
                        self.frames.push(f);
                    }
                    for (suffix, id) in &elements {
                        let f = self.frame(
                            src,
                            arena,
                            Some(*id),
                            kind,
                            format!("{name_text}{suffix}"),
                            name,
                        );
                        self.frames.push(f);
                    }
                    self.scan(src, arena, false);
                } else {
                    // A record declared in the module with target components: each element's
                    // component is a named target (`seam{1}.where`), so a move through the
                    // component finds it; any other target-shaped part is still found inline.
                    let before = self.positions.len();
                    let components: Vec<(usize, PositionKind, Span)> = self
                        .records
                        .iter()
                        .find(|r| NameKey(r.name.slice(src)) == NameKey(ty))
                        .map(|r| {
                            r.fields
                                .iter()
                                .enumerate()
                                .filter_map(|(k, &(field_ty, field))| {
                                    let t = field_ty.slice(src);
                                    let kind = if t.eq_ignore_ascii_case(b"robtarget") {
                                        PositionKind::Robtarget
                                    } else if t.eq_ignore_ascii_case(b"jointtarget") {
                                        PositionKind::Jointtarget
                                    } else {
                                        return None;
                                    };
                                    Some((k, kind, field))
                                })
                                .collect()
                        })
                        .unwrap_or_default();
                    for (suffix, id) in &elements {
                        for &(k, kind, field) in &components {
                            let Some(part) = arena.children(*id).nth(k) else {
                                continue;
                            };
                            let full = format!("{name_text}{suffix}.{}", text_of(src, field));
                            self.check_shape(arena, part, kind, Some(&full));
                            if let Some(p) = self.position(src, arena, part, kind, Some(full)) {
                                self.push(p, src);
                            }
                        }
                    }
                    let named = self.positions.len();
                    self.scan(src, arena, true);
                    if named > before {
                        let spans: Vec<Span> = (before..named)
                            .filter_map(|i| self.positions.span(i))
                            .collect();
                        let mut i = named;
                        while i < self.positions.len() {
                            if self.positions.span(i).is_some_and(|sp| spans.contains(&sp)) {
                                self.positions.remove(i);
                            } else {
                                i += 1;
                            }
                        }
                    }
                }
            }
        }
    }

    /// A call's use: its callee, line and routine, its tool and work object, its positional
    /// arguments, and the targets written in it or reached through an offset (`Offs(p10, ..)`).
    /// Arguments the parser read as plain names (`plain`) hold neither: no expression of
    /// theirs is looked at; the robtarget literal the parser read as the first of them
    /// (`literal`) is the call's inline target, packed as it was read. Whether the record is
    /// the call's use alone: no argument passed by name, no data written by name (see
    /// [`Extractor::last_plain_call`]).
    #[allow(clippy::too_many_arguments)]
    fn statement_call(
        &mut self,
        src: &[u8],
        arena: &Arena,
        name: Span,
        args: u32,
        plain: Option<&PlainArgs>,
        literal: Option<&RobtargetLiteral>,
        span: Span,
    ) -> bool {
        let (inline, via_offset) = match plain {
            Some(_) => (Vec::new(), Vec::new()),
            None => self.scan(src, arena, true),
        };
        let head = self.call_head(name, span);
        if let Some(literal) = literal {
            self.push_inline_literal(src, arena, literal, head.is_some());
        }
        let Some(mut u) = head else {
            return false;
        };
        let passed = self.passed.args.len();
        let writes = writes_data_by_name(name.slice(src));
        if writes {
            let literal = literal.map(|l| l.span);
            self.data_call(src, arena, name, args, plain, literal, span);
        }
        self.call_refs.extend(via_offset);
        self.call_inline.extend(inline);
        match plain {
            Some(plain) => {
                for a in plain.iter() {
                    // A named argument other than the frame and tool: rare (`mv \p:=p10;`,
                    // `mv d, p:=p10;`).
                    if a.label.end > a.label.start
                        && let Some(v) = a.value
                        && !a.label.slice(src).eq_ignore_ascii_case(b"WObj")
                    {
                        self.composed_arg(&u, src, name, (a.switch, a.label), v, true);
                    }
                    self.call_arg(&mut u, src, a.switch, a.label, a.value.map(|v| (v, true)));
                }
            }
            None => {
                for a in arena.children(args) {
                    let Some(arg) = arena.get(a) else { continue };
                    let value_id = arena.arg_value(a);
                    let value = value_id.and_then(|v| arena.get(v));
                    // A literal (a generated program's inline target) passes no name: not
                    // scanned for names it does not hold.
                    let literal = value_id.is_some_and(|v| arena.reads_no_name(v));
                    if let Some(v) = value.filter(|_| !literal) {
                        let plain = matches!(v.kind, ExprKind::Ident | ExprKind::Access);
                        let label = (arg.switch, arg.name_span());
                        self.composed_arg(&u, src, name, label, v.span(), plain);
                    }
                    self.arena_arg(&mut u, src, arg, value);
                }
            }
        }
        self.uses.push(u);
        !writes && self.passed.args.len() == passed
    }

    /// Out of line, a call that writes data by name or through its first argument, or calls a
    /// routine chosen at run time ([`writes_data_by_name`]): `GetDataVal "p10", pv` copies
    /// `p10` into `pv`, `SetDataVal "p10", pv` gives `p10` a value (a copy of `pv`), `Add
    /// pp.trans.z, 10` changes `pp`; a data name computed at run time (or `SetAllDataVal` of a
    /// type that holds positions or frames) may touch any target, and a late call's arguments
    /// go to a routine trackfix cannot tell ([`Extractor::named_at_run_time`]).
    /// The first of `plain` may be a robtarget `literal` (its span), which has no value there.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn data_call(
        &mut self,
        src: &[u8],
        arena: &Arena,
        name: Span,
        args: u32,
        plain: Option<&PlainArgs>,
        literal: Option<Span>,
        span: Span,
    ) {
        // The positional arguments: (value, whether a string literal).
        let mut positional: Vec<(Span, bool)> = Vec::new();
        match plain {
            Some(plain) => positional.extend(
                plain
                    .iter()
                    .filter(|a| !a.switch)
                    .filter_map(|a| Some((a.value.or(literal)?, false))),
            ),
            None => {
                for a in arena.children(args) {
                    if arena.get(a).is_none_or(|a| a.switch) {
                        continue;
                    }
                    if let Some(v) = arena.arg_value(a).and_then(|v| arena.get(v)) {
                        positional.push((v.span(), v.kind == ExprKind::Str));
                    }
                }
            }
        }
        let line = self.lines.line(span.start);
        let callee = name.slice(src);
        let is = |w: &[u8]| callee.eq_ignore_ascii_case(w);
        let first = positional.first().copied();
        let second = positional.get(1).map(|&(v, _)| v);
        let named = first.and_then(|(v, s)| s.then(|| string_inside(src, v)).flatten());
        if callee.first() == Some(&b'%') {
            let mut names = Vec::new();
            for &(v, _) in &positional {
                names_in(src, v, &mut names);
            }
            self.named_at_run_time.push((name, line, Some(names)));
        } else if is(b"GetDataVal") {
            match (named, second) {
                (Some(data), Some(into)) => {
                    self.copies.push(crate::resolve::CopyFact {
                        copy: into,
                        source: data,
                        routine: self.current,
                    });
                }
                _ => self.named_at_run_time.push((name, line, None)),
            }
            if let Some(into) = second {
                self.computed_write(src, written_name(src, into), line);
            }
        } else if is(b"SetDataVal") {
            match (named, second) {
                (Some(data), Some(from)) => {
                    let mut names = Vec::new();
                    names_in(src, from, &mut names);
                    self.copies
                        .extend(names.into_iter().map(|source| crate::resolve::CopyFact {
                            copy: data,
                            source,
                            routine: self.current,
                        }));
                    self.computed_write(src, data, line);
                }
                _ => self.named_at_run_time.push((name, line, None)),
            }
        } else if is(b"SetAllDataVal") {
            // A type that holds no position nor frame changes none.
            let harmless = named.is_some_and(|t| {
                let t = t.slice(src);
                ![&b"robtarget"[..], b"jointtarget", b"wobjdata", b"tooldata"]
                    .iter()
                    .any(|k| t.eq_ignore_ascii_case(k))
            });
            if !harmless {
                self.named_at_run_time.push((name, line, None));
            }
        } else if let Some((v, false)) = first {
            // `Add`, `Incr`, `Decr`, `Clear`: the first argument changes.
            self.computed_write(src, written_name(src, v), line);
        }
    }

    /// Out of line, `StrToVal(text, data)` at node `id`: `data` is given a value the program
    /// reads when it runs.
    #[inline(never)]
    fn value_read_into(&mut self, src: &[u8], arena: &Arena, id: u32) {
        let into = arena
            .children(id)
            .filter(|&a| arena.get(a).is_some_and(|a| !a.switch))
            .nth(1)
            .and_then(|a| arena.arg_value(a))
            .and_then(|v| arena.get(v));
        if let Some(v) = into {
            let line = self.lines.line(v.span().start);
            self.computed_write(src, written_name(src, v.span()), line);
        }
    }

    /// The required parameter named `name` of the routine being read, with the routine: the
    /// caller's argument, which hides module data of its name.
    fn own_param(&self, src: &[u8], name: &[u8]) -> Option<(usize, Span32)> {
        let r = self.current?;
        let routine = self.routines.get(r)?;
        let p = routine.params.get(routine.required_named(src, name)?)?;
        Some((r, Span32::of(*p)?))
    }

    /// A value computed at run time given to `target` (a name, an element) on `line`, as an
    /// assignment's: the routine's own parameter of that name is the caller's argument.
    fn computed_write(&mut self, src: &[u8], target: Span, line: usize) {
        let text = text_of(src, target);
        let head = text.split(['{', '.']).next().unwrap_or_default().trim();
        let param = self.own_param(src, head.as_bytes());
        match param {
            Some((r, p)) => {
                self.param_writes.push((r, p, line));
                self.param_assignments.push((r, p, line));
            }
            None => self.computed.push(crate::resolve::Assignment {
                name: text.trim().to_owned(),
                line,
                literal: false,
            }),
        }
    }

    /// Out of line, for an argument (written `\label` when a switch; its value `v`, `plain`
    /// when a name) of call `u` to `name` that is not a
    /// plain name: the names its value reads are references of the call (`MoveL id(p10), …`,
    /// `MoveL Offs(getP(), …)`: a function's value is a copy of what it reads and of what it
    /// returns, reached under its name) and, with a named argument (`mv \p:=p10;`), what
    /// is passed to the routine's parameter ([`Extractor::passed`]).
    #[inline(never)]
    fn composed_arg(
        &mut self,
        u: &CallUse,
        src: &[u8],
        name: Span,
        (switch, label): (bool, Span),
        v: Span,
        plain: bool,
    ) {
        let param = if switch || label.end > label.start {
            let l = label.slice(src);
            if l.eq_ignore_ascii_case(b"WObj") || l.eq_ignore_ascii_case(b"Tool") {
                return;
            }
            crate::resolve::PassedTo::Named(label)
        } else if plain {
            return;
        } else {
            let position = self.call_args.len().saturating_sub(u.args_start as usize);
            crate::resolve::PassedTo::Position(position)
        };
        let names = &mut self.passed.names;
        let start = names.len();
        if plain {
            names.push(v);
        } else {
            names_in(src, v, names);
            if !switch {
                self.call_refs
                    .extend_from_slice(names.get(start..).unwrap_or_default());
            }
        }
        // A value that reads no name (a literal target, as generated programs pass one to
        // every motion) hands the routine nothing to bind.
        if names.len() == start {
            return;
        }
        // A module's names stay far below 4 G entries (each is a name of its source).
        let range = start as u32..names.len() as u32;
        self.passed.args.push(crate::resolve::PassedArg {
            line: u.line as usize,
            routine: self.current,
            callee: name,
            param,
            names: range,
        });
    }

    /// Records the function call at `id` of the arena (`CalcJointT(p10, tGun \WObj:=wCar)`) as a
    /// use, as a call statement of its arguments is recorded.
    fn expression_call_use(&mut self, src: &[u8], arena: &Arena, id: u32) {
        let Some(n) = arena.get(id) else { return };
        let Some(mut u) = self.call_head(n.name_span(), n.span()) else {
            return;
        };
        for a in arena.children(id) {
            let Some(arg) = arena.get(a) else { continue };
            let value = arena.arg_value(a).and_then(|v| arena.get(v));
            self.arena_arg(&mut u, src, arg, value);
        }
        self.uses.push(u);
        // The last use is no longer the last call statement's, which a call read like it
        // copies.
        self.last_plain_call = None;
    }

    /// [`Extractor::call_arg`] of argument node `arg` of the arena, its value `value`.
    fn arena_arg(&mut self, u: &mut CallUse, src: &[u8], arg: &ExprNode, value: Option<&ExprNode>) {
        let value = value.map(|v| {
            let name = matches!(v.kind, ExprKind::Ident | ExprKind::Access);
            (v.span(), name)
        });
        self.call_arg(u, src, arg.switch, arg.name_span(), value);
    }

    /// Records one argument of call `u`: written `\label` (`switch`) or `label:=` (a label
    /// empty for a plain value), with its value's span and whether that value is a name (or
    /// an access, `p{2}`).
    fn call_arg(
        &mut self,
        u: &mut CallUse,
        src: &[u8],
        switch: bool,
        label: Span,
        value: Option<(Span, bool)>,
    ) {
        let v = value.and_then(|(v, _)| Span32::of(v));
        if switch {
            let nm = label.slice(src);
            if nm.eq_ignore_ascii_case(b"WObj") {
                u.wobj = v;
            } else if nm.eq_ignore_ascii_case(b"Tool") {
                u.tool = v;
            }
        } else {
            // A required argument may be given by name: `..., fine, tool:=tGun;`.
            if label.end > label.start && label.slice(src).eq_ignore_ascii_case(b"Tool") {
                u.tool = v;
            }
            self.call_args.push(
                value
                    .filter(|&(_, name)| name)
                    .and_then(|(v, _)| Span32::of(v)),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recent_frame_names_are_the_names_the_map_gives() {
        let robhold: NameMap<NameKey, bool> = [(NameKey(b"wHeld"), true)].into_iter().collect();
        let mut texts = FrameTexts::new(&robhold);
        let names: [&[u8]; 5] = [b"tGun", b"wCar", b"WHELD", b"wHeld", b"tgun"];
        // Alternating, repeated, and three in a row (past what the recent two hold).
        let order = [0, 1, 0, 1, 1, 2, 3, 4, 0, 2, 2, 1, 3, 0, 4, 4];
        for &k in &order {
            let bytes = names[k];
            let fast = texts.get(bytes);
            let plain = texts.get_known(bytes);
            assert_eq!(fast.name.as_ptr(), plain.name.as_ptr(), "{k}");
            assert_eq!((&*fast.name, fast.robhold), (&*plain.name, plain.robhold));
            assert_eq!(&*fast.name, latin1(bytes));
        }
        assert!(texts.get(b"wHeld").robhold && !texts.get(b"wCar").robhold);
    }

    #[test]
    fn recent_argument_kinds_are_the_kinds_the_map_gives() {
        use crate::resolve::DeclKind;
        let type_of: NameMap<NameKey, DeclKind> = [
            (NameKey(b"rdkSpeed"), DeclKind::Speed),
            (NameKey(b"rdkZone"), DeclKind::Zone),
            (NameKey(b"rdkTool"), DeclKind::Tool),
            (NameKey(b"tGun"), DeclKind::Tool),
            (NameKey(b"rdkTarget"), DeclKind::Other),
        ]
        .into_iter()
        .collect();
        let kinds = ArgKinds::new(&type_of);
        let names: [&[u8]; 7] = [
            b"rdkSpeed",
            b"rdkZone",
            b"rdkTool",
            b"tGun",
            b"rdkTarget",
            b"rdkNone",
            b"RDKTOOL",
        ];
        // A call's three in turn, again and again; then more distinct names than are kept,
        // repeated, alternating and out of order.
        let order = [
            0, 1, 2, 0, 1, 2, 0, 1, 2, 3, 4, 5, 6, 0, 6, 2, 2, 5, 3, 1, 4, 0, 2,
        ];
        for &k in &order {
            let n = NameKey(names[k]);
            let want = type_of.get(&n).copied();
            for kind in [
                DeclKind::Tool,
                DeclKind::Zone,
                DeclKind::Speed,
                DeclKind::Other,
            ] {
                assert_eq!(kinds.declared(n, kind), want == Some(kind), "{k} {kind:?}");
            }
        }
        assert!(kinds.declared(NameKey(b"RDKTOOL"), DeclKind::Tool));
    }

    /// Targets with their usage (as `Debug` text), and the parser's and extractor's reports.
    type Read = (Vec<(Option<crate::position::Position>, String)>, String);

    /// What the extractor makes of one module read with or without the parser's fast paths.
    fn extracted(src: &[u8], fast: bool) -> Read {
        let lines = LineIndex::new(src);
        let mut x = Extractor::new(&lines);
        let mut sink = |s: Statement<'_>| x.statement(s);
        let parse = if fast {
            crate::rapid::parser::parse_streamed(src, &mut sink, crate::rapid::flow::walked)
        } else {
            crate::rapid::parser::parse_streamed_plain(src, &mut sink)
        };
        x.keep_skeleton(parse.tree.nodes.clone());
        let out = finish_task(vec![(x, src, Arc::from("test.mod"))]).remove(0);
        let targets = (0..out.positions.len())
            .map(|i| {
                let usage = format!("{:?}", out.positions.usage(i));
                (out.positions.get(i, src), usage)
            })
            .collect();
        let report = format!(
            "{:?}\n{:?}\n{:?}",
            parse.diagnostics, out.diagnostics, out.frames
        );
        (targets, report)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 512, ..proptest::prelude::ProptestConfig::default()
        })]
        /// Robtarget declarations of the fast path's shape and of shapes it leaves to the
        /// general path, one after another (so that the literals it remembers per field are
        /// followed by other texts there, `0` by `0.5`): the same targets and reports either
        /// way.
        #[test]
        fn declared_targets_read_alike_with_and_without_the_fast_paths(
            decls in proptest::collection::vec(declaration(), 1..8),
            twice in proptest::bool::ANY,
        ) {
            let mut src = b"MODULE M\r\n".to_vec();
            for d in &decls {
                src.extend_from_slice(d);
                // The same parts again, which the fast path takes from the one before.
                if twice {
                    src.extend_from_slice(d);
                }
            }
            src.extend_from_slice(b"PROC main()\r\n  MoveL p1, v10, z1, tool0;\r\nENDPROC\r\nENDMODULE\r\n");
            let fast = extracted(&src, true);
            let plain = extracted(&src, false);
            proptest::prop_assert_eq!(fast, plain);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 256, ..proptest::prelude::ProptestConfig::default()
        })]
        /// Calls with a target written inline, of the fast path's shape and of others, among
        /// motions to declared targets (which a call may repeat with a name changed), a
        /// compact `IF`, data writers and a routine that takes a target: the same targets,
        /// usage and reports either way.
        #[test]
        fn inline_targets_read_alike_with_and_without_the_fast_paths(
            lines in proptest::collection::vec(motion_line(), 1..12),
        ) {
            let mut src = b"MODULE M\r\n\
                PERS tooldata tGun:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\r\n\
                TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1,2,3],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\r\n\
                CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[10,9E9,9E9,9E9,9E9,9E9]];\r\n\
                PROC main()\r\n"
                .to_vec();
            for l in &lines {
                src.extend_from_slice(l);
            }
            src.extend_from_slice(b"ENDPROC\r\n\
                PROC mv(robtarget p \\num d)\r\n  MoveL p, v10, fine, tGun\\WObj:=wCar;\r\nENDPROC\r\n\
                ENDMODULE\r\n");
            let fast = extracted(&src, true);
            let plain = extracted(&src, false);
            proptest::prop_assert_eq!(fast, plain);
        }
    }

    /// A line of a routine: mostly a call with a target written inline
    /// ([`crate::rapid::parser::inline_robtarget`]), else a motion to a declared target (alike
    /// but for a name, as a program's runs are), an approach through `Offs`, or a compact `IF`.
    fn motion_line() -> impl proptest::strategy::Strategy<Value = Vec<u8>> {
        use proptest::prelude::*;
        let callee = prop_oneof![
            8 => proptest::sample::select(vec!["MoveL", "MoveJ", "MoveLDO", "TriggL"]),
            1 => proptest::sample::select(vec!["MoveC", "Incr", "SetDataVal", "GetDataVal", "mv"]),
        ];
        let rest = proptest::sample::select(vec![
            ", v1000, z10, tGun\\WObj:=wCar",
            ",rdkSpeed,rdkZone,tGun,\\WObj:=wCar",
            ", v10, fine, tool:=tGun",
            ", v10, z1, tGun \\WObj := wCar \\Tool:=tGun",
            "\\Conc, v10, z1, tGun",
            " \\d:=dd",
            ", p1",
            "",
            ", v10, z1, tGun\\WObj:=Offs(p1,0,0,1)",
        ]);
        let blank = proptest::sample::select(vec![" ", "\t", "\r\n    ", ""]);
        let inline = (
            callee,
            blank,
            crate::rapid::parser::inline_robtarget(),
            rest,
        )
            .prop_map(|(c, b, t, r)| format!("  {c}{b}{t}{r};\r\n"));
        let named = (
            proptest::sample::select(vec!["MoveL", "MoveJ"]),
            proptest::sample::select(vec!["p1", "p2", "p10"]),
            proptest::sample::select(vec!["wCar", "wTable"]),
        )
            .prop_map(|(c, p, w)| format!("  {c} {p}, v1000, z10, tGun\\WObj:={w};\r\n"));
        let other = proptest::sample::select(vec![
            "  MoveL Offs(p1,0,0,10), v10, z1, tGun;\r\n",
            "  IF di1 = 1 MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v10, fine, tGun;\r\n",
            "  IF di1 = 1 MoveL p1, v10, fine, tGun;\r\n",
        ])
        .prop_map(str::to_owned);
        prop_oneof![6 => inline, 3 => named, 1 => other]
            .prop_map(|l| crate::rapid::parser::latin1_bytes(&l))
    }

    #[test]
    fn a_motion_to_a_target_written_inline_is_recorded_as_the_general_path_records_it() {
        let target = "[[1520.3,-850.1,612.4],[0.0,0.707107,0.707107,0.0],[0,0,-1,0],\
            [1650.0,9E+09,9E+09,9E+09,9E+09,9E+09]]";
        let src = format!(
            "MODULE M\r\n\
            PERS tooldata tGun:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\r\n\
            TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1,2,3],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\r\n\
            PROC main()\r\n\
              MoveL {target},v1000,z10,tGun\\WObj:=wCar;\r\n\
              MoveL {target},v1000,z10,tGun\\WObj:=wCar;\r\n\
              MoveJ {target}, v1000, fine, tool:=tGun;\r\n\
              MoveL p1, v1000, z10, tGun\\WObj:=wCar;\r\n\
              MoveL {target},v1000,z10,tGun\\WObj:=wCar;\r\n\
              MoveL p2, v1000, z10, tGun\\WObj:=wCar;\r\n\
            ENDPROC\r\n\
            ENDMODULE\r\n"
        );
        let fast = extracted(src.as_bytes(), true);
        assert_eq!(fast, extracted(src.as_bytes(), false));
        // The four inline targets, unnamed, each used by its motion with its frame and tool.
        assert_eq!(fast.0.len(), 4);
        for (k, line) in [(0, 5), (1, 6), (2, 7), (3, 9)] {
            let (p, usage) = &fast.0[k];
            let p = p.as_ref().unwrap();
            assert_eq!((p.name.is_none(), p.line), (true, line));
            let wobj = if k == 2 { "wobj0" } else { "wCar" };
            assert!(
                usage.contains(wobj) && usage.contains("tGun"),
                "{k}: {usage}"
            );
        }
    }

    fn declaration() -> impl proptest::strategy::Strategy<Value = Vec<u8>> {
        use proptest::prelude::*;
        // Mostly literals the fast path reads, some that share a head with another (`0`,
        // `0.5`), a few it leaves to the general path.
        let number = prop_oneof![
            12 => proptest::sample::select(vec![
                "0", "0.5", "-0.5", ".5", "5.", "+1", "9E+09", "9E9", "9e+9", "9E09",
                "1.50E+2", "0.707107", "-0.707107", "-1520.30", "0.000000", "1", "-1",
                "0.3826834323650898",
            ]),
            1 => proptest::sample::select(vec![
                "12345678901234567890", "1E", "1.2.3", "x", "1E-9000", "-0.38268343236508977",
            ]),
        ];
        let sep = proptest::sample::select(vec![",", " , ", ",\r\n    ", ",\t"]);
        // The four parts' lengths of a robtarget, or any others.
        let lengths = prop_oneof![
            6 => (1usize..=13).prop_map(|axes| vec![3, 4, 4, axes]),
            1 => proptest::collection::vec(0usize..14, 3..6),
        ];
        let parts = (lengths, sep)
            .prop_flat_map(move |(lengths, sep)| {
                let parts: Vec<_> = lengths
                    .into_iter()
                    .map(|n| proptest::collection::vec(number.clone(), n))
                    .collect();
                (parts, Just(sep))
            })
            .prop_map(|(parts, sep)| {
                parts
                    .iter()
                    .map(|ns| format!("[{}]", ns.join(sep)))
                    .collect::<Vec<_>>()
                    .join(",")
            });
        let head = prop_oneof![
            6 => Just("CONST robtarget p1"),
            1 => proptest::sample::select(vec![
            "PERS ROBTARGET p_2",
            "VAR robtarget p\u{c4}",
            "CONST robtarget pa{2}",
            "LOCAL CONST robtarget p3",
            "CONST jointtarget j1",
        ]),
        ];
        let tail = prop_oneof![
            6 => Just(";"),
            1 => proptest::sample::select(vec![" ;", " ! c\r\n;", ".trans;", " + p1;", ""]),
        ];
        (head, parts, tail, proptest::bool::weighted(0.9)).prop_map(|(head, parts, tail, wrap)| {
            let value = if wrap { format!("[{parts}]") } else { parts };
            // `Ä` as Latin-1, the way a controller writes it.
            let head = head.replace('\u{c4}', "\u{1}");
            let mut line = format!("  {head}:={value}{tail}\r\n").into_bytes();
            for b in &mut line {
                if *b == 1 {
                    *b = 0xc4;
                }
            }
            line
        })
    }

    #[test]
    fn parts_taken_from_the_target_before_read_as_the_general_path_reads_them() {
        let q = [
            "[0,0,1,0]",
            "[0.000000,0.707107,0.707107,0.000000]",
            // The first 16 bytes as above, then other digits; then past 64 bytes.
            "[0.000000,0.707107,0.707108,0.000000]",
            "[0.000000000000001,0.707106781186548,0.707106781186548,0.000000000000001]",
        ];
        let cf = [
            "[0,0,-1,0]",
            "[0,0,-1,1]",
            "[-1,-2,-2,0]",
            "[ 0 , 0 , -1 , 0 ]",
        ];
        // What follows the first external axis.
        let axes = [",9E+09]", ",9E+09,9E+09]", " , 9E9 ]", "]", ",9E+09,9E+08]"];
        let mut src = b"MODULE M\r\n".to_vec();
        let mut n = 0;
        for (k, (a, b)) in [
            (0, 0),
            (1, 0),
            (1, 0),
            (2, 0),
            (2, 1),
            (3, 1),
            (3, 1),
            (1, 2),
            (1, 3),
        ]
        .into_iter()
        .enumerate()
        {
            for _ in 0..2 {
                n += 1;
                let line = format!(
                    "  CONST robtarget p{n}:=[[1,2,3],{},{},[{n}{}];\r\n",
                    q[a],
                    cf[b],
                    axes[k % axes.len()]
                );
                src.extend_from_slice(line.as_bytes());
            }
        }
        src.extend_from_slice(b"ENDMODULE\r\n");
        let fast = extracted(&src, true);
        assert_eq!(fast, extracted(&src, false));
        assert_eq!(fast.0.len(), 18);
        let p = fast.0[9].0.as_ref().unwrap();
        assert_eq!(p.label(), "p10");
        assert!(format!("{p:?}").contains("0.707108"), "{p:?}");
    }

    #[test]
    fn a_run_of_motions_alike_is_recorded_as_each_reads() {
        let src = b"MODULE M\r\n\
            PERS tooldata tGun:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\r\n\
            CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[10,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p2:=[[1,2,3],[1,0,0,0],[0,0,0,0],[20,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p3:=[[1,2,3],[1,0,0,0],[0,0,0,0],[30,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p44:=[[1,2,3],[1,0,0,0],[0,0,0,0],[40,9E9,9E9,9E9,9E9,9E9]];\r\n\
            PROC main()\r\n\
              MoveL p1, v1000, z10, tGun\\WObj:=wCar;\r\n\
              MoveL p2, v1000, z10, tGun\\WObj:=wCar;\r\n\
              MoveL p3, v1000, z10, tGun\\WObj:=wTable;\r\n\
              MoveJ p3, v1000, z10, tGun\\WObj:=wTable;\r\n\
              MoveL p44, v1000, z10, tGun\\WObj:=wTable;\r\n\
              MoveL p44, v1000, z10, tool0\\WObj:=wTable;\r\n\
              MoveL p44, v1000, z10, tool0\\Tool:=wTable;\r\n\
              MoveL p1, v1000, z10, tGun\\WObj:=wCar;\r\n\
            ENDPROC\r\n\
            ENDMODULE\r\n";
        let fast = extracted(src, true);
        assert_eq!(fast, extracted(src, false));
        // Each target's work objects and tools, as each call names them.
        let usage: Vec<&str> = fast.0.iter().map(|(_, u)| u.as_str()).collect();
        let names = |u: &str, want: &[&str]| want.iter().all(|w| u.contains(w));
        assert!(
            names(usage[0], &["wCar", "tGun", "8", "15"]),
            "{}",
            usage[0]
        );
        assert!(
            names(usage[1], &["wCar", "9"]) && !usage[1].contains("wTable"),
            "{}",
            usage[1]
        );
        assert!(names(usage[2], &["wTable", "10", "11"]) && !usage[2].contains("wCar"));
        assert!(
            names(usage[3], &["wTable", "tGun", "12", "13", "14"]),
            "{}",
            usage[3]
        );
    }

    /// A call read as the one before it (`mv \\p:=p11;` after `mv \\p:=p10;`), and a required
    /// argument given by name (`mr p:=p12, d:=n1;`), pass their targets to the routine's
    /// parameter as the general path does: each moves with the routine's motion. A call that
    /// writes data by name is recorded as such after one alike that does not (`Incr n1;` after
    /// `Show n1;`; the test build's record of the fast paths holds it to the plain one).
    #[test]
    fn arguments_passed_by_name_reach_the_routine_on_the_fast_paths() {
        let src = b"MODULE M\r\n\
            CONST robtarget p10:=[[1,2,3],[1,0,0,0],[0,0,0,0],[10,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p11:=[[1,2,3],[1,0,0,0],[0,0,0,0],[11,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p12:=[[1,2,3],[1,0,0,0],[0,0,0,0],[12,9E9,9E9,9E9,9E9,9E9]];\r\n\
            CONST robtarget p13:=[[1,2,3],[1,0,0,0],[0,0,0,0],[13,9E9,9E9,9E9,9E9,9E9]];\r\n\
            TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1,2,3],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\r\n\
            PROC main()\r\n\
              mv \\p:=p10;\r\n\
              mv \\p:=p11;\r\n\
              mr p:=p12, d:=n1;\r\n\
              mr p:=p13, d:=n1;\r\n\
              Show n1;\r\n\
              Incr n1;\r\n\
            ENDPROC\r\n\
            PROC mv(\\robtarget p)\r\n  MoveL p, v10, z1, tool0\\WObj:=wCar;\r\nENDPROC\r\n\
            PROC mr(num d, robtarget p)\r\n  MoveL p, v10, z1, tool0\\WObj:=wCar;\r\nENDPROC\r\n\
            ENDMODULE\r\n";
        let fast = extracted(src, true);
        assert_eq!(fast, extracted(src, false));
        for (k, (_, usage)) in fast.0.iter().enumerate() {
            assert!(usage.contains("\"wCar\""), "p1{k}: {usage}");
        }
    }

    #[test]
    fn trimming_the_bytes_trims_their_text() {
        // Every byte value alone, at both ends of a name, inside one, and doubled.
        for b in 0..=255u8 {
            for bytes in [
                vec![b],
                vec![b, b'w', b],
                vec![b'w', b, b'1'],
                vec![b, b, b'w', b'1', b],
            ] {
                assert_eq!(
                    latin1(trim_latin1(&bytes)),
                    latin1(&bytes).trim(),
                    "{bytes:?}"
                );
            }
        }
    }
}
