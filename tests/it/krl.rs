//! Integration tests: KRL parsing, positions and base/tool resolution on `samples/krl/`.

use std::path::{Path, PathBuf};

use crate::support::texts;
use proptest::prelude::*;
use trackfix::krl;
use trackfix::position::{
    Config, FrameKind, Orientation, ParsedFile, Position, PositionKind, Program,
};
use trackfix::program::LoadOptions;
use trackfix::syntax::{NumLit, Severity};

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples/krl")
        .join(name)
}

fn all_samples() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/krl"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                matches!(
                    p.extension()
                        .and_then(|e| e.to_str())
                        .map(str::to_ascii_lowercase)
                        .as_deref(),
                    Some("src" | "dat" | "sub")
                )
            })
            .collect();
    v.sort();
    v
}

/// Load options with the samples' `$config.dat` as the cell's, inputs read (not mapped).
fn with_sample_config() -> LoadOptions {
    LoadOptions {
        krl_config_dat: Some(sample("$config.dat")),
        map_inputs: false,
        ..LoadOptions::default()
    }
}

/// The program of a `cell.src`/`cell.dat` pair, with the sample `$config.dat`.
fn load_cell_pair(src: &str, dat: &str) -> Program {
    krl::load_program_from_sources(
        vec![
            (PathBuf::from("cell.src"), src.as_bytes().to_vec()),
            (PathBuf::from("cell.dat"), dat.as_bytes().to_vec()),
        ],
        &with_sample_config(),
    )
    .unwrap()
}

fn parse_sample(name: &str) -> ParsedFile {
    let path = sample(name);
    krl::parse_file(&path, std::fs::read(&path).unwrap())
}

fn load(name: &str, config: bool) -> Program {
    let options = LoadOptions {
        krl_config_dat: config.then(|| sample("$config.dat")),
        map_inputs: false,
        ..LoadOptions::default()
    };
    krl::load_program(&sample(name), &options).unwrap()
}

/// One line per position: where, what, every field as written (read back through its span), and
/// how motions use it.
fn dump_position(src: &[u8], p: &Position) -> String {
    let mut s = format!("{}:{} {} {}", p.line, p.column, p.kind.as_str(), p.label());
    if let Some(c) = &p.cartesian {
        s += &format!(" xyz=[{}]", texts(src, &c.trans));
        if let Some(Orientation::Abc(abc)) = &c.orient {
            s += &format!(" abc=[{}]", texts(src, abc));
        }
    }
    if !p.joints.is_empty() {
        s += &format!(" axes=[{}]", texts(src, &p.joints));
    }
    if let Config::StatusTurn { status, turn } = &p.config {
        let bit = |b: &Option<trackfix::position::BitField>| match b {
            Some(b) => format!(
                "{}={}",
                String::from_utf8_lossy(b.span().slice(src)),
                b.value()
            ),
            None => "-".to_owned(),
        };
        s += &format!(" S={} T={}", bit(status), bit(turn));
    }
    if !p.extax.is_empty() {
        s += &format!(" E=[{}]", texts(src, &p.extax));
    }
    let u = &p.usage;
    if !u.lines.is_empty() {
        s += &format!(
            " | base={} tool={} lines={:?}",
            u.wobj.as_deref().unwrap_or("?"),
            u.tool.as_deref().unwrap_or("?"),
            u.lines
        );
        if !u.other_wobjs().is_empty() {
            s += &format!(" also={:?}", u.other_wobjs());
        }
        if u.stationary_tool() {
            s += " stationary-tool";
        }
    }
    s
}

fn dump_program(program: &Program) -> String {
    let mut out = String::new();
    for f in &program.files {
        out += &format!(
            "== {} ({} positions, {} frames, {} opaque, round_trip {})\n",
            f.path.file_name().unwrap().to_string_lossy(),
            f.positions.len(),
            f.frames.len(),
            f.opaque,
            f.round_trip
        );
        for p in f.positions() {
            out += &dump_position(&f.source, &p);
            out.push('\n');
        }
        for fr in &f.frames {
            let c = fr.frame.as_ref().unwrap();
            let abc = match &c.orient {
                Some(Orientation::Abc(abc)) => texts(&f.source, abc),
                _ => "-".to_owned(),
            };
            out += &format!(
                "{} {:?} {} xyz=[{}] abc=[{}]\n",
                fr.line,
                fr.kind,
                fr.name,
                texts(&f.source, &c.trans),
                abc
            );
        }
        for d in &f.diagnostics {
            let (l, c) = f.lines.line_col(d.span.start);
            out += &format!("{l}:{c} {}: {}\n", d.severity.as_str(), d.message);
        }
    }
    out
}

#[test]
fn every_sample_round_trips_byte_for_byte() {
    let samples = all_samples();
    assert!(samples.len() >= 8, "{samples:?}");
    for path in samples {
        let src = std::fs::read(&path).unwrap();
        let parse = krl::parse(&src);
        assert_eq!(parse.tree.print(&src), src, "{}", path.display());
        let file = krl::parse_file(&path, src);
        assert!(file.round_trip, "{}", path.display());
        let errors: Vec<_> = file
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .map(|d| file.render(d))
            .collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
        assert_eq!(file.opaque, 0, "{}", path.display());
    }
}

#[test]
fn samples_cover_the_encoding_oddities() {
    let bom = std::fs::read(sample("bom_cell.src")).unwrap();
    assert!(bom.starts_with(b"\xEF\xBB\xBF"));
    let spot = std::fs::read(sample("spot_line.src")).unwrap();
    assert!(spot.windows(2).any(|w| w == b"\r\n"));
    assert!(spot.windows(10).any(|w| w == b"Schwei\xDFpun"), "cp1252 ß");
    let low = std::fs::read(sample("lower_case.src")).unwrap();
    assert!(!low.ends_with(b"\n"));
    let sub = std::fs::read(sample("cell.sub")).unwrap();
    assert!(sub.windows(2).any(|w| w == b"\r\n"));
    assert!(sub.windows(2).any(|w| w[0] == b'\r' && w[1] != b'\n'));
}

#[test]
fn spot_line_has_160_points_on_the_track_resolved_through_fdat() {
    let program = load("spot_line.dat", true);
    let names: Vec<_> = program
        .files
        .iter()
        .map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["spot_line.src", "spot_line.dat", "$config.dat"]);
    let dat = &program.files[1];
    assert_eq!(dat.positions.len(), 161);
    let mut e1 = Vec::new();
    for p in dat.positions() {
        assert_eq!(p.kind, PositionKind::E6Pos);
        let trackfix::position::Skid::At(s) = p.skid(0) else {
            panic!("{} has no skid", p.label());
        };
        assert!(s > 0.0 && s < 8000.0, "{} at {s}", p.label());
        e1.push(s);
        assert!(p.cartesian.as_ref().unwrap().pose().is_some());
    }
    assert!(e1.iter().cloned().fold(0.0, f64::max) - e1[0] > 7500.0);
    let p12 = dat
        .positions()
        .find(|p| p.name.as_deref() == Some("XP12"))
        .unwrap();
    assert_eq!(p12.usage.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(p12.usage.tool.as_deref(), Some("TOOL_DATA[1]"));
    assert!(p12.usage.other_wobjs().is_empty());
    assert!(!p12.usage.stationary_tool());
    let src = &program.files[0];
    let line = src.lines.line(
        src.source
            .windows(b"LIN XP12 C_DIS".len())
            .position(|w| w == b"LIN XP12 C_DIS")
            .unwrap(),
    );
    assert_eq!(p12.usage.lines, [u32::try_from(line).unwrap()]);
    // P0 is taught in BASE_NO 0: the world.
    let p0 = &dat.position(0).unwrap();
    assert_eq!(p0.usage.wobj.as_deref(), Some("$WORLD"));
    // The spans point at the literal text.
    let e1 = p12.extax[0].as_ref().unwrap();
    assert_eq!(e1.span().slice(&dat.source), b"690.750");
    assert_eq!(NumLit::parse(b"690.750"), Some(e1.lit()));
    let cfg = &program.files[2];
    assert!(cfg.positions.is_empty());
    let bases: Vec<_> = cfg.frames.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        bases,
        [
            "TOOL_DATA[1]",
            "TOOL_DATA[2]",
            "TOOL_DATA[3]",
            "BASE_DATA[1]",
            "BASE_DATA[2]",
            "BASE_DATA[3]",
            "BASE_DATA[4]"
        ]
    );
}

