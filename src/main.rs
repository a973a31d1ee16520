//! The `trackfix` command line: parse flags, run, map outcomes to documented exit codes.
//!
//! Exit codes (DESIGN.md §5): 0 ok, 1 findings (`check`, `--check` differences), 2 usage or
//! input error, 3 a transform refused.

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

Exit codes: 0 ok, 1 findings (check, --check), 2 usage or input error, 3 transform refused.";

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
    /// Print the man page (roff) to standard output.
    #[command(after_help = "Example:\n  trackfix man > trackfix.1 && man ./trackfix.1")]
    Man,
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

fn main() -> ExitCode {
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
        Command::Man => {
            let mut page = Vec::new();
            clap_mangen::Man::new(Cli::command())
                .render(&mut page)
                .map_err(anyhow::Error::from)
                .and_then(|()| to_stdout(&page))
        }
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
