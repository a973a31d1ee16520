//! Expressions: operators, postfix access, primaries, aggregates and the numeric-aggregate
//! fast path (`grammars/rapid.ebnf`, section "expressions").

use super::*;

impl Parser<'_, '_> {
    /// Fast path of `aggregate` for the shape that makes up most of a robtarget file:
    /// brackets, commas, numbers with an attached sign, spaces and newlines — nothing else.
    /// It builds exactly the nodes the general path would, straight from the bytes; on anything
    /// else it undoes its nodes and returns `None`, and the general path reads the aggregate.
    pub(super) fn numeric_aggregate(&mut self) -> Option<u32> {
        const MAX: usize = 16;
        let src = self.src;
        let mark = self.arena.mark();
        let mut stack = [(NONE, NONE); MAX];
        let mut depth = 0usize;
        let mut i = self.tok.start as usize;
        // After `[` or `,` an element must follow (or `]` right after `[`).
        let mut expect_elem = true;
        let mut just_opened = false;
        let mut root = NONE;
        let ok = loop {
            let Some(&b) = src.get(i) else { break false };
            match b {
                b' ' | b'\t' | b'\r' | b'\n' => i += 1,
                b'[' if expect_elem => {
                    if depth == MAX {
                        break false;
                    }
                    let id = self.arena.open(ExprKind::Aggregate, i as u32);
                    if depth > 0 {
                        let (parent, last) = stack[depth - 1];
                        self.arena.link(parent, last, id);
                        stack[depth - 1].1 = id;
                    } else {
                        root = id;
                    }
                    stack[depth] = (id, NONE);
                    depth += 1;
                    i += 1;
                    just_opened = true;
                }
                b']' if !expect_elem || just_opened => {
                    let Some(d) = depth.checked_sub(1) else {
                        break false;
                    };
                    depth = d;
                    self.arena.close(stack[depth].0, i as u32 + 1);
                    i += 1;
                    if depth == 0 {
                        break true;
                    }
                    expect_elem = false;
                    just_opened = false;
                }
                b',' if !expect_elem => {
                    i += 1;
                    expect_elem = true;
                    just_opened = false;
                }
                b'-' | b'+' | b'0'..=b'9' | b'.' if expect_elem && depth > 0 => {
                    // The literal is parsed while it is scanned, and kept for the extractor.
                    let Some((lit, len)) = fast_number(src, i) else {
                        break false;
                    };
                    let end = i + len;
                    let id = self.arena.num(i as u32, end as u32, lit);
                    let (parent, last) = stack[depth - 1];
                    self.arena.link(parent, last, id);
                    stack[depth - 1].1 = id;
                    i = end;
                    expect_elem = false;
                    just_opened = false;
                }
                _ => break false,
            }
        };
        if !ok || root == NONE {
            self.arena.truncate(mark);
            return None;
        }
        self.resume_at(i);
        Some(root)
    }

    /// Fast path of a scalar robtarget declaration's value, at its `[`: the literal
    /// `[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,…]]` with one to
    /// [`MAX_EXTERNAL_AXES`] external axes, blanks between, every number one that
    /// [`NumLit::parse_prefix`] reads and that packs, and `;` right after it. Read into
    /// [`Parser::literal`] straight from the bytes, with no expression nodes: the extractor
    /// packs it as it is (most of a robtarget file is these, and building the nodes to walk
    /// them once was a fifth of reading the file). On anything else nothing is read and the
    /// general path reads the value; [`Parser::literal_read_again`] holds the two to the same
    /// end in every debug build.
    pub(super) fn robtarget_literal(&mut self) -> bool {
        let read = self.robtarget_literal_at(self.tok.start as usize);
        if read {
            self.resume_at(self.literal.span.end);
        }
        read
    }

    /// [`Parser::robtarget_literal`] of the value whose `[` is at `start`, wherever the
    /// parser stands, and without moving it (nothing is read on anything else): a `;` follows
    /// the literal past blanks.
    pub(super) fn robtarget_literal_at(&mut self, start: usize) -> bool {
        self.robtarget_literal_then(start, |next| next == b';')
    }