#[test]
fn config_dat_bases_and_tools() {
    let frames = krl::load_config_dat(&sample("$config.dat")).unwrap();
    let base1 = frames.iter().find(|f| f.name == "BASE_DATA[1]").unwrap();
    assert_eq!(base1.kind, FrameKind::Base);
    let pose = base1.pose().unwrap();
    assert!(
        (pose.translation.vector - nalgebra::Vector3::new(2150.0, -1480.0, 720.0)).norm() < 1e-9
    );
    let tool1 = frames.iter().find(|f| f.name == "TOOL_DATA[1]").unwrap();
    assert_eq!(tool1.kind, FrameKind::Tool);
    // B -90: the tool z axis points along the flange x axis (KUKA R = Rz(A)·Ry(B)·Rx(C)).
    let z = tool1.pose().unwrap().rotation * nalgebra::Vector3::z();
    assert!(
        (z - nalgebra::Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12,
        "{z}"
    );
    // BASE_DATA[3] is in the file with fractional values; check the span text.
    let base3 = frames.iter().find(|f| f.name == "BASE_DATA[3]").unwrap();
    let src = std::fs::read(sample("$config.dat")).unwrap();
    let y = base3.frame.as_ref().unwrap().trans[1].as_ref().unwrap();
    assert_eq!(y.span().slice(&src), b"1350.25");
}

#[test]
fn binary_status_turn_and_kinds_in_bom_file() {
    let f = parse_sample("bom_cell.src");
    let kinds: Vec<_> = f.positions().map(|p| (p.label(), p.kind)).collect();
    assert_eq!(
        kinds,
        [
            ("XSTART".to_owned(), PositionKind::E6Pos),
            ("PCHECK".to_owned(), PositionKind::Pos),
            ("XPARK".to_owned(), PositionKind::E6Axis),
            ("AREST".to_owned(), PositionKind::Axis),
            ("FCHECK".to_owned(), PositionKind::Frame),
            ("inline E6POS".to_owned(), PositionKind::E6Pos),
            ("inline E6POS".to_owned(), PositionKind::E6Pos),
        ]
    );
    let Config::StatusTurn { status, turn } = &f.position(0).unwrap().config else {
        panic!()
    };
    let (s, t) = (status.as_ref().unwrap(), turn.as_ref().unwrap());
    assert_eq!((s.value(), s.binary_digits()), (2, Some(3)));
    assert_eq!((t.value(), t.binary_digits()), (35, Some(6)));
    assert_eq!(s.span().slice(&f.source), b"'B010'");
    assert_eq!(t.rewrite(35 ^ 0b101001).as_deref(), Some("'B001010'"));
    // Joint positions: A1..A6 and E1, no Cartesian part.
    let park = &f.position(2).unwrap();
    assert!(park.cartesian.is_none());
    assert_eq!(park.joints.len(), 6);
    assert_eq!(park.joints[4].as_ref().unwrap().value(), 35.5);
    assert_eq!(park.extax.len(), 1);
    // Every position is used, with BASE_DATA[1] and TOOL_DATA[2].
    for p in f.positions() {
        assert_eq!(
            p.usage.wobj.as_deref(),
            Some("BASE_DATA[1]"),
            "{}",
            p.label()
        );
        assert_eq!(p.usage.tool.as_deref(), Some("TOOL_DATA[2]"));
    }
}

#[test]
fn fdat_tcp_and_with_clauses_resolve() {
    let program = load("glue_tcp.src", false);
    let dat = &program.files[1];
    let by = |n: &str| {
        dat.positions()
            .find(|p| p.name.as_deref() == Some(n))
            .unwrap()
    };
    assert!(!by("XP1").usage.stationary_tool());
    assert_eq!(by("XP1").usage.wobj.as_deref(), Some("$WORLD"));
    for n in ["XP2", "XP3"] {
        assert!(by(n).usage.stationary_tool(), "{n}");
        assert_eq!(by(n).usage.wobj.as_deref(), Some("BASE_DATA[4]"));
        assert_eq!(by(n).usage.tool.as_deref(), Some("TOOL_DATA[2]"));
    }
    // SPTP … WITH $BASE=SBASE(FP4.BASE_NO), $TOOL=STOOL2(FP4), $IPO_MODE=SIPO_MODE(…).
    assert_eq!(by("XP4").usage.wobj.as_deref(), Some("BASE_DATA[2]"));
    assert_eq!(by("XP4").usage.tool.as_deref(), Some("TOOL_DATA[1]"));
    assert!(!by("XP4").usage.stationary_tool());
}

#[test]
fn a_point_used_with_two_bases_is_flagged() {
    let program = load("two_bases.dat", false);
    assert_eq!(program.files.len(), 2);
    let dat = &program.files[1];
    let shared = dat
        .positions()
        .find(|p| p.name.as_deref() == Some("XSHARED"))
        .unwrap();
    assert_eq!(shared.usage.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(shared.usage.other_wobjs(), ["BASE_DATA[2]"]);
    assert_eq!(shared.usage.lines, [8, 10]);
    // BAS(#BASE,1) before XEND; the second DEF starts over and leaves it unresolved.
    let end = dat
        .positions()
        .find(|p| p.name.as_deref() == Some("XEND"))
        .unwrap();
    assert_eq!(end.usage.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(end.usage.lines, [12, 16]);
    let src = &program.files[0];
    let warn: Vec<_> = src
        .diagnostics
        .iter()
        .map(|d| (src.lines.line(d.span.start), d.message.as_str()))
        .collect();
    assert_eq!(warn, [(16, "the base of this motion is not resolved")]);
}

#[test]
fn frames_are_targets_only_when_a_motion_uses_them() {
    let program = load("pallet.src", false);
    let dat = &program.files[1];
    let names: Vec<_> = dat.positions().map(|p| p.label()).collect();
    // FPALLET only appears in `:` expressions, FUNUSED nowhere: neither is a target.
    assert_eq!(names, ["XPICK_APP", "XPICK", "XPLACE_REL"]);
    let src = &program.files[0];
    // `SLOT = {…}` is a FRAME used only as an offset: not a position either.
    assert!(src.positions.is_empty(), "{:?}", src.positions);
    let warnings = src
        .diagnostics
        .iter()
        .filter(|d| d.message.starts_with("computed target"))
        .count();
    assert_eq!(warnings, 1);
    assert_eq!(
        dat.position(1).unwrap().usage.wobj.as_deref(),
        Some("BASE_DATA[3]")
    );
    assert_eq!(
        dat.position(1).unwrap().usage.tool.as_deref(),
        Some("TOOL_DATA[2]")
    );
    // A FRAME that a motion does use is a target (bom_cell's FCHECK).
    let f = parse_sample("bom_cell.src");
    let fcheck = f
        .positions()
        .find(|p| p.kind == PositionKind::Frame)
        .unwrap();
    assert_eq!(fcheck.config, Config::None);
}

#[test]
fn lowercase_file_without_final_newline() {
    let f = parse_sample("lower_case.src");
    assert!(f.round_trip);
    let labels: Vec<_> = f.positions().map(|p| (p.label(), p.line)).collect();
    assert_eq!(
        labels,
        [
            ("xa".to_owned(), 2),
            ("xb".to_owned(), 8),
            ("inline E6AXIS".to_owned(), 9),
            ("inline E6POS".to_owned(), 13),
            ("inline E6POS".to_owned(), 15),
        ]
    );
    for p in f.positions() {
        assert_eq!(
            p.usage.wobj.as_deref(),
            Some("BASE_DATA[2]"),
            "{}",
            p.label()
        );
    }
    let circ_aux = &f.position(4).unwrap();
    assert!(circ_aux.extax.is_empty());
    let c = circ_aux.cartesian.as_ref().unwrap();
    assert!(c.orient.is_none());
    assert_eq!(c.translation(), Some([130.0, 0.0, 300.0]));
}

#[test]
fn position_dumps() {
    for name in [
        "bom_cell.src",
        "glue_tcp.src",
        "lower_case.src",
        "pallet.src",
        "two_bases.src",
        "cell.sub",
    ] {
        let program = load(name, false);
        insta::assert_snapshot!(format!("positions_{name}"), dump_program(&program));
    }
    let program = load("spot_line.src", true);
    let dump = dump_program(&program);
    // The full 161-point dump is long; snapshot its head and tail.
    let lines: Vec<&str> = dump.lines().collect();
    let mut short: Vec<&str> = lines.iter().take(12).copied().collect();
    short.push("…");
    short.extend(lines.iter().skip(lines.len().saturating_sub(20)));
    insta::assert_snapshot!("positions_spot_line", short.join("\n"));
}

/// Every statement form the parser knows, in random order and case: prints back unchanged,
/// without diagnostics.
fn statement() -> impl Strategy<Value = String> {
    let num = (-5000.0f64..5000.0).prop_map(|v| format!("{v:.3}"));
    let ident = "[A-Z][A-Z0-9_]{0,6}".prop_map(|s| format!("X{s}"));
    prop_oneof![
        (ident.clone(), num.clone(), num.clone(), num.clone()).prop_map(|(n, x, y, z)| format!(
            "DECL E6POS {n}={{X {x},Y {y},Z {z},A 0.0,B 90.0,C 0.0,S 'B010',T 6,E1 {x}}}"
        )),
        (ident.clone(), num.clone()).prop_map(|(n, x)| format!("{n}={{X {x},Y 1}}")),
        (ident.clone()).prop_map(|n| format!("LIN {n} C_DIS")),
        (num.clone(), num.clone()).prop_map(|(x, y)| format!("lin {{x {x}, y {y}, z 0}} c_vel")),
        (ident.clone(), ident.clone()).prop_map(|(a, b)| format!("CIRC {a}, {b}, CA 90.0 C_ORI")),
        (1u32..32).prop_map(|n| format!("$BASE=BASE_DATA[{n}]")),
        (1u32..16).prop_map(|n| format!("BAS(#TOOL,{n})")),
        Just("WAIT SEC 0.5".to_owned()),
        Just("; comment with \u{e4}".to_owned()),
        Just(";FOLD LIN P1;%{PE}%R 8.3.31,%P 1:LIN".to_owned()),
        Just(";ENDFOLD".to_owned()),
        Just("".to_owned()),
        Just("  \t".to_owned()),
        (ident.clone(), num.clone()).prop_map(|(n, x)| format!("E6POS {n}={{X {x},E1 {x}}}")),
        (ident.clone()).prop_map(|n| format!(
            "decl fdat F{n}={{TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] \" \"}}"
        )),
        (ident.clone()).prop_map(|n| format!("FDAT_ACT=F{n}")),
        (ident.clone()).prop_map(|n| format!(
            "SPTP {n} WITH $BASE=SBASE(F{n}.BASE_NO), $TOOL=STOOL2(F{n}) C_SPL"
        )),
        (ident.clone(), ident.clone()).prop_map(|(a, b)| format!("{a} = {a}:{b}")),
        (num.clone()).prop_map(|x| format!("PTP {{A1 {x},A2 -90,A3 90,A4 0,A5 0,A6 0}}")),
        (1u32..32, num.clone())
            .prop_map(|(n, x)| format!("BASE_DATA[{n}]={{X {x},Y 0,Z 0,A 0,B 0,C 0}}")),
        Just("TRIGGER WHEN DISTANCE=0 DELAY=20 DO $OUT[2]=TRUE PRIO=-1".to_owned()),
        Just("\t$OUT[3] = NOT $IN[1] AND ($IN[2] OR $IN[3])".to_owned()),
        Just("INT I".to_owned()),
        Just("HALT".to_owned()),
        Just("IF $IN[1] THEN".to_owned()),
        Just("ENDIF".to_owned()),
        Just("&REL 3".to_owned()),
    ]
}

fn newline() -> impl Strategy<Value = &'static str> {
    prop_oneof![Just("\n"), Just("\r\n"), Just("\r")]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn generated_programs_round_trip(
        body in prop::collection::vec((statement(), newline()), 0..40),
        bom in any::<bool>(),
        last_newline in any::<bool>(),
    ) {
        let mut src: Vec<u8> = Vec::new();
        if bom {
            src.extend_from_slice(b"\xEF\xBB\xBF");
        }
        src.extend_from_slice(b"DEF gen( )\r\n");
        for (s, nl) in &body {
            src.extend_from_slice(s.as_bytes());
            src.extend_from_slice(nl.as_bytes());
        }
        src.extend_from_slice(b"END");
        if last_newline {
            src.extend_from_slice(b"\n");
        }
        let parse = krl::parse(&src);
        prop_assert_eq!(parse.tree.print(&src), src.clone());
        prop_assert_eq!(parse.opaque, 0);
        let file = krl::parse_file(Path::new("gen.src"), src);
        prop_assert!(file.round_trip);
    }

    /// Every generated `E6POS` declaration is found, and every field's span holds the text
    /// that was written for it.
    #[test]
    fn generated_dat_positions_are_all_found(
        points in prop::collection::vec(
            (
                prop::array::uniform6(-9999.0f64..9999.0),
                0u32..8,
                0u32..64,
                1.0f64..7999.0,
                any::<bool>(),
            ),
            1..30,
        ),
    ) {
        let mut src = String::from("&ACCESS RVP\r\nDEFDAT gen PUBLIC\r\n");
        let mut expected = Vec::new();
        for (i, (v, s, t, e1, binary)) in points.iter().enumerate() {
            let texts: Vec<String> = v.iter().map(|x| format!("{x:.4}")).collect();
            let (st, tt) = if *binary {
                (format!("'B{s:03b}'"), format!("'B{t:06b}'"))
            } else {
                (s.to_string(), t.to_string())
            };
            src += &format!(
                "DECL E6POS XP{i}={{X {},Y {},Z {},A {},B {},C {},S {st},T {tt},E1 {e1:.3},E2 0.0}}\r\n",
                texts[0], texts[1], texts[2], texts[3], texts[4], texts[5]
            );
            expected.push((texts, *s, *t, format!("{e1:.3}")));
        }
        src += "ENDDAT\r\n";
        let file = krl::parse_file(Path::new("gen.dat"), src.into_bytes());
        prop_assert!(file.diagnostics.is_empty(), "{:?}", file.diagnostics);
        prop_assert_eq!(file.positions.len(), expected.len());
        for (p, (texts, s, t, e1)) in file.positions().zip(&expected) {
            let c = p.cartesian.as_ref().unwrap();
            let Some(Orientation::Abc(abc)) = &c.orient else { panic!() };
            let got: Vec<&[u8]> = c.trans.iter().chain(abc.iter())
                .map(|f| f.as_ref().unwrap().span().slice(&file.source))
                .collect();
            let want: Vec<&[u8]> = texts.iter().map(|t| t.as_bytes()).collect();
            prop_assert_eq!(got, want);
            let Config::StatusTurn { status, turn } = &p.config else { panic!() };
            prop_assert_eq!(status.as_ref().unwrap().value(), *s);
            prop_assert_eq!(turn.as_ref().unwrap().value(), *t);
            prop_assert_eq!(p.extax.len(), 2);
            prop_assert_eq!(p.extax[0].as_ref().unwrap().span().slice(&file.source), e1.as_bytes());
        }
    }

    #[test]
    fn arbitrary_bytes_round_trip_and_never_panic(src in prop::collection::vec(any::<u8>(), 0..400)) {
        let parse = krl::parse(&src);
        prop_assert_eq!(parse.tree.print(&src), src.clone());
        let file = krl::parse_file(Path::new("x.src"), src);
        prop_assert!(file.round_trip);
        for d in &file.diagnostics {
            prop_assert!(d.span.end <= file.source.len());
        }
    }

    #[test]
    fn corrupted_samples_never_panic_and_report_located(
        which in 0usize..12,
        cut in any::<prop::sample::Index>(),
        at in any::<prop::sample::Index>(),
        byte in any::<u8>(),
        truncate in any::<bool>(),
    ) {
        let samples = all_samples();
        let path = &samples[which % samples.len()];
        let mut src = std::fs::read(path).unwrap();
        let original = krl::parse_file(path, src.clone());
        if truncate {
            src.truncate(cut.index(src.len() + 1));
        } else {
            let i = at.index(src.len());
            src[i] = byte;
        }
        let file = krl::parse_file(path, src.clone());
        prop_assert!(file.round_trip);
        for d in &file.diagnostics {
            prop_assert!(d.span.end <= src.len());
            let rendered = file.render(d);
            let prefix = format!("{}:", path.display());
            prop_assert!(rendered.starts_with(&prefix));
        }
        // Cutting a sample inside a routine (DEF … END, DEFDAT … ENDDAT), or before its first
        // routine, always leaves a trace: an opaque line, a located error, or a warning.
        let tree = krl::parse(&original.source).tree;
        let mut routines = Vec::new();
        let mut open = None;
        for node in &tree.nodes {
            let span = tree.node_span(node);
            match node.kind {
                krl::NodeKind::RoutineStart => open = Some(span.start),
                krl::NodeKind::RoutineEnd => {
                    if let Some(start) = open.take() {
                        let end = span.start
                            + krl::lex(span.slice(&original.source))
                                .iter()
                                .rev()
                                .find(|t| !t.kind.is_trivia())
                                .map_or(0, |t| t.end as usize);
                        routines.push((start, end));
                    }
                }
                _ => {}
            }
        }
        let cut_at = src.len();
        let inside = routines.iter().any(|&(a, b)| a < cut_at && cut_at < b)
            || routines.first().is_none_or(|&(a, _)| cut_at <= a);
        if truncate && inside {
            let noticed = file.opaque > 0
                || file.diagnostics.iter().any(|d| d.severity >= Severity::Warning);
            prop_assert!(noticed, "cut at {} of {}", cut_at, path.display());
        }
    }
}

/// Real programs, not committed (their text is not ours): point `TRACKFIX_KRL_CORPUS` at a
/// directory of `.src`/`.dat`/`.sub` files and run
/// `TRACKFIX_KRL_CORPUS=dir cargo test --test it krl::real_corpus -- --ignored --nocapture`.
/// Every file must round-trip; every `E6POS`/`POS`/`E6AXIS`/`AXIS` declared with a value must
/// be found.
#[test]
#[ignore = "needs TRACKFIX_KRL_CORPUS"]
#[allow(clippy::print_stdout)] // the report is the point of this manual check
fn real_corpus() {
    let Ok(dir) = std::env::var("TRACKFIX_KRL_CORPUS") else {
        return;
    };
    let mut files = crate::support::files_under(Path::new(&dir));
    files.retain(|p| trackfix::program::language_of(p) == Some(trackfix::position::Language::Krl));
    for path in files {
        let src = std::fs::read(&path).unwrap();
        let declared = src
            .split(|&b| b == b'\n' || b == b'\r')
            .filter(|l| {
                let l = String::from_utf8_lossy(l).to_ascii_uppercase();
                let l = l.trim_start();
                let l = l.strip_prefix("DECL ").unwrap_or(l);
                let l = l.strip_prefix("GLOBAL ").unwrap_or(l);
                ["E6POS ", "POS ", "E6AXIS ", "AXIS "]
                    .iter()
                    .any(|t| l.starts_with(t))
                    && l.contains('=')
            })
            .count();
        let file = krl::parse_file(&path, src);
        let program = krl::load_program(&path, &LoadOptions::default()).unwrap();
        let found = file
            .positions()
            .filter(|p| p.name.is_some() && p.kind != PositionKind::Frame)
            .count();
        let frames_used = program
            .files
            .iter()
            .flat_map(|f| f.positions())
            .filter(|p| p.kind == PositionKind::Frame)
            .count();
        let errors: Vec<String> = file
            .diagnostics
            .iter()
            .filter(|d| d.severity >= Severity::Warning)
            .map(|d| file.render(d))
            .collect();
        println!(
            "{}: round_trip={} declared={declared} found={found} frames_used={frames_used} bases/tools={} opaque={} diagnostics={}",
            path.display(),
            file.round_trip,
            file.frames.len(),
            file.opaque,
            errors.len()
        );
        for e in errors.iter().take(5) {
            println!("{e}");
        }
        for p in program.files.iter().flat_map(|f| f.positions()).take(12) {
            println!(
                "    {} {} base={:?} tool={:?} lines={:?}",
                p.kind.as_str(),
                p.label(),
                p.usage.wobj,
                p.usage.tool,
                p.usage.lines
            );
        }
        assert!(file.round_trip);
        assert_eq!(declared, found, "{}", path.display());
    }
}

/// The tree, one line per node (routines and blocks as branches), and the diagnostics: a valid file and a
/// damaged one (rust-analyzer's `test_data/{ok,err}` in small).
#[test]
fn tree_dumps() {
    let ok = std::fs::read(sample("lower_case.src")).unwrap();
    insta::assert_snapshot!("tree_lower_case", krl::parse(&ok).tree.dump(&ok));
    let err: &[u8] = b"DEF broken( )\r\n  IF $IN[1] THEN\r\n    LIN {X 10, Y 20 Z 30} C_DIS\r\n    FROB XP1\r\n    S = \"open\r\n  ENDFOR\r\n  WAIT SEC 1\r\n";
    let file = krl::parse_file(Path::new("broken.src"), err.to_vec());
    let mut dump = krl::parse(err).tree.dump(err);
    for d in &file.diagnostics {
        dump += &file.render(d);
    }
    assert!(file.round_trip);
    insta::assert_snapshot!("tree_broken", dump);
}

#[test]
fn pair_lookup_any_case_and_declared_types_across_the_pair() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("Cell.SRC"),
        "DEF cell( )\r\n  BAS(#BASE,2)\r\n  XP1={X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 3}\r\n  F1={X 1}\r\n  XQ={X 5,Y 6,Z 7}\r\n  LIN XQ\r\nEND\r\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("cell.dat"),
        "DEFDAT cell\r\n  DECL POS XP1\r\n  DECL FRAME F1\r\nENDDAT\r\n",
    )
    .unwrap();
    let named_dat =
        krl::load_program(&dir.path().join("cell.dat"), &LoadOptions::default()).unwrap();
    let names: Vec<_> = named_dat
        .files
        .iter()
        .map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["Cell.SRC", "cell.dat"]);
    let src = &named_dat.files[0];
    let found: Vec<_> = src
        .positions()
        .map(|p| {
            (
                p.label(),
                p.kind,
                p.usage.wobj.as_deref().map(str::to_owned),
            )
        })
        .collect();
    assert_eq!(
        found,
        [
            ("XP1".to_owned(), PositionKind::Pos, None),
            (
                "XQ".to_owned(),
                PositionKind::E6Pos,
                Some("BASE_DATA[2]".to_owned())
            ),
        ]
    );
    // A lone file loads alone; a .sub never pairs.
    std::fs::write(dir.path().join("alone.sub"), "DEF alone( )\r\nEND\r\n").unwrap();
    let alone = krl::load_program(&dir.path().join("alone.sub"), &LoadOptions::default()).unwrap();
    assert_eq!(alone.files.len(), 1);
    assert_eq!(krl::partner_of(&dir.path().join("alone.sub")), None);
}

