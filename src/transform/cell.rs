//! `cell.toml` (docs/design.md §6): the robots of a cell, their tracks, frames and the mirror plane.
//!
//! ```toml
//! [robot.r1]
//! profile = "track/profile.toml"          # relative to this file
//! base = { x = 0, y = -1800, z = 0, rx = 0, ry = 0, rz = 90 }
//! track_axis = [1, 0, 0]
//! skid = "eax_a"                          # or "E1"; the default
//! [robot.r1.wobj]                         # overrides the program's declarations
//! wobj_car = { x = 2000, y = 0, z = 600, rx = 0, ry = 0, rz = 0 }
//! "BASE_DATA[3]" = { x = 2000, y = 0, z = 600, rx = 0, ry = 0, rz = 0 }
//!
//! [mirror]
//! plane = "xz"
//! frame = { x = 0, y = -1850.75, z = 0, rx = 0, ry = 0, rz = 0 }   # optional
//! frame_in = "world"                      # or "wobj" (the default)
//! tool_flip = "y"
//! config = "mirror"
//! skid_map = [1.0, 0.0]
//! skid_map_from = "r1"                    # or ["r1", "k1"]: whose skids the map takes
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Deserialize;
use toml::Spanned;

use crate::geometry::{Pose, pose_xyz_deg};
use crate::located::Located;
use crate::syntax::Span;
use crate::syntax::{Diagnostic, Encoding};

/// Why a cell file could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CellError {
    /// The cell file could not be read.
    #[error("cannot read the cell file {}", path.display())]
    Io {
        /// The cell file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A syntax or schema error at its place in the cell file (or at a robot's `profile`).
    #[error(transparent)]
    Invalid(Box<Located>),
    /// A robot the cell file does not have.
    #[error("{}: no robot `{name}` in the cell file (robots: {})", path.display(), known.join(", "))]
    UnknownRobot {
        /// The cell file.
        path: PathBuf,
        /// The robot asked for.
        name: String,
        /// The robots the cell file has.
        known: Vec<String>,
    },
}

impl CellError {
    fn invalid(path: &Path, text: &str, span: Span, message: String, hint: &str) -> CellError {
        let mut d = Diagnostic::error(span, message);
        if !hint.is_empty() {
            d = d.with_hint(hint);
        }
        // TOML is UTF-8: its excerpts decode so, not as a program's Latin-1.
        let located = Located::new(path, text.as_bytes().to_vec(), d).in_encoding(Encoding::Utf8);
        CellError::Invalid(Box::new(located))
    }
}

/// What to do about a skid map that does not place the mirror-image robot (for a map from the
/// cell file or from elsewhere alike).
pub const SKID_MAP_HINT: &str =
    "write the map the bases give, or check both robots' base and track_axis and the mirror plane";

/// [`SKID_MAP_HINT`] for `mismatch`: with the plane in each work object, each work object's
/// plane needs the map to fit, and the plane in world is one for all.
pub fn skid_map_hint(mismatch: &super::mirror::SkidMapMismatch) -> String {
    match mismatch.work_object {
        None => SKID_MAP_HINT.to_owned(),
        Some(_) => format!(
            "{SKID_MAP_HINT}; or give the plane in world (frame_in = \"world\"), one plane for the targets of every work object"
        ),
    }
}

/// A pose written as `{ x, y, z, rx, ry, rz }` (mm, degrees, `R = Rz·Ry·Rx`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FrameXyz {
    /// Translation x, mm.
    #[serde(deserialize_with = "plausible_mm")]
    pub x: f64,
    /// Translation y, mm.
    #[serde(deserialize_with = "plausible_mm")]
    pub y: f64,
    /// Translation z, mm.
    #[serde(deserialize_with = "plausible_mm")]
    pub z: f64,
    /// Rotation about x, degrees (applied first).
    #[serde(deserialize_with = "plausible_deg")]
    pub rx: f64,
    /// Rotation about y, degrees.
    #[serde(deserialize_with = "plausible_deg")]
    pub ry: f64,
    /// Rotation about z, degrees (applied last).
    #[serde(deserialize_with = "plausible_deg")]
    pub rz: f64,
}

/// A frame coordinate beyond this (mm) is no position in a robot cell: a typo or a placeholder.
const PLAUSIBLE_FRAME_MM: f64 = 1e6;
/// A frame angle beyond this (degrees) is a typo.
const PLAUSIBLE_FRAME_DEG: f64 = 360.0;

fn plausible<'de, D: serde::Deserializer<'de>>(
    d: D,
    limit: f64,
    unit: &str,
) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && v.abs() <= limit {
        Ok(v)
    } else {
        Err(serde::de::Error::custom(format!(
            "{v} is not a plausible value: write a finite number of {unit} (at most {limit:e} in size)"
        )))
    }
}

fn plausible_mm<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    plausible(d, PLAUSIBLE_FRAME_MM, "mm")
}

fn plausible_deg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    plausible(d, PLAUSIBLE_FRAME_DEG, "degrees")
}

impl FrameXyz {
    /// The pose, `R = Rz·Ry·Rx` (`geometry::conventions`).
    pub fn pose(&self) -> Pose {
        pose_xyz_deg(self.x, self.y, self.z, self.rx, self.ry, self.rz)
    }
}

