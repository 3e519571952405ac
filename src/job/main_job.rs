//! The main job as library calls: [`main_job`] is the whole of `sylva run` (living conditions →
//! maps → simulation → stills → close-up → timelapse → `summary.md`), [`simulate`] the whole of
//! `sylva simulate` (the run directory of a scenario, stepped in one process, in tiles or as
//! rank 0 of MPI ranks). Both report through a progress sink (a closure over [`Event`]) and
//! return a summary; the command line only parses arguments, draws progress bars and handles
//! Ctrl-C (the stop flag of the options). What a run writes is listed once, with its schedule,
//! in [`OUTPUTS`].

use crate::output::inventory::InventoryFormat;
use super::adapted::AdaptStats;
use super::keyframes::{self, KeyFrames};
pub use super::timing::{process_cpu_s, Clock, PhaseTime};
use super::pictures::{self, Stage, TimelapseOptions};
use super::run::{run_scenario, OnSnapshot, Progress, RunOptions};
use super::{scene, JobError, Result};
use crate::render::camera::{Camera, CameraPreset};
use crate::sim::scenario::Scenario;
use crate::sim::stats::StandRow;
use crate::sim::tiles::Transport;
use crate::sim::world::World;
use crate::species::{Season, SpeciesLibrary};
use crate::conditions::SiteConditions;
use crate::Error;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

/// The embedded default scenario (`scenarios/default.toml`).
pub const DEFAULT_SCENARIO: &str = include_str!("../../scenarios/default.toml");

/// The name [`default_scenario`] gives the embedded scenario in its error messages.
pub const DEFAULT_SCENARIO_SOURCE: &str = "embedded default scenario (scenarios/default.toml)";

/// The embedded default scenario, parsed.
///
/// Errors: none for the shipped file (a test parses it); [`Error::Format`] / [`Error::Invalid`]
/// naming [`DEFAULT_SCENARIO_SOURCE`] otherwise.
pub fn default_scenario() -> crate::Result<Scenario> {
    Scenario::from_toml_str(DEFAULT_SCENARIO, DEFAULT_SCENARIO_SOURCE)
}

/// Years at which [`main_job`] renders stills when the scenario names none (`still_years`;
/// those that are snapshot years of the run; the last snapshot's year is always added).
pub const STILL_YEARS: [u32; 6] = [0, 10, 25, 50, 100, 150];

/// The years [`main_job`] draws stills from afar at, ascending: the scenario's `still_years`
/// (else [`STILL_YEARS`]) that have a key frame (`key_years`, the run's plain snapshots), and
/// the last key year.
pub fn still_years(sc: &Scenario, key_years: &[u32]) -> Vec<u32> {
    let wanted: &[u32] = sc.still_years.as_deref().unwrap_or(&STILL_YEARS);
    let mut years: Vec<u32> = wanted.iter().copied().filter(|y| key_years.contains(y)).collect();
    if let Some(&last) = key_years.iter().max() {
        if !years.contains(&last) {
            years.push(last);
        }
    }
    years.sort_unstable();
    years
}

/// The default still years ([`STILL_YEARS`], when the scenario names no `still_years`) within
/// the run (≤ `years`) that [`still_years`] leaves out because they have no key frame (not a
/// snapshot year: e.g. 25 with `snapshot_every = 10`), ascending; empty when the scenario names
/// its own still years (those are snapshot years by [`Scenario::snapshot_year`]). Trial 47 D8:
/// [`main_job`] warns about them instead of dropping them silently.
pub fn skipped_still_years(sc: &Scenario, key_years: &[u32]) -> Vec<u32> {
    if sc.still_years.is_some() {
        return Vec::new();
    }
    STILL_YEARS.iter().copied().filter(|&y| y <= sc.years && !key_years.contains(&y)).collect()
}

/// When an output of a run is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// Once, when the run starts (a resumed run rewrites `scenario.toml` only).
    Start,
    /// At every plain snapshot: year 0 of a fresh run, every `snapshot_every` years, every
    /// year whose management removed trees (thinning, harvest), the last year, a year stopped
    /// at.
    Snapshot,
    /// At the plain snapshots that hold the tree inventory: year 0 of a fresh run, every
    /// `inventory_every` years (absent: every snapshot), every year whose management removed
    /// trees, the last year, a year stopped at.
    Inventory,
    /// At the inventory snapshots of `seasonal_snapshots` runs, after spring, summer and
    /// autumn.
    Season,
    /// At every checkpoint: every `checkpoint_every` years, the last year, a year stopped at.
    Checkpoint,
    /// After the simulation, once per still year ([`still_years`]: the scenario's `still_years`
    /// or [`STILL_YEARS`] within the run, and the last snapshot's year); `sylva run` only.
    StillYears,
    /// Once after the simulation; `sylva run` only.
    End,
}

/// One output of a run directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Output {
    /// Path in the run directory; `NNNN` stands for a four-digit year (`NNNNN` a frame
    /// number), `*` for any name, `{a,b}` for one of the names.
    pub path: &'static str,
    /// When it is written.
    pub when: When,
    /// True for outputs of `sylva run` ([`main_job`]) only, false for outputs of both commands.
    pub main_job_only: bool,
    /// What it holds.
    pub what: &'static str,
}

/// Every file a run directory may hold, with its schedule (tests/main_job.rs checks that a
/// run writes nothing else). `sylva simulate` ([`simulate`]) writes those with
/// `main_job_only` false; [`main_job`] all of them (GeoPackage inventories only for the last
/// year).
pub const OUTPUTS: &[Output] = &[
    Output { path: "scenario.toml", when: When::Start, main_job_only: false, what: "the scenario as run (`years` included)" },
    Output { path: "species/*.toml", when: When::Start, main_job_only: false, what: "the species files of the pool, as simulated" },
    Output { path: "maps/conditions/*.{png,tif}", when: When::Start, main_job_only: true, what: "condition maps with legends and GeoTIFFs" },
    Output { path: "inventory/year_NNNN.{parquet,csv}", when: When::Inventory, main_job_only: false, what: "every tree (GeoParquet by default; CSV with `--inventory csv`)" },
    Output { path: "inventory/year_NNNN.gpkg", when: When::Inventory, main_job_only: false, what: "every tree as a GeoPackage point layer `inventory` (the main job: the last year only)" },
    Output { path: "inventory/year_NNNN_regeneration.{parquet,csv}", when: When::Inventory, main_job_only: false, what: "the sapling cohorts of the regeneration layer" },
    Output { path: "inventory/year_NNNN_{spring,summer,autumn}.{parquet,csv,gpkg}", when: When::Season, main_job_only: false, what: "seasonal inventories" },
    Output { path: "maps/{species,basal_area}_year_NNNN.{png,tif}", when: When::Snapshot, main_job_only: false, what: "dominant species and basal-area maps" },
    Output { path: "maps/species_codes.csv", when: When::Snapshot, main_job_only: false, what: "the codes of the species GeoTIFFs" },
    Output { path: "stand_table.{csv,png}", when: When::Checkpoint, main_job_only: false, what: "one row per year, and its plot (also at every snapshot)" },
    Output { path: "stand_table_species.csv", when: When::Checkpoint, main_job_only: false, what: "one row per year and species: stems, basal area, Dq, the species' H100, volume, and its deaths and harvest (also at every snapshot)" },
    Output { path: "management_table.csv", when: When::Checkpoint, main_job_only: false, what: "a run with `[[management]]`: one row per year and entry, the figures of the entry's area and its harvest (also at every snapshot)" },
    Output { path: "checkpoint.bin", when: When::Checkpoint, main_job_only: false, what: "the latest checkpoint (a tiled run: `checkpoint/`)" },
    Output { path: "checkpoint/*", when: When::Checkpoint, main_job_only: false, what: "per-rank checkpoints of a tiled run" },
    Output { path: "stills/year_NNNN_{oblique,topdown}.png", when: When::StillYears, main_job_only: true, what: "stills from afar" },
    Output { path: "stills/year_NNNN_closeup.png", when: When::End, main_job_only: true, what: "a close view into the last year's forest, its near field adapted" },
    Output { path: "frames/frame_NNNNN.png", when: When::End, main_job_only: true, what: "the timelapse's frames" },
    Output { path: "timelapse.{gif,mp4}", when: When::End, main_job_only: true, what: "the timelapse (MP4 when ffmpeg is installed)" },
    Output { path: "summary.md", when: When::End, main_job_only: true, what: "the figures and every picture in one page" },
    Output { path: "timings.csv", when: When::End, main_job_only: true, what: "where the run's time went: each phase's wall and CPU seconds" },
];

