//! Any bytes, as one RAPID module and as one KRL file: the parsers never panic, the printed tree
//! equals the input, every reported span lies inside it, and on an input without syntax errors
//! `correct` and `mirror` never panic, their output reads again cleanly and prints back, and a
//! zero deviation changes no byte. The checks live in `tests/it/fuzz_bodies.rs`, which `cargo
//! test` runs over every sample and fuzz regression (`tests/fuzz_regressions/rapid/`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../tests/it/fuzz_bodies.rs"]
#[allow(dead_code)]
mod fuzz_bodies;

fuzz_target!(|data: &[u8]| {
    fuzz_bodies::one_file(data);
});
