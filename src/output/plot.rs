//! Plots (plotters, DejaVu Sans registered from `assets/fonts/`) and raster maps (PNG).

use super::{OutputError, Result};
use crate::error::Error;
use crate::sim::stats::StandRow;
use crate::sim::World;
use plotters::prelude::*;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn register() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// A line (or marker) series of a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Draw markers instead of a line.
    pub markers: bool,
}

/// One chart of a figure.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
}

fn perr(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::format(path, format!("plot: {e}"))
}

/// Draws `panels` in a grid of `cols` columns into a PNG of `size` pixels.
pub fn plot_panels_png(path: &Path, panels: &[Panel], cols: usize, size: (u32, u32)) -> Result<()> {
    register();
    let (w, h) = size;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| perr(path, e))?;
        let rows = panels.len().div_ceil(cols.max(1));
        let areas = root.split_evenly((rows.max(1), cols.max(1)));
        for (p, area) in panels.iter().zip(areas.iter()) {
            let pts = p.series.iter().flat_map(|s| s.points.iter()).filter(|q| q.0.is_finite() && q.1.is_finite());
            let (mut x0, mut x1, mut y1) = (f64::MAX, f64::MIN, 0f64);
            for q in pts {
                x0 = x0.min(q.0);
                x1 = x1.max(q.0);
                y1 = y1.max(q.1);
            }
            if x0 >= x1 {
                x0 = 0.0;
                x1 = x0 + 1.0;
            }
            let y1 = if y1 <= 0.0 { 1.0 } else { y1 * 1.08 };
            // the legend goes where it hides no data (round 30's trial: top left, it hid the
            // seed trees' QMD and beech's share of the first years)
            let (aw, ah) = area.dim_in_pixel();
            let plot_px = (aw as f64 - 16.0 - 56.0, ah as f64 - 16.0 - 36.0 - 26.0);
            let labels: Vec<&str> = p.series.iter().map(|s| s.name.as_str()).collect();
            let all: Vec<(f64, f64)> = p.series.iter().flat_map(|s| s.points.iter().copied()).filter(|q| q.0.is_finite() && q.1.is_finite()).collect();
            let (corner, y1) = legend_place(&all, &labels, (x0, x1), y1, plot_px);
            let mut ch = ChartBuilder::on(area)
                .caption(&p.title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d(x0..x1, 0f64..y1)
                .map_err(|e| perr(path, e))?;
            let mut mesh = ch.configure_mesh();
            mesh.x_desc(&p.x_label).y_desc(&p.y_label).label_style(("sans-serif", 13));
            let year_fmt = |v: &f64| format!("{v:.0}");
            // the y labels with as many decimals as the axis' range needs ("3500", not "3500.0";
            // found by a trial)
            let y_fmt = move |v: &f64| axis_label(*v, y1);
            mesh.y_label_formatter(&y_fmt);
            if p.x_label == "year" {
                // whole years only: at most one tick per year, integer labels
                mesh.x_labels(((x1 - x0).round() as usize + 1).clamp(2, 11)).x_label_formatter(&year_fmt);
            }
            mesh.draw().map_err(|e| perr(path, e))?;
            for s in &p.series {
                let c = RGBColor(s.color[0], s.color[1], s.color[2]);
                if s.markers {
                    ch.draw_series(s.points.iter().map(|&q| Circle::new(q, 3, c.filled()))).map_err(|e| perr(path, e))?.label(&s.name).legend(move |(x, y)| Circle::new((x + 8, y), 3, c.filled()));
                } else {
                    ch.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2))).map_err(|e| perr(path, e))?.label(&s.name).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
                }
            }
            ch.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).label_font(("sans-serif", 12)).position(corner.position()).draw().map_err(|e| perr(path, e))?;
        }
        root.present().map_err(|e| perr(path, e))?;
    }
    write_rgb_png(path, w, h, buf)
}

/// A corner of a panel's plotting area for its legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Corner {
    UpperLeft,
    UpperRight,
    LowerRight,
    LowerLeft,
}

