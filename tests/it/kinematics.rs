//! Integration tests: the OPW kinematics, ABB/KUKA configurations, `reach`, joint-target
//! correction and mirroring at the kinematics level.

use std::path::Path;

use nalgebra::{Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;

use trackfix::geometry::{Pose, abb_quat, pose_xyz_deg, wrap_deg};
use trackfix::kinematics::reach::{ReachOptions, ReachStatus, reach_program};
use trackfix::kinematics::{
    ConfigValue, Joints, KinematicRefusal, Kinematics, MODELS, OpwGeometry, abb, check_target,
    joint_target_correction, kuka, mirror_config_by_ik, mirrored_joints, model,
};
use trackfix::position::{Language, Program};
use trackfix::transform::Cell;

use crate::support::trackfix;

/// Joint targets written with four decimals on every axis.
const FOUR_DECIMALS: [f64; 6] = [1e-4; 6];

fn irb2400() -> Kinematics {
    model("abb_irb2400_10").expect("bundled").kinematics()
}

/// An arm with a sideways offset `b`, which no bundled model has, so the IK's `b` terms are
/// exercised too.
fn offset_arm() -> Kinematics {
    Kinematics {
        geometry: OpwGeometry {
            a1: 150.0,
            a2: -110.0,
            b: 35.0,
            c1: 500.0,
            c2: 800.0,
            c3: 900.0,
            c4: 120.0,
        },
        offsets: [10.0, -90.0, 5.0, 0.0, 0.0, 20.0],
        signs: [-1.0, 1.0, 1.0, -1.0, 1.0, -1.0],
        limits: [[-185.0, 185.0]; 6],
    }
}

fn all_arms() -> Vec<(String, Kinematics)> {
    let mut v: Vec<(String, Kinematics)> = MODELS
        .iter()
        .map(|m| (m.name.to_owned(), m.kinematics()))
        .collect();
    v.push(("offset_arm".to_owned(), offset_arm()));
    v
}

// ---- an independent forward kinematics: a product of elementary homogeneous transforms ----

fn trans(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m[(0, 3)] = x;
    m[(1, 3)] = y;
    m[(2, 3)] = z;
    m
}

fn rot(axis: usize, a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    let mut m = Matrix4::identity();
    let (i, j) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    m[(i, i)] = c;
    m[(j, j)] = c;
    m[(i, j)] = -s;
    m[(j, i)] = s;
    m
}

/// The OPW chain joint by joint: axis 1 at the base origin, axis 2 at (a1, b, c1) in the
/// axis-1 frame, axis 3 c2 above it, the wrist centre at (a2, 0, c3) from axis 3, the flange c4
/// further along the wrist's z.
fn chain_fk(k: &Kinematics, j: &Joints) -> Matrix4<f64> {
    let g = k.geometry;
    let q: Vec<f64> = (0..6)
        .map(|i| (k.signs[i] * j[i] - k.offsets[i]).to_radians())
        .collect();
    rot(2, q[0])
        * trans(g.a1, g.b, g.c1)
        * rot(1, q[1])
        * trans(0.0, 0.0, g.c2)
        * rot(1, q[2])
        * trans(g.a2, 0.0, g.c3)
        * rot(2, q[3])
        * rot(1, q[4])
        * rot(2, q[5])
        * trans(0.0, 0.0, g.c4)
}

fn matrix(p: &Pose) -> Matrix4<f64> {
    p.to_homogeneous()
}

fn max_abs(m: &Matrix4<f64>) -> f64 {
    m.iter().fold(0.0, |a, v| a.max(v.abs()))
}

fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        a.rotation.angle_to(&b.rotation),
    )
}

fn joints_close(a: &Joints, b: &Joints, tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| wrap_deg(x - y).abs() < tol)
}

#[test]
#[allow(clippy::approx_constant)] // the published quaternion as printed, six decimals
fn irb2400_home_pose_is_the_published_one() {
    let k = irb2400();
    let f = k.forward(&[0.0; 6]);
    let p = f.translation.vector;
    assert!((p - Vector3::new(940.0, 0.0, 1455.0)).norm() < 1e-6, "{p}");
    let q = abb_quat([0.707107, 0.0, 0.707107, 0.0]).unwrap();
    assert!(f.rotation.angle_to(&q) < 1e-6);
    // tool z along base +x (reference/README.md).
    assert!((f.rotation * Vector3::z() - Vector3::x()).norm() < 1e-12);
}

#[test]
fn wrist_centre_and_arm_of_hand_worked_poses() {
    let k = irb2400();
    // Home: the wrist centre 85 mm behind the flange.
    let c = k.wrist_centre(&[0.0; 6]);
    assert!((c - Vector3::new(855.0, 0.0, 1455.0)).norm() < 1e-9);
    // Upper arm tilted back to horizontal (θ2 = -90°), forearm level with it (θ3 = 0):
    // x in the axis-1 frame = 100 − 705 − 135 = −740 mm: behind axis 1.
    let back = [0.0, -90.0, 0.0, 0.0, 30.0, 0.0];
    let c = k.wrist_centre(&back);
    assert!((c.x + 740.0).abs() < 1e-9, "{c}");
    assert_eq!(abb::config_of(&k, &back), [0, 0, 0, 4]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// FK equals the joint-by-joint product of elementary transforms, for every model.
    #[test]
    fn forward_kinematics_matches_the_elementary_chain(raw in prop::array::uniform6(-180.0f64..180.0)) {
        for (name, k) in all_arms() {
            let diff = matrix(&k.forward(&raw)) - chain_fk(&k, &raw);
            prop_assert!(max_abs(&diff) < 1e-9 * 3000.0, "{name}: {diff}");
        }
    }

    /// IK(FK(J)) contains J for joints anywhere on the circle (all 8 branches), and every
    /// solution reproduces the pose.
    #[test]
    fn inverse_finds_every_branch(raw in prop::array::uniform6(-179.0f64..179.0)) {
        for (name, k) in all_arms() {
            let f = k.forward(&raw);
            let sols = k.inverse(&f, Some(raw[3]));
            for s in &sols {
                let (dp, dr) = pose_error(&k.forward(s), &f);
                prop_assert!(dp < 1e-6 && dr < 1e-9, "{name}: {s:?} misses by {dp} mm {dr} rad");
            }
            let q = k.model_joints(&raw);
            let psi = k.geometry.a2.atan2(k.geometry.c3);
            let regular = q[4].sin().abs() > 1e-3
                && (q[2] + psi).sin().abs() > 1e-3
                && k.wrist_centre(&raw).xy().norm() > 1.0 + k.geometry.b.abs();
            if regular {
                prop_assert!(
                    sols.iter().any(|s| joints_close(s, &raw, 1e-6)),
                    "{name}: {raw:?} not among {sols:?}"
                );
                // Eight distinct (arm, wrist) branches when all are in reach; at least the original's.
                let branches: std::collections::BTreeSet<(bool, bool, bool)> = sols
                    .iter()
                    .map(|s| { let a = k.arm(s); (a.front_of_axis1, a.front_of_lower_arm, s[4] >= 0.0) })
                    .collect();
                prop_assert_eq!(branches.len(), sols.len(), "{}: one solution per branch", name);
            }
        }
    }

    /// Near-singular wrists (|axis 5| down to 1e-7°) still give exact poses, and the solution
    /// nearest to J is J.
    #[test]
    fn near_singular_wrists_round_trip(raw in prop::array::uniform6(-150.0f64..150.0), exp in 1.0f64..7.0, neg in any::<bool>()) {
        for (name, k) in all_arms() {
            let mut j = raw;
            j[1] = j[1].clamp(k.limits[1][0] + 1.0, k.limits[1][1] - 1.0);
            j[2] = j[2].clamp(k.limits[2][0] + 1.0, k.limits[2][1] - 1.0);
            // Controller axis 5 such that the model's q5 = ±10^-exp degrees.
            let q5 = if neg { -1.0 } else { 1.0 } * 10f64.powf(-exp);
            j[4] = k.signs[4] * (q5 + k.offsets[4]);
            let f = k.forward(&j);
            let sols = k.inverse(&f, Some(j[3]));
            prop_assert!(!sols.is_empty(), "{name}: no solution near the singularity");
            for s in &sols {
                let (dp, dr) = pose_error(&k.forward(s), &f);
                prop_assert!(dp < 1e-6 && dr < 1e-9, "{name}: {dp} mm {dr} rad");
            }
            if k.within_limits(&j) {
                let n = k.nearest(&f, &j, true).expect("a solution within the limits");
                let (dp, _) = pose_error(&k.forward(&n), &f);
                prop_assert!(dp < 1e-6);
                prop_assert!(k.wrist_singularity_deg(&n) < 10f64.powf(-exp) * 1.001 + 1e-9);
            }
        }
    }
}

#[test]
fn exactly_singular_wrist_keeps_the_hinted_axis_4() {
    let k = irb2400();
    let j = [10.0, 20.0, -10.0, 33.0, 0.0, -50.0];
    let f = k.forward(&j);
    let sols = k.inverse(&f, Some(33.0));
    // The singular branch has one wrist solution (axis 4 = the hint), the others two each.
    assert_eq!(sols.len(), 7, "{sols:?}");
    let singular: Vec<&Joints> = sols.iter().filter(|s| s[4].abs() < 1e-9).collect();
    assert_eq!(singular.len(), 1, "{sols:?}");
    assert!(joints_close(singular[0], &j, 1e-6), "{sols:?}");
    assert!(k.wrist_singularity_deg(&j) < 1e-12);
}

#[test]
fn turns_of_axes_4_and_6_are_kept() {
    let k = irb2400(); // axis 4 ±200°, axis 6 ±400°
    let j = [5.0, 10.0, 20.0, 190.0, 40.0, 350.0];
    let f = k.forward(&j);
    let n = k.nearest(&f, &j, true).expect("reachable");
    assert!(n.iter().zip(&j).all(|(a, b)| (a - b).abs() < 1e-6), "{n:?}");
    // Variants: axis 4 190 and -170, axis 6 350, -10 (and -370): 2 × 3.
    let variants = k.turns(&[5.0, 10.0, 20.0, -170.0, 40.0, -10.0]);
    assert_eq!(variants.len(), 6, "{variants:?}");
    // Same pose and reference one turn away: the nearest follows the reference.
    let r = [5.0, 10.0, 20.0, -170.0, 40.0, -370.0];
    let n = k.nearest(&f, &r, true).expect("reachable");
    assert!(
        (n[3] + 170.0).abs() < 1e-6 && (n[5] + 370.0).abs() < 1e-6,
        "{n:?}"
    );
}

#[test]
fn abb_quadrants_and_cfx_by_hand() {
    for (deg, q) in [
        (0.0, 0),
        (45.0, 0),
        (95.0, 1),
        (-45.0, -1),
        (-95.0, -2),
        (185.0, 2),
        (-185.0, -3),
        (350.0, 3),
    ] {
        assert_eq!(abb::quadrant(deg), q, "{deg}");
    }
    let k = irb2400();
    assert_eq!(
        abb::config_of(&k, &[0.0, 0.0, 0.0, 0.0, 30.0, 0.0]),
        [0, 0, 0, 0]
    );
    assert_eq!(
        abb::config_of(&k, &[-10.0, 0.0, 0.0, 100.0, -30.0, -200.0]),
        [-1, 1, -3, 1]
    );
    // Elbow behind the lower arm: q3 + ψ < 0 with ψ = atan2(-135, 755) = -10.14°, i.e.
    // θ3 < -79.86° (beyond the limits, but the configuration is geometry).
    assert_eq!(
        abb::config_of(&k, &[0.0, 0.0, -85.0, 0.0, 30.0, 0.0]),
        [0, 0, 0, 2]
    );
    assert_eq!(
        abb::config_of(&k, &[0.0, -90.0, -85.0, 0.0, -30.0, 0.0]),
        [0, 0, 0, 7]
    );
    // A joint on a quadrant boundary matches both sides.
    assert!(abb::matches(
        &k,
        &[0.0, 0.0, 0.0, 0.0, 30.0, 0.0],
        [-1, 0, 0, 0]
    ));
    assert!(!abb::matches(
        &k,
        &[0.0, 0.0, 0.0, 0.0, 30.0, 0.0],
        [0, 0, 0, 1]
    ));
}

#[test]
fn kuka_status_and_turn_by_hand() {
    let k = model("kuka_kr210_r3100_2").unwrap().kinematics();
    // The KUKA home {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}: S 'B010', T 'B000010'.
    assert_eq!(
        kuka::status_turn_of(&k, &[0.0, -90.0, 90.0, 0.0, 0.0, 0.0]),
        (0b010, 0b000010)
    );
    // A5 negative sets bit 2; Turn: A1, A2, A5, A6 negative.
    assert_eq!(
        kuka::status_turn_of(&k, &[-10.0, -90.0, 90.0, 20.0, -30.0, -100.0]),
        (0b110, 0b110011)
    );
    // Overhead: the upper arm tilted 80° back (A2 = -170°, beyond its -140° limit: geometry
    // only) and the forearm in line puts the wrist behind A1: bit 0.
    let (s, _) = kuka::status_turn_of(&k, &[0.0, -170.0, 0.0, 0.0, 30.0, 0.0]);
    assert_eq!(s & 1, 1, "{s:b}");
    // The arm bit flips at φ = -ψ = atan2(115, 1420) = 4.63°.
    let phi = 115f64.atan2(1420.0).to_degrees();
    let s_above = kuka::status_turn_of(&k, &[0.0, -90.0, phi + 0.01, 0.0, 30.0, 0.0]).0;
    let s_below = kuka::status_turn_of(&k, &[0.0, -90.0, phi - 0.01, 0.0, 30.0, 0.0]).0;
    assert_eq!((s_above & 2, s_below & 2), (2, 0));
    assert!(kuka::matches(
        &k,
        &[0.0, -90.0, 90.0, 0.0, 30.0, 0.0],
        Some(0b010),
        Some(0b000010)
    ));
    assert!(!kuka::matches(
        &k,
        &[0.0, -90.0, 90.0, 0.0, 30.0, 0.0],
        Some(0b110),
        None
    ));
}

#[test]
fn the_written_configuration_selects_the_solution() {
    let k = irb2400();
    for j in [
        [10.0, 20.0, -10.0, 30.0, 40.0, -50.0],
        [10.0, 20.0, -10.0, -150.0, -40.0, 130.0],
        [-100.0, 5.0, 15.0, 60.0, 80.0, 200.0],
    ] {
        let f = k.forward(&j);
        let written = ConfigValue::Quadrants(abb::config_of(&k, &j));
        let s = trackfix::kinematics::select(&k, &f, Some(&written)).unwrap();
        assert!(s.config_matches && s.within_limits);
        assert!(joints_close(&s.joints, &j, 1e-6), "{:?} vs {j:?}", s.joints);
        assert!((s.joints[5] - j[5]).abs() < 1e-6, "turn of axis 6 from cf6");
    }
}

/// A KUKA Turn that demands a negative A2 of a pose the arm reaches only with A2 > 0 is
/// another configuration, not "outside the limits" at A2 − 360° (axis 2 cannot turn around).
#[test]
fn a_turn_against_an_arm_axis_is_another_configuration_not_a_limit() {
    let k = trackfix::kinematics::model("kuka_kr210_r3100_2")
        .unwrap()
        .kinematics();
    assert!(k.limits[1][1] - k.limits[1][0] <= 360.0);
    let j = [10.0, -60.0, 80.0, 20.0, 40.0, 30.0];
    let f = k.forward(&j);
    let ConfigValue::StatusTurn { status, turn } =
        ConfigValue::of_joints(trackfix::Language::Krl, &k, &j)
    else {
        panic!("a KUKA configuration");
    };
    // Bit 1 (A2 < 0) cleared: the written Turn says A2 >= 0.
    let written = ConfigValue::StatusTurn {
        status,
        turn: turn.map(|t| t & !0b10),
    };
    let s = trackfix::kinematics::select(&k, &f, Some(&written)).unwrap();
    assert!(!s.config_matches, "{s:?}");
    assert!(s.joints[1].abs() <= 180.0, "{:?}", s.joints);
}

#[test]
fn mirrored_joints_give_the_mirrored_pose_and_ik_agrees_with_the_rule() {
    // Sa = Sb = diag(1, -1, 1) for the xz plane through the base.
    let s = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, -1.0, 1.0, 1.0));
    for m in MODELS {
        let k = m.kinematics();
        for j in [
            [
                20.0,
                -30.0
                    + if m.name.starts_with("kuka") {
                        -60.0
                    } else {
                        0.0
                    },
                40.0,
                35.0,
                50.0,
                -70.0,
            ],
            [
                -60.0,
                10.0 + if m.name.starts_with("kuka") {
                    -90.0
                } else {
                    0.0
                },
                30.0,
                -100.0,
                70.0,
                160.0,
            ],
        ] {
            let lhs = matrix(&k.forward(&mirrored_joints(&j)));
            let rhs = s * matrix(&k.forward(&j)) * s;
            assert!(max_abs(&(lhs - rhs)) < 1e-9, "{}: {}", m.name, lhs - rhs);
            // IK of the mirrored pose picks the rule's joints, and its configuration is the
            // rule's (cf1, cf4, cf6 → -cf-1, cfx kept; Turn bits of A1, A4, A6 toggled).
            let mirrored = Pose::from_parts(
                nalgebra::Translation3::from(Vector3::new(rhs[(0, 3)], rhs[(1, 3)], rhs[(2, 3)])),
                nalgebra::UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                    Matrix3::from_fn(|r, c| rhs[(r, c)]),
                )),
            );
            if !k.within_limits(&j) {
                continue;
            }
            let (jm, abb_c) = mirror_config_by_ik(&k, &mirrored, &j, Language::Rapid).unwrap();
            assert!(
                joints_close(&jm, &mirrored_joints(&j), 1e-6),
                "{}: {jm:?}",
                m.name
            );
            let [c1, c4, c6, cx] = abb::config_of(&k, &j);
            assert_eq!(
                abb_c,
                ConfigValue::Quadrants([-c1 - 1, -c4 - 1, -c6 - 1, cx]),
                "{}",
                m.name
            );
            let (_, kuka_c) = mirror_config_by_ik(&k, &mirrored, &j, Language::Krl).unwrap();
            let (st, t) = kuka::status_turn_of(&k, &j);
            assert_eq!(
                kuka_c,
                ConfigValue::StatusTurn {
                    status: Some(st),
                    turn: Some(t ^ 0b101001)
                },
                "{}",
                m.name
            );
        }
    }
}

