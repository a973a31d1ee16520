//! Statements: what a line holds, routines and blocks, declarations and motions
//! (`grammars/krl.ebnf`, sections "lines" to "statements").

use super::*;

impl LineParser<'_, '_> {
    /// Rule `statement`, with rules `routine_end`, `other_decl`, `simple`, `block_open`,
    /// `block_middle` and `block_close`. Returns the line's node kind.
    pub(super) fn statement(&mut self, sig: &[Token], eol: Span) -> NodeKind {
        let stmt_span = match (sig.first(), sig.last()) {
            (Some(f), Some(l)) => f.span().cover(l.span()),
            _ => eol,
        };
        if let Some(bad) = sig
            .iter()
            .find(|t| matches!(t.kind, TokenKind::Unknown | TokenKind::Unterminated))
        {
            let (message, hint) = if bad.kind == TokenKind::Unknown {
                (
                    "bytes outside the KRL character set in code",
                    "non-ASCII text belongs in a `;` comment or a string",
                )
            } else {
                (
                    "string without its closing quote",
                    "close the string on the same line",
                )
            };
            let e = PErr {
                span: bad.span(),
                message: message.to_owned(),
                hint,
            };
            return self.error(e);
        }
        let Some(first) = sig.first() else {
            return NodeKind::Blank;
        };
        if first.kind == TokenKind::Header {
            return NodeKind::Header;
        }
        if first.kind != TokenKind::Ident {
            let what = format!(
                "starting with `{}`",
                crate::syntax::latin1(first.text(self.src))
            );
            return self.unknown(stmt_span, what);
        }
        let mut c = self.cursor(sig, eol);
        let global = c.is_kw("GLOBAL");
        if global {
            c.pos += 1;
        }
        let Some(head) = c.peek() else {
            let e = PErr {
                span: eol,
                message: "`GLOBAL` without a declaration".to_owned(),
                hint: "write `GLOBAL DEF`, `GLOBAL DEFFCT` or `GLOBAL DECL`",
            };
            return self.error(e);
        };
        let word = Word::of(head.text(self.src));
        let result: Result<(NodeKind, Option<StmtKind>), PErr> = match word.bytes() {
            b"DEF" | b"DEFFCT" | b"DEFDAT" => self
                .routine(&mut c, word.as_str(), head.span())
                .map(|(node, k)| (node, k.map(|k| k.made_global(global)))),
            b"END" | b"ENDFCT" | b"ENDDAT" if !global => {
                let w = word.as_str();
                c.pos += 1;
                c.expect_end(w).map(|()| {
                    self.close(w, head.span());
                    (NodeKind::RoutineEnd, None)
                })
            }
            b"DECL" => {
                c.pos += 1;
                let mut global = global;
                while c.is_kw("GLOBAL") || c.is_kw("CONST") {
                    global |= c.is_kw("GLOBAL");
                    c.pos += 1;
                }
                if c.is_kw("INTERRUPT") {
                    Ok((NodeKind::Simple, Some(StmtKind::Handler)))
                } else if c.is_kw("STRUC") || c.is_kw("ENUM") || c.is_kw("SIGNAL") {
                    Ok((NodeKind::Declaration, None))
                } else {
                    decl(&mut c).map(|k| (NodeKind::Declaration, Some(k.made_global(global))))
                }
            }
            b"INTERRUPT" | b"TRIGGER" => Ok((NodeKind::Simple, Some(StmtKind::Handler))),
            _ if word.is_in(DECL_KEYWORDS) => Ok((NodeKind::Declaration, None)),
            // `GLOBAL INT x = 10`: a predefined type may omit `DECL` after `GLOBAL` too.
            _ if global && word.is_in(PREDEFINED_TYPES) => {
                decl(&mut c).map(|k| (NodeKind::Declaration, Some(k.made_global(true))))
            }
            _ if global => Err(PErr {
                span: head.span(),
                message: format!("`GLOBAL` before `{}`", c.text(head)),
                hint: "`GLOBAL` only qualifies DEF, DEFFCT, DECL, STRUC, ENUM, SIGNAL and INTERRUPT",
            }),
            _ if word.is_in(MOTION_KEYWORDS) => motion(&mut c).map(|k| (NodeKind::Motion, Some(k))),
            // `EXIT` leaves the innermost loop: program order goes on after it.
            b"EXIT" => Ok((NodeKind::Simple, Some(StmtKind::Branch(head.span())))),
            b"GOTO" => Ok((NodeKind::Simple, Some(StmtKind::Goto))),
            b"RETURN" => Ok((NodeKind::Simple, Some(StmtKind::Return))),
            _ if word.is_in(SIMPLE_KEYWORDS) => Ok((NodeKind::Simple, None)),
            b"IF" => {
                let has_then = sig.last().is_some_and(|t| is_kw(self.src, Some(t), "THEN"));
                if has_then {
                    self.push_open("IF", head.span(), NodeKind::Block);
                    Ok((NodeKind::BlockOpen, Some(StmtKind::Branch(head.span()))))
                } else {
                    Err(PErr {
                        span: eol,
                        message: "`IF` without `THEN`".to_owned(),
                        hint: "write `IF condition THEN` on one line",
                    })
                }
            }
            b"FOR" | b"WHILE" | b"LOOP" | b"REPEAT" | b"SWITCH" | b"SPLINE" | b"PTP_SPLINE" => {
                let w = word.as_str();
                if let Some(k) = static_kw(w) {
                    self.push_open(k, head.span(), NodeKind::Block);
                }
                // A spline block is one motion, not a change of program order; its `WITH`
                // settings hold for every motion in it.
                if w.ends_with("SPLINE") {
                    c.pos += 1;
                    let with = if c.is_kw("WITH") {
                        c.pos += 1;
                        with_list(&mut c)
                    } else {
                        Ok(Vec::new())
                    };
                    with.map(|with| (NodeKind::BlockOpen, Some(StmtKind::SplineBlock { with })))
                } else {
                    Ok((NodeKind::BlockOpen, Some(StmtKind::Branch(head.span()))))
                }
            }
            b"ELSE" | b"CASE" | b"DEFAULT" => {
                let w = word.as_str();
                let parent = if w == "ELSE" { "IF" } else { "SWITCH" };
                if self.stack.last().is_some_and(|o| o.keyword == parent) {
                    Ok((NodeKind::BlockMiddle, Some(StmtKind::Branch(head.span()))))
                } else {
                    Err(PErr {
                        span: head.span(),
                        message: format!("`{w}` outside `{parent}`"),
                        hint: "check the block structure above this line",
                    })
                }
            }
            b"ENDIF" | b"ENDFOR" | b"ENDWHILE" | b"ENDLOOP" | b"UNTIL" | b"ENDSWITCH"
            | b"ENDSPLINE" => {
                let w = word.as_str();
                let matched = self.stack.iter().any(|o| closer_of(o.keyword) == w);
                self.close(w, head.span());
                let stmt = match (matched, w == "ENDSPLINE") {
                    (true, true) => Some(StmtKind::EndSpline),
                    (true, false) => Some(StmtKind::Branch(head.span())),
                    (false, _) => None,
                };
                Ok((NodeKind::BlockClose, stmt))
            }
            _ => self.other(&mut c, head, stmt_span),
        };
        match result {
            Ok((kind, stmt)) => {
                if let Some(kind) = stmt {
                    // The line's leaf comes next, after any branch this line opened.
                    let node = self.tree.len() as u32;
                    self.sink.accept(Stmt {
                        node,
                        span: stmt_span,
                        kind,
                    });
                }
                kind
            }
            Err(e) => self.error(e),
        }
    }

