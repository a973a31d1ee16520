//! Which base and tool each motion of a program uses: program order within each `DEF`, forked
//! and joined at `IF`/`SWITCH`, over every file of a `.src`/`.dat` pair. What a motion reaches
//! (its target, what that was copied from) goes with its base and tool to the shared usage pass
//! ([`crate::resolve`]), which fills each position's [`Usage`](crate::position::Usage).

use super::positions::{
    BranchEvent, Event, Facts, Fdat, FrameRef, HandedBack, LoopKind, Ref, Setting, SharedCopy,
    computed_index, guessed_field_problem, name_key,
};
use crate::position::{
    Config, FrameDecl, FrameName, Name, ParsedFile, PositionKind, RunTimeValue, UnresolvedCause,
    UnresolvedFrame, UseLine,
};
use crate::syntax::Diagnostic;
use std::collections::BTreeMap;
use std::rc::Rc;
use std::sync::Arc;

pub(crate) use crate::names::NameMap as HashMap;

/// How KRL references reach declarations: a name its declaration, an element chosen at run
/// time (`P[I]`) every element of the array as well; in the module's own files first (the
/// pair), else what other modules export ([`Modules`]).
const NAMING: crate::resolve::Naming = crate::resolve::Naming {
    open: '[',
    close: ']',
    arrays: crate::resolve::ArrayReach::WhenIndexComputed,
};

/// The name trackfix gives a base: `BASE_DATA[n]`, `$WORLD` for base 0.
pub(crate) fn base_label(r: &FrameRef) -> Option<String> {
    match r {
        FrameRef::Data(0) => Some("$WORLD".to_owned()),
        FrameRef::Data(n) => Some(format!("BASE_DATA[{n}]")),
        FrameRef::Named(s) => Some(s.clone()),
        FrameRef::RunTime(_) | FrameRef::Unknown => None,
    }
}

/// The name trackfix gives a tool: `TOOL_DATA[n]`, `$NULLFRAME` (the flange) for tool 0.
pub(crate) fn tool_label(r: &FrameRef) -> Option<String> {
    match r {
        FrameRef::Data(0) => Some("$NULLFRAME".to_owned()),
        FrameRef::Data(n) => Some(format!("TOOL_DATA[{n}]")),
        FrameRef::Named(s) => Some(s.clone()),
        FrameRef::RunTime(_) | FrameRef::Unknown => None,
    }
}

/// The names of the bases and tools a program's motions use, each made once: thousands of
/// motions with base 1 share one `BASE_DATA[1]`, where a name each was a `format!` per motion.
#[derive(Default)]
struct FrameLabels {
    /// `BASE_DATA[n]` (false) and `TOOL_DATA[n]` (true) by number.
    data: HashMap<(bool, u32), FrameName>,
    /// Frames the program declares, by name.
    named: HashMap<String, FrameName>,
}

impl FrameLabels {
    /// The name of base (`tool` false) or tool `r`, as [`base_label`] and [`tool_label`] give it.
    fn get(&mut self, r: &FrameRef, tool: bool) -> Option<FrameName> {
        let label = |r: &FrameRef| if tool { tool_label(r) } else { base_label(r) };
        match r {
            FrameRef::Data(n) => Some(
                self.data
                    .entry((tool, *n))
                    .or_insert_with(|| FrameName::from(label(r).unwrap_or_default().as_str()))
                    .clone(),
            ),
            FrameRef::Named(s) => Some(match self.named.get(s.as_str()) {
                Some(name) => name.clone(),
                None => {
                    let name = FrameName::from(s.as_str());
                    self.named.insert(s.clone(), name.clone());
                    name
                }
            }),
            FrameRef::RunTime(_) | FrameRef::Unknown => None,
        }
    }
}

/// Whether `$IPO_MODE` may be `#TCP` (the tool stationary) at a point of a routine, for each
/// mode the routine may be entered with: a function of the entry mode, held as its two values,
/// so that one pass over a routine serves every caller. A point the routine reaches without
/// setting the mode has it as entered ([`MayTcp::AS_ENTERED`], the default); a call applies its
/// routine's exit to both ([`MayTcp::then`]); a motion's own is the one for the mode its
/// routine is entered with ([`MayTcp::given`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MayTcp {
    /// Had the routine been entered with `#BASE`.
    entered_base: bool,
    /// Had it been entered with `#TCP`.
    entered_tcp: bool,
}

impl Default for MayTcp {
    fn default() -> MayTcp {
        MayTcp::AS_ENTERED
    }
}

impl MayTcp {
    /// The mode the routine was entered with, not changed since.
    const AS_ENTERED: MayTcp = MayTcp {
        entered_base: false,
        entered_tcp: true,
    };

    /// Set to `#TCP` (`true`) or `#BASE`, whatever the routine was entered with.
    fn set(tcp: bool) -> MayTcp {
        MayTcp {
            entered_base: tcp,
            entered_tcp: tcp,
        }
    }

    /// Where two paths join: `#TCP` where either may have it.
    fn or(self, other: MayTcp) -> MayTcp {
        MayTcp {
            entered_base: self.entered_base || other.entered_base,
            entered_tcp: self.entered_tcp || other.entered_tcp,
        }
    }

    /// After a call of a routine that leaves `exit` (its mode at its end, by the mode it is
    /// entered with, which is this one).
    fn then(self, exit: MayTcp) -> MayTcp {
        MayTcp {
            entered_base: exit.given(self.entered_base),
            entered_tcp: exit.given(self.entered_tcp),
        }
    }

    /// Whether it may be `#TCP` when the routine is entered with `#TCP` (`entered_tcp`) or not.
    fn given(self, entered_tcp: bool) -> bool {
        if entered_tcp {
            self.entered_tcp
        } else {
            self.entered_base
        }
    }
}

#[derive(Clone, Default, PartialEq)]
struct State<'e> {
    base: Option<FrameRef>,
    tool: Option<FrameRef>,
    /// Whether `$IPO_MODE` may be `#TCP`, by the mode the routine was entered with.
    tcp: MayTcp,
    /// What `FDAT_ACT` holds, which only a `BAS` call that applies it puts into effect
    /// ([`Setting::ApplyFdat`]). `None`: nothing staged on this path since the routine's entry,
    /// so it holds what it held then.
    staged: Option<Staged>,
    /// What the names copied into may hold on this path.
    aliases: Aliases<'e>,
    /// The path has left by a `GOTO`: a join does not take it (the jump goes on at its label,
    /// which makes what it arrives with unknown).
    dead: bool,
}

impl<'e> State<'e> {
    /// The base, tool, IPO mode and staged FDAT, without the aliases: what a motion's own
    /// `WITH` is applied to (a copy of the aliases per motion would cost on every motion).
    fn frames(&self) -> State<'e> {
        State {
            base: self.base.clone(),
            tool: self.tool.clone(),
            tcp: self.tcp,
            staged: self.staged.clone(),
            aliases: Aliases::default(),
            dead: false,
        }
    }
}

/// What each name a copy was made into may hold on a path (`XC = XP1`: `XC` → `XP1`): the
/// names it may be a copy of, sorted, itself among them when it may still hold what it held
/// before (`IF … THEN XC = XP1 ENDIF`). A name not in it holds its own value. Shared between
/// the states of a fork or loop until one of them copies (`Rc::make_mut`): following an `IF`
/// costs no copy of the table.
#[derive(Clone, Default, PartialEq)]
struct Aliases<'e>(Option<Rc<BTreeMap<&'e str, Vec<&'e str>>>>);

impl<'e> Aliases<'e> {
    fn is_empty(&self) -> bool {
        self.0.as_ref().is_none_or(|m| m.is_empty())
    }

    fn get(&self, name: &str) -> Option<&[&'e str]> {
        self.0.as_ref()?.get(name).map(Vec::as_slice)
    }

    fn map_mut(&mut self) -> &mut BTreeMap<&'e str, Vec<&'e str>> {
        Rc::make_mut(self.0.get_or_insert_with(Default::default))
    }

    /// `name = source`: it now holds `source` (or, `joined`, may hold it besides what it held).
    /// A name given itself (`name == source`, not joined) holds its own value again.
    fn copy(&mut self, name: &'e str, source: &'e str, joined: bool) {
        if name == source {
            if !joined && self.get(name).is_some() {
                self.map_mut().remove(name);
            }
            return;
        }
        let m = self.map_mut();
        match m.get_mut(name) {
            Some(held) if joined => add_sorted(held, source),
            _ if joined => {
                let mut held = vec![name];
                add_sorted(&mut held, source);
                m.insert(name, held);
            }
            Some(held) => {
                held.clear();
                held.push(source);
            }
            None => {
                m.insert(name, vec![source]);
            }
        }
    }

    /// What every name may hold on any of `paths`: the union, per name, of what each path
    /// gives it (its own value, where a path made no copy into it).
    fn join<'s>(paths: impl Iterator<Item = &'s Aliases<'e>> + Clone) -> Aliases<'e>
    where
        'e: 's,
    {
        let mut all = paths.clone().filter(|a| !a.is_empty());
        let Some(first) = all.next() else {
            return Aliases::default();
        };
        if paths.clone().all(|a| a == first) {
            return first.clone();
        }
        let mut out: BTreeMap<&'e str, Vec<&'e str>> = BTreeMap::new();
        for a in paths.clone() {
            for &name in a.0.iter().flat_map(|m| m.keys()) {
                if out.contains_key(name) {
                    continue;
                }
                let mut held: Vec<&'e str> = Vec::new();
                for b in paths.clone() {
                    match b.get(name) {
                        Some(h) => h.iter().for_each(|s| add_sorted(&mut held, s)),
                        None => add_sorted(&mut held, name),
                    }
                }
                if held.len() > 1 || held.first() != Some(&name) {
                    out.insert(name, held);
                }
            }
        }
        Aliases(Some(Rc::new(out)))
    }

    /// Adds what `more` gives each name to what it may hold here (a call of a routine that
    /// copies into names other routines see).
    fn absorb(&mut self, more: &Aliases<'e>) {
        if more.is_empty() {
            return;
        }
        *self = Aliases::join([&*self, more].into_iter());
    }

    /// The names `name` may be a copy of: its own entry, and for an element (`XC[1]`) those of
    /// the elements of the same array written through a computed index (`XC[I] = XP1`), or,
    /// for one read through a computed index (`XC[I]`), those of every element.
    fn sources(&self, name: &str, out: &mut Vec<&'e str>) {
        let Some(m) = self.0.as_deref() else {
            return;
        };
        out.extend(m.get(name).into_iter().flatten().copied());
        let Some((array, _)) = name.split_once('[') else {
            return;
        };
        let any = computed_index(name);
        let from = std::ops::Bound::Included(array);
        for (element, held) in m.range::<str, _>((from, std::ops::Bound::Unbounded)) {
            let Some(index) = element.strip_prefix(array) else {
                break;
            };
            if index.starts_with('[') && *element != name && (any || computed_index(element)) {
                out.extend(held.iter().copied());
            }
        }
    }
}

/// Inserts `name` into the sorted `list` unless it is there.
fn add_sorted<'e>(list: &mut Vec<&'e str>, name: &'e str) {
    if let Err(at) = list.binary_search(&name) {
        list.insert(at, name);
    }
}

/// The frame data `FDAT_ACT` holds: the base, tool and IPO mode a `BAS` call applies.
#[derive(Clone, PartialEq)]
struct Staged {
    base: FrameRef,
    tool: FrameRef,
    tcp: bool,
}

/// An open `IF`/`SWITCH` while following program order.
struct Fork<'e> {
    is_if: bool,
    entry: State<'e>,
    outcomes: Vec<State<'e>>,
    in_branch: bool,
    exhaustive: bool,
}

