//! Stand statistics: one row of the stand table per year.

use super::trees::DeathCause;
use super::cohorts::RegenYear;
use super::trees::TreeStore;
use super::world::{Site, World};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One stand-table row (per hectare of unmasked area).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StandRow {
    /// Simulation year (1 = after the first year).
    pub year: u32,
    /// Individual trees (the tree store) per ha with height ≥ 1.3 m. Natural regeneration enters
    /// the tree store at [`super::regen::RECRUIT_HEIGHT_M`]; its saplings below that height are
    /// counted in [`StandRow::regeneration_ha`], not here.
    pub stems_ha: f64,
    /// Individual trees per ha below 1.3 m (planted; natural regeneration is in
    /// [`StandRow::regeneration_ha`]).
    pub seedlings_ha: f64,
    /// Regeneration layer: sapling stems per ha below the recruitment height
    /// ([`super::regen::RECRUIT_HEIGHT_M`]), from the cohorts' stem counts.
    pub regeneration_ha: f64,
    /// Basal area (m²/ha).
    pub basal_area_m2_ha: f64,
    /// Mean height of stems ≥ 1.3 m (m).
    pub mean_height_m: f64,
    /// Top height H100 (m): mean height of the 100 largest-DBH trees (≥ 1.3 m) per ha of
    /// unmasked area, i.e. of the `round(100 · area_ha)` thickest trees; where fewer trees stand,
    /// the mean height of all of them (the H100 definition of the yield tables, Assmann 1970).
    pub top_height_m: f64,
    /// Quadratic mean DBH of stems ≥ 1.3 m (cm).
    pub qmd_cm: f64,
    /// Stems per ha with DBH ≥ 7 cm (the merchantable-timber threshold of German yield tables).
    pub stems_7cm_ha: f64,
    /// Quadratic mean DBH of stems with DBH ≥ 7 cm (cm).
    pub qmd_7cm_cm: f64,
    /// Share of basal area per pool species (0–1), pool order.
    pub share_ba: Vec<f64>,
    /// Share of stems (≥ 1.3 m) per pool species (0–1), pool order.
    pub share_stems: Vec<f64>,
    /// Deaths in the year per cause ([`DeathCause::ALL`] order).
    pub deaths: [u64; super::trees::N_CAUSES],
    /// Regeneration layer in the year: stems germinated.
    pub regen_germinated: u64,
    /// Regeneration layer in the year: stems recruited as individual trees.
    pub regen_recruited: u64,
    /// Regeneration layer in the year: stems dead by cause ([`super::regen::RegenDeath::ALL`] order).
    pub regen_deaths: [u64; super::cohorts::N_REGEN_CAUSES],
    /// Standing stem volume (m³/ha) of the trees with DBH ≥ 7 cm ([`stem_volume_m3`]).
    pub volume_m3_ha: f64,
    /// Stems (≥ 1.3 m) per ha removed by the year's thinnings and harvests.
    pub harvest_stems_ha: f64,
    /// Stem volume (m³/ha, trees with DBH ≥ 7 cm, [`stem_volume_m3`]) removed by the year's
    /// thinnings and harvests.
    pub harvest_volume_m3_ha: f64,
    /// The year's temperature offset (K) against the scenario's base climate
    /// (`sim::climate_change`; 0 under a constant climate).
    pub temperature_offset_k: f64,
    /// The year's precipitation factor (1 under a constant climate).
    pub precipitation_factor: f64,
}

/// DBH (cm) from which a stem has merchantable volume (German "Derbholz": wood of at least 7 cm
/// diameter; the yield tables' volumes count it).
pub const VOLUME_MIN_DBH_CM: f32 = 7.0;

