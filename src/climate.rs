//! Climate and soil constants of a scenario: a base module below both `terrain` (whose fields
//! use the latitude, lapse rate and wind direction) and `conditions` (which maps the fields to
//! indices), so that neither imports the other for it (issue 13).

/// Climate and soil constants of a scenario that, with the terrain, give the living conditions.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Climate {
    /// Latitude (degrees, −90…90) for insolation, the sun of the pictures and the stands' sky
    /// where the terrain's CRS gives none: PNG heightmaps, generated and uniform sites, projected
    /// DEMs of a CRS Sylva cannot invert. A geographic DEM, or a projected one with a UTM code
    /// on WGS 84, NAD83 or ETRS89 or a `.prj`, uses its own (`GeoRef::insolation_latitude_deg`).
    pub latitude_deg: f64,
    /// Mean annual temperature (°C) at `reference_elevation_m`.
    pub reference_temperature_c: f32,
    /// Elevation (m) at which `reference_temperature_c` holds.
    pub reference_elevation_m: f32,
    /// Temperature lapse rate (K per km, negative = cooling upwards); default −6.5.
    pub lapse_rate_k_per_km: f32,
    /// Continentality index K (1–9), constant over the terrain.
    pub continentality_k: f32,
    /// Soil reaction index R (1–9), constant over the terrain.
    pub reaction_r: f32,
    /// Nitrogen index N (1–9), constant over the terrain.
    pub nitrogen_n: f32,
    /// Cells at or below this elevation (m) are water and masked.
    pub sea_level_m: f32,
    /// Direction the prevailing wind comes from (degrees clockwise from north).
    pub wind_from_deg: f32,
    /// Linear warming (K per century, −20…20; default 0): the mean annual temperature of every
    /// cell rises by `warming_k_per_century · Y / 100` in simulation year `Y` (the stand table's
    /// year), a ramp from year 0. Moves the temperature index T of every cell each year
    /// (`sim::climate_change`); the terrain fields are not recomputed.
    #[serde(skip_serializing_if = "is_zero")]
    pub warming_k_per_century: f32,
    /// A CSV of yearly anomalies `year,temperature_k[,precipitation_factor]` (a header line
    /// allowed; `#` comments), added to the ramp of `warming_k_per_century`; years not listed have
    /// none. Relative paths are relative to the scenario file (stored absolute in a run's copy).
    /// Read and checked by `sim::climate_change::ClimateChange::of` (errors name the file and
    /// line).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anomalies_file: Option<std::path::PathBuf>,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

impl Default for Climate {
    fn default() -> Self {
        Climate {
            latitude_deg: 46.0,
            reference_temperature_c: 9.0,
            reference_elevation_m: 300.0,
            lapse_rate_k_per_km: -6.5,
            continentality_k: 4.0,
            reaction_r: 6.0,
            nitrogen_n: 5.0,
            sea_level_m: 0.0,
            wind_from_deg: 270.0,
            warming_k_per_century: 0.0,
            anomalies_file: None,
        }
    }
}
