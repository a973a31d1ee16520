//! `frame base`: the robot base at skid 0, `B0`, and the unit track axis `a` in the cell (world)
//! frame from TCP points measured at any skid positions, with `meas ≈ Trans(s·a)·B0·D(s)·robot`
//! (thesis §7.3; `D = I` is the uncompensated fit the thesis compares against, Table 7.2).
//!
//! Eight parameters: `B0` perturbed on the right, `B0·(δt, δθ)`, and `a` tilted in its normal
//! plane, `a ← (a + α·e1 + β·e2)/|…|`. The start is closed form (the rotation from the skid
//! with the most points, then a straight line of `meas - R·q` over `s`), then Gauss-Newton.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Point3, Vector3};

use super::{
    FrameError, PointResidual, PoseUncertainty, Underdetermined, perturb_right, rms, sigma_of,
    solve_normal, xyz_deg_uncertainty,
};
use crate::geometry::Pose;
use crate::geometry::rigid_fit::fit_rigid;
use crate::track::csv_table::NumericCsv;
use crate::track::identify::MEASUREMENTS_HEADER;
use crate::track::profile::line_fit;
use crate::track::simulate::MeasurementRow;
use crate::track::uncertainty::{ProfileUncertainty, Sigma};
use crate::track::{Profile, TrackError};

/// The fitted base and track axis.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseFit {
    /// `B0`: the robot base at skid 0 in world.
    pub base0: Pose,
    /// `a`: the unit track direction in world.
    pub track_axis: Vector3<f64>,
    /// `meas - Trans(s·a)·B0·D(s)·robot` per row, in input order.
    pub residuals: Vec<PointResidual>,
    /// `sqrt(mean |residual|²)`, mm.
    pub rms: f64,
    /// Whether `D(s)` of a profile was applied.
    pub compensated: bool,
    /// The noise level the uncertainties below are scaled by, and where it came from.
    pub sigma: Sigma,
    /// Of `B0`'s `x, y, z, rx, ry, rz`.
    pub u_base: PoseUncertainty,
    /// Of the three components of `a`.
    pub u_axis: [f64; 3],
    /// RMS over the measured points of the standard uncertainty (root of the covariance's
    /// trace) of the modelled point, mm: how well the fitted frame places a TCP in the
    /// measured volume.
    pub u_point: f64,
    /// Gauss-Newton steps taken until the step fell below the convergence threshold.
    pub iterations: usize,
}

/// Reads `POINTS.csv` (the columns of `measurements.csv`); unlike `track identify`, any number
/// of points per skid is fine. A point measured twice at one skid is an error at its line.
pub fn read_points(path: &Path) -> Result<Vec<MeasurementRow>, TrackError> {
    points_from(&NumericCsv::read(path, &MEASUREMENTS_HEADER)?)
}

/// The points of a table read with [`MEASUREMENTS_HEADER`] (whose notes the caller shows).
pub fn points_from(table: &NumericCsv) -> Result<Vec<MeasurementRow>, TrackError> {
    let mut seen: BTreeMap<(u64, u64), u64> = BTreeMap::new();
    let mut rows = Vec::new();
    for (line, [skid, point, rx, ry, rz, mx, my, mz]) in table.select(&MEASUREMENTS_HEADER)? {
        if point < 0.0 || point.fract() != 0.0 || point > u32::MAX as f64 {
            return Err(table.error(
                line,
                "point",
                format!("`{point}` is not a point number"),
                "number the points 0, 1, 2, ...",
            ));
        }
        if let Some(first) = seen.insert((skid.to_bits(), point.to_bits()), line) {
            return Err(table.error(
                line,
                "point",
                format!("point {point} at skid {skid} was already measured on line {first}"),
                "keep one row per point and skid",
            ));
        }
        rows.push(MeasurementRow {
            skid,
            point: point as u32,
            robot: [rx, ry, rz],
            meas: [mx, my, mz],
        });
    }
    Ok(rows)
}

/// Two unit vectors spanning the plane normal to `a`.
fn normal_basis(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = a.cross(&helper).normalize();
    let e2 = a.cross(&e1);
    (e1, e2)
}