/// The reflected plane of a mirror, in the mirror frame.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    /// The plane of x and y (normal z).
    Xy,
    /// The plane of x and z (normal y).
    Xz,
    /// The plane of y and z (normal x).
    Yz,
}

impl Plane {
    /// Index of the plane's normal axis (0 = x).
    pub fn normal_axis(self) -> usize {
        match self {
            Plane::Xy => 2,
            Plane::Xz => 1,
            Plane::Yz => 0,
        }
    }
}

/// A tool axis (the one a mirror flips to make the tool frame right-handed again).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// The tool's x axis.
    X,
    /// The tool's y axis.
    Y,
    /// The tool's z axis.
    Z,
}

impl Axis {
    /// 0 for x, 1 for y, 2 for z.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// Where the `[mirror]` frame is given.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum FrameIn {
    /// In each target's work object (docs/design.md §4; the default).
    #[default]
    Wobj,
    /// In world: the physical plane of the cell, taken into each target's resolved work object
    /// (`M = W⁻¹·frame`), so targets in different work objects mirror about the same plane.
    World,
}

/// What a mirror does to the robot configuration.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ConfigRule {
    /// ABB cf1, cf4, cf6 → -cf-1; KUKA Turn bits of A1, A4, A6 toggled (mirror-image robots).
    Mirror,
    /// Configuration left as written.
    Keep,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CellToml {
    robot: BTreeMap<String, RobotToml>,
    mirror: Option<MirrorToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotToml {
    profile: Spanned<String>,
    base: FrameXyz,
    track_axis: Spanned<[f64; 3]>,
    skid: Option<Spanned<String>>,
    #[serde(default)]
    wobj: BTreeMap<String, FrameXyz>,
    config_dat: Option<String>,
    kinematics: Option<Spanned<crate::kinematics::cell_table::KinematicsToml>>,
    #[serde(default)]
    tool: BTreeMap<String, FrameXyz>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MirrorToml {
    plane: Option<Plane>,
    frame: Option<FrameXyz>,
    frame_in: Option<FrameIn>,
    tool_flip: Option<Axis>,
    config: Option<ConfigRule>,
    skid_map: Option<Spanned<[f64; 2]>>,
    skid_map_from: Option<Spanned<RobotNames>>,
}

/// A robot's name or a list of them (`"r1"`, `["r1", "k1"]`).
struct RobotNames(Vec<String>);

impl<'de> Deserialize<'de> for RobotNames {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<RobotNames, D::Error> {
        struct Names;
        impl<'de> serde::de::Visitor<'de> for Names {
            type Value = RobotNames;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a robot's name or a list of them, e.g. \"r1\" or [\"r1\", \"k1\"]")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RobotNames, E> {
                Ok(RobotNames(vec![v.to_owned()]))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<RobotNames, A::Error> {
                let mut names = Vec::new();
                while let Some(n) = seq.next_element::<String>()? {
                    names.push(n);
                }
                Ok(RobotNames(names))
            }
        }
        d.deserialize_any(Names)
    }
}

/// One robot of the cell, validated.
#[derive(Clone, Debug)]
pub struct Robot {
    /// Its name in the cell file (`[robot.NAME]`).
    pub name: String,
    /// The profile file, resolved against the cell file's folder.
    pub profile: PathBuf,
    /// Where the cell file names it.
    pub profile_span: Span,
    /// `B_0`: the controller's robot base in world at skid 0.
    pub base0: Pose,
    /// `a`: the unit track direction in world.
    pub track_axis: Vector3<f64>,
    /// The external axis holding the skid: 0 = `eax_a` / `E1`.
    pub skid_axis: usize,
    /// Work objects / bases that override the program's (lower-case name → pose in world).
    pub frames: BTreeMap<String, Pose>,
    /// KUKA `$config.dat`, resolved against the cell file's folder.
    pub config_dat: Option<PathBuf>,
    /// `[robot.NAME.kinematics]`: the arm, for reach and configuration checks.
    pub kinematics: Option<crate::kinematics::Kinematics>,
    /// `[robot.NAME.tool]`: tool frames on the flange that override the program's (lower-case
    /// name → pose), so each robot uses its own measured TCP.
    pub tools: BTreeMap<String, Pose>,
}

/// The `[mirror]` table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MirrorTable {
    /// `plane`: the reflected plane, in the mirror frame.
    pub plane: Option<Plane>,
    /// `frame`: the mirror frame; `None` for the work object's (or world's) own.
    pub frame: Option<Pose>,
    /// `frame_in`: what `frame` is given in.
    pub frame_in: FrameIn,
    /// `tool_flip`: the tool axis to flip.
    pub tool_flip: Option<Axis>,
    /// `config`: what happens to the robot configuration.
    pub config: Option<ConfigRule>,
    /// `skid_map = [scale, offset]`: the mirrored skid `s' = scale·s + offset` (`scale` finite
    /// and not 0, so the map has an inverse).
    pub skid_map: Option<(f64, f64)>,
    /// Where the cell file writes `skid_map`, for an error about it.
    pub skid_map_span: Option<Span>,
    /// `skid_map_from`: the robots whose skids `skid_map` takes (its `s`), robots of the cell;
    /// a mirror from another robot to one of them takes its inverse. Empty when not given:
    /// the map is then taken as written whichever way a mirror goes.
    pub skid_map_from: Vec<String>,
    /// Where the cell file writes `skid_map_from`.
    pub skid_map_from_span: Option<Span>,
}

/// Which way a mirror takes the `[mirror]` table's skid map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkidMapWay {
    /// As written: the mirror is from a robot `skid_map_from` names, or the table does not say.
    AsWritten,
    /// Its inverse, `s = (s' − offset)/scale`: the mirror is to a robot `skid_map_from` names.
    Inverse,
}

