//! What `inspect` reports about programs: positions, frames, counts and lints per file, as a
//! table, JSON or CSV.
//!
//! The report is built from the shared position model and the dialect's vocabulary only, so
//! every language gets the same shape (docs/design.md §5). Rendering returns strings; the binary
//! prints them.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use nalgebra::UnitQuaternion;

use crate::geometry::{Pose, abb_quat_components, xyz_deg_angles};
use crate::position::{
    CartesianFields, Config, FrameDecl, FrameKind, Language, NumField, Orientation, ParsedFile,
    Position, Program, Skid,
};
use crate::syntax::{Diagnostic, Severity, Span, printable};

use super::check::{count_suffix, lints};

/// Options of `inspect`.
#[derive(Clone, Copy, Debug, Default)]
pub struct InspectOptions {
    /// External axis holding the skid: 0 = `eax_a` / `E1`.
    pub skid_axis: usize,
}

/// The whole JSON inspect document: `{"files": [...]}`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct InspectReport {
    /// One entry per file, in input order.
    pub files: Vec<FileReport>,
    /// The programs of more than one file (a RAPID task, a KSS tree, a KRL pair): which files
    /// form each, and how many of its targets resolved to a frame.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub programs: Vec<ProgramReport>,
}

/// One program of several files.
#[derive(Clone, Debug, Serialize)]
pub struct ProgramReport {
    /// The program's language.
    pub language: Language,
    /// The files that form it, as named.
    pub files: Vec<String>,
    /// Its Cartesian targets.
    pub targets: usize,
    /// Targets whose work object / base is known.
    pub resolved: usize,
}

impl ProgramReport {
    /// The report of `program`; `None` for a program with no language (no files).
    pub fn of(program: &Program) -> Option<ProgramReport> {
        let language = program.language()?;
        let targets = || program.files.iter().flat_map(|f| f.positions.usages());
        Some(ProgramReport {
            language,
            files: program
                .files
                .iter()
                .map(|f| f.path.display().to_string())
                .collect(),
            targets: targets().count(),
            resolved: targets().filter(|u| u.wobj.is_some()).count(),
        })
    }
}

/// `program (rapid, 3 files): 4 of 4 targets resolved to a wobj`.
impl std::fmt::Display for ProgramReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "program ({}, {} files): {} of {} targets resolved to a {}",
            language_name(self.language),
            self.files.len(),
            self.resolved,
            self.targets,
            self.language.dialect().vocabulary().frame_column,
        )
    }
}

/// Where a frame is declared: file and 1-based line.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Place {
    /// The file, as loaded.
    pub file: String,
    /// 1-based line of the declaration.
    pub line: usize,
}

impl InspectReport {
    /// The table's last line: `3 files, 41 positions, 1 skipped`.
    pub fn summary_line(&self, skipped: usize, unreadable: usize) -> String {
        let positions: usize = self.files.iter().map(|f| f.positions.len()).sum();
        format!(
            "{} files, {positions} positions{}{}",
            self.files.len(),
            count_suffix(skipped, "skipped"),
            count_suffix(unreadable, "unreadable")
        )
    }
}

/// One file of the report.
#[derive(Clone, Debug, Serialize)]
pub struct FileReport {
    /// The file, as named on input.
    pub path: String,
    /// Its language.
    pub language: Language,
    /// Every position it declares or writes inline, in file order.
    pub positions: Vec<PositionRow>,
    /// The work objects, tools and bases it declares.
    pub frames: Vec<FrameRow>,
    /// Constructs kept verbatim that the grammar does not know.
    pub opaque: usize,
    /// Positions by kind (`"robtarget": 212`).
    pub counts: BTreeMap<String, usize>,
    /// The file's findings ([`crate::report::lints`]): its warnings and errors.
    pub warnings: Vec<Message>,
    /// trackfix's provenance stamp: the last transform that wrote the file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stamp: Option<crate::transform::Stamp>,
}

