//! One simulated year as data: [`PHASES`], the phases in order, each with its name (used by the
//! timers, the bench's per-phase output and ARCHITECTURE.md), what it does, the season it
//! closes, and the function that hands it the parts of the [`World`] it reads and writes.

use super::density;
use super::phases::{climate, growth, light, management, mortality, regen, reproduction};
use super::scenario::Scenario;
use super::stats::{entry_harvest, stand_row, StandRow};
use super::world::World;
use crate::species::Season;
use std::time::Instant;

/// What happened in a year.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct YearReport {
    /// Stand-table row at the end of the year.
    pub row: Option<StandRow>,
    /// Trees recruited from the regeneration layer this spring.
    pub established: usize,
    /// Trees that died this winter.
    pub died: usize,
    /// Living trees at the end of the year.
    pub trees: usize,
    /// Wall time (s) of each phase in [`PHASES`] order (for profiling; not part of the state).
    pub phase_seconds: [f64; N_PHASES],
    /// Notes for the run's log, one line each: a thinning entry due this year that removed
    /// nothing, and why ([`management::run`]). In a tiled run every rank has them (the
    /// management phase acts on the same trees on every rank); the run writes rank 0's.
    pub notes: Vec<String>,
}

/// One phase of the year.
pub struct Phase {
    /// Short name: timers, bench output, ARCHITECTURE.md.
    pub name: &'static str,
    /// What the phase does, in one line (quoted in ARCHITECTURE.md).
    pub summary: &'static str,
    /// The season that ends with this phase (seasonal snapshots are taken after it).
    pub ends: Option<Season>,
    /// Runs the phase: passes it the parts of the world it reads and writes.
    pub run: fn(&mut World, &mut YearReport),
    /// What the phase reads across a tile edge (a tiled run, `sim::tiles`, passes each tile
    /// the neighbours' trees within that reach before it).
    pub halo: Halo,
}

/// What a phase reads of the trees around a tile ([`Phase::halo`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Halo {
    /// Nothing beyond its own cells and trees.
    None,
    /// Crowns shading its cells (light): every tree within the largest crown plus two light cells.
    Crowns,
    /// Crowding neighbourhoods (growth): every tree within three 10 m crowding cells.
    Crowding,
    /// Seed sources (reproduction): the mature trees within the longest seed reach; a tiled
    /// run passes their production per seed cell instead of the trees (`sim::tiles`).
    SeedSources,
    /// The areas of the management entries due this year (management): a thinning's target,
    /// triggers and choice of trees are over its whole area, so every tile gets every tree of
    /// the areas of the year's thinnings and harvests (`sim::tiles`).
    Areas,
}

/// Number of phases.
pub const N_PHASES: usize = 8;

/// The year, in order. ARCHITECTURE.md quotes this list (checked by `tests/layers.rs`).
pub const PHASES: [Phase; N_PHASES] = [
    Phase { name: "climate", summary: "the year's temperature offset moves T, and the year's temperature and precipitation drive every cell's monthly water balance (`climate::water`), whose rise of the drought index over the base climate's lowers F; suitability of every cell and tree, the species' niche and drought limit of the year's indices (nothing under a constant climate)", ends: None, run: run_climate, halo: Halo::None },
    Phase { name: "light", summary: "canopy grid from the trees at the start of the year; light of every tree and of the ground", ends: None, run: run_light, halo: Halo::Crowns },
    Phase { name: "regeneration", summary: "spring: germination, growth, thinning and recruitment of the sapling cohorts", ends: Some(Season::Spring), run: run_regeneration, halo: Halo::None },
    Phase { name: "growth", summary: "summer: crowding of every tree's neighbourhood; height, DBH and crown increments", ends: Some(Season::Summer), run: run_growth, halo: Halo::Crowding },
    Phase { name: "reproduction", summary: "autumn: seed production and dispersal onto the seed grids", ends: Some(Season::Autumn), run: run_reproduction, halo: Halo::SeedSources },
    Phase { name: "mortality", summary: "winter: senescence, background, stress (drought stress years under a changing climate included) and wind deaths", ends: None, run: run_mortality, halo: Halo::None },
    Phase { name: "management", summary: "the year's end: thinnings, harvests, clearings kept open (cause `harvest`) and plantings of the scenario's `[[management]]` entries due", ends: None, run: run_management, halo: Halo::Areas },
    Phase { name: "stats", summary: "the year ends: stand-table row of the year", ends: Some(Season::Winter), run: run_stats, halo: Halo::None },
];

fn run_climate(w: &mut World, _: &mut YearReport) {
    climate::run(climate::ClimatePhase {
        year: w.stand.year,
        change: &w.site.climate_change,
        site: &w.site.conditions,
        lib: &w.site.lib,
        pool: &w.site.pool,
        suitability: &mut w.site.suitability,
        trees: &mut w.stand.trees,
    });
}

