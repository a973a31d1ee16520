//! Integration tests: rapid.
//!
//! - every sample prints back byte for byte, with no errors and no opaque node;
//! - positions per sample: counts, exact values, spans that point at the literal's text, and a
//!   compact dump per sample as an insta snapshot;
//! - usage resolution: work object, tool, two-wobj flag, stationary tool, arrays;
//! - tree dumps of small inputs (valid and broken) as snapshots;
//! - property tests: generated modules, token soup, arbitrary bytes, corrupted and truncated
//!   samples never panic, always print back, and report located errors.

use std::path::{Path, PathBuf};

use crate::support::{text, texts};
use proptest::prelude::*;
use trackfix::position::{
    CartesianFields, Config, FrameDecl, FrameKind, NumField, Orientation, ParsedFile, Position,
    PositionKind, Skid,
};
use trackfix::rapid;
use trackfix::syntax::{NumLit, Severity};

fn samples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/rapid")
}

fn sample_paths() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(samples_dir())
        .expect("samples/rapid exists")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

fn load(name: &str) -> ParsedFile {
    let path = samples_dir().join(name);
    let src = std::fs::read(&path).expect("sample readable");
    rapid::parse_file(Path::new(name), src)
}

fn pos(f: &ParsedFile, name: &str) -> Position {
    f.positions()
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no position {name}"))
}

fn frame<'a>(f: &'a ParsedFile, name: &str) -> &'a FrameDecl {
    f.frames
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no frame {name}"))
}

fn cartesian(src: &[u8], c: &Option<CartesianFields>) -> String {
    let Some(c) = c else { return "-".into() };
    let rot = match &c.orient {
        Some(Orientation::Quaternion(q)) => texts(src, q),
        Some(Orientation::Abc(a)) => texts(src, a),
        None => "-".into(),
    };
    format!("[{}|{}]", texts(src, &c.trans), rot)
}

/// One line per frame, position, offset call and diagnostic: the literal texts as written.
fn dump(f: &ParsedFile) -> String {
    let src = &f.source;
    let mut out = format!(
        "round_trip={} opaque={} positions={} frames={} offsets={}\n",
        f.round_trip,
        f.opaque,
        f.positions.len(),
        f.frames.len(),
        f.offsets.len()
    );
    for fr in &f.frames {
        out += &format!(
            "frame {} {:?} L{} robhold={:?} ufprog={:?} ufmec={:?} frame={} oframe={}\n",
            fr.name,
            fr.kind,
            fr.line,
            fr.held_by_robot,
            fr.fixed,
            fr.moved_by,
            cartesian(src, &fr.frame),
            cartesian(src, &fr.oframe)
        );
    }
    for p in f.positions() {
        let body = match p.kind {
            PositionKind::Jointtarget => format!("[{}]", texts(src, &p.joints)),
            _ => cartesian(src, &p.cartesian),
        };
        let cfg = match &p.config {
            Config::Quadrants(c) => format!("[{}]", texts(src, c)),
            _ => "-".into(),
        };
        let u = &p.usage;
        out += &format!(
            "{} {} {}:{} {} cf={} eax=[{}] wobj={} tool={}{}{} lines={:?}\n",
            p.label(),
            p.kind.as_str(),
            p.line,
            p.column,
            body,
            cfg,
            texts(src, &p.extax),
            u.wobj.as_deref().unwrap_or("-"),
            u.tool.as_deref().unwrap_or("-"),
            if u.other_wobjs().is_empty() {
                String::new()
            } else {
                format!(" ALSO={}", u.other_wobjs().join("+"))
            },
            if u.stationary_tool() {
                " STATIONARY"
            } else {
                ""
            },
            u.lines
        );
    }
    for o in &f.offsets {
        out += &format!(
            "{:?} L{} target={} d=[{}] r=[{}]\n",
            o.kind,
            o.line,
            o.target,
            texts(src, &o.delta),
            texts(src, &o.rot)
        );
    }
    for d in &f.diagnostics {
        let (l, c) = f.lines.line_col(d.span.start);
        out += &format!("{} {l}:{c} {}\n", d.severity.as_str(), d.message);
    }
    out
}

/// Every numeric field's span holds exactly the literal's text.
fn assert_spans_match(f: &ParsedFile) {
    let src = &f.source;
    let check = |field: &Option<NumField>| {
        if let Some(n) = field {
            assert_eq!(
                NumLit::parse(n.span().slice(src)).and_then(|lit| NumField::new(n.span(), lit)),
                Some(*n),
                "{}",
                f.path.display()
            );
        }
    };
    let check_cart = |c: &Option<CartesianFields>| {
        if let Some(c) = c {
            c.trans.iter().for_each(check);
            if let Some(Orientation::Quaternion(q)) = &c.orient {
                q.iter().for_each(check);
            }
        }
    };
    for p in f.positions() {
        check_cart(&p.cartesian);
        p.joints.iter().for_each(check);
        p.extax.iter().for_each(check);
        if let Config::Quadrants(c) = &p.config {
            c.iter().for_each(check);
        }
        assert_eq!(p.span.slice(src).first(), Some(&b'['));
        assert_eq!(p.span.slice(src).last(), Some(&b']'));
    }
    for fr in &f.frames {
        check_cart(&fr.frame);
        check_cart(&fr.oframe);
    }
    for o in &f.offsets {
        o.delta.iter().for_each(check);
        o.rot.iter().for_each(check);
    }
}

