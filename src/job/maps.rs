//! Condition maps of a simulated site (`RUN_DIR/maps/conditions/`): every field the simulation
//! reads, as a colour PNG with legend and as a GeoTIFF with the site's georeferencing.

use crate::conditions::{factor, SiteConditions};
use crate::grid::Grid;
use crate::output::{geotiff, maps};
use super::Result;
use crate::Error;
use std::path::Path;

/// One condition map: file stem, field (row 0 north, NaN = no data), colour ramp, title, units
/// and optional fixed value range.
pub struct Layer {
    /// File stem (`NAME.png`, `NAME.tif`).
    pub name: &'static str,
    /// The field.
    pub grid: Grid<f32>,
    /// Colour ramp of the PNG.
    pub ramp: maps::Ramp,
    /// Title drawn above the map.
    pub title: String,
    /// Units under the colour bar.
    pub units: &'static str,
    /// Fixed colour-bar range, else the field's range.
    pub range: Option<(f32, f32)>,
}

/// The maps of every field a site holds, in order: elevation, slope, aspect, TWI, insolation,
/// wind exposure, temperature, then the Ellenberg-style L, T, K, F, R, N. Masked cells are NaN.
/// `flat_insolation_kwh_m2` and `wind_from_deg` only enrich the titles.
pub fn site_layers(site: &SiteConditions, flat_insolation_kwh_m2: Option<f64>, wind_from_deg: Option<f32>) -> Vec<Layer> {
    let m = &site.mask;
    let masked = |g: &Grid<f32>| Grid { width: g.width, height: g.height, data: g.data.iter().zip(&m.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect::<Vec<f32>>() };
    let index = |k: usize| Grid { width: m.width, height: m.height, data: site.indices.data.iter().zip(&m.data).map(|(v, ok)| if *ok { v[k] } else { f32::NAN }).collect::<Vec<f32>>() };
    let layer = |name, grid, ramp, title: String, units, range| Layer { name, grid, ramp, title, units, range };
    use maps::Ramp::*;
    vec![
        layer("elevation", site.elevation_m.clone(), Terrain, "Elevation".into(), "m", None),
        layer("slope", masked(&site.slope_deg), Viridis, "Slope (Horn 1981)".into(), "degrees", None),
        layer("aspect", masked(&site.aspect_deg.map(|a| if *a < 0.0 { f32::NAN } else { *a })), Cyclic, "Aspect (from north, clockwise)".into(), "degrees", Some((0.0, 360.0))),
        layer("twi", masked(&site.twi), Blues, "Topographic wetness index".into(), "ln(m)", None),
        layer("insolation", masked(&site.insolation_kwh_m2), Magma, match flat_insolation_kwh_m2 {
            Some(f) => format!("Annual clear-sky insolation (flat {f:.0})"),
            None => "Annual clear-sky insolation".into(),
        }, "kWh/m²/yr", None),
        layer("wind_exposure", masked(&site.wind_exposure), Viridis, match wind_from_deg {
            Some(d) => format!("Wind exposure (wind from {d}°)"),
            None => "Wind exposure".into(),
        }, "0–1", Some((0.0, 1.0))),
        layer("temperature", masked(&site.temperature_c), BlueRed, "Mean annual temperature".into(), "°C", None),
        layer("L", index(factor::L), Magma, "Ellenberg-style L (light)".into(), "1–9", Some((1.0, 9.0))),
        layer("T", index(factor::T), BlueRed, "Ellenberg-style T (temperature)".into(), "1–9", Some((1.0, 9.0))),
        layer("K", index(factor::K), Viridis, "Ellenberg-style K (continentality)".into(), "1–9", Some((1.0, 9.0))),
        layer("F", index(factor::F), Blues, "Ellenberg-style F (moisture)".into(), "1–12", Some((1.0, 12.0))),
        layer("R", index(factor::R), Viridis, "Ellenberg-style R (soil reaction)".into(), "1–9", Some((1.0, 9.0))),
        layer("N", index(factor::N), Viridis, "Ellenberg-style N (nitrogen)".into(), "1–9", Some((1.0, 9.0))),
    ]
}

/// Writes each layer into `dir` (created) as `NAME.png` (legend, colour bar; shaded by
/// `hillshade` at strength `shade` when given) and `NAME.tif` (Float32 GeoTIFF with `geo`).
/// Returns the names written, in order.
///
/// # Errors
/// [`Error::Io`] naming the file that could not be written.
pub fn write_layers(layers: &[Layer], mask: &Grid<bool>, geo: &crate::grid::GeoRef, dir: &Path, hillshade: Option<(&Grid<f32>, f32)>) -> Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut names = Vec::new();
    for l in layers {
        let shade = if l.name == "hillshade" { None } else { hillshade };
        let style = maps::MapStyle { ramp: l.ramp, title: l.title.clone(), units: l.units.to_string(), range: l.range, hillshade: shade.map(|s| s.0), shade_strength: shade.map_or(0.0, |s| s.1), cell_m: Some(geo.cell_x_m_at_row(mask.height / 2)) };
        maps::write_field_png_styled(&l.grid, Some(mask), &style, &dir.join(format!("{}.png", l.name)))?;
        geotiff::write_f32_band(&dir.join(format!("{}.tif", l.name)), &l.grid, geo, Some(geotiff::Band { description: &l.title, unit: l.units }))?;
        names.push(l.name.to_string());
    }
    Ok(names)
}

/// Writes elevation, slope, aspect, TWI, insolation, wind exposure, temperature and the six
/// Ellenberg-style indices of `site` into `dir` (created), `NAME.png` + `NAME.tif` each
/// ([`site_layers`], [`write_layers`]). Returns the names written, in order.
///
/// # Errors
/// [`Error::Io`] naming the file that could not be written.
pub fn write_site_maps(site: &SiteConditions, dir: &Path) -> Result<Vec<String>> {
    write_layers(&site_layers(site, None, None), &site.mask, &site.geo, dir, None)
}
