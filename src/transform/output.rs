//! Where transformed files go: `-o`, `--out-dir`, `--in-place` (with a `.orig` backup), and the
//! unified diff of `--diff`.
//!
//! Every destination is decided and checked before the first byte is written, each file is
//! written atomically (temporary file + rename), and if a write still fails the files this run
//! created are removed again: a failed run leaves nothing behind.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::syntax::latin1;

use super::edits::ProgramResult;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    #[error("{}: refusing to overwrite an input file; use --in-place to change inputs", path.display())]
    WouldOverwriteInput { path: PathBuf },
    #[error("-o names one output, but {count} programs were given; use --out-dir")]
    OneOutputManyPrograms { count: usize },
    #[error("{} is written twice (two inputs with the same file name?)", path.display())]
    Duplicate { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Where the transformed programs go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// `-o FILE`: one program; a KRL pair's second file takes the same stem with its own
    /// extension.
    File(PathBuf),
    /// `--out-dir DIR`: every file under its own name.
    Dir(PathBuf),
    /// `--in-place`, keeping `FILE.orig` unless `backup` is false.
    InPlace { backup: bool },
}

/// One file to write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedWrite {
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// `path` plus `.orig`: `spot_line.mod` → `spot_line.mod.orig`.
pub fn backup_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".orig");
    PathBuf::from(s)
}

/// The same file whether named relatively or absolutely (for files that may not exist yet, the
/// folder is resolved).
fn identity(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) => {
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            dir.canonicalize()
                .map(|d| d.join(name))
                .unwrap_or_else(|_| path.to_owned())
        }
        _ => path.to_owned(),
    }
}

/// Where one file of a program goes (`first`: the program's first file, whose stem names the
/// program; `None` for a one-file program). `None` for an unchanged file under `--in-place`,
/// which is left alone. With `-o`, the other file of a KRL pair takes the output's stem and its
/// own extension; a file with another stem (a mirrored `$config.dat`) keeps its name, beside it.
pub fn output_path(
    dest: &Destination,
    input: &Path,
    first: Option<&Path>,
    changed: bool,
) -> Option<PathBuf> {
    match dest {
        Destination::File(out) => match (first, input.extension()) {
            (Some(f), _) if f.file_stem() != input.file_stem() => Some(
                out.parent()
                    .unwrap_or(Path::new(""))
                    .join(input.file_name().unwrap_or_default()),
            ),
            (Some(_), Some(ext)) => Some(out.with_extension(ext)),
            _ => Some(out.clone()),
        },
        Destination::Dir(dir) => Some(dir.join(input.file_name().unwrap_or_default())),
        Destination::InPlace { .. } => changed.then(|| input.to_owned()),
    }
}

/// Every write of a run, checked: no input is overwritten (except `--in-place`), no file is
/// written twice. `--in-place` writes only files that change.
pub fn plan_writes(
    programs: &[ProgramResult],
    dest: &Destination,
) -> Result<Vec<PlannedWrite>, OutputError> {
    let inputs: Vec<PathBuf> = programs
        .iter()
        .flat_map(|p| &p.files)
        .map(|f| identity(&f.path))
        .collect();
    if let (Destination::File(_), n @ 2..) = (dest, programs.len()) {
        return Err(OutputError::OneOutputManyPrograms { count: n });
    }
    let mut writes = Vec::new();
    for p in programs {
        let first = (p.files.len() > 1)
            .then(|| p.files.first().map(|f| f.path.as_path()))
            .flatten();
        for f in &p.files {
            let Some(path) = output_path(dest, &f.path, first, f.changed()) else {
                continue;
            };
            if let Destination::InPlace { backup: true } = dest {
                writes.push(PlannedWrite {
                    path: backup_path(&f.path),
                    bytes: f.original.clone(),
                });
            }
            writes.push(PlannedWrite {
                path,
                bytes: f.output.clone(),
            });
        }
    }
    if let Destination::InPlace { .. } = dest {
        return check_duplicates(writes);
    }
    for w in &writes {
        if inputs.contains(&identity(&w.path)) {
            return Err(OutputError::WouldOverwriteInput {
                path: w.path.clone(),
            });
        }
    }
    check_duplicates(writes)
}

fn check_duplicates(writes: Vec<PlannedWrite>) -> Result<Vec<PlannedWrite>, OutputError> {
    let mut seen = std::collections::BTreeSet::new();
    for w in &writes {
        if !seen.insert(identity(&w.path)) {
            return Err(OutputError::Duplicate {
                path: w.path.clone(),
            });
        }
    }
    Ok(writes)
}