#[test]
fn every_sample_round_trips_without_errors() {
    let paths = sample_paths();
    assert!(
        paths.len() >= 10,
        "at least 10 samples, found {}",
        paths.len()
    );
    for path in paths {
        let src = std::fs::read(&path).unwrap();
        assert_eq!(rapid::print(&src), src, "{}", path.display());
        let f = rapid::parse_file(&path, src);
        assert!(f.round_trip, "{}", path.display());
        assert_eq!(f.opaque, 0, "{}", path.display());
        let errors: Vec<String> = f
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .map(|d| f.render(d))
            .collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
        assert_spans_match(&f);
    }
}

#[test]
fn position_snapshots_per_sample() {
    for path in sample_paths() {
        let name = path
            .file_name()
            .unwrap()
            .to_string_lossy()
            .replace('.', "_");
        let src = std::fs::read(&path).unwrap();
        let f = rapid::parse_file(Path::new(path.file_name().unwrap()), src);
        insta::assert_snapshot!(format!("positions_{name}"), dump(&f));
    }
}

#[test]
fn spot_line_is_a_track_program() {
    let f = load("spot_line.mod");
    let src = &f.source;
    assert!(src.starts_with(b"%%%\r\n"));
    assert!(!src.ends_with(b"\n") && src.ends_with(b"ENDMODULE"));
    assert!(
        src.windows(11).any(|w| w == b"Schwei\xDFpunk"),
        "Latin-1 ß kept"
    );
    assert!(
        !src.windows(2).any(|w| w[1] == b'\n' && w[0] != b'\r'),
        "CRLF only"
    );
    let declared: Vec<Position> = f.positions().filter(|p| p.name.is_some()).collect();
    let spots: Vec<&Position> = declared
        .iter()
        .filter(|p| p.name.as_deref().is_some_and(|n| n.starts_with("Sp")))
        .collect();
    assert_eq!(spots.len(), 216);
    assert_eq!(f.positions().filter(|p| p.name.is_none()).count(), 9);
    let mut last = 0.0;
    for p in &spots {
        let Skid::At(s) = p.skid(0) else {
            panic!("{:?}", p.name)
        };
        assert!(s > 0.0 && s < 8000.0 && s > last, "{:?} skid {s}", p.name);
        last = s;
        for k in 1..6 {
            assert_eq!(p.skid(k), Skid::NotConnected);
            assert_eq!(p.extax[k].as_ref().unwrap().span().slice(src), b"9E+09");
        }
        assert_eq!(p.usage.wobj.as_deref(), Some("wobj_car"));
        assert_eq!(p.usage.tool.as_deref(), Some("tGun1"));
        assert!(p.usage.other_wobjs().is_empty());
        // Tool pointing down: the tool z axis has a negative world z component.
        let pose = p.cartesian.as_ref().unwrap().pose().unwrap();
        let z = pose.rotation * nalgebra::Vector3::z();
        assert!(z.z < -0.9, "{:?} tool z {z:?}", p.name);
    }
    let sp1 = pos(&f, "Sp001");
    assert_eq!(sp1.line, 16);
    let Skid::At(first) = sp1.skid(0) else {
        panic!()
    };
    assert!((first - 150.0).abs() < 1e-9);
    let Skid::At(lastv) = pos(&f, "Sp216").skid(0) else {
        panic!()
    };
    assert!((lastv - 7850.0).abs() < 1e-9);
    let car = frame(&f, "wobj_car");
    assert_eq!(
        (car.held_by_robot, car.fixed, car.kind),
        (Some(false), Some(true), FrameKind::WorkObject)
    );
    let world = car.pose().unwrap();
    assert!((world.translation.vector.x - (1520.3 + 150.0)).abs() < 0.01);
    assert_eq!(frame(&f, "tGun1").kind, FrameKind::Tool);
    assert!(f.offsets.len() >= 40);
}

#[test]
fn nine_e_nine_styles_and_expression_fields() {
    let f = load("hand_9e9.mod");
    let src = &f.source;
    let b = pos(&f, "pB");
    assert_eq!(texts(src, &b.extax), "2400.0,9E+09,9E+9,9e9,9e+09,9E+009");
    assert!((1..6).all(|k| b.skid(k) == Skid::NotConnected));
    let c = b.cartesian.as_ref().unwrap();
    assert_eq!(text(src, &c.trans[2]), ".5");
    let pc = pos(&f, "pC");
    assert_eq!(
        pc.cartesian.as_ref().unwrap().translation(),
        Some([-150.0, 25.0, 0.0])
    );
    // `xOff*2` is an expression: no field, no pose, but the other fields are there.
    let d = pos(&f, "pD");
    let dc = d.cartesian.as_ref().unwrap();
    assert!(dc.trans[0].is_none() && dc.trans[2].is_some() && dc.pose().is_none());
    // `- 5` (sign apart from the digits) is not one literal.
    assert_eq!(pos(&f, "pE").skid(0), Skid::Missing);
    // Keywords and optional arguments in any case.
    assert!(
        f.positions()
            .all(|p| p.usage.wobj.as_deref() == Some("wTable"))
    );
    assert!(
        f.positions()
            .all(|p| p.usage.tool.as_deref() == Some("tPen"))
    );
}

