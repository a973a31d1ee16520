//! Targets a run leaves as written (`--keep`, `--skip-unsupported`) are listed in the stamp it
//! writes (`kept=`), and the transform that undoes it leaves them as written too
//! (docs/design.md §4, "Targets kept as written").

use std::path::{Path, PathBuf};

use crate::support::trackfix;

/// `p01` reaches its corrected pose on r1 only with another `cf1` and `j03` has axis 5 at its
/// upper limit, which the correction pushes out (both refused as `reach`); `pNC`'s skid is not
/// connected; `jOk` and `pT` are corrected. `pT` is `twin.mod`'s: the flange of `jOk`'s
/// neighbour at skid 3000, reached with `[0,0,-1,0]`.
const MODULE: &str = "MODULE KeptRound
  CONST robtarget p01:=[[3952.1344,-1905.2735,969.1064],[-0.1657189,-0.0957184,0.9658045,0.1749198],[0,0,0,0],[4000.0,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget j03:=[[10,10,20,30,120,60],[4000,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jOk:=[[10,10,20,30,45,60],[4000,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pNC:=[[3952.1344,-1905.2735,969.1064],[-0.1657189,-0.0957184,0.9658045,0.1749198],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pT:=[[2772.5670,-1761.7710,927.7176],[0.1591504,0.7545567,-0.5855842,-0.2498130],[0,0,-1,0],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveJ p01, v100, fine, tool0;
    MoveL Offs(p01,0,0,50), v100, fine, tool0;
    MoveAbsJ j03, v100, fine, tool0;
    MoveAbsJ jOk, v100, fine, tool0;
    MoveJ pNC, v100, fine, tool0;
    MoveJ pT, v100, fine, tool0;
  ENDPROC
ENDMODULE
";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn read(p: &Path) -> String {
    String::from_utf8(std::fs::read(p).unwrap()).unwrap()
}

/// The stamp line of `text` (the line after `MODULE` / `DEF` / `DEFDAT`).
fn stamp_line(text: &str) -> &str {
    text.lines()
        .nth(1)
        .filter(|l| l.contains("trackfix:"))
        .unwrap_or("")
}

/// The line declaring `name`.
fn line_of<'a>(text: &'a str, name: &str) -> &'a str {
    let key = format!(" {name}:=");
    text.lines().find(|l| l.contains(&key)).unwrap()
}

/// A zero of a partly corrected file gives every target back as written: those the correction
/// moved, and those it left as written, which carry none of it (before the stamp listed them,
/// zero moved `p01` by 1.38 mm and `j03` by hundredths of a degree).
#[test]
fn correct_keep_then_zero_gives_back_every_target_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "m.mod", MODULE);
    let listed = " kept=0:reach:p01;1:reach:j03;3:skid-not-connected:pNC ";
    for (i, keep) in [
        &["--keep", "reach,skid-not-connected"][..],
        &["--skip-unsupported"],
    ]
    .into_iter()
    .enumerate()
    {
        let (c, z) = (
            dir.path().join(format!("c{i}.mod")),
            dir.path().join(format!("z{i}.mod")),
        );
        let cell = ["--cell", "samples/cell.toml", "--robot", "r1"];
        let correct = [
            &["correct", m.to_str().unwrap(), "-o", c.to_str().unwrap()],
            &cell[..],
            keep,
        ]
        .concat();
        let (code, _, err) = trackfix(&correct);
        assert_eq!(code, 4, "{err}");
        let corrected = read(&c);
        assert!(stamp_line(&corrected).contains(listed), "{corrected}");
        // Corrected, and left as written, offset call included.
        assert_ne!(line_of(&corrected, "jOk"), line_of(MODULE, "jOk"));
        assert_ne!(line_of(&corrected, "pT"), line_of(MODULE, "pT"));
        for kept in ["p01", "j03", "pNC"] {
            assert_eq!(line_of(&corrected, kept), line_of(MODULE, kept));
        }
        assert!(corrected.contains("Offs(p01,0,0,50)"), "{corrected}");
        let zero = [
            &["zero", c.to_str().unwrap(), "-o", z.to_str().unwrap()],
            &cell[..],
        ]
        .concat();
        let (code, _, err) = trackfix(&zero);
        assert_eq!(code, 0, "{err}");
        // Byte for byte the original: the corrected targets come back, the others were never
        // touched, and the stamp goes.
        assert_eq!(read(&z), MODULE);
        for (target, line) in [("p01", 3), ("j03", 4), ("pNC", 6)] {
            let note = format!("c{i}.mod:{line}:");
            assert!(err.contains(&note), "{err}");
            assert!(
                err.contains(&format!(
                    "`{target}` was left as written by the `correct` this file's stamp records"
                )),
                "{err}"
            );
        }
        assert!(
            err.contains(
                "it carries none of robot `r1`'s correction, so zero leaves it as written"
            ),
            "{err}"
        );
    }
}

/// A KRL pair whose `.src` holds only a target the correction leaves as written: its `.dat`
/// is stamped, and so is the `.src` (unstamped, the `.dat`'s stamp would speak for it, and zero
/// would move the inline target).
#[test]
fn a_file_whose_every_target_was_kept_is_stamped_beside_its_stamped_pair() {
    let dir = tempfile::tempdir().unwrap();
    // XA1P is corrected on k1; the inline target (A1 at -0.005°) needs
    // another Turn bit after the correction and is refused.
    let src = "DEF kk( )\n  BAS(#INITMOV,0)\n  BAS(#BASE,0)\n  BAS(#TOOL,0)\n  PTP XA1P\n  PTP {X 4084.6749,Y -1451.7674,Z 1399.2490,A -17.30529,B -13.89205,C -147.34288,S 2,T 3,E1 4000.0}\nEND\n";
    let dat = "DEFDAT kk\nDECL E6POS XA1P={X 4085.0322,Y -1451.7822,Z 1399.2490,A -17.31529,B -13.89205,C -147.34288,S 2,T 2,E1 4000.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}\nENDDAT\n";
    write(dir.path(), "kk.src", src);
    write(dir.path(), "kk.dat", dat);
    let (c, z) = (dir.path().join("c"), dir.path().join("z"));
    let cell = ["--cell", "samples/cell.toml", "--robot", "k1"];
    let input = dir.path().join("kk.src");
    let (code, _, err) = trackfix(
        &[
            &[
                "correct",
                input.to_str().unwrap(),
                "--out-dir",
                c.to_str().unwrap(),
                "--keep",
                "reach",
            ],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 4, "{err}");
    let (csrc, cdat) = (read(&c.join("kk.src")), read(&c.join("kk.dat")));
    assert!(
        stamp_line(&csrc).contains(" kept=0:reach version="),
        "{csrc}"
    );
    assert_ne!(cdat, dat);
    assert!(!stamp_line(&cdat).contains("kept="), "{cdat}");
    let (code, _, err) = trackfix(
        &[
            &[
                "zero",
                c.join("kk.src").to_str().unwrap(),
                "--out-dir",
                z.to_str().unwrap(),
            ],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        (read(&z.join("kk.src")), read(&z.join("kk.dat"))),
        (src.to_owned(), dat.to_owned())
    );
    // One file alone, nothing changed, is not stamped: no stamp then says it is corrected.
    let (code, out, err) = trackfix(
        &[
            &[
                "correct",
                input.to_str().unwrap(),
                "--diff",
                "--keep",
                "reach",
            ],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 4, "{err}");
    assert!(out.contains("+; trackfix: correct robot=k1"), "{out}");
}

/// A `zero` that leaves a target as written (it still carries the correction) lists it; a
/// `correct` of its output leaves it as written and corrects the rest.
#[test]
fn correct_of_a_zero_that_kept_targets_leaves_them_as_written() {
    let dir = tempfile::tempdir().unwrap();
    // Taught on the real track: zero would push axis 5 of jLow past -125°.
    let tuned = "MODULE Tuned
  CONST jointtarget jLow:=[[10,10,20,30,-124.99,60],[4000,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jOk:=[[10,10,20,30,45,60],[4000,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveAbsJ jLow, v100, fine, tool0;
    MoveAbsJ jOk, v100, fine, tool0;
  ENDPROC
ENDMODULE
";
    let t = write(dir.path(), "t.mod", tuned);
    let (z, zc) = (dir.path().join("z.mod"), dir.path().join("zc.mod"));
    let cell = ["--cell", "samples/cell.toml", "--robot", "r1"];
    let (code, _, err) = trackfix(
        &[
            &[
                "zero",
                t.to_str().unwrap(),
                "-o",
                z.to_str().unwrap(),
                "--force",
                "--keep",
                "reach",
            ],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 4, "{err}");
    let zeroed = read(&z);
    assert!(
        stamp_line(&zeroed).contains(" kept=0:reach:jLow "),
        "{zeroed}"
    );
    assert_ne!(line_of(&zeroed, "jOk"), line_of(tuned, "jOk"));
    let (code, _, err) = trackfix(
        &[
            &["correct", z.to_str().unwrap(), "-o", zc.to_str().unwrap()],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("it still carries robot `r1`'s correction, so correct leaves it as written"),
        "{err}"
    );
    let back = read(&zc);
    // jLow as written (before the record it was corrected a second time), jOk back.
    assert_eq!(line_of(&back, "jLow"), line_of(tuned, "jLow"));
    assert_eq!(line_of(&back, "jOk"), line_of(tuned, "jOk"));
}

/// `transfer` of a partly corrected file: the targets the stamp lists are zeroed as written
/// (they carry none of r1's correction) and transferred like the rest. The transfer's own
/// stamp lists what it left as written (robot r1's text), which a `zero` for r2 leaves as
/// written and lists again, and another transfer refuses.
#[test]
fn transfer_reads_and_writes_the_kept_targets() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "m.mod", MODULE);
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_owned();
    let cell = "samples/cell.toml";
    let run = |args: &[&str]| {
        let (code, _, err) = trackfix(args);
        assert_eq!(code, 4, "{args:?}: {err}");
        err
    };
    run(&[
        "correct",
        m.to_str().unwrap(),
        "-o",
        &d("c.mod"),
        "--cell",
        cell,
        "--robot",
        "r1",
        "--skip-unsupported",
    ]);
    let err = run(&[
        "transfer",
        &d("c.mod"),
        "-o",
        &d("ct.mod"),
        "--cell",
        cell,
        "--from",
        "r1",
        "--to",
        "r2",
        "--mirror",
        "--skip-unsupported",
    ]);
    assert!(
        err.contains("`p01` was left as written by the `correct`"),
        "{err}"
    );
    // The three commands in a row on the original give p01 the same text.
    run(&[
        "mirror",
        m.to_str().unwrap(),
        "-o",
        &d("m1.mod"),
        "--cell",
        cell,
        "--robot",
        "r1",
        "--to",
        "r2",
        "--skip-unsupported",
    ]);
    run(&[
        "correct",
        &d("m1.mod"),
        "-o",
        &d("m1c.mod"),
        "--cell",
        cell,
        "--robot",
        "r2",
        "--skip-unsupported",
    ]);
    let (transferred, chained) = (
        read(Path::new(&d("ct.mod"))),
        read(Path::new(&d("m1c.mod"))),
    );
    assert_ne!(line_of(&transferred, "p01"), line_of(MODULE, "p01"));
    assert_eq!(line_of(&transferred, "p01"), line_of(&chained, "p01"));
    let stamp = stamp_line(&transferred);
    assert!(
        stamp.starts_with("! trackfix: transfer robot=r2 ")
            && stamp.contains(" kept=3:skid-missing:pNC "),
        "{stamp}"
    );
    // j03 is transferred too: on r2's own base the image of its axis 5 lies inside the limit
    // (119.988°), where the rule's image was at it (120°) and r2's correction pushed it out.
    assert_ne!(line_of(&transferred, "j03"), line_of(MODULE, "j03"));
    // zero for r2: pNC is robot r1's program as written, left so and listed again.
    let (code, _, err) = trackfix(&[
        "zero",
        &d("ct.mod"),
        "-o",
        &d("ctz.mod"),
        "--cell",
        cell,
        "--robot",
        "r2",
    ]);
    assert_eq!(code, 0, "{err}");
    let zeroed = read(Path::new(&d("ctz.mod")));
    assert_eq!(line_of(&zeroed, "pNC"), line_of(MODULE, "pNC"));
    assert!(
        stamp_line(&zeroed).contains(" kept=3:skid-missing:pNC "),
        "{zeroed}"
    );
    // A transfer back refuses it by the kind it was first refused as.
    let (code, _, err) = trackfix(&[
        "transfer",
        &d("ct.mod"),
        "-o",
        &d("back.mod"),
        "--cell",
        cell,
        "--from",
        "r2",
        "--to",
        "r1",
        "--mirror",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("`pNC` was left as written by the `transfer` this file's stamp records (refused as skid-missing)"), "{err}");
    assert!(err.contains("[skid-missing]"), "{err}");
}

/// Mirroring back leaves the targets the first mirror left as written; a track rule on the
/// mirrored file refuses them, by the kind they were refused as, since they are no mirror image.
#[test]
fn mirror_back_leaves_the_kept_targets_and_other_rules_refuse_them() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "m.mod", MODULE);
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_owned();
    // Without kinematics joint targets are not mirrored.
    let rules = ["--cell", "samples/cell_rules.toml"];
    let (code, _, err) = trackfix(
        &[
            &[
                "mirror",
                m.to_str().unwrap(),
                "-o",
                &d("m1.mod"),
                "--skip-unsupported",
            ],
            &rules[..],
        ]
        .concat(),
    );
    assert_eq!(code, 4, "{err}");
    let once = read(Path::new(&d("m1.mod")));
    assert!(
        stamp_line(&once).contains(" kept=1:joint-target:j03;2:joint-target:jOk "),
        "{once}"
    );
    let (code, _, err) =
        trackfix(&[&["mirror", &d("m1.mod"), "-o", &d("m2.mod")], &rules[..]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("it is no mirror image, so mirroring the file back leaves it as written"),
        "{err}"
    );
    let twice = read(Path::new(&d("m2.mod")));
    let unstamped: Vec<&str> = twice.lines().filter(|l| !l.contains("trackfix:")).collect();
    assert_eq!(unstamped, MODULE.lines().collect::<Vec<_>>());
    let (code, _, err) = trackfix(&[
        "correct",
        &d("m1.mod"),
        "-o",
        &d("m1c.mod"),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r2",
        "--keep",
        "skid-not-connected",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("`jOk` was left as written by the `mirror` this file's stamp records (refused as joint-target): it lacks what that transform gave the rest of the file"), "{err}");
}

/// A record that no longer fits its file (a target renamed, an entry that cannot be read) says
/// nothing of which targets carry the correction: refused whole, unless forced.
#[test]
fn a_kept_record_out_of_step_with_its_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "m.mod", MODULE);
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_owned();
    let cell = [
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--skip-unsupported",
    ];
    let (code, _, err) = trackfix(
        &[
            &["correct", m.to_str().unwrap(), "-o", &d("c.mod")],
            &cell[..],
        ]
        .concat(),
    );
    assert_eq!(code, 4, "{err}");
    let corrected = read(Path::new(&d("c.mod")));
    for (edit, said) in [
        (
            corrected.replace(":reach:p01;", ":reach:pX;"),
            "says target index 0 is `pX`, and the file has `p01` there",
        ),
        (
            corrected.replace(":reach:p01;", ":rich:p01;"),
            "cannot be read",
        ),
    ] {
        std::fs::write(d("e.mod"), &edit).unwrap();
        let (code, _, err) =
            trackfix(&[&["zero", &d("e.mod"), "-o", &d("ez.mod")], &cell[..]].concat());
        assert_eq!(code, 3, "{err}");
        assert!(err.contains(said) && err.contains("pass --force"), "{err}");
        assert!(!Path::new(&d("ez.mod")).exists());
        let (code, _, err) = trackfix(
            &[
                &["zero", &d("e.mod"), "-o", &d("ez.mod"), "--force"],
                &cell[..],
            ]
            .concat(),
        );
        assert!(code == 0 || code == 4, "{err}");
        std::fs::remove_file(d("ez.mod")).unwrap();
    }
}
