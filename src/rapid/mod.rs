//! ABB RAPID: lossless lexer, parser and printer, and the positions found in a module.
//!
//! Grammar: `grammars/rapid.ebnf`. The tree is the shared [`crate::syntax::Tree`]; this folder
//! holds RAPID's lexer rules ([`tokenize`]), grammar (`parser`, [`parse_tree`]), node kinds
//! ([`NodeKind`]) and extraction.
//!
//! ```
//! use std::path::Path;
//! let src = b"MODULE m\r\n  CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\r\nENDMODULE".to_vec();
//! let file = trackfix::rapid::parse_file(Path::new("m.mod"), src.clone());
//! assert!(file.round_trip);
//! assert_eq!(trackfix::rapid::print(&src), src);
//! assert_eq!(file.positions.len(), 1);
//! ```

pub(crate) mod expr;
pub(crate) mod lexer;
pub(crate) mod parser;
pub mod positions;
pub(crate) mod tree;

use std::path::Path;

pub use lexer::{Token, TokenKind, tokenize};
pub use parser::Parse;
pub(crate) use parser::parse;
pub use tree::{Node, NodeKind, Rapid, Tree};

use crate::position::{Language, ParsedFile};
use crate::syntax::{Diagnostic, LineIndex};

/// Parses `src` into its lossless tree only (no positions): the fast path.
pub fn parse_tree(src: &[u8]) -> Parse {
    parse(src, &mut crate::syntax::NoSink)
}

/// `print(parse(src))`: the bytes the tree prints. Equal to `src` for every input.
pub fn print(src: &[u8]) -> Vec<u8> {
    parse_tree(src).tree.print(src)
}

/// Parses one RAPID module. Never fails: what the grammar does not know is kept verbatim and
/// reported in the file's diagnostics.
pub fn parse_file(path: &Path, source: Vec<u8>) -> ParsedFile {
    let lines = LineIndex::new(&source);
    let mut extractor = positions::Extractor::new(&lines, &source);
    let parsed = parse(&source, &mut |s: parser::Statement<'_>| {
        extractor.statement(s.src, s.arena, s.stmt, s.span)
    });
    let extracted = extractor.finish(&source);
    let round_trip = parsed.tree.prints_back(&source);
    let mut diagnostics = parsed.diagnostics;
    if !round_trip {
        diagnostics.push(
            Diagnostic::error(
                crate::syntax::Span::new(0, 0),
                "internal error: the parsed tree does not print back to the file",
            )
            .with_hint("please report this file; trackfix will not rewrite it"),
        );
    }
    diagnostics.extend(extracted.diagnostics);
    diagnostics.sort_by_key(|d| (d.span.start, std::cmp::Reverse(d.severity)));
    ParsedFile {
        path: path.to_owned(),
        language: Language::Rapid,
        lines,
        source,
        positions: extracted.positions,
        frames: extracted.frames,
        offsets: extracted.offsets,
        opaque: parsed.opaque,
        diagnostics,
        round_trip,
    }
}
