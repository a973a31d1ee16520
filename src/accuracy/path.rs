//! ISO 9283 path accuracy and repeatability (thesis §3.4.1, eqs 3.12-3.23): the runs of a
//! recorded motion cut by planes normal to the commanded path.

use std::path::Path;

use nalgebra::Vector3;
use serde::Serialize;

use super::error::AccuracyError;
use super::line::{LineReport, line_report};
use super::segment::{RunInfo, runs_by_cycle, runs_by_motion};
use super::stats::{Running, RunningPoint, angle_deviation, angle_lerp, repeatability, spread};
use super::table::{ColumnMap, Table};

/// The programmed path: a polyline (two vertices for a straight line), with `[rx, ry, rz]` at
/// each vertex when given (interpolated linearly along the path, the shorter way round).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    vertices: Vec<Vector3<f64>>,
    angles: Option<Vec<[f64; 3]>>,
    /// Arc length at each vertex.
    cumulative: Vec<f64>,
}

/// Where a point is relative to the path: the arc position of its foot, the perpendicular
/// distance (eq. 3.38) and the offset vector from the foot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Arc length of the foot; below 0 or above the length beyond the end planes.
    pub s: f64,
    /// Perpendicular distance from the path, mm (eq. 3.38).
    pub distance: f64,
    /// The point minus its foot on the path.
    pub offset: Vector3<f64>,
    /// The 0-based segment the foot is on.
    pub segment: usize,
}

impl Polyline {
    /// At least two vertices, no zero-length segment.
    pub fn new(
        vertices: Vec<Vector3<f64>>,
        angles: Option<Vec<[f64; 3]>>,
    ) -> Result<Polyline, AccuracyError> {
        if vertices.len() < 2 {
            return Err(AccuracyError::PathTooShort {
                points: vertices.len(),
            });
        }
        let mut cumulative = vec![0.0];
        for (k, w) in vertices.windows(2).enumerate() {
            let len = (w[1] - w[0]).norm();
            if len < 1e-9 {
                return Err(AccuracyError::CoincidentPoints { first: k + 1 });
            }
            cumulative.push(cumulative[k] + len);
        }
        Ok(Polyline {
            vertices,
            angles,
            cumulative,
        })
    }

    /// The vertices, in path order.
    pub fn vertices(&self) -> &[Vector3<f64>] {
        &self.vertices
    }

    /// Whether the vertices carry `[rx, ry, rz]`.
    pub fn has_angles(&self) -> bool {
        self.angles.is_some()
    }

    /// Arc length at vertex `k`.
    pub fn arc_at_vertex(&self, k: usize) -> f64 {
        self.cumulative
            .get(k)
            .copied()
            .unwrap_or_else(|| self.length())
    }

    /// Arc length `L`.
    pub fn length(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    fn segment_at(&self, s: f64) -> usize {
        let last = self.vertices.len() - 2;
        (0..=last)
            .find(|&k| s <= self.cumulative[k + 1])
            .unwrap_or(last)
    }

    /// The unit direction of segment `k`.
    pub fn tangent(&self, k: usize) -> Vector3<f64> {
        (self.vertices[k + 1] - self.vertices[k]).normalize()
    }

    /// The point at arc length `s` and the direction of the path there.
    pub fn at(&self, s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let k = self.segment_at(s);
        let u = self.tangent(k);
        (self.vertices[k] + u * (s - self.cumulative[k]), u)
    }

    /// The commanded angles at arc length `s`.
    pub fn angles_at(&self, s: f64) -> Option<[f64; 3]> {
        let angles = self.angles.as_ref()?;
        let k = self.segment_at(s);
        let len = self.cumulative[k + 1] - self.cumulative[k];
        let lambda = ((s - self.cumulative[k]) / len).clamp(0.0, 1.0);
        Some(std::array::from_fn(|c| {
            angle_lerp(angles[k][c], angles[k + 1][c], lambda)
        }))
    }

    /// The nearest point of the path; the first and last segments extend beyond the ends, so
    /// a point before the start plane has `s < 0`.
    pub fn project(&self, p: &Vector3<f64>) -> Projection {
        let last = self.vertices.len() - 2;
        let mut best: Option<Projection> = None;
        for k in 0..=last {
            let a = self.vertices[k];
            let u = self.tangent(k);
            let len = self.cumulative[k + 1] - self.cumulative[k];
            let mut lambda = (p - a).dot(&u);
            if k > 0 {
                lambda = lambda.max(0.0);
            }
            if k < last {
                lambda = lambda.min(len);
            }
            let offset = p - (a + u * lambda);
            let distance = offset.norm();
            if best.is_none_or(|b| distance < b.distance) {
                best = Some(Projection {
                    s: self.cumulative[k] + lambda,
                    distance,
                    offset,
                    segment: k,
                });
            }
        }
        best.unwrap_or(Projection {
            s: 0.0,
            distance: 0.0,
            offset: Vector3::zeros(),
            segment: 0,
        })
    }
}

/// One sample of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// 1-based line of the file the sample is on.
    pub line: u64,
    /// Time in seconds, when the recording has it.
    pub t: Option<f64>,
    /// Measured position, mm.
    pub position: Vector3<f64>,
    /// Measured `[rx, ry, rz]` in degrees, when the file has them.
    pub angles: Option<[f64; 3]>,
}

