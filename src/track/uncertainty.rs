//! Uncertainty of a track profile, from the tracker and robot noise to `D(s)` and to a corrected
//! TCP (docs/design.md §14 §6).
//!
//! 1. **Frame**: the base frame at one skid is a rigid fit of `n` point pairs. With independent
//!    noise `σ` per axis, its covariance in the perturbation `F = F̂·(δt, δθ)` is
//!    `σ²·(JᵀJ)⁻¹`, `J_j = [I, -[p_j]×]` (the fitted rotation drops out of `JᵀJ`). `σ` is given, or
//!    pooled from the residuals of all skids: `σ̂² = Σ|r|² / Σ(3n_i - 6)`.
//! 2. **Knot**: `D_i = N(s_i)⁻¹·F_i` with `D_i ≈ I`, so the knot's components move by `(δt, δθ)`.
//!    The nominal's own error is affine in `s` and cancels in `N(s)·D(s)` (a spline reproduces
//!    affine functions), so knots are independent with the frame's standard uncertainties.
//! 3. **Between knots**: the spline is linear in the knot values, `S(s) = Σ w_i(s)·y_i`, so the
//!    noise part is `Σ w_i(s)²·u_i²`. The interpolation error is estimated by leave-one-out: the
//!    spline without interior knot `i` misses it by `e_i`, of which `u_i² + Σ w'_j(s_i)²u_j²` is
//!    noise. In an interval the interpolation uncertainty is
//!    `ê·16t²(1-t)²·INTERPOLATION_SHARE` (`ê` the larger noise-free leave-one-out miss at its
//!    two ends, or at the nearest interior knot for an end interval; `t` the position in the
//!    interval: zero at the knots, `ê·INTERPOLATION_SHARE` in the middle).

use std::collections::BTreeMap;

use nalgebra::{DMatrix, Matrix3, Matrix6, Point3, Vector3};

use super::error::{SkidProblem, TrackError};
use super::identify::Identification;
use super::profile::{Extrapolate, KnotUncertainty, Profile};
use super::simulate::MeasurementRow;
use super::spline::{CubicSpline, EndCondition};
use crate::geometry::Pose;

/// The interpolation uncertainty in the middle of an interval, as a share of the noise-free
/// leave-one-out miss `ê` (which is taken at twice the spacing). A smooth track's `h⁴` law
/// would give 1/16 (and `h²` near the natural ends 1/4): calibrated at 3-4 knots per wavelength
/// of the rail's waviness, but 76 % coverage at the 2 knots per wavelength `track spectrum`
/// recommends, where leave-one-out cannot tell a resolved waviness from an aliased one. 1/2
/// keeps the coverage of 2u at 91-98 % from 2 to 4 knots per wavelength and 500-1000 mm spacing
/// (tests/it/frames.rs), on the safe side where the sampling is fine. Sampled coarser than the
/// spectrum recommends, the leave-one-out cannot see the waviness and the uncertainty is too
/// small.
pub const INTERPOLATION_SHARE: f64 = 0.5;

/// Where the noise level used for an uncertainty came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sigma {
    /// Given by the user (tracker and robot noise combined, per axis), mm.
    Given(f64),
    /// Pooled from the fit's residuals.
    Estimated {
        /// The pooled standard deviation, mm.
        sigma: f64,
        /// Residual count minus fitted parameters: how far the estimate can be trusted.
        dof: usize,
    },
}

impl Sigma {
    /// The value in mm.
    pub fn value(&self) -> f64 {
        match *self {
            Sigma::Given(s) => s,
            Sigma::Estimated { sigma, .. } => sigma,
        }
    }

    /// `"given"` or `"residuals"`.
    pub fn source(&self) -> &'static str {
        match self {
            Sigma::Given(_) => "given",
            Sigma::Estimated { .. } => "residuals",
        }
    }
}

