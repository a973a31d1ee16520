//! `track spectrum`: how densely to sample a track, from a continuous scan (seed 4.9-4.12).
//!
//! The straight-line fit of the scanned points is removed, the residual of each coordinate is
//! Tukey-windowed and transformed (real DFT, zero-padded to [`PADDING`] times its length); the
//! amplitude in mm at spatial frequency `f` (1/mm) combines the three coordinates
//! (`sqrt(ax² + ay² + az²)`, so it does not depend on how the tracker was turned). The highest
//! frequency at which the amplitude peaks above the threshold, `f_max`, gives the sampling
//! spacing `1/(2·f_max)` (thesis eq. 4.12: 0.005/mm → 100 mm).

use realfft::RealFftPlanner;

use super::csv_table::NumericCsv;
use super::profile::{TrackError, line_residuals};

/// Fewest samples a spectrum is computed from.
pub const MIN_SAMPLES: usize = 8;

/// The positions (column `position`, times `scale`: 1 for a skid in mm, the speed for a time in
/// s) and points of a scan table; a position that does not increase is an error at its line.
pub fn scan_from_table(
    table: &NumericCsv,
    position: &str,
    scale: f64,
) -> Result<(Vec<f64>, Vec<[f64; 3]>), TrackError> {
    let mut positions: Vec<f64> = Vec::with_capacity(table.rows.len());
    let mut points = Vec::with_capacity(table.rows.len());
    for (line, [s, x, y, z]) in table.select(&[position, "x", "y", "z"])? {
        let s = s * scale;
        if let Some(prev) = positions.last()
            && s <= *prev
        {
            return Err(table.error(
                line,
                position,
                format!("position {s} mm does not follow {prev} mm in increasing order"),
                "sort the scan by position and keep one row per position",
            ));
        }
        positions.push(s);
        points.push([x, y, z]);
    }
    if positions.len() < MIN_SAMPLES {
        let line = table.rows.last().map_or(table.header_line, |r| r.line);
        return Err(table.error(
            line,
            "",
            format!(
                "{} scan sample(s); a spectrum needs at least {MIN_SAMPLES}",
                positions.len()
            ),
            "scan the track continuously (a point every 10 mm is usual)",
        ));
    }
    Ok((positions, points))
}

/// Fraction of the window that is tapered (0 = rectangular, 1 = Hann).
pub const TUKEY_ALPHA: f64 = 0.5;

/// How many times the scan's length the transform is (the rest zeros): the amplitudes are read
/// on a grid this much finer than the scan's frequency resolution. A waviness whose wavelength
/// falls between two bins of the scan's own grid read up to 22 % low there (a 0.1 mm wave at
/// 1234 mm over 8 m read 0.078 mm, under a 0.08 mm threshold); at a sixteenth of a bin off the
/// line, the most this grid leaves, the main lobe is within 1 % of its top.
pub const PADDING: usize = 8;

/// Spacings that differ by more than this fraction from the mean are resampled.
const UNIFORM_TOLERANCE: f64 = 0.01;

/// The result of a scan analysis.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Number of samples transformed.
    pub samples: usize,
    /// Sample spacing, mm.
    pub spacing_mm: f64,
    /// Whether the scan was linearly resampled to uniform spacing first.
    pub resampled: bool,
    /// Spatial frequencies, 1/mm (`k / (PADDING·n·spacing)`, k = 0..=PADDING·n/2).
    pub frequency: Vec<f64>,
    /// Combined amplitude per frequency, mm.
    pub amplitude: Vec<f64>,
    /// Amplitude threshold, mm.
    pub threshold_mm: f64,
    /// The highest frequency (above 0) at which the amplitude peaks above the threshold, and
    /// that amplitude.
    pub highest: Option<(f64, f64)>,
}

impl Spectrum {
    /// `1/(2·f_max)`, mm; `None` when no frequency exceeds the threshold.
    pub fn recommended_spacing_mm(&self) -> Option<f64> {
        self.highest.map(|(f, _)| 1.0 / (2.0 * f))
    }

    /// The Nyquist frequency of the scan, 1/mm.
    pub fn nyquist(&self) -> f64 {
        0.5 / self.spacing_mm
    }

    /// The indices of the local maxima of the amplitude (above frequency 0), largest first.
    pub fn peaks(&self) -> Vec<usize> {
        let amp = &self.amplitude;
        let mut peaks: Vec<usize> = (1..amp.len())
            .filter(|&k| {
                let a = amp[k];
                a >= amp[k - 1] && amp.get(k + 1).is_none_or(|n| a > *n)
            })
            .collect();
        peaks.sort_by(|&x, &y| amp[y].total_cmp(&amp[x]));
        peaks
    }

