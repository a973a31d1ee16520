//! Statements: simple statements, calls and their arguments, and the compound statements
//! `IF`, `FOR`, `WHILE`, `TEST` (`grammars/rapid.ebnf`, section "statements").

use super::*;

impl Parser<'_, '_> {
    /// `statements = { statement }`, up to one of `ends` or a keyword that closes an outer block.
    pub(super) fn statements(&mut self, ends: &[&[u8]]) {
        loop {
            if self.tok.kind == TokenKind::Eof || self.at_any(ends) || self.at_any(HARD_ENDS) {
                return;
            }
            // A local data declaration is allowed at the start of a routine body.
            if self.at_any(&[b"CONST", b"PERS", b"VAR"]) {
                let start = self.tok.start;
                self.arena.clear();
                self.data_decl(start, false);
                continue;
            }
            self.statement();
        }
    }

    /// `statement = if | for | while | test | label | jump | late_call | assignment
    ///             | call | placeholder`
    pub(super) fn statement(&mut self) {
        let start = self.tok.start;
        self.arena.clear();
        if self.depth > MAX_DEPTH {
            let e = self.error("less deeply nested blocks");
            self.recover(start, e);
            return;
        }
        self.depth += 1;
        if self.at_kw(b"IF") {
            self.if_stmt(start);
        } else if self.at_kw(b"FOR") {
            self.for_stmt(start);
        } else if self.at_kw(b"WHILE") {
            self.while_stmt(start);
        } else if self.at_kw(b"TEST") {
            self.test_stmt(start);
        } else {
            match self.simple_statement() {
                Ok((kind, stmt)) => {
                    self.leaf(kind, start);
                    self.emit(stmt, start);
                }
                Err(e) => self.recover(start, e),
            }
        }
        self.depth -= 1;
    }

    /// `simple = jump | label | placeholder | late_call | assignment | call` (one leaf), with
    /// rules `jump`, `label`, `assignment` and `call`.
    pub(super) fn simple_statement(&mut self) -> PResult<(NodeKind, Stmt)> {
        let t = self.tok;
        if t.kind == TokenKind::Placeholder {
            self.bump();
            self.eat_punct(b';');
            return Ok((NodeKind::Placeholder, Stmt::Other));
        }
        if self.at_punct(b'%') {
            return self.late_call();
        }
        if t.kind != TokenKind::Ident {
            return Err(self.error("a statement"));
        }
        if self.at_any(&[b"GOTO"]) {
            self.bump();
            self.expect_ident("a label after GOTO")?;
            self.expect_punct(b';', "`;` after GOTO label")?;
            return Ok((NodeKind::Jump, Stmt::Other));
        }
        if self.at_any(&[b"RETURN", b"RAISE"]) {
            self.bump();
            if !self.at_punct(b';') {
                self.expr()?;
            }
            self.expect_punct(b';', "`;` at the end of the statement")?;
            return Ok((NodeKind::Jump, Stmt::Other));
        }
        if self.at_any(&[b"EXIT", b"RETRY", b"TRYNEXT"]) {
            self.bump();
            self.expect_punct(b';', "`;` at the end of the statement")?;
            return Ok((NodeKind::Jump, Stmt::Other));
        }
        if self.at_kw(b"CONNECT") {
            self.bump();
            self.expr()?;
            self.expect_kw(b"WITH", "WITH after CONNECT's interrupt variable")?;
            self.expect_ident("a trap routine name after WITH")?;
            self.expect_punct(b';', "`;` at the end of the statement")?;
            return Ok((NodeKind::Jump, Stmt::Other));
        }
        if self.is_reserved(t) {
            return Err(self.error("a statement"));
        }
        // `label:` — a colon, not `:=`.
        if self.peek2().punct(self.src) == b':' {
            self.bump();
            self.bump();
            return Ok((NodeKind::Label, Stmt::Other));
        }
        // `Hand_MoveTo(10);`, `TPWrite("a"+b);`: a routine call whose first argument is a
        // parenthesised expression (seen in real programs); a call result is never assigned to.
        if self.peek2().punct(self.src) == b'(' {
            self.bump();
            let args = self.call_args(t.end)?;
            return Ok((
                NodeKind::Call,
                Stmt::Call {
                    name: t.span(),
                    args,
                },
            ));
        }
        let target = self.postfix()?;
        if self.tok.kind == TokenKind::Assign {
            self.bump();
            let value = self.expr()?;
            self.expect_punct(b';', "`;` at the end of the assignment")?;
            let target = self.arena.get(target).map_or(t.span(), |n| n.span());
            return Ok((NodeKind::Assign, Stmt::Assign { target, value }));
        }
        if self.arena.get(target).map(|n| n.kind) != Some(ExprKind::Ident) {
            return Err(self.error("`:=` in the assignment"));
        }
        let args = self.call_args(t.end)?;
        Ok((
            NodeKind::Call,
            Stmt::Call {
                name: t.span(),
                args,
            },
        ))
    }

