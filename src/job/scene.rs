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

pub use crate::species::srgb_to_linear;

/// Day of year (1–365) used to draw each season: mid-May, mid-July, mid-October, mid-January.
pub fn season_day(season: Season) -> f32 {
    match season {
        Season::Spring => 135.0,
        Season::Summer => 196.0,
        Season::Autumn => 290.0,
        Season::Winter => 15.0,
    }
}

/// The sun of every picture of `season` at latitude `latitude_deg`: its [`season_day`] at
/// [`crate::sun::REFERENCE_HOUR`] (14:00 local solar time).
pub fn season_sun(latitude_deg: f64, season: Season) -> Sun {
    Sun::from_position(latitude_deg as f32, season_day(season), crate::sun::REFERENCE_HOUR)
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

/// Instances of the trees `keep` (indices into `rows`).
fn tree_instances(rows: &[Plant], keep: &[usize], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    keep.iter()
        .map(|&i| &rows[i])
        .filter_map(|r| {
            let sid = library.find(r.species)?;
            let sp = &library.species[sid as usize];
            let (col, amount) = foliage(sp, season);
            let z = cond.elevation_at(r.x_m, r.y_m);
            let mut inst = TreeInstance::new(r.id, [r.x_m as f32, r.y_m as f32, z], r.height_m, r.crown_radius_m.max(0.2), sid as u32, col);
            inst.leaf_amount = amount;
            // the crown from where the simulation has its base
            let cb = r.crown_base_m / r.height_m;
            if cb.is_finite() && cb > 0.0 {
                inst.crown_base = cb.clamp(0.05, 0.85);
            }
            Some(inst)
        })
        .collect()
}

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
fn unit(key: u64) -> f64 {
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

/// The drawn saplings of one cohort: `(count, crown radius m)`. The open-grown crown radius of
/// the species at the cohort's height ([`crate::species::allometry::open_crown_radius`] of
/// [`crate::species::allometry::open_dbh`]) gives the cover ([`sapling_cover`]); the instances
/// share the covered area `cover · A` equally, as many as the stems up to
/// [`MAX_SAPLINGS_PER_COHORT`] with crowns no wider than `1.0 · h + 0.3` m (a clump of a few
/// stems), so the drawn plan area is the cohort's cover while it fits, and proportional to the
/// stem density in sparse cohorts. `(0, 0)` below [`MIN_SAPLING_HEIGHT_M`] or without stems.
pub fn sapling_clumps(sp: &Species, stems: u32, height_m: f32, cell_m: f64) -> (u32, f32) {
    use crate::species::allometry::{open_crown_radius, open_dbh};
    if stems == 0 || !(height_m >= MIN_SAPLING_HEIGHT_M) {
        return (0, 0.0);
    }
    let r = open_crown_radius(sp, height_m, open_dbh(sp, height_m)).max(0.05);
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
/// (± 15 %) and the clump's crown radius, scattered in the light cell by a hash of the cell,
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

/// The ground of the pictures: the site's window and around it the terrain beyond the window
/// (from the DEM where there is one, else a flat apron), at most 10 m between samples, with
/// what land cover needs per sample (streams, wetness) and the fade of the surroundings into
/// the sky. [`Landscape::mesh`] colours it by the canopy cover of a frame's trees.
#[derive(Debug, Clone, PartialEq)]
pub struct Landscape {
    /// The samples.
    pub ground: crate::render::terrain::GroundGrid,
    /// Land-cover colours (sea level).
    pub cover: LandCover,
}

/// Width (m) over which the edge of the DEM (or of a site without surroundings) fades out.
pub const EDGE_FADE_M: f64 = 150.0;

/// Multi-source breadth-first distance (in samples, 8-connected with √2 diagonals, a chamfer
/// approximation of the Euclidean distance) from the cells where `src` is true, and the index
/// of the nearest source cell; `(∞, usize::MAX)` when there is no source.
fn chamfer(w: usize, h: usize, src: &[bool]) -> (Vec<f32>, Vec<usize>) {
    let n = w * h;
    let mut d = vec![f32::INFINITY; n];
    let mut near = vec![usize::MAX; n];
    for i in 0..n {
        if src[i] {
            d[i] = 0.0;
            near[i] = i;
        }
    }
    // two raster passes of the 3 x 3 chamfer (Borgefors 1986, "Distance transformations in
    // digital images", CVGIP 34:344–371), carrying the nearest source
    let diag = std::f32::consts::SQRT_2;
    let fwd: [(i64, i64, f32); 4] = [(-1, 0, 1.0), (-1, -1, diag), (0, -1, 1.0), (1, -1, diag)];
    let bwd: [(i64, i64, f32); 4] = [(1, 0, 1.0), (1, 1, diag), (0, 1, 1.0), (-1, 1, diag)];
    for (pass, offs) in [(0, fwd), (1, bwd)] {
        for k in 0..n {
            let i = if pass == 0 { k } else { n - 1 - k };
            let (c, r) = ((i % w) as i64, (i / w) as i64);
            for (dc, dr, cost) in offs {
                let (nc, nr) = (c + dc, r + dr);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                    continue;
                }
                let j = nr as usize * w + nc as usize;
                if d[j] + cost < d[i] {
                    d[i] = d[j] + cost;
                    near[i] = near[j];
                }
            }
        }
    }
    (d, near)
}

/// Stream channels as smoothed centre lines (for drawing). Every cell of the flow grid with a
/// [`crate::render::terrain::stream_strength`] s > 0 of its contributing area (`acc` cells of
/// `cell_area` m²) is a channel cell; its part of the channel runs from the midpoint of the D8
/// step into it (from its upstream channel neighbour of largest area; from its own centre at a
/// channel head) to the midpoint of its D8 step out (its own centre at an outlet), as the
/// quadratic Bézier curve with the cell centre as control point, every centre first replaced by
/// the mean of the centres within two steps along the channel (upstream along the main stem; as
/// many steps on each side, so heads and outlets stay in place).
/// D8 paths are staircases of axis and diagonal steps in irregular runs; averaged along the
/// channel and with their corners cut (Chaikin's corner cutting, one round), a channel running
/// at 30° to the grid is drawn as a smooth line, not a staircase. `at(x, y, s, len)` is called at points of every curve at most
/// `spacing` m apart (window-local metres from `local`, the plan position of a cell centre),
/// `len` the length of curve (m) the point stands for (half of each chord beside it).
fn stream_lines(acc: &Grid<f32>, dir: &Grid<u8>, m: &Grid<bool>, cell_area: f64, local: &dyn Fn(usize, usize) -> [f64; 2], spacing: f64, mut at: impl FnMut(f64, f64, f32, f64)) {
    let (w, h) = (acc.width, acc.height);
    let strength = |i: usize| if m.data[i] { crate::render::terrain::stream_strength((acc.data[i] as f64 * cell_area) as f32) } else { 0.0 };
    let s: Vec<f32> = (0..w * h).map(strength).collect();
    let down = |i: usize| crate::terrain::fields::downstream(dir, i);
    // the main upstream channel cell of every channel cell: the one of largest area
    let mut up: Vec<Option<usize>> = vec![None; w * h];
    for i in 0..w * h {
        if s[i] > 0.0 {
            if let Some(j) = down(i) {
                if up[j].is_none_or(|k| acc.data[i] > acc.data[k]) {
                    up[j] = Some(i);
                }
            }
        }
    }
    // every channel cell's centre smoothed along the channel: the mean of the centres of the
    // cells up to SMOOTH steps upstream (main stem) and as many downstream of it
    const SMOOTH: usize = 2;
    let centre = |i: usize| local(i % w, i / w);
    let xy = |i: usize| {
        let mut sum = centre(i);
        let mut k = 1.0;
        let (mut u, mut d) = (i, i);
        // as many steps upstream as downstream, so that heads and outlets stay where they are
        for _ in 0..SMOOTH {
            let (Some(nu), Some(nd)) = (up[u], down(d)) else { break };
            (u, d) = (nu, nd);
            let (qu, qd) = (centre(u), centre(d));
            sum = [sum[0] + qu[0] + qd[0], sum[1] + qu[1] + qd[1]];
            k += 2.0;
        }
        [sum[0] / k, sum[1] / k]
    };
    // smoothed once per channel cell (and per cell a channel drains into), not per curve
    let smooth: Vec<Option<[f64; 2]>> = (0..w * h).map(|i| (s[i] > 0.0 || up[i].is_some()).then(|| xy(i))).collect();
    let at_cell = |i: usize| smooth[i].unwrap_or_else(|| xy(i));
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    for i in 0..w * h {
        if s[i] <= 0.0 {
            continue;
        }
        let p = at_cell(i);
        let a = up[i].map_or(p, |k| mid(at_cell(k), p));
        let b = down(i).map_or(p, |j| mid(p, at_cell(j)));
        let len = (a[0] - p[0]).hypot(a[1] - p[1]) + (b[0] - p[0]).hypot(b[1] - p[1]);
        if len <= 0.0 {
            continue; // a lone channel cell (head and outlet): no line
        }
        let n = ((len / spacing.max(1e-3)).ceil() as usize).clamp(2, 256);
        let pts: Vec<[f64; 2]> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                let (u, v, z) = ((1.0 - t) * (1.0 - t), 2.0 * (1.0 - t) * t, t * t);
                [u * a[0] + v * p[0] + z * b[0], u * a[1] + v * p[1] + z * b[1]]
            })
            .collect();
        let chord = |k: usize| (pts[k + 1][0] - pts[k][0]).hypot(pts[k + 1][1] - pts[k][1]);
        for k in 0..=n {
            // the curves of consecutive cells meet at the midpoints: each end counts half
            let l = 0.5 * (if k > 0 { chord(k - 1) } else { 0.0 } + if k < n { chord(k) } else { 0.0 });
            at(pts[k][0], pts[k][1], s[i], l);
        }
    }
}

