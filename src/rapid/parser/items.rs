//! Items: the file, modules, data declarations, records, routines and their parameters
//! (`grammars/rapid.ebnf`, sections "file" and "routines").

use super::*;

impl Parser<'_, '_> {
    /// `file = [ BOM ] { header_line } { module | item } EOF`
    pub(super) fn file(&mut self) {
        let mut outside_warned = false;
        // The `%%%` line that opened a header block not yet closed.
        let mut open_header: Option<Token> = None;
        loop {
            match self.tok.kind {
                TokenKind::Eof => break,
                TokenKind::HeaderLine => {
                    let t = self.tok;
                    if self.text(t).starts_with(b"%%%") {
                        open_header = match open_header {
                            Some(_) => None,
                            None => Some(t),
                        };
                    }
                    self.bump();
                    self.leaf(NodeKind::Header, t.start);
                }
                _ if self.at_kw(b"MODULE") => self.module(),
                _ => {
                    if !outside_warned && self.is_item_start() {
                        outside_warned = true;
                        self.diagnostics.push(
                            Diagnostic::warning(
                                self.tok.span(),
                                "declaration outside a MODULE ... ENDMODULE block",
                            )
                            .with_hint(
                                "a controller loads only modules; wrap the text in MODULE name ... ENDMODULE",
                            ),
                        );
                    }
                    self.item(true);
                }
            }
        }
        if let Some(t) = open_header {
            self.diagnostics.push(
                Diagnostic::error(
                    t.span(),
                    "`%%%` header block without its closing `%%%` line",
                )
                .with_hint(
                    "close the header with a line `%%%`; everything after it was read as header",
                ),
            );
        }
    }

    pub(super) fn is_item_start(&self) -> bool {
        self.at_any(&[
            b"CONST", b"PERS", b"VAR", b"LOCAL", b"TASK", b"PROC", b"FUNC", b"TRAP", b"RECORD",
            b"ALIAS",
        ])
    }

    /// `module = "MODULE" ident [ "(" attribute { "," attribute } ")" ] { item } "ENDMODULE"`
    /// (rule `attribute`: any identifier).
    pub(super) fn module(&mut self) {
        let start = self.tok.start;
        let branch = self.open(NodeKind::Module, start);
        let head = self.tok;
        self.bump();
        let head_ok: PResult<()> = (|| {
            if self.tok.kind != TokenKind::Ident {
                return Err(self.error("a module name after MODULE"));
            }
            self.bump();
            if self.eat_punct(b'(') {
                loop {
                    self.expect_ident(
                        "a module attribute (SYSMODULE, NOSTEPIN, VIEWONLY, READONLY, NOVIEW)",
                    )?;
                    if self.eat_punct(b')') {
                        break;
                    }
                    self.expect_punct(b',', "`,` or `)` in the module attributes")?;
                }
            }
            Ok(())
        })();
        match head_ok {
            Ok(()) => self.leaf(NodeKind::ModuleHead, start),
            Err(e) => {
                // Keep the rest of the head line opaque but go on reading the module body.
                if e.at.kind == TokenKind::Unknown {
                    self.reported_unknown = Some(e.at.start);
                }
                while self.tok.kind != TokenKind::Eof && !self.newline_before_tok() {
                    self.bump();
                }
                let found = self.describe(e.at);
                self.diagnostics.push(
                    Diagnostic::error(
                        e.at.span(),
                        format!("expected {}, found {found}", e.expected),
                    )
                    .with_hint(
                        "write the module head as MODULE name or MODULE name(SYSMODULE, NOSTEPIN)",
                    ),
                );
                self.opaque += 1;
                self.leaf(NodeKind::Opaque, start);
            }
        }
        loop {
            if self.tok.kind == TokenKind::Eof {
                self.diagnostics.push(
                    Diagnostic::error(head.span(), "MODULE without ENDMODULE").with_hint(
                        "add ENDMODULE at the end of the module (is the file truncated?)",
                    ),
                );
                break;
            }
            if self.at_kw(b"ENDMODULE") {
                let s = self.tok.start;
                self.bump();
                self.leaf(NodeKind::ModuleEnd, s);
                break;
            }
            if self.at_kw(b"MODULE") {
                self.diagnostics.push(
                    Diagnostic::error(
                        head.span(),
                        "MODULE without ENDMODULE before the next MODULE",
                    )
                    .with_hint("add ENDMODULE before the next MODULE"),
                );
                break;
            }
            self.item(true);
        }
        self.close(branch);
    }

