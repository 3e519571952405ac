//! The hydrology of a DEM by bands of rows, equal bit for bit to the whole raster's
//! ([`fields::fill_depressions`], [`fields::flow_directions`], [`fields::flow_accumulation`])
//! whatever the cut: each band works on its own rows plus at most two rows of halo, and the
//! bands exchange only their perimeters, so that no band (no rank) holds the whole DEM.
//!
//! Three exchanges, each a small central solve between two per-band passes:
//! 1. **Fill** (Barnes 2016, "Parallel priority-flood depression filling for trillion cell
//!    digital elevation models", Environmental Modelling & Software 86:27–38): each band floods
//!    its cells from the raster's outlets and from its own top and bottom rows (each such cell a
//!    watershed label), keeping for each pair of touching labels the lowest spill
//!    `max(fill a, fill b)`; the central solve floods the graph of labels (the bands' graphs plus
//!    the pairs across band edges) from the outlets' label and returns each label's level; each
//!    cell's filled level is `max(its band's fill, its label's level)`. Every value is a max or
//!    a min of input elevations, and equals the spill level of the whole raster's fill.
//! 2. **Flats** (Barnes, Lehman & Mulla 2014, flats; [`fields::flow_directions`]): with two rows
//!    of the neighbours' filled levels, each band gives its cells their D8 directions and
//!    resolves the flats that lie wholly in it; the cells of flats that touch a band edge (a
//!    flat cell of the band's edge row next to a flat cell of the next band) are sent whole,
//!    with their high-edge and low-edge flags, to the central solve, which resolves them as one
//!    process would ([`fields::flat_dirs`]: breadth-first distances over the joined flat) and
//!    returns their directions. A flat across a band edge costs its cells, not a round per cell
//!    of its width.
//! 3. **Accumulation** (Barnes 2017, "Parallel non-divergent flow accumulation for trillion
//!    cell digital elevation models", Computers & Geosciences 109:28–41): each band accumulates
//!    its own cells, lists the cells whose flow leaves it (with their count and the cell they
//!    flow into) and, for each cell that receives flow from the next band, the cell by which
//!    that flow leaves the band again (or none); the central solve passes the counts along that
//!    graph in topological order and returns each entry cell's inflow; each band adds it along
//!    the entry's path. Counts are integers summed in f64 (exact below 2⁵³), so the order of the
//!    sums does not matter.
//!
//! This module holds the per-band passes and the central solves, pure functions of their
//! inputs; `job::hydrology_ranks::hydrology_of_rank` runs them as one rank of any transport
//! (MPI, or threads: `job::hydrology_ranks::hydrology_by_bands`), so that `terrain` imports
//! nothing of `sim`.

use super::fields::{self, FlatCell, D8, NOFLOW, OUTLET};
use crate::error::{Error, Result};
use crate::grid::{GeoRef, Window};
use std::collections::{BinaryHeap, HashMap, VecDeque};

pub(crate) const NONE: u32 = u32::MAX;

/// Rows of halo each band reads around its own: enough to know whether a neighbour of an edge
/// row drains (its own neighbours' levels and mask).
pub const HALO_ROWS: usize = 2;

/// A band's rows of the raster and the halo it reads: rows `ext0 .. ext1` (full width) of which
/// `row0 .. row1` are its own.
#[derive(Debug, Clone)]
pub(crate) struct BandRows {
    pub(crate) row0: usize,
    pub(crate) row1: usize,
    pub(crate) ext0: usize,
    pub(crate) ext1: usize,
    pub(crate) w: usize,
    pub(crate) full_h: usize,
}

