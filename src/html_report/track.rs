//! The track report: what was measured, what the model is and what to enter in the controller,
//! from whichever of measurements, frames, profile and scan were given. Missing steps are
//! computed with the track library (measurements → frames → profile), exactly as
//! `track identify` and `track fit` would.

use std::fmt::Write as _;

use crate::digest::sha256_hex;

use super::figures::ControllerFigures;
use super::html::{Cell, Page, Row, Section, definitions, escape, table};
use super::svg::{Chart, Span, fmt_fixed};
use crate::track::adjustment::{TWIST_LEVER_MM, chord_bounds, manual_adjustment, twist_diagram};
use crate::track::frames_csv::{SamplingFrame, frames_csv};
use crate::track::identify::{Identification, OUTLIER_FACTOR, identify};
use crate::track::nominal::{FitOptions, TrackFit, fit_track};
use crate::track::simulate::MeasurementRow;
use crate::track::spectrum::{PADDING, Spectrum, TUKEY_ALPHA};
use crate::track::{Profile, TrackError};

/// The six deviation components, in profile order.
pub const COMPONENTS: [&str; 6] = ["dx", "dy", "dz", "rx", "ry", "rz"];
const UNITS: [&str; 6] = ["mm", "mm", "mm", "deg", "deg", "deg"];

/// Headings of the track report's sections, in page order (tests look for them in the browser).
pub mod headings {
    /// The files read, with their hashes.
    pub const INPUTS: &str = "Inputs";
    /// The numbers to type into the controller.
    pub const CONTROLLER: &str = "Enter in the controller";
    /// How well the measured points fit each knot frame.
    pub const IDENTIFICATION: &str = "Identification residuals";
    /// `D(s)` with its uncertainty band.
    pub const DEVIATION: &str = "Deviation along the track";
    /// What to shim and turn at each rail segment.
    pub const ADJUSTMENT: &str = "Manual adjustment and twist diagram";
    /// How far the spline may stray between knots.
    pub const BOUNDS: &str = "Spline error bounds per interval";
    /// Whether the knot spacing resolves the rail's waviness.
    pub const SPECTRUM: &str = "Scan spectrum and sampling spacing";
    /// Repeatability and accuracy of the measured poses.
    pub const ACCURACY: &str = "ISO 9283 accuracy";
}

/// One input file as the report records it.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceFile {
    /// As given (a path), plain text.
    pub path: String,
    /// sha256 of the bytes read, hex.
    pub sha256: String,
}

impl SourceFile {
    /// Records a file read, hashing `bytes`.
    pub fn new(path: impl Into<String>, bytes: &[u8]) -> SourceFile {
        SourceFile {
            path: path.into(),
            sha256: sha256_hex(bytes),
        }
    }
}

/// A plain table for sections whose numbers come from elsewhere (ISO 9283 results, kinematics
/// checks): a title, column names and rows of already formatted cells.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DataTable {
    /// The table's caption, plain text.
    pub title: String,
    /// The column headings, plain text.
    pub columns: Vec<String>,
    /// One formatted cell per column, plain text.
    pub rows: Vec<Vec<String>>,
    /// A sentence under the table (what the figures mean), plain text.
    pub note: Option<String>,
}

impl DataTable {
    /// The table as HTML: cells that read as numbers are right-aligned.
    pub fn to_html(&self) -> String {
        let headers: Vec<&str> = self.columns.iter().map(String::as_str).collect();
        let rows: Vec<Row> = self
            .rows
            .iter()
            .map(|r| {
                Row::new(
                    r.iter()
                        .map(|c| {
                            if c.trim().parse::<f64>().is_ok() {
                                Cell::num(c.clone())
                            } else {
                                Cell::text(c.clone())
                            }
                        })
                        .collect(),
                )
            })
            .collect();
        let mut s = format!("<h3>{}</h3>\n", escape(&self.title));
        s.push_str(&table(&headers, &rows));
        if let Some(n) = &self.note {
            let _ = writeln!(s, "<p class=\"note\">{}</p>", escape(n));
        }
        s
    }
}

/// One ISO 9283 result for the accuracy section: the files it comes from, its tables and
/// optionally a chart (an inline SVG the private `svg` module draws) with its caption.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccuracyResult {
    /// (role, file), listed under the report's inputs.
    pub sources: Vec<(String, SourceFile)>,
    /// The result tables, in page order.
    pub tables: Vec<DataTable>,
    /// A chart: (SVG, caption).
    pub figure: Option<(String, String)>,
}

