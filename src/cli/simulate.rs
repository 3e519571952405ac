//! `sylva simulate SCENARIO [--out DIR] [--resume] [--threads N]`.

use anyhow::Context;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use sylva::conditions::SiteConditions;
use sylva::job::run::{run_scenario, Progress, RunOptions};
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
}

/// Parses `--tiles`: an integer 1–4096.
pub fn parse_tiles(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=4096).contains(&n) => Ok(n),
        _ => Err(format!("expected a whole number of tiles from 1 to 4096, got '{s}'")),
    }
}

/// How `sylva simulate` steps the years.
pub enum Mode<'a> {
    /// One process, the whole landscape.
    One,
    /// N tiles, one thread each, in this process (`--tiles N`).
    Local(usize),
    /// Rank 0 of a tiled run over a transport (MPI); the other ranks run
    /// [`sylva::job::tiled::work`].
    #[cfg_attr(not(feature = "mpi"), allow(dead_code))]
    Ranks(&'a mut dyn sylva::sim::tiles::Transport),
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

/// Folder of a run directory that holds the species files the run was simulated with.
pub fn run_species_dir(run_dir: &Path) -> PathBuf {
    run_dir.join("species")
}

/// Writes the pool's species files into `RUN/species/` (so `render`, `timelapse` and a
/// `--resume` find the same species later, also edited or custom ones).
pub fn save_run_species(sc: &Scenario, lib: &SpeciesLibrary, run_dir: &Path) -> anyhow::Result<()> {
    let dir = run_species_dir(run_dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for name in &sc.species {
        if let Some(sp) = lib.get(name) {
            sylva::output::write_atomic(&dir.join(format!("{}.toml", sp.id)), sp.to_toml_string()?.as_bytes())?;
        }
    }
    Ok(())
}

/// Loads the site conditions a scenario names (window applied).
pub fn load_site(sc: &Scenario) -> anyhow::Result<SiteConditions> {
    Ok(sc.site().with_context(|| format!("terrain of scenario {}", sc.name))?)
}

/// What `sylva run` needs from a finished simulation.
pub struct SimOutcome {
    /// Final year.
    pub year: u32,
    /// Live trees at the end (all sizes).
    pub trees_alive: usize,
    /// Species ids of the pool, in stand-table order.
    pub pool: Vec<String>,
    /// Stand table rows.
    pub rows: Vec<sylva::sim::stats::StandRow>,
}

/// Runs `sc` into `out` with a progress bar and a Ctrl-C handler (stop after the current year);
/// returns what the main job reports.
///
/// `geojson_years`: the years whose snapshots also get a GeoJSON inventory (`None`: all).
pub fn simulate(sc: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, out: PathBuf, resume: bool, geojson_years: Option<Vec<u32>>, on_snapshot: Option<&mut dyn FnMut(u32, &sylva::sim::World)>) -> anyhow::Result<SimOutcome> {
    simulate_mode(sc, site, lib, out, resume, geojson_years, on_snapshot, Mode::One)
}

/// [`simulate`] stepped as `mode` says (one process, tiles in threads, rank 0 of MPI ranks).
#[allow(clippy::too_many_arguments)]
pub fn simulate_mode(sc: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, out: PathBuf, resume: bool, geojson_years: Option<Vec<u32>>, on_snapshot: Option<&mut dyn FnMut(u32, &sylva::sim::World)>, mode: Mode) -> anyhow::Result<SimOutcome> {
    if out.exists() && !out.is_dir() {
        anyhow::bail!("--out {}: is a file; expected a folder for the run's outputs", out.display());
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let s = stop.clone();
        let _ = ctrlc::set_handler(move || {
            s.store(true, Ordering::SeqCst);
        });
    }
    let pb = super::progress(sc.years as u64, "simulate");
    // wall time per phase (and of the outputs) summed over the years: printed at the end with
    // SYLVA_PHASE_TIMES=1 (a tiled run: rank 0's tile, its exchanges included)
    let mut phase_sums = [0f64; sylva::sim::step::N_PHASES + 1];
    let mut cb = |p: &Progress| {
        pb.set_position(p.year as u64);
        pb.set_message(format!("year {} · {} trees · {:.0} trees/s", p.year, p.trees, p.trees_per_s));
        for (k, s) in p.phase_seconds.iter().chain([&p.output_seconds]).enumerate() {
            phase_sums[k] += s;
        }
    };
    // a resumed run keeps the species files it was simulated with (a changed species is
    // refused by the checkpoint before anything is written)
    if !(resume && sylva::job::checkpoint::exists(&out)) {
        save_run_species(sc, lib, &out)?;
    }
    let mut opts = RunOptions::new(&out);
    opts.resume = resume;
    opts.geojson_years = geojson_years;
    opts.stop = Some(stop);
    opts.progress = Some(&mut cb);
    let mut on_snapshot = on_snapshot;
    if let Some(f) = on_snapshot.as_mut() {
        opts.on_snapshot = Some(&mut **f);
    }
    let res = match mode {
        Mode::One => run_scenario(sc, site, lib, opts),
        Mode::Local(n) => sylva::job::tiled::run_local_tiles(sc, site, lib, opts, n).map(|r| r.0),
        Mode::Ranks(t) => sylva::job::tiled::run_tiled(sc, site, lib, opts, t).and_then(|r| r.ok_or_else(|| sylva::Error::Exchange { peer: 0, reason: "rank 0 ended without a run summary".into() }.into())),
    }
    .with_context(|| format!("simulating {}", sc.name))?;
    pb.finish();
    if std::env::var_os("SYLVA_PHASE_TIMES").is_some() {
        let names = sylva::sim::step::PHASES.iter().map(|p| p.name).chain(["outputs"]);
        let list: Vec<String> = names.zip(phase_sums).map(|(n, s)| format!("{n} {s:.1} s")).collect();
        eprintln!("phase times: {}", list.join(", "));
    }
    let last = res.rows.last();
    eprintln!(
        "{} year {}: {} trees, basal area {:.1} m²/ha, top height {:.1} m ({:.1} s){} → {}",
        sc.name,
        res.world.stand.year,
        res.trees,
        last.map_or(0.0, |r| r.basal_area_m2_ha),
        last.map_or(0.0, |r| r.top_height_m),
        res.seconds,
        if res.stopped { ", stopped early" } else { "" },
        out.display()
    );
    if res.stopped {
        return Err(super::Interrupted(format!("stopped (Ctrl-C or SIGTERM) after year {}: outputs so far are complete in {}; continue with --resume", res.world.stand.year, out.display())).into());
    }
    let pool = res.world.site.pool.iter().map(|&s| res.world.site.lib.species[s as usize].id.clone()).collect();
    Ok(SimOutcome { year: res.world.stand.year, trees_alive: res.trees, pool, rows: res.rows })
}

/// Prints one line per rank of a tiled run to stderr: wall time, peak resident memory
/// (VmHWM of /proc/self/status) and the bytes sent to other ranks (in all and per year of
/// `years`), the figures of docs/SCALING.md.
#[cfg_attr(not(feature = "mpi"), allow(dead_code))]
fn rank_stats(rank: usize, size: usize, seconds: f64, sent: u64, years: u32) {
    let hwm = std::fs::read_to_string("/proc/self/status").ok().and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok()));
    let mib = hwm.map_or("?".to_string(), |k| format!("{:.0}", k as f64 / 1024.0));
    // one write of the whole line: stderr is unbuffered, and `eprintln!` writes each piece of
    // its format on its own, so the lines of ranks sharing mpirun's stderr came interleaved
    let line = format!("rank {rank}/{size}: {seconds:.1} s, peak RSS {mib} MiB, sent {sent} bytes ({:.0} per year)\n", sent as f64 / years.max(1) as f64);
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
}

