//! What the transforms do with a robot's kinematics (docs/design.md §10): every changed
//! Cartesian target is checked before and after, and joint targets are moved through forward
//! and inverse kinematics instead of being refused.
//!
//! The rule, in one place:
//! - before: the written configuration must reach the target within the limits (a target
//!   whose `confdata` / Status-Turn selects another solution than the robot would take is a
//!   wrong program, and "the same configuration after" would mean nothing);
//! - after: the new pose must be reachable in that configuration within the limits, from the
//!   joints before without a swing or a turn of any axis ([`check_target`], [`check_move`]).
//!
//! Either failure is a [`RefusalKind::Reach`] refusal with the joints before and after.

use std::collections::BTreeMap;

use crate::geometry::Pose;
pub(crate) use crate::kinematics::correction::fmt_joints;
use crate::kinematics::reach::resolve_tool;
use crate::kinematics::{
    ConfigValue, JointRefusal, Joints, KinematicCheck, KinematicRefusal, Kinematics, check_move,
    check_target, select,
};
use crate::position::{Config, NumField, ParsedFile, Position, Program};
use crate::syntax::Edit;

use super::cell::Robot;
use super::policy::{Why, describe, tool_in_two_values};
use super::refusal::RefusalKind;
use super::rewrite::{
    DEG_DECIMALS, bits_edit, integer_edit, number_edit, pose_change, reversible_edits,
};

/// A robot arm as the transforms need it: its kinematics and the cell's tools on its flange.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// The arm's OPW model, joint signs, offsets and limits.
    pub kinematics: Kinematics,
    /// Tools overriding the program's (lower-case name → pose on the flange).
    pub tools: BTreeMap<String, Pose>,
}

impl Arm {
    /// The arm of `robot`, if the cell gives it kinematics.
    pub fn of(robot: &Robot) -> Option<Arm> {
        Some(Arm {
            kinematics: robot.kinematics.clone()?,
            tools: robot.tools.clone(),
        })
    }

    /// Every tool `p` (a target of file `own`) is used with, on the flange, in the order of
    /// [`Usage::tools`](crate::position::Usage::tools). A target's joints depend on the tool,
    /// so a check that holds with one says nothing of another.
    pub(crate) fn tools(
        &self,
        program: &Program,
        own: &ParsedFile,
        p: &Position,
    ) -> Result<Vec<Pose>, Why> {
        let what = describe(p);
        if let Some(why) = tool_in_two_values(
            p,
            "its joints depend on the tool, which puts the flange elsewhere in each",
        ) {
            return Err(why);
        }
        if let Some(u) = p.usage.unresolved_tool() {
            // (A tool is only ever unknown as a routine's parameter.)
            let name = match &u.cause {
                crate::position::UnresolvedCause::Parameter(n) => n.as_str(),
                _ => "a tool",
            };
            return Err(reach(
                format!(
                    "{what} is moved to on {} with `{name}`, a parameter of the routine: the tool is whichever one each caller passes, so its joints cannot be checked",
                    u.at
                ),
                "name the tool in the motion itself, or give the robot no kinematics",
            ));
        }
        let mut tools = Vec::with_capacity(1);
        for name in p.usage.tools() {
            let pose = resolve_tool(program, Some(own), &self.tools, name).map_err(|e| {
                reach(
                    format!("{what}: its joints cannot be checked: {}", e.message),
                    e.hint,
                )
            })?;
            tools.push(pose);
        }
        if tools.is_empty() {
            return Err(reach(
                format!("{what} is not used with a tool: its joints cannot be checked"),
                "use it in a motion instruction, or give the robot no kinematics",
            ));
        }
        Ok(tools)
    }

    /// The joints the written configuration selects for `flange` (in the robot base), or why
    /// the target is wrong as written.
    pub(crate) fn joints_before(
        &self,
        p: &Position,
        flange: &Pose,
        language: crate::position::Language,
    ) -> Result<Joints, Why> {
        let kin = &self.kinematics;
        let what = describe(p);
        let written = ConfigValue::written(&p.config);
        let Some(sel) = select(kin, flange, written.as_ref()) else {
            return Err(reach(
                format!(
                    "{what} is out of reach as written (the flange is {:.1} mm from the robot base)",
                    flange.translation.vector.norm()
                ),
                format!(
                    "check the target, its {} and tool, and the robot's kinematics",
                    language.dialect().vocabulary().frame
                ),
            ));
        };
        let solved = match &written {
            Some(w) => w.solved(kin, &sel.joints),
            None => ConfigValue::of_joints(language, kin, &sel.joints),
        };
        if !sel.config_matches {
            let w = written.map_or(String::new(), |w| w.to_string());
            return Err(reach(
                format!(
                    "{what} is written with configuration {w}, which does not reach it; the \
                     robot reaches it with {solved} at joints {}",
                    fmt_joints(&sel.joints)
                ),
                "write the configuration the robot reaches the target with (see reach)",
            ));
        }
        if !sel.within_limits {
            return Err(reach(
                format!(
                    "{what} is outside the joint limits as written: joints {}",
                    fmt_joints(&sel.joints)
                ),
                "move the target inside the robot's working range",
            ));
        }
        Ok(sel.joints)
    }

