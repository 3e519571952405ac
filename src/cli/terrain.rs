//! `sylva terrain info|maps`.
use anyhow::Context;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use sylva::conditions::{self, factor, Climate};
use sylva::grid::{Crs, Grid};
use sylva::output::{geotiff, maps};
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
    /// Cell size (m) of a generated terrain or a PNG heightmap.
    #[arg(long, default_value_t = 10.0)]
    pub cell: f64,
    /// Relief (m) of a generated terrain.
    #[arg(long, default_value_t = 600.0)]
    pub relief: f64,
    /// Seed of a generated terrain.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// PNG heightmap: height (m) of value 0.
    #[arg(long, default_value_t = 0.0)]
    pub min_height: f64,
    /// PNG heightmap: height (m) of the largest value.
    #[arg(long, default_value_t = 1000.0)]
    pub max_height: f64,
    /// Cells at or below this elevation (m) are water and masked.
    #[arg(long, default_value_t = 0.0)]
    pub sea_level: f32,
    /// Latitude (degrees) for insolation when the terrain is not geographic or UTM.
    #[arg(long)]
    pub latitude: Option<f64>,
}

impl Source {
    fn load(&self) -> anyhow::Result<Terrain> {
        if self.generate {
            return Ok(generate::generate(self.size, self.cell, self.relief, self.seed)?);
        }
        Ok(match &self.file {
            None => io::default_terrain()?,
            Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) => io::load_png_heightmap(p, self.cell, self.min_height, self.max_height)?,
            Some(p) => io::load(p)?,
        })
    }
    fn climate(&self) -> Climate {
        let mut c = Climate { sea_level_m: self.sea_level, ..Climate::default() };
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
        /// Output folder (created if missing).
        #[arg(long, default_value = "out/terrain")]
        out: PathBuf,
    },
}

/// Runs a terrain subcommand.
pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Info { source, tolerance } => info(&source, tolerance),
        Command::Maps { source, out } => maps_cmd(&source, &out),
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
    println!("latitude:    {:.3}°", t.geo.latitude_deg);
    println!("elevation:   {lo:.1} … {hi:.1} m");
    println!("nodata:      {} cells{}", g.len() - valid.len(), t.nodata.map(|v| format!(" (file value {v})")).unwrap_or_default());
    let below = valid.iter().filter(|&&v| v <= s.sea_level).count();
    println!("water:       {below} cells at or below sea level {} m", s.sea_level);
    let tin = Tin::build(&t, tolerance, usize::MAX)?;
    println!("TIN:         {} vertices, {} triangles at tolerance {tolerance} m (max error {:.3} m)", tin.num_vertices(), tin.num_triangles(), tin.max_error_m);
    Ok(())
}

fn maps_cmd(s: &Source, out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let t = s.load()?;
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
    let elev = t.elevation.clone();
    let flat = f.flat_insolation_kwh_m2;
    let site = conditions::from_fields(&t, &climate, f.clone());
    let index = |k: usize| -> Grid<f32> { Grid { width: m.width, height: m.height, data: site.indices.data.iter().zip(&m.data).map(|(v, ok)| if *ok { v[k] } else { f32::NAN }).collect() } };
    use maps::Ramp::*;
    let items: Vec<(&str, Grid<f32>, maps::Ramp, String, &str, Option<(f32, f32)>)> = vec![
        ("elevation", elev, Terrain, "Elevation".into(), "m", None),
        ("hillshade", hs.clone(), Grey, "Hillshade (az 315°, alt 45°)".into(), "0–255", Some((0.0, 255.0))),
        ("slope", f.slope_deg.clone(), Viridis, "Slope (Horn)".into(), "degrees", None),
        ("aspect", f.aspect_deg.map(|a| if *a < 0.0 { f32::NAN } else { *a }), Cyclic, "Aspect (from north, clockwise)".into(), "degrees", Some((0.0, 360.0))),
        ("flow_accumulation", log_acc, Blues, "Flow accumulation (D8)".into(), "log10 cells", None),
        ("twi", f.twi.clone(), Blues, "Topographic wetness index".into(), "ln(m)", None),
        ("insolation", f.insolation_kwh_m2.clone(), Magma, format!("Annual clear-sky insolation (flat {flat:.0})"), "kWh/m²/yr", None),
        ("wind_exposure", f.wind_exposure.clone(), Viridis, format!("Wind exposure (wind from {}°)", climate.wind_from_deg), "0–1", Some((0.0, 1.0))),
        ("temperature", f.temperature_c.clone(), BlueRed, "Mean annual temperature".into(), "°C", None),
        ("L", index(factor::L), Magma, "Ellenberg-style L (light)".into(), "1–9", Some((1.0, 9.0))),
        ("T", index(factor::T), BlueRed, "Ellenberg-style T (temperature)".into(), "1–9", Some((1.0, 9.0))),
        ("K", index(factor::K), Viridis, "Ellenberg-style K (continentality)".into(), "1–9", Some((1.0, 9.0))),
        ("F", index(factor::F), Blues, "Ellenberg-style F (moisture)".into(), "1–12", Some((1.0, 12.0))),
        ("R", index(factor::R), Viridis, "Ellenberg-style R (soil reaction)".into(), "1–9", Some((1.0, 9.0))),
        ("N", index(factor::N), Viridis, "Ellenberg-style N (nitrogen)".into(), "1–9", Some((1.0, 9.0))),
    ];
    pb.set_message("writing maps");
    for (name, grid, ramp, title, units, range) in &items {
        let shade = if *name == "hillshade" { None } else { Some(&hs) };
        let style = maps::MapStyle { ramp: *ramp, title: title.clone(), units: units.to_string(), range: *range, hillshade: shade, shade_strength: 0.35 };
        maps::write_field_png_styled(grid, Some(&m), &style, &out.join(format!("{name}.png")))?;
        geotiff::write_f32(&out.join(format!("{name}.tif")), grid, &t.geo)?;
    }
    pb.inc(stages.saturating_sub(pb.position()));
    pb.finish_with_message("done");
    println!("wrote {} maps (PNG + GeoTIFF) to {}", items.len(), out.display());
    Ok(())
}
