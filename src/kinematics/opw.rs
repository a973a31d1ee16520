//! The OPW model: ortho-parallel base, spherical wrist (Brandstötter, Angerer, Hofbaur, "An
//! analytical solution of the inverse kinematics problem of industrial serial manipulators with
//! an ortho-parallel basis and a spherical wrist", Austrian Robotics Workshop 2014).
//!
//! Seven lengths describe the arm (mm): `c1` the height of axis 2 over the base, `a1` its
//! forward offset from axis 1, `b` the sideways offset of the arm plane, `c2` the upper arm
//! (axis 2 to axis 3), `c3` the forearm (axis 3 to the wrist centre), `a2` the forearm's offset
//! perpendicular to it, `c4` the wrist centre to the flange. In the model's zero position the arm
//! stands straight up.
//!
//! Controller joints `θ` (degrees, as the program writes them) map to model joints by
//! `q_i = sign_i·θ_i − offset_i`, the convention of the OPW paper and of the `opw_kinematics`
//! packages (ROS-Industrial, `rs-opw-kinematics`).
//!
//! Forward kinematics, in the frame rotated by `q1` (the "axis-1 frame"), wrist centre `C`:
//! `C = (a1 + c2·sin q2 + k·sin(q2+q3+ψ), b, c1 + c2·cos q2 + k·cos(q2+q3+ψ))` with
//! `k = √(a2² + c3²)`, `ψ = atan2(a2, c3)`; orientation `R = Rz(q1)·Ry(q2+q3)·Rz(q4)·Ry(q5)·Rz(q6)`;
//! flange `= C + c4·R·e_z`.
//!
//! Inverse kinematics: the wrist centre `C = P − c4·R·e_z` gives `q1` (two solutions, wrist in
//! front of or behind axis 1), the planar two-link arm gives `q2, q3` (two solutions each, wrist
//! in front of or behind the lower arm), and `Rz(q4)·Ry(q5)·Rz(q6) = (Rz(q1)·Ry(q2+q3))ᵀ·R` gives
//! the wrist (two solutions, axis 5 positive or negative): up to 8. Each is checked by forward
//! kinematics before it is returned.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::geometry::Pose;

/// Controller joint angles, axes 1…6, in degrees.
pub type Joints = [f64; 6];

/// The seven OPW lengths in mm.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct OpwGeometry {
    /// Forward offset of axis 2 from axis 1.
    pub a1: f64,
    /// Forearm offset perpendicular to it (negative for ABB and KUKA arms).
    pub a2: f64,
    /// Sideways offset of the arm plane.
    pub b: f64,
    /// Height of axis 2 above the base.
    pub c1: f64,
    /// Upper arm, axis 2 → axis 3.
    pub c2: f64,
    /// Forearm, axis 3 → wrist centre.
    pub c3: f64,
    /// Wrist centre → flange.
    pub c4: f64,
}

/// A robot arm: geometry, the controller-to-model joint map and the joint limits.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Kinematics {
    /// The seven OPW lengths.
    pub geometry: OpwGeometry,
    /// `offset_i` in degrees (`q_i = sign_i·θ_i − offset_i`).
    pub offsets: [f64; 6],
    /// `sign_i`, +1 or −1.
    pub signs: [f64; 6],
    /// `[min, max]` of each controller joint in degrees.
    pub limits: [[f64; 2]; 6],
}

/// Where the wrist centre lies: the two arm choices of the inverse kinematics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct Arm {
    /// Wrist centre in front of axis 1: positive x in the axis-1 frame (ABB cfx, KUKA Status
    /// bit 0 "basic area").
    pub front_of_axis1: bool,
    /// Wrist centre in front of the lower arm (the line through axes 2 and 3): the elbow
    /// choice (ABB cfx, KUKA Status bit 1).
    pub front_of_lower_arm: bool,
}

/// A wrist whose axis 5 is within this (radians) of 0 or 180° cannot tell axes 4 and 6 apart.
const SINGULAR: f64 = 1e-9;
/// Forward kinematics must reproduce the requested pose to this (mm, radians) for an inverse
/// solution to count: it rejects spurious branches, never a real one.
const CHECK_MM: f64 = 1e-4;
const CHECK_RAD: f64 = 1e-7;

fn wrap_pi(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}

impl Kinematics {
    /// Model joints (radians) of controller joints (degrees).
    pub fn model_joints(&self, j: &Joints) -> [f64; 6] {
        std::array::from_fn(|i| (self.signs[i] * j[i] - self.offsets[i]).to_radians())
    }

    /// Controller joints (degrees) of model joints (radians): `θ = sign·(q + offset)`.
    pub fn controller_joints(&self, q: &[f64; 6]) -> Joints {
        std::array::from_fn(|i| self.signs[i] * (q[i].to_degrees() + self.offsets[i]))
    }

    fn psi_k(&self) -> (f64, f64) {
        let g = &self.geometry;
        (g.a2.atan2(g.c3), g.a2.hypot(g.c3))
    }

