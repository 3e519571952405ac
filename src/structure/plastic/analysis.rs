//! Tree analysis of Plastic Trees section 4 (Pirk et al. 2012, `000_*.txt`), done once per tree:
//! internode length (mean-shift), growth rates (eq. 1), branch seasons (eq. 2), leaf clusters
//! from terminal lobes and their younger versions (eq. 5), the foliage lobes whose volume casts
//! the clusters' shade ([`FOLIAGE_REACH`], section 8), the temporal light the tree grew in
//! (eqs. 3–4), the untropic direction of every segment (inverse tropism, eqs. 6–9) and the
//! pruning thresholds (eqs. 10–11).

use super::light::{light_many, Occluder, ShadowVolumes, Sky, SkyMask, Solids};
use super::{tropism, Environment};
use crate::error::{Error, Result};
use crate::species::PlasticParams;
use crate::structure::skeleton::Skeleton;
use glam::Vec3;
use rayon::prelude::*;

/// Seasons (years) of growth a terminal lobe spans: the nodes created in the last
/// `LOBE_SEASONS` seasons form the leaf clusters of the input tree.
pub const LOBE_SEASONS: u16 = 2;

/// Most seasons reconstructed; deeper trees are clamped (their oldest levels merge).
pub const MAX_SEASONS: u16 = 400;

/// Reach of a foliage lobe relative to d_r (the path distance from the root to the furthest
/// leaf): a foliage lobe is a maximal subtree whose segments, from its parent junction to its
/// furthest tip, reach at most `FOLIAGE_REACH·d_r`. Section 8 of the paper keeps only the
/// branches above a thickness threshold in the tree graph and turns "the smaller branches" into
/// the leaf clusters (Livny et al. 2011, texture lobes): the volume of thin twigs is where the
/// foliage is, and that volume is what casts shade. Our terminal lobes (the nodes of the last
/// [`LOBE_SEASONS`] seasons) stay the units of light, pruning and density (eqs. 10–13); the
/// shade they cast is the foliage lobe's (see [`shade_casters`]).
///
/// Why 0.3: the terminal lobes of our light-guided trees hold one or two internodes, so their
/// spheres (radius at least ½ l_i) fill a small part of the crown; as occluders they let most
/// light through the gaps between them. Measured on an 8-year light-guided beech (436 nodes,
/// seed 3) 1.2 m from the trunk of a 40-year one (1,510 nodes, 16.2 m), the sapling's mean
/// cluster light (eq. 3) grown in the open → adapted beside the neighbour, its bent segments and
/// its segments shed for light (round 13, BENCHMARKS.md): terminal lobes alone 0.94 → 0.86,
/// 0 bent, 0 shed; reach 0.2: 0.91 → 0.59, 20, 0; 0.25: 0.84 → 0.41, 169, 26; 0.3: 0.74 → 0.32,
/// 188, 67 (the 40-year
/// crown then casts 78 foliage spheres). Texture lobes (Livny et al. 2011) are of this scale:
/// a few dozen per crown.
pub const FOLIAGE_REACH: f32 = 0.3;

/// Second bound of a foliage lobe's reach, in crown radii (the largest horizontal distance of a
/// node from the base): a lobe reaches at most `min(FOLIAGE_REACH·d_r, FOLIAGE_REACH_CROWN·r)`.
/// The two bounds meet for a tree as slender as the 40-year beech that chose
/// [`FOLIAGE_REACH`] (d_r 17.7 m, crown radius 3.22 m); in narrower crowns the lobes stay the
/// size of the laterals instead of taking a third of the leader. Measured on two 60-year
/// light-guided Norway spruces 3 m apart (d_r 42 m, crown radius 2.56 m, 1,512 nodes, round
/// 13): without this bound one sheds 783 nodes, the lower crown on both sides; with it 478, the
/// far side's upper crown kept.
pub const FOLIAGE_REACH_CROWN: f32 = 1.65;

/// A leaf cluster of the input tree (a terminal lobe): a sphere around the young nodes of one
/// branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Lobe {
    /// Nodes of the lobe (input ids, arena order); the first is the lobe's root.
    pub nodes: Vec<u32>,
    /// Centroid of the nodes (m).
    pub center: Vec3,
    /// Radius (m): the largest node distance from the centroid, at least half an internode.
    pub radius: f32,
}

/// A leaf cluster of the tree at one growth stage (section 4.2, Fig. 2b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageCluster {
    /// Node carrying the cluster: the lobe's root, or for a propagated cluster the node that is
    /// a leaf at this stage.
    pub anchor: u32,
    /// Radius r_c (m): the lobe's, or eq. (5) for a propagated cluster.
    pub radius: f32,
    /// The lobe this cluster is, `None` for a propagated (merged) cluster.
    pub lobe: Option<u32>,
    /// Latest season among the nodes the cluster covers (it exists at stages ≥ its anchor's
    /// season and is kept unchanged down to this season).
    pub max_season: u16,
}

/// What section 4 derives from a tree once; adaptation reuses it.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// Internode length l_i (m): the main peak of the distances between nearest branching nodes,
    /// found by mean-shift (section 4.1).
    pub internode_m: f32,
    /// Relative growth rate ν̂_s of eq. (1) per node (0–1; 1 on the fastest axis).
    pub growth_rate: Vec<f32>,
    /// Season in which each node was created (eq. 2, rounded down; root 0).
    pub season: Vec<u16>,
    /// Last season T (the tree's age in reconstructed seasons).
    pub seasons: u16,
    /// Terminal lobes (leaf clusters of the full-grown tree).
    pub lobes: Vec<Lobe>,
    /// Leaf clusters per stage t = 0..=T (index t); stage T holds one cluster per lobe.
    pub stages: Vec<Vec<StageCluster>>,
    /// Light i_c (0–1, eq. 3) on every stage cluster in the environment the tree grew in. With
    /// c_ψ = 0 (nothing shed for light: eq. 11's thresholds are all 0) only the last stage's
    /// light is needed (the leaf clusters', eqs. 12–13) and the earlier stages hold NaN.
    pub stage_light: Vec<Vec<f32>>,
    /// Average light direction (unit, eq. 3) at every node in the stage it was created.
    pub light_dir: Vec<Vec3>,
    /// w_s of eq. (7) per node: (1 − w_p − w_g)^(l_s/l_i).
    pub w_s: Vec<f32>,
    /// Untropic direction d_o of each segment (inverse tropism, eqs. 8–9; unit; root: +z).
    pub d_o: Vec<Vec3>,
    /// Residual p·h − (w_s·d_o + (1 − w_s)·t) of the inverse (zero where eq. 9 has a root; where
    /// it has none the closest-point d_o does not reproduce h and the residual keeps the input
    /// direction when nothing changes).
    pub residual: Vec<Vec3>,
    /// Reference pruning factor ψ_ref of eq. (11): the 5th percentile of the ψ_s(t) > 0 of the
    /// branches judged (our reading: the paper takes all ψ_s(t); inside crowns shaded by
    /// foliage lobes ([`FOLIAGE_REACH`]) more than 5 % of the values are 0, fully dark, which made
    /// ψ_ref 0 and so every threshold ψ_s,min 0: measured on the 9,133-node bench tree, ψ_ref
    /// 8·10⁻⁵ and nothing shed for light beside a wall; with the lit values 1,624 nodes shed).
    /// 0 when c_ψ = 0 (not evaluated: every threshold is 0 whatever it is).
    pub psi_ref: f32,
    /// Pruning threshold ψ_s,min = c_ψ·min(ψ_ref, min_t ψ_s(t)) per node (eq. 11; m of leaf
    /// area per m of branch); 0 (never shed) on the main stem (Gravelius order 0) and the root.
    pub psi_min: Vec<f32>,
    /// Sky directions blocked by solids at each input node position in the environment the
    /// tree grew in (bit k: direction k of [`Sky::dirs`]).
    pub mask: Vec<u32>,
    /// Sky of that environment.
    pub sky: Sky,
    /// Foliage lobe of every node ([`FOLIAGE_REACH`]), `u32::MAX` for the branches above them
    /// (the skeleton proper).
    pub foliage_of: Vec<u32>,
}

