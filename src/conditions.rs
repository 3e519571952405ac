//! Living conditions: terrain fields mapped to Ellenberg-style indices (L, T, K, F, R, N).
//!
//! OWNERSHIP NOTE (foundation): [`SiteConditions`] is the contract between terrain and the
//! simulation; fields may be added, not renamed.

pub use crate::climate::Climate;
use crate::grid::{GeoRef, Grid, Window};

/// Index of each Ellenberg factor in `[L, T, K, F, R, N]` arrays.
pub mod factor {
    /// Light.
    pub const L: usize = 0;
    /// Temperature.
    pub const T: usize = 1;
    /// Continentality.
    pub const K: usize = 2;
    /// Moisture.
    pub const F: usize = 3;
    /// Soil reaction.
    pub const R: usize = 4;
    /// Nitrogen.
    pub const N: usize = 5;
    /// Names in order.
    pub const NAMES: [&str; 6] = ["L", "T", "K", "F", "R", "N"];
}

/// All per-cell site data the simulation reads, on the terrain's grid (row 0 north).
#[derive(Debug, Clone)]
pub struct SiteConditions {
    /// Georeferencing of the grid.
    pub geo: GeoRef,
    /// Mean east–west cell size used for world coordinates (m).
    pub cell_x_m: f64,
    /// North–south cell size (m).
    pub cell_y_m: f64,
    /// `true` where trees may stand (valid data, above sea level).
    pub mask: Grid<bool>,
    /// Elevation (m above sea level); masked cells hold their raw value or 0.
    pub elevation_m: Grid<f32>,
    /// Slope (degrees, 0–90).
    pub slope_deg: Grid<f32>,
    /// Aspect (degrees clockwise from north, 0–360; −1 where flat).
    pub aspect_deg: Grid<f32>,
    /// Topographic wetness index ln(a / tan β) (dimensionless).
    pub twi: Grid<f32>,
    /// Annual clear-sky insolation with terrain shading (kWh/m²/yr).
    pub insolation_kwh_m2: Grid<f32>,
    /// Wind exposure (0 sheltered … 1 fully exposed).
    pub wind_exposure: Grid<f32>,
    /// Mean annual air temperature (°C).
    pub temperature_c: Grid<f32>,
    /// Ellenberg-style indices per cell, `[L, T, K, F, R, N]`, each on its 1–9 (F: 1–12) scale.
    pub indices: Grid<[f32; 6]>,
    /// The cells of the site's grid that the grids above hold (columns and rows of the whole
    /// grid, row 0 north): the whole grid ([`Window::full`] of [`SiteConditions::full`]), or, on
    /// a tile of a tiled run ([`SiteConditions::hold`], issue 37 Build 1), the tile's cells plus
    /// a halo. Cell `(col, row)` of the whole grid is element [`SiteConditions::held_index`] of
    /// every grid above.
    pub held: Window,
    /// Columns and rows of the whole site's grid (what [`SiteConditions::width`] and
    /// [`SiteConditions::height`] return; `held` lies inside it).
    pub full: (usize, usize),
}