/// A deformation of the track at one skid, like a profile's D(s): mm and hundredths of a degree.
fn deviation() -> Pose {
    pose_xyz_deg(1.2, -0.8, 2.1, 0.03, -0.02, 0.05)
}

#[test]
fn joint_targets_follow_the_deformed_track() {
    let d = deviation();
    for m in MODELS {
        let k = m.kinematics();
        let j = if m.name.starts_with("kuka") {
            [15.0, -80.0, 100.0, 30.0, 45.0, -200.0]
        } else {
            [15.0, 10.0, 20.0, 30.0, 45.0, -200.0]
        };
        assert!(k.within_limits(&j), "{}", m.name);
        // correct: FK(J') = D⁻¹·FK(J); zero: FK(J') = D·FK(J) and back.
        let jc = joint_target_correction(&k, &j, &d.inverse(), &FOUR_DECIMALS).expect("reachable");
        let want = d.inverse() * k.forward(&j);
        let (dp, dr) = pose_error(&k.forward(&jc), &want);
        assert!(dp < 1e-3 && dr < 1e-8, "{}: {dp} mm", m.name);
        assert!(
            jc.iter().zip(&j).all(|(a, b)| (a - b).abs() < 1.0),
            "{}: {jc:?}",
            m.name
        );
        assert!(
            (jc[5] + 200.0).abs() < 1.0,
            "the turn of axis 6 is kept: {jc:?}"
        );
        let back = joint_target_correction(&k, &jc, &d, &FOUR_DECIMALS).expect("reachable");
        assert!(
            back.iter().zip(&j).all(|(a, b)| (a - b).abs() < 1e-6),
            "{back:?}"
        );
    }
}

#[test]
fn check_target_refuses_unreachable_limit_and_configuration_changes() {
    let k = irb2400();
    let j = [10.0, 20.0, -10.0, 30.0, 40.0, -50.0];
    let f = k.forward(&j);
    let written = ConfigValue::Quadrants(abb::config_of(&k, &j));
    // A small move: same configuration, joints close by.
    let moved = pose_xyz_deg(0.5, -0.3, 0.2, 0.0, 0.0, 0.01) * f;
    let c = check_target(&k, &f, &moved, Some(&written));
    assert_eq!(c.refusal, None);
    assert!(
        c.after
            .unwrap()
            .iter()
            .zip(&j)
            .all(|(a, b)| (a - b).abs() < 0.5)
    );
    // 3 m away: out of reach.
    let far = pose_xyz_deg(3000.0, 0.0, 0.0, 0.0, 0.0, 0.0) * f;
    let c = check_target(&k, &f, &far, Some(&written));
    assert_eq!(c.refusal, Some(KinematicRefusal::Unreachable));
    assert_eq!(
        c.message().unwrap(),
        "the transformed target is out of reach: joints before [10.000, 20.000, -10.000, 30.000, 40.000, -50.000], after none"
    );
    // Mirrored through the base's xz plane with the configuration unchanged: cf1 = 0 cannot
    // reach an axis 1 of -10°.
    let mj = mirrored_joints(&j);
    let c = check_target(&k, &f, &k.forward(&mj), Some(&written));
    assert!(
        matches!(c.refusal, Some(KinematicRefusal::ConfigChange { .. })),
        "{c:?}"
    );
    // Axis 5 bent past its 120° limit: in the written configuration only 123° reaches it.
    let edge = [0.0, 10.0, 20.0, 0.0, 118.0, 0.0];
    let fe = k.forward(&edge);
    let w = ConfigValue::Quadrants(abb::config_of(&k, &edge));
    let bent = k.forward(&[0.0, 10.0, 20.0, 0.0, 123.0, 0.0]);
    let c = check_target(&k, &fe, &bent, Some(&w));
    assert_eq!(
        c.refusal,
        Some(KinematicRefusal::OutsideLimit {
            axis: 5,
            value: c.after.unwrap()[4],
            limits: [-120.0, 120.0]
        }),
        "{c:?}"
    );
    assert!((c.after.unwrap()[4] - 123.0).abs() < 1e-6);
}

// ---- reach on a program ----

const CELL: &str = r#"
[robot.r1]
profile = "track/profile.toml"
base = { x = 0, y = -1000, z = 0, rx = 0, ry = 0, rz = 90 }
track_axis = [1, 0, 0]
skid = "eax_a"
[robot.r1.kinematics]
model = "abb_irb2400_10"
[robot.r1.tool]
tgun = { x = 0, y = 0, z = 200, rx = 0, ry = 0, rz = 0 }
"#;

fn robtarget(name: &str, t: &Pose, cf: [i32; 4], skid: f64) -> String {
    let p = t.translation.vector;
    let q = t.rotation.quaternion();
    format!(
        "  CONST robtarget {name}:=[[{:.4},{:.4},{:.4}],[{:.8},{:.8},{:.8},{:.8}],[{},{},{},{}],[{skid},9E9,9E9,9E9,9E9,9E9]];\n",
        p.x, p.y, p.z, q.w, q.i, q.j, q.k, cf[0], cf[1], cf[2], cf[3]
    )
}

#[test]
fn reach_flags_far_targets_wrong_configurations_and_singular_wrists() {
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    // wobj0 = world: T = B(s)·FK(J)·TOOL.
    let target = |j: &Joints| b * k.forward(j) * tool;
    let good = [10.0, 20.0, -10.0, 30.0, 40.0, -50.0];
    let singular = [10.0, 20.0, -10.0, 30.0, 2.0, -50.0];
    let far = pose_xyz_deg(0.0, 2500.0, 0.0, 0.0, 0.0, 0.0) * target(&good);
    let cf = abb::config_of(&k, &good);
    let mut src = String::from(
        "MODULE M\n  PERS tooldata tGun:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n",
    );
    src += &robtarget("pGood", &target(&good), cf, skid);
    src += &robtarget(
        "pWrongCf",
        &target(&good),
        [cf[0], cf[1], cf[2], cf[3] ^ 4],
        skid,
    );
    src += &robtarget("pFar", &far, cf, skid);
    src += &robtarget(
        "pWrist",
        &target(&singular),
        abb::config_of(&k, &singular),
        skid,
    );
    src += "  CONST jointtarget jOut:=[[0,0,0,0,130,0],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    src += "  PROC main()\n    MoveL pGood,v100,fine,tGun\\WObj:=wobj0;\n    MoveL pWrongCf,v100,fine,tGun;\n    MoveL pFar,v100,fine,tGun;\n    MoveL pWrist,v100,fine,tGun;\n    MoveAbsJ jOut,v100,fine,tGun;\n  ENDPROC\nENDMODULE\n";
    let program = Program {
        files: vec![trackfix::rapid::parse_file(
            Path::new("m.mod"),
            src.into_bytes(),
        )],
    };
    let files = reach_program(&program, robot, &k, &ReachOptions::default());
    let t = &files[0].targets;
    let by = |n: &str| t.iter().find(|x| x.name == n).unwrap();
    let g = by("pGood");
    assert_eq!(g.status, ReachStatus::Ok, "{g:?}");
    assert!(
        joints_close(&g.joints.unwrap(), &good, 1e-4),
        "{:?}",
        g.joints
    );
    assert_eq!(g.config_matches, Some(true));
    let m = g.limit_margin_deg.unwrap();
    assert!(
        (m[1] - 90.0).abs() < 1e-3 && (m[4] - 80.0).abs() < 1e-3,
        "{m:?}"
    );
    let w = by("pWrongCf");
    assert_eq!(w.status, ReachStatus::ConfigMismatch);
    assert_eq!(w.config_matches, Some(false));
    assert_eq!(by("pFar").status, ReachStatus::Unreachable);
    assert_eq!(by("pFar").reachable, Some(false));
    let s = by("pWrist");
    assert_eq!(s.status, ReachStatus::Ok);
    assert!(
        s.warnings.iter().any(|w| w.contains("wrist singularity")),
        "{s:?}"
    );
    let j = by("jOut");
    assert_eq!(j.status, ReachStatus::OutsideLimit);
    assert!((j.limit_margin_deg.unwrap()[4] + 10.0).abs() < 1e-9);
    // The tool override in the cell is used: the program's tGun has no offset.
    assert!((tool.translation.vector.z - 200.0).abs() < 1e-12);
}

