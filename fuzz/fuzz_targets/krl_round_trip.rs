//! Any bytes as a KRL `.src`/`.dat` pair (the input is cut at its first `\0` into the two
//! files): the parser never panics, every file prints back byte for byte, and every span it
//! reports (diagnostics, positions, fields) lies inside its file. Failures found here are
//! replayed from `tests/fuzz_regressions/krl/` by `tests/it/krl.rs`.
#![no_main]

use std::path::PathBuf;

use libfuzzer_sys::fuzz_target;
use trackfix::program::LoadOptions;

fuzz_target!(|data: &[u8]| {
    let (src, dat) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &data[..0]),
    };
    assert_eq!(trackfix::krl::parse(src).tree.print(src), src);
    let files = vec![
        (PathBuf::from("fuzz.dat"), dat.to_vec()),
        (PathBuf::from("fuzz.src"), src.to_vec()),
    ];
    let program = trackfix::krl::load_program_from_sources(files, &LoadOptions::default())
        .expect("nothing to read from disk");
    for file in &program.files {
        assert!(file.round_trip);
        let len = file.source.len();
        for d in &file.diagnostics {
            assert!(d.span.start <= d.span.end && d.span.end <= len);
            let _ = d.render("fuzz", &file.source, &file.lines);
        }
        for p in &file.positions {
            assert!(p.span.end <= len);
            if let Some(c) = &p.cartesian {
                for f in c.trans.iter().flatten() {
                    assert!(f.span.end <= len);
                }
            }
        }
    }
});