/// A pose as reported: translation in mm, orientation as an ABB quaternion `[q1, q2, q3, q4]`
/// (scalar first, for every language) and as fixed-axis angles in degrees (docs/design.md §2).
/// A value that is not a numeric literal is `null`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PoseColumns {
    /// Translation x, mm.
    pub x: Option<f64>,
    /// Translation y, mm.
    pub y: Option<f64>,
    /// Translation z, mm.
    pub z: Option<f64>,
    /// The orientation as an ABB quaternion `[q1, q2, q3, q4]`, scalar first.
    pub q: Option<[f64; 4]>,
    /// Fixed-axis angle about x, degrees.
    pub rx: Option<f64>,
    /// Fixed-axis angle about y, degrees.
    pub ry: Option<f64>,
    /// Fixed-axis angle about z, degrees.
    pub rz: Option<f64>,
}

/// One position of the report. Coordinates that are not numeric literals are `null`.
#[derive(Clone, Debug, Serialize)]
pub struct PositionRow {
    /// Declared name; `null` for an inline literal.
    pub name: Option<String>,
    /// The data type (`robtarget`, `E6POS`, …).
    pub kind: &'static str,
    /// 1-based line of the position.
    pub line: usize,
    /// 1-based column of the position.
    pub column: usize,
    /// Translation and orientation.
    #[serde(flatten)]
    pub pose: PoseColumns,
    /// KRL only: `[A, B, C]` as written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub abc: Option<[Option<f64>; 3]>,
    /// ABB `[cf1, cf4, cf6, cfx]`; KRL `[Status, Turn]` values.
    pub config: Vec<Option<f64>>,
    /// KRL only: Status and Turn as written (`"'B010'"`, `"2"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub status: Option<String>,
    /// KRL only: Turn as written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turn: Option<String>,
    /// Joint values of joint targets, degrees.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub joints: Vec<Option<f64>>,
    /// The skid: the configured external axis; `null` when missing or not connected (9E9).
    pub skid: Option<f64>,
    /// Every external axis value as written (`null` where not a numeric literal).
    pub extax: Vec<Option<f64>>,
    /// The work object (RAPID `wobj`) or base (KRL `base`) of the instructions using it.
    #[serde(flatten)]
    pub frame: FrameColumn,
    /// The tool of the instructions using it; `null` when unused or unresolved.
    pub tool: Option<String>,
    /// Where the tool is declared in the program (`null`-less: absent when not declared).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_at: Option<Place>,
    /// With a robot's kinematics (inspect given a cell and robot): the `reach` verdict and the joints
    /// it solved (or the joint target's), degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reach: Option<ReachColumns>,
}

/// The reach columns of a position.
#[derive(Clone, Debug, Serialize)]
pub struct ReachColumns {
    /// The `reach` verdict (`ok`, `unreachable`, `outside-limit`, `config-mismatch`, `not-checked`).
    pub status: &'static str,
    /// The joints the solver found (or the joint target's own), degrees.
    pub solved_joints: Option<[f64; 6]>,
}

impl InspectReport {
    /// Adds the reach columns from `reach` (per file, its targets in the file's order).
    pub fn add_reach(&mut self, reach: &[crate::kinematics::reach::FileReach]) {
        for fr in reach {
            let path = fr.path.display().to_string();
            let Some(f) = self.files.iter_mut().find(|f| f.path == path) else {
                continue;
            };
            for (row, t) in f.positions.iter_mut().zip(&fr.targets) {
                row.reach = Some(ReachColumns {
                    status: t.status.as_str(),
                    solved_joints: t.joints,
                });
            }
        }
    }
}

fn reach_cells(p: &PositionRow) -> Option<[String; 7]> {
    let r = p.reach.as_ref()?;
    let j = |i: usize| r.solved_joints.map(|j| crate::syntax::fixed(j[i], 2));
    let c = |i: usize| j(i).unwrap_or_else(|| "-".to_owned());
    Some([r.status.to_owned(), c(0), c(1), c(2), c(3), c(4), c(5)])
}