#[test]
fn kinematics_table_errors_are_located() {
    let parse = |t: &str| match Cell::parse(Path::new("cell.toml"), t) {
        Err(e) => e.to_string(),
        Ok(_) => "parsed".to_owned(),
    };
    let e = parse(&CELL.replace("abb_irb2400_10", "irb9999"));
    assert!(
        e.starts_with("cell.toml:8:9: error: robot `r1`: unknown robot model `irb9999`"),
        "{e}"
    );
    assert!(e.contains("abb_irb2400_10"), "{e}");
    let e = parse(&CELL.replace("model = \"abb_irb2400_10\"", "a1 = 100.0"));
    assert!(e.contains("kinematics has no `a2`"), "{e}");
    let e = parse(&CELL.replace(
        "model = \"abb_irb2400_10\"",
        "model = \"abb_irb2400_10\"\nsigns = [1, 1, 2, 1, 1, 1]",
    ));
    assert!(
        e.starts_with("cell.toml:9:9: error:") && e.contains("signs must be 1 or -1"),
        "{e}"
    );
    let e = parse(&CELL.replace(
        "model = \"abb_irb2400_10\"",
        "model = \"abb_irb2400_10\"\nc5 = 1",
    ));
    assert!(e.contains("unknown field `c5`"), "{e}");
    // Overrides on a model.
    let cell = Cell::parse(
        Path::new("cell.toml"),
        &CELL.replace(
            "model = \"abb_irb2400_10\"",
            "model = \"ABB-IRB2400/10\"\nc4 = 100",
        ),
    )
    .unwrap();
    let k = cell.robot("r1").unwrap().kinematics.clone().unwrap();
    assert_eq!(k.geometry.c4, 100.0);
    assert_eq!(k.geometry.c3, 755.0);
}

