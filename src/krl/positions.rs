//! From the KRL tree to the shared position model: `E6POS`/`POS`/`FRAME` targets, `E6AXIS`/`AXIS`
//! joint positions, `BASE_DATA[n]`/`TOOL_DATA[n]` frames, and the facts needed to resolve which
//! base and tool each motion uses (`FDAT_ACT`, `$BASE=…`, `BAS(#BASE,n)`, `WITH $BASE=…`).
//!
//! Resolution needs both files of a `.src`/`.dat` pair (the `.src` moves, the `.dat` declares
//! the points and the `FDAT`s), so extraction only records facts per file and
//! [`super::resolve`] follows them over a whole program.

use super::resolve::HashMap;
use super::tree::{Aggregate, Expr, ExprKind, Stmt, StmtKind};
use crate::position::{
    Axes, BitField, CartesianFields, Config, FrameDecl, FrameKind, FrameScope, FrameStorage, Name,
    NumField, Orientation, Position, PositionKind, PositionList, Usage,
};
use crate::syntax::{Diagnostic, LineIndex, NumLit, Span, Span32};

/// A base or tool as a motion sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum FrameRef {
    /// `BASE_DATA[n]` / `TOOL_DATA[n]`; 0 is the world (base) or the flange (tool).
    Data(u32),
    /// A frame declared in the program itself (`$BASE={…}` → `$BASE (line 12)`).
    Named(String),
    /// Set by an expression computed when the program runs (`EK(…)`, `BASE_DATA[I]`,
    /// `BAS(#BASE, nBase)`): the span of that expression.
    RunTime(Span),
    /// Set by something trackfix cannot evaluate (a frame variable, branches that disagree).
    Unknown,
}

/// A statement that changes the base, the tool or the interpolation mode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Setting {
    Base(FrameRef),
    Tool(FrameRef),
    /// `$IPO_MODE = #TCP` (true) or `#BASE`.
    Tcp(bool),
    /// `$IPO_MODE` given a value trackfix does not evaluate (`$IPO_MODE = MODE`,
    /// `SIPO_MODE(#TCP)`, `FP1.IPO_FRAME`), at that value's span: it may be `#TCP`.
    TcpUnevaluated(Span),
    /// `FDAT_ACT = FP1`: stages base, tool and IPO mode of that FDAT for [`Setting::ApplyFdat`].
    Fdat(Name),
    /// `FDAT_ACT = {TOOL_NO 1, BASE_NO 2, IPO_FRAME #BASE}` written inline.
    FdatValue(Fdat),
    /// `BAS(#PTP_PARAMS, …)`, `BAS(#CP_PARAMS, …)`, `BAS(#FRAMES)`: KSS's `BAS.SRC` sets
    /// `$BASE`, `$TOOL` and `$IPO_MODE` from what `FDAT_ACT` holds then (an inline form's fold
    /// runs it right after `FDAT_ACT = …`; until it runs, the frames in effect stay).
    ApplyFdat,
    BaseOfFdat(String),
    ToolOfFdat(String),
    TcpOfFdat(String),
}

/// A target a motion uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Ref {
    /// A declared name, upper case (`XP1`, `P[3]`).
    Named(Name),
    /// An inline literal: the span of its position in the same file.
    Inline(Span),
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Event {
    /// A `DEF`/`DEFFCT` (its name, upper case): program order starts again.
    Reset(Option<String>),
    /// A call of a routine by name (upper case), written at `at` (the routine's name): the base
    /// and tool it leaves set apply after it.
    Call {
        name: String,
        at: Span,
    },
    Set(Setting),
    /// Program order forks (`IF`, `SWITCH`), switches branch (`ELSE`, `CASE`, `DEFAULT`) or
    /// joins (`ENDIF`, `ENDSWITCH`).
    Branch(BranchEvent),
    /// A loop opens: its kind, and the index of its [`Event::EndLoop`] in the same list (0
    /// while it is not closed, as after a block left open: then followed once).
    Loop {
        kind: LoopKind,
        end: usize,
    },
    /// The end of a loop's body: program order goes back to its top.
    EndLoop,
    /// `GOTO`: program order does not go on past it (it goes on at the label: the index of
    /// its [`Event::Label`] in the same list, when its routine has one of that name).
    Goto {
        label: Option<usize>,
    },
    /// `EXIT`: program order leaves the innermost loop.
    Exit,
    /// `RETURN`: program order leaves the routine, with what it has set on this path.
    Return,
    /// A label, with where the `GOTO`s of its routine that name it are (`jumps`: the index of
    /// each one's [`Event::Goto`]). A jump forward arrives with the state it was made with,
    /// joined there with the path that falls through; one back may arrive with another base
    /// and tool than program order brings, so from there on they are unknown until set again,
    /// unless it cannot (a retry jumping back over nothing that changes them:
    /// `jumps_keep_state` in resolution), and the IPO mode each jump back was made with is
    /// joined there; a label no jump names changes nothing.
    Label {
        jumps: Vec<usize>,
    },
    /// `XPICK = XP3`: until reassigned, a motion to `XPICK` moves to (a copy of) `XP3`, so
    /// `XP3` is used with that motion's base and tool. A function's value (`XC = MID(XP3,
    /// XP4)`) is an alias of each name its arguments give: the first replaces what the name
    /// held, each further one is `joined` to it.
    Alias {
        name: Name,
        source: Name,
        joined: bool,
    },
    Motion {
        span: Span,
        line: usize,
        refs: Vec<Ref>,
        with: Vec<Setting>,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BranchEvent {
    If,
    Switch,
    /// `ELSE` or `DEFAULT`: the branches now cover every case.
    Otherwise,
    Case,
    EndIf,
    EndSwitch,
}

/// Where a loop tests whether to go round again, which says what program order after it joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LoopKind {
    /// `FOR`: at the top (its bounds may give no pass at all).
    For,
    /// `WHILE`: at the top.
    While,
    /// `LOOP`: never; only `EXIT` leaves it.
    Loop,
    /// `REPEAT … UNTIL`: at the bottom, after at least one pass.
    Repeat,
}

/// `DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,…}`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Fdat {
    pub base: Option<u32>,
    pub tool: Option<u32>,
    pub tcp: Option<bool>,
}

/// What one file contributes to resolving a program.
#[derive(Clone, Debug, Default)]
pub(crate) struct Facts {
    pub events: Vec<Event>,
    pub fdats: HashMap<Name, Fdat>,
    /// Routines the program runs where trackfix does not follow them, upper case: its
    /// functions (`DEFFCT`, called inside expressions) and the routines of its triggers
    /// (`TRIGGER … DO SETB()`), and of its interrupts once one is known to be switched on. One
    /// that changes the base or tool leaves every motion's unknown.
    pub unfollowed: Vec<String>,
    /// Some of the file's positions are points held in a structure's member (`S1.P` of `DECL
    /// SPT S1={P {X …}}`).
    pub holds_members: bool,
    /// The interrupts declared (`INTERRUPT DECL 3 WHEN … DO SETB()`): the number (`None` when
    /// it is not a literal) and the routine, upper case. A declared interrupt runs its routine
    /// only once an `INTERRUPT ON` switches it on.
    pub interrupts: Vec<(Option<u32>, String)>,
    /// The interrupts `INTERRUPT ON` switches on: the number, `None` for every one (`INTERRUPT
    /// ON` alone, or a number computed when the program runs).
    pub switched_on: Vec<Option<u32>>,
    /// Names a routine assigns, whole or a component (`FP1.BASE_NO = 2`, `FP1 = FP2`), upper
    /// case: an `FDAT` among them does not hold its declared value when a motion applies it.
    pub written_in_routines: Vec<Name>,
    /// Declared `FRAME`s and aggregates assigned to names of unknown type: positions only when
    /// a motion uses them.
    pub candidates: Vec<Position>,
    /// Per candidate: `Some` when its kind was guessed from its fields because this file does
    /// not declare the name (the other file of the pair may), holding the names of its fields
    /// in written order, to be held to the type of that declaration once it is known
    /// ([`guessed_field_problem`]).
    pub inferred: Vec<Option<Box<[Span32]>>>,
    /// Positional types this file declares, by upper-case name.
    pub declared: HashMap<Name, PositionKind>,
    /// Values computed at run time given to declared names (`XP1 = $POS_ACT`, `P[I] = …`).
    pub assignments: Vec<crate::resolve::Assignment>,
    /// Bases and tools given a value when the program runs (`BASE_DATA[1] = BASE_DATA[2]`,
    /// `TOOL_DATA[1].Z = 300`, `BASE_DATA[1] = {X 100, …}` in a `DEF`).
    pub data_assignments: Vec<DataAssignment>,
    /// Names written after a geometric operator `:` (`SLOT` and `XPLACE_REL` of
    /// `FPALLET:SLOT:XPLACE_REL`), and the targets of relative motions (`LIN_REL XSTEP`),
    /// upper case, with their lines and how they are used: offsets in another frame, not
    /// positions.
    pub offsets: Vec<(Name, usize, OffsetUse)>,
    /// Names this file declares `GLOBAL` (upper case): seen from every module of the program.
    pub globals: Vec<Name>,
    /// The FDATs of [`Facts::fdats`] it declares `GLOBAL`: what `FDAT_ACT = FPG` and
    /// `SIPO_MODE(FPG.IPO_FRAME)` read in every module.
    pub global_fdats: Vec<Name>,
    /// Routines other modules may call (upper case): the file's first `DEF` (the module's own,
    /// named as the file) and every `GLOBAL DEF`; another `DEF` is the module's alone.
    pub public_routines: Vec<String>,
    /// The routines that take parameters, in file order.
    pub routines: Vec<ParamRoutine>,
    /// Call statements that pass a plain reference (`Remember(XP5)`): what a routine writes
    /// into an `:OUT` parameter it writes into the caller's variable.
    pub calls: Vec<ParamCall>,
    /// Values computed at run time given to a parameter not written `:IN` of the routine they
    /// are written in (`pOut = $POS_ACT`, `pOut.X = 5` in `DEF Remember(pOut:OUT)`): the
    /// routine (index into `routines`), the parameter's name in its `DEF` line, the line.
    pub param_assignments: Vec<(usize, Span32, usize)>,
    /// Names whose value a routine hands back to its callers: written into a parameter not
    /// `:IN` (`P = XP1` in `DEF SETC(P:OUT)`) or returned by a function (`RETURN XP1`). A
    /// caller's motion to what it gets moves to that value in a base trackfix does not tie to
    /// the name.
    pub handed_back: Vec<HandedBack>,
    /// Copies a routine makes into a name it does not declare itself (`XC = XP1` with `XC` in
    /// the data list), which other routines and later runs of it see, and the copies of a
    /// trigger's or interrupt's `DO XC = XP1`, which run at any time.
    pub shared_copies: Vec<SharedCopy>,
}

/// A copy into a name other routines see ([`Facts::shared_copies`]).
#[derive(Clone, Debug)]
pub(crate) struct SharedCopy {
    /// The routine it is made in, upper case; `None` for a trigger's or interrupt's `DO`.
    pub routine: Option<String>,
    /// The name copied into, upper case, as written (`XC`, `XC[I]`).
    pub name: Name,
    /// What it copies (`XP1`).
    pub source: Name,
    /// 1-based line.
    pub line: usize,
}

/// A value a routine hands back to its callers ([`Facts::handed_back`]).
#[derive(Clone, Debug)]
pub(crate) struct HandedBack {
    /// The name whose value it is, upper case.
    pub source: Name,
    /// 1-based line of the assignment or `RETURN`.
    pub line: usize,
    /// The routine's name.
    pub routine: Span,
    /// The parameter written, or `None` for a function's `RETURN`.
    pub param: Option<Span>,
    /// Not handed back by a routine but copied into a name other modules see (`XC = XP1` with
    /// `XC` declared `GLOBAL`, or not declared by the module): that name (`routine` is then
    /// where the copy is made).
    pub into: Option<Name>,
}

