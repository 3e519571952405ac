//! Light: a height-sorted canopy grid with Beer–Lambert attenuation along sun directions.
//!
//! Model (documented choice): a *ray-cast canopy grid* in the spirit of SORTIE's gap light
//! index (Pacala et al. 1996) and the ForClim/JABOWA height-sorted leaf-area profile
//! (Bugmann 2001, Climatic Change 51:259), not iLand's pre-computed light influence patterns.
//! 1. Each tree spreads its leaf area `LA = π r² · LAI_crown` over the light cells its crown
//!    covers (area-weighted), as an entry at its top height.
//! 2. Per light cell the entries are sorted by height; `LAI_above(c, z)` is the leaf-area index
//!    of all entries taller than `z` (binary search on the cumulative profile).
//! 3. A tree's light (0–1.5, relative to open flat ground) is
//!    `I_rel · [w_z·e^(−k·LAI_above(c, h)) + w_s·e^(−k·(½ LAI_above(c, h) + ½ LAI_above(c_sun, h + d·tan E)) / sin E)]`
//!    with Beer–Lambert extinction `k = 0.5`, the zenith (diffuse) weight `w_z = 0.35`, the sun
//!    weight `w_s = 0.65`, `E = 90° − |latitude|` the equinox noon sun elevation, `c_sun` the
//!    neighbouring cell towards the equator at distance `d` (one cell), and `I_rel` the cell's
//!    insolation relative to the terrain's median (terrain shading, slope and aspect).
//!
//!    With `[light] diffuse = "sky"` ([`Diffuse::Sky`]) the zenith term `e^(−k·LAI_above(c, h))`
//!    becomes the sky's: the hemisphere in zenith bands and azimuth sectors weighted by the
//!    standard overcast sky, each sector's ray followed through the neighbouring cells' canopy
//!    ([`Sky`], after Canham 1988's gap light index and SORTIE, Pacala et al. 1996), so the
//!    trees round a gap shade its lower sky. There each crown's leaf area is spread over its
//!    depth (crown base to top) in layers of [`SKY_LAYER_M`], and a sector's sums along its rays
//!    are a sheared running sum over the layers for all cells at once ([`sky_diffuse`], after
//!    Yi et al.'s shadow propagation in a voxel light space; round 45).
//!
//! 4. The scenario's obstacles (`sim::obstacle::light_cells`) enter as opaque entries at their
//!    top height, with the leaf-area index whose transmission is the uncovered share of the cell.
//!
//! Cost O(E) for E ≈ 2–4 entries per tree (counting sort by cell, then a small sort per cell),
//! then O(log) per tree; with the sky, 48 sectors × (layers × cells integer adds + places
//! exponentials).

use crate::conditions::SiteConditions;
use crate::sim::light_grid::{CellRect, Diffuse, LightGrid, SKY_REACH_M};
use crate::sim::trees::{SpatialGrid, TreeStore};
use crate::species::SpeciesLibrary;
use rayon::prelude::*;

/// Beer–Lambert extinction coefficient (dimensionless; defined in
/// [`crate::sim::light_grid::EXTINCTION_K`], where the obstacles' entries read it too).
pub const K_EXT: f32 = crate::sim::light_grid::EXTINCTION_K;
/// Weight of the diffuse part (the zenith direction, or the sky with [`Diffuse::Sky`]).
pub const W_ZENITH: f32 = 0.35;

/// Leaf-area index of a crown (m² leaf per m² crown projection) by shade tolerance (1–5):
/// `2 + 0.5 · ST` (tolerant species carry deeper, denser crowns). ESTIMATE without a source:
/// what the light phase shades with (and the hemispherical photograph, `job::hemi`, compared
/// with it). Drawn crowns take the species' sourced leaf-area index where its file gives one
/// (`job::leaf_area::drawn_crown_lai`, round 36), e.g. Norway spruce 10.0 against 3.6 here.
/// Round 41 (issue 35) measured closed pure stands passing 24–27 % of full light to the floor
/// with it, and tried the sourced values (docs/management.md, "Round 41").
#[inline]
pub fn crown_lai(shade_tolerance: f32) -> f32 {
    2.0 + 0.5 * shade_tolerance
}

/// Leaf area (m², one-sided) of a crown of radius `crown_radius_m` (m) of a species of shade
/// tolerance `shade_tolerance` (1–5): [`crown_lai`] × the crown projection `π r²` (r at least
/// 0.05 m), the leaf area the light phase spreads over the light cells the crown covers (drawn
/// trees take `job::leaf_area::drawn_leaf_area` since round 36).
#[inline]
pub fn crown_leaf_area(shade_tolerance: f32, crown_radius_m: f32) -> f32 {
    let r = crown_radius_m.max(0.05);
    std::f32::consts::PI * r * r * crown_lai(shade_tolerance)
}

/// The sorted canopy of one year.
pub struct Canopy {
    /// Per cell `start[c]..start[c+1]` into `h` / `cum`.
    pub start: Vec<u32>,
    /// Entry heights (m), descending within a cell.
    pub h: Vec<f32>,
    /// Cumulative LAI including the entry.
    pub cum: Vec<f32>,
    /// Crown base (m, 0 ≤ base ≤ the entry's height) per entry with `[light] diffuse = "sky"`
    /// (the crown's leaf area spread evenly from its base to its top, [`Canopy::lai_between`]);
    /// empty with the column model, which keeps each crown's leaf area at its top. An
    /// obstacle's entry has its base at its top (a thin opaque layer).
    pub base: Vec<f32>,
}

impl Canopy {
    /// LAI of entries in cell `c` taller than `z` (m).
    #[inline]
    pub fn lai_above(&self, c: usize, z: f32) -> f32 {
        let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
        let n = self.h[a..b].partition_point(|&h| h > z);
        if n == 0 {
            0.0
        } else {
            self.cum[a + n - 1]
        }
    }

