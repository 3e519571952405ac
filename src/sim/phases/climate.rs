//! Climate (the year's start): under a changing climate ([`ClimateChange`]), the year's
//! temperature offset and precipitation factor move every cell's T (and F) index
//! ([`shifted_indices`]); the suitability of every cell for every pool species and of every tree
//! for its species follow, times each species' drought response to the year's moisture deficit
//! ([`crate::species::Species::drought_response`], issue 35 round 39: a dry year cuts growth by
//! drought tolerance), so establishment (regeneration) and growth respond this year. Under a
//! constant climate it does nothing. Per cell and per tree, in parallel, each value written
//! once: the result does not depend on the thread count.

use crate::conditions::{factor, SiteConditions};
use crate::sim::climate_change::{shifted_indices, ClimateChange};
use crate::sim::trees::TreeStore;
use crate::species::{SpeciesId, SpeciesLibrary};
use rayon::prelude::*;

/// What the climate phase reads and writes.
pub struct ClimatePhase<'a> {
    /// The year being simulated (years completed before it): the offset of year `year + 1`.
    pub year: u32,
    /// The change.
    pub change: &'a ClimateChange,
    /// Site conditions (base indices, mask).
    pub site: &'a SiteConditions,
    /// Species library.
    pub lib: &'a SpeciesLibrary,
    /// Pool species.
    pub pool: &'a [SpeciesId],
    /// Written: suitability per pool species per site cell held (the cells of `site`'s grids)
    /// under this year's climate.
    pub suitability: &'a mut [Vec<f32>],
    /// Written: each tree's suitability (its cell's, for its species).
    pub trees: &'a mut TreeStore,
}

/// Applies the year's climate. Returns the temperature offset (K) and precipitation factor.
pub fn run(c: ClimatePhase<'_>) -> (f64, f64) {
    let (dt, pf) = c.change.of_year(c.year + 1);
    if !c.change.is_active() {
        return (dt, pf);
    }
    let site = c.site;
    for (p, out) in c.suitability.iter_mut().enumerate() {
        let sp = &c.lib.species[c.pool[p] as usize];
        out.par_iter_mut().zip(site.indices.data.par_iter()).zip(site.mask.data.par_iter()).with_min_len(4096).for_each(|((o, ix), m)| {
            *o = if *m {
                let sh = shifted_indices(ix, dt, pf);
                // the niche of the year's indices, times the drought response to the year's
                // moisture deficit against the base climate (issue 35, round 39)
                sp.suitability(&sh) * sp.drought_response(ix[factor::F] - sh[factor::F])
            } else {
                0.0
            };
        });
    }
    let suit = &*c.suitability;
    let pidx: Vec<Option<usize>> = (0..c.lib.species.len() as u16).map(|s| c.pool.iter().position(|&q| q == s)).collect();
    let t = &mut *c.trees;
    let (x, y, species) = (&t.x, &t.y, &t.species);
    t.suitability.par_iter_mut().enumerate().with_min_len(4096).for_each(|(i, s)| {
        // the tree's cell among the cells held (a tile's own trees stand on its cells)
        let cell = site.cell_at(x[i] as f64, y[i] as f64).and_then(|(col, row)| site.held_index(col, row)).filter(|&k| site.mask.data[k]);
        if let (Some(cell), Some(p)) = (cell, pidx[species[i] as usize]) {
            *s = suit[p][cell];
        }
    });
    (dt, pf)
}
