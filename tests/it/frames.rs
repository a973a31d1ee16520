//! Frames (base, work object, tool, point pairs) and the uncertainty of profiles, on simulated
//! cells whose truth is known.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, Point3, Vector3};
use trackfix::frame::base::{fit_base, tcp_error};
use trackfix::frame::pairs::fit_pairs;
use trackfix::frame::tool::fit_tool;
use trackfix::frame::wobj::fit_wobj;
use trackfix::geometry::{Pose, pose_to_xyz_deg, pose_xyz_deg, wrap_deg};
use trackfix::track::Profile;
use trackfix::track::identify::identify;
use trackfix::track::nominal::{FitOptions, fit_track};
use trackfix::track::simulate::{
    SplitMix64, TrackTruth, sample_tcp_points, simulate_marks, simulate_measurements,
    simulate_pivot,
};
use trackfix::track::uncertainty::{ProfileUncertainty, knot_uncertainties, tcp_uncertainty};
use trackfix::transform::TrackSetup;

/// Identify → fit → knot uncertainties for a simulated track sampled every `spacing` mm.
fn profile_of(truth: &TrackTruth, spacing: f64, noise: f64, seed: u64) -> Profile {
    let n = (truth.length_mm / spacing).round() as usize;
    let skids: Vec<f64> = (0..=n).map(|i| i as f64 * spacing).collect();
    let rows = simulate_measurements(truth, &skids, &sample_tcp_points(), noise, seed);
    let ident = identify(&rows).unwrap();
    let fit = fit_track(&ident.frames(), &FitOptions::default()).unwrap();
    let (u, _) = knot_uncertainties(&rows, &ident, None).unwrap();
    fit.profile.with_knot_uncertainties(&u).unwrap()
}

/// The tracker stood here (in world) while it measured the track profile: the profile's
/// deviations are local, so they hold in the cell although the nominal is in tracker axes.
fn tracker_in_world() -> Pose {
    pose_xyz_deg(4200.0, 1500.0, -900.0, 0.4, -0.3, 137.0)
}

fn in_tracker(truth: &TrackTruth) -> TrackTruth {
    TrackTruth {
        start: tracker_in_world().inverse() * truth.start,
        ..*truth
    }
}

/// `D̂(s) - D_true(s)` per component, `D_true = N̂(s)⁻¹·truth(s)` (deviations are relative to
/// the fitted nominal).
fn true_error(p: &Profile, truth: &TrackTruth, s: f64) -> [f64; 6] {
    let est = p.deviation_components(s).unwrap();
    let t = pose_to_xyz_deg(&(p.nominal_frame(s).inverse() * truth.base_frame(s)));
    let mut e = [0.0; 6];
    for c in 0..6 {
        e[c] = if c < 3 {
            est[c] - t[c]
        } else {
            wrap_deg(est[c] - t[c])
        };
    }
    e
}

/// Fraction of held-out (skid, component) pairs whose true error lies within 2u, and the
/// fraction of held-out (skid, TCP point, axis) whose TCP error lies within 2u of
/// `tcp_uncertainty`.
fn coverage(tracks: u64, spacing: f64, held_out: usize, seed0: u64) -> (f64, f64) {
    let (mut inside, mut total, mut tcp_in, mut tcp_total) = (0, 0, 0, 0);
    for k in 0..tracks {
        let truth = TrackTruth::random(
            pose_xyz_deg(0.0, -3500.0, 0.0, 0.0, 0.0, 90.0),
            8000.0,
            seed0 + k,
        );
        // A negative spacing means "this many knots per wavelength of the rail's waviness".
        let spacing = if spacing < 0.0 {
            8000.0 / (8000.0 * -spacing / truth.deformation.wave_length_mm).ceil()
        } else {
            spacing
        };
        let p = profile_of(&truth, spacing, 0.02, 100 + seed0 + k);
        let pu = ProfileUncertainty::new(&p).unwrap().unwrap();
        let mut rng = SplitMix64::new(7 + k);
        for _ in 0..held_out {
            let s = 8000.0 * rng.next_f64();
            let e = true_error(&p, &truth, s);
            let u = pu.at(s).unwrap();
            for (ec, uc) in e.iter().zip(&u.u) {
                total += 1;
                inside += usize::from(ec.abs() <= 2.0 * uc);
            }
            // The TCP 1.5 m in front of the robot: modelled against true base.
            let r = Vector3::new(1500.0, 300.0, 900.0);
            let model = p.base_frame(s).unwrap() * Point3::from(r);
            let real = truth.base_frame(s) * Point3::from(r);
            let err = p
                .base_frame(s)
                .unwrap()
                .inverse_transform_vector(&(model - real));
            let tu = pu.tcp_at(s, &r).unwrap();
            // The diagonal-only figure may only err on the safe side.
            let plain = tcp_uncertainty(&u, &r);
            for a in 0..3 {
                tcp_total += 1;
                tcp_in += usize::from(err[a].abs() <= 2.0 * tu.u[a]);
                assert!(plain.u[a] >= tu.u[a] * 0.999, "{plain:?} vs {tu:?}");
            }
        }
    }
    (
        inside as f64 / total as f64,
        tcp_in as f64 / tcp_total as f64,
    )
}

