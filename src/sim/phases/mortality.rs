//! Mortality (winter): intrinsic, rising with age ([`p_intrinsic`]; recorded as `age` for
//! senescent trees, `background` for younger ones), shade ([`p_shade`], by shade tolerance, for
//! trees below the upper layer ([`below_upper_layer`]); recorded as `stress`), stress (suppressed growth under crowding, a poor site or drought over
//! several years), drought stress under a changing climate ([`drought_stressed`]: the species'
//! drought limit below ForClim's slow-growth threshold in [`DROUGHT_STRESS_YEARS`] consecutive
//! years; recorded as `stress`) and windthrow. Dead trees leave the store and are recorded with
//! their cause.

use crate::conditions::SiteConditions;
use crate::sim::climate_change::{year_indices, ClimateChange};
use crate::sim::light_grid::{CellRect, LightGrid, Span};
use crate::sim::trees::{DeadTree, DeathCause, TreeStore, N_CAUSES, SENESCENT_AGE_SHARE};
use crate::species::SpeciesLibrary;
use crate::rng::{salt, Stream};
use rayon::prelude::*;

/// Stress mortality probability per year while vigour is below the threshold
/// (Bugmann 2001: 0.368, "suppressed trees die within about a decade").
pub const P_STRESS: f64 = 0.368;

/// Annual shade mortality at zero growth of the most shade-tolerant class (shade tolerance 5):
/// 1/72, a mean survival time of 72 years, that of juvenile European beech in the deep shade of
/// the primeval beech forest of Uholka, Ukraine (Petrovska, Bugmann, Hobi, Ghosh & Brang 2021,
/// Eur. J. For. Res. 141:43–58, "Survival time and mortality rate of regeneration in the deep
/// shade of a primeval beech forest", abstract: "the average survival time of F. sylvatica
/// juveniles (72 years)"; the two maples there survive shorter).
pub const P_SHADE_TOLERANT: f64 = 1.0 / 72.0;

/// Annual shade mortality (0–1) at zero growth of a species of shade survival class `st` (1–5,
/// clamped; `life.shade_survival()`, the shipped files' LandClim class): log-linear in `st` from [`P_STRESS`] (0.368, class 1: ForClim's slow-growth
/// mortality, Bugmann 2001, 1 % of suppressed trees alive after a decade) to
/// [`P_SHADE_TOLERANT`] (1/72, class 5, Petrovska et al. 2021):
/// `P_STRESS · (P_SHADE_TOLERANT / P_STRESS)^((st − 1) / 4)`. Half-lives in full shade
/// (`ln 2 / −ln(1 − p)`): class 1 (birch, larch, Scots pine) 1.5 years, 2 (the oaks, aspen,
/// rowan) 3.9, 3 (spruce, ash, alder, Norway maple, lime) 9.3, 4 (sycamore, hornbeam, elm) 21.6,
/// 5 (beech, fir) 49.5. The interpolation between the two cited ends is a model
/// choice (ESTIMATE): Kobe et al. (1995, Ecol. Appl. 5:517–532) found juvenile survival in
/// shade to order species as their shade tolerance does, without a scale for European classes.
pub fn p_shade_zero_growth(st: f32) -> f64 {
    let w = ((st as f64 - 1.0) / 4.0).clamp(0.0, 1.0);
    P_STRESS * (P_SHADE_TOLERANT / P_STRESS).powf(w)
}

/// Decline of shade mortality with relative growth ([`p_shade`]): `ln 100`, so that a tree
/// growing at its full-light rate dies at 1 % of the zero-growth rate. Model choice (ESTIMATE):
/// Kobe et al. (1995) fit the decline per species on radial growth in mm/yr, which Sylva's
/// relative growth does not give.
pub const SHADE_GROWTH_DECLINE: f64 = 4.605_170_185_988_091;

/// Annual shade mortality (0–1) of a tree or sapling of shade survival class `survival` (1–5,
/// `life.shade_survival()`) and light-response class `st` (1–5, `life.shade_tolerance`) under
/// relative light `light` (0–1):
/// `p_shade_zero_growth(survival) · exp(−SHADE_GROWTH_DECLINE · f(L, st))` with `f` the species'
/// relative growth in that light ([`super::growth::light_response`], the JABOWA/ForClim curves,
/// 0–1): the growth-dependent mortality of juveniles of Kobe et al.
/// (1995, Ecol. Appl. 5:517–532; SORTIE's "GMF" mortality `m = A · e^(−B·G)`, with growth `G`
/// relative here), falling from the zero-growth rate [`p_shade_zero_growth`] below the light
/// compensation point of both curves (L ≤ 0.05) to 1 % of it in full light. Issue 35, round 39
/// (trial 38: light-demanding oak and pine persisted for decades under a closed canopy).
pub fn p_shade(light: f32, survival: f32, st: f32) -> f64 {
    let f = super::growth::light_response(light, st).clamp(0.0, 1.0) as f64;
    p_shade_zero_growth(survival) * (-SHADE_GROWTH_DECLINE * f).exp()
}

