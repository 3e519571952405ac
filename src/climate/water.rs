//! A monthly soil-water balance and ForClim's drought index (issue 35, round 44): what warming
//! and a drier climate act on.
//!
//! Per site cell and year, twelve months of a bucket model after Bugmann & Cramer (1998, "Improving
//! the behaviour of forest gap models along drought gradients", For. Ecol. Manage. 103:247–263;
//! the scheme of ForClim 2.9 and 3, and of LandClim):
//!
//! - monthly mean temperature `t_m` from the cell's mean annual temperature and the climate's
//!   annual range ([`monthly_temperatures`]), monthly precipitation `P_m` the year's annual
//!   precipitation in equal shares (Sylva choice: no seasonal precipitation cycle);
//! - potential evapotranspiration `PET_m` by Thornthwaite (1948) ([`thornthwaite_pet_mm`]);
//! - soil water `W` (mm, 0 … capacity `C`; [`soil_water_capacity_mm`]) starts the year full in
//!   the coldest month (winter recharge; Sylva choice, so a year needs no state from the year
//!   before);
//! - supply `S = min(C, c_w) · W / C` (Bugmann & Cramer's `c_w · W / kBS`, with `c_w` = 120 mm
//!   per month, [`CW_MM_PER_MONTH`]; the `min` keeps the supply within the water there, as
//!   ForClim 3's correction does), demand `D = PET_m`, actual evapotranspiration `E = min(S, D)`,
//!   then `W ← clamp(W + P_m − E, 0, C)`;
//! - the year's drought index `DI = mean over the growing-season months of 1 − E/D`: the months
//!   of the season ([`in_season`]: April–September north of the equator, October–March south
//!   of it) warmer than [`GROWING_SEASON_C`] (ForClim 3's drought index, the mean of its monthly
//!   `1 − E/D` over a season's months above its degree-day base; 0 no drought … 1 no water for
//!   transpiration) ([`drought_index`]). The calendar window is a Sylva choice: with the
//!   temperature threshold alone a warmer year's season gains cool spring and autumn months of
//!   no drought, and the mean fell under warming (measured: +6 K raised the index of a 700 m
//!   Coweeta cell less than +3 K).
//!
//! Canopy interception (ForClim's `min(k·P, PET)`, which lowers both the water reaching the
//! soil and the demand) is left out: a Sylva choice, stated.
//!
//! The species respond with ForClim's `sqrt(1 − DI / droughtTol)` ([`crate::species::drought_factor`])
//! to the *rise* of the index over the cell's index in the base climate (no temperature offset,
//! precipitation factor 1): the base climate's moisture is what each species' Ellenberg F niche
//! already encodes, so a constant climate leaves every run as it was (`sim::phases::climate`).

use super::Climate;

/// Days of each month (February 28.25: the mean year).
pub const MONTH_DAYS: [f64; 12] = [31.0, 28.25, 31.0, 30.0, 31.0, 30.0, 31.0, 31.0, 30.0, 31.0, 30.0, 31.0];

/// Maximum evapotranspiration rate of a saturated soil under high demand, `c_w` (mm per month):
/// 12 cm per month, Bugmann & Cramer (1998) after Federer (1982, Water Resour. Res. 18:355–362).
pub const CW_MM_PER_MONTH: f64 = 120.0;

/// Growing-season threshold (°C): the months of the season ([`in_season`]) whose mean
/// temperature exceeds it enter the drought index; ForClim's degree-day base temperature
/// `kDTT` = 5.5 °C (Bugmann 1994).
pub const GROWING_SEASON_C: f64 = 5.5;

/// Reference wetness index of [`soil_water_capacity_mm`]: TWI 8, the mid-slope that
/// [`crate::conditions::moisture_index`] maps to F 5 ("fresh", Ellenberg's mid-point), where a
/// cell holds the climate's `soil_water_capacity_mm`.
pub const TWI_REFERENCE: f64 = 8.0;