#[test]
fn profile_uncertainty_is_calibrated() {
    // 4 random tracks × 30 held-out skids × 6 components, sampled every 500 mm and 1000 mm
    // (the spacings `track spectrum` recommends for their waviness).
    for spacing in [500.0, 1000.0] {
        let (c, tcp) = coverage(4, spacing, 30, 11);
        assert!(
            (0.90..=0.99).contains(&c),
            "spacing {spacing}: coverage {c:.3}"
        );
        assert!(
            (0.90..=0.99).contains(&tcp),
            "spacing {spacing}: TCP coverage {tcp:.3}"
        );
    }
}

#[test]
#[allow(clippy::print_stderr)] // the figures for the README
#[ignore = "long: 20 tracks per spacing; run with --ignored"]
fn profile_uncertainty_is_calibrated_over_many_tracks() {
    // 500, 750, 1000 mm; then 2 (what `track spectrum` recommends, 1/(2f)), 3 and 4 knots per
    // wavelength of each track's waviness.
    for spacing in [500.0, 750.0, 1000.0, -2.0, -3.0, -4.0] {
        let (c, tcp) = coverage(20, spacing, 30, 1000);
        eprintln!("spacing {spacing} mm: coverage of 2u {c:.3}, TCP {tcp:.3}");
        assert!(
            (0.90..=0.99).contains(&c),
            "spacing {spacing}: coverage {c:.3}"
        );
        assert!(
            (0.90..=0.99).contains(&tcp),
            "spacing {spacing}: TCP coverage {tcp:.3}"
        );
    }
}

/// Base points: 7 TCP points at each of 5 skids, measured in world with 0.02 mm noise.
fn base_points(truth: &TrackTruth, seed: u64) -> Vec<trackfix::track::simulate::MeasurementRow> {
    let pts: Vec<Point3<f64>> = sample_tcp_points().into_iter().take(7).collect();
    simulate_measurements(
        truth,
        &[400.0, 2100.0, 3900.0, 5600.0, 7300.0],
        &pts,
        0.02,
        seed,
    )
}

