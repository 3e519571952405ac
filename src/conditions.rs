//! Living conditions: terrain fields mapped to Ellenberg-style indices (L, T, K, F, R, N).
//!
//! OWNERSHIP NOTE (foundation): [`SiteConditions`] is the contract between terrain and the
//! simulation; fields may be added, not renamed.

use crate::grid::{GeoRef, Grid};

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
}

impl SiteConditions {
    /// Width of the grid (columns).
    pub fn width(&self) -> usize {
        self.mask.width
    }
    /// Height of the grid (rows).
    pub fn height(&self) -> usize {
        self.mask.height
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
    /// Bilinear elevation (m) at world point `(x, y)`, clamped to the grid.
    pub fn elevation_at(&self, x: f64, y: f64) -> f32 {
        let w = self.width();
        let h = self.height();
        let fx = (x / self.cell_x_m - 0.5).clamp(0.0, (w - 1) as f64);
        let fy = ((self.height() as f64 - y / self.cell_y_m) - 0.5).clamp(0.0, (h - 1) as f64);
        let (c0, r0) = (fx.floor() as usize, fy.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
        let (tx, ty) = ((fx - c0 as f64) as f32, (fy - r0 as f64) as f32);
        let e = &self.elevation_m;
        let a = e.get(c0, r0) * (1.0 - tx) + e.get(c1, r0) * tx;
        let b = e.get(c0, r1) * (1.0 - tx) + e.get(c1, r1) * tx;
        a * (1.0 - ty) + b * ty
    }

    /// A flat, uniform site of `width × height` cells of `cell_m` metres with the given indices
    /// (for tests and stand-level scenarios).
    pub fn uniform(width: usize, height: usize, cell_m: f64, elevation_m: f32, indices: [f32; 6], latitude_deg: f64) -> Self {
        SiteConditions {
            geo: GeoRef::local(cell_m, latitude_deg),
            cell_x_m: cell_m,
            cell_y_m: cell_m,
            mask: Grid::filled(width, height, true),
            elevation_m: Grid::filled(width, height, elevation_m),
            slope_deg: Grid::filled(width, height, 0.0),
            aspect_deg: Grid::filled(width, height, -1.0),
            twi: Grid::filled(width, height, 8.0),
            insolation_kwh_m2: Grid::filled(width, height, 1200.0),
            wind_exposure: Grid::filled(width, height, 0.3),
            temperature_c: Grid::filled(width, height, 8.0),
            indices: Grid::filled(width, height, indices),
        }
    }
}

/// Climate and soil constants of a scenario that, with the terrain, give the living conditions.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Climate {
    /// Latitude (degrees, −90…90) for insolation when the terrain is not geographic.
    pub latitude_deg: f64,
    /// Mean annual temperature (°C) at `reference_elevation_m`.
    pub reference_temperature_c: f32,
    /// Elevation (m) at which `reference_temperature_c` holds.
    pub reference_elevation_m: f32,
    /// Temperature lapse rate (K per km, negative = cooling upwards); default −6.5.
    pub lapse_rate_k_per_km: f32,
    /// Continentality index K (1–9), constant over the terrain.
    pub continentality_k: f32,
    /// Soil reaction index R (1–9), constant over the terrain.
    pub reaction_r: f32,
    /// Nitrogen index N (1–9), constant over the terrain.
    pub nitrogen_n: f32,
    /// Cells at or below this elevation (m) are water and masked.
    pub sea_level_m: f32,
    /// Direction the prevailing wind comes from (degrees clockwise from north).
    pub wind_from_deg: f32,
}

impl Default for Climate {
    fn default() -> Self {
        Climate {
            latitude_deg: 46.0,
            reference_temperature_c: 9.0,
            reference_elevation_m: 300.0,
            lapse_rate_k_per_km: -6.5,
            continentality_k: 4.0,
            reaction_r: 6.0,
            nitrogen_n: 5.0,
            sea_level_m: 0.0,
            wind_from_deg: 270.0,
        }
    }
}