    /// Leaf-area index of cell `c` between the heights `z0 < z1` (m) with the crowns' depth
    /// ([`Canopy::base`], which must be filled): each entry's leaf-area index spread evenly over
    /// its crown from `base` to its top `h`, of which the share `|[base, h] ∩ [z0, z1]| / (h −
    /// base)` lies between the heights; an entry shallower than 1 mm is a layer at its top,
    /// counted when `z0 < h ≤ z1`. Entries at or below `z0` (the tree itself at its top) count 0.
    pub fn lai_between(&self, c: usize, z0: f32, z1: f32) -> f32 {
        let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
        // only the entries taller than z0 (the first ones, heights descending) reach above it
        let n = self.h[a..b].partition_point(|&h| h > z0);
        let mut sum = 0.0f32;
        for e in a..a + n {
            let lai = self.cum[e] - if e > a { self.cum[e - 1] } else { 0.0 };
            sum += lai * depth_share(self.base[e], self.h[e], z0, z1);
        }
        sum
    }
}

/// The share (0–1) of a crown from `base` to `top` (m) that lies between the heights `z0` and
/// `z1` (m), its leaf area spread evenly over its depth; a crown shallower than 1 mm is a layer at
/// its top, all of it between the heights when `z0 < top ≤ z1`.
#[inline]
fn depth_share(base: f32, top: f32, z0: f32, z1: f32) -> f32 {
    let len = top - base;
    if len < 1e-3 {
        return (top > z0 && top <= z1) as u8 as f32;
    }
    ((top.min(z1) - base.max(z0)) / len).max(0.0)
}

/// What the light phase reads (the light grid, the site's latitude, the species' crown LAI,
/// the light cells' site cells and relative insolation, the trees) and writes (each tree's
/// light, the ground light per light cell, the spatial hash of the trees).
pub struct Light<'a> {
    /// The light grid (row 0 south).
    pub light: &'a LightGrid,
    /// Site conditions (latitude for the sun elevation).
    pub site: &'a SiteConditions,
    /// Species library (crown leaf-area index from the shade tolerance).
    pub lib: &'a SpeciesLibrary,
    /// Site cell per light cell of the span of `window` (`u32::MAX` where masked;
    /// [`crate::sim::light_grid::Span`]: the whole grid for one process, the tile's cells for a
    /// tile). A tree on a cell outside the span (a halo copy, whose light is dropped with it) is
    /// lit as if unmasked.
    pub light_site: &'a [u32],
    /// Relative insolation per site cell held (element [`SiteConditions::held`] of a site cell).
    pub rel_insolation: &'a [f32],
    /// Opaque canopy entries of the scenario's obstacles (`sim::obstacle::light_cells`: key
    /// cell << 32 | inverted top height bits, leaf-area index), stamped with the trees'.
    pub obstacles: &'a [(u64, f32)],
    /// Trees: read; `light` written.
    pub trees: &'a mut TreeStore,
    /// Written: relative light at the ground per light cell of the span of `window`.
    pub ground_light: &'a mut Vec<f32>,
    /// Written: the local top height (m, ≥ 0) per light cell of the span of `window`: the
    /// tallest canopy entry over the cell (the top of the tallest crown whose projection
    /// overlaps it, or of an obstacle), 0 where none. Mortality and regeneration take a tree or
    /// sapling below [`crate::sim::phases::mortality::UPPER_LAYER_SHARE`] of it to stand below
    /// the upper layer (shade mortality, issue 35).
    pub canopy_top: &'a mut Vec<f32>,
    /// Written: spatial hash of the trees on the light grid.
    pub grid: &'a mut SpatialGrid,
    /// Only these light cells' ground light is computed and held (a tile's,
    /// [`crate::sim::tiles`]: regeneration reads it on the tile's cells only), and `light_site`
    /// is over them. `None`: every cell.
    pub window: Option<crate::sim::light_grid::CellRect>,
}

/// The trees' slots of the light column, written from several threads: every tree index
/// appears exactly once in the spatial grid (`SpatialGrid::items` is a permutation of the
/// indices), so no two writes go to one slot.
struct Slots(*mut f32, usize);
// SAFETY: the pointer is only written through `set`, at distinct indices (see above), while the
// vector it points into is alive and not otherwise accessed.
unsafe impl Sync for Slots {}
impl Slots {
    #[inline]
    fn set(&self, i: usize, v: f32) {
        assert!(i < self.1);
        // SAFETY: in bounds (checked), and no other thread writes index i (see the type docs).
        unsafe { *self.0.add(i) = v }
    }
}

/// Rows of light cells per band of the canopy build (each band is stamped, bucketed and sorted
/// on its own, in parallel).
const BAND_ROWS: usize = 32;