impl Corner {
    fn position(self) -> SeriesLabelPosition {
        match self {
            Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
            Corner::UpperRight => SeriesLabelPosition::UpperRight,
            Corner::LowerRight => SeriesLabelPosition::LowerRight,
            Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        }
    }
}

/// Where a panel's legend goes: the corner of the plotting area (`plot_px`: width, height in
/// pixels; x from `xr.0` to `xr.1`, y from 0 to `y1`) whose legend box (about 50 + 7.5 px per
/// character of the longest label wide, 20 + 21 px per label tall, 10 px from the corner: plotters'
/// box at 12-point labels, measured on the stand table's picture) covers
/// the fewest of `points`, first of upper left, upper right, lower right, lower left among equals.
/// When every corner hides some, the y axis is raised (`y1` returned larger, at most 2.5 ×) so
/// that the upper corner needing the least headroom hides none. Returns the corner and `y1`.
fn legend_place(points: &[(f64, f64)], labels: &[&str], xr: (f64, f64), y1: f64, plot_px: (f64, f64)) -> (Corner, f64) {
    if labels.is_empty() || points.is_empty() || plot_px.0 <= 0.0 || plot_px.1 <= 0.0 {
        return (Corner::UpperLeft, y1);
    }
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    let (bw, bh) = ((50.0 + 7.5 * chars + 10.0) / plot_px.0, (20.0 + 21.0 * labels.len() as f64 + 10.0) / plot_px.1);
    let span = (xr.1 - xr.0).max(f64::MIN_POSITIVE);
    // fractions of the plotting area: u from the left, v from the bottom
    let frac = |q: &(f64, f64), y1: f64| ((q.0 - xr.0) / span, q.1 / y1);
    let left = |u: f64| u <= bw;
    let right = |u: f64| u >= 1.0 - bw;
    let hidden = |c: Corner, y1: f64| {
        points
            .iter()
            .filter(|q| {
                let (u, v) = frac(q, y1);
                match c {
                    Corner::UpperLeft => left(u) && v >= 1.0 - bh,
                    Corner::UpperRight => right(u) && v >= 1.0 - bh,
                    Corner::LowerRight => right(u) && v <= bh,
                    Corner::LowerLeft => left(u) && v <= bh,
                }
            })
            .count()
    };
    let corners = [Corner::UpperLeft, Corner::UpperRight, Corner::LowerRight, Corner::LowerLeft];
    let best = corners.iter().copied().min_by_key(|&c| hidden(c, y1)).unwrap_or(Corner::UpperLeft);
    if hidden(best, y1) == 0 || bh >= 0.6 {
        return (best, y1);
    }
    // raise the axis: the highest point under an upper corner's box then sits below it
    let need = |side: &dyn Fn(f64) -> bool| points.iter().filter(|q| side(frac(q, y1).0)).map(|q| q.1).fold(0.0f64, f64::max) / (1.0 - bh) * 1.02;
    let (c, y) = [(Corner::UpperLeft, need(&left)), (Corner::UpperRight, need(&right))].into_iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap_or((Corner::UpperLeft, y1));
    if y <= 2.5 * y1 {
        (c, y.max(y1))
    } else {
        (best, y1)
    }
}

fn write_rgb_png(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| perr(path, "buffer size"))?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| perr(path, e))?;
    crate::output::write_atomic(path, &bytes)
}

/// Categorical palette for species: the 7 colours of Okabe & Ito (2008, "Color Universal
/// Design", colour-blind safe; black left out) and 10 picked greedily from Kelly's (1965)
/// colours of maximum contrast and Tableau 20 (Tableau Software), each the candidate farthest in
/// CIELAB (CIE 1976 ΔE*ab) from the colours before it and from the maps' own grey (outside),
/// beige (no tree) and dark grey (not in the pool). Ordered greedily too (from Okabe–Ito's blue,
/// each next colour the one farthest from those before it), so that a pool of the first k
/// species is told apart as well as this set allows: any two of the first 8 differ by
/// ΔE*ab ≥ 36, any two of all 17 by ≥ 26. The palette before round 24 (Okabe–Ito then
/// Tableau 10 in their own orders) had pairs at 12.9 (beech and sycamore of the default run,
/// both blue) and orange next to vermillion (black alder and silver birch, 33).
pub const SPECIES_PALETTE: [[u8; 3]; 17] = [
    [0, 114, 178],
    [240, 228, 66],
    [190, 0, 50],
    [0, 158, 115],
    [101, 69, 34],
    [204, 121, 167],
    [213, 94, 0],
    [249, 147, 121],
    [44, 160, 44],
    [230, 159, 0],
    [152, 223, 138],
    [118, 183, 178],
    [148, 103, 189],
    [141, 182, 0],
    [136, 45, 23],
    [197, 176, 213],
    [86, 180, 233],
];

