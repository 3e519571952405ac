//! Float32 GeoTIFF writer carrying a grid's georeferencing (readable by GDAL/QGIS), and a
//! categorical Byte writer with a colour table ([`write_u8_palette_band`]).
//!
//! Tags: ModelPixelScale (33550) = (pixel_w, pixel_h, 0); ModelTiepoint (33922) =
//! (0, 0, 0, origin_x, origin_y, 0); GeoKeyDirectory (34735) with GTModelType (1024: 1
//! projected, 2 geographic), GTRasterType (1025: 1 PixelIsArea) and ProjectedCSType (3072) or
//! GeographicType (2048) = EPSG when known; GDAL_NODATA (42113) = "nan"; GDAL_METADATA (42112)
//! with the band's description and unit when given ([`Band`]: `gdalinfo` shows them as
//! `Description` and `Unit Type`, QGIS as the band name). Local grids get the scale and
//! tiepoint only. Deflate-compressed strips.

use super::{OutputError, Result};
use crate::grid::{Crs, GeoRef, Grid};
use std::path::Path;
use tiff::encoder::{colortype, Compression, TiffEncoder};
use tiff::tags::Tag;

/// GeoKeyDirectory entries for `geo` (GeoTIFF 1.0 spec §2.4).
fn geokeys(geo: &GeoRef) -> Option<Vec<u16>> {
    let (model, key) = match geo.crs {
        Crs::Projected => (1u16, 3072u16),
        Crs::Geographic => (2, 2048),
        Crs::Local => return None,
    };
    let mut k = vec![1u16, 1, 0, 2, 1024, 0, 1, model, 1025, 0, 1, 1];
    if let Some(e) = geo.epsg.and_then(|e| u16::try_from(e).ok()) {
        k.extend_from_slice(&[key, 0, 1, e]);
        k[3] = 3;
    }
    Some(k)
}

/// What a map's single band holds: a description (e.g. "Annual clear-sky insolation") and its
/// unit (e.g. "kWh/m²/yr"), written as GDAL_METADATA (42112) items `DESCRIPTION` and
/// `UNITTYPE` of band 0. TIFF text is ASCII, so ² ³ ° – × are written as 2, 3, deg, -, x
/// ([`ascii_text`]).
#[derive(Clone, Copy, Debug)]
pub struct Band<'a> {
    /// What the values are.
    pub description: &'a str,
    /// Their unit ("1" or a range such as "1–9" for indices).
    pub unit: &'a str,
}

/// `s` in 7-bit ASCII for a TIFF text tag, XML-escaped: ² ³ → 2 3, ° → deg, – — → -, × → x,
/// any other non-ASCII character → `?`.
pub fn ascii_text(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '²' => o.push('2'),
            '³' => o.push('3'),
            '°' => o.push_str("deg"),
            '–' | '—' | '−' => o.push('-'),
            '×' => o.push('x'),
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c if c.is_ascii() && c != '\0' => o.push(c),
            _ => o.push('?'),
        }
    }
    o
}

/// The GDAL_METADATA XML of `band` (GDAL's PAM layout: items with `sample="0"` and a `role`).
fn gdal_metadata(band: &Band) -> String {
    format!(
        "<GDALMetadata>\n  <Item name=\"DESCRIPTION\" sample=\"0\" role=\"description\">{}</Item>\n  <Item name=\"UNITTYPE\" sample=\"0\" role=\"unittype\">{}</Item>\n</GDALMetadata>\n",
        ascii_text(band.description),
        ascii_text(band.unit)
    )
}

/// Encodes `grid` as a Float32 GeoTIFF in memory.
pub fn encode_f32(grid: &Grid<f32>, geo: &GeoRef) -> std::result::Result<Vec<u8>, tiff::TiffError> {
    encode_f32_band(grid, geo, None)
}

