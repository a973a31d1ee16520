//! Runtime data: targets whose pose the program computes when it runs (or whose work object or
//! base it computes) are marked, in both languages, by the shared resolution pass.

use std::path::Path;

use trackfix::position::{ParsedFile, RunTimeValue, UseLine};
use trackfix::{krl, rapid};

use crate::support::with_constant_deviation;

fn run_time(f: &ParsedFile, name: &str) -> Option<RunTimeValue> {
    f.positions()
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no target {name}"))
        .usage
        .run_time()
        .cloned()
}

const T: &str = "[[1,2,3],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]]";

#[test]
fn rapid_targets_and_work_objects_computed_at_run_time_are_marked_literal_ones_are_not() {
    let src = format!(
        "MODULE R\n\
  PERS wobjdata wFix:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PERS wobjdata wCalc:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PERS wobjdata wLit:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PERS robtarget pFix:={T};\n\
  PERS robtarget pOnCalc:={T};\n\
  PERS robtarget pOnLit:={T};\n\
  PERS robtarget pBuf{{2}}:=[{T},{T}];\n\
  PERS robtarget pHere:={T};\n\
  PROC main()\n\
    wCalc.uframe:=[[0,0,0],OrientZYX(nAngle,0,0)];\n\
    wLit:=[FALSE,TRUE,\"\",[[900,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
    pBuf{{i}}:=Offs(pFix,0,0,10);\n\
    pHere:=CRobT();\n\
    MoveL pFix,v100,fine,tool0\\WObj:=wFix;\n\
    MoveL pOnCalc,v100,fine,tool0\\WObj:=wCalc;\n\
    MoveL pOnLit,v100,fine,tool0\\WObj:=wLit;\n\
    MoveL pBuf{{i}},v100,fine,tool0\\WObj:=wFix;\n\
    MoveL pHere,v100,fine,tool0\\WObj:=wFix;\n\
  ENDPROC\nENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("r.mod"), src.into_bytes());
    assert_eq!(run_time(&f, "pFix"), None);
    assert_eq!(
        run_time(&f, "pOnCalc"),
        Some(RunTimeValue::Frame {
            name: Some("wCalc".into()),
            at: UseLine::new(11)
        })
    );
    // One literal value is known offline: the frame takes it, with a warning, no refusal.
    assert_eq!(run_time(&f, "pOnLit"), None);
    // Written through a computed index: any element may be the one the program fills.
    for n in ["pBuf{1}", "pBuf{2}"] {
        assert_eq!(
            run_time(&f, n),
            Some(RunTimeValue::Target {
                at: UseLine::new(13)
            }),
            "{n}"
        );
    }
    assert_eq!(
        run_time(&f, "pHere"),
        Some(RunTimeValue::Target {
            at: UseLine::new(14)
        })
    );
}

#[test]
fn krl_bases_and_points_computed_at_run_time_are_marked_constant_bases_are_not() {
    let src = b"DEF k( )\n\
  DECL E6POS XA={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  DECL E6POS XB={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  DECL E6POS XC={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  DECL E6POS XD={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  $BASE=BASE_DATA[2]\n\
  LIN XA\n\
  $BASE=BASE_DATA[NBASE]\n\
  LIN XB\n\
  BAS(#BASE,2)\n\
  XC=$POS_ACT\n\
  LIN XC\n\
  $BASE=EK(MACHINE_DEF[2].ROOT,MACHINE_DEF[2].MECH_TYPE,BASE_DATA[1])\n\
  LIN XD\n\
END\n";
    let f = krl::parse_file(Path::new("k.src"), src.to_vec());
    assert_eq!(run_time(&f, "XA"), None);
    assert_eq!(
        run_time(&f, "XB"),
        Some(RunTimeValue::Frame {
            name: None,
            at: UseLine::new(8)
        })
    );
    assert_eq!(
        run_time(&f, "XC"),
        Some(RunTimeValue::Target {
            at: UseLine::new(11)
        })
    );
    assert_eq!(
        run_time(&f, "XD"),
        Some(RunTimeValue::Frame {
            name: None,
            at: UseLine::new(13)
        })
    );
}

#[test]
fn a_transform_refuses_runtime_data_by_name_and_counts_it_apart() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ek.src");
    std::fs::write(
        &path,
        "DEF ek( )\n  DECL E6POS XD={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n  $BASE=EK(MACHINE_DEF[2].ROOT,MACHINE_DEF[2].MECH_TYPE,BASE_DATA[1])\n  LIN XD\nEND\n",
    )
    .unwrap();
    let file = path.to_str().unwrap();
    let args = [
        "correct",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        file,
        "--diff",
    ];
    let (code, _, err) = crate::support::trackfix(&args);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains(
            "E6POS `XD` is used with a base computed at run time (line 3): not correctable offline"
        ),
        "{err}"
    );
    assert!(err.contains("--keep runtime-data"), "{err}");
    assert!(
        err.contains(
            "note: 1 of the 1 refused target(s) depend on values the program sets when it runs: not correctable offline"
        ),
        "{err}"
    );
    let mut kept = args.to_vec();
    kept.extend(["--keep", "runtime-data"]);
    let (code, out, err) = crate::support::trackfix(&kept);
    assert_ne!(code, 3, "{err}");
    assert!(out.is_empty(), "nothing changes: {out}");
    assert!(err.contains("[runtime-data]"), "{err}");
}

#[test]
fn a_krl_target_that_leaves_out_pose_fields_is_refused_for_what_it_leaves_out() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("part.src");
    std::fs::write(
        &src,
        "DEF part( )\n  DECL E6POS XHALF={X 1,Y 2,Z 3,E1 4200}\n  BAS(#INITMOV,0)\n  BAS(#TOOL,2)\n  BAS(#BASE,3)\n  LIN {Z 500}\n  LIN XHALF\nEND\n",
    )
    .unwrap();
    let (code, _, err) = crate::support::trackfix(&[
        "correct",
        src.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--diff",
    ]);
    assert_eq!(code, 3, "{err}");
    // Inline: the fields left out are the robot's when the motion runs.
    assert!(
        err.contains("part.src:6:7: error: inline E6POS leaves out X, Y, A, B, C: the controller takes them from where the robot is when the motion runs"),
        "{err}"
    );
    assert!(err.contains("leave it as written [runtime-data]"), "{err}");
    // Declared: whatever the variable held before.
    assert!(
        err.contains(
            "part.src:2:20: error: E6POS `XHALF` leaves out A, B, C: its pose is not known whole"
        ),
        "{err}"
    );
    assert!(err.contains("leave it as written [expression]"), "{err}");
}

/// Messages on a target name the line of a use in another file together with that file: a
/// `.dat` point assigned, used with a computed base or added as an offset in its `.src`.
#[test]
fn a_use_in_the_other_file_of_a_pair_is_named_with_its_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("cell.dat"),
        "DEFDAT cell\n\
  DECL E6POS XA={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  DECL E6POS XB={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  DECL E6POS XOFF={X 0,Y 0,Z 9,A 0,B 0,C 0,E1 0}\n\
ENDDAT\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("cell.src"),
        "DEF cell( )\n\
  DECL E6POS XHERE={X 1,Y 2,Z 3,A 0,B 0,C 0,E1 500}\n\
  BAS(#BASE,2)\n\
  XA=$POS_ACT\n\
  LIN XA\n\
  XHERE=$POS_ACT\n\
  LIN XHERE\n\
  $BASE=BASE_DATA[NBASE]\n\
  LIN XB:XOFF\n\
  LIN XB\n\
END\n",
    )
    .unwrap();
    let program = krl::load_program(
        &dir.path().join("cell.src"),
        &trackfix::program::LoadOptions::default(),
    )
    .unwrap();
    let dat = program
        .files
        .iter()
        .find(|f| f.path.ends_with("cell.dat"))
        .unwrap();
    let src = program
        .files
        .iter()
        .find(|f| f.path.ends_with("cell.src"))
        .unwrap();
    let in_src = |line| UseLine {
        line,
        file: Some("cell.src".into()),
    };
    assert_eq!(
        run_time(dat, "XA"),
        Some(RunTimeValue::Target { at: in_src(4) })
    );
    assert_eq!(
        run_time(dat, "XB"),
        Some(RunTimeValue::Frame {
            name: None,
            at: in_src(8)
        })
    );
    // A use in the target's own file: its line alone.
    assert_eq!(
        run_time(src, "XHERE"),
        Some(RunTimeValue::Target {
            at: UseLine::new(6)
        })
    );
    let offset = dat
        .positions()
        .find(|p| p.name.as_deref() == Some("XOFF"))
        .and_then(|p| p.usage.non_position().cloned())
        .unwrap();
    assert_eq!(offset.at, in_src(9));
    assert_eq!(offset.at.to_string(), "line 9 of cell.src");
    assert_eq!(UseLine::new(7).to_string(), "line 7");
}

