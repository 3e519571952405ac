//! `sylva simulate SCENARIO [--out DIR] [--resume] [--threads N]`: parses the arguments, loads
//! the scenario, site and species, draws progress and handles Ctrl-C around
//! [`sylva::job::main_job::simulate`].

use anyhow::Context;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use sylva::conditions::SiteConditions;
use sylva::job::main_job::{self, Event, Simulated, SimulateOptions, Stepping};
pub use sylva::job::main_job::run_species_dir;
use sylva::sim::Scenario;
use sylva::species::SpeciesLibrary;

/// Arguments of `sylva simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Run directory.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Override the scenario's number of years (1–10,000), e.g. to try a shipped scenario for
    /// a few years; the run directory's `scenario.toml` records the years run.
    // a range of its own, and a negative value read as one (clap's tip for `--years -3` was
    // to pass `-- -3`, which names a scenario; round 30's trial)
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub years: Option<u32>,
    /// Continue an interrupted run from its checkpoint (OUT/checkpoint.bin, or a tiled run's
    /// per-rank OUT/checkpoint/).
    #[arg(long)]
    pub resume: bool,
    /// Worker threads, 1–256 (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Folder of extra or edited species files (e.g. made by `sylva species new`): they are
    /// added to the shipped library, replacing shipped species of the same id.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// Cut the landscape into N tiles stepped by N threads of this process (the exchanges of
    /// an MPI run, in memory); the run directory is the one of a single process. Under
    /// `mpirun -np N` (a build with the `mpi` feature) the ranks are the tiles instead.
    #[arg(long, value_parser = parse_tiles)]
    pub tiles: Option<usize>,
    /// File format of the inventories and regeneration tables: `parquet` (GeoParquet, read by
    /// geopandas, R arrow, DuckDB, QGIS) or `csv`.
    #[arg(long, default_value = "parquet")]
    pub inventory: sylva::output::inventory::InventoryFormat,
    /// Which snapshots also get a GeoPackage inventory (`inventory/year_NNNN.gpkg`): `final`
    /// (the last year only, as `sylva run`) or `every-snapshot` (every snapshot with a tree
    /// inventory, `inventory_every`; uncompressed: 133 MB for the default run's year 150,
    /// ≈ 0.5 GB over its 7 inventory years).
    #[arg(long, value_enum, default_value = "final")]
    pub gpkg: GpkgWhen,
}

/// When `sylva simulate` writes GeoPackage inventories ([`Args::gpkg`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GpkgWhen {
    /// The final year only.
    Final,
    /// Every snapshot with a tree inventory.
    EverySnapshot,
}

/// Most tiles `--tiles` steps in one process. Each tile is a thread holding its own trees plus
/// a halo as wide as the pool's longest seed reach (875 m for birch), so memory grows with the
/// count: `scenarios/parcels.toml` held 9 GB by its year 14 with 256 tiles, and 1,000 tiles
/// were killed for memory on a 24 GiB machine (4,000 overflowed a thread's stack). More ranks
/// than this belong on a cluster (`mpirun`, docs/SCALING.md).
pub const MAX_LOCAL_TILES: usize = 64;

/// Parses `--tiles`: an integer 1–[`MAX_LOCAL_TILES`].
pub fn parse_tiles(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_LOCAL_TILES).contains(&n) => Ok(n),
        Ok(n) if n > MAX_LOCAL_TILES => Err(format!(
            "expected 1 to {MAX_LOCAL_TILES} tiles in one process, got {n}: each tile is a thread holding its trees and a halo as wide as the longest seed reach, so memory grows with the count (256 tiles of scenarios/parcels.toml held 9 GB); run more ranks with mpirun"
        )),
        _ => Err(format!("expected a whole number of tiles from 1 to {MAX_LOCAL_TILES}, got '{s}'")),
    }
}

/// Parses `--threads`: an integer 1–256.
pub fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=256).contains(&n) => Ok(n),
        _ => Err(format!("expected a whole number of worker threads from 1 to 256, got '{s}'")),
    }
}

/// The species library used by simulations: the shipped species, overlaid by the files of each
/// folder in `dirs` that exists or is given explicitly (later folders win; see
/// [`SpeciesLibrary::overlay_dir`]).
pub fn library(dirs: &[&Path]) -> anyhow::Result<SpeciesLibrary> {
    let mut lib = SpeciesLibrary::embedded()?;
    for d in dirs {
        lib.overlay_dir(d).with_context(|| format!("species folder {}", d.display()))?;
    }
    Ok(lib)
}