/// Checks the skeleton: non-empty, parents before children, finite positions and radii ≥ 0.
pub(crate) fn validate_skeleton(sk: &Skeleton) -> Result<()> {
    let bad = |field: &str, value: String, expected: &str| Err(Error::Invalid { context: "Plastic Trees skeleton".into(), field: field.into(), value, expected: expected.into() });
    if sk.nodes.is_empty() {
        return bad("nodes", "0".into(), "at least the root node");
    }
    for (i, n) in sk.nodes.iter().enumerate() {
        if !n.pos.is_finite() {
            return bad(&format!("node {i} position"), n.pos.to_string(), "finite coordinates (m)");
        }
        if !(n.radius >= 0.0 && n.radius.is_finite()) {
            return bad(&format!("node {i} radius"), n.radius.to_string(), "a finite radius ≥ 0 m");
        }
        match n.parent {
            None if i != 0 => return bad(&format!("node {i} parent"), "none".into(), "a parent (only node 0 is the root)"),
            Some(p) if p as usize >= i => return bad(&format!("node {i} parent"), p.to_string(), "a parent id smaller than the node's (parents first)"),
            _ => {}
        }
    }
    Ok(())
}

/// Checks the Plastic Trees parameters.
pub(crate) fn validate_params(p: &PlasticParams) -> Result<()> {
    let bad = |f: &str, v: String, e: &str| Err(Error::Invalid { context: "Plastic Trees".into(), field: f.into(), value: v, expected: e.into() });
    let (wp, wg) = (p.phototropism, p.gravitropism);
    if !(wp >= 0.0 && wg >= 0.0 && wp + wg < 1.0) {
        return bad("phototropism/gravitropism", format!("{wp}/{wg}"), "weights ≥ 0 with a sum < 1 (eq. 7)");
    }
    if !(0.0..=1.0).contains(&p.translucency_gamma_c0) {
        return bad("translucency_gamma_c0", p.translucency_gamma_c0.to_string(), "0 ..= 1 (eq. 4)");
    }
    if !(p.pruning_c_psi >= 0.0 && p.pruning_c_psi.is_finite()) {
        return bad("pruning_c_psi", p.pruning_c_psi.to_string(), "a finite factor ≥ 0 (paper default 0.8, eq. 11)");
    }
    Ok(())
}

/// Reach of the Gaussian kernel of [`internode_length`]'s mean-shift, in bandwidths: samples
/// further from the point weigh less than e^(−KERNEL_REACH²/2) = e^(−50) ≈ 2·10⁻²² each
/// (at most 4,000 of them: far below the weight of the samples near a mode), and are skipped.
pub const KERNEL_REACH: f64 = 10.0;

/// Internode length (section 4.1): the distances from every branching node and tip to its
/// nearest branching ancestor (or the root), and the most significant mode of their
/// distribution by mean-shift with a Gaussian kernel (bandwidth by Silverman's rule,
/// 1.06·σ·n^(−1/5), at least 1 % of the mean; cut at [`KERNEL_REACH`] bandwidths), started
/// from the eight highest local maxima of the density binned on a grid of a quarter bandwidth
/// (until round 23 from 64 samples at the quantiles: 64 mean-shift paths over every sample,
/// 70 % of the analyses of the full-detail stand bench; BENCHMARKS.md, round 24). Returns the
/// mean segment length when the tree has no branching, and at least 1 mm.
pub fn internode_length(sk: &Skeleton) -> f32 {
    let n = sk.nodes.len();
    if n < 2 {
        return 0.1;
    }
    let mut d_root = vec![0.0f32; n];
    let mut last_branch = vec![0.0f32; n]; // path distance of the nearest branching ancestor
    let mut samples = Vec::new();
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        d_root[k] = d_root[p] + sk.segment_length(k);
        let pb = sk.nodes[p].children.len() >= 2 || p == 0;
        last_branch[k] = if pb { d_root[p] } else { last_branch[p] };
        if sk.nodes[k].children.len() != 1 {
            samples.push(d_root[k] - last_branch[k]);
        }
    }
    samples.retain(|d| *d > 0.0);
    if samples.is_empty() {
        return ((1..n).map(|k| sk.segment_length(k)).sum::<f32>() / (n - 1) as f32).max(1e-3);
    }
    samples.sort_by(f32::total_cmp);
    // bounded cost: at most 4,000 samples (evenly strided over the sorted list)
    if samples.len() > 4000 {
        let step = samples.len() as f32 / 4000.0;
        samples = (0..4000).map(|i| samples[(i as f32 * step) as usize]).collect();
    }
    let m = samples.len() as f64;
    let mean = samples.iter().map(|&x| x as f64).sum::<f64>() / m;
    let sd = (samples.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / m).sqrt();
    let h = (1.06 * sd * m.powf(-0.2)).max(0.01 * mean).max(1e-6);
    // the samples within KERNEL_REACH bandwidths of x (sorted: a window found by bisection);
    // the others weigh less than e^(−KERNEL_REACH²/2) each
    let reach = KERNEL_REACH * h;
    let density_and_shift = |x: f64| {
        let (mut w, mut wx) = (0.0f64, 0.0f64);
        let lo = samples.partition_point(|&s| (s as f64) < x - reach);
        let hi = samples.partition_point(|&s| (s as f64) <= x + reach);
        for &s in &samples[lo..hi] {
            let k = (-0.5 * ((s as f64 - x) / h).powi(2)).exp();
            w += k;
            wx += k * s as f64;
        }
        (w, if w > 0.0 { wx / w } else { x })
    };
    // the starting points: the local maxima of the density on a grid of step h/4 (at most
    // MAX_GRID points), from the samples binned linearly onto it (binned kernel density
    // estimation, Wand 1994, J. Comput. Graph. Stat. 3: 433–445), the densest
    // MODE_STARTS of them; each is then carried to its mode by the exact mean-shift
    const MAX_GRID: usize = 16_384;
    const MODE_STARTS: usize = 8;
    let (x0, x1) = (samples[0] as f64 - 3.0 * h, samples[samples.len() - 1] as f64 + 3.0 * h);
    let grid = (((x1 - x0) / (0.25 * h)).ceil() as usize + 1).clamp(2, MAX_GRID);
    let step = (x1 - x0) / (grid - 1) as f64;
    let mut counts = vec![0.0f64; grid];
    for &s in &samples {
        let u = ((s as f64 - x0) / step).clamp(0.0, (grid - 1) as f64);
        let i = (u.floor() as usize).min(grid - 2);
        let frac = u - i as f64;
        counts[i] += 1.0 - frac;
        counts[i + 1] += frac;
    }
    let reach_cells = ((KERNEL_REACH * h / step).ceil() as usize).min(grid);
    let kernel: Vec<f64> = (0..=reach_cells).map(|j| (-0.5 * (j as f64 * step / h).powi(2)).exp()).collect();
    let dens: Vec<f64> = (0..grid).map(|i| (i.saturating_sub(reach_cells)..(i + reach_cells + 1).min(grid)).map(|j| counts[j] * kernel[i.abs_diff(j)]).sum()).collect();
    let mut peaks: Vec<usize> = (0..grid).filter(|&i| (i == 0 || dens[i] > dens[i - 1]) && (i + 1 == grid || dens[i] >= dens[i + 1])).collect();
    peaks.sort_by(|&a, &b| dens[b].total_cmp(&dens[a]).then(a.cmp(&b)));
    peaks.truncate(MODE_STARTS);
    let mut best = (f64::NEG_INFINITY, mean);
    for &i in &peaks {
        let mut x = x0 + i as f64 * step;
        for _ in 0..100 {
            let (_, nx) = density_and_shift(x);
            let done = (nx - x).abs() < 1e-6 * h;
            x = nx;
            if done {
                break;
            }
        }
        let (w, _) = density_and_shift(x);
        if w > best.0 + 1e-9 {
            best = (w, x);
        }
    }
    (best.1 as f32).max(1e-3)
}

