//! ABB RAPID: modules (`.mod`, `.sys`, …), one file per program; work objects, quaternions,
//! configuration `[cf1, cf4, cf6, cfx]`.

use std::path::{Path, PathBuf};

use crate::position::{Config, PositionKind, Program};
use crate::program::{LoadError, LoadOptions, read_source};
use crate::syntax::Edit;
use crate::transform::rewrite::integer_edit;

use super::{Dialect, Language, Vocabulary};

/// The RAPID dialect.
/// The RAPID dialect.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rapid;

#[allow(non_upper_case_globals)]
impl Language {
    /// ABB RAPID (`.mod`, `.modx`, `.sys`, `.sysx`, `.prg`).
    pub const Rapid: Language = Language::of(&Rapid);
}

#[allow(non_upper_case_globals)]
impl PositionKind {
    /// RAPID `robtarget`.
    pub const Robtarget: PositionKind = PositionKind::new("robtarget", true);
    /// RAPID `jointtarget`.
    pub const Jointtarget: PositionKind = PositionKind::new("jointtarget", false);
}

const VOCABULARY: Vocabulary = Vocabulary {
    frame_column: "wobj",
    frames: "work objects",
    tool_kind: "tooldata",
    stationary_tool: "robhold TRUE",
    world_frames: &["wobj0"],
};

impl Dialect for Rapid {
    fn name(&self) -> &'static str {
        "rapid"
    }

    fn extensions(&self) -> &'static [&'static str] {
        &["mod", "modx", "sys", "sysx", "prg"]
    }

    /// `.pgf` is RobotStudio's XML program file: it lists modules but holds no RAPID.
    fn skipped_extensions(&self) -> &'static [&'static str] {
        &["pgf"]
    }

    fn load(&self, path: &Path, _options: &LoadOptions) -> Result<Program, LoadError> {
        let is_pgf = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("pgf"));
        if is_pgf {
            return Err(LoadError::ProgramXml {
                path: path.to_owned(),
            });
        }
        let source = read_source(path)?;
        Ok(Program {
            files: vec![crate::rapid::parse_file(path, source)],
        })
    }

    fn reparse(
        &self,
        files: Vec<(PathBuf, Vec<u8>)>,
        _options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        let files = files
            .into_iter()
            .map(|(path, source)| crate::rapid::parse_file(&path, source))
            .collect();
        Ok(Program { files })
    }

    fn vocabulary(&self) -> &'static Vocabulary {
        &VOCABULARY
    }

    fn axis_name(&self, index: usize) -> String {
        format!("eax_{}", (b'a' + index.min(25) as u8) as char)
    }

    /// A mirror-image arm: `cf1, cf4, cf6 → -cf - 1` (the quadrant counted the other way).
    fn mirror_config(&self, config: &Config) -> Vec<Edit> {
        let Config::Abb(cf) = config else {
            return Vec::new();
        };
        cf.iter()
            .take(3)
            .filter_map(|f| {
                let v = f.as_ref()?.value();
                integer_edit(f, -(v.round() as i64) - 1)
            })
            .collect()
    }
}
