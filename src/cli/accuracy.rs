//! `trackfix accuracy pose | path`: ISO 9283 figures from laser-tracker measurements, the
//! straight-line report and the figures.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use trackfix::accuracy::{
    ColumnMap, PathOptions, PathReport, PointAccuracy, PoseComparison, PoseReport, PoseSummary,
    compare, path_svg, path_svgs, pose_accuracy, pose_svg, read_commanded_path,
    read_commanded_poses, read_recording, read_visits,
};
use trackfix::output::write_file;

use super::Exit;

#[derive(clap::Subcommand)]
pub(crate) enum AccuracyCommand {
    /// ISO 9283 pose accuracy AP and repeatability RP of visits to commanded poses.
    Pose(PoseArgs),
    /// ISO 9283 path accuracy AT and repeatability RT, and the straight-line report.
    Path(PathArgs),
}

const POSE_EXAMPLES: &str = "\
Examples:
  trackfix accuracy pose samples/accuracy/pose_commanded.csv samples/accuracy/pose_measured.csv
  trackfix accuracy pose cmd.csv after.csv --before before.csv --format json
  trackfix accuracy pose cmd.csv export.csv --map point=Name,cycle=Run --plot figures/

COMMANDED.csv: point,x,y,z[,rx,ry,rz] (programmed poses in the measurement frame, mm, deg).
MEASURED.csv: point,cycle,x,y,z[,rx,ry,rz], one row per visit; `;` between fields with a
decimal comma is read too. AP = |mean - commanded|, RP = mean(l) + 3 S(l) with S over n-1,
MAX = the largest single distance from the commanded position.";

const PATH_EXAMPLES: &str = "\
Examples:
  trackfix accuracy path samples/accuracy/line_commanded.csv samples/accuracy/line_cycles.csv --speed 600
  trackfix accuracy path samples/accuracy/line_commanded.csv samples/accuracy/line_continuous.csv --plot figures/

COMMANDED.csv: x,y,z[,rx,ry,rz] vertices of the programmed path (two rows for a line).
MEASURED.csv: cycle,t,x,y,z[,rx,ry,rz] samples (t in s). Without `cycle` the recording is cut
into runs at stops and reversals; runs against the commanded direction are listed, not used.";

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Format {
    Table,
    Json,
    Csv,
}

#[derive(clap::Args)]
#[command(after_help = POSE_EXAMPLES)]
pub(crate) struct PoseArgs {
    /// COMMANDED.csv: point,x,y,z[,rx,ry,rz]
    pub commanded: PathBuf,
    /// MEASURED.csv: point,cycle,x,y,z[,rx,ry,rz]
    pub measured: PathBuf,
    /// An earlier measurement of the same poses (e.g. before `correct`): report the improvement.
    #[arg(long, value_name = "MEASURED0.csv")]
    pub before: Option<PathBuf>,
    /// Output format (JSON and CSV round to 6 decimals).
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
    /// Write the figure: FILE.svg, or a folder (pose.svg in it). With --before it shows the
    /// earlier AP and how far each point's mean moved.
    #[arg(long, value_name = "DIR_or_FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Which columns of a measurement export hold the roles: point=COL,cycle=COL,x=COL,…
    /// (other columns are then ignored).
    #[arg(long, value_name = "ROLE=COL,...")]
    pub map: Option<String>,
}

#[derive(clap::Args)]
#[command(after_help = PATH_EXAMPLES)]
pub(crate) struct PathArgs {
    /// COMMANDED.csv: x,y,z[,rx,ry,rz], the vertices of the programmed path.
    pub commanded: PathBuf,
    /// MEASURED.csv: [cycle,]t,x,y,z[,rx,ry,rz]
    pub measured: PathBuf,
    /// Number of planes normal to the path, at arc lengths L·i/(M+1).
    #[arg(long, value_name = "M", default_value_t = 10)]
    pub planes: usize,
    /// The programmed speed in mm/s (for the velocity deviation).
    #[arg(long, value_name = "MM_PER_S")]
    pub speed: Option<f64>,
    /// Output format (JSON and CSV round to 6 decimals).
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
    /// Write the figures: FILE.svg (all in one), or a folder (path_planes.svg,
    /// path_deviation.svg, path_look_through.svg, path_velocity.svg).
    #[arg(long, value_name = "DIR_or_FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Which columns of the recording hold the roles: cycle=COL,t=COL,x=COL,…
    #[arg(long, value_name = "ROLE=COL,...")]
    pub map: Option<String>,
}

pub(crate) fn run(command: AccuracyCommand) -> anyhow::Result<Exit> {
    let text = match command {
        AccuracyCommand::Pose(a) => run_pose(&a)?,
        AccuracyCommand::Path(a) => run_path(&a)?,
    };
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(Exit::Ok)
}

