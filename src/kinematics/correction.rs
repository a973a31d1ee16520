//! Kinematic checks for the transforms: is a corrected or mirrored target still reachable,
//! inside the limits and in the same configuration; joint targets moved with the track; and the
//! configuration of a mirrored target found by IK.

use crate::geometry::Pose;

use super::opw::distance2;
use super::{ConfigValue, Joints, Kinematics, select};

/// Why a transformed target would be refused.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum KinematicRefusal {
    /// The new pose has no joint solution.
    Unreachable,
    /// The new pose is reachable in the configuration only with a joint outside its limits.
    OutsideLimit {
        /// The axis, 1-based.
        axis: usize,
        /// Its angle in the new pose, degrees.
        value: f64,
        /// Its `[min, max]`, degrees.
        limits: [f64; 2],
    },
    /// The new pose needs another configuration (`before` is the written or original one).
    ConfigChange {
        /// The written (or original) configuration.
        before: ConfigValue,
        /// The configuration the new pose needs.
        after: ConfigValue,
    },
}

impl std::fmt::Display for KinematicRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KinematicRefusal::Unreachable => write!(f, "the transformed target is out of reach"),
            KinematicRefusal::OutsideLimit {
                axis,
                value,
                limits,
            } => write!(
                f,
                "the transformed target needs axis {axis} = {value:.3}°, outside its limits [{}, {}]",
                limits[0], limits[1]
            ),
            KinematicRefusal::ConfigChange { before, after } => write!(
                f,
                "the transformed target needs configuration {after} instead of {before}"
            ),
        }
    }
}

/// The joints of a target before and after a transform, and whether the transform is refused.
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicCheck {
    /// The solution of the original pose the written configuration selects.
    pub before: Option<Joints>,
    /// The solution of the new pose in the same configuration nearest to `before` (or the
    /// nearest outside the limits / in another configuration when refused).
    pub after: Option<Joints>,
    /// Why the transform is refused; `None` when the new pose is accepted.
    pub refusal: Option<KinematicRefusal>,
}

fn fmt_joints(j: &Joints) -> String {
    let v: Vec<String> = j.iter().map(|a| format!("{a:.3}")).collect();
    format!("[{}]", v.join(", "))
}

impl KinematicCheck {
    /// The refusal as a message with the joints before and after (degrees), for a transform to
    /// report by the target's name; `None` when the transform may go ahead.
    pub fn message(&self) -> Option<String> {
        let r = self.refusal.as_ref()?;
        let before = self
            .before
            .map_or("none (not reachable)".to_owned(), |j| fmt_joints(&j));
        let after = self.after.map_or("none".to_owned(), |j| fmt_joints(&j));
        Some(format!("{r}: joints before {before}, after {after}"))
    }
}

fn first_outside(kin: &Kinematics, j: &Joints) -> Option<KinematicRefusal> {
    let m = kin.limit_margins(j);
    let axis = (0..6).find(|&i| m[i] < -1e-9)?;
    Some(KinematicRefusal::OutsideLimit {
        axis: axis + 1,
        value: j[axis],
        limits: kin.limits[axis],
    })
}

