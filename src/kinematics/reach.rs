//! `reach`: every target of a program through the robot's kinematics — reachable, its joints,
//! whether the written configuration reaches it, the margin to each joint limit, and a warning
//! near the wrist singularity.
//!
//! The flange pose of a Cartesian target in the robot base is
//! `F = B(s)⁻¹ · W · T · TOOL⁻¹` (`B(s) = Trans(s·a)·B_0` at the target's own skid, `W` its
//! resolved work object, `TOOL` its tool frame on the flange). Joint targets are checked
//! against the limits as written.

use std::collections::BTreeMap;

use crate::geometry::Pose;
use crate::position::{FrameKind, ParsedFile, Position, Program, Skid};
use crate::track::TrackError;
use crate::transform::Robot;
use crate::transform::policy::{describe, resolve_frame, wobj_of};
use crate::transform::track_correction::TrackSetup;

use super::{ConfigValue, Joints, Kinematics, select};

/// Options of a reach check.
#[derive(Clone, Debug)]
pub struct ReachOptions {
    /// Warn when |axis 5| is below this (degrees).
    pub singularity_deg: f64,
    /// The work object of declared targets no motion uses.
    pub default_wobj: Option<String>,
}

impl Default for ReachOptions {
    fn default() -> Self {
        ReachOptions {
            singularity_deg: 5.0,
            default_wobj: None,
        }
    }
}

/// The verdict on one target.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReachStatus {
    /// Reachable in the written configuration, within the limits.
    Ok,
    /// No joint solution: the pose is out of the arm's reach.
    Unreachable,
    /// The selected solution has a joint outside its limits.
    OutsideLimit,
    /// The written configuration does not reach the pose (another one does).
    ConfigMismatch,
    /// The target could not be placed (unresolved tool or work object, no skid, expressions).
    NotChecked,
}

impl ReachStatus {
    /// The status as it appears in the JSON and table output (kebab-case).
    pub fn as_str(self) -> &'static str {
        match self {
            ReachStatus::Ok => "ok",
            ReachStatus::Unreachable => "unreachable",
            ReachStatus::OutsideLimit => "outside-limit",
            ReachStatus::ConfigMismatch => "config-mismatch",
            ReachStatus::NotChecked => "not-checked",
        }
    }
}

/// One target's reach.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TargetReach {
    /// The target's name.
    pub name: String,
    /// What kind of target it is (`robtarget`, `E6POS`, …), as the position model names it.
    pub kind: &'static str,
    /// 1-based line of its declaration.
    pub line: usize,
    /// The verdict.
    pub status: ReachStatus,
    /// `None` when not checked.
    pub reachable: Option<bool>,
    /// The controller joints of the selected solution, degrees; `None` when not checked or unreachable.
    pub joints: Option<Joints>,
    /// `None` when nothing is written (or for joint targets).
    pub config_matches: Option<bool>,
    /// The configuration the target writes, as text; `None` when it writes none.
    pub config_written: Option<String>,
    /// The configuration of the selected solution, as text; `None` when not solved.
    pub config_solved: Option<String>,
    /// Per axis, degrees to the nearer limit (negative: outside).
    pub limit_margin_deg: Option<[f64; 6]>,
    /// What the check noticed besides the verdict (why not checked, near a singularity, …).
    pub warnings: Vec<String>,
}

/// The targets of one file.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FileReach {
    /// The program file.
    pub path: std::path::PathBuf,
    /// Its targets, in the order of the file.
    pub targets: Vec<TargetReach>,
}

impl TargetReach {
    fn new(p: &Position) -> TargetReach {
        TargetReach {
            name: p.label(),
            kind: p.kind.as_str(),
            line: p.line,
            status: ReachStatus::NotChecked,
            reachable: None,
            joints: None,
            config_matches: None,
            config_written: None,
            config_solved: None,
            limit_margin_deg: None,
            warnings: Vec::new(),
        }
    }

    fn not_checked(mut self, why: String) -> TargetReach {
        self.warnings.push(format!("not checked: {why}"));
        self
    }
}

/// Names that mean the bare flange.
fn is_flange(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    matches!(n.as_str(), "tool0" | "$nullframe" | "tool_data[0]")
}

/// Why a tool cannot be put on the flange ([`resolve_tool`]), and what to do, in words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ToolUnresolved {
    /// What is wrong with the tool.
    pub message: String,
    /// What to do.
    pub hint: String,
}

