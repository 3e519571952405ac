//! Plastic Trees benchmark (Pirk et al. 2012, `000_*.txt`, Table 2): light-guided beeches of
//! about 530, 2,540 and 9,130 nodes beside a finite wall; analysis (once), adaptation and the
//! time our light-guided model takes to regrow the same tree beside the same wall; two
//! ≈2,540-node trees adapted together; moving the wall by 10 cm and re-adapting. Plain program:
//! `RAYON_NUM_THREADS=1 cargo bench --bench plastic`. Medians over repeated runs (regrowth: one
//! run).
use std::time::Instant;
use glam::Vec3;
use sylva::species::SpeciesLibrary;
use sylva::structure::grow::space::Obstacle;
use sylva::structure::plastic::{adapt_group, Environment, PlasticTree};
use sylva::structure::species_tree::{grow_species_tree, GrownTree, Model};

mod common;
use common::median_ms;

fn wall_for(g: &GrownTree) -> Obstacle {
    let env = g.envelope.expect("light-guided trees have an envelope");
    Obstacle::FiniteWall { x: 0.5 * env.radius_m, length: 4.0 * env.radius_m, height: 1.2 * env.height_m }
}

fn main() {
    let lib = SpeciesLibrary::embedded().expect("embedded species");
    let sp = &lib.species[lib.find("beech").expect("beech") as usize];
    let mut p = sp.architecture.plastic;
    p.phototropism = 0.25; // the paper's Tree 1 (section 6)
    p.gravitropism = 0.12;
    println!("# Plastic Trees benchmark (light-guided beech beside a finite wall; threads: {})", rayon::current_num_threads());
    println!("| target nodes | age (yr) | nodes | analysis ms | adapt ms | regrow ms | regrow / adapt | bent | pruned | move wall 10 cm: ms (recomputed nodes) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut mid: Option<(GrownTree, f32)> = None;
    let mut age = 6.0f32;
    for target in [530usize, 2540, 9130] {
        // the youngest age whose tree reaches the target (ages step by one year)
        let mut g = grow_species_tree(sp, Model::Light, age, &[], 1).expect("grow");
        while g.skeleton.len() < target && age < 60.0 {
            age += 1.0;
            g = grow_species_tree(sp, Model::Light, age, &[], 1).expect("grow");
        }
        let sk = &g.skeleton;
        let wall = wall_for(&g);
        let env = Environment::with_obstacles(&[wall]);
        let t0 = Instant::now();
        let tree = PlasticTree::analyse(sk, &p, &Environment::open(), None).expect("analyse");
        let analysis_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut rep = None;
        let adapt_ms = median_ms(7, || {
            let mut t = tree.clone();
            rep = Some(t.adapt(&env).expect("adapt"));
        });
        let rep = rep.expect("ran");
        let mut adapted = tree.clone();
        adapted.adapt(&env).expect("adapt");
        let mut rec = 0;
        let moved = match wall {
            Obstacle::FiniteWall { x, length, height } => Obstacle::FiniteWall { x: x + 0.1, length, height },
            o => o,
        };
        let move_ms = median_ms(7, || {
            let mut t = adapted.clone();
            rec = t.adapt(&Environment::with_obstacles(&[moved])).expect("adapt").recomputed_nodes;
        });
        let t1 = Instant::now();
        std::hint::black_box(grow_species_tree(sp, Model::Light, age, &[wall], 1).expect("regrow"));
        let regrow_ms = t1.elapsed().as_secs_f64() * 1e3;
        println!(
            "| {target} | {age} | {} | {analysis_ms:.1} | {adapt_ms:.2} | {regrow_ms:.0} | {:.0}× | {} | {} | {move_ms:.2} ({rec}) |",
            sk.len(),
            regrow_ms / adapt_ms,
            rep.bent,
            rep.pruned_light + rep.pruned_collision
        );
        if target == 2540 {
            mid = Some((g.clone(), age));
        }
    }
    if let Some((g, age)) = mid {
        let r = g.envelope.map(|e| e.radius_m).unwrap_or(2.0);
        let a = PlasticTree::analyse(&g.skeleton, &p, &Environment::open(), None).expect("analyse");
        let mut b = a.clone();
        b.translate(Vec3::new(1.5 * r, 0.0, 0.0));
        let env = Environment::open();
        let mut rec = 0;
        let ms = median_ms(7, || {
            let mut pair = vec![a.clone(), b.clone()];
            rec = adapt_group(&mut pair, &env).expect("group").recomputed_nodes;
        });
        println!("\ntwo {}-node trees ({age} yr) {:.2} m apart adapted together: {ms:.2} ms ({rec} nodes recomputed)", g.skeleton.len(), 1.5 * r);
    }
}
