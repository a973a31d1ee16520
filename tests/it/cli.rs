//! The command line as a user meets it: help, exit codes, input errors, `inspect`/`check` over
//! the samples.

use std::process::{Command, Output};

/// Runs the built `trackfix` binary from the package root.
pub fn trackfix(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trackfix"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the trackfix binary runs")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

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