#[test]
fn base_with_track_compensation_reaches_the_noise_level() {
    let truth = TrackTruth::sample_r1();
    let profile = profile_of(&in_tracker(&truth), 500.0, 0.02, 5);
    let rows = base_points(&truth, 6);
    let skids: Vec<f64> = (0..=32).map(|i| i as f64 * 250.0).collect();
    let tcp = sample_tcp_points();
    let real = |s: f64| truth.base_frame(s);

    let comp = fit_base(&rows, Some(&profile), None).unwrap();
    // The base the controller should have: the profile's nominal, carried from the tracker
    // into world. Its error at the TCP over the whole track is the identification's.
    let ideal_b0 = tracker_in_world() * profile.nominal_frame(0.0);
    let ideal_axis = tracker_in_world().rotation * Vector3::from(profile.nominal().direction);
    let ideal = |s: f64| {
        nalgebra::Translation3::from(ideal_axis * s) * ideal_b0 * profile.deviation(s).unwrap()
    };
    let base_err = tcp_error(&comp, Some(&profile), &ideal, &skids, &tcp).unwrap();
    assert!(
        base_err <= 0.05,
        "compensated base error at the TCP {base_err:.4} mm"
    );
    let d = ideal_b0.inverse() * comp.base0;
    assert!(d.translation.vector.norm() < 0.05, "{d:?}");
    assert!(d.rotation.angle().to_degrees() < 0.002, "{d:?}");
    assert!(
        (ideal_axis - comp.track_axis).norm() < 2e-5,
        "{ideal_axis} vs {}",
        comp.track_axis
    );
    // Against the real track the profile's own error adds (its knots carry the same 0.02 mm
    // tracker noise).
    let err = tcp_error(&comp, Some(&profile), &real, &skids, &tcp).unwrap();
    assert!(err <= 0.08, "compensated TCP error {err:.4} mm");
    // Residuals at the noise level: |3D noise| of 0.02 mm per axis has rms 0.035 mm.
    assert!(comp.rms < 0.05, "compensated rms {:.4}", comp.rms);
    assert!(
        (comp.sigma.value() - 0.02).abs() < 0.008,
        "{:?}",
        comp.sigma
    );

    let plain = fit_base(&rows, None, None).unwrap();
    let err_plain = tcp_error(&plain, None, &real, &skids, &tcp).unwrap();
    assert!(
        err_plain >= 0.3,
        "uncompensated TCP error {err_plain:.4} mm"
    );
    let base_err_plain = tcp_error(&plain, None, &ideal, &skids, &tcp).unwrap();
    assert!(
        base_err_plain >= 0.3,
        "uncompensated base error {base_err_plain:.4} mm"
    );
    assert!(plain.rms >= 0.3, "uncompensated rms {:.4}", plain.rms);
    // The uncertainty follows: the uncompensated fit's residuals are the track's shape.
    assert!(plain.u_point > 5.0 * comp.u_point);
}

#[test]
fn base_uncertainty_is_calibrated() {
    // 150 noisy identifications of the base of a straight track: each of x, y, z, rx, ry, rz
    // of B0 lies within 2u of the truth for 90-99 % of them.
    let start = pose_xyz_deg(0.0, -3500.0, 0.0, 0.0, 0.0, 90.0);
    let truth = TrackTruth::straight(start, 8000.0);
    let want = pose_to_xyz_deg(&start);
    let (mut inside, mut total) = (0, 0);
    for seed in 0..150 {
        let fit = fit_base(&base_points(&truth, 2000 + seed), None, None).unwrap();
        let got = pose_to_xyz_deg(&fit.base0);
        for c in 0..6 {
            total += 1;
            let e = if c < 3 {
                got[c] - want[c]
            } else {
                wrap_deg(got[c] - want[c])
            };
            inside += usize::from(e.abs() <= 2.0 * fit.u_base.u[c]);
        }
    }
    let cov = inside as f64 / total as f64;
    assert!((0.90..=0.99).contains(&cov), "{cov}");
}

#[test]
fn compensated_base_uncertainty_covers_the_profiles_error() {
    // The profile is re-measured for every identification: the base's 2u covers the truth
    // (the profile's nominal, carried into world) in at least 90 % of the components. It errs
    // on the safe side: the residual-based σ̂ holds part of the profile's error already, and
    // the profile's interpolation part is conservative for this track (4 knots per wavelength
    // of its waviness). Without the profile's covariance it is about 91 %.
    let truth = TrackTruth::sample_r1();
    let (mut inside, mut total) = (0, 0);
    for seed in 0..24 {
        let profile = profile_of(&in_tracker(&truth), 500.0, 0.02, 300 + seed);
        let fit = fit_base(&base_points(&truth, 700 + seed), Some(&profile), None).unwrap();
        let ideal = pose_to_xyz_deg(&(tracker_in_world() * profile.nominal_frame(0.0)));
        let got = pose_to_xyz_deg(&fit.base0);
        for c in 0..6 {
            total += 1;
            let e = if c < 3 {
                got[c] - ideal[c]
            } else {
                wrap_deg(got[c] - ideal[c])
            };
            inside += usize::from(e.abs() <= 2.0 * fit.u_base.u[c]);
        }
    }
    let cov = inside as f64 / total as f64;
    assert!(cov >= 0.90, "{cov}");
}

fn fixture() -> (Pose, Vec<Point3<f64>>, Vec<f64>) {
    let wobj = pose_xyz_deg(1670.3, -1850.75, 612.4, 0.12, -0.2, 1.5);
    let cad: Vec<Point3<f64>> = [
        [-1500.0, -600.0, 0.0],
        [-700.0, 700.0, 150.0],
        [0.0, -650.0, 420.0],
        [600.0, 600.0, 0.0],
        [1300.0, -500.0, 300.0],
        [1600.0, 550.0, 600.0],
    ]
    .into_iter()
    .map(Point3::from)
    .collect();
    // The robot drives along to each mark.
    let skids = vec![800.0, 1400.0, 2300.0, 2900.0, 3600.0, 4100.0];
    (wobj, cad, skids)
}

