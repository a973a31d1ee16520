//! `trackfix report`: the track report as one self-contained HTML file.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use trackfix::accuracy::{AccuracyError, ColumnMap};
use trackfix::accuracy::{pose_accuracy, read_commanded_poses, read_visits};
use trackfix::html_report::accuracy::pose_result;
use trackfix::html_report::track::TrackReport;
use trackfix::html_report::{SourceFile, TrackInputs};
use trackfix::track::frames_csv::parse_frames;
use trackfix::track::identify::parse_measurements;
use trackfix::track::nominal::FitOptions;
use trackfix::track::spectrum::{scan_from_table, scan_spectrum};
use trackfix::track::{Gear, NumericCsv, Profile, Reference};

use super::Exit;
use super::track::report_located;

const REPORT_EXAMPLES: &str = "\
Examples:
  trackfix report --measurements samples/track/measurements.csv --scan samples/track/scan.csv -o r1.html
  trackfix report --profile samples/track/profile.toml -o profile.html
  trackfix report --profile samples/track/profile.toml --accuracy-pose samples/accuracy/pose_commanded.csv samples/accuracy/pose_measured.csv -o cell.html

One HTML file with its stylesheet and charts inline: no script, no font or file fetched; it opens
from a USB stick and prints to PDF (one section per page). What is not given is computed:
measurements -> frames (as track identify) -> profile (as track fit).";

#[derive(clap::Args)]
#[command(after_help = REPORT_EXAMPLES)]
#[command(group = clap::ArgGroup::new("input").required(true).multiple(true)
    .args(["measurements", "frames", "profile", "scan", "accuracy_pose"]))]
pub(crate) struct ReportArgs {
    /// measurements.csv: skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z
    #[arg(long, value_name = "M.csv")]
    pub measurements: Option<PathBuf>,
    /// frames.csv: skid,x,y,z,rx,ry,rz (default: identified from --measurements).
    #[arg(long, value_name = "F.csv")]
    pub frames: Option<PathBuf>,
    /// profile.toml (default: fitted to the frames).
    #[arg(long, value_name = "P.toml")]
    pub profile: Option<PathBuf>,
    /// scan.csv: skid,x,y,z (or t,x,y,z with --speed), for the spectrum.
    #[arg(long, value_name = "S.csv")]
    pub scan: Option<PathBuf>,
    /// ISO 9283 pose accuracy: commanded poses (point,x,y,z[,rx,ry,rz]) and their measured
    /// visits (point,cycle,x,y,z[,rx,ry,rz]), as `accuracy pose` reads them (repeatable).
    #[arg(long, num_args = 2, value_names = ["C.csv", "M.csv"], action = clap::ArgAction::Append)]
    pub accuracy_pose: Vec<PathBuf>,
    /// Spectrum amplitude threshold in mm: frequencies above it must be sampled.
    #[arg(
        long,
        value_name = "MM",
        default_value_t = 0.05,
        allow_negative_numbers = true
    )]
    pub threshold: f64,
    /// Skid speed in mm/s, for a scan timed in seconds (t,x,y,z).
    #[arg(long, value_name = "MM_PER_S", allow_negative_numbers = true)]
    pub speed: Option<f64>,
    /// Name of a fitted profile (default: the folder of the measurements or frames).
    #[arg(long)]
    pub name: Option<String>,
    /// For a fitted profile: the straight line the deviations are taken from.
    #[arg(long, value_enum, default_value = "regression")]
    pub reference: Reference,
    /// For a fitted profile: keep the controller's gear factor or enter the new one.
    #[arg(long, value_enum, default_value = "as-is")]
    pub gear: Gear,
    /// Where to write the HTML file.
    #[arg(short, long, value_name = "FILE.html")]
    pub output: PathBuf,
}

fn read(path: &Path) -> anyhow::Result<(SourceFile, Vec<u8>)> {
    let bytes = trackfix::output::read_input(path).with_context(|| path.display().to_string())?;
    Ok((SourceFile::new(path.display().to_string(), &bytes), bytes))
}