fn column_map(text: &Option<String>) -> anyhow::Result<ColumnMap> {
    match text {
        Some(t) => ColumnMap::parse(t).map_err(|e| anyhow::anyhow!("--map {t}: {e}")),
        None => Ok(ColumnMap::default()),
    }
}

/// `FILE.svg` or a folder that will hold `name`.
fn plot_target(plot: &Path, name: &str) -> anyhow::Result<PathBuf> {
    if plot
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
    {
        return Ok(plot.to_path_buf());
    }
    std::fs::create_dir_all(plot).with_context(|| format!("--plot {}", plot.display()))?;
    Ok(plot.join(name))
}

fn is_file_target(plot: &Path) -> bool {
    plot.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
}

/// Pretty JSON in the types' field order with every fractional number rounded to 6 decimals
/// (µm; no float noise in the last digits). Rounds the number tokens of serde_json's output,
/// so the documented key order stays (a `serde_json::Value` would sort the keys).
fn rounded_json(value: impl serde::Serialize) -> anyhow::Result<String> {
    let text = serde_json::to_string_pretty(&value)?;
    let mut out = String::with_capacity(text.len());
    let mut chars = text.char_indices().peekable();
    let mut in_string = false;
    while let Some((i, c)) = chars.next() {
        if in_string {
            out.push(c);
            if c == '\\' {
                if let Some((_, e)) = chars.next() {
                    out.push(e);
                }
            } else if c == '"' {
                in_string = false;
            }
            continue;
        }
        if c == '"' {
            in_string = true;
            out.push(c);
            continue;
        }
        if c == '-' || c.is_ascii_digit() {
            let mut end = i + c.len_utf8();
            while let Some(&(j, d)) = chars.peek() {
                if d.is_ascii_digit() || matches!(d, '.' | 'e' | 'E' | '+' | '-') {
                    end = j + d.len_utf8();
                    chars.next();
                } else {
                    break;
                }
            }
            let token = &text[i..end];
            match token.parse::<f64>() {
                Ok(x) if token.contains(['.', 'e', 'E']) => {
                    let r = (x * 1e6).round() / 1e6 + 0.0;
                    out.push_str(&serde_json::to_string(&r)?);
                }
                _ => out.push_str(token),
            }
            continue;
        }
        out.push(c);
    }
    out.push('\n');
    Ok(out)
}

fn cell(v: Option<f64>, width: usize) -> String {
    match v {
        Some(v) => format!("{v:>width$.4}"),
        None => format!("{:>width$}", "-"),
    }
}

fn csv_cell(v: Option<f64>) -> String {
    v.map(|v| format!("{:.6}", (v * 1e6).round() / 1e6 + 0.0))
        .unwrap_or_default()
}

fn percent(p: Option<f64>) -> String {
    p.map_or_else(|| "-".to_owned(), |p| format!("{p:+.1}%"))
}

fn run_pose(a: &PoseArgs) -> anyhow::Result<String> {
    let map = column_map(&a.map)?;
    // The commanded file is ours, not an export: the map applies to measurements only.
    let commanded = read_commanded_poses(&a.commanded, &ColumnMap::default())?;
    let visits = read_visits(&a.measured, &map, &commanded)?;
    let report =
        pose_accuracy(&commanded, &visits).with_context(|| a.measured.display().to_string())?;
    let before = match &a.before {
        Some(path) => {
            let v = read_visits(path, &map, &commanded)?;
            let b = pose_accuracy(&commanded, &v).with_context(|| path.display().to_string())?;
            let c = compare(&b, &report)?;
            Some((b, c))
        }
        None => None,
    };
    if let Some(plot) = &a.plot {
        let svg = pose_svg(&report, before.as_ref().map(|b| &b.0))?;
        write_file(&plot_target(plot, "pose.svg")?, svg.as_bytes())?;
    }
    Ok(match a.format {
        Format::Json => match &before {
            Some((b, c)) => rounded_json(BeforeAfter {
                points: &report.points,
                summary: &report.summary,
                before: b,
                improvement: c,
            })?,
            None => rounded_json(&report)?,
        },
        Format::Csv => pose_csv(&report, before.as_ref().map(|b| &b.1)),
        Format::Table => pose_table(a, &report, before.as_ref().map(|b| &b.1)),
    })
}

/// The pose JSON with `--before`: the figures, the earlier ones and the improvement.
#[derive(serde::Serialize)]
struct BeforeAfter<'a> {
    points: &'a [PointAccuracy],
    summary: &'a PoseSummary,
    before: &'a PoseReport,
    improvement: &'a PoseComparison,
}