/// Whether `rel` (a path in a run directory, `/`-separated) is one of [`OUTPUTS`]' patterns:
/// `N` matches a digit, `*` one or more characters other than `/`, `{a,b}` one of the names.
pub fn is_output(rel: &str) -> bool {
    OUTPUTS.iter().any(|o| expand(o.path).iter().any(|p| matches_pattern(p.as_bytes(), rel.as_bytes())))
}

/// Removes from the run directory `dir` the files an earlier `sylva run` wrote that only the
/// main job writes ([`OUTPUTS`] with `main_job_only`: condition maps, stills, the timelapse and
/// its frames, `summary.md`), and the folders `maps/conditions`, `stills` and `frames` when that
/// leaves them empty; other files are kept. A fresh run into the folder calls it once its
/// scenario is known to run ([`main_job`] before its condition maps; `sylva simulate`, which
/// writes none of them, when it starts simulating), so that a new run never sits beside
/// another run's pictures and summary (round 32's trial: `summary.md` and the condition maps
/// of a Coweeta run stayed beside a new 1 ha run). Returns what it removed (paths relative to
/// `dir`, `/`-separated, sorted).
///
/// Errors: [`Error::Io`] naming the folder or file that cannot be listed or removed.
pub fn clear_main_job_outputs(dir: &Path) -> Result<Vec<String>> {
    let mut removed = Vec::new();
    for sub in ["", "maps/conditions", "stills", "frames"] {
        let d = if sub.is_empty() { dir.to_path_buf() } else { dir.join(sub) };
        if !d.is_dir() {
            continue;
        }
        for e in std::fs::read_dir(&d).map_err(|e| Error::io(&d, e))? {
            let e = e.map_err(|err| Error::io(&d, err))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let rel = if sub.is_empty() { name } else { format!("{sub}/{name}") };
            let main_only = OUTPUTS.iter().filter(|o| o.main_job_only).any(|o| expand(o.path).iter().any(|p| matches_pattern(p.as_bytes(), rel.as_bytes())));
            if main_only && e.path().is_file() {
                std::fs::remove_file(e.path()).map_err(|err| Error::io(&e.path(), err))?;
                removed.push(rel);
            }
        }
        if !sub.is_empty() {
            // only while empty
            let _ = std::fs::remove_dir(&d);
        }
    }
    removed.sort();
    Ok(removed)
}

/// The patterns of `p` with its `{a,b}` groups expanded.
fn expand(p: &str) -> Vec<String> {
    let (Some(i), Some(j)) = (p.find('{'), p.find('}')) else { return vec![p.to_string()] };
    p[i + 1..j].split(',').flat_map(|alt| expand(&format!("{}{alt}{}", &p[..i], &p[j + 1..]))).collect()
}

fn matches_pattern(p: &[u8], s: &[u8]) -> bool {
    match (p.first(), s.first()) {
        (None, None) => true,
        (Some(b'*'), Some(&c)) if c != b'/' => matches_pattern(&p[1..], &s[1..]) || matches_pattern(p, &s[1..]),
        (Some(b'N'), Some(c)) if c.is_ascii_digit() => matches_pattern(&p[1..], &s[1..]),
        (Some(a), Some(b)) if *a != b'*' && *a != b'N' && a == b => matches_pattern(&p[1..], &s[1..]),
        _ => false,
    }
}

/// What [`main_job`] and [`simulate`] report while they run, in order.
#[derive(Debug)]
pub enum Event<'a> {
    /// The main job starts: the scenario's name, years and seed, the run directory.
    Begin {
        /// Scenario name.
        name: &'a str,
        /// Years to simulate.
        years: u32,
        /// Scenario seed.
        seed: u64,
        /// Run directory.
        out: &'a Path,
    },
    /// The living conditions are derived and mapped: grid size (cells), extent (m), map names,
    /// wall time (s).
    Conditions {
        /// Grid columns.
        width: usize,
        /// Grid rows.
        height: usize,
        /// Extent east and north (m).
        extent_m: (f64, f64),
        /// Names of the condition maps written (`maps/conditions/NAME.png`).
        maps: &'a [String],
        /// Wall time (s).
        seconds: f64,
    },
    /// The simulation of `years` years starts: the scenario has been checked against its site
    /// (a refused one ends before this event).
    Simulating {
        /// Years of the scenario.
        years: u32,
    },
    /// A year is simulated.
    Year(&'a Progress),
    /// `sylva run` into the folder of an earlier `sylva run` of the same scenario, species and
    /// picture options that was stopped (or killed) after its simulation while drawing its
    /// pictures: the simulation of `year` years is not run again; only the missing pictures
    /// are drawn (trial 46 D10).
    Resuming {
        /// The last year simulated.
        year: u32,
        /// Stills (from afar and the close-up) already drawn.
        stills_drawn: usize,
        /// Film frames already drawn.
        frames_drawn: usize,
    },
    /// The simulation ended (or was stopped: [`Simulated::stopped`]).
    Simulated(&'a Simulated),
    /// `sylva run` found no graphics adapter before simulating (`message`: what wgpu said and
    /// the package to install): it simulates and writes every output that needs no rendering,
    /// then ends with [`JobError::Render`].
    NoAdapter {
        /// The error, naming the package to install.
        message: String,
    },
    /// The stills start: `count` pictures from afar (two per still year) on the renderer's
    /// `adapter`.
    Stills {
        /// Stills from afar to come.
        count: usize,
        /// The renderer's adapter (name, driver).
        adapter: &'a str,
    },
    /// A still from afar is written.
    Still,
    /// The close-up of year `year` starts: its near field is adapted at full detail, the
    /// longest picture of the run (said so that a run under load is not silent for minutes;
    /// trial 36).
    CloseUpBegin {
        /// The close-up's year.
        year: u32,
    },
    /// The close-up is written, with what its near field adapted.
    CloseUp(&'a AdaptStats),
    /// The stills are done.
    StillsDone,
    /// The timelapse starts.
    Timelapse,
    /// `done` of `total` timelapse frames are written.
    Frame {
        /// Frames written so far.
        done: usize,
        /// Frames of the film.
        total: usize,
    },
    /// The timelapse is done.
    TimelapseDone,
}

/// A progress sink: called with every [`Event`] (`&mut |_| {}` ignores them).
pub type Sink<'s> = dyn FnMut(&Event) + 's;

/// How [`simulate`] steps the years.
pub enum Stepping<'a> {
    /// One process, the whole landscape.
    One,
    /// N tiles, one thread each, in this process (`sylva simulate --tiles N`).
    Local(usize),
    /// Rank 0 of a tiled run over a transport (MPI); the other ranks run
    /// [`super::tiled::work`].
    Ranks(&'a mut dyn Transport),
}

/// Options of [`simulate`].
pub struct SimulateOptions {
    /// Run directory (created; it must not be a file).
    pub out: PathBuf,
    /// Continue from the run directory's checkpoint ([`RunOptions::resume`]).
    pub resume: bool,
    /// Years whose snapshots also get a GeoPackage inventory (`None`: all; the last year always).
    pub gpkg_years: Option<Vec<u32>>,
    /// Stop after the current year when set (e.g. by a Ctrl-C handler); the outputs so far are
    /// complete and a checkpoint is written.
    pub stop: Option<Arc<AtomicBool>>,
    /// File format of the inventories (`--inventory`; default Parquet).
    pub inventory: InventoryFormat,
}

impl SimulateOptions {
    /// A fresh run into `out`: no resume, GeoPackage at every snapshot, no stop flag.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        SimulateOptions { out: out.into(), resume: false, gpkg_years: None, stop: None, inventory: InventoryFormat::Parquet }
    }
}

/// What a simulation did.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// Scenario name.
    pub name: String,
    /// The last year simulated.
    pub year: u32,
    /// Living trees at the end (all sizes).
    pub trees_alive: usize,
    /// Species ids of the pool, in stand-table order.
    pub pool: Vec<String>,
    /// The pool's species as the maps' legends name them (`identity.common_name`, e.g.
    /// "Norway maple"), in the order of [`Simulated::pool`]: `summary.md`'s species table
    /// (trial 46 D14: it wrote the ids, `norway_maple`).
    pub pool_names: Vec<String>,
    /// Stand table, one row per year.
    pub rows: Vec<StandRow>,
    /// True when stopped early by the stop flag (outputs so far complete; continue with a
    /// resume).
    pub stopped: bool,
    /// Wall time of the years simulated (s).
    pub seconds: f64,
    /// Wall time (s) of each phase ([`crate::sim::step::PHASES`] names) and of the yearly
    /// outputs (`"outputs"`), summed over the years (a tiled run: rank 0's tile, its exchanges
    /// included).
    pub phase_seconds: Vec<(&'static str, f64)>,
    /// The run directory.
    pub out: PathBuf,
}

/// Errors: [`Error::Format`] naming `out` when it is a file.
fn check_out(out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        return Err(Error::format(out, "is a file; expected a folder for the run's outputs").into());
    }
    Ok(())
}

