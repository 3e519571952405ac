//! Colour-mapped PNG maps of grids with a legend (title, colour bar, units), optional hillshade
//! underlay. Text is drawn with `ab_glyph` and the bundled DejaVu Sans.

use super::{OutputError, Result};
use crate::error::Error;
use crate::grid::Grid;
use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use image::{Rgb, RgbImage};
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Colour ramps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ramp {
    /// Perceptually uniform dark blue → green → yellow (matplotlib viridis stops).
    Viridis,
    /// Hypsometric: green lowlands → yellow → brown → white summits.
    Terrain,
    /// Black → purple → orange → pale yellow (matplotlib magma stops), for energy.
    Magma,
    /// White → dark blue, for water.
    Blues,
    /// Cyclic hue wheel for directions (0° = 360°).
    Cyclic,
    /// Diverging blue (cold/low) → yellow → red (warm/high).
    BlueRed,
    /// Black → white.
    Grey,
}

fn hex(c: u32) -> [f32; 3] {
    [((c >> 16) & 255) as f32, ((c >> 8) & 255) as f32, (c & 255) as f32]
}

impl Ramp {
    /// Colour of `t` in 0–1 (clamped).
    pub fn color(self, t: f32) -> [u8; 3] {
        let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
        if self == Ramp::Cyclic {
            let h = t * 6.0;
            let x = 1.0 - (h % 2.0 - 1.0).abs();
            let (r, g, b) = match h as u32 {
                0 => (1.0, x, 0.0),
                1 => (x, 1.0, 0.0),
                2 => (0.0, 1.0, x),
                3 => (0.0, x, 1.0),
                4 => (x, 0.0, 1.0),
                _ => (1.0, 0.0, x),
            };
            return [(40.0 + 200.0 * r) as u8, (40.0 + 200.0 * g) as u8, (40.0 + 200.0 * b) as u8];
        }
        let stops: &[u32] = match self {
            Ramp::Viridis => &[0x440154, 0x482878, 0x3e4989, 0x31688e, 0x26828e, 0x1f9e89, 0x35b779, 0x6ece58, 0xb5de2b, 0xfde725],
            Ramp::Terrain => &[0x1a9850, 0x91cf60, 0xd9ef8b, 0xfee08b, 0xd8b365, 0x8c510a, 0xf5f5f5],
            Ramp::Magma => &[0x000004, 0x3b0f70, 0x8c2981, 0xde4968, 0xfe9f6d, 0xfcfdbf],
            Ramp::Blues => &[0xf7fbff, 0xc6dbef, 0x6baed6, 0x2171b5, 0x08306b],
            Ramp::BlueRed => &[0x313695, 0x4575b4, 0xabd9e9, 0xffffbf, 0xfdae61, 0xd73027, 0xa50026],
            _ => &[0x000000, 0xffffff],
        };
        let f = t * (stops.len() - 1) as f32;
        let i = (f.floor() as usize).min(stops.len() - 2);
        let u = f - i as f32;
        let (a, b) = (hex(stops[i]), hex(stops[i + 1]));
        [0, 1, 2].map(|k| (a[k] + (b[k] - a[k]) * u).round() as u8)
    }
}

/// How to draw a field.
#[derive(Debug, Clone)]
pub struct MapStyle<'a> {
    /// Colour ramp.
    pub ramp: Ramp,
    /// Title above the map.
    pub title: String,
    /// Units written under the colour bar.
    pub units: String,
    /// Value range mapped onto the ramp; `None`: 1st–99th percentile of valid values.
    pub range: Option<(f32, f32)>,
    /// Hillshade (0–255) multiplied under the colours (gdaldem-style relief).
    pub hillshade: Option<&'a Grid<f32>>,
    /// Strength of the hillshade (0 none … 1 full).
    pub shade_strength: f32,
    /// East–west size of one grid cell in metres (at the map's centre row for geographic
    /// grids); `Some` draws a scale bar and a north arrow on the map ([`draw_scale_bar`]).
    pub cell_m: Option<f64>,
}

