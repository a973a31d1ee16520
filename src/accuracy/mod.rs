//! Accuracy analysis from laser-tracker measurements (thesis chapters 3 and 5): ISO 9283 pose
//! accuracy and repeatability ([`pose_accuracy`]), path accuracy and repeatability on planes
//! normal to the commanded path ([`path_accuracy`]), the straight-line report of Table 5.1
//! ([`LineReport`]), cutting a continuous recording into runs ([`RunInfo`]) and the figures
//! ([`pose_svg`], [`path_svgs`]).
//!
//! Conventions: mm, degrees, seconds; angles `rx, ry, rz` are compared component by component
//! as ISO 9283 does, each deviation wrapped to (-180, 180]. Standard deviations are over
//! `n − 1`. The contract is `docs/design.md §11`.

mod error;
mod line;
mod path;
mod plot;
mod pose;
mod segment;
pub mod simulate;
mod stats;
mod table;

pub use error::{AccuracyError, Located};
pub use line::{LegReport, LineReport};
pub use path::{
    Crossing, PathOptions, PathReport, PlaneAccuracy, Polyline, Projection, Recording, Run, Sample,
    path_accuracy, plane_crossing, read_commanded_path, read_recording,
};
pub use plot::{path_svg, path_svgs, pose_svg};
pub use pose::{
    Change, CommandedPose, PointAccuracy, PointChange, PoseComparison, PoseReport, PoseSummary,
    Visit, compare, pose_accuracy, read_commanded_poses, read_visits,
};
pub use segment::{Direction, RunInfo};
pub use table::ColumnMap;
