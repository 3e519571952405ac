//! Reproduction (autumn): mature trees produce seeds in proportion to crown projection area
//! and light; seeds are spread over the whole landscape on a per-species seed grid
//! ([`SeedGrid`](super::super::world::SeedGrid)) by each species' dispersal kernel, in two
//! scales (round 45): the near field (closer than [`NEAR_FIELD_M`] to the source) on the grid's fine
//! cells (at most 5 m), the long-distance tail on its coarse cells (at least 20 m, at most 8 to
//! the kernel's reach), a gather over kernel offsets, so tile borders do not exist. Seeds that
//! would land outside the terrain are lost.

use crate::sim::light_grid::CellRect;
use crate::sim::trees::TreeStore;
use crate::sim::world::{SeedGrid, NEAR_FIELD_M};
use crate::species::{Dispersal, KernelType, SpeciesId, SpeciesLibrary};
use rayon::prelude::*;

/// Seed density (per m², of one seed) of kernel `d` at distance `r` (m), before the cut at
/// `max_m`: negative exponential `e^(−r/a) / (2π a²)` with `a = mean/2` (whose mean distance is
/// `2a`); 2Dt (Clark et al. 1999, Ecology 80:1475, eq. 3) `p / (π u) · (1 + r²/u)^(−(p+1))`
/// with `p = 1.5`, `u = mean²` (for p = 1.5 the mean distance is √u · Γ(½)Γ(p−½)/(2Γ(p)) ≈ √u).
pub fn density(d: &Dispersal, r: f64) -> f64 {
    let mean = d.mean_m.max(0.1) as f64;
    match d.kernel {
        KernelType::NegativeExponential => {
            let a = mean / 2.0;
            (-r / a).exp() / (std::f64::consts::TAU * a * a)
        }
        KernelType::TwoDt => {
            let (p, u) = (1.5, mean * mean);
            p / (std::f64::consts::PI * u) * (1.0 + r * r / u).powf(-(p + 1.0))
        }
    }
}

/// A dispersal kernel in two scales (round 45): the share of a source's seeds landing on each
/// fine cell closer than `near_m` to it, and the share landing on each coarse cell (`block ×
/// block` fine cells) beyond. The shares of both lists sum to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct TwoScale {
    /// `(dcol, drow, share)`: fine-cell offsets from the source's fine cell.
    pub near: Vec<(isize, isize, f32)>,
    /// `(dcol, drow, share)`: coarse-cell offsets from the source's coarse cell.
    pub far: Vec<(isize, isize, f32)>,
    /// Fine cells per coarse cell side.
    pub block: usize,
}

impl TwoScale {
    /// The kernel's reach in fine cells: a target's sources lie within this many fine cells of
    /// it along each axis (the near offsets, and the far offsets' coarse cells whole).
    pub fn reach(&self) -> usize {
        let near = self.near.iter().map(|o| o.0.unsigned_abs().max(o.1.unsigned_abs())).max().unwrap_or(0);
        let far = self.far.iter().map(|o| o.0.unsigned_abs().max(o.1.unsigned_abs())).max().unwrap_or(0);
        near.max((far + 1) * self.block)
    }
}

