//! Where results go and how safely: numbered backups, the mirrored `--out-dir` tree, symlinks
//! and modes, `-o -`, refusals of destinations in the way, full or closed stdout/stderr,
//! inputs that are no regular files, and temporary files after a kill.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::support::{root, trackfix};

const CELL: &str = "samples/cell_rules.toml";

/// A sample copied into a fresh folder, and the folder.
fn copy_sample(sample: &str, name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::copy(root().join(sample), &path).unwrap();
    (dir, path)
}

fn correct(extra: &[&str]) -> (i32, String, String) {
    trackfix(
        &[
            &[
                "correct",
                "--cell",
                CELL,
                "--robot",
                "r1",
                "--skip-unsupported",
            ],
            extra,
        ]
        .concat(),
    )
}

/// Names in `dir` (recursively), relative, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = walkdir::WalkDir::new(dir)
        .min_depth(1)
        .into_iter()
        .map(|e| {
            e.unwrap()
                .path()
                .strip_prefix(dir)
                .unwrap()
                .display()
                .to_string()
        })
        .collect();
    v.sort();
    v
}

#[test]
fn in_place_twice_keeps_the_first_backup_and_numbers_the_next() {
    let (dir, input) = copy_sample("samples/rapid/spot_line.mod", "spot_line.mod");
    let original = std::fs::read(&input).unwrap();
    let inp = input.to_str().unwrap();
    let (code, _, err) = correct(&[inp, "--in-place"]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    assert!(err.contains(", backup "), "{err}");
    let once = std::fs::read(&input).unwrap();
    // The file now carries correct's stamp: correcting it again needs --force.
    let (code, _, err) = correct(&[inp, "--in-place", "--force"]);
    assert_eq!(code, 4, "{err}");
    // The summary names the new backup; the first one still holds the untouched original.
    assert!(err.contains("spot_line.mod.orig.1"), "{err}");
    assert_eq!(
        std::fs::read(dir.path().join("spot_line.mod.orig")).unwrap(),
        original
    );
    assert_eq!(
        std::fs::read(dir.path().join("spot_line.mod.orig.1")).unwrap(),
        once
    );
    assert_eq!(
        listing(dir.path()),
        [
            "spot_line.mod",
            "spot_line.mod.orig",
            "spot_line.mod.orig.1"
        ]
    );
}

#[test]
fn out_dir_mirrors_the_input_tree_and_lists_every_file_written() {
    let dir = tempfile::tempdir().unwrap();
    let backup = dir.path().join("backup");
    for task in ["TASK1", "TASK2"] {
        let d = backup.join(task).join("PROGMOD");
        std::fs::create_dir_all(&d).unwrap();
        std::fs::copy(
            root().join("samples/rapid/spot_line.mod"),
            d.join("MainModule.mod"),
        )
        .unwrap();
    }
    let out = dir.path().join("out");
    let (code, _, err) = correct(&[backup.to_str().unwrap(), "--out-dir", out.to_str().unwrap()]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    assert_eq!(
        listing(&out),
        [
            "TASK1",
            "TASK1/PROGMOD",
            "TASK1/PROGMOD/MainModule.mod",
            "TASK2",
            "TASK2/PROGMOD",
            "TASK2/PROGMOD/MainModule.mod"
        ]
    );
    for task in ["TASK1", "TASK2"] {
        let written = out.join(task).join("PROGMOD/MainModule.mod");
        assert!(err.contains(&format!("→ {}", written.display())), "{err}");
    }
}

#[test]
fn a_directory_in_the_way_is_refused_and_nothing_is_left() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("spot_line.dat")).unwrap();
    let (code, _, err) = correct(&[
        "samples/krl/spot_line.src",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("spot_line.dat: cannot write there: it is a directory"),
        "{err}"
    );
    assert_eq!(listing(&out), ["spot_line.dat"]);
}

#[test]
fn dash_o_dash_writes_the_program_to_standard_output() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("c.mod");
    let (code, _, err) = correct(&["samples/rapid/spot_line.mod", "-o", file.to_str().unwrap()]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    let o = Command::new(env!("CARGO_BIN_EXE_trackfix"))
        .args([
            "correct",
            "samples/rapid/spot_line.mod",
            "--cell",
            CELL,
            "--robot",
            "r1",
        ])
        .args(["--skip-unsupported", "-o", "-"])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(4)); // written, jHome kept as written
    assert_eq!(o.stdout, std::fs::read(&file).unwrap());
    assert!(!root().join("-").exists());
}

