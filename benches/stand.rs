//! Stand adaptation benchmark (issue 14): the per-tree skeletons of a near field of ≥ 1,000
//! trees adapted with their neighbours by `structure::stand::adapt_stand` (Plastic Trees,
//! Pirk et al. 2012, `000_*.txt`). A synthetic mixed stand like the default run's close-up
//! (beech, sycamore, Norway spruce, Scots pine; ages 20–140 years; about 600 canopy stems/ha on
//! flat ground), the 1,000 trees nearest a camera point as targets, every tree within the halo
//! as a neighbour. Plain program: `cargo bench --bench stand` (threads: `RAYON_NUM_THREADS`).
//! Prints wall time (open-grown cache, analyses and adaptation together, then again with the
//! cache warm) and the counts; the figures go to BENCHMARKS.md. Also prints a fingerprint
//! (FNV-1a over the bits of every adapted node position and radius, leaf position and cluster
//! of the targets) so a speed-up can be checked to compute the same stand bit for bit.
//! `SYLVA_STAND_SPECIES_DIR=DIR` reads the species from DIR instead of the embedded library;
//! `SYLVA_STAND_TARGETS=N` adapts the N nearest trees instead of 1,000 (for a profiler);
//! `SYLVA_STAND_ONCE=1` skips the second call; `SYLVA_STAND_CELL=M` sets the neighbourhood
//! cell side (m, default 12; other cells group the trees otherwise, so the stand differs);
//! `SYLVA_STAND_FULL=1` adapts the targets at full detail (`FULL_STRANDS`: every strand of
//! their species at their age, forest-grown, as stills and `--full-detail` exports draw them;
//! issue 32's near field) instead of `DEFAULT_MAX_STRANDS`. `SYLVA_STAND_SKY_RINGS=4,8` sets the
//! sky's rings (`StandOptions::sky_rings`, default 4,8,8: 20 directions since round 47, 4,8,12 (24) before); `SYLVA_STAND_HEIGHT_STEP=S`
//! sets the height classes' step (`StandOptions::height_step`, default 1.25); `SYLVA_STAND_SHAPE_STEP=S`
//! the crown-shape classes' step (`StandOptions::shape_step`, default 1.1025 since round 41, 1.05
//! before); `SYLVA_STAND_BEND_CELL=M` and `SYLVA_STAND_LEAF_CELL=M` the cubes (m) within which the
//! bending light and the last level's leaf-cluster light share one query
//! (`StandOptions::bend_light_cell_m`, default 0.25 since round 41, 0 before; `leaf_light_cell_m`,
//! default 0: every point its own); `SYLVA_STAND_BEND_LEVEL=0|1` whether the bending light's cubes
//! are shared over a whole level (`StandOptions::bend_light_whole_level`, default 1 since round 42);
//! `SYLVA_STAND_BEND_CELL=0 SYLVA_STAND_SHAPE_STEP=1.05` gives
//! round 40's exact near field with each cell's trees in index order (fingerprint
//! `4e723b2882995bc1` at 1,000 targets since round 42; `6ff74109f4fe3705` until then, when a cell's
//! trees came in the targets' nearest-first order); the default is `72358689bcdcd49b`. The default
//! shape step is 1.05² in f32, 1.1024998, one ulp below `SYLVA_STAND_SHAPE_STEP=1.1025`, which
//! gives other classes (fingerprint `ef21e986a49d6d42` against the default's
//! `74179efbd385d243` at 1,000 targets, round 41); `SYLVA_STAND_TREES=FILE`
//! writes one CSV row per target (index, live nodes, leaves, crown radius, height); `SYLVA_STAND_DUMP=FILE`
//! writes every target's leaf clusters (`AdaptedTree::leaf_clusters`, in order) as
//! little-endian f32 rows (tree index, centre x, y, z (m), light i, light in the analysis i_l0,
//! radius (m)), so two runs' adapted trees can be compared (BENCHMARKS.md, round 32).
//! Also prints the memory of the adapted trees' nodes and leaves. The light grids' geometry
//! (which changes no value, only the cost) has measurement hooks in the library:
//! `SYLVA_GRID_CELL_RADII` (cell side in mean caster radii, default 2) and
//! `SYLVA_GRID_CELLS_PER_CASTER` (default 2); BENCHMARKS.md round 43.
use glam::Vec3;
use sylva::rng::Stream;
use sylva::species::SpeciesLibrary;
use sylva::structure::stand::{adapt_stand, mean_crown_radius, Stand, SkeletonCache, StandOptions, StandTree, DEFAULT_MAX_STRANDS, FULL_STRANDS};

/// FNV-1a over the bits of the adapted trees of `st`: node positions and radii, leaf positions,
/// clusters after adaptation, and the report counts.
fn fingerprint(st: &Stand) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |v: u32| {
        for b in v.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for a in &st.trees {
        eat(a.index as u32);
        for n in &a.skeleton.nodes {
            n.pos.to_array().iter().for_each(|v| eat(v.to_bits()));
            eat(n.radius.to_bits());
        }
        a.leaves.for_each(|l| l.pos.to_array().iter().for_each(|v| eat(v.to_bits())));
        for (c, r) in &a.clusters_after {
            c.to_array().iter().for_each(|v| eat(v.to_bits()));
            eat(r.to_bits());
        }
        let r = &a.report;
        [r.nodes_after, r.bent, r.pruned_light, r.pruned_collision, r.recomputed_nodes].iter().for_each(|&v| eat(v as u32));
    }
    h
}

