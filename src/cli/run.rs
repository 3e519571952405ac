//! `sylva run [SCENARIO]`: the main job. Derives the living conditions of the scenario's
//! terrain, simulates the forest, and writes maps, the stand table and its plot, inventory
//! snapshots, stills from an oblique and a top-down camera at years 0, 10, 25, 50, 100 and 150,
//! a timelapse GIF (MP4 too when ffmpeg is installed) and `summary.md`.

use anyhow::Context;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sylva::job::pictures::{self, Stage, TimelapseOptions};
use sylva::job::scene;
use sylva::render::scene::TreeInstance;
use sylva::render::camera::CameraPreset;
use sylva::sim::Scenario;
use sylva::species::Season;

/// The embedded default scenario (`scenarios/default.toml`).
pub const DEFAULT_SCENARIO: &str = include_str!("../../scenarios/default.toml");

/// Years at which stills are rendered (those within the run).
pub const STILL_YEARS: [u32; 6] = [0, 10, 25, 50, 100, 150];

/// Arguments of `sylva run`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML); the embedded default scenario when omitted.
    pub scenario: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Override the scenario's number of years.
    #[arg(long)]
    pub years: Option<u32>,
    /// Size of the stills WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = super::render::parse_size)]
    pub size: (u32, u32),
    /// Size of the timelapse frames WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = super::render::parse_size)]
    pub timelapse_size: (u32, u32),
    /// Interpolated timelapse frames between consecutive snapshots (0–50; 0: one per snapshot).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=50))]
    pub frames_between: u32,
    /// Timelapse frames per second (1–100).
    #[arg(long, default_value_t = 8.0, value_parser = parse_fps)]
    pub fps: f32,
    /// Skip stills and timelapse (no GPU or software adapter needed).
    #[arg(long)]
    pub no_render: bool,
    /// Folder of extra or edited species files (e.g. made by `sylva species new`): they are
    /// added to the shipped library, replacing shipped species of the same id.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
}

fn parse_fps(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("fps `{s}`: expected a number"))?;
    if !(1.0..=100.0).contains(&v) {
        return Err(format!("fps `{s}`: expected 1–100 frames per second"));
    }
    Ok(v)
}

