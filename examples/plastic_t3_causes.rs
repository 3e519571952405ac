//! What Plastic Trees removes from Table 1's trees, cause by cause, against what growth beside
//! the wall loses (issue 31, round 38, `docs/plastic_table1.md` "Round 38"):
//! `cargo run --release --example plastic_t3_causes -- [SEED0] [PAIRS] [TYPE]` (defaults 101,
//! 50, 3) builds the sets O, G and T of one type as
//! [`sylva::structure::plastic::evaluation::evaluate_type`] does (the same seeds, parameters and
//! wall at the main distance; the trees are grown cycle by cycle here to count what each cycle's
//! shedding removed) and prints, as means per tree:
//! - nodes and size S = Σ node radius (cm) of O, G and T, of T adapted without eq. (11)'s
//!   shedding (c_ψ = 0) and of O cut at the wall (its nodes beyond the plane and what hangs
//!   below them removed: what the wall takes geometrically);
//! - for T, the nodes and S removed per cause, by the fate of the removed subtree's root: light
//!   (eq. 11; how much of it in front of the wall, on the wall's half, and the roots' age and
//!   radius), collision with a node already beyond the wall in the input, collision of a node
//!   bent into the wall; the segments bent by more than 1°;
//! - ψ_ref of eq. (11) as the analysis takes it (5th percentile of the ψ_s(t) > 0), recomputed
//!   from the analysis' stage light, as the 5th percentile of all ψ_s(t), and the share of zeros;
//! - for G against O: the nodes lost, O's nodes beyond the wall, the nodes shed by the growth
//!   model's r_s rule over the cycles, the nodes on the open half;
//! - T–G and G–G means and Welch's p for T and for T without eq. (11).
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashSet;
use sylva::species::PlasticParams;
use sylva::structure::grow::light_guided::LightSpace;
use sylva::structure::grow::space::Obstacle;
use sylva::structure::plastic::evaluation::{EvalOptions, MAIN_WALL_FRACTION, PAPER_TYPES};
use sylva::structure::plastic::{Environment, Fate, PlasticTree};
use sylva::structure::skeleton::Skeleton;

fn size_cm(sk: &Skeleton) -> f64 {
    sk.nodes.iter().map(|n| 100.0 * n.radius as f64).sum()
}

/// Per tree, everything counted (nodes, S in cm).
#[derive(Default, Clone, Debug)]
struct Counts {
    o_nodes: f64,
    o_s: f64,
    o_beyond_nodes: f64, // O's nodes beyond the wall, with what hangs below them
    o_beyond_s: f64,
    g_nodes: f64,
    g_s: f64,
    g_shed: f64, // nodes the growth model shed over its cycles
    g_open_side: f64,
    o_open_side: f64,
    t_nodes: f64,
    t_s: f64,
    light_roots: f64,
    light_nodes: f64,
    light_s: f64,
    light_roots_wallside: f64, // own light sheds on the wall's half of the crown (x > 0)
    light_front_nodes: f64, // light-shed nodes in front of the wall (not in O's geometric cut)
    light_front_s: f64,
    light_root_season: f64, // sum over roots of T − season of the root
    light_root_radius_cm: f64,
    o_shed_abs: f64,
    coll_in_roots: f64,  // collision roots whose input node is beyond the wall already
    coll_in_nodes: f64,
    coll_in_s: f64,
    coll_bent_roots: f64, // collision roots bent into the wall (input in front of it)
    coll_bent_nodes: f64,
    coll_bent_s: f64,
    bent: f64,
    alive_in_cut: f64,        // T nodes alive although in O's geometric cut
    alive_beyond: f64,        // T nodes alive whose adapted position is beyond the plane
    alive_in_cut_moved_cm: f64, // sum over the former of how far in front of the plane they stand now
    // T without eq. (11) (c_psi = 0): bending and collisions only
    t0_nodes: f64,
    t0_s: f64,
    // eq. (11)'s ψ_ref: the analysis' (5th percentile of the ψ_s(t) > 0), recomputed here from
    // the analysis' stage light, and the 5th percentile of all ψ_s(t) (zeros included), and
    // the share of zeros
    psi_ref: f64,
    psi_ref_lit: f64,
    psi_ref_all: f64,
    psi_zero_share: f64,
}

