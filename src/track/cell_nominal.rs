//! The cell's robot base `B_0` and track axis `a` against a profile's nominal `N(s)`, and
//! writing the nominal into a cell file.
//!
//! A correction assumes the controller's straight track `B(s) = Trans(s·a)·B_0` is the profile's
//! nominal seen from the cell. What can be compared depends on what the profile knows about its
//! measurement frame:
//!
//! - always (frame-independent): the track direction in the robot's own base frame,
//!   `R(B_0)ᵀ·a` against `R_Nᵀ·u`. A `track_axis = [0, 1, 0]` for a track along x fails here.
//! - when the profile records `measured_in = "world"` (the tracker was aligned to the cell's
//!   world frame): also `a` against `u`, and `B_0` against `N(0)` (position and rotation). A
//!   design-value base instead of the fitted one fails here.

use std::fmt;

use nalgebra::Vector3;

use super::profile::{MeasuredIn, Profile};
use crate::geometry::{Pose, pose_to_xyz_deg};

/// Largest angle between the cell's and the profile's track direction, degrees (0.01° is
/// 1.4 mm over 8 m of track).
pub const DIRECTION_TOLERANCE_DEG: f64 = 0.01;
/// Largest distance between the cell's base at skid 0 and the nominal's, mm.
pub const BASE_POSITION_TOLERANCE_MM: f64 = 0.1;
/// Largest rotation between the cell's base at skid 0 and the nominal's, degrees (0.01° is
/// 0.17 mm at a TCP 1 m from the base).
pub const BASE_ROTATION_TOLERANCE_DEG: f64 = 0.01;

/// What was compared and how far apart it was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NominalComparison {
    /// Angle between the track directions in the robot base frame, degrees.
    pub axis_in_base_deg: f64,
    /// With a profile measured in the world frame: the angle between `a` and `u` (degrees),
    /// and the base's position (mm) and rotation (degrees) difference at skid 0.
    pub world: Option<WorldComparison>,
}

/// The cell against a profile measured in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldComparison {
    /// Angle between the cell's `track_axis` `a` and the profile's direction `u`, degrees.
    pub axis_deg: f64,
    /// Distance between the cell's base and the nominal's at skid 0, mm.
    pub base_position_mm: f64,
    /// Rotation between the cell's base and the nominal's at skid 0, degrees.
    pub base_rotation_deg: f64,
}

/// One quantity beyond its tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Disagreement {
    /// The track direction in the robot base frame.
    AxisInBase {
        /// The angle between the two directions, degrees.
        angle_deg: f64,
    },
    /// The track direction in the world.
    Axis {
        /// The angle between the two directions, degrees.
        angle_deg: f64,
    },
    /// The base's position at skid 0.
    BasePosition {
        /// The distance between the two, mm.
        distance_mm: f64,
    },
    /// The base's rotation at skid 0.
    BaseRotation {
        /// The rotation between the two, degrees.
        angle_deg: f64,
    },
}

impl fmt::Display for Disagreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Disagreement::AxisInBase { angle_deg } => write!(
                f,
                "seen from the robot base, the cell's track_axis is {angle_deg:.4} deg off the profile's track direction (tolerance {DIRECTION_TOLERANCE_DEG} deg)"
            ),
            Disagreement::Axis { angle_deg } => write!(
                f,
                "track_axis is {angle_deg:.4} deg off the profile's direction in the world (tolerance {DIRECTION_TOLERANCE_DEG} deg)"
            ),
            Disagreement::BasePosition { distance_mm } => write!(
                f,
                "base is {distance_mm:.3} mm from the profile's nominal base at skid 0 (tolerance {BASE_POSITION_TOLERANCE_MM} mm)"
            ),
            Disagreement::BaseRotation { angle_deg } => write!(
                f,
                "base is turned {angle_deg:.4} deg from the profile's nominal base at skid 0 (tolerance {BASE_ROTATION_TOLERANCE_DEG} deg)"
            ),
        }
    }
}

/// The cell does not describe the track the profile was fitted on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("the cell's base and track_axis disagree with profile `{profile}`: {}", list(.disagreements))]
pub struct NominalMismatch {
    /// The profile's name.
    pub profile: String,
    /// Each quantity beyond its tolerance.
    pub disagreements: Vec<Disagreement>,
    /// Every figure compared, within tolerance or not.
    pub comparison: NominalComparison,
}