/// The light cells whose canopy the light phase builds and reads: every cell of `light` when
/// `window` is `None` (one process); else the cells of `trees` (a tile's own trees and halo
/// copies, [`crate::sim::tiles`]) and of `window` (its ground light), one row wider on each side
/// (the row towards the equator that a cell's light also reads), clipped to the grid (issue 37
/// Build 1). Every canopy entry a tree or ground cell there reads lies inside: its entries come
/// from the crowns of `trees` only.
pub fn held_cells(trees: &TreeStore, light: &LightGrid, window: Option<CellRect>) -> CellRect {
    let Some(win) = window else {
        return CellRect { col0: 0, row0: 0, col1: light.cols, row1: light.rows };
    };
    let (mut c0, mut r0, mut c1, mut r1) = (win.col0.min(light.cols), win.row0.min(light.rows), win.col1.min(light.cols), win.row1.min(light.rows));
    if c0 >= c1 || r0 >= r1 {
        (c0, r0, c1, r1) = (usize::MAX, usize::MAX, 0, 0);
    }
    let cr = |x: f32, y: f32| light.col_row(light.cell_of(x, y));
    let (tc0, tr0, tc1, tr1) = trees.x.par_iter().zip(&trees.y).with_min_len(1 << 14).map(|(&x, &y)| {
        let (c, r) = cr(x, y);
        (c, r, c + 1, r + 1)
    }).reduce(|| (usize::MAX, usize::MAX, 0, 0), |a, b| (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3)));
    (c0, r0, c1, r1) = (c0.min(tc0), r0.min(tr0), c1.max(tc1), r1.max(tr1));
    if c0 >= c1 {
        // no tree and an empty window: one cell
        return CellRect { col0: 0, row0: 0, col1: 1, row1: 1 };
    }
    match light.diffuse {
        Diffuse::Column => CellRect { col0: c0, row0: r0.saturating_sub(1), col1: c1, row1: (r1 + 1).min(light.rows) },
        // the sky's rays read every direction
        Diffuse::Sky => {
            let n = light.read_cells();
            CellRect { col0: c0.saturating_sub(n), row0: r0.saturating_sub(n), col1: (c1 + n).min(light.cols), row1: (r1 + n).min(light.rows) }
        }
    }
}

/// Builds the spatial grid and canopy over the cells [`held_cells`] (the whole grid in one
/// process, a tile's trees' and own cells in a tiled run), and sets every tree's light and the
/// ground light and local top height ([`Light::canopy_top`]) of the cells of `window`.
pub fn run(w: Light<'_>) {
    let grid = SpatialGrid::build_in(&w.trees, &w.light, held_cells(&w.trees, &w.light, w.window));
    let (cols, rows) = (grid.cols, grid.rows);
    let t = &w.trees;
    let lai_c: Vec<f32> = w.lib.species.iter().map(|s| crown_lai(s.life.shade_tolerance)).collect();
    let sky = w.light.diffuse == Diffuse::Sky;
    let canopy = build_canopy(t, &grid, w.light.cols, &lai_c, w.obstacles, sky);
    let ncell = cols * rows;
    let span = crate::sim::light_grid::Span::new(w.window, w.light);
    let shade = Shading::new(&canopy, &grid, w.light, w.site.geo.latitude_deg);
    let rel = Rel { span, light_site: w.light_site, rel_insolation: w.rel_insolation, site: w.site };
    // with the sky, the diffuse part of every tree (in the spatial grid's order) and of every
    // ground cell of the span (after them), all at once (`sky_diffuse`)
    let diffuse: Vec<f32> = if sky {
        let mut q: Vec<(u32, f32)> = Vec::with_capacity(t.len() + span.len());
        for c in 0..ncell {
            q.extend(grid.cell(c).iter().map(|&i| (c as u32, t.height[i as usize])));
        }
        q.extend((0..span.len()).map(|k| (shade.held_of(span.cell(k)) as u32, 0.0)));
        sky_diffuse(&Sky::standard_overcast(), &canopy, cols, w.light.cell_m as f32, &q)
    } else {
        Vec::new()
    };
    let diffuse_at = |p: usize| diffuse.get(p).copied();
    // Trees are queried cell by cell (the spatial grid's order), so that the canopy profile of
    // a cell is read once from memory for all its trees; each value is written straight to its
    // tree's slot (blocks of cells in parallel).
    const BLOCK: usize = 2048;
    let mut light = vec![0f32; t.len()];
    {
        let out = Slots(light.as_mut_ptr(), light.len());
        (0..ncell.div_ceil(BLOCK)).into_par_iter().for_each(|b| {
            let (c0, c1) = (b * BLOCK, ((b + 1) * BLOCK).min(ncell));
            for c in c0..c1 {
                let r = rel.of(shade.whole_of(c));
                let p0 = grid.start[c] as usize;
                for (j, &i) in grid.cell(c).iter().enumerate() {
                    out.set(i as usize, shade.at(c, t.height[i as usize], r, diffuse_at(p0 + j)));
                }
            }
        });
    }
    // the ground light of the span's cells only (a tile's: the cells regeneration reads)
    let nt = t.len();
    let ground: Vec<f32> = (0..span.len())
        .into_par_iter()
        .map(|k| {
            let c = span.cell(k);
            shade.at(shade.held_of(c), 0.0, rel.of(c), diffuse_at(nt + k))
        })
        .collect();
    // the tallest entry over each of the span's cells (the first of its descending heights)
    let top: Vec<f32> = (0..span.len())
        .into_par_iter()
        .map(|k| {
            let c = shade.held_of(span.cell(k));
            let a = canopy.start[c] as usize;
            if (canopy.start[c + 1] as usize) > a {
                canopy.h[a]
            } else {
                0.0
            }
        })
        .collect();
    w.trees.light = light;
    *w.ground_light = ground;
    *w.canopy_top = top;
    *w.grid = grid;
}

/// What a tree's light formula reads (module docs, step 3): the sorted canopy of the held
/// cells and the sun geometry of the site's latitude.
struct Shading<'a> {
    canopy: &'a Canopy,
    cols: usize,
    row0: usize,
    col0: usize,
    whole_cols: usize,
    whole_rows: usize,
    drow: isize,
    rise: f32,
    sin_e: f32,
}

/// The light cells' relative insolation (module docs, step 3: `I_rel`).
struct Rel<'a> {
    span: crate::sim::light_grid::Span,
    light_site: &'a [u32],
    rel_insolation: &'a [f32],
    site: &'a SiteConditions,
}

