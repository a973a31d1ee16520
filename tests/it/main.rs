//! trackfix's integration tests: one binary, one module per area.

mod krl;
mod rapid;
mod track;
mod transform;
