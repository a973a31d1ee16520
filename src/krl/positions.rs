//! From the KRL tree to the shared position model: `E6POS`/`POS`/`FRAME` targets, `E6AXIS`/`AXIS`
//! joint positions, `BASE_DATA[n]`/`TOOL_DATA[n]` frames, and the facts needed to resolve which
//! base and tool each motion uses (`FDAT_ACT`, `$BASE=…`, `BAS(#BASE,n)`, `WITH $BASE=…`).
//!
//! Resolution needs both files of a `.src`/`.dat` pair (the `.src` moves, the `.dat` declares
//! the points and the `FDAT`s), so extraction only records facts per file and [`resolve`] runs
//! over a whole program.

use std::collections::HashMap as StdHashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Names are short, trusted-enough keys (the file is the user's own program) and a `.dat` holds
/// hundreds of thousands of them: SipHash showed up as a tenth of the run time. This is the
/// multiply-rotate hash of rustc's `FxHasher` with a finaliser, written out to avoid a
/// dependency.
#[derive(Default, Clone, Copy)]
pub(crate) struct NameHasher(u64);

impl Hasher for NameHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.0 = (self.0.rotate_left(5) ^ u64::from_le_bytes(word))
                .wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
        }
    }

    /// MurmurHash3's finaliser: hashbrown picks buckets from the low bits, which the
    /// multiply alone leaves equal for names differing only in their last bytes (`XP100001`).
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

pub(crate) type HashMap<K, V> = StdHashMap<K, V, BuildHasherDefault<NameHasher>>;

use super::tree::{Aggregate, Expr, ExprKind, Stmt, StmtKind};
use crate::position::{
    BitField, CartesianFields, Config, FrameDecl, FrameKind, NumField, Orientation, ParsedFile,
    Position, PositionKind, Usage,
};
use crate::syntax::{Diagnostic, LineIndex, NumLit, Span};

/// A base or tool as a motion sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum FrameRef {
    /// `BASE_DATA[n]` / `TOOL_DATA[n]`; 0 is the world (base) or the flange (tool).
    Data(u32),
    /// A frame declared in the program itself (`$BASE={…}` → `$BASE (line 12)`).
    Named(String),
    /// Set by an expression trackfix cannot evaluate.
    Unknown,
}

/// A statement that changes the base, the tool or the interpolation mode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Setting {
    Base(FrameRef),
    Tool(FrameRef),
    /// `$IPO_MODE = #TCP` (true) or `#BASE`.
    Tcp(bool),
    /// `FDAT_ACT = FP1`: base, tool and IPO mode of that FDAT.
    Fdat(String),
    /// `FDAT_ACT = {TOOL_NO 1, BASE_NO 2, IPO_FRAME #BASE}` written inline.
    FdatValue(Fdat),
    BaseOfFdat(String),
    ToolOfFdat(String),
    TcpOfFdat(String),
}

/// A target a motion uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Ref {
    /// A declared name, upper case (`XP1`, `P[3]`).
    Named(String),
    /// An inline literal: the span of its position in the same file.
    Inline(Span),
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Event {
    /// A `DEF`/`DEFFCT`: program order starts again.
    Reset,
    Set(Setting),
    /// `XPICK = XP3`: until reassigned, a motion to `XPICK` moves to (a copy of) `XP3`, so
    /// `XP3` is used with that motion's base and tool.
    Alias {
        name: String,
        source: String,
    },
    Motion {
        span: Span,
        line: usize,
        refs: Vec<Ref>,
        with: Vec<Setting>,
    },
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
    pub fdats: HashMap<String, Fdat>,
    /// Declared `FRAME`s and aggregates assigned to names of unknown type: positions only when
    /// a motion uses them.
    pub candidates: Vec<Position>,
}

/// A declared name as motions reference it: upper case, without blanks (`p[ 3 ]` → `P[3]`).
fn name_key(name: &str) -> String {
    name.chars()
        .filter(|c| !c.is_ascii_whitespace())
        .map(|c| c.to_ascii_uppercase())
        .collect()
}

