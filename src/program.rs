//! Loading programs: file types, directories, and dispatch to the language parsers.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::output::InputBytes;
use crate::position::{Language, Program};
use crate::syntax::looks_binary;

/// Options that change how a program is read.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// A KUKA `$config.dat` whose `BASE_DATA`/`TOOL_DATA` resolve KRL bases and tools.
    pub krl_config_dat: Option<PathBuf>,
    /// Map large inputs instead of reading them ([`crate::output::InputBytes`]). Only for runs
    /// that write no input: a mapped file changes if another process rewrites it in place.
    pub map_inputs: bool,
    /// The [`krl_config_dat`](Self::krl_config_dat) once read and parsed, shared by these
    /// options and their clones: every program of a KSS tree uses it, and it was read and
    /// parsed again for each one. Build options with `..LoadOptions::default()`.
    pub config_dat: crate::krl::ConfigDatOnce,
}

/// Why a file could not be read as a program. Parse problems are not load errors: the parsers
/// never fail, they keep what they do not understand and report it as diagnostics.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A binary or encrypted file ([`crate::syntax::looks_binary`]); skipped, not parsed.
    #[error("{}: not a text module (binary or encrypted file); skipped", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
    },
    /// A RobotStudio program file: XML that lists modules, no RAPID of its own.
    #[error("{}: RobotStudio program file (.pgf, XML): it lists modules but holds no RAPID; skipped", path.display())]
    ProgramXml {
        /// The file.
        path: PathBuf,
    },
    /// An extension no registered dialect claims.
    #[error("{}: unknown file type; expected {}", path.display(), known_extensions())]
    UnknownType {
        /// The file.
        path: PathBuf,
    },
}

impl LoadError {
    /// The file concerned.
    pub fn path(&self) -> &Path {
        match self {
            LoadError::Io { path, .. }
            | LoadError::NotText { path }
            | LoadError::ProgramXml { path }
            | LoadError::UnknownType { path } => path,
        }
    }

    /// True for files that are skipped with a note rather than failing a batch.
    pub fn is_skip(&self) -> bool {
        matches!(
            self,
            LoadError::NotText { .. } | LoadError::ProgramXml { .. }
        )
    }
}

/// The language of a file, by its extension: the dialect registry's answer.
pub fn language_of(path: &Path) -> Option<Language> {
    crate::dialect::dialect_of(path).map(Language::of)
}

/// `.mod/.modx/.sys/.sysx/.prg or .src/.dat/.sub`: the program extensions of every dialect.
fn known_extensions() -> String {
    crate::dialect::registry()
        .iter()
        .map(|d| {
            d.extensions()
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join("/")
        })
        .collect::<Vec<_>>()
        .join(" or ")
}

/// Reads (or, with [`LoadOptions::map_inputs`], maps) a file as bytes, refusing binary content.
pub fn read_source(path: &Path, options: &LoadOptions) -> Result<InputBytes, LoadError> {
    let bytes = crate::output::map_or_read_regular_file(
        path,
        crate::output::MAX_INPUT_BYTES,
        options.map_inputs,
    )
    .map_err(|source| LoadError::Io {
        path: path.to_owned(),
        source,
    })?;
    if looks_binary(&bytes) {
        return Err(LoadError::NotText {
            path: path.to_owned(),
        });
    }
    Ok(bytes)
}

/// Loads the program `path` belongs to, with its dialect: a RAPID module, a KRL
/// `.src`/`.dat` pair (naming either file loads both), …
pub fn load(path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
    match crate::dialect::dialect_of(path) {
        Some(dialect) => dialect.load(path, options),
        None => Err(LoadError::UnknownType {
            path: path.to_owned(),
        }),
    }
}