/// `r` with its error under the message `what` ([`JobError::Context`]).
fn context<T>(r: Result<T>, what: impl FnOnce() -> String) -> Result<T> {
    r.map_err(|e| JobError::Context { what: what(), source: Box::new(e) })
}

/// Folder of a run directory that holds the species files the run was simulated with.
pub fn run_species_dir(run_dir: &Path) -> PathBuf {
    run_dir.join("species")
}

/// Writes the pool's species files into `RUN/species/` (so `render`, `timelapse` and a
/// `--resume` find the same species later, also edited or custom ones) and removes the other
/// `.toml` files there (an earlier run's pool). A scenario with `species = []` pools every
/// species of the library, and all of them are written.
///
/// Errors: I/O errors naming the folder or file; serialising a species.
pub fn save_run_species(sc: &Scenario, lib: &SpeciesLibrary, run_dir: &Path) -> Result<()> {
    let dir = run_species_dir(run_dir);
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let pool: Vec<&crate::species::Species> = if sc.species.is_empty() { lib.species.iter().collect() } else { sc.species.iter().filter_map(|name| lib.get(name)).collect() };
    for sp in &pool {
        crate::output::write_atomic(&dir.join(format!("{}.toml", sp.id)), sp.to_toml_string()?.as_bytes())?;
    }
    // an earlier run's species files that are not in this pool are removed: `render`,
    // `timelapse` and `--resume` read this folder as the run's pool (trial 36 found an old run's
    // `sessile_oak.toml` beside a new beech-only run's file)
    for e in std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))? {
        let p = e.map_err(|e| Error::io(&dir, e))?.path();
        let stale = p.extension().is_some_and(|x| x == "toml") && p.file_stem().is_some_and(|st| !pool.iter().any(|sp| st.to_string_lossy() == sp.id));
        if stale && p.is_file() {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

/// Runs `sc` on `site` with species from `lib` into the run directory `opts.out`, stepped as
/// `stepping` says: saves the pool's species files (not on a resume with a checkpoint), then
/// [`run_scenario`] (or a tiled run) with `on_snapshot` called at every plain snapshot with the
/// in-memory world. Reports [`Event::Simulating`], [`Event::Year`] and [`Event::Simulated`].
/// A run stopped by `opts.stop` returns with [`Simulated::stopped`] set.
///
/// Errors: as [`run_scenario`] under "simulating NAME"; [`Error::Format`] when `opts.out` is
/// a file.
pub fn simulate(sc: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: SimulateOptions, stepping: Stepping, on_snapshot: Option<&mut OnSnapshot>, sink: &mut Sink) -> Result<Simulated> {
    let out = opts.out;
    check_out(&out)?;
    // the scenario is checked against its site before any folder is made (a refused scenario
    // left `inventory/`, `maps/` and `species/` behind; found by a break-it pass)
    let site = context(World::check(site, lib, sc).map_err(JobError::from), || format!("simulating {}", sc.name))?;
    // a tile count the site cannot hold is refused before any folder is made (the ranks of an
    // MPI run are told by `tiled::run_tiled`, which checks the same before any rank waits)
    if let Stepping::Local(n) = stepping {
        context(super::tiled::check_tile_count(&site, sc, n), || format!("simulating {}", sc.name))?;
    }
    // `--resume` into a folder that holds no run (a mistyped --out) is refused before the
    // species files below would make it look like one (a trial's resume started from year 0)
    if opts.resume && !super::checkpoint::exists(&out) {
        context(super::run::started_here(&out, &out.join(super::checkpoint::FILE)).map_err(JobError::from), || format!("simulating {}", sc.name))?;
    }
    // said once the scenario is known to run (a caller's note that the folder's earlier run
    // is replaced came before a refusal; round 30's trial)
    sink(&Event::Simulating { years: sc.years });
    let mut phase_sums = [0f64; crate::sim::step::N_PHASES + 1];
    let mut cb = |p: &Progress| {
        for (k, s) in p.phase_seconds.iter().chain([&p.output_seconds]).enumerate() {
            phase_sums[k] += s;
        }
        sink(&Event::Year(p));
    };
    // a resumed run keeps the species files it was simulated with (a changed species is
    // refused by the checkpoint before anything is written); a fresh one writes them once the
    // world is built, so a scenario the ranks of an MPI run refuse as they build their tiles
    // (a managed area without ground, a planting that plants nothing) leaves no folder, as
    // one process refuses it in `World::check` above (issue 37 round 37)
    let fresh = !(opts.resume && super::checkpoint::exists(&out));
    let mut species = || if fresh { save_run_species(sc, lib, &out) } else { Ok(()) };
    let mut ro = RunOptions::new(&out);
    ro.on_start = Some(&mut species);
    ro.resume = opts.resume;
    ro.gpkg_years = opts.gpkg_years;
    ro.inventory = opts.inventory;
    ro.stop = opts.stop;
    ro.progress = Some(&mut cb);
    let mut on_snapshot = on_snapshot;
    if let Some(f) = on_snapshot.as_mut() {
        ro.on_snapshot = Some(&mut **f);
    }
    let res = match stepping {
        Stepping::One => run_scenario(sc, site, lib, ro),
        Stepping::Local(n) => super::tiled::run_local_tiles(sc, site, lib, ro, n).map(|r| r.0),
        Stepping::Ranks(t) => super::tiled::run_tiled(sc, site, lib, ro, t).and_then(|r| r.ok_or_else(|| Error::Exchange { peer: 0, reason: "rank 0 ended without a run summary".into() }.into())),
    };
    let res = context(res, || format!("simulating {}", sc.name))?;
    let names = crate::sim::step::PHASES.iter().map(|p| p.name).chain(["outputs"]);
    let pool = res.world.site.pool.iter().map(|&s| res.world.site.lib.species[s as usize].id.clone()).collect();
    let pool_names = res.world.site.pool.iter().map(|&s| res.world.site.lib.species[s as usize].identity.common_name.clone()).collect();
    let done = Simulated { name: sc.name.clone(), year: res.world.stand.year, trees_alive: res.trees, pool, pool_names, rows: res.rows, stopped: res.stopped, seconds: res.seconds, phase_seconds: names.zip(phase_sums).collect(), out };
    sink(&Event::Simulated(&done));
    Ok(done)
}

/// Options of [`main_job`].
#[derive(Debug, Clone)]
pub struct MainJobOptions {
    /// Output folder (created; it must not be a file).
    pub out: PathBuf,
    /// Size of the stills (px).
    pub size: (u32, u32),
    /// Size of the timelapse frames (px).
    pub timelapse_size: (u32, u32),
    /// Interpolated timelapse frames between consecutive snapshots (0–50).
    pub frames_between: u32,
    /// Timelapse frames per second (1–100).
    pub fps: f32,
    /// Render stills and the timelapse (false: no GPU or software adapter needed).
    pub render: bool,
    /// Stop after the current year when set (e.g. by a Ctrl-C handler): no pictures, no
    /// `summary.md`; [`Simulated::stopped`] is set.
    pub stop: Option<Arc<AtomicBool>>,
    /// File format of the inventories (`--inventory`; default Parquet).
    pub inventory: InventoryFormat,
}

impl MainJobOptions {
    /// The defaults of `sylva run`: stills 1280 × 720, frames 640 × 360, one interpolated
    /// frame between snapshots, 8 frames per second, rendering on, no stop flag.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        MainJobOptions { out: out.into(), size: (1280, 720), timelapse_size: (640, 360), frames_between: 1, fps: 8.0, render: true, stop: None, inventory: InventoryFormat::Parquet }
    }
}

/// One still of the main job.
#[derive(Debug, Clone, PartialEq)]
pub struct Still {
    /// Snapshot year.
    pub year: u32,
    /// View: `oblique`, `topdown` or `closeup`.
    pub view: String,
    /// The PNG written.
    pub path: PathBuf,
}

/// The timelapse of the main job.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    /// The GIF written.
    pub gif: PathBuf,
    /// Frames in it.
    pub frames: usize,
    /// True when an MP4 was written beside it.
    pub mp4: bool,
}

