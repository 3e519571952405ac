//! Stand statistics: one row of the stand table per year.

use super::trees::DeathCause;
use super::cohorts::RegenYear;
use super::trees::TreeStore;
use super::world::{Site, World};
// the selection by summed counts and the reduction it takes (sim::select), at their former paths
pub use super::select::{alone, kth_smallest_by, Reduce};
use super::select::{from_total_key, total_key};
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
    /// unmasked area, i.e. of the `round(100 · area_ha)` thickest trees (the H100 definition of
    /// the yield tables, Assmann 1970), taken over the upper layer: the stems at least two
    /// thirds of the top height tall (IUFRO tree classes, Leibundgut 1958; Pretzsch 2009); where
    /// the upper layer holds fewer, the mean height of all of them, so ingrowth under a thin
    /// overstorey does not lower it ([`top_height`]).
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
    /// The year's drought index (0–1), site mean: ForClim's growing-season `1 − AET/PET` of each
    /// site cell's monthly water balance ([`crate::climate::water`]) under the year's climate,
    /// averaged over the site's unmasked light cells ([`drought_sums`]); under a constant climate
    /// the base climate's, the same every year. The species respond to its rise over the base
    /// climate's, cell by cell (`sim::phases::climate`). Round 44.
    #[serde(default)]
    pub drought_index: f64,
    /// The figures of each `[[management]]` entry's area this year, scenario order (empty
    /// without management): the run's `management_table.csv` ([`entry_rows`]).
    #[serde(default)]
    pub management: Vec<EntryRow>,
    /// Stem volume (m³/ha, trees with DBH ≥ 7 cm, [`stem_volume_m3`] at their size when they
    /// died) of the trees that died of natural causes in the year: every [`DeathCause`] but
    /// [`DeathCause::Harvest`] (the harvested volume is [`StandRow::harvest_volume_m3_ha`]), so
    /// gross total production is the standing volume plus the sums over the years of this and
    /// of the harvested volume (trial 41, defect 2).
    #[serde(default)]
    pub deaths_volume_m3_ha: f64,
    /// The year's figures per pool species (pool order): the run's `stand_table_species.csv`
    /// ([`species_rows`]; trial 41, defect 2).
    #[serde(default)]
    pub species: Vec<SpeciesRow>,
}

/// One pool species in a year: a row of `stand_table_species.csv`. Per hectare of the site's
/// unmasked area, as the stand table; stems are trees ≥ 1.3 m, volume the stems with DBH ≥ 7 cm
/// ([`stem_volume_m3`]). Over the species, `stems_ha`, `basal_area_m2_ha` and `volume_m3_ha` add
/// up to the stand table's (the sums are exact, [`fixed`]; each is rounded once), and the
/// deaths of all causes but harvest to [`StandRow::deaths_volume_m3_ha`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeciesRow {
    /// Stems (≥ 1.3 m) per ha.
    pub stems_ha: f64,
    /// Basal area (m²/ha) of the stems.
    pub basal_area_m2_ha: f64,
    /// Quadratic mean DBH Dq (cm) of the stems (0 without stems).
    pub qmd_cm: f64,
    /// The species' own top height H100 (m): the mean height of its `round(100 · area_ha)`
    /// thickest stems (Assmann 1970's h100 over this species' stems only, [`h100_by`]; all its
    /// stems where it has fewer). Unlike the stand table's `top_height_m` it is not taken over
    /// the upper layer: a species of the understorey has its own, lower, top height. 0 without
    /// stems.
    pub top_height_m: f64,
    /// Standing stem volume (m³/ha) of the stems with DBH ≥ 7 cm.
    pub volume_m3_ha: f64,
    /// The species' top height over its own area (m): Assmann's h100 (the mean height of the
    /// 100 thickest stems per hectare) over the hectares the species holds, its share of the
    /// stand's basal area times the site's unmasked area (`round(100 · a · G_sp / G)` of its
    /// thickest stems; all of them where it has fewer; [`species_own_area_top_heights`]). The
    /// species' proportion by area estimated by its basal-area proportion, the simplest of the
    /// estimates del Río et al. 2016 review (*Characterization of the structure, dynamics, and
    /// productivity of mixed-species stands*, Eur. J. For. Res. 135:23–49, §"Species
    /// proportion"; Pretzsch 2009, *Forest Dynamics, Growth and Yield*, §mixed stands), so a
    /// species growing in patches or scattered has the top height of where it grows, not of
    /// the whole site: `top_height_m` takes 100 stems per hectare of the whole site, which for a
    /// species on a sixth of it averages its dominant trees with its thinnest (round 44, trial
    /// 43 defect 8: birch 14.1 m while its trees of 80–120 years were 22–28 m). 0 without stems.
    pub top_height_own_area_m: f64,
    /// Stems (≥ 1.3 m) per ha that died in the year, by cause ([`DeathCause::ALL`] order; the
    /// last, harvest, is what management removed).
    pub deaths_stems_ha: [f64; super::trees::N_CAUSES],
    /// Stem volume (m³/ha, DBH ≥ 7 cm, at death) of the trees that died in the year, by cause
    /// ([`DeathCause::ALL`] order).
    pub deaths_volume_m3_ha: [f64; super::trees::N_CAUSES],
}