#[test]
fn usage_two_wobjs_is_flagged_with_a_warning() {
    let f = load("two_wobjs.mod");
    let shared = pos(&f, "pShared");
    assert_eq!(shared.usage.wobj.as_deref(), Some("wLeft"));
    assert_eq!(shared.usage.other_wobjs(), ["wRight"]);
    assert_eq!(shared.usage.lines, vec![11, 13]);
    assert!(pos(&f, "pLeftOnly").usage.other_wobjs().is_empty());
    let warn = f
        .diagnostics
        .iter()
        .find(|d| d.severity == Severity::Warning && d.message.contains("pShared"))
        .expect("two-wobj warning");
    assert_eq!(f.lines.line_col(warn.span.start), (7, 28));
}

/// A target literal whose parts are not its type's sizes is an error at the literal (the
/// controller does not load the module), whichever path reads it: the parser's fast path (six
/// external axes expected), the general one, an element of an array, an inline target, a
/// jointtarget. A literal part written as a name (`eaxNone`) has any shape. A correct file has
/// none of these.
#[test]
fn misshapen_target_literals_are_errors() {
    let text = "MODULE m\n  CONST robtarget pShort:=[[1,2,3],[1,0,0,0],[0,0,0,0],[1500]];\n  CONST robtarget pPos:=[[1,2,3,4],[1,0,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget pParts:=[[1,2,3],[1,0,0,0],[0,0,0,0]];\n  CONST robtarget pArr{2}:=[[[1,2,3],[1,0,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]],[[1,2,3],[1,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]]];\n  CONST jointtarget jBad:=[[0,0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget pName:=[[1,2,3],[1,0,0,0],[0,0,0,0],eaxNone];\n  CONST robtarget pGood:=[[1,2,3],[1,0,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[1500,9E9]],v100,z10,tool0;\n  ENDPROC\nENDMODULE\n";
    let f = rapid::parse_file(Path::new("m.mod"), text.as_bytes().to_vec());
    let errors: Vec<(usize, usize, String)> = f
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .map(|d| {
            let (l, c) = f.lines.line_col(d.span.start);
            (l, c, d.message.clone())
        })
        .collect();
    let want = [
        (
            2,
            27,
            "robtarget `pShort`: its external axes [eax_a,…,eax_f] has 1 value where a robtarget takes 6",
        ),
        (
            3,
            25,
            "robtarget `pPos`: its position [x,y,z] has 4 values where a robtarget takes 3",
        ),
        (
            4,
            27,
            "robtarget `pParts`: it has 3 parts where a robtarget has 4",
        ),
        (
            5,
            86,
            "robtarget `pArr{2}`: its orientation [q1,q2,q3,q4] has 3 values where a robtarget takes 4",
        ),
        (
            6,
            27,
            "jointtarget `jBad`: its robot axes [rax_1,…,rax_6] has 5 values where a jointtarget takes 6",
        ),
        (
            10,
            11,
            "inline robtarget: its external axes [eax_a,…,eax_f] has 2 values where a robtarget takes 6",
        ),
    ];
    let got: Vec<(usize, usize, &str)> = errors
        .iter()
        .map(|(l, c, m)| (*l, *c, m.as_str()))
        .collect();
    assert_eq!(got, want);
    let good = "MODULE m\n  CONST robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n";
    let f = rapid::parse_file(Path::new("m.mod"), good.as_bytes().to_vec());
    assert!(f.diagnostics.iter().all(|d| d.severity != Severity::Error));
}

#[test]
fn usage_stationary_tool_and_moving_wobj() {
    let f = load("stationary_tool.mod");
    assert!(f.positions().all(|p| p.usage.stationary_tool()));
    assert_eq!(frame(&f, "wNozzle").held_by_robot, Some(true));
    let m = load("moving_wobj.mod");
    let w = frame(&m, "wStn1");
    assert_eq!(
        (w.fixed, w.moved_by.as_deref()),
        (Some(false), Some("STN1"))
    );
    let seam2 = pos(&m, "pSeam2");
    assert_eq!(seam2.usage.wobj.as_deref(), Some("wStn1"));
    // ArcL: the tool is the declared tooldata, not the argument after the zone.
    assert_eq!(seam2.usage.tool.as_deref(), Some("tTorch"));
    assert!(!seam2.usage.stationary_tool());
}

#[test]
fn usage_through_arrays_and_offsets() {
    let f = load("arrays.mod");
    for n in ["pRow{1}", "pRow{2}", "pRow{3}", "pGrid{1,1}", "pGrid{2,2}"] {
        let p = pos(&f, n);
        assert_eq!(p.usage.wobj.as_deref(), Some("wPallet"), "{n}");
        assert_eq!(p.usage.tool.as_deref(), Some("tGripper"), "{n}");
    }
    // `pGrid{ 2, 1 }` names one element; `pGrid{r,c}` in Offs may be any.
    assert_eq!(pos(&f, "pGrid{2,1}").usage.lines, vec![18, 22]);
    assert_eq!(pos(&f, "pGrid{1,2}").usage.lines, vec![18]);
    let g21 = pos(&f, "pGrid{2,1}").cartesian.unwrap();
    assert_eq!(g21.translation(), Some([0.0, 500.0, 50.0]));
    let o = &f.offsets[0];
    assert_eq!(o.target, "pGrid{r,c}");
    assert_eq!(o.delta[2].as_ref().map(|d| d.value()), Some(100.0));
}