/// The same in a RAPID task: a target of one module used in another with a work object that
/// module computes, and a world zone's tolerance declared in one module and taken in another.
#[test]
fn a_use_in_another_module_of_a_task_is_named_with_its_module() {
    let dir = tempfile::tempdir().unwrap();
    let progmod = dir.path().join("TASK1").join("PROGMOD");
    std::fs::create_dir_all(&progmod).unwrap();
    std::fs::write(
        progmod.join("A.mod"),
        "MODULE A\n\
  PERS wobjdata wCalc:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PROC main()\n\
    wCalc.uframe:=[[0,0,0],OrientZYX(nAngle,0,0)];\n\
    MoveL pB,v100,fine,tool0\\WObj:=wCalc;\n\
    WZHomeJointDef \\Inside, shHome, jMid, jTol;\n\
  ENDPROC\nENDMODULE\n",
    )
    .unwrap();
    std::fs::write(
        progmod.join("B.mod"),
        format!(
            "MODULE B\n\
  PERS robtarget pB:={T};\n\
  CONST jointtarget jMid:=[[10,-20,30,0,45,0],[4250,9E9,9E9,9E9,9E9,9E9]];\n\
  CONST jointtarget jTol:=[[2,2,2,2,2,2],[5,9E9,9E9,9E9,9E9,9E9]];\n\
  VAR shapedata shHome;\nENDMODULE\n"
        ),
    )
    .unwrap();
    let task = dir.path().join("TASK1");
    let (code, _, err) = crate::support::trackfix(&[
        "correct",
        task.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--diff",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("B.mod:2:20: error: robtarget `pB` is used with `wCalc`, which is computed at run time (line 4 of A.mod)"),
        "{err}"
    );
    assert!(
        err.contains("B.mod:4:25: note: jointtarget `jTol` is the `DeltaJointVal` of `WZHomeJointDef` on line 6 of A.mod"),
        "{err}"
    );
}

/// A program that offsets the external axes (`EOffsSet`) moves the track to the written
/// position plus an offset known only when it runs: every target a motion uses while the
/// offset may be active is refused as runtime data, the instruction and its line named; one
/// moved to before it (`main` ending with the offset ended) or no motion uses is not marked.
#[test]
fn a_program_that_offsets_the_external_axes_has_its_targets_refused_by_name() {
    let src = format!(
        "MODULE eo\n\
  CONST extjoint eShift:=[2000,9E9,9E9,9E9,9E9,9E9];\n\
  CONST robtarget pa:={T};\n\
  CONST robtarget pIdle:={T};\n\
  CONST jointtarget jHome:=[[0,0,0,0,90,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n\
  PROC main()\n\
    MoveAbsJ jHome,v200,fine,tool0;\n\
    eoffsset eShift;\n\
    MoveL pa,v200,fine,tool0;\n\
    EOffsOff;\n\
  ENDPROC\nENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("eo.mod"), src.into_bytes());
    let why = RunTimeValue::AxesOffset {
        instruction: "EOffsSet",
        at: UseLine::new(8),
    };
    let offset = Some(why.clone());
    assert_eq!(run_time(&f, "pa"), offset);
    assert_eq!(run_time(&f, "jHome"), None);
    assert_eq!(run_time(&f, "pIdle"), None);
    assert_eq!(
        why.describe(),
        "is moved to by a program that offsets the external axes (`EOffsSet`, line 8): its skid when it runs is not the one written"
    );
}

/// What the offset does not reach: a `MoveAbsJ …\NoEOffs` moves the axes to the values
/// written, and `EOffsSet` of a literal of zeros (and 9E9 for an axis not there) offsets
/// nothing.
#[test]
fn motions_that_ignore_the_axes_offset_and_an_offset_of_zeros_are_not_marked() {
    let module = |offset: &str| {
        format!(
            "MODULE eo\n\
  CONST robtarget pa:={T};\n\
  CONST jointtarget jPark:=[[0,0,0,0,90,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n\
  CONST jointtarget jBoth:=[[0,0,0,0,90,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n\
  PROC main()\n\
    {offset}\n\
    MoveAbsJ jPark\\NoEOffs,v200,fine,tool0;\n\
    MoveAbsJ jBoth\\NoEOffs,v200,fine,tool0;\n\
    MoveAbsJ jBoth,v200,fine,tool0;\n\
    MoveL pa,v200,fine,tool0;\n\
  ENDPROC\nENDMODULE\n"
        )
    };
    let f = rapid::parse_file(
        Path::new("eo.mod"),
        module("EOffsOn \\ExeP:=pa, pa;").into_bytes(),
    );
    let offset = Some(RunTimeValue::AxesOffset {
        instruction: "EOffsOn",
        at: UseLine::new(6),
    });
    assert_eq!(run_time(&f, "jPark"), None);
    assert_eq!(run_time(&f, "jBoth"), offset);
    assert_eq!(run_time(&f, "pa"), offset);
    for zeros in [
        "EOffsSet [0,0,0,0,0,0];",
        "EOffsSet [ 0, 9E9, 9E+09, 9e9, 0.0, 9E9 ];",
    ] {
        let f = rapid::parse_file(Path::new("eo.mod"), module(zeros).into_bytes());
        for name in ["jPark", "jBoth", "pa"] {
            assert_eq!(run_time(&f, name), None, "{zeros} {name}");
        }
    }
    let f = rapid::parse_file(
        Path::new("eo.mod"),
        module("EOffsSet [0,100,0,0,0,0];").into_bytes(),
    );
    assert!(run_time(&f, "pa").is_some());
}

/// A routine that gives its parameter a computed value (`pOut := CRobT(…)` in `PROC
/// Remember(INOUT robtarget pOut)`) computes the target a call passes there, followed through
/// routines as any use of a parameter; one that only moves to its parameter computes nothing.
#[test]
fn a_target_a_routine_computes_through_its_parameter_is_marked() {
    let src = format!(
        "MODULE io\n\
  PERS robtarget pTaught:={T};\n\
  PERS robtarget pPassed:={T};\n\
  PERS robtarget pMoved:={T};\n\
  PROC main()\n\
    Remember pTaught;\n\
    Relay pPassed;\n\
    GoTo pMoved;\n\
  ENDPROC\n\
  PROC Remember(INOUT robtarget pOut)\n\
    pOut:=CRobT(\\Tool:=tool0);\n\
  ENDPROC\n\
  PROC Relay(INOUT robtarget pOn)\n\
    Remember pOn;\n\
  ENDPROC\n\
  PROC GoTo(robtarget pTo)\n\
    MoveL pTo,v200,fine,tool0;\n\
  ENDPROC\nENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("io.mod"), src.into_bytes());
    let computed = Some(RunTimeValue::Target {
        at: UseLine::new(11),
    });
    assert_eq!(run_time(&f, "pTaught"), computed);
    assert_eq!(run_time(&f, "pPassed"), computed);
    assert_eq!(run_time(&f, "pMoved"), None);
}

/// A program displacement (`PDispOn`, `PDispSet`) moves the frame every Cartesian motion is
/// reached in: their targets are refused as runtime data; a joint target reached by
/// `MoveAbsJ`, which no displacement moves, is not, and a displacement of the identity moves
/// nothing.
#[test]
fn a_program_displacement_marks_the_cartesian_targets_it_moves() {
    let module = |disp: &str| {
        format!(
            "MODULE pd\n\
  CONST robtarget pa:={T};\n\
  CONST jointtarget jHome:=[[0,0,0,0,90,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n\
  PROC main()\n\
    {disp}\n\
    MoveL pa,v200,fine,tool0;\n\
    MoveAbsJ jHome,v200,fine,tool0;\n\
    PDispOff;\n\
  ENDPROC\nENDMODULE\n"
        )
    };
    let f = rapid::parse_file(
        Path::new("pd.mod"),
        module("PDispOn \\ExeP:=pa, pa, tool0;").into_bytes(),
    );
    let why = RunTimeValue::ProgramDisplacement {
        instruction: "PDispOn",
        at: UseLine::new(5),
    };
    assert_eq!(run_time(&f, "pa"), Some(why.clone()));
    assert_eq!(run_time(&f, "jHome"), None);
    assert_eq!(
        why.describe(),
        "is moved to by a program that displaces its motions (`PDispOn`, line 5): the frame it is reached in is not its work object's"
    );
    let f = rapid::parse_file(
        Path::new("pd.mod"),
        module("PDispSet [[0,0,0],[1,0,0,0]];").into_bytes(),
    );
    assert_eq!(run_time(&f, "pa"), None);
    let f = rapid::parse_file(
        Path::new("pd.mod"),
        module("PDispSet [[0,0,50],[1,0,0,0]];").into_bytes(),
    );
    assert!(run_time(&f, "pa").is_some());
}

/// Which of `targets` a module moving to them in `routines` refuses as displaced (a program
/// displacement or an axes offset): for each, the instruction named and its line, `None` where
/// it is not refused. A name starting with `j` is a jointtarget, any other a robtarget; the
/// module declares the displacement `dWeld` and the axes offset `eShift`. And the module's
/// text.
fn displaced(targets: &[&str], routines: &str) -> (Vec<Option<(&'static str, usize)>>, String) {
    let mut src = String::from(
        "MODULE pd\n  CONST pose dWeld:=[[0,0,50],[1,0,0,0]];\n  CONST extjoint eShift:=[2000,9E9,9E9,9E9,9E9,9E9];\n",
    );
    for t in targets {
        src += &match t.starts_with('j') {
            true => {
                format!("  CONST jointtarget {t}:=[[0,0,0,0,90,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n")
            }
            false => format!("  CONST robtarget {t}:={T};\n"),
        };
    }
    src += routines;
    src += "ENDMODULE\n";
    let f = rapid::parse_file(Path::new("pd.mod"), src.clone().into_bytes());
    let found = targets
        .iter()
        .map(|t| match run_time(&f, t) {
            None => None,
            Some(
                RunTimeValue::ProgramDisplacement { instruction, at }
                | RunTimeValue::AxesOffset { instruction, at },
            ) => {
                assert_eq!(at.file, None, "{t}");
                Some((instruction, at.line))
            }
            Some(other) => panic!("{t}: {other:?}"),
        })
        .collect();
    (found, src)
}

/// The 1-based number of the first line of `src` that holds `needle`.
fn line_of(src: &str, needle: &str) -> usize {
    src.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// A routine that sets a displacement and ends it (`PDispSet … PDispOff`) refuses the targets
/// of the motions between, its own and those of the routines it calls there, and not those of
/// the rest of the task (before, every Cartesian target of the task was refused); a
/// `MoveAbsJ`, which no program displacement moves, is not refused either.
#[test]
fn a_displacement_refuses_only_the_motions_that_may_run_while_it_is_active() {
    let targets = ["pBefore", "pIn", "pSeam", "jIn", "pAfter", "pOther"];
    let (found, src) = displaced(
        &targets,
        "  PROC main()\n    MoveL pBefore,v200,fine,tool0;\n    weld;\n    MoveL pAfter,v200,fine,tool0;\n    other;\n  ENDPROC\n  PROC weld()\n    PDispSet dWeld;\n    MoveL pIn,v200,fine,tool0;\n    seam;\n    MoveAbsJ jIn,v200,fine,tool0;\n    PDispOff;\n  ENDPROC\n  PROC seam()\n    MoveL pSeam,v200,fine,tool0;\n  ENDPROC\n  PROC other()\n    MoveL pOther,v200,fine,tool0;\n  ENDPROC\n",
    );
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, set, set, None, None, None]);
}

/// A routine called both while a displacement is active and while none is moves to its
/// targets displaced once: they are refused. A target passed to a routine's parameter is
/// refused when the routine's motion may be displaced, whichever call passed it; one passed to
/// a routine only called undisplaced is not.
#[test]
fn a_routine_called_while_displaced_once_has_its_targets_refused_for_every_call() {
    let targets = ["pApp", "pA", "pB", "pC"];
    let (found, src) = displaced(
        &targets,
        "  PROC main()\n    approach;\n    go pA;\n    stay pC;\n    PDispSet dWeld;\n    approach;\n    go pB;\n    PDispOff;\n  ENDPROC\n  PROC approach()\n    MoveL pApp,v200,fine,tool0;\n  ENDPROC\n  PROC go(robtarget p)\n    MoveL p,v200,fine,tool0;\n  ENDPROC\n  PROC stay(robtarget p)\n    MoveL p,v200,fine,tool0;\n  ENDPROC\n",
    );
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [set, set, set, None]);
}

/// A routine that returns with the displacement it set still active displaces its caller's
/// motions after the call, up to the `PDispOff`; and since `main` runs again once it ends, a
/// `main` that never ends it displaces its first motions too (from the second cycle on).
#[test]
fn a_displacement_left_active_by_a_routine_displaces_its_callers_motions_after_the_call() {
    let routines = "  PROC main()\n    MoveL p1,v200,fine,tool0;\n    setDisp;\n    MoveL p2,v200,fine,tool0;\n    PDispOff;\n    MoveL p3,v200,fine,tool0;\n  ENDPROC\n  PROC setDisp()\n    PDispSet dWeld;\n  ENDPROC\n";
    let (found, src) = displaced(&["p1", "p2", "p3"], routines);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, set, None]);
    let never_ended = routines.replace("    PDispOff;\n", "");
    let (found, src) = displaced(&["p1", "p2", "p3"], &never_ended);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [set, set, set]);
}

