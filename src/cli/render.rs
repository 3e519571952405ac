//! `sylva render` and `sylva timelapse`.

/// Arguments of `sylva render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: std::path::PathBuf,
}

/// Arguments of `sylva timelapse`.
#[derive(clap::Args)]
pub struct TimelapseArgs {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: std::path::PathBuf,
}

/// Renders a still.
pub fn render(_a: RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}

/// Renders a timelapse.
pub fn timelapse(_a: TimelapseArgs) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
