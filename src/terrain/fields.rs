//! Fields derived from a DEM on its own grid (row 0 north): mask, slope, aspect, depression
//! filling, D8 flow accumulation, topographic wetness index, clear-sky annual insolation with
//! terrain shading, wind exposure, temperature.
//!
//! Every field is `f32` on the terrain's grid; masked cells (nodata or at/below sea level) hold
//! `NaN` (flow accumulation: 0). Row-parallel with rayon; no result depends on the thread count.
//! Geographic grids use the east–west cell size of each row ([`GeoRef::cell_x_m_at_row`]).

use super::Terrain;
use crate::climate::Climate;
use crate::error::{Error, Result};
use crate::grid::{Crs, GeoRef, Grid, Window};
use rayon::prelude::*;
use std::collections::VecDeque;

/// Cells that take part in every field: finite elevation strictly above `sea_level_m`.
pub fn mask(t: &Terrain, sea_level_m: f32) -> Grid<bool> {
    t.elevation.map(|z| z.is_finite() && *z > sea_level_m)
}

/// A part of a DEM and where it lies in the whole raster: the elevations `z` and mask `m`
/// (both `at.width × at.height`) of the window `at` of a `full_w × full_h` raster whose
/// georeferencing is `geo` (the whole raster's: rows and latitudes are the raster's). The
/// whole raster is the patch `at = Window::full(w, h)` ([`Patch::whole`]); a rank's part is its
/// cells plus the halo a field needs ([`halo_cells`]). The field functions derive cells of an
/// output window inside the patch, with the raster's edges (not the patch's) as edges, so a
/// window derived from a large enough patch equals the same window of the whole raster's field
/// bit for bit.
#[derive(Debug, Clone, Copy)]
pub struct Patch<'a> {
    /// Elevations (m; NaN invalid) of the patch's cells, row 0 its northern row.
    pub z: &'a Grid<f32>,
    /// Mask ([`mask`]) of the patch's cells.
    pub m: &'a Grid<bool>,
    /// Where the patch lies in the raster.
    pub at: Window,
    /// Columns of the whole raster.
    pub full_w: usize,
    /// Rows of the whole raster.
    pub full_h: usize,
    /// Georeferencing of the whole raster.
    pub geo: &'a GeoRef,
}

impl<'a> Patch<'a> {
    /// The whole of terrain `t` with its mask `m`.
    pub fn whole(t: &'a Terrain, m: &'a Grid<bool>) -> Patch<'a> {
        Patch { z: &t.elevation, m, at: Window::full(m.width, m.height), full_w: m.width, full_h: m.height, geo: &t.geo }
    }
    /// Index in the patch's grids of raster cell `(c, r)` (inside the patch).
    #[inline]
    fn idx(&self, c: usize, r: usize) -> usize {
        (r - self.at.row0) * self.at.width + (c - self.at.col0)
    }
    /// Refuses an output window `out` whose cells and `halo` cells around them (clipped to the
    /// raster) are not all in the patch.
    ///
    /// Errors: [`Error::Invalid`] naming the field, the window, the halo and the patch.
    fn check(&self, out: &Window, halo: usize, field: &str) -> Result<()> {
        let need = out.with_halo(halo, self.full_w, self.full_h);
        if !out.inside(self.full_w, self.full_h) || !self.at.contains(&need) || self.z.width != self.at.width || self.z.height != self.at.height || self.m.width != self.at.width || self.m.height != self.at.height {
            return Err(Error::Invalid {
                context: format!("{field} of a {} x {} raster", self.full_w, self.full_h),
                field: "window".into(),
                value: format!("{out} from a patch of {} ({} x {} elevations, {} x {} mask)", self.at, self.z.width, self.z.height, self.m.width, self.m.height),
                expected: format!("a patch holding the window and {halo} cells around it ({need})"),
            });
        }
        Ok(())
    }
}

/// The 3×3 window around raster cell `(c, r)` of patch `p` in gdaldem's order
/// `[a b c; d e f; g h i]` (row above first). Neighbours outside the raster or masked take the
/// centre's value (edge replication). The patch must hold the cell's neighbours in the raster.
#[inline]
fn window3(p: &Patch, c: usize, r: usize) -> [f32; 9] {
    let e = p.z.data[p.idx(c, r)];
    let mut w = [e; 9];
    for (k, (dc, dr)) in [(-1i64, -1i64), (0, -1), (1, -1), (-1, 0), (0, 0), (1, 0), (-1, 1), (0, 1), (1, 1)].iter().enumerate() {
        let (cc, rr) = (c as i64 + dc, r as i64 + dr);
        if cc >= 0 && rr >= 0 && (cc as usize) < p.full_w && (rr as usize) < p.full_h {
            let i = p.idx(cc as usize, rr as usize);
            if p.m.data[i] {
                w[k] = p.z.data[i];
            }
        }
    }
    w
}

/// Horn (1981) gradient `(∂z/∂x east, ∂z/∂y north)` (m/m) from a 3×3 window, with cell sizes
/// `dx`, `dy` (m): ∂z/∂x = ((c+2f+i) − (a+2d+g)) / 8dx, ∂z/∂y = ((a+2b+c) − (g+2h+i)) / 8dy —
/// the kernel of `gdaldem slope/aspect` (Horn 1981, Proc. IEEE 69(1), eq. for p and q).
#[inline]
pub fn horn_gradient(w: &[f32; 9], dx: f64, dy: f64) -> (f64, f64) {
    let w: [f64; 9] = w.map(|v| v as f64);
    let gx = ((w[2] + 2.0 * w[5] + w[8]) - (w[0] + 2.0 * w[3] + w[6])) / (8.0 * dx);
    let gy = ((w[0] + 2.0 * w[1] + w[2]) - (w[6] + 2.0 * w[7] + w[8])) / (8.0 * dy);
    (gx, gy)
}

/// Aspect (degrees clockwise from north, the direction the slope faces, 0–360) of a gradient;
/// `-1` for flat ground (both components 0), as `gdaldem aspect` without `-zero_for_flat`.
#[inline]
pub fn aspect_from_gradient(gx: f64, gy: f64) -> f32 {
    if gx == 0.0 && gy == 0.0 {
        return -1.0;
    }
    let a = (-gx).atan2(-gy).to_degrees();
    let a = if a < 0.0 { a + 360.0 } else { a };
    if a >= 360.0 { 0.0 } else { a as f32 }
}

/// Slope (degrees, 0–90) and aspect (degrees from north clockwise; −1 flat) by Horn's method
/// exactly as `gdaldem slope`/`aspect` (Horn 1981). Unlike gdaldem's default, border cells and
/// cells next to masked cells are computed with edge replication instead of left nodata.
/// Masked cells are NaN.
pub fn slope_aspect(t: &Terrain, m: &Grid<bool>) -> (Grid<f32>, Grid<f32>) {
    let p = Patch::whole(t, m);
    slope_aspect_window(&p, &p.at).expect("the whole raster is its own patch")
}

/// [`slope_aspect`] of the cells of window `out` (raster columns and rows) from patch `p`,
/// which must hold `out` and one cell around it (clipped to the raster): equal bit for bit to
/// the same window of the whole raster's fields. Grids of `out.width × out.height`.
///
/// Errors: [`Error::Invalid`] when the patch lacks the window or its 1-cell halo.
pub fn slope_aspect_window(p: &Patch, out: &Window) -> Result<(Grid<f32>, Grid<f32>)> {
    p.check(out, 1, "slope and aspect")?;
    let w = out.width;
    let mut slope = Grid::filled(w, out.height, f32::NAN);
    let mut aspect = Grid::filled(w, out.height, f32::NAN);
    let dy = p.geo.cell_y_m();
    slope.data.par_chunks_mut(w).zip(aspect.data.par_chunks_mut(w)).enumerate().for_each(|(i, (sr, ar))| {
        let r = out.row0 + i;
        let dx = p.geo.cell_x_m_at_row(r);
        for (j, c) in (out.col0..out.col1()).enumerate() {
            if !p.m.data[p.idx(c, r)] {
                continue;
            }
            let (gx, gy) = horn_gradient(&window3(p, c, r), dx, dy);
            sr[j] = (gx * gx + gy * gy).sqrt().atan().to_degrees() as f32;
            ar[j] = aspect_from_gradient(gx, gy);
        }
    });
    Ok((slope, aspect))
}

/// Column and row offsets (dc, dr) of the D8 neighbours in the order of [`flow_directions`]'
/// codes 0–7: N, NE, E, SE, S, SW, W, NW (rows grow southwards).
pub const D8: [(i64, i64); 8] = [(0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)];

pub(crate) fn is_seed(m: &Grid<bool>, c: usize, r: usize) -> bool {
    if c == 0 || r == 0 || c + 1 == m.width || r + 1 == m.height {
        return true;
    }
    D8.iter().any(|(dc, dr)| !*m.get((c as i64 + dc) as usize, (r as i64 + dr) as usize))
}

/// Monotone priority queue of (key, cell) pairs: a radix heap (Ahuja, Mehlhorn, Orlin & Tarjan
/// 1990, "Faster algorithms for the shortest path problem", J. ACM 37(2), section 2) over 32-bit
/// keys. Valid because Priority-Flood only ever pushes keys ≥ the last key popped; pushes are
/// O(1) and each item moves down at most 32 buckets, with sequential memory access instead of
/// a binary heap's scattered sifts. Equal keys pop last-in first-out (deterministic).
pub(crate) struct RadixHeap {
    last: u32,
    len: usize,
    buckets: Vec<Vec<(u32, u32)>>,
}

