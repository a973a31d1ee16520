//! `mirror` (DESIGN.md §4): `T' = M·Sa·M⁻¹ · T · Sb` in work-object coordinates.
//!
//! `Sa` reflects the normal of the mirror plane, `Sb` flips one tool axis so the tool frame is
//! right-handed again. A reflection `S = I - 2nnᵀ` is minus the half turn about `n`, whose
//! quaternion is `[0, n]`; so `Sa·R·Sb = (-Sa)·R·(-Sb)` and the mirrored quaternion is
//! `[0, na] ⊗ q ⊗ [0, nb]` exactly, without a matrix round trip. For the xz plane and tool flip
//! y this is RobotStudio's `[q1, q2, q3, q4] → [q1, -q2, q3, -q4]` and KUKA's
//! `(A, B, C) → (-A, B, -C)`.

use nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::geometry::Pose;
use crate::position::{
    CartesianFields, Config, FrameKind, NumField, OffsetKind, ParsedFile, Position, Program, Skid,
};
use crate::syntax::Edit;

use super::cell::{Axis, ConfigRule, Plane};
use super::edits::{ProgramEdits, TargetChange};
use super::refusal::{Refusal, RefusalKind, SKIP_HINT};
use super::rewrite::{
    MM_DECIMALS, OrientationHint, bits_edit, integer_edit, number_edit, pose_change, pose_edits,
    wijk,
};
use super::track_correction::common_refusal;

/// KUKA Turn bits of A1, A4 and A6: a mirror-image robot runs those axes with the opposite sign.
const TURN_A1_A4_A6: u32 = 0b10_1001;

/// Everything `mirror` needs.
#[derive(Clone, Debug, PartialEq)]
pub struct MirrorSettings {
    /// `M`: the mirror-plane frame in the work object (identity: the work object's own plane).
    pub frame: Pose,
    pub plane: Plane,
    pub tool_flip: Axis,
    pub config: ConfigRule,
    /// `s' = scale·s + offset`.
    pub skid_map: (f64, f64),
    /// External axis index of the skid (0 = `eax_a` / `E1`).
    pub skid_axis: usize,
    /// Also mirror the program's work objects, bases and tools.
    pub mirror_frames: bool,
    /// Mirror joint targets (axes 1, 4, 6 negated) instead of refusing them.
    pub mirror_joints: bool,
}

impl Default for MirrorSettings {
    fn default() -> MirrorSettings {
        MirrorSettings {
            frame: Pose::identity(),
            plane: Plane::Xz,
            tool_flip: Axis::Y,
            config: ConfigRule::Mirror,
            skid_map: (1.0, 0.0),
            skid_axis: 0,
            mirror_frames: false,
            mirror_joints: false,
        }
    }
}

fn unit(i: usize) -> Vector3<f64> {
    let mut v = Vector3::zeros();
    if let Some(c) = v.get_mut(i) {
        *c = 1.0;
    }
    v
}

/// The geometry of one mirror: the plane (point and unit normal) and the tool axis.
#[derive(Clone, Copy, Debug)]
pub struct Reflection {
    point: Vector3<f64>,
    normal: Vector3<f64>,
    tool_axis: Vector3<f64>,
}

impl Reflection {
    pub fn new(settings: &MirrorSettings) -> Reflection {
        Reflection {
            point: settings.frame.translation.vector,
            normal: settings.frame.rotation * unit(settings.plane.normal_axis()),
            tool_axis: unit(settings.tool_flip.index()),
        }
    }

