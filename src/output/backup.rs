//! Backups of files replaced in place: `FILE.orig`, then `FILE.orig.1`, `FILE.orig.2`, …: a backup is never
//! overwritten, so the first one always holds the file as it was before trackfix first touched
//! it.

use std::path::{Path, PathBuf};

use super::paths::with_suffix;

/// `path` plus `.orig`: `spot_line.mod` → `spot_line.mod.orig` (the first backup's name).
pub fn backup_path(path: &Path) -> PathBuf {
    with_suffix(path, ".orig")
}

/// The backup names in the order they are tried: `FILE.orig`, `FILE.orig.1`, ….
pub fn backup_candidates(path: &Path) -> impl Iterator<Item = PathBuf> + '_ {
    (0usize..).map(move |n| match n {
        0 => backup_path(path),
        n => with_suffix(path, &format!(".orig.{n}")),
    })
}

/// The first backup name not taken (by any kind of file, a dangling link included). The
/// transaction creates it with `create_new`, so a name taken meanwhile is skipped, not
/// overwritten.
pub fn next_free_backup(path: &Path) -> PathBuf {
    backup_candidates(path)
        .find(|p| std::fs::symlink_metadata(p).is_err())
        .unwrap_or_else(|| backup_path(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_backups_after_the_first() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.mod");
        assert_eq!(next_free_backup(&f), dir.path().join("a.mod.orig"));
        std::fs::write(dir.path().join("a.mod.orig"), "x").unwrap();
        assert_eq!(next_free_backup(&f), dir.path().join("a.mod.orig.1"));
        std::fs::write(dir.path().join("a.mod.orig.1"), "x").unwrap();
        assert_eq!(next_free_backup(&f), dir.path().join("a.mod.orig.2"));
    }
}