impl Landscape {
    /// The landscape of `site`. `full`: the whole terrain the site was cut from and the window
    /// `[col0, row0, width, height]` (cells of that terrain) it was cut with; `None`: the site
    /// alone (its edges fade out over [`EDGE_FADE_M`] beyond it). The margin drawn around the
    /// window is half its longer side, at most 2 km; the surroundings fade into the sky from
    /// 35 % of the margin to its end, and over [`EDGE_FADE_M`] at the edge of the DEM (nodata or
    /// the end of the grid). Samples at most `max_cell_m` apart; inside the window their height
    /// is the site's [`SiteConditions::elevation_at`], so trees stand on the ground drawn.
    /// Streams ([`crate::render::terrain::stream_strength`] of the D8 flow accumulation, drawn
    /// along corner-cut centre lines so that they do not show the D8 staircase) and
    /// wetness (topographic wetness index, [`crate::render::terrain::wetness`]) are computed on
    /// the terrain of the drawn area (`crate::terrain::fields`), so the flow from beyond the
    /// window counts.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when the window leaves `full`'s grid or `max_cell_m ≤ 0`.
    pub fn new(site: &SiteConditions, full: Option<(&crate::terrain::Terrain, [usize; 4])>, max_cell_m: f64, sea_level: f32) -> Result<Landscape> {
        use crate::terrain::fields;
        if !(max_cell_m > 0.0) {
            return Err(crate::Error::Invalid { context: "job::scene::Landscape".into(), field: "max_cell_m".into(), value: max_cell_m.to_string(), expected: "> 0 m".into() });
        }
        let f = ((site.cell_x_m.max(site.cell_y_m) / max_cell_m).ceil() as usize).clamp(1, 16);
        let (cx, cy) = (site.cell_x_m / f as f64, site.cell_y_m / f as f64);
        let (ex, ey) = site.extent_m();
        // the source terrain: the full DEM around the window, or the site itself
        let own;
        let (src, [c0, r0, ww, wh]) = match full {
            Some((t, w)) => {
                if w[0] + w[2] > t.elevation.width || w[1] + w[3] > t.elevation.height {
                    return Err(crate::Error::Invalid { context: t.source.clone(), field: "window".into(), value: format!("{w:?}"), expected: format!("inside {} x {}", t.elevation.width, t.elevation.height) });
                }
                (t, w)
            }
            None => {
                own = crate::terrain::Terrain { elevation: site.elevation_m.clone(), geo: site.geo.clone(), nodata: None, source: "site".into() };
                (&own, [0, 0, site.width(), site.height()])
            }
        };
        let (scx, scy) = (ex / ww as f64, ey / wh as f64);
        let margin = (0.5 * ex.max(ey)).min(2000.0);
        let (mx, my) = ((margin / cx).ceil() as usize, (margin / cy).ceil() as usize);
        let (nw, nh) = (((ex / cx).round() as usize) + 2 * mx, ((ey / cy).round() as usize) + 2 * my);
        let origin = [-(mx as f64 * cx), -(my as f64 * cy)];
        // the source cells under the drawn area, for the flow fields
        let sc0 = (c0 as f64 - margin / scx).floor().max(0.0) as usize;
        let sr0 = (r0 as f64 - margin / scy).floor().max(0.0) as usize;
        let sc1 = ((c0 + ww) as f64 + margin / scx).ceil().min(src.elevation.width as f64) as usize;
        let sr1 = ((r0 + wh) as f64 + margin / scy).ceil().min(src.elevation.height as f64) as usize;
        let sub = crate::terrain::io::window(src, sc0, sr0, sc1 - sc0, sr1 - sr0)?;
        let m = fields::mask(&sub, sea_level);
        let filled = fields::fill_depressions(&sub, &m);
        let dir = fields::flow_directions(&filled, &sub.geo, &m);
        let acc = fields::flow_accumulation(&dir, &m);
        let (slope, _) = fields::slope_aspect(&sub, &m);
        let twi = fields::twi(&acc, &slope, &sub.geo, &m);
        // source grid position (fractional column, row) of a window-local point
        let to_src = |x: f64, y: f64| (c0 as f64 + x / scx - 0.5, r0 as f64 + wh as f64 - y / scy - 0.5);
        let src_at = |fc: f64, fr: f64| -> f32 {
            let g = &src.elevation;
            if fc < -0.5 || fr < -0.5 || fc > g.width as f64 - 0.5 || fr > g.height as f64 - 0.5 {
                return f32::NAN;
            }
            let (fc, fr) = (fc.clamp(0.0, (g.width - 1) as f64), fr.clamp(0.0, (g.height - 1) as f64));
            let (a, b) = (fc.floor() as usize, fr.floor() as usize);
            let (a1, b1) = ((a + 1).min(g.width - 1), (b + 1).min(g.height - 1));
            let (tx, ty) = ((fc - a as f64) as f32, (fr - b as f64) as f32);
            let v = g.get(a, b) * (1.0 - tx) * (1.0 - ty) + g.get(a1, b) * tx * (1.0 - ty) + g.get(a, b1) * (1.0 - tx) * ty + g.get(a1, b1) * tx * ty;
            v
        };
        let n = nw * nh;
        let mut heights = vec![f32::NAN; n];
        let mut stream = vec![0.0f32; n];
        let mut wet = vec![0.0f32; n];
        let mut outside = vec![0.0f64; n];
        let cell_area = scx * scy;
        for r in 0..nh {
            for c in 0..nw {
                let i = r * nw + c;
                let x = origin[0] + (c as f64 + 0.5) * cx;
                let y = origin[1] + (nh as f64 - r as f64 - 0.5) * cy;
                let inside = x >= 0.0 && y >= 0.0 && x <= ex && y <= ey;
                let (fc, fr) = to_src(x, y);
                heights[i] = if inside { site.elevation_at(x, y) } else { src_at(fc, fr) };
                let (dx, dy) = ((-x).max(x - ex).max(0.0), (-y).max(y - ey).max(0.0));
                outside[i] = dx.hypot(dy);
                let (sc, sr) = (fc.round() as i64 - sc0 as i64, fr.round() as i64 - sr0 as i64);
                if sc >= 0 && sr >= 0 && (sc as usize) < acc.width && (sr as usize) < acc.height {
                    let (sc, sr) = (sc as usize, sr as usize);
                    if *m.get(sc, sr) {
                        wet[i] = crate::render::terrain::wetness(*twi.get(sc, sr));
                    }
                }
            }
        }
        // window-local plan position of the centre of cell (c, r) of `sub`
        let local = |c: usize, r: usize| -> [f64; 2] { [((sc0 + c) as f64 - c0 as f64 + 0.5) * scx, (r0 as f64 + wh as f64 - (sr0 + r) as f64 - 0.5) * scy] };
        // every curve point splats its strength bilinearly onto the four samples around it,
        // weighted by the length of curve it stands for (so a line through sample centres
        // along an axis draws its strength there, and the strength-weighted centre of a column
        // lies on the line: bilinear weights keep the first moment), at most 1 where lines meet
        stream_lines(&acc, &dir, &m, cell_area, &local, 0.2 * cx.min(cy), |x, y, s, len| {
            let (fc, fr) = ((x - origin[0]) / cx - 0.5, nh as f64 - (y - origin[1]) / cy - 0.5);
            let (c, r) = (fc.floor(), fr.floor());
            let (tx, ty) = (fc - c, fr - r);
            for (dc, dr, wgt) in [(0.0, 0.0, (1.0 - tx) * (1.0 - ty)), (1.0, 0.0, tx * (1.0 - ty)), (0.0, 1.0, (1.0 - tx) * ty), (1.0, 1.0, tx * ty)] {
                let (cc, rr) = (c + dc, r + dr);
                if cc >= 0.0 && rr >= 0.0 && cc < nw as f64 && rr < nh as f64 {
                    stream[rr as usize * nw + cc as usize] += (s as f64 * wgt * len / cx.min(cy)) as f32;
                }
            }
        });
        stream.iter_mut().for_each(|v| *v = v.min(1.0));
        // fill the samples without ground from the nearest ground (flat aprons) and fade them
        let valid: Vec<bool> = heights.iter().map(|v| v.is_finite()).collect();
        let invalid: Vec<bool> = valid.iter().map(|v| !v).collect();
        let (d_out, near) = chamfer(nw, nh, &valid);
        let (d_in, _) = chamfer(nw, nh, &invalid);
        let step = cx.min(cy);
        let sstep = |e0: f64, e1: f64, v: f64| {
            let t = ((v - e0) / (e1 - e0)).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        };
        let mut fade = vec![0.0f32; n];
        for i in 0..n {
            if !valid[i] {
                heights[i] = if near[i] == usize::MAX { 0.0 } else { heights[near[i]] };
            }
            if outside[i] <= 0.0 {
                continue;
            }
            // signed distance to the edge of the ground: negative inside
            let sd = if valid[i] { -(d_in[i] as f64) * step } else { d_out[i] as f64 * step };
            let edge = if full.is_some() { sstep(-EDGE_FADE_M, 0.25 * EDGE_FADE_M, sd) } else { sstep(0.0, EDGE_FADE_M, outside[i]) };
            fade[i] = sstep(0.35 * margin, margin, outside[i]).max(edge) as f32;
        }
        let ground = crate::render::terrain::GroundGrid {
            heights: Grid { width: nw, height: nh, data: heights },
            cell_x: cx as f32,
            cell_y: cy as f32,
            origin: [origin[0] as f32, origin[1] as f32],
            stream,
            wetness: wet,
            fade,
            focus: Some(([0.0, 0.0], [ex as f32, ey as f32])),
        };
        Ok(Landscape { ground, cover: LandCover { sea_level, ..LandCover::default() } })
    }

