//! `mirror` (docs/design.md §4): `T' = M·Sa·M⁻¹ · T · Sb` in work-object coordinates.
//!
//! `Sa` reflects the normal of the mirror plane, `Sb` flips one tool axis so the tool frame is
//! right-handed again. A reflection `S = I - 2nnᵀ` is minus the half turn about `n`, whose
//! quaternion is `[0, n]`; so `Sa·R·Sb = (-Sa)·R·(-Sb)` and the mirrored quaternion is
//! `[0, na] ⊗ q ⊗ [0, nb]` exactly, without a matrix round trip. For the xz plane and tool flip
//! y this is RobotStudio's `[q1, q2, q3, q4] → [q1, -q2, q3, -q4]` and KUKA's
//! `(A, B, C) → (-A, B, -C)`.

use std::collections::BTreeMap;

use nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::geometry::Pose;
use crate::position::{
    CartesianFields, FrameDecl, FrameKind, NonPositionRole, NumField, OffsetCall, OffsetKind,
    ParsedFile, Position, Program, Skid,
};
use crate::syntax::Edit;

use super::cell::{Axis, ConfigRule, Plane};
use super::driver::{KeptByStamp, NewPose, Scope, Step, TargetRule, apply_rule};
use super::edits::{ProgramEdits, TargetChange};
use super::kinematic_policy::{Arm, config_edits, with_tool};
use super::kinematic_policy::{flange_move, fmt_joints};
use super::policy::{
    Why, common_refusal, describe, offset_bases, stationary_tool, wobj_of, words_of, work_object_of,
};
use super::refusal::{Refusal, RefusalKind, Remedy};
use super::rewrite::{
    DEG_DECIMALS, MM_DECIMALS, OrientationHint, QUAT_DECIMALS, number_edit, pose_edits,
};
use super::stamp::{Stamp, StampReading};
use crate::kinematics::reach::resolve_tool;
use crate::kinematics::{
    ConfigValue, Joints, KinematicRefusal, mirror_config_by_ik, mirrored_joints,
};

/// Everything `mirror` needs.
#[derive(Clone, Debug, PartialEq)]
pub struct MirrorSettings {
    /// `M`: the mirror-plane frame in the work object (identity: the work object's own plane).
    pub frame: Pose,
    /// The reflected plane, in `frame`.
    pub plane: Plane,
    /// The tool axis flipped to keep the tool frame right-handed.
    pub tool_flip: Axis,
    /// What happens to the robot configuration.
    pub config: ConfigRule,
    /// `s' = scale·s + offset`.
    pub skid_map: (f64, f64),
    /// External axis index of the skid (0 = `eax_a` / `E1`).
    pub skid_axis: usize,
    /// The mirror-image robot's skid axis when it is another one (`transfer` between robots
    /// whose skids sit on different axes): the mapped skid moves there and that axis's old
    /// value takes its place, so a second mirror the other way gives the program back.
    pub skid_axis_to: Option<usize>,
    /// Also mirror the program's work objects, bases and tools.
    pub mirror_frames: bool,
    /// Mirror joint targets (axes 1, 4, 6 negated) instead of refusing them; with `arm` they
    /// are always mirrored, through kinematics.
    pub mirror_joints: bool,
    /// The plane given in world instead (`frame_in = "world"`): each target mirrors about it
    /// in its own work object, `M = W⁻¹·plane`.
    pub world: Option<WorldPlane>,
    /// The robot's arm and track, when the cell gives its kinematics: configurations and joint
    /// targets are then mirrored through inverse kinematics (docs/design.md §10).
    pub arm: Option<MirrorArm>,
}

/// What mirroring through kinematics needs: the arm, where the robot base is at each skid, and
/// how a target's work object resolves.
///
/// Without [`MirrorArm::image`] the mirror-image robot is assumed to stand as this robot's
/// mirror image in the xz plane of its base (a symmetric cell: `B' = Sa·B·Sy`): a flange pose
/// `F` in this robot's base is then `Sy·F·Sy` in the other's, `Sy = diag(1, −1, 1)`. A real
/// cell's two bases are measured apart (the sample's by 0.86 mm): with the image robot given,
/// configurations and joint targets are solved in its own base.
#[derive(Clone, Debug, PartialEq)]
pub struct MirrorArm {
    /// The arm being mirrored, with the cell's tools.
    pub arm: Arm,
    /// `B_0`, the robot base at skid 0 (as [`TrackSetup`](super::TrackSetup)).
    pub base0: Pose,
    /// The unit track direction in the world, along which the base moves with the skid.
    pub track_axis: Vector3<f64>,
    /// Work objects / bases overriding the program's.
    pub frames: BTreeMap<String, Pose>,
    /// The work object of declared targets no motion uses.
    pub default_wobj: Option<String>,
    /// The mirror-image robot, when the image is for a robot of the cell with kinematics and the
    /// plane is given in world (a mirror for another robot, and a transfer's mirror).
    pub image: Option<ImageRobot>,
}

/// The robot a mirror image is for: its arm and where its base stands on its track. With a
/// plane in world, the image of a target is a place in the cell; this robot reaches it from its
/// own base at the mapped skid (`MirrorSettings::skid_map`), `B_to(s')`, which is the mirror
/// image of the other's only as far as the cell is symmetric.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageRobot {
    /// Its name in the cell, for messages.
    pub name: String,
    /// Its arm, with the cell's tools on its flange.
    pub arm: Arm,
    /// `B_0` of its track.
    pub base0: Pose,
    /// Its track's unit direction in world.
    pub track_axis: Vector3<f64>,
}

impl ImageRobot {
    /// The image robot `robot`, if the cell gives it kinematics.
    pub fn of(robot: &super::cell::Robot) -> Option<ImageRobot> {
        Some(ImageRobot {
            name: robot.name.clone(),
            arm: Arm::of(robot)?,
            base0: robot.base0,
            track_axis: robot.track_axis,
        })
    }

    /// `B(s) = Trans(s·a)·B_0`.
    fn base_at(&self, skid: f64) -> Pose {
        Translation3::from(self.track_axis * skid) * self.base0
    }

    /// ` on robot `r2` at skid 3000.0 mm (its flange 1729.3 mm from that robot's base)`: where
    /// a refused image was to be reached, for its message.
    fn where_it_stands(&self, skid: f64, flange: &Pose) -> String {
        format!(
            " on robot `{}` at skid {skid:.1} mm (its flange {:.1} mm from that robot's base)",
            self.name,
            flange.translation.vector.norm()
        )
    }
}

impl MirrorArm {
    /// The arm of `robot`, if the cell gives it kinematics.
    pub fn of(robot: &super::cell::Robot, default_wobj: Option<&str>) -> Option<MirrorArm> {
        Some(MirrorArm {
            arm: Arm::of(robot)?,
            base0: robot.base0,
            track_axis: robot.track_axis,
            frames: robot.frames.clone(),
            default_wobj: default_wobj.map(str::to_owned),
            image: None,
        })
    }

    /// `B(s) = Trans(s·a)·B_0`.
    fn base_at(&self, skid: f64) -> Pose {
        Translation3::from(self.track_axis * skid) * self.base0
    }
}

/// `Sy·F·Sy`: a flange pose in the mirror-image robot's base (see [`MirrorArm`]).
pub fn mirrored_flange(f: &Pose) -> Pose {
    let t = f.translation.vector;
    let q = reflect_rotation(Vector3::y(), &f.rotation, Vector3::y());
    Pose::from_parts(
        Translation3::new(t.x, -t.y, t.z),
        UnitQuaternion::from_quaternion(q),
    )
}

/// Largest distance along its track between the mirror-image robot's base at the mapped skid
/// and the mirror image of the mirrored robot's base, mm (docs/design.md §10). Across the track
/// and in rotation the two bases fall short of mirror images by what the cell is built off
/// (the sample's by 0.86 mm), which the image solved in the other robot's base takes up; along
/// the track the skid map alone places the robot, and a map within 1 mm of the bases' is as
/// good as that. A map farther off stands the robot where the mirror image is not, turning its
/// arm (≈ 0.04° per mm on the bundled arms) to reach the image: not the mirror image.
pub const SKID_MAP_TOLERANCE_MM: f64 = 1.0;

/// The inverse of skid map `(scale, offset)`: `s = (s' − offset)/scale`, the map of a mirror the
/// other way round (`scale` not 0).
pub fn inverse_skid_map((scale, offset): (f64, f64)) -> (f64, f64) {
    (1.0 / scale, -offset / scale)
}

/// A skid map that does not put the mirror-image robot's base where the mirror image of the
/// mirrored robot's stands ([`check_skid_map`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SkidMapMismatch {
    /// The mirrored robot.
    pub from: String,
    /// The mirror-image robot.
    pub to: String,
    /// The map checked, `s' = scale·s + offset`.
    pub map: (f64, f64),
    /// The map the two bases give: at `scale·s + offset` the image robot's base is level, along
    /// its track, with the mirror image of the other's base at `s`.
    pub implied: (f64, f64),
    /// At each end of the mirrored robot's skid range: its skid, the mapped skid and how far
    /// along its track (mm, in the direction of its `track_axis`) the image robot's base
    /// stands there from the mirror image of the other's.
    pub ends: [(f64, f64, f64); 2],
    /// The map's inverse fits where the map does not: it takes the image robot's skids to the
    /// mirrored robot's (it is written for a mirror the other way round).
    pub inverse_fits: bool,
    /// With the plane in each target's work object (`frame_in = "wobj"`), the work object whose
    /// plane the map was checked in.
    pub work_object: Option<String>,
}