impl RadixHeap {
    pub(crate) fn new() -> RadixHeap {
        RadixHeap { last: 0, len: 0, buckets: (0..33).map(|_| Vec::new()).collect() }
    }
    #[inline]
    fn bucket(&self, key: u32) -> usize {
        (32 - (key ^ self.last).leading_zeros()) as usize
    }
    #[inline]
    pub(crate) fn push(&mut self, key: u32, item: u32) {
        debug_assert!(key >= self.last);
        let b = self.bucket(key);
        self.buckets[b].push((key, item));
        self.len += 1;
    }
    pub(crate) fn pop(&mut self) -> Option<(u32, u32)> {
        if self.len == 0 {
            return None;
        }
        if self.buckets[0].is_empty() {
            let i = (1..33).find(|&i| !self.buckets[i].is_empty())?;
            let moved = std::mem::take(&mut self.buckets[i]);
            self.last = moved.iter().map(|e| e.0).min()?;
            for &(k, v) in &moved {
                let b = self.bucket(k);
                self.buckets[b].push((k, v));
            }
            // Reuse the allocation of the emptied bucket.
            let mut moved = moved;
            moved.clear();
            if self.buckets[i].is_empty() {
                self.buckets[i] = moved;
            }
        }
        self.len -= 1;
        self.buckets[0].pop()
    }
}

/// Depression filling to the exact spill levels: plain Priority-Flood (Barnes, Lehman & Mulla
/// 2014, "Priority-flood: an optimal depression-filling and watershed-labeling algorithm for
/// digital elevation models", Computers & Geosciences 62:117–127, Algorithm 2, without the ε of
/// their Algorithm 3). Cells on the grid border or next to a masked cell are outlets (their own
/// elevation); every other valid cell is raised to its spill level, the lowest over all D8 paths
/// from it to an outlet of the highest elevation on the path (m). Every output value is one of
/// the input elevations (a max/min of them, no arithmetic), so the result depends only on the
/// DEM, not on the order cells are flooded: the same bits on one process, by bands or on any
/// number of ranks ([`crate::job::hydrology_ranks::hydrology_of_rank`]). Filled depressions become exact flats; their flow
/// directions are resolved by [`flow_directions`] (Barnes, Lehman & Mulla 2014, flats). The
/// priority queue is a radix heap ([`RadixHeap`]). Cells strictly uphill of a cell whose value
/// is final are final themselves and are traced with a plain stack instead of the queue (Zhou,
/// Sun & Fu 2016, "An efficient variant of the Priority-Flood algorithm for filling depressions
/// in raster digital elevation models", Computers & Geosciences 90:87–96). Shape: `m`'s
/// `width × height`, row 0 north; masked cells stay NaN.
pub fn fill_depressions(t: &Terrain, m: &Grid<bool>) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let mut z: Vec<f32> = t.elevation.data.iter().zip(&m.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect();
    // Closed cells as a bitset (2 MiB for 4096², cache-resident); masked cells start closed.
    let mut closed = vec![0u64; (w * h).div_ceil(64)];
    for (i, ok) in m.data.iter().enumerate() {
        if !*ok {
            closed[i / 64] |= 1 << (i % 64);
        }
    }
    let is_closed = |closed: &[u64], i: usize| closed[i / 64] >> (i % 64) & 1 != 0;
    let close = |closed: &mut [u64], i: usize| closed[i / 64] |= 1 << (i % 64);
    let mut open = RadixHeap::new();
    for r in 0..h {
        for c in 0..w {
            let i = r * w + c;
            if m.data[i] && is_seed(m, c, r) {
                close(&mut closed, i);
                open.push(f32_key(z[i]), i as u32);
            }
        }
    }
    let mut pit: VecDeque<u32> = VecDeque::new();
    let mut trace: Vec<u32> = Vec::new();
    loop {
        // `ordered`: the cell's value is the current flood level (popped from the priority
        // queue, or a pit cell filled to it), so lower neighbours may be filled to it.
        let (ci, ordered) = if let Some(p) = pit.pop_front() {
            (p as usize, true)
        } else if let Some(t) = trace.pop() {
            (t as usize, false)
        } else if let Some((_, i)) = open.pop() {
            (i as usize, true)
        } else {
            break;
        };
        let (c, r) = ((ci % w) as i64, (ci / w) as i64);
        let zc = z[ci];
        let mut deferred = false;
        for (dc, dr) in D8 {
            let (nc, nr) = (c + dc, r + dr);
            if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                continue;
            }
            let ni = nr as usize * w + nc as usize;
            if is_closed(&closed, ni) {
                continue;
            }
            if ordered && z[ni] <= zc {
                // In the depression or flat spilling over this cell: its spill level is the
                // flood's level.
                close(&mut closed, ni);
                z[ni] = zc;
                pit.push_back(ni as u32);
            } else if z[ni] > zc {
                // Strictly uphill of a cell whose value is final: it drains through it, so its
                // own elevation is final too (Zhou, Sun & Fu 2016, slope tracing).
                close(&mut closed, ni);
                trace.push(ni as u32);
            } else {
                // A lower (or equal) neighbour of a traced slope cell: its spill level is not
                // known until the flood reaches this cell's level in order.
                deferred = true;
            }
        }
        if deferred {
            open.push(f32_key(zc), ci as u32);
        }
    }
    Grid { width: w, height: h, data: z }
}

/// Monotone map of a finite f32 to u32 (the total order of finite values).
#[inline]
pub(crate) fn f32_key(v: f32) -> u32 {
    let b = v.to_bits();
    if b & 0x8000_0000 != 0 { !b } else { b | 0x8000_0000 }
}

/// Outlet marker in a D8 direction grid.
pub const OUTLET: u8 = 255;

/// Marker of a cell with no downhill neighbour while [`flow_directions`] resolves flats.
pub(crate) const NOFLOW: u8 = 254;

/// D8 flow directions (O'Callaghan & Mark 1984) on a filled DEM ([`fill_depressions`]): index
/// 0–7 into N, NE, E, SE, S, SW, W, NW ([`D8`]) of the steepest strictly downhill neighbour
/// (drop / distance, metres; ties to the first in that order); [`OUTLET`] for masked cells and
/// for outlets (cells on the border or next to a masked cell) with no lower valid neighbour.
///
/// Flats (an 8-connected set of valid non-outlet cells of equal filled elevation with no lower
/// neighbour) drain by Barnes, Lehman & Mulla (2014, "An efficient assignment of drainage
/// direction over flat surfaces in raster digital elevation models", Computers & Geosciences
/// 62:128–135): each flat cell gets `2·t + (H − a)`, with `t` its breadth-first distance in
/// cells (within the flat, 8-connected) from the flat's low edges (cells of equal elevation that
/// drain: they have a lower neighbour or are outlets), `a` its distance from the flat's high
/// edges (flat cells next to higher ground; `a = 1` there) and `H` the largest `a` of the flat
/// (the term is 0 in a flat with no higher edge); low edges count as 0. A flat cell flows to
/// the neighbour of its flat, or low edge, with the steepest fall of that value per metre
/// (ties to the first in D8's order): towards the outlets and away from higher ground. Every
/// step is an integer distance, so the directions depend only on the filled DEM, not on the
/// order of any pass. Shape: `m`'s `width × height`.
pub fn flow_directions(filled: &Grid<f32>, geo: &GeoRef, m: &Grid<bool>) -> Grid<u8> {
    let (w, h) = (m.width, m.height);
    let mut dir = Grid::filled(w, h, OUTLET);
    let dists = |r: usize| d8_dists(geo, r);
    dir.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dist = dists(r);
        for c in 0..w {
            if !*m.get(c, r) {
                continue;
            }
            let code = steepest(*filled.get(c, r), &dist, |k| {
                let (nc, nr) = (c as i64 + D8[k].0, r as i64 + D8[k].1);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 || !*m.get(nc as usize, nr as usize) {
                    return None;
                }
                Some(*filled.get(nc as usize, nr as usize))
            });
            row[c] = if code == OUTLET && !is_seed(m, c, r) { NOFLOW } else { code };
        }
    });
    resolve_flats(&mut dir, filled, m, &dists);
    dir
}

/// The D8 code of the steepest strictly downhill neighbour of a cell at filled level `z0`
/// (drop / distance; ties to the first in [`D8`]'s order), [`OUTLET`] when none is lower.
/// `dist`: the step lengths (m) of the cell's row; `nb(k)`: the filled level of neighbour `k`,
/// `None` off the raster or masked.
#[inline]
pub(crate) fn steepest(z0: f32, dist: &[f64; 8], nb: impl Fn(usize) -> Option<f32>) -> u8 {
    let mut best = (0.0f64, OUTLET);
    for (k, d) in dist.iter().enumerate() {
        if let Some(zn) = nb(k) {
            let drop = (z0 - zn) as f64 / d;
            if drop > best.0 {
                best = (drop, k as u8);
            }
        }
    }
    best.1
}

/// The lengths (m) of the D8 steps ([`D8`]'s order) from a cell of raster row `r` of `geo`.
pub(crate) fn d8_dists(geo: &GeoRef, r: usize) -> [f64; 8] {
    let (dx, dy) = (geo.cell_x_m_at_row(r), geo.cell_y_m());
    D8.map(|(dc, dr)| ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt())
}