/// A `DEF`/`DEFFCT` that takes parameters (`DEF Remember(pOut:OUT, nTry:IN)`).
#[derive(Clone, Debug)]
pub(crate) struct ParamRoutine {
    /// Its name.
    pub name: Span,
    /// Callable from other modules: the file's first `DEF` or a `GLOBAL` one.
    pub public: bool,
    /// Its parameters, in the order a call's arguments bind to them.
    pub params: Vec<Param>,
    /// Whether a motion of the routine moves to each parameter (in order), named as its target
    /// or anywhere in a composed one (`LIN P:{Z 10}`): a target passed there is moved in a base
    /// trackfix does not follow.
    pub moved: Vec<bool>,
    /// Whether the routine writes each parameter's value into something else (`Q = P`), which
    /// a motion of it may move to.
    pub copied: Vec<bool>,
    /// Whether the routine has a motion at all.
    pub moves: bool,
}

impl ParamRoutine {
    /// Whether a target passed to parameter `k` may be moved to by this routine (not yet
    /// through the routines it calls).
    pub(crate) fn may_move(&self, k: usize) -> bool {
        self.moved.get(k).copied().unwrap_or(false)
            || (self.moves && self.copied.get(k).copied().unwrap_or(false))
    }
}

/// One parameter of a routine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Param {
    /// Its name, without the `[]` of an array.
    pub name: Span,
    /// Written `:IN`: the routine gets a copy, and what it assigns to it the caller never
    /// sees. Any other (`:OUT`, or no direction) is taken as the caller's variable itself: a
    /// target it may overwrite is refused rather than corrected.
    pub by_value: bool,
}

/// A call statement with the plain references it passes (`None` for any other argument).
#[derive(Clone, Debug)]
pub(crate) struct ParamCall {
    /// The routine it is written in, when that takes parameters (index into
    /// [`Facts::routines`]).
    pub routine: Option<usize>,
    /// The routine it calls, by name.
    pub callee: Span,
    /// 1-based line.
    pub line: usize,
    /// Its arguments in order: the span of each that is a plain reference (`XP5`, `P[I]`).
    pub args: Vec<Option<Span32>>,
}

/// Records routine `name` (its `DEF` line ending at `end`) in `routines` when it takes
/// parameters, and returns its index there. Kept out of [`Extractor::statement`], which stays
/// small enough to be inlined into the parser's sink.
#[inline(never)]
fn param_routine(
    src: &[u8],
    name: Span,
    end: usize,
    public: bool,
    routines: &mut Vec<ParamRoutine>,
) -> Option<usize> {
    let params = def_params(src, name, end);
    if params.is_empty() {
        return None;
    }
    routines.push(ParamRoutine {
        name,
        public,
        moved: vec![false; params.len()],
        copied: vec![false; params.len()],
        moves: false,
        params,
    });
    Some(routines.len() - 1)
}

/// Records a call of `callee` with `args`, written in `routine` at offset `start`, in `calls`
/// when it passes a plain reference. Out of line as [`param_routine`].
#[inline(never)]
fn param_call(
    callee: Span,
    args: &[Option<Expr>],
    (routine, lines, start): (Option<usize>, &LineIndex, usize),
    calls: &mut Vec<ParamCall>,
) {
    let refs = || {
        args.iter().map(|a| {
            a.as_ref()
                .filter(|a| matches!(a.kind, ExprKind::Name | ExprKind::Index(..)))
                .and_then(|a| Span32::of(a.span))
        })
    };
    if refs().any(|a| a.is_some()) {
        calls.push(ParamCall {
            routine,
            callee,
            line: lines.line(start),
            args: refs().collect(),
        });
    }
}

/// The parameters of a `DEF` line, read from the tokens after the routine's name (the parser
/// keeps them as written): `(pOut:OUT, P[]:IN)`. Empty when it has none or the list is not
/// that shape.
fn def_params(src: &[u8], name: Span, end: usize) -> Vec<Param> {
    let Some(rest) = src.get(name.end..end.max(name.end)) else {
        return Vec::new();
    };
    let mut tokens = super::lexer::Lexer::new(rest)
        .filter(|t| !t.kind.is_trivia())
        .map(|t| {
            (
                t,
                Span::new(name.end + t.start as usize, name.end + t.end as usize),
            )
        });
    let punct = |t: &super::lexer::Token, p: &[u8]| {
        t.kind == super::lexer::TokenKind::Punct && t.text(rest) == p
    };
    match tokens.next() {
        Some((t, _)) if punct(&t, b"(") => {}
        _ => return Vec::new(),
    }
    let mut params = Vec::new();
    // The current parameter: its name, then whether `:IN` followed.
    let mut current: Option<Param> = None;
    let mut after_colon = false;
    for (t, span) in tokens {
        if punct(&t, b",") || punct(&t, b")") {
            params.extend(current.take());
            after_colon = false;
            if punct(&t, b")") {
                break;
            }
        } else if punct(&t, b":") {
            after_colon = true;
        } else if t.kind == super::lexer::TokenKind::Ident {
            match &mut current {
                None => {
                    current = Some(Param {
                        name: span,
                        by_value: false,
                    });
                }
                Some(p) if after_colon => p.by_value = t.text(rest).eq_ignore_ascii_case(b"IN"),
                Some(_) => {}
            }
        }
    }
    params
}

/// A declared name as motions reference it: upper case, without blanks (`p[ 3 ]` → `P[3]`).
pub(crate) use crate::names::fold as name_key;

/// A name as text (Latin-1, as the controller writes it): one copy for the usual ASCII name
/// instead of a character at a time (a 50 MB `.dat` names 131 000 positions).
fn name_text(bytes: &[u8]) -> String {
    if bytes.is_ascii() {
        String::from_utf8(bytes.to_vec()).unwrap_or_else(|_| crate::syntax::latin1(bytes))
    } else {
        crate::syntax::latin1(bytes)
    }
}

fn upper(src: &[u8], span: Span) -> String {
    let text = span.slice(src);
    // Names are plain ASCII nearly always: one copy, no per-character UTF-8 encoding.
    if text
        .iter()
        .all(|b| b.is_ascii() && !b.is_ascii_whitespace())
    {
        return String::from_utf8(text.to_ascii_uppercase()).unwrap_or_default();
    }
    text.iter()
        .filter(|b| !b.is_ascii_whitespace())
        .map(|b| b.to_ascii_uppercase() as char)
        .collect()
}

/// [`upper`] as a [`Name`], without a `String` on the way for the usual short ASCII name: a
/// motion's target, an alias and an `FDAT_ACT` are kept until the program is resolved, and a
/// `String` each was 170,000 heap blocks on the 34 MB pair.
fn upper_name(src: &[u8], span: Span) -> Name {
    let mut buf = [0u8; crate::position::INLINE_NAME];
    let text = span.slice(src);
    match buf.get_mut(..text.len()) {
        Some(to)
            if text
                .iter()
                .all(|b| b.is_ascii() && !b.is_ascii_whitespace()) =>
        {
            for (t, b) in to.iter_mut().zip(text) {
                *t = b.to_ascii_uppercase();
            }
            Name::from_ascii(to).unwrap_or_else(|| Name::from(upper(src, span)))
        }
        _ => Name::from(upper(src, span)),
    }
}

/// `span`'s text as [`upper`] writes it, in `buf`, when that is ASCII and fits (every keyword,
/// setting and system name it is compared with does): the comparisons a statement makes need no
/// copy of their own (900,000 of them on a 34 MB pair). `""` otherwise, which matches no word.
fn upper_short<'b>(src: &[u8], span: Span, buf: &'b mut [u8; 16]) -> &'b str {
    let mut n = 0;
    for &b in span.slice(src).iter().filter(|b| !b.is_ascii_whitespace()) {
        match buf.get_mut(n) {
            Some(slot) if b.is_ascii() => *slot = b.to_ascii_uppercase(),
            _ => return "",
        }
        n += 1;
    }
    buf.get(..n)
        .and_then(|t| std::str::from_utf8(t).ok())
        .unwrap_or("")
}

/// Whether `span`'s text as [`upper`] writes it is `word` (ASCII upper case).
fn upper_is(src: &[u8], span: Span, word: &str) -> bool {
    upper_short(src, span, &mut [0; 16]) == word
}

fn is_word(src: &[u8], span: Span, word: &[u8]) -> bool {
    span.slice(src).eq_ignore_ascii_case(word)
}

fn positional_type(name: &str) -> Option<PositionKind> {
    Some(match name {
        "E6POS" => PositionKind::E6Pos,
        "POS" => PositionKind::Pos,
        "FRAME" => PositionKind::Frame,
        "E6AXIS" => PositionKind::E6Axis,
        "AXIS" => PositionKind::Axis,
        _ => return None,
    })
}

/// The plain name an expression stores into (`XP1`, `P` of `P[3]`), upper case.
fn base_name(src: &[u8], e: &Expr) -> Option<String> {
    match &e.kind {
        ExprKind::Name => Some(upper(src, e.span)),
        ExprKind::Index(b, _) => base_name(src, b),
        _ => None,
    }
}

fn integer(src: &[u8], e: &Expr) -> Option<u32> {
    if e.kind != ExprKind::Number {
        return None;
    }
    std::str::from_utf8(e.span.slice(src)).ok()?.parse().ok()
}

/// `BASE_DATA[n]` / `TOOL_DATA[n]` → (kind, n).
fn data_element(src: &[u8], e: &Expr) -> Option<(FrameKind, u32)> {
    let ExprKind::Index(b, args) = &e.kind else {
        return None;
    };
    let kind = match upper_short(src, b.span, &mut [0; 16]) {
        "BASE_DATA" => FrameKind::Base,
        "TOOL_DATA" => FrameKind::Tool,
        _ => return None,
    };
    match args.as_slice() {
        [Some(i)] => Some((kind, integer(src, i)?)),
        _ => None,
    }
}

fn frame_ref(src: &[u8], e: &Expr) -> FrameRef {
    if let Some((_, n)) = data_element(src, e) {
        return FrameRef::Data(n);
    }
    match (&e.kind, upper_short(src, e.span, &mut [0; 16])) {
        (ExprKind::Name, "$WORLD" | "$NULLFRAME") => FrameRef::Data(0),
        _ if computed_at_run_time(src, e) => FrameRef::RunTime(e.span),
        _ => FrameRef::Unknown,
    }
}

/// Whether a value is computed when the program runs: a call, an operation (the geometric
/// operator `:` included), a component, an index that is not a number (`BASE_DATA[I]`), or a
/// system variable (`$POS_ACT`). A literal, a plain variable or an element with a literal
/// index is not.
fn computed_at_run_time(src: &[u8], e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Call(..)
        | ExprKind::Binary(..)
        | ExprKind::Unary(..)
        | ExprKind::Paren(..)
        | ExprKind::Member(..) => true,
        ExprKind::Index(_, args) => args
            .iter()
            .any(|a| a.as_ref().is_none_or(|a| a.kind != ExprKind::Number)),
        ExprKind::Name => src.get(e.span.start) == Some(&b'$'),
        _ => false,
    }
}

/// The FDAT an `S…(FP1.BASE_NO)` / `STOOL2(FP1)` argument names.
fn fdat_argument(src: &[u8], e: &Expr) -> Option<String> {
    match &e.kind {
        ExprKind::Call(_, args) => fdat_argument(src, args.first()?.as_ref()?),
        ExprKind::Member(b, _) => fdat_argument(src, b),
        ExprKind::Name => Some(upper(src, e.span)),
        _ => None,
    }
}

