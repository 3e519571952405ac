//! From simulation results to a render [`Scene`]: the terrain mesh of the site, one prototype per
//! species (its EcoMod skeleton meshed into a level-of-detail chain), and one instance per live
//! tree of an inventory snapshot.
//!
//! [`prototypes`] builds one open-grown tree per species; the trees near the camera get their own
//! adapted skeletons and meshes in [`super::adapted`] (Plastic Trees, Pirk et al. 2012,
//! `000_*.txt`).

use crate::conditions::SiteConditions;
use crate::grid::Grid;
use crate::job::inventory::InventoryRow;
use crate::sim::World;
use crate::render::scene::{Prototype, Scene, Sky, Sun, TerrainMesh, TreeInstance, Wind};
use crate::render::terrain::{from_grid, LandCover};
use crate::species::{Season, Species, SpeciesLibrary};
use crate::Result;

/// sRGB (0–255) to linear RGB (0–1), IEC 61966-2-1.
pub fn srgb_to_linear(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| {
        let s = v as f32 / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    })
}

/// Day of year (1–365) used to draw each season: mid-May, mid-July, mid-October, mid-January.
pub fn season_day(season: Season) -> f32 {
    match season {
        Season::Spring => 135.0,
        Season::Summer => 196.0,
        Season::Autumn => 290.0,
        Season::Winter => 15.0,
    }
}

/// Foliage colour (linear RGB) and leaf amount (0–1) of `species` in `season`: its
/// [`foliage_on_day`] on the season's [`season_day`], so that species with different leaf-out and
/// autumn dates differ in the same picture (in mid-May a birch is past its flush while an oak is
/// still unfolding; in mid-October a birch is yellow and thinning while an oak is still turning).
pub fn foliage(species: &Species, season: Season) -> ([f32; 3], f32) {
    foliage_on_day(species, season_day(season))
}

/// Foliage colour (linear RGB) and leaf amount (0–1) of `species` on day of year `doy`
/// (1–365, wrapped), from its phenology (`appearance.leaf_out_doy`, `autumn_doy`,
/// `leaf_fall_doy`; sources in `species/README.md`) and its four colours, blended in linear RGB.
///
/// Deciduous (with `o` = leaf-out, `a` = autumn colour, `f` = leaf fall): bare before `o`;
/// leaves unfold over `o..o+15` (amount 0 → 1, spring colour); spring → summer colour over
/// `o+15..o+45`; summer → autumn colour over `a−20..a`; leaves fall over `f−10..f+14`
/// (amount 1 → 0; BBCH 95 at `f` ≈ half fallen). Evergreen: winter colour from `f` until
/// 30 days before the flush, back to summer by `o`, the light new shoots (spring colour, blended
/// half-way) over `o..o+45`, summer → winter colour over `a..f`; always fully leaved.
pub fn foliage_on_day(species: &Species, doy: f32) -> ([f32; 3], f32) {
    let a = &species.appearance;
    let (spring, summer, autumn, winter) = (srgb_to_linear(a.leaf_spring), srgb_to_linear(a.leaf_summer), srgb_to_linear(a.leaf_autumn), srgb_to_linear(a.leaf_winter));
    let lerp = |x: [f32; 3], y: [f32; 3], t: f32| {
        let t = t.clamp(0.0, 1.0);
        [x[0] + (y[0] - x[0]) * t, x[1] + (y[1] - x[1]) * t, x[2] + (y[2] - x[2]) * t]
    };
    let ramp = |d: f32, from: f32, to: f32| ((d - from) / (to - from).max(1e-3)).clamp(0.0, 1.0);
    let d = doy.rem_euclid(365.0);
    let (o, au, f) = (a.leaf_out_doy, a.autumn_doy, a.leaf_fall_doy);
    if species.identity.deciduous {
        if d < o || d > f + 14.0 {
            return (autumn, 0.0);
        }
        let amount = ramp(d, o, o + 15.0) * (1.0 - ramp(d, f - 10.0, f + 14.0));
        let c = if d < au - 20.0 { lerp(spring, summer, ramp(d, o + 15.0, o + 45.0)) } else { lerp(summer, autumn, ramp(d, au - 20.0, au)) };
        (c, amount)
    } else {
        let c = if d >= f || d < o - 30.0 {
            winter
        } else if d < o {
            lerp(winter, summer, ramp(d, o - 30.0, o))
        } else if d < au {
            // the flush: new shoots half-way to the spring colour, fading into the summer colour
            let k = 0.5 * (1.0 - ramp(d, o + 15.0, o + 45.0)) * ramp(d, o, o + 5.0);
            lerp(summer, spring, k)
        } else {
            lerp(summer, winter, ramp(d, au, f))
        };
        (c, 1.0)
    }
}

/// The crown look of `species` from afar (`appearance.crown_top_flatness`, `crown_cover`,
/// `crown_clump`), which the renderer's coarse levels draw, and its leaf outline
/// (`appearance.leaf_texture`) for the leaf cards.
pub fn crown_look(species: &Species) -> crate::render::lod::CrownLook {
    let a = &species.appearance;
    crate::render::lod::CrownLook { top_flatness: a.crown_top_flatness, cover: a.crown_cover, clump: a.crown_clump, leaf_shape: Some(crate::structure::texture::LeafShape::of_species(species)) }
}