/// Species colour for plots and maps: [`SPECIES_PALETTE`] by the species' position in the pool
/// (cycling after 17 species); species outside the pool are dark grey.
pub fn species_color(w: &World, s: u16) -> [u8; 3] {
    match w.pool_index(s) {
        Some(p) => SPECIES_PALETTE[p % SPECIES_PALETTE.len()],
        None => [60, 60, 60],
    }
}

/// A figure of the stand table: stems/ha (individual trees, and the regeneration layer's
/// sapling stems below the recruitment height), basal area, heights and diameters (QMD of every
/// stem ≥ 1.3 m, and Dq of the stems ≥ 7 cm DBH, the yield tables' measure, which ingrowth
/// under a thinned stand does not pull down), species basal-area shares, the wood: standing
/// stem volume and the volume harvested so far (cumulative, m³/ha; issue 35's thinnings and
/// harvests), and under a changing climate the year's temperature offset and precipitation
/// factor.
pub fn plot_stand_table(path: &Path, rows: &[StandRow], w: &World) -> Result<()> {
    let x = |f: &dyn Fn(&StandRow) -> f64| rows.iter().map(|r| (r.year as f64, f(r))).collect::<Vec<_>>();
    let s = |name: &str, pts, color| Series { name: name.into(), points: pts, color, markers: false };
    let mut shares = Vec::new();
    for (p, &sp) in w.site.pool.iter().enumerate() {
        shares.push(s(&w.site.lib.species[sp as usize].identity.common_name, x(&|r| r.share_ba.get(p).copied().unwrap_or(0.0)), species_color(w, sp)));
    }
    let mut panels = vec![
        Panel { title: "Stems".into(), x_label: "year".into(), y_label: "stems/ha".into(), series: vec![s("trees ≥ 1.3 m (tree list)", x(&|r| r.stems_ha), [30, 90, 160]), s("DBH ≥ 7 cm", x(&|r| r.stems_7cm_ha), [200, 80, 40]), s("regeneration < 4 m (cohorts)", x(&|r| r.regeneration_ha), [120, 170, 60])] },
        Panel { title: "Basal area".into(), x_label: "year".into(), y_label: "m²/ha".into(), series: vec![s("basal area", x(&|r| r.basal_area_m2_ha), [40, 120, 40])] },
        Panel { title: "Height and diameter".into(), x_label: "year".into(), y_label: "m, cm".into(), series: vec![s("top height H100 (m)", x(&|r| r.top_height_m), [40, 120, 40]), s("mean height (m)", x(&|r| r.mean_height_m), [120, 160, 60]), s("QMD (cm)", x(&|r| r.qmd_cm), [150, 60, 40]), s("Dq, DBH ≥ 7 cm (cm)", x(&|r| r.qmd_7cm_cm), [210, 140, 60])] },
        Panel { title: "Species share of basal area".into(), x_label: "year".into(), y_label: "share".into(), series: shares },
        Panel { title: "Stem volume".into(), x_label: "year".into(), y_label: "m³/ha".into(), series: vec![s("standing", x(&|r| r.volume_m3_ha), [40, 120, 40]), s("harvested (cumulative)", cumulative(rows, |r| r.harvest_volume_m3_ha), [170, 90, 30])] },
    ];
    // a changing climate: the year's temperature offset and precipitation factor (round 32's
    // trial: the warming run's figure did not show its climate)
    if w.site.climate_change.is_active() {
        panels.push(Panel { title: "Climate".into(), x_label: "year".into(), y_label: "K, factor, index".into(), series: vec![s("temperature offset (K)", x(&|r| r.temperature_offset_k), [200, 60, 40]), s("precipitation factor", x(&|r| r.precipitation_factor), [40, 90, 180]), s("drought index", x(&|r| r.drought_index), [190, 140, 30])] });
    }
    plot_panels_png(path, &panels, 2, (1200, 1350))
}