/// One `[[management]]` entry's area in a year: a row of the management table
/// (`management_table.csv`). The stand figures are over the trees standing in the entry's area
/// ([`crate::sim::management::Region::contains`]) at the end of the year, after that year's
/// management, per hectare of the area's unmasked ground (`Region::area_ha`), with the stand
/// table's definitions (stems ≥ 1.3 m; volume of stems ≥ 7 cm DBH, [`stem_volume_m3`]; top
/// height [`top_height_by`] over the area); the harvest figures are the trees this entry
/// removed in the year (0 in other years and for plantings), per hectare of its area. The
/// columns after `harvest_volume_m3_ha` (round 41, trial 40) name the entry and give the
/// basal area it removed, the sapling stems a `keep_open` entry cut and the species mix
/// standing in the area.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EntryRow {
    /// Index of the entry in the scenario's `[[management]]` list (0 the first).
    pub entry: usize,
    /// The entry's `kind` (`thinning`, `harvest` or `planting`).
    pub kind: String,
    /// The entry's `method` (`from_below`, `from_above`, `crop_trees`, `clear_cut`, `patch`,
    /// `shelterwood`; empty for a planting).
    pub method: String,
    /// Unmasked area of the entry's area (ha).
    pub area_ha: f64,
    /// Stems (≥ 1.3 m) per ha of the area.
    pub stems_ha: f64,
    /// Basal area (m²/ha) of the stems.
    pub basal_area_m2_ha: f64,
    /// Standing stem volume (m³/ha) of the stems with DBH ≥ 7 cm.
    pub volume_m3_ha: f64,
    /// Quadratic mean DBH (cm) of the stems.
    pub qmd_cm: f64,
    /// Top height (m) of the area: [`top_height_by`] with the area's hectares.
    pub top_height_m: f64,
    /// Stems (≥ 1.3 m) per ha of the area this entry removed in the year.
    pub harvest_stems_ha: f64,
    /// Stem volume (m³/ha of the area, DBH ≥ 7 cm) this entry removed in the year.
    pub harvest_volume_m3_ha: f64,
    /// The entry's name ([`crate::sim::management::Management::display_name`]).
    pub name: String,
    /// Basal area (m²/ha of the area) of the stems (≥ 1.3 m) this entry removed in the year.
    pub harvest_basal_area_m2_ha: f64,
    /// Sapling stems (per ha of the area) of the regeneration layer's cohorts this entry
    /// removed in the year (`keep_open` only; 0 for the other kinds).
    pub cut_saplings_ha: f64,
    /// Share (0–1) of each pool species (pool order) in the basal area of the stems standing in
    /// the area (0 for every species where none stands).
    pub ba_share: Vec<f64>,
    /// Share (0–1) of each pool species (pool order) in the stems (≥ 1.3 m) standing in the
    /// area.
    pub stem_share: Vec<f64>,
    /// True when the entry's `max_removal_share` stopped its thinning this year short of its
    /// target ([`crate::sim::management::Management::max_removal_share`]; round 42, trial 41
    /// defect 1).
    #[serde(default)]
    pub capped: bool,
    /// Trees a planting entry planted in the year per ha of its area (0 in other years and for
    /// the other kinds; trial 46 D5: a planting could not be checked against its spacing, a
    /// spacing of `s` m planting at most `10 000 / s²` per ha).
    #[serde(default)]
    pub planted_ha: f64,
    /// Trees below 1.3 m (planted: natural regeneration is in the cohorts) standing in the
    /// area at the year's end per ha of the area: the stand table's `seedlings_ha` over the
    /// area (trial 46 D5).
    #[serde(default)]
    pub seedlings_ha: f64,
}

pub use super::world::EntryHarvest;

/// The management table's rows of a year ([`EntryRow`]): one per entry of `site.management`,
/// from the sums over the trees in each entry's area (`sums`, [`RowSums::over_where`]), each
/// area's top height (`h100`, m) and each entry's harvest of the year (`harvest`: stems ≥ 1.3 m,
/// their basal area and volume, [`entry_harvest`] over the trees it removed, and the saplings
/// it cut); all three in entry order.
pub fn entry_rows(site: &Site, sums: &[RowSums], h100: &[f64], harvest: &[EntryHarvest]) -> Vec<EntryRow> {
    site.management
        .iter()
        .enumerate()
        .map(|(e, op)| {
            let a = op.region.area_ha.max(1e-9);
            let s = &sums[e];
            let n = s.stems;
            let h = harvest.get(e).copied().unwrap_or_default();
            let ba = unfixed(s.ba);
            EntryRow {
                entry: op.index,
                kind: op.spec.kind.clone(),
                method: op.spec.method.clone().unwrap_or_default(),
                area_ha: op.region.area_ha,
                stems_ha: n as f64 / a,
                basal_area_m2_ha: unfixed(s.ba) / a,
                volume_m3_ha: unfixed(s.vol) / a,
                qmd_cm: if n > 0 { (unfixed(s.d2) / n as f64).sqrt() } else { 0.0 },
                top_height_m: h100[e],
                harvest_stems_ha: h.stems as f64 / a,
                harvest_volume_m3_ha: h.volume_m3 / a,
                name: op.spec.display_name(op.index),
                harvest_basal_area_m2_ha: h.basal_area_m2 / a,
                cut_saplings_ha: h.saplings as f64 / a,
                ba_share: s.ba_sp.iter().map(|&v| if ba > 0.0 { unfixed(v) / ba } else { 0.0 }).collect(),
                stem_share: s.stems_sp.iter().map(|&v| if n > 0 { v as f64 / n as f64 } else { 0.0 }).collect(),
                capped: h.capped,
                planted_ha: h.planted as f64 / a,
                seedlings_ha: (s.trees - s.stems) as f64 / a,
            }
        })
        .collect()
}

/// Each management entry's sums over the trees `t` in its area ([`RowSums::over_where`]),
/// in entry order (empty without management).
pub fn entry_sums(site: &Site, t: &TreeStore) -> Vec<RowSums> {
    let pidx: Vec<usize> = (0..site.lib.species.len() as u16).map(|s| site.pool_index(s).unwrap_or(0)).collect();
    let ff: Vec<f32> = site.lib.species.iter().map(|s| s.life.form_factor).collect();
    site.management.iter().map(|op| RowSums::over_where(t, site.pool.len(), &pidx, &ff, &|i| op.region.contains(t.x[i] as f64, t.y[i] as f64))).collect()
}

