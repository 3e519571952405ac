//! Tree architecture benchmark: time per node of each growth model and of meshing, and the
//! 10,000-node full-detail meshing figure (target ≤ 20 ms on one core). Plain program; run with
//! `cargo bench --bench architecture`. Single-threaded throughout. Medians over repeated runs.
use sylva::species::EcoModParams;
use sylva::structure::grow::{ecomod, laplacian, light_guided};
use sylva::structure::mesh::{self, LodOptions};
use sylva::structure::params;

mod common;
use common::median_ms;

fn main() {
    println!("# architecture benchmark (one core, medians)");
    // EcoMod
    for (name, p) in [("beech S=1000", EcoModParams::beech_paper()), ("pine S=6000", EcoModParams::pine_paper())] {
        let n = ecomod::grow(&p, 1, 0.0).0.len();
        let ms = median_ms(21, || {
            std::hint::black_box(ecomod::grow(&p, 1, 0.0));
        });
        println!("ecomod {name}: {n} nodes, {ms:.2} ms, {:.1} ns/node", ms * 1e6 / n as f64);
    }
    // 10,000-node tree: EcoMod beech with S = 5000 (2S = 10,000 nodes)
    let mut p = EcoModParams::beech_paper();
    p.strands = 5000;
    let (sk, lv) = ecomod::grow(&p, 1, 0.0);
    let o = LodOptions::default();
    let full = mesh::full_mesh(&sk, &lv, &o);
    let bark_ms = median_ms(31, || {
        std::hint::black_box(mesh::branch_mesh(&sk, &o, None));
    });
    let full_ms = median_ms(31, || {
        std::hint::black_box(mesh::full_mesh(&sk, &lv, &o));
    });
    let chain_ms = median_ms(15, || {
        std::hint::black_box(mesh::lod_chain(&sk, &lv, &o));
    });
    println!(
        "mesh 10,000-node tree ({} nodes, {} leaves): full detail LOD0 {:.2} ms ({} triangles; bark only {:.2} ms), {:.1} ns/node; whole LOD chain {:.2} ms",
        sk.len(),
        lv.len(),
        full_ms,
        full.triangle_count(),
        bark_ms,
        full_ms * 1e6 / sk.len() as f64,
        chain_ms
    );
    // light-guided
    let lp = params::light_guided_paper();
    let lo = light_guided::LightOptions::default();
    let mut nodes = 0;
    let ms = median_ms(5, || {
        nodes = light_guided::grow(&lp, &lo, &[], 1, 12).unwrap().len();
    });
    println!("light-guided 12 cycles: {nodes} nodes, {ms:.1} ms, {:.1} µs/node", ms * 1e3 / nodes as f64);
    let wall = [sylva::structure::grow::space::Obstacle::Wall { x: 1.5 }];
    let ms = median_ms(5, || {
        nodes = light_guided::grow(&lp, &lo, &wall, 1, 12).unwrap().len();
    });
    println!("light-guided 12 cycles beside a wall: {nodes} nodes, {ms:.1} ms, {:.1} µs/node", ms * 1e3 / nodes as f64);
    // Laplacian
    let ap = params::laplacian_paper();
    let ao = laplacian::LaplacianOptions::default();
    let ms = median_ms(5, || {
        nodes = laplacian::grow(&ap, &ao, &[], 1, 500).unwrap().skeleton.len();
    });
    println!("laplacian 500 branches (24x24x28 voxels): {nodes} nodes, {ms:.1} ms, {:.1} µs/node", ms * 1e3 / nodes as f64);
    // species trees inside their crown envelopes (what `sylva tree grow` does)
    use sylva::structure::species_tree::{grow_species_tree, Model};
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let sp = |id: &str| lib.species[lib.find(id).unwrap() as usize].clone();
    for (id, model, age, roof) in [("beech", Model::Light, 40.0, false), ("beech", Model::Light, 40.0, true), ("norway_spruce", Model::Light, 40.0, false), ("beech", Model::Laplacian, 40.0, false), ("pedunculate_oak", Model::Laplacian, 60.0, false), ("scots_pine", Model::EcoMod, 80.0, false)] {
        let s = sp(id);
        let obstacles: Vec<sylva::structure::grow::space::Obstacle> = if roof {
            let e = sylva::structure::grow::envelope::CrownEnvelope::for_species(&s, age, glam::Vec3::ZERO);
            let r = 3.0 * e.radius_m;
            vec![sylva::structure::grow::space::Obstacle::Box { min: glam::Vec3::new(-r, -r, 1.5 * e.height_m), max: glam::Vec3::new(r, r, 1.6 * e.height_m) }]
        } else {
            Vec::new()
        };
        let mut h = 0.0;
        let ms = median_ms(3, || {
            let g = grow_species_tree(&s, model, age, &obstacles, 1).unwrap();
            nodes = g.skeleton.len();
            h = g.skeleton.height();
        });
        println!("species tree {id} {model:?} {age} yr{}: {nodes} nodes, height {h:.1} m, {ms:.1} ms, {:.1} µs/node", if roof { " under a high roof" } else { "" }, ms * 1e3 / nodes as f64);
    }
    // Plastic Trees: adapt a grown light-guided beech to a wall versus regrowing it beside the wall
    let s = sp("beech");
    let g = grow_species_tree(&s, Model::Light, 40.0, &[], 1).unwrap();
    let r = sylva::structure::crown_radius(&g.skeleton, &Default::default());
    let wall = [sylva::structure::grow::space::Obstacle::Wall { x: 0.5 * r }];
    let internode = (g.envelope.unwrap().height_m / 40.0).max(0.15);
    let mut rep = None;
    let adapt_ms = median_ms(3, || {
        let (out, report) = sylva::structure::plastic::adapt(&g.skeleton, &s.architecture.plastic, &wall, internode).unwrap();
        nodes = out.len();
        rep = Some(report);
    });
    let regrow_ms = median_ms(3, || {
        std::hint::black_box(grow_species_tree(&s, Model::Light, 40.0, &wall, 1).unwrap());
    });
    println!("plastic adaptation of a {}-node beech to a wall at {:.1} m: {adapt_ms:.1} ms ({nodes} nodes left, {rep:?}); regrowing it beside the wall: {regrow_ms:.1} ms", g.skeleton.len(), 0.5 * r);
}