/// The `[mirror]` table's skid map as one mirror takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectedSkidMap {
    /// `(scale, offset)`, `s' = scale·s + offset` from the mirrored robot's skid.
    pub map: (f64, f64),
    /// Whether that is the table's map or its inverse.
    pub way: SkidMapWay,
}

/// A validated cell file.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The cell file.
    pub path: PathBuf,
    /// Its robots, by name.
    pub robots: BTreeMap<String, Robot>,
    /// Its `[mirror]` table (all `None` when it has none).
    pub mirror: MirrorTable,
    /// The file's text, for messages located in it after loading.
    text: String,
}

/// What the cell's entries for `robots` make of `program`'s work objects where the program's text
/// alone does not say: per file (its index), a warning at each declaration of a work object the
/// entries give whose object frame (RAPID `oframe`) is not the identity. An entry is the work
/// object's user frame, and the object frame the program's: the targets are transformed in
/// `entry · oframe` (`policy::resolve_frame`), as a controller composes `uframe · oframe`, where
/// before the entry stood for both and the object frame was dropped unsaid.
pub fn frame_readings(
    program: &crate::position::Program,
    robots: &[&Robot],
) -> Vec<(usize, Diagnostic)> {
    let mut out = Vec::new();
    if robots.iter().all(|r| r.frames.is_empty()) {
        return out;
    }
    for (fi, file) in program.files.iter().enumerate() {
        for d in &file.frames {
            if d.kind != crate::position::FrameKind::WorkObject
                || matches!(d.scope, crate::position::FrameScope::Routine(_))
            {
                continue;
            }
            let key = frame_key(&d.name);
            let named: Vec<String> = robots
                .iter()
                .filter(|r| r.frames.contains_key(&key))
                .map(|r| format!("`{}`", r.name))
                .collect();
            let Some(o) = d.oframe.as_ref().filter(|_| !named.is_empty()) else {
                continue;
            };
            let written = match o.pose() {
                Some(pose) if is_identity(&pose) => continue,
                Some(pose) => format!("oframe {}", inline_pose(&pose)),
                None => "an oframe with fields that are not numbers".to_owned(),
            };
            let entries = match named.as_slice() {
                [one] => format!("entry for robot {one} is"),
                [all @ .., last] => format!("entries for robots {} and {last} are", all.join(", ")),
                [] => continue,
            };
            out.push((
                fi,
                Diagnostic::warning(
                    d.span,
                    format!(
                        "work object `{}`: the cell file's {entries} its user frame, and this declaration's object frame ({written}) is kept: the targets are transformed in the cell's uframe · this oframe",
                        d.name
                    ),
                )
                .with_hint(
                    "if the cell's entry measures the whole work object (its object frame too), write this oframe as [[0,0,0],[1,0,0,0]]",
                )
                .shaping_transforms(),
            ));
        }
    }
    out
}

/// Whether `p` moves nothing, to 1e-9 mm and rad.
fn is_identity(p: &Pose) -> bool {
    p.translation.vector.norm() < 1e-9 && p.rotation.angle() < 1e-9
}

/// `{ x = 200, y = 0, z = 0, rx = 0, ry = 0, rz = 10 }`: a pose as the cell file writes one, to
/// 4 decimals with trailing zeros left off.
fn inline_pose(p: &Pose) -> String {
    let [x, y, z, rx, ry, rz] = crate::geometry::pose_to_xyz_deg(p);
    let short = |v: f64| short_number(v, 4);
    format!(
        "{{ x = {}, y = {}, z = {}, rx = {}, ry = {}, rz = {} }}",
        short(x),
        short(y),
        short(z),
        short(rx),
        short(ry),
        short(rz)
    )
}

