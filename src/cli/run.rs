//! `sylva run [SCENARIO]`: the main job ([`sylva::job::main_job::main_job`]; this module parses
//! the arguments, draws progress and handles Ctrl-C). Derives the living conditions of the scenario's
//! terrain, simulates the forest, and writes maps, the stand table and its plot, inventory
//! snapshots, stills from an oblique and a top-down camera at years 0, 10, 25, 50, 100 and 150
//! (or the scenario's `still_years`, `--still-years`),
//! a timelapse GIF (MP4 too when ffmpeg is installed) and `summary.md`.

use std::path::PathBuf;
use std::time::Instant;
use sylva::job::main_job::{self, Event, MainJobOptions};
use sylva::sim::Scenario;

/// Arguments of `sylva run`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML); the embedded default scenario when omitted.
    pub scenario: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Override the scenario's number of years (1–10,000).
    // a range of its own, and a negative value read as one (clap's tip for `--years -3` was
    // to pass `-- -3`, which names a scenario; round 30's trial)
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub years: Option<u32>,
    /// Years of the stills from afar, comma-separated and ascending, within the run (e.g.
    /// `20,40`); overrides the scenario's `still_years` (default: 0, 10, 25, 50, 100 and 150 as
    /// far as the run reaches). The last year is drawn too. Each is a snapshot year (maps, key
    /// frame).
    #[arg(long, value_parser = parse_years, value_name = "Y,Y,...")]
    pub still_years: Option<YearList>,
    /// Size of the stills WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = super::render::parse_size)]
    pub size: (u32, u32),
    /// Size of the timelapse frames WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = super::render::parse_size)]
    pub timelapse_size: (u32, u32),
    /// Interpolated timelapse frames between snapshots a regular interval apart (0–50; 0: one per snapshot); shorter or longer intervals get frames in proportion to their years.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=50))]
    pub frames_between: u32,
    /// Timelapse frames per second (1–100).
    #[arg(long, default_value_t = 8.0, value_parser = super::render::parse_fps)]
    pub fps: f32,
    /// Skip stills and timelapse (no GPU or software adapter needed).
    #[arg(long, alias = "no-render")]
    pub no_pictures: bool,
    /// Folder of extra or edited species files (e.g. made by `sylva species new`): they are
    /// added to the shipped library, replacing shipped species of the same id.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// File format of the inventories and regeneration tables: `parquet` (GeoParquet, read by
    /// geopandas, R arrow, DuckDB, QGIS) or `csv`.
    #[arg(long, default_value = "parquet")]
    pub inventory: sylva::output::inventory::InventoryFormat,
}

/// The years of `--still-years` (one option value, comma-separated).
#[derive(Debug, Clone, PartialEq)]
pub struct YearList(pub Vec<u32>);

/// Parses `--still-years`: whole numbers 0–10,000 separated by commas (ascending and within the
/// run is checked with the scenario).
fn parse_years(s: &str) -> Result<YearList, String> {
    s.split(',')
        .map(|y| y.trim().parse::<u32>().ok().filter(|&y| y <= 10_000).ok_or_else(|| format!("`{s}`: expected years as whole numbers 0–10000 separated by commas, e.g. 20,40 (`{}` is not one)", y.trim())))
        .collect::<Result<Vec<u32>, String>>()
        .map(YearList)
}

/// Runs the main job.
pub fn run(a: Args) -> anyhow::Result<()> {
    super::refuse_mpi_launch("run", false)?;
    let mut sc = match &a.scenario {
        Some(p) => Scenario::load(p)?,
        None => main_job::default_scenario()?,
    };
    let warned = super::simulate::apply_years(&mut sc, a.years, false)?;
    if let Some(ys) = &a.still_years {
        sc.still_years = Some(ys.0.clone());
        sc.validate("--still-years")?;
    }
    super::check_out_dir(&a.out, "--out")?;
    let _lock = super::lock_run_dir(&a.out, "--out")?;
    let lib = super::simulate::library(a.species_dir.as_deref().as_slice())?;
    let opts = MainJobOptions { out: a.out.clone(), size: a.size, timelapse_size: a.timelapse_size, frames_between: a.frames_between, fps: a.fps, render: !a.no_pictures, stop: Some(super::simulate::stop_on_ctrl_c()), inventory: a.inventory };
    let mut bars = Bars::default();
    let summary = match main_job::main_job(&sc, &lib, &opts, &mut |e| bars.show(e)) {
        // Ctrl-C during the pictures: exit status 130 like a stop during the simulation
        Err(e @ sylva::job::JobError::Stopped(_)) => return Err(super::Interrupted(e.to_string()).into()),
        r => r?,
    };
    if summary.sim.stopped {
        // `sylva run` itself starts over: the simulation continues with `simulate --resume`
        let out = a.out.display();
        return Err(super::simulate::interrupted(&summary.sim, &format!("continue the simulation with `sylva simulate {out}/scenario.toml --out {out} --resume`, then draw the pictures with `sylva render {out}` and `sylva timelapse {out}`")).into());
    }
    let (table, shares) = summary.tables();
    println!("\n{}\n{}", table, shares);
    println!("{}", summary.coordinates_md());
    if summary.film.as_ref().is_some_and(|f| !f.mp4) {
        println!("timelapse.gif written; no MP4: ffmpeg is not on PATH");
    }
    for w in &warned {
        eprintln!("warning: {w} (also in summary.md)");
    }
    println!("outputs in {} (see summary.md)", a.out.display());
    Ok(())
}

