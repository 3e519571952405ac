//! The light under closed stands (issue 35, round 41): `sim::phases::light::cell_light_at`, the
//! light phase's relative light at any height over every light cell, and the closed-stand floor
//! light against Emborg (1998).
//!
//! Emborg, J. 1998. Understorey light conditions and regeneration with respect to the structural
//! dynamics of a near-natural temperate deciduous forest in Denmark. Forest Ecology and
//! Management 106:83–95 (abstract): in the beech-dominated Suserup Skov the relative light
//! intensity at the floor "was below 2 % in all phases of the forest cycle, except in gaps"
//! (degradation and innovation phases), where it rose to about 10 %; beech and ash regeneration
//! did not survive below 2 %.
use sylva::sim::phases::light::cell_light_at;
use sylva::sim::pure_stand::pure_stand_toml;
use sylva::sim::step::{step_year_with, YearReport};
use sylva::sim::{Scenario, World};
use sylva::species::{Season, SpeciesLibrary};

/// A pure stand of `id` planted at 1.5 m, age 3, on a 100 m square (`sim::pure_stand`), run for
/// `years` years; calls `at_spring(world)` in the spring of the last year (after the light
/// phase of that year: the trees' light and the ground light are of this year's canopy).
fn pure_stand(lib: &SpeciesLibrary, id: &str, years: u32, at_spring: &mut dyn FnMut(&World)) {
    let sp = lib.get(id).unwrap();
    let sc = Scenario::from_toml_str(&pure_stand_toml(sp, 100.0, 1.5, 3.0, years, 7), "pure stand").unwrap();
    let mut w = World::new(sc.site().unwrap(), lib, &sc).unwrap();
    for y in 1..=years {
        let mut r = YearReport::default();
        step_year_with(&mut w, &sc, &mut r, &mut |season, w| {
            if y == years && season == Season::Spring {
                at_spring(w);
            }
        });
    }
}

fn light_at(w: &World, z: f32) -> Vec<f32> {
    cell_light_at(&w.stand.trees, &w.site.light, &w.site.conditions, &w.site.lib, &w.site.light_site, &w.site.rel_insolation, &w.site.obstacle_canopy, z)
}

/// `cell_light_at` is the light phase's formula: at height 0 it gives the phase's ground light of
/// every cell, and at a tree's height in the tree's cell the tree's light, bit for bit (a
/// 30-year beech thicket, where light varies from cell to cell and tree to tree).
#[test]
fn light_at_a_height_is_the_light_phases() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut checked = 0usize;
    pure_stand(&lib, "beech", 27, &mut |w| {
        let g = light_at(w, 0.0);
        assert_eq!(g.len(), w.scratch.ground_light.len());
        for (c, (a, b)) in g.iter().zip(&w.scratch.ground_light).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "cell {c}: {a} against the ground light {b}");
        }
        let t = &w.stand.trees;
        let (lo, hi) = g.iter().fold((f32::MAX, 0f32), |a, &v| (a.0.min(v), a.1.max(v)));
        assert!(hi - lo > 0.05, "the floor light varies over the stand ({lo}–{hi})");
        // a sample of the trees (none recruited: beech bears seed from 40 years)
        for i in (0..t.len()).step_by(97) {
            let at = light_at_tree(w, i);
            assert_eq!(at.to_bits(), t.light[i].to_bits(), "tree {i} at {} m: {at} against {}", t.height[i], t.light[i]);
            checked += 1;
        }
    });
    assert!(checked >= 20, "{checked} trees compared");
}

/// The light at tree `i`'s height in its cell, from [`cell_light_at`].
fn light_at_tree(w: &World, i: usize) -> f32 {
    let t = &w.stand.trees;
    let c = w.site.light.cell_of(t.x[i], t.y[i]);
    light_at(w, t.height[i])[c]
}

/// A closed pure beech stand at 100 years passes at most 5 % of full light to its median light
/// cell: between Emborg's (1998) < 2 % under every closed phase of the beech forest cycle and his
/// about 10 % in gaps, so at least half of a closed stand's floor is darker than its gaps.
///
/// Ignored: not met (issue 35, round 41). The light phase's crowns (crown LAI `2 + 0.5 · shade
/// tolerance` over the crown-space projection) give a median of 0.157 (the stand's leaf-area
/// index 3.3); the sourced crown LAI over the crown outlines
/// (tools/experiments/r41_sourced_lai_outline_light.patch) gives about 0.11 (0.107 a year
/// later, `examples/understorey_light.rs`), and fails spruce's density checks. docs/management.md, "Round 41".
#[test]
#[ignore = "issue 35: closed beech passes 16 % of full light to the median floor cell (Emborg 1998: < 2 % outside gaps); docs/management.md, Round 41"]
fn closed_beech_passes_little_light_to_the_floor() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut median = f32::NAN;
    pure_stand(&lib, "beech", 97, &mut |w| {
        let mut g = light_at(w, 0.0);
        g.sort_by(f32::total_cmp);
        median = g[g.len() / 2];
    });
    eprintln!("beech at 100 years: median relative floor light {median:.3}");
    assert!(median <= 0.05, "median floor light {median:.3} > 0.05");
}
