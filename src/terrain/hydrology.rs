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
//! [`hydrology_of_rank`] is one rank's part (rank 0 runs the central solves) over any
//! [`Transport`] (MPI, or threads: [`hydrology_by_bands`]).

use super::fields::{self, FlatCell, D8, NOFLOW, OUTLET};
use super::Terrain;
use crate::error::{Error, Result};
use crate::grid::{GeoRef, Grid, Window};
use crate::sim::codec::{Dec, Enc, Short};
use crate::sim::tiles::{LocalTransport, Transport};
use std::collections::{BinaryHeap, HashMap, VecDeque};

const NONE: u32 = u32::MAX;

/// Rows of halo each band reads around its own: enough to know whether a neighbour of an edge
/// row drains (its own neighbours' levels and mask).
pub const HALO_ROWS: usize = 2;

/// A band's rows of the raster and the halo it reads: rows `ext0 .. ext1` (full width) of which
/// `row0 .. row1` are its own.
#[derive(Debug, Clone)]
struct BandRows {
    row0: usize,
    row1: usize,
    ext0: usize,
    ext1: usize,
    w: usize,
    full_h: usize,
}

impl BandRows {
    fn new(b: &Window, full_h: usize) -> BandRows {
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
    fn own(&self, g: usize) -> Option<usize> {
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
struct LocalFill {
    /// Filled level of the band's own cells (NaN masked).
    zf: Vec<f32>,
    /// Label of each own cell (0: drains to an outlet of the raster; [`NONE`] masked).
    label: Vec<u32>,
    nlabels: u32,
    /// (label a, label b, spill) with a < b, the lowest spill per pair.
    edges: Vec<(u32, u32, f32)>,
}

/// Priority-Flood of a band's own cells from the raster's outlets (label 0) and from the cells
/// of its top and bottom rows that border another band (a label each), with watershed labels.
fn fill_band(br: &BandRows, z: &[f32], m: &[bool]) -> LocalFill {
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
struct FillSummary {
    nlabels: u32,
    edges: Vec<(u32, u32, f32)>,
    /// Labels and levels of the band's first and last own rows.
    top: (Vec<u32>, Vec<f32>),
    bottom: (Vec<u32>, Vec<f32>),
}

/// The central solve of the fill: each band's labels' levels (−∞ for label 0), by a minimax
/// flood of the joined label graph from every band's label 0.
fn solve_levels(s: &[FillSummary]) -> Vec<Vec<f32>> {
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
fn directions_band(br: &BandRows, zf: &[f32], m: &[bool], geo: &GeoRef) -> (Vec<u8>, Vec<FlatCell>) {
    let (w, h) = (br.w, br.full_h);
    let dy = geo.cell_y_m();
    let dists = |r: usize| -> [f64; 8] {
        let dx = geo.cell_x_m_at_row(r);
        D8.map(|(dc, dr)| ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt())
    };
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
    let mut slot: HashMap<usize, usize> = own.iter().enumerate().map(|(k, &g)| (g, k)).collect();
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
                if let Some(&q) = slot.get(&j) {
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
    slot = lc.iter().enumerate().map(|(k, c)| (c.i, k)).collect();
    for (c, d) in lc.iter().zip(fields::flat_dirs(&lc, w, h, &|i| slot.get(&i).copied(), &dists)) {
        out[c.i - br.row0 * w] = d;
    }
    (out, shared.iter().map(|&k| cells[k]).collect())
}

/// The central solve of the flats that touch band edges: their cells' D8 codes.
fn solve_flats(cells: &[FlatCell], w: usize, h: usize, geo: &GeoRef) -> Vec<u8> {
    let slot: HashMap<usize, usize> = cells.iter().enumerate().map(|(k, c)| (c.i, k)).collect();
    let dy = geo.cell_y_m();
    let dists = |r: usize| -> [f64; 8] {
        let dx = geo.cell_x_m_at_row(r);
        D8.map(|(dc, dr)| ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt())
    };
    fields::flat_dirs(cells, w, h, &|i| slot.get(&i).copied(), &dists)
}

/// The raster cell that raster cell `g` of a `w × h` raster flows into under code `d`.
#[inline]
fn down(g: usize, d: u8, w: usize, h: usize) -> Option<usize> {
    let (dc, dr) = *D8.get(d as usize)?;
    let (c, r) = ((g % w) as i64 + dc, (g / w) as i64 + dr);
    (c >= 0 && r >= 0 && (c as usize) < w && (r as usize) < h).then(|| r as usize * w + c as usize)
}

/// Pass 3 of a band: the accumulation of its own cells alone, the cells whose flow leaves it
/// `(cell, count, cell it flows into)` and its entry cells `(cell, exit cell of its path or
/// None)`. `halo_dirs`: the codes of the rows just above and below the band (empty at the
/// raster's edges), as `(first row, codes)`.
#[allow(clippy::type_complexity)]
fn accumulate_band(br: &BandRows, dir: &[u8], m: &[bool], halo_dirs: &[(usize, Vec<u8>)]) -> (Vec<f64>, Vec<(usize, f64, usize)>, Vec<(usize, Option<usize>)>) {
    let (w, h, n) = (br.w, br.full_h, br.len());
    let base = br.row0 * w;
    let valid = |i: usize| m[br.x(i % w, br.row0 + i / w)];
    let local_down = |i: usize| down(base + i, dir[i], w, h).and_then(|g| br.own(g));
    let mut indeg = vec![0u8; n];
    for i in 0..n {
        if valid(i) {
            if let Some(j) = local_down(i) {
                indeg[j] += 1;
            }
        }
    }
    let mut acc: Vec<f64> = (0..n).map(|i| if valid(i) { 1.0 } else { 0.0 }).collect();
    let mut stack: Vec<usize> = (0..n).filter(|&i| valid(i) && indeg[i] == 0).collect();
    while let Some(i) = stack.pop() {
        if let Some(j) = local_down(i) {
            acc[j] += acc[i];
            indeg[j] -= 1;
            if indeg[j] == 0 {
                stack.push(j);
            }
        }
    }
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
fn solve_inflows(exits: &[(usize, f64, usize)], links: &[(usize, Option<usize>)]) -> HashMap<usize, f64> {
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
fn check_bands(bands: &[Window], w: usize, h: usize, context: &str) -> Result<()> {
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
/// `h`-row raster ([`hydrology_of_rank`]): its own rows and [`HALO_ROWS`] around them.
pub fn read_rows(band: &Window, h: usize) -> (usize, usize) {
    let b = BandRows::new(band, h);
    (b.ext0, b.ext1)
}

/// Every rank's rows `want(j)` of a per-row grid (`w` cells a row) held by bands: this rank
/// sends each other rank the part of its own rows `own` that it wants and returns its own
/// wanted rows, `w × rows` values.
fn exchange_rows<T: Copy + Default>(tr: &mut dyn Transport, brs: &[BandRows], own: &[T], want: &dyn Fn(&BandRows) -> (usize, usize), to_bytes: fn(&[T]) -> Vec<u8>, from_bytes: fn(&[u8]) -> Vec<T>) -> Result<Vec<T>> {
    let (me, n) = (tr.rank(), tr.size());
    let w = brs[me].w;
    let cut = |k: usize, j: usize| -> (usize, usize) {
        let (lo, hi) = want(&brs[j]);
        let (lo, hi) = (lo.max(brs[k].row0), hi.min(brs[k].row1));
        (lo, hi.max(lo))
    };
    let out: Vec<Vec<u8>> = (0..n)
        .map(|j| {
            let (lo, hi) = cut(me, j);
            if j == me || lo == hi {
                return Vec::new();
            }
            to_bytes(&own[(lo - brs[me].row0) * w..(hi - brs[me].row0) * w])
        })
        .collect();
    let got = tr.exchange(out)?;
    let (w0, w1) = want(&brs[me]);
    let mut rows = vec![T::default(); (w1 - w0) * w];
    for (k, msg) in got.iter().enumerate() {
        let (lo, hi) = cut(k, me);
        if lo == hi {
            continue;
        }
        let part = if k == me { own[(lo - brs[me].row0) * w..(hi - brs[me].row0) * w].to_vec() } else { from_bytes(msg) };
        if part.len() != (hi - lo) * w {
            return Err(Error::Exchange { peer: k, reason: format!("rows {lo}..{hi} of the hydrology: {} values, expected {}", part.len(), (hi - lo) * w) });
        }
        rows[(lo - w0) * w..(hi - w0) * w].copy_from_slice(&part);
    }
    Ok(rows)
}

/// The depression-filled elevation (m) and D8 flow accumulation (cells) of this rank's band of
/// rows of a `w × h` raster, by the three perimeter exchanges of the module documentation
/// (rank 0 runs the central solves), equal bit for bit to the same rows of
/// [`fields::fill_depressions`] and [`fields::flow_accumulation`] over
/// [`fields::flow_directions`] of the whole raster, whatever the number of ranks or the cut.
/// `bands[k]`: rank `k`'s band (full-width consecutive rows covering the raster in rank order;
/// empty bands allowed); `z`, `m`: the elevations (m, NaN invalid) and mask
/// ([`fields::mask`]) of this rank's [`read_rows`], row by row; `geo`: the whole raster's.
/// Every rank calls it together. Returns `(filled, accumulation)`, each `w × band rows`
/// (masked cells NaN and 0).
///
/// Errors: [`Error::Invalid`] for a bad cut or a read of the wrong size; [`Error::Exchange`]
/// from the transport or for a message cut short.
#[allow(clippy::too_many_arguments)]
pub fn hydrology_of_rank(tr: &mut dyn Transport, bands: &[Window], w: usize, h: usize, z: &[f32], m: &[bool], geo: &GeoRef, context: &str) -> Result<(Grid<f32>, Grid<f32>)> {
    let (me, n) = (tr.rank(), tr.size());
    check_bands(bands, w, h, context)?;
    if bands.len() != n {
        return Err(Error::Invalid { context: context.into(), field: "bands".into(), value: bands.len().to_string(), expected: format!("one band per rank ({n})") });
    }
    let brs: Vec<BandRows> = bands.iter().map(|b| BandRows { w, ..BandRows::new(b, h) }).collect();
    let br = &brs[me];
    let ext = (br.ext1 - br.ext0) * w;
    if z.len() != ext || m.len() != ext {
        return Err(Error::Invalid { context: context.into(), field: "rows read for the hydrology".into(), value: format!("{} elevations, {} mask cells", z.len(), m.len()), expected: format!("rows {}..{} of {w} cells ({ext})", br.ext0, br.ext1) });
    }
    let rows = br.row1 - br.row0;
    let fail = |peer: usize| move |s: Short| Error::Exchange { peer, reason: format!("hydrology message cut short at byte {}", s.at()) };
    // 1. fill: each band's label graph to rank 0, each band's labels' levels back
    let f = if rows > 0 { fill_band(br, z, m) } else { LocalFill { zf: Vec::new(), label: Vec::new(), nlabels: 0, edges: Vec::new() } };
    let mut out = vec![Vec::new(); n];
    let mut e = Enc(Vec::new());
    e.u64(f.nlabels as u64);
    e.u64(f.edges.len() as u64);
    for &(a, b, v) in &f.edges {
        e.u64((a as u64) << 32 | b as u64);
        e.f32(v);
    }
    let (top, bottom) = if rows > 0 { (0..w, (rows - 1) * w..rows * w) } else { (0..0, 0..0) };
    e.u32s(&f.label[top.clone()]);
    e.f32s(&f.zf[top]);
    e.u32s(&f.label[bottom.clone()]);
    e.f32s(&f.zf[bottom]);
    out[0] = e.0;
    let got = tr.exchange(out)?;
    let mut out = vec![Vec::new(); n];
    if me == 0 {
        let mut sums = Vec::with_capacity(n);
        for (k, msg) in got.iter().enumerate() {
            let fk = fail(k);
            let mut d = Dec::new(msg, &fk);
            let nlabels = d.u64()? as u32;
            let ne = d.count(12)?;
            let mut edges = Vec::with_capacity(ne);
            for _ in 0..ne {
                let ab = d.u64()?;
                edges.push(((ab >> 32) as u32, ab as u32, d.f32()?));
            }
            let top = (d.u32s()?, d.f32s()?);
            let bottom = (d.u32s()?, d.f32s()?);
            sums.push(FillSummary { nlabels, edges, top, bottom });
        }
        for (o, lv) in out.iter_mut().zip(solve_levels(&sums)) {
            let mut e = Enc(Vec::new());
            e.f32s(&lv);
            *o = e.0;
        }
    }
    let got = tr.exchange(out)?;
    let f0 = fail(0);
    let levels = Dec::new(&got[0], &f0).f32s()?;
    if levels.len() != f.nlabels as usize {
        return Err(Error::Exchange { peer: 0, reason: format!("{} label levels for {} labels", levels.len(), f.nlabels) });
    }
    let filled: Vec<f32> = f.zf.iter().zip(&f.label).map(|(z, l)| if *l == NONE { *z } else { z.max(levels[*l as usize]) }).collect();
    // 2. directions: the filled rows of the halo from the ranks that own them; the flats across
    // band edges resolved by rank 0
    let f32_bytes: fn(&[f32]) -> Vec<u8> = |v| v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect();
    let f32_back: fn(&[u8]) -> Vec<f32> = |b| b.chunks_exact(4).map(|c| f32::from_bits(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))).collect();
    let zf_ext = exchange_rows(tr, &brs, &filled, &|b| (b.ext0, b.ext1), f32_bytes, f32_back)?;
    let (mut dirs, shared) = if rows > 0 { directions_band(br, &zf_ext, m, geo) } else { (Vec::new(), Vec::new()) };
    let mut out = vec![Vec::new(); n];
    let mut e = Enc(Vec::new());
    e.u64(shared.len() as u64);
    for c in &shared {
        e.u64((c.i as u64) << 16 | (c.high as u64) << 8 | c.low as u64);
    }
    out[0] = e.0;
    let got = tr.exchange(out)?;
    let mut out = vec![Vec::new(); n];
    if me == 0 {
        let mut all = Vec::new();
        let mut counts = Vec::with_capacity(n);
        for (k, msg) in got.iter().enumerate() {
            let fk = fail(k);
            let mut d = Dec::new(msg, &fk);
            let c = d.count(8)?;
            for x in d.u64s_n(c)? {
                all.push(FlatCell { i: (x >> 16) as usize, high: (x >> 8) & 1 != 0, low: x as u8 });
            }
            counts.push(c);
        }
        let codes = solve_flats(&all, w, h, geo);
        let mut at = 0;
        for (o, c) in out.iter_mut().zip(counts) {
            *o = codes[at..at + c].to_vec();
            at += c;
        }
    }
    let got = tr.exchange(out)?;
    if got[0].len() != shared.len() {
        return Err(Error::Exchange { peer: 0, reason: format!("{} flat codes for {} cells", got[0].len(), shared.len()) });
    }
    for (c, d) in shared.iter().zip(&got[0]) {
        dirs[c.i - br.row0 * w] = *d;
    }
    // 3. accumulation: the codes of the rows just outside the band from their owners; the counts
    // across band edges passed by rank 0
    let around = |b: &BandRows| (b.row0.saturating_sub(1), (b.row1 + 1).min(h));
    let dir_ext = exchange_rows(tr, &brs, &dirs, &around, |v| v.to_vec(), |b| b.to_vec())?;
    let (a0, a1) = around(br);
    let mut halo = Vec::new();
    if rows > 0 && a0 < br.row0 {
        halo.push((a0, dir_ext[..w].to_vec()));
    }
    if rows > 0 && a1 > br.row1 {
        halo.push((br.row1, dir_ext[(br.row1 - a0) * w..(a1 - a0) * w].to_vec()));
    }
    let (mut acc, exits, links) = if rows > 0 { accumulate_band(br, &dirs, m, &halo) } else { (Vec::new(), Vec::new(), Vec::new()) };
    let mut out = vec![Vec::new(); n];
    let mut e = Enc(Vec::new());
    e.u64(exits.len() as u64);
    for &(g, c, t) in &exits {
        e.u64(g as u64);
        e.f64(c);
        e.u64(t as u64);
    }
    e.u64(links.len() as u64);
    for &(g, x) in &links {
        e.u64(g as u64);
        e.u64(x.map_or(u64::MAX, |x| x as u64));
    }
    out[0] = e.0;
    let got = tr.exchange(out)?;
    let mut out = vec![Vec::new(); n];
    if me == 0 {
        let (mut all_exits, mut all_links, mut per) = (Vec::new(), Vec::new(), Vec::with_capacity(n));
        for (k, msg) in got.iter().enumerate() {
            let fk = fail(k);
            let mut d = Dec::new(msg, &fk);
            let ne = d.count(24)?;
            for _ in 0..ne {
                all_exits.push((d.u64()? as usize, d.f64()?, d.u64()? as usize));
            }
            let nl = d.count(16)?;
            let mut mine = Vec::with_capacity(nl);
            for _ in 0..nl {
                let (g, x) = (d.u64()? as usize, d.u64()?);
                all_links.push((g, (x != u64::MAX).then_some(x as usize)));
                mine.push(g);
            }
            per.push(mine);
        }
        let inflow = solve_inflows(&all_exits, &all_links);
        for (o, mine) in out.iter_mut().zip(per) {
            let mut e = Enc(Vec::new());
            for g in mine {
                e.f64(inflow.get(&g).copied().unwrap_or(0.0));
            }
            *o = e.0;
        }
    }
    let got = tr.exchange(out)?;
    if got[0].len() != 8 * links.len() {
        return Err(Error::Exchange { peer: 0, reason: format!("{} bytes of inflows for {} entry cells", got[0].len(), links.len()) });
    }
    let base = br.row0 * w;
    for ((e, _), b) in links.iter().zip(got[0].chunks_exact(8)) {
        let add = f64::from_le_bytes(b.try_into().unwrap_or_default());
        if add == 0.0 {
            continue;
        }
        let mut i = e - base;
        loop {
            acc[i] += add;
            match down(base + i, dirs[i], w, h).and_then(|g| br.own(g)) {
                Some(j) => i = j,
                None => break,
            }
        }
    }
    Ok((Grid { width: w, height: rows, data: filled }, Grid { width: w, height: rows, data: acc.into_iter().map(|v| v as f32).collect() }))
}

/// The depression-filled elevation (m) and D8 flow accumulation (cells) of each band of a
/// raster, one process: every band a rank of a [`LocalTransport`] group on a thread of its own,
/// reading only its [`read_rows`] of `t` and `m` ([`hydrology_of_rank`]); equal bit for bit
/// to the same rows of the whole raster's ([`fields::fill_depressions`],
/// [`fields::flow_accumulation`] over [`fields::flow_directions`]) for any cut. `bands`:
/// full-width windows of consecutive rows covering the `m.width × m.height` raster from row 0,
/// in order (empty ones allowed). Returns one `(filled, accumulation)` pair per band, each
/// `width × band rows`.
///
/// Errors: [`Error::Invalid`] naming the first band that is not full width or not next to the
/// one before, or a cut that does not end at the raster's last row.
pub fn hydrology_by_bands(t: &Terrain, m: &Grid<bool>, bands: &[Window]) -> Result<Vec<(Grid<f32>, Grid<f32>)>> {
    let (w, h) = (m.width, m.height);
    check_bands(bands, w, h, &t.source)?;
    let ends = LocalTransport::group(bands.len());
    std::thread::scope(|s| {
        let handles: Vec<_> = ends
            .into_iter()
            .map(|mut tr| {
                s.spawn(move || {
                    let (r0, r1) = read_rows(&bands[tr.rank()], h);
                    let (z, mm) = (&t.elevation.data[r0 * w..r1 * w], &m.data[r0 * w..r1 * w]);
                    hydrology_of_rank(&mut tr, bands, w, h, z, mm, &t.geo, &t.source)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|_| Err(Error::Invalid { context: t.source.clone(), field: "hydrology".into(), value: "a band's thread panicked".into(), expected: "no panic".into() }))).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::fields::{fill_depressions, flow_accumulation, flow_directions, mask};

    /// A `w × h` terrain of 10 m cells with elevations `f(c, r)` (NaN: nodata).
    fn terrain(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Terrain {
        let data = (0..w * h).map(|i| f(i % w, i / w)).collect();
        Terrain { elevation: Grid { width: w, height: h, data }, geo: GeoRef::local(10.0, 45.0), nodata: None, source: "test".into() }
    }

    fn hash(c: usize, r: usize, seed: u64) -> f64 {
        let x = ((c as u64) << 32 | r as u64).wrapping_add(seed).wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let x = (x ^ (x >> 29)).wrapping_mul(0xbf58476d1ce4e5b9);
        (x >> 40) as f64 / (1u64 << 24) as f64
    }

    /// Bands of `n` cuts (as `job::site_ranks::band`), empty ones left out.
    fn cut(w: usize, h: usize, n: usize) -> Vec<Window> {
        (0..n).map(|k| Window { col0: 0, row0: k * h / n, width: w, height: (k + 1) * h / n - k * h / n }).filter(|b| b.height > 0).collect()
    }

    /// The whole raster's fill, codes and accumulation against every cut's, bit for bit.
    fn same_by_bands(t: &Terrain, cuts: &[usize]) {
        let m = mask(t, 0.0);
        let filled = fill_depressions(t, &m);
        let dir = flow_directions(&filled, &t.geo, &m);
        let acc = flow_accumulation(&dir, &m);
        let full = Window::full(m.width, m.height);
        for &n in cuts {
            let bands = cut(m.width, m.height, n);
            let got = hydrology_by_bands(t, &m, &bands).unwrap();
            for (b, (f, a)) in bands.iter().zip(got) {
                let (wf, wa) = (b.cut(&filled, &full), b.cut(&acc, &full));
                for i in 0..f.data.len() {
                    let (c, r) = (i % b.width, b.row0 + i / b.width);
                    assert_eq!(f.data[i].to_bits(), wf.data[i].to_bits(), "{n} bands: filled at {c},{r}: {} against {}", f.data[i], wf.data[i]);
                    assert_eq!(a.data[i].to_bits(), wa.data[i].to_bits(), "{n} bands: accumulation at {c},{r}: {} against {}", a.data[i], wa.data[i]);
                }
            }
        }
    }

    #[test]
    fn noise_with_pits_is_the_same_by_bands() {
        // random heights in 0–20 m: hundreds of pits, some across band edges
        let t = terrain(37, 29, |c, r| (100.0 + 20.0 * hash(c, r, 1)) as f32);
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        assert!(f.data.iter().zip(&t.elevation.data).filter(|(a, b)| a > b).count() > 50);
        same_by_bands(&t, &[1, 2, 3, 7, 29]);
    }

    #[test]
    fn integer_metre_noise_with_flats_and_holes_is_the_same_by_bands() {
        // heights rounded to whole metres (flats everywhere, outlets of equal height) with a
        // few nodata holes (outlets inside the raster)
        let t = terrain(41, 33, |c, r| if hash(c, r, 7) < 0.02 { f32::NAN } else { (100.0 + (6.0 * hash(c, r, 3)).floor() + 0.2 * r as f64).floor() as f32 });
        same_by_bands(&t, &[1, 2, 3, 7, 33]);
    }

    #[test]
    fn walled_flat_across_band_edges_is_the_same_by_bands() {
        // the flat floor of `fields`' walled-flat test, with notches of equal height in the
        // west and the east walls, a pit in it and the floor spanning every band of 2, 3, 7 cuts
        let (w, h) = (15usize, 21usize);
        let t = terrain(w, h, |c, r| {
            if (c, r) == (0, 4) || (c, r) == (w - 1, 16) || (c > 0 && r > 0 && c + 1 < w && r + 1 < h) {
                if (c, r) == (7, 10) { 90.0 } else { 100.0 }
            } else {
                110.0
            }
        });
        let m = mask(&t, 0.0);
        // the floor's flat touches both bands' edge rows: its cells are resolved centrally
        let bands = cut(w, h, 2);
        let br = BandRows::new(&bands[0], h);
        let z: Vec<f32> = fill_depressions(&t, &m).data[br.ext0 * w..br.ext1 * w].to_vec();
        let (_, shared) = directions_band(&br, &z, &m.data[br.ext0 * w..br.ext1 * w], &t.geo);
        assert_eq!(shared.len(), 13 * (10 - 1), "the upper band's floor rows 1–9, 13 cells each");
        same_by_bands(&t, &[1, 2, 3, 7, 21]);
    }

    #[test]
    fn bad_cuts_are_refused() {
        let t = terrain(5, 4, |_, _| 100.0);
        let m = mask(&t, 0.0);
        let e = hydrology_by_bands(&t, &m, &[Window { col0: 0, row0: 0, width: 5, height: 2 }, Window { col0: 0, row0: 3, width: 5, height: 1 }]).unwrap_err().to_string();
        assert!(e.contains("starting at row 2"), "{e}");
        let e = hydrology_by_bands(&t, &m, &[Window { col0: 0, row0: 0, width: 5, height: 3 }]).unwrap_err().to_string();
        assert!(e.contains("covering the 4 rows"), "{e}");
    }
}
