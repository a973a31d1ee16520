//! "Enter in the controller": the figures `track fit` prints, as data and as the literals an
//! engineer types into an ABB or KUKA controller.

use nalgebra::Vector3;

use crate::geometry::{Pose, abb_pose_literal, kuka_frame_literal, pose_to_xyz_deg};
use crate::track::frames_csv::clean;
use crate::track::nominal::TrackFit;
use crate::track::{Gear, MeasuredIn, Profile};

/// How the controller figures name the frame they are in: the profile's `measured_in`. A base
/// and direction in the tracker's frame must be taken into the cell's world before they are
/// entered.
pub fn frame_name(m: Option<MeasuredIn>) -> &'static str {
    match m {
        Some(MeasuredIn::World) => "world",
        Some(MeasuredIn::Tracker) => {
            "the tracker's; take the base and direction into the cell's world before entering them"
        }
        None => "not stated in the profile",
    }
}

/// The controller set-up of a fitted track.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerFigures {
    /// `g`: measured mm per commanded mm; the new gear factor is `g ×` the current one.
    pub gear_factor: f64,
    /// Whether the profile assumes the new gear factor is entered.
    pub gear: Gear,
    /// The measured skid range, mm.
    pub skid_range: (f64, f64),
    /// Unit track direction in the measurement frame.
    pub direction: Vector3<f64>,
    /// The same direction in the base frame at skid 0.
    pub direction_in_base: Vector3<f64>,
    /// `N(0)`: the base frame at skid 0, in the measurement frame.
    pub base_at_zero: Pose,
    /// The frame the measurements were taken in, as the profile states it.
    pub measured_in: Option<MeasuredIn>,
}

impl ControllerFigures {
    /// The figures of a fit, exactly as `track fit` computes them.
    pub fn from_fit(fit: &TrackFit) -> ControllerFigures {
        ControllerFigures {
            gear_factor: fit.gear_factor,
            gear: fit.profile.gear(),
            skid_range: fit.profile.skid_range(),
            direction: fit.direction,
            direction_in_base: fit.direction_in_base(),
            base_at_zero: fit.base_at_zero,
            measured_in: fit.profile.measured_in(),
        }
    }

    /// The figures stored in a profile's nominal (rounded there to 1e-6 mm, 1e-9°, 1e-12: far
    /// below the printed digits).
    pub fn from_profile(p: &Profile) -> ControllerFigures {
        let n = p.nominal();
        let base_at_zero = p.nominal_frame(0.0);
        ControllerFigures {
            gear_factor: n.gear_factor,
            gear: p.gear(),
            skid_range: p.skid_range(),
            direction: Vector3::from(n.direction),
            direction_in_base: n.axis_in_base(),
            base_at_zero,
            measured_in: p.measured_in(),
        }
    }

    /// `the skid moves 0.999847 mm per commanded mm (-1.227 mm over 8000 mm)`.
    pub fn gear_text(&self) -> String {
        let (s0, s1) = self.skid_range;
        format!(
            "the skid moves {:.6} mm per commanded mm ({:+.3} mm over {} mm)",
            self.gear_factor,
            (self.gear_factor - 1.0) * (s1 - s0),
            s1 - s0
        )
    }

    /// What to do with the gear factor, for this profile's gear setting.
    pub fn new_gear_text(&self) -> String {
        let [convention, abb, kuka, travel] = crate::track::gear::advice(self.gear_factor);
        format!(
            "{convention} {abb}; {kuka} {travel}; {}",
            match self.gear {
                Gear::AsIs => "this profile keeps the drift instead (gear as-is)",
                Gear::Recalibrated => "this profile assumes you enter it (gear recalibrated)",
            }
        )
    }

    /// `[0.999999, -0.000003, 0.000001]` in the measurement frame.
    pub fn direction_text(&self) -> String {
        vector6(&self.direction)
    }

    /// The direction in the base frame at skid 0.
    pub fn direction_in_base_text(&self) -> String {
        vector6(&self.direction_in_base)
    }

    /// `x 0.016 y -3499.087 z -1.496 mm, rx 0.0004 ry -0.0001 rz 90.0007 deg`.
    pub fn base_text(&self) -> String {
        let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(&self.base_at_zero);
        format!("x {x:.3} y {y:.3} z {z:.3} mm, rx {rx:.4} ry {ry:.4} rz {rz:.4} deg")
    }

    /// The base at skid 0 as a RAPID pose literal `[[x,y,z],[q1,q2,q3,q4]]`.
    pub fn abb_literal(&self) -> String {
        abb_pose_literal(&self.base_at_zero)
    }

    /// The base at skid 0 as a KRL FRAME literal `{X x,Y y,Z z,A a,B b,C c}`.
    pub fn kuka_literal(&self) -> String {
        kuka_frame_literal(&self.base_at_zero)
    }
}

fn vector6(v: &Vector3<f64>) -> String {
    format!(
        "[{:.6}, {:.6}, {:.6}]",
        clean(v.x, 6),
        clean(v.y, 6),
        clean(v.z, 6)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose_xyz_deg;

    #[test]
    fn literals_follow_each_vendor_convention() {
        // R = Rz(30)·Ry(20)·Rx(10): KUKA A, B, C = 30, 20, 10; the ABB quaternion (scalar
        // first) is qz(30)·qy(20)·qx(10), multiplied out by hand.
        let p = pose_xyz_deg(1.0, -2.5, 3.0, 10.0, 20.0, 30.0);
        assert_eq!(
            abb_pose_literal(&p),
            "[[1.000,-2.500,3.000],[0.951549,0.038135,0.189308,0.239298]]"
        );
        assert_eq!(
            kuka_frame_literal(&p),
            "{X 1.000,Y -2.500,Z 3.000,A 30.0000,B 20.0000,C 10.0000}"
        );
    }
}
