//! The RAPID parser: a recursive-descent reader over the streaming lexer's tokens that builds
//! the lossless [`Tree`] and never fails.
//!
//! Each function's doc comment names the rule of `grammars/rapid.ebnf` it implements. A
//! statement or item that does not fit its rule becomes an [`NodeKind::Opaque`] leaf running to
//! the next `;` (or to the next block keyword), with a located diagnostic: the round trip holds
//! for every input because leaves are byte ranges and every byte lands in exactly one leaf.

mod expressions;
mod items;
mod statements;

use super::expr::{Arena, ExprKind, NONE};
use super::lexer::{Lexer, Token, TokenKind, ident_len, is_ident_continue, is_keyword};
use super::tree::{NodeKind, Rapid, Tree};
use crate::syntax::{Diagnostic, NumLit, ShortLit, Sink, Span, TreeBuilder};

/// Nesting deeper than this (brackets, blocks) is reported instead of recursed into, so a
/// hostile input cannot overflow the stack.
const MAX_DEPTH: u32 = 96;

/// Storage class of a data declaration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Storage {
    Const,
    Pers,
    Var,
    Alias,
}

/// What the position extractor needs to know about a statement just read; expression ids
/// point into the parser's [`Arena`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Stmt {
    /// A data declaration. `module_scope` is false inside routines.
    Decl {
        storage: Storage,
        type_name: Span,
        name: Span,
        dims: u8,
        init: Option<u32>,
        module_scope: bool,
        /// Declared `LOCAL`: visible only in its module (otherwise in the whole task).
        local: bool,
    },
    /// `PROC`/`FUNC`/`TRAP` head (its name is a module-scope symbol); its required parameters
    /// follow as [`Stmt::Param`].
    Routine { name: Span, local: bool },
    /// A parameter of the routine just read: its name (of `type name`); the required ones in
    /// order, then the optional ones (`\\switch`, `\\num a | num b`: each alternative).
    Param { name: Span, optional: bool },
    /// `RECORD name` (the components follow as [`Stmt::RecordField`]).
    Record { name: Span },
    /// `type name;` inside a `RECORD`.
    RecordField { type_name: Span, name: Span },
    /// A procedure call; `args` is an [`ExprKind::Args`] node, `name` the routine name (for a
    /// late-binding call, the `%expr%` text).
    Call { name: Span, args: u32 },
    /// `target := value;` (`target` is the whole left side, e.g. `p.trans.x`).
    Assign { target: Span, value: u32 },
    /// Any other statement: its expressions are still scanned for inline targets and offsets.
    Other,
}

/// One statement as it is read, handed to the parser's [`Sink`] (the positions layer is one):
/// the source, the scratch arena its expression ids point into (valid only during the call),
/// the statement and its span.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Statement<'e> {
    pub src: &'e [u8],
    pub arena: &'e Arena,
    pub stmt: &'e Stmt,
    pub span: Span,
    /// A [`Stmt::Decl`]'s robtarget value, when the declaration fast path read it: then the
    /// value is not in the arena (release builds give no `init`). Of a [`Stmt::Call`], its
    /// first argument, when [`Parser::literal_call_args`] read it: the first of
    /// [`Statement::plain_args`], which has no value there.
    pub literal: Option<&'e RobtargetLiteral>,
    /// A [`Stmt::Call`]'s arguments, when each is a plain name (see [`PlainArgs`]) or the
    /// first is [`Statement::literal`]: then they are not in the arena (the call's `args` is
    /// [`NONE`]; with a literal, a debug build's `args` are the general path's reading).
    pub plain_args: Option<&'e PlainArgs>,
    /// A call with [`Statement::plain_args`] that [`Parser::call_like_last`] took from the
    /// call before with no label changed: how its offsets moved from that call's.
    pub moved: Option<MovedCall>,
}

/// How a call's offsets lie against the call before it, which it repeats with at most one
/// name (not a label) changed: every offset of that call moves by `shift`, those at `pivot`
/// or after by `grown` more. Offsets are below `u32::MAX` (a source is no longer), so the
/// wrapping arithmetic is exact.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct MovedCall {
    /// Where the call before starts (its callee).
    pub from: usize,
    shift: usize,
    pivot: usize,
    grown: isize,
}

impl MovedCall {
    /// Whether the name changed, if any, ends at or before the offset `at` of the call before
    /// (at its callee's end: the callee changed, `MoveJ` for `MoveL`).
    pub(crate) fn changed_by(&self, at: usize) -> bool {
        self.pivot <= at
    }

    /// Where the offset `at` of the call before lies in this one.
    #[inline(always)]
    pub(crate) fn moved(&self, at: usize) -> usize {
        at.wrapping_add(self.shift)
            .wrapping_add_signed(self.grown * isize::from(at >= self.pivot))
    }
}

/// The most arguments [`PlainArgs`] holds; a call with more takes the arena's paths.
pub(crate) const MAX_PLAIN_ARGS: usize = 16;

/// A call's arguments as [`Parser::plain_args_from`] reads them when every one is a plain name,
/// `name:=name`, `\switch` or `\switch:=name` (`MoveL p10, v1000, z10, tGun\WObj:=wCar;`,
/// most lines of a program): in a fixed array, not as expression nodes, which the extractor
/// then walked back (building and reading a motion's eleven nodes was a tenth of `check`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlainArgs {
    /// Each argument's span, label and value, as their starts and ends one after another: a
    /// call read as the one before it ([`Parser::call_like_last`]) moves them in one loop
    /// the compiler vectorises (field by field they were half of reading such a call).
    offsets: [usize; OFFSETS_PER_ARG * MAX_PLAIN_ARGS],
    /// Each argument written `\name`, and each given a value.
    switch: [bool; MAX_PLAIN_ARGS],
    valued: [bool; MAX_PLAIN_ARGS],
    pub len: usize,
}

/// A [`PlainArg`]'s span, label and value, start and end of each.
const OFFSETS_PER_ARG: usize = 6;

impl PlainArgs {
    const EMPTY: PlainArgs = PlainArgs {
        offsets: [0; OFFSETS_PER_ARG * MAX_PLAIN_ARGS],
        switch: [false; MAX_PLAIN_ARGS],
        valued: [false; MAX_PLAIN_ARGS],
        len: 0,
    };

