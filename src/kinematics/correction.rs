//! Kinematic checks for the transforms: is a corrected or mirrored target still reachable,
//! inside the limits and in the same configuration, without a swing of its joints; joint
//! targets moved with the track; and the configuration of a mirrored target found by IK.
//!
//! One rule runs through them: a transformed target is where the robot goes *from* the
//! original joints, each axis by the least it must turn (no axis moved by a whole turn to stay
//! within its limits, none swung through tens of degrees by a correction of hundredths).
//! Where that is not possible the target is refused, with what it would need.

use crate::geometry::{Pose, wrap_deg};

use super::opw::distance2;
use super::{ConfigValue, Joints, Kinematics, select};

/// Why a transformed target would be refused.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum KinematicRefusal {
    /// The new pose has no joint solution.
    Unreachable,
    /// The new pose is reached in the configuration, from the original joints, only with a
    /// joint outside its limits.
    OutsideLimit {
        /// The axis, 1-based.
        axis: usize,
        /// Its angle in the new pose, degrees.
        value: f64,
        /// Its `[min, max]`, degrees.
        limits: [f64; 2],
    },
    /// The new pose is reached (in the written configuration; a joint target in the same arm
    /// and wrist) only by turning some axis by more than [`WRIST_TURN_LIMIT_DEG`]. At or near
    /// the wrist singularity these are axes 4 and 6: the tiny tilt a correction adds decides
    /// which way axis 4 points, and axis 6 makes up for it. Elsewhere it is an arm axis near a
    /// singular posture of the arm.
    Swing {
        /// Axis 5 before, degrees.
        a5: f64,
        /// How far each axis would turn (after − before), degrees.
        turns: Joints,
        /// The distance of the joints before from the wrist singularity, degrees
        /// ([`Kinematics::wrist_singularity_deg`]).
        from_singularity: f64,
        /// The joints that reach the new pose.
        after: Joints,
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
                "the transformed target needs axis {axis} = {}°, outside its limits [{}, {}]",
                beyond_limit(*value, *limits),
                limits[0],
                limits[1]
            ),
            KinematicRefusal::Swing { .. } => write!(f, "the target {}", self.swing_text(None)),
            KinematicRefusal::ConfigChange { before, after } => write!(
                f,
                "the transformed target needs configuration {after} instead of {before}"
            ),
        }
    }
}

/// `value` with the fewest decimals, three or more, that still show it outside `limits`: an
/// axis 3e-5° beyond its limit of −125° reads `-125.00003`, where three decimals would print
/// the limit itself.
fn beyond_limit(value: f64, [lo, hi]: [f64; 2]) -> String {
    (3..=12)
        .map(|d| format!("{value:.d$}"))
        .find(|t| t.parse::<f64>().is_ok_and(|v| v < lo || v > hi))
        .unwrap_or_else(|| value.to_string())
}

/// An angle with one decimal, or with as many as show that a small one is not zero
/// (`A5 = -0.01°`, not `-0.0°`).
fn small_angle(v: f64) -> String {
    (1..=6)
        .map(|d| format!("{v:.d$}"))
        .find(|t| v == 0.0 || t.parse::<f64>().is_ok_and(|r| r != 0.0))
        .unwrap_or_else(|| format!("{v:e}"))
}