impl Rel<'_> {
    /// Relative insolation of the whole grid's cell `c` (1 outside the span or where masked).
    #[inline]
    fn of(&self, c: usize) -> f32 {
        let s = self.span.index(c).map_or(u32::MAX, |k| self.light_site[k]);
        if s == u32::MAX {
            1.0
        } else {
            self.rel_insolation[self.site.held(s as usize)]
        }
    }
}

impl<'a> Shading<'a> {
    fn new(canopy: &'a Canopy, grid: &SpatialGrid, light: &LightGrid, latitude_deg: f64) -> Self {
        let lat = latitude_deg as f32;
        // the equinox's noon sun (crate::sun), kept within 10–80° above the horizon: the shading
        // geometry below looks one light row towards the equator at `cell · tan e` higher, which
        // a sun near the zenith (tan e → ∞) or the horizon (sin e → 0) would break
        let elev = crate::sun::noon_equinox_elevation_deg(lat).clamp(10.0, 80.0).to_radians();
        Shading {
            canopy,
            cols: grid.cols,
            row0: grid.row0,
            col0: grid.col0,
            whole_cols: light.cols,
            whole_rows: light.rows,
            drow: crate::sun::equatorward(lat) as isize, // towards the equator (row 0 is south here)
            rise: light.cell_m as f32 * elev.tan(),
            sin_e: elev.sin(),
        }
    }
    /// The whole grid's cell of held cell `c`.
    #[inline]
    fn whole_of(&self, c: usize) -> usize {
        (self.row0 + c / self.cols) * self.whole_cols + self.col0 + c % self.cols
    }
    /// The held cell of the whole grid's cell `g`.
    #[inline]
    fn held_of(&self, g: usize) -> usize {
        (g / self.whole_cols - self.row0) * self.cols + g % self.whole_cols - self.col0
    }
    /// The diffuse and direct parts' transmissions (0–1) at height `z` (m) in held cell `c`
    /// (module docs, step 3): the diffuse part is `sky` where given ([`sky_diffuse`]), else the
    /// column's `e^(−k LAI_above)`.
    #[inline]
    fn parts(&self, c: usize, z: f32, sky: Option<f32>) -> (f32, f32) {
        let own = self.canopy.lai_above(c, z);
        // the next row towards the equator, if the whole grid has it (then it is held)
        let r = (c / self.cols) as isize + self.drow;
        let g = self.row0 as isize + r;
        let sun = if g >= 0 && (g as usize) < self.whole_rows { self.canopy.lai_above(r as usize * self.cols + c % self.cols, z + self.rise) } else { 0.0 };
        (sky.unwrap_or_else(|| (-K_EXT * own).exp()), (-K_EXT * (0.5 * own + 0.5 * sun) / self.sin_e).exp())
    }
    /// Light at height `z` (m) in held cell `c` of relative insolation `rel` (module docs, step
    /// 3), with the diffuse part `sky` where given ([`Shading::parts`]).
    #[inline]
    fn at(&self, c: usize, z: f32, rel: f32, sky: Option<f32>) -> f32 {
        let (d, s) = self.parts(c, z, sky);
        rel * (W_ZENITH * d + (1.0 - W_ZENITH) * s)
    }
}

/// The sky hemisphere of the diffuse part with `[light] diffuse = "sky"`, as the gap light
/// index of Canham (1988, Can. J. For. Res. 18:1731) and SORTIE (Canham et al. 1990; Pacala et
/// al. 1996) divide it: [`SKY_BANDS`] zenith bands of 90°/[`SKY_BANDS`] and [`SKY_AZIMUTHS`]
/// azimuth sectors, each sector one ray at its centre. A band's weight is its share of the
/// diffuse irradiance on a horizontal surface under the standard overcast sky (SOC, Moon &
/// Spencer 1942: radiance `L(θ) = L_z (1 + 2 cos θ) / 3`), `∫ L(θ) cos θ sin θ dθ`, which with
/// `F(μ) = μ²/2 + 2μ³/3` (μ = cos θ) is `(F(cos θ_lo) − F(cos θ_hi)) / F(1)`, split evenly over
/// the azimuths. The weights sum to 1, so an open sky transmits 1.
#[derive(Debug, Clone)]
pub struct Sky {
    /// Per sector: (sin φ, cos φ) of its azimuth φ (clockwise from north: x east, y north),
    /// tan θ and 1 / cos θ of its zenith angle θ, and its weight (sum 1).
    pub sectors: Vec<([f32; 2], f32, f32, f32)>,
}

/// Zenith bands of [`Sky`] (15° each).
pub const SKY_BANDS: usize = 6;
/// Azimuth sectors of [`Sky`] (45° each).
pub const SKY_AZIMUTHS: usize = 8;

impl Sky {
    /// The [`SKY_BANDS`] × [`SKY_AZIMUTHS`] sectors under the standard overcast sky.
    pub fn standard_overcast() -> Sky {
        let f = |mu: f64| mu * mu / 2.0 + 2.0 * mu * mu * mu / 3.0;
        let dz = std::f64::consts::FRAC_PI_2 / SKY_BANDS as f64;
        let mut sectors = Vec::with_capacity(SKY_BANDS * SKY_AZIMUTHS);
        for j in 0..SKY_BANDS {
            let (lo, hi) = (j as f64 * dz, (j + 1) as f64 * dz);
            let w = (f(lo.cos()) - f(hi.cos())) / f(1.0) / SKY_AZIMUTHS as f64;
            let th = (lo + hi) / 2.0;
            for a in 0..SKY_AZIMUTHS {
                let phi = (a as f64 + 0.5) * std::f64::consts::TAU / SKY_AZIMUTHS as f64;
                sectors.push(([phi.sin() as f32, phi.cos() as f32], th.tan() as f32, (1.0 / th.cos()) as f32, w as f32));
            }
        }
        Sky { sectors }
    }
}

