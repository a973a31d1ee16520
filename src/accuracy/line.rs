//! The straight-line report of thesis §5.2 (Table 5.1): path length, commanded and measured
//! velocity, the largest velocity deviation, acceleration, the largest perpendicular deviation
//! (eq. 3.38), repeat uncertainty and the deviations at the start and end positions.
//!
//! Velocities are difference quotients over ±[`WINDOW`] samples (the thesis's quotient over one
//! sample interval, eq. in §3.5.3, would report the tracker's noise as speed changes). The
//! travel figures use the samples between the first and the last plane, where the robot
//! travels at speed; acceleration is the 10 %-90 % rise of the speed at the start of each run,
//! `a = 0.8·v / (t90 − t10)` (deceleration likewise at the end), averaged over the runs.

use serde::Serialize;

use super::path::{PlaneAccuracy, Polyline, Run};
use super::segment::WINDOW;

/// Table 5.1. Lengths in mm, velocities in mm/s, accelerations in mm/s².
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LineReport {
    /// Commanded path length.
    pub length: f64,
    /// The programmed speed, when given.
    pub commanded_velocity: Option<f64>,
    /// Median travel speed; `None` without times.
    pub measured_velocity: Option<f64>,
    /// Largest `|v − v_c| / v_c` in per cent while travelling (`v_c`: the commanded velocity,
    /// else the measured one).
    pub velocity_deviation_max_percent: Option<f64>,
    /// Mean 10 %-90 % speed rise at the start of the runs, mm/s²; `None` without times.
    pub acceleration: Option<f64>,
    /// The same at the end of the runs (a positive figure), mm/s²; `None` without times.
    pub deceleration: Option<f64>,
    /// Largest perpendicular distance to the path of any sample between the end planes
    /// (eq. 3.38), where it is and in which run.
    pub max_deviation: f64,
    /// Arc length along the commanded path where the largest deviation is, mm.
    pub max_deviation_s: f64,
    /// The run the largest deviation is in.
    pub max_deviation_run: String,
    /// Mean perpendicular distance over the same samples.
    pub mean_deviation: f64,
    /// The path repeatability RT.
    pub repeat_uncertainty: f64,
    /// Distance of the runs' mean start (first samples) and end (last samples) from the
    /// commanded start and end.
    pub start_deviation: f64,
    /// Distance of the runs' mean end from the commanded end, mm.
    pub end_deviation: f64,
    /// The same figures per straight leg of the commanded path (one for a line): where a path
    /// changes direction the deviations of one leg do not hide those of the next.
    pub legs: Vec<LegReport>,
}

/// The straight-line figures of one leg of the commanded path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LegReport {
    /// 1-based.
    pub leg: usize,
    /// Arc length where the leg starts, mm.
    pub from_s: f64,
    /// Arc length where the leg ends, mm.
    pub to_s: f64,
    /// Samples whose nearest path point is on this leg.
    pub samples: usize,
    /// Largest and mean perpendicular distance of the samples whose nearest path point is on
    /// this leg (eq. 3.38).
    pub max_deviation: f64,
    /// Mean perpendicular distance of those samples, mm.
    pub mean_deviation: f64,
    /// Median windowed speed of those samples; `None` without times.
    pub measured_velocity: Option<f64>,
}

fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    Some(if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    })
}

/// `(t − t_first, speed)` of each sample over the window; empty without times.
pub(crate) fn speed_series(run: &Run) -> Vec<(f64, f64)> {
    let n = run.samples.len();
    let times: Option<Vec<f64>> = run.samples.iter().map(|s| s.t).collect();
    let Some(times) = times else {
        return Vec::new();
    };
    (0..n)
        .filter_map(|k| {
            let lo = k.saturating_sub(WINDOW);
            let hi = (k + WINDOW).min(n - 1);
            let dt = times[hi] - times[lo];
            (hi > lo && dt > 0.0).then(|| {
                let d = (run.samples[hi].position - run.samples[lo].position).norm();
                (times[k] - times[0], d / dt)
            })
        })
        .collect()
}

/// `(t − t_first, acceleration)`: the difference quotient of [`speed_series`] over the window.
pub(crate) fn acceleration_series(run: &Run) -> Vec<(f64, f64)> {
    let v = speed_series(run);
    let n = v.len();
    (0..n)
        .filter_map(|k| {
            let lo = k.saturating_sub(WINDOW);
            let hi = (k + WINDOW).min(n.saturating_sub(1));
            let dt = v[hi].0 - v[lo].0;
            (hi > lo && dt > 0.0).then(|| (v[k].0, (v[hi].1 - v[lo].1) / dt))
        })
        .collect()
}

