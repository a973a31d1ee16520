//! The track model (DESIGN.md §3): sampling frames, the straight nominal with its gear factor,
//! deviations, natural cubic splines, error bounds and the frequency scan.
//!
//! Owned by issue 4.

pub mod adjustment;
pub mod csv_table;
pub mod frames_csv;
pub mod identify;
pub mod nominal;
pub mod plot;
pub mod profile;
pub mod simulate;
pub mod spectrum;
pub mod spline;
pub mod uncertainty;

pub use csv_table::NumericCsv;
pub use profile::{
    Extrapolate, Gear, Knot, KnotUncertainty, Nominal, Profile, Reference, TrackError,
};