/// A loop that sets the displacement after its first motion and ends it at the bottom of its
/// body: every way to that motion (into the loop, or round again past the `PDispOff`) has none
/// active, so its target is not refused; when the end is only on one branch, the next pass
/// may start displaced.
#[test]
fn a_loop_that_ends_its_displacement_at_the_bottom_starts_each_pass_undisplaced() {
    let routines = "  PROC main()\n    WHILE TRUE DO\n      MoveL p1,v200,fine,tool0;\n      PDispSet dWeld;\n      MoveL p2,v200,fine,tool0;\n      PDispOff;\n    ENDWHILE\n  ENDPROC\n";
    let (found, src) = displaced(&["p1", "p2"], routines);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, set]);
    let sometimes = routines.replace("PDispOff;", "IF bDone PDispOff;");
    let (found, src) = displaced(&["p1", "p2"], &sometimes);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [set, set]);
}

/// The external axes offset likewise: the track's targets moved to while `EOffsSet` may hold,
/// a joint target's too, are refused naming it; those moved to before it, and a `MoveAbsJ
/// …\NoEOffs` (which moves the axes to the values written), are not.
#[test]
fn an_axes_offset_refuses_only_the_motions_that_may_run_while_it_is_active() {
    let targets = ["jPark", "pFree", "pShifted", "jShifted", "jOwn"];
    let (found, src) = displaced(
        &targets,
        "  PROC main()\n    MoveAbsJ jPark,v200,fine,tool0;\n    MoveL pFree,v200,fine,tool0;\n    shift;\n  ENDPROC\n  PROC shift()\n    EOffsSet eShift;\n    MoveL pShifted,v200,fine,tool0;\n    MoveAbsJ jShifted,v200,fine,tool0;\n    MoveAbsJ jOwn\\NoEOffs,v200,fine,tool0;\n    EOffsOff;\n  ENDPROC\n",
    );
    let set = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
    assert_eq!(found, [None, None, set, set, None]);
}

/// An interrupt runs its `TRAP` between any two statements of the task: a `TRAP` that returns
/// with a displacement active displaces every motion of the task after it (refused naming
/// the `TRAP`'s instruction, as every target was before); one that ends it before it returns
/// displaces its own motions only.
#[test]
fn a_trap_that_leaves_a_displacement_active_displaces_the_whole_task() {
    let routines = "  PROC main()\n    MoveL pMain,v200,fine,tool0;\n    MoveAbsJ jMain,v200,fine,tool0;\n  ENDPROC\n  TRAP service\n    PDispSet dWeld;\n    MoveL pTrap,v200,fine,tool0;\n  ENDTRAP\n";
    let targets = ["pMain", "jMain", "pTrap"];
    let (found, src) = displaced(&targets, routines);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [set, None, set]);
    let ended = routines.replace("  ENDTRAP", "    PDispOff;\n  ENDTRAP");
    let (found, src) = displaced(&targets, &ended);
    let set = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, None, set]);
}

/// Calls trackfix cannot follow to a routine: one no module given defines (an instruction of
/// the controller, or a routine of a module not given) neither sets nor ends a displacement,
/// so one active before stays active after it and none becomes active; one that names its
/// routine at run time (`%"set" + "Disp"%`) may run any `PROC` whose name starts so, so it
/// leaves the displacement `setDisp` sets possibly active, and a `PROC` it may run while one is
/// active is displaced.
#[test]
fn calls_to_routines_not_given_or_named_at_run_time() {
    let (found, src) = displaced(
        &["p1", "p2", "p3", "p4"],
        "  PROC main()\n    MoveL p1,v200,fine,tool0;\n    PDispSet dWeld;\n    Unknown;\n    MoveL p2,v200,fine,tool0;\n    PDispOff;\n    Unknown;\n    MoveL p3,v200,fine,tool0;\n    %\"set\" + \"Disp\"%;\n    MoveL p4,v200,fine,tool0;\n    PDispOff;\n  ENDPROC\n  PROC setDisp()\n    PDispSet dFar;\n  ENDPROC\n",
    );
    let in_main = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    let in_set_disp = Some(("PDispSet", line_of(&src, "PDispSet dFar")));
    assert_eq!(found, [None, in_main, None, in_set_disp]);
    let (found, src) = displaced(
        &["p5"],
        "  PROC main()\n    PDispSet dWeld;\n    %\"m\" + \"v\"%;\n    PDispOff;\n  ENDPROC\n  PROC mv()\n    MoveL p5,v200,fine,tool0;\n  ENDPROC\n",
    );
    assert_eq!(found, [Some(("PDispSet", line_of(&src, "PDispSet dWeld")))]);
}

/// A KRL point taught in the `.dat` with the track at 1500 mm, as `DECL E6POS {name}={…}`.
fn krl_point(name: &str) -> String {
    format!(
        "DECL E6POS {name}={{X 410.0,Y -95.0,Z 230.0,A 180.0,B 0.0,C 180.0,S 6,T 27,E1 1500.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}\n"
    )
}

/// Writes `cell.src` and a `cell.dat` declaring `points` into `dir`; returns the `.src`.
fn krl_pair(dir: &Path, src: &str, points: &[&str]) -> std::path::PathBuf {
    let dat: String = points.iter().map(|p| krl_point(p)).collect();
    std::fs::write(dir.join("cell.dat"), format!("DEFDAT cell\n{dat}ENDDAT\n")).unwrap();
    std::fs::write(dir.join("cell.src"), src).unwrap();
    dir.join("cell.src")
}

/// The KRL form of the routine that computes the point its caller passes: `pOut = $POS_ACT` in
/// `DEF Remember(pOut:OUT)` writes into the caller's `XP5` (an `:OUT` parameter is the caller's
/// variable), so `XP5` is refused as runtime data, the assignment's line and file named, and
/// kept byte for byte when the refusal is kept; so is a point passed on through another
/// routine's `:OUT` parameter, and one whose component the routine sets (`p.X = 5`). A point
/// the program only moves to is corrected.
#[test]
fn a_krl_point_a_routine_computes_through_its_out_parameter_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let src = krl_pair(
        dir.path(),
        "DEF cell( )\n\
  BAS(#INITMOV,0)\n\
  BAS(#BASE,1)\n\
  BAS(#TOOL,1)\n\
  LIN XP5\n\
  LIN XP6\n\
  LIN XP7\n\
  LIN XP8\n\
  Remember(XP5)\n\
  Relay(XP6)\n\
  Nudge(XP7)\n\
END\n\
\n\
DEF Remember(pOut:OUT)\n\
  DECL E6POS pOut\n\
  pOut = $POS_ACT\n\
END\n\
\n\
DEF Relay(pOn:OUT)\n\
  DECL E6POS pOn\n\
  Remember(pOn)\n\
END\n\
\n\
DEF Nudge(p:OUT)\n\
  DECL E6POS p\n\
  p.X = 5\n\
END\n",
        &["XP5", "XP6", "XP7", "XP8"],
    );
    let program = krl::load_program(&src, &trackfix::program::LoadOptions::default()).unwrap();
    let dat = program
        .files
        .iter()
        .find(|f| f.path.ends_with("cell.dat"))
        .unwrap();
    let in_src = |line| {
        Some(RunTimeValue::Target {
            at: UseLine {
                line,
                file: Some("cell.src".into()),
            },
        })
    };
    assert_eq!(run_time(dat, "XP5"), in_src(16));
    assert_eq!(run_time(dat, "XP6"), in_src(16));
    assert_eq!(run_time(dat, "XP7"), in_src(26));
    assert_eq!(run_time(dat, "XP8"), None);

    let src = src.to_str().unwrap();
    let args = [
        "correct",
        src,
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
    ];
    let (code, _, err) = crate::support::trackfix(&args);
    assert_eq!(code, 3, "{err}");
    for (name, at, line) in [("XP5", 2, 16), ("XP6", 3, 16), ("XP7", 4, 26)] {
        assert!(
            err.contains(&format!(
                "cell.dat:{at}:16: error: E6POS `{name}` is given a computed value at run time (line {line} of cell.src): not correctable offline"
            )),
            "{name}: {err}"
        );
    }
    assert!(err.contains("[runtime-data]"), "{err}");
    assert!(
        err.contains(
            "note: 3 of the 3 refused target(s) depend on values the program sets when it runs: not correctable offline"
        ),
        "{err}"
    );

    let out = dir.path().join("out");
    let mut kept = args.to_vec();
    kept.extend(["--keep", "runtime-data", "--out-dir", out.to_str().unwrap()]);
    let (code, _, err) = crate::support::trackfix(&kept);
    assert_eq!(code, 4, "{err}");
    let written = std::fs::read_to_string(out.join("cell.dat")).unwrap();
    for name in ["XP5", "XP6", "XP7"] {
        assert!(written.contains(&krl_point(name)), "{name}: {written}");
    }
    assert!(!written.contains(&krl_point("XP8")), "{written}");
}

