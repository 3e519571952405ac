//! Reproduction (autumn): mature trees produce seeds in proportion to crown projection area
//! and light; seeds are spread over the whole landscape on a per-species seed grid
//! ([`SeedGrid`](super::super::world::SeedGrid), cells of at least 20 m) by each species' dispersal kernel
//! (a gather over kernel offsets, so tile borders do not exist). Seeds that would land outside
//! the terrain are lost.

use crate::sim::trees::TreeStore;
use crate::sim::world::SeedGrid;
use crate::species::{Dispersal, KernelType, SpeciesId, SpeciesLibrary};
use rayon::prelude::*;

/// Discrete dispersal kernel: `(dcol, drow, weight)` offsets within `max_m`, weights sum to 1.
/// Densities per m² at distance r: negative exponential `e^(−r/a) / (2π a²)` with `a = mean/2`;
/// 2Dt (Clark et al. 1999, Ecology 80:1475, eq. 3) `p / (π u) · (1 + r²/u)^(−(p+1))` with
/// `p = 1.5`, `u = mean²` (for p = 1.5 the mean distance is √u).
pub fn kernel(d: &Dispersal, cell: f64) -> Vec<(isize, isize, f32)> {
    let n = (d.max_m as f64 / cell).ceil() as isize;
    let mut out = Vec::new();
    let mean = d.mean_m.max(0.1) as f64;
    for dr in -n..=n {
        for dc in -n..=n {
            let r = ((dc * dc + dr * dr) as f64).sqrt() * cell;
            if r > d.max_m as f64 + 0.5 * cell {
                continue;
            }
            let r = r.max(cell / 3.0);
            let dens = match d.kernel {
                KernelType::NegativeExponential => {
                    let a = mean / 2.0;
                    (-r / a).exp() / (std::f64::consts::TAU * a * a)
                }
                KernelType::TwoDt => {
                    let (p, u) = (1.5, mean * mean);
                    p / (std::f64::consts::PI * u) * (1.0 + r * r / u).powf(-(p + 1.0))
                }
            };
            out.push((dc, dr, dens));
        }
    }
    let sum: f64 = out.iter().map(|o| o.2).sum();
    out.into_iter().map(|(a, b, w)| (a, b, (w / sum) as f32)).filter(|o| o.2 > 1e-7).collect()
}

/// What reproduction reads (the trees, the species, the pool) and writes (the seed grids).
pub struct Reproduction<'a> {
    /// Trees (mature ones produce seeds).
    pub trees: &'a TreeStore,
    /// Species library.
    pub lib: &'a SpeciesLibrary,
    /// Species taking part (pool order indexes `seeds`).
    pub pool: &'a [SpeciesId],
    /// Written: seeds per m² per pool species.
    pub seeds: &'a mut [SeedGrid],
}

impl Reproduction<'_> {
    /// Position of species `s` in the pool.
    pub fn pool_index(&self, s: SpeciesId) -> Option<usize> {
        self.pool.iter().position(|&q| q == s)
    }
}

/// Seeds tree `i` of `t` produces this autumn (a species of `lib`):
/// `seeds_per_m2_crown · π r² · min(L, 1)` with crown radius `r` (m) and light `L`, for a tree
/// at or above its species' maturity age; `None` below it (no seed source).
#[inline]
pub fn seeds_of(t: &TreeStore, i: usize, lib: &SpeciesLibrary) -> Option<f32> {
    let sp = &lib.species[t.species[i] as usize];
    if t.age[i] < sp.life.maturity_age_yr {
        return None;
    }
    let r = t.crown_radius[i];
    Some(sp.life.seeds_per_m2_crown * std::f32::consts::PI * r * r * t.light[i].min(1.0))
}

/// The seed cell `(col, row)` of `g` that a source at world point `(x, y)` (m) puts its seeds
/// in (clamped to the grid).
#[inline]
pub fn source_cell(g: &SeedGrid, x: f32, y: f32) -> (usize, usize) {
    (((x as f64 / g.cell_m) as usize).min(g.cols - 1), ((y as f64 / g.cell_m) as usize).min(g.rows - 1))
}

/// Seeds per m² that land on cell `(col, row)` of a `cols × rows` seed grid of cell area
/// `area` (m²) from the seeds produced per cell, `src(col, row)` (cells off the grid are not
/// asked: their seeds are lost): the sum over the kernel `k` ([`kernel`]) in its order,
/// `Σ src(col − dc, row − dr) · w`, divided by `area`. One process and the tiles of a tiled run
/// (`sim::tiles`) both use it, so the same sources give the same bits.
#[inline]
pub fn gather(k: &[(isize, isize, f32)], cols: usize, rows: usize, area: f32, col: usize, row: usize, src: impl Fn(usize, usize) -> f32) -> f32 {
    let (r0, c0) = (row as isize, col as isize);
    let mut acc = 0f32;
    for &(dc, dr, wt) in k {
        let (rr, cc) = (r0 - dr, c0 - dc);
        if rr >= 0 && cc >= 0 && (rr as usize) < rows && (cc as usize) < cols {
            acc += src(cc as usize, rr as usize) * wt;
        }
    }
    acc / area
}

/// Produces and disperses this year's seeds into `w.seeds` (seeds per m² per pool species),
/// on the cells each grid holds (one process: the whole grid).
/// Seeds per tree: [`seeds_of`], summed per seed cell in tree order ([`source_cell`]), then
/// spread by the kernel ([`gather`]).
pub fn run(w: Reproduction<'_>) {
    let t = &w.trees;
    let mut src: Vec<Vec<f32>> = w.seeds.iter().map(|g| vec![0f32; g.cols * g.rows]).collect();
    let pidx: Vec<Option<usize>> = (0..w.lib.species.len() as u16).map(|s| w.pool_index(s)).collect();
    for i in 0..t.len() {
        let Some(p) = pidx[t.species[i] as usize] else { continue };
        let Some(n) = seeds_of(t, i, w.lib) else { continue };
        let g = &w.seeds[p];
        let (c, rw) = source_cell(g, t.x[i], t.y[i]);
        src[p][rw * g.cols + c] += n;
    }
    for (p, s) in src.iter().enumerate() {
        let sp = &w.lib.species[w.pool[p] as usize];
        let g = &mut w.seeds[p];
        if s.iter().all(|v| *v == 0.0) {
            g.data.iter_mut().for_each(|v| *v = 0.0);
            continue;
        }
        let (cols, rows, h) = (g.cols, g.rows, g.held);
        let area = (g.cell_m * g.cell_m) as f32;
        let k = kernel(&sp.life.dispersal, g.cell_m);
        // onto the cells held (one process: every cell)
        let hw = h.col1 - h.col0;
        g.data = (0..h.len()).into_par_iter().map(|i| gather(&k, cols, rows, area, h.col0 + i % hw, h.row0 + i / hw, |cc, rr| s[rr * cols + cc])).collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_normalised_and_decreasing() {
        for kt in [KernelType::NegativeExponential, KernelType::TwoDt] {
            let k = kernel(&Dispersal { kernel: kt, mean_m: 30.0, max_m: 200.0 }, 20.0);
            let s: f32 = k.iter().map(|o| o.2).sum();
            assert!((s - 1.0).abs() < 1e-3);
            let w = |dc: isize| k.iter().find(|o| o.0 == dc && o.1 == 0).unwrap().2;
            assert!(w(0) > w(1) && w(1) > w(3));
        }
    }
}