/// Writes a colour-mapped PNG of `grid` with a title, a colour bar and its units. Cells that are
/// NaN or `false` in `mask` are light grey. Range: 1st–99th percentile of valid values; where
/// the data reach beyond it, the bar's end labels read "≤ lo" / "≥ hi" and a line under the
/// units gives the data's whole range ("data 748–1281").
///
/// Errors: [`Error::Invalid`] (in [`OutputError::Input`]) for an empty grid or a mask of another size; [`OutputError::Io`].
pub fn write_field_png(grid: &Grid<f32>, mask: Option<&Grid<bool>>, ramp: Ramp, title: &str, units: &str, path: &Path) -> Result<()> {
    let style = MapStyle { ramp, title: title.into(), units: units.into(), range: None, hillshade: None, shade_strength: 0.0, cell_m: None };
    write_field_png_styled(grid, mask, &style, path)
}

/// Percentile range (p in 0–1) of the finite values; `None` when there are none.
pub fn percentile_range(grid: &Grid<f32>, mask: Option<&Grid<bool>>, lo: f64, hi: f64) -> Option<(f32, f32)> {
    let mut v: Vec<f32> = grid.data.iter().enumerate().filter(|(i, x)| x.is_finite() && mask.is_none_or(|m| m.data[*i])).map(|(_, x)| *x).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_unstable_by(f32::total_cmp);
    let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    Some((at(lo), at(hi)))
}

/// Like [`write_field_png`] with full control of the style.
pub fn write_field_png_styled(grid: &Grid<f32>, mask: Option<&Grid<bool>>, style: &MapStyle, path: &Path) -> Result<()> {
    let img = render_field(grid, mask, style).map_err(|e| match e {
        OutputError::Input(Error::Invalid { field, value, expected, .. }) => Error::Invalid { context: path.display().to_string(), field, value, expected }.into(),
        o => o,
    })?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "PNG", message: e.to_string() })?;
    super::write_atomic(path, &bytes)
}

/// Renders the map into an image (see [`write_field_png_styled`]).
pub fn render_field(grid: &Grid<f32>, mask: Option<&Grid<bool>>, style: &MapStyle) -> Result<RgbImage> {
    let (w, h) = (grid.width, grid.height);
    let inv = |f: &str, v: String, e: &str| OutputError::from(Error::Invalid { context: "map".into(), field: f.into(), value: v, expected: e.into() });
    if w == 0 || h == 0 {
        return Err(inv("grid", format!("{w} x {h}"), "a non-empty grid"));
    }
    if let Some(m) = mask {
        if (m.width, m.height) != (w, h) {
            return Err(inv("mask", format!("{} x {}", m.width, m.height), &format!("{w} x {h} like the grid")));
        }
    }
    let (lo, hi) = style.range.or_else(|| percentile_range(grid, mask, 0.01, 0.99)).unwrap_or((0.0, 1.0));
    let hi = if hi > lo { hi } else { lo + 1.0 };
    // the data's whole range, for the bar's labels
    let (vmin, vmax) = grid.data.iter().enumerate().filter(|(i, x)| x.is_finite() && mask.is_none_or(|m| m.data[*i])).fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), (_, &x)| (a.min(x), b.max(x)));
    let fmt = |v: f32| if (hi - lo).abs() >= 20.0 { format!("{v:.0}") } else if (hi - lo).abs() >= 2.0 { format!("{v:.1}") } else { format!("{v:.2}") };
    // Map scale: enlarge small grids to ≥ 600 px, shrink grids over 2000 px.
    let (num, den) = if w.max(h) > 2000 { (1, w.max(h).div_ceil(2000)) } else { ((600 / w.max(1)).max(1), 1) };
    let (mw, mh) = (w * num / den, h * num / den);
    let (top, right, pad) = (44usize, 150usize, 12usize);
    let (iw, ih) = (pad + mw + right, top + mh.max(260) + pad);
    let mut img = RgbImage::from_pixel(iw as u32, ih as u32, Rgb([255, 255, 255]));
    for y in 0..mh {
        let r = y * den / num;
        for x in 0..mw {
            let c = x * den / num;
            let i = r * w + c;
            let v = grid.data[i];
            let valid = v.is_finite() && mask.is_none_or(|m| m.data[i]);
            let px = if valid {
                let mut col = style.ramp.color((v - lo) / (hi - lo));
                if let Some(hs) = style.hillshade {
                    let s = hs.data.get(i).copied().unwrap_or(255.0);
                    let s = if s.is_finite() { s / 255.0 } else { 1.0 };
                    let k = 1.0 - style.shade_strength + style.shade_strength * s;
                    col = col.map(|c| (c as f32 * k).clamp(0.0, 255.0) as u8);
                }
                col
            } else {
                [215, 215, 215]
            };
            img.put_pixel((pad + x) as u32, (top + y) as u32, Rgb(px));
        }
    }
    let font = FontRef::try_from_slice(FONT).map_err(|e| OutputError::Bundled { what: "font", message: e.to_string() })?;
    if let Some(c) = style.cell_m {
        draw_scale_bar(&mut img, &font, (pad, top), (mw, mh), c * den as f64 / num as f64);
    }
    draw_text(&mut img, &font, pad as f32, 10.0, 22.0, &style.title);
    // Colour bar.
    let (bx, by, bw, bh) = (pad + mw + 20, top + 10, 22usize, mh.clamp(200, 400) - 20);
    for y in 0..bh {
        let t = 1.0 - y as f32 / (bh - 1) as f32;
        let col = style.ramp.color(t);
        for x in 0..bw {
            img.put_pixel((bx + x) as u32, (by + y) as u32, Rgb(col));
        }
    }
    for k in 0..=4 {
        let t = k as f32 / 4.0;
        let y = by + ((1.0 - t) * (bh - 1) as f32) as usize;
        for x in bw..bw + 5 {
            img.put_pixel((bx + x) as u32, y as u32, Rgb([0, 0, 0]));
        }
        let v = lo + (hi - lo) * t;
        let mut label = fmt(v);
        // the bar's ends clip the data: said at the ends (a trial read the 1st–99th percentile
        // bar as the slope's whole range and missed the steepest 52° cells)
        if k == 0 && vmin < lo {
            label = format!("≤ {label}");
        } else if k == 4 && vmax > hi {
            label = format!("≥ {label}");
        }
        draw_text(&mut img, &font, (bx + bw + 8) as f32, y as f32 - 8.0, 14.0, &label);
    }
    draw_text(&mut img, &font, bx as f32, (by + bh + 8) as f32, 14.0, &style.units);
    if vmin < lo || vmax > hi {
        draw_text(&mut img, &font, bx as f32, (by + bh + 28) as f32, 12.0, &format!("data {}–{}", fmt(vmin), fmt(vmax)));
    }
    Ok(img)
}

