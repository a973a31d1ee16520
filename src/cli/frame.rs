//! `trackfix frame base | wobj | tool | fit`: frames from tracker and robot measurements, with
//! their uncertainties (docs/design.md).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use serde::Serialize;
use trackfix::frame::base::{BaseFit, fit_base, points_from};
use trackfix::frame::pairs::{POINTS_HEADER, REJECT_FACTOR, fit_pairs, point_file_from};
use trackfix::frame::tool::{FLANGE_COLUMNS, fit_tool, flange_from};
use trackfix::frame::wobj::{MARKS_HEADER, fit_wobj, marks_from};
use trackfix::frame::{FrameError, PointResidual, PoseUncertainty};
use trackfix::geometry::{
    Pose, abb_pose_literal, abb_quat_components, kuka_abc_angles, kuka_frame_literal,
    pose_to_xyz_deg,
};
use trackfix::output::write_file;
use trackfix::track::NumericCsv;
use trackfix::track::Profile;
use trackfix::track::frames_csv::clean;
use trackfix::track::identify::MEASUREMENTS_HEADER;
use trackfix::track::uncertainty::{ProfileUncertainty, Sigma};
use trackfix::transform::{Cell, TrackSetup};

use super::Exit;
use super::track::{print_notes, report_located};

#[derive(clap::Subcommand)]
pub(crate) enum FrameCommand {
    /// Robot base at skid 0 and track axis in world from TCP points at several skids,
    /// compensated by the track profile.
    Base(BaseArgs),
    /// A work object from fixture marks touched at several skid positions, compensated.
    Wobj(WobjArgs),
    /// The TCP from flange poses pivoting about one fixed point.
    Tool(ToolArgs),
    /// Best fit of point pairs (e.g. the tracker to the cell's reference marks), with outlier
    /// rejection.
    Fit(PairArgs),
    /// Simulate the frame samples (how samples/frames/ was made).
    #[command(hide = true)]
    Simulate(SimulateArgs),
}

