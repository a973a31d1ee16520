//! Cutting a recording into runs: by its `cycle` column, or, for one continuous recording of
//! several runs, at the "key positions" of thesis §5.1.1 — where the robot stops and where it
//! reverses along the path.
//!
//! The motion state of each sample comes from its velocity along the path, taken over a window
//! of ±[`WINDOW`] samples (tracker noise over one sample interval is several per cent of the
//! speed; over ten it is a tenth of that). A sample moves forward or backward when that
//! velocity exceeds [`STOP_FRACTION`] of the recording's typical travel speed (its 95th
//! percentile), and stands otherwise. A run is a span of one direction with the standing
//! samples around it; a stop between two runs is split in the middle. Spans shorter than the
//! window are noise and stand. A stop inside the path (a corner, a fine point) does not end a
//! run: two spans of one direction around it are one run.

use nalgebra::Vector3;
use serde::Serialize;

use super::error::AccuracyError;
use super::path::{Polyline, Run, Sample};

/// Half-width of the velocity window, in samples.
pub(crate) const WINDOW: usize = 5;
/// Below this fraction of the travel speed a sample stands.
pub(crate) const STOP_FRACTION: f64 = 0.1;
/// A run used for the figures must reach from this fraction of the path length from the start
/// to this fraction from the end.
pub(crate) const COVER_FRACTION: f64 = 0.05;

/// The direction of a run along the commanded path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// From the first commanded point towards the last.
    Forward,
    /// From the last commanded point towards the first.
    Backward,
}

/// A run found in the recording, whether it was used and, if not, why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunInfo {
    /// `cycle C` for a run of the `cycle` column, `run N` (1-based) for one found from the motion.
    pub label: String,
    /// 1-based line of the run's first sample.
    pub first_line: u64,
    /// 1-based line of the run's last sample.
    pub last_line: u64,
    /// Samples in the run.
    pub samples: usize,
    /// Which way along the path the run goes.
    pub direction: Direction,
    /// The stretch of the path the run covers: the smallest arc length of its samples, mm.
    pub from_s: f64,
    /// The largest arc length of its samples, mm.
    pub to_s: f64,
    /// Whether the figures use this run.
    pub used: bool,
    /// Why the run is not used; `None` when it is.
    pub note: Option<String>,
}

fn info(commanded: &Polyline, label: String, samples: &[Sample]) -> RunInfo {
    let s: Vec<f64> = samples
        .iter()
        .map(|x| commanded.project(&x.position).s)
        .collect();
    let first = s.first().copied().unwrap_or(0.0);
    let last = s.last().copied().unwrap_or(0.0);
    let from_s = s.iter().copied().fold(f64::INFINITY, f64::min);
    let to_s = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let direction = if last >= first {
        Direction::Forward
    } else {
        Direction::Backward
    };
    let length = commanded.length();
    let covers = from_s <= COVER_FRACTION * length && to_s >= (1.0 - COVER_FRACTION) * length;
    let note = if direction == Direction::Backward {
        Some("runs backward along the path; ISO 9283 compares runs in one direction".to_owned())
    } else if !covers {
        Some(format!(
            "covers s = {from_s:.1} .. {to_s:.1} mm only, not the whole path (0 .. {length:.1} mm)"
        ))
    } else {
        None
    };
    RunInfo {
        label,
        first_line: samples.first().map_or(0, |x| x.line),
        last_line: samples.last().map_or(0, |x| x.line),
        samples: samples.len(),
        direction,
        from_s,
        to_s,
        used: note.is_none(),
        note,
    }
}

/// Runs from the `cycle` column, in order of first appearance.
pub(crate) fn runs_by_cycle(
    commanded: &Polyline,
    samples: &[Sample],
    cycles: &[String],
) -> Result<(Vec<Run>, Vec<RunInfo>), AccuracyError> {
    let mut keys: Vec<&str> = Vec::new();
    let mut runs: Vec<Run> = Vec::new();
    for (s, c) in samples.iter().zip(cycles) {
        match keys.iter().position(|k| *k == c.as_str()) {
            Some(i) => runs[i].samples.push(s.clone()),
            None => {
                keys.push(c);
                runs.push(Run {
                    label: format!("cycle {c}"),
                    samples: vec![s.clone()],
                });
            }
        }
    }
    let infos = runs
        .iter()
        .map(|r| info(commanded, r.label.clone(), &r.samples))
        .collect();
    Ok((runs, infos))
}