/// Share of the local top height (0–1) that a tree or sapling must exceed to stand in the
/// upper layer, where shade mortality ([`p_shade`]) does not act: 2/3, the bound of the upper
/// height class of the IUFRO tree classification (Leibundgut's proposal after Schädelin 1931:
/// class 100, "taking part in the upper canopy, tree height more than two thirds of the top
/// height"; the middle class 1/3–2/3 and the lower class below 1/3 do not take part in it).
/// The top height here is local: the tallest crown over the tree's light cell (the light
/// phase's [`crate::sim::phases::light::Light::canopy_top`]), not the stand's H100.
///
/// Why (issue 35, round 40): the growth-dependent mortality of Kobe et al. (1995) was fitted on
/// saplings in the understorey (SORTIE-ND's "GMF mortality" lets a user apply it to any life
/// stage: sortie-nd.org, help, mortality behaviours; where it acts is the modeller's choice);
/// applied to every tree, it killed the codominant and
/// intermediate trees of light-demanders in their own closed stands (light 0.3–0.5) at about
/// 3 % a year, so unmanaged Scots pine fell to 0.62 of its maximum-density line (round 39,
/// branch `r39p`).
pub const UPPER_LAYER_SHARE: f32 = 2.0 / 3.0;

/// True when a tree or sapling of height `h` (m) stands below the upper layer of a canopy
/// whose local top height is `top` (m, [`UPPER_LAYER_SHARE`]): `h < UPPER_LAYER_SHARE · top`.
/// Where nothing is taller than 1.5 h (an open cell: `top` 0, or the tree among its peers) it
/// is in the upper layer.
#[inline]
pub fn below_upper_layer(h: f32, top: f32) -> bool {
    h < UPPER_LAYER_SHARE * top
}

/// Vigour threshold below which stress mortality applies, by shade tolerance (1–5):
/// `0.02 + 0.08 (5 − ST) / 4` (intolerant trees die sooner when suppressed; below the upper
/// layer the vigour leaves light out, which acts there through [`p_shade`]).
pub fn stress_threshold(st: f32) -> f32 {
    0.02 + 0.08 * ((5.0 - st) / 4.0).clamp(0.0, 1.0)
}

/// ForClim's relative slow-growth threshold `kMinRelInc` (0–1) applied to the drought factor
/// alone: a year in which a species' drought limit at a cell
/// ([`crate::species::Species::drought_limit`] of the year's F, `sqrt(1 − DI / kDrTol)`) is
/// below 0.1 is a drought stress year there. ForClim counts a tree's consecutive years whose
/// growth reduction factor is below `kMinRelInc` (ForClim v3.0 documentation, eq. 4.30, the
/// slow-growth counter `sGr` of `Cohort.Grow`, as a public Java port of ForClim's C# `Cohort.cs`
/// quotes them in the code search corpus; the 10 % of optimal growth of Bugmann's gap models).
/// Sylva keeps 0.1 and counts the drought part of the growth
/// reduction only: light and crowding have their own mortality ([`p_shade`], the vigour's
/// [`stress_threshold`]), whose threshold for shade-tolerant species (0.02 for beech) a drought
/// alone never reached: the vigour memory `v ← 0.5 v + 0.5 S` settles at half of a starved
/// beech's S, 0.05 at S 0.1 (trial 46 D4: +6 K and drought years killed no tree).
pub const DROUGHT_STRESS_LIMIT: f32 = 0.1;

/// Consecutive drought stress years ([`DROUGHT_STRESS_LIMIT`]) after which a tree faces
/// [`P_STRESS`] a year: 3, the form of ForClim's stress memory (mortality once the count exceeds
/// `kSlowGrowThreshold`; ForClim v3.0 eq. 4.30). ESTIMATE: ForClim's default of
/// `kSlowGrowThreshold` was not found in a citable table; 3 years (a threshold of 2) is the
/// value assumed here.
pub const DROUGHT_STRESS_YEARS: u32 = 3;

