//! `trackfix correct | zero | mirror | transfer`.
//!
//! Every command: load the programs, compute every result in memory, report refusals (exit 3,
//! nothing written, unless `--skip-unsupported`), then either print a diff, check, or plan and
//! write all outputs atomically.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};

use trackfix::output::{self, Destination, Roots, unified_diff};
use trackfix::position::Program;
use trackfix::program::{LoadOptions, collect_inputs, load};
use trackfix::report::{FileSummary, would_change};
use trackfix::syntax::Severity;
use trackfix::track::{Profile, TrackError};
use trackfix::transform::cell::skid_axis_index;
use trackfix::transform::{
    Axis, Cell, ConfigRule, Direction, FrameIn, MirrorSettings, Plane, ProgramResult, Remedy,
    Robot, TrackSetup, TransferPlan, TransformStep, WorldPlane, apply, transfer,
};

use super::Exit;
use super::track::report_located;

/// Where results go and what to do with refusals (shared by all four commands).
#[derive(clap::Args, Debug)]
pub struct OutputArgs {
    /// Write the result to FILE (one program; a KRL pair writes FILE.src and FILE.dat).
    #[arg(short = 'o', long = "output", value_name = "FILE", conflicts_with_all = ["out_dir", "in_place"])]
    pub output: Option<PathBuf>,
    /// Write every result under its own file name into DIR (created if missing).
    #[arg(long, value_name = "DIR", conflicts_with = "in_place")]
    pub out_dir: Option<PathBuf>,
    /// Overwrite the input files, keeping FILE.orig backups.
    #[arg(long)]
    pub in_place: bool,
    /// With --in-place: keep no .orig backup.
    #[arg(long, requires = "in_place")]
    pub no_backup: bool,
    /// Print a unified diff of what would change; write nothing.
    #[arg(long, conflicts_with_all = ["check", "output", "out_dir", "in_place"])]
    pub diff: bool,
    /// Exit 1 if anything would change; write nothing.
    #[arg(long, conflicts_with_all = ["output", "out_dir", "in_place"])]
    pub check: bool,
    /// Leave unsupported targets (joint targets, 9E9 skids, …) unchanged instead of failing.
    #[arg(long)]
    pub skip_unsupported: bool,
}