    /// `late_call = "%" expr "%" call_args ";"`
    pub(super) fn late_call(&mut self) -> PResult<(NodeKind, Stmt)> {
        let open = self.bump();
        let late = self.arena.open(ExprKind::Late, open.start);
        let inner = self.expr()?;
        self.arena.link(late, NONE, inner);
        let close = self.expect_punct(b'%', "`%` closing the late-binding routine name")?;
        self.arena.close(late, close.end);
        let args = self.call_args(close.end)?;
        Ok((
            NodeKind::LateCall,
            Stmt::Call {
                name: Span::new(open.start as usize, close.end as usize),
                args,
            },
        ))
    }

    /// `call_args = [ arg { [ "," ] arg } ] ";"` — a comma before a `\switch` is optional.
    pub(super) fn call_args(&mut self, start: u32) -> PResult<u32> {
        let args = self.arena.open(ExprKind::Args, start);
        let mut last = NONE;
        let mut first = true;
        loop {
            if self.at_punct(b';') {
                let end = self.bump().end;
                self.arena.close(args, end);
                return Ok(args);
            }
            if !first && !self.eat_punct(b',') && !self.at_punct(b'\\') {
                return Err(self.error("`,` or `;` after the argument"));
            }
            first = false;
            let a = self.arg()?;
            self.arena.link(args, last, a);
            last = a;
        }
    }

    /// `arg = "\" ident [ ( ":=" | "?" ) expr ] | [ ident ":=" ] expr`
    pub(super) fn arg(&mut self) -> PResult<u32> {
        let start = self.tok.start;
        let a = self.arena.open(ExprKind::Arg, start);
        if self.eat_punct(b'\\') {
            let name = self.expect_ident("an optional argument name after `\\`")?;
            if let Some(n) = self.arena.set_mut(a) {
                n.switch = true;
                n.name_start = name.start;
                n.name_end = name.end;
            }
            if self.tok.kind == TokenKind::Assign || self.at_punct(b'?') {
                self.bump();
                let v = self.expr()?;
                self.arena.link(a, NONE, v);
            }
        } else {
            if self.tok.kind == TokenKind::Ident && self.peek2().kind == TokenKind::Assign {
                let name = self.bump();
                self.bump();
                if let Some(n) = self.arena.set_mut(a) {
                    n.name_start = name.start;
                    n.name_end = name.end;
                }
            }
            let v = self.expr()?;
            self.arena.link(a, NONE, v);
        }
        self.arena.close(a, self.prev_end);
        Ok(a)
    }

    /// `if = "IF" expr ( "THEN" statements { "ELSEIF" expr "THEN" statements }
    ///       [ "ELSE" statements ] "ENDIF" | simple )`
    pub(super) fn if_stmt(&mut self, start: u32) {
        let if_tok = self.tok;
        let head: PResult<bool> = (|| {
            self.bump();
            self.expr()?;
            if self.at_kw(b"THEN") {
                self.bump();
                Ok(true)
            } else {
                Ok(false)
            }
        })();
        match head {
            Ok(true) => {
                let branch = self.open(NodeKind::If, start);
                self.leaf(NodeKind::IfPart, start);
                self.emit(Stmt::Other, start);
                self.block_body(&[b"ELSEIF", b"ELSE", b"ENDIF"]);
                loop {
                    let s = self.tok.start;
                    self.arena.clear();
                    if self.at_kw(b"ELSEIF") {
                        self.bump();
                        let cond: PResult<()> = (|| {
                            self.expr()?;
                            self.expect_kw(b"THEN", "THEN after the ELSEIF condition")?;
                            Ok(())
                        })();
                        self.close_part(cond, NodeKind::IfPart, s);
                        self.block_body(&[b"ELSEIF", b"ELSE", b"ENDIF"]);
                    } else if self.at_kw(b"ELSE") {
                        self.bump();
                        self.leaf(NodeKind::IfPart, s);
                        self.block_body(&[b"ENDIF"]);
                    } else {
                        break;
                    }
                }
                self.block_end(b"ENDIF", if_tok);
                self.close(branch);
            }
            Ok(false) => {
                // Compact IF: one simple statement follows the condition.
                let branch = self.open(NodeKind::CompactIf, start);
                self.leaf(NodeKind::CompactIfHead, start);
                self.emit(Stmt::Other, start);
                let s = self.tok.start;
                self.arena.clear();
                match self.simple_statement() {
                    Ok((kind, stmt)) => {
                        self.leaf(kind, s);
                        self.emit(stmt, s);
                    }
                    Err(e) => self.recover(s, e),
                }
                self.close(branch);
            }
            Err(e) => self.recover(start, e),
        }
    }

