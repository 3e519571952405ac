//! A virtual hemispherical photograph (issue 32 item 4; `sylva render RUN --year Y --camera
//! hemi:X,Y --out hemi.png --stats s.json`): the upward fisheye view that ecologists take under
//! a canopy to measure its gaps, made from a snapshot's inventory.
//!
//! **What it sees.** The crowns as the simulation's light model has them (`sim::phases::light`):
//! each live tree's crown a vertical cylinder of its crown radius from its crown base to its top,
//! holding its leaf area `LA = π r² · LAI_crown` spread evenly (leaf area density
//! `LAD = LAI_crown / crown length`, m² m⁻³), a ray through it transmitting
//! `exp(−k · LAD · path)` (Beer–Lambert with the light model's `k = 0.5`, so a vertical ray through
//! a crown transmits `exp(−k · LAI_crown)` as in the light grid); stems opaque cylinders of their
//! DBH up to the crown base; the terrain's horizon from the elevation model (720 azimuths,
//! marched to 1.5 km). A pixel is sky when a hash of the pixel falls below the transmission of
//! its ray (so a translucent crown shows as speckled light, as in a photograph), else canopy.
//!
//! **Projection.** Equisolid (equal-area) fisheye, `r = R · sin(θ/2) / sin(45°)` for zenith angle
//! θ, the horizon at the image circle's edge: every pixel in the circle spans the same solid
//! angle, so the share of sky pixels is the gap fraction of the sky hemisphere. As a photograph
//! taken looking up: north at the top, east on the left.
//!
//! **Figures.** `gap_fraction` (sky pixels in the circle), `openness` (the expected value: the
//! mean transmission over the circle, without the dithering), `diffuse_site_factor` (the
//! transmission weighted by the standard overcast sky's irradiance on a horizontal surface, the
//! figure to hold against `simulated_diffuse`, the light phase's diffuse part as the run's
//! `[light] diffuse` takes it) and `simulated_light`: the light
//! phase's relative light (0–1.5) at that place and 1.3 m, from the same snapshot's trees (the
//! crowns stamped on the scenario's light cells, `LAI_above` and the zenith/sun mix of
//! `sim::phases::light`, times the place's relative insolation; the scenario's obstacles are
//! left out of this figure, though the picture shows them: they are opaque to the rays).

use super::Result;
use crate::conditions::SiteConditions;
use crate::error::Error;
use crate::job::inventory::InventoryRow;
use crate::sim::phases::light::{crown_lai, K_EXT, W_ZENITH};
use crate::sim::Scenario;
use crate::species::SpeciesLibrary;
use image::RgbImage;
use rayon::prelude::*;
use std::path::Path;

/// Height of the camera above the ground (m): the usual height of hemispherical photographs
/// (breast height).
pub const CAMERA_HEIGHT_M: f32 = 1.3;

/// Trees farther than this from the camera (m, horizontally) are left out: a 40 m tree at 300 m
/// stands 7° above the horizon.
pub const VIEW_RADIUS_M: f64 = 300.0;

/// Side of the grid cells that hold the crowns for the rays (m).
const GRID_M: f32 = 5.0;

/// What to photograph.
#[derive(Debug, Clone, PartialEq)]
pub struct HemiOptions {
    /// Snapshot year; `None`: the last one.
    pub year: Option<u32>,
    /// Place (m, world coordinates as the inventory's `x_m`, `y_m`).
    pub x_m: f64,
    /// Place (m).
    pub y_m: f64,
    /// Image side (pixels, 64–8192); the circle fills it.
    pub size_px: u32,
}