impl std::fmt::Display for SkidMapMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let number = super::cell::short_number;
        let map =
            |(scale, offset): (f64, f64)| format!("[{}, {}]", number(scale, 6), number(offset, 3));
        let (to, from) = (&self.to, &self.from);
        let [(s0, t0, e0), (s1, t1, e1)] = self.ends;
        let plane = match &self.work_object {
            Some(w) => format!(" in the plane of work object `{w}`"),
            None => String::new(),
        };
        write!(
            f,
            "skid map {} puts robot `{to}`'s base {e0:.3} mm along its track from the mirror image of robot `{from}`'s{plane} at `{from}`'s skid {s0:.1} (`{to}` at {t0:.1}), and {e1:.3} mm at {s1:.1} (at {t1:.1}): more than {SKID_MAP_TOLERANCE_MM} mm; the bases give {}",
            map(self.map),
            map(self.implied)
        )?;
        if self.inverse_fits {
            write!(
                f,
                "; its inverse {} fits, so {} is a map from robot `{to}`'s skids to robot `{from}`'s",
                map(inverse_skid_map(self.map)),
                map(self.map)
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for SkidMapMismatch {}

/// Whether the skid map of `settings` puts robot `to` at the mirror image of robot `from` along
/// its track, over `from`'s skid range `range` (its track's measured range), within
/// [`SKID_MAP_TOLERANCE_MM`], where the mirror plane has a place in the cell: given in world.
/// With the plane in each target's work object (no `world`) each work object places it
/// ([`work_object_planes`], [`check_skid_map_in`]) and this is `Ok`.
pub fn check_skid_map(
    settings: &MirrorSettings,
    from: &super::cell::Robot,
    to: &super::cell::Robot,
    range: (f64, f64),
) -> Result<(), Box<SkidMapMismatch>> {
    match &settings.world {
        Some(world) => check_skid_map_in(&world.frame, None, settings, from, to, range),
        None => Ok(()),
    }
}

/// [`check_skid_map`] about the mirror plane of `settings` in frame `plane` in world (the
/// plane's own in world, or a work object's `W·M`, named `work_object`).
///
/// The map means: at skid `s` of `from`, `to` stands at `s' = scale·s + offset` as its mirror
/// image (docs/design.md §6, §10). With bases `B(s) = Trans(s·a)·B_0` and the plane's
/// reflection `A`, the image robot's base is level with `A·B_from(s)` at
/// `s'* = a_to·(A·p_from0 − p_to0) + s·(a_to·A·a_from)` (`A` acting on the vector `a_from` as a
/// reflection of directions): a line in `s`, so the map's miss is the largest at the range's
/// ends. Where the map misses and its inverse would not, the mismatch says so.
pub fn check_skid_map_in(
    plane: &Pose,
    work_object: Option<&str>,
    settings: &MirrorSettings,
    from: &super::cell::Robot,
    to: &super::cell::Robot,
    range: (f64, f64),
) -> Result<(), Box<SkidMapMismatch>> {
    let reflection = Reflection::about(plane, settings);
    let axis = to.track_axis;
    let implied = (
        axis.dot(&reflection.vector(&from.track_axis)),
        axis.dot(&(reflection.point(&from.base0.translation.vector) - to.base0.translation.vector)),
    );
    let ends_of = |(scale, offset): (f64, f64)| {
        let end = |s: f64| {
            let mapped = scale * s + offset;
            (s, mapped, mapped - (implied.0 * s + implied.1))
        };
        [end(range.0), end(range.1)]
    };
    let fits =
        |ends: &[(f64, f64, f64); 2]| ends.iter().all(|e| e.2.abs() <= SKID_MAP_TOLERANCE_MM);
    let ends = ends_of(settings.skid_map);
    if fits(&ends) {
        return Ok(());
    }
    Err(Box::new(SkidMapMismatch {
        from: from.name.clone(),
        to: to.name.clone(),
        map: settings.skid_map,
        implied,
        ends,
        inverse_fits: settings.skid_map.0 != 0.0
            && fits(&ends_of(inverse_skid_map(settings.skid_map))),
        work_object: work_object.map(str::to_owned),
    }))
}

/// With the mirror plane in each target's work object (`frame_in = "wobj"`): where the work
/// objects of a program's Cartesian targets place it in the cell ([`work_object_planes`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WorkObjectPlanes {
    /// Each work object that places it, once, and the plane's frame in world, `W·M`.
    pub placed: Vec<(String, Pose)>,
    /// Why the others place it nowhere (the program gives the work object at run time, a unit
    /// moves it…), one message per work object (per target where it has none).
    pub unplaced: Vec<String>,
}

/// [`WorkObjectPlanes`] of `program`, its work objects `W` as `frames` (the mirrored robot's
/// cell entries) override the program's declarations, for [`check_skid_map_in`]. Joint targets
/// have no work object. The plane of the targets in one work object is one plane in the cell,
/// but two work objects (the sample's `wobj_car` is turned by 1°, `wobj0` is world) place it
/// apart: one map need not fit them all.
pub fn work_object_planes(
    program: &Program,
    settings: &MirrorSettings,
    frames: &BTreeMap<String, Pose>,
    default_wobj: Option<&str>,
) -> WorkObjectPlanes {
    let mut out = WorkObjectPlanes::default();
    let mut seen: Vec<String> = Vec::new();
    for file in &program.files {
        for p in file.positions().filter(|p| p.cartesian.is_some()) {
            let name = match wobj_of(&p, default_wobj, words_of(program)) {
                Ok(name) => name,
                Err(why) => {
                    out.unplaced.push(why.message);
                    continue;
                }
            };
            let key = super::cell::frame_key(&name);
            if seen.contains(&key) {
                continue;
            }
            seen.push(key);
            // With the frames mirrored, a declared work object mirrors in world with its
            // targets, about `M` read in world (`mirror_frame`, `reflection_for`).
            if settings.mirror_frames && declares_work_object_of(program, &p, default_wobj) {
                out.placed.push((name, settings.frame));
                continue;
            }
            match work_object_of(program, Some(file), &p, frames, default_wobj) {
                Ok(w) => out.placed.push((name, w * settings.frame)),
                Err(why) => out.unplaced.push(why.message),
            }
        }
    }
    out
}

/// A mirror plane given in world, and what resolves each target's work object.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldPlane {
    /// The plane's frame in world (its `plane` is reflected).
    pub frame: Pose,
    /// Work objects / bases overriding the program's (lower-case name → pose in world).
    pub frames: BTreeMap<String, Pose>,
    /// The mirror-image robot's own overrides, when it is another robot of the cell
    /// (`transfer`): the mirrored point in world, `A·W·T·Sb`, is written in the work object as
    /// that robot places it, `T' = W_to⁻¹·A·W·T·Sb`.
    pub frames_to: Option<BTreeMap<String, Pose>>,
    /// The work object of declared targets no motion uses.
    pub default_wobj: Option<String>,
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
            skid_axis_to: None,
            mirror_frames: false,
            mirror_joints: false,
            world: None,
            arm: None,
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

/// The geometry of one mirror: the plane (point and unit normal) and the tool axis, and the
/// move from the work object as this robot places it to the same work object as the
/// mirror-image robot places it (identity but for a plane in world between two robots whose
/// cell entries place the work object a little differently).
#[derive(Clone, Copy, Debug)]
pub struct Reflection {
    point: Vector3<f64>,
    normal: Vector3<f64>,
    tool_axis: Vector3<f64>,
    after: Pose,
}

impl Reflection {
    /// The mirror of `settings` in work-object coordinates (`settings.frame` as `M`).
    pub fn new(settings: &MirrorSettings) -> Reflection {
        Reflection::about(&settings.frame, settings)
    }

    /// The mirror about the plane of `frame` (given in the coordinates being mirrored).
    pub fn about(frame: &Pose, settings: &MirrorSettings) -> Reflection {
        Reflection {
            point: frame.translation.vector,
            normal: frame.rotation * unit(settings.plane.normal_axis()),
            tool_axis: unit(settings.tool_flip.index()),
            after: Pose::identity(),
        }
    }

    /// The same mirror, its result then moved by `c` (`W_to⁻¹·W_from`): `T' = c·M·Sa·M⁻¹·T·Sb`.
    pub fn then(self, c: Pose) -> Reflection {
        Reflection { after: c, ..self }
    }

    /// Whether its result is moved after the reflection ([`Reflection::then`]).
    fn moves_after(&self) -> bool {
        self.after.translation.vector != Vector3::zeros() || self.after.rotation.angle() != 0.0
    }

    /// An `Offs` offset (a vector in the work object) mirrored: reflected, then turned as the
    /// work object is between the two robots.
    fn offset(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.after.rotation * self.vector(v)
    }

    /// `Lₙ`: the reflection in the plane through the origin with this one's normal (its
    /// components read in whatever frame it acts in). Mirroring the frames mirrors a work object
    /// or base as `A·F·Lₙ` ([`Reflection::frame`], `A` this reflection); what is given in that
    /// frame then reflects in `Lₙ`, and the chain `A·F·Lₙ·Lₙ·X` is the mirror image `A·F·X`.
    /// (For a plane through the origin, `Lₙ` is the reflection itself.)
    pub fn through_origin(&self) -> Reflection {
        Reflection {
            point: Vector3::zeros(),
            ..*self
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
        reflect_rotation(self.normal, r, right)
    }

    /// `T' = M·Sa·M⁻¹·T·Sb`, with the quaternion the analytic formula gives (sign included).
    pub fn target(&self, t: &Pose) -> (Pose, [f64; 4]) {
        let (p, q) = (
            self.point(&t.translation.vector),
            self.rotation(&t.rotation, self.tool_axis),
        );
        if !self.moves_after() {
            return pose_with_quat(p, q);
        }
        let c = &self.after;
        pose_with_quat(
            c.rotation * p + c.translation.vector,
            c.rotation.quaternion() * q,
        )
    }

    /// A frame in the mirrored space: `A·F·A` (work objects, bases: both sides reflect the
    /// plane, so `uframe'·oframe'·T' = Sa·uframe·oframe·T·Sb`).
    pub fn frame(&self, f: &Pose) -> (Pose, [f64; 4]) {
        pose_with_quat(
            self.point(&f.translation.vector),
            self.rotation(&f.rotation, self.normal),
        )
    }

    /// A tool in the flange of the mirror-image robot: `Sb·tframe·Sb` (the mirrored flange is
    /// the flange reflected in its own flip axis).
    pub fn tool(&self, f: &Pose) -> (Pose, [f64; 4]) {
        pose_with_quat(
            self.tool_vector(&f.translation.vector),
            reflect_rotation(self.tool_axis, &f.rotation, self.tool_axis),
        )
    }
}

/// `Sl·R·Sr` for the reflections with unit normals `left` and `right` (module comment).
fn reflect_rotation(
    left: Vector3<f64>,
    r: &UnitQuaternion<f64>,
    right: Vector3<f64>,
) -> Quaternion<f64> {
    -(Quaternion::from_parts(0.0, left) * r.quaternion() * Quaternion::from_parts(0.0, right))
}

/// The pose and the exact quaternion it came from: the caller keeps the quaternion's sign.
fn pose_with_quat(p: Vector3<f64>, q: Quaternion<f64>) -> (Pose, [f64; 4]) {
    (
        Pose::from_parts(Translation3::from(p), UnitQuaternion::from_quaternion(q)),
        [q.w, q.i, q.j, q.k],
    )
}

/// An edit for a value that may be an exact sign flip: a flip keeps the original decimals
/// (`90` → `-90`), anything else gets the house minimum.
fn flip_or_value_edit(field: &Option<NumField>, new: f64, min_decimals: usize) -> Option<Edit> {
    let old = field.as_ref()?.value();
    let decimals = if new == -old { 0 } else { min_decimals };
    number_edit(field, new, decimals)
}

fn skid_edits(file: &ParsedFile, p: &Position, settings: &MirrorSettings) -> Vec<Edit> {
    let (scale, offset) = settings.skid_map;
    let from = settings.skid_axis;
    let Some(field) = p.extax.get(from) else {
        return Vec::new();
    };
    // A skid not connected (`9E9`) maps to itself; it still changes places below, and the
    // other axis's value with it: the mirror-image robot reads its skid from the other axis.
    let mapped = match p.skid(from) {
        Skid::At(s) => number_edit(field, scale * s + offset, MM_DECIMALS),
        Skid::NotConnected => None,
        Skid::Missing => return Vec::new(),
    };
    let to = match settings.skid_axis_to {
        Some(to) if to != from => to,
        _ => return mapped.into_iter().collect(),
    };
    // Both fields exist: `skid_refusal` refused the target otherwise.
    let (Some(old), Some(Some(new))) = (field, p.extax.get(to)) else {
        return Vec::new();
    };
    let mapped_text = match mapped {
        Some(e) => e.text.to_vec(),
        None => old.span().slice(&file.source).to_vec(),
    };
    vec![
        Edit::new(new.span(), mapped_text),
        Edit::new(old.span(), new.span().slice(&file.source).to_vec()),
    ]
}

/// A skid that has to move to another axis the target does not write.
fn skid_refusal(p: &Position, settings: &MirrorSettings) -> Option<Why> {
    let to = settings.skid_axis_to?;
    if to == settings.skid_axis || !matches!(p.skid(settings.skid_axis), Skid::At(_)) {
        return None;
    }
    if matches!(p.extax.get(to), Some(Some(_))) {
        return None;
    }
    Some(Why::new(
        RefusalKind::SkidMissing,
        format!(
            "{} has no numeric external axis {} to take the mirror-image robot's skid",
            describe(p),
            to + 1
        ),
        "write that axis in the target (9E9 will do)",
    ))
}

/// `mirror` as a rule of the transform driver.
struct MirrorRule<'s> {
    settings: &'s MirrorSettings,
    /// The reflection in the work object (`settings.frame` as `M`).
    own: Reflection,
    stamps: StampReading,
}

impl TargetRule for MirrorRule<'_> {
    type Frame = Reflection;

    fn keeps(&self, role: NonPositionRole) -> bool {
        matches!(role, NonPositionRole::Tolerance | NonPositionRole::Found)
    }

    /// A mirror of a file a `mirror` stamped is the way back (mirroring twice gives the
    /// program back): the targets the stamp lists were never mirrored and are left as written.
    /// Any other stamp's are refused: they lack what that transform gave the rest.
    fn kept_by_stamp(&self, stamp: &Stamp) -> Option<KeptByStamp> {
        if self.stamps == StampReading::Ignore {
            return None;
        }
        Some(match stamp.command.as_str() {
            "mirror" => KeptByStamp::Leave {
                said: "it is no mirror image, so mirroring the file back leaves it as written"
                    .to_owned(),
                carry: false,
            },
            _ => KeptByStamp::Refuse {
                said: "it lacks what that transform gave the rest of the file, so its mirror image would not be the rest's".to_owned(),
            },
        })
    }

    fn joint(&self, scope: Scope, p: &Position) -> Step {
        // With the arm's kinematics the mirror image is computed, not guessed: no need to ask.
        if !self.settings.mirror_joints && self.settings.arm.is_none() {
            return Err(Why::new(
                RefusalKind::JointTarget,
                format!("{} is a joint target: it is not mirrored", describe(p)),
                "mirror joint targets too (axes 1, 4 and 6 negated)",
            )
            .with_remedy(Remedy::MirrorJoints)
            .at(scope.file, p));
        }
        // The flange's move is the size of the change; without the arm's kinematics it is
        // not known, and the axes are only negated: the largest axis change (2·|θ|) stands
        // for it, said as such, never as a move of 0 mm.
        let (mut edits, (mm, deg), axes_deg): (Vec<Edit>, _, _) = match &self.settings.arm {
            None => {
                let flipped = [0, 3, 5].iter().filter_map(|&i| {
                    let f = p.joints.get(i)?;
                    Some((f, f.as_ref()?.value()))
                });
                let largest = flipped
                    .clone()
                    .map(|(_, v)| 2.0 * v.abs())
                    .fold(0.0, f64::max);
                (
                    flipped
                        .filter_map(|(f, v)| flip_or_value_edit(f, -v, 0))
                        .collect(),
                    (0.0, 0.0),
                    Some(largest),
                )
            }
            Some(m) => {
                let (edits, size) =
                    mirror_joints(self.settings, m, p).map_err(|why| why.at(scope.file, p))?;
                (edits, size, None)
            }
        };
        if let Some(why) = skid_refusal(p, self.settings) {
            return Err(why.at(scope.file, p));
        }
        edits.extend(skid_edits(scope.file, p, self.settings));
        let change = TargetChange {
            mm,
            deg,
            skid: None,
            name: p.name.clone(),
            line: p.line,
            uncertainty_mm: None,
            axes_deg,
        };
        Ok(Some((edits, change)))
    }

    fn refusal(&self, scope: Scope, p: &Position) -> Option<Why> {
        // A plane given in the work object mirrors a target used with two work objects the
        // same way in both; a plane in world does not.
        let common = common_refusal(scope.file, p)
            .filter(|w| w.kind != RefusalKind::TwoWorkObjects || self.settings.world.is_some())
            // (A tool the program gives another value is mirrored in its declaration and in
            // the assignment alike: a motion with either value reaches the image.)
            .or_else(|| stationary_tool(scope.program, scope.file, p));
        if common.is_some() || self.settings.arm.is_none() {
            return common;
        }
        self.ik_config(scope, p).err()
    }

    fn skid(&self, _scope: Scope, p: &Position) -> Result<Option<f64>, Why> {
        if let Some(why) = skid_refusal(p, self.settings) {
            return Err(why);
        }
        Ok(match p.skid(self.settings.skid_axis) {
            Skid::At(s) => Some(s),
            _ => None,
        })
    }

    fn frame(&self, scope: Scope, p: &Position) -> Result<Reflection, Why> {
        reflection_for(scope.program, Some(scope.file), p, self.settings, &self.own)
    }

    fn new_pose(
        &self,
        _p: &Position,
        refl: &Reflection,
        _skid: Option<f64>,
        t: &Pose,
    ) -> Result<NewPose, Why> {
        let (new, expected) = refl.target(t);
        Ok(NewPose {
            pose: new,
            hint: OrientationHint::Expected(expected),
            undo: None,
        })
    }

    fn more_edits(&self, scope: Scope, p: &Position) -> Vec<Edit> {
        let mut edits = Vec::new();
        if self.settings.config == ConfigRule::Mirror {
            match self.settings.arm.as_ref().map(|_| self.ik_config(scope, p)) {
                // `refusal` has checked the target: the configuration is IK's.
                Some(Ok(Some(c))) => edits.extend(config_edits(&p.config, &c)),
                _ => edits.extend(scope.file.language.dialect().mirror_config(&p.config)),
            }
        }
        edits.extend(skid_edits(scope.file, p, self.settings));
        edits
    }

    fn offset(&self, scope: Scope, call: &OffsetCall) -> Result<Vec<Edit>, Box<Refusal>> {
        mirror_offset(scope, self.settings, &self.own, call)
    }

    fn declaration(&self, _scope: Scope, decl: &FrameDecl) -> Vec<Edit> {
        // (`_scope` gives the source the tool's load is read from.)
        if self.settings.mirror_frames {
            let mut edits = mirror_frame(decl, self.settings, &self.own);
            if decl.kind == FrameKind::Tool {
                edits.extend(mirror_tool_load(&_scope.file.source, decl, &self.own));
            }
            edits
        } else {
            Vec::new()
        }
    }
}

