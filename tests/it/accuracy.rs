//! Accuracy analysis: ISO 9283 pose and path figures against the thesis's worked numbers and
//! against independent implementations written here, the samples, the CLI and the figures.

use nalgebra::Vector3;
use proptest::prelude::*;
use trackfix::accuracy::simulate::{
    LineSimulation, THESIS_POINTS, edge_csvs, line_csvs, pose_csvs,
};
use trackfix::accuracy::{
    CommandedPose, PathOptions, Polyline, Recording, Sample, Visit, compare, path_accuracy,
    plane_crossing, pose_accuracy,
};

use crate::support::{root, trackfix};

const POSE: [&str; 2] = [
    "samples/accuracy/pose_commanded.csv",
    "samples/accuracy/pose_measured.csv",
];
const LINE: &str = "samples/accuracy/line_commanded.csv";

const POSE_SEED: u64 = 9283;
const LINE_SEED: u64 = 5101;
const EDGE_SEED: u64 = 3406;

/// The sample files and how they are made: `TRACKFIX_WRITE_SAMPLES=1` rewrites them.
fn sample_files() -> Vec<(&'static str, String)> {
    let (commanded, measured, before) = pose_csvs(POSE_SEED, 10, 0.3, 0.006);
    let (line, cycles, continuous) = line_csvs(LINE_SEED, &LineSimulation::default(), 3);
    let edge = edge_csvs(EDGE_SEED, 3);
    vec![
        ("pose_commanded.csv", commanded),
        ("pose_measured.csv", measured),
        ("pose_before.csv", before),
        ("line_commanded.csv", line),
        ("line_cycles.csv", cycles),
        ("line_continuous.csv", continuous),
        ("edge_commanded.csv", edge.0),
        ("edge_cycles.csv", edge.1),
    ]
}

#[test]
fn samples_are_reproducible() {
    let dir = root().join("samples/accuracy");
    for (name, text) in sample_files() {
        let path = dir.join(name);
        if std::env::var_os("TRACKFIX_WRITE_SAMPLES").is_some() {
            std::fs::write(&path, &text).unwrap();
        }
        let on_disk = std::fs::read_to_string(&path).unwrap();
        assert_same_table(name, &on_disk, &text);
    }
}

/// Equal text, except that a number may differ by one unit of its last written digit: the
/// generator's noise goes through `ln` and `cos`, whose last bit may differ between platforms.
fn assert_same_table(name: &str, on_disk: &str, generated: &str) {
    let (a, b): (Vec<&str>, Vec<&str>) = (on_disk.lines().collect(), generated.lines().collect());
    assert_eq!(a.len(), b.len(), "{name}: line count");
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        let split = |l: &str| l.split([',', ';']).map(str::to_owned).collect::<Vec<_>>();
        let (fx, fy) = (split(x), split(y));
        assert_eq!(fx.len(), fy.len(), "{name}:{}", k + 1);
        for (u, v) in fx.iter().zip(&fy) {
            if u == v {
                continue;
            }
            let num = |t: &str| t.replace(',', ".").parse::<f64>().ok();
            let (Some(p), Some(q)) = (num(u), num(v)) else {
                panic!("{name}:{}: `{u}` vs `{v}`", k + 1);
            };
            let unit = 10f64.powi(-(u.rsplit(['.', ',']).next().map_or(0, str::len) as i32));
            assert!((p - q).abs() <= 1.5 * unit, "{name}:{}: {u} vs {v}", k + 1);
        }
    }
}

/// The pose measurement as a tracker's export: `;` between fields, decimal commas, quoted
/// names, its own column names and a column the analysis does not use.
fn as_tracker_export(measured: &str) -> String {
    let mut out = String::from("\"Name\";\"Run\";\"X [mm]\";\"Y [mm]\";\"Z [mm]\";\"Temp\"\n");
    for line in measured.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        out.push_str(&format!(
            "\"{}\";{};{};{};{};21,4\n",
            f[0],
            f[1],
            f[2].replace('.', ","),
            f[3].replace('.', ","),
            f[4].replace('.', ",")
        ));
    }
    out
}

#[test]
fn tracker_export_sample_is_reproducible() {
    let (_, measured, _) = pose_csvs(POSE_SEED, 10, 0.3, 0.006);
    let path = root().join("samples/accuracy/pose_export.csv");
    let text = as_tracker_export(&measured);
    if std::env::var_os("TRACKFIX_WRITE_SAMPLES").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    assert_same_table(
        "pose_export.csv",
        &std::fs::read_to_string(&path).unwrap(),
        &text,
    );
}

// ---- independent implementations -------------------------------------------------------

/// Degrees between two angles the other way than the code (atan2 of sine and cosine, not a
/// modulo).
fn naive_angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).to_radians();
    d.sin().atan2(d.cos()).to_degrees()
}

fn naive_mean(xs: &[f64]) -> f64 {
    xs.iter().sum::<f64>() / xs.len() as f64
}

