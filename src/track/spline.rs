//! Cubic interpolating splines (thesis eqs. 4.43-4.52, 7.5-7.11) and the spline-to-chord error
//! bound between knots (seed 4.9-4.12, docs/design.md §3).
//!
//! The spline is stored by its knot values and second derivatives `M_i`; on `[x_i, x_{i+1}]`
//! with `h = x_{i+1} - x_i` and `t = (x - x_i)/h` it is the chord minus
//! `h²/6 · t(1-t) · ((2-t)·M_i + (1+t)·M_{i+1})`, which makes the chord distance a closed form.

/// End conditions of the spline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EndCondition {
    /// `S''(x_0) = S''(x_N) = 0` (the track model, docs/design.md §3).
    Natural,
    /// Given first derivatives at both ends.
    Clamped {
        /// `S'(x_0)`.
        start: f64,
        /// `S'(x_N)`.
        end: f64,
    },
}

/// Why a spline cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SplineError {
    /// Fewer than two knots (the count).
    #[error("a spline needs at least 2 knots, got {0}")]
    TooFewKnots(usize),
    /// Knot positions and values differ in number.
    #[error("{xs} knot positions but {ys} values")]
    LengthMismatch {
        /// Knot positions.
        xs: usize,
        /// Values.
        ys: usize,
    },
    /// A knot position not above the one before it.
    #[error(
        "knots must be strictly increasing: knot {index} at {value} follows {previous}; sort the rows and remove duplicates"
    )]
    NotIncreasing {
        /// The knot's 0-based index.
        index: usize,
        /// The position of the knot before it.
        previous: f64,
        /// Its position.
        value: f64,
    },
    /// A knot position or value is NaN or infinite.
    #[error("knot {index} is not a finite number")]
    NotFinite {
        /// The knot's 0-based index.
        index: usize,
    },
}

/// The largest distance between the spline and the chord on one interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChordDistance {
    /// Where the largest distance occurs.
    pub at: f64,
    /// Signed `S(at) - chord(at)`.
    pub distance: f64,
}

/// A cubic spline through `(x_i, y_i)`.
#[derive(Clone, Debug, PartialEq)]
pub struct CubicSpline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl CubicSpline {
    /// Builds the spline; 2 natural knots give the straight line between them.
    pub fn new(x: &[f64], y: &[f64], end: EndCondition) -> Result<CubicSpline, SplineError> {
        if x.len() != y.len() {
            return Err(SplineError::LengthMismatch {
                xs: x.len(),
                ys: y.len(),
            });
        }
        let n = x.len();
        if n < 2 {
            return Err(SplineError::TooFewKnots(n));
        }
        for (i, (xi, yi)) in x.iter().zip(y).enumerate() {
            if !xi.is_finite() || !yi.is_finite() {
                return Err(SplineError::NotFinite { index: i });
            }
        }
        for (i, w) in x.windows(2).enumerate() {
            if let [a, b] = w
                && b <= a
            {
                return Err(SplineError::NotIncreasing {
                    index: i + 1,
                    previous: *a,
                    value: *b,
                });
            }
        }
        let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let slope: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
        // Tridiagonal system for M: sub[i]·M[i-1] + diag[i]·M[i] + sup[i]·M[i+1] = rhs[i].
        let mut sub = vec![0.0; n];
        let mut diag = vec![1.0; n];
        let mut sup = vec![0.0; n];
        let mut rhs = vec![0.0; n];
        for i in 1..n - 1 {
            sub[i] = h[i - 1];
            diag[i] = 2.0 * (h[i - 1] + h[i]);
            sup[i] = h[i];
            rhs[i] = 6.0 * (slope[i] - slope[i - 1]);
        }
        match end {
            EndCondition::Natural => {} // diag 1, rhs 0: M_0 = M_N = 0.
            EndCondition::Clamped { start, end } => {
                diag[0] = 2.0 * h[0];
                sup[0] = h[0];
                rhs[0] = 6.0 * (slope[0] - start);
                sub[n - 1] = h[n - 2];
                diag[n - 1] = 2.0 * h[n - 2];
                rhs[n - 1] = 6.0 * (end - slope[n - 2]);
            }
        }
        let m = solve_tridiagonal(&sub, &diag, &sup, &rhs);
        Ok(CubicSpline {
            x: x.to_vec(),
            y: y.to_vec(),
            m,
        })
    }

