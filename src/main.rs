//! The `trackfix` command line: parse flags, run, map outcomes to documented exit codes.
//!
//! Exit codes (docs/design.md §7): 0 ok, 1 findings (`check`, `--check` differences), 2 usage
//! or input error, 3 a transform refused, 4 a transform wrote its output with refused targets
//! kept as written.

// stdout and stderr go through `writeln!`, never `println!`/`eprintln!`: a closed pipe or a
// full disk is an error we handle (a closed pipe is success), not a panic (Cargo.toml [lints]).

mod cli;

use std::io::Write as _;
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};

const EXAMPLES: &str = "\
Examples:
  trackfix inspect samples/rapid/spot_line.mod
  trackfix check samples/
  trackfix track identify samples/track/measurements.csv -o frames.csv
  trackfix track fit frames.csv -o profile.toml
  trackfix track show profile.toml --step 500
  trackfix frame base points.csv --profile profile.toml -o base.toml
  trackfix correct program.mod --cell samples/cell.toml --robot r1 -o corrected.mod
  trackfix transfer samples/rapid/spot_line.mod --cell samples/cell.toml --from r1 --to r2 --mirror --out-dir out/

Exit codes: 0 ok, 1 findings (check, --check), 2 usage or input error, 3 transform refused,
4 written with refused targets kept as written (--keep, --skip-unsupported).";

/// Model a robot's deformed linear track and rewrite ABB RAPID and KUKA KRL programs for it,
/// losslessly: everything not changed stays byte for byte.
#[derive(Parser)]
#[command(name = "trackfix", version, after_help = EXAMPLES, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List every position, work object and tool in RAPID/KRL programs.
    Inspect(cli::inspect::InspectArgs),
    /// Verify the byte-exact round trip and lint programs (exit 1 on findings).
    Check(cli::inspect::CheckArgs),
    /// Measure and model a linear track: identify, fit, show, spectrum.
    #[command(subcommand)]
    Track(cli::track::TrackCommand),
    /// Frames from tracker and robot: base and track axis, work objects, TCP, point pairs.
    #[command(subcommand)]
    Frame(cli::frame::FrameCommand),
    /// Apply a track profile to every target (offline program → real track).
    Correct(cli::transform::CorrectArgs),
    /// Remove a track profile from an online-tuned program (→ straight track).
    Zero(cli::transform::ZeroArgs),
    /// Mirror positions to the opposite robot of a symmetric cell.
    Mirror(cli::transform::MirrorArgs),
    /// Zero with one robot's track, optionally mirror, correct with another's.
    Transfer(cli::transform::TransferArgs),
    /// Check every target's reach, joint limits and configuration with the robot's kinematics.
    Reach(cli::reach::ReachArgs),
    /// ISO 9283 pose and path accuracy from laser-tracker measurements.
    #[command(subcommand)]
    Accuracy(cli::accuracy::AccuracyCommand),
    /// Write the track report: one self-contained HTML file (measurements, model, controller figures).
    Report(cli::report::ReportArgs),
    /// Print a shell completion script (bash, zsh, fish, powershell, elvish).
    #[command(
        after_help = "Example:\n  trackfix completions bash > /etc/bash_completion.d/trackfix"
    )]
    Completions { shell: clap_complete::Shell },
    /// Print the man page (roff) of trackfix or of one subcommand, or write every page.
    #[command(
        after_help = "Examples:\n  trackfix man > trackfix.1 && man ./trackfix.1\n  trackfix man correct | man -l -\n  trackfix man --out-dir man/    # trackfix.1, trackfix-correct.1, trackfix-track-fit.1, …"
    )]
    Man {
        /// The subcommand (`correct`, `track fit`, …); none: the top-level page.
        #[arg(conflicts_with = "out_dir")]
        subcommand: Vec<String>,
        /// Write the page of trackfix and of every subcommand into DIR (created if missing).
        #[arg(long, value_name = "DIR")]
        out_dir: Option<std::path::PathBuf>,
    },
}

/// The error and its causes, `: `-separated, each cause only once: library errors show their
/// OS error in their own message and also keep it as their source.
fn chain_text(err: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in err.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

/// Writes a rendered text to standard output; a failure (a full disk) is an error, not a panic.
fn to_stdout(bytes: &[u8]) -> anyhow::Result<cli::Exit> {
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|()| out.flush())
        .map_err(|e| anyhow::Error::from(e).context("writing to standard output"))?;
    Ok(cli::Exit::Ok)
}

