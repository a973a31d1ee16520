//! trackfix's integration tests: one binary, one module per area.

mod cli;
mod frames;
mod krl;
mod rapid;
mod support;
mod track;
mod transform;