    /// Rule `routine`: `DEF name(params)`, `DEFFCT type name(params)`, `DEFDAT name [PUBLIC]`.
    pub(super) fn routine(
        &mut self,
        c: &mut Cursor<'_>,
        w: &str,
        keyword: Span,
    ) -> PResult<(NodeKind, Option<StmtKind>)> {
        c.pos += 1;
        if w == "DEFFCT" {
            c.expect_ident(
                "the function's return type",
                "write `DEFFCT TYPE name(params)`",
            )?;
            // An array return type: `DEFFCT CHAR[128] NAME( )`.
            if c.is_punct(b"[") {
                c.pos += 1;
                c.list(b"]")?;
                c.expect_punct(b"]", "close the return type's array size with `]`")?;
            }
        }
        let name = c.expect_ident("a name", "write `DEF name()`")?;
        // Parameters and `PUBLIC` are kept as written.
        if !self.stack.is_empty() {
            let open: Vec<Open> = std::mem::take(&mut self.stack);
            for o in open {
                self.tree.close(o.node);
                self.out.diagnostics.push(
                    Diagnostic::error(o.span, format!("`{}` is never closed", o.keyword))
                        .with_hint(format!(
                            "add `{}` before the next routine",
                            closer_of(o.keyword)
                        )),
                );
            }
        }
        if let Some(k) = static_kw(w) {
            self.push_open(k, keyword, NodeKind::Routine);
        }
        Ok((
            NodeKind::RoutineStart,
            Some(StmtKind::Routine {
                keyword,
                name: Some(name),
                global: false,
            }),
        ))
    }