/// The running sum of `f` over the rows (year, Σ f up to that year).
fn cumulative(rows: &[StandRow], f: impl Fn(&StandRow) -> f64) -> Vec<(f64, f64)> {
    let mut sum = 0.0;
    rows.iter()
        .map(|r| {
            sum += f(r);
            (r.year as f64, sum)
        })
        .collect()
}

/// Map raster size: cells of `cell_m` so that the longer side has at most `max_px` pixels.
/// Smallest cell of the species and basal-area maps (m): 20 m × 20 m = 0.04 ha, a usual
/// inventory plot size. Finer cells would hold a single tree each, and basal area per hectare
/// of a 5 m cell under one crown reads as hundreds of m²/ha (salt-and-pepper maps).
pub const MIN_MAP_CELL_M: f64 = 20.0;

/// The species and basal-area maps' raster of `w` for `max_px`: (columns, rows, cell in m).
pub fn map_dims(w: &World, max_px: usize) -> (usize, usize, f64) {
    let cell = (w.site.extent.0.max(w.site.extent.1) / max_px as f64).max(w.site.light.cell_m).max(MIN_MAP_CELL_M);
    (((w.site.extent.0 / cell).ceil() as usize).max(1), ((w.site.extent.1 / cell).ceil() as usize).max(1), cell)
}

/// "year N" from a snapshot file name such as `species_year_0010_spring.png`.
fn snapshot_label(p: &Path) -> String {
    let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    match stem.find("year_") {
        Some(i) => {
            let rest = &stem[i + 5..];
            let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
            let n: u64 = digits.parse().unwrap_or(0);
            let season = rest[digits.len()..].trim_start_matches('_');
            if season.is_empty() { format!("year {n}") } else { format!("year {n}, {season}") }
        }
        None => stem,
    }
}

/// Code of masked cells (outside the window, no data, water) in the species GeoTIFF (255).
pub const SPECIES_NODATA: u8 = 255;

/// Writes a species map (dominant species by basal area per map cell, in its
/// [`species_color`]; grey = masked, beige = no tree ≥ 1.3 m) with a title and a legend, and a
/// basal-area map (m²/ha per map cell, viridis 0–60 m²/ha) with a title and a colour bar.
/// Map cells are `max(light cell, longest extent / max_px)` metres; the pictures are enlarged to
/// at least 512 pixels on the long side. Text: DejaVu Sans via [`super::maps::draw_text`].
///
/// Beside each PNG the same map is written as a GeoTIFF (`.tif`, georeferenced like the
/// terrain, see [`map_georef`]): the basal area in m²/ha (Float32, NaN masked cells), and the
/// species map as codes — 0 no tree ≥ 1.3 m, k ≥ 1 the k-th species of the scenario's pool —
/// listed in `species_codes.csv` (code,species) in the same folder: a categorical Byte raster
/// with the PNG's colours as its colour table and [`SPECIES_NODATA`] marking masked cells
/// ([`super::geotiff::write_u8_palette_band`]; Float32 with NaN for a pool above 254 species).
///
/// Errors: [`OutputError::Io`] / PNG or GeoTIFF encoding errors naming the file.
pub fn write_maps(species_png: &Path, ba_png: &Path, w: &World, max_px: usize) -> Result<()> {
    let ba = map_basal_area(w, max_px);
    write_maps_from(species_png, ba_png, w, max_px, &ba)
}

