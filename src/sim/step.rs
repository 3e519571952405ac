//! One simulated year as a readable list of phases.

use super::phases::{growth, light, mortality, regen, reproduction};
use super::scenario::Scenario;
use super::stats::{stand_row, StandRow};
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
}

/// Number of timed phases.
pub const N_PHASES: usize = 6;
/// Names of the timed phases, in [`YearReport::phase_seconds`] order.
pub const PHASES: [&str; N_PHASES] = ["light", "establishment", "growth", "reproduction", "mortality", "stats"];

/// Simulates one year: light → spring establishment → summer growth → autumn seed fall →
/// winter mortality → statistics. Increments `world.year`.
pub fn step_year(world: &mut World, scenario: &Scenario, report: &mut YearReport) {
    step_year_with(world, scenario, report, &mut |_, _| {});
}

/// Like [`step_year`], calling `on_season(season, world)` after spring, summer, autumn and
/// winter (for seasonal snapshots).
pub fn step_year_with(world: &mut World, _scenario: &Scenario, report: &mut YearReport, on_season: &mut dyn FnMut(Season, &World)) {
    world.dead.clear();
    let mut clock = Instant::now();
    let mut lap = |k: usize, report: &mut YearReport| {
        let now = Instant::now();
        report.phase_seconds[k] = (now - clock).as_secs_f64();
        clock = now;
    };
    // light regime from the canopy at the start of the year
    light::run(world);
    lap(0, report);
    // spring: germination and establishment
    report.established = regen::run(world);
    lap(1, report);
    on_season(Season::Spring, world);
    // summer: growth
    growth::run(world);
    lap(2, report);
    on_season(Season::Summer, world);
    // autumn: seed production and dispersal
    reproduction::run(world);
    lap(3, report);
    on_season(Season::Autumn, world);
    // winter: mortality and windthrow
    mortality::run(world);
    lap(4, report);
    world.year += 1;
    report.died = world.dead.len();
    report.trees = world.trees.len();
    report.row = Some(stand_row(world));
    lap(5, report);
    on_season(Season::Winter, world);
}
