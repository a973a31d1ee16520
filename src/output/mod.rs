//! Where transformed files go and how they get there: one file, standard output, a
//! directory (mirroring the input tree), in place (numbered backups); the unified diff of a run;
//! and safe reading of inputs.
//!
//! Every destination is decided and checked before the first byte is written, and a run's
//! writes are one transaction ([`transaction`]): all files are written or none, originals are
//! never lost, and no temporary file outlives the run that made it. The contract is written
//! down in `docs/design.md §9`.

pub mod backup;
pub mod diff;
pub mod paths;
pub mod read;
pub mod transaction;

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use crate::transform::ProgramResult;

pub use backup::{backup_path, next_free_backup};
pub use diff::unified_diff;
pub use paths::{Destination, Roots, output_path, output_path_under};
pub use read::{
    InputBytes, MAP_FROM_BYTES, MAX_INPUT_BYTES, map_or_read_regular_file, read_input,
    read_regular_file,
};
pub use transaction::{FileWrite, Written, clean_stale, commit};

/// The files the process has read (through [`read_regular_file`] and its kin) or written
/// (through [`commit`]), by [`paths::identity`]: a file written besides a run's outputs never
/// replaces one of them. A process is one run.
mod run_files {
    use std::collections::BTreeSet;
    use std::path::{Path, PathBuf};
    use std::sync::Mutex;

    static TOUCHED: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

    pub(super) fn note(path: &Path) {
        let id = super::paths::identity(path);
        if let Ok(mut t) = TOUCHED.lock() {
            t.insert(id);
        }
    }

    pub(super) fn touched(path: &Path) -> bool {
        let id = super::paths::identity(path);
        TOUCHED.lock().is_ok_and(|t| t.contains(&id))
    }
}

/// Why the outputs of a run were not written. Nothing was changed on disk when one of these
/// is returned, except as [`OutputError::RollbackFailed`] says.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// An output path is one of the inputs (writing it is what in-place writing is for).
    #[error("{}: refusing to overwrite an input file; write it in place instead", path.display())]
    WouldOverwriteInput {
        /// The input named as an output.
        path: PathBuf,
    },
    /// A file a run writes besides its outputs names one of its inputs or outputs.
    #[error("{}: refusing to write there: this run reads or writes that file; name another", path.display())]
    ReadOrWritten {
        /// The path named.
        path: PathBuf,
    },
    /// One output file for several programs.
    #[error("one output file was named, but {count} programs were given; name an output folder")]
    OneOutputManyPrograms {
        /// How many programs were given.
        count: usize,
    },
    /// Standard output as the destination of a program of several files.
    #[error(
        "standard output takes one file, but the program has {count} files to write (a KRL pair?); name an output file or folder"
    )]
    OneStreamManyFiles {
        /// How many files the program has to write.
        count: usize,
    },
    /// Two results map to the same destination.
    #[error("{} would be written twice (two inputs with the same name and no input folder to tell them apart?)", path.display())]
    Duplicate {
        /// The destination.
        path: PathBuf,
    },
    /// The destination exists and is not a regular file (or a symlink to one).
    #[error("{}: cannot write there: it is {what}", path.display())]
    NotAFile {
        /// The destination.
        path: PathBuf,
        /// What it is instead (`a directory`, …).
        what: &'static str,
    },
    /// Another run holds the destination's lock file.
    #[error("{}: another trackfix run{} is writing it; try again when it has finished (a lock left by a killed run is removed automatically)", path.display(), pid.map(|p| format!(" (process {p})")).unwrap_or_default())]
    Locked {
        /// The destination.
        path: PathBuf,
        /// The process the lock file names, when it names one.
        pid: Option<u32>,
    },
    /// An input's bytes changed between reading it and replacing it.
    #[error("{}: changed since it was read (by another run?); nothing written, run again", path.display())]
    ChangedSinceRead {
        /// The input.
        path: PathBuf,
    },
    // The OS error is part of the message and deliberately not a `source`: printed with its
    // chain, it would otherwise appear twice.
    /// A file-system operation failed; the run was undone.
    #[error("{}: {error}; nothing written", path.display())]
    Io {
        /// The file or directory operated on.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A run failed and undoing it failed too: some files may be changed.
    #[error("{error}, and undoing the run failed for: {}; the backups are kept", failures.join("; "))]
    RollbackFailed {
        /// Why the run failed.
        error: Box<OutputError>,
        /// Each step of the undo that failed, with its path and error.
        failures: Vec<String>,
    },
}

