//! Helpers shared by the sim_* tests.
#![allow(dead_code)]
use sylva::species::SpeciesLibrary;
use sylva::sim::stats::StandRow;
use sylva::sim::{fixtures, step_year, Scenario, World, YearReport};

/// Builds the world of a scenario with a uniform terrain, using the fixture species.
pub fn world(toml: &str) -> (Scenario, World) {
    world_with(toml, &fixtures::library())
}

/// Builds the world of a scenario (any terrain) with species from `lib`.
pub fn world_with(toml: &str, lib: &SpeciesLibrary) -> (Scenario, World) {
    let sc = Scenario::from_toml_str(toml, "test").unwrap();
    let site = sc.site().unwrap();
    let w = World::new(site, lib, &sc).unwrap();
    (sc, w)
}

/// The species shipped in species/.
pub fn embedded() -> SpeciesLibrary {
    SpeciesLibrary::embedded().unwrap()
}

/// Steps `n` years and returns the rows.
pub fn run(sc: &Scenario, w: &mut World, n: u32) -> Vec<StandRow> {
    (0..n)
        .map(|_| {
            let mut r = YearReport::default();
            step_year(w, sc, &mut r);
            r.row.unwrap()
        })
        .collect()
}

/// Least-squares slope of y on x.
pub fn slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}