/// The `[mirror]` table, its skid map checked: a scale that is a number and not 0 (a map with an
/// inverse), and `skid_map_from` naming robots of the cell, beside a `skid_map`, and not all of
/// them (the map takes the skids of one side of the mirror).
fn mirror_table(
    m: MirrorToml,
    robots: &BTreeMap<String, Robot>,
    located: &dyn Fn(Span, String, &str) -> CellError,
) -> Result<MirrorTable, CellError> {
    let skid_map = match &m.skid_map {
        None => None,
        Some(map) => {
            let [scale, offset] = *map.get_ref();
            let span = map.span().into();
            if !scale.is_finite() || !offset.is_finite() {
                return Err(located(
                    span,
                    format!("skid_map [{scale}, {offset}] is not two numbers"),
                    "write [scale, offset] for s' = scale·s + offset, e.g. [1.0, 0.0]",
                ));
            }
            if scale == 0.0 {
                return Err(located(
                    span,
                    format!(
                        "skid_map [0, {offset}] stands the mirror-image robot at skid {offset} whatever the skid, and has no inverse"
                    ),
                    "write the mirror-image robot's mm of skid per mm of the other's as the scale: 1 for tracks that run the same way, -1 for tracks that run opposite ways",
                ));
            }
            Some((scale, offset))
        }
    };
    let mut skid_map_from = Vec::new();
    if let Some(from) = &m.skid_map_from {
        let span = from.span().into();
        let names = &from.get_ref().0;
        let known = || robots.keys().cloned().collect::<Vec<_>>().join(", ");
        let hint = "name the robots whose skids the map takes, its s in s' = scale·s + offset (those on one side of the mirror), e.g. skid_map_from = \"r1\"";
        if skid_map.is_none() {
            return Err(located(
                span,
                "skid_map_from without a skid_map: it says whose skids the map takes".to_owned(),
                "write the skid_map it is about beside it, or leave skid_map_from out",
            ));
        }
        if names.is_empty() {
            return Err(located(
                span,
                "skid_map_from names no robot".to_owned(),
                hint,
            ));
        }
        if let Some(unknown) = names.iter().find(|n| !robots.contains_key(n.as_str())) {
            return Err(located(
                span,
                format!(
                    "skid_map_from: no robot `{unknown}` in the cell file (robots: {})",
                    known()
                ),
                hint,
            ));
        }
        if robots.keys().all(|r| names.contains(r)) {
            return Err(located(
                span,
                format!(
                    "skid_map_from names every robot of the cell ({}): the map takes the skids of one side of the mirror, and a mirror the other way its inverse",
                    known()
                ),
                hint,
            ));
        }
        skid_map_from = names.clone();
    }
    Ok(MirrorTable {
        plane: m.plane,
        frame: m.frame.map(|f| f.pose()),
        frame_in: m.frame_in.unwrap_or_default(),
        tool_flip: m.tool_flip,
        config: m.config,
        skid_map,
        skid_map_span: m.skid_map.as_ref().map(|m| m.span().into()),
        skid_map_from,
        skid_map_from_span: m.skid_map_from.as_ref().map(|m| m.span().into()),
    })
}

/// `v` to `decimals` decimals with trailing zeros left off, as a cell file is written by hand
/// (`1.000000` → `1`, `-0.0001` to 3 → `0`).
pub fn short_number(v: f64, decimals: usize) -> String {
    let t = format!("{v:.decimals$}");
    let t = match t.contains('.') {
        true => t.trim_end_matches('0').trim_end_matches('.'),
        false => &t,
    };
    match t {
        "-0" => "0".to_owned(),
        t => t.to_owned(),
    }
}

/// The key a frame or tool is found by in a cell's `[robot.NAME.wobj]` and `[robot.NAME.tool]`
/// tables: the name case-folded, an array element's index as its number (`"BASE_DATA[ 01 ]"`
/// → `"base_data[1]"`, `"wArr{ 2 }"` → `"warr{2}"`), which is how the programs' resolvers
/// name the element whatever its spelling.
pub fn frame_key(name: &str) -> String {
    let lower = name.trim().to_ascii_lowercase();
    for (open, close) in [('[', ']'), ('{', '}')] {
        if let Some((array, rest)) = lower.split_once(open)
            && let Some(index) = rest.strip_suffix(close)
            && let Ok(n) = index.trim().parse::<u32>()
        {
            return format!("{}{open}{n}{close}", array.trim_end());
        }
    }
    lower
}

/// `"eax_a"`…`"eax_f"` or `"E1"`…`"E6"` (any case) → 0…5.
pub fn skid_axis_index(name: &str) -> Option<usize> {
    let lower = name.trim().to_ascii_lowercase();
    if let Some(letter) = lower.strip_prefix("eax_") {
        let b = letter.as_bytes();
        if b.len() == 1 && (b'a'..=b'f').contains(&b[0]) {
            return Some((b[0] - b'a') as usize);
        }
    } else if let Some(digit) = lower.strip_prefix('e') {
        let b = digit.as_bytes();
        if b.len() == 1 && (b'1'..=b'6').contains(&b[0]) {
            return Some((b[0] - b'1') as usize);
        }
    }
    None
}

impl Cell {
    /// Reads and validates a cell file. Every schema error names `file:line:col`.
    pub fn load(path: &Path) -> Result<Cell, CellError> {
        let io = |source| CellError::Io {
            path: path.to_owned(),
            source,
        };
        let bytes = crate::output::read_input(path).map_err(io)?;
        let text = String::from_utf8(bytes)
            .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
        Cell::parse(path, &text)
    }

