//! Climate and soil constants of a scenario: a base module below both `terrain` (whose fields
//! use the latitude, lapse rate and wind direction) and `conditions` (which maps the fields to
//! indices), so that neither imports the other for it (issue 13). Its submodule [`water`] is the
//! monthly water balance (round 44), which the moisture index F reads since round 45.

pub mod water;

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
    /// Continentality index K (1–9), constant over the terrain, when the scenario gives it;
    /// otherwise (the default since round 45) derived from the climate's annual temperature
    /// range and the site's latitude ([`continentality_index`]: Conrad's index mapped onto
    /// Ellenberg's scale), [`Climate::continentality`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continentality_k: Option<f32>,
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
    /// Annual precipitation of the base climate (mm, 50–10000; default 790, about Germany's
    /// 1961–1990 area mean of the Deutscher Wetterdienst), uniform over the terrain, falling in
    /// equal monthly shares; an anomaly year's precipitation is this times its precipitation
    /// factor. Read by the water balance ([`crate::climate::water`]), which acts only under a
    /// changing climate, against the base climate's.
    #[serde(skip_serializing_if = "is_default_precipitation")]
    pub precipitation_mm: f32,
    /// Warmest minus coldest monthly mean temperature (K, 0–60; default 17.4, Germany's
    /// 1961–1990 July 16.9 °C less January −0.5 °C, Deutscher Wetterdienst): the amplitude of
    /// the water balance's annual temperature cycle ([`crate::climate::water::monthly_temperatures`]).
    #[serde(skip_serializing_if = "is_default_range")]
    pub temperature_range_k: f32,
    /// Plant-available soil water capacity (mm, 10–1000; default 150) of a cell at the reference
    /// wetness index (TWI 8, F 5); wetter cells hold more, drier less
    /// ([`crate::climate::water::soil_water_capacity_mm`]). 150 mm: a loam's available water
    /// (field capacity less wilting point, 0.13–0.18 m³/m³: FAO-56, Allen et al. 1998, Table 19)
    /// over a rooting depth of 1 m (ESTIMATE).
    #[serde(skip_serializing_if = "is_default_capacity")]
    pub soil_water_capacity_mm: f32,
}

/// Default [`Climate::precipitation_mm`] (mm).
pub const DEFAULT_PRECIPITATION_MM: f32 = 790.0;
/// Default [`Climate::temperature_range_k`] (K).
pub const DEFAULT_TEMPERATURE_RANGE_K: f32 = 17.4;
/// Default [`Climate::soil_water_capacity_mm`] (mm).
pub const DEFAULT_SOIL_WATER_CAPACITY_MM: f32 = 150.0;

/// Conrad's continentality index (Conrad 1946, "Usual formulas of continentality and their
/// limits of validity", Trans. Am. Geophys. Union 27:663–664): `C = 1.7 A / sin φ − 14`, with
/// `A` the annual temperature range (K, warmest minus coldest monthly mean) and `φ` the
/// latitude; about 0 on the most oceanic coasts (Thorshavn) and 100 in the most continental
/// interior (Verkhoyansk). `|φ|` is taken as at least 10°: the formula is not meant for the
/// tropics (there `sin φ → 0`).
pub fn conrad_index(range_k: f64, latitude_deg: f64) -> f64 {
    let s = latitude_deg.abs().clamp(10.0, 90.0).to_radians().sin();
    1.7 * range_k / s - 14.0
}

/// Ellenberg continentality index K (1–9) of a climate of annual temperature range `range_k`
/// (K) at `latitude_deg`: Conrad's index ([`conrad_index`], 0 … 100) mapped linearly onto
/// Ellenberg's scale (1 euoceanic … 9 eucontinental; Ellenberg et al. 1992, Scripta Geobotanica
/// 18), `K = clamp(1 + 0.08 C, 1, 9)`. The linear map is a Sylva choice: both scales run from
/// the most oceanic to the most continental climate. Values: Germany's range 17.4 K at 50° N
/// gives C 24.6, K 3.0 (Ellenberg's K 3, "most of Central Europe"); Brest (about 10 K at
/// 48.4° N) K 1.7; Moscow (about 26 K at 55.8° N) K 4.4; the default scenario's 17.4 K at
/// Coweeta's 35.05° N K 4.0.
pub fn continentality_index(range_k: f64, latitude_deg: f64) -> f32 {
    (1.0 + 0.08 * conrad_index(range_k, latitude_deg)).clamp(1.0, 9.0) as f32
}

impl Climate {
    /// The continentality index K (1–9) of the site at `latitude_deg` (the latitude the
    /// terrain's insolation uses): `continentality_k` where the scenario gives it, else
    /// [`continentality_index`] of `temperature_range_k`.
    pub fn continentality(&self, latitude_deg: f64) -> f32 {
        self.continentality_k.unwrap_or_else(|| continentality_index(self.temperature_range_k as f64, latitude_deg))
    }
}

fn is_default_precipitation(v: &f32) -> bool {
    *v == DEFAULT_PRECIPITATION_MM
}

fn is_default_range(v: &f32) -> bool {
    *v == DEFAULT_TEMPERATURE_RANGE_K
}

fn is_default_capacity(v: &f32) -> bool {
    *v == DEFAULT_SOIL_WATER_CAPACITY_MM
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
            continentality_k: None,
            reaction_r: 6.0,
            nitrogen_n: 5.0,
            sea_level_m: 0.0,
            wind_from_deg: 270.0,
            warming_k_per_century: 0.0,
            anomalies_file: None,
            precipitation_mm: DEFAULT_PRECIPITATION_MM,
            temperature_range_k: DEFAULT_TEMPERATURE_RANGE_K,
            soil_water_capacity_mm: DEFAULT_SOIL_WATER_CAPACITY_MM,
        }
    }
}
