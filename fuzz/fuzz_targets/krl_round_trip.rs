//! Any bytes as a KRL `.src`/`.dat` pair (the input is cut at its first `\0` into the two
//! files): the parser never panics, every file prints back byte for byte, every span it reports
//! lies inside its file, and on a pair without syntax errors `correct` and `mirror` never panic,
//! their output reads again cleanly and prints back, and a zero deviation changes no byte. The
//! checks live in `tests/it/fuzz_bodies.rs`; failures found here are kept in
//! `tests/fuzz_regressions/krl/`, which `cargo test` replays through them.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../tests/it/fuzz_bodies.rs"]
#[allow(dead_code)]
mod fuzz_bodies;

fuzz_target!(|data: &[u8]| {
    fuzz_bodies::krl_pair(data);
});
