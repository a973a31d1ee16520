//! `frame fit`: the plain point-pair best fit, e.g. of the tracker to the cell's reference marks
//! (`nominal ≈ T·measured`, `T` the measurement frame in the cell), with residuals and the
//! rejection of points far off the rest.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use nalgebra::{Matrix6, Point3};

use super::{
    FrameError, PointResidual, PoseUncertainty, Underdetermined, rms, sigma_of, xyz_deg_uncertainty,
};
use crate::geometry::Pose;
use crate::geometry::rigid_fit::{RigidFitError, fit_rigid};
use crate::track::TrackError;
use crate::track::csv_table::NumericCsv;
use crate::track::uncertainty::{Sigma, rigid_fit_cofactor};

/// The header of a point file.
pub const POINTS_HEADER: [&str; 4] = ["point", "x", "y", "z"];

/// A point is rejected when its residual exceeds this many times the median residual (the
/// factor `track identify` flags outliers with).
pub const REJECT_FACTOR: f64 = crate::track::identify::OUTLIER_FACTOR;

/// Reads `point,x,y,z`; a point number twice is an error at its line.
pub fn read_point_file(path: &Path) -> Result<BTreeMap<u32, Point3<f64>>, TrackError> {
    point_file_from(&NumericCsv::read(path, &POINTS_HEADER)?)
}

/// The points of a table read with [`POINTS_HEADER`] (whose notes the caller shows).
pub fn point_file_from(table: &NumericCsv) -> Result<BTreeMap<u32, Point3<f64>>, TrackError> {
    let mut out = BTreeMap::new();
    for (line, [point, x, y, z]) in table.select(&POINTS_HEADER)? {
        if point < 0.0 || point.fract() != 0.0 || point > u32::MAX as f64 {
            return Err(table.error(
                line,
                "point",
                format!("`{point}` is not a point number"),
                "number the points 1, 2, 3, ... (the same number in both files)",
            ));
        }
        if out.insert(point as u32, Point3::new(x, y, z)).is_some() {
            return Err(table.error(
                line,
                "point",
                format!("point {point} appears twice"),
                "keep one row per point",
            ));
        }
    }
    Ok(out)
}

/// The fitted transform.
#[derive(Clone, Debug, PartialEq)]
pub struct PairFit {
    /// `T` with `nominal ≈ T·measured`.
    pub pose: Pose,
    /// `nominal - T·measured` of the points used.
    pub residuals: Vec<PointResidual>,
    /// Rejected points with their residual against the final `T`.
    pub rejected: Vec<PointResidual>,
    /// Point numbers in only one of the files: (nominal only, measured only).
    pub unpaired: (Vec<u32>, Vec<u32>),
    /// `sqrt(mean |residual|²)` over the points used, mm.
    pub rms: f64,
    /// The noise level the uncertainty is scaled by, and where it came from.
    pub sigma: Sigma,
    /// Of `T`'s `x, y, z, rx, ry, rz`.
    pub u_pose: PoseUncertainty,
}

/// The point whose residual against the fit of all the others is largest: `(index, that
/// residual, the median of all such residuals)`.
fn worst_left_out(src: &[Point3<f64>], dst: &[Point3<f64>]) -> Option<(usize, f64, f64)> {
    let mut out = Vec::with_capacity(src.len());
    for i in 0..src.len() {
        let keep = |v: &[Point3<f64>]| -> Vec<Point3<f64>> {
            v.iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, p)| *p)
                .collect()
        };
        let fit = fit_rigid(&keep(src), &keep(dst)).ok()?;
        out.push((dst[i] - fit.pose * src[i]).norm());
    }
    let mut sorted = out.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied()?.max(1e-6);
    let (i, r) = out.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    Some((i, *r, median))
}

/// Pairs the points by number and fits `T`; with `reject_factor`, the worst point is dropped
/// while its residual against the fit of the others is above that many times the median of
/// such residuals and more than 4 points remain.
pub fn fit_pairs(
    nominal: &BTreeMap<u32, Point3<f64>>,
    measured: &BTreeMap<u32, Point3<f64>>,
    reject_factor: Option<f64>,
    sigma: Option<f64>,
) -> Result<PairFit, FrameError> {
    let only_nominal: Vec<u32> = nominal
        .keys()
        .filter(|k| !measured.contains_key(k))
        .copied()
        .collect();
    let only_measured: Vec<u32> = measured
        .keys()
        .filter(|k| !nominal.contains_key(k))
        .copied()
        .collect();
    let mut used: BTreeSet<u32> = nominal
        .keys()
        .filter(|k| measured.contains_key(k))
        .copied()
        .collect();
    let mut rejected_ids = Vec::new();
    loop {
        let ids: Vec<u32> = used.iter().copied().collect();
        let src: Vec<Point3<f64>> = ids.iter().map(|k| measured[k]).collect();
        let dst: Vec<Point3<f64>> = ids.iter().map(|k| nominal[k]).collect();
        let fit = fit_rigid(&src, &dst).map_err(|e| {
            FrameError::from(match e {
                RigidFitError::TooFewPoints { got } => Underdetermined::TooFewPairs { got },
                error => Underdetermined::PairFit {
                    paired: ids.len(),
                    error,
                },
            })
        })?;
        // A least-squares fit spreads one bad point over the others; its residual against
        // the fit of the rest shows it plainly.
        if let Some(factor) = reject_factor
            && ids.len() > 4
            && let Some((i, r, median)) = worst_left_out(&src, &dst)
            && r > factor * median
        {
            rejected_ids.push(ids[i]);
            used.remove(&ids[i]);
            continue;
        }
        let residuals: Vec<PointResidual> = ids
            .iter()
            .zip(&fit.residuals)
            .map(|(k, r)| PointResidual {
                skid: 0.0,
                point: *k,
                residual: *r,
            })
            .collect();
        let rejected = rejected_ids
            .iter()
            .map(|k| PointResidual {
                skid: 0.0,
                point: *k,
                residual: nominal[k] - fit.pose * measured[k],
            })
            .collect();
        let sigma = sigma_of(sigma, &residuals, 6)?;
        let cof = rigid_fit_cofactor(&src)
            .ok_or_else(|| FrameError::from(Underdetermined::PointsSpread))?;
        let cov: Matrix6<f64> = cof * sigma.value().powi(2);
        return Ok(PairFit {
            u_pose: xyz_deg_uncertainty(&fit.pose, &cov),
            pose: fit.pose,
            rms: rms(&residuals),
            residuals,
            rejected,
            unpaired: (only_nominal, only_measured),
            sigma,
        });
    }
}