/// What [`main_job`] did.
#[derive(Debug, Clone)]
pub struct MainJobSummary {
    /// The simulation.
    pub sim: Simulated,
    /// Scenario name, years, seed and species count as `summary.md` states them.
    pub scenario: Scenario,
    /// Names of the condition maps (`maps/conditions/NAME.png`).
    pub maps: Vec<String>,
    /// Stills written, in order (empty without rendering or when stopped).
    pub stills: Vec<Still>,
    /// The timelapse (none without rendering or when stopped).
    pub film: Option<Film>,
    /// Wall time (s) of the living conditions and their maps.
    pub site_s: f64,
    /// Wall time (s) of the simulation.
    pub sim_s: f64,
    /// Wall time (s) of the pictures.
    pub pictures_s: f64,
    /// Wall time (s) of the whole job.
    pub total_s: f64,
    /// Wall and CPU seconds of each phase of the job ([`PhaseTime`], written to `timings.csv`
    /// and `summary.md`); a run that finished an earlier run's pictures ([`Event::Resuming`])
    /// lists the earlier run's conditions and simulation first.
    pub timings: Vec<PhaseTime>,
    /// True when this run finished the pictures of an earlier, stopped run without simulating
    /// ([`Event::Resuming`]).
    pub resumed: bool,
    /// How the site's local metres map to the terrain's map coordinates (its south-west corner
    /// and CRS), as the inventories' geometry and the map GeoTIFFs use it.
    pub geo: crate::output::georef::PointGeoRef,
    /// The site's size (m): `(east-west, south-north)`.
    pub extent_m: (f64, f64),
    /// Columns, rows and the east-west cell size (m) of the site's grid.
    pub cells: (usize, usize, f64),
}

impl MainJobSummary {
    /// The summary's "Site and coordinates" paragraph (Markdown): the site's size and cells, the
    /// map coordinates of its south-west corner, and how local metres (inventory `x_m`, `y_m`,
    /// `--area`, `--camera`, scenario points) become map coordinates. A trial's artist had to work
    /// the corner out by hand to place a stand in GIS.
    pub fn coordinates_md(&self) -> String {
        let g = &self.geo;
        let (w, h) = self.extent_m;
        let (cols, rows, cell) = self.cells;
        let crs = match g.epsg {
            Some(c) => format!("EPSG:{c}"),
            None => "no coordinate reference system (a local grid: map coordinates are the local metres)".to_string(),
        };
        let (x0, y0) = if g.degrees { (format!("{:.7}", g.x0), format!("{:.7}", g.y0)) } else { (format!("{:.2}", g.x0), format!("{:.2}", g.y0)) };
        let mut md = format!(
            "The site is {w:.0} m × {h:.0} m ({cols} × {rows} cells of {cell} m), in {crs}. Every local coordinate \
             (the inventories' `x_m`, `y_m`; `--area`, `--camera` and the scenario's points) is metres east and \
             north of the site's south-west corner, at map x {x0}, y {y0}"
        );
        if g.degrees {
            md.push_str(&format!(": longitude = {x0} + x_m · {:.9}, latitude = {y0} + y_m · {:.9} (degrees per metre at the site's centre).", g.per_m.0, g.per_m.1));
        } else {
            md.push_str(&format!(": map x = {x0} + x_m, map y = {y0} + y_m."));
        }
        md.push_str(" The inventories' geometry, the GeoPackage and the map GeoTIFFs are in map coordinates already.\n");
        md
    }

    /// The summary's two Markdown tables: figures and times, species shares of basal area
    /// and stems (largest first), as printed by `sylva run` and written into `summary.md`.
    pub fn tables(&self) -> (String, String) {
        let s = &self.sim;
        let last = s.rows.last();
        let mut table = String::new();
        let _ = writeln!(table, "| quantity | value |\n|---|---|");
        let _ = writeln!(table, "| year | {} |", s.year);
        // the tree list holds every individual tree; natural regeneration enters it at 4 m, its
        // saplings below are cohorts counted apart (a trial read "all sizes" as including them)
        let _ = writeln!(table, "| trees alive (the tree list: planted and seeded trees, recruits ≥ 4 m) | {} |", s.trees_alive);
        if let Some(r) = last {
            let _ = writeln!(table, "| stems ≥ 1.3 m per ha (tree list) | {:.0} |", r.stems_ha);
            let _ = writeln!(table, "| saplings below 4 m per ha (regeneration cohorts) | {:.0} |", r.regeneration_ha);
            let _ = writeln!(table, "| basal area (m²/ha) | {:.1} |", r.basal_area_m2_ha);
            let _ = writeln!(table, "| top height H100 (m) | {:.1} |", r.top_height_m);
            let _ = writeln!(table, "| quadratic mean DBH (cm) | {:.1} |", r.qmd_cm);
        }
        let _ = writeln!(table, "| time: living conditions (s) | {:.1} |", self.site_s);
        let _ = writeln!(table, "| time: simulation (s) | {:.1} |", self.sim_s);
        let _ = writeln!(table, "| time: pictures (s) | {:.1} |", self.pictures_s);
        let _ = writeln!(table, "| time: total (s) | {:.1} |", self.total_s);
        if self.resumed {
            let _ = writeln!(table, "| pictures finished by a second `sylva run` (the simulation not run again) | yes |");
        }
        let mut shares = String::from("| species | share of basal area | share of stems |\n|---|---|---|\n");
        if let Some(r) = last {
            let mut order: Vec<usize> = (0..s.pool.len()).collect();
            order.sort_by(|&i, &j| r.share_ba[j].total_cmp(&r.share_ba[i]).then(i.cmp(&j)));
            for i in order {
                let _ = writeln!(shares, "| {} | {:.1} % | {:.1} % |", s.pool_names.get(i).unwrap_or(&s.pool[i]), 100.0 * r.share_ba[i], 100.0 * r.share_stems[i]);
            }
        }
        (table, shares)
    }
}

