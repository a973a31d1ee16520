//! ABB `confdata [cf1, cf4, cf6, cfx]` of 6-axis robots (ABB, Technical reference manual RAPID
//! Instructions, Functions and Data types, "confdata").
//!
//! - `cf1`, `cf4`, `cf6`: the quadrant of axes 1, 4 and 6, `⌊θ/90°⌋`: 0 for 0…90°, 1 for
//!   90…180°, −1 for −90…0°, −2 for −180…−90°, and so on beyond one turn.
//! - `cfx`, one of eight arm configurations:
//!
//! | cfx | wrist centre relative to axis 1 | wrist centre relative to the lower arm | axis 5 |
//! |----|----|----|----|
//! | 0 | in front of | in front of | positive |
//! | 1 | in front of | in front of | negative |
//! | 2 | in front of | behind | positive |
//! | 3 | in front of | behind | negative |
//! | 4 | behind | in front of | positive |
//! | 5 | behind | in front of | negative |
//! | 6 | behind | behind | positive |
//! | 7 | behind | behind | negative |
//!
//! "In front of axis 1" is positive x of the wrist centre in the frame that turns with axis 1;
//! "in front of the lower arm" is the wrist centre's side of the line through axes 2 and 3
//! (see [`Arm`]); axis 5 = 0 counts as positive.

use super::opw::{Arm, Joints, Kinematics};

/// Joint angles on a quadrant boundary within this (degrees) match either quadrant.
const BOUNDARY_DEG: f64 = 1e-6;

/// The ABB quadrant `⌊θ/90°⌋` of a joint angle in degrees.
pub fn quadrant(deg: f64) -> i32 {
    // The tiny bias keeps 89.9999999999 (arithmetic noise on a taught 90°) in quadrant 1.
    (deg / 90.0 + 1e-12).floor() as i32
}

/// `cfx` of an arm and an axis-5 angle.
pub fn cfx(arm: Arm, axis5_deg: f64) -> i32 {
    i32::from(!arm.front_of_axis1) * 4
        + i32::from(!arm.front_of_lower_arm) * 2
        + i32::from(axis5_deg < 0.0)
}

/// `[cf1, cf4, cf6, cfx]` of controller joints.
pub fn config_of(kin: &Kinematics, j: &Joints) -> [i32; 4] {
    [
        quadrant(j[0]),
        quadrant(j[3]),
        quadrant(j[5]),
        cfx(kin.arm(j), j[4]),
    ]
}

fn in_quadrant(deg: f64, cf: i32) -> bool {
    let lo = f64::from(cf) * 90.0;
    deg >= lo - BOUNDARY_DEG && deg <= lo + 90.0 + BOUNDARY_DEG
}

/// Whether joints `j` are in the written configuration (a joint on a quadrant boundary, or
/// axis 5 at 0, matches both sides).
pub fn matches(kin: &Kinematics, j: &Joints, written: [i32; 4]) -> bool {
    let [cf1, cf4, cf6, cfx_w] = written;
    if !(in_quadrant(j[0], cf1) && in_quadrant(j[3], cf4) && in_quadrant(j[5], cf6)) {
        return false;
    }
    let arm = kin.arm(j);
    let solved = cfx(arm, j[4]);
    solved == cfx_w || (j[4].abs() <= BOUNDARY_DEG && solved ^ 1 == cfx_w)
}
