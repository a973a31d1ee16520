//! Targets a program uses as other than positions — the joint targets RAPID's world-zone
//! instructions take as a tolerance or as joint limits, the KRL positions added to a frame
//! with the geometric operator `:` — are marked, and no transform moves them as positions.

use std::path::Path;

use trackfix::position::{NonPosition, NonPositionRole, ParsedFile, UseLine};
use trackfix::{krl, rapid};

use crate::support::trackfix;

/// A zone module: a home zone (middle and tolerance), a joint-limit zone, arguments by name
/// and in another case, and a joint target the zones do not take.
const ZONES: &str = "MODULE Zones\r\n\
  CONST jointtarget jHome:=[[10,-20,30,0,45,0],[4250,9E9,9E9,9E9,9E9,9E9]];\r\n\
  CONST jointtarget jDelta:=[[2,2,2,2,2,2],[5,9E9,9E9,9E9,9E9,9E9]];\r\n\
  CONST jointtarget jLow:=[[-90,-60,-60,-180,-100,-360],[0,9E9,9E9,9E9,9E9,9E9]];\r\n\
  CONST jointtarget jHigh:=[[30,60,60,180,100,360],[6000,9E9,9E9,9E9,9E9,9E9]];\r\n\
  CONST jointtarget jTol:=[[1,1,1,1,1,1],[2,9E9,9E9,9E9,9E9,9E9]];\r\n\
  CONST jointtarget jPark:=[[0,-30,30,0,90,0],[4000,9E9,9E9,9E9,9E9,9E9]];\r\n\
  VAR shapedata shHome;\r\n\
  VAR shapedata shPark;\r\n\
  VAR shapedata shLim;\r\n\
  PROC zones()\r\n\
    WZHomeJointDef \\Inside, shHome, jHome, jDelta;\r\n\
    wzhomejointdef \\Inside, shPark, MiddleJointVal:=jPark, DeltaJointVal:=jTol;\r\n\
    WZLimJointDef \\Outside, shLim, jLow, jHigh;\r\n\
    MoveAbsJ jHome, v1000, fine, tool0;\r\n\
  ENDPROC\r\n\
ENDMODULE\r\n";

fn non_position_of(f: &ParsedFile, name: &str) -> Option<NonPosition> {
    f.positions()
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no target {name}"))
        .usage
        .non_position()
        .cloned()
}

#[test]
fn the_tolerance_and_limits_of_a_world_zone_are_marked_its_middle_is_not() {
    let f = rapid::parse_file(Path::new("zones.mod"), ZONES.as_bytes().to_vec());
    let want = |instruction, parameter, role, line| NonPosition {
        instruction,
        parameter,
        role,
        at: UseLine::new(line),
    };
    assert_eq!(
        non_position_of(&f, "jDelta"),
        Some(want(
            "WZHomeJointDef",
            "DeltaJointVal",
            NonPositionRole::Tolerance,
            12
        ))
    );
    assert_eq!(
        non_position_of(&f, "jTol"),
        Some(want(
            "WZHomeJointDef",
            "DeltaJointVal",
            NonPositionRole::Tolerance,
            13
        ))
    );
    assert_eq!(
        non_position_of(&f, "jLow"),
        Some(want(
            "WZLimJointDef",
            "LowJointVal",
            NonPositionRole::Limit,
            14
        ))
    );
    assert_eq!(
        non_position_of(&f, "jHigh"),
        Some(want(
            "WZLimJointDef",
            "HighJointVal",
            NonPositionRole::Limit,
            14
        ))
    );
    // The middle of a home zone is a position, as a motion's target is.
    assert_eq!(non_position_of(&f, "jHome"), None);
    assert_eq!(non_position_of(&f, "jPark"), None);
    // Each zone argument is still used, on its instruction's line.
    let lines = |name: &str| {
        f.positions()
            .find(|p| p.name.as_deref() == Some(name))
            .unwrap()
            .usage
            .lines
            .to_vec()
    };
    assert_eq!(lines("jDelta"), [12]);
    assert_eq!(lines("jHigh"), [14]);
    assert_eq!(lines("jHome"), [12, 15]);
}

