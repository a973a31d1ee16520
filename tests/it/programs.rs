//! Whole programs: the modules of a RAPID task resolved together (task and global data across
//! modules, `LOCAL` data private, targets used through routine parameters).

use std::path::{Path, PathBuf};

use trackfix::position::{Position, Program};
use trackfix::program::{LoadOptions, collect_inputs, group_inputs, load_group};

use crate::support::{root, trackfix};

const TARGET: &str =
    "[[812.5,-120,455],[0,0.7071068,0.7071068,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]]";

/// Writes `files` (path under the task folder, text) into a fresh `TASK1` folder.
fn task(files: &[(&str, String)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let task = dir.path().join("TASK1");
    for (path, text) in files {
        let p = task.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    (dir, task)
}

fn programs(dir: &Path) -> Vec<Program> {
    let groups = group_inputs(collect_inputs(&[dir.to_owned()]).unwrap());
    groups
        .iter()
        .flat_map(|g| load_group(g, &LoadOptions::default()))
        .map(Result::unwrap)
        .collect()
}

fn target(program: &Program, name: &str) -> Position {
    program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no target {name}"))
}

/// The work objects target `name` of `program` is used with, sorted.
fn work_objects(program: &Program, name: &str) -> Vec<String> {
    crate::support::sorted_work_objects(&target(program, name).usage)
}

/// The new user's case: data in one module, the motion in another, the work object declared in
/// the data module: one program, the target used with `wCar`, and `correct` moves it.
#[test]
fn data_and_motion_modules_of_one_task_resolve_together() {
    let data = format!(
        "MODULE Data\n  PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[2000,-600,300],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n  CONST robtarget p10:={TARGET};\nENDMODULE\n"
    );
    let main = "MODULE Main\n  PROC main()\n    MoveL p10,v200,fine,tool0\\WObj:=wCar;\n  ENDPROC\nENDMODULE\n";
    let (_dir, task) = task(&[
        ("PROGMOD/Data.mod", data.clone()),
        ("PROGMOD/Main.mod", main.to_owned()),
    ]);
    let ps = programs(&task);
    assert_eq!(ps.len(), 1, "one task, one program");
    assert_eq!(ps[0].files.len(), 2);
    let p10 = target(&ps[0], "p10");
    assert_eq!(p10.usage.wobj.as_deref(), Some("wCar"));
    assert_eq!(p10.usage.tool.as_deref(), Some("tool0"));

    let out = task.parent().unwrap().join("out");
    let (code, _, err) = trackfix(&[
        "correct",
        task.to_str().unwrap(),
        "--cell",
        root().join("samples/cell_rules.toml").to_str().unwrap(),
        "--robot",
        "r1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let written = std::fs::read_to_string(out.join("PROGMOD/Data.mod")).unwrap();
    assert_ne!(written, data, "p10 is corrected");
    assert!(
        written.contains("wCar:=[FALSE,TRUE,\"\",[[2000,-600,300]"),
        "{written}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("PROGMOD/Main.mod")).unwrap(),
        main
    );
}

/// `LOCAL` data is its module's: another module's motion does not reach it (and a module's own
/// declaration hides the task's of the same name).
#[test]
fn local_data_stays_in_its_module() {
    let a = format!(
        "MODULE A\n  LOCAL CONST robtarget pL:={TARGET};\n  CONST robtarget pG:={TARGET};\nENDMODULE\n"
    );
    let b = format!(
        "MODULE B\n  CONST robtarget pOwn:={TARGET};\n  PROC r()\n    MoveL pL,v1,fine,tool0\\WObj:=wB;\n    MoveL pG,v1,fine,tool0\\WObj:=wB;\n  ENDPROC\nENDMODULE\n"
    );
    let (_dir, task) = task(&[("PROGMOD/A.mod", a), ("SYSMOD/B.sys", b)]);
    let ps = programs(&task);
    assert_eq!(ps.len(), 1);
    assert_eq!(
        target(&ps[0], "pL").usage.wobj,
        None,
        "LOCAL: not seen from B"
    );
    assert_eq!(target(&ps[0], "pG").usage.wobj.as_deref(), Some("wB"));
}

/// A target whose frame is set on one path only is refused, and the help says how the
/// program's language sets a frame: a base before the motion (KRL), `\WObj:=` in it (RAPID).
#[test]
fn an_unresolved_frame_is_explained_in_the_programs_language() {
    let cell = root().join("samples/cell_rules.toml");
    // Set on one path only; and known for one motion, set on one path only before another:
    // whatever the first motion's base, the point's is not known.
    for (src, line) in [
        (
            "DEF m( )\n  INT I\n  IF I == 1 THEN\n    BAS (#BASE,1 )\n  ENDIF\n  LIN XP1\nEND\n",
            6,
        ),
        (
            "DEF m( )\n  INT I\n  BAS (#BASE,1 )\n  LIN XP1\n  IF I == 1 THEN\n    BAS (#BASE,2 )\n  ENDIF\n  LIN XP1\nEND\n",
            8,
        ),
    ] {
        unresolved_frame_is_refused(&cell, src, line);
    }
}

fn unresolved_frame_is_refused(cell: &Path, src: &str, line: usize) {
    let dat = format!("DEFDAT m PUBLIC\nDECL E6POS XP1={P1}\nENDDAT\n");
    let (dir, r1) = kss(&[
        ("Program/m.src", src),
        ("Program/m.dat", &dat),
        ("System/$config.dat", CONFIG),
    ]);
    let out = dir.path().join("out");
    let (code, _, err) = trackfix(&[
        "correct",
        r1.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains(&format!(
            "E6POS `XP1` is moved to on line {line} of m.src with a base that cannot be resolved"
        )),
        "{err}"
    );
    assert!(
        err.contains("help: set the base before each motion to it (BAS(#BASE,n), $BASE = BASE_DATA[n] or the point's FDAT), the same on every path"),
        "{err}"
    );
}

/// A copy of a target's value (`pv := p1;`, `buf{1} := p2;`, `RETURN p5;` in a function) is
/// used as the copy is: a motion
/// to `pv` in `wA` is a use of `p1` in `wA`, so `p1`, also moved to in `wB`, has both work
/// objects; an element chosen at run time (`buf{i}`) reaches every copy into the array, one
/// chosen by a number only its own; a copy made in another module of the task counts there.
/// The copy itself is computed at run time and is no target of its own.
#[test]
fn a_copy_of_a_target_is_used_as_the_copy_is() {
    let data = format!(
        "MODULE D\n  CONST robtarget p1:={TARGET};\n  CONST robtarget p2:={TARGET};\n  CONST robtarget p3:={TARGET};\n  CONST robtarget p4:={TARGET};\n  CONST robtarget p5:={TARGET};\n  CONST jointtarget jTaught:=[[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  CONST jointtarget jEnd:=[[10,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  VAR jointtarget jFound;\n  VAR robtarget pv;\n  VAR robtarget buf{{3}};\nENDMODULE\n"
    );
    let main = "MODULE M\n  FUNC robtarget nextOne()\n    RETURN p5;\n  ENDFUNC\n  PROC r()\n    VAR num i := 2;\n    pv := p1;\n    buf{1} := p2;\n    buf{2} := p3;\n    buf{3} := p4;\n    MoveL pv,v1,fine,tool0\\WObj:=wA;\n    MoveL p1,v1,fine,tool0\\WObj:=wB;\n    MoveL buf{i},v1,fine,tool0\\WObj:=wC;\n    MoveL buf{3},v1,fine,tool0\\WObj:=wD;\n    MoveL nextOne(),v1,fine,tool0\\WObj:=wE;\n    MoveL Offs(p5,0,0,10),v1,fine,tool0\\WObj:=wF;\n    jFound := jTaught;\n    SearchExtJ di1, jFound, jEnd, v100;\n  ENDPROC\nENDMODULE\n"
        .to_owned();
    let (_dir, task) = task(&[("PROGMOD/D.mod", data), ("PROGMOD/M.mod", main)]);
    let ps = programs(&task);
    assert_eq!(ps.len(), 1);
    let wobjs = |name: &str| work_objects(&ps[0], name);
    assert_eq!(wobjs("p1"), ["wA", "wB"]);
    assert_eq!(wobjs("p2"), ["wC"]);
    assert_eq!(wobjs("p3"), ["wC"]);
    assert_eq!(wobjs("p4"), ["wC", "wD"]);
    // A function that returns a target: a call of it as a motion's target is a use.
    assert_eq!(wobjs("p5"), ["wE", "wF"]);
    // The search writes its found position into the copy, not into what was copied to it.
    assert!(target(&ps[0], "jTaught").usage.non_position().is_none());
    assert!(
        ps[0]
            .files
            .iter()
            .flat_map(|f| f.positions())
            .all(|p| p.name.as_deref() != Some("pv")),
        "a VAR without a value is no target"
    );
}

/// Two modules of a task may each declare a `LOCAL` work object (and tool) of one name: a target
/// is transformed with its own module's, as when that module is corrected on its own, where
/// every module's targets took the first module's frame.
#[test]
fn a_local_work_object_is_the_one_of_the_targets_module() {
    let module = |name: &str, uframe: &str, target: &str| {
        format!(
            "MODULE {name}\n  LOCAL PERS wobjdata wX:=[FALSE,TRUE,\"\",[{uframe}],[[0,0,0],[1,0,0,0]]];\n  CONST robtarget {target}:=[[10,20,30],[0,1,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  PROC r{name}()\n    MoveL {target},v100,fine,tool0\\WObj:=wX;\n  ENDPROC\nENDMODULE\n"
        )
    };
    let a = module("A", "[1000,0,0],[1,0,0,0]", "pa");
    let b = module("B", "[3000,-500,0],[0.707107,0,0,0.707107]", "pb");
    let (dir, both) = task(&[("PROGMOD/A.mod", a), ("PROGMOD/B.mod", b.clone())]);
    let cell = root().join("samples/cell_rules.toml");
    let correct = |input: &Path, out: &Path| {
        let (code, _, err) = trackfix(&[
            "correct",
            input.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--robot",
            "r1",
            "--no-stamp",
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
    };
    let together = dir.path().join("together");
    correct(&both, &together);
    let alone_in = dir.path().join("B.mod");
    std::fs::write(&alone_in, &b).unwrap();
    let alone = dir.path().join("alone");
    correct(&alone_in, &alone);
    let line = |text: String, name: &str| {
        text.lines()
            .find(|l| l.contains(&format!("robtarget {name}:=")))
            .unwrap()
            .to_owned()
    };
    let read = |p: PathBuf| std::fs::read_to_string(p).unwrap();
    let pb = line(read(together.join("PROGMOD/B.mod")), "pb");
    assert_eq!(pb, line(read(alone.join("B.mod")), "pb"));
    let pa = line(read(together.join("PROGMOD/A.mod")), "pa");
    assert_ne!(pa.replace("pa:=", ""), pb.replace("pb:=", ""), "{pa}\n{pb}");

    // B's `wX` holds the tool (robhold TRUE), A's does not: B's target is refused as a
    // stationary-tool point, A's corrected as before (B, read last, decided for both).
    let held = b.replace("[FALSE,TRUE,", "[TRUE,TRUE,");
    let a = module("A", "[1000,0,0],[1,0,0,0]", "pa");
    let (held_dir, held_task) = task(&[("PROGMOD/A.mod", a), ("PROGMOD/B.mod", held)]);
    let out = held_dir.path().join("out");
    let (code, _, err) = trackfix(&[
        "correct",
        held_task.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r1",
        "--no-stamp",
        "--keep",
        "stationary-tool",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{err}");
    assert!(err.contains("`pb`") && !err.contains("`pa`"), "{err}");
    assert_eq!(line(read(out.join("PROGMOD/A.mod")), "pa"), pa);
}

/// `CalcJointT(p, tool \WObj:=w)` reaches `p` in `w` (the joints a `MoveAbsJ` then moves to),
/// in an assignment or as an argument: a use of `p` there, as a motion to it is. Motions alike
/// around it keep their own work objects (the call read like the one before is not confused
/// with it).
#[test]
fn calc_joint_t_is_a_use_of_its_target_in_its_work_object() {
    let module = format!(
        "MODULE M\n  CONST robtarget p1:={TARGET};\n  CONST robtarget p2:={TARGET};\n  CONST robtarget p3:={TARGET};\n  CONST robtarget p4:={TARGET};\n  VAR jointtarget jt;\n  PROC r()\n    MoveL p2,v1,fine,tool0\\WObj:=wC;\n    jt := CalcJointT(p1, tool0 \\WObj:=wA);\n    MoveL p3,v1,fine,tool0\\WObj:=wC;\n    MoveAbsJ CalcJointT(p4, tool0 \\WObj:=wD), v1, fine, tool0;\n    MoveAbsJ jt, v1, fine, tool0;\n    MoveL p1,v1,fine,tool0\\WObj:=wB;\n  ENDPROC\nENDMODULE\n"
    );
    let (_dir, task) = task(&[("PROGMOD/M.mod", module)]);
    let ps = programs(&task);
    let wobjs = |name: &str| work_objects(&ps[0], name);
    assert_eq!(wobjs("p1"), ["wA", "wB"]);
    assert_eq!(wobjs("p2"), ["wC"]);
    assert_eq!(wobjs("p3"), ["wC"]);
    assert_eq!(wobjs("p4"), ["wD"]);
}

/// A target passed to a routine's parameter is used as the routine's motions use it: directly,
/// through `Offs`/`RelTool`, and passed on to a further routine; recursion ends; two paths with
/// different work objects leave both on the target (refused by name as before).
#[test]
fn targets_through_routine_parameters() {
    let data = format!(
        "MODULE Data\n  CONST robtarget p1:={TARGET};\n  CONST robtarget p2:={TARGET};\n  CONST robtarget p3:={TARGET};\n  CONST robtarget p4:={TARGET};\nENDMODULE\n"
    );
    let main = "MODULE Main\n\
        PROC main()\n  Weld p1;\n  Outer 5, p2;\n  Spin p3;\n  Weld p4;\n  Other p4;\nENDPROC\n\
        PROC Weld(robtarget p)\n  MoveL Offs(p,0,0,50),v200,z10,tGun\\WObj:=wCar;\nENDPROC\n\
        PROC Outer(num n, INOUT robtarget q)\n  Weld q;\nENDPROC\n\
        PROC Spin(robtarget s)\n  Spin s;\n  MoveJ RelTool(s,0,0,-10),v200,z10,tGun\\WObj:=wSpin;\nENDPROC\n\
        PROC Other(robtarget o)\n  MoveL o,v200,z10,tGun\\WObj:=wOther;\nENDPROC\n\
        ENDMODULE\n";
    let (_dir, task) = task(&[
        ("PROGMOD/Data.mod", data),
        ("PROGMOD/Main.mod", main.to_owned()),
    ]);
    let ps = programs(&task);
    let u = |n: &str| target(&ps[0], n).usage.clone();
    assert_eq!(u("p1").wobj.as_deref(), Some("wCar"));
    assert_eq!(u("p1").tool.as_deref(), Some("tGun"));
    assert_eq!(
        u("p1").lines,
        vec![3],
        "the line of the call that passes it"
    );
    assert_eq!(u("p2").wobj.as_deref(), Some("wCar"), "passed on by Outer");
    assert_eq!(u("p3").wobj.as_deref(), Some("wSpin"), "recursive routine");
    assert_eq!(u("p4").wobj.as_deref(), Some("wCar"));
    assert_eq!(u("p4").other_wobjs(), ["wOther"]);
}

/// A call names the routine of its own module first (`LOCAL` or not), else the first other
/// module's routine that is not `LOCAL`: with a `LOCAL` routine of that name in a module before
/// it, the call from a third module binds to the later module's global one.
#[test]
fn a_call_binds_its_own_modules_routine_then_a_global_one() {
    let data = format!(
        "MODULE Data\n  CONST robtarget pA:={TARGET};\n  CONST robtarget pB:={TARGET};\n  CONST robtarget pC:={TARGET};\nENDMODULE\n"
    );
    let a = "MODULE A\n\
        LOCAL PROC Place(robtarget p)\n  MoveL p,v200,z10,tGun\\WObj:=wA;\nENDPROC\n\
        PROC FromA()\n  Place pA;\nENDPROC\nENDMODULE\n";
    let b = "MODULE B\n\
        PROC Place(robtarget p)\n  MoveL p,v200,z10,tGun\\WObj:=wB;\nENDPROC\n\
        PROC FromB()\n  Place pB;\nENDPROC\nENDMODULE\n";
    let c = "MODULE C\nPROC FromC()\n  Place pC;\nENDPROC\nENDMODULE\n";
    let (_dir, task) = task(&[
        ("PROGMOD/A.mod", a.to_owned()),
        ("PROGMOD/B.mod", b.to_owned()),
        ("PROGMOD/C.mod", c.to_owned()),
        ("PROGMOD/Data.mod", data),
    ]);
    let ps = programs(&task);
    let wobj = |n: &str| target(&ps[0], n).usage.wobj.as_deref().map(str::to_owned);
    assert_eq!(
        wobj("pA").as_deref(),
        Some("wA"),
        "its own module's LOCAL routine"
    );
    assert_eq!(
        wobj("pB").as_deref(),
        Some("wB"),
        "its own module's routine"
    );
    assert_eq!(
        wobj("pC").as_deref(),
        Some("wB"),
        "the global one, not A's LOCAL one"
    );
}

fn cartesian(program: &Program) -> Vec<(String, [f64; 3])> {
    program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .filter_map(|p| Some((p.label(), p.cartesian.as_ref()?.translation()?)))
        .collect()
}

/// Per program: every target of the RobotStudio-style sample backup is transformed, and
/// zero(correct(P)) gives back P's numbers within the written precision (3 decimals, two
/// roundings: 1.5e-3 mm). `Weld`'s `Offs(p,0,0,50)` stands for two targets whose corrections
/// turn it differently: it is kept as written (`--keep shared-offset`, exit 4), every target
/// moves.
#[test]
fn correct_then_zero_gives_back_the_sample_backup() {
    let dir = tempfile::tempdir().unwrap();
    let (c, z) = (dir.path().join("c"), dir.path().join("z"));
    let sample = root().join("samples/robotstudio_backup");
    let cell = root().join("samples/cell_rules.toml");
    let (code, _, err) = trackfix(&[
        "correct",
        sample.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r1",
        "--keep",
        "shared-offset",
        "--out-dir",
        c.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "every target transformed, the offset kept: {err}");
    assert!(
        err.contains("Main.mod:12:15: warning: the 2 targets `p` stands for"),
        "{err}"
    );
    let (code, _, err) = trackfix(&[
        "zero",
        c.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r1",
        "--keep",
        "shared-offset",
        "--out-dir",
        z.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{err}");
    let before = cartesian(&programs(&sample)[0]);
    let corrected = cartesian(&programs(&c)[0]);
    let after = cartesian(&programs(&z)[0]);
    assert_eq!(before.len(), 4);
    assert_eq!(before.len(), after.len());
    let moved = before
        .iter()
        .zip(&corrected)
        .any(|(a, b)| (0..3).any(|k| (a.1[k] - b.1[k]).abs() > 0.1));
    assert!(moved, "correct moves the targets");
    for (a, b) in before.iter().zip(&after) {
        assert_eq!(a.0, b.0);
        for k in 0..3 {
            assert!(
                (a.1[k] - b.1[k]).abs() <= 1.5e-3,
                "{}: {:?} vs {:?}",
                a.0,
                a.1,
                b.1
            );
        }
    }
}

/// Writes `files` (path under `KRC/R1`, text) into a fresh KSS-style tree; returns the `R1` path.
fn kss(files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let r1 = dir.path().join("KRC/R1");
    for (path, text) in files {
        let p = r1.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    (dir, r1)
}

const CONFIG: &str = "DEFDAT $CONFIG\n\
    DECL E6POS XGLOBAL={X 150.0,Y 40.0,Z 380.0,A 180.0,B 0.0,C 180.0,S 6,T 27,E1 2500.0}\n\
    DECL E6POS XUNUSED={X 1.0,Y 2.0,Z 3.0,A 0.0,B 0.0,C 0.0,S 6,T 27,E1 100.0}\n\
    DECL E6AXIS XHOME={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0,E1 4000.0}\n\
    BASE_DATA[1]={X 2150.0,Y -1480.0,Z 720.0,A 0.0,B 0.0,C 0.0}\n\
    BASE_DATA[2]={X 3650.0,Y -1480.0,Z 720.0,A 90.0,B 0.0,C 0.0}\n\
    TOOL_DATA[1]={X 0.0,Y 0.0,Z 245.0,A 0.0,B 0.0,C 0.0}\n\
    ENDDAT\n";

const P1: &str = "{X 410.0,Y -95.0,Z 230.0,A 180.0,B 0.0,C 180.0,S 6,T 27,E1 1500.0}";

/// A KSS tree is one program: the `.src`/`.dat` pairs, lone `.src` files and the tree's own
/// `$config.dat`. A base and tool set in a subroutine (of another file, called through a further
/// subroutine) hold for the motions after the call; a subroutine that sets the base on one path
/// only leaves it unknown; recursion ends; `$config.dat` points the program moves to are its
/// targets, the others (and joint points like `XHOME`) are not.
#[test]
fn kss_tree_resolves_across_files_and_subroutines() {
    let main_src = "DEF main( )\n  PTP XHOME\n  car( )\n  LIN XP1\n  LIN XGLOBAL\n  maybe( )\n  LIN XP2\n  other( )\n  LIN XP3\nEND\n";
    let main_dat = format!(
        "DEFDAT main PUBLIC\nDECL E6POS XP1={P1}\nDECL E6POS XP2={P1}\nDECL E6POS XP3={P1}\nENDDAT\n"
    );
    let subs = "GLOBAL DEF car( )\n  tools( )\n  BAS (#BASE,1 )\nEND\n\
        DEF tools( )\n  $TOOL=TOOL_DATA[1]\nEND\n\
        GLOBAL DEF maybe( )\n  IF $IN[1] THEN\n    BAS (#BASE,2 )\n  ENDIF\nEND\n\
        GLOBAL DEF other( )\n  BAS (#BASE,2 )\n  other( )\nEND\n";
    let (_dir, r1) = kss(&[
        ("Program/main.src", main_src),
        ("Program/main.dat", &main_dat),
        ("Program/lib/subs.src", subs),
        ("System/$config.dat", CONFIG),
    ]);
    let ps = programs(&r1);
    assert_eq!(ps.len(), 1, "one tree, one program");
    assert_eq!(ps[0].files.len(), 4);
    let u = |n: &str| target(&ps[0], n).usage.clone();
    assert_eq!(u("XP1").wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(
        u("XP1").tool.as_deref(),
        Some("TOOL_DATA[1]"),
        "set two calls deep"
    );
    assert_eq!(u("XGLOBAL").wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(u("XP2").wobj, None, "base set on one path only: unknown");
    assert_eq!(
        u("XP3").wobj.as_deref(),
        Some("BASE_DATA[2]"),
        "recursive routine"
    );
    let config = ps[0]
        .files
        .iter()
        .find(|f| f.path.ends_with("System/$config.dat"))
        .unwrap();
    let names: Vec<_> = config.positions().map(|p| p.label()).collect();
    assert_eq!(names, ["XGLOBAL"], "only the used Cartesian global point");
}

/// A tree's own `$config.dat` goes to `--out-dir` with the tree's program files: as it was when
/// the program moves to none of its points, corrected when it does, so a later run on the output
/// tree reads the same bases. Programs named by their files (no folder given) are written flat,
/// without it; a `$config.dat` named alone is no program and nothing is written.
#[test]
fn config_dat_goes_to_the_out_dir_with_its_tree() {
    let cell = root().join("samples/cell_rules.toml");
    let correct = |inputs: &[&Path], out: &Path| {
        let mut args = vec!["correct"];
        args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
        args.extend([
            "--cell",
            cell.to_str().unwrap(),
            "--robot",
            "r1",
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        trackfix(&args)
    };
    for uses_global in [false, true] {
        let src = if uses_global {
            "DEF m( )\n  BAS (#BASE,1 )\n  LIN XP1\n  LIN XGLOBAL\nEND\n"
        } else {
            "DEF m( )\n  BAS (#BASE,1 )\n  LIN XP1\nEND\n"
        };
        let dat = format!("DEFDAT m PUBLIC\nDECL E6POS XP1={P1}\nENDDAT\n");
        let (dir, r1) = kss(&[
            ("Program/m.src", src),
            ("Program/m.dat", &dat),
            ("System/$config.dat", CONFIG),
        ]);
        let out = dir.path().join("out");
        let (code, _, err) = correct(&[&r1], &out);
        assert_eq!(code, 0, "{err}");
        assert_ne!(
            std::fs::read_to_string(out.join("Program/m.dat")).unwrap(),
            dat
        );
        let text = std::fs::read_to_string(out.join("System/$config.dat")).unwrap();
        if uses_global {
            assert!(!text.contains("XGLOBAL={X 150.0,"), "{text}");
            assert!(
                text.contains("XUNUSED={X 1.0,Y 2.0,Z 3.0,"),
                "untouched: {text}"
            );
            assert!(err.contains("$config.dat: 1 target(s) changed"), "{err}");
        } else {
            assert_eq!(text, CONFIG, "copied as it was");
            assert!(err.contains("$config.dat: unchanged"), "{err}");
        }
        // The output tree corrects nothing again in a way the input did not: its bases are
        // the same (zero gives the input back).
        let back = dir.path().join("back");
        let (code, _, err) = trackfix(&[
            "zero",
            out.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--robot",
            "r1",
            "--out-dir",
            back.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        assert_eq!(
            std::fs::read_to_string(back.join("System/$config.dat")).unwrap(),
            CONFIG
        );

        if !uses_global {
            // The program's files named: written flat, the tree's `$config.dat` read for its
            // bases only.
            let flat = dir.path().join("flat");
            let (m_src, m_dat) = (r1.join("Program/m.src"), r1.join("Program/m.dat"));
            let (code, _, err) = correct(&[&m_src, &m_dat], &flat);
            assert_eq!(code, 0, "{err}");
            let mut names: Vec<_> = std::fs::read_dir(&flat)
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect();
            names.sort();
            assert_eq!(names, ["m.dat", "m.src"]);
            // Named alone: nothing to write.
            let alone = dir.path().join("alone");
            let config = r1.join("System/$config.dat");
            let (code, _, err) = correct(&[&config], &alone);
            assert_eq!(code, 2, "{err}");
            assert!(err.contains("holds no program"), "{err}");
            assert!(!alone.exists());
        }
    }
}

/// zero(correct(P)) = P per program over the KSS-style sample tree (all three targets, the
/// global one in `$config.dat` included).
#[test]
fn correct_then_zero_gives_back_the_kss_sample() {
    let dir = tempfile::tempdir().unwrap();
    let (c, z) = (dir.path().join("c"), dir.path().join("z"));
    let sample = root().join("samples/kss_backup");
    let cell = root().join("samples/cell_rules.toml");
    for (cmd, from, to) in [("correct", &sample, &c), ("zero", &c, &z)] {
        let (code, _, err) = trackfix(&[
            cmd,
            from.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--robot",
            "r1",
            "--out-dir",
            to.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{cmd}: {err}");
    }
    let before = cartesian(&programs(&sample)[0]);
    let corrected = cartesian(&programs(&c)[0]);
    let after = cartesian(&programs(&z)[0]);
    let names: Vec<_> = before.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(names, ["XP1", "XP2", "XPick_Point"]);
    assert_eq!(after.len(), before.len());
    for ((a, m), b) in before.iter().zip(&corrected).zip(&after) {
        assert!(
            (0..3).any(|k| (a.1[k] - m.1[k]).abs() > 0.1),
            "{} moved",
            a.0
        );
        for k in 0..3 {
            assert!(
                (a.1[k] - b.1[k]).abs() <= 1.5e-3,
                "{}: {:?} vs {:?}",
                a.0,
                a.1,
                b.1
            );
        }
    }
}

/// `inspect --format json` of a task folder: each target names the file and line of the work
/// object and tool it resolved to, and the program lists its files and how many targets resolved.
#[test]
fn inspect_json_places_frames_and_lists_the_program() {
    let (code, out, err) = trackfix(&["inspect", "samples/robotstudio_backup", "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    let p10 = &json["files"][0]["positions"][0];
    assert_eq!(p10["name"], "p10");
    assert_eq!(p10["wobj"], "wCar");
    assert_eq!(
        p10["wobj_at"]["file"],
        "samples/robotstudio_backup/RAPID/TASK1/SYSMOD/user.sys"
    );
    assert_eq!(p10["wobj_at"]["line"], 3);
    assert_eq!(
        p10["tool_at"]["file"],
        "samples/robotstudio_backup/RAPID/TASK1/PROGMOD/Data.mod"
    );
    assert_eq!(p10["tool_at"]["line"], 3);
    let program = &json["programs"][0];
    assert_eq!(program["files"].as_array().unwrap().len(), 3);
    assert_eq!(
        (program["targets"].as_u64(), program["resolved"].as_u64()),
        (Some(4), Some(4))
    );
}

/// Loose modules named together on the command line are one task: the new user's two files,
/// outside any task folder, are transformed; named one at a time (or found by walking a plain
/// folder) they stay separate programs and `p10` is refused.
#[test]
fn modules_named_together_are_one_task() {
    let dir = tempfile::tempdir().unwrap();
    let data = format!(
        "MODULE Data\n  PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[2000,-600,300],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n  CONST robtarget p10:={TARGET};\nENDMODULE\n"
    );
    let main = "MODULE Main\n  PROC main()\n    MoveL p10,v200,fine,tool0\\WObj:=wCar;\n  ENDPROC\nENDMODULE\n";
    let (d, m) = (dir.path().join("Data.mod"), dir.path().join("Main.mod"));
    std::fs::write(&d, &data).unwrap();
    std::fs::write(&m, main).unwrap();
    let groups = trackfix::program::collect_programs(&[d.clone(), m.clone()]).unwrap();
    assert_eq!(groups, vec![vec![d.clone(), m.clone()]]);
    let walked = trackfix::program::collect_programs(&[dir.path().to_owned()]).unwrap();
    assert_eq!(walked.len(), 2, "a plain folder's modules stay separate");
    let cell = root().join("samples/cell_rules.toml");
    let out = dir.path().join("out");
    let args = |files: &[&Path]| {
        let mut a: Vec<String> = vec!["correct".into()];
        a.extend(files.iter().map(|f| f.to_str().unwrap().to_owned()));
        a.extend(
            [
                "--cell",
                cell.to_str().unwrap(),
                "--robot",
                "r1",
                "--out-dir",
            ]
            .map(str::to_owned),
        );
        a.push(out.to_str().unwrap().to_owned());
        a
    };
    let run = |files: &[&Path]| {
        let a = args(files);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        trackfix(&a)
    };
    let (code, _, err) = run(&[&d, &m]);
    assert_eq!(code, 0, "{err}");
    assert_ne!(std::fs::read_to_string(out.join("Data.mod")).unwrap(), data);
    let (code, _, err) = run(&[&d]);
    assert_ne!(code, 0, "alone, p10 is used by no motion");
    assert!(err.contains("p10"), "{err}");
}

/// A refused target of a robot tree's own `$config.dat` is reported and stops the run like any
/// other (before: the unchanged `$config.dat` was dropped from the results with its refusal, and
/// the run exited 0 with the global point silently uncorrected). The point is out of reach of the
/// sample cell's KR 210 at skid 2500 mm.
#[test]
fn a_refused_global_point_of_config_dat_is_reported() {
    let tree = root().join("samples/kss_backup");
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("kss_backup");
    for entry in crate::support::files_under(&tree) {
        let rel = entry.strip_prefix(&tree).unwrap();
        let to = copy.join(rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(&entry, &to).unwrap();
    }
    let config = copy.join("KRC/R1/System/$config.dat");
    let text = std::fs::read_to_string(&config).unwrap();
    let far = text.replacen(",E1 2000.0,", ",E1 2500.0,", 1);
    assert_ne!(far, text);
    std::fs::write(&config, far).unwrap();
    let out = dir.path().join("out");
    let (code, _, err) = trackfix(&[
        "correct",
        copy.to_str().unwrap(),
        "--cell",
        root().join("samples/cell.toml").to_str().unwrap(),
        "--robot",
        "k1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("$config.dat:7:") && err.contains("E6POS `XPick_Point` is out of reach"),
        "{err}"
    );
    // The hint speaks KRL: the target's frame is its base (RAPID says work object).
    assert!(
        err.contains("help: check the target, its base and tool, and the robot's kinematics"),
        "{err}"
    );
    assert!(!out.exists());
}

/// `transfer` of a KSS tree reads each step's output again with the tree's own `$config.dat`
/// (not the cell's), so its global point stays a target through the chain: r1 → r2 moves it,
/// r1 → r1 without a stamp gives every file back byte for byte.
#[test]
fn transfer_keeps_the_kss_trees_own_config_dat() {
    let dir = tempfile::tempdir().unwrap();
    let sample = root().join("samples/kss_backup");
    let cell = root().join("samples/cell_rules.toml");
    let config = "KRC/R1/System/$config.dat";
    for to in ["r2", "r1"] {
        let out = dir.path().join(to);
        let (code, _, err) = trackfix(&[
            "transfer",
            sample.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--from",
            "r1",
            "--to",
            to,
            "--no-stamp",
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{to}: {err}");
        let original = std::fs::read(sample.join(config)).unwrap();
        match std::fs::read(out.join(config)) {
            Ok(written) if to == "r2" => {
                assert_ne!(written, original, "XPick_Point moved to r2's track")
            }
            Ok(written) => assert_eq!(written, original),
            Err(_) => assert_eq!(to, "r1", "r2: `$config.dat` was not written: {err}"),
        }
        for f in ["KRC/R1/Program/weld_car.dat", "KRC/R1/Program/weld_car.src"] {
            let written = std::fs::read(out.join(f)).unwrap();
            let same = written == std::fs::read(sample.join(f)).unwrap();
            assert_eq!(same, to == "r1" || f.ends_with(".src"), "{to}: {f}");
        }
    }
}

/// `check --format json` of a backup folder prints one JSON document: the per-program line of
/// the text report becomes the `"programs"` list.
#[test]
fn check_json_of_a_tree_is_one_document() {
    let (code, out, err) = trackfix(&["check", "samples/kss_backup", "--format", "json"]);
    assert!(code == 0 || code == 1, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("one JSON document");
    let program = &json["programs"][0];
    assert_eq!(program["files"].as_array().unwrap().len(), 4, "{out}");
    assert_eq!(
        (program["targets"].as_u64(), program["resolved"].as_u64()),
        (Some(3), Some(3))
    );
}

/// A program loaded from mapped files is the program loaded from read ones: the same bytes,
/// positions and diagnostics, RAPID and a KRL pair, a task of several modules among them. The
/// files are over the size from which inputs are mapped, and the test asserts they were.
#[test]
fn a_mapped_program_is_the_read_one() {
    let dir = tempfile::tempdir().unwrap();
    let mut module = String::from("MODULE Big\r\n");
    let mut motions = String::from("MODULE Moves\r\n  PROC main()\r\n");
    let mut n = 0;
    while module.len() <= trackfix::output::MAP_FROM_BYTES as usize {
        module.push_str(&format!(
            "  PERS robtarget p{n}:=[[{}.5,-120,455],[0,0.7071068,0.7071068,0],[0,0,-1,0],[{},9E9,9E9,9E9,9E9,9E9]];\r\n",
            n % 900,
            n * 3
        ));
        motions.push_str(&format!("    MoveL p{n}, v100, z10, tool0;\r\n"));
        n += 1;
    }
    module.push_str("ENDMODULE\r\n");
    motions.push_str("  ENDPROC\r\nENDMODULE\r\n");
    let task = dir.path().join("TASK1");
    std::fs::create_dir_all(task.join("PROGMOD")).unwrap();
    std::fs::write(task.join("PROGMOD/Big.mod"), &module).unwrap();
    std::fs::write(task.join("PROGMOD/Moves.mod"), &motions).unwrap();
    let mut src = String::from("DEF big( )\n");
    let mut dat = String::from("DEFDAT big\n");
    for i in 0..n {
        src.push_str(&format!("  PTP XP{i}\n"));
        dat.push_str(&format!(
            "DECL E6POS XP{i}={{X {}.25,Y 20,Z 900,A 0,B 90,C 0,S 2,T 10,E1 {},E2 0,E3 0,E4 0,E5 0,E6 0}}\n",
            i % 700,
            i * 2
        ));
    }
    src.push_str("END\n");
    dat.push_str("ENDDAT\n");
    std::fs::write(dir.path().join("big.src"), &src).unwrap();
    std::fs::write(dir.path().join("big.dat"), &dat).unwrap();

    let load = |map_inputs: bool| {
        let options = LoadOptions {
            map_inputs,
            ..LoadOptions::default()
        };
        let groups = group_inputs(collect_inputs(&[dir.path().to_owned()]).unwrap());
        assert_eq!(groups.len(), 2, "{groups:?}");
        groups
            .iter()
            .flat_map(|g| load_group(g, &options))
            .map(Result::unwrap)
            .collect::<Vec<_>>()
    };
    let (read, mapped) = (load(false), load(true));
    let files = |ps: &[Program]| ps.iter().flat_map(|p| p.files.iter()).count();
    assert_eq!(files(&read), 4);
    assert_eq!(files(&mapped), 4);
    let mut targets = 0;
    for (r, m) in read
        .iter()
        .flat_map(|p| &p.files)
        .zip(mapped.iter().flat_map(|p| &p.files))
    {
        assert!(!r.source.is_mapped(), "{}", r.path.display());
        let big = r.source.len() as u64 >= trackfix::output::MAP_FROM_BYTES;
        assert_eq!(m.source.is_mapped(), big, "{}", m.path.display());
        assert_eq!(r.path, m.path);
        assert!(r.source[..] == m.source[..], "{}", r.path.display());
        assert!(m.round_trip);
        let (rp, mp): (Vec<Position>, Vec<Position>) =
            (r.positions().collect(), m.positions().collect());
        assert_eq!(rp, mp, "{}", r.path.display());
        assert_eq!(r.diagnostics, m.diagnostics, "{}", r.path.display());
        targets += rp.len();
    }
    // Every declaration and every motion to one (RAPID's motions name them, KRL's too).
    assert!(targets >= 2 * n, "{targets} of {n}");
    assert!(
        mapped
            .iter()
            .flat_map(|p| &p.files)
            .any(|f| f.source.is_mapped())
    );
}

/// A point of a KSS tree's module as it is seen: by name (`XP1`, `FP1` and `setfr` are in
/// nearly every module), the module's own `.dat` and routines first, of another module only
/// what it declares `GLOBAL` (or its own first `DEF`), and `$config.dat`'s everywhere unless
/// the module declares the name itself.
#[test]
fn a_kss_tree_module_sees_its_own_names_and_only_the_global_ones_of_others() {
    let dir = tempfile::tempdir().unwrap();
    let r1 = dir.path().join("KRC").join("R1");
    let program = r1.join("Program");
    std::fs::create_dir_all(&program).unwrap();
    std::fs::create_dir_all(r1.join("System")).unwrap();
    std::fs::write(
        r1.join("System").join("$config.dat"),
        "DEFDAT $CONFIG\n\
DECL BASIS_SUGG_T LAST_BASIS={POINT1[] \"BASE\"}\n\
DECL E6POS XSHARED={X 500.0,Y -700.0,Z 900.0,A 0.0,B 90.0,C 0.0,S 2,T 10,E1 1500.0}\n\
ENDDAT\n",
    )
    .unwrap();
    let point = |name: &str, x: f64| {
        format!(
            "DECL E6POS {name}={{X {x:.1},Y -800.0,Z 800.0,A 0.0,B 90.0,C 0.0,S 2,T 10,E1 1500.0}}\n"
        )
    };
    let files = [
        // alpha declares XP1 and FP1 (base 1) and never moves to XP1.
        (
            "alpha.src",
            "DEF alpha( )\n  FDAT_ACT=FP1\n  BAS(#CP_PARAMS,2)\n  LIN XOWN\nEND\n".to_owned(),
        ),
        (
            "alpha.dat",
            format!(
                "DEFDAT alpha\n{}{}DECL FDAT FP1={{TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}}\nENDDAT\n",
                point("XP1", 100.0),
                point("XOWN", 150.0)
            ),
        ),
        // beta has its own XP1, FP1 (base 2) and setfr (base 2); it moves to delta's global
        // point, not to delta's local one, and to its own XSHARED, not $config.dat's.
        (
            "beta.src",
            "DEF beta( )\n  FDAT_ACT=FP1\n  BAS(#CP_PARAMS,2)\n  LIN XP1\n  setfr( )\n  LIN XGLOBAL\n  LIN XLOCAL\n  LIN XSHARED\nEND\nDEF setfr( )\n  $BASE=BASE_DATA[2]\n  $TOOL=TOOL_DATA[1]\nEND\n".to_owned(),
        ),
        (
            "beta.dat",
            format!(
                "DEFDAT beta\n{}{}DECL FDAT FP1={{TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}}\nENDDAT\n",
                point("XP1", 200.0),
                point("XSHARED", 250.0)
            ),
        ),
        // gamma calls a setfr of its own (base 1) and delta's global one (base 3).
        (
            "gamma.src",
            "DEF gamma( )\n  setfr( )\n  LIN XG1\n  setglobal( )\n  LIN XG3\nEND\nDEF setfr( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\nEND\n".to_owned(),
        ),
        (
            "gamma.dat",
            format!(
                "DEFDAT gamma\n{}{}ENDDAT\n",
                point("XG1", 300.0),
                point("XG3", 350.0)
            ),
        ),
        (
            "delta.src",
            "DEF delta( )\nEND\nGLOBAL DEF setglobal( )\n  $BASE=BASE_DATA[3]\n  $TOOL=TOOL_DATA[1]\nEND\n".to_owned(),
        ),
        (
            "delta.dat",
            format!(
                "DEFDAT delta PUBLIC\nGLOBAL {}{}ENDDAT\n",
                point("XGLOBAL", 400.0),
                point("XLOCAL", 450.0)
            ),
        ),
    ];
    for (name, text) in &files {
        std::fs::write(program.join(name), text).unwrap();
    }
    let all = programs(&dir.path().join("KRC"));
    assert_eq!(all.len(), 1, "one robot tree, one program");
    let of = |file: &str, name: &str| {
        all[0]
            .files
            .iter()
            .filter(|f| f.path.file_name().is_some_and(|n| n == file))
            .flat_map(|f| f.positions())
            .find(|p| p.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no {name} in {file}"))
    };
    let bases = |file: &str, name: &str| -> Vec<String> {
        of(file, name)
            .usage
            .work_objects()
            .map(str::to_owned)
            .collect()
    };
    // Each module's XP1 with its own FDAT; alpha's, which no motion uses (beta's motion to
    // XP1 moves to beta's), in the base of alpha's FP1, its inline form's.
    assert_eq!(bases("alpha.dat", "XP1"), ["BASE_DATA[1]"]);
    assert!(of("alpha.dat", "XP1").usage.lines.is_empty());
    assert_eq!(bases("alpha.dat", "XOWN"), ["BASE_DATA[1]"]);
    assert_eq!(bases("beta.dat", "XP1"), ["BASE_DATA[2]"]);
    // Each module's own setfr; delta's GLOBAL DEF from gamma.
    assert_eq!(bases("gamma.dat", "XG1"), ["BASE_DATA[1]"]);
    assert_eq!(bases("gamma.dat", "XG3"), ["BASE_DATA[3]"]);
    // delta's GLOBAL point is seen from beta, its local one is not.
    assert_eq!(bases("delta.dat", "XGLOBAL"), ["BASE_DATA[2]"]);
    assert_eq!(bases("delta.dat", "XLOCAL"), Vec::<String>::new());
    // beta's own XSHARED hides $config.dat's.
    assert_eq!(bases("beta.dat", "XSHARED"), ["BASE_DATA[2]"]);
    assert!(
        all[0]
            .files
            .iter()
            .filter(|f| f.path.ends_with("$config.dat"))
            .flat_map(|f| f.positions())
            .all(|p| p.name.as_deref() != Some("XSHARED")),
        "$config.dat's XSHARED is used by no motion: not the program's"
    );
}

/// A target literal assigned to a name (`pv := [[…]];` in a routine) is a value of that name:
/// the motions that move to `pv` move to it, so it is used as the declaration is (its work
/// object and tool, the motions' lines), where it was "not used by any motion". A literal
/// assigned to a name no target is declared by stays unused.
#[test]
fn a_target_literal_assigned_to_a_name_is_used_as_the_name_is() {
    let (_dir, task) = task(&[(
        "PROGMOD/assign.mod",
        format!(
            "MODULE assign\n\
  TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[1,0,0,0]]];\n\
  VAR robtarget pv:={TARGET};\n\
  VAR num n:=0;\n\
  PROC main()\n\
    pv:=[[700,-100,400],[0,0.707107,0.707107,0],[0,0,-2,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n\
    pOther:=[[600,-100,400],[0,0.707107,0.707107,0],[0,0,-2,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n\
    MoveL pv,v200,fine,tool0\\WObj:=wCar;\n\
  ENDPROC\nENDMODULE\n"
        ),
    )]);
    let all = programs(&task);
    let inline: Vec<Position> = all[0]
        .files
        .iter()
        .flat_map(|f| f.positions())
        .filter(|p| p.name.is_none())
        .collect();
    assert_eq!(inline.len(), 2);
    let declared = target(&all[0], "pv");
    assert_eq!(declared.usage.work_objects().collect::<Vec<_>>(), ["wCar"]);
    assert_eq!(inline[0].usage, declared.usage);
    assert_eq!(&*inline[0].usage.lines, [8]);
    assert!(inline[1].usage.lines.is_empty(), "{:?}", inline[1].usage);
}

/// A loop's body is followed again from the state its end leaves: a base set late in the body
/// holds for the motions before it on the next pass, so `XP1` is used with both bases and
/// refused; after the loop the base is what every way out agrees on (a `WHILE` or `FOR` may
/// run no pass, a `REPEAT` runs one, a `LOOP` is left at its `EXIT`s). A body that sets
/// nothing keeps the one base, and its points are corrected.
#[test]
fn a_base_set_late_in_a_loop_holds_at_its_top() {
    let dat = format!("DEFDAT a1 PUBLIC\nDECL E6POS XP1={P1}\nDECL E6POS XP2={P1}\nENDDAT\n");
    let cell = root().join("samples/cell_rules.toml");
    let run = |body: &str| {
        let src = format!(
            "DEF a1( )\n  INT I\n  BAS (#INITMOV,0 )\n  BAS (#TOOL,1 )\n  BAS (#BASE,1 )\n{body}END\n"
        );
        let (dir, r1) = kss(&[
            ("Program/a1.src", &src),
            ("Program/a1.dat", &dat),
            ("System/$config.dat", CONFIG),
        ]);
        let ps = programs(&r1);
        let u = |n: &str| work_objects(&ps[0], n);
        let bases = (u("XP1"), u("XP2"));
        let (code, out, err) = trackfix(&[
            "correct",
            r1.to_str().unwrap(),
            "--cell",
            cell.to_str().unwrap(),
            "--robot",
            "r1",
            "--diff",
        ]);
        drop(dir);
        (bases, code, out, err)
    };
    let two = || vec!["BASE_DATA[1]".to_owned(), "BASE_DATA[2]".to_owned()];
    let one = |n: u32| vec![format!("BASE_DATA[{n}]")];
    for (body, xp1, xp2) in [
        (
            "  FOR I = 1 TO 3\n    LIN XP1\n    BAS (#BASE,2 )\n    LIN XP2\n  ENDFOR\n",
            two(),
            one(2),
        ),
        (
            "  WHILE $IN[1]\n    LIN XP1\n    BAS (#BASE,2 )\n  ENDWHILE\n  LIN XP2\n",
            two(),
            vec![],
        ),
        (
            "  REPEAT\n    LIN XP1\n    BAS (#BASE,2 )\n  UNTIL $IN[1]\n  LIN XP2\n",
            two(),
            one(2),
        ),
        (
            "  LOOP\n    LIN XP1\n    IF $IN[1] THEN\n      EXIT\n    ENDIF\n    BAS (#BASE,2 )\n  ENDLOOP\n  LIN XP2\n",
            two(),
            vec![],
        ),
        (
            "  FOR I = 1 TO 3\n    WHILE $IN[2]\n      LIN XP2\n    ENDWHILE\n    LIN XP1\n    BAS (#BASE,2 )\n  ENDFOR\n",
            two(),
            two(),
        ),
    ] {
        let ((b1, b2), code, out, err) = run(body);
        assert_eq!((&b1, &b2), (&xp1, &xp2), "{body}");
        assert_eq!(code, 3, "{body}: {err}");
        assert!(out.is_empty(), "{body}: {out}");
        assert!(
            err.contains(
                "a1.dat:2:16: error: E6POS `XP1` is used with two bases (`BASE_DATA[1]` and `BASE_DATA[2]`)"
            ),
            "{body}: {err}"
        );
    }
    let ((b1, b2), code, out, err) = run(
        "  FOR I = 1 TO 3\n    LIN XP1\n    WHILE $IN[1]\n      LIN XP2\n    ENDWHILE\n  ENDFOR\n",
    );
    assert_eq!((b1, b2), (one(1), one(1)));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("+DECL E6POS XP1={X 410.745,"), "{out}");
}

/// A copy is followed however it is made: through another copy (`pw := pv; pv := p1;`, in
/// either order), computed from the target by a function (`Offs`, `RelTool`, `MirPos`, a
/// function of the program whose `RETURN` names it, nested), into an element chosen at run
/// time and moved to by a number, through a whole array copied, into a record's component, and
/// into data of another module moved to there. Each target, also moved to in `wA`, is then used
/// with two work objects (before, each was corrected in `wA` alone).
#[test]
fn copies_are_followed_through_chains_functions_arrays_records_and_modules() {
    let names = [
        "p1", "p2", "p3", "p4", "p5", "p6", "p7", "p8", "p9", "p10", "p11",
    ];
    let mut data = String::from("MODULE D\n");
    for n in names {
        data += &format!("  CONST robtarget {n}:={TARGET};\n");
    }
    data += "  PERS robtarget pShared:=[[0,0,0],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n\
             ENDMODULE\n";
    let main = "MODULE M\n  RECORD ptrec\n    robtarget p;\n    num n;\n  ENDRECORD\n  \
        VAR robtarget pv;\n  VAR robtarget pw;\n  VAR robtarget pa;\n  VAR robtarget pb;\n  \
        VAR robtarget pc;\n  VAR robtarget pd;\n  VAR robtarget arr{2};\n  VAR robtarget a1{2};\n  \
        VAR robtarget a2{2};\n  VAR ptrec rec;\n  VAR num i := 1;\n  \
        FUNC robtarget getP()\n    RETURN p5;\n  ENDFUNC\n  \
        FUNC robtarget id(robtarget p)\n    RETURN p;\n  ENDFUNC\n  \
        PROC r()\n    pw := pv;\n    pv := p1;\n    MoveL pw,v1,fine,tool0\\WObj:=wB;\n    \
        pa := Offs(p2,0,0,10);\n    MoveL pa,v1,fine,tool0\\WObj:=wB;\n    \
        pb := RelTool(MirPos(p3, mp),0,0,10);\n    MoveL pb,v1,fine,tool0\\WObj:=wB;\n    \
        pc := getP();\n    MoveL pc,v1,fine,tool0\\WObj:=wB;\n    \
        pd := Offs(id(p4),0,0,10);\n    MoveL pd,v1,fine,tool0\\WObj:=wB;\n    \
        arr{i} := p6;\n    MoveL arr{2},v1,fine,tool0\\WObj:=wB;\n    \
        a1{1} := p7;\n    a2 := a1;\n    MoveL a2{1},v1,fine,tool0\\WObj:=wB;\n    \
        rec.p := p8;\n    MoveL rec.p,v1,fine,tool0\\WObj:=wB;\n    \
        MoveL RelTool(getP(),0,0,10),v1,fine,tool0\\WObj:=wB;\n    \
        pShared := p9;\n  ENDPROC\n  \
        PROC all()\n    MoveL p1,v1,fine,tool0\\WObj:=wA;\n    MoveL p2,v1,fine,tool0\\WObj:=wA;\n    \
        MoveL p3,v1,fine,tool0\\WObj:=wA;\n    MoveL p4,v1,fine,tool0\\WObj:=wA;\n    \
        MoveL p5,v1,fine,tool0\\WObj:=wA;\n    MoveL p6,v1,fine,tool0\\WObj:=wA;\n    \
        MoveL p7,v1,fine,tool0\\WObj:=wA;\n    MoveL p8,v1,fine,tool0\\WObj:=wA;\n    \
        MoveL p9,v1,fine,tool0\\WObj:=wA;\n    MoveL p10,v1,fine,tool0\\WObj:=wA;\n    \
        MoveL p11,v1,fine,tool0\\WObj:=wA;\n  ENDPROC\nENDMODULE\n"
        .to_owned();
    // A copy into the `PERS` of module M, moved to in module O.
    let other = "MODULE O\n  PROC o()\n    MoveL pShared,v1,fine,tool0\\WObj:=wB;\n    \
        arr{1} := p11;\n  ENDPROC\nENDMODULE\n"
        .to_owned();
    let (_dir, task) = task(&[
        ("PROGMOD/D.mod", data),
        ("PROGMOD/M.mod", main),
        ("PROGMOD/O.mod", other),
    ]);
    let ps = programs(&task);
    for n in ["p1", "p2", "p3", "p4", "p5", "p6", "p7", "p8", "p9"] {
        assert_eq!(work_objects(&ps[0], n), ["wA", "wB"], "{n}");
    }
    // Moved to by nothing but its own motion.
    assert_eq!(work_objects(&ps[0], "p10"), ["wA"]);
    // A copy into `arr{1}` is not what `arr{2}` holds.
    assert_eq!(work_objects(&ps[0], "p11"), ["wA"]);
}

/// What a routine does with its parameter reaches what its callers pass: a function's value
/// (`MoveL id(p1)`, `RETURN Offs(p, …)`, a local copy returned), a composed argument or a
/// function's value passed to a routine that moves its parameter (`mv Offs(p4,…)`, `mv
/// getP()`), a copy of the parameter moved to inside the routine or, written into module data,
/// elsewhere, and an optional parameter given by name (`mv \p:=p8`, or passed on as `inner
/// \p:=q`). Before, each target was corrected in `wA` alone.
#[test]
fn a_routines_use_of_its_parameter_reaches_what_its_callers_pass() {
    let names = ["p1", "p2", "p3", "p4", "p5", "p6", "p7", "p8", "p9"];
    let mut data = String::from("MODULE D\n");
    for n in names {
        data += &format!("  CONST robtarget {n}:={TARGET};\n");
    }
    data += "ENDMODULE\n";
    let mut main = String::from(
        "MODULE M\n  VAR robtarget g;\n  \
        FUNC robtarget id(robtarget p)\n    RETURN p;\n  ENDFUNC\n  \
        FUNC robtarget above(robtarget p)\n    RETURN Offs(p,0,0,100);\n  ENDFUNC\n  \
        FUNC robtarget kept(robtarget p)\n    VAR robtarget q;\n    q := p;\n    RETURN q;\n  ENDFUNC\n  \
        FUNC robtarget getP()\n    RETURN p5;\n  ENDFUNC\n  \
        PROC mv(robtarget p)\n    MoveL p,v1,fine,tool0\\WObj:=wB;\n  ENDPROC\n  \
        PROC sub(robtarget p)\n    VAR robtarget pv;\n    pv := p;\n    MoveL pv,v1,fine,tool0\\WObj:=wB;\n  ENDPROC\n  \
        PROC keep(robtarget p)\n    g := p;\n  ENDPROC\n  \
        PROC opt(\\robtarget p)\n    IF Present(p) MoveL p,v1,fine,tool0\\WObj:=wB;\n  ENDPROC\n  \
        PROC outer(robtarget q)\n    opt \\p:=q;\n  ENDPROC\n  \
        PROC r()\n    MoveL id(p1),v1,fine,tool0\\WObj:=wB;\n    \
        MoveL above(p2),v1,fine,tool0\\WObj:=wB;\n    MoveL kept(p3),v1,fine,tool0\\WObj:=wB;\n    \
        mv Offs(p4,0,0,10);\n    mv getP();\n    sub p6;\n    keep p7;\n    \
        MoveL g,v1,fine,tool0\\WObj:=wB;\n    opt \\p:=p8;\n    outer p9;\n  ENDPROC\n  PROC all()\n",
    );
    for n in names {
        main += &format!("    MoveL {n},v1,fine,tool0\\WObj:=wA;\n");
    }
    main += "  ENDPROC\nENDMODULE\n";
    let (_dir, task) = task(&[("PROGMOD/D.mod", data), ("PROGMOD/M.mod", main)]);
    let ps = programs(&task);
    for n in names {
        assert_eq!(work_objects(&ps[0], n), ["wA", "wB"], "{n}");
    }
}
