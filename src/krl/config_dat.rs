//! `$config.dat`: the controller's `BASE_DATA[n]` and `TOOL_DATA[n]` frames.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use crate::output::InputBytes;
use crate::position::{FrameDecl, FrameKind, ParsedFile};
use crate::program::{LoadError, LoadOptions, read_source};

/// A `$config.dat` read and parsed once for every program of a run that uses it
/// ([`LoadOptions`]' own; clones share it).
#[derive(Clone, Debug, Default)]
pub struct ConfigDatOnce(Arc<OnceLock<(PathBuf, ParsedFile)>>);

impl ConfigDatOnce {
    /// The cell's `$config.dat` at `path` as a program carries it: parsed as [`parse_config`]
    /// parses it, with its frames only (its own positions, such as `XHOME`, are no program's).
    /// The first time read, then a copy of that reading; a reading of another path (options
    /// cloned with a different file) is not kept.
    pub(crate) fn get(&self, path: &Path) -> Result<ParsedFile, LoadError> {
        if let Some((kept, file)) = self.0.get()
            && kept == path
        {
            return Ok(file.clone());
        }
        let mut file = parse_config(path)?;
        file.positions.clear();
        if self.0.get().is_none() {
            let _ = self.0.set((path.to_owned(), file.clone()));
        }
        Ok(file)
    }
}

/// Read, not mapped: a `$config.dat` is small (and read once a run, [`ConfigDatOnce`]).
pub(crate) fn parse_config(path: &Path) -> Result<ParsedFile, LoadError> {
    Ok(parse_config_source(
        path,
        read_source(path, &LoadOptions::default())?,
    ))
}

pub(crate) fn parse_config_source(path: &Path, source: impl Into<InputBytes>) -> ParsedFile {
    super::parse_file(path, source)
}

/// The `BASE_DATA[n]` and `TOOL_DATA[n]` assignments of a parsed `$config.dat` (or any KRL file).
pub fn config_frames(file: &ParsedFile) -> Vec<FrameDecl> {
    file.frames
        .iter()
        .filter(|f| {
            matches!(f.kind, FrameKind::Base | FrameKind::Tool)
                && (f.name.starts_with("BASE_DATA[") || f.name.starts_with("TOOL_DATA["))
        })
        .cloned()
        .collect()
}

/// Reads a `$config.dat` and returns its bases and tools, named `BASE_DATA[n]` / `TOOL_DATA[n]`
/// with their frames (`FrameDecl::pose` gives the pose). Parse problems do not fail: the file's
/// diagnostics are available through [`crate::krl::parse_file`].
pub fn load_config_dat(path: &Path) -> Result<Vec<FrameDecl>, LoadError> {
    Ok(config_frames(&parse_config(path)?))
}
