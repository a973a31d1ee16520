//! Every human and machine output model: what `inspect`, `check` and the transforms report.
//! Each model is data (serde for JSON) with the text renderings beside it; the CLI only
//! chooses the format and where it goes.

pub mod check;
pub mod inspect;
pub mod transform;

pub use check::{
    CheckSummary, QUATERNION_NORM_TOLERANCE, errors, findings, lints, values_pass_lints,
};
pub use inspect::{
    FileReport, FrameColumn, FrameRow, InspectJson, InspectOptions, InspectReport, Message, Place,
    PoseColumns, PositionRow, ProgramReport, inspect_file, inspect_program, message, render_csv,
    render_table,
};
pub use transform::{FileSummary, would_change};
