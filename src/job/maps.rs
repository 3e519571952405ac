//! Condition maps of a simulated site (`RUN_DIR/maps/conditions/`): every field the simulation
//! reads, as a colour PNG with legend and as a GeoTIFF with the site's georeferencing.

use crate::conditions::{factor, SiteConditions};
use crate::grid::Grid;
use crate::output::{geotiff, maps};
use crate::{Error, Result};
use std::path::Path;

/// Writes elevation, slope, aspect, TWI, insolation, wind exposure, temperature and the six
/// Ellenberg-style indices of `site` into `dir` (created), `NAME.png` + `NAME.tif` each.
/// Returns the names written, in order.
///
/// # Errors
/// [`Error::Io`] naming the file that could not be written.
pub fn write_site_maps(site: &SiteConditions, dir: &Path) -> Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let m = &site.mask;
    let masked = |g: &Grid<f32>| Grid { width: g.width, height: g.height, data: g.data.iter().zip(&m.data).map(|(v, ok)| if *ok { *v } else { f32::NAN }).collect::<Vec<f32>>() };
    let index = |k: usize| Grid { width: m.width, height: m.height, data: site.indices.data.iter().zip(&m.data).map(|(v, ok)| if *ok { v[k] } else { f32::NAN }).collect::<Vec<f32>>() };
    use maps::Ramp::*;
    let items: Vec<(&str, Grid<f32>, maps::Ramp, &str, &str, Option<(f32, f32)>)> = vec![
        ("elevation", site.elevation_m.clone(), Terrain, "Elevation", "m", None),
        ("slope", masked(&site.slope_deg), Viridis, "Slope (Horn 1981)", "degrees", None),
        ("aspect", site.aspect_deg.map(|a| if *a < 0.0 { f32::NAN } else { *a }), Cyclic, "Aspect (from north, clockwise)", "degrees", Some((0.0, 360.0))),
        ("twi", masked(&site.twi), Blues, "Topographic wetness index", "ln(m)", None),
        ("insolation", masked(&site.insolation_kwh_m2), Magma, "Annual clear-sky insolation", "kWh/m²/yr", None),
        ("wind_exposure", masked(&site.wind_exposure), Viridis, "Wind exposure", "0–1", Some((0.0, 1.0))),
        ("temperature", masked(&site.temperature_c), BlueRed, "Mean annual temperature", "°C", None),
        ("L", index(factor::L), Magma, "Ellenberg-style L (light)", "1–9", Some((1.0, 9.0))),
        ("T", index(factor::T), BlueRed, "Ellenberg-style T (temperature)", "1–9", Some((1.0, 9.0))),
        ("K", index(factor::K), Viridis, "Ellenberg-style K (continentality)", "1–9", Some((1.0, 9.0))),
        ("F", index(factor::F), Blues, "Ellenberg-style F (moisture)", "1–12", Some((1.0, 12.0))),
        ("R", index(factor::R), Viridis, "Ellenberg-style R (soil reaction)", "1–9", Some((1.0, 9.0))),
        ("N", index(factor::N), Viridis, "Ellenberg-style N (nitrogen)", "1–9", Some((1.0, 9.0))),
    ];
    let mut names = Vec::new();
    for (name, grid, ramp, title, units, range) in items {
        let style = maps::MapStyle { ramp, title: title.to_string(), units: units.to_string(), range, hillshade: None, shade_strength: 0.0 };
        maps::write_field_png_styled(&grid, Some(m), &style, &dir.join(format!("{name}.png")))?;
        geotiff::write_f32(&dir.join(format!("{name}.tif")), &grid, &site.geo)?;
        names.push(name.to_string());
    }
    Ok(names)
}
