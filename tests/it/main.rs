//! trackfix's integration tests: one binary, one module per area.

mod cli;
mod krl;
mod rapid;
mod rust_version;
mod support;
mod track;
mod transform;