/// Plant-available water (mm) gained per unit of topographic wetness index above
/// [`TWI_REFERENCE`] (lost below it): TOPMODEL's local storage deficit, linear in the wetness
/// index with the recession parameter `m` (Beven & Kirkby 1979, Hydrol. Sci. Bull. 24:43–69;
/// `D_i = D̄ − m (TWI_i − λ)`), read as water the cell holds beyond (or short of) the site's
/// capacity. `m` = 20 mm: ESTIMATE (not fitted to a catchment).
pub const TWI_WATER_MM: f64 = 20.0;

/// Smallest soil water capacity (mm) of a cell: a ridge's shallow soil still holds some water
/// (ESTIMATE; keeps the bucket from vanishing where the wetness index is low).
pub const MIN_CAPACITY_MM: f64 = 10.0;

/// The climate's water-balance constants (`[climate]` `precipitation_mm`, `temperature_range_k`,
/// `soil_water_capacity_mm`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterClimate {
    /// Annual precipitation of the base climate (mm), uniform over the terrain.
    pub precipitation_mm: f64,
    /// Warmest minus coldest monthly mean temperature (K).
    pub temperature_range_k: f64,
    /// Plant-available soil water capacity (mm) at the reference wetness index.
    pub soil_water_capacity_mm: f64,
}

impl Default for WaterClimate {
    /// The constants of the default `[climate]`.
    fn default() -> Self {
        WaterClimate::of(&Climate::default())
    }
}

impl WaterClimate {
    /// The constants of `c`.
    pub fn of(c: &Climate) -> WaterClimate {
        WaterClimate { precipitation_mm: c.precipitation_mm as f64, temperature_range_k: c.temperature_range_k as f64, soil_water_capacity_mm: c.soil_water_capacity_mm as f64 }
    }

    /// Drought index (0–1) of a cell of mean annual temperature `t_c` (°C), topographic wetness
    /// index `twi` and latitude `latitude_deg`, in a year `dt_k` kelvin warmer than the base
    /// climate with precipitation factor `precip` ([`drought_index`] of the cell's
    /// [`monthly_temperatures`], [`thornthwaite_pet_mm`] and [`soil_water_capacity_mm`]).
    pub fn cell_drought_index(&self, t_c: f64, twi: f64, latitude_deg: f64, dt_k: f64, precip: f64) -> f64 {
        let t = monthly_temperatures(t_c + dt_k, self.temperature_range_k, latitude_deg);
        let pet = thornthwaite_pet_mm(&t, latitude_deg);
        let p = self.precipitation_mm * precip / 12.0;
        drought_index(&t, &[p; 12], &pet, soil_water_capacity_mm(self.soil_water_capacity_mm, twi), latitude_deg)
    }
}

/// Plant-available soil water capacity (mm) of a cell of topographic wetness index `twi` on a
/// site whose capacity at [`TWI_REFERENCE`] is `capacity_mm`: `capacity_mm + m (TWI − 8)`
/// ([`TWI_WATER_MM`], TOPMODEL's linear form), at least [`MIN_CAPACITY_MM`]. A NaN index gives
/// `capacity_mm`.
pub fn soil_water_capacity_mm(capacity_mm: f64, twi: f64) -> f64 {
    let c = if twi.is_finite() { capacity_mm + TWI_WATER_MM * (twi - TWI_REFERENCE) } else { capacity_mm };
    c.max(MIN_CAPACITY_MM)
}

/// The coldest month (0 = January): January north of the equator, July south of it.
pub fn coldest_month(latitude_deg: f64) -> usize {
    if latitude_deg < 0.0 {
        6
    } else {
        0
    }
}

/// Whether month `m` (0 = January) lies in the growing season of the drought index at
/// `latitude_deg`: April–September north of the equator, October–March south of it (Sylva
/// choice, module docs).
pub fn in_season(m: usize, latitude_deg: f64) -> bool {
    let north = (3..=8).contains(&(m % 12));
    if latitude_deg < 0.0 {
        !north
    } else {
        north
    }
}