/// The 10 %-90 % ramps of one run's speed: (acceleration, deceleration).
fn ramps(series: &[(f64, f64)], v: f64) -> (Option<f64>, Option<f64>) {
    let (low, high) = (0.1 * v, 0.9 * v);
    let up = series.iter().position(|p| p.1 >= low).and_then(|a| {
        let b = a + series[a..].iter().position(|p| p.1 >= high)?;
        let dt = series[b].0 - series[a].0;
        (dt > 0.0).then(|| 0.8 * v / dt)
    });
    let down = series.iter().rposition(|p| p.1 >= high).and_then(|a| {
        let b = a + series[a..].iter().position(|p| p.1 <= low)?;
        let dt = series[b].0 - series[a].0;
        (dt > 0.0).then(|| 0.8 * v / dt)
    });
    (up, down)
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Table 5.1 from the runs used, the plane figures and RT.
pub(crate) fn line_report(
    commanded: &Polyline,
    runs: &[Run],
    planes: &[PlaneAccuracy],
    rt: f64,
    commanded_speed: Option<f64>,
) -> LineReport {
    let length = commanded.length();
    let (s_first, s_last) = (
        planes.first().map_or(0.0, |p| p.s),
        planes.last().map_or(length, |p| p.s),
    );
    let legs_count = commanded.vertices().len() - 1;
    let mut per_leg: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); legs_count];
    let mut travel = Vec::new();
    let mut max_deviation = (0.0, 0.0, String::new());
    let mut deviations = Vec::new();
    for run in runs {
        let series = speed_series(run);
        for (k, sample) in run.samples.iter().enumerate() {
            let p = commanded.project(&sample.position);
            if (0.0..=length).contains(&p.s) {
                deviations.push(p.distance);
                if p.distance > max_deviation.0 || max_deviation.2.is_empty() {
                    max_deviation = (p.distance, p.s, run.label.clone());
                }
                if let Some(leg) = per_leg.get_mut(p.segment) {
                    leg.0.push(p.distance);
                    if let Some(v) = series.get(k) {
                        leg.1.push(v.1);
                    }
                }
            }
            if (s_first..=s_last).contains(&p.s)
                && let Some(v) = series.get(k)
            {
                travel.push(v.1);
            }
        }
    }
    let measured_velocity = median(&travel);
    let reference = commanded_speed.or(measured_velocity).filter(|v| *v > 0.0);
    let velocity_deviation_max_percent = reference.and_then(|r| {
        travel
            .iter()
            .map(|v| 100.0 * (v - r).abs() / r)
            .reduce(f64::max)
    });
    let (mut ups, mut downs) = (Vec::new(), Vec::new());
    if let Some(v) = measured_velocity.filter(|v| *v > 0.0) {
        for run in runs {
            let (up, down) = ramps(&speed_series(run), v);
            ups.extend(up);
            downs.extend(down);
        }
    }
    let vertices = commanded.vertices();
    let end_of = |first: bool| {
        let mut sum = nalgebra::Vector3::zeros();
        for run in runs {
            let s = if first {
                run.samples.first()
            } else {
                run.samples.last()
            };
            if let Some(s) = s {
                sum += s.position;
            }
        }
        let target = if first {
            vertices[0]
        } else {
            vertices[vertices.len() - 1]
        };
        (sum / runs.len().max(1) as f64 - target).norm()
    };
    let legs = per_leg
        .iter()
        .enumerate()
        .map(|(k, (d, v))| LegReport {
            leg: k + 1,
            from_s: commanded.arc_at_vertex(k),
            to_s: commanded.arc_at_vertex(k + 1),
            samples: d.len(),
            max_deviation: d.iter().copied().fold(0.0, f64::max),
            mean_deviation: mean(d).unwrap_or(0.0),
            measured_velocity: median(v),
        })
        .collect();
    LineReport {
        legs,
        length,
        commanded_velocity: commanded_speed,
        measured_velocity,
        velocity_deviation_max_percent,
        acceleration: mean(&ups),
        deceleration: mean(&downs),
        max_deviation: max_deviation.0,
        max_deviation_s: max_deviation.1,
        max_deviation_run: max_deviation.2,
        mean_deviation: mean(&deviations).unwrap_or(0.0),
        repeat_uncertainty: rt,
        start_deviation: end_of(true),
        end_deviation: end_of(false),
    }
}