    /// `item = data_decl | routine | record | placeholder | opaque`
    pub(super) fn item(&mut self, module_scope: bool) {
        let start = self.tok.start;
        self.first = self.tok;
        self.arena.clear();
        if self.tok.kind == TokenKind::Placeholder {
            self.bump();
            self.eat_punct(b';');
            self.leaf(NodeKind::Placeholder, start);
            return;
        }
        // Most items of a robtarget file are `CONST` declarations: their keyword is compared
        // as a word first, not with `LOCAL`, `TASK` and `CONST` byte by byte.
        if self.tok.keyword
            && self.tok.end - self.tok.start == 5
            && letters_at(self.src, start as usize, b"const")
        {
            self.data_decl(start, module_scope);
            return;
        }
        // The token after `LOCAL` or `TASK` says what is declared. Only then is it lexed
        // ahead: a declaration's head is mostly read by bytes, and the token lexed ahead of
        // every item was a fifth of reading a robtarget's head.
        let second = self
            .at_any(&[b"LOCAL", b"TASK"])
            .then(|| self.peek2())
            .filter(|t| t.keyword)
            .map(|t| t.text(self.src));
        let kw_is = |words: &[&[u8]]| second.is_some_and(|text| is_word_in(text, words));
        if self.at_any(&[b"CONST", b"PERS", b"VAR", b"ALIAS"])
            || kw_is(&[b"CONST", b"PERS", b"VAR"])
        {
            self.data_decl(start, module_scope);
        } else if self.at_any(&[b"PROC", b"FUNC", b"TRAP"]) || kw_is(&[b"PROC", b"FUNC", b"TRAP"]) {
            self.routine(start);
        } else if self.at_kw(b"RECORD") || kw_is(&[b"RECORD"]) {
            self.record(start);
        } else {
            self.unknown_item(start);
        }
    }

    /// `data_decl = [ "LOCAL" | "TASK" ] ( "CONST" | "PERS" | "VAR" ) type ident [ dims ]
    ///              [ ":=" expr ] ";" | "ALIAS" type ident ";"`, with rule `dims`.
    pub(super) fn data_decl(&mut self, start: u32, module_scope: bool) {
        match self.data_decl_inner(module_scope) {
            Ok((stmt, literal)) => {
                self.leaf(NodeKind::DataDecl, start);
                self.emit_with(stmt, start, literal);
            }
            Err(e) => self.recover(start, e),
        }
    }