/// Runs the main job.
pub fn run(a: Args) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let mut sc = match &a.scenario {
        Some(p) => Scenario::load(p)?,
        None => Scenario::from_toml_str(DEFAULT_SCENARIO, "embedded default scenario (scenarios/default.toml)")?,
    };
    if let Some(y) = a.years {
        sc.years = y;
        sc.validate("--years")?;
    }
    let out = a.out.clone();
    if out.exists() && !out.is_dir() {
        anyhow::bail!("--out {}: is a file; expected a folder for the run's outputs", out.display());
    }
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    eprintln!("Sylva · {} · {} years · seed {} → {}", sc.name, sc.years, sc.seed, out.display());

    // 1. Living conditions.
    let t_site = Instant::now();
    let site = super::simulate::load_site(&sc)?;
    let lib = super::simulate::library(a.species_dir.as_deref().as_slice())?;
    let map_names = sylva::job::maps::write_site_maps(&site, &out.join("maps").join("conditions"))?;
    let site_s = t_site.elapsed().as_secs_f64();
    let (ex, ey) = site.extent_m();
    eprintln!("[1/4] conditions: {} × {} cells, {:.2} km × {:.2} km, {} maps ({:.1} s)", site.width(), site.height(), ex / 1000.0, ey / 1000.0, map_names.len(), site_s);

    // 2. Simulation.
    let t_sim = Instant::now();
    eprintln!("[2/4] simulating {} years", sc.years);
    // The pictures' key frames come from the in-memory world at each snapshot (summer
    // instances of the visible trees), not from the inventory files.
    let mut keys: Vec<(u32, Vec<TreeInstance>)> = Vec::new();
    // the living trees of the last kept snapshot, for the adapted close-up
    let mut last_rows: Vec<sylva::job::inventory::InventoryRow> = Vec::new();
    let mut keep = |y: u32, w: &sylva::sim::World| {
        if !a.no_render {
            keys.push((y, scene::instances_with_saplings(&scene::plants_from_world(w), &scene::saplings_from_world(w), &lib, &site, Season::Summer)));
            last_rows = sylva::job::inventory::rows_from_world(w);
        }
    };
    // GeoJSON (≈ 280 bytes per tree, ≈ 250 MB at the end of the default run) only for the
    // final year; the CSV inventory is written at every snapshot
    let summary = super::simulate::simulate(&sc, site.clone(), &lib, out.clone(), false, Some(vec![sc.years]), Some(&mut keep))?;
    let sim_s = t_sim.elapsed().as_secs_f64();

    // 3 + 4. Pictures.
    let mut stills: Vec<(u32, String, PathBuf)> = Vec::new();
    let mut gif: Option<(PathBuf, usize, bool)> = None;
    let t_pic = Instant::now();
    if !a.no_render {
        let mut stage = Stage::new(site.clone(), lib.clone(), sc.climate.sea_level_m).context("setting up the renderer (install mesa-vulkan-drivers for the CPU adapter)")?;
        stage.set_scenario(sc.seed, &sc.obstacles);
        stage.set_surroundings_of(&sc).context("the terrain around the simulated window")?;
        // the stills from afar draw instanced prototypes; the close-up adapts its near field
        let adapt = stage.adapt.take();
        eprintln!("[3/4] stills on {}", stage.renderer.adapter_description());
        let mut years: Vec<u32> = STILL_YEARS.iter().copied().filter(|y| keys.iter().any(|k| k.0 == *y)).collect();
        if let Some(last) = keys.iter().map(|k| k.0).max() {
            if !years.contains(&last) {
                years.push(last);
            }
        }
        let stills_dir = out.join("stills");
        std::fs::create_dir_all(&stills_dir).with_context(|| format!("creating {}", stills_dir.display()))?;
        remove_old_stills(&stills_dir)?;
        let pb = super::progress((years.len() * 2) as u64, "stills");
        let key = |y: u32| keys.iter().find(|k| k.0 == y).map(|k| k.1.clone()).unwrap_or_default();
        for &y in &years {
            for (preset, name) in [(CameraPreset::Oblique, "oblique"), (CameraPreset::Map, "topdown")] {
                let cam = stage.camera_sized(preset, a.size.0, a.size.1);
                let img = stage.render_instances(key(y), Season::Summer, &cam, a.size.0, a.size.1)?;
                let path = stills_dir.join(format!("year_{y:04}_{name}.png"));
                sylva::output::pictures::write_png(&path, &img)?;
                stills.push((y, name.to_string(), path));
                pb.inc(1);
            }
        }
        // A close view into the final forest, where the species' architectures show.
        if let Some(&y) = years.last() {
            let (ex, ey) = site.extent_m();
            let (x0, y0) = (0.3 * ex, 0.3 * ey);
            let (x1, y1) = (0.45 * ex, 0.45 * ey);
            let z0 = site.elevation_at(x0, y0) + 45.0;
            let z1 = site.elevation_at(x1, y1) + 5.0;
            let cam = sylva::render::camera::Camera::look_at([x0 as f32, y0 as f32, z0], [x1 as f32, y1 as f32, z1], 50.0);
            stage.adapt = adapt;
            let img = stage.render_rows(&last_rows, Season::Summer, &cam, a.size.0, a.size.1)?;
            stage.adapt = None;
            let ad = stage.last_adapt;
            eprintln!("close-up: {} trees adapted to their neighbours ({:.1} s adaptation, {:.1} s meshes)", ad.adapted_trees, ad.adapt_s, ad.mesh_s);
            let path = stills_dir.join(format!("year_{y:04}_closeup.png"));
            sylva::output::pictures::write_png(&path, &img)?;
            stills.push((y, "closeup".to_string(), path));
        }
        pb.finish_and_clear();
        eprintln!("[4/4] timelapse");
        let opts = TimelapseOptions { width: a.timelapse_size.0, height: a.timelapse_size.1, fps: a.fps, frames_between: a.frames_between, camera: None, season: Season::Summer };
        let pb = super::progress(1, "timelapse");
        let tl0 = Instant::now();
        let gif_path = out.join("timelapse.gif");
        let key_years: Vec<u32> = keys.iter().map(|k| k.0).collect();
        let mut key_frames: Vec<Vec<TreeInstance>> = std::mem::take(&mut keys).into_iter().map(|k| k.1).collect();
        let (n, mp4) = pictures::timelapse_from(&mut stage, &key_years, &mut |_, k| Ok(std::mem::take(&mut key_frames[k])), &out.join("frames"), &gif_path, &opts, &mut |done, total| {
            pb.set_length(total as u64);
            pb.set_position(done as u64);
            pb.set_message(format!("{:.1} frames/s", done as f64 / tl0.elapsed().as_secs_f64().max(1e-3)));
        })?;
        pb.finish_and_clear();
        gif = Some((gif_path, n, mp4));
    }
    let pic_s = t_pic.elapsed().as_secs_f64();
    let total_s = t0.elapsed().as_secs_f64();

    // Summary.
    let names: Vec<String> = summary.pool.iter().map(|s| s.to_string()).collect();
    let last = summary.rows.last();
    let mut table = String::new();
    let _ = writeln!(table, "| quantity | value |\n|---|---|");
    let _ = writeln!(table, "| year | {} |", summary.year);
    let _ = writeln!(table, "| trees alive (all sizes) | {} |", summary.trees_alive);
    if let Some(r) = last {
        let _ = writeln!(table, "| stems ≥ 1.3 m per ha | {:.0} |", r.stems_ha);
        let _ = writeln!(table, "| basal area (m²/ha) | {:.1} |", r.basal_area_m2_ha);
        let _ = writeln!(table, "| top height H100 (m) | {:.1} |", r.top_height_m);
        let _ = writeln!(table, "| quadratic mean DBH (cm) | {:.1} |", r.qmd_cm);
    }
    let _ = writeln!(table, "| time: living conditions (s) | {:.1} |", site_s);
    let _ = writeln!(table, "| time: simulation (s) | {:.1} |", sim_s);
    let _ = writeln!(table, "| time: pictures (s) | {:.1} |", pic_s);
    let _ = writeln!(table, "| time: total (s) | {:.1} |", total_s);
    let mut shares = String::from("| species | share of basal area | share of stems |\n|---|---|---|\n");
    if let Some(r) = last {
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|&i, &j| r.share_ba[j].total_cmp(&r.share_ba[i]).then(i.cmp(&j)));
        for i in order {
            let _ = writeln!(shares, "| {} | {:.1} % | {:.1} % |", names[i], 100.0 * r.share_ba[i], 100.0 * r.share_stems[i]);
        }
    }
    write_summary_md(&out, &sc, &table, &shares, &map_names, &stills, gif.as_ref())?;
    println!("\n{}\n{}", table, shares);
    println!("outputs in {} (see summary.md)", out.display());
    Ok(())
}

