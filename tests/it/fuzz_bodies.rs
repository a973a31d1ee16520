//! The checks the cargo-fuzz targets run on every input, in one file that both the fuzz targets
//! (`fuzz/fuzz_targets/*.rs`, through `#[path]`) and `cargo test` (`tests/it/fuzzed_transforms.rs`,
//! over every sample, parser test file and fuzz regression) compile, so the two cannot drift and
//! the fuzz bodies type-check without cargo-fuzz.
//!
//! Each function panics on a violated invariant (that is how libFuzzer learns of a failure):
//! - the parsers never panic, print every input back byte for byte, and every span they report
//!   lies inside its file;
//! - on an input without syntax errors, `correct` (with a small in-code cell and deviation) and
//!   `mirror` never panic, their edits splice without overlap, and the output parses again
//!   without syntax errors and prints back byte for byte;
//! - `correct` with a zero deviation changes no byte.
//!
//! Only the library's public API and `std` are used: the fuzz crate depends on nothing else.

use std::path::{Path, PathBuf};

use trackfix::geometry::{Pose, pose_xyz_deg};
use trackfix::program::LoadOptions;
use trackfix::syntax::Severity;
use trackfix::track::TrackError;
use trackfix::transform::{
    Cell, Direction, MirrorSettings, ProgramResult, TrackSetup, apply, mirror, reparse,
    track_correction,
};
use trackfix::{ParsedFile, Program};

/// One robot on a track along world x, its base turned as in a real cell, with one work object
/// the fuzzer can name; the skid is `eax_a` / `E1`. The profile path is never read here.
const CELL: &str = r#"
[robot.r1]
profile = "profile.toml"
base = { x = 0, y = -1800, z = 0, rx = 0, ry = 0, rz = 90 }
track_axis = [1, 0, 0]
[robot.r1.wobj]
wobj_car = { x = 2000, y = 0, z = 600, rx = 0, ry = 0, rz = 0 }
"#;

/// A deviation that moves every target by a visible amount (so edits happen) and varies with
/// the skid (so each skid is its own case); finite for every finite skid.
fn sagging(skid: f64) -> Result<Pose, TrackError> {
    let s = skid / 1000.0;
    Ok(pose_xyz_deg(
        0.01 * s,
        0.3 * s.sin(),
        -0.5 - 0.2 * s,
        0.002 * s,
        -0.001,
        0.003 * s.cos(),
    ))
}

fn no_deviation(_skid: f64) -> Result<Pose, TrackError> {
    Ok(Pose::identity())
}

/// `data` as one RAPID module and as one KRL `.src` file; what the transforms did to each.
pub(crate) fn one_file(data: &[u8]) -> [Option<Exercised>; 2] {
    let rapid = trackfix::rapid::parse_file(Path::new("fuzz.mod"), data.to_vec());
    assert_eq!(trackfix::rapid::print(data), data);
    file_holds(&rapid);
    let as_rapid = transforms_hold(&Program { files: vec![rapid] });

    let krl = trackfix::krl::parse_file(Path::new("fuzz.src"), data.to_vec());
    assert_eq!(trackfix::krl::parse(data).tree.print(data), data);
    file_holds(&krl);
    let as_krl = transforms_hold(&Program { files: vec![krl] });
    [as_rapid, as_krl]
}

/// A KRL `.src`/`.dat` pair: `data` cut at its first `\0` (no `\0`: a `.src` with an empty
/// `.dat`); what the transforms did to it.
pub(crate) fn krl_pair(data: &[u8]) -> Option<Exercised> {
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
        file_holds(file);
    }
    transforms_hold(&program)
}

