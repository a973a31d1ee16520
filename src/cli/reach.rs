//! `trackfix reach`: every target through the robot's kinematics.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::bail;
use trackfix::kinematics::reach::{FileReach, ReachOptions, ReachStatus, reach_program};
use trackfix::program::{LoadOptions, collect_programs, load_group};
use trackfix::transform::Cell;

use super::Exit;

const REACH_EXAMPLES: &str = "\
Examples:
  trackfix reach samples/rapid/spot_line.mod --cell samples/cell.toml --robot r1
  trackfix reach samples/krl/spot_line.src --cell samples/cell.toml --robot k1 --format json

For every target at its skid s, in its work object W with tool TOOL, the flange in the robot base
  F = B(s)⁻¹ · W · T · TOOL⁻¹
goes through the robot's [robot.NAME.kinematics]: joints, the configuration the target writes,
the margin to each joint limit, a warning near the wrist singularity.

Exit codes: 0 every target reachable in its configuration within the limits, 1 a target is
unreachable, outside a limit, in another configuration or could not be checked, 2 input error.";

#[derive(Clone, Copy, Debug, Default, clap::ValueEnum)]
pub(crate) enum ReachFormat {
    /// Aligned columns for people.
    #[default]
    Table,
    /// `{"files":[{"path","targets":[…]}]}`.
    Json,
}

/// Check that every target is reachable, inside the joint limits and in its configuration.
#[derive(clap::Args, Debug)]
#[command(after_help = REACH_EXAMPLES)]
pub(crate) struct ReachArgs {
    /// RAPID modules, KRL programs (.src or .dat loads the pair) or folders.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The cell file; the robot needs a [robot.NAME.kinematics] table.
    #[arg(long, value_name = "CELL.toml")]
    pub cell: PathBuf,
    /// The robot (a [robot.NAME] of the cell file).
    #[arg(long)]
    pub robot: String,
    #[arg(long, value_enum, default_value_t = ReachFormat::Table)]
    pub format: ReachFormat,
    /// Warn when |axis 5| is below this many degrees.
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub singularity_deg: f64,
    /// Work object (or KRL base) of declared targets no motion uses.
    #[arg(long, value_name = "NAME")]
    pub default_wobj: Option<String>,
}

pub(crate) fn run(a: ReachArgs) -> anyhow::Result<Exit> {
    let cell = Cell::load(&a.cell)?;
    let robot = cell.robot(&a.robot)?;
    let Some(kin) = robot.kinematics.as_ref() else {
        bail!(
            "{}: robot `{}` has no [robot.{}.kinematics] table; add `model = \"NAME\"` or the OPW lengths",
            a.cell.display(),
            a.robot,
            a.robot
        );
    };
    let options = LoadOptions {
        krl_config_dat: robot.config_dat.clone(),
        // `reach` writes nothing.
        map_inputs: true,
        ..LoadOptions::default()
    };
    let reach_options = ReachOptions {
        singularity_deg: a.singularity_deg,
        default_wobj: a.default_wobj.clone(),
    };
    let mut files: Vec<FileReach> = Vec::new();
    for group in collect_programs(&a.files)? {
        for loaded in load_group(&group, &options) {
            match loaded {
                Ok(p) => {
                    // What the cell's entries make of the program's work objects (an object
                    // frame kept), as the transforms say it.
                    super::transform::show_readings(
                        std::slice::from_ref(&p),
                        &[robot],
                        super::transform::Readings::Cell,
                        Default::default(),
                    )?;
                    files.extend(reach_program(&p, robot, kin, &reach_options));
                }
                Err(e) if e.is_skip() => {
                    let _ = writeln!(std::io::stderr(), "note: {e}");
                }
                Err(e) => return Err(e.into()),
            }
        }
    }
    let bad = files
        .iter()
        .flat_map(|f| &f.targets)
        .filter(|t| t.status != ReachStatus::Ok)
        .count();
    let mut out = std::io::stdout().lock();
    match a.format {
        ReachFormat::Json => {
            serde_json::to_writer_pretty(&mut out, &serde_json::json!({ "files": files }))?;
            writeln!(out)?;
        }
        ReachFormat::Table => write_table(&mut out, &files)?,
    }
    Ok(if bad > 0 { Exit::Findings } else { Exit::Ok })
}

fn write_table(out: &mut impl std::io::Write, files: &[FileReach]) -> anyhow::Result<()> {
    let mut total = 0;
    let mut counts = std::collections::BTreeMap::new();
    for f in files {
        writeln!(out, "{}", f.path.display())?;
        writeln!(
            out,
            "  {:<18} {:>5} {:<15} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:<14} {:<14} {:>7}",
            "name",
            "line",
            "status",
            "a1",
            "a2",
            "a3",
            "a4",
            "a5",
            "a6",
            "written",
            "solved",
            "margin"
        )?;
        for t in &f.targets {
            total += 1;
            *counts.entry(t.status.as_str()).or_insert(0) += 1;
            let joints: Vec<String> = match t.joints {
                Some(j) => j.iter().map(|v| format!("{v:.2}")).collect(),
                None => vec!["-".to_owned(); 6],
            };
            let margin = t
                .limit_margin_deg
                .map(|m| format!("{:.1}", m.iter().copied().fold(f64::INFINITY, f64::min)))
                .unwrap_or_else(|| "-".to_owned());
            writeln!(
                out,
                "  {:<18} {:>5} {:<15} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:<14} {:<14} {:>7}",
                t.name,
                t.line,
                t.status.as_str(),
                joints[0],
                joints[1],
                joints[2],
                joints[3],
                joints[4],
                joints[5],
                t.config_written.as_deref().unwrap_or("-"),
                t.config_solved.as_deref().unwrap_or("-"),
                margin
            )?;
            for w in &t.warnings {
                writeln!(out, "      warning: {w}")?;
            }
        }
    }
    let summary: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    writeln!(out, "{total} target(s): {}", summary.join(", "))?;
    Ok(())
}
