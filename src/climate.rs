//! Climate and soil constants of a scenario: a base module below both `terrain` (whose fields
//! use the latitude, lapse rate and wind direction) and `conditions` (which maps the fields to
//! indices), so that neither imports the other for it (issue 13).

/// Climate and soil constants of a scenario that, with the terrain, give the living conditions.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Climate {
    /// Latitude (degrees, −90…90) for insolation when the terrain is not geographic.
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
        }
    }
}