/// `'B0101'` → (value, digits). nom keeps the shape of the literal in one line.
fn bit_string(text: &[u8]) -> Option<(u32, usize)> {
    use nom::Parser;
    use nom::bytes::complete::{tag, tag_no_case, take_while1};
    use nom::combinator::all_consuming;
    use nom::sequence::{delimited, preceded};
    let quote = || tag(&b"'"[..]);
    let mut p = all_consuming(delimited(
        quote(),
        preceded(
            tag_no_case(&b"B"[..]),
            take_while1(|c: u8| c == b'0' || c == b'1'),
        ),
        quote(),
    ));
    let r: nom::IResult<&[u8], &[u8]> = p.parse(text);
    let (_, digits) = r.ok()?;
    if digits.len() > 32 {
        return None;
    }
    let v = digits
        .iter()
        .fold(0u32, |acc, d| (acc << 1) | u32::from(d - b'0'));
    Some((v, digits.len()))
}

/// The number field of token `e`: the literal `NumField::read_at` reads at its start when that
/// is the whole token (nearly always), so the position list need not read it again
/// (`read_elsewhere` stays false); else the token read on its own.
fn num_field(src: &[u8], e: &Expr, read_elsewhere: &mut bool) -> Option<NumField> {
    if e.kind != ExprKind::Number {
        return None;
    }
    match NumField::read_at(src, e.span.start) {
        Some(f) if f.span() == e.span => Some(f),
        _ => {
            *read_elsewhere = true;
            NumField::new(e.span, NumLit::parse(e.span.slice(src))?)
        }
    }
}

fn bit_field(src: &[u8], e: &Expr) -> Option<BitField> {
    match e.kind {
        ExprKind::Number => BitField::new(e.span, integer(src, e)?, None),
        ExprKind::Quoted => {
            let (value, digits) = bit_string(e.span.slice(src))?;
            BitField::new(e.span, value, Some(digits))
        }
        _ => None,
    }
}

/// The fields of a position aggregate, by KRL name.
#[derive(Default)]
struct Fields {
    xyz: [Option<NumField>; 3],
    abc: [Option<NumField>; 3],
    abc_written: bool,
    s: Option<BitField>,
    t: Option<BitField>,
    axes: [Option<NumField>; 6],
    ext: [Option<NumField>; 6],
    ext_written: usize,
    cartesian_written: bool,
    joints_written: bool,
    /// A number field is not what `NumField::read_at` reads at its start (see `num_field`).
    read_elsewhere: bool,
    /// The fields written, by [`field_index`]; `odd` when one is written twice or is none of
    /// them: what [`field_problem`] then reports ([`aggregate_problem`]).
    seen: u32,
    odd: bool,
}

impl Fields {
    /// Notes field `k` (of [`field_index`]) as written.
    fn saw(&mut self, k: u32) {
        let bit = 1 << k;
        self.odd |= self.seen & bit != 0;
        self.seen |= bit;
    }
}

/// The place of a position's field among `X Y Z A B C S T` (0-7), `E1`-`E6` (8-13) and
/// `A1`-`A6` (14-19), compared without case; `None` for any other name.
fn field_index(name: &[u8]) -> Option<u32> {
    match name {
        [c] => Some(match c.to_ascii_uppercase() {
            b'X' => 0,
            b'Y' => 1,
            b'Z' => 2,
            b'A' => 3,
            b'B' => 4,
            b'C' => 5,
            b'S' => 6,
            b'T' => 7,
            _ => return None,
        }),
        [c, d @ b'1'..=b'6'] => {
            let k = u32::from(d - b'1');
            match c.to_ascii_uppercase() {
                b'E' => Some(8 + k),
                b'A' => Some(14 + k),
                _ => None,
            }
        }
        _ => None,
    }
}

/// The fields a `kind` position has, by [`field_index`]: E6POS X..T and E1-E6, POS X..T, FRAME
/// X..C, E6AXIS A1-A6 and E1-E6, AXIS A1-A6 (none for another kind).
fn allowed_fields(kind: PositionKind) -> u32 {
    match kind {
        PositionKind::E6Pos => 0x3fff,
        PositionKind::Pos => 0xff,
        PositionKind::Frame => 0x3f,
        PositionKind::E6Axis => 0xf_ff00,
        PositionKind::Axis => 0xf_c000,
        _ => 0,
    }
}

/// Every field [`field_index`] knows: what an aggregate of a type not known may give.
const ANY_FIELD: u32 = 0xf_ffff;

/// An error for the first of `names` (an aggregate's field names, in written order) that a
/// `kind` position does not have, or that is given twice: KSS does not load such a file, and a
/// transform would rewrite one of the two values and leave the other. `kind` is `None` for a
/// type not known (a name no declaration of the program types), which may have any field, so
/// only a field given twice is wrong there. `name` is what the aggregate is the value of (`None`:
/// written inline in a motion). Out of line: the statement handler it is called from is inlined
/// into the parser's sink.
#[inline(never)]
fn field_problem(
    src: &[u8],
    names: impl Iterator<Item = Span> + Clone,
    kind: Option<PositionKind>,
    name: Option<&str>,
) -> Option<Diagnostic> {
    let fields = match kind {
        None => "",
        Some(PositionKind::E6Pos) => "X, Y, Z, A, B, C, S, T, E1-E6",
        Some(PositionKind::Pos) => "X, Y, Z, A, B, C, S, T",
        Some(PositionKind::Frame) => "X, Y, Z, A, B, C",
        Some(PositionKind::E6Axis) => "A1-A6, E1-E6",
        Some(PositionKind::Axis) => "A1-A6",
        Some(_) => return None,
    };
    let allowed = kind.map_or(ANY_FIELD, allowed_fields);
    let mut seen = 0u32;
    for (i, at) in names.clone().enumerate() {
        let text = at.slice(src);
        let bit = field_index(text)
            .map(|k| 1u32 << k)
            .filter(|b| allowed & b != 0);
        let twice = match (bit, kind) {
            (Some(b), _) if seen & b == 0 => {
                seen |= b;
                continue;
            }
            (Some(_), _) => true,
            // No position's field, in a type that may have it: wrong only when given again.
            (None, None) => {
                let again = |n: Span| n.slice(src).eq_ignore_ascii_case(text);
                if !names.clone().take(i).any(again) {
                    continue;
                }
                true
            }
            (None, Some(_)) => false,
        };
        let written = crate::syntax::latin1(text);
        let what = match (kind, name) {
            (Some(k), Some(n)) => format!("{} `{n}`", k.as_str()),
            (Some(k), None) => format!("inline {}", k.as_str()),
            (None, Some(n)) => format!("`{n}`"),
            (None, None) => "inline aggregate".to_owned(),
        };
        let problem = if twice {
            format!("{what} gives field `{written}` twice")
        } else {
            format!("{what} has no field `{written}`")
        };
        let hint = match kind {
            Some(k) => format!(
                "the controller does not load the file: write each of {}'s fields ({fields}) at most once; trackfix transforms no file with an error",
                k.as_str()
            ),
            None => "the controller does not load the file: write each field at most once; trackfix transforms no file with an error".to_owned(),
        };
        return Some(Diagnostic::error(at, problem).with_hint(hint));
    }
    None
}

/// The [`field_problem`] of aggregate `agg`, whose fields `f` read: told from `f` in the usual
/// case, where no field is odd, without a second look at the fields.
fn aggregate_problem(
    src: &[u8],
    agg: &Aggregate,
    f: &Fields,
    kind: Option<PositionKind>,
    name: Option<&str>,
) -> Option<Diagnostic> {
    let allowed = kind.map_or(ANY_FIELD, allowed_fields);
    if !f.odd && f.seen & !allowed == 0 {
        return None;
    }
    field_problem(src, agg.fields.iter().map(|x| x.name), kind, name)
}

/// The [`field_problem`] of a candidate assigned to `name` whose kind was guessed
/// ([`Facts::inferred`]: `fields` its field names), once the type a declaration of the program
/// gives the name is known (`None`: none does).
pub(crate) fn guessed_field_problem(
    src: &[u8],
    fields: &[Span32],
    kind: Option<PositionKind>,
    name: &str,
) -> Option<Diagnostic> {
    field_problem(src, fields.iter().map(|s| s.span()), kind, Some(name))
}

fn read_fields(src: &[u8], agg: &Aggregate) -> Fields {
    let mut f = Fields::default();
    for field in &agg.fields {
        // Field names are compared as bytes: a 50 MB `.dat` has millions of them.
        let name = field.name.slice(src);
        let v = &field.value;
        let upper0 = name.first().map_or(0, u8::to_ascii_uppercase);
        let digit = match name {
            [_, d @ b'1'..=b'6'] => Some(usize::from(d - b'1')),
            _ => None,
        };
        match (name.len(), upper0, digit) {
            (1, b'X' | b'Y' | b'Z', _) => {
                if let Some(slot) = f.xyz.get_mut(usize::from(upper0 - b'X')) {
                    *slot = num_field(src, v, &mut f.read_elsewhere);
                }
                f.saw(u32::from(upper0 - b'X'));
                f.cartesian_written = true;
            }
            (1, b'A' | b'B' | b'C', _) => {
                if let Some(slot) = f.abc.get_mut(usize::from(upper0 - b'A')) {
                    *slot = num_field(src, v, &mut f.read_elsewhere);
                }
                f.saw(3 + u32::from(upper0 - b'A'));
                f.abc_written = true;
                f.cartesian_written = true;
            }
            (1, b'S', _) => {
                f.s = bit_field(src, v);
                f.saw(6);
            }
            (1, b'T', _) => {
                f.t = bit_field(src, v);
                f.saw(7);
            }
            (2, b'A', Some(i)) => {
                if let Some(slot) = f.axes.get_mut(i) {
                    *slot = num_field(src, v, &mut f.read_elsewhere);
                }
                f.saw(14 + i as u32);
                f.joints_written = true;
            }
            (2, b'E', Some(i)) => {
                if let Some(slot) = f.ext.get_mut(i) {
                    *slot = num_field(src, v, &mut f.read_elsewhere);
                }
                f.saw(8 + i as u32);
                f.ext_written = f.ext_written.max(i + 1);
            }
            _ => f.odd = true,
        }
    }
    f
}

/// The kind of an aggregate without a declared type: its own `{TYPE: …}`, else its fields.
fn inferred_kind(src: &[u8], agg: &Aggregate, f: &Fields) -> Option<PositionKind> {
    if let Some(t) = agg.type_name {
        return positional_type(&upper(src, t));
    }
    if f.joints_written && !f.cartesian_written {
        Some(PositionKind::E6Axis)
    } else if f.cartesian_written {
        Some(PositionKind::E6Pos)
    } else {
        None
    }
}

fn build_position(
    lines: &LineIndex,
    span: Span,
    kind: PositionKind,
    name: Option<String>,
    f: Fields,
) -> Position {
    let (line, column) = lines.line_col(span.start);
    let extax: Axes = f.ext.into_iter().take(f.ext_written).collect();
    let joint = matches!(kind, PositionKind::E6Axis | PositionKind::Axis);
    Position {
        name: name.map(Name::from),
        kind,
        span,
        line,
        column,
        cartesian: (!joint).then(|| CartesianFields {
            trans: f.xyz,
            orient: f.abc_written.then_some(Orientation::Abc(f.abc)),
        }),
        joints: if joint { f.axes.into() } else { Vec::new() },
        config: match kind {
            PositionKind::E6Pos | PositionKind::Pos => Config::StatusTurn {
                status: f.s,
                turn: f.t,
            },
            _ => Config::None,
        },
        extax,
        usage: Usage::default(),
    }
}

/// What an [`Extractor`] found in one file.
pub(crate) struct Extracted {
    pub positions: PositionList,
    pub frames: Vec<FrameDecl>,
    pub facts: Facts,
}

