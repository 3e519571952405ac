//! Terrain: a digital elevation model (DEM) read from GeoTIFF, ESRI ASCII grid or a 16-bit PNG
//! heightmap, or generated; its TIN; and the fields derived from it.

use crate::grid::{GeoRef, Grid};

/// A loaded elevation model.
#[derive(Debug, Clone)]
pub struct Terrain {
    /// Elevation (m above sea level), row 0 north. Invalid cells hold `f32::NAN`.
    pub elevation: Grid<f32>,
    /// Georeferencing.
    pub geo: GeoRef,
    /// Nodata value declared by the file, if any (informative; invalid cells are NaN).
    pub nodata: Option<f64>,
    /// Where the terrain came from (file path or "generated ...").
    pub source: String,
}

impl Terrain {
    /// `true` for cells holding a finite elevation.
    pub fn is_valid(&self, col: usize, row: usize) -> bool {
        self.elevation.get(col, row).is_finite()
    }
}

pub mod fields;
pub mod generate;
pub mod hydrology;
pub mod io;
pub mod tin;
