//! `track identify`: the robot base frame at each skid position from laser-tracker points
//! (`measurements.csv`, DESIGN.md §6), with per-point residuals (seed Table 7.2) and outliers.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point3;

use super::csv_table::NumericCsv;
use super::frames_csv::SamplingFrame;
use super::profile::TrackError;
use super::simulate::MeasurementRow;
use crate::geometry::rigid_fit::{RigidFit, RigidFitError, fit_rigid};

/// The header of `measurements.csv`.
pub const MEASUREMENTS_HEADER: [&str; 8] = [
    "skid", "point", "robot_x", "robot_y", "robot_z", "meas_x", "meas_y", "meas_z",
];

/// A point is an outlier when its residual exceeds this many times the median residual.
pub const OUTLIER_FACTOR: f64 = 4.0;

/// Reads `measurements.csv`. A point number repeated at one skid is an error at its line.
pub fn read_measurements(path: &Path) -> Result<Vec<MeasurementRow>, TrackError> {
    measurements_of(&NumericCsv::read(path)?)
}

/// Parses `measurements.csv` bytes; `path` is for messages only.
pub fn parse_measurements(path: &Path, bytes: &[u8]) -> Result<Vec<MeasurementRow>, TrackError> {
    measurements_of(&NumericCsv::parse(path, bytes)?)
}

fn measurements_of(table: &NumericCsv) -> Result<Vec<MeasurementRow>, TrackError> {
    let mut seen: BTreeMap<(u64, u32), u64> = BTreeMap::new();
    let mut rows = Vec::with_capacity(table.rows.len());
    for (line, [skid, point, rx, ry, rz, mx, my, mz]) in table.select(&MEASUREMENTS_HEADER)? {
        if point < 0.0 || point.fract() != 0.0 || point > u32::MAX as f64 {
            return Err(table.error(
                line,
                "point",
                format!("`{point}` is not a point number"),
                "number the points 0, 1, 2, ... (the same number for the same TCP point at every skid)",
            ));
        }
        let point = point as u32;
        if let Some(first) = seen.insert((skid.to_bits(), point), line) {
            return Err(table.error(
                line,
                "point",
                format!("point {point} at skid {skid} was already measured on line {first}"),
                "keep one row per point and skid",
            ));
        }
        rows.push(MeasurementRow {
            skid,
            point,
            robot: [rx, ry, rz],
            meas: [mx, my, mz],
        });
    }
    // identify() says the same without a location; the file can point at the rows.
    let mut per_skid: BTreeMap<u64, (f64, usize, u64)> = BTreeMap::new();
    for ((skid_bits, _), &line) in &seen {
        let e = per_skid
            .entry(*skid_bits)
            .or_insert((f64::from_bits(*skid_bits), 0, 0));
        e.1 += 1;
        e.2 = e.2.max(line);
    }
    if let Some((skid, count, line)) = per_skid.values().find(|(_, count, _)| *count < 3) {
        return Err(table.error(
            *line,
            "skid",
            format!(
                "skid {skid} mm: {count} point(s) measured, a base frame needs at least 3 non-collinear points"
            ),
            "measure at least 3 well-spread TCP points at every skid position (10 is usual)",
        ));
    }
    Ok(rows)
}

/// The fit at one skid position.
#[derive(Clone, Debug, PartialEq)]
pub struct SkidFit {
    pub skid: f64,
    /// Point numbers, in the order of `fit.residuals`.
    pub points: Vec<u32>,
    pub fit: RigidFit,
}

/// A point whose residual is far above the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outlier {
    pub skid: f64,
    pub point: u32,
    /// `|residual|`, mm.
    pub residual: f64,
    /// `residual / median`.
    pub ratio: f64,
}

/// Every skid position's base frame and the quality of the fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Identification {
    /// In increasing skid order.
    pub fits: Vec<SkidFit>,
    /// Median `|residual|` over all points, mm.
    pub median_residual: f64,
    /// Points above [`OUTLIER_FACTOR`] × the median.
    pub outliers: Vec<Outlier>,
}

impl Identification {
    /// The sampling frames for `frames.csv`.
    pub fn frames(&self) -> Vec<SamplingFrame> {
        self.fits
            .iter()
            .map(|f| SamplingFrame {
                skid: f.skid,
                pose: f.fit.pose,
            })
            .collect()
    }
}

/// Fits one base frame per skid position: the pose mapping robot-base points onto tracker
/// points.
pub fn identify(rows: &[MeasurementRow]) -> Result<Identification, TrackError> {
    let mut groups: BTreeMap<u64, (f64, Vec<&MeasurementRow>)> = BTreeMap::new();
    for r in rows {
        // Order-preserving key for finite f64: flip bits so negative skids sort first.
        let bits = r.skid.to_bits();
        let key = if r.skid.is_sign_negative() {
            !bits
        } else {
            bits | (1 << 63)
        };
        groups.entry(key).or_insert((r.skid, Vec::new())).1.push(r);
    }
    let mut fits = Vec::with_capacity(groups.len());
    for (skid, group) in groups.into_values() {
        let src: Vec<Point3<f64>> = group.iter().map(|r| Point3::from(r.robot)).collect();
        let dst: Vec<Point3<f64>> = group.iter().map(|r| Point3::from(r.meas)).collect();
        let fit = fit_rigid(&src, &dst).map_err(|e| match e {
            RigidFitError::TooFewPoints { got } => TrackError::TooFewPoints { skid, count: got },
            other => TrackError::Degenerate {
                skid,
                reason: other.to_string(),
            },
        })?;
        fits.push(SkidFit {
            skid,
            points: group.iter().map(|r| r.point).collect(),
            fit,
        });
    }
    if fits.is_empty() {
        return Err(TrackError::Invalid(
            "no measurements: the file has a header but no rows".to_string(),
        ));
    }
    let mut norms: Vec<f64> = fits.iter().flat_map(|f| f.fit.residual_norms()).collect();
    norms.sort_by(f64::total_cmp);
    let median_residual = median(&norms);
    let mut outliers = Vec::new();
    if median_residual > 0.0 {
        for f in &fits {
            for (point, r) in f.points.iter().zip(f.fit.residual_norms()) {
                if r > OUTLIER_FACTOR * median_residual {
                    outliers.push(Outlier {
                        skid: f.skid,
                        point: *point,
                        residual: r,
                        ratio: r / median_residual,
                    });
                }
            }
        }
    }
    Ok(Identification {
        fits,
        median_residual,
        outliers,
    })
}

fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n == 0 {
        return 0.0;
    }
    let hi = sorted.get(n / 2).copied().unwrap_or(0.0);
    if n % 2 == 1 {
        hi
    } else {
        (sorted.get(n / 2 - 1).copied().unwrap_or(hi) + hi) / 2.0
    }
}