/// The valid in-grid D8 neighbours `(k, index)` of cell `i` of a `w × h` grid.
#[inline]
pub(crate) fn neighbours(i: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    let (c, r) = ((i % w) as i64, (i / w) as i64);
    D8.iter().enumerate().filter_map(move |(k, (dc, dr))| {
        let (nc, nr) = (c + dc, r + dr);
        (nc >= 0 && nr >= 0 && nc < w as i64 && nr < h as i64).then(|| (k, nr as usize * w + nc as usize))
    })
}

/// Gives every [`NOFLOW`] cell of `dir` a direction by Barnes, Lehman & Mulla's (2014) flat
/// gradients (see [`flow_directions`]). `dists(r)`: the D8 step lengths (m) in row `r`.
fn resolve_flats(dir: &mut Grid<u8>, filled: &Grid<f32>, m: &Grid<bool>, dists: &dyn Fn(usize) -> [f64; 8]) {
    let (w, h) = (m.width, m.height);
    let cells: Vec<FlatCell> = (0..w * h).filter(|&i| dir.data[i] == NOFLOW).map(|i| flat_cell(i, w, h, &|n| (m.data[n], filled.data[n], dir.data[n] != NOFLOW), filled.data[i])).collect();
    if cells.is_empty() {
        return;
    }
    let mut slot = vec![u32::MAX; w * h];
    for (k, c) in cells.iter().enumerate() {
        slot[c.i] = k as u32;
    }
    let dirs = flat_dirs(&cells, w, h, &|i| (slot[i] != u32::MAX).then(|| slot[i] as usize), dists);
    for (c, d) in cells.iter().zip(dirs) {
        dir.data[c.i] = d;
    }
}

/// A cell of a flat (a [`NOFLOW`] cell) as [`flat_dirs`] sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FlatCell {
    /// Row-major index in the whole raster.
    pub i: usize,
    /// Next to higher ground (a valid neighbour with a higher filled elevation): a high edge.
    pub high: bool,
    /// Bit k set: neighbour k ([`D8`]) is a low edge (valid, equal filled elevation, drains).
    pub low: u8,
}

/// The [`FlatCell`] of flat cell `i` (filled elevation `z`) of a `w × h` raster; `nb(n)`: for
/// a neighbour `n`, (valid, filled elevation, drains: not [`NOFLOW`]).
pub(crate) fn flat_cell(i: usize, w: usize, h: usize, nb: &dyn Fn(usize) -> (bool, f32, bool), z: f32) -> FlatCell {
    let (mut high, mut low) = (false, 0u8);
    for (k, n) in neighbours(i, w, h) {
        let (ok, zn, drains) = nb(n);
        if ok && zn > z {
            high = true;
        }
        if ok && zn == z && drains {
            low |= 1 << k;
        }
    }
    FlatCell { i, high, low }
}

/// D8 codes of flat cells by Barnes, Lehman & Mulla's (2014) gradients towards lower and away
/// from higher edges ([`flow_directions`]). `cells`: every cell of each flat they belong to
/// (two flat cells side by side are in one flat: a cell next to a lower one would drain), in
/// any order; `slot(i)`: the position in `cells` of raster cell `i`, `None` outside them;
/// `dists(r)`: the D8 step lengths (m) of row `r` of the `w × h` raster. Breadth-first
/// distances are exact integers, so the codes depend only on the set of cells and their flags,
/// not on their order or on how the raster is cut. A flat with no low edge (only on a DEM that
/// was not filled) gets [`OUTLET`].
pub(crate) fn flat_dirs(cells: &[FlatCell], w: usize, h: usize, slot: &dyn Fn(usize) -> Option<usize>, dists: &dyn Fn(usize) -> [f64; 8]) -> Vec<u8> {
    const NONE: u32 = u32::MAX;
    let n = cells.len();
    // the flat (8-connected component) of each cell
    let mut label = vec![NONE; n];
    let mut nlabels = 0u32;
    let mut queue: VecDeque<usize> = VecDeque::new();
    for s in 0..n {
        if label[s] != NONE {
            continue;
        }
        label[s] = nlabels;
        queue.push_back(s);
        while let Some(k) = queue.pop_front() {
            for (_, j) in neighbours(cells[k].i, w, h) {
                if let Some(q) = slot(j) {
                    if label[q] == NONE {
                        label[q] = nlabels;
                        queue.push_back(q);
                    }
                }
            }
        }
        nlabels += 1;
    }
    // breadth-first distance (1 at the seeds) within the flat from the seed cells
    let bfs = |seed: &dyn Fn(&FlatCell) -> bool, height: &mut Vec<u32>| -> Vec<u32> {
        let mut dist = vec![0u32; n];
        let mut q: Vec<usize> = (0..n).filter(|&k| seed(&cells[k])).collect();
        for &k in &q {
            dist[k] = 1;
        }
        let mut d = 1u32;
        while !q.is_empty() {
            let mut next = Vec::new();
            for &k in &q {
                height[label[k] as usize] = d;
                for (_, j) in neighbours(cells[k].i, w, h) {
                    if let Some(p) = slot(j) {
                        if dist[p] == 0 {
                            dist[p] = d + 1;
                            next.push(p);
                        }
                    }
                }
            }
            q = next;
            d += 1;
        }
        dist
    };
    // a: from the high edges, H per flat (its largest a; 0 with no high edge)
    let mut height = vec![0u32; nlabels as usize];
    let away = bfs(&|c| c.high, &mut height);
    let mut unused = vec![0u32; nlabels as usize];
    let toward = bfs(&|c| c.low != 0, &mut unused);
    let value = |k: usize| -> u64 {
        let hl = height[label[k] as usize] as u64;
        2 * toward[k] as u64 + if hl > 0 { hl - away[k] as u64 } else { 0 }
    };
    (0..n)
        .map(|k| {
            let c = cells[k];
            let v = value(k);
            let dist = dists(c.i / w);
            let mut best = (0.0f64, OUTLET);
            for (d, j) in neighbours(c.i, w, h) {
                // a low edge counts 0; a neighbour in the flat its value; any other is not a way out
                let vn = if c.low >> d & 1 != 0 {
                    0
                } else if let Some(q) = slot(j) {
                    value(q)
                } else {
                    continue;
                };
                if vn < v {
                    let fall = (v - vn) as f64 / dist[d];
                    if fall > best.0 {
                        best = (fall, d as u8);
                    }
                }
            }
            best.1
        })
        .collect()
}

/// The cell (row-major index) that cell `i` of the D8 direction grid `dir` drains into; `None`
/// at an outlet ([`OUTLET`]), for a code that is not a direction, or for a step off the grid.
pub fn downstream(dir: &Grid<u8>, i: usize) -> Option<usize> {
    d8_step(i, *dir.data.get(i)?, dir.width, dir.height)
}

/// The cell (row-major index) that cell `g` of a `w × h` raster drains into under the D8 code
/// `d` (index into [`D8`]); `None` for [`OUTLET`], any other code that is not a direction, or a
/// step off the raster.
#[inline]
pub(crate) fn d8_step(g: usize, d: u8, w: usize, h: usize) -> Option<usize> {
    let (dc, dr) = *D8.get(d as usize)?;
    let (c, r) = ((g % w) as i64 + dc, (g / w) as i64 + dr);
    (c >= 0 && r >= 0 && (c as usize) < w && (r as usize) < h).then(|| r as usize * w + c as usize)
}

/// D8 flow accumulation (number of cells, including the cell itself, draining through each
/// cell), by a topological sweep (Kahn) over the direction grid. Masked cells hold 0.
/// Invariant: the sum over outlet cells equals the number of valid cells.
pub fn flow_accumulation(dir: &Grid<u8>, m: &Grid<bool>) -> Grid<f32> {
    let acc = accumulate(m.width * m.height, |i| m.data[i], |i| downstream(dir, i));
    Grid { width: m.width, height: m.height, data: acc.into_iter().map(|v| v as f32).collect() }
}

/// The topological sweep (Kahn) of [`flow_accumulation`] over `n` cells: each cell `i` with
/// `valid(i)` counts 1 and passes its count to `down(i)` (`None`: it leaves the cells swept);
/// invalid cells hold 0. The order of the additions is fixed by the cells' indices, so the
/// result is the same bit for bit wherever the sweep runs (the whole raster, or one band of it
/// in `terrain::hydrology`).
pub(crate) fn accumulate(n: usize, valid: impl Fn(usize) -> bool, down: impl Fn(usize) -> Option<usize>) -> Vec<f64> {
    let mut indeg = vec![0u8; n];
    for i in 0..n {
        if valid(i) {
            if let Some(j) = down(i) {
                indeg[j] += 1;
            }
        }
    }
    let mut acc: Vec<f64> = (0..n).map(|i| if valid(i) { 1.0 } else { 0.0 }).collect();
    let mut stack: Vec<usize> = (0..n).filter(|&i| valid(i) && indeg[i] == 0).collect();
    while let Some(i) = stack.pop() {
        if let Some(j) = down(i) {
            acc[j] += acc[i];
            indeg[j] -= 1;
            if indeg[j] == 0 {
                stack.push(j);
            }
        }
    }
    acc
}

/// Minimum tan β used in the TWI so that flat cells stay finite (≈ 0.057°).
pub const MIN_TAN_SLOPE: f64 = 0.001;

/// Topographic wetness index TWI = ln(a / tan β) (Beven & Kirkby 1979): `a` = upslope area per
/// unit contour width = accumulation · cell area / east–west cell width (m; D8, one cell width
/// of contour), β = Horn slope, tan β ≥ [`MIN_TAN_SLOPE`]. Dimensionless; NaN where masked.
pub fn twi(acc: &Grid<f32>, slope_deg: &Grid<f32>, geo: &GeoRef, m: &Grid<bool>) -> Grid<f32> {
    twi_window(acc, slope_deg, geo, m, 0)
}