/// The whole of `sylva run`: derives the living conditions of `sc`'s terrain and writes their
/// maps, simulates the forest with species from `lib` ([`simulate`]: stand table, inventories
/// with a GeoPackage for the last year, species and basal-area maps, checkpoints), then, with
/// `opts.render`, stills from an oblique and a top-down camera at [`STILL_YEARS`] (and the last
/// snapshot), a close view into the last year's forest with its near field adapted, a
/// timelapse of every snapshot, `summary.md` and `timings.csv` (each phase's wall and CPU
/// seconds). [`OUTPUTS`] lists the files. Reports every step to `sink`. A run stopped by
/// `opts.stop` returns after the simulation with [`Simulated::stopped`] set (no pictures, no
/// `summary.md`); stopped during the pictures, it returns [`JobError::Stopped`] between two
/// pictures (those written are whole).
///
/// Finishing a stopped run's pictures (trial 46 D10): from the end of the simulation until the
/// last picture the run directory holds the pictures' key frames ([`keyframes::LINKED_FILE`])
/// and their state ([`PICTURES_STATE_FILE`]: scenario, species, picture options, the key
/// frames' index, the stumps). When `sylva run` finds them and they match `sc`, `lib` and
/// `opts`, with the final year's checkpoint, it does not simulate: it reads the checkpoint
/// (stand table, the close-up's trees), reports [`Event::Resuming`] and draws only the
/// pictures not on disk (film frames written before are read back). Otherwise it runs afresh.
///
/// Errors: [`Error::Format`] when `opts.out` is a file; I/O errors naming the file; reading the
/// terrain (under "[terrain] of FILE (scenario NAME)"); the simulation's (under "simulating NAME");
/// [`JobError::Render`] when no adapter is found (under "setting up the renderer").
pub fn main_job(sc: &Scenario, lib: &SpeciesLibrary, opts: &MainJobOptions, sink: &mut Sink) -> Result<MainJobSummary> {
    let t0 = Instant::now();
    let out = opts.out.clone();
    check_out(&out)?;
    sink(&Event::Begin { name: &sc.name, years: sc.years, seed: sc.seed, out: &out });
    if opts.render {
        if let Some(state) = PicturesState::matching(&out, sc, lib, opts) {
            return finish_pictures(sc, lib, opts, state, sink, t0);
        }
    }
    let mut timings = Vec::new();

    // 1. Living conditions. The scenario is checked against the site before any folder is
    // made, so a refused one leaves none behind.
    let t_site = Instant::now();
    let clock = Clock::start();
    let site = context(sc.site().map_err(JobError::from), || format!("[terrain] of {}", sc.context()))?;
    let site = context(World::check(site, lib, sc).map_err(JobError::from), || format!("simulating {}", sc.name))?;
    std::fs::create_dir_all(&out).map_err(|e| Error::io(&out, e))?;
    // an earlier run's pictures and summary go before this run writes its own, and so does
    // the state of an earlier run's unfinished pictures
    clear_main_job_outputs(&out)?;
    remove_pictures_state(&out)?;
    let maps = super::maps::write_site_maps(&site, &out.join("maps").join("conditions"))?;
    let site_s = t_site.elapsed().as_secs_f64();
    clock.push(&mut timings, "conditions (living conditions and their maps)");
    sink(&Event::Conditions { width: site.width(), height: site.height(), extent_m: site.extent_m(), maps: &maps, seconds: site_s });

    // the adapter is looked for before the simulation: without one the run says so now,
    // writes everything that needs no rendering and then fails
    let no_adapter = if opts.render { crate::render::headless::probe_adapter().err() } else { None };
    if let Some(e) = &no_adapter {
        sink(&Event::NoAdapter { message: e.to_string() });
    }
    let render = opts.render && no_adapter.is_none();
    if !render {
        // a run without pictures into an earlier run's folder: that run's pictures would stand
        // beside this run's data as if they were its own (found by a trial), so they go
        remove_earlier_pictures(&out)?;
    }

    // 2. Simulation. The pictures' key frames come from the in-memory world at each snapshot
    // (summer instances of the visible trees), not from the inventory files.
    let t_sim = Instant::now();
    let clock = Clock::start();
    // the key frames wait on disk, not in memory (about 1.2 GB for the default run's 31
    // snapshots; issue 34), in a file kept until the pictures are drawn (trial 46 D10)
    let mut keys = if render { Some(KeyFrames::linked(&out)?) } else { None };
    let mut keys_err: Option<Error> = None;
    // the living trees of the last kept snapshot, for the adapted close-up
    let mut last = LastTrees::default();
    // the trees management removed, from every snapshot (a year that removed trees is one),
    // for the stumps of the stills
    let mut stumps: Vec<scene::Stump> = Vec::new();
    let mut key_time = (0.0, 0.0);
    let mut keep = |y: u32, w: &World| {
        if let Some(k) = keys.as_mut() {
            let clock = Clock::start();
            stumps.extend(scene::stumps_from_world(w));
            let plants = scene::plants_from_world(w);
            let inst = scene::instances_with_saplings(&plants, &scene::saplings_from_world(w), lib, &site, Season::Summer);
            if let Err(e) = k.push(y, &inst) {
                keys_err.get_or_insert(e);
            }
            drop(inst);
            last = LastTrees::of(w, &plants);
            clock.add_to(&mut key_time);
        }
    };
    // the GeoPackage (≈ 115 bytes per tree, ≈ 120 MB at the end of the default run) only for
    // the final year; the Parquet (or CSV) inventory at every inventory snapshot (`inventory_every`)
    let so = SimulateOptions { out: out.clone(), resume: false, gpkg_years: Some(vec![sc.years]), stop: opts.stop.clone(), inventory: opts.inventory };
    let sim = simulate(sc, site.clone(), lib, so, Stepping::One, Some(&mut keep), sink)?;
    if let Some(e) = keys_err {
        return context(Err(e.into()), || "keeping the key frames of the pictures".into());
    }
    let sim_s = t_sim.elapsed().as_secs_f64();
    clock.push(&mut timings, "simulation (all of it, as the rows below split it)");
    let outputs_s = sim.phase_seconds.iter().find(|p| p.0 == "outputs").map_or(0.0, |p| p.1);
    timings.push(PhaseTime { phase: "simulation: of which outputs (inventories, maps, stand table, checkpoints; wall only)".into(), wall_s: outputs_s, cpu_s: f64::NAN });
    timings.push(PhaseTime { phase: "simulation: of which the pictures' key frames".into(), wall_s: key_time.0, cpu_s: key_time.1 });
    let geo = crate::output::georef::PointGeoRef::of_site(&site);
    let cells = (site.width(), site.height(), site.cell_x_m);
    let mut summary = MainJobSummary { sim, scenario: sc.clone(), maps, stills: Vec::new(), film: None, site_s, sim_s, pictures_s: 0.0, total_s: 0.0, timings, resumed: false, geo, extent_m: site.extent_m(), cells };
    if summary.sim.stopped {
        // the key frames of a stopped simulation go (`sylva run` starts it over)
        drop(keys);
        summary.total_s = t0.elapsed().as_secs_f64();
        return Ok(summary);
    }

    // 3 + 4. Pictures.
    let t_pic = Instant::now();
    if let Some(mut keys) = keys {
        // from here a stopped or killed run's pictures can be finished without simulating
        let state = PicturesState::of(sc, lib, opts, &keys, &stumps, &summary)?;
        state.write(&out)?;
        keys.keep();
        let (stills, film) = pictures_of(sc, site, lib, keys, last, &stumps, opts, false, &mut summary.timings, sink)?;
        summary.stills = stills;
        summary.film = Some(film);
    }
    seal(&out, &mut summary, t_pic, t0)?;
    match no_adapter {
        Some(e) => context(Err(JobError::from(e)), || "the pictures of the run (the maps, tables and inventories are written; `--no-pictures` skips the pictures on purpose)".into()),
        None => Ok(summary),
    }
}

/// The second half of [`main_job`] for a run directory whose simulation is complete and whose
/// pictures are not (`state`, matched to the run's scenario, species and options): reads the
/// final checkpoint, reports [`Event::Resuming`], draws the missing pictures, writes
/// `summary.md` and `timings.csv` and removes the pictures' state.
fn finish_pictures(sc: &Scenario, lib: &SpeciesLibrary, opts: &MainJobOptions, state: PicturesState, sink: &mut Sink, t0: Instant) -> Result<MainJobSummary> {
    let out = opts.out.clone();
    let mut timings = state.timings.clone();
    let clock = Clock::start();
    let site = context(sc.site().map_err(JobError::from), || format!("[terrain] of {}", sc.context()))?;
    let site = context(World::check(site, lib, sc).map_err(JobError::from), || format!("simulating {}", sc.name))?;
    // the final world from its checkpoint: the stand table and the close-up's trees, as the
    // simulation left them (the checkpoint refuses a world of other species, seed or site)
    let ck = out.join(super::checkpoint::FILE);
    let mut w = context(World::new(site.clone(), lib, sc).map_err(JobError::from), || format!("finishing the pictures of {}", out.display()))?;
    let mut rows = context(super::checkpoint::load(&ck, &mut w), || format!("finishing the pictures of {}", out.display()))?;
    if w.stand.year != state.year {
        return Err(Error::format(&ck, format!("year {}; expected {}, the year the pictures' state {} was written at (run `sylva run` into an empty folder)", w.stand.year, state.year, PICTURES_STATE_FILE)).into());
    }
    if rows.first().is_some_and(|r| r.year == 0) {
        rows.remove(0);
    }
    let last = LastTrees::of(&w, &scene::plants_from_world(&w));
    let pool = w.site.pool.iter().map(|&s| w.site.lib.species[s as usize].id.clone()).collect();
    let pool_names = w.site.pool.iter().map(|&s| w.site.lib.species[s as usize].identity.common_name.clone()).collect();
    drop(w);
    clock.push(&mut timings, "finishing the pictures: the final checkpoint read (no simulation)");
    let stills_drawn = std::fs::read_dir(out.join("stills")).map_or(0, |d| d.filter_map(|e| e.ok()).filter(|e| is_output(&format!("stills/{}", e.file_name().to_string_lossy()))).count());
    let frames_drawn = std::fs::read_dir(out.join("frames")).map_or(0, |d| d.filter_map(|e| e.ok()).filter(|e| is_output(&format!("frames/{}", e.file_name().to_string_lossy()))).count());
    sink(&Event::Resuming { year: state.year, stills_drawn, frames_drawn });
    let keys = KeyFrames::reopen(&out, state.keyframes.clone())?;
    let sim = Simulated { name: sc.name.clone(), year: state.year, trees_alive: state.trees_alive, pool, pool_names, rows, stopped: false, seconds: state.sim_s, phase_seconds: Vec::new(), out: out.clone() };
    let geo = crate::output::georef::PointGeoRef::of_site(&site);
    let cells = (site.width(), site.height(), site.cell_x_m);
    let mut summary = MainJobSummary { sim, scenario: sc.clone(), maps: state.maps.clone(), stills: Vec::new(), film: None, site_s: state.site_s, sim_s: state.sim_s, pictures_s: 0.0, total_s: 0.0, timings, resumed: true, geo, extent_m: site.extent_m(), cells };
    let t_pic = Instant::now();
    let (stills, film) = pictures_of(sc, site, lib, keys, last, &state.stumps, opts, true, &mut summary.timings, sink)?;
    summary.stills = stills;
    summary.film = Some(film);
    seal(&out, &mut summary, t_pic, t0)?;
    Ok(summary)
}