    /// The scan's frequency resolution, 1/mm: `1/(n·spacing)`, the width of a bin of its own
    /// (the grid the amplitudes are read on is [`PADDING`] times finer).
    pub fn resolution(&self) -> f64 {
        1.0 / (self.samples as f64 * self.spacing_mm)
    }
}

/// The Tukey window of length `n`.
pub fn tukey_window(n: usize, alpha: f64) -> Vec<f64> {
    if n < 2 {
        return vec![1.0; n];
    }
    let m = (n - 1) as f64;
    let edge = alpha * m / 2.0;
    (0..n)
        .map(|i| {
            let x = i as f64;
            let d = x.min(m - x);
            if alpha <= 0.0 || d >= edge {
                1.0
            } else {
                0.5 * (1.0 - (std::f64::consts::PI * d / edge).cos())
            }
        })
        .collect()
}

/// Analyses a scan: `positions` along the track (mm, strictly increasing) and the measured
/// points.
pub fn scan_spectrum(
    positions: &[f64],
    points: &[[f64; 3]],
    threshold_mm: f64,
) -> Result<Spectrum, TrackError> {
    let n = positions.len();
    if n != points.len() {
        return Err(TrackError::Scan(format!(
            "{n} positions but {} points",
            points.len()
        )));
    }
    if n < MIN_SAMPLES {
        return Err(TrackError::Scan(format!(
            "{n} scan samples; a spectrum needs at least {MIN_SAMPLES}"
        )));
    }
    for (i, w) in positions.windows(2).enumerate() {
        if let [a, b] = w
            && b <= a
        {
            return Err(TrackError::Scan(format!(
                "scan row {}: position {b} does not follow {a} in increasing order",
                i + 2
            )));
        }
    }
    let (first, last) = (positions[0], positions[n - 1]);
    let spacing = (last - first) / (n - 1) as f64;
    let uniform = positions
        .windows(2)
        .all(|w| ((w[1] - w[0]) - spacing).abs() <= UNIFORM_TOLERANCE * spacing);
    let grid: Vec<f64> = (0..n).map(|i| first + i as f64 * spacing).collect();
    let mut coords: [Vec<f64>; 3] = [0, 1, 2].map(|a| points.iter().map(|p| p[a]).collect());
    if !uniform {
        coords = coords.map(|c| resample(positions, &c, &grid));
    }
    let window = tukey_window(n, TUKEY_ALPHA);
    let gain: f64 = window.iter().sum();
    let mut planner = RealFftPlanner::<f64>::new();
    let padded = n * PADDING;
    let fft = planner.plan_fft_forward(padded);
    let bins = padded / 2 + 1;
    let mut power = vec![0.0; bins];
    for c in &coords {
        let residual = line_residuals(&grid, c);
        let mut input: Vec<f64> = residual.iter().zip(&window).map(|(r, w)| r * w).collect();
        input.resize(padded, 0.0);
        let mut output = fft.make_output_vec();
        fft.process(&mut input, &mut output)
            .map_err(|e| TrackError::Output(format!("DFT failed: {e}")))?;
        for (k, (p, x)) in power.iter_mut().zip(&output).enumerate() {
            // One-sided amplitude: DC and Nyquist are not doubled.
            let scale = if k == 0 || k == padded / 2 { 1.0 } else { 2.0 };
            let a = scale * x.norm() / gain;
            *p += a * a;
        }
    }
    let amplitude: Vec<f64> = power.iter().map(|p| p.sqrt()).collect();
    let frequency: Vec<f64> = (0..bins)
        .map(|k| k as f64 / (padded as f64 * spacing))
        .collect();
    let mut spectrum = Spectrum {
        samples: n,
        spacing_mm: spacing,
        resampled: !uniform,
        frequency,
        amplitude,
        threshold_mm,
        highest: None,
    };
    // The highest frequency whose amplitude peaks above the threshold, read at the peak: on
    // the fine grid the window's main lobe stays above the threshold well past the line (a
    // bin and a half for a line twice the threshold), which would ask for denser sampling
    // than the track's waviness needs. A side lobe of a strong line that peaks above the
    // threshold errs on the safe side.
    spectrum.highest = spectrum
        .peaks()
        .into_iter()
        .filter(|&k| spectrum.amplitude[k] > threshold_mm)
        .max()
        .map(|k| (spectrum.frequency[k], spectrum.amplitude[k]));
    Ok(spectrum)
}