/// Each management entry's top height ([`top_height_by`]) over the trees of `t` in its area,
/// with the area's hectares, `stems[e]` the stems in entry `e`'s area over every part (the
/// ranks of a tiled run, `reduce`), in entry order.
///
/// Errors: those of `reduce`.
pub fn entry_top_heights(site: &Site, t: &TreeStore, stems: &[u64], reduce: &mut Reduce) -> crate::Result<Vec<f64>> {
    let mut out = Vec::with_capacity(site.management.len());
    for (e, op) in site.management.iter().enumerate() {
        let idx: Vec<usize> = (0..t.len()).filter(|&i| op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect();
        let d: Vec<f32> = idx.iter().map(|&i| t.dbh[i]).collect();
        let h: Vec<f32> = idx.iter().map(|&i| t.height[i]).collect();
        out.push(top_height_by(&d, &h, op.region.area_ha.max(1e-9), stems[e], reduce)?);
    }
    Ok(out)
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
    let h = entry_harvest(site, dead);
    (h.stems, h.volume_m3)
}

/// What the harvested trees of `dead` (cause harvest) were: stems ≥ 1.3 m, their basal area
/// (m², π/4 · DBH²) and the stem volume of all of them (m³, [`stem_volume_m3`]), summed in the
/// order given; no saplings.
pub fn entry_harvest(site: &Site, dead: &[super::trees::DeadTree]) -> EntryHarvest {
    let mut h = EntryHarvest::default();
    for d in dead.iter().filter(|d| d.cause == DeathCause::Harvest) {
        if d.height >= 1.3 {
            h.stems += 1;
            let m = d.dbh as f64 / 100.0;
            h.basal_area_m2 += std::f64::consts::FRAC_PI_4 * m * m;
        }
        h.volume_m3 += stem_volume_m3(site.lib.species[d.species as usize].life.form_factor, d.dbh, d.height);
    }
    h
}

/// The year's dead trees per pool species and cause, as exact sums ([`fixed`]) that add up over
/// the parts of a tiled run as [`RowSums`] do: stems (≥ 1.3 m) and stem volume
/// ([`stem_volume_m3`] at the size the tree died at; 0 below 7 cm DBH). Per species and cause
/// they make the deaths columns of `stand_table_species.csv` ([`species_rows`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeadSums {
    /// Stems (≥ 1.3 m) per pool species (pool order) and cause ([`DeathCause::ALL`] order).
    pub stems: Vec<[u64; super::trees::N_CAUSES]>,
    /// Stem volume (m³, fixed point) per pool species and cause.
    pub vol: Vec<[i128; super::trees::N_CAUSES]>,
}

impl DeadSums {
    /// The sums over `dead` (a year's dead trees, [`super::world::Scratch::dead`]) of `site`'s
    /// pool species; a tree of a species outside the pool is not counted.
    pub fn of(site: &Site, dead: &[super::trees::DeadTree]) -> DeadSums {
        let np = site.pool.len();
        let mut s = DeadSums { stems: vec![[0; super::trees::N_CAUSES]; np], vol: vec![[0; super::trees::N_CAUSES]; np] };
        for d in dead {
            let Some(p) = site.pool_index(d.species) else { continue };
            let c = d.cause.index();
            if is_stem(d.height) {
                s.stems[p][c] += 1;
            }
            s.vol[p][c] += fixed(stem_volume_m3(site.lib.species[d.species as usize].life.form_factor, d.dbh, d.height));
        }
        s
    }

    /// The sums as u64 words whose element-wise sums over parts are the words of the parts'
    /// sums ([`DeadSums::from_words`]): the counts, then each volume as 3 limbs.
    pub fn words(&self) -> Vec<u64> {
        let mut w: Vec<u64> = self.stems.iter().flatten().copied().collect();
        for v in self.vol.iter().flatten() {
            push_limbs(&mut w, *v);
        }
        w
    }

    /// Number of [`DeadSums::words`] for `np` pool species.
    pub fn n_words(np: usize) -> usize {
        4 * np * super::trees::N_CAUSES
    }

    /// The sums of [`DeadSums::words`] (summed over parts) for `np` pool species; `w` holds
    /// [`DeadSums::n_words`] words.
    pub fn from_words(w: &[u64], np: usize) -> DeadSums {
        const N: usize = super::trees::N_CAUSES;
        let mut s = DeadSums { stems: vec![[0; N]; np], vol: vec![[0; N]; np] };
        for p in 0..np {
            for c in 0..N {
                s.stems[p][c] = w[p * N + c];
                s.vol[p][c] = from_limbs(&w[np * N + 3 * (p * N + c)..]);
            }
        }
        s
    }
}

/// Each pool species' top height H100 (m; pool order): Assmann's h100 over the species' own
/// stems ([`h100_by`] with `a`, the site's hectares: the mean height of its `round(100 · a)`
/// thickest stems, all of them where it has fewer), `stems_sp` each species' stems over every
/// part (the ranks of a tiled run, `reduce`). 0 for a species without stems.
///
/// Errors: those of `reduce`.
pub fn species_top_heights(site: &Site, t: &TreeStore, stems_sp: &[u64], reduce: &mut Reduce) -> crate::Result<Vec<f64>> {
    let np = site.pool.len();
    let (d, h) = by_species(site, t);
    let a = site.area_ha.max(1e-9);
    (0..np).map(|p| h100_by(&d[p], &h[p], a, stems_sp.get(p).copied().unwrap_or(0), reduce)).collect()
}

/// The DBHs (cm) and heights (m) of the trees of `t` per pool species (pool order, store order).
fn by_species(site: &Site, t: &TreeStore) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let np = site.pool.len();
    let pidx: Vec<Option<usize>> = (0..site.lib.species.len() as u16).map(|s| site.pool_index(s)).collect();
    let (mut d, mut h) = (vec![Vec::new(); np], vec![Vec::new(); np]);
    for i in 0..t.len() {
        if let Some(p) = pidx[t.species[i] as usize] {
            d[p].push(t.dbh[i]);
            h[p].push(t.height[i]);
        }
    }
    (d, h)
}

/// Each pool species' top height over its own area (m; pool order,
/// [`SpeciesRow::top_height_own_area_m`]): [`h100_by`] over the species' stems with the
/// hectares `a · G_sp / G` (`a` the site's unmasked hectares, `G_sp` and `G` the species' and
/// the stand's basal area of `sums`, summed over every part: the ranks of a tiled run,
/// `reduce`). 0 for a species without stems or a stand without basal area.
///
/// Errors: those of `reduce`.
pub fn species_own_area_top_heights(site: &Site, t: &TreeStore, sums: &RowSums, reduce: &mut Reduce) -> crate::Result<Vec<f64>> {
    let np = site.pool.len();
    let (d, h) = by_species(site, t);
    let g = unfixed(sums.ba);
    (0..np)
        .map(|p| {
            let share = if g > 0.0 { unfixed(sums.ba_sp.get(p).copied().unwrap_or(0)) / g } else { 0.0 };
            let stems = sums.stems_sp.get(p).copied().unwrap_or(0);
            // every part takes the same rounds of h100_by (an all-sum each), with 0 stems too
            let v = h100_by(&d[p], &h[p], site.area_ha.max(1e-9) * share, stems, reduce)?;
            Ok(if share > 0.0 { v } else { 0.0 })
        })
        .collect()
}

