//! Ecosystem simulation: scenario, tree store (struct of arrays), yearly phases, statistics and
//! checkpoint encoding. A pure core: it computes and returns values and writes no files (the run
//! driver that writes the run directory is [`crate::job::run`]).
//!
//! Year (see [`step::step_year`]): light (height-sorted canopy grid, [`phases::light`]) →
//! spring regeneration layer (sapling cohorts, [`regen`]) → summer growth → autumn seed fall → winter mortality → stand table.
//! All randomness comes from [`crate::rng::Stream`]s keyed by (seed, tree id or cell, year,
//! phase); parallel work is merged in index order, so results do not depend on thread count.

pub mod bucket;
pub mod checkpoint;
pub mod codec;
pub mod climate_change;
pub mod cohorts;
pub mod density;
pub mod fixtures;
pub mod light_grid;
pub mod management;
pub mod obstacle;
pub mod phases;
pub mod pure_stand;
pub mod rules;
pub mod scenario;
pub mod select;
pub mod stats;
pub mod step;
pub mod tiles;
pub mod trees;
/// The water balance (moved to [`crate::climate::water`] in round 45, so that the site's
/// moisture index F can read it; re-exported here under its round-44 path).
pub use crate::climate::water;
pub mod world;

pub use scenario::{Scenario, Start, TerrainSpec};
pub use step::{step_year, YearReport};
pub use trees::{DeathCause, TreeId, TreeStore};
pub use cohorts::{Cohort, Cohorts, RegenDeath, RECRUIT_HEIGHT_M};
/// The regeneration phase, also at its former path `sim::regen`.
pub use phases::regen;
pub use world::World;
pub use light_grid::LightGrid;