/// [`twi`] of a window of the raster whose first row is raster row `row0` (`acc`, `slope_deg`
/// and `m` the window's cells; `geo` the whole raster's): cell-local given the window's flow
/// accumulation and slope, so equal bit for bit to the same window of the whole raster's TWI.
pub fn twi_window(acc: &Grid<f32>, slope_deg: &Grid<f32>, geo: &GeoRef, m: &Grid<bool>, row0: usize) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let mut out = Grid::filled(w, h, f32::NAN);
    let dy = geo.cell_y_m();
    out.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dx = geo.cell_x_m_at_row(row0 + r);
        for c in 0..w {
            if *m.get(c, r) {
                let a = *acc.get(c, r) as f64 * dx * dy / dx;
                let tb = (*slope_deg.get(c, r) as f64).to_radians().tan().max(MIN_TAN_SLOPE);
                row[c] = (a / tb).ln() as f32;
            }
        }
    });
    out
}

/// Settings of the sun and horizon model.
#[derive(Debug, Clone)]
pub struct SkyParams {
    /// Days sampled over the year (mid-month days when 12), ≥ 1.
    pub days: usize,
    /// Sun positions per day (evenly spaced over 24 h, at interval midpoints), ≥ 1.
    pub steps_per_day: usize,
    /// Atmospheric transmittance τ of the clear-sky model (0–1).
    pub transmittance: f64,
    /// Largest distance (m) searched for the horizon.
    pub horizon_max_m: f64,
    /// Largest distance in cells searched for the horizon.
    pub horizon_max_cells: usize,
}

impl Default for SkyParams {
    fn default() -> Self {
        SkyParams { days: 12, steps_per_day: 24, transmittance: 0.7, horizon_max_m: 20_000.0, horizon_max_cells: 128 }
    }
}

/// One sampled sun position with the energy it brings (Wh/m² over the year for the time step).
#[derive(Debug, Clone, Copy)]
struct Sun {
    v: [f64; 3],
    tan_alt: f64,
    sector: usize,
    frac: f64,
    beam_wh: f64,
    diffuse_wh: f64,
}

/// Sun positions above the horizon for latitude `lat_deg`: declination and direction from
/// [`crate::sun`] (Cooper 1969: δ = 23.45° sin(360°(284+n)/365); hour angle 15°/h); clear-sky beam normal irradiance
/// I₀ τ^M and diffuse horizontal irradiance I₀ (0.271 − 0.294 τ^M) sin α, with I₀ = 1367 W/m² ·
/// (1 + 0.034 cos(360° n/365)) and air mass M = √(1229 + (614 sin α)²) − 614 sin α
/// (Kumar, Skidmore & Knowles 1997, Int. J. GIS 11(5):475–497, eqs. 1–9).
fn sun_table(lat_deg: f64, p: &SkyParams) -> Vec<Sun> {
    let phi = lat_deg.to_radians();
    let days = p.days.max(1);
    let steps = p.steps_per_day.max(1);
    let day_w = 365.0 / days as f64;
    let dt_h = 24.0 / steps as f64;
    let mut out = Vec::new();
    for d in 0..days {
        let n = ((d as f64 + 0.5) * day_w).round();
        let decl = crate::sun::declination_rad(n);
        let i0 = 1367.0 * (1.0 + 0.034 * (2.0 * std::f64::consts::PI * n / 365.0).cos());
        for s in 0..steps {
            let hour = (s as f64 + 0.5) * dt_h;
            let [e, nn, u] = crate::sun::direction(phi, decl, hour);
            if u <= 0.0 {
                continue;
            }
            let am = (1229.0 + (614.0 * u).powi(2)).sqrt() - 614.0 * u;
            let tm = p.transmittance.powf(am);
            let az = e.atan2(nn).to_degrees().rem_euclid(360.0);
            let sec = az / 45.0;
            let horiz = (e * e + nn * nn).sqrt();
            out.push(Sun {
                v: [e, nn, u],
                tan_alt: u / horiz.max(1e-12),
                sector: (sec.floor() as usize) % 8,
                frac: sec - sec.floor(),
                beam_wh: i0 * tm * dt_h * day_w,
                diffuse_wh: i0 * (0.271 - 0.294 * tm).max(0.0) * u * dt_h * day_w,
            });
        }
    }
    out
}

/// Annual clear-sky insolation on flat, unobstructed ground (kWh/m²/yr) at `lat_deg`, with the
/// model of [`insolation_and_wind`].
pub fn flat_insolation(lat_deg: f64, p: &SkyParams) -> f64 {
    sun_table(lat_deg, p).iter().map(|s| s.beam_wh * s.v[2] + s.diffuse_wh).sum::<f64>() / 1000.0
}

/// Latitude (degrees) the sun model uses for row `r`: per row for geographic grids, the grid's
/// centre latitude for projected grids whose CRS the reader inverted (UTM on WGS 84, NAD83 or
/// ETRS89, or a `.prj`: [`GeoRef::insolation_latitude_deg`]), else `climate_lat`. Until round 37
/// only WGS 84 UTM codes (EPSG 326xx/327xx) took their own latitude, so a NAD83 or ETRS89 DEM
/// got the climate's (46° by default).
pub fn row_latitude(geo: &GeoRef, r: usize, climate_lat: f64) -> f64 {
    match geo.crs {
        Crs::Geographic => geo.row_latitude_deg(r),
        _ => geo.insolation_latitude_deg(climate_lat),
    }
}

/// Distances (in cells along a direction) of the horizon search: geometric, 1 … max.
fn horizon_steps(max_cells: usize) -> Vec<usize> {
    let mut v = Vec::new();
    let mut s = 1.0f64;
    while (s.round() as usize) <= max_cells.max(1) {
        let k = s.round() as usize;
        if v.last() != Some(&k) {
            v.push(k);
        }
        s *= 1.5;
    }
    v
}

/// Sun positions of one latitude regrouped for the per-cell loop: sorted by azimuth sector
/// (0 = N–NE, …, 7 = NW–N) into structure-of-arrays slices, f32, so that the inner loop is
/// branch-free and vectorises.
struct SunSoA {
    /// Start of each sector's slice (9 entries; sector k is `start[k]..start[k+1]`).
    start: [usize; 9],
    vx: Vec<f32>,
    vy: Vec<f32>,
    vz: Vec<f32>,
    tan_alt: Vec<f32>,
    frac: Vec<f32>,
    beam_wh: Vec<f32>,
    /// Σ diffuse horizontal energy over all positions (Wh/m², unobstructed flat ground).
    diffuse_wh: f64,
}

impl SunSoA {
    fn new(suns: &[Sun]) -> SunSoA {
        // Sector slices padded with zero-energy entries to a multiple of `LANES`, so the inner
        // loop runs on whole lanes.
        let mut soa = SunSoA { start: [0; 9], vx: vec![], vy: vec![], vz: vec![], tan_alt: vec![], frac: vec![], beam_wh: vec![], diffuse_wh: suns.iter().map(|s| s.diffuse_wh).sum() };
        for k in 0..8 {
            soa.start[k] = soa.vx.len();
            for s in suns.iter().filter(|s| s.sector == k) {
                soa.vx.push(s.v[0] as f32);
                soa.vy.push(s.v[1] as f32);
                soa.vz.push(s.v[2] as f32);
                soa.tan_alt.push(s.tan_alt as f32);
                soa.frac.push(s.frac as f32);
                soa.beam_wh.push(s.beam_wh as f32);
            }
            while soa.vx.len() % LANES != 0 {
                for v in [&mut soa.vx, &mut soa.vy, &mut soa.vz, &mut soa.tan_alt, &mut soa.frac, &mut soa.beam_wh] {
                    v.push(0.0);
                }
            }
        }
        soa.start[8] = soa.vx.len();
        soa
    }

    /// Beam energy (Wh/m²) on a surface of unit normal `n` with horizon tangents `hz` (N, NE, …,
    /// NW), linearly interpolated in azimuth between the two directions bounding each sun.
    #[inline]
    fn beam(&self, n: [f32; 3], hz: &[f32; 8]) -> f32 {
        let mut lanes = [0f32; LANES];
        for k in 0..8 {
            let (a, b) = (hz[k], hz[(k + 1) % 8] - hz[k]);
            let r = self.start[k]..self.start[k + 1];
            let it = self.vx[r.clone()]
                .chunks_exact(LANES)
                .zip(self.vy[r.clone()].chunks_exact(LANES))
                .zip(self.vz[r.clone()].chunks_exact(LANES))
                .zip(self.tan_alt[r.clone()].chunks_exact(LANES))
                .zip(self.frac[r.clone()].chunks_exact(LANES))
                .zip(self.beam_wh[r].chunks_exact(LANES));
            for (((((vx, vy), vz), ta), fr), bw) in it {
                for j in 0..LANES {
                    let ci = n[0] * vx[j] + n[1] * vy[j] + n[2] * vz[j];
                    let lit = (ta[j] > a + b * fr[j]) as u32 as f32;
                    lanes[j] += bw[j] * if ci > 0.0 { ci } else { 0.0 } * lit;
                }
            }
        }
        lanes.iter().sum()
    }
}

