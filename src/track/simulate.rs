//! A deterministic simulator of a deformed linear track and of laser-tracker measurements on it,
//! for tests, samples and end-to-end checks (truth → measurements → identify → fit → profile →
//! corrected program → physical TCP error against the truth).
//!
//! How to compare a fitted profile with the truth: the profile's deviations are taken from the
//! *fitted* nominal (the regression line), not from the truth's straight line, so compare base
//! frames, `profile.base_frame(s)` (= `N(s)·D(s)`) against [`TrackTruth::base_frame`], both in
//! the measurement frame. A controller set up with the fitted nominal (`track fit` prints the
//! base at skid 0 and the track direction) puts the real robot base at
//! `truth.base_frame(s)`, so a program corrected with the profile reaches its target to within
//! `|profile.base_frame(s)⁻¹ · truth.base_frame(s)|`.
//!
//! Everything is seeded: the same inputs give the same numbers on every platform (splitmix64,
//! Box-Muller, no external RNG).

use std::f64::consts::PI;
use std::fmt::Write as _;

use nalgebra::{Point3, Translation3, Vector3};

use crate::geometry::{Pose, pose_to_xyz_deg, pose_xyz_deg};

/// splitmix64 with Box-Muller normals: tiny, portable, deterministic.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator whose sequence is fixed by `seed`, so simulated data sets repeat.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64 { state: seed }
    }

    /// The next 64 uniform bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1): never 0, so `ln` is safe.
    pub fn next_f64(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal (Box-Muller; the second value is discarded for simplicity).
    pub fn gaussian(&mut self) -> f64 {
        let u1 = self.next_f64();
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// A smooth deformation of the rails over the track length `L`, as a deviation from the
/// straight line. "Along" is the track axis, "sideways" is horizontal across it (`z × axis` in
/// the robot base), "vertical" is the base z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deformation {
    /// Vertical sag at mid-track, mm: `vertical = -sag·sin(πs/L)`.
    pub sag_mm: f64,
    /// Sideways bow at mid-track, mm: `sideways = bow·sin(πs/L)`.
    pub bow_mm: f64,
    /// Amplitude of a rail waviness, sideways and vertical, mm.
    pub wave_mm: f64,
    /// Wavelength of that waviness, mm.
    pub wave_length_mm: f64,
    /// Twist about the track axis, degrees: `twist·sin(2πs/L)`.
    pub twist_deg: f64,
    /// Relative gear error: the skid travels `(1 + gear_error)·s` for a commanded `s`.
    pub gear_error: f64,
}

impl Deformation {
    /// No deformation at all.
    pub fn none() -> Deformation {
        Deformation {
            sag_mm: 0.0,
            bow_mm: 0.0,
            wave_mm: 0.0,
            wave_length_mm: 1000.0,
            twist_deg: 0.0,
            gear_error: 0.0,
        }
    }
}

/// The true track: where the robot base really is at every skid position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackTruth {
    /// The straight track's base frame at skid 0, in the measurement frame (tracker or world).
    pub start: Pose,
    /// Unit direction the base moves per commanded mm, in the robot base frame (robots on a
    /// track usually face across it, e.g. `[0, -1, 0]`). Must be horizontal (no z component)
    /// for "sideways" and "vertical" to mean what they say.
    pub axis_in_base: Vector3<f64>,
    /// Track length `L`, mm.
    pub length_mm: f64,
    /// How the rails bend along the track.
    pub deformation: Deformation,
}

impl TrackTruth {
    /// Robot `r1` of the samples, measured in the world frame of `samples/cell.toml`: base at
    /// skid 0 at (0, -3500, 0) turned 90° about z, so the track (world +x) runs along base -y.
    /// An 8 m track with 2.5 mm sag, 1.5 mm sideways bow, 0.08 mm waviness of 2 m wavelength,
    /// 0.03° twist, gear error -1.5e-4 (1.2 mm short over 8 m).
    pub fn sample_r1() -> TrackTruth {
        TrackTruth {
            start: pose_xyz_deg(0.0, -3500.0, 0.0, 0.0, 0.0, 90.0),
            axis_in_base: Vector3::new(0.0, -1.0, 0.0),
            length_mm: 8000.0,
            deformation: Deformation {
                sag_mm: 2.5,
                bow_mm: 1.5,
                wave_mm: 0.08,
                wave_length_mm: 2000.0,
                twist_deg: 0.03,
                gear_error: -1.5e-4,
            },
        }
    }

