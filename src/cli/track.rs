//! `trackfix track identify | fit | show | spectrum` (the samples' simulator is
//! `examples/simulate_track.rs`).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use trackfix::geometry::{abb_pose_literal, kuka_frame_literal, pose_to_xyz_deg};
use trackfix::track::adjustment::{chord_bounds, manual_adjustment, twist_diagram};
use trackfix::track::cell_nominal::{check_cell_nominal, write_nominal_into_cell};
use trackfix::track::csv_table::NumericCsv;
use trackfix::track::frames_csv::{FRAMES_HEADER, clean, frames_csv, frames_from};
use trackfix::track::gear;
use trackfix::track::identify::{
    CONDITION_LIMIT, Exclusion, FrameShift, MEASUREMENTS_HEADER, OUTLIER_FACTOR,
    identify_excluding, measurements_from,
};
use trackfix::track::nominal::{FitOptions, TrackFit, fit_track};
use trackfix::track::plot::{profile_svg, spectrum_svg};
use trackfix::track::point_export::{ColumnMap, points_csv, read_point_export};
use trackfix::track::spectrum::{PADDING, TUKEY_ALPHA, scan_from_table, scan_spectrum};
use trackfix::track::uncertainty::{ProfileUncertainty, Sigma, knot_uncertainties};
use trackfix::track::{
    Extrapolate, Gear, Knot, LocatedError, MeasuredIn, Profile, Reference, TrackError,
};
use trackfix::transform::{Cell, CellError};

use super::Exit;

#[derive(clap::Subcommand)]
pub(crate) enum TrackCommand {
    /// Identify the robot base frame at each skid position from laser-tracker points.
    Identify(IdentifyArgs),
    /// Fit the nominal straight track, gear factor and deviation splines: frames.csv → profile.toml.
    Fit(FitArgs),
    /// Evaluate a profile, or show its adjustment table, twist diagram and error bounds.
    Show(ShowArgs),
    /// Recommend a sampling spacing from a continuous scan along the track.
    Spectrum(SpectrumArgs),
    /// Read a laser tracker's point export (name x y z; `;`, tab, space or `,`) into point,x,y,z CSV.
    Import(ImportArgs),
}

const IDENTIFY_EXAMPLES: &str = "\
Examples:
  trackfix track identify samples/track/measurements.csv -o frames.csv

