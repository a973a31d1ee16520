//! `correct` and `zero` (docs/design.md §4, thesis eq. 4.55).
//!
//! For a target `T` in work object `W` at skid `s`, with the controller's nominal base
//! `B(s) = Trans(s·a)·B_0` and the profile's deviation `D(s)`:
//! - correct: `T' = W⁻¹ · B(s) · D(s)⁻¹ · B(s)⁻¹ · W · T`
//! - zero:    `T' = W⁻¹ · B(s) · D(s)   · B(s)⁻¹ · W · T`

use crate::track::uncertainty::{ProfileUncertainty, tcp_uncertainty_world};
use std::collections::BTreeMap;

use nalgebra::{Translation3, Vector3};

use crate::geometry::Pose;
use crate::position::{Position, Program, Reading, Skid};
use crate::track::{Profile, TrackError};

use super::cell::Robot;
use super::driver::{KeptByStamp, NewPose, Scope, Step, TargetRule, apply_rule};
use super::edits::{ProgramEdits, TargetChange};
use super::kinematic_policy::{
    Arm, flange_move, joint_edits, reversible_joint_edits, with_tool, written_steps,
};
use super::policy::{
    LastWorkObject, Why, common_refusal, describe, joint_target, offset_bases, stationary_tool,
};
use super::refusal::Refusal;
use super::refusal::RefusalKind;
use super::rewrite::OrientationHint;
use super::rewrite::{MM_DECIMALS, number_edit};
use super::stamp::{Stamp, StampReading};
use crate::position::{NumField, OffsetCall, OffsetKind};
use crate::syntax::Edit;

/// `D(s)`: anything that gives the track's deviation at a skid (a [`Profile`], or a test's
/// closed form).
pub trait Deviation: Sync {
    /// `D(s)` at skid `s` (mm): the measured carriage frame relative to the nominal one,
    /// `N(s)⁻¹·F(s)` (`docs/design.md §3`).
    fn deviation(&self, skid: f64) -> Result<Pose, TrackError>;
}

impl Deviation for Profile {
    fn deviation(&self, skid: f64) -> Result<Pose, TrackError> {
        Profile::deviation(self, skid)
    }
}

impl<F: Fn(f64) -> Result<Pose, TrackError> + Sync> Deviation for F {
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
    /// The transform's name (`correct`, `zero`), as reports show it.
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
    /// The track's deviation `D(s)`.
    pub deviation: &'a dyn Deviation,
    /// The work object for declared targets no motion uses (the caller's
    /// default; `None`: such targets are refused).
    pub default_wobj: Option<String>,
    /// The profile's uncertainty, when it carries one: each corrected target then records the
    /// expanded uncertainty of its TCP.
    pub uncertainty: Option<&'a ProfileUncertainty>,
    /// The robot's arm, when the cell gives its kinematics: every target is then checked and
    /// joint targets are moved (docs/design.md §10).
    pub arm: Option<Arm>,
    /// The robot's name, as provenance stamps give it: a file stamped for this robot has the
    /// targets its stamp lists as kept as written treated apart ([`StampReading`]); `None`:
    /// stamps are not read.
    pub robot: Option<String>,
}

