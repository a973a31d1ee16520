//! The seam between a robot language and the rest of trackfix.
//!
//! A [`Dialect`] says everything the loader, the reports and the transforms need to know about
//! one language: its file extensions, how to load and re-read a program, its vocabulary (work
//! object or base, axis names, what makes a tool stationary) and its configuration's mirror
//! rule. Dialects are registered in one table, [`registry`]; nothing else matches on a
//! language. To add a language: one folder with its parser and a `Dialect`, and one line in
//! [`BUILT_IN`] (or [`register`] at run time, as the stub dialect test does).

pub(crate) mod krl;
pub(crate) mod rapid;

use std::path::{Path, PathBuf};
use std::sync::RwLock;

use crate::kinematics::{ConfigValue, Joints, Kinematics};
use crate::output::InputBytes;
use crate::position::{Config, Program};
use crate::program::{LoadError, LoadOptions};
use crate::syntax::Edit;

/// What a language calls things, for reports and messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Vocabulary {
    /// The frame a target is taught in, as a report column: `wobj` (RAPID), `base` (KRL).
    pub frame_column: &'static str,
    /// The same in a sentence, plural: `work objects`, `bases`.
    pub frames: &'static str,
    /// The same in a sentence, singular: `work object`, `base`.
    pub frame: &'static str,
    /// The setting that makes such a frame one a mechanical unit moves (so it is not where the
    /// track puts it): `ufprog FALSE`, `MACHINE_FRAME_DAT: an external kinematic`.
    pub moved_frame: &'static str,
    /// The data type of a tool declaration: `tooldata`, `tool`.
    pub tool_kind: &'static str,
    /// The setting that makes a target a stationary-tool point: `robhold TRUE`,
    /// `IPO_FRAME #TCP`.
    pub stationary_tool: &'static str,
    /// Why a point is a stationary-tool point: its work object's setting (`robhold TRUE`), or
    /// (KRL) the interpolation mode a path to the motion may set, which the program's flow
    /// decides (see docs/design.md, KRL stationary tool).
    pub stationary_point: &'static str,
    /// Frame names that mean world when the program does not declare them (lower case).
    pub world_frames: &'static [&'static str],
    /// How a program names the frame of a motion on every path to it, for a target whose
    /// frame is not known: `\WObj:=` in the instruction (RAPID), a base set before it (KRL).
    pub frame_of_a_motion: &'static str,
}

