//! Mortality (winter): intrinsic, rising with age ([`p_intrinsic`]; recorded as `age` for
//! senescent trees, `background` for younger ones), stress (suppressed growth over several years) and windthrow. Dead trees leave the store and are recorded with their cause.

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

/// Shape `k` of the age-dependent intrinsic mortality hazard ([`p_intrinsic`]).
pub const INTRINSIC_SHAPE: f64 = 0.25;

/// Intrinsic (background and senescence) mortality probability per year of a tree of age `age`
/// (yr) of a species reaching `max_age` (yr): the Weibull hazard
/// `h(a) = (k + 1) · 4.605 / max_age · (a / max_age)^k` with `k` = [`INTRINSIC_SHAPE`], clamped
/// to 0–1. Its cumulative hazard at `max_age` is 4.605, so 1 % of trees survive to the maximum
/// age as in the constant rate `4.605 / max_age` of the gap models (Botkin et al. 1972;
/// Bugmann 2001), which is the case `k = 0`; with `k > 0` the hazard rises with age
/// (senescence) and young trees die less from chance, so that self-thinning in young stands is
/// left to competition (stress mortality). Model choice (ESTIMATE): k = 0.25 is the mildest
/// age-dependence tried (0.25, 0.5, 1, 2) with which the short-lived species (aspen, max age 100;
/// rowan and hornbeam, 150), whose constant rate of 3.1–4.6 %/yr removed 56–71 % of a stand's
/// stems by age 27 whatever the crowding, reach their maximum-density lines, while mixed stands stay
/// within 10 % of theirs (tests/sim_density.rs).
pub fn p_intrinsic(age: f32, max_age: f32) -> f64 {
    let m = (max_age as f64).max(1.0);
    let rel = (age as f64 / m).clamp(0.0, 1.0);
    ((INTRINSIC_SHAPE + 1.0) * 4.605 / m * rel.powf(INTRINSIC_SHAPE)).clamp(0.0, 1.0)
}

/// Upper bound of [`p_intrinsic`] for a species of maximum age `max_age` (yr): the hazard at
/// the maximum age, `(k + 1) · 4.605 / max_age` clamped to 0–1, computed as `p_intrinsic`
/// computes its factor, so `p_intrinsic(a, max_age) ≤ intrinsic_bound(max_age)` for every age
/// (the power `(a / max_age)^k` is at most 1 and rounding is monotone).
#[inline]
pub fn intrinsic_bound(max_age: f32) -> f64 {
    let m = (max_age as f64).max(1.0);
    ((INTRINSIC_SHAPE + 1.0) * 4.605 / m).clamp(0.0, 1.0)
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
            // the draw of `r.chance(p_intrinsic(..))`; the hazard's power of the relative age is
            // at most 1, so p_intrinsic is at most its factor `intrinsic_bound`, and draws at or
            // above that bound need not evaluate the power (the outcome is the same)
            let u = r.uniform();
            if u < intrinsic_bound(sp.life.max_age_yr) && u < p_intrinsic(t.age[i], sp.life.max_age_yr) {
                let senescent = t.age[i] >= SENESCENT_AGE_SHARE * sp.life.max_age_yr;
                return Some(if senescent { DeathCause::Age } else { DeathCause::Background });
            }
            if t.vigour[i] < stress_threshold(sp.life.shade_tolerance) && r.chance(P_STRESS) {
                return Some(DeathCause::Stress);
            }
            let exp = site.cell_at(t.x[i] as f64, t.y[i] as f64).and_then(|(c, rw)| site.held_index(c, rw)).map(|k| site.wind_exposure.data[k]).unwrap_or(0.0);
            let pw = p_wind(exp, t.height[i]);
            if pw > 0.0 && Stream::new(seed, t.id[i], year, salt::WIND).chance(pw) {
                return Some(DeathCause::Wind);
            }
            None
        })
        .collect();
    let keep: Vec<bool> = causes.par_iter().with_min_len(1 << 14).map(|c| c.is_none()).collect();
    // the dead in index order (an order-keeping parallel collect), then counted by cause
    let year = w.year;
    let lib = w.lib;
    let dead: Vec<DeadTree> = causes
        .par_iter()
        .enumerate()
        .with_min_len(1 << 14)
        .filter_map(|(i, c)| {
            c.map(|cause| DeadTree {
                id: t.id[i],
                species: t.species[i],
                x: t.x[i],
                y: t.y[i],
                z: t.z[i],
                age: t.age[i],
                height: t.height[i],
                dbh: t.dbh[i],
                crown_radius: t.crown_outline(lib, i),
                crown_base: t.crown_base[i],
                year,
                cause,
            })
        })
        .collect();
    drop(causes);
    for d in &dead {
        w.deaths_total[d.cause.index()] += 1;
    }
    w.dead.extend(dead);
    w.trees.retain(&keep);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intrinsic_hazard_keeps_one_percent_to_max_age() {
        // yearly survival multiplied over a lifetime: ≈ e^−4.605 = 1 % reach max_age
        for max_age in [100.0f32, 150.0, 600.0] {
            let s: f64 = (0..max_age as u32).map(|a| 1.0 - p_intrinsic(a as f32 + 0.5, max_age)).product();
            assert!((s - 0.01).abs() < 0.002, "max age {max_age}: survival {s:.4}");
        }
        // rising with age: at 10 % of max age 0.70 × the constant rate, at max age 1.25 ×
        let c = 4.605 / 150.0;
        assert!((p_intrinsic(15.0, 150.0) / c - 1.25 * 0.1f64.powf(0.25)).abs() < 1e-9);
        assert!((p_intrinsic(150.0, 150.0) / c - 1.25).abs() < 1e-9);
        assert!(p_intrinsic(10.0, 150.0) < p_intrinsic(100.0, 150.0));
        assert_eq!(p_intrinsic(0.0, 150.0), 0.0);
        for max_age in [1.0f32, 100.0, 160.0, 600.0] {
            for a in 0..=700 {
                let age = a as f32 * 1.37;
                assert!(p_intrinsic(age, max_age) <= intrinsic_bound(max_age), "{age} {max_age}");
            }
            assert_eq!(p_intrinsic(max_age, max_age), intrinsic_bound(max_age));
        }
    }
}