/// Fits `B0` and `a` to `rows`; with `profile`, the robot points are first moved by `D(s)`.
/// `sigma` is the noise per axis (tracker and robot together), else estimated from the
/// residuals with `3n - 8` degrees of freedom; a profile with knot uncertainties adds its own.
pub fn fit_base(
    rows: &[MeasurementRow],
    profile: Option<&Profile>,
    sigma: Option<f64>,
) -> Result<BaseFit, FrameError> {
    if rows.len() < 4 {
        return Err(Underdetermined::TooFewBasePoints { got: rows.len() }.into());
    }
    let mut q = Vec::with_capacity(rows.len());
    for r in rows {
        let p = Point3::from(r.robot);
        q.push(match profile {
            Some(pr) => pr.deviation(r.skid)? * p,
            None => p,
        });
    }
    let meas: Vec<Point3<f64>> = rows.iter().map(|r| Point3::from(r.meas)).collect();
    let skids: Vec<f64> = rows.iter().map(|r| r.skid).collect();
    let (mut base0, mut axis) = start(rows, &q, &meas, &skids)?;
    let n = rows.len();
    let mut iterations = 0;
    let mut cof = DMatrix::<f64>::zeros(8, 8);
    for _ in 0..50 {
        let (jac, res) = linearise(&base0, &axis, &q, &meas, &skids);
        let (step, inv) = solve_normal(&jac, &res)
            .ok_or_else(|| FrameError::from(Underdetermined::BaseAndAxis))?;
        cof = inv;
        iterations += 1;
        base0 = perturb_right(&base0, &step.as_slice()[..6]);
        let (e1, e2) = normal_basis(&axis);
        axis = (axis + e1 * step[6] + e2 * step[7]).normalize();
        let small = step.rows(0, 3).norm() < 1e-10
            && step.rows(3, 3).norm() < 1e-13
            && step.rows(6, 2).norm() < 1e-13;
        if small {
            break;
        }
    }
    let residuals: Vec<PointResidual> = rows
        .iter()
        .enumerate()
        .map(|(j, r)| PointResidual {
            skid: r.skid,
            point: r.point,
            residual: meas[j] - model(&base0, &axis, &q[j], skids[j]),
        })
        .collect();
    // The profile's own uncertainty moves all points at a skid together (and points at
    // neighbouring skids through shared knots): not independent noise, so it enters as
    // `(JᵀJ)⁻¹·Jᵀ·Σ_D·J·(JᵀJ)⁻¹`. The residual-based σ̂ already holds part of it, so this errs
    // on the safe side (taking that part out, `tr((I − H)·Σ_D)`, undercovers: Σ_D's
    // interpolation part is itself conservative).
    let (jac, _) = linearise(&base0, &axis, &q, &meas, &skids);
    let sigma = sigma_of(sigma, &residuals, 8)?;
    let mut cov = &cof * sigma.value().powi(2);
    if let Some(pr) = profile
        && let Some(pu) = ProfileUncertainty::new(pr)?
    {
        let sd = profile_covariance(&pu, &base0, &q, &skids)?;
        cov += &cof * (jac.transpose() * sd * &jac) * &cof;
    }
    let cov6 = Matrix6::from_fn(|i, k| cov[(i, k)]);
    let u_base = xyz_deg_uncertainty(&base0, &cov6);
    let (e1, e2) = normal_basis(&axis);
    let e = nalgebra::Matrix3x2::from_columns(&[e1, e2]);
    let cab = nalgebra::Matrix2::new(cov[(6, 6)], cov[(6, 7)], cov[(7, 6)], cov[(7, 7)]);
    let ca: Matrix3<f64> = e * cab * e.transpose();
    let u_axis = [0, 1, 2].map(|i| ca[(i, i)].max(0.0).sqrt());
    let mut sum = 0.0;
    for j in 0..n {
        let jj = jac.rows(3 * j, 3);
        let c = jj * &cov * jj.transpose();
        sum += c.trace().max(0.0);
    }
    let u_point = (sum / n as f64).sqrt();
    Ok(BaseFit {
        base0,
        track_axis: axis,
        rms: rms(&residuals),
        residuals,
        compensated: profile.is_some(),
        sigma,
        u_base,
        u_axis,
        u_point,
        iterations,
    })
}

/// `Σ_D` (3n × 3n, world axes): the covariance the profile's uncertainty puts on the points.
fn profile_covariance(
    pu: &ProfileUncertainty,
    base0: &Pose,
    q: &[Point3<f64>],
    skids: &[f64],
) -> Result<DMatrix<f64>, TrackError> {
    let n = q.len();
    let r = base0.rotation.to_rotation_matrix().into_inner();
    let mut out = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for j in 0..n {
        for k in j..n {
            let c = pu.point_covariance((skids[j], &q[j].coords), (skids[k], &q[k].coords))?;
            let world = r * c * r.transpose();
            for a in 0..3 {
                for b in 0..3 {
                    out[(3 * j + a, 3 * k + b)] = world[(a, b)];
                    out[(3 * k + b, 3 * j + a)] = world[(a, b)];
                }
            }
        }
    }
    Ok(out)
}

