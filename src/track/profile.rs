//! `profile.toml`: a fitted track profile and its evaluation `D(s)`.

use std::path::Path;

use crate::geometry::Pose;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrackError {
    #[error("skid {skid} mm is outside the profile's range [{min}, {max}] mm")]
    OutOfRange { skid: f64, min: f64, max: f64 },
    #[error("{0}")]
    Invalid(String),
}

/// A fitted track profile.
#[derive(Clone, Debug)]
pub struct Profile {}

impl Profile {
    /// Reads and validates a `profile.toml`.
    pub fn load(path: &Path) -> Result<Profile, TrackError> {
        Err(TrackError::Invalid(format!(
            "{}: profiles are not implemented yet",
            path.display()
        )))
    }

    /// `[s_0, s_N]`.
    pub fn skid_range(&self) -> (f64, f64) {
        (0.0, 0.0)
    }

    /// `D(s)`: the deviation of the real base from the nominal at skid `s`, in the nominal base
    /// frame (DESIGN.md §3). Outside the range per the profile's `extrapolate` setting.
    pub fn deviation(&self, skid: f64) -> Result<Pose, TrackError> {
        Err(TrackError::OutOfRange {
            skid,
            min: 0.0,
            max: 0.0,
        })
    }
}