#[test]
fn collect_inputs_lists_a_pair_once_in_any_case() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("Cell.SRC"), "DEF cell( )\r\nEND\r\n").unwrap();
    std::fs::write(d.join("cell.dat"), "DEFDAT cell\r\nENDDAT\r\n").unwrap();
    std::fs::write(d.join("lone.dat"), "DEFDAT lone\r\nENDDAT\r\n").unwrap();
    std::fs::write(d.join("other.src"), "DEF other( )\r\nEND\r\n").unwrap();
    let names = |paths: Vec<PathBuf>| -> Vec<String> {
        paths
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect()
    };
    let listed = trackfix::program::collect_inputs(&[d.to_owned()]).unwrap();
    assert_eq!(names(listed), ["Cell.SRC", "lone.dat", "other.src"]);
    // Named explicitly, in either order and spelled differently, the pair is still one program.
    let named = trackfix::program::collect_inputs(&[
        d.join("cell.dat"),
        d.join(".").join("Cell.SRC"),
        d.join("Cell.SRC"),
    ])
    .unwrap();
    assert_eq!(names(named), ["Cell.SRC"]);
}

#[test]
fn program_from_sources_in_memory_matches_the_program_from_disk() {
    let options = with_sample_config();
    for name in [
        "spot_line.src",
        "glue_tcp.dat",
        "two_bases.src",
        "pallet.src",
    ] {
        let from_disk = krl::load_program(&sample(name), &options).unwrap();
        // Given .dat first: the in-memory build still puts the .src first.
        let mut sources: Vec<(PathBuf, Vec<u8>)> = from_disk
            .files
            .iter()
            .filter(|f| !f.path.ends_with("$config.dat"))
            .map(|f| (f.path.clone(), f.source.to_vec()))
            .collect();
        sources.reverse();
        let in_memory = krl::load_program_from_sources(sources.clone(), &options).unwrap();
        let summary = |p: &Program| -> Vec<String> {
            p.files
                .iter()
                .flat_map(|f| {
                    std::iter::once(f.path.display().to_string()).chain(f.positions().map(|pos| {
                        format!(
                            "{} {:?} {:?} {:?} {:?}",
                            pos.label(),
                            pos.usage.wobj,
                            pos.usage.tool,
                            pos.usage.stationary_tool(),
                            pos.usage.lines
                        )
                    }))
                })
                .collect()
        };
        assert_eq!(summary(&in_memory), summary(&from_disk), "{name}");
        assert!(summary(&from_disk).iter().any(|s| s.contains("BASE_DATA[")));
        // The $config.dat may come in memory too, named in any case.
        sources.push((
            PathBuf::from("$CONFIG.DAT"),
            std::fs::read(sample("$config.dat")).unwrap(),
        ));
        let all_in_memory =
            krl::load_program_from_sources(sources, &LoadOptions::default()).unwrap();
        let frames = |p: &Program| p.files.last().map(|f| f.frames.len());
        assert_eq!(frames(&all_in_memory), frames(&from_disk));
        assert!(all_in_memory.files.last().unwrap().positions.is_empty());
    }
}

#[test]
fn frame_array_moved_to_with_a_computed_index_makes_every_element_a_target() {
    // A stacking cell: three FRAMEs in an array, the routine picks one at run time.
    let files = vec![
        (
            PathBuf::from("stack.src"),
            b"DEF stack( )\n  BAS(#BASE,2)\n  FOR I = 1 TO 3\n    SPTP TOPS[I] C_DIS\n    SLIN LIFT(ONTOP[I], 2)\n  ENDFOR\nEND\n".to_vec(),
        ),
        (
            PathBuf::from("stack.dat"),
            b"DEFDAT stack\nDECL FRAME TOPS[3]\nTOPS[1]={X 600,Y -30,Z 330,A 90,B 0,C 180}\nTOPS[2]={X 600,Y 150,Z 330,A 90,B 0,C 180}\nDECL FRAME ONTOP[3]\nONTOP[1]={X 600,Y -30,Z 60,A 90,B 0,C 180}\nENDDAT\n".to_vec(),
        ),
    ];
    let program = krl::load_program_from_sources(files, &LoadOptions::default()).unwrap();
    let found: Vec<_> = program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .map(|p| {
            (
                p.label(),
                p.usage.wobj.as_deref().map(str::to_owned),
                p.usage.lines.to_vec(),
            )
        })
        .collect();
    assert_eq!(
        found,
        [
            (
                "TOPS[1]".to_owned(),
                Some("BASE_DATA[2]".to_owned()),
                vec![4]
            ),
            (
                "TOPS[2]".to_owned(),
                Some("BASE_DATA[2]".to_owned()),
                vec![4]
            ),
        ]
    );
}

#[test]
fn a_joint_target_needs_no_base_a_cartesian_one_does() {
    let src = b"DEF rsi( )\n  PTP {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}\n  LIN {X 600, Y 0, Z 900, A 0, B 90, C 0}\nEND\n";
    let file = krl::parse_file(Path::new("rsi.src"), src.to_vec());
    let warned: Vec<usize> = file
        .diagnostics
        .iter()
        .filter(|d| d.message.contains("base of this motion"))
        .map(|d| file.lines.line(d.span.start))
        .collect();
    assert_eq!(warned, [3]);
}

/// Inputs kept from `cargo fuzz run krl_round_trip` (`fuzz/fuzz_targets/krl_round_trip.rs`):
/// each is cut at its first NUL into a `.src` and a `.dat`, as the fuzz target does, and must
/// print back byte for byte with every reported span inside its file.
#[test]
fn fuzz_regressions_replay() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/krl");
    let mut replayed = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let data = std::fs::read(&path).unwrap();
        let (src, dat) = match data.iter().position(|&b| b == 0) {
            Some(i) => (&data[..i], &data[i + 1..]),
            None => (&data[..], &data[..0]),
        };
        assert_eq!(krl::parse(src).tree.print(src), src, "{}", path.display());
        let files = vec![
            (PathBuf::from("fuzz.dat"), dat.to_vec()),
            (PathBuf::from("fuzz.src"), src.to_vec()),
        ];
        let program = krl::load_program_from_sources(files, &LoadOptions::default()).unwrap();
        for file in &program.files {
            assert!(file.round_trip, "{}", path.display());
            let len = file.source.len();
            for d in &file.diagnostics {
                assert!(d.span.start <= d.span.end && d.span.end <= len);
                assert!(file.render(d).starts_with("fuzz."));
            }
            for p in file.positions() {
                assert!(p.span.end <= len);
            }
        }
        replayed += 1;
    }
    assert!(replayed >= 7, "only {replayed} regression inputs found");
}

/// Constructs met in real KSS backups in round two, written anew: each parses with no opaque
/// line and no error, and only true targets become positions.
#[test]
fn kss_backup_oddities_parse_cleanly() {
    let machine = "&ACCESS RV$\r\n&PARAM VERSION = 1.0.0\r\nDEFDAT  $MACHINE PUBLIC\r\n\
        DECL FRA $COUPLING[6,6] ;N = numerator, D = denominator\r\n$COUPLING[4,5]={N -3,D 91}\r\n\
        FRAME $ROBROOT={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0} ;robot in world\r\n\
        DECL CYLINDER $CYLSPACE[8]\r\n$CYLSPACE[1]={X 1.0,Y 2.0,Z 3.0,A 0.0,B 0.0,C 0.0,Z1 0.0,Z2 0.0,R 0.0,MODE #OFF,STATE FALSE}\r\n\
        INT $CAL_ORDER[12]\r\n$CAL_ORDER[12]='B100000000000'\r\nENDDAT\r\n";
    let program = "&ACCESS RVP\nDEF  grind (nStation :IN, nTool: IN)\n\
        INT nStation, nTool\n\
        IF ($T1 OR $T2)THEN\n   GLOBAL INTERRUPT DECL 3 WHEN $STOPMESS==TRUE DO IR_STOPM ( )\n   INTERRUPT ON 3\nENDIF\n\
        ;;// a comment written with two semicolons\n\
        SWITCH($ERR.NUMBER)\n  CASE 0\n    ;ok\n  CASE 1430\n    GLOBAL INTERRUPT DECL 3 WHEN $STOPMESS==TRUE DO IR_STOPM ()\n  DEFAULT\n    ERR_RAISE($ERR)\nENDSWITCH\n\
        ;FOLD SPTP P1 CONT ;%{PE}\n\
        SPTP XP1 WITH $VEL_AXIS[1] = SVEL_JOINT(100.0), $TOOL = STOOL2(FP1), $BASE = SBASE(FP1.BASE_NO), $IPO_MODE = SIPO_MODE(FP1.IPO_FRAME), $APO = SAPO_PTP(PPDAT1) C_Spl\n\
        ;ENDFOLD\n\
        BASE_DATA[12] = BASE_DATA[nStation]:SHIFT[nStation]\n\
        IF (nTool > 0) Then\n  $BASE=EK(MACHINE_DEF[2].ROOT,MACHINE_DEF[2].MECH_TYPE,BASE_DATA[3])\nEndIf\nEND\n\
        ;ENDFOLD GRIND ()\n;FOLD {H}\nDEF helper( )\n\tCONTINUE\nEND\n;ENDFOLD";
    let data = "DEFDAT grind\nDECL E6POS XP1={X 10.0,Y 20.0,Z 30.0,A 0.0,B 90.0,C 0.0,S 2,T 35,E1 4100.0}\n\
        DECL FDAT FP1={TOOL_NO 2,BASE_NO 4,IPO_FRAME #BASE,POINT2[] \" \"}\nENDDAT\n";
    let loaded = krl::load_program_from_sources(
        vec![
            (PathBuf::from("$MACHINE.DAT"), machine.as_bytes().to_vec()),
            (PathBuf::from("grind.src"), program.as_bytes().to_vec()),
            (PathBuf::from("grind.dat"), data.as_bytes().to_vec()),
        ],
        &LoadOptions::default(),
    )
    .unwrap();
    for file in &loaded.files {
        assert!(file.round_trip, "{}", file.path.display());
        assert_eq!(file.opaque, 0, "{}", file.path.display());
        let errors: Vec<_> = file
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .map(|d| file.render(d))
            .collect();
        assert!(errors.is_empty(), "{errors:?}");
    }
    let found: Vec<_> = loaded
        .files
        .iter()
        .flat_map(|f| f.positions())
        .map(|p| {
            (
                p.label(),
                p.usage.wobj.as_deref().map(str::to_owned),
                p.usage.tool.as_deref().map(str::to_owned),
            )
        })
        .collect();
    // `$ROBROOT` and the `$` workspace literal are system data, not targets.
    assert_eq!(
        found,
        [(
            "XP1".to_owned(),
            Some("BASE_DATA[4]".to_owned()),
            Some("TOOL_DATA[2]".to_owned())
        )]
    );
}

/// A run reads the cell's `$config.dat` once for all its programs: the options (and their
/// clones) keep the first reading, so a program loaded after the file changed on disk still
/// gets the frames read first, and a program of its own options the new ones.
#[test]
fn the_cells_config_dat_is_read_once_for_every_program_of_a_run() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("$config.dat");
    std::fs::copy(sample("$config.dat"), &config).unwrap();
    for name in ["spot_line.src", "spot_line.dat", "pallet.src", "pallet.dat"] {
        std::fs::copy(sample(name), dir.path().join(name)).unwrap();
    }
    let options = LoadOptions {
        krl_config_dat: Some(config.clone()),
        ..LoadOptions::default()
    };
    let frames = |p: &Program| {
        let cfg = p.files.last().unwrap();
        assert_eq!(cfg.path, config);
        cfg.frames
            .iter()
            .map(|f| (f.name.clone(), f.pose()))
            .collect::<Vec<_>>()
    };
    let first = krl::load_program(&dir.path().join("spot_line.src"), &options).unwrap();
    let read_first = frames(&first);
    assert!(read_first.len() >= 2, "{read_first:?}");
    // The file is now one base only; the run's options, cloned or not, keep what they read.
    std::fs::write(
        &config,
        "DEFDAT $CONFIG\nDECL GLOBAL FRAME BASE_DATA[32]\nBASE_DATA[1]={X 1,Y 2,Z 3,A 0,B 0,C 0}\nENDDAT\n",
    )
    .unwrap();
    let later = krl::load_program(&dir.path().join("pallet.src"), &options.clone()).unwrap();
    assert_eq!(frames(&later), read_first);
    let fresh = LoadOptions {
        krl_config_dat: Some(config.clone()),
        ..LoadOptions::default()
    };
    let new_run = krl::load_program(&dir.path().join("pallet.src"), &fresh).unwrap();
    assert_eq!(frames(&new_run).len(), 1);
}

/// A declared position that gives a field twice, or a field its type lacks, is an error at the
/// field (KSS does not load the file): the transforms then refuse the file. Case does not
/// matter (`a1` is `A1`); a partial aggregate in any order is fine.
#[test]
fn a_field_given_twice_or_unknown_is_an_error() {
    let dat = "DEFDAT m PUBLIC\nDECL E6POS XP1={X 410.0,Y -95.0,Z 230.0,A 180.0,B 0.0,C 180.0,S 6,T 27,E1 1500.0,X 500.0}\nDECL E6POS XP2={X 410.0,Y -95.0,Q 7.0}\nDECL E6AXIS XJ={A1 0.0,A2 -90.0,E1 5.0,a1 3.0}\nDECL FRAME F1={x 1,y 2,z 3,a 0,b 0,c 0}\nDECL POS P1={X 1,Y 2,E1 3}\nDECL E6POS XP3={E1 1500.0,T 2,X 1.0}\nENDDAT\n";
    let f = krl::parse_file(Path::new("m.dat"), dat.as_bytes().to_vec());
    let errors: Vec<(usize, usize, &str)> = f
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .map(|d| {
            let (l, c) = f.lines.line_col(d.span.start);
            (l, c, d.message.as_str())
        })
        .collect();
    assert_eq!(
        errors,
        [
            (2, 82, "E6POS `XP1` gives field `X` twice"),
            (3, 33, "E6POS `XP2` has no field `Q`"),
            (4, 40, "E6AXIS `XJ` gives field `a1` twice"),
            (6, 22, "POS `P1` has no field `E1`"),
        ]
    );
}

/// The base, tool and stationary-tool mode of each named point of a program, by name.
fn frames_by_name(program: &Program) -> Vec<(String, Option<String>, Vec<String>, bool)> {
    program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .filter_map(|p| {
            Some((
                p.name.as_deref()?.to_owned(),
                p.usage.wobj.as_deref().map(str::to_owned),
                p.usage
                    .other_wobjs()
                    .iter()
                    .map(|w| w.to_string())
                    .collect(),
                p.usage.stationary_tool(),
            ))
        })
        .collect()
}

