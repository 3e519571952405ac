//! Plastic Trees benchmark (Pirk et al. 2012, `000_*.txt`, Table 2): light-guided trees (Yi et
//! al. paper parameters, beech Plastic Trees parameters with the paper's Tree 1 tropisms) of
//! about 530, 2,540 and 9,130 nodes (the paper's Table 2; the cycle count and seed whose tree
//! is nearest in node count) beside a finite wall; analysis (once), adaptation and the
//! time our light-guided model takes to regrow the same tree beside the same wall; two
//! ≈2,540-node trees adapted together; moving the wall by 10 cm and re-adapting. Plain program:
//! `RAYON_NUM_THREADS=1 cargo bench --bench plastic`. Process CPU time (hardly affected when
//! the machine is shared) and, in the last columns, wall-clock time (the figure of a goal on
//! several cores), medians over repeated runs (regrowth: one run). `SYLVA_PLASTIC_NO_REGROW=1`
//! skips the regrowth (for profiling). The "move wall 10 cm" columns report the move light model
//! (`PlasticTree::set_move_light`, tolerance `MOVE_LIGHT_TOL_M`; `SYLVA_PLASTIC_MOVE_LIGHT=exact`
//! or a tolerance in m), the last two columns the exact move (round 36's). Each case also prints a fingerprint (FNV-1a over the bits
//! of every adapted position, bend angle and fate) so a speed-up can be checked to compute the
//! same trees bit for bit.
use glam::Vec3;
use sylva::species::SpeciesLibrary;
use sylva::structure::grow::space::Obstacle;
use sylva::structure::plastic::{adapt_group, Environment, PlasticTree, Sky};
use sylva::structure::grow::light_guided::{self, LightOptions};
use sylva::structure::params;
use sylva::structure::Skeleton;

/// CPU time of the whole process (ms): with `RAYON_NUM_THREADS=1` the work of one case, and
/// unlike wall time hardly affected by other jobs sharing the cores.
fn cpu_ms() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_PROCESS_CPUTIME_ID is always available on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 * 1e3 + ts.tv_nsec as f64 * 1e-6
}

/// Median process CPU time (ms) of `runs` calls of `f` (see [`cpu_ms`]), and the median
/// wall-clock time (ms) of the same calls: with more than one thread the CPU time adds the
/// threads' times, so the wall time is the figure of a multi-core goal. The clones a call makes
/// of its input are inside both.
fn median_ms(runs: usize, mut f: impl FnMut()) -> (f64, f64) {
    let (mut t, mut w): (Vec<f64>, Vec<f64>) = (0..runs)
        .map(|_| {
            let (s, c) = (cpu_ms(), std::time::Instant::now());
            f();
            (cpu_ms() - s, c.elapsed().as_secs_f64() * 1e3)
        })
        .unzip();
    t.sort_by(f64::total_cmp);
    w.sort_by(f64::total_cmp);
    (t[t.len() / 2], w[w.len() / 2])
}