    /// Robot `r2` of the samples, the opposite robot: base at skid 0 at (0, -201.5, 0) turned
    /// -90° about z (track along base +y). 1.2 mm sag, bow -0.9 mm, 0.05 mm waviness of 2.5 m
    /// wavelength, 0.018° twist, gear error +0.8e-4.
    pub fn sample_r2() -> TrackTruth {
        TrackTruth {
            start: pose_xyz_deg(0.0, -201.5, 0.0, 0.0, 0.0, -90.0),
            axis_in_base: Vector3::new(0.0, 1.0, 0.0),
            length_mm: 8000.0,
            deformation: Deformation {
                sag_mm: 1.2,
                bow_mm: -0.9,
                wave_mm: 0.05,
                wave_length_mm: 2500.0,
                twist_deg: 0.018,
                gear_error: 0.8e-4,
            },
        }
    }

    /// A perfectly straight track along base +x (no deformation, no gear error).
    pub fn straight(start: Pose, length_mm: f64) -> TrackTruth {
        TrackTruth {
            start,
            axis_in_base: Vector3::x(),
            length_mm,
            deformation: Deformation::none(),
        }
    }

    /// A randomly deformed track for statistical tests: an `length_mm` track along base -y
    /// starting at `start`, with sag 0.5-3 mm, bow ±2 mm, waviness 0.02-0.1 mm of 1.5-4 m
    /// wavelength, twist ±0.04° and gear error ±2e-4, all drawn from `seed`.
    pub fn random(start: Pose, length_mm: f64, seed: u64) -> TrackTruth {
        let mut rng = SplitMix64::new(seed);
        let mut between = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        TrackTruth {
            start,
            axis_in_base: Vector3::new(0.0, -1.0, 0.0),
            length_mm,
            deformation: Deformation {
                sag_mm: between(0.5, 3.0),
                bow_mm: between(-2.0, 2.0),
                wave_mm: between(0.02, 0.1),
                wave_length_mm: between(1500.0, 4000.0),
                twist_deg: between(-0.04, 0.04),
                gear_error: between(-2e-4, 2e-4),
            },
        }
    }

    /// The unit track axis in the base frame (`x` if `axis_in_base` is degenerate).
    fn axis(&self) -> Vector3<f64> {
        self.axis_in_base
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::x)
    }

    /// The straight, undeformed base frame at commanded skid `s`.
    pub fn straight_frame(&self, skid: f64) -> Pose {
        let t = self.axis() * skid;
        self.start * Pose::translation(t.x, t.y, t.z)
    }

    /// `[along, sideways, vertical, twist, pitch, yaw]` (mm, degrees) of the deformation at `s`,
    /// in track coordinates. Pitch and yaw follow the rails' slope, as a carriage on them does.
    pub fn track_deformation(&self, skid: f64) -> [f64; 6] {
        let d = &self.deformation;
        let l = self.length_mm.max(1.0);
        let k = PI / l;
        let wl = d.wave_length_mm.max(1.0);
        let w = 2.0 * PI / wl;
        let side = d.bow_mm * (k * skid).sin() + d.wave_mm * (w * skid + 0.7).sin();
        let vert = -d.sag_mm * (k * skid).sin() + d.wave_mm * (w * skid + 2.1).sin();
        let side_ds = d.bow_mm * k * (k * skid).cos() + d.wave_mm * w * (w * skid + 0.7).cos();
        let vert_ds = -d.sag_mm * k * (k * skid).cos() + d.wave_mm * w * (w * skid + 2.1).cos();
        let twist = d.twist_deg * (2.0 * k * skid).sin();
        // A positive rotation about the sideways axis tips the track axis down; about z it
        // turns the axis towards the sideways direction.
        let pitch = -vert_ds.atan().to_degrees();
        let yaw = side_ds.atan().to_degrees();
        [d.gear_error * skid, side, vert, twist, pitch, yaw]
    }

    /// The true deviation from the straight frame, in the base frame at that skid.
    pub fn deviation(&self, skid: f64) -> Pose {
        let [along, side, vert, twist, pitch, yaw] = self.track_deformation(skid);
        let a = self.axis();
        let sideways = Vector3::z().cross(&a);
        let t = a * along + sideways * side + Vector3::z() * vert;
        let omega = (a * twist + sideways * pitch + Vector3::z() * yaw) * (PI / 180.0);
        Pose::from_parts(
            Translation3::from(t),
            nalgebra::UnitQuaternion::from_scaled_axis(omega),
        )
    }

    /// `[dx, dy, dz, rx, ry, rz]` (mm, degrees) of [`TrackTruth::deviation`].
    pub fn deviation_components(&self, skid: f64) -> [f64; 6] {
        pose_to_xyz_deg(&self.deviation(skid))
    }

    /// The true robot base at commanded skid `s`, in the measurement frame.
    pub fn base_frame(&self, skid: f64) -> Pose {
        self.straight_frame(skid) * self.deviation(skid)
    }
}