/// [`encode_f32`] with the band's description and unit ([`Band`]) when given.
pub fn encode_f32_band(grid: &Grid<f32>, geo: &GeoRef, band: Option<Band>) -> std::result::Result<Vec<u8>, tiff::TiffError> {
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf)?.with_compression(Compression::Deflate(Default::default()));
        let mut img = enc.new_image::<colortype::Gray32Float>(grid.width as u32, grid.height as u32)?;
        let e = img.encoder();
        e.write_tag(Tag::ModelPixelScaleTag, &[geo.pixel_w, geo.pixel_h, 0.0][..])?;
        e.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, geo.origin_x, geo.origin_y, 0.0][..])?;
        if let Some(k) = geokeys(geo) {
            e.write_tag(Tag::GeoKeyDirectoryTag, &k[..])?;
        }
        e.write_tag(Tag::GdalNodata, "nan")?;
        if let Some(b) = band {
            e.write_tag(Tag::Unknown(42112), gdal_metadata(&b).as_str())?;
        }
        img.write_data(&grid.data)?;
    }
    Ok(buf.into_inner())
}

/// Writes `grid` (row 0 north; NaN = nodata) with `geo`'s georeferencing to `path` atomically.
///
/// Errors: [`OutputError::Encode`] when encoding fails (naming `path`), [`OutputError::Io`] when writing.
pub fn write_f32(path: &Path, grid: &Grid<f32>, geo: &GeoRef) -> Result<()> {
    write_f32_band(path, grid, geo, None)
}

/// [`write_f32`] with the band's description and unit ([`Band`]) when given.
///
/// Errors: as [`write_f32`].
pub fn write_f32_band(path: &Path, grid: &Grid<f32>, geo: &GeoRef, band: Option<Band>) -> Result<()> {
    let bytes = encode_f32_band(grid, geo, band).map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "GeoTIFF", message: e.to_string() })?;
    super::write_atomic(path, &bytes)
}

/// Encodes a categorical `grid` (codes 0–255, row 0 north) as a Byte GeoTIFF with a colour
/// table: PhotometricInterpretation 3 (palette) and ColorMap (320) of 256 entries, entry `k`
/// the sRGB colour `palette[k]` scaled to 16 bits (entries past the palette black), GDAL_NODATA
/// = `nodata`, `geo`'s georeferencing and `band` as [`encode_f32_band`] writes them. GDAL reads
/// it as a Byte band with a colour table and QGIS draws it in those colours (trial 37: the
/// species codes were Float32 without colours).
pub fn encode_u8_palette_band(grid: &Grid<u8>, geo: &GeoRef, band: Option<Band>, palette: &[[u8; 3]], nodata: u8) -> std::result::Result<Vec<u8>, tiff::TiffError> {
    let mut map = vec![0u16; 3 * 256];
    for (k, c) in palette.iter().take(256).enumerate() {
        for ch in 0..3 {
            map[ch * 256 + k] = c[ch] as u16 * 257;
        }
    }
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf)?.with_compression(Compression::Deflate(Default::default()));
        let mut img = enc.new_image::<colortype::Gray8>(grid.width as u32, grid.height as u32)?;
        let e = img.encoder();
        e.write_tag(Tag::PhotometricInterpretation, 3u16)?;
        e.write_tag(Tag::ColorMap, &map[..])?;
        e.write_tag(Tag::ModelPixelScaleTag, &[geo.pixel_w, geo.pixel_h, 0.0][..])?;
        e.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, geo.origin_x, geo.origin_y, 0.0][..])?;
        if let Some(k) = geokeys(geo) {
            e.write_tag(Tag::GeoKeyDirectoryTag, &k[..])?;
        }
        e.write_tag(Tag::GdalNodata, nodata.to_string().as_str())?;
        if let Some(b) = band {
            e.write_tag(Tag::Unknown(42112), gdal_metadata(&b).as_str())?;
        }
        img.write_data(&grid.data)?;
    }
    Ok(buf.into_inner())
}

/// Writes [`encode_u8_palette_band`] of `grid` to `path` atomically.
///
/// Errors: as [`write_f32`].
pub fn write_u8_palette_band(path: &Path, grid: &Grid<u8>, geo: &GeoRef, band: Option<Band>, palette: &[[u8; 3]], nodata: u8) -> Result<()> {
    let bytes = encode_u8_palette_band(grid, geo, band, palette, nodata).map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "GeoTIFF", message: e.to_string() })?;
    super::write_atomic(path, &bytes)
}
