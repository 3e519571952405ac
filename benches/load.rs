//! Load benchmark (issue 16, Build 4): a 10,000 ha run of 100 years through the run driver
//! (`job::run::run_scenario`: stand table and a checkpoint every 10 years on disk, as
//! `sylva simulate` writes them; snapshots off unless `SYLVA_LOAD_SNAPSHOTS=1`, since an
//! inventory of ~10 M trees is ~1 GB per snapshot). Flat uniform site of 50 m cells with seed
//! rain of beech, Norway spruce and silver birch (the ecosystem bench's afforestation, ten times
//! the area), or a generated fractal terrain with `SYLVA_LOAD_TERRAIN=generate`.
//!
//! Prints wall time, time per decade, wall time per phase of the year summed over the years
//! (and of the outputs: stand table, checkpoint), live trees and regeneration cohorts, the checkpoint's
//! size and the peak resident memory (VmHWM of /proc/self/status); the goal is ≤ 4 GiB and
//! ≤ 5 min on 2 cores. Command (BENCHMARKS.md):
//! `cargo bench --bench load` (release), under `/usr/bin/time -v` for the peak RSS as the
//! kernel counts it. Environment: `SYLVA_LOAD_HA` (default 10000), `SYLVA_LOAD_YEARS`
//! (default 100), `SYLVA_LOAD_THREADS` (default 2), `SYLVA_LOAD_OUT` (run directory; default a
//! temporary one, removed at the end).
use std::time::Instant;
mod common;
use sylva::job::run::{run_scenario, Progress, RunOptions};
use sylva::sim::Scenario;
use sylva::species::SpeciesLibrary;

fn vm_hwm_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    s.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()
}

fn env<T: std::str::FromStr>(k: &str, default: T) -> T {
    std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn main() {
    let ha: f64 = env("SYLVA_LOAD_HA", 10_000.0);
    let years: u32 = env("SYLVA_LOAD_YEARS", 100);
    let threads: usize = env("SYLVA_LOAD_THREADS", 2);
    let generate = std::env::var("SYLVA_LOAD_TERRAIN").is_ok_and(|v| v == "generate");
    let snapshots = std::env::var("SYLVA_LOAD_SNAPSHOTS").is_ok_and(|v| v == "1");
    let side = ((ha * 10_000.0).sqrt() / 50.0).round().max(1.0) as usize; // 50 m cells
    let terrain = if generate {
        format!("generate = {{ size = {side}, cell_m = 50.0, relief_m = 300.0, seed = 4 }}")
    } else {
        format!("uniform = {{ width = {side}, height = {side}, cell_m = 50.0, elevation_m = 500.0, indices = [5, 5, 3, 5, 6, 6] }}")
    };
    let toml = common::afforestation_toml("load", years, "snapshot_every = 0\ncheckpoint_every = 10", &terrain);
    let sc = Scenario::from_toml_str(&toml, "load bench").expect("scenario");
    let lib = SpeciesLibrary::embedded().expect("species");
    let tmp;
    let out = match std::env::var("SYLVA_LOAD_OUT") {
        Ok(p) => std::path::PathBuf::from(p),
        Err(_) => {
            tmp = tempfile::tempdir().expect("temporary folder");
            tmp.path().join("run")
        }
    };
    rayon::ThreadPoolBuilder::new().num_threads(threads).build_global().expect("thread pool");
    let t0 = Instant::now();
    let site = sc.site().expect("site");
    let site_s = t0.elapsed().as_secs_f64();
    eprintln!("load bench: {} × {} cells of 50 m ({:.0} ha, {}), {years} years, {threads} threads, snapshots {}", side, side, (side * side) as f64 * 0.25, if generate { "generated terrain" } else { "uniform site" }, if snapshots { "on" } else { "off" });
    let mut last = Instant::now();
    let mut decade = Vec::new();
    let mut phases = [0f64; sylva::sim::step::N_PHASES + 1];
    let mut cb = |p: &Progress| {
        for (k, s) in p.phase_seconds.iter().enumerate() {
            phases[k] += s;
        }
        phases[sylva::sim::step::N_PHASES] += p.output_seconds;
        if p.year % 10 == 0 {
            let s = last.elapsed().as_secs_f64();
            last = Instant::now();
            eprintln!("year {:>3}: {:>10} trees, {:6.1} s this decade, peak RSS {:.0} MiB", p.year, p.trees, s, vm_hwm_kib().unwrap_or(0) as f64 / 1024.0);
            decade.push((p.year, p.trees, s));
        }
    };
    let mut opts = RunOptions::new(&out);
    opts.write_snapshots = snapshots;
    opts.progress = Some(&mut cb);
    let res = run_scenario(&sc, site, &lib, opts).expect("run");
    let names: Vec<&str> = sylva::sim::step::PHASES.iter().map(|p| p.name).chain(["outputs"]).collect();
    eprintln!("wall time per phase, all years (s): {}", names.iter().zip(&phases).map(|(n, s)| format!("{n} {s:.1}")).collect::<Vec<_>>().join(", "));
    let total = t0.elapsed().as_secs_f64();
    let ck = std::fs::metadata(out.join("checkpoint.bin")).map(|m| m.len()).unwrap_or(0);
    let last_row = res.rows.last();
    println!("| area (ha) | years | threads | live trees at end | cohorts at end | conditions (s) | simulation + outputs (s) | total (s) | checkpoint (MB) | peak RSS (MiB) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    println!(
        "| {:.0} | {years} | {threads} | {} | {} | {site_s:.1} | {:.1} | {total:.1} | {:.0} | {:.0} |",
        res.world.site.area_ha,
        res.world.stand.trees.len(),
        res.world.stand.cohorts.len(),
        res.seconds,
        ck as f64 / 1e6,
        vm_hwm_kib().unwrap_or(0) as f64 / 1024.0
    );
    if let Some(r) = last_row {
        println!("basal area {:.1} m²/ha, top height {:.1} m, {:.0} stems/ha", r.basal_area_m2_ha, r.top_height_m, r.stems_ha);
    }
}