    pub(super) fn block_body(&mut self, ends: &[&[u8]]) {
        self.statements(ends);
    }

    /// The closing keyword of a block, or a located error naming the block's opening keyword.
    pub(super) fn block_end(&mut self, end_kw: &'static [u8], opener: Token) {
        if self.at_kw(end_kw) {
            let s = self.tok.start;
            self.bump();
            let kind = match end_kw {
                b"ENDFOR" => NodeKind::ForPart,
                b"ENDWHILE" => NodeKind::WhilePart,
                b"ENDTEST" => NodeKind::TestPart,
                _ => NodeKind::IfPart,
            };
            self.leaf(kind, s);
        } else {
            let found = self.describe(self.tok);
            self.diagnostics.push(
                Diagnostic::error(
                    opener.span(),
                    format!(
                        "{} without {} (found {found})",
                        crate::syntax::latin1(self.text(opener)),
                        String::from_utf8_lossy(end_kw)
                    ),
                )
                .with_hint(format!(
                    "add {} to close the block",
                    String::from_utf8_lossy(end_kw)
                )),
            );
        }
    }

    /// `for = "FOR" ident "FROM" expr "TO" expr [ "STEP" expr ] "DO" statements "ENDFOR"`
    pub(super) fn for_stmt(&mut self, start: u32) {
        let opener = self.tok;
        let head: PResult<()> = (|| {
            self.bump();
            self.expect_ident("a loop variable after FOR")?;
            self.expect_kw(b"FROM", "FROM after the loop variable")?;
            self.expr()?;
            self.expect_kw(b"TO", "TO in the FOR head")?;
            self.expr()?;
            if self.at_kw(b"STEP") {
                self.bump();
                self.expr()?;
            }
            self.expect_kw(b"DO", "DO at the end of the FOR head")?;
            Ok(())
        })();
        self.loop_rest(
            start,
            opener,
            head,
            NodeKind::For,
            NodeKind::ForPart,
            b"ENDFOR",
        );
    }

    /// `while = "WHILE" expr "DO" statements "ENDWHILE"`
    pub(super) fn while_stmt(&mut self, start: u32) {
        let opener = self.tok;
        let head: PResult<()> = (|| {
            self.bump();
            self.expr()?;
            self.expect_kw(b"DO", "DO after the WHILE condition")?;
            Ok(())
        })();
        self.loop_rest(
            start,
            opener,
            head,
            NodeKind::While,
            NodeKind::WhilePart,
            b"ENDWHILE",
        );
    }

    pub(super) fn loop_rest(
        &mut self,
        start: u32,
        opener: Token,
        head: PResult<()>,
        kind: NodeKind,
        part: NodeKind,
        end_kw: &'static [u8],
    ) {
        match head {
            Ok(()) => {
                let branch = self.open(kind, start);
                self.leaf(part, start);
                self.emit(Stmt::Other, start);
                self.block_body(&[end_kw]);
                self.block_end(end_kw, opener);
                self.close(branch);
            }
            Err(e) => self.recover(start, e),
        }
    }

    /// `test = "TEST" expr { "CASE" expr { "," expr } ":" statements }
    ///         [ "DEFAULT" ":" statements ] "ENDTEST"`
    pub(super) fn test_stmt(&mut self, start: u32) {
        let opener = self.tok;
        let head: PResult<()> = (|| {
            self.bump();
            self.expr()?;
            Ok(())
        })();
        if let Err(e) = head {
            self.recover(start, e);
            return;
        }
        let branch = self.open(NodeKind::Test, start);
        self.leaf(NodeKind::TestPart, start);
        self.emit(Stmt::Other, start);
        loop {
            let s = self.tok.start;
            self.arena.clear();
            if self.at_kw(b"CASE") {
                let head: PResult<()> = (|| {
                    self.bump();
                    loop {
                        self.expr()?;
                        if !self.eat_punct(b',') {
                            break;
                        }
                    }
                    self.expect_punct(b':', "`:` after the CASE values")?;
                    Ok(())
                })();
                self.close_part(head, NodeKind::TestPart, s);
                self.block_body(&[b"CASE", b"DEFAULT", b"ENDTEST"]);
            } else if self.at_kw(b"DEFAULT") {
                self.bump();
                match self.expect_punct(b':', "`:` after DEFAULT") {
                    Ok(_) => self.leaf(NodeKind::TestPart, s),
                    Err(e) => self.recover(s, e),
                }
                self.block_body(&[b"CASE", b"DEFAULT", b"ENDTEST"]);
            } else {
                break;
            }
        }
        self.block_end(b"ENDTEST", opener);
        self.close(branch);
    }
}