/// The line of `text` that declares `name`.
fn declaration<'a>(text: &'a str, name: &str) -> &'a str {
    text.lines()
        .find(|l| l.contains(&format!(" {name}:=")))
        .unwrap_or_else(|| panic!("no {name} in {text}"))
}

fn zones_file(dir: &Path) -> String {
    let path = dir.join("zones.mod");
    std::fs::write(&path, ZONES).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn correct_leaves_the_tolerance_and_limits_as_written_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let input = zones_file(dir.path());
    let out = dir.path().join("out.mod");
    let (code, _, err) = trackfix(&[
        "correct",
        &input,
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    for name in ["jDelta", "jTol", "jLow", "jHigh"] {
        assert_eq!(declaration(&text, name), declaration(ZONES, name), "{text}");
    }
    // The middles are positions: corrected with the arm's kinematics.
    assert_ne!(declaration(&text, "jHome"), declaration(ZONES, "jHome"));
    assert!(
        err.contains("`jDelta` is the `DeltaJointVal` of `WZHomeJointDef` on line 12: a tolerance"),
        "{err}"
    );
    assert!(
        err.contains("`jLow` is the `LowJointVal` of `WZLimJointDef` on line 14: joint limits, not a position; left as written"),
        "{err}"
    );
}

#[test]
fn a_mirror_refuses_joint_limits_by_name_and_keeps_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let input = zones_file(dir.path());
    let out = dir.path().join("out.mod");
    let args = |keep: bool| {
        let mut a = vec![
            "transfer".to_owned(),
            input.clone(),
            "--cell".into(),
            "samples/cell.toml".into(),
            "--from".into(),
            "r1".into(),
            "--to".into(),
            "r2".into(),
            "--mirror".into(),
            "-o".into(),
            out.to_str().unwrap().into(),
        ];
        if keep {
            a.extend(["--keep".into(), "world-zone-limits".into()]);
        }
        a
    };
    let refused = args(false);
    let (code, _, err) = trackfix(&refused.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 3, "{err}");
    assert!(!out.exists());
    for name in ["jLow", "jHigh"] {
        assert!(
            err.contains(&format!("`{name}` is the `")) && err.contains("[world-zone-limits]"),
            "{err}"
        );
    }
    let kept = args(true);
    let (code, _, err) = trackfix(&kept.iter().map(String::as_str).collect::<Vec<_>>());
    // Left as written on request: a partial result, told by its exit code.
    assert_eq!(code, 4, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    for name in ["jDelta", "jTol", "jLow", "jHigh"] {
        assert_eq!(declaration(&text, name), declaration(ZONES, name), "{text}");
    }
    // The home zone's middle is the mirrored robot's: axis 1 turned the other way.
    assert!(declaration(&text, "jHome").contains("[[-10."), "{text}");
}

#[test]
fn krl_names_after_a_geometric_operator_are_offsets_the_frame_before_is_not() {
    let src = "DEF comp( )\n\
  DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 2,E1 100}\n\
  DECL E6POS XOFF={X 0,Y 0,Z 50,A 0,B 0,C 0,S 2,T 2,E1 0}\n\
  DECL E6POS XA={X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 2,E1 100}\n\
  DECL E6POS XB={X 0,Y 0,Z 9,A 0,B 0,C 0,S 2,T 2,E1 0}\n\
  DECL E6POS XC={X 0,Y 0,Z 7,A 0,B 0,C 0,S 2,T 2,E1 0}\n\
  DECL E6POS XD={X 0,Y 0,Z 5,A 0,B 0,C 0,S 2,T 2,E1 0}\n\
  DECL E6POS XE={X 0,Y 0,Z 5,A 0,B 0,C 0,S 2,T 2,E1 0}\n\
  DECL E6POS XPLAIN={X 4,Y 5,Z 6,A 0,B 0,C 0,S 2,T 2,E1 100}\n\
  DECL E6POS XPT\n\
  BAS(#BASE,1)\n\
  LIN XP1:XOFF\n\
  LIN (XA:(XB)):xc\n\
  XPT = INV_POS(XA):XD\n\
  XPT = XPLAIN\n\
  LIN XPLAIN\n\
  IF XE.Z > 0 THEN\n\
  ENDIF\n\
END\n";
    let f = krl::parse_file(Path::new("comp.src"), src.as_bytes().to_vec());
    let offset = |line| {
        Some(NonPosition {
            instruction: ":",
            parameter: "right operand",
            role: NonPositionRole::Offset,
            at: UseLine::new(line),
        })
    };
    assert_eq!(non_position_of(&f, "XOFF"), offset(12));
    assert_eq!(non_position_of(&f, "XB"), offset(13));
    // Written in lower case: names compare without case.
    assert_eq!(non_position_of(&f, "XC"), offset(13));
    assert_eq!(non_position_of(&f, "XD"), offset(14));
    // The frames the offsets are taken in, a target moved to, one only read: no offsets.
    for name in ["XP1", "XA", "XPLAIN", "XE"] {
        assert_eq!(non_position_of(&f, name), None, "{name}");
    }
    // Nor is any operand of a composed motion a use: the motion is reported instead.
    let lines_of = |name: &str| {
        f.positions()
            .find(|p| p.name.as_deref() == Some(name))
            .map(|p| p.usage.lines.to_vec())
    };
    for name in ["XP1", "XA", "XOFF", "XB", "XC", "XD"] {
        assert_eq!(lines_of(name), Some(vec![]), "{name}");
    }
    assert_eq!(lines_of("XPLAIN"), Some(vec![16]));
    assert!(
        f.diagnostics
            .iter()
            .any(|d| d.message.contains("computed target")),
        "{:?}",
        f.diagnostics
    );
}

/// The target of a relative motion (`LIN_REL XSTEP`) is a displacement from wherever the
/// robot is: an offset, left as written with a note, never corrected as a position (nor, with
/// `--default-wobj`, as one no motion uses). A point moved to as well as moved by is both, which
/// no one value can be: refused by name.
#[test]
fn krl_relative_motion_targets_are_offsets_and_one_also_moved_to_is_refused() {
    let program = |extra: &str| {
        format!(
            "DEF rel( )\n\
  DECL E6POS XA={{X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 2,E1 100}}\n\
  DECL E6POS XSTEP={{X 0,Y 0,Z 50,A 0,B 0,C 0,E1 0}}\n\
  BAS(#BASE,1)\n\
  LIN XA\n\
  LIN_REL XSTEP\n\
  PTP_REL (XSTEP) #TOOL\n\
{extra}END\n"
        )
    };
    let f = krl::parse_file(Path::new("rel.src"), program("").into_bytes());
    assert_eq!(
        non_position_of(&f, "XSTEP"),
        Some(NonPosition {
            instruction: "LIN_REL",
            parameter: "relative target",
            role: NonPositionRole::Offset,
            at: UseLine::new(6),
        })
    );
    assert_eq!(non_position_of(&f, "XA"), None);
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("rel.src");
    let correct = |text: &str| {
        std::fs::write(&src, text).unwrap();
        trackfix(&[
            "correct",
            src.to_str().unwrap(),
            "--cell",
            "samples/cell_rules.toml",
            "--robot",
            "r1",
            "--default-wobj",
            "BASE_DATA[1]",
            "--diff",
        ])
    };
    let (code, diff, err) = correct(&program(""));
    assert_eq!(code, 0, "{err}");
    assert!(diff.contains("+DECL E6POS XA="), "{diff}");
    assert!(!diff.contains("+DECL E6POS XSTEP"), "{diff}");
    assert!(
        err.contains("E6POS `XSTEP` is the relative target of `LIN_REL` on line 6: a displacement from wherever the robot is, not a position; left as written"),
        "{err}"
    );
    let (code, diff, err) = correct(&program("  LIN_REL XA\n"));
    assert_eq!(code, 3, "{err}");
    assert!(diff.is_empty(), "{diff}");
    assert!(
        err.contains("E6POS `XA` is moved to by a motion (line 5) and is also the relative target of `LIN_REL` on line 8: one value cannot be both a position and an offset"),
        "{err}"
    );
}

/// A KUKA program with one target a motion moves to and one no motion uses.
const PARTLY_USED: &str = "DEF part( )\n\
  DECL E6POS XP1={X 592.548,Y -746.673,Z 974.380,A -178.9394,B 15.8711,C 177.3993,S 6,T 50,E1 150.000}\n\
  DECL E6POS XP2={X 592.548,Y -746.673,Z 974.380,A -178.9394,B 15.8711,C 177.3993,S 6,T 50,E1 150.000}\n\
  BAS(#INITMOV,0)\n\
  BAS(#TOOL,1)\n\
  BAS(#BASE,1)\n\
  LIN XP1\n\
END\n";

#[test]
fn a_diff_that_keeps_refused_targets_exits_as_a_partial_result() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("part.src");
    std::fs::write(&src, PARTLY_USED).unwrap();
    let (code, diff, err) = trackfix(&[
        "correct",
        src.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--keep",
        "unresolved-work-object",
        "--diff",
    ]);
    // The diff shows XP1 corrected and nothing else; XP2 kept, as the warning says.
    assert_eq!(code, 4, "{err}");
    assert!(diff.contains("+DECL E6POS XP1="), "{diff}");
    assert!(!diff.contains("+DECL E6POS XP2"), "{diff}");
    assert!(
        err.contains("warning: E6POS `XP2` is not used by any motion"),
        "{err}"
    );
}

/// A search writes the position it finds into its search point: what a motion to it later
/// reaches is measured, so every transform leaves it as written with a note (the mirror too),
/// and corrects the search's end point like any target.
#[test]
fn a_search_point_is_left_as_written_and_its_end_point_moves() {
    let target =
        "[[812.5,-120,455],[0,0.707107,0.707107,0],[-1,-1,1,0],[1500,9E9,9E9,9E9,9E9,9E9]]";
    let module = format!(
        "MODULE s\n\
  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\n\
  TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[1,0,0,0]]];\n\
  PERS robtarget pHit:={target};\n\
  CONST robtarget pTo:={target};\n\
  PROC main()\n\
    searchl \\Stop, diTouch, pHit, pTo, v100, tGun\\WObj:=wCar;\n\
    MoveL pHit, v100, fine, tGun\\WObj:=wCar;\n\
  ENDPROC\n\
ENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("s.mod"), module.clone().into_bytes());
    assert_eq!(
        non_position_of(&f, "pHit"),
        Some(NonPosition {
            instruction: "SearchL",
            parameter: "SearchPoint",
            role: NonPositionRole::Found,
            at: UseLine::new(7),
        })
    );
    assert_eq!(non_position_of(&f, "pTo"), None);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("s.mod");
    std::fs::write(&input, &module).unwrap();
    let out = dir.path().join("out.mod");
    let (code, _, err) = trackfix(&[
        "correct",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(declaration(&text, "pHit"), declaration(&module, "pHit"));
    assert_ne!(declaration(&text, "pTo"), declaration(&module, "pTo"));
    assert!(
        err.contains("robtarget `pHit` is the `SearchPoint` of `SearchL` on line 7: written by the search with the position it finds, not a position; left as written"),
        "{err}"
    );
}