/// How a table was read when that is not plain CSV (`;`-separated, …), for the user to check.
fn print_notes(table: &NumericCsv) -> anyhow::Result<()> {
    for note in &table.notes {
        writeln!(std::io::stderr(), "note: {note}")?;
    }
    Ok(())
}

fn folder_name(path: &Path) -> Option<String> {
    path.parent()
        .and_then(|p| p.file_name())
        .and_then(|s| s.to_str())
        .map(str::to_owned)
}

pub(crate) fn run(a: ReportArgs) -> anyhow::Result<Exit> {
    let result = report_located(run_inner(&a));
    // An accuracy input error already says `file:line:col: error: …` with the line and a hint.
    if let Err(err) = &result
        && let Some(AccuracyError::Input(located)) =
            err.chain().find_map(|c| c.downcast_ref::<AccuracyError>())
    {
        writeln!(std::io::stderr(), "{located}")?;
        return Ok(Exit::Usage);
    }
    result
}

fn run_inner(a: &ReportArgs) -> anyhow::Result<Exit> {
    if a.threshold.is_nan() || a.threshold <= 0.0 {
        anyhow::bail!(
            "--threshold {}: give a positive amplitude in mm",
            a.threshold
        );
    }
    if let Some(v) = a.speed
        && (v.is_nan() || v <= 0.0)
    {
        anyhow::bail!("--speed {v}: give a positive speed in mm/s");
    }
    let mut inputs = TrackInputs {
        fit: FitOptions {
            name: a
                .name
                .clone()
                .or_else(|| {
                    a.measurements
                        .as_deref()
                        .or(a.frames.as_deref())
                        .and_then(folder_name)
                })
                .unwrap_or_else(|| "track".to_owned()),
            reference: a.reference,
            gear: a.gear,
            ..FitOptions::default()
        },
        ..TrackInputs::default()
    };
    if let Some(path) = &a.measurements {
        let (src, bytes) = read(path)?;
        inputs.measurements = Some((src, parse_measurements(path, &bytes)?));
    }
    if let Some(path) = &a.frames {
        let (src, bytes) = read(path)?;
        inputs.frames = Some((src, parse_frames(path, &bytes)?));
    }
    if let Some(path) = &a.profile {
        let (src, bytes) = read(path)?;
        let text = std::str::from_utf8(&bytes)
            .with_context(|| format!("{}: not UTF-8 text", path.display()))?;
        inputs.profile = Some((src, Profile::from_toml_str(text, path)?));
    }
    if let Some(path) = &a.scan {
        let (src, bytes) = read(path)?;
        let (pos_col, scale) = match a.speed {
            Some(v) => ("t", v),
            None => ("skid", 1.0),
        };
        let table = NumericCsv::parse(path, &bytes, &[pos_col, "x", "y", "z"])?;
        print_notes(&table)?;
        let (positions, points) = scan_from_table(&table, pos_col, scale)?;
        let spec = scan_spectrum(&positions, &points, a.threshold)
            .with_context(|| path.display().to_string())?;
        inputs.scan = Some((src, spec));
    }
    for pair in a.accuracy_pose.chunks(2) {
        let [commanded, measured] = pair else {
            anyhow::bail!("--accuracy-pose takes two files: C.csv M.csv");
        };
        let map = ColumnMap::default();
        let poses = read_commanded_poses(commanded, &map)?;
        let visits = read_visits(measured, &map, &poses)?;
        let report = pose_accuracy(&poses, &visits)
            .with_context(|| format!("ISO 9283 pose accuracy of {}", measured.display()))?;
        inputs
            .accuracy
            .push(pose_result(&report, read(commanded)?.0, read(measured)?.0));
    }
    let report = TrackReport::compute(inputs)?;
    let page = report.page();
    let html = page.render();
    let sections = &page.sections;
    // One write helper for every file trackfix writes: temporary + rename, mode kept.
    trackfix::output::write_file(&a.output, html.as_bytes())?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "wrote {} ({} bytes), {} sections:",
        a.output.display(),
        html.len(),
        sections.len()
    )?;
    for s in sections {
        writeln!(out, "  {}", s.heading)?;
    }
    out.flush()?;
    Ok(Exit::Ok)
}
