//! Issue 32: side views of the EcoMod trees of beech, sessile oak, Scots pine and Norway spruce
//! at ONE scale (ticks every 5 m), as `sylva tree grow` gives them, and their measures as a
//! Markdown table (BENCHMARKS.md, round 33).
//!
//! ```text
//! cargo run --release --example species_architecture -- OUT_DIR [OLD_SPECIES_DIR]
//! ```
//! writes `OUT_DIR/after_80.png` (the four species at 80 years, stand-grown, `sylva tree grow`'s
//! default), `OUT_DIR/after_ages.png` (each at 20 and 80 years) and, with `OLD_SPECIES_DIR` (the
//! species files of an earlier commit, e.g. `git archive main species | tar -x -C /tmp/old`),
//! `OUT_DIR/before_80.png`: the unsized EcoMod trees of those files at 80 years as `sylva tree
//! grow` drew them before (each tree at the height the strand model gives it).
use std::path::PathBuf;
use sylva::output::gltf::Look;
use sylva::species::{Season, Species, SpeciesLibrary};
use sylva::structure::mesh::{lod_chain, LodOptions};
use sylva::structure::forest_form::{grow_formed_tree, ArchitectureMeasures, CrownProportions, Habit};
use sylva::structure::species_tree::{grow_species_tree, Model};
use sylva::structure::{Leaves, Skeleton};

const IDS: [&str; 4] = ["beech", "sessile_oak", "scots_pine", "norway_spruce"];

/// Level 0 of a lone tree as `sylva tree grow` meshes it (its crown leaf area as sprigs).
fn full_level(sk: &Skeleton, lv: &mut Leaves, sp: &Species) -> sylva::mesh::TreeMesh {
    let (sprigs, _) = sylva::job::leaf_area::lone_tree_sprigs(sk, lv, sp);
    let mut chain = lod_chain(sk, lv, &LodOptions::default());
    let mut full = chain.levels.swap_remove(0);
    full.leaves.append(&sprigs);
    full
}

fn refs(v: &[(sylva::mesh::TreeMesh, Look)]) -> Vec<(&sylva::mesh::TreeMesh, &Look)> {
    v.iter().map(|(m, l)| (m, l)).collect()
}

fn save(img: image::RgbImage, path: PathBuf) {
    img.save(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    println!("wrote {}", path.display());
}

fn main() {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().expect("usage: species_architecture OUT_DIR [OLD_SPECIES_DIR]"));
    std::fs::create_dir_all(&out).unwrap();
    let lib = SpeciesLibrary::embedded().unwrap();
    let (w, h) = (240, 420);
    println!("| species | age | height m (curve) | DBH cm | crown base / height (TreeGrOSS) | crown width / length (TreeGrOSS) | measured: height m | clear bole | width/length | order-1 branches | mean angle from vertical | limb ends from vertical | widest at |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut at80 = Vec::new();
    let mut ages = Vec::new();
    for id in IDS {
        let sp = lib.get(id).unwrap();
        for age in [20.0f32, 80.0] {
            let (g, f) = grow_formed_tree(sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
            let m = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
            println!(
                "| {id} | {age} | {:.1} ({:.1}) | {:.1} | {:.2} | {:.2} | {:.1} | {:.2} | {:.2} | {} | {:.0}° | {:.0}° | {:.2} |",
                m.height_m,
                f.height_m,
                f.dbh_cm,
                f.clear_bole_share(),
                f.width_to_length(),
                m.height_m,
                m.clear_bole_share(),
                m.width_to_length(),
                m.branches,
                m.branch_angle_deg,
                m.limb_end_angle_deg,
                m.widest_at
            );
            let mut lv = g.leaves.clone();
            let mesh = full_level(&g.skeleton, &mut lv, sp);
            let look = Look::for_species(sp, Season::Summer);
            if age == 80.0 {
                at80.push((mesh.clone(), look.clone()));
            }
            ages.push((mesh, look));
        }
    }
    save(sylva::output::tree_preview::same_scale_preview(&refs(&at80), w, h, 5.0), out.join("after_80.png"));
    save(sylva::output::tree_preview::same_scale_preview(&refs(&ages), w / 2 + 40, h, 5.0), out.join("after_ages.png"));
    if let Some(old) = args.next() {
        let old = SpeciesLibrary::load_dir(std::path::Path::new(&old)).unwrap();
        let mut before = Vec::new();
        for id in IDS {
            let sp = old.get(id).unwrap();
            let g = grow_species_tree(sp, Model::EcoMod, 80.0, &[], 1).unwrap();
            let m = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
            println!("before {id} 80: height {:.1} m, clear bole {:.2}, width/length {:.2}, {} order-1 branches at {:.0}°", m.height_m, m.clear_bole_share(), m.width_to_length(), m.branches, m.branch_angle_deg);
            let mut lv = g.leaves.clone();
            before.push((full_level(&g.skeleton, &mut lv, sp), Look::for_species(sp, Season::Summer)));
        }
        save(sylva::output::tree_preview::same_scale_preview(&refs(&before), w, h, 5.0), out.join("before_80.png"));
    }
}
