//! Stand adaptation benchmark (issue 14): the per-tree skeletons of a near field of ≥ 1,000
//! trees adapted with their neighbours by `structure::stand::adapt_stand` (Plastic Trees,
//! Pirk et al. 2012, `000_*.txt`). A synthetic mixed stand like the default run's close-up
//! (beech, sycamore, Norway spruce, Scots pine; ages 20–140 years; about 600 canopy stems/ha on
//! flat ground), the 1,000 trees nearest a camera point as targets, every tree within the halo
//! as a neighbour. Plain program: `cargo bench --bench stand` (threads: `RAYON_NUM_THREADS`).
//! Prints wall time (open-grown cache, analyses and adaptation together, then again with the
//! cache warm) and the counts; the figures go to BENCHMARKS.md.
use glam::Vec3;
use sylva::rng::Stream;
use sylva::species::SpeciesLibrary;
use sylva::structure::stand::{adapt_stand, SkeletonCache, StandOptions, StandTree, DEFAULT_MAX_STRANDS};

fn main() {
    let lib = SpeciesLibrary::embedded().expect("embedded species");
    let names = ["beech", "sycamore", "norway_spruce", "scots_pine"];
    let ids: Vec<u16> = names.iter().map(|n| lib.find(n).expect("species")).collect();
    // 160 m × 160 m at ~4 m spacing with jitter: 1,600 trees (625/ha)
    let mut trees = Vec::new();
    for j in 0..40u64 {
        for i in 0..40u64 {
            let mut r = Stream::new(42, j * 40 + i, 0, 7);
            let age = r.range(20.0, 140.0) as f32;
            let h = (35.0 * (1.0 - (-age / 60.0).exp())) as f32 * r.range(0.85, 1.15) as f32;
            trees.push(StandTree {
                id: j * 40 + i,
                species: ids[r.below(ids.len() as u64) as usize],
                base: Vec3::new((i as f64 * 4.0 + r.range(-1.0, 1.0)) as f32, (j as f64 * 4.0 + r.range(-1.0, 1.0)) as f32, 300.0),
                age_yr: age,
                height_m: h,
                crown_radius_m: (0.12 * h).max(1.0) * r.range(0.8, 1.2) as f32,
                crown_base_m: 0.45 * h,
                slope_deg: 0.0,
                aspect_deg: 180.0,
            });
        }
    }
    let eye = Vec3::new(80.0, 20.0, 300.0);
    let mut order: Vec<usize> = (0..trees.len()).collect();
    order.sort_by(|&a, &b| trees[a].base.distance(eye).total_cmp(&trees[b].base.distance(eye)).then(a.cmp(&b)));
    let targets: Vec<usize> = order[..1000].to_vec();
    let opts = StandOptions { latitude_deg: 36.6, ..Default::default() };
    let mut cache = SkeletonCache::new(42, DEFAULT_MAX_STRANDS);
    let t = std::time::Instant::now();
    let st = adapt_stand(&trees, &targets, &lib, &mut cache, &opts).expect("adapt");
    let cold = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let st2 = adapt_stand(&trees, &targets, &lib, &mut cache, &opts).expect("adapt");
    let warm = t.elapsed().as_secs_f64();
    assert_eq!(st.trees.len(), st2.trees.len());
    let nodes: usize = st.trees.iter().map(|a| a.report.nodes_before).sum();
    let pruned: usize = st.trees.iter().map(|a| a.report.pruned_light + a.report.pruned_collision).sum();
    println!("# stand adaptation (threads: {})", rayon::current_num_threads());
    println!("| targets | trees in groups | cells | analyses | open-grown trees | nodes (targets) | pruned | first call s | second call s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    println!("| {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} |", st.trees.len(), st.trees_in_groups, st.cells, st.analyses, cache.len(), nodes, pruned, cold, warm);
}
