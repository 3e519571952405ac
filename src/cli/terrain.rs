//! `sylva terrain info|maps`.
use anyhow::Context;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use sylva::conditions::{self, Climate};
use sylva::grid::Crs;
use sylva::job::maps as job_maps;
use sylva::output::maps;
use sylva::sim::Scenario;
use sylva::terrain::{fields, generate, io, tin::Tin, Terrain};

/// Where the terrain comes from.
#[derive(Args, Debug, Clone)]
pub struct Source {
    /// DEM file (GeoTIFF .tif, ESRI ASCII .asc, 16-bit PNG heightmap); the embedded default
    /// (terrains/jacksboro_fault_dem_utm16n.tif) when omitted.
    pub file: Option<PathBuf>,
    /// Generate a seeded fBm/ridged terrain instead of reading a file.
    #[arg(long)]
    pub generate: bool,
    /// Generated grid size (cells per side).
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// Cell size (m) of a generated terrain or a PNG heightmap [default: 10].
    #[arg(long)]
    pub cell: Option<f64>,
    /// Relief (m) of a generated terrain.
    #[arg(long, default_value_t = 600.0, allow_negative_numbers = true, value_parser = parse_finite)]
    pub relief: f64,
    /// Seed of a generated terrain.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// PNG heightmap: height (m) of value 0 [default: 0].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_finite)]
    pub min_height: Option<f64>,
    /// PNG heightmap: height (m) of value 65535 [default: 1000].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_finite)]
    pub max_height: Option<f64>,
    /// Cells at or below this elevation (m) are water and masked [default: 0; a PNG heightmap
    /// has no sea unless this is given: its lowest pixel is no sea level].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_finite_f32)]
    pub sea_level: Option<f32>,
    /// Latitude (degrees, −90…90) for insolation when the terrain's CRS gives none (a PNG
    /// heightmap, a local grid, a projected grid of an unknown CRS) [default: 46]; a geographic
    /// grid or a projected one Sylva can invert (UTM on WGS 84, NAD83, ETRS89, or a `.prj`) uses
    /// its own.
    #[arg(long, allow_negative_numbers = true, value_parser = parse_latitude)]
    pub latitude: Option<f64>,
}

/// Parses `--latitude`: a finite number of degrees in −90…90.
fn parse_latitude(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (-90.0..=90.0).contains(&v) => Ok(v),
        _ => Err(format!("expected a latitude in degrees from -90 to 90, got '{s}'")),
    }
}

/// Parses a finite number (metres) for `--sea-level`, `--min-height`, `--max-height`, `--relief`.
fn parse_finite(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number of metres, got '{s}'")),
    }
}

/// [`parse_finite`] for `f32` options.
fn parse_finite_f32(s: &str) -> Result<f32, String> {
    parse_finite(s).map(|v| v as f32)
}

impl Source {
    /// The terrain, refused (with the same error for `info` and `maps`) when smaller than
    /// 2 × 2 cells ([`Terrain::check_min_size`]).
    fn load(&self) -> anyhow::Result<Terrain> {
        let t = if self.generate {
            generate::generate(self.size, self.cell.unwrap_or(io::PNG_DEFAULT_CELL_M), self.relief, self.seed)?
        } else {
            match &self.file {
                None => io::default_terrain()?,
                Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) => {
                    let [lo, hi] = io::PNG_DEFAULT_HEIGHT_RANGE_M;
                    let range = (self.min_height.is_some() || self.max_height.is_some()).then(|| [self.min_height.unwrap_or(lo), self.max_height.unwrap_or(hi)]);
                    io::load_png_heightmap_or_default(p, self.cell, range, ("--cell", "--min-height/--max-height"))?
                }
                Some(p) => io::load(p)?,
            }
        };
        t.check_min_size()?;
        Ok(t)
    }
    /// The sea level: `--sea-level`, or 0 m, or for a PNG heightmap none
    /// ([`sylva::terrain::NO_SEA_LEVEL_M`]: a heightmap's 0 is the bottom of its range,
    /// not the sea; trial 37).
    fn sea_level_m(&self) -> f32 {
        let png = self.file.as_ref().and_then(|f| f.extension()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
        self.sea_level.unwrap_or(if png { sylva::terrain::NO_SEA_LEVEL_M } else { 0.0 })
    }

    fn climate(&self) -> Climate {
        let mut c = Climate { sea_level_m: self.sea_level_m(), ..Climate::default() };
        if let Some(l) = self.latitude {
            c.latitude_deg = l;
        }
        c
    }
}

