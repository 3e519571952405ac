//! Issue 35 round 37: BWINPro/TreeGrOSS's crown-competition index C66 as the crowding phase
//! computes it for species with `life.bai_bwinpro` (`sylva::sim::density::Crowding::c66`):
//! the crown cross-sections of the neighbourhood's trees at 2/3 of the tree's crown length
//! below its top, per m² of the neighbourhood.
mod common;

use sylva::sim::density::{crowding, neighbour_weight, MIN_DBH_CM};
use sylva::species::BaiBwinpro;

/// Beech's block 211 of TreeGrOSS's `ForestSimulatorNWGermany6.xml` (as species/beech.toml
/// would carry it).
fn bwinpro_beech() -> BaiBwinpro {
    BaiBwinpro { a0: 2.6518, csa: 1.0414, age: -0.6322, c66: -0.555, bias0: -22.77, bias1: 1.417, bias2: 0.03803, bias3: -0.002403, bias4: 0.00003191, bias5: -0.0000001202, youth_hd: 1.40, period_sigma: None }
}

/// A 30 m × 30 m site (3 × 3 crowding cells) planted with beech at 1.5 m, every tree set to
/// 20 cm and 20 m: the trees of the middle cell see the whole site, and as every crown is cut at
/// its own 2/3 point their C66 is the whole site's crown cover, its cells weighted 1–2–1 per
/// axis since round 43 (`density::neighbour_weight`): Σ w π r² / (16 · 100 m²) (r the
/// stand-grown crown radius at 20 cm, Döbbeler's beech: 2.529 m; 400 trees: 8.49; with the
/// equal weights before, N π r² / 900 m² = 8.93, which the weighted sum fails). Shorter trees
/// (5 m, 5 cm, every other one) are below the tall trees' cut and do not count for them; below
/// 7 cm a tree gets no C66. Without the field no C66 is computed.
#[test]
fn c66_of_a_closed_stand_is_its_crown_cover_at_two_thirds() {
    let toml = common::ScenarioToml::new("c66", 1, 1).species(&["beech"]).uniform_indices(3, 3, 10.0, 200.0, [3.0, 5.0, 2.0, 5.0, 6.0, 6.0]).planted("beech", 1.5, 20.0).build();
    let mut lib = common::embedded();
    let b = lib.find("beech").unwrap() as usize;
    lib.species[b].life.bai_bwinpro = None;
    let (_, w0) = common::world_with(&toml, &lib);
    assert!(crowding(&w0.site, &w0.stand.trees).c66.is_empty(), "C66 computed though no species has the field");
    lib.species[b].life.bai_bwinpro = Some(bwinpro_beech());
    let (_, mut w) = common::world_with(&toml, &lib);
    let n = w.stand.trees.len();
    assert!(n >= 300, "{n} trees planted");
    let r = sylva::species::allometry::stand_crown_radius(&lib.species[b], 20.0, 20.0, 0.0).unwrap();
    assert!((r - 2.529).abs() < 0.005, "{r}");
    let middle = |w: &sylva::sim::World, i: usize| (10.0..20.0).contains(&w.stand.trees.x[i]) && (10.0..20.0).contains(&w.stand.trees.y[i]);
    for i in 0..n {
        w.stand.trees.dbh[i] = 20.0;
        w.stand.trees.height[i] = 20.0;
    }
    let c = crowding(&w.site, &w.stand.trees);
    // the middle cell's neighbourhood is the whole 3 × 3 site, its cells weighted 1–2–1 per
    // axis (`neighbour_weight`, round 43): the crown area of the trees `of` counts by their
    // cell's weight, over the weighted ground (16 cells' worth of 100 m²)
    let weighted = |w: &sylva::sim::World, of: &dyn Fn(usize) -> bool| {
        (0..n).filter(|&i| of(i)).map(|i| neighbour_weight((w.stand.trees.x[i] / 10.0).floor() as isize - 1, (w.stand.trees.y[i] / 10.0).floor() as isize - 1)).sum::<f64>() as f32
    };
    let want = weighted(&w, &|_| true) * std::f32::consts::PI * r * r / 1600.0;
    let mid: Vec<usize> = (0..n).filter(|&i| middle(&w, i)).collect();
    assert!(mid.len() > 20);
    for &i in &mid {
        assert!((c.c66[i] - want).abs() < 1e-3 * want, "tree {i}: C66 {} want {want}", c.c66[i]);
        assert!((c.h100[i] - 20.0).abs() < 1e-6);
    }
    // every other tree short and thin: out of the tall trees' C66
    for i in (0..n).step_by(2) {
        w.stand.trees.dbh[i] = 5.0;
        w.stand.trees.height[i] = 5.0;
    }
    let c = crowding(&w.site, &w.stand.trees);
    let want = weighted(&w, &|i| i % 2 == 1) * std::f32::consts::PI * r * r / 1600.0;
    for &i in &mid {
        if w.stand.trees.dbh[i] < MIN_DBH_CM {
            assert_eq!(c.c66[i], 0.0);
        } else {
            assert!((c.c66[i] - want).abs() < 1e-3 * want, "tree {i}: C66 {} want {want}", c.c66[i]);
        }
    }
}