fn upper(src: &[u8], span: Span) -> String {
    span.slice(src)
        .iter()
        .filter(|b| !b.is_ascii_whitespace())
        .map(|b| b.to_ascii_uppercase() as char)
        .collect()
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
    let kind = match upper(src, b.span).as_str() {
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
    match (&e.kind, upper(src, e.span).as_str()) {
        (ExprKind::Name, "$WORLD" | "$NULLFRAME") => FrameRef::Data(0),
        _ => FrameRef::Unknown,
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

fn num_field(src: &[u8], e: &Expr) -> Option<NumField> {
    if e.kind != ExprKind::Number {
        return None;
    }
    Some(NumField {
        span: e.span,
        lit: NumLit::parse(e.span.slice(src))?,
    })
}

fn bit_field(src: &[u8], e: &Expr) -> Option<BitField> {
    match e.kind {
        ExprKind::Number => Some(BitField {
            span: e.span,
            value: integer(src, e)?,
            binary_digits: None,
        }),
        ExprKind::Quoted => {
            let (value, digits) = bit_string(e.span.slice(src))?;
            Some(BitField {
                span: e.span,
                value,
                binary_digits: Some(digits),
            })
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
                    *slot = num_field(src, v);
                }
                f.cartesian_written = true;
            }
            (1, b'A' | b'B' | b'C', _) => {
                if let Some(slot) = f.abc.get_mut(usize::from(upper0 - b'A')) {
                    *slot = num_field(src, v);
                }
                f.abc_written = true;
                f.cartesian_written = true;
            }
            (1, b'S', _) => f.s = bit_field(src, v),
            (1, b'T', _) => f.t = bit_field(src, v),
            (2, b'A', Some(i)) => {
                if let Some(slot) = f.axes.get_mut(i) {
                    *slot = num_field(src, v);
                }
                f.joints_written = true;
            }
            (2, b'E', Some(i)) => {
                if let Some(slot) = f.ext.get_mut(i) {
                    *slot = num_field(src, v);
                }
                f.ext_written = f.ext_written.max(i + 1);
            }
            _ => {}
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
    let extax: Vec<Option<NumField>> = f.ext.into_iter().take(f.ext_written).collect();
    let joint = matches!(kind, PositionKind::E6Axis | PositionKind::Axis);
    Position {
        name,
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
            PositionKind::E6Pos | PositionKind::Pos => Config::Kuka {
                status: f.s,
                turn: f.t,
            },
            _ => Config::None,
        },
        extax,
        usage: Usage::default(),
    }
}

/// What [`extract`] found in one file.
pub(crate) struct Extracted {
    pub positions: Vec<Position>,
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
        robhold: None,
        ufprog: None,
        ufmec: None,
        frame: Some(CartesianFields {
            trans: f.xyz,
            orient: f.abc_written.then_some(Orientation::Abc(f.abc)),
        }),
        oframe: None,
    }
}

/// Reads positions, frames and resolution facts from a file's statements, one at a time and in
/// source order (KRL declares before use, so a declared type is known when its assignments
/// come).
pub(crate) struct Extractor<'a> {
    src: &'a [u8],
    lines: &'a LineIndex,
    declared: HashMap<String, PositionKind>,
    out: Extracted,
    /// Notes about what is deliberately not a target (relative motions, computed targets).
    pub diagnostics: Vec<Diagnostic>,
}