impl BandRows {
    pub(crate) fn new(b: &Window, full_h: usize) -> BandRows {
        let (row0, row1) = (b.row0, b.row0 + b.height);
        BandRows { row0, row1, ext0: row0.saturating_sub(HALO_ROWS), ext1: (row1 + HALO_ROWS).min(full_h), w: b.width, full_h }
    }
    /// Index in the extended rows of raster cell `(c, r)`.
    #[inline]
    fn x(&self, c: usize, r: usize) -> usize {
        (r - self.ext0) * self.w + c
    }
    /// Index in the band's own rows of raster index `g`.
    #[inline]
    pub(crate) fn own(&self, g: usize) -> Option<usize> {
        let r = g / self.w;
        (r >= self.row0 && r < self.row1).then(|| g - self.row0 * self.w)
    }
    fn len(&self) -> usize {
        (self.row1 - self.row0) * self.w
    }
    /// Whether raster cell `(c, r)` (in the extended rows, with its neighbours) is an outlet of
    /// the whole raster: on its border or next to a masked cell ([`fields::is_seed`]).
    fn is_outlet(&self, m: &[bool], c: usize, r: usize) -> bool {
        if c == 0 || r == 0 || c + 1 == self.w || r + 1 == self.full_h {
            return true;
        }
        D8.iter().any(|(dc, dr)| !m[self.x((c as i64 + dc) as usize, (r as i64 + dr) as usize)])
    }
}

/// Pass 1 of a band: its local fill, labels and label graph.
pub(crate) struct LocalFill {
    /// Filled level of the band's own cells (NaN masked).
    pub(crate) zf: Vec<f32>,
    /// Label of each own cell (0: drains to an outlet of the raster; [`NONE`] masked).
    pub(crate) label: Vec<u32>,
    pub(crate) nlabels: u32,
    /// (label a, label b, spill) with a < b, the lowest spill per pair.
    pub(crate) edges: Vec<(u32, u32, f32)>,
}

/// Priority-Flood of a band's own cells from the raster's outlets (label 0) and from the cells
/// of its top and bottom rows that border another band (a label each), with watershed labels.
pub(crate) fn fill_band(br: &BandRows, z: &[f32], m: &[bool]) -> LocalFill {
    let (w, n) = (br.w, br.len());
    let mut zf: Vec<f32> = (0..n).map(|i| if m[br.x(i % w, br.row0 + i / w)] { z[br.x(i % w, br.row0 + i / w)] } else { f32::NAN }).collect();
    let mut label = vec![NONE; n];
    let mut open = fields::RadixHeap::new();
    let mut nlabels = 1u32;
    for i in 0..n {
        let (c, r) = (i % w, br.row0 + i / w);
        if !m[br.x(c, r)] {
            continue;
        }
        if br.is_outlet(m, c, r) {
            label[i] = 0;
        } else if (r == br.row0 && br.row0 > 0) || (r + 1 == br.row1 && br.row1 < br.full_h) {
            label[i] = nlabels;
            nlabels += 1;
        } else {
            continue;
        }
        open.push(fields::f32_key(zf[i]), i as u32);
    }
    let mut pit: VecDeque<u32> = VecDeque::new();
    let rows = br.row1 - br.row0;
    loop {
        let ci = if let Some(p) = pit.pop_front() {
            p as usize
        } else if let Some((_, i)) = open.pop() {
            i as usize
        } else {
            break;
        };
        for (_, ni) in fields::neighbours(ci, w, rows) {
            if label[ni] != NONE || zf[ni].is_nan() {
                continue;
            }
            label[ni] = label[ci];
            if zf[ni] <= zf[ci] {
                zf[ni] = zf[ci];
                pit.push_back(ni as u32);
            } else {
                open.push(fields::f32_key(zf[ni]), ni as u32);
            }
        }
    }
    let mut best: HashMap<(u32, u32), f32> = HashMap::new();
    for i in 0..n {
        if label[i] == NONE {
            continue;
        }
        for (_, j) in fields::neighbours(i, w, rows) {
            if j > i && label[j] != NONE && label[j] != label[i] {
                let key = (label[i].min(label[j]), label[i].max(label[j]));
                let s = zf[i].max(zf[j]);
                best.entry(key).and_modify(|v| *v = v.min(s)).or_insert(s);
            }
        }
    }
    let mut edges: Vec<(u32, u32, f32)> = best.into_iter().map(|((a, b), s)| (a, b, s)).collect();
    edges.sort_by_key(|e| (e.0, e.1));
    LocalFill { zf, label, nlabels, edges }
}

