//! `sylva export RUN_DIR --year Y --area X0,Y0,X1,Y1 --out stand.glb`: the adapted trees of an
//! area with the terrain patch and the obstacles as one glTF scene ([`sylva::job::export`]).
use anyhow::Context;
use std::path::PathBuf;
use sylva::species::Season;

/// Arguments of `sylva export`.
#[derive(clap::Args)]
pub struct Args {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: PathBuf,
    /// Snapshot year (default: the last one).
    #[arg(long)]
    pub year: Option<u32>,
    /// Area X0,Y0,X1,Y1 (m, world coordinates from the terrain's south-west corner, as in the
    /// inventory's x_m, y_m).
    #[arg(long, allow_hyphen_values = true)]
    pub area: String,
    /// Season of the foliage colours: spring, summer, autumn, winter.
    #[arg(long, default_value = "summer", value_parser = super::render::parse_season)]
    pub season: Season,
    /// Levels of detail to write, e.g. `0` (full trees only, for Blender) or `0,1,2,3` (LOD
    /// groups for game engines; the default).
    #[arg(long, value_delimiter = ',', default_value = "0,1,2,3")]
    pub lod: Vec<usize>,
    /// Folder of extra or edited species files, over the shipped library and the run's own
    /// `species/` folder.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// Output `.glb`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `sylva export`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if a.out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) != Some("glb".into()) {
        anyhow::bail!("--out {}: the stand is written as binary glTF; give a file name ending in .glb", a.out.display());
    }
    anyhow::ensure!(a.run_dir.join("scenario.toml").is_file(), "{}: not a Sylva run directory (no scenario.toml)", a.run_dir.display());
    let area = sylva::job::export::parse_area(&a.area)?;
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let lib = super::simulate::run_library(&a.run_dir, a.species_dir.as_deref())?;
    let mut o = sylva::job::export::ExportOptions::new(area);
    o.year = a.year;
    o.season = a.season;
    o.levels = a.lod.clone();
    let r = sylva::job::export::export_stand(&a.run_dir, &lib, &o, &a.out)?;
    println!(
        "year {}: {} trees ({} tree models), {} obstacles, terrain {} triangles; {} meshes, {} mesh nodes, {} images; adapt {:.2} s → {} ({:.1} MB)",
        r.year, r.trees, r.models, r.obstacles, r.terrain_triangles, r.counts.meshes, r.counts.mesh_nodes, r.counts.images, r.adapt_s, r.out.display(), r.bytes as f64 / 1e6
    );
    Ok(())
}