    /// Checks a Cartesian target moved from flange `before` to `after` (both in the robot
    /// base), written with its configuration as it is.
    pub(crate) fn check(
        &self,
        p: &Position,
        before: &Pose,
        after: &Pose,
        language: crate::position::Language,
    ) -> Result<(), Why> {
        self.joints_before(p, before, language)?;
        let written = ConfigValue::written(&p.config);
        let check = check_target(&self.kinematics, before, after, written.as_ref());
        self.verdict(p, &check, written.as_ref())
    }

    /// Checks a Cartesian target whose new pose `after` (in the robot base) will be written
    /// with configuration `config`, moving from joints `from` (the mirror image of the joints
    /// before, for `mirror`).
    pub(crate) fn check_from(
        &self,
        p: &Position,
        from: &Joints,
        after: &Pose,
        config: Option<&ConfigValue>,
    ) -> Result<(), Why> {
        let check = check_move(&self.kinematics, from, after, config);
        self.verdict(p, &check, config)
    }

    /// The refusal of a checked Cartesian target, if it is refused.
    fn verdict(
        &self,
        p: &Position,
        check: &KinematicCheck,
        config: Option<&ConfigValue>,
    ) -> Result<(), Why> {
        match (&check.refusal, check.before, check.after) {
            (None, ..) => Ok(()),
            (Some(why @ KinematicRefusal::Swing { .. }), Some(before), Some(after)) => {
                // The configuration the swung joints are in: the written one, or (no
                // configuration reaching the pose calmly) the one nearest.
                let kin = &self.kinematics;
                let (shown, unwritten) = match config {
                    Some(c) if !c.matches(kin, &after) => (
                        Some(c.solved(kin, &after)),
                        format!(" (it is written with {c}, which does not reach it)"),
                    ),
                    c => (c.copied(), String::new()),
                };
                Err(reach(
                    format!(
                        "{} {}{unwritten}: joints before {}, after {}",
                        describe(p),
                        why.swing_text(shown.as_ref()),
                        fmt_joints(&before),
                        fmt_joints(&after)
                    ),
                    swing_hint(why, "re-teach it with axis 5 a few degrees away from 0"),
                ))
            }
            (why, ..) => Err(reach(
                format!("{}: {}", describe(p), check.message().unwrap_or_default()),
                why.as_ref().map_or(String::new(), hint),
            )),
        }
    }

    /// A joint target's six axes, inside the limits.
    pub(crate) fn joints_of(&self, p: &Position) -> Result<Joints, Why> {
        let what = describe(p);
        let values: Option<Vec<f64>> = p
            .joints
            .iter()
            .take(6)
            .map(|f| f.as_ref().map(|f| f.value()))
            .collect();
        let j: Joints = match values.as_deref() {
            Some(&[a, b, c, d, e, f]) => [a, b, c, d, e, f],
            _ => {
                return Err(Why::new(
                    RefusalKind::Expression,
                    format!("{what} has axes that are not numbers"),
                    "write the axes as numeric literals",
                ));
            }
        };
        if !self.kinematics.within_limits(&j) {
            return Err(reach(
                format!(
                    "{what} is outside the joint limits as written: joints {}",
                    fmt_joints(&j)
                ),
                "move the target inside the robot's working range",
            ));
        }
        Ok(j)
    }

    /// The refusal of joint target `p` (joints `before`) that cannot be moved.
    pub(crate) fn joint_refusal(
        &self,
        p: &Position,
        before: &Joints,
        refused: &JointRefusal,
    ) -> Why {
        let why = &refused.why;
        let before = fmt_joints(before);
        let after = refused.after_text();
        if let KinematicRefusal::Swing { .. } = why {
            return reach(
                format!(
                    "{} {}: joints before {before}, after {after}",
                    describe(p),
                    why.swing_text(None),
                ),
                swing_hint(
                    why,
                    "re-teach it with axis 5 a few degrees away from 0, or write it as a \
                     Cartesian target (its configuration is then checked)",
                ),
            );
        }
        reach(
            format!(
                "{}: {why}: joints before {before}, after {after}",
                describe(p)
            ),
            hint(why),
        )
    }
}

/// The hint for a refusal other than a swing.
fn hint(why: &KinematicRefusal) -> String {
    match why {
        KinematicRefusal::OutsideLimit { axis, .. } => {
            format!("re-teach the target farther inside the range of axis {axis}")
        }
        _ => "the transform would move the robot through another posture: re-teach the target"
            .to_owned(),
    }
}

