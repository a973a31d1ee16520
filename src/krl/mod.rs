//! KUKA KRL: lossless lexer, parser and printer for `.src`/`.dat`/`.sub` files and
//! `$config.dat`, and the positions found in a program.
//!
//! Owned by issue 3. Grammar: `grammars/krl.ebnf`.
//!
//! ```
//! let src = b"DEF a()\r\n  LIN {X 10, Y 20, Z 30, A 0, B 90, C 0} C_DIS ; go\r\nEND";
//! let parse = trackfix::krl::parse(src);
//! assert_eq!(parse.tree.print(src), src);
//! ```

mod config_dat;
pub mod lexer;
mod pair;
pub mod parser;
mod positions;
pub mod tree;

use std::path::Path;

pub use config_dat::{config_frames, load_config_dat};
pub use pair::{load_program, partner_of};
pub use parser::{Parse, parse};

use crate::position::{Language, ParsedFile};
use crate::syntax::LineIndex;

/// Parses one KRL file on its own (no pair, no `$config.dat`). Never fails: what the grammar
/// does not know is kept verbatim and reported in the file's diagnostics. Bases and tools are
/// resolved from this file alone; [`load_program`] resolves them over the `.src`/`.dat` pair.
pub fn parse_file(path: &Path, source: Vec<u8>) -> ParsedFile {
    let (file, facts) = analyse(path, source);
    let mut files = [file];
    let mut facts = [facts];
    positions::resolve(&mut files, &mut facts);
    let [file] = files;
    file
}

/// Parses a file and extracts what it holds, before resolution.
fn analyse(path: &Path, source: Vec<u8>) -> (ParsedFile, positions::Facts) {
    let parse = parser::parse(&source);
    let lines = LineIndex::new(&source);
    let round_trip = parse.tree.print(&source) == source;
    let mut diagnostics = parse.diagnostics;
    let extracted = positions::extract(&source, &parse.tree, &lines, &mut diagnostics);
    let file = ParsedFile {
        path: path.to_owned(),
        language: Language::Krl,
        lines,
        source,
        positions: extracted.positions,
        frames: extracted.frames,
        offsets: Vec::new(),
        opaque: parse.opaque,
        diagnostics,
        round_trip,
    };
    (file, extracted.facts)
}