fn rel(out: &Path, p: &Path) -> String {
    p.strip_prefix(out).unwrap_or(p).display().to_string()
}

fn write_summary_md(out: &Path, sc: &Scenario, table: &str, shares: &str, maps: &[String], stills: &[(u32, String, PathBuf)], gif: Option<&(PathBuf, usize, bool)>) -> anyhow::Result<()> {
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", sc.name);
    let _ = writeln!(md, "{} years, seed {}, {} species in the pool. Scenario as run: `scenario.toml`.\n", sc.years, sc.seed, if sc.species.is_empty() { "all".to_string() } else { sc.species.len().to_string() });
    let _ = writeln!(md, "## Result\n\n{table}\n{shares}");
    let _ = writeln!(md, "## Stand development\n\n![stand table](stand_table.png)\n\nData: `stand_table.csv`; inventories: `inventory/`.\n");
    if let Some((g, n, mp4)) = gif {
        let _ = writeln!(md, "## Timelapse\n\n![timelapse]({})\n\n{n} frames{}.\n", rel(out, g), if *mp4 { ", also as `timelapse.mp4`" } else { "" });
    }
    if !stills.is_empty() {
        if let Some(c) = stills.iter().find(|s| s.1 == "closeup") {
            let _ = writeln!(md, "## Year {} from within the forest\n\n![close view]({})\n", c.0, rel(out, &c.2));
        }
        let _ = writeln!(md, "## Stills\n\n| year | oblique | top-down |\n|---|---|---|");
        let mut years: Vec<u32> = stills.iter().map(|s| s.0).collect();
        years.dedup();
        for y in years {
            let get = |n: &str| stills.iter().find(|s| s.0 == y && s.1 == n).map(|s| format!("![year {y} {n}]({})", rel(out, &s.2))).unwrap_or_default();
            let _ = writeln!(md, "| {y} | {} | {} |", get("oblique"), get("topdown"));
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Living conditions\n");
    for m in maps {
        let _ = writeln!(md, "![{m}](maps/conditions/{m}.png)");
    }
    sylva::output::write_atomic(&out.join("summary.md"), md.as_bytes())?;
    Ok(())
}

/// Removes the stills an earlier run wrote (`year_NNNN_<view>.png`, nothing else) so that a new
/// run into the same folder does not leave stills of years it did not reach.
fn remove_old_stills(dir: &std::path::Path) -> anyhow::Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let p = e.with_context(|| format!("listing {}", dir.display()))?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let ours = name.starts_with("year_") && name.ends_with(".png") && name.len() > 10 && name[5..9].bytes().all(|b| b.is_ascii_digit()) && name.as_bytes()[9] == b'_';
        if ours {
            std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
        }
    }
    Ok(())
}
