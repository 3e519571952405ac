//! Climate (the year's start): under a changing climate ([`ClimateChange`]), the year's
//! temperature offset moves every cell's T index, and the year's temperature and precipitation
//! move every cell's soil-water balance ([`crate::climate::water`]), whose rise of the drought
//! index over the base climate's lowers the cell's F index ([`year_indices`]); the suitability
//! of every cell for every pool species and of every tree for its species follow: each
//! species' niche and drought limit of the year's indices
//! ([`crate::species::Species::suitability`], [`crate::species::Species::drought_limit`];
//! issue 35: round 39's drought term, round 44's water balance, round 45's F from the water
//! balance), so establishment (regeneration) and growth respond this year. Under a constant
//! climate it does nothing. Per cell and per tree, in parallel, each value written once: the
//! result does not depend on the thread count.

use crate::conditions::SiteConditions;
use crate::climate::water::WaterClimate;
use crate::sim::climate_change::{year_indices, ClimateChange};
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
    // each cell's rise of the drought index over the base climate's (round 44)
    let rise = drought_rise(site, &c.change.water, dt, pf);
    for (p, out) in c.suitability.iter_mut().enumerate() {
        let sp = &c.lib.species[c.pool[p] as usize];
        out.par_iter_mut().zip(site.indices.data.par_iter()).zip(site.mask.data.par_iter()).zip(rise.par_iter()).with_min_len(4096).for_each(|(((o, ix), m), r)| {
            *o = if *m {
                // the niche and drought limit of the year's indices: T of the year's
                // temperature, F lowered by the rise of the year's drought index (round 45)
                sp.suitability(&year_indices(ix, dt, *r))
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

/// The rise (≥ 0) of every held cell's drought index in a year `dt_k` kelvin warmer than the
/// base climate with precipitation factor `precip`, over the cell's index in the base climate
/// ([`WaterClimate::cell_drought_index`] of the cell's mean annual temperature and wetness index
/// at the site's latitude); 0 on masked cells. Per cell, in parallel: the same on a tile as in
/// one process.
pub fn drought_rise(site: &SiteConditions, water: &WaterClimate, dt_k: f64, precip: f64) -> Vec<f32> {
    let lat = site.geo.latitude_deg;
    site.mask
        .data
        .par_iter()
        .zip(site.temperature_c.data.par_iter())
        .zip(site.twi.data.par_iter())
        .with_min_len(1024)
        .map(|((m, t), twi)| {
            if !*m {
                return 0.0;
            }
            let (t, twi) = (*t as f64, *twi as f64);
            let base = water.cell_drought_index(t, twi, lat, 0.0, 1.0);
            (water.cell_drought_index(t, twi, lat, dt_k, precip) - base).max(0.0) as f32
        })
        .collect()
}