/// The end of a run's pictures (a whole run's or a finished one's): the pictures' and the
/// run's wall seconds into `summary`, then `summary.md` and `timings.csv` written and the
/// pictures' state removed (the run is complete).
fn seal(out: &Path, summary: &mut MainJobSummary, t_pic: Instant, t0: Instant) -> Result<()> {
    summary.pictures_s = t_pic.elapsed().as_secs_f64();
    summary.total_s = t0.elapsed().as_secs_f64();
    write_summary_md(out, summary)?;
    write_timings_csv(out, &summary.timings)?;
    remove_pictures_state(out)
}

/// The main job's pictures: stills at the still years (with the stumps of `stumps` cut in the
/// 20 years up to each), the close-up of the last one, the timelapse of the key frames `keys`
/// (year, summer instances; each with the stumps of its 20 years), in `opts.out`. With
/// `finish` (an earlier, stopped run's pictures: [`Event::Resuming`]) the stills already on
/// disk are kept and not drawn again, and the film's frames on disk are read back. Adds each
/// kind of picture's wall and CPU seconds to `timings`.
#[allow(clippy::too_many_arguments)]
fn pictures_of(sc: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, mut keys: KeyFrames, last: LastTrees, stumps: &[scene::Stump], opts: &MainJobOptions, finish: bool, timings: &mut Vec<PhaseTime>, sink: &mut Sink) -> Result<(Vec<Still>, Film)> {
    let out = &opts.out;
    let (w, h) = opts.size;
    let clock = Clock::start();
    // the stills, the close-up and the film each on a stage of its own: a stage's renderer keeps
    // what its pictures grew (render targets, buffers, the software rasteriser's arenas), and
    // these added up at the close-up and the film (issue 34: 2.05 GiB peak before)
    let new_stage = || context(Stage::for_scenario(sc, site.clone(), lib.clone()), || "setting up the renderer (install mesa-vulkan-drivers for the CPU adapter)".into());
    let mut stage = new_stage()?;
    // the stills from afar draw instanced prototypes; the close-up adapts its near field
    let adapt = stage.set_adapt(None);
    let key_years = keys.years();
    let years = still_years(sc, &key_years);
    let skipped = skipped_still_years(sc, &key_years);
    if !skipped.is_empty() {
        tracing::warn!("no stills of year(s) {skipped:?}: not snapshot years of this run (snapshot_every = {}); name the years in the scenario's `still_years` to draw them", sc.snapshot_every);
    }
    sink(&Event::Stills { count: years.len() * 2, adapter: &stage.renderer.adapter_description() });
    let stills_dir = out.join("stills");
    std::fs::create_dir_all(&stills_dir).map_err(|e| Error::io(&stills_dir, e))?;
    if !finish {
        remove_old_stills(&stills_dir)?;
    }
    clock.push(timings, "pictures: setting up the renderer (stage, prototypes)");
    // Ctrl-C during the pictures: stop between pictures (each written whole)
    let stopped = || opts.stop.as_ref().is_some_and(|s| s.load(std::sync::atomic::Ordering::SeqCst));
    let stop_here = || Err(JobError::Stopped(out.clone()));
    let mut stills = Vec::new();
    let mut view_times = [(0.0, 0.0); 2];
    for &y in &years {
        if stopped() {
            return stop_here();
        }
        stage.set_stumps(stumps, y);
        for (v, (preset, name)) in [(CameraPreset::Oblique, "oblique"), (CameraPreset::Map, "topdown")].into_iter().enumerate() {
            let path = stills_dir.join(format!("year_{y:04}_{name}.png"));
            if !(finish && path.is_file()) {
                let clock = Clock::start();
                let cam = stage.camera_sized(preset, w, h);
                let mut img = stage.render_instances(keys.get_year(y)?, Season::Summer, &cam, w, h)?;
                // a north arrow on the oblique (the top-down still is north up)
                if preset != CameraPreset::Map {
                    crate::render::overlay::stamp_north_arrow(&mut img, &cam);
                }
                crate::output::pictures::write_png(&path, &img)?;
                clock.add_to(&mut view_times[v]);
            }
            stills.push(Still { year: y, view: name.to_string(), path });
            sink(&Event::Still);
        }
    }
    for (v, name) in ["stills from afar: oblique", "stills from afar: top-down"].into_iter().enumerate() {
        timings.push(PhaseTime { phase: name.into(), wall_s: view_times[v].0, cpu_s: view_times[v].1 });
    }
    if stopped() {
        return stop_here();
    }
    // A close view into the final forest, where the species' architectures show.
    if let Some(&y) = years.last() {
        let path = stills_dir.join(format!("year_{y:04}_closeup.png"));
        if !(finish && path.is_file()) {
            let clock = Clock::start();
            sink(&Event::CloseUpBegin { year: y });
            let cam = closeup_camera(&site);
            drop(stage);
            stage = new_stage()?;
            stage.set_stumps(stumps, y);
            stage.set_adapt(adapt);
            let mut img = stage.render_plants(&last.plants(), Season::Summer, &cam, w, h)?;
            crate::render::overlay::stamp_north_arrow(&mut img, &cam);
            stage.set_adapt(None);
            sink(&Event::CloseUp(&stage.last_adapt));
            crate::output::pictures::write_png(&path, &img)?;
            clock.push(timings, "close-up (its near field adapted at full detail)");
            timings.push(PhaseTime { phase: "close-up: of which adapting the near field (wall only)".into(), wall_s: stage.last_adapt.adapt_s, cpu_s: f64::NAN });
        }
        stills.push(Still { year: y, view: "closeup".to_string(), path });
    }
    // the close-up's trees and open-grown skeletons are not needed by the film (issue 34)
    drop(last);
    sink(&Event::StillsDone);
    if stopped() {
        return stop_here();
    }
    sink(&Event::Timelapse);
    drop(stage);
    let mut stage = new_stage()?;
    let topts = TimelapseOptions { width: opts.timelapse_size.0, height: opts.timelapse_size.1, fps: opts.fps, frames_between: opts.frames_between, camera: None, season: Season::Summer };
    let gif = out.join("timelapse.gif");
    // each key frame with the stumps of its 20 years (fading in and out between key frames)
    let key = &mut |st: &pictures::Stage, k: usize| -> Result<Vec<crate::render::scene::TreeInstance>> {
        if stopped() {
            return Err(JobError::Stopped(out.clone()));
        }
        let mut inst = keys.get(k)?;
        inst.extend(st.stump_instances_of(stumps, key_years[k]));
        Ok(inst)
    };
    let mut film_times = pictures::FilmTimes::default();
    let (frames, mp4) = pictures::timelapse_timed(&mut stage, &key_years, key, &out.join("frames"), &gif, &topts, finish, &mut film_times, &mut |done, total| sink(&Event::Frame { done, total }))?;
    timings.push(PhaseTime { phase: format!("timelapse: frames ({} drawn, {} read back)", frames - film_times.reused, film_times.reused), wall_s: film_times.frames.0, cpu_s: film_times.frames.1 });
    timings.push(PhaseTime { phase: "timelapse: encoding (GIF; MP4 by ffmpeg, its CPU not counted)".into(), wall_s: film_times.encoding.0, cpu_s: film_times.encoding.1 });
    sink(&Event::TimelapseDone);
    Ok((stills, Film { gif, frames, mp4 }))
}

/// Writes `timings.csv` into `out` atomically: `phase,wall_s,cpu_s` per [`PhaseTime`] (CPU
/// empty where not measured), then `total` (the sum of the rows that are not "of which" parts).
///
/// Errors: I/O errors naming the file.
fn write_timings_csv(out: &Path, timings: &[PhaseTime]) -> Result<()> {
    let mut csv = String::from("phase,wall_s,cpu_s\n");
    let num = |v: f64| if v.is_finite() { format!("{v:.2}") } else { String::new() };
    for t in timings {
        let _ = writeln!(csv, "\"{}\",{},{}", t.phase.replace('"', "'"), num(t.wall_s), num(t.cpu_s));
    }
    let whole = timings.iter().filter(|t| !t.phase.contains("of which"));
    let (w, c) = whole.fold((0.0, 0.0), |a, t| (a.0 + t.wall_s, a.1 + if t.cpu_s.is_finite() { t.cpu_s } else { 0.0 }));
    let _ = writeln!(csv, "total,{},{}", num(w), num(c));
    crate::output::write_atomic(&out.join("timings.csv"), csv.as_bytes())?;
    Ok(())
}

