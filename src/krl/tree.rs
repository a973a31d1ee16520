//! The KRL syntax tree: the shared pre-order tree ([`crate::syntax::Tree`]) whose leaves are
//! source lines (KRL is line oriented), each owning a contiguous run of tokens including its
//! trivia and newline, and whose branches are the `DEF … END` routines and `IF … ENDIF` blocks;
//! plus the parsed statements that trackfix reads (declarations, assignments, calls, motions).

use crate::syntax::Span;

crate::syntax::language! {
    /// KRL in the shared tree ([`crate::syntax::Tree`]): lines are leaves, routines and blocks
    /// branches. Leaves are whole lines, so the builder never sees a gap between two of them.
    Krl: NodeKind, root Root, gap Blank,
    branches [Root, Routine, Block]
}

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
    /// Branch: the whole file.
    Root,
    /// Branch: a `DEF`/`DEFFCT`/`DEFDAT` line, the lines inside and its `END` line.
    Routine,
    /// Branch: a block-opening line, the lines inside and its closing line.
    Block,
}

/// An expression as far as trackfix needs it: literals and aggregates in detail, the rest as
/// spans.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// The expression's bytes, trivia excluded.
    pub span: Span,
    /// What it is.
    pub kind: ExprKind,
}

/// The shapes of [`Expr`] trackfix distinguishes; operators and names are spans of the source.
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
    /// The fields, in written order.
    pub fields: Vec<Field>,
}

/// `NAME value` inside an aggregate (`POINT2[] " "` keeps its `[]` out of the name).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// The field's name (`X`, `S`, `POINT2`).
    pub name: Span,
    /// Its value.
    pub value: Expr,
}

/// One declared variable: `name[dims] = init`.
#[derive(Clone, Debug, PartialEq)]
pub struct DeclVar {
    /// The variable's name.
    pub name: Span,
    /// One entry per written dimension, `None` where it is left empty (`a[,3]`); empty for a
    /// scalar or `a[]`.
    pub dims: Vec<Option<Expr>>,
    /// The initial value after `=`, when written.
    pub init: Option<Expr>,
}

/// The parsed content of the lines trackfix reads.
#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// `DEF name`, `DEFFCT type name`, `DEFDAT name`.
    Routine {
        /// The `DEF`, `DEFFCT` or `DEFDAT` keyword.
        keyword: Span,
        /// The routine's name, when the line has one.
        name: Option<Span>,
        /// Written `GLOBAL`: callable from every module.
        global: bool,
    },
    /// `DECL type a = …, b`.
    Decl {
        /// The data type (`E6POS`, `FRAME`, …).
        type_name: Span,
        /// The variables declared, in order.
        vars: Vec<DeclVar>,
        /// Written `GLOBAL` (before or after `DECL`): seen from every module.
        global: bool,
    },
    /// `target = value`.
    Assign {
        /// The left side (`$BASE`, `XP1.X`, …).
        target: Expr,
        /// The right side.
        value: Expr,
    },
    /// A subroutine call statement (`BAS(#INITMOV, 0)`): the call expression.
    Call(Expr),
    /// `IF`, `ELSE`, `ENDIF`, `SWITCH`, `CASE`, `DEFAULT`, `ENDSWITCH`, a loop's opening and
    /// closing keyword (`FOR`…`ENDFOR`, `WHILE`, `LOOP`, `REPEAT`…`UNTIL`) and `EXIT` (the
    /// keyword): where program order forks, joins and goes round, for following the base and
    /// tool.
    Branch(Span),
    /// `SPLINE` or `PTP_SPLINE` opening a spline block, with its `WITH` assignments, which hold
    /// for every motion in the block.
    SplineBlock {
        /// `WITH name = value` assignments, in order.
        with: Vec<(Expr, Expr)>,
    },
    /// `ENDSPLINE` closing a spline block.
    EndSpline,
    /// `NAME:`, a label a `GOTO` jumps to: program order may arrive there from anywhere.
    Label,
    /// `GOTO NAME`.
    Goto,
    /// `RETURN` or `RETURN value`: a function's value leaves it.
    Return,
    /// `INTERRUPT DECL … DO routine(…)` or `TRIGGER WHEN … DO routine(…)`: a routine run when
    /// an event happens, wherever the program then is.
    Handler,
    /// `keyword target` / `keyword aux, target`, then approximation and `WITH` assignments.
    Motion {
        /// `PTP`, `LIN`, `CIRC`, … (one of [`crate::krl::MOTION_KEYWORDS`]).
        keyword: Span,
        /// The target expressions (two for `CIRC`: auxiliary point, then target).
        targets: Vec<Expr>,
        /// `WITH name = value` assignments, in order.
        with: Vec<(Expr, Expr)>,
    },
}

impl StmtKind {
    /// The statement with `GLOBAL` recorded when `global` (a routine or a declaration; any
    /// other statement as it is).
    pub(crate) fn made_global(mut self, global: bool) -> StmtKind {
        if let StmtKind::Routine { global: g, .. } | StmtKind::Decl { global: g, .. } = &mut self {
            *g |= global;
        }
        self
    }
}

/// One statement trackfix reads: where it is in the tree and what it says. What
/// [`crate::krl::parse_with`] streams to its sink.
#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// Index of the line's node in [`Tree::nodes`].
    pub node: u32,
    /// The statement's own text, trivia excluded.
    pub span: Span,
    /// What it says.
    pub kind: StmtKind,
}