fn frame_decl(
    src: &[u8],
    lines: &LineIndex,
    name: String,
    kind: FrameKind,
    agg_expr: &Expr,
    agg: &Aggregate,
) -> FrameDecl {
    let f = read_fields(src, agg);
    FrameDecl {
        name,
        kind,
        span: agg_expr.span,
        line: lines.line(agg_expr.span.start),
        held_by_robot: None,
        fixed: None,
        moved_by: None,
        frame: Some(CartesianFields {
            trans: f.xyz,
            orient: f.abc_written.then_some(Orientation::Abc(f.abc)),
        }),
        oframe: None,
        scope: FrameScope::Program,
        storage: FrameStorage::Persistent,
        assigned: false,
    }
}

/// A value the program gives a base or tool of `$config.dat` when it runs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DataAssignment {
    /// A tool (`TOOL_DATA`), else a base.
    pub tool: bool,
    /// Its number; `None` for an index computed at run time (any of them).
    pub number: Option<u32>,
    /// 1-based line of the assignment.
    pub line: usize,
    /// A whole literal value (`BASE_DATA[1] = {X 100, …}`): its index in the file's frames.
    pub literal: Option<usize>,
}

/// Reads positions, frames and resolution facts from a file's statements, one at a time and in
/// source order (KRL declares before use, so a declared type is known when its assignments
/// come).
pub(crate) struct Extractor<'a> {
    src: &'a [u8],
    lines: &'a LineIndex,
    declared: HashMap<Name, PositionKind>,
    /// A `DEF` was read: the next is not the module's own routine.
    seen_def: bool,
    /// The statements are a routine's (`DEF`/`DEFFCT`), not a data list's (`DEFDAT`).
    in_routine: bool,
    /// The loops open at this statement: the index of each one's [`Event::Loop`].
    loops: Vec<usize>,
    /// The routine's labels (their event's index and name, upper case) and the names its
    /// `GOTO`s jump to (with the index the next event has there): a label's
    /// [`Event::Label`]`{ jumps }` are filled in once the routine has been read.
    labels: Vec<(usize, String)>,
    gotos: Vec<(String, usize)>,
    /// The `WITH` settings of the spline block open at this statement: they hold for each
    /// motion in it.
    block_with: Vec<Setting>,
    /// The routines that take parameters, moved into [`Facts::routines`] at the end.
    routines: Vec<ParamRoutine>,
    /// The routine being read, when it takes parameters (index into `routines`).
    current: Option<usize>,
    /// The function (`DEFFCT`) being read: its name.
    function: Option<Span>,
    /// The routine being read (upper case) and the names it declares itself: a copy into any
    /// other name is one other routines see ([`Facts::shared_copies`]).
    routine_name: Option<String>,
    locals: Vec<Name>,
    out: Extracted,
    /// Notes about what is deliberately not a target (relative motions, computed targets).
    pub diagnostics: Vec<Diagnostic>,
}

impl<'a> Extractor<'a> {
    pub(crate) fn new(src: &'a [u8], lines: &'a LineIndex) -> Extractor<'a> {
        Extractor {
            src,
            lines,
            declared: HashMap::default(),
            seen_def: false,
            in_routine: false,
            loops: Vec::new(),
            labels: Vec::new(),
            gotos: Vec::new(),
            block_with: Vec::new(),
            routines: Vec::new(),
            current: None,
            function: None,
            routine_name: None,
            locals: Vec::new(),
            out: Extracted {
                positions: PositionList::new(),
                frames: Vec::new(),
                facts: Facts::default(),
            },
            diagnostics: Vec::new(),
        }
    }

    pub(crate) fn finish(mut self) -> (Extracted, Vec<Diagnostic>) {
        self.close_labels();
        self.out.facts.declared = self.declared;
        self.out.facts.routines = self.routines;
        (self.out, self.diagnostics)
    }

    /// Marks the labels of the routine just read that one of its `GOTO`s names (KRL jumps stay
    /// inside their routine). Out of line: once a routine.
    #[inline(never)]
    fn close_labels(&mut self) {
        for (at, name) in self.labels.drain(..) {
            let events = &mut self.out.facts.events;
            for &(_, from) in self.gotos.iter().filter(|(to, _)| *to == name) {
                if let Some(Event::Goto { label }) = events.get_mut(from) {
                    label.get_or_insert(at);
                }
                if let Some(Event::Label { jumps }) = events.get_mut(at) {
                    jumps.push(from);
                }
            }
        }
        self.gotos.clear();
    }

    // Inlined into the parser's sink, which calls it once a statement: as a call of its own
    // (as the build's partition sometimes made it) it cost 1.7 M instructions more on the
    // 3 MB pair, its statement copied through memory.
    #[inline(always)]
    pub(crate) fn statement(&mut self, stmt: &Stmt) {
        let (src, lines) = (self.src, self.lines);
        if matches!(stmt.kind, StmtKind::Routine { .. })
            && !(self.labels.is_empty() && self.gotos.is_empty())
        {
            self.close_labels();
        }
        let out = &mut self.out;
        match &stmt.kind {
            StmtKind::Routine {
                keyword,
                name,
                global,
            } => {
                self.current = None;
                self.in_routine = !upper(src, *keyword).starts_with("DEFDAT");
                if self.in_routine {
                    let first = !self.seen_def;
                    self.seen_def = true;
                    if let Some(n) = *name {
                        self.current = param_routine(
                            src,
                            n,
                            stmt.span.end,
                            first || *global,
                            &mut self.routines,
                        );
                    }
                    let span = *name;
                    let name = name.map(|n| upper(src, n));
                    if let Some(n) = name.as_ref().filter(|_| first || *global) {
                        out.facts.public_routines.push(n.clone());
                    }
                    self.function =
                        span.filter(|_| function_routine(src, *keyword, name.as_ref(), out));
                    self.routine_name.clone_from(&name);
                    self.locals.clear();
                    out.facts.events.push(Event::Reset(name));
                    self.loops.clear();
                }
            }
            StmtKind::Decl {
                type_name,
                vars,
                global,
            } => {
                let positional = ["E6POS", "POS", "FRAME", "E6AXIS", "AXIS"]
                    .into_iter()
                    .find(|t| is_word(src, *type_name, t.as_bytes()))
                    .and_then(positional_type);
                let is_fdat = is_word(src, *type_name, b"FDAT");
                if self.in_routine {
                    self.locals
                        .extend(vars.iter().map(|v| upper_name(src, v.name)));
                }
                for v in vars {
                    if let Some(kind) = positional {
                        self.declared.insert(upper_name(src, v.name), kind);
                    }
                    // A structure declared `GLOBAL` too: the points its members hold are seen
                    // from every module.
                    if *global {
                        let name = upper_name(src, v.name);
                        if is_fdat {
                            out.facts.global_fdats.push(name);
                        } else {
                            out.facts.globals.push(name);
                        }
                    }
                    let Some(init) = &v.init else { continue };
                    let ExprKind::Aggregate(agg) = &init.kind else {
                        continue;
                    };
                    if is_fdat {
                        out.facts
                            .fdats
                            .insert(upper_name(src, v.name), fdat(src, agg));
                    } else if let Some(kind) = positional {
                        let name = name_text(v.name.slice(src));
                        let f = read_fields(src, agg);
                        self.diagnostics.extend(aggregate_problem(
                            src,
                            agg,
                            &f,
                            Some(kind),
                            Some(&name),
                        ));
                        let read_elsewhere = f.read_elsewhere;
                        let p = build_position(lines, init.span, kind, Some(name), f);
                        if kind == PositionKind::Frame {
                            out.facts.candidates.push(p);
                            out.facts.inferred.push(None);
                        } else {
                            out.positions.push_checking(p, src, read_elsewhere);
                        }
                    } else if agg.fields.iter().any(|f| is_aggregate(&f.value)) {
                        let at = (v.name, v.name);
                        member_points(src, lines, at, &mut Vec::new(), agg, out);
                    }
                }
            }
            StmtKind::Assign { target, value } => {
                offset_operands(src, lines, value, &mut out.facts.offsets);
                let routine = self
                    .current
                    .and_then(|r| Some((r, self.routines.get(r)?.params.as_slice())));
                let at = (self.in_routine, routine);
                let before = out.facts.events.len();
                let problem = assignment(src, lines, &self.declared, at, target, value, out);
                self.diagnostics.extend(problem);
                if self.in_routine && out.facts.events.len() > before {
                    let line = lines.line(stmt.span.start);
                    let routine = (self.routine_name.as_deref(), &self.locals[..]);
                    shared_copies(routine, before, line, out);
                }
                if let Some(r) = self.current.and_then(|r| self.routines.get_mut(r)) {
                    copied_parameters(src, r, value);
                }
                if self.in_routine && matches!(value.kind, ExprKind::Call(..) | ExprKind::Paren(..))
                {
                    function_value(value, (self.current, lines, stmt.span.start), out);
                }
                if let Some(r) = self.current.and_then(|r| self.routines.get(r)) {
                    handed_back(src, lines, r, target, value, out);
                }
            }
            StmtKind::Call(call) => {
                if let Some(s) = bas_call(src, call) {
                    out.facts.events.push(Event::Set(s));
                } else if let ExprKind::Call(callee, args) = &call.kind {
                    // KUKA's own `BAS` is read by `bas_call`; its other modes set no frame.
                    let name = upper(src, callee.span);
                    if name != "BAS" {
                        out.facts.events.push(Event::Call {
                            name,
                            at: callee.span,
                        });
                        if !args.is_empty() {
                            let at = (self.current, lines, stmt.span.start);
                            param_call(callee.span, args, at, &mut out.facts.calls);
                        }
                    }
                }
            }
            StmtKind::Branch(keyword) => {
                branch_event(src, *keyword, &mut self.loops, &mut out.facts.events);
            }
            StmtKind::SplineBlock { with } => {
                self.block_with = with
                    .iter()
                    .filter_map(|(l, r)| setting(src, l, r))
                    .collect();
                let warned = self
                    .block_with
                    .iter()
                    .filter_map(|s| unevaluated_mode(src, s));
                self.diagnostics.extend(warned);
            }
            StmtKind::EndSpline => self.block_with.clear(),
            StmtKind::Label => {
                let text = stmt.span.slice(src);
                let name = text.split(|&b| b == b':').next().unwrap_or(text);
                self.labels.push((
                    out.facts.events.len(),
                    String::from_utf8_lossy(name.trim_ascii()).to_ascii_uppercase(),
                ));
                out.facts.events.push(Event::Label { jumps: Vec::new() });
            }
            StmtKind::Goto => {
                let text = stmt.span.slice(src);
                let target = text.get(4..).unwrap_or_default().trim_ascii();
                let target = target
                    .split(|b| b.is_ascii_whitespace() || *b == b';')
                    .next()
                    .unwrap_or(target);
                self.gotos.push((
                    String::from_utf8_lossy(target).to_ascii_uppercase(),
                    out.facts.events.len(),
                ));
                out.facts.events.push(Event::Goto { label: None });
            }
            StmtKind::Return => {
                if let Some(f) = self.function {
                    returned(src, lines, f, stmt.span, out);
                }
                if self.in_routine {
                    out.facts.events.push(Event::Return);
                }
            }
            StmtKind::Handler => {
                handler(stmt.span.slice(src), &mut out.facts);
                handler_copy(src, lines, stmt.span, out);
            }
            StmtKind::Motion {
                keyword,
                targets,
                with,
            } => {
                let line = lines.line(stmt.span.start);
                if upper_short(src, *keyword, &mut [0; 16]).ends_with("_REL") {
                    relative_motion(src, *keyword, line, targets, out);
                    self.diagnostics.push(
                        Diagnostic::note(
                            stmt.span,
                            "relative motion: its offset is not a target and is left unchanged",
                        )
                        .with_hint("check this motion by hand after a transform")
                        .shaping_transforms(),
                    );
                    return;
                }
                // Sized for one reference per target (nearly always so): a vector grown from
                // empty reserves four, and the motions' lists are kept until resolution.
                let mut refs = Vec::with_capacity(targets.len());
                for t in targets {
                    offset_operands(src, lines, t, &mut out.facts.offsets);
                    let notes = &mut self.diagnostics;
                    if !target_refs(src, lines, t, &mut refs, &mut out.positions, notes) {
                        self.diagnostics.push(
                            Diagnostic::warning(
                                t.span,
                                "computed target (geometric operator `:` or an expression): \
                                 its operands are not treated as targets",
                            )
                            .with_hint(
                                "trackfix cannot transform a composed frame; check this motion by hand",
                            )
                            // A transform leaves the motion as it is: its output says so.
                            .shaping_transforms(),
                        );
                    }
                }
                if let Some(r) = self.current.and_then(|r| self.routines.get_mut(r)) {
                    moved_parameters(src, r, targets);
                }
                // The spline block's settings first: the motion's own are written after them.
                let own: Vec<Setting> = with
                    .iter()
                    .filter_map(|(l, r)| setting(src, l, r))
                    .collect();
                let warned = own.iter().filter_map(|s| unevaluated_mode(src, s));
                self.diagnostics.extend(warned);
                let with = self.block_with.iter().cloned().chain(own).collect();
                out.facts.events.push(Event::Motion {
                    span: stmt.span,
                    line,
                    refs,
                    with,
                });
            }
        }
    }
}