/// The per-species rows of a year ([`SpeciesRow`], pool order) from the sums over the trees
/// standing at its end (`sums`), its dead trees (`dead`) and each species' top height (`h100`,
/// [`species_top_heights`]), per hectare of `site`'s unmasked area; and the natural deaths'
/// stem volume (m³/ha: every cause but harvest, [`StandRow::deaths_volume_m3_ha`]), summed
/// exactly over the species.
pub fn species_rows(site: &Site, sums: &RowSums, dead: &DeadSums, h100: &[f64], own_area_h100: &[f64]) -> (Vec<SpeciesRow>, f64) {
    let a = site.area_ha.max(1e-9);
    let harvest = DeathCause::Harvest.index();
    let mut natural: i128 = 0;
    let rows = (0..site.pool.len())
        .map(|p| {
            let n = sums.stems_sp[p];
            natural += dead.vol[p].iter().enumerate().filter(|(c, _)| *c != harvest).map(|(_, v)| *v).sum::<i128>();
            SpeciesRow {
                stems_ha: n as f64 / a,
                basal_area_m2_ha: unfixed(sums.ba_sp[p]) / a,
                qmd_cm: if n > 0 { (unfixed(sums.d2_sp[p]) / n as f64).sqrt() } else { 0.0 },
                top_height_m: h100.get(p).copied().unwrap_or(0.0),
                volume_m3_ha: unfixed(sums.vol_sp[p]) / a,
                top_height_own_area_m: own_area_h100.get(p).copied().unwrap_or(0.0),
                deaths_stems_ha: dead.stems[p].map(|v| v as f64 / a),
                deaths_volume_m3_ha: dead.vol[p].map(|v| unfixed(v) / a),
            }
        })
        .collect();
    (rows, unfixed(natural) / a)
}

/// Binary digits below the unit of the stand table's exact sums ([`RowSums`], [`top_height`]):
/// every tree's value (height m, DBH² cm², basal area m², volume m³) enters as the integer
/// nearest to `value · 2^64`, so sums are exact integers that do not depend on the order of
/// addition (threads, ranks, partial sums) and are rounded once, to the f64 nearest the exact
/// sum of the fixed-point values. 2⁻⁶⁴ (5.4 · 10⁻²⁰) is far below the printed precision
/// (10⁻³); heights of stems (≥ 1.3 m, f32: multiples of 2⁻²³) and DBH² of DBHs from 2⁻⁹ cm
/// (f32 squared: multiples of 2⁻⁶⁴ there) enter exactly. An i128 holds any sum of values below
/// 2²⁰ over 2⁴³ trees.
pub const FIXED_BITS: i32 = 64;

/// `v` (|v| below 2⁶³) in units of 2^-[`FIXED_BITS`], rounded to nearest, ties away from
/// zero: `(v · 2^64).round() as i128`, from the bits (a float-to-i128 conversion is a library
/// call, several times slower); 0 for NaN, saturated for larger values.
#[inline]
pub fn fixed(v: f64) -> i128 {
    let b = v.to_bits();
    let exp = ((b >> 52) & 0x7ff) as i32;
    if exp == 0 || v.is_nan() {
        // zero or subnormal (below 2^-1022): 0 at 2^-64
        return 0;
    }
    let m = (b & ((1u64 << 52) - 1)) | (1u64 << 52);
    // |v| = m · 2^(exp - 1075), so |v| · 2^64 = m · 2^sh
    let sh = exp - 1075 + FIXED_BITS;
    let r: i128 = if sh >= 0 {
        if sh > 127 - 53 {
            i128::MAX
        } else {
            (m as i128) << sh
        }
    } else if -sh <= 64 {
        (((m >> (-sh - 1)) + 1) >> 1) as i128
    } else {
        0
    };
    if b >> 63 == 1 {
        -r
    } else {
        r
    }
}

/// The f64 nearest the fixed-point sum `s` ([`fixed`]).
#[inline]
pub fn unfixed(s: i128) -> f64 {
    s as f64 * 2f64.powi(-FIXED_BITS)
}

/// Bits per limb when an i128 travels as u64 words ([`RowSums::words`]): 3 limbs of 43 bits
/// (129 ≥ 128), so the limbs of up to 2²¹ ranks add up in a u64 without overflow.
const LIMB_BITS: u32 = 43;

/// `v` as 3 limbs of [`LIMB_BITS`] (two's complement, low limb first).
fn push_limbs(out: &mut Vec<u64>, v: i128) {
    let u = v as u128;
    for j in 0..3 {
        out.push(((u >> (LIMB_BITS * j)) & ((1u128 << LIMB_BITS) - 1)) as u64);
    }
}

/// The i128 whose limbs, summed over the parts, are `w[..3]` (the wrapping sum of the parts'
/// values: exact when the sum fits).
fn from_limbs(w: &[u64]) -> i128 {
    w.iter().take(3).enumerate().fold(0u128, |s, (j, &l)| s.wrapping_add((l as u128).wrapping_shl(LIMB_BITS * j as u32))) as i128
}

/// The sums of a stand-table row over trees, exact ([`FIXED_BITS`]): the same integers
/// whatever the order, so the sums of a tiled run's parts add up to one process's bit for bit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowSums {
    /// Trees (every height).
    pub trees: u64,
    /// Stems (≥ 1.3 m).
    pub stems: u64,
    /// Stems with DBH ≥ 7 cm.
    pub stems_7: u64,
    /// Basal area of the stems (m², fixed point).
    pub ba: i128,
    /// Heights of the stems (m, fixed point).
    pub height: i128,
    /// DBH² of the stems (cm², fixed point).
    pub d2: i128,
    /// DBH² of the stems with DBH ≥ 7 cm (cm², fixed point).
    pub d2_7: i128,
    /// Stem volume ([`stem_volume_m3`], m³, fixed point).
    pub vol: i128,
    /// Basal area of the stems per pool species (m², fixed point).
    pub ba_sp: Vec<i128>,
    /// Stems per pool species.
    pub stems_sp: Vec<u64>,
    /// DBH² of the stems per pool species (cm², fixed point).
    pub d2_sp: Vec<i128>,
    /// Stem volume per pool species (m³, fixed point).
    pub vol_sp: Vec<i128>,
}

impl RowSums {
    /// Zero sums for `np` pool species.
    pub fn zero(np: usize) -> RowSums {
        RowSums { trees: 0, stems: 0, stems_7: 0, ba: 0, height: 0, d2: 0, d2_7: 0, vol: 0, ba_sp: vec![0; np], stems_sp: vec![0; np], d2_sp: vec![0; np], vol_sp: vec![0; np] }
    }

