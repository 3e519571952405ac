//! The site of a tiled run derived by its ranks (issue 37 Build 1, first part): for a scenario
//! whose terrain is a GeoTIFF file, every rank reads its band of rows of the DEM **by window**
//! (only the strips or tiles it overlaps, [`crate::terrain::io::read_geotiff_window`]) with the
//! halo its fields need, derives its band's conditions
//! ([`crate::conditions::derive_window`]), and the bands are exchanged so that every rank
//! holds the site of one process, bit for bit ([`site_by_ranks`]).
//!
//! Per field: mask, elevation, temperature, TWI and the indices cell by cell; slope and aspect
//! with 1 cell of halo; insolation and wind exposure with the horizon's halo
//! ([`crate::terrain::fields::window_halo_cells`], 86 cells); depression filling, flow
//! directions and flow accumulation from the rank's rows and two rows of halo, read by window,
//! with three exchanges of the bands' perimeters (round 34,
//! [`crate::job::hydrology_ranks::hydrology_of_rank`]: Barnes 2016's fill, flats across band
//! edges resolved on rank 0, Barnes 2017's accumulation), equal bit for bit to the whole DEM's.
//! [`site_by_ranks`] gathers the bands on every rank (the whole site of one process);
//! [`site_by_ranks_held`] (what `sylva simulate` under `mpirun` uses for a scenario without
//! management, round 32) gathers them on rank 0 only and every other rank keeps its band, from
//! which `job::tiled::tile_site_by` moves each tile its cells. No rank reads the whole DEM
//! (until round 33 rank 0 did, for the hydrology).

use crate::conditions::SiteConditions;
use crate::error::{Error, Result};
use crate::grid::{Crs, Grid, Window};
use crate::sim::codec::{Dec, Enc, Short};
use crate::sim::scenario::{Scenario, TerrainSpec};
use crate::sim::tiles::Transport;

