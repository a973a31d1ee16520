//! A program written under a new file name: languages whose main routine must carry the file's
//! name (KRL: `DEF spot_line(` in `spot_line.src`, `DEFDAT spot_line` in `spot_line.dat`) get
//! the header renamed to the new stem, or the new name is refused.

use std::path::{Path, PathBuf};

use super::edits::ProgramResult;
use super::stamp::header_name;

/// One header renamed.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Renamed {
    /// The file whose header was renamed.
    pub path: PathBuf,
    /// The name the `DEF`/`DEFDAT` had.
    pub from: String,
    /// The name it has now: the output file's stem.
    pub to: String,
}

/// Why a program cannot be written under a new name.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("{}: `{stem}` cannot be the name of a {language} program (its DEF/DEFDAT must be the file's name: a letter or `_` first, then letters, digits or `_`, at most {max} characters); choose another output name", path.display())]
pub struct RenameError {
    /// The output file.
    pub path: PathBuf,
    /// Its stem, which cannot be a program name.
    pub stem: String,
    /// The language's name, for the message.
    pub language: &'static str,
    /// The longest program name the language allows.
    pub max: usize,
}

/// KRL names: at most 24 characters (KSS limit for routine and data-list names).
const MAX_NAME: usize = 24;

fn is_name(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && s.len() <= MAX_NAME
}

/// Renames the header of every file of `result` named like its first file to `new_stem`, when
/// its language needs the two to agree. Returns what was renamed.
pub fn rename_program(
    result: &mut ProgramResult,
    new_stem: &str,
) -> Result<Vec<Renamed>, RenameError> {
    let Some(first) = result.files.first().map(|f| f.path.clone()) else {
        return Ok(Vec::new());
    };
    let stem = |p: &Path| p.file_stem().map(|s| s.to_string_lossy().into_owned());
    if stem(&first).as_deref() == Some(new_stem) {
        return Ok(Vec::new());
    }
    let mut renamed = Vec::new();
    for f in &mut result.files {
        let Some(dialect) = crate::dialect::dialect_of(&f.path) else {
            continue;
        };
        if !dialect.names_follow_file() || stem(&f.path) != stem(&first) {
            continue;
        }
        if !is_name(new_stem) {
            return Err(RenameError {
                path: f.path.clone(),
                stem: new_stem.to_owned(),
                language: dialect.name(),
                max: MAX_NAME,
            });
        }
        let Some(h) = header_name(&f.output, dialect.header_keywords()) else {
            continue;
        };
        if h.name.is_empty() {
            continue;
        }
        let from = crate::syntax::latin1(h.name.slice(&f.output));
        if from == new_stem {
            continue;
        }
        let mut out = f.output[..h.name.start].to_vec();
        out.extend_from_slice(new_stem.as_bytes());
        out.extend_from_slice(&f.output[h.name.end..]);
        f.output = out;
        // The edits' precision record no longer describes the output.
        f.widened = None;
        renamed.push(Renamed {
            path: f.path.clone(),
            from,
            to: new_stem.to_owned(),
        });
    }
    Ok(renamed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::FileResult;

    fn file(path: &str, text: &str) -> FileResult {
        FileResult {
            path: PathBuf::from(path),
            original: text.as_bytes().to_vec().into(),
            output: text.as_bytes().to_vec(),
            refusals: Vec::new(),
            notes: Vec::new(),
            changes: Default::default(),
            widened: None,
            kept: Vec::new(),
        }
    }

    #[test]
    fn krl_headers_take_the_new_stem_and_rapid_is_left_alone() {
        let mut r = ProgramResult {
            files: vec![
                file(
                    "in/spot_line.src",
                    "&ACCESS RVP\nDEF spot_line( )\n  PTP XP1\nEND\n",
                ),
                file("in/spot_line.dat", "DEFDAT  spot_line PUBLIC\nENDDAT\n"),
                file("in/$config.dat", "DEFDAT  $CONFIG\nENDDAT\n"),
            ],
        };
        let renamed = rename_program(&mut r, "side_b").unwrap();
        assert_eq!(renamed.len(), 2);
        assert_eq!(renamed[0].from, "spot_line");
        assert_eq!(
            r.files[0].output,
            b"&ACCESS RVP\nDEF side_b( )\n  PTP XP1\nEND\n"
        );
        assert_eq!(r.files[1].output, b"DEFDAT  side_b PUBLIC\nENDDAT\n");
        assert_eq!(r.files[2].output[..], r.files[2].original[..]);
        let mut m = ProgramResult {
            files: vec![file("a.mod", "MODULE a\nENDMODULE\n")],
        };
        assert_eq!(rename_program(&mut m, "b").unwrap(), Vec::new());
        let e = rename_program(&mut r, "2-bad").unwrap_err();
        assert!(
            e.to_string()
                .contains("`2-bad` cannot be the name of a krl program")
        );
    }
}