/// FNV-1a over the bits of the adapted positions, bend angles and fates of `trees`.
fn fingerprint(trees: &[PlasticTree]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |v: u32| {
        for b in v.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for t in trees {
        for p in t.positions() {
            eat(p.x.to_bits());
            eat(p.y.to_bits());
            eat(p.z.to_bits());
        }
        for b in t.bend_angles() {
            eat(b.to_bits());
        }
        for f in t.fates() {
            eat(*f as u32);
        }
    }
    h
}

/// The sky of every environment: `SYLVA_PLASTIC_SKY_RINGS=4,8,8,12` (ring direction counts,
/// see `Sky::with_rings`; `zenith:4,8,8,12` for the equal zenith bands of rounds 1–10), else
/// the default sky.
fn sky() -> Sky {
    match std::env::var("SYLVA_PLASTIC_SKY_RINGS") {
        Ok(v) => {
            let (old, list) = match v.strip_prefix("zenith:") {
                Some(l) => (true, l.to_string()),
                None => (false, v),
            };
            let rings: Vec<usize> = list.split(',').map(|t| t.trim().parse().expect("SYLVA_PLASTIC_SKY_RINGS: counts")).collect();
            if old { Sky::zenith_rings(Vec3::Z, &rings) } else { Sky::with_rings(Vec3::Z, &rings) }.expect("SYLVA_PLASTIC_SKY_RINGS")
        }
        Err(_) => Sky::default(),
    }
}

/// Open space under [`sky`] with `obstacles`.
fn env_with(obstacles: &[Obstacle]) -> Environment {
    Environment { sky: sky(), ..Environment::with_obstacles(obstacles) }
}

/// The move light model of the wall moves (`PlasticTree::set_move_light`): `SYLVA_PLASTIC_MOVE_LIGHT=exact`
/// for the exact move, a number for its tolerance (m), else
/// [`sylva::structure::plastic::MOVE_LIGHT_TOL_M`].
fn move_light() -> Option<f32> {
    match std::env::var("SYLVA_PLASTIC_MOVE_LIGHT") {
        Ok(v) if v == "exact" => None,
        Ok(v) => Some(v.parse().expect("SYLVA_PLASTIC_MOVE_LIGHT: exact or a tolerance in m")),
        Err(_) => Some(sylva::structure::plastic::MOVE_LIGHT_TOL_M),
    }
}

/// A finite wall beside a tree of crown half-width `r` and height `h` (m).
fn wall_for(r: f32, h: f32) -> Obstacle {
    Obstacle::FiniteWall { x: 0.5 * r, length: 4.0 * r, height: 1.2 * h }
}

/// `SYLVA_PLASTIC_PROFILE=CYCLES,SEED` (e.g. `14,5`, the 9,133-node tree): grows that one
/// tree, analyses it, adapts it beside the wall once and once more after moving the wall 10 cm,
/// printing the CPU time of each step and the wall time of the first adaptation (for a
/// profiler: no search over seeds, no medians). `SYLVA_PLASTIC_ADAPTS=N` repeats the first
/// adaptation N more times, `SYLVA_PLASTIC_MOVES=N` the wall move. The moves use the move light
/// model ([`move_light`]), on from the first adaptation (which it leaves exact).
fn profile_case(case: &str, lp: &sylva::species::LightGuidedParams, lo: &LightOptions, p: &sylva::species::PlasticParams) {
    let v: Vec<u64> = case.split(',').filter_map(|t| t.trim().parse().ok()).collect();
    let (years, seed) = (v.first().copied().unwrap_or(14) as u32, v.get(1).copied().unwrap_or(5));
    let sk = light_guided::grow(lp, lo, &[], seed, years).expect("grow");
    let (lo_b, hi_b) = sk.bounds().expect("nodes");
    let wall = wall_for(0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y), hi_b.z - lo_b.z);
    let t0 = cpu_ms();
    let tree = PlasticTree::analyse(&sk, p, &env_with(&[]), None).expect("analyse");
    let t1 = cpu_ms();
    let mut t = tree.clone();
    t.set_move_light(move_light()).expect("move light");
    let wall_clock = std::time::Instant::now();
    let rep = t.adapt(&env_with(&[wall])).expect("adapt");
    let wall_ms = wall_clock.elapsed().as_secs_f64() * 1e3;
    let t2 = cpu_ms();
    let first = fingerprint(std::slice::from_ref(&t));
    let moved = match wall {
        Obstacle::FiniteWall { x, length, height } => Obstacle::FiniteWall { x: x + 0.1, length, height },
        o => o,
    };
    // `SYLVA_PLASTIC_FIRST_MOVES=N`: N more first moves, each from a copy of the tree as the
    // first adaptation left it (the bench's move column; for a profile of that move)
    let first_moves: usize = std::env::var("SYLVA_PLASTIC_FIRST_MOVES").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    for _ in 0..first_moves {
        std::hint::black_box(t.clone().adapt(&env_with(&[moved])).expect("adapt"));
    }
    let t2m = cpu_ms();
    let rep2 = t.adapt(&env_with(&[moved])).expect("adapt");
    let t3 = cpu_ms();
    // `SYLVA_PLASTIC_MOVES=N`: N more moves of the wall by ±10 cm (for a profile of the moves)
    let extra: usize = std::env::var("SYLVA_PLASTIC_MOVES").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    // `SYLVA_PLASTIC_ADAPTS=N`: N more first adaptations (for a profile of the first adaptation)
    let again: usize = std::env::var("SYLVA_PLASTIC_ADAPTS").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    for _ in 0..again {
        std::hint::black_box(tree.clone().adapt(&env_with(&[wall])).expect("adapt"));
    }
    let mut m = t.clone();
    for i in 0..extra {
        m.adapt(&env_with(&[if i % 2 == 0 { wall } else { moved }])).expect("adapt");
    }
    println!("{} nodes, {} seasons: analysis {:.1} ms, adapt {:.1} ms CPU, {wall_ms:.1} ms wall ({rep:?}), move wall {:.1} ms ({} recomputed); fingerprints {first:016x}, {:016x}", sk.len(), tree.analysis().seasons, t1 - t0, t2 - t1, t3 - t2m, rep2.recomputed_nodes, fingerprint(std::slice::from_ref(&t)));
}