/// Monthly mean temperatures (°C, January first) of a year of mean `t_annual_c` and annual range
/// `range_k` (warmest minus coldest month) at `latitude_deg`: a cosine with its minimum in the
/// coldest month ([`coldest_month`]) and its maximum six months later,
/// `t_m = t_annual − range/2 · cos(2π (m − m_cold) / 12)` (Sylva choice: the annual cycle of a
/// temperate climate as one harmonic; its mean is `t_annual`).
pub fn monthly_temperatures(t_annual_c: f64, range_k: f64, latitude_deg: f64) -> [f64; 12] {
    let m0 = coldest_month(latitude_deg) as f64;
    std::array::from_fn(|m| t_annual_c - 0.5 * range_k * (2.0 * std::f64::consts::PI * (m as f64 - m0) / 12.0).cos())
}

/// Day length (hours) at latitude `latitude_deg` on day `day_of_year`: `24/π · acos(−tan φ tan δ)`
/// (clamped to polar day and night; declination by [`crate::sun::declination_rad`]).
pub fn day_length_h(latitude_deg: f64, day_of_year: f64) -> f64 {
    let phi = latitude_deg.clamp(-89.9, 89.9).to_radians();
    let x = -phi.tan() * crate::sun::declination_rad(day_of_year).tan();
    24.0 / std::f64::consts::PI * x.clamp(-1.0, 1.0).acos()
}

/// Potential evapotranspiration (mm per month, January first) of the monthly mean temperatures
/// `t` (°C) at `latitude_deg`, by Thornthwaite (1948, "An approach toward a rational
/// classification of climate", Geogr. Rev. 38:55–94): heat index `I = Σ (t_m/5)^1.514` over the
/// months above 0 °C, exponent `a = 6.75·10⁻⁷ I³ − 7.71·10⁻⁵ I² + 1.792·10⁻² I + 0.49239`,
/// `PET_m = 16 (N_m/12) (d_m/30) (10 t_m / I)^a` with `N_m` the day length (h) of the
/// month's middle day ([`day_length_h`]) and `d_m` its days ([`MONTH_DAYS`]); 0 in months at
/// or below 0 °C (and every month when no month is above 0 °C).
pub fn thornthwaite_pet_mm(t: &[f64; 12], latitude_deg: f64) -> [f64; 12] {
    let heat: f64 = t.iter().filter(|&&v| v > 0.0).map(|&v| (v / 5.0).powf(1.514)).sum();
    if heat <= 0.0 {
        return [0.0; 12];
    }
    let a = ((6.75e-7 * heat - 7.71e-5) * heat + 1.792e-2) * heat + 0.49239;
    let mut doy = 0.0;
    std::array::from_fn(|m| {
        let mid = doy + 0.5 * MONTH_DAYS[m];
        doy += MONTH_DAYS[m];
        if t[m] > 0.0 {
            16.0 * (day_length_h(latitude_deg, mid) / 12.0) * (MONTH_DAYS[m] / 30.0) * (10.0 * t[m] / heat).powf(a)
        } else {
            0.0
        }
    })
}

