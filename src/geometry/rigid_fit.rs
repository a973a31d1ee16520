//! Rigid fit of point pairs: the pose `T` minimising `Σ |q_j - T·p_j|²`.
//!
//! Closed form first (Kabsch/Horn: SVD of the cross-covariance, written out here), then
//! Gauss-Newton steps with the pseudo-inverse of the Jacobian (thesis eq. 4.28). For equal weights
//! the closed form is already the least-squares optimum; the refinement guards its numerics and
//! reports how far it moved. A weighted variant serves robust (iteratively reweighted) fits.
//!
//! Two figures say whether the fit can be trusted, whatever the residuals: the condition number
//! of the rotation and the scale ratio of the two point sets (see [`RigidFit`]).

use nalgebra::{
    DMatrix, DVector, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3,
};

use super::Pose;

/// Why point pairs do not define a rigid transform.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RigidFitError {
    /// Fewer than three pairs.
    #[error("{got} point pair(s), a rigid fit needs at least 3")]
    TooFewPoints {
        /// How many pairs were given.
        got: usize,
    },
    /// The two point lists differ in length (source, target).
    #[error("{0} source points and {1} target points")]
    LengthMismatch(usize, usize),
    /// The points lie on one line (or coincide): the rotation about it is undetermined.
    #[error("the points are collinear or coincident, so the rotation about their line is free")]
    Collinear,
    /// A coordinate is NaN or infinite.
    #[error("a coordinate is not a finite number")]
    NotFinite,
    /// nalgebra's SVD of the cross-covariance did not converge.
    #[error("the singular value decomposition did not converge")]
    Svd,
}

/// A fitted transform and how well it fits.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidFit {
    /// Maps source points onto target points: `q ≈ pose·p`.
    pub pose: Pose,
    /// `q_j - pose·p_j` per point.
    pub residuals: Vec<Vector3<f64>>,
    /// `sqrt(mean |residual|²)`.
    pub rms: f64,
    /// Gauss-Newton iterations taken after the closed form.
    pub iterations: usize,
    /// Condition number of the rotation: with `λ1 ≥ λ2 ≥ λ3` the eigenvalues of the (weighted)
    /// spread `Σ (p - p̄)(p - p̄)ᵀ` of the source points, `sqrt((λ1 + λ2) / (λ2 + λ3))`, the
    /// ratio of the best to the worst determined rotation (1 for a spread like a sphere's, √2
    /// for a square, growing without bound as the points approach a line).
    pub condition: f64,
    /// `sqrt(Σ |q - q̄|² / Σ |p - p̄|²)`: how much wider the target points are spread than the
    /// source points; 1 for a rigid motion.
    pub scale_ratio: f64,
}

impl RigidFit {
    /// `|residual|` per point (thesis Table 7.2's "rms" column).
    pub fn residual_norms(&self) -> Vec<f64> {
        self.residuals.iter().map(|r| r.norm()).collect()
    }
}

/// Fits `pose` with `target ≈ pose·source`.
pub fn fit_rigid(
    source: &[Point3<f64>],
    target: &[Point3<f64>],
) -> Result<RigidFit, RigidFitError> {
    fit_rigid_weighted(source, target, &vec![1.0; source.len()])
}

/// Fits `pose` minimising `Σ w_j |q_j - pose·p_j|²`; residuals are given for every point,
/// `rms` is over the points of positive weight. Weights must be finite and non-negative; at
/// least 3 must be positive.
pub fn fit_rigid_weighted(
    source: &[Point3<f64>],
    target: &[Point3<f64>],
    weights: &[f64],
) -> Result<RigidFit, RigidFitError> {
    if source.len() != target.len() {
        return Err(RigidFitError::LengthMismatch(source.len(), target.len()));
    }
    if weights.len() != source.len() {
        return Err(RigidFitError::LengthMismatch(source.len(), weights.len()));
    }
    let used = weights.iter().filter(|w| **w > 0.0).count();
    if used < 3 {
        return Err(RigidFitError::TooFewPoints { got: used });
    }
    if !weights.iter().all(|w| w.is_finite() && *w >= 0.0) {
        return Err(RigidFitError::NotFinite);
    }
    if source
        .iter()
        .chain(target)
        .any(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(RigidFitError::NotFinite);
    }
    let closed = kabsch(source, target, weights)?;
    let (pose, iterations) = gauss_newton(source, target, weights, closed.pose);
    let residuals: Vec<Vector3<f64>> = source
        .iter()
        .zip(target)
        .map(|(p, q)| q - pose * p)
        .collect();
    let rms = (residuals
        .iter()
        .zip(weights)
        .filter(|(_, w)| **w > 0.0)
        .map(|(r, _)| r.norm_squared())
        .sum::<f64>()
        / used as f64)
        .sqrt();
    Ok(RigidFit {
        pose,
        residuals,
        rms,
        iterations,
        condition: closed.condition,
        scale_ratio: closed.scale_ratio,
    })
}