/// Relative growth rates ν̂_s of eq. (1): d_{s,l}/(d_r − d_{s,r}) with d_{s,l} the path
/// distance from the node to its furthest leaf, d_{s,r} from the root to the node and d_r from
/// the root to the furthest leaf; where d_{s,l} < 0.2·d_r the parent's rate is copied (root: 1).
/// Values in (0, 1].
pub fn growth_rates(sk: &Skeleton) -> Vec<f32> {
    let n = sk.nodes.len();
    let mut d_root = vec![0.0f32; n];
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        d_root[k] = d_root[p] + sk.segment_length(k);
    }
    let mut d_leaf = vec![0.0f32; n]; // distance to the furthest leaf below
    for k in (1..n).rev() {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        d_leaf[p] = d_leaf[p].max(d_leaf[k] + sk.segment_length(k));
    }
    let d_r = d_leaf[0];
    let mut nu = vec![1.0f32; n];
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        let rest = d_r - d_root[k];
        nu[k] = if d_leaf[k] >= 0.2 * d_r && rest > 0.0 { (d_leaf[k] / rest).clamp(1e-3, 1.0) } else { nu[p] };
    }
    nu
}

/// Seasons of creation by eq. (2), t_s = t_{s_p} + (l_s/l_i)/ν_s with ν_s = ν̂_s/ν̂_min,
/// rounded down (root 0), clamped to [`MAX_SEASONS`]; ν̂_min is the smallest relative growth
/// rate of eq. (1) over the tree.
///
/// Our reading of eq. (2): section 4.1 defines a branch's growth rate as "how many internodes a
/// given branch produces in one season" and normalises it to ν_s = ν̂_s/ν̂_min, so the slowest
/// branch grows one internode per season and a branch growing ν_s internodes per season needs
/// 1/ν_s seasons per internode (the printed product (l_s/l_i)·ν_s would give the fastest axis
/// the most seasons, against eq. (1)'s "all branches reach their leaf nodes at the same time").
/// Every tip then ends near season ν̂_min·d_r/l_i. Measured on the light-guided bench trees
/// (`benches/plastic.rs`) grown 8, 11 and 14 cycles: 8, 12 and 15 seasons (rounds 1–17 divided
/// by ν̂_s alone, one internode per season on the fastest axis, which gave them 30, 44 and 55
/// seasons: four levels per year of growth). Test:
/// `seasons_of_light_guided_trees_are_their_growth_cycles`.
pub fn seasons(sk: &Skeleton, internode_m: f32, rates: &[f32]) -> Vec<u16> {
    let n = sk.nodes.len();
    let mut t = vec![0.0f32; n];
    let mut out = vec![0u16; n];
    let nu_min = rates.iter().skip(1).copied().fold(1.0f32, f32::min).max(1e-3);
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        t[k] = t[p] + sk.segment_length(k) / internode_m * nu_min / rates[k].max(1e-3);
        out[k] = (t[k].floor().max(0.0) as u32).min(MAX_SEASONS as u32) as u16;
    }
    out
}

/// Terminal lobes: a node created in the last [`LOBE_SEASONS`] seasons joins its parent's lobe
/// when the parent is young too, else it starts one; a tip created earlier is a lobe of its own.
fn lobes(sk: &Skeleton, season: &[u16], last: u16, internode_m: f32) -> Vec<Lobe> {
    let n = sk.nodes.len();
    let young = |k: usize| season[k] + LOBE_SEASONS > last;
    let mut lobe_of = vec![u32::MAX; n];
    let mut lobes: Vec<Lobe> = Vec::new();
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        if young(k) || sk.nodes[k].children.is_empty() {
            if young(k) && p != 0 && young(p) && lobe_of[p] != u32::MAX {
                lobe_of[k] = lobe_of[p];
                lobes[lobe_of[p] as usize].nodes.push(k as u32);
            } else {
                lobe_of[k] = lobes.len() as u32;
                lobes.push(Lobe { nodes: vec![k as u32], center: Vec3::ZERO, radius: 0.0 });
            }
        }
    }
    for l in &mut lobes {
        let c = l.nodes.iter().map(|&k| sk.nodes[k as usize].pos).sum::<Vec3>() / l.nodes.len() as f32;
        let r = l.nodes.iter().map(|&k| sk.nodes[k as usize].pos.distance(c)).fold(0.0f32, f32::max);
        l.center = c;
        l.radius = r.max(0.5 * internode_m);
    }
    lobes
}