/// The frame a position is used in, under the name its language gives that column (the
/// dialect's [`Vocabulary::frame_column`](crate::dialect::Vocabulary)): `"wobj": "wobj_car"`,
/// `"base": "BASE_DATA[3]"`; `null` when unused or unresolved.
#[derive(Clone, Debug)]
pub struct FrameColumn {
    /// The column's name in the dialect's vocabulary (`wobj`, `base`).
    pub column: &'static str,
    /// The frame's name; `null` when unused or unresolved.
    pub name: Option<String>,
    /// Where the frame is declared in the program, under `"wobj_at"` / `"base_at"`; absent when
    /// not declared (world, or unresolved).
    pub at: Option<Place>,
}

impl Serialize for FrameColumn {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap as _;
        let mut map = s.serialize_map(None)?;
        map.serialize_entry(self.column, &self.name)?;
        if let Some(at) = &self.at {
            map.serialize_entry(&format!("{}_at", self.column), at)?;
        }
        map.end()
    }
}

/// A declared work object, tool or base, with its pose in world.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    /// Declared name.
    pub name: String,
    /// The data type (`wobjdata`, `tooldata`, `FRAME`, …).
    pub kind: &'static str,
    /// 1-based line of the declaration.
    pub line: usize,
    /// The pose in world (docs/design.md §2).
    #[serde(flatten)]
    pub pose: PoseColumns,
    /// RAPID work objects and tools: `robhold` (the robot holds it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robhold: Option<bool>,
    /// RAPID work objects: `ufprog` (the user frame is fixed, not moved by a mechanical unit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ufprog: Option<bool>,
    /// RAPID work objects: `ufmec`, the mechanical unit that moves the user frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ufmec: Option<String>,
}

/// A located message.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Message {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// How serious it is.
    pub severity: Severity,
    /// What is wrong.
    pub message: String,
    /// What to do.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hint: Option<String>,
}

fn num(f: &Option<NumField>) -> Option<f64> {
    f.as_ref().map(NumField::value)
}

fn nums(fields: &[Option<NumField>]) -> Vec<Option<f64>> {
    fields.iter().map(num).collect()
}

impl PoseColumns {
    fn new(
        trans: [Option<f64>; 3],
        rotation: Option<&UnitQuaternion<f64>>,
        like: Option<[f64; 4]>,
    ) -> Self {
        let q = rotation.map(|r| abb_quat_components(r, like).map(tidy));
        let angles = rotation.map(|r| xyz_deg_angles(r).map(tidy));
        PoseColumns {
            x: trans[0],
            y: trans[1],
            z: trans[2],
            q,
            rx: angles.map(|a| a[0]),
            ry: angles.map(|a| a[1]),
            rz: angles.map(|a| a[2]),
        }
    }

    /// A literal as written: the translation as read, the orientation when all its fields are
    /// numeric (the translation may still be an expression).
    fn of_literal(c: &CartesianFields) -> Self {
        PoseColumns::new(
            [num(&c.trans[0]), num(&c.trans[1]), num(&c.trans[2])],
            c.rotation().as_ref(),
            c.written_quaternion(),
        )
    }

    /// `x, y, z` (3 decimals) and `rx, ry, rz` (4 decimals) for a table; `-` where unknown.
    fn cells(&self) -> [String; 6] {
        [
            cell(self.x, 3),
            cell(self.y, 3),
            cell(self.z, 3),
            cell(self.rx, 4),
            cell(self.ry, 4),
            cell(self.rz, 4),
        ]
    }

    /// A computed pose (a work object's `uframe·oframe`).
    fn of_pose(p: &Pose) -> Self {
        let t = p.translation.vector;
        PoseColumns::new(
            [Some(tidy(t.x)), Some(tidy(t.y)), Some(tidy(t.z))],
            Some(&p.rotation),
            None,
        )
    }
}

