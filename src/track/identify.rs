//! `track identify`: the robot base frame at each skid position from laser-tracker points
//! (`measurements.csv`, docs/design.md §6), with per-point residuals (thesis Table 7.2) and outliers.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point3;

use super::csv_table::NumericCsv;
use super::error::{NominalProblem, SkidProblem, TrackError};
use super::frames_csv::SamplingFrame;
use super::simulate::MeasurementRow;
use crate::geometry::Pose;
use crate::geometry::rigid_fit::{RigidFit, RigidFitError, fit_rigid_weighted};

/// The header of `measurements.csv`.
pub const MEASUREMENTS_HEADER: [&str; 8] = [
    "skid", "point", "robot_x", "robot_y", "robot_z", "meas_x", "meas_y", "meas_z",
];

/// A point is an outlier when its residual exceeds this many times the median residual.
pub const OUTLIER_FACTOR: f64 = 4.0;

/// Reads `measurements.csv`. A point number repeated at one skid is an error at its line.
pub fn read_measurements(path: &Path) -> Result<Vec<MeasurementRow>, TrackError> {
    measurements_of(&NumericCsv::read(path, &MEASUREMENTS_HEADER)?)
}

/// The measurements of a table read with [`MEASUREMENTS_HEADER`] (whose notes the caller
/// shows).
pub fn measurements_from(table: &NumericCsv) -> Result<Vec<MeasurementRow>, TrackError> {
    measurements_of(table)
}

/// Parses `measurements.csv` bytes; `path` is for messages only.
pub fn parse_measurements(path: &Path, bytes: &[u8]) -> Result<Vec<MeasurementRow>, TrackError> {
    measurements_of(&NumericCsv::parse(path, bytes, &MEASUREMENTS_HEADER)?)
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

/// A fit whose rotation condition number exceeds this is refused: the points are too close to a
/// line, and the rotation about it is this many times less determined than the best-determined
/// one (noise of 0.02 mm then turns into tenths of a millimetre at a TCP 2 m away).
pub const CONDITION_LIMIT: f64 = 20.0;

/// The tracker points may be spread at most this fraction wider or narrower than the robot
/// points; beyond it the point sets are in different units (m vs mm, inches) or do not belong
/// together.
pub const SCALE_TOLERANCE: f64 = 0.01;

/// Tukey's bisquare weight is zero beyond this many times the median residual.
const BISQUARE_LIMIT: f64 = 2.0 * OUTLIER_FACTOR;

/// A point left out of the identification: `SKID:POINT` (skid in mm as written in the file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exclusion {
    /// The skid position, mm.
    pub skid: f64,
    /// The point number.
    pub point: u32,
}

impl std::str::FromStr for Exclusion {
    type Err = String;

    fn from_str(s: &str) -> Result<Exclusion, String> {
        let (skid, point) = s
            .split_once(':')
            .ok_or_else(|| format!("`{s}`: write SKID:POINT, e.g. 1500:3"))?;
        let skid: f64 = skid
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("`{s}`: the skid `{skid}` is not a number"))?;
        let point: u32 = point
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: the point `{point}` is not a point number"))?;
        Ok(Exclusion { skid, point })
    }
}

impl Exclusion {
    fn matches(&self, skid: f64, point: u32) -> bool {
        self.point == point && (self.skid - skid).abs() <= 1e-9 * (1.0 + skid.abs())
    }
}

/// How much a fitted base frame moves when points are left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameShift {
    /// Of the frame origin, mm.
    pub origin_mm: f64,
    /// Rotation angle, degrees.
    pub rotation_deg: f64,
    /// The largest move of a measured TCP point, mm.
    pub at_points_mm: f64,
}

impl FrameShift {
    /// From the frame `before` to `after`, judged at `points` (robot base coordinates).
    pub fn between(before: &Pose, after: &Pose, points: &[Point3<f64>]) -> FrameShift {
        FrameShift {
            origin_mm: (after.translation.vector - before.translation.vector).norm(),
            rotation_deg: before.rotation.angle_to(&after.rotation).to_degrees(),
            at_points_mm: points
                .iter()
                .map(|p| (after * p - before * p).norm())
                .fold(0.0, f64::max),
        }
    }
}