/// The main job's progress on stderr: a line per step, a bar for the years, the stills and the
/// timelapse's frames.
#[derive(Default)]
struct Bars {
    sim: super::simulate::SimBar,
    bar: Option<indicatif::ProgressBar>,
    t0: Option<Instant>,
    /// The run directory (from [`Event::Begin`]).
    out: Option<std::path::PathBuf>,
    /// Stills drawn and their count, and the tenth said last where stderr is no terminal
    /// ([`super::plain_progress`]).
    stills: (u64, u64, u64),
    /// The tenth of the timelapse's frames said last where stderr is no terminal.
    frames_said: u64,
}

impl Bars {
    fn show(&mut self, e: &Event) {
        match e {
            Event::Begin { name, years, seed, out } => {
                eprintln!("Sylva · {name} · {years} years · seed {seed} → {}", out.display());
                self.out = Some(out.to_path_buf());
            }
            Event::Conditions { width, height, extent_m: (ex, ey), maps, seconds } => {
                // said once the scenario has been checked against its site (before, a refused
                // scenario was preceded by this note; round 30's trial)
                if let Some(out) = &self.out {
                    super::simulate::note_replaced_run(out);
                }
                eprintln!("[1/4] conditions: {width} × {height} cells, {:.2} km × {:.2} km, {} maps ({seconds:.1} s)", ex / 1000.0, ey / 1000.0, maps.len());
            }
            Event::Simulating { years } => {
                eprintln!("[2/4] simulating {years} years");
                self.sim.show(e);
            }
            Event::NoAdapter { message } => eprintln!("warning: {message}\n  the run goes on without pictures: maps, tables and inventories are written, then it ends with this error (`--no-pictures` skips the pictures on purpose)"),
            Event::Stills { count, adapter } => {
                eprintln!("[3/4] stills on {adapter}");
                self.bar = Some(super::progress(*count as u64, "stills"));
                self.stills = (0, *count as u64, 0);
            }
            Event::Still => {
                if let Some(pb) = &self.bar {
                    pb.inc(1);
                }
                let (done, total, said) = &mut self.stills;
                *done += 1;
                super::plain_progress("stills", *done, *total, said, "");
            }
            Event::CloseUpBegin { year } => eprintln!("close-up of year {year}: adapting the trees near the camera to their neighbours at full detail (the longest picture)"),
            Event::CloseUp(ad) => eprintln!("close-up: {} trees adapted to their neighbours ({:.1} s adaptation, {:.1} s meshes)", ad.adapted_trees, ad.adapt_s, ad.mesh_s),
            Event::Timelapse => {
                eprintln!("[4/4] timelapse");
                self.bar = Some(super::progress(1, "timelapse"));
                self.t0 = Some(Instant::now());
                self.frames_said = 0;
            }
            Event::Frame { done, total } => {
                if let (Some(pb), Some(t0)) = (&self.bar, self.t0) {
                    let msg = format!("{:.1} frames/s", *done as f64 / t0.elapsed().as_secs_f64().max(1e-3));
                    super::plain_progress("timelapse frames", *done as u64, *total as u64, &mut self.frames_said, &msg);
                    pb.set_length(*total as u64);
                    pb.set_position(*done as u64);
                    pb.set_message(msg);
                }
            }
            Event::StillsDone | Event::TimelapseDone => {
                if let Some(pb) = self.bar.take() {
                    pb.finish_and_clear();
                }
            }
            Event::Resuming { year, stills_drawn, frames_drawn } => eprintln!("[resume] the simulation of {year} years is complete in this folder and its pictures were stopped ({stills_drawn} stills, {frames_drawn} film frames drawn): drawing only the missing pictures, not simulating again (run into another --out, or remove {}/.sylva_pictures.json, to start afresh)", self.out.as_ref().map_or(String::new(), |o| o.display().to_string())),
            Event::Year(_) | Event::Simulated(_) => self.sim.show(e),
        }
    }
}