/// The velocity along the path and the speed of each sample over the window.
fn motion(commanded: &Polyline, samples: &[Sample], times: &[f64]) -> Vec<(f64, f64)> {
    let n = samples.len();
    (0..n)
        .map(|k| {
            let lo = k.saturating_sub(WINDOW);
            let hi = (k + WINDOW).min(n - 1);
            let dt = times[hi] - times[lo];
            if hi == lo || dt <= 0.0 {
                return (0.0, 0.0);
            }
            let d: Vector3<f64> = samples[hi].position - samples[lo].position;
            let u = commanded.tangent(commanded.project(&samples[k].position).segment);
            (d.dot(&u) / dt, d.norm() / dt)
        })
        .collect()
}

/// Runs of a continuous recording, cut at stops and reversals (see the module text).
pub(crate) fn runs_by_motion(
    commanded: &Polyline,
    samples: &[Sample],
) -> Result<(Vec<Run>, Vec<RunInfo>), AccuracyError> {
    let times: Option<Vec<f64>> = samples.iter().map(|s| s.t).collect();
    let Some(times) = times else {
        return Err(AccuracyError::NoTimes);
    };
    if samples.len() < 2 * WINDOW + 2 {
        return Err(AccuracyError::TooFewSamples {
            samples: samples.len(),
            needed: 2 * WINDOW + 2,
        });
    }
    let m = motion(commanded, samples, &times);
    let mut speeds: Vec<f64> = m.iter().map(|x| x.1).collect();
    speeds.sort_by(f64::total_cmp);
    let travel = speeds[(speeds.len() - 1) * 95 / 100];
    if travel <= 0.0 {
        return Err(AccuracyError::Standing);
    }
    let threshold = STOP_FRACTION * travel;
    let mut state: Vec<i8> = m
        .iter()
        .map(|&(axial, _)| {
            if axial > threshold {
                1
            } else if axial < -threshold {
                -1
            } else {
                0
            }
        })
        .collect();
    let spans = |state: &[i8]| {
        let mut out: Vec<(usize, usize, i8)> = Vec::new();
        let mut k = 0;
        while k < state.len() {
            let s = state[k];
            let start = k;
            while k < state.len() && state[k] == s {
                k += 1;
            }
            if s != 0 {
                out.push((start, k - 1, s));
            }
        }
        out
    };
    for (a, b, _) in spans(&state) {
        if b - a < 2 * WINDOW {
            state[a..=b].fill(0);
        }
    }
    // A stop inside the path (at a corner, a fine point, a pause) does not end the run: two
    // spans of one direction with a stop between them merge unless the stop is at an end.
    let length = commanded.length();
    let mut moving: Vec<(usize, usize, i8)> = Vec::new();
    for span in spans(&state) {
        if let Some(last) = moving.last_mut()
            && last.2 == span.2
        {
            let gap = &samples[last.1 + 1..span.0];
            let inside = gap.is_empty() || {
                let mean = gap.iter().map(|x| x.position).sum::<Vector3<f64>>() / gap.len() as f64;
                let s = commanded.project(&mean).s;
                s > COVER_FRACTION * length && s < (1.0 - COVER_FRACTION) * length
            };
            if inside {
                last.1 = span.1;
                continue;
            }
        }
        moving.push(span);
    }
    let mut runs = Vec::with_capacity(moving.len());
    let mut infos = Vec::with_capacity(moving.len());
    for (j, &(a, b, _)) in moving.iter().enumerate() {
        // A stop between two runs is split in the middle: its first half still holds the end
        // of the previous run's deceleration, its second half is where the next one starts.
        let start = if j == 0 {
            0
        } else {
            (moving[j - 1].1 + a).div_ceil(2)
        };
        let end = moving
            .get(j + 1)
            .map_or(samples.len() - 1, |next| (b + next.0) / 2);
        let (start, end) = (start.min(a), end.max(b));
        let label = format!("run {}", j + 1);
        let run_samples = samples[start..=end].to_vec();
        infos.push(info(commanded, label.clone(), &run_samples));
        runs.push(Run {
            label,
            samples: run_samples,
        });
    }
    Ok((runs, infos))
}
