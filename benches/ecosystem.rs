//! Ecosystem benchmark: afforestation of a flat 10 km² (1,000 ha) site by seed rain of beech,
//! Norway spruce and silver birch for 100 years. Prints time per year and per phase, trees/s,
//! live trees, the regeneration layer (cohorts, stems) and peak memory (VmHWM from
//! /proc/self/status).
//!
//! `cargo bench --bench ecosystem` (release). Environment: `SYLVA_BENCH_HA` (area, default 1000),
//! `SYLVA_BENCH_YEARS` (default 100).
use std::time::Instant;
mod common;
use sylva::sim::{step_year, Scenario, World, YearReport};
use sylva::species::SpeciesLibrary;

fn vm_hwm_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    s.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let ha: f64 = std::env::var("SYLVA_BENCH_HA").ok().and_then(|v| v.parse().ok()).unwrap_or(1000.0);
    let years: u32 = std::env::var("SYLVA_BENCH_YEARS").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    let side_cells = ((ha * 10_000.0).sqrt() / 50.0).round().max(1.0) as usize; // 50 m cells
    let terrain = format!("uniform = {{ width = {side_cells}, height = {side_cells}, cell_m = 50.0, elevation_m = 500.0, indices = [5, 5, 3, 5, 6, 6] }}");
    let toml = common::afforestation_toml("bench", years, "", &terrain);
    let sc = Scenario::from_toml_str(&toml, "bench").expect("scenario");
    let lib = SpeciesLibrary::embedded().expect("species");
    let mut w = World::new(sc.site().expect("site"), &lib, &sc).expect("world");
    eprintln!("ecosystem bench: {:.0} ha, {years} years, {} threads", w.site.area_ha, rayon::current_num_threads());
    let t0 = Instant::now();
    let mut tree_years = 0u64;
    let mut phase_total = [0f64; sylva::sim::step::N_PHASES];
    let mut phase_decade = [0f64; sylva::sim::step::N_PHASES];
    for _ in 0..years {
        let ty = Instant::now();
        let mut r = YearReport::default();
        step_year(&mut w, &sc, &mut r);
        tree_years += r.trees as u64;
        for k in 0..phase_total.len() {
            phase_total[k] += r.phase_seconds[k];
            phase_decade[k] += r.phase_seconds[k];
        }
        if w.stand.year % 10 == 0 {
            let phases: Vec<String> = sylva::sim::step::PHASES.iter().map(|p| p.name).zip(&phase_decade).map(|(n, s)| format!("{n} {:.2}", s / 10.0)).collect();
            eprintln!("year {:3}: {:8} trees, {:8} cohorts ({:9} stems), {:.2} s/yr; per phase (s/yr over the decade): {}", w.stand.year, r.trees, w.stand.cohorts.len(), w.stand.cohorts.total_stems(), ty.elapsed().as_secs_f64(), phases.join(", "));
            phase_decade = [0.0; sylva::sim::step::N_PHASES];
        }
    }
    let s = t0.elapsed().as_secs_f64();
    let row = sylva::sim::stats::stand_row(&w);
    println!("area_ha {:.0}", w.site.area_ha);
    println!("years {years}");
    println!("live_trees_end {}", w.stand.trees.len());
    println!("cohorts_end {} cohort_stems_end {} regeneration_per_ha_end {:.0}", w.stand.cohorts.len(), w.stand.cohorts.total_stems(), row.regeneration_ha);
    println!("stems_per_ha_end {:.0} basal_area_m2_ha {:.1} top_height_m {:.1}", row.stems_ha, row.basal_area_m2_ha, row.top_height_m);
    println!("total_s {s:.2}");
    println!("s_per_year {:.3}", s / years as f64);
    println!("tree_years_per_s {:.0}", tree_years as f64 / s);
    for (n, s) in sylva::sim::step::PHASES.iter().map(|p| p.name).zip(&phase_total) {
        println!("phase_s {n} {s:.2}");
    }
    println!("peak_rss_mib {:.0}", vm_hwm_kib().unwrap_or(0) as f64 / 1024.0);
}
