//! Accuracy analysis from laser-tracker measurements (thesis chapters 3 and 5): ISO 9283 pose
//! accuracy and repeatability ([`pose`]), path accuracy and repeatability on planes normal to
//! the commanded path ([`path`]), the straight-line report of Table 5.1 ([`line`]), cutting a
//! continuous recording into runs ([`segment`]) and the figures ([`plot`]).
//!
//! Conventions: mm, degrees, seconds; angles `rx, ry, rz` are compared component by component
//! as ISO 9283 does, each deviation wrapped to (-180, 180]. Standard deviations are over
//! `n − 1`. The contract is `docs/design-accuracy.md`.

pub mod error;
pub mod line;
pub mod path;
pub mod plot;
pub mod pose;
pub mod segment;
pub mod simulate;
pub mod stats;
pub mod table;

pub use error::{AccuracyError, Located};
pub use line::LineReport;
pub use path::{PathOptions, PathReport, PlaneAccuracy, Polyline, Recording, Run, Sample};
pub use pose::{CommandedPose, PointAccuracy, PoseComparison, PoseReport, PoseSummary, Visit};
pub use table::ColumnMap;