impl MirrorRule<'_> {
    /// The tool `name` on the image robot's flange: its cell entry, else the program's
    /// declaration as the image's program has it (mirrored with `mirror_frames`).
    fn image_tool(&self, scope: Scope, image: &ImageRobot, name: &str) -> Result<Pose, Why> {
        let pose =
            resolve_tool(scope.program, Some(scope.file), &image.arm.tools, name).map_err(|e| {
                Why::new(
                    RefusalKind::Reach,
                    format!(
                        "its mirror image on robot `{}` cannot be checked: {}",
                        image.name, e.message
                    ),
                    e.hint,
                )
            })?;
        let from_cell = image.arm.tools.contains_key(&super::cell::frame_key(name));
        Ok(match self.settings.mirror_frames && !from_cell {
            true => self.own.tool(&pose).0,
            false => pose,
        })
    }

    /// The configuration inverse kinematics finds for the mirrored target (`None` when the
    /// target writes none), or why it is refused: the target does not reach as written, or its
    /// mirror image is out of reach within the limits.
    fn ik_config(&self, scope: Scope, p: &Position) -> Result<Option<ConfigValue>, Why> {
        let Some(m) = &self.settings.arm else {
            return Ok(None);
        };
        let Some(t) = p.cartesian.as_ref().and_then(|c| c.pose()) else {
            return Ok(None);
        };
        let written = ConfigValue::written(&p.config);
        let what = describe(p);
        let skid = skid_of(p, self.settings.skid_axis, || {
            format!("{what} has no skid position: its joints cannot be checked")
        })?;
        let w = work_object_of(
            scope.program,
            Some(scope.file),
            p,
            &m.frames,
            m.default_wobj.as_deref(),
        )?;
        let tools = m.arm.tools(scope.program, scope.file, p)?;
        let language = scope.file.language;
        // With the image robot and a plane in world, the image of the TCP is a place in the
        // cell (`A·W·T·Sb`), which that robot reaches from its own base at the mapped skid.
        let image = match (&m.image, &self.settings.world) {
            (Some(image), Some(world)) => {
                let (scale, offset) = self.settings.skid_map;
                let tcp = Reflection::about(&world.frame, self.settings)
                    .target(&(w * t))
                    .0;
                Some((image, scale * skid + offset, tcp))
            }
            _ => None,
        };
        let kin = image.map_or(&m.arm.kinematics, |(i, _, _)| &i.arm.kinematics);
        // Each tool puts the flange elsewhere, so each gives the mirror image its own
        // configuration; the one target holds one.
        let mut found: Option<(&str, ConfigValue)> = None;
        for (tool, name) in tools.iter().zip(p.usage.tools()) {
            let flange = m.base_at(skid).inverse() * w * t * tool.inverse();
            let before = m
                .arm
                .joints_before(p, &flange, language)
                .map_err(|why| with_tool(why, p, name))?;
            let (mirrored, on) = match image {
                None => (mirrored_flange(&flange), String::new()),
                Some((image, skid_to, tcp)) => {
                    let tool = self
                        .image_tool(scope, image, name)
                        .map_err(|why| with_tool(why, p, name))?;
                    let flange = image.base_at(skid_to).inverse() * tcp * tool.inverse();
                    let on = image.where_it_stands(skid_to, &flange);
                    (flange, on)
                }
            };
            let solved = match mirror_config_by_ik(kin, &mirrored, &before, language) {
                Ok((_, solved)) => solved,
                Err(refused) => {
                    let message = match &refused.why {
                        KinematicRefusal::Unreachable => format!(
                            "{what}: its mirror image is out of reach{on} within the limits: joints before {}, after none",
                            fmt_joints(&before)
                        ),
                        why => format!(
                            "{what}: its mirror image{on}: {why}: joints before {}, of the image {}, after {}",
                            fmt_joints(&before),
                            fmt_joints(&mirrored_joints(&before)),
                            refused.after_text()
                        ),
                    };
                    let hint = image_hint(
                        &refused.why,
                        "check the mirror plane, the skid map and the mirror-image robot's cell",
                    );
                    return Err(with_tool(
                        Why::new(RefusalKind::Reach, message, hint),
                        p,
                        name,
                    ));
                }
            };
            // KUKA programs may write only one of Status and Turn: keep to what is written.
            let kept = match (&written, solved) {
                (
                    Some(ConfigValue::StatusTurn { status, turn }),
                    ConfigValue::StatusTurn { status: s, turn: t },
                ) => ConfigValue::StatusTurn {
                    status: status.and(s),
                    turn: turn.and(t),
                },
                (_, solved) => solved,
            };
            // The configuration written must reach the image from the mirror image of the
            // joints before without a swing (the wrist singularity) or a turn, on the robot
            // that moves to it: the image robot in its own base where there is one.
            if written.is_some() {
                let arm = image.map_or(&m.arm, |(i, _, _)| &i.arm);
                arm.check_from(p, &mirrored_joints(&before), &mirrored, Some(&kept))
                    .map_err(|why| with_tool(why, p, name))?;
            }
            match &found {
                None => found = Some((name, kept)),
                Some((first, c)) if *c != kept && written.is_some() => {
                    return Err(Why::new(
                        RefusalKind::Reach,
                        format!(
                            "{what} is used with tools `{first}` and `{name}`, whose mirror images take configurations {c} and {kept}: one target cannot hold both"
                        ),
                        "use a target for each tool",
                    ));
                }
                Some(_) => {}
            }
        }
        Ok(written.and(found.map(|(_, c)| c)))
    }
}