/// Every ψ_s(t) of eq. (10) of the analysed tree that eq. (11) judges (the branch at least
/// two seasons old at stage t), as `analysis::analyse` computes them: ζ = Σ 2π r_c² i_c over
/// the stage clusters below (i_c the stage light over its best-lit cluster), l the length of
/// the stage subtree.
fn all_psi(t: &PlasticTree) -> Vec<f32> {
    let a = t.analysis();
    let sk = t.input();
    let n = sk.len();
    let mut out = Vec::new();
    for (st, clusters) in a.stages.iter().enumerate() {
        let li = &a.stage_light[st];
        let m = li.iter().copied().fold(0.0f32, f32::max);
        let (mut zeta, mut len) = (vec![0.0f32; n], vec![0.0f32; n]);
        for (c, &i) in clusters.iter().zip(li) {
            zeta[c.anchor as usize] += 2.0 * std::f32::consts::PI * c.radius * c.radius * if m > 0.0 { i / m } else { i };
        }
        for k in (1..n).rev() {
            if a.season[k] as usize > st {
                continue;
            }
            len[k] += sk.segment_length(k);
            if len[k] > 0.0 && st >= a.season[k] as usize + 2 {
                out.push(zeta[k] / len[k]);
            }
            let p = sk.nodes[k].parent.unwrap_or(0) as usize;
            let (z, l) = (zeta[k], len[k]);
            zeta[p] += z;
            len[p] += l;
        }
    }
    out
}