/// Two-pass sample standard deviation.
fn naive_std(xs: &[f64]) -> f64 {
    let m = naive_mean(xs);
    (xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
}

#[derive(Debug)]
struct NaivePose {
    ap: f64,
    ap_xyz: [f64; 3],
    ap_abc: [f64; 3],
    rp: f64,
    rp_abc: [f64; 3],
    max: f64,
}

/// ISO 9283 pose figures by the formulas, one loop per equation.
fn naive_pose(c: &[f64; 6], visits: &[[f64; 6]]) -> NaivePose {
    let col = |k: usize| visits.iter().map(|v| v[k]).collect::<Vec<f64>>();
    let mean: Vec<f64> = (0..3).map(|k| naive_mean(&col(k))).collect();
    let ap_xyz = [mean[0] - c[0], mean[1] - c[1], mean[2] - c[2]];
    let ap = (ap_xyz[0].powi(2) + ap_xyz[1].powi(2) + ap_xyz[2].powi(2)).sqrt();
    let l: Vec<f64> = visits
        .iter()
        .map(|v| {
            ((v[0] - mean[0]).powi(2) + (v[1] - mean[1]).powi(2) + (v[2] - mean[2]).powi(2)).sqrt()
        })
        .collect();
    let rp = naive_mean(&l) + 3.0 * naive_std(&l);
    let dev = |k: usize| {
        visits
            .iter()
            .map(|v| naive_angle_diff(v[k], c[k]))
            .collect::<Vec<f64>>()
    };
    let ap_abc = [3, 4, 5].map(|k| naive_mean(&dev(k)));
    let rp_abc = [3, 4, 5].map(|k| 3.0 * naive_std(&dev(k)));
    let max = visits
        .iter()
        .map(|v| ((v[0] - c[0]).powi(2) + (v[1] - c[1]).powi(2) + (v[2] - c[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    NaivePose {
        ap,
        ap_xyz,
        ap_abc,
        rp,
        rp_abc,
        max,
    }
}

/// Parses the sample CSV text (the test's own reader: split at commas).
fn parse_rows(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

fn nums(row: &[String], from: usize) -> Vec<f64> {
    row[from..].iter().map(|f| f.parse().unwrap()).collect()
}

fn poses_from(commanded: &str, measured: &str) -> (Vec<CommandedPose>, Vec<Visit>) {
    let cmd = parse_rows(commanded)
        .iter()
        .map(|r| {
            let v = nums(r, 1);
            CommandedPose {
                name: r[0].clone(),
                line: 0,
                position: Vector3::new(v[0], v[1], v[2]),
                angles: Some([v[3], v[4], v[5]]),
            }
        })
        .collect();
    let visits = parse_rows(measured)
        .iter()
        .map(|r| {
            let v = nums(r, 2);
            Visit {
                point: r[0].clone(),
                cycle: Some(r[1].clone()),
                line: 0,
                position: Vector3::new(v[0], v[1], v[2]),
                angles: Some([v[3], v[4], v[5]]),
            }
        })
        .collect();
    (cmd, visits)
}

#[test]
fn table_3_3_iso_column_from_the_table_3_2_means() {
    // Reference: the thesis's spreadsheet, ../shared/reference/README.md. Five visits per point
    // whose mean is the printed mean (symmetric offsets around it, so RP is not tested here).
    let means = [
        [-199.9586, -200.0634, 200.003],
        [-199.646, 199.705, 200.0458],
        [199.974, 0.0212, 199.9568],
        [-200.0638, -199.954, 300.006],
        [199.8968, -199.9884, 299.8866],
        [199.9466, 200.0672, 300.0198],
        [-199.798, 199.8288, 300.0426],
        [199.8894, 200.1602, 400.0348],
        [199.8158, -199.9244, 399.8974],
        [-200.0514, 0.131, 400.0676],
    ];
    let offsets = [
        [0.004, -0.003, 0.002],
        [-0.004, 0.003, -0.002],
        [0.002, 0.005, -0.001],
        [-0.002, -0.005, 0.001],
        [0.0, 0.0, 0.0],
    ];
    let commanded: Vec<CommandedPose> = THESIS_POINTS
        .iter()
        .enumerate()
        .map(|(i, p)| CommandedPose {
            name: format!("P{}", i + 1),
            line: 0,
            position: Vector3::from(*p),
            angles: None,
        })
        .collect();
    let mut visits = Vec::new();
    for (i, m) in means.iter().enumerate() {
        for (j, o) in offsets.iter().enumerate() {
            visits.push(Visit {
                point: format!("P{}", i + 1),
                cycle: Some(j.to_string()),
                line: 0,
                position: Vector3::new(m[0] + o[0], m[1] + o[1], m[2] + o[2]),
                angles: None,
            });
        }
    }
    let r = pose_accuracy(&commanded, &visits).unwrap();
    let iso: Vec<String> = r.points.iter().map(|p| format!("{:.2}", p.ap)).collect();
    assert_eq!(
        iso,
        [
            "0.08", "0.46", "0.05", "0.08", "0.15", "0.09", "0.27", "0.20", "0.22", "0.16"
        ]
    );
    assert!((r.points[0].ap - 0.0758).abs() < 5e-5, "{}", r.points[0].ap);
    assert!((r.points[1].ap - 0.4631).abs() < 5e-5, "{}", r.points[1].ap);
    assert_eq!(r.summary.worst_ap_point, "P2");
    // Without angle columns the orientation figures are absent, not zero.
    assert!(
        r.points
            .iter()
            .all(|p| p.ap_a.is_none() && p.rp_a.is_none())
    );
    let json = serde_json::to_value(&r).unwrap();
    assert!(json["points"][0]["APa"].is_null() && json["summary"]["RPc"].is_null());
}

#[test]
fn pose_figures_equal_the_naive_formulas_on_generated_data() {
    // Large scatter and angles commanded at rx = 180°: the visits wrap across ±180°.
    for seed in [1u64, 2, 3] {
        let (commanded, measured, _) = pose_csvs(seed, 7, 0.5, 0.05);
        assert!(measured.contains(",-179.9") && measured.contains(",179.9"));
        let (cmd, visits) = poses_from(&commanded, &measured);
        let r = pose_accuracy(&cmd, &visits).unwrap();
        let crows = parse_rows(&commanded);
        let mrows = parse_rows(&measured);
        for (p, crow) in r.points.iter().zip(&crows) {
            let c: Vec<f64> = nums(crow, 1);
            let c: [f64; 6] = c.try_into().unwrap();
            let vs: Vec<[f64; 6]> = mrows
                .iter()
                .filter(|m| m[0] == crow[0])
                .map(|m| nums(m, 2).try_into().unwrap())
                .collect();
            let n = naive_pose(&c, &vs);
            let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
            assert!(close(p.ap, n.ap), "{} AP {} {}", p.point, p.ap, n.ap);
            assert!(close(p.ap_x, n.ap_xyz[0]) && close(p.ap_y, n.ap_xyz[1]));
            assert!(close(p.ap_z, n.ap_xyz[2]));
            assert!(close(p.rp, n.rp), "{} RP {} {}", p.point, p.rp, n.rp);
            assert!(close(p.max, n.max));
            for k in 0..3 {
                let (ap, rp) = (
                    [p.ap_a, p.ap_b, p.ap_c][k].unwrap(),
                    [p.rp_a, p.rp_b, p.rp_c][k].unwrap(),
                );
                assert!(
                    close(ap, n.ap_abc[k]),
                    "{} AP angle {k}: {ap} {:?}",
                    p.point,
                    n
                );
                assert!(
                    close(rp, n.rp_abc[k]),
                    "{} RP angle {k}: {rp} {:?}",
                    p.point,
                    n
                );
                // Wrap-safe: the spread is a few hundredths of a degree, not 360.
                assert!(rp < 0.1, "{rp}");
            }
        }
    }
}

#[test]
fn before_after_reports_the_improvement() {
    let (commanded, measured, before) = pose_csvs(POSE_SEED, 10, 0.3, 0.006);
    let (cmd, after) = poses_from(&commanded, &measured);
    let (_, earlier) = poses_from(&commanded, &before);
    let a = pose_accuracy(&cmd, &after).unwrap();
    let b = pose_accuracy(&cmd, &earlier).unwrap();
    let c = compare(&b, &a).unwrap();
    for (p, (pa, pb)) in c.points.iter().zip(a.points.iter().zip(&b.points)) {
        assert_eq!((p.ap.before, p.ap.after), (pb.ap, pa.ap));
        let pct = 100.0 * (pa.ap - pb.ap) / pb.ap;
        assert!((p.ap.percent.unwrap() - pct).abs() < 1e-9);
        // The simulated "before" has four times the systematic error.
        assert!((-80.0..-70.0).contains(&pct), "{pct}");
    }
}

// ---- path -------------------------------------------------------------------------------

/// Samples of one run parsed from `cycle,t,x,y,z,rx,ry,rz` text.
fn runs_from(text: &str) -> Vec<(String, Vec<[f64; 7]>)> {
    let mut runs: Vec<(String, Vec<[f64; 7]>)> = Vec::new();
    for r in parse_rows(text) {
        let v: [f64; 7] = nums(&r, 1).try_into().unwrap();
        match runs.iter_mut().find(|(c, _)| *c == r[0]) {
            Some((_, s)) => s.push(v),
            None => runs.push((r[0].clone(), vec![v])),
        }
    }
    runs
}

fn recording_from(runs: &[(String, Vec<[f64; 7]>)]) -> Recording {
    let mut samples = Vec::new();
    let mut cycles = Vec::new();
    for (c, s) in runs {
        for v in s {
            samples.push(Sample {
                line: 0,
                t: Some(v[0]),
                position: Vector3::new(v[1], v[2], v[3]),
                angles: Some([v[4], v[5], v[6]]),
            });
            cycles.push(c.clone());
        }
    }
    Recording {
        samples,
        cycles: Some(cycles),
    }
}

/// Where a run crosses the plane `(p − c)·u = 0`, by bisection on the run's piecewise-linear
/// parameter (the code solves each segment in closed form): the bracket nearest to `c`.
fn bisect_crossing(run: &[[f64; 7]], c: &Vector3<f64>, u: &Vector3<f64>) -> [f64; 6] {
    let at = |x: f64| -> [f64; 6] {
        let k = (x.floor() as usize).min(run.len() - 2);
        let f = x - k as f64;
        std::array::from_fn(|i| {
            let (a, b) = (run[k][i + 1], run[k + 1][i + 1]);
            if i >= 3 {
                a + f * naive_angle_diff(b, a)
            } else {
                a + f * (b - a)
            }
        })
    };
    let g = |x: f64| {
        let p = at(x);
        (Vector3::new(p[0], p[1], p[2]) - c).dot(u)
    };
    let mut best: Option<(f64, [f64; 6])> = None;
    for k in 0..run.len() - 1 {
        let (mut lo, mut hi) = (k as f64, k as f64 + 1.0);
        if g(lo).signum() == g(hi).signum() && g(lo) != 0.0 {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if g(lo).signum() == g(mid).signum() && g(mid) != 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let p = at(0.5 * (lo + hi));
        let d = (Vector3::new(p[0], p[1], p[2]) - c).norm();
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, p));
        }
    }
    best.unwrap().1
}

#[test]
fn path_figures_equal_an_independent_implementation_on_generated_data() {
    let sim = LineSimulation {
        overshoot: 1.2,
        run_scatter: 0.05,
        ..LineSimulation::default()
    };
    let (commanded, cycles, _) = line_csvs(77, &sim, 4);
    let ends: Vec<Vec<f64>> = parse_rows(&commanded).iter().map(|r| nums(r, 1)).collect();
    let a = Vector3::new(ends[0][0], ends[0][1], ends[0][2]);
    let b = Vector3::new(ends[1][0], ends[1][1], ends[1][2]);
    let runs = runs_from(&cycles);
    let poly = Polyline::new(vec![a, b], Some(vec![[180.0, 0.0, 90.0]; 2])).unwrap();
    let report = path_accuracy(
        &poly,
        &recording_from(&runs),
        PathOptions {
            planes: 12,
            commanded_speed: Some(600.0),
        },
    )
    .unwrap();
    let length = (b - a).norm();
    let u = (b - a) / length;
    let (mut at, mut rt, mut at_a, mut rt_c) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (i, plane) in (1..=12).zip(&report.planes) {
        let s = length * i as f64 / 13.0;
        let c = a + u * s;
        let xs: Vec<[f64; 6]> = runs
            .iter()
            .map(|(_, r)| bisect_crossing(r, &c, &u))
            .collect();
        let col = |k: usize| xs.iter().map(|x| x[k]).collect::<Vec<f64>>();
        let bary = Vector3::new(
            naive_mean(&col(0)),
            naive_mean(&col(1)),
            naive_mean(&col(2)),
        );
        let atp = (bary - c).norm();
        let l: Vec<f64> = xs
            .iter()
            .map(|x| (Vector3::new(x[0], x[1], x[2]) - bary).norm())
            .collect();
        let rtp = naive_mean(&l) + 3.0 * naive_std(&l);
        let da: Vec<f64> = xs.iter().map(|x| naive_angle_diff(x[3], 180.0)).collect();
        let dc: Vec<f64> = xs.iter().map(|x| naive_angle_diff(x[5], 90.0)).collect();
        assert!((plane.s - s).abs() < 1e-9);
        assert!(
            (plane.atp - atp).abs() < 1e-7,
            "plane {i}: {} {atp}",
            plane.atp
        );
        assert!(
            (plane.rtp - rtp).abs() < 1e-7,
            "plane {i}: {} {rtp}",
            plane.rtp
        );
        assert!((plane.at_a.unwrap() - naive_mean(&da).abs()).abs() < 1e-7);
        at = at.max(atp);
        rt = rt.max(rtp);
        at_a = at_a.max(naive_mean(&da).abs());
        rt_c = rt_c.max(3.0 * naive_std(&dc));
    }
    assert!((report.at - at).abs() < 1e-7 && (report.rt - rt).abs() < 1e-7);
    assert!((report.at_a.unwrap() - at_a).abs() < 1e-7);
    assert!((report.rt_c.unwrap() - rt_c).abs() < 1e-7);
    // The known errors: a 0.25/-0.15 mm offset gives ATp ≈ 0.29 mm away from the start.
    let offset = (0.25f64.powi(2) + 0.15f64.powi(2)).sqrt();
    assert!(
        (report.planes[6].atp - offset).abs() < 0.05,
        "{}",
        report.planes[6].atp
    );

    // Eq. 3.38 written out with the direction (l, m, n), over the samples between the end
    // planes, against the code's projection.
    let (l, m, n) = (u.x, u.y, u.z);
    let mut max_d = 0.0f64;
    for (_, r) in &runs {
        for v in r {
            let (pa, pb, pc) = (v[1], v[2], v[3]);
            let s = (Vector3::new(pa, pb, pc) - a).dot(&u);
            if !(0.0..=length).contains(&s) {
                continue;
            }
            let d2 = ((pa - a.x) * m - (pb - a.y) * l).powi(2)
                + ((pb - a.y) * n - (pc - a.z) * m).powi(2)
                + ((pc - a.z) * l - (pa - a.x) * n).powi(2);
            max_d = max_d.max(d2.sqrt());
        }
    }
    assert!((report.line.max_deviation - max_d).abs() < 1e-9);
    // The simulated overshoot: 1.2 mm sideways (-y) decaying over 60 mm, on top of the offset.
    let peak = (0..=1000)
        .map(|k| {
            let s = k as f64 * 0.1;
            let bend = 1.2 * (-s / 60.0).exp() * (s / 10.0).min(1.0);
            (0.25f64 - bend).hypot(0.15)
        })
        .fold(0.0, f64::max);
    let got = report.line.max_deviation;
    assert!((got - peak).abs() < 0.15, "{got} {peak}");
    // The simulated motion: 600 mm/s, 1500 mm/s² (the window blurs the ramp a little).
    let v = report.line.measured_velocity.unwrap();
    assert!((v - 600.0).abs() < 2.0, "{v}");
    let acc = report.line.acceleration.unwrap();
    assert!((acc - 1500.0).abs() < 150.0, "{acc}");
}

#[test]
fn a_polyline_path_is_cut_on_each_leg() {
    // An L-shaped path; each run follows it with a known perpendicular offset per leg.
    let v = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(400.0, 0.0, 0.0),
        Vector3::new(400.0, 300.0, 0.0),
    ];
    let poly = Polyline::new(v.to_vec(), None).unwrap();
    let mut samples = Vec::new();
    let mut cycles = Vec::new();
    for run in 0..3 {
        let z = 0.1 * run as f64; // RT from the spread in z: 0, 0.1, 0.2 around 0.1
        for k in 0..=700 {
            let s = k as f64;
            let p = if s <= 400.0 {
                Vector3::new(s, 0.2, z)
            } else {
                Vector3::new(400.0 - 0.2, s - 400.0, z)
            };
            samples.push(Sample {
                line: 0,
                t: Some(s / 100.0),
                position: p,
                angles: None,
            });
            cycles.push(run.to_string());
        }
    }
    let r = path_accuracy(
        &poly,
        &Recording {
            samples,
            cycles: Some(cycles),
        },
        PathOptions {
            planes: 6,
            commanded_speed: None,
        },
    )
    .unwrap();
    // Barycentre offset (0.2, 0.1) from the path on both legs; spread l = 0.1, 0, 0.1.
    let atp = (0.2f64.powi(2) + 0.1f64.powi(2)).sqrt();
    let l = [0.1, 0.0, 0.1];
    let rtp = naive_mean(&l) + 3.0 * naive_std(&l);
    for p in &r.planes {
        assert!((p.atp - atp).abs() < 1e-9, "{p:?}");
        assert!((p.rtp - rtp).abs() < 1e-9);
        assert!(p.at_a.is_none() && p.rt_a.is_none());
    }
    assert!(r.planes.iter().any(|p| p.s > 400.0) && r.planes.iter().any(|p| p.s < 400.0));
    // Per leg: the largest distance is the run at z = 0.2 beside the offset of 0.2.
    let legs: Vec<(f64, f64)> = r.line.legs.iter().map(|l| (l.from_s, l.to_s)).collect();
    assert_eq!(legs, [(0.0, 400.0), (400.0, 700.0)]);
    for leg in &r.line.legs {
        assert!((leg.max_deviation - 0.08f64.sqrt()).abs() < 1e-9, "{leg:?}");
        assert!(
            (leg.measured_velocity.unwrap() - 100.0).abs() < 1e-6,
            "{leg:?}"
        );
    }
}

#[test]
fn a_continuous_recording_is_cut_into_runs() {
    let (_, _, continuous) = line_csvs(LINE_SEED, &LineSimulation::default(), 3);
    let rows: Vec<Vec<f64>> = parse_rows(&continuous).iter().map(|r| nums(r, 0)).collect();
    let samples: Vec<Sample> = rows
        .iter()
        .map(|v| Sample {
            line: 0,
            t: Some(v[0]),
            position: Vector3::new(v[1], v[2], v[3]),
            angles: None,
        })
        .collect();
    let sim = LineSimulation::default();
    let poly = Polyline::new(vec![Vector3::from(sim.start), Vector3::from(sim.end)], None).unwrap();
    let r = path_accuracy(
        &poly,
        &Recording {
            samples: samples.clone(),
            cycles: None,
        },
        PathOptions::default(),
    )
    .unwrap();
    let directions: Vec<String> = r
        .runs
        .iter()
        .map(|x| format!("{:?}/{}", x.direction, x.used))
        .collect();
    assert_eq!(
        directions,
        [
            "Forward/true",
            "Backward/false",
            "Forward/true",
            "Backward/false",
            "Forward/true"
        ]
    );
    // Each used run begins standing at the start: the simulated runs stand 0.3 s (30 samples).
    for run in &r.used {
        let first = &run.samples[0];
        assert!((first.position - Vector3::from(sim.start)).norm() < 0.6);
        let v0 = (run.samples[1].position - first.position).norm();
        assert!(v0 < 0.1, "{v0}");
    }
    // The same figures as cutting by hand at the simulated boundaries (run length 2·30+220).
    let per_run = 2 * 30 + 220;
    let by_hand: Vec<String> = (0..samples.len())
        .map(|k| (k / per_run).to_string())
        .collect();
    let manual = path_accuracy(
        &poly,
        &Recording {
            samples,
            cycles: Some(by_hand),
        },
        PathOptions::default(),
    )
    .unwrap();
    assert_eq!(manual.runs_used, 3);
    assert!((manual.at - r.at).abs() < 1e-9, "{} {}", manual.at, r.at);
    assert!((manual.rt - r.rt).abs() < 1e-9);
}

#[test]
fn plane_crossing_interpolates_time_and_angles() {
    let s = |t: f64, x: f64, rx: f64| Sample {
        line: 0,
        t: Some(t),
        position: Vector3::new(x, 1.0, 2.0),
        angles: Some([rx, 0.0, 0.0]),
    };
    let run = [s(0.0, 0.0, 179.0), s(1.0, 10.0, -179.0)];
    let x = plane_crossing(&run, &Vector3::new(2.5, 0.0, 0.0), &Vector3::x()).unwrap();
    assert!((x.position - Vector3::new(2.5, 1.0, 2.0)).norm() < 1e-12);
    assert!((x.t.unwrap() - 0.25).abs() < 1e-12);
    assert!((x.angles.unwrap()[0] - 179.5).abs() < 1e-9);
    assert!(plane_crossing(&run, &Vector3::new(20.0, 0.0, 0.0), &Vector3::x()).is_none());
}

// ---- invariants ---------------------------------------------------------------------------

fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed
        .wrapping_mul(2_862_933_555_777_941_757)
        .wrapping_add(3_037_000_493);
    move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn pose_of_exact_visits_is_zero_and_a_translation_is_its_length(
        seed in 0u64..10_000,
        v in prop::array::uniform3(-5.0f64..5.0),
        cycles in 2usize..6,
    ) {
        let mut r = lcg(seed);
        let cmd: Vec<CommandedPose> = (0..4)
            .map(|i| CommandedPose {
                name: format!("P{i}"),
                line: 0,
                position: Vector3::new(1000.0 * r(), 1000.0 * r(), 1000.0 * r()),
                angles: Some([360.0 * r(), 180.0 * r(), 360.0 * r()]),
            })
            .collect();
        let shift = Vector3::from(v);
        let visits = |offset: Vector3<f64>, scatter: f64, r: &mut dyn FnMut() -> f64| {
            let mut out = Vec::new();
            for c in &cmd {
                for j in 0..cycles {
                    let a = c.angles.unwrap();
                    out.push(Visit {
                        point: c.name.clone(),
                        cycle: Some(j.to_string()),
                        line: 0,
                        position: c.position + offset + Vector3::new(r(), r(), r()) * scatter,
                        angles: Some([a[0] + 360.0, a[1], a[2] - 360.0]),
                    });
                }
            }
            out
        };
        let exact = pose_accuracy(&cmd, &visits(Vector3::zeros(), 0.0, &mut r)).unwrap();
        prop_assert!(exact.summary.ap < 1e-9 && exact.summary.rp < 1e-9 && exact.summary.max < 1e-9);
        prop_assert!(exact.summary.ap_a.unwrap().abs() < 1e-9);
        let moved = pose_accuracy(&cmd, &visits(shift, 0.0, &mut r)).unwrap();
        for p in &moved.points {
            prop_assert!((p.ap - shift.norm()).abs() < 1e-9);
            prop_assert!((p.max - shift.norm()).abs() < 1e-9);
            prop_assert!(p.rp < 1e-9);
        }
        // Repeatability does not see where the cloud is.
        let mut r2 = lcg(seed + 1);
        let mut r3 = lcg(seed + 1);
        let here = pose_accuracy(&cmd, &visits(Vector3::zeros(), 0.3, &mut r2)).unwrap();
        let there = pose_accuracy(&cmd, &visits(shift, 0.3, &mut r3)).unwrap();
        for (a, b) in here.points.iter().zip(&there.points) {
            prop_assert!((a.rp - b.rp).abs() < 1e-9);
        }
    }

    #[test]
    fn path_on_the_line_is_zero_and_a_shift_gives_its_perpendicular_part(
        seed in 0u64..10_000,
        v in prop::array::uniform3(-2.0f64..2.0),
        planes in 1usize..15,
    ) {
        let mut r = lcg(seed);
        let a = Vector3::new(500.0 * r(), 500.0 * r(), 500.0 * r());
        let dir = Vector3::new(r(), r(), r() + 0.7).normalize();
        let length = 300.0 + 500.0 * (r() + 0.5);
        let b = a + dir * length;
        let poly = Polyline::new(vec![a, b], None).unwrap();
        let shift = Vector3::from(v);
        let record = |offset: Vector3<f64>, r: &mut dyn FnMut() -> f64| {
            let mut samples = Vec::new();
            let mut cycles = Vec::new();
            for run in 0..3 {
                // Uneven sampling, a little before the start to a little after the end.
                let mut s = -5.0;
                let mut t = 0.0;
                while s < length + 5.0 {
                    samples.push(Sample { line: 0, t: Some(t), position: a + dir * s + offset, angles: None });
                    cycles.push(run.to_string());
                    s += 3.0 + 4.0 * (r() + 0.5);
                    t += 0.01;
                }
            }
            Recording { samples, cycles: Some(cycles) }
        };
        let opts = PathOptions { planes, commanded_speed: None };
        let exact = path_accuracy(&poly, &record(Vector3::zeros(), &mut r), opts).unwrap();
        prop_assert!(exact.at < 1e-9 && exact.rt < 1e-9 && exact.line.max_deviation < 1e-9);
        let moved = path_accuracy(&poly, &record(shift, &mut r), opts).unwrap();
        let perpendicular = (shift - dir * shift.dot(&dir)).norm();
        prop_assert!((moved.at - perpendicular).abs() < 1e-9, "{} {}", moved.at, perpendicular);
        prop_assert!(moved.rt < 1e-9);
        prop_assert!((moved.line.max_deviation - perpendicular).abs() < 1e-9);
        prop_assert_eq!(moved.planes.len(), planes);
    }
}

// ---- the command line -----------------------------------------------------------------------

fn ok(args: &[&str]) -> String {
    let (code, out, err) = trackfix(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    out
}

#[test]
fn pose_cli_outputs() {
    let base = ["accuracy", "pose", POSE[0], POSE[1]];
    insta::assert_snapshot!("pose_table", ok(&base));
    insta::assert_snapshot!(
        "pose_json",
        ok(&[&base[..], &["--format", "json"]].concat())
    );
    insta::assert_snapshot!("pose_csv", ok(&[&base[..], &["--format", "csv"]].concat()));
    let before = ["--before", "samples/accuracy/pose_before.csv"];
    insta::assert_snapshot!("pose_before_after", ok(&[&base[..], &before].concat()));
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&base[..], &before, &["--format", "json"]].concat())).unwrap();
    assert!(
        json["improvement"]["summary"]["AP"]["percent"]
            .as_f64()
            .unwrap()
            < -70.0
    );
    // The tracker export with its own column names gives the same figures.
    let export = ok(&[
        "accuracy",
        "pose",
        POSE[0],
        "samples/accuracy/pose_export.csv",
        "--map",
        "point=Name,cycle=Run,x=X [mm],y=Y [mm],z=Z [mm]",
        "--format",
        "csv",
    ]);
    let plain = ok(&[&base[..], &["--format", "csv"]].concat());
    // Same positions; the export has no angles, so those cells are empty.
    let strip = |t: &str| -> Vec<String> {
        t.lines()
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                format!("{},{},{},{},{}", f[0], f[1], f[2], f[9], f[13])
            })
            .collect()
    };
    assert_eq!(strip(&export), strip(&plain));
    assert!(export.lines().nth(1).unwrap().contains(",,,"));
}