#[test]
fn reach_cli_on_the_spot_line_sample() {
    let (code, out, err) = trackfix(&[
        "reach",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
    ]);
    // The sample's confdata is the one IK gives on the cell's IRB 4600 (written so): every
    // target is reachable as written.
    assert_eq!(code, 0, "{err}");
    assert!(out.ends_with("227 target(s): 227 ok\n"), "{out}");
    insta::assert_snapshot!(out);
    let (code, json, _) = trackfix(&[
        "reach",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let targets = v["files"][0]["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 227);
    for key in [
        "name",
        "line",
        "reachable",
        "joints",
        "config_matches",
        "config_written",
        "config_solved",
        "limit_margin_deg",
        "warnings",
    ] {
        assert!(targets[1].get(key).is_some(), "{key}");
    }
    assert_eq!(targets[0]["name"], "jHome");
    assert_eq!(targets[0]["joints"][4], 80.0);
    let (code, _, err) = trackfix(&[
        "reach",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("no [robot.r1.kinematics]"), "{err}");
}

#[test]
fn kuka_joint_directions_follow_the_controller() {
    let k = model("kuka_kr210_r3100_2").unwrap().kinematics();
    // The mastering/home pose: upper arm upright, forearm level, flange facing forward with its
    // z axis along base +x (KUKA shows B = 90°), at x = a1 + c3 + c4, z = c1 + c2 − a2.
    let home = k.forward(&[0.0, -90.0, 90.0, 0.0, 0.0, 0.0]);
    let p = home.translation.vector;
    assert!((p - Vector3::new(1990.0, 0.0, 2110.0)).norm() < 1e-9, "{p}");
    let b90 = trackfix::geometry::kuka_abc(0.0, 90.0, 0.0);
    assert!(home.rotation.angle_to(&b90) < 1e-12);
    // A1's axis points down: A1 = +90° turns the arm to base −y.
    let p = k
        .forward(&[90.0, -90.0, 90.0, 0.0, 0.0, 0.0])
        .translation
        .vector;
    assert!(
        (p - Vector3::new(0.0, -1990.0, 2110.0)).norm() < 1e-9,
        "{p}"
    );
}

#[test]
fn reach_on_the_krl_sample_reads_status_and_turn() {
    let (code, json, err) = trackfix(&[
        "reach",
        "samples/krl/spot_line.src",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let targets = v["files"][0]["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 161);
    assert!(targets.iter().all(|t| t["status"] == "ok"));
    let xp1 = &targets[1];
    assert_eq!(xp1["name"], "XP1");
    assert_eq!(xp1["status"], "ok");
    assert_eq!(xp1["config_written"], "S 6 T 50");
    assert_eq!(xp1["config_solved"], "S 6 T 50");
    assert_eq!(xp1["config_matches"], true);
    // XP0 is in $WORLD, above the car near the robot.
    assert_eq!(targets[0]["name"], "XP0");
    assert_eq!(targets[0]["config_solved"], "S 2 T 10");
}

#[test]
fn a_pose_inside_the_arm_has_all_eight_solutions() {
    let k = irb2400();
    let j = [0.0, 0.0, 60.0, 0.0, 30.0, 0.0];
    let sols = k.inverse(&k.forward(&j), None);
    let branches: std::collections::BTreeSet<(bool, bool, bool)> = sols
        .iter()
        .map(|s| {
            let a = k.arm(s);
            (a.front_of_axis1, a.front_of_lower_arm, s[4] >= 0.0)
        })
        .collect();
    assert_eq!((sols.len(), branches.len()), (8, 8), "{sols:?}");
    let cfx: std::collections::BTreeSet<i32> =
        sols.iter().map(|s| abb::config_of(&k, s)[3]).collect();
    assert_eq!(cfx, (0..8).collect());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The configuration of J, written back, selects J: ABB confdata and KUKA Status/Turn each
    /// pick exactly one solution within the limits.
    #[test]
    fn the_configuration_of_joints_selects_them(u in prop::array::uniform6(0.02f64..0.98)) {
        for m in MODELS {
            let k = m.kinematics();
            let j: Joints = std::array::from_fn(|i| {
                let [lo, hi] = k.limits[i];
                lo + u[i] * (hi - lo)
            });
            let q = k.model_joints(&j);
            let psi = k.geometry.a2.atan2(k.geometry.c3);
            let off_boundary = [0, 3, 5].iter().all(|&i| (j[i] / 90.0 - (j[i] / 90.0).round()).abs() > 1e-6)
                && q[4].sin().abs() > 1e-3
                && (q[2] + psi).sin().abs() > 1e-3
                && k.wrist_centre(&j).xy().norm() > 1.0;
            prop_assume!(off_boundary);
            let f = k.forward(&j);
            for lang in [Language::Rapid, Language::Krl] {
                let written = ConfigValue::of_joints(lang, &k, &j);
                let s = trackfix::kinematics::select(&k, &f, Some(&written)).unwrap();
                prop_assert!(s.config_matches && s.within_limits);
                let exact = s.joints.iter().zip(&j).all(|(a, b)| (a - b).abs() < 1e-6);
                if lang == Language::Rapid || m.name.starts_with("kuka") {
                    // confdata quadrants, or Turn signs within ±350°, leave one choice.
                    prop_assert!(exact, "{}: {:?} vs {:?}", m.name, s.joints, j);
                } else {
                    // Turn on an ABB arm (axis 6 ±400°): two negative turns may share it.
                    prop_assert!(joints_close(&s.joints, &j, 1e-6), "{}: {:?} vs {:?}", m.name, s.joints, j);
                }
            }
        }
    }
}

/// The README's figure: the sample's home joint target on r1's measured track.
#[test]
fn sample_home_joint_target_on_the_measured_track() {
    let profile =
        trackfix::track::Profile::load(&crate::support::root().join("samples/track/profile.toml"))
            .unwrap();
    let d = profile.deviation(150.0).unwrap();
    let k = model("abb_irb4600_40_255").unwrap().kinematics();
    let j = [0.0, -20.0, 30.0, 0.0, 80.0, 0.0];
    let jc = joint_target_correction(&k, &j, &d.inverse(), &FOUR_DECIMALS).unwrap();
    let want = [0.0514, -19.9494, 30.0292, -0.0669, 79.9236, 0.0997];
    assert!(
        jc.iter().zip(&want).all(|(a, b)| (a - b).abs() < 1e-4),
        "{jc:?}"
    );
    let (dp, dr) = pose_error(&k.forward(&jc), &(d.inverse() * k.forward(&j)));
    assert!(dp < 1e-3 && dr < 1e-9);
    let moved = (k.forward(&jc).translation.vector - k.forward(&j).translation.vector).norm();
    assert!((moved - 1.87).abs() < 0.01, "{moved}");
}

// ---- the transforms with kinematics ----

fn parsed(src: &str) -> Program {
    Program {
        files: vec![trackfix::rapid::parse_file(
            Path::new("m.mod"),
            src.as_bytes().to_vec(),
        )],
    }
}

fn joints_in(program: &Program, name: &str) -> Joints {
    let p = program.files[0]
        .positions()
        .find(|p| p.name.as_deref() == Some(name))
        .unwrap();
    let v: Vec<f64> = p
        .joints
        .iter()
        .map(|f| f.as_ref().unwrap().value())
        .collect();
    [v[0], v[1], v[2], v[3], v[4], v[5]]
}

/// `correct` with kinematics: the joint target follows the deformed track with
/// FK(J') = D⁻¹·FK(J) (design §10, 1e-3 mm through the written text), a consistent Cartesian
/// target is corrected, and one whose written configuration does not reach it is refused by
/// name as a `reach` refusal.
#[test]
fn correct_moves_joint_targets_and_checks_cartesian_ones() {
    use trackfix::transform::{Direction, RefusalKind, TrackSetup, apply, track_correction};
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    let good = [10.0, 20.0, -10.0, 30.0, 40.0, -50.0];
    let target = b * k.forward(&good) * tool;
    let cf = abb::config_of(&k, &good);
    let mut src = String::from(
        "MODULE M\n  PERS tooldata tGun:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n",
    );
    src += &robtarget("pGood", &target, cf, skid);
    src += &robtarget("pWrongCf", &target, [cf[0] - 1, cf[1], cf[2], cf[3]], skid);
    src +=
        "  CONST jointtarget jA:=[[12.345678,25.5,-10.25,30,40,-200],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    src += "  PROC main()\n    MoveL pGood,v100,fine,tGun;\n    MoveL pWrongCf,v100,fine,tGun;\n    MoveAbsJ jA,v100,fine,tGun;\n  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);
    let j = joints_in(&program, "jA");
    assert!(k.within_limits(&j));
    let d = deviation();
    let dev = move |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(d) };
    let setup = TrackSetup::new(robot, &dev);
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let refusals: Vec<_> = result.refusals().collect();
    assert_eq!(refusals.len(), 1, "{refusals:?}");
    assert_eq!(refusals[0].target, "pWrongCf");
    assert_eq!(refusals[0].kind, RefusalKind::Reach);
    assert!(
        refusals[0].message.contains("does not reach it")
            && refusals[0].message.contains("10.000, 20.000, -10.000"),
        "{}",
        refusals[0].message
    );
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    let after = parsed(&out);
    let jc = joints_in(&after, "jA");
    let want = d.inverse() * k.forward(&j);
    let (dp, dr) = pose_error(&k.forward(&jc), &want);
    // Rotation to the written precision: six axes rounded to 0.5e-4° each, at most 5.3e-6 rad.
    assert!(dp < 1e-3 && dr < 5.3e-6, "{dp} mm, {dr} rad\n{out}");
    // Six decimals as written in axis 1, the house minimum of 4 elsewhere; the turn of axis 6
    // kept.
    let line = out.lines().find(|l| l.contains("jA:=")).unwrap();
    let axes = line.split("[[").nth(1).unwrap().split(']').next().unwrap();
    let decimals: Vec<usize> = axes
        .split(',')
        .map(|a| a.split('.').nth(1).map_or(0, str::len))
        .collect();
    assert_eq!(decimals, [6, 4, 4, 4, 4, 4], "{line}");
    assert!((jc[5] + 200.0).abs() < 1.0, "{jc:?}");
    // The good target moved (its pose is corrected), the wrong one is as written.
    let before_line = |n: &str| src.lines().find(|l| l.contains(n)).unwrap().to_owned();
    let after_line = |n: &str| out.lines().find(|l| l.contains(n)).unwrap().to_owned();
    assert_ne!(before_line("pGood:="), after_line("pGood:="));
    assert_eq!(before_line("pWrongCf:="), after_line("pWrongCf:="));
}

/// Without kinematics the joint target is refused as before.
#[test]
fn correct_without_kinematics_refuses_joint_targets() {
    use trackfix::transform::{Direction, RefusalKind, TrackSetup, track_correction};
    let cell = Cell::parse(
        Path::new("cell.toml"),
        &CELL.replace("[robot.r1.kinematics]\nmodel = \"abb_irb2400_10\"\n", ""),
    )
    .unwrap();
    let robot = cell.robot("r1").unwrap();
    assert!(robot.kinematics.is_none());
    let program = parsed(
        "MODULE M\n  CONST jointtarget jA:=[[10,20,-10,30,40,-50],[500,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
    );
    let dev = |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(deviation()) };
    let setup = TrackSetup::new(robot, &dev);
    let edits = track_correction(&program, &setup, Direction::Correct);
    let kinds: Vec<_> = edits.files[0].refusals.iter().map(|r| r.kind).collect();
    assert_eq!(kinds, [RefusalKind::JointTarget]);
}

/// `mirror --mirror-joints` with kinematics: the joint target's mirror image through FK/IK is
/// `(−θ1, θ2, θ3, −θ4, θ5, −θ6)` for an arm without sideways offset, written with the rule's
/// text (a flip keeps the literal); the Cartesian target gets the configuration IK finds,
/// which is the rule's away from quadrant boundaries.
#[test]
fn mirror_with_kinematics_mirrors_joints_and_configurations_by_ik() {
    use trackfix::transform::{MirrorArm, MirrorSettings, apply, mirror};
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    let mut src = String::from(
        "MODULE M\n  PERS tooldata tGun:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n",
    );
    src += "  CONST jointtarget jA:=[[10.5,20,-10,30.25,40,-50],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    let samples: Vec<Joints> = vec![
        [10.0, 20.0, -10.0, 30.0, 40.0, -50.0],
        [-35.0, 5.0, 15.0, -120.0, -60.0, 170.0],
        [120.0, -30.0, 40.0, 95.0, 20.0, -95.0],
        [-100.0, 45.0, -30.0, -10.0, 70.0, 250.0],
    ];
    for (i, j) in samples.iter().enumerate() {
        assert!(k.within_limits(j), "{j:?}");
        src += &robtarget(
            &format!("p{i}"),
            &(b * k.forward(j) * tool),
            abb::config_of(&k, j),
            skid,
        );
    }
    src += "  PROC main()\n    MoveAbsJ jA,v100,fine,tGun;\n";
    for i in 0..samples.len() {
        src += &format!("    MoveL p{i},v100,fine,tGun;\n");
    }
    src += "  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);
    let with_arm = MirrorSettings {
        mirror_joints: true,
        arm: MirrorArm::of(robot, None),
        ..MirrorSettings::default()
    };
    let result = apply(&program, mirror(&program, &with_arm)).unwrap();
    assert!(
        result.refusals().next().is_none(),
        "{:?}",
        result.refusals().collect::<Vec<_>>()
    );
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    assert!(out.contains("jA:=[[-10.5,20,-10,-30.25,40,50],"), "{out}");
    // The rule alone (no arm) gives the same configurations on these samples.
    let by_rule = MirrorSettings {
        mirror_joints: true,
        ..MirrorSettings::default()
    };
    let rule_out = apply(&program, mirror(&program, &by_rule)).unwrap();
    assert_eq!(
        String::from_utf8(rule_out.files[0].output.clone()).unwrap(),
        out
    );
    // And the configuration written is the one of the mirrored joints.
    let after = parsed(&out);
    for (i, j) in samples.iter().enumerate() {
        let p = after.files[0]
            .positions()
            .find(|p| p.name.as_deref() == Some(&format!("p{i}")))
            .unwrap();
        let written = ConfigValue::written(&p.config).unwrap();
        assert_eq!(
            written,
            ConfigValue::Quadrants(abb::config_of(&k, &mirrored_joints(j))),
            "p{i}"
        );
    }
}

/// A target's joints depend on the tool it is moved with: one used with two tools is checked
/// with each. `pBoth` reaches with `tGun` and is 3 m out of reach with `tFar`: `reach` gives
/// the worse verdict and names the tool, and `correct` and `mirror` refuse it, naming the tool,
/// where the first tool's check alone passed it. `pSame` is used with `tGun` and `tGun2`, the
/// same tool under another name: corrected, not refused.
#[test]
fn a_target_used_with_two_tools_is_checked_with_each() {
    use trackfix::transform::{
        Direction, MirrorArm, MirrorSettings, RefusalKind, TrackSetup, apply, mirror,
        track_correction,
    };
    let cell_text = format!(
        "{CELL}tfar = {{ x = 3000, y = 0, z = 200, rx = 0, ry = 0, rz = 0 }}\n\
         tgun2 = {{ x = 0, y = 0, z = 200, rx = 0, ry = 0, rz = 0 }}\n"
    );
    let cell = Cell::parse(Path::new("cell.toml"), &cell_text).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    let good = [10.0, 20.0, -10.0, 30.0, 40.0, -50.0];
    let target = b * k.forward(&good) * tool;
    let cf = abb::config_of(&k, &good);
    let mut src = String::from("MODULE M\n");
    src += &robtarget("pBoth", &target, cf, skid);
    src += &robtarget("pSame", &target, cf, skid);
    src += "  PROC main()\n    MoveL pBoth,v100,fine,tGun;\n    MoveL pSame,v100,fine,tGun;\n    \
            MoveL pBoth,v100,fine,tFar;\n    MoveL pSame,v100,fine,tGun2;\n  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);

    let files = reach_program(&program, robot, &k, &ReachOptions::default());
    let by = |n: &str| files[0].targets.iter().find(|x| x.name == n).unwrap();
    let both = by("pBoth");
    assert_eq!(both.status, ReachStatus::Unreachable, "{both:?}");
    assert_eq!(both.reachable, Some(false));
    // The row's joints are the first tool's.
    assert!(joints_close(&both.joints.unwrap(), &good, 1e-4), "{both:?}");
    assert!(
        both.warnings
            .iter()
            .any(|w| w.starts_with("with tool `tFar`: out of reach")),
        "{both:?}"
    );
    let same = by("pSame");
    assert_eq!(same.status, ReachStatus::Ok, "{same:?}");
    assert!(same.warnings.is_empty(), "{same:?}");

    let d = deviation();
    let dev = move |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(d) };
    let setup = TrackSetup::new(robot, &dev);
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let refusals: Vec<_> = result.refusals().collect();
    assert_eq!(refusals.len(), 1, "{refusals:?}");
    assert_eq!(
        (refusals[0].target.as_str(), refusals[0].kind),
        ("pBoth", RefusalKind::Reach)
    );
    assert!(
        refusals[0].message.contains("out of reach as written")
            && refusals[0].message.ends_with("(with tool `tFar`)"),
        "{}",
        refusals[0].message
    );
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    let line = |text: &str, n: &str| text.lines().find(|l| l.contains(n)).unwrap().to_owned();
    assert_eq!(line(&src, "pBoth:="), line(&out, "pBoth:="));
    assert_ne!(line(&src, "pSame:="), line(&out, "pSame:="));

    let with_arm = MirrorSettings {
        arm: MirrorArm::of(robot, None),
        ..MirrorSettings::default()
    };
    let mirrored = apply(&program, mirror(&program, &with_arm)).unwrap();
    let refused: Vec<_> = mirrored
        .refusals()
        .map(|r| {
            (
                r.target.as_str(),
                r.kind,
                r.message.ends_with("(with tool `tFar`)"),
            )
        })
        .collect();
    assert_eq!(refused, [("pBoth", RefusalKind::Reach, true)]);
}

/// `inspect --cell --robot` adds the reach verdict and the solved joints (table, csv, json); the
/// joint target's joints are its own.
#[test]
fn inspect_with_a_robot_adds_reach_columns() {
    let args = |format: &str| {
        let (code, out, err) = trackfix(&[
            "inspect",
            "samples/rapid/spot_line.mod",
            "--cell",
            "samples/cell.toml",
            "--robot",
            "r1",
            "--format",
            format,
        ]);
        assert_eq!(code, 0, "{err}");
        out
    };
    let table = args("table");
    let header = table.lines().nth(1).unwrap();
    assert!(
        header.ends_with("reach                 a1       a2       a3       a4       a5       a6"),
        "{header}"
    );
    let pounce = table
        .lines()
        .find(|l| l.trim_start().starts_with("pPounce"))
        .unwrap();
    assert!(
        pounce.ends_with("ok                -11.87    -1.62   -14.08    -8.45   115.20   163.72"),
        "{pounce}"
    );
    let csv = args("csv");
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with(",tool,reach,a1,a2,a3,a4,a5,a6")
    );
    let jhome = csv.lines().find(|l| l.contains(",jHome,")).unwrap();
    assert!(
        jhome.ends_with(",ok,0.00,-20.00,30.00,0.00,80.00,0.00"),
        "{jhome}"
    );
    let v: serde_json::Value = serde_json::from_str(&args("json")).unwrap();
    let rows = v["files"][0]["positions"].as_array().unwrap();
    assert_eq!(rows.len(), 227);
    assert!(rows.iter().all(|r| r["reach"]["status"] == "ok"));
    assert_eq!(
        rows[1]["reach"]["solved_joints"].as_array().unwrap().len(),
        6
    );
    // Without --robot the columns are absent.
    let (_, plain, _) = trackfix(&["inspect", "samples/rapid/spot_line.mod", "--format", "csv"]);
    assert!(plain.lines().next().unwrap().ends_with(",frame,tool"));
}

/// `inspect --cell --robot` reads the cell's work objects for the reach as the transforms do,
/// and says what it makes of them as they say it: the warning that `wobj_car`'s object frame is
/// kept under the cell's user frame, word for word and with its snippet and help as `correct`
/// prints it (one code path), on standard error beside any format. Before, `inspect` printed
/// nothing of it.
#[test]
fn inspect_with_a_robot_says_what_the_cell_makes_of_the_work_objects() {
    let cell = ["--cell", "samples/cell.toml", "--robot", "r1"];
    let file = "samples/rapid/spot_line.mod";
    // The object-frame warning as a block: its line and the snippet and help under it.
    let reading = |err: &str| -> String {
        let mut block = Vec::new();
        for l in err.lines() {
            if block.is_empty()
                && !l.contains(
                    "is kept: the targets are transformed in the cell's uframe · this oframe",
                )
            {
                continue;
            }
            // The snippet's lines (`13 |`, `   |`) and the help under it.
            let under = l.find('|').is_some_and(|i| i < 6) || l.trim_start().starts_with("= ");
            if !block.is_empty() && !under {
                break;
            }
            block.push(l);
        }
        block.join("\n")
    };
    let (code, _, err) = trackfix(&[&["correct", file, "--check"][..], &cell].concat());
    assert_eq!(code, 1, "{err}");
    let said = reading(&err);
    assert!(
        said.starts_with("samples/rapid/spot_line.mod:13:32: warning: work object `wobj_car`: the cell file's entry for robot `r1` is its user frame")
            && said.ends_with("= help: if the cell's entry measures the whole work object (its object frame too), write this oframe as [[0,0,0],[1,0,0,0]]"),
        "{err}"
    );
    for format in ["table", "json"] {
        let (code, out, err) =
            trackfix(&[&["inspect", file, "--format", format][..], &cell].concat());
        assert_eq!(code, 0, "{err}");
        assert_eq!(reading(&err), said, "{format}: {err}");
        assert!(!out.contains("oframe {"), "{out}");
    }
    // Without the cell nothing reads its entries.
    let (_, _, err) = trackfix(&["inspect", file]);
    assert_eq!(reading(&err), "", "{err}");
}

/// Runs `trackfix correct FILE --cell samples/cell.toml --robot ROBOT --out-dir DIR/out
/// --no-stamp --format json` with `extra`: the exit code, the JSON report and the output text (if written).
fn correct_json(file: &Path, robot: &str, extra: &[&str]) -> (i32, serde_json::Value, String) {
    let dir = file.parent().unwrap().join("out");
    let out = dir.join(file.file_name().unwrap());
    let _ = std::fs::remove_dir_all(&dir);
    let args = [
        &[
            "correct",
            file.to_str().unwrap(),
            "--cell",
            "samples/cell.toml",
            "--robot",
            robot,
            "--out-dir",
            dir.to_str().unwrap(),
            "--no-stamp",
            "--format",
            "json",
        ][..],
        extra,
    ]
    .concat();
    let (code, stdout, err) = trackfix(&args);
    let doc: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!("{e}: {stdout}\n{err}");
    });
    (code, doc, std::fs::read_to_string(&out).unwrap_or_default())
}

