//! `trackfix correct | zero | mirror | transfer`. Owned by issue 5.

use std::path::PathBuf;

use super::Exit;

#[derive(clap::Args)]
pub struct CorrectArgs {
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

#[derive(clap::Args)]
pub struct ZeroArgs {
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

#[derive(clap::Args)]
pub struct MirrorArgs {
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

#[derive(clap::Args)]
pub struct TransferArgs {
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

pub fn run_correct(_a: CorrectArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("correct is not implemented yet")
}

pub fn run_zero(_a: ZeroArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("zero is not implemented yet")
}

pub fn run_mirror(_a: MirrorArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("mirror is not implemented yet")
}

pub fn run_transfer(_a: TransferArgs) -> anyhow::Result<Exit> {
    anyhow::bail!("transfer is not implemented yet")
}