    /// Opens a block or routine branch at the current line.
    pub(super) fn push_open(&mut self, keyword: &'static str, span: Span, kind: NodeKind) {
        let node = self.tree.open(kind, self.line_start);
        self.stack.push(Open {
            keyword,
            span,
            node,
        });
    }

    /// Pops the block `closer` closes (its branch ends after this line); reports a closer
    /// without its opener.
    pub(super) fn close(&mut self, closer: &str, span: Span) {
        if let Some(at) = self
            .stack
            .iter()
            .rposition(|o| closer_of(o.keyword) == closer)
        {
            for o in self.stack.drain(at + 1..).collect::<Vec<_>>() {
                self.tree.close(o.node);
                self.out.diagnostics.push(
                    Diagnostic::error(o.span, format!("`{}` is never closed", o.keyword))
                        .with_hint(format!("add `{}` before `{closer}`", closer_of(o.keyword))),
                );
            }
            self.close_after_line = self.stack.get(at).map(|o| o.node);
            self.stack.truncate(at);
        } else {
            self.out.diagnostics.push(
                Diagnostic::error(span, format!("`{closer}` without an open block"))
                    .with_hint("remove it or add the statement that opens the block"),
            );
        }
    }

    /// Rules `assignment`, `call`, `label` and `decl_statement` without `DECL`; else `opaque`.
    pub(super) fn other(
        &mut self,
        c: &mut Cursor<'_>,
        head: &Token,
        stmt_span: Span,
    ) -> PResult<(NodeKind, Option<StmtKind>)> {
        let next = c.peek_at(1);
        let src = self.src;
        if next.is_none() {
            let what = format!("`{}`", c.text(head));
            return Ok((self.unknown(stmt_span, what), None));
        }
        if is_punct(src, next, b":") && c.peek_at(2).is_none() {
            return Ok((NodeKind::Label, Some(StmtKind::Label)));
        }
        if next.is_some_and(|t| t.kind == TokenKind::Ident) {
            let ty = Word::of(head.text(src));
            let k = decl(c)?;
            // KRL lets `DECL` be omitted for predefined types only; a misspelt keyword
            // (`LIX XP1`) would otherwise pass silently as a declaration.
            if !ty.is_in(PREDEFINED_TYPES) {
                self.out.diagnostics.push(
                    Diagnostic::warning(
                        head.span(),
                        format!("`{}` is not a statement or a predefined type", c.text(head)),
                    )
                    .with_hint("write `DECL TYPE name` for a user-defined type, or check the keyword's spelling"),
                );
            }
            return Ok((NodeKind::Declaration, Some(k)));
        }
        if is_punct(src, next, b"=") || is_punct(src, next, b"[") || is_punct(src, next, b".") {
            let target = c.postfix()?;
            if c.is_punct(b"=") {
                c.pos += 1;
                let value = c.expr()?;
                c.expect_end("the assigned value")?;
                return Ok((
                    NodeKind::Assignment,
                    Some(StmtKind::Assign { target, value }),
                ));
            }
            if matches!(target.kind, ExprKind::Call(..)) {
                c.expect_end("the call")?;
                return Ok((NodeKind::Call, Some(StmtKind::Call(target))));
            }
            return c.err(
                format!("expected `=`, found {}", c.found()),
                "write `name = value`",
            );
        }
        if is_punct(src, next, b"(") {
            let call = c.postfix()?;
            if c.is_punct(b"=") {
                c.pos += 1;
                let value = c.expr()?;
                c.expect_end("the assigned value")?;
                return Ok((
                    NodeKind::Assignment,
                    Some(StmtKind::Assign {
                        target: call,
                        value,
                    }),
                ));
            }
            c.expect_end("the call")?;
            return Ok((NodeKind::Call, Some(StmtKind::Call(call))));
        }
        let what = format!("`{}`", c.text(head));
        Ok((self.unknown(stmt_span, what), None))
    }
}