/// The species of a run directory: the shipped library, overlaid by the run's `species/`
/// folder when it has one, then by `species_dir`.
pub fn run_library(run_dir: &Path, species_dir: Option<&Path>) -> anyhow::Result<SpeciesLibrary> {
    let run_species = run_species_dir(run_dir);
    let mut dirs: Vec<&Path> = Vec::new();
    if run_species.is_dir() {
        dirs.push(&run_species);
    }
    dirs.extend(species_dir);
    library(&dirs)
}

/// Loads the site conditions a scenario names (window applied), after checking that the
/// machine's available memory can hold the site ([`Scenario::check_site_memory`], where
/// `/proc/meminfo` tells it).
pub fn load_site(sc: &Scenario) -> anyhow::Result<SiteConditions> {
    if let Some(avail) = available_memory_bytes() {
        sc.check_site_memory(avail)?;
    }
    Ok(sc.site().with_context(|| format!("[terrain] of {}", sc.context()))?)
}

/// The machine's available memory (bytes): `MemAvailable` of `/proc/meminfo`, or
/// `SYLVA_MEM_AVAILABLE` (bytes) where set (tests); `None` where neither tells.
pub(crate) fn available_memory_bytes() -> Option<u64> {
    if let Some(v) = std::env::var("SYLVA_MEM_AVAILABLE").ok().and_then(|v| v.trim().parse().ok()) {
        return Some(v);
    }
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A stop flag set by Ctrl-C, SIGTERM or SIGHUP: the run stops after the current year with its
/// outputs so far complete.
pub fn stop_on_ctrl_c() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let _ = ctrlc::set_handler(move || {
        s.store(true, Ordering::SeqCst);
    });
    stop
}

/// The message of a run stopped early (exit status 130), ending with `how` to continue it.
pub fn interrupted(s: &Simulated, how: &str) -> super::Interrupted {
    super::Interrupted(format!("stopped (Ctrl-C or SIGTERM) after year {}: outputs so far are complete in {}; {how}", s.year, s.out.display()))
}

/// The simulation's progress on stderr: a bar over the years (where stderr is not a terminal,
/// a line at every tenth of the years instead: [`super::plain_progress`]), then one line with
/// the final year's figures (and the phase times with `SYLVA_PHASE_TIMES=1`).
#[derive(Default)]
pub struct SimBar(Option<indicatif::ProgressBar>, u64, u64);

impl SimBar {
    /// Draws `e` ([`Event::Simulating`], [`Event::Year`], [`Event::Simulated`]; others are
    /// ignored).
    pub fn show(&mut self, e: &Event) {
        match e {
            Event::Simulating { years } => {
                self.0 = Some(super::progress(*years as u64, "simulate"));
                (self.1, self.2) = (*years as u64, 0);
            }
            Event::Year(p) => {
                let msg = format!("year {} · {} trees · {:.0} trees/s", p.year, p.trees, p.trees_per_s);
                super::plain_progress("simulate", p.year as u64, self.1, &mut self.2, &msg);
                if let Some(pb) = &self.0 {
                    pb.set_position(p.year as u64);
                    pb.set_message(msg);
                }
            }
            Event::Simulated(s) => {
                if let Some(pb) = self.0.take() {
                    pb.finish();
                }
                if std::env::var_os("SYLVA_PHASE_TIMES").is_some() {
                    let list: Vec<String> = s.phase_seconds.iter().map(|(n, t)| format!("{n} {t:.1} s")).collect();
                    eprintln!("phase times: {}", list.join(", "));
                }
                let last = s.rows.last();
                eprintln!(
                    "{} year {}: {} trees, basal area {:.1} m²/ha, top height {:.1} m ({:.1} s){} → {}",
                    s.name,
                    s.year,
                    s.trees_alive,
                    last.map_or(0.0, |r| r.basal_area_m2_ha),
                    last.map_or(0.0, |r| r.top_height_m),
                    s.seconds,
                    if s.stopped { ", stopped early" } else { "" },
                    s.out.display()
                );
            }
            _ => {}
        }
    }
}