/// The refusals of a JSON report as (target, line, kind, message).
fn json_refusals(doc: &serde_json::Value) -> Vec<(String, u64, String, String)> {
    doc["refusals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["target"].as_str().unwrap().to_owned(),
                r["line"].as_u64().unwrap(),
                r["kind"].as_str().unwrap().to_owned(),
                r["message"].as_str().unwrap().to_owned(),
            )
        })
        .collect()
}

/// Each refusal of [`json_refusals`] without its message.
fn targets_lines_kinds(refusals: &[(String, u64, String, String)]) -> Vec<(&str, u64, &str)> {
    refusals
        .iter()
        .map(|(t, l, k, _)| (t.as_str(), *l, k.as_str()))
        .collect()
}

/// The turns of axes 4 and 6 a wrist-singularity message states, degrees.
fn stated_turns(message: &str) -> (f64, f64) {
    let after = |key: &str| -> f64 {
        let rest = &message[message.find(key).unwrap() + key.len()..];
        rest[..rest.find('°').unwrap()].parse().unwrap()
    };
    (after("turn A4 by "), after("and A6 by "))
}

/// The joints a reach message states after (`…, after [a1, …, a6]`).
fn stated_after(message: &str) -> Joints {
    let list = &message[message.rfind("after [").unwrap() + 7..];
    let v: Vec<f64> = list[..list.find(']').unwrap()]
        .split(", ")
        .map(|a| a.parse().unwrap())
        .collect();
    [v[0], v[1], v[2], v[3], v[4], v[5]]
}

/// A joint target the program computes when it runs (`jRun := CJointT()`) is refused as
/// runtime data, as a Cartesian one is, not moved with the track: its literal is not what the
/// robot moves to. The joint target beside it is corrected; `--keep runtime-data` writes the
/// computed one's literal unchanged.
#[test]
fn correct_refuses_a_joint_target_computed_at_run_time() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("run.mod");
    let src = "MODULE Run\n\
        \x20 VAR jointtarget jRun:=[[0,-20,30,0,80,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n\
        \x20 CONST jointtarget jBent:=[[0,-20,30,0,80,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n\
        \x20 PROC main()\n\
        \x20   jRun := CJointT();\n\
        \x20   MoveAbsJ jRun\\NoEOffs,v1000,fine,tool0;\n\
        \x20   MoveAbsJ jBent\\NoEOffs,v1000,fine,tool0;\n\
        \x20 ENDPROC\n\
        ENDMODULE\n";
    std::fs::write(&file, src).unwrap();
    let (code, doc, written) = correct_json(&file, "r1", &[]);
    assert_eq!(code, 3, "{doc}");
    assert_eq!(written, "");
    let refusals = json_refusals(&doc);
    assert_eq!(
        targets_lines_kinds(&refusals),
        [("jRun", 2, "runtime-data")]
    );
    assert!(
        refusals[0]
            .3
            .contains("is given a computed value at run time (line 5)"),
        "{}",
        refusals[0].3
    );
    let (code, doc, written) = correct_json(&file, "r1", &["--keep", "runtime-data"]);
    assert_eq!(code, 4, "{doc}");
    let line = |text: &str, n: usize| text.lines().nth(n - 1).unwrap().to_owned();
    assert_eq!(line(&written, 2), line(src, 2));
    assert_ne!(line(&written, 3), line(src, 3));
}

/// A RAPID joint target at the wrist singularity (A5 = 0), declared or inline, is refused by
/// `correct` as a `reach` refusal naming it, its A5 and the turns of A4/A6 the corrected pose
/// would need; `--keep reach` writes its literal unchanged while the bent-wrist joint target
/// beside it is corrected.
#[test]
fn correct_refuses_a_rapid_joint_target_at_the_wrist_singularity() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("wrist.mod");
    let src = "MODULE Wrist\n\
        \x20 CONST jointtarget jHome:=[[0,0,0,0,0,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n\
        \x20 CONST jointtarget jBent:=[[0,-20,30,0,80,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n\
        \x20 PROC main()\n\
        \x20   MoveAbsJ [[0,0,0,0,0,0],[1000,9E9,9E9,9E9,9E9,9E9]]\\NoEOffs,v1000,fine,tool0;\n\
        \x20   MoveAbsJ jHome\\NoEOffs,v1000,fine,tool0;\n\
        \x20   MoveAbsJ jBent\\NoEOffs,v1000,fine,tool0;\n\
        \x20 ENDPROC\n\
        ENDMODULE\n";
    std::fs::write(&file, src).unwrap();
    let (code, doc, written) = correct_json(&file, "r1", &[]);
    assert_eq!(code, 3, "{doc}");
    assert_eq!(written, "");
    let refusals = json_refusals(&doc);
    let names = targets_lines_kinds(&refusals);
    assert_eq!(
        names,
        [("jHome", 2, "reach"), ("inline jointtarget", 5, "reach")]
    );
    let profile =
        trackfix::track::Profile::load(&crate::support::root().join("samples/track/profile.toml"))
            .unwrap();
    let k = model("abb_irb4600_40_255").unwrap().kinematics();
    let zero = [0.0; 6];
    let d = profile.deviation(1000.0).unwrap();
    for (name, _, _, message) in &refusals {
        let head = if name == "jHome" {
            "jointtarget `jHome`"
        } else {
            "inline jointtarget"
        };
        assert!(
            message.starts_with(&format!(
                "{head} is at the wrist singularity (A5 = 0.0°): reaching the transformed pose would turn A4 by "
            )),
            "{message}"
        );
        // The turns stated are those of the solution that reaches D⁻¹·FK(J) from J.
        let (a4, a6) = stated_turns(message);
        assert!(a4.abs() > 5.0 && a6.abs() > 5.0, "{message}");
        assert!((a4 + a6).abs() < 0.2, "{message}");
        // The joints it states after reach the corrected pose D⁻¹·FK(J) (the track's own
        // deviation at the skid, 1000 mm) to their printed 0.0005°, and differ from J by the
        // turns stated.
        let after = stated_after(message);
        let (dp, dr) = pose_error(&k.forward(&after), &(d.inverse() * k.forward(&zero)));
        assert!(
            dp < 0.05 && dr.to_degrees() < 0.002,
            "{dp} mm {dr} rad: {message}"
        );
        assert!((after[3] - a4).abs() < 0.051 && (after[5] - a6).abs() < 0.051);
    }
    let (code, doc, written) = correct_json(&file, "r1", &["--keep", "reach"]);
    assert_eq!(code, 4, "{doc}");
    assert_eq!(json_refusals(&doc).len(), 2);
    assert!(doc["refusals"][0]["kept"].as_bool().unwrap());
    let line = |text: &str, n: usize| text.lines().nth(n - 1).unwrap().to_owned();
    assert_eq!(line(&written, 2), line(src, 2));
    assert_eq!(line(&written, 5), line(src, 5));
    assert_ne!(line(&written, 3), line(src, 3));
    let jc = joints_in(&parsed(&written), "jBent");
    let jb = [0.0, -20.0, 30.0, 0.0, 80.0, 0.0];
    assert!(
        (jc[3] - jb[3]).abs() < 0.2 && (jc[5] - jb[5]).abs() < 0.2,
        "{jc:?}"
    );
}

/// The same for a KUKA `E6AXIS` (declared and inline `PTP`): KRL joint targets take the same
/// path.
#[test]
fn correct_refuses_a_krl_joint_target_at_the_wrist_singularity() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("wrist.src");
    let src = "DEF wrist( )\n\
        \x20 DECL E6AXIS XHOME={A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0,E1 1000}\n\
        \x20 DECL E6AXIS XBENT={A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0,E1 1000}\n\
        \x20 PTP XHOME\n\
        \x20 PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0,E1 1000}\n\
        \x20 PTP XBENT\n\
        END\n";
    std::fs::write(&file, src).unwrap();
    let (code, doc, _) = correct_json(&file, "k1", &[]);
    assert_eq!(code, 3, "{doc}");
    let refusals = json_refusals(&doc);
    let names = targets_lines_kinds(&refusals);
    assert_eq!(
        names,
        [("XHOME", 2, "reach"), ("inline E6AXIS", 5, "reach")]
    );
    for (_, _, _, message) in &refusals {
        assert!(
            message.contains("is at the wrist singularity (A5 = 0.0°)"),
            "{message}"
        );
        let (a4, a6) = stated_turns(message);
        assert!(a4.abs() > 5.0 && (a4 + a6).abs() < 0.2, "{message}");
    }
    let (code, doc, written) = correct_json(&file, "k1", &["--keep", "reach"]);
    assert_eq!(code, 4, "{doc}");
    let line = |text: &str, n: usize| text.lines().nth(n - 1).unwrap().to_owned();
    assert_eq!(line(&written, 2), line(src, 2));
    assert_eq!(line(&written, 5), line(src, 5));
    assert_ne!(line(&written, 3), line(src, 3), "{written}");
}

/// `mirror` with kinematics (with or without `--mirror-joints`) keeps a singular wrist's
/// written A4/A6 split: the mirror image is exact, so IK finds `(−θ1, θ2, θ3, −θ4, θ5, −θ6)`
/// and no swing arises there.
#[test]
fn mirror_keeps_the_axis_4_and_6_split_of_a_singular_wrist() {
    use trackfix::transform::{MirrorArm, MirrorSettings, apply, mirror};
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let program = parsed(
        "MODULE M\n  CONST jointtarget jA:=[[0,0,0,30,0,-30],[500,9E9,9E9,9E9,9E9,9E9]];\n  CONST jointtarget jB:=[[0,0,0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveAbsJ jA,v100,fine,tool0;\n    MoveAbsJ jB,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n",
    );
    for mirror_joints in [false, true] {
        let settings = MirrorSettings {
            mirror_joints,
            arm: MirrorArm::of(robot, None),
            ..MirrorSettings::default()
        };
        let result = apply(&program, mirror(&program, &settings)).unwrap();
        assert!(result.refusals().next().is_none());
        let out = String::from_utf8(result.files[0].output.clone()).unwrap();
        assert!(out.contains("jA:=[[0,0,0,-30,0,30],"), "{out}");
        assert!(out.contains("jB:=[[0,0,0,0,0,0],"), "{out}");
    }
}

