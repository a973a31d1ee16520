//! Subcommand implementations. Library calls only; printing and `anyhow` live here.

pub(crate) mod accuracy;
pub(crate) mod frame;
pub(crate) mod inspect;
pub(crate) mod messages;
pub(crate) mod reach;
pub(crate) mod report;
pub(crate) mod signals;
pub(crate) mod track;
pub(crate) mod transform;

use std::process::ExitCode;

/// The documented exit codes (docs/design.md §7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// 0: everything went well.
    Ok = 0,
    /// 1: `check` or `--check` found something.
    Findings = 1,
    /// 2: a usage or input error.
    Usage = 2,
    /// 3: a transform was refused.
    Refused = 3,
    /// 4: a transform wrote its output (or showed it with `--diff`) but kept refused targets
    /// as written (`--keep`).
    Kept = 4,
}

impl From<Exit> for ExitCode {
    fn from(e: Exit) -> ExitCode {
        ExitCode::from(e as u8)
    }
}

/// A closed stdout (`trackfix inspect … | head`) is not an error.
pub(crate) fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Hands what a command built to the end of the process instead of freeing it: the process
/// exits right after, and freeing every position of a large program one by one was 4 % of
/// `check` (the operating system takes the pages back at once).
pub(super) fn leave_for_exit<T>(built: T) {
    std::mem::forget(built);
}