    /// Puts `arg` as argument `k`; `false` past the most it holds.
    fn set(&mut self, k: usize, arg: PlainArg) -> bool {
        let at = k * OFFSETS_PER_ARG;
        let (Some(offsets), Some(switch), Some(valued)) = (
            self.offsets.get_mut(at..at + OFFSETS_PER_ARG),
            self.switch.get_mut(k),
            self.valued.get_mut(k),
        ) else {
            return false;
        };
        let value = arg.value.unwrap_or(Span { start: 0, end: 0 });
        offsets.copy_from_slice(&[
            arg.span.start,
            arg.span.end,
            arg.label.start,
            arg.label.end,
            value.start,
            value.end,
        ]);
        (*switch, *valued) = (arg.switch, arg.value.is_some());
        true
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = PlainArg> + '_ {
        self.offsets
            .chunks_exact(OFFSETS_PER_ARG)
            .zip(self.switch.iter().zip(&self.valued))
            .take(self.len)
            .map(|(o, (&switch, &valued))| {
                let span = |k: usize| Span {
                    start: o.get(k).copied().unwrap_or_default(),
                    end: o.get(k + 1).copied().unwrap_or_default(),
                };
                PlainArg {
                    span: span(0),
                    label: span(2),
                    switch,
                    value: valued.then(|| span(4)),
                }
            })
    }

    /// Moves every offset of the arguments as `m` says. Only the argument its pivot falls in
    /// compares its offsets with the pivot: the others move whole, in loops of additions alone.
    fn move_offsets(&mut self, m: &MovedCall) {
        let n = (self.len * OFFSETS_PER_ARG).min(self.offsets.len());
        let Some(offsets) = self.offsets.get_mut(..n) else {
            return;
        };
        // The first argument that ends at the pivot or after (its span's end is its last
        // offset in the text).
        let straddles = offsets
            .chunks_exact(OFFSETS_PER_ARG)
            .position(|o| o.get(1).is_some_and(|&end| end >= m.pivot))
            .map_or(n, |k| k * OFFSETS_PER_ARG);
        let (before, rest) = offsets.split_at_mut(straddles.min(n));
        let (straddling, after) = rest.split_at_mut(OFFSETS_PER_ARG.min(rest.len()));
        for at in before {
            *at = at.wrapping_add(m.shift);
        }
        for at in straddling {
            *at = m.moved(*at);
        }
        let shift_and_grown = m.shift.wrapping_add_signed(m.grown);
        for at in after {
            *at = at.wrapping_add(shift_and_grown);
        }
    }
}

/// One argument of [`PlainArgs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PlainArg {
    /// From the argument's first byte (its `\` for a switch) to its end.
    pub span: Span,
    /// The argument's name (`WObj` of `\WObj:=wCar`, `tool` of `tool:=tGun`), empty at the
    /// argument's start for a plain value, as an [`ExprKind::Arg`] node has it.
    pub label: Span,
    /// Written `\name`.
    pub switch: bool,
    /// The name given as its value; `None` for a switch without one, and for the robtarget
    /// literal [`Parser::literal_call_args`] read as a call's first argument.
    pub value: Option<Span>,
}

/// More external axes than a controller has are left to the general path.
pub(crate) const MAX_EXTERNAL_AXES: usize = 12;

/// A scalar robtarget's value `[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,…]]` as the
/// declaration fast path ([`Parser::robtarget_literal`]) reads it: where it is, where each
/// number starts, and the values the lints' verdict needs. Every number is a literal that
/// [`NumLit::parse_prefix`] reads and that fits the compact form ([`NumLit::pack`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RobtargetLiteral {
    /// From its `[` to its `]`.
    pub span: Span,
    pub trans: [usize; 3],
    pub quaternion: [usize; 4],
    pub quadrants: [usize; 4],
    /// The first `axes` are the external axes' starts.
    pub extax: [usize; MAX_EXTERNAL_AXES],
    pub axes: usize,
    /// The values of the quaternion's and the configuration's literals.
    pub q: [f64; 4],
    pub cf: [f64; 4],
}

impl RobtargetLiteral {
    pub(crate) const EMPTY: RobtargetLiteral = RobtargetLiteral {
        span: Span { start: 0, end: 0 },
        trans: [0; 3],
        quaternion: [0; 4],
        quadrants: [0; 4],
        extax: [0; MAX_EXTERNAL_AXES],
        axes: 0,
        q: [f64::NAN; 4],
        cf: [f64::NAN; 4],
    };
}

/// A part of a robtarget literal [`Parser::robtarget_literal`] read (the quaternion or the
/// configuration, `[` to `]`, or the external axes after the first, to the `]`): its text,
/// where its numbers start in it, and their values (as many as it was asked for).
#[derive(Clone, Copy, Debug)]
struct SeenPart {
    text: [u8; SeenPart::MAX_LEN],
    len: usize,
    count: usize,
    offsets: [u8; MAX_EXTERNAL_AXES],
    values: [f64; 4],
    value_count: usize,
}

impl SeenPart {
    /// Longer parts are not remembered (four numbers of 15 digits are 67 bytes).
    const MAX_LEN: usize = 64;

    /// The part `src[i..end]` whose numbers start at `starts` and have `values`.
    fn of(src: &[u8], i: usize, end: usize, starts: &[usize], values: &[f64]) -> Option<SeenPart> {
        let bytes = src.get(i..end)?;
        let mut part = SeenPart {
            text: [0; SeenPart::MAX_LEN],
            len: bytes.len(),
            count: starts.len(),
            offsets: [0; MAX_EXTERNAL_AXES],
            values: [0.0; 4],
            value_count: values.len(),
        };
        part.text.get_mut(..bytes.len())?.copy_from_slice(bytes);
        for (o, &s) in part.offsets.get_mut(..starts.len())?.iter_mut().zip(starts) {
            *o = u8::try_from(s.checked_sub(i)?).ok()?;
        }
        part.values.get_mut(..values.len())?.copy_from_slice(values);
        Some(part)
    }

