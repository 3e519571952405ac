//! `sylva terrain info|maps`.
use clap::Subcommand;

/// Terrain subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Print size, CRS, cell size, elevation range, nodata count and TIN size.
    Info {
        /// DEM file (GeoTIFF, .asc, .png); the embedded default when omitted.
        file: Option<std::path::PathBuf>,
    },
}

/// Runs a terrain subcommand.
pub fn run(_c: Command) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
