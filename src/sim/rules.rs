//! The rules of a tree's life that more than one phase applies, each written once: the crown
//! base and DBH a tree starts with (planted at the start, recruited from the regeneration
//! layer), the shaded crown, and the vigour memory that feeds stress mortality (trees in
//! `growth`, sapling cohorts in `regen`). Units: metres, cm of DBH, light as the relative
//! irradiance 0–1.

use crate::species::{allometry, Species};

/// Crown base of a new tree as a fraction of its height (m/m): planted trees and recruits
/// start with 60 % of their height in crown; growth raises it from there
/// (`sim::phases::growth`, natural pruning).
pub const START_CROWN_BASE_FRACTION: f32 = 0.4;

/// DBH of a new tree as a fraction of the open-grown DBH of its height (cm/cm): young trees,
/// planted or grown up in a stand, are more slender than open-grown ones.
pub const START_DBH_FRACTION: f32 = 0.8;

/// Crown base (m) of a new tree of height `height_m` (m): [`START_CROWN_BASE_FRACTION`] of it.
#[inline]
pub fn start_crown_base(height_m: f32) -> f32 {
    height_m * START_CROWN_BASE_FRACTION
}

/// DBH (cm) of a new tree of species `sp` and height `height_m` (m): [`START_DBH_FRACTION`] of
/// the open-grown DBH ([`allometry::open_dbh`]).
#[inline]
pub fn start_dbh(sp: &Species, height_m: f32) -> f32 {
    allometry::open_dbh(sp, height_m) * START_DBH_FRACTION
}

/// Factor (0.5–1) on the open-grown crown radius under relative light `light` (clamped to
/// 0–1): `0.5 + 0.5 L`, crowns shrink to half in deep shade (crown plasticity; used by growth
/// every year and for recruits).
#[inline]
pub fn shaded_crown(light: f32) -> f32 {
    0.5 + 0.5 * light.clamp(0.0, 1.0)
}

/// Crown radius (m) of a tree as it stands in the forest (its crown's outline seen from above,
/// what inventories report, pictures draw and the light phase spreads the tree's leaf area
/// over): the larger of its crown-space radius `space_radius` (the simulated state,
/// `TreeStore::crown_radius`: the open-grown radius shrunk by crowding and shade, whose
/// projection × crown LAI is the tree's leaf area) and its species' stand-grown crown radius
/// ([`crate::species::allometry::stand_crown_radius`]: the published crown-width functions of
/// trees in closed stands, Döbbeler et al. 2001/2002 as in BWINPro/TreeGrOSS, at DBH `dbh` (cm),
/// height `h` (m), crown base `cb` (m)), at most the open-grown radius, in full while the crown
/// gets at least 0.4 of full light `light` and narrowing in shade to 0.71 of it: factor
/// `min(1, shaded_crown(L) / shaded_crown(0.4))` (ESTIMATE: the functions are fitted on the
/// trees of closed stands, whose crowns are not in full light; 0.4 of full light is a
/// co-dominant crown's in the model's closed pure stands, where 0.5 left the thinnest canopy
/// trees of beech, 10–20 cm at age 80, at 0.78 of the function: tests/sim_crowns.rs).
///
/// Crowns of closed stands interlock and overlap their neighbours' (their projections sum to
/// more than the ground: Pretzsch 2009 ch. 8), so the outline is wider than the tree's share of
/// the canopy; the leaf area stays that of the share. A species without a stand-grown function
/// has the crown-space radius.
#[inline]
pub fn crown_outline_radius(sp: &crate::species::Species, h: f32, dbh: f32, cb: f32, light: f32, space_radius: f32) -> f32 {
    match crate::species::allometry::stand_crown_radius(sp, dbh, h, cb) {
        Some(rs) => {
            let open = crate::species::allometry::open_crown_radius(sp, h, dbh);
            space_radius.max(rs.min(open) * (shaded_crown(light) / shaded_crown(0.4)).min(1.0))
        }
        None => space_radius,
    }
}

/// Vigour memory of trees (`growth`) and sapling cohorts (`regen`, with `m` = 1): the new
/// vigour from last year's `vigour` and this year's growth response `f` (the light response ×
/// the site suitability with the species' drought factor; below the upper layer the suitability
/// alone, the light's part there being the shade mortality `sim::phases::mortality::p_shade`,
/// issue 35 rounds 39–40) under crowding modifier `m` (1: none):
/// `v ← 0.5 v + 0.5 f m`, an exponential memory with a half-life of one year, so that
/// suppression is felt within a few years; stress mortality acts while it is below the
/// species' threshold (Bugmann 2001's low-growth stress mortality). Source of the weights:
/// Sylva's density calibration (commit 878c63b, "faster vigour response (0.5/0.5) so
/// self-thinning follows the line without overshoot", replacing `0.7 v + 0.3 f`), under which
/// the self-thinning and yield-table tests (tests/sim_density.rs, tests/sim_yield*.rs) pass.
#[inline]
pub fn vigour_memory(vigour: f32, f: f32, m: f32) -> f32 {
    0.5 * vigour + 0.5 * f * m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_at_their_anchors() {
        assert_eq!(start_crown_base(20.0), 8.0);
        assert_eq!(shaded_crown(-1.0), 0.5);
        assert_eq!(shaded_crown(2.0), 1.0);
        // a year of full growth halves the gap to 1; a year without growth halves the vigour
        assert_eq!(vigour_memory(0.5, 1.0, 1.0), 0.75);
        assert_eq!(vigour_memory(0.5, 0.0, 1.0), 0.25);
        let b = crate::sim::fixtures::beech_like();
        assert!((start_dbh(&b, 10.0) - 0.8 * allometry::open_dbh(&b, 10.0)).abs() < 1e-6);
    }
}
