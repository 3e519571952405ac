//! `Grid<T>`: a row-major raster with its georeferencing.
//!
//! Conventions (DESIGN.md): row 0 is the **northern** edge, as in GeoTIFF and ESRI ASCII grids;
//! column 0 the western edge. World coordinates are metres with x east, y north, origin at the
//! south-west corner of the grid, so cell `(col, row)` has its centre at
//! `x = (col + 0.5) * cell_x_m`, `y = (height - row - 0.5) * cell_y_m`.
//! For geographic grids (degrees) `cell_x_m` is the east–west spacing at the grid's central
//! latitude; fields that need the exact spacing use [`GeoRef::cell_x_m_at_row`].

use serde::{Deserialize, Serialize};

/// Coordinate reference system of a grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Crs {
    /// Longitude/latitude in degrees (e.g. EPSG:4326). Cell sizes in metres vary per row.
    Geographic,
    /// A projected CRS in metres (e.g. UTM, EPSG:326xx).
    Projected,
    /// No georeferencing: a local metric grid (generated terrain, PNG heightmap).
    Local,
}

/// Mean radius of the Earth used for degree-to-metre conversion (m), WGS 84 authalic radius.
pub const EARTH_RADIUS_M: f64 = 6_371_007.2;
/// Metres per degree of latitude, the scale `gdaldem -s 111120` uses for geographic input.
pub const METRES_PER_DEGREE: f64 = 111_120.0;

/// `v.floor() as isize`, bit for bit (NaN → 0, saturating at the ends), without the libm call
/// that `f64::floor` compiles to on the x86-64 baseline (no SSE4.1 `roundsd`): a cell index
/// from a coordinate over a cell size, computed for every tree every year.
#[inline]
pub fn floor_index(v: f64) -> isize {
    let t = v as isize;
    // truncation rounds towards zero: one less for negative non-integers
    if (t as f64) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Georeferencing of a grid: where its upper-left corner is and how large a cell is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GeoRef {
    /// Kind of coordinates.
    pub crs: Crs,
    /// EPSG code when known (4326, 32616, ...).
    pub epsg: Option<u32>,
    /// X (easting or longitude) of the upper-left corner of the upper-left cell, CRS units.
    pub origin_x: f64,
    /// Y (northing or latitude) of the upper-left corner of the upper-left cell, CRS units.
    pub origin_y: f64,
    /// Cell width in CRS units (degrees or metres), > 0.
    pub pixel_w: f64,
    /// Cell height in CRS units (degrees or metres), > 0 (rows go south).
    pub pixel_h: f64,
    /// Latitude of the grid centre in degrees (computed for geographic grids and for projected
    /// grids whose CRS the reader inverted, see `latitude_from_crs`; otherwise a placeholder that
    /// [`GeoRef::insolation_latitude_deg`] replaces by the scenario's `climate.latitude_deg`).
    pub latitude_deg: f64,
    /// True when `latitude_deg` comes from the grid's own CRS: a projected grid whose projection
    /// (an EPSG code of `terrain::io::epsg_projection` or a `.prj`) was inverted at its centre.
    /// Geographic grids need no flag (their latitude is their y). False for local grids
    /// (PNG heightmaps, generated terrains) and projected grids of an unknown CRS.
    #[serde(default)]
    pub latitude_from_crs: bool,
}

impl GeoRef {
    /// A local metric grid with square cells of `cell_m` metres at latitude `latitude_deg`.
    pub fn local(cell_m: f64, latitude_deg: f64) -> Self {
        GeoRef { crs: Crs::Local, epsg: None, origin_x: 0.0, origin_y: 0.0, pixel_w: cell_m, pixel_h: cell_m, latitude_deg, latitude_from_crs: false }
    }
    /// Latitude (degrees) of the grid centre for insolation and the sun: the grid's own for a
    /// geographic grid or a projected grid whose CRS gave it (`latitude_from_crs`, any datum:
    /// WGS 84, NAD83, ETRS89 UTM or a `.prj`), else `climate_lat` (the scenario's
    /// `climate.latitude_deg`).
    pub fn insolation_latitude_deg(&self, climate_lat: f64) -> f64 {
        if self.crs == Crs::Geographic || self.latitude_from_crs {
            self.latitude_deg
        } else {
            climate_lat
        }
    }
    /// Latitude (degrees) of the centre of `row` for geographic grids; the grid latitude otherwise.
    pub fn row_latitude_deg(&self, row: usize) -> f64 {
        match self.crs {
            Crs::Geographic => self.origin_y - (row as f64 + 0.5) * self.pixel_h,
            _ => self.latitude_deg,
        }
    }
    /// East–west cell size in metres for `row` (geographic: `pixel_w · 111120 · cos φ`).
    pub fn cell_x_m_at_row(&self, row: usize) -> f64 {
        match self.crs {
            Crs::Geographic => self.pixel_w * METRES_PER_DEGREE * self.row_latitude_deg(row).to_radians().cos(),
            _ => self.pixel_w,
        }
    }
    /// North–south cell size in metres (geographic: `pixel_h · 111120`).
    pub fn cell_y_m(&self) -> f64 {
        match self.crs {
            Crs::Geographic => self.pixel_h * METRES_PER_DEGREE,
            _ => self.pixel_h,
        }
    }
}

/// A row-major raster of `width × height` cells (row 0 north).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Grid<T> {
    /// Number of columns (west → east).
    pub width: usize,
    /// Number of rows (north → south).
    pub height: usize,
    /// Cell values, `data[row * width + col]`; length `width * height`.
    pub data: Vec<T>,
}

