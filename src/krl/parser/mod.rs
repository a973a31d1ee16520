//! KRL parser: lines into nodes, statements into [`Stmt`]s. Never fails: a line it does not know
//! or cannot parse becomes an [`NodeKind::Opaque`] node with a located diagnostic.
//!
//! Each function names the `grammars/krl.ebnf` rule it implements.

mod expressions;
mod statements;

use expressions::Cursor;

use super::lexer::{Lexer, Token, TokenKind};
use super::tree::{Aggregate, DeclVar, Expr, ExprKind, Field, Krl, NodeKind, Stmt, StmtKind, Tree};
use crate::syntax::{Diagnostic, Sink, Span, TreeBuilder};

/// The result of parsing one file.
#[derive(Clone, Debug, Default)]
pub struct Parse {
    /// The lossless tree: it prints back the source byte for byte. Empty after a parse that
    /// streams its statements and keeps no tree (loading a program).
    pub tree: Tree,
    /// The tree's leaves cover the source exactly, in order: printing gives it back. Checked
    /// as the leaves are built, also when the tree is not kept.
    pub round_trip: bool,
    /// The statements read, in order (kept by [`parse`]; empty after [`parse_with`], which
    /// streams them to its sink instead).
    pub stmts: Vec<Stmt>,
    /// What could not be read, located; those lines are kept verbatim as opaque nodes.
    pub diagnostics: Vec<Diagnostic>,
    /// Lines kept verbatim because the grammar does not know them or could not parse them.
    pub opaque: usize,
}

/// Motion keywords (rule `motion`). `_REL` forms move relative to the current position.
pub const MOTION_KEYWORDS: &[&str] = &[
    "PTP",
    "LIN",
    "CIRC",
    "SPTP",
    "SLIN",
    "SCIRC",
    "SPL",
    "PTP_REL",
    "LIN_REL",
    "CIRC_REL",
    "SPTP_REL",
    "SLIN_REL",
    "SCIRC_REL",
];

const APPROXIMATION: &[&str] = &["C_DIS", "C_PTP", "C_VEL", "C_ORI", "C_SPL", "C_AUTO"];

const SIMPLE_KEYWORDS: &[&str] = &[
    "WAIT",
    "HALT",
    "CONTINUE",
    "EXIT",
    "GOTO",
    "RETURN",
    "INTERRUPT",
    "TRIGGER",
    "BRAKE",
    "RESUME",
    "ANIN",
    "ANOUT",
    "ON_ERROR_PROCEED",
    "CONST_VEL",
    "TIME_BLOCK",
    "STOP",
    "CONFIRM",
];

const DECL_KEYWORDS: &[&str] = &[
    "STRUC", "ENUM", "SIGNAL", "EXT", "EXTFCT", "EXTP", "EXTFCTP", "IMPORT", "CONST", "CHANNEL",
];

/// Types whose declarations may omit `DECL` (a `.dat` writes `E6POS XP1={…}`, `INT I`).
const PREDEFINED_TYPES: &[&str] = &[
    "INT", "REAL", "BOOL", "CHAR", "FRAME", "POS", "E6POS", "AXIS", "E6AXIS", "SIGNAL",
];

const BINARY_WORDS: &[&str] = &["AND", "OR", "EXOR", "B_AND", "B_OR", "B_EXOR"];

/// Up to 16 bytes of a keyword candidate, upper-cased, without allocating.
#[derive(Clone, Copy)]
struct Word {
    buf: [u8; 16],
    len: usize,
}

impl Word {
    fn of(text: &[u8]) -> Word {
        let mut buf = [0u8; 16];
        let len = if text.len() <= 16 { text.len() } else { 0 };
        for (d, s) in buf.iter_mut().zip(text.iter().take(len)) {
            *d = s.to_ascii_uppercase();
        }
        Word { buf, len }
    }