/// `SYLVA_PLASTIC_PROFILE=stand`: the stand case alone. `SYLVA_PLASTIC_PROFILE=two,N`: the two ≈ 2,540-node trees (11 cycles, seed 4) 1.5 crown
/// radii apart adapted together N times (for a profiler), printing the CPU time of each call.
fn two_case(lp: &sylva::species::LightGuidedParams, lo: &LightOptions, p: &sylva::species::PlasticParams, reps: usize) {
    let sk = light_guided::grow(lp, lo, &[], 4, 11).expect("grow");
    let (lo_b, hi_b) = sk.bounds().expect("nodes");
    let r = 0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y);
    let a = PlasticTree::analyse(&sk, p, &env_with(&[]), None).expect("analyse");
    let mut b = a.clone();
    b.translate(Vec3::new(1.5 * r, 0.0, 0.0));
    let env = env_with(&[]);
    let mut last = Vec::new();
    let t0 = cpu_ms();
    for _ in 0..reps.max(1) {
        let mut pair = vec![a.clone(), b.clone()];
        adapt_group(&mut pair, &env).expect("group");
        last = pair;
    }
    println!("two {}-node trees adapted together {reps} times: {:.2} ms CPU each; fingerprint {:016x}", sk.len(), (cpu_ms() - t0) / reps.max(1) as f64, fingerprint(&last));
}