    /// The sums over the trees `t` of `site` (in parallel: the integers do not depend on the
    /// order).
    pub fn of(site: &Site, t: &TreeStore) -> RowSums {
        let pidx: Vec<usize> = (0..site.lib.species.len() as u16).map(|s| site.pool_index(s).unwrap_or(0)).collect();
        let ff: Vec<f32> = site.lib.species.iter().map(|s| s.life.form_factor).collect();
        RowSums::over(t, site.pool.len(), &pidx, &ff)
    }

    /// [`RowSums::of`] with `np` pool species, each species' pool index `pidx` and form factor
    /// `ff`: chunks of trees summed into local integers, the chunks' sums added.
    pub fn over(t: &TreeStore, np: usize, pidx: &[usize], ff: &[f32]) -> RowSums {
        RowSums::over_where(t, np, pidx, ff, &|_| true)
    }

    /// [`RowSums::over`] over the trees `i` for which `keep(i)` holds (a management entry's
    /// area: [`entry_sums`]); `trees` counts those kept.
    pub fn over_where(t: &TreeStore, np: usize, pidx: &[usize], ff: &[f32], keep: &(dyn Fn(usize) -> bool + Sync)) -> RowSums {
        const CHUNK: usize = 1 << 14;
        (0..t.len().div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut s = RowSums::zero(np);
                let (mut stems, mut stems_7) = (0u64, 0u64);
                let (mut ba, mut height, mut d2, mut d2_7, mut vol) = (0i128, 0i128, 0i128, 0i128, 0i128);
                let range = c * CHUNK..((c + 1) * CHUNK).min(t.len());
                let mut trees = 0u64;
                for i in range {
                    if !keep(i) {
                        continue;
                    }
                    trees += 1;
                    let h = t.height[i];
                    if h < 1.3 {
                        continue;
                    }
                    let d = t.dbh[i];
                    stems += 1;
                    let b = fixed(t.basal_area_m2(i));
                    ba += b;
                    height += fixed(h as f64);
                    let q = fixed((d as f64) * (d as f64));
                    d2 += q;
                    let p = pidx[t.species[i] as usize];
                    if d >= 7.0 {
                        stems_7 += 1;
                        d2_7 += q;
                        let v = fixed(stem_volume_m3(ff[t.species[i] as usize], d, h));
                        vol += v;
                        s.vol_sp[p] += v;
                    }
                    s.ba_sp[p] += b;
                    s.stems_sp[p] += 1;
                    s.d2_sp[p] += q;
                }
                (s.trees, s.stems, s.stems_7, s.ba, s.height, s.d2, s.d2_7, s.vol) = (trees, stems, stems_7, ba, height, d2, d2_7, vol);
                s
            })
            .reduce(|| RowSums::zero(np), |a, b| a.plus(&b))
    }

    /// `self` and `o` added.
    pub fn plus(mut self, o: &RowSums) -> RowSums {
        self.trees += o.trees;
        self.stems += o.stems;
        self.stems_7 += o.stems_7;
        self.ba += o.ba;
        self.height += o.height;
        self.d2 += o.d2;
        self.d2_7 += o.d2_7;
        self.vol += o.vol;
        self.ba_sp.iter_mut().zip(&o.ba_sp).for_each(|(a, b)| *a += b);
        self.stems_sp.iter_mut().zip(&o.stems_sp).for_each(|(a, b)| *a += b);
        self.d2_sp.iter_mut().zip(&o.d2_sp).for_each(|(a, b)| *a += b);
        self.vol_sp.iter_mut().zip(&o.vol_sp).for_each(|(a, b)| *a += b);
        self
    }

    /// The sums as u64 words whose element-wise sums over parts are the words of the parts'
    /// sums ([`RowSums::from_words`]): counts as they are, fixed-point sums as 3 limbs.
    pub fn words(&self) -> Vec<u64> {
        let mut w = vec![self.trees, self.stems, self.stems_7];
        w.extend(&self.stems_sp);
        for v in [self.ba, self.height, self.d2, self.d2_7, self.vol].iter().chain(&self.ba_sp).chain(&self.d2_sp).chain(&self.vol_sp) {
            push_limbs(&mut w, *v);
        }
        w
    }

    /// Number of [`RowSums::words`] for `np` pool species.
    pub fn n_words(np: usize) -> usize {
        3 + np + 3 * (5 + 3 * np)
    }

    /// The sums of [`RowSums::words`] (summed over parts) for `np` pool species; `w` holds
    /// [`RowSums::n_words`] words.
    pub fn from_words(w: &[u64], np: usize) -> RowSums {
        let l = |k: usize| from_limbs(&w[3 + np + 3 * k..]);
        RowSums {
            trees: w[0],
            stems: w[1],
            stems_7: w[2],
            stems_sp: w[3..3 + np].to_vec(),
            ba: l(0),
            height: l(1),
            d2: l(2),
            d2_7: l(3),
            vol: l(4),
            ba_sp: (0..np).map(|p| l(5 + p)).collect(),
            d2_sp: (0..np).map(|p| l(5 + np + p)).collect(),
            vol_sp: (0..np).map(|p| l(5 + 2 * np + p)).collect(),
        }
    }
}

/// Whether a tree of height `h` counts as a stem (≥ 1.3 m; NaN counts, as in [`RowSums`]).
#[inline]
fn is_stem(h: f32) -> bool {
    h.partial_cmp(&1.3) != Some(std::cmp::Ordering::Less)
}

/// Widths (bits) of the digits [`h100_by`] selects by, from the top of the 64-bit key
/// (DBH's [`total_key`], then height's): histograms of 1,024–2,048 counts per round.
const DIGITS: [u32; 6] = [10, 11, 11, 11, 11, 10];

/// Top height (m): Assmann's h100, the mean height of the `round(100 · a)` largest-DBH trees of
/// at least 1.3 m (ties by height; trees of equal DBH and height are interchangeable), taken over
/// the stand's upper layer, the stems at least [`UPPER_LAYER_SHARE`] (two thirds) of the top
/// height tall (the IUFRO tree classes' upper layer, Leibundgut 1958, as in Assmann 1970 and
/// Pretzsch 2009, §2): all of them where fewer than `round(100 · a)` stand. So a stand of 70
/// trees/ha of 38 m over ingrowth of 7–11 m has a top height of 38 m, not the mean of the 70
/// and 30 ingrowth stems (found by a trial: 34.6 → 29.0 m in an old thinned beech stand whose
/// overstorey grew). In a stand whose 100 thickest per ha are all in the upper layer (even-aged,
/// one layer) it is plain h100. Found by fixed point: h100 over all stems, then over the stems of
/// at least two thirds of it, until the layer holds the same stems (at most
/// [`UPPER_LAYER_ROUNDS`] rounds). The heights summed exactly ([`fixed`]), so any selection of
/// the same trees gives the same bits. One process ([`alone`]); [`top_height_by`] over the
/// parts of a stand. 0 without stems.
pub(crate) fn top_height(dbh: &[f32], height: &[f32], a: f64) -> f64 {
    let stems = height.iter().filter(|&&h| is_stem(h)).count() as u64;
    top_height_by(dbh, height, a, stems, &mut alone).unwrap_or(0.0)
}

