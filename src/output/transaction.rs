//! A run's writes as one transaction: every file is written or none is.
//!
//! Order: resolve and check every destination, take a lock beside each, verify that files
//! written in place still hold what the run read, create missing folders, write the backups,
//! write every new content to a temporary file beside its target, and only then rename the
//! temporaries over their targets. A file replaced that the run did not read (an earlier
//! output in an out dir) is first given a second name, so the run holds no copy of it. A
//! failure at any step undoes every step before it, in reverse: renamed targets get their old
//! file back (renamed back from its second name, or written from the bytes read), temporaries,
//! second names, backups, locks and created folders are removed. So a KRL pair never ends with
//! a new `.src` beside an old `.dat`.
//!
//! Temporaries, second names and locks carry names a later run recognises
//! (`.NAME.trackfix-tmp-PID`, `.NAME.trackfix-old-PID`, `.NAME.trackfix-lock` holding the PID): a run removes those whose process is gone from every
//! folder it writes to, so even a kill leaves nothing a later run does not clean up.
//!
//! Every change to the file system goes through [`Filesystem`], so tests can fail the k-th
//! operation for every k (and simulate a full disk) and check that nothing was lost or left.

use std::borrow::Cow;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::OutputError;
use super::backup::backup_candidates;
use super::paths::{hidden_sibling, identity};

/// One file to write.
///
/// The contents are borrowed where they can be ([`plan`](super::plan) lends each result's
/// output and original): a run's outputs are as large as its inputs, and a copy of each for
/// the write was a third of `correct`'s peak memory on a large program.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileWrite<'a> {
    /// The input file the contents came from (for the summary).
    pub input: PathBuf,
    /// The destination as named (a symlink is followed to its target when written).
    pub path: PathBuf,
    /// The new contents.
    pub bytes: Cow<'a, [u8]>,
    /// In place: the contents the run read. The write is refused if the file changed since
    /// (another run applied first), and the backup holds exactly these bytes.
    pub expected: Option<Cow<'a, [u8]>>,
    /// In place: keep a backup (`FILE.orig`, or the next free `FILE.orig.N`).
    pub backup: bool,
}

/// One file a committed run wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Written {
    /// The input the file was made from.
    pub input: PathBuf,
    /// The destination as named.
    pub path: PathBuf,
    /// The file actually replaced when `path` is a symlink.
    pub resolved: Option<PathBuf>,
    /// Where the replaced file was kept, when a backup was made.
    pub backup: Option<PathBuf>,
}

/// The file-system operations a transaction performs; the seam where tests inject faults.
pub trait Filesystem {
    /// Creates one directory (its parent exists).
    fn create_dir(&self, path: &Path) -> std::io::Result<()>;
    /// Creates `path` (it must not exist), writes `bytes`, sets `mode` (Unix permission bits;
    /// `None`: 0644 less the umask) and syncs.
    fn write_new(&self, path: &Path, bytes: &[u8], mode: Option<u32>) -> std::io::Result<()>;
    /// Renames `from` to `to`, replacing `to` atomically.
    fn rename(&self, from: &Path, to: &Path) -> std::io::Result<()>;
    /// Gives the file `original` a second name, `link` (which must not exist).
    fn hard_link(&self, original: &Path, link: &Path) -> std::io::Result<()>;
    /// Removes a file.
    fn remove_file(&self, path: &Path) -> std::io::Result<()>;
    /// Removes an empty directory.
    fn remove_dir(&self, path: &Path) -> std::io::Result<()>;
}

/// The real file system.
pub struct RealFs;

impl Filesystem for RealFs {
    fn create_dir(&self, path: &Path) -> std::io::Result<()> {
        std::fs::create_dir(path)
    }