impl SiteConditions {
    /// Width of the whole site's grid (columns; the grids held may be a window of it).
    pub fn width(&self) -> usize {
        self.full.0
    }
    /// Height of the whole site's grid (rows; the grids held may be a window of it).
    pub fn height(&self) -> usize {
        self.full.1
    }
    /// True when the grids hold the whole site (one process; not a tile's window).
    pub fn holds_all(&self) -> bool {
        self.held.width == self.full.0 && self.held.height == self.full.1
    }
    /// Element of the held grids of cell `(col, row)` of the whole grid (row 0 north), or
    /// `None` when the cell is not held.
    #[inline]
    pub fn held_index(&self, col: usize, row: usize) -> Option<usize> {
        let h = &self.held;
        (col >= h.col0 && col < h.col1() && row >= h.row0 && row < h.row1()).then(|| (row - h.row0) * h.width + (col - h.col0))
    }
    /// Element of the held grids of site cell `cell` (row-major over the whole grid, as
    /// [`SiteConditions::unmasked_cell`] gives it): `cell` itself when the whole site is held.
    /// Panics, naming the cell and the window, when the cell is not held (a reader outside the
    /// tile and halo its tiled run gave it: a defect, not bad input).
    #[inline]
    pub fn held(&self, cell: usize) -> usize {
        if self.holds_all() {
            return cell;
        }
        let (col, row) = (cell % self.full.0, cell / self.full.0);
        self.held_index(col, row).unwrap_or_else(|| panic!("site cell {cell} (column {col}, row {row}) outside the cells held ({})", self.held))
    }
    /// Site cell (row-major over the whole grid) of world point `(x, y)` (m, origin SW corner)
    /// when it is held and unmasked; `None` outside the site, on a masked cell or on a cell
    /// outside the held window.
    #[inline]
    pub fn unmasked_cell(&self, x: f64, y: f64) -> Option<usize> {
        let (c, r) = self.cell_at(x, y)?;
        let i = self.held_index(c, r)?;
        self.mask.data[i].then(|| r * self.full.0 + c)
    }
    /// Keeps of every grid only the cells of `w` (columns and rows of the whole grid, row 0
    /// north), which must lie inside the cells held: a tile's part of the site (issue 37
    /// Build 1). Readers then find cell `(col, row)` at [`SiteConditions::held_index`].
    /// Panics when `w` is not inside [`SiteConditions::held`].
    pub fn hold(&mut self, w: Window) {
        let o = self.held;
        self.mask = w.cut(&self.mask, &o);
        for g in [&mut self.elevation_m, &mut self.slope_deg, &mut self.aspect_deg, &mut self.twi, &mut self.insolation_kwh_m2, &mut self.wind_exposure, &mut self.temperature_c] {
            *g = w.cut(g, &o);
        }
        self.indices = w.cut(&self.indices, &o);
        self.held = w;
    }
    /// The cells of the whole grid (a window, row 0 north) that cover the world rectangle
    /// `[x0, x1) × [y0, y1)` (m, origin SW corner), widened by `halo` cells on every side and
    /// clipped to the grid.
    pub fn window_of(&self, x0: f64, y0: f64, x1: f64, y1: f64, halo: usize) -> Window {
        let (w, h) = self.full;
        let col = |x: f64| ((x.max(0.0) / self.cell_x_m) as usize).min(w.saturating_sub(1));
        let rs = |y: f64| ((y.max(0.0) / self.cell_y_m) as usize).min(h.saturating_sub(1));
        let (c0, c1) = (col(x0), col(x1));
        let (r0, r1) = (h - 1 - rs(y1), h - 1 - rs(y0));
        Window { col0: c0, row0: r0, width: c1 - c0 + 1, height: r1 - r0 + 1 }.with_halo(halo, w, h)
    }
    /// World extent (m): `(width · cell_x_m, height · cell_y_m)`.
    pub fn extent_m(&self) -> (f64, f64) {
        (self.width() as f64 * self.cell_x_m, self.height() as f64 * self.cell_y_m)
    }
    /// Cell `(col, row)` containing world point `(x, y)` (m, origin SW corner), or `None` outside.
    pub fn cell_at(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        if x < 0.0 || y < 0.0 {
            return None;
        }
        let col = (x / self.cell_x_m) as usize;
        let rs = (y / self.cell_y_m) as usize;
        if col >= self.width() || rs >= self.height() {
            return None;
        }
        Some((col, self.height() - 1 - rs))
    }
    /// Bilinear elevation (m) at world point `(x, y)`, clamped to the grid (and to the cells
    /// held: a tile reads points of its own cells, whose four neighbours its halo holds).
    pub fn elevation_at(&self, x: f64, y: f64) -> f32 {
        let w = self.width();
        let h = self.height();
        let fx = (x / self.cell_x_m - 0.5).clamp(0.0, (w - 1) as f64);
        let fy = ((self.height() as f64 - y / self.cell_y_m) - 0.5).clamp(0.0, (h - 1) as f64);
        let (c0, r0) = (fx.floor() as usize, fy.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (tx, ty) = ((fx - c0 as f64) as f32, (fy - r0 as f64) as f32);
        let hw = &self.held;
        let at = |c: usize, r: usize| {
            let (c, r) = (c.clamp(hw.col0, hw.col1() - 1) - hw.col0, r.clamp(hw.row0, hw.row1() - 1) - hw.row0);
            self.elevation_m.data[r * hw.width + c]
        };
        let a = at(c0, r0) * (1.0 - tx) + at(c1, r0) * tx;
        let b = at(c0, r1) * (1.0 - tx) + at(c1, r1) * tx;
        a * (1.0 - ty) + b * ty
    }

    /// Whether cell `(col, row)` (whole-grid indices, held) has no data: masked, and not water
    /// below `sea_level` (m) — a no-data cell of the DEM holds 0 ([`from_fields`]), water its
    /// own elevation at or below the sea level; with `f32::NEG_INFINITY` every masked cell.
    pub fn is_no_data(&self, col: usize, row: usize, sea_level: f32) -> bool {
        let Some(i) = self.held_index(col, row) else { return false };
        let z = self.elevation_m.data[i];
        !self.mask.data[i] && (z == 0.0 || !z.is_finite() || z > sea_level)
    }

    /// Elevation (m) at world point `(x, y)` for drawing the ground: NaN where the cell holding
    /// the point has no data ([`SiteConditions::is_no_data`] with `sea_level`; a DEM's no-data
    /// hole, drawn as a hole, round 34), else bilinear as [`SiteConditions::elevation_at`] over
    /// those of the four surrounding cells that have data (weights renormalised), so that
    /// valid cells beside a hole keep their height instead of being pulled towards the 0 the
    /// site holds in a no-data cell (walls down into a pit: the "shafts" of round 33). Clamped to
    /// the grid and the cells held as [`SiteConditions::elevation_at`]; NaN outside the grid.
    pub fn elevation_at_valid(&self, x: f64, y: f64, sea_level: f32) -> f32 {
        let (w, h) = (self.width(), self.height());
        let Some((cc, rc)) = self.cell_at(x.min(self.cell_x_m * w as f64 - 1e-9), y.min(self.cell_y_m * h as f64 - 1e-9)) else { return f32::NAN };
        let hw = &self.held;
        let clamp = |c: usize, r: usize| (c.clamp(hw.col0, hw.col1() - 1), r.clamp(hw.row0, hw.row1() - 1));
        let at = |c: usize, r: usize| {
            let (c, r) = clamp(c, r);
            if self.is_no_data(c, r, sea_level) {
                return f32::NAN;
            }
            self.elevation_m.data[(r - hw.row0) * hw.width + (c - hw.col0)]
        };
        if !at(cc, rc).is_finite() {
            return f32::NAN;
        }
        let fx = (x / self.cell_x_m - 0.5).clamp(0.0, (w - 1) as f64);
        let fy = ((h as f64 - y / self.cell_y_m) - 0.5).clamp(0.0, (h - 1) as f64);
        let (c0, r0) = (fx.floor() as usize, fy.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (tx, ty) = ((fx - c0 as f64) as f32, (fy - r0 as f64) as f32);
        let corners = [(c0, r0, (1.0 - tx) * (1.0 - ty)), (c1, r0, tx * (1.0 - ty)), (c0, r1, (1.0 - tx) * ty), (c1, r1, tx * ty)];
        if corners.iter().all(|&(c, r, _)| at(c, r).is_finite()) {
            // no no-data neighbour: exactly `elevation_at` (the ground of a DEM without holes is
            // drawn as before, to the bit)
            return self.elevation_at(x, y);
        }
        let (mut sum, mut wsum) = (0.0f32, 0.0f32);
        for (c, r, wt) in corners {
            let v = at(c, r);
            if v.is_finite() && wt > 0.0 {
                sum += v * wt;
                wsum += wt;
            }
        }
        if wsum > 0.0 {
            sum / wsum
        } else {
            at(cc, rc)
        }
    }

    /// A flat, uniform site of `width × height` cells of `cell_m` metres with the given indices
    /// (for tests and stand-level scenarios). Its mean annual temperature and wetness index are
    /// those its T and F map from ([`temperature_index`], [`moisture_index`] inverted: T 5 is
    /// 8 °C, F 5 a TWI of 8), which the water balance of a changing climate reads
    /// ([`crate::climate::water`]).
    pub fn uniform(width: usize, height: usize, cell_m: f64, elevation_m: f32, indices: [f32; 6], latitude_deg: f64) -> Self {
        SiteConditions {
            geo: GeoRef::local(cell_m, latitude_deg),
            cell_x_m: cell_m,
            cell_y_m: cell_m,
            mask: Grid::filled(width, height, true),
            elevation_m: Grid::filled(width, height, elevation_m),
            slope_deg: Grid::filled(width, height, 0.0),
            aspect_deg: Grid::filled(width, height, -1.0),
            twi: Grid::filled(width, height, 2.0 * (indices[factor::F] - 1.0)),
            insolation_kwh_m2: Grid::filled(width, height, 1200.0),
            wind_exposure: Grid::filled(width, height, 0.3),
            temperature_c: Grid::filled(width, height, (indices[factor::T] - 1.0) * 2.5 - 2.0),
            indices: Grid::filled(width, height, indices),
            held: Window::full(width, height),
            full: (width, height),
        }
    }
}

/// Light index L (1–9) from the ratio `r` of a cell's annual insolation to unshaded flat ground
/// at the same latitude: L = clamp(7 + 2·(r − 1)/0.25, 1, 9). Anchors: open flat ground (r = 1)
/// → 7 ("light plant, rarely under 40 % relative light", Ellenberg et al. 1991, Scripta
/// Geobotanica 18); r ≥ 1.25 (steep sun-facing slope) → 9; r ≤ 0.25 (deep shade of a north
/// face) → 1. Linear between.
pub fn light_index(ratio: f64) -> f32 {
    (7.0 + 2.0 * (ratio - 1.0) / 0.25).clamp(1.0, 9.0) as f32
}

/// Temperature index T (1–9) from mean annual air temperature (°C):
/// T = clamp(1 + 8·(t + 2)/20, 1, 9). Anchors: −2 °C (arctic–alpine belt) → 1, 8 °C
/// (submontane Central Europe, Ellenberg's T 5) → 5, 18 °C (Mediterranean lowland) → 9.
pub fn temperature_index(t_c: f64) -> f32 {
    (1.0 + 8.0 * (t_c + 2.0) / 20.0).clamp(1.0, 9.0) as f32
}

/// Moisture index F (1–12) from the topographic wetness index alone: F = clamp(1 + 0.5·TWI, 1,
/// 12) (ridge TWI 4 → 3, mid-slope TWI 8 → 5, valley floor TWI 14 → 8). The site's F of
/// rounds ≤ 44; since round 45 a derived site's F is [`moisture_index_of_water`], and this
/// mapping remains only to give a uniform site ([`SiteConditions::uniform`]) a wetness index
/// (its inverse, TWI = 2 (F − 1)).
pub fn moisture_index(twi: f64) -> f32 {
    (1.0 + 0.5 * twi).clamp(1.0, 12.0) as f32
}

/// F units per unit of ForClim's drought index in [`moisture_index_of_water`] (a growing season
/// without transpiration deficit, DI 0, is F 6; DI 0.1 is F 5, DI 0.3 F 3): the drought
/// index's 0–0.5 span laid over Ellenberg's 1–6 span of the terrestrial F scale (F 1 "extreme
/// dryness" … F 5 "fresh" … F 6 between fresh and moist). ESTIMATE (Sylva choice, round 45).
pub const F_PER_DROUGHT_INDEX: f64 = 10.0;

/// F of a cell whose growing season has no transpiration deficit (drought index 0) and no
/// water from upslope: 6, between Ellenberg's "fresh" (5) and "moist" (7).
pub const F_NO_DROUGHT: f64 = 6.0;

/// Wetness index above which a cell gathers water from upslope beyond what its soil holds
/// (coves and valley floors): the water balance's reference index
/// ([`crate::climate::water::TWI_REFERENCE`], TWI 8, where a cell holds the climate's
/// `soil_water_capacity_mm`). ESTIMATE (round 45: with TWI 10 the wettest 5 % of the default
/// window reached only F 5.4, with TWI 8 F 5.5).
pub const TWI_LATERAL: f64 = crate::climate::water::TWI_REFERENCE;

/// Moisture index F (1–12) of a cell from its water balance (round 45): the growing-season
/// drought index `drought_index` of the base climate (ForClim's mean `1 − AET/PET`, Bugmann &
/// Cramer 1998; [`crate::climate::water::WaterClimate::cell_drought_index`]: Thornthwaite PET,
/// the year's precipitation, a soil bucket whose capacity grows with the wetness index) and the
/// water the cell receives from upslope (its wetness index `twi` above [`TWI_LATERAL`]):
///
/// `F = clamp(6 − 10 · DI + 0.5 · max(0, TWI − 8), 1, 12)`.
///
/// The dry side follows Ellenberg's F scale (Ellenberg et al. 1992, Scripta Geobotanica 18:
/// 1 extreme dryness, 3 dry, 5 fresh: "medium-moist soils, absent from wet and from
/// drying-out ones", 7 moist, 9 wet, 10–12 water), read as a growing-season water deficit:
/// F 5 where transpiration falls short of demand by 10 % over the season, F 3 by 30 %
/// ([`F_PER_DROUGHT_INDEX`], [`F_NO_DROUGHT`]; ESTIMATE). Indicator-calibrated F tracks measured
/// soil moisture and the depth of the water table roughly linearly (Schaffers & Sýkora 2000,
/// J. Veg. Sci. 11:225–244), which the linear map follows. The wet side keeps the 0.5 F per
/// unit of wetness index of the TWI mapping of rounds ≤ 44 ([`moisture_index`]), for the water
/// from upslope the bucket does not hold: a valley floor of TWI 14 gains 3 (F ≈ 8.5, "moist to
/// wet"). On the default Coweeta window (790 mm, 9.5 °C at 750 m) F runs from about 2.6 on the
/// ridges (5 %) over 4.4 (median) to 5.5 in the coves (95 %; BENCHMARKS.md, round 45).
/// A NaN index gives NaN.
pub fn moisture_index_of_water(drought_index: f64, twi: f64) -> f32 {
    (F_NO_DROUGHT - F_PER_DROUGHT_INDEX * drought_index + 0.5 * (twi - TWI_LATERAL).max(0.0)).clamp(1.0, 12.0) as f32
}

/// Living conditions of `terrain` under `climate` (see [`derive_with_progress`]).
pub fn derive(terrain: &crate::terrain::Terrain, climate: &Climate) -> crate::Result<SiteConditions> {
    derive_with_progress(terrain, climate, &|_| {})
}

/// Computes every terrain field ([`crate::terrain::fields::compute`]) and maps it to the
/// Ellenberg-style indices: L by [`light_index`], T by [`temperature_index`], F by
/// [`moisture_index_of_water`] of the cell's base-climate drought index and wetness index, K
/// by [`Climate::continentality`] (the scenario's, else from the temperature range and the
/// latitude), R, N the scenario constants of `climate`. Masked cells (nodata or at
/// or below `climate.sea_level_m`) get indices `[0; 6]`, elevation 0 where not finite, and NaN in
/// the other fields. `progress` receives the name of each stage.
///
/// Errors: [`crate::Error::Invalid`] when no cell is above sea level.
pub fn derive_with_progress(terrain: &crate::terrain::Terrain, climate: &Climate, progress: &dyn Fn(&str)) -> crate::Result<SiteConditions> {
    let f = crate::terrain::fields::compute(terrain, climate, progress)?;
    progress("Ellenberg indices");
    Ok(from_fields(terrain, climate, f))
}

/// Builds [`SiteConditions`] from already computed fields (see [`derive_with_progress`]).
pub fn from_fields(terrain: &crate::terrain::Terrain, climate: &Climate, f: crate::terrain::fields::Fields) -> SiteConditions {
    from_fields_of(&terrain.elevation, &terrain.geo, terrain.elevation.height, climate, f)
}

/// [`SiteConditions`] of window `out` of a raster, from its DEM window `dem` (`out` and
/// [`crate::terrain::fields::window_halo_cells`] around it) and the window's hydrology
/// ([`crate::terrain::fields::hydrology_windows`], or by band
/// [`crate::job::hydrology_ranks::hydrology_of_rank`]): [`crate::terrain::fields::compute_window`]
/// mapped to the indices as [`derive`] does, with the whole raster's georeferencing and mean
/// cell width. Every grid is `out`'s cells and equals the same window of [`derive`]'s
/// conditions of the whole raster bit for bit.
///
/// Errors: as [`crate::terrain::fields::compute_window`].
pub fn derive_window(dem: &crate::terrain::io::DemWindow, out: &crate::grid::Window, climate: &Climate, filled: Grid<f32>, flow_acc: Grid<f32>) -> crate::Result<SiteConditions> {
    let f = crate::terrain::fields::compute_window(dem, out, climate, filled, flow_acc)?;
    Ok(from_fields_of(&out.cut(&dem.elevation, &dem.window), &dem.geo, dem.full_height, climate, f))
}

/// [`from_fields`] of the cells `elevation` (a window of a raster of `full_h` rows, or the
/// whole) with the raster's georeferencing `geo`.
fn from_fields_of(elevation: &Grid<f32>, geo: &GeoRef, full_h: usize, climate: &Climate, f: crate::terrain::fields::Fields) -> SiteConditions {
    let (w, h) = (elevation.width, elevation.height);
    let flat = f.flat_insolation_kwh_m2.max(1e-9);
    let lat = geo.insolation_latitude_deg(climate.latitude_deg);
    let water = crate::climate::water::WaterClimate::of(climate);
    let k = climate.continentality(lat);
    let mut indices = Grid::filled(w, h, [0f32; 6]);
    for i in 0..w * h {
        if !f.mask.data[i] {
            continue;
        }
        let (t, twi) = (f.temperature_c.data[i] as f64, f.twi.data[i] as f64);
        let mut v = [0f32; 6];
        v[factor::L] = light_index(f.insolation_kwh_m2.data[i] as f64 / flat);
        v[factor::T] = temperature_index(t);
        v[factor::K] = k;
        v[factor::F] = moisture_index_of_water(water.cell_drought_index(t, twi, lat, 0.0, 1.0), twi);
        v[factor::R] = climate.reaction_r;
        v[factor::N] = climate.nitrogen_n;
        indices.data[i] = v;
    }
    let cell_x_m = (0..full_h).map(|r| geo.cell_x_m_at_row(r)).sum::<f64>() / full_h.max(1) as f64;
    SiteConditions {
        // the latitude the insolation above used (the grid's own where its CRS gives it, else
        // the climate's), so the pictures' sun and the stands' sky agree with it
        geo: GeoRef { latitude_deg: geo.insolation_latitude_deg(climate.latitude_deg), ..geo.clone() },
        cell_x_m,
        cell_y_m: geo.cell_y_m(),
        elevation_m: elevation.map(|z| if z.is_finite() { *z } else { 0.0 }),
        mask: f.mask,
        slope_deg: f.slope_deg,
        aspect_deg: f.aspect_deg,
        twi: f.twi,
        insolation_kwh_m2: f.insolation_kwh_m2,
        wind_exposure: f.wind_exposure,
        temperature_c: f.temperature_c,
        indices,
        held: Window::full(w, h),
        full: (w, h),
    }
}

#[cfg(test)]
mod derive_tests {
    use super::*;

    #[test]
    fn index_anchors() {
        assert_eq!(light_index(1.0), 7.0);
        assert_eq!(light_index(2.0), 9.0);
        assert_eq!(light_index(0.0), 1.0);
        assert_eq!(temperature_index(8.0), 5.0);
        assert_eq!(temperature_index(-10.0), 1.0);
        assert_eq!(moisture_index(8.0), 5.0);
        assert_eq!(moisture_index(40.0), 12.0);
    }

    #[test]
    fn derive_default_terrain() {
        let t = crate::terrain::io::default_terrain().unwrap();
        let c = Climate::default();
        let s = derive(&t, &c).unwrap();
        assert_eq!(s.width(), 387);
        assert_eq!(s.cell_x_m, 80.0);
        assert!(!s.mask.get(0, 0));
        let valid: Vec<usize> = (0..s.mask.len()).filter(|&i| s.mask.data[i]).collect();
        assert!(valid.len() > 140_000);
        for &i in &valid {
            let v = s.indices.data[i];
            assert!(v.iter().all(|x| (1.0..=12.0).contains(x)), "{v:?}");
            assert_eq!(v[factor::K], c.continentality(s.geo.latitude_deg));
        }
        // Higher ground is colder: the highest valid cell has the lowest T.
        let hi = *valid.iter().max_by(|&&a, &&b| s.elevation_m.data[a].total_cmp(&s.elevation_m.data[b])).unwrap();
        let t_min = valid.iter().map(|&i| s.indices.data[i][factor::T]).fold(f32::MAX, f32::min);
        assert_eq!(s.indices.data[hi][factor::T], t_min);
    }
}