/// Expands directories (recursively, by extension, sorted) and keeps one entry per program: a
/// KRL `.dat` whose `.src` is also listed is dropped, because loading the `.src` loads both.
///
/// Files named explicitly are kept whatever their extension (so a wrong one gets a clear error).
pub fn collect_inputs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, LoadError> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut found = Vec::new();
            for entry in walkdir::WalkDir::new(p).sort_by_file_name() {
                let entry = entry.map_err(|e| LoadError::Io {
                    path: e.path().map(Path::to_owned).unwrap_or_else(|| p.clone()),
                    source: e.into(),
                })?;
                if entry.file_type().is_file() && language_of(entry.path()).is_some() {
                    found.push(entry.into_path());
                }
            }
            out.extend(found);
        } else {
            out.push(p.clone());
        }
    }
    for dialect in crate::dialect::registry() {
        dialect.dedupe_inputs(&mut out);
    }
    let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    let mut seen = BTreeSet::new();
    out.retain(|p| seen.insert(same_file(p)));
    Ok(out)
}

/// The inputs (as [`collect_inputs`] lists them) grouped into programs: the files under one
/// program root of their dialect (a RAPID task folder) form one program, every other file is
/// its own. Groups keep the order of their first file.
pub fn group_inputs(inputs: Vec<PathBuf>) -> Vec<Vec<PathBuf>> {
    group(inputs, &BTreeSet::new())
}

/// [`collect_inputs`] then [`group_inputs`], except that files named explicitly together, outside
/// any program root, form one program where their dialect joins files given together
/// ([`Dialect::joins_files_given_together`](crate::dialect::Dialect): RAPID modules named
/// together are one task; KRL modules named together are one program per folder).
pub fn collect_programs(paths: &[PathBuf]) -> Result<Vec<Vec<PathBuf>>, LoadError> {
    let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    let given: BTreeSet<PathBuf> = paths
        .iter()
        .filter(|p| !p.is_dir())
        .map(|p| same_file(p))
        .collect();
    Ok(group(collect_inputs(paths)?, &given))
}

fn group(inputs: Vec<PathBuf>, given: &BTreeSet<PathBuf>) -> Vec<Vec<PathBuf>> {
    let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    let mut groups: Vec<Vec<PathBuf>> = Vec::new();
    // (dialect, program root, folder of files given together): `None` as the root for the
    // files given together, with their folder where the dialect joins them per folder.
    type Root = (&'static str, Option<PathBuf>, Option<PathBuf>);
    let mut root_of_group: Vec<Option<Root>> = Vec::new();
    for path in inputs {
        let root = crate::dialect::dialect_of(&path).and_then(|d| match d.program_root(&path) {
            Some(r) => Some((d.name(), Some(r), None)),
            None => {
                (d.joins_files_given_together() && given.contains(&same_file(&path))).then(|| {
                    let folder = d
                        .joins_given_files_per_folder()
                        .then(|| same_file(&path).parent().map(Path::to_owned))
                        .flatten();
                    (d.name(), None, folder)
                })
            }
        });
        match root
            .as_ref()
            .and_then(|r| root_of_group.iter().position(|g| g.as_ref() == Some(r)))
        {
            Some(g) => {
                if let Some(group) = groups.get_mut(g) {
                    group.push(path);
                }
            }
            None => {
                groups.push(vec![path]);
                root_of_group.push(root);
            }
        }
    }
    groups
}

/// Loads one group of [`group_inputs`]: a single file as [`load`] does, several files as one
/// program of their dialect. A file of the group that cannot be read is its own error (a
/// binary module in a task is skipped, the others still form the program).
pub fn load_group(paths: &[PathBuf], options: &LoadOptions) -> Vec<Result<Program, LoadError>> {
    let [first, ..] = paths else {
        return Vec::new();
    };
    if paths.len() == 1 {
        return vec![load(first, options)];
    }
    let Some(dialect) = crate::dialect::dialect_of(first) else {
        return vec![Err(LoadError::UnknownType {
            path: first.clone(),
        })];
    };
    let mut out = Vec::new();
    let mut readable = Vec::with_capacity(paths.len());
    for p in paths {
        let skipped = dialect.skipped_extensions().iter().any(|e| {
            p.extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| x.eq_ignore_ascii_case(e))
        });
        if skipped {
            out.push(dialect.load(p, options));
            continue;
        }
        match read_source(p, options) {
            Ok(bytes) => readable.push((p.clone(), bytes)),
            Err(e) => out.push(Err(e)),
        }
    }
    if !readable.is_empty() {
        out.push(dialect.load_together(readable, options));
    }
    out
}
