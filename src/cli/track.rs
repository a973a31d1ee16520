//! `trackfix track identify | fit | show | spectrum`. Owned by issue 4.

use super::Exit;

#[derive(clap::Subcommand)]
pub enum TrackCommand {
    /// Identify the robot base frame at each skid position from laser-tracker points.
    Identify,
}

pub fn run(_cmd: TrackCommand) -> anyhow::Result<Exit> {
    anyhow::bail!("track is not implemented yet")
}
