//! `correct` and `zero` (DESIGN.md §4, seed eq. 4.55).
//!
//! For a target `T` in work object `W` at skid `s`, with the controller's nominal base
//! `B(s) = Trans(s·a)·B_0` and the profile's deviation `D(s)`:
//! - correct: `T' = W⁻¹ · B(s) · D(s)⁻¹ · B(s)⁻¹ · W · T`
//! - zero:    `T' = W⁻¹ · B(s) · D(s)   · B(s)⁻¹ · W · T`

use std::collections::BTreeMap;

use nalgebra::{Translation3, Vector3};

use crate::geometry::Pose;
use crate::position::{FrameKind, Language, ParsedFile, Position, Program, Skid};
use crate::track::{Profile, TrackError};

use super::cell::Robot;
use super::edits::{ProgramEdits, TargetChange};
use super::refusal::{Refusal, RefusalKind, SKIP_HINT};
use super::rewrite::{OrientationHint, pose_change, pose_edits};

/// `D(s)`: anything that gives the track's deviation at a skid (a [`Profile`], or a test's
/// closed form).
pub trait Deviation {
    fn deviation(&self, skid: f64) -> Result<Pose, TrackError>;
}

impl Deviation for Profile {
    fn deviation(&self, skid: f64) -> Result<Pose, TrackError> {
        Profile::deviation(self, skid)
    }
}

impl<F: Fn(f64) -> Result<Pose, TrackError>> Deviation for F {
    fn deviation(&self, skid: f64) -> Result<Pose, TrackError> {
        self(skid)
    }
}

/// `correct` or `zero`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// CAD → real track: apply `D⁻¹`.
    Correct,
    /// Online-tuned → straight track: apply `D`.
    Zero,
}

impl Direction {
    pub fn as_str(self) -> &'static str {
        match self {
            Direction::Correct => "correct",
            Direction::Zero => "zero",
        }
    }
}

/// One robot's track as a transform needs it.
pub struct TrackSetup<'a> {
    /// `B_0`: the controller's robot base in world at skid 0.
    pub base0: Pose,
    /// `a`: unit track direction in world.
    pub track_axis: Vector3<f64>,
    /// External axis index of the skid (0 = `eax_a` / `E1`).
    pub skid_axis: usize,
    /// Work objects / bases overriding the program's (lower-case name → pose in world).
    pub frames: BTreeMap<String, Pose>,
    pub deviation: &'a dyn Deviation,
    /// The work object for declared targets no motion uses (`--default-wobj`).
    pub default_wobj: Option<String>,
}