    /// The upper-cased bytes; compared as bytes, so the hot keyword checks skip UTF-8
    /// validation (every keyword is ASCII).
    fn bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    fn is(&self, kw: &str) -> bool {
        self.bytes() == kw.as_bytes()
    }

    fn is_in(&self, list: &[&str]) -> bool {
        list.iter().any(|k| self.is(k))
    }

    /// As text, for the rare block keywords that are passed on by name.
    fn as_str(&self) -> &str {
        std::str::from_utf8(self.bytes()).unwrap_or("")
    }
}

fn is_kw(src: &[u8], t: Option<&Token>, kw: &str) -> bool {
    t.is_some_and(|t| t.kind == TokenKind::Ident && t.text(src).eq_ignore_ascii_case(kw.as_bytes()))
}

fn is_punct(src: &[u8], t: Option<&Token>, p: &[u8]) -> bool {
    t.is_some_and(|t| t.kind == TokenKind::Punct && t.text(src) == p)
}

/// An error inside a statement: where, what, and what to do.
struct PErr {
    span: Span,
    message: String,
    hint: &'static str,
}

type PResult<T> = Result<T, PErr>;

/// An open block, for keeping `END`s in sync.
#[derive(Clone, Copy)]
struct Open {
    keyword: &'static str,
    span: Span,
    /// The branch ([`NodeKind::Routine`] or [`NodeKind::Block`]) this opener started.
    node: usize,
}

fn closer_of(open: &str) -> &'static str {
    match open {
        "DEF" => "END",
        "DEFFCT" => "ENDFCT",
        "DEFDAT" => "ENDDAT",
        "IF" => "ENDIF",
        "FOR" => "ENDFOR",
        "WHILE" => "ENDWHILE",
        "LOOP" => "ENDLOOP",
        "REPEAT" => "UNTIL",
        "SWITCH" => "ENDSWITCH",
        "SPLINE" | "PTP_SPLINE" => "ENDSPLINE",
        _ => "END",
    }
}

fn static_kw(w: &str) -> Option<&'static str> {
    const ALL: &[&str] = &[
        "DEF",
        "DEFFCT",
        "DEFDAT",
        "IF",
        "FOR",
        "WHILE",
        "LOOP",
        "REPEAT",
        "SWITCH",
        "SPLINE",
        "PTP_SPLINE",
    ];
    ALL.iter().copied().find(|k| *k == w)
}

/// Parser state across lines.
struct LineParser<'a, 'k> {
    src: &'a [u8],
    out: Parse,
    /// Where parsed statements go: kept in the tree by [`parse`], streamed by [`parse_with`].
    sink: &'k mut dyn Sink<Stmt>,
    stack: Vec<Open>,
    folds: Vec<Span>,
    tree: TreeBuilder<Krl>,
    /// Where the line being parsed starts (a block it opens starts there).
    line_start: u32,
    /// The branch the line being parsed closes, closed once the line is in the tree.
    close_after_line: Option<usize>,
}

/// Parses a KRL source (rule `file`) into a tree that keeps its statements. Never fails and
/// never panics.
pub fn parse(src: &[u8]) -> Parse {
    let mut stmts = Vec::new();
    let mut out = parse_with(src, &mut |s: Stmt| stmts.push(s));
    out.stmts = stmts;
    out
}

/// Like [`parse`], but hands each statement to `sink` as soon as it is parsed instead of keeping
/// it (`stmts` stays empty). Reading positions this way keeps memory at the
/// size of the tokens: a 50 MB `.dat` holds millions of aggregate fields.
pub fn parse_with(src: &[u8], sink: &mut dyn Sink<Stmt>) -> Parse {
    // About one node per 60 bytes of a typical `.src`/`.dat` line.
    parse_lines(
        src,
        sink,
        true,
        TreeBuilder::with_capacity(src.len() / 60 + 4),
    )
}