/// Terrain subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Print size, CRS, cell size, elevation range, nodata count and TIN size.
    Info {
        /// The terrain.
        #[command(flatten)]
        source: Source,
        /// TIN vertical tolerance (m).
        #[arg(long, default_value_t = sylva::terrain::tin::DEFAULT_TOLERANCE_M)]
        tolerance: f64,
    },
    /// Write every field and Ellenberg index as colour PNG (with legend) and GeoTIFF.
    Maps {
        /// The terrain.
        #[command(flatten)]
        source: Source,
        /// A scenario file: map its site (its terrain, window and `[climate]`) as `sylva run`
        /// maps it into `maps/conditions/`, without simulating; instead of a DEM file.
        #[arg(long, conflicts_with_all = ["file", "generate"])]
        scenario: Option<PathBuf>,
        /// Output folder (created if missing).
        #[arg(long, default_value = "out/terrain")]
        out: PathBuf,
    },
}

/// Runs a terrain subcommand.
pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Info { source, tolerance } => info(&source, tolerance),
        Command::Maps { source, out, scenario: Some(sc) } => scenario_maps(&sc, &source, &out),
        Command::Maps { source, out, scenario: None } => maps_cmd(&source, &out),
    }
}

fn info(s: &Source, tolerance: f64) -> anyhow::Result<()> {
    let t = s.load()?;
    let g = &t.elevation;
    let valid: Vec<f32> = g.data.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = valid.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    println!("source:      {}", t.source);
    println!("size:        {} x {} cells ({} cells)", g.width, g.height, g.len());
    let crs = match t.geo.crs {
        Crs::Geographic => "geographic (degrees)",
        Crs::Projected => "projected (metres)",
        Crs::Local => "local (metres, no georeferencing)",
    };
    println!("CRS:         {crs}{}", t.geo.epsg.map(|e| format!(", EPSG:{e}")).unwrap_or_default());
    println!("origin:      ({}, {}) upper-left corner", t.geo.origin_x, t.geo.origin_y);
    if t.geo.crs == Crs::Geographic {
        println!("cell:        {}° x {}°", t.geo.pixel_w, t.geo.pixel_h);
        println!(
            "cell (m):    E-W {:.2} m (north row) … {:.2} m (centre) … {:.2} m (south row); N-S {:.2} m",
            t.geo.cell_x_m_at_row(0),
            t.geo.cell_x_m_at_row(g.height / 2),
            t.geo.cell_x_m_at_row(g.height - 1),
            t.geo.cell_y_m()
        );
    } else {
        println!("cell (m):    {} x {}", t.geo.pixel_w, t.geo.pixel_h);
    }
    let own = t.geo.crs == Crs::Geographic || t.geo.latitude_from_crs;
    match (own, s.latitude) {
        (true, Some(l)) => println!("latitude:    {:.3}° (the grid's own, from its CRS; --latitude {l} is used only where the CRS gives none)", t.geo.latitude_deg),
        (true, None) => println!("latitude:    {:.3}° (the grid's own, from its CRS)", t.geo.latitude_deg),
        (false, Some(l)) => println!("latitude:    {l:.3}° (--latitude: the grid's CRS gives none)"),
        (false, None) => println!("latitude:    {:.3}° (the default: the grid's CRS gives none; set it with --latitude)", Climate::default().latitude_deg),
    }
    println!("elevation:   {lo:.1} … {hi:.1} m");
    // the readers treat NaN and infinite values as nodata as well as the file's own nodata
    // value, and keep no count of which was which (trial 41, defect 10: two `nan`/`inf` cells
    // were reported as "file value -9999")
    let why = match t.nodata {
        Some(v) => format!(" (cells of the file's nodata value {v}, or NaN or infinite)"),
        None => " (NaN or infinite cells; the file declares no nodata value)".to_string(),
    };
    println!("nodata:      {} cells{}", g.len() - valid.len(), if g.len() == valid.len() { "" } else { &why });
    let sea = s.sea_level_m();
    let below = valid.iter().filter(|&&v| v <= sea).count();
    if s.sea_level.is_none() && sea == sylva::terrain::NO_SEA_LEVEL_M {
        println!("water:       none (a PNG heightmap has no sea level; give --sea-level to set one)");
    } else {
        println!("water:       {below} cells at or below sea level {sea} m");
    }
    let tin = Tin::build(&t, tolerance, usize::MAX)?;
    println!("TIN:         {} vertices, {} triangles at tolerance {tolerance} m (max error {:.3} m)", tin.num_vertices(), tin.num_triangles(), tin.max_error_m);
    Ok(())
}

