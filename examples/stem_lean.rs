//! Main-stem lean of stand trees before and after the Plastic Trees adaptation (issue 32,
//! round 35: "main stems that lean like tent poles"): `cargo run --release --example stem_lean
//! -- [N] [SPACING_M] [SEED] [SPECIES,...]` (defaults 7, 4.5, 1, six species), or
//! `-- --run RUN_DIR YEAR X0,Y0,X1,Y1` for the trees of a run's snapshot as `sylva export` adapts them. A mixed stand of N × N trees on a jittered
//! lattice (six species of the default run, heights 12–30 m, a few gaps) is adapted by
//! [`adapt_stand`] at full detail; for every adapted tree of the inner (N − 2) × (N − 2) the lean
//! of its main stem (Gravelius order 0) from the vertical is printed, root → crown base (the
//! first branching of the stem) and root → top (its highest node), adapted and fitted
//! (un-adapted), with the median per species and height class.
use glam::Vec3;
use sylva::species::SpeciesLibrary;
use sylva::structure::plastic::analysis::{growth_rates, internode_length, seasons};
use sylva::structure::skeleton::Skeleton;
use sylva::structure::stand::{adapt_stand, age_class, crown_base_class, fit, stem_lean_deg, SkeletonCache, StandOptions, StandTree, FULL_STRANDS};

fn median(v: &mut [f32]) -> f32 {
    if v.is_empty() {
        return f32::NAN;
    }
    v.sort_by(f32::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--run") {
        return from_run(&args[1..]);
    }
    let n: usize = args.first().map(|s| s.parse()).transpose()?.unwrap_or(7);
    let spacing: f32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(4.5);
    let seed: u64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let lib = SpeciesLibrary::embedded()?;
    let species_arg = args.get(3).cloned().unwrap_or_else(|| "beech,norway_spruce,sessile_oak,silver_birch,scots_pine,norway_maple".into());
    let species: Vec<&str> = species_arg.split(',').collect();
    let trees = stand(&lib, &species, n, spacing, seed);
    let targets: Vec<usize> = (0..trees.len()).filter(|&i| inner(&trees[i], n, spacing)).collect();
    let mut cache = SkeletonCache::new(seed, FULL_STRANDS);
    report(&lib, &trees, &targets, &mut cache, &StandOptions::default(), &species)
}

/// `--run RUN_DIR YEAR X0,Y0,X1,Y1`: the trees of a run's snapshot in the area, adapted as
/// `sylva export` adapts them (full detail, the site's latitude and obstacles).
fn from_run(args: &[String]) -> anyhow::Result<()> {
    use sylva::job::adapted::{solids, stand_trees};
    let run = std::path::Path::new(args.first().ok_or_else(|| anyhow::anyhow!("--run RUN_DIR YEAR X0,Y0,X1,Y1"))?);
    let year: u32 = args.get(1).ok_or_else(|| anyhow::anyhow!("YEAR"))?.parse()?;
    let a: Vec<f64> = args.get(2).ok_or_else(|| anyhow::anyhow!("X0,Y0,X1,Y1"))?.split(',').map(|v| v.parse()).collect::<Result<_, _>>()?;
    let sc = sylva::sim::Scenario::load(&run.join("scenario.toml"))?;
    let site = sc.site()?;
    let lib = SpeciesLibrary::embedded()?;
    let opts = StandOptions { latitude_deg: site.geo.latitude_deg as f32, obstacles: solids(&sc.obstacles, &site), ..StandOptions::default() };
    let m = (opts.cell_m + opts.halo_m) as f64 + 1.0;
    let rows = sylva::job::pictures::snapshot_rows_where(run, year, |r| r.x_m >= a[0] - m && r.x_m < a[2] + m && r.y_m >= a[1] - m && r.y_m < a[3] + m)?;
    let plants = sylva::job::scene::plants_from_rows(&rows);
    let trees: Vec<StandTree> = stand_trees(&plants, &lib, &site).into_iter().map(|(_, t)| t).collect();
    let targets: Vec<usize> = (0..trees.len()).filter(|&k| (trees[k].base.x as f64) >= a[0] && (trees[k].base.x as f64) < a[2] && (trees[k].base.y as f64) >= a[1] && (trees[k].base.y as f64) < a[3]).collect();
    let mut species: Vec<String> = targets.iter().map(|&k| lib.species[trees[k].species as usize].id.clone()).collect();
    species.sort();
    species.dedup();
    let sp: Vec<&str> = species.iter().map(String::as_str).collect();
    let mut cache = SkeletonCache::new(sc.seed, FULL_STRANDS);
    report(&lib, &trees, &targets, &mut cache, &opts, &sp)
}