/// Every write of a run, checked: no input is overwritten (except in place), no file is
/// written twice. In place, only files that change are written.
pub fn plan_writes<'a>(
    programs: &'a [ProgramResult],
    dest: &Destination,
) -> Result<Vec<FileWrite<'a>>, OutputError> {
    plan(programs, dest, &Roots::default())
}

/// [`plan_writes`] with the input folders of the run (for the tree [`Destination::Dir`]
/// mirrors). The writes borrow the results' bytes.
pub fn plan<'a>(
    programs: &'a [ProgramResult],
    dest: &Destination,
    roots: &Roots,
) -> Result<Vec<FileWrite<'a>>, OutputError> {
    let inputs: Vec<PathBuf> = programs
        .iter()
        .flat_map(|p| &p.files)
        .map(|f| paths::identity(&f.path))
        .collect();
    if let (Destination::File(_), n @ 2..) = (dest, programs.len()) {
        return Err(OutputError::OneOutputManyPrograms { count: n });
    }
    let in_place = matches!(dest, Destination::InPlace { .. });
    let mut writes = Vec::new();
    for p in programs {
        let first = (p.files.len() > 1)
            .then(|| p.files.first().map(|f| f.path.as_path()))
            .flatten();
        for f in &p.files {
            let Some(path) = output_path_under(dest, roots, &f.path, first, f.changed()) else {
                continue;
            };
            writes.push(FileWrite {
                input: f.path.clone(),
                path,
                bytes: Cow::Borrowed(&f.output),
                expected: in_place.then_some(Cow::Borrowed(&f.original)),
                backup: matches!(dest, Destination::InPlace { backup: true }),
            });
        }
    }
    let mut seen = std::collections::BTreeSet::new();
    for w in &writes {
        let id = paths::identity(&w.path);
        if !in_place && inputs.contains(&id) {
            return Err(OutputError::WouldOverwriteInput {
                path: w.path.clone(),
            });
        }
        if !seen.insert(id) {
            return Err(OutputError::Duplicate {
                path: w.path.clone(),
            });
        }
    }
    Ok(writes)
}

/// Writes every planned file as one transaction ([`transaction::commit`]).
pub fn write_all(writes: &[FileWrite<'_>]) -> Result<Vec<Written>, OutputError> {
    commit(writes)
}

/// The one file `-o -` sends to standard output: the program's only file, or its only changed
/// file (a KRL pair whose `.src` is unchanged).
pub fn stream_output(programs: &[ProgramResult]) -> Result<&[u8], OutputError> {
    if programs.len() > 1 {
        return Err(OutputError::OneOutputManyPrograms {
            count: programs.len(),
        });
    }
    let files: Vec<_> = programs.iter().flat_map(|p| &p.files).collect();
    let changed: Vec<_> = files.iter().copied().filter(|f| f.changed()).collect();
    match (files.as_slice(), changed.as_slice()) {
        ([only], _) | (_, [only]) => Ok(&only.output),
        _ => Err(OutputError::OneStreamManyFiles {
            count: changed.len(),
        }),
    }
}

/// Writes `bytes` to `path` alone, as a transaction of one file (profiles, frame tables,
/// plots, run reports): a temporary beside it and a rename, the old file's mode kept, a
/// symlink followed. A file the process has read or written is refused
/// ([`OutputError::ReadOrWritten`]): a derived file never replaces its own input or an output
/// of the same run.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    check_apart(path)?;
    replace_file(path, bytes)
}