/// An `:IN` parameter is a copy: a routine that gives it a computed value, or passes it on to
/// a routine that does, leaves the caller's point as taught, and a module point of the
/// parameter's name is not the parameter. Those points are corrected.
#[test]
fn a_krl_in_parameter_given_a_computed_value_leaves_the_callers_point_taught() {
    let dir = tempfile::tempdir().unwrap();
    let src = krl_pair(
        dir.path(),
        "DEF cell( )\n\
  BAS(#INITMOV,0)\n\
  BAS(#BASE,1)\n\
  BAS(#TOOL,1)\n\
  LIN XP3\n\
  LIN XP4\n\
  LIN PIN\n\
  Copy(XP3)\n\
  CopyOn(XP4)\n\
END\n\
\n\
DEF Copy(pIn:IN)\n\
  DECL E6POS pIn\n\
  pIn = $POS_ACT\n\
END\n\
\n\
DEF CopyOn(pIn:IN)\n\
  DECL E6POS pIn\n\
  Remember(pIn)\n\
END\n\
\n\
DEF Remember(pOut:OUT)\n\
  DECL E6POS pOut\n\
  pOut = $POS_ACT\n\
END\n",
        &["XP3", "XP4", "PIN"],
    );
    let program = krl::load_program(&src, &trackfix::program::LoadOptions::default()).unwrap();
    let dat = program
        .files
        .iter()
        .find(|f| f.path.ends_with("cell.dat"))
        .unwrap();
    for name in ["XP3", "XP4", "PIN"] {
        assert_eq!(run_time(dat, name), None, "{name}");
    }
    let out = dir.path().join("out");
    let (code, _, err) = crate::support::trackfix(&[
        "correct",
        src.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("cell.dat: 3 target(s) changed"), "{err}");
    let written = std::fs::read_to_string(out.join("cell.dat")).unwrap();
    for name in ["XP3", "XP4", "PIN"] {
        assert!(!written.contains(&krl_point(name)), "{name}: {written}");
    }
}

/// A KSS tree `KRC/R1` in a new folder: `$config.dat` with bases 1 and 2 and tool 1, and the
/// program `a1` whose `.src` is `src`, moving to `XP1` and `XP2`; returns the folder and the tree.
fn kss_a1(src: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let r1 = dir.path().join("KRC/R1");
    std::fs::create_dir_all(r1.join("System")).unwrap();
    std::fs::create_dir_all(r1.join("Program")).unwrap();
    std::fs::write(
        r1.join("System/$config.dat"),
        "DEFDAT $CONFIG PUBLIC\n\
DECL GLOBAL FRAME TOOL_DATA[16]\n\
TOOL_DATA[1]={X 0.0,Y 0.0,Z 245.0,A 0.0,B 0.0,C 0.0}\n\
DECL GLOBAL FRAME BASE_DATA[32]\n\
BASE_DATA[1]={X 2150.0,Y -1480.0,Z 720.0,A 0.0,B 0.0,C 0.0}\n\
BASE_DATA[2]={X 1000.0,Y 500.0,Z 0.0,A 90.0,B 0.0,C 0.0}\n\
ENDDAT\n",
    )
    .unwrap();
    let dat = format!(
        "DEFDAT  a1 PUBLIC\n{}{}ENDDAT\n",
        krl_point("XP1"),
        krl_point("XP2")
    );
    std::fs::write(r1.join("Program/a1.dat"), dat).unwrap();
    std::fs::write(r1.join("Program/a1.src"), src).unwrap();
    (dir, r1)
}

/// `BAS(#BASE,1)` reads `BASE_DATA[1]` as it is when it runs: a program that overwrites the
/// whole element (a copy of another, a literal of another value, a tool alike) has the targets
/// moved to with it refused as runtime data, the assignment's line and file named, nothing
/// written, as one that sets a component; `BASE_DATA[3] = …` leaves base 1 alone, and a program
/// that assigns none, or gives base 1 the value `$config.dat` declares (in other digits), is
/// corrected alike.
#[test]
fn a_krl_base_or_tool_the_program_overwrites_refuses_its_targets() {
    let program = |assign: &str| {
        format!(
            "DEF a1( )\n  BAS (#INITMOV,0 )\n  BAS (#TOOL,1 )\n{assign}  BAS (#BASE,1 )\n  LIN XP1\n  LIN XP2\nEND\n"
        )
    };
    let correct = |r1: &Path| {
        crate::support::trackfix(&[
            "correct",
            r1.to_str().unwrap(),
            "--cell",
            "samples/cell_rules.toml",
            "--robot",
            "r1",
            "--diff",
        ])
    };
    let computed = "which is computed at run time";
    let literal = "which the program gives another value than its declaration";
    for (assign, frame, why) in [
        ("  BASE_DATA[1] = BASE_DATA[2]\n", "BASE_DATA[1]", computed),
        (
            "  BASE_DATA[1] = {X 1000.0,Y 500.0,Z 0.0,A 90.0,B 0.0,C 0.0}\n",
            "BASE_DATA[1]",
            literal,
        ),
        (
            "  TOOL_DATA[1] = {X 0.0,Y 0.0,Z 300.0}\n",
            "TOOL_DATA[1]",
            literal,
        ),
        ("  BASE_DATA[1].X = 2000.0\n", "BASE_DATA[1]", computed),
    ] {
        let (_dir, r1) = kss_a1(&program(assign));
        let before = std::fs::read(r1.join("Program/a1.dat")).unwrap();
        let (code, out, err) = correct(&r1);
        assert_eq!(code, 3, "{assign}: {err}");
        assert!(out.is_empty(), "{assign}: {out}");
        for (name, line) in [("XP1", 2), ("XP2", 3)] {
            assert!(
                err.contains(&format!(
                    "a1.dat:{line}:16: error: E6POS `{name}` is used with `{frame}`, {why} (line 4 of a1.src): not correctable offline"
                )),
                "{assign}: {err}"
            );
        }
        assert!(
            err.contains(
                "note: 2 of the 2 refused target(s) depend on values the program sets when it runs: not correctable offline"
            ),
            "{assign}: {err}"
        );
        assert_eq!(std::fs::read(r1.join("Program/a1.dat")).unwrap(), before);
    }
    for assign in [
        "",
        "  BASE_DATA[3] = BASE_DATA[2]\n",
        "  BASE_DATA[1] = {X 2150,Y -1480.000,Z 720,A 0,B 0.0,C 0}\n",
    ] {
        let (_dir, r1) = kss_a1(&program(assign));
        let (code, out, err) = correct(&r1);
        assert_eq!(code, 0, "{assign}: {err}");
        assert!(
            out.contains("+DECL E6POS XP1={X 410.745,Y -93.483,Z 228.198,"),
            "{assign}: {out}"
        );
    }
}

/// A frame the program gives a whole literal value other than its declaration (the way
/// generated programs set their work objects before they move): with one such value, given
/// in the module that declares the frame, the targets are corrected in that value — byte for
/// byte as if the declaration held it — and the assignment is warned about; with two values
/// the flow decides, and the targets are refused by name. An assignment of the declared value
/// (written with other digits) changes nothing and is not reported.
#[test]
fn a_frame_the_program_gives_one_other_value_is_used_two_values_are_refused() {
    use trackfix::geometry::pose_xyz_deg;
    use trackfix::position::Program;
    use trackfix::transform::{Direction, RefusalKind, apply, track_correction};
    // A deviation that turns: a work object placed elsewhere gives another correction.
    let d = pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05);
    with_constant_deviation(d, |setup| {
        let zero = "[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]";
        let v = "[FALSE,TRUE,\"\",[[2100,-1350,480],[0.965925826,0,0,0.258819045]],[[10,20,0],[1,0,0,0]]]";
        let v_digits = "[FALSE,TRUE,\"\",[[2100.000,-1350.000,480.000],[0.965925826,0,0,0.258819045]],[[10.0,20.0,0],[1,0,0,0]]]";
        let v2 = "[FALSE,TRUE,\"\",[[2200,-1350,480],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]";
        let module = |decl: &str, main: &str, other: &str| {
            format!(
                "MODULE M\n  PERS wobjdata wCar:={decl};\n  CONST robtarget p10:=[[-1702.5,-320,225],[0,0.707107,0.707107,0],[-1,0,-1,0],[400,9E9,9E9,9E9,9E9,9E9]];\n  \
                 PROC main()\n{main}    MoveL p10,v100,fine,tool0\\WObj:=wCar;\n  ENDPROC\n  PROC other()\n{other}  ENDPROC\nENDMODULE\n"
            )
        };
        let assign = |value: &str| format!("    wCar:={value};\n");
        let correct = |src: &str| {
            let program = Program {
                files: vec![rapid::parse_file(
                    Path::new("m.mod"),
                    src.as_bytes().to_vec(),
                )],
            };
            let result = apply(
                &program,
                track_correction(&program, setup, Direction::Correct),
            )
            .unwrap();
            let out = String::from_utf8(result.files[0].output.clone()).unwrap();
            let p10 = out
                .lines()
                .find(|l| l.contains("p10:="))
                .unwrap()
                .to_owned();
            let refused: Vec<(String, RefusalKind, String)> = result
                .refusals()
                .map(|r| (r.target.clone(), r.kind, r.message.clone()))
                .collect();
            let warnings: Vec<String> = program.files[0]
                .diagnostics
                .iter()
                .map(|d| d.message.clone())
                .collect();
            (p10, refused, warnings)
        };

        let (declared, refused, warnings) = correct(&module(v, "", ""));
        assert!(
            refused.is_empty() && warnings.is_empty(),
            "{refused:?} {warnings:?}"
        );
        let (in_zero, ..) = correct(&module(zero, "", ""));
        assert_ne!(
            declared, in_zero,
            "the work object's value must matter here"
        );

        let (assigned, refused, warnings) = correct(&module(zero, &assign(v), ""));
        assert_eq!(assigned, declared);
        assert!(refused.is_empty(), "{refused:?}");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].starts_with(
                "work object `wCar` is given another value here than its declaration on line 2: trackfix uses this value"
            ),
            "{}",
            warnings[0]
        );

        let (same, refused, warnings) = correct(&module(v, &assign(v_digits), ""));
        assert_eq!(same, declared);
        assert!(
            refused.is_empty() && warnings.is_empty(),
            "{refused:?} {warnings:?}"
        );

        for (main, other, line) in [
            (assign(v), assign(v2), 5),
            // The declared value given back elsewhere is a second value as well.
            (assign(v), assign(zero), 5),
        ] {
            let src = module(zero, &main, &other);
            let (kept, refused, warnings) = correct(&src);
            let f = rapid::parse_file(Path::new("m.mod"), src.clone().into_bytes());
            assert_eq!(
                run_time(&f, "p10"),
                Some(RunTimeValue::FrameAssigned {
                    name: "wCar".into(),
                    at: UseLine::new(line)
                })
            );
            assert_eq!(kept, src.lines().find(|l| l.contains("p10:=")).unwrap());
            assert_eq!(refused.len(), 1, "{refused:?}");
            assert_eq!(refused[0].1, RefusalKind::RuntimeData);
            assert!(
                refused[0].2.contains(
                    "is used with `wCar`, which the program gives another value than its declaration (line 5)"
                ),
                "{}",
                refused[0].2
            );
            assert!(
                warnings
                    .iter()
                    .all(|w| w.contains("the targets moved with it are left as written")),
                "{warnings:?}"
            );
        }
    })
}

/// `correct` of a RAPID task (modules named and written) with a deviation that turns, by the
/// library: the line declaring `p1` in each output module that has one, and the refusals as
/// (target, kind, message).
fn correct_task(
    modules: &[(&str, String)],
) -> (
    Vec<String>,
    Vec<(String, trackfix::transform::RefusalKind, String)>,
) {
    correct_task_lines(modules, "p1:=")
}