impl<'e> Fork<'e> {
    fn new(is_if: bool, entry: &State<'e>) -> Fork<'e> {
        Fork {
            is_if,
            entry: entry.clone(),
            outcomes: Vec::new(),
            // An IF's first branch starts at once; a SWITCH's at its first CASE.
            in_branch: is_if,
            exhaustive: false,
        }
    }

    /// The state after the join: what every branch agrees on; a base or tool that differs
    /// between branches is unknown, and #TCP in any branch counts.
    fn join(mut self, current: State<'e>) -> State<'e> {
        if self.in_branch {
            self.outcomes.push(current);
        }
        if !self.exhaustive {
            self.outcomes.push(self.entry.clone());
        }
        join(&self.outcomes).unwrap_or(self.entry)
    }
}

/// What every state of `states` agrees on: a base or tool that differs between them is
/// unknown, and #TCP in any counts. `None` for no state.
fn join<'e>(states: &[State<'e>]) -> Option<State<'e>> {
    if states.iter().any(|s| s.dead) {
        // Out of line in effect: only a block a `GOTO` leaves gets here.
        let live: Vec<State<'e>> = states.iter().filter(|s| !s.dead).cloned().collect();
        return if live.is_empty() {
            states.first().cloned()
        } else {
            join(&live)
        };
    }
    let first = states.first()?;
    let agree = |f: for<'s> fn(&'s State<'e>) -> &'s Option<FrameRef>| {
        if states.iter().all(|o| f(o) == f(first)) {
            f(first).clone()
        } else {
            Some(FrameRef::Unknown)
        }
    };
    Some(State {
        base: agree(|s| &s.base),
        tool: agree(|s| &s.tool),
        tcp: states
            .iter()
            .fold(MayTcp::set(false), |tcp, o| tcp.or(o.tcp)),
        staged: join_staged(states),
        aliases: Aliases::join(states.iter().map(|s| &s.aliases)),
        dead: false,
    })
}

/// What `FDAT_ACT` holds after paths that staged `states`' values: the one they agree on, else
/// a base or tool that differs between them (or that a path left as at the routine's entry) is
/// unknown, and #TCP in any counts.
fn join_staged(states: &[State<'_>]) -> Option<Staged> {
    let first = states.first()?.staged.as_ref();
    if states.iter().all(|o| o.staged.as_ref() == first) {
        return first.cloned();
    }
    let agree = |f: fn(&Staged) -> &FrameRef| match first.map(f) {
        Some(r) if states.iter().all(|o| o.staged.as_ref().map(f) == Some(r)) => r.clone(),
        _ => FrameRef::Unknown,
    };
    Some(Staged {
        base: agree(|s| &s.base),
        tool: agree(|s| &s.tool),
        tcp: states
            .iter()
            .any(|o| o.staged.as_ref().is_some_and(|s| s.tcp)),
    })
}

/// How many names a motion's target is followed back through copies to, itself included.
const FOLDED: usize = 64;

/// A module's copies into names other routines see ([`Facts::shared_copies`]).
#[derive(Default)]
struct Shared<'s> {
    /// Those a routine program order follows makes: what each routine starts with (an earlier
    /// call of it or of another may have made them) and may find after a call.
    entry: Aliases<'s>,
    /// Those made by what runs at any time (a trigger's or interrupt's `DO`, a function, the
    /// routine of an interrupt or trigger): name → what it may hold at any motion.
    anytime: HashMap<String, Vec<String>>,
}

/// Each module's [`Shared`] copies, from each file's (`copies`, in the order of `facts`). A
/// copy into a name its module does not declare, or declares `GLOBAL`, may be moved to in
/// another module, whose motions are not followed with this module's names: its source is
/// refused as handed back ([`HandedBack::into`]). Out of line: only a program that makes such
/// copies gets here.
#[inline(never)]
fn shared_by_module<'s>(
    copies: &'s [Vec<SharedCopy>],
    facts: &mut [Facts],
    modules: &Modules,
) -> Vec<Shared<'s>> {
    let unfollowed: std::collections::HashSet<&str> = facts
        .iter()
        .flat_map(|f| f.unfollowed.iter().map(String::as_str))
        .collect();
    let mut out: Vec<Shared<'s>> = (0..modules.count).map(|_| Shared::default()).collect();
    let mut refused: Vec<(usize, HandedBack)> = Vec::new();
    for (fi, list) in copies.iter().enumerate() {
        let module = modules.of(fi);
        for c in list {
            let whole = c.name.split(['[', '.']).next().unwrap_or_default();
            let own = facts.iter().enumerate().any(|(fj, g)| {
                modules.of(fj) == module
                    && !modules.is_global(fj)
                    && g.declared.contains_key(whole)
                    && !g.globals.iter().any(|n| n.as_str() == whole)
            });
            if !own {
                refused.push((
                    fi,
                    HandedBack {
                        source: c.source.clone(),
                        line: c.line,
                        routine: crate::syntax::Span::default(),
                        param: None,
                        into: Some(Name::from(whole)),
                    },
                ));
            }
            let Some(s) = out.get_mut(module) else {
                continue;
            };
            match c.routine.as_deref() {
                Some(r) if !unfollowed.contains(r) => {
                    s.entry.copy(c.name.as_str(), c.source.as_str(), true);
                }
                _ => {
                    let held = s.anytime.entry(c.name.to_string()).or_default();
                    if !held.iter().any(|h| h == c.source.as_str()) {
                        held.push(c.source.to_string());
                    }
                }
            }
        }
    }
    for (fi, h) in refused {
        if let Some(f) = facts.get_mut(fi) {
            f.handed_back.push(h);
        }
    }
    out
}

/// Adds to each file's [`Facts::unfollowed`] the routines of its interrupts that an
/// `INTERRUPT ON` anywhere in the program switches on (by number; `INTERRUPT ON` alone, or a
/// number or declaration computed when the program runs, any): a declared interrupt is off until
/// then, so the routine of one the program never switches on never runs there, and changes no
/// motion's base.
fn switched_on_interrupts(facts: &mut [Facts]) {
    if facts.iter().all(|f| f.interrupts.is_empty()) {
        return;
    }
    let on: Vec<Option<u32>> = facts
        .iter()
        .flat_map(|f| f.switched_on.iter().copied())
        .collect();
    let any = on.iter().any(Option::is_none);
    for f in facts.iter_mut() {
        for (number, routine) in std::mem::take(&mut f.interrupts) {
            let runs = match number {
                Some(n) => any || on.contains(&Some(n)),
                None => !on.is_empty(),
            };
            if runs {
                f.unfollowed.push(routine);
            }
        }
    }
}

/// How many states a loop's top is followed from before the rest are joined into one.
const LOOP_STATES: usize = 8;

/// An open loop while following program order.
struct Loop<'e> {
    kind: LoopKind,
    /// The index of its first event and of its [`Event::EndLoop`].
    start: usize,
    end: usize,
    /// How many `IF`/`SWITCH` were open at its top.
    forks: usize,
    /// Every state its body has been followed from, the first the one before the loop.
    tops: Vec<State<'e>>,
    /// The states at the end of its body, and at each `EXIT`.
    ends: Vec<State<'e>>,
    exits: Vec<State<'e>>,
}

/// Program order within a routine: the state, the open `IF`/`SWITCH` and the open loops. A
/// loop's body is followed again from each state its end leaves that its top has not been
/// followed from (so a base set late in the body holds for the motions before it on the next
/// pass: such a motion is used with both), until no new one comes; after the loop, the state
/// is the join of those it may leave with.
#[derive(Default)]
struct Flow<'e> {
    state: State<'e>,
    forks: Vec<Fork<'e>>,
    loops: Vec<Loop<'e>>,
    /// Every copy of the routine, joined, once a label a jump back reaches has asked
    /// ([`routine_copies`]): found once a routine, not once a label.
    copies: Option<Aliases<'e>>,
    /// The state each jump forward was made with, by the index of its label's event: what it
    /// arrives there with.
    jumped: Vec<(usize, State<'e>)>,
    /// The states the routine has returned with at a `RETURN`.
    returned: Vec<State<'e>>,
    /// The IPO mode the jumps back to each label (by the index of its event) were made with,
    /// joined, over every routine of the file (kept by [`Flow::reset`]): what they bring there.
    /// A jump back is made after its label is passed, so [`routine_exits`] follows a routine
    /// again while this grows ([`Flow::back_grew`]), and resolution starts with what it found.
    jumped_back: HashMap<usize, MayTcp>,
    /// A jump back has brought its label an IPO mode [`Flow::jumped_back`] did not hold.
    back_grew: bool,
}

impl<'e> Flow<'e> {
    /// Program order at the start of a routine. What jumps back bring to labels is kept: the
    /// labels are the file's, each in one routine.
    fn reset(&mut self) {
        self.state = State::default();
        self.forks.clear();
        self.loops.clear();
        self.copies = None;
        self.jumped.clear();
        self.returned.clear();
    }

    /// What the routine leaves set when it returns: the states at its `RETURN`s and at its
    /// end, joined.
    fn exit_state(&self) -> State<'e> {
        if self.returned.is_empty() {
            return self.state.clone();
        }
        let mut all = self.returned.clone();
        all.push(self.state.clone());
        join(&all).unwrap_or_default()
    }

    /// Follows control event `ev`, the `i`th of `events`; returns the index of the event that
    /// follows it. `changes`: whether a call of the named routine changes the base, tool or
    /// staged FDAT.
    fn control(
        &mut self,
        i: usize,
        ev: &Event,
        events: &'e [Event],
        changes: &dyn Fn(&str) -> bool,
    ) -> usize {
        match ev {
            Event::Branch(b) => branch(&mut self.state, &mut self.forks, *b),
            Event::Loop { kind, end } if *end > i => self.loops.push(Loop {
                kind: *kind,
                start: i + 1,
                end: *end,
                forks: self.forks.len(),
                tops: vec![self.state.clone()],
                ends: Vec::new(),
                exits: Vec::new(),
            }),
            Event::Exit => {
                if let Some(l) = self.loops.last_mut() {
                    l.exits.push(self.state.clone());
                    // The rest of the body is not followed on this path.
                    self.state.dead = true;
                }
            }
            Event::EndLoop => return self.end_of_body(i),
            Event::Goto { label } => {
                // Forward, it arrives at its label with this state (from each pass of a loop
                // it is in); a path already left (a jump after a jump) brings nothing.
                match label.filter(|_| !self.state.dead) {
                    Some(to) if to > i => self.jumped.push((to, self.state.clone())),
                    Some(to) => {
                        let had = self.jumped_back.get(&to).copied();
                        let brings = had.map_or(self.state.tcp, |h| h.or(self.state.tcp));
                        if had != Some(brings) {
                            self.jumped_back.insert(to, brings);
                            self.back_grew = true;
                        }
                    }
                    None => {}
                }
                self.state.dead = true;
            }
            Event::Return => {
                if !self.state.dead {
                    self.returned.push(self.state.clone());
                }
                self.state.dead = true;
            }
            Event::Label { jumps } if !jumps.is_empty() => {
                if jumps.iter().any(|&from| from < i) {
                    self.arrive(i);
                }
                let back: Vec<usize> = jumps.iter().copied().filter(|&from| from > i).collect();
                if back.is_empty() {
                    return i + 1;
                }
                // A jump back arrives with the IPO mode it was made with: the label's is both
                // (only that, where no path falls through to it).
                let brought = self.jumped_back.get(&i).copied();
                self.state.tcp = match brought {
                    Some(b) if self.state.dead => b,
                    Some(b) => self.state.tcp.or(b),
                    None => self.state.tcp,
                };
                // And with what the names copied into held where it was made: any copy of the
                // routine, joined (rare: a label a `GOTO` names).
                let copies = self.copies.get_or_insert_with(|| routine_copies(events, i));
                self.state.aliases.absorb(copies);
                if jumps_keep_state(events, i, &back, changes) {
                    return i + 1;
                }
                self.state.dead = false;
                self.state.base = Some(FrameRef::Unknown);
                self.state.tool = Some(FrameRef::Unknown);
                // And what `FDAT_ACT` holds: a jump may skip or repeat an `FDAT_ACT = …`.
                self.state.staged = Some(Staged {
                    base: FrameRef::Unknown,
                    tool: FrameRef::Unknown,
                    tcp: self.state.staged.as_ref().is_some_and(|s| s.tcp),
                });
            }
            _ => {}
        }
        i + 1
    }

    /// At the label of event `i`, which jumps forward reach: the state is the join of what each
    /// brings and of the path that falls through, when that is not left by a jump (a forward
    /// jump's state is exactly what arrives: the base, tool and IPO mode it was made with, and
    /// what its copies hold, where the label made them unknown and took every copy of the
    /// routine). Unreached, the label stays left.
    fn arrive(&mut self, i: usize) {
        let mut arriving: Vec<State<'e>> = self
            .jumped
            .iter()
            .filter(|(to, _)| *to == i)
            .map(|(_, s)| s.clone())
            .collect();
        if !self.state.dead {
            arriving.push(std::mem::take(&mut self.state));
        }
        if let Some(state) = join(&arriving) {
            self.state = state;
        }
    }

    /// The end of a loop's body at event `i`: back to its top from a new state, or on after it.
    fn end_of_body(&mut self, i: usize) -> usize {
        let Some(l) = self.loops.last_mut().filter(|l| l.end == i) else {
            return i + 1;
        };
        // Blocks left open inside are joined on the way out.
        while self.forks.len() > l.forks {
            if let Some(f) = self.forks.pop() {
                self.state = f.join(std::mem::take(&mut self.state));
            }
        }
        let end = self.state.clone();
        // A body every path of which leaves by a `GOTO` comes round with nothing.
        if !end.dead && !l.ends.contains(&end) {
            l.ends.push(end.clone());
        }
        if !end.dead && !l.tops.contains(&end) && l.tops.len() <= LOOP_STATES {
            let next = if l.tops.len() < LOOP_STATES {
                end
            } else {
                // Too many to follow one by one: a last pass from what they all agree on.
                let mut all = l.tops.clone();
                all.push(end);
                join(&all).unwrap_or_default()
            };
            l.tops.push(next.clone());
            self.state = next;
            return l.start;
        }
        let Some(l) = self.loops.pop() else {
            return i + 1;
        };
        // The states the loop may be left with: at its test, and at each `EXIT`.
        let mut out = match l.kind {
            LoopKind::For | LoopKind::While => l.tops,
            LoopKind::Repeat => l.ends,
            LoopKind::Loop => Vec::new(),
        };
        out.extend(l.exits);
        if let Some(after) = join(&out) {
            self.state = after;
        }
        i + 1
    }
}

