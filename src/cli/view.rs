//! `sylva view RUN_DIR` and `sylva edit [SPECIES]`: the two windows (the work is in
//! `sylva::view` and `sylva::edit`; this only reads the arguments and the inputs).

use anyhow::Context;
use std::path::PathBuf;
use sylva::gui::WindowOptions;
use sylva::sim::Scenario;

fn parse_window(s: &str) -> Result<(f32, f32), String> {
    let (w, h) = super::render::parse_size(s)?;
    Ok((w as f32, h as f32))
}

/// What both windows take: size, screenshot, frames.
#[derive(clap::Args, Clone)]
pub struct WindowArgs {
    /// Window size WIDTHxHEIGHT (logical pixels).
    #[arg(long, default_value = "1280x800", value_parser = parse_window)]
    pub window: (f32, f32),
    /// Draw --frames frames, write a PNG of the whole window to this file and exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames drawn before the screenshot (1–1000); the screenshot shows the last of them.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
}

impl WindowArgs {
    fn options(&self) -> anyhow::Result<WindowOptions> {
        if let Some(p) = &self.screenshot {
            if p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) != Some("png".into()) {
                anyhow::bail!("--screenshot {}: screenshots are written as PNG; give a file name ending in .png", p.display());
            }
            super::check_out_file(p, "--screenshot")?;
        }
        Ok(WindowOptions { size: self.window, screenshot: self.screenshot.clone(), frames: self.frames })
    }
}

fn said_screenshot(opts: &WindowOptions) {
    if let Some(p) = &opts.screenshot {
        eprintln!("screenshot → {}", p.display());
    }
}

/// Arguments of `sylva view`.
#[derive(clap::Args)]
pub struct ViewArgs {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: PathBuf,
    /// Folder of extra or edited species files, over the shipped library and the run's own
    /// `species/` folder.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// First camera: a preset of the stills (overview, oblique or ground: the ground view steps
    /// into the nearest clearing of the last snapshot, as `sylva render --camera ground` does);
    /// by default the whole terrain framed by the orbit camera.
    #[arg(long, value_parser = parse_view_camera)]
    pub camera: Option<sylva::render::camera::CameraPreset>,
    /// The trees near a resting camera drawn with their own full-detail meshes, adapted to their
    /// neighbours (Plastic Trees, as in the stills): on (default) or off (every tree its
    /// species' model).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub adapt: String,
    #[command(flatten)]
    pub window: WindowArgs,
}

fn parse_view_camera(s: &str) -> Result<sylva::render::camera::CameraPreset, String> {
    use sylva::render::camera::CameraPreset;
    match s.parse::<CameraPreset>() {
        Ok(CameraPreset::Map) | Err(_) => Err(format!("camera `{s}`: expected overview, oblique or ground")),
        Ok(p) => Ok(p),
    }
}

/// Opens the viewer.
pub fn view(a: ViewArgs) -> anyhow::Result<()> {
    let opts = a.window.options()?;
    // the run directory first: a mistyped one is named as such, with or without a display
    super::check_run_dir(&a.run_dir, "sylva view")?;
    let sc_path = a.run_dir.join("scenario.toml");
    let sc = Scenario::load(&sc_path).with_context(|| format!("{} is not a Sylva run directory", a.run_dir.display()))?;
    sylva::gui::check_display()?;
    let site = super::simulate::load_site(&sc)?;
    let run_species = super::simulate::run_species_dir(&a.run_dir);
    let mut dirs: Vec<&std::path::Path> = Vec::new();
    if run_species.is_dir() {
        dirs.push(&run_species);
    }
    dirs.extend(a.species_dir.as_deref());
    let lib = super::simulate::library(&dirs)?;
    let data = sylva::view::data::RunData::open(&a.run_dir, site, lib, sc.species.clone())?;
    // the terrain around a window cut from a DEM, drawn as the stills draw it
    let surroundings = match sc.terrain.window {
        Some(w) => sc.full_terrain().context("reading the terrain around the simulated window")?.map(|t| (t, w)),
        None => None,
    };
    let start = sylva::view::ViewStart { seed: sc.seed, obstacles: sc.obstacles.clone(), camera: a.camera, adapt: a.adapt == "on", mirror_trees: !sc.designs_its_stand() };
    sylva::view::run(data, sc.climate.sea_level_m, surroundings, &start, &opts)?;
    said_screenshot(&opts);
    Ok(())
}

fn parse_model(s: &str) -> Result<sylva::structure::species_tree::Model, String> {
    use sylva::structure::species_tree::Model;
    match s.to_ascii_lowercase().as_str() {
        "ecomod" => Ok(Model::EcoMod),
        "light" | "light_guided" | "light-guided" => Ok(Model::Light),
        "laplacian" => Ok(Model::Laplacian),
        _ => Err(format!("model `{s}`: expected ecomod, light or laplacian")),
    }
}

/// Arguments of `sylva edit`.
#[derive(clap::Args)]
pub struct EditArgs {
    /// Species file (`.toml`) or species id/name (looked up in --dir, then in the shipped
    /// library; saved to DIR/ID.toml). Default: beech.
    pub species: Option<String>,
    /// Folder of species files: where an id is looked up first, where a shipped species is saved
    /// and where "save as new species" writes (default: `species`).
    #[arg(long, default_value = "species")]
    pub dir: PathBuf,
    /// Growth model of the preview: ecomod, light or laplacian.
    #[arg(long, default_value = "ecomod", value_parser = parse_model)]
    pub model: sylva::structure::species_tree::Model,
    /// Age of the preview tree (years, 1–150).
    #[arg(long, default_value_t = 40.0)]
    pub age: f32,
    #[command(flatten)]
    pub window: WindowArgs,
}

/// Opens the species editor.
pub fn edit(a: EditArgs) -> anyhow::Result<()> {
    let opts = a.window.options()?;
    if !(1.0..=150.0).contains(&a.age) {
        anyhow::bail!("--age {}: expected 1–150 years", a.age);
    }
    // the species is looked up before the display (a misspelt id was told "no display" first;
    // round 30's trial)
    let doc = sylva::edit::open_target(a.species.as_deref(), &a.dir)?;
    sylva::gui::check_display()?;
    eprintln!("editing {} (saves there)", doc.path.display());
    sylva::edit::run(doc, a.dir.clone(), a.model, a.age, &opts)?;
    said_screenshot(&opts);
    Ok(())
}