    /// The declaration, and whether its value is the robtarget literal the fast path read
    /// ([`Parser::robtarget_literal`], into [`Parser::literal`]).
    pub(super) fn data_decl_inner(&mut self, module_scope: bool) -> PResult<(Stmt, bool)> {
        let local = self.at_kw(b"LOCAL");
        if self.at_any(&[b"LOCAL", b"TASK"]) {
            self.bump();
        }
        if self.fast_paths
            && let Some(decl) = self.plain_robtarget_decl(module_scope, local)
        {
            return decl;
        }
        let storage_tok = self.bump();
        let st = self.text(storage_tok);
        let storage = if st.eq_ignore_ascii_case(b"CONST") {
            Storage::Const
        } else if st.eq_ignore_ascii_case(b"PERS") {
            Storage::Pers
        } else if st.eq_ignore_ascii_case(b"VAR") {
            Storage::Var
        } else {
            Storage::Alias
        };
        let ty = self.expect_ident("a data type after the storage class")?;
        let name = self.expect_ident("a data name after the type")?;
        let mut dims = 0u8;
        if self.eat_punct(b'{') {
            loop {
                self.expr()?;
                dims = dims.saturating_add(1);
                if self.eat_punct(b'}') {
                    break;
                }
                self.expect_punct(b',', "`,` or `}` in the array dimensions")?;
            }
        }
        let mut init = None;
        let mut literal = false;
        if self.tok.kind == TokenKind::Assign {
            self.bump();
            literal = dims == 0
                && self.fast_paths
                && self.text(ty).eq_ignore_ascii_case(b"robtarget")
                && self.text(name).is_ascii()
                && self.robtarget_literal();
            if !literal {
                init = Some(self.expr()?);
            }
            // Every test run holds the fast path to the general one: the same end, and the
            // arena's value for the extractor to compare with.
            #[cfg(debug_assertions)]
            if literal {
                init = Some(self.literal_read_again());
            }
        }
        self.expect_punct(b';', "`;` at the end of the declaration")?;
        let stmt = Stmt::Decl {
            storage,
            type_name: ty.span(),
            name: name.span(),
            dims,
            init,
            module_scope,
            local,
        };
        Ok((stmt, literal))
    }

    /// Fast path of [`Parser::data_decl_inner`] at its storage keyword, for a scalar
    /// robtarget declared with a literal the fast path reads (`CONST robtarget p10:=[..];`,
    /// most lines of a program): its type and name are read from the bytes, with no token
    /// lexed (four tokens a declaration, each lexed to be compared and stepped over). `None`,
    /// with nothing read, for anything else.
    fn plain_robtarget_decl(
        &mut self,
        module_scope: bool,
        local: bool,
    ) -> Option<PResult<(Stmt, bool)>> {
        let src = self.src;
        let (at, len) = (
            self.tok.start as usize,
            (self.tok.end - self.tok.start) as usize,
        );
        let storage = match len {
            5 if letters_at(src, at, b"const") => Storage::Const,
            4 if letters_at(src, at, b"pers") => Storage::Pers,
            3 if letters_at(src, at, b"var") => Storage::Var,
            _ => return None,
        };
        // The type is `robtarget` in any case and nothing more: the name `plain_name` reads
        // there, compared as words (no keyword is such a name).
        let ty = blanks_end(src, self.tok.end as usize);
        let ty_end = ty + b"robtarget".len();
        if !letters_at(src, ty, b"robtarge")
            || src.get(ty_end - 1).map(|c| c | 0x20) != Some(b't')
            || src.get(ty_end).is_some_and(|&c| is_ident_continue(c))
        {
            return None;
        }
        debug_assert_eq!(plain_name(src, ty), Some(ty_end));
        let name = blanks_end(src, ty_end);
        let name_end = plain_name(src, name)?;
        let assign = blanks_end(src, name_end);
        if src.get(assign..assign + 2) != Some(b":=") {
            return None;
        }
        let value = blanks_end(src, assign + 2);
        // The name's bytes tested one by one: a name is a few bytes, and `is_ascii` was a call.
        let ascii = src.get(name..name_end)?.iter().all(u8::is_ascii);
        if !ascii || !self.robtarget_literal_at(value) {
            return None;
        }
        let end = self.literal.span.end;
        // The general path's reading of the value, to the same end, in every debug build (as
        // `data_decl_inner` holds its own fast path).
        #[cfg(debug_assertions)]
        let init = {
            self.resume_at(end);
            Some(self.literal_read_again())
        };
        #[cfg(not(debug_assertions))]
        let init = None;
        // The `;` the literal was read up to ends the statement: the parser resumes after it,
        // where lexing it as a token to step over was a tenth of the declaration's head.
        let semicolon = blanks_end(src, end);
        debug_assert_eq!(src.get(semicolon), Some(&b';'));
        self.resume_at_statement_end(semicolon + 1);
        let stmt = Stmt::Decl {
            storage,
            type_name: Span::new(ty, ty_end),
            name: Span::new(name, name_end),
            dims: 0,
            init,
            module_scope,
            local,
        };
        Some(Ok((stmt, true)))
    }