impl<'a> TrackSetup<'a> {
    /// The setup of a cell's `robot` with its track's `deviation`; no default work object.
    pub fn new(robot: &Robot, deviation: &'a dyn Deviation) -> TrackSetup<'a> {
        TrackSetup {
            base0: robot.base0,
            track_axis: robot.track_axis,
            skid_axis: robot.skid_axis,
            frames: robot.frames.clone(),
            deviation,
            default_wobj: None,
            uncertainty: None,
            arm: Arm::of(robot),
            robot: Some(robot.name.clone()),
        }
    }

    /// `B(s) = Trans(s·a)·B_0`.
    pub fn base_at(&self, skid: f64) -> Pose {
        Translation3::from(self.track_axis * skid) * self.base0
    }

    /// The work-object-frame change `W⁻¹·B·D^∓1·B⁻¹·W` at skid `s` (left factor of `T`).
    pub fn correction(&self, w: &Pose, skid: f64, dir: Direction) -> Result<Pose, TrackError> {
        Ok(self.correction_both_ways(w, skid, dir, false)?.0)
    }

    /// [`correction`](Self::correction) in `dir`, and with `inverse` also in the other
    /// direction (what the inverse transform applies), from one evaluation of the deviation:
    /// each pose is the one `correction` gives, bit for bit (the same products in the same
    /// order), at the cost of one spline evaluation, not two.
    fn correction_both_ways(
        &self,
        w: &Pose,
        skid: f64,
        dir: Direction,
        inverse: bool,
    ) -> Result<(Pose, Option<Pose>), TrackError> {
        let b = self.base_at(skid);
        let d = self.deviation.deviation(skid)?;
        let (wb, bi) = (w.inverse() * b, b.inverse());
        let through = |d: Pose| wb * d * bi * w;
        let (this, other) = match dir {
            Direction::Correct => (through(d.inverse()), inverse.then(|| through(d))),
            Direction::Zero => (through(d), inverse.then(|| through(d.inverse()))),
        };
        Ok((this, other))
    }

    /// `D(s)⁻¹` (correct) or `D(s)` (zero): the change seen from the robot base at `s`.
    pub fn base_change(&self, skid: f64, dir: Direction) -> Result<Pose, TrackError> {
        let d = self.deviation.deviation(skid)?;
        Ok(match dir {
            Direction::Correct => d.inverse(),
            Direction::Zero => d,
        })
    }
}

/// The refusal of a target whose skid the profile cannot evaluate.
fn profile_refusal(what: &impl std::fmt::Display, skid: f64, e: TrackError) -> Why {
    match e {
        TrackError::OutOfRange { min, max, .. } => Why::new(
            RefusalKind::SkidOutOfRange,
            format!("{what} is at skid {skid} mm, outside the profile's range [{min}, {max}] mm"),
            "measure the track over this range, or set extrapolate = \"clamp\" or \"linear\" in the profile",
        ),
        other => Why::new(
            RefusalKind::SkidOutOfRange,
            format!("{what} at skid {skid} mm: {other}"),
            "check the profile",
        ),
    }
}

/// A target's work object in world, and its tool on the flange when the arm is checked.
struct TrackFrame {
    w: Pose,
    /// With the arm's kinematics, every tool the target is used with (the order of
    /// `Usage::tools`); none without.
    tools: Vec<Pose>,
    language: crate::position::Language,
}

/// `correct` or `zero` as a rule of the transform driver.
struct TrackRule<'s, 'a> {
    setup: &'s TrackSetup<'a>,
    dir: Direction,
    work_objects: LastWorkObject,
    corrections: LastCorrection,
    stamps: StampReading,
    /// The first step of a `transfer`, whose later steps move what this one leaves as written.
    chain: bool,
}

/// The correction (and its undo) last worked out, with the skid and the work object it was
/// for. A program's targets come in runs taught at one skid position in one work object (a
/// station's welds), and the correction depends on those two alone: the splines, the pose
/// and its five products are worked out once per run. Keyed by their bits, so that a
/// correction is reused only for inputs it would be computed again from exactly.
#[derive(Default)]
struct LastCorrection(std::cell::Cell<Option<CorrectionFor>>);

/// A correction and its undo, with the bits of the skid and of the work object's pose.
type CorrectionFor = (u64, [u64; 7], (Pose, Option<Pose>));

impl LastCorrection {
    fn key(w: &Pose) -> [u64; 7] {
        let (t, q) = (&w.translation.vector, &w.rotation.coords);
        [t.x, t.y, t.z, q.x, q.y, q.z, q.w].map(f64::to_bits)
    }

    /// [`TrackSetup::correction_both_ways`] in `dir`, with its undo when `inverse`, for the
    /// same `setup`, `dir` and `inverse` at every call.
    fn get(
        &self,
        setup: &TrackSetup<'_>,
        w: &Pose,
        skid: f64,
        dir: Direction,
        inverse: bool,
    ) -> Result<(Pose, Option<Pose>), TrackError> {
        let (skid_bits, w_bits) = (skid.to_bits(), Self::key(w));
        if let Some((s, k, both)) = self.0.get()
            && s == skid_bits
            && k == w_bits
        {
            return Ok(both);
        }
        let both = setup.correction_both_ways(w, skid, dir, inverse)?;
        self.0.set(Some((skid_bits, w_bits, both)));
        Ok(both)
    }
}

impl TargetRule for TrackRule<'_, '_> {
    type Frame = TrackFrame;

    /// Without an arm a target's configuration and its external axes but the skid's are not
    /// looked at, but for the refusal of implausible values, which the reading keeps: the 9
    /// of a robtarget's 17 fields it leaves out were 38 % of decoding it (2 MB module:
    /// 39.2 → 24.2 M instructions). The arm's checks read every field.
    fn reading(&self) -> Reading {
        match self.setup.arm {
            Some(_) => Reading::Whole,
            None => Reading::Track {
                skid_axis: self.setup.skid_axis,
            },
        }
    }