/// Computed values (a quaternion from A, B, C; angles from a quaternion) to 1e-9, so float
/// noise like `6.1e-17` does not reach reports. Written values are reported as read.
fn tidy(v: f64) -> f64 {
    let r = (v * 1e9).round() / 1e9;
    if r == 0.0 { 0.0 } else { r }
}

fn position_row(file: &ParsedFile, p: &Position, options: InspectOptions) -> PositionRow {
    let abc = match p.cartesian.as_ref().and_then(|c| c.orient.as_ref()) {
        Some(Orientation::Abc(abc)) => Some([num(&abc[0]), num(&abc[1]), num(&abc[2])]),
        _ => None,
    };
    let text = |span: Span| String::from_utf8_lossy(span.slice(&file.source)).into_owned();
    let (config, status, turn) = match &p.config {
        Config::Quadrants(cf) => (nums(cf), None, None),
        Config::StatusTurn { status, turn } => (
            vec![
                status.as_ref().map(|s| s.value() as f64),
                turn.as_ref().map(|t| t.value() as f64),
            ],
            status.as_ref().map(|s| text(s.span())),
            turn.as_ref().map(|t| text(t.span())),
        ),
        Config::None => (Vec::new(), None, None),
    };
    let skid = match p.skid(options.skid_axis) {
        Skid::At(s) => Some(s),
        Skid::NotConnected | Skid::Missing => None,
    };
    let frame = FrameColumn {
        column: file.language.dialect().vocabulary().frame_column,
        name: p.usage.wobj.as_deref().map(str::to_owned),
        at: None,
    };
    PositionRow {
        name: p.name.as_deref().map(str::to_owned),
        kind: p.kind.as_str(),
        line: p.line,
        column: p.column,
        pose: p
            .cartesian
            .as_ref()
            .map(PoseColumns::of_literal)
            .unwrap_or_default(),
        abc,
        config,
        status,
        turn,
        joints: nums(&p.joints),
        skid,
        extax: nums(&p.extax),
        frame,
        tool: p.usage.tool.as_deref().map(str::to_owned),
        tool_at: None,
        reach: None,
    }
}

/// The data type of a frame as its language names it.
fn frame_kind(kind: FrameKind, language: Language) -> &'static str {
    match kind {
        FrameKind::WorkObject => "wobjdata",
        FrameKind::Tool => language.dialect().vocabulary().tool_kind,
        FrameKind::Base => "base",
    }
}

fn frame_row(f: &FrameDecl, language: Language) -> FrameRow {
    FrameRow {
        name: f.name.clone(),
        kind: frame_kind(f.kind, language),
        line: f.line,
        pose: f
            .pose()
            .as_ref()
            .map(PoseColumns::of_pose)
            .unwrap_or_default(),
        robhold: f.held_by_robot,
        ufprog: f.fixed,
        ufmec: f.moved_by.clone(),
    }
}

/// A diagnostic of `file` as a located message (line and column, no source text).
pub fn message(file: &ParsedFile, d: &Diagnostic) -> Message {
    let (line, column) = file.lines.line_col(d.span.start);
    Message {
        line,
        column,
        severity: d.severity,
        message: d.message.clone(),
        hint: d.hint.clone(),
    }
}

/// The report of one parsed file.
pub fn inspect_file(file: &ParsedFile, options: InspectOptions) -> FileReport {
    let mut report = file_head(file);
    report.positions = file
        .positions()
        .map(|p| position_row(file, &p, options))
        .collect();
    report
}