/// `FDAT_ACT = …` only stages frame data: KSS applies its base, tool and IPO mode when
/// `BAS(#PTP_PARAMS, …)`, `BAS(#CP_PARAMS, …)` or `BAS(#FRAMES)` runs (what an inline form does
/// right after it). A motion between the two moves with what was in effect before; what a
/// routine stages is applied by a `BAS` call after it; stagings that disagree between branches
/// leave the base unknown; a `BAS` with nothing staged before it applies what `FDAT_ACT` held on
/// entry, which is not known.
#[test]
fn krl_fdat_act_takes_effect_at_the_next_bas_call() {
    let src = "DEF fdat( )\n\
        \x20 $BASE=BASE_DATA[1]\n\
        \x20 $TOOL=TOOL_DATA[1]\n\
        \x20 FDAT_ACT=FP2\n\
        \x20 LIN XA\n\
        \x20 BAS(#CP_PARAMS,2)\n\
        \x20 LIN XB\n\
        \x20 FDAT_ACT={TOOL_NO 5,BASE_NO 6,IPO_FRAME #TCP}\n\
        \x20 PTP XC\n\
        \x20 BAS (#FRAMES )\n\
        \x20 PTP XD\n\
        \x20 stage( )\n\
        \x20 LIN XE\n\
        \x20 BAS(#PTP_PARAMS,100)\n\
        \x20 PTP XF\n\
        \x20 FDAT_ACT=FP2\n\
        \x20 IF $IN[1] THEN\n\
        \x20   FDAT_ACT=FP7\n\
        \x20 ENDIF\n\
        \x20 BAS(#CP_PARAMS,2)\n\
        \x20 LIN XG\n\
        END\n\
        DEF stage( )\n\
        \x20 FDAT_ACT=FP7\n\
        END\n\
        DEF staged_in_a_loop( )\n\
        \x20 FDAT_ACT=FP2\n\
        \x20 BAS(#CP_PARAMS,2)\n\
        \x20 LOOP\n\
        \x20   LIN XH\n\
        \x20   FDAT_ACT=FP7\n\
        \x20 ENDLOOP\n\
        END\n\
        DEF applied_in_a_loop( )\n\
        \x20 FDAT_ACT=FP2\n\
        \x20 FOR I=1 TO 2\n\
        \x20   BAS(#CP_PARAMS,2)\n\
        \x20   LIN XI\n\
        \x20   FDAT_ACT=FP7\n\
        \x20 ENDFOR\n\
        END\n\
        DEF nothing_staged( )\n\
        \x20 $BASE=BASE_DATA[1]\n\
        \x20 BAS(#PTP_PARAMS,100)\n\
        \x20 PTP XJ\n\
        END\n";
    let mut dat = String::from("DEFDAT fdat\n");
    for n in ["XA", "XB", "XC", "XD", "XE", "XF", "XG", "XH", "XI", "XJ"] {
        dat += &format!("DECL E6POS {n}={{X 1,Y 2,Z 3,A 0,B 0,C 0,E1 100}}\n");
    }
    dat += "DECL FDAT FP2={TOOL_NO 3,BASE_NO 2,IPO_FRAME #BASE}\n\
        DECL FDAT FP7={TOOL_NO 3,BASE_NO 7,IPO_FRAME #BASE}\nENDDAT\n";
    let program = krl::load_program_from_sources(
        vec![
            (PathBuf::from("fdat.src"), src.as_bytes().to_vec()),
            (PathBuf::from("fdat.dat"), dat.into_bytes()),
        ],
        &LoadOptions::default(),
    )
    .unwrap();
    let base = |n: u32| Some(format!("BASE_DATA[{n}]"));
    let at = |name: &str, wobj: Option<String>, others: &[&str], tcp: bool| {
        (
            name.to_owned(),
            wobj,
            others.iter().map(|o| (*o).to_owned()).collect::<Vec<_>>(),
            tcp,
        )
    };
    assert_eq!(
        frames_by_name(&program),
        [
            at("XA", base(1), &[], false),
            at("XB", base(2), &[], false),
            at("XC", base(2), &[], false),
            at("XD", base(6), &[], true),
            at("XE", base(6), &[], true),
            at("XF", base(7), &[], false),
            at("XG", None, &[], false),
            at("XH", base(2), &[], false),
            at("XI", base(2), &["BASE_DATA[7]"], false),
            // Nor what IPO frame it held: it may have been #TCP.
            at("XJ", None, &[], true),
        ]
    );
    let tools: Vec<_> = program.files[1]
        .positions()
        .map(|p| p.usage.tool.as_deref().map(str::to_owned))
        .collect();
    let tool = |n: u32| Some(format!("TOOL_DATA[{n}]"));
    assert_eq!(
        tools,
        [
            tool(1),
            tool(3),
            tool(3),
            tool(5),
            tool(5),
            tool(3),
            tool(3),
            tool(3),
            tool(3),
            None
        ]
    );
    // The motions whose base stays unknown are the ones warned about.
    let src_file = &program.files[0];
    let warned: Vec<_> = src_file
        .diagnostics
        .iter()
        .map(|d| (src_file.lines.line(d.span.start), d.message.as_str()))
        .collect();
    assert_eq!(
        warned,
        [
            (21, "the base of this motion is not resolved"),
            (45, "the base of this motion is not resolved"),
        ]
    );
}

/// The errors of `file`, each with its line and column.
fn located_errors(file: &ParsedFile) -> Vec<(usize, usize, String)> {
    file.diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .map(|d| {
            let (l, c) = file.lines.line_col(d.span.start);
            (l, c, d.message.clone())
        })
        .collect()
}

/// An aggregate written in a `.src`, assigned or inline in a motion, is held to the fields of its
/// type as a declaration is: a field given twice, or one its type lacks, is an error at the
/// field. The type of an assignment is the declared type of the name (in the pair's `.dat` as in
/// the `.src`); a motion's inline target is a position; where the type is not known only a field
/// given twice is. A partial aggregate is fine.
#[test]
fn krl_aggregates_in_a_src_are_held_to_their_fields() {
    let src = "DEF m( )\n  DECL POS PL\n  XP1 = {X 1, X 2, Y 0}\n  LIN {X 10, X 20, Y 0}\n  PTP {A1 0, A2 5, a1 3}\n  LIN {POS: X 1, E1 2}\n  PL = {X 1, Y 2, E1 3}\n  XQ = {X 1, Q 2}\n  XU = {X 1, Q 2}\n  XV = {Y 1, y 2}\n  XP2 = {X 10}\n  LIN {X 10}\n  XJ = {A1 1, X 2}\n  P[2] = {Z 1, Z 2}\nEND\n";
    let dat = "DEFDAT m\nDECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\nDECL E6POS XP2={X 1,Y 2,Z 3,A 0,B 0,C 0}\nDECL E6POS XQ\nDECL E6AXIS XJ\nDECL E6POS P[3]\nENDDAT\n";
    let program = krl::load_program_from_sources(
        vec![
            (PathBuf::from("m.src"), src.as_bytes().to_vec()),
            (PathBuf::from("m.dat"), dat.as_bytes().to_vec()),
        ],
        &LoadOptions::default(),
    )
    .unwrap();
    let e = |l: usize, c: usize, m: &str| (l, c, m.to_owned());
    assert_eq!(
        located_errors(&program.files[0]),
        [
            e(3, 15, "E6POS `XP1` gives field `X` twice"),
            e(4, 14, "inline E6POS gives field `X` twice"),
            e(5, 20, "inline E6AXIS gives field `a1` twice"),
            e(6, 18, "inline POS has no field `E1`"),
            e(7, 19, "POS `PL` has no field `E1`"),
            e(8, 14, "E6POS `XQ` has no field `Q`"),
            e(10, 14, "`XV` gives field `y` twice"),
            e(13, 15, "E6AXIS `XJ` has no field `X`"),
            e(14, 16, "E6POS `P[2]` gives field `Z` twice"),
        ]
    );
    assert!(located_errors(&program.files[1]).is_empty());
    // Every one is an error the transforms refuse the file for, with the hint check shows.
    let file = &program.files[0];
    let refused = trackfix::report::errors(file);
    assert_eq!(refused.len(), 9);
    assert!(
        refused.iter().all(|d| d
            .hint
            .as_deref()
            .is_some_and(|h| h.starts_with("the controller does not load the file"))),
        "{refused:?}"
    );
    // The `.src` alone: the names the `.dat` declares are of no known type, so only a field
    // given twice is an error there.
    let alone = krl::parse_file(Path::new("m.src"), src.as_bytes().to_vec());
    assert_eq!(
        located_errors(&alone),
        [
            e(3, 15, "`XP1` gives field `X` twice"),
            e(4, 14, "inline E6POS gives field `X` twice"),
            e(5, 20, "inline E6AXIS gives field `a1` twice"),
            e(6, 18, "inline POS has no field `E1`"),
            e(7, 19, "POS `PL` has no field `E1`"),
            e(10, 14, "`XV` gives field `y` twice"),
            e(14, 16, "`P[2]` gives field `Z` twice"),
        ]
    );
}

/// A point no motion uses is taken in the base and tool of its inline form's FDAT (`FP9` for
/// `XP9`): `correct` writes it byte for byte as it writes the same point a motion moves to after
/// `FDAT_ACT=FP9`, and a note on the data list says so. A point without an FDAT stays refused:
/// its base is unknown.
#[test]
fn a_point_no_motion_uses_is_taken_in_its_fdats_frames() {
    use trackfix::transform::{Direction, RefusalKind, apply, track_correction};
    let dat = "DEFDAT cell\n\
        DECL E6POS XP9={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL FDAT FP9={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}\n\
        DECL E6POS XLOOSE={X 410.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL E6POS XP8={X 420.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL FDAT FP8={TOOL_NO 1,BASE_NO 3,IPO_FRAME #BASE}\n\
        ENDDAT\n";
    let options = with_sample_config();
    let load = |src: &str| {
        krl::load_program_from_sources(
            vec![
                (PathBuf::from("cell.src"), src.as_bytes().to_vec()),
                (PathBuf::from("cell.dat"), dat.as_bytes().to_vec()),
            ],
            &options,
        )
        .unwrap()
    };
    let moved = load("DEF cell( )\n  FDAT_ACT=FP9\n  BAS(#CP_PARAMS,2)\n  LIN XP9\nEND\n");
    let unused = load("DEF cell( )\nEND\n");
    let dat_of = |p: &Program| {
        p.files
            .iter()
            .position(|f| f.path.ends_with("cell.dat"))
            .unwrap()
    };
    let point = |p: &Program, name: &str| {
        p.files[dat_of(p)]
            .positions()
            .find(|t| t.name.as_deref() == Some(name))
            .unwrap()
    };
    let (a, b) = (point(&moved, "XP9"), point(&unused, "XP9"));
    assert_eq!(a.usage.wobj.as_deref(), Some("BASE_DATA[2]"));
    assert_eq!(b.usage.wobj.as_deref(), Some("BASE_DATA[2]"));
    assert_eq!(b.usage.tool.as_deref(), Some("TOOL_DATA[1]"));
    assert!(b.usage.lines.is_empty() && !a.usage.lines.is_empty());
    assert_eq!(point(&unused, "XLOOSE").usage.wobj, None);
    // A point passed to a subroutine, which trackfix does not follow, or only named in a
    // comment, is named by the program: not taken in its FDAT's frames.
    let passed = load(
        "DEF cell( )\n  MYMOVE(xp8)\nEND\nDEF MYMOVE(PT:IN)\n  DECL E6POS PT\n  LIN PT\nEND\n",
    );
    assert_eq!(point(&passed, "XP8").usage.wobj, None);
    // Passed to a routine whose motions are not followed, the point's base there is not
    // known, whether or not a motion of the caller moves to it as well (in a base it sets).
    let also_moved = load(
        "DEF cell( )\n  $BASE=BASE_DATA[2]\n  LIN XP8\n  MYMOVE(XP8)\nEND\n\
         DEF MYMOVE(PT:IN)\n  DECL E6POS PT\n  $BASE=BASE_DATA[3]\n  LIN PT\nEND\n",
    );
    for (p, line) in [(&passed, 2), (&also_moved, 4)] {
        assert_eq!(
            point(p, "XP8").usage.unresolved_frame(),
            Some(&trackfix::position::UnresolvedFrame {
                at: trackfix::position::UseLine {
                    line,
                    file: Some("cell.src".into()),
                },
                cause: trackfix::position::UnresolvedCause::PassedTo("MYMOVE".into()),
            })
        );
    }
    assert_eq!(point(&also_moved, "XP9").usage.unresolved_frame(), None);
    // Passed on to the routine that moves to it: the same; to one that does not move to it:
    // nothing to follow.
    let relayed = load(
        "DEF cell( )\n  RELAY(XP8)\n  LOOK(XP9)\nEND\n\
         DEF RELAY(Q:IN)\n  DECL E6POS Q\n  MYMOVE(Q)\nEND\n\
         DEF LOOK(Q:IN)\n  DECL E6POS Q\n  Q.X = 1\nEND\n\
         DEF MYMOVE(PT:IN)\n  DECL E6POS PT\n  LIN PT\nEND\n",
    );
    assert_eq!(
        point(&relayed, "XP8")
            .usage
            .unresolved_frame()
            .map(|u| &u.cause),
        Some(&trackfix::position::UnresolvedCause::PassedTo(
            "RELAY".into()
        ))
    );
    assert_eq!(point(&relayed, "XP9").usage.unresolved_frame(), None);
    // Moved to through a copy the routine makes, or in a composed target: the same; copied by
    // a routine that moves nothing: nothing to follow.
    let moved_otherwise = load(
        "DEF cell( )\n  MYCOPY(XP8)\n  MYCOMP(XP9)\n  KEEP(XLOOSE)\nEND\n\
         DEF MYCOPY(P:IN)\n  DECL E6POS P,Q\n  Q=P\n  LIN Q\nEND\n\
         DEF MYCOMP(P:IN)\n  DECL E6POS P\n  LIN P:{X 0,Y 0,Z 10,A 0,B 0,C 0}\nEND\n\
         DEF KEEP(P:IN)\n  DECL E6POS P,Q\n  Q=P\nEND\n",
    );
    let passed_to = |name: &str| {
        point(&moved_otherwise, name)
            .usage
            .unresolved_frame()
            .map(|u| u.cause.clone())
    };
    assert_eq!(
        passed_to("XP8"),
        Some(trackfix::position::UnresolvedCause::PassedTo(
            "MYCOPY".into()
        ))
    );
    assert_eq!(
        passed_to("XP9"),
        Some(trackfix::position::UnresolvedCause::PassedTo(
            "MYCOMP".into()
        ))
    );
    assert_eq!(passed_to("XLOOSE"), None);
    // A copy passed, or an array element holding one: what it may hold is passed.
    let copied = load(
        "DEF cell( )\n  XC=XP8\n  MOVEIT(XC)\n  XARR[1]=XP9\n  MOVEIT(XARR[1])\nEND\n\
         DEF MOVEIT(PT:IN)\n  DECL E6POS PT\n  LIN PT\nEND\n",
    );
    for name in ["XP8", "XP9"] {
        assert_eq!(
            point(&copied, name)
                .usage
                .unresolved_frame()
                .map(|u| u.cause.clone()),
            Some(trackfix::position::UnresolvedCause::PassedTo(
                "MOVEIT".into()
            )),
            "{name}"
        );
    }
    let commented = load("DEF cell( )\n  ; LIN XP9 was here\nEND\n");
    assert_eq!(point(&commented, "XP9").usage.wobj, None);
    assert_eq!(
        point(&commented, "XP8").usage.wobj.as_deref(),
        Some("BASE_DATA[3]")
    );
    let notes: Vec<_> = unused.files[dat_of(&unused)]
        .diagnostics
        .iter()
        .filter(|d| d.shapes_transforms)
        .collect();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert_eq!(notes[0].severity, Severity::Note);
    assert!(
        notes[0].message.contains("`XP9`") && notes[0].message.contains("`FP9`"),
        "{}",
        notes[0].message
    );
    crate::support::with_constant_deviation(
        trackfix::geometry::pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05),
        |setup| {
            let run =
                |p: &Program| apply(p, track_correction(p, setup, Direction::Correct)).unwrap();
            let line = |r: &trackfix::transform::ProgramResult, p: &Program| {
                let out = String::from_utf8(r.files[dat_of(p)].output.clone()).unwrap();
                out.lines().find(|l| l.contains("XP9=")).unwrap().to_owned()
            };
            let (ra, rb) = (run(&moved), run(&unused));
            assert_eq!(line(&rb, &unused), line(&ra, &moved));
            assert!(!dat.contains(&line(&rb, &unused)), "XP9 is corrected");
            let refused: Vec<_> = rb.refusals().map(|r| (r.target.clone(), r.kind)).collect();
            assert_eq!(
                refused,
                [("XLOOSE".to_owned(), RefusalKind::UnresolvedWorkObject)]
            );
        },
    );
}

