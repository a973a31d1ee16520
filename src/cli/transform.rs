//! `trackfix correct | zero | mirror | transfer`.
//!
//! Every command: load the programs (a syntax error stops the run, exit 2), check their
//! provenance stamps, compute every result in memory, report refusals (exit 3, nothing written,
//! unless their kinds are kept with `--keep`/`--skip-unsupported`: exit 4 once written), then
//! either print a diff, check, or plan and write all outputs atomically, stamped.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};

use trackfix::html_report::{RunFile, RunInput, RunReport, run_report};
use trackfix::output::{self, Destination, Roots, unified_diff};
use trackfix::position::Program;
use trackfix::program::{LoadOptions, collect_programs, load_group};
use trackfix::report::{FileSummary, would_change};
use trackfix::syntax::{Severity, printable};
use trackfix::track::cell_nominal::check_cell_nominal;
use trackfix::track::uncertainty::ProfileUncertainty;
use trackfix::track::{Profile, TrackError};
use trackfix::transform::cell::{SkidMapWay, skid_axis_index, skid_map_hint};
use trackfix::transform::mirror::{SkidMapMismatch, inverse_skid_map};
use trackfix::transform::rename::{Renamed, rename_program};
use trackfix::transform::stamp;
use trackfix::transform::{
    Axis, Cell, ConfigRule, Direction, FrameIn, MirrorSettings, Plane, ProgramResult, RefusalKind,
    Remedy, Robot, Stamp, TrackSetup, TransferPlan, TransformStep, WorldPlane, apply_owned,
    transfer,
};

use super::Exit;
use super::messages::{Messages, Verbosity, shape};
use super::track::report_located;

/// Where results go and what to do with refusals (shared by all four commands).
#[derive(clap::Args, Debug)]
pub(crate) struct OutputArgs {
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
    /// Leave targets refused for this reason unchanged instead of failing (repeatable, or
    /// comma-separated); the run then exits 4 and lists them.
    #[arg(long, value_name = "KIND", value_enum, value_delimiter = ',')]
    pub keep: Vec<RefusalKind>,
    /// Leave every refused target unchanged instead of failing: --keep for all kinds (exit 4
    /// when any was left).
    #[arg(long)]
    pub skip_unsupported: bool,
    /// Add no provenance stamp (the comment line after the header naming command, robot,
    /// profile and version); the output then differs from the input only in changed numbers.
    #[arg(long)]
    pub no_stamp: bool,
    /// Transform even a file whose stamp says it must not be: `correct` of a file already
    /// corrected for the robot, `zero` of a file not stamped as corrected for it.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub verbosity: Verbosity,
    /// `json`: the summary, refusals and notes as one JSON document on standard output
    /// (nothing on standard error but a failure).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text, conflicts_with = "diff")]
    pub format: ReportFormat,
    /// Also write a self-contained HTML record of the run (inputs with their hashes, every
    /// changed target old and new, refusals): what is handed over at buy-off.
    #[arg(long, value_name = "FILE.html")]
    pub report: Option<PathBuf>,
    /// The files the run read besides its programs (cell, profiles), for the report.
    #[arg(skip)]
    pub also_read: Vec<(String, PathBuf)>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ReportFormat {
    #[default]
    Text,
    Json,
}

/// One refusal or note in `--format json`.
#[derive(serde::Serialize)]
struct JsonRefusal<'a> {
    #[serde(flatten)]
    refusal: &'a trackfix::transform::Refusal,
    /// `true`: left as written (`--keep`), `false`: it stopped the run.
    kept: bool,
}

/// `--format json` of a transform run.
#[derive(serde::Serialize)]
struct JsonReport<'a> {
    command: &'a str,
    exit: u8,
    files: Vec<FileSummary>,
    refusals: Vec<JsonRefusal<'a>>,
    notes: Vec<&'a trackfix::transform::Refusal>,
    renamed: &'a [Renamed],
    totals: Totals,
}

/// The one line a run ends with (a batch of several programs), and its JSON.
#[derive(Debug, Default, serde::Serialize)]
struct Totals {
    programs: usize,
    files: usize,
    changed_files: usize,
    written: usize,
    targets_changed: usize,
    refused: usize,
    kept: usize,
    notes: usize,
}

impl Totals {
    fn of(results: &[ProgramResult], written: usize, out: &OutputArgs) -> Totals {
        let files = results.iter().flat_map(|r| &r.files);
        let refusals: Vec<_> = results.iter().flat_map(|r| r.refusals()).collect();
        Totals {
            programs: results.len(),
            files: files.clone().count(),
            changed_files: files.clone().filter(|f| f.changed()).count(),
            written,
            targets_changed: files.clone().map(|f| f.changes.len()).sum(),
            refused: refusals.iter().filter(|r| !out.keeps(r.kind)).count(),
            kept: refusals.iter().filter(|r| out.keeps(r.kind)).count(),
            notes: files.map(|f| f.notes.len()).sum(),
        }
    }
}

impl std::fmt::Display for Totals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "total: {} programs ({} files): {} target(s) changed in {} files, {} written, {} refused, {} kept as written, {} notes",
            self.programs,
            self.files,
            self.targets_changed,
            self.changed_files,
            self.written,
            self.refused,
            self.kept,
            self.notes
        )
    }
}

/// Prints the JSON report of a run (`--format json`) and passes its exit code on.
fn json_report(
    command: &str,
    results: &[ProgramResult],
    summaries: Vec<FileSummary>,
    renamed: &[Renamed],
    written: usize,
    out: &OutputArgs,
    exit: Exit,
) -> anyhow::Result<Exit> {
    let report = JsonReport {
        command,
        exit: exit as u8,
        files: summaries,
        refusals: results
            .iter()
            .flat_map(|r| r.refusals())
            .map(|r| JsonRefusal {
                refusal: r,
                kept: out.keeps(r.kind),
            })
            .collect(),
        notes: results
            .iter()
            .flat_map(|r| r.files.iter().flat_map(|f| &f.notes))
            .collect(),
        renamed,
        totals: Totals::of(results, written, out),
    };
    let mut text = serde_json::to_string_pretty(&report)?;
    text.push('\n');
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes())?;
    stdout.flush()?;
    Ok(exit)
}

