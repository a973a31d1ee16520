//! `trackfix inspect` and `trackfix check`.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use trackfix::position::{Program, external_axis_index};
use trackfix::program::{LoadError, LoadOptions, collect_inputs, load};
use trackfix::report::{
    CheckSummary, InspectOptions, InspectReport, findings, inspect_program, render_csv,
    render_table,
};

use super::Exit;

#[derive(Clone, Copy, Debug, Default, clap::ValueEnum)]
pub enum Format {
    /// Aligned columns for people.
    #[default]
    Table,
    /// `{"files": [...]}`: a stable shape for scripts.
    Json,
    /// One row per position.
    Csv,
}

const INSPECT_EXAMPLES: &str = "\
Examples:
  trackfix inspect samples/rapid/spot_line.mod
  trackfix inspect samples/ --format json > positions.json
  trackfix inspect samples/krl/spot_line.src --config-dat 'samples/krl/$config.dat' --format csv

Directories are searched recursively for .mod .modx .sys .sysx .prg (RAPID) and .src .dat .sub
(KRL). Naming a KRL .src or .dat reads the pair.";

/// List every position, work object and tool in RAPID/KRL programs.
#[derive(clap::Args)]
#[command(after_help = INSPECT_EXAMPLES)]
pub struct InspectArgs {
    /// Program files or directories (searched recursively).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
    /// External axis that holds the skid position (eax_a..eax_f, E1..E6).
    #[arg(long, default_value = "eax_a", value_parser = parse_axis)]
    pub skid: usize,
    /// KUKA $config.dat whose BASE_DATA/TOOL_DATA resolve KRL bases and tools.
    #[arg(long, value_name = "FILE")]
    pub config_dat: Option<PathBuf>,
    /// The cell file: with --robot, adds each target's reach and joints (the robot needs
    /// [robot.NAME.kinematics]).
    #[arg(long, value_name = "FILE", requires = "robot")]
    pub cell: Option<PathBuf>,
    /// The robot of --cell whose arm solves the targets.
    #[arg(long, requires = "cell")]
    pub robot: Option<String>,
}

const CHECK_EXAMPLES: &str = "\
Examples:
  trackfix check samples/
  trackfix check MainModule.mod CalibData.sys

Exit codes: 0 every file round-trips and is clean, 1 findings, 2 a file could not be read.";

/// Verify the byte-exact round trip and lint programs (exit 1 on findings).
///
/// Lints: syntax errors and constructs kept verbatim, non-normalised quaternions, a target used
/// with two work objects or bases, names declared twice.
#[derive(clap::Args)]
#[command(after_help = CHECK_EXAMPLES)]
pub struct CheckArgs {
    /// Program files or directories (searched recursively).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// KUKA $config.dat whose BASE_DATA/TOOL_DATA resolve KRL bases and tools.
    #[arg(long, value_name = "FILE")]
    pub config_dat: Option<PathBuf>,
}

fn parse_axis(name: &str) -> Result<usize, String> {
    external_axis_index(name)
        .ok_or_else(|| format!("`{name}` is not an external axis; use eax_a..eax_f or E1..E6"))
}

/// Loads every program named, reporting progress on a terminal. Skipped files (binary,
/// RobotStudio XML) get a note; unreadable files are errors, and the batch goes on.
struct Batch {
    programs: Vec<Program>,
    errors: usize,
    skipped: usize,
}

fn load_all(files: &[PathBuf], options: &LoadOptions) -> anyhow::Result<Batch> {
    let inputs = collect_inputs(files).context("listing the input files")?;
    let bar = if std::io::stderr().is_terminal() && inputs.len() > 20 {
        let bar = ProgressBar::new(inputs.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} {wide_msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let mut batch = Batch {
        programs: Vec::new(),
        errors: 0,
        skipped: 0,
    };
    for path in &inputs {
        bar.set_message(path.display().to_string());
        match load(path, options) {
            Ok(p) => batch.programs.push(p),
            Err(e) if e.is_skip() => {
                bar.suspend(|| {
                    let _ = writeln!(std::io::stderr(), "note: {e}");
                });
                batch.skipped += 1;
            }
            Err(e) => {
                bar.suspend(|| {
                    let _ = writeln!(std::io::stderr(), "error: {e}");
                });
                if matches!(e, LoadError::UnknownType { .. }) {
                    bar.suspend(|| {
                        let _ = writeln!(
                            std::io::stderr(),
                            "  = help: name RAPID or KRL files, or a directory"
                        );
                    });
                }
                batch.errors += 1;
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(batch)
}

pub fn run_inspect(args: InspectArgs) -> anyhow::Result<Exit> {
    let cell = match (&args.cell, &args.robot) {
        (Some(c), Some(r)) => {
            let cell = trackfix::transform::Cell::load(c)?;
            let robot = cell.robot(r)?.clone();
            if robot.kinematics.is_none() {
                anyhow::bail!(
                    "{}: robot `{r}` has no [robot.{r}.kinematics] table; add `model = \"NAME\"` or the OPW lengths",
                    c.display()
                );
            }
            Some(robot)
        }
        _ => None,
    };
    let options = LoadOptions {
        krl_config_dat: match (&args.config_dat, &cell) {
            (None, Some(r)) => r.config_dat.clone(),
            (c, _) => c.clone(),
        },
    };
    let batch = load_all(&args.files, &options)?;
    let inspect = InspectOptions {
        skid_axis: args.skid,
    };
    let mut report = InspectReport {
        files: batch
            .programs
            .iter()
            .flat_map(|p| inspect_program(p, inspect))
            .collect(),
    };
    if let Some(robot) = &cell
        && let Some(kin) = &robot.kinematics
    {
        for p in &batch.programs {
            let reach =
                trackfix::kinematics::reach::reach_program(p, robot, kin, &Default::default());
            report.add_reach(&reach);
        }
    }
    let text = match args.format {
        Format::Table => render_table(&report),
        Format::Json => {
            let mut s = serde_json::to_string_pretty(&report)?;
            s.push('\n');
            s
        }
        Format::Csv => render_csv(&report),
    };
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    if matches!(args.format, Format::Table) {
        // writeln!, not println!: a closed pipe must be an error we can map to success.
        writeln!(out, "{}", report.summary_line(batch.skipped, batch.errors))?;
    }
    Ok(if batch.errors > 0 {
        Exit::Usage
    } else {
        Exit::Ok
    })
}

pub fn run_check(args: CheckArgs) -> anyhow::Result<Exit> {
    let options = LoadOptions {
        krl_config_dat: args.config_dat.clone(),
    };
    let batch = load_all(&args.files, &options)?;
    let mut out = std::io::stdout().lock();
    let mut summary = CheckSummary {
        skipped: batch.skipped,
        unreadable: batch.errors,
        ..CheckSummary::default()
    };
    for program in &batch.programs {
        for file in &program.files {
            let found = findings(file);
            summary.add_file(file, found.len());
            for d in &found {
                write!(out, "{}", file.render(d))?;
            }
        }
    }
    writeln!(out, "{summary}")?;
    let findings = summary.findings;
    Ok(if batch.errors > 0 {
        Exit::Usage
    } else if findings > 0 {
        Exit::Findings
    } else {
        Exit::Ok
    })
}