/// arctan in degrees by the polynomial of Abramowitz & Stegun (1964), *Handbook of
/// Mathematical Functions*, eq. 4.4.49 (|error| ≤ 2·10⁻⁸ rad on [0, 1]), with
/// atan x = 90° − atan(1/x) for |x| > 1. Branch-light and several times faster than libm's
/// atan, which matters at 8 calls per cell on 16 M cells.
#[inline]
fn atan_deg(x: f32) -> f32 {
    let (ax, sign) = (x.abs() as f64, if x < 0.0 { -1.0 } else { 1.0 });
    let (t, inv) = if ax > 1.0 { (1.0 / ax, true) } else { (ax, false) };
    let t2 = t * t;
    const A: [f64; 8] = [0.999_999_332_9, -0.333_298_560_5, 0.199_465_359_9, -0.139_085_335_1, 0.096_420_044_1, -0.055_909_886_1, 0.021_861_228_8, -0.004_054_058_0];
    let mut p = A[7];
    for k in (0..7).rev() {
        p = p * t2 + A[k];
    }
    let a = p * t;
    let a = if inv { std::f64::consts::FRAC_PI_2 - a } else { a };
    (sign * a.to_degrees()) as f32
}

/// Width of the vectorised sun loop.
const LANES: usize = 8;

/// Annual clear-sky insolation with terrain shading (kWh/m²/yr) and wind exposure (0–1).
///
/// Horizons: for each cell, the tangent of the highest elevation angle of valid terrain along
/// 8 directions (N, NE, …, NW), sampled at geometric distances (×1.5: 1, 2, 3, 5, 8, 11, 17, …)
/// up to `horizon_max_cells` cells and `horizon_max_m` metres. Near the grid's edge the march in
/// a direction is cut short (the terrain beyond is unknown). With f the fraction of the march's
/// distance inside the grid and H̄ the mean horizon of the cell's complete directions, a truncated
/// horizon H becomes f·H + (1 − f)·max(H, H̄): continuous where the march becomes complete (no
/// seam), and border cells are not read as exposed ridges merely because the grid ends. A
/// direction with no valid sample takes H̄ (0 when no direction is complete).
/// The march runs per row over all columns at once (one pass per direction and distance), so it
/// streams through memory and vectorises.
/// Insolation: Σ over sampled sun positions (see `sun_table`) of beam · max(0, n·s) where the
/// sun's altitude exceeds the horizon (interpolated between the two nearest directions), plus
/// diffuse · V, with sky view V = (1 + cos β)/2 · mean_k cos² H_k⁺ (Dozier & Frew 1990,
/// IEEE TGRS 28(5), eq. 7, for the horizon part). n from Horn's gradient.
/// Wind: a directional shelter index like TOPEX (Wilson 1984): x = 0.7·H_wind + 0.3·mean_k H_k
/// (degrees; H_wind interpolated toward `wind_from_deg`), exposure = clamp(0.5 − x/30°, 0, 1):
/// flat open ground 0.5, a 15°-sheltered hollow 0, a ridge 15° above its surroundings 1.
pub fn insolation_and_wind(t: &Terrain, m: &Grid<bool>, climate_lat: f64, wind_from_deg: f64, p: &SkyParams) -> (Grid<f32>, Grid<f32>) {
    let patch = Patch::whole(t, m);
    insolation_and_wind_window(&patch, &patch.at, climate_lat, wind_from_deg, p).expect("the whole raster is its own patch")
}

/// Cells of the horizon search's reach around a cell (and at least 1, for the slope): the
/// largest of the geometric steps up to `horizon_max_cells` whose distance along a row or a
/// column, at the raster's smallest cell size, stays within `horizon_max_m`. A patch holding a
/// window and this many cells around it gives the window's insolation and wind exposure of the
/// whole raster ([`insolation_and_wind_window`]): 86 cells with the defaults on 10–80 m cells
/// (the geometric steps 1, 2, 3, 5, 8, 11, 17, 26, 38, 58, 86 within the 128-cell cap).
pub fn horizon_halo_cells(geo: &GeoRef, full_h: usize, p: &SkyParams) -> usize {
    // the east–west size is smallest at one end of the rows (cos is concave on ±90°)
    let dx = geo.cell_x_m_at_row(0).min(geo.cell_x_m_at_row(full_h.saturating_sub(1)));
    let d1 = dx.min(geo.cell_y_m());
    horizon_steps(p.horizon_max_cells).into_iter().take_while(|&s| s as f64 * d1 <= p.horizon_max_m).last().unwrap_or(0).max(1)
}

/// [`insolation_and_wind`] of the cells of window `out` (raster columns and rows) from patch
/// `patch`, which must hold `out` and [`horizon_halo_cells`] around it (clipped to the raster):
/// the horizon march and its truncation at the raster's edges run in raster coordinates, so the
/// result equals the same window of the whole raster's fields bit for bit. Grids of
/// `out.width × out.height`.
///
/// Errors: [`Error::Invalid`] when the patch lacks the window or its halo.
pub fn insolation_and_wind_window(patch: &Patch, out: &Window, climate_lat: f64, wind_from_deg: f64, p: &SkyParams) -> Result<(Grid<f32>, Grid<f32>)> {
    patch.check(out, horizon_halo_cells(patch.geo, patch.full_h, p), "insolation and wind exposure")?;
    let (w, h) = (patch.full_w, patch.full_h);
    let (ow, pw) = (out.width, patch.at.width);
    let mut ins = Grid::filled(ow, out.height, f32::NAN);
    let mut wind = Grid::filled(ow, out.height, f32::NAN);
    let geo = patch.geo;
    let dy = geo.cell_y_m();
    let geographic = geo.crs == Crs::Geographic;
    let shared_sun = if geographic { None } else { Some(SunSoA::new(&sun_table(row_latitude(geo, 0, climate_lat), p))) };
    let steps = horizon_steps(p.horizon_max_cells);
    let wsec = (wind_from_deg.rem_euclid(360.0)) / 45.0;
    let (wk, wf) = ((wsec.floor() as usize) % 8, wsec - wsec.floor());
    // Masked cells read as NaN so that they never raise a horizon.
    let zm: Vec<f32> = patch.z.data.iter().zip(&patch.m.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect();
    ins.data.par_chunks_mut(ow).zip(wind.data.par_chunks_mut(ow)).enumerate().for_each(|(i, (irow, wrow))| {
        let r = out.row0 + i;
        let own_sun;
        let suns: &SunSoA = match &shared_sun {
            Some(s) => s,
            None => {
                own_sun = SunSoA::new(&sun_table(row_latitude(geo, r, climate_lat), p));
                &own_sun
            }
        };
        let dx = geo.cell_x_m_at_row(r);
        // row r of the patch, from raster column patch.at.col0
        let prow = |rr: usize| &zm[(rr - patch.at.row0) * pw..(rr - patch.at.row0 + 1) * pw];
        let z0 = prow(r);
        // hz[k][j]: horizon tangent of direction k for column out.col0 + j
        let mut hz = vec![vec![f32::NEG_INFINITY; ow]; 8];
        let mut nsteps = [0usize; 8];
        for (k, &(dc, dr)) in D8.iter().enumerate() {
            let d1 = ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt();
            let n = steps.iter().take_while(|&&s| s as f64 * d1 <= p.horizon_max_m).count();
            nsteps[k] = n;
            let best = &mut hz[k];
            for &s in &steps[..n] {
                let rr = r as i64 + dr * s as i64;
                if rr < 0 || rr >= h as i64 {
                    break;
                }
                let shift = dc * s as i64;
                // Raster columns c of the window with 0 ≤ c + shift < w.
                let (c0, c1) = if shift >= 0 { (out.col0, out.col1().min(w.saturating_sub(shift as usize))) } else { (out.col0.max(((-shift) as usize).min(w)), out.col1()) };
                if c0 >= c1 {
                    continue;
                }
                let src = prow(rr as usize);
                let src = &src[(c0 as i64 + shift) as usize - patch.at.col0..(c1 as i64 + shift) as usize - patch.at.col0];
                let inv = (1.0 / (d1 * s as f64)) as f32;
                for ((b, &zz), &zc) in best[c0 - out.col0..c1 - out.col0].iter_mut().zip(src).zip(&z0[c0 - patch.at.col0..c1 - patch.at.col0]) {
                    *b = b.max((zz - zc) * inv);
                }
            }
        }
        for (j, c) in (out.col0..out.col1()).enumerate() {
            if !patch.m.data[patch.idx(c, r)] {
                continue;
            }
            let mut hc = [0f32; 8];
            let mut covered = [0f32; 8];
            let (mut sum, mut cnt) = (0f32, 0u32);
            for k in 0..8 {
                hc[k] = hz[k][j];
                let (dc, dr) = D8[k];
                // Steps of the march that stay inside the raster.
                let room_c = if dc > 0 { (w - 1 - c) as i64 } else if dc < 0 { c as i64 } else { i64::MAX };
                let room_r = if dr > 0 { (h - 1 - r) as i64 } else if dr < 0 { r as i64 } else { i64::MAX };
                let room = room_c.min(room_r);
                let reach = if nsteps[k] == 0 { 0 } else { steps[nsteps[k] - 1] as i64 };
                covered[k] = if reach == 0 { 1.0 } else { (room.min(reach) as f32 / reach as f32).min(1.0) };
                if covered[k] >= 1.0 && hc[k].is_finite() {
                    sum += hc[k];
                    cnt += 1;
                }
            }
            let fill = if cnt > 0 { sum / cnt as f32 } else { 0.0 };
            for k in 0..8 {
                if covered[k] < 1.0 || !hc[k].is_finite() {
                    if !hc[k].is_finite() {
                        hc[k] = fill;
                    } else if cnt > 0 {
                        let f = covered[k];
                        hc[k] = f * hc[k] + (1.0 - f) * hc[k].max(fill);
                    }
                }
            }
            let (gx, gy) = horn_gradient(&window3(patch, c, r), dx, dy);
            let nl = (gx * gx + gy * gy + 1.0).sqrt();
            let nv = [(-gx / nl) as f32, (-gy / nl) as f32, (1.0 / nl) as f32];
            let beam = suns.beam(nv, &hc) as f64;
            let horizon_v: f64 = hc.iter().map(|&tn| 1.0 / (1.0 + (tn.max(0.0) as f64).powi(2))).sum::<f64>() / 8.0;
            let svf = (1.0 + nv[2] as f64) / 2.0 * horizon_v;
            irow[j] = ((beam + suns.diffuse_wh * svf) / 1000.0) as f32;
            let ang = hc.map(|tn| atan_deg(tn) as f64);
            let h_wind = ang[wk] * (1.0 - wf) + ang[(wk + 1) % 8] * wf;
            let mean = ang.iter().sum::<f64>() / 8.0;
            let x = 0.7 * h_wind + 0.3 * mean;
            wrow[j] = (0.5 - x / 30.0).clamp(0.0, 1.0) as f32;
        }
    });
    Ok((ins, wind))
}

/// Mean annual air temperature (°C): `ref + lapse · (z − z_ref) / 1000` (lapse in K/km, default
/// −6.5, the ICAO standard atmosphere). NaN where masked.
pub fn temperature(t: &Terrain, m: &Grid<bool>, c: &Climate) -> Grid<f32> {
    let mut out = Grid::filled(m.width, m.height, f32::NAN);
    for (i, o) in out.data.iter_mut().enumerate() {
        if m.data[i] {
            *o = c.reference_temperature_c + c.lapse_rate_k_per_km * (t.elevation.data[i] - c.reference_elevation_m) / 1000.0;
        }
    }
    out
}

/// Hillshade (0–255) as `gdaldem hillshade` with its defaults: light from azimuth 315°,
/// altitude 45°, Horn gradient; value = 255 · max(0, n·l). NaN where masked.
pub fn hillshade(t: &Terrain, m: &Grid<bool>, azimuth_deg: f64, altitude_deg: f64) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let (az, alt) = (azimuth_deg.to_radians(), altitude_deg.to_radians());
    let l = [az.sin() * alt.cos(), az.cos() * alt.cos(), alt.sin()];
    let dy = t.geo.cell_y_m();
    let mut out = Grid::filled(w, h, f32::NAN);
    let p = Patch::whole(t, m);
    out.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dx = t.geo.cell_x_m_at_row(r);
        for c in 0..w {
            if *m.get(c, r) {
                let (gx, gy) = horn_gradient(&window3(&p, c, r), dx, dy);
                let nl = (gx * gx + gy * gy + 1.0).sqrt();
                row[c] = (255.0 * ((-gx * l[0] - gy * l[1] + l[2]) / nl).max(0.0)) as f32;
            }
        }
    });
    out
}