#[test]
fn offsets_reltool_rotations_and_inline_targets() {
    let src = b"MODULE m\n PROC p()\n  MoveL RelTool(p1, 1.5, -2, 0 \\Rx:=10 \\Rz:=-45.5), v100, fine, tool0;\n  p2 := [[1,2,3],[1,0,0,0],[0,0,0,0],[4000,9E9,9E9,9E9,9E9,9E9]];\n  MoveL Offs([[4,5,6],[1,0,0,0],[0,0,0,0],[4100,9E9,9E9,9E9,9E9,9E9]],0,0,10), v100, z1, tool0 \\WObj:=wobjX;\n ENDPROC\nENDMODULE\n".to_vec();
    let f = rapid::parse_file(Path::new("t.mod"), src.clone());
    assert!(f.round_trip && f.opaque == 0, "{:?}", f.diagnostics);
    let r = &f.offsets[0];
    assert_eq!(r.target, "p1");
    assert_eq!(texts(&src, &r.delta), "1.5,-2,0");
    assert_eq!(texts(&src, &r.rot), "10,-,-45.5");
    assert_eq!(f.positions.len(), 2);
    let assigned = &f.position(0).unwrap();
    assert_eq!((assigned.line, assigned.column), (4, 9));
    assert!(assigned.usage.wobj.is_none(), "an assignment is not a use");
    let inline = &f.position(1).unwrap();
    assert_eq!(inline.usage.wobj.as_deref(), Some("wobjX"));
    assert_eq!(inline.usage.tool.as_deref(), Some("tool0"));
    assert_eq!(
        f.offsets[1].target,
        "[[4,5,6],[1,0,0,0],[0,0,0,0],[4100,9E9,9E9,9E9,9E9,9E9]]"
    );
}

#[test]
fn duplicate_module_names_warn() {
    let src = b"MODULE m\n  CONST num a:=1;\n  VAR num A:=2;\n  PROC p()\n    VAR num a;\n  ENDPROC\nENDMODULE\n".to_vec();
    let f = rapid::parse_file(Path::new("d.mod"), src);
    let w: Vec<_> = f
        .diagnostics
        .iter()
        .filter(|d| d.message.contains("declared twice"))
        .collect();
    assert_eq!(
        w.len(),
        1,
        "the routine-local `a` is not a module-scope duplicate"
    );
    assert_eq!(f.lines.line_col(w[0].span.start), (3, 11));
}

#[test]
fn tree_dump_of_a_small_module() {
    let src = b"%%%\r\n  VERSION:1\r\n%%%\r\nmodule M(sysmodule)\r\n  ! c\r\n  const robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\r\n  proc main()\r\n    if x THEN movel p,v10,fine,tool0; ELSE Stop; ENDIF\r\n    IF x Stop;\r\n  ERROR\r\n    RETRY;\r\n  endproc\r\nENDMODULE";
    let parse = rapid::parse_tree(src);
    assert!(parse.diagnostics.is_empty(), "{:?}", parse.diagnostics);
    insta::assert_snapshot!("tree_small_module", parse.tree.dump(src));
}

#[test]
fn tree_dump_of_broken_input() {
    let src = b"MODULE broken\n  CONST robtarget p:=[[1,2,3],[1,0,0;\n  PROC main()\n    MoveL p, v100 fine tool0;\n    FOR i FROM 1 TO 3 DO\n      Stop;\n  ENDPROC\n  \x01\x02 junk;\n  PROC q()\n    x := \"unterminated;\n  ENDPROC\n";
    let f = rapid::parse_file(Path::new("broken.mod"), src.to_vec());
    assert!(f.round_trip);
    let mut out = rapid::parse_tree(src).tree.dump(src);
    out.push_str("--- diagnostics\n");
    for d in &f.diagnostics {
        out.push_str(&f.render(d));
    }
    insta::assert_snapshot!("tree_broken_input", out);
}

#[test]
fn errors_are_located_with_line_caret_and_hint() {
    let src =
        b"MODULE m\r\n  PROC p()\r\n    MoveL p1, v100 z10, tool0;\r\n  ENDPROC\r\nENDMODULE\r\n";
    let f = rapid::parse_file(Path::new("m.mod"), src.to_vec());
    assert_eq!(f.opaque, 1);
    let d = f
        .diagnostics
        .iter()
        .find(|d| d.severity == Severity::Error)
        .expect("an error");
    assert_eq!(
        f.render(d),
        "m.mod:3:20: error: expected `,` or `;` after the argument, found `z10`\n  |\n3 |     MoveL p1, v100 z10, tool0;\n  |                    ^^^\n  = help: fix the syntax; trackfix keeps this text verbatim and does not transform it\n"
    );
}

// ---- property tests ---------------------------------------------------------------------

fn case_of(word: &str, mode: u8) -> String {
    match mode % 3 {
        0 => word.to_ascii_uppercase(),
        1 => word.to_ascii_lowercase(),
        _ => word
            .chars()
            .enumerate()
            .map(|(i, c)| {
                if i % 2 == 0 {
                    c.to_ascii_uppercase()
                } else {
                    c.to_ascii_lowercase()
                }
            })
            .collect(),
    }
}

/// A number in one of the styles RAPID programs use.
fn number_text(v: f64, style: u8) -> String {
    match style % 6 {
        0 => format!("{v:.0}"),
        1 => format!("{v:.3}"),
        2 => format!("{v:.1}"),
        3 => format!("{v:E}"),
        4 => format!("{}.", v.trunc() as i64),
        _ => {
            let s = format!("{:.2}", v.abs().fract());
            let frac = s.trim_start_matches('0');
            if v < 0.0 {
                format!("-{frac}")
            } else {
                frac.to_owned()
            }
        }
    }
}