impl KinematicRefusal {
    /// The predicate of a [`KinematicRefusal::Swing`] for a target's name: `is at the wrist
    /// singularity (A5 = 0.0°): reaching the transformed pose would turn A4 by 46.6° and A6 by
    /// -46.7°`; with `config`, the configuration the pose is reached in is named (`reaching the
    /// transformed pose with configuration S 6 T 18 would turn …`). Empty for the other
    /// refusals.
    pub fn swing_text(&self, config: Option<&ConfigValue>) -> String {
        let KinematicRefusal::Swing { a5, turns, .. } = self else {
            return String::new();
        };
        let beyond = |i: usize| turns[i].abs() > WRIST_TURN_LIMIT_DEG;
        // Axes 4 and 6 are named together: at the singularity their turns cancel, which is
        // what tells the swing from a real move.
        let wrist = beyond(3) || beyond(5);
        let named: Vec<String> = (0..6)
            .filter(|&i| beyond(i) || (wrist && (i == 3 || i == 5)))
            .map(|i| format!("A{} by {:.1}°", i + 1, turns[i]))
            .collect();
        let list = match named.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            _ => named.join(""),
        };
        let with = config.map_or(String::new(), |c| format!(" with configuration {c}"));
        let turns = format!("reaching the transformed pose{with} would turn {list}");
        if self.at_wrist_singularity() {
            format!(
                "is at the wrist singularity (A5 = {}°): {turns}",
                small_angle(*a5)
            )
        } else {
            format!("is near a singular posture of the arm: {turns}")
        }
    }

    /// Whether this is a [`KinematicRefusal::Swing`] of axis 4 or 6 within a few degrees of the
    /// wrist singularity: there the swing is the singularity's own; an arm axis that jumps is
    /// not named after it.
    pub fn at_wrist_singularity(&self) -> bool {
        matches!(self, KinematicRefusal::Swing { from_singularity, turns, .. }
            if *from_singularity < WRIST_SINGULAR_DEG
                && (turns[3].abs() > WRIST_TURN_LIMIT_DEG || turns[5].abs() > WRIST_TURN_LIMIT_DEG))
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

/// `[10.000, 20.000, …]` degrees.
pub(crate) fn fmt_joints(j: &Joints) -> String {
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

/// Each solution with every axis turned by whole turns to lie nearest `from`: where the arm
/// goes from `from` without winding any axis (limits not applied). A configuration's sign or
/// quadrant is then the posture's, never one a full turn buys (axis 5 at −359.97° is `cfx`
/// 1 by its sign, and no robot reaches it).
fn continuations<'a>(
    solutions: &'a [Joints],
    from: &'a Joints,
) -> impl Iterator<Item = Joints> + 'a {
    solutions
        .iter()
        .map(|s| std::array::from_fn(|i| from[i] + wrap_deg(s[i] - from[i])))
}

fn nearest_to(from: &Joints, c: impl Iterator<Item = Joints>) -> Option<Joints> {
    c.min_by(|a, b| distance2(a, from).total_cmp(&distance2(b, from)))
}

/// The [`KinematicRefusal::Swing`] of moving from `before` to `after`, if some axis turns by
/// more than [`WRIST_TURN_LIMIT_DEG`].
fn swing(kin: &Kinematics, before: &Joints, after: &Joints) -> Option<KinematicRefusal> {
    let turns: Joints = std::array::from_fn(|i| after[i] - before[i]);
    turns
        .iter()
        .any(|t| t.abs() > WRIST_TURN_LIMIT_DEG)
        .then(|| KinematicRefusal::Swing {
            a5: before[4],
            turns,
            from_singularity: kin.wrist_singularity_deg(before),
            after: *after,
        })
}

/// Checks a Cartesian target moved from flange pose `before` to `after` (both in the robot
/// base, `B(s)⁻¹·W·T·TOOL⁻¹`). `written` is the target's configuration (ABB confdata, KUKA
/// Status/Turn), `None` if it writes none: then the same arm and wrist as the original joints
/// (see [`check_move`]).
pub fn check_target(
    kin: &Kinematics,
    before: &Pose,
    after: &Pose,
    written: Option<&ConfigValue>,
) -> KinematicCheck {
    let Some(j0) = select(kin, before, written).map(|s| s.joints) else {
        // The original pose itself is out of reach: nothing to compare with.
        if kin.inverse(after, None).is_empty() {
            return KinematicCheck {
                before: None,
                after: None,
                refusal: Some(KinematicRefusal::Unreachable),
            };
        }
        let a = select(kin, after, written).map(|s| s.joints);
        return KinematicCheck {
            before: None,
            after: a,
            refusal: a.and_then(|a| first_outside(kin, &a)),
        };
    };
    check_move(kin, &j0, after, written)
}