measurements.csv has one row per tracker point: skid,point,robot_x,robot_y,robot_z,meas_x,
meas_y,meas_z (the TCP point in the robot base and the tracker's reading of it, mm). At least 3
non-collinear points per skid position (rotation condition number at most 20), tracker and
robot points in the same units. Outliers are judged against a robust fit, so one bad reading
is the one point flagged; leave it out with --exclude SKID:POINT. A `;`-separated file with
decimal commas (a spreadsheet export) is read too.";

const FIT_EXAMPLES: &str = "\
Examples:
  trackfix track fit frames.csv -o profile.toml --name r1
  trackfix track fit frames.csv -o profile.toml --gear recalibrated --extrapolate clamp

Prints what to enter in the controller: the gear factor correction, the track direction and
the base frame at skid 0.";

const SHOW_EXAMPLES: &str = "\
Examples:
  trackfix track show samples/track/profile.toml
  trackfix track show samples/track/profile.toml --at 0 --at 250 --at 4000
  trackfix track show samples/track/profile.toml --step 500 --format csv
  trackfix track show samples/track/profile.toml --plot profile.svg
  trackfix track show samples/frames/profile.toml --step 1000 --tcp 1500,300,900";

const SPECTRUM_EXAMPLES: &str = "\
Examples:
  trackfix track spectrum samples/track/scan.csv --threshold 0.05 --plot spectrum.svg
  trackfix track spectrum timed_scan.csv --speed 100 --threshold 0.05

Recommends the sampling spacing 1/(2f) for the highest frequency above the threshold.";

#[derive(clap::Args)]
#[command(after_help = IDENTIFY_EXAMPLES)]
pub(crate) struct IdentifyArgs {
    /// measurements.csv: skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z
    pub measurements: PathBuf,
    /// Where to write frames.csv (skid,x,y,z,rx,ry,rz).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Leave out a bad reading: SKID:POINT as in the file, e.g. 1500:3 (repeatable). Prints how
    /// far the frame moved.
    #[arg(long, value_name = "SKID:POINT")]
    pub exclude: Vec<Exclusion>,
}

#[derive(clap::Args)]
#[command(after_help = FIT_EXAMPLES)]
pub(crate) struct FitArgs {
    /// frames.csv: skid,x,y,z,rx,ry,rz in increasing skid order.
    pub frames: PathBuf,
    /// Where to write profile.toml.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The straight line the deviations are taken from.
    #[arg(long, value_enum, default_value = "regression")]
    pub reference: Reference,
    /// Keep the controller's gear factor (its drift goes into the profile) or enter the new one.
    #[arg(long, value_enum, default_value = "as-is")]
    pub gear: Gear,
    /// What D(s) does outside the measured skid range.
    #[arg(long, value_enum, default_value = "error")]
    pub extrapolate: Extrapolate,
    /// Profile name (default: the output file's stem, or its folder's name for profile.toml).
    #[arg(long)]
    pub name: Option<String>,
    /// The controller's current gear ratio, to print the new one: ABB's Transmission Gear
    /// Ratio as a number, or KUKA's $RAT_MOT_AX as N/D (e.g. 47746/1000).
    #[arg(long, value_name = "X")]
    pub current_gear: Option<String>,
    /// The frame the tracker measured in: `world` when it was aligned to the cell, so the
    /// profile's nominal can be checked against (and written into) the cell file.
    #[arg(long, value_enum)]
    pub measured_in: Option<MeasuredIn>,
    /// Write the fitted nominal (base at skid 0 and track axis) into this cell file's
    /// [robot.NAME] (needs --robot; implies --measured-in world). Only those two values change.
    #[arg(long, value_name = "CELL.toml", requires = "robot")]
    pub cell: Option<PathBuf>,
    /// The robot of --cell.
    #[arg(long, value_name = "NAME", requires = "cell")]
    pub robot: Option<String>,
    /// The measurements.csv the frames were identified from: gives each knot its standard
    /// uncertainties (u_dx ... u_rz), which `track show` carries to every skid.
    #[arg(long, value_name = "measurements.csv")]
    pub measurements: Option<PathBuf>,
    /// Noise per axis of a measured point, mm (tracker and robot); default: from the
    /// identification residuals. Needs --measurements.
    #[arg(long, value_name = "MM", requires = "measurements")]
    pub sigma: Option<f64>,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ShowFormat {
    Table,
    Json,
    Csv,
}

#[derive(clap::Args)]
#[command(after_help = SHOW_EXAMPLES)]
pub(crate) struct ShowArgs {
    /// profile.toml
    pub profile: PathBuf,
    /// Skid positions to evaluate D(s) at, in mm (repeatable, kept in order).
    #[arg(long = "at", value_name = "S", allow_negative_numbers = true)]
    pub at: Vec<f64>,
    /// Evaluate every MM over the profile's range.
    #[arg(
        long,
        value_name = "MM",
        conflicts_with = "at",
        allow_negative_numbers = true
    )]
    pub step: Option<f64>,
    /// Output format of the evaluated values.
    #[arg(long, value_enum, default_value = "table")]
    pub format: ShowFormat,
    /// Also write an SVG: the six deviation curves with their knots, and the twist diagram.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Also give, at each skid, the expanded uncertainty (k = 2) of a corrected TCP at X,Y,Z
    /// (robot base frame, mm). Needs a profile fitted with --measurements.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz, allow_hyphen_values = true)]
    pub tcp: Option<[f64; 3]>,
}