/// [`parse_with`] for a caller that needs only the round trip of the tree, not its nodes
/// ([`Parse::tree`] stays empty).
pub(crate) fn parse_streamed(src: &[u8], sink: &mut dyn Sink<Stmt>) -> Parse {
    parse_lines(src, sink, true, TreeBuilder::verifying())
}

/// The parser, with or without the `.dat` declaration fast path ([`super::dat_line`]); both
/// give the same result, which the fast path's tests check. Rules `line` and `trivia`: one
/// line at a time, trivia kept in the line's node.
pub(super) fn parse_lines(
    src: &[u8],
    sink: &mut dyn Sink<Stmt>,
    fast: bool,
    tree: TreeBuilder<Krl>,
) -> Parse {
    let mut p = LineParser {
        src,
        out: Parse::default(),
        sink,
        stack: Vec::new(),
        folds: Vec::new(),
        tree,
        line_start: 0,
        close_after_line: None,
    };
    if let Some(refused) = crate::syntax::too_large(src) {
        p.out.diagnostics.push(refused);
        p.out.tree = crate::syntax::refused_tree(NodeKind::Opaque);
        p.out.opaque = 1;
        return p.out;
    }
    // One line at a time: the tokens of a line live only while it is parsed, and only the
    // significant ones are kept (trivia matter only on lines without code).
    let mut lexer = Lexer::new(src);
    let mut sig: Vec<Token> = Vec::with_capacity(64);
    let mut fields = Vec::with_capacity(16);
    loop {
        let start = lexer.offset();
        if fast && let Some(line) = super::dat_line::decl_line(src, start, &mut fields) {
            let node = p.tree.len() as u32;
            p.sink.accept(Stmt {
                node,
                span: line.span,
                kind: line.kind,
            });
            p.tree
                .leaf(NodeKind::Declaration, start as u32, line.end as u32);
            if !line.had_newline {
                break;
            }
            lexer.resume_at_line(line.end);
            continue;
        }
        sig.clear();
        let mut comment = None;
        let mut content_end = start;
        let mut had_newline = false;
        for t in lexer.by_ref() {
            if t.kind == TokenKind::Newline {
                had_newline = true;
                break;
            }
            content_end = t.end as usize;
            if !t.kind.is_trivia() {
                sig.push(t);
            } else if t.kind == TokenKind::Comment && comment.is_none() {
                comment = Some(t);
            }
        }
        let end = lexer.offset();
        if end == start {
            break;
        }
        p.line_start = start as u32;
        let kind = if sig.is_empty() {
            p.trivia_line(comment)
        } else {
            p.statement(&sig, Span::new(content_end, content_end))
        };
        p.tree.leaf(kind, start as u32, end as u32);
        if let Some(branch) = p.close_after_line.take() {
            p.tree.close(branch);
        }
        if !had_newline {
            break;
        }
    }
    for open in std::mem::take(&mut p.stack) {
        p.tree.close(open.node);
        p.out.diagnostics.push(
            Diagnostic::error(open.span, format!("`{}` is never closed", open.keyword))
                .with_hint(format!("add `{}` to close it", closer_of(open.keyword))),
        );
    }
    for fold in std::mem::take(&mut p.folds) {
        p.out.diagnostics.push(
            Diagnostic::warning(fold, "`;FOLD` without `;ENDFOLD`")
                .with_hint("add `;ENDFOLD` or the pendant will fold the rest of the file"),
        );
    }
    let built = p.tree.finish(src.len() as u32);
    p.out.tree = built.tree;
    p.out.round_trip = built.round_trip;
    p.out
}