/// Every copy of the routine event `at` is in, joined (what a name may hold wherever a jump to
/// a label there is made).
fn routine_copies(events: &[Event], at: usize) -> Aliases<'_> {
    let is_reset = |e: &&Event| matches!(e, Event::Reset(_));
    let before = events.get(..at).unwrap_or_default();
    let start = before.len() - before.iter().rev().take_while(|e| !is_reset(e)).count();
    let mut out = Aliases::default();
    for ev in events
        .get(start..)
        .unwrap_or_default()
        .iter()
        .take_while(|e| {
            // The routine's own events: up to the next `DEF`.
            !is_reset(e)
        })
    {
        if let Event::Alias { name, source, .. } = ev {
            out.copy(name, source, true);
        }
    }
    out
}

/// Whether the label at event `at` is reached by its `GOTO`s back (`jumps`: the index the next
/// event has at each) only with the state program order brings there: each jumps back, and the events
/// between the label and it change no base, tool or staged FDAT (no setting, no call of a
/// routine that `changes` them, no other label a jump reaches), close or continue no block
/// opened before the label, and leave no loop open (a retry: `TOP: … IF NOT OK THEN GOTO TOP
/// ENDIF`). On every path from the label to such a jump the state stays the label's own, so
/// joining it there changes nothing. A jump forward, over a change, or from inside a loop whose
/// body goes on past it (round which the state may change) may arrive with another.
fn jumps_keep_state(
    events: &[Event],
    at: usize,
    jumps: &[usize],
    changes: &dyn Fn(&str) -> bool,
) -> bool {
    jumps.iter().all(|&to| {
        let Some(between) = events.get(at + 1..to).filter(|_| to > at) else {
            return false;
        };
        let (mut blocks, mut loops) = (0usize, 0usize);
        let kept = between.iter().all(|ev| match ev {
            Event::Set(_) | Event::Reset(_) => false,
            Event::Call { name, .. } => !changes(name),
            Event::Label { jumps } => jumps.is_empty(),
            Event::Alias { .. } | Event::Motion { .. } | Event::Goto { .. } | Event::Return => true,
            Event::Branch(BranchEvent::If | BranchEvent::Switch) => {
                blocks += 1;
                true
            }
            Event::Branch(BranchEvent::Otherwise | BranchEvent::Case) => blocks > 0,
            Event::Branch(BranchEvent::EndIf | BranchEvent::EndSwitch) => {
                blocks = blocks.wrapping_sub(1);
                blocks != usize::MAX
            }
            Event::Loop { .. } => {
                loops += 1;
                true
            }
            Event::EndLoop => {
                loops = loops.wrapping_sub(1);
                loops != usize::MAX
            }
            Event::Exit => loops > 0,
        });
        kept && loops == 0
    })
}

/// Whether an FDAT's `IPO_FRAME` may be `#TCP`: one that says `#BASE` is not; one no file given
/// declares (`FDAT_ACT = FPX` of a data list not given, `FDAT_ACT = PICK(I)`), or that does not
/// say, may be. Before, both were taken as `#BASE`: `$IPO_MODE = SIPO_MODE(FPX.IPO_FRAME)` then
/// `LIN XP1` corrected `XP1` as a tool on the flange, exit 0, whatever `FPX` holds.
fn may_be_tcp(f: Option<&Fdat>) -> bool {
    f.and_then(|f| f.tcp).unwrap_or(true)
}

impl State<'_> {
    fn apply(&mut self, s: &Setting, fdats: &HashMap<Name, Fdat>) {
        let data = |n: Option<u32>| n.map_or(FrameRef::Unknown, FrameRef::Data);
        let staged = |f: Option<&Fdat>| Staged {
            base: data(f.and_then(|f| f.base)),
            tool: data(f.and_then(|f| f.tool)),
            tcp: may_be_tcp(f),
        };
        match s {
            Setting::Base(r) => self.base = Some(r.clone()),
            Setting::Tool(r) => self.tool = Some(r.clone()),
            Setting::Tcp(t) => self.tcp = MayTcp::set(*t),
            Setting::TcpUnevaluated(_) => self.tcp = MayTcp::set(true),
            Setting::FdatValue(f) => self.staged = Some(staged(Some(f))),
            Setting::Fdat(name) => self.staged = Some(staged(fdats.get(name.as_str()))),
            Setting::ApplyFdat => match &self.staged {
                Some(f) => {
                    self.base = Some(f.base.clone());
                    self.tool = Some(f.tool.clone());
                    self.tcp = MayTcp::set(f.tcp);
                }
                // What `FDAT_ACT` held when the routine was entered (staged by a caller, or by a
                // program run before): not known here, its IPO frame neither.
                None => {
                    self.base = Some(FrameRef::Unknown);
                    self.tool = Some(FrameRef::Unknown);
                    self.tcp = MayTcp::set(true);
                }
            },
            Setting::BaseOfFdat(name) => {
                self.base = Some(data(fdats.get(name.as_str()).and_then(|f| f.base)));
            }
            Setting::ToolOfFdat(name) => {
                self.tool = Some(data(fdats.get(name.as_str()).and_then(|f| f.tool)));
            }
            Setting::TcpOfFdat(name) => {
                self.tcp = MayTcp::set(may_be_tcp(fdats.get(name.as_str())))
            }
        }
    }
}

/// What a routine leaves set when it returns (at its end or a `RETURN`): the base and tool it
/// sets, and what it leaves staged in `FDAT_ACT`, on every path (`None`: left as the caller had
/// it); `tcp`, whether `$IPO_MODE` may be `#TCP` then, by the mode the caller had (a routine
/// that sets `#BASE` on every path takes back a caller's `#TCP`; one that sets it on some
/// leaves the caller's).
#[derive(Clone, Default, PartialEq)]
struct Exit {
    base: Option<FrameRef>,
    tool: Option<FrameRef>,
    staged: Option<Staged>,
    tcp: MayTcp,
}

impl Exit {
    /// Whether the routine leaves the base, tool or staged FDAT changed, or may leave `#TCP`
    /// for a caller that had `#BASE`: what may make a motion after its call move otherwise than
    /// program order without it takes it to. Setting `#BASE` again does not count: it only
    /// takes back a stationary tool, and a motion taken to have one is refused as
    /// stationary-tool whatever else it may have.
    fn changes(&self) -> bool {
        self.base.is_some() || self.tool.is_some() || self.staged.is_some() || self.tcp.entered_base
    }

    fn apply_to(&self, state: &mut State<'_>) {
        state.tcp = state.tcp.then(self.tcp);
        if let Some(b) = &self.base {
            state.base = Some(b.clone());
        }
        if let Some(t) = &self.tool {
            state.tool = Some(t.clone());
        }
        if let Some(f) = &self.staged {
            state.staged = Some(f.clone());
        }
    }
}

use crate::resolve::CALL_DEPTH;

/// The names the calls pass to a parameter (not `:IN`) that its routine writes (`SETF(FP1)`
/// with `F.BASE_NO = 2` in `DEF SETF(F:OUT)`), upper case: written as the parameter is.
fn written_through_parameters(files: &[ParsedFile], facts: &[Facts]) -> Vec<String> {
    let mut out = Vec::new();
    for (fi, f) in facts.iter().enumerate() {
        let Some(src) = files.get(fi).map(|f| &f.source[..]) else {
            continue;
        };
        for call in &f.calls {
            let callee = call.callee.slice(src);
            let routine = facts.iter().zip(files).find_map(|(g, file)| {
                let r = g
                    .routines
                    .iter()
                    .find(|r| r.name.slice(&file.source).eq_ignore_ascii_case(callee))?;
                Some((g, r, &file.source[..]))
            });
            let Some((g, r, rsrc)) = routine else {
                continue;
            };
            for (arg, param) in call.args.iter().zip(&r.params) {
                let (Some(arg), false) = (arg, param.by_value) else {
                    continue;
                };
                let name = param.name.slice(rsrc);
                if g.written_in_routines
                    .iter()
                    .any(|w| w.as_bytes().eq_ignore_ascii_case(name))
                {
                    let text = arg.span().slice(src);
                    let whole = text.split(|&b| b == b'[').next().unwrap_or(text);
                    out.push(String::from_utf8_lossy(whole.trim_ascii()).to_ascii_uppercase());
                }
            }
        }
    }
    out
}

/// What program order brings into the routines of a program and to the labels jumps back
/// reach, found with the routines' exits ([`routine_exits`]).
#[derive(Default)]
struct Arrivals {
    /// The routines a call may enter with `$IPO_MODE` at `#TCP`, by module and name: each may
    /// run with the stationary tool, whatever else enters it; so may a routine run at any time
    /// (an interrupt's, a trigger's, a function) when the program may set `#TCP` anywhere. Any
    /// other is taken to be entered with `#BASE`, as KSS starts a program: the program's main
    /// routine, one only a program not given calls.
    tcp_entered: std::collections::HashSet<(usize, String)>,
    /// Per file, what the jumps back to each label bring there ([`Flow::jumped_back`]).
    jumped_back: Vec<HashMap<usize, MayTcp>>,
}

