//! Deterministic synthetic measurements with known errors: how `samples/accuracy/` was made,
//! and data for tests. A seeded linear congruential generator with Box-Muller noise, so the
//! same seed gives the same bytes on every machine.

use std::fmt::Write as _;

use nalgebra::Vector3;

/// Knuth's MMIX linear congruential generator.
#[derive(Clone, Debug)]
pub(crate) struct Lcg(u64);

impl Lcg {
    pub(crate) fn new(seed: u64) -> Lcg {
        Lcg(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    /// Uniform in [0, 1).
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box-Muller).
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// The thesis's ten test points (Table 3.1 as in its spreadsheet), mm.
pub const THESIS_POINTS: [[f64; 3]; 10] = [
    [-200.0, -200.0, 200.0],
    [-200.0, 200.0, 200.0],
    [200.0, 0.0, 200.0],
    [-200.0, -200.0, 300.0],
    [200.0, -200.0, 300.0],
    [200.0, 200.0, 300.0],
    [-200.0, 200.0, 300.0],
    [200.0, 200.0, 400.0],
    [200.0, -200.0, 400.0],
    [-200.0, 0.0, 400.0],
];

/// Pose sample files: `(commanded, measured, before)`. Each point gets a systematic error of
/// up to `bias` mm per axis and visits scattered by `noise` mm; angles are commanded near
/// rx = 180° so that measured ones wrap across ±180°. `before` has four times the bias.
pub fn pose_csvs(seed: u64, cycles: usize, bias: f64, noise: f64) -> (String, String, String) {
    let mut rng = Lcg::new(seed);
    let mut commanded = String::from("point,x,y,z,rx,ry,rz\n");
    let mut biases = Vec::new();
    for (i, p) in THESIS_POINTS.iter().enumerate() {
        let angles = [180.0, 0.0, -90.0 + 10.0 * i as f64];
        let _ = writeln!(
            commanded,
            "P{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3}",
            i + 1,
            p[0],
            p[1],
            p[2],
            angles[0],
            angles[1],
            angles[2]
        );
        let b: [f64; 6] = std::array::from_fn(|k| {
            let scale = if k < 3 { bias } else { 0.02 };
            scale * (2.0 * rng.uniform() - 1.0)
        });
        biases.push((p, angles, b));
    }
    let visits = |factor: f64, rng: &mut Lcg| {
        let mut out = String::from("point,cycle,x,y,z,rx,ry,rz\n");
        for cycle in 1..=cycles {
            for (i, (p, a, b)) in biases.iter().enumerate() {
                let x: [f64; 6] = std::array::from_fn(|k| {
                    let base = if k < 3 { p[k] } else { a[k - 3] };
                    let scatter = if k < 3 { noise } else { 0.005 };
                    base + factor * b[k] + scatter * rng.normal()
                });
                let rx = crate::geometry::wrap_deg(x[3]);
                let _ = writeln!(
                    out,
                    "P{},{cycle},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}",
                    i + 1,
                    x[0],
                    x[1],
                    x[2],
                    rx,
                    x[4],
                    x[5]
                );
            }
        }
        out
    };
    let measured = visits(1.0, &mut rng);
    let before = visits(4.0, &mut rng);
    (commanded, measured, before)
}

/// A trapezoidal speed profile over `length` mm: `(duration, position at t)`.
fn trapezoid(length: f64, speed: f64, accel: f64) -> (f64, impl Fn(f64) -> f64) {
    let ta = (speed / accel).min((length / accel).sqrt());
    let v = accel * ta;
    let sa = 0.5 * accel * ta * ta;
    let tc = (length - 2.0 * sa).max(0.0) / v;
    let total = 2.0 * ta + tc;
    let at = move |t: f64| {
        if t <= 0.0 {
            0.0
        } else if t < ta {
            0.5 * accel * t * t
        } else if t < ta + tc {
            sa + v * (t - ta)
        } else if t < total {
            let r = total - t;
            length - 0.5 * accel * r * r
        } else {
            length
        }
    };
    (total, at)
}

/// Settings of a simulated straight-line recording.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineSimulation {
    /// Start of the line, mm.
    pub start: [f64; 3],
    /// End of the line, mm.
    pub end: [f64; 3],
    /// Travel speed, mm/s.
    pub speed: f64,
    /// Acceleration at the start and deceleration at the end, mm/s².
    pub accel: f64,
    /// Sampling rate in Hz.
    pub rate: f64,
    /// Standing time at each stop, s.
    pub dwell: f64,
    /// Constant offset of the path, mm, perpendicular to the line.
    pub offset: [f64; 3],
    /// Amplitude of the start overshoot (decays over 60 mm of travel), mm.
    pub overshoot: f64,
    /// Standard deviation per axis of the per-run offset scatter, mm.
    pub run_scatter: f64,
    /// Standard deviation per axis of the per-sample noise, mm.
    pub noise: f64,
}

impl Default for LineSimulation {
    fn default() -> LineSimulation {
        LineSimulation {
            start: [1200.0, -540.0, 900.0],
            end: [2280.0, -540.0, 900.0],
            speed: 600.0,
            accel: 1500.0,
            rate: 100.0,
            dwell: 0.3,
            offset: [0.0, 0.25, -0.15],
            overshoot: 0.8,
            run_scatter: 0.02,
            noise: 0.01,
        }
    }
}

/// Straight-line sample files: `(commanded, by cycle, continuous)`. `by cycle` has `cycles`
/// forward runs with a `cycle` column; `continuous` is one recording of forward and backward
/// runs (`cycles` forward, one backward between each two) without it.
pub fn line_csvs(seed: u64, sim: &LineSimulation, cycles: usize) -> (String, String, String) {
    let mut rng = Lcg::new(seed);
    let a = Vector3::from(sim.start);
    let b = Vector3::from(sim.end);
    let length = (b - a).norm();
    let u = (b - a) / length;
    let offset = Vector3::from(sim.offset);
    let side = {
        let z = Vector3::z();
        let n = u.cross(&z);
        if n.norm() > 1e-6 {
            n.normalize()
        } else {
            u.cross(&Vector3::x()).normalize()
        }
    };
    let (duration, at) = trapezoid(length, sim.speed, sim.accel);
    let dt = 1.0 / sim.rate;
    let commanded = format!(
        "point,x,y,z,rx,ry,rz\nstart,{:.3},{:.3},{:.3},180.000,0.000,90.000\nend,{:.3},{:.3},{:.3},180.000,0.000,90.000\n",
        a.x, a.y, a.z, b.x, b.y, b.z
    );
    // One run: standing, moving, standing; `forward` from a to b.
    let run = |rng: &mut Lcg, forward: bool, t0: f64, out: &mut String, label: Option<usize>| {
        let scatter = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sim.run_scatter;
        let steps = ((2.0 * sim.dwell + duration) * sim.rate).round() as usize;
        for k in 0..steps {
            let t = k as f64 * dt;
            let travelled = at(t - sim.dwell);
            let s = if forward {
                travelled
            } else {
                length - travelled
            };
            let bend = sim.overshoot * (-travelled / 60.0).exp() * (travelled / 10.0).min(1.0);
            let lateral = offset - u * offset.dot(&u) + side * bend + scatter;
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sim.noise;
            let p = a + u * s + lateral + noise;
            let rx = crate::geometry::wrap_deg(180.0 + 0.02 * rng.normal() + 0.01);
            let ry = 0.03 + 0.01 * rng.normal();
            let rz = 90.0 - 0.02 + 0.01 * rng.normal();
            if let Some(c) = label {
                let _ = write!(out, "{c},");
            }
            let _ = writeln!(
                out,
                "{:.3},{:.4},{:.4},{:.4},{rx:.4},{ry:.4},{rz:.4}",
                t0 + t,
                p.x,
                p.y,
                p.z
            );
        }
        t0 + steps as f64 * dt
    };
    let mut by_cycle = String::from("cycle,t,x,y,z,rx,ry,rz\n");
    for c in 1..=cycles {
        run(&mut rng, true, 0.0, &mut by_cycle, Some(c));
    }
    let mut continuous = String::from("t,x,y,z,rx,ry,rz\n");
    let mut t0 = 0.0;
    for c in 0..cycles {
        if c > 0 {
            t0 = run(&mut rng, false, t0, &mut continuous, None);
        }
        t0 = run(&mut rng, true, t0, &mut continuous, None);
    }
    (commanded, by_cycle, continuous)
}

/// A 90° edge (thesis §3.4.2, "swing over"): commanded `(commanded, by cycle)` files of
/// `cycles` runs along two legs of 400 and 300 mm at 400 mm/s without a stop at the corner. The
/// robot cuts the corner (the path averaged over ±10 mm) and swings over behind it (0.4 mm
/// outward, decaying over 40 mm); 0.02 mm run scatter, 0.01 mm noise, 100 Hz.
pub fn edge_csvs(seed: u64, cycles: usize) -> (String, String) {
    let mut rng = Lcg::new(seed);
    let v = [
        Vector3::new(1000.0, 0.0, 500.0),
        Vector3::new(1400.0, 0.0, 500.0),
        Vector3::new(1400.0, 300.0, 500.0),
    ];
    let path = match super::path::Polyline::new(v.to_vec(), None) {
        Ok(p) => p,
        Err(_) => return (String::new(), String::new()),
    };
    let length = path.length();
    let corner = 400.0;
    let (duration, at) = trapezoid(length, 400.0, 2000.0);
    let (rate, dwell) = (100.0, 0.3);
    let mut commanded = String::from("point,x,y,z\n");
    for (name, p) in ["start", "corner", "end"].iter().zip(&v) {
        let _ = writeln!(commanded, "{name},{:.3},{:.3},{:.3}", p.x, p.y, p.z);
    }
    let mut out = String::from("cycle,t,x,y,z\n");
    for c in 1..=cycles {
        let scatter = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.02;
        let steps = ((2.0 * dwell + duration) * rate).round() as usize;
        for k in 0..steps {
            let t = k as f64 / rate;
            let s = at(t - dwell);
            // The window shrinks towards the ends, so the runs start and stop on the path.
            let h = 10.0f64.min(s).min(length - s).max(0.0);
            let cut = (-5..=5)
                .map(|j| path.at((s + h * j as f64 / 5.0).clamp(0.0, length)).0)
                .sum::<Vector3<f64>>()
                / 11.0;
            let behind = s - corner;
            let swing = if behind > 0.0 {
                0.4 * (-behind / 40.0).exp() * (behind / 8.0).min(1.0)
            } else {
                0.0
            };
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.01;
            let p = cut + Vector3::x() * swing + scatter + noise;
            let _ = writeln!(out, "{c},{t:.3},{:.4},{:.4},{:.4}", p.x, p.y, p.z);
        }
    }
    (commanded, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lcg_is_deterministic_and_roughly_normal() {
        let mut a = Lcg::new(7);
        let mut b = Lcg::new(7);
        let xs: Vec<f64> = (0..20000).map(|_| a.normal()).collect();
        assert!(
            xs.iter()
                .zip((0..20000).map(|_| b.normal()))
                .all(|(x, y)| *x == y)
        );
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }

    #[test]
    fn trapezoid_reaches_the_end_at_speed() {
        let (total, at) = trapezoid(1080.0, 600.0, 1500.0);
        assert!((total - (1080.0 / 600.0 + 600.0 / 1500.0)).abs() < 1e-12);
        assert!((at(total) - 1080.0).abs() < 1e-9);
        assert!((at(1.0) - at(0.99) - 6.0).abs() < 1e-9);
    }
}