/// Leaf clusters of every stage (section 4.2, eq. 5): going back one season at a time, a
/// cluster whose nodes all exist stays; the others move to the nearest ancestor that exists at
/// that stage, and clusters arriving at the same node merge with radius
/// r_n = ∛(Σ r_i³)·Π (d_n/d_i) (d: distance from the root to the cluster centre), at least a
/// tenth of an internode (our floor: the product of many ratios < 1 would vanish).
fn stage_clusters(sk: &Skeleton, season: &[u16], last: u16, lobes: &[Lobe], internode_m: f32) -> Vec<Vec<StageCluster>> {
    let root = sk.nodes[0].pos;
    let mut stages = vec![Vec::new(); last as usize + 1];
    let mut cur: Vec<(StageCluster, Vec3)> = full_grown_clusters(season, lobes).into_iter().zip(lobes.iter().map(|l| l.center)).collect();
    stages[last as usize] = cur.iter().map(|c| c.0).collect();
    for t in (0..last).rev() {
        let mut keep = Vec::with_capacity(cur.len());
        let mut moved: Vec<(u32, f32, Vec3)> = Vec::new(); // (new anchor, r_i, centre_i)
        for (c, centre) in cur {
            if c.max_season <= t {
                keep.push((c, centre));
            } else {
                let mut a = c.anchor as usize;
                while season[a] > t && a != 0 {
                    a = sk.nodes[a].parent.unwrap_or(0) as usize;
                }
                moved.push((a as u32, c.radius, centre));
            }
        }
        moved.sort_by_key(|m| m.0);
        let mut i = 0;
        while i < moved.len() {
            let a = moved[i].0;
            let mut j = i;
            let (mut r3, mut prod) = (0.0f64, 1.0f64);
            let pa = sk.nodes[a as usize].pos;
            let d_n = pa.distance(root) as f64;
            while j < moved.len() && moved[j].0 == a {
                r3 += (moved[j].1 as f64).powi(3);
                let d_i = moved[j].2.distance(root) as f64;
                if d_i > 0.0 {
                    prod *= (d_n / d_i).min(1.0);
                }
                j += 1;
            }
            let r = ((r3.cbrt() * prod) as f32).max(0.1 * internode_m);
            keep.push((StageCluster { anchor: a, radius: r, lobe: None, max_season: season[a as usize] }, pa));
            i = j;
        }
        keep.sort_by_key(|c| (c.0.anchor, c.0.lobe.unwrap_or(u32::MAX)));
        stages[t as usize] = keep.iter().map(|c| c.0).collect();
        cur = keep;
    }
    stages
}

/// The leaf clusters of the full-grown stage T: one per terminal lobe, in lobe order.
fn full_grown_clusters(season: &[u16], lobes: &[Lobe]) -> Vec<StageCluster> {
    lobes
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let ms = l.nodes.iter().map(|&k| season[k as usize]).max().unwrap_or(0);
            StageCluster { anchor: l.nodes[0], radius: l.radius, lobe: Some(i as u32), max_season: ms }
        })
        .collect()
}

/// Foliage lobe of every node (see [`FOLIAGE_REACH`]): node k starts a lobe when the path from
/// its parent through k to the furthest leaf below is at most
/// `min(FOLIAGE_REACH·d_r, FOLIAGE_REACH_CROWN·r)` long (r: the crown radius, the largest
/// horizontal distance of a node from the root) and its parent is in none; its subtree joins
/// it. `u32::MAX` for nodes in no lobe.
pub fn foliage_lobes(sk: &Skeleton) -> Vec<u32> {
    let n = sk.nodes.len();
    let mut d_leaf = vec![0.0f32; n];
    for k in (1..n).rev() {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        d_leaf[p] = d_leaf[p].max(d_leaf[k] + sk.segment_length(k));
    }
    let root = sk.nodes[0].pos;
    let crown_r = sk.nodes.iter().map(|nd| (nd.pos - root).truncate().length()).fold(0.0f32, f32::max);
    let reach = (FOLIAGE_REACH * d_leaf[0]).min(FOLIAGE_REACH_CROWN * crown_r);
    let mut of = vec![u32::MAX; n];
    let mut count = 0u32;
    for k in 1..n {
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        if of[p] != u32::MAX {
            of[k] = of[p];
        } else if d_leaf[k] + sk.segment_length(k) <= reach {
            of[k] = count;
            count += 1;
        }
    }
    of
}

/// Key of the shade group of a stage cluster: its anchor's foliage lobe, or (for an anchor on
/// the skeleton proper) a group of its own keyed by the anchor (above every lobe id).
pub(crate) fn shade_key(foliage_of: &[u32], c: &StageCluster) -> u64 {
    match foliage_of[c.anchor as usize] {
        u32::MAX => (1u64 << 32) | c.anchor as u64,
        f => f as u64,
    }
}

/// The shade casters of one stage: the stage's clusters (`fine`, one per cluster of `clusters`,
/// `None` for a deleted one) grouped by foliage lobe ([`shade_key`]), one translucent sphere
/// per group, sorted by key. A group's sphere encloses its clusters' spheres, centred on their
/// centroid weighted by volume r³; it is cut by `obstacles` (Fig. 4: the radius shrinks to the
/// centre's distance from the nearest, a group whose centre is inside one casts nothing); its
/// translucency is eq. (4) for its radius, γ_c0^R, raised to the volume-weighted share of the
/// group's input nodes still alive (eq. 13; `alive(ci)` is n_c/n_0 of cluster ci). A group of
/// one cluster is that cluster's occluder. Returns (key, occluder) pairs.
pub(crate) fn shade_casters(foliage_of: &[u32], clusters: &[StageCluster], fine: &[Option<Occluder>], alive: impl Fn(usize) -> f32 + Sync, gamma_c0: f32, obstacles: &[crate::structure::grow::space::Obstacle]) -> Vec<(u64, Occluder)> {
    // the keys in cluster order, in one serial pass into a vector of the stage's length, then
    // sorted. A key is one lookup per cluster: over the cores (rayon's collect of a filter, as
    // until round 43 for stages of 512 clusters or more) it gathered a list of vectors, each
    // grown one push at a time, then copied them into one, which cost far more than the
    // lookups (callgrind, 100 targets of `benches/stand.rs`: about 1.5 G instructions of
    // growth and copies; BENCHMARKS.md round 44)
    let mut members: Vec<(u64, usize, Occluder)> = Vec::with_capacity(fine.len());
    members.extend(fine.iter().enumerate().filter_map(|(ci, o)| o.map(|o| (shade_key(foliage_of, &clusters[ci]), ci, o))));
    // by (key, cluster): a stable sort by key alone gives that order (the clusters come in
    // index order)
    sort_by_shade_key(&mut members);
    // the groups (runs of one key), each merged on its own over the cores: every group's sums
    // are taken in member order as in one pass, so the casters are the same bit for bit
    // whatever the thread count
    let mut groups: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < members.len() {
        let key = members[i].0;
        let mut j = i;
        while j < members.len() && members[j].0 == key {
            j += 1;
        }
        groups.push((i, j));
        i = j;
    }
    let merged: Vec<Option<(u64, Occluder)>> = groups
        .par_iter()
        .with_min_len(SHADE_CHUNK)
        .map(|&(i, j)| {
            let group = &members[i..j];
            let key = group[0].0;
            if let [(_, _, o)] = group {
                return Some((key, *o));
            }
            let (mut vol, mut centre, mut share) = (0.0f32, Vec3::ZERO, 0.0f32);
            for &(_, ci, o) in group {
                let v = o.radius * o.radius * o.radius;
                vol += v;
                centre += o.center * v;
                share += v * alive(ci);
            }
            let (centre, share) = (centre / vol, share / vol);
            let r = group.iter().map(|(_, _, o)| o.center.distance(centre) + o.radius);
            let r = r.fold(0.0f32, f32::max).min(obstacles.iter().map(|o| o.signed_distance(centre)).fold(f32::INFINITY, f32::min));
            (r > 0.0).then(|| (key, Occluder { center: centre, radius: r, gamma: gamma_c0.powf(r * share) }))
        })
        .collect();
    merged.into_iter().flatten().collect()
}

/// Fewest stage clusters (or shade groups) per task when [`shade_casters`] splits a stage over
/// the cores: below twice this a stage is one task (no join of the cores). An ESTIMATE, the
/// value of the stage occluders' split (`SIG_CHUNK` in `transform.rs`), not tuned.
const SHADE_CHUNK: usize = 256;