fn model(base0: &Pose, axis: &Vector3<f64>, q: &Point3<f64>, skid: f64) -> Point3<f64> {
    base0 * q + axis * skid
}

/// Jacobian of the model (rows: x, y, z per point; columns: δt, δθ, α, β) and `meas - model`.
fn linearise(
    base0: &Pose,
    axis: &Vector3<f64>,
    q: &[Point3<f64>],
    meas: &[Point3<f64>],
    skids: &[f64],
) -> (DMatrix<f64>, DVector<f64>) {
    let n = q.len();
    let r = base0.rotation.to_rotation_matrix().into_inner();
    let (e1, e2) = normal_basis(axis);
    let mut jac = DMatrix::<f64>::zeros(3 * n, 8);
    let mut res = DVector::<f64>::zeros(3 * n);
    for j in 0..n {
        let d_theta = -r * q[j].coords.cross_matrix();
        let e = meas[j] - model(base0, axis, &q[j], skids[j]);
        for a in 0..3 {
            res[3 * j + a] = e[a];
            for b in 0..3 {
                jac[(3 * j + a, b)] = r[(a, b)];
                jac[(3 * j + a, 3 + b)] = d_theta[(a, b)];
            }
            jac[(3 * j + a, 6)] = skids[j] * e1[a];
            jac[(3 * j + a, 7)] = skids[j] * e2[a];
        }
    }
    (jac, res)
}

/// The closed-form start: the rotation from the skid with the most points, then `meas - R·q`
/// as a straight line over the skid.
fn start(
    rows: &[MeasurementRow],
    q: &[Point3<f64>],
    meas: &[Point3<f64>],
    skids: &[f64],
) -> Result<(Pose, Vector3<f64>), FrameError> {
    let mut groups: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (j, r) in rows.iter().enumerate() {
        groups.entry(r.skid.to_bits()).or_default().push(j);
    }
    if groups.len() < 2 {
        return Err(Underdetermined::OneSkid.into());
    }
    let mut order: Vec<&Vec<usize>> = groups.values().collect();
    order.sort_by_key(|g| std::cmp::Reverse(g.len()));
    let rotation = order
        .iter()
        .filter(|g| g.len() >= 3)
        .find_map(|g| {
            let src: Vec<Point3<f64>> = g.iter().map(|&j| q[j]).collect();
            let dst: Vec<Point3<f64>> = g.iter().map(|&j| meas[j]).collect();
            fit_rigid(&src, &dst).ok().map(|f| f.pose.rotation)
        })
        .ok_or_else(|| FrameError::from(Underdetermined::NoRotation))?;
    let offsets: Vec<Vector3<f64>> = q
        .iter()
        .zip(meas)
        .map(|(q, m)| m.coords - rotation * q.coords)
        .collect();
    let mut t = Vector3::zeros();
    let mut v = Vector3::zeros();
    for c in 0..3 {
        let ys: Vec<f64> = offsets.iter().map(|o| o[c]).collect();
        let (intercept, slope) = line_fit(skids, &ys);
        t[c] = intercept;
        v[c] = slope;
    }
    let axis = v
        .try_normalize(1e-9)
        .ok_or_else(|| FrameError::from(Underdetermined::NoTrackDirection))?;
    Ok((
        Pose::from_parts(nalgebra::Translation3::from(t), rotation),
        axis,
    ))
}

/// The TCP error of a fitted base against the true base frames, for tests and reports: the
/// largest `|B(s)·D(s)·p - truth(s)·p|` over `skids` and `tcp` points.
pub fn tcp_error(
    fit: &BaseFit,
    profile: Option<&Profile>,
    truth: &dyn Fn(f64) -> Pose,
    skids: &[f64],
    tcp: &[Point3<f64>],
) -> Result<f64, TrackError> {
    let mut worst: f64 = 0.0;
    for &s in skids {
        let d = match profile {
            Some(p) => p.deviation(s)?,
            None => Pose::identity(),
        };
        let b = nalgebra::Translation3::from(fit.track_axis * s) * fit.base0 * d;
        let t = truth(s);
        for p in tcp {
            worst = worst.max(((b * p) - (t * p)).norm());
        }
    }
    Ok(worst)
}
