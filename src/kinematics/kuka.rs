//! KUKA Status and Turn of 6-axis robots (KUKA System Software 8, operating and programming
//! instructions for system integrators, "Status and Turn").
//!
//! Status, bits 0–2 (bits 3 and 4 say nothing about the arm and are ignored here):
//! - bit 0: the wrist root point (intersection of A4, A5, A6) has negative x in the A1
//!   coordinate system (the one that turns with A1): "overhead area" 1, "basic area" 0;
//! - bit 1: A3 ≥ φ gives 1, A3 < φ gives 0, where φ is the A3 angle at which the wrist root
//!   point crosses the line through A2 and A3 (0° for robots without an A3–A4 offset): 1 is the
//!   wrist root point in front of the lower arm (see [`Arm`]);
//! - bit 2: A5 in −180°…0° (or ≥ 180°) gives 1, A5 in 0°…180° (or < −180°) gives 0.
//!
//! Turn, bits 0–5: bit i is 1 when axis A(i+1) is negative, 0 when it is zero or positive.

use super::opw::{Arm, Joints, Kinematics};

/// Joints within this (degrees) of a sign change match either bit.
const BOUNDARY_DEG: f64 = 1e-6;

/// The arm bits of Status (bits 0–2).
pub const STATUS_ARM_BITS: u32 = 0b111;
/// The six axis bits of Turn.
pub const TURN_BITS: u32 = 0b11_1111;

fn a5_negative(a5: f64) -> bool {
    // −180 ≤ A5 < 0 or A5 ≥ 180.
    (a5 + 180.0).rem_euclid(360.0) - 180.0 < 0.0
}

/// Status bits 0–2 of an arm and A5 angle.
pub fn status(arm: Arm, a5_deg: f64) -> u32 {
    u32::from(!arm.front_of_axis1)
        | u32::from(arm.front_of_lower_arm) << 1
        | u32::from(a5_negative(a5_deg)) << 2
}

/// Turn of controller joints: bit i set when axis i+1 < 0.
pub fn turn(j: &Joints) -> u32 {
    j.iter()
        .enumerate()
        .fold(0, |t, (i, a)| t | u32::from(*a < 0.0) << i)
}

/// `(Status, Turn)` of controller joints (Status bits 0–2 only).
pub fn status_turn_of(kin: &Kinematics, j: &Joints) -> (u32, u32) {
    (status(kin.arm(j), j[4]), turn(j))
}

/// Whether joints `j` are in the written Status (bits 0–2) and Turn; a missing one matches
/// anything, and an axis at a sign change matches both bits.
pub fn matches(
    kin: &Kinematics,
    j: &Joints,
    written_status: Option<u32>,
    written_turn: Option<u32>,
) -> bool {
    let (s, t) = status_turn_of(kin, j);
    let mut free_s = 0;
    if j[4].abs() <= BOUNDARY_DEG || (j[4].abs() - 180.0).abs() <= BOUNDARY_DEG {
        free_s |= 0b100;
    }
    let free_t = j
        .iter()
        .enumerate()
        .fold(0, |f, (i, a)| f | u32::from(a.abs() <= BOUNDARY_DEG) << i);
    let status_ok = written_status.is_none_or(|w| (w ^ s) & STATUS_ARM_BITS & !free_s == 0);
    let turn_ok = written_turn.is_none_or(|w| (w ^ t) & TURN_BITS & !free_t == 0);
    status_ok && turn_ok
}