/// Linear interpolation of `(xs, ys)` at `grid` (inside `xs`' range).
fn resample(xs: &[f64], ys: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut j = 0;
    grid.iter()
        .map(|&g| {
            while j + 2 < xs.len() && xs[j + 1] < g {
                j += 1;
            }
            let (x0, x1, y0, y1) = (xs[j], xs[j + 1], ys[j], ys[j + 1]);
            y0 + (y1 - y0) * (g - x0) / (x1 - x0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wave(step: f64, amp: f64, freq: f64) -> (Vec<f64>, Vec<[f64; 3]>) {
        let s: Vec<f64> = (0..800).map(|i| i as f64 * step).collect();
        let p = s
            .iter()
            .map(|&x| {
                let w = amp * (2.0 * std::f64::consts::PI * freq * x).sin();
                [x * 0.9998 + 10.0, 0.001 * x + w, -5.0]
            })
            .collect();
        (s, p)
    }

    #[test]
    fn finds_a_0_005_per_mm_wave_and_recommends_100_mm() {
        // Thesis eq. 4.12: 0.005/mm → 1/(2·0.005) = 100 mm.
        let (s, p) = wave(10.0, 0.2, 0.005);
        let spec = scan_spectrum(&s, &p, 0.05).unwrap();
        let (f, _) = spec.highest.unwrap();
        // Read at the peak, within a sixteenth of a bin (0.000125/mm) of the line.
        assert!((f - 0.005).abs() < 0.000125 / 16.0, "{f}");
        let peak = spec.amplitude.iter().copied().fold(0.0, f64::max);
        assert!((peak - 0.2).abs() < 1e-3, "{peak}");
        let spacing = spec.recommended_spacing_mm().unwrap();
        assert!((spacing - 100.0).abs() < 7.0, "{spacing}");
        assert!(!spec.resampled);
    }

    /// A waviness whose wavelength falls anywhere between the scan's own bins reads its
    /// amplitude within 1 %: 0.1 mm at 1000-1300 mm over 8010 mm read as low as 0.078 mm when
    /// the amplitudes were taken on the scan's own grid.
    #[test]
    fn a_wave_between_bins_reads_its_amplitude() {
        let s: Vec<f64> = (0..802).map(|i| i as f64 * 10.0).collect();
        for wavelength in (1000..=1300).step_by(17) {
            let f = 1.0 / wavelength as f64;
            let p: Vec<[f64; 3]> = s
                .iter()
                .map(|&x| {
                    [
                        x,
                        0.1 * (2.0 * std::f64::consts::PI * f * x + 0.3).sin(),
                        0.0,
                    ]
                })
                .collect();
            let spec = scan_spectrum(&s, &p, 0.08).unwrap();
            let (k, peak) = spec
                .amplitude
                .iter()
                .copied()
                .enumerate()
                .skip(1)
                .fold((0, 0.0), |m, (k, a)| if a > m.1 { (k, a) } else { m });
            assert!((peak - 0.1).abs() < 1e-3, "{wavelength} mm: {peak}");
            assert!(
                (spec.frequency[k] - f).abs() < spec.resolution() / 8.0,
                "{wavelength}"
            );
            assert!(spec.highest.is_some(), "{wavelength}");
        }
    }

    #[test]
    fn peaks_are_local_maxima_largest_first() {
        let spec = Spectrum {
            samples: 7,
            spacing_mm: 1.0,
            resampled: false,
            frequency: (0..7).map(f64::from).collect(),
            amplitude: vec![5.0, 1.0, 3.0, 2.0, 4.0, 0.5, 0.6],
            threshold_mm: 1.0,
            highest: None,
        };
        assert_eq!(spec.peaks(), vec![4, 2, 6]);
    }

    #[test]
    fn resamples_uneven_scans() {
        let (mut s, p) = wave(10.0, 0.2, 0.005);
        for (i, x) in s.iter_mut().enumerate() {
            if i % 3 == 1 {
                *x += 2.0;
            }
        }
        let spec = scan_spectrum(&s, &p, 0.05).unwrap();
        assert!(spec.resampled);
        assert!(spec.highest.is_some());
    }

    #[test]
    fn tukey_is_one_inside_and_zero_at_the_ends() {
        let w = tukey_window(101, 0.5);
        assert_eq!(w[0], 0.0);
        assert_eq!(w[50], 1.0);
        assert!((w[100]).abs() < 1e-15);
    }
}