fn sep(ws: u8) -> &'static str {
    ["", " ", "  ", "\t", " \r\n      ", "\n ", "\r "][ws as usize % 7]
}

fn nine_e_nine(style: u8) -> &'static str {
    ["9E9", "9E+09", "9E+9", "9e9", "9e+09"][style as usize % 5]
}

#[derive(Debug, Clone)]
struct GenTarget {
    nums: Vec<(f64, u8)>,
    ws: Vec<u8>,
}

fn gen_target() -> impl Strategy<Value = GenTarget> {
    (
        proptest::collection::vec((-9000.0f64..9000.0, 0u8..6), 15),
        proptest::collection::vec(0u8..7, 40),
    )
        .prop_map(|(nums, ws)| GenTarget { nums, ws })
}

/// Writes `[[x,y,z],[q1..q4],[cf..],[eax_a,9E9..]]` with random spacing and number styles;
/// returns the text and the literal texts in field order.
fn target_text(t: &GenTarget) -> (String, Vec<String>) {
    let mut out = String::new();
    let mut lits = Vec::new();
    let mut w = t.ws.iter().cycle();
    let mut n = t.nums.iter();
    let groups = [3usize, 4, 4, 6];
    out.push('[');
    for (g, &len) in groups.iter().enumerate() {
        if g > 0 {
            out.push(',');
        }
        out.push_str(sep(*w.next().unwrap()));
        out.push('[');
        for k in 0..len {
            if k > 0 {
                out.push_str(sep(*w.next().unwrap()));
                out.push(',');
            }
            out.push_str(sep(*w.next().unwrap()));
            let lit = if g == 3 && k > 0 {
                nine_e_nine(n.next().map_or(0, |x| x.1)).to_owned()
            } else if g == 2 {
                format!("{}", (n.next().map_or(0.0, |x| x.0) as i64 % 2))
            } else {
                let (v, style) = n.next().copied().unwrap_or((0.0, 0));
                let v = if g == 1 { v / 9000.0 } else { v };
                number_text(v, style)
            };
            out.push_str(&lit);
            lits.push(lit);
        }
        out.push(']');
    }
    out.push(']');
    (out, lits)
}

fn module_strategy() -> impl Strategy<Value = (Vec<u8>, Vec<Vec<String>>, usize)> {
    (
        proptest::collection::vec(gen_target(), 1..8),
        0u8..3,
        0u8..3,
        proptest::collection::vec(0u8..7, 16),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(targets, case, nl, ws, comments, inline)| {
            let nl = ["\r\n", "\n", "\r"][nl as usize];
            let kw = |w: &str| case_of(w, case);
            let mut s = String::new();
            let mut expected = Vec::new();
            s += &format!("{} Gen{nl}", kw("module"));
            if comments {
                s += &format!("  ! generated: \"quotes\" and [brackets] in a comment{nl}");
            }
            for (i, t) in targets.iter().enumerate() {
                let (text, lits) = target_text(t);
                s += &format!(
                    "  {} {} p{i}{}:={}{};{nl}",
                    kw("const"),
                    kw("robtarget"),
                    sep(ws[i % ws.len()]),
                    sep(ws[(i + 3) % ws.len()]),
                    text
                );
                expected.push(lits);
            }
            s += &format!("  {} main(){nl}", kw("proc"));
            for i in 0..targets.len() {
                let comma = if i % 2 == 0 { "" } else { "," };
                s += &format!(
                    "    {} p{i}, v100, z10, tool0{comma}\\{}:=wobj1;{nl}",
                    kw("movel"),
                    kw("wobj")
                );
            }
            let mut inline_count = 0;
            if inline {
                let (text, lits) = target_text(&targets[0]);
                s += &format!("    {} {text},v100,fine,tool0;{nl}", kw("movej"));
                expected.push(lits);
                inline_count = 1;
            }
            s += &format!("  {}{nl}{}", kw("endproc"), kw("endmodule"));
            (s.into_bytes(), expected, inline_count)
        })
}

fn all_fields(p: &Position) -> Vec<&Option<NumField>> {
    let mut v = Vec::new();
    if let Some(c) = &p.cartesian {
        v.extend(c.trans.iter());
        if let Some(Orientation::Quaternion(q)) = &c.orient {
            v.extend(q.iter());
        }
    }
    if let Config::Quadrants(c) = &p.config {
        v.extend(c.iter());
    }
    v.extend(p.extax.iter());
    v
}

/// Tokens RAPID text is made of, for token-soup inputs.
const VOCAB: &[&str] = &[
    "MODULE",
    "ENDMODULE",
    "PROC",
    "ENDPROC",
    "FUNC",
    "ENDFUNC",
    "TRAP",
    "ENDTRAP",
    "IF",
    "THEN",
    "ELSE",
    "ELSEIF",
    "ENDIF",
    "FOR",
    "FROM",
    "TO",
    "DO",
    "ENDFOR",
    "WHILE",
    "ENDWHILE",
    "TEST",
    "CASE",
    "DEFAULT",
    "ENDTEST",
    "CONST",
    "PERS",
    "VAR",
    "LOCAL",
    "robtarget",
    "num",
    "ERROR",
    "RETRY",
    "RETURN",
    "GOTO",
    "RECORD",
    "ENDRECORD",
    "MoveL",
    "Offs",
    "RelTool",
    "p10",
    "tool0",
    "wobj0",
    "\\WObj",
    "\\Conc",
    ":=",
    ":",
    ";",
    ",",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    "%",
    "+",
    "-",
    "*",
    "<SMT>",
    "<EXP>",
    "9E9",
    "1.5",
    ".5",
    "-3",
    "\"s\"\"q\"",
    "\"open",
    "! c",
    "\r\n",
    "\n",
    "\r",
    " ",
    "\t",
    "%%%",
    "\u{00e9}",
    "\x01",
    "[[1,2,3],[1,0,0,0],[0,0,0,0],[5,9E9,9E9,9E9,9E9,9E9]]",
];

