//! One constructor and one writer per external rotation convention (docs/design.md §2).
//!
//! Every conversion between a file's numbers and a rotation goes through exactly one function
//! here, so a convention lives in one place.

use nalgebra::{Isometry3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A rigid transform: `a * b` is `b` expressed in `a`.
pub type Pose = Isometry3<f64>;

/// Wraps degrees to (-180, 180]: a measured 359.9981 is -0.0019.
pub fn wrap_deg(a: f64) -> f64 {
    let mut w = a % 360.0;
    if w <= -180.0 {
        w += 360.0;
    } else if w > 180.0 {
        w -= 360.0;
    }
    w
}

/// Rotation from fixed-axis angles in degrees: `R = Rz(rz)·Ry(ry)·Rx(rx)` (profiles and CSV
/// files; the thesis's α, β, γ, eq. 3.25).
pub fn xyz_deg(rx: f64, ry: f64, rz: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(rx.to_radians(), ry.to_radians(), rz.to_radians())
}

/// `[rx, ry, rz]` in degrees, wrapped to (-180, 180], of a rotation (inverse of [`xyz_deg`]).
pub fn xyz_deg_angles(r: &UnitQuaternion<f64>) -> [f64; 3] {
    let (rx, ry, rz) = r.euler_angles();
    [
        wrap_deg(rx.to_degrees()),
        wrap_deg(ry.to_degrees()),
        wrap_deg(rz.to_degrees()),
    ]
}

/// A pose from a translation in mm and [`xyz_deg`] angles.
pub fn pose_xyz_deg(x: f64, y: f64, z: f64, rx: f64, ry: f64, rz: f64) -> Pose {
    Isometry3::from_parts(Translation3::new(x, y, z), xyz_deg(rx, ry, rz))
}

/// `[x, y, z, rx, ry, rz]` of a pose (inverse of [`pose_xyz_deg`]).
pub fn pose_to_xyz_deg(p: &Pose) -> [f64; 6] {
    let t = p.translation.vector;
    let [rx, ry, rz] = xyz_deg_angles(&p.rotation);
    [t.x, t.y, t.z, rx, ry, rz]
}

/// ABB `orient [q1, q2, q3, q4]`, scalar first (`q1 = w`). `None` for a zero quaternion.
///
/// `Quaternion::from(Vector4)` reads `[i, j, k, w]` and is a trap: never use it for ABB data.
pub fn abb_quat(q: [f64; 4]) -> Option<UnitQuaternion<f64>> {
    let raw = Quaternion::new(q[0], q[1], q[2], q[3]);
    let norm = raw.norm();
    if !norm.is_finite() || norm < 1e-9 {
        return None;
    }
    Some(UnitQuaternion::from_quaternion(raw))
}

/// `[q1, q2, q3, q4]` of a rotation, normalised, with the overall sign that lies closest to
/// `like` (the quaternion the file had), so a rewritten target does not flip sign needlessly.
pub fn abb_quat_components(r: &UnitQuaternion<f64>, like: Option<[f64; 4]>) -> [f64; 4] {
    let q = r.quaternion();
    let c = [q.w, q.i, q.j, q.k];
    let flip = match like {
        Some(l) => c.iter().zip(l).map(|(a, b)| a * b).sum::<f64>() < 0.0,
        None => c[0] < 0.0,
    };
    if flip { c.map(|v| -v) } else { c }
}

/// KUKA `A, B, C` in degrees: `R = Rz(A)·Ry(B)·Rx(C)` (intrinsic Z-Y'-X'').
pub fn kuka_abc(a: f64, b: f64, c: f64) -> UnitQuaternion<f64> {
    xyz_deg(c, b, a)
}

/// `[A, B, C]` in degrees of a rotation; of the two equivalent triples, the one nearest to
/// `like` (the angles the file had), so a small correction gives a small change of numbers even
/// near B = ±90°.
pub fn kuka_abc_angles(r: &UnitQuaternion<f64>, like: Option<[f64; 3]>) -> [f64; 3] {
    let [c, b, a] = xyz_deg_angles(r);
    let first = [a, b, c];
    let second = [
        wrap_deg(a + 180.0),
        wrap_deg(180.0 - b),
        wrap_deg(c + 180.0),
    ];
    let Some(like) = like else { return first };
    let dist =
        |t: [f64; 3]| -> f64 { t.iter().zip(like).map(|(x, y)| wrap_deg(x - y).abs()).sum() };
    let pick = if dist(second) < dist(first) {
        second
    } else {
        first
    };
    // Keep the file's own branch of ±180 (a written 180 stays 180, not -180).
    let mut out = pick;
    for (o, l) in out.iter_mut().zip(like) {
        let alt = *o + 360.0 * ((l - *o) / 360.0).round();
        *o = alt;
    }
    out
}

/// Angle in radians of the rotation that takes `a` to `b`: compare rotations this way, never by
/// angle triples.
pub fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    a.angle_to(b)
}

