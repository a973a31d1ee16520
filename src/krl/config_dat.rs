//! `$config.dat`: the controller's `BASE_DATA[n]` and `TOOL_DATA[n]` frames.

use std::path::Path;

use crate::position::{FrameDecl, FrameKind, ParsedFile};
use crate::program::{LoadError, read_source};

pub(crate) fn parse_config(path: &Path) -> Result<ParsedFile, LoadError> {
    Ok(parse_config_source(path, read_source(path)?))
}

pub(crate) fn parse_config_source(path: &Path, source: Vec<u8>) -> ParsedFile {
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