/// Runs a simulation.
pub fn run(a: Args) -> anyhow::Result<()> {
    let sc = Scenario::load(&a.scenario)?;
    let run_species = run_species_dir(&a.out);
    let mut dirs: Vec<&Path> = Vec::new();
    // the run's own species files count once it has a checkpoint (a run killed before that
    // starts again from year 0 and writes them anew)
    if a.resume && run_species.is_dir() && sylva::job::checkpoint::exists(&a.out) {
        dirs.push(&run_species);
    }
    dirs.extend(a.species_dir.as_deref());
    let lib = library(&dirs)?;
    let site = load_site(&sc)?;
    #[cfg(feature = "mpi")]
    if let Some(mut t) = sylva::job::mpi_transport::MpiTransport::from_env() {
        use sylva::sim::tiles::Transport;
        if t.size() > 1 {
            let t0 = std::time::Instant::now();
            let r = if t.rank() != 0 {
                // a stop (Ctrl-C, SIGTERM from mpirun) is rank 0's to decide; the others follow it
                let _ = ctrlc::set_handler(|| {});
                sylva::job::tiled::work(&sc, site, &lib, &mut t).with_context(|| format!("simulating {} (rank {})", sc.name, t.rank()))
            } else {
                simulate_mode(&sc, site, &lib, a.out.clone(), a.resume, None, None, Mode::Ranks(&mut t)).map(|_| ())
            };
            rank_stats(t.rank(), t.size(), t0.elapsed().as_secs_f64(), t.bytes_sent(), sc.years);
            return r;
        }
    }
    let mode = || match a.tiles {
        Some(n) if n > 1 => Mode::Local(n),
        _ => Mode::One,
    };
    let go = || simulate_mode(&sc, site, &lib, a.out.clone(), a.resume, None, None, mode()).map(|_| ());
    match a.threads {
        Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build().context("thread pool")?.install(go),
        None => go(),
    }
}