/// `(JᵀJ)⁻¹` of a rigid fit of `source` points in the right perturbation `(δt, δθ)` (mm, rad),
/// or `None` when the points do not fix all six (collinear, fewer than 3).
pub fn rigid_fit_cofactor(source: &[Point3<f64>]) -> Option<Matrix6<f64>> {
    let mut jtj = Matrix6::<f64>::zeros();
    for p in source {
        let skew = p.coords.cross_matrix();
        let mut a = nalgebra::Matrix3x6::<f64>::zeros();
        a.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        a.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-skew));
        jtj += a.transpose() * a;
    }
    let inv = invert_spd(&DMatrix::from_column_slice(6, 6, jtj.as_slice()))?;
    Some(Matrix6::from_column_slice(inv.as_slice()))
}

/// Inverse of a symmetric positive definite matrix via its eigen decomposition; `None` if
/// it is singular to working precision.
pub fn invert_spd(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if !m.is_square() || !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let eig = m.clone().symmetric_eigen();
    let max = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 || eig.eigenvalues.iter().any(|&l| l <= max * 1e-14) {
        return None;
    }
    let inv = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l));
    Some(&eig.eigenvectors * inv * eig.eigenvectors.transpose())
}

/// The standard uncertainties of each identified frame (`[u_dx, …, u_rz]` in mm and degrees,
/// and those of a point at the centroid of its points), in the order of `ident.fits`, and the
/// noise level used.
pub fn knot_uncertainties(
    rows: &[MeasurementRow],
    ident: &Identification,
    sigma: Option<f64>,
) -> Result<(Vec<KnotUncertainty>, Sigma), TrackError> {
    let mut by_skid: BTreeMap<u64, Vec<Point3<f64>>> = BTreeMap::new();
    for r in rows {
        by_skid
            .entry(r.skid.to_bits())
            .or_default()
            .push(Point3::from(r.robot));
    }
    let sigma = match sigma {
        Some(s) if s.is_finite() && s >= 0.0 => Sigma::Given(s),
        Some(s) => {
            return Err(TrackError::NoiseLevel { sigma: s });
        }
        None => {
            let ssr: f64 = ident
                .fits
                .iter()
                .flat_map(|f| f.fit.residuals.iter().map(|r| r.norm_squared()))
                .sum();
            let dof: usize = ident
                .fits
                .iter()
                .map(|f| (3 * f.fit.residuals.len()).saturating_sub(6))
                .sum();
            if dof == 0 {
                return Err(TrackError::NoNoiseEstimate { points: rows.len() });
            }
            Sigma::Estimated {
                sigma: (ssr / dof as f64).sqrt(),
                dof,
            }
        }
    };
    let s = sigma.value();
    let mut out = Vec::with_capacity(ident.fits.len());
    for f in &ident.fits {
        let points = by_skid
            .get(&f.skid.to_bits())
            .map(Vec::as_slice)
            .unwrap_or(&[]);
        let cof = rigid_fit_cofactor(points).ok_or(TrackError::Skid {
            skid: f.skid,
            problem: SkidProblem::Unconstrained,
        })?;
        let mut u = [0.0; 6];
        for (i, slot) in u.iter_mut().enumerate() {
            let v = s * cof[(i, i)].max(0.0).sqrt();
            *slot = if i < 3 { v } else { v.to_degrees() };
        }
        // At the centroid, position and rotation decouple: `JᵀJ` there has no cross block,
        // so a point's covariance is σ²/n per axis.
        let n = points.len().max(1) as f64;
        let c = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
        out.push(KnotUncertainty {
            u,
            centre: [c.x, c.y, c.z],
            centre_xyz: [s / n.sqrt(); 3],
        });
    }
    Ok((out, sigma))
}

/// Standard uncertainties (k = 1) of `D(s)` at one skid: `[dx, dy, dz, rx, ry, rz]`, mm and
/// degrees, split by cause.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviationUncertainty {
    /// The skid the uncertainties are evaluated at, mm.
    pub skid: f64,
    /// Combined: `sqrt(noise² + interpolation²)`.
    pub u: [f64; 6],
    /// From the identification noise of the knots.
    pub noise: [f64; 6],
    /// From interpolating between knots (zero at a knot).
    pub interpolation: [f64; 6],
}