/// Ten TCP points in the robot base frame, spread over a typical spot-welding workspace
/// (0.8 to 1.8 m in front of the robot, ±0.7 m sideways, 0.3 to 1.6 m high).
pub fn sample_tcp_points() -> Vec<Point3<f64>> {
    [
        [1200.0, 0.0, 900.0],
        [1500.0, 600.0, 1200.0],
        [1500.0, -600.0, 1200.0],
        [900.0, 500.0, 400.0],
        [900.0, -500.0, 400.0],
        [1800.0, 200.0, 600.0],
        [1800.0, -250.0, 1500.0],
        [1000.0, 700.0, 1600.0],
        [1100.0, -700.0, 300.0],
        [1650.0, 50.0, 350.0],
    ]
    .into_iter()
    .map(Point3::from)
    .collect()
}

/// One row of `measurements.csv` (docs/design.md §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasurementRow {
    /// The commanded track position, mm.
    pub skid: f64,
    /// 1-based point number.
    pub point: u32,
    /// The TCP as the controller reports it in its base frame, mm.
    pub robot: [f64; 3],
    /// The TCP as the tracker measured it, mm.
    pub meas: [f64; 3],
}

/// The tracker measures each robot point at each skid: `meas = base_frame(s)·robot + noise`,
/// with independent Gaussian noise of `noise_mm` (standard deviation per axis).
pub fn simulate_measurements(
    truth: &TrackTruth,
    skids: &[f64],
    points: &[Point3<f64>],
    noise_mm: f64,
    seed: u64,
) -> Vec<MeasurementRow> {
    let mut rng = SplitMix64::new(seed);
    let mut rows = Vec::with_capacity(skids.len() * points.len());
    for &skid in skids {
        let base = truth.base_frame(skid);
        for (j, p) in points.iter().enumerate() {
            let q = base * p;
            let noise = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_mm;
            let m = q.coords + noise;
            rows.push(MeasurementRow {
                skid,
                point: j as u32 + 1,
                robot: [p.x, p.y, p.z],
                meas: [m.x, m.y, m.z],
            });
        }
    }
    rows
}

/// `measurements.csv` text: robot values with 3 decimals (as a controller shows them), tracker
/// values with 4.
pub fn measurements_csv(rows: &[MeasurementRow]) -> String {
    let mut out = String::from("skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z\n");
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{:.3},{:.3},{:.3},{:.4},{:.4},{:.4}",
            r.skid, r.point, r.robot[0], r.robot[1], r.robot[2], r.meas[0], r.meas[1], r.meas[2]
        );
    }
    out
}

/// A continuous scan: a reflector fixed on the carriage at `reflector` (robot base frame) is
/// measured every `step_mm` from `from` to `to`, with Gaussian noise `noise_mm` per axis.
/// Rows are `[skid, x, y, z]` in the measurement frame.
pub fn simulate_scan(
    truth: &TrackTruth,
    reflector: Point3<f64>,
    from: f64,
    to: f64,
    step_mm: f64,
    noise_mm: f64,
    seed: u64,
) -> Vec<[f64; 4]> {
    let mut rng = SplitMix64::new(seed);
    let mut rows = Vec::new();
    if step_mm.is_nan() || step_mm <= 0.0 || !from.is_finite() || !to.is_finite() {
        return rows;
    }
    let n = ((to - from) / step_mm).floor().max(0.0) as usize;
    for i in 0..=n {
        let s = from + i as f64 * step_mm;
        let q = truth.base_frame(s) * reflector;
        let noise = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_mm;
        let m = q.coords + noise;
        rows.push([s, m.x, m.y, m.z]);
    }
    rows
}

/// `scan.csv` text (`skid,x,y,z`, 4 decimals).
pub fn scan_csv(rows: &[[f64; 4]]) -> String {
    let mut out = String::from("skid,x,y,z\n");
    for [s, x, y, z] in rows {
        let _ = writeln!(out, "{s},{x:.4},{y:.4},{z:.4}");
    }
    out
}