/// An arm whose axes 1 and 4 have asymmetric limits (axis 1 [−170°, 185°], axis 4 [−200°,
/// 300°]): the mirror image of A1 = 178° is −178°, of A4 = 250° is −250°, both outside. The
/// solution within the limits nearest to the image is then another posture: for `jA1` axis 1
/// a full turn away (182°), for `jA4` the flipped wrist (A5 negated, axes 4 and 6 half a turn
/// away). Before, `mirror` wrote those silently, exit 0 (on the IRB 4600 of the sample cell
/// with these limits `jA1` became the arm behind axis 1,
/// `[2.0000,-27.3155,-161.9866,156.7462,63.5747,-71.3814]`). Now the joint target and its
/// Cartesian twin are refused, naming the axis and the angle the image needs, and the target
/// whose image lies within the limits is mirrored by the rule.
#[test]
fn a_mirror_image_outside_asymmetric_limits_is_refused_not_taken_in_another_posture() {
    use trackfix::transform::mirror::mirrored_flange;
    use trackfix::transform::{MirrorArm, MirrorSettings, RefusalKind, apply, mirror};
    let asymmetric = CELL.replace(
        "model = \"abb_irb2400_10\"\n",
        "model = \"abb_irb2400_10\"\nlimits = [[-170, 185], [-100, 110], [-60, 65], [-200, 300], [-120, 120], [-400, 400]]\n",
    );
    let cell = Cell::parse(Path::new("cell.toml"), &asymmetric).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    let (j_a1, j_a4) = (
        [178.0, 10.0, 20.0, 30.0, 45.0, 60.0],
        [10.0, 10.0, 20.0, 250.0, 45.0, 60.0],
    );
    // The case: the rule's image is outside the limits, and the solution within them nearest
    // to it is the same pose with axis 1 a full turn away (182°), or the flipped wrist (axis 4
    // at −250° + 180°, axis 5 negated, axis 6 at −60° − 180°).
    let nearest = |j: &Joints| {
        let image = mirrored_joints(j);
        assert!(!k.within_limits(&image), "{image:?}");
        k.nearest(&mirrored_flange(&k.forward(j)), &image, false)
            .unwrap()
    };
    let turned = [182.0, 10.0, 20.0, -30.0, 45.0, -60.0];
    let flipped = [-10.0, 10.0, 20.0, -70.0, -45.0, -240.0];
    assert!(
        joints_close(&nearest(&j_a1), &turned, 1e-9),
        "{:?}",
        nearest(&j_a1)
    );
    assert!(
        joints_close(&nearest(&j_a4), &flipped, 1e-9),
        "{:?}",
        nearest(&j_a4)
    );
    let mut src = String::from(
        "MODULE M\n  PERS tooldata tGun:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n",
    );
    src += "  CONST jointtarget jA1:=[[178,10,20,30,45,60],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    src += "  CONST jointtarget jA4:=[[10,10,20,250,45,60],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    src += "  CONST jointtarget jOk:=[[10,10,20,30,45,60],[500,9E9,9E9,9E9,9E9,9E9]];\n";
    src += &robtarget(
        "pA1",
        &(b * k.forward(&j_a1) * tool),
        abb::config_of(&k, &j_a1),
        skid,
    );
    src += "  PROC main()\n    MoveAbsJ jA1,v100,fine,tGun;\n    MoveAbsJ jA4,v100,fine,tGun;\n    MoveAbsJ jOk,v100,fine,tGun;\n    MoveL pA1,v100,fine,tGun;\n  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);
    let settings = MirrorSettings {
        arm: MirrorArm::of(robot, None),
        ..MirrorSettings::default()
    };
    let result = apply(&program, mirror(&program, &settings)).unwrap();
    let refused: Vec<(&str, RefusalKind, &str)> = result
        .refusals()
        .map(|r| (r.target.as_str(), r.kind, r.message.as_str()))
        .collect();
    assert_eq!(refused.len(), 3, "{refused:#?}");
    for (name, axis, angle, limits, image) in [
        (
            "jA1",
            1,
            "-178.000",
            "[-170, 185]",
            "[-178.000, 10.000, 20.000, -30.000, 45.000, -60.000]",
        ),
        (
            "jA4",
            4,
            "-250.000",
            "[-200, 300]",
            "[-10.000, 10.000, 20.000, -250.000, 45.000, -60.000]",
        ),
        (
            "pA1",
            1,
            "-178.000",
            "[-170, 185]",
            "[-178.000, 10.000, 20.000, -30.000, 45.000, -60.000]",
        ),
    ] {
        let (_, kind, message) = refused
            .iter()
            .find(|r| r.0 == name)
            .unwrap_or_else(|| panic!("{name}: {refused:#?}"));
        assert_eq!(*kind, RefusalKind::Reach);
        assert!(
            message.contains(&format!(
                "`{name}`: its mirror image: the transformed target needs axis {axis} = {angle}°, outside its limits {limits}"
            )),
            "{message}"
        );
        assert!(
            message.contains(&format!("of the image {image}")),
            "{message}"
        );
    }
    let hint = &result.refusals().next().unwrap().hint;
    assert!(
        hint.contains("inside the range of axis 1 ([-170, 185])"),
        "{hint}"
    );
    // The one whose image lies within the limits is mirrored by the rule; the refused ones
    // keep their text.
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    assert!(out.contains("jOk:=[[-10,10,20,-30,45,-60],"), "{out}");
    for line in src
        .lines()
        .filter(|l| l.contains("jA1:=") || l.contains("jA4:=") || l.contains("pA1:="))
    {
        assert!(out.contains(line), "{line}\n{out}");
    }
}

/// A target a routine moves to with its tool parameter (`PROC Weld(robtarget p, PERS
/// tooldata t)`) is reached with whichever tool each caller passes: its joints cannot be
/// checked, and it is refused as such by name and line, not as "not used with a tool". The
/// target moved to with the declared tool beside it is corrected.
#[test]
fn correct_refuses_a_target_moved_with_a_tool_parameter_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("param.mod");
    let src = "MODULE Param\n\
        \x20 PERS tooldata tGun1:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\n\
        \x20 TASK PERS wobjdata wobj_car:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[0.999962,0,0,0.008727]]];\n\
        \x20 CONST robtarget Sp001:=[[-1499.39,-722.85,251.51],[0.001394,-0.982620,-0.185474,-0.007385],[-1,0,-2,0],[150.0,9E+09,9E+09,9E+09,9E+09,9E+09]];\n\
        \x20 CONST robtarget Sp002:=[[-1442.86,-646.25,295.65],[0.003079,0.983580,0.179657,-0.016858],[-1,0,-2,0],[185.8,9E+09,9E+09,9E+09,9E+09,9E+09]];\n\
        \x20 PROC Weld(robtarget p, PERS tooldata t)\n\
        \x20   MoveL p, v100, fine, t\\WObj:=wobj_car;\n\
        \x20 ENDPROC\n\
        \x20 PROC main()\n\
        \x20   Weld Sp001, tGun1;\n\
        \x20   MoveL Sp002, v100, fine, tGun1\\WObj:=wobj_car;\n\
        \x20 ENDPROC\n\
        ENDMODULE\n";
    std::fs::write(&file, src).unwrap();
    let (code, doc, _) = correct_json(&file, "r1", &[]);
    assert_eq!(code, 3, "{doc}");
    let refusals = json_refusals(&doc);
    assert_eq!(targets_lines_kinds(&refusals), [("Sp001", 4, "reach")]);
    assert_eq!(
        refusals[0].3,
        "robtarget `Sp001` is moved to on line 10 with `t`, a parameter of the routine: the tool is whichever one each caller passes, so its joints cannot be checked"
    );
    let (code, doc, written) = correct_json(&file, "r1", &["--keep", "reach"]);
    assert_eq!(code, 4, "{doc}");
    let line = |text: &str, n: usize| text.lines().nth(n - 1).unwrap().to_owned();
    assert_eq!(line(&written, 4), line(src, 4));
    assert_ne!(line(&written, 5), line(src, 5));
}

// ---- no axis turned to stay within its limits, no swing, configurations named ----

/// `chain_fk` as a pose.
fn chain_pose(k: &Kinematics, j: &Joints) -> Pose {
    let m = chain_fk(k, j);
    let r = Rotation3::from_matrix_unchecked(m.fixed_view::<3, 3>(0, 0).into_owned());
    Pose::from_parts(
        Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// The joints a reach message states before (`joints before [a1, …, a6]`).
fn stated_before(message: &str) -> Joints {
    let list = &message[message.find("joints before [").unwrap() + 15..];
    let v: Vec<f64> = list[..list.find(']').unwrap()]
        .split(", ")
        .map(|a| a.parse().unwrap())
        .collect();
    [v[0], v[1], v[2], v[3], v[4], v[5]]
}

/// The robot `name` of samples/cell.toml, and its nominal base `B(s) = Trans(s·a)·B0`.
fn sample_robot(name: &str) -> (Kinematics, impl Fn(f64) -> Pose) {
    let cell = Cell::load(&crate::support::root().join("samples/cell.toml")).unwrap();
    let robot = cell.robot(name).unwrap();
    let (b0, a) = (robot.base0, robot.track_axis);
    let base = move |s: f64| Translation3::from(a * s) * b0;
    (robot.kinematics.clone().unwrap(), base)
}

/// The deviation `D(s)` of the sample track (samples/track/profile.toml, r1's and k1's).
fn sample_deviation(s: f64) -> Pose {
    let profile =
        trackfix::track::Profile::load(&crate::support::root().join("samples/track/profile.toml"))
            .unwrap();
    profile.deviation(s).unwrap()
}

/// Runs `trackfix ARGS --cell samples/cell.toml --out-dir DIR --no-stamp --format json`: the
/// exit code and the refusals of the JSON report.
fn transform_json(args: &[&str], dir: &Path) -> (i32, Vec<(String, u64, String, String)>) {
    let out = dir.join("out");
    let _ = std::fs::remove_dir_all(&out);
    let tail = [
        "--cell",
        "samples/cell.toml",
        "--out-dir",
        out.to_str().unwrap(),
        "--no-stamp",
        "--format",
        "json",
    ];
    let (code, stdout, err) = trackfix(&[args, &tail[..]].concat());
    let doc: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!("{e}: {stdout}\n{err}");
    });
    (code, json_refusals(&doc))
}

/// KUKA `A, B, C` (degrees) of a rotation `Rz(A)·Ry(B)·Rx(C)`, away from `B = ±90°`.
fn kuka_abc_of(p: &Pose) -> [f64; 3] {
    let r = p.rotation.to_rotation_matrix().into_inner();
    [
        r[(1, 0)].atan2(r[(0, 0)]).to_degrees(),
        (-r[(2, 0)]).asin().to_degrees(),
        r[(2, 1)].atan2(r[(2, 2)]).to_degrees(),
    ]
}

/// A KRL `E6POS` declaration of world pose `t` with Status/Turn at skid `e1`.
fn e6pos(name: &str, t: &Pose, s: u32, turn: u32, e1: f64) -> String {
    let p = t.translation.vector;
    let [a, b, c] = kuka_abc_of(t);
    format!(
        "DECL E6POS {name}={{X {:.4},Y {:.4},Z {:.4},A {a:.5},B {b:.5},C {c:.5},S {s},T {turn},E1 {e1:.1},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}\n",
        p.x, p.y, p.z
    )
}

/// Writes a KRL pair `name.src`/`name.dat` into `dir` with the declarations `decls`, moving
/// to each with `PTP` in the order given; the `.src` path.
fn krl_pair(dir: &Path, name: &str, decls: &[(&str, String)]) -> std::path::PathBuf {
    let mut src = format!("DEF {name}( )\n  BAS(#INITMOV,0)\n  BAS(#BASE,0)\n  BAS(#TOOL,0)\n");
    let mut dat = format!("DEFDAT {name}\n");
    for (target, decl) in decls {
        src += &format!("  PTP {target}\n");
        dat += decl;
    }
    src += "END\n";
    dat += "ENDDAT\n";
    std::fs::write(dir.join(format!("{name}.dat")), dat).unwrap();
    let path = dir.join(format!("{name}.src"));
    std::fs::write(&path, src).unwrap();
    path
}

/// KUKA Turn of joints, worked out here: bit i set when axis i+1 is negative.
fn turn_bits(j: &Joints) -> u32 {
    (0..6).map(|i| u32::from(j[i] < 0.0) << i).sum()
}

/// KUKA Status bits 0-2 of joints on a KR 210, worked out here from the elementary chain:
/// bit 0 the wrist centre behind axis 1 (negative x in the frame turned by A1), bit 1 A3 at
/// or above φ = atan2(115, 1420) (the forearm's offset: the wrist in front of the lower arm),
/// bit 2 A5 negative.
fn kr210_status(k: &Kinematics, j: &Joints) -> u32 {
    let m = chain_fk(k, j);
    let wrist = Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)])
        - k.geometry.c4 * Vector3::new(m[(0, 2)], m[(1, 2)], m[(2, 2)]);
    // KUKA's A1 turns the arm clockwise seen from above (sign −1).
    let a1 = -j[0].to_radians();
    let x1 = wrist.x * a1.cos() + wrist.y * a1.sin();
    let phi = 115f64.atan2(1420.0).to_degrees();
    u32::from(x1 < 0.0) | u32::from(j[2] >= phi) << 1 | u32::from(j[4] < 0.0) << 2
}