/// The hint for a [`KinematicRefusal::Swing`]: `at_singularity` at the wrist singularity.
fn swing_hint(why: &KinematicRefusal, at_singularity: &str) -> String {
    if why.at_wrist_singularity() {
        at_singularity.to_owned()
    } else {
        "re-teach the target away from the singular posture of the arm".to_owned()
    }
}

/// The size of a joint target's change, as a Cartesian target's is its written pose's: the
/// translation (mm) and rotation (°) between the flange of `before` (on the arm `kin_before`)
/// and of `after` (on `kin_after`), each in its own robot's base. A mirror's image is for
/// another robot, whose base the mirrored joints are written in.
pub(crate) fn flange_move(
    kin_before: &Kinematics,
    before: &Joints,
    kin_after: &Kinematics,
    after: &Joints,
) -> (f64, f64) {
    pose_change(&kin_before.forward(before), &kin_after.forward(after))
}

/// The step of the last decimal each axis of joint target `p` is written with (its literal's
/// decimals, at least [`DEG_DECIMALS`]): within half of it beyond a limit, the written text
/// reads as the limit ([`joint_target_correction`](crate::kinematics::joint_target_correction)).
pub(crate) fn written_steps(p: &Position) -> [f64; 6] {
    std::array::from_fn(|i| {
        let places = p
            .joints
            .get(i)
            .and_then(Option::as_ref)
            .map_or(DEG_DECIMALS, |f| f.lit().places(DEG_DECIMALS));
        10f64.powi(-(places as i32))
    })
}

/// `why`, naming the tool it holds with when `p` is used with more than one (a message that
/// names none is about every tool).
pub(crate) fn with_tool(mut why: Why, p: &Position, tool: &str) -> Why {
    if !p.usage.other_tools().is_empty() {
        why.message = format!("{} (with tool `{tool}`)", why.message);
    }
    why
}

/// A [`RefusalKind::Reach`] refusal.
fn reach(message: String, hint: impl Into<String>) -> Why {
    Why::new(RefusalKind::Reach, message, hint)
}

/// Edits that make a joint target's axes say `new` (unchanged axes keep their text).
pub(crate) fn joint_edits(p: &Position, new: &Joints) -> Vec<Edit> {
    p.joints
        .iter()
        .zip(new)
        .filter_map(|(f, v)| number_edit(f, *v, DEG_DECIMALS))
        .collect()
}

/// [`joint_edits`] written so that `inverse` (the inverse transform of the joints read back
/// from the written text) gives back the original text where it can (docs/design.md §5, round
/// trip; `rewrite::reversible_edits`, with [`JOINT_ROUND_TRIP_STEPS`]).
pub(crate) fn reversible_joint_edits(
    p: &Position,
    new: &Joints,
    inverse: impl Fn(Joints) -> Option<Joints>,
) -> Vec<Edit> {
    match <&[Option<NumField>; 6]>::try_from(p.joints.as_slice()) {
        Ok(fields) => reversible_edits(fields, *new, DEG_DECIMALS, JOINT_ROUND_TRIP_STEPS, inverse),
        Err(_) => joint_edits(p, new),
    }
}

/// How many times a corrected joint target's text is stepped toward one that `zero` reads back
/// as the original (`rewrite::reversible_edits`). Near the wrist singularity the inverse turns
/// axes 4 and 6 by several times the rounding of axis 5 — 3.4 times at A5 = 0.5° on r1, growing
/// as the correction's tilt over A5² — so plain rounding, and every choice within one unit, can
/// miss the original's last decimal (A4 = 40 came back 39.9998, A6 = 60 as 60.0001). The
/// inverse is near the identity axis by axis (1.05 on axis 4 there), so a step by the miss
/// closes it: on 508 random joint targets on r1, one step brought back 15 of the 27 that no
/// choice within one unit did, two 17, more none (the rest are near a singular posture of the
/// arm); three leave room.
const JOINT_ROUND_TRIP_STEPS: usize = 3;

/// Edits that make a written configuration say `new` (fields already saying it are kept).
pub(crate) fn config_edits(config: &Config, new: &ConfigValue) -> Vec<Edit> {
    match (config, new) {
        (Config::Quadrants(fields), ConfigValue::Quadrants(values)) => fields
            .iter()
            .zip(values)
            .filter_map(|(f, v)| integer_edit(f, i64::from(*v)))
            .collect(),
        (Config::StatusTurn { status, turn }, ConfigValue::StatusTurn { status: s, turn: t }) => {
            let mut edits = Vec::new();
            if let Some(s) = s {
                edits.extend(bits_edit(status, *s));
            }
            if let Some(t) = t {
                edits.extend(bits_edit(turn, *t));
            }
            edits
        }
        _ => Vec::new(),
    }
}