    /// The wrist centre in the base frame.
    pub fn wrist_centre(&self, j: &Joints) -> Vector3<f64> {
        let q = self.model_joints(j);
        let g = &self.geometry;
        let (psi, k) = self.psi_k();
        let x1 = g.a1 + g.c2 * q[1].sin() + k * (q[1] + q[2] + psi).sin();
        let z1 = g.c1 + g.c2 * q[1].cos() + k * (q[1] + q[2] + psi).cos();
        let (s1, c1) = q[0].sin_cos();
        Vector3::new(x1 * c1 - g.b * s1, x1 * s1 + g.b * c1, z1)
    }

    /// The flange (`tool0`) in the base frame.
    pub fn forward(&self, j: &Joints) -> Pose {
        let q = self.model_joints(j);
        let r = rz(q[0]) * ry(q[1] + q[2]) * rz(q[3]) * ry(q[4]) * rz(q[5]);
        let p = self.wrist_centre(j) + self.geometry.c4 * (r * Vector3::z());
        Pose::from_parts(
            Translation3::from(p),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
        )
    }

    /// Which of the four arm solutions `j` is.
    pub fn arm(&self, j: &Joints) -> Arm {
        let q = self.model_joints(j);
        let g = &self.geometry;
        let (psi, k) = self.psi_k();
        let x1 = g.a1 + g.c2 * q[1].sin() + k * (q[1] + q[2] + psi).sin();
        Arm {
            front_of_axis1: x1 >= 0.0,
            // (C − axis 2)·n with n the lower arm's forward normal is k·sin(q3 + ψ).
            front_of_lower_arm: (q[2] + psi).sin() >= 0.0,
        }
    }

    /// Every inverse solution of a flange pose in the base frame: up to 8, controller joints
    /// wrapped to (−180°, 180°], each reproducing `flange` by [`Kinematics::forward`]. Limits are
    /// not applied (see [`Kinematics::turns`]). Empty when the pose is out of reach.
    ///
    /// At a singular wrist (axis 5 = 0) axes 4 and 6 are one rotation: axis 4 is set to
    /// `wrist_hint`'s axis 4 (degrees, controller) or 0, and axis 6 takes the rest.
    pub fn inverse(&self, flange: &Pose, wrist_hint: Option<f64>) -> Vec<Joints> {
        let g = self.geometry;
        let (psi, k) = self.psi_k();
        let r = flange.rotation.to_rotation_matrix().into_inner();
        let c = flange.translation.vector - g.c4 * r.column(2);
        if !c.iter().all(|v| v.is_finite()) {
            return Vec::new();
        }
        let rho2 = c.x * c.x + c.y * c.y - g.b * g.b;
        if rho2 < -1e-9 {
            return Vec::new();
        }
        // Distance of the wrist centre from axis 1 within the arm plane.
        let xr = rho2.max(0.0).sqrt();
        let phi0 = c.y.atan2(c.x);
        let hint_q4 = wrist_hint.map(|t4| (self.signs[3] * t4 - self.offsets[3]).to_radians());
        let mut out: Vec<Joints> = Vec::new();
        for front in [true, false] {
            let x_arm = if front { xr } else { -xr };
            let q1 = phi0 - g.b.atan2(x_arm);
            // The wrist centre relative to axis 2 in the arm plane (h forward, v up).
            let h = x_arm - g.a1;
            let v = c.z - g.c1;
            let s2 = h * h + v * v;
            let cos_phi = (s2 - g.c2 * g.c2 - k * k) / (2.0 * g.c2 * k);
            if !cos_phi.is_finite() || cos_phi.abs() > 1.0 + 1e-9 {
                continue;
            }
            let phi_abs = cos_phi.clamp(-1.0, 1.0).acos();
            for phi in [phi_abs, -phi_abs] {
                let q2 = h.atan2(v) - (k * phi.sin()).atan2(g.c2 + k * phi.cos());
                let q3 = phi - psi;
                let arm_r = (rz(q1) * ry(q2 + q3)).transpose() * r;
                for q456 in wrist(&arm_r, hint_q4) {
                    let q = [q1, q2, q3, q456[0], q456[1], q456[2]];
                    let mut j = self.controller_joints(&q);
                    for a in &mut j {
                        *a = crate::geometry::wrap_deg(*a);
                    }
                    if self.reproduces(&j, flange) && !out.iter().any(|o| same_joints(o, &j, 1e-9))
                    {
                        out.push(j);
                    }
                }
            }
        }
        out
    }

    fn reproduces(&self, j: &Joints, target: &Pose) -> bool {
        let f = self.forward(j);
        let scale = 1.0 + target.translation.vector.norm() * 1e-9;
        (f.translation.vector - target.translation.vector).norm() < CHECK_MM * scale
            && f.rotation.angle_to(&target.rotation) < CHECK_RAD
    }

