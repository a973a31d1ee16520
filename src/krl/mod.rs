//! KUKA KRL: lossless lexer, parser and printer for `.src`/`.dat`/`.sub` files and
//! `$config.dat`, and the positions found in a program.
//!
//! Owned by issue 3. Grammar: `grammars/krl.ebnf`.

use std::path::Path;

use crate::position::{Language, ParsedFile, Program};
use crate::program::{LoadError, LoadOptions, read_source};
use crate::syntax::LineIndex;

/// Parses one KRL file on its own (no pair, no `$config.dat`). Never fails: what the grammar
/// does not know is kept verbatim and reported in the file's diagnostics.
pub fn parse_file(path: &Path, source: Vec<u8>) -> ParsedFile {
    ParsedFile {
        path: path.to_owned(),
        language: Language::Krl,
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

/// Loads the program `path` belongs to: naming the `.src` or the `.dat` loads both when both
/// exist; a lone file loads alone.
pub fn load_program(path: &Path, _options: &LoadOptions) -> Result<Program, LoadError> {
    let source = read_source(path)?;
    Ok(Program {
        files: vec![parse_file(path, source)],
    })
}