/// A file's report without its positions: what is small (frames, counts, lints, stamp).
fn file_head(file: &ParsedFile) -> FileReport {
    let mut counts = BTreeMap::new();
    for (_, kind, _) in (0..file.positions.len()).filter_map(|i| file.positions.head(i)) {
        *counts.entry(kind.as_str().to_owned()).or_insert(0) += 1;
    }
    FileReport {
        path: file.path.display().to_string(),
        language: file.language,
        positions: Vec::new(),
        frames: file
            .frames
            .iter()
            .map(|f| frame_row(f, file.language))
            .collect(),
        opaque: file.opaque,
        counts,
        warnings: lints(file).iter().map(|d| message(file, d)).collect(),
        stamp: crate::transform::stamp::find(file).map(|(s, _)| s),
    }
}

/// Where in `program` the work object or base (`tool` false) or the tool named `name` is
/// declared.
fn place(program: &Program, name: &str, tool: bool) -> Option<Place> {
    program.files.iter().find_map(|f| {
        f.frames
            .iter()
            .find(|d| (d.kind == FrameKind::Tool) == tool && d.name.eq_ignore_ascii_case(name))
            .map(|d| Place {
                file: f.path.display().to_string(),
                line: d.line,
            })
    })
}

/// A position's row with the places of its frame and tool in `program`.
fn program_row(
    program: &Program,
    file: &ParsedFile,
    p: &Position,
    options: InspectOptions,
) -> PositionRow {
    let mut row = position_row(file, p, options);
    row.frame.at = row
        .frame
        .name
        .as_deref()
        .and_then(|n| place(program, n, false));
    row.tool_at = row.tool.as_deref().and_then(|n| place(program, n, true));
    row
}

/// The reports of every file of a program, each target with the place (file and line) of the
/// work object or base and of the tool it resolved to, wherever in the program they are declared.
pub fn inspect_program(program: &Program, options: InspectOptions) -> Vec<FileReport> {
    program
        .files
        .iter()
        .map(|f| {
            let mut report = file_head(f);
            report.positions = f
                .positions()
                .map(|p| program_row(program, f, &p, options))
                .collect();
            report
        })
        .collect()
}

/// The JSON inspect document of `programs` (each with whether it was loaded from several
/// inputs together, as [`ProgramReport`]s list them), serialised as it is built: the same bytes
/// as an [`InspectReport`] of [`inspect_program`] and [`ProgramReport::of`] (no reach columns),
/// without holding a row per position. A 20 MB module's rows and their text were two thirds of
/// the peak memory of its JSON report.
#[derive(Clone, Copy, Debug)]
pub struct InspectJson<'a> {
    /// The programs, in input order.
    pub programs: &'a [Program],
    /// Per program: loaded from several inputs together.
    pub grouped: &'a [bool],
    /// The options of the report.
    pub options: InspectOptions,
}

impl Serialize for InspectJson<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        /// The shape of [`InspectReport`].
        #[derive(Serialize)]
        struct Doc<'a> {
            files: LazyFiles<'a>,
            #[serde(skip_serializing_if = "Vec::is_empty")]
            programs: Vec<ProgramReport>,
        }
        Doc {
            files: LazyFiles(*self),
            programs: self
                .programs
                .iter()
                .zip(self.grouped)
                .filter(|(_, g)| **g)
                .filter_map(|(p, _)| ProgramReport::of(p))
                .collect(),
        }
        .serialize(s)
    }
}

/// The files of an [`InspectJson`], each built when it is written.
struct LazyFiles<'a>(InspectJson<'a>);

impl Serialize for LazyFiles<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq as _;
        let files = self
            .0
            .programs
            .iter()
            .flat_map(|p| p.files.iter().map(move |f| (p, f)));
        let mut seq = s.serialize_seq(Some(files.clone().count()))?;
        for (program, file) in files {
            let head = file_head(file);
            seq.serialize_element(&LazyFile {
                head: &head,
                rows: LazyRows {
                    program,
                    file,
                    options: self.0.options,
                },
            })?;
        }
        seq.end()
    }
}