impl<'a> LineParser<'a, '_> {
    /// Rules `trivia_line`, `fold_start` and `fold_end`: blank, comment, fold lines.
    fn trivia_line(&mut self, comment: Option<Token>) -> NodeKind {
        let Some(c) = comment else {
            return NodeKind::Blank;
        };
        let text = c.text(self.src);
        let body = text.get(1..).unwrap_or(&[]);
        let body = trim_start(body);
        if starts_with_ic(body, b"ENDFOLD") {
            if self.folds.pop().is_none() {
                self.out.diagnostics.push(
                    Diagnostic::warning(c.span(), "`;ENDFOLD` without `;FOLD`")
                        .with_hint("remove it or add the matching `;FOLD` line"),
                );
            }
            NodeKind::FoldEnd
        } else if starts_with_ic(body, b"FOLD") {
            self.folds.push(c.span());
            NodeKind::FoldStart
        } else {
            NodeKind::Comment
        }
    }

    fn cursor<'s>(&self, sig: &'s [Token], eol: Span) -> Cursor<'s>
    where
        'a: 's,
    {
        Cursor {
            src: self.src,
            toks: sig,
            pos: 0,
            eol,
            depth: 0,
        }
    }

    fn error(&mut self, e: PErr) -> NodeKind {
        self.out
            .diagnostics
            .push(Diagnostic::error(e.span, e.message).with_hint(e.hint));
        self.out.opaque += 1;
        NodeKind::Opaque
    }

    fn unknown(&mut self, span: Span, what: String) -> NodeKind {
        self.out.diagnostics.push(
            Diagnostic::warning(span, format!("unknown statement {what}; kept verbatim")).with_hint(
                "trackfix keeps lines it does not know unchanged; check the spelling if this should be KRL",
            ),
        );
        self.out.opaque += 1;
        NodeKind::Opaque
    }
}

fn trim_start(b: &[u8]) -> &[u8] {
    let n = b.iter().take_while(|c| matches!(c, b' ' | b'\t')).count();
    b.get(n..).unwrap_or(&[])
}