#[test]
fn work_object_with_track_compensation() {
    let truth = TrackTruth::sample_r1();
    let profile = profile_of(&truth, 500.0, 0.02, 8);
    let (wobj, cad, skids) = fixture();
    let rows = simulate_marks(&truth, &wobj, &cad, &skids, 0.02, 9);
    let n0 = profile.nominal_frame(0.0);
    let setup = TrackSetup {
        base0: n0,
        track_axis: Vector3::from(profile.nominal().direction),
        skid_axis: 0,
        frames: BTreeMap::new(),
        deviation: &profile,
        default_wobj: None,
        uncertainty: None,
        arm: None,
        robot: None,
    };
    let pu = ProfileUncertainty::new(&profile).unwrap();
    let fit = fit_wobj(&rows, &setup, pu.as_ref(), None).unwrap();
    let worst = cad
        .iter()
        .map(|c| (fit.wobj * c - wobj * c).norm())
        .fold(0.0, f64::max);
    assert!(
        worst <= 0.06,
        "work object error at the marks {worst:.4} mm"
    );
    assert!(fit.rms < 0.06, "{}", fit.rms);

    let identity = |_s: f64| Ok(Pose::identity());
    let plain_setup = TrackSetup {
        deviation: &identity,
        ..setup
    };
    let plain = fit_wobj(&rows, &plain_setup, None, None).unwrap();
    let worst_plain = cad
        .iter()
        .map(|c| (plain.wobj * c - wobj * c).norm())
        .fold(0.0, f64::max);
    assert!(worst_plain >= 0.3, "uncompensated {worst_plain:.4} mm");
}

#[test]
fn work_object_uncertainty_is_calibrated() {
    // 200 noisy touch-ups of one fixture on a straight track: the error of each of x, y, z,
    // rx, ry, rz lies within 2u for 90-99 % of them.
    let truth = TrackTruth::straight(pose_xyz_deg(0.0, -3500.0, 0.0, 0.0, 0.0, 90.0), 8000.0);
    let (wobj, cad, skids) = fixture();
    let identity = |_s: f64| Ok(Pose::identity());
    let setup = TrackSetup {
        base0: truth.start,
        track_axis: truth.start.rotation * Vector3::x(),
        skid_axis: 0,
        frames: BTreeMap::new(),
        deviation: &identity,
        default_wobj: None,
        uncertainty: None,
        arm: None,
        robot: None,
    };
    let want = pose_to_xyz_deg(&wobj);
    let (mut inside, mut total) = (0, 0);
    for seed in 0..200 {
        let rows = simulate_marks(&truth, &wobj, &cad, &skids, 0.05, 500 + seed);
        let fit = fit_wobj(&rows, &setup, None, None).unwrap();
        let got = pose_to_xyz_deg(&fit.wobj);
        for c in 0..6 {
            total += 1;
            inside += usize::from((got[c] - want[c]).abs() <= 2.0 * fit.u_wobj.u[c]);
        }
    }
    let cov = inside as f64 / total as f64;
    assert!((0.90..=0.99).contains(&cov), "{cov}");
}

/// The TCP by another method: differences of pose pairs eliminate the point,
/// `(R_i - R_j)·t = p_j - p_i`, solved by SVD.
fn tcp_by_differences(poses: &[Pose]) -> Vector3<f64> {
    let n = poses.len();
    let m = n * (n - 1) / 2;
    let mut a = DMatrix::<f64>::zeros(3 * m, 3);
    let mut b = DVector::<f64>::zeros(3 * m);
    let mut row = 0;
    for i in 0..n {
        for j in i + 1..n {
            let d = poses[i].rotation.to_rotation_matrix().into_inner()
                - poses[j].rotation.to_rotation_matrix().into_inner();
            let rhs = poses[j].translation.vector - poses[i].translation.vector;
            for k in 0..3 {
                for l in 0..3 {
                    a[(row + k, l)] = d[(k, l)];
                }
                b[row + k] = rhs[k];
            }
            row += 3;
        }
    }
    let x = a.svd(true, true).solve(&b, 1e-12).unwrap();
    Vector3::new(x[0], x[1], x[2])
}