    fn write_new(&self, path: &Path, bytes: &[u8], mode: Option<u32>) -> std::io::Result<()> {
        let mut options = std::fs::OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt as _;
            // Never wider than the final mode while the contents are written.
            options.mode(if mode.is_some() { 0o600 } else { 0o644 });
        }
        let mut file = options.open(path)?;
        let written = (|| {
            file.write_all(bytes)?;
            #[cfg(unix)]
            if let Some(m) = mode {
                use std::os::unix::fs::PermissionsExt as _;
                file.set_permissions(std::fs::Permissions::from_mode(m))?;
            }
            #[cfg(not(unix))]
            let _ = mode;
            file.sync_all()
        })();
        if written.is_err() {
            drop(file);
            let _ = std::fs::remove_file(path);
        }
        written
    }

    fn rename(&self, from: &Path, to: &Path) -> std::io::Result<()> {
        std::fs::rename(from, to)
    }

    fn hard_link(&self, original: &Path, link: &Path) -> std::io::Result<()> {
        std::fs::hard_link(original, link)
    }

    fn remove_file(&self, path: &Path) -> std::io::Result<()> {
        std::fs::remove_file(path)
    }

    fn remove_dir(&self, path: &Path) -> std::io::Result<()> {
        std::fs::remove_dir(path)
    }
}

const TEMP_MARK: &str = ".trackfix-tmp-";
const KEPT_MARK: &str = ".trackfix-old-";
const LOCK_MARK: &str = ".trackfix-lock";
/// A lock without a process id this old is left by a killed run.
const EMPTY_LOCK_STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(10);

/// `dir/.NAME.trackfix-tmp-PID`: the temporary file beside `target`.
pub fn temp_path(target: &Path) -> PathBuf {
    hidden_sibling(target, &format!("{TEMP_MARK}{}", std::process::id()))
}

/// `dir/.NAME.trackfix-old-PID`: a second name for the file `target` held before the run
/// replaced it, so a rollback can put it back without a copy of its bytes.
fn kept_path(target: &Path) -> PathBuf {
    hidden_sibling(target, &format!("{KEPT_MARK}{}", std::process::id()))
}

/// `dir/.NAME.trackfix-lock`: the lock beside `target`.
pub fn lock_path(target: &Path) -> PathBuf {
    hidden_sibling(target, LOCK_MARK)
}

/// Whether process `pid` still runs. Without `/proc` this cannot be told, and a leftover is
/// kept rather than a live run's file removed.
fn process_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return true;
    }
    pid == std::process::id() || proc.join(pid.to_string()).exists()
}

fn lock_holder(lock: &Path) -> Option<u32> {
    std::fs::read_to_string(lock).ok()?.trim().parse().ok()
}

/// Removes the temporaries, kept names and locks of runs that are gone (killed) from `dir`;
/// returns what it removed. Files of live runs and every other file are left alone.
pub fn clean_stale(dir: &Path) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    let Ok(entries) = std::fs::read_dir(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    }) else {
        return removed;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        if !name.starts_with('.') {
            continue;
        }
        let of_pid = |mark: &str| {
            name.rfind(mark)
                .map(|pos| name[pos + mark.len()..].parse::<u32>())
        };
        let stale = if let Some(pid) = of_pid(TEMP_MARK).or_else(|| of_pid(KEPT_MARK)) {
            pid.is_ok_and(|pid| pid != std::process::id() && !process_alive(pid))
        } else if name.ends_with(LOCK_MARK) {
            match lock_holder(&entry.path()) {
                Some(pid) => !process_alive(pid),
                // Killed between creating the lock and writing its process id (a window of
                // microseconds): stale once it is older than any run takes to fill it.
                None => entry
                    .metadata()
                    .and_then(|m| m.modified())
                    .ok()
                    .and_then(|t| t.elapsed().ok())
                    .is_some_and(|age| age > EMPTY_LOCK_STALE_AFTER),
            }
        } else {
            false
        };
        if stale && entry.file_type().is_ok_and(|t| t.is_file()) {
            let path = entry.path();
            if std::fs::remove_file(&path).is_ok() {
                removed.push(path);
            }
        }
    }
    removed
}

/// A destination, resolved.
struct Target<'a> {
    write: &'a FileWrite<'a>,
    /// The file to replace: `write.path`, or the target of the symlink it names.
    real: PathBuf,
    existed: bool,
    /// Unix permission bits of the replaced file (kept), `None` for a new file.
    mode: Option<u32>,
}

fn io_err(path: &Path, error: std::io::Error) -> OutputError {
    // The lock and the temporary are hidden siblings with a suffix: a name the file system
    // takes may be too long for them.
    let error = if error.kind() == std::io::ErrorKind::InvalidFilename {
        std::io::Error::new(
            error.kind(),
            format!(
                "{error}: trackfix writes `.NAME{TEMP_MARK}PID` and `.NAME{LOCK_MARK}` beside the file, which need about 30 bytes more than its name; shorten the name"
            ),
        )
    } else {
        error
    };
    OutputError::Io {
        path: path.to_owned(),
        error,
    }
}

