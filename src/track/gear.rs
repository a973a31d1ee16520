//! What to enter in the controller for a measured gear factor `g` (the skid moves `g` mm per
//! commanded mm, docs/design.md §3).
//!
//! The controllers store the inverse of the thesis's "gear factor": the thesis multiplies a
//! travel per motor turn (eq. 4.4: `new = g · old`), while ABB's *Transmission Gear Ratio*
//! (system parameters, topic Motion, type Transmission; `transm_joint` in `MOC.cfg`) and KUKA's
//! `$RAT_MOT_AX[i] = {N n, D d}` in `$machine.dat` (motor revolutions `N` per `D` axis units;
//! for a linear axis per 1000 mm; `i = 7` for the first external axis E1) are motor turns per
//! travel. For them `new = old / g`: a skid that travels short (`g < 1`) needs a larger ratio.

/// What to do with measured gear factor `g` in each controller, in words: one line for the
/// convention, one for ABB, one for KUKA, one for a travel per motor turn (the thesis's). The
/// one text `track fit` prints and the report shows: a bare "new = g × current" reads as an
/// instruction for the controllers' ratio, which it inverts.
pub fn advice(g: f64) -> [String; 4] {
    [
        format!(
            "the controllers store motor turns per travel, which must be divided by {g:.6} (it grows when the skid travels short):"
        ),
        format!(
            "ABB: the track's Transmission Gear Ratio (topic Motion, type Transmission; transm_joint in MOC.cfg): new = current / {g:.6}"
        ),
        format!(
            "KUKA: $RAT_MOT_AX[7] = {{N n,D d}} in $machine.dat ([7] = E1, [6+k] = Ek): new N/D = current N/D / {g:.6}"
        ),
        format!(
            "(a travel per motor turn, the gear factor of docs/design.md §3, thesis eq. 4.4, grows the other way: new = {g:.6} x current)"
        ),
    ]
}

/// The new motor-to-travel ratio (ABB's Transmission Gear Ratio, or KUKA's `N/D`) for the
/// current one and the measured gear factor.
pub fn new_motor_ratio(current: f64, gear_factor: f64) -> f64 {
    current / gear_factor
}

/// A KUKA `$RAT_MOT_AX` fraction `{N n, D d}`: both are `INT` (32-bit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KukaRatio {
    /// Numerator `N`.
    pub n: i64,
    /// Denominator `D`.
    pub d: i64,
}

impl KukaRatio {
    /// `N / D`.
    pub fn value(self) -> f64 {
        self.n as f64 / self.d as f64
    }
}

impl std::fmt::Display for KukaRatio {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{{N {},D {}}}", self.n, self.d)
    }
}

/// The largest value a KUKA `INT` holds.
const KUKA_INT_MAX: f64 = 2_147_483_647.0;

/// The new `{N, D}` for the current one and the measured gear factor: `D` is scaled by the
/// largest power of ten (up to 10⁶) that keeps both in a KUKA `INT`, so the new ratio is exact
/// to about 1e-7 or better. `None` when the current ratio is not usable (`D = 0`) or the
/// result does not fit.
pub fn new_kuka_ratio(current: KukaRatio, gear_factor: f64) -> Option<KukaRatio> {
    if current.d == 0 || !gear_factor.is_finite() || gear_factor <= 0.0 {
        return None;
    }
    let target = current.value() / gear_factor;
    let mut best = None;
    let mut scale = 1i64;
    for _ in 0..=6 {
        let d = current.d.checked_mul(scale)?;
        let n = (target * d as f64).round();
        if n.abs() > KUKA_INT_MAX || (d as f64).abs() > KUKA_INT_MAX {
            break;
        }
        best = Some(KukaRatio { n: n as i64, d });
        scale *= 10;
    }
    best
}

/// Parses `N/D` (or a plain integer `N`, meaning `D = 1`).
pub fn parse_kuka_ratio(text: &str) -> Option<KukaRatio> {
    let (n, d) = match text.split_once('/') {
        Some((n, d)) => (n.trim().parse().ok()?, d.trim().parse().ok()?),
        None => (text.trim().parse().ok()?, 1),
    };
    (d != 0).then_some(KukaRatio { n, d })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_travelling_skid_needs_a_larger_ratio() {
        // 8000 mm commanded, 7998.8 mm travelled: g = 0.99985.
        let g = 7998.8 / 8000.0;
        let abb = new_motor_ratio(1500.0, g);
        assert!((abb - 1500.0 * 8000.0 / 7998.8).abs() < 1e-9);
        assert!(abb > 1500.0);
        // KUKA: 9:1 gearbox on a pinion of 60 mm: 1000 / (π·60) · 9 motor turns per metre,
        // written {N 47746, D 1000}.
        let current = KukaRatio { n: 47746, d: 1000 };
        let new = new_kuka_ratio(current, g).unwrap();
        assert!(new.n <= 2_147_483_647 && new.d <= 2_147_483_647);
        let exact = 47.746 / g;
        assert!((new.value() - exact).abs() < 1e-6 * exact, "{new}");
        // D = 1000·10⁴: at 10⁵ the numerator (4.8e9) would overflow a 32-bit INT.
        assert_eq!(new.d, 10_000_000);
        assert_eq!(new.to_string(), format!("{{N {},D 10000000}}", new.n));
        assert_eq!(parse_kuka_ratio("47746/1000"), Some(current));
        assert_eq!(parse_kuka_ratio("15"), Some(KukaRatio { n: 15, d: 1 }));
        assert_eq!(parse_kuka_ratio("1/0"), None);
    }
}