/// Sorts `members` stably by key (the first field): a counting sort over the foliage lobes' keys
/// (below 2³²; the keys of clusters anchored on the skeleton proper, 2³² + anchor, come after
/// them in the order given, which is anchor order for a stage's clusters, else they are sorted
/// stably among themselves) when the largest lobe key is not far above the count, else the
/// standard stable sort. The same order either way. Measured (callgrind, issue 31's wall move of
/// the 9,133-node bench tree): the standard sort took about 3 M instructions a call, on the
/// serial path of every level.
fn sort_by_shade_key<T: Copy>(members: &mut Vec<(u64, usize, T)>) {
    let lobe = |k: u64| k < (1u64 << 32);
    let max = members.iter().filter(|m| lobe(m.0)).map(|m| m.0).max();
    let Some(max) = max else {
        members.sort_by_key(|m| m.0);
        return;
    };
    if max as usize > 4 * members.len() + 1024 {
        members.sort_by_key(|m| m.0);
        return;
    }
    // start of every lobe key's run (counting sort), the anchored clusters after them
    let mut start = vec![0u32; max as usize + 2];
    let mut rest = 0usize;
    for m in members.iter() {
        if lobe(m.0) {
            start[m.0 as usize + 1] += 1;
        } else {
            rest += 1;
        }
    }
    for i in 1..start.len() {
        start[i] += start[i - 1];
    }
    let lobes = start[max as usize + 1] as usize;
    let mut out = Vec::with_capacity(members.len());
    // placeholders (copies of a member), each slot overwritten once below
    out.resize(members.len(), members[0]);
    let mut at = lobes;
    for m in members.iter() {
        if lobe(m.0) {
            out[start[m.0 as usize] as usize] = *m;
            start[m.0 as usize] += 1;
        } else {
            out[at] = *m;
            at += 1;
        }
    }
    debug_assert_eq!(at, lobes + rest);
    // the anchored clusters' keys in the order given: already sorted for a stage (anchor order)
    if !out[lobes..].is_sorted_by_key(|m| m.0) {
        out[lobes..].sort_by_key(|m| m.0);
    }
    *members = out;
}

/// The shade casters ([`shade_casters`]) of stage clusters `clusters` with centres `centres`
/// as grown: every cluster alive, eq. (4) translucency γ_c0^r_c, no obstacle cut.
///
/// A cluster's own γ_c0^r_c is read only when it is alone in its group (a group of several
/// takes γ_c0^R of its enclosing radius), so it is taken for those clusters only: the members
/// carry NaN, which [`shade_casters`] passes through unchanged for a group of one and never
/// reads for a larger one, and each caster still NaN is a lone cluster's, given γ_c0^r_c then
/// (the same casters bit for bit; `powf` per cluster of every stage was about 1.4 % of the
/// instructions of the stand bench's analyses, callgrind, BENCHMARKS.md round 44).
pub(crate) fn input_casters(foliage_of: &[u32], clusters: &[StageCluster], centres: &[Vec3], gamma_c0: f32) -> Vec<Occluder> {
    let fine: Vec<Option<Occluder>> = clusters.iter().zip(centres).map(|(c, &centre)| Some(Occluder { center: centre, radius: c.radius, gamma: f32::NAN })).collect();
    shade_casters(foliage_of, clusters, &fine, |_| 1.0, gamma_c0, &[])
        .into_iter()
        .map(|(_, o)| if o.gamma.is_nan() { Occluder { gamma: gamma_c0.powf(o.radius), ..o } } else { o })
        .collect()
}

/// Inverse tropism (eqs. 8–9): the untropic unit direction d_o with w_s·d_o = p·h − t_w
/// (t_w = (1 − w_s)·t, h and t unit), p the larger root of
/// w_s² = p²|h|² − 2p(h·t_w) + |t_w|²; without a root, p from the first derivative (the point of
/// the line closest to the sphere). w_s ≤ 10⁻⁶ returns h.
pub fn inverse_tropism(h: Vec3, t: Vec3, w_s: f32) -> Vec3 {
    inverse_parts(h, t, w_s).0
}

/// [`inverse_tropism`] with the line parameter p of eq. (8).
fn inverse_parts(h: Vec3, t: Vec3, w_s: f32) -> (Vec3, f32) {
    if w_s <= 1e-6 {
        return (h, 1.0);
    }
    let tw = (1.0 - w_s) * t;
    let (a, b, c) = (h.length_squared(), h.dot(tw), tw.length_squared() - w_s * w_s);
    let disc = b * b - a * c;
    let p = if disc >= 0.0 { (b + disc.sqrt()) / a } else { b / a };
    (((p * h - tw) / w_s).normalize_or(h), p)
}

/// Centre of stage cluster `c` given node positions `pos`: a lobe's centroid moved by the mean
/// offset of its nodes (section 5.2), a propagated cluster at its anchor.
pub(crate) fn cluster_center(c: &StageCluster, lobes: &[Lobe], input: &Skeleton, pos: &[Vec3]) -> Vec3 {
    match c.lobe {
        Some(l) => {
            let lobe = &lobes[l as usize];
            let off = lobe.nodes.iter().map(|&k| pos[k as usize] - input.nodes[k as usize].pos).sum::<Vec3>() / lobe.nodes.len() as f32;
            lobe.center + off
        }
        None => pos[c.anchor as usize],
    }
}

/// The light of eq. (3) brought into 0–1 by the normalisation constant c: our reading takes c
/// per stage as 1/max over the stage's clusters that `keep` (so ψ of eq. 10 measures how shaded
/// a branch is relative to the best-lit part of the tree at that stage; a uniform loss of sky,
/// e.g. a dull day, sheds nothing).
pub(crate) fn normalised(light: &[f32], keep: impl Fn(usize) -> bool) -> Vec<f32> {
    let m = light.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, &l)| l).fold(0.0f32, f32::max);
    if m > 0.0 {
        light.iter().map(|l| l / m).collect()
    } else {
        light.to_vec()
    }
}

/// True when a branch created in `season` is judged by eq. (11) at stage `t`: from its
/// [`LOBE_SEASONS`]-th season on (our reading of "a branch that does not receive light for a
/// longer period of time eventually dies off": a shoot has its first seasons to form a lobe).
pub(crate) fn judged(season: u16, t: u16) -> bool {
    t >= season + LOBE_SEASONS
}

/// Accumulates ψ_s(t) = ζ_s(t)/l_s(t) (eq. 10) for the nodes existing at stage `t`: ζ from the
/// stage's clusters (2π r_c² i_c), l the total branch length of the stage subtree. `alive`
/// masks pruned nodes; `zeta`/`len` are scratch of the tree's size. ψ is written for nodes of
/// season ≤ t with length > 0, NaN elsewhere.
pub(crate) fn psi_at_stage(sk: &Skeleton, season: &[u16], t: u16, clusters: &[StageCluster], light: &[f32], alive: &[bool], zeta: &mut [f32], len: &mut [f32], psi: &mut [f32]) {
    psi_over((1..sk.nodes.len()).rev(), sk, season, t, clusters, light, alive, zeta, len, psi);
}

