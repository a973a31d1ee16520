//! The track model (docs/design.md §3): sampling frames, the straight nominal with its gear factor,
//! deviations, natural cubic splines, error bounds and the frequency scan.

pub mod adjustment;
pub mod cell_nominal;
pub mod csv_table;
pub mod error;
pub mod frames_csv;
pub mod gear;
pub mod identify;
pub mod nominal;
pub mod plot;
pub mod point_export;
pub mod profile;
pub mod simulate;
pub mod spectrum;
pub mod spline;
pub mod uncertainty;

pub use csv_table::NumericCsv;
pub use error::{LocatedError, NominalProblem, SkidProblem, TrackError};
pub use profile::{
    Extrapolate, Gear, Knot, KnotUncertainty, MeasuredIn, Nominal, Profile, Reference,
};
