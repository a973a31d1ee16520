//! trackfix's integration tests: one binary, one module per area.

mod cli;
mod krl;
mod parser_data;
mod rapid;
mod support;
mod track;
mod transform;
