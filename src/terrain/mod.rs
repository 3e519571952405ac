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

/// Fewest columns and rows of a DEM that `sylva terrain info` and `sylva terrain maps` accept
/// ([`Terrain::check_min_size`]): slopes, flow directions and the TIN need a cell's neighbours.
pub const MIN_GRID_CELLS: usize = 2;

/// Sea level (m) of a PNG heightmap whose scenario (or `sylva terrain --sea-level`) gives none:
/// the lowest valid `climate.sea_level_m`, so that no cell of a height range above −500 m is
/// water (a 16-bit PNG's 0 is the bottom of its range, not the sea; trial 37).
pub const NO_SEA_LEVEL_M: f32 = -500.0;

impl Terrain {
    /// `true` for cells holding a finite elevation.
    pub fn is_valid(&self, col: usize, row: usize) -> bool {
        self.elevation.get(col, row).is_finite()
    }

    /// Checks that the grid has at least [`MIN_GRID_CELLS`] × [`MIN_GRID_CELLS`] cells (a
    /// 1 × 1 DEM was described by `sylva terrain info`, which then failed at its TIN, while
    /// `sylva terrain maps` drew 15 maps of one flat cell; round 34 refuses it in both, with
    /// this one error).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] naming the file (`source`), the field `grid`, its size and
    /// the minimum.
    pub fn check_min_size(&self) -> crate::Result<()> {
        let (w, h) = (self.elevation.width, self.elevation.height);
        if w < MIN_GRID_CELLS || h < MIN_GRID_CELLS {
            return Err(crate::Error::Invalid {
                context: format!("DEM {}", self.source),
                field: "grid".into(),
                value: format!("{w} x {h} cells"),
                expected: format!("at least {MIN_GRID_CELLS} x {MIN_GRID_CELLS} cells (slopes, flow and the TIN need a cell's neighbours)"),
            });
        }
        Ok(())
    }
}

pub mod fields;
pub mod generate;
pub mod hydrology;
pub mod io;
pub mod tin;