/// The map bin of tree `i` of `t` on the raster `(cols, rows, cell)` of [`map_dims`] with `np`
/// species in the library: `(pixel · np + species)`, pixel row 0 north.
pub fn map_bin(t: &crate::sim::TreeStore, i: usize, (cols, rows, cell): (usize, usize, f64), np: usize) -> usize {
    let c = ((t.x[i] as f64 / cell) as usize).min(cols - 1);
    let r = rows - 1 - ((t.y[i] as f64 / cell) as usize).min(rows - 1);
    (r * cols + c) * np + t.species[i] as usize
}

/// Basal area (m²) per map bin ([`map_bin`]) of `w`'s trees, each bin summed in f64 in the
/// store's (id) order: what [`write_maps`] draws.
pub fn map_basal_area(w: &World, max_px: usize) -> Vec<f64> {
    let dims = map_dims(w, max_px);
    let np = w.site.lib.species.len();
    let mut ba = vec![0f64; dims.0 * dims.1 * np];
    let t = &w.stand.trees;
    for i in 0..t.len() {
        ba[map_bin(t, i, dims, np)] += t.basal_area_m2(i);
    }
    ba
}

/// [`write_maps`] from the basal area per map bin `ba` ([`map_basal_area`], or its bins
/// assembled from the ranks of a tiled run); `w` gives the site, pool and library.
///
/// Errors: as [`write_maps`]; [`OutputError::Io`] naming the species map when `ba` is not
/// one value per bin.
pub fn write_maps_from(species_png: &Path, ba_png: &Path, w: &World, max_px: usize, ba: &[f64]) -> Result<()> {
    write_maps_masked(species_png, ba_png, w, max_px, ba, &map_masked_centres(w, max_px))
}

/// Per pixel of the maps of `w` with longest side `max_px` ([`map_dims`]: `cols × rows`,
/// row-major, row 0 north): true where the pixel's centre lies on no unmasked site cell
/// ([`World::site_cell`]). A pixel so flagged is drawn masked unless it holds trees. Read from
/// the site cells `w` holds: the whole site's flags need the whole site (a tiled run's rank 0
/// keeps them from before its run driver's world is cut to its tile, `job::tiled`).
pub fn map_masked_centres(w: &World, max_px: usize) -> Vec<bool> {
    let dims = map_dims(w, max_px);
    (0..dims.0 * dims.1).map(|i| {
        let (x, y) = map_centre(dims, i);
        w.site_cell(x, y).is_none()
    }).collect()
}

/// The centre (m, origin SW corner) of pixel `i` (row-major, row 0 north) of the maps' raster
/// `(cols, rows, cell)` ([`map_dims`]): where [`map_masked_centres`] reads the site.
pub fn map_centre((cols, rows, cell): (usize, usize, f64), i: usize) -> (f64, f64) {
    let (c, r) = (i % cols, i / cols);
    ((c as f64 + 0.5) * cell, (rows - r) as f64 * cell - 0.5 * cell)
}