/// Issue 31, Build 3 (the paper's ecosystem demo ran at 5 fps): 50 trees of the ≈ 2,500-node
/// bench skeleton (five turns of it about the vertical, analysed once each) on a 10 × 5 lattice
/// 1.5 crown radii apart, adapted together (`adapt_group`) beside a wall 20 cm thick, as long as
/// the stand is deep and 1.2 times the trees' height, standing between the 5th and 6th columns;
/// then the wall moved 10 cm per step for 10 steps, each step re-adapted. Prints wall-clock
/// times (the goal is steps per second on the machine's cores) and the stand's fingerprint.
fn stand_case(sk: &Skeleton, p: &sylva::species::PlasticParams, prints: &mut Vec<String>) {
    let (lo_b, hi_b) = sk.bounds().expect("nodes");
    let r = 0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y);
    let h = hi_b.z - lo_b.z;
    let root = sk.nodes[0].pos;
    let variants: Vec<PlasticTree> = (0..5)
        .map(|i| {
            let q = glam::Quat::from_rotation_z(i as f32 * std::f32::consts::TAU / 5.0);
            let mut turned = sk.clone();
            for n in &mut turned.nodes {
                n.pos = root + q * (n.pos - root);
            }
            PlasticTree::analyse(&turned, p, &env_with(&[]), None).expect("analyse")
        })
        .collect();
    let s = 1.5 * r;
    let mut trees = Vec::new();
    for c in 0..10 {
        for row in 0..5 {
            let mut t = variants[(c * 3 + row) % 5].clone();
            t.translate(Vec3::new(c as f32 * s, (row as f32 - 2.0) * s, 0.0) - root);
            trees.push(t);
        }
    }
    let wall_at = |x: f32| Obstacle::OrientedBox { center: Vec3::new(x, 0.0, 0.6 * h), half: Vec3::new(0.1, 3.0 * s, 0.6 * h), yaw_deg: 0.0 };
    let x0 = 4.5 * s;
    let t0 = std::time::Instant::now();
    let first = adapt_group(&mut trees, &env_with(&[wall_at(x0)])).expect("stand");
    let first_ms = t0.elapsed().as_secs_f64() * 1e3;
    let steps = 10;
    let mut rec = 0;
    let t1 = std::time::Instant::now();
    for i in 1..=steps {
        rec += adapt_group(&mut trees, &env_with(&[wall_at(x0 + 0.1 * i as f32)])).expect("stand").recomputed_nodes;
    }
    let steps_ms = t1.elapsed().as_secs_f64() * 1e3;
    let nodes: usize = trees.iter().map(|t| t.positions().len()).sum();
    println!(
        "\nstand of 50 {}-node trees ({nodes} nodes, 10 × 5 at {s:.2} m), a wall through it moved 10 cm per step: first adaptation {first_ms:.0} ms ({} nodes recomputed); {steps} steps {steps_ms:.0} ms = {:.1} steps/s ({} nodes recomputed per step; wall-clock, threads: {})",
        sk.len(),
        first.recomputed_nodes,
        steps as f64 / (steps_ms * 1e-3),
        rec / steps,
        rayon::current_num_threads()
    );
    prints.push(format!("stand: {:016x}", fingerprint(&trees)));
}

