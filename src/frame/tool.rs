//! `frame tool`: the TCP from flange poses pivoting about one fixed point (thesis §4.4, eqs.
//! 4.1-4.3). Every pose `(R_k, p_k)` puts the TCP `t` (flange frame) on the point `P` (base
//! frame): `R_k·t + p_k = P`, linear in `(t, P)`; least squares over all poses, residual
//! `R_k·t + p_k - P` per pose (what a controller's TCP routine reports as max/mean error).

use std::path::Path;

use nalgebra::{DMatrix, DVector, Point3, Translation3, Vector3};

use super::{FrameError, PointResidual, Underdetermined, rms, sigma_of};
use crate::geometry::{Pose, abb_quat, kuka_abc, xyz_deg};
use crate::track::TrackError;
use crate::track::csv_table::NumericCsv;
use crate::track::uncertainty::{Sigma, invert_spd};

/// How a flange file writes the orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlangeOrientation {
    /// ABB `q1, q2, q3, q4`, scalar first.
    Quaternion,
    /// `rx, ry, rz` degrees, `R = Rz·Ry·Rx`.
    XyzDeg,
    /// KUKA `a, b, c` degrees, `R = Rz(A)·Ry(B)·Rx(C)`.
    KukaAbc,
}

impl FlangeOrientation {
    /// The columns that name it.
    pub fn columns(self) -> &'static [&'static str] {
        match self {
            FlangeOrientation::Quaternion => &["q1", "q2", "q3", "q4"],
            FlangeOrientation::XyzDeg => &["rx", "ry", "rz"],
            FlangeOrientation::KukaAbc => &["a", "b", "c"],
        }
    }
}

/// Every column a flange file may have: `x,y,z` and one orientation's.
pub const FLANGE_COLUMNS: [&str; 13] = [
    "x", "y", "z", "q1", "q2", "q3", "q4", "rx", "ry", "rz", "a", "b", "c",
];

/// Reads `FLANGE.csv`: `x,y,z` and one of `q1,q2,q3,q4` / `rx,ry,rz` / `a,b,c`.
pub fn read_flange(path: &Path) -> Result<(Vec<Pose>, FlangeOrientation), TrackError> {
    flange_from(&NumericCsv::read(path, &FLANGE_COLUMNS)?)
}

/// The flange poses of a table read with [`FLANGE_COLUMNS`] (whose notes the caller shows).
pub fn flange_from(table: &NumericCsv) -> Result<(Vec<Pose>, FlangeOrientation), TrackError> {
    let has = |c: &str| table.headers.iter().any(|h| h == c);
    let kind = if has("q1") {
        FlangeOrientation::Quaternion
    } else if has("rx") {
        FlangeOrientation::XyzDeg
    } else if has("a") {
        FlangeOrientation::KukaAbc
    } else {
        return Err(table.error(
            table.header_line,
            "",
            format!("no orientation columns in `{}`", table.headers.join(",")),
            "write x,y,z with q1,q2,q3,q4 (ABB), rx,ry,rz or a,b,c (KUKA)",
        ));
    };
    let mut names = vec!["x", "y", "z"];
    names.extend_from_slice(kind.columns());
    let idx = table.columns(&names)?;
    let mut poses = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let v: Vec<f64> = idx.iter().map(|&i| NumericCsv::get(row, i)).collect();
        let rot = match kind {
            FlangeOrientation::Quaternion => {
                abb_quat([v[3], v[4], v[5], v[6]]).ok_or_else(|| {
                    table.error(
                    row.line,
                    "q1",
                    "the quaternion is zero".to_string(),
                    "write the flange orientation as a unit quaternion q1,q2,q3,q4 (scalar first)",
                )
                })?
            }
            FlangeOrientation::XyzDeg => xyz_deg(v[3], v[4], v[5]),
            FlangeOrientation::KukaAbc => kuka_abc(v[3], v[4], v[5]),
        };
        poses.push(Pose::from_parts(Translation3::new(v[0], v[1], v[2]), rot));
    }
    Ok((poses, kind))
}

/// The fitted TCP.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolFit {
    /// `t`: the TCP in the flange frame, mm.
    pub tcp: Vector3<f64>,
    /// `P`: the fixed point in the robot base frame, mm.
    pub point: Point3<f64>,
    /// `R_k·t + p_k - P` per pose (`point` = pose number, 1-based).
    pub residuals: Vec<PointResidual>,
    /// `sqrt(mean |residual|²)`, mm.
    pub rms: f64,
    /// Mean `|residual|`, mm (the controller's "mean error").
    pub mean: f64,
    /// Largest `|residual|`, mm (the controller's "max error").
    pub max: f64,
    /// The noise level the uncertainties below are scaled by, and where it came from.
    pub sigma: Sigma,
    /// Standard uncertainties of `t`'s components, mm.
    pub u_tcp: [f64; 3],
    /// Standard uncertainties of `P`'s components, mm.
    pub u_point: [f64; 3],
}

/// The most the TCP's standard uncertainty may be, per unit of the flange positions' noise, for
/// [`fit_tool`] to give it: beyond, the orientations are refused as too alike (0.02 mm of noise
/// would leave the TCP 10 mm uncertain).
pub const MAX_NOISE_GAIN: f64 = 500.0;

