//! One simulated year as a readable list of phases.

use super::phases::{establishment, growth, light, mortality, reproduction};
use super::scenario::Scenario;
use super::stats::{stand_row, StandRow};
use super::world::World;
use crate::species::Season;

/// What happened in a year.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct YearReport {
    /// Stand-table row at the end of the year.
    pub row: Option<StandRow>,
    /// Trees established this spring.
    pub established: usize,
    /// Trees that died this winter.
    pub died: usize,
    /// Living trees at the end of the year.
    pub trees: usize,
}

/// Simulates one year: light → spring establishment → summer growth → autumn seed fall →
/// winter mortality → statistics. Increments `world.year`.
pub fn step_year(world: &mut World, scenario: &Scenario, report: &mut YearReport) {
    step_year_with(world, scenario, report, &mut |_, _| {});
}

/// Like [`step_year`], calling `on_season(season, world)` after spring, summer, autumn and
/// winter (for seasonal snapshots).
pub fn step_year_with(world: &mut World, _scenario: &Scenario, report: &mut YearReport, on_season: &mut dyn FnMut(Season, &World)) {
    world.dead.clear();
    // light regime from the canopy at the start of the year
    light::run(world);
    // spring: germination and establishment
    let before = world.trees.len();
    establishment::run(world);
    report.established = world.trees.len() - before;
    on_season(Season::Spring, world);
    // summer: growth
    growth::run(world);
    on_season(Season::Summer, world);
    // autumn: seed production and dispersal
    reproduction::run(world);
    on_season(Season::Autumn, world);
    // winter: mortality and windthrow
    mortality::run(world);
    world.year += 1;
    report.died = world.dead.len();
    report.trees = world.trees.len();
    report.row = Some(stand_row(world));
    on_season(Season::Winter, world);
}