    /// The knot positions.
    pub fn knots(&self) -> &[f64] {
        &self.x
    }

    /// The knot values.
    pub fn values(&self) -> &[f64] {
        &self.y
    }

    /// `(first, last)` knot position.
    pub fn range(&self) -> (f64, f64) {
        (
            self.x.first().copied().unwrap_or(0.0),
            self.x.last().copied().unwrap_or(0.0),
        )
    }

    /// Index of the interval holding `x` (the end intervals extend outwards).
    pub(crate) fn interval(&self, x: f64) -> usize {
        let last = self.x.len().saturating_sub(2);
        // partition_point: number of knots <= x.
        let k = self.x.partition_point(|&xi| xi <= x);
        k.saturating_sub(1).min(last)
    }

    /// Pieces of interval `i`: `(x_i, h, y_i, y_{i+1}, M_i, M_{i+1})`.
    fn piece(&self, i: usize) -> (f64, f64, f64, f64, f64, f64) {
        let g = |v: &Vec<f64>, k: usize| v.get(k).copied().unwrap_or(0.0);
        let x0 = g(&self.x, i);
        let h = g(&self.x, i + 1) - x0;
        (
            x0,
            h,
            g(&self.y, i),
            g(&self.y, i + 1),
            g(&self.m, i),
            g(&self.m, i + 1),
        )
    }

    /// `S(x)`; outside the knots the end cubic is continued (callers decide whether to allow it).
    pub fn value(&self, x: f64) -> f64 {
        self.value_in(self.interval(x), x)
    }

    /// [`value`](Self::value) with the interval `i` holding `x` ([`interval`](Self::interval))
    /// found by the caller: splines over the same knots (a profile's six) share one search.
    #[inline]
    pub(crate) fn value_in(&self, i: usize, x: f64) -> f64 {
        let (x0, h, y0, y1, m0, m1) = self.piece(i);
        let t = (x - x0) / h;
        let chord = y0 + (y1 - y0) * t;
        chord - h * h / 6.0 * t * (1.0 - t) * ((2.0 - t) * m0 + (1.0 + t) * m1)
    }

    /// `S'(x)`.
    pub fn derivative(&self, x: f64) -> f64 {
        let (x0, h, y0, y1, m0, m1) = self.piece(self.interval(x));
        let a = x0 + h - x;
        let b = x - x0;
        -m0 * a * a / (2.0 * h) + m1 * b * b / (2.0 * h) + (y1 - y0) / h - (m1 - m0) * h / 6.0
    }

    /// `S''(x)`.
    pub fn second_derivative(&self, x: f64) -> f64 {
        let (x0, h, _, _, m0, m1) = self.piece(self.interval(x));
        let t = (x - x0) / h;
        m0 * (1.0 - t) + m1 * t
    }

    /// For each interval, the largest distance between the spline and its chord (seed 4.9-4.12).
    pub fn chord_distances(&self) -> Vec<ChordDistance> {
        (0..self.x.len().saturating_sub(1))
            .map(|i| {
                let (x0, h, _, _, m0, m1) = self.piece(i);
                // e(t) = -h²/6 · f(t), f(t) = (t - t²)(a + b t); f'(t) = a + 2(b-a)t - 3b t².
                let a = 2.0 * m0 + m1;
                let b = m1 - m0;
                let f = |t: f64| (t - t * t) * (a + b * t);
                let mut candidates = vec![0.5];
                let (qa, qb, qc) = (-3.0 * b, 2.0 * (b - a), a);
                if qa.abs() < 1e-300 {
                    if qb.abs() > 1e-300 {
                        candidates.push(-qc / qb);
                    }
                } else {
                    let disc = qb * qb - 4.0 * qa * qc;
                    if disc >= 0.0 {
                        let r = disc.sqrt();
                        candidates.push((-qb + r) / (2.0 * qa));
                        candidates.push((-qb - r) / (2.0 * qa));
                    }
                }
                let mut best = ChordDistance {
                    at: x0 + 0.5 * h,
                    distance: -h * h / 6.0 * f(0.5),
                };
                for t in candidates.into_iter().filter(|t| (0.0..=1.0).contains(t)) {
                    let d = -h * h / 6.0 * f(t);
                    if d.abs() > best.distance.abs() {
                        best = ChordDistance {
                            at: x0 + t * h,
                            distance: d,
                        };
                    }
                }
                best
            })
            .collect()
    }
}

