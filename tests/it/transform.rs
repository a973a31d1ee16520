//! Integration tests: program transforms. Through the real parsers and the binary:
//! `--diff` snapshots of every sample and command, refusal messages, the invariants through
//! files, `transfer = zero; mirror; correct`, and the end-to-end check from a simulated
//! deformed track to the physical TCP error of corrected RAPID and KRL programs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Point3, Translation3};
use trackfix::geometry::{Pose, abb_quat_components, kuka_abc_angles, pose_to_xyz_deg, xyz_deg};
use trackfix::position::{Program, Skid};
use trackfix::program::{LoadOptions, load};
use trackfix::track::identify::{identify, read_measurements};
use trackfix::track::nominal::{FitOptions, fit_track};
use trackfix::track::simulate::{
    TrackTruth, measurements_csv, sample_tcp_points, simulate_measurements,
};
use trackfix::track::{Extrapolate, Knot, Profile};
use trackfix::transform::{Cell, Direction, TrackSetup, apply, track_correction};

use crate::support::{root, trackfix, with_constant_deviation};

/// Every program among the samples (a KRL pair once, by its .src or lone file).
fn sample_programs() -> Vec<String> {
    let mut out = Vec::new();
    for dir in ["samples/rapid", "samples/krl"] {
        let mut names: Vec<String> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('$'))
            .collect();
        names.sort();
        for n in names {
            let stem = n
                .rsplit_once('.')
                .map(|(s, _)| s.to_owned())
                .unwrap_or_default();
            if n.ends_with(".dat")
                && out
                    .iter()
                    .any(|o: &String| o.ends_with(&format!("/{stem}.src")))
            {
                continue;
            }
            if n.ends_with(".dat") && names_has(dir, &format!("{stem}.src")) {
                continue;
            }
            out.push(format!("{dir}/{n}"));
        }
    }
    out
}

fn names_has(dir: &str, name: &str) -> bool {
    root().join(dir).join(name).exists()
}

fn snapshot_name(prefix: &str, sample: &str) -> String {
    let file = sample.rsplit('/').next().unwrap_or(sample);
    format!("{prefix}_{}", file.replace(['.', '$'], "_"))
}

/// `--diff` of every sample under every command by rule (the cell without kinematics: most
/// samples show file idioms, not programs made for the cell's robots; refused targets skipped,
/// and listed on stderr, which is part of the snapshot).
#[test]
fn diff_snapshots_of_every_sample_and_command() {
    let commands: [(&str, &[&str]); 4] = [
        (
            "correct",
            &[
                "correct",
                "--cell",
                "samples/cell_rules.toml",
                "--robot",
                "r1",
            ],
        ),
        (
            "zero",
            // The samples carry no stamp: zero them all the same.
            &[
                "zero",
                "--cell",
                "samples/cell_rules.toml",
                "--robot",
                "r1",
                "--force",
            ],
        ),
        (
            "mirror",
            &[
                "mirror",
                "--cell",
                "samples/cell_rules.toml",
                "--robot",
                "r1",
            ],
        ),
        (
            "transfer",
            &[
                "transfer",
                "--cell",
                "samples/cell_rules.toml",
                "--from",
                "r1",
                "--to",
                "r2",
                "--mirror",
            ],
        ),
    ];
    for sample in sample_programs() {
        for (name, args) in commands {
            let mut a: Vec<&str> = args.to_vec();
            // The numbers only: the stamp line has its own test.
            a.extend([
                sample.as_str(),
                "--diff",
                "--skip-unsupported",
                "--no-stamp",
            ]);
            let (code, out, err) = trackfix(&a);
            // A diff that keeps skipped targets as written is a partial result: exit 4.
            let kept = err.contains("(kept as written)");
            assert_eq!(code, if kept { 4 } else { 0 }, "{name} {sample}: {err}");
            insta::assert_snapshot!(
                snapshot_name(&format!("diff_{name}"), &sample),
                format!(
                    "$ trackfix {}\nexit {code}\n--- stderr\n{err}--- stdout\n{out}",
                    a.join(" ")
                )
            );
        }
    }
}

