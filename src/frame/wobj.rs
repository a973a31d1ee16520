//! `frame wobj`: a work object from fixture marks the robot touched at several skid positions,
//! `W·cad ≈ B(s)·D(s)·robot`, with `B(s)` and `D(s)` of the cell's robot.

use std::collections::BTreeSet;
use std::path::Path;

use nalgebra::{Matrix3x6, Matrix6, Point3};

use super::{
    FrameError, PointResidual, PoseUncertainty, Underdetermined, rms, sigma_of, xyz_deg_uncertainty,
};
use crate::geometry::Pose;
use crate::geometry::rigid_fit::{RigidFitError, fit_rigid};
use crate::track::TrackError;
use crate::track::csv_table::NumericCsv;
use crate::track::simulate::MarkRow;
use crate::track::uncertainty::{ProfileUncertainty, Sigma, rigid_fit_cofactor};
use crate::transform::track_correction::TrackSetup;

/// The header of `marks.csv`.
pub const MARKS_HEADER: [&str; 8] = [
    "mark", "skid", "robot_x", "robot_y", "robot_z", "cad_x", "cad_y", "cad_z",
];

/// The fitted work object.
#[derive(Clone, Debug, PartialEq)]
pub struct WobjFit {
    /// `W`: the work object in world.
    pub wobj: Pose,
    /// `B(s)·D(s)·robot - W·cad` per mark, in input order, world axes.
    pub residuals: Vec<PointResidual>,
    /// `sqrt(mean |residual|²)`, mm.
    pub rms: f64,
    /// The noise level the uncertainty is scaled by, and where it came from.
    pub sigma: Sigma,
    /// Of `W`'s `x, y, z, rx, ry, rz`, from the marks' scatter only: an error of the cell's
    /// base frame moves `W` with it and is not included.
    pub u_wobj: PoseUncertainty,
}

/// Reads `marks.csv`; a mark number twice is an error at its line.
pub fn read_marks(path: &Path) -> Result<Vec<MarkRow>, TrackError> {
    marks_from(&NumericCsv::read(path, &MARKS_HEADER)?)
}

/// The marks of a table read with [`MARKS_HEADER`] (whose notes the caller shows).
pub fn marks_from(table: &NumericCsv) -> Result<Vec<MarkRow>, TrackError> {
    let mut seen = BTreeSet::new();
    let mut rows = Vec::new();
    for (line, [mark, skid, rx, ry, rz, cx, cy, cz]) in table.select(&MARKS_HEADER)? {
        if mark < 0.0 || mark.fract() != 0.0 || mark > u32::MAX as f64 {
            return Err(table.error(
                line,
                "mark",
                format!("`{mark}` is not a mark number"),
                "number the fixture marks 1, 2, 3, ...",
            ));
        }
        if !seen.insert(mark as u32) {
            return Err(table.error(
                line,
                "mark",
                format!("mark {mark} appears twice"),
                "touch each mark once (or average the touches into one row)",
            ));
        }
        rows.push(MarkRow {
            mark: mark as u32,
            skid,
            robot: [rx, ry, rz],
            cad: [cx, cy, cz],
        });
    }
    Ok(rows)
}

/// Fits `W` to the marks: each touched point is taken into world through the robot's base at
/// its skid, `B(s)·D(s)` (`setup.deviation` is `D`; an identity there is the uncompensated
/// fit), then `W` is the rigid fit of the CAD points onto them. `profile_u`, the uncertainty of
/// that `D`, adds the profile's correlated errors to `W`'s covariance (on the safe side: the
/// residual-based σ̂ holds part of them already).
pub fn fit_wobj(
    rows: &[MarkRow],
    setup: &TrackSetup,
    profile_u: Option<&ProfileUncertainty>,
    sigma: Option<f64>,
) -> Result<WobjFit, FrameError> {
    let mut world = Vec::with_capacity(rows.len());
    let mut in_base = Vec::with_capacity(rows.len());
    for r in rows {
        let d = setup.deviation.deviation(r.skid)?;
        let q = d * Point3::from(r.robot);
        world.push(setup.base_at(r.skid) * q);
        in_base.push(q.coords);
    }
    let cad: Vec<Point3<f64>> = rows.iter().map(|r| Point3::from(r.cad)).collect();
    let fit = fit_rigid(&cad, &world).map_err(|e| {
        FrameError::from(match e {
            RigidFitError::TooFewPoints { got } => Underdetermined::TooFewMarks { got },
            RigidFitError::Collinear => Underdetermined::CollinearMarks,
            other => Underdetermined::MarkFit(other),
        })
    })?;
    let residuals: Vec<PointResidual> = rows
        .iter()
        .zip(&fit.residuals)
        .map(|(r, res)| PointResidual {
            skid: r.skid,
            point: r.mark,
            residual: *res,
        })
        .collect();
    let sigma = sigma_of(sigma, &residuals, 6)?;
    let cof =
        rigid_fit_cofactor(&cad).ok_or_else(|| FrameError::from(Underdetermined::MarksSpread))?;
    let mut cov: Matrix6<f64> = cof * sigma.value().powi(2);
    if let Some(pu) = profile_u {
        // J_j = R_W·[I, −[c_j]×]; the profile's errors are in the base axes, B0's rotation.
        let rw = fit.pose.rotation.to_rotation_matrix().into_inner();
        let rb = setup.base0.rotation.to_rotation_matrix().into_inner();
        let jac = |j: usize| -> Matrix3x6<f64> {
            let mut a = Matrix3x6::<f64>::zeros();
            a.fixed_view_mut::<3, 3>(0, 0).copy_from(&rw);
            a.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(-rw * cad[j].coords.cross_matrix()));
            a
        };
        let mut middle = Matrix6::<f64>::zeros();
        for j in 0..rows.len() {
            for k in 0..rows.len() {
                let c =
                    pu.point_covariance((rows[j].skid, &in_base[j]), (rows[k].skid, &in_base[k]))?;
                middle += jac(j).transpose() * (rb * c * rb.transpose()) * jac(k);
            }
        }
        cov += cof * middle * cof;
    }
    Ok(WobjFit {
        u_wobj: xyz_deg_uncertainty(&fit.pose, &cov),
        wobj: fit.pose,
        rms: rms(&residuals),
        residuals,
        sigma,
    })
}