/// `sylva simulate` into `out` stepped as `stepping` says, with a progress bar and a Ctrl-C
/// handler (stop after the current year: [`super::Interrupted`]).
#[allow(clippy::too_many_arguments)]
fn simulate(sc: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, out: PathBuf, resume: bool, inventory: sylva::output::inventory::InventoryFormat, gpkg: GpkgWhen, stepping: Stepping) -> anyhow::Result<()> {
    // `Some(empty)`: the final year only (the run always writes it); `None`: every snapshot
    let gpkg_years = match gpkg {
        GpkgWhen::Final => Some(Vec::new()),
        GpkgWhen::EverySnapshot => None,
    };
    let opts = SimulateOptions { out: out.clone(), resume, gpkg_years, stop: Some(stop_on_ctrl_c()), inventory };
    let mut bar = SimBar::default();
    let s = main_job::simulate(sc, site, lib, opts, stepping, None, &mut |e| {
        // said once the scenario has been checked (before, a refused scenario was preceded by
        // a note that the folder's earlier run is replaced; round 30's trial)
        if !resume && matches!(e, Event::Simulating { .. }) {
            note_replaced_run(&out);
            // an earlier `sylva run`'s pictures, condition maps and summary would describe
            // another run beside this one's tables (round 32's trial): gone before it writes
            match main_job::clear_main_job_outputs(&out) {
                Ok(r) if !r.is_empty() => eprintln!("note: removed {} file(s) of the earlier run that `sylva simulate` does not write again ({}{})", r.len(), r.iter().take(3).cloned().collect::<Vec<_>>().join(", "), if r.len() > 3 { ", …" } else { "" }),
                Ok(_) => {}
                Err(err) => eprintln!("warning: {err}"),
            }
        }
        bar.show(e)
    })?;
    if s.stopped {
        return Err(interrupted(&s, "continue with the same command and --resume").into());
    }
    Ok(())
}

/// CPU time (s, user + system) of this process so far (getrusage); `None` where unknown.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
fn cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        // SAFETY: getrusage writes into the zeroed struct we own.
        let mut u: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: a valid pointer to a rusage struct.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
            return None;
        }
        let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(s(u.ru_utime) + s(u.ru_stime))
    }
    #[cfg(not(unix))]
    None
}

/// Prints one line per rank of a tiled run to stderr: wall time and the part of it spent in
/// exchanges (passing messages, waiting for the other ranks), CPU time (user + system),
/// peak resident memory
/// (VmHWM of /proc/self/status) and the bytes sent to other ranks (in all and per year of
/// `years`), the figures of docs/SCALING.md.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
fn rank_stats(rank: usize, size: usize, seconds: f64, in_exchanges: f64, sent: u64, years: u32) {
    let hwm = std::fs::read_to_string("/proc/self/status").ok().and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok()));
    let mib = hwm.map_or("?".to_string(), |k| format!("{:.0}", k as f64 / 1024.0));
    // one write of the whole line: stderr is unbuffered, and `eprintln!` writes each piece of
    // its format on its own, so the lines of ranks sharing mpirun's stderr came interleaved
    let line = format!("rank {rank}/{size}: {seconds:.1} s ({in_exchanges:.1} s of it in exchanges), CPU {} s, peak RSS {mib} MiB, sent {sent} bytes ({:.0} per year)\n", cpu_seconds().map_or("?".to_string(), |s| format!("{s:.1}")), sent as f64 / years.max(1) as f64);
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
}

/// Says on stderr that `out` holds an earlier run whose files a new run (not `--resume`)
/// replaces: its scenario's name and file, so that a mistyped `--out` is seen before the old
/// run's inventories, maps and checkpoint are gone (they are replaced file by file as the new
/// run writes them).
pub fn note_replaced_run(out: &Path) {
    // said once: by rank 0 of an `mpirun` (Open MPI and MPICH/PMI name the rank in the
    // environment before MPI starts), not once per rank
    if super::mpi_rank_from_env().is_some_and(|r| r != "0") {
        return;
    }
    let old = out.join("scenario.toml");
    if old.is_file() {
        let name = Scenario::load(&old).map(|s| s.name).unwrap_or_else(|_| "unreadable scenario.toml".into());
        eprintln!("note: {} holds an earlier run ({name}); this run replaces its files (use another --out to keep it, or --resume to continue it)", out.display());
    }
}