fn write_one(w: &PlannedWrite) -> std::io::Result<()> {
    if let Some(dir) = w.path.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)?;
    }
    let mut file = atomic_write_file::AtomicWriteFile::open(&w.path)?;
    file.write_all(&w.bytes)?;
    file.commit()
}

/// Writes every planned file atomically; on a failure removes the files this call created.
pub fn write_all(writes: &[PlannedWrite]) -> Result<(), OutputError> {
    let mut created = Vec::new();
    for w in writes {
        let existed = w.path.exists();
        if let Err(source) = write_one(w) {
            for c in &created {
                let _ = std::fs::remove_file(c);
            }
            return Err(OutputError::Io {
                path: w.path.clone(),
                source,
            });
        }
        if !existed {
            created.push(w.path.clone());
        }
    }
    Ok(())
}

/// A unified diff of one file (empty if unchanged). Bytes are shown as Latin-1 so that a
/// Windows-125x comment never breaks the diff.
pub fn unified_diff(path: &Path, old: &[u8], new: &[u8]) -> String {
    if old == new {
        return String::new();
    }
    let old = latin1(old);
    let new = latin1(new);
    let name = path.display().to_string();
    let name = name.trim_start_matches('/');
    similar::TextDiff::from_lines(&old, &new)
        .unified_diff()
        .context_radius(1)
        .header(&format!("a/{name}"), &format!("b/{name}"))
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::edits::FileResult;

    fn result(path: &str, old: &str, new: &str) -> ProgramResult {
        ProgramResult {
            files: vec![FileResult {
                path: PathBuf::from(path),
                original: old.as_bytes().to_vec(),
                output: new.as_bytes().to_vec(),
                refusals: Vec::new(),
                changes: Vec::new(),
            }],
        }
    }

    #[test]
    fn krl_pair_with_o_keeps_each_extension() {
        let mut r = result("in/a.src", "x", "y");
        r.files.push(result("in/a.dat", "x", "y").files.remove(0));
        let w = plan_writes(&[r], &Destination::File(PathBuf::from("out/b.src"))).unwrap();
        assert_eq!(w[0].path, Path::new("out/b.src"));
        assert_eq!(w[1].path, Path::new("out/b.dat"));
    }

    #[test]
    fn a_mirrored_config_dat_keeps_its_name_beside_the_output() {
        let mut r = result("in/a.src", "x", "y");
        r.files.push(result("in/a.dat", "x", "y").files.remove(0));
        r.files
            .push(result("cfg/$config.dat", "x", "y").files.remove(0));
        let w = plan_writes(&[r], &Destination::File(PathBuf::from("out/b.src"))).unwrap();
        assert_eq!(w[2].path, Path::new("out/$config.dat"));
    }

    #[test]
    fn in_place_writes_backup_then_file_and_skips_unchanged() {
        let plan = plan_writes(
            &[result("a.mod", "x", "y"), result("b.mod", "z", "z")],
            &Destination::InPlace { backup: true },
        )
        .unwrap();
        let paths: Vec<_> = plan.iter().map(|w| w.path.clone()).collect();
        assert_eq!(paths, [PathBuf::from("a.mod.orig"), PathBuf::from("a.mod")]);
        assert_eq!(plan[0].bytes, b"x");
    }

    #[test]
    fn refuses_to_overwrite_an_input() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("a.mod");
        std::fs::write(&input, "x").unwrap();
        let r = result(input.to_str().unwrap(), "x", "y");
        let e = plan_writes(std::slice::from_ref(&r), &Destination::File(input.clone()));
        assert!(matches!(e, Err(OutputError::WouldOverwriteInput { .. })));
        let e = plan_writes(&[r], &Destination::Dir(dir.path().to_owned()));
        assert!(matches!(e, Err(OutputError::WouldOverwriteInput { .. })));
    }

    #[test]
    fn diff_shows_only_changed_lines() {
        let d = unified_diff(Path::new("m.mod"), b"a\nb\nc\nd\n", b"a\nB\nc\nd\n");
        assert_eq!(
            d,
            "--- a/m.mod\n+++ b/m.mod\n@@ -1,3 +1,3 @@\n a\n-b\n+B\n c\n"
        );
    }
}
