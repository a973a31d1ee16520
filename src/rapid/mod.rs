//! ABB RAPID: lossless lexer, parser and printer, and the positions found in a module.
//!
//! Grammar: `grammars/rapid.ebnf`. The tree is the shared [`crate::syntax::Tree`]; this folder
//! holds RAPID's lexer rules ([`tokenize`]), grammar (`parser`, [`parse_tree`]), node kinds
//! ([`NodeKind`]) and extraction.
//!
//! ```
//! use std::path::{Path, PathBuf};
//! let src = b"MODULE m\r\n  CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\r\nENDMODULE".to_vec();
//! let file = trackfix::rapid::parse_file(Path::new("m.mod"), src.clone());
//! assert!(file.round_trip);
//! assert_eq!(trackfix::rapid::print(&src), src);
//! assert_eq!(file.positions.len(), 1);
//! ```

pub(crate) mod expr;
pub(crate) mod flow;
pub(crate) mod lexer;
pub(crate) mod parser;
pub mod positions;
pub(crate) mod tree;

use std::path::{Path, PathBuf};

pub use lexer::{Token, TokenKind, tokenize};
pub use parser::Parse;
pub(crate) use parser::parse;
pub use tree::{Node, NodeKind, Rapid, Tree};

use crate::output::InputBytes;
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
pub fn parse_file(path: &Path, source: impl Into<InputBytes>) -> ParsedFile {
    parse_task(vec![(path.to_owned(), source.into())])
        .pop()
        .unwrap_or_else(|| unreachable_empty(path))
}

fn unreachable_empty(path: &Path) -> ParsedFile {
    ParsedFile {
        path: path.to_owned(),
        language: Language::Rapid,
        lines: LineIndex::new(b""),
        source: InputBytes::default(),
        positions: crate::position::PositionList::new(),
        frames: Vec::new(),
        frame_values: Vec::new(),
        offsets: Vec::new(),
        opaque: 0,
        diagnostics: Vec::new(),
        round_trip: true,
    }
}

/// Parses the modules of one task and resolves their usage together
/// ([`positions::finish_task`]): one [`ParsedFile`] per module, in order.
pub fn parse_task(files: Vec<(PathBuf, InputBytes)>) -> Vec<ParsedFile> {
    let lines: Vec<LineIndex> = files.iter().map(|(_, s)| LineIndex::new(s)).collect();
    // Per module: its round trip, parser diagnostics and opaque count. The tree itself is not
    // kept (its round trip is checked as it is built; on a large module it is 0.4 times the
    // file at the moment memory peaks), only a skeleton of its statements, which the extractor
    // keeps for a module that gives a frame a value (`flow`).
    let mut parsed = Vec::with_capacity(files.len());
    let mut extractors = Vec::with_capacity(files.len());
    for ((path, source), lines) in files.iter().zip(&lines) {
        let mut extractor = positions::Extractor::new(lines);
        let sink = &mut |s: parser::Statement<'_>| extractor.statement(s);
        let p = parser::parse_streamed(source, sink, flow::walked);
        extractor.keep_skeleton(p.tree.nodes);
        parsed.push((p.round_trip, p.diagnostics, p.opaque));
        extractors.push((
            extractor,
            &source[..],
            crate::position::UseLine::file_name(path),
        ));
    }
    let extracted = positions::finish_task(extractors);
    let mut out = Vec::with_capacity(files.len());
    for ((((path, source), lines), (round_trip, mut diagnostics, opaque)), extracted) in
        files.into_iter().zip(lines).zip(parsed).zip(extracted)
    {
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
        out.push(ParsedFile {
            path,
            language: Language::Rapid,
            lines,
            source,
            positions: extracted.positions,
            frames: extracted.frames,
            frame_values: extracted.frame_values,
            offsets: extracted.offsets,
            opaque,
            diagnostics,
            round_trip,
        });
    }
    out
}