/// Applies `--years` (`years`) to `sc` and checks what can never happen in the run: with the
/// scenario's own `years` (or a longer `--years`), a fresh run refuses a `[[management]]` entry
/// whose years all lie after the run's end ([`Scenario::refuse_entries_never_acting`]); a run
/// that `--years` shortened says so on stderr (`warning: …`, again under the run's summary
/// line; `sylva run` also in `summary.md`) and goes on; a resumed one (whose `scenario.toml`
/// records the years run) neither refuses nor warns. Still years
/// beyond a shortened run are dropped with a warning. Returns the warnings printed.
///
/// Errors: the scenario's validation under `--years`; the refusal naming the scenario file,
/// the entry's field, its year and the run's last year.
pub fn apply_years(sc: &mut Scenario, years: Option<u32>, resume: bool) -> anyhow::Result<Vec<String>> {
    let own = sc.years;
    let mut said = Vec::new();
    if let Some(y) = years {
        sc.years = y;
        if let Some(ys) = sc.still_years.as_mut() {
            let beyond: Vec<String> = ys.iter().filter(|&&s| s > y).map(|s| s.to_string()).collect();
            if !beyond.is_empty() {
                ys.retain(|&s| s <= y);
                said.push(format!("still_years {} of {} lie after the run's last year {y} (--years): no stills of them", beyond.join(", "), sc.context()));
            }
        }
        sc.validate("--years")?;
    }
    // (a resumed run said so when it started, and its checkpoint decides what may change)
    if !resume && sc.years >= own {
        sc.refuse_entries_never_acting(&sc.context())?;
    } else if !resume {
        said.extend(sc.never_acting_warnings().into_iter().map(|w| format!("{}: {w}", sc.context())));
    }
    // once, by rank 0 of an `mpirun` (each rank reads the scenario)
    if !super::mpi_rank_from_env().is_some_and(|r| r != "0") {
        for w in &said {
            eprintln!("warning: {w}");
        }
    }
    Ok(said)
}

/// Runs a simulation.
pub fn run(a: Args) -> anyhow::Result<()> {
    super::refuse_mpi_launch("simulate", true)?;
    let mut sc = Scenario::load(&a.scenario)?;
    let warned = apply_years(&mut sc, a.years, a.resume)?;
    super::check_out_dir(&a.out, "--out")?;
    let _lock = super::lock_run_dir(&a.out, "--out")?;
    let run_species = run_species_dir(&a.out);
    let mut dirs: Vec<&Path> = Vec::new();
    // the run's own species files count once it has a checkpoint (a run killed before that
    // starts again from year 0 and writes them anew)
    if a.resume && run_species.is_dir() && sylva::job::checkpoint::exists(&a.out) {
        dirs.push(&run_species);
    }
    dirs.extend(a.species_dir.as_deref());
    let lib = library(&dirs)?;
    #[cfg(feature = "mpi")]
    if let Some(mut t) = sylva::job::mpi_transport::MpiTransport::from_env() {
        use sylva::sim::tiles::Transport;
        if t.size() > 1 {
            let t0 = std::time::Instant::now();
            // issue 37 Build 1: a GeoTIFF site derived by the ranks, each from a window of the DEM
            // a fresh run without management: rank 0 too holds its band only (its run driver
            // builds its tile's world, issue 37 round 33)
            // (with management too since round 36: the ranks resolve its areas from their tiles;
            // a resumed run too since round 37: every rank reads its part of the checkpoint)
            let site = sylva::job::site_ranks::site_by_ranks_banded(&sc, &mut t, false, true).with_context(|| format!("[terrain] of {} (rank {})", sc.context(), t.rank()))?;
            let r = if t.rank() != 0 {
                // a stop (Ctrl-C, SIGTERM from mpirun) is rank 0's to decide; the others follow it
                let _ = ctrlc::set_handler(|| {});
                sylva::job::tiled::work(&sc, site, &lib, &mut t).with_context(|| format!("simulating {} (rank {})", sc.name, t.rank()))
            } else {
                simulate(&sc, site, &lib, a.out.clone(), a.resume, a.inventory, a.gpkg, Stepping::Ranks(&mut t))
            };
            rank_stats(t.rank(), t.size(), t0.elapsed().as_secs_f64(), t.seconds_in_exchanges(), t.bytes_sent(), sc.years);
            return r;
        }
    }
    let site = load_site(&sc)?;
    let stepping = || match a.tiles {
        Some(n) if n > 1 => Stepping::Local(n),
        _ => Stepping::One,
    };
    let go = || simulate(&sc, site, &lib, a.out.clone(), a.resume, a.inventory, a.gpkg, stepping());
    let r = match a.threads {
        Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build().context("thread pool")?.install(go),
        None => go(),
    };
    // said again under the run's summary line, where it is read (trial 40: warnings were
    // easy to miss among the log lines)
    if r.is_ok() {
        for w in &warned {
            eprintln!("warning: {w}");
        }
    }
    r
}
