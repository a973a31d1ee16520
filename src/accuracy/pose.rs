//! ISO 9283 pose accuracy and repeatability (thesis §3.2.1, eqs 3.1-3.11; Tables 3.2-3.3): the
//! visits of each commanded pose against the pose, per point and the worst over all points.

use std::path::Path;

use nalgebra::Vector3;
use serde::Serialize;

use super::error::AccuracyError;
use super::stats::{Running, RunningPoint, angle_deviation, repeatability, spread};
use super::table::{ColumnMap, Table};

/// A programmed pose, in the measurement frame.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandedPose {
    /// The point's name, which the visits refer to.
    pub name: String,
    /// 1-based line of the commanded file.
    pub line: u64,
    /// Commanded position, mm.
    pub position: Vector3<f64>,
    /// `[rx, ry, rz]` in degrees, when the file has them.
    pub angles: Option<[f64; 3]>,
}

/// One measured visit of a commanded pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Visit {
    /// The commanded point visited.
    pub point: String,
    /// The cycle, when the file has a `cycle` column.
    pub cycle: Option<String>,
    /// 1-based line of the measured file.
    pub line: u64,
    /// Measured position, mm.
    pub position: Vector3<f64>,
    /// Measured `[rx, ry, rz]` in degrees, when the file has them.
    pub angles: Option<[f64; 3]>,
}

/// The figures of one commanded pose. JSON keys are the standard's symbols.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PointAccuracy {
    /// The commanded point's name.
    pub point: String,
    /// Visits.
    pub n: usize,
    /// `AP = |p̄ − p_c|` (eq. 3.1).
    #[serde(rename = "AP")]
    pub ap: f64,
    /// `p̄ − p_c` per axis (eqs 3.2-3.3).
    #[serde(rename = "APx")]
    pub ap_x: f64,
    /// `p̄ − p_c` along y, mm (eq. 3.3).
    #[serde(rename = "APy")]
    pub ap_y: f64,
    /// `p̄ − p_c` along z, mm (eq. 3.3).
    #[serde(rename = "APz")]
    pub ap_z: f64,
    /// Mean of the wrapped angle deviations (eqs 3.4-3.5); `None` without angles on both sides.
    #[serde(rename = "APa")]
    pub ap_a: Option<f64>,
    /// Like `APa`, about `ry`, degrees.
    #[serde(rename = "APb")]
    pub ap_b: Option<f64>,
    /// Like `APa`, about `rz`, degrees.
    #[serde(rename = "APc")]
    pub ap_c: Option<f64>,
    /// `RP = l̄ + 3·S_l` (eqs 3.6-3.8).
    #[serde(rename = "RP")]
    pub rp: f64,
    /// `3·S_a` etc. (eqs 3.9-3.11); `None` without measured angles.
    #[serde(rename = "RPa")]
    pub rp_a: Option<f64>,
    /// Like `RPa`, about `ry`, degrees.
    #[serde(rename = "RPb")]
    pub rp_b: Option<f64>,
    /// Like `RPa`, about `rz`, degrees.
    #[serde(rename = "RPc")]
    pub rp_c: Option<f64>,
    /// The largest single distance of a visit from the commanded position (Table 3.3 "MAX").
    #[serde(rename = "MAX")]
    pub max: f64,
    /// `l̄` and `S_l` behind RP.
    pub l_mean: f64,
    /// `S_l`, over `n − 1` (eq. 3.8).
    #[serde(rename = "S_l")]
    pub s_l: f64,
    /// The smallest and largest `l_j` (Table 3.3's repeating deviation min/max).
    pub l_min: f64,
    /// The largest `l_j`.
    pub l_max: f64,
    /// The barycentre `p̄` of the visits and the commanded position.
    pub mean: [f64; 3],
    /// The commanded position, mm.
    pub commanded: [f64; 3],
    /// Each visit minus the commanded position, in visit order (for the plots).
    #[serde(skip)]
    pub deviations: Vec<Vector3<f64>>,
}

impl PointAccuracy {
    /// AP, APx, APy, APz, APa, APb, APc, RP, RPa, RPb, RPc, MAX: the figures in the order every
    /// table, CSV and report writes them (`None` where orientations were not measured).
    pub fn figures(&self) -> [Option<f64>; 12] {
        [
            Some(self.ap),
            Some(self.ap_x),
            Some(self.ap_y),
            Some(self.ap_z),
            self.ap_a,
            self.ap_b,
            self.ap_c,
            Some(self.rp),
            self.rp_a,
            self.rp_b,
            self.rp_c,
            Some(self.max),
        ]
    }
}

