//! Loading programs: file types, directories, and dispatch to the language parsers.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::position::{Language, Program};
use crate::syntax::looks_binary;

/// RAPID file extensions (lower case). `.pgf` is RobotStudio's XML program file, which holds
/// no RAPID text and is skipped with a note.
pub const RAPID_EXTENSIONS: &[&str] = &["mod", "modx", "sys", "sysx", "prg", "pgf"];
/// KRL file extensions (lower case).
pub const KRL_EXTENSIONS: &[&str] = &["src", "dat", "sub"];

/// Options that change how a program is read.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// A KUKA `$config.dat` whose `BASE_DATA`/`TOOL_DATA` resolve KRL bases and tools.
    pub krl_config_dat: Option<PathBuf>,
}

/// Why a file could not be read as a program. Parse problems are not load errors: the parsers
/// never fail, they keep what they do not understand and report it as diagnostics.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a text module (binary or encrypted file); skipped", path.display())]
    NotText { path: PathBuf },
    #[error("{}: RobotStudio program file (.pgf, XML): it lists modules but holds no RAPID; skipped", path.display())]
    ProgramXml { path: PathBuf },
    #[error("{}: unknown file type; expected .mod/.modx/.sys/.sysx/.prg or .src/.dat/.sub", path.display())]
    UnknownType { path: PathBuf },
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

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

/// The language of a file, by its extension.
pub fn language_of(path: &Path) -> Option<Language> {
    let ext = extension(path)?;
    if RAPID_EXTENSIONS.contains(&ext.as_str()) {
        Some(Language::Rapid)
    } else if KRL_EXTENSIONS.contains(&ext.as_str()) {
        Some(Language::Krl)
    } else {
        None
    }
}

/// Reads a file as bytes, refusing binary content.
pub fn read_source(path: &Path) -> Result<Vec<u8>, LoadError> {
    let bytes = crate::output::read_regular_file(path, crate::output::MAX_INPUT_BYTES).map_err(
        |source| LoadError::Io {
            path: path.to_owned(),
            source,
        },
    )?;
    if looks_binary(&bytes) {
        return Err(LoadError::NotText {
            path: path.to_owned(),
        });
    }
    Ok(bytes)
}

/// Loads the program `path` belongs to: a RAPID module, or a KRL `.src`/`.dat` pair (naming
/// either file loads both).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
    match language_of(path) {
        Some(Language::Rapid) => {
            if extension(path).as_deref() == Some("pgf") {
                return Err(LoadError::ProgramXml {
                    path: path.to_owned(),
                });
            }
            let source = read_source(path)?;
            Ok(Program {
                files: vec![crate::rapid::parse_file(path, source)],
            })
        }
        Some(Language::Krl) => crate::krl::load_program(path, options),
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
    // The `.dat` a `.src` loads with is found the way `krl::load_program` finds it (stem and
    // extension in any case), and compared as a file, not as spelled (`./a.dat` is `a.dat`).
    let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
    let stem_key = |p: &Path| {
        let stem = p
            .file_stem()
            .map(|s| s.to_string_lossy().to_ascii_lowercase());
        (same_file(p).parent().map(Path::to_owned), stem)
    };
    // Only a `.src` whose stem a listed `.dat` shares needs its directory read.
    let dat_stems: BTreeSet<_> = out
        .iter()
        .filter(|p| extension(p).as_deref() == Some("dat"))
        .map(|p| stem_key(p))
        .collect();
    let partners: BTreeSet<PathBuf> = out
        .iter()
        .filter(|p| extension(p).as_deref() == Some("src") && dat_stems.contains(&stem_key(p)))
        .filter_map(|p| crate::krl::partner_of(p))
        .map(|d| same_file(&d))
        .collect();
    let mut seen = BTreeSet::new();
    out.retain(|p| {
        if extension(p).as_deref() == Some("dat") && partners.contains(&same_file(p)) {
            return false;
        }
        seen.insert(same_file(p))
    });
    Ok(out)
}