/// Name of the pictures' state in a run directory while `sylva run` draws its pictures
/// ([`main_job`]; removed when the last picture is written).
pub const PICTURES_STATE_FILE: &str = ".sylva_pictures.json";

/// Version of [`PICTURES_STATE_FILE`]'s layout.
const PICTURES_STATE_FORMAT: u32 = 1;

/// What [`main_job`] needs to finish a stopped run's pictures without simulating: the run as
/// asked for (to match a later `sylva run` against), the key frames' index, the stumps, and
/// the simulation's figures that the checkpoint does not hold.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct PicturesState {
    format: u32,
    /// The scenario as TOML ([`Scenario::to_toml_string`]).
    scenario: String,
    /// The pool's species files (id, TOML).
    species: Vec<(String, String)>,
    size: (u32, u32),
    timelapse_size: (u32, u32),
    frames_between: u32,
    fps: f32,
    /// The last year simulated.
    year: u32,
    trees_alive: usize,
    keyframes: Vec<keyframes::Entry>,
    stumps: Vec<scene::Stump>,
    maps: Vec<String>,
    site_s: f64,
    sim_s: f64,
    timings: Vec<PhaseTime>,
}

impl PicturesState {
    /// The state of a run whose simulation `s` just ended.
    fn of(sc: &Scenario, lib: &SpeciesLibrary, opts: &MainJobOptions, keys: &KeyFrames, stumps: &[scene::Stump], s: &MainJobSummary) -> Result<Self> {
        Ok(PicturesState {
            format: PICTURES_STATE_FORMAT,
            scenario: sc.to_toml_string()?,
            species: pool_species(sc, lib)?,
            size: opts.size,
            timelapse_size: opts.timelapse_size,
            frames_between: opts.frames_between,
            fps: opts.fps,
            year: s.sim.year,
            trees_alive: s.sim.trees_alive,
            keyframes: keys.index().to_vec(),
            stumps: stumps.to_vec(),
            maps: s.maps.clone(),
            site_s: s.site_s,
            sim_s: s.sim_s,
            timings: s.timings.clone(),
        })
    }

    /// Writes the state to `out/`[`PICTURES_STATE_FILE`] atomically.
    fn write(&self, out: &Path) -> Result<()> {
        let p = out.join(PICTURES_STATE_FILE);
        let json = serde_json::to_vec(self).map_err(|e| Error::format(&p, e.to_string()))?;
        crate::output::write_atomic(&p, &json)?;
        Ok(())
    }

    /// The state in `out` when it is there, readable, of this layout, and of the same scenario,
    /// species and picture options, with the key frames and a checkpoint beside it; `None`
    /// otherwise (the run then starts afresh).
    fn matching(out: &Path, sc: &Scenario, lib: &SpeciesLibrary, opts: &MainJobOptions) -> Option<Self> {
        let bytes = std::fs::read(out.join(PICTURES_STATE_FILE)).ok()?;
        let st: PicturesState = serde_json::from_slice(&bytes).ok()?;
        let same = st.format == PICTURES_STATE_FORMAT
            && st.scenario == sc.to_toml_string().ok()?
            && st.species == pool_species(sc, lib).ok()?
            && (st.size, st.timelapse_size, st.frames_between) == (opts.size, opts.timelapse_size, opts.frames_between)
            && st.fps.to_bits() == opts.fps.to_bits()
            && out.join(keyframes::LINKED_FILE).is_file()
            && out.join(super::checkpoint::FILE).is_file();
        same.then_some(st)
    }
}

/// The pool's species files as [`save_run_species`] writes them: (id, TOML), in pool order.
fn pool_species(sc: &Scenario, lib: &SpeciesLibrary) -> Result<Vec<(String, String)>> {
    let pool: Vec<&crate::species::Species> = if sc.species.is_empty() { lib.species.iter().collect() } else { sc.species.iter().filter_map(|name| lib.get(name)).collect() };
    pool.iter().map(|sp| Ok((sp.id.clone(), sp.to_toml_string()?))).collect()
}