fn centroid(points: &[Point3<f64>], weights: &[f64]) -> Vector3<f64> {
    let total: f64 = weights.iter().sum();
    points
        .iter()
        .zip(weights)
        .map(|(p, w)| p.coords * *w)
        .sum::<Vector3<f64>>()
        / total.max(f64::MIN_POSITIVE)
}

struct ClosedForm {
    pose: Pose,
    condition: f64,
    scale_ratio: f64,
}

/// Kabsch/Horn: `H = Σ w (p - p̄)(q - q̄)ᵀ = U Σ Vᵀ`, `R = V·diag(1, 1, det(V Uᵀ))·Uᵀ`.
fn kabsch(
    source: &[Point3<f64>],
    target: &[Point3<f64>],
    weights: &[f64],
) -> Result<ClosedForm, RigidFitError> {
    let pc = centroid(source, weights);
    let qc = centroid(target, weights);
    let mut h = Matrix3::zeros();
    let mut spread = Matrix3::zeros();
    let (mut source_sq, mut target_sq) = (0.0, 0.0);
    for ((p, q), w) in source.iter().zip(target).zip(weights) {
        let a = p.coords - pc;
        let b = q.coords - qc;
        h += a * b.transpose() * *w;
        spread += a * a.transpose() * *w;
        source_sq += w * a.norm_squared();
        target_sq += w * b.norm_squared();
    }
    // Coordinates near f64::MAX overflow when squared; an SVD of non-finite numbers never
    // converges.
    if !h.iter().chain(spread.iter()).all(|v| v.is_finite()) {
        return Err(RigidFitError::NotFinite);
    }
    // Collinear source points leave a rotation about their line undetermined: the second
    // singular value of their spread vanishes relative to the first.
    let sv = spread.symmetric_eigenvalues();
    let mut sorted = [sv[0], sv[1], sv[2]];
    sorted.sort_by(|a, b| b.total_cmp(a));
    let scale = sorted[0].max(f64::MIN_POSITIVE);
    if sorted[0] <= 1e-18 || sorted[1] <= 1e-12 * scale {
        return Err(RigidFitError::Collinear);
    }
    let condition = ((sorted[0] + sorted[1]) / (sorted[1] + sorted[2].max(0.0))).sqrt();
    let scale_ratio = (target_sq / source_sq).sqrt();
    let svd = h
        .try_svd(true, true, f64::EPSILON, 10_000)
        .ok_or(RigidFitError::Svd)?;
    let (u, v_t) = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => (u, v_t),
        _ => return Err(RigidFitError::Svd),
    };
    let v = v_t.transpose();
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = Rotation3::from_matrix_unchecked(v * d * u.transpose());
    let rot = UnitQuaternion::from_rotation_matrix(&r);
    let t = qc - rot * pc;
    Ok(ClosedForm {
        pose: Pose::from_parts(Translation3::from(t), rot),
        condition,
        scale_ratio,
    })
}