/// One file of an [`InspectJson`]: the fields of [`FileReport`], in its order, with the
/// positions written row by row (the tests compare the two documents byte for byte).
struct LazyFile<'a> {
    head: &'a FileReport,
    rows: LazyRows<'a>,
}

impl Serialize for LazyFile<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct as _;
        let h = self.head;
        let mut st = s.serialize_struct("FileReport", 7 + usize::from(h.stamp.is_some()))?;
        st.serialize_field("path", &h.path)?;
        st.serialize_field("language", &h.language)?;
        st.serialize_field("positions", &self.rows)?;
        st.serialize_field("frames", &h.frames)?;
        st.serialize_field("opaque", &h.opaque)?;
        st.serialize_field("counts", &h.counts)?;
        st.serialize_field("warnings", &h.warnings)?;
        match &h.stamp {
            Some(stamp) => st.serialize_field("stamp", stamp)?,
            None => st.skip_field("stamp")?,
        }
        st.end()
    }
}

/// A file's positions, each row built, written and dropped in turn.
struct LazyRows<'a> {
    program: &'a Program,
    file: &'a ParsedFile,
    options: InspectOptions,
}

impl Serialize for LazyRows<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq as _;
        let mut seq = s.serialize_seq(Some(self.file.positions.len()))?;
        for p in self.file.positions() {
            seq.serialize_element(&program_row(self.program, self.file, &p, self.options))?;
        }
        seq.end()
    }
}

/// The inspect table: one block per file.
pub fn render_table(report: &InspectReport) -> String {
    let mut out = String::new();
    for f in &report.files {
        let _ = writeln!(
            out,
            "{} ({})",
            printable(&f.path),
            language_name(f.language)
        );
        if let Some(s) = &f.stamp {
            let _ = writeln!(out, "  stamp: {}", printable(&s.text()));
        }
        if !f.positions.is_empty() {
            let frame_col = f.language.dialect().vocabulary().frame_column;
            // A file whose targets are written as A, B, C (KRL) shows those, as written, and
            // its Status/Turn; others show the fixed-axis angles rx, ry, rz.
            let abc = f.positions.iter().any(|p| p.abc.is_some());
            let (r1, r2, r3) = if abc {
                ("A", "B", "C")
            } else {
                ("rx", "ry", "rz")
            };
            let st = if abc { " S/T" } else { "" };
            let with_reach = f.positions.iter().any(|p| p.reach.is_some());
            let _ = write!(
                out,
                "  {:<20} {:<11} {:>6} {:>10} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:<12} {:<12}{st}",
                "name", "kind", "line", "x", "y", "z", r1, r2, r3, "skid", frame_col, "tool"
            );
            if with_reach {
                let _ = write!(
                    out,
                    " {:<15} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
                    "reach", "a1", "a2", "a3", "a4", "a5", "a6"
                );
            }
            let _ = writeln!(out);
            for p in &f.positions {
                let frame = &p.frame.name;
                let [x, y, z, mut rx, mut ry, mut rz] = p.pose.cells();
                if let Some([a, b, c]) = p.abc {
                    [rx, ry, rz] = [cell(a, 4), cell(b, 4), cell(c, 4)];
                }
                let st = match (abc, &p.status, &p.turn) {
                    (false, ..) => String::new(),
                    (true, None, None) => " -".to_owned(),
                    (true, s, t) => format!(
                        " {}/{}",
                        s.as_deref().unwrap_or("-"),
                        t.as_deref().unwrap_or("-")
                    ),
                };
                let _ = write!(
                    out,
                    "  {:<20} {:<11} {:>6} {:>10} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:<12} {:<12}{st}",
                    printable(p.name.as_deref().unwrap_or("*")),
                    p.kind,
                    p.line,
                    x,
                    y,
                    z,
                    rx,
                    ry,
                    rz,
                    cell(p.skid, 1),
                    printable(frame.as_deref().unwrap_or("-")),
                    printable(p.tool.as_deref().unwrap_or("-")),
                );
                if let Some([st, a1, a2, a3, a4, a5, a6]) = reach_cells(p) {
                    let _ = write!(
                        out,
                        " {st:<15} {a1:>8} {a2:>8} {a3:>8} {a4:>8} {a5:>8} {a6:>8}"
                    );
                }
                let _ = writeln!(out);
            }
        }
        for fr in &f.frames {
            let [x, y, z, rx, ry, rz] = fr.pose.cells();
            let _ = writeln!(
                out,
                "  {} {} (line {}): x {x} y {y} z {z} rx {rx} ry {ry} rz {rz}",
                fr.kind,
                printable(&fr.name),
                fr.line,
            );
        }
        let counts: Vec<String> = f.counts.iter().map(|(k, n)| format!("{n} {k}")).collect();
        let _ = writeln!(
            out,
            "  summary: {}; {} frames; {} opaque; {} warnings",
            if counts.is_empty() {
                "no positions".to_owned()
            } else {
                counts.join(", ")
            },
            f.frames.len(),
            f.opaque,
            f.warnings.len()
        );
        for w in &f.warnings {
            let _ = writeln!(
                out,
                "  {}:{}:{}: {}: {}",
                printable(&f.path),
                w.line,
                w.column,
                w.severity.as_str(),
                printable(&w.message)
            );
        }
    }
    for p in &report.programs {
        let _ = writeln!(out, "{p}");
        for f in &p.files {
            let _ = writeln!(out, "  {f}");
        }
    }
    out
}