/// The figures of a hemispherical photograph (`--stats`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HemiStats {
    /// Snapshot year.
    pub year: u32,
    /// Camera position (m, world coordinates; z: ground elevation + [`CAMERA_HEIGHT_M`]).
    pub camera_m: [f64; 3],
    /// Share of the pixels in the image circle that show sky (0–1).
    pub gap_fraction: f64,
    /// Mean transmission of the rays in the circle (0–1): the gap fraction's expected value.
    pub openness: f64,
    /// Indirect (diffuse) site factor (0–1): the rays' transmission weighted by the standard
    /// overcast sky's irradiance on a horizontal surface, `L(θ) cos θ` with `L ∝ (1 + 2 cos θ)`
    /// (Moon & Spencer 1942), as hemispherical-photograph software gives it (Rich 1990; Frazer
    /// et al. 1999, Gap Light Analyzer). The figure to compare with `simulated_diffuse`: the gap
    /// fraction and openness weight every solid angle alike, the horizon as much as the zenith.
    pub diffuse_site_factor: f64,
    /// The light phase's relative light at the place, 1.3 m above the ground (0–1.5).
    pub simulated_light: f64,
    /// The light phase's diffuse part at the place, 1.3 m above the ground (0–1, before the
    /// relative insolation): its transmission as the run's `[light] diffuse` takes it.
    pub simulated_diffuse: f64,
    /// The run's `[light] diffuse` (`column` or `sky`).
    pub diffuse: crate::sim::light_grid::Diffuse,
    /// Trees within [`VIEW_RADIUS_M`].
    pub trees: usize,
    /// Projection of the image.
    pub projection: &'static str,
}

/// One crown (and stem) for the rays, relative to the camera (m).
#[derive(Debug, Clone, Copy)]
struct Crown {
    x: f32,
    y: f32,
    r: f32,
    base: f32,
    top: f32,
    /// k · LAD (1/m): optical depth per metre of path.
    kd: f32,
    stem_r: f32,
    ground: f32,
}

fn invalid(field: &str, value: String, expected: String) -> super::JobError {
    Error::Invalid { context: "sylva render --camera hemi".into(), field: field.into(), value, expected }.into()
}

/// Parses `hemi:X,Y` (m) into the place; `None` when `s` does not start with `hemi:`.
///
/// Errors: [`Error::Invalid`] naming `--camera` for anything but two finite numbers after it.
pub fn parse_hemi(s: &str) -> Option<Result<(f64, f64)>> {
    let rest = s.strip_prefix("hemi:")?;
    let v: Vec<f64> = rest.split(',').map(|p| p.trim().parse::<f64>().unwrap_or(f64::NAN)).collect();
    Some(if v.len() == 2 && v.iter().all(|x| x.is_finite()) { Ok((v[0], v[1])) } else { Err(invalid("--camera", s.into(), "hemi:X,Y with X, Y the place in metres (world coordinates, as the inventory's x_m, y_m), e.g. hemi:600,450".into())) })
}

