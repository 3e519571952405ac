//! `sylva simulate SCENARIO`.

/// Arguments of `sylva simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML).
    pub scenario: std::path::PathBuf,
}

/// Runs a simulation.
pub fn run(_a: Args) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