/// What is needed to evaluate the uncertainty of `D(s)` anywhere.
#[derive(Clone, Debug)]
pub struct ProfileUncertainty {
    skids: Vec<f64>,
    knot_u: Vec<[f64; 6]>,
    /// `w_i(s)`: the spline through the `i`-th unit vector.
    cardinal: Vec<CubicSpline>,
    /// Noise-free leave-one-out miss `ê` per knot (0 at the ends), mm and degrees.
    loo: Vec<[f64; 6]>,
    /// Per knot, the identification points' centroid and a point's uncertainty there, if the
    /// profile has them.
    centres: Option<Vec<([f64; 3], [f64; 3])>>,
    extrapolate: Extrapolate,
}

fn cardinal_splines(xs: &[f64]) -> Result<Vec<CubicSpline>, TrackError> {
    (0..xs.len())
        .map(|i| {
            let ys: Vec<f64> = (0..xs.len())
                .map(|j| if i == j { 1.0 } else { 0.0 })
                .collect();
            CubicSpline::new(xs, &ys, EndCondition::Natural).map_err(|error| TrackError::Knots {
                context: "uncertainty of the profile".to_string(),
                error,
            })
        })
        .collect()
}

impl ProfileUncertainty {
    /// `None` when the profile's knots carry no uncertainties (fitted without measurements).
    pub fn new(profile: &Profile) -> Result<Option<ProfileUncertainty>, TrackError> {
        let knots = profile.knots();
        let Some(knot_u) = knots
            .iter()
            .map(|k| k.uncertainty())
            .collect::<Option<Vec<_>>>()
        else {
            return Ok(None);
        };
        let skids: Vec<f64> = knots.iter().map(|k| k.skid).collect();
        let cardinal = cardinal_splines(&skids)?;
        let n = skids.len();
        let mut loo = vec![[0.0; 6]; n];
        // A spline needs 2 knots, so leaving one out needs 3; the ends cannot be left out
        // without extrapolating.
        if n >= 3 {
            for i in 1..n - 1 {
                let xs: Vec<f64> = skids
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, s)| *s)
                    .collect();
                let reduced = cardinal_splines(&xs)?;
                let w: Vec<f64> = reduced.iter().map(|c| c.value(skids[i])).collect();
                let others: Vec<usize> = (0..n).filter(|j| *j != i).collect();
                for c in 0..6 {
                    let predicted: f64 = others
                        .iter()
                        .zip(&w)
                        .map(|(&j, wj)| wj * knots[j].components()[c])
                        .sum();
                    let miss = predicted - knots[i].components()[c];
                    let noise_var = knot_u[i][c].powi(2)
                        + others
                            .iter()
                            .zip(&w)
                            .map(|(&j, wj)| (wj * knot_u[j][c]).powi(2))
                            .sum::<f64>();
                    loo[i][c] = (miss * miss - noise_var).max(0.0).sqrt();
                }
            }
        }
        let centres = knots
            .iter()
            .map(|k| k.centre_uncertainty())
            .collect::<Option<Vec<_>>>();
        Ok(Some(ProfileUncertainty {
            skids,
            knot_u,
            cardinal,
            loo,
            centres,
            extrapolate: profile.extrapolate(),
        }))
    }

    /// `w_i(s)`, or why `s` is refused.
    fn weights(&self, skid: f64) -> Result<(Vec<f64>, bool), TrackError> {
        let (min, max) = (
            self.skids.first().copied().unwrap_or(0.0),
            self.skids.last().copied().unwrap_or(0.0),
        );
        let tol = 1e-9 * (1.0 + min.abs().max(max.abs()));
        let inside = skid >= min - tol && skid <= max + tol;
        if !skid.is_finite() || (!inside && self.extrapolate == Extrapolate::Error) {
            return Err(TrackError::OutOfRange { skid, min, max });
        }
        let end = skid.clamp(min, max);
        let weight = |c: &CubicSpline| match self.extrapolate {
            Extrapolate::Linear if !inside => c.value(end) + c.derivative(end) * (skid - end),
            _ => c.value(end),
        };
        Ok((self.cardinal.iter().map(weight).collect(), inside))
    }

    /// The standard uncertainties of `D(s)`; outside the knots as the profile's extrapolation
    /// rule says (an error for `extrapolate = "error"`).
    pub fn at(&self, skid: f64) -> Result<DeviationUncertainty, TrackError> {
        let (w, inside) = self.weights(skid)?;
        let end = skid.clamp(
            self.skids.first().copied().unwrap_or(0.0),
            self.skids.last().copied().unwrap_or(0.0),
        );
        let mut noise = [0.0; 6];
        for (c, slot) in noise.iter_mut().enumerate() {
            *slot = w
                .iter()
                .zip(&self.knot_u)
                .map(|(wi, u)| (wi * u[c]).powi(2))
                .sum::<f64>()
                .sqrt();
        }
        let mut interpolation = [0.0; 6];
        let n = self.skids.len();
        if n >= 2 {
            let k = self
                .skids
                .partition_point(|&x| x <= end)
                .saturating_sub(1)
                .min(n - 2);
            let h = self.skids[k + 1] - self.skids[k];
            // Outside the range (clamp/linear) the error is at least the interval's worst.
            let t = if inside {
                ((end - self.skids[k]) / h).clamp(0.0, 1.0)
            } else {
                0.5
            };
            let shape = 16.0 * t * t * (1.0 - t) * (1.0 - t) * INTERPOLATION_SHARE;
            for (c, slot) in interpolation.iter_mut().enumerate() {
                let e = self.loo[k][c].max(self.loo[k + 1][c]);
                *slot = e * shape;
            }
        }
        let mut u = [0.0; 6];
        for c in 0..6 {
            u[c] = noise[c].hypot(interpolation[c]);
        }
        Ok(DeviationUncertainty {
            skid,
            u,
            noise,
            interpolation,
        })
    }
}