impl<'a> TrackSetup<'a> {
    pub fn new(robot: &Robot, deviation: &'a dyn Deviation) -> TrackSetup<'a> {
        TrackSetup {
            base0: robot.base0,
            track_axis: robot.track_axis,
            skid_axis: robot.skid_axis,
            frames: robot.frames.clone(),
            deviation,
            default_wobj: None,
        }
    }

    /// `B(s) = Trans(s·a)·B_0`.
    pub fn base_at(&self, skid: f64) -> Pose {
        Translation3::from(self.track_axis * skid) * self.base0
    }

    /// The work-object-frame change `W⁻¹·B·D^∓1·B⁻¹·W` at skid `s` (left factor of `T`).
    pub fn correction(&self, w: &Pose, skid: f64, dir: Direction) -> Result<Pose, TrackError> {
        let b = self.base_at(skid);
        let d = self.deviation.deviation(skid)?;
        let d = match dir {
            Direction::Correct => d.inverse(),
            Direction::Zero => d,
        };
        Ok(w.inverse() * b * d * b.inverse() * w)
    }
}

/// Names that mean "world" when a program does not declare them.
fn is_world(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    matches!(
        n.as_str(),
        "wobj0" | "base_data[0]" | "$nullframe" | "$world"
    )
}

enum Resolved {
    Frame(Pose),
    Refused(RefusalKind, String, String),
}

/// The work object / base `name` in world: the cell's override, else the program's
/// declaration, else world for `wobj0`.
fn resolve_frame(program: &Program, setup: &TrackSetup, name: &str) -> Resolved {
    let lower = name.to_ascii_lowercase();
    if let Some(p) = setup.frames.get(&lower) {
        return Resolved::Frame(*p);
    }
    let decl = program.files.iter().flat_map(|f| &f.frames).find(|d| {
        matches!(d.kind, FrameKind::WorkObject | FrameKind::Base)
            && d.name.eq_ignore_ascii_case(name)
    });
    match decl {
        Some(d) if d.ufprog == Some(false) => Resolved::Refused(
            RefusalKind::MovingWorkObject,
            format!("work object `{name}` is moved by a mechanical unit (ufprog FALSE)"),
            "its position depends on that unit, not on the track: correct such targets by hand"
                .to_owned(),
        ),
        Some(d) if d.robhold == Some(true) => Resolved::Refused(
            RefusalKind::StationaryTool,
            format!("work object `{name}` is held by the robot (robhold TRUE: stationary tool)"),
            "a stationary-tool target moves with the work piece, not the track: correct it by hand"
                .to_owned(),
        ),
        Some(d) => match d.pose() {
            Some(p) => Resolved::Frame(p),
            None => Resolved::Refused(
                RefusalKind::UnresolvedWorkObject,
                format!("work object `{name}` has fields that are not numbers"),
                format!(
                    "give `{name}` as {{x,y,z,rx,ry,rz}} under [robot.NAME.wobj] in the cell file"
                ),
            ),
        },
        None if is_world(name) => Resolved::Frame(Pose::identity()),
        None => Resolved::Refused(
            RefusalKind::UnresolvedWorkObject,
            format!("work object `{name}` is not declared in the program"),
            format!("add `{name}` under [robot.NAME.wobj] in the cell file"),
        ),
    }
}

/// Checks that every transform makes before touching a Cartesian target; `None` = go ahead.
pub(crate) fn common_refusal(file: &ParsedFile, p: &Position) -> Option<Refusal> {
    let label = p.label();
    let refuse = |kind, msg: String, hint: &str| {
        Some(Refusal::new(
            file,
            p.span,
            label.clone(),
            kind,
            msg,
            format!("{hint}, {SKIP_HINT}"),
        ))
    };
    let kind = p.kind.as_str();
    if !p.kind.is_cartesian() {
        return refuse(
            RefusalKind::JointTarget,
            format!("{kind} `{label}` is a joint target: it is not changed"),
            "re-teach it or convert it to a Cartesian target",
        );
    }
    if p.cartesian.as_ref().and_then(|c| c.pose()).is_none() {
        return refuse(
            RefusalKind::Expression,
            format!("{kind} `{label}` has a position or orientation field that is not a number"),
            "write the fields as numeric literals",
        );
    }
    if p.usage.stationary_tool {
        let what = match file.language {
            Language::Rapid => "robhold TRUE",
            Language::Krl => "IPO_FRAME #TCP",
        };
        return refuse(
            RefusalKind::StationaryTool,
            format!("{kind} `{label}` is a stationary-tool point ({what})"),
            "it moves with the work piece, not the track: correct it by hand",
        );
    }
    if let Some(other) = p.usage.other_wobjs.first() {
        let first = p.usage.wobj.as_deref().unwrap_or("?");
        return refuse(
            RefusalKind::TwoWorkObjects,
            format!("{kind} `{label}` is used with two work objects (`{first}` and `{other}`)"),
            "split it into one target per work object",
        );
    }
    None
}

/// `correct` or `zero` every Cartesian target of `program` with `setup`'s track.
pub fn track_correction(program: &Program, setup: &TrackSetup, dir: Direction) -> ProgramEdits {
    let mut out = ProgramEdits::for_program(program);
    for (file, fe) in program.files.iter().zip(out.files.iter_mut()) {
        for p in &file.positions {
            if let Some(r) = common_refusal(file, p) {
                fe.refusals.push(r);
                continue;
            }
            match correct_one(program, file, p, setup, dir) {
                Ok((edits, change)) => {
                    if !edits.is_empty() {
                        fe.edits.extend(edits);
                        fe.changes.push(change);
                    }
                }
                Err(r) => fe.refusals.push(*r),
            }
        }
    }
    out
}

type Corrected = (Vec<crate::syntax::Edit>, TargetChange);

fn correct_one(
    program: &Program,
    file: &ParsedFile,
    p: &Position,
    setup: &TrackSetup,
    dir: Direction,
) -> Result<Corrected, Box<Refusal>> {
    let label = p.label();
    let kind = p.kind.as_str();
    let refuse = |k, msg: String, hint: String| {
        Box::new(Refusal::new(
            file,
            p.span,
            label.clone(),
            k,
            msg,
            format!("{hint}, {SKIP_HINT}"),
        ))
    };
    let axis = axis_name(file.language, setup.skid_axis);
    let skid = match p.skid(setup.skid_axis) {
        Skid::At(s) => s,
        Skid::NotConnected => {
            return Err(refuse(
                RefusalKind::SkidNotConnected,
                format!("{kind} `{label}` has {axis} = 9E9 (not connected): no skid position"),
                format!(
                    "write the skid position into {axis}, or set `skid` for this robot in the cell file"
                ),
            ));
        }
        Skid::Missing => {
            return Err(refuse(
                RefusalKind::SkidMissing,
                format!("{kind} `{label}` has no numeric {axis}: no skid position"),
                format!("write the skid position into {axis}"),
            ));
        }
    };
    let wobj_name = match (&p.usage.wobj, p.usage.lines.is_empty()) {
        (Some(w), _) => w.clone(),
        (None, true) => match &setup.default_wobj {
            Some(d) => d.clone(),
            None => {
                return Err(refuse(
                    RefusalKind::UnresolvedWorkObject,
                    format!(
                        "{kind} `{label}` is not used by any motion: its work object is unknown"
                    ),
                    "pass --default-wobj NAME to transform unused targets in NAME".to_owned(),
                ));
            }
        },
        (None, false) => {
            return Err(refuse(
                RefusalKind::UnresolvedWorkObject,
                format!("{kind} `{label}` is used with a work object that cannot be resolved"),
                "name the work object explicitly in the motion instruction".to_owned(),
            ));
        }
    };
    let w = match resolve_frame(program, setup, &wobj_name) {
        Resolved::Frame(w) => w,
        Resolved::Refused(k, msg, hint) => {
            return Err(refuse(k, format!("{kind} `{label}`: {msg}"), hint));
        }
    };
    let correction = setup
        .correction(&w, skid, dir)
        .map_err(|e| match e {
            TrackError::OutOfRange { min, max, .. } => refuse(
                RefusalKind::SkidOutOfRange,
                format!(
                    "{kind} `{label}` is at skid {skid} mm, outside the profile's range [{min}, {max}] mm"
                ),
                "measure the track over this range, or set extrapolate = \"clamp\" or \"linear\" in the profile"
                    .to_owned(),
            ),
            other => refuse(
                RefusalKind::SkidOutOfRange,
                format!("{kind} `{label}` at skid {skid} mm: {other}"),
                "check the profile".to_owned(),
            ),
        })?;
    let Some(fields) = p.cartesian.as_ref() else {
        return Ok((Vec::new(), no_change()));
    };
    let Some(t) = fields.pose() else {
        return Ok((Vec::new(), no_change()));
    };
    let new = correction * t;
    let edits = pose_edits(fields, &new, OrientationHint::NearOriginal);
    let (mm, deg) = pose_change(&t, &new);
    Ok((
        edits,
        TargetChange {
            mm,
            deg,
            skid: Some(skid),
        },
    ))
}

fn no_change() -> TargetChange {
    TargetChange {
        mm: 0.0,
        deg: 0.0,
        skid: None,
    }
}

/// `eax_a` / `E1` … for messages.
pub(crate) fn axis_name(language: Language, index: usize) -> String {
    match language {
        Language::Rapid => format!("eax_{}", (b'a' + index.min(25) as u8) as char),
        Language::Krl => format!("E{}", index + 1),
    }
}
