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
//!    trees round a gap shade its lower sky.
//!
//! 4. The scenario's obstacles (`sim::obstacle::light_cells`) enter as opaque entries at their
//!    top height, with the leaf-area index whose transmission is the uncovered share of the cell.
//!
//! Cost O(E) for E ≈ 2–4 entries per tree (counting sort by cell, then a small sort per cell),
//! then O(log) per tree.

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
    let canopy = build_canopy(t, &grid, w.light.cols, &lai_c, w.obstacles);
    let ncell = cols * rows;
    let span = crate::sim::light_grid::Span::new(w.window, w.light);
    let shade = Shading::new(&canopy, &grid, w.light, w.site, span, w.light_site, w.rel_insolation);
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
                let rel = shade.rel(shade.whole_of(c));
                for &i in grid.cell(c) {
                    out.set(i as usize, shade.at(c, t.height[i as usize], rel));
                }
            }
        });
    }
    // the ground light of the span's cells only (a tile's: the cells regeneration reads)
    let ground: Vec<f32> = (0..span.len())
        .into_par_iter()
        .map(|k| {
            let c = span.cell(k);
            shade.at(shade.held_of(c), 0.0, shade.rel(c))
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
/// cells, the sun geometry of the site's latitude and the cells' relative insolation.
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
    span: crate::sim::light_grid::Span,
    light_site: &'a [u32],
    rel_insolation: &'a [f32],
    site: &'a SiteConditions,
    /// `Some` with `[light] diffuse = "sky"`: the sky's sectors and per held cell the tallest
    /// entry (m) within the sky's reach ([`reach_tops`]).
    sky: Option<(Sky, Vec<f32>)>,
    cell_m: f32,
}

impl<'a> Shading<'a> {
    fn new(canopy: &'a Canopy, grid: &SpatialGrid, light: &LightGrid, site: &'a SiteConditions, span: crate::sim::light_grid::Span, light_site: &'a [u32], rel_insolation: &'a [f32]) -> Self {
        let lat = site.geo.latitude_deg as f32;
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
            span,
            light_site,
            rel_insolation,
            site,
            sky: (light.diffuse == Diffuse::Sky).then(|| (Sky::standard_overcast(), reach_tops(canopy, grid.cols, light.read_cells()))),
            cell_m: light.cell_m as f32,
        }
    }
    /// The diffuse part's transmission (0–1) at height `z` (m) in held cell `c` whose canopy
    /// above `z` holds the leaf-area index `own`: `e^(−k own)` ([`Diffuse::Column`]) or
    /// [`Sky::transmission`] from the cell's centre ([`Diffuse::Sky`]).
    #[inline]
    fn diffuse(&self, c: usize, z: f32, own: f32) -> f32 {
        let Some((sky, tops)) = &self.sky else {
            return (-K_EXT * own).exp();
        };
        // in the whole grid's frame (a tile's held cells are offset), so that every tile count
        // rounds the rays' positions alike
        let (c0, r0) = (self.col0 as isize, self.row0 as isize);
        let (col, row) = ((c % self.cols) as isize + c0, (c / self.cols) as isize + r0);
        let (cols, rows) = (self.cols as isize, (self.canopy.start.len() - 1) as isize / self.cols as isize);
        let lai = |cc: isize, rr: isize, z0: f32, z1: f32| -> f32 {
            let (cc, rr) = (cc - c0, rr - r0);
            if cc < 0 || rr < 0 || cc >= cols || rr >= rows {
                return 0.0;
            }
            let k = (rr * cols + cc) as usize;
            self.canopy.lai_above(k, z0) - self.canopy.lai_above(k, z1)
        };
        let m = self.cell_m;
        sky.transmission(lai, ((col as f32 + 0.5) * m, (row as f32 + 0.5) * m), z, m, tops[c])
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
    /// Relative insolation of the whole grid's cell `c` (1 outside the span or where masked).
    #[inline]
    fn rel(&self, c: usize) -> f32 {
        let s = self.span.index(c).map_or(u32::MAX, |k| self.light_site[k]);
        if s == u32::MAX {
            1.0
        } else {
            self.rel_insolation[self.site.held(s as usize)]
        }
    }
    /// Light at height `z` (m) in held cell `c` of relative insolation `rel` (module docs, step 3).
    #[inline]
    fn at(&self, c: usize, z: f32, rel: f32) -> f32 {
        let own = self.canopy.lai_above(c, z);
        // the next row towards the equator, if the whole grid has it (then it is held)
        let r = (c / self.cols) as isize + self.drow;
        let g = self.row0 as isize + r;
        let sun = if g >= 0 && (g as usize) < self.whole_rows { self.canopy.lai_above(r as usize * self.cols + c % self.cols, z + self.rise) } else { 0.0 };
        rel * (W_ZENITH * self.diffuse(c, z, own) + (1.0 - W_ZENITH) * (-K_EXT * (0.5 * own + 0.5 * sun) / self.sin_e).exp())
    }
}

/// Per cell of `canopy` (held cells, `cols` a row) the tallest entry (m, 0 where none) over the
/// square of `n` cells on every side: a sky ray from the cell (which reads at most `n` cells
/// away, [`LightGrid::read_cells`]) meets nothing above it. A running maximum along the rows,
/// then along the columns; in a tiled run the squares of a tile's own cells lie inside its
/// held cells, so they are the same as in one process.
fn reach_tops(canopy: &Canopy, cols: usize, n: usize) -> Vec<f32> {
    let ncell = canopy.start.len() - 1;
    let rows = ncell / cols.max(1);
    let own: Vec<f32> = (0..ncell).map(|c| if canopy.start[c + 1] > canopy.start[c] { canopy.h[canopy.start[c] as usize] } else { 0.0 }).collect();
    let along: Vec<f32> = (0..ncell).into_par_iter().map(|c| {
        let (col, row) = (c % cols, c / cols);
        own[row * cols + col.saturating_sub(n)..row * cols + (col + n + 1).min(cols)].iter().copied().fold(0.0f32, f32::max)
    }).collect();
    (0..ncell).into_par_iter().map(|c| {
        let (col, row) = (c % cols, c / cols);
        (row.saturating_sub(n)..(row + n + 1).min(rows)).map(|r| along[r * cols + col]).fold(0.0f32, f32::max)
    }).collect()
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

    /// Diffuse transmission (0–1) at height `z` (m) over the point `(x, y)` (m, in the frame of
    /// the cells that `lai` reads: cell `(⌊x / cell_m⌋, ⌊y / cell_m⌋)`) of a canopy whose
    /// tallest entry is `top` (m). `lai(col, row, z0, z1)` is the leaf-area index of the canopy
    /// entries of a cell with top heights in `(z0, z1]` (0 outside the grid; `z1` may be +∞).
    /// Each crown's leaf area is a thin layer at its top height, as in the column model, so a
    /// sector's ray of zenith angle θ crosses the layer at height h at the horizontal distance
    /// `(h − z) tan θ` and meets its leaf-area index over the path `1 / cos θ`: the ray's
    /// transmission is `exp(−k Σ LAI / cos θ)` (Beer–Lambert for a spherical leaf angle
    /// distribution, extinction `0.5 / cos θ`, Campbell & Norman 1998 eq. 15.4), summed along
    /// the ray in steps of half a cell until it rises above `top`, passes [`SKY_REACH_M`] or
    /// is dark (`k Σ LAI / cos θ > 6`, a transmission under 0.25 %); the sectors' transmissions weighted as [`Sky`] says. A
    /// place at or above `top` sees the whole sky (1).
    pub fn transmission(&self, lai: impl Fn(isize, isize, f32, f32) -> f32, (x, y): (f32, f32), z: f32, cell_m: f32, top: f32) -> f32 {
        if z >= top {
            return 1.0;
        }
        let ds = 0.5 * cell_m;
        let reach = SKY_REACH_M as f32;
        let cell = |px: f32, py: f32| ((px / cell_m).floor() as isize, (py / cell_m).floor() as isize);
        let mut total = 0.0f32;
        for &([sx, cy], tan, sec, w) in &self.sectors {
            let mut depth = 0.0f32; // k Σ LAI / cos θ
            let (mut s, mut za) = (0.0f32, z);
            while s < reach {
                let s1 = s + ds;
                let zb = z + s1 / tan;
                let mid = s + 0.5 * ds;
                let (cc, rr) = cell(x + sx * mid, y + cy * mid);
                depth += K_EXT * sec * lai(cc, rr, za, zb);
                if zb > top || depth > 6.0 {
                    break;
                }
                (s, za) = (s1, zb);
            }
            total += w * (-depth).exp();
        }
        total
    }
}

/// Relative light (0–1.5, as [`run`] gives a tree or the ground) at height `z_m` (m above the
/// ground) over every cell of the light grid `light` (row 0 south, one process: no window),
/// under the crowns of `trees` and the `obstacles`' entries; the arguments are those of
/// [`Light`]. For measurements (the light under closed stands, issue 35 round 41:
/// `examples/understorey_light.rs`); the simulation reads only the ground's ([`Light::ground_light`]).
#[allow(clippy::too_many_arguments)]
pub fn cell_light_at(trees: &TreeStore, light: &LightGrid, site: &SiteConditions, lib: &SpeciesLibrary, light_site: &[u32], rel_insolation: &[f32], obstacles: &[(u64, f32)], z_m: f32) -> Vec<f32> {
    let grid = SpatialGrid::build_in(trees, light, held_cells(trees, light, None));
    let lai_c: Vec<f32> = lib.species.iter().map(|s| crown_lai(s.life.shade_tolerance)).collect();
    let canopy = build_canopy(trees, &grid, light.cols, &lai_c, obstacles);
    let span = crate::sim::light_grid::Span::new(None, light);
    let shade = Shading::new(&canopy, &grid, light, site, span, light_site, rel_insolation);
    (0..light.len()).into_par_iter().map(|c| shade.at(shade.held_of(c), z_m, shade.rel(c))).collect()
}

/// The canopy of `t` on the cells of `grid` (those it holds, of a light grid of `whole_cols`
/// columns) plus the obstacles' entries there: per band of
/// [`BAND_ROWS`] rows (in parallel) the entries of every tree whose crown reaches the band
/// (found through `grid`), bucketed by cell and sorted within a cell by (key, leaf area), a
/// total order, so the canopy does not depend on the scheduling or on the order of stamping.
fn build_canopy(t: &TreeStore, grid: &SpatialGrid, whole_cols: usize, lai_c: &[f32], obstacles: &[(u64, f32)]) -> Canopy {
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
    let bands: Vec<(Vec<u32>, Vec<f32>, Vec<f32>)> = (0..nbands)
        .into_par_iter()
        .map(|b| {
            let (ra, rb) = (b * BAND_ROWS, ((b + 1) * BAND_ROWS).min(rows));
            let mut ent: Vec<(u64, f32)> = Vec::new();
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
                    let inv = u32::MAX - t.height[i].max(0.0).to_bits();
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
                                ent.push((c << 32 | inv as u64, la * f / cell_area));
                            }
                        }
                    }
                }
            }
            let (ka, kb) = (ra * cols, rb * cols);
            ent.extend(obstacles.iter().filter(|e| ((e.0 >> 32) as usize) >= ka && ((e.0 >> 32) as usize) < kb));
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
            let mut sorted = vec![(0u64, 0f32); ent.len()];
            for e in ent {
                let p = &mut pos[(e.0 >> 32) as usize - ka];
                sorted[*p as usize] = e;
                *p += 1;
            }
            let mut h = Vec::with_capacity(sorted.len());
            let mut cum = Vec::with_capacity(sorted.len());
            let mut a = 0usize;
            for &n in &count {
                let seg = &mut sorted[a..a + n as usize];
                seg.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.to_bits().cmp(&b.1.to_bits())));
                let mut acc = 0.0;
                for e in seg.iter() {
                    acc += e.1;
                    h.push(f32::from_bits(u32::MAX - (e.0 as u32)));
                    cum.push(acc);
                }
                a += n as usize;
            }
            (count, h, cum)
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
    for (_, bh, bc) in bands {
        h.extend_from_slice(&bh);
        cum.extend_from_slice(&bc);
    }
    Canopy { start, h, cum }
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

    /// Analytic cases: an open sky transmits 1; a boundless layer of leaf-area index L at height
    /// H above the place is crossed once by every ray (within the reach), so the transmission is
    /// `Σ w_j e^(−k L / cos θ_j)`; a place above the canopy sees the whole sky; a wall of canopy
    /// only to the north darkens the northern sectors only.
    #[test]
    fn sky_transmission_through_analytic_canopies() {
        let sky = Sky::standard_overcast();
        let open = sky.transmission(|_, _, _, _| 0.0, (52.5, 52.5), 1.3, 5.0, 30.0);
        assert!((open - 1.0).abs() < 1e-5, "{open}");
        let (l, h) = (3.0f32, 10.0f32);
        let layer = |_: isize, _: isize, z0: f32, z1: f32| if h > z0 && h <= z1 { l } else { 0.0 };
        let t = sky.transmission(layer, (52.5, 52.5), 0.0, 5.0, h);
        let dz = std::f32::consts::FRAC_PI_2 / SKY_BANDS as f32;
        let want: f32 = sky.sectors.iter().enumerate().map(|(i, s)| s.3 * (-K_EXT * l / (((i / SKY_AZIMUTHS) as f32 + 0.5) * dz).cos()).exp()).sum();
        assert!((t - want).abs() < 1e-5 && t < (-K_EXT * l).exp(), "{t} {want}");
        assert_eq!(sky.transmission(layer, (52.5, 52.5), 12.0, 5.0, h), 1.0);
        // a dense canopy north of y = 60 m (the place on that line): the southern half of the
        // sky stays open, the northern half is dark
        let north = |_: isize, r: isize, z0: f32, z1: f32| if r >= 12 && h > z0 && h <= z1 { 40.0 } else { 0.0 };
        let t = sky.transmission(north, (52.5, 60.0), 0.0, 5.0, h);
        assert!((t - 0.5).abs() < 0.02, "{t}");
    }
}