/// One row of a work-object touch-up file (`marks.csv`): the TCP on fixture mark `mark` at
/// skid `skid`, as the controller reports it in its base frame, and the mark's CAD coordinates
/// in the work object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkRow {
    /// The fixture mark number.
    pub mark: u32,
    /// The commanded track position, mm.
    pub skid: f64,
    /// The TCP on the mark, in the robot base frame, mm.
    pub robot: [f64; 3],
    /// The mark in the work object (CAD), mm.
    pub cad: [f64; 3],
}

/// The robot touches fixture marks: mark `j` (CAD coordinates `cad[j]` in work object `wobj`,
/// world) at skid `skids[j]`; the controller reports `truth.base_frame(s)⁻¹·wobj·cad` plus
/// Gaussian noise `noise_mm` per axis (robot repeatability and the touch).
pub fn simulate_marks(
    truth: &TrackTruth,
    wobj: &Pose,
    cad: &[Point3<f64>],
    skids: &[f64],
    noise_mm: f64,
    seed: u64,
) -> Vec<MarkRow> {
    let mut rng = SplitMix64::new(seed);
    cad.iter()
        .zip(skids)
        .enumerate()
        .map(|(j, (c, &skid))| {
            let p = truth.base_frame(skid).inverse() * (wobj * c);
            let n = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_mm;
            MarkRow {
                mark: j as u32 + 1,
                skid,
                robot: [p.x + n.x, p.y + n.y, p.z + n.z],
                cad: [c.x, c.y, c.z],
            }
        })
        .collect()
}

/// `marks.csv` text (`mark,skid,robot_x,robot_y,robot_z,cad_x,cad_y,cad_z`; robot values with 3
/// decimals as a controller shows them, CAD with 3).
pub fn marks_csv(rows: &[MarkRow]) -> String {
    let mut out = String::from("mark,skid,robot_x,robot_y,robot_z,cad_x,cad_y,cad_z\n");
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3}",
            r.mark, r.skid, r.robot[0], r.robot[1], r.robot[2], r.cad[0], r.cad[1], r.cad[2]
        );
    }
    out
}

/// Flange poses (in the robot base) of a TCP pivot: the TCP `tcp` (flange frame) held on the
/// fixed point `point` (base frame) in `count` orientations tilted up to ±35° about a mean tool
/// direction pointing down, with Gaussian noise `noise_mm` on each flange position.
pub fn simulate_pivot(
    tcp: &Vector3<f64>,
    point: &Point3<f64>,
    count: usize,
    noise_mm: f64,
    seed: u64,
) -> Vec<Pose> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|k| {
            let turn = 360.0 * k as f64 / count.max(1) as f64;
            let tilt = 15.0 + 20.0 * rng.next_f64();
            // Tool z points down (rx 180), turned about base z and tilted.
            let r = crate::geometry::xyz_deg(
                180.0 + tilt * turn.to_radians().cos(),
                tilt * turn.to_radians().sin(),
                turn,
            );
            let n = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_mm;
            let p = point.coords - r * tcp + n;
            Pose::from_parts(Translation3::from(p), r)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prng_is_deterministic_and_normal() {
        let mut a = SplitMix64::new(42);
        let mut b = SplitMix64::new(42);
        assert_eq!(a.next_u64(), b.next_u64());
        let n = 20000;
        let xs: Vec<f64> = (0..n).map(|_| a.gaussian()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
    }

    #[test]
    fn truth_is_straight_at_the_start() {
        let t = TrackTruth::sample_r1();
        // At s = 0 only the waviness and the slope rotations remain: a few hundredths of a mm.
        let d = t.deviation_components(0.0);
        assert!(
            d[0].abs() < 0.1 && d[1].abs() < 1e-12 && d[2].abs() < 0.1,
            "{d:?}"
        );
        // Mid-track: -2.5 mm sag, and the 1.5 mm bow sideways (z × (-y) = +x in the base).
        let mid = t.deviation_components(4000.0);
        assert!((mid[2] + 2.5).abs() < 0.1, "{mid:?}");
        assert!((mid[0] - 1.5).abs() < 0.1, "{mid:?}");
        // The gear error moves along the track axis, base -y: -1.2 mm at 8 m.
        let end = t.deviation_components(8000.0);
        assert!((end[1] - 1.2).abs() < 0.01, "{end:?}");
    }
}