/// Checks a Cartesian target moved from flange pose `before` to `after` (both in the robot
/// base, `B(s)⁻¹·W·T·TOOL⁻¹`). `written` is the target's configuration (ABB confdata, KUKA
/// Status/Turn), `None` if it writes none: then the solution nearest to the original joints in
/// the same arm and wrist choice must exist.
pub fn check_target(
    kin: &Kinematics,
    before: &Pose,
    after: &Pose,
    written: Option<&ConfigValue>,
) -> KinematicCheck {
    let j0 = select(kin, before, written).map(|s| s.joints);
    let all_after = kin.inverse(after, j0.map(|j| j[3]));
    if all_after.is_empty() {
        return KinematicCheck {
            before: j0,
            after: None,
            refusal: Some(KinematicRefusal::Unreachable),
        };
    }
    let Some(j0) = j0 else {
        // The original pose itself is out of reach: nothing to compare with.
        let a = select(kin, after, written).map(|s| s.joints);
        return KinematicCheck {
            before: None,
            after: a,
            refusal: a.and_then(|a| first_outside(kin, &a)),
        };
    };
    let within = kin.solutions_within_limits(after, Some(j0[3]));
    let nearest = |c: &mut dyn Iterator<Item = Joints>| {
        c.min_by(|a, b| distance2(a, &j0).total_cmp(&distance2(b, &j0)))
    };
    let same_config = |j: &Joints| match written {
        Some(w) => w.matches(kin, j),
        None => kin.arm(j) == kin.arm(&j0) && (j[4] >= 0.0) == (j0[4] >= 0.0),
    };
    if let Some(a) = nearest(&mut within.iter().copied().filter(|j| same_config(j))) {
        return KinematicCheck {
            before: Some(j0),
            after: Some(a),
            refusal: None,
        };
    }
    let wide = Kinematics {
        limits: [[-720.0, 720.0]; 6],
        ..kin.clone()
    };
    let outside = nearest(
        &mut all_after
            .iter()
            .flat_map(|j| wide.turns(j))
            .filter(|j| same_config(j)),
    );
    if let Some(a) = outside {
        return KinematicCheck {
            before: Some(j0),
            after: Some(a),
            refusal: first_outside(kin, &a),
        };
    }
    let other = nearest(&mut within.iter().copied()).unwrap_or(all_after[0]);
    let language_of = |c: Option<&ConfigValue>| match c {
        Some(ConfigValue::StatusTurn { .. }) => crate::position::Language::Krl,
        _ => crate::position::Language::Rapid,
    };
    let lang = language_of(written);
    let before_config = written
        .copied()
        .unwrap_or_else(|| ConfigValue::of_joints(lang, kin, &j0));
    KinematicCheck {
        before: Some(j0),
        after: Some(other),
        refusal: Some(KinematicRefusal::ConfigChange {
            before: before_config,
            after: before_config.solved(kin, &other),
        }),
    }
}

/// A joint target moved with the track: `J'` with `FK(J') = C·FK(J)`, where `C` is the change
/// in the robot base frame — `D(s)⁻¹` for `correct`, `D(s)` for `zero` (the Cartesian
/// correction `B·D⁻¹·B⁻¹` seen from the base; no work object and no tool enter, and `B(s)`
/// cancels). The solution is the one nearest to `J` in the same arm and wrist choice, turns of
/// axes 4 and 6 kept.
pub fn joint_target_correction(
    kin: &Kinematics,
    joints: &Joints,
    change: &Pose,
) -> Result<Joints, KinematicRefusal> {
    let target = change * kin.forward(joints);
    if let Some(j) = kin.nearest(&target, joints, true) {
        return Ok(j);
    }
    let check = check_target(kin, &kin.forward(joints), &target, None);
    Err(check.refusal.unwrap_or(KinematicRefusal::Unreachable))
}

/// The rule's mirror image of joints about the xz plane of the base (`y → −y`, mirror-image
/// robots): `(−θ1, θ2, θ3, −θ4, θ5, −θ6)`. Exact for arms without a sideways offset (`b = 0`)
/// whose axes 1, 4 and 6 have no joint offset.
pub fn mirrored_joints(j: &Joints) -> Joints {
    [-j[0], j[1], j[2], -j[3], j[4], -j[5]]
}

/// The joints and configuration IK finds for a mirrored target: the solution of the mirrored
/// flange pose (in the mirror robot's base) within the limits nearest to the rule's mirror
/// image of the original joints. `None` when the mirrored pose is out of reach within the
/// limits.
pub fn mirror_config_by_ik(
    kin: &Kinematics,
    mirrored_flange: &Pose,
    original: &Joints,
    language: crate::position::Language,
) -> Option<(Joints, ConfigValue)> {
    let reference = mirrored_joints(original);
    let j = kin.nearest(mirrored_flange, &reference, false)?;
    Some((j, ConfigValue::of_joints(language, kin, &j)))
}