/// Height (m) of the horizontal layers in which [`sky_diffuse`] holds the canopy's leaf area.
/// Sylva choice: crowns of the default run are 3–20 m deep, and a ray 82.5° from the zenith
/// crosses a 2 m layer over 15 m (three 5 m cells).
pub const SKY_LAYER_M: f32 = 2.0;

/// Fixed-point units of [`sky_diffuse`]'s layers per unit of leaf-area index (a layer's cell
/// holds at most `u16::MAX / LAI_Q` ≈ 64, more than any crown's: obstacles give at most 20).
const LAI_Q: f32 = 1024.0;

/// The canopy's leaf-area index per layer of [`SKY_LAYER_M`] and light cell, in fixed point
/// (`LAI_Q` a unit), layer by layer: `q[m · cells + c]` for the layer from `m · SKY_LAYER_M` to
/// `(m + 1) · SKY_LAYER_M`, each crown's entry spread over its depth ([`Canopy::lai_between`]).
/// `n` layers reach the tallest entry.
struct Layers {
    n: usize,
    q: Vec<u16>,
}

impl Layers {
    fn build(canopy: &Canopy) -> Layers {
        let ncell = canopy.start.len() - 1;
        let dz = SKY_LAYER_M;
        let top = (0..ncell).map(|c| if canopy.start[c + 1] > canopy.start[c] { canopy.h[canopy.start[c] as usize] } else { 0.0 }).fold(0.0f32, f32::max);
        let n = (top / dz).floor() as usize + 1;
        // cell by cell (each cell's layers together), then turned layer by layer
        let by_cell: Vec<u16> = (0..ncell)
            .into_par_iter()
            .flat_map_iter(|c| {
                let mut v = vec![0f32; n];
                let (a, b) = (canopy.start[c] as usize, canopy.start[c + 1] as usize);
                for e in a..b {
                    let lai = canopy.cum[e] - if e > a { canopy.cum[e - 1] } else { 0.0 };
                    let (base, h) = (canopy.base[e], canopy.h[e]);
                    // the layers the crown reaches (one lower for a crown whose base lies on a
                    // layer's boundary: a thin one counts in the layer below its top)
                    let lo = ((base / dz).ceil() as usize).saturating_sub(1);
                    let hi = ((h / dz).floor() as usize).min(n - 1);
                    for (m, x) in v.iter_mut().enumerate().take(hi + 1).skip(lo) {
                        *x += lai * depth_share(base, h, m as f32 * dz, (m + 1) as f32 * dz);
                    }
                }
                v.into_iter().map(|x| (x * LAI_Q).round().min(u16::MAX as f32) as u16)
            })
            .collect();
        let mut q = vec![0u16; n * ncell];
        q.par_chunks_mut(ncell.max(1)).enumerate().for_each(|(m, layer)| {
            for (c, x) in layer.iter_mut().enumerate() {
                *x = by_cell[c * n + m];
            }
        });
        Layers { n, q }
    }
}