fn starts_with_ic(b: &[u8], prefix: &[u8]) -> bool {
    b.get(..prefix.len())
        .is_some_and(|p| p.eq_ignore_ascii_case(prefix))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::Severity;

    fn first_line(p: &Parse) -> NodeKind {
        p.tree.leaves().next().map_or(NodeKind::Root, |n| n.kind)
    }

    fn dump(src: &str) -> String {
        let p = parse(src.as_bytes());
        assert_eq!(p.tree.print(src.as_bytes()), src.as_bytes());
        p.tree.dump(src.as_bytes())
    }

    #[test]
    fn lines_and_depths() {
        let src = "&ACCESS RVP\nDEF a()\n  IF X THEN\n    LIN XP1 C_DIS\n  ELSE\n  ENDIF\nEND";
        assert_eq!(
            dump(src),
            "Root@0..68\n  Header@0..12 \"&ACCESS RVP\\n\"\n  Routine@12..68\n    RoutineStart@12..20 \"DEF a()\\n\"\n    Block@20..65\n      BlockOpen@20..32 \"  IF X THEN\\n\"\n      Motion@32..50 \"    LIN XP1 C_DIS\\n\"\n      BlockMiddle@50..57 \"  ELSE\\n\"\n      BlockClose@57..65 \"  ENDIF\\n\"\n    RoutineEnd@65..68 \"END\"\n"
        );
    }

    #[test]
    fn folds_are_kept_and_balanced() {
        let src = ";FOLD LIN P1;%{PE}%R 8.3.31,%MKUKATPBASIS\nLIN XP1\n;ENDFOLD (x)\n";
        assert_eq!(
            dump(src),
            "Root@0..63\n  FoldStart@0..42 \";FOLD LIN P1;%{PE}%R 8.3.31,%MKUKATPBASIS\\n\"\n  Motion@42..50 \"LIN XP1\\n\"\n  FoldEnd@50..63 \";ENDFOLD (x)\\n\"\n"
        );
        let p = parse(b";ENDFOLD\n;FOLD a\n");
        assert_eq!(p.diagnostics.len(), 2);
    }

    #[test]
    fn lowercase_keywords() {
        let src = "def a()\n  decl e6pos p={x 1}\n  lin p c_dis\nend";
        let p = parse(src.as_bytes());
        assert!(p.diagnostics.is_empty(), "{:?}", p.diagnostics);
        assert_eq!(p.stmts.len(), 3);
    }

    #[test]
    fn declarations() {
        for src in [
            "DECL E6POS XP1={X 1.0,Y 2,Z -3.5,A 0,B 90,C 0,S 6,T 27,E1 100.0}",
            "DECL GLOBAL E6POS XP1={X 1}",
            "GLOBAL DECL FRAME F[5]",
            "E6POS XP1={X 1}",
            "INT I",
            "DECL INT A, B=3, C",
            "CHAR NAME[24]",
            "DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] \" \",TQ_STATE FALSE}",
            "DECL PDAT PPDAT1={VEL 100,ACC 100,APO_DIST 100,APO_MODE #CDIS}",
            "DECL LDAT LCPDAT1={VEL 2,ACC 100,APO_DIST 100,APO_FAC 50.0,ORI_TYP #VAR,CIRC_TYP #BASE,JERK_FAC 50.0,GEAR_JERK 100.0,EXAX_IGN 0}",
            "DECL FRAME F={FRAME: X 1,Y 2}",
            "GLOBAL STRUC MYPOS_T REAL X, Y, INT N",
            "GLOBAL ENUM COLOR_T RED, GREEN",
            "DECL GLOBAL SIGNAL GRIPPER $OUT[3]",
            "DECL POS P={POS: X 1,Y 2,Z 3,A 0,B 0,C 0,S 'B010',T 'B100011'}",
            "DECL MYSTRUC M={A {X 1, Y 2}, B 'H1F'}",
        ] {
            let p = parse(src.as_bytes());
            assert!(p.diagnostics.is_empty(), "{src}: {:?}", p.diagnostics);
            assert_eq!(first_line(&p), NodeKind::Declaration, "{src}");
        }
    }

    #[test]
    fn statements() {
        for (src, kind) in [
            (
                "BASE_DATA[3]={X 1,Y 2,Z 3,A 0,B 0,C 0}",
                NodeKind::Assignment,
            ),
            ("TOOL_NAME[1,]=\"gun\"", NodeKind::Assignment),
            ("$BASE=BASE_DATA[1]", NodeKind::Assignment),
            ("FDAT_ACT=FP1", NodeKind::Assignment),
            ("BAS(#PTP_PARAMS,100)", NodeKind::Call),
            ("P2 = P1 : {X 10, Y 0}", NodeKind::Assignment),
            (
                "LIN {X 10, Y 20, Z 30, A 0, B 90, C 0} C_DIS",
                NodeKind::Motion,
            ),
            ("PTP XP1 C_PTP C_DIS", NodeKind::Motion),
            ("CIRC XA, XB, CA 90 C_ORI", NodeKind::Motion),
            (
                "SLIN XP1 WITH $VEL = SVEL_CP(2.0, , LCPDAT1), $TOOL = STOOL2(FP1), $BASE = SBASE(FP1.BASE_NO) C_SPL",
                NodeKind::Motion,
            ),
            ("LIN_REL {Z -10} #TOOL", NodeKind::Motion),
            ("WAIT SEC 0.5", NodeKind::Simple),
            ("WAIT FOR $IN[1]", NodeKind::Simple),
            (
                "TRIGGER WHEN DISTANCE=0 DELAY=0 DO $OUT[1]=TRUE",
                NodeKind::Simple,
            ),
            (
                "GLOBAL INTERRUPT DECL 3 WHEN $STOPMESS==TRUE DO IR_STOPM()",
                NodeKind::Simple,
            ),
            ("HALT", NodeKind::Simple),
            ("M1:", NodeKind::Label),
            ("$OUT[1] = NOT $IN[2] AND (I > 3)", NodeKind::Assignment),
        ] {
            let p = parse(src.as_bytes());
            assert!(p.diagnostics.is_empty(), "{src}: {:?}", p.diagnostics);
            assert_eq!(first_line(&p), kind, "{src}");
        }
    }

    #[test]
    fn unknown_and_malformed_lines_are_opaque_and_located() {
        let src = b"DEF a()\n  FROB 1 2\n  LIN {X 1, Y\n  @@\nEND\n";
        let p = parse(src);
        assert_eq!(p.opaque, 3);
        assert_eq!(p.tree.print(src), src);
        let sev: Vec<_> = p.diagnostics.iter().map(|d| d.severity).collect();
        assert_eq!(sev, [Severity::Warning, Severity::Error, Severity::Warning]);
        assert_eq!(p.diagnostics[1].span, Span::new(32, 32));
    }

    #[test]
    fn control_structures_stay_in_sync() {
        let src = "GLOBAL DEFFCT REAL half(X:IN)\r\n  DECL REAL X\r\n  RETURN X/2\r\nENDFCT\r\n\
DEF cell( )\r\n  SPLINE WITH $ACC = {CP 2.0}\r\n    SPL XP1\r\n    SLIN XP2\r\n    SCIRC XP3, XP4\r\n  ENDSPLINE\r\n\
  SWITCH N\r\n  CASE 1, 2\r\n    PTP_REL {A1 10}\r\n  DEFAULT\r\n    EXIT\r\n  ENDSWITCH\r\n\
  REPEAT\r\n    N = N + 1\r\n  UNTIL (N > 3) OR $IN[2]\r\n  WHILE $IN[1] == TRUE\r\n    WAIT SEC 0.1\r\n  ENDWHILE\r\n\
  TIME_BLOCK START\r\n  CONST_VEL START = 100 ONSTART\r\n  ANIN ON A = 1.0 * $ANIN[1]\r\n  PULSE($OUT[3], TRUE, 0.5)\r\n\
  ;FOLD PTP P1  Vel= 100 % PDAT1;%{PE}%R 4.1.15,%MKUKATPBASIS,%CMOVE,%VPTP,%P 1:PTP, 2:P1, 3:, 5:100, 7:PDAT1\r\n\
  $BWDSTART = FALSE\r\n  PDAT_ACT=PPDAT1\r\n  BAS (#PTP_DAT )\r\n  FDAT_ACT=FP1\r\n  BAS (#FRAMES )\r\n  PTP  XP1\r\n  ;ENDFOLD\r\n\
  IF half(4.0) > 1 THEN\r\n    GOTO done\r\n  ENDIF\r\n  done:\r\n  HALT\r\nEND\r\n";
        let p = parse(src.as_bytes());
        assert!(p.diagnostics.is_empty(), "{:?}", p.diagnostics);
        assert_eq!(p.opaque, 0);
        assert_eq!(p.tree.print(src.as_bytes()), src.as_bytes());
        // The line holding `text` and the branches around it, innermost first.
        let enclosing = |text: &str| {
            let nodes = &p.tree.nodes;
            let i = nodes.iter().position(|n| {
                !n.kind.is_branch()
                    && String::from_utf8_lossy(n.span().slice(src.as_bytes())).contains(text)
            })?;
            let mut around: Vec<NodeKind> = (1..i)
                .filter(|&b| nodes[b].kind.is_branch() && nodes[b].subtree_end as usize > i)
                .map(|b| nodes[b].kind)
                .collect();
            around.reverse();
            Some((nodes[i].kind, around))
        };
        use NodeKind::{Block, Routine};
        assert_eq!(
            enclosing("SPL XP1"),
            Some((NodeKind::Motion, vec![Block, Routine]))
        );
        assert_eq!(
            enclosing("CASE 1"),
            Some((NodeKind::BlockMiddle, vec![Block, Routine]))
        );
        assert_eq!(
            enclosing("PTP_REL"),
            Some((NodeKind::Motion, vec![Block, Routine]))
        );
        assert_eq!(
            enclosing("UNTIL"),
            Some((NodeKind::BlockClose, vec![Block, Routine]))
        );
        assert_eq!(enclosing("done:"), Some((NodeKind::Label, vec![Routine])));
        assert_eq!(
            enclosing("ENDFCT"),
            Some((NodeKind::RoutineEnd, vec![Routine]))
        );
        assert_eq!(
            enclosing("DEF cell"),
            Some((NodeKind::RoutineStart, vec![Routine]))
        );
    }

    #[test]
    fn simple_values_read_as_the_full_expression_parser_reads_them() {
        let cases = [
            "12.5,", "-12.5}", "- 12.5,", "+3)", "-X,", "#BASE]", "\"s\",", "'B01'}", "XP1,",
            "XP1[2],", "XP1.X}", "NOT B,", "A:B,", "1+2,", "-5", "TRUE", "F(1),",
        ];
        for case in cases {
            let src = case.as_bytes();
            let toks: Vec<Token> = super::super::lexer::lex(src)
                .into_iter()
                .filter(|t| !t.kind.is_trivia())
                .collect();
            let cursor = |toks| Cursor {
                src,
                toks,
                pos: 0,
                eol: Span::new(src.len(), src.len()),
                depth: 0,
            };
            let mut fast = cursor(&toks);
            let mut full = cursor(&toks);
            let a = fast.expr().ok();
            let b = full.binary(0).ok();
            assert_eq!(a, b, "{case}");
            assert_eq!(fast.pos, full.pos, "{case}");
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        for unit in ["(", "{X ", "- ", "NOT "] {
            let src = format!("A = {}1\n", unit.repeat(100_000));
            let p = parse(src.as_bytes());
            assert_eq!(p.opaque, 1, "{unit}");
            assert_eq!(p.diagnostics[0].message, "expression nested too deeply");
            assert_eq!(p.tree.print(src.as_bytes()), src.as_bytes());
        }
    }

    #[test]
    fn block_mismatch_is_reported() {
        let p = parse(b"DEF a()\nIF X THEN\nENDFOR\nEND\nENDIF\n");
        let msgs: Vec<_> = p.diagnostics.iter().map(|d| d.message.as_str()).collect();
        assert_eq!(
            msgs,
            [
                "`ENDFOR` without an open block",
                "`IF` is never closed",
                "`ENDIF` without an open block"
            ]
        );
    }

    /// Every rule of `grammars/krl.ebnf` is cited by the function that implements it, and
    /// every cited rule is in the grammar.
    #[test]
    fn grammar_rules_and_parser_functions_agree() {
        crate::syntax::grammar_check::assert_rules_cited(
            "grammars/krl.ebnf",
            &[
                "src/krl/lexer.rs",
                "src/krl/dat_line.rs",
                "src/krl/parser/mod.rs",
                "src/krl/parser/statements.rs",
                "src/krl/parser/expressions.rs",
            ],
        );
    }

    /// The keyword tables are the grammar's terminals, so a keyword added to one and not the
    /// other fails here.
    #[test]
    fn keyword_tables_are_the_grammar_terminals() {
        use crate::syntax::grammar_check::{read, terminals};
        use std::collections::BTreeSet;
        let ebnf = read("grammars/krl.ebnf");
        let set = |words: &[&str]| words.iter().map(|w| w.to_string()).collect::<BTreeSet<_>>();
        assert_eq!(terminals(&ebnf, "motion_kw"), set(MOTION_KEYWORDS));
        assert_eq!(terminals(&ebnf, "approximation"), set(APPROXIMATION));
        let mut simple = set(SIMPLE_KEYWORDS);
        simple.extend(set(&["GLOBAL", "INTERRUPT", "TRIGGER"]));
        assert_eq!(terminals(&ebnf, "simple"), simple);
        assert_eq!(terminals(&ebnf, "other_decl"), set(DECL_KEYWORDS));
    }
}
