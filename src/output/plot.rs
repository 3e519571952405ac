//! Plots (plotters, DejaVu Sans registered from `assets/fonts/`) and raster maps (PNG).

use crate::error::{Error, Result};
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
            let mut ch = ChartBuilder::on(area)
                .caption(&p.title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d(x0..x1, 0f64..y1)
                .map_err(|e| perr(path, e))?;
            ch.configure_mesh().x_desc(&p.x_label).y_desc(&p.y_label).label_style(("sans-serif", 13)).draw().map_err(|e| perr(path, e))?;
            for s in &p.series {
                let c = RGBColor(s.color[0], s.color[1], s.color[2]);
                if s.markers {
                    ch.draw_series(s.points.iter().map(|&q| Circle::new(q, 3, c.filled()))).map_err(|e| perr(path, e))?.label(&s.name).legend(move |(x, y)| Circle::new((x + 8, y), 3, c.filled()));
                } else {
                    ch.draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2))).map_err(|e| perr(path, e))?.label(&s.name).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2)));
                }
            }
            ch.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).label_font(("sans-serif", 12)).position(SeriesLabelPosition::UpperLeft).draw().map_err(|e| perr(path, e))?;
        }
        root.present().map_err(|e| perr(path, e))?;
    }
    write_rgb_png(path, w, h, buf)
}

fn write_rgb_png(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| perr(path, "buffer size"))?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| perr(path, e))?;
    crate::output::write_atomic(path, &bytes)
}

/// Species colour for plots and maps: the species' summer foliage colour.
pub fn species_color(w: &World, s: u16) -> [u8; 3] {
    w.lib.species[s as usize].appearance.leaf_summer
}

/// A 2×2 figure of the stand table: stems/ha, basal area, heights, species basal-area shares.
pub fn plot_stand_table(path: &Path, rows: &[StandRow], w: &World) -> Result<()> {
    let x = |f: &dyn Fn(&StandRow) -> f64| rows.iter().map(|r| (r.year as f64, f(r))).collect::<Vec<_>>();
    let s = |name: &str, pts, color| Series { name: name.into(), points: pts, color, markers: false };
    let mut shares = Vec::new();
    for (p, &sp) in w.pool.iter().enumerate() {
        shares.push(s(&w.lib.species[sp as usize].id, x(&|r| r.share_ba.get(p).copied().unwrap_or(0.0)), species_color(w, sp)));
    }
    let panels = vec![
        Panel { title: "Stems".into(), x_label: "year".into(), y_label: "stems/ha".into(), series: vec![s("height ≥ 1.3 m", x(&|r| r.stems_ha), [30, 90, 160]), s("DBH ≥ 7 cm", x(&|r| r.stems_7cm_ha), [200, 80, 40])] },
        Panel { title: "Basal area".into(), x_label: "year".into(), y_label: "m²/ha".into(), series: vec![s("basal area", x(&|r| r.basal_area_m2_ha), [40, 120, 40])] },
        Panel { title: "Height and diameter".into(), x_label: "year".into(), y_label: "m, cm".into(), series: vec![s("top height H100 (m)", x(&|r| r.top_height_m), [40, 120, 40]), s("mean height (m)", x(&|r| r.mean_height_m), [120, 160, 60]), s("QMD (cm)", x(&|r| r.qmd_cm), [150, 60, 40])] },
        Panel { title: "Species share of basal area".into(), x_label: "year".into(), y_label: "share".into(), series: shares },
    ];
    plot_panels_png(path, &panels, 2, (1200, 900))
}

/// Map raster size: cells of `cell_m` so that the longer side has at most `max_px` pixels.
fn map_dims(w: &World, max_px: usize) -> (usize, usize, f64) {
    let cell = (w.extent.0.max(w.extent.1) / max_px as f64).max(w.light_cell_m);
    (((w.extent.0 / cell).ceil() as usize).max(1), ((w.extent.1 / cell).ceil() as usize).max(1), cell)
}

/// Writes a species map (dominant species by basal area per map cell, in its foliage colour;
/// grey = masked, light = no tree ≥ 1.3 m) and a basal-area map (white 0 → dark green ≥ 60 m²/ha).
pub fn write_maps(species_png: &Path, ba_png: &Path, w: &World, max_px: usize) -> Result<()> {
    let (cols, rows, cell) = map_dims(w, max_px);
    let np = w.lib.species.len();
    let mut ba = vec![0f64; cols * rows * np];
    let t = &w.trees;
    for i in 0..t.len() {
        let c = ((t.x[i] as f64 / cell) as usize).min(cols - 1);
        let r = rows - 1 - ((t.y[i] as f64 / cell) as usize).min(rows - 1);
        ba[(r * cols + c) * np + t.species[i] as usize] += t.basal_area_m2(i);
    }
    let area_ha = cell * cell / 10_000.0;
    let mut sp_img = image::RgbImage::new(cols as u32, rows as u32);
    let mut ba_img = image::RgbImage::new(cols as u32, rows as u32);
    for r in 0..rows {
        for c in 0..cols {
            let (x, y) = ((c as f64 + 0.5) * cell, (rows - r) as f64 * cell - 0.5 * cell);
            let masked = w.site_cell(x, y).is_none();
            let v = &ba[(r * cols + c) * np..(r * cols + c + 1) * np];
            let tot: f64 = v.iter().sum();
            let dom = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(k, _)| k).unwrap_or(0);
            let px = if masked { [128, 128, 128] } else if tot <= 0.0 { [235, 225, 200] } else { species_color(w, dom as u16) };
            sp_img.put_pixel(c as u32, r as u32, image::Rgb(px));
            let f = (tot / area_ha / 60.0).clamp(0.0, 1.0) as f32;
            let g = if masked { [128, 128, 128] } else { [(255.0 - 235.0 * f) as u8, (255.0 - 155.0 * f) as u8, (255.0 - 235.0 * f) as u8] };
            ba_img.put_pixel(c as u32, r as u32, image::Rgb(g));
        }
    }
    for (img, p) in [(sp_img, species_png), (ba_img, ba_png)] {
        let mut bytes = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| perr(p, e))?;
        crate::output::write_atomic(p, &bytes)?;
    }
    Ok(())
}