    /// Validates cell text; relative paths resolve against `path`'s folder.
    pub fn parse(path: &Path, text: &str) -> Result<Cell, CellError> {
        let located = |span: Span, message: String, hint: &str| {
            CellError::invalid(path, text, span, message, hint)
        };
        let raw: CellToml = toml::from_str(text).map_err(|e| {
            let span = e.span().map(Span::from).unwrap_or_default();
            located(
                span,
                e.message().trim().to_owned(),
                "see docs/design.md §6 or samples/cell.toml for the keys a cell file takes",
            )
        })?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut robots = BTreeMap::new();
        for (name, r) in raw.robot {
            let [ux, uy, uz] = *r.track_axis.get_ref();
            let axis = Vector3::new(ux, uy, uz);
            let norm = axis.norm();
            if !norm.is_finite() || norm < 1e-9 {
                return Err(located(
                    r.track_axis.span().into(),
                    format!("robot `{name}`: track_axis has no direction"),
                    "write the unit vector the base moves along per mm of skid, e.g. [1, 0, 0]",
                ));
            }
            // A hand-typed axis like [0.7071, 0.7071, 0] is meant to be unit; a clearly
            // non-unit one is more likely a gear factor typed into the wrong place.
            if (norm - 1.0).abs() > 1e-3 {
                return Err(located(
                    r.track_axis.span().into(),
                    format!("robot `{name}`: track_axis has length {norm:.6}, expected 1"),
                    "write a unit vector; a gear factor belongs in the track profile's fit, not in the cell",
                ));
            }
            let skid_axis = match &r.skid {
                None => 0,
                Some(s) => skid_axis_index(s.get_ref()).ok_or_else(|| {
                    located(
                        s.span().into(),
                        format!("robot `{name}`: unknown skid axis `{}`", s.get_ref()),
                        "use \"eax_a\" … \"eax_f\" (RAPID) or \"E1\" … \"E6\" (KRL)",
                    )
                })?,
            };
            let frames = r
                .wobj
                .iter()
                .map(|(k, f)| (frame_key(k), f.pose()))
                .collect();
            let kinematics = match &r.kinematics {
                Some(k) => Some(
                    k.get_ref()
                        .resolve(&name, k.span().into())
                        .map_err(|e| located(e.span, e.message, &e.hint))?,
                ),
                None => None,
            };
            let tools = r
                .tool
                .iter()
                .map(|(k, f)| (frame_key(k), f.pose()))
                .collect();
            robots.insert(
                name.clone(),
                Robot {
                    name,
                    profile: dir.join(r.profile.get_ref()),
                    profile_span: r.profile.span().into(),
                    base0: r.base.pose(),
                    track_axis: axis / norm,
                    skid_axis,
                    frames,
                    config_dat: r.config_dat.map(|c| dir.join(c)),
                    kinematics,
                    tools,
                },
            );
        }
        let mirror = match raw.mirror {
            Some(m) => mirror_table(m, &robots, &located)?,
            None => MirrorTable::default(),
        };
        Ok(Cell {
            path: path.to_owned(),
            robots,
            mirror,
            text: text.to_owned(),
        })
    }

    /// An error about `robot`'s profile, at the cell's `profile = …`: what went wrong reading
    /// it, and how to make one.
    pub fn profile_error(&self, robot: &Robot, error: &dyn std::fmt::Display) -> CellError {
        CellError::invalid(
            &self.path,
            &self.text,
            robot.profile_span,
            format!(
                "robot `{}`: cannot read its profile {}: {error}",
                robot.name,
                robot.profile.display()
            ),
            "the path is relative to the cell file; make a profile with \
             `trackfix track identify` and `trackfix track fit FRAMES.csv -o PROFILE.toml`",
        )
    }

    /// The `[mirror]` table's skid map for a mirror of robot `from`'s program for robot `to`
    /// (`None`: the run does not say), and which way it is taken: as written from a robot
    /// `skid_map_from` names, its inverse to one; as written when the table does not say.
    /// `None` without a `skid_map`. A map that is its own inverse (`[1, 0]`, `[-1, L]`) goes
    /// either way. Otherwise an error at `skid_map_from` where it does not tell the way: it
    /// names both robots or neither, or the run names only one it does not name (whose image
    /// could be for a robot on either side).
    pub fn skid_map_for(
        &self,
        from: Option<&str>,
        to: Option<&str>,
    ) -> Result<Option<DirectedSkidMap>, CellError> {
        let Some(map) = self.mirror.skid_map else {
            return Ok(None);
        };
        let directed = |map, way| Ok(Some(DirectedSkidMap { map, way }));
        let names = &self.mirror.skid_map_from;
        let inverse = super::mirror::inverse_skid_map(map);
        let own_inverse = (inverse.0 - map.0).abs() <= 1e-12 && (inverse.1 - map.1).abs() <= 1e-9;
        let Some(span) = self.mirror.skid_map_from_span.filter(|_| !own_inverse) else {
            return directed(map, SkidMapWay::AsWritten);
        };
        let named = |r: Option<&str>| r.map(|r| names.iter().any(|n| n == r));
        let message = match (named(from), named(to)) {
            (Some(true), Some(false) | None) => return directed(map, SkidMapWay::AsWritten),
            (Some(false) | None, Some(true)) => return directed(inverse, SkidMapWay::Inverse),
            (Some(true), Some(true)) => format!(
                "skid_map_from names both robot `{}` and robot `{}`, which this mirror is between: which way the skid map goes between them is not known",
                from.unwrap_or_default(),
                to.unwrap_or_default()
            ),
            (Some(false), Some(false)) => format!(
                "skid_map_from names neither robot `{}` nor robot `{}`, which this mirror is between: which way the skid map goes between them is not known",
                from.unwrap_or_default(),
                to.unwrap_or_default()
            ),
            (Some(false), None) => format!(
                "this mirror is of robot `{}`'s program, which skid_map_from does not name, for a robot not said: which way the skid map goes is not known",
                from.unwrap_or_default()
            ),
            (None, Some(false)) => format!(
                "this mirror is for robot `{}`, which skid_map_from does not name, of a robot's program not said: which way the skid map goes is not known",
                to.unwrap_or_default()
            ),
            (None, None) => "this mirror names neither the robot whose program it is nor the robot the image is for: which way the skid map goes is not known".to_owned(),
        };
        Err(CellError::invalid(
            &self.path,
            &self.text,
            span,
            message,
            "name the robots the mirror is between, one of them in skid_map_from (the map takes its skids; the way back its inverse)",
        ))
    }