    /// Whether `src` holds this part's text at `i`: compared 16 bytes at a time, the last word
    /// masked to the part's length (a slice compare was a call to memcmp per part), and where
    /// the source ends sooner, as slices.
    #[inline]
    fn at(&self, src: &[u8], i: usize) -> bool {
        let Some(rest) = src.get(i..) else {
            return false;
        };
        let len = self.len;
        let mut k = 0;
        while k < len {
            let word = |b: &[u8]| {
                b.get(k..)?
                    .first_chunk::<16>()
                    .map(|w| u128::from_le_bytes(*w))
            };
            let (Some(there), Some(here)) = (word(rest), word(&self.text)) else {
                return rest.get(k..len) == self.text.get(k..len);
            };
            let mask = u128::MAX
                .checked_shr(8 * 16usize.saturating_sub(len - k) as u32)
                .unwrap_or(0);
            if (there ^ here) & mask != 0 {
                return false;
            }
            k += 16;
        }
        true
    }

    /// The quaternion or the configuration at `i` (past blanks) read by [`literal_numbers`]
    /// (starts into `starts`, values into `values`: the index after it), or taken whole from
    /// `memo`, the last one read at its place, when it is the same text (a run of targets with
    /// one orientation and configuration), as [`PartMemo`] says when to compare. Inlined: a
    /// call per part was 50 instructions.
    #[inline(always)]
    fn take_or_read(
        memo: &mut PartMemo,
        src: &[u8],
        i: usize,
        starts: &mut [usize; 4],
        values: &mut [f64; 4],
    ) -> Option<usize> {
        let tried = memo.tried();
        if tried
            && let Some(m) = &memo.part
            && m.at(src, i)
        {
            let end = m.read_four(i, starts, values)?;
            #[cfg(debug_assertions)]
            {
                let (mut s, mut v) = ([0; 4], [0.0; 4]);
                assert_eq!(
                    literal_numbers::<4, true>(src, i, &mut s, &mut v),
                    Some(end)
                );
                assert_eq!(&s, starts);
                assert_eq!(v.map(f64::to_bits), values.map(f64::to_bits));
            }
            memo.misses = 0;
            return Some(end);
        }
        let end = literal_numbers::<4, true>(src, i, starts, values)?;
        memo.missed(tried, || SeenPart::of(src, i, end, starts, values));
        Some(end)
    }

    /// What reading the part at `i` gives, as [`SeenPart::at`] found it there: its numbers'
    /// starts and values into `starts` and `values`, the count and the index after the part.
    fn read(&self, i: usize, starts: &mut [usize], values: &mut [f64]) -> Option<(usize, usize)> {
        let offsets = self.offsets.get(..self.count)?;
        for (s, &o) in starts.get_mut(..self.count)?.iter_mut().zip(offsets) {
            *s = i + usize::from(o);
        }
        let n = self.value_count.min(values.len());
        values.get_mut(..n)?.copy_from_slice(self.values.get(..n)?);
        Some((self.count, i + self.len))
    }

    /// [`SeenPart::read`] of a part of four numbers and their values (the quaternion or the
    /// configuration), copied whole: a copy of as many as it holds was a call to memcpy. `None`
    /// for any other part (which a part of four never is).
    #[inline(always)]
    fn read_four(&self, i: usize, starts: &mut [usize; 4], values: &mut [f64; 4]) -> Option<usize> {
        if self.count != 4 || self.value_count != 4 {
            return None;
        }
        *starts = self.offsets.first_chunk::<4>()?.map(|o| i + usize::from(o));
        *values = self.values;
        Some(i + self.len)
    }
}

/// The part last read at one place of a robtarget literal, and how many times in a row the
/// part read there was not it. While each part differs from the one before (targets each with
/// their own orientation), only one in 16 is compared and remembered: doing so for every one
/// cost more than it saved.
#[derive(Clone, Copy, Debug)]
struct PartMemo {
    part: Option<SeenPart>,
    misses: u8,
}

impl PartMemo {
    const EMPTY: PartMemo = PartMemo {
        part: None,
        misses: 0,
    };

    /// Whether the part read now is compared with the one remembered.
    fn tried(&self) -> bool {
        self.misses <= 2 || self.misses.is_multiple_of(16)
    }

    /// A part read in full, not taken from the memo; `tried` as [`PartMemo::tried`] said
    /// before it was read: then `part` (what it was) is remembered.
    fn missed(&mut self, tried: bool, part: impl FnOnce() -> Option<SeenPart>) {
        self.misses = self.misses.wrapping_add(1);
        if tried {
            self.part = part();
        }
    }
}

/// What [`parse`] hands statements to: any `FnMut(Statement)` or [`crate::syntax::NoSink`].
pub(crate) type StatementSink<'s> = dyn for<'e> Sink<Statement<'e>> + 's;

/// The result of parsing: the tree, what went wrong, and how many opaque nodes it holds.
#[derive(Clone, Debug, Default)]
pub struct Parse {
    /// The lossless tree: it prints back the source byte for byte. Empty after a parse that
    /// streams its statements and keeps no tree (loading a program).
    pub tree: Tree,
    /// The tree's leaves cover the source exactly, in order: printing gives it back. Checked
    /// as the leaves are built, also when the tree is not kept.
    pub round_trip: bool,
    /// What could not be read, located; the constructs are kept verbatim as [`NodeKind::Opaque`].
    pub diagnostics: Vec<Diagnostic>,
    /// How many [`NodeKind::Opaque`] nodes the tree holds.
    pub opaque: usize,
}

/// A syntax error inside a construct: where, and what was expected there.
#[derive(Clone, Debug)]
struct SyntaxError {
    at: Token,
    expected: &'static str,
}

type PResult<T> = Result<T, SyntaxError>;

/// Parses a whole source. Never fails, never panics; see [`Parse`].
pub(crate) fn parse(src: &[u8], sink: &mut StatementSink<'_>) -> Parse {
    // About two leaves per statement; robtarget files average ~45 bytes per leaf, so this
    // avoids doubling (and a second copy) for typical modules.
    parse_into(src, sink, TreeBuilder::with_capacity(src.len() / 40 + 4))
}

/// [`parse`] for a caller that takes the statements from `sink` and needs, of the tree, its
/// round trip and a skeleton: every branch and only the leaves `keep_leaf` takes
/// ([`TreeBuilder::skeleton`]).
pub(crate) fn parse_streamed(
    src: &[u8],
    sink: &mut StatementSink<'_>,
    keep_leaf: fn(NodeKind) -> bool,
) -> Parse {
    parse_into(src, sink, TreeBuilder::skeleton(keep_leaf))
}

