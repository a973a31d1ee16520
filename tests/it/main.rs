//! trackfix's integration tests: one binary, one module per area.

mod accuracy;
mod cli;
mod dialect;
mod frames;
mod fuzz_bodies;
mod fuzzed_transforms;
mod kept_as_written;
mod kinematics;
mod krl;
mod library_text;
mod mirror_image;
mod non_positions;
mod output;
mod parser_data;
mod programs;
mod rapid;
mod report;
mod runtime_data;
mod rust_version;
mod support;
mod track;
mod transform;