/// The [`Exit`] of every routine of the program (a subroutine that runs `BAS(#BASE,2)` or
/// `$BASE=BASE_DATA[2]` sets the base of the motions after its call), found by following each
/// routine's program order from an unknown entry; calls inside are followed by repeating this
/// up to [`CALL_DEPTH`] times (a cycle settles or stops there). With them, the [`Arrivals`]:
/// the IPO mode each call is made with, by the mode its routine is entered with, gives which
/// routines are entered with `#TCP` (followed through the calls to a fixed point); a routine
/// whose jumps back bring a label more than it was followed from is followed again.
fn routine_exits(
    facts: &[Facts],
    fdats: &[HashMap<Name, Fdat>],
    modules: &Modules,
) -> (Exits, Arrivals) {
    let mut exits = Exits::default();
    for (fi, f) in facts.iter().enumerate() {
        for name in &f.public_routines {
            exits.public.entry(name.clone()).or_insert(modules.of(fi));
        }
    }
    let no_fdats = HashMap::default();
    // Each call (its file, the routine it is made in, the routine called) with the IPO mode
    // it is made with, and what the jumps back of each file bring: of the last pass.
    let mut calls: Vec<(usize, Option<&str>, &str, MayTcp)> = Vec::new();
    let mut jumped_back: Vec<HashMap<usize, MayTcp>> = Vec::new();
    // Whether `$IPO_MODE` may be `#TCP` anywhere in the program (of the last pass): a routine
    // run at any time (an interrupt's, a trigger's, a function) may then be entered with it.
    let mut tcp_somewhere = false;
    for _ in 0..CALL_DEPTH {
        calls.clear();
        jumped_back.clear();
        tcp_somewhere = false;
        let mut next: std::collections::HashMap<(usize, String), Exit> = Default::default();
        for (fi, f) in facts.iter().enumerate() {
            let module = modules.of(fi);
            let changes = |name: &str| exits.of(module, name).is_some_and(Exit::changes);
            let fdats = fdats.get(module).unwrap_or(&no_fdats);
            let mut current: Option<&str> = None;
            let mut flow = Flow::default();
            // The index of the current routine's first event.
            let mut start = 0;
            let mut i = 0;
            loop {
                let ev = f.events.get(i);
                if let None | Some(Event::Reset(_)) = ev {
                    if std::mem::take(&mut flow.back_grew) {
                        // A jump back brings a label an IPO mode the routine was not followed
                        // with from there: again, with it.
                        flow.reset();
                        i = start;
                        continue;
                    }
                    if let Some(n) = current {
                        let state = flow.exit_state();
                        next.entry((module, n.to_owned())).or_insert(Exit {
                            base: state.base,
                            tool: state.tool,
                            staged: state.staged,
                            tcp: state.tcp,
                        });
                    }
                    let Some(Event::Reset(name)) = ev else {
                        break;
                    };
                    current = name.as_deref();
                    flow.reset();
                    i += 1;
                    start = i;
                    continue;
                }
                let Some(ev) = ev else { break };
                // Only a setting or a call makes the mode `#TCP` (a join keeps what its
                // paths had), and a routine entered with it is so because a call was made with
                // it: asked there, and of a motion's own `WITH`, for a routine entered with
                // `#BASE`.
                match ev {
                    Event::Call { name, .. } => {
                        calls.push((fi, current, name.as_str(), flow.state.tcp));
                        if let Some(exit) = exits.of(module, name) {
                            exit.apply_to(&mut flow.state);
                        }
                        tcp_somewhere |= flow.state.tcp.given(false);
                    }
                    Event::Set(s) => {
                        flow.state.apply(s, fdats);
                        tcp_somewhere |= flow.state.tcp.given(false);
                    }
                    Event::Motion { with, .. } if !with.is_empty() => {
                        let mut local = flow.state.frames();
                        for s in with {
                            local.apply(s, fdats);
                        }
                        tcp_somewhere |= local.tcp.given(false);
                    }
                    Event::Branch(_)
                    | Event::Loop { .. }
                    | Event::EndLoop
                    | Event::Exit
                    | Event::Return
                    | Event::Label { .. }
                    | Event::Goto { .. } => {
                        i = flow.control(i, ev, &f.events, &changes);
                        continue;
                    }
                    Event::Reset(_) | Event::Alias { .. } | Event::Motion { .. } => {}
                }
                i += 1;
            }
            jumped_back.push(flow.jumped_back);
        }
        if next == exits.by_routine {
            break;
        }
        exits.by_routine = next;
    }
    // A routine is entered with `#TCP` when a call may be made with it, given the mode the
    // calling routine is entered with: followed until no routine is added. A routine the
    // program runs at any time (an interrupt's once switched on, a trigger's, a function) is
    // entered with whatever mode holds where it fires: `#TCP` when the program may set it
    // anywhere (the join over every point it may fire at, taken whole).
    let mut tcp_entered: std::collections::HashSet<(usize, &str)> = Default::default();
    if tcp_somewhere {
        for (fi, f) in facts.iter().enumerate() {
            for name in &f.unfollowed {
                tcp_entered.extend(exits.routine(modules.of(fi), name));
            }
        }
    }
    loop {
        let mut added = false;
        for &(fi, caller, callee, tcp) in &calls {
            let module = modules.of(fi);
            let entered = caller.is_some_and(|c| tcp_entered.contains(&(module, c)));
            if !tcp.given(entered) {
                continue;
            }
            if let Some(key) = exits.routine(module, callee) {
                added |= tcp_entered.insert(key);
            }
        }
        if !added {
            break;
        }
    }
    let tcp_entered = tcp_entered
        .into_iter()
        .map(|(m, name)| (m, name.to_owned()))
        .collect();
    let arrivals = Arrivals {
        tcp_entered,
        jumped_back,
    };
    (exits, arrivals)
}

/// KSS's own routines, which programs call without defining them and which set no base, tool or
/// `FDAT_ACT`: messages (`MsgLib`), errors, strings, channels and pulses, torque and collision
/// monitoring, and what KSS's own `System/` modules call (the PLC handshake `P00`, the torque
/// monitoring `TQM_…` of `bas.src`, the mastering test `MASREF…` of `masref_main.src`), which
/// a robot tree's run leaves out. (`BAS` is read for what it sets.) Sorted.
const KSS_ROUTINES: &[&str] = &[
    "CAST_FROM",
    "CAST_TO",
    "CCLOSE",
    "CIOCTL",
    "CLEAR_KRLMSG",
    "COPEN",
    "CREAD",
    "CWAIT",
    "CWRITE",
    "ERR_CLEAR",
    "ERR_RAISE",
    "MASREFBACKG1",
    "MASREFBACKG2",
    "MASREFBACKG3",
    "MASREFSTARTG1",
    "MASREFSTARTG2",
    "MASREFSTARTG3",
    "MSGDIALOG",
    "MSGLOOP",
    "MSGNOTIFY",
    "MSGQUIT",
    "MSGSTATE",
    "ON_ERROR_PROCEED",
    "P00",
    "PULSE",
    "RESET_CD_PARAMS",
    "RESET_TORQUE_LIMITS",
    "SET_CD_PARAMS",
    "SET_KRLDLG",
    "SET_KRLMSG",
    "SET_TORQUE_LIMITS",
    "SREAD",
    "STRCLEAR",
    "STRCOPY",
    "SWRITE",
    "TQM_FIFO_READ",
    "TQM_INI",
];

/// Warns once about each routine the program calls that none of its files defines (and that
/// is not one of [`KSS_ROUTINES`]), at its first call, with how many calls there are: program
/// order takes such a call as leaving `$BASE`, `$TOOL` and `FDAT_ACT` as they were, which only
/// the routine's definition can confirm. A call only matters in a routine that moves, or one
/// another calls (whose exit its caller applies): one in a routine that does neither (a submit
/// interpreter's `sps.sub`) is not warned about.
fn warn_unknown_routines(
    files: &mut [ParsedFile],
    events: &[Vec<Event>],
    exits: &Exits,
    modules: &Modules,
) {
    // Every routine name a call names: its exit matters to the caller.
    let called: std::collections::HashSet<&str> = events
        .iter()
        .flatten()
        .filter_map(|e| match e {
            Event::Call { name, .. } => Some(name.as_str()),
            _ => None,
        })
        .collect();
    // Name → (file, place of the first call, how many calls), in the order first called.
    let mut unknown: Vec<(&str, usize, crate::syntax::Span, usize)> = Vec::new();
    for (fi, evs) in events.iter().enumerate() {
        let module = modules.of(fi);
        // Each routine's events, and its name (on the `Reset` that starts them).
        let mut at = 0;
        while at < evs.len() {
            let name = match evs.get(at) {
                Some(Event::Reset(name)) => {
                    at += 1;
                    name.as_deref()
                }
                _ => None,
            };
            let len = evs
                .get(at..)
                .unwrap_or_default()
                .iter()
                .take_while(|e| !matches!(e, Event::Reset(_)))
                .count();
            let routine = evs.get(at..at + len).unwrap_or_default();
            at += len;
            let moves = routine.iter().any(|e| matches!(e, Event::Motion { .. }));
            if !moves && !name.is_some_and(|n| called.contains(n)) {
                continue;
            }
            for ev in routine {
                let Event::Call { name, at } = ev else {
                    continue;
                };
                if exits.of(module, name).is_some()
                    || KSS_ROUTINES.binary_search(&name.as_str()).is_ok()
                {
                    continue;
                }
                match unknown.iter_mut().find(|u| u.0 == name.as_str()) {
                    Some(u) => u.3 += 1,
                    None => unknown.push((name.as_str(), fi, *at, 1)),
                }
            }
        }
    }
    for (_, fi, at, calls) in unknown {
        let Some(file) = files.get_mut(fi) else {
            continue;
        };
        let more = match calls {
            1 => String::new(),
            n => format!(" (the first of {n} calls)"),
        };
        let written = crate::syntax::latin1(at.slice(&file.source));
        file.diagnostics.push(
            Diagnostic::warning(
                at,
                format!(
                    "`{written}` is called here{more}, but none of the files given defines it: trackfix takes it as leaving $BASE, $TOOL, $IPO_MODE and FDAT_ACT as they were for the motions after it"
                ),
            )
            .with_hint(format!(
                "give the module or folder that defines `{written}` with the program (or the robot's whole tree), so that what it sets is followed"
            ))
            .shaping_transforms(),
        );
        file.diagnostics.sort_by_key(|d| d.span.start);
    }
}

/// The [`Exit`] of every routine, by module and name, and the modules whose routines of a
/// name other modules call.
#[derive(Default)]
struct Exits {
    by_routine: std::collections::HashMap<(usize, String), Exit>,
    /// A routine name other modules may call → the module it is in (the first that has it).
    public: std::collections::HashMap<String, usize>,
}

impl Exits {
    /// What a call of `name` from `module` leaves set: the module's own routine of that name,
    /// else a public one of another module (KRL calls a `DEF` of another module only when it
    /// is that module's own or `GLOBAL`).
    fn of(&self, module: usize, name: &str) -> Option<&Exit> {
        self.called(module, name).map(|(_, exit)| exit)
    }

    /// The routine a call of `name` from `module` runs, by module and name.
    fn routine<'n>(&self, module: usize, name: &'n str) -> Option<(usize, &'n str)> {
        self.called(module, name).map(|(m, _)| (m, name))
    }

    /// The module of the routine a call of `name` from `module` runs, and its exit.
    fn called(&self, module: usize, name: &str) -> Option<(usize, &Exit)> {
        if let Some(exit) = self.by_routine.get(&(module, name.to_owned())) {
            return Some((module, exit));
        }
        let &m = self.public.get(name)?;
        Some((m, self.by_routine.get(&(m, name.to_owned()))?))
    }
}

/// Which files of a program are one module: a `.src` and the `.dat` of the same name in the
/// same folder. A `$config.dat` is a module of its own whose declarations every module sees;
/// of another module, a module sees only what is declared `GLOBAL`.
struct Modules {
    /// Each file's module.
    of: Vec<usize>,
    /// Per file: a `$config.dat`.
    global: Vec<bool>,
    /// How many modules.
    count: usize,
}

