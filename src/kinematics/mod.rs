//! Robot kinematics: the OPW arm model, bundled robot models, the ABB and KUKA configuration
//! semantics, and the checks built on them (reach of every target, corrected joint targets,
//! configurations of mirrored targets).
//!
//! Conventions: joints are the controller's, in degrees ([`Joints`]); poses are in mm with
//! `nalgebra` rotations; the flange pose is `tool0` in the robot base frame. See
//! `docs/design.md §10`.

pub mod abb;
pub mod cell_table;
pub mod correction;
pub mod kuka;
pub mod models;
pub mod opw;
pub mod reach;

pub use correction::{
    JointRefusal, KinematicCheck, KinematicRefusal, WRIST_TURN_LIMIT_DEG, check_move, check_target,
    joint_target_correction, mirror_config_by_ik, mirrored_joints,
};
pub use models::{MODELS, Model, model, model_names};
pub use opw::{Arm, Joints, Kinematics, OpwGeometry};

use crate::geometry::Pose;
use crate::position::{Config, Language};

/// A configuration as numbers: what a target writes, or what IK finds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigValue {
    /// Axis quadrants `[cf1, cf4, cf6, cfx]` (ABB `confdata`).
    Quadrants([i32; 4]),
    /// Status and Turn bits (KUKA `S`, `T`; either may be absent in a program).
    StatusTurn {
        /// The Status bits (`S`): the arm configuration (`docs/design.md §10`).
        status: Option<u32>,
        /// The Turn bits (`T`): bit i set when axis A(i+1) is negative.
        turn: Option<u32>,
    },
}

impl ConfigValue {
    /// The configuration a target writes, if it writes one with numeric fields.
    pub fn written(config: &Config) -> Option<ConfigValue> {
        match config {
            Config::Quadrants(f) => {
                let mut out = [0; 4];
                for (o, f) in out.iter_mut().zip(f) {
                    let v = f.as_ref()?.value();
                    if v.fract() != 0.0 || v.abs() > 1e6 {
                        return None;
                    }
                    *o = v as i32;
                }
                Some(ConfigValue::Quadrants(out))
            }
            Config::StatusTurn { status, turn } if status.is_some() || turn.is_some() => {
                Some(ConfigValue::StatusTurn {
                    status: status.as_ref().map(|b| b.value()),
                    turn: turn.as_ref().map(|b| b.value()),
                })
            }
            _ => None,
        }
    }

    /// The configuration of joints `j` in `language`'s terms (the convention its dialect
    /// writes).
    pub fn of_joints(language: Language, kin: &Kinematics, j: &Joints) -> ConfigValue {
        language.dialect().configuration_of(kin, j)
    }

    /// Whether joints `j` are in this configuration.
    pub fn matches(&self, kin: &Kinematics, j: &Joints) -> bool {
        match *self {
            ConfigValue::Quadrants(c) => abb::matches(kin, j, c),
            ConfigValue::StatusTurn { status, turn } => kuka::matches(kin, j, status, turn),
        }
    }

    /// The configuration of joints `j` in the same convention as this one.
    pub fn solved(&self, kin: &Kinematics, j: &Joints) -> ConfigValue {
        match self {
            ConfigValue::Quadrants(_) => ConfigValue::quadrants_of(kin, j),
            ConfigValue::StatusTurn { .. } => ConfigValue::status_turn_of(kin, j),
        }
    }

    /// The axis quadrants of joints `j` ([`ConfigValue::Quadrants`]).
    pub fn quadrants_of(kin: &Kinematics, j: &Joints) -> ConfigValue {
        ConfigValue::Quadrants(abb::config_of(kin, j))
    }

    /// The Status and Turn bits of joints `j`, both written ([`ConfigValue::StatusTurn`]).
    pub fn status_turn_of(kin: &Kinematics, j: &Joints) -> ConfigValue {
        let (status, turn) = kuka::status_turn_of(kin, j);
        ConfigValue::StatusTurn {
            status: Some(status),
            turn: Some(turn),
        }
    }
}

impl std::fmt::Display for ConfigValue {
    /// ABB `[0,0,-1,0]`, KUKA `S 2 T 10` (decimal, as KRL writes them without `'B…'`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ConfigValue::Quadrants([a, b, c, d]) => write!(f, "[{a},{b},{c},{d}]"),
            ConfigValue::StatusTurn { status, turn } => {
                let mut sep = "";
                if let Some(s) = status {
                    write!(f, "S {s}")?;
                    sep = " ";
                }
                if let Some(t) = turn {
                    write!(f, "{sep}T {t}")?;
                }
                Ok(())
            }
        }
    }
}

/// The solution of `flange` that a written configuration selects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Selection {
    /// The controller joints of the selected solution, degrees.
    pub joints: Joints,
    /// The written configuration selects these joints (always true without one).
    pub config_matches: bool,
    /// Every joint is within its limits.
    pub within_limits: bool,
}

/// Picks the solution of a flange pose: the one within the limits that `written` selects (the
/// one nearest to zero joints if several turns share the configuration); else
/// (the configuration does not reach the pose) a solution within the limits in the same arm
/// choice, else any within the limits, else the first one outside them. Without a written
/// configuration, the solution within the limits nearest to all-zero joints. `None` when the
/// pose is out of reach.
pub fn select(kin: &Kinematics, flange: &Pose, written: Option<&ConfigValue>) -> Option<Selection> {
    let base = kin.inverse(flange, None);
    let first = *base.first()?;
    let within = kin.solutions_within_limits(flange, None);
    let zero = [0.0; 6];
    let nearest_zero = |c: &[Joints]| {
        c.iter()
            .min_by(|a, b| opw::distance2(a, &zero).total_cmp(&opw::distance2(b, &zero)))
            .copied()
    };
    let pick = |joints: Joints, config_matches: bool| Selection {
        joints,
        config_matches,
        within_limits: kin.within_limits(&joints),
    };
    let Some(w) = written else {
        return Some(match nearest_zero(&within) {
            Some(j) => pick(j, true),
            None => pick(first, true),
        });
    };
    // Several turns can share one configuration (KUKA Turn gives only signs: axis 6 of
    // ±400° has two negative variants); the one nearest to zero joints is taken.
    let matching: Vec<Joints> = within
        .iter()
        .filter(|j| w.matches(kin, j))
        .copied()
        .collect();
    if let Some(j) = nearest_zero(&matching) {
        return Some(pick(j, true));
    }
    // Outside the limits but in the written configuration: report that solution (the turn
    // variant least outside), so the message is "outside a limit", not "another
    // configuration".
    // Only an axis that can turn more than once around (a range over 360°, as axes 4 and 6
    // usually have) gets turn variants here; an arm axis of a smaller range has one angle per
    // solution, so a sign the written Turn demands against it is another configuration, not
    // a limit.
    let wide = Kinematics {
        limits: kin.limits.map(|[lo, hi]| {
            if hi - lo > 360.0 {
                [-720.0, 720.0]
            } else {
                [-180.0, 180.0]
            }
        }),
        ..kin.clone()
    };
    let violation =
        |j: &Joints| -> f64 { kin.limit_margins(j).iter().map(|m| (-m).max(0.0)).sum() };
    let outside = base
        .iter()
        .flat_map(|j| wide.turns(j))
        .filter(|j| w.matches(kin, j))
        .min_by(|a, b| violation(a).total_cmp(&violation(b)));
    if let Some(j) = outside {
        return Some(pick(j, true));
    }
    Some(match nearest_zero(&within) {
        Some(j) => pick(j, false),
        None => pick(first, false),
    })
}