#[test]
fn path_cli_outputs() {
    insta::assert_snapshot!(
        "path_table_cycles",
        ok(&[
            "accuracy",
            "path",
            LINE,
            "samples/accuracy/line_cycles.csv",
            "--speed",
            "600"
        ])
    );
    insta::assert_snapshot!(
        "path_json_continuous",
        ok(&[
            "accuracy",
            "path",
            LINE,
            "samples/accuracy/line_continuous.csv",
            "--planes",
            "5",
            "--format",
            "json"
        ])
    );
    // A 90° edge without a stop: the straight-line figures per leg, the swing-over behind the
    // corner in ATp of the planes after it.
    insta::assert_snapshot!(
        "path_table_edge",
        ok(&[
            "accuracy",
            "path",
            "samples/accuracy/edge_commanded.csv",
            "samples/accuracy/edge_cycles.csv",
            "--speed",
            "400"
        ])
    );
    insta::assert_snapshot!(
        "path_csv_cycles",
        ok(&[
            "accuracy",
            "path",
            LINE,
            "samples/accuracy/line_cycles.csv",
            "--format",
            "csv"
        ])
    );
}

fn error_of(args: &[&str], files: &[(&str, &str)]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let mut full: Vec<String> = Vec::new();
    for a in args {
        match files.iter().find(|(name, _)| name == a) {
            Some((name, text)) => {
                let p = dir.path().join(name);
                std::fs::write(&p, text).unwrap();
                full.push(p.to_str().unwrap().to_owned());
            }
            None => full.push((*a).to_owned()),
        }
    }
    let refs: Vec<&str> = full.iter().map(String::as_str).collect();
    let (code, _, err) = trackfix(&refs);
    assert_eq!(code, 2, "{err}");
    err.replace(dir.path().to_str().unwrap(), "TMP")
}

