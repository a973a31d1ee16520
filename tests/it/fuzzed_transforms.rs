//! The cargo-fuzz targets' checks (`fuzz_bodies.rs`) over every file we have: the samples as
//! the programs the CLI loads, each sample, parser test file and fuzz regression as bytes, and
//! the KRL regressions as the `.src\0.dat` pairs the KRL target makes.

use std::path::PathBuf;

use trackfix::program::{LoadOptions, collect_programs, load_group};

use crate::fuzz_bodies::{Exercised, file_holds, krl_pair, one_file, transforms_hold};
use crate::support::{self, root};

fn files_under(dir: &str) -> Vec<PathBuf> {
    let mut files = support::files_under(&root().join(dir));
    files.retain(|path| path.extension().is_none_or(|e| e != "tree"));
    files
}

fn add(total: &mut Exercised, e: Option<Exercised>) -> bool {
    let Some(e) = e else { return false };
    total.corrected += e.corrected;
    total.mirrored += e.mirrored;
    true
}

/// Every sample program as loaded (KRL pairs and RAPID tasks joined), through `correct` and
/// `mirror`: all of them are free of syntax errors, and the transforms change targets in them.
#[test]
fn fuzz_checks_hold_on_every_sample_program() {
    let dirs: Vec<PathBuf> = [
        "samples/rapid",
        "samples/krl",
        "samples/kss_backup",
        "samples/robotstudio_backup",
    ]
    .iter()
    .map(|d| root().join(d))
    .collect();
    let mut total = Exercised::default();
    let mut programs = 0;
    for group in collect_programs(&dirs).unwrap() {
        for program in load_group(&group, &LoadOptions::default()) {
            let program = program.unwrap_or_else(|e| panic!("{group:?}: {e}"));
            for file in &program.files {
                file_holds(file);
            }
            assert!(
                add(&mut total, transforms_hold(&program)),
                "{group:?} has syntax errors"
            );
            programs += 1;
        }
    }
    assert!(programs >= 24, "only {programs} sample programs");
    assert!(total.corrected > 300, "{total:?}");
    assert!(total.mirrored > 1000, "{total:?}");
}

/// Every file of the samples, the parser test data and the fuzz regressions as one RAPID module
/// and as one KRL file (the `round_trip` target), and the KRL regressions as pairs (the
/// `krl_round_trip` target). The `err` test data have syntax errors and are not transformed; the
/// files that read cleanly in their own language are.
#[test]
fn fuzz_checks_hold_on_every_file_as_bytes() {
    let mut files = Vec::new();
    for dir in ["samples", "tests/data", "tests/fuzz_regressions"] {
        files.extend(files_under(dir));
    }
    assert!(files.len() > 80, "only {} files", files.len());
    let mut total = Exercised::default();
    let mut clean = 0;
    for path in &files {
        let data = std::fs::read(path).unwrap();
        let [rapid, krl] = one_file(&data);
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let own = match ext.to_ascii_lowercase().as_str() {
            "mod" | "sys" | "prg" => rapid,
            "src" | "dat" | "sub" => krl,
            _ => None,
        };
        let is_err_data = path.components().any(|c| c.as_os_str() == "err");
        if add(&mut total, own) {
            assert!(!is_err_data, "{} reads without errors", path.display());
            clean += 1;
        }
    }
    let mut pairs = 0;
    for path in files_under("tests/fuzz_regressions/krl") {
        krl_pair(&std::fs::read(&path).unwrap());
        pairs += 1;
    }
    assert!(pairs >= 7, "only {pairs} KRL regression pairs");
    assert!(clean >= 41, "only {clean} files read cleanly");
    // (A KRL point no motion uses is taken in its FDAT's base, which a file read alone often
    // does not declare: such points are refused, where the default work object took them.)
    assert!(total.corrected > 300 && total.mirrored > 1000, "{total:?}");
}