/// A `BASE_DATA[n]` a routine gives the value the cell's `$config.dat` declares changes nothing,
/// as one the tree's own `$config.dat` declares does; another value makes its points given a
/// frame of two values.
#[test]
fn an_assignment_of_the_cells_config_value_changes_nothing() {
    let options = with_sample_config();
    let program = |value: &str| {
        let src = format!(
            "DEF a( )\n  $TOOL=TOOL_DATA[1]\n  BASE_DATA[3]={value}\n  $BASE=BASE_DATA[3]\n  LIN XP1\nEND\n"
        );
        let dat = "DEFDAT a\nDECL E6POS XP1={X 420.0,Y 10.0,Z 150.0,A 0.0,B 90.0,C 0.0,S 2,T 2,E1 1500.0}\nENDDAT\n";
        krl::load_program_from_sources(
            vec![
                (PathBuf::from("a.src"), src.into_bytes()),
                (PathBuf::from("a.dat"), dat.as_bytes().to_vec()),
            ],
            &options,
        )
        .unwrap()
    };
    let run_time = |p: &Program| xp1_of(p).usage.run_time().cloned();
    // samples/krl/$config.dat: BASE_DATA[3]={X 6200.5,Y 1350.25,Z 0.0,A -90.0,B 0.0,C 0.0}.
    let same = program("{X 6200.5,Y 1350.25,Z 0.0,A -90.0,B 0.0,C 0.0}");
    assert_eq!(run_time(&same), None);
    let other = program("{X 6300.5,Y 1350.25,Z 0.0,A -90.0,B 0.0,C 0.0}");
    assert!(
        matches!(
            run_time(&other),
            Some(trackfix::position::RunTimeValue::FrameAssigned { .. })
        ),
        "{:?}",
        run_time(&other)
    );
}

/// Point `XP1` of program `p`.
fn xp1_of(p: &Program) -> trackfix::position::Position {
    p.files
        .iter()
        .flat_map(|f| f.positions())
        .find(|t| t.name.as_deref() == Some("XP1"))
        .unwrap()
}

/// The usage of point `XP1` of `dat` in the program of `cell.src` (`src`) and `cell.dat`,
/// loaded with the sample config.
fn usage_of_xp1(src: &str, dat: &str) -> trackfix::position::Usage {
    let p = load_cell_pair(src, dat);
    xp1_of(&p).usage
}

/// A data list with the one point `XP1` in it.
const DAT_XP1: &str = "DEFDAT cell\n\
    DECL E6POS XP1={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
    ENDDAT\n";

/// An FDAT the program changes when it runs (`FDAT_ACT.BASE_NO=2`, `FP1.BASE_NO=2`, `FP1=FP2`,
/// `FDAT_ACT` given a computed value) no longer says which base the next `BAS(#CP_PARAMS,…)`
/// applies: the point moved to after it is refused as moved with a base that cannot be
/// resolved, where it was corrected in the declared FDAT's base. Unchanged, or changed in a
/// field that places nothing (`TQ_STATE`), it is taken.
#[test]
fn an_fdat_the_program_changes_leaves_the_base_it_applies_unknown() {
    let dat = "DEFDAT cell\n\
        DECL E6POS XP1={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL FDAT FP1={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}\n\
        DECL FDAT FP2={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}\n\
        ENDDAT\n";
    let base_of = |change: &str| {
        let src = format!(
            "DEF cell( )\n  {change}\n  BAS(#CP_PARAMS,2)\n  LIN XP1\nEND\nDEFFCT FDAT PICK( )\n  RETURN FP2\nENDFCT\n\
             DEF SETF(F:OUT)\n  DECL FDAT F\n  F.BASE_NO=2\nEND\n"
        );
        let usage = usage_of_xp1(&src, dat);
        (
            usage.wobj.as_deref().map(str::to_owned),
            usage.unresolved_frame().is_some(),
        )
    };
    // Unchanged, or changed in a field that places nothing.
    for change in [
        "FDAT_ACT=FP1",
        "FP1.TQ_STATE=TRUE\n  FDAT_ACT=FP1",
        "FDAT_ACT=FP1\n  FDAT_ACT.TQ_STATE=TRUE",
    ] {
        assert_eq!(
            base_of(change),
            (Some("BASE_DATA[1]".to_owned()), false),
            "{change}"
        );
    }
    for change in [
        "FDAT_ACT=FP1\n  FDAT_ACT.BASE_NO=2",
        "FP1.BASE_NO=2\n  FDAT_ACT=FP1",
        "FP1=FP2\n  FDAT_ACT=FP1",
        "FDAT_ACT=PICK()",
        "SETF(FP1)\n  FDAT_ACT=FP1",
        "FDAT_ACT=FP1\n  FDAT_ACT.IPO_FRAME=#TCP",
    ] {
        assert_eq!(base_of(change), (None, true), "{change}");
    }
}

/// A label a jump back reaches may be reached with whatever base the jump brings, so a point
/// moved to after it, before the base is set again, is refused as moved with a base that
/// cannot be resolved (a loop made of a label and a jump back); so is one after a label a jump
/// forward and the path falling through reach with two bases. A jump forward over
/// `$BASE=BASE_DATA[2]` alone brings its own base. Set again after the label, the base is
/// known; a label no `GOTO` of its routine names changes nothing.
#[test]
fn a_label_leaves_the_base_unknown_until_it_is_set_again() {
    let base_of = |body: &str| {
        let usage = usage_of_xp1(&format!("DEF cell( )\n{body}END\n"), DAT_XP1);
        (
            usage.wobj.as_deref().map(str::to_owned),
            usage.unresolved_frame().map(|u| u.at.line),
        )
    };
    let forward = "  $BASE=BASE_DATA[1]\n  GOTO SKIP\n  $BASE=BASE_DATA[2]\n  SKIP:\n  LIN XP1\n";
    assert_eq!(base_of(forward), (Some("BASE_DATA[1]".to_owned()), None));
    let either = "  $BASE=BASE_DATA[1]\n  IF $IN[1] THEN\n    GOTO SKIP\n  ENDIF\n  \
                  $BASE=BASE_DATA[2]\n  SKIP:\n  LIN XP1\n";
    assert_eq!(base_of(either), (None, Some(8)));
    let backward = "  $BASE=BASE_DATA[1]\n  TOP:\n  LIN XP1\n  $BASE=BASE_DATA[2]\n  IF $IN[1] THEN\n    GOTO TOP\n  ENDIF\n";
    assert_eq!(base_of(backward), (None, Some(4)));
    // A label no jump of its routine names changes nothing.
    let unused = "  $BASE=BASE_DATA[1]\n  SKIP:\n  LIN XP1\n";
    assert_eq!(base_of(unused), (Some("BASE_DATA[1]".to_owned()), None));
    let elsewhere = format!("{unused}END\nDEF other( )\n  GOTO SKIP\n  SKIP:\n");
    assert_eq!(base_of(&elsewhere), (Some("BASE_DATA[1]".to_owned()), None));
    let set_again = "  GOTO SKIP\n  SKIP:\n  $BASE=BASE_DATA[2]\n  LIN XP1\n";
    assert_eq!(base_of(set_again), (Some("BASE_DATA[2]".to_owned()), None));
    // A retry: jumping back over nothing that changes the base arrives with the label's own,
    // from inside blocks the jump's range opens (and a loop it closes), past a call of a
    // routine that sets no frame.
    let retry = "  $BASE=BASE_DATA[1]\n  TOP:\n  LIN XP1\n  FOR I=1 TO 2\n    WAIT SEC 1\n  ENDFOR\n  \
                 GRIP()\n  IF $IN[1] THEN\n    SWITCH N\n    CASE 1\n      GOTO TOP\n    ENDSWITCH\n  ENDIF\n\
                 END\nDEF GRIP( )\n  $OUT[1]=TRUE\n";
    assert_eq!(base_of(retry), (Some("BASE_DATA[1]".to_owned()), None));
    // Over a change of the base, a call of a routine that sets one, from a loop whose body goes
    // on past the jump, or out of a block opened before the label: the base is not known.
    for jump in [
        "  $BASE=BASE_DATA[1]\n  TOP:\n  LIN XP1\n  $BASE=BASE_DATA[1]\n  GOTO TOP\n",
        "  $BASE=BASE_DATA[1]\n  TOP:\n  LIN XP1\n  SETB()\n  GOTO TOP\nEND\nDEF SETB( )\n  BAS(#BASE,2)\n",
        "  $BASE=BASE_DATA[1]\n  TOP:\n  LOOP\n    LIN XP1\n    IF $IN[1] THEN\n      GOTO TOP\n    ENDIF\n    \
         $BASE=BASE_DATA[2]\n  ENDLOOP\n",
        "  $BASE=BASE_DATA[1]\n  IF $IN[2] THEN\n    $BASE=BASE_DATA[2]\n    TOP:\n    LIN XP1\n  ENDIF\n  \
         GOTO TOP\n",
    ] {
        assert!(base_of(jump).1.is_some(), "{jump}");
    }
    // An FDAT staged before a jump forward over another, which the path falling through
    // stages: the one a `BAS` applies after the label is not known. Jumped over, it is the
    // one staged before.
    let fdats = DAT_XP1.replace(
        "ENDDAT",
        "DECL FDAT FP1={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}\n\
         DECL FDAT FP2={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}\nENDDAT",
    );
    let staged = |body: &str| {
        let usage = usage_of_xp1(&format!("DEF cell( )\n{body}END\n"), &fdats);
        (
            usage.wobj.as_deref().map(str::to_owned),
            usage.unresolved_frame().is_some(),
        )
    };
    let skipped = "  FDAT_ACT=FP1\n  IF $IN[1] THEN\n    GOTO SKIP\n  ENDIF\n  FDAT_ACT=FP2\n  SKIP:\n  \
                   BAS(#CP_PARAMS,2)\n  LIN XP1\n";
    assert_eq!(staged(skipped), (None, true));
    assert_eq!(
        staged(&skipped.replace("GOTO SKIP", "; no jump")),
        (Some("BASE_DATA[2]".to_owned()), false)
    );
    let over =
        "  FDAT_ACT=FP1\n  GOTO SKIP\n  FDAT_ACT=FP2\n  SKIP:\n  BAS(#CP_PARAMS,2)\n  LIN XP1\n";
    assert_eq!(staged(over), (Some("BASE_DATA[1]".to_owned()), false));
}

/// A copy (`XC=XP1`) moves to what it copies until the program gives it another whole value
/// (`XC=$POS_ACT`): from then on a motion to it is not a motion to `XP1`, which is no longer
/// taken as used there, in whatever base that motion moves (it was corrected in it). A
/// component changed (`XC.X=XC.X+10`, an approach point) keeps the copy: the motion still
/// tells the base `XP1` is taught in.
#[test]
fn a_copy_given_another_value_no_longer_reaches_its_source() {
    let lines_of_xp1 = |body: &str| {
        let src = format!("DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[1]\n{body}END\n");
        usage_of_xp1(&src, DAT_XP1).lines.to_vec()
    };
    assert_eq!(lines_of_xp1("  XC=XP1\n  LIN XC\n"), [5]);
    assert_eq!(lines_of_xp1("  XC=XP1\n  XC.X=XC.X+10\n  LIN XC\n"), [6]);
    assert_eq!(
        lines_of_xp1("  XC=XP1\n  XC=$POS_ACT\n  LIN XC\n"),
        Vec::<u32>::new()
    );
    // Copied again: reached again.
    assert_eq!(
        lines_of_xp1("  XC=XP1\n  XC=$POS_ACT\n  XC=XP1\n  LIN XC\n"),
        [7]
    );
}

