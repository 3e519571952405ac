//! The water balance a changing climate acts on (issue 35, round 44: trial 43 defect 7, "warming
//! that bites"): each year every cell's monthly bucket (Thornthwaite PET, ForClim's drought
//! index, `sim::water`) under the year's temperature and precipitation, against the base
//! climate's; each species' growth and establishment cut by ForClim's drought factor of the
//! rise (`sim::phases::climate`).
//!
//! On the Coweeta window of the default scenario (its climate: 9.5 °C at 750 m, −6.5 K/km) with
//! the default water balance (790 mm, annual range 17.4 K, 150 mm at TWI 8).

mod common;
use common::ScenarioToml;
use sylva::sim::water::WaterClimate;

/// A 1.2 km × 0.9 km part of the default scenario's Coweeta window (its north-west quarter: the
/// first 120 of its 240 columns and 90 of its 180 rows, row 0 north).
const WINDOW: [usize; 4] = [160, 220, 120, 90];

/// The embedded Coweeta DEM (the default scenario's terrain), window [`WINDOW`].
fn coweeta() -> String {
    format!("[terrain]\nembedded = \"coweeta\"\nwindow = {WINDOW:?}")
}

/// The default scenario's climate with the anomalies file `csv` written into `dir`.
fn climate_line(dir: &std::path::Path, csv: &str) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("anomalies.csv");
    std::fs::write(&p, csv).unwrap();
    format!("climate = {{ latitude_deg = 35.05, reference_temperature_c = 9.5, reference_elevation_m = 750.0, lapse_rate_k_per_km = -6.5, continentality_k = 4.0, reaction_r = 6.0, nitrogen_n = 5.0, anomalies_file = {:?} }}", p.display().to_string())
}

/// Every year 1–`years` `dt` kelvin warmer with precipitation factor `pf`.
fn anomalies(years: u32, dt: f64, pf: f64) -> String {
    let mut s = String::from("year,temperature_k,precipitation_factor\n");
    for y in 1..=years {
        s.push_str(&format!("{y},{dt},{pf}\n"));
    }
    s
}

/// The elevations (m) below which a third of the window's cells lie, and above which a third.
fn thirds(w: &sylva::sim::World) -> (f32, f32) {
    let c = &w.site.conditions;
    let mut z: Vec<f32> = (0..c.mask.data.len()).filter(|&k| c.mask.data[k]).map(|k| c.elevation_m.data[k]).collect();
    z.sort_by(f32::total_cmp);
    (z[z.len() / 3], z[2 * z.len() / 3])
}

/// One year 3 K warmer (precipitation as the base climate's): every cell's suitability for
/// Norway spruce (drought tolerance 0.15) and beech (0.25) is that of the warmer indices with F
/// lowered by 10 × the cell's rise of the drought index (round 45; round 44 multiplied the
/// niche by ForClim's `sqrt(1 − rise / tolerance)`), whose drought limit is ForClim's factor;
/// the rise is positive, and larger in the lowest third of the window (warmest, highest PET)
/// than in the highest. Before round 44 warming did not touch the drought term.
#[test]
fn warming_raises_the_drought_index_most_in_the_lowlands_and_cuts_suitability_by_tolerance() {
    let dir = std::env::temp_dir().join(format!("sylva_water_suit_{}", std::process::id()));
    let toml = ScenarioToml::new("water", 1, 1).species(&["beech", "norway_spruce"]).line("snapshot_every = 0").line("checkpoint_every = 0").line(&climate_line(&dir, &anomalies(1, 3.0, 1.0))).line(&coweeta()).build();
    let lib = common::embedded();
    let (sc, mut w) = common::world_with(&toml, &lib);
    common::run(&sc, &mut w, 1);
    let _ = std::fs::remove_dir_all(&dir);
    let (low, high) = thirds(&w);
    let c = &w.site.conditions;
    let water = WaterClimate::of(&sc.climate);
    assert_eq!((water.precipitation_mm, water.temperature_range_k, water.soil_water_capacity_mm), (790.0, 17.4f32 as f64, 150.0));
    let lat = c.geo.latitude_deg;
    let (mut rise_low, mut n_low, mut rise_high, mut n_high, mut checked) = (0.0, 0, 0.0, 0, 0);
    for (p, id) in ["beech", "norway_spruce"].iter().enumerate() {
        let s = lib.find(id).unwrap();
        let sp = &lib.species[s as usize];
        let p = w.site.pool.iter().position(|&q| q == s).unwrap_or(p);
        let tol = sp.life.drought_tolerance.unwrap() as f64;
        for k in (0..c.mask.data.len()).filter(|&k| c.mask.data[k]).step_by(7) {
            let (t, twi) = (c.temperature_c.data[k] as f64, c.twi.data[k] as f64);
            let rise = (water.cell_drought_index(t, twi, lat, 3.0, 1.0) - water.cell_drought_index(t, twi, lat, 0.0, 1.0)).max(0.0);
            let niche = sp.suitability(&sylva::sim::climate_change::shifted_indices(&c.indices.data[k], 3.0)) as f64;
            if niche < 0.05 {
                continue;
            }
            // round 45: the rise lowers F by 10 per unit, and the species' niche and drought
            // limit (ForClim's factor of the drought beyond its F optimum, its tolerance) of
            // the year's indices are the suitability
            let ix = sylva::sim::climate_change::year_indices(&c.indices.data[k], 3.0, rise as f32);
            assert!((ix[3] as f64 - (c.indices.data[k][3] as f64 - 10.0 * rise).max(1.0)).abs() < 1e-4);
            let v = match &sp.niche.f.value { sylva::species::Indicator::Value(v) => (*v).min(6.0) as f64, _ => 5.0 };
            let limit = (1.0 - ((v - ix[3] as f64).max(0.0) / 10.0) / tol).max(0.0).sqrt();
            assert!((sp.drought_limit(ix[3]) as f64 - limit).abs() < 1e-4, "{id} cell {k}: drought limit {} against ForClim's {limit}", sp.drought_limit(ix[3]));
            let want = sp.suitability(&ix) as f64;
            let got = w.site.suitability[p][k] as f64;
            assert!((got - want).abs() < 1e-5, "{id} cell {k} ({:.0} m, {t:.1} °C, TWI {twi:.1}): suitability {got:.5}, of the year's indices (rise {rise:.4}) {want:.5}", c.elevation_m.data[k]);
            checked += 1;
            if p == 0 {
                let z = c.elevation_m.data[k];
                if z < low {
                    rise_low += rise;
                    n_low += 1;
                } else if z > high {
                    rise_high += rise;
                    n_high += 1;
                }
            }
        }
    }
    let (rl, rh) = (rise_low / n_low.max(1) as f64, rise_high / n_high.max(1) as f64);
    eprintln!("{checked} cells checked; +3 K raises the drought index by {rl:.4} below {low:.0} m ({n_low} cells), by {rh:.4} above {high:.0} m ({n_high} cells)");
    assert!(checked > 1000, "{checked}");
    assert!(rl > 0.01, "mean rise in the lowest third {rl}");
    assert!(rl > rh, "rise in the lowest third {rl}, in the highest {rh}");
}

