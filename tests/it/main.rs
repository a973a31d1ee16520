//! trackfix's integration tests: one binary, one module per area.

mod cli;
mod dialect;
mod krl;
mod rapid;
mod support;
mod track;
mod transform;
