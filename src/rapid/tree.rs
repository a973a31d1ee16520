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

use crate::syntax::Span;

/// What a node is. Branches: [`NodeKind::Root`], [`NodeKind::Module`], [`NodeKind::Routine`],
/// [`NodeKind::Record`], [`NodeKind::If`], [`NodeKind::For`], [`NodeKind::While`],
/// [`NodeKind::Test`], [`NodeKind::CompactIf`], [`NodeKind::Handler`]. Everything else is a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeKind {
    Root,
    /// Whitespace, newlines and comments between two other leaves (or a BOM).
    Trivia,
    /// One `%%%` header line.
    Header,
    Module,
    /// `MODULE name (attributes)`
    ModuleHead,
    ModuleEnd,
    /// `[LOCAL|TASK] CONST|PERS|VAR type name [{dims}] [:= value];` and `ALIAS`.
    DataDecl,
    Record,
    RecordHead,
    RecordField,
    RecordEnd,
    Routine,
    /// `[LOCAL] PROC name (params)`, `FUNC type name (params)`, `TRAP name`.
    RoutineHead,
    /// `ERROR [(errnos)]`, `UNDO`, `BACKWARD` and the statements after it.
    Handler,
    HandlerHead,
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
    If,
    /// `IF cond THEN`, `ELSEIF cond THEN`, `ELSE`, `ENDIF`.
    IfPart,
    /// `IF cond statement` (one simple statement, no ENDIF).
    CompactIf,
    CompactIfHead,
    For,
    /// `FOR i FROM a TO b [STEP c] DO`, `ENDFOR`.
    ForPart,
    While,
    WhilePart,
    Test,
    /// `TEST expr`, `CASE a, b:`, `DEFAULT:`, `ENDTEST`.
    TestPart,
    /// A construct the grammar does not know or could not read, kept verbatim.
    Opaque,
}

impl NodeKind {
    pub fn is_branch(self) -> bool {
        matches!(
            self,
            NodeKind::Root
                | NodeKind::Module
                | NodeKind::Routine
                | NodeKind::Record
                | NodeKind::Handler
                | NodeKind::If
                | NodeKind::CompactIf
                | NodeKind::For
                | NodeKind::While
                | NodeKind::Test
        )
    }
}

/// One node: its kind, its bytes, and (for branches) where its subtree ends in [`Tree::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    pub kind: NodeKind,
    pub start: u32,
    pub end: u32,
    /// Index one past this node's last descendant (`self + 1` for a leaf).
    pub subtree_end: u32,
}

impl Node {
    pub fn span(&self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }
}

/// A parsed RAPID source: nodes in pre-order, the root first.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tree {
    pub nodes: Vec<Node>,
}

impl Tree {
    /// The source again, from the leaves. Equal to the input for every input.
    pub fn print(&self, src: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(src.len());
        for n in self.nodes.iter().filter(|n| !n.kind.is_branch()) {
            out.extend_from_slice(n.span().slice(src));
        }
        out
    }

    /// Writes the leaves in order to `out` (printing a large file without a second copy).
    pub fn write_to(&self, src: &[u8], out: &mut impl std::io::Write) -> std::io::Result<()> {
        for n in self.nodes.iter().filter(|n| !n.kind.is_branch()) {
            out.write_all(n.span().slice(src))?;
        }
        Ok(())
    }

    /// True if printing gives `src` back, compared leaf by leaf without building the copy.
    pub fn prints_back(&self, src: &[u8]) -> bool {
        let mut pos = 0usize;
        for n in self.nodes.iter().filter(|n| !n.kind.is_branch()) {
            let text = n.span().slice(src);
            if n.start as usize != pos && src.get(pos..pos + text.len()) != Some(text) {
                return false;
            }
            pos += text.len();
        }
        pos == src.len()
    }

    /// One line per node, indented by depth: kind, byte range and (for leaves) the text with
    /// control bytes escaped. For snapshot tests, in the spirit of rust-analyzer's test_data.
    pub fn dump(&self, src: &[u8]) -> String {
        let mut out = String::new();
        let mut stack: Vec<u32> = Vec::new();
        for (i, n) in self.nodes.iter().enumerate() {
            while stack.last().is_some_and(|&end| end as usize <= i) {
                stack.pop();
            }
            out.push_str(&"  ".repeat(stack.len()));
            out.push_str(&format!("{:?}@{}..{}", n.kind, n.start, n.end));
            if n.kind.is_branch() {
                stack.push(n.subtree_end);
            } else {
                out.push(' ');
                out.push_str(&escape(n.span().slice(src)));
            }
            out.push('\n');
        }
        out
    }
}

/// Bytes as a quoted, escaped string: ASCII graphic as is, everything else `\xNN`/`\r`/`\n`.
pub fn escape(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() + 2);
    s.push('"');
    for &b in bytes {
        match b {
            b'\n' => s.push_str("\\n"),
            b'\r' => s.push_str("\\r"),
            b'\t' => s.push_str("\\t"),
            b'"' => s.push_str("\\\""),
            b'\\' => s.push_str("\\\\"),
            0x20..=0x7E => s.push(b as char),
            _ => s.push_str(&format!("\\x{b:02X}")),
        }
    }
    s.push('"');
    s
}