/// What the report is made from; each given input adds its sections.
#[derive(Clone, Debug, Default)]
pub struct TrackInputs {
    /// `measurements.csv` rows.
    pub measurements: Option<(SourceFile, Vec<MeasurementRow>)>,
    /// `frames.csv`; computed from the measurements when absent.
    pub frames: Option<(SourceFile, Vec<SamplingFrame>)>,
    /// `profile.toml`; fitted from the frames when absent.
    pub profile: Option<(SourceFile, Profile)>,
    /// The spectrum of a continuous scan.
    pub scan: Option<(SourceFile, Spectrum)>,
    /// How a profile is fitted when it is computed (`source_sha256` is filled in: the frames
    /// file's hash, or the hash of the frames text `track identify` would write).
    pub fit: FitOptions,
    /// ISO 9283 results; the section appears when there is at least one.
    pub accuracy: Vec<AccuracyResult>,
}

/// A step of the report that failed, and why.
#[derive(Debug, thiserror::Error)]
#[error("{step}")]
pub struct ReportError {
    /// What the report was computing, naming the input.
    pub step: String,
    #[source]
    /// The error the step stopped on.
    pub source: Box<TrackError>,
}

/// Everything the track report shows, computed.
#[derive(Clone, Debug)]
pub struct TrackReport {
    /// Input files and how each other input was obtained.
    pub sources: Vec<(String, SourceFile)>,
    /// Inputs computed rather than read: (what, from what).
    pub derived: Vec<(String, String)>,
    /// The per-knot identification, when measurements were given.
    pub identification: Option<Identification>,
    /// The fit, when the profile was computed here.
    pub fit: Option<TrackFit>,
    /// The profile shown (read, or the fit's).
    pub profile: Option<Profile>,
    /// The scan's spectrum, when a scan was given.
    pub spectrum: Option<Spectrum>,
    /// ISO 9283 results, one per accuracy run.
    pub accuracy: Vec<AccuracyResult>,
}

impl TrackReport {
    /// Fills in what is missing: identification from measurements, frames from the
    /// identification, the profile from the frames.
    pub fn compute(inputs: TrackInputs) -> Result<TrackReport, ReportError> {
        let mut sources = Vec::new();
        let mut derived = Vec::new();
        let mut identification = None;
        if let Some((src, rows)) = &inputs.measurements {
            let id = identify(rows).map_err(|source| ReportError {
                step: format!("identifying the base frames from {}", src.path),
                source: Box::new(source),
            })?;
            identification = Some(id);
            sources.push(("measurements".to_owned(), src.clone()));
        }
        let frames: Option<(String, String, Vec<SamplingFrame>)> =
            match (&inputs.frames, &identification) {
                (Some((src, frames)), _) => {
                    sources.push(("sampling frames".to_owned(), src.clone()));
                    Some((src.path.clone(), src.sha256.clone(), frames.clone()))
                }
                (None, Some(id)) => {
                    let frames = id.frames();
                    let text = frames_csv(&frames);
                    derived.push((
                        "sampling frames".to_owned(),
                        "identified from the measurements (as track identify writes frames.csv)"
                            .to_owned(),
                    ));
                    Some((
                        "the measurements".to_owned(),
                        sha256_hex(text.as_bytes()),
                        frames,
                    ))
                }
                (None, None) => None,
            };
        let mut fit = None;
        let profile = match (&inputs.profile, frames) {
            (Some((src, p)), _) => {
                sources.push(("profile".to_owned(), src.clone()));
                Some(p.clone())
            }
            (None, Some((from, sha, frames))) => {
                let opts = FitOptions {
                    source_sha256: sha,
                    ..inputs.fit.clone()
                };
                let f = fit_track(&frames, &opts).map_err(|source| ReportError {
                    step: format!("fitting the track to the frames of {from}"),
                    source: Box::new(source),
                })?;
                derived.push((
                    "profile".to_owned(),
                    format!(
                        "fitted to the sampling frames (as track fit: reference {}, gear {})",
                        enum_text(&opts.reference),
                        enum_text(&opts.gear)
                    ),
                ));
                let p = f.profile.clone();
                fit = Some(f);
                Some(p)
            }
            (None, None) => None,
        };
        let spectrum = inputs.scan.map(|(src, spec)| {
            sources.push(("scan".to_owned(), src));
            spec
        });
        for a in &inputs.accuracy {
            sources.extend(a.sources.iter().cloned());
        }
        Ok(TrackReport {
            sources,
            derived,
            identification,
            fit,
            profile,
            spectrum,
            accuracy: inputs.accuracy,
        })
    }