/// Gauss-Newton on a small-rotation update `T ← (δR, δt)·T` with the pseudo-inverse (thesis eq.
/// 4.28): residual `r_j = q_j - T p_j`, `∂r_j/∂(δθ, δt) = [ [T p_j]×, -I ]`.
/// With weights, each point's rows are scaled by `sqrt(w)`.
fn gauss_newton(
    source: &[Point3<f64>],
    target: &[Point3<f64>],
    weights: &[f64],
    start: Pose,
) -> (Pose, usize) {
    let n = source.len();
    let mut pose = start;
    let mut iterations = 0;
    for _ in 0..5 {
        let mut jac = DMatrix::<f64>::zeros(3 * n, 6);
        let mut res = DVector::<f64>::zeros(3 * n);
        for (j, ((p, q), w)) in source.iter().zip(target).zip(weights).enumerate() {
            let sw = w.sqrt();
            let tp = pose * p;
            let r = (q - tp) * sw;
            let x = tp.coords;
            // r(δ) = q - (tp + δθ × tp + δt) = r - (-[tp]× δθ + δt); J = ∂r/∂δ = [ [tp]×, -I ].
            let skew = x.cross_matrix() * sw;
            for a in 0..3 {
                res[3 * j + a] = r[a];
                for b in 0..3 {
                    jac[(3 * j + a, b)] = skew[(a, b)];
                }
                jac[(3 * j + a, 3 + a)] = -sw;
            }
        }
        if !jac.iter().chain(res.iter()).all(|v| v.is_finite()) {
            break;
        }
        let Ok(pinv) = jac.clone().pseudo_inverse(1e-12) else {
            break;
        };
        let delta = -(pinv * &res);
        iterations += 1;
        let dtheta = Vector3::new(delta[0], delta[1], delta[2]);
        let dt = Vector3::new(delta[3], delta[4], delta[5]);
        let update = Pose::from_parts(
            Translation3::from(dt),
            UnitQuaternion::from_scaled_axis(dtheta),
        );
        pose = update * pose;
        if dtheta.norm() < 1e-15 && dt.norm() < 1e-12 {
            break;
        }
    }
    (pose, iterations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose_xyz_deg;

    fn cloud() -> Vec<Point3<f64>> {
        vec![
            Point3::new(1200.0, 0.0, 900.0),
            Point3::new(1500.0, 600.0, 1200.0),
            Point3::new(900.0, -500.0, 400.0),
            Point3::new(1800.0, 200.0, 600.0),
        ]
    }

    #[test]
    fn recovers_an_exact_transform() {
        let t = pose_xyz_deg(2500.0, -1800.0, -650.0, 0.3, -1.2, 30.0);
        let src = cloud();
        let dst: Vec<_> = src.iter().map(|p| t * p).collect();
        let fit = fit_rigid(&src, &dst).unwrap();
        assert!((fit.pose.translation.vector - t.translation.vector).norm() < 1e-9);
        assert!(fit.pose.rotation.angle_to(&t.rotation) < 1e-12);
        assert!(fit.rms < 1e-9);
    }

    #[test]
    fn condition_and_scale_of_known_spreads() {
        let t = pose_xyz_deg(10.0, 20.0, 30.0, 5.0, -3.0, 40.0);
        // Cube corners: the spread is isotropic, every rotation equally determined.
        let cube: Vec<_> = (0..8)
            .map(|i| Point3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64) * 100.0)
            .collect();
        let on = |src: &[Point3<f64>], k: f64| -> Vec<Point3<f64>> {
            src.iter().map(|p| t * Point3::from(p.coords * k)).collect()
        };
        let fit = fit_rigid(&cube, &on(&cube, 1.0)).unwrap();
        assert!((fit.condition - 1.0).abs() < 1e-12, "{}", fit.condition);
        assert!((fit.scale_ratio - 1.0).abs() < 1e-12);
        // A square: λ = (a, a, 0), sqrt(2a / a).
        let square: Vec<_> = (0..4)
            .map(|i| Point3::new((i & 1) as f64 * 500.0, (i >> 1) as f64 * 500.0, 0.0))
            .collect();
        let fit = fit_rigid(&square, &on(&square, 1.0)).unwrap();
        assert!(
            (fit.condition - 2f64.sqrt()).abs() < 1e-12,
            "{}",
            fit.condition
        );
        let fit = fit_rigid(&square, &on(&square, 1000.0)).unwrap();
        assert!((fit.scale_ratio - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn a_zero_weight_removes_the_point() {
        let t = pose_xyz_deg(2500.0, -1800.0, -650.0, 0.3, -1.2, 30.0);
        let mut src = cloud();
        src.push(Point3::new(1300.0, -100.0, 1000.0));
        let mut dst: Vec<_> = src.iter().map(|p| t * p).collect();
        dst[4].x += 5.0;
        let fit = fit_rigid_weighted(&src, &dst, &[1.0, 1.0, 1.0, 1.0, 0.0]).unwrap();
        assert!((fit.pose.translation.vector - t.translation.vector).norm() < 1e-9);
        assert!(fit.rms < 1e-9);
        assert!((fit.residuals[4].x - 5.0).abs() < 1e-9);
        assert_eq!(
            fit_rigid_weighted(&src, &dst, &[1.0, 1.0, 0.0, 0.0, 0.0]),
            Err(RigidFitError::TooFewPoints { got: 2 })
        );
    }

    #[test]
    fn residuals_match_table_7_2_norms() {
        // Point 1 of thesis Table 7.2: (1.772, -1.084, -0.468) has rms 2.130 (the norm).
        let r = Vector3::<f64>::new(1.772, -1.084, -0.468);
        assert!((r.norm() - 2.130).abs() < 1e-3);
    }

    #[test]
    fn refuses_collinear_and_too_few() {
        let huge = vec![
            Point3::new(1e300, 0.0, 0.0),
            Point3::new(0.0, 1e300, 0.0),
            Point3::origin(),
        ];
        assert_eq!(fit_rigid(&huge, &huge), Err(RigidFitError::NotFinite));
        let line: Vec<_> = (0..5)
            .map(|i| Point3::new(i as f64 * 100.0, 2.0 * i as f64, 0.0))
            .collect();
        assert_eq!(fit_rigid(&line, &line), Err(RigidFitError::Collinear));
        let two = &cloud()[..2];
        assert_eq!(
            fit_rigid(two, two),
            Err(RigidFitError::TooFewPoints { got: 2 })
        );
    }
}