/// Thomas algorithm. The systems built here are diagonally dominant, so no pivoting is needed.
fn solve_tridiagonal(sub: &[f64], diag: &[f64], sup: &[f64], rhs: &[f64]) -> Vec<f64> {
    let n = diag.len();
    let mut c = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut prev_c = 0.0;
    let mut prev_d = 0.0;
    for i in 0..n {
        let denom = diag[i] - sub[i] * prev_c;
        c[i] = sup[i] / denom;
        d[i] = (rhs[i] - sub[i] * prev_d) / denom;
        prev_c = c[i];
        prev_d = d[i];
    }
    let mut x = vec![0.0; n];
    let mut next = 0.0;
    for i in (0..n).rev() {
        x[i] = d[i] - c[i] * next;
        next = x[i];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    const XS: [f64; 4] = [0.0, 100.0, 200.0, 300.0];
    const YS: [f64; 4] = [-0.25, 0.25, 0.25, -0.25];

    #[test]
    fn clamped_bound_is_one_twelfth() {
        // Reference README: clamped ends ±0.005 give 1/12 at x = 150 (to 1e-9).
        let s = CubicSpline::new(
            &XS,
            &YS,
            EndCondition::Clamped {
                start: 0.005,
                end: -0.005,
            },
        )
        .unwrap();
        let d = s.chord_distances();
        assert!((d[1].distance - 1.0 / 12.0).abs() < 1e-9, "{:?}", d[1]);
        assert!((d[1].at - 150.0).abs() < 1e-9);
        // The middle piece is 0.25 + u/300 - u²/30000.
        for u in [0.0, 25.0, 50.0, 75.0, 100.0] {
            let want = 0.25 + u / 300.0 - u * u / 30000.0;
            assert!((s.value(100.0 + u) - want).abs() < 1e-12);
        }
        assert!((s.derivative(0.0) - 0.005).abs() < 1e-12);
        assert!((s.derivative(300.0) + 0.005).abs() < 1e-12);
    }

    #[test]
    fn natural_bound_is_0_075() {
        let s = CubicSpline::new(&XS, &YS, EndCondition::Natural).unwrap();
        assert!((s.value(150.0) - 0.325).abs() < 1e-12);
        let d = s.chord_distances();
        assert!((d[1].distance - 0.075).abs() < 1e-12);
        assert!(s.second_derivative(0.0).abs() < 1e-15);
        assert!(s.second_derivative(300.0).abs() < 1e-15);
    }

    #[test]
    fn two_knots_are_linear() {
        let s = CubicSpline::new(&[0.0, 10.0], &[1.0, 3.0], EndCondition::Natural).unwrap();
        assert!((s.value(2.5) - 1.5).abs() < 1e-12);
        assert!((s.value(12.0) - 3.4).abs() < 1e-12);
        assert!(s.chord_distances()[0].distance.abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_knots() {
        let e = CubicSpline::new(&[0.0, 5.0, 5.0], &[0.0; 3], EndCondition::Natural);
        assert_eq!(
            e,
            Err(SplineError::NotIncreasing {
                index: 2,
                previous: 5.0,
                value: 5.0
            })
        );
        let e = CubicSpline::new(&[0.0], &[0.0], EndCondition::Natural);
        assert_eq!(e, Err(SplineError::TooFewKnots(1)));
    }
}