/// A joint target at the end of a 360°-wide axis 1 (the IRB 2400's ±180°) that the
/// correction turns outward is refused with the angle it needs, where it was written a full
/// turn away (axis 1 swinging across the cell); one turned inward is moved. The deviations are
/// rotations about the base's z axis, which is axis 1: the corrected joints are the written
/// ones with axis 1 turned by the rotation, exactly (checked through the elementary chain).
/// Beyond the limit by less than half a unit of the last decimal written the axis is written
/// at the limit (its text could not say otherwise); by more, refused with the decimals that
/// show it.
#[test]
fn a_joint_target_at_the_end_of_axis_1_is_refused_not_turned_a_full_turn() {
    use trackfix::transform::{Direction, RefusalKind, TrackSetup, apply, track_correction};
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    assert_eq!(k.limits[0], [-180.0, 180.0]);
    // D(s) = Rz(−δ(s)): `correct` applies D⁻¹ = Rz(δ) in the base, turning axis 1 by +δ.
    let delta = |s: f64| match s {
        s if s < 1000.0 => 0.01,
        s if s < 2500.0 => 0.000013,
        _ => 0.00002,
    };
    let dev = move |s: f64| -> Result<Pose, trackfix::track::TrackError> {
        Ok(pose_xyz_deg(0.0, 0.0, 0.0, 0.0, 0.0, -delta(s)))
    };
    let decl = |name: &str, a1: &str, skid: u32| {
        format!(
            "  CONST jointtarget {name}:=[[{a1},10,20,30,45,60],[{skid},9E9,9E9,9E9,9E9,9E9]];\n"
        )
    };
    let names = ["jPark", "jBack", "jNear", "jOver"];
    let mut src = String::from("MODULE M\n");
    src += &decl("jPark", "180", 500);
    src += &decl("jBack", "-180", 500);
    src += &decl("jNear", "179.99999", 2000);
    src += &decl("jOver", "179.99999", 3000);
    src += "  PROC main()\n";
    for n in names {
        src += &format!("    MoveAbsJ {n},v100,fine,tool0;\n");
    }
    src += "  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);
    let setup = TrackSetup::new(robot, &dev);
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let refusals: Vec<_> = result.refusals().collect();
    let refused: Vec<_> = refusals
        .iter()
        .map(|r| (r.target.as_str(), r.kind))
        .collect();
    assert_eq!(
        refused,
        [("jPark", RefusalKind::Reach), ("jOver", RefusalKind::Reach)]
    );
    assert!(
        refusals[0]
            .message
            .contains("needs axis 1 = 180.010°, outside its limits [-180, 180]"),
        "{}",
        refusals[0].message
    );
    // The joints it would need: axis 1 turned by δ, nothing else.
    let after = stated_after(&refusals[0].message);
    let want = [180.01, 10.0, 20.0, 30.0, 45.0, 60.0];
    assert!(joints_close(&after, &want, 6e-4), "{}", refusals[0].message);
    // 1e-5° beyond, twice the half unit of 5 decimals: shown with 5.
    assert!(
        refusals[1]
            .message
            .contains("needs axis 1 = 180.00001°, outside its limits [-180, 180]"),
        "{}",
        refusals[1].message
    );
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    let corrected = parsed(&out);
    let j = [-180.0, 10.0, 20.0, 30.0, 45.0, 60.0];
    let jb = joints_in(&corrected, "jBack");
    let (dp, dr) = pose_error(
        &chain_pose(&k, &jb),
        &(pose_xyz_deg(0.0, 0.0, 0.0, 0.0, 0.0, 0.01) * chain_pose(&k, &j)),
    );
    assert!(dp < 1e-6 && dr < 1e-9, "{dp} mm {dr} rad: {jb:?}");
    assert!((jb[0] + 179.99).abs() < 1e-9, "{jb:?}");
    // 180.000003: 3e-6° beyond, within half of 1e-5: written at the limit, the other axes'
    // text kept.
    assert!(out.contains("jNear:=[[180.00000,10,20,30,45,60],"), "{out}");
    for n in ["jPark", "jOver"] {
        let line = |text: &str| text.lines().find(|l| l.contains(n)).unwrap().to_owned();
        assert_eq!(line(&out), line(&src));
    }
}

/// `correct` then `zero` of joint targets at a limit (samples/cell.toml, r1 on the measured
/// track, skid 4000): A5 at −125° and A1 at −180° are turned inward by `correct` and written
/// to four decimals; `zero` of those brings them back beyond their limits by a few 1e-5°, the
/// rounding of the written text: within half its last unit, so they come back to their text.
/// A1 at +180° is turned outward: refused, kept as written, the angle it needs stated
/// (the corrected pose, D(s)⁻¹ of the written one, checked through the elementary chain).
#[test]
fn correct_then_zero_gives_back_joint_targets_at_their_limits() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("lim.mod");
    let decls = [
        "  CONST jointtarget jA5:=[[10,10,20,30,-125,60],[4000,9E9,9E9,9E9,9E9,9E9]];\n",
        "  CONST jointtarget jA1:=[[-180,10,20,30,45,60],[4000,9E9,9E9,9E9,9E9,9E9]];\n",
        "  CONST jointtarget jOut:=[[180,10,20,30,45,60],[4000,9E9,9E9,9E9,9E9,9E9]];\n",
    ];
    let src = format!(
        "MODULE Lim\n{}  PROC main()\n    MoveAbsJ jA5,v100,fine,tool0;\n    MoveAbsJ jA1,v100,fine,tool0;\n    MoveAbsJ jOut,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n",
        decls.concat()
    );
    std::fs::write(&file, &src).unwrap();
    let corrected = dir.path().join("c.mod");
    let zeroed = dir.path().join("z.mod");
    let args = |cmd: &str, from: &Path, to: &Path| {
        [
            cmd,
            from.to_str().unwrap(),
            "--cell",
            "samples/cell.toml",
            "--robot",
            "r1",
            "-o",
            to.to_str().unwrap(),
            "--keep",
            "reach",
        ]
        .map(str::to_owned)
    };
    let run = |a: [String; 10]| trackfix(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let (code, _, err) = run(args("correct", &file, &corrected));
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("jointtarget `jOut`: the transformed target needs axis 1 = 180.007°, outside its limits [-180, 180]"),
        "{err}"
    );
    let (k, _) = sample_robot("r1");
    let d = sample_deviation(4000.0);
    let message = err.lines().find(|l| l.contains("`jOut`")).unwrap();
    let jout = [180.0, 10.0, 20.0, 30.0, 45.0, 60.0];
    let after = stated_after(message);
    assert!(after[0] > 180.0, "{message}");
    let (dp, dr) = pose_error(
        &chain_pose(&k, &after),
        &(d.inverse() * chain_pose(&k, &jout)),
    );
    // The stated joints are rounded to 0.0005°.
    assert!(dp < 0.05 && dr.to_degrees() < 0.002, "{dp} mm {dr} rad");
    let text = std::fs::read_to_string(&corrected).unwrap();
    let jc = joints_in(&parsed(&text), "jA5");
    assert!(jc[4] > -125.0, "{jc:?}");
    // The corrected joints reach D⁻¹ of the written pose to their written precision.
    let (dp, dr) = pose_error(
        &chain_pose(&k, &jc),
        &(d.inverse() * chain_pose(&k, &[10.0, 10.0, 20.0, 30.0, -125.0, 60.0])),
    );
    assert!(dp < 0.01 && dr.to_degrees() < 2e-4, "{dp} mm {dr} rad");
    assert!(text.contains(decls[2]), "{text}");
    // The stamp lists jOut as kept as written, so zero leaves it as it is.
    let (code, _, err) = run(args("zero", &corrected, &zeroed));
    assert_eq!(code, 0, "{err}");
    let back = std::fs::read_to_string(&zeroed).unwrap();
    for decl in &decls {
        assert!(back.contains(decl), "{decl}{back}");
    }
}

/// `correct` then `zero` of joint targets half a degree from the wrist singularity (r1 on the
/// measured track) gives back their text. `zero` turns axes 4 and 6 by 3.4 times the rounding
/// of the corrected axis 5 there: `jW05` corrected is A4 38.26132, A5 0.52665, A6 61.72262, and
/// its plain rounding (38.2613, 0.5267, 61.7226) came back as A4 39.9998 and A6 60.0001. It is
/// now written with `zero` in view, A4 and A6 stepped by what `zero` misses (38.2615, 61.7225),
/// which reaches the corrected pose to the text's precision as plain rounding does. The same
/// with six decimals (39.999999 and 60.000001 before) and on the other side of the singularity.
#[test]
fn correct_then_zero_gives_back_joint_targets_near_the_wrist_singularity() {
    let dir = tempfile::tempdir().unwrap();
    let decls = [
        "  CONST jointtarget jW05:=[[10,20,30,40,0.5,60],[4000,9E9,9E9,9E9,9E9,9E9]];\n",
        "  CONST jointtarget jW6:=[[10.000000,20.000000,30.000000,40.000000,0.500000,60.000000],[4000,9E9,9E9,9E9,9E9,9E9]];\n",
        "  CONST jointtarget jWn:=[[-35,10,5,-120,-0.5,170],[1500,9E9,9E9,9E9,9E9,9E9]];\n",
    ];
    let src = format!(
        "MODULE Wrist\n{}  PROC main()\n    MoveAbsJ jW05,v100,fine,tool0;\n    MoveAbsJ jW6,v100,fine,tool0;\n    MoveAbsJ jWn,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n",
        decls.concat()
    );
    let file = dir.path().join("wrist.mod");
    std::fs::write(&file, &src).unwrap();
    let (corrected, zeroed) = (dir.path().join("c.mod"), dir.path().join("z.mod"));
    let run = |cmd: &str, from: &Path, to: &Path| {
        let (from, to) = (from.to_str().unwrap(), to.to_str().unwrap());
        trackfix(&[
            cmd,
            from,
            "--cell",
            "samples/cell.toml",
            "--robot",
            "r1",
            "-o",
            to,
        ])
    };
    let (code, _, err) = run("correct", &file, &corrected);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&corrected).unwrap();
    assert!(
        text.contains("jW05:=[[9.9738,19.9348,30.0358,38.2615,0.5267,61.7225],"),
        "{text}"
    );
    // The written joints reach D⁻¹ of the original pose to their written precision, as plain
    // rounding does (2.1e-3 mm and 7.5e-5° for jW05 plainly, 8.9e-5° so).
    let (k, _) = sample_robot("r1");
    for (name, skid, j, mm, deg) in [
        (
            "jW05",
            4000.0,
            [10.0, 20.0, 30.0, 40.0, 0.5, 60.0],
            0.005,
            2e-4,
        ),
        (
            "jW6",
            4000.0,
            [10.0, 20.0, 30.0, 40.0, 0.5, 60.0],
            5e-5,
            2e-6,
        ),
        (
            "jWn",
            1500.0,
            [-35.0, 10.0, 5.0, -120.0, -0.5, 170.0],
            0.005,
            2e-4,
        ),
    ] {
        let d = sample_deviation(skid);
        let jc = joints_in(&parsed(&text), name);
        let (dp, dr) = pose_error(&chain_pose(&k, &jc), &(d.inverse() * chain_pose(&k, &j)));
        assert!(
            dp < mm && dr.to_degrees() < deg,
            "{name}: {dp} mm {} deg",
            dr.to_degrees()
        );
    }
    let (code, _, err) = run("zero", &corrected, &zeroed);
    assert_eq!(code, 0, "{err}");
    let back = std::fs::read_to_string(&zeroed).unwrap();
    assert_eq!(back, src);
}

/// The same on the KUKA arm: `E6AXIS` with A1 at 185° (the KR 210's limit) at E1 1500 needs
/// 185.059° after `correct`, and is refused as such, where it was written at −174.94°.
#[test]
fn correct_refuses_a_krl_axis_1_beyond_its_limit_instead_of_a_turn() {
    let dir = tempfile::tempdir().unwrap();
    let decl = "DECL E6AXIS XPARK={A1 185.0,A2 -80.0,A3 100.0,A4 30.0,A5 45.0,A6 60.0,E1 1500.0}\n";
    let src = krl_pair(dir.path(), "a1wrap", &[("XPARK", decl.to_owned())]);
    let (code, refusals) = transform_json(
        &["correct", src.to_str().unwrap(), "--robot", "k1"],
        dir.path(),
    );
    assert_eq!(code, 3, "{refusals:?}");
    assert_eq!(targets_lines_kinds(&refusals), [("XPARK", 2, "reach")]);
    let message = &refusals[0].3;
    assert!(
        message.contains("needs axis 1 = 185.059°, outside its limits [-185, 185]"),
        "{message}"
    );
    let (k, _) = sample_robot("k1");
    let j = [185.0, -80.0, 100.0, 30.0, 45.0, 60.0];
    let after = stated_after(message);
    let (dp, dr) = pose_error(
        &chain_pose(&k, &after),
        &(sample_deviation(1500.0).inverse() * chain_pose(&k, &j)),
    );
    assert!(dp < 0.05 && dr.to_degrees() < 0.002, "{dp} mm {dr} rad");
    assert!((after[0] - 185.059).abs() < 1e-9, "{message}");
}