    /// The sections, in page order; each only when its input is there.
    pub fn sections(&self) -> Vec<Section> {
        let mut out = vec![self.inputs_section()];
        if let Some(p) = &self.profile {
            out.push(controller_section(p, self.fit.as_ref()));
        }
        if let Some(id) = &self.identification {
            out.push(identification_section(id));
        }
        if let Some(p) = &self.profile {
            out.push(deviation_section(p, knot_uncertainty(p).as_deref()));
            out.push(adjustment_section(p));
            out.push(bounds_section(p));
        }
        if let Some(s) = &self.spectrum {
            out.push(spectrum_section(s));
        }
        if !self.accuracy.is_empty() {
            out.push(accuracy_section(&self.accuracy));
        }
        out
    }

    /// The whole HTML page.
    pub fn render(&self) -> String {
        self.page().render()
    }

    /// The page before rendering: title, subtitle and sections.
    pub fn page(&self) -> Page {
        let subtitle = match &self.profile {
            Some(p) => {
                let (s0, s1) = p.skid_range();
                format!(
                    "Track `{}`: {} knots over skid {s0} .. {s1} mm.",
                    p.name(),
                    p.knots().len()
                )
            }
            None => "Track measurements.".to_owned(),
        };
        Page {
            title: match &self.profile {
                Some(p) => format!("trackfix track report: {}", p.name()),
                None => "trackfix track report".to_owned(),
            },
            subtitle,
            sections: self.sections(),
        }
    }

    fn inputs_section(&self) -> Section {
        let mut sec = Section::new("inputs", headings::INPUTS);
        let rows: Vec<Row> = self
            .sources
            .iter()
            .map(|(what, src)| {
                Row::new(vec![
                    Cell::text(what.clone()),
                    Cell::code(src.path.clone()),
                    Cell::code(src.sha256.clone()),
                ])
            })
            .collect();
        sec.raw(&table(&["input", "file", "sha256"], &rows));
        for (what, how) in &self.derived {
            sec.para(&format!("{what}: {how}."));
        }
        if let Some(p) = &self.profile {
            let stored = p.source_sha256();
            if !stored.is_empty() {
                sec.para(&format!(
                    "The profile records the sha256 of the frames it was fitted from: {stored}."
                ));
            }
        }
        sec
    }
}

/// The text clap shows for a value (`regression`, `as-is`).
fn enum_text<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_value(v)
        .ok()
        .and_then(|j| j.as_str().map(str::to_owned))
        .unwrap_or_default()
}

/// Builds the track report page from its inputs.
pub fn track_report(inputs: TrackInputs) -> Result<String, ReportError> {
    Ok(TrackReport::compute(inputs)?.render())
}

/// Standard uncertainties `u_dx … u_rz` per knot, when every knot of the profile carries all
/// six (read from the profile's own TOML, so any profile that stores them shows its band).
pub fn knot_uncertainty(profile: &Profile) -> Option<Vec<[f64; 6]>> {
    let text = profile.to_toml_string().ok()?;
    knot_uncertainty_in(&text)
}

/// [`knot_uncertainty`] of profile text: the `u_*` keys of every `[[knot]]`.
pub fn knot_uncertainty_in(profile_toml: &str) -> Option<Vec<[f64; 6]>> {
    let doc: toml::Table = toml::from_str(profile_toml).ok()?;
    let knots = doc.get("knot")?.as_array()?;
    if knots.is_empty() {
        return None;
    }
    knots
        .iter()
        .map(|k| {
            let t = k.as_table()?;
            let mut u = [0.0; 6];
            for (slot, name) in u.iter_mut().zip(COMPONENTS) {
                let v = t.get(&format!("u_{name}"))?;
                *slot = v.as_float().or_else(|| v.as_integer().map(|i| i as f64))?;
            }
            Some(u)
        })
        .collect()
}

