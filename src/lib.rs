//! trackfix: model a robot's deformed linear track and rewrite ABB RAPID and KUKA KRL programs
//! for it, losslessly.
//!
//! Layers, bottom up:
//! - [`syntax`]: bytes, spans, line index, numeric literals, diagnostics, span-splice edits;
//! - [`rapid`] and [`krl`]: lossless parsers whose trees print back byte for byte, and the
//!   targets, frames and offsets found in a program ([`position`]);
//! - [`dialect`]: the one registry through which loading, reports and transforms reach a
//!   language (extensions, load/reparse, vocabulary, configuration mirror rule);
//! - [`geometry`]: poses, one constructor per rotation convention, rigid fits;
//! - [`track`]: the track model from laser-tracker measurements to a profile, and its
//!   uncertainty;
//! - [`frame`]: robot base, work objects, TCP and point-pair fits, track-compensated;
//! - [`kinematics`]: the OPW arm model, ABB/KUKA configurations, reach and joint checks;
//! - [`report`]: the output models of `inspect`, `check` and the transforms;
//! - [`transform`]: `correct`, `zero`, `mirror`, `transfer` as rules of one driver, giving
//!   edits to programs;
//! - [`output`]: where results go, written as one transaction; the diff; safe input reads;
//! - [`located`]: errors that render themselves (path, source, diagnostic).
//!
//! The library never prints and never panics on input.

// One exception, allowed where it is: mapping an input file (`output::read`).
#![deny(unsafe_code)]

pub mod accuracy;
pub mod dialect;
pub mod digest;
pub mod frame;
pub mod geometry;
pub mod html_report;
pub mod kinematics;
pub mod krl;
pub mod located;
mod names;
pub mod output;
pub mod position;
pub mod program;
pub mod rapid;
pub mod report;
#[warn(unreachable_pub)]
mod resolve;
pub mod syntax;
pub mod track;
pub mod transform;

// What a user of the library needs, at the top (`docs/design.md §8`, the public API): load a
// program, read what it holds, parse a file, run a transform, build a report.
pub use dialect::{Dialect, Language, Vocabulary, register as register_dialect};
/// Parses a KRL file into its lossless tree and the statements trackfix reads.
pub use krl::parse as parse_krl;
pub use located::Located;
pub use position::{
    Axes, CartesianFields, Config, FrameDecl, FrameKind, FrameName, Lines, Name, NumField,
    OffsetCall, OffsetKind, Orientation, ParsedFile, Position, PositionKind, PositionList, Program,
    Skid, Usage,
};
pub use program::{LoadError, LoadOptions, collect_inputs, load};
/// Parses a RAPID module into its lossless tree (positions are [`rapid::parse_file`]'s).
pub use rapid::parse_tree as parse_rapid;
pub use report::{
    CheckSummary, FileSummary, InspectOptions, InspectReport, errors, inspect_program, lints,
};
pub use transform::{
    Cell, CellError, Direction, MirrorSettings, ProgramResult, Refusal, RefusalKind, Remedy,
    TrackSetup, TransferPlan, TransformStep, apply, mirror, reparse, track_correction, transfer,
};
