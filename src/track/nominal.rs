//! `track fit`: the controller's straight nominal, the gear factor and the deviations `D_i`
//! (docs/design.md §3), giving a [`Profile`].

use nalgebra::{Matrix3, Translation3, UnitQuaternion, Vector3};

use super::error::NominalProblem;
use super::frames_csv::SamplingFrame;
use super::profile::{
    Extrapolate, Gear, Knot, Nominal, Profile, Reference, TrackError, line_fit, line_residuals,
};
use crate::geometry::{Pose, nearest_rotation, pose_to_xyz_deg, xyz_deg_angles};

/// How far the gear factor may be from 1: a real track's gear error is parts per ten thousand;
/// beyond this the frames are in other units than the skid (metres, inches, a scale of 1e9) or
/// the skid column is wrong.
pub const GEAR_TOLERANCE: f64 = 0.05;

/// How to fit a profile.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// The profile's name, recorded in it.
    pub name: String,
    /// Which nominal the deviations are taken from (`docs/design.md §3`).
    pub reference: Reference,
    /// Whether the nominal keeps the gear drift or leaves it to a new gear factor.
    pub gear: Gear,
    /// What evaluating the profile outside its knots does.
    pub extrapolate: Extrapolate,
    /// sha256 (hex) of the frames file, recorded in the profile.
    pub source_sha256: String,
}

impl Default for FitOptions {
    fn default() -> FitOptions {
        FitOptions {
            name: "track".to_string(),
            reference: Reference::Regression,
            gear: Gear::AsIs,
            extrapolate: Extrapolate::Error,
            source_sha256: String::new(),
        }
    }
}

/// The least-squares line of one origin coordinate over skid (thesis eq. 4.54).
#[derive(Clone, Debug, PartialEq)]
pub struct CoordinateLine {
    /// The coordinate at skid 0, mm.
    pub intercept: f64,
    /// mm of the coordinate per mm of skid.
    pub slope: f64,
    /// `o_i - (intercept + slope·s_i)`.
    pub residuals: Vec<f64>,
}

/// The fitted track.
#[derive(Clone, Debug)]
pub struct TrackFit {
    /// The profile: nominal and knots.
    pub profile: Profile,
    /// x, y, z lines of the origins.
    pub lines: [CoordinateLine; 3],
    /// `m`: measured mm per commanded mm, as a vector.
    pub slope: Vector3<f64>,
    /// `g = |m|`; the controller's new gear factor is `g · gear_old` (thesis eq. 4.4).
    pub gear_factor: f64,
    /// `u = m/|m|`, in the measurement frame.
    pub direction: Vector3<f64>,
    /// `N(0)`: the base frame at skid 0 the controller should use, in the measurement frame.
    pub base_at_zero: Pose,
}

impl TrackFit {
    /// The track direction in the nominal robot base frame (`R_Nᵀ·u`).
    pub fn direction_in_base(&self) -> Vector3<f64> {
        self.base_at_zero.rotation.inverse() * self.direction
    }
}

