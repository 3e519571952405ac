//! Fields derived from a DEM on its own grid (row 0 north): mask, slope, aspect, depression
//! filling, D8 flow accumulation, topographic wetness index, clear-sky annual insolation with
//! terrain shading, wind exposure, temperature.
//!
//! Every field is `f32` on the terrain's grid; masked cells (nodata or at/below sea level) hold
//! `NaN` (flow accumulation: 0). Row-parallel with rayon; no result depends on the thread count.
//! Geographic grids use the east–west cell size of each row ([`GeoRef::cell_x_m_at_row`]).

use super::Terrain;
use crate::conditions::Climate;
use crate::error::{Error, Result};
use crate::grid::{Crs, GeoRef, Grid};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// Cells that take part in every field: finite elevation strictly above `sea_level_m`.
pub fn mask(t: &Terrain, sea_level_m: f32) -> Grid<bool> {
    t.elevation.map(|z| z.is_finite() && *z > sea_level_m)
}

/// The 3×3 window around `(c, r)` in gdaldem's order `[a b c; d e f; g h i]` (row above first).
/// Neighbours outside the grid or masked take the centre's value (edge replication).
#[inline]
fn window3(z: &Grid<f32>, m: &Grid<bool>, c: usize, r: usize) -> [f32; 9] {
    let e = *z.get(c, r);
    let mut w = [e; 9];
    for (k, (dc, dr)) in [(-1i64, -1i64), (0, -1), (1, -1), (-1, 0), (0, 0), (1, 0), (-1, 1), (0, 1), (1, 1)].iter().enumerate() {
        let (cc, rr) = (c as i64 + dc, r as i64 + dr);
        if cc >= 0 && rr >= 0 && (cc as usize) < z.width && (rr as usize) < z.height && *m.get(cc as usize, rr as usize) {
            w[k] = *z.get(cc as usize, rr as usize);
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
    let (w, h) = (t.elevation.width, t.elevation.height);
    let mut slope = Grid::filled(w, h, f32::NAN);
    let mut aspect = Grid::filled(w, h, f32::NAN);
    let dy = t.geo.cell_y_m();
    slope.data.par_chunks_mut(w).zip(aspect.data.par_chunks_mut(w)).enumerate().for_each(|(r, (sr, ar))| {
        let dx = t.geo.cell_x_m_at_row(r);
        for c in 0..w {
            if !*m.get(c, r) {
                continue;
            }
            let (gx, gy) = horn_gradient(&window3(&t.elevation, m, c, r), dx, dy);
            sr[c] = (gx * gx + gy * gy).sqrt().atan().to_degrees() as f32;
            ar[c] = aspect_from_gradient(gx, gy);
        }
    });
    (slope, aspect)
}

/// The next representable f32 above `x` (C `nextafterf(x, +inf)`).
#[inline]
fn next_up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let b = x.to_bits();
    if x > 0.0 { f32::from_bits(b + 1) } else { f32::from_bits(b - 1) }
}

const D8: [(i64, i64); 8] = [(0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1)];

fn is_seed(m: &Grid<bool>, c: usize, r: usize) -> bool {
    if c == 0 || r == 0 || c + 1 == m.width || r + 1 == m.height {
        return true;
    }
    D8.iter().any(|(dc, dr)| !*m.get((c as i64 + dc) as usize, (r as i64 + dr) as usize))
}

/// Depression filling by Priority-Flood + ε (Barnes, Lehman & Mulla 2014, Computers &
/// Geosciences 62:117–127, Algorithm 3): cells on the grid border or next to a masked cell are
/// outlets; every other cell is raised to at least the next representable f32 above the cell
/// it is reached from, so that every valid cell has a strictly descending path to an outlet.
/// Ties in the priority queue are broken by cell index (deterministic). Masked cells stay NaN.
pub fn fill_depressions(t: &Terrain, m: &Grid<bool>) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let mut z: Vec<f32> = t.elevation.data.iter().zip(&m.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect();
    let mut closed = vec![false; w * h];
    let mut open: BinaryHeap<Reverse<(u32, u32)>> = BinaryHeap::new();
    let key = |v: f32| -> u32 {
        // Monotone map of f32 to u32 (total order for finite values).
        let b = v.to_bits();
        if b & 0x8000_0000 != 0 { !b } else { b | 0x8000_0000 }
    };
    for r in 0..h {
        for c in 0..w {
            let i = r * w + c;
            if m.data[i] && is_seed(m, c, r) {
                closed[i] = true;
                open.push(Reverse((key(z[i]), i as u32)));
            }
        }
    }
    let mut pit: VecDeque<u32> = VecDeque::new();
    loop {
        let ci = if let Some(p) = pit.pop_front() {
            p as usize
        } else if let Some(Reverse((_, i))) = open.pop() {
            i as usize
        } else {
            break;
        };
        let (c, r) = ((ci % w) as i64, (ci / w) as i64);
        let zc = z[ci];
        for (dc, dr) in D8 {
            let (nc, nr) = (c + dc, r + dr);
            if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                continue;
            }
            let ni = nr as usize * w + nc as usize;
            if closed[ni] || !m.data[ni] {
                continue;
            }
            closed[ni] = true;
            let up = next_up(zc);
            if z[ni] <= up {
                z[ni] = up;
                pit.push_back(ni as u32);
            } else {
                open.push(Reverse((key(z[ni]), ni as u32)));
            }
        }
    }
    Grid { width: w, height: h, data: z }
}