/// [`write_maps_from`] with the pixels whose centre is masked given (`centre_masked`, one per
/// pixel: [`map_masked_centres`] of the whole site); `w` gives the extent, georeferencing,
/// pool and library only, so it may hold a part of the site's cells (issue 37 Build 1).
///
/// Errors: as [`write_maps_from`]; [`OutputError::Io`] naming the species map when
/// `centre_masked` is not one flag per pixel.
pub fn write_maps_masked(species_png: &Path, ba_png: &Path, w: &World, max_px: usize, ba: &[f64], centre_masked: &[bool]) -> Result<()> {
    let (cols, rows, cell) = map_dims(w, max_px);
    if centre_masked.len() != cols * rows {
        return Err(OutputError::io(species_png, std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("{} masked-pixel flags for a {cols} × {rows} map", centre_masked.len()))));
    }
    let np = w.site.lib.species.len();
    if ba.len() != cols * rows * np {
        return Err(OutputError::io(species_png, std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("{} basal-area bins for a {cols} × {rows} map of {np} species", ba.len()))));
    }
    let area_ha = cell * cell / 10_000.0;
    let masked_px = [128u8, 128, 128];
    let empty_px = [235u8, 225, 200];
    let mut sp_cells = vec![[0u8; 3]; cols * rows];
    let mut ba_grid = crate::grid::Grid::filled(cols, rows, 0.0f32);
    let mut code_grid = crate::grid::Grid::filled(cols, rows, 0.0f32);
    let mut mask = crate::grid::Grid::filled(cols, rows, true);
    for r in 0..rows {
        for c in 0..cols {
            let v = &ba[(r * cols + c) * np..(r * cols + c + 1) * np];
            let tot: f64 = v.iter().sum();
            // a cell whose centre is masked but that holds trees keeps them (mass balance)
            let masked = centre_masked[r * cols + c] && tot <= 0.0;
            let dom = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(k, _)| k).unwrap_or(0);
            sp_cells[r * cols + c] = if masked { masked_px } else if tot <= 0.0 { empty_px } else { species_color(w, dom as u16) };
            ba_grid.data[r * cols + c] = (tot / area_ha) as f32;
            mask.data[r * cols + c] = !masked;
            let pool_pos = w.site.pool.iter().position(|&s| s as usize == dom).map_or(0.0, |k| k as f32 + 1.0);
            code_grid.data[r * cols + c] = if masked { f32::NAN } else if tot <= 0.0 { 0.0 } else { pool_pos };
        }
    }
    let when = snapshot_label(species_png);
    // species map with legend
    let font = ab_glyph::FontRef::try_from_slice(FONT).map_err(|e| OutputError::Bundled { what: "font", message: e.to_string() })?;
    let k = 512usize.div_ceil(cols.max(rows)).max(1);
    let (mw, mh) = (cols * k, rows * k);
    let (top, pad, right) = (44usize, 12usize, 190usize);
    let legend_h = 30 + 22 * (w.site.pool.len() + 2);
    let (iw, ih) = (pad + mw + right, top + mh.max(legend_h) + pad + 20);
    let mut img = image::RgbImage::from_pixel(iw as u32, ih as u32, image::Rgb([255, 255, 255]));
    for y in 0..mh {
        for x in 0..mw {
            img.put_pixel((pad + x) as u32, (top + y) as u32, image::Rgb(sp_cells[(y / k) * cols + x / k]));
        }
    }
    super::maps::draw_scale_bar(&mut img, &font, (pad, top), (mw, mh), cell / k as f64);
    super::maps::draw_text(&mut img, &font, pad as f32, 10.0, 20.0, &format!("Dominant species by basal area, {when}"));
    super::maps::draw_text(&mut img, &font, pad as f32, (top + mh + 4) as f32, 13.0, &format!("{:.0} m × {:.0} m, map cell {:.0} m", w.site.extent.0, w.site.extent.1, cell));
    let lx = pad + mw + 16;
    super::maps::draw_text(&mut img, &font, lx as f32, top as f32, 15.0, "Species");
    // common names (a trial read `norway_maple` in the legends); species_codes.csv keeps the ids
    let mut entries: Vec<(String, [u8; 3])> = w.site.pool.iter().map(|&s| (w.site.lib.species[s as usize].identity.common_name.clone(), species_color(w, s))).collect();
    entries.push(("no tree ≥ 1.3 m".into(), empty_px));
    entries.push(("outside / water".into(), masked_px));
    for (e, (name, col)) in entries.iter().enumerate() {
        let y = top + 26 + 22 * e;
        for dy in 0..14 {
            for dx in 0..18 {
                let edge = dx == 0 || dy == 0 || dx == 17 || dy == 13;
                img.put_pixel((lx + dx) as u32, (y + dy) as u32, image::Rgb(if edge { [60, 60, 60] } else { *col }));
            }
        }
        super::maps::draw_text(&mut img, &font, (lx + 26) as f32, y as f32 - 1.0, 14.0, name);
    }
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| perr(species_png, e))?;
    crate::output::write_atomic(species_png, &bytes)?;
    // basal-area map with colour bar
    let style = super::maps::MapStyle {
        ramp: super::maps::Ramp::Viridis,
        title: format!("Basal area, {when}"),
        units: "m²/ha".into(),
        range: Some((0.0, ba_scale_top(&ba_grid.data) as f32)),
        hillshade: None,
        shade_strength: 0.0,
        cell_m: Some(cell),
    };
    // the caption the species map has under its map (found by a trial: the basal-area map had
    // none); no hillshade, as the species map has none
    let caption = format!("{:.0} m × {:.0} m, map cell {:.0} m", w.site.extent.0, w.site.extent.1, cell);
    let ba_img = with_caption_under_map(super::maps::render_field(&ba_grid, Some(&mask), &style)?, (cols, rows), &font, &caption);
    let mut bytes = Vec::new();
    ba_img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| perr(ba_png, e))?;
    crate::output::write_atomic(ba_png, &bytes)?;
    let geo = map_georef(w, rows, cell);
    let ba_tif: Vec<f32> = ba_grid.data.iter().zip(&mask.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect();
    let ba_title = format!("Basal area, {when}");
    super::geotiff::write_f32_band(&ba_png.with_extension("tif"), &crate::grid::Grid { width: cols, height: rows, data: ba_tif }, &geo, Some(super::geotiff::Band { description: &ba_title, unit: "m²/ha" }))?;
    let sp_title = format!("Dominant species by basal area, {when} (codes in species_codes.csv; 0 none)");
    // a categorical Byte raster with the map's colours as its colour table, 255 no data
    // (trial 37: Float32 without colours); Float32 only for a pool of more than 254 species
    let sp_band = Some(super::geotiff::Band { description: &sp_title, unit: "code" });
    if w.site.pool.len() < 255 {
        let codes: Vec<u8> = code_grid.data.iter().map(|v| if v.is_finite() { *v as u8 } else { SPECIES_NODATA }).collect();
        let mut palette = vec![empty_px];
        palette.extend(w.site.pool.iter().map(|&s| species_color(w, s)));
        palette.resize(SPECIES_NODATA as usize, [0, 0, 0]);
        palette.push(masked_px);
        super::geotiff::write_u8_palette_band(&species_png.with_extension("tif"), &crate::grid::Grid { width: code_grid.width, height: code_grid.height, data: codes }, &geo, sp_band, &palette, SPECIES_NODATA)?;
    } else {
        super::geotiff::write_f32_band(&species_png.with_extension("tif"), &code_grid, &geo, sp_band)?;
    }
    let mut codes = String::from("code,species\n0,none\n");
    for (k, &s) in w.site.pool.iter().enumerate() {
        codes.push_str(&format!("{},{}\n", k + 1, w.site.lib.species[s as usize].id));
    }
    let codes_path = species_png.with_file_name("species_codes.csv");
    crate::output::write_atomic(&codes_path, codes.as_bytes())
}