/// [`psi_at_stage`] visiting only `nodes` (indices ≥ 1 in descending order, a child before
/// its parent): ψ is written for those of them of season ≤ `t` as [`psi_at_stage`] writes it,
/// bit for bit when `nodes` holds every node of season ≤ `t` (their sums are taken in the same
/// order; the nodes left out add nothing); the other entries of `psi` are left as they are.
#[allow(clippy::too_many_arguments)]
pub(crate) fn psi_over(nodes: impl Iterator<Item = usize>, sk: &Skeleton, season: &[u16], t: u16, clusters: &[StageCluster], light: &[f32], alive: &[bool], zeta: &mut [f32], len: &mut [f32], psi: &mut [f32]) {
    zeta.iter_mut().for_each(|z| *z = 0.0);
    len.iter_mut().for_each(|z| *z = 0.0);
    for (c, &i) in clusters.iter().zip(light) {
        if alive[c.anchor as usize] {
            zeta[c.anchor as usize] += 2.0 * std::f32::consts::PI * c.radius * c.radius * i;
        }
    }
    for k in nodes {
        if season[k] > t || !alive[k] {
            psi[k] = f32::NAN;
            continue;
        }
        len[k] += sk.segment_length(k);
        psi[k] = if len[k] > 0.0 { zeta[k] / len[k] } else { f32::NAN };
        let p = sk.nodes[k].parent.unwrap_or(0) as usize;
        let (z, l) = (zeta[k], len[k]);
        zeta[p] += z;
        len[p] += l;
    }
    psi[0] = f32::NAN;
}

/// The tree's shape as the analysis reads it: internode length l_i (`internode_m`, checked, or
/// the mean-shift estimate), growth rates (eq. 1), seasons (eq. 2), the last season T and the
/// terminal lobes.
#[allow(clippy::type_complexity)]
fn shape_of(sk: &Skeleton, internode_m: Option<f32>) -> Result<(f32, Vec<f32>, Vec<u16>, u16, Vec<Lobe>)> {
    let l_i = match internode_m {
        Some(l) if l > 0.0 && l.is_finite() => l,
        Some(l) => return Err(Error::Invalid { context: "Plastic Trees".into(), field: "internode_m".into(), value: l.to_string(), expected: "a finite length > 0 m".into() }),
        None => internode_length(sk),
    };
    let rates = growth_rates(sk);
    let season = seasons(sk, l_i, &rates);
    let last = season.iter().copied().max().unwrap_or(0);
    let lobes = lobes(sk, &season, last, l_i);
    Ok((l_i, rates, season, last, lobes))
}

/// Runs the analysis of section 4 on `sk` grown in `grown_in` (its obstacles and sky; the
/// tree alone, without neighbours). `internode_m` overrides the mean-shift estimate when given.
///
/// Errors: [`Error::Invalid`] for a bad skeleton ([`validate_skeleton`]), bad parameters, a
/// non-positive internode or an invalid obstacle.
pub fn analyse(sk: &Skeleton, p: &PlasticParams, grown_in: &Environment, internode_m: Option<f32>) -> Result<Analysis> {
    validate_skeleton(sk)?;
    validate_params(p)?;
    grown_in.validate()?;
    let (l_i, rates, season, last, lobes) = shape_of(sk, internode_m)?;
    let n = sk.nodes.len();
    let stages = stage_clusters(sk, &season, last, &lobes, l_i);
    let foliage_of = foliage_lobes(sk);
    let sky = grown_in.sky.clone();
    let solids = SkyMask::new(Solids { obstacles: &grown_in.obstacles, ground: grown_in.ground }, &sky);
    let mask: Vec<u32> = sk.nodes.iter().map(|nd| solids.mask(nd.pos)).collect();
    let pos: Vec<Vec3> = sk.nodes.iter().map(|nd| nd.pos).collect();
    let mut by_season = vec![Vec::new(); last as usize + 1];
    for (k, &s) in season.iter().enumerate().skip(1) {
        by_season[s as usize].push(k as u32);
    }
    let mut light_dir = vec![Vec3::Z; n];
    let mut stage_light = Vec::with_capacity(stages.len());
    let alive = vec![true; n];
    let (mut zeta, mut len, mut psi) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut psi_min_t = vec![f32::INFINITY; n];
    let mut all_psi = Vec::new();
    for (t, clusters) in stages.iter().enumerate() {
        let centres: Vec<Vec3> = clusters.iter().map(|c| cluster_center(c, &lobes, sk, &pos)).collect();
        let vols = ShadowVolumes::new(&sky, input_casters(&foliage_of, clusters, &centres, p.translucency_gamma_c0));
        let at_nodes: Vec<(Vec3, u32)> = by_season[t].iter().map(|&k| (pos[k as usize], mask[k as usize])).collect();
        for (&k, (_, dir)) in by_season[t].iter().zip(light_many(&sky, &vols, &at_nodes)) {
            light_dir[k as usize] = dir;
        }
        // the clusters' light: ψ of eq. (10) for the thresholds of eq. (11), and the last
        // stage's for the leaf clusters; with c_ψ = 0 every threshold is 0 and only the last
        // stage's is needed
        let prunes = p.pruning_c_psi > 0.0;
        if !prunes && t != last as usize {
            stage_light.push(vec![f32::NAN; clusters.len()]);
            continue;
        }
        let at_centres: Vec<(Vec3, u32)> = centres.iter().map(|&c| (c, solids.mask(c))).collect();
        let li: Vec<f32> = light_many(&sky, &vols, &at_centres).into_iter().map(|(i, _)| i).collect();
        if !prunes {
            stage_light.push(li);
            continue;
        }
        psi_at_stage(sk, &season, t as u16, clusters, &normalised(&li, |_| true), &alive, &mut zeta, &mut len, &mut psi);
        for k in 1..n {
            if psi[k].is_finite() && judged(season[k], t as u16) {
                psi_min_t[k] = psi_min_t[k].min(psi[k]);
                // ψ_ref from the lit branches only (see Analysis::psi_ref)
                if psi[k] > 0.0 {
                    all_psi.push(psi[k]);
                }
            }
        }
        stage_light.push(li);
    }
    let psi_ref = if all_psi.is_empty() {
        0.0
    } else {
        let i = all_psi.len() / 20;
        *all_psi.select_nth_unstable_by(i, f32::total_cmp).1
    };
    let mut psi_min: Vec<f32> = psi_min_t.iter().map(|&m| p.pruning_c_psi * psi_ref.min(m)).collect();
    // the main stem is never shed (our addition: eq. 11 alone would shed a leader whose light
    // falls by more than 1 − c_ψ below its historical minimum, killing the whole tree)
    for (k, nd) in sk.nodes.iter().enumerate() {
        if nd.gravelius == 0 {
            psi_min[k] = 0.0;
        }
    }
    let base = 1.0 - p.phototropism - p.gravitropism;
    let mut w_s = vec![1.0f32; n];
    let mut d_o = vec![Vec3::Z; n];
    let mut residual = vec![Vec3::ZERO; n];
    for k in 1..n {
        let par = sk.nodes[k].parent.unwrap_or(0) as usize;
        let seg = pos[k] - pos[par];
        let l = seg.length();
        w_s[k] = base.powf(l / l_i);
        if l > 0.0 {
            let (h, t) = (seg / l, tropism(p, light_dir[k]));
            let (d, pp) = inverse_parts(h, t, w_s[k]);
            d_o[k] = d;
            residual[k] = pp * h - (w_s[k] * d + (1.0 - w_s[k]) * t);
        }
    }
    Ok(Analysis { internode_m: l_i, growth_rate: rates, season, seasons: last, lobes, stages, stage_light, light_dir, w_s, d_o, residual, psi_ref, psi_min, mask, sky, foliage_of })
}