    /// `Sa` applied to a point (reflection about the plane).
    pub fn point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        p - 2.0 * (p - self.point).dot(&self.normal) * self.normal
    }

    /// `Sa` applied to a free vector (an `Offs` offset).
    pub fn vector(&self, v: &Vector3<f64>) -> Vector3<f64> {
        v - 2.0 * v.dot(&self.normal) * self.normal
    }

    /// `Sb` applied to a tool-frame vector (a `RelTool` offset).
    pub fn tool_vector(&self, v: &Vector3<f64>) -> Vector3<f64> {
        v - 2.0 * v.dot(&self.tool_axis) * self.tool_axis
    }

    /// The quaternion of `Sa·R·Sb` (see the module comment), not normalised away from `q`'s sign.
    fn rotation(&self, r: &UnitQuaternion<f64>, right: Vector3<f64>) -> Quaternion<f64> {
        let pa = Quaternion::from_parts(0.0, self.normal);
        let pb = Quaternion::from_parts(0.0, right);
        -(pa * r.quaternion() * pb)
    }

    /// `T' = M·Sa·M⁻¹·T·Sb`, with the quaternion the analytic formula gives (sign included).
    pub fn target(&self, t: &Pose) -> (Pose, [f64; 4]) {
        let q = self.rotation(&t.rotation, self.tool_axis);
        let p = self.point(&t.translation.vector);
        let r = UnitQuaternion::from_quaternion(q);
        (
            Pose::from_parts(Translation3::from(p), r),
            [q.w, q.i, q.j, q.k],
        )
    }

    /// A frame in the mirrored space: `A·F·A` (work objects, bases: both sides reflect the
    /// plane, so `uframe'·oframe'·T' = Sa·uframe·oframe·T·Sb`).
    pub fn frame(&self, f: &Pose) -> (Pose, [f64; 4]) {
        let q = self.rotation(&f.rotation, self.normal);
        let p = self.point(&f.translation.vector);
        let r = UnitQuaternion::from_quaternion(q);
        (
            Pose::from_parts(Translation3::from(p), r),
            [q.w, q.i, q.j, q.k],
        )
    }

    /// A tool in the flange of the mirror-image robot: `Sb·tframe·Sb` (the mirrored flange is
    /// the flange reflected in its own flip axis).
    pub fn tool(&self, f: &Pose) -> (Pose, [f64; 4]) {
        let pa = Quaternion::from_parts(0.0, self.tool_axis);
        let q = -(pa * f.rotation.quaternion() * pa);
        let p = self.tool_vector(&f.translation.vector);
        let r = UnitQuaternion::from_quaternion(q);
        (
            Pose::from_parts(Translation3::from(p), r),
            [q.w, q.i, q.j, q.k],
        )
    }
}

/// An edit for a value that may be an exact sign flip: a flip keeps the original decimals
/// (`90` → `-90`), anything else gets the house minimum.
fn flip_or_value_edit(field: &Option<NumField>, new: f64, min_decimals: usize) -> Option<Edit> {
    let old = field.as_ref()?.value();
    let decimals = if new == -old { 0 } else { min_decimals };
    number_edit(field, new, decimals)
}

fn skid_edit(p: &Position, settings: &MirrorSettings) -> Option<Edit> {
    let (scale, offset) = settings.skid_map;
    match p.skid(settings.skid_axis) {
        Skid::At(s) => number_edit(
            p.extax.get(settings.skid_axis)?,
            scale * s + offset,
            MM_DECIMALS,
        ),
        Skid::NotConnected | Skid::Missing => None,
    }
}

fn config_edits(config: &Config) -> Vec<Edit> {
    match config {
        Config::Abb(cf) => cf
            .iter()
            .take(3)
            .filter_map(|f| {
                let v = f.as_ref()?.value();
                integer_edit(f, -(v.round() as i64) - 1)
            })
            .collect(),
        Config::Kuka { turn, .. } => turn
            .as_ref()
            .and_then(|t| bits_edit(turn, t.value ^ TURN_A1_A4_A6))
            .into_iter()
            .collect(),
        Config::None => Vec::new(),
    }
}