/// A function's value moves where its arguments' targets are (`XC=GETPT(XP1)`, `XC=MID(XP2,
/// XP1)`): a motion to it is a motion to each, in that motion's base, as a copy is; before, the
/// point was corrected in the base of its own motion while the robot moved to it in another.
/// A value a routine hands back — written into a parameter not `:IN` (`P=XP1` in
/// `DEF SETC(P:OUT)`) or returned by a function (`RETURN XP1`) — reaches motions trackfix does
/// not tie to the point: it is refused, naming the routine. A function that moves to its
/// parameter is followed as a routine is.
#[test]
fn a_value_a_function_or_parameter_hands_back_reaches_its_motions() {
    use trackfix::position::UnresolvedCause;
    let usage = |body: &str, routines: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[1]\n  LIN XP1\n{body}END\n{routines}"
        );
        usage_of_xp1(&src, DAT_XP1)
    };
    let getpt = "DEFFCT E6POS GETPT(P:IN)\n  DECL E6POS P\n  P.Z=P.Z+100\n  RETURN P\nENDFCT\n";
    // Moved in the same base through the function's value: used on both lines.
    let same = usage("  XC=GETPT(XP1)\n  LIN XC\n", getpt);
    assert_eq!(same.lines, [4, 6]);
    assert_eq!(same.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(same.unresolved_frame(), None);
    // In another base: two bases, no longer one.
    let other = usage("  XC=GETPT(XP1)\n  $BASE=BASE_DATA[2]\n  LIN XC\n", getpt);
    assert_eq!(other.lines, [4, 7]);
    assert_eq!(other.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(other.other_wobjs(), ["BASE_DATA[2]"]);
    // A later argument of the function, and one inside a call given as an argument.
    let mid = "DEFFCT E6POS MID(A:IN,B:IN)\n  DECL E6POS A,B\n  RETURN A\nENDFCT\n";
    let later = usage(
        "  XC=MID(XC,(MID(XAUX,XP1)))\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
        mid,
    );
    assert_eq!(later.lines, [4, 7]);
    // A function of the name's own value keeps what it held.
    let shifted = usage(
        "  XC=XP1\n  XC=GETPT(XC)\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
        getpt,
    );
    assert_eq!(shifted.lines, [4, 8]);
    // Another whole value given after it ends it, as for a copy.
    let ended = usage(
        "  XC=GETPT(XP1)\n  XC=$POS_ACT\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
        getpt,
    );
    assert_eq!(ended.lines, [4]);
    let cause =
        |u: &trackfix::position::Usage| u.unresolved_frame().map(|u| (u.at.line, u.cause.clone()));
    // Written into an `:OUT` parameter (directly or as a function's argument), or returned.
    let out = usage(
        "  SETC(XC)\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
        "DEF SETC(P:OUT)\n  DECL E6POS P\n  P=GETPT(XP1)\nEND\n",
    );
    assert_eq!(
        cause(&out),
        Some((
            11,
            UnresolvedCause::HandedBack("written into `P`, a parameter of `SETC`".into())
        ))
    );
    let returned = usage(
        "  XC=GETA()\n  LIN XC\n",
        "DEFFCT E6POS GETA( )\n  RETURN ( xp1 ) ; the taught one\nENDFCT\n",
    );
    assert_eq!(
        cause(&returned),
        Some((9, UnresolvedCause::HandedBack("returned by `GETA`".into())))
    );
    // Into an `:IN` parameter, or a parameter's own value handed on: nothing leaves.
    let kept = usage(
        "  SETC(XC)\n  LIN XC\n",
        "DEF SETC(P:IN, Q:OUT)\n  DECL E6POS P,Q\n  P=XP1\n  Q=P\nEND\n",
    );
    assert_eq!(cause(&kept), None);
    assert_eq!(kept.lines, [4]);
    // A function that moves to its parameter.
    let moves = usage(
        "  XC=GOTHERE(XP1)\n",
        "DEFFCT E6POS GOTHERE(P:IN)\n  DECL E6POS P\n  LIN P\n  RETURN P\nENDFCT\n",
    );
    assert_eq!(
        cause(&moves),
        Some((5, UnresolvedCause::PassedTo("GOTHERE".into())))
    );
}

/// A routine the program runs where trackfix does not follow it — a function (`DEFFCT`, called
/// inside an expression such as `IF PREP() THEN`), or the routine of an interrupt or trigger
/// (`… DO SETB()`) — that changes the base leaves every motion's base unknown: its points are
/// refused naming the routine, where they were corrected in the base set before. One that
/// changes no frame, or a function nothing calls, changes nothing.
#[test]
fn a_function_or_interrupt_that_changes_the_base_leaves_it_unknown() {
    let cause_of = |src: &str| {
        usage_of_xp1(src, DAT_XP1)
            .unresolved_frame()
            .map(|u| u.cause.clone())
    };
    let changed = |name: &str| {
        Some(trackfix::position::UnresolvedCause::ChangedBy(
            name.to_owned(),
        ))
    };
    let function = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  IF PREP() THEN\n  ENDIF\n  LIN XP1\nEND\n\
                    DEFFCT BOOL PREP( )\n  $BASE=BASE_DATA[2]\n  RETURN TRUE\nENDFCT\n";
    assert_eq!(cause_of(function), changed("PREP"));
    let interrupt = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  INTERRUPT DECL 3 WHEN $IN[7] DO SETB()\n  \
                     INTERRUPT ON 3\n  LIN XP1\nEND\nDEF SETB( )\n  BAS(#BASE,2)\nEND\n";
    assert_eq!(cause_of(interrupt), changed("SETB"));
    let trigger = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  TRIGGER WHEN DISTANCE=1 DELAY=0 DO setb() PRIO=-1\n  \
                   LIN XP1\nEND\nDEF SETB( )\n  $BASE=BASE_DATA[2]\nEND\n";
    assert_eq!(cause_of(trigger), changed("SETB"));
    let harmless = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  INTERRUPT DECL 3 WHEN $IN[7] DO STOPIT()\n  \
                    IF OK() THEN\n  ENDIF\n  LIN XP1\nEND\nDEF STOPIT( )\n  BRAKE\nEND\n\
                    DEFFCT BOOL OK( )\n  RETURN TRUE\nENDFCT\n";
    assert_eq!(cause_of(harmless), None);
    // A function nothing calls never runs.
    let uncalled = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  LIN XP1\nEND\n\
                    DEFFCT BOOL PREP( )\n  $BASE=BASE_DATA[2]\n  RETURN TRUE\nENDFCT\n";
    assert_eq!(cause_of(uncalled), None);
    // Nor does the routine of an interrupt the program declares but never switches on (before,
    // its point was refused); switched on by its number, or all at once, it runs.
    let off = interrupt.replace("  INTERRUPT ON 3\n", "  INTERRUPT OFF 3\n");
    assert_eq!(cause_of(&off), None);
    assert_eq!(
        cause_of(&interrupt.replace("INTERRUPT ON 3", "INTERRUPT ON 4")),
        None
    );
    for on in ["INTERRUPT ON", "INTERRUPT ON N"] {
        let src = interrupt.replace("INTERRUPT ON 3", on);
        assert_eq!(cause_of(&src), changed("SETB"), "{on}");
    }
    // A function that sets the interpolation mode only: its refusal says so, where it said the
    // function changes the base.
    let mode = function.replace("$BASE=BASE_DATA[2]\n  RETURN", "$IPO_MODE=#TCP\n  RETURN");
    assert_eq!(cause_of(&mode), changed("PREP"));
    let p = load_cell_pair(&mode, DAT_XP1);
    crate::support::with_constant_deviation(
        trackfix::geometry::pose_xyz_deg(0.3, -0.2, 0.5, 0.02, -0.03, 0.05),
        |setup| {
            use trackfix::transform::{Direction, apply, track_correction};
            let r = apply(&p, track_correction(&p, setup, Direction::Correct)).unwrap();
            let why: Vec<String> = r.refusals().map(|r| r.message.clone()).collect();
            assert_eq!(why.len(), 1, "{why:?}");
            assert!(
                why[0].contains("`PREP` changes the base, the tool or the interpolation mode"),
                "{}",
                why[0]
            );
        },
    );
}

/// A data list with `XP1` and a copy `XC` of it, whole or an array.
fn dat_xp1_and(decl: &str) -> String {
    DAT_XP1.replace("ENDDAT", &format!("{decl}\nENDDAT"))
}

/// The bases `XP1` is used with: (the first, the others).
fn bases_of_xp1(src: &str, dat: &str) -> (Option<String>, Vec<String>) {
    let u = usage_of_xp1(src, dat);
    (
        u.wobj.as_deref().map(str::to_owned),
        u.other_wobjs().iter().map(|w| w.to_string()).collect(),
    )
}

/// After an `IF`, a `SWITCH` or a loop (no pass of a `WHILE`, an `EXIT`), a copy may hold what
/// any path put there: `XP1` copied on one path only, or on a path a later one does not take,
/// is used in the base of the motion to the copy after the join. Before, the last branch's
/// copy won, and `XP1` was corrected in its own motion's base while the robot moved to it in
/// another.
#[test]
fn a_copy_made_on_one_path_reaches_its_source_after_the_join() {
    let bases = |body: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  DECL INT K\n  $BASE=BASE_DATA[1]\n  LIN XP1\n{body}  \
             $BASE=BASE_DATA[2]\n  LIN XC\nEND\n"
        );
        bases_of_xp1(&src, DAT_XP1)
    };
    let two = (
        Some("BASE_DATA[1]".to_owned()),
        vec!["BASE_DATA[2]".to_owned()],
    );
    for body in [
        "  XC=XP2\n  IF $IN[1] THEN\n    XC=XP1\n  ENDIF\n",
        "  IF $IN[1] THEN\n    XC=XP1\n  ELSE\n    XC=XP2\n  ENDIF\n",
        "  SWITCH K\n  CASE 1\n    XC=XP1\n  DEFAULT\n    XC=XP2\n  ENDSWITCH\n",
        "  XC=XP2\n  LOOP\n    IF $IN[1] THEN\n      XC=XP1\n      EXIT\n    ENDIF\n    XC=XP2\n  ENDLOOP\n",
        "  XC=XP1\n  WHILE $IN[1]\n    XC=XP2\n  ENDWHILE\n",
        "  XC=XP1\n  FOR K=1 TO 3\n    XC=XP2\n  ENDFOR\n",
    ] {
        assert_eq!(bases(body), two, "{body}");
    }
    // Given another value on every path, or after the join: no longer `XP1`.
    let one = (Some("BASE_DATA[1]".to_owned()), Vec::new());
    for body in [
        "  IF $IN[1] THEN\n    XC=XP1\n  ENDIF\n  XC=XP2\n",
        "  IF $IN[1] THEN\n    XC=XP1\n  ELSE\n    XC=$POS_ACT\n  ENDIF\n  XC=XP2\n",
        "  XC=XP1\n  REPEAT\n    XC=XP2\n  UNTIL $IN[1]\n",
    ] {
        assert_eq!(bases(body), one, "{body}");
    }
}

/// A copy into a name other routines see (the data list's `XC`) made in one routine reaches
/// the motions to it in another (called after it, calling it, or running at any time: an
/// interrupt's routine, a function, a trigger's `DO XC=XP1`), and those of the next run of its
/// own; one into a name another module may see (`GLOBAL`) is refused, naming the name. Before,
/// each motion to `XC` outside the copying routine reached only `XC`, and `XP1` was corrected
/// in its own motion's base.
#[test]
fn a_copy_into_a_name_other_routines_see_reaches_their_motions() {
    use trackfix::position::UnresolvedCause;
    let dat = dat_xp1_and("DECL E6POS XC");
    let two = (
        Some("BASE_DATA[1]".to_owned()),
        vec!["BASE_DATA[2]".to_owned()],
    );
    let bases = |main: &str, rest: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS D\n  $BASE=BASE_DATA[1]\n  LIN XP1\n{main}END\n{rest}"
        );
        bases_of_xp1(&src, &dat)
    };
    for (main, rest) in [
        (
            "  SETC()\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
            "DEF SETC( )\n  XC=XP1\nEND\n",
        ),
        (
            "  XC=XP1\n  GO()\n",
            "DEF GO( )\n  $BASE=BASE_DATA[2]\n  LIN XC\nEND\n",
        ),
        (
            "  A()\n",
            "DEF A( )\n  XC=XP1\n  B()\nEND\nDEF B( )\n  $BASE=BASE_DATA[2]\n  LIN XC\nEND\n",
        ),
        (
            "  INTERRUPT DECL 5 WHEN $IN[1] DO GRAB()\n  INTERRUPT ON 5\n  XC=XP2\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
            "DEF GRAB( )\n  XC=XP1\nEND\n",
        ),
        (
            "  $BASE=BASE_DATA[2]\n  D=SETIT()\n  LIN XC\n",
            "DEFFCT E6POS SETIT( )\n  XC=XP1\n  RETURN XP2\nENDFCT\n",
        ),
        (
            "  TRIGGER WHEN DISTANCE=1 DELAY=0 DO XC=XP1\n  LIN XP2\n  XC=XP2\n  $BASE=BASE_DATA[2]\n  LIN XC\n",
            "",
        ),
        // The next run of the routine: the copy after the motion.
        ("  $BASE=BASE_DATA[2]\n  LIN XC\n  XC=XP1\n", ""),
    ] {
        assert_eq!(bases(main, rest), two, "{main}{rest}");
    }
    // Given another value in the routine before its motion, with no call between: not `XP1`.
    assert_eq!(
        bases("  XC=XP1\n  XC=XP2\n  $BASE=BASE_DATA[2]\n  LIN XC\n", ""),
        (Some("BASE_DATA[1]".to_owned()), Vec::new())
    );
    // A name other modules see.
    let global = DAT_XP1.replace("ENDDAT", "DECL GLOBAL E6POS XC\nENDDAT");
    let src = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  LIN XP1\n  XC=XP1\nEND\n";
    assert_eq!(
        usage_of_xp1(src, &global)
            .unresolved_frame()
            .map(|u| (u.at.line, u.cause.clone())),
        Some((
            4,
            UnresolvedCause::HandedBack(
                "copied into `XC`, a name other routines or modules may move to".into()
            )
        ))
    );
}

/// An element written or read through an index computed when the program runs may be any
/// element: `XC[I]=XP1` reaches a motion to `XC[1]`, `XC[1]=XP1` one to `XC[I]`, a copy in a
/// `FOR` loop the motions after it. Before, the element's name as written had to match, and
/// `XP1` was corrected in its own motion's base. Another literal element is not reached.
#[test]
fn an_element_copied_or_moved_to_through_a_computed_index_may_be_any() {
    let dat = dat_xp1_and("DECL E6POS XC[2]");
    let bases = |body: &str| {
        let src = format!(
            "DEF cell( )\n  DECL INT I\n  I=1\n  $BASE=BASE_DATA[1]\n  LIN XP1\n{body}END\n"
        );
        bases_of_xp1(&src, &dat)
    };
    let two = (
        Some("BASE_DATA[1]".to_owned()),
        vec!["BASE_DATA[2]".to_owned()],
    );
    for body in [
        "  XC[I]=XP1\n  $BASE=BASE_DATA[2]\n  LIN XC[1]\n",
        "  XC[1]=XP1\n  $BASE=BASE_DATA[2]\n  LIN XC[I]\n",
        "  FOR I=1 TO 2\n    XC[I]=XP1\n  ENDFOR\n  $BASE=BASE_DATA[2]\n  LIN XC[1]\n",
    ] {
        assert_eq!(bases(body), two, "{body}");
    }
    assert_eq!(
        bases("  XC[1]=XP1\n  $BASE=BASE_DATA[2]\n  LIN XC[2]\n"),
        (Some("BASE_DATA[1]".to_owned()), Vec::new())
    );
}

/// A component copied from a point (`XC.X=XP1.X`, `XC.X=XP1.X+10`, `S1.P=XP1` into a
/// structure's member, `P.X=XP1.X` into an `:OUT` parameter) puts (part of) that point into
/// the name, which keeps what it held besides: a motion to it is one to each. A copy of a name
/// into itself (`XC=XC`) leaves what it holds. Before, each of these lost the copy and `XP1`
/// was corrected in its own motion's base.
#[test]
fn a_component_copied_or_a_copy_of_itself_keeps_the_source() {
    use trackfix::position::UnresolvedCause;
    let two = (
        Some("BASE_DATA[1]".to_owned()),
        vec!["BASE_DATA[2]".to_owned()],
    );
    let bases = |body: &str, rest: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[1]\n  LIN XP1\n{body}  $BASE=BASE_DATA[2]\n  LIN XC\nEND\n{rest}"
        );
        bases_of_xp1(&src, DAT_XP1)
    };
    for body in [
        "  XC.X=XP1.X\n  XC.Y=XP1.Y\n",
        "  XC=XP2\n  XC.X=XP1.X+10\n",
        "  XC=XP1\n  XC=XC\n",
    ] {
        assert_eq!(bases(body, ""), two, "{body}");
    }
    let out = usage_of_xp1(
        "DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[2]\n  SETC(XC)\n  LIN XC\nEND\n\
         DEF SETC(P:OUT)\n  DECL E6POS P\n  P.X=XP1.X\nEND\n",
        DAT_XP1,
    );
    assert_eq!(
        out.unresolved_frame().map(|u| u.cause.clone()),
        Some(UnresolvedCause::HandedBack(
            "written into `P`, a parameter of `SETC`".into()
        ))
    );
    // A structure's member: refused (the structure is no point of the module's).
    let dat = DAT_XP1.replace("ENDDAT", "STRUC SPT E6POS P, INT K\nDECL SPT S1\nENDDAT");
    let src = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  LIN XP1\n  S1.P=XP1\n  $BASE=BASE_DATA[2]\n  LIN S1.P\nEND\n";
    let u = usage_of_xp1(src, &dat);
    assert!(
        u.unresolved_frame().is_some() || !u.other_wobjs().is_empty(),
        "{u:?}"
    );
}