fn assert_sound(src: &[u8]) -> ParsedFile {
    let f = rapid::parse_file(Path::new("p.mod"), src.to_vec());
    assert!(f.round_trip);
    assert_eq!(rapid::print(src), src);
    for d in &f.diagnostics {
        assert!(d.span.start <= src.len() && d.span.end <= src.len());
        let _ = f.render(d);
    }
    f
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn generated_modules_round_trip_and_find_every_target(
        (src, expected, inline) in module_strategy()
    ) {
        let f = assert_sound(&src);
        prop_assert_eq!(f.opaque, 0, "{:?}", f.diagnostics);
        prop_assert!(f.diagnostics.iter().all(|d| d.severity != Severity::Error));
        prop_assert_eq!(f.positions.len(), expected.len());
        for (p, lits) in f.positions().zip(&expected) {
            let got: Vec<String> = all_fields(&p)
                .into_iter()
                .map(|o| {
                    o.as_ref()
                        .map(|n| String::from_utf8_lossy(n.span().slice(&f.source)).into_owned())
                        .unwrap_or_default()
                })
                .collect();
            prop_assert_eq!(&got, lits);
            let wobj = if p.name.is_some() { "wobj1" } else { "wobj0" };
            prop_assert_eq!(p.usage.wobj.as_deref(), Some(wobj));
        }
        prop_assert_eq!(f.positions().filter(|p| p.name.is_none()).count(), inline);
    }

    #[test]
    fn token_soup_never_panics_and_round_trips(
        toks in proptest::collection::vec((0..VOCAB.len(), 0u8..3), 0..200)
    ) {
        let mut s = Vec::new();
        for (i, gap) in toks {
            s.extend_from_slice(VOCAB[i].as_bytes());
            s.extend_from_slice([&b""[..], b" ", b"\n"][gap as usize]);
        }
        assert_sound(&s);
    }

    #[test]
    fn arbitrary_bytes_never_panic_and_round_trip(
        bytes in proptest::collection::vec(any::<u8>(), 0..1500)
    ) {
        assert_sound(&bytes);
    }

    #[test]
    fn truncated_samples_report_a_located_error(sample in 0usize..64, cut in 0.0f64..1.0) {
        let paths = sample_paths();
        let src = std::fs::read(&paths[sample % paths.len()]).unwrap();
        let k = (src.len() as f64 * cut) as usize;
        let mut end = src.len();
        while end > 0 && src[end - 1].is_ascii_whitespace() {
            end -= 1;
        }
        let cut_src = &src[..k];
        let f = assert_sound(cut_src);
        // Cutting anything before the final ENDMODULE leaves a construct open.
        // A cut that leaves only a BOM and blanks leaves nothing open, nor does one inside the
        // RobotStudio `%%%` header (free lines before `MODULE`, no construct of their own).
        let text = cut_src.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(cut_src);
        let full = src.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&src);
        let header_end = full
            .strip_prefix(b"%%%")
            .and_then(|rest| rest.windows(3).position(|w| w == b"%%%"))
            .map_or(0, |i| i + 6);
        let in_header = text.len() <= header_end
            || full[header_end..text.len()].iter().all(|b| b.is_ascii_whitespace());
        if k < end && k > 0 && !in_header && !text.iter().all(|b| b.is_ascii_whitespace()) {
            let e = f.diagnostics.iter().find(|d| d.severity == Severity::Error);
            prop_assert!(e.is_some() || f.opaque > 0, "cut at {k}: {:?}", f.diagnostics);
        }
    }

    #[test]
    fn corrupted_samples_never_panic_and_flag_bad_bytes(
        sample in 0usize..64,
        at in 0.0f64..1.0,
        op in 0u8..4,
        byte in any::<u8>(),
        len in 1usize..40,
    ) {
        let paths = sample_paths();
        let mut src = std::fs::read(&paths[sample % paths.len()]).unwrap();
        let k = ((src.len() as f64 * at) as usize).min(src.len());
        match op {
            0 => src.insert(k, byte),
            1 => { src.drain(k..(k + len).min(src.len())); }
            2 => if k < src.len() { src[k] = byte },
            _ => src.insert(k, 0x01),
        }
        let f = assert_sound(&src);
        if op == 3 {
            // A control byte in code (not in a comment, string or header) is a located error.
            let tok = rapid::tokenize(&src)
                .into_iter()
                .find(|t| (t.start as usize) <= k && k < t.end as usize)
                .unwrap();
            if tok.kind == rapid::TokenKind::Unknown {
                prop_assert!(
                    f.diagnostics.iter().any(|d| d.severity == Severity::Error && d.span.start == tok.start as usize),
                    "byte at {k}: {:?}", f.diagnostics
                );
                prop_assert!(f.opaque > 0);
            }
        }
    }
}

