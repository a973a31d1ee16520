//! trackfix: model a robot's deformed linear track and rewrite ABB RAPID and KUKA KRL programs
//! for it, losslessly.
//!
//! Layers, bottom up:
//! - [`syntax`]: bytes, spans, line index, numeric literals, diagnostics, span-splice edits;
//! - [`rapid`] and [`krl`]: lossless parsers whose trees print back byte for byte, and the
//!   targets, frames and offsets found in a program ([`position`]);
//! - [`geometry`]: poses, one constructor per rotation convention, rigid fits;
//! - [`track`]: the track model from laser-tracker measurements to a profile, and its
//!   uncertainty;
//! - [`frame`]: robot base, work objects, TCP and point-pair fits, track-compensated;
//! - [`report`]: what `inspect` and `check` say about programs;
//! - [`transform`]: `correct`, `zero`, `mirror`, `transfer` as edits to programs.
//!
//! The library never prints and never panics on input.

pub mod frame;
pub mod geometry;
pub mod krl;
pub mod position;
pub mod program;
pub mod rapid;
pub mod report;
pub mod syntax;
pub mod track;
pub mod transform;