/// Stem volume (m³) of a tree of DBH `dbh_cm` (cm) and height `height_m` (m) with the form
/// factor `form_factor` of its species (`life.form_factor`): `V = f · g · h`, `g` the basal area
/// at 1.3 m (m²); 0 below [`VOLUME_MIN_DBH_CM`] (Kramer & Akça 2008, Leitfaden zur
/// Waldmesslehre, form factors of the merchantable stem; the species' factors in their files).
#[inline]
pub fn stem_volume_m3(form_factor: f32, dbh_cm: f32, height_m: f32) -> f64 {
    if dbh_cm < VOLUME_MIN_DBH_CM {
        return 0.0;
    }
    let d = dbh_cm as f64 / 100.0;
    form_factor as f64 * std::f64::consts::FRAC_PI_4 * d * d * height_m as f64
}

/// The year's harvest: stems (≥ 1.3 m) and stem volume (m³) of the trees that died of
/// [`DeathCause::Harvest`] in `dead`, summed in their order.
pub fn harvest_sums(site: &Site, dead: &[super::trees::DeadTree]) -> (u64, f64) {
    let (mut n, mut v) = (0u64, 0f64);
    for d in dead.iter().filter(|d| d.cause == DeathCause::Harvest) {
        if d.height >= 1.3 {
            n += 1;
        }
        v += stem_volume_m3(site.lib.species[d.species as usize].life.form_factor, d.dbh, d.height);
    }
    (n, v)
}