/// Outlet marker in a D8 direction grid.
pub const OUTLET: u8 = 255;

/// D8 flow directions (O'Callaghan & Mark 1984) on a filled DEM: index 0–7 into N, NE, E, SE,
/// S, SW, W, NW of the steepest strictly downhill neighbour (drop / distance, metres);
/// [`OUTLET`] where no valid neighbour is lower (outlets at the border or next to masked
/// cells) and for masked cells. Ties go to the first direction in that order.
pub fn flow_directions(filled: &Grid<f32>, geo: &GeoRef, m: &Grid<bool>) -> Grid<u8> {
    let (w, h) = (m.width, m.height);
    let mut dir = Grid::filled(w, h, OUTLET);
    let dy = geo.cell_y_m();
    dir.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dx = geo.cell_x_m_at_row(r);
        let dist: [f64; 8] = D8.map(|(dc, dr)| ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt());
        for c in 0..w {
            if !*m.get(c, r) {
                continue;
            }
            let z0 = *filled.get(c, r);
            let mut best = (0.0f64, OUTLET);
            for (k, (dc, dr)) in D8.iter().enumerate() {
                let (nc, nr) = (c as i64 + dc, r as i64 + dr);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 || !*m.get(nc as usize, nr as usize) {
                    continue;
                }
                let drop = (z0 - *filled.get(nc as usize, nr as usize)) as f64 / dist[k];
                if drop > best.0 {
                    best = (drop, k as u8);
                }
            }
            row[c] = best.1;
        }
    });
    dir
}

/// D8 flow accumulation (number of cells, including the cell itself, draining through each
/// cell), by a topological sweep (Kahn) over the direction grid. Masked cells hold 0.
/// Invariant: the sum over outlet cells equals the number of valid cells.
pub fn flow_accumulation(dir: &Grid<u8>, m: &Grid<bool>) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let n = w * h;
    let down = |i: usize| -> Option<usize> {
        let d = dir.data[i];
        if d == OUTLET {
            return None;
        }
        let (dc, dr) = D8[d as usize];
        Some(((i / w) as i64 + dr) as usize * w + ((i % w) as i64 + dc) as usize)
    };
    let mut indeg = vec![0u8; n];
    for i in 0..n {
        if m.data[i] {
            if let Some(j) = down(i) {
                indeg[j] += 1;
            }
        }
    }
    let mut acc: Vec<f64> = m.data.iter().map(|v| if *v { 1.0 } else { 0.0 }).collect();
    let mut stack: Vec<usize> = (0..n).filter(|&i| m.data[i] && indeg[i] == 0).collect();
    while let Some(i) = stack.pop() {
        if let Some(j) = down(i) {
            acc[j] += acc[i];
            indeg[j] -= 1;
            if indeg[j] == 0 {
                stack.push(j);
            }
        }
    }
    Grid { width: w, height: h, data: acc.into_iter().map(|v| v as f32).collect() }
}

/// Minimum tan β used in the TWI so that flat cells stay finite (≈ 0.057°).
pub const MIN_TAN_SLOPE: f64 = 0.001;