/// The inspect CSV: one row per position.
pub fn render_csv(report: &InspectReport) -> String {
    let with_reach = report
        .files
        .iter()
        .any(|f| f.positions.iter().any(|p| p.reach.is_some()));
    let mut out =
        String::from("file,language,name,kind,line,x,y,z,q1,q2,q3,q4,rx,ry,rz,skid,frame,tool");
    out.push_str(if with_reach {
        ",reach,a1,a2,a3,a4,a5,a6\n"
    } else {
        "\n"
    });
    for f in &report.files {
        for p in &f.positions {
            let q = |i: usize| p.pose.q.map(|q| q[i]);
            let frame = &p.frame.name;
            let fields = [
                csv_text(&f.path),
                language_name(f.language).to_owned(),
                csv_text(p.name.as_deref().unwrap_or("")),
                p.kind.to_owned(),
                p.line.to_string(),
                opt(p.pose.x),
                opt(p.pose.y),
                opt(p.pose.z),
                opt(q(0)),
                opt(q(1)),
                opt(q(2)),
                opt(q(3)),
                opt(p.pose.rx),
                opt(p.pose.ry),
                opt(p.pose.rz),
                opt(p.skid),
                csv_text(frame.as_deref().unwrap_or("")),
                csv_text(p.tool.as_deref().unwrap_or("")),
            ];
            let mut line = fields.join(",");
            if with_reach {
                let cells =
                    reach_cells(p).map(|c| c.map(|v| if v == "-" { String::new() } else { v }));
                let cells = cells.unwrap_or_default();
                line.push(',');
                line.push_str(&cells.join(","));
            }
            let _ = writeln!(out, "{line}");
        }
    }
    out
}

fn language_name(l: Language) -> &'static str {
    l.name()
}

fn cell(v: Option<f64>, places: usize) -> String {
    v.map_or_else(|| "-".to_owned(), |v| crate::syntax::fixed(v, places))
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

/// A text cell of the inspect CSV. A spreadsheet runs a cell that starts with `=`, `+`,
/// `-` or `@` (or a tab / CR) as a formula: such a cell gets a leading `'` unless it is a number.
fn csv_text(s: &str) -> String {
    let formula = s.starts_with(['=', '+', '@', '\t', '\r'])
        || (s.starts_with('-') && s.parse::<f64>().is_err());
    let s = if formula {
        format!("'{s}")
    } else {
        s.to_owned()
    };
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s
    }
}
