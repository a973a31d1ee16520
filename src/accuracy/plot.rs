//! SVG figures (plotters, SVG backend): pose deviations with repeatability circles (thesis Figs
//! 3.11-3.12); for a path the plane views ideal vs measured (Fig 5.2), the deviation along the
//! path (5.3), the look-through view along the path (5.4) and velocity and acceleration (5.5).
//! Same input, same bytes: the SVG backend estimates text without fonts.

use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::error::AccuracyError;
use super::line::{acceleration_series, speed_series};
use super::path::{PathReport, Polyline};
use super::pose::PoseReport;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type Drawn = Result<(), AccuracyError>;
/// One figure of a point, for the bars.
type Figure = fn(&super::pose::PointAccuracy) -> f64;

const IDEAL: RGBColor = RGBColor(0, 150, 0);
const MEASURED: RGBColor = RGBColor(200, 0, 0);

/// Ten distinguishable colours (matplotlib's "tab10"), one per run or point.
fn run_color(k: usize) -> RGBColor {
    const COLORS: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    COLORS[k % COLORS.len()]
}

/// A value range with some margin; a flat series gets a small symmetric one.
fn padded(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
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

/// A range centred on 0 that holds every value, for views with equal scales.
fn symmetric(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let r = values
        .filter(|v| v.is_finite())
        .map(f64::abs)
        .fold(0.0, f64::max)
        .max(1e-3)
        * 1.1;
    -r..r
}

fn circle(c: (f64, f64), r: f64) -> Vec<(f64, f64)> {
    (0..=72)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 72.0;
            (c.0 + r * a.cos(), c.1 + r * a.sin())
        })
        .collect()
}

fn svg(size: (u32, u32), draw: impl FnOnce(&Area<'_>) -> Drawn) -> Result<String, AccuracyError> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(AccuracyError::plot)?;
        draw(&root)?;
        root.present().map_err(AccuracyError::plot)?;
    }
    Ok(text)
}