impl<T: Clone> Grid<T> {
    /// A grid filled with `value`.
    pub fn filled(width: usize, height: usize, value: T) -> Self {
        Grid { width, height, data: vec![value; width * height] }
    }
}

impl<T> Grid<T> {
    /// Wraps `data` (length must be `width * height`; returns `None` otherwise).
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Option<Self> {
        (data.len() == width * height).then_some(Grid { width, height, data })
    }
    /// Linear index of `(col, row)`.
    #[inline]
    pub fn idx(&self, col: usize, row: usize) -> usize {
        row * self.width + col
    }
    /// Value at `(col, row)`; panics when out of range (like slice indexing).
    #[inline]
    pub fn get(&self, col: usize, row: usize) -> &T {
        &self.data[row * self.width + col]
    }
    /// Mutable value at `(col, row)`.
    #[inline]
    pub fn get_mut(&mut self, col: usize, row: usize) -> &mut T {
        &mut self.data[row * self.width + col]
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.data.len()
    }
    /// True for a grid without cells.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// Maps every value.
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> Grid<U> {
        Grid { width: self.width, height: self.height, data: self.data.iter().map(f).collect() }
    }
}

/// A rectangle of cells of a larger grid (row 0 north): columns `col0 .. col0 + width`, rows
/// `row0 .. row0 + height`. A rank's part of the site, and the part of a DEM read by window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Window {
    /// First column (west).
    pub col0: usize,
    /// First row (north).
    pub row0: usize,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl Window {
    /// The whole of a `width × height` grid.
    pub fn full(width: usize, height: usize) -> Window {
        Window { col0: 0, row0: 0, width, height }
    }
    /// One past the last column.
    pub fn col1(&self) -> usize {
        self.col0 + self.width
    }
    /// One past the last row.
    pub fn row1(&self) -> usize {
        self.row0 + self.height
    }
    /// This window widened by `halo` cells on every side, clipped to a `full_w × full_h` grid.
    pub fn with_halo(&self, halo: usize, full_w: usize, full_h: usize) -> Window {
        let (c0, r0) = (self.col0.saturating_sub(halo), self.row0.saturating_sub(halo));
        let (c1, r1) = (self.col1().saturating_add(halo).min(full_w), self.row1().saturating_add(halo).min(full_h));
        Window { col0: c0, row0: r0, width: c1.saturating_sub(c0), height: r1.saturating_sub(r0) }
    }
    /// True when `other` lies wholly inside this window.
    pub fn contains(&self, other: &Window) -> bool {
        other.col0 >= self.col0 && other.row0 >= self.row0 && other.col1() <= self.col1() && other.row1() <= self.row1()
    }
    /// True when the window is non-empty and lies inside a `full_w × full_h` grid.
    pub fn inside(&self, full_w: usize, full_h: usize) -> bool {
        self.width > 0 && self.height > 0 && self.col0.checked_add(self.width).is_some_and(|e| e <= full_w) && self.row0.checked_add(self.height).is_some_and(|e| e <= full_h)
    }
    /// The cells of `g` (a grid laid over `outer`, which contains this window) under this
    /// window, as a grid of `width × height`. Panics when `outer` does not contain it.
    pub fn cut<T: Clone>(&self, g: &Grid<T>, outer: &Window) -> Grid<T> {
        assert!(outer.contains(self) && g.width == outer.width && g.height == outer.height, "window {self:?} not inside {outer:?}");
        let mut data = Vec::with_capacity(self.width * self.height);
        for r in self.row0..self.row1() {
            let i = (r - outer.row0) * g.width + (self.col0 - outer.col0);
            data.extend_from_slice(&g.data[i..i + self.width]);
        }
        Grid { width: self.width, height: self.height, data }
    }
}

impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "columns {}..{}, rows {}..{}", self.col0, self.col1(), self.row0, self.row1())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn floor_index_is_floor() {
        let vals = [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999_999, -2.000_001, 1e15 + 0.5, -1e15 - 0.5, 1e300, -1e300, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, f64::MIN_POSITIVE, -f64::MIN_POSITIVE];
        for v in vals {
            assert_eq!(super::floor_index(v), v.floor() as isize, "{v}");
        }
        for k in -2000..2000 {
            let v = k as f64 * 0.37 / 5.0;
            assert_eq!(super::floor_index(v), v.floor() as isize, "{v}");
        }
    }

    use super::*;

    #[test]
    fn geographic_cell_size_at_jacksboro() {
        // 3 arc-second grid at 36.6°N: ≈ 74 m E–W × 92.6 m N–S (terrains/README.md).
        let g = GeoRef { crs: Crs::Geographic, epsg: Some(4326), origin_x: -84.41, origin_y: 36.6, pixel_w: 1.0 / 1200.0, pixel_h: 1.0 / 1200.0, latitude_deg: 36.6, latitude_from_crs: false };
        let dx = g.cell_x_m_at_row(0);
        assert!((dx - 74.3).abs() < 0.5, "dx {dx}");
        assert!((g.cell_y_m() - 92.6).abs() < 0.05);
    }
}