/// `X,Y,Z` in mm.
fn parse_xyz(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let values: Vec<f64> = parts
        .iter()
        .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{text}`: write three numbers in mm, e.g. 1500,300,900"))?;
    match values[..] {
        [x, y, z] => Ok([x, y, z]),
        _ => Err(format!(
            "`{text}`: write three numbers in mm, e.g. 1500,300,900"
        )),
    }
}

/// A `show --format json` row: the knot's keys, then the TCP's uncertainty if asked.
#[derive(serde::Serialize)]
struct ShowRow {
    #[serde(flatten)]
    knot: Knot,
    #[serde(skip_serializing_if = "Option::is_none")]
    tcp_u: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tcp_expanded: Option<f64>,
}

const IMPORT_EXAMPLES: &str = "\
Examples:
  trackfix track import marks.txt -o marks.csv
  trackfix track import export.csv --map name=Punkt,x=Ost,y=Nord,z=Hoehe -o marks.csv
  trackfix track import export.txt --map name=2,x=4,y=5,z=6 -o marks.csv

Reads one named point per line, with or without a header line, fields separated by `;`, tabs,
spaces or `,` (decimal commas where `,` is not the separator). Without --map the columns are
found from the header (name/point/id, x, y, z) or are the first four. Says how it read the file.";

#[derive(clap::Args)]
#[command(after_help = IMPORT_EXAMPLES)]
pub(crate) struct ImportArgs {
    /// The tracker software's CSV/TXT point export.
    pub export: PathBuf,
    /// Which columns hold name, x, y, z: by position (name=1,x=2,y=3,z=4) or header name.
    #[arg(long, value_name = "name=C,x=C,y=C,z=C")]
    pub map: Option<ColumnMap>,
    /// Where to write point,x,y,z CSV (mm).
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(clap::Args)]
#[command(after_help = SPECTRUM_EXAMPLES)]
pub(crate) struct SpectrumArgs {
    /// scan.csv: skid,x,y,z (or t,x,y,z with --speed).
    pub scan: PathBuf,
    /// Amplitude threshold in mm: frequencies above it must be sampled.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub threshold: f64,
    /// Skid speed in mm/s, for a scan timed in seconds (t,x,y,z).
    #[arg(long, value_name = "MM_PER_S", allow_negative_numbers = true)]
    pub speed: Option<f64>,
    /// Also write the amplitude spectrum as SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
}

pub(crate) fn run(cmd: TrackCommand) -> anyhow::Result<Exit> {
    report_located(run_command(cmd))
}

/// The text of an error that already says `file:line:col: error: …` with the line and a hint.
fn located_text(e: &(dyn std::error::Error + 'static)) -> Option<String> {
    if let Some(located) = e.downcast_ref::<TrackError>().and_then(TrackError::located) {
        return Some(located.to_string());
    }
    if let Some(located) = e.downcast_ref::<LocatedError>() {
        return Some(located.to_string());
    }
    match e.downcast_ref::<CellError>() {
        Some(CellError::Invalid(located)) => Some(located.to_string()),
        _ => None,
    }
}

/// How a table was read when it was not plain CSV, on standard error.
pub(crate) fn print_notes(table: &NumericCsv) {
    for note in &table.notes {
        let _ = writeln!(std::io::stderr(), "note: {note}");
    }
}

/// Prints an error that carries its own location as it is (not behind another `error:`),
/// with what the command was doing as a note, and exits 2; other errors pass through.
pub(crate) fn report_located(result: anyhow::Result<Exit>) -> anyhow::Result<Exit> {
    let Err(err) = result else { return result };
    let Some(text) = err.chain().find_map(located_text) else {
        return Err(err);
    };
    let mut out = text;
    for context in err.chain().take_while(|c| located_text(*c).is_none()) {
        out.push_str(&format!("\n  = note: {context}"));
    }
    let _ = writeln!(std::io::stderr(), "{out}");
    Ok(Exit::Usage)
}

fn run_command(cmd: TrackCommand) -> anyhow::Result<Exit> {
    let text = match cmd {
        TrackCommand::Identify(a) => run_identify(&a)?,
        TrackCommand::Fit(a) => run_fit(&a)?,
        TrackCommand::Show(a) => run_show(&a)?,
        TrackCommand::Spectrum(a) => run_spectrum(&a)?,
        TrackCommand::Import(a) => run_import(&a)?,
    };
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(Exit::Ok)
}

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    trackfix::output::write_file(path, text.as_bytes())?;
    Ok(())
}

fn run_identify(a: &IdentifyArgs) -> anyhow::Result<String> {
    let table = NumericCsv::read(&a.measurements, &MEASUREMENTS_HEADER)?;
    print_notes(&table);
    let rows = measurements_from(&table)?;
    let id = identify_excluding(&rows, &a.exclude)
        .with_context(|| a.measurements.display().to_string())?;
    write_file(&a.output, &frames_csv(&id.frames()))?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "identified {} base frame(s) from {} point(s) in {} -> {}",
        id.fits.len(),
        rows.len(),
        a.measurements.display(),
        a.output.display()
    );
    let _ = writeln!(
        s,
        "residual = tracker point - fitted base frame * robot point (docs/design.md §3; thesis Table 7.2)"
    );
    for f in &id.fits {
        let _ = writeln!(
            s,
            "\nskid {} mm: {} points, rms {:.4} mm, condition {:.1}",
            f.skid,
            f.points.len(),
            f.fit.rms,
            f.fit.condition
        );
        let _ = writeln!(s, "  point    dx [mm]    dy [mm]    dz [mm]   rms [mm]");
        for (p, r) in f.points.iter().zip(&f.fit.residuals) {
            let _ = writeln!(
                s,
                "  {:>5} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
                p,
                clean(r.x, 4),
                clean(r.y, 4),
                clean(r.z, 4),
                r.norm()
            );
        }
    }
    let _ = writeln!(s, "\nrms per skid:");
    let _ = writeln!(s, "      skid   rms [mm]   max [mm]");
    for f in &id.fits {
        let max = f.fit.residual_norms().into_iter().fold(0.0, f64::max);
        let _ = writeln!(s, "  {:>8} {:>10.4} {:>10.4}", f.skid, f.fit.rms, max);
    }
    let worst = id.fits.iter().map(|f| f.fit.condition).fold(0.0, f64::max);
    let _ = writeln!(
        s,
        "\nlargest condition number {worst:.1} (limit {CONDITION_LIMIT}: points near a line leave the rotation about it free)"
    );
    for f in id.fits.iter().filter(|f| !f.excluded.is_empty()) {
        let pts: Vec<String> = f.excluded.iter().map(|p| p.to_string()).collect();
        let _ = writeln!(
            s,
            "\nexcluded at skid {} mm: point(s) {}",
            f.skid,
            pts.join(", ")
        );
        if let Some(shift) = &f.exclusion_shift {
            let _ = writeln!(s, "  effect on the frame: {}", shift_text(shift));
        }
    }
    let limit = OUTLIER_FACTOR * id.median_residual;
    let _ = write!(
        s,
        "\nmedian point residual {:.4} mm (robust fit); outliers (> {OUTLIER_FACTOR} x median = {limit:.4} mm): ",
        id.median_residual
    );
    if id.outliers.is_empty() {
        let _ = writeln!(s, "none");
    } else {
        let _ = writeln!(s, "{}", id.outliers.len());
        for o in &id.outliers {
            let _ = writeln!(
                s,
                "  skid {} mm, point {}: {:.4} mm ({:.1} x median) - remeasure it, or leave it out with --exclude {}:{}",
                o.skid, o.point, o.residual, o.ratio, o.skid, o.point
            );
            if let Some(shift) = &o.shift_if_excluded {
                let _ = writeln!(
                    s,
                    "    leaving it out would move the frame: {}",
                    shift_text(shift)
                );
            }
        }
    }
    Ok(s)
}

fn shift_text(shift: &FrameShift) -> String {
    format!(
        "{:.4} mm at the measured points (origin {:.4} mm, rotation {:.5} deg)",
        shift.at_points_mm, shift.origin_mm, shift.rotation_deg
    )
}

fn default_name(output: &Path) -> String {
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    if stem == "profile"
        && let Some(dir) = output
            .parent()
            .and_then(|p| p.file_name())
            .and_then(|s| s.to_str())
    {
        return dir.to_string();
    }
    if stem.is_empty() {
        "track".to_string()
    } else {
        stem.to_string()
    }
}

fn run_fit(a: &FitArgs) -> anyhow::Result<String> {
    let bytes =
        trackfix::output::read_input(&a.frames).with_context(|| a.frames.display().to_string())?;
    let table = NumericCsv::read(&a.frames, &FRAMES_HEADER)?;
    print_notes(&table);
    let frames = frames_from(&table)?;
    let opts = FitOptions {
        name: a.name.clone().unwrap_or_else(|| default_name(&a.output)),
        reference: a.reference,
        gear: a.gear,
        extrapolate: a.extrapolate,
        source_sha256: trackfix::digest::sha256_hex(&bytes),
    };
    let mut fit = fit_track(&frames, &opts).with_context(|| a.frames.display().to_string())?;
    let measured_in = match (a.measured_in, &a.cell) {
        (Some(MeasuredIn::Tracker), Some(_)) => anyhow::bail!(
            "--cell writes the nominal as the cell's world frame: the frames must be measured in it (--measured-in world)"
        ),
        (None, Some(_)) => Some(MeasuredIn::World),
        (m, _) => m,
    };
    if let Some(m) = measured_in {
        fit.profile = fit.profile.with_measured_in(m);
    }
    let mut noise_note = None;
    if let Some(path) = &a.measurements {
        let table = NumericCsv::read(path, &MEASUREMENTS_HEADER)?;
        print_notes(&table);
        let rows = measurements_from(&table)?;
        let id = identify_excluding(&rows, &[]).with_context(|| path.display().to_string())?;
        let same = id.fits.len() == frames.len()
            && id.fits.iter().zip(&frames).all(|(f, g)| {
                // frames.csv keeps 4 decimals of mm and 6 of degrees.
                (f.skid - g.skid).abs() <= 1e-6 * (1.0 + g.skid.abs())
                    && (f.fit.pose.translation.vector - g.pose.translation.vector).norm() < 1e-3
                    && f.fit.pose.rotation.angle_to(&g.pose.rotation) < 1e-6
            });
        if !same {
            anyhow::bail!(
                "{}: its base frames are not those of {}: pass the measurements the frames were identified from (`trackfix track identify` of them gives the frames)",
                path.display(),
                a.frames.display()
            );
        }
        let (u, sigma) =
            knot_uncertainties(&rows, &id, a.sigma).with_context(|| path.display().to_string())?;
        noise_note = Some(match sigma {
            Sigma::Given(v) => format!("{v:.4} mm per axis (given)"),
            Sigma::Estimated { sigma, dof } => {
                format!("{sigma:.4} mm per axis (from the residuals, {dof} degrees of freedom)")
            }
        });
        fit.profile = fit.profile.with_knot_uncertainties(&u)?;
    }
    let p = &fit.profile;
    for w in p.measurement_warnings() {
        let _ = writeln!(std::io::stderr(), "warning: {}: {w}", a.frames.display());
    }
    p.save(&a.output)?;
    let cell_note = match (&a.cell, &a.robot) {
        (Some(cell), Some(robot)) => Some(write_cell_nominal(cell, robot, &fit)?),
        _ => None,
    };
    let (s0, s1) = p.skid_range();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "profile `{}`: {} knots, skid {s0} .. {s1} mm -> {}",
        p.name(),
        p.knots().len(),
        a.output.display()
    );
    let _ = writeln!(
        s,
        "reference {}, gear {}, extrapolate {}",
        enum_name(a.reference),
        enum_name(a.gear),
        enum_name(a.extrapolate)
    );
    if let Some(note) = &noise_note {
        let _ = writeln!(
            s,
            "knot uncertainties from the identification noise: {note}"
        );
    }
    let _ = writeln!(
        s,
        "\nenter in the controller (measurement frame: {}):",
        trackfix::html_report::figures::frame_name(fit.profile.measured_in())
    );
    let _ = writeln!(
        s,
        "  gear factor: the skid moves {:.6} mm per commanded mm ({:+.3} mm over {} mm)",
        fit.gear_factor,
        (fit.gear_factor - 1.0) * (s1 - s0),
        s1 - s0
    );
    gear_advice(&mut s, fit.gear_factor, a.current_gear.as_deref())?;
    let _ = writeln!(
        s,
        "    {}",
        match a.gear {
            Gear::AsIs => "with --gear as-is the profile keeps the drift instead",
            Gear::Recalibrated => "the profile assumes you enter the new ratio",
        }
    );
    let u = fit.direction;
    let ub = fit.direction_in_base();
    let _ = writeln!(
        s,
        "  track direction: [{:.6}, {:.6}, {:.6}] (in the base frame at skid 0: [{:.6}, {:.6}, {:.6}])",
        clean(u.x, 6),
        clean(u.y, 6),
        clean(u.z, 6),
        clean(ub.x, 6),
        clean(ub.y, 6),
        clean(ub.z, 6)
    );
    let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(&fit.base_at_zero);
    let _ = writeln!(
        s,
        "  base frame at skid 0: x {x:.3} y {y:.3} z {z:.3} mm, rx {rx:.4} ry {ry:.4} rz {rz:.4} deg"
    );
    let _ = writeln!(
        s,
        "    ABB {}   KUKA {}",
        abb_pose_literal(&fit.base_at_zero),
        kuka_frame_literal(&fit.base_at_zero)
    );
    let _ = writeln!(
        s,
        "\norigins against the skid (least squares, docs/design.md §3; thesis eq. 4.54):"
    );
    let _ = writeln!(
        s,
        "  axis        slope   intercept [mm]   residual rms [mm]   max |residual| [mm]"
    );
    for (name, l) in ["x", "y", "z"].iter().zip(&fit.lines) {
        let n = l.residuals.len().max(1) as f64;
        let rms = (l.residuals.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
        let max = l.residuals.iter().map(|r| r.abs()).fold(0.0, f64::max);
        let _ = writeln!(
            s,
            "  {name:>4} {:>12.8} {:>16.4} {:>19.4} {:>21.4}",
            l.slope, l.intercept, rms, max
        );
    }
    if let Some(note) = cell_note {
        let _ = writeln!(s, "\n{note}");
    }
    if let Some(st) = p.stats() {
        let _ = writeln!(s, "\ndeviation from the nominal:");
        let _ = writeln!(
            s,
            "  position rms {:.4} mm, max {:.4} mm; rotation max {:.4} deg",
            st.position_rms_mm, st.position_max_mm, st.rotation_max_deg
        );
        let _ = writeln!(
            s,
            "  straightness (peak-to-peak about a line): sideways {:.4} mm, vertical {:.4} mm; twist about the track {:.4} deg peak-to-peak",
            st.straightness_sideways_mm, st.straightness_vertical_mm, st.twist_deg
        );
    }
    Ok(s)
}

/// Writes the fitted nominal into `[robot.<robot>]` of the cell file (a lossless edit of the two
/// values), checks it back through the cell loader, and says what changed.
fn write_cell_nominal(cell: &Path, robot: &str, fit: &TrackFit) -> anyhow::Result<String> {
    let text = std::fs::read_to_string(cell).with_context(|| cell.display().to_string())?;
    let new = write_nominal_into_cell(&text, robot, &fit.base_at_zero, &fit.direction)
        .with_context(|| cell.display().to_string())?;
    // Checked before it replaces the file: the loader must accept it and agree with the profile.
    let loaded = Cell::parse(cell, &new)?;
    let r = loaded.robot(robot)?;
    check_cell_nominal(&r.base0, &r.track_axis, &fit.profile)
        .with_context(|| format!("{}: the written nominal", cell.display()))?;
    trackfix::output::replace_file(cell, new.as_bytes())?;
    let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(&fit.base_at_zero);
    let u = fit.direction;
    Ok(format!(
        "wrote the nominal into {} [robot.{robot}] (the rest of the file unchanged):\n  base = {{ x = {x:.4}, y = {y:.4}, z = {z:.4}, rx = {rx:.6}, ry = {ry:.6}, rz = {rz:.6} }}\n  track_axis = [{:.9}, {:.9}, {:.9}]",
        cell.display(),
        clean(u.x, 9),
        clean(u.y, 9),
        clean(u.z, 9)
    ))
}

/// The controller parameter that holds the gear ratio, which way it changes, and its new value
/// for `--current-gear` (trackfix::track::gear).
fn gear_advice(s: &mut String, g: f64, current: Option<&str>) -> anyhow::Result<()> {
    let [convention, abb, kuka, travel] = gear::advice(g);
    let _ = writeln!(s, "    {convention}");
    for line in [abb, kuka, travel] {
        let _ = writeln!(s, "      {line}");
    }
    let Some(text) = current else {
        return Ok(());
    };
    if text.contains('/') {
        let ratio = gear::parse_kuka_ratio(text).with_context(|| {
            format!("--current-gear {text}: write the KUKA ratio as N/D with integers, D not 0")
        })?;
        let new = gear::new_kuka_ratio(ratio, g).with_context(|| {
            format!("--current-gear {text}: the new ratio does not fit KUKA's INT range")
        })?;
        let _ = writeln!(
            s,
            "    for --current-gear {text} (KUKA {ratio}): $RAT_MOT_AX = {new} (= {:.9})",
            new.value()
        );
    } else {
        let current: f64 = text
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v != 0.0)
            .with_context(|| {
                format!(
                    "--current-gear {text}: give the current ratio as a number (ABB) or N/D (KUKA)"
                )
            })?;
        let _ = writeln!(
            s,
            "    for --current-gear {text}: new Transmission Gear Ratio {:.9}",
            gear::new_motor_ratio(current, g)
        );
    }
    Ok(())
}

fn enum_name(v: impl clap::ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

fn round6(v: f64) -> f64 {
    clean(v, 6)
}

/// `dx, dy, dz` to 4 decimals and `rx, ry, rz` to 6, right-aligned in `mm_width` and
/// `deg_width`, joined by `sep`.
fn deviation_cells(c: &[f64; 6], mm_width: usize, deg_width: usize, sep: &str) -> String {
    let mut cells = Vec::with_capacity(6);
    for (i, v) in c.iter().enumerate() {
        cells.push(if i < 3 {
            format!("{:>mm_width$.4}", clean(*v, 4))
        } else {
            format!("{:>deg_width$.6}", round6(*v))
        });
    }
    cells.join(sep)
}

fn run_show(a: &ShowArgs) -> anyhow::Result<String> {
    let p = Profile::load(&a.profile)?;
    for w in p
        .consistency_warnings()
        .into_iter()
        .chain(p.measurement_warnings())
    {
        let _ = writeln!(std::io::stderr(), "warning: {}: {w}", a.profile.display());
    }
    if let Some(path) = &a.plot {
        write_file(path, &profile_svg(&p)?)?;
        // On standard error: standard output may be the JSON or CSV asked for.
        let _ = writeln!(
            std::io::stderr(),
            "wrote {}: the six deviation curves of profile `{}` with their {} knots, and the twist diagram",
            path.display(),
            p.name(),
            p.knots().len()
        );
    }
    let (s0, s1) = p.skid_range();
    let skids: Vec<f64> = if let Some(step) = a.step {
        if step.is_nan() || step <= 0.0 {
            anyhow::bail!("--step {step}: give a positive step in mm");
        }
        let count = (s1 - s0) / step + 1e-9;
        if count > 1e6 {
            anyhow::bail!(
                "--step {step} gives {count:.0} rows over {s0} .. {s1} mm; use a larger step"
            );
        }
        let n = count.floor() as usize;
        let mut v: Vec<f64> = (0..=n).map(|i| s0 + i as f64 * step).collect();
        if v.last().is_some_and(|l| (s1 - l).abs() > 1e-9) {
            v.push(s1);
        }
        v
    } else {
        a.at.clone()
    };
    if skids.is_empty() {
        if a.format != ShowFormat::Table {
            anyhow::bail!(
                "--format {} needs --at or --step (the overview is a table)",
                enum_name(a.format)
            );
        }
        return Ok(overview(&p));
    }
    let pu = ProfileUncertainty::new(&p)?;
    let tcp = match (&a.tcp, &pu) {
        (Some(v), Some(_)) => Some(nalgebra::Vector3::new(v[0], v[1], v[2])),
        (Some(_), None) => anyhow::bail!(
            "{}: --tcp needs knot uncertainties, and this profile has none: fit it with `trackfix track fit FRAMES.csv --measurements MEASUREMENTS.csv`",
            a.profile.display()
        ),
        (None, _) => None,
    };
    let mut rows = Vec::with_capacity(skids.len());
    for &skid in &skids {
        let at = || format!("{}: --at {skid}", a.profile.display());
        let c = p.deviation_components(skid).with_context(at)?;
        let (u, t) = match &pu {
            Some(pu) => {
                let u = pu.at(skid).with_context(at)?.u;
                let t = match &tcp {
                    Some(r) => Some(pu.tcp_at(skid, r).with_context(at)?),
                    None => None,
                };
                (Some(u), t)
            }
            None => (None, None),
        };
        rows.push((skid, c, u, t));
    }
    let mut s = String::new();
    match a.format {
        ShowFormat::Json => {
            // Knot keeps the documented key order (a json! map would sort it).
            let arr: Vec<ShowRow> = rows
                .iter()
                .map(|(skid, c, u, t)| ShowRow {
                    knot: Knot::from_components(*skid, c.map(round6)).with_uncertainty(u.map(
                        |u| {
                            let mut r = [0.0; 6];
                            for (i, (slot, v)) in r.iter_mut().zip(u).enumerate() {
                                *slot = if i < 3 { clean(v, 4) } else { round6(v) };
                            }
                            r
                        },
                    )),
                    tcp_u: t.map(|t| t.u.map(|v| clean(v, 4))),
                    tcp_expanded: t.map(|t| clean(t.expanded, 4)),
                })
                .collect();
            s = serde_json::to_string_pretty(&arr)?;
            s.push('\n');
        }
        ShowFormat::Csv => {
            s.push_str("skid,dx,dy,dz,rx,ry,rz");
            if pu.is_some() {
                s.push_str(",u_dx,u_dy,u_dz,u_rx,u_ry,u_rz");
            }
            if tcp.is_some() {
                s.push_str(",tcp_u_x,tcp_u_y,tcp_u_z,tcp_expanded");
            }
            s.push('\n');
            for (skid, c, u, t) in &rows {
                let _ = write!(s, "{skid},{}", deviation_cells(c, 0, 0, ","));
                if let Some(u) = u {
                    let _ = write!(s, ",{}", deviation_cells(u, 0, 0, ","));
                }
                if let Some(t) = t {
                    let _ = write!(
                        s,
                        ",{:.4},{:.4},{:.4},{:.4}",
                        t.u[0], t.u[1], t.u[2], t.expanded
                    );
                }
                s.push('\n');
            }
        }
        ShowFormat::Table => {
            let _ = writeln!(
                s,
                "D(s) of profile `{}` (skid {s0} .. {s1} mm, extrapolate {})",
                p.name(),
                enum_name(p.extrapolate())
            );
            let _ = writeln!(
                s,
                "      skid    dx [mm]    dy [mm]    dz [mm]     rx [deg]     ry [deg]     rz [deg]"
            );
            // A row outside the measured skids is extrapolated (the profile allows it): marked,
            // since nothing there was measured and its u only carries the end slope's noise.
            let outside = |skid: f64| skid < s0 || skid > s1;
            for (skid, c, u, t) in &rows {
                let mark = if outside(*skid) { "*" } else { "" };
                let skid = format!("{skid}{mark}");
                let _ = writeln!(s, "{skid:>10} {}", deviation_cells(c, 10, 12, " "));
                if let Some(u) = u {
                    let _ = writeln!(s, "{:>10} {}", "u (k=1)", deviation_cells(u, 10, 12, " "));
                }
                if let Some(t) = t {
                    let _ = writeln!(
                        s,
                        "{:>10} U (k=2) {:.4} mm (u x {:.4} y {:.4} z {:.4} mm)",
                        "TCP", t.expanded, t.u[0], t.u[1], t.u[2]
                    );
                }
            }
            if pu.is_some() {
                let _ = writeln!(
                    s,
                    "u: standard uncertainty of D(s) from the knots' identification noise and the interpolation between knots"
                );
            }
            if rows.iter().any(|r| outside(r.0)) {
                let _ = writeln!(
                    s,
                    "*: outside the measured skids {s0} .. {s1} mm: extrapolated ({}), not measured; u there does not cover what the track does beyond its ends",
                    enum_name(p.extrapolate())
                );
            }
            if let Some(r) = &tcp {
                let _ = writeln!(
                    s,
                    "TCP: a corrected TCP at ({}, {}, {}) mm in the robot base; U = 2*sqrt(u_x^2 + u_y^2 + u_z^2)",
                    r.x, r.y, r.z
                );
            }
        }
    }
    Ok(s)
}

fn overview(p: &Profile) -> String {
    let (s0, s1) = p.skid_range();
    let n = p.nominal();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "profile `{}`: {} knots, skid {s0} .. {s1} mm, reference {}, gear {}, extrapolate {}",
        p.name(),
        p.knots().len(),
        enum_name(p.reference()),
        enum_name(p.gear()),
        enum_name(p.extrapolate())
    );
    let _ = writeln!(
        s,
        "nominal: origin [{:.3}, {:.3}, {:.3}] mm, direction [{:.6}, {:.6}, {:.6}], gear factor {:.6}",
        n.origin[0],
        n.origin[1],
        n.origin[2],
        clean(n.direction[0], 6),
        clean(n.direction[1], 6),
        clean(n.direction[2], 6),
        n.gear_factor
    );
    let header = "    dx [mm]    dy [mm]    dz [mm]     rx [deg]     ry [deg]     rz [deg]";
    let row6 = |c: &[f64; 6]| deviation_cells(c, 11, 13, "");
    let _ = writeln!(
        s,
        "\nmanual adjustment: deviation of each component from its own regression line (docs/design.md §3; thesis eq. 4.54)"
    );
    let _ = writeln!(s, "      skid{header}");
    for r in manual_adjustment(p) {
        let _ = writeln!(s, "{:>10}{}", r.skid, row6(&r.residual));
    }
    let _ = writeln!(
        s,
        "\ntwist diagram: tip of a 1 m lever along +z of each knot, x,y relative to the first (0.1 deg = 1.75 mm)"
    );
    let _ = writeln!(s, "      skid     x [mm]     y [mm]");
    for t in twist_diagram(p) {
        let _ = writeln!(
            s,
            "{:>10} {:>10.4} {:>10.4}",
            t.skid,
            clean(t.x, 4),
            clean(t.y, 4)
        );
    }
    let _ = writeln!(
        s,
        "\nlargest spline-to-chord distance per interval (docs/design.md §3; thesis eqs. 4.9-4.12)"
    );
    let _ = writeln!(s, "      from        to{header}");
    for b in chord_bounds(p) {
        let d = b.distance.map(|c| c.distance.abs());
        let _ = writeln!(s, "{:>10}{:>10}{}", b.from, b.to, row6(&d));
    }
    if let Ok(Some(pu)) = ProfileUncertainty::new(p) {
        let _ = writeln!(
            s,
            "\nlargest standard uncertainty (k=1) of D(s) per interval: knots' noise and interpolation"
        );
        let _ = writeln!(s, "      from        to{header}");
        for w in p.knots().windows(2) {
            let (a, b) = (w[0].skid, w[1].skid);
            let mut worst = [0.0f64; 6];
            // The interpolation part peaks mid-interval, the noise part at the knots.
            for i in 0..=16 {
                if let Ok(u) = pu.at(a + (b - a) * i as f64 / 16.0) {
                    for (m, v) in worst.iter_mut().zip(u.u) {
                        *m = m.max(v);
                    }
                }
            }
            let _ = writeln!(s, "{a:>10}{b:>10}{}", row6(&worst));
        }
    }
    s
}

fn run_import(a: &ImportArgs) -> anyhow::Result<String> {
    let export = read_point_export(&a.export, a.map.as_ref())?;
    write_file(&a.output, &points_csv(&export.points))?;
    let mut s = String::new();
    for note in &export.notes {
        let _ = writeln!(s, "{note}");
    }
    let _ = writeln!(
        s,
        "wrote {} point(s) to {}",
        export.points.len(),
        a.output.display()
    );
    Ok(s)
}

fn run_spectrum(a: &SpectrumArgs) -> anyhow::Result<String> {
    if a.threshold.is_nan() || a.threshold <= 0.0 {
        anyhow::bail!(
            "--threshold {}: give a positive amplitude in mm",
            a.threshold
        );
    }
    let (pos_col, scale) = match a.speed {
        Some(v) if v.is_nan() || v <= 0.0 => {
            anyhow::bail!("--speed {v}: give a positive speed in mm/s")
        }
        Some(v) => ("t", v),
        None => ("skid", 1.0),
    };
    let table = NumericCsv::read(&a.scan, &[pos_col, "x", "y", "z"])?;
    print_notes(&table);
    let (positions, points) = scan_from_table(&table, pos_col, scale)?;
    let spec = scan_spectrum(&positions, &points, a.threshold)
        .with_context(|| a.scan.display().to_string())?;
    if let Some(path) = &a.plot {
        write_file(path, &spectrum_svg(&spec)?)?;
        let _ = writeln!(
            std::io::stderr(),
            "wrote {}: the amplitude spectrum of {} ({} frequencies, wavelengths in brackets)",
            path.display(),
            a.scan.display(),
            spec.frequency.len()
        );
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} samples over {:.1} mm, spacing {:.3} mm{}",
        a.scan.display(),
        spec.samples,
        spec.spacing_mm * (spec.samples.saturating_sub(1)) as f64,
        spec.spacing_mm,
        if spec.resampled {
            " (uneven: resampled linearly to uniform spacing)"
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "straight-line fit removed; Tukey window (alpha {TUKEY_ALPHA}); frequency resolution {:.6} /mm, read {PADDING}× finer; Nyquist {:.6} /mm",
        spec.resolution(),
        spec.nyquist()
    );
    let _ = writeln!(s, "\nlargest peaks:");
    let _ = writeln!(s, "    f [1/mm]  wavelength [mm]  amplitude [mm]");
    let amp = &spec.amplitude;
    for &k in spec.peaks().iter().take(6) {
        let f = spec.frequency[k];
        let _ = writeln!(s, "  {f:>10.6} {:>16.1} {:>15.4}", 1.0 / f, amp[k]);
    }
    match (spec.highest, spec.recommended_spacing_mm()) {
        (Some((f, amp)), Some(spacing)) => {
            let _ = writeln!(
                s,
                "\nhighest frequency above {} mm: {f:.6} /mm (wavelength {:.1} mm, amplitude {amp:.4} mm)",
                a.threshold,
                1.0 / f
            );
            let _ = writeln!(
                s,
                "recommended sampling spacing 1/(2f) = {spacing:.1} mm (docs/design.md §3; thesis eq. 4.12)"
            );
        }
        _ => {
            let _ = writeln!(
                s,
                "\nno frequency exceeds {} mm: the straight line describes the scan; sample as coarsely as the range allows",
                a.threshold
            );
        }
    }
    Ok(s)
}