/// Topographic wetness index TWI = ln(a / tan β) (Beven & Kirkby 1979): `a` = upslope area per
/// unit contour width = accumulation · cell area / east–west cell width (m; D8, one cell width
/// of contour), β = Horn slope, tan β ≥ [`MIN_TAN_SLOPE`]. Dimensionless; NaN where masked.
pub fn twi(acc: &Grid<f32>, slope_deg: &Grid<f32>, geo: &GeoRef, m: &Grid<bool>) -> Grid<f32> {
    let (w, h) = (m.width, m.height);
    let mut out = Grid::filled(w, h, f32::NAN);
    let dy = geo.cell_y_m();
    out.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dx = geo.cell_x_m_at_row(r);
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

/// Sun positions above the horizon for latitude `lat_deg`: declination by Cooper (1969)
/// δ = 23.45° sin(360°(284+n)/365); hour angle 15°/h; clear-sky beam normal irradiance
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
        let decl = (23.45f64).to_radians() * (2.0 * std::f64::consts::PI * (284.0 + n) / 365.0).sin();
        let i0 = 1367.0 * (1.0 + 0.034 * (2.0 * std::f64::consts::PI * n / 365.0).cos());
        for s in 0..steps {
            let hour = (s as f64 + 0.5) * dt_h;
            let om = (15.0 * (hour - 12.0)).to_radians();
            let e = -decl.cos() * om.sin();
            let nn = decl.sin() * phi.cos() - decl.cos() * om.cos() * phi.sin();
            let u = decl.sin() * phi.sin() + decl.cos() * om.cos() * phi.cos();
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
/// (UTM-derived) latitude for UTM grids, else `climate_lat`.
pub fn row_latitude(geo: &GeoRef, r: usize, climate_lat: f64) -> f64 {
    match (geo.crs, geo.epsg) {
        (Crs::Geographic, _) => geo.row_latitude_deg(r),
        (Crs::Projected, Some(e)) if (32601..=32660).contains(&e) || (32701..=32760).contains(&e) => geo.latitude_deg,
        _ => climate_lat,
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

/// Annual clear-sky insolation with terrain shading (kWh/m²/yr) and wind exposure (0–1).
///
/// Horizons: for each cell, the tangent of the highest elevation angle of valid terrain along
/// 8 directions (N, NE, …, NW), marched at geometric distances (×1.5: 1, 2, 3, 5, 8, 11, 17, …) up to
/// `horizon_max_cells` cells and `horizon_max_m` metres; a direction that leaves the grid at
/// once takes the mean of the other directions (0 when none reaches terrain).
/// Insolation: Σ over sampled sun positions (see `sun_table`) of beam · max(0, n·s) where the
/// sun's altitude exceeds the horizon (interpolated between the two nearest directions), plus
/// diffuse · V, with sky view V = (1 + cos β)/2 · mean_k cos² H_k⁺ (Dozier & Frew 1990,
/// IEEE TGRS 28(5), eq. 7, for the horizon part). n from Horn's gradient.
/// Wind: a directional shelter index like TOPEX (Wilson 1984): x = 0.7·H_wind + 0.3·mean_k H_k
/// (degrees; H_wind interpolated toward `wind_from_deg`), exposure = clamp(0.5 − x/30°, 0, 1):
/// flat open ground 0.5, a 15°-sheltered hollow 0, a ridge 15° above its surroundings 1.
pub fn insolation_and_wind(t: &Terrain, m: &Grid<bool>, climate_lat: f64, wind_from_deg: f64, p: &SkyParams) -> (Grid<f32>, Grid<f32>) {
    let (w, h) = (m.width, m.height);
    let mut ins = Grid::filled(w, h, f32::NAN);
    let mut wind = Grid::filled(w, h, f32::NAN);
    let z = &t.elevation;
    let dy = t.geo.cell_y_m();
    let geographic = t.geo.crs == Crs::Geographic;
    let shared_sun = if geographic { Vec::new() } else { sun_table(row_latitude(&t.geo, 0, climate_lat), p) };
    let steps = horizon_steps(p.horizon_max_cells);
    let wsec = (wind_from_deg.rem_euclid(360.0)) / 45.0;
    let (wk, wf) = ((wsec.floor() as usize) % 8, wsec - wsec.floor());
    ins.data.par_chunks_mut(w).zip(wind.data.par_chunks_mut(w)).enumerate().for_each(|(r, (irow, wrow))| {
        let own_sun;
        let suns: &[Sun] = if geographic {
            own_sun = sun_table(row_latitude(&t.geo, r, climate_lat), p);
            &own_sun
        } else {
            &shared_sun
        };
        let dx = t.geo.cell_x_m_at_row(r);
        // (dc, dr, inverse distance per step) and the usable steps for each direction.
        let dirs: Vec<(i64, i64, f64, usize)> = D8
            .iter()
            .map(|&(dc, dr)| {
                let d1 = ((dc as f64 * dx).powi(2) + (dr as f64 * dy).powi(2)).sqrt();
                let n = steps.iter().take_while(|&&s| s as f64 * d1 <= p.horizon_max_m).count();
                (dc, dr, 1.0 / d1, n)
            })
            .collect();
        for c in 0..w {
            if !*m.get(c, r) {
                continue;
            }
            let z0 = *z.get(c, r);
            let mut hz = [0f64; 8];
            for (k, &(dc, dr, inv, n)) in dirs.iter().enumerate() {
                let mut best = f64::NEG_INFINITY;
                for &s in &steps[..n] {
                    let (cc, rr) = (c as i64 + dc * s as i64, r as i64 + dr * s as i64);
                    if cc < 0 || rr < 0 || cc >= w as i64 || rr >= h as i64 {
                        break;
                    }
                    let zz = z.data[rr as usize * w + cc as usize];
                    if zz.is_finite() {
                        let tn = (zz - z0) as f64 * inv / s as f64;
                        if tn > best {
                            best = tn;
                        }
                    }
                }
                hz[k] = best;
            }
            // Directions that leave the grid at once (border cells) take the mean of the others.
            let known: Vec<f64> = hz.iter().copied().filter(|v| v.is_finite()).collect();
            let fill = if known.is_empty() { 0.0 } else { known.iter().sum::<f64>() / known.len() as f64 };
            for v in &mut hz {
                if !v.is_finite() {
                    *v = fill;
                }
            }
            let (gx, gy) = horn_gradient(&window3(z, m, c, r), dx, dy);
            let nl = (gx * gx + gy * gy + 1.0).sqrt();
            let nv = [-gx / nl, -gy / nl, 1.0 / nl];
            let mut beam = 0.0;
            let mut diffuse = 0.0;
            for s in suns {
                diffuse += s.diffuse_wh;
                let ci = nv[0] * s.v[0] + nv[1] * s.v[1] + nv[2] * s.v[2];
                if ci <= 0.0 {
                    continue;
                }
                let hzs = hz[s.sector] * (1.0 - s.frac) + hz[(s.sector + 1) % 8] * s.frac;
                if s.tan_alt > hzs {
                    beam += s.beam_wh * ci;
                }
            }
            let horizon_v: f64 = hz.iter().map(|&tn| 1.0 / (1.0 + tn.max(0.0) * tn.max(0.0))).sum::<f64>() / 8.0;
            let svf = (1.0 + nv[2]) / 2.0 * horizon_v;
            irow[c] = ((beam + diffuse * svf) / 1000.0) as f32;
            let ang = hz.map(|tn| tn.atan().to_degrees());
            let h_wind = ang[wk] * (1.0 - wf) + ang[(wk + 1) % 8] * wf;
            let mean = ang.iter().sum::<f64>() / 8.0;
            let x = 0.7 * h_wind + 0.3 * mean;
            wrow[c] = (0.5 - x / 30.0).clamp(0.0, 1.0) as f32;
        }
    });
    (ins, wind)
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
    out.data.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let dx = t.geo.cell_x_m_at_row(r);
        for c in 0..w {
            if *m.get(c, r) {
                let (gx, gy) = horn_gradient(&window3(&t.elevation, m, c, r), dx, dy);
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
    progress("slope and aspect");
    let (slope_deg, aspect_deg) = slope_aspect(t, &m);
    progress("depression filling");
    let filled_m = fill_depressions(t, &m);
    progress("flow accumulation");
    let dir = flow_directions(&filled_m, &t.geo, &m);
    let flow_acc_cells = flow_accumulation(&dir, &m);
    let twi = twi(&flow_acc_cells, &slope_deg, &t.geo, &m);
    progress("insolation and wind exposure");
    let p = SkyParams::default();
    let (insolation_kwh_m2, wind_exposure) = insolation_and_wind(t, &m, climate.latitude_deg, climate.wind_from_deg as f64, &p);
    let flat_insolation_kwh_m2 = flat_insolation(row_latitude(&t.geo, m.height / 2, climate.latitude_deg), &p);
    progress("temperature");
    let temperature_c = temperature(t, &m, climate);
    Ok(Fields { mask: m, slope_deg, aspect_deg, filled_m, flow_acc_cells, twi, insolation_kwh_m2, flat_insolation_kwh_m2, wind_exposure, temperature_c })
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
        // the centre was raised to (just above) the lowest border cell
        let rim = (0..n).map(|c| *t.elevation.get(c, 0)).fold(f32::INFINITY, f32::min);
        assert!(*f.get(15, 15) > rim && *f.get(15, 15) < rim + 0.1);
    }

    #[test]
    fn pit_is_filled() {
        let mut t = terrain(9, 9, 10.0, |x, _| (100.0 + 0.1 * x) as f32);
        *t.elevation.get_mut(4, 4) = 50.0;
        let m = mask(&t, 0.0);
        let f = fill_depressions(&t, &m);
        let lowest_nb = [(3, 3), (4, 3), (5, 3), (3, 4), (5, 4), (3, 5), (4, 5), (5, 5)].iter().map(|&(c, r)| *t.elevation.get(c, r)).fold(f32::INFINITY, f32::min);
        assert!(*f.get(4, 4) > lowest_nb && *f.get(4, 4) < lowest_nb + 1e-3, "filled {}", f.get(4, 4));
        let d = flow_directions(&f, &t.geo, &m);
        assert_ne!(d.get(4, 4), &OUTLET);
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
    fn temperature_lapse() {
        let t = terrain(3, 3, 10.0, |x, _| (300.0 + 50.0 * x) as f32);
        let c = Climate::default();
        let tt = temperature(&t, &mask(&t, 0.0), &c);
        assert!((tt.get(2, 0) - (9.0 - 6.5 * 1.0)).abs() < 1e-4);
    }
}