    /// [`Parser::robtarget_literal_at`] of a literal followed, past blanks, by a byte `follows`
    /// takes (`;` after a declaration's value; `,`, `\\` or `;` after a call's argument, which
    /// [`Parser::literal_call_args`] reads).
    #[inline(always)]
    pub(super) fn robtarget_literal_then(
        &mut self,
        start: usize,
        follows: impl FnOnce(u8) -> bool,
    ) -> bool {
        let src = self.src;
        if src.get(start) != Some(&b'[') {
            return false;
        }
        let lit = &mut self.literal;
        let [q_part, cf_part, ex_tail] = &mut self.seen_parts;
        let read = (|| {
            let i = literal_numbers::<3, false>(src, start + 1, &mut lit.trans, &mut [0.0; 3])?;
            let q_at = blanks_end(src, literal_comma(src, i)?);
            let (q, values) = (&mut lit.quaternion, &mut lit.q);
            let i = SeenPart::take_or_read(q_part, src, q_at, q, values)?;
            let cf_at = blanks_end(src, literal_comma(src, i)?);
            let (cf, values) = (&mut lit.quadrants, &mut lit.cf);
            let i = SeenPart::take_or_read(cf_part, src, cf_at, cf, values)?;
            let (axes, i) = literal_axes(src, literal_comma(src, i)?, &mut lit.extax, ex_tail)?;
            let i = blanks_end(src, i);
            (src.get(i) == Some(&b']')
                && src.get(blanks_end(src, i + 1)).is_some_and(|&b| follows(b)))
            .then_some((axes, i + 1))
        })();
        let Some((axes, end)) = read else {
            return false;
        };
        lit.axes = axes;
        lit.span = Span::new(start, end);
        true
    }

    /// Reads the value [`Parser::robtarget_literal`] just read again, with the general fast
    /// path, and asserts that it ends where that one did: the arena's node of the value.
    #[cfg(debug_assertions)]
    pub(super) fn literal_read_again(&mut self) -> u32 {
        let after = (self.tok, self.prev_end);
        let start = self.literal.span.start as u32;
        self.tok = Token {
            kind: TokenKind::Punct,
            keyword: false,
            start,
            end: start + 1,
        };
        let id = self.numeric_aggregate();
        assert_eq!((self.tok, self.prev_end), after);
        id.unwrap_or(NONE)
    }

    // ---- expressions --------------------------------------------------------------------

    /// `expr = unary { binop unary }` with
    /// `binop = "+" | "-" | "*" | "/" | "=" | "<" | ">" | "<=" | ">=" | "<>" | "DIV" | "MOD"
    ///        | "AND" | "OR" | "XOR"`. Precedence does not matter to trackfix and is not kept.
    pub(super) fn expr(&mut self) -> PResult<u32> {
        self.nested("a less deeply nested expression", Self::expr_inner)
    }

    /// Runs `parse` one level deeper, refusing (with `expected`) past `MAX_DEPTH` so that
    /// hostile nesting is an error, not a stack overflow.
    pub(super) fn nested(
        &mut self,
        expected: &'static str,
        parse: fn(&mut Self) -> PResult<u32>,
    ) -> PResult<u32> {
        if self.depth > MAX_DEPTH {
            return Err(self.error(expected));
        }
        self.depth += 1;
        let r = parse(self);
        self.depth -= 1;
        r
    }

    pub(super) fn expr_inner(&mut self) -> PResult<u32> {
        let start = self.tok.start;
        let first = self.unary()?;
        if !self.at_binop() {
            return Ok(first);
        }
        // The compound is allocated after its first operand (only now is it known to be one).
        let comp = self.arena.open(ExprKind::Compound, start);
        self.arena.link(comp, NONE, first);
        let mut last = first;
        while self.at_binop() {
            self.bump();
            let next = self.unary()?;
            self.arena.link(comp, last, next);
            last = next;
        }
        self.arena.close(comp, self.prev_end);
        Ok(comp)
    }