    /// The error that the `[mirror]` table's `skid_map`, taken the `way` a run took it, does
    /// not put robot `to` where the mirror image of robot `from` stands: at `skid_map`, or at
    /// `skid_map_from` when the map fits the other way round (so it names the wrong side);
    /// where it fits the other way and the table does not say whose skids the map takes, the
    /// hint gives the key to add. `None` when the table has no `skid_map` (the map checked came
    /// from elsewhere).
    pub fn skid_map_error(
        &self,
        mismatch: &super::mirror::SkidMapMismatch,
        way: SkidMapWay,
    ) -> Option<CellError> {
        let map_span = self.mirror.skid_map_span?;
        let (from, to) = (&mismatch.from, &mismatch.to);
        let mut message = mismatch.to_string();
        if way == SkidMapWay::Inverse {
            message = format!(
                "skid_map_from names robot `{to}`, so this mirror takes the skid map the other way round, as its inverse: {message}"
            );
        }
        let (span, hint) = match (mismatch.inverse_fits, self.mirror.skid_map_from_span) {
            (false, _) => (map_span, skid_map_hint(mismatch)),
            (true, None) => (
                map_span,
                format!(
                    "the map takes robot `{to}`'s skids: say so with skid_map_from = \"{to}\" in the [mirror] table, and a mirror from robot `{from}` then takes its inverse"
                ),
            ),
            (true, Some(from_span)) => {
                let (named, other) = match way {
                    SkidMapWay::AsWritten => (from, to),
                    SkidMapWay::Inverse => (to, from),
                };
                (
                    from_span,
                    format!(
                        "skid_map_from names the wrong side of the mirror: name robot `{other}` in it, not `{named}`"
                    ),
                )
            }
        };
        Some(CellError::invalid(
            &self.path, &self.text, span, message, &hint,
        ))
    }