/// Mean basal-area increment (cm² per tree and year) of the planted beech standing in the
/// lowest third of the window's elevations, over `years` years each 3 K warmer than the base
/// climate with precipitation factor `pf` (beech planted 20 m apart at 40 years, as the
/// management warming test).
fn beech_bai_lowlands(years: u32, pf: f64) -> f64 {
    let dir = std::env::temp_dir().join(format!("sylva_water_bai_{}_{pf}", std::process::id()));
    let toml = ScenarioToml::new("water", years, 3).species(&["beech"]).line("snapshot_every = 0").line("checkpoint_every = 0").line(&climate_line(&dir, &anomalies(years, 3.0, pf))).line(&coweeta()).planted("beech", 20.0, 40.0).build();
    let lib = common::embedded();
    let (sc, mut w) = common::world_with(&toml, &lib);
    let (low, _) = thirds(&w);
    let t = &w.stand.trees;
    let before: std::collections::BTreeMap<u64, f32> = (0..t.len()).filter(|&i| t.z[i] < low).map(|i| (t.id[i], t.dbh[i])).collect();
    common::run(&sc, &mut w, years);
    let _ = std::fs::remove_dir_all(&dir);
    let t = &w.stand.trees;
    let g: Vec<f64> = (0..t.len()).filter_map(|i| before.get(&t.id[i]).map(|d0| std::f64::consts::PI / 4.0 * ((t.dbh[i] as f64).powi(2) - (*d0 as f64).powi(2)))).collect();
    assert!(g.len() > 200, "{} beech in the lowlands", g.len());
    g.iter().sum::<f64>() / g.len() as f64 / years as f64
}

/// Issue 35's drier warming: +3 K with 80 % of the precipitation cuts the basal-area increment of
/// beech in the lowest third of the window more than +3 K alone (the precipitation factor acts
/// through the water balance only; with it ignored the two runs are the same).
#[test]
fn a_drier_warming_cuts_beech_growth_in_the_lowlands_more_than_warming_alone() {
    let years = 4;
    let (warm, dry) = (beech_bai_lowlands(years, 1.0), beech_bai_lowlands(years, 0.8));
    eprintln!("beech basal-area increment in the lowest third: +3 K {warm:.3} cm²/yr, +3 K and precipitation × 0.8 {dry:.3} cm²/yr (× {:.3})", dry / warm);
    assert!(warm > 0.5, "{warm}");
    assert!(dry < 0.95 * warm, "+3 K: {warm:.3} cm²/yr, +3 K and × 0.8: {dry:.3}");
}