/// The stamp a run writes and what the stamps already in the files must say.
struct Provenance {
    stamp: Stamp,
    rule: StampRule,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum StampRule {
    /// Nothing required.
    Any,
    /// `correct`: no file may already be corrected for the robot.
    NotCorrected,
    /// `zero`: some file must be stamped as corrected for the robot.
    Corrected,
    /// `mirror`: no file may be corrected for any robot. Its image would carry that robot's
    /// track deviation, mirrored, and its stamp would no longer say so: a later `correct` for
    /// the other robot would add that robot's on top.
    NotCorrectedForAny,
}

impl Provenance {
    fn new(
        command: &str,
        robot: Option<&Robot>,
        profile: Option<&Profile>,
        rule: StampRule,
    ) -> Self {
        let hash = profile.map(Profile::data_sha256);
        Provenance {
            stamp: Stamp::new(
                command,
                robot.map(|r| r.name.as_str()),
                profile.zip(hash.as_deref()).map(|(p, h)| (p.name(), h)),
            ),
            rule,
        }
    }
}

/// Refuses (exit 3) a `correct` of a program already corrected for the robot, a `zero` of one
/// with targets never corrected for it and a `mirror` of one corrected for any robot, unless
/// `--force`.
fn check_stamps(
    command: &str,
    programs: &[Program],
    prov: &Provenance,
    out: &OutputArgs,
) -> anyhow::Result<Option<Exit>> {
    if out.force {
        return Ok(None);
    }
    let mut stderr = std::io::stderr().lock();
    let mut refused = 0;
    // A record of targets kept as written that no longer fits its file says nothing of which
    // targets carry the stamp's change: every transform reads it (the one undoing the stamp's
    // leaves them as written, any other refuses them).
    for p in programs {
        let mut out_of_step = false;
        for f in &p.files {
            let Some((s, span)) = stamp::find(f) else {
                continue;
            };
            let Some(why) = s.kept.out_of_step(f) else {
                continue;
            };
            out_of_step = true;
            let (line, _) = f.lines.line_col(span.start);
            writeln!(
                stderr,
                "error: {}:{line}: its stamp lists targets left as written, but {}: which targets carry what `{}` did is not known\n  = help: transform the file as that run wrote it, or pass --force to transform every target alike",
                printable(&f.path.display().to_string()),
                printable(&why),
                printable(&s.command)
            )?;
        }
        refused += usize::from(out_of_step);
    }
    if refused > 0 || prov.rule == StampRule::Any {
        return refused_by_stamps(command, refused, &mut stderr);
    }
    if prov.rule == StampRule::NotCorrectedForAny {
        for p in programs {
            let corrected: Vec<_> = p
                .files
                .iter()
                .filter_map(|f| Some((f, stamp::find(f)?)))
                .filter_map(|(f, (s, span))| {
                    let robot = s.robot.clone().filter(|r| s.corrected_for(r))?;
                    Some((f, s, span, robot))
                })
                .collect();
            refused += usize::from(!corrected.is_empty());
            for (f, s, span, robot) in corrected {
                let (line, _) = f.lines.line_col(span.start);
                // The name is the file's text: shown escaped, as the stamp is.
                let robot = printable(&robot);
                writeln!(
                    stderr,
                    "error: {}:{line}: corrected for robot `{robot}` ({}): its mirror image would carry that track's deviation, mirrored, to the other robot\n  = help: mirror the original (or `zero` this one first), or `transfer --from {robot} --to OTHER --mirror`, which takes the deviation out first; pass --force if the stamp is wrong",
                    printable(&f.path.display().to_string()),
                    printable(&s.text())
                )?;
            }
        }
        return refused_by_stamps(command, refused, &mut stderr);
    }
    let Some(robot) = prov.stamp.robot.as_deref() else {
        return Ok(None);
    };
    for p in programs {
        let stamps: Vec<_> = p
            .files
            .iter()
            .filter_map(|f| Some((f, stamp::find(f)?)))
            .collect();
        let corrected = stamps.iter().find(|(_, (s, _))| s.corrected_for(robot));
        let name = p
            .files
            .first()
            .map(|f| f.path.display().to_string())
            .unwrap_or_default();
        match (prov.rule, corrected) {
            (StampRule::NotCorrected, Some((f, (s, span)))) => {
                refused += 1;
                let (line, _) = f.lines.line_col(span.start);
                // The targets it left as written lack the correction: the original is where
                // they are corrected once fixed, with the rest.
                let but = match s.kept.targets.len() {
                    0 => String::new(),
                    n => format!(
                        ", but for the {n} target(s) it left as written, which the original corrects once they are fixed"
                    ),
                };
                writeln!(
                    stderr,
                    "error: {}:{line}: already corrected for robot `{robot}` ({}): correcting again would apply the track's deviation twice{but}\n  = help: correct the original, `zero` this one first, or pass --force if the stamp is wrong",
                    printable(&f.path.display().to_string()),
                    printable(&s.text())
                )?;
            }
            // A program without targets has nothing for `correct` to have changed (so no
            // stamp) and nothing for `zero` to change: a KSS tree's system files, say.
            (StampRule::Corrected, None) if p.files.iter().any(|f| !f.positions.is_empty()) => {
                refused += 1;
                writeln!(
                    stderr,
                    "error: {}: no stamp says it is corrected for robot `{robot}`: zero removes a correction, and this file shows none\n  = help: pass --force to zero it anyway (an online-tuned program taught on the real track, or one corrected with --no-stamp)",
                    printable(&name)
                )?;
            }
            _ => {}
        }
    }
    refused_by_stamps(command, refused, &mut stderr)
}

/// The run's end when its stamps refused `refused` programs (or files): nothing is written.
fn refused_by_stamps(
    command: &str,
    refused: usize,
    stderr: &mut impl Write,
) -> anyhow::Result<Option<Exit>> {
    if refused == 0 {
        return Ok(None);
    }
    writeln!(
        stderr,
        "error: {command} refused {refused} program(s) by their provenance stamp; nothing written"
    )?;
    Ok(Some(Exit::Refused))
}

/// Writes the stamp into every file the run changed (unless `--no-stamp`), after giving back the
/// first-written decimals of the values the run brought back (`stamp::carry_precision`).
///
/// A `zero` of a file stamped as corrected for the same robot with the same profile that leaves
/// no literal widened removes the stamp: the file is again as it was before `correct`.
///
/// A `correct` also records the A of each KUKA target written at B = ±90° (`gimbal=`), so a
/// `zero` can give back the split the file had.
fn stamp_results(
    lock_splits: &[(PathBuf, stamp::LockSplits)],
    results: &mut [ProgramResult],
    prov: &Provenance,
    out: &OutputArgs,
) {
    for r in results.iter_mut() {
        // A file whose every target was left as written is stamped all the same where another
        // file of its program is: unstamped, their stamps would speak for it. And one whose
        // stamp listed its targets as left as written gets the stamp of the run that read them.
        let stamped = r.changed();
        for f in &mut r.files {
            let lists = || {
                trackfix::dialect::dialect_of(&f.path)
                    .and_then(|d| stamp::find_stamp(&f.original, d))
                    .is_some_and(|(s, _)| !s.kept.is_empty())
            };
            if f.changed() || (stamped && (!f.kept.is_empty() || lists())) {
                stamp_file(lock_splits, f, prov, out);
            }
        }
    }
}

/// [`stamp_results`] of one file.
fn stamp_file(
    lock_splits: &[(PathBuf, stamp::LockSplits)],
    f: &mut trackfix::transform::FileResult,
    prov: &Provenance,
    out: &OutputArgs,
) {
    let Some(d) = trackfix::dialect::dialect_of(&f.path) else {
        return;
    };
    let carried = stamp::carry_precision_known(
        &f.original,
        std::mem::take(&mut f.output),
        d,
        f.widened.take(),
    );
    f.output = carried.output;
    if out.no_stamp {
        return;
    }
    let old = stamp::find_stamp(&f.original, d).map(|(s, _)| s);
    // Targets this run left as written still carry the correction: the stamp stays to
    // say so.
    let undone = prov.stamp.command == "zero"
        && carried.widened.is_empty()
        && f.kept.is_empty()
        && old.as_ref().is_some_and(|s| {
            s.command == "correct"
                && s.robot == prov.stamp.robot
                && s.profile.as_ref().map(|p| &p.1) == prov.stamp.profile.as_ref().map(|p| &p.1)
        });
    if undone {
        stamp::strip_in_place(&mut f.output, d);
        return;
    }
    let mut s = prov.stamp.clone();
    s.widened = carried.widened;
    s.kept = stamp::Kept::of(f.kept.clone());
    if let Some((_, splits)) = lock_splits.iter().find(|(p, _)| *p == f.path) {
        s.gimbal = splits.clone();
    }
    stamp::write_in_place(&mut f.output, d, &s);
}

impl OutputArgs {
    /// Whether refusals of `kind` are left unchanged rather than stopping the run.
    fn keeps(&self, kind: RefusalKind) -> bool {
        self.skip_unsupported || self.keep.contains(&kind)
    }
}

const CORRECT_EXAMPLES: &str = "\
Examples:
  trackfix correct cad/spot_line.mod --cell samples/cell.toml --robot r1 -o spot_line.mod
  trackfix correct samples/krl/spot_line.src --cell samples/cell.toml --robot r1 --out-dir out/
  trackfix correct cad/*.mod --cell samples/cell.toml --robot r1 --diff

For every Cartesian target at skid s (its own external axis), in its work object W:
  T' = W⁻¹ · B(s) · D(s)⁻¹ · B(s)⁻¹ · W · T     (docs/design.md §4)";

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
pub(crate) struct CorrectArgs {
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
pub(crate) struct ZeroArgs {
    #[command(flatten)]
    pub inner: CorrectArgs,
}

/// Mirror options shared by `mirror` and `transfer --mirror`; each overrides the cell's
/// `[mirror]` table.
#[derive(clap::Args, Debug)]
pub(crate) struct MirrorOptions {
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
pub(crate) struct MirrorArgs {
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
    /// The mirror-image robot of the cell, when the image is for it: with a world plane, the
    /// image is written in the work objects as its [robot.NAME.wobj] entries place them (as
    /// `transfer --mirror` does).
    #[arg(long = "to", value_name = "ROBOT", requires = "robot")]
    pub to_robot: Option<String>,
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
pub(crate) struct TransferArgs {
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

/// The programs among `files`; a file skipped (not a text module) is noted unless `quiet`.
fn load_programs(
    files: &[PathBuf],
    options: &LoadOptions,
    quiet: bool,
) -> anyhow::Result<Vec<Program>> {
    let mut programs = Vec::new();
    for group in collect_programs(files)? {
        for loaded in load_group(&group, options) {
            match loaded {
                Ok(p) => programs.push(p),
                Err(e) if e.is_skip() => {
                    if !quiet {
                        let _ = writeln!(std::io::stderr(), "note: {e}");
                    }
                }
                Err(e) => return Err(e.into()),
            }
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

/// The robot's profile as its file gives it; a file that cannot be read is an error at the
/// cell's `profile = …`.
fn read_profile(cell: &Cell, robot: &Robot) -> anyhow::Result<Profile> {
    match Profile::load(&robot.profile) {
        Err(TrackError::Io { error, .. }) => Err(cell.profile_error(robot, &error).into()),
        r => r.with_context(|| format!("profile of robot `{}`", robot.name)),
    }
}

/// The robot's profile, checked against the cell: a cell whose track axis (or, for a profile
/// measured in the cell's frame, whose base) disagrees with the profile's nominal would apply the
/// profile in the wrong place, so it is an error; a profile that disagrees with its own
/// statistics (a hand edit) is a warning.
fn load_profile(cell: &Cell, robot: &Robot) -> anyhow::Result<Profile> {
    let profile = read_profile(cell, robot)?;
    check_cell_nominal(&robot.base0, &robot.track_axis, &profile).with_context(|| {
        format!(
            "{}: robot `{}` does not match its profile {}",
            cell.path.display(),
            robot.name,
            robot.profile.display()
        )
    })?;
    for w in profile
        .consistency_warnings()
        .into_iter()
        .chain(profile.measurement_warnings())
    {
        let _ = writeln!(
            std::io::stderr(),
            "warning: {}: {w}",
            robot.profile.display()
        );
    }
    Ok(profile)
}

/// How a transform loads `robot`'s programs. Inputs are mapped unless the run writes them in
/// place: an in-place write's transaction compares each input on disk with the bytes it read,
/// and a mapped file would change with the disk and hide a concurrent edit. A run that writes
/// elsewhere (`-o`, `--out-dir`, `--diff`, `--check`) never writes an input (`output::plan`
/// refuses to), so it maps its inputs as `check` does (docs/design.md §9, "Reading inputs").
fn load_options(robot: Option<&Robot>, in_place: bool) -> LoadOptions {
    LoadOptions {
        krl_config_dat: robot.and_then(|r| r.config_dat.clone()),
        map_inputs: !in_place,
        ..LoadOptions::default()
    }
}

/// A `$config.dat` is loaded for its bases; it is written only if a transform changed it
/// (`--mirror-frames`, a global point), or a target of it was refused (the refusal must be
/// reported and counted like any other), or it is `copied_along`: a robot tree's own
/// `$config.dat` written to `--out-dir` with the tree's program files, changed or not, so that
/// the output tree is a whole program, and a later run on it reads the same bases.
fn drop_untouched_config(
    results: &mut [ProgramResult],
    config_dat: Option<&Path>,
    copied_along: &impl Fn(&Path) -> bool,
) {
    // A robot tree's own `$config.dat` is part of its program on the same terms.
    let is_config = |p: &Path| {
        config_dat == Some(p)
            || p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.eq_ignore_ascii_case("$config.dat"))
    };
    for r in results {
        // Named alone, a `$config.dat` is no program to write.
        let with_programs = r.files.iter().any(|f| !is_config(&f.path));
        r.files.retain(|f| {
            f.changed()
                || !f.refusals.is_empty()
                || !f.notes.is_empty()
                || !is_config(&f.path)
                || (with_programs && copied_along(&f.path))
        });
    }
}

/// The name `--keep` takes for a refusal kind (clap's, from the library's enum).
fn kind_name(kind: RefusalKind) -> String {
    use clap::ValueEnum as _;
    kind.to_possible_value()
        .map_or_else(|| format!("{kind:?}"), |v| v.get_name().to_owned())
}

/// Exit 4 when the output was written with refused targets kept as written.
fn written_exit(results: &[ProgramResult]) -> Exit {
    if results.iter().any(|r| r.refusals().next().is_some()) {
        Exit::Kept
    } else {
        Exit::Ok
    }
}

/// The command-line flag that gives a refusal's remedy.
fn remedy_flag(remedy: Remedy) -> &'static str {
    match remedy {
        Remedy::DefaultWorkObject => "pass --default-wobj NAME to transform unused targets in NAME",
        Remedy::MirrorJoints => "pass --mirror-joints to negate axes 1, 4 and 6",
    }
}

/// [`finish_outputs`], then the run report when one was asked for.
fn finish(
    command: &str,
    results: &[ProgramResult],
    renames: &[Renamed],
    out: &OutputArgs,
    inputs: &[PathBuf],
) -> anyhow::Result<Exit> {
    if out.no_backup && !out.in_place {
        bail!(
            "--no-backup is for --in-place, which replaces the inputs; -o and --out-dir never touch them"
        );
    }
    // The report's path is checked before anything is written: it must not name an input,
    // the cell or an output, and a report that cannot be written must not follow outputs
    // that are.
    if let Some(path) = &out.report {
        let planned = match destination(out) {
            Some(dest) if !out.diff && !out.check => {
                output::plan(results, &dest, &Roots::from_inputs(inputs))
                    .map(|writes| {
                        // A backup the run will make is its output too.
                        let backups = writes
                            .iter()
                            .filter(|w| w.backup)
                            .map(|w| output::next_free_backup(&w.path));
                        writes
                            .iter()
                            .map(|w| w.path.clone())
                            .chain(backups)
                            .collect()
                    })
                    .unwrap_or_default()
            }
            _ => Vec::new(),
        };
        output::check_apart_from(path, &planned)?;
    }
    let _held = super::signals::StopSignalsHeld::new();
    let exit = finish_outputs(command, results, renames, out, inputs)?;
    if let Some(path) = &out.report {
        write_run_report(path, command, results, out, exit).with_context(|| match exit {
            Exit::Ok | Exit::Kept if !out.diff && !out.check => {
                "the outputs are written, but not the run report"
            }
            _ => "the run report is not written",
        })?;
    }
    Ok(exit)
}

/// The run report: what was read (with hashes), what changed, what was refused, and the
/// outcome the exit code stands for.
fn write_run_report(
    path: &Path,
    command: &str,
    results: &[ProgramResult],
    out: &OutputArgs,
    exit: Exit,
) -> anyhow::Result<()> {
    let written = match (&out.output, &out.out_dir) {
        (Some(o), _) => format!("written to {}", o.display()),
        (_, Some(d)) => format!("written under {}", d.display()),
        _ => "written in place".to_owned(),
    };
    let outcome = match exit {
        Exit::Refused => "refused: nothing written".to_owned(),
        _ if out.diff => "preview (diff): nothing written".to_owned(),
        _ if out.check => "check: nothing written".to_owned(),
        Exit::Ok => written,
        Exit::Kept => format!("{written}; targets named below kept as written"),
        e => format!("exit {}", e as u8),
    };
    let mut inputs = Vec::new();
    for (role, file) in &out.also_read {
        let bytes = output::read_input(file).with_context(|| file.display().to_string())?;
        inputs.push(RunInput::new(role, &file.display().to_string(), &bytes, ""));
    }
    let report = RunReport {
        command: command.to_owned(),
        arguments: std::env::args().collect::<Vec<_>>().join(" "),
        outcome,
        inputs,
        files: results
            .iter()
            .flat_map(|p| &p.files)
            .map(RunFile::from_result)
            .collect(),
        checks: Vec::new(),
    };
    output::write_file(path, run_report(&report).as_bytes())?;
    if out.format != ReportFormat::Json && !out.verbosity.quiet {
        let _ = writeln!(
            std::io::stderr(),
            "wrote {}: the run report",
            path.display()
        );
    }
    Ok(())
}

/// Reports refusals, then diffs, checks or writes. The one place outcomes become an exit code.
fn finish_outputs(
    command: &str,
    results: &[ProgramResult],
    renames: &[Renamed],
    out: &OutputArgs,
    inputs: &[PathBuf],
) -> anyhow::Result<Exit> {
    let mut stderr = std::io::stderr().lock();
    let mut messages = Messages::new(out.verbosity, out.format == ReportFormat::Json);
    for n in results
        .iter()
        .flat_map(|r| r.files.iter().flat_map(|f| &f.notes))
    {
        // A target its stamp lists as kept says why in its own hint; the others are no
        // targets.
        let hint = match n.kind {
            RefusalKind::KeptAsWritten => n.hint.as_str(),
            _ => "left as written; not a target",
        };
        let text = n.located(Severity::Note, hint);
        messages.show(&mut stderr, Severity::Note, &kind_name(n.kind), &text)?;
    }
    let refused: Vec<_> = results.iter().flat_map(|r| r.refusals()).collect();
    let blocking = refused.iter().filter(|r| !out.keeps(r.kind)).count();
    for r in &refused {
        // Kept targets are reported as warnings: the run goes on without them.
        let kind = kind_name(r.kind);
        let (severity, outcome) = if out.keeps(r.kind) {
            (Severity::Warning, " (kept as written)".to_owned())
        } else {
            (
                Severity::Error,
                format!(", or pass --keep {kind} to leave it as written"),
            )
        };
        let advice = match r.remedy {
            Some(remedy) => remedy_flag(remedy),
            None => &r.hint,
        };
        let text = r.located(severity, format!("{advice}{outcome} [{kind}]"));
        messages.show(&mut stderr, severity, &kind, &text)?;
    }
    messages.finish(&mut stderr)?;
    let runtime = refused.iter().filter(|r| r.kind.is_runtime_data()).count();
    if runtime > 0 && out.format != ReportFormat::Json && !out.verbosity.quiet {
        writeln!(
            stderr,
            "note: {runtime} of the {} refused target(s) depend on values the program sets when it runs: not correctable offline",
            refused.len()
        )?;
    }
    if blocking > 0 {
        let mut kinds: Vec<_> = refused
            .iter()
            .filter(|r| !out.keeps(r.kind))
            .map(|r| r.kind)
            .collect();
        kinds.sort();
        kinds.dedup();
        let kinds: Vec<_> = kinds.into_iter().map(kind_name).collect();
        if out.format == ReportFormat::Json {
            let summaries = results
                .iter()
                .flat_map(|r| &r.files)
                .map(|f| FileSummary::new(f, command == "mirror"))
                .collect();
            return json_report(command, results, summaries, &[], 0, out, Exit::Refused);
        }
        writeln!(
            stderr,
            "error: {command} refused {blocking} target(s); nothing written (fix them, or leave them as written with --keep {}, or --skip-unsupported for every kind)",
            kinds.join(",")
        )?;
        return Ok(Exit::Refused);
    }
    if out.diff {
        let mut stdout = std::io::stdout().lock();
        for f in results.iter().flat_map(|r| &r.files) {
            stdout.write_all(&unified_diff(&f.path, &f.original, &f.output))?;
        }
        // The diff is the output: one that keeps refused targets as written is partial, as a
        // written file would be.
        return Ok(written_exit(results));
    }
    if out.check {
        let mut any = false;
        for f in results.iter().flat_map(|r| &r.files) {
            if let Some(line) = would_change(f) {
                any = true;
                if out.format == ReportFormat::Text {
                    writeln!(stderr, "{line}")?;
                }
            }
        }
        let exit = if any { Exit::Findings } else { Exit::Ok };
        if out.format == ReportFormat::Json {
            let summaries = results
                .iter()
                .flat_map(|r| &r.files)
                .map(|f| FileSummary::new(f, command == "mirror"))
                .collect();
            return json_report(command, results, summaries, &[], 0, out, exit);
        }
        return Ok(exit);
    }
    write_outputs(command, results, renames, out, inputs)
}

/// A KRL program written under a new name (`-o FILE`) gets its DEF/DEFDAT renamed to match:
/// KSS loads a module only when they agree. The results themselves are renamed, before anything
/// is shown or written, so the diff, the check, the files written and the run report's hashes
/// all speak of the same bytes.
fn rename_for_output(
    results: &mut [ProgramResult],
    out: &OutputArgs,
) -> anyhow::Result<Vec<Renamed>> {
    let stem = match &out.output {
        Some(o) if o.as_os_str() != "-" => o.file_stem(),
        _ => None,
    };
    let Some(stem) = stem.map(|s| s.to_string_lossy().into_owned()) else {
        return Ok(Vec::new());
    };
    let mut renames = Vec::new();
    for r in results {
        renames.extend(rename_program(r, &stem)?);
    }
    Ok(renames)
}

/// Where `out` says the results go: a file, a folder or in place (`None` for standard output
/// or when it names none).
fn destination(out: &OutputArgs) -> Option<Destination> {
    if let Some(o) = &out.output {
        (o.as_os_str() != "-").then(|| Destination::File(o.clone()))
    } else if let Some(d) = &out.out_dir {
        Some(Destination::Dir(d.clone()))
    } else {
        out.in_place.then_some(Destination::InPlace {
            backup: !out.no_backup,
        })
    }
}

/// Writes the results (one transaction, `trackfix::output`) and lists every file written.
fn write_outputs(
    command: &str,
    results: &[ProgramResult],
    renames: &[Renamed],
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
    let dest = if out.output.as_ref().is_some_and(|o| o.as_os_str() == "-") {
        let bytes = output::stream_output(results)?;
        let mut stdout = std::io::stdout().lock();
        stdout.write_all(bytes)?;
        stdout.flush()?;
        // The output is complete: a summary that cannot be shown changes nothing.
        let _ = summarize(command, results, &[], out, &mut stderr);
        return Ok(written_exit(results));
    } else if let Some(dest) = destination(out) {
        dest
    } else {
        bail!(
            "say where to write: -o FILE (- for standard output), --out-dir DIR or --in-place (or preview with --diff, --check)"
        );
    };
    let writes = output::plan(results, &dest, &Roots::from_inputs(inputs))?;
    let written = output::commit(&writes)?;
    // The files are written: a summary that cannot be shown (stderr full or closed) changes
    // nothing about the outcome.
    let exit = written_exit(results);
    if out.format == ReportFormat::Json {
        let summaries = summaries(command, results, &written);
        return json_report(
            command,
            results,
            summaries,
            renames,
            written.len(),
            out,
            exit,
        );
    }
    if written.is_empty() && !out.verbosity.quiet {
        let _ = writeln!(stderr, "note: nothing written: no file changed");
    }
    let _ = summarize(command, results, &written, out, &mut stderr);
    for r in renames.iter().filter(|_| !out.verbosity.quiet) {
        let _ = writeln!(
            stderr,
            "note: {}: renamed `{}` to `{}` in the written file, to match its new file name (the controller needs them equal)",
            printable(&r.path.display().to_string()),
            printable(&r.from),
            printable(&r.to)
        );
    }
    Ok(written_exit(results))
}

/// The summary of every input file: what changed, and every file written for it.
fn summaries(
    command: &str,
    results: &[ProgramResult],
    written: &[output::Written],
) -> Vec<FileSummary> {
    let mut out = Vec::new();
    for f in results.iter().flat_map(|r| &r.files) {
        let mut summary = FileSummary::new(f, command == "mirror");
        if let Some(w) = written.iter().find(|w| w.input == f.path) {
            summary.written_to = Some(w.path.clone());
            summary.link_target.clone_from(&w.resolved);
            summary.backup.clone_from(&w.backup);
        }
        out.push(summary);
    }
    out
}

/// One line per input file (unless `-q`), and a totals line for a batch of several programs.
fn summarize(
    command: &str,
    results: &[ProgramResult],
    written: &[output::Written],
    out: &OutputArgs,
    stderr: &mut impl std::io::Write,
) -> anyhow::Result<Exit> {
    if out.verbosity.quiet {
        return Ok(Exit::Ok);
    }
    for summary in summaries(command, results, written) {
        writeln!(stderr, "{summary}")?;
    }
    if results.len() > 1 {
        writeln!(stderr, "{}", Totals::of(results, written.len(), out))?;
    }
    Ok(Exit::Ok)
}

/// The one runner of every transform: load each program (with `robot`'s `$config.dat`), run
/// `transform` on it in memory, then report, diff, check or write everything at once. `others`:
/// the other robots whose cell entries the transform uses (`transfer`'s `--to`), whose
/// `$config.dat` is written only as `robot`'s is.
#[allow(clippy::too_many_arguments)]
fn run_each(
    command: &str,
    files: &[PathBuf],
    robot: Option<&Robot>,
    others: &[&Robot],
    out: &OutputArgs,
    prov: &Provenance,
    transform: impl Fn(Program) -> anyhow::Result<ProgramResult>,
) -> anyhow::Result<Exit> {
    let programs = load_programs(
        files,
        &load_options(robot, out.in_place),
        out.verbosity.quiet,
    )?;
    if let Some(exit) = refuse_syntax_errors(command, &programs)? {
        return Ok(exit);
    }
    if !out.verbosity.quiet {
        let robots: Vec<&Robot> = robot.into_iter().chain(others.iter().copied()).collect();
        show_readings(&programs, &robots, Readings::ProgramAndCell, out.verbosity)?;
    }
    if let Some(exit) = check_stamps(command, &programs, prov, out)? {
        return Ok(exit);
    }
    // A progress bar on a terminal only, for a batch long enough to wait for.
    let bar = if std::io::IsTerminal::is_terminal(&std::io::stderr())
        && programs.len() > 20
        && !out.verbosity.quiet
        && out.format == ReportFormat::Text
    {
        indicatif::ProgressBar::new(programs.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    // What the stamps need of the models, taken before the models are handed over.
    let lock_splits: Vec<(PathBuf, stamp::LockSplits)> = if prov.stamp.command == "correct" {
        programs
            .iter()
            .flat_map(|p| &p.files)
            .filter_map(|f| {
                let splits = stamp::LockSplits::of(f);
                (!splits.is_empty()).then(|| (f.path.clone(), splits))
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut results = Vec::new();
    // Each program is handed over: a transform keeps only the sources and its edits, so the
    // model of a large program is gone before its outputs are built.
    for p in programs {
        results.push(transform(p)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    stamp_results(&lock_splits, &mut results, prov, out);
    // A file the run was given, or found in a folder it was given (not a cell's `config_dat`
    // from elsewhere), goes to `--out-dir` with the others.
    let roots = Roots::from_inputs(files);
    let copied_along =
        |p: &Path| out.out_dir.is_some() && (files.iter().any(|f| f == p) || roots.holds(p));
    drop_untouched_config(
        &mut results,
        robot.and_then(|r| r.config_dat.as_deref()),
        &copied_along,
    );
    for other in others {
        drop_untouched_config(&mut results, other.config_dat.as_deref(), &copied_along);
    }
    let renames = rename_for_output(&mut results, out)?;
    let exit = finish(command, &results, &renames, out, files);
    super::leave_for_exit(results);
    exit
}

/// A file with a syntax error (or one that does not print back byte for byte) is never
/// transformed: what the parser could not read may hold targets that would stay uncorrected.
/// Every error is shown, located; the run writes nothing and exits 2.
fn refuse_syntax_errors(command: &str, programs: &[Program]) -> anyhow::Result<Option<Exit>> {
    let mut stderr = std::io::stderr().lock();
    let mut bad = Vec::new();
    for file in programs.iter().flat_map(|p| &p.files) {
        let errors = trackfix::report::errors(file);
        for d in &errors {
            writeln!(stderr, "{}", file.render(d).trim_end())?;
        }
        if !errors.is_empty() {
            bad.push(format!("{} ({})", file.path.display(), errors.len()));
        }
    }
    if bad.is_empty() {
        return Ok(None);
    }
    writeln!(
        stderr,
        "error: {command}: syntax errors in {}; a file that does not parse is never transformed: nothing written (fix them; `trackfix check` lists them)",
        bad.join(", ")
    )?;
    Ok(Some(Exit::Usage))
}

/// Which warnings [`show_readings`] shows.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Readings {
    /// The program's and the cell's: a transform, whose result depends on both.
    ProgramAndCell,
    /// The cell's alone: a command that reads the cell and lists the program's own findings
    /// elsewhere (`inspect`'s report) or not at all (`reach`).
    Cell,
}

/// Shows the warnings that say what the transforms take the programs to mean where it is not
/// what is written ([`Diagnostic::shapes_transforms`]), the program's (`which` says whether)
/// and those of the cell's entries for `robots`: the result depends on them, and on what
/// reads the cell as they do (`reach`, `inspect` with a robot).
///
/// [`Diagnostic::shapes_transforms`]: trackfix::syntax::Diagnostic::shapes_transforms
pub(super) fn show_readings(
    programs: &[Program],
    robots: &[&Robot],
    which: Readings,
    verbosity: Verbosity,
) -> anyhow::Result<()> {
    let mut stderr = std::io::stderr().lock();
    // A batch of copies of one module says each the same: shown a few times, then counted.
    let mut messages = Messages::new(verbosity, false);
    for p in programs {
        // What the cell's entries for the robots the transform uses make of the declarations.
        let cell = trackfix::transform::cell::frame_readings(p, robots);
        for (fi, file) in p.files.iter().enumerate() {
            let own = file
                .diagnostics
                .iter()
                .filter(|d| which == Readings::ProgramAndCell && d.shapes_transforms);
            let of_cell = cell.iter().filter(|(f, _)| *f == fi).map(|(_, d)| d);
            for d in own.chain(of_cell) {
                let text = file.render(d);
                messages.show(
                    &mut stderr,
                    d.severity,
                    &shape(&d.message),
                    &text.trim_end(),
                )?;
            }
        }
    }
    messages.finish(&mut stderr)?;
    Ok(())
}

/// [`run_each`] for one transform step.
fn run_step(
    command: &str,
    files: &[PathBuf],
    robot: Option<&Robot>,
    step: TransformStep,
    out: &OutputArgs,
    prov: &Provenance,
) -> anyhow::Result<Exit> {
    run_each(command, files, robot, &[], out, prov, |p| {
        let edits = step.edits(&p);
        Ok(apply_owned(p, edits)?)
    })
}

fn run_track(mut a: CorrectArgs, dir: Direction) -> anyhow::Result<Exit> {
    let cell = load_cell(&a.cell)?;
    let robot = cell.robot(&a.robot)?;
    let profile = load_profile(&cell, robot)?;
    a.out.also_read = vec![
        ("cell".to_owned(), a.cell.clone()),
        (format!("profile of {}", robot.name), robot.profile.clone()),
    ];
    let uncertainty = ProfileUncertainty::new(&profile)
        .with_context(|| format!("uncertainties of {}", robot.profile.display()))?;
    let mut setup = TrackSetup::new(robot, &profile);
    setup.uncertainty = uncertainty.as_ref();
    setup.default_wobj = a.default_wobj.clone();
    let rule = match dir {
        Direction::Correct => StampRule::NotCorrected,
        Direction::Zero => StampRule::Corrected,
    };
    run_step(
        dir.as_str(),
        &a.files,
        Some(robot),
        TransformStep::Track(&setup, dir),
        &a.out,
        &Provenance::new(dir.as_str(), Some(robot), Some(&profile), rule),
    )
}

pub(crate) fn run_correct(a: CorrectArgs) -> anyhow::Result<Exit> {
    report_located(run_correct_inner(a))
}

fn run_correct_inner(a: CorrectArgs) -> anyhow::Result<Exit> {
    run_track(a, Direction::Correct)
}

pub(crate) fn run_zero(a: ZeroArgs) -> anyhow::Result<Exit> {
    report_located(run_zero_inner(a))
}

fn run_zero_inner(a: ZeroArgs) -> anyhow::Result<Exit> {
    run_track(a.inner, Direction::Zero)
}

/// The mirror from the cell's `[mirror]` table, overridden by the command line, with the run's
/// skid map ([`skid_map_of`]). A plane given in world (`frame_in = "world"`) resolves work
/// objects with `robot`'s cell entries, then the program's declarations.
fn mirror_settings(
    cell: Option<&Cell>,
    o: &MirrorOptions,
    skid_map: (f64, f64),
    skid_axis: usize,
    robot: Option<&Robot>,
    default_wobj: Option<&str>,
) -> MirrorSettings {
    let table = cell.map(|c| c.mirror.clone()).unwrap_or_default();
    let d = MirrorSettings::default();
    let world = (table.frame_in == FrameIn::World).then(|| WorldPlane {
        frame: table.frame.unwrap_or(d.frame),
        frames: robot.map(|r| r.frames.clone()).unwrap_or_default(),
        frames_to: None,
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
        skid_map,
        skid_axis,
        skid_axis_to: None,
        mirror_frames: o.mirror_frames,
        mirror_joints: o.mirror_joints,
        arm: robot.and_then(|r| trackfix::transform::MirrorArm::of(r, default_wobj)),
    }
}

pub(crate) fn run_mirror(a: MirrorArgs) -> anyhow::Result<Exit> {
    report_located(run_mirror_inner(a))
}

fn run_mirror_inner(mut a: MirrorArgs) -> anyhow::Result<Exit> {
    let cell = a.cell.as_deref().map(load_cell).transpose()?;
    a.out.also_read = a
        .cell
        .iter()
        .map(|c| ("cell".to_owned(), c.clone()))
        .collect();
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
    require_plane(cell.as_ref(), &a.mirror)?;
    if let (Some(c), None) = (&cell, robot) {
        let plane = a.mirror.plane.or(c.mirror.plane).map_or("?", plane_name);
        let frames = if c.mirror.frame_in == FrameIn::World {
            "the cell's mirror frame in world, taken into each target's work object as the program declares it (the cell's [robot.NAME.wobj] entries are used only with --robot NAME)"
        } else if c.mirror.frame.is_some() {
            "the cell's mirror frame, in each target's own work object"
        } else {
            "each target's own work object"
        };
        let _ = writeln!(std::io::stderr(), "note: mirror: plane {plane} of {frames}");
    }
    let to = match (&cell, &a.to_robot) {
        (Some(c), Some(name)) => Some(c.robot(name)?),
        _ => None,
    };
    let (skid_map, source) = skid_map_of(cell.as_ref(), &a.mirror, robot, to)?;
    let mut settings = MirrorSettings {
        skid_axis_to: a
            .skid_to
            .as_deref()
            .map(|s| axis("skid-to", s))
            .transpose()?,
        ..mirror_settings(
            cell.as_ref(),
            &a.mirror,
            skid_map,
            skid_axis,
            robot,
            a.default_wobj.as_deref(),
        )
    };
    let mut check = None;
    if let (Some(c), Some(to)) = (&cell, to) {
        writes_image_for(&mut settings, robot, to)?;
        if let Some(from) = robot {
            // The skid range of its track: where the map is checked.
            let range = read_profile(c, from)?.skid_range();
            let map = SkidMapCheck {
                cell: c,
                source,
                from,
                to,
                range,
            };
            map.in_world(&settings)?;
            check = Some(map);
        }
    }
    let step = TransformStep::Mirror(&settings);
    run_each(
        "mirror",
        &a.files,
        robot,
        &[],
        &a.out,
        &Provenance::new("mirror", robot, None, StampRule::NotCorrectedForAny),
        |p| {
            if let Some(check) = &check {
                check.in_work_objects(&settings, &p, a.default_wobj.as_deref(), true)?;
            }
            let edits = step.edits(&p);
            Ok(apply_owned(p, edits)?)
        },
    )
}

/// A mirror whose image is for robot `to` (the program being `from`'s): with a plane in world,
/// the image is written in the work objects as `to` places them — its cell entries, then the
/// bases of its own `$config.dat` when the cell gives it another one than `from`'s — and, when
/// both robots have kinematics, its configurations and joint targets are solved in `to`'s base.
fn writes_image_for(
    settings: &mut MirrorSettings,
    from: Option<&Robot>,
    to: &Robot,
) -> anyhow::Result<()> {
    let Some(world) = &mut settings.world else {
        return Ok(());
    };
    let mut frames = to.frames.clone();
    if let Some(config) = &to.config_dat
        && from.and_then(|f| f.config_dat.as_ref()) != Some(config)
    {
        let bases = trackfix::krl::load_config_dat(config)
            .with_context(|| format!("{}: the bases of robot `{}`", config.display(), to.name))?;
        for b in bases
            .iter()
            .filter(|b| b.kind == trackfix::position::FrameKind::Base)
        {
            if let Some(pose) = b.pose() {
                frames
                    .entry(trackfix::transform::cell::frame_key(&b.name))
                    .or_insert(pose);
            }
        }
    }
    world.frames_to = Some(frames);
    // The image's configurations and joint targets are then solved in `to`'s own base.
    if let Some(arm) = &mut settings.arm {
        arm.image = trackfix::transform::ImageRobot::of(to);
    }
    Ok(())
}

/// Where a run's skid map comes from, for an error about it.
#[derive(Clone, Copy, Debug)]
enum SkidMapSource {
    /// `--skid-map`, the run's own direction.
    Flag,
    /// The cell's `[mirror]` table, taken the way the run goes.
    Cell(SkidMapWay),
    /// Neither: the identity.
    Default,
}

/// The run's skid map: `--skid-map` as given (the run's own direction), else the cell's taken
/// the way a mirror of `from`'s program for `to` goes (its inverse to a robot `skid_map_from`
/// names: `Cell::skid_map_for`), else the identity.
fn skid_map_of(
    cell: Option<&Cell>,
    o: &MirrorOptions,
    from: Option<&Robot>,
    to: Option<&Robot>,
) -> anyhow::Result<((f64, f64), SkidMapSource)> {
    if let Some(map) = o.skid_map {
        return Ok((map, SkidMapSource::Flag));
    }
    let (from, to) = (from.map(|r| r.name.as_str()), to.map(|r| r.name.as_str()));
    Ok(
        match cell
            .map(|c| c.skid_map_for(from, to))
            .transpose()?
            .flatten()
        {
            Some(directed) => (directed.map, SkidMapSource::Cell(directed.way)),
            None => (MirrorSettings::default().skid_map, SkidMapSource::Default),
        },
    )
}

/// What checks a run's skid map against the bases of the robot mirrored and the mirror-image
/// robot over the first's track (`mirror::check_skid_map`): a map that does not put `to` at
/// the mirror image of `from` is an error at the cell's entry, or naming where the map came
/// from, never used.
struct SkidMapCheck<'c> {
    cell: &'c Cell,
    source: SkidMapSource,
    from: &'c Robot,
    to: &'c Robot,
    /// `from`'s skid range (its profile's knots).
    range: (f64, f64),
}

impl SkidMapCheck<'_> {
    /// With the plane in world, before any program.
    fn in_world(&self, settings: &MirrorSettings) -> anyhow::Result<()> {
        trackfix::transform::mirror::check_skid_map(settings, self.from, self.to, self.range)
            .map_err(|m| self.error(&m))
    }

    /// With the plane in each target's work object (`frame_in = "wobj"`), before `program` is
    /// mirrored: in the plane of each work object its targets use, placed in the cell by
    /// `from`'s entries or the program's declarations. A work object that places it nowhere
    /// (not declared, given at run time, moved by a unit…) is a warning that the map was not
    /// checked for its targets, where they are mirrored (`warn_unplaced`: a transfer refuses
    /// them, its first step needing the work object in the cell too). Before, the map was never
    /// checked with the plane in the work objects.
    fn in_work_objects(
        &self,
        settings: &MirrorSettings,
        program: &Program,
        default_wobj: Option<&str>,
        warn_unplaced: bool,
    ) -> anyhow::Result<()> {
        if settings.world.is_some() {
            return Ok(());
        }
        let planes = trackfix::transform::mirror::work_object_planes(
            program,
            settings,
            &self.from.frames,
            default_wobj,
        );
        for (name, plane) in &planes.placed {
            trackfix::transform::mirror::check_skid_map_in(
                plane,
                Some(name),
                settings,
                self.from,
                self.to,
                self.range,
            )
            .map_err(|m| self.error(&m))?;
        }
        if let Some(first) = planes.unplaced.first().filter(|_| warn_unplaced) {
            let path = program.files.first().map(|f| f.path.display().to_string());
            let _ = writeln!(
                std::io::stderr(),
                "warning: {}: skid map not checked for the targets of {} work object(s) that place the mirror plane nowhere in the cell (with frame_in = \"wobj\" each target mirrors about the plane in its own work object): {first}\n  = help: give the plane in world (frame_in = \"world\" in the [mirror] table) to have the map checked for every target",
                path.unwrap_or_default(),
                planes.unplaced.len()
            );
        }
        Ok(())
    }

    /// The error for `mismatch`: at the cell's entry, or naming where the map came from.
    fn error(&self, mismatch: &SkidMapMismatch) -> anyhow::Error {
        let (from, to) = (&self.from.name, &self.to.name);
        match self.source {
            SkidMapSource::Cell(way) => match self.cell.skid_map_error(mismatch, way) {
                Some(located) => located.into(),
                None => anyhow::anyhow!("{mismatch}\n  = help: {}", skid_map_hint(mismatch)),
            },
            SkidMapSource::Flag if mismatch.inverse_fits => {
                let (scale, offset) = inverse_skid_map(mismatch.map);
                let number = trackfix::transform::cell::short_number;
                anyhow::anyhow!(
                    "--skid-map: {mismatch}\n  = help: --skid-map is this run's map, from robot `{from}`'s skids to robot `{to}`'s: pass its inverse, --skid-map {},{}",
                    number(scale, 6),
                    number(offset, 3)
                )
            }
            SkidMapSource::Flag => anyhow::anyhow!(
                "--skid-map: {mismatch}\n  = help: {}",
                skid_map_hint(mismatch)
            ),
            SkidMapSource::Default => anyhow::anyhow!(
                "{}: no skid_map in the [mirror] table, so the default: {mismatch}\n  = help: {}",
                self.cell.path.display(),
                skid_map_hint(mismatch)
            ),
        }
    }
}

/// A mirror needs a plane: from `--plane` or the cell's `[mirror]` table, never a silent
/// default.
fn require_plane(cell: Option<&Cell>, o: &MirrorOptions) -> anyhow::Result<()> {
    if o.plane.is_some() || cell.is_some_and(|c| c.mirror.plane.is_some()) {
        return Ok(());
    }
    bail!(match cell {
        Some(c) => format!(
            "say which plane to mirror in: --plane xz|yz|xy, or `plane = \"xz\"` in the [mirror] table of {}",
            c.path.display()
        ),
        None => "say which plane to mirror in: --plane xz|yz|xy, or --cell CELL.toml with a [mirror] table".to_owned(),
    })
}

/// The mirror's options given to a `transfer` without `--mirror` would change nothing (a skid
/// map of `1,250` left every skid where it was, exit 0): an error naming them, never ignored.
fn refuse_mirror_options_alone(o: &MirrorOptions) -> anyhow::Result<()> {
    let given: Vec<&str> = [
        (o.plane.is_some(), "--plane"),
        (o.tool_flip.is_some(), "--tool-flip"),
        (o.config.is_some(), "--config"),
        (o.skid_map.is_some(), "--skid-map"),
        (o.mirror_frames, "--mirror-frames"),
        (o.mirror_joints, "--mirror-joints"),
    ]
    .into_iter()
    .filter_map(|(set, flag)| set.then_some(flag))
    .collect();
    if given.is_empty() {
        return Ok(());
    }
    bail!(
        "{} only apply to a mirror: add --mirror to mirror between the two robots, or leave them out",
        given.join(", ")
    )
}

fn plane_name(p: Plane) -> &'static str {
    match p {
        Plane::Xy => "xy",
        Plane::Xz => "xz",
        Plane::Yz => "yz",
    }
}

pub(crate) fn run_transfer(a: TransferArgs) -> anyhow::Result<Exit> {
    report_located(run_transfer_inner(a))
}

fn run_transfer_inner(mut a: TransferArgs) -> anyhow::Result<Exit> {
    let cell = load_cell(&a.cell)?;
    let from = cell.robot(&a.from)?;
    let to = cell.robot(&a.to)?;
    let from_profile = load_profile(&cell, from)?;
    let to_profile = load_profile(&cell, to)?;
    a.out.also_read = vec![
        ("cell".to_owned(), a.cell.clone()),
        (format!("profile of {}", from.name), from.profile.clone()),
        (format!("profile of {}", to.name), to.profile.clone()),
    ];
    if a.mirror {
        require_plane(Some(&cell), &a.mirror_options)?;
    } else {
        refuse_mirror_options_alone(&a.mirror_options)?;
    }
    let mut check = None;
    let mut plan = TransferPlan {
        from: TrackSetup::new(from, &from_profile),
        mirror: if a.mirror {
            let (skid_map, source) =
                skid_map_of(Some(&cell), &a.mirror_options, Some(from), Some(to))?;
            let mut settings = MirrorSettings {
                skid_axis_to: Some(to.skid_axis),
                ..mirror_settings(
                    Some(&cell),
                    &a.mirror_options,
                    skid_map,
                    from.skid_axis,
                    Some(from),
                    a.default_wobj.as_deref(),
                )
            };
            writes_image_for(&mut settings, Some(from), to)?;
            let map = SkidMapCheck {
                cell: &cell,
                source,
                from,
                to,
                range: from_profile.skid_range(),
            };
            map.in_world(&settings)?;
            check = Some(map);
            Some(settings)
        } else {
            None
        },
        to: TrackSetup::new(to, &to_profile),
    };
    plan.from.default_wobj = a.default_wobj.clone();
    plan.to.default_wobj = a.default_wobj.clone();
    let written = load_options(Some(to), a.out.in_place);
    run_each(
        "transfer",
        &a.files,
        Some(from),
        &[to],
        &a.out,
        &Provenance::new("transfer", Some(to), Some(&to_profile), StampRule::Any),
        |p| {
            if let (Some(check), Some(settings)) = (&check, &plan.mirror) {
                check.in_work_objects(settings, &p, a.default_wobj.as_deref(), false)?;
            }
            Ok(transfer(&p, &plan, &written)?)
        },
    )
}