/// Whether a tree of a species with drought limit `limit(F)` stood in drought stress in each of
/// the [`DROUGHT_STRESS_YEARS`] years up to simulation year `year_1` (the stand table's year,
/// 1 = the first simulated year): for each year `y` of them, the cell's indices `ix` moved by
/// that year's offset and drought-index rise ([`year_indices`], the climate phase's own
/// computation; `rise(y)` the cell's rise in year `y`) give a drought limit below
/// [`DROUGHT_STRESS_LIMIT`]. Years before the first (`y` < 1) are the base climate's. Stateless:
/// the years' climate is a function of the year, so a resumed run sees the same memory as an
/// unbroken one and the checkpoint holds nothing more.
pub fn drought_stressed(change: &ClimateChange, year_1: u32, ix: &[f32; 6], rise: impl Fn(usize) -> f32, limit: impl Fn(f32) -> f32) -> bool {
    (0..DROUGHT_STRESS_YEARS as usize).all(|j| {
        let y = year_1 as i64 - j as i64;
        let (dt, r) = if y >= 1 { (change.of_year(y as u32).0, rise(j)) } else { (0.0, 0.0) };
        limit(year_indices(ix, dt, r)[crate::conditions::factor::F]) < DROUGHT_STRESS_LIMIT
    })
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
    /// The climate change (drought stress mortality, [`drought_stressed`]; none under a
    /// constant climate).
    pub change: &'a ClimateChange,
    /// The light grid (the cell of a tree, for its local top height).
    pub light: &'a LightGrid,
    /// The light cells `canopy_top` holds (a tile's, [`crate::sim::tiles`]); `None`: every cell.
    pub window: Option<CellRect>,
    /// Local top height (m) per light cell of the span of `window`, from this year's light
    /// phase ([`crate::sim::phases::light::Light::canopy_top`]). A tree whose cell it does not
    /// hold (an empty array) is taken to stand below the upper layer, as every tree did before
    /// round 40.
    pub canopy_top: &'a [f32],
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
    let (light, top) = (w.light, w.canopy_top);
    let span = Span::new(w.window, light);
    // each held cell's drought-index rise in the years of the drought stress memory, this
    // year's first (only under a changing climate: nothing changes otherwise)
    let change = w.change;
    let rises: Vec<Vec<f32>> = if change.is_active() {
        (0..DROUGHT_STRESS_YEARS as i64)
            .map(|j| year as i64 + 1 - j)
            .map(|y| if y >= 1 { let (dt, pf) = change.of_year(y as u32); super::climate::drought_rise(site, &change.water, dt, pf) } else { Vec::new() })
            .collect()
    } else {
        Vec::new()
    };
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
            // shade (by shade tolerance) below the upper layer, then slow growth from crowding,
            // site and drought; the shade draw is made in the upper layer too (with p = 0), so
            // the later draws of a tree's stream do not depend on its layer
            let below = span.index(light.cell_of(t.x[i], t.y[i])).and_then(|k| top.get(k)).is_none_or(|&h| below_upper_layer(t.height[i], h));
            let ps = if below { p_shade(t.light[i], sp.life.shade_survival(), sp.life.shade_tolerance) } else { 0.0 };
            if r.chance(ps) {
                return Some(DeathCause::Stress);
            }
            if t.vigour[i] < stress_threshold(sp.life.shade_tolerance) && r.chance(P_STRESS) {
                return Some(DeathCause::Stress);
            }
            // drought stress years (a changing climate only; the draw is made for stressed
            // trees alone, after the others, so the other draws are those of a constant climate)
            if !rises.is_empty() && sp.life.drought_tolerance.is_some() {
                let cell = site.cell_at(t.x[i] as f64, t.y[i] as f64).and_then(|(c, rw)| site.held_index(c, rw)).filter(|&k| site.mask.data[k]);
                if let Some(k) = cell {
                    let stressed = drought_stressed(change, year as u32 + 1, &site.indices.data[k], |j| rises[j].get(k).copied().unwrap_or(0.0), |f| sp.drought_limit(f));
                    if stressed && r.chance(P_STRESS) {
                        return Some(DeathCause::Stress);
                    }
                }
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

    /// ForClim's stress memory on the drought limit: three consecutive years below 0.1, and no
    /// fewer, make a drought-stressed tree; a wet year among them resets it; years before the
    /// first are the base climate's. The limit here is beech's (F optimum 5, kDrTol 0.25):
    /// `sqrt(1 − (5 − F) / 10 / 0.25)`, below 0.1 where F < 2.525.
    #[test]
    fn drought_stress_needs_three_consecutive_years() {
        let beech = |f: f32| crate::species::drought_factor((5.0 - f).max(0.0) / 10.0, 0.25);
        assert!(beech(2.5) < DROUGHT_STRESS_LIMIT && beech(2.6) > DROUGHT_STRESS_LIMIT);
        let change = ClimateChange { warming_k_per_century: 0.0, ..Default::default() };
        let ix = [5.0, 5.0, 3.0, 4.0, 6.0, 6.0];
        // F 4 lowered by 10 F units per unit of rise: a rise of 0.16 gives F 2.4 (stressed)
        let dry = |_: usize| 0.16f32;
        assert!(drought_stressed(&change, 10, &ix, dry, beech));
        // the year two years back wet: not stressed (only two consecutive years)
        assert!(!drought_stressed(&change, 10, &ix, |j| if j == 2 { 0.0 } else { 0.16 }, beech));
        // this year wet: not stressed
        assert!(!drought_stressed(&change, 10, &ix, |j| if j == 0 { 0.0 } else { 0.16 }, beech));
        // year 2 of a run: year 0 is the base climate's (F 4, limit 0.77): not stressed
        assert!(!drought_stressed(&change, 2, &ix, dry, beech));
        assert!(drought_stressed(&change, 3, &ix, dry, beech));
        // a rise of 0.1 (F 3, limit 0.45): never stressed
        assert!(!drought_stressed(&change, 10, &ix, |_| 0.1, beech));
        // sessile oak (kDrTol 0.33) at the beech-killing rise: limit 0.46, not stressed
        let oak = |f: f32| crate::species::drought_factor((5.0 - f).max(0.0) / 10.0, 0.33);
        assert!(!drought_stressed(&change, 10, &ix, dry, oak));
    }

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