/// A copy read out of a structure's member (`XC=S1.P`, `XC=SA[I].P`), or written into a member
/// of an element of an array of structures (`SA[1].P=XP1`), carries what the member holds: the
/// point copied there is used in the base of the motion to the copy or to the member. Before,
/// `XC=S1.P` gave `XC` a value of its own and `SA[1].P=XP1` was no copy, and `XP1` was
/// corrected in its own motion's base while the robot moved to it in another.
#[test]
fn a_copy_through_a_structures_member_reaches_its_source() {
    let bases = |body: &str, to: &str| {
        let src = format!(
            "DEF cell( )\n  DECL SPT S1,S2,SA[2]\n  DECL E6POS XC\n  DECL INT I\n  \
             $BASE=BASE_DATA[1]\n  LIN XP1\n{body}  $BASE=BASE_DATA[2]\n  LIN {to}\nEND\n"
        );
        bases_of_xp1(&src, DAT_XP1)
    };
    let two = (
        Some("BASE_DATA[1]".to_owned()),
        vec!["BASE_DATA[2]".to_owned()],
    );
    for (body, to) in [
        ("  S1.P=XP1\n  XC=S1.P\n", "XC"),
        ("  S1.P=XP1\n  S2=S1\n  XC=S2.P\n", "XC"),
        ("  SA[1].P=XP1\n", "SA[I].P"),
        ("  SA[1].P=XP1\n  XC=SA[I].P\n", "XC"),
        ("  SA[I].P=XP1\n  XC=SA[2].P\n", "XC"),
    ] {
        assert_eq!(bases(body, to), two, "{body}LIN {to}");
    }
    // Another element, or the member given another value after the read: not `XP1`.
    let one = (Some("BASE_DATA[1]".to_owned()), Vec::new());
    assert_eq!(bases("  SA[1].P=XP1\n", "SA[2].P"), one);
    assert_eq!(bases("  S1.P=XP1\n  XC=S1.P\n  XC=$POS_ACT\n", "XC"), one);
}

/// A point written in a structure's literal (`DECL SPT S1={P {X …, E1 1500.0}, K 1}`, an element
/// of an array of structures, a member given a literal `S2.P={…}`, a structure's in a structure)
/// is refused by every transform as `structure-member`, by name at its literal, whether the
/// program moves to the member or to a copy of it: a structure carries its members where
/// trackfix does not follow them (a copy of the whole structure, an array of structures chosen
/// at run time, a parameter, another module). Before, such a point was no target at all: `correct` exited 0 with the files
/// unchanged and at most a warning that spoke of a composed frame. A member that is a frame
/// (`CM` of a load) or per-axis values (`AX` of jerk limits) is no point and stays out.
#[test]
fn a_point_held_in_a_structures_member_is_refused_by_name() {
    let point = |fields: &str| {
        format!("{{X 410.0,Y -95.0,Z 230.0,A 180.0,B 0.0,C 180.0,{fields}E1 1500.0}}")
    };
    let dat = format!(
        "DEFDAT cell\n\
         STRUC SPT E6POS P, INT K\n\
         DECL SPT S1={{P {},K 1}}\n\
         DECL SPT SA[2]\n\
         SA[2]={{P {},K 2}}\n\
         DECL SPT S2\n\
         S2.P={}\n\
         DECL LOAD L1={{M 5.0,CM {{X 1.0,Y 2.0,Z 3.0,A 0.0,B 0.0,C 0.0}}}}\n\
         DECL JERK_STRUC J1={{CP 500.0,AX {{A1 1000.0,A2 1000.0,E1 1000.0}}}}\n\
         DECL OUTER O1={{N 2,A {{P {},K 1}}}}\n\
         DECL E6POS XC\n\
         DECL E6POS XP8={}\n\
         ENDDAT\n",
        point("S 6,T 27,"),
        point("S 6,T 27,"),
        point("S 6,T 27,"),
        point(""),
        point("S 6,T 27,"),
    );
    let src = "DEF cell( )\n  DECL INT I\n  BAS(#INITMOV,0)\n  BAS(#BASE,1)\n  BAS(#TOOL,1)\n  \
               XC=S1.P\n  LIN XC\n  I=2\n  LIN SA[I].P\n  LIN S2.P\n  LIN XP8\nEND\n";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cell.dat"), &dat).unwrap();
    std::fs::write(dir.path().join("cell.src"), src).unwrap();
    let src = dir.path().join("cell.src");
    let program = krl::load_program(&src, &LoadOptions::default()).unwrap();
    let names: Vec<String> = program
        .files
        .iter()
        .flat_map(|f| f.positions())
        .filter_map(|p| p.name.map(|n| n.to_string()))
        .collect();
    assert_eq!(names, ["S1.P", "SA[2].P", "S2.P", "O1.A.P", "XP8"]);

    let src = src.to_str().unwrap();
    let args = [
        "correct",
        src,
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "-v",
    ];
    let (code, _, err) = crate::support::trackfix(&args);
    assert_eq!(code, 3, "{err}");
    for (at, name, whole) in [
        ("3:16", "S1.P", "S1"),
        ("5:10", "SA[2].P", "SA[2]"),
        ("7:6", "S2.P", "S2"),
        ("10:25", "O1.A.P", "O1"),
    ] {
        assert!(
            err.contains(&format!(
                "cell.dat:{at}: error: E6POS `{name}` is held in a member of the structure `{whole}`"
            )),
            "{name}: {err}"
        );
    }
    assert_eq!(err.matches("[structure-member]").count(), 4, "{err}");
    assert!(!err.contains("composed frame"), "{err}");

    let out = dir.path().join("out");
    let mut kept = args.to_vec();
    kept.extend([
        "--keep",
        "structure-member",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    let (code, _, err) = crate::support::trackfix(&kept);
    assert_eq!(code, 4, "{err}");
    let written = std::fs::read_to_string(out.join("cell.dat")).unwrap();
    let kept_lines: Vec<&str> = dat.lines().filter(|l| !l.contains("XP8")).collect();
    for line in kept_lines {
        assert!(written.contains(line), "{line}: {written}");
    }
    assert!(
        !written.contains(&format!("XP8={}", point("S 6,T 27,"))),
        "{written}"
    );
}

/// A call of a routine none of the files given defines (`setb()`, whose module was not named
/// with the program) is taken as leaving $BASE, $TOOL, $IPO_MODE and FDAT_ACT as they were: that is said
/// once per routine, at its first call, with how many calls there are, and `correct` shows it.
/// Before, nothing was said and `XP1` was corrected in base 1 whatever `setb` sets. KSS's own
/// routines (`MsgNotify`, `PULSE`), routines the program defines, and a call in a routine that
/// neither moves nor is called (whose exit nothing applies) are not warned about.
#[test]
fn a_call_of_a_routine_no_file_defines_is_warned_about_once() {
    let src = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  setb()\n  LIN XP1\n  \
               SETB()\n  MsgNotify(\"done\")\n  PULSE($OUT[1],TRUE,0.5)\n  GRIP()\n  PREP()\nEND\n\
               DEF GRIP( )\n  $OUT[2]=TRUE\nEND\n\
               DEF PREP( )\n  settool()\nEND\n\
               DEF IDLE( )\n  H50()\nEND\n";
    let program = load_cell_pair(src, DAT_XP1);
    let f = &program.files[0];
    let warned: Vec<(usize, usize, &str)> = f
        .diagnostics
        .iter()
        .map(|d| {
            let (line, col) = f.lines.line_col(d.span.start);
            (line, col, d.message.as_str())
        })
        .collect();
    let said = "but none of the files given defines it: trackfix takes it as leaving $BASE, $TOOL, $IPO_MODE and FDAT_ACT as they were for the motions after it";
    assert_eq!(
        warned,
        [
            (
                4,
                3,
                format!("`setb` is called here (the first of 2 calls), {said}").as_str()
            ),
            (16, 3, format!("`settool` is called here, {said}").as_str()),
        ]
    );
    assert!(f.diagnostics.iter().all(|d| d.shapes_transforms));
    assert_eq!(xp1_of(&program).usage.wobj.as_deref(), Some("BASE_DATA[1]"));

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cell.src"), src).unwrap();
    // A point in the sample robot's reach.
    std::fs::write(
        dir.path().join("cell.dat"),
        "DEFDAT cell\nDECL E6POS XP1={X 410.0,Y -95.0,Z 230.0,A 180.0,B 0.0,C 180.0,S 6,T 27,E1 1500.0}\nENDDAT\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let (code, _, err) = crate::support::trackfix(&[
        "correct",
        dir.path().join("cell.src").to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains(&format!(
            "cell.src:4:3: warning: `setb` is called here (the first of 2 calls), {said}"
        )),
        "{err}"
    );
    assert!(
        err.contains("help: give the module or folder that defines `setb` with the program"),
        "{err}"
    );
}

/// A value handed back through the routine's own copy (`R=XP1` then `RETURN R`, or `P=R` into
/// an `:OUT` parameter) is refused as handing back `XP1` is; before, `R` named no point and
/// `XP1` was corrected in its own motion's base.
#[test]
fn a_value_handed_back_through_a_local_copy_is_refused() {
    use trackfix::position::UnresolvedCause;
    let cause = |main: &str, rest: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[1]\n  LIN XP1\n  $BASE=BASE_DATA[2]\n{main}END\n{rest}"
        );
        usage_of_xp1(&src, DAT_XP1)
            .unresolved_frame()
            .map(|u| u.cause.clone())
    };
    assert_eq!(
        cause(
            "  XC=GETP()\n  LIN XC\n",
            "DEFFCT E6POS GETP( )\n  DECL E6POS R\n  R=XP1\n  RETURN R\nENDFCT\n"
        ),
        Some(UnresolvedCause::HandedBack("returned by `GETP`".into()))
    );
    assert_eq!(
        cause(
            "  SETC(XC)\n  LIN XC\n",
            "DEF SETC(P:OUT)\n  DECL E6POS P,R\n  R=XP1\n  P=R\nEND\n"
        ),
        Some(UnresolvedCause::HandedBack(
            "written into `P`, a parameter of `SETC`".into()
        ))
    );
}

/// A `GOTO` leaves its path: at `ENDIF` the join takes only the paths that reach it (a branch
/// that sets another base and jumps away no longer makes the base after the block unknown, and
/// refuses nothing), and an `EXIT` leaves the rest of the loop's body. A label a jump reaches
/// gets what any copy of its routine may have put into a name: a retry jumping back over a
/// copy (`TOP: LIN XC … XC=XP1 … GOTO TOP`) moves to `XP1` in the base at the label; before,
/// the motion to `XC` reached only what program order brought, and `XP1` was corrected in its
/// own motion's base.
#[test]
fn a_goto_ends_its_path_and_a_jumped_label_gets_the_routines_copies() {
    let bases = |body: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  DECL INT N\n  $BASE=BASE_DATA[1]\n{body}END\n"
        );
        bases_of_xp1(&src, DAT_XP1)
    };
    let one = (Some("BASE_DATA[1]".to_owned()), Vec::new());
    assert_eq!(
        bases(
            "  IF $IN[1] THEN\n    $BASE=BASE_DATA[2]\n    GOTO SKIP\n  ENDIF\n  LIN XP1\n  SKIP:\n"
        ),
        one
    );
    assert_eq!(
        bases(
            "  LOOP\n    IF $IN[1] THEN\n      $BASE=BASE_DATA[2]\n      EXIT\n    ENDIF\n    LIN XP1\n  ENDLOOP\n"
        ),
        one
    );
    assert_eq!(
        bases(
            "  XC=XP2\n  LIN XP1\n  $BASE=BASE_DATA[2]\n  TOP:\n  LIN XC\n  XC=XP1\n  IF $IN[1] THEN\n    GOTO TOP\n  ENDIF\n"
        ),
        (
            Some("BASE_DATA[1]".to_owned()),
            vec!["BASE_DATA[2]".to_owned()]
        )
    );
}

/// A jump forward arrives at its label with the state it was made with: there it is joined with
/// the path that falls through (not left by a jump of its own), as a block's end joins its
/// branches. A point copied before the jump and another copied on the way it skips may each be
/// what the copy holds after the label, and are used in the base the two paths agree on; a
/// branch that set `$IPO_MODE=#TCP` and jumped brings the stationary tool to the motions
/// after the label. Before, the label made the base unknown (every point moved to after it
/// was refused), took every copy of its routine (one made after the label too), and kept the
/// falling-through path's IPO mode, so a point moved to with the stationary tool that way was
/// corrected in the base.
#[test]
fn a_forward_jump_brings_its_state_to_the_label() {
    let dat = "DEFDAT cell\n\
        DECL E6POS XP1={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL E6POS XP2={X 410.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        ENDDAT\n";
    // Per point: (bases, a motion with an unresolved base, a stationary tool).
    let used = |body: &str| {
        let src = format!(
            "DEF cell( )\n  DECL E6POS XC\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  \
             LIN XP1\n  LIN XP2\n{body}END\n"
        );
        let p = load_cell_pair(&src, dat);
        p.files
            .iter()
            .flat_map(|f| f.positions())
            .map(|t| {
                (
                    crate::support::sorted_work_objects(&t.usage),
                    t.usage.unresolved_frame().is_some(),
                    t.usage.stationary_tool(),
                )
            })
            .collect::<Vec<_>>()
    };
    let base = |n: &[u32], unresolved: bool| {
        (
            n.iter()
                .map(|n| format!("BASE_DATA[{n}]"))
                .collect::<Vec<_>>(),
            unresolved,
            false,
        )
    };
    // Both paths in base 1: each point the copy may hold is used there, and resolved.
    let skipped = "  XC=XP1\n  IF $IN[1] THEN\n    GOTO L1\n  ENDIF\n  XC=XP2\n  L1:\n  LIN XC\n";
    assert_eq!(used(skipped), [base(&[1], false), base(&[1], false)]);
    // Jumped over unconditionally: only what the jump brings (base 1, `XP1`), not the base
    // and copy of the skipped code.
    let over = "  XC=XP1\n  GOTO L1\n  XC=XP2\n  $BASE=BASE_DATA[2]\n  L1:\n  LIN XC\n";
    assert_eq!(used(over), [base(&[1], false), base(&[1], false)]);
    // In another base after the label: each copy the paths bring is used in both; a copy made
    // after the label is not what the motion before it moves to.
    let after = "  XC=XP1\n  IF $IN[1] THEN\n    GOTO L1\n  ENDIF\n  L1:\n  $BASE=BASE_DATA[2]\n  \
                 LIN XC\n  XC=XP2\n";
    assert_eq!(used(after), [base(&[1, 2], false), base(&[1], false)]);
    // The two paths in two bases: unknown after the label.
    let two = "  IF $IN[1] THEN\n    GOTO L1\n  ENDIF\n  $BASE=BASE_DATA[2]\n  L1:\n  LIN XP1\n";
    assert_eq!(used(two), [base(&[1], true), base(&[1], false)]);
    // A stationary tool brought by the jump.
    let tcp = "  IF $IN[1] THEN\n    $IPO_MODE=#TCP\n    GOTO L1\n  ENDIF\n  L1:\n  \
               $BASE=BASE_DATA[1]\n  LIN XP1\n";
    assert_eq!(used(tcp)[0], (vec!["BASE_DATA[1]".to_owned()], false, true));
}

/// Program `src` with a `cell.dat` of `XP1`, `XP2` and `XP3` (and the sample `$config.dat`).
fn with_three_points(src: &str) -> Program {
    let dat = "DEFDAT cell\n\
        DECL E6POS XP1={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL E6POS XP2={X 410.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL E6POS XP3={X 420.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        ENDDAT\n";
    load_cell_pair(src, dat)
}

/// Whether each point of [`with_three_points`] is moved to with the stationary tool in program
/// `src`, by name.
fn stationary_points(src: &str) -> Vec<(String, bool)> {
    with_three_points(src)
        .files
        .iter()
        .flat_map(|f| f.positions())
        .map(|t| {
            (
                t.name.as_deref().unwrap_or_default().to_owned(),
                t.usage.stationary_tool(),
            )
        })
        .collect()
}

/// `XP1`, `XP2` and `XP3` by name, each with whether it is moved to with the stationary tool.
fn stationary_named(xp1: bool, xp2: bool, xp3: bool) -> Vec<(String, bool)> {
    vec![
        ("XP1".to_owned(), xp1),
        ("XP2".to_owned(), xp2),
        ("XP3".to_owned(), xp3),
    ]
}