/// The diffuse part's transmission (0–1) from the sky ([`Sky`]) at each place `(c, z)` of
/// `places` (a held cell of `canopy`, `cols` cells a row of `cell_m` m, and a height z ≥ 0 m
/// above the ground, at the cell's centre), through the crowns of `canopy` with their depth
/// (its [`Canopy::base`] filled). The shadow propagation of a voxel light space (Yi, Li, Guo,
/// Deussen & Zhang 2015, Light-Guided Tree Modeling of Diverse Biomorphs, Pacific Graphics,
/// section 3: each node's shadow carried to the voxels beneath it), along each sky sector's
/// slanting direction as sheared running sums:
///
/// 1. The canopy's leaf area in layers ([`Layers`], [`SKY_LAYER_M`] high, fixed point).
/// 2. Per sector (zenith angle θ, azimuth φ, unit vector `u` of φ), a ray crossing the layer
///    `m` at cell `p` crosses the layer `m'` above at cell `p + S_m' − S_m`, where
///    `S_m = round((m + ½) · SKY_LAYER_M · tan θ · u / cell_m)` (the layers' centres). The
///    leaf-area index it meets from layer `m` up, within the layers `m … m + M` (the sky's reach,
///    below), is a running sum from the top down, one add (and one subtract) per cell and layer:
///    `D_m(p) = L_m(p) + D_{m+1}(p + S_{m+1} − S_m) − L_{m+M+1}(p + S_{m+M+1} − S_m)`, exact in
///    integers, so a tile's sums equal one process's wherever the ray stays among its held cells
///    (0 beyond them and beyond the grid: open sky).
/// 3. A place at height z in layer l meets the leaf area of its own cell above it in its layer
///    ([`Canopy::lai_between`], so a tree does not shade itself) and `D_{l+1}` at
///    `c + S_{l+1} − round(z · tan θ · u / cell_m)`: transmission `exp(−k Σ LAI / cos θ)`
///    (Beer–Lambert for a spherical leaf angle distribution, extinction `0.5 / cos θ`, Campbell &
///    Norman 1998 eq. 15.4; Monsi & Saeki 1953, Jpn. J. Bot. 14:22), weighted as [`Sky`] says.
///
/// The reach: `M = ⌊SKY_REACH_M / (SKY_LAYER_M tan θ) − 1.5⌋` layers, so a ray reads no cell
/// farther than `SKY_REACH_M / cell_m + 1` cells ([`LightGrid::read_cells`]); a ray 82.5° from
/// the zenith from the ground meets the canopy up to 20 m, the steeper ones all of it.
///
/// Cost per year: `48 · layers · cells` integer adds and `48 · places` exponentials, against r44l's
/// march of up to ~80 steps (a binary search each) per sector and place. The order of the sums
/// is fixed, so the result is the same for any thread count.
fn sky_diffuse(sky: &Sky, canopy: &Canopy, cols: usize, cell_m: f32, places: &[(u32, f32)]) -> Vec<f32> {
    let ncell = canopy.start.len() - 1;
    let rows = ncell / cols.max(1);
    let dz = SKY_LAYER_M;
    let layers = Layers::build(canopy);
    let n = layers.n;
    // the places by the layer `l + 1` whose sums they read (n: above every layer but the top's,
    // nothing above), with their own cell's leaf area above them in their layer
    let bucket = |z: f32| (((z.max(0.0) / dz).floor() as usize) + 1).min(n + 1);
    let mut count = vec![0usize; n + 2];
    for &(_, z) in places {
        count[bucket(z)] += 1;
    }
    let mut first = vec![0usize; n + 3];
    for b in 0..n + 2 {
        first[b + 1] = first[b] + count[b];
    }
    let mut order = vec![0u32; places.len()];
    {
        let mut pos = first.clone();
        for (i, &(_, z)) in places.iter().enumerate() {
            let b = bucket(z);
            order[pos[b]] = i as u32;
            pos[b] += 1;
        }
    }
    // (col, row, z, own leaf area above z in its layer), in bucket order
    let q: Vec<(i32, i32, f32, f32)> = order
        .par_iter()
        .map(|&i| {
            let (c, z) = places[i as usize];
            let c = c as usize;
            let l = (z.max(0.0) / dz).floor();
            let own = if (l as usize) < n { canopy.lai_between(c, z, (l + 1.0) * dz) } else { 0.0 };
            ((c % cols) as i32, (c / cols) as i32, z, own)
        })
        .collect();
    let mut acc = vec![0f32; places.len()];
    let (mut up, mut cur) = (vec![0u32; ncell], vec![0u32; ncell]);
    let at = |v: &[u32], cc: i32, rr: i32| -> u32 {
        if cc < 0 || rr < 0 || cc as usize >= cols || rr as usize >= rows {
            0
        } else {
            v[rr as usize * cols + cc as usize]
        }
    };
    for &([sx, cy], tan, sec, w) in &sky.sectors {
        let (ax, ay) = (sx * tan / cell_m, cy * tan / cell_m); // cells per metre of height
        let s: Vec<(i32, i32)> = (0..=n).map(|m| {
            let h = (m as f64 + 0.5) * dz as f64;
            ((h * ax as f64).round() as i32, (h * ay as f64).round() as i32)
        }).collect();
        let reach = ((SKY_REACH_M / (dz as f64 * tan as f64)) - 1.5).floor().max(0.0) as usize;
        let kc = K_EXT * sec;
        // the places reading layer m's sums from `d` (None: above the layers, nothing there)
        let answer = |acc: &mut [f32], b: usize, d: Option<&[u32]>| {
            let (a, e) = (first[b], first[b + 1]);
            acc[a..e].par_iter_mut().zip(&q[a..e]).with_min_len(1024).for_each(|(t, &(col, row, z, own))| {
                let lai = match d {
                    Some(d) => at(d, col + s[b].0 - (z * ax).round() as i32, row + s[b].1 - (z * ay).round() as i32) as f32 / LAI_Q,
                    None => 0.0,
                };
                let depth = kc * (lai + own);
                *t += w * if depth > 0.0 { (-depth).exp() } else { 1.0 };
            });
        };
        answer(&mut acc, n, None);
        answer(&mut acc, n + 1, None);
        for m in (1..n).rev() {
            let lm = &layers.q[m * ncell..(m + 1) * ncell];
            let d1 = (m + 1 < n).then(|| (s[m + 1].0 - s[m].0, s[m + 1].1 - s[m].1));
            let out = m + reach + 1;
            let d2 = (out < n).then(|| (&layers.q[out * ncell..(out + 1) * ncell], s[out].0 - s[m].0, s[out].1 - s[m].1));
            let upr = &up;
            cur.par_chunks_mut(cols).enumerate().with_min_len(8).for_each(|(r, row)| {
                for (o, &l) in row.iter_mut().zip(&lm[r * cols..(r + 1) * cols]) {
                    *o = l as u32;
                }
                // the sums of the layer above along the ray, and the layer leaving the reach
                if let Some((dx, dy)) = d1 {
                    if let Some((src, a, b)) = shifted(cols, rows, r, dx, dy) {
                        for (o, &x) in row[a..b].iter_mut().zip(&upr[src..src + (b - a)]) {
                            *o = o.wrapping_add(x);
                        }
                    }
                }
                if let Some((lo, dx, dy)) = d2 {
                    if let Some((src, a, b)) = shifted(cols, rows, r, dx, dy) {
                        for (o, &x) in row[a..b].iter_mut().zip(&lo[src..src + (b - a)]) {
                            *o = o.wrapping_sub(x as u32);
                        }
                    }
                }
            });
            answer(&mut acc, m, Some(&cur));
            std::mem::swap(&mut up, &mut cur);
        }
    }
    let mut out = vec![0f32; places.len()];
    for (k, &i) in order.iter().enumerate() {
        out[i as usize] = acc[k];
    }
    out
}

/// For row `r` of a grid of `cols` × `rows` cells read at the offset `(dx, dy)` cells: the
/// index of the first cell read and the columns `a..b` of row `r` whose cells `(col + dx, r +
/// dy)` lie in the grid (`None` where none do).
#[inline]
fn shifted(cols: usize, rows: usize, r: usize, dx: i32, dy: i32) -> Option<(usize, usize, usize)> {
    let rr = r as i64 + dy as i64;
    if rr < 0 || rr >= rows as i64 {
        return None;
    }
    let a = (-(dx as i64)).clamp(0, cols as i64) as usize;
    let b = (cols as i64 - dx as i64).clamp(0, cols as i64) as usize;
    (a < b).then(|| (rr as usize * cols + (a as i64 + dx as i64) as usize, a, b))
}