    /// `record = [ "LOCAL" | "TASK" ] "RECORD" ident { type ident ";" } "ENDRECORD"`
    pub(super) fn record(&mut self, start: u32) {
        let branch = self.open(NodeKind::Record, start);
        if self.at_any(&[b"LOCAL", b"TASK"]) {
            self.bump();
        }
        self.bump();
        self.arena.clear();
        match self.expect_ident("a record name after RECORD") {
            Ok(name) => {
                self.leaf(NodeKind::RecordHead, start);
                self.emit(Stmt::Record { name: name.span() }, start);
            }
            Err(e) => self.recover(start, e),
        }
        loop {
            if self.at_kw(b"ENDRECORD") {
                let s = self.tok.start;
                self.bump();
                self.leaf(NodeKind::RecordEnd, s);
                break;
            }
            if self.tok.kind == TokenKind::Eof || (self.at_any(HARD_ENDS)) {
                self.diagnostics.push(
                    Diagnostic::error(
                        Span::new(start as usize, start as usize + 6),
                        "RECORD without ENDRECORD",
                    )
                    .with_hint("add ENDRECORD after the record's components"),
                );
                break;
            }
            let s = self.tok.start;
            let field: PResult<(Token, Token)> = (|| {
                let type_name = self.expect_ident("a component type")?;
                let name = self.expect_ident("a component name")?;
                self.expect_punct(b';', "`;` after the record component")?;
                Ok((type_name, name))
            })();
            match field {
                Ok((type_name, name)) => {
                    self.leaf(NodeKind::RecordField, s);
                    self.emit(
                        Stmt::RecordField {
                            type_name: type_name.span(),
                            name: name.span(),
                        },
                        s,
                    );
                }
                Err(e) => self.recover(s, e),
            }
        }
        self.close(branch);
    }

    // ---- routines -----------------------------------------------------------------------