#[test]
fn error_messages() {
    let cmd = "point,x,y,z\nP1,0,0,0\nP2,100,0,0\n";
    let cases: Vec<String> = vec![
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                ("m.csv", "point,cycle,x,y,z\nP1,1,0,0,0\nP1,2,0.1,zero,0\n"),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                ("m.csv", "point,cycle,x,y,z\nP1,1,0,0,0\nP3,1,0,0,0\n"),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                ("m.csv", "point,cycle,x,y,z,temp\nP1,1,0,0,0,20\n"),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[("c.csv", cmd), ("m.csv", "point,cycle,x,y\nP1,1,0,0\n")],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                (
                    "m.csv",
                    "point,cycle,x,y,z\nP1,1,0,0,0\nP1,1,0,0,0\nP2,1,0,0,0\n",
                ),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                ("m.csv", "point,cycle,x,y,z,rx\nP1,1,0,0,0,0\n"),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv"],
            &[
                ("c.csv", cmd),
                (
                    "m.csv",
                    "point,cycle,x,y,z\nP1,1,0,0,0\nP1,2,0,0,0\nP2,1,0,0,0\n",
                ),
            ],
        ),
        error_of(
            &["accuracy", "path", "c.csv", "m.csv"],
            &[
                ("c.csv", "x,y,z\n0,0,0\n100,0,0\n"),
                ("m.csv", "cycle,t,x,y,z\n1,0,0,0,0\n1,0,1,0,0\n"),
            ],
        ),
        error_of(
            &["accuracy", "path", "c.csv", "m.csv"],
            &[
                ("c.csv", "x,y,z\n0,0,0\n100,0,0\n"),
                (
                    "m.csv",
                    "cycle,t,x,y,z\n1,0,0,0,0\n1,1,50,0,0\n2,0,0,0,0\n2,1,100,0,0\n",
                ),
            ],
        ),
        error_of(
            &["accuracy", "path", "c.csv", "m.csv"],
            &[
                ("c.csv", "x,y,z\n0,0,0\n"),
                ("m.csv", "cycle,t,x,y,z\n1,0,0,0,0\n"),
            ],
        ),
        error_of(
            &["accuracy", "pose", "c.csv", "m.csv", "--map", "point"],
            &[("c.csv", cmd), ("m.csv", "point,cycle,x,y,z\n")],
        ),
    ];
    insta::assert_snapshot!("errors", cases.join("\n---\n"));
}