/// A recording: its samples in file order and, when the file has a `cycle` column, each
/// sample's cycle.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The samples, in file order.
    pub samples: Vec<Sample>,
    /// Each sample's cycle, when the file has a `cycle` column (one per sample).
    pub cycles: Option<Vec<String>>,
}

/// One run along the path.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The cycle's name, or the run's 1-based number when runs were found from the motion.
    pub label: String,
    /// The run's samples, in time order.
    pub samples: Vec<Sample>,
}

/// Reads the commanded path: `x,y,z[,rx,ry,rz]` (an optional `point` column names the rows).
pub fn read_commanded_path(path: &Path, map: &ColumnMap) -> Result<Polyline, AccuracyError> {
    let t = Table::read(path, map)?;
    t.refuse_unknown(&["point", "x", "y", "z", "rx", "ry", "rz"])?;
    let xyz = [t.column("x")?, t.column("y")?, t.column("z")?];
    let abc = t.angle_columns()?;
    let mut vertices = Vec::new();
    let mut angles = abc.map(|_| Vec::new());
    for row in &t.rows {
        vertices.push(Vector3::new(
            t.number(row, xyz[0])?,
            t.number(row, xyz[1])?,
            t.number(row, xyz[2])?,
        ));
        if let (Some(c), Some(a)) = (abc, angles.as_mut()) {
            a.push([
                t.number(row, c[0])?,
                t.number(row, c[1])?,
                t.number(row, c[2])?,
            ]);
        }
        if let Some(&last) = vertices.iter().rev().nth(1)
            && (vertices[vertices.len() - 1] - last).norm() < 1e-9
        {
            return Err(t.located(
                row,
                None,
                "this point repeats the one before".into(),
                "remove the repeated point".into(),
            ));
        }
    }
    Polyline::new(vertices, angles)
}

/// Reads `[cycle,][t,]x,y,z[,rx,ry,rz]` samples; times must increase within a cycle (or over
/// the whole file without cycles).
pub fn read_recording(path: &Path, map: &ColumnMap) -> Result<Recording, AccuracyError> {
    let t = Table::read(path, map)?;
    t.refuse_unknown(&["cycle", "t", "x", "y", "z", "rx", "ry", "rz"])?;
    let cycle = t.optional("cycle");
    let time = t.optional("t");
    let xyz = [t.column("x")?, t.column("y")?, t.column("z")?];
    let abc = t.angle_columns()?;
    let mut samples: Vec<Sample> = Vec::with_capacity(t.rows.len());
    let mut cycles = cycle.map(|_| Vec::with_capacity(t.rows.len()));
    let mut last_time: Vec<(String, f64, u64)> = Vec::new();
    for row in &t.rows {
        let label = cycle.map(|c| t.text(row, c)).unwrap_or_default();
        let time_value = match time {
            Some(c) => Some(t.number(row, c)?),
            None => None,
        };
        if let Some(tv) = time_value {
            if let Some(prev) = last_time.iter_mut().find(|(l, _, _)| *l == label) {
                if tv <= prev.1 {
                    return Err(t.error_at(
                        row,
                        "t",
                        format!(
                            "time {tv} s does not increase (line {} has {} s)",
                            prev.2, prev.1
                        ),
                        "the samples of a run must be in time order",
                    ));
                }
                *prev = (label.clone(), tv, row.line);
            } else {
                last_time.push((label.clone(), tv, row.line));
            }
        }
        samples.push(Sample {
            line: row.line,
            t: time_value,
            position: Vector3::new(
                t.number(row, xyz[0])?,
                t.number(row, xyz[1])?,
                t.number(row, xyz[2])?,
            ),
            angles: match abc {
                Some(c) => Some([
                    t.number(row, c[0])?,
                    t.number(row, c[1])?,
                    t.number(row, c[2])?,
                ]),
                None => None,
            },
        });
        if let Some(c) = cycles.as_mut() {
            c.push(label);
        }
    }
    Ok(Recording { samples, cycles })
}

/// Where a run crosses a plane: the point, the angles and the time, linear between the two
/// samples on either side.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    /// The crossing point, mm.
    pub position: Vector3<f64>,
    /// `[rx, ry, rz]` at the crossing, degrees, when the samples have them.
    pub angles: Option<[f64; 3]>,
    /// Time of the crossing, seconds, when the samples have times.
    pub t: Option<f64>,
}

