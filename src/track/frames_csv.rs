//! `frames.csv`: `skid,x,y,z,rx,ry,rz`, the robot base frame at each skid position in the
//! measurement frame (docs/design.md §6).

use std::fmt::Write as _;
use std::path::Path;

use super::csv_table::NumericCsv;
use super::profile::TrackError;
use crate::geometry::{Pose, pose_to_xyz_deg, pose_xyz_deg};

/// The header of `frames.csv`.
pub const FRAMES_HEADER: [&str; 7] = ["skid", "x", "y", "z", "rx", "ry", "rz"];

/// The robot base frame identified at one skid position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingFrame {
    /// The skid position, mm.
    pub skid: f64,
    /// The base frame identified there, in the measurement frame.
    pub pose: Pose,
}

/// Reads `frames.csv`; rows must be in strictly increasing skid order.
pub fn read_frames(path: &Path) -> Result<Vec<SamplingFrame>, TrackError> {
    frames_of(&NumericCsv::read(path, &FRAMES_HEADER)?)
}

/// The frames of a table read with [`FRAMES_HEADER`] (whose notes the caller shows).
pub fn frames_from(table: &NumericCsv) -> Result<Vec<SamplingFrame>, TrackError> {
    frames_of(table)
}

/// Parses `frames.csv` bytes; `path` is for messages only.
pub fn parse_frames(path: &Path, bytes: &[u8]) -> Result<Vec<SamplingFrame>, TrackError> {
    frames_of(&NumericCsv::parse(path, bytes, &FRAMES_HEADER)?)
}

fn frames_of(table: &NumericCsv) -> Result<Vec<SamplingFrame>, TrackError> {
    let mut frames: Vec<SamplingFrame> = Vec::with_capacity(table.rows.len());
    for (line, [skid, x, y, z, rx, ry, rz]) in table.select(&FRAMES_HEADER)? {
        if let Some(prev) = frames.last()
            && skid <= prev.skid
        {
            return Err(table.error(
                line,
                "skid",
                format!(
                    "skid {skid} does not follow {} in increasing order",
                    prev.skid
                ),
                "sort the rows by skid and keep one row per skid position",
            ));
        }
        frames.push(SamplingFrame {
            skid,
            pose: pose_xyz_deg(x, y, z, rx, ry, rz),
        });
    }
    if frames.len() < 2 {
        let line = table.rows.last().map_or(table.header_line, |r| r.line);
        return Err(table.error(
            line,
            "",
            format!(
                "{} sampling frame(s), a track model needs at least 2",
                frames.len()
            ),
            "identify the base frame at two or more skid positions (every 500 mm is usual)",
        ));
    }
    Ok(frames)
}

/// `frames.csv` text: mm with 4 decimals, degrees with 6, angles wrapped to (-180, 180].
pub fn frames_csv(frames: &[SamplingFrame]) -> String {
    let mut out = FRAMES_HEADER.join(",");
    out.push('\n');
    for f in frames {
        let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(&f.pose);
        let _ = writeln!(
            out,
            "{},{:.4},{:.4},{:.4},{:.6},{:.6},{:.6}",
            f.skid,
            clean(x, 4),
            clean(y, 4),
            clean(z, 4),
            clean(rx, 6),
            clean(ry, 6),
            clean(rz, 6)
        );
    }
    out
}

pub use crate::geometry::clean;
