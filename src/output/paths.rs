//! Where each transformed file goes, and the real file a destination names.

use std::path::{Path, PathBuf};

/// Where the transformed programs go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// `-o FILE`: one program; a KRL pair's second file takes the same stem with its own
    /// extension.
    File(PathBuf),
    /// Into a directory: every file at its path relative to the input directory it was found in
    /// (see [`Roots`]), or under its own name when it was named directly.
    Dir(PathBuf),
    /// In place, keeping a numbered backup (`FILE.orig`, `FILE.orig.1`, …) unless `backup`
    /// is false.
    InPlace {
        /// Keep a backup of each replaced file.
        backup: bool,
    },
}

/// The input directories a run was given: written into a directory, a file found in one of them keeps
/// its path relative to it, so two `MainModule.mod` of different task folders stay apart.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Roots(Vec<PathBuf>);

impl Roots {
    /// The directories among the run's arguments (files named directly are no roots).
    pub fn from_inputs(args: &[PathBuf]) -> Roots {
        Roots(args.iter().filter(|p| p.is_dir()).cloned().collect())
    }

    /// `input` relative to the deepest root that holds it, or its file name.
    pub fn relative(&self, input: &Path) -> PathBuf {
        match self.within(input) {
            Some(rel) if rel.file_name().is_some() && is_plain_relative(&rel) => rel,
            _ => PathBuf::from(input.file_name().unwrap_or_default()),
        }
    }

    /// Whether a root holds `input` (a file found in a folder the run was given).
    pub fn holds(&self, input: &Path) -> bool {
        self.within(input).is_some()
    }

    /// `input` relative to the deepest root that holds it, if one does.
    fn within(&self, input: &Path) -> Option<PathBuf> {
        let lexical = self
            .0
            .iter()
            .filter_map(|r| input.strip_prefix(r).ok())
            .min_by_key(|rel| rel.components().count());
        lexical.map(Path::to_owned).or_else(|| {
            // Spelled differently (`./a` and `a`, a `$config.dat` named by the cell file).
            let input = input.canonicalize().ok()?;
            self.0
                .iter()
                .filter_map(|r| r.canonicalize().ok())
                .filter_map(|r| input.strip_prefix(&r).ok().map(Path::to_owned))
                .min_by_key(|rel| rel.components().count())
        })
    }
}

/// Only names below the root: no `..`, no root, no prefix.
fn is_plain_relative(p: &Path) -> bool {
    p.components()
        .all(|c| matches!(c, std::path::Component::Normal(_)))
}

/// Where one file of a program goes (`first`: the program's first file, whose stem names the
/// program; `None` for a one-file program). `None` for an unchanged file written in place,
/// which is left alone. With `-o`, the other file of a KRL pair takes the output's stem and its
/// own extension; a file with another stem (a mirrored `$config.dat`) keeps its name, beside it.
pub fn output_path(
    dest: &Destination,
    input: &Path,
    first: Option<&Path>,
    changed: bool,
) -> Option<PathBuf> {
    output_path_under(dest, &Roots::default(), input, first, changed)
}

/// [`output_path`] with the run's input directories (for [`Destination::Dir`]).
pub fn output_path_under(
    dest: &Destination,
    roots: &Roots,
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
        Destination::Dir(dir) => Some(dir.join(roots.relative(input))),
        Destination::InPlace { .. } => changed.then(|| input.to_owned()),
    }
}

/// The same file whether named relatively or absolutely (for files that may not exist yet, the
/// folder is resolved).
pub(crate) fn identity(path: &Path) -> PathBuf {
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
            identity(dir).join(name)
        }
        _ => path.to_owned(),
    }
}

/// `path` with `suffix` appended to its file name: `a.mod` + `.orig` → `a.mod.orig`.
pub(crate) fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

/// `dir/.NAME<suffix>`: a hidden sibling of `path`.
pub(crate) fn hidden_sibling(path: &Path, suffix: &str) -> PathBuf {
    let mut name = std::ffi::OsString::from(".");
    name.push(path.file_name().unwrap_or_default());
    name.push(suffix);
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_dir_mirrors_the_tree_below_the_directory_given() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("backup");
        std::fs::create_dir_all(root.join("TASK1/PROGMOD")).unwrap();
        let roots = Roots::from_inputs(&[root.clone(), dir.path().join("single.mod")]);
        let out = Destination::Dir(PathBuf::from("out"));
        let a = root.join("TASK1/PROGMOD/MainModule.mod");
        let b = root.join("TASK2/PROGMOD/MainModule.mod");
        assert_eq!(
            output_path_under(&out, &roots, &a, None, true).unwrap(),
            Path::new("out/TASK1/PROGMOD/MainModule.mod")
        );
        assert_eq!(
            output_path_under(&out, &roots, &b, None, true).unwrap(),
            Path::new("out/TASK2/PROGMOD/MainModule.mod")
        );
        // A file named directly (not found under a directory argument) keeps its name only.
        assert_eq!(
            output_path_under(&out, &roots, Path::new("/elsewhere/x.mod"), None, true).unwrap(),
            Path::new("out/x.mod")
        );
    }

    #[test]
    fn hidden_siblings_sit_in_the_same_folder() {
        assert_eq!(
            hidden_sibling(Path::new("d/a.mod"), ".trackfix-lock"),
            Path::new("d/.a.mod.trackfix-lock")
        );
        assert_eq!(
            with_suffix(Path::new("d/a.mod"), ".orig"),
            Path::new("d/a.mod.orig")
        );
    }
}
