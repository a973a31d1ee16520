//! ABB RAPID: lossless lexer, parser and printer, and the positions found in a module.
//!
//! Owned by issue 2. Grammar: `grammars/rapid.ebnf`.

use std::path::Path;

use crate::position::{Language, ParsedFile};
use crate::syntax::LineIndex;

/// Parses one RAPID module. Never fails: what the grammar does not know is kept verbatim and
/// reported in the file's diagnostics.
pub fn parse_file(path: &Path, source: Vec<u8>) -> ParsedFile {
    ParsedFile {
        path: path.to_owned(),
        language: Language::Rapid,
        lines: LineIndex::new(&source),
        source,
        positions: Vec::new(),
        frames: Vec::new(),
        offsets: Vec::new(),
        opaque: 0,
        diagnostics: Vec::new(),
        round_trip: true,
    }
}