/// A configuration the corrected pose needs is named as one, not as an axis a turn away:
/// KUKA points with A1, A3 or A6 a few thousandths of a degree below 0 (their Turn or Status
/// bit set) that the correction takes above it (k1 at E1 4000, made from the joints by the
/// elementary chain) "need configuration S … T … instead of S … T …" — the Status and Turn of
/// the joints stated after, worked out here — where they "needed axis 1 = -359.982°"; an ABB
/// target with A5 = −0.01° (cfx 1) names the configuration it would need, `[0,0,0,0]`, and
/// the written `[0,0,0,1]`, where it "needed axis 5 = -359.972°".
#[test]
fn a_configuration_change_is_named_as_one_not_as_a_turn() {
    let dir = tempfile::tempdir().unwrap();
    let (k, base) = sample_robot("k1");
    let cases: [(&str, Joints); 3] = [
        ("XA1N", [-0.005, -80.0, 100.0, 30.0, 45.0, 60.0]),
        ("XA3ZN", [10.0, -40.0, -0.01, 30.0, 45.0, 60.0]),
        ("XA6", [10.0, -80.0, 100.0, 30.0, 45.0, -0.005]),
    ];
    let decls: Vec<(&str, String)> = cases
        .iter()
        .map(|(n, j)| {
            let t = base(4000.0) * chain_pose(&k, j);
            (*n, e6pos(n, &t, kr210_status(&k, j), turn_bits(j), 4000.0))
        })
        .collect();
    let src = krl_pair(dir.path(), "cfg", &decls);
    let (code, refusals) = transform_json(
        &["correct", src.to_str().unwrap(), "--robot", "k1"],
        dir.path(),
    );
    assert_eq!(code, 3, "{refusals:?}");
    let names: Vec<&str> = refusals.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(names, ["XA1N", "XA3ZN", "XA6"]);
    for ((_, j), (name, _, kind, message)) in cases.iter().zip(&refusals) {
        assert_eq!(kind, "reach");
        let after = stated_after(message);
        let want = format!(
            "needs configuration S {} T {} instead of S {} T {}",
            kr210_status(&k, &after),
            turn_bits(&after),
            kr210_status(&k, j),
            turn_bits(j)
        );
        assert!(message.contains(&want), "{name}: {want}: {message}");
        assert_ne!(turn_bits(&after), turn_bits(j), "{message}");
        assert!(!message.contains("359") && !message.contains("outside its limits"));
        // The joints stated are where the arm goes: by the correction's own size.
        assert!(joints_close(&after, j, 0.3), "{message}");
    }
    // ABB: cfx 1 (A5 < 0) written, the corrected pose has A5 > 0.
    let (k, base) = sample_robot("r1");
    let j = [10.0, 10.0, 20.0, 30.0, -0.01, 60.0];
    let file = dir.path().join("cfx.mod");
    let decl = robtarget(
        "p18",
        &(base(4000.0) * chain_pose(&k, &j)),
        [0, 0, 0, 1],
        4000.0,
    );
    std::fs::write(
        &file,
        format!("MODULE Cfx\n{decl}  PROC main()\n    MoveJ p18, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n"),
    )
    .unwrap();
    let (code, refusals) = transform_json(
        &["correct", file.to_str().unwrap(), "--robot", "r1"],
        dir.path(),
    );
    assert_eq!(code, 3, "{refusals:?}");
    let message = &refusals[0].3;
    assert!(
        message.contains("configuration [0,0,0,0]")
            && message.contains("[0,0,0,1]")
            && !message.contains("359")
            && !message.contains("outside its limits"),
        "{message}"
    );
    assert!(stated_after(message)[4] > 0.0, "{message}");
}

/// A Cartesian target near the wrist singularity is refused by every transform that would
/// keep its configuration: ABB A5 = 0.01° with A4 = −100° (`[0,-2,-1,0]`) on the IRB 2400 of
/// the test cell, corrected and zeroed with a deviation of a few hundredths of a degree,
/// whose tilt points the wrist elsewhere. `correct`: the written configuration selects joints
/// with A4 near −157°; `zero` tilts the other way, where only `cfx` 1 reaches the pose, with
/// the same swing. The joints stated after reach the new pose (checked through the elementary
/// chain) with the turns stated, and the configuration named is theirs (quadrants and the
/// sign of A5 worked out here); before this check `correct` wrote the target and the robot
/// would swing its wrist. The same pose with A5 = 40° is corrected; `mirror` keeps the
/// singular target (its image is exact, the mirrored joints' configuration by the rule).
#[test]
fn a_cartesian_target_at_the_wrist_singularity_is_refused_not_swung() {
    use trackfix::transform::{
        Direction, MirrorArm, MirrorSettings, RefusalKind, TrackSetup, apply, mirror,
        track_correction,
    };
    let cell = Cell::parse(Path::new("cell.toml"), CELL).unwrap();
    let robot = cell.robot("r1").unwrap();
    let k = robot.kinematics.clone().unwrap();
    let tool = robot.tools["tgun"];
    let skid = 500.0;
    let b = pose_xyz_deg(skid, -1000.0, 0.0, 0.0, 0.0, 90.0);
    let singular = [10.0, 20.0, -10.0, -100.0, 0.01, -80.0];
    let bent = [10.0, 20.0, -10.0, -100.0, 40.0, -80.0];
    // ⌊θ/90°⌋ of axes 1, 4 and 6; the wrist in front of axis 1 and of the lower arm, A5 ≥ 0.
    let quadrants = |j: &Joints| [0, 3, 5].map(|i| (j[i] / 90.0).floor() as i32);
    let [cf1, cf4, cf6] = quadrants(&singular);
    assert_eq!([cf1, cf4, cf6], [0, -2, -1]);
    let cf = [cf1, cf4, cf6, 0];
    let mut src = String::from(
        "MODULE M\n  PERS tooldata tGun:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n",
    );
    src += &robtarget("pSing", &(b * chain_pose(&k, &singular) * tool), cf, skid);
    src += &robtarget("pBent", &(b * chain_pose(&k, &bent) * tool), cf, skid);
    src += "  PROC main()\n    MoveJ pSing,v100,fine,tGun;\n    MoveJ pBent,v100,fine,tGun;\n  ENDPROC\nENDMODULE\n";
    let program = parsed(&src);
    let d = deviation();
    let dev = move |_s: f64| -> Result<Pose, trackfix::track::TrackError> { Ok(d) };
    let setup = TrackSetup::new(robot, &dev);
    for (dir, change) in [(Direction::Correct, d.inverse()), (Direction::Zero, d)] {
        let result = apply(&program, track_correction(&program, &setup, dir)).unwrap();
        let refusals: Vec<_> = result.refusals().collect();
        assert_eq!(refusals.len(), 1, "{dir:?}: {refusals:?}");
        let r = &refusals[0];
        let m = &r.message;
        assert_eq!((r.target.as_str(), r.kind), ("pSing", RefusalKind::Reach));
        let head = "robtarget `pSing` is at the wrist singularity (A5 = 0.01°): reaching the \
                    transformed pose with configuration ";
        assert!(m.starts_with(head), "{m}");
        let (a4, a6) = stated_turns(m);
        assert!(a4.abs() > 5.0 && a6.abs() > 5.0, "{m}");
        let (before, after) = (stated_before(m), stated_after(m));
        // The joints before are the written ones (A4/A6 split by the written precision).
        assert!(joints_close(&before, &singular, 0.05), "{m}");
        // After: the new pose C·F, turned by what is stated.
        let (dp, dr) = pose_error(
            &chain_pose(&k, &after),
            &(change * chain_pose(&k, &singular)),
        );
        assert!(dp < 0.05 && dr.to_degrees() < 0.003, "{dp} mm {dr} rad");
        assert!((after[3] - before[3] - a4).abs() < 0.06, "{m}");
        assert!((after[5] - before[5] - a6).abs() < 0.06, "{m}");
        // The arm axes move by the correction's size (the wrist stays in front of axis 1 and
        // of the lower arm), so cfx is the sign of A5: the configuration named is the one of
        // the joints after; the written one is named too where it is not theirs.
        let arm = |j: &Joints| [j[0], j[1], j[2], 0.0, 0.0, 0.0];
        assert!(joints_close(&arm(&after), &arm(&singular), 0.5), "{m}");
        let [c1, c4, c6] = quadrants(&after);
        let solved = format!("[{c1},{c4},{c6},{}]", i32::from(after[4] < 0.0));
        assert!(m.starts_with(&format!("{head}{solved} would turn")), "{m}");
        let also_written = m.contains("(it is written with [0,-2,-1,0], which does not reach it)");
        assert_eq!(also_written, solved != "[0,-2,-1,0]", "{m}");
        // `correct` swings in the written configuration, `zero` needs cfx 1 as well.
        assert_eq!(also_written, dir == Direction::Zero, "{m}");
        let out = String::from_utf8(result.files[0].output.clone()).unwrap();
        let line = |text: &str, n: &str| text.lines().find(|l| l.contains(n)).unwrap().to_owned();
        assert_eq!(line(&out, "pSing:="), line(&src, "pSing:="));
        assert_ne!(line(&out, "pBent:="), line(&src, "pBent:="));
    }
    let settings = MirrorSettings {
        arm: MirrorArm::of(robot, None),
        ..MirrorSettings::default()
    };
    let result = apply(&program, mirror(&program, &settings)).unwrap();
    assert!(
        result.refusals().next().is_none(),
        "{:?}",
        result.refusals().collect::<Vec<_>>()
    );
    let out = String::from_utf8(result.files[0].output.clone()).unwrap();
    let p = parsed(&out).files[0]
        .positions()
        .find(|p| p.name.as_deref() == Some("pSing"))
        .unwrap();
    // (−θ1, θ2, θ3, −θ4, θ5, −θ6) = (−10, 20, −10, 100, 0.01, 80): quadrants −1, 1, 0; cfx 0.
    assert_eq!(
        ConfigValue::written(&p.config),
        Some(ConfigValue::Quadrants([-1, 1, 0, 0]))
    );
}

/// The KUKA point of the probe: A5 = −0.01° written `S 6 T 18` on k1 at E1 4000 (made from
/// the joints by the elementary chain). `correct`, `zero` and `transfer` refuse it with the
/// turns its written Status/Turn would take the wrist through: the joints stated after reach
/// D(s)⁻¹·F and carry Turn 18 and A5 < 0 (worked out here), A4 and A6 turned by over 100°.
/// `mirror` for the mirror-image robot writes it (that image is exact); `mirror --to k2`
/// refuses it, since k2's real base is not the exact image of k1's and the tilt between them
/// swings the wrist as a correction does; the bent point beside it is corrected.
#[test]
fn a_krl_point_at_the_wrist_singularity_is_refused_by_every_transform() {
    let dir = tempfile::tempdir().unwrap();
    let (k, base) = sample_robot("k1");
    let singular = [10.0, -80.0, 100.0, 30.0, -0.01, 60.0];
    let bent = [10.0, -80.0, 100.0, 30.0, -40.0, 60.0];
    // S: A3 above φ (2), A5 negative (4); T: A2 and A5 negative (2 + 16).
    assert_eq!((kr210_status(&k, &singular), turn_bits(&singular)), (6, 18));
    let decls = [
        (
            "XA5",
            e6pos(
                "XA5",
                &(base(4000.0) * chain_pose(&k, &singular)),
                6,
                18,
                4000.0,
            ),
        ),
        (
            "XBENT",
            e6pos(
                "XBENT",
                &(base(4000.0) * chain_pose(&k, &bent)),
                6,
                18,
                4000.0,
            ),
        ),
    ];
    let src = krl_pair(dir.path(), "sing", &decls);
    let src = src.to_str().unwrap();
    let (code, refusals) = transform_json(&["correct", src, "--robot", "k1"], dir.path());
    assert_eq!(code, 3, "{refusals:?}");
    assert_eq!(targets_lines_kinds(&refusals), [("XA5", 2, "reach")]);
    let message = &refusals[0].3;
    assert!(
        message.starts_with("E6POS `XA5` is at the wrist singularity (A5 = -0.01°): reaching the transformed pose with configuration S 6 T 18 would turn A4 by "),
        "{message}"
    );
    let after = stated_after(message);
    let (dp, dr) = pose_error(
        &chain_pose(&k, &after),
        &(sample_deviation(4000.0).inverse() * chain_pose(&k, &singular)),
    );
    assert!(dp < 0.05 && dr.to_degrees() < 0.003, "{dp} mm {dr} rad");
    assert_eq!(turn_bits(&after), 18, "{message}");
    assert_eq!(kr210_status(&k, &after), 6, "{message}");
    let (a4, a6) = stated_turns(message);
    assert!(a4.abs() > 100.0 && a6.abs() > 100.0, "{message}");
    for args in [
        &["zero", src, "--robot", "k1", "--force"][..],
        &["transfer", src, "--from", "k1", "--to", "k2", "--mirror"][..],
    ] {
        let (code, refusals) = transform_json(args, dir.path());
        assert_eq!(code, 3, "{args:?}: {refusals:?}");
        assert_eq!(targets_lines_kinds(&refusals), [("XA5", 2, "reach")]);
        assert!(
            refusals[0]
                .3
                .contains("is at the wrist singularity (A5 = -0.01°)"),
            "{args:?}: {}",
            refusals[0].3
        );
    }
    let (code, refusals) = transform_json(&["mirror", src, "--robot", "k1"], dir.path());
    assert_eq!((code, refusals.len()), (0, 0), "{refusals:?}");
    let (code, refusals) =
        transform_json(&["mirror", src, "--robot", "k1", "--to", "k2"], dir.path());
    assert_eq!(code, 3, "{refusals:?}");
    assert_eq!(targets_lines_kinds(&refusals), [("XA5", 2, "reach")]);
    assert!(
        refusals[0]
            .3
            .contains("is at the wrist singularity (A5 = -0.01°)"),
        "{}",
        refusals[0].3
    );
}