/// Order-preserving key of an f32 under [`f32::total_cmp`] (as an unsigned integer).
#[inline]
fn total_key(v: f32) -> u32 {
    let b = v.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Top height: mean height of the `round(100 · a)` largest-DBH trees of at least 1.3 m
/// (ties by height), summed in descending (DBH, height) order; all of them where fewer stand.
/// The candidates are found by a histogram of the DBHs' leading 16 bits (in parallel; counts
/// do not depend on the order), so only about the `k` thickest trees are sorted.
pub(crate) fn top_height(dbh: &[f32], height: &[f32], a: f64) -> f64 {
    const CH: usize = 1 << 16;
    let n = dbh.len();
    let eligible = |i: usize| !(height[i] < 1.3);
    let hist: Vec<u32> = (0..n.div_ceil(CH))
        .into_par_iter()
        .map(|c| {
            let mut h = vec![0u32; 1 << 16];
            for i in c * CH..((c + 1) * CH).min(n) {
                if eligible(i) {
                    h[(total_key(dbh[i]) >> 16) as usize] += 1;
                }
            }
            h
        })
        .reduce(|| vec![0u32; 1 << 16], |mut x, y| {
            x.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
            x
        });
    let m: usize = hist.iter().map(|&c| c as usize).sum();
    let k = ((100.0 * a).round() as usize).clamp(1, m.max(1));
    // lowest bin such that the bins from it upwards hold at least k trees
    let mut acc = 0usize;
    let mut bin = 0usize;
    for b in (0..hist.len()).rev() {
        acc += hist[b] as usize;
        if acc >= k {
            bin = b;
            break;
        }
    }
    let lo = (bin as u32) << 16;
    let mut top: Vec<(f32, f32)> = (0..n).into_par_iter().with_min_len(1 << 14).filter(|&i| eligible(i) && total_key(dbh[i]) >= lo).map(|i| (dbh[i], height[i])).collect();
    let by_dbh_desc = |x: &(f32, f32), y: &(f32, f32)| y.0.total_cmp(&x.0).then(y.1.total_cmp(&x.1));
    if k < top.len() {
        // the k thickest first (O(n) selection), then sorted for a fixed summation order
        top.select_nth_unstable_by(k - 1, by_dbh_desc);
        top.truncate(k);
    }
    top.sort_by(by_dbh_desc);
    if top.is_empty() {
        0.0
    } else {
        top.iter().map(|x| x.1 as f64).sum::<f64>() / top.len() as f64
    }
}

/// Computes the stand-table row of the world's current state (deaths from `w.scratch.dead`).
/// The sums over the trees run serially in tree order (f64) on one thread while the top height
/// ([`top_height`]) is found on the others.
pub fn stand_row(w: &World) -> StandRow {
    let mut deaths = [0u64; super::trees::N_CAUSES];
    for d in &w.scratch.dead {
        deaths[d.cause.index()] += 1;
    }
    row_of(&w.site, w.stand.year, &w.stand.trees, w.stand.cohorts.total_stems(), deaths, w.scratch.regen_year, harvest_sums(&w.site, &w.scratch.dead))
}

/// The stand-table row of `site` in `year` from the trees `t` (only their ids, species, heights
/// and DBHs are read, in store order), the regeneration layer's stems, this year's deaths by
/// cause and regeneration counts, and the year's harvest (stems ≥ 1.3 m, volume m³:
/// [`harvest_sums`]) ([`stand_row`] on a world; a tiled run's rank 0 gathers these,
/// `sim::tiles`). The year's temperature offset and precipitation factor come from the site's
/// climate change.
pub fn row_of(site: &Site, year: u32, t: &TreeStore, regeneration_stems: u64, deaths: [u64; super::trees::N_CAUSES], regen_year: RegenYear, harvest: (u64, f64)) -> StandRow {
    let w = site;
    let a = w.area_ha.max(1e-9);
    let np = w.pool.len();
    let pidx: Vec<usize> = (0..w.lib.species.len() as u16).map(|s| w.pool_index(s).unwrap_or(0)).collect();
    let ff: Vec<f32> = w.lib.species.iter().map(|s| s.life.form_factor).collect();
    let sums = || {
        let (mut n, mut ns, mut ba, mut hs, mut d2) = (0usize, 0usize, 0f64, 0f64, 0f64);
        let (mut n7, mut d27, mut vol) = (0usize, 0f64, 0f64);
        let mut sba = vec![0f64; np];
        let mut sn = vec![0f64; np];
        for i in 0..t.len() {
            if t.height[i] < 1.3 {
                ns += 1;
                continue;
            }
            n += 1;
            let b = t.basal_area_m2(i);
            ba += b;
            hs += t.height[i] as f64;
            d2 += (t.dbh[i] as f64).powi(2);
            if t.dbh[i] >= 7.0 {
                n7 += 1;
                d27 += (t.dbh[i] as f64).powi(2);
                vol += stem_volume_m3(ff[t.species[i] as usize], t.dbh[i], t.height[i]);
            }
            let p = pidx[t.species[i] as usize];
            sba[p] += b;
            sn[p] += 1.0;
        }
        (n, ns, ba, hs, d2, n7, d27, sba, sn, vol)
    };
    let ((n, ns, ba, hs, d2, n7, d27, sba, sn, vol), h100) = rayon::join(sums, || top_height(&t.dbh, &t.height, a));
    let (dt, pf) = w.climate_change.of_year(year);
    StandRow {
        year,
        stems_ha: n as f64 / a,
        seedlings_ha: ns as f64 / a,
        basal_area_m2_ha: ba / a,
        mean_height_m: if n > 0 { hs / n as f64 } else { 0.0 },
        top_height_m: h100,
        qmd_cm: if n > 0 { (d2 / n as f64).sqrt() } else { 0.0 },
        stems_7cm_ha: n7 as f64 / a,
        qmd_7cm_cm: if n7 > 0 { (d27 / n7 as f64).sqrt() } else { 0.0 },
        share_ba: sba.iter().map(|v| if ba > 0.0 { v / ba } else { 0.0 }).collect(),
        share_stems: sn.iter().map(|v| if n > 0 { v / n as f64 } else { 0.0 }).collect(),
        deaths,
        regeneration_ha: regeneration_stems as f64 / a,
        regen_germinated: regen_year.germinated,
        regen_recruited: regen_year.recruited,
        regen_deaths: regen_year.dead,
        volume_m3_ha: vol / a,
        harvest_stems_ha: harvest.0 as f64 / a,
        harvest_volume_m3_ha: harvest.1 / a,
        temperature_offset_k: dt,
        precipitation_factor: pf,
    }
}