/// The skid position of `p`, or the refusal `message` says why one is needed.
fn skid_of(p: &Position, axis: usize, message: impl FnOnce() -> String) -> Result<f64, Why> {
    match p.skid(axis) {
        Skid::At(s) => Ok(s),
        _ => Err(Why::new(
            RefusalKind::SkidMissing,
            message(),
            "write the skid position into the target",
        )),
    }
}

/// The flange of joint target `p`'s mirror image (joints `j` on `m`'s arm), in the base of the
/// robot it is for, with that robot's kinematics and where it stands (for a refusal to say).
/// For the image robot with the plane in world: `B_to(s')⁻¹·A·B(s)·FK(J)·Sb`, the mirror image
/// in world of this robot's flange, so that the joints found for it take up what the two bases
/// fall short of mirror images (before, the image was the rule `(−θ1, θ2, θ3, −θ4, θ5, −θ6)`
/// alone: on the sample cell a joint target and its Cartesian twin, one pose on robot A, ended
/// 0.85 mm apart on robot B). Otherwise the robot's own mirror image (see [`MirrorArm`]):
/// `Sy·FK(J)·Sy`.
pub(crate) fn joint_image_flange<'m>(
    settings: &MirrorSettings,
    m: &'m MirrorArm,
    p: &Position,
    j: &Joints,
) -> Result<(Pose, &'m crate::kinematics::Kinematics, String), Why> {
    let (Some(image), Some(world)) = (&m.image, &settings.world) else {
        let kin = &m.arm.kinematics;
        return Ok((mirrored_flange(&kin.forward(j)), kin, String::new()));
    };
    let what = describe(p);
    let skid = skid_of(p, settings.skid_axis, || {
        format!(
            "{what} has no skid position: where robot `{}` stands to reach its mirror image is not known",
            image.name
        )
    })?;
    let (scale, offset) = settings.skid_map;
    let skid_to = scale * skid + offset;
    let flange = m.base_at(skid) * m.arm.kinematics.forward(j);
    let mirrored = Reflection::about(&world.frame, settings).target(&flange).0;
    let target = image.base_at(skid_to).inverse() * mirrored;
    let on = image.where_it_stands(skid_to, &target);
    Ok((target, &image.arm.kinematics, on))
}

/// A joint target mirrored through kinematics: `J'` with its flange at
/// [`joint_image_flange`], found as the rule's image moved by what it falls short of it (so the
/// arm's branch is the rule's, and a wrist at its singularity that would swing is refused as a
/// track correction's would be). With the edits, the flange's move ([`flange_move`]), each
/// flange in its own robot's base as the joints are written.
fn mirror_joints(
    settings: &MirrorSettings,
    m: &MirrorArm,
    p: &Position,
) -> Result<(Vec<Edit>, (f64, f64)), Why> {
    let j = m.arm.joints_of(p)?;
    let (target, kin, on) = joint_image_flange(settings, m, p, &j)?;
    let hint = match (&m.image, &settings.world) {
        (Some(_), Some(_)) => {
            "check the mirror plane, the skid map and the mirror-image robot's cell; or re-teach the target"
        }
        _ => "check the mirror-image robot's kinematics; or re-teach the target",
    };
    let (edits, new) = image_joint_edits(kin, p, &j, &target, &on, hint)?;
    Ok((edits, flange_move(&m.arm.kinematics, &j, kin, &new)))
}

/// The edits of joint target `p` (joints `j`) mirrored to `J'` whose flange is `target`, in the
/// base of the robot it is for (kinematics `kin`): the rule's image
/// `(−θ1, θ2, θ3, −θ4, θ5, −θ6)` moved by what it falls short of `target`, as a track correction
/// moves a joint target ([`joint_target_correction`](crate::kinematics::joint_target_correction)
/// with the change `target·FK(rule)⁻¹`, the identity where the rule is exact): the rule's arm and
/// wrist, each axis by its least turn. Refused, saying so with `on` (where the image is) and
/// `hint`: an image outside the limits, with the angle it needs (before, the solution within
/// the limits nearest to the rule's was written: an axis 1 limited to [−170°, 185°] took the
/// image of 178° as the arm behind itself, `[2, −27.3, −162, …]`, and an axis 4 limited to
/// [−200°, 300°] the image of 250° as the flipped wrist), a swing (the wrist singularity), or
/// no solution in the branch. Where `J'` agrees with the rule to 1e-9° the rule's text is
/// written (a flip keeps the literal's decimals). With the edits, `J'`.
fn image_joint_edits(
    kin: &crate::kinematics::Kinematics,
    p: &Position,
    j: &Joints,
    target: &Pose,
    on: &str,
    hint: &str,
) -> Result<(Vec<Edit>, Joints), Why> {
    let rule = mirrored_joints(j);
    let change = target * kin.forward(&rule).inverse();
    let steps = super::kinematic_policy::written_steps(p);
    let new = crate::kinematics::joint_target_correction(kin, &rule, &change, &steps).map_err(
        |refused| {
            Why::new(
                RefusalKind::Reach,
                format!(
                    "{}: its mirror image{on}: {}: joints before {}, of the image {}, after {}",
                    describe(p),
                    refused.why,
                    fmt_joints(j),
                    fmt_joints(&rule),
                    refused.after_text()
                ),
                image_hint(&refused.why, hint),
            )
        },
    )?;
    let edits = p
        .joints
        .iter()
        .zip(new)
        .zip(rule)
        .filter_map(|((f, v), r)| match (v - r).abs() < 1e-9 {
            true => flip_or_value_edit(f, r, 0),
            false => number_edit(f, v, DEG_DECIMALS),
        })
        .collect();
    Ok((edits, new))
}

/// The hint for a mirror image the robot it is for cannot take: an axis outside its limits
/// names the axis; anything else gets `otherwise`.
fn image_hint(why: &KinematicRefusal, otherwise: &str) -> String {
    match why {
        KinematicRefusal::OutsideLimit { axis, limits, .. } => format!(
            "the mirror-image robot cannot take the mirror-image posture: re-teach the target so that its mirror image lies inside the range of axis {axis} ([{}, {}])",
            limits[0], limits[1]
        ),
        _ => otherwise.to_owned(),
    }
}

/// `mirror` every target (and, if asked, frame) of `program` (reading the files' provenance
/// stamps for the targets they list as kept as written: docs/design.md §4).
pub fn mirror(program: &Program, settings: &MirrorSettings) -> ProgramEdits {
    mirror_reading(program, settings, StampReading::Read)
}

/// [`mirror`], reading the files' stamps or not.
pub(crate) fn mirror_reading(
    program: &Program,
    settings: &MirrorSettings,
    stamps: StampReading,
) -> ProgramEdits {
    apply_rule(
        program,
        &MirrorRule {
            settings,
            own: Reflection::new(settings),
            stamps,
        },
    )
}

/// The reflection for one target: the settings' own, or the world plane taken into the
/// target's work object.
pub(crate) fn reflection_for(
    program: &Program,
    own_file: Option<&ParsedFile>,
    p: &Position,
    settings: &MirrorSettings,
    own: &Reflection,
) -> Result<Reflection, Why> {
    // With `--mirror-frames` a declared work object mirrors too (`mirror_frame`), as
    // `A·W·Lₙ`: the target then reflects in `Lₙ`, so that `W'·T' = A·W·Lₙ·Lₙ·T·Sb = A·W·T·Sb`.
    // In `W⁻¹·P`, or in an `A` off the origin, it would be mirrored a second time.
    let declared = |default| settings.mirror_frames && declares_work_object_of(program, p, default);
    let Some(world) = &settings.world else {
        return Ok(if declared(None) {
            own.through_origin()
        } else {
            *own
        });
    };
    let w = work_object_of(
        program,
        own_file,
        p,
        &world.frames,
        world.default_wobj.as_deref(),
    )?;
    if declared(world.default_wobj.as_deref()) {
        return Ok(Reflection::about(&world.frame, settings).through_origin());
    }
    let reflection = Reflection::about(&(w.inverse() * world.frame), settings);
    let Some(to) = &world.frames_to else {
        return Ok(reflection);
    };
    let w_to = work_object_of(program, own_file, p, to, world.default_wobj.as_deref())?;
    Ok(reflection.then(w_to.inverse() * w))
}

/// Whether the program declares the work object (base) target `p` is used in: mirroring the frames
/// then mirrors that declaration.
fn declares_work_object_of(program: &Program, p: &Position, default: Option<&str>) -> bool {
    let Ok(name) = wobj_of(p, default, words_of(program)) else {
        return false;
    };
    program.files.iter().flat_map(|f| &f.frames).any(|d| {
        matches!(d.kind, FrameKind::WorkObject | FrameKind::Base)
            && d.name.eq_ignore_ascii_case(&name)
    })
}

