//! Issue 32, round 37: do the conifers' crowns close? For each conifer of the species library, a
//! tree of a closed even-aged stand at 60, 80 and 100 years (dimensions of `sylva tree grow`'s
//! forest habit, `tree_form`) adapted at full detail among eight neighbours on a square lattice
//! of one crown diameter (`adapt_stand` with `FULL_STRANDS`, as the stand export and the stills'
//! near field do), and the same tree grown alone by `sylva tree grow` (`grow_formed_tree`):
//! first-order branches per metre of live crown, whorls, whorl spacing against the leader's
//! yearly height increment, and the share of the crown's disc (from above) and cone (from the
//! side) that the drawn full level covers (`job::crown_cover::drawn_cover`).
//!
//! ```text
//! cargo run --release --example conifer_crowns [-- SPECIES_DIR]
//! ```
//!
//! `CONIFER_SPECIES=norway_spruce` measures one species, `CONIFER_AGES=60,80` those ages;
//! `CONIFER_PICTURES=DIR` writes the cover grids as pictures. The last columns are the limbs'
//! angles from the vertical (`ArchitectureMeasures`: order-1 branches' first and last
//! segments, mean degrees, 90 horizontal) of the stand tree and of `sylva tree grow`'s tree.
use glam::Vec3;
use sylva::species::{LeafType, SpeciesLibrary};
use sylva::structure::forest_form::{grow_formed_tree, tree_form, ArchitectureMeasures, Habit, StemBranching};
use sylva::structure::species_tree::Model;
use sylva::structure::stand::{adapt_stand, SkeletonCache, StandOptions, StandTree, FULL_STRANDS};

fn main() {
    let lib = match std::env::args().nth(1) {
        Some(d) => SpeciesLibrary::load_dir(std::path::Path::new(&d)).unwrap(),
        None => SpeciesLibrary::embedded().unwrap(),
    };
    println!("| species | age | height m | crown base m | crown radius m | height increment m/yr | stand: branches/m | whorls | branches/whorl | whorl spacing m | top cover | side cover | alone: top, side | nodes | tree grow: branches/m | branches/whorl | whorl spacing m | stand: limb angle°, limb end° | tree grow: limb angle°, limb end° |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let only = std::env::var("CONIFER_SPECIES").ok();
    let ages: Vec<f32> = std::env::var("CONIFER_AGES").map_or_else(|_| vec![60.0, 80.0, 100.0], |a| a.split(',').map(|x| x.trim().parse().expect("CONIFER_AGES: numbers separated by commas")).collect());
    for (si, sp) in lib.species.iter().enumerate() {
        if sp.identity.leaf_type != LeafType::Conifer || only.as_deref().is_some_and(|o| o != sp.id) {
            continue;
        }
        for &age in &ages {
            let f = tree_form(sp, age, Habit::Forest).unwrap();
            let r = f.crown_radius_m;
            let spacing = 2.0 * r;
            let mut trees = Vec::new();
            for j in 0..3 {
                for i in 0..3 {
                    trees.push(StandTree { id: (j * 3 + i) as u64, species: si as u16, base: Vec3::new(20.0 + i as f32 * spacing, 20.0 + j as f32 * spacing, 100.0), age_yr: age, height_m: f.height_m, crown_radius_m: r, crown_base_m: f.crown_base_m, slope_deg: 0.0, aspect_deg: 180.0 });
                }
            }
            let mut cache = SkeletonCache::new(3, FULL_STRANDS);
            let st = adapt_stand(&trees, &[4], &lib, &mut cache, &StandOptions::default()).unwrap();
            let a = &st.trees[0];
            let t = &trees[4];
            let mut sk = a.skeleton.clone();
            sk.nodes.iter_mut().for_each(|n| n.pos -= t.base);
            let b = StemBranching::of(&sk, t.crown_base_m, 0.05);
            let (c, top, side) = sylva::job::crown_cover::drawn_cover_pictures(a, t, sp).unwrap();
            if let Ok(dir) = std::env::var("CONIFER_PICTURES") {
                top.save(format!("{dir}/{}_{age}_top.png", sp.id)).unwrap();
                side.save(format!("{dir}/{}_{age}_side.png", sp.id)).unwrap();
            }
            // the same tree adapted alone (no neighbour to prune or shade it)
            let one = [StandTree { base: Vec3::new(20.0, 20.0, 100.0), ..trees[4] }];
            let alone = adapt_stand(&one, &[0], &lib, &mut cache, &StandOptions::default()).unwrap();
            let ca = sylva::job::crown_cover::drawn_cover(&alone.trees[0], &one[0], sp).unwrap();
            let (g, gf) = grow_formed_tree(sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
            let gb = StemBranching::of(&g.skeleton, gf.crown_base_m, 0.05);
            let inc = sp.potential_height_m(age) - sp.potential_height_m(age - 1.0);
            let ms = ArchitectureMeasures::of(&sk, &Default::default());
            let gm = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
            println!(
                "| {} | {age} | {:.1} | {:.1} | {:.2} | {inc:.2} | {:.1} | {} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2}, {:.2} | {} | {:.1} | {:.1} | {:.2} | {:.0}, {:.0} | {:.0}, {:.0} |",
                sp.id, f.height_m, f.crown_base_m, r, b.per_m, b.whorls, b.branches_per_whorl, b.whorl_spacing_m, c.top, c.side, ca.top, ca.side, sk.nodes.len(), gb.per_m, gb.branches_per_whorl, gb.whorl_spacing_m, ms.branch_angle_deg, ms.limb_end_angle_deg, gm.branch_angle_deg, gm.limb_end_angle_deg
            );
        }
    }
}