/// Writes `text` into a fresh temp dir as `name`, with a copy of the sample cell and profiles.
fn scratch_with(name: &str, text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

fn refusal_output(args: &[&str]) -> String {
    let (code, out, err) = trackfix(args);
    assert_eq!(code, 3, "{args:?}: {err}");
    assert!(out.is_empty());
    err
}

/// Every refusal kind, by message: on the samples that carry them, and on small modules for the
/// rest. Each run fails with exit 3 and writes nothing.
#[test]
fn refusal_messages() {
    let mut all = String::new();
    for sample in [
        "samples/rapid/joints_only.mod",
        "samples/rapid/two_wobjs.mod",
        "samples/rapid/moving_wobj.mod",
        "samples/rapid/stationary_tool.mod",
        "samples/rapid/hand_9e9.mod",
        "samples/krl/glue_tcp.src",
    ] {
        let out = tempfile::tempdir().unwrap();
        let dir = out.path().to_str().unwrap();
        let err = refusal_output(&[
            "correct",
            sample,
            "--cell",
            "samples/cell_rules.toml",
            "--robot",
            "r1",
            "--out-dir",
            dir,
        ]);
        assert_eq!(
            std::fs::read_dir(out.path()).unwrap().count(),
            0,
            "wrote into {dir}"
        );
        writeln!(all, "$ trackfix correct {sample} …\n{err}").unwrap();
    }
    let cell = root().join("samples/cell_rules.toml");
    let cell = cell.to_str().unwrap();
    let cases = [
        (
            "out_of_range.mod",
            "MODULE m\n  CONST robtarget pFar:=[[10,20,30],[1,0,0,0],[0,0,0,0],[9100.5,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL pFar, v100, fine, tool0\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n",
        ),
        (
            "not_connected.mod",
            "MODULE m\n  CONST robtarget pA:=[[10,20,30],[1,0,0,0],[0,0,0,0],[9E+09,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL pA, v100, fine, tool0\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n",
        ),
        (
            "expression.mod",
            "MODULE m\n  VAR num y0 := 5;\n  PROC main()\n    MoveL [[10,y0+5,30],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n",
        ),
        (
            "unknown_wobj.mod",
            "MODULE m\n  CONST robtarget pA:=[[10,20,30],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL pA, v100, fine, tool0\\WObj:=wobj_fixture;\n  ENDPROC\nENDMODULE\n",
        ),
        (
            "implausible.mod",
            "MODULE m\n  CONST robtarget pTypo:=[[1e300,20,30],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL pTypo, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
        ),
        (
            "unused.mod",
            "MODULE m\n  CONST robtarget pSpare:=[[10,20,30],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
        ),
    ];
    for (name, text) in cases {
        let (dir, path) = scratch_with(name, text);
        let out = dir.path().join("out.mod");
        let err = refusal_output(&[
            "correct",
            path.to_str().unwrap(),
            "--cell",
            cell,
            "--robot",
            "r1",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!out.exists());
        let err = err.replace(dir.path().to_str().unwrap(), "<tmp>");
        writeln!(all, "$ trackfix correct {name} …\n{err}").unwrap();
    }
    insta::assert_snapshot!("refusals", all);
}

/// The refusals `mirror` adds: an offset or a `RelTool` rotation written as an expression where
/// the reflection changes it, each by name; exit 3, nothing written.
#[test]
fn mirror_refusal_messages() {
    let (dir, path) = scratch_with(
        "offsets.mod",
        "MODULE m\n  VAR num a := 5;\n  CONST robtarget p1:=[[1,0,3],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL RelTool(p1,0,0,10\\Rx:=a), v100, fine, tool0;\n    MoveL Offs(p1,0,a,0), v100, fine, tool0;\n    MoveL RelTool(p1,0,0,10\\Ry:=a), v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
    );
    let out = dir.path().join("out.mod");
    let err = refusal_output(&[
        "mirror",
        path.to_str().unwrap(),
        "--plane",
        "xz",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!out.exists());
    insta::assert_snapshot!(
        "mirror_refusals",
        err.replace(dir.path().to_str().unwrap(), "<tmp>")
    );
}

/// Each robot's `skid` axis applies: r1 on eax_a, r2 (in a copy of the sample cell) on eax_b.
/// `transfer --from r1 --to r2 --mirror` moves the skid to eax_b, and back again the other way.
#[test]
fn transfer_moves_the_skid_to_the_other_robots_axis() {
    let dir = tempfile::tempdir().unwrap();
    let cell_text = std::fs::read_to_string(root().join("samples/cell_rules.toml"))
        .unwrap()
        .replace("track/", &format!("{}/samples/track/", root().display()))
        .replace(
            "krl/$config",
            &format!("{}/samples/krl/$config", root().display()),
        );
    let r2_at = cell_text.find("[robot.r2]").unwrap();
    let (head, tail) = cell_text.split_at(r2_at);
    let cell_text = format!(
        "{head}{}",
        tail.replacen("skid = \"eax_a\"", "skid = \"eax_b\"", 1)
    );
    let cell = dir.path().join("cell.toml");
    std::fs::write(&cell, cell_text).unwrap();
    let module = dir.path().join("m.mod");
    std::fs::write(
        &module,
        "MODULE m\n  CONST robtarget p1:=[[1200,-1500,900],[0,0,1,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL p1, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
    )
    .unwrap();
    let there = dir.path().join("there.mod");
    let back = dir.path().join("back.mod");
    for (from, to, input, output) in [("r1", "r2", &module, &there), ("r2", "r1", &there, &back)] {
        run_ok(&[
            "transfer",
            input.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--from",
            from,
            "--to",
            to,
            "--mirror",
            "-o",
            output.to_str().unwrap(),
        ]);
    }
    let there = std::fs::read_to_string(&there).unwrap();
    assert!(there.contains("[9E9,2500,9E9,9E9,9E9,9E9]]"), "{there}");
    // `mirror --skid-to` is the middle step on its own.
    let (code, diff, err) = trackfix(&[
        "mirror",
        module.to_str().unwrap(),
        "--plane",
        "xz",
        "--skid-to",
        "eax_b",
        "--diff",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(diff.contains("[9E9,2500,9E9,9E9,9E9,9E9]]"), "{diff}");
    let start = poses(&load(&module, &LoadOptions::default()).unwrap());
    let end = poses(&load(&back, &LoadOptions::default()).unwrap());
    let moved = (end[0].1.translation.vector - start[0].1.translation.vector).norm();
    assert!(moved < 2e-3, "{moved} mm");
    let back = std::fs::read_to_string(&back).unwrap();
    assert!(back.contains("[2500,9E9,9E9,9E9,9E9,9E9]]"), "{back}");
}

/// Errors in the cell file and its profiles name `file:line:col`, show the line and say what
/// to do: a misspelt key, a profile that is not there, a profile with a bad value, an unknown
/// robot, a missing cell file. Exit 2, nothing written.
#[test]
fn cell_error_messages() {
    let dir = tempfile::tempdir().unwrap();
    let sample = std::fs::read_to_string(root().join("samples/cell_rules.toml")).unwrap();
    let profile = std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap();
    std::fs::create_dir(dir.path().join("track")).unwrap();
    std::fs::write(
        dir.path().join("track/bad_gear.toml"),
        profile.replace("gear = \"as-is\"", "gear = \"asis\""),
    )
    .unwrap();
    let cells = [
        (
            "typo.toml",
            sample.replacen("track_axis = ", "track_axes = ", 1),
        ),
        (
            "no_profile.toml",
            sample.replacen("track/profile.toml", "track/nope.toml", 1),
        ),
        (
            "bad_profile.toml",
            sample.replacen("track/profile.toml", "track/bad_gear.toml", 1),
        ),
    ];
    let mut all = String::new();
    for (name, text) in &cells {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let out = dir.path().join("out.mod");
    for (cell, robot) in [
        ("typo.toml", "r1"),
        ("no_profile.toml", "r1"),
        ("bad_profile.toml", "r1"),
        ("nope.toml", "r1"),
    ] {
        let cell_path = dir.path().join(cell);
        let (code, _, err) = trackfix(&[
            "correct",
            "samples/rapid/spot_line.mod",
            "--cell",
            cell_path.to_str().unwrap(),
            "--robot",
            robot,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(!out.exists());
        let err = err.replace(dir.path().to_str().unwrap(), "<tmp>");
        writeln!(
            all,
            "$ trackfix correct … --cell {cell} --robot {robot}\n{err}"
        )
        .unwrap();
    }
    // The unknown-robot case needs a loadable cell.
    let (code, _, err) = trackfix(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r3",
        "--diff",
    ]);
    assert_eq!(code, 2);
    writeln!(all, "$ trackfix correct … --robot r3\n{err}").unwrap();
    insta::assert_snapshot!("cell_errors", all);
}

/// `--default-wobj` resolves declared targets that no motion uses.
#[test]
fn default_wobj_resolves_unused_targets() {
    let (dir, path) = scratch_with(
        "unused.mod",
        "MODULE m\n  CONST robtarget pSpare:=[[10,20,30],[1,0,0,0],[0,0,0,0],[4000,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
    );
    let out = dir.path().join("out.mod");
    let (code, _, err) = trackfix(&[
        "correct",
        path.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--default-wobj",
        "wobj_car",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let before = poses(&load(&path, &LoadOptions::default()).unwrap());
    let after = poses(&load(&out, &LoadOptions::default()).unwrap());
    // wobj_car at skid 4000, mid-track: the sample profile moves the point by a millimetre or so.
    let moved = (before[0].1.translation.vector - after[0].1.translation.vector).norm();
    assert!((0.3..5.0).contains(&moved), "{moved} mm");
}

fn sample_cell() -> Cell {
    Cell::load(&root().join("samples/cell_rules.toml")).unwrap()
}

fn load_with_cell(path: &Path, cell: &Cell, robot: &str) -> Program {
    let opts = LoadOptions {
        krl_config_dat: cell.robots[robot].config_dat.clone(),
        map_inputs: false,
        ..LoadOptions::default()
    };
    load(path, &opts).unwrap()
}

/// docs/design.md §4: a profile of zero deviations leaves every sample byte-identical.
#[test]
fn zero_deviation_profile_leaves_every_sample_byte_identical() {
    let knots = (0..=8).map(|i| Knot::zero(i as f64 * 1000.0)).collect();
    let flat = Profile::from_knots("flat", knots, Extrapolate::Linear).unwrap();
    let cell = sample_cell();
    let mut checked = 0;
    for sample in sample_programs() {
        let program = load_with_cell(&root().join(&sample), &cell, "r1");
        for dir in [Direction::Correct, Direction::Zero] {
            let mut setup = TrackSetup::new(&cell.robots["r1"], &flat);
            setup.default_wobj = Some("wobj0".into());
            let result = apply(&program, track_correction(&program, &setup, dir)).unwrap();
            for f in &result.files {
                assert!(
                    f.output[..] == f.original[..],
                    "{} changed under {dir:?}",
                    f.path.display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 30, "{checked}");
}

/// Reads the numbers of every Cartesian target of a program: (label, pose).
fn poses(program: &Program) -> Vec<(String, Pose)> {
    program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .filter_map(|p| Some((p.label(), p.cartesian.as_ref()?.pose()?)))
        .collect()
}

/// Runs a transform that must succeed: exit 0, or 4 when it was told to keep refused targets.
fn run_ok(args: &[&str]) {
    let (code, _, err) = trackfix(args);
    let keeps = args
        .iter()
        .any(|a| *a == "--skip-unsupported" || *a == "--keep");
    assert!(
        code == 0 || (keeps && code == 4),
        "{args:?}: exit {code}: {err}"
    );
}

/// Through files: zero(correct(P)) and mirror(mirror(P)) give back P's numbers within the
/// written precision (3 decimals mm → 1.5e-3 after two roundings; orientation 2e-4°), on the
/// two spot-line samples.
#[test]
fn round_trips_through_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = |s: &str| dir.path().join(s).to_str().unwrap().to_owned();
    let cell = sample_cell();
    for (sample, ext) in [
        ("samples/rapid/spot_line.mod", "mod"),
        ("samples/krl/spot_line.src", "src"),
    ] {
        let (c, z) = (d(&format!("c.{ext}")), d(&format!("z.{ext}")));
        let common = ["--cell", "samples/cell_rules.toml", "--skip-unsupported"];
        run_ok(&[&["correct", sample, "--robot", "r1", "-o", &c], &common[..]].concat());
        run_ok(&[&["zero", &c, "--robot", "r1", "-o", &z], &common[..]].concat());
        let (m1, m2) = (d(&format!("m1.{ext}")), d(&format!("m2.{ext}")));
        run_ok(&[
            "mirror",
            sample,
            "--plane",
            "xz",
            "-o",
            &m1,
            "--skip-unsupported",
        ]);
        run_ok(&[
            "mirror",
            &m1,
            "--plane",
            "xz",
            "-o",
            &m2,
            "--skip-unsupported",
        ]);
        // transfer to the mirror-image robot and back, with the sample cell's world plane and
        // each robot's own entries for the car's work object (0.34 mm and 0.012° apart): the
        // mirror image is written in the work object as the other robot places it, so the way
        // back lands on the original (it was 3.2 mm off when both ways used the sending
        // robot's entry).
        let (t1, t2) = (d(&format!("t1.{ext}")), d(&format!("t2.{ext}")));
        let to_and_back = [
            ["--from", "r1", "--to", "r2", "-o", &t1],
            ["--from", "r2", "--to", "r1", "-o", &t2],
        ];
        let pair = if ext == "mod" {
            ("r1", "r2")
        } else {
            ("k1", "k2")
        };
        for (step, input) in to_and_back.iter().zip([sample, t1.as_str()]) {
            let step: Vec<&str> = step
                .iter()
                .map(|a| match *a {
                    "r1" => pair.0,
                    "r2" => pair.1,
                    a => a,
                })
                .collect();
            run_ok(
                &[
                    &["transfer", input, "--cell", "samples/cell.toml", "--mirror"][..],
                    &step,
                    &["--skip-unsupported", "--force"],
                ]
                .concat(),
            );
        }
        let original = poses(&load_with_cell(&root().join(sample), &cell, "r1"));
        for back in [&z, &m2, &t2] {
            let again = poses(&load_with_cell(Path::new(back), &cell, "r1"));
            assert_eq!(original.len(), again.len());
            assert!(original.len() > 100);
            for ((name, a), (_, b)) in original.iter().zip(&again) {
                let mm = (a.translation.vector - b.translation.vector).amax();
                let deg = a.rotation.angle_to(&b.rotation).to_degrees();
                assert!(mm <= 1.5e-3 && deg <= 2e-4, "{back} {name}: {mm} mm {deg}°");
            }
        }
        // Mirror twice gives the same numbers: the text of every changed number is back.
        let m3 = d(&format!("m3.{ext}"));
        run_ok(&[
            "mirror",
            &m2,
            "--plane",
            "xz",
            "-o",
            &m3,
            "--skip-unsupported",
        ]);
        // The same bytes but the KRL header names, which follow the file names (m1, m3).
        assert_eq!(
            unnamed(&std::fs::read(&m1).unwrap()),
            unnamed(&std::fs::read(&m3).unwrap())
        );
    }
}

/// A value whose sign alone `mirror` flips (`-450` → `450.000`, `0.5` → `-0.500000`) is widened
/// to the house decimals and recorded so in the stamp; mirrored back, it is written as it was
/// first written (before, the scan, whose literal starts after its sign, took it for one the
/// transform had not rewritten, and it stayed widened).
#[test]
fn mirror_twice_gives_back_a_sign_flip_as_first_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = |s: &str| dir.path().join(s).to_str().unwrap().to_owned();
    let target = "  CONST robtarget p10:=[[1200,-450,800],[0.5,0.5,0.5,0.5],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n";
    let module = format!(
        "MODULE M\n{target}  PROC main()\n    MoveL p10,v100,fine,tool0\\WObj:=wobj0;\n  ENDPROC\nENDMODULE\n"
    );
    std::fs::write(d("m.mod"), &module).unwrap();
    let mirror =
        |from: &str, to: &str| run_ok(&["mirror", &d(from), "--plane", "xz", "-o", &d(to)]);
    mirror("m.mod", "m1.mod");
    let once = std::fs::read_to_string(d("m1.mod")).unwrap();
    assert!(
        once.contains("[[1200,450.000,800],[0.5,-0.500000,0.5,-0.500000]"),
        "{once}"
    );
    mirror("m1.mod", "m2.mod");
    let twice = std::fs::read_to_string(d("m2.mod")).unwrap();
    assert!(twice.contains(target), "{twice}");
    assert!(
        twice
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("! trackfix: mirror version="),
        "{twice}"
    );
}

/// A file's text with the name of its KRL `DEF`/`DEFDAT` header blanked: a program written
/// under another file name carries that name there.
fn unnamed(bytes: &[u8]) -> String {
    trackfix::syntax::latin1(bytes)
        .split_inclusive('\n')
        .map(|l| {
            let t = l.trim_start();
            for k in ["DEFDAT", "DEF"] {
                if let Some(rest) = t.strip_prefix(k) {
                    let name_end = rest
                        .trim_start()
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                        .unwrap_or(rest.trim_start().len());
                    return format!("{k} _{}", &rest.trim_start()[name_end..]);
                }
            }
            l.to_owned()
        })
        .collect()
}

/// docs/design.md §4: transfer equals zero; mirror; correct, byte for byte, through files.
#[test]
fn transfer_equals_zero_mirror_correct() {
    let dir = tempfile::tempdir().unwrap();
    let d = |s: &str| dir.path().join(s).to_str().unwrap().to_owned();
    for (sample, stem, ext) in [
        ("samples/rapid/spot_line.mod", "spot_line", "mod"),
        ("samples/krl/spot_line.src", "spot_line", "src"),
    ] {
        let common = [
            "--cell",
            "samples/cell_rules.toml",
            "--skip-unsupported",
            "--no-stamp",
        ];
        let out = d(&format!("transfer_{ext}"));
        run_ok(
            &[
                &[
                    "transfer",
                    sample,
                    "--from",
                    "r1",
                    "--to",
                    "r2",
                    "--mirror",
                    "--out-dir",
                    &out,
                ],
                &common[..],
            ]
            .concat(),
        );
        let (z, m, c) = (
            d(&format!("z.{ext}")),
            d(&format!("m.{ext}")),
            d(&format!("c.{ext}")),
        );
        run_ok(
            &[
                &["zero", sample, "--robot", "r1", "-o", &z, "--force"],
                &common[..],
            ]
            .concat(),
        );
        // The cell's mirror plane is in world: the mirror resolves work objects like transfer
        // does, with --from's cell entries.
        run_ok(
            &[
                &["mirror", &z, "--robot", "r1", "--to", "r2", "-o", &m],
                &common[..],
            ]
            .concat(),
        );
        run_ok(&[&["correct", &m, "--robot", "r2", "-o", &c], &common[..]].concat());
        let chained = std::fs::read(&c).unwrap();
        let transferred = std::fs::read(Path::new(&out).join(format!("{stem}.{ext}"))).unwrap();
        let original = std::fs::read(root().join(sample)).unwrap();
        let chained = unnamed(&chained).into_bytes();
        let transferred = unnamed(&transferred).into_bytes();
        same_but_unmoved(
            &unnamed(&original).into_bytes(),
            &chained,
            &transferred,
            sample,
        );
        if ext == "src" {
            let a = std::fs::read(Path::new(&c).with_extension("dat")).unwrap();
            let b = std::fs::read(Path::new(&out).join(format!("{stem}.dat"))).unwrap();
            let o = std::fs::read(root().join("samples/krl/spot_line.dat")).unwrap();
            let (a, b, o) = (unnamed(&a), unnamed(&b), unnamed(&o));
            same_but_unmoved(o.as_bytes(), a.as_bytes(), b.as_bytes(), "spot_line.dat");
            assert!(a != o);
        }
    }
}

/// `transferred` is `chained` byte for byte, except literals that the chain brought back to
/// their original value (to one unit of the last written place) and transfer wrote as the
/// original text.
fn same_but_unmoved(original: &[u8], chained: &[u8], transferred: &[u8], what: &str) {
    let words = |b: &[u8]| -> Vec<String> {
        trackfix::syntax::latin1(b)
            .split_inclusive([',', '[', ']', '{', '}', ' ', '\n'])
            .map(str::to_owned)
            .collect()
    };
    let (o, c, t) = (words(original), words(chained), words(transferred));
    assert_eq!(c.len(), t.len(), "{what}");
    assert_eq!(o.len(), t.len(), "{what}");
    let mut restored = 0;
    for ((o, c), t) in o.iter().zip(&c).zip(&t) {
        if c == t {
            continue;
        }
        assert_eq!(t, o, "{what}: transfer wrote {t:?}, the chain {c:?}");
        let num = |s: &str| {
            s.trim_end_matches([',', ']', '}', ' ', '\n'])
                .trim_start_matches(|ch: char| ch.is_ascii_alphabetic() || ch == ' ')
                .to_owned()
        };
        let (ov, cv) = (num(o), num(c));
        let decimals = |s: &str| s.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
        let unit = 10f64.powi(-decimals(&ov).max(decimals(&cv)));
        let (a, b): (f64, f64) = (ov.parse().unwrap(), cv.parse().unwrap());
        assert!((a - b).abs() <= 2.0 * unit, "{what}: {o:?} vs {c:?}");
        restored += 1;
    }
    assert!(restored < 20, "{what}: {restored} literals restored");
}

/// Writes, refuses to overwrite inputs, `--in-place` keeps a backup, `--check` exits 1.
#[test]
fn output_modes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spot_line.mod");
    std::fs::copy(root().join("samples/rapid/spot_line.mod"), &input).unwrap();
    let inp = input.to_str().unwrap();
    let common = [
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--skip-unsupported",
    ];
    let (code, _, err) = trackfix(&[&["correct", inp, "-o", inp], &common[..]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("refusing to overwrite an input file"), "{err}");
    let (code, _, err) = trackfix(&[&["correct", inp], &common[..]].concat());
    assert_eq!(code, 2);
    assert!(err.contains("say where to write"), "{err}");
    let (code, _, err) = trackfix(&[&["correct", inp, "--check"], &common[..]].concat());
    assert_eq!(code, 1, "{err}");
    let before = std::fs::read(&input).unwrap();
    let (code, _, err) = trackfix(&[&["correct", inp, "--in-place"], &common[..]].concat());
    assert_eq!(code, 4, "{err}"); // written, jHome kept as written
    assert!(
        err.contains("target(s) changed, largest correction"),
        "{err}"
    );
    let backup = dir.path().join("spot_line.mod.orig");
    assert_eq!(std::fs::read(&backup).unwrap(), before);
    assert_ne!(std::fs::read(&input).unwrap(), before);
    // Refused without --skip-unsupported: the input stays as it was, no backup is touched.
    std::fs::remove_file(&backup).unwrap();
    let now = std::fs::read(&input).unwrap();
    let (code, _, _) = trackfix(&[
        "correct",
        inp,
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--in-place",
    ]);
    assert_eq!(code, 3);
    assert_eq!(std::fs::read(&input).unwrap(), now);
    assert!(!backup.exists());
}

/// A module of a megabyte and more is mapped when the run writes elsewhere and read when it
/// writes in place (docs/design.md §9, "Reading inputs"): both write the same bytes, and the
/// input written elsewhere is left as it was.
#[test]
fn a_large_module_corrects_alike_mapped_and_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut module = String::from("MODULE Big\r\n");
    let mut moves = String::from("  PROC main()\r\n");
    let mut i = 0;
    while module.len() < 1_200_000 {
        module.push_str(&format!(
            "  CONST robtarget p{i}:=[[{}.5,-700.25,{}],[0.707107,0,0.707107,0],[0,0,-1,0],[{},9E+09,9E+09,9E+09,9E+09,9E+09]];\r\n",
            1200 + i % 500,
            250 + i % 40,
            150 + i % 7000
        ));
        moves.push_str(&format!(
            "    MoveL p{i}, v1000, z10, tool0\\WObj:=wobj_car;\r\n"
        ));
        i += 1;
    }
    module.push_str(
        "  PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\r\n",
    );
    module.push_str(&moves);
    module.push_str("  ENDPROC\r\nENDMODULE\r\n");
    assert!(module.len() as u64 >= trackfix::output::MAP_FROM_BYTES);
    let input = dir.path().join("Big.mod");
    let in_place = dir.path().join("in_place/Big.mod");
    std::fs::create_dir(in_place.parent().unwrap()).unwrap();
    std::fs::write(&input, &module).unwrap();
    std::fs::write(&in_place, &module).unwrap();
    let out_dir = dir.path().join("out");
    let common = ["--cell", "samples/cell_rules.toml", "--robot", "r1"];
    let run = |target: &Path, mode: &[&str]| {
        let (code, _, err) =
            trackfix(&[&["correct", target.to_str().unwrap()], mode, &common[..]].concat());
        assert_eq!(code, 0, "{err}");
        assert!(err.contains(&format!("{i} target(s) changed")), "{err}");
    };
    run(&input, &["--out-dir", out_dir.to_str().unwrap()]);
    run(&in_place, &["--in-place", "--no-backup"]);
    let (mapped, read) = (
        std::fs::read(out_dir.join("Big.mod")).unwrap(),
        std::fs::read(&in_place).unwrap(),
    );
    assert!(mapped != module.as_bytes());
    assert!(
        mapped == read,
        "the mapped run wrote other bytes than the read one"
    );
    assert!(std::fs::read(&input).unwrap() == module.as_bytes());
}

// ---------------------------------------------------------------------------------------------
// End to end: a known deformed track → measurements.csv → identify → fit → profile.toml →
// cell.toml → corrected program → the TCP the robot physically reaches, from the truth.

/// The TCP the robot reaches for commanded `t` (in work object `w`) at skid `s`: the controller
/// solves the joints for its nominal base `B(s)`, the robot really stands at `truth(s)`.
fn reached(truth: &TrackTruth, b: &Pose, w: &Pose, t: &Pose, s: f64) -> Point3<f64> {
    let real = truth.base_frame(s) * b.inverse() * w * t;
    Point3::from(real.translation.vector)
}

struct E2e {
    _dir: tempfile::TempDir,
    cell: PathBuf,
    truth: TrackTruth,
    w: Pose,
    b0: Pose,
    axis: nalgebra::Vector3<f64>,
    /// (skid, CAD pose in W) of every target, as written.
    targets: Vec<(f64, Pose)>,
}

/// Simulated tracker session of robot r1's truth, fitted through the files the CLI would use.
fn e2e_setup() -> E2e {
    let dir = tempfile::tempdir().unwrap();
    let truth = TrackTruth::sample_r1();
    let skids: Vec<f64> = (0..=16).map(|i| i as f64 * 500.0).collect();
    let rows = simulate_measurements(&truth, &skids, &sample_tcp_points(), 0.01, 11);
    let meas = dir.path().join("measurements.csv");
    std::fs::write(&meas, measurements_csv(&rows)).unwrap();
    let id = identify(&read_measurements(&meas).unwrap()).unwrap();
    let fit = fit_track(&id.frames(), &FitOptions::default()).unwrap();
    let profile = dir.path().join("profile.toml");
    fit.profile.save(&profile).unwrap();
    let b0 = fit.base_at_zero;
    let axis = fit.direction;
    // The car: 1.4 m beside the track, 0.5 m up, turned 90° about z, in the tracker's frame.
    let w = b0 * trackfix::geometry::pose_xyz_deg(0.0, 1400.0, 500.0, 0.0, 0.0, 90.0);
    let [bx, by, bz, brx, bry, brz] = pose_to_xyz_deg(&b0);
    let [wx, wy, wz, wrx, wry, wrz] = pose_to_xyz_deg(&w);
    let cell = dir.path().join("cell.toml");
    std::fs::write(
        &cell,
        format!(
            "[robot.r1]\nprofile = \"profile.toml\"\n\
             base = {{ x = {bx:.9}, y = {by:.9}, z = {bz:.9}, rx = {brx:.12}, ry = {bry:.12}, rz = {brz:.12} }}\n\
             track_axis = [{:.15}, {:.15}, {:.15}]\n\
             [robot.r1.wobj]\n\"BASE_DATA[1]\" = {{ x = {wx:.9}, y = {wy:.9}, z = {wz:.9}, rx = {wrx:.12}, ry = {wry:.12}, rz = {wrz:.12} }}\n",
            axis.x, axis.y, axis.z
        ),
    )
    .unwrap();
    // 79 targets over the track, 0.9-1.3 m in front of the base, 0.2-1.2 m high, tool down.
    let mut targets = Vec::new();
    for i in 0..79 {
        let s = 100.0 + i as f64 * 100.0;
        let b = Translation3::from(axis * s) * b0;
        let k = i as f64;
        let local = Pose::from_parts(
            Translation3::new(
                200.0 * (k * 0.7).sin(),
                900.0 + 400.0 * (k * 0.3).cos().abs(),
                200.0 + 1000.0 * (k * 0.13).sin().abs(),
            ),
            xyz_deg(
                180.0 + 10.0 * (k * 0.5).sin(),
                15.0 * (k * 0.9).cos(),
                30.0 * k.sin(),
            ),
        );
        // Written to the file's precision, so the CAD pose is what the file says.
        let t = w.inverse() * b * local;
        targets.push((s, t));
    }
    E2e {
        _dir: dir,
        cell,
        truth,
        w,
        b0,
        axis,
        targets,
    }
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// The physical TCP errors (mm) of the commanded targets in `program` against the CAD poses.
fn physical_errors(
    e: &E2e,
    program: &Program,
    skid_of: impl Fn(&trackfix::position::Position) -> f64,
) -> Vec<f64> {
    let positions: Vec<_> = program.files.iter().flat_map(|f| f.positions()).collect();
    assert_eq!(positions.len(), e.targets.len());
    positions
        .iter()
        .zip(&e.targets)
        .map(|(p, (s, cad))| {
            let s_file = skid_of(p);
            assert!((s_file - s).abs() < 1e-6);
            let t = p.cartesian.as_ref().unwrap().pose().unwrap();
            let b = Translation3::from(e.axis * s_file) * e.b0;
            let want = Point3::from((e.w * cad).translation.vector);
            (reached(&e.truth, &b, &e.w, &t, s_file) - want).norm()
        })
        .collect()
}

fn skid0(p: &trackfix::position::Position) -> f64 {
    match p.skid(0) {
        Skid::At(s) => s,
        other => panic!("{other:?}"),
    }
}

/// The end-to-end correction test, RAPID. Truth: `TrackTruth::sample_r1()` (2.5 mm sag, 1.5 mm bow,
/// 0.08 mm waviness, 0.03° twist, gear error -1.5e-4), 10 tracker points at 17 skid positions
/// every 500 mm, 0.01 mm noise; 79 targets every 100 mm of skid, 0.9-1.3 m from the base.
/// Measured: uncorrected targets miss by 1.82 mm rms, corrected ones by 0.021 mm rms
/// (required: > 1 mm before, < 0.05 mm after).
#[test]
fn end_to_end_rapid_correction_reaches_the_cad_points() {
    let e = e2e_setup();
    let [wx, wy, wz] = [e.w.translation.x, e.w.translation.y, e.w.translation.z];
    let wq = abb_quat_components(&e.w.rotation, None);
    let mut m = String::from("MODULE E2e\n");
    writeln!(m, "  TASK PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[{wx:.4},{wy:.4},{wz:.4}],[{:.9},{:.9},{:.9},{:.9}]],[[0,0,0],[1,0,0,0]]];", wq[0], wq[1], wq[2], wq[3]).unwrap();
    for (i, (s, t)) in e.targets.iter().enumerate() {
        let q = abb_quat_components(&t.rotation, None);
        let v = t.translation.vector;
        writeln!(m, "  CONST robtarget P{i:03}:=[[{:.3},{:.3},{:.3}],[{:.6},{:.6},{:.6},{:.6}],[0,0,0,0],[{s:.1},9E9,9E9,9E9,9E9,9E9]];", v.x, v.y, v.z, q[0], q[1], q[2], q[3]).unwrap();
    }
    m.push_str("  PROC main()\n");
    for i in 0..e.targets.len() {
        writeln!(m, "    MoveL P{i:03}, v1000, fine, tool0\\WObj:=wobj_car;").unwrap();
    }
    m.push_str("  ENDPROC\nENDMODULE\n");
    let dir = e.cell.parent().unwrap().to_owned();
    let cad = dir.join("e2e.mod");
    std::fs::write(&cad, &m).unwrap();
    let mut e = e;
    e.use_written_targets(&cad);
    let out = dir.join("corrected.mod");
    let summary = correct_and_measure(&e, &cad, &["-o", out.to_str().unwrap()], &out);
    insta::assert_snapshot!("e2e_rapid", summary);
}

impl E2e {
    /// The CAD poses are what the file says (rounded), so compare against those.
    fn use_written_targets(&mut self, cad: &Path) {
        self.targets = poses(&load(cad, &LoadOptions::default()).unwrap())
            .into_iter()
            .zip(&self.targets)
            .map(|((_, p), (s, _))| (*s, p))
            .collect();
    }
}

/// Runs `trackfix correct CAD --cell … --robot r1 OUTPUT`, then the physical TCP error of the
/// program before and after (read back from `corrected`): the issue's levels are asserted, the
/// figures returned for the snapshot.
fn correct_and_measure(e: &E2e, cad: &Path, output: &[&str], corrected: &Path) -> String {
    let mut args = vec![
        "correct",
        cad.to_str().unwrap(),
        "--cell",
        e.cell.to_str().unwrap(),
        "--robot",
        "r1",
    ];
    args.extend(output);
    run_ok(&args);
    let before = physical_errors(e, &load(cad, &LoadOptions::default()).unwrap(), skid0);
    let after = physical_errors(e, &load(corrected, &LoadOptions::default()).unwrap(), skid0);
    let (rb, ra) = (rms(&before), rms(&after));
    let ma = after.iter().cloned().fold(0.0, f64::max);
    assert!(rb > 1.0, "uncorrected rms {rb:.3} mm");
    assert!(ra < 0.05, "corrected rms {ra:.4} mm (max {ma:.4})");
    format!("before rms {rb:.2} mm, after rms {ra:.3} mm")
}

/// The end-to-end correction test, KRL (.src/.dat pair, BASE_DATA[1] from the cell), same track and
/// targets: uncorrected 1.82 mm rms, corrected 0.021 mm rms.
#[test]
fn end_to_end_krl_correction_reaches_the_cad_points() {
    let mut e = e2e_setup();
    let dir = e.cell.parent().unwrap().to_owned();
    let mut src = String::from("DEF e2e( )\n$BASE=BASE_DATA[1]\n$TOOL=TOOL_DATA[1]\n");
    let mut dat = String::from("DEFDAT e2e\n");
    for (i, (s, t)) in e.targets.iter().enumerate() {
        let [a, b, c] = kuka_abc_angles(&t.rotation, None);
        let v = t.translation.vector;
        writeln!(dat, "DECL E6POS XP{i}={{X {:.3},Y {:.3},Z {:.3},A {a:.4},B {b:.4},C {c:.4},S 6,T 50,E1 {s:.1},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}", v.x, v.y, v.z).unwrap();
        writeln!(src, "LIN XP{i}").unwrap();
    }
    src.push_str("END\n");
    dat.push_str("ENDDAT\n");
    std::fs::write(dir.join("e2e.src"), &src).unwrap();
    std::fs::write(dir.join("e2e.dat"), &dat).unwrap();
    let cad = dir.join("e2e.src");
    e.use_written_targets(&cad);
    let out = dir.join("out");
    let summary = correct_and_measure(
        &e,
        &cad,
        &["--out-dir", out.to_str().unwrap()],
        &out.join("e2e.src"),
    );
    assert_eq!(std::fs::read(out.join("e2e.src")).unwrap(), src.as_bytes());
    insta::assert_snapshot!("e2e_krl", summary);
}

/// A cell whose track axis is not the profile's direction (here: y for a track along x) would
/// apply the profile in the wrong place: the run stops with exit 2, names both files and writes
/// nothing.
#[test]
fn a_cell_that_disagrees_with_its_profile_is_refused() {
    let cell = std::fs::read_to_string(root().join("samples/cell.toml")).unwrap();
    let samples = root().join("samples");
    let bad = cell
        .lines()
        .map(|l| match l {
            l if l.starts_with("track_axis") => "track_axis = [0, 1, 0]".to_owned(),
            l if l.starts_with("profile = \"") => l.replacen(
                "profile = \"",
                &format!("profile = \"{}/", samples.display()),
                1,
            ),
            l => l.to_owned(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let (dir, cell_path) = scratch_with("cell.toml", &bad);
    let out = dir.path().join("out");
    let module = root().join("samples/rapid/spot_line.mod");
    let (code, stdout, err) = trackfix(&[
        "correct",
        module.to_str().unwrap(),
        "--cell",
        cell_path.to_str().unwrap(),
        "--robot",
        "r1",
        "--skip-unsupported",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(stdout.is_empty());
    assert!(
        err.contains("robot `r1` does not match its profile"),
        "{err}"
    );
    assert!(err.contains("track_axis is 90.0"), "{err}");
    assert!(!out.exists(), "nothing may be written");
}

/// A profile fitted with `--measurements` carries knot uncertainties: `correct` then states
/// the largest expanded uncertainty (k = 2) of a corrected TCP. For the sample (0.02 mm
/// tracker noise, TCPs 2-2.5 m from the base) it lies between the noise itself and the largest
/// correction; a profile without uncertainties states none.
#[test]
fn correct_states_the_expanded_uncertainty_when_the_profile_has_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Exit 4: written, with the sample's joint target kept as written.
    let run = |args: &[&str]| {
        let (code, out, err) = trackfix(args);
        assert!(code == 0 || code == 4, "{args:?}: exit {code}: {err}");
        format!("{out}{err}")
    };
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let meas = s(&root().join("samples/track/measurements.csv"));
    let frames = d.join("frames.csv");
    let profile = d.join("profile.toml");
    run(&["track", "identify", &meas, "-o", &s(&frames)]);
    run(&[
        "track",
        "fit",
        &s(&frames),
        "--measurements",
        &meas,
        "--name",
        "r1",
        "-o",
        &s(&profile),
    ]);
    let cell = std::fs::read_to_string(root().join("samples/cell.toml"))
        .unwrap()
        .replace(
            "profile = \"track/profile.toml\"",
            &format!("profile = {:?}", s(&profile)),
        )
        .replace(
            "profile = \"track/r2/profile.toml\"",
            &format!(
                "profile = {:?}",
                s(&root().join("samples/track/r2/profile.toml"))
            ),
        );
    let cell_path = d.join("cell.toml");
    std::fs::write(&cell_path, cell).unwrap();
    let module = s(&root().join("samples/rapid/spot_line.mod"));
    let out = run(&[
        "correct",
        &module,
        "--cell",
        &s(&cell_path),
        "--robot",
        "r1",
        "--skip-unsupported",
        "--out-dir",
        &s(&d.join("out")),
    ]);
    let u: f64 = out
        .split("U (k=2) up to ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no uncertainty stated: {out}"));
    let largest: f64 = out
        .split("largest correction ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap();
    assert!(
        u > 2.0 * 0.02 && u < largest,
        "U {u} mm, largest correction {largest} mm"
    );
    let plain = run(&[
        "correct",
        &module,
        "--cell",
        &s(&root().join("samples/cell.toml")),
        "--robot",
        "r1",
        "--skip-unsupported",
        "--out-dir",
        &s(&d.join("out2")),
    ]);
    assert!(!plain.contains("U (k=2)"), "{plain}");
}

/// The files a run in `dir` left there, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A file with a syntax error is never transformed: every error located, exit 2, nothing written
/// (before, `correct` changed the 225 readable targets and exited 0).
#[test]
fn a_file_with_syntax_errors_is_not_transformed() {
    let good = trackfix::syntax::latin1(
        &std::fs::read(root().join("samples/rapid/spot_line.mod")).unwrap(),
    );
    let broken = good.replacen("[[-1499.39,-722.85,251.51]", "[[-1499.39,,251.51]", 1);
    assert_ne!(broken, good);
    // And one cut off inside a PROC.
    let cut = &good[..good.find("ENDPROC").unwrap()];
    for (text, line) in [(broken.as_str(), 16), (cut, 0)] {
        let (dir, input) = scratch_with("a.mod", text);
        let out = dir.path().join("out.mod");
        let (code, _, err) = trackfix(&[
            "correct",
            input.to_str().unwrap(),
            "--cell",
            "samples/cell.toml",
            "--robot",
            "r1",
            "--skip-unsupported",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(": error: "), "{err}");
        if line > 0 {
            assert!(err.contains(&format!("a.mod:{line}:37: error: ")), "{err}");
        }
        assert!(
            err.contains("is never transformed: nothing written"),
            "{err}"
        );
        assert!(!err.contains("target(s) changed"), "{err}");
        assert_eq!(listing(dir.path()), ["a.mod"]);
    }
}

/// A KRL aggregate in a `.src` that gives a field twice is an error `check` locates, with its
/// hint, and a file the transforms refuse: exit 2, nothing written (before, `correct` rewrote
/// one of the two X's and exited 0).
#[test]
fn a_krl_aggregate_giving_a_field_twice_is_not_transformed() {
    let src = "DEF twice( )\n  BAS(#BASE,1)\n  LIN {X 10, Y 20, Z 30, A 0, B 90, C 0, E1 500, X 40}\nEND\n";
    let (dir, input) = scratch_with("twice.src", src);
    let (code, out, _) = trackfix(&["check", input.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("twice.src:3:50: error: inline E6POS gives field `X` twice"),
        "{out}"
    );
    assert!(
        out.contains("the controller does not load the file"),
        "{out}"
    );
    let output = dir.path().join("out.src");
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--skip-unsupported",
        "-o",
        output.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("twice.src:3:50: error: "), "{err}");
    assert!(
        err.contains("is never transformed: nothing written"),
        "{err}"
    );
    assert_eq!(listing(dir.path()), ["twice.src"]);
}

/// `--keep KIND` keeps only that kind; other refusals still stop the run; a run that wrote
/// output with targets kept exits 4 (`--skip-unsupported` is every kind).
#[test]
fn keep_one_refusal_kind_at_a_time_and_exit_4_when_any_was_kept() {
    let text = "MODULE k\n  CONST jointtarget jHome:=[[0,0,0,0,30,0],[0,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget p1:=[[100,0,0],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget p2:=[[100,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveJ jHome, v100, fine, tool0;\n    MoveL p1, v100, fine, tool0;\n    MoveL p2, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n";
    let (dir, input) = scratch_with("k.mod", text);
    let out = dir.path().join("o.mod");
    let run = |extra: &[&str]| {
        let args = [
            &[
                "correct",
                input.to_str().unwrap(),
                "--cell",
                "samples/cell_rules.toml",
                "--robot",
                "r1",
                "-o",
                out.to_str().unwrap(),
            ],
            extra,
        ]
        .concat();
        trackfix(&args)
    };
    let (code, _, err) = run(&["--keep", "joint-targets"]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("warning: jointtarget `jHome`"), "{err}");
    assert!(err.contains("error: robtarget `p2`"), "{err}");
    assert!(err.contains("--keep skid-not-connected"), "{err}");
    assert!(!out.exists());
    for keep in [
        &["--keep", "joint-target", "--keep", "not-connected-skid"][..],
        &["--keep", "joint-target,skid-not-connected"],
        &["--skip-unsupported"],
    ] {
        let _ = std::fs::remove_file(&out);
        let (code, _, err) = run(keep);
        assert_eq!(code, 4, "{keep:?}: {err}");
        assert!(err.contains("k.mod: 1 target(s) changed"), "{err}");
        assert!(out.exists());
    }
    // The kinds --keep takes are the library's refusal kinds, every one of them.
    let (code, _, err) = run(&["--keep", "no-such-kind"]);
    assert_eq!(code, 2);
    use clap::ValueEnum as _;
    for kind in trackfix::transform::RefusalKind::value_variants() {
        let name = kind.to_possible_value().unwrap();
        assert!(err.contains(name.get_name()), "{name:?} missing: {err}");
    }
}

/// The provenance stamp: one comment line after the header; `correct` twice for one robot and
/// `zero` of an unstamped file are refused unless `--force`; `--no-stamp` adds nothing.
#[test]
fn provenance_stamp_blocks_double_correction() {
    let dir = tempfile::tempdir().unwrap();
    let d = |s: &str| dir.path().join(s).to_str().unwrap().to_owned();
    let common = [
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--keep",
        "joint-target",
    ];
    let sample = "samples/rapid/spot_line.mod";
    let original = trackfix::syntax::latin1(&std::fs::read(root().join(sample)).unwrap());
    let (c, cc, z) = (d("c.mod"), d("cc.mod"), d("z.mod"));
    run_ok(&[&["correct", sample, "-o", &c], &common[..]].concat());
    let corrected = std::fs::read(&c).unwrap();
    let text = trackfix::syntax::latin1(&corrected);
    let lines: Vec<&str> = text.lines().collect();
    let header = lines.iter().position(|l| l.starts_with("MODULE ")).unwrap();
    let stamp = lines[header + 1];
    assert!(
        stamp.starts_with("! trackfix: correct robot=r1 profile=")
            && stamp.contains(" sha256=")
            && stamp.ends_with(&format!(" version={}", env!("CARGO_PKG_VERSION"))),
        "{stamp}"
    );
    // The one line added: everything else has the input's line count.
    assert_eq!(lines.len(), original.lines().count() + 1);
    // inspect and check show it.
    let (_, inspect, _) = trackfix(&["inspect", &c]);
    assert!(
        inspect.contains("stamp: trackfix: correct robot=r1"),
        "{inspect}"
    );
    let (_, check, _) = trackfix(&["check", &c]);
    assert!(check.contains("trackfix: correct robot=r1"), "{check}");
    // Correcting again for r1 is refused, nothing written; with --force it goes.
    let (code, _, err) = trackfix(&[&["correct", &c, "-o", &cc], &common[..]].concat());
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("already corrected for robot `r1`"), "{err}");
    assert!(!Path::new(&cc).exists());
    run_ok(&[&["correct", &c, "-o", &cc, "--force"], &common[..]].concat());
    // A mirror of the corrected file is refused: its image would carry r1's deviation,
    // mirrored, under a `mirror` stamp that no longer says so, and a `correct` for r2 would
    // add r2's. The original mirrors; with --force the corrected one does too.
    let m = d("m.mod");
    let mirror = |input: &str, force: bool| {
        let mut args = vec![
            "mirror",
            input,
            "--cell",
            "samples/cell_rules.toml",
            "-o",
            &m,
        ];
        args.extend(["--keep", "joint-target"]);
        if force {
            args.push("--force");
        }
        trackfix(&args)
    };
    let (code, _, err) = mirror(&c, false);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains(&format!(
            "{c}:{}: corrected for robot `r1` (trackfix: correct robot=r1",
            header + 2
        )),
        "{err}"
    );
    assert!(
        err.contains("transfer --from r1 --to OTHER --mirror"),
        "{err}"
    );
    assert!(!Path::new(&m).exists());
    let (code, _, err) = mirror(sample, false);
    assert!(code == 0 || code == 4, "{err}");
    std::fs::remove_file(&m).unwrap();
    let (code, _, err) = mirror(&c, true);
    assert!(code == 0 || code == 4, "{err}");
    // zero of the unstamped sample is refused; of the corrected file it goes.
    let (code, _, err) = trackfix(&[&["zero", sample, "-o", &z], &common[..]].concat());
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("no stamp says it is corrected for robot `r1`"),
        "{err}"
    );
    run_ok(&[&["zero", &c, "-o", &z], &common[..]].concat());
    // zero undoes the correction the stamp names and leaves no literal widened: the stamp goes
    // with it (the file is as before `correct`; zeroing it again is refused).
    let zeroed = trackfix::syntax::latin1(&std::fs::read(&z).unwrap());
    assert!(!zeroed.contains("trackfix:"), "{zeroed}");
    assert_eq!(zeroed.lines().count(), original.lines().count());
    let (code, _, err) = trackfix(&[&["zero", &z, "-o", &d("zz.mod")], &common[..]].concat());
    assert_eq!(code, 3, "{err}");
    // A zero that leaves a literal widened (here: of a file corrected twice) stamps `zero`.
    run_ok(&[&["zero", &cc, "-o", &z, "--force"], &common[..]].concat());
    let zeroed = trackfix::syntax::latin1(&std::fs::read(&z).unwrap());
    assert!(
        zeroed
            .lines()
            .nth(header + 1)
            .unwrap()
            .starts_with("! trackfix: zero robot=r1"),
        "{zeroed}"
    );
    // KRL: a `;` comment after DEFDAT in the .dat (the .src is unchanged: not stamped).
    let k = d("k.src");
    run_ok(
        &[
            &["correct", "samples/krl/spot_line.src", "-o", &k],
            &common[..],
        ]
        .concat(),
    );
    let dat = trackfix::syntax::latin1(&std::fs::read(d("k.dat")).unwrap());
    let at = dat.lines().position(|l| l.starts_with("DEFDAT")).unwrap();
    assert!(
        dat.lines()
            .nth(at + 1)
            .unwrap()
            .starts_with("; trackfix: correct robot=r1")
    );
    // A program without targets needs no stamp: zero has nothing in it to change (a KSS
    // tree's system files). Zeroed beside the corrected pair, it is written as it is.
    let (plain, both) = (d("plain.src"), d("both"));
    std::fs::write(&plain, "DEF plain( )\r\n  HALT\r\nEND\r\n").unwrap();
    run_ok(&[&["zero", &k, &plain, "--out-dir", &both], &common[..]].concat());
    assert_eq!(
        std::fs::read(Path::new(&both).join("plain.src")).unwrap(),
        std::fs::read(&plain).unwrap()
    );
    // --no-stamp: the lines are the input's.
    let n = d("n.mod");
    run_ok(&[&["correct", sample, "-o", &n, "--no-stamp"], &common[..]].concat());
    let plain = trackfix::syntax::latin1(&std::fs::read(&n).unwrap());
    assert!(!plain.contains("trackfix:"));
    assert_eq!(plain.lines().count(), original.lines().count());
}

/// `trackfix transfer samples/rapid/spot_line.mod --cell samples/cell.toml --from r1 --to TO`
/// with `more` arguments.
fn transfer_spot_line(to: &str, more: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "transfer",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell.toml",
        "--from",
        "r1",
        "--to",
        to,
    ];
    args.extend_from_slice(more);
    trackfix(&args)
}

/// Identity is byte-identical: `transfer --from r1 --to r1` gives every sample back byte for byte
/// (before: 226 lines of spot_line.mod rewritten, `-1200` → `-1200.000`); `correct` then `zero`
/// through files gives back every number within its written precision and every byte outside
/// the numbers the correction changed.
#[test]
fn identity_is_byte_identical_for_every_sample() {
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for sample in sample_programs() {
        let (code, out, err) = trackfix(&[
            "transfer",
            &sample,
            "--cell",
            "samples/cell.toml",
            "--from",
            "r1",
            "--to",
            "r1",
            "--skip-unsupported",
            "--default-wobj",
            "wobj0",
            "--no-stamp",
            "--diff",
        ]);
        // Skipped targets make it a partial result (exit 4), but nothing may change.
        let kept = err.contains("(kept as written)");
        assert_eq!(code, if kept { 4 } else { 0 }, "{sample}: {err}");
        assert_eq!(out, "", "{sample}: identity transfer changed bytes");
        checked += 1;
    }
    assert!(checked >= 20, "{checked}");
    // Nor does it say a target changed: the change records are of the text written.
    let out_dir = dir.path().join("identity");
    let (code, _, err) = transfer_spot_line(
        "r1",
        &["--no-stamp", "--out-dir", out_dir.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("spot_line.mod: unchanged →"), "{err}");
    // correct → zero through files, every sample: the lines the correction did not touch are the
    // input's bytes, and every target's numbers come back within the written precision.
    let cell = sample_cell();
    for (i, sample) in sample_programs().into_iter().enumerate() {
        let ext = sample.rsplit('.').next().unwrap();
        let own = dir.path().join(i.to_string());
        std::fs::create_dir(&own).unwrap();
        let c = own.join(format!("c.{ext}"));
        let z = own.join(format!("z.{ext}"));
        let common = [
            "--cell",
            "samples/cell.toml",
            "--robot",
            "r1",
            "--skip-unsupported",
            "--default-wobj",
            "wobj0",
            "--no-stamp",
        ];
        let (cs, zs) = (c.to_str().unwrap(), z.to_str().unwrap());
        let (code, _, err) = trackfix(&[&["correct", &sample, "-o", cs], &common[..]].concat());
        if code == 2 && err.contains("nothing written") {
            continue; // a sample with nothing to correct
        }
        assert!(code == 0 || code == 4, "{sample}: {err}");
        if !c.exists() {
            continue;
        }
        run_ok(&[&["zero", cs, "-o", zs, "--force"], &common[..]].concat());
        let before = load_with_cell(&root().join(&sample), &cell, "r1");
        let after = load_with_cell(&z, &cell, "r1");
        let (a, b) = (poses(&before), poses(&after));
        assert_eq!(a.len(), b.len(), "{sample}");
        for ((name, p), (_, q)) in a.iter().zip(&b) {
            let mm = (p.translation.vector - q.translation.vector).amax();
            let deg = p.rotation.angle_to(&q.rotation).to_degrees();
            assert!(
                mm <= 1.5e-3 && deg <= 2e-4,
                "{sample} {name}: {mm} mm {deg}°"
            );
        }
        let own = |f: &&trackfix::position::ParsedFile| !f.path.to_string_lossy().contains('$');
        for x in before.files.iter().filter(own) {
            let ext = x.path.extension();
            let Some(y) = after
                .files
                .iter()
                .filter(own)
                .find(|f| f.path.extension() == ext)
            else {
                continue;
            };
            let lines = |s: &[u8]| s.iter().filter(|&&b| b == b'\n').count();
            assert_eq!(lines(&x.source), lines(&y.source), "{}", x.path.display());
        }
    }
}

/// The mirror's options given to `transfer` without `--mirror` are a usage error: they changed
/// nothing. Before, `--skid-map 1,250` wrote every target at the skid it was written with,
/// exit 0, as if it had been taken.
#[test]
fn transfer_without_mirror_refuses_the_mirror_options() {
    let transfer = |extra: &[&str]| {
        let mut args = vec![
            "transfer",
            "samples/rapid/spot_line.mod",
            "--cell",
            "samples/cell_rules.toml",
            "--from",
            "r1",
            "--to",
            "r2",
            "--skip-unsupported",
            "--check",
        ];
        args.extend(extra);
        trackfix(&args)
    };
    let (code, _, err) = transfer(&["--skid-map=1,250", "--mirror-joints"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--skid-map, --mirror-joints only apply to a mirror: add --mirror"),
        "{err}"
    );
    // Without them, the transfer runs (exit 1: --check, something would change).
    let (code, _, err) = transfer(&[]);
    assert_eq!(code, 1, "{err}");
}

/// `mirror` needs a plane: no --plane and no cell [mirror] is a usage error (it used to mirror
/// in xz silently); `--cell` without `--robot` says which frames it used.
#[test]
fn mirror_without_a_plane_is_a_usage_error() {
    let (code, _, err) = trackfix(&[
        "mirror",
        "samples/rapid/spot_line.mod",
        "--diff",
        "--skip-unsupported",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("say which plane to mirror in: --plane"),
        "{err}"
    );
    let (dir, cell) = scratch_with(
        "cell.toml",
        &std::fs::read_to_string(root().join("samples/cell.toml"))
            .unwrap()
            .replace("plane = \"xz\"\n", "")
            .replace("profile = \"track/", "profile = \"../samples/track/"),
    );
    let (code, _, err) = trackfix(&[
        "mirror",
        "samples/rapid/spot_line.mod",
        "--cell",
        cell.to_str().unwrap(),
        "--diff",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("in the [mirror] table of"), "{err}");
    drop(dir);
    let (code, _, err) = trackfix(&[
        "mirror",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell.toml",
        "--diff",
        "--skip-unsupported",
    ]);
    // jHome is a joint target, kept as written: a partial result.
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("note: mirror: plane xz of the cell's mirror frame in world, taken into each target's work object as the program declares it"),
        "{err}"
    );
}

/// Absurd values are refusals by name, never silently dropped or written: a config of 1.5 or
/// 1e22, KRL `B 9E9` and `T 1e30`-like Turn values; a profile `dx = 1e300` (the result is not
/// finite); `base x = nan` in the cell is a located cell error.
#[test]
fn absurd_values_are_named_refusals_and_check_findings() {
    let rapid = "MODULE a\n  CONST robtarget p1:=[[100,0,0],[1,0,0,0],[0,1.5,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget p2:=[[100,0,0],[1,0,0,0],[0,0,1E22,0],[500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL p1, v100, fine, tool0;\n    MoveL p2, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n";
    let (dir, input) = scratch_with("a.mod", rapid);
    let (code, out, _) = trackfix(&["check", input.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("`p1` has cf4 = 1.5: a configuration is a small integer"),
        "{out}"
    );
    assert!(out.contains("`p2` has cf6 = 1e22"), "{out}");
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--diff",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("a.mod:2:23: error: robtarget `p1` has cf4 = 1.5"),
        "{err}"
    );
    assert!(err.contains("[implausible]"), "{err}");
    drop(dir);
    let krl = "DEFDAT a\nDECL E6POS XP1={X 100.0,Y 0.0,Z 0.0,A 0.0,B 9E9,C 0.0,S 2,T 35,E1 500.0}\nDECL E6POS XP2={X 100.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0,S 2,T 99999,E1 500.0}\nDECL E6POS XP3={X 100.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0,S 2,T 1e30,E1 500.0}\nENDDAT\n";
    let (dir, input) = scratch_with("a.dat", krl);
    let (code, out, _) = trackfix(&["check", input.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("`XP1` has B = 9e9: not an angle in degrees"),
        "{out}"
    );
    assert!(out.contains("`XP2` has Turn 99999"), "{out}");
    assert!(
        out.contains("`XP3` has Turn 1e30: Status and Turn are small whole numbers"),
        "{out}"
    );
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--default-wobj",
        "$WORLD",
        "--diff",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("E6POS `XP1` has B = 9e9"), "{err}");
    drop(dir);
    // A profile that makes the result absurd: a named refusal, not a silently unchanged file.
    let profile = std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap();
    let dx = profile.find("dx = ").unwrap();
    let end = dx + profile[dx..].find('\n').unwrap();
    let line = &profile[dx..end];
    let comma = line.find(',').map_or(end, |c| dx + c);
    let absurd = format!("{}dx = 1e300{}", &profile[..dx], &profile[comma..]);
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("track")).unwrap();
    std::fs::write(dir.path().join("track/profile.toml"), absurd).unwrap();
    let cell_text = std::fs::read_to_string(root().join("samples/cell_rules.toml")).unwrap();
    std::fs::write(dir.path().join("cell.toml"), &cell_text).unwrap();
    let (code, _, err) = trackfix(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        dir.path().join("cell.toml").to_str().unwrap(),
        "--robot",
        "r1",
        "--keep",
        "joint-target",
        "--diff",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("error: robtarget `Sp001`: the computed position lies more than 1 km from its work object's origin"),
        "{err}"
    );
    assert!(err.contains("[implausible-result]"), "{err}");
    // The cell: base x = nan is located.
    let nan = cell_text.replacen("base = { x = 0.016,", "base = { x = nan,", 1);
    assert_ne!(nan, cell_text);
    std::fs::write(dir.path().join("cell.toml"), nan).unwrap();
    let (code, _, err) = trackfix(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        dir.path().join("cell.toml").to_str().unwrap(),
        "--robot",
        "r1",
        "--diff",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("cell.toml:19:") && err.contains("not a plausible value"),
        "{err}"
    );
}

/// KSS 8 sets Status bit 4 on a point taught with an absolutely accurate robot (`S 18`, `S 22`
/// in real backups): such a point is transformed, its Status kept; bit 5 and above are refused.
#[test]
fn kuka_status_bit_4_is_a_real_status() {
    let krl = "DEFDAT acc\nDECL E6POS XP1={X 900.0,Y 0.0,Z 600.0,A 0.0,B 90.0,C 0.0,S 22,T 2,E1 1500.0}\nDECL E6POS XP2={X 900.0,Y 0.0,Z 600.0,A 0.0,B 90.0,C 0.0,S 34,T 2,E1 1500.0}\nENDDAT\n";
    let (dir, input) = scratch_with("acc.dat", krl);
    let (code, out, _) = trackfix(&["check", input.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(!out.contains("`XP1` has Status"), "{out}");
    assert!(
        out.contains("`XP2` has Status 34: only bits 0 to 4 exist"),
        "{out}"
    );
    let out_file = dir.path().join("out.dat");
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--default-wobj",
        "$WORLD",
        "--keep",
        "implausible",
        "--no-stamp",
        "-o",
        out_file.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{err}");
    assert!(err.contains("1 target(s) changed"), "{err}");
    let written = std::fs::read_to_string(&out_file).unwrap();
    let xp1 = written.lines().find(|l| l.contains("XP1")).unwrap();
    assert!(xp1.contains(",S 22,T 2,E1 1500.0}"), "{xp1}");
    assert!(
        !xp1.contains("X 900.0,Y 0.0,Z 600.0,"),
        "not transformed: {xp1}"
    );
    assert!(written.contains("S 34,T 2,E1 1500.0}"), "{written}");
}

/// 2,000 refused targets on one line: each diagnostic shows a window of the line, so the
/// output grows linearly (before: every refusal kept and printed the whole 300 kB line).
#[test]
fn refusals_on_one_long_line_render_a_window() {
    let n = 2000;
    let mut line = String::from("  ");
    for i in 0..n {
        line.push_str(&format!(
            "CONST jointtarget j{i}:=[[0,0,0,0,30,0],[0,9E9,9E9,9E9,9E9,9E9]];"
        ));
    }
    let text = format!("MODULE big\n{line}\nENDMODULE\n");
    let (dir, input) = scratch_with("big.mod", &text);
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--diff",
        "-v",
    ]);
    assert_eq!(code, 3);
    assert_eq!(
        err.matches("is a joint target").count(),
        n,
        "{}",
        &err[..2000]
    );
    // Each diagnostic is a few short lines: about 700 bytes, not the 130 kB line.
    assert!(err.len() < n * 1000, "{} bytes", err.len());
    assert!(err.lines().all(|l| l.len() < 1000));
    assert!(err.contains("2:"), "{}", &err[..500]);
    let last = format!("j{}", n - 1);
    assert!(err.contains(&format!("`{last}`")));
    drop(dir);
}

/// Control characters in source lines are shown escaped, never sent to the terminal.
#[test]
fn control_characters_are_escaped_in_diagnostics() {
    let text = "MODULE m\n  CONST robtarget p1:=[[1,,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]; ! \u{1b}]0;owned\u{7}\nENDMODULE\n";
    let (dir, input) = scratch_with("m.mod", text);
    let (code, out, _) = trackfix(&["check", input.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(!out.contains('\u{1b}') && !out.contains('\u{7}'), "{out:?}");
    assert!(out.contains("\\x1b]0;owned\\x07"), "{out}");
    assert!(out.contains("control character 0x1b"), "{out}");
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--diff",
    ]);
    assert_eq!(code, 2);
    assert!(!err.contains('\u{1b}'), "{err:?}");
    drop(dir);
}

/// A KRL pair written under a new name gets `DEF`/`DEFDAT` renamed to it, and says so; a name
/// KRL cannot take is refused with nothing written.
#[test]
fn krl_pair_under_a_new_name_renames_def_and_defdat() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("side_b.src");
    let args = |o: &str| {
        vec![
            "correct".to_owned(),
            "samples/krl/spot_line.src".to_owned(),
            "--cell".to_owned(),
            "samples/cell.toml".to_owned(),
            "--robot".to_owned(),
            "r1".to_owned(),
            "--skip-unsupported".to_owned(),
            "-o".to_owned(),
            o.to_owned(),
        ]
    };
    let a = args(out.to_str().unwrap());
    let (code, _, err) = trackfix(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(code == 0 || code == 4, "{err}");
    assert!(err.contains("renamed `spot_line` to `side_b`"), "{err}");
    let src = trackfix::syntax::latin1(&std::fs::read(&out).unwrap());
    let dat = trackfix::syntax::latin1(&std::fs::read(out.with_extension("dat")).unwrap());
    assert!(src.contains("\nDEF side_b( )"), "{}", &src[..300]);
    assert!(!src.contains("DEF spot_line("));
    assert!(dat.contains("\nDEFDAT  side_b PUBLIC"), "{}", &dat[..300]);
    // Everything else of the .src is the input's.
    let original =
        trackfix::syntax::latin1(&std::fs::read(root().join("samples/krl/spot_line.src")).unwrap());
    assert_eq!(src, original.replacen("DEF spot_line(", "DEF side_b(", 1));
    let bad = dir.path().join("2-side.src");
    let a = args(bad.to_str().unwrap());
    let (code, _, err) = trackfix(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot be the name of a krl program"), "{err}");
    assert_eq!(listing(dir.path()), ["side_b.dat", "side_b.src"]);
}

/// A batch: repeated warnings grouped (3 shown, then counted; `-v` shows all), one totals line,
/// `-q` prints nothing but errors, `--format json` is one document on standard output.
#[test]
fn batch_reports_group_repeats_end_with_totals_and_speak_json() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir(&input).unwrap();
    for i in 0..5 {
        std::fs::copy(
            root().join("samples/rapid/spot_line.mod"),
            input.join(format!("m{i}.mod")),
        )
        .unwrap();
    }
    let run = |extra: &[&str], out: &str| {
        let o = dir.path().join(out);
        trackfix(
            &[
                &[
                    "correct",
                    input.to_str().unwrap(),
                    "--cell",
                    "samples/cell_rules.toml",
                    "--robot",
                    "r1",
                    "--keep",
                    "joint-target",
                    "--out-dir",
                    o.to_str().unwrap(),
                ],
                extra,
            ]
            .concat(),
        )
    };
    // What the cell's entry makes of each copy's `wobj_car` (its object frame is kept), shown
    // three times, then counted.
    let reading =
        "warning: work object `wobj_car`: the cell file's entry for robot `r1` is its user frame";
    let (code, _, err) = run(&[], "a");
    assert_eq!(code, 4, "{err}");
    assert_eq!(err.matches(reading).count(), 3, "{err}");
    assert!(
        err.contains("warning: … and 2 more like this [work object `…`: the cell file"),
        "{err}"
    );
    assert_eq!(
        err.matches("warning: jointtarget `jHome`").count(),
        3,
        "{err}"
    );
    assert!(
        err.contains("warning: … and 2 more like this [joint-target] (-v shows all)"),
        "{err}"
    );
    let last = err.lines().last().unwrap();
    assert_eq!(
        last,
        "total: 5 programs (5 files): 1130 target(s) changed in 5 files, 5 written, 0 refused, 5 kept as written, 0 notes"
    );
    let (_, _, err) = run(&["-v"], "b");
    assert_eq!(err.matches(reading).count(), 5, "{err}");
    assert_eq!(
        err.matches("warning: jointtarget `jHome`").count(),
        5,
        "{err}"
    );
    assert!(!err.contains("more like this"));
    let (code, out, err) = run(&["-q"], "c");
    assert_eq!((code, out.as_str(), err.as_str()), (4, "", ""));
    // JSON on standard output; on standard error only what the transform takes the programs
    // to mean, as in text.
    let (code, out, err) = run(&["--format", "json"], "d");
    assert_eq!(code, 4);
    assert_eq!(err.matches(reading).count(), 3, "{err}");
    assert!(!err.contains("jHome") && !err.contains("total:"), "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(doc["exit"], 4);
    assert_eq!(doc["files"].as_array().unwrap().len(), 5);
    assert_eq!(doc["refusals"][0]["kind"], "joint-target");
    assert_eq!(doc["refusals"][0]["kept"], true);
    assert_eq!(doc["totals"]["targets_changed"], 1130);
    assert!(
        doc["files"][0]["written_to"]
            .as_str()
            .unwrap()
            .ends_with(".mod")
    );
    // check --format json.
    let (code, out, _) = trackfix(&["check", "samples/rapid/two_wobjs.mod", "--format", "json"]);
    assert_eq!(code, 1);
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(doc["summary"]["findings"].as_u64().unwrap() >= 1);
    assert!(doc["files"][0]["findings"][0]["line"].as_u64().unwrap() > 0);
}

/// `--mirror-frames` mirrors a tool's load like its frame, with `Sb` (tool flip y): the centre of
/// gravity's y changes sign, the axes of moment `Rx(90°)` become `Rx(-90°)`; mass and moments
/// stay.
#[test]
fn mirror_frames_mirrors_the_tool_load_centre_of_gravity() {
    let (dir, input) = scratch_with(
        "t.mod",
        "MODULE t\n  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[10,20,180],[0.707107,0.707107,0,0],0.9,1.1,0.6]];\nENDMODULE\n",
    );
    let (code, out, err) = trackfix(&[
        "mirror",
        input.to_str().unwrap(),
        "--plane",
        "xz",
        "--mirror-frames",
        "--no-stamp",
        "--diff",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("+  PERS tooldata tGun:=[TRUE,[[12.5,3.200,412.8],[0.965926,0,0.258819,0]],[48.5,[10,-20.000,180],[0.707107,-0.707107,0,0],0.9,1.1,0.6]];"),
        "{out}"
    );
    drop(dir);
}

/// `--mirror-frames` with the cell's plane in world (y = -1850.75, the samples' `[mirror]`): a
/// KSS base mirrors in world and the point in it locally, so the chain reaches the world mirror
/// image once. `BASE_DATA[1]` at y -1480 goes to -2221.5, `XP1` at y 20 in it to -20: the point,
/// at world y -1460, reaches -2241.5 = 2·(-1850.75) + 1460. (The point was mirrored in world as
/// well, to y -741.5, and reached -2963: its image 721.5 mm off.)
#[test]
fn mirror_frames_with_a_world_plane_mirrors_base_and_point_once() {
    let dir = tempfile::tempdir().unwrap();
    let r1 = dir.path().join("KRC/R1");
    let files = [
        (
            "System/$config.dat",
            "DEFDAT $CONFIG PUBLIC\nDECL GLOBAL FRAME BASE_DATA[32]\nBASE_DATA[1]={X 2150.0,Y -1480.0,Z 720.0,A 0.0,B 0.0,C 0.0}\nENDDAT\n",
        ),
        (
            "Program/m.src",
            "DEF m( )\n  BAS (#BASE,1 )\n  LIN XP1\nEND\n",
        ),
        (
            "Program/m.dat",
            "DEFDAT m PUBLIC\nDECL E6POS XP1={X 10.0,Y 20.0,Z 30.0,A 0.0,B 0.0,C 0.0,S 6,T 27,E1 1500.0}\nENDDAT\n",
        ),
    ];
    for (path, text) in files {
        let p = r1.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    let out = dir.path().join("out");
    let (code, _, err) = trackfix(&[
        "mirror",
        r1.to_str().unwrap(),
        "--cell",
        "samples/cell_rules.toml",
        "--mirror-frames",
        "--no-stamp",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let config = std::fs::read_to_string(out.join("System/$config.dat")).unwrap();
    assert!(
        config.contains("BASE_DATA[1]={X 2150.0,Y -2221.500,Z 720.0,A 0.0,B 0.0,C 0.0}"),
        "{config}"
    );
    let dat = std::fs::read_to_string(out.join("Program/m.dat")).unwrap();
    assert!(
        dat.contains("XP1={X 10.0,Y -20.000,Z 30.0,A 0.0,B 0.0,C 0.0,"),
        "{dat}"
    );
}

/// The README's main command on the sample, with the cell's kinematics: no target refused (the
/// joint target jHome moves through FK/IK with the tracks), and `correct`'s diff of jHome.
#[test]
fn readme_main_command_with_kinematics() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let (code, _, err) = transfer_spot_line("r2", &["--mirror", "--out-dir", out]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("227 target(s) changed"), "{err}");
    let (code, diff, err) = trackfix(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--diff",
    ]);
    assert_eq!(code, 0, "{err}");
    let jhome: Vec<&str> = diff.lines().filter(|l| l.contains("jHome:=")).collect();
    assert_eq!(
        jhome,
        [
            "-  CONST jointtarget jHome:=[[0,-20,30,0,80,0],[150,9E+09,9E+09,9E+09,9E+09,9E+09]];",
            "+  CONST jointtarget jHome:=[[0.0514,-19.9494,30.0292,-0.0669,79.9236,0.0997],[150,9E+09,9E+09,9E+09,9E+09,9E+09]];",
        ]
    );
}

/// A number literal of a program's text, by an independent scanner: its text and value. Signs
/// are not part of it; names (`p10`, `$X1`) hold none.
fn literals(src: &[u8]) -> Vec<(String, f64)> {
    let text = String::from_utf8_lossy(src);
    let b = text.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_' || c == b'$' || c == b'.';
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        if word(b[i]) && (i == 0 || !word(b[i - 1])) {
            while i < b.len()
                && (word(b[i])
                    || ((b[i] == b'+' || b[i] == b'-') && matches!(b[i - 1], b'e' | b'E')))
            {
                i += 1;
            }
            let w = &text[start..i];
            if w.starts_with(|c: char| c.is_ascii_digit() || c == '.')
                && let Ok(v) = w.parse::<f64>()
            {
                out.push((w.to_owned(), v));
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Issue 10 item 5: `correct` then `zero` through files, both stamped (the default), gives back
/// the input bytes for every sample and both sample cells — the stamp line too: `correct`
/// records in its stamp the decimals of the literals it widened (`-1200` → `-1200.873`), `zero`
/// writes a value it brought back with them again (`-1200.000` → `-1200`) and, with nothing
/// left widened, removes the stamp. Compared: every file of each program, byte for byte.
///
/// Where the bytes differ, each differing literal is the one documented limit (README "Identity
/// is byte-identical", docs/design.md §4), checked here literal by literal: a leading-point
/// literal (`.5`) corrected past 1, which comes back at its value with a leading zero. Every
/// other literal — quaternions written at 6 decimals, exponent forms, widened values, the A and
/// C of a KUKA target at B = ±90° (gimbal lock: the stamp's `gimbal=` keeps the split written)
/// — comes back as written: `correct` writes with `zero` in view (docs/design.md §5).
#[test]
fn correct_then_zero_stamped_gives_back_the_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (mut identical, mut changed_and_back) = (0, 0);
    let mut lost_points = 0;
    for cell in ["samples/cell.toml", "samples/cell_rules.toml"] {
        for (i, sample) in sample_programs().into_iter().enumerate() {
            let name = sample.rsplit('/').next().unwrap().to_owned();
            let sample_dir = root().join(sample.rsplit_once('/').unwrap().0);
            let own = dir.path().join(format!("{}-{i}", cell.len()));
            let (c, z) = (own.join("c"), own.join("z"));
            let common = [
                "--cell",
                cell,
                "--robot",
                "r1",
                "--skip-unsupported",
                "--default-wobj",
                "wobj0",
            ];
            let (code, _, err) = trackfix(
                &[
                    &["correct", &sample, "--out-dir", c.to_str().unwrap()],
                    &common[..],
                ]
                .concat(),
            );
            assert!(code == 0 || code == 4 || code == 2, "{sample}: {err}");
            if !c.join(&name).exists() {
                continue;
            }
            // --force: a program the correction left unchanged carries no stamp.
            let (code, _, err) = trackfix(
                &[
                    &[
                        "zero",
                        c.join(&name).to_str().unwrap(),
                        "--force",
                        "--out-dir",
                        z.to_str().unwrap(),
                    ],
                    &common[..],
                ]
                .concat(),
            );
            assert!(code == 0 || code == 4, "{sample}: {err}");
            for entry in std::fs::read_dir(&c).unwrap() {
                let file = entry.unwrap().file_name();
                let original = std::fs::read(sample_dir.join(&file)).unwrap();
                let corrected = std::fs::read(c.join(&file)).unwrap();
                let back = std::fs::read(z.join(&file)).unwrap();
                let what = format!("{cell} {}", file.to_string_lossy());
                if back == original {
                    identical += 1;
                    changed_and_back += usize::from(corrected != original);
                    continue;
                }
                // The stamp line of a file still widened holds numbers of its own.
                let unstamped: String = String::from_utf8_lossy(&back)
                    .lines()
                    .filter(|l| !l.contains("trackfix: zero"))
                    .flat_map(|l| [l, "\n"])
                    .collect();
                let (a, b) = (literals(&original), literals(unstamped.as_bytes()));
                assert_eq!(a.len(), b.len(), "{what}: literal count");
                let text = String::from_utf8_lossy(&original).into_owned();
                let lines: Vec<&str> = text.lines().collect();
                let line_of = |k: usize| {
                    // The line of the k-th literal: count literals line by line.
                    let mut seen = 0;
                    for l in &lines {
                        seen += literals(l.as_bytes()).len();
                        if seen > k {
                            return l.to_ascii_uppercase();
                        }
                    }
                    String::new()
                };
                for (k, ((ta, va), (tb, vb))) in a.iter().zip(&b).enumerate() {
                    if ta == tb {
                        continue;
                    }
                    let line = line_of(k);
                    // `.5` corrected past 1 (`1.734`) has no leading-point spelling; zero then
                    // writes the value back with its decimals, and a leading zero.
                    let lost_point = ta.starts_with('.') && *tb == format!("0{ta}") && va == vb;
                    assert!(lost_point, "{what}: `{ta}` came back as `{tb}` in {line}");
                    lost_points += usize::from(lost_point);
                }
                // Nothing but the literals differs: the same lines, and no stamp unless some
                // literal is still widened.
                assert_eq!(
                    String::from_utf8_lossy(&back).lines().count(),
                    lines.len()
                        + usize::from(String::from_utf8_lossy(&back).contains("trackfix: zero")),
                    "{what}"
                );
            }
        }
    }
    // Figures seen: 49 files identical (20 of them changed by the correction and back); one
    // literal differs: a `.5` corrected to `-1.022` (hand_9e9.mod, samples/cell_rules.toml).
    // The A and C of the KUKA targets at B = 90° come back as written: the stamp's `gimbal=`
    // keeps their split (before it, 18 literals of 9 targets differed).
    assert!(
        identical >= 49 && changed_and_back >= 20,
        "{identical} {changed_and_back}"
    );
    assert!(lost_points <= 1, "{lost_points}");
}

/// `correct` turns an `Offs` offset with its target: the corrected target is `G·T` (in the
/// work object), and the point `Offs(T, d)` corrected is `G·(T + d)` = `Offs(G·T, R_G·d)`. The
/// test reads `G` back from the written target (its pose after over before) and holds the
/// written offset to `R_G·d` within the written precision; `RelTool`'s offset, in the tool
/// frame, stays; `zero` brings the offset back.
#[test]
fn correct_turns_an_offs_offset_with_its_target() {
    use trackfix::geometry::pose_xyz_deg;
    let d = pose_xyz_deg(0.3, -0.2, 0.5, 0.2, -0.3, 0.5);
    with_constant_deviation(d, |setup| {
        let src = "MODULE M\n  PERS wobjdata w1:=[FALSE,TRUE,\"\",[[2100,-1350,480],[0.965925826,0,0,0.258819045]],[[0,0,0],[1,0,0,0]]];\n  \
            CONST robtarget p1:=[[-1702.5,-320,225],[0,0.707107,0.707107,0],[-1,0,-1,0],[400,9E9,9E9,9E9,9E9,9E9]];\n  \
            CONST robtarget p3:=[[-1102.5,-320,225],[0,0.707107,0.707107,0],[-1,0,-1,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n  \
            PROC main()\n    MoveL Offs(p1,10,20,300),v100,fine,tool0\\WObj:=w1;\n    \
            MoveL RelTool(p1,10,20,300),v100,fine,tool0\\WObj:=w1;\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n    \
            Weld p1;\n    Weld p3;\n    MoveL Offs(getP(),10,20,300),v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n  \
            PROC Weld(robtarget p)\n    MoveL Offs(p,10,20,300),v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n  \
            FUNC robtarget getP()\n    RETURN p1;\n  ENDFUNC\nENDMODULE\n";
        let parse = |text: &str| Program {
            files: vec![trackfix::rapid::parse_file(
                Path::new("m.mod"),
                text.as_bytes().to_vec(),
            )],
        };
        let run = |p: &Program, dir: Direction| {
            let r = apply(p, track_correction(p, setup, dir)).unwrap();
            assert!(r.refusals().next().is_none());
            String::from_utf8(r.files[0].output.clone()).unwrap()
        };
        let before = parse(src);
        let corrected = run(&before, Direction::Correct);
        let after = parse(&corrected);
        let pose = |p: &Program| {
            p.files[0]
                .positions()
                .find(|t| t.name.as_deref() == Some("p1"))
                .unwrap()
                .cartesian
                .unwrap()
                .pose()
                .unwrap()
        };
        let g = pose(&after) * pose(&before).inverse();
        assert!(g.rotation.angle().to_degrees() > 0.3, "{g:?}");
        let offsets = |p: &Program| -> Vec<[f64; 3]> {
            p.files[0]
                .offsets
                .iter()
                .map(|c| c.delta.each_ref().map(|f| f.as_ref().unwrap().value()))
                .collect()
        };
        let want = g.rotation * nalgebra::Vector3::new(10.0, 20.0, 300.0);
        let got = offsets(&after);
        // Three decimals written, and G read back from a target written to 3 and 6 decimals.
        for (k, w) in [want.x, want.y, want.z].iter().enumerate() {
            assert!(
                (got[0][k] - w).abs() < 2e-3,
                "{got:?} {want:?}\n{corrected}"
            );
        }
        let moved =
            (nalgebra::Vector3::from(got[0]) - nalgebra::Vector3::new(10.0, 20.0, 300.0)).norm();
        assert!(moved > 1.0, "the offset turned: {got:?}");
        assert_eq!(got[1], [10.0, 20.0, 300.0], "RelTool's stays");
        // The offset of what `getP()` returns, `p1`, turns as p1's.
        assert_eq!(got[2], got[0], "{corrected}");
        // `Weld`'s offset stands for p1 and p3, at two skids of a track whose deviation does
        // not turn along it: both turn it alike, and it is written as for p1 alone.
        assert_eq!(got[3], got[0], "{corrected}");
        // `zero` gives the offset back (the stamp, which the command line writes, gives its text
        // back too: `correct_then_zero_stamped_gives_back_the_bytes`).
        let zeroed = run(&after, Direction::Zero);
        assert_eq!(offsets(&parse(&zeroed))[0], [10.0, 20.0, 300.0], "{zeroed}");
    })
}

/// An `Offs`/`RelTool` call's bases are the targets its reference names where it is written,
/// as a motion there reaches them: a module's own `LOCAL` target before another module's of the
/// same name, another module's exported one, every element of an array indexed by a computed
/// value, the target inside a nested call; a routine's parameter stands for the targets the
/// calls pass there.
#[test]
fn an_offset_calls_bases_are_the_targets_its_reference_means_there() {
    let t = |x: u32| format!("[[{x},0,500],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]");
    let a = format!(
        "MODULE A\n  LOCAL CONST robtarget p1:={};\n  PROC a()\n    \
         MoveL Offs(p1,0,0,10),v100,fine,tool0;\n    \
         MoveL Offs(RelTool(p2,0,0,5),0,0,10),v100,fine,tool0;\n    b p1;\n  ENDPROC\n  \
         PROC b(robtarget p2)\n    MoveL Offs(p2,0,0,5),v100,fine,tool0;\n  ENDPROC\n  \
         PROC relay(robtarget q)\n    b q;\n  ENDPROC\nENDMODULE\n",
        t(1)
    );
    let b = format!(
        "MODULE B\n  LOCAL CONST robtarget p1:={};\n  CONST robtarget p2:={};\n  \
         CONST robtarget pGrid{{2}}:=[{},{}];\n  PROC c()\n    \
         MoveL Offs(p1,0,0,10),v100,fine,tool0;\n    relay p2;\n    \
         FOR i FROM 1 TO 2 DO\n      MoveL Offs(pGrid{{i}},0,0,10),v100,fine,tool0;\n    ENDFOR\n  \
         ENDPROC\nENDMODULE\n",
        t(2),
        t(3),
        t(4),
        t(5)
    );
    let files = trackfix::rapid::parse_task(vec![
        ("A.mod".into(), a.into_bytes().into()),
        ("B.mod".into(), b.into_bytes().into()),
    ]);
    // (file, index) of the target whose x is `x`: each literal above has its own.
    let at = |x: f64| -> (usize, usize) {
        files
            .iter()
            .enumerate()
            .find_map(|(fi, f)| {
                f.positions()
                    .position(|p| {
                        p.cartesian
                            .as_ref()
                            .and_then(|c| c.trans[0].as_ref().map(|n| n.value()))
                            == Some(x)
                    })
                    .map(|i| (fi, i))
            })
            .unwrap()
    };
    let bases = |fi: usize| -> Vec<(String, Vec<(usize, usize)>)> {
        files[fi]
            .offsets
            .iter()
            .map(|c| (c.target.clone(), c.bases.clone()))
            .collect()
    };
    assert_eq!(
        bases(0),
        vec![
            ("p1".to_owned(), vec![at(1.0)]),
            ("RelTool(p2,0,0,5)".to_owned(), vec![at(3.0)]),
            ("p2".to_owned(), vec![at(3.0)]),
            // `b p1` in `a`, and B's `relay p2` on through `relay`'s `b q`.
            ("p2".to_owned(), vec![at(1.0), at(3.0)]),
        ]
    );
    assert_eq!(
        bases(1),
        vec![
            ("p1".to_owned(), vec![at(2.0)]),
            ("pGrid{i}".to_owned(), vec![at(4.0), at(5.0)]),
        ]
    );
}

/// An offset that stands for targets some of which are left as written and some moved follows
/// neither: it is refused by name (kept as written, it is wrong for the moved one). A work
/// object named by a routine's parameter is the caller's, not the module's frame of that name:
/// the targets moved with it are refused, where they were corrected in the module's frame.
#[test]
fn a_partly_kept_offset_and_a_parameter_work_object_are_refused() {
    use trackfix::geometry::pose_xyz_deg;
    use trackfix::transform::RefusalKind;
    let w = "[FALSE,TRUE,\"\",[[2100,-1350,480],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]";
    let t =
        |skid: &str| format!("[[500,200,300],[0,0,1,0],[0,0,0,0],[{skid},9E9,9E9,9E9,9E9,9E9]]");
    let partly = format!(
        "MODULE M\n  PERS wobjdata w1:={w};\n  CONST robtarget pa:={};\n  CONST robtarget pc:={};\n  \
         PROC main()\n    Weld pa;\n    Weld pc;\n  ENDPROC\n  \
         PROC Weld(robtarget p)\n    MoveL Offs(p,0,30,50),v100,fine,tool0\\WObj:=w1;\n    \
         MoveL p,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n",
        t("9E9"),
        t("3000")
    );
    let by_parameter = format!(
        "MODULE M\n  PERS wobjdata w1:={w};\n  PERS wobjdata wo:={w};\n  CONST robtarget pa:={};\n  \
         PROC main()\n    WeldW pa, w1;\n  ENDPROC\n  \
         PROC WeldW(robtarget p, PERS wobjdata wo)\n    MoveL p,v100,fine,tool0\\WObj:=wo;\n  ENDPROC\nENDMODULE\n",
        t("3000")
    );
    let d = pose_xyz_deg(0.3, -0.2, 0.5, 0.2, -0.3, 0.5);
    with_constant_deviation(d, |setup| {
        let refused = |src: &str| -> Vec<(String, RefusalKind, String)> {
            let p = Program {
                files: vec![trackfix::rapid::parse_file(
                    Path::new("m.mod"),
                    src.as_bytes().to_vec(),
                )],
            };
            apply(&p, track_correction(&p, setup, Direction::Correct))
                .unwrap()
                .refusals()
                .map(|r| (r.target.clone(), r.kind, r.message.clone()))
                .collect()
        };
        let got = refused(&partly);
        let kinds: Vec<_> = got.iter().map(|(t, k, _)| (t.as_str(), *k)).collect();
        assert_eq!(
            kinds,
            [
                ("pa", RefusalKind::SkidNotConnected),
                ("p", RefusalKind::SharedOffset)
            ],
            "{got:?}"
        );
        assert!(got[1].2.contains("1 of them left as written"), "{got:?}");
        // Required, optional, or one of optional alternatives.
        for head in [
            "robtarget p, PERS wobjdata wo",
            "robtarget p, \\PERS wobjdata wo",
            "robtarget p, \\PERS wobjdata w2 | PERS wobjdata wo",
        ] {
            let call = if head.contains('\\') {
                "WeldW pa \\wo:=w1;"
            } else {
                "WeldW pa, w1;"
            };
            let program = by_parameter
                .replace("robtarget p, PERS wobjdata wo", head)
                .replace("WeldW pa, w1;", call);
            let got = refused(&program);
            let kinds: Vec<_> = got.iter().map(|(t, k, _)| (t.as_str(), *k)).collect();
            assert_eq!(
                kinds,
                [("pa", RefusalKind::UnresolvedWorkObject)],
                "{head}: {got:?}"
            );
            // Named as the parameter it is, on the line of the call that passes the target.
            assert!(
                got[0]
                    .2
                    .contains("on line 6 with `wo`, a parameter of the routine"),
                "{head}: {got:?}"
            );
        }
    })
}

/// The cell's identified frame stands for the program's declaration, which still says whether
/// the frame moves with another unit: a work object on a positioner, given under
/// `[robot.NAME.wobj]`, is refused as moving, not corrected in the identified pose. A KRL base
/// given as `"BASE_DATA[ 01 ]"` is the program's `BASE_DATA[1]`, as the program's own spellings
/// of the element are.
#[test]
fn a_cells_frame_keeps_its_declarations_unit_and_is_found_by_its_element() {
    use trackfix::transform::RefusalKind;
    let path = root().join("samples/cell_rules.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |lines: &str| {
        let text = text.replacen("[robot.r1.wobj]\n", &format!("[robot.r1.wobj]\n{lines}"), 1);
        Cell::parse(
            &path,
            &text.replace("\"BASE_DATA[1]\" = { x = -440.0", "old = { x = -440.0"),
        )
        .unwrap()
    };
    let d = trackfix::geometry::pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05);
    let profile = move |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(d) };
    // The positioner's work object, identified: still moving.
    let cell = with("wStn1 = { x = 1000, y = -1000, z = 500, rx = 0, ry = 0, rz = 0 }\n");
    let program = load_with_cell(&root().join("samples/rapid/moving_wobj.mod"), &cell, "r1");
    let setup = TrackSetup::new(&cell.robots["r1"], &profile);
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let moving: Vec<_> = result
        .refusals()
        .filter(|r| r.kind == RefusalKind::MovingWorkObject)
        .map(|r| r.target.clone())
        .collect();
    assert_eq!(moving, ["pSeam1", "pSeam2"]);
    // The same base, keyed three ways: one result, the identified base's.
    let krl = root().join("samples/krl/two_bases.src");
    let corrected = |cell: &Cell| -> Vec<Vec<u8>> {
        let program = load_with_cell(&krl, cell, "r1");
        let setup = TrackSetup::new(&cell.robots["r1"], &profile);
        let result = apply(
            &program,
            track_correction(&program, &setup, Direction::Correct),
        )
        .unwrap();
        result.files.iter().map(|f| f.output.clone()).collect()
    };
    let outputs: Vec<_> = [
        "\"BASE_DATA[1]\"",
        "\"base_data[ 1 ]\"",
        "\"BASE_DATA[01]\"",
    ]
    .iter()
    .map(|key| {
        corrected(&with(&format!(
            "{key} = {{ x = -300.0, y = -1850.75, z = 612.4, rx = 0.0, ry = 0.0, rz = 0.0 }}\n"
        )))
    })
    .collect();
    assert_eq!(outputs[0], outputs[1]);
    assert_eq!(outputs[0], outputs[2]);
    // And not the config's BASE_DATA[1].
    assert_ne!(outputs[0], corrected(&with("")));
}

/// `mirror --robot k1 --to k2` with a plane in world, for KUKA robots whose cell gives each its
/// own `$config.dat`: the image is written in k2's `BASE_DATA[1]`, not k1's. Worked by hand:
/// `XP1` in k1's base `(1000, -1850.75, 600)` is the world point `(1100, -2150.75, 800)`; its
/// image in the plane `y = -1850.75` is `(1100, -1550.75, 800)`; in k2's base, at
/// `(1030, -1820, 590)` turned 4° about z, that is `(70, 269.25, 210)` turned by -4°, with
/// `A = -10° - 4°`.
#[test]
fn a_mirror_for_another_kuka_robot_is_written_in_its_own_config_base() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let config = |base: &str| {
        format!(
            "DEFDAT  $CONFIG\nDECL GLOBAL FRAME TOOL_DATA[16]\nTOOL_DATA[1]={{X 0.0,Y 0.0,Z 200.0,A 0.0,B 0.0,C 0.0}}\nDECL GLOBAL FRAME BASE_DATA[32]\nBASE_DATA[1]={{{base}}}\nENDDAT\n"
        )
    };
    std::fs::write(
        d.join("cfgA.dat"),
        config("X 1000.0,Y -1850.75,Z 600.0,A 0.0,B 0.0,C 0.0"),
    )
    .unwrap();
    std::fs::write(
        d.join("cfgB.dat"),
        config("X 1030.0,Y -1820.0,Z 590.0,A 4.0,B 0.0,C 0.0"),
    )
    .unwrap();
    let profile = root().join("samples/track/profile.toml");
    let robot = |name: &str, y: f64, rz: f64, cfg: &str| {
        format!(
            "[robot.{name}]\nprofile = \"{}\"\nbase = {{ x = 0.0, y = {y}, z = 0.0, rx = 0.0, ry = 0.0, rz = {rz} }}\ntrack_axis = [1.0, 0.0, 0.0]\nskid = \"E1\"\nconfig_dat = \"{cfg}\"\n\n",
            profile.display()
        )
    };
    let cell = format!(
        "{}{}[mirror]\nplane = \"xz\"\nframe = {{ x = 0.0, y = -1850.75, z = 0.0, rx = 0.0, ry = 0.0, rz = 0.0 }}\nframe_in = \"world\"\ntool_flip = \"y\"\nconfig = \"keep\"\n",
        robot("k1", -3500.0, 90.0, "cfgA.dat"),
        robot("k2", -200.0, -90.0, "cfgB.dat")
    );
    std::fs::write(d.join("kc.toml"), cell).unwrap();
    std::fs::write(
        d.join("km.src"),
        "DEF km( )\n  $TOOL=TOOL_DATA[1]\n  $BASE=BASE_DATA[1]\n  LIN XP1\nEND\n",
    )
    .unwrap();
    std::fs::write(
        d.join("km.dat"),
        "DEFDAT km\nDECL E6POS XP1={X 100.0,Y -300.0,Z 200.0,A 10.0,B 20.0,C 30.0,S 2,T 2,E1 500.0}\nENDDAT\n",
    )
    .unwrap();
    let out = d.join("out");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (code, _, err) = trackfix(&[
        "mirror",
        &s(&d.join("km.src")),
        "--cell",
        &s(&d.join("kc.toml")),
        "--robot",
        "k1",
        "--to",
        "k2",
        "--out-dir",
        &s(&out),
    ]);
    assert_eq!(code, 0, "{err}");
    let (sin, cos) = 4f64.to_radians().sin_cos();
    let (x, y) = (70.0 * cos + 269.25 * sin, -70.0 * sin + 269.25 * cos);
    let written = std::fs::read_to_string(out.join("km.dat")).unwrap();
    let expected = format!(
        "DECL E6POS XP1={{X {x:.3},Y {y:.3},Z 210.000,A -14.0000,B 20.0,C -30.0000,S 2,T 2,E1 500.0}}"
    );
    assert!(written.contains(&expected), "{expected}\n{written}");
}

/// A cell file's entry for a RAPID work object is its user frame: the declaration's object frame
/// (`oframe`, here 200 mm along x and turned 10°) is kept, as the controller composes
/// `uframe·oframe`, and a warning at the declaration says so with its value. An entry equal to
/// the declared user frame then corrects as the declaration alone does (before, the entry stood
/// for the whole work object and the object frame was dropped unsaid). An object frame that is
/// the identity says nothing; one with fields that are not numbers refuses the targets.
#[test]
fn a_cell_work_object_entry_keeps_the_programs_object_frame() {
    use trackfix::transform::RefusalKind;
    use trackfix::transform::cell::frame_readings;
    let module = |oframe: &str| {
        format!(
            "MODULE M\n  PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[1670.3,-1850.75,612.4],[1,0,0,0]],{oframe}];\n  \
             CONST robtarget p10:=[[100,200,300],[0,1,0,0],[-1,-1,-2,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  \
             PROC main()\n    MoveL p10,v100,fine,tool0\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n"
        )
    };
    let cell = |entry: &str| {
        Cell::parse(
            Path::new("cell.toml"),
            &format!(
                "[robot.r1]\nprofile = \"track/profile.toml\"\n\
                 base = {{ x = 0, y = -3500, z = 0, rx = 0, ry = 0, rz = 90 }}\n\
                 track_axis = [1, 0, 0]\nskid = \"eax_a\"\n{entry}"
            ),
        )
        .unwrap()
    };
    let user_frame = "[robot.r1.wobj]\nwobj_car = { x = 1670.3, y = -1850.75, z = 612.4, rx = 0, ry = 0, rz = 0 }\n";
    let deviation = trackfix::geometry::pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05);
    let dev = move |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(deviation) };
    // (the line of `p10` written, the refusals, the readings) of `correct` of `src` with `cell`.
    let correct = |src: &str, cell: &Cell| {
        let robot = cell.robot("r1").unwrap();
        let program = Program {
            files: vec![trackfix::rapid::parse_file(
                Path::new("m.mod"),
                src.as_bytes().to_vec(),
            )],
        };
        let setup = TrackSetup::new(robot, &dev);
        let result = apply(
            &program,
            track_correction(&program, &setup, Direction::Correct),
        )
        .unwrap();
        let out = String::from_utf8(result.files[0].output.clone()).unwrap();
        let p10 = out
            .lines()
            .find(|l| l.contains("p10:="))
            .unwrap()
            .to_owned();
        let refused: Vec<_> = result
            .refusals()
            .map(|r| (r.kind, r.message.clone()))
            .collect();
        let readings: Vec<String> = frame_readings(&program, &[robot])
            .into_iter()
            .map(|(_, d)| d.message)
            .collect();
        (p10, refused, readings)
    };
    let turned = module("[[200,0,0],[0.996195,0,0,0.087156]]");
    let (declared, refused, readings) = correct(&turned, &cell(""));
    assert!(
        refused.is_empty() && readings.is_empty(),
        "{refused:?} {readings:?}"
    );
    let (with_entry, refused, readings) = correct(&turned, &cell(user_frame));
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(with_entry, declared);
    assert_eq!(
        readings,
        [
            "work object `wobj_car`: the cell file's entry for robot `r1` is its user frame, and this declaration's object frame (oframe { x = 200, y = 0, z = 0, rx = 0, ry = 0, rz = 10 }) is kept: the targets are transformed in the cell's uframe · this oframe"
        ]
    );
    // The object frame matters here: without it the target is corrected otherwise.
    let (plain, _, readings) = correct(&module("[[0,0,0],[1,0,0,0]]"), &cell(user_frame));
    assert_ne!(plain, declared);
    assert!(readings.is_empty(), "{readings:?}");
    let (_, refused, _) = correct(&module("[[200,0,0],[q1,0,0,0.087156]]"), &cell(user_frame));
    assert_eq!(
        refused,
        [(
            RefusalKind::UnresolvedWorkObject,
            "robtarget `p10`: work object `wobj_car` has an object frame (oframe) with fields that are not numbers: the cell file's entry gives its user frame only".to_owned()
        )]
    );
}

/// A work object the cell file gives (`wobj_car` in samples/cell.toml) that the program gives
/// another value before it moves: the robot moves in the program's value, not in the one the
/// cell's entry stands for, so its targets are refused (before, they were corrected in the
/// cell's frame while a warning said trackfix used the program's).
#[test]
fn a_cell_work_object_the_program_gives_another_value_is_refused() {
    let (dir, path) = scratch_with(
        "m.mod",
        "MODULE M\n  PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[1670.3,-1850.75,612.4],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n  \
         CONST robtarget p10:=[[100,200,300],[0,1,0,0],[-1,-1,-2,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  \
         PROC main()\n    wobj_car := [FALSE,TRUE,\"\",[[1800,-1900,700],[0.996195,0,0,0.087156]],[[0,0,0],[1,0,0,0]]];\n    \
         MoveL p10,v100,fine,tool0\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n",
    );
    let out = dir.path().join("out");
    let err = refusal_output(&[
        "correct",
        path.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(
        err.contains("`p10`") && err.contains("`wobj_car` is given another value by the program"),
        "{err}"
    );
    assert!(err.contains("[runtime-data]"), "{err}");
}

/// A tool the robot does not hold (`tooldata` robhold FALSE) makes a stationary-tool target as
/// much as a work object it holds: refused as `stationary-tool` by `correct` and `mirror`,
/// with or without the robot's kinematics. Before, the cell without kinematics corrected `pB`
/// as a point of a tool on the flange (exit 0) and the one with them refused it as `reach`.
#[test]
fn a_tool_the_robot_does_not_hold_is_a_stationary_tool_with_or_without_an_arm() {
    let module = |wobj_robhold: &str| {
        format!(
            "MODULE StatTool\n  PERS tooldata tStat:=[FALSE,[[1800,900,1100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n  \
             PERS wobjdata wOdd:=[{wobj_robhold},TRUE,\"\",[[1500,-1500,600],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n  \
             CONST robtarget pB:=[[0,60,0],[1,0,0,0],[0,0,0,0],[1650,9E9,9E9,9E9,9E9,9E9]];\n  \
             PROC main()\n    MoveL pB, v100, fine, tStat\\WObj:=wOdd;\n  ENDPROC\nENDMODULE\n"
        )
    };
    // The work object says nothing (FALSE), or says so too (TRUE, as RAPID pairs them).
    for (wobj_robhold, said) in [
        (
            "FALSE",
            "is moved to with tool `tStat`, which the robot does not hold (robhold FALSE: stationary tool)",
        ),
        ("TRUE", "is a stationary-tool point (robhold TRUE)"),
    ] {
        let (dir, path) = scratch_with("stat.mod", &module(wobj_robhold));
        let out = dir.path().join("out.mod");
        for cell in ["samples/cell.toml", "samples/cell_rules.toml"] {
            let base = ["--cell", cell, "-o", out.to_str().unwrap()];
            let robot = ["--robot", "r1"];
            for command in [&["correct"][..], &["mirror"]] {
                let args = [
                    command,
                    &[path.to_str().unwrap()][..],
                    &base[..],
                    &robot[..],
                ]
                .concat();
                let err = refusal_output(&args);
                assert!(
                    err.contains("`pB` ") && err.contains(said),
                    "{args:?}: {err}"
                );
                assert!(
                    err.contains("[stationary-tool]") && !err.contains("[reach]"),
                    "{args:?}: {err}"
                );
                assert!(!out.exists());
                let kept = [&args[..], &["--keep", "stationary-tool"]].concat();
                let (code, _, err) = trackfix(&kept);
                assert_eq!(code, 4, "{kept:?}: {err}");
                let written = std::fs::read_to_string(&out).unwrap();
                assert!(
                    written.contains("pB:=[[0,60,0],[1,0,0,0],[0,0,0,0],[1650,"),
                    "{written}"
                );
                std::fs::remove_file(&out).unwrap();
            }
        }
    }
}
