//! `trackfix inspect` and `trackfix check`. Owned by issue 2.

use std::path::PathBuf;

use super::Exit;

#[derive(clap::Args)]
pub struct InspectArgs {
    /// Program files or directories (searched recursively).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

#[derive(clap::Args)]
pub struct CheckArgs {
    /// Program files or directories (searched recursively).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

pub fn run_inspect(_args: InspectArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("inspect is not implemented yet")
}

pub fn run_check(_args: CheckArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("check is not implemented yet")
}