    /// The mesh of the landscape coloured for a frame whose trees are `instances`: plan canopy
    /// cover per sample from their crowns ([`canopy_cover`]) turns grass into forest floor.
    ///
    /// Errors: as [`crate::render::terrain::from_ground`] (none for a grid built by [`Landscape::new`]).
    pub fn mesh(&self, instances: &[TreeInstance]) -> Result<TerrainMesh> {
        let g = &self.ground;
        let cov = canopy_cover(instances, g);
        let (w, h) = (g.heights.width, g.heights.height);
        let lookup = |x: f32, y: f32| {
            let c = ((x - g.origin[0]) / g.cell_x - 0.5).round();
            let r = (h as f32 - (y - g.origin[1]) / g.cell_y - 0.5).round();
            if c < 0.0 || r < 0.0 || c >= w as f32 || r >= h as f32 {
                return 0.0;
            }
            cov[r as usize * w + c as usize]
        };
        crate::render::terrain::from_ground(g, &self.cover, &lookup)
    }
}

/// Share of the surroundings' trees kept on a DEM sample beyond the window on a slope of
/// `slope_deg` at elevation `z` (m): all of them, except on slopes of bare rock (from
/// [`LandCover::rock_slope_deg`] + 2° to + 10°), above the tree line (from 100 m below
/// [`LandCover::tree_line`] to 100 m above) and at or below the sea.
fn surroundings_keep(slope_deg: f32, z: f32, cover: &LandCover) -> f32 {
    if !(z > cover.sea_level) {
        return 0.0;
    }
    (1.0 - (slope_deg - cover.rock_slope_deg - 2.0) / 8.0).clamp(0.0, 1.0) * (1.0 - (z - cover.tree_line + 100.0) / 200.0).clamp(0.0, 1.0)
}