/// Length of a map's scale bar in metres: the longest 1, 2 or 5 × 10ⁿ m not over a quarter of
/// `map_m` (the map's width in metres, > 0); 0 for a map under 4 m.
pub fn scale_bar_length_m(map_m: f64) -> f64 {
    let target = map_m / 4.0;
    if !(target >= 1.0) {
        return 0.0;
    }
    let p = 10f64.powi(target.log10().floor() as i32);
    [5.0, 2.0, 1.0].into_iter().map(|k| k * p).find(|&l| l <= target * (1.0 + 1e-9)).unwrap_or(p)
}

/// Draws a scale bar (lower-left) and a north arrow (upper-right) on the map drawn at pixel
/// `origin` with size `size` (pixels), `m_per_px` metres per map pixel (east–west), each on a
/// white box so they read on any colour. The bar is [`scale_bar_length_m`] of the map's width,
/// in four alternating black and white segments, labelled in m or km. Maps are drawn north up
/// (row 0 north, [`Grid`]). Draws nothing where the map is under 120 px wide.
pub fn draw_scale_bar(img: &mut RgbImage, font: &FontRef, origin: (usize, usize), size: (usize, usize), m_per_px: f64) {
    let ((x0, y0), (mw, mh)) = (origin, size);
    if mw < 120 || mh < 80 || !(m_per_px > 0.0) {
        return;
    }
    let len_m = scale_bar_length_m(mw as f64 * m_per_px);
    let bar = (len_m / m_per_px).round() as usize;
    if len_m <= 0.0 || bar < 20 {
        return;
    }
    let label = if len_m >= 1000.0 { format!("{} km", len_m / 1000.0) } else { format!("{len_m} m") };
    let sf = font.as_scaled(PxScale::from(13.0));
    let text_w: f32 = label.chars().map(|c| sf.h_advance(sf.glyph_id(c))).sum();
    let fill = |x: usize, y: usize, w: usize, h: usize, col: [u8; 3], img: &mut RgbImage| {
        for yy in y..(y + h).min(img.height() as usize) {
            for xx in x..(x + w).min(img.width() as usize) {
                img.put_pixel(xx as u32, yy as u32, Rgb(col));
            }
        }
    };
    // scale bar: box 8 px in from the map's lower-left corner
    let (bw, bh) = (8 + bar + 6 + text_w.ceil() as usize + 8, 26usize);
    let (bx, by) = (x0 + 8, y0 + mh - 8 - bh);
    fill(bx, by, bw, bh, [255, 255, 255], img);
    let (sx, sy, sh) = (bx + 8, by + 10, 7usize);
    fill(sx, sy, bar, sh, [0, 0, 0], img);
    for k in 0..4 {
        let (a, b) = (sx + bar * k / 4, sx + bar * (k + 1) / 4);
        if k % 2 == 1 && b > a + 2 {
            fill(a + 1, sy + 1, b - a - 1, sh - 2, [255, 255, 255], img);
        }
    }
    draw_text(img, font, (sx + bar + 6) as f32, (by + 5) as f32, 13.0, &label);
    // north arrow: box 8 px in from the map's upper-right corner
    let (aw, ah) = (24usize, 40usize);
    let (ax, ay) = (x0 + mw - 8 - aw, y0 + 8);
    fill(ax, ay, aw, ah, [255, 255, 255], img);
    let tip = ay + 18;
    for dy in 0..18usize {
        let half = dy * 7 / 17;
        let cx = ax + aw / 2;
        // left half black, right half outlined: the common north arrow
        fill(cx - half, tip + dy, half + 1, 1, [0, 0, 0], img);
        if half > 0 {
            fill(cx + half, tip + dy, 1, 1, [0, 0, 0], img);
        }
    }
    fill(ax + aw / 2 - 7, tip + 17, 15, 1, [0, 0, 0], img);
    let nw: f32 = sf.h_advance(sf.glyph_id('N'));
    draw_text(img, font, (ax + aw / 2) as f32 - nw / 2.0, (ay + 2) as f32, 13.0, "N");
}

