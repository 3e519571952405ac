//! Ecosystem simulation: scenario, tree store (struct of arrays), yearly phases, statistics,
//! checkpoints and the run driver.
//!
//! Year (see [`step::step_year`]): light (height-sorted canopy grid, [`phases::light`]) →
//! spring regeneration layer (sapling cohorts, [`regen`]) → summer growth → autumn seed fall → winter mortality → stand table.
//! All randomness comes from [`crate::rng::Stream`]s keyed by (seed, tree id or cell, year,
//! phase); parallel work is merged in index order, so results do not depend on thread count.

pub mod checkpoint;
pub mod density;
pub mod fixtures;
pub mod phases;
pub mod regen;
pub mod run;
pub mod scenario;
pub mod stats;
pub mod step;
pub mod trees;
pub mod world;

pub use scenario::{Scenario, Start, TerrainSpec};
pub use step::{step_year, YearReport};
pub use trees::{DeathCause, TreeId, TreeStore};
pub use regen::{Cohort, Cohorts, RegenDeath, RECRUIT_HEIGHT_M};
pub use world::World;
