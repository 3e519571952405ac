//! Pure, unmanaged stands of one species at its niche optimum, run for the density checks
//! (`tests/sim_density.rs`, `examples/yield_check.rs`): the scenario and the yearly stand
//! density of its run. Apart from [`crate::sim::density`] (which the growth phase reads), since
//! it drives the yearly step.

use super::density::{stand_density, StandDensity};
use super::scenario::Scenario;
use super::step::{step_year, YearReport};
use super::world::World;
use crate::error::Result;
use crate::species::{Indicator, Species, SpeciesLibrary};

/// Site indices `[L, T, K, F, R, N]` at a species' niche optimum: each Ellenberg value of the
/// species, and for indifferent ("x") factors the fresh, base-rich values `[5, 5, 2, 5, 6, 6]`
/// (an "x" imposes no limit, [`crate::species::Factor::suitability`]; F 5 is also where an
/// indifferent F's drought limit starts, [`crate::species::INDIFFERENT_OPTIMUM`]): the site
/// suitability is 1 (L is not part of it since round 45).
pub fn niche_optimum(sp: &Species) -> [f32; 6] {
    const DEFAULT: [f32; 6] = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0];
    let n = &sp.niche;
    let f = [&n.l, &n.t, &n.k, &n.f, &n.r, &n.n];
    std::array::from_fn(|i| match f[i].value {
        Indicator::Value(v) => v,
        Indicator::Indifferent(_) => DEFAULT[i],
    })
}

/// Scenario TOML of a pure, unmanaged stand of species `id` planted at `spacing_m` (m) and age
/// `plant_age_yr` (yr) on a flat `side_m × side_m` (m) site at the species' niche optimum
/// ([`niche_optimum`]), latitude 51° N, 200 m a.s.l., run for `years` years.
pub fn pure_stand_toml(sp: &Species, side_m: f64, spacing_m: f64, plant_age_yr: f64, years: u32, seed: u64) -> String {
    let cells = (side_m / 10.0).round().max(1.0) as usize;
    let ix = niche_optimum(sp);
    format!(
        "name = \"pure_{id}\"\nyears = {years}\nseed = {seed}\nspecies = [\"{id}\"]\nclimate = {{ latitude_deg = 51.0 }}\n\
         [terrain]\nuniform = {{ width = {cells}, height = {cells}, cell_m = 10.0, elevation_m = 200.0, indices = {ix:?} }}\n\
         [[start]]\nkind = \"planted\"\nspecies = \"{id}\"\nspacing_m = {spacing_m:?}\nage_yr = {plant_age_yr:?}\n",
        id = sp.id
    )
}

/// One year of a pure stand's development.
#[derive(Debug, Clone, PartialEq)]
pub struct PureStandYear {
    /// Stand age (yr): planting age + years simulated.
    pub age: f64,
    /// Top height H100 (m).
    pub h100_m: f64,
    /// Density of stems ≥ 7 cm DBH (the yield tables' threshold).
    pub d7: StandDensity,
    /// Density of all stems with a DBH (≥ 1.3 m tall).
    pub all: StandDensity,
}

/// Plants and runs a pure stand ([`pure_stand_toml`]) of species `id` from `lib` to age
/// `to_age` (yr), one row per year.
///
/// Errors: unknown species id ([`crate::Error::Invalid`]); scenario errors.
pub fn run_pure_stand(lib: &SpeciesLibrary, id: &str, side_m: f64, spacing_m: f64, plant_age_yr: f64, to_age: f64, seed: u64) -> Result<Vec<PureStandYear>> {
    let sp = lib.species.iter().find(|s| s.id == id).ok_or_else(|| crate::Error::Invalid { context: "pure stand".into(), field: "species".into(), value: id.into(), expected: "a species id of the library".into() })?;
    let years = (to_age - plant_age_yr).round().max(1.0) as u32;
    let sc = Scenario::from_toml_str(&pure_stand_toml(sp, side_m, spacing_m, plant_age_yr, years, seed), "pure stand")?;
    let mut w = World::new(sc.site()?, lib, &sc)?;
    let mut out = Vec::with_capacity(years as usize);
    for _ in 0..years {
        let mut r = YearReport::default();
        step_year(&mut w, &sc, &mut r);
        let h100 = r.row.as_ref().map(|r| r.top_height_m).unwrap_or(0.0);
        out.push(PureStandYear { age: plant_age_yr + w.stand.year as f64, h100_m: h100, d7: stand_density(&w, 7.0), all: stand_density(&w, 0.0) });
    }
    Ok(out)
}
