//! Integration tests: track. The simulation test, properties, and snapshots of the
//! `trackfix track` commands on the samples.

use std::path::Path;

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use trackfix::geometry::rigid_fit::fit_rigid;
use trackfix::geometry::{Pose, pose_xyz_deg};
use trackfix::track::frames_csv::{SamplingFrame, frames_csv};
use trackfix::track::identify::{
    Exclusion, MEASUREMENTS_HEADER, identify, identify_excluding, parse_measurements,
};
use trackfix::track::nominal::{FitOptions, fit_track};
use trackfix::track::simulate::{
    TrackTruth, measurements_csv, sample_tcp_points, scan_csv, simulate_measurements, simulate_scan,
};
use trackfix::track::spline::{CubicSpline, EndCondition};
use trackfix::track::{
    Extrapolate, Knot, NominalProblem, NumericCsv, Profile, SkidProblem, TrackError,
};

use trackfix::track::MeasuredIn;
use trackfix::track::cell_nominal::{Disagreement, check_cell_nominal};
use trackfix::transform::Cell;

use crate::support::{root, trackfix};

fn skids() -> Vec<f64> {
    (0..=16).map(|i| i as f64 * 500.0).collect()
}

/// The simulation test. Truth: `TrackTruth::sample_r1()` without its waviness, i.e. a
/// smooth deformation: 2.5 mm sag, 1.5 mm sideways bow, 0.03° twist, pitch/yaw following the
/// rails (up to 0.06°), gear error -1.5e-4 (1.2 mm over 8 m). 10 TCP points at each of 17 skid
/// positions (0..8000 every 500 mm), tracker noise 0.02 mm per axis (seed 7). identify + fit,
/// then the modelled base `N(s)·D(s)` against the true one at the 16 held-out positions half-way
/// between the knots: the TCP error at the 10 working points (up to 2 m from the base), the
/// base-origin error and the rotation error.
/// Level: TCP within 0.04 mm (2 σ of the per-axis noise; one noisy 3D reading is 0.035 mm rms).
/// Measured: TCP 0.031 mm, base origin 0.052 mm, rotation 0.0020° (docs/notes-track.md).
#[test]
fn simulation_recovers_the_truth_between_knots() {
    let mut truth = TrackTruth::sample_r1();
    truth.deformation.wave_mm = 0.0;
    let rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.02, 7);
    let id = identify(&rows).unwrap();
    assert!(id.outliers.is_empty());
    let fit = fit_track(&id.frames(), &FitOptions::default()).unwrap();
    let mut worst_base: f64 = 0.0;
    let mut worst_tcp: f64 = 0.0;
    let mut worst_rot: f64 = 0.0;
    for i in 0..16 {
        let s = 250.0 + 500.0 * i as f64;
        let model = fit.profile.base_frame(s).unwrap();
        let real = truth.base_frame(s);
        let err = model.inverse() * real;
        worst_base = worst_base.max(err.translation.vector.norm());
        worst_rot = worst_rot.max(err.rotation.angle().to_degrees());
        for p in sample_tcp_points() {
            worst_tcp = worst_tcp.max((model * p - real * p).norm());
        }
    }
    assert!(
        worst_tcp < 0.04,
        "TCP {worst_tcp} mm, base {worst_base} mm, rotation {worst_rot} deg"
    );
    // The base origin lies 1-2 m from the measured points, so it carries the rotation noise
    // times that lever: looser than at the TCP.
    assert!(worst_base < 0.08, "base origin error {worst_base} mm");
    assert!(worst_rot < 0.004, "rotation error {worst_rot} deg");
    // Without the profile (the straight nominal alone) the error is millimetres.
    let straight = (0..16)
        .map(|i| {
            let s = 250.0 + 500.0 * i as f64;
            (fit.profile.nominal_frame(s).inverse() * truth.base_frame(s))
                .translation
                .vector
                .norm()
        })
        .fold(0.0, f64::max);
    assert!(straight > 1.0, "{straight}");
}

/// The samples are what the documented commands give (samples/track/README.md).
#[test]
fn samples_are_reproducible() {
    let dir = root().join("samples/track");
    for (truth, seed, sub) in [
        (TrackTruth::sample_r1(), 1u64, ""),
        (TrackTruth::sample_r2(), 2, "r2"),
    ] {
        let d = dir.join(sub);
        let rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.02, seed);
        let text = measurements_csv(&rows);
        let committed = std::fs::read_to_string(d.join("measurements.csv")).unwrap();
        assert_eq!(text, committed, "{}", d.display());
        let scan = simulate_scan(
            &truth,
            Point3::new(0.0, 0.0, 250.0),
            0.0,
            8000.0,
            10.0,
            0.02,
            seed + 1000,
        );
        assert_eq!(
            scan_csv(&scan),
            std::fs::read_to_string(d.join("scan.csv")).unwrap()
        );
        let parsed = parse_measurements(Path::new("m.csv"), committed.as_bytes()).unwrap();
        let frames = identify(&parsed).unwrap().frames();
        assert_eq!(
            frames_csv(&frames),
            std::fs::read_to_string(d.join("frames.csv")).unwrap()
        );
        let profile = Profile::load(&d.join("profile.toml")).unwrap();
        assert_eq!(profile.knots().len(), 17);
        assert_eq!(profile.skid_range(), (0.0, 8000.0));
    }
}

