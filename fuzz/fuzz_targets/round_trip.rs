//! Any bytes, as RAPID and as KRL: the parsers never panic and the printed tree equals the
//! input. Crashes found here are committed as regression tests in `tests/it/rapid.rs`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let rapid = trackfix::rapid::parse_file(Path::new("fuzz.mod"), data.to_vec());
    assert!(rapid.round_trip);
    assert_eq!(trackfix::rapid::print(data), data);
    for d in &rapid.diagnostics {
        assert!(d.span.end <= data.len());
    }
    let krl = trackfix::krl::parse_file(Path::new("fuzz.src"), data.to_vec());
    assert!(krl.round_trip);
});