/// The tool `name` on the flange: the cell's `[robot.NAME.tool]` entry, else the program's
/// declaration (RAPID `tooldata` `tframe`, KRL `TOOL_DATA[n]`), else the flange for `tool0`.
pub fn resolve_tool<'a>(
    program: &'a Program,
    own: Option<&'a ParsedFile>,
    overrides: &BTreeMap<String, Pose>,
    name: &str,
) -> Result<Pose, ToolUnresolved> {
    let unresolved = |message: String| ToolUnresolved {
        message,
        hint: "give the tool under [robot.NAME.tool] in the cell file".to_owned(),
    };
    // The declaration of `own`, the target's file, first: two RAPID modules may each declare
    // a `LOCAL` tool of one name.
    let decl = || {
        program
            .frame_seen_from(own, name, |k| k == FrameKind::Tool)
            .map(|(_, d)| d)
    };
    if let Some(p) = overrides.get(&crate::transform::cell::frame_key(name)) {
        // The program gives the tool another value, which the robot then moves with: the
        // cell's entry stands for the declaration, not for that value (as for a work object).
        return match decl() {
            Some(d) if d.assigned => Err(ToolUnresolved {
                message: format!(
                    "tool `{name}` is given another value by the program (line {}) than the declaration the cell file's entry for it replaces: the robot moves with the program's value",
                    d.line
                ),
                hint: format!(
                    "remove `{name}` from the cell file's [robot.NAME.tool], or declare it with the value the program gives it"
                ),
            }),
            _ => Ok(*p),
        };
    }
    match decl() {
        Some(d) if d.held_by_robot == Some(false) => Err(unresolved(format!(
            "tool `{name}` is stationary (robhold FALSE): the robot holds the work piece"
        ))),
        Some(d) => d
            .pose()
            .ok_or_else(|| unresolved(format!("tool `{name}` has fields that are not numbers"))),
        None if is_flange(name) => Ok(Pose::identity()),
        None => Err(unresolved(format!(
            "tool not resolved: `{name}` is not declared in the program; give it under \
             [robot.NAME.tool] in the cell file"
        ))),
    }
}

/// Reach of every target of `program` on `robot` with arm `kin`.
pub fn reach_program(
    program: &Program,
    robot: &Robot,
    kin: &Kinematics,
    options: &ReachOptions,
) -> Vec<FileReach> {
    let no_deviation = |_s: f64| -> Result<Pose, TrackError> { Ok(Pose::identity()) };
    let setup = TrackSetup::new(robot, &no_deviation);
    program
        .files
        .iter()
        .filter(|f| !f.positions.is_empty())
        .map(|file| FileReach {
            path: file.path.clone(),
            targets: file
                .positions()
                .map(|p| {
                    let r = TargetReach::new(&p);
                    if p.kind.is_cartesian() {
                        cartesian(program, file, &p, robot, &setup, kin, options, r)
                    } else {
                        joint_target(&p, kin, options, r)
                    }
                })
                .collect(),
        })
        .collect()
}

fn finish(mut r: TargetReach, kin: &Kinematics, j: Joints, options: &ReachOptions) -> TargetReach {
    let margins = kin.limit_margins(&j);
    let outside = margins.iter().any(|m| *m < -1e-9);
    if outside {
        for (i, m) in margins.iter().enumerate().filter(|(_, m)| **m < -1e-9) {
            let [lo, hi] = kin.limits[i];
            r.warnings.push(format!(
                "axis {} = {:.2}° is {:.2}° outside its limits [{lo}, {hi}]",
                i + 1,
                j[i],
                -m
            ));
        }
    }
    let wrist = kin.wrist_singularity_deg(&j);
    if wrist < options.singularity_deg {
        r.warnings.push(format!(
            "near the wrist singularity: |axis 5| = {wrist:.2}° (< {}°)",
            options.singularity_deg
        ));
    }
    r.joints = Some(j);
    r.limit_margin_deg = Some(margins);
    r.status = if outside {
        ReachStatus::OutsideLimit
    } else if r.config_matches == Some(false) {
        ReachStatus::ConfigMismatch
    } else {
        ReachStatus::Ok
    };
    r
}