/// Checks the move from joints `from` to flange pose `after` (in the robot base) with the
/// configuration `config` the target will be written with (`None`: none written, then the
/// same arm and wrist as `from`, [`Kinematics::same_branch`]):
///
/// 1. the solution of `after` in `config` that each axis reaches from `from` by its least turn
///    is taken if no axis turns by more than [`WRIST_TURN_LIMIT_DEG`] (one within the limits
///    first); outside the limits it is [`KinematicRefusal::OutsideLimit`] with the angle it
///    needs (never the same angle a turn away, which the limits would allow but the robot
///    would wind through);
/// 2. else what `config` selects within the limits, as the controller does, is taken if it
///    does not swing, and refused as [`KinematicRefusal::Swing`] if it does: near the wrist
///    singularity KUKA Status/Turn or ABB confdata pins the wrist to a solution tens of
///    degrees away from the one the correction's tilt leads to;
/// 3. else, if `config` reaches `after` only outside the limits with a swing, the swing;
/// 4. else [`KinematicRefusal::ConfigChange`], naming the configuration of the solution
///    nearest `from` (an axis 5 that crosses 0 needs the other `cfx` / Status bit 2, not a
///    turn of axis 5) — or, if that solution swings the wrist at its singularity, the swing.
pub fn check_move(
    kin: &Kinematics,
    from: &Joints,
    after: &Pose,
    config: Option<&ConfigValue>,
) -> KinematicCheck {
    let solutions = kin.inverse(after, Some(from[3]));
    let result = |a: Option<Joints>, refusal: Option<KinematicRefusal>| KinematicCheck {
        before: Some(*from),
        after: a,
        refusal,
    };
    if solutions.is_empty() {
        return result(None, Some(KinematicRefusal::Unreachable));
    }
    let same_config = |j: &Joints| match config {
        Some(c) => c.matches(kin, j),
        None => kin.same_branch(from, j),
    };
    let followed: Vec<Joints> = continuations(&solutions, from)
        .filter(|j| same_config(j))
        .collect();
    let calm = || {
        followed
            .iter()
            .filter(|a| swing(kin, from, a).is_none())
            .copied()
    };
    let calm = nearest_to(from, calm().filter(|a| kin.within_limits(a)))
        .or_else(|| nearest_to(from, calm()));
    if let Some(a) = calm {
        return result(Some(a), first_outside(kin, &a));
    }
    let selected = nearest_to(
        from,
        kin.solutions_within_limits(after, Some(from[3]))
            .into_iter()
            .filter(|j| same_config(j)),
    );
    if let Some(a) = selected.or_else(|| nearest_to(from, followed.iter().copied())) {
        return result(Some(a), swing(kin, from, &a));
    }
    let other = nearest_to(from, continuations(&solutions, from)).unwrap_or(solutions[0]);
    if let Some(s) = swing(kin, from, &other).filter(KinematicRefusal::at_wrist_singularity) {
        // At the wrist singularity axis 5 crossing 0 flips the configuration and swings the
        // wrist alike: no configuration reaches the pose calmly, and the swing is what to fix.
        return result(Some(other), Some(s));
    }
    let language = match config {
        Some(ConfigValue::StatusTurn { .. }) => crate::position::Language::Krl,
        _ => crate::position::Language::Rapid,
    };
    let before = config
        .copied()
        .unwrap_or_else(|| ConfigValue::of_joints(language, kin, from));
    result(
        Some(other),
        Some(KinematicRefusal::ConfigChange {
            before,
            after: before.solved(kin, &other),
        }),
    )
}

/// The most a transform may turn any axis of a target, degrees (named for the wrist, whose
/// axes are the ones that exceed it).
///
/// A track correction tilts the flange by hundredths of a degree and shifts it by a few mm,
/// which turns the arm's axes by about a tenth of a degree; the wrist takes up that rotation
/// with axes 4 and 6 turning by about `rotation / sin(A5)`: 0.15° at most over every sample
/// joint target. At the singularity (A5 = 0, axes 4 and 6 aligned) the pose reached with a
/// tiny tilt needs axis 4 to point along the tilt, whatever it was, and axis 6 to turn it
/// back: tens of degrees (47° and 63° on the samples), a swing of the dress pack and of every
/// motion after. 5° lies well between the two, and is exceeded by a real correction (≤ 0.1°
/// of rotation) only within about 1° of the singularity, where the swing is no longer the
/// correction's own. The same holds for Cartesian targets, whose written configuration then
/// selects the swung solution.
pub const WRIST_TURN_LIMIT_DEG: f64 = 5.0;

/// Within this many degrees of the wrist singularity a refused turn is named after it (the
/// distance the reach check warns within by default, `ReachOptions::singularity_deg`).
const WRIST_SINGULAR_DEG: f64 = 5.0;

