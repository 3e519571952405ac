//! `sylva species list|show|check|new`.
use clap::Subcommand;

/// Species subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// List the species of the library.
    List,
}

/// Runs a species subcommand.
pub fn run(_c: Command) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