impl ProfileUncertainty {
    /// The covariance (mm², base axes) between the errors that `D(s)` puts on a point `qa` at
    /// skid `sa` and on a point `qb` at skid `sb` (points in the robot base at their skid).
    /// A knot's error is a position error at its centroid `c_i` plus a rotation `δθ_i` about
    /// it, independent of each other (exact for the rigid fit), so the knots contribute
    /// `Σ w_i(sa)·w_i(sb)·(C_c,i + [qa−c_i]×·C_θ,i·[qb−c_i]×ᵀ)`. Without centroids (older
    /// profiles) the knots' six components are taken as independent about the base origin,
    /// which overstates the uncertainty near the identification points. The interpolation
    /// error is independent between skids and, at one skid, independent translation and
    /// rotation errors.
    pub fn point_covariance(
        &self,
        (sa, qa): (f64, &Vector3<f64>),
        (sb, qb): (f64, &Vector3<f64>),
    ) -> Result<Matrix3<f64>, TrackError> {
        let (wa, _) = self.weights(sa)?;
        let (wb, _) = self.weights(sb)?;
        let diag = |v: [f64; 3]| Matrix3::from_diagonal(&Vector3::from(v).map(|x| x * x));
        let rad = |u: &[f64; 6]| [u[3], u[4], u[5]].map(f64::to_radians);
        let mut cov = Matrix3::<f64>::zeros();
        for (i, u) in self.knot_u.iter().enumerate() {
            let (c, cov_c) = match &self.centres {
                Some(cs) => (Vector3::from(cs[i].0), diag(cs[i].1)),
                None => (Vector3::zeros(), diag([u[0], u[1], u[2]])),
            };
            let arm_a = (qa - c).cross_matrix();
            let arm_b = (qb - c).cross_matrix();
            cov += (cov_c + arm_a * diag(rad(u)) * arm_b.transpose()) * (wa[i] * wb[i]);
        }
        if sa == sb {
            let ip = self.at(sa)?.interpolation;
            cov += diag([ip[0], ip[1], ip[2]])
                + qa.cross_matrix() * diag(rad(&ip)) * qb.cross_matrix().transpose();
        }
        Ok(cov)
    }