/// A joint target moved with the track: `J'` with `FK(J') = C·FK(J)`, where `C` is the change
/// in the robot base frame — `D(s)⁻¹` for `correct`, `D(s)` for `zero` (the Cartesian
/// correction `B·D⁻¹·B⁻¹` seen from the base; no work object and no tool enter, and `B(s)`
/// cancels).
///
/// `J'` is the solution in `J`'s arm and wrist that each axis reaches from `J` by its least
/// turn: axis 4/6 turns are kept, and no axis is moved by a whole turn to stay within its
/// limits (axis 1 at 180° that the correction takes to 180.007° is refused, not written as
/// −179.993°, a turn of the whole arm). Refused: a `J'` that turns some axis by more than
/// [`WRIST_TURN_LIMIT_DEG`] ([`KinematicRefusal::Swing`]: at the wrist singularity the exact
/// new pose is only reached by swinging the wrist, and nothing nearer reaches it), and one
/// outside the limits.
///
/// A refusal comes with the joints after where some solution in the branch reaches the new
/// pose ([`JointRefusal`]).
///
/// `written_step` is, per axis, the step of the last decimal the axis will be written with
/// (1e-4° for four decimals). An axis the correction takes beyond a limit by less than half
/// of it is set at the limit: written, it could not say the difference (a joint target at its
/// limit, corrected inward and written to four decimals, comes back from `zero` 3e-5° beyond
/// it only by that rounding).
pub fn joint_target_correction(
    kin: &Kinematics,
    joints: &Joints,
    change: &Pose,
    written_step: &[f64; 6],
) -> Result<Joints, Box<JointRefusal>> {
    let target = change * kin.forward(joints);
    let refused =
        |after: Option<Joints>, why: KinematicRefusal| Box::new(JointRefusal { why, after });
    let solutions = kin.inverse(&target, Some(joints[3]));
    if solutions.is_empty() {
        return Err(refused(None, KinematicRefusal::Unreachable));
    }
    let followed = nearest_to(
        joints,
        continuations(&solutions, joints).filter(|j| kin.same_branch(joints, j)),
    );
    let Some(mut j) = followed else {
        // Only another arm or wrist reaches it.
        let check = check_move(kin, joints, &target, None);
        let why = check.refusal.unwrap_or(KinematicRefusal::Unreachable);
        return Err(refused(check.after, why));
    };
    if let Some(s) = swing(kin, joints, &j) {
        return Err(refused(Some(j), s));
    }
    for ((a, [lo, hi]), step) in j.iter_mut().zip(kin.limits).zip(written_step) {
        let slack = step / 2.0;
        if *a < lo && *a > lo - slack {
            *a = lo;
        } else if *a > hi && *a < hi + slack {
            *a = hi;
        }
    }
    match first_outside(kin, &j) {
        Some(r) => Err(refused(Some(j), r)),
        None => Ok(j),
    }
}

/// Why a joint target cannot be moved ([`joint_target_correction`]), and the joints that would
/// reach its new pose in its branch, if any (outside the limits, or swung).
#[derive(Clone, Debug, PartialEq)]
pub struct JointRefusal {
    /// Why it is refused.
    pub why: KinematicRefusal,
    /// The joints that would reach the new pose, if any.
    pub after: Option<Joints>,
}

impl JointRefusal {
    /// The joints after, for a message: `[…]`, or that no solution in the branch reaches the
    /// new pose.
    pub(crate) fn after_text(&self) -> String {
        self.after
            .map_or("none in the same branch".to_owned(), |j| fmt_joints(&j))
    }
}

/// The rule's mirror image of joints about the xz plane of the base (`y → −y`, mirror-image
/// robots): `(−θ1, θ2, θ3, −θ4, θ5, −θ6)`. Exact for arms without a sideways offset (`b = 0`)
/// whose axes 1, 4 and 6 have no joint offset.
pub fn mirrored_joints(j: &Joints) -> Joints {
    [-j[0], j[1], j[2], -j[3], j[4], -j[5]]
}

