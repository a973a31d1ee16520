//! Expressions of one line: operators, postfix access, primaries and aggregates, over a
//! cursor of the line's significant tokens (`grammars/krl.ebnf`, section "expressions").

use super::*;

/// A cursor over the significant tokens of one line.
pub(super) struct Cursor<'a> {
    pub(super) src: &'a [u8],
    pub(super) toks: &'a [Token],
    pub(super) pos: usize,
    /// Where "end of statement" is, for messages.
    pub(super) eol: Span,
    /// Nesting of parentheses, aggregates and prefix operators: bounded so that a damaged
    /// file of ten thousand `(` cannot exhaust the stack.
    pub(super) depth: u32,
}

/// Deeper nesting than any real program writes (nested aggregates in `$config.dat` reach 3).
pub(super) const MAX_DEPTH: u32 = 200;

impl<'a> Cursor<'a> {
    pub(super) fn peek(&self) -> Option<&'a Token> {
        self.toks.get(self.pos)
    }

    pub(super) fn peek_at(&self, n: usize) -> Option<&'a Token> {
        self.toks.get(self.pos + n)
    }

    pub(super) fn bump(&mut self) -> Option<&'a Token> {
        let t = self.toks.get(self.pos);
        if t.is_some() {
            self.pos += 1;
        }
        t
    }

    pub(super) fn at_end(&self) -> bool {
        self.pos >= self.toks.len()
    }

    pub(super) fn here(&self) -> Span {
        self.peek().map_or(self.eol, |t| t.span())
    }

    pub(super) fn text(&self, t: &Token) -> String {
        crate::syntax::latin1(t.text(self.src))
    }

    pub(super) fn err<T>(&self, message: String, hint: &'static str) -> PResult<T> {
        Err(PErr {
            span: self.here(),
            message,
            hint,
        })
    }

    pub(super) fn found(&self) -> String {
        match self.peek() {
            Some(t) => format!("`{}`", self.text(t)),
            None => "end of line".to_owned(),
        }
    }

    pub(super) fn expect_punct(&mut self, p: &[u8], hint: &'static str) -> PResult<Span> {
        if is_punct(self.src, self.peek(), p) {
            Ok(self.bump().map(|t| t.span()).unwrap_or(self.eol))
        } else {
            self.err(
                format!(
                    "expected `{}`, found {}",
                    String::from_utf8_lossy(p),
                    self.found()
                ),
                hint,
            )
        }
    }

    pub(super) fn expect_ident(&mut self, what: &str, hint: &'static str) -> PResult<Span> {
        match self.peek() {
            Some(t) if t.kind == TokenKind::Ident => {
                self.pos += 1;
                Ok(t.span())
            }
            _ => self.err(format!("expected {what}, found {}", self.found()), hint),
        }
    }

    pub(super) fn expect_end(&self, after: &str) -> PResult<()> {
        if self.at_end() {
            Ok(())
        } else {
            self.err(
                format!("unexpected {} after {after}", self.found()),
                "one KRL statement per line; move the rest to its own line or comment it out with `;`",
            )
        }
    }

    pub(super) fn is_kw(&self, kw: &str) -> bool {
        is_kw(self.src, self.peek(), kw)
    }

    pub(super) fn is_punct(&self, p: &[u8]) -> bool {
        is_punct(self.src, self.peek(), p)
    }

    /// Rule `expr`: precedence climbing; `:` (geometric operator) binds tightest.
    pub(super) fn expr(&mut self) -> PResult<Expr> {
        if let Some(e) = self.simple_value() {
            return Ok(e);
        }
        self.binary(0)
    }

    /// The common case of a `.dat` field, a lone literal or name before `,` `}` `)` `]` or the
    /// end of the line, read without descending the precedence levels. Gives exactly what
    /// [`Self::binary`] gives for it (a sign written against a number is part of the number).
    pub(super) fn simple_value(&mut self) -> Option<Expr> {
        let t = self.peek()?;
        let (kind, span, used) = match t.kind {
            TokenKind::Number => (ExprKind::Number, t.span(), 1),
            TokenKind::Str => (ExprKind::Str, t.span(), 1),
            TokenKind::Quoted => (ExprKind::Quoted, t.span(), 1),
            TokenKind::Enum => (ExprKind::Enum, t.span(), 1),
            TokenKind::Ident => {
                let text = t.text(self.src);
                if text.eq_ignore_ascii_case(b"NOT") || text.eq_ignore_ascii_case(b"B_NOT") {
                    return None;
                }
                (ExprKind::Name, t.span(), 1)
            }
            TokenKind::Punct if matches!(t.text(self.src), b"-" | b"+") => {
                let n = self.peek_at(1)?;
                if n.kind != TokenKind::Number || n.start != t.end {
                    return None;
                }
                (ExprKind::Number, t.span().cover(n.span()), 2)
            }
            _ => return None,
        };
        let ends = match self.peek_at(used) {
            None => true,
            Some(f) => {
                f.kind == TokenKind::Punct && matches!(f.text(self.src), b"," | b"}" | b")" | b"]")
            }
        };
        if !ends {
            return None;
        }
        self.pos += used;
        Some(Expr { span, kind })
    }

    pub(super) fn binary_prec(&self) -> Option<u8> {
        let t = self.peek()?;
        match t.kind {
            TokenKind::Punct => match t.text(self.src) {
                b":" => Some(6),
                b"*" | b"/" => Some(5),
                b"+" | b"-" => Some(4),
                b"==" | b"<>" | b"<" | b">" | b"<=" | b">=" => Some(3),
                _ => None,
            },
            TokenKind::Ident => {
                let w = Word::of(t.text(self.src));
                match w.bytes() {
                    b"AND" | b"B_AND" => Some(2),
                    _ if w.is_in(BINARY_WORDS) => Some(1),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    /// Rules `expr` and `binop`, from operators of precedence `min` up.
    pub(super) fn binary(&mut self, min: u8) -> PResult<Expr> {
        let mut lhs = self.unary()?;
        while let Some(prec) = self.binary_prec() {
            if prec < min {
                break;
            }
            let op = self.bump().map(|t| t.span()).unwrap_or(self.eol);
            let rhs = self.binary(prec + 1)?;
            lhs = Expr {
                span: lhs.span.cover(rhs.span),
                kind: ExprKind::Binary(Box::new(lhs), op, Box::new(rhs)),
            };
        }
        Ok(lhs)
    }

    /// Rule `unary`. A sign written directly in front of a number is part of the literal.
    pub(super) fn unary(&mut self) -> PResult<Expr> {
        if self.depth >= MAX_DEPTH {
            return self.err(
                "expression nested too deeply".to_owned(),
                "simplify the expression; check for a damaged line",
            );
        }
        self.depth += 1;
        let e = self.unary_inner();
        self.depth -= 1;
        e
    }

    pub(super) fn unary_inner(&mut self) -> PResult<Expr> {
        let sign = self.is_punct(b"-") || self.is_punct(b"+");
        if sign || self.is_kw("NOT") || self.is_kw("B_NOT") {
            let op = self.bump().map(|t| t.span()).unwrap_or(self.eol);
            let inner = self.unary()?;
            if sign && inner.kind == ExprKind::Number && inner.span.start == op.end {
                return Ok(Expr {
                    span: op.cover(inner.span),
                    kind: ExprKind::Number,
                });
            }
            return Ok(Expr {
                span: op.cover(inner.span),
                kind: ExprKind::Unary(op, Box::new(inner)),
            });
        }
        self.postfix()
    }

    /// Rule `postfix`: indexing, calls and member access.
    pub(super) fn postfix(&mut self) -> PResult<Expr> {
        let mut e = self.primary()?;
        loop {
            if self.is_punct(b"[") {
                self.pos += 1;
                let args = self.list(b"]")?;
                let close = self.expect_punct(b"]", "close the index with `]`")?;
                e = Expr {
                    span: e.span.cover(close),
                    kind: ExprKind::Index(Box::new(e), args),
                };
            } else if self.is_punct(b"(") {
                self.pos += 1;
                let args = self.list(b")")?;
                let close = self.expect_punct(b")", "close the argument list with `)`")?;
                e = Expr {
                    span: e.span.cover(close),
                    kind: ExprKind::Call(Box::new(e), args),
                };
            } else if self.is_punct(b".") {
                self.pos += 1;
                let field = self.expect_ident("a field name after `.`", "write `name.field`")?;
                e = Expr {
                    span: e.span.cover(field),
                    kind: ExprKind::Member(Box::new(e), field),
                };
            } else {
                return Ok(e);
            }
        }
    }

    /// Rule `list`: comma-separated, entries may be empty (`TOOL_NAME[1,]`, `F()`).
    pub(super) fn list(&mut self, close: &[u8]) -> PResult<Vec<Option<Expr>>> {
        let mut out = Vec::new();
        if self.is_punct(close) {
            return Ok(out);
        }
        loop {
            if self.is_punct(b",") || self.is_punct(close) {
                out.push(None);
            } else {
                out.push(Some(self.expr()?));
            }
            if self.is_punct(b",") {
                self.pos += 1;
            } else {
                return Ok(out);
            }
        }
    }

    /// Rule `primary`.
    pub(super) fn primary(&mut self) -> PResult<Expr> {
        let Some(t) = self.peek() else {
            return self.err(
                "expected a value, found end of line".to_owned(),
                "complete the expression",
            );
        };
        let kind = match t.kind {
            TokenKind::Number => ExprKind::Number,
            TokenKind::Str => ExprKind::Str,
            TokenKind::Quoted => ExprKind::Quoted,
            TokenKind::Enum => ExprKind::Enum,
            // `# State`: KSS accepts blanks between `#` and the enum value's name.
            TokenKind::Punct
                if t.text(self.src) == b"#"
                    && self.peek_at(1).is_some_and(|n| n.kind == TokenKind::Ident) =>
            {
                let name = self.peek_at(1).map_or(t.span(), |n| n.span());
                self.pos += 2;
                return Ok(Expr {
                    span: t.span().cover(name),
                    kind: ExprKind::Enum,
                });
            }
            TokenKind::Ident => ExprKind::Name,
            TokenKind::Punct if t.text(self.src) == b"{" => return self.aggregate(),
            TokenKind::Punct if t.text(self.src) == b"(" => {
                self.pos += 1;
                let inner = self.expr()?;
                let close = self.expect_punct(b")", "close the parenthesis")?;
                return Ok(Expr {
                    span: t.span().cover(close),
                    kind: ExprKind::Paren(Box::new(inner)),
                });
            }
            TokenKind::Unterminated => {
                return self.err(
                    "string without its closing quote".to_owned(),
                    "close the string on the same line",
                );
            }
            _ => {
                return self.err(
                    format!("expected a value, found {}", self.found()),
                    "write a number, a name, a string or a `{…}` aggregate here",
                );
            }
        };
        self.pos += 1;
        Ok(Expr {
            span: t.span(),
            kind,
        })
    }

    /// Rules `aggregate` and `field`: `{ [TYPE :] field {, field} }`.
    pub(super) fn aggregate(&mut self) -> PResult<Expr> {
        let open = self.bump().map(|t| t.span()).unwrap_or(self.eol);
        let mut type_name = None;
        if self.peek().is_some_and(|t| t.kind == TokenKind::Ident)
            && is_punct(self.src, self.peek_at(1), b":")
        {
            type_name = self.peek().map(|t| t.span());
            self.pos += 2;
        }
        // One allocation per aggregate: the commas left on the line bound its field count
        // (a `.dat` line is one aggregate of up to 14 fields, nested ones are short).
        let commas = self
            .toks
            .get(self.pos..)
            .unwrap_or(&[])
            .iter()
            .filter(|t| t.kind == TokenKind::Punct && t.text(self.src) == b",")
            .count();
        let mut fields = Vec::with_capacity((commas + 1).min(16));
        if !self.is_punct(b"}") {
            loop {
                let name = self.expect_ident(
                    "a field name",
                    "aggregates are written `{NAME value, NAME value}`",
                )?;
                // Char-array fields: `POINT2[] " "`.
                if self.is_punct(b"[") && is_punct(self.src, self.peek_at(1), b"]") {
                    self.pos += 2;
                }
                let value = self.expr()?;
                fields.push(Field { name, value });
                if self.is_punct(b",") {
                    self.pos += 1;
                } else {
                    break;
                }
            }
        }
        let close = self.expect_punct(
            b"}",
            "separate fields with `,` and close the aggregate with `}` on the same line",
        )?;
        Ok(Expr {
            span: open.cover(close),
            kind: ExprKind::Aggregate(Aggregate { type_name, fields }),
        })
    }
}
