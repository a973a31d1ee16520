//! Reading inputs safely: only regular files, and only up to a stated size, so that a FIFO
//! never blocks a run and `/dev/zero` is never read until memory runs out.

use std::io::Read as _;
use std::path::Path;

/// The largest input trackfix reads: 512 MiB. The largest real programs are tens of MB; a file
/// beyond this is not a program (or a profile, or a measurement table).
pub const MAX_INPUT_BYTES: u64 = 512 * 1024 * 1024;

/// Reads `path` whole if it is a regular file (a symlink to one is followed) of at most
/// `limit` bytes. Anything else is an [`std::io::ErrorKind::InvalidInput`] error that says what
/// the path is, without opening it (opening a FIFO for reading blocks until a writer comes).
pub fn read_regular_file(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    check_kind(&meta)?;
    check_size(meta.len(), limit)?;
    let file = std::fs::File::open(path)?;
    // The file may have been swapped or may grow between the check and the read.
    let meta = file.metadata()?;
    check_kind(&meta)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit + 1).read_to_end(&mut bytes)?;
    check_size(bytes.len() as u64, limit)?;
    Ok(bytes)
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