/// The edits of one `Offs`/`RelTool` call: its offsets reflected, or why not.
fn mirror_offset(
    scope: Scope,
    settings: &MirrorSettings,
    own: &Reflection,
    call: &OffsetCall,
) -> Result<Vec<Edit>, Box<Refusal>> {
    let (program, file) = (scope.program, scope.file);
    let mut edits = Vec::new();
    {
        // Offs offsets are in the work object of the target they offset: with a plane in world
        // that target's work object decides the plane.
        let refl = match (&settings.world, call.kind) {
            (Some(_), OffsetKind::Offs) => {
                let targets = offset_bases(program, call, crate::position::Reading::Whole);
                let reflections: Vec<_> = targets
                    .iter()
                    .map(|(f, p)| reflection_for(program, Some(f), p, settings, own))
                    .collect();
                let resolved = match reflections.first() {
                    None => Err(Why::new(
                        RefusalKind::UnresolvedWorkObject,
                        format!(
                            "`{}` is not a declared target: its work object is unknown",
                            call.target
                        ),
                        "offset a declared target, or mirror with the plane in the work object",
                    )),
                    Some(Err(e)) => Err(e.clone()),
                    Some(Ok(first)) => {
                        // Array elements share one declaration; they must share one plane too.
                        let same = reflections.iter().all(|r| match r {
                            Ok(r) => {
                                (r.normal - first.normal).norm() < 1e-12
                                    && (r.point - first.point).norm() < 1e-9
                                    && (r.after.inverse() * first.after).rotation.angle() < 1e-12
                                    && (r.after.translation.vector - first.after.translation.vector)
                                        .norm()
                                        < 1e-9
                            }
                            Err(_) => false,
                        });
                        if same {
                            Ok(*first)
                        } else {
                            Err(Why::new(
                                RefusalKind::TwoWorkObjects,
                                format!(
                                    "the elements of `{}` lie in different work objects",
                                    call.target
                                ),
                                "offset one target per work object",
                            ))
                        }
                    }
                };
                match resolved {
                    Ok(r) => r,
                    Err(why) => {
                        let message = format!("Offs({}, …): {}", call.target, why.message);
                        return Err(Why { message, ..why }.at_call(file, call));
                    }
                }
            }
            _ => *own,
        };
        let (name, frame) = match call.kind {
            OffsetKind::Offs => ("Offs", "object"),
            OffsetKind::RelTool => ("RelTool", "tool"),
        };
        // A reflection `I - 2nnᵀ` reads component j only where n_j ≠ 0, and leaves it alone
        // otherwise: an expression there (Offs(p, 0, 0, zUp)) is fine, anywhere else it is not.
        let axis = match call.kind {
            OffsetKind::Offs => refl.normal,
            OffsetKind::RelTool => refl.tool_axis,
        };
        // A RelTool rotation changes sign unless it turns about the flipped tool axis.
        let rot_switch = ["\\Rx", "\\Ry", "\\Rz"]
            .into_iter()
            .zip(&call.rot_expression)
            .zip(refl.tool_axis.iter())
            .find(|((_, expression), n)| {
                call.kind == OffsetKind::RelTool && **expression && **n == 0.0
            })
            .map(|((switch, _), _)| switch);
        // Turned after the reflection, every component of an `Offs` offset changes.
        let turned = call.kind == OffsetKind::Offs && refl.after.rotation.angle() != 0.0;
        let offset_blocked = call
            .delta
            .iter()
            .zip(axis.iter())
            .any(|(f, n)| f.is_none() && (turned || n.abs() > 1e-12));
        let why = match (rot_switch, offset_blocked) {
            (Some(switch), _) => Some((
                format!(
                    "{name}({}, …): its rotation {switch} is not a number and the mirror changes its sign",
                    call.target
                ),
                format!("write {switch} as a number (or negate the expression by hand)"),
            )),
            (None, true) => Some((
                format!(
                    "{name}({}, …) has an offset that is not a number where the mirror changes it",
                    call.target
                ),
                format!("write the {frame}-frame offsets as numbers"),
            )),
            (None, false) => None,
        };
        if let Some((message, hint)) = why {
            return Err(Why::new(RefusalKind::Expression, message, hint).at_call(file, call));
        }
        let d = call.delta.map(|f| f.map_or(0.0, |f| f.value()));
        let v = Vector3::new(d[0], d[1], d[2]);
        let new = match call.kind {
            OffsetKind::Offs => refl.offset(&v),
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
                if let Some(v) = f.as_ref().map(NumField::value)
                    && flip
                {
                    edits.extend(flip_or_value_edit(f, -v, 0));
                }
            }
        }
    }
    Ok(edits)
}

fn frame_field_edits(fields: &CartesianFields, new: &Pose, expected: [f64; 4]) -> Vec<Edit> {
    pose_edits(fields, new, OrientationHint::Expected(expected))
}

/// A numeric literal inside a declaration, as found by [`numbers_after`].
struct Lit {
    span: crate::syntax::Span,
    lit: crate::syntax::NumLit,
}

/// The numeric literals of `src[from..to]`, in order (separators `[ ] , ` and blanks only: any
/// other text ends the scan, so only a plain literal is read).
fn numbers_after(src: &[u8], from: usize, to: usize) -> Vec<Lit> {
    let mut out = Vec::new();
    let mut i = from;
    while i < to {
        match src[i] {
            b'[' | b']' | b',' | b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            _ => {
                let start = i;
                while i < to && !matches!(src[i], b'[' | b']' | b',' | b' ' | b'\t' | b'\r' | b'\n')
                {
                    i += 1;
                }
                match crate::syntax::NumLit::parse(&src[start..i]) {
                    Some(lit) => out.push(Lit {
                        span: crate::syntax::Span::new(start, i),
                        lit,
                    }),
                    None => break,
                }
            }
        }
    }
    out
}

/// The tool's load (RAPID `tooldata` `tload = [mass, [cog x, y, z], [aom q1..q4], ix, iy, iz]`,
/// after the tool frame): its centre of gravity and axes of moment are in the flange frame and
/// mirror with `Sb`, like the tool frame.
fn mirror_tool_load(src: &[u8], d: &FrameDecl, own: &Reflection) -> Vec<Edit> {
    let Some(frame) = &d.frame else {
        return Vec::new();
    };
    let Some(crate::position::Orientation::Quaternion(q)) = &frame.orient else {
        return Vec::new();
    };
    let Some(Some(last)) = q.last() else {
        return Vec::new();
    };
    let nums = numbers_after(src, last.span().end, d.span.end.min(src.len()));
    // mass, cog x y z, aom q1..q4 (ix, iy, iz are moments about the aom axes: kept).
    if nums.len() < 8 {
        return Vec::new();
    }
    let mut edits = Vec::new();
    let cog = Vector3::new(
        nums[1].lit.value(),
        nums[2].lit.value(),
        nums[3].lit.value(),
    );
    let new = own.tool_vector(&cog);
    for (n, v) in nums[1..4].iter().zip([new.x, new.y, new.z]) {
        if let Some(text) = n.lit.rewrite(v, MM_DECIMALS) {
            edits.push(Edit::new(n.span, text));
        }
    }
    let aom = [4, 5, 6, 7].map(|i| nums[i].lit.value());
    if let Some(r) = crate::geometry::abb_quat(aom) {
        let m = reflect_rotation(own.tool_axis, &r, own.tool_axis);
        let m = [m.w, m.i, m.j, m.k];
        // The sign nearest the written one.
        let dot: f64 = m.iter().zip(aom).map(|(a, b)| a * b).sum();
        let m = if dot < 0.0 { m.map(|v| -v) } else { m };
        for (n, v) in nums[4..8].iter().zip(m) {
            if let Some(text) = n.lit.rewrite(v, QUAT_DECIMALS) {
                edits.push(Edit::new(n.span, text));
            }
        }
    }
    edits
}

