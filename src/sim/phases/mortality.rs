//! Mortality (winter): intrinsic (recorded as `age` for senescent trees, `background` for
//! younger ones), stress (suppressed growth over several years) and windthrow. Dead trees leave the store and are recorded with their cause.

use crate::conditions::SiteConditions;
use crate::sim::trees::{DeadTree, DeathCause, TreeStore, N_CAUSES, SENESCENT_AGE_SHARE};
use crate::species::SpeciesLibrary;
use crate::rng::{salt, Stream};
use rayon::prelude::*;

/// Stress mortality probability per year while vigour is below the threshold
/// (Bugmann 2001: 0.368, "suppressed trees die within about a decade").
pub const P_STRESS: f64 = 0.368;

/// Vigour threshold below which stress mortality applies, by shade tolerance (1–5):
/// `0.02 + 0.08 (5 − ST) / 4` (intolerant trees die sooner in shade).
pub fn stress_threshold(st: f32) -> f32 {
    0.02 + 0.08 * ((5.0 - st) / 4.0).clamp(0.0, 1.0)
}

/// Windthrow probability per year: `0.02 · exposure² · (H / 40 m)²` for trees above 10 m
/// (a simple stand-in for EcoMod's "windiness" living condition, `004_*.txt` section IV).
pub fn p_wind(exposure: f32, height: f32) -> f64 {
    if height < 10.0 {
        return 0.0;
    }
    let e = exposure.clamp(0.0, 1.0) as f64;
    0.02 * e * e * (height as f64 / 40.0).powi(2)
}

/// What mortality reads (seed and year for the random streams, the site's wind exposure, the
/// species) and writes (removes the dead from the trees, records them and counts them by cause).
pub struct Mortality<'a> {
    /// Scenario seed.
    pub seed: u64,
    /// The year being simulated (years completed before it).
    pub year: u32,
    /// Site conditions (wind exposure).
    pub site: &'a SiteConditions,
    /// Species library.
    pub lib: &'a SpeciesLibrary,
    /// Trees: the dead are removed.
    pub trees: &'a mut TreeStore,
    /// Appended: this year's dead with their cause.
    pub dead: &'a mut Vec<DeadTree>,
    /// Incremented: deaths since the start by cause ([`DeathCause::ALL`] order).
    pub deaths_total: &'a mut [u64; N_CAUSES],
}

/// Draws deaths for the year and removes the dead trees.
pub fn run(w: Mortality<'_>) {
    let t = &w.trees;
    let (seed, year) = (w.seed, w.year as u64);
    let site = &w.site;
    let lib = &w.lib;
    let causes: Vec<Option<DeathCause>> = (0..t.len())
        .into_par_iter()
        .map(|i| {
            let sp = &lib.species[t.species[i] as usize];
            let mut r = Stream::new(seed, t.id[i], year, salt::MORTALITY);
            if t.age[i] >= sp.life.max_age_yr {
                return Some(DeathCause::Age);
            }
            if r.chance(4.605 / sp.life.max_age_yr as f64) {
                let senescent = t.age[i] >= SENESCENT_AGE_SHARE * sp.life.max_age_yr;
                return Some(if senescent { DeathCause::Age } else { DeathCause::Background });
            }
            if t.vigour[i] < stress_threshold(sp.life.shade_tolerance) && r.chance(P_STRESS) {
                return Some(DeathCause::Stress);
            }
            let exp = site.cell_at(t.x[i] as f64, t.y[i] as f64).map(|(c, rw)| *site.wind_exposure.get(c, rw)).unwrap_or(0.0);
            let pw = p_wind(exp, t.height[i]);
            if pw > 0.0 && Stream::new(seed, t.id[i], year, salt::WIND).chance(pw) {
                return Some(DeathCause::Wind);
            }
            None
        })
        .collect();
    let mut keep = vec![true; t.len()];
    for (i, c) in causes.iter().enumerate() {
        if let Some(c) = c {
            keep[i] = false;
            w.deaths_total[c.index()] += 1;
            w.dead.push(DeadTree {
                id: t.id[i],
                species: t.species[i],
                x: t.x[i],
                y: t.y[i],
                z: t.z[i],
                age: t.age[i],
                height: t.height[i],
                dbh: t.dbh[i],
                crown_radius: t.crown_radius[i],
                crown_base: t.crown_base[i],
                year: w.year,
                cause: *c,
            });
        }
    }
    w.trees.retain(&keep);
}
