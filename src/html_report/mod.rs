//! Reports an engineer hands over: one self-contained HTML file (inline stylesheet and SVG, no
//! script, no URL) per track ([`track`]) and per program run ([`run`]), printable to PDF from
//! the browser, each section on its own page.
//!
//! Every text taken from a file goes through [`html::escape`]; charts are small hand-written
//! SVG (the private `svg` module) printed with fixed decimals, so the same inputs give the
//! same bytes.

pub mod accuracy;
pub mod figures;
pub mod html;
pub mod run;
pub(crate) mod svg;
pub mod track;

pub use crate::geometry::{abb_pose_literal, kuka_frame_literal};
pub use figures::ControllerFigures;
pub use run::{RunFile, RunInput, RunReport, run_report};
pub use track::{
    AccuracyResult, DataTable, ReportError, SourceFile, TrackInputs, TrackReport, accuracy_section,
    track_report,
};