#[test]
fn config_dat_alone_says_why_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("X");
    let (code, _, err) = correct(&[
        "samples/krl/$config.dat",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("nothing written") && err.contains("$config.dat"),
        "{err}"
    );
    assert!(!out.exists());
}

#[cfg(unix)]
#[test]
fn in_place_on_a_symlink_replaces_its_target_and_keeps_the_mode() {
    use std::os::unix::fs::PermissionsExt as _;
    let (dir, real) = copy_sample("samples/rapid/spot_line.mod", "real.mod");
    std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
    let links = dir.path().join("links");
    std::fs::create_dir(&links).unwrap();
    let link = links.join("spot_line.mod");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let original = std::fs::read(&real).unwrap();
    let (code, _, err) = correct(&[link.to_str().unwrap(), "--in-place"]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_ne!(std::fs::read(&real).unwrap(), original);
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&real), 0o640);
    let backup = links.join("spot_line.mod.orig");
    assert_eq!(std::fs::read(&backup).unwrap(), original);
    assert_eq!(mode(&backup), 0o640);
    // -o onto a symlink likewise writes its target.
    let out_real = dir.path().join("out_real.mod");
    std::fs::write(&out_real, "old").unwrap();
    std::fs::set_permissions(&out_real, std::fs::Permissions::from_mode(0o600)).unwrap();
    let out_link = dir.path().join("out.mod");
    std::os::unix::fs::symlink(&out_real, &out_link).unwrap();
    let (code, _, err) = correct(&[
        "samples/rapid/spot_line.mod",
        "-o",
        out_link.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{err}"); // written, jHome kept as written
    assert!(
        std::fs::symlink_metadata(&out_link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(mode(&out_real), 0o600);
    assert!(std::fs::read(&out_real).unwrap().starts_with(b"%%%"));
}

fn spawn(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trackfix"));
    c.args(args).current_dir(root());
    c
}

#[cfg(unix)]
#[test]
fn a_full_stderr_or_stdout_is_an_exit_code_not_a_panic() {
    let full = || {
        Stdio::from(
            std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap(),
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.mod");
    let status = spawn(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        CELL,
        "--robot",
        "r1",
    ])
    .args(["--skip-unsupported", "-o", out.to_str().unwrap()])
    .stderr(full())
    .status()
    .unwrap();
    // The warnings cannot be shown: the run stops before writing, with an error code.
    assert_eq!(status.code(), Some(2));
    let status = spawn(&["completions", "bash"])
        .stdout(full())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert_eq!(status.code(), Some(2));
    let status = spawn(&["man"])
        .stdout(full())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert_eq!(status.code(), Some(2));
    // A closed pipe is no error.
    let mut child = spawn(&["completions", "zsh"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    assert_eq!(child.wait().unwrap().code(), Some(0));
    assert!(!out.exists());
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_instead_of_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.mod");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let mut child = spawn(&["check", fifo.to_str().unwrap()])
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed().as_secs() > 30 {
            child.kill().unwrap();
            panic!("check of a FIFO blocks");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(2), "{err}");
    assert!(err.contains("not a regular file (a FIFO)"), "{err}");
}

/// A large module: the sample with 300,000 comment lines (about 20 MB).
fn large_module(dir: &Path) -> PathBuf {
    let src = std::fs::read(root().join("samples/rapid/spot_line.mod")).unwrap();
    let at = src
        .windows(15)
        .position(|w| w == b"MODULE SpotLine")
        .unwrap();
    let at = at + src[at..].iter().position(|&b| b == b'\n').unwrap() + 1;
    let mut big = src[..at].to_vec();
    for k in 0..300_000 {
        big.extend_from_slice(
            format!("  ! filler line {k:08} of a large generated module\n").as_bytes(),
        );
    }
    big.extend_from_slice(&src[at..]);
    let path = dir.join("big.mod");
    std::fs::write(&path, big).unwrap();
    path
}

/// trackfix's temporaries and locks in `dir`.
fn temps(dir: &Path) -> Vec<String> {
    listing(dir)
        .into_iter()
        .filter(|n| n.contains(".trackfix-"))
        .collect()
}

/// A temporary (created after the run's lock holds its process id).
fn has_temporary(dir: &Path) -> bool {
    listing(dir).iter().any(|n| n.contains(".trackfix-tmp-"))
}

#[cfg(target_os = "linux")]
#[test]
fn a_kill_during_a_long_write_leaves_no_partial_output_and_the_next_run_cleans_up() {
    let dir = tempfile::tempdir().unwrap();
    let input = large_module(dir.path());
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("big.mod");
    let args = |out: &Path| {
        vec![
            "correct".to_owned(),
            input.display().to_string(),
            "--cell".into(),
            CELL.into(),
            "--robot".into(),
            "r1".into(),
            "--skip-unsupported".into(),
            "-o".into(),
            out.display().to_string(),
        ]
    };
    // Kill as soon as the temporary file appears: during its write or sync. On a loaded
    // machine the poll may miss the short window; a missed run is repeated (a few times).
    let mut killed_with_temp = false;
    for _ in 0..5 {
        let _ = std::fs::remove_file(&out);
        let mut child = spawn(&[])
            .args(args(&out))
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        killed_with_temp = loop {
            if has_temporary(&out_dir) {
                child.kill().unwrap();
                child.wait().unwrap();
                break true;
            }
            if child.try_wait().unwrap().is_some() {
                break false;
            }
        };
        if killed_with_temp {
            break;
        }
    }
    assert!(
        killed_with_temp,
        "the run ended before its temporary file was seen"
    );
    // No partial output under the real name: the output is only ever renamed into place whole.
    // (Should the kill land just after the rename, the output is there and whole.)
    if out.exists() {
        let bytes = std::fs::read(&out).unwrap();
        let src = std::fs::read(&input).unwrap();
        assert!(bytes.len() > src.len() * 9 / 10 && bytes.ends_with(&src[src.len() - 12..]));
    }
    let left = temps(&out_dir);
    // The next run writing into that folder removes the dead run's temporary.
    let other = out_dir.join("small.mod");
    let (code, _, err) = correct(&["samples/rapid/spot_line.mod", "-o", other.to_str().unwrap()]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    assert_eq!(
        temps(&out_dir),
        Vec::<String>::new(),
        "left by the kill: {left:?}"
    );
    assert_eq!(listing(&out_dir), ["small.mod"]);
}

#[test]
fn an_os_error_is_named_once() {
    let (code, _, err) = correct(&["no_such_file.mod", "-o", "never.mod"]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
}

#[test]
fn a_multi_file_in_place_run_that_fails_on_its_second_file_changes_neither() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.mod");
    let b = dir.path().join("b.mod");
    for f in [&a, &b] {
        std::fs::copy(root().join("samples/rapid/spot_line.mod"), f).unwrap();
    }
    // A directory where b's first backup would go is skipped, never written into.
    std::fs::create_dir(dir.path().join("b.mod.orig")).unwrap();
    // A live run holds b (process 1 always runs): the whole run must fail, a untouched.
    std::fs::write(dir.path().join(".b.mod.trackfix-lock"), "1").unwrap();
    let before = listing(dir.path());
    let original = std::fs::read(&a).unwrap();
    let (code, _, err) = correct(&[a.to_str().unwrap(), b.to_str().unwrap(), "--in-place"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("another trackfix run (process 1) is writing it"),
        "{err}"
    );
    assert_eq!(listing(dir.path()), before);
    assert_eq!(std::fs::read(&a).unwrap(), original);
    // Once the lock is gone, both are written and b's backup takes the next free name.
    std::fs::remove_file(dir.path().join(".b.mod.trackfix-lock")).unwrap();
    let (code, _, err) = correct(&[a.to_str().unwrap(), b.to_str().unwrap(), "--in-place"]);
    assert_eq!(code, 4, "{err}"); // 4: written, jHome kept as written
    assert_eq!(
        std::fs::read(dir.path().join("a.mod.orig")).unwrap(),
        original
    );
    assert_eq!(
        std::fs::read(dir.path().join("b.mod.orig.1")).unwrap(),
        original
    );
    assert!(dir.path().join("b.mod.orig").is_dir());
}

#[cfg(target_os = "linux")]
#[test]
fn two_concurrent_in_place_runs_on_one_file_do_not_both_apply() {
    let dir = tempfile::tempdir().unwrap();
    let input = large_module(dir.path());
    let original = std::fs::read(&input).unwrap();
    let run = || {
        spawn(&[
            "correct",
            input.to_str().unwrap(),
            "--cell",
            CELL,
            "--robot",
            "r1",
        ])
        .args(["--skip-unsupported", "--in-place"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
    };
    // Both read the file before either writes (reading and correcting 20 MB takes a while).
    let (first, second) = (run(), run());
    let outcomes: Vec<(i32, String)> = [first, second]
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            (
                o.status.code().unwrap_or(-1),
                String::from_utf8_lossy(&o.stderr).into_owned(),
            )
        })
        .collect();
    // 4: written, jHome kept as written.
    let ok = outcomes.iter().filter(|(c, _)| *c == 4).count();
    assert_eq!(ok, 1, "{outcomes:?}");
    let (_, refused) = outcomes.iter().find(|(c, _)| *c != 4).unwrap();
    assert!(
        refused.contains("changed since it was read") || refused.contains("another trackfix run"),
        "{refused}"
    );
    // One correction: one backup holding the original, nothing else left.
    assert_eq!(
        std::fs::read(dir.path().join("big.mod.orig")).unwrap(),
        original
    );
    assert_eq!(listing(dir.path()), ["big.mod", "big.mod.orig"]);
}

#[test]
fn a_failed_out_dir_run_leaves_no_folder_it_created() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in");
    std::fs::create_dir_all(input.join("sub")).unwrap();
    for f in ["sub/a.mod", "b.mod"] {
        std::fs::copy(root().join("samples/rapid/spot_line.mod"), input.join(f)).unwrap();
    }
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // `out/sub/` is created for a.mod before the lock on `out/b.mod` (held by a live run) fails.
    std::fs::write(out.join(".b.mod.trackfix-lock"), "1").unwrap();
    let (code, _, err) = correct(&[input.to_str().unwrap(), "--out-dir", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(listing(&out), [".b.mod.trackfix-lock"]);
}

/// Ctrl-C (SIGINT) or SIGTERM while a batch is written in place stops nothing half-way: the
/// signal waits until the transaction has committed or been undone. Sent as soon as the first
/// temporary or lock file appears, it leaves either every module as it was, with no backup, or
/// every module corrected with its backup, and no temporary or lock file either way.
#[cfg(target_os = "linux")]
#[test]
fn a_stop_signal_during_an_in_place_batch_leaves_all_or_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let batch = dir.path().join("batch");
    std::fs::create_dir(&batch).unwrap();
    let src = std::fs::read_to_string("samples/rapid/bom.mod").unwrap();
    const MODULES: usize = 400;
    for i in 0..MODULES {
        let text = src.replacen("MODULE WithBom", &format!("MODULE m{i}"), 1);
        std::fs::write(batch.join(format!("m{i}.mod")), text).unwrap();
    }
    let original = listing(&batch);
    let mut signalled = 0;
    for signal in ["-INT", "-TERM", "-INT", "-TERM"] {
        let mut child = spawn(&[])
            .args([
                "correct",
                batch.to_str().unwrap(),
                "--cell",
                CELL,
                "--robot",
                "r1",
                "--skip-unsupported",
                "--in-place",
                "--force",
            ])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let sent = loop {
            let writing = listing(&batch)
                .iter()
                .any(|n| n.contains(".trackfix-tmp-") || n.contains(".trackfix-lock"));
            if writing {
                let pid = child.id().to_string();
                let kill = Command::new("kill").args([signal, &pid]).status().unwrap();
                assert!(kill.success());
                break true;
            }
            if child.try_wait().unwrap().is_some() {
                break false;
            }
        };
        child.wait().unwrap();
        signalled += usize::from(sent);
        let names = listing(&batch);
        assert!(
            !names
                .iter()
                .any(|n| n.contains(".trackfix-tmp-") || n.contains(".trackfix-lock")),
            "{signal}: left {names:?}"
        );
        let backups = names.iter().filter(|n| n.contains(".orig")).count();
        assert!(
            backups == 0 || backups % MODULES == 0,
            "{signal}: {backups} backups of {MODULES} modules"
        );
        if backups == 0 {
            assert_eq!(names, original, "{signal}");
        }
    }
    assert!(signalled > 0, "no run was seen writing");
}

/// Applies a unified diff of one file to `old`, as `patch` does: the hunks' removed and context
/// lines must be `old`'s at the line numbers the hunk gives, each line split after `\n`.
fn apply_unified_diff(old: &[u8], diff: &[u8]) -> Vec<u8> {
    let old_lines: Vec<&[u8]> = old.split_inclusive(|&b| b == b'\n').collect();
    let diff_lines: Vec<&[u8]> = diff.split_inclusive(|&b| b == b'\n').collect();
    let mut out: Vec<u8> = Vec::new();
    let mut next = 0; // the next old line not yet copied
    let mut d = 2; // past `---` and `+++`
    while d < diff_lines.len() {
        let header = std::str::from_utf8(diff_lines[d]).unwrap();
        assert!(header.starts_with("@@ -"), "{header}");
        let start: usize = header[4..]
            .split([',', ' '])
            .next()
            .unwrap()
            .parse()
            .unwrap();
        // `-0,0`: insertion before the first line.
        let first = start.saturating_sub(1);
        let len_zero = header[4..].split(' ').next().unwrap().ends_with(",0");
        let first = if len_zero { start } else { first };
        while next < first {
            out.extend_from_slice(old_lines[next]);
            next += 1;
        }
        d += 1;
        let mut last: Option<(u8, usize)> = None; // the last line written: (tag, out length before it)
        while d < diff_lines.len() && !diff_lines[d].starts_with(b"@@") {
            let line = diff_lines[d];
            if line.starts_with(b"\\ No newline") {
                // The line before has no `\n` of its own.
                if let Some((tag, _)) = last
                    && tag != b'-'
                {
                    assert_eq!(out.pop(), Some(b'\n'));
                }
                d += 1;
                continue;
            }
            let (tag, body) = (line[0], &line[1..]);
            match tag {
                b' ' | b'-' => {
                    let expect = old_lines[next];
                    let body_trimmed = body.strip_suffix(b"\n").unwrap_or(body);
                    assert_eq!(
                        expect.strip_suffix(b"\n").unwrap_or(expect),
                        body_trimmed,
                        "context or removed line {} differs",
                        next + 1
                    );
                    if tag == b' ' {
                        out.extend_from_slice(body);
                    }
                    next += 1;
                }
                b'+' => out.extend_from_slice(body),
                _ => panic!("bad diff line {line:?}"),
            }
            last = Some((tag, out.len()));
            d += 1;
        }
    }
    while next < old_lines.len() {
        out.extend_from_slice(old_lines[next]);
        next += 1;
    }
    out
}

/// `--diff` writes the files' own bytes (a BOM, a Latin-1 comment, CRLF, a bare CR, no final
/// line end): applied as `patch` applies it, it gives the file `-o` writes, byte for byte.
#[test]
fn a_diff_applies_to_the_input_and_gives_the_output() {
    let body = "  ! Schwei\u{df}punkt\n  CONST robtarget p1:=[[300,-50,620],[0.5,0.5,0.5,0.5],[0,0,1,0],[6400,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL p1,v100,fine,tool0;\n  ENDPROC\n";
    let latin1 = |s: &str| s.chars().map(|c| c as u8).collect::<Vec<u8>>();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        (
            "latin1.mod",
            latin1(&format!("MODULE L1\n{body}ENDMODULE\n")),
        ),
        (
            "bom.mod",
            [
                &b"\xef\xbb\xbf"[..],
                format!("MODULE L2\n{body}ENDMODULE\n").as_bytes(),
            ]
            .concat(),
        ),
        (
            "crlf.mod",
            latin1(&format!("MODULE L3\n{body}ENDMODULE").replace('\n', "\r\n")),
        ),
        (
            "cr.mod",
            latin1(&format!("MODULE L4\n{body}ENDMODULE\n").replace('\n', "\r")),
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in cases {
        let input = dir.path().join(name);
        std::fs::write(&input, &bytes).unwrap();
        let out = dir.path().join(format!("out-{name}"));
        let base = [
            "correct",
            input.to_str().unwrap(),
            "--cell",
            CELL,
            "--robot",
            "r1",
            "--no-stamp",
        ];
        let (code, _, err) = trackfix(&[&base[..], &["-o", out.to_str().unwrap()]].concat());
        assert_eq!(code, 0, "{name}: {err}");
        let written = std::fs::read(&out).unwrap();
        assert_ne!(written, bytes, "{name}");
        let diff = crate::support::run(&[&base[..], &["--diff"]].concat()).stdout;
        assert_eq!(apply_unified_diff(&bytes, &diff), written, "{name}");
    }
}

/// A file whose name leaves no room for the lock and temporary beside it (a legal name of 246
/// bytes) is refused with what to do, nothing written, and no false word of a failed undo: a
/// lock never created is nothing to remove.
#[cfg(unix)]
#[test]
fn a_name_too_long_for_the_lock_is_refused_with_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let name = format!("{}.mod", "a".repeat(242));
    let path = dir.path().join(&name);
    std::fs::copy("samples/rapid/bom.mod", &path).unwrap();
    let before = listing(dir.path());
    let (code, _, err) = correct(&[path.to_str().unwrap(), "--in-place"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("shorten the name; nothing written"), "{err}");
    assert!(!err.contains("undoing the run failed"), "{err}");
    assert_eq!(listing(dir.path()), before);
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read("samples/rapid/bom.mod").unwrap()
    );
}

/// `--no-backup` is for `--in-place`: with `-o` or `--out-dir` it is a usage error (exit 2,
/// nothing written), not silently ignored; `-q` keeps a skipped file's note to itself.
#[test]
fn no_backup_outside_in_place_is_refused_and_quiet_is_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (code, _, err) = correct(&[
        "samples/rapid/bom.mod",
        "--no-backup",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--no-backup is for --in-place"), "{err}");
    assert!(!out.exists());
    let batch = dir.path().join("batch");
    std::fs::create_dir(&batch).unwrap();
    std::fs::copy("samples/rapid/bom.mod", batch.join("bom.mod")).unwrap();
    std::fs::write(batch.join("blob.mod"), b"\x00\x01\x02binary\xff").unwrap();
    let o = dir.path().join("o");
    let args = [batch.to_str().unwrap(), "--out-dir", o.to_str().unwrap()];
    let (code, _, err) = correct(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("blob.mod: not a text module"), "{err}");
    let (code, _, err) = correct(&[&args[..], &["-q", "--force"]].concat());
    assert_eq!(code, 0, "{err}");
    assert_eq!(err, "");
}
