//! SVG figures (plotters, SVG backend only): the six deviation curves with their knots and the
//! twist diagram of a profile, and the amplitude spectrum of a scan. Same input, same bytes:
//! plotters' SVG backend estimates text size without fonts, so nothing depends on the machine.

use plotters::prelude::*;

use super::adjustment::twist_diagram;
use super::profile::{Profile, TrackError};
use super::spectrum::Spectrum;

const CURVE_SAMPLES: usize = 400;
const LABELS: [&str; 6] = [
    "dx [mm]", "dy [mm]", "dz [mm]", "rx [deg]", "ry [deg]", "rz [deg]",
];

fn plot_error(e: impl std::fmt::Display) -> TrackError {
    TrackError::Output(format!("cannot draw the plot: {e}"))
}

/// A value range with some margin; a flat series gets a small symmetric one.
fn padded(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() || !hi.is_finite() {
        return -1.0..1.0;
    }
    let span = hi - lo;
    let pad = if span > 1e-9 {
        0.08 * span
    } else {
        1e-3_f64.max(lo.abs() * 0.1)
    };
    (lo - pad)..(hi + pad)
}

/// The profile figure: six deviation curves (line: spline, dots: knots) and the twist diagram.
pub fn profile_svg(profile: &Profile) -> Result<String, TrackError> {
    let (s0, s1) = profile.skid_range();
    let xs: Vec<f64> = (0..=CURVE_SAMPLES)
        .map(|i| s0 + (s1 - s0) * i as f64 / CURVE_SAMPLES as f64)
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1200, 1500)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let root = root
            .titled(
                &format!(
                    "track profile `{}`: deviation D(s) from the nominal",
                    profile.name()
                ),
                ("sans-serif", 22),
            )
            .map_err(plot_error)?;
        let areas = root.split_evenly((4, 2));
        for (c, (area, label)) in areas.iter().zip(LABELS).enumerate() {
            let Some(spline) = profile.splines().get(c) else {
                continue;
            };
            let curve: Vec<(f64, f64)> = xs.iter().map(|&x| (x, spline.value(x))).collect();
            let knots: Vec<(f64, f64)> = spline
                .knots()
                .iter()
                .zip(spline.values())
                .map(|(x, y)| (*x, *y))
                .collect();
            let yr = padded(curve.iter().map(|p| p.1));
            let mut chart = ChartBuilder::on(area)
                .caption(label, ("sans-serif", 18))
                .margin(12)
                .margin_right(28)
                .x_label_area_size(32)
                .y_label_area_size(64)
                .build_cartesian_2d(s0..s1, yr)
                .map_err(plot_error)?;
            chart
                .configure_mesh()
                .x_label_formatter(&|v| format!("{v:.0}"))
                .x_desc("skid [mm]")
                .y_desc(label)
                .draw()
                .map_err(plot_error)?;
            chart
                .draw_series(LineSeries::new(curve, BLUE.stroke_width(2)))
                .map_err(plot_error)?;
            chart
                .draw_series(knots.into_iter().map(|p| Circle::new(p, 4, RED.filled())))
                .map_err(plot_error)?;
        }
        if let Some(area) = areas.get(6) {
            twist_panel(area, profile)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

/// Ranges around `x` and `y` with one scale (mm per pixel) for both axes over a plotting area
/// of `width` × `height` pixels, so the diagram shows the lever's true direction.
fn equal_scale(
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    (width, height): (u32, u32),
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (w, h) = (f64::from(width.max(1)), f64::from(height.max(1)));
    let per_pixel = ((x.end - x.start) / w).max((y.end - y.start) / h);
    let widen = |r: std::ops::Range<f64>, pixels: f64| {
        let mid = (r.start + r.end) / 2.0;
        let half = per_pixel * pixels / 2.0;
        (mid - half)..(mid + half)
    };
    (widen(x, w), widen(y, h))
}

/// The twist diagram: the tip of a 1 m lever along +z of each knot, labelled with the knot's
/// skid, on equal x and y scales.
fn twist_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    profile: &Profile,
) -> Result<(), TrackError> {
    let twist = twist_diagram(profile);
    let area = area
        .titled(
            "twist diagram: 1 m lever along +z, relative to the first knot [mm], labels: skid [mm]",
            ("sans-serif", 15),
        )
        .map_err(plot_error)?;
    let build = |xr: std::ops::Range<f64>, yr: std::ops::Range<f64>| {
        ChartBuilder::on(&area)
            .margin(12)
            .margin_right(28)
            .x_label_area_size(32)
            .y_label_area_size(64)
            .build_cartesian_2d(xr, yr)
            .map_err(plot_error)
    };
    // Building a chart draws nothing: the first one only measures the plotting area.
    let dims = build(0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
    let (xr, yr) = equal_scale(
        padded(twist.iter().map(|t| t.x)),
        padded(twist.iter().map(|t| t.y)),
        dims,
    );
    let mut chart = build(xr, yr)?;
    chart
        .configure_mesh()
        .x_desc("x [mm]")
        .y_desc("y [mm]")
        .draw()
        .map_err(plot_error)?;
    let pts: Vec<(f64, f64)> = twist.iter().map(|t| (t.x, t.y)).collect();
    chart
        .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(1)))
        .map_err(plot_error)?;
    chart
        .draw_series(pts.iter().map(|p| Circle::new(*p, 4, RED.filled())))
        .map_err(plot_error)?;
    chart
        .draw_series(twist.iter().map(|t| {
            // Beside the dot, not on it.
            EmptyElement::at((t.x, t.y))
                + Text::new(
                    format!("{}", t.skid),
                    (7, -5),
                    ("sans-serif", 11).into_font().color(&BLACK),
                )
        }))
        .map_err(plot_error)?;
    Ok(())
}