fn pose_csv(r: &PoseReport, change: Option<&PoseComparison>) -> String {
    let mut s = String::from("point,n,AP,APx,APy,APz,APa,APb,APc,RP,RPa,RPb,RPc,MAX");
    if change.is_some() {
        s.push_str(",AP_before,RP_before,MAX_before");
    }
    s.push('\n');
    for (i, p) in r.points.iter().enumerate() {
        let cells = p.figures();
        let _ = write!(s, "{},{}", p.point, p.n);
        for c in cells {
            let _ = write!(s, ",{}", csv_cell(c));
        }
        if let Some(pc) = change.and_then(|c| c.points.get(i)) {
            for c in [pc.ap.before, pc.rp.before, pc.max.before] {
                let _ = write!(s, ",{}", csv_cell(Some(c)));
            }
        }
        s.push('\n');
    }
    s
}

fn pose_table(a: &PoseArgs, r: &PoseReport, change: Option<&PoseComparison>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "ISO 9283 pose accuracy and repeatability: {} point(s), {} visit(s) in {}",
        r.summary.points,
        r.summary.visits,
        a.measured.display()
    );
    let _ = writeln!(
        s,
        "{:<8} {:>3} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "point",
        "n",
        "AP",
        "APx",
        "APy",
        "APz",
        "APa",
        "APb",
        "APc",
        "RP",
        "RPa",
        "RPb",
        "RPc",
        "MAX"
    );
    let row = |s: &mut String, name: &str, n: String, v: [Option<f64>; 12]| {
        let _ = write!(s, "{name:<8} {n:>3}");
        for c in v {
            let _ = write!(s, " {}", cell(c, 8));
        }
        s.push('\n');
    };
    for p in &r.points {
        row(&mut s, &p.point, p.n.to_string(), p.figures());
    }
    let w = &r.summary;
    row(
        &mut s,
        "worst",
        String::new(),
        [
            Some(w.ap),
            Some(w.ap_x),
            Some(w.ap_y),
            Some(w.ap_z),
            w.ap_a,
            w.ap_b,
            w.ap_c,
            Some(w.rp),
            w.rp_a,
            w.rp_b,
            w.rp_c,
            Some(w.max),
        ],
    );
    let _ = writeln!(
        s,
        "mm and degrees; worst AP at {}, RP at {}, MAX at {}",
        w.worst_ap_point, w.worst_rp_point, w.worst_max_point
    );
    if let Some(c) = change {
        let _ = writeln!(
            s,
            "\nimprovement over {} (before -> after, change in % of before)",
            a.before.as_deref().unwrap_or(Path::new("")).display()
        );
        let _ = writeln!(
            s,
            "{:<8} {:>26} {:>26} {:>26}",
            "point", "AP [mm]", "RP [mm]", "MAX [mm]"
        );
        for p in c.points.iter().chain(std::iter::once(&c.summary)) {
            let _ = write!(s, "{:<8}", p.point);
            for ch in [p.ap, p.rp, p.max] {
                let _ = write!(
                    s,
                    " {:>8.4} -> {:>7.4} {:>7}",
                    ch.before,
                    ch.after,
                    percent(ch.percent)
                );
            }
            s.push('\n');
        }
    }
    s
}

fn run_path(a: &PathArgs) -> anyhow::Result<String> {
    let map = column_map(&a.map)?;
    if let Some(v) = a.speed
        && !(v.is_finite() && v > 0.0)
    {
        anyhow::bail!("--speed {v}: give the programmed speed in mm/s (a positive number)");
    }
    let commanded = read_commanded_path(&a.commanded, &ColumnMap::default())?;
    let recording = read_recording(&a.measured, &map)?;
    let report = trackfix::accuracy::path_accuracy(
        &commanded,
        &recording,
        PathOptions {
            planes: a.planes,
            commanded_speed: a.speed,
        },
    )
    .with_context(|| a.measured.display().to_string())?;
    if a.format != Format::Table {
        for r in report.runs.iter().filter(|r| !r.used) {
            let _ = writeln!(
                std::io::stderr(),
                "note: {} (lines {}-{}) not used: {}",
                r.label,
                r.first_line,
                r.last_line,
                r.note.as_deref().unwrap_or("")
            );
        }
    }
    if let Some(plot) = &a.plot {
        if is_file_target(plot) {
            write_file(plot, path_svg(&commanded, &report)?.as_bytes())?;
        } else {
            for (name, svg) in path_svgs(&commanded, &report)? {
                let target = plot_target(plot, &format!("path_{name}.svg"))?;
                write_file(&target, svg.as_bytes())?;
            }
        }
    }
    Ok(match a.format {
        Format::Json => rounded_json(&report)?,
        Format::Csv => path_csv(&report),
        Format::Table => path_table(a, &report),
    })
}