/// [`correct_task`], with the first line holding `pattern` in each output module that has one.
fn correct_task_lines(
    modules: &[(&str, String)],
    pattern: &str,
) -> (
    Vec<String>,
    Vec<(String, trackfix::transform::RefusalKind, String)>,
) {
    use trackfix::geometry::pose_xyz_deg;
    use trackfix::position::Program;
    use trackfix::transform::{Direction, apply, track_correction};
    let d = pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05);
    with_constant_deviation(d, |setup| {
        let program = Program {
            files: rapid::parse_task(
                modules
                    .iter()
                    .map(|(n, t)| (std::path::PathBuf::from(n), t.as_bytes().to_vec().into()))
                    .collect(),
            ),
        };
        let result = apply(
            &program,
            track_correction(&program, setup, Direction::Correct),
        )
        .unwrap();
        let p1 = result
            .files
            .iter()
            .filter_map(|f| {
                let out = String::from_utf8(f.output.clone()).unwrap();
                Some(out.lines().find(|l| l.contains(pattern))?.to_owned())
            })
            .collect();
        let refused = result
            .refusals()
            .map(|r| (r.target.clone(), r.kind, r.message.clone()))
            .collect();
        (p1, refused)
    })
}

const P1: &str = "  CONST robtarget p1:=[[-1702.5,-320,225],[0,0.707107,0.707107,0],[-1,0,-1,0],[400,9E9,9E9,9E9,9E9,9E9]];\n";
const W_ORIGIN: &str = "[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]";
const W_AWAY: &str =
    "[FALSE,TRUE,\"\",[[2100,-1350,480],[0.965925826,0,0,0.258819045]],[[10,20,0],[1,0,0,0]]]";