/// Figs 3.11-3.12: AP, MAX and RP per point, and each point's visits in the x/y plane around
/// its mean deviation with the RP circle. With an earlier measurement, its AP as a bar beside
/// and a line from its mean deviation to the new one: how far a correction moved each point.
pub fn pose_svg(report: &PoseReport, before: Option<&PoseReport>) -> Result<String, AccuracyError> {
    let earlier = |name: &str| before.and_then(|b| b.points.iter().find(|p| p.point == name));
    svg((1400, 650), |root| {
        let root = root
            .titled(
                "ISO 9283 pose accuracy (AP, MAX) and repeatability (RP)",
                ("sans-serif", 22),
            )
            .map_err(AccuracyError::plot)?;
        let (left, right) = root.split_horizontally(750);
        let n = report.points.len();
        let top = report
            .points
            .iter()
            .flat_map(|p| [p.ap, p.max, p.rp, earlier(&p.point).map_or(0.0, |b| b.ap)])
            .fold(0.0, f64::max)
            .max(1e-3)
            * 1.35;
        let mut chart = ChartBuilder::on(&left)
            .caption("per point [mm]", ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..top)
            .map_err(AccuracyError::plot)?;
        let names: Vec<String> = report.points.iter().map(|p| p.point.clone()).collect();
        chart
            .configure_mesh()
            .x_labels(n.max(1))
            .x_label_formatter(&|v| {
                let i = v.round();
                if (v - i).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc("deviation [mm]")
            .draw()
            .map_err(AccuracyError::plot)?;
        let series: [(&str, RGBColor, Figure); 3] = [
            ("AP (ISO)", BLUE, |p| p.ap),
            ("MAX", MEASURED, |p| p.max),
            ("RP", IDEAL, |p| p.rp),
        ];
        let (bars, width) = if before.is_some() {
            (4.0, 0.18)
        } else {
            (3.0, 0.22)
        };
        let offset = |k: usize| (k as f64 - (bars - 1.0) / 2.0) * width;
        if before.is_some() {
            let light = RGBColor(150, 170, 230);
            chart
                .draw_series(report.points.iter().enumerate().map(|(i, p)| {
                    let x = i as f64 + offset(0);
                    let h = earlier(&p.point).map_or(0.0, |b| b.ap);
                    Rectangle::new(
                        [(x - width / 2.2, 0.0), (x + width / 2.2, h)],
                        light.filled(),
                    )
                }))
                .map_err(AccuracyError::plot)?
                .label("AP before")
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], light.filled())
                });
        }
        let first = usize::from(before.is_some());
        for (k, (label, color, value)) in series.into_iter().enumerate() {
            let dx = offset(k + first);
            chart
                .draw_series(report.points.iter().enumerate().map(|(i, p)| {
                    let x = i as f64 + dx;
                    Rectangle::new(
                        [(x - width / 2.2, 0.0), (x + width / 2.2, value(p))],
                        color.filled(),
                    )
                }))
                .map_err(AccuracyError::plot)?
                .label(label)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(AccuracyError::plot)?;

        let range = symmetric(report.points.iter().flat_map(|p| {
            p.deviations
                .iter()
                .flat_map(|d| [d.x, d.y])
                .chain([p.ap_x.abs() + p.rp, p.ap_y.abs() + p.rp])
                .chain(earlier(&p.point).map_or([0.0; 2], |b| [b.ap_x, b.ap_y]))
                .collect::<Vec<_>>()
        }));
        let mut chart = ChartBuilder::on(&right)
            .caption(
                if before.is_some() {
                    "x/y deviation of each visit; circle: RP around the mean; x: mean before"
                } else {
                    "x/y deviation of each visit; circle: RP around the mean"
                },
                ("sans-serif", 16),
            )
            .margin(14)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(range.clone(), range)
            .map_err(AccuracyError::plot)?;
        chart
            .configure_mesh()
            .x_desc("dx [mm]")
            .y_desc("dy [mm]")
            .draw()
            .map_err(AccuracyError::plot)?;
        for (i, p) in report.points.iter().enumerate() {
            let color = run_color(i);
            if let Some(b) = earlier(&p.point) {
                chart
                    .draw_series(LineSeries::new(
                        [(b.ap_x, b.ap_y), (p.ap_x, p.ap_y)],
                        color.mix(0.6),
                    ))
                    .map_err(AccuracyError::plot)?;
                chart
                    .draw_series(std::iter::once(Cross::new((b.ap_x, b.ap_y), 4, color)))
                    .map_err(AccuracyError::plot)?;
            }
            chart
                .draw_series(
                    p.deviations
                        .iter()
                        .map(|d| Circle::new((d.x, d.y), 2, color.filled())),
                )
                .map_err(AccuracyError::plot)?;
            chart
                .draw_series(LineSeries::new(circle((p.ap_x, p.ap_y), p.rp), color))
                .map_err(AccuracyError::plot)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    p.point.clone(),
                    // Beside the circle, not over the visits.
                    (p.ap_x + p.rp, p.ap_y + p.rp),
                    ("sans-serif", 13).into_font().color(&BLACK),
                )))
                .map_err(AccuracyError::plot)?;
        }
        Ok(())
    })
}

/// The look-through frame of segment `k`: `z` along the path, `x` horizontal.
fn look_frame(commanded: &Polyline, k: usize) -> (Vector3<f64>, Vector3<f64>) {
    let u = commanded.tangent(k);
    let side = u.cross(&Vector3::z());
    let e1 = if side.norm() > 1e-6 {
        side.normalize()
    } else {
        u.cross(&Vector3::x()).normalize()
    };
    (e1, u.cross(&e1))
}

fn plane_views(area: &Area<'_>, commanded: &Polyline, report: &PathReport) -> Drawn {
    let panels = area.split_evenly((1, 3));
    let views: [(usize, usize, &str); 3] = [(0, 1, "x/y"), (0, 2, "x/z"), (1, 2, "y/z")];
    for (panel, (a, b, name)) in panels.iter().zip(views) {
        let measured: Vec<(f64, f64)> = report
            .used
            .iter()
            .flat_map(|r| r.samples.iter().map(|s| (s.position[a], s.position[b])))
            .collect();
        let ideal: Vec<(f64, f64)> = commanded.vertices().iter().map(|v| (v[a], v[b])).collect();
        let xr = padded(measured.iter().chain(&ideal).map(|p| p.0));
        let yr = padded(measured.iter().chain(&ideal).map(|p| p.1));
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!("{name} plane (green: ideal, red: measured)"),
                ("sans-serif", 15),
            )
            .margin(10)
            .x_label_area_size(32)
            .y_label_area_size(64)
            .build_cartesian_2d(xr, yr)
            .map_err(AccuracyError::plot)?;
        let axis = ["x [mm]", "y [mm]", "z [mm]"];
        chart
            .configure_mesh()
            .x_labels(5)
            .x_desc(axis[a])
            .y_desc(axis[b])
            .draw()
            .map_err(AccuracyError::plot)?;
        chart
            .draw_series(LineSeries::new(ideal.clone(), IDEAL.stroke_width(2)))
            .map_err(AccuracyError::plot)?;
        // Looking along the path (its projection shorter than a millimetre), a line through
        // the samples would only zigzag: show them as dots.
        let projected: f64 = ideal
            .windows(2)
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .sum();
        for run in &report.used {
            let pts = run.samples.iter().map(|s| (s.position[a], s.position[b]));
            if projected < 1.0 {
                chart
                    .draw_series(pts.map(|p| Circle::new(p, 1, MEASURED.mix(0.5).filled())))
                    .map_err(AccuracyError::plot)?;
            } else {
                chart
                    .draw_series(LineSeries::new(pts, MEASURED))
                    .map_err(AccuracyError::plot)?;
            }
        }
    }
    Ok(())
}

