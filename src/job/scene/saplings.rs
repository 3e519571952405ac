//! The regeneration layer's sapling cohorts as clumps of small tree instances.

use super::*;

/// One cohort of the regeneration layer (saplings below the recruitment height,
/// [`crate::sim::cohorts`]) as the pictures need it: from the in-memory [`World`]
/// ([`saplings_from_world`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaplingCohort<'a> {
    /// Light cell index (stable across years: keys the cohort's instances).
    pub cell: u32,
    /// Species id.
    pub species: &'a str,
    /// Light-cell centre, easting (m).
    pub x_m: f64,
    /// Light-cell centre, northing (m).
    pub y_m: f64,
    /// Light-cell side (m), > 0.
    pub cell_m: f64,
    /// Stems of the cohort in the cell.
    pub stems: u32,
    /// Mean height (m), below 4 m.
    pub height_m: f32,
}

/// The cohorts of `w`'s regeneration layer as [`SaplingCohort`]s, in (cell, pool) order.
pub fn saplings_from_world(w: &World) -> Vec<SaplingCohort<'_>> {
    let c = &w.stand.cohorts;
    (0..c.len())
        .filter_map(|i| {
            let sp = *w.site.pool.get(c.pool[i] as usize)?;
            let (x, y) = w.site.light.centre(c.cell[i] as usize);
            Some(SaplingCohort { cell: c.cell[i], species: w.site.lib.species[sp as usize].id.as_str(), x_m: x, y_m: y, cell_m: w.site.light.cell_m, stems: c.stems[i], height_m: c.height[i] })
        })
        .collect()
}

/// A uniform number in 0..1 from a key (SplitMix64 finaliser, [`crate::rng::mix64`]).
pub(super) fn unit(key: u64) -> f64 {
    (crate::rng::mix64(key) >> 11) as f64 / (1u64 << 53) as f64
}

/// The rows of a regeneration-layer file ([`crate::job::inventory::read_regeneration`]) as
/// [`SaplingCohort`]s; the light-cell side comes from `stems / stems_per_ha` (cells without a
/// positive density are skipped).
pub fn saplings_from_rows(rows: &[crate::job::inventory::RegenRow]) -> Vec<SaplingCohort<'_>> {
    rows.iter()
        .filter(|r| r.stems > 0 && r.stems_per_ha > 0.0)
        .map(|r| SaplingCohort { cell: r.cell, species: r.species.as_str(), x_m: r.x_m, y_m: r.y_m, cell_m: (r.stems as f64 * 10_000.0 / r.stems_per_ha).sqrt(), stems: r.stems, height_m: r.height_m })
        .collect()
}

/// Saplings lower than this (m) are not drawn (they stand in the grass).
pub const MIN_SAPLING_HEIGHT_M: f32 = 0.5;
/// Most instances drawn per cohort; denser cohorts get wider clumps instead of more instances.
pub const MAX_SAPLINGS_PER_COHORT: u32 = 3;
/// Bit set in the ids of sapling instances (tree ids never reach it), so that a timelapse
/// matches a cohort's saplings across snapshots and never with a tree.
pub const SAPLING_ID_BIT: u64 = 1 << 63;

/// Plan cover (0..1) of a light cell of `area_m2` by `stems` crowns of radius `r` (m) placed at
/// random: `1 − exp(−N π r² / A)` (Poisson (Boolean) model of overlapping discs; proportional
/// to the stem density, `N π r² / A`, while crowns rarely overlap).
pub fn sapling_cover(stems: u32, r: f32, area_m2: f64) -> f64 {
    if area_m2 <= 0.0 {
        return 0.0;
    }
    1.0 - (-(stems as f64) * std::f64::consts::PI * (r as f64).powi(2) / area_m2).exp()
}

/// The sapling form of a cohort's stems of `sp`, `height_m` tall: (crown base m, crown radius m)
/// of [`crate::structure::forest_form::sapling_blend`] in full (a cohort is below the
/// recruitment height, 4 m: the form of 2–10-year trees), the form `sylva tree grow` gives a
/// stand-grown sapling.
pub fn sapling_form(sp: &Species, height_m: f32) -> (f32, f32) {
    crate::structure::forest_form::sapling_blend(sp, 0.0, height_m, 0.0, 0.0)
}