fn pct5(mut v: Vec<f32>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let i = v.len() / 20;
    *v.select_nth_unstable_by(i, f32::total_cmp).1 as f64
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed0: u64 = args.first().map(|s| s.parse()).transpose()?.unwrap_or(101);
    let pairs: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(50);
    let ty_i: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(3);
    let ty = PAPER_TYPES[ty_i - 1];
    let o = EvalOptions { pairs, wall_fraction: MAIN_WALL_FRACTION, seed0, ..EvalOptions::default() };
    let rest = 1.0 - ty.phototropism - ty.gravitropism;
    let mut lp = sylva::structure::params::light_guided_paper();
    lp.mu = ty.phototropism / rest;
    lp.gamma = ty.gravitropism / rest;
    lp.r_s *= ty.shedding_factor;
    let cycles = ((o.cycles as f32 * ty.age_factor).round() as u32).max(1);
    let pp = PlasticParams { phototropism: ty.phototropism, gravitropism: ty.gravitropism, pruning_c_psi: 0.8, translucency_gamma_c0: 0.5 };
    let n = 2 * pairs;
    // grows one tree cycle by cycle, counting the nodes each cycle's shedding removed (nodes
    // present before a cycle and missing after it: growth only adds, shedding only removes)
    let grow = |obs: &[Obstacle], seed: u64| -> anyhow::Result<(Skeleton, usize)> {
        let mut ls = LightSpace::new(&[Vec3::ZERO], obs, lp, o.light, seed)?;
        let mut shed = 0;
        for _ in 0..cycles {
            let before: HashSet<[u32; 3]> = ls.trees[0].skeleton.nodes.iter().map(|nd| nd.pos.to_array().map(f32::to_bits)).collect();
            ls.step();
            let after: HashSet<[u32; 3]> = ls.trees[0].skeleton.nodes.iter().map(|nd| nd.pos.to_array().map(f32::to_bits)).collect();
            shed += before.difference(&after).count();
        }
        Ok((ls.trees.swap_remove(0).skeleton, shed))
    };
    let open: Vec<(Skeleton, usize)> = (0..n).into_par_iter().map(|k| grow(&[], seed0 + k as u64)).collect::<anyhow::Result<_>>()?;
    let crown = |sk: &Skeleton| {
        let base = sk.nodes[0].pos;
        sk.nodes.iter().map(|nd| (nd.pos - base).truncate().length()).fold(0.0f32, f32::max)
    };
    let r_o = open.iter().map(|(s, _)| crown(s)).sum::<f32>() / n as f32;
    let wall_x = o.wall_fraction * r_o;
    let wall = [Obstacle::Wall { x: wall_x }];
    let env = Environment::with_obstacles(&wall);
    let per: Vec<(Counts, Skeleton, Skeleton, Skeleton)> = open
        .par_iter()
        .enumerate()
        .map(|(k, (sk, o_shed))| -> anyhow::Result<_> {
            let (g, g_shed) = grow(&wall, seed0 + k as u64)?;
            let mut c = Counts { o_nodes: sk.len() as f64, o_s: size_cm(sk), g_nodes: g.len() as f64, g_s: size_cm(&g), g_shed: g_shed as f64 - *o_shed as f64, o_shed_abs: *o_shed as f64, ..Default::default() };
            c.g_open_side = g.nodes.iter().filter(|nd| nd.pos.x <= 0.0).count() as f64;
            c.o_open_side = sk.nodes.iter().filter(|nd| nd.pos.x <= 0.0).count() as f64;
            // O's nodes beyond the wall and below them (what a geometric cut removes)
            let mut cut = vec![false; sk.len()];
            for i in 1..sk.len() {
                let p = sk.nodes[i].parent.unwrap_or(0) as usize;
                cut[i] = cut[p] || sk.nodes[i].pos.x >= wall_x;
            }
            c.o_beyond_nodes = cut.iter().filter(|&&x| x).count() as f64;
            c.o_beyond_s = sk.nodes.iter().zip(&cut).filter(|(_, &x)| x).map(|(nd, _)| 100.0 * nd.radius as f64).sum();
            let mut t = PlasticTree::analyse(sk, &pp, &Environment::open(), None)?;
            let psi = all_psi(&t);
            c.psi_ref = t.analysis().psi_ref as f64;
            c.psi_zero_share = psi.iter().filter(|&&v| v == 0.0).count() as f64 / psi.len().max(1) as f64;
            c.psi_ref_all = pct5(psi.clone());
            c.psi_ref_lit = pct5(psi.into_iter().filter(|&v| v > 0.0).collect());
            let rep = t.adapt(&env)?;
            c.bent = rep.bent as f64;
            let ts = t.skeleton();
            c.t_nodes = ts.len() as f64;
            c.t_s = size_cm(&ts);
            let fate = t.fates();
            let inp = t.input();
            // the root of every removed subtree, and its subtree's nodes and S
            let mut root_of = vec![usize::MAX; inp.len()];
            for i in 1..inp.len() {
                let p = inp.nodes[i].parent.unwrap_or(0) as usize;
                if fate[i] != Fate::Alive {
                    root_of[i] = if fate[p] == Fate::Alive { i } else { root_of[p] };
                }
            }
            for i in 1..inp.len() {
                if fate[i] == Fate::Alive {
                    let x = t.positions()[i].x;
                    c.alive_beyond += (x >= wall_x) as u8 as f64;
                    if cut[i] {
                        c.alive_in_cut += 1.0;
                        c.alive_in_cut_moved_cm += 100.0 * (wall_x - x) as f64;
                    }
                    continue;
                }
                let r = root_of[i];
                let own = r == i;
                let s = 100.0 * inp.nodes[i].radius as f64;
                match fate[r] {
                    Fate::Light => {
                        c.light_nodes += 1.0;
                        c.light_s += s;
                        if !cut[i] {
                            c.light_front_nodes += 1.0;
                            c.light_front_s += s;
                        }
                        if own {
                            c.light_roots += 1.0;
                            c.light_root_season += (t.analysis().seasons - t.analysis().season[i]) as f64;
                            c.light_root_radius_cm += s;
                            if inp.nodes[i].pos.x > 0.0 {
                                c.light_roots_wallside += 1.0;
                            }
                        }
                    }
                    Fate::Collision if inp.nodes[r].pos.x >= wall_x => {
                        c.coll_in_nodes += 1.0;
                        c.coll_in_s += s;
                        c.coll_in_roots += own as u8 as f64;
                    }
                    Fate::Collision => {
                        c.coll_bent_nodes += 1.0;
                        c.coll_bent_s += s;
                        c.coll_bent_roots += own as u8 as f64;
                    }
                    Fate::Alive => {}
                }
            }
            // without light pruning (c_ψ = 0): the same tree, thresholds 0
            let p0 = PlasticParams { pruning_c_psi: 0.0, ..pp };
            let mut t0 = PlasticTree::analyse(sk, &p0, &Environment::open(), None)?;
            t0.adapt(&env)?;
            let t0s = t0.skeleton();
            c.t0_nodes = t0s.len() as f64;
            c.t0_s = size_cm(&t0s);
            Ok((c, g, ts, t0s))
        })
        .collect::<anyhow::Result<_>>()?;
    let m = n as f64;
    let mean = |f: &dyn Fn(&Counts) -> f64| per.iter().map(|(c, ..)| f(c)).sum::<f64>() / m;
    println!("type {ty_i}, seeds {seed0}–{}, {cycles} cycles, r_O {r_o:.2} m, wall x = {wall_x:.2} m", seed0 + n as u64 - 1);
    println!("| set | nodes | S (cm) |\n|---|---|---|");
    println!("| O | {:.0} | {:.1} |", mean(&|c| c.o_nodes), mean(&|c| c.o_s));
    println!("| G | {:.0} | {:.1} |", mean(&|c| c.g_nodes), mean(&|c| c.g_s));
    println!("| T | {:.0} | {:.1} |", mean(&|c| c.t_nodes), mean(&|c| c.t_s));
    println!("| T, c_ψ = 0 | {:.0} | {:.1} |", mean(&|c| c.t0_nodes), mean(&|c| c.t0_s));
    println!("| O cut at the wall | {:.0} | {:.1} |", mean(&|c| c.o_nodes - c.o_beyond_nodes), mean(&|c| c.o_s - c.o_beyond_s));
    println!("\nT per tree, by cause (mean): nodes removed (subtree roots) S");
    println!("light (eq. 11): {:.1} ({:.1} roots, {:.1} of them on the wall's half) S {:.1}", mean(&|c| c.light_nodes), mean(&|c| c.light_roots), mean(&|c| c.light_roots_wallside), mean(&|c| c.light_s));
    println!("  of them in front of the wall (not in O's geometric cut): {:.1} nodes, S {:.1}; roots: mean age T − t_s {:.2} seasons, mean radius {:.2} cm", mean(&|c| c.light_front_nodes), mean(&|c| c.light_front_s), mean(&|c| c.light_root_season) / mean(&|c| c.light_roots), mean(&|c| c.light_root_radius_cm) / mean(&|c| c.light_roots));
    println!("collision, beyond the wall in the input: {:.1} ({:.1}) S {:.1}", mean(&|c| c.coll_in_nodes), mean(&|c| c.coll_in_roots), mean(&|c| c.coll_in_s));
    println!("collision, bent into the wall: {:.1} ({:.1}) S {:.1}", mean(&|c| c.coll_bent_nodes), mean(&|c| c.coll_bent_roots), mean(&|c| c.coll_bent_s));
    println!("ψ_ref (eq. 11): analysis {:.5}, recomputed (ψ > 0) {:.5}, all ψ_s(t) {:.5}; share of ψ_s(t) = 0: {:.3}", mean(&|c| c.psi_ref), mean(&|c| c.psi_ref_lit), mean(&|c| c.psi_ref_all), mean(&|c| c.psi_zero_share));
    println!("alive in T although in O's cut: {:.1} nodes, standing {:.1} cm in front of the plane on average; alive beyond the plane: {:.1}", mean(&|c| c.alive_in_cut), mean(&|c| c.alive_in_cut_moved_cm) / mean(&|c| c.alive_in_cut).max(1e-9), mean(&|c| c.alive_beyond));
    println!("segments bent > 1°: {:.1}", mean(&|c| c.bent));
    println!("\nG per tree against O (mean): nodes O − G {:.1}, S O − G {:.1}; O's nodes beyond the wall {:.1} (S {:.1}); nodes shed over the cycles: O {:.1}, G − O {:+.1}; nodes on the open half (x ≤ 0): O {:.1}, G {:.1}", mean(&|c| c.o_nodes - c.g_nodes), mean(&|c| c.o_s - c.g_s), mean(&|c| c.o_beyond_nodes), mean(&|c| c.o_beyond_s), mean(&|c| c.o_shed_abs), mean(&|c| c.g_shed), mean(&|c| c.o_open_side), mean(&|c| c.g_open_side));
    // the groups of Table 1 for T as adapted and for T without light pruning
    let d = |a: &Skeleton, b: &Skeleton| sylva::structure::edit_distance::constrained_edit_distance(a, b).map(|v| 100.0 * v as f64);
    let gg: Vec<f64> = (0..pairs).into_par_iter().map(|k| d(&per[2 * k].1, &per[2 * k + 1].1)).collect::<sylva::Result<_>>()?;
    for (name, pick) in [("T", 2usize), ("T, c_ψ = 0", 3)] {
        let get = |k: usize| if pick == 2 { &per[k].2 } else { &per[k].3 };
        let tg: Vec<f64> = (0..pairs).into_par_iter().map(|k| d(get(k), &per[k + pairs].1)).collect::<sylva::Result<_>>()?;
        let mt = tg.iter().sum::<f64>() / pairs as f64;
        let mg = gg.iter().sum::<f64>() / pairs as f64;
        println!("{name}: T–G {mt:.1}, G–G {mg:.1}, p {:.3}", sylva::structure::plastic::evaluation::welch_p(&tg, &gg)?);
    }
    Ok(())
}