const CORRECT_EXAMPLES: &str = "\
Examples:
  trackfix correct cad/spot_line.mod --cell samples/cell.toml --robot r1 -o spot_line.mod
  trackfix correct samples/krl/spot_line.src --cell samples/cell.toml --robot r1 --out-dir out/
  trackfix correct cad/*.mod --cell samples/cell.toml --robot r1 --diff

For every Cartesian target at skid s (its own external axis), in its work object W:
  T' = W⁻¹ · B(s) · D(s)⁻¹ · B(s)⁻¹ · W · T     (DESIGN.md §4)";

const ZERO_EXAMPLES: &str = "\
Examples:
  trackfix zero tuned/spot_line.mod --cell samples/cell.toml --robot r1 -o spot_line_zero.mod
  trackfix zero tuned/ --cell samples/cell.toml --robot r1 --check

The exact inverse of `correct`: T' = W⁻¹ · B(s) · D(s) · B(s)⁻¹ · W · T";

const MIRROR_EXAMPLES: &str = "\
Examples:
  trackfix mirror spot_line.mod --plane xz -o spot_line_m.mod
  trackfix mirror spot_line.mod --cell samples/cell.toml --robot r1 --skid-map 1,250 --diff
  trackfix mirror samples/krl/spot_line.src --plane xz --config keep --out-dir out/

T' = M · Sa · M⁻¹ · T · Sb in work-object coordinates; ABB cf1/cf4/cf6 → -cf-1 and KUKA Turn
bits of A1/A4/A6 toggled unless --config keep. Joint targets are refused unless --mirror-joints.";

const TRANSFER_EXAMPLES: &str = "\
Examples:
  trackfix transfer samples/krl/spot_line.src --cell samples/cell.toml \\
      --from r1 --to r2 --mirror --out-dir out/
  trackfix transfer tuned/ --cell samples/cell.toml --from r1 --to r2 --diff

zero with --from's track, mirror (with --mirror, plane from the cell's [mirror] table), then
correct with --to's track: the same bytes as running the three commands in a row.";

#[derive(clap::Args, Debug)]
#[command(after_help = CORRECT_EXAMPLES)]
pub struct CorrectArgs {
    /// RAPID modules, KRL programs (.src or .dat loads the pair) or folders.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The cell file: robots, track profiles, work objects (see samples/cell.toml).
    #[arg(long, value_name = "CELL.toml")]
    pub cell: PathBuf,
    /// The robot (a [robot.NAME] of the cell file) whose track the program runs on.
    #[arg(long)]
    pub robot: String,
    /// Work object (or KRL base, e.g. "BASE_DATA[3]") of declared targets no motion uses.
    #[arg(long, value_name = "NAME")]
    pub default_wobj: Option<String>,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(clap::Args, Debug)]
#[command(after_help = ZERO_EXAMPLES)]
pub struct ZeroArgs {
    #[command(flatten)]
    pub inner: CorrectArgs,
}

/// Mirror options shared by `mirror` and `transfer --mirror`; each overrides the cell's
/// `[mirror]` table.
#[derive(clap::Args, Debug)]
pub struct MirrorOptions {
    /// The plane of the work object (or of the cell's mirror frame) to mirror in.
    #[arg(long, value_enum)]
    pub plane: Option<Plane>,
    /// The tool axis flipped to keep the tool frame right-handed [default: y].
    #[arg(long, value_enum)]
    pub tool_flip: Option<Axis>,
    /// mirror: ABB cf1/cf4/cf6 → -cf-1, KUKA Turn A1/A4/A6 toggled; keep: unchanged [default: mirror].
    #[arg(long, value_enum)]
    pub config: Option<ConfigRule>,
    /// Skid map `s' = SCALE·s + OFFSET`, e.g. `1,250` [default: 1,0].
    #[arg(long, value_name = "SCALE,OFFSET", value_parser = parse_skid_map, allow_hyphen_values = true)]
    pub skid_map: Option<(f64, f64)>,
    /// Also mirror the program's wobjdata/tooldata/BASE_DATA/TOOL_DATA declarations.
    #[arg(long)]
    pub mirror_frames: bool,
    /// Mirror joint targets (axes 1, 4, 6 negated) instead of refusing them.
    #[arg(long)]
    pub mirror_joints: bool,
}

#[derive(clap::Args, Debug)]
#[command(after_help = MIRROR_EXAMPLES)]
pub struct MirrorArgs {
    /// RAPID modules, KRL programs (.src or .dat loads the pair) or folders.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// A cell file whose [mirror] table gives the plane, frame, tool flip, config and skid map.
    #[arg(long, value_name = "CELL.toml")]
    pub cell: Option<PathBuf>,
    /// The external axis holding the skid (eax_a … eax_f, E1 … E6) [default: --robot's `skid`
    /// in the cell, else eax_a / E1].
    #[arg(long, value_name = "AXIS")]
    pub skid: Option<String>,
    /// The mirror-image robot's skid axis, if it is another one: the skid moves there (and that
    /// axis's old value to --skid's place), as `transfer` does between robots.
    #[arg(long, value_name = "AXIS")]
    pub skid_to: Option<String>,
    /// The robot whose work objects place a world mirror plane (`frame_in = "world"`).
    #[arg(long, requires = "cell")]
    pub robot: Option<String>,
    /// Work object (or KRL base) of declared targets no motion uses (world mirror plane only).
    #[arg(long, value_name = "NAME")]
    pub default_wobj: Option<String>,
    #[command(flatten)]
    pub mirror: MirrorOptions,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(clap::Args, Debug)]
#[command(after_help = TRANSFER_EXAMPLES)]
pub struct TransferArgs {
    /// RAPID modules, KRL programs (.src or .dat loads the pair) or folders.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The cell file with both robots.
    #[arg(long, value_name = "CELL.toml")]
    pub cell: PathBuf,
    /// The robot the program was tuned on (its track is zeroed out).
    #[arg(long)]
    pub from: String,
    /// The robot the program is for (its track is corrected for).
    #[arg(long)]
    pub to: String,
    /// Mirror between the two (plane from the cell's [mirror] table or --plane).
    #[arg(long)]
    pub mirror: bool,
    /// Work object (or KRL base) of declared targets no motion uses.
    #[arg(long, value_name = "NAME")]
    pub default_wobj: Option<String>,
    #[command(flatten)]
    pub mirror_options: MirrorOptions,
    #[command(flatten)]
    pub out: OutputArgs,
}

fn parse_skid_map(s: &str) -> Result<(f64, f64), String> {
    let parse = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("`{t}` is not a number; write SCALE,OFFSET, e.g. 1,250"))
    };
    match s.split_once(',') {
        Some((a, b)) => Ok((parse(a)?, parse(b)?)),
        None => Err("write SCALE,OFFSET, e.g. 1,250 or -1,8000".to_owned()),
    }
}

fn load_programs(files: &[PathBuf], options: &LoadOptions) -> anyhow::Result<Vec<Program>> {
    let mut programs = Vec::new();
    for path in collect_inputs(files)? {
        match load(&path, options) {
            Ok(p) => programs.push(p),
            Err(e) if e.is_skip() => {
                let _ = writeln!(std::io::stderr(), "note: {e}");
            }
            Err(e) => return Err(e.into()),
        }
    }
    if programs.is_empty() {
        bail!("no program to transform among the inputs");
    }
    Ok(programs)
}

fn load_cell(path: &Path) -> anyhow::Result<Cell> {
    Ok(Cell::load(path)?)
}

fn load_profile(cell: &Cell, robot: &Robot) -> anyhow::Result<Profile> {
    match Profile::load(&robot.profile) {
        Err(TrackError::Io { error, .. }) => Err(cell.profile_error(robot, &error).into()),
        r => r.with_context(|| format!("profile of robot `{}`", robot.name)),
    }
}

fn load_options(robot: Option<&Robot>) -> LoadOptions {
    LoadOptions {
        krl_config_dat: robot.and_then(|r| r.config_dat.clone()),
    }
}

/// A `$config.dat` is loaded for its bases; it is written only if a transform changed it
/// (`--mirror-frames`), never copied along.
fn drop_untouched_config(results: &mut [ProgramResult], config_dat: Option<&Path>) {
    let Some(cfg) = config_dat else { return };
    for r in results {
        r.files.retain(|f| f.changed() || f.path != cfg);
    }
}

/// The command-line flag that gives a refusal's remedy.
fn remedy_flag(remedy: Remedy) -> &'static str {
    match remedy {
        Remedy::DefaultWorkObject => "pass --default-wobj NAME to transform unused targets in NAME",
        Remedy::MirrorJoints => "pass --mirror-joints to negate axes 1, 4 and 6",
    }
}

/// Reports refusals, then diffs, checks or writes. The one place outcomes become an exit code.
fn finish(
    command: &str,
    results: &[ProgramResult],
    out: &OutputArgs,
    inputs: &[PathBuf],
) -> anyhow::Result<Exit> {
    let mut stderr = std::io::stderr().lock();
    let refused: Vec<_> = results.iter().flat_map(|r| r.refusals()).collect();
    for r in &refused {
        // Skipped targets are reported as warnings: the run goes on without them.
        let (severity, outcome) = if out.skip_unsupported {
            (Severity::Warning, " (left unchanged)")
        } else {
            (
                Severity::Error,
                ", or pass --skip-unsupported to leave it unchanged",
            )
        };
        let advice = match r.remedy {
            Some(remedy) => remedy_flag(remedy),
            None => &r.hint,
        };
        writeln!(
            stderr,
            "{}",
            r.located(severity, format!("{advice}{outcome}"))
        )?;
    }
    if !refused.is_empty() && !out.skip_unsupported {
        writeln!(
            stderr,
            "error: {command} refused {} target(s); nothing written (fix them, or pass --skip-unsupported to leave them unchanged)",
            refused.len()
        )?;
        return Ok(Exit::Refused);
    }
    if out.diff {
        let mut stdout = std::io::stdout().lock();
        for f in results.iter().flat_map(|r| &r.files) {
            write!(stdout, "{}", unified_diff(&f.path, &f.original, &f.output))?;
        }
        return Ok(Exit::Ok);
    }
    if out.check {
        let mut any = false;
        for f in results.iter().flat_map(|r| &r.files) {
            if let Some(line) = would_change(f) {
                any = true;
                writeln!(stderr, "{line}")?;
            }
        }
        return Ok(if any { Exit::Findings } else { Exit::Ok });
    }
    write_outputs(command, results, out, inputs)
}

/// Writes the results (one transaction, `trackfix::output`) and lists every file written.
fn write_outputs(
    command: &str,
    results: &[ProgramResult],
    out: &OutputArgs,
    inputs: &[PathBuf],
) -> anyhow::Result<Exit> {
    let mut stderr = std::io::stderr().lock();
    if results.iter().all(|r| r.files.is_empty()) {
        // Only a `$config.dat` was given: it is read for its bases and written only when a
        // transform changes it.
        bail!(
            "nothing written: {} holds no program to {command} (a $config.dat is read for its bases and written only when a transform changes it; name the programs that use it)",
            inputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let dest = if let Some(o) = &out.output {
        if o.as_os_str() == "-" {
            let bytes = output::stream_output(results)?;
            let mut stdout = std::io::stdout().lock();
            stdout.write_all(bytes)?;
            stdout.flush()?;
            // The output is complete: a summary that cannot be shown changes nothing.
            let _ = summarize(command, results, &[], &mut stderr);
            return Ok(Exit::Ok);
        }
        Destination::File(o.clone())
    } else if let Some(d) = &out.out_dir {
        Destination::Dir(d.clone())
    } else if out.in_place {
        Destination::InPlace {
            backup: !out.no_backup,
        }
    } else {
        bail!(
            "say where to write: -o FILE (- for standard output), --out-dir DIR or --in-place (or preview with --diff, --check)"
        );
    };
    let writes = output::plan(results, &dest, &Roots::from_inputs(inputs))?;
    let written = output::commit(&writes)?;
    // The files are written: a summary that cannot be shown (stderr full or closed) changes
    // nothing about the outcome.
    if written.is_empty() {
        let _ = writeln!(stderr, "note: nothing written: no file changed");
    }
    let _ = summarize(command, results, &written, &mut stderr);
    Ok(Exit::Ok)
}

/// One line per input file: what changed, and every file written for it.
fn summarize(
    command: &str,
    results: &[ProgramResult],
    written: &[output::Written],
    stderr: &mut impl std::io::Write,
) -> anyhow::Result<Exit> {
    for f in results.iter().flat_map(|r| &r.files) {
        let mut summary = FileSummary::new(f, command == "mirror");
        if let Some(w) = written.iter().find(|w| w.input == f.path) {
            summary.written_to = Some(w.path.clone());
            summary.link_target.clone_from(&w.resolved);
            summary.backup.clone_from(&w.backup);
        }
        writeln!(stderr, "{summary}")?;
    }
    Ok(Exit::Ok)
}

/// The one runner of every transform: load each program (with `robot`'s `$config.dat`), run
/// `transform` on it in memory, then report, diff, check or write everything at once.
fn run_each(
    command: &str,
    files: &[PathBuf],
    robot: Option<&Robot>,
    other_configs: &[Option<&Path>],
    out: &OutputArgs,
    transform: impl Fn(&Program) -> anyhow::Result<ProgramResult>,
) -> anyhow::Result<Exit> {
    let programs = load_programs(files, &load_options(robot))?;
    let mut results = Vec::new();
    for p in &programs {
        results.push(transform(p)?);
    }
    drop_untouched_config(&mut results, robot.and_then(|r| r.config_dat.as_deref()));
    for cfg in other_configs {
        drop_untouched_config(&mut results, *cfg);
    }
    finish(command, &results, out, files)
}

/// [`run_each`] for one transform step.
fn run_step(
    command: &str,
    files: &[PathBuf],
    robot: Option<&Robot>,
    step: TransformStep,
    out: &OutputArgs,
) -> anyhow::Result<Exit> {
    run_each(command, files, robot, &[], out, |p| {
        Ok(apply(p, step.edits(p))?)
    })
}

fn run_track(a: CorrectArgs, dir: Direction) -> anyhow::Result<Exit> {
    let cell = load_cell(&a.cell)?;
    let robot = cell.robot(&a.robot)?;
    let profile = load_profile(&cell, robot)?;
    let mut setup = TrackSetup::new(robot, &profile);
    setup.default_wobj = a.default_wobj.clone();
    run_step(
        dir.as_str(),
        &a.files,
        Some(robot),
        TransformStep::Track(&setup, dir),
        &a.out,
    )
}

pub fn run_correct(a: CorrectArgs) -> anyhow::Result<Exit> {
    report_located(run_correct_inner(a))
}

fn run_correct_inner(a: CorrectArgs) -> anyhow::Result<Exit> {
    run_track(a, Direction::Correct)
}

pub fn run_zero(a: ZeroArgs) -> anyhow::Result<Exit> {
    report_located(run_zero_inner(a))
}

fn run_zero_inner(a: ZeroArgs) -> anyhow::Result<Exit> {
    run_track(a.inner, Direction::Zero)
}

/// The mirror from the cell's `[mirror]` table, overridden by the command line. A plane given
/// in world (`frame_in = "world"`) resolves work objects with `robot`'s cell entries, then the
/// program's declarations.
fn mirror_settings(
    cell: Option<&Cell>,
    o: &MirrorOptions,
    skid_axis: usize,
    robot: Option<&Robot>,
    default_wobj: Option<&str>,
) -> MirrorSettings {
    let table = cell.map(|c| c.mirror.clone()).unwrap_or_default();
    let d = MirrorSettings::default();
    let world = (table.frame_in == FrameIn::World).then(|| WorldPlane {
        frame: table.frame.unwrap_or(d.frame),
        frames: robot.map(|r| r.frames.clone()).unwrap_or_default(),
        default_wobj: default_wobj.map(str::to_owned),
    });
    MirrorSettings {
        frame: match world {
            Some(_) => d.frame,
            None => table.frame.unwrap_or(d.frame),
        },
        world,
        plane: o.plane.or(table.plane).unwrap_or(d.plane),
        tool_flip: o.tool_flip.or(table.tool_flip).unwrap_or(d.tool_flip),
        config: o.config.or(table.config).unwrap_or(d.config),
        skid_map: o.skid_map.or(table.skid_map).unwrap_or(d.skid_map),
        skid_axis,
        skid_axis_to: None,
        mirror_frames: o.mirror_frames,
        mirror_joints: o.mirror_joints,
        arm: robot.and_then(|r| trackfix::transform::MirrorArm::of(r, default_wobj)),
    }
}

pub fn run_mirror(a: MirrorArgs) -> anyhow::Result<Exit> {
    report_located(run_mirror_inner(a))
}

fn run_mirror_inner(a: MirrorArgs) -> anyhow::Result<Exit> {
    let cell = a.cell.as_deref().map(load_cell).transpose()?;
    let robot = match (&cell, &a.robot) {
        (Some(c), Some(name)) => Some(c.robot(name)?),
        (None, Some(_)) => bail!("--robot needs --cell"),
        _ => None,
    };
    let axis = |flag: &str, s: &str| {
        skid_axis_index(s).with_context(|| format!("--{flag} {s}: use eax_a … eax_f or E1 … E6"))
    };
    let skid_axis = match &a.skid {
        Some(s) => axis("skid", s)?,
        None => robot.map_or(0, |r| r.skid_axis),
    };
    let settings = MirrorSettings {
        skid_axis_to: a
            .skid_to
            .as_deref()
            .map(|s| axis("skid-to", s))
            .transpose()?,
        ..mirror_settings(
            cell.as_ref(),
            &a.mirror,
            skid_axis,
            robot,
            a.default_wobj.as_deref(),
        )
    };
    run_step(
        "mirror",
        &a.files,
        robot,
        TransformStep::Mirror(&settings),
        &a.out,
    )
}

pub fn run_transfer(a: TransferArgs) -> anyhow::Result<Exit> {
    report_located(run_transfer_inner(a))
}

fn run_transfer_inner(a: TransferArgs) -> anyhow::Result<Exit> {
    let cell = load_cell(&a.cell)?;
    let from = cell.robot(&a.from)?;
    let to = cell.robot(&a.to)?;
    let from_profile = load_profile(&cell, from)?;
    let to_profile = load_profile(&cell, to)?;
    let mut plan = TransferPlan {
        from: TrackSetup::new(from, &from_profile),
        mirror: a.mirror.then(|| MirrorSettings {
            skid_axis_to: Some(to.skid_axis),
            ..mirror_settings(
                Some(&cell),
                &a.mirror_options,
                from.skid_axis,
                Some(from),
                a.default_wobj.as_deref(),
            )
        }),
        to: TrackSetup::new(to, &to_profile),
    };
    plan.from.default_wobj = a.default_wobj.clone();
    plan.to.default_wobj = a.default_wobj.clone();
    let written = load_options(Some(to));
    run_each(
        "transfer",
        &a.files,
        Some(from),
        &[to.config_dat.as_deref()],
        &a.out,
        |p| Ok(transfer(p, &plan, &written)?),
    )
}