/// The crossing of `samples` with the plane through `c` normal to `u` nearest to `c`: signed
/// distances change sign between two samples (a run through a corner may cross the plane of
/// another leg far away; the nearest crossing is the one that belongs to this plane).
pub fn plane_crossing(samples: &[Sample], c: &Vector3<f64>, u: &Vector3<f64>) -> Option<Crossing> {
    let mut best: Option<(f64, Crossing)> = None;
    let signed: Vec<f64> = samples.iter().map(|s| (s.position - c).dot(u)).collect();
    for k in 0..samples.len().saturating_sub(1) {
        let (f0, f1) = (signed[k], signed[k + 1]);
        let crosses = (f0 <= 0.0 && f1 > 0.0) || (f0 >= 0.0 && f1 < 0.0);
        if !crosses {
            continue;
        }
        let lambda = f0 / (f0 - f1);
        let (a, b) = (&samples[k], &samples[k + 1]);
        let position = a.position + (b.position - a.position) * lambda;
        let angles = match (a.angles, b.angles) {
            (Some(x), Some(y)) => Some(std::array::from_fn(|i| angle_lerp(x[i], y[i], lambda))),
            _ => None,
        };
        let t = match (a.t, b.t) {
            (Some(x), Some(y)) => Some(x + (y - x) * lambda),
            _ => None,
        };
        let d = (position - c).norm();
        if best.as_ref().is_none_or(|(bd, _)| d < *bd) {
            best = Some((
                d,
                Crossing {
                    position,
                    angles,
                    t,
                },
            ));
        }
    }
    best.map(|(_, c)| c)
}

/// The figures at one plane.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlaneAccuracy {
    /// 1..=M.
    pub i: usize,
    /// Arc length `L·i/(M+1)`.
    pub s: f64,
    /// The commanded point at `s`.
    pub commanded: [f64; 3],
    /// The barycentre of the runs' crossings (eq. 3.13).
    pub barycentre: [f64; 3],
    /// `|barycentre − commanded|` (eq. 3.12).
    #[serde(rename = "ATp")]
    pub atp: f64,
    /// `l̄ + 3·S_l` of the crossings around the barycentre (eqs 3.18-3.20).
    #[serde(rename = "RTp")]
    pub rtp: f64,
    /// `l̄`, mean distance of the crossings from their barycentre (eq. 3.19).
    pub l_mean: f64,
    /// `S_l`, the standard deviation behind RTp (eq. 3.20).
    #[serde(rename = "S_l")]
    pub s_l: f64,
    /// `|ā − a_c|` etc. (eqs 3.14-3.17), `None` without angles on both sides.
    #[serde(rename = "ATa")]
    pub at_a: Option<f64>,
    /// Like `ATa`, about `ry`.
    #[serde(rename = "ATb")]
    pub at_b: Option<f64>,
    /// Like `ATa`, about `rz`.
    #[serde(rename = "ATc")]
    pub at_c: Option<f64>,
    /// `3·S` of the crossings' angles (eqs 3.21-3.23), `None` without measured angles.
    #[serde(rename = "RTa")]
    pub rt_a: Option<f64>,
    /// Like `RTa`, about `ry`.
    #[serde(rename = "RTb")]
    pub rt_b: Option<f64>,
    /// Like `RTa`, about `rz`.
    #[serde(rename = "RTc")]
    pub rt_c: Option<f64>,
    /// Each run's crossing (for the plots).
    #[serde(skip)]
    pub crossings: Vec<Vector3<f64>>,
}

/// Path accuracy and repeatability of a recording, and the straight-line report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathReport {
    /// Commanded path length in mm.
    pub length: f64,
    /// Runs used for the figures.
    pub runs_used: usize,
    /// `AT`: the largest `ATp` over the planes, mm.
    #[serde(rename = "AT")]
    pub at: f64,
    /// `RT`: the largest `RTp` over the planes, mm.
    #[serde(rename = "RT")]
    pub rt: f64,
    /// The largest `ATa` over the planes, degrees.
    #[serde(rename = "ATa")]
    pub at_a: Option<f64>,
    /// The largest `ATb` over the planes, degrees.
    #[serde(rename = "ATb")]
    pub at_b: Option<f64>,
    /// The largest `ATc` over the planes, degrees.
    #[serde(rename = "ATc")]
    pub at_c: Option<f64>,
    /// The largest `RTa` over the planes, degrees.
    #[serde(rename = "RTa")]
    pub rt_a: Option<f64>,
    /// The largest `RTb` over the planes, degrees.
    #[serde(rename = "RTb")]
    pub rt_b: Option<f64>,
    /// The largest `RTc` over the planes, degrees.
    #[serde(rename = "RTc")]
    pub rt_c: Option<f64>,
    /// The figures at each plane, in path order.
    pub planes: Vec<PlaneAccuracy>,
    /// The straight-line report of Table 5.1 (`docs/design.md §11`).
    pub line: LineReport,
    /// Every run found in the recording, used or not, and why not.
    pub runs: Vec<RunInfo>,
    /// The runs used, for the plots.
    #[serde(skip)]
    pub used: Vec<Run>,
}