/// The fit at one skid position.
#[derive(Clone, Debug, PartialEq)]
pub struct SkidFit {
    /// The skid position, mm.
    pub skid: f64,
    /// Point numbers, in the order of `fit.residuals` (the excluded points are not among them).
    pub points: Vec<u32>,
    /// The least-squares fit of the points (the frame written to `frames.csv`).
    pub fit: RigidFit,
    /// `|residual|` per point against the robust fit, which a bad point does not pull.
    pub robust_residuals: Vec<f64>,
    /// The excluded points of this skid, and how far the frame moved by leaving them out.
    pub excluded: Vec<u32>,
    /// How far the frame moved by leaving them out; `None` without exclusions.
    pub exclusion_shift: Option<FrameShift>,
}

/// A point whose residual is far above the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outlier {
    /// The skid position, mm.
    pub skid: f64,
    /// The point number.
    pub point: u32,
    /// `|residual|` against the robust fit, mm.
    pub residual: f64,
    /// `residual / median`.
    pub ratio: f64,
    /// How far the skid's frame would move if the point were excluded.
    pub shift_if_excluded: Option<FrameShift>,
}

/// Every skid position's base frame and the quality of the fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Identification {
    /// In increasing skid order.
    pub fits: Vec<SkidFit>,
    /// Median `|residual|` over all points against the robust fits, mm.
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

/// The points of one skid position.
struct Group {
    skid: f64,
    points: Vec<u32>,
    robot: Vec<Point3<f64>>,
    meas: Vec<Point3<f64>>,
}

impl Group {
    fn fit(&self, weights: &[f64]) -> Result<RigidFit, TrackError> {
        let skid = self.skid;
        let fit = fit_rigid_weighted(&self.robot, &self.meas, weights).map_err(|e| {
            let problem = match e {
                RigidFitError::TooFewPoints { got } => SkidProblem::TooFewPoints { count: got },
                other => SkidProblem::Degenerate(other),
            };
            TrackError::Skid { skid, problem }
        })?;
        if fit.condition > CONDITION_LIMIT {
            return Err(TrackError::Skid {
                skid,
                problem: SkidProblem::IllConditioned {
                    condition: fit.condition,
                    limit: CONDITION_LIMIT,
                },
            });
        }
        if !((1.0 - SCALE_TOLERANCE)..=(1.0 + SCALE_TOLERANCE)).contains(&fit.scale_ratio) {
            return Err(TrackError::Skid {
                skid,
                problem: SkidProblem::Scale {
                    ratio: fit.scale_ratio,
                    tolerance: SCALE_TOLERANCE,
                },
            });
        }
        Ok(fit)
    }

    /// The residuals of the fit, among the full one (`full`) and those leaving out one point,
    /// with the smallest median residual: with one bad reading, the fit without it.
    fn robust_start(&self, full: Vec<f64>) -> Vec<f64> {
        let median_of = |r: &[f64]| {
            let mut v = r.to_vec();
            v.sort_by(f64::total_cmp);
            median(&v)
        };
        let mut best = (median_of(&full), full);
        for i in 0..self.points.len() {
            if let Some(fit) = self.fit_without(i) {
                let r = fit.residual_norms();
                let m = median_of(&r);
                if m < best.0 {
                    best = (m, r);
                }
            }
        }
        best.1
    }

    /// The least-squares fit without point `index`, if the rest still fixes a frame.
    fn fit_without(&self, index: usize) -> Option<RigidFit> {
        let mut w = vec![1.0; self.points.len()];
        *w.get_mut(index)? = 0.0;
        self.fit(&w).ok()
    }
}

/// Tukey's bisquare: 1 at 0, 0 from `limit` on.
fn bisquare(r: f64, limit: f64) -> f64 {
    if limit <= 0.0 || r >= limit {
        return 0.0;
    }
    let u = r / limit;
    (1.0 - u * u).powi(2)
}

/// Fits one base frame per skid position: the pose mapping robot-base points onto tracker
/// points.
pub fn identify(rows: &[MeasurementRow]) -> Result<Identification, TrackError> {
    identify_excluding(rows, &[])
}