#[cfg(unix)]
fn mode_of(meta: &std::fs::Metadata) -> Option<u32> {
    use std::os::unix::fs::PermissionsExt as _;
    Some(meta.permissions().mode() & 0o777)
}

#[cfg(not(unix))]
fn mode_of(_: &std::fs::Metadata) -> Option<u32> {
    None
}

fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

fn resolve<'a>(write: &'a FileWrite<'a>) -> Result<Target<'a>, OutputError> {
    let path = &write.path;
    let (real, meta) = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Target {
                write,
                real: path.clone(),
                existed: false,
                mode: None,
            });
        }
        Err(e) => return Err(io_err(path, e)),
        Ok(m) if m.file_type().is_symlink() => {
            let real = std::fs::canonicalize(path).map_err(|_| OutputError::NotAFile {
                path: path.clone(),
                what: "a symlink to a missing file",
            })?;
            let meta = std::fs::metadata(&real).map_err(|e| io_err(&real, e))?;
            (real, meta)
        }
        Ok(m) => (path.clone(), m),
    };
    if !meta.is_file() {
        return Err(OutputError::NotAFile {
            path: path.clone(),
            what: kind_of(&meta),
        });
    }
    Ok(Target {
        write,
        real,
        existed: true,
        mode: mode_of(&meta),
    })
}

/// What has been done so far, to be undone on failure.
#[derive(Default)]
struct Journal {
    dirs: Vec<PathBuf>,
    locks: Vec<PathBuf>,
    backups: Vec<PathBuf>,
    temps: Vec<PathBuf>,
    /// Indices of targets whose temporary has been renamed over them.
    renamed: Vec<usize>,
    /// Targets replaced that were not read (an earlier output in an out dir), each under a
    /// second name ([`kept_path`]) until the run ends: a rollback renames it back.
    kept: Vec<(usize, PathBuf)>,
    /// The same, read into memory where the file system has no hard links.
    old: Vec<(usize, Vec<u8>)>,
}

/// Folders missing above `path`, outermost first.
fn missing_dirs(path: &Path) -> Vec<PathBuf> {
    let mut missing = Vec::new();
    let mut dir = path.parent();
    while let Some(d) = dir {
        if d.as_os_str().is_empty() || std::fs::symlink_metadata(d).is_ok() {
            break;
        }
        missing.push(d.to_owned());
        dir = d.parent();
    }
    missing.reverse();
    missing
}