    pub(super) fn at_binop(&self) -> bool {
        match self.tok.kind {
            TokenKind::Compare2 => true,
            TokenKind::Punct => matches!(
                self.tok.punct(self.src),
                b'+' | b'-' | b'*' | b'/' | b'=' | b'<' | b'>'
            ),
            TokenKind::Ident => self.tok.keyword && is_word_in(self.text(self.tok), BINARY_WORDS),
            _ => false,
        }
    }

    /// `unary = [ "-" | "+" | "NOT" ] postfix` — a sign written directly before a number is
    /// part of the numeric literal (`-0.5`), so a transform rewrites sign and digits together.
    pub(super) fn unary(&mut self) -> PResult<u32> {
        let t = self.tok;
        let c = t.punct(self.src);
        if c == b'-' || c == b'+' {
            self.bump();
            if self.tok.kind == TokenKind::Number && self.tok.start == t.end {
                let n = self.bump();
                let id = self.arena.open(ExprKind::Num, t.start);
                self.arena.close(id, n.end);
                return Ok(id);
            }
            return self.operator_applied(t.start);
        }
        if self.at_kw(b"NOT") {
            self.bump();
            return self.operator_applied(t.start);
        }
        self.postfix()
    }

    /// The compound of a unary operator that started at `start` and the operand after it,
    /// counted against the nesting limit.
    pub(super) fn operator_applied(&mut self, start: u32) -> PResult<u32> {
        let id = self.arena.open(ExprKind::Compound, start);
        let inner = self.nested("fewer stacked unary operators", Self::unary)?;
        self.arena.link(id, NONE, inner);
        self.arena.close(id, self.prev_end);
        Ok(id)
    }

    /// `postfix = primary { "{" expr { "," expr } "}" | "." ident }`
    pub(super) fn postfix(&mut self) -> PResult<u32> {
        let start = self.tok.start;
        let mut base = self.primary()?;
        while self.at_punct(b'{') || self.at_punct(b'.') {
            // The access node wraps what was read so far: move it under a new parent by
            // allocating the parent now and linking the base as its first child.
            let acc = self.arena.open(ExprKind::Access, start);
            self.arena.link(acc, NONE, base);
            let mut last = base;
            if self.eat_punct(b'.') {
                self.expect_ident("a component name after `.`")?;
            } else {
                self.bump();
                loop {
                    let i = self.expr()?;
                    self.arena.link(acc, last, i);
                    last = i;
                    if self.eat_punct(b'}') {
                        break;
                    }
                    self.expect_punct(b',', "`,` or `}` in the index")?;
                }
            }
            self.arena.close(acc, self.prev_end);
            base = acc;
        }
        Ok(base)
    }