/// Share of the top height above which a stem is of the upper layer that the top height is
/// taken over: two thirds (IUFRO tree classes, Leibundgut 1958; Pretzsch 2009, §2).
pub const UPPER_LAYER_SHARE: f64 = 2.0 / 3.0;

/// Most rounds of [`top_height_by`]'s fixed point (one usually; two with a lower layer).
pub const UPPER_LAYER_ROUNDS: usize = 8;

/// [`top_height`] over a stand in parts (the ranks of a tiled run), each passing its own trees
/// (`dbh`, `height`) and `stems`, the stems (≥ 1.3 m) of the whole stand: each round of the
/// fixed point is an h100 ([`h100_by`]) over the stems at least [`UPPER_LAYER_SHARE`] of the
/// last round's result tall, their count summed over the parts (`reduce`); every part sees the
/// same sums, so all take the same rounds.
///
/// Errors: those of `reduce`.
pub fn top_height_by(dbh: &[f32], height: &[f32], a: f64, stems: u64, reduce: &mut Reduce) -> crate::Result<f64> {
    let mut h = h100_by(dbh, height, a, stems, reduce)?;
    let mut layer = stems;
    for _ in 0..UPPER_LAYER_ROUNDS {
        let low = (UPPER_LAYER_SHARE * h) as f32;
        let keep: Vec<usize> = (0..dbh.len()).filter(|&i| is_stem(height[i]) && height[i] >= low).collect();
        let n = reduce(vec![keep.len() as u64])?[0];
        if n == layer || n == 0 {
            break;
        }
        let d: Vec<f32> = keep.iter().map(|&i| dbh[i]).collect();
        let hh: Vec<f32> = keep.iter().map(|&i| height[i]).collect();
        h = h100_by(&d, &hh, a, n, reduce)?;
        layer = n;
    }
    Ok(h)
}

/// Assmann's h100 over a stand in parts (the ranks of a tiled run), each passing its own trees
/// (`dbh`, `height`) and `stems`, the stems (≥ 1.3 m) of the whole stand; nothing per tree is
/// passed: the `k` thickest are found by a radix selection over the 64-bit key (DBH, height),
/// descending, digit by digit ([`DIGITS`]): every part counts its candidates per digit value,
/// the counts are summed (`reduce`), and every part keeps the candidates in the digit value
/// where the `k`-th tree falls, adding the heights of those above it to its partial sum. It
/// stops when the candidates left are all taken, or when the whole key is fixed (trees of the
/// same DBH and height: as many as are still needed, each of that height). Then the partial
/// sums are summed. At most 7 reductions, usually 3–4.
///
/// Errors: those of `reduce`.
pub fn h100_by(dbh: &[f32], height: &[f32], a: f64, stems: u64, reduce: &mut Reduce) -> crate::Result<f64> {
    if stems == 0 {
        return Ok(0.0);
    }
    let k = ((100.0 * a).round() as u64).clamp(1, stems);
    let mut cand: Vec<u64> = (0..dbh.len())
        .into_par_iter()
        .with_min_len(1 << 14)
        .filter(|&i| is_stem(height[i]))
        .map(|i| (total_key(dbh[i]) as u64) << 32 | total_key(height[i]) as u64)
        .collect();
    let h_of = |key: u64| fixed(from_total_key(key as u32) as f64);
    let (mut need, mut count) = (k, stems);
    let (mut shift, mut prefix) = (64u32, 0u64);
    let mut sum: i128 = 0;
    let mut extra: i128 = 0;
    for &w in DIGITS.iter() {
        if need == count {
            break;
        }
        shift -= w;
        let mask = (1u64 << w) - 1;
        let bins = 1usize << w;
        let hist = cand
            .par_chunks(1 << 16)
            .map(|c| {
                let mut h = vec![0u64; bins];
                for &key in c {
                    h[((key >> shift) & mask) as usize] += 1;
                }
                h
            })
            .reduce(|| vec![0u64; bins], |mut x, y| {
                x.iter_mut().zip(&y).for_each(|(a, b)| *a = a.wrapping_add(*b));
                x
            });
        let hist = reduce(hist)?;
        let mut acc = 0u64;
        let mut pick = 0u64;
        for b in (0..bins).rev() {
            if acc + hist[b] >= need {
                pick = b as u64;
                break;
            }
            acc += hist[b];
        }
        sum += cand.par_iter().with_min_len(1 << 14).filter(|&&key| (key >> shift) & mask > pick).map(|&key| h_of(key)).sum::<i128>();
        cand = cand.into_par_iter().with_min_len(1 << 14).filter(|&key| (key >> shift) & mask == pick).collect();
        prefix |= pick << shift;
        need -= acc;
        count = hist[pick as usize];
        if shift == 0 && need < count {
            // the whole key fixed: `count` trees of one DBH and height, `need` of them taken
            extra = need as i128 * h_of(prefix);
            cand.clear();
            need = 0;
            count = 0;
        }
    }
    debug_assert_eq!(need, count);
    sum += cand.iter().map(|&key| h_of(key)).sum::<i128>();
    let mut w = Vec::with_capacity(3);
    push_limbs(&mut w, sum);
    let total = from_limbs(&reduce(w)?) + extra;
    Ok(unfixed(total) / k as f64)
}

/// Fixed-point unit of [`drought_sums`]: a drought index of 1 is `2^24`.
pub const DROUGHT_ONE: f64 = (1u64 << 24) as f64;