/// Relative light (0–1.5, as [`run`] gives a tree or the ground) at height `z_m` (m above the
/// ground) over every cell of the light grid `light` (row 0 south, one process: no window),
/// under the crowns of `trees` and the `obstacles`' entries; the arguments are those of
/// [`Light`]. For measurements (the light under closed stands, issue 35 round 41:
/// `examples/understorey_light.rs`); the simulation reads only the ground's ([`Light::ground_light`]).
#[allow(clippy::too_many_arguments)]
pub fn cell_light_at(trees: &TreeStore, light: &LightGrid, site: &SiteConditions, lib: &SpeciesLibrary, light_site: &[u32], rel_insolation: &[f32], obstacles: &[(u64, f32)], z_m: f32) -> Vec<f32> {
    let span = crate::sim::light_grid::Span::new(None, light);
    let rel = Rel { span, light_site, rel_insolation, site };
    light_parts_at(trees, light, site.geo.latitude_deg, lib, obstacles, None, z_m).into_par_iter().enumerate().map(|(c, (d, s))| rel.of(c) * (W_ZENITH * d + (1.0 - W_ZENITH) * s)).collect()
}

/// The diffuse and direct parts' transmissions (0–1, before the relative insolation; module
/// docs, step 3) at height `z_m` (m above the ground) over the light cells of `window` (`None`:
/// every cell of `light`; row by row from the south-west), under the crowns of `trees` and the
/// `obstacles`' entries, at the latitude `latitude_deg` (degrees); the diffuse part as
/// `light.diffuse` takes it. The light phase's formula ([`run`] builds the same canopy):
/// [`cell_light_at`] mixes them; the hemispherical photograph (`job::hemi`) compares the
/// diffuse part with its own.
pub fn light_parts_at(trees: &TreeStore, light: &LightGrid, latitude_deg: f64, lib: &SpeciesLibrary, obstacles: &[(u64, f32)], window: Option<CellRect>, z_m: f32) -> Vec<(f32, f32)> {
    let grid = SpatialGrid::build_in(trees, light, held_cells(trees, light, window));
    let lai_c: Vec<f32> = lib.species.iter().map(|s| crown_lai(s.life.shade_tolerance)).collect();
    let sky = light.diffuse == Diffuse::Sky;
    let canopy = build_canopy(trees, &grid, light.cols, &lai_c, obstacles, sky);
    let span = crate::sim::light_grid::Span::new(window, light);
    let shade = Shading::new(&canopy, &grid, light, latitude_deg);
    let held: Vec<usize> = (0..span.len()).map(|k| shade.held_of(span.cell(k))).collect();
    let diffuse = if sky {
        let places: Vec<(u32, f32)> = held.iter().map(|&c| (c as u32, z_m)).collect();
        sky_diffuse(&Sky::standard_overcast(), &canopy, grid.cols, light.cell_m as f32, &places)
    } else {
        Vec::new()
    };
    held.into_par_iter().enumerate().map(|(k, c)| shade.parts(c, z_m, diffuse.get(k).copied())).collect()
}