/// [`identify`] with the points `exclude` left out. An exclusion that matches no row is an
/// error, so a typo cannot pass as a cleaned identification.
///
/// The frames are least-squares fits of the remaining points. Outliers are judged against
/// robust fits (iteratively reweighted least squares with Tukey's bisquare weight on the median
/// residual of all skids), which a single bad reading does not pull towards itself: the bad
/// point is the one flagged, not its neighbours.
pub fn identify_excluding(
    rows: &[MeasurementRow],
    exclude: &[Exclusion],
) -> Result<Identification, TrackError> {
    if let Some(e) = exclude
        .iter()
        .find(|e| !rows.iter().any(|r| e.matches(r.skid, r.point)))
    {
        return Err(TrackError::UnknownExclusion {
            skid: e.skid,
            point: e.point,
        });
    }
    let mut keyed: BTreeMap<u64, (Group, Group)> = BTreeMap::new();
    for r in rows {
        // Order-preserving key for finite f64: flip bits so negative skids sort first.
        let bits = r.skid.to_bits();
        let key = if r.skid.is_sign_negative() {
            !bits
        } else {
            bits | (1 << 63)
        };
        let new = || Group {
            skid: r.skid,
            points: Vec::new(),
            robot: Vec::new(),
            meas: Vec::new(),
        };
        let (kept, all) = keyed.entry(key).or_insert_with(|| (new(), new()));
        for g in [&mut *all]
            .into_iter()
            .chain((!exclude.iter().any(|e| e.matches(r.skid, r.point))).then_some(kept))
        {
            g.points.push(r.point);
            g.robot.push(Point3::from(r.robot));
            g.meas.push(Point3::from(r.meas));
        }
    }
    if keyed.is_empty() {
        return Err(TrackError::Nominal(NominalProblem::TooFewFrames {
            count: 0,
        }));
    }
    let groups: Vec<(Group, Group)> = keyed.into_values().collect();
    let mut fits = Vec::with_capacity(groups.len());
    for (kept, all) in &groups {
        let fit = kept.fit(&vec![1.0; kept.points.len()])?;
        let excluded: Vec<u32> = all
            .points
            .iter()
            .copied()
            .filter(|p| !kept.points.contains(p))
            .collect();
        let exclusion_shift = if excluded.is_empty() {
            None
        } else {
            all.fit(&vec![1.0; all.points.len()])
                .ok()
                .map(|before| FrameShift::between(&before.pose, &fit.pose, &all.robot))
        };
        fits.push(SkidFit {
            skid: kept.skid,
            points: kept.points.clone(),
            robust_residuals: fit.residual_norms(),
            fit,
            excluded,
            exclusion_shift,
        });
    }
    // Iteratively reweighted least squares, all skids sharing one residual scale. A plain
    // least-squares start lets a bad point push its neighbours' residuals above the cut-off
    // (masking), so each skid starts from the best of the full fit and its leave-one-out fits.
    let mut scale = median_residual_of(&fits);
    if scale > 1e-9 {
        for (f, (kept, _)) in fits.iter_mut().zip(&groups) {
            f.robust_residuals = kept.robust_start(f.fit.residual_norms());
        }
        scale = median_residual_of(&fits);
    }
    // Residuals at the level of rounding are exact data: nothing to reweight.
    for _ in 0..10 {
        if scale <= 1e-9 {
            break;
        }
        for (f, (kept, _)) in fits.iter_mut().zip(&groups) {
            let w: Vec<f64> = f
                .robust_residuals
                .iter()
                .map(|r| bisquare(*r, BISQUARE_LIMIT * scale))
                .collect();
            // Too few points keep weight to fix a frame: the plain fit stands.
            if let Ok(robust) = kept.fit(&w) {
                f.robust_residuals = robust.residual_norms();
            }
        }
        let next = median_residual_of(&fits);
        let settled = (next - scale).abs() <= 1e-4 * scale;
        scale = next;
        if settled {
            break;
        }
    }
    let median_residual = scale;
    let mut outliers = Vec::new();
    if median_residual > 0.0 {
        for (f, (kept, _)) in fits.iter().zip(&groups) {
            for (i, (point, r)) in f.points.iter().zip(&f.robust_residuals).enumerate() {
                if *r > OUTLIER_FACTOR * median_residual {
                    outliers.push(Outlier {
                        skid: f.skid,
                        point: *point,
                        residual: *r,
                        ratio: r / median_residual,
                        shift_if_excluded: kept.fit_without(i).map(|without| {
                            FrameShift::between(&f.fit.pose, &without.pose, &kept.robot)
                        }),
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

fn median_residual_of(fits: &[SkidFit]) -> f64 {
    let mut norms: Vec<f64> = fits
        .iter()
        .flat_map(|f| f.robust_residuals.iter().copied())
        .collect();
    norms.sort_by(f64::total_cmp);
    median(&norms)
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