/// The drawn saplings of one cohort: `(count, crown radius m)`. The sapling form's crown radius
/// at the cohort's height ([`sapling_form`], as `sylva tree grow`; until round 35 the
/// open-grown crown radius) gives the cover ([`sapling_cover`]); the instances
/// share the covered area `cover · A` equally, as many as the stems up to
/// [`MAX_SAPLINGS_PER_COHORT`] with crowns no wider than `1.0 · h + 0.3` m (a clump of a few
/// stems), so the drawn plan area is the cohort's cover while it fits, and proportional to the
/// stem density in sparse cohorts. `(0, 0)` below [`MIN_SAPLING_HEIGHT_M`] or without stems.
pub fn sapling_clumps(sp: &Species, stems: u32, height_m: f32, cell_m: f64) -> (u32, f32) {
    if stems == 0 || !(height_m >= MIN_SAPLING_HEIGHT_M) {
        return (0, 0.0);
    }
    let r = sapling_form(sp, height_m).1.max(0.05);
    let area = cell_m * cell_m;
    let covered = sapling_cover(stems, r, area) * area;
    let r_max = (1.0 * height_m + 0.3).max(r);
    let one = std::f64::consts::PI * (r as f64).powi(2);
    let want = (covered / one).ceil().max(1.0) as u32;
    let n = want.min(stems).min(MAX_SAPLINGS_PER_COHORT).max(1);
    let ri = ((covered / (n as f64 * std::f64::consts::PI)).sqrt() as f32).min(r_max).max(0.05);
    (n, ri)
}

/// Render instances of the saplings of `cohorts` (the regeneration layer) for `season`: per
/// cohort [`sapling_clumps`] instances of the species' prototype scaled to the cohort's height
/// (± 15 %), the clump's crown radius and the sapling form's crown base ([`sapling_form`]),
/// scattered in the light cell by a hash of the cell,
/// species and index (deterministic, stable across snapshots; ids carry [`SAPLING_ID_BIT`]).
/// Cohorts under a drawn canopy (`canopy`, [`visible_with_canopy`]) lower than
/// [`UNDERSTORY_FRACTION`] of it are hidden, as understory trees are.
pub fn sapling_instances(cohorts: &[SaplingCohort], canopy: Option<&CanopyHeights>, library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    let mut out = Vec::new();
    for c in cohorts {
        let Some(sid) = library.find(c.species) else { continue };
        let sp = &library.species[sid as usize];
        if canopy.is_some_and(|k| c.height_m < UNDERSTORY_FRACTION * k.at(c.x_m, c.y_m)) {
            continue;
        }
        let (n, r) = sapling_clumps(sp, c.stems, c.height_m, c.cell_m);
        let (col, amount) = foliage(sp, season);
        for k in 0..n {
            let id = SAPLING_ID_BIT | ((c.cell as u64) << 16) | ((sid as u64 & 0xfff) << 4) | k as u64;
            let jx = (unit(id) - 0.5) * c.cell_m;
            let jy = (unit(id ^ 0x5bd1_e995) - 0.5) * c.cell_m;
            let (x, y) = (c.x_m + jx, c.y_m + jy);
            let h = c.height_m * (0.85 + 0.3 * unit(id ^ 0x27d4_eb2d) as f32);
            let z = cond.elevation_at(x, y);
            let mut inst = TreeInstance::new(id, [x as f32, y as f32, z], h, r, sid as u32, col);
            inst.leaf_amount = amount;
            // live branches nearly to the ground, as the sapling form has them
            inst.crown_base = (sapling_form(sp, h).0 / h).clamp(0.05, 0.85);
            out.push(inst);
        }
    }
    out
}

/// [`instances`] of the trees of `rows` and, below them, the saplings of `cohorts`
/// ([`sapling_instances`], hidden under the drawn canopy): what a picture of a snapshot draws.
pub fn instances_with_saplings(rows: &[Plant], cohorts: &[SaplingCohort], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    let (keep, canopy) = visible_with_canopy(rows, cond.extent_m());
    let mut out = tree_instances(rows, &keep, library, cond, season);
    out.extend(sapling_instances(cohorts, Some(&canopy), library, cond, season));
    out
}
