//! The trees worth drawing (live, tall enough, not hidden under taller crowns) and their instances.

use super::*;

/// Seedlings below this height (m) are not drawn at landscape scale.
pub const MIN_DRAWN_HEIGHT_M: f32 = 1.0;
/// A tree whose top is below this fraction of the canopy already drawn over its stem is hidden
/// under that canopy and not drawn (see [`visible_rows`]).
pub const UNDERSTORY_FRACTION: f32 = 0.6;
/// Cell size (m) of the canopy-height raster used to find understory trees.
pub const CANOPY_CELL_M: f64 = 2.0;

/// Indices of the trees of `rows` worth drawing from above or at an angle: live, at least
/// [`MIN_DRAWN_HEIGHT_M`] tall, and not hidden under the crowns of taller trees.
///
/// Trees are visited tallest first; each drawn tree stamps its crown disc into a canopy-height
/// raster of [`CANOPY_CELL_M`] cells; a later (shorter) tree whose top is below
/// [`UNDERSTORY_FRACTION`] × the canopy height at its stem is suppressed understory that no
/// camera above the canopy sees, and is skipped. This is a visibility cull, not ecology: the
/// inventory keeps every tree. It bounds the instances of dense young stands (thousands of stems
/// per hectare) by the number of crowns that fit side by side. Deterministic (ties by id).
pub fn visible_rows(rows: &[InventoryRow], extent_m: (f64, f64)) -> Vec<usize> {
    visible(&plants_from_rows(rows), extent_m)
}

/// One tree as the pictures need it, from an in-memory [`World`] ([`plants_from_world`]) or an
/// inventory file ([`plants_from_rows`]): world coordinates (m, from the site's south-west
/// corner), height and crown radius (m), alive or not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plant<'a> {
    /// Stable tree id.
    pub id: u64,
    /// Species id (as in `species/*.toml`).
    pub species: &'a str,
    /// Easting (m).
    pub x_m: f64,
    /// Northing (m).
    pub y_m: f64,
    /// Height (m).
    pub height_m: f32,
    /// Crown radius (m).
    pub crown_radius_m: f32,
    /// Age (years).
    pub age_yr: f32,
    /// Crown base height above the stem base (m).
    pub crown_base_m: f32,
    /// False for a tree that died in the snapshot's year (drawn by no picture).
    pub alive: bool,
}

/// The living trees of `w` as [`Plant`]s, in tree-store order (no file round trip).
pub fn plants_from_world(w: &World) -> Vec<Plant<'_>> {
    let t = &w.stand.trees;
    (0..t.len())
        .map(|i| Plant { id: t.id[i], species: w.site.lib.species[t.species[i] as usize].id.as_str(), x_m: t.x[i] as f64, y_m: t.y[i] as f64, height_m: t.height[i], crown_radius_m: t.crown_radius[i], age_yr: t.age[i], crown_base_m: t.crown_base[i], alive: true })
        .collect()
}

/// The rows of an inventory snapshot as [`Plant`]s, one per row in row order (status `alive`
/// read once here).
pub fn plants_from_rows(rows: &[InventoryRow]) -> Vec<Plant<'_>> {
    rows.iter().map(|r| Plant { id: r.id, species: r.species.as_str(), x_m: r.x_m, y_m: r.y_m, height_m: r.height_m, crown_radius_m: r.crown_radius_m, age_yr: r.age_yr, crown_base_m: r.crown_base_m, alive: r.status == "alive" }).collect()
}

/// [`visible_rows`] over [`Plant`]s: indices of the drawn trees of `rows`, ascending.
pub fn visible(rows: &[Plant], extent_m: (f64, f64)) -> Vec<usize> {
    visible_with_canopy(rows, extent_m).0
}

/// The canopy-height raster of [`visible`]: per [`CANOPY_CELL_M`] cell the height (m) of the
/// tallest drawn crown over it (0: open).
#[derive(Debug, Clone, PartialEq)]
pub struct CanopyHeights {
    /// Columns (west to east).
    pub nx: usize,
    /// Rows (south to north).
    pub ny: usize,
    /// Heights (m), row-major from the south-west cell.
    pub h: Vec<f32>,
}