fn report(lib: &SpeciesLibrary, trees: &[StandTree], targets: &[usize], cache: &mut SkeletonCache, opts: &StandOptions, species: &[&str]) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let st = adapt_stand(trees, targets, lib, cache, opts)?;
    eprintln!("{} trees, {} adapted in {:.1} s", trees.len(), st.trees.len(), t0.elapsed().as_secs_f64());
    println!("| tree | species | height m | crown base m | lean to crown base: fitted → adapted (°) | lean to top: fitted → adapted (°) |");
    println!("|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for a in &st.trees {
        let t = &trees[a.index];
        let g = cache.get((t.species, age_class(t.age_yr), crown_base_class(t.height_m, t.crown_base_m))).expect("grown");
        let (mut fitted, _) = fit(g, t.height_m, t.crown_radius_m, t.crown_base_m);
        for nd in &mut fitted.nodes {
            nd.pos += t.base;
        }
        let (f_cb, f_top) = stem_lean_deg(&fitted);
        // eq. (2) seasons of the fitted tree: the bole's (node 1, the first segment) and the last
        let li = internode_length(&fitted);
        let seas = seasons(&fitted, li, &growth_rates(&fitted));
        let last = seas.iter().copied().max().unwrap_or(0);
        let bole_len = fitted.segment_length(1);
        eprintln!("tree {}: l_i {li:.3} m, bole {bole_len:.2} m = {:.0} internodes, season of the bole's top {} of {last}", t.id, bole_len / li, seas[1]);
        let (a_cb, a_top) = stem_lean_deg(&a.skeleton);
        eprintln!("tree {}: adapted stem segments from the vertical, max {:.1}°; crown base → top {:.1}°", t.id, stem_max_segment_deg(&a.skeleton), crown_stem_deg(&a.skeleton));
        let name = &lib.species[t.species as usize].id;
        println!("| {} | {name} | {:.1} | {:.1} | {f_cb:.1} → {a_cb:.1} | {f_top:.1} → {a_top:.1} |", t.id, t.height_m, t.crown_base_m);
        rows.push((name.clone(), t.height_m, f_cb, a_cb, f_top, a_top));
    }
    println!("\n| group | trees | median lean to crown base: fitted, adapted (°) | median lean to top: fitted, adapted (°) | max adapted to top (°) |");
    println!("|---|---|---|---|---|");
    let mut groups: Vec<(String, Box<dyn Fn(&(String, f32, f32, f32, f32, f32)) -> bool>)> = vec![("all".into(), Box::new(|_| true))];
    for &s in species {
        let s2 = s.to_string();
        groups.push((s.into(), Box::new(move |r| r.0 == s2)));
    }
    for (lo, hi) in [(0.0, 18.0), (18.0, 24.0), (24.0, 99.0)] {
        groups.push((format!("height {lo}–{hi} m"), Box::new(move |r| r.1 >= lo && r.1 < hi)));
    }
    for (name, f) in &groups {
        let sel: Vec<_> = rows.iter().filter(|r| f(r)).collect();
        if sel.is_empty() {
            continue;
        }
        let col = |i: usize| -> Vec<f32> { sel.iter().map(|r| [r.2, r.3, r.4, r.5][i]).collect() };
        let mx = col(3).into_iter().fold(0.0f32, f32::max);
        println!("| {name} | {} | {:.1}, {:.1} | {:.1}, {:.1} | {mx:.1} |", sel.len(), median(&mut col(0)), median(&mut col(1)), median(&mut col(2)), median(&mut col(3)));
    }
    Ok(())
}

fn inner(t: &StandTree, n: usize, spacing: f32) -> bool {
    let (i, j) = (((t.base.x - 10.0) / spacing).round() as usize, ((t.base.y - 10.0) / spacing).round() as usize);
    i > 0 && j > 0 && i + 1 < n && j + 1 < n
}

/// The stand: N × N lattice positions jittered by ±0.2 spacing, one in nine left out (a gap),
/// species in turn, heights 12–30 m with crown base 0.35–0.55 of the height.
fn stand(lib: &SpeciesLibrary, species: &[&str], n: usize, spacing: f32, seed: u64) -> Vec<StandTree> {
    let mut v = Vec::new();
    let mut rng = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f32 / (1u64 << 53) as f32
    };
    for j in 0..n {
        for i in 0..n {
            let (u, w, h, c, gap) = (next(), next(), next(), next(), next());
            if gap < 1.0 / 9.0 && i > 0 && j > 0 && i + 1 < n && j + 1 < n {
                continue;
            }
            let sp = species[(i + j * n) % species.len()];
            let height = 12.0 + 18.0 * h;
            let x = 10.0 + i as f32 * spacing + (u - 0.5) * 0.4 * spacing;
            let y = 10.0 + j as f32 * spacing + (w - 0.5) * 0.4 * spacing;
            v.push(StandTree { id: (j * n + i) as u64, species: lib.find(sp).unwrap(), base: Vec3::new(x, y, 100.0), age_yr: 40.0 + 3.0 * height, height_m: height, crown_radius_m: 0.6 * spacing, crown_base_m: (0.35 + 0.2 * c) * height, slope_deg: 0.0, aspect_deg: 180.0 });
        }
    }
    v
}

/// The main stem's nodes (Gravelius order 0 along the continuing children), root first.
fn stem(sk: &Skeleton) -> Vec<usize> {
    let mut v = vec![0usize];
    while let Some(&c) = sk.nodes[*v.last().unwrap()].children.iter().find(|&&c| sk.nodes[c as usize].gravelius == 0) {
        v.push(c as usize);
    }
    v
}

fn angle(d: Vec3) -> f32 {
    if d.length() <= 0.0 { 0.0 } else { (d.z / d.length()).clamp(-1.0, 1.0).acos().to_degrees() }
}

fn stem_max_segment_deg(sk: &Skeleton) -> f32 {
    let s = stem(sk);
    s.windows(2).map(|w| angle(sk.nodes[w[1]].pos - sk.nodes[w[0]].pos)).fold(0.0, f32::max)
}

/// Lean of the stem within the crown: first branching of the stem → its top.
fn crown_stem_deg(sk: &Skeleton) -> f32 {
    let s = stem(sk);
    let cb = s.iter().copied().find(|&k| k != 0 && sk.nodes[k].children.iter().any(|&c| sk.nodes[c as usize].gravelius > 0)).unwrap_or(*s.last().unwrap());
    angle(sk.nodes[*s.last().unwrap()].pos - sk.nodes[cb].pos)
}