/// The parse of one file: it prints back, and every span it reports lies inside it.
pub(crate) fn file_holds(file: &ParsedFile) {
    assert!(
        file.round_trip,
        "{} does not print back",
        file.path.display()
    );
    let len = file.source.len();
    for d in &file.diagnostics {
        assert!(d.span.start <= d.span.end && d.span.end <= len);
        let _ = file.render(d);
    }
    for p in file.positions() {
        assert!(p.span.start <= p.span.end && p.span.end <= len);
        if let Some(c) = &p.cartesian {
            for f in c.trans.iter().flatten() {
                assert!(f.span().end <= len);
            }
        }
        for f in p.extax.iter().flatten() {
            assert!(f.span().end <= len);
        }
    }
}

fn has_syntax_errors(program: &Program) -> bool {
    program
        .files
        .iter()
        .any(|f| f.diagnostics.iter().any(|d| d.severity == Severity::Error))
}

/// `correct` and `mirror` on a program without syntax errors (a file with one is never
/// transformed): no panic, the output reads again cleanly, and a zero deviation is the identity.
/// Returns how many targets each transform changed, `None` when the program has syntax errors.
pub(crate) fn transforms_hold(program: &Program) -> Option<Exercised> {
    if program.files.is_empty() || has_syntax_errors(program) {
        return None;
    }
    let cell = Cell::parse(Path::new("cell.toml"), CELL).expect("the in-code cell is valid");
    let robot = &cell.robots["r1"];

    let mut setup = TrackSetup::new(robot, &sagging);
    setup.default_wobj = Some("wobj0".to_owned());
    let corrected = apply(
        program,
        track_correction(program, &setup, Direction::Correct),
    )
    .expect("the edits of `correct` never overlap");
    output_reads_again(program, &corrected, "correct");
    let mut exercised = Exercised {
        corrected: changed(&corrected),
        mirrored: 0,
    };

    let mut identity = TrackSetup::new(robot, &no_deviation);
    identity.default_wobj = Some("wobj0".to_owned());
    let same = apply(
        program,
        track_correction(program, &identity, Direction::Correct),
    )
    .expect("the edits of `correct` never overlap");
    for f in &same.files {
        assert!(
            f.output[..] == f.original[..],
            "`correct` with a zero deviation changed {}",
            f.path.display()
        );
    }

    for settings in [
        MirrorSettings::default(),
        MirrorSettings {
            mirror_frames: true,
            mirror_joints: true,
            skid_map: (-1.0, 4000.0),
            ..MirrorSettings::default()
        },
    ] {
        let mirrored = apply(program, mirror(program, &settings))
            .expect("the edits of `mirror` never overlap");
        output_reads_again(program, &mirrored, "mirror");
        exercised.mirrored += changed(&mirrored);
    }
    Some(exercised)
}

/// How much of a program the transforms touched, so a test over many inputs can show that the
/// checks ran on edited output, not only on unchanged files.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Exercised {
    /// Targets `correct` changed.
    pub(crate) corrected: usize,
    /// Targets the two `mirror` runs changed, together.
    pub(crate) mirrored: usize,
}

fn changed(result: &ProgramResult) -> usize {
    result.files.iter().map(|f| f.changes.len()).sum()
}

/// The transformed files parse again without syntax errors and print back byte for byte.
fn output_reads_again(program: &Program, result: &ProgramResult, what: &str) {
    let again = reparse(program, result, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("`{what}` output does not load again: {e}"));
    assert_eq!(again.files.len(), program.files.len());
    for file in &again.files {
        file_holds(file);
        let printed = match file.language.name() {
            "rapid" => trackfix::rapid::print(&file.source),
            "krl" => trackfix::krl::parse(&file.source).tree.print(&file.source),
            _ => file.source.to_vec(),
        };
        assert!(
            printed[..] == file.source[..],
            "`{what}` output does not print back"
        );
        if let Some(d) = file
            .diagnostics
            .iter()
            .find(|d| d.severity == Severity::Error)
        {
            panic!(
                "`{what}` output has a syntax error:\n{}\n--- output\n{}",
                file.render(d),
                String::from_utf8_lossy(&file.source)
            );
        }
    }
}