/// What a band sends for the fill's central solve: its label graph and its edge rows' labels
/// and levels.
pub(crate) struct FillSummary {
    pub(crate) nlabels: u32,
    pub(crate) edges: Vec<(u32, u32, f32)>,
    /// Labels and levels of the band's first and last own rows.
    pub(crate) top: (Vec<u32>, Vec<f32>),
    pub(crate) bottom: (Vec<u32>, Vec<f32>),
}

/// The central solve of the fill: each band's labels' levels (−∞ for label 0), by a minimax
/// flood of the joined label graph from every band's label 0.
pub(crate) fn solve_levels(s: &[FillSummary]) -> Vec<Vec<f32>> {
    let mut offset = vec![0usize; s.len() + 1];
    for (k, b) in s.iter().enumerate() {
        offset[k + 1] = offset[k] + b.nlabels as usize;
    }
    let total = offset[s.len()];
    let mut adj: Vec<Vec<(usize, f32)>> = vec![Vec::new(); total];
    let mut link = |a: usize, b: usize, v: f32| {
        adj[a].push((b, v));
        adj[b].push((a, v));
    };
    for (k, b) in s.iter().enumerate() {
        for &(x, y, v) in &b.edges {
            link(offset[k] + x as usize, offset[k] + y as usize, v);
        }
    }
    let full: Vec<usize> = (0..s.len()).filter(|&k| !s[k].top.0.is_empty()).collect();
    for p in full.windows(2) {
        let (k, k1) = (p[0], p[1]);
        let (up, down) = (&s[k].bottom, &s[k1].top);
        let w = up.0.len();
        for c in 0..w {
            if up.0[c] == NONE {
                continue;
            }
            for nc in c.saturating_sub(1)..(c + 2).min(w) {
                if down.0[nc] != NONE {
                    link(offset[k] + up.0[c] as usize, offset[k1] + down.0[nc] as usize, up.1[c].max(down.1[nc]));
                }
            }
        }
    }
    let mut level = vec![f32::INFINITY; total];
    let mut heap = BinaryHeap::new();
    for k in full {
        level[offset[k]] = f32::NEG_INFINITY;
        heap.push(std::cmp::Reverse((fields::f32_key(f32::NEG_INFINITY), offset[k])));
    }
    while let Some(std::cmp::Reverse((key, a))) = heap.pop() {
        if key != fields::f32_key(level[a]) {
            continue;
        }
        for &(b, v) in &adj[a] {
            let cand = level[a].max(v);
            if cand < level[b] {
                level[b] = cand;
                heap.push(std::cmp::Reverse((fields::f32_key(cand), b)));
            }
        }
    }
    (0..s.len()).map(|k| level[offset[k]..offset[k + 1]].to_vec()).collect()
}