    /// The robot called `name`, or an error listing the known ones.
    pub fn robot(&self, name: &str) -> Result<&Robot, CellError> {
        self.robots
            .get(name)
            .ok_or_else(|| CellError::UnknownRobot {
                path: self.path.clone(),
                name: name.to_owned(),
                known: self.robots.keys().cloned().collect(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CELL: &str = r#"
[robot.r1]
profile = "track/profile.toml"
base = { x = 0, y = -1800, z = 0, rx = 0, ry = 0, rz = 90 }
track_axis = [1, 0, 0]
skid = "E2"
[robot.r1.wobj]
wobj_car = { x = 2000, y = 0, z = 600, rx = 0, ry = 0, rz = 0 }

[mirror]
plane = "xz"
skid_map = [1.0, 5.0]
"#;

    fn err(text: &str) -> String {
        match Cell::parse(Path::new("cell.toml"), text) {
            Err(e) => e.to_string(),
            Ok(_) => "parsed".to_owned(),
        }
    }

    #[test]
    fn frame_keys_fold_case_and_an_elements_index() {
        for (name, key) in [
            ("wobj_car", "wobj_car"),
            (" WObj_Car ", "wobj_car"),
            ("BASE_DATA[1]", "base_data[1]"),
            ("base_data[ 01 ]", "base_data[1]"),
            ("BASE_DATA [12]", "base_data[12]"),
            ("wArr{ 2 }", "warr{2}"),
            // Not a number: as written, folded.
            ("BASE_DATA[I]", "base_data[i]"),
            ("BASE_DATA[-1]", "base_data[-1]"),
        ] {
            assert_eq!(frame_key(name), key, "{name}");
        }
    }

    #[test]
    fn reads_robots_and_mirror() {
        let cell = Cell::parse(Path::new("cells/cell.toml"), CELL).unwrap();
        let r1 = cell.robot("r1").unwrap();
        assert_eq!(r1.profile, Path::new("cells/track/profile.toml"));
        assert_eq!(r1.skid_axis, 1);
        assert!((r1.base0.translation.vector.y + 1800.0).abs() < 1e-12);
        assert!(r1.frames.contains_key("wobj_car"));
        assert_eq!(cell.mirror.plane, Some(Plane::Xz));
        assert_eq!(cell.mirror.skid_map, Some((1.0, 5.0)));
        assert!(cell.robot("r9").unwrap_err().to_string().contains("r1"));
    }

    #[test]
    fn unknown_and_missing_keys_are_located() {
        let e = err(&CELL.replace("skid = \"E2\"", "skidd = \"E2\""));
        assert!(
            e.starts_with("cell.toml:6:1: error: unknown field `skidd`"),
            "{e}"
        );
        let e = err(&CELL.replace("track_axis = [1, 0, 0]\n", ""));
        assert!(e.contains("cell.toml:") && e.contains("track_axis"), "{e}");
        let e = err(&CELL.replace("rz = 90", "rw = 90"));
        assert!(e.starts_with("cell.toml:4:"), "{e}");
    }

    #[test]
    fn an_error_line_shows_its_utf8_comment_as_written() {
        // TOML is UTF-8: `·` is one character, not `Â·` (its two bytes as Latin-1).
        let e = err(&CELL.replace("[1.0, 5.0]", "[1.0, 5.0x]  # s' = 1.0·s + 5.0"));
        assert_eq!(
            e.lines().skip(2).take(2).collect::<Vec<_>>(),
            [
                "12 | skid_map = [1.0, 5.0x]  # s' = 1.0·s + 5.0",
                "   |                     ^"
            ],
            "{e}"
        );
        // The caret covers a value's characters, not its bytes.
        let e = err(&CELL.replace("plane = \"xz\"", "plane = \"x·z\""));
        assert_eq!(
            e.lines().skip(2).take(2).collect::<Vec<_>>(),
            ["11 | plane = \"x·z\"", "   |         ^^^^^"],
            "{e}"
        );
    }

    #[test]
    fn rejects_non_unit_axis_and_bad_skid() {
        let e = err(&CELL.replace("[1, 0, 0]", "[2, 0, 0]"));
        assert!(e.starts_with("cell.toml:5:14: error: robot `r1`: track_axis has length 2.000000"));
        let e = err(&CELL.replace("\"E2\"", "\"E7\""));
        assert!(e.contains("unknown skid axis `E7`"), "{e}");
        let ok = Cell::parse(
            Path::new("c.toml"),
            &CELL.replace("[1, 0, 0]", "[0.7071, 0.7071, 0]"),
        )
        .unwrap();
        assert!((ok.robots["r1"].track_axis.norm() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_non_finite_or_absurd_frame_value_is_a_located_error() {
        let good = "[robot.r1]\nprofile = \"p.toml\"\nbase = { x = 0, y = 0, z = 0, rx = 0, ry = 0, rz = 0 }\ntrack_axis = [1, 0, 0]\n";
        assert!(Cell::parse(Path::new("cell.toml"), good).is_ok());
        for bad in ["x = nan", "y = inf", "z = 1e22", "rz = 1e9"] {
            let key = bad.split(' ').next().unwrap();
            let text = good.replacen(&format!(" {key} = 0"), &format!(" {bad}"), 1);
            let e = err(&text);
            let value = bad.split(' ').next_back().unwrap();
            let col = text.lines().nth(2).unwrap().find(value).unwrap() + 1;
            assert!(
                e.starts_with(&format!("cell.toml:3:{col}: error:")),
                "{bad}: {e}"
            );
            assert!(e.contains("not a plausible value"), "{bad}: {e}");
        }
    }

    /// Two robots and a map that is not its own inverse, with `skid_map_from` = `from`.
    fn two_robots(from: &str) -> String {
        let robot = |name: &str| {
            format!(
                "[robot.{name}]\nprofile = \"p.toml\"\nbase = {{ x = 0, y = 0, z = 0, rx = 0, ry = 0, rz = 0 }}\ntrack_axis = [1, 0, 0]\n"
            )
        };
        format!(
            "{}{}{}[mirror]\nplane = \"xz\"\nskid_map = [2.0, 20.0]\nskid_map_from = {from}\n",
            robot("r1"),
            robot("k1"),
            robot("r2")
        )
    }

    /// The error's first line and its help line.
    fn said(e: &str) -> (String, String) {
        let first = e.lines().next().unwrap_or_default().to_owned();
        let help = e
            .lines()
            .find(|l| l.contains("= help:"))
            .unwrap_or_default();
        (first, help.trim().to_owned())
    }

    /// `skid_map_from` names the robots whose skids the map takes: a mirror from one of them
    /// takes the map as written, to one of them its inverse `s = (s' − offset)/scale`; where
    /// the run does not tell the way, an error at the entry. A map that is its own inverse goes
    /// either way, and without the key the map is taken as written (as before).
    #[test]
    fn skid_map_from_gives_the_way_a_mirror_takes_the_map() {
        let cell = Cell::parse(Path::new("cell.toml"), &two_robots("[\"r1\", \"k1\"]")).unwrap();
        assert_eq!(cell.mirror.skid_map_from, ["r1", "k1"]);
        let way = |from: Option<&str>, to: Option<&str>| {
            cell.skid_map_for(from, to).map_err(|e| e.to_string())
        };
        // s' = 2·s + 20, so s = (s' − 20)/2 = 0.5·s' − 10.
        let directed = |map, way| Ok(Some(DirectedSkidMap { map, way }));
        let written = directed((2.0, 20.0), SkidMapWay::AsWritten);
        let inverse = directed((0.5, -10.0), SkidMapWay::Inverse);
        assert_eq!(way(Some("r1"), Some("r2")), written);
        assert_eq!(way(Some("k1"), None), written);
        assert_eq!(way(Some("r2"), Some("r1")), inverse);
        assert_eq!(way(None, Some("k1")), inverse);
        for (from, to, message) in [
            (
                Some("r1"),
                Some("k1"),
                "skid_map_from names both robot `r1` and robot `k1`, which this mirror is between: which way the skid map goes between them is not known",
            ),
            (
                Some("r2"),
                None,
                "this mirror is of robot `r2`'s program, which skid_map_from does not name, for a robot not said: which way the skid map goes is not known",
            ),
            (
                None,
                None,
                "this mirror names neither the robot whose program it is nor the robot the image is for: which way the skid map goes is not known",
            ),
        ] {
            let e = way(from, to).unwrap_err();
            assert_eq!(
                said(&e),
                (
                    format!("cell.toml:16:17: error: {message}"),
                    "= help: name the robots the mirror is between, one of them in skid_map_from (the map takes its skids; the way back its inverse)".to_owned()
                ),
                "{e}"
            );
        }
        // Its own inverse: either way, whoever the robots are.
        for map in ["[1.0, 0.0]", "[-1.0, 8000.0]"] {
            let text = two_robots("\"r1\"").replace("[2.0, 20.0]", map);
            let own = Cell::parse(Path::new("cell.toml"), &text).unwrap();
            let written = own.mirror.skid_map.map(|map| DirectedSkidMap {
                map,
                way: SkidMapWay::AsWritten,
            });
            assert_eq!(own.skid_map_for(Some("r2"), Some("r1")).ok(), Some(written));
            assert_eq!(own.skid_map_for(None, None).ok(), Some(written));
        }
        // Without the key: as written, whichever way.
        let text = two_robots("\"r1\"").replace("skid_map_from = \"r1\"\n", "");
        let plain = Cell::parse(Path::new("cell.toml"), &text).unwrap();
        assert_eq!(
            plain.skid_map_for(Some("r2"), Some("r1")).ok(),
            Some(Some(DirectedSkidMap {
                map: (2.0, 20.0),
                way: SkidMapWay::AsWritten
            }))
        );
    }

    /// A `skid_map_from` that names no robot of the cell, every robot, or is beside no map, and
    /// a map with no inverse, are errors at the entry, saying what to write.
    #[test]
    fn skid_map_and_skid_map_from_are_checked_at_load() {
        let hint = "= help: name the robots whose skids the map takes, its s in s' = scale·s + offset (those on one side of the mirror), e.g. skid_map_from = \"r1\"";
        for (from, first, help) in [
            (
                "\"r3\"",
                "cell.toml:16:17: error: skid_map_from: no robot `r3` in the cell file (robots: k1, r1, r2)",
                hint,
            ),
            (
                "[\"r1\", \"r3\"]",
                "cell.toml:16:17: error: skid_map_from: no robot `r3` in the cell file (robots: k1, r1, r2)",
                hint,
            ),
            (
                "[]",
                "cell.toml:16:17: error: skid_map_from names no robot",
                hint,
            ),
            (
                "[\"r1\", \"k1\", \"r2\"]",
                "cell.toml:16:17: error: skid_map_from names every robot of the cell (k1, r1, r2): the map takes the skids of one side of the mirror, and a mirror the other way its inverse",
                hint,
            ),
            (
                "1",
                "cell.toml:16:17: error: invalid type: integer `1`, expected a robot's name or a list of them, e.g. \"r1\" or [\"r1\", \"k1\"]",
                "= help: see docs/design.md §6 or samples/cell.toml for the keys a cell file takes",
            ),
        ] {
            let e = err(&two_robots(from));
            assert_eq!(said(&e), (first.to_owned(), help.to_owned()), "{e}");
        }
        let e = err(&two_robots("\"r1\"").replace("skid_map = [2.0, 20.0]\n", ""));
        assert_eq!(
            said(&e),
            (
                "cell.toml:15:17: error: skid_map_from without a skid_map: it says whose skids the map takes".to_owned(),
                "= help: write the skid_map it is about beside it, or leave skid_map_from out".to_owned()
            ),
            "{e}"
        );
        let e = err(&two_robots("\"r1\"").replace("[2.0, 20.0]", "[0.0, 20.0]"));
        assert_eq!(
            said(&e),
            (
                "cell.toml:15:12: error: skid_map [0, 20] stands the mirror-image robot at skid 20 whatever the skid, and has no inverse".to_owned(),
                "= help: write the mirror-image robot's mm of skid per mm of the other's as the scale: 1 for tracks that run the same way, -1 for tracks that run opposite ways".to_owned()
            ),
            "{e}"
        );
        let e = err(&two_robots("\"r1\"").replace("[2.0, 20.0]", "[1.0, nan]"));
        assert!(
            e.starts_with("cell.toml:15:12: error: skid_map [1, NaN] is not two numbers"),
            "{e}"
        );
    }

    #[test]
    fn skid_names() {
        assert_eq!(skid_axis_index("eax_a"), Some(0));
        assert_eq!(skid_axis_index("EAX_F"), Some(5));
        assert_eq!(skid_axis_index("E1"), Some(0));
        assert_eq!(skid_axis_index("e6"), Some(5));
        assert_eq!(skid_axis_index("eax_g"), None);
        assert_eq!(skid_axis_index("E0"), None);
    }
}
