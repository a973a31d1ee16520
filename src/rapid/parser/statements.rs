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
        self.first = self.tok;
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
        // `MoveL p10, v1000, z10, tGun\WObj:=wCar;`: a name, then a name, a switch or the
        // `;`, is a call (not a label, an assignment or an access); its arguments are read
        // from the bytes when they are plain names, with no token lexed (a call's first
        // argument was lexed here only for the fast path to read it again).
        if self.fast_paths && !t.keyword {
            let after = blanks_end(self.src, t.end as usize);
            match self.src.get(after) {
                Some(b'a'..=b'z' | b'A'..=b'Z' | b'_' | b'\\' | b';')
                    if self.call_like_last(t) || self.plain_args_from(after) =>
                {
                    self.last_call = Some(Span::new(t.start as usize, self.prev_end as usize));
                    let call = Stmt::Call {
                        name: t.span(),
                        args: NONE,
                    };
                    return Ok((NodeKind::Call, call));
                }
                // `MoveL [[1520.3,-850.1,612.4],[0,0.707107,0.707107,0],…],v1000,…;`: the
                // target written inline, as generated programs write every motion. No call
                // is read as this one: the literal's numbers are no names to put in place.
                Some(b'[') if self.literal_call_args(after) => {
                    // Every test run holds the fast path to the general one, and hands the
                    // extractor the general path's arguments to compare with.
                    #[cfg(debug_assertions)]
                    let args = self.literal_call_read_again(t, after);
                    #[cfg(not(debug_assertions))]
                    let args = NONE;
                    self.call_literal = true;
                    return Ok((
                        NodeKind::Call,
                        Stmt::Call {
                            name: t.span(),
                            args,
                        },
                    ));
                }
                _ => {}
            }
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
    ///
    /// [`NONE`] when [`Parser::plain_args_from`] read them (into [`Parser::plain`], not the arena).
    pub(super) fn call_args(&mut self, start: u32) -> PResult<u32> {
        if self.fast_paths {
            if self.plain_args_from(self.tok.start as usize) {
                return Ok(NONE);
            }
            if let Some(args) = self.plain_call_args(start) {
                return Ok(args);
            }
        }
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

    /// The fastest path of `call_args`, for a call whose every argument is a plain name,
    /// `name:=name`, `\switch` or `\switch:=name`: reads them as [`Parser::plain_call_args`]
    /// does, into [`Parser::plain`] instead of expression nodes, and ends after the `;`. On
    /// anything else (a function call in an argument too) it reads nothing and says `false`.
    fn plain_args_from(&mut self, start: usize) -> bool {
        self.plain_args_after(start, None)
    }

    /// Fast path of a call statement's arguments whose first is a robtarget literal, at its
    /// `[` (`start`), written as a declaration's value is ([`Parser::robtarget_literal_at`],
    /// six external axes) and followed by `,`, `\` or `;`, every other argument one that
    /// [`Parser::plain_args_from`] reads: the literal into [`Parser::literal`], the arguments
    /// into [`Parser::plain`] (the literal the first, with no value), no expression nodes,
    /// and the parser goes on after the `;`. A generated program writes every motion's target
    /// so (`MoveL [[…],[…],[…],[…]],v1000,z10,tGun\WObj:=wCar;`), where the general path
    /// built a node per number and lexed every other argument. On anything else (another
    /// shape, a comment inside, a joint target, a blank the fast path does not step over) it
    /// reads nothing and says `false`, and the general path reads the call.
    fn literal_call_args(&mut self, start: usize) -> bool {
        // The general path reads each argument one level deeper; past the limit it refuses.
        if self.depth > MAX_DEPTH
            || !self.robtarget_literal_then(start, |next| matches!(next, b',' | b'\\' | b';'))
            || self.literal.axes != 6
        {
            return false;
        }
        let literal = PlainArg {
            span: self.literal.span,
            label: Span::new(start, start),
            switch: false,
            value: None,
        };
        self.plain_args_after(blanks_end(self.src, self.literal.span.end), Some(literal))
    }

    /// [`Parser::plain_args_from`] at `start`, after `first` when given: the arguments read
    /// into [`Parser::plain`] after it.
    #[inline(always)]
    fn plain_args_after(&mut self, start: usize, first: Option<PlainArg>) -> bool {
        // What [`Parser::plain`] holds is no longer the last call's (the caller says again).
        (self.last_call, self.moved) = (None, None);
        // The general path reads each argument one level deeper; past the limit it refuses.
        if self.depth > MAX_DEPTH {
            return false;
        }
        let src = self.src;
        let mut i = start;
        let mut len = 0;
        if let Some(first) = first {
            if !self.plain.set(0, first) {
                return false;
            }
            len = 1;
        }
        loop {
            match src.get(i) {
                Some(b';') => break,
                Some(b',') if len > 0 => i = blanks_end(src, i + 1),
                Some(b'\\') => {}
                _ if len == 0 => {}
                _ => return false,
            }
            let Some((arg, after)) = plain_arg(src, i) else {
                return false;
            };
            if src.get(after) == Some(&b'(') {
                return false;
            }
            if !self.plain.set(len, arg) {
                return false;
            }
            len += 1;
            i = after;
        }
        self.plain.len = len;
        self.resume_at_statement_end(i + 1);
        true
    }

    /// The call statement at `t` when its bytes are those of the last call read at its
    /// statement's first byte ([`Parser::last_call`]) with at most one name changed for another
    /// (`MoveL p11, v1000, z10, tGun\WObj:=wCar;` after `MoveL p10, ...`: runs of motions alike
    /// but for the target are most of a program): [`Parser::plain`] then holds its arguments,
    /// the last call's moved to its place, and the parser goes on after its `;`, as
    /// [`Parser::plain_args_from`] would leave it (a debug build reads the call that way too and
    /// holds the two to each other). On any other difference it reads nothing and says `false`.
    ///
    /// Every run of identifier bytes in a call that path read is a whole name (the callee, a
    /// label, a value), and the rest is blanks and punctuation; the name put in place of one is
    /// a plain name too, so the call reads as the last one did, argument for argument.
    fn call_like_last(&mut self, t: Token) -> bool {
        // The general path reads each argument one level deeper; past the limit it refuses.
        let Some(last) = self.last_call.filter(|_| self.depth <= MAX_DEPTH) else {
            return false;
        };
        let src = self.src;
        let now_start = t.start as usize;
        let (Some(before), Some(now)) = (src.get(last.start..last.end), src.get(now_start..))
        else {
            return false;
        };
        let alike = crate::syntax::common_len(before, now);
        // Where the last call's bytes move by `grown` more than by the shift to the new start:
        // after the name that differs (the end for a call written again as it was).
        let (from, grown) = if alike == before.len() {
            (before.len(), 0)
        } else {
            let name = before
                .get(..alike)
                .unwrap_or_default()
                .iter()
                .rposition(|&c| !is_ident_continue(c))
                .map_or(0, |k| k + 1);
            let old_end = match before.get(name..) {
                Some(rest @ [b'a'..=b'z' | b'A'..=b'Z' | b'_', ..]) => name + ident_len(rest),
                _ => return false,
            };
            let Some(new_end) = plain_name(src, now_start + name) else {
                return false;
            };
            let new_end = new_end - now_start;
            let rest = before.get(old_end..).unwrap_or_default();
            if now.get(new_end..new_end + rest.len()) != Some(rest) {
                return false;
            }
            (old_end, new_end as isize - old_end as isize)
        };
        #[cfg(debug_assertions)]
        let read = {
            let last_plain = self.plain;
            let after = blanks_end(src, t.end as usize);
            let read = self
                .plain_args_from(after)
                .then_some((self.plain, self.prev_end));
            self.plain = last_plain;
            read
        };
        let m = MovedCall {
            from: last.start,
            shift: now_start.wrapping_sub(last.start),
            pivot: last.start + from,
            grown,
        };
        self.plain.move_offsets(&m);
        let end = m.moved(last.end);
        // A label changed (`\Tool:=` for `\WObj:=`) says something else of the call: what
        // the extractor records for it is read again.
        let changed_end = now_start + from.wrapping_add_signed(grown);
        let label_changed = from < before.len()
            && self
                .plain
                .iter()
                .any(|a| a.label.end > a.label.start && a.label.end == changed_end);
        self.moved = (!label_changed).then_some(m);
        #[cfg(debug_assertions)]
        assert_eq!(
            read.map(|(plain, end)| (plain.iter().collect::<Vec<_>>(), end)),
            Some((self.plain.iter().collect(), end as u32)),
            "a call read as the one before"
        );
        self.resume_at_statement_end(end);
        true
    }

    /// Reads the call [`Parser::literal_call_args`] just read again, its arguments from the
    /// literal's `[` at `start` (the callee `callee`), with the general path, and asserts that
    /// it ends where that one did and reads the same arguments: the literal an aggregate of its
    /// span, each other argument of the span, label and name that [`Parser::plain`] holds.
    /// The arena's node of the arguments, for the extractor to compare its record with.
    #[cfg(debug_assertions)]
    fn literal_call_read_again(&mut self, callee: Token, start: usize) -> u32 {
        let (plain, literal) = (self.plain, self.literal);
        let after = (self.tok, self.prev_end, self.lex, self.peeked);
        self.resume_at(start);
        let args = self.call_args(callee.end);
        assert_eq!((self.tok, self.prev_end), (after.0, after.1));
        let args = args.unwrap_or_else(|e| panic!("the general path refused {e:?}"));
        let read: Vec<PlainArg> = self
            .arena
            .children(args)
            .filter_map(|a| {
                let arg = self.arena.get(a)?;
                let value = self.arena.arg_value(a).and_then(|v| self.arena.get(v));
                let value = match value.map(|v| (v.kind, v.span())) {
                    Some((ExprKind::Aggregate, v)) => {
                        assert_eq!(v, literal.span, "the inline literal");
                        None
                    }
                    Some((kind, v)) => {
                        assert_eq!(kind, ExprKind::Ident);
                        Some(v)
                    }
                    None => None,
                };
                Some(PlainArg {
                    span: arg.span(),
                    label: arg.name_span(),
                    switch: arg.switch,
                    value,
                })
            })
            .collect();
        assert_eq!(
            read,
            plain.iter().collect::<Vec<_>>(),
            "a call with a literal"
        );
        (self.plain, self.literal) = (plain, literal);
        (self.tok, self.prev_end, self.lex, self.peeked) = after;
        (self.last_call, self.moved) = (None, None);
        args
    }

    /// Fast path of `call_args` for the arguments nearly every motion line has: plain names,
    /// `name:=name`, `\switch` and `\switch:=name`, with commas and blanks between
    /// (`MoveL p10, v1000, z10, tGun\WObj:=wCar;`). It builds exactly the nodes the general
    /// path would, straight from the bytes, and ends after the `;`; on anything else (a
    /// number, a call, a comment, an operator...) it undoes its nodes and returns `None`, and
    /// the general path reads the arguments.
    fn plain_call_args(&mut self, start: u32) -> Option<u32> {
        // The general path reads each argument one level deeper; past the limit it refuses.
        if self.depth > MAX_DEPTH {
            return None;
        }
        let src = self.src;
        let mark = self.arena.mark();
        let args = self.arena.open(ExprKind::Args, start);
        let mut last = NONE;
        let mut i = self.tok.start as usize;
        let mut first = true;
        let ok = loop {
            match src.get(i) {
                Some(b';') => break true,
                Some(b',') if !first => i = blanks_end(src, i + 1),
                Some(b'\\') => {}
                _ if first => {}
                _ => break false,
            }
            first = false;
            let Some((arg, after)) = plain_arg(src, i) else {
                break false;
            };
            let a = self.arena.open(ExprKind::Arg, arg.span.start as u32);
            if arg.label.end > arg.label.start
                && let Some(n) = self.arena.set_mut(a)
            {
                n.switch = arg.switch;
                n.name_start = arg.label.start as u32;
                n.name_end = arg.label.end as u32;
            }
            match (arg.value, src.get(after)) {
                (Some(f), Some(b'(')) => match self.plain_function_call(f.start, f.end, after) {
                    Some((v, close)) => {
                        self.arena.link(a, NONE, v);
                        self.arena.close(a, close as u32);
                        self.arena.link(args, last, a);
                        last = a;
                        i = blanks_end(src, close);
                        continue;
                    }
                    None => break false,
                },
                // A switch without a value, then `(`.
                (None, Some(b'(')) => break false,
                (Some(v), _) => {
                    let id = self.arena.open(ExprKind::Ident, v.start as u32);
                    self.arena.close(id, v.end as u32);
                    self.arena.link(a, NONE, id);
                }
                (None, _) => {}
            }
            self.arena.close(a, arg.span.end as u32);
            self.arena.link(args, last, a);
            last = a;
            i = after;
        };
        if !ok {
            self.arena.truncate(mark);
            return None;
        }
        let end = i + 1;
        self.arena.close(args, end as u32);
        self.resume_at_statement_end(end);
        Some(args)
    }

    /// The part of [`Parser::plain_call_args`] for an argument that calls a function with
    /// plain names and numbers (`Offs(p10,0,0,100)`, `RelTool(p10, 0, 0, -50)`): the nodes
    /// the general path builds for the function named at `name..name_end` whose `(` is at
    /// `paren`, and the index after its `)`; `None` for any other arguments (then nothing
    /// built is kept: the caller undoes its nodes). Approach motions through `Offs` were a
    /// tenth of a module's motions and cost what three motions cost on the general path.
    fn plain_function_call(
        &mut self,
        name: usize,
        name_end: usize,
        paren: usize,
    ) -> Option<(u32, usize)> {
        let src = self.src;
        let blanks = |i: usize| blanks_end(src, i);
        let call = self.arena.open(ExprKind::Call, name as u32);
        let n = self.arena.set_mut(call)?;
        n.name_start = name as u32;
        n.name_end = name_end as u32;
        let mut last = NONE;
        let mut i = blanks(paren + 1);
        if src.get(i) == Some(&b')') {
            self.arena.close(call, i as u32 + 1);
            return Some((call, i + 1));
        }
        loop {
            // A name that is no keyword, or a number with its sign, ended as the lexer ends
            // it (what the numeric-aggregate fast path reads).
            let (kind, end) = match plain_name(src, i) {
                Some(end) if token_ends(src, end) => (ExprKind::Ident, end),
                Some(_) => return None,
                None => (ExprKind::Num, i + fast_number(src, i)?.1),
            };
            let a = self.arena.open(ExprKind::Arg, i as u32);
            let v = self.arena.open(kind, i as u32);
            self.arena.close(v, end as u32);
            self.arena.link(a, NONE, v);
            self.arena.close(a, end as u32);
            self.arena.link(call, last, a);
            last = a;
            let after = blanks(end);
            match src.get(after)? {
                b',' => i = blanks(after + 1),
                b')' => {
                    self.arena.close(call, after as u32 + 1);
                    return Some((call, after + 1));
                }
                _ => return None,
            }
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

/// One argument of a call's plain arguments at `i` ([`Parser::plain_args_from`],
/// [`Parser::plain_call_args`]): a plain name, `name:=name`, `\\switch` or `\\switch:=name`,
/// and the place after it and the blanks after it, where a `(` says its value names a
/// function. Each name is read once, and the blanks after it once: what follows decides what
/// it was (a label before `:=`, a value, or a function's name before `(`).
#[inline(always)]
fn plain_arg(src: &[u8], i: usize) -> Option<(PlainArg, usize)> {
    let switch = src.get(i) == Some(&b'\\');
    let at = if switch { blanks_end(src, i + 1) } else { i };
    let end = plain_name(src, at)?;
    let after = blanks_end(src, end);
    let (label, value, end, after) = if src.get(after..after + 2) == Some(b":=") {
        let v = blanks_end(src, after + 2);
        let v_end = plain_name(src, v)?;
        let value = Some(Span::new(v, v_end));
        (Span::new(at, end), value, v_end, blanks_end(src, v_end))
    } else if switch {
        (Span::new(at, end), None, end, after)
    } else {
        (Span::new(at, at), Some(Span::new(at, end)), end, after)
    };
    let arg = PlainArg {
        span: Span::new(i, end),
        label,
        switch,
        value,
    };
    Some((arg, after))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// What a call statement leaves behind: the result, the expression nodes, and where the
    /// parser stands after it (the next token and the end of the last one consumed).
    type Read = (
        Result<(NodeKind, String), &'static str>,
        Vec<crate::rapid::expr::ExprNode>,
        Token,
        u32,
    );

    fn read(src: &[u8], fast: bool) -> Read {
        let mut sink = crate::syntax::NoSink;
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        p.fast_paths = fast;
        read_next(&mut p)
    }

    /// [`read`] of the statement `p` stands at. The nodes without the literals the numeric
    /// scan hands on (the general path hands none on).
    fn read_next(p: &mut Parser<'_, '_>) -> Read {
        p.arena.clear();
        let result = p.simple_statement();
        // A call with a literal: what the fast path read is the literal and `p.plain` (a debug
        // build's arena holds the general path's reading, which is not what is compared).
        let literal = std::mem::take(&mut p.call_literal);
        let mut arena = match literal {
            true => Arena::default(),
            false => p.arena.clone(),
        };
        let result = result
            .map(|(kind, stmt)| match stmt {
                Stmt::Call { name, args } if args == NONE || literal => {
                    // Read at the statement, the callee is no node either.
                    if arena.nodes.is_empty() {
                        let callee = arena.open(ExprKind::Ident, name.start as u32);
                        arena.close(callee, name.end as u32);
                    }
                    let args = plain_args_as_nodes(p, &mut arena, literal, name.end);
                    (kind, format!("{:?}", Stmt::Call { name, args }))
                }
                stmt => (kind, format!("{stmt:?}")),
            })
            .map_err(|e| e.expected);
        let nodes = arena
            .nodes
            .iter()
            .map(|n| crate::rapid::expr::ExprNode { lit: NONE, ..*n })
            .collect();
        (result, nodes, p.tok, p.prev_end)
    }

    /// The nodes the general path builds for the arguments `p.plain` holds, from `start` (the
    /// callee's end) to after the `;`, appended to `arena`: what the plain-argument path
    /// stands for. With `literal`, the first is `p.literal`, whose nodes the general path
    /// reads (token by token) where it stands.
    fn plain_args_as_nodes(
        p: &mut Parser<'_, '_>,
        arena: &mut Arena,
        literal: bool,
        start: usize,
    ) -> u32 {
        let args = arena.open(ExprKind::Args, start as u32);
        let mut last = NONE;
        let plain = p.plain;
        for (k, a) in plain.iter().enumerate() {
            let arg = arena.open(ExprKind::Arg, a.span.start as u32);
            if a.label.end > a.label.start {
                let n = arena.set_mut(arg).unwrap();
                n.switch = a.switch;
                n.name_start = a.label.start as u32;
                n.name_end = a.label.end as u32;
            }
            if let Some(v) = a.value {
                let id = arena.open(ExprKind::Ident, v.start as u32);
                arena.close(id, v.end as u32);
                arena.link(arg, NONE, id);
            }
            if literal && k == 0 {
                assert_eq!(a.span, p.literal.span);
                let after = (p.tok, p.prev_end, p.lex, p.peeked);
                std::mem::swap(&mut p.arena, arena);
                p.fast_paths = false;
                p.resume_at(a.span.start);
                let id = p.primary().expect("the literal read by tokens");
                assert_eq!(p.prev_end as usize, a.span.end);
                p.fast_paths = true;
                std::mem::swap(&mut p.arena, arena);
                (p.tok, p.prev_end, p.lex, p.peeked) = after;
                arena.link(arg, NONE, id);
            }
            arena.close(arg, a.span.end as u32);
            arena.link(args, last, arg);
            last = arg;
        }
        arena.close(args, p.prev_end);
        args
    }

    /// Argument lists of the fast path's shape, with pieces it leaves to the general path
    /// mixed in: numbers, calls, accesses, operators, comments, keywords, odd separators.
    fn call() -> impl Strategy<Value = String> {
        let name = prop_oneof![
            "[a-zA-Z_][a-zA-Z0-9_]{0,6}",
            Just("tool0".to_owned()),
            Just("AND".to_owned()),
            Just("Ñame".to_owned()),
        ];
        let arg = prop_oneof![
            4 => name.clone(),
            3 => (
                crate::rapid::parser::inline_robtarget(),
                proptest::sample::select(vec!["", "", "", "", ".trans", "+p1", "{1}", " ! c\r\n"]),
            )
                .prop_map(|(literal, after)| format!("{literal}{after}")),
            2 => (name.clone(), "[ ]{0,1}", name.clone()).prop_map(|(s, b, v)| format!("\\{s}{b}:={b}{v}")),
            1 => name.clone().prop_map(|s| format!("\\{s}")),
            1 => (name.clone(), name.clone()).prop_map(|(n, v)| format!("{n}:={v}")),
            1 => Just("Offs(p1,0,0,10)".to_owned()),
            2 => (name.clone(), proptest::collection::vec(call_arg(), 0..5), "[ ]{0,1}")
                .prop_map(|(f, args, b)| format!("{f}{b}({b}{}{b})", args.join(","))),
            1 => (name.clone(), name.clone(), "[ ]{0,1}")
                .prop_map(|(s, f, b)| format!("\\{s}:={f}{b}(p1,{b}-5)")),
            1 => Just("-5".to_owned()),
            1 => Just("0.5".to_owned()),
            1 => Just("a.b".to_owned()),
            1 => Just("a{2}".to_owned()),
            1 => Just("a+b".to_owned()),
            1 => Just("\\T?t".to_owned()),
            1 => Just("! c\n x".to_owned()),
            1 => Just("\"s\"".to_owned()),
            1 => Just("".to_owned()),
        ];
        let sep = prop_oneof![
            Just(", ".to_owned()),
            Just(",".to_owned()),
            Just(" ,\r\n  ".to_owned()),
            Just("".to_owned()),
            Just(" ".to_owned()),
            Just(",,".to_owned()),
            Just(" : ".to_owned()),
        ];
        // The callee and what parts it from the first argument (the statement-level fast path
        // looks at the byte after the blanks).
        let callee = prop_oneof![
            6 => Just("MoveL "),
            1 => proptest::sample::select(vec!["MoveL", "MoveL\r\n  ", "Stop ", "TO ", "p.x ", "a{1} "]),
        ];
        (
            callee,
            proptest::collection::vec((sep, arg), 0..6),
            prop_oneof![Just(";"), Just(" ;"), Just(""), Just(";;")],
        )
            .prop_map(|(callee, parts, end)| {
                let mut s = callee.to_owned();
                for (k, (sep, arg)) in parts.iter().enumerate() {
                    if k > 0 || arg.starts_with('\\') {
                        s.push_str(sep);
                    }
                    s.push_str(arg);
                }
                format!("{s}{end}\r\n  next")
            })
    }

    /// A motion whose arguments are all of the fast paths' shapes, with at least one function
    /// called in them (`Offs(p10,0,0,100)`) among plain names, switches with and without a
    /// value, and labels.
    fn offs_call() -> impl Strategy<Value = String> {
        let name = prop_oneof![
            Just("p10"),
            Just("v1000"),
            Just("z10"),
            Just("tGun"),
            Just("wCar")
        ];
        let arg = prop_oneof![
            3 => name.clone().prop_map(str::to_owned),
            2 => (name.clone(), proptest::sample::select(vec!["WObj", "Tool", "V", "Conc"]))
                .prop_map(|(v, s)| format!("\\{s}:={v}")),
            1 => proptest::sample::select(vec!["\\Conc", "\\NoEOffs"]).prop_map(str::to_owned),
            1 => (name.clone(), name.clone()).prop_map(|(n, v)| format!("{n}:={v}")),
            2 => (proptest::collection::vec(call_arg(), 0..5), "[ ]{0,1}")
                .prop_map(|(args, b)| format!("Offs{b}({b}{}{b})", args.join(","))),
        ];
        (
            proptest::collection::vec(arg, 0..6),
            0..6usize,
            proptest::collection::vec(call_arg(), 1..5),
        )
            .prop_map(|(mut args, at, offs)| {
                args.insert(at.min(args.len()), format!("Offs(p1,{})", offs.join(",")));
                let mut s = "MoveL ".to_owned();
                for (k, a) in args.iter().enumerate() {
                    if k > 0 && !a.starts_with('\\') {
                        s.push_str(", ");
                    }
                    s.push_str(a);
                }
                format!("{s};\r\n  next")
            })
    }

    /// A call whose first argument is a robtarget written inline (mostly of the fast path's
    /// shape, [`crate::rapid::parser::inline_robtarget`]), then arguments mostly of the plain
    /// path's shape, with odd ones now and then: what follows the literal, a function's call,
    /// a number, a second literal (`MoveC`'s), a data writer's callee.
    fn literal_call() -> impl Strategy<Value = String> {
        let callee = proptest::sample::select(vec![
            "MoveL ",
            "MoveJ ",
            "MoveC ",
            "MoveLDO ",
            "MoveL",
            "MoveL\r\n  ",
            "TriggL ",
            "Incr ",
        ]);
        let after = prop_oneof![
            8 => proptest::sample::select(vec![",", " ,", ", ", ",\r\n      ", "\t,\t"]),
            1 => proptest::sample::select(vec![
                "", " ", ".trans,", "+p1,", " ! c\r\n,", "\\", ",,", ";", "{1},", "\u{1},",
            ]),
        ];
        let arg = prop_oneof![
            8 => proptest::sample::select(vec!["v1000", "z10", "tGun", "rdkSpeed", "fine", "tool0"]),
            3 => proptest::sample::select(vec![
                "\\WObj:=wCar", "\\WObj := rdkWObj", "\\Conc", "\\V:=vmax", "tool:=tGun",
                "\\Tool:=tGun", "\\T:=timer",
            ]),
            1 => proptest::sample::select(vec!["Offs(p1,0,0,10)", "-5", "a.b", "\"s\"", "", "AND"]),
        ]
        .prop_map(str::to_owned);
        let arg = prop_oneof![12 => arg, 1 => crate::rapid::parser::inline_robtarget()];
        let sep = prop_oneof![
            8 => proptest::sample::select(vec![", ", ",", ",\r\n  "]),
            1 => proptest::sample::select(vec!["", " ", ",,"]),
        ];
        (
            callee,
            crate::rapid::parser::inline_robtarget(),
            after,
            proptest::collection::vec((sep, arg), 0..6),
            prop_oneof![8 => Just(";"), 1 => Just(" ;"), 1 => Just("")],
        )
            .prop_map(|(callee, literal, after, args, end)| {
                let mut s = format!("{callee}{literal}{after}");
                for (k, (sep, arg)) in args.iter().enumerate() {
                    if k > 0 || after.is_empty() || after.ends_with(' ') {
                        s.push_str(sep);
                    }
                    s.push_str(arg);
                }
                format!("{s}{end}\r\n  next")
            })
    }

    /// An argument of a function called in an argument: mostly what the fast path reads
    /// (names, numbers with a sign), some it leaves to the general path.
    fn call_arg() -> impl Strategy<Value = String> {
        prop_oneof![
            6 => proptest::sample::select(vec![
                "p1", "0", "-5", "+5", "0.5", "-.5", "1E3", "9E+09", " 10 ", "\r\n  20", "_x",
            ]),
            1 => proptest::sample::select(vec![
                "- 5", "a.b", "a{2}", "f(1)", "1E", "0x1F", "1.2.3", "\\Z:=5", "x:=1", "AND",
                "NOT a", "a+b", "\"s\"", "", "! c\n 1", "12345678901234567890123",
            ]),
        ]
        .prop_map(str::to_owned)
    }

    /// The second of two statements read after the first, with the first's arguments at hand
    /// ([`Parser::call_like_last`]) and without, and whether the first was a call read at its
    /// statement's first byte.
    fn read_second(first: &str, second: &str) -> (Read, Read, bool) {
        let src = crate::rapid::parser::latin1_bytes(&format!("{first}\r\n  {second}\r\n  next"));
        let read = |like_last: bool| {
            let mut sink = crate::syntax::NoSink;
            let mut p = Parser::new(&src, &mut sink, TreeBuilder::with_capacity(4));
            let _first = read_next(&mut p);
            let was_call = p.last_call.is_some();
            if !like_last {
                p.last_call = None;
            }
            (read_next(&mut p), was_call)
        };
        let ((after, was_call), (alone, _)) = (read(true), read(false));
        (after, alone, was_call)
    }

    /// A call, and another one: mostly the first with one of its names (the callee, a label,
    /// a value) put in place of another, which may be no name (a keyword, a number, nothing,
    /// a function's call).
    fn like_calls() -> impl Strategy<Value = (String, String)> {
        let new_name = proptest::sample::select(vec![
            "p11",
            "p1",
            "v500",
            "Tool",
            "WObj",
            "MoveJ",
            "x",
            "a_much_longer_name_12",
            "Ñame",
            "AND",
            "TO",
            "9x",
            "",
            "p1(",
            "p1 ",
            "a.b",
        ]);
        let first = prop_oneof![3 => call(), 1 => literal_call()]
            .prop_map(|c| c.trim_end_matches("\r\n  next").to_owned());
        (
            first,
            any::<proptest::sample::Index>(),
            new_name,
            0..8u8,
            call(),
        )
            .prop_map(|(first, which, new_name, other, other_call)| {
                if other == 0 {
                    let other_call = other_call.trim_end_matches("\r\n  next").to_owned();
                    return (first, other_call);
                }
                let is_name = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || b >= 0xC0;
                let bytes = first.as_bytes();
                let names: Vec<(usize, usize)> = (0..bytes.len())
                    .filter(|&i| is_name(bytes[i]) && (i == 0 || !is_name(bytes[i - 1])))
                    .map(|i| {
                        (
                            i,
                            i + bytes[i..].iter().take_while(|&&b| is_name(b)).count(),
                        )
                    })
                    .collect();
                let second = match names.get(which.index(names.len().max(1))) {
                    Some(&(start, end)) => {
                        let mut s = bytes[..start].to_vec();
                        s.extend_from_slice(new_name.as_bytes());
                        s.extend_from_slice(&bytes[end..]);
                        String::from_utf8_lossy(&s).into_owned()
                    }
                    None => first.clone(),
                };
                (first, second)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 1024, ..ProptestConfig::default() })]

        #[test]
        fn fast_call_args_path_builds_what_the_general_path_builds(c in call()) {
            let c = crate::rapid::parser::latin1_bytes(&c);
            prop_assert_eq!(read(&c, true), read(&c, false));
        }

        /// A motion's target written inline, then mostly plain names: the literal and the names
        /// read without nodes, or the general path's reading of anything else.
        #[test]
        fn an_inline_target_builds_what_the_general_path_builds(c in literal_call()) {
            let c = crate::rapid::parser::latin1_bytes(&c);
            prop_assert_eq!(read(&c, true), read(&c, false));
        }

        /// The node path's own shape: every argument one the fast paths read, a function's
        /// call among them, beside switches and labels (mixed in [`call`] they seldom meet).
        #[test]
        fn a_function_beside_switches_builds_what_the_general_path_builds(c in offs_call()) {
            prop_assert_eq!(read(c.as_bytes(), true), read(c.as_bytes(), false));
        }

        #[test]
        fn a_call_like_the_one_before_reads_as_it_reads_alone((first, second) in like_calls()) {
            let (after, alone, _) = read_second(&first, &second);
            prop_assert_eq!(after, alone);
        }
    }

    #[test]
    fn a_call_like_the_one_before_takes_its_arguments() {
        let first = "MoveL p10, v1000, z10, tGun\\WObj:=wCar;";
        // Each is `first` with one name changed, or written again as it was.
        let like = [
            "MoveL p11, v1000, z10, tGun\\WObj:=wCar;",
            "MoveL p1, v1000, z10, tGun\\WObj:=wCar;",
            "MoveL p10000, v1000, z10, tGun\\WObj:=wCar;",
            "MoveJ p10, v1000, z10, tGun\\WObj:=wCar;",
            "MoveL p10, v1000, z10, tGun\\Tool:=wCar;",
            "MoveL p10, v1000, z10, tGun\\WObj:=wTable;",
            "MoveL p10, v1000, z10, tGun\\WObj:=wCar;",
        ];
        for second in like {
            let mut sink = crate::syntax::NoSink;
            let src = format!("{first}\n{second}\nx");
            let mut p = Parser::new(src.as_bytes(), &mut sink, TreeBuilder::with_capacity(4));
            assert!(read_next(&mut p).0.is_ok());
            let t = p.tok;
            assert!(p.call_like_last(t), "{second}");
            let texts: Vec<_> = p
                .plain
                .iter()
                .map(|a| a.span.slice(src.as_bytes()))
                .collect();
            let want: Vec<&[u8]> = second.as_bytes()[6..second.len() - 1]
                .split(|&b| b == b',')
                .flat_map(|a| a.strip_prefix(b" ").unwrap_or(a).split(|&b| b == b'\\'))
                .collect();
            let want: Vec<Vec<u8>> = want
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    if k == 4 {
                        [b"\\", *a].concat()
                    } else {
                        a.to_vec()
                    }
                })
                .collect();
            assert_eq!(texts, want, "{second}");
            assert_eq!(p.tok.start as usize, src.len() - 1);
        }
        // Not alike: another blank, a keyword or a number for a name, another separator, a
        // function called.
        for second in [
            "MoveL p10,  v1000, z10, tGun\\WObj:=wCar;",
            "MoveL AND, v1000, z10, tGun\\WObj:=wCar;",
            "MoveL 9x, v1000, z10, tGun\\WObj:=wCar;",
            "MoveL p10, v1000, z10, tGun, \\WObj:=wCar;",
            "MoveL p10(1), v1000, z10, tGun\\WObj:=wCar;",
            "MoveL p10, v1000, z10;",
        ] {
            let (after, alone, was_call) = read_second(first, second);
            assert!(was_call);
            assert_eq!(after, alone, "{second}");
            let mut sink = crate::syntax::NoSink;
            let src = format!("{first}\n{second}\nx");
            let mut p = Parser::new(src.as_bytes(), &mut sink, TreeBuilder::with_capacity(4));
            assert!(read_next(&mut p).0.is_ok());
            let t = p.tok;
            assert!(!p.call_like_last(t), "{second}");
        }
    }

    /// The call statement `src` (`MoveL` then its arguments) read by the fast path alone:
    /// the nodes it built and where the parser stands after them, once the general path is
    /// known to read the same.
    fn fast_path_read(src: &[u8]) -> (usize, usize) {
        let mut sink = crate::syntax::NoSink;
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        p.bump();
        assert!(p.plain_call_args(5).is_some());
        assert_eq!(read(src, true), read(src, false));
        (p.arena.nodes.len(), p.tok.start as usize)
    }

    #[test]
    fn plain_names_are_read_without_nodes() {
        let src = b"MoveL p10, v1000, z10, tGun\\WObj:=wCar, \\Conc;\nx";
        let mut sink = crate::syntax::NoSink;
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        p.bump();
        assert!(p.plain_args_from(p.tok.start as usize));
        assert!(p.arena.nodes.is_empty());
        let texts: Vec<_> = p
            .plain
            .iter()
            .map(|a| {
                let text = |s: Span| String::from_utf8_lossy(s.slice(src)).into_owned();
                (text(a.span), text(a.label), a.switch, a.value.map(text))
            })
            .collect();
        let t = |s: &str| s.to_owned();
        assert_eq!(
            texts,
            [
                (t("p10"), t(""), false, Some(t("p10"))),
                (t("v1000"), t(""), false, Some(t("v1000"))),
                (t("z10"), t(""), false, Some(t("z10"))),
                (t("tGun"), t(""), false, Some(t("tGun"))),
                (t("\\WObj:=wCar"), t("WObj"), true, Some(t("wCar"))),
                (t("\\Conc"), t("Conc"), true, None),
            ]
        );
        assert_eq!(p.tok.start as usize, src.len() - 1);
        // An argument that calls a function is the node path's.
        let src = b"MoveL Offs(p10,0,0,10), v1000, z10, tGun;\nx";
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        p.bump();
        assert!(!p.plain_args_from(p.tok.start as usize));
        assert_eq!(p.tok.start, 6);
    }

    #[test]
    fn an_approach_through_offs_takes_the_fast_path() {
        let src = b"MoveL Offs(p10, 0, 0, -100), v1000, z10, tGun\\WObj:=wCar;\nx";
        // Args; the first Arg, its Call and the Call's four Args with their values; then an
        // Arg and its Ident for each of the other four arguments.
        assert_eq!(fast_path_read(src), (1 + 2 + 4 * 2 + 4 * 2, src.len() - 1));
    }

    #[test]
    fn a_motion_to_a_target_written_inline_takes_the_fast_path() {
        let literal = "[[1520.3,-850.1,612.4],[0.0,0.707107,0.707107,0.0],[0,0,-1,0],\
            [1650.0,9E+09,9E+09,9E+09,9E+09,9E+09]]";
        let src = format!("MoveL {literal},v1000,z10,tGun\\WObj:=wCar;\nx");
        let src = src.as_bytes();
        assert_eq!(read(src, true), read(src, false));
        let mut sink = crate::syntax::NoSink;
        let mut p = Parser::new(src, &mut sink, TreeBuilder::with_capacity(4));
        let (kind, _) = p.simple_statement().expect("a call");
        assert_eq!(kind, NodeKind::Call);
        assert!(p.call_literal);
        let l = p.literal;
        assert_eq!(l.span, Span::new(6, 6 + literal.len()));
        let text = |at: usize| {
            let rest = &src[at..];
            let end = rest.iter().position(|&b| b == b',' || b == b']').unwrap();
            std::str::from_utf8(&rest[..end]).unwrap()
        };
        assert_eq!(l.trans.map(text), ["1520.3", "-850.1", "612.4"]);
        assert_eq!(
            l.quaternion.map(text),
            ["0.0", "0.707107", "0.707107", "0.0"]
        );
        assert_eq!(l.quadrants.map(text), ["0", "0", "-1", "0"]);
        assert_eq!(l.axes, 6);
        assert_eq!(
            l.extax[..6].iter().map(|&a| text(a)).collect::<Vec<_>>(),
            ["1650.0", "9E+09", "9E+09", "9E+09", "9E+09", "9E+09"]
        );
        // The values as the standard library reads the texts.
        let value = |t: &str| t.parse::<f64>().unwrap();
        assert_eq!(l.q, ["0.0", "0.707107", "0.707107", "0.0"].map(value));
        assert_eq!(l.cf, [0.0, 0.0, -1.0, 0.0]);
        let args: Vec<_> = p
            .plain
            .iter()
            .map(|a| (a.span.slice(src), a.value.map(|v| v.slice(src))))
            .collect();
        let arg = |s: &'static str, v: Option<&'static str>| (s.as_bytes(), v.map(str::as_bytes));
        assert_eq!(
            args,
            [
                arg(literal, None),
                arg("v1000", Some("v1000")),
                arg("z10", Some("z10")),
                arg("tGun", Some("tGun")),
                arg("\\WObj:=wCar", Some("wCar")),
            ]
        );
        // Past the `;`, with no call to repeat: the literal's numbers are no names.
        assert_eq!(p.tok.start as usize, src.len() - 1);
        assert_eq!(p.last_call, None);
    }

    #[test]
    fn an_inline_target_of_another_shape_is_left_to_the_general_path() {
        let target = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let five = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9]]";
        let joints = "[[0,0,0,0,90,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let named = "[[1,2,3],[1,0,0,0],[0,0,0,0],rdkExtJoints]";
        let comment = "[[1,2,3],[1,0,0,0] ! c\r\n,[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let form_feed = "[[1,2,3],[1,0,0,0],\u{c}[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let latin1 = "[[1,2,3],[1,0,0,0],[0,0,0,0]\u{1},[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let apart = "[[1,2,3],[1,0,0,0],[0,0,- 1,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
        let unread = "[[1,2,3],[1,0,0,0],[0,0,0,0],[1E,9E9,9E9,9E9,9E9,9E9]]";
        for call in [
            format!("MoveL {five},v10,z1,tool0;"),
            format!("MoveAbsJ {joints},v10,z1,tool0;"),
            format!("MoveL {named},v10,z1,tool0;"),
            format!("MoveL {comment},v10,z1,tool0;"),
            format!("MoveL {form_feed},v10,z1,tool0;"),
            format!("MoveL {latin1},v10,z1,tool0;"),
            format!("MoveL {apart},v10,z1,tool0;"),
            format!("MoveL {unread},v10,z1,tool0;"),
            format!("MoveL {target}.trans,v10,z1,tool0;"),
            format!("MoveL {target}+p1,v10,z1,tool0;"),
            format!("MoveL {target} v10,z1,tool0;"),
            format!("MoveL {target},v10,z1,tool0 ! c\r\n;"),
            format!("MoveL {target},Offs(p1,0,0,10),z1,tool0;"),
            format!("MoveC {target},{target},v10,z1,tool0;"),
        ] {
            let src = crate::rapid::parser::latin1_bytes(&format!("{call}\r\nx"));
            let mut sink = crate::syntax::NoSink;
            let mut p = Parser::new(&src, &mut sink, TreeBuilder::with_capacity(4));
            let _ = p.simple_statement();
            assert!(!p.call_literal, "{call}");
            assert_eq!(read(&src, true), read(&src, false), "{call}");
        }
        // The same target with six axes, before `;`, `\` or a blank and `,` takes it.
        for call in [
            format!("MoveL {target};"),
            format!("MoveL {target}\\Conc,v10,z1,tool0;"),
            format!("MoveL\t{target}\r\n  ,\tv10 ,z1,tool0 \\WObj := wCar ;"),
        ] {
            let src = format!("{call}\r\nx");
            let mut sink = crate::syntax::NoSink;
            let mut p = Parser::new(src.as_bytes(), &mut sink, TreeBuilder::with_capacity(4));
            let _ = p.simple_statement();
            assert!(p.call_literal, "{call}");
            assert_eq!(
                read(src.as_bytes(), true),
                read(src.as_bytes(), false),
                "{call}"
            );
        }
    }

    #[test]
    fn a_motion_line_takes_the_fast_path() {
        let src = b"MoveL p10, v1000, z10, tGun\\WObj:=wCar;\nx";
        // Args, then per argument an Arg and its Ident (the switch's value too).
        assert_eq!(fast_path_read(src), (1 + 5 * 2, src.len() - 1));
    }
}