/// The stand table's drought-index sums of `site` in `year`: the unmasked light cells this world
/// steps (`site.light_site`: every light cell in one process, a tile's own) and the sum of
/// their site cells' drought indices ([`crate::climate::water::WaterClimate::cell_drought_index`]
/// under the year's temperature offset and precipitation factor), each rounded to
/// [`DROUGHT_ONE`]: integers, so the parts of a tiled run add to one process's sums exactly.
/// Under a constant climate the sums are the base climate's, computed once
/// (`site.drought_base`). The row's index is `sum / count / DROUGHT_ONE`.
pub fn drought_sums(site: &Site, year: u32) -> (u64, u64) {
    let of = |dt: f64, pf: f64| {
        let c = &site.conditions;
        let lat = c.geo.latitude_deg;
        let water = &site.climate_change.water;
        let di: Vec<f32> = c
            .mask
            .data
            .par_iter()
            .zip(c.temperature_c.data.par_iter())
            .zip(c.twi.data.par_iter())
            .with_min_len(1024)
            .map(|((m, t), twi)| if *m { water.cell_drought_index(*t as f64, *twi as f64, lat, dt, pf) as f32 } else { 0.0 })
            .collect();
        let (mut n, mut sum) = (0u64, 0u64);
        for &k in site.light_site.iter().filter(|&&k| k != u32::MAX) {
            n += 1;
            sum += (di[c.held(k as usize)] as f64 * DROUGHT_ONE).round() as u64;
        }
        (n, sum)
    };
    if site.climate_change.is_active() {
        let (dt, pf) = site.climate_change.of_year(year);
        of(dt, pf)
    } else {
        *site.drought_base.get_or_init(|| of(0.0, 1.0))
    }
}

/// The site-mean drought index of [`drought_sums`]' `(count, sum)` (0 without a cell).
pub fn drought_mean((n, sum): (u64, u64)) -> f64 {
    if n == 0 {
        0.0
    } else {
        sum as f64 / n as f64 / DROUGHT_ONE
    }
}

/// Computes the stand-table row of the world's current state (deaths from `w.scratch.dead`):
/// exact sums ([`RowSums`]), the top height ([`top_height`]) and the per-species rows
/// ([`species_rows`]). At year 0 (a world as [`World::new`] starts it) it is the state after
/// the `[[start]]` plantings, before any growth.
pub fn stand_row(w: &World) -> StandRow {
    let mut deaths = [0u64; super::trees::N_CAUSES];
    for d in &w.scratch.dead {
        deaths[d.cause.index()] += 1;
    }
    let t = &w.stand.trees;
    let sums = RowSums::of(&w.site, t);
    let h100 = top_height_by(&t.dbh, &t.height, w.site.area_ha.max(1e-9), sums.stems, &mut alone).unwrap_or(0.0);
    let mut row = row_of(&w.site, w.stand.year, &sums, h100, w.stand.cohorts.total_stems(), deaths, w.scratch.regen_year, harvest_sums(&w.site, &w.scratch.dead));
    row.drought_index = drought_mean(drought_sums(&w.site, w.stand.year));
    let hs = species_top_heights(&w.site, t, &sums.stems_sp, &mut alone).unwrap_or_else(|_| vec![0.0; sums.stems_sp.len()]);
    let ho = species_own_area_top_heights(&w.site, t, &sums, &mut alone).unwrap_or_else(|_| vec![0.0; sums.stems_sp.len()]);
    (row.species, row.deaths_volume_m3_ha) = species_rows(&w.site, &sums, &DeadSums::of(&w.site, &w.scratch.dead), &hs, &ho);
    // (no management table row at year 0: nothing was managed before the first year)
    if !w.site.management.is_empty() && w.stand.year > 0 {
        let es = entry_sums(&w.site, t);
        let stems: Vec<u64> = es.iter().map(|s| s.stems).collect();
        let h = entry_top_heights(&w.site, t, &stems, &mut alone).unwrap_or_else(|_| vec![0.0; stems.len()]);
        row.management = entry_rows(&w.site, &es, &h, &w.scratch.entry_harvest);
    }
    row
}