// ---- figures --------------------------------------------------------------------------------

fn svg_summary(text: &str) -> String {
    use sha2::{Digest, Sha256};
    let digest = Sha256::digest(text.as_bytes());
    let hex: String = digest.iter().take(8).map(|b| format!("{b:02x}")).collect();
    format!(
        "bytes {} sha256 {hex}…\npolylines {} circles {} rects {} texts {}",
        text.len(),
        text.matches("<polyline").count(),
        text.matches("<circle").count(),
        text.matches("<rect").count(),
        text.matches("<text").count(),
    )
}

#[test]
fn figures_are_deterministic_and_snapshotted() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    ok(&[
        "accuracy",
        "pose",
        POSE[0],
        POSE[1],
        "--plot",
        &d("pose.svg"),
    ]);
    ok(&["accuracy", "pose", POSE[0], POSE[1], "--plot", &d("figs")]);
    let pose = std::fs::read_to_string(d("pose.svg")).unwrap();
    assert_eq!(pose, std::fs::read_to_string(d("figs/pose.svg")).unwrap());
    // 10 points: 100 visit dots, 10 RP circles (polylines) and their labels.
    assert_eq!(pose.matches("<circle").count(), 100);
    insta::assert_snapshot!("pose_svg", pose);
    // With the earlier measurement: its AP bars (one more per point, 10 more rects), a cross at
    // each earlier mean and a line from it to the new one.
    ok(&[
        "accuracy",
        "pose",
        POSE[0],
        POSE[1],
        "--before",
        "samples/accuracy/pose_before.csv",
        "--plot",
        &d("before.svg"),
    ]);
    let compared = std::fs::read_to_string(d("before.svg")).unwrap();
    assert_eq!(
        compared.matches("<rect").count(),
        pose.matches("<rect").count() + 11
    );
    assert!(compared.contains("AP before") && compared.contains("x: mean before"));
    insta::assert_snapshot!("pose_before_svg_summary", svg_summary(&compared));

    let cycles = "samples/accuracy/line_cycles.csv";
    ok(&[
        "accuracy",
        "path",
        LINE,
        cycles,
        "--speed",
        "600",
        "--plot",
        &d("path.svg"),
    ]);
    ok(&[
        "accuracy",
        "path",
        LINE,
        cycles,
        "--speed",
        "600",
        "--plot",
        &d("figs"),
    ]);
    ok(&[
        "accuracy",
        "path",
        LINE,
        cycles,
        "--speed",
        "600",
        "--plot",
        &d("again"),
    ]);
    let mut summary = vec![format!(
        "path.svg: {}",
        svg_summary(&std::fs::read_to_string(d("path.svg")).unwrap())
    )];
    for name in [
        "path_planes",
        "path_deviation",
        "path_look_through",
        "path_velocity",
    ] {
        let a = std::fs::read_to_string(d(&format!("figs/{name}.svg"))).unwrap();
        let b = std::fs::read_to_string(d(&format!("again/{name}.svg"))).unwrap();
        assert_eq!(a, b, "{name} is not deterministic");
        summary.push(format!("{name}.svg: {}", svg_summary(&a)));
    }
    insta::assert_snapshot!("path_svg_summary", summary.join("\n"));
}