/// Takes the photograph (module documentation) of a run's snapshot.
///
/// Errors: [`Error::Format`] / [`Error::Io`] when the run or snapshot cannot be read;
/// [`Error::Invalid`] naming `--camera` for a place outside the site, on a masked cell
/// (no-data or sea: [`crate::conditions::SiteConditions::unmasked_cell`]) or inside an obstacle,
/// naming `--size` for a side outside 64–8192.
pub fn hemispherical_photo(run_dir: &Path, library: &SpeciesLibrary, o: &HemiOptions) -> Result<(RgbImage, HemiStats)> {
    if !(64..=8192).contains(&o.size_px) {
        return Err(invalid("--size", o.size_px.to_string(), "an image side of 64–8192 pixels (the circle fills a square)".into()));
    }
    let sc = Scenario::load(&run_dir.join("scenario.toml"))?;
    let site = sc.site()?;
    let (w, h) = (site.width() as f64 * site.cell_x_m, site.height() as f64 * site.cell_y_m);
    let place = format!("hemi:{},{}", o.x_m, o.y_m);
    if !(o.x_m >= 0.0 && o.y_m >= 0.0 && o.x_m < w && o.y_m < h) || !site.elevation_at(o.x_m, o.y_m).is_finite() {
        return Err(invalid("--camera", place, format!("a place on the site: 0 ≤ X < {w:.1} m east, 0 ≤ Y < {h:.1} m north, on valid terrain")));
    }
    // a no-data (or sea) cell is refused as a place off the site is (round 33's trial: a photo
    // was taken from the bottom of a hole filled with elevation 0, about 300 m down)
    if site.unmasked_cell(o.x_m, o.y_m).is_none() {
        return Err(invalid("--camera", place, format!("a place on valid terrain: the cell there is no-data (a hole in the DEM) or at or below sea level, where the site holds no terrain or trees; the site spans 0 ≤ X < {w:.1} m east, 0 ≤ Y < {h:.1} m north")));
    }
    let ground = site.elevation_at(o.x_m, o.y_m);
    let eye_h = ground + CAMERA_HEIGHT_M;
    for ob in &sc.obstacles {
        if ob.solid_at_ground(o.x_m, o.y_m) && ob.top_at(o.x_m, o.y_m).is_some_and(|t| t >= CAMERA_HEIGHT_M as f64) {
            return Err(invalid("--camera", place, format!("a place outside the obstacles (it is inside the {})", ob.kind())));
        }
    }
    let year = match o.year {
        Some(y) => y,
        None => super::inventory::snapshots(run_dir)?.iter().map(|s| s.0).max().ok_or_else(|| Error::format(run_dir, "no inventory snapshots (inventory/year_NNNN.parquet or .csv)"))?,
    };
    let r2 = VIEW_RADIUS_M * VIEW_RADIUS_M;
    let mut unknown = 0usize;
    let rows = super::pictures::snapshot_rows_where(run_dir, year, |r| {
        let near = r.status == "alive" && (r.x_m - o.x_m).powi(2) + (r.y_m - o.y_m).powi(2) < r2 && r.height_m > 0.0 && r.crown_radius_m > 0.0;
        let known = library.find(&r.species).is_some();
        unknown += (near && !known) as usize;
        near && known
    })?;
    if unknown > 0 {
        tracing::warn!("{unknown} trees within {VIEW_RADIUS_M} m are of species not in the library and are left out of the photograph (give their species files with --species-dir)");
    }
    let crowns: Vec<Crown> = rows
        .iter()
        .filter_map(|r| {
            let sp = &library.species[library.find(&r.species)? as usize];
            let g = site.elevation_at(r.x_m, r.y_m);
            let g = if g.is_finite() { g } else { ground };
            let base = r.crown_base_m.clamp(0.0, 0.95 * r.height_m);
            let len = (r.height_m - base).max(0.1);
            let kd = K_EXT * crown_lai(sp.life.shade_tolerance) / len;
            Some(Crown { x: (r.x_m - o.x_m) as f32, y: (r.y_m - o.y_m) as f32, r: r.crown_radius_m, base: g + base - eye_h, top: g + r.height_m - eye_h, kd, stem_r: (r.dbh_cm / 200.0).max(0.0), ground: g - eye_h })
        })
        .collect();
    // obstacles relative to the camera
    let eye = glam::Vec3::new(o.x_m as f32, o.y_m as f32, eye_h);
    let grid = CrownGrid::new(&crowns, super::adapted::solids(&sc.obstacles, &site), eye);
    let horizon = horizon_angles(&site, o.x_m, o.y_m, eye_h);
    let n = o.size_px as usize;
    let half = n as f32 * 0.5;
    let sky_top = [232u8, 240, 250];
    // rows of pixels in parallel; each pixel's colour and (in circle, sky, transmission)
    let px: Vec<(Vec<[u8; 3]>, u64, u64, f64, [f64; 2])> = (0..n)
        .into_par_iter()
        .map(|j| {
            let mut line = vec![[0u8; 3]; n];
            let (mut inside, mut sky, mut trans) = (0u64, 0u64, 0.0f64);
            let mut soc = [0.0f64; 2]; // Σ w·t, Σ w under the standard overcast sky
            for (i, c) in line.iter_mut().enumerate() {
                // image x to the right = west (looking up, east is on the left), y down = south
                let (u, v) = ((i as f32 + 0.5 - half) / half, (j as f32 + 0.5 - half) / half);
                let rho = (u * u + v * v).sqrt();
                if rho > 1.0 {
                    continue;
                }
                inside += 1;
                // equisolid: rho = sin(θ/2) / sin(45°)
                let theta = 2.0 * (rho * std::f32::consts::FRAC_1_SQRT_2).min(1.0).asin();
                let (east, north) = if rho > 0.0 { (-u / rho, -v / rho) } else { (0.0, 1.0) };
                let (st, ct) = theta.sin_cos();
                let d = [st * east, st * north, ct];
                let t = transmission(&grid, &crowns, &horizon, d);
                trans += t as f64;
                // each pixel spans the same solid angle: weight L(θ) cos θ ∝ (1 + 2 cos θ) cos θ
                let w = ((1.0 + 2.0 * ct) * ct).max(0.0) as f64;
                soc[0] += w * t as f64;
                soc[1] += w;
                let hsh = crate::rng::hash(&[i as u64, j as u64, 0x6865_6d69]);
                let lit = ((hsh >> 11) as f64 / (1u64 << 53) as f64) < t as f64;
                if lit {
                    sky += 1;
                    // brighter towards the zenith, as under an overcast sky
                    let f = 0.85 + 0.15 * ct;
                    *c = sky_top.map(|x| (x as f32 * f) as u8);
                } else {
                    // canopy: dark, the farther the darker
                    *c = [34, 44, 30];
                }
            }
            (line, inside, sky, trans, soc)
        })
        .collect();
    let mut img = RgbImage::new(o.size_px, o.size_px);
    let (mut inside, mut sky, mut trans) = (0u64, 0u64, 0.0f64);
    let mut soc = [0.0f64; 2];
    for (j, (line, a, b, t, w)) in px.into_iter().enumerate() {
        for (i, c) in line.into_iter().enumerate() {
            img.put_pixel(i as u32, j as u32, image::Rgb(c));
        }
        inside += a;
        sky += b;
        trans += t;
        soc = [soc[0] + w[0], soc[1] + w[1]];
    }
    let (simulated_light, simulated_diffuse) = simulated_light(&site, &sc, library, &rows, o.x_m, o.y_m);
    let stats = HemiStats {
        year,
        camera_m: [o.x_m, o.y_m, eye_h as f64],
        gap_fraction: sky as f64 / inside.max(1) as f64,
        openness: trans / inside.max(1) as f64,
        diffuse_site_factor: soc[0] / soc[1].max(1e-12),
        simulated_light: simulated_light as f64,
        simulated_diffuse: simulated_diffuse as f64,
        diffuse: sc.light.diffuse,
        trees: crowns.len(), projection: "equisolid, north up, east left (looking up)" };
    Ok((img, stats))
}