fn joint_target(
    p: &Position,
    kin: &Kinematics,
    options: &ReachOptions,
    r: TargetReach,
) -> TargetReach {
    let values: Option<Vec<f64>> = p
        .joints
        .iter()
        .map(|f| f.as_ref().map(|f| f.value()))
        .collect();
    match values.as_deref() {
        Some(&[a, b, c, d, e, f, ..]) => {
            let mut r = finish(r, kin, [a, b, c, d, e, f], options);
            r.reachable = Some(true);
            r
        }
        _ => r.not_checked(format!("{} has axes that are not numbers", describe(p))),
    }
}

/// The reach of Cartesian target `p` with its first tool; another tool it is used with that
/// does not reach it as the first does adds its verdict (the worse one is the target's) and
/// says why, naming the tool: the joints depend on the tool.
#[allow(clippy::too_many_arguments)]
fn cartesian(
    program: &Program,
    file: &ParsedFile,
    p: &Position,
    robot: &Robot,
    setup: &TrackSetup,
    kin: &Kinematics,
    options: &ReachOptions,
    r: TargetReach,
) -> TargetReach {
    let mut tools = p.usage.tools();
    let Some(first) = tools.next() else {
        return r.not_checked(format!(
            "tool not resolved: {} is not used with a tool",
            describe(p)
        ));
    };
    let mut r = cartesian_with(program, file, p, robot, setup, kin, options, first, r);
    for name in tools {
        let other = TargetReach::new(p);
        let other = cartesian_with(program, file, p, robot, setup, kin, options, name, other);
        if other.status == ReachStatus::Ok {
            continue;
        }
        let why = match other.warnings.as_slice() {
            [] => other.status.as_str().to_owned(),
            w => w.join("; "),
        };
        r.warnings.push(format!("with tool `{name}`: {why}"));
        if r.status == ReachStatus::Ok {
            r.status = other.status;
        }
        if other.reachable == Some(false) {
            r.reachable = Some(false);
        }
    }
    // The declaration's value of the tool is not kept once the program's stands for it.
    if let Some(t) = p.usage.two_values(FrameKind::Tool) {
        r.warnings
            .push(format!("with tool {t}: checked with the value given only"));
    }
    r
}

/// [`cartesian`] with the tool named `tool_name`.
#[allow(clippy::too_many_arguments)]
fn cartesian_with(
    program: &Program,
    file: &ParsedFile,
    p: &Position,
    robot: &Robot,
    setup: &TrackSetup,
    kin: &Kinematics,
    options: &ReachOptions,
    tool_name: &str,
    mut r: TargetReach,
) -> TargetReach {
    let what = describe(p);
    let Some(t) = p.cartesian.as_ref().and_then(|c| c.pose()) else {
        return r.not_checked(format!("{what} has fields that are not numbers"));
    };
    let written = ConfigValue::written(&p.config);
    r.config_written = written.map(|c| c.to_string());
    let language = file.language;
    let words = language.dialect().vocabulary();
    let wobj = match wobj_of(p, options.default_wobj.as_deref(), words) {
        Ok(w) => w,
        Err(why) => return r.not_checked(why.message),
    };
    let w = match resolve_frame(program, Some(file), &robot.frames, &wobj) {
        Ok(w) => w,
        Err(why) => return r.not_checked(why.message),
    };
    let tool = match resolve_tool(program, Some(file), &robot.tools, tool_name) {
        Ok(t) => t,
        Err(e) => return r.not_checked(e.message),
    };
    let skid = match p.skid(robot.skid_axis) {
        Skid::At(s) => s,
        Skid::NotConnected | Skid::Missing => {
            return r.not_checked(format!("{what} has no skid position"));
        }
    };
    let flange = setup.base_at(skid).inverse() * w * t * tool.inverse();
    let Some(sel) = select(kin, &flange, written.as_ref()) else {
        r.reachable = Some(false);
        r.status = ReachStatus::Unreachable;
        let dist = flange.translation.vector.norm();
        r.warnings.push(format!(
            "out of reach: the flange would be {dist:.1} mm from the robot base"
        ));
        return r;
    };
    r.reachable = Some(true);
    let solved = match &written {
        Some(w) => w.solved(kin, &sel.joints),
        None => ConfigValue::of_joints(language, kin, &sel.joints),
    };
    r.config_solved = Some(solved.to_string());
    if written.is_some() {
        r.config_matches = Some(sel.config_matches);
    }
    finish(r, kin, sel.joints, options)
}