/// Least squares for `(t, P)` from flange poses; `sigma` is the noise of a flange position per
/// axis, else estimated with `3n - 6` degrees of freedom.
pub fn fit_tool(poses: &[Pose], sigma: Option<f64>) -> Result<ToolFit, FrameError> {
    if poses.len() < 3 {
        return Err(Underdetermined::TooFewPoses { got: poses.len() }.into());
    }
    let n = poses.len();
    let mut a = DMatrix::<f64>::zeros(3 * n, 6);
    let mut b = DVector::<f64>::zeros(3 * n);
    for (k, f) in poses.iter().enumerate() {
        let r = f.rotation.to_rotation_matrix().into_inner();
        for i in 0..3 {
            for j in 0..3 {
                a[(3 * k + i, j)] = r[(i, j)];
            }
            a[(3 * k + i, 3 + i)] = -1.0;
            b[3 * k + i] = -f.translation.vector[i];
        }
    }
    let ata = a.transpose() * &a;
    let inv =
        invert_spd(&ata).ok_or_else(|| FrameError::from(Underdetermined::OrientationsAlike))?;
    // Orientations that differ, but too little: the TCP's standard uncertainty per unit of
    // noise. Nine poses tilted by ±30° give about 1; a few tenths of a degree give tens of
    // thousands, and a TCP hundreds of mm off with a u to match.
    let gain = (0..3).map(|i| inv[(i, i)]).fold(0.0, f64::max).sqrt();
    if gain > MAX_NOISE_GAIN {
        return Err(Underdetermined::OrientationsAlike.into());
    }
    let x = &inv * (a.transpose() * &b);
    let tcp = Vector3::new(x[0], x[1], x[2]);
    let point = Point3::new(x[3], x[4], x[5]);
    let residuals: Vec<PointResidual> = poses
        .iter()
        .enumerate()
        .map(|(k, f)| PointResidual {
            skid: 0.0,
            point: k as u32 + 1,
            residual: f.rotation * tcp + f.translation.vector - point.coords,
        })
        .collect();
    let sigma = sigma_of(sigma, &residuals, 6)?;
    let cov = &inv * sigma.value().powi(2);
    let u = |i: usize| cov[(i, i)].max(0.0).sqrt();
    let norms: Vec<f64> = residuals.iter().map(PointResidual::norm).collect();
    Ok(ToolFit {
        tcp,
        point,
        rms: rms(&residuals),
        mean: norms.iter().sum::<f64>() / n as f64,
        max: norms.iter().copied().fold(0.0, f64::max),
        residuals,
        sigma,
        u_tcp: [u(0), u(1), u(2)],
        u_point: [u(3), u(4), u(5)],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::pose_xyz_deg;

    #[test]
    fn orientations_about_one_axis_do_not_fix_the_tcp() {
        // Turning only about base z leaves the TCP's z and the point's z trading off.
        let poses: Vec<Pose> = (0..6)
            .map(|k| pose_xyz_deg(100.0 * k as f64, 0.0, 500.0, 0.0, 0.0, 60.0 * k as f64))
            .collect();
        let e = fit_tool(&poses, None).unwrap_err();
        assert!(
            matches!(
                e,
                FrameError::Underdetermined(Underdetermined::OrientationsAlike)
            ),
            "{e:?}"
        );
        assert!(e.to_string().contains("two different axes"), "{e}");
    }

    /// Turned about one axis with the tool tilted by nearly the same angle each time (a cone of
    /// 3°, wobbling by a hundredth of a degree), the orientations fix the TCP along the turning
    /// axis in theory only: refused as too alike, where such poses gave z 178 mm below the
    /// flange for a TCP 215 mm above it, with u 485 mm. Tilted by angles that differ by 20°
    /// they fix it.
    #[test]
    fn orientations_on_a_narrow_cone_do_not_fix_the_tcp() {
        let tcp = Vector3::new(12.5, -3.2, 215.0);
        let point = Vector3::new(1400.0, 200.0, 600.0);
        let poses = |wobble: f64| -> Vec<Pose> {
            (0..8)
                .map(|k| {
                    let (rx, ry) = (
                        3.0 + wobble * (k % 2) as f64,
                        wobble * ((k % 3) as f64 - 1.0),
                    );
                    let r = pose_xyz_deg(0.0, 0.0, 0.0, rx, ry, 45.0 * k as f64).rotation;
                    // Noise of a few hundredths of a mm, as a tracker gives.
                    let noise = Vector3::new(0.02, -0.015, 0.01) * (k as f64 - 3.5) / 3.5;
                    Pose::from_parts((point - r * tcp + noise).into(), r)
                })
                .collect()
        };
        let e = fit_tool(&poses(0.01), None).unwrap_err();
        assert!(
            matches!(
                e,
                FrameError::Underdetermined(Underdetermined::OrientationsAlike)
            ),
            "{e:?}"
        );
        let fit = fit_tool(&poses(20.0), None).unwrap();
        assert!((fit.tcp - tcp).norm() < 0.1, "{:?}", fit.tcp);
    }

    #[test]
    fn what_is_missing_is_data_and_renders_with_its_count() {
        let poses = [pose_xyz_deg(0.0, 0.0, 500.0, 0.0, 0.0, 0.0); 2];
        let e = fit_tool(&poses, None).unwrap_err();
        assert!(
            matches!(
                e,
                FrameError::Underdetermined(Underdetermined::TooFewPoses { got: 2 })
            ),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            "2 pose(s): a TCP needs at least 3 (4 or more to see the error)"
        );
    }
}