/// The worst of each figure over all points (largest magnitude; signed figures keep their sign).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseSummary {
    /// Commanded points measured.
    pub points: usize,
    /// Visits over all points.
    pub visits: usize,
    /// The largest `AP`, mm.
    #[serde(rename = "AP")]
    pub ap: f64,
    /// The `APx` of largest magnitude, signed, mm.
    #[serde(rename = "APx")]
    pub ap_x: f64,
    /// The `APy` of largest magnitude, signed, mm.
    #[serde(rename = "APy")]
    pub ap_y: f64,
    /// The `APz` of largest magnitude, signed, mm.
    #[serde(rename = "APz")]
    pub ap_z: f64,
    /// The `APa` of largest magnitude, signed, degrees.
    #[serde(rename = "APa")]
    pub ap_a: Option<f64>,
    /// The `APb` of largest magnitude, signed, degrees.
    #[serde(rename = "APb")]
    pub ap_b: Option<f64>,
    /// The `APc` of largest magnitude, signed, degrees.
    #[serde(rename = "APc")]
    pub ap_c: Option<f64>,
    /// The largest `RP`, mm.
    #[serde(rename = "RP")]
    pub rp: f64,
    /// The largest `RPa`, degrees.
    #[serde(rename = "RPa")]
    pub rp_a: Option<f64>,
    /// The largest `RPb`, degrees.
    #[serde(rename = "RPb")]
    pub rp_b: Option<f64>,
    /// The largest `RPc`, degrees.
    #[serde(rename = "RPc")]
    pub rp_c: Option<f64>,
    /// The largest `MAX`, mm.
    #[serde(rename = "MAX")]
    pub max: f64,
    /// Where the worst AP, RP and MAX are.
    pub worst_ap_point: String,
    /// The point with the largest RP.
    pub worst_rp_point: String,
    /// The point with the largest MAX.
    pub worst_max_point: String,
}

/// Pose accuracy and repeatability of a measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// One entry per commanded point with visits, in commanded order.
    pub points: Vec<PointAccuracy>,
    /// The worst figures over all points.
    pub summary: PoseSummary,
}

/// Reads `point,x,y,z[,rx,ry,rz]`.
pub fn read_commanded_poses(
    path: &Path,
    map: &ColumnMap,
) -> Result<Vec<CommandedPose>, AccuracyError> {
    let t = Table::read(path, map)?;
    t.refuse_unknown(&["point", "x", "y", "z", "rx", "ry", "rz"])?;
    let point = t.column("point")?;
    let xyz = [t.column("x")?, t.column("y")?, t.column("z")?];
    let abc = t.angle_columns()?;
    let mut out: Vec<CommandedPose> = Vec::with_capacity(t.rows.len());
    for row in &t.rows {
        let name = t.text(row, point);
        if name.is_empty() {
            return Err(t.error_at(
                row,
                "point",
                "empty point name".into(),
                "name every commanded pose (P1, P2, …)",
            ));
        }
        if let Some(first) = out.iter().find(|c| c.name == name) {
            return Err(t.error_at(
                row,
                "point",
                format!(
                    "point `{name}` is commanded twice (first on line {})",
                    first.line
                ),
                "give each commanded pose its own name",
            ));
        }
        let position = Vector3::new(
            t.number(row, xyz[0])?,
            t.number(row, xyz[1])?,
            t.number(row, xyz[2])?,
        );
        let angles = match abc {
            Some(c) => Some([
                t.number(row, c[0])?,
                t.number(row, c[1])?,
                t.number(row, c[2])?,
            ]),
            None => None,
        };
        out.push(CommandedPose {
            name,
            line: row.line,
            position,
            angles,
        });
    }
    Ok(out)
}

