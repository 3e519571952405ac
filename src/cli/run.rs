//! `sylva run [SCENARIO]`: the main job.

/// Arguments of `sylva run`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML); the embedded default scenario when omitted.
    pub scenario: Option<std::path::PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "out")]
    pub out: std::path::PathBuf,
}

/// Runs the main job.
pub fn run(_a: Args) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
