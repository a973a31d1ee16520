//! The command line as a user meets it: help, exit codes, input errors, `inspect`/`check` over
//! the samples.

use std::process::Command;

use crate::support::{run as trackfix, stderr, stdout};

#[test]
fn help_lists_every_command_with_examples() {
    let o = trackfix(&["--help"]);
    assert!(o.status.success());
    let text = stdout(&o);
    for cmd in [
        "inspect", "check", "track", "correct", "zero", "mirror", "transfer",
    ] {
        assert!(text.contains(cmd), "--help lacks {cmd}:\n{text}");
    }
    assert!(text.contains("Exit codes: 0 ok, 1 findings"), "{text}");
}

#[test]
fn missing_file_is_an_input_error_and_the_batch_goes_on() {
    let o = trackfix(&["check", "tests/no/such/file.mod", "tests/no/such/other.src"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("tests/no/such/file.mod"), "{err}");
    assert!(err.contains("tests/no/such/other.src"), "{err}");
}

#[test]
fn unknown_extension_says_what_is_expected() {
    let o = trackfix(&["inspect", "Cargo.toml"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("unknown file type"), "{err}");
    assert!(err.contains(".mod"), "{err}");
}

#[test]
fn bad_axis_name_is_a_usage_error() {
    let o = trackfix(&["inspect", "--skid", "E9", "x.mod"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("use eax_a..eax_f or E1..E6"));
}

#[test]
fn binary_and_xml_program_files_are_skipped_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let enc = dir.path().join("Encrypted.mod");
    std::fs::write(&enc, b"\x00\x17\x9a\x01binary").unwrap();
    let pgf = dir.path().join("T_ROB1.pgf");
    std::fs::write(&pgf, b"<?xml version=\"1.0\"?><Program></Program>").unwrap();
    let o = trackfix(&["check", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("not a text module"), "{err}");
    assert!(err.contains("RobotStudio program file"), "{err}");
    assert!(stdout(&o).contains("2 skipped"), "{}", stdout(&o));
}

/// A `.pgf` that holds RAPID text (not RobotStudio's XML) is read as a module.
#[test]
fn a_pgf_holding_rapid_text_is_a_module() {
    let dir = tempfile::tempdir().unwrap();
    let pgf = dir.path().join("T_ROB1.pgf");
    std::fs::write(
        &pgf,
        "MODULE m\n  CONST robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
    )
    .unwrap();
    let o = trackfix(&["inspect", pgf.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stdout(&o).ends_with("1 files, 1 positions\n"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn man_page_and_completions_come_from_the_same_definitions() {
    let man = trackfix(&["man"]);
    assert!(man.status.success());
    let page = stdout(&man);
    assert!(page.starts_with(".ie"), "roff expected:\n{page}");
    assert!(page.contains("transfer"), "{page}");
    let bash = trackfix(&["completions", "bash"]);
    assert!(bash.status.success());
    assert!(stdout(&bash).contains("trackfix__subcmd__transfer"));
}

/// Every program in `samples/`: RAPID modules, and KRL programs named once (the `.src` of a pair).
fn sample_programs() -> Vec<String> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = trackfix::program::collect_inputs(&[root.join("samples")]).expect("samples listed");
    let mut out: Vec<String> = files
        .iter()
        .filter(|p| !p.ends_with("$config.dat"))
        .map(|p| {
            p.strip_prefix(root)
                .unwrap_or(p)
                .to_string_lossy()
                .replace('\\', "/")
        })
        .collect();
    out.sort();
    out
}

#[test]
fn inspect_json_snapshot_per_sample() {
    let programs = sample_programs();
    assert!(
        programs.len() >= 20,
        "expected the RAPID and KRL samples, found {programs:?}"
    );
    for program in &programs {
        let o = trackfix(&["inspect", "--format", "json", program]);
        assert_eq!(o.status.code(), Some(0), "{program}: {}", stderr(&o));
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
        // The stable shape: every position has every documented key.
        for file in json["files"].as_array().expect("files") {
            for p in file["positions"].as_array().expect("positions") {
                for key in [
                    "name", "kind", "line", "x", "y", "z", "q", "rx", "ry", "rz", "config", "skid",
                    "extax", "tool",
                ] {
                    assert!(p.get(key).is_some(), "{program}: position lacks {key}: {p}");
                }
                let frame_key = if file["language"] == "krl" {
                    "base"
                } else {
                    "wobj"
                };
                assert!(p.get(frame_key).is_some(), "{program}: lacks {frame_key}");
            }
        }
        let name = format!("inspect_{}", program.replace(['/', '.', '$'], "_"));
        insta::assert_snapshot!(name, stdout(&o));
    }
}

/// `inspect --format json` writes its document as it builds it ([`InspectJson`]): the bytes are
/// those of the whole report serialised at once, for every sample and for the backups' programs
/// of several files (the `programs` list).
///
/// [`InspectJson`]: trackfix::report::InspectJson
#[test]
fn streamed_inspect_json_equals_the_whole_report() {
    use trackfix::program::{LoadOptions, collect_programs, load_group};
    use trackfix::report::{InspectJson, InspectReport, ProgramReport, inspect_program};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut batches: Vec<Vec<std::path::PathBuf>> = sample_programs()
        .iter()
        .map(|p| vec![root.join(p)])
        .collect();
    batches.push(vec![root.join("samples/robotstudio_backup")]);
    batches.push(vec![root.join("samples/kss_backup")]);
    batches.push(vec![root.join("samples")]);
    let dir = tempfile::tempdir().unwrap();
    let stamped = dir.path().join("stamped.mod");
    std::fs::write(
        &stamped,
        "MODULE m\r\n! trackfix: correct robot=r1 profile=\"r1 track\" sha256=0123456789ab version=9.9.9\r\n  CONST robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\r\nENDMODULE\r\n",
    )
    .unwrap();
    batches.push(vec![stamped]);
    let mut grouped_seen = 0;
    let mut stamps_seen = 0;
    for inputs in &batches {
        let mut programs = Vec::new();
        let mut grouped = Vec::new();
        for group in collect_programs(inputs).expect("inputs listed") {
            for p in load_group(&group, &LoadOptions::default())
                .into_iter()
                .flatten()
            {
                programs.push(p);
                grouped.push(group.len() > 1);
            }
        }
        let options = Default::default();
        let whole = InspectReport {
            files: programs
                .iter()
                .flat_map(|p| inspect_program(p, options))
                .collect(),
            programs: programs
                .iter()
                .zip(&grouped)
                .filter(|(_, g)| **g)
                .filter_map(|(p, _)| ProgramReport::of(p))
                .collect(),
        };
        grouped_seen += whole.programs.len();
        stamps_seen += whole.files.iter().filter(|f| f.stamp.is_some()).count();
        let streamed = InspectJson {
            programs: &programs,
            grouped: &grouped,
            options,
        };
        assert_eq!(
            serde_json::to_string_pretty(&streamed).unwrap(),
            serde_json::to_string_pretty(&whole).unwrap(),
            "{inputs:?}"
        );
    }
    assert!(
        grouped_seen >= 2,
        "the backups form programs of several files"
    );
    assert_eq!(stamps_seen, 1, "the stamped module's stamp is reported");
}

#[test]
fn inspect_krl_with_config_dat_resolves_bases() {
    let o = trackfix(&[
        "inspect",
        "--format",
        "json",
        "--config-dat",
        "samples/krl/$config.dat",
        "samples/krl/spot_line.dat",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("valid JSON");
    let files = json["files"].as_array().expect("files");
    // Naming the .dat reads the pair (the .src first) and the $config.dat.
    assert_eq!(files[0]["path"], "samples/krl/spot_line.src");
    assert_eq!(files[1]["path"], "samples/krl/spot_line.dat");
    let frames: Vec<&str> = files
        .iter()
        .flat_map(|f| f["frames"].as_array().into_iter().flatten())
        .filter_map(|f| f["name"].as_str())
        .collect();
    assert!(frames.contains(&"BASE_DATA[1]"), "{frames:?}");
    assert!(frames.contains(&"TOOL_DATA[1]"), "{frames:?}");
    let points = files[1]["positions"].as_array().expect("positions");
    assert!(points.len() >= 150, "{}", points.len());
    // Every spot point is welded on the car (BASE_DATA[1]); only the home point is in $WORLD.
    let on_car = points
        .iter()
        .filter(|p| p["base"] == "BASE_DATA[1]")
        .count();
    let in_world: Vec<&str> = points
        .iter()
        .filter(|p| p["base"] == "$WORLD")
        .filter_map(|p| p["name"].as_str())
        .collect();
    assert_eq!(on_car + in_world.len(), points.len());
    assert_eq!(in_world, ["XP0"]);
    let skids: Vec<f64> = points.iter().filter_map(|p| p["skid"].as_f64()).collect();
    assert!(skids.iter().all(|s| (0.0..=8000.0).contains(s)));
}

#[test]
fn check_over_all_samples_round_trips_and_reports_the_deliberate_findings() {
    let o = trackfix(&["check", "samples"]);
    let out = stdout(&o);
    // Findings are the samples that exercise warnings on purpose (two work objects, a
    // reassigned RoboDK frame, a composed KRL frame, an unresolved base).
    assert_eq!(o.status.code(), Some(1), "{out}");
    let summary = out.lines().last().unwrap_or_default();
    let files: usize = summary
        .strip_prefix("checked ")
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("summary line");
    assert!(
        summary.contains(&format!("{files} round-trip byte for byte")),
        "{summary}"
    );
    insta::assert_snapshot!(out);
}

#[test]
fn table_and_csv_list_the_same_positions() {
    let table = stdout(&trackfix(&["inspect", "samples/rapid/spot_line.mod"]));
    let csv = stdout(&trackfix(&[
        "inspect",
        "--format",
        "csv",
        "samples/rapid/spot_line.mod",
    ]));
    let rows = csv.lines().count() - 1;
    assert!(rows > 200, "{rows}");
    assert!(
        table.contains(&format!("1 files, {rows} positions")),
        "{table}"
    );
    assert!(
        csv.starts_with(
            "file,language,name,kind,line,x,y,z,q1,q2,q3,q4,rx,ry,rz,skid,frame,tool\n"
        )
    );
    assert!(
        csv.contains("samples/rapid/spot_line.mod,rapid,Sp001,robtarget,"),
        "{csv}"
    );
}

#[test]
fn a_closed_pipe_is_not_an_error() {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_trackfix"))
        // Small enough to fit a pipe's buffer, so the first write succeeds and a later one meets
        // the closed pipe.
        .args(["inspect", "samples/rapid/bom.mod"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    // Read one byte, then close the pipe, as `trackfix inspect … | head -c1` does.
    let mut stdout = child.stdout.take().expect("stdout");
    let mut one = [0u8; 1];
    stdout.read_exact(&mut one).expect("some output");
    drop(stdout);
    let out = child.wait_with_output().expect("exits");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.code(), Some(0), "{err}");
}

/// Controllers write unused slots of `PERS robtarget` arrays as all zeros: `check` does not call
/// that a defect, and the transforms leave the slot as written with a note naming it: it is not
/// a target, so never a refusal (nothing to keep).
#[test]
fn an_all_zero_quaternion_is_an_unset_slot() {
    let dir = tempfile::tempdir().unwrap();
    let module = dir.path().join("slots.mod");
    std::fs::write(
        &module,
        "MODULE slots\n  PERS robtarget s{2}:=[[[0,0,0],[0,0,0,0],[0,0,0,0],[0,9E9,9E9,9E9,9E9,9E9]],\
         [[10,0,0],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]]];\n  PROC main()\n    \
         MoveL s{1}, v100, fine, tool0;\n    MoveL s{2}, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
    )
    .unwrap();
    let path = module.to_str().unwrap();
    let check = trackfix(&["check", path]);
    assert_eq!(check.status.code(), Some(0), "{}", stdout(&check));
    let correct = trackfix(&[
        "correct",
        path,
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--diff",
    ]);
    let err = stderr(&correct);
    assert_eq!(correct.status.code(), Some(0), "{err}");
    assert!(
        err.contains(": note: robtarget `s{1}` has the quaternion [0,0,0,0]: an unset slot"),
        "{err}"
    );
    assert!(!err.contains("refused"), "{err}");
    assert!(
        !err.contains("s{2}`"),
        "only the unset slot is noted: {err}"
    );
    // The slot stays as written, the set one is corrected.
    let out = stdout(&correct);
    assert!(
        out.contains("-    PERS") || out.contains("-  PERS"),
        "{out}"
    );
    assert!(out.contains("[[[0,0,0],[0,0,0,0]"), "{out}");
}

/// `inspect --format csv` guards cells a spreadsheet would run as formulas; a negative number
/// stays a number.
#[test]
fn csv_cells_that_start_like_formulas_are_guarded() {
    let dir = tempfile::tempdir().unwrap();
    let module = dir.path().join("=HYPERLINK(1).mod");
    std::fs::write(
        &module,
        "MODULE m\n  CONST robtarget p1:=[[-100,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
    )
    .unwrap();
    // Named relative to its folder, so the file cell starts with `=`.
    let o = Command::new(env!("CARGO_BIN_EXE_trackfix"))
        .args(["inspect", "--format", "csv", "=HYPERLINK(1).mod"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let csv = stdout(&o);
    let row = csv.lines().nth(1).unwrap();
    assert!(row.starts_with("'=HYPERLINK(1).mod,"), "{row}");
    assert!(row.contains(",-100,"), "{row}");
}

/// KRL tables show A, B, C as written and Status/Turn.
#[test]
fn krl_inspect_table_labels_a_b_c_and_shows_status_turn() {
    let o = trackfix(&["inspect", "samples/krl/spot_line.src"]);
    let text = stdout(&o);
    let header = text.lines().find(|l| l.contains("name ")).unwrap();
    assert!(
        header.contains(" A ") && header.contains(" B ") && header.contains(" C "),
        "{header}"
    );
    assert!(header.ends_with("S/T"), "{header}");
    let xp0 = text
        .lines()
        .find(|l| l.trim_start().starts_with("XP0 "))
        .unwrap();
    // DECL E6POS XP0={X 1480.0,Y -2400.0,Z 1650.0,A -200.2528,B 41.2947,C 168.1590,S 2,T 10,…}
    assert!(
        xp0.contains("-200.2528") && xp0.contains("41.2947") && xp0.contains("168.1590"),
        "{xp0}"
    );
    assert!(xp0.ends_with(" 2/10"), "{xp0}");
    let o = trackfix(&["inspect", "samples/rapid/spot_line.mod"]);
    let header = stdout(&o)
        .lines()
        .find(|l| l.contains("name "))
        .unwrap()
        .to_owned();
    assert!(
        header.contains(" rx ") && !header.contains("S/T"),
        "{header}"
    );
}

/// `check` of an empty directory or of a binary file named on the command line is an input
/// error (exit 2), not "0 findings"; an empty module is reported.
#[test]
fn check_of_nothing_or_of_a_named_binary_file_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let empty_dir = dir.path().join("empty");
    std::fs::create_dir(&empty_dir).unwrap();
    let o = trackfix(&["check", empty_dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("no RAPID or KRL program in"),
        "{}",
        stderr(&o)
    );
    let bin = dir.path().join("Encrypted.mod");
    std::fs::write(&bin, b"\x00\x17\x9a\x01binary").unwrap();
    let o = trackfix(&["check", bin.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a text module"), "{}", stderr(&o));
    let empty = dir.path().join("Empty.mod");
    std::fs::write(&empty, b"").unwrap();
    let o = trackfix(&["check", empty.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains("the file is empty"), "{}", stdout(&o));
}

/// A man page for every subcommand: `trackfix man correct` prints one, `--out-dir` writes all.
#[test]
fn man_pages_for_every_subcommand() {
    let o = trackfix(&["man", "correct"]);
    assert_eq!(o.status.code(), Some(0));
    let page = stdout(&o);
    assert!(page.contains(".TH trackfix-correct 1"), "{}", &page[..200]);
    assert!(page.contains("keep"), "the page lists the options");
    let o = trackfix(&["man", "track", "fit"]);
    assert!(stdout(&o).contains("trackfix\\-track\\-fit"));
    let o = trackfix(&["man", "nope"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("pages: inspect, check"),
        "{}",
        stderr(&o)
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man");
    let o = trackfix(&["man", "--out-dir", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for name in [
        "trackfix",
        "trackfix-inspect",
        "trackfix-check",
        "trackfix-correct",
        "trackfix-zero",
        "trackfix-mirror",
        "trackfix-transfer",
        "trackfix-reach",
        "trackfix-track",
        "trackfix-track-identify",
        "trackfix-track-fit",
        "trackfix-track-show",
        "trackfix-track-spectrum",
        "trackfix-accuracy-pose",
        "trackfix-accuracy-path",
    ] {
        let page = std::fs::read_to_string(out.join(format!("{name}.1"))).unwrap();
        assert!(page.contains(&format!(".TH {name} 1")), "{name}");
    }
}

/// `check` prints findings as the transforms print refusals: three of a kind over the whole
/// batch, then a count naming the kind (`-v`: every one); `-q` prints errors only and keeps the
/// exit code of every finding; `-q -v` is a usage error.
#[test]
fn check_groups_repeated_findings_and_takes_quiet_and_verbose() {
    let dir = tempfile::tempdir().unwrap();
    let target = |name: &str| {
        format!(
            "  CONST robtarget {name} := [[1,2,3],[1,0.05,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        )
    };
    // Three off-norm quaternions in each of two modules, and a syntax error in the second.
    let a = format!(
        "MODULE A\n{}{}{}ENDMODULE\n",
        target("pA1"),
        target("pA2"),
        target("pA3")
    );
    let b = format!(
        "MODULE B\n{}{}{}  CONST num n := ;\nENDMODULE\n",
        target("pB1"),
        target("pB2"),
        target("pB3")
    );
    std::fs::write(dir.path().join("a.mod"), a).unwrap();
    std::fs::write(dir.path().join("b.mod"), b).unwrap();
    let d = dir.path().to_str().unwrap();
    let off_norm = |out: &str| {
        out.lines()
            .filter(|l| l.contains("warning: quaternion of `p"))
            .count()
    };
    let count_line = "warning: … and 3 more like this [quaternion of `…` is not normalised (|q| = …)] (-v shows all)";

    let o = trackfix(&["check", d]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert_eq!(off_norm(&out), 3, "{out}");
    assert!(out.lines().any(|l| l == count_line), "{out}");
    assert!(out.contains("b.mod:5:"), "{out}");
    assert!(out.contains(": error: "), "{out}");
    assert!(
        out.lines().last().unwrap().starts_with("checked 2 files:")
            && out.contains("7 findings in 2 files"),
        "{out}"
    );

    let o = trackfix(&["check", "-v", d]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert_eq!(off_norm(&out), 6, "{out}");
    assert!(!out.contains("more like this"), "{out}");

    let o = trackfix(&["check", "--quiet", d]);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(!out.contains("warning"), "{out}");
    assert!(!out.contains("checked 2 files"), "{out}");
    assert_eq!(
        out.lines().filter(|l| l.contains(": error: ")).count(),
        1,
        "{out}"
    );

    let o = trackfix(&["check", "-q", "-v", d]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// The help of every transform and of `check`/`reach`, as the user reads it: the refusal kinds
/// `--keep` takes, the formulas and the exit codes are reviewed in the snapshot when they change.
#[test]
fn help_of_the_transforms_and_checks() {
    for cmd in ["correct", "zero", "mirror", "transfer", "check", "reach"] {
        // Help wraps at the terminal's width (COLUMNS when no terminal): fixed here.
        let o = Command::new(env!("CARGO_BIN_EXE_trackfix"))
            .args([cmd, "--help"])
            .env("COLUMNS", "100")
            .output()
            .unwrap();
        assert!(o.status.success(), "{cmd}");
        insta::assert_snapshot!(format!("help_{cmd}"), stdout(&o));
    }
}
