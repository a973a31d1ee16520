//! Frames measured with a laser tracker and the robot (docs/design.md): the robot base and
//! track axis in the cell, compensated by the track profile ([`base`]); work objects touched at
//! several skid positions ([`wobj`]); the TCP from pivot poses ([`tool`]); and the plain
//! point-pair fit that ties a tracker to the cell's reference marks ([`pairs`]). Every result
//! comes with its standard uncertainty from the fit's Jacobian, `σ²·(JᵀJ)⁻¹`.

pub mod base;
pub mod pairs;
pub mod tool;
pub mod wobj;

use nalgebra::{DMatrix, DVector, Matrix6, Translation3, UnitQuaternion, Vector3};

use crate::geometry::rigid_fit::RigidFitError;
use crate::geometry::{Pose, pose_to_xyz_deg, wrap_deg};
use crate::track::TrackError;
use crate::track::uncertainty::Sigma;

/// Why a frame cannot be identified from the data.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The data do not fix the frame (too few points, collinear, one skid only, ...).
    #[error(transparent)]
    Underdetermined(#[from] Underdetermined),
    /// Reading the input, or the track profile, failed.
    #[error(transparent)]
    Track(#[from] TrackError),
    /// A noise level that is not a non-negative number.
    #[error("noise level {0} mm: give a non-negative number")]
    BadSigma(f64),
}

/// What the data lack to fix a frame: the counts and the missing property, rendered with
/// what to measure on display.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Underdetermined {
    /// As many unknowns as coordinates: nothing is left to estimate the noise from.
    #[error(
        "{points} point(s) leave no residual to estimate the noise from: give the noise level, or measure more points"
    )]
    NoResidual {
        /// The points measured.
        points: usize,
    },
    /// Too few points paired by number between the two files of a best fit.
    #[error(
        "{got} point(s) in both files: a best fit needs at least 3 non-collinear points, paired by point number"
    )]
    TooFewPairs {
        /// The points paired.
        got: usize,
    },
    /// The paired points do not fix a rigid fit.
    #[error("{paired} paired points: {error}")]
    PairFit {
        /// The points paired.
        paired: usize,
        /// Why the fit fails.
        error: RigidFitError,
    },
    /// The points fit, but their spread leaves a direction of the six free.
    #[error("the points do not fix all six degrees of freedom")]
    PointsSpread,
    /// Too few points for a base and a track axis.
    #[error(
        "{got} point(s): a base and a track axis need at least 4 (and at least 2 skid positions)"
    )]
    TooFewBasePoints {
        /// The points measured.
        got: usize,
    },
    /// The normal equations of the base fit are singular.
    #[error(
        "the points do not fix the base and the track axis: spread them in all three directions and over the track"
    )]
    BaseAndAxis,
    /// Every point at one skid position.
    #[error("all points are at one skid position: the track axis needs points at two or more")]
    OneSkid,
    /// No skid position with three points that fix a rotation.
    #[error(
        "no skid position has 3 non-collinear points: measure at least 3 well-spread points at one of them"
    )]
    NoRotation,
    /// The points do not move with the skid.
    #[error("the measured points do not move with the skid: no track direction")]
    NoTrackDirection,
    /// Too few marks for a work object.
    #[error("{got} mark(s): a work object needs at least 3 non-collinear marks")]
    TooFewMarks {
        /// The marks measured.
        got: usize,
    },
    /// The marks lie on one line.
    #[error(
        "the marks are collinear: the rotation about their line is free; touch a mark off that line"
    )]
    CollinearMarks,
    /// The marks do not fix a rigid fit for another reason.
    #[error(transparent)]
    MarkFit(RigidFitError),
    /// The marks fit, but their spread leaves a direction of the six free.
    #[error("the marks do not fix all six degrees of freedom")]
    MarksSpread,
    /// Too few flange poses for a TCP.
    #[error("{got} pose(s): a TCP needs at least 3 (4 or more to see the error)")]
    TooFewPoses {
        /// The poses measured.
        got: usize,
    },
    /// The flange orientations are too alike to fix the TCP.
    #[error(
        "the orientations do not differ enough to fix the TCP: tilt the tool about two different axes (at least 3 orientations)"
    )]
    OrientationsAlike,
}

/// The residual of one measured point: `measured - model`, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointResidual {
    /// The skid position (0 where the data have none).
    pub skid: f64,
    /// The point, mark or pose number.
    pub point: u32,
    /// `measured - model` in world axes, mm.
    pub residual: Vector3<f64>,
}