fn main() {
    let lib = SpeciesLibrary::embedded().expect("embedded species");
    let sp = &lib.species[lib.find("beech").expect("beech") as usize];
    let mut p = sp.architecture.plastic;
    p.phototropism = 0.25; // the paper's Tree 1 (section 6)
    p.gravitropism = 0.12;
    let lp = params::light_guided_paper();
    // the light-guided model (Yi et al.) with the paper parameters in a 24 m × 24 m × 22 m space
    let lo = LightOptions { extent_m: 12.0, height_m: 22.0, ..LightOptions::default() };
    println!("# Plastic Trees benchmark (light-guided trees beside a finite wall; threads: {})", rayon::current_num_threads());
    // the move columns: the move light model unless SYLVA_PLASTIC_MOVE_LIGHT=exact; the last
    // two columns the exact move always
    println!("| target nodes | cycles | seed | nodes | analysis ms | adapt ms | regrow ms | regrow / adapt | bent | pruned | move wall 10 cm: ms (recomputed nodes) | adapt wall-clock ms | move wall-clock ms | exact move ms | exact move wall-clock ms |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    if let Some(case) = std::env::var_os("SYLVA_PLASTIC_PROFILE") {
        let case = case.to_string_lossy();
        if case == "stand" {
            // the stand case alone (for a profiler)
            let sk = light_guided::grow(&lp, &lo, &[], 4, 11).expect("grow");
            stand_case(&sk, &p, &mut Vec::new());
        } else if let Some(reps) = case.strip_prefix("two") {
            two_case(&lp, &lo, &p, reps.trim_start_matches(',').parse().unwrap_or(50));
        } else {
            profile_case(&case, &lp, &lo, &p);
        }
        return;
    }
    let regrow = std::env::var_os("SYLVA_PLASTIC_NO_REGROW").is_none();
    let mut prints = Vec::new();
    let mut mid: Option<Skeleton> = None;
    let mut years = 4u32;
    for target in [530usize, 2540, 9130] {
        // the fewest cycles whose seed-1 tree reaches the target, then of that and one cycle
        // fewer, seeds 1–6, the tree nearest the target in node count
        let mut sk = light_guided::grow(&lp, &lo, &[], 1, years).expect("grow");
        while sk.len() < target && years < 60 {
            years += 1;
            sk = light_guided::grow(&lp, &lo, &[], 1, years).expect("grow");
        }
        let mut seed = 1u64;
        for y in [years.saturating_sub(1).max(1), years] {
            for s in 1..=6u64 {
                let cand = light_guided::grow(&lp, &lo, &[], s, y).expect("grow");
                if cand.len().abs_diff(target) < sk.len().abs_diff(target) {
                    (sk, seed, years) = (cand, s, y);
                }
            }
        }
        let (lo_b, hi_b) = sk.bounds().expect("nodes");
        let wall = wall_for(0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y), hi_b.z - lo_b.z);
        let env = env_with(&[wall]);
        let t0 = cpu_ms();
        let tree = PlasticTree::analyse(&sk, &p, &env_with(&[]), None).expect("analyse");
        let analysis_ms = cpu_ms() - t0;
        let mut rep = None;
        let (adapt_ms, adapt_wall) = median_ms(7, || {
            let mut t = tree.clone();
            rep = Some(t.adapt(&env).expect("adapt"));
        });
        let rep = rep.expect("ran");
        let mut adapted = tree.clone();
        adapted.set_move_light(move_light()).expect("move light");
        adapted.adapt(&env).expect("adapt");
        let mut exact = tree.clone();
        exact.adapt(&env).expect("adapt");
        let mut rec = 0;
        let moved = match wall {
            Obstacle::FiniteWall { x, length, height } => Obstacle::FiniteWall { x: x + 0.1, length, height },
            o => o,
        };
        let mut after_move = adapted.clone();
        let (move_ms, move_wall) = median_ms(7, || {
            let mut t = adapted.clone();
            rec = t.adapt(&env_with(&[moved])).expect("adapt").recomputed_nodes;
            after_move = t;
        });
        let mut after_exact = exact.clone();
        let (exact_ms, exact_wall) = median_ms(7, || {
            let mut t = exact.clone();
            t.adapt(&env_with(&[moved])).expect("adapt");
            after_exact = t;
        });
        prints.push(format!("{} (seed {seed}): adapt {:016x}, moved wall {:016x} (exact {:016x})", sk.len(), fingerprint(std::slice::from_ref(&adapted)), fingerprint(std::slice::from_ref(&after_move)), fingerprint(std::slice::from_ref(&after_exact))));
        let t1 = cpu_ms();
        if regrow {
            std::hint::black_box(light_guided::grow(&lp, &lo, &[wall], seed, years).expect("regrow"));
        }
        let regrow_ms = cpu_ms() - t1;
        println!(
            "| {target} | {years} | {seed} | {} | {analysis_ms:.1} | {adapt_ms:.2} | {regrow_ms:.0} | {:.0}× | {} | {} | {move_ms:.2} ({rec}) | {adapt_wall:.2} | {move_wall:.2} | {exact_ms:.2} | {exact_wall:.2} |",
            sk.len(),
            regrow_ms / adapt_ms,
            rep.bent,
            rep.pruned_light + rep.pruned_collision
        );
        if target == 2540 {
            mid = Some(sk.clone());
        }
    }
    if let Some(sk) = &mid {
        let (lo_b, hi_b) = sk.bounds().expect("nodes");
        let r = 0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y);
        let a = PlasticTree::analyse(&sk, &p, &env_with(&[]), None).expect("analyse");
        let mut b = a.clone();
        b.translate(Vec3::new(1.5 * r, 0.0, 0.0));
        let env = env_with(&[]);
        let mut rec = 0;
        let mut last = Vec::new();
        let (ms, wall_ms) = median_ms(7, || {
            let mut pair = vec![a.clone(), b.clone()];
            rec = adapt_group(&mut pair, &env).expect("group").recomputed_nodes;
            last = pair;
        });
        prints.push(format!("two trees: {:016x}", fingerprint(&last)));
        println!("\ntwo {}-node trees {:.2} m apart (1.5 crown radii) adapted together: {ms:.2} ms ({rec} nodes recomputed; wall-clock {wall_ms:.2} ms)", sk.len(), 1.5 * r);
        stand_case(sk, &p, &mut prints);
    }
    println!("\nresult fingerprints (FNV-1a of positions, bend angles, fates): {}", prints.join("; "));
}