/// `img`, a map that [`super::maps::render_field`] drew of a `cols × rows` grid, with `caption`
/// written under the map (13 px, as the species map's), the image 20 px taller when the
/// caption would not fit below the map otherwise. The map's place repeats `render_field`'s
/// layout: 44 px title band, 12 px left pad, grids enlarged to at least 600 px (whole factor)
/// or shrunk to at most 2000 px.
fn with_caption_under_map(img: image::RgbImage, (cols, rows): (usize, usize), font: &ab_glyph::FontRef, caption: &str) -> image::RgbImage {
    let (top, pad) = (44usize, 12usize);
    let long = cols.max(rows).max(1);
    let (num, den) = if long > 2000 { (1, long.div_ceil(2000)) } else { ((600 / long).max(1), 1) };
    let map_bottom = top + rows * num / den;
    let need = (map_bottom + 4 + 20) as u32;
    let mut out = image::RgbImage::from_pixel(img.width(), img.height().max(need), image::Rgb([255, 255, 255]));
    image::imageops::replace(&mut out, &img, 0, 0);
    super::maps::draw_text(&mut out, font, pad as f32, (map_bottom + 4) as f32, 13.0, caption);
    out
}

/// Top of the basal-area colour scale (m²/ha): the 99th percentile of the non-empty cells,
/// rounded up to 10, at least 60 (so maps of different years share the scale until a stand
/// exceeds it).
fn ba_scale_top(v: &[f32]) -> f64 {
    let mut nz: Vec<f32> = v.iter().copied().filter(|x| x.is_finite() && *x > 0.0).collect();
    if nz.is_empty() {
        return 60.0;
    }
    nz.sort_by(f32::total_cmp);
    let p99 = nz[(nz.len() * 99 / 100).min(nz.len() - 1)] as f64;
    ((p99 / 10.0).ceil() * 10.0).max(60.0)
}