fn deviation_along(area: &Area<'_>, commanded: &Polyline, report: &PathReport) -> Drawn {
    let curves: Vec<Vec<(f64, f64)>> = report
        .used
        .iter()
        .map(|r| {
            r.samples
                .iter()
                .map(|s| commanded.project(&s.position))
                .filter(|p| (0.0..=report.length).contains(&p.s))
                .map(|p| (p.s, p.distance))
                .collect()
        })
        .collect();
    let top = curves
        .iter()
        .flatten()
        .map(|p| p.1)
        .fold(0.0, f64::max)
        .max(1e-3)
        * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption(
            "absolute deviation from the commanded path (eq. 3.38); dots: ATp per plane",
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(32)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..report.length.max(1e-3), 0.0..top)
        .map_err(AccuracyError::plot)?;
    chart
        .configure_mesh()
        .x_desc("path position s [mm]")
        .y_desc("deviation [mm]")
        .draw()
        .map_err(AccuracyError::plot)?;
    for (k, c) in curves.into_iter().enumerate() {
        chart
            .draw_series(LineSeries::new(c, run_color(k)))
            .map_err(AccuracyError::plot)?;
    }
    chart
        .draw_series(
            report
                .planes
                .iter()
                .map(|p| Circle::new((p.s, p.atp), 4, BLACK.filled())),
        )
        .map_err(AccuracyError::plot)?;
    Ok(())
}

