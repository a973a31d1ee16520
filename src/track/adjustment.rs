//! What `track show` reports when no skid is asked for: the manual-adjustment table (thesis eq.
//! 4.54), the twist diagram (thesis Fig. 4.34) and the spline-to-chord bound per interval (seed
//! 4.9-4.12).

use nalgebra::Vector3;

use super::profile::{Profile, line_residuals};
use super::spline::ChordDistance;

/// Deviation of each knot component from the least-squares line of that component over skid:
/// what the adjustment screws must take out (the line itself is for the controller).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdjustmentRow {
    /// The knot's skid position, mm.
    pub skid: f64,
    /// dx, dy, dz (mm), rx, ry, rz (degrees).
    pub residual: [f64; 6],
}

/// The manual-adjustment table, one row per knot.
pub fn manual_adjustment(profile: &Profile) -> Vec<AdjustmentRow> {
    let knots = profile.knots();
    let skids: Vec<f64> = knots.iter().map(|k| k.skid).collect();
    let columns: Vec<Vec<f64>> = (0..6)
        .map(|c| {
            let ys: Vec<f64> = knots
                .iter()
                .map(|k| k.components().get(c).copied().unwrap_or(0.0))
                .collect();
            line_residuals(&skids, &ys)
        })
        .collect();
    skids
        .iter()
        .enumerate()
        .map(|(i, &skid)| {
            let mut residual = [0.0; 6];
            for (r, col) in residual.iter_mut().zip(&columns) {
                *r = col.get(i).copied().unwrap_or(0.0);
            }
            AdjustmentRow { skid, residual }
        })
        .collect()
}

/// The lever of the twist diagram: 1 m along +z of the base (thesis Fig. 4.34).
pub const TWIST_LEVER_MM: f64 = 1000.0;

/// One point of the twist diagram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwistPoint {
    /// The knot's skid position, mm.
    pub skid: f64,
    /// x, y in mm, relative to the first knot.
    pub x: f64,
    /// y in mm, relative to the first knot.
    pub y: f64,
}

/// The twist diagram: the tip of a 1 m lever along +z of each knot's rotation, projected to
/// the nominal x,y plane, relative to the first knot. Only the rotation moves the tip (the
/// translations have their own table), so 0.1° shows as 1.75 mm.
pub fn twist_diagram(profile: &Profile) -> Vec<TwistPoint> {
    let tip = |k: &super::Knot| k.pose().rotation * Vector3::new(0.0, 0.0, TWIST_LEVER_MM);
    let Some(first) = profile.knots().first().map(tip) else {
        return Vec::new();
    };
    profile
        .knots()
        .iter()
        .map(|k| {
            let t = tip(k) - first;
            TwistPoint {
                skid: k.skid,
                x: t.x,
                y: t.y,
            }
        })
        .collect()
}

/// The largest spline-to-chord distance of each component on one knot interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntervalBound {
    /// The interval's first knot, skid mm.
    pub from: f64,
    /// Its last knot, skid mm.
    pub to: f64,
    /// dx, dy, dz (mm), rx, ry, rz (degrees).
    pub distance: [ChordDistance; 6],
}

/// Per interval, how far the spline strays from a straight interpolation between the knots.
pub fn chord_bounds(profile: &Profile) -> Vec<IntervalBound> {
    let per_component: Vec<Vec<ChordDistance>> = profile
        .splines()
        .iter()
        .map(|s| s.chord_distances())
        .collect();
    let knots = profile.knots();
    knots
        .windows(2)
        .enumerate()
        .map(|(i, w)| {
            let zero = ChordDistance {
                at: 0.0,
                distance: 0.0,
            };
            let mut distance = [zero; 6];
            for (d, comp) in distance.iter_mut().zip(&per_component) {
                *d = comp.get(i).copied().unwrap_or(zero);
            }
            IntervalBound {
                from: w.first().map(|k| k.skid).unwrap_or(0.0),
                to: w.last().map(|k| k.skid).unwrap_or(0.0),
                distance,
            }
        })
        .collect()
}