/// Georeferencing of a map of `rows` rows with square cells of `cell` metres laid over the
/// world (x east from the terrain's west edge, y north from its south edge; map row 0 north,
/// its top edge at y = rows·cell): the terrain's CRS, cell size converted to CRS units by the
/// terrain's own metres-per-unit (degrees for geographic grids, at the grid's mean row).
pub fn map_georef(w: &World, rows: usize, cell: f64) -> crate::grid::GeoRef {
    let g = &w.site.conditions.geo;
    let sx = g.pixel_w / w.site.conditions.cell_x_m.max(1e-12);
    let sy = g.pixel_h / w.site.conditions.cell_y_m.max(1e-12);
    let south = g.origin_y - w.site.conditions.height() as f64 * g.pixel_h;
    crate::grid::GeoRef { pixel_w: cell * sx, pixel_h: cell * sy, origin_x: g.origin_x, origin_y: south + rows as f64 * cell * sy, ..g.clone() }
}

/// A y-axis label of value `v` on an axis reaching `top`: whole numbers from a top of 50 up,
/// one decimal from 5, two below; trailing zeros of the decimals dropped (`2.50` → `2.5`).
fn axis_label(v: f64, top: f64) -> String {
    let d = if top >= 50.0 { 0 } else if top >= 5.0 { 1 } else { 2 };
    let s = format!("{v:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn axis_labels_have_the_decimals_the_range_needs() {
        assert_eq!(super::axis_label(3500.0, 4000.0), "3500");
        assert_eq!(super::axis_label(12.5, 30.0), "12.5");
        assert_eq!(super::axis_label(10.0, 30.0), "10");
        assert_eq!(super::axis_label(0.25, 1.0), "0.25");
        assert_eq!(super::axis_label(0.0, 1.0), "0");
    }

    #[test]
    fn legend_goes_where_it_hides_no_data() {
        use super::{legend_place, Corner};
        let px = (500.0, 330.0);
        // the default run's "Height and diameter": seed trees' 30 cm at the start, then a
        // curve rising to 25 by year 150: the top left hides data, the top right does not
        let mut pts: Vec<(f64, f64)> = (1..=150).map(|y| (y as f64, 5.0 + 15.0 * y as f64 / 150.0)).collect();
        pts.extend([(1.0, 30.0), (2.0, 29.5), (3.0, 29.0)]);
        let (c, y1) = legend_place(&pts, &["top height H100 (m)", "mean height (m)", "QMD (cm)"], (1.0, 150.0), 32.4, px);
        assert_eq!((c, y1), (Corner::UpperRight, 32.4), "the top right is empty here");
        // a curve high at both ends and low in the middle: both upper corners hide it, the
        // lower ones are empty (the lower right first)
        let u: Vec<(f64, f64)> = (0..=100).map(|x| (x as f64, 10.0 + 0.004 * ((x - 50) * (x - 50)) as f64)).collect();
        assert_eq!(legend_place(&u, &["a", "b"], (0.0, 100.0), 21.6, px), (Corner::LowerRight, 21.6));
        // data in every corner: the axis is raised so an upper corner is clear
        let full: Vec<(f64, f64)> = (0..=100).flat_map(|x| [(x as f64, 0.0), (x as f64, 10.0)]).collect();
        let (c, y1) = legend_place(&full, &["one", "two"], (0.0, 100.0), 10.8, px);
        assert_eq!(c, Corner::UpperLeft);
        assert!(y1 > 10.8 && y1 < 27.0, "{y1}");
        let bh = (20.0 + 42.0 + 10.0) / 330.0;
        assert!(10.0 / y1 < 1.0 - bh, "the top data line below the legend box: {y1}");
    }
}
