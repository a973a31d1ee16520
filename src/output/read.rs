//! Reading inputs safely: only regular files, and only up to a stated size, so that a FIFO
//! never blocks a run and `/dev/zero` is never read until memory runs out.

use std::io::Read as _;
use std::path::Path;
use std::sync::Arc;

/// The largest input trackfix reads: 512 MiB. The largest real programs are tens of MB; a file
/// beyond this is not a program (or a profile, or a measurement table).
pub const MAX_INPUT_BYTES: u64 = 512 * 1024 * 1024;

/// Reads `path` whole if it is a regular file (a symlink to one is followed) of at most
/// `limit` bytes. Anything else is an [`std::io::ErrorKind::InvalidInput`] error that says what
/// the path is, without opening it (opening a FIFO for reading blocks until a writer comes).
pub fn read_regular_file(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let (file, len) = open_regular(path, limit)?;
    read_open(file, len, limit)
}

/// `path` opened if it is a regular file of at most `limit` bytes (see
/// [`read_regular_file`]), with the length the open file has.
fn open_regular(path: &Path, limit: u64) -> std::io::Result<(std::fs::File, u64)> {
    let meta = std::fs::metadata(path)?;
    check_kind(&meta)?;
    check_size(meta.len(), limit)?;
    let file = std::fs::File::open(path)?;
    // The file may have been swapped or may grow between the check and the read.
    let meta = file.metadata()?;
    check_kind(&meta)?;
    super::run_files::note(path);
    Ok((file, meta.len()))
}

/// The bytes of an open file of about `len` bytes, refused beyond `limit`.
fn read_open(file: std::fs::File, len: u64, limit: u64) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    file.take(limit + 1).read_to_end(&mut bytes)?;
    check_size(bytes.len() as u64, limit)?;
    Ok(bytes)
}

/// An input's bytes: read into memory, or mapped from its file.
///
/// Reading a file copies it into fresh memory, and on a virtual machine fresh memory is dear:
/// each page costs a fault and a clearing, about 0.75 ms a MB here, so reading a 20 MB module
/// took 15-20 ms of system time of a 100 ms `check`. A mapped file's pages come from the page
/// cache, sixteen to a fault, and are neither cleared nor copied.
///
/// A map is only taken for runs that write no input ([`map_or_read_regular_file`]): a mapped
/// file that another process rewrites in place changes under the run, which a report or a
/// result written elsewhere can live with (it is of the file as it was read, or as it
/// became) but an in-place rewrite, whose transaction compares the file on disk with the
/// bytes it read before writing over it, cannot.
#[derive(Clone)]
pub struct InputBytes(Held);

#[derive(Clone)]
enum Held {
    Read(Vec<u8>),
    Mapped(Arc<memmap2::Mmap>),
}

impl InputBytes {
    /// The bytes, copied into a vector of their own (a mapped file's are copied).
    pub fn into_vec(self) -> Vec<u8> {
        match self.0 {
            Held::Read(v) => v,
            Held::Mapped(m) => m.to_vec(),
        }
    }

    /// Whether the bytes are mapped from their file rather than read.
    pub fn is_mapped(&self) -> bool {
        matches!(self.0, Held::Mapped(_))
    }
}

impl std::ops::Deref for InputBytes {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        match &self.0 {
            Held::Read(v) => v,
            Held::Mapped(m) => m,
        }
    }
}

impl AsRef<[u8]> for InputBytes {
    fn as_ref(&self) -> &[u8] {
        self
    }
}

impl From<Vec<u8>> for InputBytes {
    fn from(v: Vec<u8>) -> InputBytes {
        InputBytes(Held::Read(v))
    }
}

impl Default for InputBytes {
    fn default() -> InputBytes {
        InputBytes(Held::Read(Vec::new()))
    }
}

impl std::fmt::Debug for InputBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let how = if self.is_mapped() { "mapped" } else { "read" };
        write!(f, "InputBytes({} bytes {how})", self.len())
    }
}

impl PartialEq for InputBytes {
    fn eq(&self, other: &InputBytes) -> bool {
        **self == **other
    }
}

impl Eq for InputBytes {}

/// The smallest file [`map_or_read_regular_file`] maps: below it, setting up and tearing down a
/// map costs more than the copy it saves.
pub const MAP_FROM_BYTES: u64 = 1024 * 1024;