#[test]
fn tcp_from_nine_pivot_poses() {
    let tcp = Vector3::new(12.5, -3.2, 215.0);
    let point = Point3::new(1400.0, 200.0, 600.0);
    let poses = simulate_pivot(&tcp, &point, 9, 0.02, 3);
    let fit = fit_tool(&poses, None).unwrap();
    assert!((fit.tcp - tcp).norm() <= 0.1, "{}", (fit.tcp - tcp).norm());
    assert!((fit.point - point).norm() <= 0.1);
    let other = tcp_by_differences(&poses);
    assert!((other - fit.tcp).norm() < 0.05, "{other} vs {}", fit.tcp);
    // Exact poses: both methods give the TCP to rounding.
    let exact = simulate_pivot(&tcp, &point, 9, 0.0, 3);
    let f = fit_tool(&exact, Some(0.0)).unwrap();
    assert!((f.tcp - tcp).norm() < 1e-9 && f.max < 1e-9);
    assert!((tcp_by_differences(&exact) - tcp).norm() < 1e-7);
    // The residuals are at the noise level, and so is the mean error a controller shows.
    assert!(fit.mean < 0.05 && fit.max < 0.1, "{} {}", fit.mean, fit.max);
}

#[test]
fn tcp_uncertainty_is_calibrated() {
    let tcp = Vector3::new(12.5, -3.2, 215.0);
    let point = Point3::new(1400.0, 200.0, 600.0);
    let (mut inside, mut total) = (0, 0);
    for seed in 0..300 {
        let poses = simulate_pivot(&tcp, &point, 9, 0.02, 1000 + seed);
        let fit = fit_tool(&poses, None).unwrap();
        for a in 0..3 {
            total += 1;
            inside += usize::from((fit.tcp[a] - tcp[a]).abs() <= 2.0 * fit.u_tcp[a]);
        }
    }
    let cov = inside as f64 / total as f64;
    assert!((0.90..=0.99).contains(&cov), "{cov}");
}

#[test]
fn point_pairs_reject_a_bad_mark() {
    let t = pose_xyz_deg(-2500.0, 800.0, 150.0, 0.05, -0.1, -63.0);
    let mut rng = SplitMix64::new(21);
    let marks: Vec<Point3<f64>> = (0..8)
        .map(|i| {
            let a = i as f64 * 0.8;
            Point3::new(3000.0 * a.cos(), 2500.0 * a.sin(), 200.0 * (i % 3) as f64)
        })
        .collect();
    let nominal: BTreeMap<u32, Point3<f64>> = marks
        .iter()
        .enumerate()
        .map(|(i, p)| (i as u32 + 1, *p))
        .collect();
    let mut measured: BTreeMap<u32, Point3<f64>> = marks
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * 0.01;
            (i as u32 + 1, t.inverse() * p + n)
        })
        .collect();
    // Mark 5 was knocked by 2 mm; mark 9 exists only in the tracker file.
    *measured.get_mut(&5).unwrap() += Vector3::new(2.0, 0.0, 0.0);
    measured.insert(9, Point3::origin());
    let fit = fit_pairs(&nominal, &measured, Some(4.0), None).unwrap();
    assert_eq!(
        fit.rejected.iter().map(|r| r.point).collect::<Vec<_>>(),
        [5]
    );
    assert!((fit.rejected[0].norm() - 2.0).abs() < 0.05);
    assert_eq!(fit.unpaired, (vec![], vec![9]));
    assert!(fit.rms < 0.03, "{}", fit.rms);
    for p in &marks {
        assert!((fit.pose * (t.inverse() * p) - p).norm() < 0.03);
    }
    let kept = fit_pairs(&nominal, &measured, None, None).unwrap();
    assert!(kept.rejected.is_empty() && kept.rms > 0.5);
}

mod cli {
    use crate::support::{root, trackfix};