/// Fits the nominal and the deviations of sampling frames in increasing skid order.
pub fn fit_track(frames: &[SamplingFrame], opts: &FitOptions) -> Result<TrackFit, TrackError> {
    let Some(first) = frames.first() else {
        return Err(TrackError::Nominal(NominalProblem::TooFewFrames {
            count: 0,
        }));
    };
    if frames.len() < 2 {
        return Err(TrackError::Nominal(NominalProblem::TooFewFrames {
            count: frames.len(),
        }));
    }
    let skids: Vec<f64> = frames.iter().map(|f| f.skid).collect();
    let coord = |a: usize| -> Vec<f64> {
        frames
            .iter()
            .map(|f| f.pose.translation.vector[a])
            .collect()
    };
    let line = |a: usize| {
        let ys = coord(a);
        let (intercept, slope) = line_fit(&skids, &ys);
        CoordinateLine {
            intercept,
            slope,
            residuals: line_residuals(&skids, &ys),
        }
    };
    let lines = [line(0), line(1), line(2)];
    let slope = Vector3::new(lines[0].slope, lines[1].slope, lines[2].slope);
    let gear_factor = slope.norm();
    if gear_factor.is_nan() || gear_factor <= 0.0 || !gear_factor.is_finite() {
        return Err(TrackError::Nominal(NominalProblem::NoDirection));
    }
    if (gear_factor - 1.0).abs() > GEAR_TOLERANCE {
        return Err(TrackError::Nominal(NominalProblem::ImplausibleGear {
            gear_factor,
            tolerance: GEAR_TOLERANCE,
        }));
    }
    let direction = slope / gear_factor;
    let step = match opts.gear {
        Gear::AsIs => direction,
        Gear::Recalibrated => slope,
    };
    let (rotation, origin) = match opts.reference {
        Reference::Regression => {
            let sum: Matrix3<f64> = frames
                .iter()
                .map(|f| f.pose.rotation.to_rotation_matrix().into_inner())
                .sum();
            let r = nearest_rotation(&sum)
                .ok_or(TrackError::Nominal(NominalProblem::DegenerateRotation))?;
            let origin = Vector3::new(lines[0].intercept, lines[1].intercept, lines[2].intercept);
            (UnitQuaternion::from_rotation_matrix(&r), origin)
        }
        Reference::First => (
            first.pose.rotation,
            first.pose.translation.vector - step * first.skid,
        ),
    };
    let nominal_at = |s: f64| Pose::from_parts(Translation3::from(origin + step * s), rotation);
    let round = |v: f64| {
        let r = (v * 1e6).round() / 1e6;
        if r == 0.0 { 0.0 } else { r }
    };
    let knots: Vec<Knot> = frames
        .iter()
        .map(|f| {
            // docs/design.md §3: D_i = N(s_i)⁻¹·F_i.
            let d = nominal_at(f.skid).inverse() * f.pose;
            Knot::from_components(f.skid, pose_to_xyz_deg(&d).map(round))
        })
        .collect();
    let nominal = Nominal {
        origin: [origin.x, origin.y, origin.z].map(|v| (v * 1e6).round() / 1e6),
        direction: [direction.x, direction.y, direction.z].map(|v| (v * 1e12).round() / 1e12),
        rotation: xyz_deg_angles(&rotation).map(|v| (v * 1e9).round() / 1e9),
        gear_factor: (gear_factor * 1e12).round() / 1e12,
    };
    let profile = Profile::from_parts(opts, nominal, knots)?;
    Ok(TrackFit {
        base_at_zero: nominal_at(0.0),
        profile,
        lines,
        slope,
        gear_factor,
        direction,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose_xyz_deg;
    use crate::track::frames_csv::parse_frames;
    use std::path::Path;

    const TABLE_4_1: &str = include_str!("../../samples/track/table_4_1_frames.csv");

    #[test]
    fn table_4_1_regression_and_gear_factor() {
        // Reference README, to 1e-4 (slopes to their printed digits).
        let frames = parse_frames(Path::new("table_4_1_frames.csv"), TABLE_4_1.as_bytes()).unwrap();
        let fit = fit_track(&frames, &FitOptions::default()).unwrap();
        let [x, y, z] = &fit.lines;
        assert!((x.slope - 0.99985205).abs() < 1e-8, "{}", x.slope);
        assert!((x.intercept + 0.0212).abs() < 1e-4);
        assert!((y.slope - 0.0007044).abs() < 1e-7, "{}", y.slope);
        assert!((y.intercept + 0.5194).abs() < 1e-4);
        assert!((z.slope + 0.0000869).abs() < 1e-7, "{}", z.slope);
        assert!((z.intercept + 0.1700).abs() < 1e-4);
        let want = [
            [0.0212, -0.1169, 0.1760, -0.0861, 0.0058],
            [0.5194, -0.2074, -0.5802, -0.2950, 0.5632],
            [0.1700, -0.0842, -0.1334, -0.1606, 0.2082],
        ];
        for (line, w) in fit.lines.iter().zip(want) {
            for (r, w) in line.residuals.iter().zip(w) {
                assert!((r - w).abs() < 1e-4, "{r} vs {w}");
            }
        }
        assert!((fit.gear_factor - 0.99985).abs() < 1e-4);
        // 359.9981 is wrapped: the knots stay hundredths of a degree.
        for k in fit.profile.knots() {
            assert!(
                k.rx.abs() < 0.05 && k.ry.abs() < 0.05 && k.rz.abs() < 0.05,
                "{k:?}"
            );
        }
    }

    #[test]
    fn straight_track_gives_zero_deviations() {
        let base = pose_xyz_deg(100.0, 200.0, 300.0, 1.0, 2.0, 30.0);
        let frames: Vec<SamplingFrame> = (0..5)
            .map(|i| {
                let s = i as f64 * 1000.0;
                SamplingFrame {
                    skid: s,
                    pose: base * Pose::translation(s, 0.0, 0.0),
                }
            })
            .collect();
        for reference in [Reference::Regression, Reference::First] {
            let opts = FitOptions {
                reference,
                ..FitOptions::default()
            };
            let fit = fit_track(&frames, &opts).unwrap();
            for k in fit.profile.knots() {
                assert!(k.components().iter().all(|c| c.abs() < 1e-6), "{k:?}");
            }
            assert!((fit.gear_factor - 1.0).abs() < 1e-12);
        }
    }
}