#[test]
fn measured_angles_without_commanded_ones_give_repeatability_only() {
    let cmd = [CommandedPose {
        name: "P1".into(),
        line: 0,
        position: Vector3::zeros(),
        angles: None,
    }];
    // rx visits at 179.99, -179.99, 180.0: a spread of hundredths, not of 360°.
    let visits: Vec<Visit> = [179.99, -179.99, 180.0]
        .iter()
        .enumerate()
        .map(|(j, rx)| Visit {
            point: "P1".into(),
            cycle: Some(j.to_string()),
            line: 0,
            position: Vector3::new(0.01 * j as f64, 0.0, 0.0),
            angles: Some([*rx, 0.0, 0.0]),
        })
        .collect();
    let r = pose_accuracy(&cmd, &visits).unwrap();
    let p = &r.points[0];
    assert!(p.ap_a.is_none() && p.ap_b.is_none() && p.ap_c.is_none());
    let d = [0.0, 0.02, 0.01];
    assert!(
        (p.rp_a.unwrap() - 3.0 * naive_std(&d)).abs() < 1e-9,
        "{:?}",
        p.rp_a
    );
    assert_eq!(p.rp_b, Some(0.0));
}

#[test]
fn a_stop_at_a_corner_does_not_end_the_run() {
    // Three runs along an L, each standing 0.2 s at the start, at the corner and at the end, with
    // a trapezoidal speed on each leg; one continuous recording without cycles.
    let v = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(400.0, 0.0, 0.0),
        Vector3::new(400.0, 300.0, 0.0),
    ];
    let poly = Polyline::new(v.to_vec(), None).unwrap();
    let mut samples = Vec::new();
    let mut t = 0.0;
    let dt = 0.01;
    let mut push = |p: Vector3<f64>, t: &mut f64| {
        samples.push(Sample {
            line: 0,
            t: Some(*t),
            position: p,
            angles: None,
        });
        *t += dt;
    };
    for run in 0..3 {
        let offset = Vector3::new(0.0, 0.0, 0.05 * run as f64);
        for (from, to) in [(v[0], v[1]), (v[1], v[2])] {
            for _ in 0..20 {
                push(from + offset, &mut t);
            }
            let len = (to - from).norm();
            let steps = (len / 4.0) as usize; // 400 mm/s
            for k in 1..=steps {
                let f = k as f64 / steps as f64;
                let eased = 0.5 - 0.5 * (std::f64::consts::PI * f).cos();
                push(from + (to - from) * eased + offset, &mut t);
            }
        }
        for _ in 0..20 {
            push(v[2] + offset, &mut t);
        }
        // Back to the start, quickly and off the path (not a run along it).
        for k in 1..=30 {
            let f = k as f64 / 30.0;
            push(
                v[2] + (v[0] - v[2]) * f
                    + Vector3::new(0.0, 0.0, 50.0) * (1.0 - (2.0 * f - 1.0).powi(2)),
                &mut t,
            );
        }
    }
    let r = path_accuracy(
        &poly,
        &Recording {
            samples,
            cycles: None,
        },
        PathOptions::default(),
    )
    .unwrap();
    assert_eq!(r.runs_used, 3, "{:#?}", r.runs);
    // Offsets 0, 0.05, 0.1 in z: barycentre 0.05 off, l = 0.05, 0, 0.05.
    assert!((r.at - 0.05).abs() < 1e-9, "{}", r.at);
    let l = [0.05, 0.0, 0.05];
    assert!((r.rt - (naive_mean(&l) + 3.0 * naive_std(&l))).abs() < 1e-9);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any recording along any polyline gives figures or an error, never a panic.
    #[test]
    fn path_analysis_never_panics(
        vertices in prop::collection::vec(prop::array::uniform3(-100.0f64..100.0), 2..5),
        points in prop::collection::vec(prop::array::uniform3(-120.0f64..120.0), 0..80),
        with_cycles in any::<bool>(),
        planes in 0usize..6,
    ) {
        let Ok(poly) = Polyline::new(vertices.iter().map(|v| Vector3::from(*v)).collect(), None) else {
            return Ok(());
        };
        let samples: Vec<Sample> = points
            .iter()
            .enumerate()
            .map(|(k, p)| Sample { line: k as u64 + 2, t: Some(k as f64 * 0.01), position: Vector3::from(*p), angles: Some([p[0], p[1], p[2]]) })
            .collect();
        let cycles = with_cycles.then(|| (0..samples.len()).map(|k| (k % 3).to_string()).collect());
        let rec = Recording { samples, cycles };
        if let Ok(r) = path_accuracy(&poly, &rec, PathOptions { planes, commanded_speed: Some(100.0) }) {
            prop_assert!(r.at.is_finite() && r.rt.is_finite() && r.runs_used >= 2);
            let _ = trackfix::accuracy::path_svg(&poly, &r).unwrap();
        }
    }
}