    fn ok(args: &[&str]) -> String {
        let (code, out, err) = trackfix(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        out
    }

    #[test]
    fn samples_are_reproducible() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().to_str().unwrap();
        ok(&["frame", "simulate", "--out-dir", d]);
        for f in [
            "base_points.csv",
            "marks.csv",
            "flange.csv",
            "flange_abc.csv",
            "marks_nominal.csv",
            "marks_tracker.csv",
        ] {
            let made = std::fs::read_to_string(dir.path().join(f)).unwrap();
            let committed = std::fs::read_to_string(root().join("samples/frames").join(f)).unwrap();
            assert_eq!(made, committed, "{f}");
        }
        let profile = dir.path().join("profile.toml");
        ok(&[
            "track",
            "fit",
            "samples/track/frames.csv",
            "-o",
            profile.to_str().unwrap(),
            "--name",
            "r1",
            "--measurements",
            "samples/track/measurements.csv",
        ]);
        assert_eq!(
            std::fs::read_to_string(&profile).unwrap(),
            std::fs::read_to_string(root().join("samples/frames/profile.toml")).unwrap()
        );
    }

    #[test]
    fn a_given_noise_level_scales_the_knot_uncertainties() {
        let dir = tempfile::tempdir().unwrap();
        let given = dir.path().join("given.toml");
        let out = ok(&[
            "track",
            "fit",
            "samples/track/frames.csv",
            "-o",
            given.to_str().unwrap(),
            "--measurements",
            "samples/track/measurements.csv",
            "--sigma",
            "0.04",
        ]);
        assert!(out.contains("0.0400 mm per axis (given)"), "{out}");
        let est =
            trackfix::track::Profile::load(&root().join("samples/frames/profile.toml")).unwrap();
        let giv = trackfix::track::Profile::load(&given).unwrap();
        // The sample's pooled estimate is 0.0203 mm: a given 0.04 mm scales every u by 0.04/0.0203.
        let sigma_est = 0.0203;
        for (a, b) in est.knots().iter().zip(giv.knots()) {
            let (ua, ub) = (a.uncertainty().unwrap(), b.uncertainty().unwrap());
            for (x, y) in ua.iter().zip(ub) {
                assert!(
                    (y / x - 0.04 / sigma_est).abs() < 0.01 * 0.04 / sigma_est + 2e-6 / x,
                    "{x} {y}"
                );
            }
        }
    }