/// The stand-table row of `site` in `year` from the sums over its trees ([`RowSums`]), the top
/// height (m, [`top_height_by`]), the regeneration layer's stems, this year's deaths by cause
/// and regeneration counts, and the year's harvest (stems ≥ 1.3 m, volume m³:
/// [`harvest_sums`]) ([`stand_row`] on a world; a tiled run's ranks sum these,
/// `sim::tiles`). The year's temperature offset and precipitation factor come from the site's
/// climate change; the drought index is left 0 for the caller ([`drought_sums`], summed over a
/// tiled run's parts).
#[allow(clippy::too_many_arguments)]
pub fn row_of(site: &Site, year: u32, s: &RowSums, h100: f64, regeneration_stems: u64, deaths: [u64; super::trees::N_CAUSES], regen_year: RegenYear, harvest: (u64, f64)) -> StandRow {
    let w = site;
    let a = w.area_ha.max(1e-9);
    let (n, n7) = (s.stems, s.stems_7);
    let ns = s.trees - s.stems;
    let (ba, hs, d2, d27, vol) = (unfixed(s.ba), unfixed(s.height), unfixed(s.d2), unfixed(s.d2_7), unfixed(s.vol));
    let sba: Vec<f64> = s.ba_sp.iter().map(|&v| unfixed(v)).collect();
    let sn: Vec<f64> = s.stems_sp.iter().map(|&v| v as f64).collect();
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
        drought_index: 0.0,
        management: Vec::new(),
        deaths_volume_m3_ha: 0.0,
        species: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::tiles::{LocalTransport, Transport};

    /// DBHs and heights with ties (equal DBH; equal DBH and height) and saplings below 1.3 m.
    fn trees(n: usize) -> (Vec<f32>, Vec<f32>) {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut d, mut h) = (Vec::new(), Vec::new());
        for i in 0..n {
            let (a, b) = (r(), r());
            let dbh = if i % 7 == 0 { 30.0 } else { (a * 60.0 * 64.0).round() / 64.0 };
            let height = if i % 11 == 0 { 25.5 } else if i % 13 == 0 { 0.9 } else { 1.3 + b * 35.0 };
            d.push(dbh);
            h.push(height);
        }
        (d, h)
    }

    /// The mean height of the k thickest (ties by height), by a sort.
    fn by_sort(d: &[f32], h: &[f32], a: f64) -> f64 {
        let mut t: Vec<(f32, f32)> = d.iter().zip(h).filter(|(_, h)| **h >= 1.3).map(|(d, h)| (*d, *h)).collect();
        if t.is_empty() {
            return 0.0;
        }
        t.sort_by(|x, y| y.0.total_cmp(&x.0).then(y.1.total_cmp(&x.1)));
        let k = ((100.0 * a).round() as usize).clamp(1, t.len());
        unfixed(t[..k].iter().map(|x| fixed(x.1 as f64)).sum()) / k as f64
    }

    /// [`top_height`] by sorts: h100 ([`by_sort`]) over the stems at least two thirds of the
    /// last result tall, until their count stays.
    fn layered_by_sort(d: &[f32], h: &[f32], a: f64) -> f64 {
        let mut top = by_sort(d, h, a);
        let mut layer = h.iter().filter(|h| **h >= 1.3).count();
        for _ in 0..UPPER_LAYER_ROUNDS {
            let low = (UPPER_LAYER_SHARE * top) as f32;
            let keep: Vec<usize> = (0..d.len()).filter(|&i| h[i] >= 1.3 && h[i] >= low).collect();
            if keep.len() == layer || keep.is_empty() {
                break;
            }
            let kd: Vec<f32> = keep.iter().map(|&i| d[i]).collect();
            let kh: Vec<f32> = keep.iter().map(|&i| h[i]).collect();
            top = by_sort(&kd, &kh, a);
            layer = keep.len();
        }
        top
    }

    /// A stand of 70 trees/ha of 50–60 cm and 36–40 m over 500 stems/ha of ingrowth of
    /// 7–10 cm and 7–11 m (1 ha, 2 ha): its top height is the mean height of the 70, not of
    /// the 100 thickest (70 big and 30 ingrowth: about 29 m); with 150 big trees/ha it is
    /// the h100 of the big trees.
    #[test]
    fn top_height_of_a_thin_overstorey_over_ingrowth_is_the_overstoreys() {
        for a in [1.0, 2.0] {
            for n_big in [70usize, 150] {
                let (mut d, mut h) = (Vec::new(), Vec::new());
                let nb = (n_big as f64 * a) as usize;
                for i in 0..nb {
                    d.push(50.0 + 10.0 * (i as f32 / nb as f32));
                    h.push(36.0 + 4.0 * ((i * 7 % nb) as f32 / nb as f32));
                }
                let ni = (500.0 * a) as usize;
                for i in 0..ni {
                    d.push(7.0 + 3.0 * (i as f32 / ni as f32));
                    h.push(7.0 + 4.0 * ((i * 13 % ni) as f32 / ni as f32));
                }
                let got = top_height(&d, &h, a);
                let want = by_sort(&d[..nb], &h[..nb], a);
                assert_eq!(got.to_bits(), want.to_bits(), "a {a}, {n_big} big/ha: {got} vs the big trees' h100 {want}");
                assert!(got > 37.0 && got < 39.0, "{got}");
                if n_big == 70 {
                    let plain = by_sort(&d, &h, a);
                    assert!(plain < 32.0, "plain h100 {plain} takes in the ingrowth");
                    // the part of the stand with a third of the stems each still gives the same
                    let got3: Vec<f64> = std::thread::scope(|s| {
                        let hs: Vec<_> = LocalTransport::group(3)
                            .into_iter()
                            .map(|mut t| {
                                let (d, h) = (&d, &h);
                                s.spawn(move || {
                                    let me = t.rank();
                                    let idx: Vec<usize> = (0..d.len()).filter(|i| i % 3 == me).collect();
                                    let pd: Vec<f32> = idx.iter().map(|&i| d[i]).collect();
                                    let ph: Vec<f32> = idx.iter().map(|&i| h[i]).collect();
                                    top_height_by(&pd, &ph, a, d.len() as u64, &mut |v| t.all_sum(v)).unwrap()
                                })
                            })
                            .collect();
                        hs.into_iter().map(|h| h.join().unwrap()).collect()
                    });
                    assert!(got3.iter().all(|v| v.to_bits() == got.to_bits()), "{got3:?} vs {got}");
                }
            }
        }
    }

    #[test]
    fn top_height_over_parts_is_one_stands() {
        let (d, h) = trees(5_000);
        let stems = h.iter().filter(|h| **h >= 1.3).count() as u64;
        // k from 1 to beyond the stems, through the tie of 30 cm
        for a in [0.01, 0.5, 3.0, 7.77, 20.0, 44.0, 100.0] {
            let one = top_height(&d, &h, a);
            assert_eq!(one.to_bits(), layered_by_sort(&d, &h, a).to_bits(), "a = {a}");
            for parts in [2usize, 3] {
                let got: Vec<f64> = std::thread::scope(|s| {
                    let hs: Vec<_> = LocalTransport::group(parts)
                        .into_iter()
                        .map(|mut t| {
                            let (d, h) = (&d, &h);
                            s.spawn(move || {
                                let me = t.rank();
                                let idx: Vec<usize> = (0..d.len()).filter(|i| i % parts == me).collect();
                                let pd: Vec<f32> = idx.iter().map(|&i| d[i]).collect();
                                let ph: Vec<f32> = idx.iter().map(|&i| h[i]).collect();
                                top_height_by(&pd, &ph, a, stems, &mut |v| t.all_sum(v)).unwrap()
                            })
                        })
                        .collect();
                    hs.into_iter().map(|h| h.join().unwrap()).collect()
                });
                assert!(got.iter().all(|v| v.to_bits() == one.to_bits()), "a = {a}, {parts} parts: {got:?} vs {one}");
            }
        }
        assert_eq!(top_height(&[], &[], 1.0), 0.0);
    }

    #[test]
    fn fixed_is_the_rounded_product() {
        let (d, h) = trees(2_000);
        let mut vals: Vec<f64> = d.iter().chain(&h).flat_map(|&x| [x as f64, (x as f64).powi(2), std::f64::consts::FRAC_PI_4 * (x as f64 / 100.0).powi(2), x as f64 * 1e-9]).collect();
        vals.extend([0.0, 1.0, 0.5, 2f64.powi(-64), 2f64.powi(-65), 1.5 * 2f64.powi(-65), 2f64.powi(-66), 2f64.powi(40) + 0.25, -3.75, 1e-300, 123456.789]);
        for v in vals {
            assert_eq!(fixed(v), (v * 2f64.powi(64)).round() as i128, "{v:e}");
        }
        assert_eq!(fixed(f64::NAN), 0);
    }

    #[test]
    fn limbs_add_up_to_the_sum() {
        let vals = [0i128, 1, (1 << 100) + 12345, i64::MAX as i128 * 3, 7 << 80];
        let mut total = vec![0u64; 3];
        for v in vals {
            let mut w = Vec::new();
            push_limbs(&mut w, v);
            assert_eq!(from_limbs(&w), v);
            total.iter_mut().zip(&w).for_each(|(a, b)| *a += b);
        }
        assert_eq!(from_limbs(&total), vals.iter().sum::<i128>());
    }
}