/// [`read_regular_file`], except that a file of [`MAP_FROM_BYTES`] or more is mapped, not read,
/// when `map` is set. For runs that write no input (see [`InputBytes`]).
pub fn map_or_read_regular_file(path: &Path, limit: u64, map: bool) -> std::io::Result<InputBytes> {
    if !map {
        return read_regular_file(path, limit).map(InputBytes::from);
    }
    let (file, len) = open_regular(path, limit)?;
    check_size(len, limit)?;
    if len >= MAP_FROM_BYTES {
        // A file system that cannot map (some network and FUSE mounts) is read instead.
        if let Ok(m) = map_file(&file) {
            return Ok(InputBytes(Held::Mapped(Arc::new(m))));
        }
    }
    read_open(file, len, limit).map(InputBytes::from)
}

#[allow(unsafe_code)]
fn map_file(file: &std::fs::File) -> std::io::Result<memmap2::Mmap> {
    // SAFETY: the map is read-only and private, and nothing in this process writes the file.
    // Another process may still change it while it is mapped: the bytes seen then are some
    // mix of the old and the new (see `InputBytes` for why only runs that write no input map),
    // and a file truncated under the map ends the run with SIGBUS, as it does ripgrep's. That
    // is the trade every mapping reader makes; no byte the run depends on is written through
    // the map.
    unsafe { memmap2::Mmap::map(file) }
}

/// [`read_regular_file`] with the one limit every input of trackfix shares.
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    read_regular_file(path, MAX_INPUT_BYTES)
}

fn check_kind(meta: &std::fs::Metadata) -> std::io::Result<()> {
    if meta.is_file() {
        return Ok(());
    }
    let what = if meta.is_dir() {
        "a directory"
    } else {
        kind_name(meta.file_type())
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("not a regular file ({what}); name a file"),
    ))
}

fn check_size(len: u64, limit: u64) -> std::io::Result<()> {
    if len <= limit {
        return Ok(());
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "larger than the {} MiB trackfix reads; not a program",
            limit / (1024 * 1024)
        ),
    ))
}

#[cfg(unix)]
fn kind_name(t: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

#[cfg(not(unix))]
fn kind_name(_: std::fs::FileType) -> &'static str {
    "not a file"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn refuses_devices_and_directories_without_reading() {
        let e = read_regular_file(Path::new("/dev/zero"), MAX_INPUT_BYTES).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("character device"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = read_regular_file(dir.path(), MAX_INPUT_BYTES).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
    }

    /// A file from the mapping size up is mapped when asked, a smaller one or one not asked for
    /// is read; the bytes are the file's either way, and what is not a regular file is still
    /// refused before it is opened.
    #[test]
    fn maps_large_files_only_when_asked() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.mod");
        let small = dir.path().join("small.mod");
        let bytes: Vec<u8> = (0..MAP_FROM_BYTES + 7).map(|i| (i % 251) as u8).collect();
        std::fs::write(&big, &bytes).unwrap();
        std::fs::write(&small, &bytes[..(MAP_FROM_BYTES - 1) as usize]).unwrap();
        let mapped = map_or_read_regular_file(&big, MAX_INPUT_BYTES, true).unwrap();
        assert!(mapped.is_mapped());
        assert!(mapped[..] == bytes[..]);
        assert!(mapped.clone().into_vec() == bytes);
        let read = map_or_read_regular_file(&big, MAX_INPUT_BYTES, false).unwrap();
        assert!(!read.is_mapped());
        assert_eq!(read, mapped);
        let small_read = map_or_read_regular_file(&small, MAX_INPUT_BYTES, true).unwrap();
        assert!(!small_read.is_mapped());
        assert!(small_read[..] == bytes[..(MAP_FROM_BYTES - 1) as usize]);
        let e = map_or_read_regular_file(&big, MAP_FROM_BYTES, true).unwrap_err();
        assert!(e.to_string().contains("larger than the 1 MiB"), "{e}");
        let e = map_or_read_regular_file(dir.path(), MAX_INPUT_BYTES, true).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        #[cfg(unix)]
        {
            let e = map_or_read_regular_file(Path::new("/dev/zero"), MAX_INPUT_BYTES, true)
                .unwrap_err();
            assert!(e.to_string().contains("character device"), "{e}");
        }
    }

    #[test]
    fn refuses_files_beyond_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("big.mod");
        std::fs::write(&f, vec![b'x'; 2 * 1024 * 1024 + 1]).unwrap();
        let e = read_regular_file(&f, 2 * 1024 * 1024).unwrap_err();
        assert!(e.to_string().contains("larger than the 2 MiB"), "{e}");
        assert_eq!(
            read_regular_file(&f, 3 * 1024 * 1024).unwrap().len(),
            2 * 1024 * 1024 + 1
        );
    }
}