/// ForClim's drought index (0–1) of one year: monthly temperatures `t` (°C), precipitation `p`
/// and potential evapotranspiration `pet` (mm per month, January first), soil water capacity
/// `capacity_mm` (> 0) at latitude `latitude_deg`, the bucket full at the start of the coldest
/// month ([`coldest_month`]); the months in order from there (module docs): supply `min(C, c_w) · W / C`, `E = min(supply, PET)`,
/// `W ← clamp(W + P − E, 0, C)`; the index is the mean of `1 − E/PET` over the season's months
/// warmer than [`GROWING_SEASON_C`] with a demand (0 when there is none).
pub fn drought_index(t: &[f64; 12], p: &[f64; 12], pet: &[f64; 12], capacity_mm: f64, latitude_deg: f64) -> f64 {
    let start = coldest_month(latitude_deg);
    let c = capacity_mm.max(1e-9);
    let rate = c.min(CW_MM_PER_MONTH) / c;
    let mut w = c;
    let (mut sum, mut n) = (0.0, 0u32);
    for k in 0..12 {
        let m = (start + k) % 12;
        let demand = pet[m];
        let e = (rate * w).min(demand);
        w = (w + p[m] - e).clamp(0.0, c);
        if in_season(m, latitude_deg) && t[m] > GROWING_SEASON_C && demand > 0.0 {
            sum += 1.0 - e / demand;
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thornthwaite_and_bucket() {
        // the cycle's mean is the annual mean, its range the range
        let t = monthly_temperatures(8.0, 18.0, 50.0);
        assert!((t.iter().sum::<f64>() / 12.0 - 8.0).abs() < 1e-9);
        assert!((t[0] - -1.0).abs() < 1e-9 && (t[6] - 17.0).abs() < 1e-9);
        assert!((monthly_temperatures(8.0, 18.0, -30.0)[6] - -1.0).abs() < 1e-9);
        // Thornthwaite's unadjusted PET of a month at 26.5 °C is about 13.5 cm whatever the heat
        // index (the point where his nomogram's lines cross), here for a 12-hour, 30-day month
        let flat = [26.5; 12];
        let pet = thornthwaite_pet_mm(&flat, 0.0);
        let unadjusted = pet[3] / ((day_length_h(0.0, 105.0) / 12.0) * (MONTH_DAYS[3] / 30.0));
        assert!((unadjusted - 135.0).abs() < 5.0, "{unadjusted}");
        // equinox day length is 12 h at every latitude, the equator's always
        assert!((day_length_h(50.0, 80.0) - 12.0).abs() < 0.2 && (day_length_h(0.0, 172.0) - 12.0).abs() < 1e-6);
        assert!(day_length_h(50.0, 172.0) > 16.0);
        // no demand or ample rain: no drought; no rain: the bucket drains
        let wet = drought_index(&t, &[200.0; 12], &thornthwaite_pet_mm(&t, 50.0), 150.0, 50.0);
        assert_eq!(wet, 0.0);
        let dry = drought_index(&t, &[0.0; 12], &thornthwaite_pet_mm(&t, 50.0), 150.0, 50.0);
        assert!(dry > 0.5 && dry <= 1.0, "{dry}");
        // warmer or drier years, or smaller buckets, are drier
        let w = WaterClimate { precipitation_mm: 700.0, temperature_range_k: 18.0, soil_water_capacity_mm: 150.0 };
        let base = w.cell_drought_index(9.0, 8.0, 48.0, 0.0, 1.0);
        assert!(w.cell_drought_index(9.0, 8.0, 48.0, 3.0, 1.0) > base);
        assert!(w.cell_drought_index(9.0, 8.0, 48.0, 3.0, 0.8) > w.cell_drought_index(9.0, 8.0, 48.0, 3.0, 1.0));
        assert!(w.cell_drought_index(9.0, 4.0, 48.0, 0.0, 1.0) > base && w.cell_drought_index(9.0, 12.0, 48.0, 0.0, 1.0) < base);
        assert_eq!(soil_water_capacity_mm(150.0, 2.0), 30.0);
        // the season: April–September in the north, October–March in the south
        assert!(in_season(3, 45.0) && in_season(8, 45.0) && !in_season(9, 45.0) && !in_season(2, 45.0));
        assert!(in_season(9, -45.0) && in_season(2, -45.0) && !in_season(5, -45.0));
        // warming by 6 K dries a lowland cell more than by 3 K (with a season set by temperature
        // alone it did not: the cool months a warmer year adds to it have no drought)
        let low = WaterClimate::default();
        let d = |dt: f64| low.cell_drought_index(9.8, 8.0, 35.05, dt, 1.0);
        assert!(d(6.0) - d(3.0) > 0.5 * (d(3.0) - d(0.0)) && d(3.0) > d(0.0), "{} {} {}", d(0.0), d(3.0), d(6.0));
        assert_eq!(soil_water_capacity_mm(150.0, -5.0), MIN_CAPACITY_MM);
    }
}