    /// `primary = number | string | placeholder | "*" | aggregate | "(" expr ")"
    ///          | ident [ "(" [ arg { [ "," ] arg } ] ")" ]`
    /// with `aggregate = "[" [ expr { "," expr } ] "]"`.
    pub(super) fn primary(&mut self) -> PResult<u32> {
        let t = self.tok;
        match t.kind {
            TokenKind::Number => {
                self.bump();
                let id = self.arena.open(ExprKind::Num, t.start);
                self.arena.close(id, t.end);
                Ok(id)
            }
            TokenKind::Str => {
                self.bump();
                let id = self.arena.open(ExprKind::Str, t.start);
                self.arena.close(id, t.end);
                Ok(id)
            }
            TokenKind::Placeholder => {
                self.bump();
                let id = self.arena.open(ExprKind::Placeholder, t.start);
                self.arena.close(id, t.end);
                Ok(id)
            }
            TokenKind::Ident if !self.is_reserved(t) => {
                self.bump();
                if self.at_punct(b'(') {
                    self.bump();
                    let id = self.arena.open(ExprKind::Call, t.start);
                    if let Some(n) = self.arena.set_mut(id) {
                        n.name_start = t.start;
                        n.name_end = t.end;
                    }
                    let mut last = NONE;
                    let mut first = true;
                    while !self.at_punct(b')') {
                        if !first && !self.eat_punct(b',') && !self.at_punct(b'\\') {
                            return Err(self.error("`,` or `)` in the function arguments"));
                        }
                        first = false;
                        let a = self.arg()?;
                        self.arena.link(id, last, a);
                        last = a;
                    }
                    let close = self.bump();
                    self.arena.close(id, close.end);
                    Ok(id)
                } else {
                    let id = self.arena.open(ExprKind::Ident, t.start);
                    self.arena.close(id, t.end);
                    Ok(id)
                }
            }
            TokenKind::Punct if t.punct(self.src) == b'[' => {
                if self.fast_paths
                    && let Some(id) = self.numeric_aggregate()
                {
                    return Ok(id);
                }
                self.bump();
                let id = self.arena.open(ExprKind::Aggregate, t.start);
                let mut last = NONE;
                if !self.at_punct(b']') {
                    loop {
                        let e = self.expr()?;
                        self.arena.link(id, last, e);
                        last = e;
                        if self.eat_punct(b',') {
                            continue;
                        }
                        break;
                    }
                }
                let close = self.expect_punct(b']', "`,` or `]` in the aggregate")?;
                self.arena.close(id, close.end);
                Ok(id)
            }
            TokenKind::Punct if t.punct(self.src) == b'*' => {
                // `MoveL *, v100, ...`: an unnamed target stored by an old editor.
                self.bump();
                let id = self.arena.open(ExprKind::Placeholder, t.start);
                self.arena.close(id, t.end);
                Ok(id)
            }
            TokenKind::Punct if t.punct(self.src) == b'(' => {
                self.bump();
                let id = self.arena.open(ExprKind::Compound, t.start);
                let e = self.expr()?;
                self.arena.link(id, NONE, e);
                let close = self.expect_punct(b')', "`)`")?;
                self.arena.close(id, close.end);
                Ok(id)
            }
            _ => Err(self.error("a value")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    type Read = (
        Vec<crate::rapid::expr::ExprNode>,
        Vec<Option<String>>,
        Option<Token>,
    );

    /// The expression nodes, the literal each number resolves to (handed on by the parser or
    /// parsed from its span, as the extractor does; `Debug` keeps the sign of `-0`) and the
    /// following token, read with or without the fast path.
    fn read(src: &[u8], fast: bool) -> Read {
        let mut sink = crate::syntax::NoSink;
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        p.fast_paths = fast;
        match p.expr() {
            Ok(_) => {
                let lits = p
                    .arena
                    .nodes
                    .iter()
                    .map(|n| {
                        let lit = p.arena.lit(n);
                        assert!(
                            fast || lit.is_none(),
                            "only the fast path hands literals on"
                        );
                        let lit = lit.or_else(|| NumLit::parse(n.span().slice(src)));
                        lit.map(|l| format!("{l:?}"))
                    })
                    .collect();
                let nodes = p
                    .arena
                    .nodes
                    .iter()
                    .map(|n| crate::rapid::expr::ExprNode { lit: NONE, ..*n })
                    .collect();
                (nodes, lits, Some(p.tok))
            }
            Err(_) => (Vec::new(), Vec::new(), None),
        }
    }

    fn aggregate() -> impl Strategy<Value = String> {
        let leaf = prop_oneof![
            "-?[0-9]{1,5}(\\.[0-9]{0,4})?([eE][+-]?[0-9]{1,2})?",
            "[+-]?\\.[0-9]{1,3}",
            Just("9E+09".to_owned()),
            Just("- 5".to_owned()),
            Just("x".to_owned()),
            Just("1.5.2".to_owned()),
            Just("! c\n0".to_owned()),
            Just("0x1F".to_owned()),
        ];
        leaf.prop_recursive(4, 40, 6, |inner| {
            (
                proptest::collection::vec(inner, 0..6),
                "[ \\t\\r\\n]{0,2}",
                any::<bool>(),
            )
                .prop_map(|(items, ws, trailing)| {
                    let sep = format!(",{ws}");
                    let tail = if trailing && !items.is_empty() {
                        ","
                    } else {
                        ""
                    };
                    format!("[{ws}{}{tail}]", items.join(&sep))
                })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn fast_aggregate_path_builds_what_the_general_path_builds(a in aggregate()) {
            let src = format!("{a} ;");
            prop_assert_eq!(read(src.as_bytes(), true), read(src.as_bytes(), false));
        }
    }
}