/// Removes the pictures' state ([`PICTURES_STATE_FILE`], then the key frames
/// [`keyframes::LINKED_FILE`]) from `out`, where there.
///
/// Errors: [`Error::Io`] naming the file that cannot be removed.
fn remove_pictures_state(out: &Path) -> Result<()> {
    for f in [PICTURES_STATE_FILE, keyframes::LINKED_FILE] {
        let p = out.join(f);
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

/// The camera of the close-up still (`stills/year_NNNN_closeup.png`; `sylva render --camera
/// closeup`): from 45 m above the ground at 30 % of the site's width and height towards 5 m
/// above the ground at 45 %, a 50° field of view.
pub fn closeup_camera(site: &SiteConditions) -> Camera {
    let (ex, ey) = site.extent_m();
    let (x0, y0) = (0.3 * ex, 0.3 * ey);
    let (x1, y1) = (0.45 * ex, 0.45 * ey);
    let z0 = site.elevation_at(x0, y0) + 45.0;
    let z1 = site.elevation_at(x1, y1) + 5.0;
    Camera::look_at([x0 as f32, y0 as f32, z0], [x1 as f32, y1 as f32, z1], 50.0)
}

/// The living trees of the last snapshot, for the adapted close-up: what [`scene::Plant`]
/// holds, with the species as an index into the world's species names (about 40 bytes a tree
/// instead of an inventory row's 170).
#[derive(Default)]
struct LastTrees {
    /// Species ids of the world's library.
    names: Vec<String>,
    /// id, species index, x and y (m), height, crown radius (m), age (years), crown base (m).
    trees: Vec<(u64, u16, [f32; 6])>,
}

impl LastTrees {
    /// The trees of `plants` ([`scene::plants_from_world`] of `w`).
    fn of(w: &World, plants: &[scene::Plant]) -> Self {
        let names: Vec<String> = w.site.lib.species.iter().map(|s| s.id.clone()).collect();
        let t = &w.stand.trees;
        let trees = plants.iter().enumerate().map(|(i, p)| (p.id, t.species[i], [t.x[i], t.y[i], p.height_m, p.crown_radius_m, p.age_yr, p.crown_base_m])).collect();
        LastTrees { names, trees }
    }

    /// The trees as [`scene::Plant`]s, equal to those [`LastTrees::of`] was given.
    fn plants(&self) -> Vec<scene::Plant<'_>> {
        self.trees.iter().map(|&(id, s, [x, y, h, r, a, cb])| scene::Plant { id, species: self.names[s as usize].as_str(), x_m: x as f64, y_m: y as f64, height_m: h, crown_radius_m: r, age_yr: a, crown_base_m: cb, alive: true }).collect()
    }
}

fn rel(out: &Path, p: &Path) -> String {
    p.strip_prefix(out).unwrap_or(p).display().to_string()
}

/// Writes `summary.md` of the main job into `out`.
///
/// Errors: I/O errors naming the file.
fn write_summary_md(out: &Path, s: &MainJobSummary) -> Result<()> {
    let sc = &s.scenario;
    let (table, shares) = s.tables();
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", sc.name);
    let _ = writeln!(md, "{} years, seed {}, {} species in the pool. Scenario as run: `scenario.toml`.\n", sc.years, sc.seed, if sc.species.is_empty() { "all".to_string() } else { sc.species.len().to_string() });
    // entries a run shortened with `--years` never reaches (the command line says so too;
    // trial 40: a log line was easy to miss)
    let never = sc.never_acting_warnings();
    if !never.is_empty() {
        let _ = writeln!(md, "## Warnings\n");
        for w in &never {
            let _ = writeln!(md, "- {w}");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Result\n\n{table}\n{shares}");
    if !s.timings.is_empty() {
        let _ = writeln!(md, "## Where the time went\n\nWall and CPU seconds (user + system, all threads) of each phase; a loaded machine stretches the wall time far more than the CPU time. Also in `timings.csv`.\n\n| phase | wall (s) | CPU (s) |\n|---|---|---|");
        let num = |v: f64| if v.is_finite() { format!("{v:.1}") } else { "–".to_string() };
        for t in &s.timings {
            let _ = writeln!(md, "| {} | {} | {} |", t.phase, num(t.wall_s), num(t.cpu_s));
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Site and coordinates\n\n{}", s.coordinates_md());
    let _ = writeln!(md, "## Stand development\n\n![stand table](stand_table.png)\n\nData: `stand_table.csv`; inventories: `inventory/`.\n");
    if let Some(f) = &s.film {
        let _ = writeln!(md, "## Timelapse\n\n![timelapse]({})\n\n{} frames{}.\n", rel(out, &f.gif), f.frames, if f.mp4 { ", also as `timelapse.mp4`" } else { "; no MP4 (ffmpeg was not on PATH)" });
    }
    // the final year's species and basal-area maps (a trial missed them in the page that
    // claims every picture)
    let label = format!("year_{:04}", s.sim.year);
    let maps: Vec<String> = ["species", "basal_area"].iter().map(|m| format!("maps/{m}_{label}.png")).filter(|p| out.join(p).is_file()).collect();
    if !maps.is_empty() {
        let _ = writeln!(md, "## Species and basal area, year {}\n", s.sim.year);
        for m in &maps {
            let _ = writeln!(md, "![{m}]({m})");
        }
        let _ = writeln!(md, "\nEvery {} years: `maps/species_year_NNNN.png`, `maps/basal_area_year_NNNN.png` (GeoTIFF twins `.tif`, codes in `maps/species_codes.csv`).\n", sc.snapshot_every);
    }
    let stills = &s.stills;
    if !stills.is_empty() {
        if let Some(c) = stills.iter().find(|s| s.view == "closeup") {
            let _ = writeln!(md, "## Year {} from within the forest\n\n![close view]({})\n", c.year, rel(out, &c.path));
        }
        let _ = writeln!(md, "## Stills\n\n| year | oblique | top-down |\n|---|---|---|");
        let mut years: Vec<u32> = stills.iter().map(|s| s.year).collect();
        years.dedup();
        for y in years {
            let get = |n: &str| stills.iter().find(|s| s.year == y && s.view == n).map(|s| format!("![year {y} {n}]({})", rel(out, &s.path))).unwrap_or_default();
            let _ = writeln!(md, "| {y} | {} | {} |", get("oblique"), get("topdown"));
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Living conditions\n");
    for m in &s.maps {
        let _ = writeln!(md, "![{m}](maps/conditions/{m}.png)");
    }
    crate::output::write_atomic(&out.join("summary.md"), md.as_bytes())?;
    Ok(())
}

/// Removes the pictures an earlier run wrote into the run directory `out`: its stills
/// (`stills/year_NNNN_<view>.png`), film frames (`frames/frame_NNNNN.png`) and
/// `timelapse.gif`/`timelapse.mp4`; nothing else (other files in those folders are kept).
///
/// Errors: I/O errors naming the folder or file.
fn remove_earlier_pictures(out: &Path) -> Result<()> {
    let (stills, frames) = (out.join("stills"), out.join("frames"));
    if stills.is_dir() {
        remove_old_stills(&stills)?;
    }
    if frames.is_dir() {
        pictures::remove_frames(&frames)?;
    }
    for f in ["timelapse.gif", "timelapse.mp4"] {
        let p = out.join(f);
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

/// Removes the stills an earlier run wrote (`year_NNNN_<view>.png`, nothing else) so that a new
/// run into the same folder does not leave stills of years it did not reach.
///
/// Errors: I/O errors naming the folder or file.
fn remove_old_stills(dir: &Path) -> Result<()> {
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let p = e.map_err(|e| Error::io(dir, e))?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let ours = name.starts_with("year_") && name.ends_with(".png") && name.len() > 10 && name[5..9].bytes().all(|b| b.is_ascii_digit()) && name.as_bytes()[9] == b'_';
        if ours {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_patterns() {
        for ok in ["scenario.toml", "inventory/year_0030.csv", "inventory/year_0030_regeneration.csv", "inventory/year_0030.parquet", "inventory/year_0030_regeneration.parquet", "inventory/year_0005_spring.gpkg", "maps/basal_area_year_0010.tif", "maps/conditions/L.png", "stills/year_0030_closeup.png", "frames/frame_00012.png", "timelapse.mp4", "checkpoint/rank_0001.bin", "species/beech.toml"] {
            assert!(is_output(ok), "{ok}");
        }
        for bad in ["notes.txt", "inventory/year_30.csv", "maps/conditions/sub/L.png", "stills/year_0030_side.png", "frames/frame_0001.png", "species/beech.txt"] {
            assert!(!is_output(bad), "{bad}");
        }
    }

    /// `species = []` pools the whole library: every species file is written (the run's
    /// `render`, `export` and `--resume` read them back), and a named pool writes only its own.
    #[test]
    fn an_empty_species_list_saves_the_whole_library() {
        let lib = SpeciesLibrary::embedded().unwrap();
        let dir = std::env::temp_dir().join(format!("sylva_run_species_{}", std::process::id()));
        let mut sc = default_scenario().unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        // the second pool is written over the first (a fresh run into an earlier run's folder):
        // the first pool's other files go (trial 36), a file not `.toml` stays
        for (pool, expected) in [(Vec::new(), lib.species.len()), (vec!["beech".to_string(), "silver_birch".to_string()], 2)] {
            sc.species = pool;
            save_run_species(&sc, &lib, &dir).unwrap();
            std::fs::write(run_species_dir(&dir).join("notes.txt"), b"mine").unwrap();
            let mut names: Vec<String> = std::fs::read_dir(run_species_dir(&dir)).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).filter(|n| n.ends_with(".toml")).collect();
            names.sort();
            assert_eq!(names.len(), expected, "{names:?}");
            if expected == 2 {
                assert_eq!(names, ["beech.toml", "silver_birch.toml"]);
            }
            assert!(run_species_dir(&dir).join("notes.txt").is_file());
        }
        assert!(lib.species.len() > 2);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn default_scenario_parses() {
        let sc = default_scenario().unwrap();
        assert!(sc.years > 0 && !sc.name.is_empty());
    }

    /// Round 41 (trial 40, item 5): `still_years` chooses the stills' years; each is a snapshot
    /// year (so it has a key frame); out of the run, unsorted or twice is refused naming the
    /// field; without it the default years and the default run's snapshots are unchanged.
    #[test]
    fn still_years_choose_the_stills_and_are_snapshot_years() {
        let mut sc = default_scenario().unwrap();
        let d: Vec<u32> = (0..=sc.years).filter(|&y| sc.snapshot_year(y)).collect();
        assert_eq!(d, (0..=150).step_by(5).collect::<Vec<u32>>(), "the default run's snapshots");
        assert_eq!(still_years(&sc, &d), vec![0, 10, 25, 50, 100, 150]);
        // trial 40's park: 60 years, snapshots every 10, a thinning snapshot at 55
        sc.years = 60;
        sc.snapshot_every = 10;
        let keys = [0, 10, 20, 30, 40, 50, 55, 60];
        assert_eq!(still_years(&sc, &keys), vec![0, 10, 50, 60]);
        // trial 47 D8: the default year 25 is left out there, and said so (100 and 150 lie
        // beyond the run's 60 years)
        assert_eq!(skipped_still_years(&sc, &keys), vec![25]);
        assert_eq!(skipped_still_years(&default_scenario().unwrap(), &d), Vec::<u32>::new());
        sc.still_years = Some(vec![20, 35, 40]);
        assert!(skipped_still_years(&sc, &keys).is_empty(), "named still years are snapshot years");
        sc.validate("park.toml").unwrap();
        assert!(sc.snapshot_year(35) && !sc.snapshot_year(45));
        assert_eq!(still_years(&sc, &[0, 10, 20, 30, 35, 40, 50, 55, 60]), vec![20, 35, 40, 60]);
        for (ys, field, want) in [(vec![20, 70], "still_years[1]", "0–60"), (vec![40, 20], "still_years[1]", "ascending"), (vec![20, 20], "still_years[1]", "each once")] {
            sc.still_years = Some(ys);
            let e = sc.validate("park.toml").unwrap_err().to_string();
            assert!(e.contains("park.toml") && e.contains(field) && e.contains(want), "{e}");
        }
        // written to and read from the run's scenario.toml
        sc.still_years = Some(vec![20, 40]);
        let back = Scenario::from_toml_str(&sc.to_toml_string().unwrap(), "back").unwrap();
        assert_eq!(back.still_years, Some(vec![20, 40]));
    }
}