/// The joints and configuration IK finds for a mirrored target: the mirrored flange pose (in
/// the mirror robot's base) reached from the rule's mirror image of the original joints
/// ([`mirrored_joints`]) in its arm and wrist, each axis by its least turn ([`check_move`]
/// without a configuration) — the rule's image itself where the image is exact.
///
/// That image outside the limits is refused ([`KinematicRefusal::OutsideLimit`], with the
/// joints): the mirror-image robot cannot take the mirror-image posture, and the solution
/// within the limits nearest to it is then the same pose a turn of an axis away, or another
/// arm or wrist (an axis 1 limited to [−170°, 185°] reaches the image of 178° as 182°, or
/// behind itself at 2°). Where only a swing or another branch reaches the pose, the solution
/// within the limits nearest to the rule's image is given, for the written configuration's
/// check to name the swing ([`check_move`]); no solution at all is
/// [`KinematicRefusal::Unreachable`].
pub fn mirror_config_by_ik(
    kin: &Kinematics,
    mirrored_flange: &Pose,
    original: &Joints,
    language: crate::position::Language,
) -> Result<(Joints, ConfigValue), Box<JointRefusal>> {
    let reference = mirrored_joints(original);
    let check = check_move(kin, &reference, mirrored_flange, None);
    let j = match (check.refusal, check.after) {
        (None, Some(j)) => j,
        (Some(why @ KinematicRefusal::OutsideLimit { .. }), after) => {
            return Err(Box::new(JointRefusal { why, after }));
        }
        _ => kin
            .nearest(mirrored_flange, &reference, false)
            .ok_or_else(|| {
                Box::new(JointRefusal {
                    why: KinematicRefusal::Unreachable,
                    after: None,
                })
            })?,
    };
    Ok((j, ConfigValue::of_joints(language, kin, &j)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose_xyz_deg;

    /// A track correction in the robot base: 0.5 mm along x and a 0.02° tilt about x.
    fn change() -> Pose {
        pose_xyz_deg(0.5, 0.0, 0.0, 0.02, 0.0, 0.0)
    }

    /// Four decimals on every axis.
    const STEP: [f64; 6] = [1e-4; 6];

    fn arm() -> Kinematics {
        super::super::model("abb_irb4600_40_255")
            .expect("bundled")
            .kinematics()
    }

    /// The position error of `j`'s flange from `target`, mm.
    fn mm_from(kin: &Kinematics, j: &Joints, target: &Pose) -> f64 {
        (kin.forward(j).translation.vector - target.translation.vector).norm()
    }

    /// At the singular wrist (A5 = 0) the corrected pose is reached only with axis 4 along
    /// the correction's tilt and axis 6 turned back: refused, with the turns. A5 = 0 with A4/A6
    /// split 30/−30 is the same pose as all zeros, so the same joints reach it; only the turns
    /// differ (the written split is what would be lost).
    #[test]
    fn a_singular_wrist_is_refused_with_the_turns_it_would_need() {
        let kin = arm();
        let c = change();
        let mut afters = Vec::new();
        for j in [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 30.0, 0.0, -30.0],
            [0.0, 0.0, 0.0, 10.0, 1e-6, -10.0],
        ] {
            let target = c * kin.forward(&j);
            let refused = joint_target_correction(&kin, &j, &c, &STEP).expect_err("refused");
            let err = refused.why;
            assert_eq!(
                refused.after,
                match err {
                    KinematicRefusal::Swing { after, .. } => Some(after),
                    _ => None,
                }
            );
            let KinematicRefusal::Swing {
                a5,
                turns,
                from_singularity,
                after,
            } = err
            else {
                panic!("{err:?}");
            };
            let (a4_turn, a6_turn) = (turns[3], turns[5]);
            assert_eq!(a5, j[4]);
            assert!(from_singularity < 1e-5, "{from_singularity}");
            assert!(err.at_wrist_singularity());
            // The joints refused do reach the corrected pose exactly.
            assert!(mm_from(&kin, &after, &target) < 1e-6, "{after:?}");
            assert!((after[3] - j[3] - a4_turn).abs() < 1e-12);
            assert!((after[5] - j[5] - a6_turn).abs() < 1e-12);
            assert!(
                a4_turn.abs() > WRIST_TURN_LIMIT_DEG && a6_turn.abs() > WRIST_TURN_LIMIT_DEG,
                "{a4_turn} {a6_turn}"
            );
            // Axes 4 and 6 aligned: the flange's roll is A4 + A6 (every sign +1 on this arm),
            // which the correction changes by a small fraction of a degree only, so the turns
            // cancel.
            assert!((a4_turn + a6_turn).abs() < 0.1, "{a4_turn} {a6_turn}");
            // The arm axes and A5 move by the correction's own size.
            for i in [0, 1, 2, 4] {
                assert!((after[i] - j[i]).abs() < 0.1, "axis {}: {after:?}", i + 1);
            }
            afters.push(after);
            let text = err.to_string();
            // A5 with the decimals that show it is not 0 when it is not.
            let a5 = if j[4] == 0.0 { "0.0" } else { "0.000001" };
            assert!(
                text.starts_with(&format!("the target is at the wrist singularity (A5 = {a5}°): reaching the transformed pose would turn A4 by ")),
                "{text}"
            );
        }
        // The first two written poses are one pose (A4 + A6 = 0 at A5 = 0): one answer for
        // both. The third is 1e-6° off it: its answer differs by the thousandths of a degree
        // that tilt makes in the direction of axis 4.
        for (a, tol) in [(&afters[1], 1e-6), (&afters[2], 0.01)] {
            let close = a.iter().zip(&afters[0]).all(|(x, y)| (x - y).abs() < tol);
            assert!(close, "{a:?} {:?}", afters[0]);
        }
    }

    /// Away from the singularity the joint target is moved as before: FK(J') = C·FK(J) and
    /// axes 4 and 6 turn by a tenth of a degree at most (about rotation / sin A5).
    #[test]
    fn a_bent_wrist_is_moved_with_small_turns_of_axes_4_and_6() {
        let kin = arm();
        let c = change();
        for j in [
            [0.0, -20.0, 30.0, 0.0, 80.0, 0.0],
            [0.0, -20.0, 30.0, 15.0, 10.0, -15.0],
            [30.0, 10.0, -20.0, -45.0, -30.0, 60.0],
        ] {
            let target = c * kin.forward(&j);
            let jc = joint_target_correction(&kin, &j, &c, &STEP).expect("moved");
            assert!(mm_from(&kin, &jc, &target) < 1e-6, "{jc:?}");
            assert!(
                kin.forward(&jc).rotation.angle_to(&target.rotation) < 1e-9,
                "{jc:?}"
            );
            for i in [3, 5] {
                assert!((jc[i] - j[i]).abs() < 0.2, "axis {}: {jc:?}", i + 1);
            }
        }
    }

    /// A swing of an arm axis, away from the wrist singularity, is not named after it; the
    /// wrist's turns are named together even when one of them stays under the limit, with the
    /// configuration they are reached in and an A5 of hundredths printed as such.
    #[test]
    fn a_swing_away_from_the_wrist_singularity_is_not_called_singular() {
        let arm_jump = KinematicRefusal::Swing {
            a5: 45.0,
            turns: [150.0, 0.1, -0.2, 0.1, 0.0, 0.1],
            from_singularity: 45.0,
            after: [0.0; 6],
        };
        assert!(!arm_jump.at_wrist_singularity());
        assert_eq!(
            arm_jump.to_string(),
            "the target is near a singular posture of the arm: reaching the transformed pose would turn A1 by 150.0°"
        );
        let wrist = KinematicRefusal::Swing {
            a5: -0.01,
            turns: [0.03, -0.03, 0.0, 115.61, -0.02, 3.0],
            from_singularity: 0.01,
            after: [0.0; 6],
        };
        assert!(wrist.at_wrist_singularity());
        let config = ConfigValue::StatusTurn {
            status: Some(6),
            turn: Some(18),
        };
        assert_eq!(
            wrist.swing_text(Some(&config)),
            "is at the wrist singularity (A5 = -0.01°): reaching the transformed pose with configuration S 6 T 18 would turn A4 by 115.6° and A6 by 3.0°"
        );
        // A5 with one decimal, or as many as show that it is not 0.
        assert_eq!(small_angle(0.0), "0.0");
        assert_eq!(small_angle(-0.0123), "-0.01");
        assert_eq!(small_angle(45.04), "45.0");
    }

    /// A limit is printed with the decimals that show the value beyond it.
    #[test]
    fn a_value_just_beyond_a_limit_is_printed_beyond_it() {
        let r = |value| KinematicRefusal::OutsideLimit {
            axis: 5,
            value,
            limits: [-125.0, 120.0],
        };
        assert_eq!(
            r(-125.00003).to_string(),
            "the transformed target needs axis 5 = -125.00003°, outside its limits [-125, 120]"
        );
        assert_eq!(
            r(120.036).to_string(),
            "the transformed target needs axis 5 = 120.036°, outside its limits [-125, 120]"
        );
    }
}