/// All fields of a terrain.
#[derive(Debug, Clone)]
pub struct Fields {
    /// Valid cells above sea level.
    pub mask: Grid<bool>,
    /// Slope (degrees).
    pub slope_deg: Grid<f32>,
    /// Aspect (degrees from north clockwise, −1 flat).
    pub aspect_deg: Grid<f32>,
    /// Depression-filled elevation (m).
    pub filled_m: Grid<f32>,
    /// D8 flow accumulation (cells).
    pub flow_acc_cells: Grid<f32>,
    /// Topographic wetness index (dimensionless).
    pub twi: Grid<f32>,
    /// Annual clear-sky insolation with shading (kWh/m²/yr).
    pub insolation_kwh_m2: Grid<f32>,
    /// Flat-ground unshaded annual insolation at the grid's (centre) latitude (kWh/m²/yr).
    pub flat_insolation_kwh_m2: f64,
    /// Wind exposure (0–1).
    pub wind_exposure: Grid<f32>,
    /// Mean annual temperature (°C).
    pub temperature_c: Grid<f32>,
}

/// Computes every field of `t` for `climate`, reporting each stage through `progress`.
///
/// Errors: [`Error::Invalid`] when no cell is above sea level.
pub fn compute(t: &Terrain, climate: &Climate, progress: &dyn Fn(&str)) -> Result<Fields> {
    let m = mask(t, climate.sea_level_m);
    if !m.data.iter().any(|v| *v) {
        return Err(Error::Invalid {
            context: t.source.clone(),
            field: "sea_level_m".into(),
            value: climate.sea_level_m.to_string(),
            expected: "a sea level below some valid elevation (every cell is nodata or water)".into(),
        });
    }
    // Two independent branches run concurrently: the hydrology chain (priority-flood is
    // sequential) and the per-cell fields (parallel over rows), so that on 2 cores the
    // sequential fill overlaps the rest.
    progress("slope, aspect, depression filling, flow, insolation, wind exposure, temperature");
    let p = SkyParams::default();
    let ((filled_m, flow_acc_cells), ((slope_deg, aspect_deg), (insolation_kwh_m2, wind_exposure), temperature_c)) = rayon::join(
        || {
            let filled = fill_depressions(t, &m);
            let dir = flow_directions(&filled, &t.geo, &m);
            let acc = flow_accumulation(&dir, &m);
            (filled, acc)
        },
        || (slope_aspect(t, &m), insolation_and_wind(t, &m, climate.latitude_deg, climate.wind_from_deg as f64, &p), temperature(t, &m, climate)),
    );
    progress("topographic wetness index");
    let twi = twi(&flow_acc_cells, &slope_deg, &t.geo, &m);
    let flat_insolation_kwh_m2 = flat_insolation(row_latitude(&t.geo, m.height / 2, climate.latitude_deg), &p);
    Ok(Fields { mask: m, slope_deg, aspect_deg, filled_m, flow_acc_cells, twi, insolation_kwh_m2, flat_insolation_kwh_m2, wind_exposure, temperature_c })
}

/// Halo (cells) a window's fields need around it ([`compute_window`]): the horizon search's
/// reach ([`horizon_halo_cells`], at least the slope's 1 cell).
pub fn window_halo_cells(geo: &GeoRef, full_h: usize) -> usize {
    horizon_halo_cells(geo, full_h, &SkyParams::default())
}

/// The depression-filled elevation (m) and D8 flow accumulation (cells) of windows of a raster:
/// **derived on the whole raster** ([`fill_depressions`], [`flow_directions`],
/// [`flow_accumulation`]) and cut to each window (what rank 0 of a regional run still does for
/// the other ranks: it holds the whole DEM once). Since round 34 the fill is exact (no ε) and the
/// flats are routed by breadth-first distances, so the same values come from the bands alone
/// ([`crate::job::hydrology_ranks::hydrology_by_bands`]: each band's rows, two rows of halo and
/// three perimeter exchanges), bit for bit. Returns one `(filled, accumulation)` pair per window,
/// each `width × height`.
///
/// Errors: [`Error::Invalid`] naming a window that leaves the raster.
pub fn hydrology_windows(t: &Terrain, m: &Grid<bool>, windows: &[Window]) -> Result<Vec<(Grid<f32>, Grid<f32>)>> {
    let full = Window::full(m.width, m.height);
    if let Some(w) = windows.iter().find(|w| !w.inside(full.width, full.height)) {
        return Err(Error::Invalid { context: t.source.clone(), field: "window".into(), value: w.to_string(), expected: format!("a non-empty window inside the {} x {} raster", full.width, full.height) });
    }
    let filled = fill_depressions(t, m);
    let dir = flow_directions(&filled, &t.geo, m);
    let acc = flow_accumulation(&dir, m);
    Ok(windows.iter().map(|w| (w.cut(&filled, &full), w.cut(&acc, &full))).collect())
}

