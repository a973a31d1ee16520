//! The dialect seam: a third language, written here, joins trackfix with one registry line
//! (`register(&Stub)`) and nothing else edited. The loader finds its files by extension, the
//! report names it, and `correct` transforms its targets through the one transform driver.
//!
//! The stub's format: one target per line, `x y z q1 q2 q3 q4 skid`, used in world.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use trackfix::dialect::{Dialect, Language, Vocabulary, register};
use trackfix::geometry::{Pose, pose_xyz_deg};
use trackfix::position::{
    CartesianFields, Config, KindSpec, NumField, Orientation, ParsedFile, Position, PositionKind,
    Program, Usage,
};
use trackfix::program::{LoadError, LoadOptions, load, read_source};
use trackfix::syntax::{LineIndex, NumLit, Span};
use trackfix::track::TrackError;
use trackfix::transform::{Direction, TrackSetup, apply, reparse, track_correction};

/// The stub dialect's one kind (a constant: a `KindSpec` is kept by reference).
const STUB_POSE: PositionKind = PositionKind::new(&KindSpec::pose("stubpose"));

struct Stub;

const VOCABULARY: Vocabulary = Vocabulary {
    frame_column: "frame",
    frames: "frames",
    frame: "frame",
    moved_frame: "moving frame",
    tool_kind: "tool",
    stationary_tool: "fixed tool",
    stationary_point: "fixed tool",
    world_frames: &["world"],
    frame_of_a_motion: "name the frame in each motion to it",
};

fn fields(src: &[u8], line: Span) -> Vec<NumField> {
    let mut out = Vec::new();
    let mut at = line.start;
    for word in line.slice(src).split(|b| *b == b' ') {
        if let Some(lit) = NumLit::parse(word) {
            out.extend(NumField::new(Span::new(at, at + word.len()), lit));
        }
        at += word.len() + 1;
    }
    out
}

fn parse(path: &Path, source: Vec<u8>) -> ParsedFile {
    let lines = LineIndex::new(&source);
    let mut positions = Vec::new();
    let mut start = 0;
    for (n, text) in source.split(|b| *b == b'\n').enumerate() {
        let span = Span::new(start, start + text.len());
        start = span.end + 1;
        let f: Vec<Option<NumField>> = fields(&source, span).into_iter().map(Some).collect();
        let [x, y, z, q1, q2, q3, q4, skid] = <[_; 8]>::try_from(f).unwrap_or_default();
        if x.is_none() {
            continue;
        }
        positions.push(Position {
            name: Some(format!("t{}", n + 1).into()),
            kind: STUB_POSE,
            span,
            line: n + 1,
            column: 1,
            cartesian: Some(CartesianFields {
                trans: [x, y, z],
                orient: Some(Orientation::Quaternion([q1, q2, q3, q4])),
            }),
            joints: Vec::new(),
            config: Config::None,
            extax: vec![skid].into(),
            usage: {
                let mut u = Usage::default();
                u.record(Some("world"), None, false, n + 1);
                u
            },
        });
    }
    ParsedFile {
        path: path.to_owned(),
        language: Language::of(&Stub),
        round_trip: true,
        lines,
        positions: trackfix::PositionList::packed(positions, &source),
        source: source.into(),
        frames: Vec::new(),
        frame_values: Vec::new(),
        offsets: Vec::new(),
        opaque: 0,
        diagnostics: Vec::new(),
    }
}

impl Dialect for Stub {
    fn name(&self) -> &'static str {
        "stub"
    }
    fn extensions(&self) -> &'static [&'static str] {
        &["stubpos"]
    }
    fn load(&self, path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
        Ok(Program {
            files: vec![parse(path, read_source(path, options)?.into_vec())],
        })
    }
    fn reparse(
        &self,
        files: Vec<(PathBuf, Vec<u8>)>,
        _: &LoadOptions,
    ) -> Result<Program, LoadError> {
        Ok(Program {
            files: files.into_iter().map(|(p, s)| parse(&p, s)).collect(),
        })
    }
    fn vocabulary(&self) -> &'static Vocabulary {
        &VOCABULARY
    }
    fn axis_name(&self, index: usize) -> String {
        format!("skid{index}")
    }
    fn mirror_config(&self, _: &Config) -> Vec<trackfix::syntax::Edit> {
        Vec::new()
    }
}

#[test]
fn a_third_dialect_joins_with_one_registry_line() {
    register(&Stub);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cell.STUBPOS");
    std::fs::write(
        &path,
        "100 200 300 1 0 0 0 2500\n# a comment\n0 0 0 1 0 0 0 9E9\n",
    )
    .unwrap();
    let program = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(program.language().map(Language::name), Some("stub"));
    assert_eq!(program.files[0].positions.len(), 2);

    // The report names the language and its frame column as the dialect says.
    let report = trackfix::report::inspect_program(&program, Default::default());
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json[0]["language"], "stub");
    assert_eq!(json[0]["positions"][0]["frame"], "world");

    // `correct` through the driver: rails 1 mm low everywhere lift the target by 1 mm; the
    // second target's skid is not connected and is refused in the dialect's words.
    let sag =
        |_s: f64| -> Result<Pose, TrackError> { Ok(pose_xyz_deg(0.0, 0.0, -1.0, 0.0, 0.0, 0.0)) };
    let setup = TrackSetup {
        base0: Pose::identity(),
        track_axis: nalgebra::Vector3::x(),
        skid_axis: 0,
        frames: BTreeMap::new(),
        deviation: &sag,
        default_wobj: None,
        uncertainty: None,
        arm: None,
        robot: None,
    };
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let refused: Vec<_> = result.refusals().collect();
    assert_eq!(refused.len(), 1);
    assert!(
        refused[0].message.contains("skid0 = 9E9"),
        "{}",
        refused[0].message
    );
    let again = reparse(&program, &result, &LoadOptions::default()).unwrap();
    let t = again.files[0]
        .position(0)
        .unwrap()
        .cartesian
        .as_ref()
        .unwrap()
        .translation()
        .unwrap();
    assert!((t[2] - 301.0).abs() < 1e-9, "{t:?}");
    assert!(
        (t[0] - 100.0).abs() < 1e-9 && (t[1] - 200.0).abs() < 1e-9,
        "{t:?}"
    );

    // An unknown extension's error lists every registered dialect's extensions.
    let err = load(&dir.path().join("x.txt"), &LoadOptions::default()).unwrap_err();
    assert!(err.to_string().contains(".stubpos"), "{err}");
}
