//! Crown radii of the simulation against the published crown-width functions of stand-grown
//! trees (Döbbeler et al. 2001/2002 and the other functions of the BWINPro/TreeGrOSS species
//! file, cited per species in `species/*.toml`, field `life.stand_crown`; issue 32, Build 1).
//!
//! - The function itself: beech at 20 cm DBH has a crown width of 5.058 m, the figure
//!   TreeGrOSSinR's README gives for `tg_kronenbreite(ba = 'Buche', bhd = 20)`.
//! - Pure, unmanaged stands of the default run's eight species (planted at 1.5 m, 1 ha, at the
//!   species' niche optimum, `sim::pure_stand`), at age 80: the canopy trees (dominant and
//!   co-dominant: height ≥ 0.8 × the top height H100, DBH ≥ 10 cm) have a mean crown radius within
//!   ±20 % of the function's in every 10 cm DBH class holding at least 20 of them (a class mean
//!   over fewer is noise), while the suppressed trees (relative light below 0.25 at the top,
//!   DBH ≥ 7 cm) keep narrower crowns for their diameter (mean ratio to the function at least 0.1
//!   below the canopy trees'). In light-demanding birch and alder stands too few suppressed
//!   trees live (shaded trees of 7 cm die) for the second check; it needs 20 of them.
use sylva::sim::pure_stand::pure_stand_toml;
use sylva::sim::scenario::Scenario;
use sylva::sim::step::{step_year, YearReport};
use sylva::sim::world::World;
use sylva::species::allometry::stand_crown_radius;
use sylva::species::SpeciesLibrary;

#[test]
fn beech_crown_width_is_treegross_own_figure() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let beech = &lib.species[lib.find("beech").unwrap() as usize];
    let r = stand_crown_radius(beech, 20.0, 25.0, 12.0).unwrap();
    assert!((2.0 * r - 5.058341).abs() < 1e-4, "beech crown width at 20 cm: {} m", 2.0 * r);
    // Norway spruce: linear (Nagel 1999), 1.2644 + 0.1072 d
    let spruce = &lib.species[lib.find("norway_spruce").unwrap() as usize];
    let r = stand_crown_radius(spruce, 40.0, 30.0, 15.0).unwrap();
    assert!((2.0 * r - (1.2644 + 0.1072 * 40.0)).abs() < 1e-4, "spruce crown width at 40 cm: {} m", 2.0 * r);
    // black alder: Schröder's crown-length form 0.17998 d^0.75155 (h − cb)^0.35611
    let alder = &lib.species[lib.find("black_alder").unwrap() as usize];
    let r = stand_crown_radius(alder, 30.0, 25.0, 15.0).unwrap();
    let want = 0.17998 * 30f32.powf(0.75155) * 10f32.powf(0.35611);
    assert!((2.0 * r - want).abs() < 1e-3, "alder crown width at 30 cm, 10 m crown: {} m, want {want}", 2.0 * r);
    // every shipped species carries a function
    for sp in &lib.species {
        assert!(sp.life.stand_crown.is_some(), "{} has no stand_crown", sp.id);
    }
}

#[test]
fn canopy_crowns_follow_the_published_crown_widths_and_suppressed_crowns_stay_narrower() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut report = String::new();
    let mut failures = Vec::new();
    for id in ["beech", "sycamore", "norway_maple", "scots_pine", "silver_birch", "norway_spruce", "sessile_oak", "black_alder"] {
        let sp = &lib.species[lib.find(id).unwrap() as usize];
        let years = 77;
        let sc = Scenario::from_toml_str(&pure_stand_toml(sp, 100.0, 1.5, 3.0, years, 7), "pure stand").unwrap();
        let mut w = World::new(sc.site().unwrap(), &lib, &sc).unwrap();
        let mut h100 = 0.0;
        for _ in 0..years {
            let mut r = YearReport::default();
            step_year(&mut w, &sc, &mut r);
            h100 = r.row.as_ref().map(|r| r.top_height_m).unwrap_or(0.0);
        }
        let t = &w.stand.trees;
        let mut classes: std::collections::BTreeMap<u32, Vec<f64>> = Default::default();
        let (mut sup, mut can) = (Vec::new(), Vec::new());
        for i in 0..t.len() {
            let (h, d, cb) = (t.height[i], t.dbh[i], t.crown_base[i]);
            let reference = stand_crown_radius(sp, d, h, cb).unwrap() as f64;
            if d < 7.0 || reference <= 0.0 {
                continue;
            }
            let ratio = t.crown_outline(&lib, i) as f64 / reference;
            if h as f64 >= 0.8 * h100 && d >= 10.0 {
                classes.entry((d / 10.0) as u32).or_default().push(ratio);
                can.push(ratio);
            } else if t.light[i] < 0.25 {
                sup.push(ratio);
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        for (k, v) in &classes {
            if v.len() < 20 {
                continue;
            }
            let m = mean(v);
            report.push_str(&format!("{id} DBH {}-{} cm: {} canopy trees, crown radius {:.2} of the function\n", k * 10, k * 10 + 10, v.len(), m));
            if !(0.8..=1.2).contains(&m) {
                failures.push(format!("{id} DBH class {}-{} cm: {m:.2}", k * 10, k * 10 + 10));
            }
        }
        assert!(classes.values().any(|v| v.len() >= 20), "{id}: no DBH class with 20 canopy trees at age 80 (H100 {h100:.1} m)");
        report.push_str(&format!("{id}: canopy mean {:.2} ({}), suppressed mean {:.2} ({})\n", mean(&can), can.len(), mean(&sup), sup.len()));
        if sup.len() >= 20 && mean(&sup) > mean(&can) - 0.1 {
            failures.push(format!("{id}: suppressed crowns {:.2} of the function, canopy {:.2}", mean(&sup), mean(&can)));
        }
    }
    println!("{report}");
    assert!(failures.is_empty(), "{failures:?}\n{report}");
}