/// The part of the analysis (section 4) that a tree standing unadapted among adapted ones
/// needs (the `fixed` trees of [`super::transform::adapt_group_among`], a stand's context
/// trees, which only shade and block): the internode length (`internode_m` or the mean-shift
/// estimate), growth rates, seasons, terminal lobes, the full-grown stage's clusters
/// (`stages[T]`; the earlier stages are empty) and the foliage lobes, without any light: the
/// light fields are empty (`stage_light[T]` NaN, `light_dir`, `w_s`, `d_o`, `residual` and
/// `mask` empty), ψ_ref is 0 and every ψ_s,min 0, the sky is `sky`. Such a tree cannot be
/// adapted ([`super::PlasticTree::standing`]). The light of the full analysis was most of a
/// context tree's cost and none of it was read.
///
/// Errors: as [`analyse`] (skeleton, parameters, internode).
pub fn analyse_shape(sk: &Skeleton, p: &PlasticParams, sky: &super::Sky, internode_m: Option<f32>) -> Result<Analysis> {
    validate_skeleton(sk)?;
    validate_params(p)?;
    let (l_i, rates, season, last, lobes) = shape_of(sk, internode_m)?;
    let n = sk.nodes.len();
    let mut stages = vec![Vec::new(); last as usize + 1];
    stages[last as usize] = full_grown_clusters(&season, &lobes);
    let mut stage_light = vec![Vec::new(); last as usize + 1];
    stage_light[last as usize] = vec![f32::NAN; lobes.len()];
    let foliage_of = foliage_lobes(sk);
    Ok(Analysis { internode_m: l_i, growth_rate: rates, season, seasons: last, lobes, stages, stage_light, light_dir: Vec::new(), w_s: Vec::new(), d_o: Vec::new(), residual: Vec::new(), psi_ref: 0.0, psi_min: vec![0.0; n], mask: Vec::new(), sky: sky.clone(), foliage_of })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::grow::space::Obstacle;

    /// A trunk of two 5 m segments, a 2 m twig and a 6 m limb at 5 m: d_r = 5 + 6 = 11 m, so
    /// foliage lobes reach at most 0.3·11 = 3.3 m from their parent junction.
    #[test]
    fn foliage_lobes_are_the_maximal_subtrees_within_the_reach() {
        let mut sk = Skeleton::new();
        let root = sk.add_root(Vec3::ZERO, 0.2);
        let mid = sk.add_child(root, Vec3::new(0.0, 0.0, 5.0), 0.15, false).unwrap();
        let top = sk.add_child(mid, Vec3::new(0.0, 0.0, 10.0), 0.05, false).unwrap();
        let t1 = sk.add_child(mid, Vec3::new(1.0, 0.0, 5.0), 0.02, true).unwrap();
        let t2 = sk.add_child(t1, Vec3::new(2.0, 0.0, 5.0), 0.01, false).unwrap();
        let l1 = sk.add_child(mid, Vec3::new(0.0, 2.0, 5.0), 0.05, true).unwrap();
        let l2 = sk.add_child(l1, Vec3::new(0.0, 4.0, 5.0), 0.04, false).unwrap();
        let l3 = sk.add_child(l2, Vec3::new(0.0, 6.0, 5.0), 0.02, false).unwrap();
        let of = foliage_lobes(&sk);
        let none = u32::MAX;
        // the twig (reach 2 m) is lobe 0 with its tip; of the limb only its last segment (2 m;
        // the one before reaches 4 m); the leader's top segment (5 m) is skeleton
        assert_eq!([of[root as usize], of[mid as usize], of[top as usize]], [none; 3]);
        assert_eq!([of[t1 as usize], of[t2 as usize]], [0, 0]);
        assert_eq!([of[l1 as usize], of[l2 as usize], of[l3 as usize]], [none, none, 1]);
        // a slender tree: a 20 m trunk of 5 m segments with a 1 m twig at 17.5 m. d_r = 20 m
        // allows 6 m, so by d_r alone the leader's top segment (5 m) would be a lobe; the crown
        // radius (1 m) caps the reach at 1.65 m: only the twig is
        let mut sk = Skeleton::new();
        let mut k = sk.add_root(Vec3::ZERO, 0.3);
        let mut trunk = vec![k];
        for i in 1..=4 {
            k = sk.add_child(k, Vec3::new(0.0, 0.0, 5.0 * i as f32), 0.1, false).unwrap();
            trunk.push(k);
        }
        let below_top = sk.add_child(trunk[3], Vec3::new(0.0, 0.0, 17.5), 0.05, false);
        let twig = sk.add_child(below_top.unwrap(), Vec3::new(1.0, 0.0, 17.5), 0.01, true).unwrap();
        let of = foliage_lobes(&sk);
        assert!(trunk.iter().all(|&t| of[t as usize] == none), "{of:?}");
        assert_eq!(of[twig as usize], 0);
    }

    /// The counting sort of the shade keys gives the standard stable sort's order: lobe keys
    /// (repeated, out of order), anchored keys in and out of order, equal anchored keys, and a
    /// lobe key far above the count (the standard sort's path).
    #[test]
    fn shade_key_sort_is_the_stable_sort() {
        let anchored = |a: u64| (1u64 << 32) | a;
        let cases: Vec<Vec<u64>> = vec![
            vec![],
            vec![5],
            vec![anchored(3), anchored(1)],
            (0..300u64).map(|i| (i * 37) % 23).collect(),
            (0..300u64).map(|i| if i % 4 == 0 { anchored(i) } else { (i * 7919) % 101 }).collect(),
            (0..300u64).map(|i| if i % 3 == 0 { anchored(300 - i) } else { (i * 13) % 17 }).collect(),
            (0..50u64).map(|i| if i % 5 == 0 { anchored(7) } else { i % 3 }).collect(),
            vec![4, 1_000_000, 2, anchored(1), 4, 0],
        ];
        for keys in cases {
            let members: Vec<(u64, usize, u32)> = keys.iter().enumerate().map(|(i, &k)| (k, i, i as u32 * 3)).collect();
            let mut plain = members.clone();
            plain.sort_by_key(|m| m.0);
            let mut ours = members;
            sort_by_shade_key(&mut ours);
            assert_eq!(ours, plain, "keys {keys:?}");
        }
    }

    /// Two clusters of one foliage lobe (unit spheres 2 m apart) cast one sphere enclosing both:
    /// centre halfway, radius 2 m, γ = γ_c0^2; with half its nodes dead (eq. 13) γ_c0^(2·½);
    /// cut by a wall 1.5 m from the centre (Fig. 4). A cluster on the skeleton casts itself.
    #[test]
    fn shade_casters_enclose_a_lobes_clusters() {
        let foliage_of = vec![u32::MAX, 0, 0, u32::MAX];
        let clusters: Vec<StageCluster> = (1..4).map(|a| StageCluster { anchor: a, radius: 1.0, lobe: Some(a - 1), max_season: 0 }).collect();
        let occ = |x: f32, r: f32| Some(Occluder { center: Vec3::new(x, 0.0, 0.0), radius: r, gamma: 0.5f32.powf(r) });
        let fine = vec![occ(0.0, 1.0), occ(2.0, 1.0), occ(9.0, 0.5)];
        let out = shade_casters(&foliage_of, &clusters, &fine, |_| 1.0, 0.5, &[]);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].0, 0);
        let g = out[0].1;
        assert!(g.center.distance(Vec3::new(1.0, 0.0, 0.0)) < 1e-6 && (g.radius - 2.0).abs() < 1e-6 && (g.gamma - 0.25).abs() < 1e-6, "{g:?}");
        assert_eq!(out[1], ((1u64 << 32) | 3, fine[2].unwrap()));
        let thinned = shade_casters(&foliage_of, &clusters, &fine, |ci| if ci == 0 { 1.0 } else { 0.0 }, 0.5, &[]);
        assert!((thinned[0].1.gamma - 0.5).abs() < 1e-6, "{:?}", thinned[0]);
        let cut = shade_casters(&foliage_of, &clusters, &fine, |_| 1.0, 0.5, &[Obstacle::Wall { x: 2.5 }]);
        assert!((cut[0].1.radius - 1.5).abs() < 1e-6, "{:?}", cut[0]);
        // a deleted cluster leaves its lobe's other cluster alone: that cluster's own sphere
        let one = shade_casters(&foliage_of, &clusters, &[occ(0.0, 1.0), None, None], |_| 1.0, 0.5, &[]);
        assert_eq!(one, vec![(0, occ(0.0, 1.0).unwrap())]);
    }

    /// [`shade_casters`] split over the cores (stages of more than twice `SHADE_CHUNK` clusters
    /// and groups) gives, on 1, 2 and 3 threads, the casters of a plain serial merge of each
    /// lobe's clusters in cluster order, bit for bit: 3,000 clusters, 400 lobes and clusters of
    /// their own, some deleted, some alive only in part, cut by a wall.
    #[test]
    fn shade_casters_over_the_cores_are_the_serial_merge() {
        let n = 3000u32;
        let foliage_of: Vec<u32> = (0..=n).map(|a| if a % 11 == 0 { u32::MAX } else { (a * 7919) % 400 }).collect();
        let clusters: Vec<StageCluster> = (1..=n).map(|a| StageCluster { anchor: a, radius: 1.0, lobe: None, max_season: 0 }).collect();
        let fine: Vec<Option<Occluder>> = (0..n as usize)
            .map(|i| {
                let f = i as f32;
                (i % 13 != 5).then(|| Occluder { center: Vec3::new((f * 0.71).sin() * 6.0, (f * 0.53).cos() * 6.0, 3.0 + (f * 0.29).sin().abs() * 9.0), radius: 0.1 + 0.8 * (f * 0.37).sin().abs(), gamma: 0.4 })
            })
            .collect();
        let alive = |ci: usize| if ci % 7 == 3 { 0.5 } else { 1.0 };
        let wall = [Obstacle::Wall { x: 4.0 }];
        // the reference: every lobe's clusters merged in cluster order, keys ascending
        let mut by_key: std::collections::BTreeMap<u64, Vec<usize>> = std::collections::BTreeMap::new();
        for (ci, o) in fine.iter().enumerate() {
            if o.is_some() {
                by_key.entry(shade_key(&foliage_of, &clusters[ci])).or_default().push(ci);
            }
        }
        let mut want = Vec::new();
        for (key, group) in &by_key {
            if let [ci] = group[..] {
                want.push((*key, fine[ci].unwrap()));
                continue;
            }
            let (mut vol, mut centre, mut share) = (0.0f32, Vec3::ZERO, 0.0f32);
            for &ci in group {
                let o = fine[ci].unwrap();
                let v = o.radius * o.radius * o.radius;
                vol += v;
                centre += o.center * v;
                share += v * alive(ci);
            }
            let (centre, share) = (centre / vol, share / vol);
            let r = group.iter().map(|&ci| fine[ci].unwrap().center.distance(centre) + fine[ci].unwrap().radius).fold(0.0f32, f32::max).min(wall[0].signed_distance(centre));
            if r > 0.0 {
                want.push((*key, Occluder { center: centre, radius: r, gamma: 0.5f32.powf(r * share) }));
            }
        }
        assert!(want.len() > 2 * SHADE_CHUNK, "{} casters of {} groups", want.len(), by_key.len());
        let bits = |v: &[(u64, Occluder)]| v.iter().map(|(k, o)| (*k, o.center.to_array().map(f32::to_bits), o.radius.to_bits(), o.gamma.to_bits())).collect::<Vec<_>>();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let got = pool.install(|| shade_casters(&foliage_of, &clusters, &fine, alive, 0.5, &wall));
            assert_eq!(bits(&got), bits(&want), "{threads} threads");
        }
    }

    /// [`input_casters`] takes γ_c0^r_c only for the clusters alone in their group: its casters
    /// are, bit for bit, those of [`shade_casters`] over every cluster given γ_c0^r_c, with
    /// lobes of one cluster, lobes of several and clusters on the skeleton proper, none NaN.
    #[test]
    fn input_casters_are_the_shade_casters_of_every_clusters_own_gamma() {
        let n = 700u32;
        // lobe of node a: every 5th node on the skeleton proper, the others in 260 lobes, some of
        // one cluster (a lobe id met once) and some of several
        let foliage_of: Vec<u32> = (0..=n).map(|a| if a % 5 == 0 { u32::MAX } else { (a * 37) % 260 }).collect();
        let clusters: Vec<StageCluster> = (1..=n).map(|a| StageCluster { anchor: a, radius: 0.05 + 0.01 * (a % 17) as f32, lobe: None, max_season: 0 }).collect();
        let centres: Vec<Vec3> = (0..n).map(|i| Vec3::new((i as f32 * 0.37).sin() * 4.0, (i as f32 * 0.23).cos() * 4.0, 2.0 + (i % 11) as f32 * 0.5)).collect();
        let g0 = 0.43f32;
        let fine: Vec<Option<Occluder>> = clusters.iter().zip(&centres).map(|(c, &centre)| Some(Occluder { center: centre, radius: c.radius, gamma: g0.powf(c.radius) })).collect();
        let want: Vec<Occluder> = shade_casters(&foliage_of, &clusters, &fine, |_| 1.0, g0, &[]).into_iter().map(|(_, o)| o).collect();
        let got = input_casters(&foliage_of, &clusters, &centres, g0);
        let bits = |v: &[Occluder]| v.iter().map(|o| (o.center.to_array().map(f32::to_bits), o.radius.to_bits(), o.gamma.to_bits())).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&want));
        // both kinds of group occur: casters that are a lone cluster's own sphere, and merged ones
        let lone = got.iter().filter(|o| fine.iter().flatten().any(|f| f.center == o.center && f.radius == o.radius)).count();
        assert!(lone > 100 && got.len() - lone > 100, "{lone} lone of {}", got.len());
        assert!(got.iter().all(|o| o.gamma > 0.0 && o.gamma < 1.0));
    }
}