/// Pass 2 of a band: D8 codes of its own cells with the flats that lie wholly in it resolved,
/// [`NOFLOW`] left on the cells of flats that touch a band edge, and those cells' flags.
pub(crate) fn directions_band(br: &BandRows, zf: &[f32], m: &[bool], geo: &GeoRef) -> (Vec<u8>, Vec<FlatCell>) {
    let (w, h) = (br.w, br.full_h);
    let dists = |r: usize| fields::d8_dists(geo, r);
    // codes of the own rows and one row of halo each side ([`fields::steepest`], as the whole
    // raster's [`fields::flow_directions`])
    let (d0, d1) = (br.row0.saturating_sub(1), (br.row1 + 1).min(h));
    let mut dir = vec![OUTLET; (d1 - d0) * w];
    for r in d0..d1 {
        let dist = dists(r);
        for c in 0..w {
            if !m[br.x(c, r)] {
                continue;
            }
            let z0 = zf[br.x(c, r)];
            let code = fields::steepest(z0, &dist, |k| {
                let (nc, nr) = (c as i64 + D8[k].0, r as i64 + D8[k].1);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 || !m[br.x(nc as usize, nr as usize)] {
                    return None;
                }
                Some(zf[br.x(nc as usize, nr as usize)])
            });
            dir[(r - d0) * w + c] = if code == OUTLET && !br.is_outlet(m, c, r) { NOFLOW } else { code };
        }
    }
    let dd = |g: usize| dir[g - d0 * w];
    // the band's flat cells, their flats (within the band) and whether each touches a band edge
    let own: Vec<usize> = (br.row0 * w..br.row1 * w).filter(|&g| dd(g) == NOFLOW).collect();
    // position in `own` of each of the band's cells (NONE: not a flat cell), a dense index
    let mut slot = vec![NONE; br.len()];
    for (k, &g) in own.iter().enumerate() {
        slot[g - br.row0 * w] = k as u32;
    }
    let at = |slot: &[u32], g: usize| br.own(g).map(|o| slot[o]).filter(|k| *k != NONE).map(|k| k as usize);
    let mut comp = vec![NONE; own.len()];
    let mut crossing: Vec<bool> = Vec::new();
    let mut queue = VecDeque::new();
    for s in 0..own.len() {
        if comp[s] != NONE {
            continue;
        }
        let id = crossing.len() as u32;
        let mut cross = false;
        comp[s] = id;
        queue.push_back(s);
        while let Some(k) = queue.pop_front() {
            for (_, j) in fields::neighbours(own[k], w, h) {
                if let Some(q) = at(&slot, j) {
                    if comp[q] == NONE {
                        comp[q] = id;
                        queue.push_back(q);
                    }
                } else if br.own(j).is_none() && dd(j) == NOFLOW {
                    cross = true;
                }
            }
        }
        crossing.push(cross);
    }
    let cells: Vec<FlatCell> = own.iter().map(|&g| fields::flat_cell(g, w, h, &|n| (m[n - br.ext0 * w], zf[n - br.ext0 * w], dd(n) != NOFLOW), zf[g - br.ext0 * w])).collect();
    let (local, shared): (Vec<usize>, Vec<usize>) = (0..own.len()).partition(|&k| !crossing[comp[k] as usize]);
    let mut out: Vec<u8> = dir[(br.row0 - d0) * w..(br.row1 - d0) * w].to_vec();
    let lc: Vec<FlatCell> = local.iter().map(|&k| cells[k]).collect();
    slot.fill(NONE);
    for (k, c) in lc.iter().enumerate() {
        slot[c.i - br.row0 * w] = k as u32;
    }
    for (c, d) in lc.iter().zip(fields::flat_dirs(&lc, w, h, &|i| at(&slot, i), &dists)) {
        out[c.i - br.row0 * w] = d;
    }
    (out, shared.iter().map(|&k| cells[k]).collect())
}

/// The central solve of the flats that touch band edges: their cells' D8 codes.
pub(crate) fn solve_flats(cells: &[FlatCell], w: usize, h: usize, geo: &GeoRef) -> Vec<u8> {
    let slot: HashMap<usize, usize> = cells.iter().enumerate().map(|(k, c)| (c.i, k)).collect();
    let dists = |r: usize| fields::d8_dists(geo, r);
    fields::flat_dirs(cells, w, h, &|i| slot.get(&i).copied(), &dists)
}

/// The raster cell that raster cell `g` of a `w × h` raster flows into under code `d`
/// ([`fields::d8_step`]).
pub(crate) use fields::d8_step as down;