    /// `routine = [ "LOCAL" ] ( "PROC" ident "(" params ")" | "FUNC" type ident "(" params ")"
    ///            | "TRAP" ident ) body { handler } end_routine`: rules `handler` and
    /// `end_routine` too.
    pub(super) fn routine(&mut self, start: u32) {
        let branch = self.open(NodeKind::Routine, start);
        let local = self.at_kw(b"LOCAL");
        if self.at_kw(b"LOCAL") || self.at_kw(b"TASK") {
            self.bump();
        }
        let kw = self.bump();
        let kind = self.text(kw).to_ascii_uppercase();
        let end_kw: &'static [u8] = match kind.as_slice() {
            b"FUNC" => b"ENDFUNC",
            b"TRAP" => b"ENDTRAP",
            _ => b"ENDPROC",
        };
        let head: PResult<(Span, RoutineParams)> = (|| {
            if kind == b"FUNC" {
                self.expect_ident("the return type after FUNC")?;
            }
            let name = self.expect_ident("a routine name")?;
            let params = if kind != b"TRAP" {
                self.params()?
            } else {
                RoutineParams::default()
            };
            Ok((name.span(), params))
        })();
        match head {
            Ok((name, RoutineParams { required, optional })) => {
                self.leaf(NodeKind::RoutineHead, start);
                self.arena.clear();
                self.emit(Stmt::Routine { name, local }, start);
                for (_, name) in required {
                    self.emit(
                        Stmt::Param {
                            name,
                            optional: false,
                        },
                        start,
                    );
                }
                for name in optional {
                    self.emit(
                        Stmt::Param {
                            name,
                            optional: true,
                        },
                        start,
                    );
                }
            }
            Err(e) => self.recover(start, e),
        }
        self.statements(&[end_kw, b"ERROR", b"UNDO", b"BACKWARD"]);
        while self.at_any(&[b"ERROR", b"UNDO", b"BACKWARD"]) {
            let hs = self.tok.start;
            let handler = self.open(NodeKind::Handler, hs);
            self.bump();
            let head: PResult<()> = (|| {
                if self.eat_punct(b'(') {
                    loop {
                        self.expr()?;
                        if self.eat_punct(b')') {
                            break;
                        }
                        self.expect_punct(b',', "`,` or `)` in the ERROR handler's error numbers")?;
                    }
                }
                Ok(())
            })();
            match head {
                Ok(()) => self.leaf(NodeKind::HandlerHead, hs),
                Err(e) => self.recover(hs, e),
            }
            self.statements(&[end_kw, b"ERROR", b"UNDO", b"BACKWARD"]);
            self.close(handler);
        }
        if self.at_kw(end_kw) {
            let s = self.tok.start;
            self.bump();
            self.leaf(NodeKind::RoutineEnd, s);
        } else {
            let found = self.describe(self.tok);
            self.diagnostics.push(
                Diagnostic::error(
                    kw.span(),
                    format!(
                        "{} without {} (found {found})",
                        crate::syntax::latin1(self.text(kw)),
                        String::from_utf8_lossy(end_kw)
                    ),
                )
                .with_hint(format!(
                    "add {} at the end of the routine",
                    String::from_utf8_lossy(end_kw)
                )),
            );
        }
        self.close(branch);
    }

    /// `params = "(" [ param { ( "," | "|" ) param } ] ")"` with
    /// `param = [ "\" ] [ "INOUT" | "VAR" | "PERS" ] type ident [ "{" "*" { "," "*" } "}" ]`;
    /// read as a balanced parenthesis group (the positions never depend on parameters).
    /// The parameter list; returns the required parameters (`type name`, in order: the
    /// positional arguments of a call), skipping optional `\name` ones and `VAR`/`PERS`/`INOUT`.
    pub(super) fn params(&mut self) -> PResult<RoutineParams> {
        self.expect_punct(b'(', "`(` before the parameter list")?;
        let mut depth = 1u32;
        let mut required = Vec::new();
        // The optional parameters' names, alternatives (`\a | b`) each.
        let mut optional_names = Vec::new();
        let mut words: Vec<Span> = Vec::new();
        let mut optional = false;
        let mut first = true;
        loop {
            match self.tok.kind {
                TokenKind::Eof => return Err(self.error("`)` closing the parameter list")),
                TokenKind::Unknown | TokenKind::UnterminatedStr => {
                    return Err(self.error("a parameter"));
                }
                _ => {}
            }
            if self.at_punct(b';') || self.at_any(HARD_ENDS) {
                return Err(self.error("`)` closing the parameter list"));
            }
            let c = self.tok.punct(self.src);
            if depth == 1 {
                if first && c == b'\\' {
                    optional = true;
                }
                if self.tok.kind == TokenKind::Ident && !self.at_any(&[b"VAR", b"PERS", b"INOUT"]) {
                    words.push(self.tok.span());
                }
                first = false;
            }
            self.bump();
            if c == b'(' {
                depth += 1;
            } else if c == b')' || (c == b',' && depth == 1) {
                if depth == 1 {
                    match (optional, words.as_slice()) {
                        (false, [ty, name, ..]) => required.push((*ty, *name)),
                        (true, words) => {
                            optional_names.extend(words.chunks(2).filter_map(|c| c.get(1)));
                        }
                        _ => {}
                    }
                    words.clear();
                    optional = false;
                    first = true;
                }
                if c == b')' {
                    depth -= 1;
                    if depth == 0 {
                        return Ok(RoutineParams {
                            required,
                            optional: optional_names,
                        });
                    }
                }
            }
        }
    }
}

/// A routine's parameter list as the head gives it: the required parameters (type, name), in
/// order, and the optional ones' names (each alternative of `\\a | b`).
#[derive(Default)]
pub(super) struct RoutineParams {
    required: Vec<(Span, Span)>,
    optional: Vec<Span>,
}