/// Every field of window `out` of a raster, from `dem` (a window of the raster holding `out`
/// and [`window_halo_cells`] around it, clipped to the raster: read with
/// [`crate::terrain::io::read_geotiff_window`]) and the window's hydrology from
/// [`hydrology_windows`] or [`crate::job::hydrology_ranks::hydrology_of_rank`] (`filled`,
/// `flow_acc`: `out`'s cells). Per field: the mask, temperature
/// and TWI cell by cell; slope and aspect with a 1-cell halo ([`slope_aspect_window`]);
/// insolation and wind exposure with the horizon's halo ([`insolation_and_wind_window`]); the
/// flat-ground insolation at the raster's middle row. Equal bit for bit to the same window of
/// [`compute`]'s fields of the whole raster. Unlike [`compute`], a window with no cell above sea
/// level is accepted (a part of a site may be water).
///
/// Errors: [`Error::Invalid`] when `dem` lacks `out` or its halo, or the hydrology grids are
/// not `out`'s size.
pub fn compute_window(dem: &crate::terrain::io::DemWindow, out: &Window, climate: &Climate, filled: Grid<f32>, flow_acc: Grid<f32>) -> Result<Fields> {
    let (ow, oh) = (out.width, out.height);
    if (filled.width, filled.height, flow_acc.width, flow_acc.height) != (ow, oh, ow, oh) {
        return Err(Error::Invalid {
            context: dem.source.clone(),
            field: "hydrology of the window".into(),
            value: format!("filled {} x {}, accumulation {} x {}", filled.width, filled.height, flow_acc.width, flow_acc.height),
            expected: format!("the window's {ow} x {oh} cells ({out})"),
        });
    }
    let t = Terrain { elevation: dem.elevation.clone(), geo: dem.geo.clone(), nodata: dem.nodata, source: dem.source.clone() };
    let pm = mask(&t, climate.sea_level_m);
    let patch = Patch { z: &t.elevation, m: &pm, at: dem.window, full_w: dem.full_width, full_h: dem.full_height, geo: &dem.geo };
    let p = SkyParams::default();
    let (slope_deg, aspect_deg) = slope_aspect_window(&patch, out)?;
    let (insolation_kwh_m2, wind_exposure) = insolation_and_wind_window(&patch, out, climate.latitude_deg, climate.wind_from_deg as f64, &p)?;
    let ot = Terrain { elevation: out.cut(&t.elevation, &dem.window), geo: dem.geo.clone(), nodata: dem.nodata, source: dem.source.clone() };
    let m = out.cut(&pm, &dem.window);
    let temperature_c = temperature(&ot, &m, climate);
    let twi = twi_window(&flow_acc, &slope_deg, &dem.geo, &m, out.row0);
    let flat_insolation_kwh_m2 = flat_insolation(row_latitude(&dem.geo, dem.full_height / 2, climate.latitude_deg), &p);
    Ok(Fields { mask: m, slope_deg, aspect_deg, filled_m: filled, flow_acc_cells: flow_acc, twi, insolation_kwh_m2, flat_insolation_kwh_m2, wind_exposure, temperature_c })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn terrain(w: usize, h: usize, cell: f64, f: impl Fn(f64, f64) -> f32) -> Terrain {
        // x east, y north in metres, row 0 north.
        let mut data = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                data.push(f(c as f64 * cell, (h - 1 - r) as f64 * cell));
            }
        }
        Terrain { elevation: Grid { width: w, height: h, data }, geo: GeoRef::local(cell, 45.0), nodata: None, source: "test".into() }
    }

    #[test]
    fn tilted_plane_slope_and_aspect() {
        // z = 0.5 x + 0.25 y (rises east and north): faces south-west-ish.
        let t = terrain(20, 20, 10.0, |x, y| (100.0 + 0.5 * x + 0.25 * y) as f32);
        let m = mask(&t, 0.0);
        let (s, a) = slope_aspect(&t, &m);
        let want_s = (0.5f64 * 0.5 + 0.25 * 0.25).sqrt().atan().to_degrees();
        let want_a = (-0.5f64).atan2(-0.25).to_degrees() + 360.0;
        for r in 1..19 {
            for c in 1..19 {
                assert!((*s.get(c, r) as f64 - want_s).abs() < 1e-3, "slope {}", s.get(c, r));
                assert!((*a.get(c, r) as f64 - want_a).abs() < 1e-3, "aspect {}", a.get(c, r));
            }
        }
        // Pure south-facing plane: aspect 180, slope 45.
        let t = terrain(10, 10, 5.0, |_, y| (200.0 + y) as f32);
        let (s, a) = slope_aspect(&t, &mask(&t, 0.0));
        assert!((s.get(5, 5) - 45.0).abs() < 1e-4);
        assert!((a.get(5, 5) - 180.0).abs() < 1e-4);
        // East-facing: z falls to the east.
        let t = terrain(10, 10, 5.0, |x, _| (200.0 - x) as f32);
        let (_, a) = slope_aspect(&t, &mask(&t, 0.0));
        assert!((a.get(5, 5) - 90.0).abs() < 1e-4);
    }

    #[test]
    fn cone_accumulation_totals_number_of_cells() {
        let n = 41;
        let t = terrain(n, n, 10.0, |x, y| (1000.0 - ((x - 200.0).powi(2) + (y - 200.0).powi(2)).sqrt()) as f32);
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        assert_eq!(f.data, t.elevation.data, "a cone has no pit");
        let d = flow_directions(&f, &t.geo, &m);
        let acc = flow_accumulation(&d, &m);
        let total: f64 = (0..n * n).filter(|&i| d.data[i] == OUTLET).map(|i| acc.data[i] as f64).sum();
        assert_eq!(total, (n * n) as f64);
        assert_eq!(acc.data.iter().map(|&v| v as f64).fold(0.0, f64::max) >= 1.0, true);
        // Only border cells are outlets on a cone.
        for i in 0..n * n {
            if d.data[i] == OUTLET {
                let (c, r) = (i % n, i / n);
                assert!(c == 0 || r == 0 || c == n - 1 || r == n - 1);
            }
        }
    }

    #[test]
    fn bowl_is_filled_and_drains_to_border() {
        let n = 31;
        let t = terrain(n, n, 10.0, |x, y| (100.0 + ((x - 150.0).powi(2) + (y - 150.0).powi(2)) / 100.0) as f32);
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        let d = flow_directions(&f, &t.geo, &m);
        let acc = flow_accumulation(&d, &m);
        let total: f64 = (0..n * n).filter(|&i| d.data[i] == OUTLET).map(|i| acc.data[i] as f64).sum();
        assert_eq!(total, (n * n) as f64);
        // the centre was raised exactly to the lowest border cell (the spill level)
        let rim = (0..n).map(|c| *t.elevation.get(c, 0)).fold(f32::INFINITY, f32::min);
        assert_eq!(f.get(15, 15).to_bits(), rim.to_bits());
        // the filled bowl is one flat at the rim's lowest level (the four mid-side border cells):
        // every cell drains to an outlet on the border
        for i in 0..n * n {
            if d.data[i] == OUTLET {
                let (c, r) = (i % n, i / n);
                assert!(c == 0 || r == 0 || c == n - 1 || r == n - 1, "outlet inside at {c},{r}");
            }
        }
    }

    #[test]
    fn tilted_plane_accumulates_its_rows() {
        // z falls to the south: every cell drains south, so a cell gathers the cells above it
        let (w, h) = (12usize, 9usize);
        let t = terrain(w, h, 10.0, |_, y| (100.0 + 0.5 * y) as f32);
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        assert_eq!(f.data, t.elevation.data);
        let d = flow_directions(&f, &t.geo, &m);
        let acc = flow_accumulation(&d, &m);
        for r in 0..h {
            for c in 0..w {
                assert_eq!(*acc.get(c, r), (r + 1) as f32, "cell {c},{r}");
                assert_eq!(*d.get(c, r), if r + 1 == h { OUTLET } else { 4 }, "cell {c},{r}");
            }
        }
    }

    #[test]
    fn cone_accumulation_is_mirror_symmetric() {
        let n = 41;
        let t = terrain(n, n, 10.0, |x, y| (1000.0 - ((x - 200.0).powi(2) + (y - 200.0).powi(2)).sqrt()) as f32);
        let m = mask(&t, 0.0);
        let d = flow_directions(&fill_depressions(&t, &m), &t.geo, &m);
        let acc = flow_accumulation(&d, &m);
        // the apex gathers nothing and drains north-east: its four diagonal neighbours fall
        // 1.000001 m per metre in f32 against the cardinal ones' 1.0, and north-east is the
        // first of them; the four axes from it run straight outwards to the border, so an axis
        // cell k steps from the apex gathers at least the k − 1 cells before it and itself
        assert_eq!(*acc.get(20, 20), 1.0);
        assert_eq!(*d.get(20, 20), 1);
        let axes = |k: usize| [((20 + k, 20), 2u8), ((20 - k, 20), 6), ((20, 20 + k), 4), ((20, 20 - k), 0)];
        for k in 1..=20usize {
            for ((c, r), code) in axes(k) {
                // (the border cell, an outlet, falls along the border)
                assert!(k == 20 || *d.get(c, r) == code, "axis cell {c},{r} runs outwards: {}", d.get(c, r));
                assert!(*acc.get(c, r) >= k as f32, "axis cell {c},{r}: {}", acc.get(c, r));
            }
        }
        // mirrored across the apex's diagonal (south-west to north-east), the accumulation is
        // the same
        for r in 0..n {
            for c in 0..n {
                assert_eq!(acc.get(c, r), acc.get(n - 1 - r, n - 1 - c), "mirror at {c},{r}");
            }
        }
    }

    #[test]
    fn walled_flat_drains_to_its_notch() {
        // A flat floor at 100 m inside walls at 110 m with one notch at 100 m in the west wall
        // (0, 4): the fill leaves it as it is, and every cell drains through the notch, the
        // floor's cells towards it and away from the walls (Barnes, Lehman & Mulla 2014).
        let (w, h) = (11usize, 9usize);
        let t = terrain(w, h, 10.0, |x, y| {
            let (c, r) = ((x / 10.0).round() as usize, h - 1 - (y / 10.0).round() as usize);
            if (c, r) == (0, 4) || (c > 0 && r > 0 && c + 1 < w && r + 1 < h) { 100.0 } else { 110.0 }
        });
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        assert_eq!(f.data, t.elevation.data, "the floor's spill level is the notch's 100 m");
        let d = flow_directions(&f, &t.geo, &m);
        let acc = flow_accumulation(&d, &m);
        assert_eq!(*d.get(0, 4), OUTLET);
        assert_eq!(*acc.get(0, 4), (w * h) as f32, "every cell drains through the notch");
        assert_eq!(*d.get(1, 4), 6, "next to the notch: west into it");
        // (5, 1), under the north wall, 5 cells from the notch: south-west, one cell nearer the
        // notch and one farther from the wall (value 2·5 + H − 1 against 2·4 + H − 2)
        assert_eq!(*d.get(5, 1), 5);
        for r in 0..h {
            for c in 0..w {
                let (mut cc, mut rr, mut steps) = (c as i64, r as i64, 0);
                while *d.get(cc as usize, rr as usize) != OUTLET {
                    let (dc, dr) = D8[*d.get(cc as usize, rr as usize) as usize];
                    assert!(f.get((cc + dc) as usize, (rr + dr) as usize) <= f.get(cc as usize, rr as usize));
                    (cc, rr, steps) = (cc + dc, rr + dr, steps + 1);
                    assert!(steps < 40, "cycle from {c},{r}");
                }
                assert_eq!((cc, rr), (0, 4), "{c},{r} ends at {cc},{rr}");
            }
        }
    }

    #[test]
    fn atan_deg_matches_libm() {
        for i in -2000..=2000 {
            let x = i as f32 / 100.0;
            let want = (x as f64).atan().to_degrees();
            assert!((atan_deg(x) as f64 - want).abs() < 1e-4, "{x}: {} vs {want}", atan_deg(x));
        }
        assert!((atan_deg(f32::INFINITY) - 90.0).abs() < 1e-4);
    }

    #[test]
    fn radix_heap_pops_in_key_order() {
        let mut h = RadixHeap::new();
        let mut x = 12345u64;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 1000) as u32
        };
        let mut popped = Vec::new();
        let mut last = 0;
        for i in 0..2000u32 {
            h.push(last + rnd(), i);
            if i % 3 == 0 {
                let (k, _) = h.pop().unwrap();
                assert!(k >= last);
                last = k;
                popped.push(k);
            }
        }
        while let Some((k, _)) = h.pop() {
            assert!(k >= last, "{k} < {last}");
            last = k;
            popped.push(k);
        }
        assert_eq!(popped.len(), 2000);
    }

    #[test]
    fn filled_noise_terrain_drains_everywhere() {
        // Every valid cell of a filled random terrain reaches an outlet on the border by a D8
        // path that never rises (falling on slopes, level across the filled flats), and filling
        // never lowers a cell.
        let t = terrain(40, 30, 10.0, |x, y| {
            let h = ((x * 7.0 + y * 131.0) as u64).wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (100.0 + (h >> 40) as f64 / (1u64 << 24) as f64 * 20.0) as f32
        });
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        let d = flow_directions(&f, &t.geo, &m);
        for r in 0..30 {
            for c in 0..40 {
                assert!(f.get(c, r) >= t.elevation.get(c, r));
                let (mut cc, mut rr, mut n) = (c as i64, r as i64, 0);
                while *d.get(cc as usize, rr as usize) != OUTLET {
                    let (dc, dr) = D8[*d.get(cc as usize, rr as usize) as usize];
                    assert!(f.get((cc + dc) as usize, (rr + dr) as usize) <= f.get(cc as usize, rr as usize));
                    cc += dc;
                    rr += dr;
                    n += 1;
                    assert!(n < 1200, "cycle from {c},{r}");
                }
                assert!(cc == 0 || rr == 0 || cc == 39 || rr == 29, "({c},{r}) ends inside at ({cc},{rr})");
            }
        }
        // Exact: equal bit for bit to the spill level, the lowest over all paths to the border of
        // the highest cell on the path, computed by a plain Dijkstra-like flood.
        let (w, h) = (40usize, 30usize);
        let mut spill = vec![f32::INFINITY; w * h];
        let mut heap = std::collections::BinaryHeap::new();
        for r in 0..h {
            for c in 0..w {
                if c == 0 || r == 0 || c == w - 1 || r == h - 1 {
                    let i = r * w + c;
                    spill[i] = t.elevation.data[i];
                    heap.push(std::cmp::Reverse((spill[i].to_bits(), i)));
                }
            }
        }
        while let Some(std::cmp::Reverse((b, i))) = heap.pop() {
            if b != spill[i].to_bits() {
                continue;
            }
            for (dc, dr) in D8 {
                let (nc, nr) = ((i % w) as i64 + dc, (i / w) as i64 + dr);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                    continue;
                }
                let ni = nr as usize * w + nc as usize;
                let v = spill[i].max(t.elevation.data[ni]);
                if v < spill[ni] {
                    spill[ni] = v;
                    heap.push(std::cmp::Reverse((v.to_bits(), ni)));
                }
            }
        }
        let raised = (0..w * h).filter(|&i| f.data[i] > t.elevation.data[i]).count();
        assert!(raised > 20, "the noise terrain has depressions: {raised} cells raised");
        for i in 0..w * h {
            assert_eq!(f.data[i].to_bits(), spill[i].to_bits(), "cell {i}: filled {} spill {}", f.data[i], spill[i]);
        }
    }

    #[test]
    fn pit_is_filled() {
        let mut t = terrain(9, 9, 10.0, |x, _| (100.0 + 0.1 * x) as f32);
        *t.elevation.get_mut(4, 4) = 50.0;
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        let lowest_nb = [(3, 3), (4, 3), (5, 3), (3, 4), (5, 4), (3, 5), (4, 5), (5, 5)].iter().map(|&(c, r)| *t.elevation.get(c, r)).fold(f32::INFINITY, f32::min);
        // filled exactly to its spill level: the lowest neighbour, (3, 3) at 100.3 m
        assert_eq!(f.get(4, 4).to_bits(), lowest_nb.to_bits(), "filled {}", f.get(4, 4));
        assert_eq!(lowest_nb, 103.0);
        // the pit, now level with its western neighbours (3, 3), (3, 4), (3, 5), drains into them:
        // west (6) is the nearest, its value 2 against 0
        let d = flow_directions(&f, &t.geo, &m);
        assert_eq!(*d.get(4, 4), 6);
        // untouched elsewhere
        assert_eq!(f.get(1, 1), t.elevation.get(1, 1));
    }

    #[test]
    fn insolation_south_beats_north_and_equator_beats_60n() {
        let p = SkyParams::default();
        let south = terrain(21, 21, 10.0, |_, y| (500.0 + 0.5 * y) as f32); // rises north -> faces south
        let north = terrain(21, 21, 10.0, |_, y| (500.0 - 0.5 * y) as f32);
        let (is, _) = insolation_and_wind(&south, &mask(&south, 0.0), 45.0, 270.0, &p);
        let (inn, _) = insolation_and_wind(&north, &mask(&north, 0.0), 45.0, 270.0, &p);
        let (a, b) = (*is.get(10, 10), *inn.get(10, 10));
        assert!(a > 1.2 * b, "south {a} north {b}");
        let eq = flat_insolation(0.0, &p);
        let n60 = flat_insolation(60.0, &p);
        assert!(eq > n60 * 1.3, "equator {eq} 60N {n60}");
        // flat ground in the shading model equals the unshaded flat value
        let flat = terrain(11, 11, 10.0, |_, _| 300.0);
        let (fi, fw) = insolation_and_wind(&flat, &mask(&flat, 0.0), 45.0, 270.0, &p);
        assert!((*fi.get(5, 5) as f64 - flat_insolation(45.0, &p)).abs() < 1e-3 * flat_insolation(45.0, &p));
        assert!((fw.get(5, 5) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn ridge_is_exposed_and_valley_sheltered() {
        let p = SkyParams::default();
        let ridge = terrain(41, 41, 10.0, |x, _| (500.0 - (x - 200.0).abs() * 0.5) as f32);
        let (_, w) = insolation_and_wind(&ridge, &mask(&ridge, 0.0), 45.0, 270.0, &p);
        let valley = terrain(41, 41, 10.0, |x, _| (500.0 + (x - 200.0).abs() * 0.5) as f32);
        let (_, v) = insolation_and_wind(&valley, &mask(&valley, 0.0), 45.0, 270.0, &p);
        assert!(*w.get(20, 20) > 0.8 && *v.get(20, 20) < 0.2, "ridge {} valley {}", w.get(20, 20), v.get(20, 20));
    }

    #[test]
    fn wind_exposure_has_no_border_seam_on_a_plane() {
        // A plane rising to the east, wind from the west: every interior cell sees the same
        // terrain, so exposure must change smoothly toward the upwind (west) border and never
        // exceed the interior value there (the grid's end is not a ridge).
        let p = SkyParams { horizon_max_cells: 16, ..SkyParams::default() };
        let t = terrain(60, 60, 10.0, |x, _| (300.0 + 0.2 * x) as f32);
        let (_, w) = insolation_and_wind(&t, &mask(&t, 0.0), 45.0, 270.0, &p);
        let row: Vec<f32> = (0..60).map(|c| *w.get(c, 30)).collect();
        let interior = row[30];
        for c in 0..30 {
            assert!(row[c] <= interior + 1e-6, "col {c}: {} > interior {interior}", row[c]);
            // a linear ramp over the 11-cell reach of the march (old rule: one jump of ≈ 0.45)
            assert!(row[c + 1] >= row[c] - 1e-6 && row[c + 1] - row[c] < 0.05, "jump at col {c}: {} -> {} ({row:?})", row[c], row[c + 1]);
        }
        // the upwind-facing slope is more exposed than flat ground (0.5)
        assert!(interior > 0.5, "{interior}");
    }

    #[test]
    fn temperature_lapse() {
        let t = terrain(3, 3, 10.0, |x, _| (300.0 + 50.0 * x) as f32);
        let c = Climate::default();
        let tt = temperature(&t, &mask(&t, 0.0), &c);
        assert!((tt.get(2, 0) - (9.0 - 6.5 * 1.0)).abs() < 1e-4);
    }
}