/// What the path analysis needs besides the files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptions {
    /// Number of planes `M` (ISO 9283: at least 10 are usual).
    pub planes: usize,
    /// The programmed speed in mm/s, for the velocity figures.
    pub commanded_speed: Option<f64>,
}

impl Default for PathOptions {
    fn default() -> PathOptions {
        PathOptions {
            planes: 10,
            commanded_speed: None,
        }
    }
}

fn max_opt(values: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let mut best: Option<f64> = None;
    for v in values {
        let v = v?;
        best = Some(best.map_or(v, |b: f64| b.max(v)));
    }
    best
}

/// ISO 9283 path figures on `M` planes, and the straight-line report. Runs come from the
/// `cycle` column or, without one, from cutting the recording at stops and reversals.
pub fn path_accuracy(
    commanded: &Polyline,
    recording: &Recording,
    options: PathOptions,
) -> Result<PathReport, AccuracyError> {
    if options.planes == 0 {
        return Err(AccuracyError::NoPlanes);
    }
    let (runs, infos) = match &recording.cycles {
        Some(cycles) => runs_by_cycle(commanded, &recording.samples, cycles)?,
        None => runs_by_motion(commanded, &recording.samples)?,
    };
    let used: Vec<Run> = runs
        .into_iter()
        .zip(&infos)
        .filter(|(_, info)| info.used)
        .map(|(r, _)| r)
        .collect();
    if used.len() < 2 {
        return Err(AccuracyError::TooFewRuns {
            used: used.len(),
            found: infos.len(),
        });
    }
    let m = options.planes;
    let length = commanded.length();
    let mut planes = Vec::with_capacity(m);
    for i in 1..=m {
        let s = length * i as f64 / (m + 1) as f64;
        let (c, u) = commanded.at(s);
        let mut crossings = Vec::with_capacity(used.len());
        for run in &used {
            let Some(x) = plane_crossing(&run.samples, &c, &u) else {
                return Err(AccuracyError::NoCrossing {
                    run: run.label.clone(),
                    s,
                });
            };
            crossings.push(x);
        }
        let mut centre = RunningPoint::default();
        for x in &crossings {
            centre.push(&x.position);
        }
        let bary = centre.mean();
        let points: Vec<Vector3<f64>> = crossings.iter().map(|x| x.position).collect();
        let l = spread(points.iter(), &bary);
        let commanded_angles = commanded.angles_at(s);
        let measured: Option<Vec<[f64; 3]>> = crossings.iter().map(|x| x.angles).collect();
        let (mut at_abc, mut rt_abc) = ([None; 3], [None; 3]);
        if let Some(measured) = &measured {
            let origin = commanded_angles.unwrap_or(measured[0]);
            for k in 0..3 {
                let mut r = Running::default();
                for a in measured {
                    r.push(angle_deviation(a[k], origin[k]));
                }
                if commanded_angles.is_some() {
                    at_abc[k] = Some(r.mean().abs());
                }
                rt_abc[k] = r.std().map(|sd| 3.0 * sd);
            }
        }
        planes.push(PlaneAccuracy {
            i,
            s,
            commanded: c.into(),
            barycentre: bary.into(),
            atp: (bary - c).norm(),
            rtp: repeatability(&l).unwrap_or(0.0),
            l_mean: l.mean(),
            s_l: l.std().unwrap_or(0.0),
            at_a: at_abc[0],
            at_b: at_abc[1],
            at_c: at_abc[2],
            rt_a: rt_abc[0],
            rt_b: rt_abc[1],
            rt_c: rt_abc[2],
            crossings: points,
        });
    }
    let at = planes.iter().map(|p| p.atp).fold(0.0, f64::max);
    let rt = planes.iter().map(|p| p.rtp).fold(0.0, f64::max);
    let line = line_report(commanded, &used, &planes, rt, options.commanded_speed);
    Ok(PathReport {
        length,
        runs_used: used.len(),
        at,
        rt,
        at_a: max_opt(planes.iter().map(|p| p.at_a)),
        at_b: max_opt(planes.iter().map(|p| p.at_b)),
        at_c: max_opt(planes.iter().map(|p| p.at_c)),
        rt_a: max_opt(planes.iter().map(|p| p.rt_a)),
        rt_b: max_opt(planes.iter().map(|p| p.rt_b)),
        rt_c: max_opt(planes.iter().map(|p| p.rt_c)),
        planes,
        line,
        runs: infos,
        used,
    })
}