fn run_management(w: &mut World, report: &mut YearReport) {
    if w.site.management.is_empty() {
        return;
    }
    let d0 = w.scratch.dead.len();
    let (_, notes, removed, capped, planted) = management::run_by_entry(management::Manage { seed: w.site.seed, year: w.stand.year, site: &w.site, trees: &mut w.stand.trees, dead: &mut w.scratch.dead, deaths_total: &mut w.tallies.deaths_total });
    report.notes.extend(notes);
    // a clearing kept open loses its sapling cohorts above its height too (a tiled run's rank
    // its own cells' cohorts)
    let saplings = management::keep_open_cohorts(&w.site, w.stand.year, &mut w.stand.cohorts);
    // each entry's harvest, over its removed trees in the order they were recorded (a tiled
    // run's ranks all see every removed tree here: `sim::tiles`)
    let mut at = d0;
    w.scratch.entry_harvest = removed
        .iter()
        .zip(saplings)
        .zip(capped)
        .zip(planted.iter())
        .map(|(((&n, saplings), capped), planted)| {
            let s = entry_harvest(&w.site, &w.scratch.dead[at..at + n]);
            at += n;
            super::stats::EntryHarvest { saplings, capped, planted: planted.len() as u64, ..s }
        })
        .collect();
    w.scratch.planted_at = planted;
}

fn run_light(w: &mut World, _: &mut YearReport) {
    light::run(light::Light {
        light: &w.site.light,
        site: &w.site.conditions,
        lib: &w.site.lib,
        light_site: &w.site.light_site,
        rel_insolation: &w.site.rel_insolation,
        obstacles: &w.site.obstacle_canopy,
        trees: &mut w.stand.trees,
        ground_light: &mut w.scratch.ground_light,
        canopy_top: &mut w.scratch.canopy_top,
        grid: &mut w.scratch.grid,
        window: w.site.window,
    });
}

fn run_regeneration(w: &mut World, report: &mut YearReport) {
    report.established = regen::run(regen::Regen {
        seed: w.site.seed,
        year: w.stand.year,
        light: &w.site.light,
        light_site: &w.site.light_site,
        site: &w.site.conditions,
        lib: &w.site.lib,
        pool: &w.site.pool,
        suitability: &w.site.suitability,
        seed_rain: &w.site.seed_rain,
        ground_light: &w.scratch.ground_light,
        canopy_top: &w.scratch.canopy_top,
        ground_free: &w.site.ground_free,
        obstacles: &w.site.obstacles,
        seeds: &w.stand.seeds,
        cohorts: &mut w.stand.cohorts,
        trees: &mut w.stand.trees,
        regen_ledger: &mut w.tallies.regen_ledger,
        regen_year: &mut w.scratch.regen_year,
        window: w.site.window,
    });
}

fn run_growth(w: &mut World, _: &mut YearReport) {
    let crowd = density::crowding(&w.site, &w.stand.trees);
    growth::run(growth::Growth { seed: w.site.seed, year: w.stand.year, lib: &w.site.lib, pool: &w.site.pool, crowd: &crowd, light: &w.site.light, window: w.site.window, canopy_top: &w.scratch.canopy_top, trees: &mut w.stand.trees });
}

fn run_reproduction(w: &mut World, _: &mut YearReport) {
    reproduction::run(reproduction::Reproduction { trees: &w.stand.trees, lib: &w.site.lib, pool: &w.site.pool, seeds: &mut w.stand.seeds });
}

fn run_mortality(w: &mut World, _: &mut YearReport) {
    mortality::run(mortality::Mortality {
        seed: w.site.seed,
        year: w.stand.year,
        site: &w.site.conditions,
        lib: &w.site.lib,
        change: &w.site.climate_change,
        light: &w.site.light,
        window: w.site.window,
        canopy_top: &w.scratch.canopy_top,
        trees: &mut w.stand.trees,
        dead: &mut w.scratch.dead,
        deaths_total: &mut w.tallies.deaths_total,
    });
}

fn run_stats(w: &mut World, report: &mut YearReport) {
    w.stand.year += 1;
    report.died = w.scratch.dead.len();
    report.trees = w.stand.trees.len();
    report.row = Some(stand_row(w));
}

/// Simulates one year: the [`PHASES`] in order. Increments `world.stand.year`.
pub fn step_year(world: &mut World, scenario: &Scenario, report: &mut YearReport) {
    step_year_with(world, scenario, report, &mut |_, _| {});
}

/// Like [`step_year`], calling `on_season(season, world)` after the phases that end spring,
/// summer, autumn and winter (for seasonal snapshots). Each phase's wall time goes to
/// `report.phase_seconds` (callbacks not included).
pub fn step_year_with(world: &mut World, _scenario: &Scenario, report: &mut YearReport, on_season: &mut dyn FnMut(Season, &World)) {
    world.scratch.dead.clear();
    for (k, phase) in PHASES.iter().enumerate() {
        let t0 = Instant::now();
        (phase.run)(world, report);
        report.phase_seconds[k] = t0.elapsed().as_secs_f64();
        if let Some(season) = phase.ends {
            on_season(season, world);
        }
    }
}