#[test]
fn hostile_nesting_is_reported_not_overflowed() {
    let inputs: Vec<Vec<u8>> = vec![
        [
            b"MODULE m\nPROC p()\nx:=".as_slice(),
            &b"-".repeat(200_000),
            b"1;\nENDPROC\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nPROC p()\nx:=".as_slice(),
            &b"NOT ".repeat(50_000),
            b"a;\nENDPROC\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nCONST num a:=".as_slice(),
            &b"[".repeat(200_000),
            b";\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nCONST num a:=".as_slice(),
            &b"(".repeat(200_000),
            b";\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nPROC p()\n".as_slice(),
            &b"IF a THEN\n".repeat(20_000),
            b"ENDPROC\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nPROC p()\n".as_slice(),
            &b"WHILE TRUE DO ".repeat(20_000),
            b"ENDPROC\nENDMODULE",
        ]
        .concat(),
        [
            b"MODULE m\nPROC p()\nf ".as_slice(),
            &b"g(".repeat(100_000),
            b";\nENDPROC\nENDMODULE",
        ]
        .concat(),
    ];
    for src in inputs {
        let f = assert_sound(&src);
        assert!(
            f.diagnostics.iter().any(|d| d.severity == Severity::Error),
            "{:?}",
            &f.diagnostics[..f.diagnostics.len().min(3)]
        );
    }
}

#[test]
fn inline_targets_with_external_axes_in_a_variable() {
    let src = b"MODULE m\nPROC p()\n  MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],rdkExtJoints],v100,z1,tool0;\n  MoveAbsJ [[0,0,0,0,90,0],rdkExtJoints],v100,z1,tool0;\n  p1 := [[1,2,3],[1,0,0,0]];\nENDPROC\nENDMODULE\n".to_vec();
    let f = rapid::parse_file(Path::new("x.mod"), src);
    let kinds: Vec<PositionKind> = f.positions().map(|p| p.kind).collect();
    assert_eq!(
        kinds,
        vec![PositionKind::Robtarget, PositionKind::Jointtarget]
    );
    assert!(
        f.positions()
            .all(|p| p.extax.is_empty() && p.skid(0) == Skid::Missing)
    );
    assert_eq!(
        f.position(0)
            .unwrap()
            .cartesian
            .as_ref()
            .unwrap()
            .translation(),
        Some([1.0, 2.0, 3.0])
    );
}

#[test]
fn calls_with_a_parenthesised_first_argument_are_calls() {
    let src = b"MODULE m\nPROC p()\n  Hand_MoveTo(10);\n  TPWrite(\"Err \"+ValToStr(ERRNO)+\" | x\");\n  SocketClose(sd);\n  Hand_MoveTo (5)+1,\\NoWait;\n  x := Fn(1);\n  MoveL Offs(p1,0,0,5),v100,z1,tool0;\nENDPROC\nENDMODULE\n";
    let tree = rapid::parse_tree(src);
    assert!(tree.diagnostics.is_empty(), "{:?}", tree.diagnostics);
    assert_eq!(tree.opaque, 0);
    let dump = tree.tree.dump(src);
    assert_eq!(dump.matches("Call@").count(), 5, "{dump}");
    assert_eq!(dump.matches("Assign@").count(), 1, "{dump}");
}

#[test]
fn a_missing_semicolon_ends_at_the_line_break_and_the_next_target_is_found() {
    // A generator wrote `WaitTime 1.000` without its `;`.
    let src = b"MODULE m\nPROC p()\n  WaitTime 1.000\n  MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v100,z1,tGun\\WObj:=wCar;\nENDPROC\nENDMODULE\n".to_vec();
    let f = rapid::parse_file(Path::new("gen.mod"), src.clone());
    assert!(f.round_trip);
    assert_eq!(f.opaque, 1);
    let errors: Vec<String> = f
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .map(|d| f.render(d))
        .collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    // Reported at the end of the broken line, not on the good line after it.
    assert!(
        errors[0].starts_with("gen.mod:3:17: error: expected"),
        "{}",
        errors[0]
    );
    assert_eq!(f.positions.len(), 1);
    let p = &f.position(0).unwrap();
    assert_eq!(p.line, 4);
    assert_eq!(p.usage.wobj.as_deref(), Some("wCar"));
    assert_eq!(p.usage.tool.as_deref(), Some("tGun"));
    // A broken continuation line is still one opaque statement up to its `;`.
    let src = b"MODULE m\nPROC p()\n  x := [1,2\n    3];\n  MoveL p1,v100,z1,tool0;\nENDPROC\nENDMODULE\n";
    let t = rapid::parse_tree(src);
    assert_eq!(t.diagnostics.len(), 1, "{:?}", t.diagnostics);
    assert_eq!(t.opaque, 1);
}