/// The eight mirror images of the window around it: (−1, 0, +1) per axis, the west / south
/// edge, none, the east / north edge.
const MIRRORS: [(i8, i8); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];

impl Landscape {
    /// The trees drawn on the terrain beyond the simulated window, so that the window and its
    /// surroundings read as one landscape: the window's own trees (`instances` inside
    /// [`GroundGrid::focus`]: trees, saplings, all as drawn this frame) mirrored across its
    /// four edges and four corners, standing on the surroundings' ground.
    ///
    /// Why mirrors: the surroundings are not simulated, so the most honest stand-in is the
    /// window's own stand, in the same year, season and state of growth (bare land at year 0,
    /// saplings while the window has saplings, the same species patches, heights, gaps and
    /// composition later); a mirror image continues every crown and patch across the window's
    /// edge, so no seam or straight line shows there, and the trees go through the same
    /// renderer (billboards, canopy layer, shadows) as the window's. One mirror image per edge
    /// reaches as far beyond it as the window is wide, so it fills the drawn margin
    /// ([`Landscape::new`]: half the longer side) for windows up to twice as long as they are
    /// wide; beyond that the far part of the margin along the long edges stays unforested.
    ///
    /// An image is kept with probability [`surroundings_keep`] of the ground sample it lands on
    /// (slope, tree line; a hash of its id), so the forest keeps off bare rock and stays below
    /// the tree line, and not where the ground has wholly faded into the sky; it fades into the
    /// sky with that ground ([`TreeInstance::sky_fade`] = the sample's fade). Its id is the tree's
    /// with the image number (1..=8) in bits 48..52, so that it varies like a tree of its own
    /// and keeps its sapling flag ([`SAPLING_ID_BIT`]); `z` is the ground's height there
    /// (bilinear over the samples). Empty without a window.
    ///
    /// [`GroundGrid::focus`]: crate::render::terrain::GroundGrid::focus
    pub fn surroundings(&self, instances: &[TreeInstance]) -> Vec<TreeInstance> {
        let g = &self.ground;
        let Some((lo, hi)) = g.focus else { return Vec::new() };
        let (w, h) = (g.heights.width, g.heights.height);
        if w < 2 || h < 2 {
            return Vec::new();
        }
        // fractional sample coordinates (column, row) of a plan point
        let frac = |x: f32, y: f32| ((x - g.origin[0]) / g.cell_x - 0.5, h as f32 - (y - g.origin[1]) / g.cell_y - 0.5);
        let z = |c: usize, r: usize| *g.heights.get(c.min(w - 1), r.min(h - 1));
        let mut out = Vec::new();
        for t in instances {
            let [x, y, _] = t.position;
            if !(x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1]) {
                continue;
            }
            for (k, &(mx, my)) in MIRRORS.iter().enumerate() {
                let xs = match mx {
                    -1 => 2.0 * lo[0] - x,
                    1 => 2.0 * hi[0] - x,
                    _ => x,
                };
                let ys = match my {
                    -1 => 2.0 * lo[1] - y,
                    1 => 2.0 * hi[1] - y,
                    _ => y,
                };
                let (fc, fr) = frac(xs, ys);
                if !(fc >= 0.0 && fr >= 0.0 && fc <= (w - 1) as f32 && fr <= (h - 1) as f32) {
                    continue;
                }
                let (c, r) = (fc.floor() as usize, fr.floor() as usize);
                let (tx, ty) = (fc - c as f32, fr - r as f32);
                let zz = z(c, r) * (1.0 - tx) * (1.0 - ty) + z(c + 1, r) * tx * (1.0 - ty) + z(c, r + 1) * (1.0 - tx) * ty + z(c + 1, r + 1) * tx * ty;
                let (cn, rn) = (fc.round() as usize, fr.round() as usize);
                // central differences, one-sided at the grid's edge
                let (c0, c1, r0, r1) = (cn.saturating_sub(1), (cn + 1).min(w - 1), rn.saturating_sub(1), (rn + 1).min(h - 1));
                let dzdx = (z(c1, rn) - z(c0, rn)) / ((c1 - c0).max(1) as f32 * g.cell_x);
                let dzdy = (z(cn, r0) - z(cn, r1)) / ((r1 - r0).max(1) as f32 * g.cell_y);
                let slope = dzdx.hypot(dzdy).atan().to_degrees();
                let fade = g.fade.get(rn * w + cn).copied().unwrap_or(0.0);
                let id = t.id ^ ((k as u64 + 1) << 48);
                let keep = surroundings_keep(slope, zz, &self.cover);
                if !(keep > 0.0 && fade < 0.99) || crate::render::terrain::cell_hash((id & 0xFFFF_FFFF) as i64, (id >> 32) as i64, 0x5EED) >= keep {
                    continue;
                }
                out.push(TreeInstance { position: [xs, ys, zz], id, sky_fade: fade, ..*t });
            }
        }
        out
    }
}