impl<'a> Extractor<'a> {
    pub fn new(src: &'a [u8], lines: &'a LineIndex) -> Extractor<'a> {
        Extractor {
            src,
            lines,
            declared: HashMap::default(),
            out: Extracted {
                positions: Vec::new(),
                frames: Vec::new(),
                facts: Facts::default(),
            },
            diagnostics: Vec::new(),
        }
    }

    pub fn finish(self) -> (Extracted, Vec<Diagnostic>) {
        (self.out, self.diagnostics)
    }

    pub fn statement(&mut self, stmt: &Stmt) {
        let (src, lines) = (self.src, self.lines);
        let out = &mut self.out;
        match &stmt.kind {
            StmtKind::Routine { keyword, .. } => {
                if !upper(src, *keyword).starts_with("DEFDAT") {
                    out.facts.events.push(Event::Reset);
                }
            }
            StmtKind::Decl { type_name, vars } => {
                let ty = upper(src, *type_name);
                let positional = positional_type(&ty);
                for v in vars {
                    if let Some(kind) = positional {
                        self.declared.insert(upper(src, v.name), kind);
                    }
                    let Some(init) = &v.init else { continue };
                    let ExprKind::Aggregate(agg) = &init.kind else {
                        continue;
                    };
                    if ty == "FDAT" {
                        out.facts.fdats.insert(upper(src, v.name), fdat(src, agg));
                    } else if let Some(kind) = positional {
                        let name = crate::syntax::latin1(v.name.slice(src));
                        let f = read_fields(src, agg);
                        let p = build_position(lines, init.span, kind, Some(name), f);
                        if kind == PositionKind::Frame {
                            out.facts.candidates.push(p);
                        } else {
                            out.positions.push(p);
                        }
                    }
                }
            }
            StmtKind::Assign { target, value } => {
                assignment(src, lines, &self.declared, target, value, out);
            }
            StmtKind::Call(call) => {
                if let Some(s) = bas_call(src, call) {
                    out.facts.events.push(Event::Set(s));
                }
            }
            StmtKind::Motion {
                keyword,
                targets,
                with,
            } => {
                let line = lines.line(stmt.span.start);
                if upper(src, *keyword).ends_with("_REL") {
                    self.diagnostics.push(
                        Diagnostic::note(
                            stmt.span,
                            "relative motion: its offset is not a target and is left unchanged",
                        )
                        .with_hint("check this motion by hand after a transform"),
                    );
                    return;
                }
                let mut refs = Vec::new();
                for t in targets {
                    if !target_refs(src, lines, t, &mut refs, &mut out.positions) {
                        self.diagnostics.push(
                            Diagnostic::warning(
                                t.span,
                                "computed target (geometric operator `:` or an expression): \
                                 its operands are not treated as targets",
                            )
                            .with_hint(
                                "trackfix cannot transform a composed frame; check this motion by hand",
                            ),
                        );
                    }
                }
                let with = with
                    .iter()
                    .filter_map(|(l, r)| setting(src, l, r))
                    .collect();
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

fn fdat(src: &[u8], agg: &Aggregate) -> Fdat {
    let mut f = Fdat::default();
    for field in &agg.fields {
        match upper(src, field.name).as_str() {
            "TOOL_NO" => f.tool = integer(src, &field.value),
            "BASE_NO" => f.base = integer(src, &field.value),
            "IPO_FRAME" if field.value.kind == ExprKind::Enum => {
                f.tcp = Some(upper(src, field.value.span) == "#TCP");
            }
            _ => {}
        }
    }
    f
}

/// `BAS(#BASE, n)` / `BAS(#TOOL, n)`.
fn bas_call(src: &[u8], call: &Expr) -> Option<Setting> {
    let ExprKind::Call(name, args) = &call.kind else {
        return None;
    };
    if upper(src, name.span) != "BAS" {
        return None;
    }
    let [Some(which), Some(n)] = args.as_slice() else {
        return None;
    };
    let r = integer(src, n).map_or(FrameRef::Unknown, FrameRef::Data);
    match upper(src, which.span).as_str() {
        "#BASE" => Some(Setting::Base(r)),
        "#TOOL" => Some(Setting::Tool(r)),
        _ => None,
    }
}

/// `$BASE = …`, `$TOOL = …`, `$IPO_MODE = …`, `FDAT_ACT = …` (also inside `WITH`).
/// Aggregate values of `$BASE`/`$TOOL` are handled by [`assignment`], which names them.
fn setting(src: &[u8], target: &Expr, value: &Expr) -> Option<Setting> {
    let fdat_of = || fdat_argument(src, value);
    match upper(src, target.span).as_str() {
        "$BASE" => Some(match &value.kind {
            ExprKind::Call(..) => fdat_of()
                .map(Setting::BaseOfFdat)
                .unwrap_or(Setting::Base(FrameRef::Unknown)),
            _ => Setting::Base(frame_ref(src, value)),
        }),
        "$TOOL" => Some(match &value.kind {
            ExprKind::Call(..) => fdat_of()
                .map(Setting::ToolOfFdat)
                .unwrap_or(Setting::Tool(FrameRef::Unknown)),
            _ => Setting::Tool(frame_ref(src, value)),
        }),
        "$IPO_MODE" => match &value.kind {
            ExprKind::Enum => Some(Setting::Tcp(upper(src, value.span) == "#TCP")),
            ExprKind::Call(..) => fdat_of().map(Setting::TcpOfFdat),
            _ => None,
        },
        "FDAT_ACT" => match &value.kind {
            ExprKind::Name => Some(Setting::Fdat(upper(src, value.span))),
            ExprKind::Aggregate(agg) => Some(Setting::FdatValue(fdat(src, agg))),
            _ => None,
        },
        _ => None,
    }
}

fn assignment(
    src: &[u8],
    lines: &LineIndex,
    declared: &HashMap<String, PositionKind>,
    target: &Expr,
    value: &Expr,
    out: &mut Extracted,
) {
    let ExprKind::Aggregate(agg) = &value.kind else {
        if let Some(s) = setting(src, target, value) {
            out.facts.events.push(Event::Set(s));
        } else if matches!(target.kind, ExprKind::Name | ExprKind::Index(..))
            && matches!(value.kind, ExprKind::Name | ExprKind::Index(..))
        {
            let name = upper(src, target.span);
            if !name.starts_with('$') {
                out.facts.events.push(Event::Alias {
                    name,
                    source: upper(src, value.span),
                });
            }
        }
        return;
    };
    if upper(src, target.span) == "FDAT_ACT" {
        if let Some(s) = setting(src, target, value) {
            out.facts.events.push(Event::Set(s));
        }
        return;
    }
    if let Some((kind, n)) = data_element(src, target) {
        let prefix = if kind == FrameKind::Base {
            "BASE_DATA"
        } else {
            "TOOL_DATA"
        };
        let d = frame_decl(src, lines, format!("{prefix}[{n}]"), kind, value, agg);
        out.frames.push(d);
        return;
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
        return;
    }
    let Some(base) = base_name(src, target) else {
        return;
    };
    if base.starts_with('$') {
        return;
    }
    let f = read_fields(src, agg);
    let name = Some(crate::syntax::latin1(target.span.slice(src)));
    match declared.get(&base) {
        Some(PositionKind::Frame) => out.facts.candidates.push(build_position(
            lines,
            value.span,
            PositionKind::Frame,
            name,
            f,
        )),
        Some(&kind) => out
            .positions
            .push(build_position(lines, value.span, kind, name, f)),
        None => {
            if let Some(kind) = inferred_kind(src, agg, &f) {
                out.facts
                    .candidates
                    .push(build_position(lines, value.span, kind, name, f));
            }
        }
    }
}

/// The targets of a motion: names and inline literals. Returns false when a target is built
/// with the geometric operator `:` (or another expression), whose operands are offsets and
/// frames rather than targets: those are left out and reported by the caller.
fn target_refs(
    src: &[u8],
    lines: &LineIndex,
    e: &Expr,
    refs: &mut Vec<Ref>,
    positions: &mut Vec<Position>,
) -> bool {
    match &e.kind {
        ExprKind::Name | ExprKind::Index(..) => {
            refs.push(Ref::Named(upper(src, e.span)));
            true
        }
        ExprKind::Aggregate(agg) => {
            let f = read_fields(src, agg);
            if let Some(kind) = inferred_kind(src, agg, &f) {
                positions.push(build_position(lines, e.span, kind, None, f));
                refs.push(Ref::Inline(e.span));
            }
            true
        }
        ExprKind::Paren(inner) => target_refs(src, lines, inner, refs, positions),
        _ => false,
    }
}

/// The name trackfix gives a base: `BASE_DATA[n]`, `$WORLD` for base 0.
pub(crate) fn base_label(r: &FrameRef) -> Option<String> {
    match r {
        FrameRef::Data(0) => Some("$WORLD".to_owned()),
        FrameRef::Data(n) => Some(format!("BASE_DATA[{n}]")),
        FrameRef::Named(s) => Some(s.clone()),
        FrameRef::Unknown => None,
    }
}

/// The name trackfix gives a tool: `TOOL_DATA[n]`, `$NULLFRAME` (the flange) for tool 0.
pub(crate) fn tool_label(r: &FrameRef) -> Option<String> {
    match r {
        FrameRef::Data(0) => Some("$NULLFRAME".to_owned()),
        FrameRef::Data(n) => Some(format!("TOOL_DATA[{n}]")),
        FrameRef::Named(s) => Some(s.clone()),
        FrameRef::Unknown => None,
    }
}

#[derive(Clone, Default)]
struct State {
    base: Option<FrameRef>,
    tool: Option<FrameRef>,
    tcp: bool,
}

impl State {
    fn apply(&mut self, s: &Setting, fdats: &HashMap<String, Fdat>) {
        let data = |n: Option<u32>| n.map_or(FrameRef::Unknown, FrameRef::Data);
        match s {
            Setting::Base(r) => self.base = Some(r.clone()),
            Setting::Tool(r) => self.tool = Some(r.clone()),
            Setting::Tcp(t) => self.tcp = *t,
            Setting::FdatValue(f) => {
                self.base = Some(data(f.base));
                self.tool = Some(data(f.tool));
                self.tcp = f.tcp.unwrap_or(false);
            }
            Setting::Fdat(name) => {
                let f = fdats.get(name);
                self.base = Some(data(f.and_then(|f| f.base)));
                self.tool = Some(data(f.and_then(|f| f.tool)));
                self.tcp = f.and_then(|f| f.tcp).unwrap_or(false);
            }
            Setting::BaseOfFdat(name) => {
                self.base = Some(data(fdats.get(name).and_then(|f| f.base)));
            }
            Setting::ToolOfFdat(name) => {
                self.tool = Some(data(fdats.get(name).and_then(|f| f.tool)));
            }
            Setting::TcpOfFdat(name) => {
                self.tcp = fdats.get(name).and_then(|f| f.tcp).unwrap_or(false);
            }
        }
    }
}

fn record_use(u: &mut Usage, base: &Option<String>, tool: &Option<String>, tcp: bool, line: usize) {
    if let Some(b) = base {
        match &u.wobj {
            None => u.wobj = Some(b.clone()),
            Some(w) if w != b && !u.other_wobjs.contains(b) => u.other_wobjs.push(b.clone()),
            Some(_) => {}
        }
    }
    if u.tool.is_none() {
        u.tool.clone_from(tool);
    }
    u.stationary_tool |= tcp;
    if !u.lines.contains(&line) {
        u.lines.push(line);
    }
}

/// Resolves base, tool and IPO mode of every motion of a program (files in the same order as
/// `facts`), fills each used position's [`Usage`], promotes used `FRAME`s and candidate
/// aggregates to positions, and reports motions whose base stays unknown.
pub(crate) fn resolve(files: &mut [ParsedFile], facts: &mut [Facts]) {
    let mut fdats: HashMap<String, Fdat> = HashMap::default();
    for f in facts.iter() {
        for (k, v) in &f.fdats {
            fdats.entry(k.clone()).or_insert_with(|| v.clone());
        }
    }
    // Where each declared name lives: (file, in candidates?, index).
    let mut by_name: HashMap<String, Vec<(usize, bool, usize)>> = HashMap::default();
    for (fi, (file, fact)) in files.iter().zip(facts.iter()).enumerate() {
        for (i, p) in file.positions.iter().enumerate() {
            if let Some(n) = &p.name {
                by_name.entry(name_key(n)).or_default().push((fi, false, i));
            }
        }
        for (i, p) in fact.candidates.iter().enumerate() {
            if let Some(n) = &p.name {
                by_name.entry(name_key(n)).or_default().push((fi, true, i));
            }
        }
    }
    let mut used_candidates: Vec<Vec<bool>> = facts
        .iter()
        .map(|f| vec![false; f.candidates.len()])
        .collect();
    for fi in 0..files.len() {
        let events = facts
            .get_mut(fi)
            .map(|f| std::mem::take(&mut f.events))
            .unwrap_or_default();
        let mut state = State::default();
        let mut aliases: HashMap<&str, &str> = HashMap::default();
        for ev in &events {
            match ev {
                Event::Reset => {
                    state = State::default();
                    aliases.clear();
                }
                Event::Alias { name, source } => {
                    aliases.insert(name, source);
                }
                Event::Set(s) => state.apply(s, &fdats),
                Event::Motion {
                    span,
                    line,
                    refs,
                    with,
                } => {
                    let mut local = state.clone();
                    for s in with {
                        local.apply(s, &fdats);
                    }
                    let base = local.base.as_ref().and_then(base_label);
                    let tool = local.tool.as_ref().and_then(tool_label);
                    let mut found = false;
                    for r in refs {
                        match r {
                            Ref::Inline(s) => {
                                if let Some(p) = files
                                    .get_mut(fi)
                                    .and_then(|f| f.positions.iter_mut().find(|p| p.span == *s))
                                {
                                    record_use(&mut p.usage, &base, &tool, local.tcp, *line);
                                    found = true;
                                }
                            }
                            Ref::Named(n) => {
                                // The name itself, then what it was last copied from.
                                let mut chain = vec![n.as_str()];
                                while chain.len() < 8 {
                                    match chain.last().and_then(|c| aliases.get(c)) {
                                        Some(next) if !chain.contains(next) => chain.push(next),
                                        _ => break,
                                    }
                                }
                                let hits = chain.iter().flat_map(|c| {
                                    by_name.get(*c).map_or(&[][..], Vec::as_slice).iter()
                                });
                                for &(f2, cand, i) in hits {
                                    let p = if cand {
                                        if let Some(u) =
                                            used_candidates.get_mut(f2).and_then(|v| v.get_mut(i))
                                        {
                                            *u = true;
                                        }
                                        facts.get_mut(f2).and_then(|f| f.candidates.get_mut(i))
                                    } else {
                                        files.get_mut(f2).and_then(|f| f.positions.get_mut(i))
                                    };
                                    if let Some(p) = p {
                                        record_use(&mut p.usage, &base, &tool, local.tcp, *line);
                                        found = true;
                                    }
                                }
                            }
                        }
                    }
                    // A motion to a point outside the program (`XHOME` of $config.dat) is not
                    // this program's business.
                    if base.is_none()
                        && found
                        && let Some(file) = files.get_mut(fi)
                    {
                        file.diagnostics.push(
                            Diagnostic::warning(*span, "the base of this motion is not resolved")
                                .with_hint(
                                    "set FDAT_ACT, $BASE=BASE_DATA[n] or BAS(#BASE,n) before it in the same DEF",
                                ),
                        );
                    }
                }
            }
        }
    }
    for (fi, file) in files.iter_mut().enumerate() {
        let (Some(fact), Some(used)) = (facts.get_mut(fi), used_candidates.get(fi)) else {
            continue;
        };
        let cands = std::mem::take(&mut fact.candidates);
        let mut promoted = false;
        for (p, &u) in cands.into_iter().zip(used) {
            if u {
                file.positions.push(p);
                promoted = true;
            } else {
                fact.candidates.push(p);
            }
        }
        if promoted {
            file.positions.sort_by_key(|p| p.span.start);
        }
        file.diagnostics.sort_by_key(|d| d.span.start);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn copies_carry_the_use_to_their_source() {
        let src = b"DEF a()\n  DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\n  DECL E6POS XCOPY\n  $BASE=BASE_DATA[4]\n  XCOPY = XP1\n  XCOPY.Z = XCOPY.Z + 100\n  LIN XCOPY\nEND\n";
        let f = crate::krl::parse_file(Path::new("a.src"), src.to_vec());
        assert_eq!(f.positions.len(), 1);
        let u = &f.positions[0].usage;
        assert_eq!(u.wobj.as_deref(), Some("BASE_DATA[4]"));
        assert_eq!(u.lines, [7]);
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
            .iter()
            .map(|p| {
                (
                    p.usage.wobj.as_deref(),
                    p.usage.tool.as_deref(),
                    p.usage.stationary_tool,
                )
            })
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

    #[test]
    fn bit_strings() {
        assert_eq!(bit_string(b"'B010'"), Some((2, 3)));
        assert_eq!(bit_string(b"'b100011'"), Some((35, 6)));
        assert_eq!(bit_string(b"'H1F'"), None);
        assert_eq!(bit_string(b"'B'"), None);
        assert_eq!(bit_string(b"'B012'"), None);
    }
}