/// Whether [`write_file`] may write `path`, asked before a run commits anything else: not a
/// file the process has read or written, nor one of `planned` (the run's own outputs), nor a
/// folder, and in a folder that exists.
pub fn check_apart_from(path: &Path, planned: &[PathBuf]) -> Result<(), OutputError> {
    check_apart(path)?;
    let id = paths::identity(path);
    if planned.iter().any(|p| paths::identity(p) == id) {
        return Err(OutputError::ReadOrWritten {
            path: path.to_owned(),
        });
    }
    if std::fs::metadata(path).is_ok_and(|m| m.is_dir()) {
        return Err(OutputError::NotAFile {
            path: path.to_owned(),
            what: "a directory",
        });
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !std::fs::metadata(parent).is_ok_and(|m| m.is_dir()) {
        return Err(OutputError::Io {
            path: path.to_owned(),
            error: std::io::Error::new(std::io::ErrorKind::NotFound, "its folder does not exist"),
        });
    }
    Ok(())
}

fn check_apart(path: &Path) -> Result<(), OutputError> {
    if run_files::touched(path) {
        return Err(OutputError::ReadOrWritten {
            path: path.to_owned(),
        });
    }
    Ok(())
}

/// [`write_file`] for a file the run means to update in place (a cell file given the fitted
/// nominal), which it has read.
pub fn replace_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    commit(&[FileWrite {
        input: path.to_owned(),
        path: path.to_owned(),
        bytes: Cow::Borrowed(bytes),
        expected: None,
        backup: false,
    }])
    .map(drop)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::FileResult;

    fn result(path: &str, old: &str, new: &str) -> ProgramResult {
        ProgramResult {
            files: vec![FileResult {
                path: PathBuf::from(path),
                original: old.as_bytes().to_vec().into(),
                output: new.as_bytes().to_vec(),
                refusals: Vec::new(),
                notes: Vec::new(),
                changes: Default::default(),
                widened: None,
                kept: Vec::new(),
            }],
        }
    }

    #[test]
    fn krl_pair_with_o_keeps_each_extension() {
        let mut r = result("in/a.src", "x", "y");
        r.files.push(result("in/a.dat", "x", "y").files.remove(0));
        let results = [r];
        let w = plan_writes(&results, &Destination::File(PathBuf::from("out/b.src"))).unwrap();
        assert_eq!(w[0].path, Path::new("out/b.src"));
        assert_eq!(w[1].path, Path::new("out/b.dat"));
    }

    #[test]
    fn a_mirrored_config_dat_keeps_its_name_beside_the_output() {
        let mut r = result("in/a.src", "x", "y");
        r.files.push(result("in/a.dat", "x", "y").files.remove(0));
        r.files
            .push(result("cfg/$config.dat", "x", "y").files.remove(0));
        let results = [r];
        let w = plan_writes(&results, &Destination::File(PathBuf::from("out/b.src"))).unwrap();
        assert_eq!(w[2].path, Path::new("out/$config.dat"));
    }

    #[test]
    fn in_place_writes_changed_files_with_their_original_for_the_backup() {
        let results = [result("a.mod", "x", "y"), result("b.mod", "z", "z")];
        let plan = plan_writes(&results, &Destination::InPlace { backup: true }).unwrap();
        // Lent, not copied: the write holds the result's own bytes.
        assert!(
            matches!(plan[0].bytes, std::borrow::Cow::Borrowed(b) if std::ptr::eq(b, results[0].files[0].output.as_slice()))
        );
        assert_eq!(plan.len(), 1);
        assert_eq!(plan[0].path, Path::new("a.mod"));
        assert_eq!(plan[0].expected.as_deref(), Some(&b"x"[..]));
        assert!(plan[0].backup);
    }

    #[test]
    fn refuses_to_overwrite_an_input() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("a.mod");
        std::fs::write(&input, "x").unwrap();
        let r = result(input.to_str().unwrap(), "x", "y");
        let e = plan_writes(std::slice::from_ref(&r), &Destination::File(input.clone()));
        assert!(matches!(e, Err(OutputError::WouldOverwriteInput { .. })));
        let e = plan_writes(
            std::slice::from_ref(&r),
            &Destination::Dir(dir.path().to_owned()),
        );
        assert!(matches!(e, Err(OutputError::WouldOverwriteInput { .. })));
    }

    #[test]
    fn same_names_in_different_task_folders_do_not_collide_under_out_dir() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("backup");
        for task in ["T_ROB1", "T_ROB2"] {
            std::fs::create_dir_all(root.join(task)).unwrap();
        }
        let a = root.join("T_ROB1/MainModule.mod");
        let b = root.join("T_ROB2/MainModule.mod");
        let programs = [
            result(a.to_str().unwrap(), "x", "y"),
            result(b.to_str().unwrap(), "x", "z"),
        ];
        let out = Destination::Dir(dir.path().join("out"));
        // Without the input folder, the two collide (what happened before).
        assert!(matches!(
            plan_writes(&programs, &out),
            Err(OutputError::Duplicate { .. })
        ));
        let w = plan(&programs, &out, &Roots::from_inputs(&[root])).unwrap();
        assert_eq!(w[0].path, dir.path().join("out/T_ROB1/MainModule.mod"));
        assert_eq!(w[1].path, dir.path().join("out/T_ROB2/MainModule.mod"));
    }

    #[test]
    fn io_errors_name_the_os_error_once() {
        let e = OutputError::Io {
            path: PathBuf::from("a"),
            error: std::io::Error::from_raw_os_error(28),
        };
        // Printed with its chain (as the command line does), the OS error must not repeat.
        assert!(std::error::Error::source(&e).is_none());
        assert_eq!(e.to_string().matches("os error 28").count(), 1, "{e}");
    }
}
