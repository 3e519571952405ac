//! Establishment (spring): natural regeneration enters the regeneration layer of sapling cohorts
//! ([`crate::sim::regen`]), which germinates, grows, thins and recruits individual trees into
//! the tree store when they pass [`crate::sim::regen::RECRUIT_HEIGHT_M`].

use super::super::world::World;

/// Runs the regeneration layer for the year; returns the number of trees recruited.
pub fn run(w: &mut World) -> usize {
    super::super::regen::run(w)
}