    fn refusal(&self, scope: Scope, p: &Position) -> Option<Why> {
        common_refusal(scope.file, p).or_else(|| stationary_tool(scope.program, scope.file, p))
    }

    fn joint(&self, scope: Scope, p: &Position) -> Step {
        let refuse = |why: Why| why.at(scope.file, p);
        let Some(arm) = &self.setup.arm else {
            return Err(refuse(joint_target(p)));
        };
        let j = arm.joints_of(p).map_err(refuse)?;
        let skid = self.skid(scope, p).map_err(refuse)?.unwrap_or_default();
        let change = self
            .setup
            .base_change(skid, self.dir)
            .map_err(|e| refuse(profile_refusal(&describe(p), skid, e)))?;
        let kin = &arm.kinematics;
        let steps = written_steps(p);
        let new = crate::kinematics::joint_target_correction(kin, &j, &change, &steps)
            .map_err(|refused| refuse(arm.joint_refusal(p, &j, &refused)))?;
        // `correct` is written so that `zero` gives back the text it read, as a pose is
        // (`new_pose`); the corrected text has the original's places, at least four.
        let edits = match self.dir {
            Direction::Correct => {
                let undo = self
                    .setup
                    .base_change(skid, Direction::Zero)
                    .map_err(|e| refuse(profile_refusal(&describe(p), skid, e)))?;
                reversible_joint_edits(p, &new, |written| {
                    crate::kinematics::joint_target_correction(kin, &written, &undo, &steps).ok()
                })
            }
            Direction::Zero => joint_edits(p, &new),
        };
        let (mm, deg) = flange_move(kin, &j, kin, &new);
        let change = TargetChange {
            mm,
            deg,
            skid: Some(skid),
            name: p.name.clone(),
            line: p.line,
            // A joint target has no work object or tool: its TCP in the world is not known
            // here, so no uncertainty is stated for it.
            uncertainty_mm: None,
            axes_deg: None,
        };
        Ok(Some((edits, change)))
    }

    fn skid(&self, scope: Scope, p: &Position) -> Result<Option<f64>, Why> {
        let what = describe(p);
        let axis = || {
            scope
                .file
                .language
                .dialect()
                .axis_name(self.setup.skid_axis)
        };
        match p.skid(self.setup.skid_axis) {
            Skid::At(s) => Ok(Some(s)),
            Skid::NotConnected => {
                let axis = axis();
                // As written: `9E+09`, or a value beyond it that reads the same.
                let written = p
                    .extax
                    .get(self.setup.skid_axis)
                    .and_then(Option::as_ref)
                    .map_or_else(
                        || "9E9".to_owned(),
                        |f| crate::syntax::latin1(f.span().slice(&scope.file.source)),
                    );
                Err(Why::new(
                    RefusalKind::SkidNotConnected,
                    format!(
                        "{what} has {axis} = {written}, which reads as not connected (8.9E9 or beyond, read as the 9E9 mark): no skid position"
                    ),
                    format!(
                        "write the skid position into {axis}, or set `skid` for this robot in the cell file"
                    ),
                ))
            }
            Skid::Missing => {
                let axis = axis();
                Err(Why::new(
                    RefusalKind::SkidMissing,
                    format!("{what} has no numeric {axis}: no skid position"),
                    format!("write the skid position into {axis}"),
                ))
            }
        }
    }

    fn frame(&self, scope: Scope, p: &Position) -> Result<TrackFrame, Why> {
        let w = self.work_objects.work_object_of(
            scope.program,
            scope.file,
            p,
            &self.setup.frames,
            self.setup.default_wobj.as_deref(),
        )?;
        let tools = match &self.setup.arm {
            Some(arm) => arm.tools(scope.program, scope.file, p)?,
            None => Vec::new(),
        };
        Ok(TrackFrame {
            w,
            tools,
            language: scope.file.language,
        })
    }

    /// `correct` is written so that `zero` gives back the text it read (its change is the
    /// undo): a program corrected for a track and zeroed again is the program as drawn. `zero`
    /// is not written for a later `correct`: a choice made for that could undo the one
    /// `correct` made, and a program zeroed from an online-tuned one has no text to come back
    /// to.
    fn new_pose(
        &self,
        p: &Position,
        frame: &TrackFrame,
        skid: Option<f64>,
        t: &Pose,
    ) -> Result<NewPose, Why> {
        let what = describe(p);
        // `skid` refused targets without one.
        let skid = skid.unwrap_or_default();
        let w = &frame.w;
        let (correction, undo) = self
            .corrections
            .get(
                self.setup,
                w,
                skid,
                self.dir,
                self.dir == Direction::Correct,
            )
            .map_err(|e| profile_refusal(&what, skid, e))?;
        let new = correction * t;
        if let Some(arm) = &self.setup.arm {
            // The flange in the base the controller computes: F = B(s)⁻¹·W·T·TOOL⁻¹.
            let to_base = self.setup.base_at(skid).inverse() * w;
            for (tool, name) in frame.tools.iter().zip(p.usage.tools()) {
                let flange = |t: &Pose| to_base * t * tool.inverse();
                arm.check(p, &flange(t), &flange(&new), frame.language)
                    .map_err(|why| with_tool(why, p, name))?;
            }
        }
        Ok(NewPose {
            pose: new,
            hint: OrientationHint::NearOriginal,
            undo,
        })
    }