/// Records routine `name` as a function (`DEFFCT`, called inside expressions, which trackfix
/// does not follow: [`Facts::unfollowed`]) when `keyword` says it is one. Out of line, as
/// [`param_routine`].
#[inline(never)]
fn function_routine(src: &[u8], keyword: Span, name: Option<&String>, out: &mut Extracted) -> bool {
    let function = upper_is(src, keyword, "DEFFCT");
    if let Some(n) = name.filter(|_| function) {
        out.facts.unfollowed.push(n.clone());
    }
    function
}

/// Records a function call that is the value of an assignment (`XC = GETPT(XP1)`) as a call
/// with the plain references it passes: a function of the program that moves to a parameter,
/// or writes one, does to what is passed there what a routine does. Out of line, as
/// [`param_routine`].
#[inline(never)]
fn function_value(value: &Expr, at: (Option<usize>, &LineIndex, usize), out: &mut Extracted) {
    if let ExprKind::Call(callee, args) = &unparenthesized(value).kind
        && !args.is_empty()
    {
        param_call(callee.span, args, at, &mut out.facts.calls);
    }
}

/// The names a function's value may hold, upper case, into `out`: the arguments of the call
/// `e` that are plain references (`XP1` of `GETPT(XP1)`), and those of a call given as an
/// argument (`F(G(XP1))`). Nothing when `e` is no call.
fn function_arguments(src: &[u8], e: &Expr, out: &mut Vec<Name>) {
    if let ExprKind::Call(_, args) = &unparenthesized(e).kind {
        for a in args.iter().flatten() {
            let a = unparenthesized(a);
            match a.kind {
                ExprKind::Name | ExprKind::Index(..) => out.push(upper_name(src, a.span)),
                ExprKind::Call(..) => function_arguments(src, a, out),
                _ => {}
            }
        }
    }
}

/// The names of data a value reads, upper case, into `out`: a plain name or element (`XP1`,
/// `XA[I]`), the whole of a component read (`XP1` of `XP1.X + 10`), and the same in the
/// operands and a call's arguments; not a system variable (`$POS_ACT`) nor an index.
fn value_names(src: &[u8], e: &Expr, out: &mut Vec<Name>) {
    match &e.kind {
        ExprKind::Name | ExprKind::Index(..) if src.get(e.span.start) != Some(&b'$') => {
            out.push(upper_name(src, e.span));
        }
        ExprKind::Member(inner, _) | ExprKind::Unary(_, inner) | ExprKind::Paren(inner) => {
            value_names(src, inner, out);
        }
        ExprKind::Binary(l, _, r) => {
            value_names(src, l, out);
            value_names(src, r, out);
        }
        ExprKind::Call(_, args) => {
            for a in args.iter().flatten() {
                value_names(src, a, out);
            }
        }
        _ => {}
    }
}

/// Records the copies among `out`'s events from `from` on (an assignment's, in `routine`: its
/// name and the names it declares) into a name the routine does not declare itself: other
/// routines, and the routine's next run, see what it may hold ([`Facts::shared_copies`]). Out
/// of line, as [`param_routine`]: only an assignment that copies gets here.
#[inline(never)]
fn shared_copies(
    (routine, locals): (Option<&str>, &[Name]),
    from: usize,
    line: usize,
    out: &mut Extracted,
) {
    let Some(new) = out.facts.events.get(from..) else {
        return;
    };
    for ev in new {
        let Event::Alias { name, source, .. } = ev else {
            continue;
        };
        let whole = name.split(['[', '.']).next().unwrap_or_default();
        if name == source || locals.iter().any(|l| l.as_str() == whole) {
            continue;
        }
        out.facts.shared_copies.push(SharedCopy {
            routine: routine.map(str::to_owned),
            name: name.clone(),
            source: source.clone(),
            line,
        });
    }
}

/// Records the copy a trigger's or interrupt's `DO` makes (`TRIGGER WHEN DISTANCE=1 DELAY=0
/// DO XC=XP1`): it runs at a time program order does not tell, so each name its value reads
/// may be what the name holds at any motion ([`Facts::shared_copies`], no routine). Read from
/// the statement's text, which the parser keeps whole. Out of line, as [`param_routine`].
#[inline(never)]
fn handler_copy(src: &[u8], lines: &LineIndex, stmt: Span, out: &mut Extracted) {
    let text = stmt.slice(src);
    let is_word = |b: u8| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$' | b'#') || b >= 0x80;
    // The words before `DO`, then what follows it.
    let mut k = 0;
    let mut after = None;
    while k < text.len() {
        if !text.get(k).copied().is_some_and(is_word) {
            k += 1;
            continue;
        }
        let start = k;
        while text.get(k).copied().is_some_and(is_word) {
            k += 1;
        }
        if text
            .get(start..k)
            .is_some_and(|w| w.eq_ignore_ascii_case(b"DO"))
        {
            after = Some(k);
            break;
        }
    }
    let Some(after) = after else { return };
    let rest = text.get(after..).unwrap_or_default();
    let rest = rest.split(|&b| b == b';').next().unwrap_or(rest);
    let Some(eq) = rest.iter().position(|&b| b == b'=') else {
        return;
    };
    let (target, value) = (
        rest.get(..eq).unwrap_or_default(),
        rest.get(eq + 1..).unwrap_or_default(),
    );
    let target = target.trim_ascii();
    // `DO $OUT[1]=TRUE`, `DO X==Y` (no assignment), `DO SETB()`: no copy.
    if target.is_empty()
        || target.first() == Some(&b'$')
        || value.first() == Some(&b'=')
        || target.contains(&b'(')
    {
        return;
    }
    let name: String = target
        .iter()
        .filter(|b| !b.is_ascii_whitespace())
        .map(|b| char::from(b.to_ascii_uppercase()))
        .collect();
    let name = name.split('.').next().unwrap_or_default().to_owned();
    let line = lines.line(stmt.start);
    let mut at = 0;
    while at < value.len() {
        let Some(start) = (at..value.len()).find(|&i| value.get(i).copied().is_some_and(is_word))
        else {
            break;
        };
        let mut end = start;
        while value.get(end).copied().is_some_and(is_word) {
            end += 1;
        }
        at = end;
        let Some(word) = value.get(start..end) else {
            break;
        };
        if word
            .first()
            .is_some_and(|b| b.is_ascii_digit() || matches!(b, b'$' | b'#'))
        {
            continue;
        }
        let source: String = word
            .iter()
            .map(|b| char::from(b.to_ascii_uppercase()))
            .collect();
        if source != name {
            out.facts.shared_copies.push(SharedCopy {
                routine: None,
                name: Name::from(name.as_str()),
                source: Name::from(source),
                line,
            });
        }
    }
}

/// Records the names whose value an assignment in routine `r` writes into one of its
/// parameters not written `:IN` (`P = XP1`, `P = GETPT(XP1)`): the caller's variable then
/// holds it ([`Facts::handed_back`]). A parameter given another parameter's value hands back
/// nothing of the routine's own. Out of line, as [`param_routine`].
#[inline(never)]
fn handed_back(
    src: &[u8],
    lines: &LineIndex,
    r: &ParamRoutine,
    target: &Expr,
    value: &Expr,
    out: &mut Extracted,
) {
    use crate::names::NameKey;
    let component = matches!(target.kind, ExprKind::Member(..));
    let whole = match &target.kind {
        ExprKind::Name => target.span,
        ExprKind::Index(base, _) => base.span,
        // `P.X = XP1.X`: the caller's variable then holds part of `XP1`.
        ExprKind::Member(..) => match whole_span(target) {
            Some(span) => span,
            None => return,
        },
        _ => return,
    };
    let key = NameKey(whole.slice(src).trim_ascii());
    let is_param = |name: &[u8]| {
        let name = name.split(|&b| b == b'[').next().unwrap_or(name);
        r.params
            .iter()
            .find(|p| NameKey(p.name.slice(src)) == NameKey(name))
    };
    let Some(param) = is_param(key.0).filter(|p| !p.by_value) else {
        return;
    };
    let mut sources = Vec::new();
    let v = unparenthesized(value);
    if component {
        value_names(src, v, &mut sources);
    } else if matches!(v.kind, ExprKind::Name | ExprKind::Index(..)) {
        sources.push(upper_name(src, v.span));
    } else {
        function_arguments(src, v, &mut sources);
    }
    let line = lines.line(target.span.start);
    for source in sources {
        if is_param(source.as_bytes()).is_none() {
            out.facts.handed_back.push(HandedBack {
                source,
                line,
                routine: r.name,
                param: Some(param.name),
                into: None,
            });
        }
    }
}