    /// The uncertainty of the corrected TCP for a target at skid `s` whose TCP is at
    /// `tcp_in_base` (offset from the robot base, base frame, mm): the track's part, from
    /// [`ProfileUncertainty::point_covariance`].
    pub fn tcp_at(
        &self,
        skid: f64,
        tcp_in_base: &Vector3<f64>,
    ) -> Result<TcpUncertainty, TrackError> {
        let cov = self.point_covariance((skid, tcp_in_base), (skid, tcp_in_base))?;
        Ok(TcpUncertainty {
            u: [0, 1, 2].map(|i| cov[(i, i)].max(0.0).sqrt()),
            expanded: 2.0 * cov.trace().max(0.0).sqrt(),
        })
    }
}

/// Uncertainty of a corrected TCP at one skid (the track's part).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TcpUncertainty {
    /// Standard uncertainty (k = 1) along the robot base axes x, y, z at that skid, mm.
    pub u: [f64; 3],
    /// `2·sqrt(u_x² + u_y² + u_z²)`, mm: the expanded uncertainty (k = 2) of the TCP's
    /// position error. It covers `|error|` with a probability between 95 % (error along one
    /// axis) and 99 % (isotropic).
    pub expanded: f64,
}

/// The uncertainty of a TCP at `tcp_in_base` (offset from the robot base, base frame, mm) from
/// the standard uncertainties of `D(s)` alone: a base error `(δt, δθ)` moves the TCP by
/// `δt + δθ × r`. The six components are taken as independent, which overstates the
/// uncertainty of TCPs near the points the knots were identified from (the origin's position
/// error and the rotation error are correlated); [`ProfileUncertainty::tcp_at`] does better
/// where the profile has the knots' centroids.
pub fn tcp_uncertainty(dev: &DeviationUncertainty, tcp_in_base: &Vector3<f64>) -> TcpUncertainty {
    let du = dev.u;
    let rad = |d: f64| d.to_radians();
    let cov_t = Matrix3::from_diagonal(&Vector3::new(du[0] * du[0], du[1] * du[1], du[2] * du[2]));
    let cov_r = Matrix3::from_diagonal(&Vector3::new(
        rad(du[3]).powi(2),
        rad(du[4]).powi(2),
        rad(du[5]).powi(2),
    ));
    let skew = tcp_in_base.cross_matrix();
    let cov = cov_t + skew * cov_r * skew.transpose();
    let u = [
        cov[(0, 0)].max(0.0).sqrt(),
        cov[(1, 1)].max(0.0).sqrt(),
        cov[(2, 2)].max(0.0).sqrt(),
    ];
    TcpUncertainty {
        u,
        expanded: 2.0 * cov.trace().max(0.0).sqrt(),
    }
}