    fn keeps_lock_splits(&self) -> bool {
        self.dir == Direction::Zero
    }

    /// A `zero` for robot R of a file stamped as corrected for R (`correct`, or `transfer` to
    /// R) leaves the targets the stamp lists as written: they carry none of R's correction.
    /// Those a `transfer` kept are its source robot's as written, neither corrected for R nor
    /// for no track: listed again, and refused within a `transfer`, whose later steps would
    /// treat them as zeroed. A `correct` for R of a file a `zero` for R stamped leaves them as
    /// written: they still carry R's correction. Any other track rule on such a file would
    /// treat them as it treats the rest, which carries what they lack: refused. (A `correct`
    /// of a file corrected for the same robot is the command line's to refuse, whole.)
    fn kept_by_stamp(&self, stamp: &Stamp) -> Option<KeptByStamp> {
        if self.stamps == StampReading::Ignore {
            return None;
        }
        let robot = self.setup.robot.as_deref()?;
        let same_robot = stamp.robot.as_deref() == Some(robot);
        let verb = self.dir.as_str();
        match (self.dir, stamp.command.as_str()) {
            (Direction::Zero, "correct" | "transfer") if same_robot => {
                let carry = stamp.command == "transfer";
                if carry && self.chain {
                    return Some(KeptByStamp::Refuse {
                        said: format!(
                            "it is the program it was transferred from as written, with none of robot `{robot}`'s correction, and the transfer's later steps would take it for zeroed"
                        ),
                    });
                }
                let said = if carry {
                    format!(
                        "it is the program it was transferred from as written, with none of robot `{robot}`'s correction, so {verb} leaves it as written"
                    )
                } else {
                    format!(
                        "it carries none of robot `{robot}`'s correction, so {verb} leaves it as written"
                    )
                };
                Some(KeptByStamp::Leave { said, carry })
            }
            (Direction::Correct, "zero") if same_robot => Some(KeptByStamp::Leave {
                said: format!(
                    "it still carries robot `{robot}`'s correction, so {verb} leaves it as written"
                ),
                carry: false,
            }),
            (Direction::Correct, "correct" | "transfer") if same_robot => None,
            _ => Some(KeptByStamp::Refuse {
                said: format!(
                    "it lacks what that transform gave the rest of the file, so {verb} for robot `{robot}` cannot treat it as the rest"
                ),
            }),
        }
    }