/// One robot language.
pub trait Dialect: Sync + 'static {
    /// The name reports use (`rapid`, `krl`): lower case, unique in the registry.
    fn name(&self) -> &'static str;

    /// The file extensions of its programs, lower case, without the dot.
    fn extensions(&self) -> &'static [&'static str];

    /// Extensions of the language's files that hold no program text: recognised, so that
    /// [`Dialect::load`] skips them with a note instead of failing as an unknown type.
    fn skipped_extensions(&self) -> &'static [&'static str] {
        &[]
    }

    /// Loads the program `path` belongs to (a file, or the files loading it implies).
    fn load(&self, path: &Path, options: &LoadOptions) -> Result<Program, LoadError>;

    /// Builds a program from files in memory, resolved as [`Dialect::load`] resolves them:
    /// how `transfer` reads a step's output before the next step.
    fn reparse(
        &self,
        files: Vec<(PathBuf, Vec<u8>)>,
        options: &LoadOptions,
    ) -> Result<Program, LoadError>;

    /// Drops from a list of inputs the files that loading another listed file reads too (a KRL
    /// `.dat` whose `.src` is listed), so each program is loaded once.
    fn dedupe_inputs(&self, _inputs: &mut Vec<PathBuf>) {}

    /// The folder whose files of this language form one program with `path` (a RAPID task
    /// folder), if the language groups files that way; `None` loads `path` on its own.
    fn program_root(&self, _path: &Path) -> Option<PathBuf> {
        None
    }

    /// Files of this language named together (outside any program root) are one program.
    fn joins_files_given_together(&self) -> bool {
        false
    }

    /// Of the files named together, only those in one folder are one program (KRL: the modules
    /// of a KSS `Program` folder see each other's `GLOBAL` data and routines; files from two
    /// folders may be two robots'). Read only where [`Dialect::joins_files_given_together`].
    fn joins_given_files_per_folder(&self) -> bool {
        false
    }

    /// One program of several files of this language, resolved together, from their bytes as
    /// [`load_group`](crate::program::load_group) read them (each file is read once: a task of
    /// many modules was read twice, once to find the unreadable ones and once to parse). The
    /// default loads each file on its own, through [`Dialect::load`], which reads it again
    /// (languages that group by [`Dialect::program_root`] override it and use the bytes).
    fn load_together(
        &self,
        sources: Vec<(PathBuf, InputBytes)>,
        options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        let mut files = Vec::new();
        for (p, _) in sources {
            files.extend(self.load(&p, options)?.files);
        }
        Ok(Program { files })
    }

    /// The language's words for the shared concepts (work object or base, stationary tool, …),
    /// for reports and messages.
    fn vocabulary(&self) -> &'static Vocabulary;

    /// The mark that starts a comment running to the end of the line (`!`, `;`): trackfix's
    /// provenance stamp is written as such a comment. `None`: files are not stamped.
    fn line_comment(&self) -> Option<&'static str> {
        None
    }

    /// What makes the configuration written in a target's literal text absurd, when the model
    /// could not read it (KRL `T 1e30`, `S 1.5`), in words; `None` if nothing.
    fn implausible_configuration(&self, _literal: &[u8]) -> Option<String> {
        None
    }

    /// The pose fields a target's literal text leaves out, which the controller takes from
    /// where the robot is when the motion runs (KRL `LIN {Z 500}`), in words; `None` where it
    /// writes them all, or writes no pose.
    fn pose_fields_left_out(&self, _literal: &[u8]) -> Option<String> {
        None
    }

    /// Whether a program's main routine must carry its file's name (KRL `DEF spot_line(` in
    /// `spot_line.src`): a program written under a new name then gets its header renamed.
    fn names_follow_file(&self) -> bool {
        false
    }

    /// Keywords opening a file's header (`MODULE`; `DEF`, `DEFDAT`): the provenance stamp is
    /// the line after the first line that starts with one.
    fn header_keywords(&self) -> &'static [&'static str] {
        &[]
    }

    /// The name of external axis `index` (0-based) as the language writes it.
    fn axis_name(&self, index: usize) -> String;

    /// The edits that give a mirror-image robot's configuration for `config` (the arm runs
    /// the axes that change sign under a mirror, 1, 4 and 6, the other way).
    fn mirror_config(&self, config: &Config) -> Vec<Edit>;

    /// The configuration the language writes for an arm at joints `j`, in the convention its
    /// targets hold ([`Config`]: axis quadrants as ABB `confdata`, Status and Turn bits as
    /// KUKA `S`/`T`). A dialect without one of its own writes axis quadrants.
    fn configuration_of(&self, kin: &Kinematics, j: &Joints) -> ConfigValue {
        ConfigValue::quadrants_of(kin, j)
    }
}

/// A language, as a handle to its dialect: what every parsed file carries.
#[derive(Clone, Copy)]
pub struct Language(&'static dyn Dialect);

impl Language {
    /// The handle of `dialect`.
    pub const fn of(dialect: &'static dyn Dialect) -> Language {
        Language(dialect)
    }

    /// The dialect behind the handle.
    pub fn dialect(self) -> &'static dyn Dialect {
        self.0
    }

    /// The dialect's name (`"rapid"`, `"krl"`), as reports and JSON show it.
    pub fn name(self) -> &'static str {
        self.0.name()
    }
}

impl PartialEq for Language {
    fn eq(&self, other: &Language) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Language {}

impl std::hash::Hash for Language {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state);
    }
}

impl std::fmt::Debug for Language {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for Language {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// The dialects trackfix is built with: the one table a new language is added to.
pub const BUILT_IN: &[&dyn Dialect] = &[&rapid::Rapid, &krl::Krl];

static REGISTERED: RwLock<Vec<&'static dyn Dialect>> = RwLock::new(Vec::new());

/// Adds a dialect at run time (after the built-in ones; a name already known is ignored).
pub fn register(dialect: &'static dyn Dialect) {
    if registry().iter().any(|d| d.name() == dialect.name()) {
        return;
    }
    // A poisoned lock only means another registration panicked: the list is still whole.
    let mut list = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    list.push(dialect);
}

/// Every dialect: the built-in ones, then those registered at run time.
pub fn registry() -> Vec<&'static dyn Dialect> {
    let extra = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    BUILT_IN
        .iter()
        .copied()
        .chain(extra.iter().copied())
        .collect()
}

/// Whether any dialect satisfies `test`, without collecting the registry (for per-target
/// questions such as "does this name mean world?").
pub fn any(mut test: impl FnMut(&dyn Dialect) -> bool) -> bool {
    if BUILT_IN.iter().any(|d| test(*d)) {
        return true;
    }
    let extra = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    extra.iter().any(|d| test(*d))
}

/// The dialect of a file, by its extension (any case).
pub fn dialect_of(path: &Path) -> Option<&'static dyn Dialect> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    registry().into_iter().find(|d| {
        d.extensions().contains(&ext.as_str()) || d.skipped_extensions().contains(&ext.as_str())
    })
}
