//! ABB RAPID: modules (`.mod`, `.sys`, …), one file per program; work objects, quaternions,
//! configuration `[cf1, cf4, cf6, cfx]`.

use std::path::{Path, PathBuf};

use crate::output::InputBytes;
use crate::position::{Config, KindSpec, PositionKind, Program};
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
    pub const Robtarget: PositionKind = PositionKind::new(&KindSpec::pose("robtarget"));
    /// RAPID `jointtarget`.
    pub const Jointtarget: PositionKind = PositionKind::new(&KindSpec::joints("jointtarget"));
}

const VOCABULARY: Vocabulary = Vocabulary {
    frame_column: "wobj",
    frames: "work objects",
    frame: "work object",
    moved_frame: "ufprog FALSE",
    tool_kind: "tooldata",
    stationary_tool: "robhold TRUE",
    stationary_point: "robhold TRUE",
    world_frames: &["wobj0"],
    frame_of_a_motion: "name the work object in each motion to it (\\WObj:=…), the same on every path",
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

    fn load(&self, path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
        let is_pgf = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("pgf"));
        let source = read_source(path, options)?;
        // A `.pgf` is RobotStudio's XML list of modules; some tools write RAPID text under that
        // name instead, and that is read as a module.
        let xml = || {
            let text = source.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&source);
            text.iter()
                .find(|b| !b.is_ascii_whitespace())
                .is_none_or(|&b| b == b'<')
        };
        if is_pgf && xml() {
            return Err(LoadError::ProgramXml {
                path: path.to_owned(),
            });
        }
        Ok(Program {
            files: vec![crate::rapid::parse_file(path, source)],
        })
    }

    fn reparse(
        &self,
        files: Vec<(PathBuf, Vec<u8>)>,
        _options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        let files = files.into_iter().map(|(p, s)| (p, s.into())).collect();
        Ok(Program {
            files: crate::rapid::parse_task(files),
        })
    }

    /// A RobotStudio task folder: the nearest of the three folders above the module that holds
    /// a `PROGMOD` or `SYSMOD` folder (`RAPID/TASK1/PROGMOD/Main.mod` → `RAPID/TASK1`).
    fn program_root(&self, path: &Path) -> Option<PathBuf> {
        path.ancestors().skip(1).take(3).find_map(|dir| {
            let entries = std::fs::read_dir(dir).ok()?;
            entries
                .filter_map(Result::ok)
                .any(|e| {
                    e.file_type().is_ok_and(|t| t.is_dir())
                        && e.file_name().to_str().is_some_and(|n| {
                            n.eq_ignore_ascii_case("PROGMOD") || n.eq_ignore_ascii_case("SYSMOD")
                        })
                })
                .then(|| dir.to_owned())
        })
    }

    /// Modules named together are the modules of one task (RAPID scoping keeps each module's
    /// own and `LOCAL` data first, so unrelated modules do not take each other's targets).
    fn joins_files_given_together(&self) -> bool {
        true
    }

    /// The modules of one task, resolved together (task and global data seen across modules).
    fn load_together(
        &self,
        sources: Vec<(PathBuf, InputBytes)>,
        _options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        Ok(Program {
            files: crate::rapid::parse_task(sources),
        })
    }

    fn vocabulary(&self) -> &'static Vocabulary {
        &VOCABULARY
    }

    fn line_comment(&self) -> Option<&'static str> {
        Some("!")
    }

    fn header_keywords(&self) -> &'static [&'static str] {
        &["MODULE"]
    }

    fn axis_name(&self, index: usize) -> String {
        format!("eax_{}", (b'a' + index.min(25) as u8) as char)
    }

    /// A mirror-image arm: `cf1, cf4, cf6 → -cf - 1` (the quadrant counted the other way).
    fn mirror_config(&self, config: &Config) -> Vec<Edit> {
        let Config::Quadrants(cf) = config else {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modules_loaded_together_are_parsed_from_the_bytes_given() {
        // No file has these names: the modules' bytes are the ones load_group read, and
        // loading them together reads nothing again.
        let a: &[u8] = b"MODULE A\r\n  CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\r\nENDMODULE\r\n";
        let b: &[u8] =
            b"MODULE B\nPROC main()\n  MoveL p1, v100, fine, tool0;\nENDPROC\nENDMODULE\n";
        let sources = vec![
            (
                PathBuf::from("no-such-task/A.mod"),
                InputBytes::from(a.to_vec()),
            ),
            (
                PathBuf::from("no-such-task/B.mod"),
                InputBytes::from(b.to_vec()),
            ),
        ];
        let program = Rapid
            .load_together(sources, &LoadOptions::default())
            .unwrap();
        let [fa, fb] = &program.files[..] else {
            panic!("two modules, got {}", program.files.len());
        };
        assert_eq!((&*fa.source, &*fb.source), (a, b));
        // Resolved as one task: the target of A is used by B's motion.
        let p1 = fa.positions().next().unwrap();
        assert_eq!(&*p1.usage.lines, &[3]);
    }
}