fn path_csv(r: &PathReport) -> String {
    let mut s = String::from("i,s,ATp,RTp,ATa,ATb,ATc,RTa,RTb,RTc\n");
    for p in &r.planes {
        let _ = write!(s, "{},{}", p.i, csv_cell(Some(p.s)));
        for c in [
            Some(p.atp),
            Some(p.rtp),
            p.at_a,
            p.at_b,
            p.at_c,
            p.rt_a,
            p.rt_b,
            p.rt_c,
        ] {
            let _ = write!(s, ",{}", csv_cell(c));
        }
        s.push('\n');
    }
    s
}

/// Rounded to 0.1 without a "-0.0" for a sample a hair before the start.
fn tenths(v: f64) -> f64 {
    (v * 10.0).round() / 10.0 + 0.0
}

fn opt(v: Option<f64>, unit: &str, decimals: usize) -> String {
    v.map_or_else(|| "-".to_owned(), |v| format!("{v:.decimals$} {unit}"))
}

fn path_table(a: &PathArgs, r: &PathReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "ISO 9283 path accuracy and repeatability: {} run(s), {} plane(s), path length {:.3} mm ({})",
        r.runs_used,
        r.planes.len(),
        r.length,
        a.measured.display()
    );
    let _ = writeln!(
        s,
        "AT  {:.4} mm   RT  {:.4} mm   ATa/ATb/ATc {} {} {} deg   RTa/RTb/RTc {} {} {} deg",
        r.at,
        r.rt,
        cell(r.at_a, 0),
        cell(r.at_b, 0),
        cell(r.at_c, 0),
        cell(r.rt_a, 0),
        cell(r.rt_b, 0),
        cell(r.rt_c, 0),
    );
    let _ = writeln!(
        s,
        "{:>5} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "plane", "s [mm]", "ATp", "RTp", "ATa", "ATb", "ATc", "RTa", "RTb", "RTc"
    );
    for p in &r.planes {
        let _ = write!(s, "{:>5} {:>10.3}", p.i, p.s);
        for c in [
            Some(p.atp),
            Some(p.rtp),
            p.at_a,
            p.at_b,
            p.at_c,
            p.rt_a,
            p.rt_b,
            p.rt_c,
        ] {
            let _ = write!(s, " {}", cell(c, 8));
        }
        s.push('\n');
    }
    let l = &r.line;
    let _ = writeln!(
        s,
        "\nstraight-line report (docs/design.md §11; thesis Table 5.1)"
    );
    let rows: [(&str, String); 12] = [
        ("path length", format!("{:.3} m", l.length / 1000.0)),
        ("commanded velocity", opt(l.commanded_velocity, "mm/s", 1)),
        ("measured velocity", opt(l.measured_velocity, "mm/s", 1)),
        (
            "velocity deviation (max)",
            opt(l.velocity_deviation_max_percent, "%", 1),
        ),
        ("acceleration", opt(l.acceleration, "mm/s²", 0)),
        ("deceleration", opt(l.deceleration, "mm/s²", 0)),
        (
            "max. path deviation",
            format!(
                "{:.3} mm ({} at s = {:.1} mm)",
                l.max_deviation, l.max_deviation_run, l.max_deviation_s
            ),
        ),
        ("mean path deviation", format!("{:.3} mm", l.mean_deviation)),
        (
            "repeating uncertainty (RT)",
            format!("{:.3} mm", l.repeat_uncertainty),
        ),
        (
            "abs. deviation at start position",
            format!("{:.3} mm", l.start_deviation),
        ),
        (
            "abs. deviation at end position",
            format!("{:.3} mm", l.end_deviation),
        ),
        ("runs", format!("{} used of {}", r.runs_used, r.runs.len())),
    ];
    for (k, v) in rows {
        let _ = writeln!(s, "  {k:<34} {v}");
    }
    if l.legs.len() > 1 {
        for leg in &l.legs {
            let _ = writeln!(
                s,
                "  leg {:<3} s {:>8.1} .. {:>8.1} mm  max. deviation {:.3} mm, mean {:.3} mm, velocity {}",
                leg.leg,
                leg.from_s,
                leg.to_s,
                leg.max_deviation,
                leg.mean_deviation,
                opt(leg.measured_velocity, "mm/s", 1)
            );
        }
    }
    for run in &r.runs {
        let _ = writeln!(
            s,
            "  {:<8} lines {:>5}-{:<5} {:>5} samples  {:<8} s {:>8.1} .. {:>8.1} mm  {}",
            run.label,
            run.first_line,
            run.last_line,
            run.samples,
            match run.direction {
                trackfix::accuracy::Direction::Forward => "forward",
                trackfix::accuracy::Direction::Backward => "backward",
            },
            tenths(run.from_s),
            tenths(run.to_s),
            if run.used {
                "used".to_owned()
            } else {
                format!("not used: {}", run.note.as_deref().unwrap_or(""))
            }
        );
    }
    s
}