/// Plan canopy cover (0..1) per sample of `g` from the crowns of `instances` (saplings count
/// with weight `0.3 · h / 4 m`: grass still grows among young saplings): each crown of radius `r` adds to the samples within it the anti-aliased cover
/// `clamp((r − d)/s + 0.5, 0, 1)` of their centre at distance `d` (`s` the sample spacing),
/// then a 3 × 3 box blur softens the forest edge.
pub fn canopy_cover(instances: &[TreeInstance], g: &crate::render::terrain::GroundGrid) -> Vec<f32> {
    let (w, h) = (g.heights.width, g.heights.height);
    let mut cov = vec![0.0f32; w * h];
    let s = g.cell_x.min(g.cell_y).max(1e-3);
    for t in instances {
        let weight = if t.id & SAPLING_ID_BIT != 0 { 0.3 * (t.height / 4.0).min(1.0) } else { 1.0 } * t.opacity.clamp(0.0, 1.0);
        let r = t.crown_radius.max(0.3);
        let (x, y) = (t.position[0], t.position[1]);
        let c0 = (((x - r - g.origin[0]) / g.cell_x - 0.5).floor().max(0.0)) as usize;
        let c1 = ((((x + r - g.origin[0]) / g.cell_x - 0.5).ceil()).max(0.0) as usize).min(w - 1);
        let rr0 = ((h as f32 - (y + r - g.origin[1]) / g.cell_y - 0.5).floor().max(0.0)) as usize;
        let rr1 = (((h as f32 - (y - r - g.origin[1]) / g.cell_y - 0.5).ceil()).max(0.0) as usize).min(h - 1);
        for rr in rr0..=rr1 {
            let py = g.origin[1] + (h as f32 - rr as f32 - 0.5) * g.cell_y;
            for c in c0..=c1 {
                let px = g.origin[0] + (c as f32 + 0.5) * g.cell_x;
                let d = (px - x).hypot(py - y);
                let a = ((r - d) / s + 0.5).clamp(0.0, 1.0);
                if a > 0.0 {
                    cov[rr * w + c] += a * weight;
                }
            }
        }
    }
    let mut out = vec![0.0f32; w * h];
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut k) = (0.0, 0.0);
            for rr in r.saturating_sub(1)..=(r + 1).min(h - 1) {
                for cc in c.saturating_sub(1)..=(c + 1).min(w - 1) {
                    sum += cov[rr * w + cc].min(1.0);
                    k += 1.0;
                }
            }
            out[r * w + c] = sum / k;
        }
    }
    out
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

    fn cohort(cell: u32, stems: u32, h: f32) -> SaplingCohort<'static> {
        // 40 light cells of 5 m per row, row 0 south
        let (c, r) = (cell % 40, cell / 40);
        SaplingCohort { cell, species: "beech", x_m: (c as f64 + 0.5) * 5.0, y_m: (r as f64 + 0.5) * 5.0, cell_m: 5.0, stems, height_m: h }
    }

    #[test]
    fn a_stand_of_only_cohorts_draws_saplings_in_proportion_to_their_density() {
        use std::f64::consts::PI;
        let lib = SpeciesLibrary::embedded().unwrap();
        let beech = &lib.species[lib.find("beech").unwrap() as usize];
        let cond = SiteConditions::uniform(20, 20, 10.0, 500.0, [5.0; 6], 47.0);
        // three bands of 1.5 m beech saplings: rows 0-9 one stem per 5 m cell, rows 10-19 two,
        // rows 20-29 none; row 30 a dense thicket of 400 stems of 3 m per cell
        let mut cohorts = Vec::new();
        for cell in 0..40 * 31u32 {
            let band = cell / 400;
            let stems = [1, 2, 0, 400][band as usize];
            let h = if band == 3 { 3.0 } else { 1.5 };
            cohorts.push(cohort(cell, stems, h));
        }
        let inst = instances_with_saplings(&[], &cohorts, &lib, &cond, Season::Summer);
        assert!(inst.iter().all(|t| t.id & SAPLING_ID_BIT != 0 && t.height > 1.0 && t.height < 4.0));
        let band_of = |t: &TreeInstance| (t.position[1] / 50.0) as usize;
        let count = |b: usize| inst.iter().filter(|t| band_of(t) == b && t.position[1] < 150.0).count();
        let area = |b: usize| inst.iter().filter(|t| band_of(t) == b && t.position[1] < 150.0).map(|t| PI * (t.crown_radius as f64).powi(2)).sum::<f64>();
        // one instance per stem in the sparse bands, none without stems
        assert_eq!((count(0), count(1), count(2)), (400, 800, 0));
        // drawn plan cover = the Poisson cover of the cohorts' open-grown crowns
        let r = crate::species::allometry::open_crown_radius(beech, 1.5, crate::species::allometry::open_dbh(beech, 1.5)) as f64;
        let lambda = PI * r * r / 25.0;
        assert!(lambda > 0.005 && lambda < 0.5, "beech sapling crown radius {r} m");
        let want1 = 400.0 * 25.0 * (1.0 - (-lambda).exp());
        assert!((area(0) / want1 - 1.0).abs() < 1e-3, "band 1: {} m² drawn, {want1} m² covered", area(0));
        // twice the density: the cover of 2 stems, (1 + e^-λ) times that of one: ~ proportional
        let ratio = area(1) / area(0);
        assert!((ratio - (1.0 + (-lambda).exp())).abs() < 1e-3 && ratio > 1.6, "ratio {ratio}");
        // the thicket covers its cells (clumps of at most 3 instances per cohort)
        let thicket: Vec<&TreeInstance> = inst.iter().filter(|t| t.position[1] >= 150.0).collect();
        assert_eq!(thicket.len(), 40 * 3);
        let cover = thicket.iter().map(|t| PI * (t.crown_radius as f64).powi(2)).sum::<f64>() / (40.0 * 25.0);
        assert!(cover > 0.95 && cover < 1.01, "thicket cover {cover}");
        // deterministic, and inside their light cells
        assert_eq!(inst, instances_with_saplings(&[], &cohorts, &lib, &cond, Season::Summer));
        for (t, c) in inst.iter().zip(cohorts.iter().filter(|c| c.stems > 0).flat_map(|c| std::iter::repeat_n(c, sapling_clumps(beech, c.stems, c.height_m, 5.0).0 as usize))) {
            assert!((t.position[0] as f64 - c.x_m).abs() <= 2.5 && (t.position[1] as f64 - c.y_m).abs() <= 2.5);
        }
    }

    #[test]
    fn saplings_under_a_canopy_and_seedlings_are_not_drawn() {
        let lib = SpeciesLibrary::embedded().unwrap();
        let cond = SiteConditions::uniform(20, 20, 10.0, 500.0, [5.0; 6], 47.0);
        let tree = Plant { id: 1, species: "beech", x_m: 102.5, y_m: 102.5, height_m: 25.0, crown_radius_m: 6.0, age_yr: 60.0, crown_base_m: 12.0, alive: true };
        let under = cohort(20 * 40 + 20, 5, 2.0); // centre (102.5, 102.5), under the crown
        let open = cohort(2 * 40 + 2, 5, 2.0);
        let seedlings = cohort(5 * 40 + 5, 50, 0.3);
        let inst = instances_with_saplings(&[tree], &[under, open, seedlings], &lib, &cond, Season::Summer);
        let saplings: Vec<&TreeInstance> = inst.iter().filter(|t| t.id & SAPLING_ID_BIT != 0).collect();
        assert_eq!(inst.len() - saplings.len(), 1, "the tree");
        assert!(!saplings.is_empty() && saplings.iter().all(|t| (t.position[0] - 12.5).abs() < 2.6), "only the open cohort: {saplings:?}");
    }

    /// A 2 km × 2 km ground of 10 m samples around a 1 km window filled with crowns of two
    /// species (70 % / 30 %), flat except a cliff south of y = −300 m, faded into the sky west
    /// of x = −400 m (half) and x = −450 m (wholly); the surroundings are the window mirrored.
    #[test]
    fn surroundings_mirror_the_window_stand() {
        let (w, h) = (200, 200);
        let (mut heights, mut fade) = (vec![500.0f32; w * h], vec![0.0f32; w * h]);
        for r in 0..h {
            for c in 0..w {
                let (x, y) = (-500.0 + (c as f32 + 0.5) * 10.0, -500.0 + (h as f32 - r as f32 - 0.5) * 10.0);
                if y < -300.0 {
                    heights[r * w + c] = 500.0 + 2.0 * (-300.0 - y); // 63°: bare rock
                }
                fade[r * w + c] = if x < -450.0 { 1.0 } else if x < -400.0 { 0.5 } else { 0.0 };
            }
        }
        let ground = crate::render::terrain::GroundGrid {
            heights: Grid { width: w, height: h, data: heights },
            cell_x: 10.0,
            cell_y: 10.0,
            origin: [-500.0, -500.0],
            stream: vec![],
            wetness: vec![],
            fade,
            focus: Some(([0.0, 0.0], [1000.0, 1000.0])),
        };
        let land = Landscape { ground, cover: LandCover::default() };
        let mut trees = Vec::new();
        for j in 0..125 {
            for i in 0..125 {
                let id = (j * 125 + i) as u64 + 1;
                let sp = if (i * 7 + j * 3) % 10 < 7 { 0 } else { 1 };
                let id = if sp == 1 { id | SAPLING_ID_BIT } else { id };
                trees.push(TreeInstance::new(id, [4.0 + 8.0 * i as f32, 4.0 + 8.0 * j as f32, 500.0], 25.0, 4.5, sp, [0.1, 0.4, 0.1]));
            }
        }
        assert!(land.surroundings(&[]).is_empty(), "nothing beyond a bare window");
        let far = land.surroundings(&trees);
        assert_eq!(far, land.surroundings(&trees), "deterministic");
        let by_id: std::collections::HashMap<u64, &TreeInstance> = trees.iter().map(|t| (t.id, t)).collect();
        let (mut n, mut sp1) = (0usize, 0usize);
        for t in &far {
            let [x, y, z] = t.position;
            assert!(!((0.0..=1000.0).contains(&x) && (0.0..=1000.0).contains(&y)), "beyond the window: {x} {y}");
            // the image of a window tree across the edges it is beyond
            let k = ((t.id >> 48) & 0xF) as usize;
            assert!((1..=8).contains(&k));
            let src = by_id[&(t.id ^ ((k as u64) << 48))];
            let (mx, my) = MIRRORS[k - 1];
            let mirror = |v: f32, m: i8| match m {
                -1 => -v,
                1 => 2000.0 - v,
                _ => v,
            };
            assert_eq!((x, y), (mirror(src.position[0], mx), mirror(src.position[1], my)));
            assert_eq!((t.species, t.height, t.crown_radius, t.id & SAPLING_ID_BIT), (src.species, src.height, src.crown_radius, src.id & SAPLING_ID_BIT));
            // on the ground there, off the cliff, not where it has faded away, fading with it
            assert!(y > -305.0 && (z - 500.0).abs() < 1e-3, "{x} {y} {z}");
            assert!(x > -455.0, "{x}");
            assert_eq!(t.sky_fade, if x < -400.0 { 0.5 } else { 0.0 }, "{x}");
            n += 1;
            sp1 += t.species as usize;
        }
        // all the ground that keeps trees does, at the window's density (15,625 trees per km²):
        // x from −450 m, y from −300 m to the grid's end at 1500 m, less the window; the
        // window's mix beyond it
        let want = 15_625.0 * (1950.0 * 1800.0 - 1e6) / 1e6;
        assert!((n as f64 / want - 1.0).abs() < 0.05, "{n} trees beyond the window, {want} expected");
        assert!((sp1 as f64 / n as f64 - 0.3).abs() < 0.02, "{sp1} of {n}");
    }

    /// A valley running at 30° to the grid: its D8 channel is a staircase of east and
    /// north-east steps. Drawn per cell (as before), the stream's centre in each column jumps
    /// about a straight line by a good part of a cell; drawn along the corner-cut centre lines
    /// of `stream_lines`, it runs straight.
    #[test]
    fn streams_are_drawn_without_the_d8_staircase() {
        use crate::grid::GeoRef;
        let n = 120usize;
        let (ca, sa) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let mut e = Grid::filled(n, n, 0.0f32);
        for r in 0..n {
            for c in 0..n {
                // window-local metres (x east, y north) of the cell centre, from the grid's centre
                let (x, y) = ((c as f32 + 0.5 - 0.5 * n as f32) * 10.0, (0.5 * n as f32 - r as f32 - 0.5) * 10.0);
                let (along, across) = (x * ca + y * sa, -x * sa + y * ca);
                *e.get_mut(c, r) = 500.0 + 0.08 * along + 0.25 * across.abs();
            }
        }
        let t = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: None, source: "test".into() };
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let g = &l.ground;
        let (w, h) = (g.heights.width, g.heights.height);
        // the same channel drawn per cell: the strength of the flow cell under each sample
        let m = crate::terrain::fields::mask(&t, f32::NEG_INFINITY);
        let filled = crate::terrain::fields::fill_depressions(&t, &m);
        let dir = crate::terrain::fields::flow_directions(&filled, &t.geo, &m);
        let acc = crate::terrain::fields::flow_accumulation(&dir, &m);
        let per_cell = |x: f32, y: f32| {
            let (c, r) = ((x / 10.0).floor(), n as f32 - 1.0 - (y / 10.0).floor());
            if c < 0.0 || r < 0.0 || c >= n as f32 || r >= n as f32 {
                return 0.0;
            }
            crate::render::terrain::stream_strength(*acc.get(c as usize, r as usize) * 100.0)
        };
        // per sample column inside the site: the strength-weighted mean y of the stream, then the
        // RMS of these means about their least-squares line (m)
        let roughness = |value: &dyn Fn(usize, usize) -> f32| {
            let mut pts = Vec::new();
            for c in 0..w {
                let x = g.origin[0] + (c as f32 + 0.5) * g.cell_x;
                if !(50.0..=1150.0).contains(&x) {
                    continue;
                }
                let (mut sw, mut sy) = (0.0f64, 0.0f64);
                for r in 0..h {
                    let y = g.origin[1] + (h as f32 - r as f32 - 0.5) * g.cell_y;
                    if (0.0..=1200.0).contains(&y) {
                        let v = value(c, r) as f64;
                        sw += v;
                        sy += v * y as f64;
                    }
                }
                if sw > 0.0 {
                    pts.push((x as f64, sy / sw));
                }
            }
            let k = pts.len() as f64;
            let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / k, pts.iter().map(|p| p.1).sum::<f64>() / k);
            let b = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            let rms = (pts.iter().map(|p| (p.1 - my - b * (p.0 - mx)).powi(2)).sum::<f64>() / k).sqrt();
            (pts.len(), b.atan().to_degrees(), rms)
        };
        let drawn = roughness(&|c, r| g.stream[r * w + c]);
        let raw = roughness(&|c, r| per_cell(g.origin[0] + (c as f32 + 0.5) * g.cell_x, g.origin[1] + (h as f32 - r as f32 - 0.5) * g.cell_y));
        eprintln!("stream columns, direction, RMS about the line: drawn {drawn:?}, per cell {raw:?}");
        // a long stream at about 30°
        assert!(drawn.0 >= 40 && (drawn.1 - 30.0).abs() < 3.0, "{drawn:?}");
        // per cell, the staircase shows (RMS of a few metres on 10 m cells); drawn, it is gone
        assert!(raw.2 > 2.0, "the per-cell drawing should show the staircase: {raw:?}");
        assert!(drawn.2 < 0.3 * raw.2 && drawn.2 < 0.8, "drawn {drawn:?}, per cell {raw:?}");
    }

    #[test]
    fn landscape_shows_the_dem_beyond_the_window_and_fades_out_at_its_edge() {
        use crate::grid::GeoRef;
        // a 60 x 40 DEM of 10 m: a plane rising 0.2 m/m eastwards, cut by a valley along row 20
        // draining west; a nodata block in the north-east
        let (w, h) = (60usize, 40usize);
        let mut e = Grid::filled(w, h, 0.0f32);
        for r in 0..h {
            for c in 0..w {
                *e.get_mut(c, r) = if c >= 40 && r < 8 { f32::NAN } else { 500.0 + 2.0 * c as f32 + 3.0 * (r as f32 - 20.0).abs() };
            }
        }
        let full = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: None, source: "test".into() };
        let win = [20, 10, 20, 20];
        let t = crate::terrain::io::window(&full, win[0], win[1], win[2], win[3]).unwrap();
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, Some((&full, win)), 10.0, f32::NEG_INFINITY).unwrap();
        let g = &l.ground;
        // margin: half the window's side (100 m = 10 samples) on every side
        assert_eq!((g.heights.width, g.heights.height, g.origin), (40, 40, [-100.0, -100.0]));
        let at = |x: f32, y: f32| {
            let c = ((x - g.origin[0]) / g.cell_x - 0.5).round() as usize;
            let r = (g.heights.height as f32 - (y - g.origin[1]) / g.cell_y - 0.5).round() as usize;
            r * g.heights.width + c
        };
        // inside the window: the site's heights, no fade
        let i = at(55.0, 75.0);
        assert_eq!(g.heights.data[i], site.elevation_at(55.0, 75.0));
        assert_eq!(g.fade[i], 0.0);
        // beyond it: the DEM (column 20 + (x - 5)/10 - ..., row of y) and a fade rising outwards
        let (x, y) = (-45.0f32, 75.0f32); // column 15, row 10 + 20 - 8 - 1 = 22 (north of the window's south edge)
        let (c, r) = ((20.0 + (x / 10.0) - 0.5).round() as usize, (10.0 + 20.0 - y / 10.0 - 0.5).round() as usize);
        assert_eq!(g.heights.data[at(x, y)], *full.elevation.get(c, r));
        let f_near = g.fade[at(-5.0, 75.0)];
        let f_mid = g.fade[at(-55.0, 75.0)];
        let f_far = g.fade[at(-95.0, 75.0)];
        assert!(f_near == 0.0 && f_mid > 0.0 && f_mid < f_far && f_far > 0.95, "{f_near} {f_mid} {f_far}");
        // the nodata corner (columns 40-59, rows 0-7: x ≥ 205 m, y ≥ 225 m) is filled flat and
        // faded out, although it is near the window
        let k = at(215.0, 235.0);
        assert!(g.heights.data[k].is_finite() && g.fade[k] > 0.95, "{}", g.fade[k]);
        assert!(g.fade[at(215.0, 165.0)] < 0.5, "the DEM south of it is shown: {}", g.fade[at(215.0, 165.0)]);
        // the valley floor (row 20: y = 95 m) is a stream, the slopes are not
        assert!(g.stream[at(-95.0, 95.0)] > 0.0 && g.stream[at(-95.0, 45.0)] == 0.0, "{} {}", g.stream[at(-95.0, 95.0)], g.stream[at(-95.0, 45.0)]);
        // the mesh's bounds are the window's: cameras frame the site, not its surroundings
        let m = l.mesh(&[]).unwrap();
        m.validate().unwrap();
        let (lo, hi) = m.bounds();
        assert!(lo[0] >= 0.0 && lo[1] >= 0.0 && hi[0] <= 200.0 && hi[1] <= 200.0 && hi[0] > 190.0, "{lo:?} {hi:?}");
        assert!(m.full_bounds().0[0] < -90.0);
        // forest floor under a crown
        let tree = TreeInstance::new(1, [105.0, 105.0, 600.0], 20.0, 20.0, 0, [0.1, 0.3, 0.1]);
        let m2 = l.mesh(&[tree]).unwrap();
        let v = at(105.0, 105.0);
        assert!(m2.colors[v][0] > m2.colors[v][1] && m.colors[v][1] > m.colors[v][0], "{:?} vs {:?}", m2.colors[v], m.colors[v]);
        // without surroundings the site's edges fade out within EDGE_FADE_M
        let alone = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let ga = &alone.ground;
        assert!(ga.fade.iter().all(|f| (0.0..=1.0).contains(f)) && ga.fade[0] > 0.99);
    }
}
/// A full scene for one snapshot: terrain, prototypes, instances, the sun of the site's
/// latitude on the season's day at 14:00 solar time, and a light westerly breeze.
pub fn scene(terrain: TerrainMesh, prototypes: Vec<Prototype>, instances: Vec<TreeInstance>, latitude_deg: f64, season: Season, sea_level: Option<f32>) -> Scene {
    Scene::new(terrain, sea_level, prototypes, instances, season_sun(latitude_deg, season), Sky::default(), Wind { direction: [1.0, 0.0], directed: 1.5, undirected: 1.0, time_s: 0.0 })
}