/// The GeoTIFF a scenario's site is read from, if it is one: the file and the scenario's
/// window of it (`[terrain] window`, or `None`).
pub fn geotiff_of(sc: &Scenario) -> Option<(std::path::PathBuf, Option<[usize; 4]>)> {
    match sc.terrain_spec() {
        TerrainSpec::Path(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff")) && p.is_file() => Some((p, sc.terrain.window)),
        _ => None,
    }
}

/// Rows `row0..row1` of an `h`-row site for rank `k` of `n`: `k · h / n` to `(k + 1) · h / n`.
pub fn band(k: usize, n: usize, w: usize, h: usize) -> Window {
    let (r0, r1) = (k * h / n, (k + 1) * h / n);
    Window { col0: 0, row0: r0, width: w, height: r1 - r0 }
}

/// The site conditions of `sc` on every rank of `t`, equal bit for bit to [`Scenario::site`]:
/// for a GeoTIFF terrain each rank derives the band of rows [`band`] from a window of the DEM
/// (module documentation) and the bands are exchanged; any other terrain is derived whole by
/// every rank ([`Scenario::site`]). Prints one line per rank to stderr (`rank k/n: site rows
/// …`). Every rank fails when one does.
///
/// Errors: as [`Scenario::site`]; [`Error::Exchange`] from the transport, naming the rank that
/// failed.
pub fn site_by_ranks(sc: &Scenario, t: &mut dyn Transport) -> Result<SiteConditions> {
    site_by_ranks_held(sc, t, true)
}

/// [`site_by_ranks`], but with `whole` false a rank other than 0 keeps only its band of rows
/// ([`band`]; [`SiteConditions::held`] the band, [`SiteConditions::full`] the site's size;
/// every value the one of [`site_by_ranks`]'s site there) and rank 0 the whole site (issue 37
/// Build 1, item (a), round 32): for a GeoTIFF terrain the ranks other than 0 send their band's
/// conditions only to rank 0 (and their cell size to the others); any other terrain is
/// derived whole and cut to the band (a uniform terrain: its band only, built directly).
///
/// Errors: as [`site_by_ranks`].
pub fn site_by_ranks_held(sc: &Scenario, t: &mut dyn Transport, whole: bool) -> Result<SiteConditions> {
    site_by_ranks_banded(sc, t, whole, false)
}

/// [`site_by_ranks_held`], with `band0` (and `whole` false) rank 0 keeping its band too: no
/// rank holds the whole site's conditions (issue 37 Build 1, round 33: a fresh run without
/// management, whose rank 0 builds its tile's world only, `job::tiled`'s lean start). For a
/// GeoTIFF terrain every rank reads only its band's rows of the DEM (with the halos of the
/// module documentation); every rank then sends every other only its cell size.
///
/// Errors: as [`site_by_ranks`].
pub fn site_by_ranks_banded(sc: &Scenario, t: &mut dyn Transport, whole: bool, band0: bool) -> Result<SiteConditions> {
    let (me, n) = (t.rank(), t.size());
    let keep_band = !whole && (me != 0 || band0) && n > 1;
    let Some((path, sw)) = geotiff_of(sc) else {
        if keep_band && sc.terrain.window.is_none() {
            if let TerrainSpec::Uniform(u) = sc.terrain_spec() {
                // the band of a uniform site, equal cell by cell to the whole one's rows
                let b = band(me, n, u.width, u.height);
                let mut c = SiteConditions::uniform(u.width, b.height, u.cell_m, u.elevation_m, u.indices, sc.climate.latitude_deg);
                (c.held, c.full) = (b, (u.width, u.height));
                return Ok(c);
            }
        }
        let mut c = sc.site()?;
        if keep_band {
            c.hold(band(me, n, c.width(), c.height()));
        }
        return Ok(c);
    };
    // the site's raster: the scenario's window of the file, or the file
    let head = crate::terrain::io::load_window(&path, Window { col0: 0, row0: 0, width: 1, height: 1 });
    let head = agreed(t, head)?;
    let base = match sw {
        Some([c0, r0, w, h]) => Window { col0: c0, row0: r0, width: w, height: h },
        None => Window::full(head.full_width, head.full_height),
    };
    if !base.inside(head.full_width, head.full_height) {
        // as the whole read refuses it (io::window)
        return sc.site();
    }
    let (w, h) = (base.width, base.height);
    let mut geo = head.geo.clone();
    if sw.is_some() {
        // as crate::terrain::io::window re-bases a window
        geo.origin_x += base.col0 as f64 * geo.pixel_w;
        geo.origin_y -= base.row0 as f64 * geo.pixel_h;
        if geo.crs == Crs::Geographic {
            geo.latitude_deg = geo.origin_y - geo.pixel_h * h as f64 / 2.0;
        }
    }
    let bands: Vec<Window> = (0..n).map(|k| band(k, n, w, h)).collect();
    // every rank: the hydrology of its band from its rows of the DEM and two rows of halo, read
    // by window, and the ranks' perimeters (terrain::hydrology, round 34): no rank reads the
    // whole DEM
    let me_band = bands[me];
    let (r0, r1) = crate::terrain::hydrology::read_rows(&me_band, h);
    let sea = sc.climate.sea_level_m;
    let read = crate::terrain::io::load_window(&path, Window { col0: base.col0, row0: base.row0 + r0, width: w, height: r1 - r0 }).map(|d| {
        let m: Vec<bool> = d.elevation.data.iter().map(|z| z.is_finite() && *z > sea).collect();
        (d.elevation.data, m)
    });
    let (z, m) = agreed(t, read)?;
    let own = (me_band.row0 - r0) * w..(me_band.row1() - r0) * w;
    let valid = t.all_sum(vec![m[own].iter().filter(|v| **v).count() as u64])?;
    if valid.first() == Some(&0) {
        // as fields::compute refuses it
        return Err(Error::Invalid { context: path.display().to_string(), field: "sea_level_m".into(), value: sea.to_string(), expected: "a sea level below some valid elevation (every cell is nodata or water)".into() });
    }
    let context = path.display().to_string();
    let hydro = crate::job::hydrology_ranks::hydrology_of_rank(t, &bands, w, h, &z, &m, &geo, &context)?;
    drop((z, m));
    let part: Result<Option<SiteConditions>> = (|| {
        if me_band.height == 0 {
            return Ok(None);
        }
        let (filled, acc) = hydro;
        // the band and its halo, read by window from the file
        let halo = crate::terrain::fields::window_halo_cells(&geo, h);
        let patch = me_band.with_halo(halo, w, h);
        let file_win = Window { col0: base.col0 + patch.col0, row0: base.row0 + patch.row0, width: patch.width, height: patch.height };
        let mut dem = crate::terrain::io::load_window(&path, file_win)?;
        dem.window = patch;
        (dem.full_width, dem.full_height) = (w, h);
        dem.geo = geo.clone();
        let c = crate::conditions::derive_window(&dem, &me_band, &sc.climate, filled, acc)?;
        let line = format!("rank {me}/{n}: site rows {}..{} of {h} derived from a window of {} ({} of {} cells read, halo {halo}; hydrology from rows {r0}..{r1})\n", me_band.row0, me_band.row1(), path.display(), patch.width * patch.height, w * h);
        let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
        Ok(Some(c))
    })();
    // every rank sends every other its band's conditions (or its error)
    let mine = match &part {
        Ok(c) => {
            let mut e = Enc(vec![0u8]);
            if let Some(c) = c {
                encode(&mut e, c);
            }
            e.0
        }
        Err(err) => {
            let mut m = vec![1u8];
            m.extend_from_slice(err.to_string().as_bytes());
            m
        }
    };
    // the ranks that keep their band only (`whole` false: all but 0) get the others' cell
    // size (a 0 byte, then `cell_x_m` and `cell_y_m` of a non-empty band) instead of the band
    let short = |m: &Vec<u8>| -> Vec<u8> {
        match (&part, m.first()) {
            (Ok(Some(c)), Some(0)) => {
                let mut e = Enc(vec![0u8]);
                e.f64(c.cell_x_m);
                e.f64(c.cell_y_m);
                e.0
            }
            _ => m.clone(),
        }
    };
    // a copy for every other rank; this rank's own goes to itself without one
    let mut out: Vec<Vec<u8>> = (0..n).map(|k| if k == me { Vec::new() } else if whole || (k == 0 && !band0) { mine.clone() } else { short(&mine) }).collect();
    out[me] = mine;
    let got = t.exchange(out)?;
    let part = part?;
    for (k, m) in got.iter().enumerate() {
        if m.first() != Some(&0) {
            return Err(Error::Exchange { peer: k, reason: format!("rank {k} failed: {}", String::from_utf8_lossy(m.get(1..).unwrap_or(&[]))) });
        }
    }
    if !keep_band {
        return assemble(got, &bands, w, h, geo);
    }
    // this rank's band: the cell size is the last non-empty band's, as `assemble` takes it
    let mut cell = (geo.pixel_w, geo.cell_y_m());
    for (k, (m, b)) in got.iter().zip(&bands).enumerate() {
        if b.height == 0 {
            continue;
        }
        cell = match (k == me, &part) {
            (true, Some(c)) => (c.cell_x_m, c.cell_y_m),
            _ => {
                let fail = |s: Short| Error::Exchange { peer: k, reason: format!("cell size message cut short at byte {}", s.at()) };
                let mut d = Dec::at(m, 1, &fail);
                (d.f64()?, d.f64()?)
            }
        };
    }
    let mut c = match part {
        Some(c) => c,
        // an empty band (more ranks than rows): no cells
        None => assemble(Vec::new(), &[], w, 0, geo.clone())?,
    };
    (c.geo, c.cell_x_m, c.cell_y_m, c.held, c.full) = (geo, cell.0, cell.1, me_band, (w, h));
    Ok(c)
}

/// Every rank learns whether `r` (each rank's own result, e.g. reading the DEM's header) failed
/// on some rank; returns this rank's value when none did.
///
/// Errors: the first failure, naming its rank; [`Error::Exchange`] from the transport.
fn agreed<T>(t: &mut dyn Transport, r: Result<T>) -> Result<T> {
    let n = t.size();
    let msg = r.as_ref().err().map(|e| e.to_string().into_bytes()).unwrap_or_default();
    let got = t.exchange(vec![msg; n])?;
    let v = r?;
    match got.iter().enumerate().find(|(_, m)| !m.is_empty()) {
        Some((k, m)) => Err(Error::Exchange { peer: k, reason: format!("rank {k} failed: {}", String::from_utf8_lossy(m)) }),
        None => Ok(v),
    }
}

/// The per-cell fields of site conditions as the ranks exchange them ([`field_values`]): the
/// mask, seven `f32` grids, the indices.
pub const FIELDS: usize = 9;

/// The `f32` grid of field `f` (1–7: elevation, slope, aspect, TWI, insolation, wind exposure,
/// temperature) of `c`.
fn f32_grid(c: &SiteConditions, f: usize) -> &Grid<f32> {
    [&c.elevation_m, &c.slope_deg, &c.aspect_deg, &c.twi, &c.insolation_kwh_m2, &c.wind_exposure, &c.temperature_c][f - 1]
}

/// Field `f` of the [`FIELDS`] of `c` over the cells `win` (inside the cells held, row-major,
/// row 0 north) as `f32`s, as the ranks send them: 0 the mask (1.0 unmasked, 0.0 masked), 1–7
/// elevation (m), slope (°), aspect (°), TWI, insolation (kWh/m²/yr), wind exposure (0–1),
/// temperature (°C), 8 the indices (6 values a cell, `[L, T, K, F, R, N]`). Shared by the
/// bands' gather ([`site_by_ranks`]) and the tiles' windows (`job::tiled::tile_site_by`).
/// Panics when `win` is not inside [`SiteConditions::held`].
pub fn field_values(c: &SiteConditions, f: usize, win: Window) -> Vec<f32> {
    match f {
        0 => win.cut(&c.mask, &c.held).data.iter().map(|&m| if m { 1.0 } else { 0.0 }).collect(),
        8 => win.cut(&c.indices, &c.held).data.iter().flatten().copied().collect(),
        f => win.cut(f32_grid(c, f), &c.held).data,
    }
}

/// Gives up field `f` ([`field_values`]) of `c` (its grid emptied): a rank that has sent its
/// band's field keeps no copy of it.
pub fn drop_field(c: &mut SiteConditions, f: usize) {
    match f {
        0 => c.mask.data = Vec::new(),
        8 => c.indices.data = Vec::new(),
        1 => c.elevation_m.data = Vec::new(),
        2 => c.slope_deg.data = Vec::new(),
        3 => c.aspect_deg.data = Vec::new(),
        4 => c.twi.data = Vec::new(),
        5 => c.insolation_kwh_m2.data = Vec::new(),
        6 => c.wind_exposure.data = Vec::new(),
        _ => c.temperature_c.data = Vec::new(),
    }
}

/// The site conditions holding the cells `held` of a grid of `full` (columns, rows) from the
/// [`FIELDS`] fields `fields` in [`field_values`]' order and encoding (each
/// `held.width · held.height` values, the indices 6 a cell; a missing field is an empty grid),
/// with georeferencing `geo` and cell size `cell_x_m × cell_y_m` (m).
pub fn conditions_of(geo: crate::grid::GeoRef, cell_x_m: f64, cell_y_m: f64, held: Window, full: (usize, usize), fields: Vec<Vec<f32>>) -> SiteConditions {
    let (w, h) = (held.width, held.height);
    let mut it = fields.into_iter();
    let mut next = || Grid { width: w, height: h, data: it.next().unwrap_or_default() };
    let mask = next().map(|v| *v != 0.0);
    let (elevation_m, slope_deg, aspect_deg, twi, insolation_kwh_m2, wind_exposure, temperature_c) = (next(), next(), next(), next(), next(), next(), next());
    let indices = Grid { width: w, height: h, data: next().data.chunks_exact(6).map(|q| [q[0], q[1], q[2], q[3], q[4], q[5]]).collect() };
    SiteConditions { geo, cell_x_m, cell_y_m, mask, elevation_m, slope_deg, aspect_deg, twi, insolation_kwh_m2, wind_exposure, temperature_c, indices, held, full }
}

/// The per-cell grids of a band's conditions, in [`field_values`]' order, then its cell size.
fn encode(e: &mut Enc<Vec<u8>>, c: &SiteConditions) {
    for f in 0..FIELDS {
        e.f32s(&field_values(c, f, c.held));
    }
    e.f64(c.cell_x_m);
    e.f64(c.cell_y_m);
}

/// The site of `w × h` cells from the ranks' bands (`got[k]`: rank `k`'s message, [`encode`]d
/// after a 0 byte), rows in rank order; each message is dropped once read, so the peak is about
/// the site plus one band's message.
///
/// Errors: [`Error::Exchange`] naming a rank whose message is short or of the wrong size.
fn assemble(got: Vec<Vec<u8>>, bands: &[Window], w: usize, h: usize, geo: crate::grid::GeoRef) -> Result<SiteConditions> {
    let mut fields: Vec<Vec<f32>> = (0..FIELDS).map(|f| Vec::with_capacity(if f == 8 { 6 } else { 1 } * w * h)).collect();
    let (mut cx, mut cy) = (None, None);
    for (k, (m, b)) in got.into_iter().zip(bands).enumerate() {
        if b.height == 0 {
            continue;
        }
        let fail = |s: Short| Error::Exchange { peer: k, reason: format!("site band message cut short at byte {}", s.at()) };
        let mut d = Dec::at(&m, 1, &fail);
        let cells = b.width * b.height;
        for (f, g) in fields.iter_mut().enumerate() {
            let per = if f == 8 { 6 } else { 1 };
            let v = d.f32s()?;
            if v.len() != per * cells {
                let what = if f == 8 { "index values / 6" } else { "cells" };
                return Err(Error::Exchange { peer: k, reason: format!("site band {b} of rank {k}: {} {what}, expected {cells}", v.len() / per) });
            }
            g.extend_from_slice(&v);
        }
        (cx, cy) = (Some(d.f64()?), Some(d.f64()?));
    }
    let (cell_x_m, cell_y_m) = (cx.unwrap_or(geo.pixel_w), cy.unwrap_or(geo.cell_y_m()));
    Ok(conditions_of(geo, cell_x_m, cell_y_m, Window::full(w, h), (w, h), fields))
}