fn controller_section(p: &Profile, fit: Option<&TrackFit>) -> Section {
    let mut f = match fit {
        Some(fit) => ControllerFigures::from_fit(fit),
        None => ControllerFigures::from_profile(p),
    };
    // A fit from the measurements states no frame; the profile given with them may.
    f.measured_in = f.measured_in.or(p.measured_in());
    let mut sec = Section::new("controller", headings::CONTROLLER);
    sec.para(&format!(
        "Measurement frame: {}. The same figures track fit prints.",
        super::figures::frame_name(f.measured_in)
    ));
    sec.raw(&definitions(&[
        ("gear factor", f.gear_text()),
        ("", f.new_gear_text()),
        ("track direction (measurement frame)", f.direction_text()),
        (
            "track direction (base at skid 0)",
            f.direction_in_base_text(),
        ),
        ("base frame at skid 0", f.base_text()),
        ("ABB (pose)", f.abb_literal()),
        ("KUKA (FRAME)", f.kuka_literal()),
    ]));
    if let Some(fit) = fit {
        sec.sub("Origins against the skid (least squares, docs/design.md §3; thesis eq. 4.54)");
        let rows: Vec<Row> = ["x", "y", "z"]
            .iter()
            .zip(&fit.lines)
            .map(|(name, l)| {
                let n = l.residuals.len().max(1) as f64;
                let rms = (l.residuals.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
                let max = l.residuals.iter().map(|r| r.abs()).fold(0.0, f64::max);
                Row::new(vec![
                    Cell::text(*name),
                    Cell::num(format!("{:.8}", l.slope)),
                    Cell::num(format!("{:.4}", l.intercept)),
                    Cell::num(format!("{rms:.4}")),
                    Cell::num(format!("{max:.4}")),
                ])
            })
            .collect();
        sec.raw(&table(
            &[
                "axis",
                "slope",
                "intercept [mm]",
                "residual rms [mm]",
                "max |residual| [mm]",
            ],
            &rows,
        ));
    }
    if let Some(st) = p.stats() {
        sec.sub("Deviation from the nominal");
        sec.raw(&definitions(&[
            (
                "position",
                format!(
                    "rms {:.4} mm, max {:.4} mm",
                    st.position_rms_mm, st.position_max_mm
                ),
            ),
            ("rotation", format!("max {:.4} deg", st.rotation_max_deg)),
            (
                "straightness (peak-to-peak)",
                format!(
                    "sideways {:.4} mm, vertical {:.4} mm",
                    st.straightness_sideways_mm, st.straightness_vertical_mm
                ),
            ),
            (
                "twist about the track",
                format!("{:.4} deg peak-to-peak", st.twist_deg),
            ),
        ]));
    }
    sec.para_class(
        "note",
        &format!(
            "Profile `{}`: reference {}, gear {}, extrapolate {}.",
            p.name(),
            enum_text(&p.reference()),
            enum_text(&p.gear()),
            enum_text(&p.extrapolate())
        ),
    );
    sec
}

/// A skid value as the files write it (`500`, `1250.5`).
fn skid_text(s: f64) -> String {
    format!("{s}")
}

fn identification_section(id: &Identification) -> Section {
    let mut sec = Section::new("identification", headings::IDENTIFICATION);
    let limit = OUTLIER_FACTOR * id.median_residual;
    let points: usize = id.fits.iter().map(|f| f.points.len()).sum();
    sec.para(&format!(
        "{} base frames from {points} points. Residual = tracker point - fitted base frame x robot point (docs/design.md §3; thesis Table 7.2). Median point residual {:.4} mm; outlier limit {OUTLIER_FACTOR} x median = {limit:.4} mm.",
        id.fits.len(),
        id.median_residual
    ));
    let is_outlier = |skid: f64, point: u32| {
        id.outliers
            .iter()
            .any(|o| o.skid.to_bits() == skid.to_bits() && o.point == point)
    };
    let groups = id.fits.len().max(1);
    let max_r = id
        .fits
        .iter()
        .flat_map(|f| f.fit.residual_norms())
        .fold(limit, f64::max);
    let label_every = groups.div_ceil(20);
    let cats: Vec<(f64, String)> = id
        .fits
        .iter()
        .enumerate()
        .filter(|(g, _)| g % label_every == 0)
        .map(|(g, f)| (g as f64 + 0.5, skid_text(f.skid)))
        .collect();
    let mut ch = Chart::new(
        1040.0,
        320.0,
        Span::new(0.0, groups as f64),
        Span::new(0.0, max_r * 1.12),
    )
    .title("Residual |r| per point, grouped by skid position")
    .labels("skid [mm] (one bar per point)", "|residual| [mm]")
    .x_categories(cats);
    for (g, f) in id.fits.iter().enumerate() {
        let n = f.points.len().max(1) as f64;
        let w = 0.8 / n;
        for (j, (p, r)) in f.points.iter().zip(f.fit.residual_norms()).enumerate() {
            let x0 = g as f64 + 0.1 + j as f64 * w;
            let outlier = is_outlier(f.skid, *p);
            let class = if outlier { "bar outlier" } else { "bar" };
            let tip = format!(
                "skid {} mm, point {p}: {r:.4} mm{}",
                skid_text(f.skid),
                if outlier { " (outlier)" } else { "" }
            );
            ch.bar(x0, x0 + 0.85 * w, r, class, &tip);
        }
    }
    ch.hline(
        limit,
        "limit",
        Some(&format!("outlier limit {limit:.4} mm")),
    );
    ch.hline(id.median_residual, "median", None);
    sec.figure(
        &ch.render(),
        &format!(
            "Bars: one per measured point; red: above {OUTLIER_FACTOR} x the median residual (dashed red line); dotted: the median."
        ),
    );
    sec.sub("Per skid position");
    let rows: Vec<Row> = id
        .fits
        .iter()
        .map(|f| {
            let norms = f.fit.residual_norms();
            let max = norms.iter().copied().fold(0.0, f64::max);
            let out = id
                .outliers
                .iter()
                .filter(|o| o.skid.to_bits() == f.skid.to_bits())
                .count();
            let row = Row::new(vec![
                Cell::num(skid_text(f.skid)),
                Cell::num(f.points.len().to_string()),
                Cell::num(format!("{:.4}", f.fit.rms)),
                Cell::num(format!("{max:.4}")),
                Cell::num(out.to_string()),
            ]);
            if out > 0 {
                row.with_class("outlier")
            } else {
                row
            }
        })
        .collect();
    sec.raw(&table(
        &["skid [mm]", "points", "rms [mm]", "max [mm]", "outliers"],
        &rows,
    ));
    sec.sub("Outliers");
    if id.outliers.is_empty() {
        sec.para("None: every point lies within the limit.");
    } else {
        let rows: Vec<Row> = id
            .outliers
            .iter()
            .map(|o| {
                Row::new(vec![
                    Cell::num(skid_text(o.skid)),
                    Cell::num(o.point.to_string()),
                    Cell::num(format!("{:.4}", o.residual)),
                    Cell::num(format!("{:.1}", o.ratio)),
                    Cell::text("remeasure or remove the row"),
                ])
                .with_class("outlier")
            })
            .collect();
        sec.raw(&table(
            &[
                "skid [mm]",
                "point",
                "|residual| [mm]",
                "x median",
                "what to do",
            ],
            &rows,
        ));
    }
    sec
}

/// Linear interpolation of per-knot values at `s` (clamped to the ends).
fn interpolate(knots: &[f64], values: &[f64], s: f64) -> f64 {
    let (Some(&first), Some(&last)) = (knots.first(), knots.last()) else {
        return 0.0;
    };
    if s <= first {
        return values.first().copied().unwrap_or(0.0);
    }
    if s >= last {
        return values.last().copied().unwrap_or(0.0);
    }
    let i = knots.partition_point(|k| *k <= s).saturating_sub(1);
    let (Some(&x0), Some(&x1), Some(&y0), Some(&y1)) = (
        knots.get(i),
        knots.get(i + 1),
        values.get(i),
        values.get(i + 1),
    ) else {
        return values.last().copied().unwrap_or(0.0);
    };
    if x1 > x0 {
        y0 + (y1 - y0) * (s - x0) / (x1 - x0)
    } else {
        y0
    }
}

const CURVE_SAMPLES: usize = 240;

/// Six charts of `D(s)`: the spline, its knots and, when the profile carries them, a band of
/// ± one standard uncertainty (linear between the knots).
pub fn deviation_section(p: &Profile, uncertainty: Option<&[[f64; 6]]>) -> Section {
    let mut sec = Section::new("deviation", headings::DEVIATION);
    // One uncertainty per knot, or none at all.
    let uncertainty = uncertainty.filter(|u| u.len() == p.knots().len());
    let (s0, s1) = p.skid_range();
    sec.para(&format!(
        "D(s): deviation of the real base from the nominal straight track, in the nominal base frame (R = Rz*Ry*Rx). Line: natural cubic spline; dots: the {} knots.",
        p.knots().len()
    ));
    let xs: Vec<f64> = (0..=CURVE_SAMPLES)
        .map(|i| s0 + (s1 - s0) * i as f64 / CURVE_SAMPLES as f64)
        .collect();
    let knot_skids: Vec<f64> = p.knots().iter().map(|k| k.skid).collect();
    sec.raw("<div class=\"grid\">");
    for (c, spline) in p.splines().iter().enumerate() {
        let curve: Vec<(f64, f64)> = xs.iter().map(|&x| (x, spline.value(x))).collect();
        let u: Option<Vec<f64>> =
            uncertainty.map(|u| u.iter().map(|k| k.get(c).copied().unwrap_or(0.0)).collect());
        let band = u.as_ref().map(|u| {
            let lower: Vec<(f64, f64)> = curve
                .iter()
                .map(|&(x, y)| (x, y - interpolate(&knot_skids, u, x)))
                .collect();
            let upper: Vec<(f64, f64)> = curve
                .iter()
                .map(|&(x, y)| (x, y + interpolate(&knot_skids, u, x)))
                .collect();
            (lower, upper)
        });
        let mut ys: Vec<f64> = curve.iter().map(|p| p.1).collect();
        if let Some((lo, hi)) = &band {
            ys.extend(lo.iter().chain(hi).map(|p| p.1));
        }
        let (name, unit) = (COMPONENTS[c], UNITS[c]);
        let mut ch = Chart::new(520.0, 250.0, Span::new(s0, s1), Span::padded(ys))
            .title(&format!("{name} [{unit}]"))
            .labels("skid [mm]", &format!("{name} [{unit}]"));
        if let Some((lo, hi)) = &band {
            ch.band(lo, hi);
        }
        ch.polyline(&curve, "curve");
        let decimals = if c < 3 { 4 } else { 6 };
        for (x, y) in spline.knots().iter().zip(spline.values()) {
            ch.dot(
                *x,
                *y,
                3.5,
                "knot",
                Some(&format!(
                    "skid {} mm: {name} {} {unit}",
                    skid_text(*x),
                    fmt_fixed(*y, decimals)
                )),
            );
        }
        sec.raw(&ch.render());
    }
    sec.raw("</div>");
    if uncertainty.is_some() {
        sec.para_class(
            "note",
            "Shaded: plus/minus one standard uncertainty (k = 1) from the profile's u_* per knot, linear between the knots.",
        );
    } else {
        sec.para_class(
            "note",
            "The profile carries no uncertainties (u_* per knot): no band is drawn.",
        );
    }
    sec
}

/// `dx, dy, dz` to 4 decimals and `rx, ry, rz` to 6, as `track show` prints them.
fn six_cells(c: &[f64; 6]) -> Vec<Cell> {
    c.iter()
        .enumerate()
        .map(|(i, v)| Cell::num(fmt_fixed(*v, if i < 3 { 4 } else { 6 })))
        .collect()
}

const SIX_HEADERS: [&str; 6] = [
    "dx [mm]", "dy [mm]", "dz [mm]", "rx [deg]", "ry [deg]", "rz [deg]",
];

fn adjustment_section(p: &Profile) -> Section {
    let mut sec = Section::new("adjustment", headings::ADJUSTMENT);
    sec.para("Deviation of each knot component from its own regression line over skid (docs/design.md §3; thesis eq. 4.54): what the adjustment screws must take out; the line itself is for the controller.");
    let rows: Vec<Row> = manual_adjustment(p)
        .iter()
        .map(|r| {
            let mut cells = vec![Cell::num(skid_text(r.skid))];
            cells.extend(six_cells(&r.residual));
            Row::new(cells)
        })
        .collect();
    let mut headers = vec!["skid [mm]"];
    headers.extend(SIX_HEADERS);
    sec.raw(&table(&headers, &rows));
    let twist = twist_diagram(p);
    sec.sub("Twist diagram");
    let mut ch = Chart::new(
        620.0,
        520.0,
        Span::padded(twist.iter().map(|t| t.x)),
        Span::padded(twist.iter().map(|t| t.y)),
    )
    .title("Tip of a 1 m lever along +z of each knot, relative to the first")
    .labels("x [mm]", "y [mm]")
    .equal_scale();
    let pts: Vec<(f64, f64)> = twist.iter().map(|t| (t.x, t.y)).collect();
    ch.polyline(&pts, "curve");
    for (i, t) in twist.iter().enumerate() {
        ch.dot(
            t.x,
            t.y,
            3.5,
            "point",
            Some(&format!(
                "skid {} mm: x {:.4} mm, y {:.4} mm",
                skid_text(t.skid),
                t.x,
                t.y
            )),
        );
        // Neighbouring knots lie close: labels alternate above and below their dot.
        let dy = if i % 2 == 0 { -5.0 } else { 13.0 };
        ch.label(t.x, t.y, 5.0, dy, &skid_text(t.skid));
    }
    sec.figure(
        &ch.render(),
        &format!(
            "Equal scales on both axes; labels: skid [mm]. Only the rotation moves the tip: 0.1 deg shows as {:.2} mm.",
            TWIST_LEVER_MM * 0.1_f64.to_radians()
        ),
    );
    let rows: Vec<Row> = twist
        .iter()
        .map(|t| {
            Row::new(vec![
                Cell::num(skid_text(t.skid)),
                Cell::num(fmt_fixed(t.x, 4)),
                Cell::num(fmt_fixed(t.y, 4)),
            ])
        })
        .collect();
    sec.raw(&table(&["skid [mm]", "x [mm]", "y [mm]"], &rows));
    sec
}

fn bounds_section(p: &Profile) -> Section {
    let mut sec = Section::new("bounds", headings::BOUNDS);
    sec.para("Largest distance between the spline and the straight chord through the two knots of each interval (docs/design.md §3; thesis eqs. 4.9-4.12): how much a linear interpolation would miss.");
    let bounds = chord_bounds(p);
    let rows: Vec<Row> = bounds
        .iter()
        .map(|b| {
            let mut cells = vec![Cell::num(skid_text(b.from)), Cell::num(skid_text(b.to))];
            cells.extend(six_cells(&b.distance.map(|d| d.distance.abs())));
            Row::new(cells)
        })
        .collect();
    let mut headers = vec!["from [mm]", "to [mm]"];
    headers.extend(SIX_HEADERS);
    sec.raw(&table(&headers, &rows));
    sec
}

/// Indices of local maxima of the amplitude, largest first.
fn spectrum_section(spec: &Spectrum) -> Section {
    let mut sec = Section::new("spectrum", headings::SPECTRUM);
    let nyquist = spec.nyquist();
    sec.para(&format!(
        "{} samples, spacing {:.3} mm{}; straight-line fit removed; Tukey window (alpha {TUKEY_ALPHA}); frequency resolution {:.6} /mm, read {PADDING}× finer; Nyquist {:.6} /mm.",
        spec.samples,
        spec.spacing_mm,
        if spec.resampled {
            " (uneven: resampled linearly to uniform spacing)"
        } else {
            ""
        },
        spec.resolution(),
        nyquist
    ));
    match (spec.highest, spec.recommended_spacing_mm()) {
        (Some((f, a)), Some(spacing)) => {
            sec.raw(&definitions(&[
                (
                    "highest frequency above the threshold",
                    format!(
                        "{f:.6} /mm (wavelength {:.1} mm, amplitude {a:.4} mm > {} mm)",
                        1.0 / f,
                        spec.threshold_mm
                    ),
                ),
                (
                    "recommended sampling spacing",
                    format!("1/(2f) = {spacing:.1} mm (docs/design.md §3; thesis eq. 4.12)"),
                ),
            ]));
        }
        _ => {
            sec.para(&format!(
                "No frequency exceeds {} mm: the straight line describes the scan; sample as coarsely as the range allows.",
                spec.threshold_mm
            ));
        }
    }
    // Up to Nyquist the noise floor would squeeze what matters into a few pixels.
    let fmax = spec
        .highest
        .map_or(nyquist, |(f, _)| (10.0 * f).min(nyquist))
        .max(1e-12);
    let pts: Vec<(f64, f64)> = spec
        .frequency
        .iter()
        .zip(&spec.amplitude)
        .skip(1)
        .take_while(|(f, _)| **f <= fmax * (1.0 + 1e-12))
        .map(|(f, a)| (*f, *a))
        .collect();
    let amax = pts
        .iter()
        .map(|p| p.1)
        .fold(spec.threshold_mm, f64::max)
        .max(1e-9);
    let mut ch = Chart::new(
        1040.0,
        360.0,
        Span::new(0.0, fmax),
        Span::new(0.0, amax * 1.12),
    )
    .title("Amplitude spectrum of the deviation from the straight line")
    .labels(
        &if fmax < nyquist {
            format!("spatial frequency [1/mm] (shown to {fmax:.6}; Nyquist {nyquist:.6})")
        } else {
            "spatial frequency [1/mm]".to_owned()
        },
        "amplitude [mm]",
    );
    ch.polyline(&pts, "curve");
    ch.hline(
        spec.threshold_mm,
        "limit",
        Some(&format!("threshold {} mm", spec.threshold_mm)),
    );
    if let (Some((f, a)), Some(spacing)) = (spec.highest, spec.recommended_spacing_mm()) {
        ch.vline(
            f,
            "marker",
            Some(&format!("{f:.6} /mm: sample every {spacing:.0} mm")),
        );
        ch.dot(f, a, 4.0, "knot", None);
    }
    sec.figure(
        &ch.render(),
        "Dashed: the threshold; vertical line: the highest frequency above it, which sets the spacing.",
    );
    sec.sub("Largest peaks");
    let rows: Vec<Row> = spec
        .peaks()
        .iter()
        .take(6)
        .filter_map(|&k| {
            let (f, a) = (spec.frequency.get(k)?, spec.amplitude.get(k)?);
            Some(Row::new(vec![
                Cell::num(format!("{f:.6}")),
                Cell::num(format!("{:.1}", 1.0 / f)),
                Cell::num(format!("{a:.4}")),
            ]))
        })
        .collect();
    sec.raw(&table(
        &["f [1/mm]", "wavelength [mm]", "amplitude [mm]"],
        &rows,
    ));
    sec
}

/// ISO 9283 results (pose accuracy, repeatability, …) as given: tables and charts.
pub fn accuracy_section(results: &[AccuracyResult]) -> Section {
    let mut sec = Section::new("accuracy", headings::ACCURACY);
    sec.para("Accuracy and repeatability per ISO 9283, from laser-tracker measurements of commanded poses.");
    for r in results {
        for t in &r.tables {
            sec.raw(&t.to_html());
        }
        if let Some((svg, caption)) = &r.figure {
            sec.figure(svg, caption);
        }
    }
    sec
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncertainty_needs_all_six_on_every_knot() {
        let with = "[[knot]]\nskid = 0.0\nu_dx = 0.01\nu_dy = 0.02\nu_dz = 0.03\nu_rx = 1e-4\nu_ry = 2e-4\nu_rz = 3e-4\n\
                    [[knot]]\nskid = 1.0\nu_dx = 0.1\nu_dy = 0.2\nu_dz = 0.3\nu_rx = 1\nu_ry = 2\nu_rz = 3\n";
        let u = knot_uncertainty_in(with).unwrap();
        assert_eq!(u.len(), 2);
        assert_eq!(u[0], [0.01, 0.02, 0.03, 1e-4, 2e-4, 3e-4]);
        assert_eq!(u[1], [0.1, 0.2, 0.3, 1.0, 2.0, 3.0]);
        let partial = "[[knot]]\nskid = 0.0\nu_dx = 0.01\n";
        assert_eq!(knot_uncertainty_in(partial), None);
        assert_eq!(knot_uncertainty_in("name = \"x\"\n"), None);
    }

    #[test]
    fn interpolation_is_linear_between_knots_and_clamped_outside() {
        let k = [0.0, 10.0, 20.0];
        let v = [1.0, 3.0, 2.0];
        assert_eq!(interpolate(&k, &v, -5.0), 1.0);
        assert_eq!(interpolate(&k, &v, 5.0), 2.0);
        assert_eq!(interpolate(&k, &v, 15.0), 2.5);
        assert_eq!(interpolate(&k, &v, 25.0), 2.0);
    }

    #[test]
    fn data_table_escapes_and_aligns_numbers() {
        let t = DataTable {
            title: "Pose <1>".into(),
            columns: vec!["point".into(), "AP [mm]".into()],
            rows: vec![vec!["P&1".into(), "0.08".into()]],
            note: Some("n < 30".into()),
        };
        let h = t.to_html();
        assert!(h.contains("<h3>Pose &lt;1&gt;</h3>"));
        assert!(h.contains("<td>P&amp;1</td><td class=\"n\">0.08</td>"));
        assert!(h.contains("n &lt; 30"));
    }
}
