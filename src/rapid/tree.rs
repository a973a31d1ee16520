//! The lossless RAPID syntax tree: nodes hold byte spans, never copies.
//!
//! Nodes are stored in pre-order in one vector. Leaves own bytes (a statement, a declaration, a
//! run of trivia between them); branches (module, routine, IF, ...) only group their children.
//! Printing concatenates the leaves in order, so the round trip is checked, not assumed: a leaf
//! that is lost, duplicated or out of place shows as a difference.
//!
//! Statements are the finest level kept: a 50 MB module must parse in well under 2× its size,
//! which rules out a node per token. Expressions inside a statement are parsed (and their
//! targets, frames and offsets extracted) while the statement is read, in a scratch arena that
//! is reused for the next statement.

/// What a node is. Branches: [`NodeKind::Root`], [`NodeKind::Module`], [`NodeKind::Routine`],
/// [`NodeKind::Record`], [`NodeKind::If`], [`NodeKind::For`], [`NodeKind::While`],
/// [`NodeKind::Test`], [`NodeKind::CompactIf`], [`NodeKind::Handler`]. Everything else is a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    /// The whole module (branch): the root of every tree.
    Root,
    /// Whitespace, newlines and comments between two other leaves (or a BOM).
    Trivia,
    /// One `%%%` header line.
    Header,
    /// `MODULE … ENDMODULE` (branch).
    Module,
    /// `MODULE name (attributes)`
    ModuleHead,
    /// `ENDMODULE`.
    ModuleEnd,
    /// `[LOCAL|TASK] CONST|PERS|VAR type name [{dims}] [:= value];` and `ALIAS`.
    DataDecl,
    /// `RECORD … ENDRECORD` (branch).
    Record,
    /// `RECORD name`.
    RecordHead,
    /// `type name;` inside a record.
    RecordField,
    /// `ENDRECORD`.
    RecordEnd,
    /// `PROC`/`FUNC`/`TRAP … END…` (branch).
    Routine,
    /// `[LOCAL] PROC name (params)`, `FUNC type name (params)`, `TRAP name`.
    RoutineHead,
    /// `ERROR [(errnos)]`, `UNDO`, `BACKWARD` and the statements after it.
    Handler,
    /// The keyword line of a handler (`ERROR [(errnos)]`, `UNDO`, `BACKWARD`).
    HandlerHead,
    /// `ENDPROC`, `ENDFUNC`, `ENDTRAP`.
    RoutineEnd,
    /// `name args;` (procedure call).
    Call,
    /// `%expr% args;` (late-binding procedure call).
    LateCall,
    /// `target := expr;`
    Assign,
    /// `name:`
    Label,
    /// `GOTO`, `RETURN`, `RAISE`, `EXIT`, `RETRY`, `TRYNEXT`, `CONNECT ... WITH ...`.
    Jump,
    /// An editor placeholder statement or item (`<SMT>`, `<DDN>`, ...).
    Placeholder,
    /// `IF … ENDIF` (branch of its parts and statements).
    If,
    /// `IF cond THEN`, `ELSEIF cond THEN`, `ELSE`, `ENDIF`.
    IfPart,
    /// `IF cond statement` (one simple statement, no ENDIF).
    CompactIf,
    /// The `IF cond` of a compact IF.
    CompactIfHead,
    /// `FOR … ENDFOR` (branch).
    For,
    /// `FOR i FROM a TO b [STEP c] DO`, `ENDFOR`.
    ForPart,
    /// `WHILE … ENDWHILE` (branch).
    While,
    /// `WHILE cond DO`, `ENDWHILE`.
    WhilePart,
    /// `TEST … ENDTEST` (branch).
    Test,
    /// `TEST expr`, `CASE a, b:`, `DEFAULT:`, `ENDTEST`.
    TestPart,
    /// A construct the grammar does not know or could not read, kept verbatim.
    Opaque,
}

crate::syntax::language! {
    /// RAPID in the shared tree ([`crate::syntax::Tree`]).
    Rapid: NodeKind, root Root, gap Trivia,
    branches [Root, Module, Routine, Record, Handler, If, CompactIf, For, While, Test]
}