#[test]
fn frame_names_keep_the_first_spelling_and_compare_without_case() {
    // The same work object and tool written three ways, one holding the tool (`robhold`).
    let t = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]";
    let src = format!(
        "MODULE m\n  PERS wobjdata wStn:=[TRUE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n\
  CONST robtarget p1:={t};\n  CONST robtarget p2:={t};\n  CONST robtarget p3:={t};\n\
  PROC q()\n    MoveL p1, v100, z10, tPen\\WObj:= wStn ;\n    MoveL p1, v100, z10, TPEN\\WObj:=WSTN;\n\
    MoveL p2, v100, z10, TPEN\\WObj:=WSTN;\n    MoveL p2, v100, z10, tPen\\WObj:=wStn;\n\
    MoveL p3, v100, fine, tPen;\n  ENDPROC\nENDMODULE\n"
    );
    let f = rapid::parse_file(Path::new("w.mod"), src.into_bytes());
    assert!(f.diagnostics.is_empty(), "{:?}", f.diagnostics);
    let usage = |n: &str| {
        let u = pos(&f, n).usage;
        (
            u.wobj.as_deref().map(str::to_owned),
            u.tool.as_deref().map(str::to_owned),
            u.other_wobjs().len(),
            u.stationary_tool(),
            u.lines.to_vec(),
        )
    };
    let some = |s: &str| Some(s.to_owned());
    assert_eq!(
        usage("p1"),
        (some("wStn"), some("tPen"), 0, true, vec![7, 8])
    );
    assert_eq!(
        usage("p2"),
        (some("WSTN"), some("TPEN"), 0, true, vec![9, 10])
    );
    assert_eq!(
        usage("p3"),
        (some("wobj0"), some("tPen"), 0, false, vec![11])
    );
}

#[test]
fn a_tool_given_by_name_is_the_tool() {
    let src = b"MODULE m\nCONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nPROC p()\n  MoveL ToPoint:=p1, Speed:=v100, Tool:=tCam, Zone:=fine;\nENDPROC\nENDMODULE\n".to_vec();
    let f = rapid::parse_file(Path::new("n.mod"), src);
    assert!(f.diagnostics.is_empty(), "{:?}", f.diagnostics);
    let p = pos(&f, "p1");
    assert_eq!(p.usage.tool.as_deref(), Some("tCam"));
    assert_eq!(p.usage.wobj.as_deref(), Some("wobj0"));
}

#[test]
fn second_round_idioms_sample() {
    let f = load("cell_idioms.mod");
    // Robtargets inside the value of a record declared in the module are named by component,
    // once each, and a move through the component gives their usage.
    let named: Vec<String> = f
        .positions()
        .filter_map(|p| p.name.map(|n| n.to_string()))
        .collect();
    assert_eq!(
        named,
        vec![
            "seamA{1}.where",
            "seamA{2}.where",
            "jPark",
            "pPick",
            "pDrop"
        ]
    );
    assert_eq!(f.positions.len(), 7);
    let seam = pos(&f, "seamA{1}.where");
    assert_eq!(seam.usage.wobj.as_deref(), Some("wConveyor"));
    assert_eq!(seam.usage.lines, vec![57]);
    assert_eq!(
        seam.cartesian.as_ref().unwrap().translation(),
        Some([10.0, 0.0, 5.0])
    );
    assert!(pos(&f, "seamA{2}.where").usage.wobj.is_none());
    let pick = pos(&f, "pPick");
    assert_eq!(pick.usage.wobj.as_deref(), Some("wConveyor"));
    assert_eq!(pick.usage.tool.as_deref(), Some("tGripper"));
    // `9E+009` is "not connected", the track value is kept.
    let park = pos(&f, "jPark");
    assert_eq!(park.skid(0), Skid::At(0.0));
    assert_eq!(park.skid(1), Skid::NotConnected);
}

/// Inputs that once broke the parser or are kept as edge cases found while fuzzing
/// (`fuzz/`, see docs/notes-rapid.md): each must print back byte for byte, never panic, and
/// report every diagnostic inside the file.
#[test]
fn fuzz_regressions_replay() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/rapid");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/fuzz_regressions/rapid exists")
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for path in files {
        let src = std::fs::read(&path).unwrap();
        assert_eq!(rapid::print(&src), src, "{}", path.display());
        let f = rapid::parse_file(&path, src.clone());
        assert!(f.round_trip, "{}", path.display());
        assert!(
            f.diagnostics.iter().all(|d| d.span.end <= src.len()),
            "{}",
            path.display()
        );
        // Every one of them is broken somewhere: the break is reported, not swallowed.
        assert!(
            f.diagnostics.iter().any(|d| d.severity == Severity::Error),
            "{}",
            path.display()
        );
        let krl = trackfix::krl::parse_file(&path, src);
        assert!(krl.round_trip, "{}", path.display());
    }
}

/// Real programs, not committed (their text is not ours): point `TRACKFIX_RAPID_CORPUS` at a
/// directory of modules and run
/// `TRACKFIX_RAPID_CORPUS=dir cargo test --test it rapid::real_corpus -- --ignored --nocapture`.
/// Every file must round-trip; the report lists targets found, opaque nodes and diagnostics.
#[test]
#[ignore = "needs TRACKFIX_RAPID_CORPUS"]
#[allow(clippy::print_stdout)] // the report is the point of this manual check
fn real_corpus() {
    let Ok(dir) = std::env::var("TRACKFIX_RAPID_CORPUS") else {
        return;
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    for path in files {
        let src = std::fs::read(&path).unwrap();
        let f = rapid::parse_file(&path, src);
        let count = |k: PositionKind| f.positions().filter(|p| p.kind == k).count();
        println!(
            "{}: round_trip={} robtargets={} jointtargets={} frames={} opaque={}",
            path.display(),
            f.round_trip,
            count(PositionKind::Robtarget),
            count(PositionKind::Jointtarget),
            f.frames.len(),
            f.opaque
        );
        for d in &f.diagnostics {
            println!("{}", f.render(d));
        }
        assert!(f.round_trip, "{}", path.display());
    }
}