/// The canopy of `t` on the cells of `grid` (those it holds, of a light grid of `whole_cols`
/// columns) plus the obstacles' entries there, with the crowns' bases where `with_base`
/// ([`Canopy::base`]): per band of
/// [`BAND_ROWS`] rows (in parallel) the entries of every tree whose crown reaches the band
/// (found through `grid`), bucketed by cell and sorted within a cell by (key, leaf area), a
/// total order, so the canopy does not depend on the scheduling or on the order of stamping.
fn build_canopy(t: &TreeStore, grid: &SpatialGrid, whole_cols: usize, lai_c: &[f32], obstacles: &[(u64, f32)], with_base: bool) -> Canopy {
    let (cols, rows, cell) = (grid.cols, grid.rows, grid.cell_m);
    let (oc, or) = (grid.col0 as isize, grid.row0 as isize);
    // the obstacles' entries on the cells held, keyed by held cell
    let obstacles: Vec<(u64, f32)> = obstacles
        .iter()
        .filter_map(|&(k, v)| {
            let g = (k >> 32) as usize;
            let (col, row) = ((g % whole_cols) as isize - oc, (g / whole_cols) as isize - or);
            ((0..cols as isize).contains(&col) && (0..rows as isize).contains(&row)).then(|| (((row as usize * cols + col as usize) as u64) << 32 | (k & 0xffff_ffff), v))
        })
        .collect();
    let cell_area = (cell * cell) as f32;
    let ncell = cols * rows;
    // rows beyond its own that a crown can reach (half side of the equal-area square)
    let s_max = t.crown_radius.par_iter().with_min_len(1 << 14).map(|r| r.max(0.05) * 0.886_226_9).reduce(|| 0.0f32, f32::max);
    let reach = (s_max as f64 / cell).ceil() as usize + 2;
    let nbands = rows.div_ceil(BAND_ROWS);
    // 1. stamp entries (key = cell << 32 | inverted height bits → ascending key = cell, tallest first)
    let bands: Vec<(Vec<u32>, Vec<f32>, Vec<f32>, Vec<f32>)> = (0..nbands)
        .into_par_iter()
        .map(|b| {
            let (ra, rb) = (b * BAND_ROWS, ((b + 1) * BAND_ROWS).min(rows));
            // (key, leaf-area index, crown base): 16 bytes as (key, leaf-area index) alone
            let mut ent: Vec<(u64, f32, f32)> = Vec::new();
            for c in ra.saturating_sub(reach) * cols..(rb + reach).min(rows) * cols {
                for &i in grid.cell(c) {
                    let i = i as usize;
                    let r = t.crown_radius[i].max(0.05);
                    let s = r * 0.886_226_9; // half side of the equal-area square
                    let (x, y) = (t.x[i], t.y[i]);
                    // held rows and columns (the whole grid's less the offset)
                    let r0 = (crate::grid::floor_index((y - s) as f64 / cell) - or).max(ra as isize);
                    let r1 = (crate::grid::floor_index((y + s) as f64 / cell) - or).min(rows as isize - 1).min(rb as isize - 1);
                    if r0 > r1 {
                        continue;
                    }
                    // crown_leaf_area, with the species' crown LAI looked up once
                    let la = std::f32::consts::PI * r * r * lai_c[t.species[i] as usize];
                    let c0 = (crate::grid::floor_index((x - s) as f64 / cell) - oc).max(0);
                    let c1 = (crate::grid::floor_index((x + s) as f64 / cell) - oc).min(cols as isize - 1);
                    let top = t.height[i].max(0.0);
                    let inv = u32::MAX - top.to_bits();
                    let base = t.crown_base[i].clamp(0.0, top);
                    let sq = 4.0 * s * s;
                    for row in r0..=r1 {
                        let gr = row + or; // the whole grid's row and column, for the overlaps
                        let oy = ((y + s).min((gr + 1) as f32 * cell as f32) - (y - s).max(gr as f32 * cell as f32)).max(0.0);
                        for col in c0..=c1 {
                            let gc = col + oc;
                            let ox = ((x + s).min((gc + 1) as f32 * cell as f32) - (x - s).max(gc as f32 * cell as f32)).max(0.0);
                            let f = ox * oy / sq;
                            if f > 0.0 {
                                let c = row as u64 * cols as u64 + col as u64;
                                ent.push((c << 32 | inv as u64, la * f / cell_area, base));
                            }
                        }
                    }
                }
            }
            let (ka, kb) = (ra * cols, rb * cols);
            // an obstacle's entry is a thin layer at its top (base = top)
            ent.extend(obstacles.iter().filter(|e| ((e.0 >> 32) as usize) >= ka && ((e.0 >> 32) as usize) < kb).map(|&(k, v)| (k, v, f32::from_bits(u32::MAX - k as u32))));
            // bucket by cell (counting sort), then sort each cell's few entries
            let nb = kb - ka;
            let mut count = vec![0u32; nb];
            for e in &ent {
                count[(e.0 >> 32) as usize - ka] += 1;
            }
            let mut pos = Vec::with_capacity(nb);
            let mut acc = 0u32;
            for &n in &count {
                pos.push(acc);
                acc += n;
            }
            let mut sorted = vec![(0u64, 0f32, 0f32); ent.len()];
            for e in ent {
                let p = &mut pos[(e.0 >> 32) as usize - ka];
                sorted[*p as usize] = e;
                *p += 1;
            }
            let mut h = Vec::with_capacity(sorted.len());
            let mut cum = Vec::with_capacity(sorted.len());
            let mut base = Vec::with_capacity(if with_base { sorted.len() } else { 0 });
            let mut a = 0usize;
            for &n in &count {
                let seg = &mut sorted[a..a + n as usize];
                seg.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.to_bits().cmp(&b.1.to_bits())).then(a.2.to_bits().cmp(&b.2.to_bits())));
                let mut acc = 0.0;
                for e in seg.iter() {
                    acc += e.1;
                    h.push(f32::from_bits(u32::MAX - (e.0 as u32)));
                    cum.push(acc);
                    if with_base {
                        base.push(e.2);
                    }
                }
                a += n as usize;
            }
            (count, h, cum, base)
        })
        .collect();
    let n_entries: usize = bands.iter().map(|b| b.1.len()).sum();
    let mut start = Vec::with_capacity(ncell + 1);
    let mut acc = 0u32;
    for b in &bands {
        for &n in &b.0 {
            start.push(acc);
            acc += n;
        }
    }
    start.push(acc);
    // concatenated band by band, each band freed once copied
    let (mut h, mut cum) = (Vec::with_capacity(n_entries), Vec::with_capacity(n_entries));
    let mut base = Vec::with_capacity(if with_base { n_entries } else { 0 });
    for (_, bh, bc, bb) in bands {
        h.extend_from_slice(&bh);
        cum.extend_from_slice(&bc);
        base.extend_from_slice(&bb);
    }
    Canopy { start, h, cum, base }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sectors' weights are the standard overcast sky's shares of the horizontal diffuse
    /// irradiance: they sum to 1, and the zenith band's share is `1 − F(cos 15°) / F(1)` with
    /// `F(μ) = μ²/2 + 2μ³/3` (0.0852; a uniform sky would give sin² 15° = 0.067).
    #[test]
    fn sky_weights_are_the_standard_overcast_sky() {
        let sky = Sky::standard_overcast();
        assert_eq!(sky.sectors.len(), SKY_BANDS * SKY_AZIMUTHS);
        let total: f32 = sky.sectors.iter().map(|s| s.3).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        let f = |mu: f64| mu * mu / 2.0 + 2.0 * mu * mu * mu / 3.0;
        let zenith: f32 = sky.sectors[..SKY_AZIMUTHS].iter().map(|s| s.3).sum();
        let want = 1.0 - f(15f64.to_radians().cos()) / f(1.0);
        assert!((zenith as f64 - want).abs() < 1e-6 && (want - 0.0852).abs() < 1e-3, "{zenith} {want}");
    }
}