/// A rotation matrix that is the nearest proper rotation to `m` (SVD projection), e.g. for the
/// mean of several measured rotations. `None` if `m` is degenerate.
pub fn nearest_rotation(m: &nalgebra::Matrix3<f64>) -> Option<Rotation3<f64>> {
    let svd = m.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut d = nalgebra::Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    Some(Rotation3::from_matrix_unchecked(u * d * v_t))
}

/// The translation part as a vector (a small readability helper).
pub fn origin(p: &Pose) -> Vector3<f64> {
    p.translation.vector
}

/// Rounds away a `-0.000000` (a negative value below the written precision).
pub fn clean(v: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    let r = (v * scale).round() / scale;
    if r == 0.0 { 0.0 } else { r }
}

/// A RAPID `pose` literal: position to 3 decimals (mm), quaternion scalar first to 6.
pub fn abb_pose_literal(p: &Pose) -> String {
    let t = p.translation.vector;
    let q = abb_quat_components(&p.rotation, None);
    format!(
        "[[{:.3},{:.3},{:.3}],[{:.6},{:.6},{:.6},{:.6}]]",
        clean(t.x, 3),
        clean(t.y, 3),
        clean(t.z, 3),
        clean(q[0], 6),
        clean(q[1], 6),
        clean(q[2], 6),
        clean(q[3], 6)
    )
}

/// A KRL `FRAME` literal: position to 3 decimals (mm), A, B, C (Rz·Ry·Rx) to 4 (degrees).
pub fn kuka_frame_literal(p: &Pose) -> String {
    let t = p.translation.vector;
    let abc = kuka_abc_angles(&p.rotation, None);
    format!(
        "{{X {:.3},Y {:.3},Z {:.3},A {:.4},B {:.4},C {:.4}}}",
        clean(t.x, 3),
        clean(t.y, 3),
        clean(t.z, 3),
        clean(abc[0], 4),
        clean(abc[1], 4),
        clean(abc[2], 4)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_to_half_open_interval() {
        assert!((wrap_deg(359.9981) - -0.0019).abs() < 1e-9);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(540.0), 180.0);
    }

    #[test]
    fn abb_quaternion_is_scalar_first() {
        // 90° about z: [cos 45°, 0, 0, sin 45°].
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let r = abb_quat([h, 0.0, 0.0, h]).unwrap();
        let x = r * Vector3::x();
        assert!((x - Vector3::y()).norm() < 1e-12);
        assert_eq!(abb_quat([0.0; 4]), None);
        let back = abb_quat_components(&r, Some([-h, 0.0, 0.0, -h]));
        assert!((back[0] + h).abs() < 1e-12 && (back[3] + h).abs() < 1e-12);
    }

    #[test]
    fn kuka_abc_is_intrinsic_zyx() {
        // A = 90: x → y.
        let r = kuka_abc(90.0, 0.0, 0.0);
        assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-12);
        // C = 90: y → z.
        let r = kuka_abc(0.0, 0.0, 90.0);
        assert!((r * Vector3::y() - Vector3::z()).norm() < 1e-12);
        let r = kuka_abc(30.0, -20.0, 170.0);
        let abc = kuka_abc_angles(&r, Some([30.0, -20.0, 170.0]));
        assert!(
            (abc[0] - 30.0).abs() < 1e-9
                && (abc[1] + 20.0).abs() < 1e-9
                && (abc[2] - 170.0).abs() < 1e-9
        );
    }

    #[test]
    fn kuka_abc_keeps_the_files_branch() {
        let r = kuka_abc(0.0, 90.0, 0.0);
        let abc = kuka_abc_angles(&r, Some([10.0, 90.0, 10.0]));
        assert!(angle_between(&kuka_abc(abc[0], abc[1], abc[2]), &r) < 1e-9);
        let r = kuka_abc(-180.0, 0.0, 180.0);
        let abc = kuka_abc_angles(&r, Some([180.0, 0.0, 180.0]));
        assert!((abc[0] - 180.0).abs() < 1e-9 && (abc[2] - 180.0).abs() < 1e-9);
    }

    #[test]
    fn xyz_round_trip() {
        let p = pose_xyz_deg(1.0, 2.0, 3.0, 10.0, -20.0, 30.0);
        let v = pose_to_xyz_deg(&p);
        for (a, b) in v.iter().zip([1.0, 2.0, 3.0, 10.0, -20.0, 30.0]) {
            assert!((a - b).abs() < 1e-9);
        }
    }
}