fn look_through(area: &Area<'_>, commanded: &Polyline, report: &PathReport) -> Drawn {
    let points: Vec<(f64, f64)> = report
        .used
        .iter()
        .flat_map(|r| r.samples.iter())
        .map(|s| commanded.project(&s.position))
        .filter(|p| (0.0..=report.length).contains(&p.s))
        .map(|p| {
            let (e1, e2) = look_frame(commanded, p.segment);
            (p.offset.dot(&e1), p.offset.dot(&e2))
        })
        .collect();
    let range = symmetric(points.iter().flat_map(|p| [p.0, p.1]));
    let mut chart = ChartBuilder::on(area)
        .caption(
            "look-through: deviation across the path, z along it (density of samples)",
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(32)
        .y_label_area_size(64)
        .build_cartesian_2d(range.clone(), range)
        .map_err(AccuracyError::plot)?;
    chart
        .configure_mesh()
        .x_desc("across, horizontal [mm]")
        .y_desc("across, up [mm]")
        .draw()
        .map_err(AccuracyError::plot)?;
    chart
        .draw_series(
            points
                .into_iter()
                .map(|p| Circle::new(p, 2, MEASURED.mix(0.25).filled())),
        )
        .map_err(AccuracyError::plot)?;
    chart
        .draw_series(std::iter::once(Cross::new(
            (0.0, 0.0),
            6,
            IDEAL.stroke_width(2),
        )))
        .map_err(AccuracyError::plot)?;
    Ok(())
}

fn velocity(area: &Area<'_>, report: &PathReport) -> Drawn {
    let (top, bottom) = area.split_vertically(area.dim_in_pixel().1 / 2);
    let speeds: Vec<Vec<(f64, f64)>> = report.used.iter().map(speed_series).collect();
    let accels: Vec<Vec<(f64, f64)>> = report.used.iter().map(acceleration_series).collect();
    for (panel, curves, label) in [
        (&top, &speeds, "velocity [mm/s]"),
        (&bottom, &accels, "acceleration [mm/s²]"),
    ] {
        let xr = padded(curves.iter().flatten().map(|p| p.0));
        let mut values: Vec<f64> = curves.iter().flatten().map(|p| p.1).collect();
        if label.starts_with("velocity") {
            values.extend(report.line.commanded_velocity);
            values.push(0.0);
        }
        let yr = padded(values.into_iter());
        let mut chart = ChartBuilder::on(panel)
            .caption(label, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(32)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.clone(), yr)
            .map_err(AccuracyError::plot)?;
        chart
            .configure_mesh()
            .x_desc("time from the run's first sample [s]")
            .y_desc(label)
            .draw()
            .map_err(AccuracyError::plot)?;
        for (k, c) in curves.iter().enumerate() {
            chart
                .draw_series(LineSeries::new(c.iter().copied(), run_color(k)))
                .map_err(AccuracyError::plot)?;
        }
        if label.starts_with("velocity")
            && let Some(v) = report.line.commanded_velocity
        {
            chart
                .draw_series(LineSeries::new(
                    [(xr.start, v), (xr.end, v)],
                    IDEAL.stroke_width(2),
                ))
                .map_err(AccuracyError::plot)?;
        }
    }
    Ok(())
}

/// Table 5.1 as text, beside the look-through view of the combined figure.
fn line_facts(area: &Area<'_>, report: &PathReport) -> Drawn {
    let l = &report.line;
    let opt = |v: Option<f64>, unit: &str, decimals: usize| {
        v.map_or_else(|| "-".to_owned(), |v| format!("{v:.decimals$} {unit}"))
    };
    let rows = [
        ("path length", format!("{:.3} m", l.length / 1000.0)),
        ("commanded velocity", opt(l.commanded_velocity, "mm/s", 1)),
        ("measured velocity", opt(l.measured_velocity, "mm/s", 1)),
        (
            "velocity deviation (max)",
            opt(l.velocity_deviation_max_percent, "%", 1),
        ),
        ("acceleration", opt(l.acceleration, "mm/s²", 0)),
        ("max. path deviation", format!("{:.3} mm", l.max_deviation)),
        (
            "repeating uncertainty",
            format!("{:.3} mm", l.repeat_uncertainty),
        ),
        ("deviation at start", format!("{:.3} mm", l.start_deviation)),
        ("deviation at end", format!("{:.3} mm", l.end_deviation)),
        ("AT / RT", format!("{:.3} / {:.3} mm", report.at, report.rt)),
    ];
    let font = ("sans-serif", 18).into_font().color(&BLACK);
    area.draw(&Text::new(
        "straight line (Table 5.1)",
        (30, 40),
        font.clone(),
    ))
    .map_err(AccuracyError::plot)?;
    for (k, (name, value)) in rows.iter().enumerate() {
        let y = 80 + 30 * k as i32;
        area.draw(&Text::new(name.to_string(), (30, y), font.clone()))
            .map_err(AccuracyError::plot)?;
        area.draw(&Text::new(value.clone(), (330, y), font.clone()))
            .map_err(AccuracyError::plot)?;
    }
    Ok(())
}

/// The path figures, each on its own: `(file stem, SVG)` for Figs 5.2-5.5.
pub fn path_svgs(
    commanded: &Polyline,
    report: &PathReport,
) -> Result<Vec<(&'static str, String)>, AccuracyError> {
    Ok(vec![
        (
            "planes",
            svg((1500, 500), |a| plane_views(a, commanded, report))?,
        ),
        (
            "deviation",
            svg((1200, 500), |a| deviation_along(a, commanded, report))?,
        ),
        (
            "look_through",
            svg((700, 700), |a| look_through(a, commanded, report))?,
        ),
        ("velocity", svg((1200, 800), |a| velocity(a, report))?),
    ])
}

/// All path figures in one SVG.
pub fn path_svg(commanded: &Polyline, report: &PathReport) -> Result<String, AccuracyError> {
    svg((1500, 2300), |root| {
        let root = root
            .titled(
                &format!(
                    "ISO 9283 path accuracy: AT {:.3} mm, RT {:.3} mm over {} runs",
                    report.at, report.rt, report.runs_used
                ),
                ("sans-serif", 22),
            )
            .map_err(AccuracyError::plot)?;
        let (planes, rest) = root.split_vertically(480);
        let (deviation, rest) = rest.split_vertically(480);
        let (look, speed) = rest.split_vertically(760);
        plane_views(&planes, commanded, report)?;
        deviation_along(&deviation, commanded, report)?;
        let (look, facts) = look.split_horizontally(760);
        look_through(&look, commanded, report)?;
        line_facts(&facts, report)?;
        velocity(&speed, report)
    })
}