/// The man page of a (sub)command, rendered in memory.
fn man_page(cmd: clap::Command) -> anyhow::Result<Vec<u8>> {
    let mut page = Vec::new();
    clap_mangen::Man::new(cmd).render(&mut page)?;
    Ok(page)
}

/// `trackfix man [SUBCOMMAND…] | --out-dir DIR`.
fn man(subcommand: &[String], out_dir: Option<&std::path::Path>) -> anyhow::Result<cli::Exit> {
    let mut root = Cli::command().disable_help_subcommand(true);
    root.build();
    if let Some(dir) = out_dir {
        // Every visible command, named as `man` finds them: trackfix-track-fit.1.
        let mut pages = Vec::new();
        let mut stack = vec![(root, "trackfix".to_owned())];
        while let Some((cmd, name)) = stack.pop() {
            for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
                stack.push((sub.clone(), format!("{name}-{}", sub.get_name())));
            }
            let page = man_page(cmd.display_name(name.clone()))?;
            pages.push((dir.join(format!("{name}.1")), page));
        }
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("creating {}: {e}", dir.display()))?;
        let mut out = std::io::stderr().lock();
        for (path, page) in &pages {
            trackfix::output::write_file(path, page)?;
        }
        let _ = writeln!(
            out,
            "wrote {} man pages into {}",
            pages.len(),
            dir.display()
        );
        return Ok(cli::Exit::Ok);
    }
    let mut cmd = root;
    let mut name = "trackfix".to_owned();
    for word in subcommand {
        let Some(sub) = cmd.find_subcommand(word).cloned() else {
            let known: Vec<_> = cmd
                .get_subcommands()
                .filter(|s| !s.is_hide_set())
                .map(|s| s.get_name().to_owned())
                .collect();
            anyhow::bail!(
                "`{name}` has no subcommand `{word}`; pages: {}",
                known.join(", ")
            );
        };
        name = format!("{name}-{word}");
        cmd = sub;
    }
    to_stdout(&man_page(cmd.display_name(name))?)
}

/// Fixes glibc's mmap threshold at 128 KiB, its initial value, for the whole run.
///
/// glibc raises the threshold to the size of any mmap'd block that is freed (up to 32 MiB), so
/// after the first large vector is dropped every later one comes from the brk heap, and the old
/// halves of vectors that grew by doubling stay resident after they are freed: a `correct` of a
/// 34 MB KRL pair peaked at 141 MB RSS for a 112 MB heap. With the threshold fixed, large
/// blocks stay mmap'd and go back to the system when freed (113 MB), and a growing one is
/// moved by `mremap`, not copied.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
fn fix_mmap_threshold() {
    // SAFETY: `mallopt` only sets a parameter of the allocator, takes plain integers and is
    // called before any other thread exists; a refusal (return 0) leaves the default in place,
    // which is harmless, so its result is not checked.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

fn main() -> ExitCode {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fix_mmap_threshold();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(a) => cli::inspect::run_inspect(a),
        Command::Check(a) => cli::inspect::run_check(a),
        Command::Track(c) => cli::track::run(c),
        Command::Frame(c) => cli::frame::run(c),
        Command::Correct(a) => cli::transform::run_correct(a),
        Command::Zero(a) => cli::transform::run_zero(a),
        Command::Mirror(a) => cli::transform::run_mirror(a),
        Command::Transfer(a) => cli::transform::run_transfer(a),
        Command::Reach(a) => cli::reach::run(a),
        Command::Accuracy(c) => cli::accuracy::run(c),
        Command::Report(a) => cli::report::run(a),
        Command::Completions { shell } => {
            // Rendered first: clap_complete panics on a failed write.
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "trackfix", &mut script);
            to_stdout(&script)
        }
        Command::Man {
            subcommand,
            out_dir,
        } => man(&subcommand, out_dir.as_deref()),
    };
    match result {
        Ok(exit) => exit.into(),
        Err(err) => {
            if cli::is_broken_pipe(&err) {
                return ExitCode::SUCCESS;
            }
            // A full or closed stderr leaves only the exit code to tell; never a panic.
            let _ = writeln!(std::io::stderr(), "error: {}", chain_text(&err));
            cli::Exit::Usage.into()
        }
    }
}