/// Rules `decl_statement`, `decl` and `var`: `type name [dims] [= value] {, name [dims]
/// [= value]}` (after `DECL`).
fn decl(c: &mut Cursor<'_>) -> PResult<StmtKind> {
    let type_name = c.expect_ident("a data type", "write `DECL TYPE name`")?;
    let mut vars = Vec::new();
    loop {
        let name = c.expect_ident("a variable name", "write `DECL TYPE name`")?;
        let mut dims = Vec::new();
        if c.is_punct(b"[") {
            c.pos += 1;
            dims = c.list(b"]")?;
            c.expect_punct(b"]", "close the array size with `]`")?;
        }
        let init = if c.is_punct(b"=") {
            c.pos += 1;
            Some(c.expr()?)
        } else {
            None
        };
        vars.push(DeclVar { name, dims, init });
        if c.is_punct(b",") {
            c.pos += 1;
        } else {
            break;
        }
    }
    c.expect_end("the declaration")?;
    Ok(StmtKind::Decl {
        type_name,
        vars,
        global: false,
    })
}

/// Rule `with`: the assignments after `WITH`, up to the end of the list.
fn with_list(c: &mut Cursor<'_>) -> PResult<Vec<(Expr, Expr)>> {
    let mut with = Vec::new();
    loop {
        let lhs = c.postfix()?;
        c.expect_punct(b"=", "write `WITH $VAR = value, …`")?;
        let rhs = c.expr()?;
        with.push((lhs, rhs));
        if c.is_punct(b",") {
            c.pos += 1;
        } else {
            return Ok(with);
        }
    }
}

/// Rule `motion`: `KEYWORD target`, `CIRC aux, target [, CA angle]`, then approximation
/// (`C_DIS` …), enums (`#TOOL`) and `WITH` assignments; rules `motion_kw`, `circ_rest`,
/// `approximation` and `with`.
fn motion(c: &mut Cursor<'_>) -> PResult<StmtKind> {
    let keyword = c.bump().map(|t| t.span()).unwrap_or(c.eol);
    let kw = Word::of(keyword.slice(c.src));
    let circ = kw.bytes().windows(4).any(|w| w == b"CIRC");
    let mut targets = vec![c.expr()?];
    if circ {
        c.expect_punct(
            b",",
            "a circular motion takes an auxiliary point and a target",
        )?;
        targets.push(c.expr()?);
        if c.is_punct(b",") {
            c.pos += 1;
            if c.is_kw("CA") {
                c.pos += 1;
                c.expr()?;
            } else {
                return c.err(
                    format!("expected `CA`, found {}", c.found()),
                    "write `CIRC aux, target, CA angle`",
                );
            }
        }
    }
    let mut with = Vec::new();
    while let Some(t) = c.peek() {
        let word = Word::of(t.text(c.src));
        if (t.kind == TokenKind::Ident && word.is_in(APPROXIMATION)) || t.kind == TokenKind::Enum {
            c.pos += 1;
        } else if t.kind == TokenKind::Ident && word.is("WITH") {
            c.pos += 1;
            with.extend(with_list(c)?);
        } else {
            return c.err(
                format!("unexpected {} in a motion statement", c.found()),
                "after the target, KRL expects C_DIS/C_PTP/C_VEL/C_ORI/C_SPL or WITH",
            );
        }
    }
    Ok(StmtKind::Motion {
        keyword,
        targets,
        with,
    })
}