/// The two-scale kernel of `d` on a seed grid of fine cells of `fine` metres, `block` to a
/// coarse cell side, with the near field closer than `near_m` metres
/// ([`crate::sim::world::NEAR_FIELD_M`] in a run).
///
/// Every fine offset `k` (fine cells) within `max_m` carries `g(k) = ρ(max(|k|·fine, fine/3))
/// · fine²`, the [`density`] ρ at the cell's centre (the source's own cell at a third of a
/// cell, as the kernel before round 45 did). An offset closer than `near_m` goes to the near list
/// as it is. The rest go to the coarse cells: coarse offset `D` takes the mean over the
/// source's positions in its coarse cell of what lands in the target coarse cell,
/// `(1/b²) Σ_a (b − |a_x|)(b − |a_y|) g(D·b + a)` over `|a_x|, |a_y| < b` (the two cells'
/// fine positions, a triangle in each axis), so a source's near and far shares together are
/// its fine kernel's, whatever its place in its coarse cell. Both lists are then divided by
/// their common sum: the shares of a source's seeds sum to 1 (seeds are conserved but for
/// those landing off the grid). `near_m = 0` gives the coarse kernel alone (main's before
/// round 45, but for the fine sampling of each coarse cell).
pub fn kernel(d: &Dispersal, fine: f64, block: usize, near_m: f64) -> TwoScale {
    let b = block.max(1) as isize;
    let max_m = d.max_m.max(0.0) as f64;
    let n = (max_m / fine).ceil() as isize;
    let side = (2 * n + 1) as usize;
    // g(k) over the fine offsets within max_m; whether k is in the near field
    let mut g = vec![0f64; side * side];
    let mut near_of = vec![false; side * side];
    let mut near = Vec::new();
    for dr in -n..=n {
        for dc in -n..=n {
            let r = ((dc * dc + dr * dr) as f64).sqrt() * fine;
            if r > max_m {
                continue;
            }
            let i = ((dr + n) as usize) * side + (dc + n) as usize;
            g[i] = density(d, r.max(fine / 3.0)) * fine * fine;
            if r < near_m {
                near_of[i] = true;
                near.push((dc, dr, g[i]));
            }
        }
    }
    let gf = |kc: isize, kr: isize| -> f64 {
        if kc.abs() > n || kr.abs() > n {
            return 0.0;
        }
        let i = ((kr + n) as usize) * side + (kc + n) as usize;
        if near_of[i] { 0.0 } else { g[i] }
    };
    let nd = (n + b - 1) / b;
    let mut far = Vec::new();
    for dr in -nd..=nd {
        for dc in -nd..=nd {
            let mut acc = 0f64;
            for ar in -(b - 1)..b {
                for ac in -(b - 1)..b {
                    acc += ((b - ac.abs()) * (b - ar.abs())) as f64 * gf(dc * b + ac, dr * b + ar);
                }
            }
            if acc > 0.0 {
                far.push((dc, dr, acc / (b * b) as f64));
            }
        }
    }
    let sum: f64 = near.iter().chain(&far).map(|o| o.2).sum();
    let norm = |v: Vec<(isize, isize, f64)>| -> Vec<(isize, isize, f32)> { v.into_iter().map(|(a, c, w)| (a, c, (w / sum) as f32)).filter(|o| o.2 > 0.0).collect() };
    TwoScale { near: norm(near), far: norm(far), block: block.max(1) }
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

/// `Σ src(col − dc, row − dr) · w` over the offsets `k` in their order, for the source cells
/// that lie in `rect` (cells of the grid outside it are not asked; `src` indexes `rect`
/// row-major).
#[inline]
fn gather(k: &[(isize, isize, f32)], rect: CellRect, col: usize, row: usize, src: &[f32]) -> f32 {
    let (r0, c0) = (row as isize, col as isize);
    let w = rect.col1 - rect.col0;
    let mut acc = 0f32;
    for &(dc, dr, wt) in k {
        let (rr, cc) = (r0 - dr, c0 - dc);
        if rr >= rect.row0 as isize && cc >= rect.col0 as isize && (rr as usize) < rect.row1 && (cc as usize) < rect.col1 {
            acc += src[(rr as usize - rect.row0) * w + (cc as usize - rect.col0)] * wt;
        }
    }
    acc
}

/// Seeds per m² that land on the fine cells of `read` (row-major; columns and rows of the
/// whole grid of `cols × rows` fine cells of `fine_m` metres), from the seeds produced per fine
/// cell `src` over `need` (row-major), by the two-scale kernel `k` ([`kernel`]):
/// `Σ_near src · w / fine² + Σ_far S · W / coarse²`, where `S` are the coarse cells'
/// productions (the sums of their fine cells, row-major) and the tail's seeds spread evenly
/// over the fine cells of the coarse cell they land in. `need` must start on a coarse cell
/// (its first column and row multiples of `k.block`) and hold every cell of the grid within
/// [`TwoScale::reach`] of `read`; sources off the grid are none. One process (`need` the whole
/// grid) and the tiles of a tiled run (`sim::tiles`) both use it, so the same productions give
/// the same bits, whatever the thread count.
///
/// Panics when `src` does not have `need`'s length.
pub fn disperse(k: &TwoScale, cols: usize, rows: usize, fine_m: f64, need: CellRect, src: &[f32], read: CellRect) -> Vec<f32> {
    assert_eq!(src.len(), need.len(), "seed production over {need:?}");
    let b = k.block;
    debug_assert!(need.col0 % b == 0 && need.row0 % b == 0 && cols % b == 0 && rows % b == 0);
    // the coarse cells of `need` (a partial block at its far edge holds what `need` holds)
    let cneed = CellRect { col0: need.col0 / b, row0: need.row0 / b, col1: need.col1.div_ceil(b), row1: need.row1.div_ceil(b) };
    let (cw, w) = (cneed.col1 - cneed.col0, need.col1 - need.col0);
    let csrc: Vec<f32> = (0..cneed.len())
        .into_par_iter()
        .map(|i| {
            let (c0, r0) = ((cneed.col0 + i % cw) * b, (cneed.row0 + i / cw) * b);
            let mut acc = 0f32;
            for r in r0..(r0 + b).min(need.row1) {
                for c in c0..(c0 + b).min(need.col1) {
                    acc += src[(r - need.row0) * w + (c - need.col0)];
                }
            }
            acc
        })
        .collect();
    // the near field reaches this many coarse cells: a coarse cell without a source within
    // them gets no near seeds (a sparse or young stand skips the fine gather)
    let qn = k.near.iter().map(|o| o.0.unsigned_abs().max(o.1.unsigned_abs())).max().unwrap_or(0).div_ceil(b) + 1;
    // the tail on the coarse cells of `read`
    let cread = CellRect { col0: read.col0 / b, row0: read.row0 / b, col1: read.col1.div_ceil(b), row1: read.row1.div_ceil(b) };
    let crw = cread.col1 - cread.col0;
    let (far, any_near): (Vec<f32>, Vec<bool>) = (0..cread.len())
        .into_par_iter()
        .map(|i| {
            let (c, r) = (cread.col0 + i % crw, cread.row0 + i / crw);
            let f = gather(&k.far, cneed, c, r, &csrc);
            let (ca, cb) = (c.saturating_sub(qn).max(cneed.col0), (c + qn + 1).min(cneed.col1));
            let (ra, rb) = (r.saturating_sub(qn).max(cneed.row0), (r + qn + 1).min(cneed.row1));
            let any = (ra..rb).any(|rr| (ca..cb).any(|cc| csrc[(rr - cneed.row0) * cw + (cc - cneed.col0)] != 0.0));
            (f, any)
        })
        .unzip();
    let (fa, ca) = ((fine_m * fine_m) as f32, (fine_m * fine_m * (b * b) as f64) as f32);
    let rw = read.col1 - read.col0;
    (0..read.len())
        .into_par_iter()
        .map(|i| {
            let (c, r) = (read.col0 + i % rw, read.row0 + i / rw);
            let j = (r / b - cread.row0) * crw + (c / b - cread.col0);
            let near = if any_near[j] { gather(&k.near, need, c, r, src) } else { 0.0 };
            near / fa + far[j] / ca
        })
        .collect()
}

/// Produces and disperses this year's seeds into `w.seeds` (seeds per m² per pool species),
/// on the cells each grid holds (one process: the whole grid).
/// Seeds per tree: [`seeds_of`], summed per fine seed cell in tree order ([`source_cell`]),
/// then spread by the two-scale kernel ([`kernel`], [`disperse`]).
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
        let k = kernel(&sp.life.dispersal, g.cell_m, g.block, NEAR_FIELD_M);
        let whole = CellRect { col0: 0, row0: 0, col1: g.cols, row1: g.rows };
        // onto the cells held (one process: every cell)
        g.data = disperse(&k, g.cols, g.rows, g.cell_m, whole, s, g.held);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_normalised_and_decreasing() {
        for kt in [KernelType::NegativeExponential, KernelType::TwoDt] {
            let k = kernel(&Dispersal { kernel: kt, mean_m: 30.0, max_m: 200.0 }, 5.0, 5, 50.0);
            let s: f64 = k.near.iter().chain(&k.far).map(|o| o.2 as f64).sum();
            assert!((s - 1.0).abs() < 1e-5, "{s}");
            let w = |dc: isize| k.near.iter().find(|o| o.0 == dc && o.1 == 0).unwrap().2;
            assert!(w(0) > w(1) && w(1) > w(3) && w(3) > w(9));
            // no near offset at 50 m or beyond, no tail in the source's own coarse cell
            assert!(k.near.iter().all(|o| ((o.0 * o.0 + o.1 * o.1) as f64).sqrt() * 5.0 < 50.0));
            assert!(k.far.iter().all(|o| (o.0, o.1) != (0, 0)));
            // the tail's coarse offsets reach 8 cells of 25 m (200 m), and their cells whole
            assert_eq!(k.reach(), (8 + 1) * 5);
        }
    }
}