/// [`ProfileUncertainty::tcp_at`] for a target given in world: `base` is the robot base `B(s)` in world at
/// that skid, `tcp_in_world` the corrected TCP position.
pub fn tcp_uncertainty_world(
    profile_u: &ProfileUncertainty,
    base: &Pose,
    skid: f64,
    tcp_in_world: &Point3<f64>,
) -> Result<TcpUncertainty, TrackError> {
    let r = base.inverse() * tcp_in_world;
    profile_u.tcp_at(skid, &r.coords)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::Knot;

    #[test]
    fn cofactor_of_a_symmetric_cloud_is_closed_form() {
        // Six points at ±d on the axes: JᵀJ = [[6I, 0], [0, 4d²I]] (centred, Σ(|p|²I - ppᵀ)).
        let d = 500.0;
        let pts: Vec<Point3<f64>> = [
            [d, 0.0, 0.0],
            [-d, 0.0, 0.0],
            [0.0, d, 0.0],
            [0.0, -d, 0.0],
            [0.0, 0.0, d],
            [0.0, 0.0, -d],
        ]
        .into_iter()
        .map(Point3::from)
        .collect();
        let c = rigid_fit_cofactor(&pts).unwrap();
        assert!((c[(0, 0)] - 1.0 / 6.0).abs() < 1e-12);
        assert!((c[(3, 3)] - 1.0 / (4.0 * d * d)).abs() < 1e-15);
        assert!(c[(0, 3)].abs() < 1e-15);
        let line: Vec<_> = (0..4).map(|i| Point3::new(i as f64, 0.0, 0.0)).collect();
        assert!(rigid_fit_cofactor(&line).is_none());
    }

    #[test]
    fn noise_between_knots_follows_the_spline_weights() {
        // Linear data: the leave-one-out miss is pure noise, so only the noise part remains;
        // at a knot it is that knot's u, between two knots with equal u it is below u.
        let knots: Vec<Knot> = (0..5)
            .map(|i| {
                Knot::from_components(
                    i as f64 * 1000.0,
                    [0.001 * i as f64, 0.0, 0.0, 0.0, 0.0, 0.0],
                )
                .with_uncertainty(Some([0.01; 6]))
            })
            .collect();
        let p = Profile::from_knots("t", knots, Extrapolate::Error).unwrap();
        let pu = ProfileUncertainty::new(&p).unwrap().unwrap();
        let at_knot = pu.at(2000.0).unwrap();
        assert!((at_knot.u[0] - 0.01).abs() < 1e-12, "{at_knot:?}");
        let mid = pu.at(2500.0).unwrap();
        assert!(mid.u[0] < 0.01 && mid.u[0] > 0.005, "{mid:?}");
        assert!(mid.interpolation.iter().all(|v| *v < 1e-9), "{mid:?}");
        assert!(pu.at(4001.0).is_err());
    }

    #[test]
    fn world_and_base_tcp_agree() {
        let knots: Vec<Knot> = (0..4)
            .map(|i| {
                Knot::from_components(i as f64 * 1000.0, [0.0; 6])
                    .with_uncertainty(Some([0.01, 0.02, 0.03, 0.001, 0.002, 0.003]))
            })
            .collect();
        let p = Profile::from_knots("t", knots, Extrapolate::Error).unwrap();
        let pu = ProfileUncertainty::new(&p).unwrap().unwrap();
        let base = crate::geometry::pose_xyz_deg(100.0, -3500.0, 20.0, 0.0, 0.0, 90.0);
        let r = Vector3::new(1500.0, 300.0, 900.0);
        let a = pu.tcp_at(1500.0, &r).unwrap();
        let b = tcp_uncertainty_world(&pu, &base, 1500.0, &(base * Point3::from(r))).unwrap();
        assert!((a.expanded - b.expanded).abs() < 1e-12);
        // No centroids: the same as the independent-components figure.
        let c = tcp_uncertainty(&pu.at(1500.0).unwrap(), &r);
        assert!((a.expanded - c.expanded).abs() < 1e-9, "{a:?} {c:?}");
    }

    #[test]
    fn tcp_uncertainty_adds_the_lever_arm() {
        let dev = DeviationUncertainty {
            skid: 0.0,
            u: [0.0, 0.0, 0.0, 0.0, 0.0, (0.001f64).to_degrees()],
            noise: [0.0; 6],
            interpolation: [0.0; 6],
        };
        // 1 mrad about z at 1 m along x moves the TCP 1 mm along y.
        let t = tcp_uncertainty(&dev, &Vector3::new(1000.0, 0.0, 0.0));
        assert!((t.u[1] - 1.0).abs() < 1e-9 && t.u[0].abs() < 1e-12, "{t:?}");
        assert!((t.expanded - 2.0).abs() < 1e-9);
    }
}