#[derive(clap::Args)]
pub(crate) struct SimulateArgs {
    /// Folder for base_points.csv, marks.csv, flange.csv, flange_abc.csv, marks_nominal.csv
    /// and marks_tracker.csv.
    #[arg(long)]
    pub out_dir: PathBuf,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Format {
    Table,
    Json,
}

const BASE_EXAMPLES: &str = "\
Examples:
  trackfix frame base samples/frames/base_points.csv --profile samples/frames/profile.toml
  trackfix frame base samples/frames/base_points.csv --profile samples/frames/profile.toml -o base.toml
  trackfix frame base samples/frames/base_points.csv --format json

POINTS.csv has the columns of measurements.csv: skid,point,robot_x,robot_y,robot_z,meas_x,
meas_y,meas_z (TCP points as the controller reports them in its base frame, and as the tracker
measured them in the cell). Fits B0 and the unit track axis a of B(s) = Trans(s*a)*B0 so that
meas = B(s)*D(s)*robot; without --profile D = I (the uncompensated fit).";

const WOBJ_EXAMPLES: &str = "\
Examples:
  trackfix frame wobj samples/frames/marks.csv --cell samples/frames/cell.toml --robot r1
  trackfix frame wobj samples/frames/marks.csv --cell samples/frames/cell.toml --robot r1 --no-compensation

MARKS.csv: mark,skid,robot_x,robot_y,robot_z,cad_x,cad_y,cad_z (the TCP on each fixture mark as
the controller reports it, and the mark's CAD coordinates in the work object). Fits W with
W*cad = B(s)*D(s)*robot, B and D from the cell's robot.";

const TOOL_EXAMPLES: &str = "\
Examples:
  trackfix frame tool samples/frames/flange.csv

FLANGE.csv: x,y,z and q1,q2,q3,q4 (ABB, scalar first), rx,ry,rz or a,b,c (KUKA): flange poses in
the robot base while the TCP sits on one fixed point, in different orientations.";

const PAIR_EXAMPLES: &str = "\
Examples:
  trackfix frame fit samples/frames/marks_nominal.csv samples/frames/marks_tracker.csv

Both files: point,x,y,z, paired by point number. Gives T with NOMINAL = T*MEASURED (the
measurement frame in the nominal one). A point whose residual against the fit of the others is
above 4 x the median is rejected (while more than 4 remain).";

#[derive(clap::Args)]
#[command(after_help = BASE_EXAMPLES)]
pub(crate) struct BaseArgs {
    /// POINTS.csv: skid,point,robot_x,robot_y,robot_z,meas_x,meas_y,meas_z
    pub points: PathBuf,
    /// The track profile whose D(s) compensates the points.
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Noise per axis, mm (tracker and robot together); default: from the residuals.
    #[arg(long, value_name = "MM")]
    pub sigma: Option<f64>,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
    /// Write `base` and `track_axis` for cell.toml to this file.
    #[arg(short, long, value_name = "base.toml")]
    pub output: Option<PathBuf>,
}

#[derive(clap::Args)]
#[command(after_help = WOBJ_EXAMPLES)]
pub(crate) struct WobjArgs {
    /// MARKS.csv: mark,skid,robot_x,robot_y,robot_z,cad_x,cad_y,cad_z
    pub marks: PathBuf,
    /// The cell file with the robot's base, track axis and profile.
    #[arg(long)]
    pub cell: PathBuf,
    /// The robot that touched the marks.
    #[arg(long)]
    pub robot: String,
    /// Ignore the track profile (D = I).
    #[arg(long)]
    pub no_compensation: bool,
    /// Noise per axis of a touched point, mm; default: from the residuals.
    #[arg(long, value_name = "MM")]
    pub sigma: Option<f64>,
    /// Name of the RAPID wobjdata in the printed literal.
    #[arg(long, default_value = "wobj1")]
    pub name: String,
    /// Index of the KUKA BASE_DATA in the printed literal.
    #[arg(long, default_value_t = 1)]
    pub base_index: u32,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
}

#[derive(clap::Args)]
#[command(after_help = TOOL_EXAMPLES)]
pub(crate) struct ToolArgs {
    /// FLANGE.csv: x,y,z with q1,q2,q3,q4 / rx,ry,rz / a,b,c
    pub flange: PathBuf,
    /// Noise per axis of a flange position, mm; default: from the residuals.
    #[arg(long, value_name = "MM")]
    pub sigma: Option<f64>,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
}

#[derive(clap::Args)]
#[command(after_help = PAIR_EXAMPLES)]
pub(crate) struct PairArgs {
    /// point,x,y,z in the frame to fit into (e.g. the cell's reference marks).
    pub nominal: PathBuf,
    /// point,x,y,z as measured (e.g. by the tracker).
    pub measured: PathBuf,
    /// Reject a point above this many times the median residual.
    #[arg(long, value_name = "FACTOR", default_value_t = REJECT_FACTOR)]
    pub reject_factor: f64,
    /// Keep every point.
    #[arg(long, conflicts_with = "reject_factor")]
    pub no_reject: bool,
    /// Noise per axis, mm; default: from the residuals.
    #[arg(long, value_name = "MM")]
    pub sigma: Option<f64>,
    /// Output format.
    #[arg(long, value_enum, default_value = "table")]
    pub format: Format,
}

pub(crate) fn run(cmd: FrameCommand) -> anyhow::Result<Exit> {
    report_located(run_command(cmd))
}

fn run_command(cmd: FrameCommand) -> anyhow::Result<Exit> {
    let text = match cmd {
        FrameCommand::Base(a) => run_base(&a)?,
        FrameCommand::Wobj(a) => run_wobj(&a)?,
        FrameCommand::Tool(a) => run_tool(&a)?,
        FrameCommand::Fit(a) => run_pairs(&a)?,
        FrameCommand::Simulate(a) => run_simulate(&a)?,
    };
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(Exit::Ok)
}

/// Reads a numeric table, telling how when it is not plain CSV.
fn read_table(path: &Path, accepted: &[&str]) -> anyhow::Result<NumericCsv> {
    let table = NumericCsv::read(path, accepted)?;
    print_notes(&table);
    Ok(table)
}

/// A located input error stays findable by `report_located`.
fn frame_error(e: FrameError) -> anyhow::Error {
    match e {
        FrameError::Track(t) => t.into(),
        other => other.into(),
    }
}

#[derive(Serialize)]
struct XyzRxyz {
    x: f64,
    y: f64,
    z: f64,
    rx: f64,
    ry: f64,
    rz: f64,
}

impl XyzRxyz {
    fn of(v: [f64; 6], mm: i32, deg: i32) -> XyzRxyz {
        let [x, y, z, rx, ry, rz] = v;
        XyzRxyz {
            x: clean(x, mm),
            y: clean(y, mm),
            z: clean(z, mm),
            rx: clean(rx, deg),
            ry: clean(ry, deg),
            rz: clean(rz, deg),
        }
    }

    fn pose(p: &Pose) -> XyzRxyz {
        XyzRxyz::of(pose_to_xyz_deg(p), 4, 6)
    }

    fn uncertainty(u: &PoseUncertainty) -> XyzRxyz {
        XyzRxyz::of(u.u, 4, 6)
    }
}

#[derive(Serialize)]
struct ResidualRow {
    skid: f64,
    point: u32,
    dx: f64,
    dy: f64,
    dz: f64,
    rms: f64,
}

fn residual_rows(rs: &[PointResidual]) -> Vec<ResidualRow> {
    rs.iter()
        .map(|r| ResidualRow {
            skid: r.skid,
            point: r.point,
            dx: clean(r.residual.x, 4),
            dy: clean(r.residual.y, 4),
            dz: clean(r.residual.z, 4),
            rms: clean(r.norm(), 4),
        })
        .collect()
}

#[derive(Serialize)]
struct SigmaJson {
    sigma: f64,
    sigma_source: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    dof: Option<usize>,
}

fn sigma_json(s: &Sigma) -> SigmaJson {
    SigmaJson {
        sigma: clean(s.value(), 4),
        sigma_source: s.source(),
        dof: match s {
            Sigma::Estimated { dof, .. } => Some(*dof),
            Sigma::Given(_) => None,
        },
    }
}

fn sigma_text(s: &Sigma) -> String {
    match s {
        Sigma::Given(v) => format!("noise {v:.4} mm per axis (given)"),
        Sigma::Estimated { sigma, dof } => {
            format!("noise {sigma:.4} mm per axis (from the residuals, {dof} degrees of freedom)")
        }
    }
}

fn to_json(v: &impl Serialize) -> anyhow::Result<String> {
    let mut s = serde_json::to_string_pretty(v)?;
    s.push('\n');
    Ok(s)
}

fn residual_table(s: &mut String, rs: &[PointResidual], with_skid: bool, label: &str) {
    let skid = if with_skid { "      skid " } else { "" };
    let norm = if label == "pose" { "error" } else { "rms" };
    let _ = writeln!(
        s,
        "  {skid}{label:>5}    dx [mm]    dy [mm]    dz [mm] {norm:>5} [mm]"
    );
    for r in rs {
        let skid = if with_skid {
            format!("{:>10} ", r.skid)
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {skid}{:>5} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            r.point,
            clean(r.residual.x, 4),
            clean(r.residual.y, 4),
            clean(r.residual.z, 4),
            r.norm()
        );
    }
}

fn pose_line(p: &Pose, u: &PoseUncertainty) -> String {
    let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(p);
    let [ux, uy, uz, urx, ury, urz] = u.u;
    format!(
        "x {x:.4} y {y:.4} z {z:.4} mm, rx {rx:.6} ry {ry:.6} rz {rz:.6} deg\n    u (k=1): x {ux:.4} y {uy:.4} z {uz:.4} mm, rx {urx:.6} ry {ury:.6} rz {urz:.6} deg"
    )
}

#[derive(Serialize)]
struct BaseJson {
    base: XyzRxyz,
    track_axis: [f64; 3],
    rms: f64,
    compensated: bool,
    uncertainty: BaseUncertaintyJson,
    residuals: Vec<ResidualRow>,
}

#[derive(Serialize)]
struct BaseUncertaintyJson {
    #[serde(flatten)]
    sigma: SigmaJson,
    base: XyzRxyz,
    track_axis: [f64; 3],
    /// RMS of the modelled points' standard uncertainty.
    point: f64,
}

fn base_toml(fit: &BaseFit, source: &str) -> String {
    let [x, y, z, rx, ry, rz] = pose_to_xyz_deg(&fit.base0);
    let a = fit.track_axis;
    format!(
        "# Robot base at skid 0 and unit track axis in world (mm, degrees, R = Rz*Ry*Rx),\n\
         # from `trackfix frame base {source}`.\n\
         # Paste into the robot's [robot.NAME] table of cell.toml.\n\
         base = {{ x = {:.4}, y = {:.4}, z = {:.4}, rx = {:.6}, ry = {:.6}, rz = {:.6} }}\n\
         track_axis = [{:.9}, {:.9}, {:.9}]\n",
        clean(x, 4),
        clean(y, 4),
        clean(z, 4),
        clean(rx, 6),
        clean(ry, 6),
        clean(rz, 6),
        clean(a.x, 9),
        clean(a.y, 9),
        clean(a.z, 9)
    )
}

fn run_base(a: &BaseArgs) -> anyhow::Result<String> {
    let rows = points_from(&read_table(&a.points, &MEASUREMENTS_HEADER)?)?;
    let profile = match &a.profile {
        Some(p) => Some(Profile::load(p)?),
        None => None,
    };
    let fit = fit_base(&rows, profile.as_ref(), a.sigma)
        .map_err(frame_error)
        .with_context(|| a.points.display().to_string())?;
    if let Some(out) = &a.output {
        let source = match &a.profile {
            Some(p) => format!("{} --profile {}", a.points.display(), p.display()),
            None => a.points.display().to_string(),
        };
        write_file(out, base_toml(&fit, &source).as_bytes())?;
    }
    let axis = fit.track_axis;
    let round_axis = [axis.x, axis.y, axis.z].map(|v| clean(v, 9));
    if a.format == Format::Json {
        return to_json(&BaseJson {
            base: XyzRxyz::pose(&fit.base0),
            track_axis: round_axis,
            rms: clean(fit.rms, 4),
            compensated: fit.compensated,
            uncertainty: BaseUncertaintyJson {
                sigma: sigma_json(&fit.sigma),
                base: XyzRxyz::uncertainty(&fit.u_base),
                track_axis: fit.u_axis.map(|v| clean(v, 9)),
                point: clean(fit.u_point, 4),
            },
            residuals: residual_rows(&fit.residuals),
        });
    }
    let mut s = String::new();
    let skids: std::collections::BTreeSet<u64> = rows.iter().map(|r| r.skid.to_bits()).collect();
    let _ = writeln!(
        s,
        "robot base at skid 0 and track axis in world, {}",
        match (&profile, &a.profile) {
            (Some(p), Some(path)) =>
                format!("compensated by profile `{}` ({})", p.name(), path.display()),
            _ => "uncompensated (D = I; pass --profile to compensate the track)".to_string(),
        }
    );
    let _ = writeln!(s, "  base: {}", pose_line(&fit.base0, &fit.u_base));
    let _ = writeln!(
        s,
        "  track axis: [{:.9}, {:.9}, {:.9}]\n    u (k=1): [{:.9}, {:.9}, {:.9}]",
        round_axis[0], round_axis[1], round_axis[2], fit.u_axis[0], fit.u_axis[1], fit.u_axis[2]
    );
    let _ = writeln!(
        s,
        "  {} points at {} skid positions, rms {:.4} mm; {}",
        rows.len(),
        skids.len(),
        fit.rms,
        sigma_text(&fit.sigma)
    );
    let _ = writeln!(
        s,
        "  a TCP in the measured volume is placed to u = {:.4} mm (k=1, rms over the points)",
        fit.u_point
    );
    if let Some(out) = &a.output {
        let _ = writeln!(
            s,
            "  base and track_axis for cell.toml -> {}",
            out.display()
        );
    }
    let _ = writeln!(
        s,
        "\nresiduals = measured - B(s)*D(s)*robot (docs/design.md §14; thesis Table 7.2)"
    );
    residual_table(&mut s, &fit.residuals, true, "point");
    Ok(s)
}

#[derive(Serialize)]
struct WobjJson {
    wobj: XyzRxyz,
    rms: f64,
    compensated: bool,
    uncertainty: WobjUncertaintyJson,
    rapid: String,
    kuka: String,
    residuals: Vec<MarkResidualRow>,
}

#[derive(Serialize)]
struct WobjUncertaintyJson {
    #[serde(flatten)]
    sigma: SigmaJson,
    wobj: XyzRxyz,
}

#[derive(Serialize)]
struct MarkResidualRow {
    mark: u32,
    skid: f64,
    dx: f64,
    dy: f64,
    dz: f64,
    rms: f64,
}

/// RAPID `wobjdata` with the frame as uframe (oframe identity, fixed in world).
fn rapid_wobj(name: &str, p: &Pose) -> String {
    format!(
        "PERS wobjdata {name}:=[FALSE,TRUE,\"\",{},[[0,0,0],[1,0,0,0]]];",
        abb_pose_literal(p)
    )
}

/// KUKA `BASE_DATA[n]` (A, B, C = Rz·Ry·Rx).
fn kuka_base(index: u32, p: &Pose) -> String {
    format!("BASE_DATA[{index}]={}", kuka_frame_literal(p))
}

fn run_wobj(a: &WobjArgs) -> anyhow::Result<String> {
    let cell = Cell::load(&a.cell)?;
    let robot = cell.robot(&a.robot)?;
    let rows = marks_from(&read_table(&a.marks, &MARKS_HEADER)?)?;
    let identity = |_s: f64| Ok(Pose::identity());
    let profile = if a.no_compensation {
        None
    } else {
        Some(Profile::load(&robot.profile).map_err(|e| cell.profile_error(robot, &e))?)
    };
    let setup = match &profile {
        Some(p) => TrackSetup::new(robot, p),
        None => TrackSetup::new(robot, &identity),
    };
    let profile_u = match &profile {
        Some(p) => ProfileUncertainty::new(p)?,
        None => None,
    };
    let fit = fit_wobj(&rows, &setup, profile_u.as_ref(), a.sigma)
        .map_err(frame_error)
        .with_context(|| a.marks.display().to_string())?;
    let rapid = rapid_wobj(&a.name, &fit.wobj);
    let kuka = kuka_base(a.base_index, &fit.wobj);
    if a.format == Format::Json {
        return to_json(&WobjJson {
            wobj: XyzRxyz::pose(&fit.wobj),
            rms: clean(fit.rms, 4),
            compensated: profile.is_some(),
            uncertainty: WobjUncertaintyJson {
                sigma: sigma_json(&fit.sigma),
                wobj: XyzRxyz::uncertainty(&fit.u_wobj),
            },
            rapid,
            kuka,
            residuals: fit
                .residuals
                .iter()
                .map(|r| MarkResidualRow {
                    mark: r.point,
                    skid: r.skid,
                    dx: clean(r.residual.x, 4),
                    dy: clean(r.residual.y, 4),
                    dz: clean(r.residual.z, 4),
                    rms: clean(r.norm(), 4),
                })
                .collect(),
        });
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "work object in world from {} marks touched by robot `{}`, {}",
        rows.len(),
        robot.name,
        match &profile {
            Some(p) => format!("compensated by profile `{}`", p.name()),
            None => "uncompensated (D = I)".to_string(),
        }
    );
    let _ = writeln!(s, "  wobj: {}", pose_line(&fit.wobj, &fit.u_wobj));
    let _ = writeln!(
        s,
        "    (u from the marks' scatter{}; an error of the robot's base in the cell moves the work object with it)",
        if profile_u.is_some() {
            " and the profile's uncertainty"
        } else {
            ""
        }
    );
    let _ = writeln!(s, "  rms {:.4} mm; {}", fit.rms, sigma_text(&fit.sigma));
    let _ = writeln!(s, "\n  RAPID: {rapid}");
    let _ = writeln!(s, "  KUKA:  {kuka}");
    let _ = writeln!(s, "\nresiduals = B(s)*D(s)*robot - W*cad");
    residual_table(&mut s, &fit.residuals, true, "mark");
    Ok(s)
}

#[derive(Serialize)]
struct ToolJson {
    tool: Xyz,
    point: [f64; 3],
    rms: f64,
    mean: f64,
    max: f64,
    uncertainty: ToolUncertaintyJson,
    residuals: Vec<PoseResidualRow>,
}

#[derive(Serialize)]
struct Xyz {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Serialize)]
struct ToolUncertaintyJson {
    #[serde(flatten)]
    sigma: SigmaJson,
    tool: Xyz,
    point: [f64; 3],
}

#[derive(Serialize)]
struct PoseResidualRow {
    pose: u32,
    dx: f64,
    dy: f64,
    dz: f64,
    error: f64,
}

fn run_tool(a: &ToolArgs) -> anyhow::Result<String> {
    let (poses, kind) = flange_from(&read_table(&a.flange, &FLANGE_COLUMNS)?)?;
    let fit = fit_tool(&poses, a.sigma)
        .map_err(frame_error)
        .with_context(|| a.flange.display().to_string())?;
    let xyz = |v: [f64; 3]| Xyz {
        x: clean(v[0], 4),
        y: clean(v[1], 4),
        z: clean(v[2], 4),
    };
    let t = [fit.tcp.x, fit.tcp.y, fit.tcp.z];
    let p = [fit.point.x, fit.point.y, fit.point.z];
    if a.format == Format::Json {
        return to_json(&ToolJson {
            tool: xyz(t),
            point: p.map(|v| clean(v, 4)),
            rms: clean(fit.rms, 4),
            mean: clean(fit.mean, 4),
            max: clean(fit.max, 4),
            uncertainty: ToolUncertaintyJson {
                sigma: sigma_json(&fit.sigma),
                tool: xyz(fit.u_tcp),
                point: fit.u_point.map(|v| clean(v, 4)),
            },
            residuals: fit
                .residuals
                .iter()
                .map(|r| PoseResidualRow {
                    pose: r.point,
                    dx: clean(r.residual.x, 4),
                    dy: clean(r.residual.y, 4),
                    dz: clean(r.residual.z, 4),
                    error: clean(r.norm(), 4),
                })
                .collect(),
        });
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "TCP from {} flange poses ({} orientation) about one fixed point",
        poses.len(),
        kind.columns().join(",")
    );
    let _ = writeln!(
        s,
        "  tool (flange frame): x {:.4} y {:.4} z {:.4} mm   u (k=1): {:.4} {:.4} {:.4} mm",
        t[0], t[1], t[2], fit.u_tcp[0], fit.u_tcp[1], fit.u_tcp[2]
    );
    let _ = writeln!(
        s,
        "  point (base frame):  x {:.4} y {:.4} z {:.4} mm   u (k=1): {:.4} {:.4} {:.4} mm",
        p[0], p[1], p[2], fit.u_point[0], fit.u_point[1], fit.u_point[2]
    );
    let _ = writeln!(
        s,
        "  error per pose: mean {:.4} mm, max {:.4} mm, rms {:.4} mm; {}",
        fit.mean,
        fit.max,
        fit.rms,
        sigma_text(&fit.sigma)
    );
    let _ = writeln!(s, "\nerror = R*tool + flange - point");
    residual_table(&mut s, &fit.residuals, false, "pose");
    Ok(s)
}

#[derive(Serialize)]
struct PairJson {
    pose: XyzRxyz,
    rms: f64,
    uncertainty: PairUncertaintyJson,
    residuals: Vec<PairResidualRow>,
    rejected: Vec<PairResidualRow>,
    nominal_only: Vec<u32>,
    measured_only: Vec<u32>,
}

#[derive(Serialize)]
struct PairUncertaintyJson {
    #[serde(flatten)]
    sigma: SigmaJson,
    pose: XyzRxyz,
}

#[derive(Serialize)]
struct PairResidualRow {
    point: u32,
    dx: f64,
    dy: f64,
    dz: f64,
    rms: f64,
}

fn pair_rows(rs: &[PointResidual]) -> Vec<PairResidualRow> {
    rs.iter()
        .map(|r| PairResidualRow {
            point: r.point,
            dx: clean(r.residual.x, 4),
            dy: clean(r.residual.y, 4),
            dz: clean(r.residual.z, 4),
            rms: clean(r.norm(), 4),
        })
        .collect()
}

fn numbers(v: &[u32]) -> String {
    if v.is_empty() {
        return "none".to_string();
    }
    v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
}

fn run_pairs(a: &PairArgs) -> anyhow::Result<String> {
    let nominal = point_file_from(&read_table(&a.nominal, &POINTS_HEADER)?)?;
    let measured = point_file_from(&read_table(&a.measured, &POINTS_HEADER)?)?;
    if a.reject_factor.is_nan() || a.reject_factor <= 1.0 {
        anyhow::bail!(
            "--reject-factor {}: give a factor above 1 (or --no-reject)",
            a.reject_factor
        );
    }
    let factor = (!a.no_reject).then_some(a.reject_factor);
    let fit = fit_pairs(&nominal, &measured, factor, a.sigma)
        .map_err(frame_error)
        .with_context(|| format!("{} and {}", a.nominal.display(), a.measured.display()))?;
    if a.format == Format::Json {
        return to_json(&PairJson {
            pose: XyzRxyz::pose(&fit.pose),
            rms: clean(fit.rms, 4),
            uncertainty: PairUncertaintyJson {
                sigma: sigma_json(&fit.sigma),
                pose: XyzRxyz::uncertainty(&fit.u_pose),
            },
            residuals: pair_rows(&fit.residuals),
            rejected: pair_rows(&fit.rejected),
            nominal_only: fit.unpaired.0.clone(),
            measured_only: fit.unpaired.1.clone(),
        });
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} = T * {} from {} point pairs",
        file_name(&a.nominal),
        file_name(&a.measured),
        fit.residuals.len()
    );
    let _ = writeln!(s, "  T: {}", pose_line(&fit.pose, &fit.u_pose));
    let _ = writeln!(s, "  rms {:.4} mm; {}", fit.rms, sigma_text(&fit.sigma));
    let _ = writeln!(
        s,
        "  not paired: only in {}: {}; only in {}: {}",
        file_name(&a.nominal),
        numbers(&fit.unpaired.0),
        file_name(&a.measured),
        numbers(&fit.unpaired.1)
    );
    let _ = writeln!(s, "\nresiduals = nominal - T*measured");
    residual_table(&mut s, &fit.residuals, false, "point");
    match (factor, fit.rejected.is_empty()) {
        (None, _) => {
            let _ = writeln!(s, "\nno rejection (--no-reject)");
        }
        (Some(f), true) => {
            let _ = writeln!(s, "\nrejected (> {f} x median): none");
        }
        (Some(f), false) => {
            let _ = writeln!(
                s,
                "\nrejected (> {f} x median of the residuals against the fit of the others; residual against the final T):"
            );
            residual_table(&mut s, &fit.rejected, false, "point");
        }
    }
    Ok(s)
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// What samples/frames/README.md describes: robot r1 of samples/cell.toml on its simulated
/// track (`TrackTruth::sample_r1`), everything seeded.
fn run_simulate(a: &SimulateArgs) -> anyhow::Result<String> {
    use nalgebra::{Point3, Vector3};
    use trackfix::geometry::pose_xyz_deg;
    use trackfix::track::simulate::{
        SplitMix64, TrackTruth, marks_csv, measurements_csv, sample_tcp_points, simulate_marks,
        simulate_measurements, simulate_pivot,
    };
    std::fs::create_dir_all(&a.out_dir).with_context(|| a.out_dir.display().to_string())?;
    let write = |name: &str, text: &str| -> anyhow::Result<()> {
        write_file(&a.out_dir.join(name), text.as_bytes())?;
        Ok(())
    };
    let truth = TrackTruth::sample_r1();
    let tcp: Vec<Point3<f64>> = sample_tcp_points().into_iter().take(7).collect();
    let rows = simulate_measurements(
        &truth,
        &[400.0, 2100.0, 3900.0, 5600.0, 7300.0],
        &tcp,
        0.02,
        31,
    );
    write("base_points.csv", &measurements_csv(&rows))?;

    let wobj = pose_xyz_deg(1670.3, -1850.75, 612.4, 0.02, -0.03, 0.15);
    let cad: Vec<Point3<f64>> = [
        [-1500.0, -600.0, 0.0],
        [-700.0, 700.0, 150.0],
        [0.0, -650.0, 420.0],
        [600.0, 600.0, 0.0],
        [1300.0, -500.0, 300.0],
        [1600.0, 550.0, 600.0],
    ]
    .into_iter()
    .map(Point3::from)
    .collect();
    let skids = [200.0, 950.0, 1650.0, 2250.0, 2950.0, 3250.0];
    write(
        "marks.csv",
        &marks_csv(&simulate_marks(&truth, &wobj, &cad, &skids, 0.02, 32)),
    )?;

    let poses = simulate_pivot(
        &Vector3::new(12.5, -3.2, 215.0),
        &Point3::new(1400.0, 200.0, 600.0),
        9,
        0.02,
        33,
    );
    let mut abb = String::from("x,y,z,q1,q2,q3,q4\n");
    let mut kuka = String::from("x,y,z,a,b,c\n");
    for p in &poses {
        let t = p.translation.vector;
        let q = abb_quat_components(&p.rotation, None);
        let [ka, kb, kc] = kuka_abc_angles(&p.rotation, None);
        let _ = writeln!(
            abb,
            "{:.3},{:.3},{:.3},{:.8},{:.8},{:.8},{:.8}",
            t.x, t.y, t.z, q[0], q[1], q[2], q[3]
        );
        let _ = writeln!(
            kuka,
            "{:.3},{:.3},{:.3},{:.4},{:.4},{:.4}",
            t.x, t.y, t.z, ka, kb, kc
        );
    }
    write("flange.csv", &abb)?;
    write("flange_abc.csv", &kuka)?;

    // Reference marks of the cell and the tracker's reading of them from where it stood;
    // mark 5 was knocked by 1.5 mm, mark 9 is a tracker-only point.
    let tracker = pose_xyz_deg(-2500.0, 800.0, 150.0, 0.05, -0.1, -63.0);
    let mut rng = SplitMix64::new(34);
    let mut nominal = String::from("point,x,y,z\n");
    let mut measured = String::from("point,x,y,z\n");
    for i in 0..8 {
        let ang = i as f64 * 0.8;
        let p = Point3::new(
            (3000.0 * ang.cos()).round(),
            (2500.0 * ang.sin()).round() - 1850.0,
            200.0 * (i % 3) as f64,
        );
        let _ = writeln!(nominal, "{},{:.3},{:.3},{:.3}", i + 1, p.x, p.y, p.z);
        let noise = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * 0.01;
        let knock = if i == 4 {
            Vector3::new(1.5, 0.0, 0.0)
        } else {
            Vector3::zeros()
        };
        let m = tracker.inverse() * (p + knock) + noise;
        let _ = writeln!(measured, "{},{:.4},{:.4},{:.4}", i + 1, m.x, m.y, m.z);
    }
    let extra = tracker.inverse() * Point3::new(0.0, -1850.0, 900.0);
    let _ = writeln!(measured, "9,{:.4},{:.4},{:.4}", extra.x, extra.y, extra.z);
    write("marks_nominal.csv", &nominal)?;
    write("marks_tracker.csv", &measured)?;
    Ok(format!(
        "wrote base_points.csv, marks.csv, flange.csv, flange_abc.csv, marks_nominal.csv, marks_tracker.csv to {}\n",
        a.out_dir.display()
    ))
}
