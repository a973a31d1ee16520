//! `trackfix inspect` and `trackfix check`.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use trackfix::position::{Program, external_axis_index};
use trackfix::program::{LoadError, LoadOptions, collect_programs, load_group};
use trackfix::report::{
    CheckSummary, InspectJson, InspectOptions, InspectReport, ProgramReport, findings,
    inspect_program, render_csv, render_table,
};
use trackfix::syntax::printable;

use super::Exit;
use super::messages::{Messages, Verbosity, shape};

#[derive(Clone, Copy, Debug, Default, clap::ValueEnum)]
pub(crate) enum Format {
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
pub(crate) struct InspectArgs {
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
pub(crate) struct CheckArgs {
    /// Program files or directories (searched recursively).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// KUKA $config.dat whose BASE_DATA/TOOL_DATA resolve KRL bases and tools.
    #[arg(long, value_name = "FILE")]
    pub config_dat: Option<PathBuf>,
    /// `json`: `{"files": [{"path", "stamp", "findings": [...]}], "summary": {...}}` on
    /// standard output.
    #[arg(long, value_enum, default_value_t = super::transform::ReportFormat::Text)]
    pub format: super::transform::ReportFormat,
    // `-q`: errors only (the exit code still counts every finding); `-v`: every finding.
    #[command(flatten)]
    pub verbosity: Verbosity,
}

/// One file of `check --format json`.
#[derive(serde::Serialize)]
struct CheckedFile {
    path: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    stamp: Option<trackfix::transform::Stamp>,
    findings: Vec<trackfix::report::Message>,
}

fn parse_axis(name: &str) -> Result<usize, String> {
    external_axis_index(name)
        .ok_or_else(|| format!("`{name}` is not an external axis; use eax_a..eax_f or E1..E6"))
}

/// Loads every program named, reporting progress on a terminal. Skipped files (binary,
/// RobotStudio XML) get a note; unreadable files are errors, and the batch goes on.
struct Batch {
    programs: Vec<Program>,
    /// Programs loaded from several inputs together (a RAPID task, a KSS tree): reported as such.
    grouped: Vec<bool>,
    errors: usize,
    skipped: usize,
}

fn load_all(files: &[PathBuf], options: &LoadOptions) -> anyhow::Result<Batch> {
    let groups = collect_programs(files).context("listing the input files")?;
    let count: usize = groups.iter().map(Vec::len).sum();
    if count == 0 {
        let names: Vec<_> = files.iter().map(|p| p.display().to_string()).collect();
        anyhow::bail!(
            "no RAPID or KRL program in {} (looked for .mod .modx .sys .sysx .prg .src .dat .sub)",
            names.join(", ")
        );
    }
    let bar = if std::io::stderr().is_terminal() && count > 20 {
        let bar = ProgressBar::new(count as u64);
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
        grouped: Vec::new(),
        errors: 0,
        skipped: 0,
    };
    for group in groups {
        let label = group
            .first()
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        bar.set_message(label);
        let n = group.len() as u64;
        for loaded in load_group(&group, options) {
            match loaded {
                Ok(p) => {
                    batch.programs.push(p);
                    batch.grouped.push(n > 1);
                }
                // A file named on the command line is meant to be a program: one that is not
                // is an error, not a silent skip (a control byte must not bypass `check`).
                Err(e) if e.is_skip() && !files.iter().any(|f| f == e.path()) => {
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
        }
        bar.inc(n);
    }
    bar.finish_and_clear();
    Ok(batch)
}

pub(crate) fn run_inspect(args: InspectArgs) -> anyhow::Result<Exit> {
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
        // `inspect` writes nothing.
        map_inputs: true,
        ..LoadOptions::default()
    };
    let batch = load_all(&args.files, &options)?;
    let inspect = InspectOptions {
        skid_axis: args.skid,
    };
    let exit = if batch.errors > 0 {
        Exit::Usage
    } else {
        Exit::Ok
    };
    if matches!(args.format, Format::Json) && cell.is_none() {
        // Written as it is built: the rows of a large program never all exist at once.
        let doc = InspectJson {
            programs: &batch.programs,
            grouped: &batch.grouped,
            options: inspect,
        };
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        serde_json::to_writer_pretty(&mut out, &doc).map_err(std::io::Error::from)?;
        out.write_all(b"\n")?;
        out.flush()?;
        super::leave_for_exit(batch);
        return Ok(exit);
    }
    let mut report = InspectReport {
        files: batch
            .programs
            .iter()
            .flat_map(|p| inspect_program(p, inspect))
            .collect(),
        programs: batch
            .programs
            .iter()
            .zip(&batch.grouped)
            .filter(|(_, g)| **g)
            .filter_map(|(p, _)| ProgramReport::of(p))
            .collect(),
    };
    if let Some(robot) = &cell
        && let Some(kin) = &robot.kinematics
    {
        // The reach reads the cell's entries as the transforms do: what they make of the
        // program's declarations is said as the transforms say it.
        super::transform::show_readings(
            &batch.programs,
            &[robot],
            super::transform::Readings::Cell,
            Default::default(),
        )?;
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
    super::leave_for_exit((batch, report, text));
    Ok(exit)
}

pub(crate) fn run_check(args: CheckArgs) -> anyhow::Result<Exit> {
    let options = LoadOptions {
        krl_config_dat: args.config_dat.clone(),
        // `check` writes nothing.
        map_inputs: true,
        ..LoadOptions::default()
    };
    let batch = load_all(&args.files, &options)?;
    let mut out = std::io::stdout().lock();
    let mut summary = CheckSummary {
        skipped: batch.skipped,
        unreadable: batch.errors,
        ..CheckSummary::default()
    };
    let json = args.format == super::transform::ReportFormat::Json;
    let mut checked = Vec::new();
    let mut program_reports = Vec::new();
    // Findings of one kind across the batch: three shown, the rest counted (`-v`: all).
    let mut messages = Messages::new(args.verbosity, false);
    let quiet = args.verbosity.quiet;
    for (program, grouped) in batch.programs.iter().zip(&batch.grouped) {
        for file in &program.files {
            if json {
                let found = findings(file);
                summary.add_file(file, found.len());
                checked.push(CheckedFile {
                    path: file.path.display().to_string(),
                    stamp: trackfix::transform::stamp::find(file).map(|(s, _)| s),
                    findings: found
                        .iter()
                        .map(|d| trackfix::report::message(file, d))
                        .collect(),
                });
                continue;
            }
            if let Some((stamp, _)) = trackfix::transform::stamp::find(file).filter(|_| !quiet) {
                writeln!(
                    out,
                    "{}: stamped: {}",
                    printable(&file.path.display().to_string()),
                    printable(&stamp.text())
                )?;
            }
            let found = findings(file);
            summary.add_file(file, found.len());
            for d in &found {
                let text = file.render(d);
                let text = text.strip_suffix('\n').unwrap_or(&text);
                messages.show(&mut out, d.severity, &shape(&d.message), &text)?;
            }
        }
        // A program of several inputs: which files form it and how much of it resolved.
        // JSON keeps standard output one document: the programs are a list in it.
        if let Some(report) = grouped.then(|| ProgramReport::of(program)).flatten() {
            if json {
                program_reports.push(report);
            } else if !quiet {
                writeln!(out, "{report}: {}", report.files.join(", "))?;
            }
        }
    }
    if json {
        let doc = serde_json::json!({ "files": checked, "programs": program_reports, "summary": summary });
        writeln!(out, "{}", serde_json::to_string_pretty(&doc)?)?;
    } else {
        messages.finish(&mut out)?;
        if !quiet {
            writeln!(out, "{summary}")?;
        }
    }
    let findings = summary.findings;
    let exit = if batch.errors > 0 {
        Exit::Usage
    } else if findings > 0 {
        Exit::Findings
    } else {
        Exit::Ok
    };
    super::leave_for_exit((batch, checked));
    Ok(exit)
}
