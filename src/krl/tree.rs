//! The KRL syntax tree: one node per source line (KRL is line oriented), each owning a contiguous
//! run of tokens including its trivia and newline, plus the parsed statements that trackfix
//! reads (declarations, assignments, calls, motions).
//!
//! Nodes are stored flat in source order with their block depth (a pre-order listing of the
//! `DEF … END` / `IF … ENDIF` nesting), so printing is the concatenation of every node's tokens
//! and the round trip holds by construction.

use crate::syntax::{Span, latin1};

/// What a line holds (`grammars/krl.ebnf`, rule `line`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    /// Only whitespace (or nothing) before the newline.
    Blank,
    /// A `;` comment line.
    Comment,
    /// `;FOLD …` (an inline form's `%{PE}%` parameters included), kept verbatim.
    FoldStart,
    /// `;ENDFOLD …`, kept verbatim.
    FoldEnd,
    /// `&ACCESS`, `&REL`, `&PARAM`, `&COMMENT`, `&USER` header lines.
    Header,
    /// `DEF`, `DEFFCT`, `DEFDAT` (optionally `GLOBAL`).
    RoutineStart,
    /// `END`, `ENDFCT`, `ENDDAT`.
    RoutineEnd,
    /// `DECL …`, a `.dat` declaration without `DECL`, `STRUC`, `ENUM`, `SIGNAL`, `EXT` …
    Declaration,
    /// `name = expr`, `name[i].field = expr`.
    Assignment,
    /// `NAME(args)`.
    Call,
    /// `PTP`, `LIN`, `CIRC`, `SPTP`, `SLIN`, `SCIRC`, `SPL` and their `_REL` forms.
    Motion,
    /// `IF`, `FOR`, `WHILE`, `LOOP`, `REPEAT`, `SWITCH`, `SPLINE` … opening a block.
    BlockOpen,
    /// `ELSE`, `CASE`, `DEFAULT`.
    BlockMiddle,
    /// `ENDIF`, `ENDFOR`, `ENDWHILE`, `ENDLOOP`, `UNTIL`, `ENDSWITCH`, `ENDSPLINE`.
    BlockClose,
    /// `WAIT`, `HALT`, `GOTO`, `INTERRUPT`, `TRIGGER` … kept as written.
    Simple,
    /// `LABEL:`.
    Label,
    /// A line the grammar does not know or could not parse: kept verbatim and reported.
    Opaque,
}

impl NodeKind {
    pub fn as_str(self) -> &'static str {
        match self {
            NodeKind::Blank => "blank",
            NodeKind::Comment => "comment",
            NodeKind::FoldStart => "fold",
            NodeKind::FoldEnd => "endfold",
            NodeKind::Header => "header",
            NodeKind::RoutineStart => "routine",
            NodeKind::RoutineEnd => "end",
            NodeKind::Declaration => "decl",
            NodeKind::Assignment => "assign",
            NodeKind::Call => "call",
            NodeKind::Motion => "motion",
            NodeKind::BlockOpen => "block",
            NodeKind::BlockMiddle => "middle",
            NodeKind::BlockClose => "endblock",
            NodeKind::Simple => "simple",
            NodeKind::Label => "label",
            NodeKind::Opaque => "opaque",
        }
    }
}

/// One line: bytes `first..end` of the source (its newline included) and its block depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    pub kind: NodeKind,
    pub first: u32,
    pub end: u32,
    pub depth: u16,
}

/// An expression as far as trackfix needs it: literals and aggregates in detail, the rest as
/// spans.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub span: Span,
    pub kind: ExprKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// A numeric literal, its sign included when written directly in front (`-12.5`).
    Number,
    /// `"text"`.
    Str,
    /// `'B0101'`, `'H1F'`.
    Quoted,
    /// `#BASE`.
    Enum,
    /// A name (`XP1`, `$BASE`, `TRUE`).
    Name,
    /// `{[TYPE:] NAME value, …}`.
    Aggregate(Aggregate),
    /// `base[i, j]`; an empty index (`TOOL_NAME[1,]`) is `None`.
    Index(Box<Expr>, Vec<Option<Expr>>),
    /// `name(args)`.
    Call(Box<Expr>, Vec<Option<Expr>>),
    /// `base.field`.
    Member(Box<Expr>, Span),
    /// `-x`, `NOT x`, `B_NOT x`.
    Unary(Span, Box<Expr>),
    /// `a op b`; `op` is `:` for the geometric operator.
    Binary(Box<Expr>, Span, Box<Expr>),
    /// `(x)`.
    Paren(Box<Expr>),
}

/// A struct literal.
#[derive(Clone, Debug, PartialEq)]
pub struct Aggregate {
    /// `FRAME` in `{FRAME: X 1}`.
    pub type_name: Option<Span>,
    pub fields: Vec<Field>,
}

/// `NAME value` inside an aggregate (`POINT2[] " "` keeps its `[]` out of the name).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: Span,
    pub value: Expr,
}

/// One declared variable: `name[dims] = init`.
#[derive(Clone, Debug, PartialEq)]
pub struct DeclVar {
    pub name: Span,
    pub dims: Vec<Option<Expr>>,
    pub init: Option<Expr>,
}

/// The parsed content of the lines trackfix reads.
#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// `DEF name`, `DEFFCT type name`, `DEFDAT name`.
    Routine {
        keyword: Span,
        name: Option<Span>,
    },
    /// `DECL type a = …, b`.
    Decl {
        type_name: Span,
        vars: Vec<DeclVar>,
    },
    Assign {
        target: Expr,
        value: Expr,
    },
    Call(Expr),
    /// `IF`, `ELSE`, `ENDIF`, `SWITCH`, `CASE`, `DEFAULT`, `ENDSWITCH` (the keyword): where
    /// program order forks and joins, for following the base and tool.
    Branch(Span),
    /// `keyword target` / `keyword aux, target`, then approximation and `WITH` assignments.
    Motion {
        keyword: Span,
        targets: Vec<Expr>,
        with: Vec<(Expr, Expr)>,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// Index of the node (line) in [`Tree::nodes`].
    pub node: u32,
    /// The statement's own text, trivia excluded.
    pub span: Span,
    pub kind: StmtKind,
}

/// A parsed file: its lines and the statements read from them. Tokens are not kept: a line is
/// re-lexed on demand ([`super::lexer::lex`] over [`Tree::node_span`]), which keeps a parsed
/// 50 MB `.dat` at a fraction of its size.
#[derive(Clone, Debug, Default)]
pub struct Tree {
    pub nodes: Vec<Node>,
    pub stmts: Vec<Stmt>,
}

impl Tree {
    /// The bytes of a node, trivia and newline included.
    pub fn node_span(&self, node: &Node) -> Span {
        Span::new(node.first as usize, node.end.max(node.first) as usize)
    }

    /// The source again, from the nodes' spans.
    pub fn print(&self, src: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(src.len());
        for node in &self.nodes {
            out.extend_from_slice(self.node_span(node).slice(src));
        }
        out
    }

    /// One line per node: depth, kind and the line's text (newline excluded), for tests.
    pub fn dump(&self, src: &[u8]) -> String {
        let mut out = String::new();
        for node in &self.nodes {
            let text = self.node_span(node).slice(src);
            let text = text
                .strip_suffix(b"\r\n")
                .or_else(|| text.strip_suffix(b"\n"))
                .or_else(|| text.strip_suffix(b"\r"))
                .unwrap_or(text);
            out.push_str(&format!(
                "{}{} {:?}\n",
                "  ".repeat(node.depth as usize),
                node.kind.as_str(),
                latin1(text)
            ));
        }
        out
    }
}