/// Reads `point[,cycle],x,y,z[,rx,ry,rz]`: one row per visit; every point must be commanded and
/// a `(point, cycle)` pair appears once.
pub fn read_visits(
    path: &Path,
    map: &ColumnMap,
    commanded: &[CommandedPose],
) -> Result<Vec<Visit>, AccuracyError> {
    let t = Table::read(path, map)?;
    t.refuse_unknown(&["point", "cycle", "x", "y", "z", "rx", "ry", "rz"])?;
    let point = t.column("point")?;
    let cycle = t.optional("cycle");
    let xyz = [t.column("x")?, t.column("y")?, t.column("z")?];
    let abc = t.angle_columns()?;
    let mut out: Vec<Visit> = Vec::with_capacity(t.rows.len());
    for row in &t.rows {
        let name = t.text(row, point);
        if !commanded.iter().any(|c| c.name == name) {
            let known: Vec<&str> = commanded.iter().map(|c| c.name.as_str()).collect();
            return Err(t.error_at(
                row,
                "point",
                format!("point `{name}` is not among the commanded poses"),
                &format!(
                    "the commanded poses are {}; fix the name or add the pose",
                    known.join(", ")
                ),
            ));
        }
        let cycle = cycle.map(|c| t.text(row, c));
        if cycle.is_some()
            && let Some(first) = out.iter().find(|v| v.point == name && v.cycle == cycle)
        {
            return Err(t.error_at(
                row,
                "cycle",
                format!(
                    "point `{name}` cycle `{}` is measured twice (first on line {})",
                    cycle.as_deref().unwrap_or(""),
                    first.line
                ),
                "each cycle visits each point once; renumber the cycles or remove the duplicate",
            ));
        }
        let position = Vector3::new(
            t.number(row, xyz[0])?,
            t.number(row, xyz[1])?,
            t.number(row, xyz[2])?,
        );
        let angles = match abc {
            Some(c) => Some([
                t.number(row, c[0])?,
                t.number(row, c[1])?,
                t.number(row, c[2])?,
            ]),
            None => None,
        };
        out.push(Visit {
            point: name,
            cycle,
            line: row.line,
            position,
            angles,
        });
    }
    Ok(out)
}

/// The value of largest magnitude (its sign kept) and where it is.
fn worst<'a>(values: impl Iterator<Item = (f64, &'a str)>) -> (f64, &'a str) {
    values.fold((0.0, ""), |best, (v, p)| {
        if v.abs() > best.0.abs() || best.1.is_empty() {
            (v, p)
        } else {
            best
        }
    })
}

fn worst_opt(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let mut best: Option<f64> = None;
    for v in values {
        let v = v?;
        if best.is_none_or(|b| v.abs() > b.abs()) {
            best = Some(v);
        }
    }
    best
}