/// Records the name a function's `RETURN` statement (`stmt`) gives as its value, when that is
/// a plain reference (`RETURN XP1`): the caller's expression gets it ([`Facts::handed_back`]).
/// Out of line, as [`param_routine`].
#[inline(never)]
fn returned(src: &[u8], lines: &LineIndex, function: Span, stmt: Span, out: &mut Extracted) {
    let text = stmt.slice(src);
    let value = text.get(6..).unwrap_or_default();
    let mut value = value
        .split(|&b| b == b';')
        .next()
        .unwrap_or(value)
        .trim_ascii();
    while let Some(inner) = value.strip_prefix(b"(").and_then(|v| v.strip_suffix(b")")) {
        value = inner.trim_ascii();
    }
    let name_end = value
        .iter()
        .position(|b| !(b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$') || *b >= 0x80))
        .unwrap_or(value.len());
    let (name, rest) = value.split_at(name_end);
    let plain = !name.is_empty()
        && !name[0].is_ascii_digit()
        && (rest.is_empty() || (rest.first() == Some(&b'[') && rest.last() == Some(&b']')));
    if !plain {
        return;
    }
    let start = stmt.start + (value.as_ptr() as usize - text.as_ptr() as usize);
    out.facts.handed_back.push(HandedBack {
        source: upper_name(src, Span::new(start, start + value.len())),
        line: lines.line(stmt.start),
        routine: function,
        param: None,
        into: None,
    });
}

/// Records the named targets of relative motion `keyword` (`LIN_REL XSTEP`) on `line` as
/// offsets: a displacement from wherever the robot is, in the base or tool frame, not a
/// position. Out of line, as [`param_routine`].
#[inline(never)]
fn relative_motion(src: &[u8], keyword: Span, line: usize, targets: &[Expr], out: &mut Extracted) {
    let word = upper(src, keyword);
    let instruction = crate::krl::MOTION_KEYWORDS
        .iter()
        .find(|k| **k == word)
        .copied()
        .unwrap_or("_REL");
    for t in targets {
        let operand = unparenthesized(t);
        if matches!(operand.kind, ExprKind::Name | ExprKind::Index(..)) {
            out.facts.offsets.push((
                upper_name(src, operand.span),
                line,
                (instruction, "relative target"),
            ));
        }
    }
}

/// Marks the parameters of routine `r` that `targets`, a motion's, name anywhere as moved, and
/// the routine as one that moves.
#[inline(never)]
fn moved_parameters(src: &[u8], r: &mut ParamRoutine, targets: &[Expr]) {
    r.moves = true;
    for t in targets {
        mark_named(src, t, &r.params, &mut r.moved);
    }
}

/// Marks the parameters of routine `r` whose value `value`, assigned to something, reads.
#[inline(never)]
fn copied_parameters(src: &[u8], r: &mut ParamRoutine, value: &Expr) {
    mark_named(src, value, &r.params, &mut r.copied);
}

/// Sets `marks[k]` for each parameter `params[k]` that a name anywhere in `e` is.
fn mark_named(src: &[u8], e: &Expr, params: &[Param], marks: &mut [bool]) {
    match &e.kind {
        ExprKind::Name => {
            let name = e.span.slice(src).trim_ascii();
            for (p, m) in params.iter().zip(marks.iter_mut()) {
                *m |= p.name.slice(src).eq_ignore_ascii_case(name);
            }
        }
        ExprKind::Index(base, args) | ExprKind::Call(base, args) => {
            mark_named(src, base, params, marks);
            for a in args.iter().flatten() {
                mark_named(src, a, params, marks);
            }
        }
        ExprKind::Member(inner, _) | ExprKind::Unary(_, inner) | ExprKind::Paren(inner) => {
            mark_named(src, inner, params, marks);
        }
        ExprKind::Binary(l, _, r) => {
            mark_named(src, l, params, marks);
            mark_named(src, r, params, marks);
        }
        _ => {}
    }
}

/// The event of a block keyword (`IF`, `ENDSWITCH`, `FOR`, `EXIT`, …). Out of line, as
/// [`param_routine`]: [`Extractor::statement`] stays small enough to be inlined.
#[inline(never)]
fn branch_event(src: &[u8], keyword: Span, loops: &mut Vec<usize>, events: &mut Vec<Event>) {
    let ev = match upper_short(src, keyword, &mut [0; 16]) {
        "IF" => BranchEvent::If,
        "SWITCH" => BranchEvent::Switch,
        "ELSE" | "DEFAULT" => BranchEvent::Otherwise,
        "CASE" => BranchEvent::Case,
        "ENDIF" => BranchEvent::EndIf,
        "ENDSWITCH" => BranchEvent::EndSwitch,
        word => return loop_event(word, loops, events),
    };
    events.push(Event::Branch(ev));
}

/// A loop's opening (`FOR`, `WHILE`, `LOOP`, `REPEAT`) or closing keyword (`word`, upper
/// case), or `EXIT`, as an event: a closing one gives its opening one the index of its
/// [`Event::EndLoop`].
fn loop_event(word: &str, open: &mut Vec<usize>, events: &mut Vec<Event>) {
    let kind = match word {
        "FOR" => LoopKind::For,
        "WHILE" => LoopKind::While,
        "LOOP" => LoopKind::Loop,
        "REPEAT" => LoopKind::Repeat,
        "EXIT" => {
            events.push(Event::Exit);
            return;
        }
        _ => {
            // The parser hands a closing keyword only when a block it closes is open.
            if let Some(start) = open.pop() {
                let end = events.len();
                if let Some(Event::Loop { end: e, .. }) = events.get_mut(start) {
                    *e = end;
                }
                events.push(Event::EndLoop);
            }
            return;
        }
    };
    open.push(events.len());
    events.push(Event::Loop { kind, end: 0 });
}

fn fdat(src: &[u8], agg: &Aggregate) -> Fdat {
    let mut f = Fdat::default();
    for field in &agg.fields {
        if is_word(src, field.name, b"TOOL_NO") {
            f.tool = integer(src, &field.value);
        } else if is_word(src, field.name, b"BASE_NO") {
            f.base = integer(src, &field.value);
        } else if is_word(src, field.name, b"IPO_FRAME") && field.value.kind == ExprKind::Enum {
            f.tcp = Some(is_word(src, field.value.span, b"#TCP"));
        }
    }
    f
}

/// `BAS(#BASE, n)` / `BAS(#TOOL, n)`, and the calls that apply `FDAT_ACT`
/// ([`Setting::ApplyFdat`]; `BAS(#FRAMES)` takes no value).
fn bas_call(src: &[u8], call: &Expr) -> Option<Setting> {
    let ExprKind::Call(name, args) = &call.kind else {
        return None;
    };
    if !upper_is(src, name.span, "BAS") {
        return None;
    }
    let (which, n) = match args.as_slice() {
        [Some(which)] => (which, None),
        [Some(which), n] => (which, n.as_ref()),
        _ => return None,
    };
    let r = || n.map(|n| integer(src, n).map_or(FrameRef::RunTime(n.span), FrameRef::Data));
    match upper_short(src, which.span, &mut [0; 16]) {
        "#BASE" => r().map(Setting::Base),
        "#TOOL" => r().map(Setting::Tool),
        "#PTP_PARAMS" | "#CP_PARAMS" | "#FRAMES" => Some(Setting::ApplyFdat),
        _ => None,
    }
}

/// `$BASE = …`, `$TOOL = …`, `$IPO_MODE = …`, `FDAT_ACT = …` (also inside `WITH`).
/// Aggregate values of `$BASE`/`$TOOL` are handled by [`assignment`], which names them.
fn setting(src: &[u8], target: &Expr, value: &Expr) -> Option<Setting> {
    let fdat_of = || fdat_argument(src, value);
    // `$BASE.X = 100`: a component changed when the program runs makes the frame one it
    // computes.
    if let ExprKind::Member(whole, _) = &target.kind {
        return match upper_short(src, whole.span, &mut [0; 16]) {
            "$BASE" => Some(Setting::Base(FrameRef::RunTime(target.span))),
            "$TOOL" => Some(Setting::Tool(FrameRef::RunTime(target.span))),
            // `FDAT_ACT.BASE_NO = 2`: what the next `BAS` applies is no longer a known FDAT.
            "FDAT_ACT" if places_frames(src, target) => Some(Setting::FdatValue(Fdat::default())),
            _ => None,
        };
    }
    match upper_short(src, target.span, &mut [0; 16]) {
        "$BASE" => Some(match &value.kind {
            ExprKind::Call(..) => fdat_of()
                .map(Setting::BaseOfFdat)
                .unwrap_or(Setting::Base(FrameRef::RunTime(value.span))),
            _ => Setting::Base(frame_ref(src, value)),
        }),
        "$TOOL" => Some(match &value.kind {
            ExprKind::Call(..) => fdat_of()
                .map(Setting::ToolOfFdat)
                .unwrap_or(Setting::Tool(FrameRef::RunTime(value.span))),
            _ => Setting::Tool(frame_ref(src, value)),
        }),
        "$IPO_MODE" => match &value.kind {
            ExprKind::Enum => Some(Setting::Tcp(upper_is(src, value.span, "#TCP"))),
            ExprKind::Call(..) => Some(
                fdat_of()
                    .map(Setting::TcpOfFdat)
                    .unwrap_or(Setting::TcpUnevaluated(value.span)),
            ),
            _ => Some(Setting::TcpUnevaluated(value.span)),
        },
        "FDAT_ACT" => match &value.kind {
            ExprKind::Name => Some(Setting::Fdat(upper_name(src, value.span))),
            ExprKind::Aggregate(agg) => Some(Setting::FdatValue(fdat(src, agg))),
            // Computed (`FDAT_ACT = PICK(I)`, `FDAT_ACT = FTAB[I]`): no known FDAT.
            _ => Some(Setting::FdatValue(Fdat::default())),
        },
        _ => None,
    }
}

/// The warning at a `$IPO_MODE` value trackfix does not evaluate ([`Setting::TcpUnevaluated`]):
/// the motions it reaches are taken as moving with the stationary tool. Before, such a value
/// was passed over and `$IPO_MODE = MODE` (`MODE` holding `#TCP`) then `LIN XP1` corrected
/// `XP1` as a tool on the flange, exit 0.
fn unevaluated_mode(src: &[u8], s: &Setting) -> Option<Diagnostic> {
    let Setting::TcpUnevaluated(at) = s else {
        return None;
    };
    Some(
        Diagnostic::warning(
            *at,
            format!(
                "`$IPO_MODE` is given `{}`, which trackfix does not evaluate: the motions it reaches may move with the stationary tool (#TCP), and are taken so",
                crate::syntax::latin1(at.slice(src))
            ),
        )
        .with_hint("write the mode itself (`$IPO_MODE=#BASE` or `#TCP`) where the program sets it")
        .shaping_transforms(),
    )
}

/// Records that `target` is given a value computed at run time, in `routine` (when that takes
/// parameters: its index and its parameters); a system variable (`$BASE`) is not data of the
/// program. Out of line: rare, and [`assignment`] is inlined into the statement loop.
#[inline(never)]
fn computed_assignment(
    src: &[u8],
    lines: &LineIndex,
    routine: Option<(usize, &[Param])>,
    target: &Expr,
    out: &mut Extracted,
) {
    let written = upper(src, target.span);
    let name = written.split('.').next().unwrap_or_default();
    if name.starts_with('$') {
        return;
    }
    let line = lines.line(target.span.start);
    let array = name.split_once('[').map_or(name, |(a, _)| a);
    if let Some(tool) = match array {
        "BASE_DATA" => Some(false),
        "TOOL_DATA" => Some(true),
        _ => None,
    } {
        let index = name.get(array.len() + 1..name.len().saturating_sub(1));
        let number = index.and_then(|i| i.parse().ok());
        out.facts.data_assignments.push(DataAssignment {
            tool,
            number,
            line,
            literal: None,
        });
        return;
    }
    // The routine's own parameter hides module data of its name.
    let key = crate::names::NameKey(array.as_bytes());
    let param = routine.and_then(|(r, params)| {
        Some((
            r,
            params
                .iter()
                .find(|p| crate::names::NameKey(p.name.slice(src)) == key)?,
        ))
    });
    match param {
        // A copy: the caller's variable keeps its value.
        Some((_, p)) if p.by_value => {}
        Some((r, p)) => out
            .facts
            .param_assignments
            .extend(Span32::of(p.name).map(|at| (r, at, line))),
        None => out.facts.assignments.push(crate::resolve::Assignment {
            name: name.to_owned(),
            line,
            literal: false,
        }),
    }
}

/// The name an assignment to `target` writes (`FP1` of `FP1.BASE_NO`), upper case, into
/// `out`; a system variable's (`$BASE`) is not data of the program.
fn written_name(src: &[u8], target: &Expr, out: &mut Vec<Name>) {
    // The list is only looked into: repeats further apart cost a little memory, not a
    // search per assignment.
    let Some(span) = whole_span(target) else {
        return;
    };
    let text = span.slice(src).trim_ascii();
    // KSS's active motion data (`LDAT_ACT = LCPDAT1`, `PDAT_ACT = …` before each motion of a
    // taught program) are no FDATs the program declares (`FDAT_ACT` is read as a setting), and
    // the same name again right after (`P.X = …`, `P.Y = …`) is kept once.
    let active = text.len() > 4
        && text
            .get(text.len() - 4..)
            .is_some_and(|t| t.eq_ignore_ascii_case(b"_ACT"));
    if active
        || text.first() == Some(&b'$')
        || out
            .last()
            .is_some_and(|last| last.as_bytes().eq_ignore_ascii_case(text))
    {
        return;
    }
    out.push(upper_name(src, span));
}

/// Records what an assignment in a routine writes: the name, whole or a component
/// ([`Facts::written_in_routines`]), and the end of a copy. A copy (`XC = XA`) is made an
/// alias by [`assignment`]; another whole value given to the name (`XC = $POS_ACT`) ends it: a
/// motion to it then moves to that value, and says nothing of the target it was copied from.
/// A component changed (`XC.Z = XC.Z + 100`, an approach point) keeps it: the motion is still
/// taught in that target's base. Out of line, as [`param_routine`].
#[inline(never)]
fn written_in_routine(src: &[u8], target: &Expr, value: &Expr, out: &mut Extracted) {
    if places_frames(src, target) {
        written_name(src, target, &mut out.facts.written_in_routines);
    }
    let copy = matches!(value.kind, ExprKind::Name | ExprKind::Index(..))
        || member_read(src, value).is_some();
    if matches!(target.kind, ExprKind::Member(..)) {
        component_copy(src, target, value, out);
    }
    if !copy
        && matches!(target.kind, ExprKind::Name)
        && let Some(name) = whole_name(src, target)
    {
        let mut sources = Vec::new();
        function_arguments(src, value, &mut sources);
        let ended = sources.is_empty();
        // `XC = SHIFT(XC)`: what the name held, it may still hold.
        let mut joined = sources.contains(&name);
        for source in sources.into_iter().filter(|s| *s != name) {
            out.facts.events.push(Event::Alias {
                name: name.clone(),
                source,
                joined,
            });
            joined = true;
        }
        if ended {
            out.facts.events.push(Event::Alias {
                name: name.clone(),
                source: name,
                joined: false,
            });
        }
    }
}

/// A component given a value that reads other data (`XC.X = XP1.X`, `XC.X = XP1.X + 10`,
/// `S1.P = XP1`): the whole name may then hold part of each, besides what it held (joined
/// aliases). Out of line, as [`param_routine`].
#[inline(never)]
fn component_copy(src: &[u8], target: &Expr, value: &Expr, out: &mut Extracted) {
    // `SA[1].P = XP1`: the element of an array of structures holds it.
    let Some(name) = member_read(src, target).map(|w| upper_name(src, w)) else {
        return;
    };
    let mut sources = Vec::new();
    value_names(src, value, &mut sources);
    // `FP1.TQ_STATE = TRUE`: a constant is no data.
    sources.retain(|s| !matches!(s.as_str(), "TRUE" | "FALSE"));
    for source in sources {
        if source != name && !out.facts.events.last().is_some_and(
            |e| matches!(e, Event::Alias { name: n, source: s, .. } if *n == name && *s == source),
        ) {
            out.facts.events.push(Event::Alias {
                name: name.clone(),
                source,
                joined: true,
            });
        }
    }
}

/// Whether a name is KSS's active motion data (`LDAT_ACT`, `PDAT_ACT`): no point is copied
/// there.
fn active_data(name: &str) -> bool {
    name.len() > 4
        && name
            .get(name.len() - 4..)
            .is_some_and(|t| t.eq_ignore_ascii_case("_ACT"))
}

/// Whether a name as written (`XC[I]`) is an element whose index is not a number: chosen when
/// the program runs.
pub(crate) fn computed_index(name: &str) -> bool {
    name.split_once('[').is_some_and(|(_, index)| {
        !index
            .trim_end_matches(']')
            .split(',')
            .all(|i| !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()))
    })
}

/// Whether an assignment to `target` may change which base, tool or IPO mode an FDAT applies:
/// a whole value, or its `BASE_NO`, `TOOL_NO` or `IPO_FRAME` (`FP1.TQ_STATE = TRUE` does not).
fn places_frames(src: &[u8], target: &Expr) -> bool {
    match &target.kind {
        ExprKind::Member(_, field) => {
            let field = field.slice(src).trim_ascii();
            [&b"BASE_NO"[..], b"TOOL_NO", b"IPO_FRAME"]
                .iter()
                .any(|f| field.eq_ignore_ascii_case(f))
        }
        _ => true,
    }
}

/// Records what an `INTERRUPT …` or `TRIGGER …` statement (`text`) says of the routines run
/// where program order does not follow them: the routine a `TRIGGER … DO NAME(…)` runs
/// ([`Facts::unfollowed`]), the number and routine of an `INTERRUPT DECL n WHEN … DO NAME(…)`
/// ([`Facts::interrupts`]), the number an `INTERRUPT ON n` switches on
/// ([`Facts::switched_on`]). Out of line, as [`param_routine`].
#[inline(never)]
fn handler(text: &[u8], facts: &mut Facts) {
    let words: Vec<&[u8]> = text
        .split(|b| !(b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$' | b'#')))
        .filter(|w| !w.is_empty())
        .collect();
    let is = |k: usize, word: &[u8]| words.get(k).is_some_and(|w| w.eq_ignore_ascii_case(word));
    let first = usize::from(is(0, b"GLOBAL"));
    let number = |k: usize| {
        words
            .get(k)
            .and_then(|w| std::str::from_utf8(w).ok()?.parse().ok())
    };
    let routine = words
        .iter()
        .position(|w| w.eq_ignore_ascii_case(b"DO"))
        .and_then(|at| words.get(at + 1))
        .map(|name| String::from_utf8_lossy(name).to_ascii_uppercase());
    if is(first, b"INTERRUPT") {
        if is(first + 1, b"DECL") {
            facts
                .interrupts
                .extend(routine.map(|r| (number(first + 2), r)));
        } else if is(first + 1, b"ON") {
            // `INTERRUPT ON` alone, or `INTERRUPT ON nIR`: any of them.
            facts.switched_on.push(number(first + 2));
        }
    } else {
        facts.unfollowed.extend(routine);
    }
}

/// The data name an assignment to `target` gives a value (`XC` of `XC.X`), upper case; `None`
/// for a system variable (`$BASE`) or an array element.
fn whole_name(src: &[u8], target: &Expr) -> Option<Name> {
    let whole = whole_span(target)?;
    let text = whole.slice(src).trim_ascii();
    (text.first() != Some(&b'$')).then(|| upper_name(src, whole))
}

/// The span of the data name an assignment to `target` gives a value (`XC` of `XC.X`); `None`
/// for a system variable (`$BASE`) or an array element. Read without a copy of the text.
fn whole_span(target: &Expr) -> Option<Span> {
    let mut whole = target;
    while let ExprKind::Member(inner, _) = &whole.kind {
        whole = inner;
    }
    matches!(whole.kind, ExprKind::Name).then_some(whole.span)
}

/// An assignment statement, written in a `DEF`/`DEFFCT` (`in_routine`) or a data list.
/// `routine` is the routine it is written in, when that takes parameters: its index and its
/// parameters. Returns the error of an aggregate it assigns to a position that gives a field
/// twice or one the position's type lacks ([`field_problem`]).
fn assignment(
    src: &[u8],
    lines: &LineIndex,
    declared: &HashMap<Name, PositionKind>,
    (in_routine, routine): (bool, Option<(usize, &[Param])>),
    target: &Expr,
    value: &Expr,
    out: &mut Extracted,
) -> Option<Diagnostic> {
    if in_routine {
        written_in_routine(src, target, value, out);
    }
    let ExprKind::Aggregate(agg) = &value.kind else {
        if let Some(s) = setting(src, target, value) {
            let warning = unevaluated_mode(src, &s);
            out.facts.events.push(Event::Set(s));
            return warning;
        }
        // A whole base or tool (`BASE_DATA[1] = BASE_DATA[2]`) is the controller's to change
        // as its components are: `BAS(#BASE,1)` after it reads the new value.
        if computed_at_run_time(src, value)
            || computed_at_run_time(src, target)
            || data_element(src, target).is_some()
        {
            computed_assignment(src, lines, routine, target, out);
        }
        // `XC = S1.P`: a copy of what the structure's member holds, which the structure's
        // name stands for (a copy into one of its members, `S1.P = XP1`, joins it there).
        let source = match value.kind {
            ExprKind::Name | ExprKind::Index(..) => Some(value.span),
            _ => member_read(src, value),
        };
        if let (ExprKind::Name | ExprKind::Index(..), Some(source)) = (&target.kind, source) {
            let name = upper_name(src, target.span);
            let source = upper_name(src, source);
            // `XC = XC` gives it nothing new: what it held, it holds. KSS's active motion data
            // (`LDAT_ACT = LCPDAT1` before each taught motion) hold no point: no copy to follow
            // (one per motion would make every loop's body a state of its own).
            if !name.starts_with('$') && name != source && !active_data(&name) {
                out.facts.events.push(Event::Alias {
                    // An element chosen when the program runs (`XC[I] = XP1`) may be any of
                    // them: what each held, it may still hold.
                    joined: computed_index(&name),
                    name,
                    source,
                });
            }
        }
        return None;
    };
    if upper_is(src, target.span, "FDAT_ACT") {
        if let Some(s) = setting(src, target, value) {
            out.facts.events.push(Event::Set(s));
        }
        return None;
    }
    if let Some((kind, n)) = data_element(src, target) {
        let prefix = if kind == FrameKind::Base {
            "BASE_DATA"
        } else {
            "TOOL_DATA"
        };
        let d = frame_decl(src, lines, format!("{prefix}[{n}]"), kind, value, agg);
        // In a data list it is the frame's value; in a routine it overwrites that value when
        // the program runs.
        if in_routine {
            out.facts.data_assignments.push(DataAssignment {
                tool: kind == FrameKind::Tool,
                number: Some(n),
                line: lines.line(target.span.start),
                literal: Some(out.frames.len()),
            });
        }
        out.frames.push(d);
        return None;
    }
    let target_name = upper(src, target.span);
    if target_name == "$BASE" || target_name == "$TOOL" {
        let line = lines.line(value.span.start);
        let name = format!("{target_name} (line {line})");
        let kind = if target_name == "$BASE" {
            FrameKind::Base
        } else {
            FrameKind::Tool
        };
        out.frames
            .push(frame_decl(src, lines, name.clone(), kind, value, agg));
        let r = FrameRef::Named(name);
        out.facts
            .events
            .push(Event::Set(if kind == FrameKind::Base {
                Setting::Base(r)
            } else {
                Setting::Tool(r)
            }));
        return None;
    }
    if let ExprKind::Member(..) = target.kind {
        member_assignment(src, lines, target, value, agg, out);
        return None;
    }
    let base = base_name(src, target)?;
    if base.starts_with('$') {
        return None;
    }
    let f = read_fields(src, agg);
    let name = name_text(target.span.slice(src));
    let kind = declared.get(base.as_str()).copied();
    let problem = kind.and_then(|k| aggregate_problem(src, agg, &f, Some(k), Some(&name)));
    match kind {
        Some(PositionKind::Frame) => {
            out.facts.candidates.push(build_position(
                lines,
                value.span,
                PositionKind::Frame,
                Some(name),
                f,
            ));
            out.facts.inferred.push(None);
        }
        Some(kind) => {
            let read_elsewhere = f.read_elsewhere;
            let p = build_position(lines, value.span, kind, Some(name), f);
            out.positions.push_checking(p, src, read_elsewhere);
        }
        None => {
            if let Some(kind) = inferred_kind(src, agg, &f) {
                // Checked once the pair's declarations are known: the `.dat` may type the name.
                let fields = agg.fields.iter().filter_map(|x| Span32::of(x.name));
                out.facts.inferred.push(Some(fields.collect()));
                out.facts
                    .candidates
                    .push(build_position(lines, value.span, kind, Some(name), f));
            } else if agg.fields.iter().any(|f| is_aggregate(&f.value)) {
                // A structure's literal (`S1={P {X 100, …}, K 1}`): the points its members hold.
                let at = (target.span, target.span);
                member_points(src, lines, at, &mut Vec::new(), agg, out);
            }
        }
    }
    problem
}

fn is_aggregate(e: &Expr) -> bool {
    matches!(e.kind, ExprKind::Aggregate(_))
}

/// The kind of a structure member's literal that is a point the robot may move to: typed
/// `E6POS` or `POS` (`{E6POS: X 1, …}`), or writing a position's coordinates (`X`, `Y`, `Z` or an
/// angle) with a field only a point has (`S`, `T`, an external axis). A frame (`LOAD_DATA`'s
/// `CM`, a pallet's offset) has the coordinates alone, and an axis-wise limit (`JERK_STRUC`'s
/// `AX`) the axes alone: neither is a point.
fn member_point_kind(src: &[u8], agg: &Aggregate, f: &Fields) -> Option<PositionKind> {
    /// [`field_index`] bits of `S`, `T` and `E1`-`E6`.
    const POINT_ONLY: u32 = 0x3fc0;
    match agg.type_name {
        Some(t) => positional_type(&upper(src, t))
            .filter(|&k| k == PositionKind::E6Pos || k == PositionKind::Pos),
        None => (f.cartesian_written && !f.joints_written && f.seen & POINT_ONLY != 0)
            .then_some(PositionKind::E6Pos),
    }
}

/// How deep structures nested in structures are looked into for points.
const MEMBER_DEPTH: usize = 8;

/// The points held in the members of the literal `agg` of the structure `whole` (its name as
/// written, `S1`, `SA[1]`), whose members are named after `prefix` (`S1.P`; `S1.A.P` a level
/// down, `path` holding the fields between): each a position refused by every transform as held
/// in a structure's member ([`crate::position::UnresolvedCause::Member`]). Names are only
/// written for a point found: a data list's motion data (`LDAT`'s `CB {AUX_PT {…}}`) holds
/// none. Out of line, as [`param_routine`]: only a declaration or assignment of a structure's
/// literal gets here.
#[inline(never)]
fn member_points(
    src: &[u8],
    lines: &LineIndex,
    (whole, prefix): (Span, Span),
    path: &mut Vec<Span>,
    agg: &Aggregate,
    out: &mut Extracted,
) {
    for field in &agg.fields {
        let ExprKind::Aggregate(inner) = &field.value.kind else {
            continue;
        };
        path.push(field.name);
        let f = read_fields(src, inner);
        if let Some(kind) = member_point_kind(src, inner, &f) {
            let mut name = name_text(prefix.slice(src));
            for p in path.iter() {
                name.push('.');
                name.push_str(&name_text(p.slice(src)));
            }
            let read_elsewhere = f.read_elsewhere;
            let p = build_position(lines, field.value.span, kind, Some(name), f);
            let whole = name_text(whole.slice(src));
            out.positions
                .push_checking(held_in(p, &whole), src, read_elsewhere);
            out.facts.holds_members = true;
        } else if path.len() < MEMBER_DEPTH {
            member_points(src, lines, (whole, prefix), path, inner, out);
        }
        path.pop();
    }
}

/// `p`, marked as held in a member of the structure `whole`.
fn held_in(mut p: Position, whole: &str) -> Position {
    p.usage
        .mark_unresolved_frame(crate::position::UnresolvedFrame {
            at: crate::position::UseLine::new(p.line),
            cause: crate::position::UnresolvedCause::Member(whole.to_owned()),
        });
    p
}

/// An aggregate `value` given to a member (`S1.P={X 100, …, E1 500}`, `SA[1].P={…}`,
/// `S1.A={P {…}}`): the point it is, or the points its own members hold, held in the
/// structure. Out of line, as [`param_routine`].
#[inline(never)]
fn member_assignment(
    src: &[u8],
    lines: &LineIndex,
    target: &Expr,
    value: &Expr,
    agg: &Aggregate,
    out: &mut Extracted,
) {
    let Some(whole) = member_read(src, target) else {
        return;
    };
    let f = read_fields(src, agg);
    if let Some(kind) = member_point_kind(src, agg, &f) {
        let read_elsewhere = f.read_elsewhere;
        let name = name_text(target.span.slice(src));
        let p = build_position(lines, value.span, kind, Some(name), f);
        let whole = name_text(whole.slice(src));
        out.positions
            .push_checking(held_in(p, &whole), src, read_elsewhere);
        out.facts.holds_members = true;
    } else {
        let at = (whole, target.span);
        member_points(src, lines, at, &mut Vec::new(), agg, out);
    }
}

/// The structure whose member `value` reads whole (`S1` of `S1.P`, `SA[I]` of `SA[I].P`), when
/// that is data of the program (not a system variable's, `$POS_ACT.X`).
fn member_read(src: &[u8], value: &Expr) -> Option<Span> {
    member_whole(value).filter(|w| w.slice(src).first() != Some(&b'$'))
}

/// The structure a member (`S1.P`, `SA[I].P`, `S1.A.P`) is part of: the span of `S1`, `SA[I]`;
/// `None` when `e` is no member of a name or element.
fn member_whole(e: &Expr) -> Option<Span> {
    let ExprKind::Member(inner, _) = &e.kind else {
        return None;
    };
    let mut whole: &Expr = inner;
    while let ExprKind::Member(inner, _) = &whole.kind {
        whole = inner;
    }
    match &whole.kind {
        ExprKind::Name => Some(whole.span),
        ExprKind::Index(base, _) if base.kind == ExprKind::Name => Some(whole.span),
        _ => None,
    }
}

/// `e` without the brackets around it: `XB` of `((XB))`.
fn unparenthesized(mut e: &Expr) -> &Expr {
    while let ExprKind::Paren(inner) = &e.kind {
        e = inner;
    }
    e
}

/// How a name is used as an offset: (the instruction or operator, the operand it is).
pub(crate) type OffsetUse = (&'static str, &'static str);

/// The right operand of a geometric operator `:`.
const FRAME_OFFSET: OffsetUse = (":", "right operand");

/// The names `e` writes after a geometric operator `:`, anywhere in it (a name in brackets
/// included), into `out` with their lines: `B` and `C` of `A:B:C`, `B` of `F(A:B)`; not `A`,
/// the frame the offsets are taken in.
fn offset_operands(
    src: &[u8],
    lines: &LineIndex,
    e: &Expr,
    out: &mut Vec<(Name, usize, OffsetUse)>,
) {
    match &e.kind {
        ExprKind::Binary(left, op, right) => {
            offset_operands(src, lines, left, out);
            if op.slice(src) == b":" {
                let operand = unparenthesized(right);
                if matches!(operand.kind, ExprKind::Name | ExprKind::Index(..)) {
                    out.push((
                        upper_name(src, operand.span),
                        lines.line(operand.span.start),
                        FRAME_OFFSET,
                    ));
                    return;
                }
            }
            offset_operands(src, lines, right, out);
        }
        ExprKind::Paren(inner) | ExprKind::Unary(_, inner) | ExprKind::Member(inner, _) => {
            offset_operands(src, lines, inner, out);
        }
        ExprKind::Call(_, args) | ExprKind::Index(_, args) => {
            for a in args.iter().flatten() {
                offset_operands(src, lines, a, out);
            }
        }
        _ => {}
    }
}

/// The targets of a motion: names and inline literals. Returns false when a target is built
/// with the geometric operator `:` (or another expression), whose operands are offsets and
/// frames rather than targets: those are left out and reported by the caller. Not even the
/// frame before the `:` is the motion's target: KSS gives the result the type of the operand
/// after it, and with it, as far as trackfix knows, that operand's Status, Turn and external
/// axes (none for a `POS`), so the skid a correction of the frame would need is not known to
/// be the one it is written with. An inline literal that gives a field twice, or one its
/// type lacks, is an error in `notes`.
fn target_refs(
    src: &[u8],
    lines: &LineIndex,
    e: &Expr,
    refs: &mut Vec<Ref>,
    positions: &mut PositionList,
    notes: &mut Vec<Diagnostic>,
) -> bool {
    match &e.kind {
        ExprKind::Name | ExprKind::Index(..) => {
            refs.push(Ref::Named(upper_name(src, e.span)));
            true
        }
        ExprKind::Aggregate(agg) => {
            let f = read_fields(src, agg);
            if let Some(kind) = inferred_kind(src, agg, &f) {
                // A motion's target is a position: its type is the one its fields (or its own
                // `{E6POS: …}`) say.
                notes.extend(aggregate_problem(src, agg, &f, Some(kind), None));
                let read_elsewhere = f.read_elsewhere;
                let p = build_position(lines, e.span, kind, None, f);
                positions.push_checking(p, src, read_elsewhere);
                refs.push(Ref::Inline(e.span));
            }
            true
        }
        ExprKind::Paren(inner) => target_refs(src, lines, inner, refs, positions, notes),
        // A member of a structure (`LIN S1.P`, `LIN SA[I].P`): what a copy put there
        // (`S1.P = XP1`), which the whole structure's aliases carry, and a literal it holds
        // (`S1={P {X …}}`, refused as held in a member, `member_points`), which resolution
        // reaches from the structure's name.
        ExprKind::Member(..) => match member_read(src, e) {
            Some(whole) => {
                refs.push(Ref::Named(upper_name(src, whole)));
                true
            }
            None => false,
        },
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_upper_case_compares_as_the_copy_does() {
        let words = [
            "BAS",
            "#TCP",
            "FDAT_ACT",
            "$IPO_MODE",
            "BASE_DATA",
            "LIN_REL",
            "",
        ];
        for text in [
            &b"bas"[..],
            b"Bas ",
            b" f dat_act",
            b"$ipo_mode",
            b"base_data",
            b"BASE_DATA_LONGER_THAN_16",
            b"lin_rel",
            b"b\xe4s",
            b"#tcp",
            b"",
        ] {
            let span = Span::new(0, text.len());
            let copy = upper(text, span);
            let mut buf = [0; 16];
            let short = upper_short(text, span, &mut buf);
            // Either the same text, or (too long, not ASCII) a text that matches no word.
            assert!(
                short == copy || (short.is_empty() && !copy.is_empty()),
                "{text:?}"
            );
            for w in words.iter().filter(|w| !w.is_empty()) {
                assert_eq!(upper_is(text, span, w), copy == *w, "{text:?} vs {w}");
            }
        }
    }

    #[test]
    fn def_line_parameters_and_their_direction() {
        let params = |line: &str, name: &str| {
            let src = line.as_bytes();
            let start = line.find(name).unwrap();
            def_params(src, Span::new(start, start + name.len()), src.len())
                .into_iter()
                .map(|p| (crate::syntax::latin1(p.name.slice(src)), p.by_value))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            params(
                "GLOBAL DEF Remember(pOut:OUT, P[ ]:in,nTry, x : IN ) ; not : IN",
                "Remember"
            ),
            [
                ("pOut".to_owned(), false),
                ("P".to_owned(), true),
                ("nTry".to_owned(), false),
                ("x".to_owned(), true),
            ]
        );
        assert_eq!(
            params("DEFFCT REAL half(X:IN)", "half"),
            [("X".to_owned(), true)]
        );
        assert!(params("DEF a( )", "a").is_empty());
        assert!(params("DEF b", "b").is_empty());
    }

    #[test]
    fn bit_strings() {
        assert_eq!(bit_string(b"'B010'"), Some((2, 3)));
        assert_eq!(bit_string(b"'b100011'"), Some((35, 6)));
        assert_eq!(bit_string(b"'H1F'"), None);
        assert_eq!(bit_string(b"'B'"), None);
        assert_eq!(bit_string(b"'B012'"), None);
    }
}
