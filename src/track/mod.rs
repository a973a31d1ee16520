//! The track model (DESIGN.md §3): sampling frames, the straight nominal with its gear factor,
//! deviations, natural cubic splines, error bounds and the frequency scan.
//!
//! Owned by issue 4.

pub mod profile;

pub use profile::{Profile, TrackError};