/// The scan figure: amplitude over spatial frequency, the threshold and the reported peak.
pub fn spectrum_svg(spectrum: &Spectrum) -> Result<String, TrackError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        // Up to the Nyquist frequency the noise floor would squeeze the part that matters into
        // the first few pixels: show ten times the reported frequency instead.
        let nyquist = spectrum.nyquist().max(1e-9);
        let fmax = spectrum
            .highest
            .map_or(nyquist, |(f, _)| (10.0 * f).min(nyquist));
        let amax = spectrum
            .amplitude
            .iter()
            .skip(1)
            .copied()
            .fold(spectrum.threshold_mm, f64::max)
            * 1.1;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "track scan: amplitude spectrum of the deviation from the straight line",
                ("sans-serif", 20),
            )
            .margin(14)
            .margin_right(30)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..fmax, 0.0..amax.max(1e-6))
            .map_err(plot_error)?;
        let x_desc = if fmax < nyquist {
            format!(
                "spatial frequency [1/mm] (wavelength [mm]); shown to {fmax:.6}, Nyquist {nyquist:.6}"
            )
        } else {
            "spatial frequency [1/mm] (wavelength [mm])".to_owned()
        };
        chart
            .configure_mesh()
            .x_label_formatter(&|f| {
                if *f > 0.0 {
                    format!("{f:.4} ({:.0})", 1.0 / f)
                } else {
                    "0".to_owned()
                }
            })
            .x_desc(x_desc)
            .y_desc("amplitude [mm]")
            .draw()
            .map_err(plot_error)?;
        let pts: Vec<(f64, f64)> = spectrum
            .frequency
            .iter()
            .zip(&spectrum.amplitude)
            .skip(1)
            .take_while(|(f, _)| **f <= fmax)
            .map(|(f, a)| (*f, *a))
            .collect();
        chart
            .draw_series(LineSeries::new(pts, BLUE.stroke_width(1)))
            .map_err(plot_error)?;
        let threshold = spectrum.threshold_mm;
        chart
            .draw_series(LineSeries::new(
                [(0.0, threshold), (fmax, threshold)],
                RED.stroke_width(1),
            ))
            .map_err(plot_error)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("threshold {threshold} mm"),
                (fmax * 0.75, threshold + amax * 0.02),
                ("sans-serif", 14).into_font().color(&RED),
            )))
            .map_err(plot_error)?;
        if let Some((f, a)) = spectrum.highest {
            chart
                .draw_series(std::iter::once(Circle::new((f, a), 5, RED.filled())))
                .map_err(plot_error)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!(
                        "highest above threshold: {f:.6} /mm (wavelength {:.0} mm) -> sample every {:.0} mm",
                        1.0 / f,
                        0.5 / f
                    ),
                    (f + fmax * 0.02, a + amax * 0.03),
                    ("sans-serif", 14).into_font().color(&RED),
                )))
                .map_err(plot_error)?;
        }
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_scale_gives_both_axes_one_mm_per_pixel_and_keeps_the_data() {
        let (x, y) = equal_scale(-0.6..0.6, -0.2..2.3, (512, 300));
        let (sx, sy) = ((x.end - x.start) / 512.0, (y.end - y.start) / 300.0);
        assert!((sx - sy).abs() < 1e-15, "{sx} {sy}");
        // y (2.5 mm over 300 px) sets the scale; x is widened about its middle.
        assert!((sy - 2.5 / 300.0).abs() < 1e-15);
        assert!(x.start <= -0.6 && x.end >= 0.6 && (x.start + x.end).abs() < 1e-12);
        assert!((y.start + 0.2).abs() < 1e-12 && (y.end - 2.3).abs() < 1e-12);
    }
}
