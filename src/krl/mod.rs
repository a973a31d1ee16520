//! KUKA KRL: lossless lexer, parser and printer for `.src`/`.dat`/`.sub` files and
//! `$config.dat`, and the positions found in a program.
//!
//! Grammar: `grammars/krl.ebnf`.
//!
//! - `lexer` ([`lex`]): bytes → `(kind, u32 span)` tokens covering every byte;
//! - `parser` ([`parse`], [`parse_with`]) and `tree` ([`NodeKind`], [`Stmt`]): the shared [`crate::syntax::Tree`] with one leaf per line under
//!   routine and block branches, statements for what trackfix reads, opaque
//!   nodes with located diagnostics for the rest; `tree.print(src) == src`;
//! - `positions`: targets, joint positions, `BASE_DATA`/`TOOL_DATA` into the shared model;
//! - `resolve`: the base and tool of every motion over a `.src`/`.dat` pair;
//! - [`load_program`] (the pair; [`load_program_from_sources`] from bytes in memory),
//!   [`load_config_dat`] (bases and tools of a `$config.dat`).
//!
//! ```
//! let src = b"DEF a()\r\n  LIN {X 10, Y 20, Z 30, A 0, B 90, C 0} C_DIS ; go\r\nEND";
//! let parse = trackfix::krl::parse(src);
//! assert_eq!(parse.tree.print(src), src);
//! ```

mod config_dat;
mod dat_line;
pub(crate) mod lexer;
mod pair;
pub(crate) mod parser;
mod positions;
mod resolve;
pub(crate) mod tree;

use std::path::Path;

pub use config_dat::{ConfigDatOnce, config_frames, load_config_dat};
pub use lexer::{Token, TokenKind, lex};
pub use pair::{load_program, load_program_from_sources, partner_of};
pub use parser::{MOTION_KEYWORDS, Parse, parse, parse_with};
pub use tree::{
    Aggregate, DeclVar, Expr, ExprKind, Field, Krl, Node, NodeKind, Stmt, StmtKind, Tree,
};

use crate::output::InputBytes;
use crate::position::{Language, ParsedFile};
use crate::syntax::LineIndex;

/// Parses one KRL file on its own (no pair, no `$config.dat`). Never fails: what the grammar
/// does not know is kept verbatim and reported in the file's diagnostics. Bases and tools are
/// resolved from this file alone; [`load_program`] resolves them over the `.src`/`.dat` pair.
pub fn parse_file(path: &Path, source: impl Into<InputBytes>) -> ParsedFile {
    let (file, facts) = analyse(path, source.into());
    let mut files = [file];
    let mut facts = [facts];
    resolve::resolve(&mut files, &mut facts, &[]);
    let [file] = files;
    file
}

/// Parses a file and extracts what it holds, before resolution.
fn analyse(path: &Path, source: InputBytes) -> (ParsedFile, positions::Facts) {
    let lines = LineIndex::new(&source);
    let mut extractor = positions::Extractor::new(&source, &lines);
    // The tree is not kept: only its round trip is needed here (checked as it is built), and
    // a `DEF`/`DEFDAT` line is seen as its routine statement.
    let mut has_routine = false;
    let parse = parser::parse_streamed(&source, &mut |stmt: tree::Stmt| {
        has_routine |= matches!(stmt.kind, tree::StmtKind::Routine { .. });
        extractor.statement(&stmt)
    });
    let (extracted, notes) = extractor.finish();
    let round_trip = parse.round_trip;
    let mut diagnostics = parse.diagnostics;
    diagnostics.extend(notes);
    if !has_routine {
        let at = lexer::Lexer::new(&source)
            .find(|t| !t.kind.is_trivia())
            .map_or(crate::syntax::Span::new(0, 0), |t| t.span());
        diagnostics.insert(
            0,
            crate::syntax::Diagnostic::warning(at, "no `DEF` or `DEFDAT` in this file")
                .with_hint("a KRL module is `DEF name( )` … `END` or `DEFDAT name` … `ENDDAT`, after its `&` header lines"),
        );
    }
    let file = ParsedFile {
        path: path.to_owned(),
        language: Language::Krl,
        lines,
        source,
        positions: extracted.positions,
        frames: extracted.frames,
        frame_values: Vec::new(),
        offsets: Vec::new(),
        opaque: parse.opaque,
        diagnostics,
        round_trip,
    };
    (file, extracted.facts)
}