/// One prototype per species of `library`, in library order (so `SpeciesId` indexes them):
/// the species' EcoMod tree (004_*.txt, Algorithm 1) normalised to 1 m height, meshed into its
/// LOD chain by [`crate::structure::species_lod_chain`]. A species whose model cannot be built
/// falls back to the renderer's stand-in chain (logged).
pub fn prototypes(library: &SpeciesLibrary) -> Vec<Prototype> {
    use rayon::prelude::*;
    library
        .species
        .par_iter()
        .map(|s| {
            let mut lods = crate::structure::species_lod_chain(s, 42);
            if lods.levels.is_empty() {
                lods = crate::render::lod::placeholder_chain(s.identity.leaf_type == crate::species::LeafType::Conifer);
            }
            Prototype {
                name: s.id.clone(),
                lods,
                bark_color: srgb_to_linear(s.appearance.bark),
                leaf_color: srgb_to_linear(s.appearance.leaf_summer),
                stiffness: s.architecture.ecomod.k_f.clamp(0.0, 1.0),
                look: Some(crown_look(s)),
            }
        })
        .collect()
}

/// Bilinearly upsamples the site's elevation so that render cells are at most `max_cell_m`
/// metres; masked (NaN) cells take the minimum valid elevation. Returns the grid and its cell
/// sizes (m).
pub fn render_heights(cond: &SiteConditions, max_cell_m: f64) -> (Grid<f32>, f32, f32) {
    let f = ((cond.cell_x_m.max(cond.cell_y_m) / max_cell_m).ceil() as usize).clamp(1, 16);
    let (w, h) = (cond.width() * f, cond.height() * f);
    let (cx, cy) = (cond.cell_x_m / f as f64, cond.cell_y_m / f as f64);
    let ymax = cond.height() as f64 * cond.cell_y_m;
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        let y = ymax - (r as f64 + 0.5) * cy;
        for c in 0..w {
            let x = (c as f64 + 0.5) * cx;
            data.push(cond.elevation_at(x, y));
        }
    }
    let min = data.iter().copied().filter(|v| v.is_finite()).fold(f32::INFINITY, f32::min);
    for v in &mut data {
        if !v.is_finite() {
            *v = if min.is_finite() { min } else { 0.0 };
        }
    }
    (Grid { width: w, height: h, data }, cx as f32, cy as f32)
}

/// The terrain mesh of the site (cells ≤ `max_cell_m` m), land-cover coloured, with an optional
/// overlay field (values 0–1) on the site grid.
pub fn terrain_mesh(cond: &SiteConditions, max_cell_m: f64, sea_level: f32) -> Result<TerrainMesh> {
    let (g, cx, cy) = render_heights(cond, max_cell_m);
    let cover = LandCover { sea_level, ..LandCover::default() };
    from_grid(&g, cx, cy, &cover, None)
}

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
    let mut order: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].alive && rows[i].height_m >= MIN_DRAWN_HEIGHT_M).collect();
    order.sort_by(|&a, &b| rows[b].height_m.total_cmp(&rows[a].height_m).then(rows[a].id.cmp(&rows[b].id)));
    let nx = ((extent_m.0 / CANOPY_CELL_M).ceil() as usize).max(1);
    let ny = ((extent_m.1 / CANOPY_CELL_M).ceil() as usize).max(1);
    let mut canopy = vec![0.0f32; nx * ny];
    let cell = |v: f64, n: usize| ((v / CANOPY_CELL_M).floor().max(0.0) as usize).min(n - 1);
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
    keep
}

/// Render instances of the visible live trees of `rows` ([`visible`]) for `season`; trees of
/// species not in `library` are skipped. Positions are in the site's world coordinates with z
/// from the terrain.
pub fn instances(rows: &[Plant], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    visible(rows, cond.extent_m())
        .into_iter()
        .map(|i| &rows[i])
        .filter_map(|r| {
            let sid = library.find(r.species)?;
            let sp = &library.species[sid as usize];
            let (col, amount) = foliage(sp, season);
            let z = cond.elevation_at(r.x_m, r.y_m);
            let mut inst = TreeInstance::new(r.id, [r.x_m as f32, r.y_m as f32, z], r.height_m, r.crown_radius_m.max(0.2), sid as u32, col);
            inst.leaf_amount = amount;
            Some(inst)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: u64, x: f64, y: f64, h: f32, r: f32) -> InventoryRow {
        InventoryRow { id, species: "beech".into(), x_m: x, y_m: y, z_m: 0.0, age_yr: 10.0, height_m: h, dbh_cm: 10.0, crown_radius_m: r, crown_base_m: h * 0.5, status: "alive".into() }
    }

    #[test]
    fn understory_under_a_crown_is_hidden_and_open_trees_are_kept() {
        let rows = vec![
            row(1, 50.0, 50.0, 30.0, 6.0), // canopy tree
            row(2, 52.0, 51.0, 8.0, 2.0),  // under its crown: hidden (8 < 0.6·30)
            row(3, 53.0, 50.0, 25.0, 4.0), // co-dominant under the crown edge: kept (25 ≥ 18)
            row(4, 80.0, 80.0, 5.0, 2.0),  // in the open: kept
            row(5, 90.0, 90.0, 0.5, 0.3),  // seedling: not drawn
            InventoryRow { status: "dead:stress".into(), ..row(6, 20.0, 20.0, 20.0, 3.0) },
        ];
        assert_eq!(visible_rows(&rows, (100.0, 100.0)), vec![0, 2, 3]);
    }
}
/// A full scene for one snapshot: terrain, prototypes, instances, the sun of the site's
/// latitude on the season's day at 14:00 solar time, and a light westerly breeze.
pub fn scene(terrain: TerrainMesh, prototypes: Vec<Prototype>, instances: Vec<TreeInstance>, latitude_deg: f64, season: Season, sea_level: Option<f32>) -> Scene {
    Scene::new(terrain, sea_level, prototypes, instances, Sun::from_position(latitude_deg as f32, season_day(season), 14.0), Sky::default(), Wind { direction: [1.0, 0.0], directed: 1.5, undirected: 1.0, time_s: 0.0 })
}
