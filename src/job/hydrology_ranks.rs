//! The hydrology of a DEM by ranks (issue 37, round 34): each rank runs the per-band passes of
//! [`crate::terrain::hydrology`] on its band of rows and rank 0 the central solves, over any
//! [`Transport`] (MPI under `mpirun`, or a [`LocalTransport`] thread per band:
//! [`hydrology_by_bands`]). The result equals the whole raster's
//! ([`crate::terrain::fields::fill_depressions`], [`crate::terrain::fields::flow_directions`], [`crate::terrain::fields::flow_accumulation`])
//! bit for bit whatever the number of ranks; no rank holds the whole DEM.

use crate::error::{Error, Result};
use crate::grid::{GeoRef, Grid, Window};
use crate::sim::codec::{Dec, Enc, Short};
use crate::sim::tiles::{LocalTransport, Transport};
use crate::terrain::fields::FlatCell;
use crate::terrain::hydrology::{accumulate_band, check_bands, directions_band, down, fill_band, read_rows, solve_flats, solve_inflows, solve_levels, BandRows, FillSummary, LocalFill, NONE};
use crate::terrain::Terrain;

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
/// [`crate::terrain::fields::fill_depressions`] and [`crate::terrain::fields::flow_accumulation`] over
/// [`crate::terrain::fields::flow_directions`] of the whole raster, whatever the number of ranks or the cut
/// (the passes: [`crate::terrain::hydrology`]).
/// `bands[k]`: rank `k`'s band (full-width consecutive rows covering the raster in rank order;
/// empty bands allowed); `z`, `m`: the elevations (m, NaN invalid) and mask
/// ([`crate::terrain::fields::mask`]) of this rank's [`read_rows`], row by row; `geo`: the whole raster's.
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
/// to the same rows of the whole raster's ([`crate::terrain::fields::fill_depressions`],
/// [`crate::terrain::fields::flow_accumulation`] over [`crate::terrain::fields::flow_directions`]) for any cut. `bands`:
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
    use crate::terrain::hydrology::{directions_band, BandRows};

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
