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
    /// Where the light phase's diffuse part comes from (the scenario's `[light] diffuse`):
    /// [`Diffuse::Column`] (the default) or [`Diffuse::Sky`].
    pub diffuse: Diffuse,
}

/// The diffuse part of the light phase (`sim::phases::light`), the scenario's
/// `[light] diffuse = "column" | "sky"`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Diffuse {
    /// From the leaf-area index straight above the cell only, `e^(−k LAI_above)` (rounds 1–43).
    #[default]
    Column,
    /// From the sky hemisphere: zenith bands and azimuth sectors under the standard overcast
    /// sky, each sector's ray through the neighbouring cells' canopy, the crowns with their
    /// depth (`light::sky_diffuse`, after Canham 1988's gap light index), reaching at most
    /// [`SKY_REACH_M`].
    Sky,
}

/// How far (m, horizontally) a sky sector's ray of [`Diffuse::Sky`] is followed through the
/// canopy before the rest of its path counts as open. 150 m: a ray 82.5° from the zenith (the
/// lowest band's centre) from the ground reaches 20 m at 150 m, the top layer of a young stand;
/// it sets a tiled run's halo too (`sim::tiles::Reach`). Sylva choice.
pub const SKY_REACH_M: f64 = 150.0;

impl LightGrid {
    /// The grid of `cell_m`-metre cells over an extent `(x, y)` metres.
    pub fn new(extent: (f64, f64), cell_m: f64) -> Self {
        LightGrid { cell_m, cols: ((extent.0 / cell_m).ceil() as usize).max(1), rows: ((extent.1 / cell_m).ceil() as usize).max(1), diffuse: Diffuse::Column }
    }

    /// The same grid with the diffuse part `diffuse` (the scenario's `[light] diffuse`).
    pub fn with_diffuse(self, diffuse: Diffuse) -> Self {
        LightGrid { diffuse, ..self }
    }

    /// Cells (at least 0) beyond its own that the light of a cell reads: 1 (the row towards
    /// the equator, the sun's direction) for [`Diffuse::Column`], `⌈SKY_REACH_M / cell_m⌉ + 1`
    /// in every direction for [`Diffuse::Sky`].
    pub fn read_cells(&self) -> usize {
        match self.diffuse {
            Diffuse::Column => 1,
            Diffuse::Sky => (SKY_REACH_M / self.cell_m).ceil() as usize + 1,
        }
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
    /// Its cells' indices in a grid of `cols` columns (`row · cols + col`), row-major (rows
    /// south to north, each west to east).
    pub fn cells(self, cols: usize) -> impl Iterator<Item = usize> {
        (self.row0..self.row1).flat_map(move |r| (self.col0..self.col1).map(move |c| r * cols + c))
    }
}

/// The light cells a world steps, and the cells its per-light-cell site arrays hold (issue 37
/// Build 1): a tile's rectangle ([`crate::sim::World`]'s `site.window`), or the whole grid (one
/// process). Array index `k` of a span is its `k`-th cell in ascending light-cell order (rows
/// of the rectangle south to north, each west to east), so a tile's arrays hold its own cells
/// in one process's order and nothing else.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// Columns of the whole light grid.
    cols: usize,
    /// Cells of the whole light grid.
    all: usize,
    /// The rectangle; `None`: the whole grid.
    rect: Option<CellRect>,
}

impl Span {
    /// The span of `window` (`None`: every cell) on `grid`. A rectangle reaching beyond the
    /// grid is clipped to it.
    pub fn new(window: Option<CellRect>, grid: &LightGrid) -> Span {
        let rect = window.map(|r| CellRect { col0: r.col0.min(grid.cols), row0: r.row0.min(grid.rows), col1: r.col1.min(grid.cols), row1: r.row1.min(grid.rows) });
        Span { cols: grid.cols, all: grid.len(), rect }
    }
    /// Number of cells (the length of the arrays over the span).
    #[inline]
    pub fn len(&self) -> usize {
        self.rect.map_or(self.all, |r| if r.col1 > r.col0 && r.row1 > r.row0 { r.len() } else { 0 })
    }
    /// True when the span has no cell.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The light cell (index of the whole grid, `row · cols + col`) at index `k` of the span
    /// (`k < len()`).
    #[inline]
    pub fn cell(&self, k: usize) -> usize {
        match self.rect {
            None => k,
            Some(r) => {
                let w = r.col1 - r.col0;
                (r.row0 + k / w) * self.cols + r.col0 + k % w
            }
        }
    }
    /// The index in the span of light cell `c` (of the whole grid), or `None` outside it.
    #[inline]
    pub fn index(&self, c: usize) -> Option<usize> {
        match self.rect {
            None => (c < self.all).then_some(c),
            Some(r) => {
                let (col, row) = (c % self.cols, c / self.cols);
                r.contains(col, row).then(|| (row - r.row0) * (r.col1 - r.col0) + col - r.col0)
            }
        }
    }
    /// The values of `whole` (one per light cell of the whole grid) over the span, in span
    /// order; an empty `whole` stays empty.
    pub fn cut<T: Copy>(&self, whole: &[T]) -> Vec<T> {
        if whole.is_empty() || self.rect.is_none() {
            return whole.to_vec();
        }
        (0..self.len()).map(|k| whole[self.cell(k)]).collect()
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

    #[test]
    fn a_span_indexes_its_rectangle_in_light_cell_order() {
        // 5 × 4 cells; the rectangle of columns 1..3, rows 2..4 holds cells 11, 12, 16, 17
        let g = LightGrid::new((25.0, 20.0), 5.0);
        let s = Span::new(Some(CellRect { col0: 1, row0: 2, col1: 3, row1: 4 }), &g);
        assert_eq!(s.len(), 4);
        assert_eq!((0..4).map(|k| s.cell(k)).collect::<Vec<_>>(), vec![11, 12, 16, 17]);
        let idx: Vec<Option<usize>> = (0..g.len()).map(|c| s.index(c)).collect();
        for (c, i) in idx.iter().enumerate() {
            assert_eq!(*i, [11, 12, 16, 17].iter().position(|&x| x == c), "cell {c}");
        }
        let whole: Vec<u32> = (0..g.len() as u32).map(|c| c * 10).collect();
        assert_eq!(s.cut(&whole), vec![110, 120, 160, 170]);
        assert!(s.cut::<u32>(&[]).is_empty());
        // the whole grid: the identity
        let a = Span::new(None, &g);
        assert_eq!((a.len(), a.cell(7), a.index(7), a.index(20)), (20, 7, Some(7), None));
        assert_eq!(a.cut(&whole), whole);
        // a rectangle beyond the grid is clipped; an empty one has no cells
        let c = Span::new(Some(CellRect { col0: 3, row0: 3, col1: 9, row1: 9 }), &g);
        assert_eq!((c.len(), c.cell(0), c.cell(1)), (2, 18, 19));
        assert!(Span::new(Some(CellRect { col0: 2, row0: 0, col1: 2, row1: 4 }), &g).is_empty());
    }
}