/// Draws `text` (black) with its top-left at `(x, y)` pixels, `px` pixels high.
pub fn draw_text(img: &mut RgbImage, font: &FontRef, x: f32, y: f32, px: f32, text: &str) {
    let (w, h) = img.dimensions();
    glyph_coverage(font, x, y, px, text, w, h, |gx, gy, cov| {
        let p = img.get_pixel_mut(gx, gy);
        for c in 0..3 {
            p.0[c] = (p.0[c] as f32 * (1.0 - cov)) as u8;
        }
    });
}

/// Calls `put(x, y, coverage 0–1)` for every pixel inside `w × h` that the glyphs of `text`
/// (top-left at `(x, y)`, `px` pixels high) cover.
#[allow(clippy::too_many_arguments)]
fn glyph_coverage(font: &FontRef, x: f32, y: f32, px: f32, text: &str, w: u32, h: u32, mut put: impl FnMut(u32, u32, f32)) {
    let sf = font.as_scaled(PxScale::from(px));
    let mut caret = x;
    let mut prev = None;
    for ch in text.chars() {
        let id = sf.glyph_id(ch);
        if let Some(p) = prev {
            caret += sf.kern(p, id);
        }
        let g = id.with_scale_and_position(px, ab_glyph::point(caret, y + sf.ascent()));
        caret += sf.h_advance(id);
        prev = Some(id);
        if let Some(og) = font.outline_glyph(g) {
            let b = og.px_bounds();
            og.draw(|gx, gy, cov| {
                let (px_, py_) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
                if px_ >= 0 && py_ >= 0 && (px_ as u32) < w && (py_ as u32) < h {
                    put(px_ as u32, py_ as u32, cov.clamp(0.0, 1.0));
                }
            });
        }
    }
}

