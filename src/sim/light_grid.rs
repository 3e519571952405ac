//! The light grid: the square cells (`light_cell_m` of the scenario) on which the canopy, the
//! ground light, the spatial hash of the trees and the regeneration cohorts live.
//!
//! Orientation (unlike [`crate::grid::Grid`], whose row 0 is the northern edge): **row 0 is the
//! southern edge**, rows grow with world y (north), columns with world x (east); cell
//! `c = row · cols + col` covers `[col·cell, (col+1)·cell) × [row·cell, (row+1)·cell)` metres
//! from the terrain's south-west corner. The grid covers the whole extent, so the last row and
//! column may reach past it.

/// Beer–Lambert extinction coefficient k of the light phase (dimensionless, 0.5: spherical leaf
/// angle distribution, Monsi & Saeki 1953).
pub const EXTINCTION_K: f32 = 0.5;

/// Shape and orientation of the light grid (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LightGrid {
    /// Cell side (m), > 0.
    pub cell_m: f64,
    /// Columns: `ceil(extent_x / cell_m)`, at least 1.
    pub cols: usize,
    /// Rows: `ceil(extent_y / cell_m)`, at least 1.
    pub rows: usize,
}

impl LightGrid {
    /// The grid of `cell_m`-metre cells over an extent `(x, y)` metres.
    pub fn new(extent: (f64, f64), cell_m: f64) -> Self {
        LightGrid { cell_m, cols: ((extent.0 / cell_m).ceil() as usize).max(1), rows: ((extent.1 / cell_m).ceil() as usize).max(1) }
    }

    /// Number of cells, `cols · rows`.
    #[inline]
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// True for a grid without cells (only the `Default` value).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `(col, row)` of cell `c` (row 0 south).
    #[inline]
    pub fn col_row(&self, c: usize) -> (usize, usize) {
        (c % self.cols, c / self.cols)
    }

    /// Centre of cell `c` (m, world coordinates).
    #[inline]
    pub fn centre(&self, c: usize) -> (f64, f64) {
        let (col, row) = self.col_row(c);
        ((col as f64 + 0.5) * self.cell_m, (row as f64 + 0.5) * self.cell_m)
    }

    /// Cell of world point `(x, y)` (m), clamped to the grid.
    #[inline]
    pub fn cell_of(&self, x: f32, y: f32) -> usize {
        let c = ((x as f64 / self.cell_m) as isize).clamp(0, self.cols as isize - 1) as usize;
        let r = ((y as f64 / self.cell_m) as isize).clamp(0, self.rows as isize - 1) as usize;
        r * self.cols + c
    }

    /// Area of one cell (m²).
    #[inline]
    pub fn cell_area_m2(&self) -> f64 {
        self.cell_m * self.cell_m
    }
}

/// A rectangle of light cells: columns `col0..col1`, rows `row0..row1` (row 0 south), the
/// cells a tile of a tiled run owns ([`crate::sim::tiles`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CellRect {
    /// First column.
    pub col0: usize,
    /// First row (southernmost).
    pub row0: usize,
    /// One past the last column.
    pub col1: usize,
    /// One past the last row.
    pub row1: usize,
}

impl CellRect {
    /// True when cell `(col, row)` lies in the rectangle.
    #[inline]
    pub fn contains(&self, col: usize, row: usize) -> bool {
        col >= self.col0 && col < self.col1 && row >= self.row0 && row < self.row1
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        (self.col1 - self.col0) * (self.row1 - self.row0)
    }
    /// True for a rectangle without cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_and_orientation() {
        let g = LightGrid::new((12.0, 7.0), 5.0);
        assert_eq!((g.cols, g.rows, g.len()), (3, 2, 6));
        // row 0 is south: the point (11, 6.5) is in the last column of the northern row
        assert_eq!(g.cell_of(11.0, 6.5), 5);
        assert_eq!(g.col_row(5), (2, 1));
        assert_eq!(g.centre(5), (12.5, 7.5));
        assert_eq!(g.cell_of(-3.0, 100.0), 3, "clamped");
        assert_eq!(g.cell_area_m2(), 25.0);
    }
}