/// Commits `writes` on the real file system.
pub fn commit(writes: &[FileWrite<'_>]) -> Result<Vec<Written>, OutputError> {
    let written = commit_with(&RealFs, writes)?;
    for w in &written {
        super::run_files::note(&w.path);
        if let Some(b) = &w.backup {
            super::run_files::note(b);
        }
    }
    Ok(written)
}

/// Commits `writes` through `fs`: all of them, or (on any failure) none, with everything
/// restored.
pub fn commit_with(
    fs: &dyn Filesystem,
    writes: &[FileWrite<'_>],
) -> Result<Vec<Written>, OutputError> {
    let mut targets = Vec::with_capacity(writes.len());
    let mut seen = std::collections::BTreeSet::new();
    for w in writes {
        let t = resolve(w)?;
        if !seen.insert(identity(&t.real)) {
            return Err(OutputError::Duplicate {
                path: w.path.clone(),
            });
        }
        targets.push(t);
    }
    let mut journal = Journal::default();
    match run(fs, &targets, &mut journal) {
        Ok(backups) => {
            // The run is complete: the names the replaced files were kept under, and the
            // locks, are no longer needed; one whose removal fails is stale and the next run
            // removes it.
            for (_, kept) in &journal.kept {
                let _ = fs.remove_file(kept);
            }
            for lock in &journal.locks {
                let _ = fs.remove_file(lock);
            }
            Ok(targets
                .iter()
                .zip(backups)
                .map(|(t, backup)| Written {
                    input: t.write.input.clone(),
                    path: t.write.path.clone(),
                    resolved: (t.real != t.write.path).then(|| t.real.clone()),
                    backup,
                })
                .collect())
        }
        Err(error) => {
            let failures = rollback(fs, &targets, &journal);
            if failures.is_empty() {
                Err(error)
            } else {
                Err(OutputError::RollbackFailed {
                    error: Box::new(error),
                    failures: failures
                        .into_iter()
                        .map(|(p, e)| format!("{}: {e}", p.display()))
                        .collect(),
                })
            }
        }
    }
}

fn run(
    fs: &dyn Filesystem,
    targets: &[Target<'_>],
    journal: &mut Journal,
) -> Result<Vec<Option<PathBuf>>, OutputError> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    for t in targets {
        for d in missing_dirs(&t.real) {
            if !dirs.contains(&d) {
                dirs.push(d);
            }
        }
    }
    for d in dirs {
        fs.create_dir(&d).map_err(|e| io_err(&d, e))?;
        journal.dirs.push(d);
    }
    let mut cleaned = std::collections::BTreeSet::new();
    for t in targets {
        let dir = t.real.parent().unwrap_or(Path::new("")).to_owned();
        if cleaned.insert(dir.clone()) {
            clean_stale(&dir);
        }
    }
    for t in targets {
        lock(fs, t, journal)?;
    }
    for t in targets {
        if let Some(expected) = &t.write.expected {
            let now = std::fs::read(&t.real).map_err(|e| io_err(&t.real, e))?;
            if now != **expected {
                return Err(OutputError::ChangedSinceRead {
                    path: t.write.path.clone(),
                });
            }
        }
    }
    let mut backups = Vec::with_capacity(targets.len());
    for t in targets {
        backups.push(match (&t.write.expected, t.write.backup) {
            (Some(original), true) => Some(write_backup(fs, t, original, journal)?),
            _ => None,
        });
    }
    for (i, t) in targets.iter().enumerate() {
        if t.existed && t.write.expected.is_none() {
            keep_replaced(fs, i, t, journal)?;
        }
    }
    for t in targets {
        let tmp = temp_path(&t.real);
        // A temporary of this name is from an earlier process with the same id.
        let _ = std::fs::remove_file(&tmp);
        journal.temps.push(tmp.clone());
        fs.write_new(&tmp, &t.write.bytes, t.mode)
            .map_err(|e| io_err(&t.write.path, e))?;
    }
    for (i, t) in targets.iter().enumerate() {
        let tmp = temp_path(&t.real);
        fs.rename(&tmp, &t.real)
            .map_err(|e| io_err(&t.write.path, e))?;
        journal.temps.retain(|p| p != &tmp);
        journal.renamed.push(i);
    }
    Ok(backups)
}

/// Keeps what `t` holds now, which the run did not read (an earlier output), for a rollback:
/// a second name costs no memory, where a copy of an out dir's files would add their size to
/// the run's peak. Without hard links (some network shares and FAT volumes) the bytes are
/// read instead.
fn keep_replaced(
    fs: &dyn Filesystem,
    i: usize,
    t: &Target<'_>,
    journal: &mut Journal,
) -> Result<(), OutputError> {
    let kept = kept_path(&t.real);
    // A file of this name is from an earlier process with the same id.
    let _ = std::fs::remove_file(&kept);
    match fs.hard_link(&t.real, &kept) {
        Ok(()) => journal.kept.push((i, kept)),
        Err(_) => {
            let old = std::fs::read(&t.real).map_err(|e| io_err(&t.real, e))?;
            journal.old.push((i, old));
        }
    }
    Ok(())
}

fn lock(fs: &dyn Filesystem, t: &Target<'_>, journal: &mut Journal) -> Result<(), OutputError> {
    let lock = lock_path(&t.real);
    let pid = std::process::id().to_string();
    if std::fs::symlink_metadata(&lock).is_ok() {
        return Err(OutputError::Locked {
            path: t.write.path.clone(),
            pid: lock_holder(&lock),
        });
    }
    match fs.write_new(&lock, pid.as_bytes(), None) {
        Ok(()) => {
            journal.locks.push(lock);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(OutputError::Locked {
            path: t.write.path.clone(),
            pid: lock_holder(&lock),
        }),
        Err(e) => {
            // A partly written lock is ours to remove; one never created (a read-only folder,
            // a name too long) is nothing to undo.
            if std::fs::symlink_metadata(&lock).is_ok() {
                journal.locks.push(lock);
            }
            Err(io_err(&t.write.path, e))
        }
    }
}

fn write_backup(
    fs: &dyn Filesystem,
    t: &Target<'_>,
    original: &[u8],
    journal: &mut Journal,
) -> Result<PathBuf, OutputError> {
    for candidate in backup_candidates(&t.write.path) {
        // Taken names are skipped without a try: a failed try on a name that is not ours
        // must never make the rollback remove it.
        if std::fs::symlink_metadata(&candidate).is_ok() {
            continue;
        }
        match fs.write_new(&candidate, original, t.mode) {
            Ok(()) => {
                journal.backups.push(candidate.clone());
                return Ok(candidate);
            }
            // Taken (a backup of an earlier run, or anything else): never overwritten.
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => {
                // Partly written, ours to remove; never created, nothing to undo.
                if std::fs::symlink_metadata(&candidate).is_ok() {
                    journal.backups.push(candidate.clone());
                }
                return Err(io_err(&candidate, e));
            }
        }
    }
    unreachable!("backup candidates never end")
}

/// Undoes `journal` in reverse; returns what could not be undone.
fn rollback(
    fs: &dyn Filesystem,
    targets: &[Target<'_>],
    journal: &Journal,
) -> Vec<(PathBuf, std::io::Error)> {
    let mut failures = Vec::new();
    let mut note = |path: &Path, r: std::io::Result<()>| match r {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            failures.push((path.to_owned(), e));
            false
        }
        _ => true,
    };
    let mut restored_all = true;
    for &i in journal.renamed.iter().rev() {
        let Some(t) = targets.get(i) else { continue };
        if !t.existed {
            note(&t.real, fs.remove_file(&t.real));
            continue;
        }
        if let Some((_, kept)) = journal.kept.iter().find(|(k, _)| *k == i) {
            // The file it replaced, under its second name: renamed back, atomically.
            restored_all &= note(&t.real, fs.rename(kept, &t.real));
            continue;
        }
        let old = journal
            .old
            .iter()
            .find(|(k, _)| *k == i)
            .map(|(_, b)| b.as_slice())
            .or(t.write.expected.as_deref())
            .unwrap_or_default();
        let tmp = temp_path(&t.real);
        let _ = fs.remove_file(&tmp);
        let ok =
            note(&tmp, fs.write_new(&tmp, old, t.mode)) && note(&t.real, fs.rename(&tmp, &t.real));
        if !ok {
            restored_all = false;
            let _ = fs.remove_file(&tmp);
        }
    }
    // The second name of a file never replaced is an extra name only. One that was put back
    // is gone with the rename; where the rename back failed it is the only copy of the old
    // file, and kept.
    for (i, kept) in journal.kept.iter().rev() {
        if !journal.renamed.contains(i) {
            note(kept, fs.remove_file(kept));
        }
    }
    for tmp in journal.temps.iter().rev() {
        note(tmp, fs.remove_file(tmp));
    }
    // A backup is the only copy of an original that could not be restored: keep them then.
    if restored_all {
        for b in journal.backups.iter().rev() {
            note(b, fs.remove_file(b));
        }
    }
    for l in journal.locks.iter().rev() {
        note(l, fs.remove_file(l));
    }
    for d in journal.dirs.iter().rev() {
        note(d, fs.remove_dir(d));
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;
    use std::collections::BTreeMap;

    /// How the injected fault shows.
    #[derive(Clone, Copy, Debug)]
    enum Fault {
        /// The operation fails and does nothing.
        Error,
        /// The disk is full: a write leaves half its bytes behind and fails with ENOSPC
        /// (like a real full disk); other operations fail with ENOSPC.
        DiskFull,
    }

    /// The real file system, failing its `fail_at`-th operation (counting from 0); without
    /// `links`, a file system that cannot make hard links.
    struct FaultFs {
        fail_at: usize,
        fault: Fault,
        count: Cell<usize>,
        links: bool,
    }

    impl FaultFs {
        fn new(fail_at: usize, fault: Fault) -> FaultFs {
            FaultFs {
                fail_at,
                fault,
                count: Cell::new(0),
                links: true,
            }
        }

        fn without_links(self) -> FaultFs {
            FaultFs {
                links: false,
                ..self
            }
        }

        fn fails_now(&self) -> bool {
            let n = self.count.get();
            self.count.set(n + 1);
            n == self.fail_at
        }

        fn error(&self) -> std::io::Error {
            match self.fault {
                Fault::Error => std::io::Error::other("injected fault"),
                // ENOSPC on Linux and macOS.
                Fault::DiskFull => std::io::Error::from_raw_os_error(28),
            }
        }
    }

    impl Filesystem for FaultFs {
        fn create_dir(&self, path: &Path) -> std::io::Result<()> {
            if self.fails_now() {
                return Err(self.error());
            }
            RealFs.create_dir(path)
        }
        fn write_new(&self, path: &Path, bytes: &[u8], mode: Option<u32>) -> std::io::Result<()> {
            if self.fails_now() {
                if let Fault::DiskFull = self.fault {
                    let mut f = std::fs::OpenOptions::new()
                        .write(true)
                        .create_new(true)
                        .open(path)?;
                    f.write_all(&bytes[..bytes.len() / 2])?;
                }
                return Err(self.error());
            }
            RealFs.write_new(path, bytes, mode)
        }
        fn rename(&self, from: &Path, to: &Path) -> std::io::Result<()> {
            if self.fails_now() {
                return Err(self.error());
            }
            RealFs.rename(from, to)
        }
        fn hard_link(&self, original: &Path, link: &Path) -> std::io::Result<()> {
            // Counted either way, so the k-th operation is the same step with or without links.
            let fails = self.fails_now();
            if !self.links {
                return Err(std::io::ErrorKind::Unsupported.into());
            }
            if fails {
                return Err(self.error());
            }
            RealFs.hard_link(original, link)
        }
        fn remove_file(&self, path: &Path) -> std::io::Result<()> {
            if self.fails_now() {
                return Err(self.error());
            }
            RealFs.remove_file(path)
        }
        fn remove_dir(&self, path: &Path) -> std::io::Result<()> {
            if self.fails_now() {
                return Err(self.error());
            }
            RealFs.remove_dir(path)
        }
    }

    /// Every file and folder under `root` with its contents (folders: `None`).
    fn snapshot(root: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
        walkdir::WalkDir::new(root)
            .into_iter()
            .map(|e| e.unwrap())
            .map(|e| {
                let bytes = e
                    .file_type()
                    .is_file()
                    .then(|| std::fs::read(e.path()).unwrap());
                (e.path().to_owned(), bytes)
            })
            .collect()
    }

    fn write(input: &Path, path: &Path, bytes: &str, in_place: bool) -> FileWrite<'static> {
        FileWrite {
            input: input.to_owned(),
            path: path.to_owned(),
            bytes: bytes.as_bytes().to_vec().into(),
            expected: in_place.then(|| std::fs::read(input).unwrap().into()),
            backup: in_place,
        }
    }

    /// A KRL pair corrected in place (backups), a module written into new folders of an
    /// output tree, and one over an earlier output: 2 locks + 2 backups + 2 temporaries + 2
    /// renames + 2 unlocks; 2 folders + 1 lock + 1 temporary + 1 rename + 1 unlock; 1 lock + 1
    /// second name + 1 temporary + 1 rename + 1 removal of the second name + 1 unlock.
    fn scenario(root: &Path) -> Vec<FileWrite<'static>> {
        let src = root.join("spot.src");
        let dat = root.join("spot.dat");
        std::fs::write(&src, "DEF spot()\nEND\n").unwrap();
        std::fs::write(&dat, "DEFDAT spot\nENDDAT\n").unwrap();
        // An earlier run's backup, which must survive everything.
        std::fs::write(root.join("spot.src.orig"), "first original\n").unwrap();
        let module = root.join("main.mod");
        std::fs::write(&module, "MODULE m\nENDMODULE\n").unwrap();
        std::fs::create_dir(root.join("prev")).unwrap();
        let earlier = root.join("prev/main.mod");
        std::fs::write(&earlier, "MODULE earlier\nENDMODULE\n").unwrap();
        // The earlier output is not last, so a later rename's failure puts it back.
        vec![
            write(&src, &src, "DEF spot()\n; new\nEND\n", true),
            write(&dat, &dat, "DEFDAT spot\n; new\nENDDAT\n", true),
            write(&module, &earlier, "MODULE again\nENDMODULE\n", false),
            write(
                &module,
                &root.join("out/task/main.mod"),
                "MODULE n\nENDMODULE\n",
                false,
            ),
        ]
    }

    #[test]
    fn a_fault_at_any_step_restores_everything_and_leaves_nothing() {
        // The number of operations of a run without faults.
        let dir = tempfile::tempdir().unwrap();
        let writes = scenario(dir.path());
        let counting = FaultFs::new(usize::MAX, Fault::Error);
        commit_with(&counting, &writes).unwrap();
        let ops = counting.count.get();
        assert_eq!(
            ops,
            2 + 4 + 2 + 1 + 4 + 4 + 1 + 4,
            "create 2 folders, lock, back up, keep the earlier output, write, rename, \
             remove its second name, unlock"
        );

        // Without hard links the earlier output is read instead: no second name to remove.
        let dir = tempfile::tempdir().unwrap();
        let writes = scenario(dir.path());
        let counting = FaultFs::new(usize::MAX, Fault::Error).without_links();
        commit_with(&counting, &writes).unwrap();
        let ops_without_links = counting.count.get();
        assert_eq!(ops_without_links, ops - 1);

        // After the folders, locks and backups: the second name of the earlier output.
        const LINK_OP: usize = 2 + 4 + 2;
        for (fault, links) in [
            (Fault::Error, true),
            (Fault::DiskFull, true),
            (Fault::Error, false),
        ] {
            let ops = if links { ops } else { ops_without_links };
            for k in 0..ops {
                let dir = tempfile::tempdir().unwrap();
                let writes = scenario(dir.path());
                let before = snapshot(dir.path());
                let fs = FaultFs::new(k, fault);
                let fs = if links { fs } else { fs.without_links() };
                let result = commit_with(&fs, &writes);
                match result {
                    Err(e) => {
                        // Byte-identical originals, no partial output, no leftover file or folder.
                        assert_eq!(
                            snapshot(dir.path()),
                            before,
                            "{fault:?} at operation {k}: {e}"
                        );
                    }
                    Ok(_) => {
                        // Only a failed hard link (the earlier output is read instead), a
                        // failed unlock, or a failed removal of a replaced file's second name
                        // lets the run succeed: every output is complete and that stale file is
                        // the only extra one, which the next run removes.
                        for w in &writes {
                            assert_eq!(
                                std::fs::read(&w.path).unwrap(),
                                *w.bytes,
                                "{fault:?} at {k}"
                            );
                        }
                        let removed = clean_stale_of_dead_run(dir.path());
                        if k == LINK_OP {
                            assert_eq!(removed, Vec::<PathBuf>::new(), "{fault:?} at {k}");
                            continue;
                        }
                        assert_eq!(removed.len(), 1, "{fault:?} at {k}: {removed:?}");
                        let name = removed[0].to_string_lossy();
                        assert!(
                            name.ends_with(LOCK_MARK) || name.contains(KEPT_MARK),
                            "{name}"
                        );
                    }
                }
            }
        }
    }

    /// A lock of this very process looks live; pretend it was left by a killed run.
    fn clean_stale_of_dead_run(root: &Path) -> Vec<PathBuf> {
        let mut removed = Vec::new();
        for e in walkdir::WalkDir::new(root).into_iter().map(|e| e.unwrap()) {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(LOCK_MARK) || name.contains(TEMP_MARK) || name.contains(KEPT_MARK) {
                std::fs::remove_file(e.path()).unwrap();
                removed.push(e.path().to_owned());
            }
        }
        removed
    }

    #[test]
    fn a_successful_run_keeps_old_backups_and_numbers_the_new_one() {
        let dir = tempfile::tempdir().unwrap();
        let writes = scenario(dir.path());
        let written = commit(&writes).unwrap();
        assert_eq!(
            written[0].backup.as_deref(),
            Some(dir.path().join("spot.src.orig.1").as_path())
        );
        assert_eq!(
            written[1].backup.as_deref(),
            Some(dir.path().join("spot.dat.orig").as_path())
        );
        assert_eq!(
            std::fs::read_to_string(dir.path().join("spot.src.orig")).unwrap(),
            "first original\n"
        );
        assert_eq!(
            std::fs::read_to_string(dir.path().join("spot.src.orig.1")).unwrap(),
            "DEF spot()\nEND\n"
        );
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(names.is_empty(), "{names:?}");
    }

    #[test]
    fn a_file_changed_since_it_was_read_is_not_overwritten() {
        let dir = tempfile::tempdir().unwrap();
        let writes = scenario(dir.path());
        // Another run applied first.
        std::fs::write(
            dir.path().join("spot.dat"),
            "DEFDAT spot\n; other\nENDDAT\n",
        )
        .unwrap();
        let before = snapshot(dir.path());
        let e = commit(&writes).unwrap_err();
        assert!(matches!(e, OutputError::ChangedSinceRead { .. }), "{e}");
        assert_eq!(snapshot(dir.path()), before);
    }

    #[test]
    fn a_live_lock_refuses_and_a_dead_ones_is_cleaned() {
        let dir = tempfile::tempdir().unwrap();
        let writes = scenario(dir.path());
        let lock = lock_path(&dir.path().join("spot.dat"));
        // PID 1 always runs.
        std::fs::write(&lock, "1").unwrap();
        let before = snapshot(dir.path());
        let e = commit(&writes).unwrap_err();
        assert!(matches!(e, OutputError::Locked { pid: Some(1), .. }), "{e}");
        assert_eq!(snapshot(dir.path()), before);
        // A process that has exited.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        std::fs::write(&lock, dead.to_string()).unwrap();
        let stale_temp = dir.path().join(format!(".spot.src{TEMP_MARK}{dead}"));
        std::fs::write(&stale_temp, "half").unwrap();
        commit(&writes).unwrap();
        assert!(!lock.exists() && !stale_temp.exists());
        // A run killed between creating its lock and writing its id leaves an empty lock: held
        // while fresh, stale once old.
        std::fs::write(&lock, "").unwrap();
        let e = commit(&writes).unwrap_err();
        assert!(matches!(e, OutputError::Locked { pid: None, .. }), "{e}");
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(60);
        std::fs::File::options()
            .write(true)
            .open(&lock)
            .unwrap()
            .set_modified(old)
            .unwrap();
        assert_eq!(clean_stale(dir.path()), vec![lock]);
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_are_followed_and_modes_kept_never_widened() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let real_dir = dir.path().join("real");
        std::fs::create_dir(&real_dir).unwrap();
        let real = real_dir.join("a.mod");
        std::fs::write(&real, "old\n").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.path().join("a.mod");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let mut w = write(&link, &link, "new\n", true);
        w.expected = Some(b"old\n"[..].into());
        let written = commit(&[w]).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "new\n");
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&real), 0o640);
        let backup = written[0].backup.clone().unwrap();
        assert_eq!(backup, dir.path().join("a.mod.orig"));
        assert_eq!(mode(&backup), 0o640);
        // A new file is 0644 at most.
        let new = dir.path().join("new.mod");
        commit(&[write(&real, &new, "x\n", false)]).unwrap();
        assert_eq!(mode(&new) & !0o644, 0);
        // A backup name taken by a symlink is skipped, its target untouched.
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "keep\n").unwrap();
        std::os::unix::fs::symlink(&victim, dir.path().join("a.mod.orig.1")).unwrap();
        let mut w = write(&link, &link, "newer\n", true);
        w.expected = Some(b"new\n"[..].into());
        let written = commit(&[w]).unwrap();
        assert_eq!(
            written[0].backup.as_deref(),
            Some(dir.path().join("a.mod.orig.2").as_path())
        );
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep\n");
    }

    #[test]
    fn a_directory_in_the_way_is_refused_before_anything_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let mut writes = scenario(dir.path());
        std::fs::create_dir_all(dir.path().join("out/task/main.mod")).unwrap();
        writes.rotate_left(2);
        let before = snapshot(dir.path());
        let e = commit(&writes).unwrap_err();
        assert!(
            matches!(
                e,
                OutputError::NotAFile {
                    what: "a directory",
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(snapshot(dir.path()), before);
    }
}