/// The edits of one work object, base or tool declaration.
fn mirror_frame(d: &FrameDecl, settings: &MirrorSettings, own: &Reflection) -> Vec<Edit> {
    let mut edits = Vec::new();
    match d.kind {
        FrameKind::WorkObject | FrameKind::Base => {
            // The user frame (in world) reflects in the plane, `A·U·Lₙ`, and the object frame
            // (in the user frame) in `Lₙ`, `Lₙ·O·Lₙ`, so that the targets in it reflect in
            // `Lₙ` as well (`reflection_for`).
            let for_uframe = match &settings.world {
                Some(w) => Reflection::about(&w.frame, settings),
                None => *own,
            };
            let for_oframe = for_uframe.through_origin();
            for (fields, refl) in [(&d.frame, for_uframe), (&d.oframe, for_oframe)] {
                let Some(fields) = fields else { continue };
                if let Some(f) = fields.pose() {
                    let (new, q) = refl.frame(&f);
                    edits.extend(frame_field_edits(fields, &new, q));
                }
            }
        }
        FrameKind::Tool => {
            if let Some(fields) = &d.frame
                && let Some(f) = fields.pose()
            {
                let (new, q) = own.tool(&f);
                edits.extend(frame_field_edits(fields, &new, q));
            }
        }
    }
    edits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{abb_quat, kuka_abc, pose_xyz_deg};
    use crate::position::{Config, Orientation};
    use crate::transform::edits::apply;
    use crate::transform::rewrite::wijk;
    use crate::transform::test_support::{krl, rapid};
    use proptest::prelude::*;

    const NC: &str = "[9E9,9E9,9E9,9E9,9E9,9E9]";

    fn mirrored_text(p: &Program, s: &MirrorSettings) -> String {
        let out = apply(p, mirror(p, s)).unwrap();
        String::from_utf8(out.files[0].output.clone()).unwrap()
    }

    fn quat_of(p: &Position) -> [f64; 4] {
        match &p.cartesian.as_ref().unwrap().orient {
            Some(Orientation::Quaternion(q)) => (*q).map(|f| f.unwrap().value()),
            _ => panic!("not a quaternion"),
        }
    }

    fn same_up_to_sign(a: [f64; 4], b: [f64; 4], tol: f64) -> bool {
        let plus = a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        let minus = a.iter().zip(b).all(|(x, y)| (x + y).abs() <= tol);
        plus || minus
    }

    #[test]
    fn skid_moves_to_the_mirror_image_robots_axis_and_back() {
        let src = "[[100,0,300],[1,0,0,0],[0,0,0,0],[1500.5,9E9,9E9,9E9,9E9,9E9]]\n";
        let there = MirrorSettings {
            skid_axis_to: Some(1),
            ..MirrorSettings::default()
        };
        let text = mirrored_text(&rapid(src, "wobj0"), &there);
        assert!(text.ends_with("[9E9,1500.5,9E9,9E9,9E9,9E9]]\n"), "{text}");
        let back = MirrorSettings {
            skid_axis: 1,
            skid_axis_to: Some(0),
            ..MirrorSettings::default()
        };
        assert_eq!(mirrored_text(&rapid(&text, "wobj0"), &back), src);
        let mapped = MirrorSettings {
            skid_map: (1.0, 250.0),
            ..there
        };
        let text = mirrored_text(&rapid(src, "wobj0"), &mapped);
        assert!(
            text.ends_with("[9E9,1750.500,9E9,9E9,9E9,9E9]]\n"),
            "{text}"
        );
        // A skid not connected changes places too: the other axis's value (a positioner's)
        // must not become the mirror-image robot's skid.
        let loose = "[[100,0,300],[1,0,0,0],[0,0,0,0],[9E+09,100,9E9,9E9,9E9,9E9]]\n";
        let text = mirrored_text(&rapid(loose, "wobj0"), &mapped);
        assert!(text.ends_with("[100,9E+09,9E9,9E9,9E9,9E9]]\n"), "{text}");
        assert_eq!(mirrored_text(&rapid(&text, "wobj0"), &back), loose);
    }

    #[test]
    fn a_target_without_the_other_skid_axis_is_refused() {
        let p = krl("{X 1,Y 2,Z 3,A 0,B 0,C 0,S 6,T 27,E1 800}\n", "$WORLD");
        let settings = MirrorSettings {
            skid_axis_to: Some(1),
            ..MirrorSettings::default()
        };
        let edits = mirror(&p, &settings);
        let r = &edits.files[0].refusals;
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].kind, RefusalKind::SkidMissing);
        assert!(r[0].message.contains("external axis 2"), "{}", r[0].message);
        assert!(edits.files[0].edits.is_empty());
    }

    /// `../shared/reference/README.md`: RobotStudio's mirror in the work object's xz plane.
    // The literals are RobotStudio's printed numbers, not approximations of 1/√2 we chose.
    #[allow(clippy::approx_constant)]
    #[test]
    fn reproduces_robotstudio_mirror_numbers() {
        let src = format!(
            "[[298.36,100.97,250.58],[0.000000269,0.707107,0.707107,-0.000000268],[0,-1,0,0],{NC}]\n\
             [[0,0,0],[0,0.707106781,0.707106781,0],[-1,0,-1,0],{NC}]\n"
        );
        let text = mirrored_text(&rapid(&src, "wobj0"), &MirrorSettings::default());
        let m = rapid(&text, "wobj0");
        let (t50, t10) = (
            &m.files[0].position(0).unwrap(),
            &m.files[0].position(1).unwrap(),
        );
        let trans = t50.cartesian.as_ref().unwrap().translation().unwrap();
        assert_eq!(trans, [298.36, -100.97, 250.58]);
        // Quaternions up to the sign of the whole, to the 6 decimals RobotStudio printed.
        assert!(same_up_to_sign(
            quat_of(t50),
            [2.69e-7, -0.707107, 0.707107, 2.68e-7],
            1e-6
        ));
        assert!(same_up_to_sign(
            quat_of(t10),
            [0.0, -0.707106781, 0.707106781, 0.0],
            1e-9
        ));
        let cf = |p: &Position| match &p.config {
            Config::Quadrants(c) => (*c).map(|f| f.unwrap().value()),
            _ => panic!(),
        };
        assert_eq!(cf(t50), [-1.0, 0.0, -1.0, 0.0]);
        assert_eq!(cf(t10), [0.0, -1.0, 0.0, 0.0]);
        // Unchanged literals keep their text; 9E9 stays 9E9.
        assert_eq!(
            text.lines().next().unwrap(),
            "[[298.36,-100.970,250.58],[0.000000269,-0.707107,0.707107,0.000000268],[-1,0,-1,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
        );
    }

    #[test]
    fn kuka_xz_mirror_is_minus_a_b_minus_c_with_turn_toggled() {
        let src = "{X 1200.5,Y 310.25,Z 845,A 30,B 10,C 170,S 6,T 27,E1 2500}\n";
        let text = mirrored_text(&krl(src, "BASE_DATA[1]"), &MirrorSettings::default());
        assert_eq!(
            text,
            "{X 1200.5,Y -310.250,Z 845,A -30.0000,B 10,C -170.0000,S 6,T 50,E1 2500}\n"
        );
        // The same rule through the rotation, for an arbitrary triple.
        let refl = Reflection::new(&MirrorSettings::default());
        let t = Pose::from_parts(Default::default(), kuka_abc(-47.3, 61.2, -118.9));
        let (m, _) = refl.target(&t);
        let expected = kuka_abc(47.3, 61.2, 118.9);
        assert!(m.rotation.angle_to(&expected) < 1e-12);
    }

    /// A robot of a cell on a straight track, for [`check_skid_map`].
    fn robot_on_track(name: &str, base0: Pose, track_axis: Vector3<f64>) -> super::super::Robot {
        super::super::Robot {
            name: name.to_owned(),
            profile: Default::default(),
            profile_span: Default::default(),
            base0,
            track_axis,
            skid_axis: 0,
            frames: BTreeMap::new(),
            config_dat: None,
            kinematics: None,
            tools: BTreeMap::new(),
        }
    }

    /// Two robots either side of the plane y = 500 in world, b's track running against a's: a
    /// at skid s stands at x = 100 + s, b at skid s' at x = 8300 − s', so b is a's mirror image
    /// at s' = 8200 − s, the map [-1, 8200]. Within 1 mm along the track a map passes; the
    /// across-track 2 mm (b's base at y = 1002 where a's image is at 1000) is the cell's own.
    #[test]
    fn a_skid_map_is_checked_along_the_image_robots_track_at_the_ends_of_the_range() {
        let a = robot_on_track(
            "a",
            pose_xyz_deg(100.0, 0.0, 0.0, 0.0, 0.0, 90.0),
            Vector3::x(),
        );
        let b = robot_on_track(
            "b",
            pose_xyz_deg(8300.0, 1002.0, 0.0, 0.0, 0.0, -90.0),
            -Vector3::x(),
        );
        let settings = |map| MirrorSettings {
            skid_map: map,
            world: Some(WorldPlane {
                frame: pose_xyz_deg(0.0, 500.0, 0.0, 0.0, 0.0, 0.0),
                frames: BTreeMap::new(),
                frames_to: None,
                default_wobj: None,
            }),
            ..MirrorSettings::default()
        };
        let range = (0.0, 6000.0);
        assert_eq!(
            check_skid_map(&settings((-1.0, 8200.0)), &a, &b, range),
            Ok(())
        );
        assert_eq!(
            check_skid_map(&settings((-1.0, 8201.0)), &a, &b, range),
            Ok(())
        );
        let off = check_skid_map(&settings((-1.0, 8201.5)), &a, &b, range).unwrap_err();
        assert_eq!((off.from.as_str(), off.to.as_str()), ("a", "b"));
        let implied = off.implied;
        assert!(
            (implied.0 + 1.0).abs() < 1e-12 && (implied.1 - 8200.0).abs() < 1e-9,
            "{implied:?}"
        );
        // The tracks taken as running the same way: 8200 mm off at skid 0, 3800 the other way
        // at 6000.
        let wrong = check_skid_map(&settings((1.0, 0.0)), &a, &b, range).unwrap_err();
        let [(s0, t0, e0), (s1, t1, e1)] = wrong.ends;
        assert_eq!((s0, t0, s1, t1), (0.0, 0.0, 6000.0, 6000.0));
        assert!(
            (e0 + 8200.0).abs() < 1e-9 && (e1 - 3800.0).abs() < 1e-9,
            "{e0} {e1}"
        );
        assert_eq!(
            wrong.to_string(),
            "skid map [1, 0] puts robot `b`'s base -8200.000 mm along its track from the mirror image of robot `a`'s at `a`'s skid 0.0 (`b` at 0.0), and 3800.000 mm at 6000.0 (at 6000.0): more than 1 mm; the bases give [-1, 8200]"
        );
        // A plane in each target's work object is placed by each work object, and checked in
        // those (`check_skid_map_in`), not here.
        let per_wobj = MirrorSettings {
            world: None,
            ..settings((1.0, 0.0))
        };
        assert_eq!(check_skid_map(&per_wobj, &a, &b, range), Ok(()));
    }

    /// b stands at x = 80 + s' beside a at x = 100 + s (tracks running the same way, either side
    /// of y = 500): b is a's mirror image at s' = s + 20. The map written for the way back,
    /// [1, -20], misses by 40 mm, and its inverse fits: the mismatch says so. In the plane of a
    /// work object turned by 5° about z through (0, 500), a's track mirrors to a direction 10°
    /// off b's: the bases give the scale cos 10°, and the plane is named.
    #[test]
    fn a_skid_map_written_the_other_way_round_is_said_to_fit_inverted() {
        let a = robot_on_track(
            "a",
            pose_xyz_deg(100.0, 0.0, 0.0, 0.0, 0.0, 90.0),
            Vector3::x(),
        );
        let b = robot_on_track(
            "b",
            pose_xyz_deg(80.0, 1000.0, 0.0, 0.0, 0.0, -90.0),
            Vector3::x(),
        );
        let plane = pose_xyz_deg(0.0, 500.0, 0.0, 0.0, 0.0, 0.0);
        let settings = |map| MirrorSettings {
            skid_map: map,
            ..MirrorSettings::default()
        };
        let range = (0.0, 6000.0);
        let check =
            |map, plane: &Pose, wobj| check_skid_map_in(plane, wobj, &settings(map), &a, &b, range);
        assert_eq!(check((1.0, 20.0), &plane, None), Ok(()));
        let back = check((1.0, -20.0), &plane, None).unwrap_err();
        assert!(back.inverse_fits);
        assert_eq!(inverse_skid_map((1.0, -20.0)), (1.0, 20.0));
        assert_eq!(
            back.to_string(),
            "skid map [1, -20] puts robot `b`'s base -40.000 mm along its track from the mirror image of robot `a`'s at `a`'s skid 0.0 (`b` at -20.0), and -40.000 mm at 6000.0 (at 5980.0): more than 1 mm; the bases give [1, 20]; its inverse [1, 20] fits, so [1, -20] is a map from robot `b`'s skids to robot `a`'s"
        );
        // Off both ways: no inverse is offered.
        assert!(!check((1.0, 60.0), &plane, None).unwrap_err().inverse_fits);
        let turned = pose_xyz_deg(0.0, 500.0, 0.0, 0.0, 0.0, 5.0);
        let off = check((1.0, 20.0), &turned, Some("wTurned")).unwrap_err();
        assert!(
            (off.implied.0 - 10f64.to_radians().cos()).abs() < 1e-12,
            "{:?}",
            off.implied
        );
        let text = off.to_string();
        assert!(
            text.contains(
                "from the mirror image of robot `a`'s in the plane of work object `wTurned` at"
            ),
            "{text}"
        );
    }

    #[test]
    fn config_keep_and_skid_map() {
        let src = "[[1,2,3],[1,0,0,0],[0,-1,2,1],[2000,9E9,9E9,9E9,9E9,9E9]]\n";
        let s = MirrorSettings {
            config: ConfigRule::Keep,
            skid_map: (-1.0, 8000.0),
            ..MirrorSettings::default()
        };
        let text = mirrored_text(&rapid(src, "wobj0"), &s);
        assert_eq!(
            text,
            "[[1,-2.000,3],[1,0,0,0],[0,-1,2,1],[6000.000,9E9,9E9,9E9,9E9,9E9]]\n"
        );
    }

    const MODULE: &str = "MODULE m\n  PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1500,-400,600],[0.996195,0,0,0.087156]],[[100,20,0],[0.999848,0,0.017452,0]]];\n  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\n  CONST robtarget p1:=[[310.5,-120.25,80],[0.183013,0.683013,0.683013,-0.183013],[0,-1,2,1],[2500,9E9,9E9,9E9,9E9,9E9]];\n  CONST jointtarget jHome:=[[10,-20,30,40,50,-60],[2500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveAbsJ jHome, v1000, fine, tGun;\n    MoveL Offs(p1,10,-20.5,30), v1000, fine, tGun\\WObj:=wCar;\n    MoveL RelTool(p1,5,6,-7\\Rx:=1\\Ry:=2\\Rz:=3), v1000, fine, tGun\\WObj:=wCar;\n  ENDPROC\nENDMODULE\n";

    /// The pose target `name` of `f` is written with.
    /// The pose of the frame `name` declares in `f`.
    fn frame(f: &ParsedFile, name: &str) -> Pose {
        f.frames
            .iter()
            .find(|d| d.name == name)
            .unwrap()
            .pose()
            .unwrap()
    }

    fn pose_of(f: &ParsedFile, name: &str) -> Pose {
        f.positions()
            .find(|p| p.name.as_deref() == Some(name))
            .unwrap()
            .cartesian
            .as_ref()
            .unwrap()
            .pose()
            .unwrap()
    }

    fn parse(text: &str) -> Program {
        Program {
            files: vec![crate::rapid::parse_file(
                std::path::Path::new("m.mod"),
                text.as_bytes().to_vec(),
            )],
        }
    }

    /// A target the mirror refuses keeps its `Offs` offset as written with it; the offset of a
    /// target it mirrors is mirrored.
    #[test]
    fn a_refused_targets_offset_is_left_as_written() {
        let text = "MODULE m\n\
            VAR robtarget pX:=[[xOff,0,100],[0,1,0,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n\
            CONST robtarget pY:=[[200,50,100],[0,1,0,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n\
            PROC main()\n\
            MoveL Offs(pX,0,100,0), v1000, z10, tool0\\WObj:=wobj0;\n\
            MoveL Offs(pY,0,100,0), v1000, z10, tool0\\WObj:=wobj0;\n\
            ENDPROC\n\
            ENDMODULE\n";
        let p = parse(text);
        let edits = mirror(&p, &MirrorSettings::default());
        let refused: Vec<_> = edits.refusals().map(|r| r.target.clone()).collect();
        assert_eq!(refused, ["pX"]);
        let out = mirrored_text(&p, &MirrorSettings::default());
        assert!(out.contains("Offs(pX,0,100,0)"), "{out}");
        assert!(out.contains("Offs(pY,0,-100,0)"), "{out}");
    }

    /// A frame the program gives its own value again in a routine is mirrored there too, or
    /// the routine would set the old value again when it runs: after the mirror every
    /// assignment still gives its frame's (mirrored) value. With the declaration at the origin
    /// and two assignments of one other value, the first stands for the frame and both are
    /// mirrored alike.
    #[test]
    fn frames_the_program_assigns_are_mirrored_where_they_are_assigned() {
        let wobj =
            "[FALSE,TRUE,\"\",[[1500,-400,600],[0.996195,0,0,0.087156]],[[100,20,0],[1,0,0,0]]]";
        let wobj_digits = "[FALSE,TRUE,\"\",[[1500.00,-400.00,600.0],[0.996195,0,0,0.087156]],[[100,20,0],[1,0,0,0]]]";
        let tool = "[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]]";
        let zero = "[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]]";
        let s = MirrorSettings {
            mirror_frames: true,
            ..MirrorSettings::default()
        };
        let refl = Reflection::new(&s);
        for (decl, first, second, own) in [(wobj, wobj_digits, wobj, 2), (zero, wobj, wobj, 1)] {
            let text = format!(
                "MODULE m\n  PERS wobjdata wCar:={decl};\n  PERS tooldata tGun:={tool};\n  \
                 CONST robtarget p1:=[[310.5,-120.25,80],[0.183013,0.683013,0.683013,-0.183013],[0,-1,2,1],[2500,9E9,9E9,9E9,9E9,9E9]];\n  \
                 PROC main()\n    wCar:={first};\n    tGun:={tool};\n    MoveL p1, v1000, fine, tGun\\WObj:=wCar;\n  ENDPROC\n  \
                 PROC other()\n    wCar:={second};\n  ENDPROC\nENDMODULE\n"
            );
            let p0 = parse(&text);
            let given = |f: &ParsedFile| f.frame_values.iter().filter(|v| v.assigned).count();
            assert_eq!(given(&p0.files[0]), own + 1, "{text}");
            let edits = mirror(&p0, &s);
            assert!(edits.refusals().next().is_none());
            let out = apply(&p0, edits).unwrap();
            let mirrored = String::from_utf8(out.files[0].output.clone()).unwrap();
            let p1 = parse(&mirrored);
            let (f0, f1) = (&p0.files[0], &p1.files[0]);
            // Every assignment gives its frame's value still: none is a second value.
            assert!(
                f1.diagnostics
                    .iter()
                    .all(|d| !d.message.contains("left as written")),
                "{:?}\n{mirrored}",
                f1.diagnostics
            );
            assert_eq!(given(f1), own + 1, "{mirrored}");
            let (want, _) = refl.frame(&frame(f0, "wCar"));
            let got = frame(f1, "wCar");
            assert!(
                (want.translation.vector - got.translation.vector).norm() < 1e-3
                    && want.rotation.angle_to(&got.rotation) < 1e-5,
                "{want:?} {got:?}\n{mirrored}"
            );
            // (The declaration of a frame an assignment stands for is rewritten too, with its
            // own value.)
            for v in f1.frame_values.iter().filter(|v| v.assigned) {
                let (a, b) = (v.pose().unwrap(), frame(f1, &v.name));
                assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
            }
        }
    }

    /// Mirroring the frames of a work object the program gives one other value after a motion:
    /// the first motion runs with the declared value, the second with the one given, and a
    /// mirror in the work object's own plane mirrors both targets. Both values mirror, so each
    /// motion's TCP lands on the mirror image of where it was (`Sa·W·T·Sb`). Before, the
    /// declaration stayed as written: `p1` ran with it and landed 693 mm and 20° (twice the
    /// frame's 10° turn) away from its image.
    #[test]
    fn the_declaration_of_a_frame_given_another_value_mirrors_too() {
        let declared =
            "[FALSE,TRUE,\"\",[[1500,-400,600],[0.996195,0,0,0.087156]],[[0,0,0],[1,0,0,0]]]";
        let given =
            "[FALSE,TRUE,\"\",[[1600,-300,600],[0.996195,0,0,0.087156]],[[0,0,0],[1,0,0,0]]]";
        let assignment = format!("    wCar:={given};\n");
        let text = format!(
            "MODULE m\n  PERS wobjdata wCar:={declared};\n  \
             CONST robtarget p1:=[[310.5,-120.25,80],[0,0.707107,0.707107,0],[0,-1,2,1],[2500,9E9,9E9,9E9,9E9,9E9]];\n  \
             CONST robtarget p2:=[[410.5,-20.25,80],[0,0.707107,0.707107,0],[0,-1,2,1],[2500,9E9,9E9,9E9,9E9,9E9]];\n  \
             PROC main()\n    MoveL p1, v1000, fine, tool0\\WObj:=wCar;\n{assignment}    \
             MoveL p2, v1000, fine, tool0\\WObj:=wCar;\n  ENDPROC\nENDMODULE\n"
        );
        let s = MirrorSettings {
            mirror_frames: true,
            ..MirrorSettings::default()
        };
        let refl = Reflection::new(&s);
        let p0 = parse(&text);
        let edits = mirror(&p0, &s);
        assert!(edits.refusals().next().is_none());
        let out = apply(&p0, edits).unwrap();
        let mirrored = String::from_utf8(out.files[0].output.clone()).unwrap();
        // The work object each motion runs with: the declaration's (read with the assignment
        // left out), then the value given.
        let without_assignment = |t: &str| {
            let kept: String = t
                .lines()
                .filter(|l| !l.trim_start().starts_with("wCar:="))
                .map(|l| format!("{l}\n"))
                .collect();
            parse(&kept).files[0].clone()
        };
        let with_assignment = |t: &str| parse(t).files[0].clone();
        let before_assignment = without_assignment(&text);
        let declared_mirrored = without_assignment(&mirrored);
        let assigned_mirrored = with_assignment(&mirrored);
        for (target, f0, f1) in [
            ("p1", &before_assignment, &declared_mirrored),
            ("p2", &with_assignment(&text), &assigned_mirrored),
        ] {
            let (want, _) = refl.target(&(frame(f0, "wCar") * pose_of(f0, target)));
            let got = frame(f1, "wCar") * pose_of(f1, target);
            assert!(
                (want.translation.vector - got.translation.vector).norm() < 2e-3
                    && want.rotation.angle_to(&got.rotation) < 1e-5,
                "{target}: {want:?} {got:?}\n{mirrored}"
            );
        }
    }

    /// Mirroring the frames: the work object and the tool mirror so that the world pose of the TCP
    /// is the mirror image of the original in world (`Sa·W·T·Sb`), offsets follow Sa / Sb and
    /// mirroring joints negates axes 1, 4, 6.
    #[test]
    fn frames_offsets_and_joints_through_the_rapid_parser() {
        let p0 = parse(MODULE);
        let s = MirrorSettings {
            mirror_frames: true,
            mirror_joints: true,
            ..MirrorSettings::default()
        };
        let edits = mirror(&p0, &s);
        assert!(edits.refusals().next().is_none());
        let out = apply(&p0, edits).unwrap();
        let text = String::from_utf8(out.files[0].output.clone()).unwrap();
        let p1 = parse(&text);
        let (f0, f1) = (&p0.files[0], &p1.files[0]);
        let wobj = |f: &ParsedFile| frame(f, "wCar");
        let tool = |f: &ParsedFile| frame(f, "tGun");
        let target = |f: &ParsedFile| pose_of(f, "p1");
        let refl = Reflection::new(&s);
        let (want, _) = refl.target(&(wobj(f0) * target(f0)));
        let got = wobj(f1) * target(f1);
        assert!(
            (want.translation.vector - got.translation.vector).norm() < 2e-3,
            "{text}"
        );
        assert!(want.rotation.angle_to(&got.rotation) < 1e-5, "{text}");
        // The flange of the mirror-image robot is Sb·F·Sb, so the tool mirrors as Sb·tool·Sb.
        let (tw, _) = refl.tool(&tool(f0));
        assert!((tw.translation.vector - tool(f1).translation.vector).norm() < 1e-3);
        assert!(text.contains("[[12.5,3.200,412.8]"), "{text}");
        assert!(text.contains("Offs(p1,10,20.5,30)"), "{text}");
        assert!(
            text.contains("RelTool(p1,5,-6,-7\\Rx:=-1\\Ry:=2\\Rz:=-3)"),
            "{text}"
        );
        assert!(text.contains("jHome:=[[-10,-20,30,-40,50,60]"), "{text}");
        assert!(text.contains("[-1,0,-3,1],[2500,"), "{text}");
    }

    /// `frame_in = "world"`, frames mirrored (`mirror_frames`): the work object (a turned user frame, an
    /// object frame moved and turned in it) mirrors, and the chain `uframe'·oframe'·T'` is the
    /// world mirror image of `uframe·oframe·T`, once: `S·U·O·T·Sb`, `S` the plane in world
    /// (turned and off the origin here) and `Sb` the tool flip, both built in the test as 4×4
    /// matrices. An `Offs` in that work object follows; a target in world mirrors in world.
    #[test]
    fn world_plane_with_frames_mirrors_the_chain_once() {
        let text = "MODULE m\n  PERS wobjdata wS:=[FALSE,TRUE,\"\",[[1000,-1000,50],[0.965926,0,0,0.258819]],[[120,-80,30],[0.996195,0.087156,0,0]]];\n  CONST robtarget p1:=[[10,20,30],[0,0.707107,0.707107,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget pW:=[[900,-1200,400],[0,1,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL p1, v100, z10, tool0\\WObj:=wS;\n    MoveL Offs(p1,5,-7,9), v100, z10, tool0\\WObj:=wS;\n    MoveL pW, v100, z10, tool0;\n  ENDPROC\nENDMODULE\n";
        let p0 = parse(text);
        let plane = pose_xyz_deg(40.0, -1850.75, 10.0, 3.0, -2.0, 25.0);
        let in_world = MirrorSettings {
            mirror_frames: true,
            world: Some(WorldPlane {
                frame: plane,
                frames: BTreeMap::new(),
                frames_to: None,
                default_wobj: None,
            }),
            ..MirrorSettings::default()
        };
        // The plane in the work object, off its origin: the frames mirror in that plane read in
        // world, and what is in them with it.
        let in_wobj = MirrorSettings {
            mirror_frames: true,
            frame: plane,
            ..MirrorSettings::default()
        };
        for s in [in_world, in_wobj] {
            chain_mirrors_once(&p0, text, &plane, &s);
        }
    }

    fn chain_mirrors_once(p0: &Program, text: &str, plane: &Pose, s: &MirrorSettings) {
        use nalgebra::{Matrix4, Vector4};
        let edits = mirror(p0, s);
        assert!(edits.refusals().next().is_none());
        let out = String::from_utf8(apply(p0, edits).unwrap().files[0].output.clone()).unwrap();
        let p1 = parse(&out);
        // The reflection in the plane through `plane`'s origin with normal `plane`'s y (xz
        // plane), and the tool flip in the tool's y.
        let n = plane.rotation * Vector3::y();
        let o = plane.translation.vector;
        let mut world = Matrix4::identity();
        let linear = nalgebra::Matrix3::identity() - 2.0 * n * n.transpose();
        world.fixed_view_mut::<3, 3>(0, 0).copy_from(&linear);
        world
            .fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&(2.0 * o.dot(&n) * n));
        let flip = Matrix4::from_diagonal(&Vector4::new(1.0, -1.0, 1.0, 1.0));
        let m = |p: &Pose| p.to_homogeneous();
        let pos = |prog: &Program, name: &str| pose_of(&prog.files[0], name);
        let wobj = |prog: &Program| prog.files[0].frames[0].pose().unwrap();
        let close = |got: Matrix4<f64>, want: Matrix4<f64>| {
            let dt = (got.fixed_view::<3, 1>(0, 3) - want.fixed_view::<3, 1>(0, 3)).norm();
            let dr = (got.fixed_view::<3, 3>(0, 0) - want.fixed_view::<3, 3>(0, 0)).norm();
            (dt, dr)
        };
        // Both written at six decimals in the quaternions, three in millimetres.
        let (dt, dr) = close(
            m(&wobj(&p1)) * m(&pos(&p1, "p1")),
            world * m(&wobj(p0)) * m(&pos(p0, "p1")) * flip,
        );
        assert!(dt < 2e-3 && dr < 2e-5, "{dt} {dr}\n{out}");
        let (dt, dr) = close(m(&pos(&p1, "pW")), world * m(&pos(p0, "pW")) * flip);
        assert!(dt < 2e-3 && dr < 2e-5, "{dt} {dr}\n{out}");
        // The offset is a free vector in the work object: in world, `W·d` mirrors to `W'·d'`.
        let offs = |text: &str| -> Vector3<f64> {
            let at = text.find("Offs(p1,").unwrap() + "Offs(p1,".len();
            let v: Vec<f64> = text[at..text[at..].find(')').unwrap() + at]
                .split(',')
                .map(|x| x.trim().parse().unwrap())
                .collect();
            Vector3::new(v[0], v[1], v[2])
        };
        let (w0, w1) = (wobj(p0), wobj(&p1));
        let want = linear * (w0.rotation * offs(text));
        assert!((w1.rotation * offs(&out) - want).norm() < 1e-3, "{out}");
    }

    /// `frame_in = "world"`: a target in a work object and a target in world mirror about the
    /// same physical plane.
    #[test]
    fn world_plane_mirrors_every_work_object_about_one_plane() {
        let text = "MODULE m\n  PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1500,-1850.75,600],[0.996195,0,0,0.087156]],[[0,0,0],[1,0,0,0]]];\n  CONST robtarget pCar:=[[100,300,50],[1,0,0,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget pWorld:=[[1600,-1550.75,650],[1,0,0,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL pCar, v1000, fine, tool0\\WObj:=wCar;\n    MoveL pWorld, v1000, fine, tool0;\n    MoveL Offs(pCar,0,10,0), v1000, fine, tool0\\WObj:=wCar;\n  ENDPROC\nENDMODULE\n";
        let p0 = parse(text);
        let plane = pose_xyz_deg(0.0, -1850.75, 0.0, 0.0, 0.0, 0.0);
        let s = MirrorSettings {
            world: Some(WorldPlane {
                frame: plane,
                frames: BTreeMap::new(),
                frames_to: None,
                default_wobj: None,
            }),
            ..MirrorSettings::default()
        };
        let edits = mirror(&p0, &s);
        assert!(edits.refusals().next().is_none());
        let out = String::from_utf8(apply(&p0, edits).unwrap().files[0].output.clone()).unwrap();
        let p1 = parse(&out);
        let w = p1.files[0].frames[0].pose().unwrap();
        let world = Reflection::about(&plane, &s);
        let (want_car, _) = world.target(&(w * pose_of(&p0.files[0], "pCar")));
        let got_car = w * pose_of(&p1.files[0], "pCar");
        assert!(
            (want_car.translation.vector - got_car.translation.vector).norm() < 2e-3,
            "{out}"
        );
        assert!(
            want_car.rotation.angle_to(&got_car.rotation) < 1e-5,
            "{out}"
        );
        let got_world = pose_of(&p1.files[0], "pWorld").translation.vector;
        assert!(
            (got_world - Vector3::new(1600.0, -2150.75, 650.0)).norm() < 1e-9,
            "{out}"
        );
        // The Offs offset is a vector in wCar, turned 10° against the plane.
        assert!(out.contains("Offs(pCar,-3.420,-9.397,0)"), "{out}");
    }

    /// An expression in an offset blocks the mirror only where the reflection reads it.
    #[test]
    fn offset_expressions_block_only_the_mirrored_component() {
        let text = "MODULE m\n  VAR num zUp := 5;\n  CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL Offs(p1,10,20,zUp), v1000, fine, tool0;\n    MoveL Offs(p1,10,zUp,0), v1000, fine, tool0;\n  ENDPROC\nENDMODULE\n";
        let p0 = parse(text);
        let edits = mirror(&p0, &MirrorSettings::default());
        let refused: Vec<_> = edits.refusals().map(|r| (r.line, r.kind)).collect();
        assert_eq!(refused, [(6, RefusalKind::Expression)]);
        let out = String::from_utf8(apply(&p0, edits).unwrap().files[0].output.clone()).unwrap();
        assert!(out.contains("Offs(p1,10,-20,zUp)"), "{out}");
        assert!(out.contains("Offs(p1,10,zUp,0)"), "{out}");
    }

    #[test]
    fn reltool_rotation_expressions_are_refused_where_the_mirror_changes_them() {
        let text = "MODULE m\n  VAR num a := 5;\n  CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL RelTool(p1,0,0,10\\Rz:=a), v1000, fine, tool0;\n    MoveL RelTool(p1,0,0,10\\Ry:=a), v1000, fine, tool0;\n    MoveL RelTool(p1,0,0,10\\Rz:=30), v1000, fine, tool0;\n  ENDPROC\nENDMODULE\n";
        let p0 = parse(text);
        let edits = mirror(&p0, &MirrorSettings::default());
        let refused: Vec<_> = edits
            .refusals()
            .map(|r| (r.line, r.kind, r.message.clone()))
            .collect();
        assert_eq!(
            refused,
            [(
                5,
                RefusalKind::Expression,
                "RelTool(p1, …): its rotation \\Rz is not a number and the mirror changes its sign"
                    .to_owned()
            )]
        );
        let out = String::from_utf8(apply(&p0, edits).unwrap().files[0].output.clone()).unwrap();
        // Tool flip y: a turn about y keeps its sign, one about z changes it.
        assert!(out.contains("RelTool(p1,0,0,10\\Ry:=a)"), "{out}");
        assert!(out.contains("RelTool(p1,0,0,10\\Rz:=-30)"), "{out}");
    }

    fn settings() -> impl Strategy<Value = MirrorSettings> {
        let frame = (
            -500.0..500.0f64,
            -500.0..500.0f64,
            -500.0..500.0f64,
            -180.0..180.0f64,
            -89.0..89.0f64,
            -180.0..180.0f64,
        );
        (
            frame,
            prop_oneof![Just(Plane::Xy), Just(Plane::Xz), Just(Plane::Yz)],
            prop_oneof![Just(Axis::X), Just(Axis::Y), Just(Axis::Z)],
            any::<bool>(),
        )
            .prop_map(
                |((x, y, z, a, b, c), plane, tool_flip, ident)| MirrorSettings {
                    frame: if ident {
                        Pose::identity()
                    } else {
                        pose_xyz_deg(x, y, z, a, b, c)
                    },
                    plane,
                    tool_flip,
                    ..MirrorSettings::default()
                },
            )
    }

    fn unit_quat() -> impl Strategy<Value = [f64; 4]> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
            .prop_filter("not tiny", |(a, b, c, d)| {
                a * a + b * b + c * c + d * d > 0.05
            })
            .prop_map(|(a, b, c, d)| {
                let n = (a * a + b * b + c * c + d * d).sqrt();
                [a / n, b / n, c / n, d / n]
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// docs/design.md §4: mirror(mirror(P)) = P in memory, 1e-6 mm, 1e-9 in quaternion components.
        #[test]
        fn mirror_twice_in_memory(s in settings(), q in unit_quat(),
                                  x in -3000.0..3000.0f64, y in -3000.0..3000.0f64, z in -3000.0..3000.0f64) {
            let refl = Reflection::new(&s);
            let t = Pose::from_parts(nalgebra::Translation3::new(x, y, z), abb_quat(q).unwrap());
            let (once, _) = refl.target(&t);
            let (twice, _) = refl.target(&once);
            prop_assert!((twice.translation.vector - t.translation.vector).norm() < 1e-6);
            let back = wijk(&twice.rotation);
            prop_assert!(same_up_to_sign(back, q, 1e-9), "{back:?} vs {q:?}");
            // A mirror is a reflection: proper rotation out, improper nowhere.
            prop_assert!((once.rotation.norm() - 1.0).abs() < 1e-12);
        }

        /// A plane in world, taken into a work object (`M = W⁻¹·P`), mirrors the target's world
        /// pose about that plane: `W·T' = P·Sa·P⁻¹·W·T·Sb`.
        #[test]
        fn world_plane_equals_mirror_in_world(s in settings(), q in unit_quat(),
                                              w in (-2000.0..2000.0f64, -2000.0..2000.0f64, -500.0..500.0f64, -180.0..180.0f64, -20.0..20.0f64)) {
            let t = Pose::from_parts(nalgebra::Translation3::new(120.0, -340.0, 56.0), abb_quat(q).unwrap());
            let w = pose_xyz_deg(w.0, w.1, w.2, w.4, 0.0, w.3);
            let (local, _) = Reflection::about(&(w.inverse() * s.frame), &s).target(&t);
            let (world, _) = Reflection::about(&s.frame, &s).target(&(w * t));
            let got = w * local;
            prop_assert!((got.translation.vector - world.translation.vector).norm() < 1e-6);
            prop_assert!(got.rotation.angle_to(&world.rotation) < 1e-9);
        }

        /// Through files: twice gives back the same numbers, to the written precision.
        #[test]
        fn mirror_twice_through_text(s in settings(), q in unit_quat(),
                                     x in -3000.0..3000.0f64, y in -3000.0..3000.0f64, z in -3000.0..3000.0f64,
                                     cf in (-4i64..4, -4i64..4, -4i64..4, 0i64..8)) {
            let line = format!(
                "[[{x:.3},{y:.3},{z:.3}],[{:.6},{:.6},{:.6},{:.6}],[{},{},{},{}],[{:.3},9E9,9E9,9E9,9E9,9E9]]\n",
                q[0], q[1], q[2], q[3], cf.0, cf.1, cf.2, cf.3, x.abs()
            );
            let p0 = rapid(&line, "wobj0");
            let once = mirrored_text(&p0, &s);
            let twice = mirrored_text(&rapid(&once, "wobj0"), &s);
            let (a, b) = (&p0.files[0].position(0).unwrap(), &rapid(&twice, "wobj0").files[0].position(0).unwrap());
            let ta = a.cartesian.as_ref().unwrap().translation().unwrap();
            let tb = b.cartesian.as_ref().unwrap().translation().unwrap();
            for (u, v) in ta.iter().zip(tb) {
                prop_assert!((u - v).abs() <= 1.5e-3, "{once}{twice}");
            }
            prop_assert!(same_up_to_sign(quat_of(a), quat_of(b), 3e-6), "{line}{once}{twice}");
            prop_assert_eq!(&a.config, &b.config);
        }
    }
}