    /// An `Offs` offset is a vector in the work object: the corrected target `G·T` offset by
    /// `d` is `G·(d + T)`, the target offset by `R_G·d`, so the offset turns with the
    /// correction's rotation. A `RelTool` offset is in the tool frame, which moves with the
    /// target: it stays. A target left as written keeps its offsets (the driver does not ask
    /// then), and so does one the rule cannot place, which is refused with the target.
    fn offset(&self, scope: Scope, call: &OffsetCall) -> Result<Vec<Edit>, Box<Refusal>> {
        if call.kind != OffsetKind::Offs {
            return Ok(Vec::new());
        }
        let refuse = |kind, message: String, hint: &str| {
            Err(Why::new(kind, message, hint).at_call(scope.file, call))
        };
        let d = call
            .delta
            .each_ref()
            .map(|f| f.as_ref().map(NumField::value));
        // (Asked as `new_pose` asks, whose cache this is.)
        let inverse = self.dir == Direction::Correct;
        // The offset each base turns it to.
        let mut turned_to: Vec<Vector3<f64>> = Vec::new();
        for (file, p) in offset_bases(scope.program, call, self.reading()) {
            let at = Scope {
                program: scope.program,
                file,
            };
            let w = self.work_objects.work_object_of(
                scope.program,
                file,
                &p,
                &self.setup.frames,
                self.setup.default_wobj.as_deref(),
            );
            let (Ok(Some(skid)), Ok(w)) = (self.skid(at, &p), w) else {
                continue;
            };
            let Ok((g, _)) = self
                .corrections
                .get(self.setup, &w, skid, self.dir, inverse)
            else {
                continue;
            };
            let turned = g.rotation.angle() != 0.0;
            if turned && d.iter().any(Option::is_none) {
                return refuse(
                    RefusalKind::Expression,
                    format!(
                        "Offs({}, …) has an offset that is not a number, which the correction turns by {:.4}°",
                        call.target,
                        g.rotation.angle().to_degrees()
                    ),
                    "write the object-frame offsets as numbers",
                );
            }
            turned_to.push(
                g.rotation
                    * Vector3::new(
                        d[0].unwrap_or_default(),
                        d[1].unwrap_or_default(),
                        d[2].unwrap_or_default(),
                    ),
            );
        }
        let Some(&first) = turned_to.first() else {
            return Ok(Vec::new());
        };
        // The bases of an array element through a computed index, or of a routine's parameter,
        // are several targets: one written offset follows them all when their turns agree
        // within the written precision, and is written at the middle of the range.
        let (lo, hi) = turned_to
            .iter()
            .fold((first, first), |(lo, hi), v| (lo.inf(v), hi.sup(v)));
        let spread = (hi - lo).max();
        if spread > 10f64.powi(-(MM_DECIMALS as i32)) {
            return refuse(
                RefusalKind::SharedOffset,
                format!(
                    "the {} targets `{}` stands for are corrected by different turns, which move its offset apart by up to {spread:.3} mm: one Offs offset cannot follow each",
                    turned_to.len(),
                    call.target
                ),
                "write the offset point of each as a target of its own",
            );
        }
        let v = (lo + hi) / 2.0;
        Ok(call
            .delta
            .iter()
            .zip([v.x, v.y, v.z])
            .filter_map(|(f, n)| number_edit(f, n, MM_DECIMALS))
            .collect())
    }