fn list(d: &[Disagreement]) -> String {
    d.iter()
        .map(|d| d.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    // atan2 of |a×b| and a·b stays accurate for tiny angles, where acos does not.
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

/// Compares the cell's `base0` (`B_0`, the base in world at skid 0) and unit `track_axis` (`a`,
/// world) with the profile's nominal; a disagreement beyond the tolerances is an error listing
/// each quantity.
pub fn check_cell_nominal(
    base0: &Pose,
    track_axis: &Vector3<f64>,
    profile: &Profile,
) -> Result<NominalComparison, NominalMismatch> {
    let nominal = profile.nominal();
    let axis = track_axis
        .try_normalize(1e-12)
        .unwrap_or_else(Vector3::zeros);
    let cell_in_base = base0.rotation.inverse() * axis;
    let axis_in_base_deg = angle_deg(&cell_in_base, &nominal.axis_in_base());
    let mut disagreements = Vec::new();
    if axis_in_base_deg.is_nan() || axis_in_base_deg > DIRECTION_TOLERANCE_DEG {
        disagreements.push(Disagreement::AxisInBase {
            angle_deg: axis_in_base_deg,
        });
    }
    let world = (profile.measured_in() == Some(MeasuredIn::World)).then(|| {
        let n0 = profile.nominal_frame(0.0);
        WorldComparison {
            axis_deg: angle_deg(&axis, &Vector3::from(nominal.direction)),
            base_position_mm: (base0.translation.vector - n0.translation.vector).norm(),
            base_rotation_deg: base0.rotation.angle_to(&n0.rotation).to_degrees(),
        }
    });
    if let Some(w) = &world {
        if w.axis_deg.is_nan() || w.axis_deg > DIRECTION_TOLERANCE_DEG {
            disagreements.push(Disagreement::Axis {
                angle_deg: w.axis_deg,
            });
        }
        if w.base_position_mm.is_nan() || w.base_position_mm > BASE_POSITION_TOLERANCE_MM {
            disagreements.push(Disagreement::BasePosition {
                distance_mm: w.base_position_mm,
            });
        }
        if w.base_rotation_deg.is_nan() || w.base_rotation_deg > BASE_ROTATION_TOLERANCE_DEG {
            disagreements.push(Disagreement::BaseRotation {
                angle_deg: w.base_rotation_deg,
            });
        }
    }
    let comparison = NominalComparison {
        axis_in_base_deg,
        world,
    };
    if disagreements.is_empty() {
        Ok(comparison)
    } else {
        Err(NominalMismatch {
            profile: profile.name().to_owned(),
            disagreements,
            comparison,
        })
    }
}

/// Why a cell file could not be given the nominal.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CellEditError {
    /// The cell file is not TOML.
    #[error("the cell file is not valid TOML: {0}")]
    Parse(#[from] toml_edit::TomlError),
    /// The cell file has no table for the robot (its name).
    #[error("the cell file has no [robot.{0}] table")]
    NoRobot(String),
}

/// `text` of a cell file with `[robot.<robot>]`'s `base` and `track_axis` set to the nominal
/// at skid 0 (`base_at_zero`, world) and its unit direction; every other byte, comments and
/// layout included, stays as it was (toml_edit), and a value's own trailing comment is kept.
pub fn write_nominal_into_cell(
    text: &str,
    robot: &str,
    base_at_zero: &Pose,
    direction: &Vector3<f64>,
) -> Result<String, CellEditError> {
    let mut doc: toml_edit::DocumentMut = text.parse()?;
    let table = doc
        .get_mut("robot")
        .and_then(|r| r.get_mut(robot))
        .and_then(|t| t.as_table_like_mut())
        .ok_or_else(|| CellEditError::NoRobot(robot.to_owned()))?;
    let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(base_at_zero);
    let mut base = toml_edit::InlineTable::new();
    for (k, v, decimals) in [
        ("x", x, 4),
        ("y", y, 4),
        ("z", z, 4),
        ("rx", rx, 6),
        ("ry", ry, 6),
        ("rz", rz, 6),
    ] {
        base.insert(k, toml_edit::Value::from(round(v, decimals)));
    }
    let mut axis = toml_edit::Array::new();
    for c in direction.iter() {
        axis.push(round(*c, 9));
    }
    set_keeping_decor(table, "base", toml_edit::Value::InlineTable(base));
    set_keeping_decor(table, "track_axis", toml_edit::Value::Array(axis));
    Ok(doc.to_string())
}

fn round(v: f64, decimals: i32) -> f64 {
    let s = 10f64.powi(decimals);
    let r = (v * s).round() / s;
    if r == 0.0 { 0.0 } else { r }
}

/// Replaces the value of `key`, keeping the whitespace and comment around the old value.
fn set_keeping_decor(table: &mut dyn toml_edit::TableLike, key: &str, mut value: toml_edit::Value) {
    match table.get_mut(key).and_then(|i| i.as_value_mut()) {
        Some(old) => {
            let decor = old.decor().clone();
            *value.decor_mut() = decor;
            *old = value;
        }
        None => {
            value.decor_mut().set_prefix(" ");
            table.insert(key, toml_edit::Item::Value(value));
        }
    }
}
