//! The statistics of ISO 9283: means of positions and angles, the spread `l̄ + 3·S_l` and `3·S`
//! with `S` over `n − 1`, angle deviations that do not jump at ±180°.

use nalgebra::Vector3;

use crate::geometry::wrap_deg;

/// Running mean and sum of squared deviations (Welford): one pass over the visits, no
/// cancellation when the values are large and the spread small (tracker coordinates in mm).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Running {
    n: usize,
    mean: f64,
    m2: f64,
}

impl Running {
    pub(crate) fn push(&mut self, x: f64) {
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
    }

    pub(crate) fn mean(&self) -> f64 {
        self.mean
    }

    /// The sample standard deviation (over `n − 1`, eqs 3.8-3.11); `None` below 2 values.
    pub(crate) fn std(&self) -> Option<f64> {
        (self.n >= 2).then(|| (self.m2.max(0.0) / (self.n - 1) as f64).sqrt())
    }
}

/// The mean of points, component by component.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RunningPoint([Running; 3]);

impl RunningPoint {
    pub(crate) fn push(&mut self, p: &Vector3<f64>) {
        for (r, v) in self.0.iter_mut().zip(p.iter()) {
            r.push(*v);
        }
    }

    pub(crate) fn mean(&self) -> Vector3<f64> {
        Vector3::new(self.0[0].mean(), self.0[1].mean(), self.0[2].mean())
    }
}

/// `l̄` and `S_l` of the distances `l_j = |p_j − p̄|` (eqs 3.6-3.8 and 3.19-3.20): the centre
/// is known only after all points, so this takes the points and the centre.
pub(crate) fn spread<'a>(
    points: impl Iterator<Item = &'a Vector3<f64>>,
    centre: &Vector3<f64>,
) -> Running {
    let mut r = Running::default();
    for p in points {
        r.push((p - centre).norm());
    }
    r
}

/// `l̄ + 3·S_l` (eqs 3.7, 3.18); `None` below 2 values.
pub(crate) fn repeatability(r: &Running) -> Option<f64> {
    r.std().map(|s| r.mean() + 3.0 * s)
}

/// The deviation of a measured angle from the commanded one in degrees, wrapped to
/// (-180, 180]: 179.9° against -179.9° is 0.2°, not 359.8°.
pub(crate) fn angle_deviation(measured: f64, commanded: f64) -> f64 {
    wrap_deg(measured - commanded)
}

/// `a + λ·(b − a)` for angles, along the shorter way round.
pub(crate) fn angle_lerp(a: f64, b: f64, lambda: f64) -> f64 {
    wrap_deg(a + lambda * angle_deviation(b, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_matches_the_textbook_values() {
        let mut r = Running::default();
        for x in [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0] {
            r.push(x);
        }
        assert!((r.mean() - 5.0).abs() < 1e-12);
        // Population σ = 2, so the sample S = 2·sqrt(8/7).
        assert!((r.std().unwrap() - 2.0 * (8.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(Running::default().std(), None);
    }

    #[test]
    fn angles_wrap() {
        assert!((angle_deviation(-179.9, 179.9) - 0.2).abs() < 1e-9);
        assert!((angle_deviation(179.9, -179.9) + 0.2).abs() < 1e-9);
        assert!((angle_lerp(170.0, -170.0, 0.5) - 180.0).abs() < 1e-9);
    }
}