    fn uncertainty(&self, frame: &TrackFrame, skid: Option<f64>, new: &Pose) -> Option<f64> {
        let (pu, skid) = (self.setup.uncertainty?, skid?);
        let tcp = frame.w * nalgebra::Point3::from(new.translation.vector);
        tcp_uncertainty_world(pu, &self.setup.base_at(skid), skid, &tcp)
            .ok()
            .map(|u| u.expanded)
    }
}

/// `correct` or `zero` every Cartesian target of `program` with `setup`'s track (reading the
/// files' provenance stamps for the targets they list as kept as written: docs/design.md §4).
pub fn track_correction(program: &Program, setup: &TrackSetup, dir: Direction) -> ProgramEdits {
    track_rule(program, setup, dir, StampReading::Read, false)
}

/// [`track_correction`] as a step of a chain: `chain` for its first step.
pub(crate) fn track_rule(
    program: &Program,
    setup: &TrackSetup,
    dir: Direction,
    stamps: StampReading,
    chain: bool,
) -> ProgramEdits {
    let rule = TrackRule {
        setup,
        dir,
        work_objects: LastWorkObject::default(),
        corrections: LastCorrection::default(),
        stamps,
        chain,
    };
    apply_rule(program, &rule)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{abb_quat, pose_xyz_deg};
    use crate::position::Orientation;
    use crate::track::profile::{Extrapolate, Knot};
    use crate::transform::edits::{apply, apply_owned};
    use crate::transform::test_support::{krl, rapid};
    use proptest::prelude::*;

    fn setup<'a>(dev: &'a dyn Deviation, base0: Pose, axis: Vector3<f64>) -> TrackSetup<'a> {
        TrackSetup {
            base0,
            track_axis: axis.normalize(),
            skid_axis: 0,
            frames: BTreeMap::new(),
            deviation: dev,
            default_wobj: None,
            uncertainty: None,
            arm: None,
            robot: None,
        }
    }

    fn text_after(p: &Program, s: &TrackSetup, dir: Direction) -> String {
        let edits = track_correction(p, s, dir);
        let r = apply(p, edits.clone()).unwrap();
        // Handing the program over gives the same files, byte for byte.
        let owned = apply_owned(p.clone(), edits).unwrap();
        for (a, b) in r.files.iter().zip(&owned.files) {
            assert_eq!(
                (&a.path, &a.original, &a.output),
                (&b.path, &b.original, &b.output)
            );
        }
        assert_eq!(r.files.len(), owned.files.len());
        assert!(
            r.refusals().next().is_none(),
            "{:?}",
            r.refusals().collect::<Vec<_>>()
        );
        String::from_utf8(r.files[0].output.clone()).unwrap()
    }

    #[test]
    fn worked_example_sag_lifts_the_target() {
        // The rails sag 1 mm at every skid: the real base is 1 mm lower than the controller
        // thinks, so the corrected target must be 1 mm higher for the TCP to land on the CAD
        // point. Base at skid 0 in world (0, -1800, 0) turned 90° about z, track along +x.
        let sag = |_s: f64| -> Result<Pose, TrackError> {
            Ok(pose_xyz_deg(0.0, 0.0, -1.0, 0.0, 0.0, 0.0))
        };
        let s = setup(
            &sag,
            pose_xyz_deg(0.0, -1800.0, 0.0, 0.0, 0.0, 90.0),
            Vector3::x(),
        );
        let w = pose_xyz_deg(2000.0, 0.0, 600.0, 0.0, 0.0, 0.0);
        let c = s.correction(&w, 3000.0, Direction::Correct).unwrap();
        let t = pose_xyz_deg(100.0, 200.0, 300.0, 0.0, 0.0, 0.0);
        let v = (c * t).translation.vector - t.translation.vector;
        assert!((v - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-12, "{v}");
        // And the physical check of docs/design.md §4: B·D·B⁻¹·W·T' = W·T.
        let b = s.base_at(3000.0);
        let d = sag(3000.0).unwrap();
        let reached = b * d * b.inverse() * w * (c * t);
        assert!((reached.translation.vector - (w * t).translation.vector).norm() < 1e-9);
    }

    #[test]
    fn twist_turns_about_the_base_not_the_work_object() {
        // A twist of 0.01° about the base x axis at skid s, with the target 1 m above the base:
        // the correction moves it sideways by 1000·sin(0.01°) ≈ 0.1745 mm.
        let twist = |_s: f64| -> Result<Pose, TrackError> {
            Ok(pose_xyz_deg(0.0, 0.0, 0.0, 0.01, 0.0, 0.0))
        };
        let s = setup(&twist, Pose::identity(), Vector3::x());
        let c = s
            .correction(&Pose::identity(), 500.0, Direction::Correct)
            .unwrap();
        let t = pose_xyz_deg(500.0, 0.0, 1000.0, 0.0, 0.0, 0.0);
        let moved = (c * t).translation.vector - t.translation.vector;
        assert!(
            (moved.y - 1000.0 * 0.01f64.to_radians().sin()).abs() < 1e-9,
            "{moved}"
        );
    }

    #[test]
    fn a_run_of_targets_at_one_skid_works_out_its_correction_once() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let calls = AtomicUsize::new(0);
        let wave = deformation((1.5, 0.02, 900.0));
        let counted = |s: f64| {
            calls.fetch_add(1, Ordering::Relaxed);
            wave(s)
        };
        let mut s = setup(
            &counted,
            pose_xyz_deg(10.0, -1800.0, 5.0, 0.0, 0.0, 90.0),
            Vector3::x(),
        );
        s.frames.insert(
            "wobj_car".into(),
            pose_xyz_deg(2000.0, 0.0, 600.0, 0.0, 0.0, 180.0),
        );
        // Runs at 100, 200 and 100 mm again; -0 and 0 are different inputs.
        let skids = ["100", "100", "100.0", "200", "200", "100", "0", "-0"];
        let lines: Vec<String> = skids
            .iter()
            .enumerate()
            .map(|(k, skid)| {
                format!(
                    "[[{}.5,-310.25,845],[0.0436194,0.0,0.9990482,0.0],[0,-1,0,1],[{skid},9E9,9E9,9E9,9E9,9E9]]\n",
                    1200 + k
                )
            })
            .collect();
        for dir in [Direction::Correct, Direction::Zero] {
            calls.store(0, Ordering::Relaxed);
            let all = text_after(&rapid(&lines.concat(), "wobj_car"), &s, dir);
            assert_eq!(calls.load(Ordering::Relaxed), 5, "{dir:?}");
            // Each target as the one target of a program (worked out from nothing) is written
            // as in the run.
            let alone: String = lines
                .iter()
                .map(|l| text_after(&rapid(l, "wobj_car"), &s, dir))
                .collect();
            assert_eq!(all, alone);
            assert_ne!(all, lines.concat());
        }
    }

    #[test]
    fn zero_deviation_profile_leaves_files_byte_identical() {
        let knots = (0..5).map(|i| Knot::zero(i as f64 * 2000.0)).collect();
        let profile = crate::track::Profile::from_knots("flat", knots, Extrapolate::Error).unwrap();
        let src = "[[1200.5,-310.25,845],[0.0436194,0.0,0.9990482,0.0],[0,-1,0,1],[2500,9E9,9E9,9E9,9E9,9E9]]\n\
                   [[0,0,0],[0.7071,0,0.7071,0],[0,0,0,0],[0,9E+09,9E9,9E9,9E9,9E9]]\n";
        let s = setup(
            &profile,
            pose_xyz_deg(10.0, -1800.0, 5.0, 0.0, 0.0, 90.0),
            Vector3::x(),
        );
        let mut s = s;
        s.frames.insert(
            "wobj_car".into(),
            pose_xyz_deg(2000.0, 0.0, 600.0, 0.0, 0.0, 180.0),
        );
        for dir in [Direction::Correct, Direction::Zero] {
            assert_eq!(text_after(&rapid(src, "wobj_car"), &s, dir), src);
        }
        let k = "{X 1200.5,Y 310.25,Z 845,A 30,B 89.99,C 170,S 6,T 27,E1 7999.5}\n";
        assert_eq!(text_after(&krl(k, "wobj_car"), &s, Direction::Correct), k);
    }

    fn quat(p: &Position) -> [f64; 4] {
        match &p.cartesian.as_ref().unwrap().orient {
            Some(Orientation::Quaternion(q)) => (*q).map(|f| f.unwrap().value()),
            _ => panic!(),
        }
    }

    /// A generated deformation of amplitude `amp.0` mm and `amp.1` degrees over a wavelength
    /// of `amp.2` mm: mm-size translations, hundredths of a degree.
    fn deformation(amp: (f64, f64, f64)) -> impl Fn(f64) -> Result<Pose, TrackError> {
        move |s: f64| {
            let u = s / amp.2;
            Ok(pose_xyz_deg(
                amp.0 * u.cos(),
                amp.0 * u.sin(),
                -amp.0 * (2.0 * u).sin(),
                amp.1 * u.sin(),
                -amp.1 * u.cos(),
                amp.1 * (3.0 * u).sin(),
            ))
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// docs/design.md §4: zero(correct(P)) = P in memory, 1e-6 mm and 1e-9 quaternion.
        #[test]
        fn zero_undoes_correct_in_memory(
            base in (-3000.0..3000.0f64, -3000.0..3000.0f64, -500.0..500.0f64, -180.0..180.0f64),
            axis in (0.5..1.0f64, -0.2..0.2f64, -0.05..0.05f64),
            w in (-3000.0..3000.0f64, -3000.0..3000.0f64, 0.0..1500.0f64, -180.0..180.0f64, -30.0..30.0f64),
            t in (-1500.0..1500.0f64, -1500.0..1500.0f64, -500.0..1500.0f64, -180.0..180.0f64, -80.0..80.0f64, -180.0..180.0f64),
            skid in 0.0..8000.0f64,
            amp in (0.05..5.0f64, 0.001..0.1f64, 500.0..9000.0f64),
        ) {
            let dev = deformation(amp);
            let s = setup(&dev, pose_xyz_deg(base.0, base.1, base.2, 0.0, 0.0, base.3), Vector3::new(axis.0, axis.1, axis.2));
            let w = pose_xyz_deg(w.0, w.1, w.2, 0.0, w.4, w.3);
            let t = pose_xyz_deg(t.0, t.1, t.2, t.3, t.4, t.5);
            let corrected = s.correction(&w, skid, Direction::Correct).unwrap() * t;
            let back = s.correction(&w, skid, Direction::Zero).unwrap() * corrected;
            prop_assert!((back.translation.vector - t.translation.vector).norm() < 1e-6);
            let (a, b) = (back.rotation.quaternion(), t.rotation.quaternion());
            prop_assert!((a.coords - b.coords).amax() < 1e-9 || (a.coords + b.coords).amax() < 1e-9);
            // The correction is a real one (tenths of mm), not a no-op.
            prop_assert!((corrected.translation.vector - t.translation.vector).norm() > 1e-3);
        }

        /// The undo a correction comes with is the other direction's correction bit for bit
        /// (what a second evaluation of the deviation gave), both ways.
        #[test]
        fn the_undo_is_the_other_directions_correction(
            base in (-3000.0..3000.0f64, -3000.0..3000.0f64, -500.0..500.0f64, -180.0..180.0f64),
            w in (-3000.0..3000.0f64, -3000.0..3000.0f64, 0.0..1500.0f64, -180.0..180.0f64, -30.0..30.0f64),
            skid in 0.0..8000.0f64,
            amp in (0.05..5.0f64, 0.001..0.1f64, 500.0..9000.0f64),
        ) {
            let dev = deformation(amp);
            let s = setup(&dev, pose_xyz_deg(base.0, base.1, base.2, 0.0, 0.0, base.3), Vector3::new(1.0, 0.01, 0.0));
            let w = pose_xyz_deg(w.0, w.1, w.2, 0.0, w.4, w.3);
            // `W⁻¹·B·D^∓1·B⁻¹·W` as one expression, each direction on its own.
            let b = s.base_at(skid);
            let d = dev(skid).unwrap();
            let correct = w.inverse() * b * d.inverse() * b.inverse() * w;
            let zero = w.inverse() * b * d * b.inverse() * w;
            for (dir, this, other) in [(Direction::Correct, correct, zero), (Direction::Zero, zero, correct)] {
                prop_assert_eq!(s.correction_both_ways(&w, skid, dir, true).unwrap(), (this, Some(other)));
                prop_assert_eq!(s.correction(&w, skid, dir).unwrap(), this);
            }
        }

        /// Through text: zero(correct(file)) gives back the file's numbers to written precision.
        #[test]
        fn zero_undoes_correct_through_text(
            q in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_filter("norm", |q| q.0*q.0+q.1*q.1+q.2*q.2+q.3*q.3 > 0.05),
            x in -1500.0..1500.0f64, y in -1500.0..1500.0f64, z in -500.0..1500.0f64,
            skid in 0.0..8000.0f64,
            abc in (-180.0..180.0f64, -85.0..85.0f64, -180.0..180.0f64),
            knots in proptest::collection::vec((-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64, -0.1..0.1f64, -0.1..0.1f64, -0.1..0.1f64), 2..10),
        ) {
            // A generated profile: 2 to 9 knots spread evenly over 0..8000 mm.
            let step = 8000.0 / (knots.len() - 1) as f64;
            let knots = knots.iter().enumerate().map(|(i, k)| Knot::from_components(i as f64 * step, [k.0, k.1, k.2, k.3, k.4, k.5])).collect();
            let profile = crate::track::Profile::from_knots("generated", knots, Extrapolate::Error).unwrap();
            let n = (q.0*q.0+q.1*q.1+q.2*q.2+q.3*q.3).sqrt();
            let q = [q.0/n, q.1/n, q.2/n, q.3/n];
            let mut s = setup(&profile, pose_xyz_deg(0.0, -1800.0, 0.0, 0.0, 0.0, 90.0), Vector3::x());
            s.frames.insert("wobj_car".into(), pose_xyz_deg(2000.0, 0.0, 600.0, 0.0, 0.0, 180.0));
            let line = format!("[[{x:.3},{y:.3},{z:.3}],[{:.6},{:.6},{:.6},{:.6}],[0,0,0,0],[{skid:.2},9E9,9E9,9E9,9E9,9E9]]\n", q[0], q[1], q[2], q[3]);
            let p0 = rapid(&line, "wobj_car");
            let c = text_after(&p0, &s, Direction::Correct);
            let back = text_after(&rapid(&c, "wobj_car"), &s, Direction::Zero);
            let p1 = rapid(&back, "wobj_car");
            let (a, b) = (&p0.files[0].position(0).unwrap(), &p1.files[0].position(0).unwrap());
            let (ta, tb) = (a.cartesian.as_ref().unwrap().translation().unwrap(), b.cartesian.as_ref().unwrap().translation().unwrap());
            for (u, v) in ta.iter().zip(tb) { prop_assert!((u - v).abs() <= 1.5e-3, "{line}{c}{back}"); }
            let ra = abb_quat(quat(a)).unwrap();
            let rb = abb_quat(quat(b)).unwrap();
            prop_assert!(ra.angle_to(&rb) < 1e-5, "{line}{c}{back}");
            // KUKA through text as well.
            let kl = format!("{{X {x:.3},Y {y:.3},Z {z:.3},A {:.4},B {:.4},C {:.4},S 2,T 0,E1 {skid:.2}}}\n", abc.0, abc.1, abc.2);
            let kc = text_after(&krl(&kl, "wobj_car"), &s, Direction::Correct);
            let kb = text_after(&krl(&kc, "wobj_car"), &s, Direction::Zero);
            let (ka, kz) = (krl(&kl, "w").files[0].position(0).unwrap().cartesian.clone().unwrap(), krl(&kb, "w").files[0].position(0).unwrap().cartesian.clone().unwrap());
            let (pa, pz) = (ka.pose().unwrap(), kz.pose().unwrap());
            prop_assert!((pa.translation.vector - pz.translation.vector).amax() <= 1.5e-3, "{kl}{kc}{kb}");
            prop_assert!(pa.rotation.angle_to(&pz.rotation).to_degrees() < 3e-4, "{kl}{kc}{kb}");
        }
    }
}