/// A frame name means, where a motion uses it, the routine's own declaration, else its
/// module's, else one not `LOCAL` of another module: a routine's parameter or own data of the
/// frame's name, assigned, leaves the module's frame alone; a frame a call passes to a
/// parameter its routine assigns is given a value when the program runs; a `VAR` frame given
/// another value starts from its declaration whenever the program starts, so both values hold
/// at times; a `CONST` one cannot be assigned.
#[test]
fn a_frames_assignments_are_read_where_its_name_means_the_frame() {
    use trackfix::transform::RefusalKind;
    let module = |decl: &str, body: &str| {
        format!(
            "MODULE M\n  {decl}\n{P1}{body}  PROC main()\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n"
        )
    };
    let pers = |v: &str| format!("PERS wobjdata w1:={v};");
    let (at_origin, refused) = correct_task(&[("m.mod", module(&pers(W_ORIGIN), ""))]);
    assert!(refused.is_empty(), "{refused:?}");
    let (away, _) = correct_task(&[("m.mod", module(&pers(W_AWAY), ""))]);
    assert_ne!(at_origin, away);
    // A parameter named `w1`, and a routine's own `w1`, assigned: the module's `w1` is as
    // declared.
    for body in [
        format!("  PROC setw(INOUT wobjdata w1)\n    w1:={W_AWAY};\n  ENDPROC\n"),
        format!("  PROC other()\n    VAR wobjdata w1:={W_ORIGIN};\n    w1:={W_AWAY};\n  ENDPROC\n"),
    ] {
        let (p1, refused) = correct_task(&[("m.mod", module(&pers(W_ORIGIN), &body))]);
        assert!(refused.is_empty(), "{body}{refused:?}");
        assert_eq!(p1, at_origin, "{body}");
    }
    // `setw w1;` passes the frame to a parameter `setw` assigns, whole or in part.
    for write in [format!("wx:={W_AWAY}"), "wx.uframe.trans.x:=100".to_owned()] {
        let body = format!(
            "  PROC setw(INOUT wobjdata wx)\n    {write};\n  ENDPROC\n  PROC first()\n    setw w1;\n  ENDPROC\n"
        );
        let (_, refused) = correct_task(&[("m.mod", module(&pers(W_ORIGIN), &body))]);
        assert_eq!(refused.len(), 1, "{body}{refused:?}");
        assert_eq!(
            (refused[0].1, refused[0].2.as_str()),
            (
                RefusalKind::RuntimeData,
                "robtarget `p1` is used with `w1`, which is computed at run time (line 5): not correctable offline"
            )
        );
    }
    // A written-out value of an element or a component is given, not computed.
    let array = format!("PERS wobjdata wA{{2}}:=[{W_ORIGIN},{W_ORIGIN}];");
    for (write, frame) in [
        (format!("wA{{2}}:={W_AWAY}"), "wA{2}"),
        ("w1.uframe.trans.x:=100".to_owned(), "w1"),
    ] {
        let decl = if frame == "w1" {
            pers(W_ORIGIN)
        } else {
            array.clone()
        };
        let body = format!("  PROC first()\n    {write};\n  ENDPROC\n");
        let (_, refused) = correct_task(&[(
            "m.mod",
            module(&decl, &body).replace("WObj:=w1", &format!("WObj:={frame}")),
        )]);
        assert_eq!(refused.len(), 1, "{write}: {refused:?}");
        assert_eq!(
            refused[0].2,
            format!(
                "robtarget `p1` is used with `{frame}`, which the program gives another value than its declaration (line 5): not correctable offline"
            )
        );
    }
    // A VAR given another value: refused, where a PERS takes the value (`main` gives it before
    // it moves, calling `first`).
    let assign = format!("  PROC first()\n    w1:={W_AWAY};\n  ENDPROC\n");
    let first_then_move = |m: String| m.replace("PROC main()\n", "PROC main()\n    first;\n");
    let (p1, refused) =
        correct_task(&[("m.mod", first_then_move(module(&pers(W_ORIGIN), &assign)))]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(p1, away);
    let var = format!("VAR wobjdata w1:={W_ORIGIN};");
    let (_, refused) = correct_task(&[("m.mod", first_then_move(module(&var, &assign)))]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert!(
        refused[0]
            .2
            .contains("which the program gives another value than its declaration (line 5)"),
        "{refused:?}"
    );
    let f = rapid::parse_file(Path::new("m.mod"), module(&var, &assign).into_bytes());
    assert!(
        f.diagnostics.iter().any(|d| d
            .message
            .contains("a VAR, which starts from its declaration whenever the program starts")),
        "{:?}",
        f.diagnostics
    );
    // A CONST cannot be assigned: an error at the assignment, as the controller gives.
    let f = rapid::parse_file(
        Path::new("m.mod"),
        module(&format!("CONST wobjdata w1:={W_ORIGIN};"), &assign).into_bytes(),
    );
    let errors: Vec<_> = f
        .diagnostics
        .iter()
        .filter(|d| d.severity == trackfix::syntax::Severity::Error)
        .map(|d| (f.lines.line(d.span.start), d.message.as_str()))
        .collect();
    assert_eq!(
        errors,
        [(
            5,
            "work object `w1` is a CONST (line 2): the controller does not let a program give it a value"
        )]
    );
}

/// A `LOCAL` frame is its module's alone, and a routine's own frame its routine's: a target
/// declared where such a frame shadows the name the motion's module means is refused by name,
/// and a target whose module declares no frame of the name takes the one every module sees,
/// whatever the order of the files.
#[test]
fn local_and_routine_frames_are_seen_only_where_they_are_declared() {
    use trackfix::transform::RefusalKind;
    let motion = "  PROC main()\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n";
    let global =
        |v: &str, body: &str| format!("MODULE B\n  PERS wobjdata w1:={v};\n{body}ENDMODULE\n");
    let (seen, refused) = correct_task(&[
        ("m.mod", format!("MODULE M\n{P1}ENDMODULE\n")),
        ("b.mod", global(W_ORIGIN, motion)),
    ]);
    assert!(refused.is_empty(), "{refused:?}");
    let local = format!("MODULE L\n  LOCAL PERS wobjdata w1:={W_AWAY};\nENDMODULE\n");
    for order in [[0, 1, 2], [1, 2, 0], [2, 0, 1]] {
        let modules = [
            ("l.mod", local.clone()),
            ("m.mod", format!("MODULE M\n{P1}ENDMODULE\n")),
            ("b.mod", global(W_ORIGIN, motion)),
        ];
        let task: Vec<_> = order.iter().map(|&i| modules[i].clone()).collect();
        let (p1, refused) = correct_task(&task);
        assert!(refused.is_empty(), "{order:?}: {refused:?}");
        assert_eq!(p1, seen, "{order:?}");
    }
    // The target beside a LOCAL `w1`, moved to from a module that means the global one.
    let (_, refused) = correct_task(&[
        (
            "m.mod",
            format!("MODULE M\n  LOCAL PERS wobjdata w1:={W_AWAY};\n{P1}ENDMODULE\n"),
        ),
        ("b.mod", global(W_ORIGIN, motion)),
    ]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].1, RefusalKind::UnresolvedWorkObject);
    assert_eq!(
        refused[0].2,
        "robtarget `p1` is moved to on line 4 of b.mod with `w1`, which means another declaration there than where the target is declared (a LOCAL one, or a routine's own)"
    );
    // A routine's own `w1`: its motion is refused; another routine's motion means the module's.
    let own = format!(
        "MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\n{P1}  PROC main()\n    VAR wobjdata w1:={W_AWAY};\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n"
    );
    let (_, refused) = correct_task(&[("m.mod", own.clone())]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert!(
        refused[0].2.contains("is moved to on line 6 with `w1`"),
        "{refused:?}"
    );
    let other = own
        .replace("PROC main()\n    VAR", "PROC other()\n    VAR")
        .replace(
            "    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n",
            &format!("  ENDPROC\n{motion}ENDMODULE\n"),
        );
    let (p1, refused) = correct_task(&[("m.mod", other.clone())]);
    assert!(refused.is_empty(), "{other}{refused:?}");
    let (plain, _) = correct_task(&[(
        "m.mod",
        format!("MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\n{P1}{motion}ENDMODULE\n"),
    )]);
    assert_eq!(p1, plain);
}

/// A work object the program gives one other value (a PERS, in its module) is taken at that
/// value for the motions every way to which passes the assignment. A motion that may run while
/// the declared value holds — before the assignment in its routine (`main` runs again and
/// again: the first time with the declared value), in a loop that gives the value after it, in
/// a routine called before and after a routine that gives it, before an `ERROR` handler gives it
/// and `RETRY` runs the motion again — moves to its targets in both values: they are refused as
/// a target used with two work objects is, and the `Offs` of one stays as written with it
/// (before, each was corrected for the value given alone, and a warning said the program gave
/// it before it moved).
#[test]
fn a_motion_that_may_run_before_its_work_object_is_given_a_value_refuses_its_targets() {
    use trackfix::transform::RefusalKind;
    const P2: &str = "  CONST robtarget p2:=[[-1500,-300,225],[0,0.707107,0.707107,0],[-1,0,-1,0],[900,9E9,9E9,9E9,9E9,9E9]];\n";
    let give = format!("w1:={W_AWAY};");
    let mv = |p: &str| format!("MoveL {p},v100,fine,tool0\\WObj:=w1;");
    // (A comment on `p2`'s line where it is not moved to: the lines stay where they are.)
    let module = |routines: &str| {
        let p2 = if routines.contains("p2") {
            P2
        } else {
            "  ! p2\n"
        };
        format!("MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\n{P1}{p2}{routines}ENDMODULE\n")
    };
    let (as_given, _) = correct_task(&[(
        "m.mod",
        module(&format!("  PROC main()\n    {}\n  ENDPROC\n", mv("p1"))).replace(W_ORIGIN, W_AWAY),
    )]);
    // Given before every motion: corrected in the value given, as before.
    let (p1, refused) = correct_task(&[(
        "m.mod",
        module(&format!(
            "  PROC main()\n    {give}\n    {}\n  ENDPROC\n",
            mv("p1")
        )),
    )]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(p1, as_given);
    // `p2` is moved to before the assignment, `p1` only after it.
    let (p1, refused) = correct_task(&[(
        "m.mod",
        module(&format!(
            "  PROC main()\n    {}\n    {give}\n    {}\n  ENDPROC\n",
            mv("p2"),
            mv("p1")
        )),
    )]);
    assert_eq!(p1, as_given);
    assert_eq!(
        refused,
        [(
            "p2".to_owned(),
            RefusalKind::TwoWorkObjects,
            "robtarget `p2` is moved to in two values of work object `w1`: as declared (line 2) and as the program gives it (line 7), since the motion on line 6 may run before the assignment".to_owned()
        )]
    );
    for routines in [
        // The first motion before the assignment, the second after (an `Offs` of it).
        format!(
            "  PROC main()\n    {}\n    {give}\n    MoveL Offs(p1,0,0,10),v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n",
            mv("p1")
        ),
        // Given in the error handler, which runs the motion again.
        format!(
            "  PROC main()\n    {}\n  ERROR\n    {give}\n    RETRY;\n  ENDPROC\n",
            mv("p1")
        ),
        // Given after the motion in a loop: the first pass moves in the declared value.
        format!(
            "  PROC run()\n    WHILE TRUE DO\n      {}\n      {give}\n    ENDWHILE\n  ENDPROC\n  PROC main()\n    run;\n  ENDPROC\n",
            mv("p1")
        ),
        // A routine called before and after the one that gives the value.
        format!(
            "  PROC init()\n    {give}\n  ENDPROC\n  PROC go()\n    {}\n  ENDPROC\n  PROC main()\n    go;\n    init;\n    go;\n  ENDPROC\n",
            mv("p1")
        ),
        // A routine nothing calls gives it: it may run before `main` or after it.
        format!(
            "  PROC init()\n    {give}\n  ENDPROC\n  PROC main()\n    {}\n  ENDPROC\n",
            mv("p1")
        ),
    ] {
        let src = module(&routines);
        let (kept, refused) = correct_task(&[("m.mod", src.clone())]);
        assert_eq!(kept, [P1.trim_end()], "{src}");
        assert_eq!(refused.len(), 1, "{src}{refused:?}");
        assert_eq!(
            (refused[0].0.as_str(), refused[0].1),
            ("p1", RefusalKind::TwoWorkObjects),
            "{src}"
        );
        assert!(
            refused[0].2.starts_with(
                "robtarget `p1` is moved to in two values of work object `w1`: as declared (line 2) and as the program gives it"
            ),
            "{}",
            refused[0].2
        );
    }
    // Given in a routine called first, and the `Offs` of a target left as written stays so.
    let (p1, refused) = correct_task(&[(
        "m.mod",
        module(&format!(
            "  PROC init()\n    {give}\n  ENDPROC\n  PROC main()\n    init;\n    {}\n  ENDPROC\n",
            mv("p1")
        )),
    )]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(p1, as_given);
    // The same across modules: the one that gives the value, and one that gives none (whose
    // statements the flow reads again) and moves before or after the call.
    let init = module(&format!("  PROC init()\n    {give}\n  ENDPROC\n"));
    let caller = |body: &str| format!("MODULE B\n  PROC main()\n{body}  ENDPROC\nENDMODULE\n");
    let after = caller(&format!("    init;\n    {}\n", mv("p1")));
    let (p1, refused) = correct_task(&[("m.mod", init.clone()), ("b.mod", after)]);
    assert!(refused.is_empty(), "{refused:?}");
    assert_eq!(p1, as_given);
    let before = caller(&format!("    {}\n    init;\n", mv("p1")));
    let (_, refused) = correct_task(&[("m.mod", init), ("b.mod", before)]);
    let refused: Vec<_> = refused.iter().map(|r| (r.0.as_str(), r.1)).collect();
    assert_eq!(refused, [("p1", RefusalKind::TwoWorkObjects)]);
    let offs = module(&format!(
        "  PROC main()\n    {}\n    {give}\n    MoveL Offs(p1,0,0,10),v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n",
        mv("p1")
    ));
    let (written, _) = correct_task_lines(&[("m.mod", offs.clone())], "Offs(");
    assert_eq!(
        written,
        ["    MoveL Offs(p1,0,0,10),v100,fine,tool0\\WObj:=w1;"]
    );
    // A mirror in the work object's own plane is the same in both values: the target is
    // mirrored; a plane in world is not, and refuses it.
    use trackfix::position::Program;
    use trackfix::transform::{MirrorSettings, WorldPlane, apply, mirror};
    let program = Program {
        files: vec![rapid::parse_file(
            Path::new("m.mod"),
            offs.as_bytes().to_vec(),
        )],
    };
    let own_plane = apply(&program, mirror(&program, &MirrorSettings::default())).unwrap();
    assert_eq!(own_plane.refusals().count(), 0);
    assert_eq!(own_plane.files[0].changes.len(), 1);
    let world = MirrorSettings {
        world: Some(WorldPlane {
            frame: trackfix::geometry::Pose::identity(),
            frames: Default::default(),
            frames_to: None,
            default_wobj: None,
        }),
        ..MirrorSettings::default()
    };
    let in_world = apply(&program, mirror(&program, &world)).unwrap();
    let refused: Vec<_> = in_world
        .refusals()
        .map(|r| (r.target.as_str(), r.kind))
        .collect();
    assert_eq!(refused, [("p1", RefusalKind::TwoWorkObjects)]);
    let f = rapid::parse_file(Path::new("m.mod"), offs.as_bytes().to_vec());
    let warned: Vec<(usize, &str)> = f
        .diagnostics
        .iter()
        .map(|d| (f.lines.line(d.span.start), d.message.as_str()))
        .collect();
    assert_eq!(
        warned,
        [
            (
                3,
                "target `p1` is moved to with `w1` as declared (line 2) and as the program gives it (line 7): the motion on line 6 may run before the assignment"
            ),
            (
                7,
                "work object `w1` is given another value here than its declaration on line 2: trackfix uses this value, but the motion on line 6 may run before it, while the declared one holds: the targets moved there are left as written, but by a mirror in the work object's own plane"
            ),
        ]
    );
}

/// The sample tool `tGun1` (on r1 of the sample cell it puts `Sp001` and `Sp002` in the
/// configuration they are written with), and the same turned half a turn about its z axis,
/// which puts axis 6 half a turn away: the targets' written configuration does not reach them.
const TOOL_WRITTEN: &str =
    "[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]]";
const TOOL_TURNED: &str =
    "[TRUE,[[12.5,-3.2,412.8],[0,0.258819,0,0.965926]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]]";

/// A module of the sample's `wobj_car` and two of its welds (declared on lines 4 and 5), moved
/// to with tool `tGun` declared `declared`, `Sp001` first; `give` (`tGun:=…;`) between the two
/// motions (line 8, after `Sp001`'s on line 7), or on line 7 before both when `first`.
fn tool_module(declared: &str, give: Option<&str>, first: bool) -> String {
    let give = give.map_or("    ! tGun as declared\n".to_owned(), |v| {
        format!("    tGun:={v};\n")
    });
    let (before, after) = if first {
        (give.as_str(), "    ! (given above)\n")
    } else {
        ("", give.as_str())
    };
    format!(
        "MODULE ToolGiven\n  PERS tooldata tGun:={declared};\n  \
         TASK PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[0.999962,0,0,0.008727]]];\n  \
         CONST robtarget Sp001:=[[-1499.39,-722.85,251.51],[0.001394,-0.982620,-0.185474,-0.007385],[-1,0,-2,0],[150.0,9E+09,9E+09,9E+09,9E+09,9E+09]];\n  \
         CONST robtarget Sp002:=[[-1442.86,-646.25,295.65],[0.003079,0.983580,0.179657,-0.016858],[-1,0,-2,0],[185.8,9E+09,9E+09,9E+09,9E+09,9E+09]];\n  \
         PROC main()\n{before}    MoveL Sp001, v1000, fine, tGun\\WObj:=wobj_car;\n{after}    MoveL Sp002, v1000, fine, tGun\\WObj:=wobj_car;\n  ENDPROC\nENDMODULE\n"
    )
}

/// Runs `trackfix` on module `src` written to a file, with `args` and `-o`: the exit code, the
/// messages and the lines declaring `Sp001` and `Sp002` in the output (none where nothing is
/// written).
fn run_on_module(src: &str, args: &[&str]) -> (i32, String, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("tool.mod"), dir.path().join("out.mod"));
    std::fs::write(&input, src).unwrap();
    let mut all = args.to_vec();
    all.extend([input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let (code, _, err) = crate::support::trackfix(&all);
    let written = std::fs::read_to_string(&out).unwrap_or_default();
    let welds = written
        .lines()
        .filter(|l| l.contains("robtarget Sp00"))
        .map(str::to_owned)
        .collect();
    (code, err, welds)
}

/// A tool the program gives one other value is taken at that value, and a motion that may run
/// while the tool still holds its declared value moves to its targets with both. A track
/// correction does not depend on the tool (it acts on the TCP: `B·D⁻¹·B⁻¹`), so without the
/// robot's kinematics the targets are corrected as before, to the same numbers as with either
/// value; but the joints do: with the robot's kinematics such a target is refused as one moved
/// to in two values of its work object is, and so is it under a mirror of the frames, which
/// writes the tool's mirror image into the assignment only. Before, `Sp001` (moved to before the
/// assignment with the turned tool, in which its written configuration does not reach it) was
/// checked with the value given alone, and corrected.
#[test]
fn a_motion_that_may_run_before_its_tool_is_given_a_value_refuses_its_targets_where_the_tool_matters()
 {
    let correct = ["correct", "--cell", "samples/cell.toml", "--robot", "r1"];
    let (code, err, as_declared) = run_on_module(&tool_module(TOOL_WRITTEN, None, false), &correct);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        as_declared,
        [
            "  CONST robtarget Sp001:=[[-1499.759,-722.058,250.090],[0.001257,-0.982675,-0.185160,-0.007945],[-1,0,-2,0],[150.0,9E+09,9E+09,9E+09,9E+09,9E+09]];",
            "  CONST robtarget Sp002:=[[-1443.265,-645.477,294.280],[0.003215,0.983644,0.179355,-0.016293],[-1,0,-2,0],[185.8,9E+09,9E+09,9E+09,9E+09,9E+09]];",
        ]
    );
    // The turned tool alone: the written configurations do not reach the welds.
    let (code, err, _) = run_on_module(&tool_module(TOOL_TURNED, None, false), &correct);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains(
            "robtarget `Sp001` is written with configuration [-1,0,-2,0], which does not reach it"
        ),
        "{err}"
    );

    // Given before every motion: the motions run with the value given, and are checked with it.
    let given_first = tool_module(TOOL_TURNED, Some(TOOL_WRITTEN), true);
    let (code, err, welds) = run_on_module(&given_first, &correct);
    assert_eq!((code, &welds), (0, &as_declared), "{err}");

    // Given between the motions: `Sp001` runs with either value.
    let between = tool_module(TOOL_TURNED, Some(TOOL_WRITTEN), false);
    let (code, err, welds) = run_on_module(&between, &correct);
    assert_eq!(code, 3, "{err}");
    assert!(welds.is_empty());
    assert!(
        err.contains(
            "tool.mod:4:26: error: robtarget `Sp001` is moved to in two values of tool `tGun`: as declared (line 2) and as the program gives it (line 8), since the motion on line 7 may run before the assignment: its joints depend on the tool, which puts the flange elsewhere in each"
        ),
        "{err}"
    );
    assert!(
        err.contains("--keep two-work-objects to leave it as written [two-work-objects]"),
        "{err}"
    );
    assert!(!err.contains("`Sp002`"), "{err}");
    assert!(
        err.contains(
            "tool.mod:8:5: warning: tool `tGun` is given another value here than its declaration on line 2: trackfix uses this value, but the motion on line 7 may run before it, while the declared one holds: the targets moved there are left as written where the tool matters (the robot's kinematics)"
        ),
        "{err}"
    );
    let mut keep = correct.to_vec();
    keep.extend(["--keep", "two-work-objects"]);
    let (code, err, welds) = run_on_module(&between, &keep);
    assert_eq!(code, 4, "{err}");
    assert_eq!(
        welds,
        [between.lines().nth(3).unwrap(), as_declared[1].as_str()]
    );

    // Without the robot's kinematics nothing reads the tool: corrected as before, the
    // numbers the tool's declared value gives.
    let rules = [
        "correct",
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
    ];
    let (code, err, welds) = run_on_module(&between, &rules);
    assert_eq!((code, &welds), (0, &as_declared), "{err}");

    // A mirror writes the tool's image into its declaration and the assignment with the
    // frames, so a motion with either value reaches the target's image; without them it reads
    // no tool. (Before the declaration was mirrored too, `Sp001` was refused.)
    let mirror = ["mirror", "--cell", "samples/cell_rules.toml"];
    let (code, err, welds) = run_on_module(&between, &mirror);
    assert_eq!((code, welds.len()), (0, 2), "{err}");
    let mut frames = mirror.to_vec();
    frames.push("--mirror-frames");
    let (code, err, with_frames) = run_on_module(&between, &frames);
    assert_eq!((code, with_frames.len()), (0, 2), "{err}");
    assert!(!err.contains("two values of tool"), "{err}");

    // `reach` says which value it checked.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tool.mod");
    std::fs::write(&input, &between).unwrap();
    let (_, out, err) = crate::support::trackfix(&[
        "reach",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        input.to_str().unwrap(),
    ]);
    let warned: Vec<&str> = out.lines().filter(|l| l.contains("warning:")).collect();
    assert_eq!(
        warned,
        [
            "      warning: with tool `tGun` as declared (line 2) and as the program gives it (line 8): the motion on line 7 may run before the assignment: checked with the value given only"
        ],
        "{out}{err}"
    );
}

/// A tool the cell file gives (`[robot.NAME.tool]`) stands for its declaration: where the
/// program gives the tool one other value, the robot moves with that value, which the entry does
/// not describe, so the joints of the targets moved with it cannot be checked. Before, they were
/// checked with the cell's entry (here the declared value, in which the welds' written
/// configuration reaches them) and corrected, while the robot moves with the turned tool.
#[test]
fn a_cell_tool_entry_does_not_stand_for_a_value_the_program_gives_the_tool() {
    let dir = tempfile::tempdir().unwrap();
    let cell = dir.path().join("cell.toml");
    std::fs::write(
        &cell,
        format!(
            "{}\n[robot.r1.tool]\ntGun = {{ x = 12.5, y = -3.2, z = 412.8, rx = 0, ry = 30, rz = 0 }}\n",
            crate::support::sample_cell()
        ),
    )
    .unwrap();
    let correct = ["correct", "--cell", cell.to_str().unwrap(), "--robot", "r1"];
    let (code, err, welds) = run_on_module(&tool_module(TOOL_WRITTEN, None, false), &correct);
    assert_eq!((code, welds.len()), (0, 2), "{err}");
    let given = tool_module(TOOL_WRITTEN, Some(TOOL_TURNED), true);
    let (code, err, _) = run_on_module(&given, &correct);
    assert_eq!(code, 3, "{err}");
    for (weld, line) in [("Sp001", 4), ("Sp002", 5)] {
        assert!(
            err.contains(&format!(
                "tool.mod:{line}:26: error: robtarget `{weld}`: its joints cannot be checked: tool `tGun` is given another value by the program (line 7) than the declaration the cell file's entry for it replaces: the robot moves with the program's value"
            )),
            "{err}"
        );
    }
    assert!(
        err.contains("help: remove `tGun` from the cell file's [robot.NAME.tool], or declare it with the value the program gives it"),
        "{err}"
    );
}

/// A whole array of work objects given a value in a routine (`wArr := [w_away, w_origin];`):
/// the targets moved with its elements are refused by name as given another value, where they
/// were corrected in the declared elements. One element given a value is read as a frame is.
#[test]
fn a_whole_array_of_frames_given_a_value_refuses_its_elements_targets() {
    use trackfix::transform::RefusalKind;
    let module = |body: &str| {
        format!(
            "MODULE M\n  PERS wobjdata wArr{{2}}:=[{W_ORIGIN},{W_AWAY}];\n{P1}  PROC main()\n{body}    MoveL p1,v100,fine,tool0\\WObj:=wArr{{1}};\n  ENDPROC\nENDMODULE\n"
        )
    };
    let (_, refused) = correct_task(&[("m.mod", module(""))]);
    assert!(refused.is_empty(), "{refused:?}");
    let (_, refused) = correct_task(&[(
        "m.mod",
        module(&format!("    wArr := [{W_AWAY},{W_ORIGIN}];\n")),
    )]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].0, "p1");
    assert_eq!(refused[0].1, RefusalKind::RuntimeData);
    assert!(
        refused[0]
            .2
            .contains("`wArr{1}`, which the program gives another value"),
        "{}",
        refused[0].2
    );
}

/// A tool the program gives a computed value (`tG := tOther;`, `tG.tframe.trans.z := 300;`)
/// refuses the targets moved with it, as a work object does: their joints, reach and
/// configuration depend on it. Its load (`tG.tload := load1;`) places nothing: no finding.
#[test]
fn a_tool_given_a_computed_value_refuses_its_targets_but_not_its_load() {
    use trackfix::transform::RefusalKind;
    let tool = "[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]]";
    let module = |body: &str| {
        format!(
            "MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\n  PERS tooldata tG:={tool};\n  PERS tooldata tOther:={tool};\n  PERS loaddata load1:=[2,[0,0,1],[1,0,0,0],0,0,0];\n{P1}  PROC main()\n{body}    MoveL p1,v100,fine,tG\\WObj:=w1;\n  ENDPROC\nENDMODULE\n"
        )
    };
    for body in ["", "    tG.tload := load1;\n", "    tG.tload.mass := 3;\n"] {
        let (_, refused) = correct_task(&[("m.mod", module(body))]);
        assert!(refused.is_empty(), "{body}: {refused:?}");
    }
    for body in ["    tG := tOther;\n", "    tG.tframe.trans.z := 300;\n"] {
        let (_, refused) = correct_task(&[("m.mod", module(body))]);
        assert_eq!(refused.len(), 1, "{body}: {refused:?}");
        assert_eq!(refused[0].1, RefusalKind::RuntimeData, "{body}");
        assert!(refused[0].2.contains("`tG`"), "{}", refused[0].2);
    }
}

/// A PERS work object given one other literal value that changes whether the robot holds the
/// tool (`robhold`) is not taken at that value: the motions were bound as the declaration
/// says, so the targets are refused as given another value (before: corrected in the assigned
/// pose yet refused as stationary-tool points).
#[test]
fn an_assignment_that_changes_robhold_is_not_taken() {
    use trackfix::transform::RefusalKind;
    let held = W_ORIGIN.replacen("FALSE", "TRUE", 1);
    let (_, refused) = correct_task(&[(
        "m.mod",
        format!(
            "MODULE M\n  PERS wobjdata w1:={held};\n{P1}  PROC main()\n    w1 := {W_AWAY};\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n"
        ),
    )]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].1, RefusalKind::RuntimeData, "{refused:?}");
}

/// A work object declared for every module to see in two modules with two values is one object
/// at run time, of a value the text does not decide: the targets moved with it are refused, and
/// the second declaration is warned about. Two declarations of one value are one frame.
#[test]
fn a_frame_declared_in_two_modules_with_two_values_refuses_its_targets() {
    use trackfix::transform::RefusalKind;
    let motion = "  PROC main()\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\n";
    let other = |v: &str| format!("MODULE B\n  PERS wobjdata w1:={v};\nENDMODULE\n");
    let first = format!("MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\n{P1}{motion}ENDMODULE\n");
    let (_, refused) = correct_task(&[("m.mod", first.clone()), ("b.mod", other(W_ORIGIN))]);
    assert!(refused.is_empty(), "{refused:?}");
    let (_, refused) = correct_task(&[("m.mod", first), ("b.mod", other(W_AWAY))]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].1, RefusalKind::RuntimeData, "{refused:?}");
    let files = rapid::parse_task(vec![
        (
            "m.mod".into(),
            format!("MODULE M\n  PERS wobjdata w1:={W_ORIGIN};\nENDMODULE\n")
                .into_bytes()
                .into(),
        ),
        ("b.mod".into(), other(W_AWAY).into_bytes().into()),
    ]);
    let warned: Vec<_> = files[1]
        .diagnostics
        .iter()
        .filter(|d| d.message.contains("is declared here and in m.mod"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", files[1].diagnostics);
    assert!(warned[0].shapes_transforms);
}

/// A target moved to with a work object that only a `LOCAL` declaration in another module gives
/// is refused with that said, not as undeclared.
#[test]
fn a_local_frame_the_targets_module_does_not_see_is_named() {
    let (_, refused) = correct_task(&[
        ("m.mod", format!("MODULE M\n{P1}ENDMODULE\n")),
        (
            "b.mod",
            format!(
                "MODULE B\n  LOCAL PERS wobjdata w1:={W_AWAY};\n  PROC main()\n    MoveL p1,v100,fine,tool0\\WObj:=w1;\n  ENDPROC\nENDMODULE\n"
            ),
        ),
    ]);
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert!(
        refused[0].2.contains("`w1` is declared LOCAL in b.mod"),
        "{}",
        refused[0].2
    );
}

/// The work objects target `name` of `f` is used with, sorted.
fn wobjs_of(f: &ParsedFile, name: &str) -> Vec<String> {
    let target = f
        .positions()
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no target {name}"));
    crate::support::sorted_work_objects(&target.usage)
}

/// Data a call names with a literal is that data: `GetDataVal "p1", pv` copies `p1` into `pv`
/// (a motion to `pv` is one to `p1`) and gives `pv` a value, `SetDataVal "pp", p2` and
/// `StrToVal(…, pq)` give their data a value, and `Add`, `Incr` or a component passed to a
/// routine that writes its parameter change a target or work object in part. Before, each
/// was corrected as written.
#[test]
fn rapid_data_written_by_name_or_in_part_is_run_time_data() {
    let src = format!(
        "MODULE R\n\
  PERS wobjdata wC:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PERS wobjdata wD:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  PERS wobjdata wE:=[FALSE,TRUE,\"\",[[1000,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  CONST robtarget p1:={T};\n\
  CONST robtarget p2:={T};\n\
  PERS robtarget pp:={T};\n\
  PERS robtarget pq:={T};\n\
  PERS robtarget pr:={T};\n\
  PERS robtarget ps:={T};\n\
  PERS robtarget pt:={T};\n\
  CONST robtarget onC:={T};\n\
  CONST robtarget onD:={T};\n\
  CONST robtarget onE:={T};\n\
  VAR robtarget pv;\n\
  VAR bool ok;\n\
  PROC bump(INOUT num z)\n    z := z + 10;\n  ENDPROC\n\
  PROC main()\n\
    GetDataVal \"p1\", pv;\n\
    MoveL pv,v100,fine,tool0\\WObj:=wB;\n\
    MoveL p1,v100,fine,tool0\\WObj:=wA;\n\
    SetDataVal \"pp\", p2;\n\
    ok := StrToVal(\"[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\", pq);\n\
    Add pr.trans.z, 10;\n\
    Incr ps.extax.eax_a;\n\
    bump pt.trans.z;\n\
    Add wC.uframe.trans.x, 100;\n\
    bump wD.uframe.trans.x;\n\
    GetDataVal \"wB\", wE;\n\
    MoveL pp,v100,fine,tool0\\WObj:=wA;\n\
    MoveL pq,v100,fine,tool0\\WObj:=wA;\n\
    MoveL pr,v100,fine,tool0\\WObj:=wA;\n\
    MoveL ps,v100,fine,tool0\\WObj:=wA;\n\
    MoveL pt,v100,fine,tool0\\WObj:=wA;\n\
    MoveL p2,v100,fine,tool0\\WObj:=wA;\n\
    MoveL onC,v100,fine,tool0\\WObj:=wC;\n\
    MoveL onD,v100,fine,tool0\\WObj:=wD;\n\
    MoveL onE,v100,fine,tool0\\WObj:=wE;\n\
  ENDPROC\nENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("r.mod"), src.into_bytes());
    assert_eq!(wobjs_of(&f, "p1"), ["wA", "wB"]);
    for n in ["pp", "pq", "pr", "ps", "pt", "onC", "onD", "onE"] {
        assert!(run_time(&f, n).is_some(), "{n}");
    }
    // What `SetDataVal` reads is not changed.
    assert_eq!(run_time(&f, "p2"), None);
}

/// A data name or routine the program computes when it runs: `GetDataVal s, pv` or
/// `SetDataVal s, …` may read or write any target (and work object) of the program, every
/// one refused naming the call; `SetAllDataVal` of a type holding no position or frame
/// touches none; a late-bound call (`%pn% p1;`) passes its arguments to a routine trackfix
/// cannot tell, which refuses them, and nothing else.
#[test]
fn rapid_data_or_routines_named_at_run_time_refuse_what_they_may_touch() {
    let module = |body: &str| {
        let src = format!(
            "MODULE R\n  CONST robtarget p1:={T};\n  CONST robtarget p2:={T};\n  VAR robtarget pv;\n  \
             VAR string s:=\"p1\";\n  VAR num n;\n  PROC mvB(robtarget p)\n    \
             MoveL p,v100,fine,tool0\\WObj:=wB;\n  ENDPROC\n  PROC main()\n    \
             MoveL p1,v100,fine,tool0\\WObj:=wA;\n    MoveL p2,v100,fine,tool0\\WObj:=wA;\n    \
             {body}\n  ENDPROC\nENDMODULE\n"
        );
        rapid::parse_file(Path::new("r.mod"), src.into_bytes())
    };
    let named = |f: &ParsedFile, n: &str| match run_time(f, n) {
        Some(RunTimeValue::NamedAtRunTime { call, at }) => Some((call, at.line)),
        _ => None,
    };
    for (body, call) in [
        ("GetDataVal s, pv;", "GetDataVal"),
        ("SetDataVal s, pv;", "SetDataVal"),
        (
            "SetAllDataVal \"robtarget\"\\Object:=\"p.*\", pv;",
            "SetAllDataVal",
        ),
    ] {
        let f = module(body);
        for n in ["p1", "p2"] {
            assert_eq!(named(&f, n), Some((call.to_owned(), 13)), "{body} {n}");
        }
    }
    let f = module("SetAllDataVal \"num\", n;");
    assert_eq!(run_time(&f, "p1"), None);
    let f = module("%\"mv\" + \"B\"% p1;");
    assert_eq!(named(&f, "p1"), Some(("%\"mv\" + \"B\"%".to_owned(), 13)));
    assert_eq!(run_time(&f, "p2"), None);
}

/// The weld job of the example: `main` runs `Job 1` and `Job 2` with the axes offset possibly
/// active, and `Job` runs its seam by a name written `{late}` at run time; `Seam_1` displaces
/// its own middle motion, and `Unused` is run by nothing.
fn weld_job(late: &str) -> String {
    format!(
        "  PROC main()\n    MoveL pA,v200,fine,tool0;\n    IF bOffs THEN\n      EOffsSet eShift;\n    ENDIF\n    Job 1;\n    Job 2;\n    EOffsOff;\n    MoveL pH,v200,fine,tool0;\n  ENDPROC\n  PROC Job(num n)\n    {late};\n  ENDPROC\n  PROC Seam_1()\n    MoveL pB,v200,fine,tool0;\n    PDispSet dWeld;\n    MoveL pC,v200,fine,tool0;\n    PDispOff;\n    MoveL pD,v200,fine,tool0;\n  UNDO\n    PDispOff;\n  ENDPROC\n  PROC Seam_2()\n    MoveL pE,v200,fine,tool0;\n  ENDPROC\n  PROC Unused()\n    MoveL pF,v200,fine,tool0;\n  ENDPROC\n"
    )
}

const WELD_TARGETS: [&str; 7] = ["pA", "pB", "pC", "pD", "pE", "pF", "pH"];

/// A call that names its routine at run time by a name starting with a literal
/// (`%"Seam_"+ValToStr(n)%`, `CallByVar "Seam_",n`) runs only the `PROC`s whose names start
/// so (ignoring case): the seams' motions, reached while the axes offset may be active, are
/// refused naming it (the displaced one too: the offset is written first), while `main`'s
/// motions outside the offset and a `PROC` nothing runs are not (`pA` and `pF` were, when such
/// a call could run any `PROC`).
#[test]
fn a_late_call_by_a_literal_start_runs_only_the_procs_named_so() {
    for late in [
        "%\"Seam_\"+ValToStr(n)%",
        "%\"seam_\" + ValToStr(n)%",
        "CallByVar \"Seam_\",n",
    ] {
        let (found, src) = displaced(&WELD_TARGETS, &weld_job(late));
        let offset = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
        assert_eq!(
            found,
            [None, offset, offset, offset, offset, None, None],
            "{late}"
        );
    }
}

/// `CallByVar "Seam_",n` runs a procedure named by the start and a number's digits: not
/// `Seam_1Old`, which `%"Seam_"+ValToStr(n)%` (any text after the start) may run.
#[test]
fn call_by_var_runs_only_the_procs_named_by_its_start_and_digits() {
    for (late, old) in [
        ("CallByVar \"Seam_\",n", false),
        ("%\"Seam_\"+ValToStr(n)%", true),
    ] {
        let job = weld_job(late).replace("PROC Unused()", "PROC Seam_1Old()");
        let (found, src) = displaced(&WELD_TARGETS, &job);
        let offset = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
        let f = if old { offset } else { None };
        assert_eq!(
            found,
            [None, offset, offset, offset, offset, f, None],
            "{late}"
        );
    }
}

/// A name written whole (`%"Seam_2"%`) runs that `PROC` only; a start no `PROC` has runs a
/// routine no module given defines (which changes nothing: the offset stays active after it);
/// a name not written as a literal (`%sSeam%`) may still run any `PROC` of the task, `main`
/// and `Unused` included.
#[test]
fn a_late_call_by_a_whole_name_runs_that_proc_and_one_by_a_variable_any() {
    let (found, src) = displaced(&WELD_TARGETS, &weld_job("%\"Seam_2\"%"));
    let offset = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
    let own = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, None, own, None, offset, None, None]);
    let none_so = weld_job("%\"Weld_\"+ValToStr(n)%").replace(
        "    EOffsOff;\n    MoveL pH,v200,fine,tool0;\n",
        "    MoveL pH,v200,fine,tool0;\n    EOffsOff;\n",
    );
    let (found, src) = displaced(&WELD_TARGETS, &none_so);
    let offset = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
    let own = Some(("PDispSet", line_of(&src, "PDispSet dWeld")));
    assert_eq!(found, [None, None, own, None, None, None, offset]);
    let (found, src) = displaced(&WELD_TARGETS, &weld_job("%sSeam%"));
    let offset = Some(("EOffsSet", line_of(&src, "EOffsSet eShift")));
    assert_eq!(
        found,
        [offset, offset, offset, offset, offset, offset, None]
    );
}
