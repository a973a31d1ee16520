//! The RAPID parser: a recursive-descent reader over the streaming lexer's tokens that builds
//! the lossless [`Tree`] and never fails.
//!
//! Each function's doc comment names the rule of `grammars/rapid.ebnf` it implements. A
//! statement or item that does not fit its rule becomes an [`NodeKind::Opaque`] leaf running to
//! the next `;` (or to the next block keyword), with a located diagnostic: the round trip holds
//! for every input because leaves are byte ranges and every byte lands in exactly one leaf.

use super::expr::{Arena, ExprKind, NONE};
use super::lexer::{Lexer, Token, TokenKind};
use super::tree::{Node, NodeKind, Tree};
use crate::syntax::{Diagnostic, Span};

/// Nesting deeper than this (brackets, blocks) is reported instead of recursed into, so a
/// hostile input cannot overflow the stack.
const MAX_DEPTH: u32 = 96;

/// Storage class of a data declaration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    Const,
    Pers,
    Var,
    Alias,
}

/// What the position extractor needs to know about a statement just read; expression ids
/// point into the parser's [`Arena`].
#[derive(Clone, Copy, Debug)]
pub enum Stmt {
    /// A data declaration. `module_scope` is false inside routines.
    Decl {
        storage: Storage,
        type_name: Span,
        name: Span,
        dims: u8,
        init: Option<u32>,
        module_scope: bool,
    },
    /// `PROC`/`FUNC`/`TRAP` head (its name is a module-scope symbol).
    Routine { name: Span },
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

/// Receives every statement as it is read (the positions layer implements it).
pub trait StatementSink {
    fn statement(&mut self, src: &[u8], arena: &Arena, stmt: &Stmt, span: Span);
}

/// A sink that keeps nothing: parsing for the tree alone.
pub struct NoSink;

impl StatementSink for NoSink {
    fn statement(&mut self, _: &[u8], _: &Arena, _: &Stmt, _: Span) {}
}

/// The result of parsing: the tree, what went wrong, and how many opaque nodes it holds.
#[derive(Clone, Debug, Default)]
pub struct Parse {
    pub tree: Tree,
    pub diagnostics: Vec<Diagnostic>,
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
pub fn parse(src: &[u8], sink: &mut dyn StatementSink) -> Parse {
    if src.len() > u32::MAX as usize {
        let mut tree = Tree::default();
        tree.nodes.push(Node {
            kind: NodeKind::Root,
            start: 0,
            end: 0,
            subtree_end: 2,
        });
        tree.nodes.push(Node {
            kind: NodeKind::Opaque,
            start: 0,
            end: 0,
            subtree_end: 2,
        });
        return Parse {
            tree,
            diagnostics: vec![
                Diagnostic::error(Span::new(0, 0), "file larger than 4 GiB; not parsed")
                    .with_hint("split the module"),
            ],
            opaque: 1,
        };
    }
    let mut p = Parser::new(src, sink);
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
    nodes: Vec<Node>,
    /// End of the last leaf pushed: bytes between it and the next leaf are trivia.
    leaf_end: u32,
    diagnostics: Vec<Diagnostic>,
    opaque: usize,
    arena: Arena,
    depth: u32,
    /// The unknown token already reported as the cause of an error (not reported twice).
    reported_unknown: Option<u32>,
    /// Use [`Parser::numeric_aggregate`] (off only in tests that compare it with the general
    /// path).
    fast_aggregates: bool,
    sink: &'s mut dyn StatementSink,
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

impl<'a, 's> Parser<'a, 's> {
    fn new(src: &'a [u8], sink: &'s mut dyn StatementSink) -> Parser<'a, 's> {
        let mut p = Parser {
            src,
            lex: Lexer::new(src),
            tok: Token {
                kind: TokenKind::Eof,
                keyword: false,
                start: 0,
                end: 0,
            },
            peeked: None,
            prev_end: 0,
            // About two leaves per statement; robtarget files average ~45 bytes per leaf, so
            // this avoids doubling (and a second copy) for typical modules.
            nodes: Vec::with_capacity(src.len() / 40 + 4),
            leaf_end: 0,
            diagnostics: Vec::new(),
            opaque: 0,
            arena: Arena::default(),
            depth: 0,
            reported_unknown: None,
            fast_aggregates: true,
            sink,
        };
        p.nodes.push(Node {
            kind: NodeKind::Root,
            start: 0,
            end: 0,
            subtree_end: 1,
        });
        p.tok = p.next_significant();
        p
    }

    fn finish(mut self) -> Parse {
        let end = self.src.len() as u32;
        self.flush_trivia(end);
        self.close(0);
        Parse {
            tree: Tree { nodes: self.nodes },
            diagnostics: self.diagnostics,
            opaque: self.opaque,
        }
    }

    // ---- tokens -------------------------------------------------------------------------

    fn next_significant(&mut self) -> Token {
        loop {
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
            self.tok = match self.peeked.take() {
                Some((next, lex)) => {
                    self.lex = lex;
                    next
                }
                None => self.next_significant(),
            };
        }
        t
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

    // ---- tree building ------------------------------------------------------------------

    fn flush_trivia(&mut self, upto: u32) {
        if upto > self.leaf_end {
            self.nodes.push(Node {
                kind: NodeKind::Trivia,
                start: self.leaf_end,
                end: upto,
                subtree_end: self.nodes.len() as u32 + 1,
            });
            self.leaf_end = upto;
        }
    }

    /// Pushes a leaf from `start` to the end of the last consumed token.
    fn leaf(&mut self, kind: NodeKind, start: u32) {
        let end = self.prev_end.max(start);
        self.flush_trivia(start);
        self.nodes.push(Node {
            kind,
            start,
            end,
            subtree_end: self.nodes.len() as u32 + 1,
        });
        self.leaf_end = end;
    }

    fn open(&mut self, kind: NodeKind, start: u32) -> usize {
        self.flush_trivia(start);
        let idx = self.nodes.len();
        self.nodes.push(Node {
            kind,
            start,
            end: start,
            subtree_end: idx as u32 + 1,
        });
        idx
    }

    fn close(&mut self, idx: usize) {
        let len = self.nodes.len() as u32;
        let end = self.leaf_end;
        if let Some(n) = self.nodes.get_mut(idx) {
            n.subtree_end = len;
            n.end = end.max(n.start);
        }
    }

    fn emit(&mut self, stmt: Stmt, start: u32) {
        let span = Span::new(start as usize, self.prev_end as usize);
        self.sink.statement(self.src, &self.arena, &stmt, span);
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

    // ---- file, module, items ------------------------------------------------------------

    /// `file = [ BOM ] { header_line } { module | item } EOF`
    fn file(&mut self) {
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

    fn is_item_start(&self) -> bool {
        self.at_any(&[
            b"CONST", b"PERS", b"VAR", b"LOCAL", b"TASK", b"PROC", b"FUNC", b"TRAP", b"RECORD",
            b"ALIAS",
        ])
    }

    /// `module = "MODULE" ident [ "(" attribute { "," attribute } ")" ] { item } "ENDMODULE"`
    fn module(&mut self) {
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
    fn item(&mut self, module_scope: bool) {
        let start = self.tok.start;
        self.arena.clear();
        if self.tok.kind == TokenKind::Placeholder {
            self.bump();
            self.eat_punct(b';');
            self.leaf(NodeKind::Placeholder, start);
            return;
        }
        let second = self.peek2();
        let second_text = second.text(self.src);
        let prefixed = self.at_any(&[b"LOCAL", b"TASK"]);
        let kw_is = |words: &[&[u8]]| {
            if prefixed {
                second.keyword && is_word_in(second_text, words)
            } else {
                false
            }
        };
        if self.at_any(&[b"CONST", b"PERS", b"VAR", b"ALIAS"])
            || kw_is(&[b"CONST", b"PERS", b"VAR"])
        {
            self.data_decl(start, module_scope);
        } else if self.at_any(&[b"PROC", b"FUNC", b"TRAP"]) || kw_is(&[b"PROC", b"FUNC", b"TRAP"]) {
            self.routine(start);
        } else if self.at_kw(b"RECORD") {
            self.record(start);
        } else {
            self.unknown_item(start);
        }
    }

    /// `data_decl = [ "LOCAL" | "TASK" ] ( "CONST" | "PERS" | "VAR" ) type ident [ dims ]
    ///              [ ":=" expr ] ";" | "ALIAS" type ident ";"`
    fn data_decl(&mut self, start: u32, module_scope: bool) {
        match self.data_decl_inner(module_scope) {
            Ok(stmt) => {
                self.leaf(NodeKind::DataDecl, start);
                self.emit(stmt, start);
            }
            Err(e) => self.recover(start, e),
        }
    }

    fn data_decl_inner(&mut self, module_scope: bool) -> PResult<Stmt> {
        if self.at_any(&[b"LOCAL", b"TASK"]) {
            self.bump();
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
        if self.tok.kind == TokenKind::Assign {
            self.bump();
            init = Some(self.expr()?);
        }
        self.expect_punct(b';', "`;` at the end of the declaration")?;
        Ok(Stmt::Decl {
            storage,
            type_name: ty.span(),
            name: name.span(),
            dims,
            init,
            module_scope,
        })
    }

    /// `record = "RECORD" ident { type ident ";" } "ENDRECORD"`
    fn record(&mut self, start: u32) {
        let branch = self.open(NodeKind::Record, start);
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
    ///            | "TRAP" ident ) body { handler } end_routine`
    fn routine(&mut self, start: u32) {
        let branch = self.open(NodeKind::Routine, start);
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
        let head: PResult<Span> = (|| {
            if kind == b"FUNC" {
                self.expect_ident("the return type after FUNC")?;
            }
            let name = self.expect_ident("a routine name")?;
            if kind != b"TRAP" {
                self.params()?;
            }
            Ok(name.span())
        })();
        match head {
            Ok(name) => {
                self.leaf(NodeKind::RoutineHead, start);
                self.arena.clear();
                self.emit(Stmt::Routine { name }, start);
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
    fn params(&mut self) -> PResult<()> {
        self.expect_punct(b'(', "`(` before the parameter list")?;
        let mut depth = 1u32;
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
            self.bump();
            if c == b'(' {
                depth += 1;
            } else if c == b')' {
                depth -= 1;
                if depth == 0 {
                    return Ok(());
                }
            }
        }
    }

    // ---- statements ---------------------------------------------------------------------

    /// `statements = { statement }`, up to one of `ends` or a keyword that closes an outer block.
    fn statements(&mut self, ends: &[&[u8]]) {
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
    fn statement(&mut self) {
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

    /// `simple = jump | label | placeholder | late_call | assignment | call` (one leaf).
    fn simple_statement(&mut self) -> PResult<(NodeKind, Stmt)> {
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
    fn late_call(&mut self) -> PResult<(NodeKind, Stmt)> {
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
    fn call_args(&mut self, start: u32) -> PResult<u32> {
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
    fn arg(&mut self) -> PResult<u32> {
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
    fn if_stmt(&mut self, start: u32) {
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

    fn block_body(&mut self, ends: &[&[u8]]) {
        self.statements(ends);
    }

    /// The closing keyword of a block, or a located error naming the block's opening keyword.
    fn block_end(&mut self, end_kw: &'static [u8], opener: Token) {
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
    fn for_stmt(&mut self, start: u32) {
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
    fn while_stmt(&mut self, start: u32) {
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

    fn loop_rest(
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
    fn test_stmt(&mut self, start: u32) {
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

    /// Fast path of `aggregate` for the shape that makes up most of a robtarget file:
    /// brackets, commas, numbers with an attached sign, spaces and newlines — nothing else.
    /// It builds exactly the nodes the general path would, straight from the bytes; on anything
    /// else it undoes its nodes and returns `None`, and the general path reads the aggregate.
    fn numeric_aggregate(&mut self) -> Option<u32> {
        const MAX: usize = 16;
        let src = self.src;
        let mark = self.arena.nodes.len();
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
                    let digits = if matches!(b, b'-' | b'+') { i + 1 } else { i };
                    let rest = src.get(digits..).unwrap_or(&[]);
                    let starts_number = match rest.first() {
                        Some(c) if c.is_ascii_digit() => true,
                        Some(b'.') => rest.get(1).is_some_and(u8::is_ascii_digit),
                        _ => false,
                    };
                    if !starts_number {
                        break false;
                    }
                    let end = digits + super::lexer::number_len(rest);
                    // The next byte must end the token the way the lexer would end it.
                    if src
                        .get(end)
                        .is_some_and(|c| c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.'))
                    {
                        break false;
                    }
                    let id = self.arena.open(ExprKind::Num, i as u32);
                    self.arena.close(id, end as u32);
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
            self.arena.nodes.truncate(mark);
            return None;
        }
        self.lex.seek(i);
        self.peeked = None;
        self.prev_end = i as u32;
        self.tok = self.next_significant();
        Some(root)
    }

    // ---- expressions --------------------------------------------------------------------

    /// `expr = unary { binop unary }` with
    /// `binop = "+" | "-" | "*" | "/" | "=" | "<" | ">" | "<=" | ">=" | "<>" | "DIV" | "MOD"
    ///        | "AND" | "OR" | "XOR"`. Precedence does not matter to trackfix and is not kept.
    fn expr(&mut self) -> PResult<u32> {
        self.nested("a less deeply nested expression", Self::expr_inner)
    }

    /// Runs `parse` one level deeper, refusing (with `expected`) past `MAX_DEPTH` so that
    /// hostile nesting is an error, not a stack overflow.
    fn nested(
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

    fn expr_inner(&mut self) -> PResult<u32> {
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

    fn at_binop(&self) -> bool {
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
    fn unary(&mut self) -> PResult<u32> {
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
    fn operator_applied(&mut self, start: u32) -> PResult<u32> {
        let id = self.arena.open(ExprKind::Compound, start);
        let inner = self.nested("fewer stacked unary operators", Self::unary)?;
        self.arena.link(id, NONE, inner);
        self.arena.close(id, self.prev_end);
        Ok(id)
    }

    /// `postfix = primary { "{" expr { "," expr } "}" | "." ident }`
    fn postfix(&mut self) -> PResult<u32> {
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
    fn primary(&mut self) -> PResult<u32> {
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
                if self.fast_aggregates
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

    /// The expression nodes and the following token, read with or without the fast path.
    fn read(src: &[u8], fast: bool) -> (Vec<super::super::expr::ExprNode>, Option<Token>) {
        let mut sink = NoSink;
        let mut p = Parser::new(src, &mut sink);
        p.fast_aggregates = fast;
        match p.expr() {
            Ok(_) => (p.arena.nodes.clone(), Some(p.tok)),
            Err(_) => (Vec::new(), None),
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
