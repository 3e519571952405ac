//! Float32 GeoTIFF writer carrying a grid's georeferencing (readable by GDAL/QGIS).
//!
//! Tags: ModelPixelScale (33550) = (pixel_w, pixel_h, 0); ModelTiepoint (33922) =
//! (0, 0, 0, origin_x, origin_y, 0); GeoKeyDirectory (34735) with GTModelType (1024: 1
//! projected, 2 geographic), GTRasterType (1025: 1 PixelIsArea) and ProjectedCSType (3072) or
//! GeographicType (2048) = EPSG when known; GDAL_NODATA (42113) = "nan". Local grids get the
//! scale and tiepoint only. Deflate-compressed strips.

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

/// Encodes `grid` as a Float32 GeoTIFF in memory.
pub fn encode_f32(grid: &Grid<f32>, geo: &GeoRef) -> std::result::Result<Vec<u8>, tiff::TiffError> {
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
        img.write_data(&grid.data)?;
    }
    Ok(buf.into_inner())
}

/// Writes `grid` (row 0 north; NaN = nodata) with `geo`'s georeferencing to `path` atomically.
///
/// Errors: [`OutputError::Encode`] when encoding fails (naming `path`), [`OutputError::Io`] when writing.
pub fn write_f32(path: &Path, grid: &Grid<f32>, geo: &GeoRef) -> Result<()> {
    let bytes = encode_f32(grid, geo).map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "GeoTIFF", message: e.to_string() })?;
    super::write_atomic(path, &bytes)
}