impl PointResidual {
    /// `|residual|` (thesis Table 7.2's "rms" column).
    pub fn norm(&self) -> f64 {
        self.residual.norm()
    }
}

/// `sqrt(mean |r|²)` of residuals.
pub fn rms(residuals: &[PointResidual]) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    (residuals
        .iter()
        .map(|r| r.residual.norm_squared())
        .sum::<f64>()
        / residuals.len() as f64)
        .sqrt()
}

/// The noise level for a fit: the given one, or `sqrt(SSR/dof)` from its residuals.
pub(crate) fn sigma_of(
    given: Option<f64>,
    residuals: &[PointResidual],
    parameters: usize,
) -> Result<Sigma, FrameError> {
    match given {
        Some(s) if s.is_finite() && s >= 0.0 => Ok(Sigma::Given(s)),
        Some(s) => Err(FrameError::BadSigma(s)),
        None => {
            let dof = (3 * residuals.len()).saturating_sub(parameters);
            if dof == 0 {
                return Err(Underdetermined::NoResidual {
                    points: residuals.len(),
                }
                .into());
            }
            let ssr: f64 = residuals.iter().map(|r| r.residual.norm_squared()).sum();
            Ok(Sigma::Estimated {
                sigma: (ssr / dof as f64).sqrt(),
                dof,
            })
        }
    }
}

/// Standard uncertainties (k = 1) of a pose written as `x, y, z, rx, ry, rz` (mm, degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseUncertainty {
    /// `x, y, z` in mm, then `rx, ry, rz` in degrees.
    pub u: [f64; 6],
}

/// `pose·(δt, δθ)`: the right perturbation the fits and their covariances use.
pub(crate) fn perturb_right(pose: &Pose, d: &[f64]) -> Pose {
    let g = |i: usize| d.get(i).copied().unwrap_or(0.0);
    let delta = Pose::from_parts(
        Translation3::new(g(0), g(1), g(2)),
        UnitQuaternion::from_scaled_axis(Vector3::new(g(3), g(4), g(5))),
    );
    pose * delta
}

/// Propagates the covariance of a right perturbation `(δt, δθ)` of `pose` (mm, rad) to its
/// written values `x, y, z, rx, ry, rz` by a central-difference Jacobian.
pub(crate) fn xyz_deg_uncertainty(pose: &Pose, cov: &Matrix6<f64>) -> PoseUncertainty {
    let mut g = DMatrix::<f64>::zeros(6, 6);
    for k in 0..6 {
        let h = if k < 3 { 1e-3 } else { 1e-6 };
        let mut d = [0.0; 6];
        d[k] = h;
        let plus = pose_to_xyz_deg(&perturb_right(pose, &d));
        d[k] = -h;
        let minus = pose_to_xyz_deg(&perturb_right(pose, &d));
        for i in 0..6 {
            let diff = if i < 3 {
                plus[i] - minus[i]
            } else {
                wrap_deg(plus[i] - minus[i])
            };
            g[(i, k)] = diff / (2.0 * h);
        }
    }
    let c = DMatrix::from_column_slice(6, 6, cov.as_slice());
    let out = &g * c * g.transpose();
    let mut u = [0.0; 6];
    for (i, slot) in u.iter_mut().enumerate() {
        *slot = out[(i, i)].max(0.0).sqrt();
    }
    PoseUncertainty { u }
}

/// Solves the normal equations `(JᵀJ)·δ = Jᵀr` with column scaling (the columns differ by
/// orders of magnitude: mm against rad·m); returns `δ` and `(JᵀJ)⁻¹`, or `None` if singular.
pub(crate) fn solve_normal(
    jac: &DMatrix<f64>,
    res: &DVector<f64>,
) -> Option<(DVector<f64>, DMatrix<f64>)> {
    let n = jac.ncols();
    let scale: Vec<f64> = (0..n)
        .map(|k| {
            let c = jac.column(k).norm();
            if c > 0.0 { 1.0 / c } else { 1.0 }
        })
        .collect();
    let mut js = jac.clone();
    for (k, s) in scale.iter().enumerate() {
        js.column_mut(k).scale_mut(*s);
    }
    let jtj = js.transpose() * &js;
    let inv = crate::track::uncertainty::invert_spd(&jtj)?;
    let step = &inv * (js.transpose() * res);
    let d = DMatrix::from_diagonal(&DVector::from_vec(scale));
    Some((&d * step, &d * inv * &d))
}