/// `mirror` every target (and, if asked, frame) of `program`.
pub fn mirror(program: &Program, settings: &MirrorSettings) -> ProgramEdits {
    let refl = Reflection::new(settings);
    let mut out = ProgramEdits::for_program(program);
    for (file, fe) in program.files.iter().zip(out.files.iter_mut()) {
        for p in &file.positions {
            if !p.kind.is_cartesian() {
                if settings.mirror_joints {
                    let mut edits: Vec<Edit> = [0, 3, 5]
                        .iter()
                        .filter_map(|&i| {
                            let f = p.joints.get(i)?;
                            flip_or_value_edit(f, -f.as_ref()?.value(), 0)
                        })
                        .collect();
                    edits.extend(skid_edit(p, settings));
                    if !edits.is_empty() {
                        fe.edits.extend(edits);
                        fe.changes.push(TargetChange {
                            mm: 0.0,
                            deg: 0.0,
                            skid: None,
                        });
                    }
                } else {
                    let label = p.label();
                    fe.refusals.push(Refusal::new(
                        file,
                        p.span,
                        label.clone(),
                        RefusalKind::JointTarget,
                        format!(
                            "{} `{label}` is a joint target: it is not mirrored",
                            p.kind.as_str()
                        ),
                        format!("pass --mirror-joints to negate axes 1, 4 and 6, {SKIP_HINT}"),
                    ));
                }
                continue;
            }
            match common_refusal(file, p) {
                // A mirror works in the target's own work-object coordinates, so a target used
                // with two work objects mirrors the same way in both.
                Some(r) if r.kind != RefusalKind::TwoWorkObjects => {
                    fe.refusals.push(r);
                    continue;
                }
                _ => {}
            }
            let Some(fields) = p.cartesian.as_ref() else {
                continue;
            };
            let Some(t) = fields.pose() else { continue };
            let (new, expected) = refl.target(&t);
            let mut edits = pose_edits(fields, &new, OrientationHint::Expected(expected));
            if settings.config == ConfigRule::Mirror {
                edits.extend(config_edits(&p.config));
            }
            edits.extend(skid_edit(p, settings));
            if !edits.is_empty() {
                let (mm, deg) = pose_change(&t, &new);
                let skid = match p.skid(settings.skid_axis) {
                    Skid::At(s) => Some(s),
                    _ => None,
                };
                fe.edits.extend(edits);
                fe.changes.push(TargetChange { mm, deg, skid });
            }
        }
        mirror_offsets(file, &refl, &mut fe.edits, &mut fe.refusals);
        if settings.mirror_frames {
            mirror_frames(file, &refl, &mut fe.edits);
        }
    }
    out
}

fn mirror_offsets(
    file: &ParsedFile,
    refl: &Reflection,
    edits: &mut Vec<Edit>,
    refusals: &mut Vec<Refusal>,
) {
    for call in &file.offsets {
        let known: Option<Vec<f64>> = call
            .delta
            .iter()
            .map(|f| f.as_ref().map(NumField::value))
            .collect();
        let (name, frame) = match call.kind {
            OffsetKind::Offs => ("Offs", "object"),
            OffsetKind::RelTool => ("RelTool", "tool"),
        };
        let v = match known {
            Some(d) => Vector3::new(d[0], d[1], d[2]),
            None => {
                refusals.push(Refusal::new(
                    file,
                    call.span,
                    call.target.clone(),
                    RefusalKind::Expression,
                    format!(
                        "{name}({}, …) has an offset that is not a number: it cannot be mirrored",
                        call.target
                    ),
                    format!("write the {frame}-frame offsets as numbers, {SKIP_HINT}"),
                ));
                continue;
            }
        };
        let new = match call.kind {
            OffsetKind::Offs => refl.vector(&v),
            OffsetKind::RelTool => refl.tool_vector(&v),
        };
        for (f, n) in call.delta.iter().zip([new.x, new.y, new.z]) {
            edits.extend(flip_or_value_edit(f, n, MM_DECIMALS));
        }
        if call.kind == OffsetKind::RelTool {
            // Sb·Rot(axis, θ)·Sb is the rotation about Sb·axis by -θ: rotations about the
            // flipped axis keep their sign, the other two change it.
            for (i, f) in call.rot.iter().enumerate() {
                let flip = refl.tool_axis[i] == 0.0;
                if let Some(v) = f.as_ref().map(NumField::value) {
                    if flip {
                        edits.extend(flip_or_value_edit(f, -v, 0));
                    }
                }
            }
        }
    }
}

fn frame_field_edits(fields: &CartesianFields, new: &Pose, expected: [f64; 4]) -> Vec<Edit> {
    pose_edits(fields, new, OrientationHint::Expected(expected))
}

fn mirror_frames(file: &ParsedFile, refl: &Reflection, edits: &mut Vec<Edit>) {
    for d in &file.frames {
        match d.kind {
            FrameKind::WorkObject | FrameKind::Base => {
                for fields in [&d.frame, &d.oframe].into_iter().flatten() {
                    if let Some(f) = fields.pose() {
                        let (new, q) = refl.frame(&f);
                        edits.extend(frame_field_edits(fields, &new, q));
                    }
                }
            }
            FrameKind::Tool => {
                if let Some(fields) = &d.frame {
                    if let Some(f) = fields.pose() {
                        let (new, q) = refl.tool(&f);
                        edits.extend(frame_field_edits(fields, &new, q));
                    }
                }
            }
        }
    }
}

/// `[q1..q4]` of a pose's rotation (tests and callers comparing with RobotStudio numbers).
pub fn quaternion_of(p: &Pose) -> [f64; 4] {
    wijk(&p.rotation)
}