    #[test]
    fn base_outputs() {
        let args = [
            "frame",
            "base",
            "samples/frames/base_points.csv",
            "--profile",
            "samples/frames/profile.toml",
        ];
        insta::assert_snapshot!("frame_base", ok(&args));
        let mut json = args.to_vec();
        json.extend(["--format", "json"]);
        let text = ok(&json);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["residuals"].as_array().unwrap().len(), 35);
        insta::assert_snapshot!("frame_base_json", text);
        insta::assert_snapshot!(
            "frame_base_uncompensated",
            ok(&["frame", "base", "samples/frames/base_points.csv"])
        );
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("base.toml");
        let mut with_o = args.to_vec();
        with_o.extend(["-o", out.to_str().unwrap()]);
        ok(&with_o);
        let toml_text = std::fs::read_to_string(&out).unwrap();
        insta::assert_snapshot!("frame_base_toml", toml_text);
        // What -o writes is what samples/frames/cell.toml carries.
        let cell = std::fs::read_to_string(root().join("samples/frames/cell.toml")).unwrap();
        for line in toml_text.lines().filter(|l| !l.starts_with('#')) {
            assert!(cell.contains(line), "{line}");
        }
    }

    #[test]
    fn wobj_tool_and_pair_outputs() {
        let wobj = [
            "frame",
            "wobj",
            "samples/frames/marks.csv",
            "--cell",
            "samples/frames/cell.toml",
            "--robot",
            "r1",
        ];
        insta::assert_snapshot!("frame_wobj", ok(&wobj));
        let mut json = wobj.to_vec();
        json.extend(["--format", "json"]);
        insta::assert_snapshot!("frame_wobj_json", ok(&json));
        let mut plain = wobj.to_vec();
        plain.push("--no-compensation");
        insta::assert_snapshot!("frame_wobj_uncompensated", ok(&plain));
        let tool = ok(&["frame", "tool", "samples/frames/flange.csv"]);
        insta::assert_snapshot!("frame_tool", tool);
        // KUKA A, B, C give the same TCP (to the written 4 decimals of the angles).
        let abc = ok(&[
            "frame",
            "tool",
            "samples/frames/flange_abc.csv",
            "--format",
            "json",
        ]);
        insta::assert_snapshot!("frame_tool_abc_json", abc);
        insta::assert_snapshot!(
            "frame_fit",
            ok(&[
                "frame",
                "fit",
                "samples/frames/marks_nominal.csv",
                "samples/frames/marks_tracker.csv",
            ])
        );
    }

    /// Hamilton product of scalar-first quaternions, written out here.
    fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    }

    #[test]
    fn wobj_literals_follow_the_controllers_conventions() {
        let json = ok(&[
            "frame",
            "wobj",
            "samples/frames/marks.csv",
            "--cell",
            "samples/frames/cell.toml",
            "--robot",
            "r1",
            "--name",
            "wobj_car",
            "--base-index",
            "3",
            "--format",
            "json",
        ]);
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        let w = |k: &str| v["wobj"][k].as_f64().unwrap();
        let numbers = |text: &str| -> Vec<f64> {
            text.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
                .filter_map(|t| t.parse().ok())
                .collect()
        };
        // KUKA: A, B, C = Rz·Ry·Rx, the same order as rx, ry, rz: A = rz, B = ry, C = rx.
        let kuka = v["kuka"].as_str().unwrap();
        assert!(kuka.starts_with("BASE_DATA[3]={X "), "{kuka}");
        let k = numbers(kuka.trim_start_matches("BASE_DATA[3]"));
        for (got, want) in k
            .iter()
            .zip([w("x"), w("y"), w("z"), w("rz"), w("ry"), w("rx")])
        {
            assert!((got - want).abs() < 6e-4, "{kuka} vs {v}");
        }
        // RAPID: q = qz·qy·qx from half angles, scalar first.
        let half = |deg: f64| (deg.to_radians() / 2.0).sin_cos();
        let (sx, cx) = half(w("rx"));
        let (sy, cy) = half(w("ry"));
        let (sz, cz) = half(w("rz"));
        let q = qmul(
            qmul([cz, 0.0, 0.0, sz], [cy, 0.0, sy, 0.0]),
            [cx, sx, 0.0, 0.0],
        );
        let rapid = v["rapid"].as_str().unwrap();
        assert!(
            rapid.starts_with("PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[["),
            "{rapid}"
        );
        let r = numbers(rapid);
        assert_eq!(r.len(), 3 + 4 + 3 + 4, "{rapid}");
        for (got, want) in r[..3].iter().zip([w("x"), w("y"), w("z")]) {
            assert!((got - want).abs() < 6e-4);
        }
        for (got, want) in r[3..7].iter().zip(q) {
            assert!((got - want).abs() < 2e-6, "{rapid} vs {q:?}");
        }
        assert_eq!(r[7..], [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn show_carries_the_uncertainty() {
        let p = "samples/frames/profile.toml";
        let table = ok(&[
            "track", "show", p, "--at", "0", "--at", "250", "--at", "4250",
        ]);
        insta::assert_snapshot!("show_u_table", table);
        let json = ok(&["track", "show", p, "--step", "2000", "--format", "json"]);
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        for row in v.as_array().unwrap() {
            for k in ["u_dx", "u_dy", "u_dz", "u_rx", "u_ry", "u_rz"] {
                assert!(row[k].as_f64().unwrap() > 0.0, "{row}");
            }
        }
        insta::assert_snapshot!("show_u_json", json);
        let csv = ok(&["track", "show", p, "--at", "250", "--format", "csv"]);
        insta::assert_snapshot!("show_u_csv", csv);
        let tcp = ok(&[
            "track",
            "show",
            p,
            "--at",
            "250",
            "--at",
            "4250",
            "--tcp",
            "1500,300,900",
        ]);
        insta::assert_snapshot!("show_u_tcp", tcp);
        let json = ok(&[
            "track",
            "show",
            p,
            "--at",
            "4250",
            "--tcp",
            "1500,300,900",
            "--format",
            "json",
        ]);
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        let expanded = v[0]["tcp_expanded"].as_f64().unwrap();
        let u: Vec<f64> = (0..3).map(|i| v[0]["tcp_u"][i].as_f64().unwrap()).collect();
        let want = 2.0 * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        assert!((expanded - want).abs() < 2e-4, "{expanded} vs {want}");
        let (code, _, err) = trackfix(&[
            "track",
            "show",
            "samples/track/profile.toml",
            "--at",
            "250",
            "--tcp",
            "1500,300,900",
        ]);
        assert_eq!(code, 2);
        assert!(err.contains("--measurements"), "{err}");
        let overview = ok(&["track", "show", p]);
        assert!(
            overview.contains("largest standard uncertainty"),
            "{overview}"
        );
        insta::assert_snapshot!("show_u_overview", overview);
        // An old profile without knot uncertainties reads as before.
        let old = ok(&[
            "track",
            "show",
            "samples/track/profile.toml",
            "--at",
            "250",
            "--format",
            "json",
        ]);
        assert!(!old.contains("u_dx"), "{old}");
    }

    #[test]
    fn frame_errors() {
        let dir = tempfile::tempdir().unwrap();
        let one_skid = dir.path().join("one_skid.csv");
        std::fs::write(
            &one_skid,
            "skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z\n\
             0,1,1000,0,0,1000,0,0\n0,2,0,1000,0,0,1000,0\n0,3,0,0,1000,0,0,1000\n0,4,500,500,0,500,500,0\n",
        )
        .unwrap();
        let two = dir.path().join("two.csv");
        std::fs::write(&two, "point,x,y,z\n1,0,0,0\n2,1000,0,0\n").unwrap();
        let no_rot = dir.path().join("flange.csv");
        std::fs::write(&no_rot, "x,y,z,w\n1,2,3,4\n").unwrap();
        let mut all = String::new();
        for args in [
            vec!["frame", "base", one_skid.to_str().unwrap()],
            vec!["frame", "tool", no_rot.to_str().unwrap()],
            vec![
                "frame",
                "wobj",
                "samples/frames/marks.csv",
                "--cell",
                "samples/frames/cell.toml",
                "--robot",
                "r9",
            ],
            vec!["frame", "fit", two.to_str().unwrap(), two.to_str().unwrap()],
            vec![
                "track",
                "fit",
                "samples/track/frames.csv",
                "-o",
                dir.path().join("p.toml").to_str().unwrap(),
                "--measurements",
                "samples/track/r2/measurements.csv",
            ],
        ] {
            let (code, _, err) = trackfix(&args);
            assert_eq!(code, 2, "{args:?}");
            all.push_str(&err.replace(dir.path().to_str().unwrap(), "TMP"));
            all.push('\n');
        }
        insta::assert_snapshot!("frame_errors", all);
    }
}

mod invariants {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Exact points at several skids give back the base and the axis they came from.
        #[test]
        fn base_of_exact_points_is_recovered(
            x in -5000.0f64..5000.0, y in -5000.0f64..5000.0, z in -500.0f64..500.0,
            rx in -3.0f64..3.0, ry in -3.0f64..3.0, rz in -180.0f64..180.0,
            tilt in -0.01f64..0.01, turn in -180.0f64..180.0,
        ) {
            let b0 = pose_xyz_deg(x, y, z, rx, ry, rz);
            let axis = trackfix::geometry::xyz_deg(0.0, tilt, turn) * Vector3::x();
            let rows: Vec<_> = [0.0, 1700.0, 4100.0]
                .iter()
                .flat_map(|&s| {
                    sample_tcp_points().into_iter().take(5).map(move |p| {
                        let m = b0 * p + axis * s;
                        trackfix::track::simulate::MeasurementRow {
                            skid: s,
                            point: 1,
                            robot: [p.x, p.y, p.z],
                            meas: [m.x, m.y, m.z],
                        }
                    })
                })
                .collect();
            let fit = fit_base(&rows, None, Some(0.01)).unwrap();
            prop_assert!((fit.base0.translation.vector - b0.translation.vector).norm() < 1e-6);
            prop_assert!(fit.base0.rotation.angle_to(&b0.rotation) < 1e-9);
            prop_assert!((fit.track_axis - axis).norm() < 1e-9);
            prop_assert!(fit.rms < 1e-6);
        }

        /// Exact pivot poses give back the TCP; the residuals vanish.
        #[test]
        fn tcp_of_exact_poses_is_recovered(
            tx in -50.0f64..50.0, ty in -50.0f64..50.0, tz in 50.0f64..400.0,
            px in 500.0f64..2000.0, py in -800.0f64..800.0, pz in 0.0f64..1500.0,
            seed in 0u64..1000,
        ) {
            let tcp = Vector3::new(tx, ty, tz);
            let poses = simulate_pivot(&tcp, &Point3::new(px, py, pz), 6, 0.0, seed);
            let fit = fit_tool(&poses, Some(0.0)).unwrap();
            prop_assert!((fit.tcp - tcp).norm() < 1e-8);
            prop_assert!(fit.max < 1e-8);
        }
    }
}