/// [`parse_streamed`] on the general paths alone: what the tests hold the fast paths to.
#[cfg(test)]
pub(crate) fn parse_streamed_plain(src: &[u8], sink: &mut StatementSink<'_>) -> Parse {
    let mut p = Parser::new(src, sink, TreeBuilder::skeleton(super::flow::walked));
    p.fast_paths = false;
    p.file();
    p.finish()
}

fn parse_into(src: &[u8], sink: &mut StatementSink<'_>, tree: TreeBuilder<Rapid>) -> Parse {
    if let Some(refused) = crate::syntax::too_large(src) {
        return Parse {
            tree: crate::syntax::refused_tree(NodeKind::Opaque),
            round_trip: false,
            diagnostics: vec![refused],
            opaque: 1,
        };
    }
    let mut p = Parser::new(src, sink, tree);
    p.file();
    p.finish()
}

struct Parser<'a, 's> {
    src: &'a [u8],
    lex: Lexer<'a>,
    /// The current significant (non-trivia) token.
    tok: Token,
    /// The token after `tok` and the lexer positioned after it, once looked at.
    peeked: Option<(Token, Lexer<'a>)>,
    /// End of the last significant token consumed.
    prev_end: u32,
    /// Bytes between two leaves become trivia leaves.
    tree: TreeBuilder<Rapid>,
    diagnostics: Vec<Diagnostic>,
    opaque: usize,
    arena: Arena,
    depth: u32,
    /// The unknown token already reported as the cause of an error (not reported twice).
    reported_unknown: Option<u32>,
    /// Use the fast paths [`Parser::numeric_aggregate`] and [`Parser::plain_call_args`] (off
    /// only in tests that compare them with the general path).
    fast_paths: bool,
    /// What [`Parser::robtarget_literal`] last read (reused: it is most of a robtarget file's
    /// declarations).
    literal: RobtargetLiteral,
    /// The quaternion, the configuration and the external axes after the first it last read,
    /// and how many times in a row each was not the one before.
    seen_parts: [PartMemo; 3],
    /// The first token of the statement or item being read (see
    /// [`Parser::next_statement_start`]).
    first: Token,
    /// What [`Parser::plain_args_from`] last read.
    plain: PlainArgs,
    /// The call statement [`Parser::plain`] holds the arguments of, when it was read at its
    /// statement's first byte: from its callee's start to after its `;`.
    last_call: Option<Span>,
    /// How the call [`Parser::plain`] holds moved from the one before, when it took that
    /// call's arguments and no label changed.
    moved: Option<MovedCall>,
    /// The call [`Parser::plain`] holds was read by [`Parser::literal_call_args`]: its first
    /// argument is [`Parser::literal`] (handed on, and cleared, with the call's statement).
    call_literal: bool,
    sink: &'s mut StatementSink<'s>,
}

/// Keywords that end a statement list (and so also end error recovery).
const BLOCK_ENDS: &[&[u8]] = &[
    b"ENDPROC",
    b"ENDFUNC",
    b"ENDTRAP",
    b"ENDMODULE",
    b"ENDRECORD",
    b"MODULE",
    b"PROC",
    b"FUNC",
    b"TRAP",
    b"LOCAL",
    b"TASK",
    b"RECORD",
    b"ERROR",
    b"UNDO",
    b"BACKWARD",
    b"ELSEIF",
    b"ELSE",
    b"ENDIF",
    b"ENDFOR",
    b"ENDWHILE",
    b"CASE",
    b"DEFAULT",
    b"ENDTEST",
];

/// Ends that close a routine or module whatever is open inside them.
const HARD_ENDS: &[&[u8]] = &[
    b"ENDPROC",
    b"ENDFUNC",
    b"ENDTRAP",
    b"ENDMODULE",
    b"MODULE",
    b"PROC",
    b"FUNC",
    b"TRAP",
    b"LOCAL",
    b"TASK",
    b"RECORD",
    b"ERROR",
    b"UNDO",
    b"BACKWARD",
];

/// Reserved words that can never start an operand.
const RESERVED: &[&[u8]] = &[
    b"THEN",
    b"DO",
    b"TO",
    b"FROM",
    b"STEP",
    b"WITH",
    b"ELSE",
    b"ELSEIF",
    b"ENDIF",
    b"ENDFOR",
    b"ENDWHILE",
    b"ENDTEST",
    b"CASE",
    b"DEFAULT",
    b"ENDPROC",
    b"ENDFUNC",
    b"ENDTRAP",
    b"ENDMODULE",
    b"PROC",
    b"FUNC",
    b"TRAP",
    b"MODULE",
    b"CONST",
    b"PERS",
    b"VAR",
    b"IF",
    b"FOR",
    b"WHILE",
    b"TEST",
    b"GOTO",
    b"RETURN",
    b"RAISE",
    b"EXIT",
    b"RETRY",
    b"TRYNEXT",
    b"DIV",
    b"MOD",
    b"AND",
    b"OR",
    b"XOR",
    b"ERROR",
    b"UNDO",
    b"BACKWARD",
    b"LOCAL",
    b"TASK",
    b"INOUT",
    b"RECORD",
    b"ENDRECORD",
    b"ALIAS",
    b"CONNECT",
];

const BINARY_WORDS: &[&[u8]] = &[b"DIV", b"MOD", b"AND", b"OR", b"XOR"];

fn is_word_in(text: &[u8], words: &[&[u8]]) -> bool {
    words.iter().any(|w| w.eq_ignore_ascii_case(text))
}

// ---- what the fast paths read straight from the bytes --------------------------------------

/// The first index at or after `i` that is no blank or line end the fast paths step over
/// (space, tab, CR, LF; the lexer's rarer blanks are left to the general path).
#[inline]
fn blanks_end(src: &[u8], mut i: usize) -> usize {
    while matches!(src.get(i), Some(b' ' | b'\t' | b'\r' | b'\n')) {
        i += 1;
    }
    i
}

/// Whether a name or number that a fast path read up to `at` ends there the way the lexer
/// ends it: not before a letter, digit, `_` or `.` (`0` of `0.5`, `p1` of `p1.x` do not).
#[inline]
fn token_ends(src: &[u8], at: usize) -> bool {
    !src.get(at)
        .is_some_and(|c| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.'))
}

/// The number a fast path reads at `i`, and its length: a sign, digit or point first, read by
/// [`NumLit::parse_prefix`] and ended as the lexer ends it ([`token_ends`]). `None` for
/// anything `NumLit` does not read that way (based numbers, `1E`, overflow), which the
/// general path reads. Written out in each fast path's loop: a call per number was 1.5 % of
/// `check`.
#[inline(always)]
fn fast_number(src: &[u8], i: usize) -> Option<(NumLit, usize)> {
    if !matches!(src.get(i), Some(b'-' | b'+' | b'0'..=b'9' | b'.')) {
        return None;
    }
    let (number, len) = NumLit::parse_prefix(src.get(i..)?)?;
    token_ends(src, i + len).then_some((number, len))
}

/// A number of a robtarget literal as [`literal_number`] reads it.
#[derive(Clone, Copy, Debug)]
struct LiteralNumber {
    start: usize,
    /// The index after it.
    end: usize,
    /// The first byte after it and the blanks there, and its index.
    sep: u8,
    sep_at: usize,
    /// Its value, when it was asked for (else 0).
    value: f64,
}

/// The number of a robtarget literal at `i`, past blanks: one [`fast_number`] reads and that
/// packs ([`NumLit::pack`]), the declaration fast path's rule, with its value when `VALUE`.
/// A short literal right before its `,` or `]` (nearly every one) is read by words
/// ([`ShortLit`]), with no [`NumLit`] built and its value decoded only when asked for; any
/// other is read by [`literal_number_read`], which every debug build holds the short reading
/// to.
#[inline(always)]
fn literal_number<const VALUE: bool>(src: &[u8], i: usize) -> Option<LiteralNumber> {
    let read = match ShortLit::read(src, i) {
        Some(s) if matches!(s.next, b',' | b']') => LiteralNumber {
            start: i,
            end: s.end,
            sep: s.next,
            sep_at: s.end,
            value: if VALUE { s.value() } else { 0.0 },
        },
        _ => return literal_number_read(src, i),
    };
    #[cfg(debug_assertions)]
    {
        let plain = literal_number_read(src, i).map(|n| (n.start, n.end, n.sep, n.sep_at));
        assert_eq!(plain, Some((read.start, read.end, read.sep, read.sep_at)));
        if VALUE {
            let plain = literal_number_read(src, i).map(|n| n.value.to_bits());
            assert_eq!(plain, Some(read.value.to_bits()));
        }
    }
    Some(read)
}

/// [`literal_number`] of any number, through [`fast_number`]: blanks around it, more digits, a
/// longer exponent. Apart, as the rarer case.
#[inline(never)]
fn literal_number_read(src: &[u8], i: usize) -> Option<LiteralNumber> {
    let start = blanks_end(src, i);
    let (number, len) = fast_number(src, start)?;
    number.pack(len)?;
    let end = start + len;
    let sep_at = blanks_end(src, end);
    Some(LiteralNumber {
        start,
        end,
        sep: *src.get(sep_at)?,
        sep_at,
        value: number.value(),
    })
}

/// The bracketed list of `N` numbers of a robtarget literal at `i` (blanks before it), each
/// one [`literal_number`] reads: their starts into `starts` and, when `VALUES`, their values
/// into `values`; the index after its `]`.
#[inline(always)]
fn literal_numbers<const N: usize, const VALUES: bool>(
    src: &[u8],
    i: usize,
    starts: &mut [usize; N],
    values: &mut [f64; N],
) -> Option<usize> {
    let i = blanks_end(src, i);
    if src.get(i) != Some(&b'[') {
        return None;
    }
    let mut i = i + 1;
    for (k, (start, value)) in starts.iter_mut().zip(values.iter_mut()).enumerate() {
        let n = literal_number::<VALUES>(src, i)?;
        *start = n.start;
        if VALUES {
            *value = n.value;
        }
        if n.sep != if k + 1 == N { b']' } else { b',' } {
            return None;
        }
        i = n.sep_at + 1;
    }
    Some(i)
}

/// The index after the `,` at `i` (past blanks) in a robtarget literal.
#[inline(always)]
fn literal_comma(src: &[u8], i: usize) -> Option<usize> {
    let i = blanks_end(src, i);
    (src.get(i) == Some(&b',')).then_some(i + 1)
}

/// The external axes of a robtarget literal at `i` (blanks before them): one to
/// [`MAX_EXTERNAL_AXES`] numbers [`literal_number`] reads, their starts into `starts`; how
/// many and the index after the `]`.
///
/// What follows the first number is taken whole from `tail`, the list read before, when it is
/// the same text (a track's position, then `9E+09` for each unused axis: alike in every
/// target of a program), and remembered when not, as [`SeenPart::take_or_read`] takes a part.
/// A debug build reads it all the same and holds the two to each other.
#[inline(always)]
fn literal_axes(
    src: &[u8],
    i: usize,
    starts: &mut [usize; MAX_EXTERNAL_AXES],
    tail: &mut PartMemo,
) -> Option<(usize, usize)> {
    let i = blanks_end(src, i);
    if src.get(i) != Some(&b'[') {
        return None;
    }
    let first = literal_number::<false>(src, i + 1)?;
    let (head, rest) = starts.split_first_mut()?;
    *head = first.start;
    let tried = tail.tried();
    if tried
        && let Some(m) = &tail.part
        && m.at(src, first.end)
    {
        tail.misses = 0;
        let (count, after) = m.read(first.end, rest, &mut [])?;
        #[cfg(debug_assertions)]
        {
            let mut plain = [0; MAX_EXTERNAL_AXES - 1];
            let read = literal_axes_after(src, first, &mut plain);
            assert_eq!(read, Some((count + 1, after)));
            assert_eq!(plain.get(..count), rest.get(..count));
        }
        return Some((count + 1, after));
    }
    let (count, after) = literal_axes_after(src, first, rest)?;
    tail.missed(tried, || {
        SeenPart::of(src, first.end, after, rest.get(..count - 1)?, &[])
    });
    Some((count, after))
}

/// The external axes after the first, `first`, of a robtarget literal: their starts into
/// `rest`; how many the list holds, the first included, and the index after its `]`.
#[inline(always)]
fn literal_axes_after(
    src: &[u8],
    first: LiteralNumber,
    rest: &mut [usize],
) -> Option<(usize, usize)> {
    let (mut count, mut last) = (1, first);
    while last.sep == b',' {
        let n = literal_number::<false>(src, last.sep_at + 1)?;
        *rest.get_mut(count - 1)? = n.start;
        count += 1;
        last = n;
    }
    (last.sep == b']').then_some((count, last.sep_at + 1))
}

/// The end of the name a fast path reads at `i`: an identifier that is no keyword (a keyword
/// may be an operator or end the statement, which the general path decides).
#[inline]
fn plain_name(src: &[u8], i: usize) -> Option<usize> {
    let rest = src.get(i..)?;
    if !matches!(rest.first()?, b'a'..=b'z' | b'A'..=b'Z' | b'_') {
        return None;
    }
    let len = ident_len(rest);
    (!is_keyword(rest.get(..len)?)).then_some(i + len)
}

/// Whether the bytes at `at` of `src` are `word` (lower-case letters, at most 8) in any case,
/// with 8 bytes to read there: compared as one word with the case bit set, where
/// `eq_ignore_ascii_case` took 8 instructions a byte. (A byte with the bit set is a lower-case
/// letter only if it was that letter in either case.)
#[inline(always)]
fn letters_at(src: &[u8], at: usize, word: &[u8]) -> bool {
    let Some(there) = src.get(at..).and_then(|s| s.first_chunk::<8>()) else {
        return false;
    };
    let mut lower = [0u8; 8];
    for (l, &c) in lower.iter_mut().zip(word) {
        *l = c;
    }
    let mask = u64::MAX
        .checked_shr(8 * (8 - word.len().min(8)) as u32)
        .unwrap_or(0);
    (u64::from_le_bytes(*there) | 0x2020_2020_2020_2020) & mask == u64::from_le_bytes(lower) & mask
}

impl<'a, 's> Parser<'a, 's> {
    fn new(
        src: &'a [u8],
        sink: &'s mut StatementSink<'s>,
        tree: TreeBuilder<Rapid>,
    ) -> Parser<'a, 's> {
        let mut p = Parser {
            src,
            lex: Lexer::new(src),
            tok: Token::NONE,
            peeked: None,
            prev_end: 0,
            tree,
            diagnostics: Vec::new(),
            opaque: 0,
            arena: Arena::default(),
            depth: 0,
            reported_unknown: None,
            fast_paths: true,
            literal: RobtargetLiteral::EMPTY,
            plain: PlainArgs::EMPTY,
            first: Token::NONE,
            last_call: None,
            moved: None,
            call_literal: false,
            seen_parts: [PartMemo::EMPTY; 3],
            sink,
        };
        p.tok = p.next_significant();
        p
    }

    fn finish(self) -> Parse {
        let end = self.src.len() as u32;
        let built = self.tree.finish(end);
        Parse {
            tree: built.tree,
            round_trip: built.round_trip,
            diagnostics: self.diagnostics,
            opaque: self.opaque,
        }
    }

    // ---- tokens -------------------------------------------------------------------------

    /// [`Parser::next_significant`] for the token that starts a statement: first as the one
    /// the statement before started with ([`Parser::first`]), else lexed.
    fn next_statement_start(&mut self) -> Token {
        self.lex.skip_blanks();
        let first = self.first;
        if first.kind == TokenKind::Ident
            && let Some(t) = self.lex.ident_again(first.text(self.src), first.keyword)
        {
            debug_assert_eq!(t, {
                let mut lex = self.lex;
                lex.seek(t.start as usize);
                lex.next_token()
            });
            return t;
        }
        self.next_significant()
    }

    fn next_significant(&mut self) -> Token {
        loop {
            self.lex.skip_blanks();
            let t = self.lex.next_token();
            if !t.kind.is_trivia() {
                return t;
            }
        }
    }

    fn bump(&mut self) -> Token {
        let t = self.tok;
        if t.kind == TokenKind::Unknown && self.reported_unknown != Some(t.start) {
            // Stepped over while recovering from another error: still say where it is.
            self.diagnostics.push(
                Diagnostic::error(
                    t.span(),
                    format!("{} in the program text", self.describe(t)),
                )
                .with_hint("remove the byte or move it into a comment or string"),
            );
        }
        if t.kind != TokenKind::Eof {
            self.prev_end = t.end;
            self.tok = self.next_after();
        }
        t
    }

    /// The token after the current one: the one lexed ahead, else lexed now.
    #[inline(always)]
    fn next_after(&mut self) -> Token {
        match self.peeked.take() {
            Some((next, lex)) => {
                self.lex = lex;
                next
            }
            None => self.next_significant(),
        }
    }

    /// The token after the current one (lexed once on a copy of the lexer, then kept).
    fn peek2(&mut self) -> Token {
        if let Some((t, _)) = self.peeked {
            return t;
        }
        let mut lex = self.lex;
        let t = loop {
            let t = lex.next_token();
            if !t.kind.is_trivia() {
                break t;
            }
        };
        self.peeked = Some((t, lex));
        t
    }

    /// A line break lies between the last consumed token and the current one.
    fn newline_before_tok(&self) -> bool {
        self.src
            .get(self.prev_end as usize..self.tok.start as usize)
            .is_some_and(|gap| gap.iter().any(|&b| b == b'\n' || b == b'\r'))
    }

    fn text(&self, t: Token) -> &'a [u8] {
        t.text(self.src)
    }

    fn at_kw(&self, kw: &[u8]) -> bool {
        self.tok.keyword && self.text(self.tok).eq_ignore_ascii_case(kw)
    }

    fn at_any(&self, words: &[&[u8]]) -> bool {
        self.tok.keyword && is_word_in(self.text(self.tok), words)
    }

    fn is_reserved(&self, t: Token) -> bool {
        t.keyword && is_word_in(self.text(t), RESERVED)
    }

    fn at_punct(&self, c: u8) -> bool {
        self.tok.punct(self.src) == c
    }

    fn eat_punct(&mut self, c: u8) -> bool {
        if self.at_punct(c) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn expect_punct(&mut self, c: u8, expected: &'static str) -> PResult<Token> {
        if self.at_punct(c) {
            Ok(self.bump())
        } else {
            Err(self.error(expected))
        }
    }

    fn expect_kw(&mut self, kw: &[u8], expected: &'static str) -> PResult<Token> {
        if self.at_kw(kw) {
            Ok(self.bump())
        } else {
            Err(self.error(expected))
        }
    }

    fn expect_ident(&mut self, expected: &'static str) -> PResult<Token> {
        if self.tok.kind == TokenKind::Ident && !self.is_reserved(self.tok) {
            Ok(self.bump())
        } else {
            Err(self.error(expected))
        }
    }

    fn error(&self, expected: &'static str) -> SyntaxError {
        SyntaxError {
            at: self.tok,
            expected,
        }
    }

    /// Goes on after `end`, up to which a fast path read the bytes itself: the next token is
    /// lexed from there.
    fn resume_at(&mut self, end: usize) {
        self.lex.seek(end);
        self.peeked = None;
        self.prev_end = end as u32;
        self.tok = self.next_significant();
    }

    /// [`Parser::resume_at`] the end of a statement: the next token is lexed as
    /// [`Parser::next_statement_start`] lexes it.
    fn resume_at_statement_end(&mut self, end: usize) {
        self.lex.seek(end);
        self.peeked = None;
        self.prev_end = end as u32;
        self.tok = self.next_statement_start();
    }

    // ---- tree building ------------------------------------------------------------------

    /// Pushes a leaf from `start` to the end of the last consumed token.
    fn leaf(&mut self, kind: NodeKind, start: u32) {
        self.tree.leaf(kind, start, self.prev_end);
    }

    fn open(&mut self, kind: NodeKind, start: u32) -> usize {
        self.tree.open(kind, start)
    }

    fn close(&mut self, idx: usize) {
        self.tree.close(idx);
    }

    /// Hands `stmt` to the sink; a call whose arguments [`Parser::plain_args_from`] read (its
    /// `args` is [`NONE`]) with them, and one [`Parser::literal_call_args`] read with them and
    /// its literal.
    fn emit(&mut self, stmt: Stmt, start: u32) {
        let literal = std::mem::take(&mut self.call_literal);
        let plain = literal || matches!(stmt, Stmt::Call { args: NONE, .. });
        self.sink.accept(Statement {
            src: self.src,
            arena: &self.arena,
            stmt: &stmt,
            span: Span::new(start as usize, self.prev_end as usize),
            literal: literal.then_some(&self.literal),
            plain_args: plain.then_some(&self.plain),
            moved: if plain { self.moved } else { None },
        });
    }

    /// [`Parser::emit`] of a declaration, handing on [`Parser::literal`] too when `literal`.
    fn emit_with(&mut self, stmt: Stmt, start: u32, literal: bool) {
        self.sink.accept(Statement {
            src: self.src,
            arena: &self.arena,
            stmt: &stmt,
            span: Span::new(start as usize, self.prev_end as usize),
            literal: literal.then_some(&self.literal),
            plain_args: None,
            moved: None,
        });
    }

    /// Ends the head of a compound statement's part (`ELSEIF … THEN`, `CASE …:`) that started
    /// at `start`: a leaf and a statement when it parsed, an error and an opaque leaf when not.
    fn close_part(&mut self, head: PResult<()>, kind: NodeKind, start: u32) {
        match head {
            Ok(()) => {
                self.leaf(kind, start);
                self.emit(Stmt::Other, start);
            }
            Err(e) => self.recover(start, e),
        }
    }

    fn describe(&self, t: Token) -> String {
        match t.kind {
            TokenKind::Eof => "the end of the file".to_owned(),
            TokenKind::Unknown => format!(
                "the byte(s) `{}` that RAPID does not allow here",
                crate::syntax::latin1(self.text(t)).escape_default()
            ),
            TokenKind::UnterminatedStr => "a string without its closing quote".to_owned(),
            _ => {
                let text = crate::syntax::latin1(self.text(t));
                let short: String = text.chars().take(40).collect();
                format!("`{short}`")
            }
        }
    }

    /// Records a syntax error and turns what was read of the construct, up to the next `;` or
    /// block keyword, into an opaque leaf.
    fn recover(&mut self, start: u32, err: SyntaxError) {
        let found = self.describe(err.at);
        if err.at.kind == TokenKind::Unknown {
            self.reported_unknown = Some(err.at.start);
        }
        let hint = match err.at.kind {
            TokenKind::UnterminatedStr => {
                "close the string with `\"` on the same line (write `\"\"` for a quote inside it)"
            }
            TokenKind::Unknown => {
                "remove the byte or move it into a comment or string; the line is kept as it is"
            }
            TokenKind::Eof => "the file looks truncated: complete the construct",
            _ => "fix the syntax; trackfix keeps this text verbatim and does not transform it",
        };
        // A statement missing its `;` (a generator's `WaitTime 1.000` line) ends at the line
        // break when the next line starts with a name: the following statement is read as
        // usual instead of disappearing into this opaque node with its targets.
        let next_line_starts_statement = err.at.kind == TokenKind::Ident
            && err.at.start == self.tok.start
            && err.at.start > start
            && self.newline_before_tok();
        let diagnostic = if next_line_starts_statement {
            let end = self.prev_end as usize;
            Diagnostic::error(
                Span::new(end, end),
                format!(
                    "expected {} before the line break, found {found} on the next line",
                    err.expected
                ),
            )
            .with_hint("add the missing `;`; trackfix keeps this line verbatim")
        } else {
            Diagnostic::error(
                err.at.span(),
                format!("expected {}, found {found}", err.expected),
            )
            .with_hint(hint)
        };
        self.diagnostics.push(diagnostic);
        if next_line_starts_statement {
            self.prev_end = self.prev_end.max(start);
        } else {
            self.skip_to_statement_end(start);
        }
        self.opaque += 1;
        self.leaf(NodeKind::Opaque, start);
    }

    fn skip_to_statement_end(&mut self, start: u32) {
        loop {
            if self.tok.kind == TokenKind::Eof {
                break;
            }
            if self.at_punct(b';') {
                self.bump();
                break;
            }
            // Stop before a block keyword so the enclosing construct can resume, but always
            // consume something: a stray keyword where a statement was expected is the error.
            if self.at_any(BLOCK_ENDS) && self.prev_end > start {
                break;
            }
            self.bump();
        }
        if self.prev_end < start {
            self.prev_end = start;
        }
    }

    /// A construct understood only as far as its extent (module-level text that is not an
    /// item): an opaque leaf with a warning.
    fn unknown_item(&mut self, start: u32) {
        let first = self.tok;
        if first.kind == TokenKind::Unknown {
            self.reported_unknown = Some(first.start);
        }
        self.skip_to_statement_end(start);
        if self.prev_end <= start {
            self.bump();
        }
        self.opaque += 1;
        let message = format!(
            "unknown construct at module level starting with {}; kept verbatim",
            self.describe(first)
        );
        // Bytes no RAPID text may hold are an error; an unknown but well-formed construct is
        // only a warning (trackfix keeps it and does not look inside).
        let diagnostic = match first.kind {
            TokenKind::Unknown | TokenKind::UnterminatedStr => {
                Diagnostic::error(first.span(), message)
                    .with_hint("remove the bytes or close the string; the text is kept as it is")
            }
            _ => Diagnostic::warning(first.span(), message)
                .with_hint("trackfix does not read or transform anything in it"),
        };
        self.diagnostics.push(diagnostic);
        self.leaf(NodeKind::Opaque, start);
    }
}

/// Robtarget literals as generated programs write them inline, for the property tests: mostly
/// of the fast paths' shape (signs, exponents, the spellings of `9E9`, blanks, CRLF), some with
/// one thing they leave to the general path (another count of external axes, a joint target's
/// shape, a name for the external axes, a comment or a Latin-1 byte between two numbers, a
/// number `NumLit` does not read whole, a sign apart). `\u{1}` stands for the Latin-1 byte `Ä`
/// ([`latin1_bytes`]).
#[cfg(test)]
pub(crate) fn inline_robtarget() -> impl proptest::strategy::Strategy<Value = String> {
    use proptest::prelude::*;
    let number = proptest::sample::select(vec![
        "0",
        "0.5",
        "-0.5",
        ".5",
        "5.",
        "+1",
        "9E+09",
        "9E9",
        "9e+9",
        "9E09",
        "9E+9",
        "1.50E+2",
        "2.5e-3",
        "0.707107",
        "-0.707107",
        "1520.3",
        "-1520.30",
        "0.000000",
        "1",
        "-1",
        "0.3826834323650898",
        "-850.123456",
        "1234567.1234567",
        "+0.0",
    ]);
    let odd_number = proptest::sample::select(vec![
        "12345678901234567890",
        "1E",
        "1.2.3",
        "x",
        "1E-9000",
        "-0.38268343236508977",
        "- 5",
        "\u{1}",
        "0x1F",
        "1E+123",
    ]);
    let sep = proptest::sample::select(vec![",", " , ", ",\r\n    ", ",\t", ", ", ",\n"]);
    let odd_sep = proptest::sample::select(vec![" ! c\r\n,", ",\u{1}", ",\u{c}", ",,"]);
    // The four parts' counts of a robtarget (mostly six external axes), a joint target's,
    // or any others.
    let lengths = prop_oneof![
        12 => Just(vec![3, 4, 4, 6]),
        2 => (1usize..=13).prop_map(|axes| vec![3, 4, 4, axes]),
        1 => Just(vec![6, 6]),
        1 => proptest::collection::vec(0usize..8, 1..6),
    ];
    let numbers = proptest::collection::vec(number, 40);
    let once = |s| proptest::option::weighted(0.1, (any::<proptest::sample::Index>(), s));
    (
        lengths,
        numbers,
        sep,
        once(odd_number),
        once(odd_sep),
        proptest::bool::weighted(0.05),
    )
        .prop_map(|(lengths, numbers, sep, odd_number, odd_sep, axes_named)| {
            let count: usize = lengths.iter().sum();
            let mut numbers: Vec<&str> = numbers.into_iter().cycle().take(count).collect();
            if let (Some((at, n)), false) = (odd_number, numbers.is_empty()) {
                let k = at.index(numbers.len());
                numbers[k] = n;
            }
            let mut seps = vec![sep; count + lengths.len()];
            if let Some((at, s)) = odd_sep {
                let k = at.index(seps.len());
                seps[k] = s;
            }
            let (mut numbers, mut seps) = (numbers.into_iter(), seps.into_iter());
            let last = lengths.len() - 1;
            let parts: Vec<String> = lengths
                .iter()
                .enumerate()
                .map(|(k, &n)| {
                    let mut part = "[".to_owned();
                    for j in 0..n {
                        if j > 0 {
                            part.push_str(seps.next().unwrap_or(","));
                        }
                        part.push_str(numbers.next().unwrap_or("0"));
                    }
                    part.push(']');
                    match k == last && axes_named {
                        true => "rdkExtJoints".to_owned(),
                        false => part,
                    }
                })
                .collect();
            let mut literal = "[".to_owned();
            for (k, part) in parts.iter().enumerate() {
                if k > 0 {
                    literal.push_str(seps.next().unwrap_or(","));
                }
                literal.push_str(part);
            }
            literal + "]"
        })
}

/// The bytes of a test input written with `\u{1}` for the Latin-1 byte `Ä` (0xC4, the way a
/// controller writes it; not UTF-8).
#[cfg(test)]
pub(crate) fn latin1_bytes(s: &str) -> Vec<u8> {
    s.bytes().map(|b| if b == 1 { 0xc4 } else { b }).collect()
}

#[cfg(test)]
mod tests {
    /// Every rule of `grammars/rapid.ebnf` is cited by the function that implements it, and
    /// every cited rule is in the grammar.
    #[test]
    fn grammar_rules_and_parser_functions_agree() {
        crate::syntax::grammar_check::assert_rules_cited(
            "grammars/rapid.ebnf",
            &[
                "src/rapid/lexer.rs",
                "src/rapid/parser/mod.rs",
                "src/rapid/parser/items.rs",
                "src/rapid/parser/statements.rs",
                "src/rapid/parser/expressions.rs",
            ],
        );
    }

    /// `letters_at` is `eq_ignore_ascii_case` of the bytes there, for every byte value in
    /// each place of the words it is asked about (and nothing where 8 bytes cannot be read).
    #[test]
    fn letters_compared_as_a_word_are_the_letters_compared_one_by_one() {
        for word in [&b"const"[..], b"pers", b"var", b"robtarge"] {
            for place in 0..word.len() {
                for b in 0..=255u8 {
                    let mut src = word.to_ascii_uppercase();
                    src[place] = b;
                    src.extend_from_slice(b"\xe4 robtarget");
                    let by_bytes = src[..word.len()].eq_ignore_ascii_case(word);
                    assert_eq!(super::letters_at(&src, 0, word), by_bytes, "{src:?}");
                    assert!(!super::letters_at(&src[..7], 0, word));
                }
            }
        }
    }
}
