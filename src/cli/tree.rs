//! `sylva tree grow`.
use clap::Subcommand;

/// Tree subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Grow one tree skeleton and export it.
    Grow {
        /// Species id or name.
        #[arg(long)]
        species: String,
    },
}

/// Runs a tree subcommand.
pub fn run(_c: Command) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