    /// The ±360° variants of `j` within the limits, axis by axis (all combinations). Empty when
    /// some axis has no variant within its limits.
    pub fn turns(&self, j: &Joints) -> Vec<Joints> {
        let mut out = vec![*j];
        for (i, &[lo, hi]) in self.limits.iter().enumerate() {
            let mut next = Vec::new();
            for base in &out {
                for n in -3..=3 {
                    let v = base[i] + 360.0 * f64::from(n);
                    if v >= lo - 1e-9 && v <= hi + 1e-9 {
                        let mut c = *base;
                        c[i] = v;
                        next.push(c);
                    }
                }
            }
            out = next;
        }
        out
    }

    /// Every solution of `flange` with its turns, within the limits.
    pub fn solutions_within_limits(&self, flange: &Pose, wrist_hint: Option<f64>) -> Vec<Joints> {
        self.inverse(flange, wrist_hint)
            .iter()
            .flat_map(|j| self.turns(j))
            .collect()
    }

    /// Margin of each joint to its nearer limit in degrees (negative: outside).
    pub fn limit_margins(&self, j: &Joints) -> [f64; 6] {
        std::array::from_fn(|i| (j[i] - self.limits[i][0]).min(self.limits[i][1] - j[i]))
    }

    /// Whether every joint is within its limits (to 1e-9°).
    pub fn within_limits(&self, j: &Joints) -> bool {
        self.limit_margins(j).iter().all(|m| *m >= -1e-9)
    }

    /// The solution of `flange` within the limits nearest to `reference` (sum of squared joint
    /// differences), optionally only among those with `reference`'s arm (see [`Arm`]) and sign
    /// of axis 5. Keeps axis 4/6 turns because every ±360° variant is a candidate.
    pub fn nearest(&self, flange: &Pose, reference: &Joints, same_branch: bool) -> Option<Joints> {
        self.solutions_within_limits(flange, Some(reference[3]))
            .into_iter()
            .filter(|j| !same_branch || self.same_branch(reference, j))
            .min_by(|a, b| distance2(a, reference).total_cmp(&distance2(b, reference)))
    }

    /// Whether `j` has `reference`'s arm (see [`Arm`]) and sign of axis 5. An axis 5 within
    /// 1e-6° of 0 on either side has both signs: at the singular wrist the sign is the
    /// arithmetic's, not the posture's.
    pub fn same_branch(&self, reference: &Joints, j: &Joints) -> bool {
        let wrist_known = reference[4].abs() > 1e-6 && j[4].abs() > 1e-6;
        self.arm(j) == self.arm(reference)
            && (!wrist_known || (j[4] >= 0.0) == (reference[4] >= 0.0))
    }

    /// `|axis 5|` in degrees: the distance from the wrist singularity (axes 4 and 6 aligned).
    pub fn wrist_singularity_deg(&self, j: &Joints) -> f64 {
        let q5 = wrap_pi(self.model_joints(j)[4]);
        q5.abs().min(PI - q5.abs()).to_degrees()
    }
}

/// Sum of squared differences in degrees².
pub fn distance2(a: &Joints, b: &Joints) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

fn same_joints(a: &Joints, b: &Joints, tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

fn rz(a: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), a).into_inner()
}

fn ry(a: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::y_axis(), a).into_inner()
}

/// The two `(q4, q5, q6)` with `Rz(q4)·Ry(q5)·Rz(q6) = m` (one at a singular wrist).
fn wrist(m: &Matrix3<f64>, hint_q4: Option<f64>) -> Vec<[f64; 3]> {
    // Third column of Rz(q4)·Ry(q5)·Rz(q6): (cos q4·sin q5, sin q4·sin q5, cos q5).
    let s5 = m[(0, 2)].hypot(m[(1, 2)]);
    let q5 = s5.atan2(m[(2, 2)]);
    if s5 < SINGULAR {
        let q4 = hint_q4.unwrap_or(0.0);
        let q6 = if m[(2, 2)] > 0.0 {
            // Rz(q4 + q6).
            m[(1, 0)].atan2(m[(0, 0)]) - q4
        } else {
            // Rz(q4 − q6)·Ry(π).
            q4 - (-m[(1, 0)]).atan2(-m[(0, 0)])
        };
        return vec![[q4, q5, wrap_pi(q6)]];
    }
    let q4 = m[(1, 2)].atan2(m[(0, 2)]);
    // q6 from what is left, Rz(q6) = (Rz(q4)·Ry(q5))ᵀ·m, rather than from m's third row: near
    // the singularity q4 is ill-conditioned, and this way q6 absorbs its error exactly.
    let q6_of = |q4: f64, q5: f64| {
        let n = (rz(q4) * ry(q5)).transpose() * m;
        n[(1, 0)].atan2(n[(0, 0)])
    };
    let q4b = wrap_pi(q4 + PI);
    vec![[q4, q5, q6_of(q4, q5)], [q4b, -q5, q6_of(q4b, -q5)]]
}