/// `sylva terrain maps --scenario FILE`: the living conditions of the scenario's site, the maps
/// `sylva run` writes into `maps/conditions/` (round 32's trial: an ecologist had no way to see
/// a scenario's Ellenberg maps but a one-year `sylva run`).
fn scenario_maps(path: &Path, s: &Source, out: &Path) -> anyhow::Result<()> {
    anyhow::ensure!(s.latitude.is_none(), "--latitude: not with --scenario (the scenario's [climate] latitude_deg sets it)");
    // an --out that is a file is named before any work (round 33's trial: "creating holes.asc:
    // File exists"), as `run` and `simulate` name theirs
    super::check_out_dir(out, "--out")?;
    let sc = Scenario::load(path)?;
    // the site is derived first, so that a refused scenario leaves no output folder behind
    let site = sc.site().with_context(|| format!("[terrain] of {}", sc.context()))?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let names = job_maps::write_site_maps(&site, out)?;
    println!("wrote {} maps (PNG + GeoTIFF) of the site of {} to {}: {}", names.len(), path.display(), out.display(), names.join(", "));
    Ok(())
}

fn maps_cmd(s: &Source, out: &Path) -> anyhow::Result<()> {
    // the DEM is read first, so that a missing or unreadable one leaves no empty output folder
    // behind (found by a trial: `sylva terrain maps nothere.tif` made the folder, then failed);
    // an --out that is a file is named before it (round 33's trial: "creating holes.asc: File
    // exists"), as `run` and `simulate` name theirs
    super::check_out_dir(out, "--out")?;
    let t = s.load()?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let climate = s.climate();
    let stages = 16u64;
    let pb = super::progress(stages, "terrain");
    pb.set_message("loading");
    let f = fields::compute(&t, &climate, &|stage| {
        pb.set_message(stage.to_string());
        pb.inc(1);
    })?;
    let m = f.mask.clone();
    let hs = fields::hillshade(&t, &m, 315.0, 45.0);
    let log_acc = f.flow_acc_cells.map(|v| if *v > 0.0 { v.log10() } else { f32::NAN });
    let flat = f.flat_insolation_kwh_m2;
    let site = conditions::from_fields(&t, &climate, f);
    let mut layers = job_maps::site_layers(&site, Some(flat), Some(climate.wind_from_deg));
    // The raw elevation (masked water included) and two maps the simulation does not read.
    layers[0].grid = t.elevation.clone();
    let extra = |name, grid, ramp, title: &str, units, range| job_maps::Layer { name, grid, ramp, title: title.to_string(), units, range };
    layers.insert(1, extra("hillshade", hs.clone(), maps::Ramp::Grey, "Hillshade (az 315°, alt 45°)", "0–255", Some((0.0, 255.0))));
    layers.insert(4, extra("flow_accumulation", log_acc, maps::Ramp::Blues, "Flow accumulation (D8)", "log10 cells", None));
    pb.set_message("writing maps");
    let names = job_maps::write_layers(&layers, &m, &t.geo, out, Some((&hs, 0.35)))?;
    pb.inc(stages.saturating_sub(pb.position()));
    pb.finish_with_message("done");
    println!("wrote {} maps (PNG + GeoTIFF) to {}", names.len(), out.display());
    Ok(())
}