/// ISO 9283 pose figures of each commanded pose from its visits (at least 2 each).
pub fn pose_accuracy(
    commanded: &[CommandedPose],
    visits: &[Visit],
) -> Result<PoseReport, AccuracyError> {
    if commanded.is_empty() {
        return Err(AccuracyError::NoCommandedPoses);
    }
    let mut points = Vec::with_capacity(commanded.len());
    for c in commanded {
        let mine: Vec<&Visit> = visits.iter().filter(|v| v.point == c.name).collect();
        if mine.len() < 2 {
            return Err(AccuracyError::TooFewVisits {
                point: c.name.clone(),
                visits: mine.len(),
            });
        }
        let mut centre = RunningPoint::default();
        for v in &mine {
            centre.push(&v.position);
        }
        let mean = centre.mean();
        let ap = mean - c.position;
        let l = spread(mine.iter().map(|v| &v.position), &mean);
        let s_l = l.std().unwrap_or(0.0);
        let (mut l_min, mut l_max) = (f64::INFINITY, 0.0f64);
        for v in &mine {
            let d = (v.position - mean).norm();
            l_min = l_min.min(d);
            l_max = l_max.max(d);
        }
        let deviations: Vec<Vector3<f64>> = mine.iter().map(|v| v.position - c.position).collect();
        let max = deviations.iter().map(|d| d.norm()).fold(0.0, f64::max);
        // Angles: deviations from the commanded angle when it is known, else from the first
        // visit, so that a spread across ±180° stays small (3·S does not depend on the origin).
        let measured: Option<Vec<[f64; 3]>> = mine.iter().map(|v| v.angles).collect();
        let (mut ap_abc, mut rp_abc) = ([None; 3], [None; 3]);
        if let Some(measured) = &measured {
            let origin = c.angles.unwrap_or(measured[0]);
            for k in 0..3 {
                let mut r = Running::default();
                for a in measured {
                    r.push(angle_deviation(a[k], origin[k]));
                }
                if c.angles.is_some() {
                    ap_abc[k] = Some(r.mean());
                }
                rp_abc[k] = r.std().map(|s| 3.0 * s);
            }
        }
        points.push(PointAccuracy {
            point: c.name.clone(),
            n: mine.len(),
            ap: ap.norm(),
            ap_x: ap.x,
            ap_y: ap.y,
            ap_z: ap.z,
            ap_a: ap_abc[0],
            ap_b: ap_abc[1],
            ap_c: ap_abc[2],
            rp: repeatability(&l).unwrap_or(0.0),
            rp_a: rp_abc[0],
            rp_b: rp_abc[1],
            rp_c: rp_abc[2],
            max,
            l_mean: l.mean(),
            s_l,
            l_min,
            l_max,
            mean: mean.into(),
            commanded: c.position.into(),
            deviations,
        });
    }
    let named = |f: fn(&PointAccuracy) -> f64| {
        let (v, p) = worst(points.iter().map(|q| (f(q), q.point.as_str())));
        (v, p.to_owned())
    };
    let (ap, worst_ap_point) = named(|q| q.ap);
    let (rp, worst_rp_point) = named(|q| q.rp);
    let (max, worst_max_point) = named(|q| q.max);
    let summary = PoseSummary {
        points: points.len(),
        visits: points.iter().map(|p| p.n).sum(),
        ap,
        ap_x: named(|q| q.ap_x).0,
        ap_y: named(|q| q.ap_y).0,
        ap_z: named(|q| q.ap_z).0,
        ap_a: worst_opt(points.iter().map(|q| q.ap_a)),
        ap_b: worst_opt(points.iter().map(|q| q.ap_b)),
        ap_c: worst_opt(points.iter().map(|q| q.ap_c)),
        rp,
        rp_a: worst_opt(points.iter().map(|q| q.rp_a)),
        rp_b: worst_opt(points.iter().map(|q| q.rp_b)),
        rp_c: worst_opt(points.iter().map(|q| q.rp_c)),
        max,
        worst_ap_point,
        worst_rp_point,
        worst_max_point,
    };
    Ok(PoseReport { points, summary })
}

/// One figure before and after, and the change in percent of before (negative: better).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Change {
    /// The figure of the earlier measurement.
    pub before: f64,
    /// The figure of the later measurement.
    pub after: f64,
    /// `after − before`.
    pub change: f64,
    /// `100·(after − before)/before`; `None` when before is 0.
    pub percent: Option<f64>,
}

impl Change {
    /// The change from `before` to `after`.
    pub fn new(before: f64, after: f64) -> Change {
        Change {
            before,
            after,
            change: after - before,
            percent: (before != 0.0).then(|| 100.0 * (after - before) / before),
        }
    }
}

/// How one point changed between two measurements.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PointChange {
    /// The point's name (`"worst"` for the summary).
    pub point: String,
    /// AP before and after, mm.
    #[serde(rename = "AP")]
    pub ap: Change,
    /// RP before and after, mm.
    #[serde(rename = "RP")]
    pub rp: Change,
    /// MAX before and after, mm.
    #[serde(rename = "MAX")]
    pub max: Change,
}

/// Before/after: the improvement a correction brought, per point and for the worst figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseComparison {
    /// Per point of the later measurement, in its order.
    pub points: Vec<PointChange>,
    /// The worst figures before and after.
    pub summary: PointChange,
}

/// Compares two reports over the same commanded poses.
pub fn compare(before: &PoseReport, after: &PoseReport) -> Result<PoseComparison, AccuracyError> {
    let mut points = Vec::with_capacity(after.points.len());
    for a in &after.points {
        let Some(b) = before.points.iter().find(|b| b.point == a.point) else {
            return Err(AccuracyError::NotInEarlier {
                point: a.point.clone(),
            });
        };
        points.push(PointChange {
            point: a.point.clone(),
            ap: Change::new(b.ap, a.ap),
            rp: Change::new(b.rp, a.rp),
            max: Change::new(b.max, a.max),
        });
    }
    let (b, a) = (&before.summary, &after.summary);
    Ok(PoseComparison {
        points,
        summary: PointChange {
            point: "worst".into(),
            ap: Change::new(b.ap, a.ap),
            rp: Change::new(b.rp, a.rp),
            max: Change::new(b.max, a.max),
        },
    })
}