/// Stamps a caption (e.g. `year 45`) in the top-left corner of a rendered frame: white text
/// (height 1/18 of the frame, at least 10 px) on a 55 % dark box, so it reads on sky and forest.
///
/// Errors: only if the bundled font could not be parsed.
pub fn stamp_caption(img: &mut image::RgbaImage, text: &str) -> Result<()> {
    let font = FontRef::try_from_slice(FONT).map_err(|e| OutputError::Bundled { what: "font", message: e.to_string() })?;
    let (w, h) = img.dimensions();
    let px = (h as f32 / 18.0).max(10.0);
    let sf = font.as_scaled(PxScale::from(px));
    let text_w: f32 = text.chars().map(|c| sf.h_advance(sf.glyph_id(c))).sum();
    let (x0, y0, pad) = (0.4 * px, 0.4 * px, 0.3 * px);
    let (bx1, by1) = (((x0 + text_w + pad) as u32).min(w), ((y0 + px * 1.2 + pad) as u32).min(h));
    for yy in ((y0 - pad).max(0.0) as u32)..by1 {
        for xx in ((x0 - pad).max(0.0) as u32)..bx1 {
            let p = img.get_pixel_mut(xx, yy);
            for c in 0..3 {
                p.0[c] = (p.0[c] as f32 * 0.45) as u8;
            }
        }
    }
    glyph_coverage(&font, x0, y0, px, text, w, h, |gx, gy, cov| {
        let p = img.get_pixel_mut(gx, gy);
        for c in 0..3 {
            p.0[c] = (p.0[c] as f32 + (255.0 - p.0[c] as f32) * cov) as u8;
        }
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_and_masked_grey() {
        assert_eq!(Ramp::Viridis.color(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(Ramp::Viridis.color(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(Ramp::Grey.color(0.5), [128, 128, 128]);
        let mut g = Grid::filled(10, 10, 1.0f32);
        g.data[0] = f32::NAN;
        let st = MapStyle { ramp: Ramp::Grey, title: "t".into(), units: "m".into(), range: Some((0.0, 1.0)), hillshade: None, shade_strength: 0.0, cell_m: None };
        let img = render_field(&g, None, &st).unwrap();
        assert_eq!(img.get_pixel(12, 44).0, [215, 215, 215]);
        assert_eq!(img.get_pixel(12 + 60, 44).0, [255, 255, 255]);
    }

    /// A bar that clips the data says so under its units ("data lo–hi"); one that holds the
    /// data draws nothing there.
    #[test]
    fn clipped_bar_gives_the_data_range() {
        let mut g = Grid::filled(10, 10, 0.0f32);
        for (i, v) in g.data.iter_mut().enumerate() {
            *v = i as f32;
        }
        g.data[99] = 1000.0; // an outlier above the 99th percentile
        // 600 × 600 px map: the bar at x 632, 54–433 px; the data line at y 462
        let ink = |img: &RgbImage| (462..478).flat_map(|y| (632..760).map(move |x| (x, y))).filter(|&(x, y)| img.get_pixel(x, y).0[0] < 128).count();
        let style = |range| MapStyle { ramp: Ramp::Grey, title: "t".into(), units: "m".into(), range, hillshade: None, shade_strength: 0.0, cell_m: None };
        let clipped = render_field(&g, None, &style(None)).unwrap();
        let whole = render_field(&g, None, &style(Some((0.0, 1000.0)))).unwrap();
        assert!(ink(&clipped) > 40, "{}", ink(&clipped));
        assert_eq!(ink(&whole), 0);
    }

    /// The scale bar's length: 1, 2 or 5 × 10ⁿ m, at most a quarter of the map.
    #[test]
    fn scale_bar_lengths() {
        assert_eq!(scale_bar_length_m(2400.0), 500.0);
        assert_eq!(scale_bar_length_m(1999.0), 200.0);
        assert_eq!(scale_bar_length_m(4000.0), 1000.0);
        assert_eq!(scale_bar_length_m(799.0), 100.0);
        assert_eq!(scale_bar_length_m(12_000.0), 2000.0);
        assert_eq!(scale_bar_length_m(30.0), 5.0);
        assert_eq!(scale_bar_length_m(3.0), 0.0);
    }

    /// A map with its cell size gets a bar of the right pixel length in its lower-left corner
    /// (black pixels along the bar's top edge) and nothing there without it.
    #[test]
    fn scale_bar_drawn_to_scale() {
        let g = Grid::filled(100, 100, 0.5f32); // 600 × 600 px, 6 px a cell
        let st = |cell_m| MapStyle { ramp: Ramp::Grey, title: "t".into(), units: "m".into(), range: Some((0.0, 1.0)), hillshade: None, shade_strength: 0.0, cell_m };
        // 10 m cells: 1,000 m map, bar 200 m (≤ 250) = 120 px, from x 12+16 at y 44+600-8-26+10
        let img = render_field(&g, None, &st(Some(10.0))).unwrap();
        let y = 44 + 600 - 8 - 26 + 10;
        let black: Vec<u32> = (12..150).filter(|&x| img.get_pixel(x, y).0 == [0, 0, 0]).collect();
        assert_eq!((black.first().copied(), black.last().copied()), (Some(28), Some(28 + 119)), "{black:?}");
        let plain = render_field(&g, None, &st(None)).unwrap();
        assert!((12..400).all(|x| plain.get_pixel(x, y).0 == [128, 128, 128]));
    }
}