#[test]
fn identify_then_fit_through_the_binary_matches_the_samples() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames.csv");
    let profile = tmp.path().join("profile.toml");
    let frames_s = frames.to_str().unwrap();
    let (code, _, err) = trackfix(&[
        "track",
        "identify",
        "samples/track/measurements.csv",
        "-o",
        frames_s,
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read(&frames).unwrap(),
        std::fs::read(root().join("samples/track/frames.csv")).unwrap()
    );
    // The committed profile was fitted from the committed frames (same bytes, same hash).
    std::fs::copy(root().join("samples/track/frames.csv"), &frames).unwrap();
    let (code, out, err) = trackfix(&[
        "track",
        "fit",
        frames_s,
        "-o",
        profile.to_str().unwrap(),
        "--name",
        "r1",
        "--measured-in",
        "world",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read_to_string(&profile).unwrap(),
        std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap()
    );
    let out = out.replace(tmp.path().to_str().unwrap(), "<tmp>");
    insta::assert_snapshot!("fit_r1", out);
}

#[test]
fn identify_output_on_the_sample() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames.csv");
    let (code, out, _) = trackfix(&[
        "track",
        "identify",
        "samples/track/measurements.csv",
        "-o",
        frames.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    insta::assert_snapshot!(
        "identify_r1",
        out.replace(tmp.path().to_str().unwrap(), "<tmp>")
    );
}

#[test]
fn identify_flags_an_outlier() {
    let truth = TrackTruth::sample_r1();
    let mut rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.02, 3);
    if let Some(r) = rows.iter_mut().find(|r| r.skid == 3000.0 && r.point == 4) {
        r.meas[2] += 0.5;
    }
    let id = identify(&rows).unwrap();
    assert_eq!(id.outliers.len(), 1, "{:?}", id.outliers);
    let worst = id
        .outliers
        .iter()
        .max_by(|a, b| a.ratio.total_cmp(&b.ratio))
        .unwrap();
    assert_eq!((worst.skid, worst.point), (3000.0, 4));
    assert!(worst.ratio > 10.0, "{worst:?}");
    assert!(
        id.outliers.iter().all(|o| o.skid == 3000.0),
        "{:?}",
        id.outliers
    );
}

#[test]
fn show_overview_on_the_sample() {
    let (code, out, err) = trackfix(&["track", "show", "samples/track/profile.toml"]);
    assert_eq!(code, 0, "{err}");
    insta::assert_snapshot!("show_r1", out);
}

#[test]
fn show_values_in_three_formats() {
    let base = ["track", "show", "samples/track/profile.toml"];
    let (code, json, _) = trackfix(
        &[
            &base[..],
            &["--at", "4000", "--at", "250", "--format", "json"],
        ]
        .concat(),
    );
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    // In the order asked.
    assert_eq!(v[0]["skid"], 4000.0);
    assert_eq!(v[1]["skid"], 250.0);
    insta::assert_snapshot!("show_r1_json", json);
    let (code, table, _) = trackfix(&[&base[..], &["--step", "1000"]].concat());
    assert_eq!(code, 0);
    insta::assert_snapshot!("show_r1_step", table);
    let (code, csv, _) = trackfix(&[&base[..], &["--step", "2000", "--format", "csv"]].concat());
    assert_eq!(code, 0);
    insta::assert_snapshot!("show_r1_csv", csv);
}

#[test]
fn svg_is_deterministic() {
    let tmp = tempfile::tempdir().unwrap();
    let a = tmp.path().join("a.svg");
    let b = tmp.path().join("b.svg");
    for p in [&a, &b] {
        let (code, _, err) = trackfix(&[
            "track",
            "show",
            "samples/track/profile.toml",
            "--plot",
            p.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        assert_eq!(
            err,
            format!(
                "wrote {}: the six deviation curves of profile `r1` with their 17 knots, and the twist diagram\n",
                p.display()
            )
        );
    }
    let (sa, sb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(sa, sb);
    let text = String::from_utf8(sa).unwrap();
    // Six curves + the twist diagram; 17 knots in each of the 7 panels.
    // The twist diagram labels each of its 17 dots with the knot's skid.
    // (plotters anchors axis ticks in the middle or at the end, the diagram's labels at the start).
    let started: Vec<&str> = text
        .split("<text ")
        .filter(|t| t.contains("text-anchor=\"start\""))
        .filter_map(|t| t.split_once('>').and_then(|(_, r)| r.split_once("</text>")))
        .map(|(content, _)| content.trim())
        .collect();
    let labels: Vec<String> = (0..=16).map(|i| (500 * i).to_string()).collect();
    let summary = format!(
        "polylines: {}\ncircles: {}\ntitles: {:?}\nskid labels: {}",
        text.matches("<polyline").count(),
        text.matches("<circle").count(),
        ["dx [mm]", "rz [deg]", "twist diagram", "track profile `r1`"]
            .iter()
            .map(|t| text.contains(t))
            .collect::<Vec<_>>(),
        labels
            .iter()
            .filter(|l| started.contains(&l.as_str()))
            .count()
    );
    insta::assert_snapshot!("svg_summary", summary);
    let c = tmp.path().join("c.svg");
    let (code, _, _) = trackfix(&[
        "track",
        "spectrum",
        "samples/track/scan.csv",
        "--threshold",
        "0.05",
        "--plot",
        c.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let spectrum = std::fs::read_to_string(&c).unwrap();
    assert!(spectrum.starts_with("<svg"));
    // Frequency ticks carry their wavelength: 0.0005 /mm is 2000 mm.
    assert!(spectrum.contains("\n0.0005 (2000)\n</text>"), "{spectrum}");
    assert!(spectrum.contains("(wavelength 1942 mm)"));
}

#[test]
fn spectrum_on_the_sample_scan() {
    let (code, out, err) = trackfix(&[
        "track",
        "spectrum",
        "samples/track/scan.csv",
        "--threshold",
        "0.05",
    ]);
    assert_eq!(code, 0, "{err}");
    insta::assert_snapshot!("spectrum_r1", out);
}

fn error_of(args: &[&str]) -> String {
    let (code, out, err) = trackfix(args);
    assert_eq!(code, 2, "{out}{err}");
    err
}

#[test]
fn error_messages() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str, text: &str| {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let clean = |s: String| s.replace(tmp.path().to_str().unwrap(), "<tmp>");
    let out = tmp.path().join("out");
    let out = out.to_str().unwrap();

    let bad_csv = t(
        "m.csv",
        "skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z\n0,1,1,2,3,4,5,6\n0,2,1,2,x3,4,5,6\n",
    );
    let e1 = error_of(&["track", "identify", bad_csv.to_str().unwrap(), "-o", out]);

    let short = t(
        "m2.csv",
        "skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z\n0,1,1,2,3,4,5,6\n0,2,1,0,0,1,0,0\n",
    );
    let e2 = error_of(&["track", "identify", short.to_str().unwrap(), "-o", out]);

    let profile = std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap();
    let unknown = t(
        "unknown.toml",
        &profile.replace("gear = \"as-is\"", "gear = \"as-is\"\ncolour = \"red\""),
    );
    let e3 = error_of(&["track", "show", unknown.to_str().unwrap()]);

    let missing = t(
        "missing.toml",
        &profile.replace("extrapolate = \"error\"\n", ""),
    );
    let e4 = error_of(&["track", "show", missing.to_str().unwrap()]);

    let decreasing = t(
        "decreasing.toml",
        &profile.replacen("skid = 1000.0", "skid = 400.0", 1),
    );
    let e5 = error_of(&["track", "show", decreasing.to_str().unwrap()]);

    let e6 = error_of(&[
        "track",
        "show",
        "samples/track/profile.toml",
        "--at",
        "9000",
    ]);

    let frames = t(
        "frames.csv",
        "skid,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0\n1000,1000,0,0,0,0,0\n1000,2000,0,0,0,0,0\n",
    );
    let e7 = error_of(&["track", "fit", frames.to_str().unwrap(), "-o", out]);

    // A file given to the wrong command.
    let e8 = error_of(&[
        "track",
        "spectrum",
        "samples/track/measurements.csv",
        "--threshold",
        "0.05",
    ]);
    let e9 = error_of(&["track", "show", frames.to_str().unwrap()]);

    let all = [e1, e2, e3, e4, e5, e6, e7, e8, e9].map(clean).join("\n");
    insta::assert_snapshot!("errors", all);
}

#[test]
fn out_of_range_is_typed() {
    let p = Profile::load(&root().join("samples/track/profile.toml")).unwrap();
    match p.deviation(-1.0) {
        Err(TrackError::OutOfRange { skid, min, max }) => {
            assert_eq!((skid, min, max), (-1.0, 0.0, 8000.0))
        }
        other => panic!("{other:?}"),
    }
}

fn knot_strategy() -> impl Strategy<Value = Vec<Knot>> {
    (2usize..12).prop_flat_map(|n| {
        (
            prop::collection::vec(1.0f64..800.0, n),
            prop::collection::vec(prop::array::uniform6(-3.0f64..3.0), n),
        )
            .prop_map(|(gaps, vals)| {
                let mut s = -200.0;
                gaps.iter()
                    .zip(vals)
                    .map(|(g, v)| {
                        s += g;
                        Knot::from_components(
                            s,
                            [v[0], v[1], v[2], v[3] / 10.0, v[4] / 10.0, v[5] / 10.0],
                        )
                    })
                    .collect()
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn rigid_fit_of_exact_data_recovers_the_transform(
        t in prop::array::uniform3(-5000.0f64..5000.0),
        a in prop::array::uniform3(-180.0f64..180.0),
        pts in prop::collection::vec(prop::array::uniform3(-1500.0f64..1500.0), 4..10),
    ) {
        let pose = pose_xyz_deg(t[0], t[1], t[2], a[0], a[1], a[2]);
        let src: Vec<Point3<f64>> = pts.iter().map(|p| Point3::from(*p)).collect();
        let dst: Vec<Point3<f64>> = src.iter().map(|p| pose * p).collect();
        let fit = fit_rigid(&src, &dst).unwrap();
        prop_assert!((fit.pose.translation.vector - pose.translation.vector).norm() < 1e-9);
        prop_assert!(fit.pose.rotation.angle_to(&pose.rotation) < 1e-9);
    }

    #[test]
    fn splines_interpolate_with_continuous_derivatives(knots in knot_strategy()) {
        let xs: Vec<f64> = knots.iter().map(|k| k.skid).collect();
        let ys: Vec<f64> = knots.iter().map(|k| k.dy).collect();
        for end in [EndCondition::Natural, EndCondition::Clamped { start: 0.01, end: -0.02 }] {
            let s = CubicSpline::new(&xs, &ys, end).unwrap();
            for (x, y) in xs.iter().zip(&ys) {
                prop_assert!((s.value(*x) - y).abs() < 1e-9);
            }
            let mmax = xs.iter().map(|x| s.second_derivative(*x).abs()).fold(1.0, f64::max);
            for w in xs.windows(3) {
                let (x, h) = (w[1], 1e-9 * (w[2] - w[0]));
                let tol = 1e-5 * mmax;
                prop_assert!((s.value(x - h) - s.value(x + h)).abs() < tol);
                prop_assert!((s.derivative(x - h) - s.derivative(x + h)).abs() < tol);
                prop_assert!((s.second_derivative(x - h) - s.second_derivative(x + h)).abs() < tol);
            }
        }
    }

    #[test]
    fn a_straight_track_gives_an_all_zero_profile(
        t in prop::array::uniform3(-5000.0f64..5000.0),
        a in prop::array::uniform3(-180.0f64..180.0),
        n in 2usize..12,
        step in 100.0f64..1500.0,
    ) {
        let truth = TrackTruth::straight(pose_xyz_deg(t[0], t[1], t[2], a[0], a[1], a[2]), 1e4);
        let skids: Vec<f64> = (0..n).map(|i| i as f64 * step).collect();
        let rows = simulate_measurements(&truth, &skids, &sample_tcp_points(), 0.0, 1);
        let fit = fit_track(&identify(&rows).unwrap().frames(), &FitOptions::default()).unwrap();
        for k in fit.profile.knots() {
            prop_assert!(k.components().iter().all(|c| c.abs() < 1e-6), "{:?}", k);
        }
        prop_assert!((fit.gear_factor - 1.0).abs() < 1e-9);
        let d: Pose = fit.profile.deviation(skids[n - 1] / 2.0).unwrap();
        prop_assert!(d.translation.vector.norm() < 1e-6 && d.rotation.angle() < 1e-9);
        let u = Vector3::from(fit.profile.nominal().direction);
        prop_assert!((u - truth.start.rotation * Vector3::x()).norm() < 1e-9);
    }

    #[test]
    fn profile_save_load_round_trip(knots in knot_strategy(), ext in 0usize..3) {
        let extrapolate = [Extrapolate::Error, Extrapolate::Clamp, Extrapolate::Linear][ext];
        let p = Profile::from_knots("prop", knots, extrapolate).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("profile.toml");
        p.save(&path).unwrap();
        let back = Profile::load(&path).unwrap();
        prop_assert_eq!(&back, &p);
        let (s0, s1) = p.skid_range();
        let mid = (s0 + s1) / 2.0;
        prop_assert_eq!(back.deviation_components(mid).unwrap(), p.deviation_components(mid).unwrap());
    }
}

/// `--gear recalibrated` takes the gear drift out of the profile; `as-is` keeps it along the
/// track axis (docs/design.md §3).
#[test]
fn gear_recalibrated_removes_the_drift() {
    let truth = TrackTruth::sample_r1();
    let rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.0, 1);
    let frames = identify(&rows).unwrap().frames();
    let along = |gear| {
        let opts = FitOptions {
            gear,
            ..FitOptions::default()
        };
        let fit = fit_track(&frames, &opts).unwrap();
        let axis = fit.profile.nominal().axis_in_base();
        let d = fit.profile.deviation(8000.0).unwrap().translation.vector
            - fit.profile.deviation(0.0).unwrap().translation.vector;
        (d.dot(&axis), fit.gear_factor)
    };
    let (as_is, g) = along(trackfix::track::Gear::AsIs);
    let (recal, _) = along(trackfix::track::Gear::Recalibrated);
    // Truth: gear error -1.5e-4, i.e. -1.2 mm over 8 m.
    assert!((g - (1.0 - 1.5e-4)).abs() < 2e-6, "{g}");
    assert!((as_is + 1.2).abs() < 0.02, "{as_is}");
    assert!(recal.abs() < 0.02, "{recal}");
}

/// A scan timed in seconds with `--speed` gives the same answer as the scan over skid.
#[test]
fn spectrum_of_a_timed_scan() {
    let text = std::fs::read_to_string(root().join("samples/track/scan.csv")).unwrap();
    let mut timed = String::from("t,x,y,z\n");
    for line in text.lines().skip(1) {
        let (s, rest) = line.split_once(',').unwrap();
        let t: f64 = s.parse::<f64>().unwrap() / 250.0;
        timed.push_str(&format!("{t},{rest}\n"));
    }
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("timed.csv");
    std::fs::write(&p, timed).unwrap();
    let last = |args: &[&str]| {
        let (code, out, err) = trackfix(args);
        assert_eq!(code, 0, "{err}");
        out.lines().last().unwrap_or_default().to_string()
    };
    let a = last(&[
        "track",
        "spectrum",
        "samples/track/scan.csv",
        "--threshold",
        "0.05",
    ]);
    let b = last(&[
        "track",
        "spectrum",
        p.to_str().unwrap(),
        "--threshold",
        "0.05",
        "--speed",
        "250",
    ]);
    assert_eq!(a, b);
    assert!(a.contains("970.9 mm"), "{a}");
}

/// One reading 2 mm off: a least-squares fit spreads it over the other points of its skid (the
/// old check flagged most of them); the robust fit flags exactly that one point, and says how
/// far leaving it out would move the frame.
#[test]
fn one_bad_reading_flags_that_point_only() {
    let truth = TrackTruth::sample_r1();
    let mut rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.02, 3);
    let bad = rows
        .iter_mut()
        .find(|r| r.skid == 3000.0 && r.point == 4)
        .unwrap();
    bad.meas[0] += 1.2;
    bad.meas[1] -= 1.6; // |(1.2, -1.6, 0)| = 2 mm
    let id = identify(&rows).unwrap();
    let flagged: Vec<(f64, u32)> = id.outliers.iter().map(|o| (o.skid, o.point)).collect();
    assert_eq!(flagged, [(3000.0, 4)], "{:?}", id.outliers);
    let o = id.outliers[0];
    // Against the robust fit the residual is the whole 2 mm (noise 0.02 mm per axis).
    assert!((o.residual - 2.0).abs() < 0.1, "{o:?}");
    // A plain least-squares fit leaves a tenth of the error in each of the other 9 points.
    let plain = &id.fits.iter().find(|f| f.skid == 3000.0).unwrap().fit;
    let others = plain
        .residual_norms()
        .iter()
        .zip(&id.fits[6].points)
        .filter(|(_, p)| **p != 4)
        .map(|(r, _)| *r)
        .fold(0.0, f64::max);
    assert!(others > 4.0 * id.median_residual, "{others}");
    let shift = o.shift_if_excluded.unwrap();
    assert!(shift.at_points_mm > 0.1, "{shift:?}");
    // Leaving it out gives the frame of the clean data back (within the noise).
    let clean = identify(&simulate_measurements(
        &truth,
        &skids(),
        &sample_tcp_points(),
        0.02,
        3,
    ))
    .unwrap();
    let excl = identify_excluding(
        &rows,
        &[Exclusion {
            skid: 3000.0,
            point: 4,
        }],
    )
    .unwrap();
    let f = &excl.fits[6];
    assert_eq!((f.skid, f.excluded.clone()), (3000.0, vec![4]));
    let moved = f.exclusion_shift.unwrap();
    assert!((moved.at_points_mm - shift.at_points_mm).abs() < 1e-9);
    let pts = sample_tcp_points();
    let err = pts
        .iter()
        .map(|p| (f.fit.pose * p - clean.fits[6].fit.pose * p).norm())
        .fold(0.0, f64::max);
    assert!(err < 0.03, "{err}");
    assert!(excl.outliers.is_empty(), "{:?}", excl.outliers);
    // Other tracks' noise, other skids and points, other directions of the 2 mm error.
    for (seed, skid, point, dir) in [
        (1, 3000.0, 4, [0.6, -0.8, 0.0]),
        (2, 0.0, 1, [0.0, 0.0, 1.0]),
        (4, 8000.0, 10, [1.0, 0.0, 0.0]),
        (5, 4500.0, 7, [0.0, 0.6, 0.8]),
    ] {
        let mut rows = simulate_measurements(&truth, &skids(), &sample_tcp_points(), 0.02, seed);
        let bad = rows
            .iter_mut()
            .find(|r| r.skid == skid && r.point == point)
            .unwrap();
        for (m, d) in bad.meas.iter_mut().zip(dir) {
            *m += 2.0 * d;
        }
        let flagged: Vec<(f64, u32)> = identify(&rows)
            .unwrap()
            .outliers
            .iter()
            .map(|o| (o.skid, o.point))
            .collect();
        assert_eq!(flagged, [(skid, point)], "seed {seed}");
    }
}

#[test]
fn exclude_through_the_binary() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("frames.csv");
    let out = out.to_str().unwrap();
    let (code, text, err) = trackfix(&[
        "track",
        "identify",
        "samples/track/measurements.csv",
        "-o",
        out,
        "--exclude",
        "1500:3",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("skid 1500 mm: 9 points"), "{text}");
    assert!(
        text.contains("excluded at skid 1500 mm: point(s) 3\n  effect on the frame: "),
        "{text}"
    );
    let e = error_of(&[
        "track",
        "identify",
        "samples/track/measurements.csv",
        "-o",
        out,
        "--exclude",
        "1501:3",
    ]);
    assert!(e.contains("no point 3 at skid 1501 mm to exclude"), "{e}");
    let e = error_of(&[
        "track",
        "identify",
        "samples/track/measurements.csv",
        "-o",
        out,
        "--exclude",
        "1500",
    ]);
    assert!(e.contains("write SKID:POINT"), "{e}");
}

/// Nearly collinear points: noise turns into a rotation about their line, so the fit is refused
/// with its condition number; tracker points in other units (scaled) are refused too.
#[test]
fn ill_conditioned_and_scaled_fits_are_refused() {
    let truth = pose_xyz_deg(100.0, -2300.0, 0.0, 0.0, 0.0, 90.0);
    let line: Vec<[f64; 3]> = (0..10)
        .map(|i| {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            [900.0 + 100.0 * i as f64, 3.0 * s, 800.0 + 2.0 * s]
        })
        .collect();
    let rows = |scale: f64, pts: &[[f64; 3]]| -> Vec<trackfix::track::simulate::MeasurementRow> {
        [0.0, 1000.0]
            .iter()
            .flat_map(|&skid| {
                pts.iter().enumerate().map(move |(i, p)| {
                    let q = truth * Point3::from(*p);
                    trackfix::track::simulate::MeasurementRow {
                        skid,
                        point: i as u32 + 1,
                        robot: *p,
                        meas: [q.x * scale + skid, q.y * scale, q.z * scale],
                    }
                })
            })
            .collect()
    };
    // Independent figure: the spread of the points, sqrt((λ1 + λ2) / (λ2 + λ3)).
    let c = {
        let n = line.len() as f64;
        let mean: Vector3<f64> = line.iter().map(|p| Vector3::from(*p)).sum::<Vector3<f64>>() / n;
        let s: nalgebra::Matrix3<f64> = line
            .iter()
            .map(|p| (Vector3::from(*p) - mean) * (Vector3::from(*p) - mean).transpose())
            .sum();
        let mut l: Vec<f64> = s.symmetric_eigenvalues().iter().copied().collect();
        l.sort_by(|a, b| b.total_cmp(a));
        ((l[0] + l[1]) / (l[1] + l[2])).sqrt()
    };
    assert!(c > 20.0, "{c}");
    match identify(&rows(1.0, &line)) {
        Err(TrackError::Skid {
            skid,
            problem: SkidProblem::IllConditioned { condition, limit },
        }) => {
            assert_eq!(skid, 0.0);
            assert!((condition - c).abs() < 1e-6 * c, "{condition} vs {c}");
            assert_eq!(limit, 20.0);
        }
        other => panic!("{other:?}"),
    }
    let good: Vec<[f64; 3]> = sample_tcp_points()
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    assert!(identify(&rows(1.0, &good)).is_ok());
    for scale in [1e9, 1e-3, 1.02] {
        match identify(&rows(scale, &good)) {
            Err(TrackError::Skid {
                problem: SkidProblem::Scale { ratio, .. },
                ..
            }) => assert!((ratio / scale - 1.0).abs() < 1e-9, "{ratio}"),
            other => panic!("{scale}: {other:?}"),
        }
    }
    // Frames in metres against a skid in mm: a gear factor of 0.001 is not a track.
    let frames: Vec<SamplingFrame> = (0..5)
        .map(|i| SamplingFrame {
            skid: 1000.0 * i as f64,
            pose: pose_xyz_deg(1.0 * i as f64, 0.0, 0.0, 0.0, 0.0, 0.0),
        })
        .collect();
    match fit_track(&frames, &FitOptions::default()) {
        Err(TrackError::Nominal(NominalProblem::ImplausibleGear { gear_factor, .. })) => {
            assert!((gear_factor - 1e-3).abs() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
}

/// A German spreadsheet's export: `;` between the fields and decimal commas. Read with a note,
/// to the same frames as the CSV.
#[test]
fn semicolon_and_decimal_comma_tables_are_read() {
    let text = std::fs::read_to_string(root().join("samples/track/measurements.csv")).unwrap();
    let german = text.replace(',', ";").replace('.', ",");
    let tmp = tempfile::tempdir().unwrap();
    let m = tmp.path().join("messungen.csv");
    std::fs::write(&m, &german).unwrap();
    let out = tmp.path().join("frames.csv");
    let (code, _, err) = trackfix(&[
        "track",
        "identify",
        m.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("note: ")
            && err.contains("read with `;` between the fields and `,` as the decimal point"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(root().join("samples/track/frames.csv")).unwrap()
    );
    // A bad number in such a file is located in its own column.
    let broken = german.replacen("1200,000", "1200,0x0", 1);
    let e =
        NumericCsv::parse(Path::new("m.csv"), broken.as_bytes(), &MEASUREMENTS_HEADER).unwrap_err();
    let l = e.located().unwrap();
    assert_eq!(l.line_col(), (2, 5));
    assert_eq!(l.column_name(), Some("robot_x"));
}

/// Files that are not what they were given as are not quoted; the errors of a wrong `format`,
/// a one-knot profile and a scan out of order carry `file:line:column`.
#[test]
fn located_errors_and_foreign_files() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str, text: &str| {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let clean = |s: String| s.replace(tmp.path().to_str().unwrap(), "<tmp>");
    let passwd = t(
        "passwd",
        "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n",
    );
    let p = passwd.to_str().unwrap();
    let out = tmp.path().join("o");
    let out = out.to_str().unwrap();
    let e1 = error_of(&["track", "show", p]);
    let e2 = error_of(&["track", "identify", p, "-o", out]);
    let e3 = error_of(&["track", "fit", p, "-o", out]);
    let e4 = error_of(&["track", "spectrum", p, "--threshold", "0.05"]);
    for e in [&e1, &e2, &e3, &e4] {
        assert!(!e.contains("root:x") && !e.contains("daemon"), "{e}");
    }
    let profile = std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap();
    let wrong = t(
        "wrong.toml",
        &profile.replace("trackfix-profile/1", "trackfix-profile/2"),
    );
    let e5 = error_of(&["track", "show", wrong.to_str().unwrap()]);
    let first_knot_end = profile.match_indices("[[knot]]").nth(1).unwrap().0;
    let one = t("one.toml", &profile[..first_knot_end]);
    let e6 = error_of(&["track", "show", one.to_str().unwrap()]);
    let scan = std::fs::read_to_string(root().join("samples/track/scan.csv")).unwrap();
    let swapped = scan.replacen("\n20,", "\n5,", 1);
    let s = t("scan.csv", &swapped);
    let e7 = error_of(&[
        "track",
        "spectrum",
        s.to_str().unwrap(),
        "--threshold",
        "0.05",
    ]);
    let short = t("short.csv", "skid,x,y,z\n0,0,0,0\n10,10,0,0\n");
    let e8 = error_of(&[
        "track",
        "spectrum",
        short.to_str().unwrap(),
        "--threshold",
        "0.05",
    ]);
    let all = [e1, e2, e3, e4, e5, e6, e7, e8].map(clean).join("\n");
    insta::assert_snapshot!("errors_located", all);
}

/// `--current-gear` prints the new controller value: motor turns per travel divided by the
/// measured gear factor (the sample's skid travels short, so the ratio grows).
#[test]
fn current_gear_gives_the_new_controller_value() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("profile.toml");
    let run = |current: &str| {
        let (code, text, err) = trackfix(&[
            "track",
            "fit",
            "samples/track/frames.csv",
            "-o",
            out.to_str().unwrap(),
            "--current-gear",
            current,
        ]);
        assert_eq!(code, 0, "{err}");
        text.lines()
            .find(|l| l.contains("for --current-gear"))
            .unwrap()
            .to_string()
    };
    let g = Profile::load(&root().join("samples/track/profile.toml"))
        .unwrap()
        .nominal()
        .gear_factor;
    let abb = run("1500");
    let value: f64 = abb.rsplit(' ').next().unwrap().parse().unwrap();
    assert!((value - 1500.0 / g).abs() < 1e-8, "{abb}");
    assert!(value > 1500.0);
    let kuka = run("47746/1000");
    let (n, d) = kuka
        .split_once("$RAT_MOT_AX = {N ")
        .and_then(|(_, r)| r.split_once('}'))
        .and_then(|(f, _)| f.split_once(",D "))
        .unwrap();
    let (n, d): (f64, f64) = (n.parse().unwrap(), d.parse().unwrap());
    assert!(n < 2_147_483_647.0 && d < 2_147_483_647.0);
    assert!((n / d - 47.746 / g).abs() < 1e-7, "{kuka}");
    let e = error_of(&[
        "track",
        "fit",
        "samples/track/frames.csv",
        "-o",
        out.to_str().unwrap(),
        "--current-gear",
        "1/0",
    ]);
    assert!(e.contains("write the KUKA ratio as N/D"), "{e}");
}

/// The cell against the profile's nominal: the samples agree; a track_axis along y for a track
/// along x fails the frame-independent check (direction seen from the base); a design-value base
/// fails the world check of a profile measured in the world frame.
#[test]
fn cell_is_checked_against_the_nominal() {
    let cell = Cell::load(&root().join("samples/cell.toml")).unwrap();
    for name in ["r1", "r2"] {
        let r = cell.robot(name).unwrap();
        let p = Profile::load(&r.profile).unwrap();
        let c = check_cell_nominal(&r.base0, &r.track_axis, &p).unwrap();
        let w = c.world.unwrap();
        // The sample cell holds the fitted nominal to 3 decimals (mm) and 6 (deg).
        assert!(w.base_position_mm < 0.002, "{name}: {c:?}");
        assert!(
            c.axis_in_base_deg < 1e-3 && w.axis_deg < 1e-3,
            "{name}: {c:?}"
        );
    }
    let r1 = cell.robot("r1").unwrap();
    let p = Profile::load(&r1.profile).unwrap();
    let e = check_cell_nominal(&r1.base0, &Vector3::y(), &p).unwrap_err();
    assert!(matches!(
        e.disagreements[0],
        Disagreement::AxisInBase { angle_deg } if (angle_deg - 90.0).abs() < 0.01
    ));
    // Without knowing the measurement frame only the direction in the base is compared: a
    // base moved by 1.7 mm passes, a wrong axis does not.
    let tracker = p.clone().with_measured_in(MeasuredIn::Tracker);
    let design = pose_xyz_deg(0.0, -3500.0, 0.0, 0.0, 0.0, 90.0);
    let c = check_cell_nominal(&design, &Vector3::x(), &tracker).unwrap();
    assert!(c.world.is_none());
    assert!(check_cell_nominal(&design, &Vector3::y(), &tracker).is_err());
    let e = check_cell_nominal(&design, &Vector3::x(), &p).unwrap_err();
    let found: Vec<String> = e.disagreements.iter().map(|d| d.to_string()).collect();
    // |(0.016, -3499.087, -1.496) - (0, -3500, 0)| = 1.753 mm.
    assert!(
        matches!(e.disagreements[0], Disagreement::BasePosition { distance_mm } if (distance_mm - 1.7532).abs() < 1e-3),
        "{found:?}"
    );
    assert!(e.to_string().contains("tolerance 0.1 mm"), "{e}");
}

/// `track fit --cell C --robot R` writes the fitted nominal into the cell: only `base` and
/// `track_axis` of that robot change, comments and layout stay, and the result passes the check.
#[test]
fn fit_writes_the_nominal_into_the_cell() {
    let tmp = tempfile::tempdir().unwrap();
    let original = std::fs::read_to_string(root().join("samples/cell.toml")).unwrap();
    let design = original
        .replace(
            "base = { x = 0.016, y = -3499.087, z = -1.496, rx = 0.000412, ry = -0.000064, rz = 90.000710 }",
            "base = { x = 0, y = -3500, z = 0, rx = 0, ry = 0, rz = 90 }",
        )
        .replace(
            "track_axis = [1.0, -0.0000032, 0.0000014]",
            "track_axis = [0, 1, 0]",
        );
    assert_ne!(design, original);
    let cell = tmp.path().join("cell.toml");
    std::fs::write(&cell, &design).unwrap();
    let profile = tmp.path().join("profile.toml");
    let (code, out, err) = trackfix(&[
        "track",
        "fit",
        "samples/track/frames.csv",
        "-o",
        profile.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r1",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("[robot.r1] (the rest of the file unchanged)"),
        "{out}"
    );
    let written = std::fs::read_to_string(&cell).unwrap();
    let changed: Vec<(&str, &str)> = design
        .lines()
        .zip(written.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(design.lines().count(), written.lines().count());
    assert_eq!(changed.len(), 2, "{changed:?}");
    assert!(
        changed[0]
            .1
            .starts_with("base = { x = 0.0157, y = -3499.0871, z = -1.4958, rx = 0.000412"),
        "{changed:?}"
    );
    assert!(
        changed[1]
            .1
            .starts_with("track_axis = [1.0, -0.000003206, 0.000001369]  # unit direction"),
        "{changed:?}"
    );
    let p = Profile::load(&profile).unwrap();
    assert_eq!(p.measured_in(), Some(MeasuredIn::World));
    let c = Cell::load(&cell).unwrap();
    let r = c.robot("r1").unwrap();
    check_cell_nominal(&r.base0, &r.track_axis, &p).unwrap();
    let e = error_of(&[
        "track",
        "fit",
        "samples/track/frames.csv",
        "-o",
        profile.to_str().unwrap(),
        "--cell",
        cell.to_str().unwrap(),
        "--robot",
        "r9",
    ]);
    assert!(e.contains("no [robot.r9] table"), "{e}");
}

/// A profile edited by hand (a knot's value) disagrees with its own [stats] and hash: a
/// warning; editing the extrapolation rule, as the out-of-range message suggests, is not.
#[test]
fn hand_edited_profile_is_a_warning() {
    let text = std::fs::read_to_string(root().join("samples/track/profile.toml")).unwrap();
    let p = Profile::from_toml_str(&text, Path::new("p.toml")).unwrap();
    assert!(p.consistency_warnings().is_empty());
    let clamp = text.replace("extrapolate = \"error\"", "extrapolate = \"clamp\"");
    let p = Profile::from_toml_str(&clamp, Path::new("p.toml")).unwrap();
    assert!(p.consistency_warnings().is_empty());
    let edited = text.replacen("dz = 1.589099", "dz = 2.589099", 1);
    assert_ne!(edited, text);
    let p = Profile::from_toml_str(&edited, Path::new("p.toml")).unwrap();
    let w = p.consistency_warnings();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w[0].contains("data_sha256 does not match"), "{w:?}");
    assert!(w[1].contains("[stats] are not those of its knots"), "{w:?}");
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("edited.toml");
    std::fs::write(&f, &edited).unwrap();
    let (code, _, err) = trackfix(&["track", "show", f.to_str().unwrap(), "--at", "0"]);
    assert_eq!(code, 0);
    assert_eq!(err.matches("warning: ").count(), 2, "{err}");
}

/// A tracker's point export (German spreadsheet style, extra columns) through `track import`
/// with `--map`: the points come out as point,x,y,z, and the command says how it read the file.
#[test]
fn tracker_export_is_imported_with_a_map() {
    let tmp = tempfile::tempdir().unwrap();
    let export = tmp.path().join("export.csv");
    std::fs::write(
        &export,
        "Nr;Punkt;Zeit;Ost;Nord;Hoehe\n1;M1;12:00;1670,3;-1850,75;612,4\n2;M2;12:01;2670,25;-1850,5;612\n",
    )
    .unwrap();
    let out = tmp.path().join("marks.csv");
    let (code, text, err) = trackfix(&[
        "track",
        "import",
        export.to_str().unwrap(),
        "--map",
        "name=Punkt,x=Ost,y=Nord,z=Hoehe",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains("2 point(s), fields separated by `;` with `,` as the decimal point, a header line; name, x, y, z in columns 2, 4, 5, 6"),
        "{text}"
    );
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "point,x,y,z\nM1,1670.3000,-1850.7500,612.4000\nM2,2670.2500,-1850.5000,612.0000\n"
    );
    let e = error_of(&[
        "track",
        "import",
        "/etc/passwd",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!e.contains("daemon") && !e.contains("root:"), "{e}");
}

/// A profile sampled too sparsely to show the track between its knots says so wherever it is
/// used (`track fit`, `track show`, the transforms): fewer than four knots, or knots more than
/// 2000 mm apart. Before, two knots 8 m apart gave "straightness 0.0000 mm" and a `u` that
/// claimed to cover the interpolation, 130 u from a 1.2 mm sag. Rows of `track show` beyond the
/// measured skids are marked as extrapolated.
#[test]
fn sparse_knots_and_extrapolated_rows_are_said() {
    let text = std::fs::read_to_string(root().join("samples/track/frames.csv")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let fit = |name: &str, skids: &[&str], extra: &[&str]| {
        let frames = tmp.path().join(format!("{name}.csv"));
        let kept: Vec<&str> = text
            .lines()
            .enumerate()
            .filter(|(i, l)| *i == 0 || skids.contains(&l.split(',').next().unwrap()))
            .map(|(_, l)| l)
            .collect();
        std::fs::write(&frames, kept.join("\n") + "\n").unwrap();
        let out = tmp.path().join(format!("{name}.toml"));
        let (f, o) = (frames.display().to_string(), out.display().to_string());
        let mut args = vec!["track", "fit", f.as_str(), "-o", o.as_str()];
        args.extend(extra);
        let (code, _, err) = trackfix(&args);
        assert_eq!(code, 0, "{err}");
        (o, err)
    };
    let (three, err) = fit("three", &["0", "4000", "8000"], &[]);
    assert!(
        err.contains("3 knots: the deviation between them is not measured"),
        "{err}"
    );
    // The sample's frames with `columns` rewritten by `f`, fitted: (exit code, standard error).
    let fit_rewritten =
        |name: &str, columns: std::ops::RangeInclusive<usize>, f: fn(f64) -> f64| {
            let rewritten: String = text
                .lines()
                .enumerate()
                .map(|(i, l)| {
                    if i == 0 {
                        return format!("{l}\n");
                    }
                    let cells: Vec<String> = l
                        .split(',')
                        .enumerate()
                        .map(|(c, v)| match columns.contains(&c) {
                            true => f(v.parse::<f64>().unwrap()).to_string(),
                            false => v.to_owned(),
                        })
                        .collect();
                    cells.join(",") + "\n"
                })
                .collect();
            let frames = tmp.path().join(format!("{name}.csv"));
            std::fs::write(&frames, rewritten).unwrap();
            let out = tmp.path().join(format!("{name}.toml"));
            let (code, _, err) = trackfix(&[
                "track",
                "fit",
                frames.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ]);
            (code, err)
        };
    // Skids and positions written in metres: the whole track 8 mm long.
    let (_, err) = fit_rewritten("metres", 0..=3, |v| v / 1000.0);
    assert!(err.contains("its skids span 0 .. 8 mm"), "{err}");
    // Angles written in radians: the base's rz of 90° read as 1.5708°.
    let (code, err) = fit_rewritten("radians", 4..=6, f64::to_radians);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("its nominal's rz is 1.5708°"), "{err}");
    assert!(err.contains("(were they written in radians?)"), "{err}");
    let (_, err) = fit("wide", &["0", "2500", "5000", "6000", "8000"], &[]);
    assert!(err.contains("knots up to 2500 mm apart"), "{err}");
    let every_1000: Vec<String> = (0..=8).map(|k| (k * 1000).to_string()).collect();
    let every_1000: Vec<&str> = every_1000.iter().map(String::as_str).collect();
    let (dense, err) = fit("dense", &every_1000, &["--extrapolate", "linear"]);
    assert!(!err.contains("warning"), "{err}");
    let (code, _, err) = trackfix(&["track", "show", &three, "--at", "2000"]);
    assert_eq!(code, 0);
    assert!(err.contains("3 knots"), "{err}");
    let (code, out, _) = trackfix(&["track", "show", &dense, "--at", "4000", "--at", "9000"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("\n      4000 ") && out.contains("\n     9000* "),
        "{out}"
    );
    assert!(
        out.contains("*: outside the measured skids 0 .. 8000 mm: extrapolated (linear)"),
        "{out}"
    );
}