/// The crowns binned on a grid of [`GRID_M`] cells round the camera, each crown in every cell its
/// disc reaches.
struct CrownGrid {
    n: usize,
    half: f32,
    /// The highest crown top above the camera (m, at least 0).
    top: f32,
    /// The scenario's obstacles as solids (world coordinates, m) and the camera among them.
    solids: Vec<crate::obstacle::Obstacle>,
    eye: glam::Vec3,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CrownGrid {
    fn new(crowns: &[Crown], solids: Vec<crate::obstacle::Obstacle>, eye: glam::Vec3) -> CrownGrid {
        let half = VIEW_RADIUS_M as f32 + 20.0;
        let n = (2.0 * half / GRID_M).ceil() as usize;
        let cell = |v: f32| (((v + half) / GRID_M).floor().max(0.0) as usize).min(n - 1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n * n];
        for (k, c) in crowns.iter().enumerate() {
            let r = c.r.max(c.stem_r);
            for y in cell(c.y - r)..=cell(c.y + r) {
                for x in cell(c.x - r)..=cell(c.x + r) {
                    lists[y * n + x].push(k as u32);
                }
            }
        }
        let mut start = Vec::with_capacity(n * n + 1);
        let mut items = Vec::new();
        for l in lists {
            start.push(items.len() as u32);
            items.extend(l);
        }
        start.push(items.len() as u32);
        let top = crowns.iter().map(|c| c.top).fold(0.0f32, f32::max);
        CrownGrid { n, half, top, solids, eye, start, items }
    }
}

/// Transmission (0–1) of the ray from the camera (the origin) in unit direction `d` (x east,
/// y north, z up): 0 below the terrain's horizon or through a stem, else
/// `exp(−Σ k · LAD · path)` over the crowns it crosses. The ray's ground track is walked cell by
/// cell of the crown grid, each crown's path counted only within the cell's stretch of the ray
/// (so a crown in several cells is counted once).
fn transmission(grid: &CrownGrid, crowns: &[Crown], horizon: &[f32], d: [f32; 3]) -> f32 {
    let az = d[0].atan2(d[1]).rem_euclid(std::f32::consts::TAU);
    let elev = d[2].clamp(-1.0, 1.0).asin();
    if elev <= horizon[((az / std::f32::consts::TAU * horizon.len() as f32) as usize).min(horizon.len() - 1)] {
        return 0.0;
    }
    // the scenario's obstacles: opaque
    if grid.solids.iter().any(|o| o.ray_hits(grid.eye, glam::Vec3::from(d), f32::INFINITY)) {
        return 0.0;
    }
    let hor = (d[0] * d[0] + d[1] * d[1]).sqrt();
    // ray parameter t (m along d); the ground track leaves the grid at t_max, the canopy above
    // the highest crown
    let top = grid.top;
    let t_top = if d[2] > 1e-6 { top / d[2] } else { f32::INFINITY };
    let t_max = if hor > 1e-6 { (grid.half - GRID_M) / hor } else { f32::INFINITY }.min(t_top);
    let mut depth = 0.0f32;
    // DDA over the grid cells of the ground track
    let cell_of = |v: f32| ((v + grid.half) / GRID_M).floor() as isize;
    let (mut cx, mut cy) = (cell_of(0.0), cell_of(0.0));
    let step = |dv: f32| if dv > 0.0 { 1isize } else { -1 };
    let (sx, sy) = (step(d[0]), step(d[1]));
    let next = |c: isize, s: isize, dv: f32| {
        if dv.abs() < 1e-9 {
            return f32::INFINITY;
        }
        let edge = (c + if s > 0 { 1 } else { 0 }) as f32 * GRID_M - grid.half;
        edge / dv
    };
    let (mut tx, mut ty) = (next(cx, sx, d[0]), next(cy, sy, d[1]));
    let (dtx, dty) = (if d[0].abs() < 1e-9 { f32::INFINITY } else { GRID_M / d[0].abs() }, if d[1].abs() < 1e-9 { f32::INFINITY } else { GRID_M / d[1].abs() });
    let mut t0 = 0.0f32;
    loop {
        let t1 = tx.min(ty).min(t_max);
        if cx < 0 || cy < 0 || cx as usize >= grid.n || cy as usize >= grid.n {
            break;
        }
        let c = cy as usize * grid.n + cx as usize;
        for &k in &grid.items[grid.start[c] as usize..grid.start[c + 1] as usize] {
            let cr = &crowns[k as usize];
            // stem: opaque
            if let Some((a, b)) = cylinder_span(cr.x, cr.y, cr.stem_r, cr.ground, cr.base, d) {
                if a.max(t0) < b.min(t1) {
                    return 0.0;
                }
            }
            if let Some((a, b)) = cylinder_span(cr.x, cr.y, cr.r, cr.base, cr.top, d) {
                let path = b.min(t1) - a.max(t0);
                if path > 0.0 {
                    depth += cr.kd * path;
                }
            }
        }
        if depth > 12.0 {
            return 0.0;
        }
        if t1 >= t_max {
            break;
        }
        t0 = t1;
        if tx < ty {
            cx += sx;
            tx += dtx;
        } else {
            cy += sy;
            ty += dty;
        }
    }
    (-depth).exp()
}

/// The span `(t_in, t_out)` (t ≥ 0) of the ray from the origin along `d` inside the vertical
/// cylinder of radius `r` round `(x, y)` between heights `z0` and `z1`; `None` when it misses.
fn cylinder_span(x: f32, y: f32, r: f32, z0: f32, z1: f32, d: [f32; 3]) -> Option<(f32, f32)> {
    if r <= 0.0 || z1 <= z0 {
        return None;
    }
    // horizontal: |t·(dx, dy) − (x, y)|² ≤ r²
    let a = d[0] * d[0] + d[1] * d[1];
    let (mut lo, mut hi) = if a < 1e-12 {
        if x * x + y * y > r * r {
            return None;
        }
        (0.0f32, f32::INFINITY)
    } else {
        let b = d[0] * x + d[1] * y;
        let c = x * x + y * y - r * r;
        let disc = b * b - a * c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        ((b - s) / a, (b + s) / a)
    };
    // vertical: z0 ≤ t·dz ≤ z1
    if d[2].abs() < 1e-9 {
        if !(z0 <= 0.0 && 0.0 <= z1) {
            return None;
        }
    } else {
        let (a, b) = (z0 / d[2], z1 / d[2]);
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        lo = lo.max(a);
        hi = hi.min(b);
    }
    lo = lo.max(0.0);
    (lo < hi).then_some((lo, hi))
}

/// Elevation angle (rad) of the terrain's horizon seen from `(x, y)` at height `eye` (m) in 720
/// azimuth bins (clockwise from north), marched outwards to 1.5 km at the elevation model's cell
/// size; at least 0 (the camera's own ground plane).
fn horizon_angles(site: &SiteConditions, x: f64, y: f64, eye: f32) -> Vec<f32> {
    let step = site.cell_x_m.min(site.cell_y_m).max(1.0);
    (0..720)
        .into_par_iter()
        .map(|k| {
            let az = (k as f64 + 0.5) / 720.0 * std::f64::consts::TAU;
            let (dx, dy) = (az.sin(), az.cos());
            let mut best = 0.0f32;
            let mut s = step;
            while s <= 1500.0 {
                let z = site.elevation_at(x + dx * s, y + dy * s);
                if z.is_finite() {
                    best = best.max(((z - eye) as f64 / s).atan() as f32);
                }
                s += step;
            }
            best
        })
        .collect()
}

/// The light phase's relative light (`sim::phases::light`, 0–1.5) at `(x, y)`, 1.3 m above the
/// ground, and its diffuse part's transmission (0–1), from the trees `rows`: the light phase's
/// own formula (`light::light_parts_at`: the crowns stamped on the scenario's light cells, the
/// diffuse part as the scenario's `[light] diffuse` takes it, the column above the place's cell
/// or the sky's sectors through the crowns with their depth, the direct part from `LAI_above` in
/// the place's cell and in the cell towards the equator at the sun's rise), times the place's
/// relative insolation (the site's insolation over its median, 0.2–1.5).
fn simulated_light(site: &SiteConditions, sc: &Scenario, library: &SpeciesLibrary, rows: &[InventoryRow], x: f64, y: f64) -> (f32, f32) {
    let cell = sc.light_cell_m;
    let (col, row) = ((x / cell).floor(), (y / cell).floor());
    let z = CAMERA_HEIGHT_M;
    let light = crate::sim::light_grid::LightGrid::new(site.extent_m(), cell).with_diffuse(sc.light.diffuse);
    let mut trees = crate::sim::trees::TreeStore::default();
    for r in rows {
        let Some(s) = library.find(&r.species) else { continue };
        trees.push(crate::sim::trees::NewTree { species: s, x: r.x_m as f32, y: r.y_m as f32, z: r.z_m as f32, age: r.age_yr, height: r.height_m, dbh: r.dbh_cm, crown_radius: r.crown_radius_m, suitability: 1.0 });
        *trees.crown_base.last_mut().expect("pushed") = r.crown_base_m;
    }
    let (c, rw) = ((col.max(0.0) as usize).min(light.cols - 1), (row.max(0.0) as usize).min(light.rows - 1));
    let window = crate::sim::light_grid::CellRect { col0: c, row0: rw, col1: c + 1, row1: rw + 1 };
    let (diffuse, direct) = crate::sim::phases::light::light_parts_at(&trees, &light, site.geo.latitude_deg, library, &[], Some(window), z)[0];
    let ins = &site.insolation_kwh_m2;
    let mut vals: Vec<f32> = ins.data.iter().copied().filter(|v| v.is_finite()).collect();
    let median = if vals.is_empty() {
        1.0
    } else {
        let m = vals.len() / 2;
        *vals.select_nth_unstable_by(m, f32::total_cmp).1
    };
    // the light cell's centre, as the light phase takes it
    let here = site.cell_at((col + 0.5) * cell, (row + 0.5) * cell).map_or(median, |(c, r)| *ins.get(c, r));
    let rel = if here.is_finite() && median > 0.0 { (here / median).clamp(0.2, 1.5) } else { 1.0 };
    (rel * (W_ZENITH * diffuse + (1.0 - W_ZENITH) * direct), diffuse)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_spans_are_the_chords() {
        // straight up inside a crown from 2 to 10 m above the eye: the span is 2–10 m
        let s = cylinder_span(0.0, 0.0, 3.0, 2.0, 10.0, [0.0, 0.0, 1.0]).unwrap();
        assert!((s.0 - 2.0).abs() < 1e-5 && (s.1 - 10.0).abs() < 1e-5, "{s:?}");
        // horizontally through a crown of radius 1 at 5 m east, at the eye's height
        let s = cylinder_span(5.0, 0.0, 1.0, -1.0, 1.0, [1.0, 0.0, 0.0]).unwrap();
        assert!((s.0 - 4.0).abs() < 1e-5 && (s.1 - 6.0).abs() < 1e-5, "{s:?}");
        // behind the camera, or above it at a low angle: missed
        assert!(cylinder_span(-5.0, 0.0, 1.0, -1.0, 1.0, [1.0, 0.0, 0.0]).is_none());
        assert!(cylinder_span(5.0, 0.0, 1.0, 10.0, 20.0, [1.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn a_crown_overhead_transmits_by_beer_lambert() {
        // one crown of LAI 4.5 overhead (k·LAD over its 8 m length): exp(−0.5 · 4.5) straight up
        let lai = 4.5;
        let c = Crown { x: 0.5, y: 0.0, r: 4.0, base: 4.0, top: 12.0, kd: K_EXT * lai / 8.0, stem_r: 0.2, ground: -1.3 };
        let grid = CrownGrid::new(&[c], Vec::new(), glam::Vec3::ZERO);
        let flat = vec![0.0f32; 720];
        let t = transmission(&grid, &[c], &flat, [0.0, 0.0, 1.0]);
        assert!((t - (-K_EXT * lai).exp()).abs() < 1e-4, "{t}");
        // a ray that leaves the crown through its side crosses less of it (away from the stem
        // at x = 0.5 m, which a ray towards +x would hit)
        let d = [-(0.6f32.sin()), 0.0, 0.6f32.cos()];
        let t2 = transmission(&grid, &[c], &flat, d);
        assert!(t2 > t && t2 < 1.0, "{t2}");
        // a low ray beside it sees the sky; one into the stem is dark; below the horizon dark
        assert_eq!(transmission(&grid, &[c], &flat, [0.0, 0.995, 0.0998]), 1.0);
        let stem = Crown { x: 3.0, y: 0.0, r: 0.0, base: 5.0, top: 5.0, kd: 0.0, stem_r: 0.3, ground: -1.3 };
        let g2 = CrownGrid::new(&[stem], Vec::new(), glam::Vec3::ZERO);
        assert_eq!(transmission(&g2, &[stem], &flat, [0.995, 0.0, 0.0998]), 0.0);
        let high = vec![0.3f32; 720];
        assert_eq!(transmission(&grid, &[c], &high, [0.0, 0.995, 0.0998]), 0.0);
        // an obstacle (a 10 m box 2 m north of a camera at (100, 100, 1.3)) is opaque; the sky
        // beside it is not
        let eye = glam::Vec3::new(100.0, 100.0, 1.3);
        let wall = crate::obstacle::Obstacle::Box { min: glam::Vec3::new(95.0, 102.0, 0.0), max: glam::Vec3::new(105.0, 104.0, 10.0) };
        let g3 = CrownGrid::new(&[], vec![wall], eye);
        assert_eq!(transmission(&g3, &[], &flat, [0.0, 0.8, 0.6]), 0.0);
        assert_eq!(transmission(&g3, &[], &flat, [0.0, -0.8, 0.6]), 1.0);
    }
}