fn main() {
    // `SYLVA_STAND_SPECIES_DIR=DIR`: the species of a folder instead of the embedded library
    // (e.g. main's species files beside a branch's, to tell a species change from a code change)
    let lib = match std::env::var_os("SYLVA_STAND_SPECIES_DIR") {
        Some(d) => SpeciesLibrary::load_dir(std::path::Path::new(&d)).expect("SYLVA_STAND_SPECIES_DIR: a species folder"),
        None => SpeciesLibrary::embedded().expect("embedded species"),
    };
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
    let n_targets = std::env::var("SYLVA_STAND_TARGETS").ok().and_then(|v| v.parse().ok()).unwrap_or(1000usize).min(order.len());
    let targets: Vec<usize> = order[..n_targets].to_vec();
    let mut opts = StandOptions { latitude_deg: 36.6, ..Default::default() };
    if let Some(c) = std::env::var("SYLVA_STAND_CELL").ok().and_then(|v| v.parse().ok()) {
        opts.cell_m = c;
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_HEIGHT_STEP") {
        opts.height_step = v.trim().parse().expect("SYLVA_STAND_HEIGHT_STEP: a relative step, e.g. 1.5625");
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_SHAPE_STEP") {
        opts.shape_step = v.trim().parse().expect("SYLVA_STAND_SHAPE_STEP: a relative step, e.g. 1.1025");
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_BEND_CELL") {
        opts.bend_light_cell_m = v.trim().parse().expect("SYLVA_STAND_BEND_CELL: a cube side in m, e.g. 0.25");
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_BEND_LEVEL") {
        opts.bend_light_whole_level = v.trim() == "1";
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_LEAF_CELL") {
        opts.leaf_light_cell_m = v.trim().parse().expect("SYLVA_STAND_LEAF_CELL: a cube side in m, e.g. 0.25");
    }
    if let Ok(v) = std::env::var("SYLVA_STAND_SKY_RINGS") {
        opts.sky_rings = v.split(',').map(|x| x.trim().parse().expect("SYLVA_STAND_SKY_RINGS: comma-separated ring sizes, e.g. 4,8")).collect();
    }
    let full = std::env::var_os("SYLVA_STAND_FULL").is_some();
    let mut cache = SkeletonCache::new(42, if full { FULL_STRANDS } else { DEFAULT_MAX_STRANDS });
    let t = std::time::Instant::now();
    let st = adapt_stand(&trees, &targets, &lib, &mut cache, &opts).expect("adapt");
    let cold = t.elapsed().as_secs_f64();
    let fp = fingerprint(&st);
    if let Some(path) = std::env::var_os("SYLVA_STAND_DUMP") {
        let mut out = Vec::new();
        for a in &st.trees {
            for c in &a.leaf_clusters {
                for v in [a.index as f32, c.center.x, c.center.y, c.center.z, c.light, c.light_input, c.radius] {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        std::fs::write(&path, out).expect("SYLVA_STAND_DUMP: a writable file");
    }
    if let Some(path) = std::env::var_os("SYLVA_STAND_TREES") {
        // per target: index, live nodes after adaptation, leaves, crown radius (m) as
        // foresters measure it (mean_crown_radius, about the stem base), height (m)
        let mut out = String::from("index,nodes,leaves,crown_radius_m,height_m\n");
        for a in &st.trees {
            let b = trees[a.index].base;
            let mut sk = a.skeleton.clone();
            sk.nodes.iter_mut().for_each(|n| n.pos -= b);
            let mut lv = a.leaves.build();
            lv.leaves.iter_mut().for_each(|l| l.pos -= b);
            let h = sk.nodes.iter().map(|n| n.pos.z).fold(0.0f32, f32::max);
            out += &format!("{},{},{},{},{}\n", a.index, a.report.nodes_after, lv.len(), mean_crown_radius(&sk, &lv), h);
        }
        std::fs::write(&path, out).expect("SYLVA_STAND_TREES: a writable file");
    }
    let warm = if std::env::var_os("SYLVA_STAND_ONCE").is_some() {
        f64::NAN
    } else {
        let t = std::time::Instant::now();
        let st2 = adapt_stand(&trees, &targets, &lib, &mut cache, &opts).expect("adapt");
        assert_eq!(fingerprint(&st2), fp, "the second call computes the same stand");
        t.elapsed().as_secs_f64()
    };
    let nodes: usize = st.trees.iter().map(|a| a.report.nodes_before).sum();
    let pruned: usize = st.trees.iter().map(|a| a.report.pruned_light + a.report.pruned_collision).sum();
    println!("# stand adaptation (threads: {}; {}; sky rings {:?})", rayon::current_num_threads(), if full { "full detail" } else { "at most DEFAULT_MAX_STRANDS strands" }, opts.sky_rings);
    println!("| targets | trees in groups | cells | analyses | open-grown trees | nodes (targets) | pruned | first call s | second call s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    println!("| {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} |", st.trees.len(), st.trees_in_groups, st.cells, st.analyses, cache.len(), nodes, pruned, cold, warm);
    println!("first call: open-grown trees {:.2} s, analyses {:.2} s, adaptation {:.2} s", cold - st.analysis_s - st.adaptation_s, st.analysis_s, st.adaptation_s);
    let leaves: usize = st.trees.iter().map(|a| a.leaves.len()).sum();
    let held: usize = st.trees.iter().map(|a| a.leaves.held_bytes()).sum();
    let node_bytes: usize = st.trees.iter().map(|a| a.skeleton.nodes.len() * std::mem::size_of::<sylva::structure::Node>()).sum();
    println!("adapted trees: {} nodes ({:.2} GB), {leaves} leaves ({:.2} GB made, {:.3} GB held: made when read)", st.trees.iter().map(|a| a.skeleton.nodes.len()).sum::<usize>(), node_bytes as f64 / 1e9, (leaves * std::mem::size_of::<sylva::structure::Leaf>()) as f64 / 1e9, held as f64 / 1e9);
    println!("fingerprint {fp:016x}");
}
