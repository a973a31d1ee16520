//! Program transforms (docs/design.md §4): `correct`, `zero`, `mirror`, `transfer`, and the cell
//! file that describes robots, tracks and the mirror plane.
//!
//! Every transform reads a [`Program`](crate::position::Program) and returns
//! [`ProgramEdits`]: per file, the [`Edit`](crate::syntax::Edit)s of the numeric literals that
//! change, the targets it refused, and how much each changed target moved. Nothing is written
//! here; [`output`] turns applied edits into files, diffs and checks.

pub mod cell;
mod driver;
pub mod edits;
pub mod kinematic_policy;
pub mod mirror;
pub mod output;
pub(crate) mod policy;
pub mod refusal;
pub mod rename;
pub(crate) mod rewrite;
pub mod stamp;
pub mod track_correction;
pub mod transfer;

pub use cell::{Axis, Cell, CellError, ConfigRule, FrameIn, MirrorTable, Plane, Robot};
pub use edits::{
    ChangeRef, Changes, FileEdits, FileResult, ProgramEdits, ProgramResult, TargetChange, apply,
    apply_owned,
};
pub use kinematic_policy::Arm;
pub use mirror::{ImageRobot, MirrorArm, MirrorSettings, WorldPlane, mirror};
pub use refusal::{Refusal, RefusalKind, Remedy};
pub use stamp::Stamp;
pub use track_correction::{Deviation, Direction, TrackSetup, track_correction};
pub use transfer::{TransferError, TransferPlan, TransformStep, reparse, transfer};

#[cfg(test)]
pub(crate) mod test_support;