/// Pass 3 of a band: the accumulation of its own cells alone, the cells whose flow leaves it
/// `(cell, count, cell it flows into)` and its entry cells `(cell, exit cell of its path or
/// None)`. `halo_dirs`: the codes of the rows just above and below the band (empty at the
/// raster's edges), as `(first row, codes)`.
#[allow(clippy::type_complexity)]
pub(crate) fn accumulate_band(br: &BandRows, dir: &[u8], m: &[bool], halo_dirs: &[(usize, Vec<u8>)]) -> (Vec<f64>, Vec<(usize, f64, usize)>, Vec<(usize, Option<usize>)>) {
    let (w, h, n) = (br.w, br.full_h, br.len());
    let base = br.row0 * w;
    let valid = |i: usize| m[br.x(i % w, br.row0 + i / w)];
    let local_down = |i: usize| down(base + i, dir[i], w, h).and_then(|g| br.own(g));
    let acc = fields::accumulate(n, &valid, &local_down);
    let exits: Vec<(usize, f64, usize)> = (0..n).filter(|&i| valid(i)).filter_map(|i| down(base + i, dir[i], w, h).filter(|g| br.own(*g).is_none()).map(|g| (base + i, acc[i], g))).collect();
    let mut entries: Vec<usize> = Vec::new();
    for (r, codes) in halo_dirs {
        for (c, &d) in codes.iter().enumerate() {
            if let Some(g) = down(r * w + c, d, w, h) {
                if br.own(g).is_some() {
                    entries.push(g);
                }
            }
        }
    }
    entries.sort_unstable();
    entries.dedup();
    let links = entries
        .into_iter()
        .map(|g| {
            let mut i = g - base;
            loop {
                match down(base + i, dir[i], w, h) {
                    Some(t) => match br.own(t) {
                        Some(j) => i = j,
                        None => break (g, Some(base + i)),
                    },
                    None => break (g, None),
                }
            }
        })
        .collect();
    (acc, exits, links)
}

/// The central solve of the accumulation: the inflow (cells) of every entry cell, from every
/// band's exits `(cell, count, cell it flows into)` and entries' links `(entry, exit)`.
pub(crate) fn solve_inflows(exits: &[(usize, f64, usize)], links: &[(usize, Option<usize>)]) -> HashMap<usize, f64> {
    let link: HashMap<usize, usize> = links.iter().filter_map(|(e, x)| x.map(|x| (*e, x))).collect();
    let index: HashMap<usize, usize> = exits.iter().enumerate().map(|(k, x)| (x.0, k)).collect();
    let mut indeg = vec![0u32; exits.len()];
    for x in exits {
        if let Some(k) = link.get(&x.2).and_then(|x2| index.get(x2)) {
            indeg[*k] += 1;
        }
    }
    let mut extra = vec![0.0f64; exits.len()];
    let mut inflow: HashMap<usize, f64> = links.iter().map(|(e, _)| (*e, 0.0)).collect();
    let mut stack: Vec<usize> = (0..exits.len()).filter(|&k| indeg[k] == 0).collect();
    while let Some(k) = stack.pop() {
        let (_, count, target) = exits[k];
        let out = count + extra[k];
        *inflow.entry(target).or_insert(0.0) += out;
        if let Some(&k2) = link.get(&target).and_then(|x2| index.get(x2)) {
            extra[k2] += out;
            indeg[k2] -= 1;
            if indeg[k2] == 0 {
                stack.push(k2);
            }
        }
    }
    inflow
}

/// Refuses a cut that is not full-width non-empty bands of consecutive rows covering the
/// `w × h` raster from row 0 in order; empty bands (more ranks than rows) are allowed anywhere.
pub(crate) fn check_bands(bands: &[Window], w: usize, h: usize, context: &str) -> Result<()> {
    let mut next = 0;
    for b in bands {
        if b.height == 0 {
            continue;
        }
        if b.col0 != 0 || b.width != w || b.row0 != next {
            return Err(Error::Invalid { context: context.into(), field: "band".into(), value: b.to_string(), expected: format!("a full-width band of rows starting at row {next} of the {w} x {h} raster") });
        }
        next = b.row0 + b.height;
    }
    if next != h {
        return Err(Error::Invalid { context: context.into(), field: "bands".into(), value: format!("{} bands ending at row {next}", bands.len()), expected: format!("bands covering the {h} rows of the raster") });
    }
    Ok(())
}

/// The rows `(first, one past the last)` of the DEM and mask a rank reads for band `band` of an
/// `h`-row raster (`job::hydrology_ranks::hydrology_of_rank`): its own rows and [`HALO_ROWS`] around them.
pub fn read_rows(band: &Window, h: usize) -> (usize, usize) {
    let b = BandRows::new(band, h);
    (b.ext0, b.ext1)
}

