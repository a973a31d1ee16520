//! The `trackfix` command line: parse flags, run, map outcomes to documented exit codes.
//!
//! Exit codes (DESIGN.md §5): 0 ok, 1 findings (`check`, `--check` differences), 2 usage or
//! input error, 3 a transform refused.

// The binary may write to stderr; stdout goes through `writeln!` so that a closed pipe is an
// error we map to success rather than a panic in `println!` (Cargo.toml [lints]).
#![allow(clippy::print_stderr)]

mod cli;

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
    /// Print a shell completion script (bash, zsh, fish, powershell, elvish).
    #[command(
        after_help = "Example:\n  trackfix completions bash > /etc/bash_completion.d/trackfix"
    )]
    Completions { shell: clap_complete::Shell },
    /// Print the man page (roff) to standard output.
    #[command(after_help = "Example:\n  trackfix man > trackfix.1 && man ./trackfix.1")]
    Man,
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
        Command::Completions { shell } => {
            let mut cmd = Cli::command();
            clap_complete::generate(shell, &mut cmd, "trackfix", &mut std::io::stdout());
            Ok(cli::Exit::Ok)
        }
        Command::Man => clap_mangen::Man::new(Cli::command())
            .render(&mut std::io::stdout())
            .map(|()| cli::Exit::Ok)
            .map_err(Into::into),
    };
    match result {
        Ok(exit) => exit.into(),
        Err(err) => {
            if cli::is_broken_pipe(&err) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {err:#}");
            cli::Exit::Usage.into()
        }
    }
}