impl Modules {
    fn new(files: &[ParsedFile]) -> Modules {
        let mut ids: std::collections::HashMap<(Option<&std::path::Path>, String), usize> =
            Default::default();
        let mut of = Vec::with_capacity(files.len());
        let mut global = Vec::with_capacity(files.len());
        let mut count = 0;
        for f in files {
            let name = f
                .path
                .file_name()
                .map(|n| n.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            let is_config = name == "$config.dat";
            let stem = f
                .path
                .file_stem()
                .map(|n| n.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            let id = if is_config {
                count += 1;
                count - 1
            } else {
                *ids.entry((f.path.parent(), stem)).or_insert_with(|| {
                    count += 1;
                    count - 1
                })
            };
            of.push(id);
            global.push(is_config);
        }
        Modules { of, global, count }
    }

    fn of(&self, file: usize) -> usize {
        self.of.get(file).copied().unwrap_or(file)
    }

    fn is_global(&self, file: usize) -> bool {
        self.global.get(file).copied().unwrap_or(false)
    }

    /// Per module, what its files give (moved, not copied), then what the global files give
    /// that the module lacks (copied: a `$config.dat` is small beside the programs).
    fn gathered<V: Clone>(&self, per_file: Vec<HashMap<Name, V>>) -> Vec<HashMap<Name, V>> {
        let mut out: Vec<HashMap<Name, V>> = (0..self.count).map(|_| HashMap::default()).collect();
        let mut globals: Vec<(Name, V)> = Vec::new();
        for (fi, own) in per_file.into_iter().enumerate() {
            if self.is_global(fi) {
                globals.extend(own.iter().map(|(k, v)| (k.clone(), v.clone())));
            }
            let Some(all) = out.get_mut(self.of(fi)) else {
                continue;
            };
            if all.is_empty() {
                *all = own;
            } else {
                for (k, v) in own {
                    all.entry(k).or_insert(v);
                }
            }
        }
        if !globals.is_empty() {
            for all in &mut out {
                for (k, v) in &globals {
                    all.entry(k.clone()).or_insert_with(|| v.clone());
                }
            }
        }
        out
    }

    /// Per file, which of its positions other modules see (`None`: all, a `$config.dat`'s):
    /// those declared `GLOBAL`.
    fn exported(&self, files: &[ParsedFile], facts: &[Facts]) -> Vec<Option<Vec<bool>>> {
        files
            .iter()
            .zip(facts)
            .enumerate()
            .map(|(fi, (f, fact))| {
                if self.is_global(fi) {
                    return None;
                }
                let n = f.positions.len();
                if fact.globals.is_empty() {
                    return Some(vec![false; n]);
                }
                let globals: std::collections::HashSet<&str> =
                    fact.globals.iter().map(Name::as_str).collect();
                Some(
                    (0..n)
                        .map(|i| {
                            f.positions.name(i).is_some_and(|name| {
                                let key = name_key(name);
                                // `S1.P` is seen where the structure `S1` is.
                                let whole = key.split(['[', '.']).next();
                                globals.contains(whole.unwrap_or_default())
                            })
                        })
                        .collect(),
                )
            })
            .collect()
    }
}

/// Program order at `IF`/`SWITCH`: fork, switch branch, or join.
fn branch<'e>(state: &mut State<'e>, forks: &mut Vec<Fork<'e>>, b: BranchEvent) {
    match b {
        BranchEvent::If | BranchEvent::Switch => {
            forks.push(Fork::new(b == BranchEvent::If, state));
        }
        BranchEvent::Otherwise | BranchEvent::Case => {
            if let Some(f) = forks.last_mut() {
                if f.in_branch {
                    f.outcomes.push(state.clone());
                }
                f.in_branch = true;
                f.exhaustive |= b == BranchEvent::Otherwise;
                *state = f.entry.clone();
            }
        }
        BranchEvent::EndIf | BranchEvent::EndSwitch => {
            // Blocks left open inside are joined on the way out.
            let want_if = b == BranchEvent::EndIf;
            while let Some(f) = forks.pop() {
                let done = f.is_if == want_if;
                *state = f.join(std::mem::take(state));
                if done {
                    break;
                }
            }
        }
    }
}

/// Resolves base, tool and IPO mode of every motion of a program (files in the same order as
/// `facts`) by following program order, hands each motion to the shared usage pass
/// ([`crate::resolve::Binder`]) to fill the [`Usage`](crate::position::Usage) of the positions
/// it uses, promotes used `FRAME`s and candidate aggregates to positions, and reports motions
/// whose base stays unknown.
/// `config_frames`: frames declared outside `files` (the cell's `$config.dat`), whose values
/// an assignment in the program may repeat.
pub(crate) fn resolve(files: &mut [ParsedFile], facts: &mut [Facts], config_frames: &[FrameDecl]) {
    let modules = Modules::new(files);
    switched_on_interrupts(facts);
    let shared_copies: Vec<Vec<SharedCopy>> = facts
        .iter_mut()
        .map(|f| std::mem::take(&mut f.shared_copies))
        .collect();
    let shared = if shared_copies.iter().all(Vec::is_empty) {
        Vec::new()
    } else {
        shared_by_module(&shared_copies, facts, &modules)
    };
    let (no_aliases, no_anytime) = (Aliases::default(), HashMap::default());
    // A module's own `FDAT`s, then `$config.dat`'s: `FP1` is in nearly every data list.
    // An FDAT a routine assigns anywhere in the program holds, when a motion applies it, a
    // value trackfix does not follow: it is left out, so the base and tool it sets are unknown.
    let mut own_fdats: Vec<HashMap<Name, Fdat>> = facts
        .iter_mut()
        .map(|f| std::mem::take(&mut f.fdats))
        .collect();
    if facts.iter().any(|f| !f.written_in_routines.is_empty()) {
        let mut written: std::collections::HashSet<String> = facts
            .iter()
            .flat_map(|f| f.written_in_routines.iter().map(|n| n.to_string()))
            .collect();
        written.extend(written_through_parameters(files, facts));
        for f in &mut own_fdats {
            f.retain(|name, _| !written.contains(name.as_str()));
        }
    }
    // A module's `GLOBAL` FDATs are every module's too, after its own and `$config.dat`'s.
    let exported: Vec<(Name, Fdat)> = facts
        .iter()
        .zip(&own_fdats)
        .flat_map(|(f, own)| {
            let found = f
                .global_fdats
                .iter()
                .filter_map(|n| own.get_key_value(n.as_str()));
            found.map(|(k, v)| (k.clone(), v.clone()))
        })
        .collect();
    let mut fdats = modules.gathered(own_fdats);
    for all in fdats.iter_mut().filter(|_| !exported.is_empty()) {
        for (k, v) in &exported {
            all.entry(k.clone()).or_insert_with(|| v.clone());
        }
    }
    // Candidates that are positions whether or not a motion uses them.
    let mut kept: Vec<Vec<bool>> = facts
        .iter()
        .map(|f| vec![false; f.candidates.len()])
        .collect();
    // `XP1={…}` in the `.src` of a point the `.dat` declares (`DECL POS XP1`): the declaration
    // gives the kind, and the fields the aggregate may give; a non-FRAME declared point is a
    // position whether or not it moves.
    let declared = modules.gathered(
        facts
            .iter_mut()
            .map(|f| std::mem::take(&mut f.declared))
            .collect(),
    );
    let no_declared = HashMap::default();
    let pairs = files.iter_mut().zip(facts.iter_mut()).zip(kept.iter_mut());
    for (fi, ((file, fact), kept)) in pairs.enumerate() {
        let declared = declared.get(modules.of(fi)).unwrap_or(&no_declared);
        let Facts {
            candidates,
            inferred,
            ..
        } = fact;
        for ((p, guessed), k) in candidates.iter_mut().zip(inferred.iter()).zip(kept) {
            let (Some(name), Some(fields)) = (p.name.as_deref(), guessed) else {
                continue;
            };
            let key = name_key(name);
            let base = key.split('[').next().unwrap_or_default();
            let kind = declared.get(base).copied();
            file.diagnostics
                .extend(guessed_field_problem(&file.source, fields, kind, name));
            if let Some(kind) = kind {
                p.kind = kind;
                if kind == PositionKind::Frame {
                    p.config = Config::None;
                } else {
                    *k = true;
                }
            }
        }
    }
    let (exits, mut arrivals) = routine_exits(facts, &fdats, &modules);
    // A routine run where trackfix does not follow it (a function, an interrupt's or a
    // trigger's) that leaves the base or tool changed: the first, by name.
    let changing: Vec<&str> = facts
        .iter()
        .enumerate()
        .flat_map(|(fi, f)| {
            let module = modules.of(fi);
            let exits = &exits;
            f.unfollowed.iter().filter_map(move |name| {
                let exit = exits.of(module, name)?;
                exit.changes().then_some(name.as_str())
            })
        })
        .collect();
    // Named somewhere besides its own `DEF`/`DEFFCT` line (a call, an interrupt's `DO`): one
    // nothing names never runs.
    let unfollowed: Option<String> = if changing.is_empty() {
        None
    } else {
        let mut named: HashMap<&str, usize> = HashMap::default();
        for f in files.iter() {
            for (name, n) in word_counts(&f.source, changing.iter().copied()) {
                *named.entry(name).or_default() += n;
            }
        }
        changing
            .iter()
            .find(|name| named.get(*name).copied().unwrap_or(0) > 1)
            .map(|name| name.to_string())
    };
    let events: Vec<Vec<Event>> = facts
        .iter_mut()
        .map(|f| std::mem::take(&mut f.events))
        .collect();
    warn_unknown_routines(files, &events, &exits, &modules);
    // A call passes names to a routine of the program that takes parameters.
    let passes =
        facts.iter().any(|f| !f.calls.is_empty()) && facts.iter().any(|f| !f.routines.is_empty());
    // Each file's copies (`XC = XP1`: name → source), wherever they are: a copy passed to a
    // routine passes what it may hold. Only asked when a call passes names.
    let copies: Vec<Vec<(String, String)>> =
        if passes || facts.iter().any(|f| !f.handed_back.is_empty()) {
            events
                .iter()
                .map(|evs| {
                    evs.iter()
                        .filter_map(|e| match e {
                            Event::Alias { name, source, .. } if name != source => {
                                Some((name.to_string(), source.to_string()))
                            }
                            _ => None,
                        })
                        .collect()
                })
                .collect()
        } else {
            Vec::new()
        };
    // The candidates go after each file's positions while the motions are bound: a motion may
    // use them.
    let counts: Vec<usize> = files.iter().map(|f| f.positions.len()).collect();
    for (file, fact) in files.iter_mut().zip(facts.iter_mut()) {
        file.positions
            .extend(std::mem::take(&mut fact.candidates), &file.source);
    }
    // The points held in structures' members, reached from the structure's name.
    let members = if facts.iter().any(|f| f.holds_members) {
        Members::of(files)
    } else {
        Members::default()
    };
    // Per file, the motions to warn about: a Cartesian target and no base.
    let mut unresolved: Vec<Vec<crate::syntax::Span>> = vec![Vec::new(); files.len()];
    {
        let exported = modules.exported(files, facts);
        let (mut bound, lines): (Vec<_>, Vec<_>) = files
            .iter_mut()
            .zip(&exported)
            .enumerate()
            .map(|(fi, (f, e))| shared_facts(f, &[], &[], modules.of(fi), e.as_deref()))
            .unzip();
        let mut binder = crate::resolve::Binder::new(&mut bound, &NAMING);
        let no_fdats = HashMap::default();
        let mut labels = FrameLabels::default();
        for (fi, events) in events.into_iter().enumerate() {
            // The targets and names of a motion, buffers reused from motion to motion.
            let mut targets: Vec<usize> = Vec::new();
            let mut folded: Vec<&str> = Vec::new();
            let mut more: Vec<&str> = Vec::new();
            let own = counts.get(fi).copied().unwrap_or_default();
            let mut inline_at: Option<HashMap<crate::syntax::Span, usize>> = None;
            let mut flow = Flow::default();
            if let Some(back) = arrivals.jumped_back.get_mut(fi) {
                flow.jumped_back = std::mem::take(back);
            }
            // Whether the routine followed is entered with `#TCP` by a call.
            let mut tcp_entered = false;
            let module = modules.of(fi);
            let changes = |name: &str| exits.of(module, name).is_some_and(Exit::changes);
            let fdats = fdats.get(module).unwrap_or(&no_fdats);
            let (entry, anytime) = shared
                .get(module)
                .map_or((&no_aliases, &no_anytime), |s| (&s.entry, &s.anytime));
            let mut i = 0;
            while let Some(ev) = events.get(i) {
                i += 1;
                match ev {
                    Event::Reset(name) => {
                        tcp_entered = !arrivals.tcp_entered.is_empty()
                            && name.as_ref().is_some_and(|n| {
                                arrivals.tcp_entered.contains(&(module, n.clone()))
                            });
                        flow.reset();
                        // What a copy into a name other routines see left there, on an earlier
                        // call of this routine or of another.
                        flow.state.aliases = entry.clone();
                    }
                    Event::Call { name, .. } => {
                        if let Some(exit) = exits.of(module, name) {
                            exit.apply_to(&mut flow.state);
                        }
                        // The routine, or one it calls, may copy into such a name.
                        flow.state.aliases.absorb(entry);
                    }
                    Event::Branch(_)
                    | Event::Loop { .. }
                    | Event::EndLoop
                    | Event::Exit
                    | Event::Return
                    | Event::Label { .. }
                    | Event::Goto { .. } => {
                        i = flow.control(i - 1, ev, &events, &changes);
                    }
                    Event::Alias {
                        name,
                        source,
                        joined,
                    } => flow.state.aliases.copy(name, source, *joined),
                    Event::Set(s) => flow.state.apply(s, fdats),
                    Event::Motion {
                        span,
                        line,
                        refs,
                        with,
                    } => {
                        let mut local = flow.state.frames();
                        for s in with {
                            local.apply(s, fdats);
                        }
                        targets.clear();
                        folded.clear();
                        for r in refs {
                            match r {
                                // An inline literal is one of the file's own positions:
                                // the first with its span, found through a table made at
                                // the file's first inline literal (a scan of the positions
                                // per literal was quadratic in a file's inline motions).
                                Ref::Inline(s) => {
                                    let at = inline_at.get_or_insert_with(|| {
                                        let mut at = HashMap::default();
                                        if let Some((ps, _)) = binder.positions(fi) {
                                            for i in 0..own.min(ps.len()) {
                                                if let Some(span) = ps.span(i) {
                                                    at.entry(span).or_insert(i);
                                                }
                                            }
                                        }
                                        at
                                    });
                                    targets.extend(at.get(s).copied());
                                }
                                Ref::Named(n) => {
                                    // The name itself, then what it may have been copied
                                    // from on this path (and what a function it was given
                                    // reads, and what a copy run at any time puts there),
                                    // and so on back, `FOLDED` names at most.
                                    let start = folded.len();
                                    folded.push(n.as_str());
                                    if flow.state.aliases.is_empty() && anytime.is_empty() {
                                        continue;
                                    }
                                    let mut at = start;
                                    while at < folded.len() && folded.len() - start < FOLDED {
                                        let name = folded.get(at).copied().unwrap_or_default();
                                        at += 1;
                                        more.clear();
                                        flow.state.aliases.sources(name, &mut more);
                                        if let Some(then) = anytime.get(name) {
                                            more.extend(then.iter().map(String::as_str));
                                        }
                                        for &next in &more {
                                            let chain = folded.get(start..).unwrap_or_default();
                                            if !chain.contains(&next)
                                                && folded.len() - start < FOLDED
                                            {
                                                folded.push(next);
                                            }
                                        }
                                    }
                                }
                            }
                        }
                        if !members.is_empty() {
                            members.extend(&mut folded);
                        }
                        let u = crate::resolve::Use {
                            line: *line,
                            frame: local.base.as_ref().and_then(|b| labels.get(b, false)),
                            tool: local.tool.as_ref().and_then(|t| labels.get(t, true)),
                            stationary: local.tcp.given(tcp_entered),
                            run_time: match (&local.base, lines.get(fi)) {
                                (Some(FrameRef::RunTime(at)), Some(l)) => {
                                    Some(RunTimeValue::Frame {
                                        name: None,
                                        at: UseLine::new(l.line(at.start)),
                                    })
                                }
                                _ => None,
                            },
                            folded: &folded,
                            targets: &targets,
                            ..Default::default()
                        };
                        // A motion to a point outside the program (`XHOME` of $config.dat) is
                        // not this program's business, nor is one to a joint target only (it
                        // moves the same whatever the base).
                        binder.bind(fi, &u);
                        if let Some(routine) = &unfollowed
                            && u.run_time.is_none()
                            && binder.reached_cartesian()
                        {
                            binder.mark_reached(fi, |elsewhere, usage| {
                                usage.mark_unresolved_frame(UnresolvedFrame {
                                    at: UseLine {
                                        line: *line,
                                        file: elsewhere.cloned(),
                                    },
                                    cause: UnresolvedCause::ChangedBy(routine.clone()),
                                });
                            });
                        }
                        if u.frame.is_none() && binder.reached_cartesian() {
                            // Whatever base its other motions use, the point's is not known
                            // (a base computed at run time is refused as such).
                            if u.run_time.is_none() {
                                binder.mark_reached(fi, |elsewhere, usage| {
                                    usage.mark_unresolved_frame(UnresolvedFrame {
                                        at: UseLine {
                                            line: *line,
                                            file: elsewhere.cloned(),
                                        },
                                        cause: UnresolvedCause::SomePaths,
                                    });
                                });
                            }
                            if let Some(w) = unresolved.get_mut(fi) {
                                w.push(*span);
                            }
                        }
                    }
                }
            }
        }
        binder.finish();
    }
    for (fi, file) in files.iter_mut().enumerate() {
        // A motion in a loop followed from several states is warned about once.
        if let Some(w) = unresolved.get_mut(fi) {
            w.sort_by_key(|s| s.start);
            w.dedup();
        }
        for &span in unresolved.get(fi).into_iter().flatten() {
            file.diagnostics.push(
                Diagnostic::warning(span, "the base of this motion is not resolved").with_hint(
                    "set $BASE=BASE_DATA[n] or BAS(#BASE,n), or FDAT_ACT then BAS(#PTP_PARAMS,…) or BAS(#CP_PARAMS,…), before it in the same DEF",
                ),
            );
        }
        let (Some(fact), Some(kept)) = (facts.get_mut(fi), kept.get(fi)) else {
            continue;
        };
        let cands = file
            .positions
            .split_off(counts.get(fi).copied().unwrap_or_default(), &file.source);
        let mut promoted = false;
        for (p, &k) in cands.into_iter().zip(kept) {
            if k || !p.usage.lines.is_empty() {
                file.positions.push(p, &file.source);
                promoted = true;
            } else {
                fact.candidates.push(p);
            }
        }
        if promoted {
            file.positions.sort_by_start();
        }
        file.diagnostics.sort_by_key(|d| d.span.start);
    }
    // The positions are in their final order now (candidates promoted, sorted).
    let exported = modules.exported(files, facts);
    frames_of_unused_points(files, &exported, &fdats, &modules);
    mark_offsets(files, facts, &modules, &exported);
    // The routines, for the binder: only when a routine gives a parameter a computed value,
    // or a call passes a name to a routine of the program.
    let follow = passes
        || facts
            .iter()
            .any(|f| !f.param_assignments.is_empty() || !f.handed_back.is_empty());
    let routines: Vec<Vec<crate::resolve::Routine>> = if follow {
        facts
            .iter()
            .map(|f| {
                f.routines
                    .iter()
                    .map(|r| crate::resolve::Routine {
                        name: r.name,
                        local: !r.public,
                        params: r.params.iter().map(|p| p.name).collect(),
                        optional: Vec::new(),
                    })
                    .collect()
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut shared: Vec<crate::resolve::FileFacts<'_>> = files
        .iter_mut()
        .zip(facts.iter())
        .zip(&exported)
        .enumerate()
        .map(|(fi, ((file, fact), e))| {
            let routines = routines.get(fi).map_or(&[][..], Vec::as_slice);
            shared_facts(
                file,
                &fact.assignments,
                routines,
                modules.of(fi),
                e.as_deref(),
            )
            .0
        })
        .collect();
    if follow {
        computed_through_parameters(&mut shared, facts, &copies);
    }
    crate::resolve::mark_run_time(&mut shared, &NAMING);
    drop(shared);
    mark_assigned_data(files, facts, config_frames);
}

/// The points held in structures' members (`S1.P` of `DECL SPT S1={P {X …}, K 1}`,
/// [`UnresolvedCause::Member`]), by the structure they are in: a motion to the structure's
/// member (`LIN S1.P`), or to a copy of it (`XC = S1.P`, `S2 = S1`), reaches them through the
/// structure's name. Every transform refuses them; reached, they are used as the points
/// motions reach are (their lines and bases shown, a `$config.dat`'s kept).
#[derive(Default)]
struct Members {
    /// Structure (`S1`, `SA[1]`, upper case) → the names of the points its members hold.
    of: HashMap<String, Vec<String>>,
    /// Array of structures (`SA`) → the names of the points its elements' members hold.
    arrays: HashMap<String, Vec<String>>,
}

impl Members {
    fn of(files: &[ParsedFile]) -> Members {
        let mut out = Members::default();
        for f in files {
            for (i, u) in f.positions.usages().enumerate() {
                let Some(UnresolvedCause::Member(whole)) = u.unresolved_frame().map(|u| &u.cause)
                else {
                    continue;
                };
                let (Some(name), whole) = (f.positions.name(i), name_key(whole)) else {
                    continue;
                };
                let name = name_key(name);
                if let Some((array, _)) = whole.split_once('[') {
                    out.arrays
                        .entry(array.to_owned())
                        .or_default()
                        .push(name.clone());
                }
                out.of.entry(whole).or_default().push(name);
            }
        }
        out
    }

    fn is_empty(&self) -> bool {
        self.of.is_empty()
    }

    /// Adds to `folded` (a motion's names) the points held in the members of each structure
    /// among them: of the element named, of every element for one chosen at run time (`SA[I]`)
    /// or for the whole array (`SA`).
    fn extend<'m>(&'m self, folded: &mut Vec<&'m str>) {
        for k in 0..folded.len() {
            let Some(&name) = folded.get(k) else { break };
            let key = name_key(name);
            let array = match key.split_once('[') {
                Some((array, _)) if computed_index(&key) => Some(array),
                Some(_) => None,
                None => Some(key.as_str()),
            };
            let found = self.of.get(key.as_str()).into_iter().flatten();
            let elements = array.and_then(|a| self.arrays.get(a)).into_iter().flatten();
            for member in found.chain(elements) {
                if !folded.contains(&member.as_str()) {
                    folded.push(member);
                }
            }
        }
    }
}

/// A Cartesian point the program never names again takes the base and tool of its inline
/// form's `FDAT` (`FP1` for `XP1`, found as a motion's `FDAT_ACT = FP1` finds it): the frames it
/// was taught in, which the motion the inline form writes moves to it with (docs/design.md,
/// "Points no motion uses"). Without them its base is unknown and the transforms refuse it. A
/// point named anywhere but its declaration (passed to a subroutine, copied, read, or only in a
/// comment) is not taken: a motion trackfix does not follow may reach it. One note per file
/// names them: what the transforms do with them rests on it. `exported`: per file, which
/// positions other modules see ([`Modules::exported`]; `None`: all).
fn frames_of_unused_points(
    files: &mut [ParsedFile],
    exported: &[Option<Vec<bool>>],
    fdats: &[HashMap<Name, Fdat>],
    modules: &Modules,
) {
    // (file, index, the point's name upper-cased, its FDAT's name): the points no motion
    // uses that have an FDAT of their name.
    let mut candidates: Vec<(usize, usize, String, String)> = Vec::new();
    for (fi, file) in files.iter().enumerate() {
        let Some(fdats) = fdats.get(modules.of(fi)).filter(|f| !f.is_empty()) else {
            continue;
        };
        for i in 0..file.positions.len() {
            let unused = file
                .positions
                .usage(i)
                .is_some_and(|u| u.lines.is_empty() && u.wobj.is_none());
            if !unused || !file.positions.has_cartesian(i) {
                continue;
            }
            let Some(name) = file.positions.name(i) else {
                continue;
            };
            // The inline form's names: `X` and `F` before the point's own.
            let Some(own) = name
                .strip_prefix(['X', 'x'])
                .filter(|n| !n.is_empty() && !n.contains('['))
            else {
                continue;
            };
            let key = format!("F{}", own.to_ascii_uppercase());
            if fdats.contains_key(key.as_str()) {
                candidates.push((fi, i, name.to_ascii_uppercase(), key));
            }
        }
    }
    if candidates.is_empty() {
        return;
    }
    // Per file, how often it names each.
    let mentions: Vec<HashMap<&str, usize>> = files
        .iter()
        .map(|f| word_counts(&f.source, candidates.iter().map(|c| c.2.as_str())))
        .collect();
    let mut labels = FrameLabels::default();
    let data = |n: Option<u32>| n.map_or(FrameRef::Unknown, FrameRef::Data);
    // Per file: (point, FDAT, span) of each point taken.
    let mut taken: Vec<Vec<(String, String, crate::syntax::Span)>> = vec![Vec::new(); files.len()];
    for (fi, i, name, key) in &candidates {
        let (fi, i) = (*fi, *i);
        // Named where it is seen: its module's files, and every file for a global point.
        let global = exported
            .get(fi)
            .is_none_or(|e| e.as_ref().is_none_or(|e| e.get(i).copied().unwrap_or(true)));
        let named: usize = mentions
            .iter()
            .enumerate()
            .filter(|&(fj, _)| global || modules.of(fj) == modules.of(fi))
            .filter_map(|(_, m)| m.get(name.as_str()))
            .sum();
        // Its declaration is the one mention a point no one names has.
        if named > 1 {
            continue;
        }
        let (Some(file), Some(f)) = (
            files.get_mut(fi),
            fdats.get(modules.of(fi)).and_then(|f| f.get(key.as_str())),
        ) else {
            continue;
        };
        let Some(base) = labels.get(&data(f.base), false) else {
            continue;
        };
        let tool = labels.get(&data(f.tool), true);
        let (label, span) = (
            file.positions.name(i).unwrap_or_default().to_owned(),
            file.positions.span(i),
        );
        if let (Some(u), Some(list)) = (file.positions.usage_mut(i), taken.get_mut(fi)) {
            u.record_frames(Some(&base), tool.as_ref(), f.tcp.unwrap_or(false));
            list.push((label, key.clone(), span.unwrap_or_default()));
        }
    }
    for (file, taken) in files.iter_mut().zip(taken) {
        let Some((first, first_fdat, span)) = taken.first() else {
            continue;
        };
        let message = match taken.len() {
            1 => format!(
                "`{first}` is named by no motion nor any other statement: trackfix takes it in the base and tool of its FDAT `{first_fdat}`"
            ),
            n => format!(
                "{n} points named by no motion nor any other statement ({}{}) are taken in the bases and tools of their FDATs (`{first_fdat}`, …)",
                taken
                    .iter()
                    .take(4)
                    .map(|(n, ..)| format!("`{n}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                if n > 4 { ", …" } else { "" }
            ),
        };
        file.diagnostics.push(
            Diagnostic::new(crate::syntax::Severity::Note, *span, message)
                .with_hint("the frames their inline forms would move to them with; delete the points no program moves to")
                .shaping_transforms(),
        );
        file.diagnostics.sort_by_key(|d| d.span.start);
    }
}

/// How often each of `names` (upper-case) stands as a word (a KRL name: letters, digits, `_`,
/// `$`) in `src`, compared without case; comments and strings count too.
fn word_counts<'n>(src: &[u8], names: impl Iterator<Item = &'n str>) -> HashMap<&'n str, usize> {
    let mut counts: HashMap<&'n str, usize> = names.map(|n| (n, 0)).collect();
    let longest = counts.keys().map(|n| n.len()).max().unwrap_or(0);
    let is_word = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b == b'$';
    let mut word = String::new();
    let mut k = 0;
    while k < src.len() {
        if !src.get(k).copied().is_some_and(is_word) {
            k += 1;
            continue;
        }
        let start = k;
        while src.get(k).copied().is_some_and(is_word) {
            k += 1;
        }
        if k - start > longest {
            continue;
        }
        word.clear();
        word.extend(
            src.get(start..k)
                .unwrap_or_default()
                .iter()
                .map(|b| char::from(b.to_ascii_uppercase())),
        );
        if let Some(c) = counts.get_mut(word.as_str()) {
            *c += 1;
        }
    }
    counts
}

/// Marks every target moved to with a base or tool the program assigns when it runs
/// (`BASE_DATA[1] = BASE_DATA[2]`, `TOOL_DATA[1].Z = 300`; `BASE_DATA[I] = …` may be any of
/// them) as used with a frame computed at run time, the first such assignment's line and file
/// named: `BAS(#BASE,1)` reads the value the element has then, not the one `$config.dat` gives
/// it. Flow-insensitive, as every computed assignment; and by number, whether or not
/// `$config.dat` declares the element. A whole literal value (`TOOL_DATA[1] = {X 0, …}` in a
/// `DEF`) is known offline: one that is the declaration's changes nothing, and another marks
/// the targets as given a frame of two values (docs/design.md, "Frames the program assigns":
/// the value is given in another file than the declaring `$config.dat`, so which one a motion
/// runs with depends on the flow).
fn mark_assigned_data(files: &mut [ParsedFile], facts: &[Facts], config_frames: &[FrameDecl]) {
    if facts.iter().all(|f| f.data_assignments.is_empty()) {
        return;
    }
    let prefix = |tool: bool| if tool { "TOOL_DATA" } else { "BASE_DATA" };
    // The declarations: frames no routine assigns.
    let declaration = |tool: bool, n: u32| {
        let name = format!("{}[{n}]", prefix(tool));
        files
            .iter()
            .zip(facts)
            .find_map(|(f, x)| {
                f.frames.iter().enumerate().find_map(|(i, d)| {
                    let assigned = x.data_assignments.iter().any(|a| a.literal == Some(i));
                    (!assigned && d.name.eq_ignore_ascii_case(&name)).then_some(d)
                })
            })
            .or_else(|| {
                config_frames
                    .iter()
                    .find(|d| d.name.eq_ignore_ascii_case(&name))
            })
    };
    // (tool, number: `None` for any, line, file, a literal value) of the first assignment of
    // each that does not give the declared value.
    let mut assigned: Vec<(bool, Option<u32>, usize, usize, bool)> = Vec::new();
    for (fi, (f, x)) in files.iter().zip(facts).enumerate() {
        for a in &x.data_assignments {
            let value = a.literal.and_then(|i| f.frames.get(i));
            let declared = a.number.and_then(|n| declaration(a.tool, n));
            if let (Some(v), Some(d)) = (value, declared)
                && d.same_value(v)
            {
                continue;
            }
            if !assigned.iter().any(|b| (b.0, b.1) == (a.tool, a.number)) {
                assigned.push((a.tool, a.number, a.line, fi, value.is_some()));
            }
        }
    }
    if assigned.is_empty() {
        return;
    }
    let data = |name: &str, tool: bool| -> Option<Option<u32>> {
        let index = name.strip_prefix(prefix(tool))?.strip_prefix('[')?;
        Some(index.strip_suffix(']')?.parse().ok())
    };
    let names: Vec<Arc<str>> = files.iter().map(|f| UseLine::file_name(&f.path)).collect();
    for (tf, file) in files.iter_mut().enumerate() {
        for usage in file.positions.usages_mut() {
            if usage.run_time().is_some() {
                continue;
            }
            let frames = usage.work_objects().map(|w| (w, false));
            let used = frames.chain(usage.tools().map(|t| (t, true)));
            let found = used.into_iter().find_map(|(name, tool)| {
                let n = data(name, tool)?;
                let &(.., line, fi, literal) = assigned
                    .iter()
                    .find(|&&(t, m, ..)| t == tool && (m == n || m.is_none()))?;
                Some((name.to_owned(), (line, fi, literal)))
            });
            if let Some((name, (line, fi, literal))) = found
                && let Some(from) = names.get(fi)
            {
                let at = UseLine::of(line, fi, tf, from);
                usage.set_run_time(if literal {
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

/// Marks the targets a call passes to an `:OUT` parameter that its routine gives a computed
/// value (`pOut = $POS_ACT` in `DEF Remember(pOut:OUT)`, `Remember(XP5)`), directly or by
/// passing it on to another routine's `:OUT` parameter, as computed at run time, the
/// assignment's line named. The binder follows it as a use of the parameter carrying the value.
/// Bound after the candidates are promoted, as the assignments of computed values are marked:
/// a `FRAME` no motion uses stays no target. Only what binds to an `:OUT` parameter of a routine
/// of the program is handed over: a reference the binder binds to no parameter would be a use
/// of its own, and an `:IN` parameter is a copy, which the caller's variable does not follow.
/// Nothing being bound to an `:IN` parameter, what a routine passes on from one reaches no
/// target either.
fn computed_through_parameters(
    shared: &mut [crate::resolve::FileFacts<'_>],
    facts: &[Facts],
    copies: &[Vec<(String, String)>],
) {
    use crate::names::NameKey;
    let srcs: Vec<&[u8]> = shared.iter().map(|f| f.src).collect();
    // The routines of each name as the binder finds a callee: (file, index, public).
    let mut by_name: HashMap<NameKey<'_>, Vec<(usize, usize, bool)>> = HashMap::default();
    for (fi, (f, src)) in facts.iter().zip(&srcs).enumerate() {
        for (ri, r) in f.routines.iter().enumerate() {
            by_name
                .entry(NameKey(r.name.slice(src)))
                .or_default()
                .push((fi, ri, r.public));
        }
    }
    // The file's own routine first, else one of another file that is not local to it.
    let callee_at = |fi: usize, name: &[u8]| -> Option<(usize, usize)> {
        let all = by_name.get(&NameKey(name))?;
        let &(cf, cr, _) = all
            .iter()
            .find(|&&(f, ..)| f == fi)
            .or_else(|| all.iter().find(|&&(f, _, public)| f != fi && public))?;
        Some((cf, cr))
    };
    // Each routine's parameters a motion moves to, there or in a routine it passes them on
    // to (to a fixed point: each round marks one more at least, or ends).
    let mut moved: Vec<Vec<Vec<bool>>> = facts
        .iter()
        .map(|f| {
            f.routines
                .iter()
                .map(|r| (0..r.params.len()).map(|k| r.may_move(k)).collect())
                .collect()
        })
        .collect();
    let own_param = |fi: usize, r: usize, text: &[u8]| -> Option<usize> {
        let key = NameKey(
            text.split(|&b| b == b'[')
                .next()
                .unwrap_or(text)
                .trim_ascii(),
        );
        let src = srcs.get(fi)?;
        facts
            .get(fi)?
            .routines
            .get(r)?
            .params
            .iter()
            .position(|p| NameKey(p.name.slice(src)) == key)
    };
    loop {
        let mut changed = false;
        for (fi, (f, src)) in facts.iter().zip(&srcs).enumerate() {
            for call in &f.calls {
                let (Some(r), Some((cf, cr))) =
                    (call.routine, callee_at(fi, call.callee.slice(src)))
                else {
                    continue;
                };
                for (i, a) in call.args.iter().enumerate() {
                    let Some(k) = a.and_then(|a| own_param(fi, r, a.span().slice(src))) else {
                        continue;
                    };
                    let passes_to_moved = moved
                        .get(cf)
                        .and_then(|m| m.get(cr))
                        .is_some_and(|m| m.get(i).copied().unwrap_or(false));
                    if let Some(slot) = moved.get_mut(fi).and_then(|m| m.get_mut(r)?.get_mut(k))
                        && passes_to_moved
                        && !*slot
                    {
                        *slot = true;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut binder = crate::resolve::Binder::new(shared, &NAMING);
    let mut args: Vec<Option<crate::syntax::Span32>> = Vec::new();
    let mut passed = Vec::new();
    for (fi, (f, src)) in facts.iter().zip(&srcs).enumerate() {
        for call in &f.calls {
            let Some((cf, cr)) = callee_at(fi, call.callee.slice(src)) else {
                continue;
            };
            let Some(to) = facts.get(cf).and_then(|f| f.routines.get(cr)) else {
                continue;
            };
            // Every target passed to a routine of the program that moves to it: its motions
            // are not followed (a routine's effect on its callers is only the base and tool it
            // leaves set), so the base it is moved in there is not known. An argument that is
            // the calling routine's own parameter is the caller's caller's, marked where that
            // passes it.
            let moves = moved.get(cf).and_then(|m| m.get(cr));
            passed.clear();
            for (i, a) in call.args.iter().enumerate() {
                let Some(a) = a else { continue };
                let text = a.span().slice(src);
                let own = call.routine.and_then(|r| own_param(fi, r, text));
                if own.is_some() || !moves.is_some_and(|m| m.get(i).copied().unwrap_or(false)) {
                    continue;
                }
                binder.targets_named(fi, text, &mut passed);
                // And what a copy of that name may hold (`XC = XP1; MOVEIT(XC)`), followed a
                // few copies back.
                let file_copies = copies.get(fi).map_or(&[][..], Vec::as_slice);
                if !file_copies.is_empty() {
                    let mut names =
                        vec![String::from_utf8_lossy(text.trim_ascii()).to_ascii_uppercase()];
                    let mut from = 0;
                    while from < names.len() && names.len() < 16 {
                        let name = names[from].clone();
                        from += 1;
                        for (_, source) in file_copies.iter().filter(|(n, _)| *n == name) {
                            if !names.contains(source) {
                                binder.targets_named(fi, source.as_bytes(), &mut passed);
                                names.push(source.clone());
                            }
                        }
                    }
                }
            }
            if !passed.is_empty() {
                let routine = String::from_utf8_lossy(call.callee.slice(src)).into_owned();
                let cause = UnresolvedCause::PassedTo(routine);
                mark_unresolved(&mut binder, fi, &passed, call.line, &cause);
            }
            args.clear();
            args.extend(
                call.args
                    .iter()
                    .enumerate()
                    .map(|(i, a)| a.filter(|_| to.params.get(i).is_some_and(|p| !p.by_value))),
            );
            if args.iter().all(Option::is_none) {
                continue;
            }
            binder.bind(
                fi,
                &crate::resolve::Use {
                    line: call.line,
                    routine: call.routine,
                    callee: Some(call.callee),
                    args: &args,
                    ..Default::default()
                },
            );
        }
        for &(routine, param, line) in &f.param_assignments {
            binder.bind_computed_parameter(fi, routine, param, line);
        }
        // A value a routine hands back (`P = XP1` into an `:OUT` parameter, `RETURN XP1`):
        // the motions its callers make to what they get are not tied to the name.
        let mut copied_into: Option<HashMap<&str, Vec<&str>>> = None;
        for h in &f.handed_back {
            passed.clear();
            binder.targets_named(fi, h.source.as_bytes(), &mut passed);
            // And what the name may hold through the file's copies (`R = XP1; RETURN R`),
            // looked up by name (a file may copy often and hand back often).
            let by_name = copied_into.get_or_insert_with(|| {
                let mut m: HashMap<&str, Vec<&str>> = HashMap::default();
                for (n, source) in copies.get(fi).into_iter().flatten() {
                    m.entry(n.as_str()).or_default().push(source.as_str());
                }
                m
            });
            let mut names = vec![h.source.as_str()];
            let mut from = 0;
            while let Some(&name) = names.get(from).filter(|_| names.len() < FOLDED) {
                from += 1;
                for &source in by_name.get(name).into_iter().flatten() {
                    if !names.contains(&source) {
                        binder.targets_named(fi, source.as_bytes(), &mut passed);
                        names.push(source);
                    }
                }
            }
            if passed.is_empty() {
                continue;
            }
            let routine = String::from_utf8_lossy(h.routine.slice(src));
            let how = match (&h.into, h.param) {
                (Some(name), _) => {
                    format!("copied into `{name}`, a name other routines or modules may move to")
                }
                (None, Some(p)) => format!(
                    "written into `{}`, a parameter of `{routine}`",
                    String::from_utf8_lossy(p.slice(src))
                ),
                (None, None) => format!("returned by `{routine}`"),
            };
            mark_unresolved(
                &mut binder,
                fi,
                &passed,
                h.line,
                &UnresolvedCause::HandedBack(how),
            );
        }
    }
    binder.finish();
}

/// Marks the targets `found` in file `fi` as moved on `line` with a base that cannot be
/// resolved, for `cause`.
fn mark_unresolved(
    binder: &mut crate::resolve::Binder<'_, '_>,
    fi: usize,
    found: &[(usize, usize)],
    line: usize,
    cause: &UnresolvedCause,
) {
    binder.mark(fi, found, |elsewhere, usage| {
        usage.mark_unresolved_frame(UnresolvedFrame {
            at: UseLine {
                line,
                file: elsewhere.cloned(),
            },
            cause: cause.clone(),
        });
    });
}

/// Marks every position of the program written after a geometric operator `:` anywhere in it
/// ([`Facts::offsets`]) as such an offset, with the first line it is so written on. Only the
/// mark: a frame used as nothing but an offset stays no target, as it was before the mark.
fn mark_offsets(
    files: &mut [ParsedFile],
    facts: &[Facts],
    modules: &Modules,
    exported: &[Option<Vec<bool>>],
) {
    // (module, name) → (line, the file it is written in: `facts` are the files' in order, the
    // use); name → the first of those in any module, for what other modules see.
    type First = (usize, usize, crate::krl::positions::OffsetUse);
    let mut first: std::collections::HashMap<(usize, &str), First> = Default::default();
    let mut anywhere: HashMap<&str, First> = HashMap::default();
    for (fi, f) in facts.iter().enumerate() {
        for (name, line, what) in &f.offsets {
            first
                .entry((modules.of(fi), name.as_str()))
                .or_insert((*line, fi, *what));
            anywhere.entry(name.as_str()).or_insert((*line, fi, *what));
        }
    }
    if first.is_empty() {
        return;
    }
    let names: Vec<Arc<str>> = files.iter().map(|f| UseLine::file_name(&f.path)).collect();
    for (tf, file) in files.iter_mut().enumerate() {
        let module = modules.of(tf);
        let seen = exported.get(tf);
        for i in 0..file.positions.len() {
            let Some(key) = file.positions.name(i).map(name_key) else {
                continue;
            };
            // The offset written in the target's own module, else (a target other modules see)
            // in any.
            let own = first.get(&(module, key.as_str()));
            let other = || {
                let seen = seen.is_some_and(|e| {
                    e.as_ref()
                        .is_none_or(|e| e.get(i).copied().unwrap_or(false))
                });
                anywhere.get(key.as_str()).filter(|_| seen)
            };
            let Some(&(line, fi, (instruction, parameter))) = own.or_else(other) else {
                continue;
            };
            let (Some(u), Some(from)) = (file.positions.usage_mut(i), names.get(fi)) else {
                continue;
            };
            u.set_non_position(crate::position::NonPosition {
                instruction,
                parameter,
                role: crate::position::NonPositionRole::Offset,
                at: UseLine::of(line, fi, tf, from),
            });
        }
    }
}

/// A file as the shared pass sees it, and its line index. Its motions are bound without
/// routines: a subroutine's effect on its callers' motions is the base and tool it leaves set,
/// found in program order; `routines` are given only to follow what a routine writes into an
/// `:OUT` parameter ([`computed_through_parameters`]). Every declaration of its module is seen
/// from both files of the module, and of the others' only those `exported` says (see
/// [`Modules`]).
fn shared_facts<'a>(
    file: &'a mut ParsedFile,
    assignments: &'a [crate::resolve::Assignment],
    routines: &'a [crate::resolve::Routine],
    module: usize,
    exported: Option<&'a [bool]>,
) -> (crate::resolve::FileFacts<'a>, &'a crate::syntax::LineIndex) {
    let facts = crate::resolve::FileFacts {
        name: UseLine::file_name(&file.path),
        module,
        src: &file.source,
        positions: &mut file.positions,
        exported,
        frames: &file.frames,
        routines,
        assignments,
        // KRL copies are followed in program order by the base pass (`Event::Alias`).
        copies: &[],
    };
    (facts, &file.lines)
}

#[cfg(test)]
mod tests {
    use crate::position::{FrameKind, ParsedFile};
    use std::path::Path;

    /// `KSS_ROUTINES` is searched by bisection.
    #[test]
    fn kss_routines_are_sorted_and_upper_case() {
        let names = super::KSS_ROUTINES;
        assert!(names.windows(2).all(|w| w[0] < w[1]), "{names:?}");
        assert!(names.iter().all(|n| *n == n.to_ascii_uppercase()));
    }

    /// Each position's base and tool, as resolved.
    fn bases_and_tools(f: &ParsedFile) -> Vec<(Option<&str>, Option<&str>)> {
        f.positions
            .usages()
            .map(|u| (u.wobj.as_deref(), u.tool.as_deref()))
            .collect()
    }

    #[test]
    fn branches_that_disagree_leave_the_base_unresolved() {
        let src = b"DEF b()\n\
  DECL E6POS XA={X 1}\n  DECL E6POS XB={X 2}\n  DECL E6POS XC={X 3}\n  DECL E6POS XD={X 4}\n\
  $BASE=BASE_DATA[1]\n\
  IF $IN[1] THEN\n    $BASE=BASE_DATA[2]\n    LIN XA\n  ELSE\n    $BASE=BASE_DATA[3]\n  ENDIF\n\
  LIN XB\n\
  $BASE=BASE_DATA[4]\n  IF $IN[2] THEN\n    $TOOL=TOOL_DATA[1]\n  ENDIF\n  LIN XC\n\
  SWITCH N\n  CASE 1\n    $BASE=BASE_DATA[4]\n  DEFAULT\n    BAS(#BASE,4)\n  ENDSWITCH\n  LIN XD\n\
END\n";
        let f = crate::krl::parse_file(Path::new("b.src"), src.to_vec());
        let usage = bases_and_tools(&f);
        assert_eq!(
            usage,
            [
                (Some("BASE_DATA[2]"), None),
                (None, None),
                (Some("BASE_DATA[4]"), None),
                (Some("BASE_DATA[4]"), None),
            ]
        );
        let warned: Vec<_> = f
            .diagnostics
            .iter()
            .map(|d| f.lines.line(d.span.start))
            .collect();
        assert_eq!(warned, [13]);
    }

    #[test]
    fn copies_carry_the_use_to_their_source() {
        let src = b"DEF a()\n  DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\n  DECL E6POS XCOPY\n  $BASE=BASE_DATA[4]\n  XCOPY = XP1\n  XCOPY.Z = XCOPY.Z + 100\n  LIN XCOPY\nEND\n";
        let f = crate::krl::parse_file(Path::new("a.src"), src.to_vec());
        assert_eq!(f.positions.len(), 1);
        let u = &f.position(0).unwrap().usage;
        assert_eq!(u.wobj.as_deref(), Some("BASE_DATA[4]"));
        assert_eq!(u.lines, [7]);
    }

    /// A component of `$BASE` or `$TOOL` changed in the routine (`$BASE.X=100`) makes the
    /// frame one the program computes: the points moved with it are not correctable offline.
    #[test]
    fn a_changed_component_of_base_or_tool_is_computed() {
        let src = b"DEF c()\n  DECL E6POS XA={X 1,Y 2,Z 3}\n  DECL E6POS XB={X 1,Y 2,Z 3}\n  $TOOL=TOOL_DATA[1]\n  $BASE=BASE_DATA[2]\n  LIN XA\n  $BASE.X=100\n  LIN XB\nEND\n";
        let f = crate::krl::parse_file(Path::new("c.src"), src.to_vec());
        let computed: Vec<bool> = f
            .positions
            .usages()
            .map(|u| {
                matches!(
                    u.run_time(),
                    Some(crate::position::RunTimeValue::Frame { .. })
                )
            })
            .collect();
        assert_eq!(computed, [false, true]);
    }

    /// A spline block's `WITH $BASE`/`$TOOL` hold for each motion in the block, after the
    /// settings before it, and end with the block; a motion's own `WITH` is read after the
    /// block's.
    #[test]
    fn a_spline_blocks_settings_hold_for_its_motions() {
        let src = b"DEF s()\n  DECL E6POS XA={X 1,Y 2,Z 3}\n  DECL E6POS XB={X 1,Y 2,Z 3}\n  DECL E6POS XC={X 1,Y 2,Z 3}\n  DECL E6POS XD={X 1,Y 2,Z 3}\n  $TOOL=TOOL_DATA[1]\n  $BASE=BASE_DATA[2]\n  SPLINE WITH $BASE = BASE_DATA[1], $TOOL = TOOL_DATA[3]\n    SPL XA\n    SLIN XB WITH $BASE = BASE_DATA[4]\n  ENDSPLINE\n  PTP_SPLINE\n    SPTP XC\n  ENDSPLINE\n  LIN XD\nEND\n";
        let f = crate::krl::parse_file(Path::new("s.src"), src.to_vec());
        assert!(f.diagnostics.is_empty(), "{:?}", f.diagnostics);
        let usage = bases_and_tools(&f);
        assert_eq!(
            usage,
            [
                (Some("BASE_DATA[1]"), Some("TOOL_DATA[3]")),
                (Some("BASE_DATA[4]"), Some("TOOL_DATA[3]")),
                (Some("BASE_DATA[2]"), Some("TOOL_DATA[1]")),
                (Some("BASE_DATA[2]"), Some("TOOL_DATA[1]")),
            ]
        );
    }

    #[test]
    fn inline_frames_and_inline_fdat_resolve() {
        let src = b"DEF r()\n  $BASE = {FRAME: X 100, Y 0, Z 0, A 0, B 0, C 0}\n  $TOOL = {FRAME: X 0, Y 0, Z 200, A 0, B 0, C 0}\n  LIN {X 10, Y 20, Z 30, A 0, B 90, C 0, E1 500} C_DIS\n  FDAT_ACT= {TOOL_NO 11, BASE_NO 1, IPO_FRAME #TCP}\n  BAS(#PTP_PARAMS,100)\n  PTP {X 1,Y 2,Z 3}\n  $BASE = EK(MACHINE_DEF[2].ROOT, MACHINE_DEF[2].MECH_TYPE, BASE_DATA[1])\n  LIN {X 5}\nEND\n";
        let f = crate::krl::parse_file(Path::new("r.src"), src.to_vec());
        let names: Vec<_> = f.frames.iter().map(|d| (d.name.as_str(), d.kind)).collect();
        assert_eq!(
            names,
            [
                ("$BASE (line 2)", FrameKind::Base),
                ("$TOOL (line 3)", FrameKind::Tool)
            ]
        );
        let usage: Vec<_> = f
            .positions
            .usages()
            .map(|u| (u.wobj.as_deref(), u.tool.as_deref(), u.stationary_tool()))
            .collect();
        assert_eq!(
            usage,
            [
                (Some("$BASE (line 2)"), Some("$TOOL (line 3)"), false),
                (Some("BASE_DATA[1]"), Some("TOOL_DATA[11]"), true),
                (None, Some("TOOL_DATA[11]"), true),
            ]
        );
        let unresolved: Vec<_> = f
            .diagnostics
            .iter()
            .map(|d| (f.lines.line(d.span.start), d.message.as_str()))
            .collect();
        assert_eq!(unresolved, [(9, "the base of this motion is not resolved")]);
    }
}