impl CanopyHeights {
    fn cell(v: f64, n: usize) -> usize {
        ((v / CANOPY_CELL_M).floor().max(0.0) as usize).min(n - 1)
    }
    /// Canopy height (m) over plan point `(x, y)` (clamped to the raster).
    pub fn at(&self, x: f64, y: f64) -> f32 {
        self.h[Self::cell(y, self.ny) * self.nx + Self::cell(x, self.nx)]
    }
}

/// [`visible`] and the canopy-height raster its drawn trees leave.
pub fn visible_with_canopy(rows: &[Plant], extent_m: (f64, f64)) -> (Vec<usize>, CanopyHeights) {
    let mut order: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].alive && rows[i].height_m >= MIN_DRAWN_HEIGHT_M).collect();
    order.sort_by(|&a, &b| rows[b].height_m.total_cmp(&rows[a].height_m).then(rows[a].id.cmp(&rows[b].id)));
    let nx = ((extent_m.0 / CANOPY_CELL_M).ceil() as usize).max(1);
    let ny = ((extent_m.1 / CANOPY_CELL_M).ceil() as usize).max(1);
    let mut canopy = vec![0.0f32; nx * ny];
    let cell = CanopyHeights::cell;
    let mut keep = Vec::with_capacity(order.len());
    for i in order {
        let r = &rows[i];
        let (cx, cy) = (cell(r.x_m, nx), cell(r.y_m, ny));
        if r.height_m < UNDERSTORY_FRACTION * canopy[cy * nx + cx] {
            continue;
        }
        keep.push(i);
        let rad = r.crown_radius_m.max(0.5) as f64;
        let (x0, x1) = (cell(r.x_m - rad, nx), cell(r.x_m + rad, nx));
        let (y0, y1) = (cell(r.y_m - rad, ny), cell(r.y_m + rad, ny));
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = ((x as f64 + 0.5) * CANOPY_CELL_M, (y as f64 + 0.5) * CANOPY_CELL_M);
                if (px - r.x_m).powi(2) + (py - r.y_m).powi(2) <= rad * rad {
                    let c = &mut canopy[y * nx + x];
                    *c = c.max(r.height_m);
                }
            }
        }
    }
    keep.sort_unstable();
    (keep, CanopyHeights { nx, ny, h: canopy })
}

/// Render instances of the visible live trees of `rows` ([`visible`]) for `season`; trees of
/// species not in `library` are skipped. Positions are in the site's world coordinates with z
/// from the terrain.
pub fn instances(rows: &[Plant], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    tree_instances(rows, &visible(rows, cond.extent_m()), library, cond, season)
}

/// Instances of the trees `keep` (indices into `rows`); a tree younger than
/// [`crate::structure::forest_form::SAPLING_END_AGE_YR`] is drawn with the sapling form blended
/// into its crown ([`crate::structure::forest_form::sapling_blend`], as `sylva tree grow`).
pub(super) fn tree_instances(rows: &[Plant], keep: &[usize], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    keep.iter()
        .map(|&i| &rows[i])
        .filter_map(|r| {
            let sid = library.find(r.species)?;
            let sp = &library.species[sid as usize];
            let (col, amount) = foliage(sp, season);
            let z = cond.elevation_at(r.x_m, r.y_m);
            // a young tree drawn with the sapling form of `sylva tree grow` (round 35, issue 32:
            // the simulation's crowns of 2–10-year trees drew round tufts on sticks)
            let (cb_m, crown_r) = crate::structure::forest_form::sapling_blend(sp, r.age_yr, r.height_m, r.crown_base_m, r.crown_radius_m);
            // the tree's own value and hue about its species' colour (round 46)
            let k = tree_tint(r.id);
            let col = [col[0] * k[0], col[1] * k[1], col[2] * k[2]];
            let mut inst = TreeInstance::new(r.id, [r.x_m as f32, r.y_m as f32, z], r.height_m, crown_r.max(0.2), sid as u32, col);
            inst.leaf_amount = amount;
            // the crown from where the simulation has its base
            let cb = cb_m / r.height_m;
            if cb.is_finite() && cb > 0.0 {
                inst.crown_base = cb.clamp(0.05, 0.85);
            }
            Some(inst)
        })
        .collect()
}