/// A subroutine that leaves `$IPO_MODE` at `#TCP` leaves it so for the motions after its call:
/// they move with the stationary tool. Before, a routine's exit carried only the base, tool and
/// staged FDAT it set, so `SETTCP()` then `LIN XP1` was corrected in the base as a tool on the
/// flange.
#[test]
fn a_subroutine_that_sets_the_stationary_tool_leaves_it_set_after_its_call() {
    let stationary = |sub: &str| {
        stationary_points(&format!(
            "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP2\n  SETTCP()\n  \
             LIN XP1\nEND\nDEF SETTCP( )\n{sub}END\n"
        ))
    };
    // XP1, moved to after the call, with the stationary tool; XP2, before it, on the flange.
    assert_eq!(
        stationary("  $IPO_MODE=#TCP\n"),
        stationary_named(true, false, false)
    );
    // On one path of the routine: may be stationary, so not corrected as on the flange.
    assert_eq!(
        stationary("  IF $IN[1] THEN\n    $IPO_MODE=#TCP\n  ENDIF\n"),
        stationary_named(true, false, false)
    );
    // A routine that leaves the IPO mode alone.
    assert_eq!(
        stationary("  $OUT[1]=TRUE\n"),
        stationary_named(false, false, false)
    );
}

/// `$IPO_MODE` given a value trackfix does not evaluate (a variable, a function of a literal, an
/// FDAT's field) may be `#TCP`: the motions it reaches are taken as moving with the stationary
/// tool, and a warning at the value says so. Before, such a value was passed over: `$IPO_MODE=
/// MODE` then `LIN XP1` corrected `XP1` as a tool on the flange, exit 0, whatever `MODE` held.
#[test]
fn an_ipo_mode_trackfix_does_not_evaluate_may_be_the_stationary_tool() {
    let src = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP3\n  \
               LIN XP2 WITH $IPO_MODE=SIPO_MODE(#TCP)\n  $IPO_MODE=MODE\n  LIN XP1\nEND\n";
    // XP2 with its own WITH only; XP1 after the assignment; XP3 before both, on the flange.
    assert_eq!(stationary_points(src), stationary_named(true, true, false));
    let program = with_three_points(src);
    let warned: Vec<&str> = program.files[0]
        .diagnostics
        .iter()
        .map(|d| d.message.as_str())
        .filter(|m| m.starts_with("`$IPO_MODE` is given"))
        .collect();
    let taken = "which trackfix does not evaluate: the motions it reaches may move with the stationary tool (#TCP), and are taken so";
    assert_eq!(
        warned,
        [
            format!("`$IPO_MODE` is given `SIPO_MODE(#TCP)`, {taken}"),
            format!("`$IPO_MODE` is given `MODE`, {taken}"),
        ]
    );
}

/// An FDAT no file given declares (its data list not given) may hold `IPO_FRAME #TCP`: the
/// motions its IPO frame reaches, through `SIPO_MODE(FPX.IPO_FRAME)` or `FDAT_ACT = FPX` and a
/// `BAS` call, are taken as moving with the stationary tool, even where the base and tool are
/// set again after it. Before, its IPO frame was taken as `#BASE`, and `XP1`, `XP2` were
/// corrected as a tool on the flange, exit 0.
#[test]
fn the_ipo_frame_of_an_fdat_no_file_declares_may_be_the_stationary_tool() {
    let src = "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP3\n  \
               $IPO_MODE=SIPO_MODE(FPX.IPO_FRAME)\n  LIN XP1\n  $IPO_MODE=#BASE\n  \
               FDAT_ACT=FPX\n  BAS(#CP_PARAMS,0.2)\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  \
               LIN XP2\nEND\n";
    assert_eq!(stationary_points(src), stationary_named(true, true, false));
}

/// An FDAT another module's data list declares `GLOBAL` is read where a module stages or
/// reads it: its base, tool and IPO frame. Before, only `$config.dat`'s FDATs were seen from
/// other modules, so `FDAT_ACT = FPG` of `b.dat`'s `GLOBAL` FDAT left `XP1`'s base unknown
/// (refused) and `FPT`'s `#TCP` was not seen.
#[test]
fn an_fdat_another_module_declares_global_is_read_there() {
    let src = "DEF a( )\n  FDAT_ACT=FPG\n  BAS(#PTP_PARAMS,100)\n  PTP XP1\n  \
               $IPO_MODE=SIPO_MODE(FPT.IPO_FRAME)\n  LIN XP2\nEND\n";
    let dat = "DEFDAT a\n\
        DECL E6POS XP1={X 400.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        DECL E6POS XP2={X 410.0,Y -300.0,Z 500.0,A 10.0,B 80.0,C 5.0,S 2,T 10,E1 1500.0}\n\
        ENDDAT\n";
    let other = "DEFDAT b PUBLIC\n\
        DECL GLOBAL FDAT FPG={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE,POINT2[] \" \"}\n\
        DECL GLOBAL FDAT FPT={TOOL_NO 1,BASE_NO 1,IPO_FRAME #TCP,POINT2[] \" \"}\n\
        ENDDAT\n";
    let program = krl::load_program_from_sources(
        vec![
            (PathBuf::from("a.src"), src.as_bytes().to_vec()),
            (PathBuf::from("a.dat"), dat.as_bytes().to_vec()),
            (PathBuf::from("b.src"), b"DEF b( )\nEND\n".to_vec()),
            (PathBuf::from("b.dat"), other.as_bytes().to_vec()),
        ],
        &LoadOptions::default(),
    )
    .unwrap();
    let base1 = Some("BASE_DATA[1]".to_owned());
    assert_eq!(
        frames_by_name(&program),
        [
            ("XP1".to_owned(), base1.clone(), vec![], false),
            ("XP2".to_owned(), base1, vec![], true),
        ]
    );
}

/// A routine a call enters with `$IPO_MODE` at `#TCP` moves with the stationary tool until it
/// sets `#BASE`, whatever other calls enter it with, and passes it on to the routines it calls.
/// Before, every routine was followed as if entered with `#BASE`, so `$IPO_MODE=#TCP` then
/// `MOVE_PART()` corrected the routine's `LIN XP1` in the base as a tool on the flange.
#[test]
fn a_routine_entered_with_the_stationary_tool_moves_with_it() {
    let stationary = |main: &str, routines: &str| {
        stationary_points(&format!(
            "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP3\n{main}END\n\
             DEF MOVE_PART( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP1\nEND\n\
             {routines}"
        ))
    };
    // Entered with the stationary tool; the caller's motion before it on the flange.
    assert_eq!(
        stationary("  $IPO_MODE=#TCP\n  MOVE_PART()\n", ""),
        stationary_named(true, false, false)
    );
    // Entered with #BASE by one call, with #TCP by another: it may run with the stationary
    // tool.
    assert_eq!(
        stationary("  MOVE_PART()\n  $IPO_MODE=#TCP\n  MOVE_PART()\n", ""),
        stationary_named(true, false, false)
    );
    // Through a routine that calls it: entered with what that one was entered with.
    assert_eq!(
        stationary(
            "  $IPO_MODE=#TCP\n  OUTER()\n",
            "DEF OUTER( )\n  LIN XP2\n  MOVE_PART()\nEND\n"
        ),
        stationary_named(true, true, false)
    );
    // The stationary tool set after the call, or only in another routine, reaches no call.
    assert_eq!(
        stationary(
            "  MOVE_PART()\n  $IPO_MODE=#TCP\n",
            "DEF OTHER( )\n  $IPO_MODE=#TCP\n  LIN XP2\nEND\n"
        ),
        stationary_named(false, true, false)
    );
    // A routine that sets #BASE before it moves: on the flange, whatever it is entered with.
    assert_eq!(
        stationary(
            "  $IPO_MODE=#TCP\n  OUTER()\n",
            "DEF OUTER( )\n  $IPO_MODE=#BASE\n  LIN XP2\n  MOVE_PART()\nEND\n"
        ),
        stationary_named(false, false, false)
    );
}

/// A label a jump back reaches is reached with the IPO mode the jump was made with: after
/// `M1: LIN XP1 … $IPO_MODE=#TCP … GOTO M1` the second time round `XP1` moves with the
/// stationary tool. Before, the label kept the IPO mode of the path falling through to it, so
/// `XP1` was corrected in the base as a tool on the flange.
#[test]
fn a_jump_back_brings_its_ipo_mode_to_the_label() {
    let stationary = |body: &str| {
        stationary_points(&format!(
            "DEF cell( )\n  LIN XP3\nM1:\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  \
             LIN XP1\n{body}END\n"
        ))
    };
    let back = "  IF $IN[1] THEN\n    GOTO M1\n  ENDIF\n";
    assert_eq!(
        stationary(&format!("  $IPO_MODE=#TCP\n  LIN XP2\n{back}")),
        stationary_named(true, true, false)
    );
    // Set #BASE again before the jump: the label is reached with #BASE both ways.
    assert_eq!(
        stationary(&format!(
            "  $IPO_MODE=#TCP\n  LIN XP2\n  $IPO_MODE=#BASE\n{back}"
        )),
        stationary_named(false, true, false)
    );
    // Through a second label: `M2` is reached with #TCP by its own jump back, and the path
    // from it brings that to the jump back to `M1` (followed round until nothing more comes).
    assert_eq!(
        stationary(
            "M2:\n  LIN XP2\n  IF $IN[2] THEN\n    $IPO_MODE=#TCP\n    GOTO M2\n  ENDIF\n  \
             IF $IN[3] THEN\n    GOTO M1\n  ENDIF\n"
        ),
        stationary_named(true, true, false)
    );
}

/// A subroutine that sets `$IPO_MODE=#BASE` on every path takes back a caller's `#TCP`: the
/// motions after its call are on the flange. One that sets it on some path only leaves the
/// caller's. Before, a routine was never taken to undo a caller's `#TCP`, and the motions
/// after the call were refused as stationary-tool.
#[test]
fn a_subroutine_that_sets_base_takes_back_the_callers_stationary_tool() {
    let stationary = |sub: &str| {
        stationary_points(&format!(
            "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  $IPO_MODE=#TCP\n  \
             LIN XP2\n  TO_BASE()\n  LIN XP1\nEND\nDEF TO_BASE( )\n{sub}END\n"
        ))
    };
    assert_eq!(
        stationary("  $IPO_MODE=#BASE\n"),
        stationary_named(false, true, false)
    );
    assert_eq!(
        stationary("  IF $IN[1] THEN\n    $IPO_MODE=#BASE\n  ENDIF\n"),
        stationary_named(true, true, false)
    );
}

/// A `RETURN` leaves its routine with what it has set on that path: the caller's motions after
/// the call get it joined with what the routine's end leaves. Before, `RETURN` was not followed,
/// so a path that set `#TCP` (or another base) and returned was taken over by the `#BASE` (or
/// base) set after it, and the caller's point was corrected with that.
#[test]
fn a_return_leaves_the_routine_with_what_it_set() {
    // The routine sets `returned` then returns on one path, `at_end` on the other.
    let src = |returned: &str, at_end: &str| {
        format!(
            "DEF cell( )\n  $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP2\n  SET()\n  \
             LIN XP1\nEND\nDEF SET( )\n  IF $IN[1] THEN\n    {returned}\n    RETURN\n  \
             ENDIF\n  {at_end}\nEND\n"
        )
    };
    assert_eq!(
        stationary_points(&src("$IPO_MODE=#TCP", "$IPO_MODE=#BASE")),
        stationary_named(true, false, false)
    );
    // The base: 2 on the returning path, 1 at the end; unknown after the call.
    let p = with_three_points(&src("$BASE=BASE_DATA[2]", "$BASE=BASE_DATA[1]"));
    let unresolved: Vec<bool> = p
        .files
        .iter()
        .flat_map(|f| f.positions())
        .map(|t| t.usage.unresolved_frame().is_some())
        .collect();
    assert_eq!(unresolved, [true, false, false]);
}

/// KRL modules named together from one folder are one program, as a KSS tree's `Program`
/// folder is: another module's motion to a `GLOBAL` point is one to that point, and a point used
/// with two bases that way is refused. Before, each pair was a program of its own and the point
/// was corrected in its own module's base while the other module moved to it in another. Files
/// from two folders stay programs of their own.
#[test]
fn krl_modules_named_together_from_one_folder_are_one_program() {
    use trackfix::program::{LoadOptions, collect_programs, load_group};
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    };
    let main = write(
        "main.src",
        "DEF main( )\n  $BASE=BASE_DATA[1]\n  LIN XG\n  mod2()\nEND\n",
    );
    write(
        "main.dat",
        "DEFDAT main PUBLIC\nDECL GLOBAL E6POS XG={X 100.0,Y 200.0,Z 300.0,A 0.0,B 0.0,C 0.0,S 2,T 2,E1 500.0}\nENDDAT\n",
    );
    let mod2 = write(
        "mod2.src",
        "DEF mod2( )\n  $BASE=BASE_DATA[2]\n  LIN XG\nEND\n",
    );
    write("mod2.dat", "DEFDAT mod2\nENDDAT\n");
    let other = write("other/mod2.src", "DEF mod2( )\nEND\n");
    let groups = collect_programs(&[main.clone(), mod2.clone(), other]).unwrap();
    assert_eq!(groups.len(), 2, "{groups:?}");
    let program = load_group(&groups[0], &LoadOptions::default())
        .into_iter()
        .next()
        .unwrap()
        .unwrap();
    let xg = program
        .files
        .iter()
        .flat_map(|f| (0..f.positions.len()).filter_map(|i| f.position(i)))
        .find(|p| p.name.as_deref() == Some("XG"))
        .unwrap();
    assert_eq!(xg.usage.wobj.as_deref(), Some("BASE_DATA[1]"));
    assert_eq!(xg.usage.other_wobjs(), ["BASE_DATA[2]"]);
}

/// An interrupt's routine runs whenever the interrupt fires once switched on, so it may be
/// entered with `$IPO_MODE` at `#TCP` wherever the program sets it: its points may move with
/// the stationary tool. Before, it was taken to start with `#BASE`, so with `$IPO_MODE=#TCP`
/// in the main routine `CATCH`'s `LIN XP1 WITH $BASE=…` was corrected in the base as a tool on
/// the flange. (The frames are set in each motion's `WITH`: a routine run at any time that
/// sets `$BASE` leaves every motion's base unknown.)
#[test]
fn an_interrupts_routine_may_start_with_the_stationary_tool() {
    let stationary = |main: &str| {
        stationary_points(&format!(
            "DEF cell( )\n  INTERRUPT DECL 5 WHEN $IN[10]==TRUE DO CATCH( )\n  INTERRUPT ON 5\n  \
             $BASE=BASE_DATA[1]\n  $TOOL=TOOL_DATA[1]\n  LIN XP3\n{main}END\n\
             DEF CATCH( )\n  LIN XP1 WITH $BASE=BASE_DATA[1], $TOOL=TOOL_DATA[1]\n  SUB()\nEND\n\
             DEF SUB( )\n  LIN XP2 WITH $BASE=BASE_DATA[1], $TOOL=TOOL_DATA[1]\nEND\n"
        ))
    };
    // #TCP set while the interrupt may fire: `CATCH` and the routine it calls may run with it.
    assert_eq!(
        stationary("  $IPO_MODE=#TCP\n  LIN XP3\n"),
        stationary_named(true, true, true)
    );
    // Set in a motion's own `WITH` alone: the interrupt may fire during that motion.
    assert_eq!(
        stationary("  LIN XP3 WITH $IPO_MODE=#TCP\n"),
        stationary_named(true, true, true)
    );
    // Never #TCP: on the flange.
    assert_eq!(
        stationary("  LIN XP3\n"),
        stationary_named(false, false, false)
    );
}
