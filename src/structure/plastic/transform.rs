//! Transformations and interactions of Plastic Trees sections 5–6 (Pirk et al. 2012,
//! `000_*.txt`): trees are bent and pruned level by level of branch age in a changed
//! environment, alone or several together.
//!
//! Per call of [`adapt_group`]:
//! 1. **What changed.** For every input node the sky directions blocked by solids (obstacles,
//!    terrain) and by the other trees' leaf clusters are computed as a bit signature; nodes whose
//!    signature differs from the previous call, and the children of a recomputed node that
//!    turned by more than [`ROTATION_EPS`], are recomputed; the others (which only follow
//!    their parent's displacement)
//!    keep their state (section 5: "parts of the tree are transformed only when required"). A
//!    changed sky (global light) recomputes everything.
//! 2. **Levels.** All trees are processed together by season: with G the largest number of
//!    seasons in the group, a tree of T seasons processes its season t at global level
//!    g = t + (G − T), so the younger trees' schedules end with the others' (section 6,
//!    tree–tree interaction). At each level the leaf clusters of every tree at its stage (moved
//!    with their nodes, section 5.2; cut by obstacles, Fig. 4: the radius shrinks to the distance
//!    from the centre to the obstacle and a cluster whose centre is inside is removed;
//!    translucency γ_c = γ_c0^r_c (eq. 4) raised to n_c/n_0 when nodes of it were removed
//!    (eq. 13)) are the receivers of light; the shadows are cast through [`ShadowVolumes`] by
//!    their foliage lobes ([`super::analysis::FOLIAGE_REACH`], one sphere enclosing the stage
//!    clusters of each lobe, cut and thinned the same way), as in the analysis. Before the
//!    level's casters are built, the nodes created in that season are placed where they stand
//!    before bending (following their parent's rotation), so a tree adapted back to the
//!    environment of its analysis gets its input back.
//! 3. **Bending (eq. 6)** of every recomputed node created in that season:
//!    h' = w_s·(Q_parent d_o) + (1 − w_s)·t', with d_o the untropic direction from the analysis,
//!    Q_parent the parent's rotation (so a turn propagates to the children), w_s of eq. (7) and
//!    t' = t + κ·(t(L') − t), L' the new average light direction at the node, t the tropism it
//!    grew with. κ = 1 − a/(T + 1), a = T − season the branch age in years: old trunks bend
//!    little, but they bend (our form of "transform individual branch segments according to
//!    their estimated age", section 5.1). The season is the segment's own of eq. (2) (its
//!    tip's), except for a forest-grown tree's lengthened bole ([`PlasticTree::set_bole`]),
//!    which takes its parent's, t_{s_p} of eq. (2): the age of its base (round 36). A node that enters an obstacle or the ground (closer
//!    than `clearance_m`), or whose segment crosses one, is removed with its subtree.
//! 4. **Pruning (section 5.1)** after every level: ψ_s(t) = ζ_s(t)/l_s(t) from the light on the
//!    stage's clusters (eq. 10; light normalised per stage by its best-lit cluster, see
//!    [`super::analysis::Analysis::stage_light`]); a branch with ψ_s(t) < ψ_s,min (eq. 11) is shed with its
//!    children. Cluster light is evaluated at the moved cluster centres with the level's
//!    shadow volumes (built before the level's bending).
//!    The light of each level's clusters is evaluated direction by direction; a cluster that
//!    is the same occluder as at the previous level keeps that level's transmittance of a sky
//!    direction when no caster that changed between the two levels (added, removed, moved,
//!    cut or thinned) lies on the ray, which is exactly the value a recomputation gives (the
//!    same casters, multiplied in the same order); levels where most casters changed recompute
//!    everything. Only in a group or among fixed trees: for one tree alone the level's grids are
//!    built for every direction anyway, and the check costs more than the queries it saves.
//! 5. **Leaf density (eq. 12)** ρ_l = ρ_l0·ρ(i)/ρ(i_l0) with ρ(i) = i (linear) for every leaf
//!    cluster of the full-grown stage after the levels: [`PlasticTree::leaf_clusters`] (with the
//!    obstacle-cut radius and the translucency of eqs. 4 and 13) and, per node of the adapted
//!    skeleton, [`PlasticTree::leaf_density`] (what a leaf generator scales its leaf count by).
//! 6. **Wood of other trees** (segments at least `wood_radius_m` thick) is solid: nodes inside it
//!    are removed after the levels; the other trees' leaf clusters are not solid (they overlap
//!    and share the space, section 5.2).
//!
//! Approximation: a node whose signature did not change keeps its state even when moved
//! clusters of recomputed subtrees now shade it differently.
//!
//! **Move light model** (round 37, off by default; [`PlasticTree::set_move_light`]): a lone
//! tree may keep the per-direction transmittances of its light queries between calls, each
//! level's casters kept as a snapshot, so that a call after a small change (a wall moved 10 cm)
//! applies the casters that changed to the stored products instead of rebuilding the level's
//! shadow grids (see `MoveCache`). It changes results on purpose, within tolerances measured
//! against the exact calls (BENCHMARKS.md, round 37); the first call is exact.

use super::analysis::{cluster_center, input_casters, judged, normalised, shade_casters, StageCluster};
use super::light::{light_by, Occluder, ShadowVolumes, SkyMask, Solids};
use super::{tropism, Environment, Fate, PlasticReport, PlasticTree};
use crate::error::Result;
use crate::structure::grow::space::Obstacle;
use glam::{IVec3, Quat, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// What an [`adapt_group`] call did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GroupReport {
    /// One report per tree, in the order given.
    pub trees: Vec<PlasticReport>,
    /// Nodes recomputed over all trees.
    pub recomputed_nodes: usize,
    /// Global levels (seasons) processed.
    pub levels: usize,
}

/// Leaf density ρ_l of eq. (12), ρ_l = ρ_l0·ρ(i)/ρ(i_l0), for a cluster of initial density
/// `rho0` at initial light `i0`, now at light `i` (both 0–1, eq. 3), with ρ(i) = i (linear; the
/// paper leaves ρ open): ρ_l0·i/i_0, ρ_l0 when i_0 = 0. Not clamped: a cluster that receives
/// more light than in the input gets denser than it was.
pub fn cluster_density(rho0: f32, i0: f32, i: f32) -> f32 {
    if i0 > 0.0 {
        rho0 * i / i0
    } else {
        rho0
    }
}

/// Translucency of a cluster after losing nodes, eq. (13): γ_c' = γ_c^(n_c/n_0).
pub fn thinned_translucency(gamma_c: f32, n_c: usize, n_0: usize) -> f32 {
    // γ^1 = γ: a cluster that lost no node (nearly every cluster at nearly every level) costs
    // no `powf` (glibc's powf(γ, 1) is γ, so the value is the same)
    if n_0 == 0 || n_c == n_0 {
        return gamma_c;
    }
    gamma_c.powf(n_c as f32 / n_0 as f32)
}

/// Capsules of solid wood of one tree (segments ≥ its `wood_radius_m`), hashed on a grid.
struct Wood {
    segs: Vec<(Vec3, Vec3, f32)>,
    cell: f32,
    grid: FxHashMap<IVec3, Vec<u32>>,
    /// Bounds of every capsule (m): points outside touch no wood of the tree.
    lo: Vec3,
    hi: Vec3,
}

impl Wood {
    fn of(t: &PlasticTree) -> Wood {
        let mut segs = Vec::new();
        for k in 1..t.input.nodes.len() {
            let r = t.input.nodes[k].radius;
            if t.fate[k] == Fate::Alive && r >= t.wood_radius_m {
                let p = t.input.nodes[k].parent.unwrap_or(0) as usize;
                segs.push((t.pos[p], t.pos[k], r));
            }
        }
        let cell = (2.0 * t.analysis.internode_m).max(0.1);
        let mut grid: FxHashMap<IVec3, Vec<u32>> = FxHashMap::default();
        let (mut lo_b, mut hi_b) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (i, &(a, b, r)) in segs.iter().enumerate() {
            lo_b = lo_b.min(a.min(b) - r);
            hi_b = hi_b.max(a.max(b) + r);
            let lo = ((a.min(b) - r) / cell).floor().as_ivec3();
            let hi = ((a.max(b) + r) / cell).floor().as_ivec3();
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        grid.entry(IVec3::new(x, y, z)).or_default().push(i as u32);
                    }
                }
            }
        }
        Wood { segs, cell, grid, lo: lo_b, hi: hi_b }
    }

    fn contains(&self, p: Vec3) -> bool {
        if !(p.cmpge(self.lo).all() && p.cmple(self.hi).all()) {
            return false;
        }
        let Some(list) = self.grid.get(&(p / self.cell).floor().as_ivec3()) else { return false };
        list.iter().any(|&i| {
            let (a, b, r) = self.segs[i as usize];
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
            p.distance_squared(a + ab * t) <= r * r
        })
    }
}

/// True when node position `p` (segment from `a`) collides: inside an obstacle, closer than
/// `clear` to one while coming nearer to it than `a` is (a segment growing away from an
/// obstacle out of the clearance zone is kept: the branches leaving a trunk that stands within
/// the clearance of a wall on its open side), below the ground, or the segment crosses an
/// obstacle.
fn collides(env: &Environment, a: Vec3, p: Vec3, clear: f32) -> bool {
    if env.ground.is_some_and(|g| g.height_of(p) < 0.0) {
        return true;
    }
    let mid = 0.5 * (a + p);
    env.obstacles.iter().any(|o| {
        let (dp, dm) = (o.signed_distance(p), o.signed_distance(mid));
        if dp < 0.0 || dm < 0.0 || ((dp < clear || dm < clear) && dp < o.signed_distance(a)) {
            return true;
        }
        let d = p - a;
        let l = d.length();
        l > 0.0 && o.ray_hits(a, d / l, l)
    })
}

/// Clearance (m) node `k` of `t` keeps from obstacles: the tree's `clearance_m` for branches,
/// none for the main stem (Gravelius order 0), which is shed only where it crosses an obstacle.
/// Our addition, as for light (the stem is never shed for light): with the clearance (the
/// species' leaf size) a wall 0.2 m from a 10-year beech's trunk cut the stem at its base and
/// shed the whole tree (830 of 831 nodes).
fn clearance(t: &PlasticTree, k: usize) -> f32 {
    if t.input.nodes[k].gravelius == 0 {
        0.0
    } else {
        t.clearance_m
    }
}

/// Smallest signed distance from `c` to the obstacles (m; +∞ without obstacles).
fn obstacle_distance(obs: &[Obstacle], c: Vec3) -> f32 {
    obs.iter().map(|o| o.signed_distance(c)).fold(f32::INFINITY, f32::min)
}

/// The occluders of tree `t` at stage `s`: its stage clusters at their current centres, cut by
/// obstacles, with translucency by eqs. (4) and (13); dead clusters are left out. Returns
/// (occluder or None per stage cluster).
fn stage_occluders(t: &PlasticTree, s: usize, env: &Environment) -> Vec<Option<Occluder>> {
    stage_occluders_with(t, s, env, None, false).into_iter().map(|c| c.occ).collect()
}

/// One stage cluster at a level ([`stage_occluders_with`]): its occluder (None when dead), its
/// share of input nodes alive n_c/n_0 (eq. 13; 0 when dead), the radius r (m) and γ_c0^r of
/// eq. (4) its occluder was made with (NaN when none), which the next level reuses for the same
/// stage cluster at the same radius, and the signed distance (m) from its centre to the
/// obstacles (+∞ without obstacles; NaN when dead), which the next level reuses for the same
/// stage cluster at the same centre.
#[derive(Debug, Clone, Copy)]
struct StageOcc {
    occ: Option<Occluder>,
    share: f32,
    r: f32,
    base: f32,
    dist: f32,
}

/// [`stage_occluders`] with each cluster's alive share (so [`stage_casters`] does not count the
/// lobe's nodes again) and its eq. (4) base γ_c0^r; `earlier` is (index in the previous stage of
/// every cluster of stage `s` that is the same stage cluster, [`match_stage`]; the previous
/// level's clusters). Reused from the previous level, the same values bit for bit:
/// - γ_c0^r of a cluster whose radius is the one it had there (no `powf` again);
/// - the centre of a cluster none of whose nodes is younger than season s − 2: a level moves
///   only the nodes of its season (placed by [`preposition`], bent by [`level`]), so the nodes
///   of such a cluster stand where they stood when the previous level took its centre (the
///   same positions summed in the same order).
/// - the obstacle distance of a cluster whose centre is so reused (the same centre, the same
///   obstacles within a call: the same distance; measured, callgrind, the 10 cm wall move of
///   the 9,133-node bench tree: [`obstacle_distance`] was about 2 % of a move's instructions).
///
/// With `all_alive` (no node of `t` shed or removed) a cluster's (n_c, n_0) of eq. (13) is its
/// node count twice, not counted.
fn stage_occluders_with(t: &PlasticTree, s: usize, env: &Environment, earlier: Option<(&[Option<u32>], &[StageOcc])>, all_alive: bool) -> Vec<StageOcc> {
    let a = &t.analysis;
    let dead = StageOcc { occ: None, share: 0.0, r: f32::NAN, base: f32::NAN, dist: f32::NAN };
    a.stages[s]
        .par_iter()
        .enumerate()
        .with_min_len(SIG_CHUNK)
        .map(|(ci, c)| {
            let (n_c, n_0) = match (all_alive, c.lobe) {
                (true, Some(l)) => (a.lobes[l as usize].nodes.len(), a.lobes[l as usize].nodes.len()),
                (true, None) => (1, 1),
                _ => alive_counts(t, c),
            };
            if n_c == 0 {
                return dead;
            }
            let same = earlier.and_then(|(map, prev)| map.get(ci).copied().flatten().and_then(|j| prev.get(j as usize)));
            let (centre, dist) = match same.and_then(|p| p.occ.map(|o| (o, p.dist))) {
                Some((o, d)) if c.max_season as usize + 2 <= s => (o.center, d),
                _ => {
                    let centre = cluster_center(c, &a.lobes, &t.input, &t.pos);
                    (centre, obstacle_distance(&env.obstacles, centre))
                }
            };
            let r = c.radius.min(dist);
            if !(r > 0.0) {
                return dead;
            }
            let before = same.filter(|p| p.r.to_bits() == r.to_bits());
            let base = match before {
                Some(p) => p.base,
                None => t.params.translucency_gamma_c0.powf(r),
            };
            let gamma = thinned_translucency(base, n_c, n_0);
            StageOcc { occ: Some(Occluder { center: centre, radius: r, gamma }), share: n_c as f32 / n_0.max(1) as f32, r, base, dist }
        })
        .collect()
}

/// (n_c, n_0) of eq. (13) for stage cluster `c` of tree `t`: the input nodes it covers still
/// alive, and all of them (a propagated cluster covers its anchor).
fn alive_counts(t: &PlasticTree, c: &StageCluster) -> (usize, usize) {
    match c.lobe {
        Some(l) => {
            let nodes = &t.analysis.lobes[l as usize].nodes;
            (nodes.iter().filter(|&&k| t.fate[k as usize] == Fate::Alive).count(), nodes.len())
        }
        None => ((t.fate[c.anchor as usize] == Fate::Alive) as usize, 1),
    }
}

/// The shade casters of tree `t` at stage `s` from its stage occluders `fine`
/// ([`stage_occluders`]): one sphere per foliage lobe ([`shade_casters`]), cut by the
/// obstacles, sorted by key.
fn stage_casters(t: &PlasticTree, s: usize, fine: &[Option<Occluder>], env: &Environment) -> Vec<(u64, Occluder)> {
    let clusters = &t.analysis.stages[s];
    let share = |ci: usize| {
        let (n_c, n_0) = alive_counts(t, &clusters[ci]);
        n_c as f32 / n_0.max(1) as f32
    };
    shade_casters(&t.analysis.foliage_of, clusters, fine, share, t.params.translucency_gamma_c0, &env.obstacles)
}

/// [`stage_casters`] from [`stage_occluders_with`]'s clusters, whose alive shares it reads
/// instead of counting the lobes' nodes again (the same casters).
fn stage_casters_of(t: &PlasticTree, s: usize, fine: &[Option<Occluder>], stage: &[StageOcc], env: &Environment) -> Vec<(u64, Occluder)> {
    shade_casters(&t.analysis.foliage_of, &t.analysis.stages[s], fine, |ci| stage[ci].share, t.params.translucency_gamma_c0, &env.obstacles)
}

/// Adapts several trees together to `env` and to each other (sections 5–6; see the module
/// documentation for the steps). Each tree sees the others' leaf clusters as translucent
/// occluders and their wood as solid. Deterministic and independent of the thread count
/// (trees are processed in parallel with rayon, each writing only its own state). Calling it
/// again after a change recomputes only the subtrees whose light or obstacles changed; the
/// report says how many nodes that was.
///
/// Errors: [`crate::Error::Invalid`] for an invalid environment (obstacle or ground), or a
/// tree of [`PlasticTree::standing`] among `trees` (field `tree i`).
pub fn adapt_group(trees: &mut [PlasticTree], env: &Environment) -> Result<GroupReport> {
    adapt_group_among(trees, &[], env)
}

/// [`adapt_group`] among `fixed` trees that are not adapted: they stand as they are (their
/// current positions and living nodes) for the whole life span of the adapted trees, as the
/// obstacles of the paper's tree–obstacle interaction do ("the obstacle then becomes a part of
/// the environment that influences the tree by casting a shadow for the entire life span of its
/// growth", section 6): their full-grown leaf clusters are translucent occluders (eq. 4) and
/// their wood is solid. Used for the context trees around a stand's neighbourhood
/// ([`crate::structure::stand`]): they shade and block the adapted trees without being adapted
/// themselves, so one set of shadow volumes serves every level instead of their clusters being
/// rebuilt at each level. A fixed tree may be a [`PlasticTree::standing`] one (shape only,
/// without light): it casts the same shade and blocks with the same wood.
///
/// Errors: as [`adapt_group`].
pub fn adapt_group_among(trees: &mut [PlasticTree], fixed: &[PlasticTree], env: &Environment) -> Result<GroupReport> {
    adapt_among(trees, fixed, env, false)
}

/// [`adapt_group_among`] for trees that are adapted once and then only read (a stand's
/// neighbourhood, [`crate::structure::stand`]): the same adapted trees and report, bit for
/// bit, but a node's signature (step 1 of the module documentation: the sky directions in
/// which the other trees' and the fixed trees' clusters shade it) is computed only as far as
/// this call needs it. When a node's stored signature holds no shade (a tree fresh from its
/// analysis, scaling or translation), the node is recomputed exactly when its solids' mask
/// changed or some direction is shaded, so the directions are queried (nearest the horizon
/// first, where neighbours shade most) until the first shaded one, not all of them; a node
/// whose mask changed, or a tree whose recomputation is forced, needs no shade query at all.
/// The signatures kept are then partial, so every tree is left to recompute every node in a
/// later call ([`PlasticTree::invalidate`]).
///
/// Errors: as [`adapt_group`].
pub fn adapt_group_among_once(trees: &mut [PlasticTree], fixed: &[PlasticTree], env: &Environment) -> Result<GroupReport> {
    adapt_among(trees, fixed, env, true)
}

/// [`adapt_group_among`], and [`adapt_group_among_once`] when `once`.
fn adapt_among(trees: &mut [PlasticTree], fixed: &[PlasticTree], env: &Environment, once: bool) -> Result<GroupReport> {
    // called from outside the thread pool (a program's main thread), every parallel loop below
    // would be injected into the pool and block this thread on a latch: one cross-thread wake-up
    // per loop, and a level has a loop per depth batch (measured: a fifth of the first
    // adaptation of the 9,133-node bench tree on one thread went to waking the worker). Run the
    // whole call on a worker instead, where the loops fork and join in place.
    if rayon::current_thread_index().is_none() {
        return rayon::scope(|_| adapt_among(trees, fixed, env, once));
    }
    env.validate()?;
    if let Some(i) = trees.iter().position(|t| t.standing) {
        return Err(crate::Error::Invalid { context: "Plastic Trees adaptation".into(), field: format!("tree {i}"), value: "a standing tree (shape only)".into(), expected: "a tree of PlasticTree::analyse (a standing tree can only be among the fixed trees)".into() });
    }
    let sky = &env.sky;
    let solids = SkyMask::new(Solids { obstacles: &env.obstacles, ground: env.ground }, sky);
    // 1. signatures: solids and the other trees' input-time clusters at the final stage
    let neighbours: Vec<(usize, Occluder)> = trees
        .iter()
        .enumerate()
        .flat_map(|(i, t)| {
            let pos: Vec<Vec3> = t.input.nodes.iter().map(|nd| nd.pos).collect();
            let a = &t.analysis;
            let clusters = &a.stages[a.seasons as usize];
            let centres: Vec<Vec3> = clusters.iter().map(|c| cluster_center(c, &a.lobes, &t.input, &pos)).collect();
            input_casters(&a.foliage_of, clusters, &centres, t.params.translucency_gamma_c0).into_iter().map(|o| (i, o)).collect::<Vec<_>>()
        })
        .collect();
    let group = trees.len() > 1;
    // one set of grids over every tree's clusters, each tagged with its tree; tree i's queries
    // leave its own out (the same casters, in the same order, as shadow volumes of the other
    // trees' clusters alone, without building a set per tree: O(N) grid entries, not O(N²))
    let others = (group && trees.len() > OWN_OTHERS_MAX).then(|| {
        let owners = neighbours.iter().map(|(j, _)| *j as u32).collect();
        ShadowVolumes::with_owners(sky, neighbours.iter().map(|(_, o)| *o).collect(), owners)
    });
    // a small group: per tree, shadow volumes of the other trees' clusters alone, told the
    // tree's bounds, so a query scans no cell full of its own tree's clusters (a signature bit
    // is whether any caster is hit, so the answers are the same as the shared grids')
    let own_others: Vec<Option<ShadowVolumes>> = trees
        .iter()
        .enumerate()
        .map(|(i, t)| {
            (group && trees.len() <= OWN_OTHERS_MAX).then(|| {
                let occ: Vec<Occluder> = neighbours.iter().filter(|(j, _)| *j != i).map(|(_, o)| *o).collect();
                let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                for nd in &t.input.nodes {
                    (lo, hi) = (lo.min(nd.pos), hi.max(nd.pos));
                }
                ShadowVolumes::new(sky, occ).within(lo, hi)
            })
        })
        .collect();
    // the fixed trees' full-grown clusters as they stand: one set of shadow volumes for the call
    let fixed_vols = (!fixed.is_empty()).then(|| {
        let occ: Vec<Occluder> = fixed
            .iter()
            .flat_map(|t| {
                let last = t.analysis.seasons as usize;
                stage_casters(t, last, &stage_occluders(t, last, env), env).into_iter().map(|(_, o)| o)
            })
            .collect();
        ShadowVolumes::new(sky, occ)
    });
    let fixed_vols = fixed_vols.as_ref();
    // what the other trees' shade depends on: the sky, every tree's input (its clusters stand
    // where the input has them) and translucency, the fixed trees as they stand now
    let shade_key = {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |v: u64| h = (h ^ v).wrapping_mul(0x0000_0100_0000_01b3);
        sky.dirs.iter().chain(std::iter::once(&sky.brightest)).for_each(|d| d.to_array().iter().for_each(|v| eat(v.to_bits() as u64)));
        sky.weights.iter().for_each(|w| eat(w.to_bits() as u64));
        eat(trees.len() as u64);
        for t in trees.iter() {
            eat(t.input.nodes.len() as u64);
            eat(t.params.translucency_gamma_c0.to_bits() as u64);
            t.input.nodes.iter().for_each(|nd| nd.pos.to_array().iter().for_each(|v| eat(v.to_bits() as u64)));
        }
        eat(fixed.len() as u64);
        for t in fixed {
            eat(t.pos.len() as u64);
            eat(t.params.translucency_gamma_c0.to_bits() as u64);
            t.pos.iter().for_each(|p| p.to_array().iter().for_each(|v| eat(v.to_bits() as u64)));
            t.fate.iter().for_each(|f| eat(*f as u64));
        }
        h.max(1)
    };
    let key_of = |i: usize| (shade_key ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)).max(1);
    // every direction of the shade grids that the signatures query, built over the cores before
    // the signatures (which query every direction at every node): built lazily inside the
    // parallel loop over the nodes, a grid is wanted by both cores at once and one core waits
    // on the other's build (a `OnceLock`) instead of working. The same grids, so the same answers
    let every_dir = sky_bits(sky);
    if trees.iter().enumerate().any(|(i, t)| t.shade_key != key_of(i)) {
        if let Some(o) = others.as_ref() {
            o.prepare(every_dir);
        }
        if let Some(f) = fixed_vols {
            f.prepare(every_dir);
        }
    }
    let own: Vec<(Vec<bool>, bool)> = trees
        .par_iter_mut()
        .enumerate()
        .map(|(i, t)| {
            let n = t.input.nodes.len();
            let all = t.force || t.sky != *sky;
            let mut dirty = vec![false; n];
            // the others' shade is the one of the last call when nothing it depends on changed
            let key = key_of(i);
            let same_shade = t.shade_key == key;
            if !same_shade {
                if let Some(o) = own_others[i].as_ref() {
                    o.prepare(every_dir);
                }
            }
            // every node's signature over the cores (a tree adapted alone has only its own
            // nodes to split), then compared in node order
            let sigs: Vec<u64> = (0..n)
                .into_par_iter()
                .with_min_len(SIG_CHUNK)
                .map(|k| {
                    let p = t.input.nodes[k].pos;
                    let mut sig = solids.mask(p) as u64;
                    let shaded = |d: usize| others.as_ref().is_some_and(|o| o.shaded_except(d, p, i as u32)) || own_others[i].as_ref().is_some_and(|o| o.shaded(d, p)) || fixed_vols.is_some_and(|f| f.shaded(d, p));
                    if same_shade {
                        sig |= t.sig[k] & !(u32::MAX as u64);
                    } else if once && t.sig[k] >> 32 == 0 {
                        // only whether the node is recomputed (`dirty` below): with no shade
                        // stored, exactly when the mask changed or any direction is shaded
                        if !all && sig == t.sig[k] {
                            if let Some(d) = (0..sky.dirs.len()).rev().find(|&d| shaded(d)) {
                                sig |= 1u64 << (32 + d);
                            }
                        }
                    } else {
                        for d in 0..sky.dirs.len() {
                            if shaded(d) {
                                sig |= 1u64 << (32 + d);
                            }
                        }
                    }
                    sig
                })
                .collect();
            for (k, sig) in sigs.into_iter().enumerate() {
                dirty[k] = all || sig != t.sig[k];
                t.sig[k] = sig;
            }
            t.shade_key = key;
            // every node may be shed anew: light pruning is re-evaluated each call
            for f in &mut t.fate {
                *f = Fate::Alive;
            }
            t.force = false;
            t.sky = sky.clone();
            (dirty, all || !same_shade)
        })
        .collect();
    // the move light model serves a tree adapted alone (no group, no fixed trees); its rows are
    // forgotten when everything is recomputed or the others' shade changed
    let lone = !group && fixed.is_empty();
    let own: Vec<Vec<bool>> = own
        .into_iter()
        .zip(trees.iter_mut())
        .map(|((dirty, reset), t)| {
            if let Some(mc) = t.move_light.as_mut() {
                if reset || !lone {
                    mc.clear();
                }
            }
            dirty
        })
        .collect();
    // where this call's light queries can come from: the trees with a node to recompute, as
    // they stand and as grown, widened by their largest cluster and 2 m for the bending within
    // the call (a query outside is still answered exactly, from grids of every caster)
    // and whether the call recomputes only part of its trees (some node is below no changed
    // signature): then each level's grids answer few queries, and coarser cells cost less
    // (`ShadowVolumes::coarse`; the same answers)
    let mut partial = false;
    let region = {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (t, own) in trees.iter().zip(&own) {
            if !own.iter().any(|&x| x) {
                partial = true;
            } else {
                let r = 2.0 + t.analysis.stages.iter().flatten().map(|c| c.radius).fold(0.0f32, f32::max);
                // only the subtrees below a node whose signature changed are recomputed (a
                // node is recomputed when its own signature changed or its parent turned), and
                // the clusters lit are theirs (parents precede their children)
                let mut below = vec![false; own.len()];
                for k in 0..own.len() {
                    let par = t.input.nodes[k].parent.map_or(k, |p| p as usize);
                    below[k] = own[k] || (par < k && below[par]);
                    if below[k] {
                        for p in [t.pos[k], t.input.nodes[k].pos] {
                            (lo, hi) = (lo.min(p - r), hi.max(p + r));
                        }
                    } else {
                        partial = true;
                    }
                }
            }
        }
        (lo, hi)
    };
    // 2.–4. levels; a node is recomputed when its own signature changed or its parent moved
    let mut work: Vec<Work> = own
        .into_iter()
        .zip(trees.iter_mut())
        .map(|(own, t)| {
            let n = own.len();
            // a tree with nothing to recompute replays the levels of its last such call, or
            // records this one's (QuietLevels); any other call forgets them
            let quiet = !own.iter().any(|&x| x);
            let replay = if quiet { t.quiet.take() } else { None };
            t.quiet = None;
            let record = (quiet && replay.is_none()).then(|| QuietLevels { live: vec![Vec::new(); t.analysis.stages.len()], set: Vec::new(), last: vec![Fate::Alive; n] });
            // ψ ≥ 0 (eq. 10), so eq. (11) sheds no node whose ψ_min is 0 or below (every node
            // of a tree with c_ψ = 0, the stand's forest-grown trees)
            let prunes = t.analysis.psi_min.iter().any(|&m| m > 0.0);
            // the nodes (root left out) by season, each season's in index order (a counting sort)
            let last = t.analysis.seasons as usize;
            let mut season_start = vec![0u32; last + 2];
            for &sn in &t.analysis.season[1..] {
                season_start[sn as usize + 1] += 1;
            }
            for i in 1..season_start.len() {
                season_start[i] += season_start[i - 1];
            }
            let mut fill = season_start.clone();
            let mut by_season = vec![0u32; n.saturating_sub(1)];
            for k in 1..n {
                let sn = t.analysis.season[k] as usize;
                by_season[fill[sn] as usize] = k as u32;
                fill[sn] += 1;
            }
            let mc = if lone { t.move_light.take() } else { None };
            Work { before: t.pos.clone(), moved: vec![false; n], shifted: vec![false; n], done: vec![false; n], own, replay, replayed: 0, record, prunes, by_season, season_start, stage: Vec::new(), stage_upto: None, carry: vec![(false, Quat::IDENTITY); n], depth: vec![0; n], pruning: None, mc, mc_epoch: 0, mc_delta: CasterSet::default(), mc_new: true, mc_stats: [0; 4], mc_snapshots: 0 }
        })
        .collect();
    let g_max = trees.iter().map(|t| t.analysis.seasons as usize).max().unwrap_or(0);
    // per tree: the previous level's occluders, shade casters and per-direction cluster
    // transmittances
    let mut prev: Vec<Option<Prev>> = vec![None; trees.len()];
    // whether a cluster's value of the previous level is reused where no changed caster lies
    // on its ray (`Reuse`): for one tree among no fixed trees it cannot pay, as every direction
    // open at a lit cluster has its grid of the level's casters built anyway (`prepare` before
    // the queries, and the level's bending asks for nearly every direction), so a reused value
    // only trades a query of those grids for a query of the changed casters' grids, and those
    // grids cost their builds on top (measured, callgrind, the wall move of the 9,133-node
    // bench tree: 3.4 M instructions a move, 3.5 %, go with the reuse; the same trees bit for
    // bit, as a reused value is the one recomputed). With fixed trees a reused value also
    // saves the query of their grids, and in a group the changed casters are few against the
    // shared grids' casters: kept there (not measured)
    let reuse_pays = trees.len() > 1 || fixed_vols.is_some();
    // the level before's shadow volumes, from whose grids this level's are merged (the casters
    // unchanged bit for bit copied, not binned again; the same grids' answers, round 46)
    let mut prev_vols: Option<ShadowVolumes> = None;
    for g in 0..=g_max {
        let stage_of = |t: &PlasticTree| (g + t.analysis.seasons as usize).checked_sub(g_max);
        // the receivers that are the same stage cluster as at the previous level
        let maps: Vec<Vec<Option<u32>>> = trees.iter().zip(&prev).map(|(t, pr)| match (stage_of(t), pr) {
            (Some(s), Some(_)) if s > 0 => match_stage(&t.analysis.stages[s - 1], &t.analysis.stages[s]),
            (Some(s), _) => vec![None; t.analysis.stages[s].len()],
            _ => Vec::new(),
        }).collect();
        let occ: Vec<(Vec<Option<Occluder>>, Vec<(u64, Occluder)>, Vec<StageOcc>)> = trees
            .par_iter_mut()
            .zip(&mut work)
            .zip(prev.par_iter().zip(&maps))
            .map(|((t, w), (pr, map))| match stage_of(t) {
                Some(s) => {
                    preposition(t, s, w);
                    let all_alive = t.fate.iter().all(|f| *f == Fate::Alive);
                    let stage = stage_occluders_with(t, s, env, pr.as_ref().map(|p| (&map[..], &p.stage[..])), all_alive);
                    let fine: Vec<Option<Occluder>> = stage.iter().map(|c| c.occ).collect();
                    let shade = stage_casters_of(t, s, &fine, &stage, env);
                    (fine, shade, stage)
                }
                None => Default::default(),
            })
            .collect();
        for ((t, w), (_, shade, _)) in trees.iter().zip(work.iter_mut()).zip(&occ) {
            if let (Some(mc), Some(s)) = (w.mc.as_mut(), stage_of(t)) {
                let before = mc.stages.get(s).map_or(0, |st| st.epoch);
                let (epoch, delta) = mc.level(s, shade);
                (w.mc_epoch, w.mc_delta) = (epoch, CasterSet::of_delta(&delta));
                w.mc_new = w.mc_epoch != before;
                w.mc_snapshots += w.mc_new as usize;
            }
        }
        let casters: Vec<Occluder> = occ.iter().flat_map(|(_, c, _)| c.iter().map(|(_, o)| *o)).collect();
        // the casters that differ from the previous level's (removed, added or changed): both
        // lists are sorted by key; only where a reused value can pay (`reuse_pays`)
        let mut delta = Vec::new();
        for ((_, cur, _), pr) in occ.iter().zip(&prev).filter(|_| reuse_pays) {
            let old: &[(u64, Occluder)] = pr.as_ref().map_or(&[], |p| &p.shade);
            by_key(old, cur, |a, b| {
                match (a, b) {
                    (Some(a), Some(b)) if same_occluder(&Some(a), &Some(b)) => {}
                    (Some(a), Some(b)) => delta.extend([a, b]),
                    (a, b) => delta.extend(a.or(b)),
                }
                true
            });
        }
        // reuse pays while the changes are a minority of the casters
        // (measured on the bench trees: below 60 % changed casters the check is cheaper than the
        // products it saves; above, it is not)
        let delta = (reuse_pays && 5 * delta.len() < 3 * casters.len()).then(|| ShadowVolumes::new(sky, delta).within(region.0, region.1));
        // where each of the level before's casters is in this level's list, when it is the same
        // bit for bit (a tree's casters are sorted by key and the trees keep their order, so the
        // indices kept rise)
        let map: Option<Vec<u32>> = prev_vols.as_ref().map(|pv| {
            let mut map = Vec::with_capacity(pv.occluders().len());
            let mut base = 0usize;
            for ((_, cur, _), pr) in occ.iter().zip(&prev) {
                let old: &[(u64, Occluder)] = pr.as_ref().map_or(&[], |p| &p.shade);
                let mut j = 0;
                for (key, o) in old {
                    while j < cur.len() && cur[j].0 < *key {
                        j += 1;
                    }
                    if j < cur.len() && cur[j].0 == *key && same_occluder(&Some(*o), &Some(cur[j].1)) {
                        map.push((base + j) as u32);
                        j += 1;
                    } else {
                        map.push(u32::MAX);
                    }
                }
                base += cur.len();
            }
            map
        });
        let vols = ShadowVolumes::new(sky, casters).within(region.0, region.1).tracked();
        let vols = if partial { vols.coarse() } else { vols };
        let vols = match (prev_vols.take(), map) {
            (Some(pv), Some(map)) if !forced(Forced::FreshGrids) => vols.after(pv, map),
            _ => vols,
        };
        // trees at work at this level share its grids: built over the cores before the trees'
        // levels run side by side (else each tree's first batch builds them, and a core wanting
        // a grid that the other core is building waits for it); only with two or more such
        // trees, as a lone tree's batches ask for exactly the directions they need. Every
        // direction above the terrain: nearly every one is open at some receiver of a tree
        if trees.iter().zip(&work).filter(|(t, w)| stage_of(t).is_some() && w.own.iter().any(|&x| x)).take(2).count() == 2 {
            vols.prepare(every_dir & !solids.below_ground());
        }
        let next: Vec<Option<Prev>> = trees
            .par_iter_mut()
            .zip(&mut work)
            .zip(occ)
            .zip(&prev)
            .zip(&maps)
            .map(|((((t, w), (occ, shade, stage)), pr), map)| {
                let s = stage_of(t)?;
                let reuse = match (&delta, pr) {
                    (Some(d), Some(p)) => Some(Reuse { delta: d, occ: &p.occ, rows: &p.rows, map }),
                    _ => None,
                };
                if let Some(q) = w.replay.as_ref() {
                    if q.live.get(s).is_some_and(|l| l.len() == occ.len() && l.iter().zip(&occ).all(|(&l, o)| l == o.is_some())) {
                        // the level as recorded: the same live clusters, the same fates
                        while let Some(&(st, k, f)) = q.set.get(w.replayed) {
                            if st as usize != s {
                                break;
                            }
                            t.fate[k as usize] = f;
                            w.replayed += 1;
                        }
                        let rows = Rows { start: vec![u32::MAX; occ.len()], t: Vec::new() };
                        return Some(Prev { occ, shade, rows, stage });
                    }
                    // another cluster lives or died (an obstacle reached it): evaluated as
                    // usual from this level on
                    w.replay = None;
                }
                let rows = level(t, s, w, &occ, env, &solids, &vols, fixed_vols, reuse);
                if let Some(r) = w.record.as_mut() {
                    r.live[s] = occ.iter().map(Option::is_some).collect();
                    for (k, (f, last)) in t.fate.iter().zip(&mut r.last).enumerate() {
                        if f != last {
                            r.set.push((s as u32, k as u32, *f));
                            *last = *f;
                        }
                    }
                }
                Some(Prev { occ, shade, rows, stage })
            })
            .collect();
        prev = next;
        prev_vols = Some(vols);
    }
    // the quiet trees keep the levels they replayed whole or recorded; a call `once` leaves
    // partial signatures, so a later call recomputes everything
    for (t, w) in trees.iter_mut().zip(&mut work) {
        if let Some(mc) = w.mc.take() {
            t.move_light = Some(mc);
            static STATS: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
            if *STATS.get_or_init(|| std::env::var_os("SYLVA_PLASTIC_MOVE_STATS").is_some()) {
                let [all, whole, part, dirs] = w.mc_stats;
                eprintln!("move light: {all} queries, {whole} reused whole, {part} in part, {dirs} directions computed; {} levels with a new snapshot", w.mc_snapshots);
            }
            if knobs().check {
                let mut e = CHECK_ERR.lock().unwrap_or_else(|p| p.into_inner());
                let line: Vec<String> = e.iter().enumerate().filter(|(_, b)| b[0] + b[3] > 0.0).map(|(s, b)| format!("L{s}:reused {}/{:.4}/{:.3} fresh {}/{:.4}/{:.3} dark {}/{:.4}", b[0], b[1] / b[0].max(1.0), b[2], b[3], b[4] / b[3].max(1.0), b[5], b[6], b[7] / b[6].max(1.0))).collect();
                let (n, sum) = e.iter().fold((0.0, 0.0), |(n, s), b| (n + b[0], s + b[1]));
                eprintln!("move check: mean {:.5} over {n} reused; {}", sum / f64::max(n, 1.0), line.join(" "));
                e.clear();
            }
        }
        t.quiet = w.replay.take().or_else(|| w.record.take().map(|mut r| {
            r.last = Vec::new();
            Box::new(r)
        }));
        if once {
            t.shade_key = 0;
            t.invalidate();
        }
    }
    // 6. wood of the other trees, then the report
    if group || !fixed.is_empty() {
        let wood: Vec<Wood> = trees.par_iter().map(Wood::of).collect();
        let fixed_wood: Vec<Wood> = fixed.par_iter().map(Wood::of).collect();
        trees.par_iter_mut().enumerate().for_each(|(i, t)| {
            // the other trees' wood whose bounds meet this tree's (a point outside a wood's
            // bounds touches none of it)
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for &p in &t.pos {
                (lo, hi) = (lo.min(p), hi.max(p));
            }
            let near = |w: &&Wood| w.lo.cmple(hi).all() && w.hi.cmpge(lo).all();
            let wood: Vec<&Wood> = wood.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, w)| w).filter(near).collect();
            let fixed_wood: Vec<&Wood> = fixed_wood.iter().filter(near).collect();
            for k in 1..t.input.nodes.len() {
                let p = t.input.nodes[k].parent.unwrap_or(0) as usize;
                if t.fate[p] != Fate::Alive {
                    if t.fate[k] == Fate::Alive {
                        t.fate[k] = t.fate[p];
                    }
                } else if t.fate[k] == Fate::Alive && t.input.nodes[k].gravelius != 0 && (wood.iter().any(|w| w.contains(t.pos[k])) || fixed_wood.iter().any(|w| w.contains(t.pos[k]))) {
                    // the main stem (Gravelius order 0) is not pruned for meeting another
                    // tree's wood, as it is not for clearance or light: two stems the
                    // simulation stands a few centimetres apart both stand (round 32's trial:
                    // an 11.97 m oak 0.21 m from a maple was pruned to its root and left out of
                    // the export)
                    t.fate[k] = Fate::Collision;
                }
            }
        });
    }
    // the leaf clusters of the full-grown stage as they end (section 5.2, eqs. 12–13)
    trees.par_iter_mut().for_each(|t| {
        let last = t.analysis.seasons as usize;
        t.final_occ = stage_occluders(t, last, env);
    });
    let mut rep = GroupReport { trees: Vec::with_capacity(trees.len()), recomputed_nodes: 0, levels: g_max + 1 };
    for (t, w) in trees.iter_mut().zip(&work) {
        let d = &w.done;
        let n = t.input.nodes.len();
        let mut r = PlasticReport { nodes_before: n, recomputed_nodes: d.iter().filter(|&&x| x).count(), ..Default::default() };
        for k in 0..n {
            match t.fate[k] {
                Fate::Alive => {
                    r.nodes_after += 1;
                    if t.bend[k] > 1f32.to_radians() {
                        r.bent += 1;
                    }
                }
                Fate::Light => r.pruned_light += 1,
                Fate::Collision => r.pruned_collision += 1,
            }
        }
        rep.recomputed_nodes += r.recomputed_nodes;
        t.report = r;
        rep.trees.push(r);
    }
    Ok(rep)
}

/// Eq. (3) at every point of `at` over the level's shadow volumes `vols` and those of the
/// `fixed` trees (their transmittances multiplied in), with the solids' mask at each point:
/// (i in 0–1, average light direction) per point, bit for bit what [`super::light::light_by`] gives point by
/// point (each point's sums in direction order). The points are split over the cores in chunks
/// of [`light_chunk`], each chunk taken direction by direction so a direction's grid is read
/// while in cache.
fn light_many_among(sky: &super::light::Sky, solids: &SkyMask, vols: &ShadowVolumes, fixed: Option<&ShadowVolumes>, at: &[Vec3]) -> Vec<(f32, Vec3)> {
    let mut out = vec![(0.0f32, Vec3::ZERO); at.len()];
    let masks: Vec<u32> = at.par_iter().map(|&p| solids.mask(p)).collect();
    // the grids of the directions open at some point, built over the cores first
    let open = !masks.iter().fold(u32::MAX, |a, &m| a & m);
    vols.prepare(open);
    if let Some(f) = fixed {
        f.prepare(open);
    }
    let chunk = light_chunk(at.len());
    out.par_chunks_mut(chunk).zip(at.par_chunks(chunk).zip(masks.par_chunks(chunk))).for_each(|(out, (at, masks))| {
        for k in 0..sky.dirs.len() {
            let wk = sky.weights[k];
            if wk == 0.0 {
                continue;
            }
            let d = sky.dirs[k];
            for ((o, &p), &m) in out.iter_mut().zip(at).zip(masks) {
                if m & (1 << k) != 0 {
                    continue;
                }
                let tk = through_both(vols, fixed, k, p);
                o.0 += wk * tk;
                o.1 += d * (wk * tk);
            }
        }
        for o in out.iter_mut() {
            o.1 = o.1.normalize_or(Vec3::Z);
        }
    });
    out
}

/// Representatives of `at` for light queries shared within cubes of side `cell` (m): per point,
/// the index into the returned points of the first point (in order) of its cube (world
/// coordinates, ⌊p / cell⌋) that has the same solids' mask `mask(i)`. With `cell` 0 (or not a
/// positive number) every point is its own.
fn shared_points(at: &[Vec3], cell: f32, mask: impl Fn(usize) -> u32) -> (Vec<usize>, Vec<u32>) {
    if !(cell > 0.0 && cell.is_finite()) {
        return ((0..at.len()).collect(), (0..at.len() as u32).collect());
    }
    let mut first: FxHashMap<(IVec3, u32), u32> = FxHashMap::with_capacity_and_hasher(at.len(), Default::default());
    let (mut reps, mut of) = (Vec::new(), Vec::with_capacity(at.len()));
    for (i, &p) in at.iter().enumerate() {
        let key = ((p / cell).floor().as_ivec3(), mask(i));
        let r = *first.entry(key).or_insert_with(|| {
            reps.push(i);
            (reps.len() - 1) as u32
        });
        of.push(r);
    }
    (reps, of)
}

/// The cubes whose bending light one level of one tree took ([`PlasticTree::bend_light_whole_level`]):
/// per cube and solids' mask the index of its light in `light`. A point asks the map once
/// (rustc-hash's Fx hash of the four integers): a cube met for the first time gets the next index
/// at once, and its light is filled in after the level's batch is queried (until round 42: std's
/// SipHash and three map operations per point, which cost about what the sharing saved,
/// BENCHMARKS.md round 42).
#[derive(Debug, Default)]
struct LevelLight {
    index: FxHashMap<(IVec3, u32), u32>,
    light: Vec<(f32, Vec3)>,
}

/// [`light_many_among`] with the points of each cube of side `cell` (m) that see the same
/// solids sharing the light of the first of them ([`PlasticTree::bend_light_cell_m`]); exactly
/// [`light_many_among`] with `cell` 0.
/// With `seen` (the cubes already queried at this level, [`PlasticTree::bend_light_whole_level`]),
/// a point of a cube in `seen` takes its light, and the cubes queried here are added to it.
fn light_many_shared(sky: &super::light::Sky, solids: &SkyMask, vols: &ShadowVolumes, fixed: Option<&ShadowVolumes>, at: &[Vec3], cell: f32, seen: Option<&mut LevelLight>) -> Vec<(f32, Vec3)> {
    if !(cell > 0.0 && cell.is_finite()) {
        return light_many_among(sky, solids, vols, fixed, at);
    }
    if let Some(seen) = seen {
        // each point's slot in `seen.light`: the first point of a cube not yet seen (in order)
        // reserves the next slot and is queried; the same representatives, in the same order,
        // as a lookup of the seen cubes followed by one of the cubes met in this batch
        let mut reps: Vec<usize> = Vec::new();
        let slots: Vec<u32> = at
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let next = seen.light.len() as u32;
                let slot = *seen.index.entry(((p / cell).floor().as_ivec3(), solids.mask(p))).or_insert(next);
                if slot == next {
                    reps.push(i);
                    seen.light.push((0.0, Vec3::Z));
                }
                slot
            })
            .collect();
        if !reps.is_empty() {
            let pts: Vec<Vec3> = reps.iter().map(|&i| at[i]).collect();
            let lit = light_many_among(sky, solids, vols, fixed, &pts);
            for (&i, l) in reps.iter().zip(lit) {
                seen.light[slots[i] as usize] = l;
            }
        }
        return slots.iter().map(|&s| seen.light[s as usize]).collect();
    }
    if at.len() < 2 {
        return light_many_among(sky, solids, vols, fixed, at);
    }
    let (reps, of) = shared_points(at, cell, |i| solids.mask(at[i]));
    if reps.len() == at.len() {
        return light_many_among(sky, solids, vols, fixed, at);
    }
    let pts: Vec<Vec3> = reps.iter().map(|&i| at[i]).collect();
    let lit = light_many_among(sky, solids, vols, fixed, &pts);
    of.iter().map(|&r| lit[r as usize]).collect()
}

/// Transmittance of the ray from `p` along sky direction `k` through the level's casters `vols`
/// and the `fixed` trees' (eq. 4, the two products multiplied): `vols.transmittance(k, p) *
/// fixed.transmittance(k, p)` bit for bit, but a ray that the level's casters make dark
/// (transmittance 0: the product fell below 10⁻⁴, [`ShadowVolumes::transmittance`]) does not
/// query the fixed trees' grid, as 0 · t is +0 for every t in 0–1. The level's casters go first:
/// they darken a ray about five times as often as the fixed trees (stand bench, 100 targets:
/// 2.1 % against 0.4 % of the bending rays; BENCHMARKS.md, round 37).
fn through_both(vols: &ShadowVolumes, fixed: Option<&ShadowVolumes>, k: usize, p: Vec3) -> f32 {
    let a = vols.transmittance(k, p);
    match fixed {
        Some(f) if a != 0.0 => a * f.transmittance(k, p),
        _ => a,
    }
}

/// Per-direction transmittances (eq. 4 products) of the clusters of one stage as evaluated at
/// its level: `start[ci]` indexes `t` (one value per sky direction, NaN where not evaluated),
/// `u32::MAX` for a cluster not evaluated.
#[derive(Debug, Clone, Default)]
struct Rows {
    start: Vec<u32>,
    t: Vec<f32>,
}

/// One tree's state of the previous level: its stage occluders (the receivers), its shade
/// casters (by key), the receivers' per-direction transmittances and its stage clusters.
#[derive(Debug, Clone)]
struct Prev {
    occ: Vec<Option<Occluder>>,
    shade: Vec<(u64, Occluder)>,
    rows: Rows,
    /// The stage's clusters as [`stage_occluders_with`] made them (their γ_c0^r reused).
    stage: Vec<StageOcc>,
}

/// What a level may reuse from the level before: the casters that changed since (`delta`),
/// the previous stage's occluders and transmittances, and the previous index of every cluster.
struct Reuse<'a> {
    delta: &'a ShadowVolumes,
    occ: &'a [Option<Occluder>],
    rows: &'a Rows,
    map: &'a [Option<u32>],
}

/// Index in stage `prev` of every cluster of stage `cur` that is the same stage cluster
/// (anchor, radius, lobe); both lists are sorted by (anchor, lobe).
fn match_stage(prev: &[super::analysis::StageCluster], cur: &[super::analysis::StageCluster]) -> Vec<Option<u32>> {
    let key = |c: &super::analysis::StageCluster| (c.anchor, c.lobe.unwrap_or(u32::MAX));
    let mut j = 0;
    cur.iter()
        .map(|c| {
            while j < prev.len() && key(&prev[j]) < key(c) {
                j += 1;
            }
            (j < prev.len() && prev[j] == *c).then_some(j as u32)
        })
        .collect()
}

/// Walks two caster lists sorted by key side by side, calling `f` with (the old caster, the
/// caster now) per key: both when the key is in both lists, one `None` when it is in one only;
/// stops when `f` returns false.
fn by_key(old: &[(u64, Occluder)], cur: &[(u64, Occluder)], mut f: impl FnMut(Option<Occluder>, Option<Occluder>) -> bool) {
    let (mut i, mut j) = (0, 0);
    while i < old.len() || j < cur.len() {
        use std::cmp::Ordering;
        let ord = match (old.get(i), cur.get(j)) {
            (Some(a), Some(b)) => a.0.cmp(&b.0),
            (Some(_), None) => Ordering::Less,
            _ => Ordering::Greater,
        };
        let go = match ord {
            Ordering::Equal => {
                i += 1;
                j += 1;
                f(Some(old[i - 1].1), Some(cur[j - 1].1))
            }
            Ordering::Less => {
                i += 1;
                f(Some(old[i - 1].1), None)
            }
            Ordering::Greater => {
                j += 1;
                f(None, Some(cur[j - 1].1))
            }
        };
        if !go {
            return;
        }
    }
}

/// Bitwise equality of two optional occluders.
fn same_occluder(a: &Option<Occluder>, b: &Option<Occluder>) -> bool {
    let bits = |o: &Occluder| [o.center.x.to_bits(), o.center.y.to_bits(), o.center.z.to_bits(), o.radius.to_bits(), o.gamma.to_bits()];
    match (a, b) {
        (Some(a), Some(b)) => bits(a) == bits(b),
        (None, None) => true,
        _ => false,
    }
}

/// The levels of a call in which a tree had nothing to recompute (no signature changed, no
/// recomputation forced): at each level, which of its stage clusters were alive (had an
/// occluder: not shed, not inside an obstacle) and the fates the level set. In such a call a
/// level moves no node and lights no cluster of the tree; it only re-evaluates the pruning of
/// eqs. (10)–(11) (Pirk et al. 2012) from the tree's unchanged stage light, so the fates it sets
/// follow from the tree's state and from which stage clusters are alive. The next call that
/// again recomputes nothing of the tree replays them level by level while the live clusters are
/// the same (the same fates, bit for bit, without a pass over every node at every level), and
/// evaluates the levels as usual from the first where they differ. A call with work, and
/// every change of the tree outside a call (translation, scaling, invalidation), forgets them.
#[derive(Debug, Clone, Default)]
pub(crate) struct QuietLevels {
    /// Per stage: whether each stage cluster had an occluder.
    live: Vec<Vec<bool>>,
    /// (stage, node, fate) of every fate set by the levels, in stage order.
    set: Vec<(u32, u32, Fate)>,
    /// While recording: every node's fate after the last level recorded.
    last: Vec<Fate>,
}

/// Per-tree flags of one [`adapt_group`] call: `own` (signature changed), `moved` (position or
/// rotation changed by this call), `done` (recomputed).
struct Work {
    /// Levels of the tree's last quiet call, replayed in this quiet call ([`QuietLevels`]).
    replay: Option<Box<QuietLevels>>,
    /// Entries of `replay.set` applied so far.
    replayed: usize,
    /// Levels of this quiet call, recorded for the next.
    record: Option<QuietLevels>,
    /// Whether eq. (11) can shed a node of the tree (some ψ_min > 0): else the light of its
    /// stage clusters is evaluated at the last level only, and no ψ at all.
    prunes: bool,
    /// Positions at the start of the call.
    before: Vec<Vec3>,
    own: Vec<bool>,
    moved: Vec<bool>,
    shifted: Vec<bool>,
    done: Vec<bool>,
    /// Every node but the root, by season (season s: `by_season[season_start[s]..season_start[s
    /// + 1]]`), each season's nodes in index order: the per-level passes visit the nodes of
    /// their season or stage only, not every node at every level.
    by_season: Vec<u32>,
    season_start: Vec<u32>,
    /// The nodes of season ≤ `stage_upto` (root left out), in index order.
    stage: Vec<u32>,
    stage_upto: Option<usize>,
    /// Scratch of [`preposition`] (per node; written for a season's node before it is read).
    carry: Vec<(bool, Quat)>,
    /// Scratch of [`level`] (per season node: its depth below the older wood, or its place in
    /// the level's chains ([`bend_by_chains`]); likewise).
    depth: Vec<u32>,
    /// The tree's parents, segment lengths and ψ sums for [`prune`] (made at its first level
    /// that evaluates eq. 10).
    pruning: Option<Pruning>,
    /// The tree's move light model while the call runs ([`MoveCache`]; `None`: exact), and of
    /// the current level its epoch and changed casters ([`MoveCache::level`]).
    mc: Option<Box<MoveCache>>,
    mc_epoch: u32,
    mc_delta: CasterSet,
    /// Whether the current level took a new snapshot in this call (its queries all exact).
    mc_new: bool,
    /// Light queries of the call under the move light model: all, reused whole, reused in
    /// part, directions computed; and levels with a new snapshot (printed with
    /// `SYLVA_PLASTIC_MOVE_STATS` set, for the measurements of BENCHMARKS.md).
    mc_stats: [usize; 4],
    mc_snapshots: usize,
}

/// What [`prune`] reads per node, as arrays (parent index, segment length l of eq. 10 as
/// `Skeleton::segment_length` gives it: the input's, which bending does not change), and its
/// sums ζ, l and ψ of eq. (10) (scratch, every entry of a stage's node written before read),
/// and the tree split for pruning over the cores ([`PrunePart`]).
#[derive(Default)]
struct Pruning {
    parent: Vec<u32>,
    seg: Vec<f32>,
    zeta: Vec<f32>,
    len: Vec<f32>,
    psi: Vec<f32>,
    /// The subtrees, in parts of about max(n / [`PRUNE_TASKS`], [`PRUNE_PART`]) nodes ([`PrunePart`]).
    parts: Vec<PrunePart>,
    /// The nodes outside every subtree (the root, the stem and the big branches near it) and
    /// the subtrees' roots, in index order: (node, its part and place in the part's list for a
    /// subtree's root, `u32::MAX` twice for a node outside).
    top: Vec<(u32, u32, u32)>,
}

/// Subtrees of at most half a part's nodes whose parent is in no such subtree ([`Pruning::of`]),
/// taken together as one task of [`prune`]: their nodes in index order, each one's parent's place in
/// the list (`u32::MAX` for a subtree's root), and per node the ζ, l, ψ sums of eq. (10) and the
/// fate (scratch, written before read at every level).
#[derive(Default)]
struct PrunePart {
    nodes: Vec<u32>,
    par: Vec<u32>,
    /// Per node: its season (eq. 2), segment length l (m) and ψ_s,min (eq. 11), copied from the
    /// analysis so that a level reads them in list order.
    season: Vec<u16>,
    seg: Vec<f32>,
    psi_min: Vec<f32>,
    zeta: Vec<f32>,
    len: Vec<f32>,
    psi: Vec<f32>,
    fate: Vec<Fate>,
    /// Fates the part's pass changed at the level: (node, fate).
    changed: Vec<(u32, Fate)>,
}

/// Fewest nodes per task of [`prune`] ([`Pruning::of`]: a tree of n nodes is split into parts of
/// about max(n / [`PRUNE_TASKS`], this) nodes, each of subtrees of at most half as many).
const PRUNE_PART: usize = 256;

/// Tasks [`prune`] splits a large tree into: our choice, a few per core of a two-core machine
/// (the 9,133-node bench tree: parts of about 1,140 nodes).
const PRUNE_TASKS: usize = 8;

impl Pruning {
    fn of(sk: &crate::structure::skeleton::Skeleton, a: &super::analysis::Analysis) -> Pruning {
        let n = sk.nodes.len();
        let seg: Vec<f32> = (0..n).map(|k| sk.segment_length(k)).collect();
        let parent: Vec<u32> = sk.nodes.iter().map(|nd| nd.parent.unwrap_or(0)).collect();
        // subtree sizes (parents precede their children), then the subtrees of at most half a
        // part's nodes whose parent's subtree is larger; the root stays outside
        let mut size = vec![1u32; n];
        for k in (1..n).rev() {
            size[parent[k] as usize] += size[k];
        }
        let part_nodes = (n / PRUNE_TASKS).max(PRUNE_PART);
        let cap = if forced(Forced::SerialPrune) { 0 } else { (part_nodes / 2) as u32 };
        let (mut sub_of, mut roots) = (vec![u32::MAX; n], Vec::new());
        for k in 1..n {
            let p = parent[k] as usize;
            if sub_of[p] != u32::MAX {
                sub_of[k] = sub_of[p];
            } else if size[k] <= cap {
                sub_of[k] = roots.len() as u32;
                roots.push(k as u32);
            }
        }
        // the subtrees, in their roots' order, gathered into parts of about `part_nodes` nodes
        let mut part_of_sub = Vec::with_capacity(roots.len());
        let (mut parts, mut fill) = (0u32, 0usize);
        for &r in &roots {
            if fill >= part_nodes {
                (parts, fill) = (parts + 1, 0);
            }
            part_of_sub.push(parts);
            fill += size[r as usize] as usize;
        }
        let mut parts: Vec<PrunePart> = (0..parts as usize + (!roots.is_empty()) as usize).map(|_| PrunePart::default()).collect();
        let mut place = vec![u32::MAX; n];
        let mut top = Vec::new();
        for k in 0..n {
            let Some(&pi) = sub_of.get(k).filter(|&&x| x != u32::MAX).map(|&x| &part_of_sub[x as usize]) else {
                top.push((k as u32, u32::MAX, u32::MAX));
                continue;
            };
            let part = &mut parts[pi as usize];
            let p = parent[k] as usize;
            place[k] = part.nodes.len() as u32;
            let root = sub_of[p] != sub_of[k];
            if root {
                top.push((k as u32, pi, place[k]));
            }
            part.par.push(if root { u32::MAX } else { place[p] });
            part.nodes.push(k as u32);
            part.season.push(a.season[k]);
            part.seg.push(seg[k]);
            part.psi_min.push(a.psi_min[k]);
        }
        for part in &mut parts {
            let m = part.nodes.len();
            (part.zeta, part.len, part.psi, part.fate) = (vec![0.0; m], vec![0.0; m], vec![f32::NAN; m], vec![Fate::Alive; m]);
        }
        Pruning { seg, parent, zeta: vec![0.0; n], len: vec![0.0; n], psi: vec![f32::NAN; n], parts, top }
    }
}

impl Work {
    /// The nodes created in season `s`, in index order.
    fn season(&self, s: usize) -> &[u32] {
        match (self.season_start.get(s), self.season_start.get(s + 1)) {
            (Some(&a), Some(&b)) => &self.by_season[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Brings [`Work::stage`] up to season `s` (the nodes of season ≤ `s`, in index order),
    /// merging in the seasons not yet in it.
    fn stage_to(&mut self, s: usize) {
        let from = self.stage_upto.map_or(0, |u| u + 1);
        if from > s {
            return;
        }
        let (a, b) = (self.season_start[from.min(self.season_start.len() - 1)] as usize, self.season_start[(s + 1).min(self.season_start.len() - 1)] as usize);
        let mut add = self.by_season[a..b].to_vec();
        add.sort_unstable();
        let old = std::mem::take(&mut self.stage);
        let mut merged = Vec::with_capacity(old.len() + add.len());
        let (mut i, mut j) = (0, 0);
        while i < old.len() || j < add.len() {
            if j >= add.len() || (i < old.len() && old[i] < add[j]) {
                merged.push(old[i]);
                i += 1;
            } else {
                merged.push(add[j]);
                j += 1;
            }
        }
        self.stage = merged;
        self.stage_upto = Some(s);
    }
}

/// Places the nodes created in season `s` where they stand before the level bends them: a node
/// that may be recomputed (its own signature changed, or its chain down from the older wood
/// holds such a node or starts at an older node that moved) continues the older wood rigidly:
/// it takes the rotation of its nearest ancestor of an earlier season (its own turn is what the
/// level computes); a node kept follows its parent with its own rotation. So the stage's
/// clusters cast their shadows from the stage tree as adapted so far, not from where the
/// previous call left the young nodes (with that, an adaptation back to the environment of the
/// analysis restores the input: a season holds several internodes along a shoot, and their
/// same-season parents are not bent yet when the level's shadows are built).
fn preposition(t: &mut PlasticTree, s: usize, w: &mut Work) {
    // per node of the season: (may be recomputed, rotation carried down the season's chain)
    let mut carry = std::mem::take(&mut w.carry);
    for &k in w.season(s) {
        let k = k as usize;
        let par = t.input.nodes[k].parent.unwrap_or(0) as usize;
        let same = par != 0 && t.analysis.season[par] as usize == s;
        let (rec_par, q_par) = if same { carry[par] } else { (w.moved[par], t.rot[par]) };
        let seg = t.input.nodes[k].pos - t.input.nodes[par].pos;
        if w.own[k] || rec_par {
            t.pos[k] = t.pos[par] + q_par * seg;
            carry[k] = (true, q_par);
        } else {
            if same || w.shifted[par] {
                t.pos[k] = t.pos[par] + t.rot[k] * seg;
            }
            carry[k] = (false, t.rot[k]);
        }
    }
    w.carry = carry;
}

/// The move light model of one tree ([`PlasticTree::set_move_light`]): per-direction foliage
/// transmittances (the products of eq. 4 along each sky direction, the transmittance factors of
/// eq. 3) of every light query of the tree's last exact evaluations, kept between calls, so that
/// a call after a small change of the environment (a wall moved) builds no shadow grid where
/// nothing forces it: an acceleration structure of the casters updated, not rebuilt. Per level
/// (stage) the model keeps a snapshot of the level's casters; a row holds the transmittances
/// from its point through the snapshot's casters. A query (a node's bending light at its
/// season's level, a stage cluster's light at its stage's level) reuses its row when
/// - the row is of the level's current snapshot (its epoch), and
/// - the query point lies within `tol_m` of the point the row was taken at;
///
/// the casters that changed since the snapshot (added, removed, or moved, grown or cut by more
/// than `tol_m` in centre plus radius, or whose transmittance changed by more than
/// [`MOVE_GAMMA_TOL`]) are then applied to the row ray by ray (their new γ multiplied in, the
/// snapshot's divided out, where the ray from the point meets them; [`CasterSet::factors`],
/// which first drops the casters outside the cone of the sky's directions, and for a reused row
/// tests only the directions the solids leave open), so the products are those of the casters
/// now but for the smaller changes. The solids' mask (the obstacles, the terrain:
/// what a wall move changes) is taken anew at every query, and eq. (3) sums over the directions
/// open now. Any other query is evaluated exactly from the level's grids and stored. A level
/// whose changed casters exceed [`MOVE_DELTA_MAX`] (or half its casters), or would bring the
/// changed casters applied since its snapshot past [`MOVE_PATCH_BUDGET`], takes a new snapshot
/// and evaluates all its queries exactly. Errors so bounded: a receiver within `tol_m` of where
/// its row was taken, casters within `tol_m` (and [`MOVE_GAMMA_TOL`]) of the snapshot; no drift,
/// since rows and snapshots are compared with the values at the last exact evaluation, not at
/// the last call. Our model (not in Pirk et al. 2012, whose section 5 recomputes "only when
/// required" without saying how); measured against the exact recomputation in BENCHMARKS.md,
/// round 37.
#[derive(Debug, Clone)]
pub(crate) struct MoveCache {
    /// Receiver and caster tolerance (m).
    pub(crate) tol_m: f32,
    /// Rows of every node's bending light (slot: node index).
    nodes: RowCache,
    /// Per stage: rows of the stage clusters' light (slot: cluster index) and the level's
    /// caster snapshot.
    stages: Vec<StageCache>,
}

/// Slots per block of a [`RowCache`]: a block is shared between clones of a tree and copied
/// whole when a call first writes a row of it (32 slots of 32 directions: 4 KiB of rows). Our
/// choice: small enough that a wall move, which writes the fresh rows of the nodes and clusters
/// near the wall (a season's nodes lie together in index order), copies a small part of the
/// rows, large enough that a clone copies few block pointers (286 for the 9,133-node bench tree).
const ROW_BLOCK: usize = 32;

/// One block of a [`RowCache`]: [`ROW_BLOCK`] slots' query points, epochs and rows.
#[derive(Debug, Clone)]
struct RowBlock {
    at: [Vec3; ROW_BLOCK],
    epoch: [u32; ROW_BLOCK],
    row: Vec<f32>,
}

/// Stored per-direction transmittances of light queries, `nd` per slot ([`MoveCache`]), in
/// blocks of [`ROW_BLOCK`] slots behind [`Arc`], copied on write: cloning a tree (and its move
/// light model) shares every block, and a call copies only the blocks whose rows it writes.
#[derive(Debug, Clone, Default)]
struct RowCache {
    /// Slots (the last block may hold more, never used).
    slots: usize,
    /// Transmittances per slot.
    nd: usize,
    /// Per block: query point of each slot's row (m; NaN: no row), the level epoch each row
    /// was filled in (0: none), `nd` transmittances per slot (NaN where never computed).
    blocks: Vec<std::sync::Arc<RowBlock>>,
}

impl RowCache {
    /// Makes the cache hold `slots` empty rows of `nd` values unless it holds `slots` already
    /// (every block the same empty one until written).
    fn ensure(&mut self, slots: usize, nd: usize) {
        if self.slots != slots || self.nd != nd {
            let empty = std::sync::Arc::new(RowBlock { at: [Vec3::NAN; ROW_BLOCK], epoch: [0; ROW_BLOCK], row: vec![f32::NAN; ROW_BLOCK * nd] });
            self.blocks = vec![empty; slots.div_ceil(ROW_BLOCK)];
            (self.slots, self.nd) = (slots, nd);
        }
    }

    /// Whether slot `i` holds a row of `epoch` taken within `tol` (m) of `p`.
    fn valid(&self, i: usize, epoch: u32, p: Vec3, tol: f32) -> bool {
        let b = &self.blocks[i / ROW_BLOCK];
        b.epoch[i % ROW_BLOCK] == epoch && b.at[i % ROW_BLOCK].distance(p) <= tol
    }

    /// The row of slot `i`.
    fn row(&self, i: usize) -> &[f32] {
        let j = i % ROW_BLOCK;
        &self.blocks[i / ROW_BLOCK].row[j * self.nd..(j + 1) * self.nd]
    }

    /// The row of slot `i`, to be filled anew at point `p` in `epoch` (its block copied first
    /// when shared).
    fn fill(&mut self, i: usize, p: Vec3, epoch: u32) -> &mut [f32] {
        let (j, nd) = (i % ROW_BLOCK, self.nd);
        let b = std::sync::Arc::make_mut(&mut self.blocks[i / ROW_BLOCK]);
        b.at[j] = p;
        b.epoch[j] = epoch;
        &mut b.row[j * nd..(j + 1) * nd]
    }
}

/// One level's part of a [`MoveCache`]: its rows, the casters at its last snapshot (sorted by
/// key, as [`stage_casters`] gives them) and the snapshot's epoch (0: none yet).
#[derive(Debug, Clone, Default)]
struct StageCache {
    rows: RowCache,
    /// Shared between clones of the tree (a new snapshot replaces it whole).
    snapshot: std::sync::Arc<Vec<(u64, Occluder)>>,
    epoch: u32,
    /// Changed casters applied to the level's rows, summed over the calls since its snapshot.
    patched: usize,
}

/// Largest change of a caster's transmittance γ (eq. 4, eq. 13) that the move light model
/// ([`MoveCache`]) ignores: a ray through it changes by at most this factor's difference. An
/// ESTIMATE (a few per cent of a ray's light), not tuned.
pub const MOVE_GAMMA_TOL: f32 = 0.02;

/// Most points a level of the move light model evaluates afresh by testing every caster of the
/// level from each (all directions at once, no grid) in a call that reuses stored rows; more
/// points build the level's grids. An ESTIMATE: a grid of a few hundred casters for one
/// direction costs about as many instructions as testing them from a few dozen points in all
/// directions (round 36's phase table: 3.8 ms of grid builds in about 60 builds a move).
pub const MOVE_SCAN_MAX_POINTS: usize = 64;

/// Most changed casters a level of the move light model applies to its stored rows in one call
/// ([`MoveCache`]); beyond it (or beyond half the level's casters, or past
/// [`MOVE_PATCH_BUDGET`]) the level takes a new snapshot and evaluates every query exactly. The
/// changed casters are tested per query after the sky-cone test of [`CasterSet::factors`].
/// Issue 31's 10 cm wall move of the 9,133-node bench tree changes up to about 190 casters at
/// its late levels (every caster the wall cuts grows by the step): with 256 it patches every
/// level (round 38: 75.6 M instructions against 91.1 M with 64, which took four new snapshots;
/// round 40: 74.6 M against 90.0 M), and the drift that 256 alone showed (round 38: after 50
/// moves 0.0192 from the tree adapted from scratch against the bound 0.0183) is bounded by
/// [`MOVE_PATCH_BUDGET`]. An ESTIMATE (BENCHMARKS.md, rounds 38 and 40), not tuned.
pub const MOVE_DELTA_MAX: usize = 256;

/// Most changed casters a level of the move light model applies to its stored rows summed over
/// the calls since its snapshot ([`MoveCache`]); a call that would pass it takes a new snapshot
/// instead. It bounds how long the errors the model accepts (receivers and casters within the
/// tolerance of the snapshot) stay in a level's rows: twice [`MOVE_DELTA_MAX`], so a level is
/// patched by at least two calls, the bench's first move (up to about 190 changed casters) by
/// one. Round 40 (BENCHMARKS.md): in `structure_plastic::the_move_light_model_stays_near_the_exact_moves`
/// the mean leaf-cluster light after 50 moves is 0.0173 from the tree adapted from scratch
/// (bound 0.0183; without a budget 0.0192); budgets of 128 to 1,024 gave 0.0163–0.0195, not
/// monotone in the budget (the fates of a few branches decide it), so the value is not tuned on
/// the test but set from [`MOVE_DELTA_MAX`]. An ESTIMATE.
pub const MOVE_PATCH_BUDGET: usize = 2 * MOVE_DELTA_MAX;

/// Measurement hooks of the move light model (round 40, BENCHMARKS.md), read once from the
/// environment: `SYLVA_PLASTIC_MOVE_DELTA_MAX` and `SYLVA_PLASTIC_MOVE_BUDGET` override
/// [`MOVE_DELTA_MAX`] and [`MOVE_PATCH_BUDGET`] (64 and a budget larger than any sum give
/// round 39's model, so one binary measures both); `SYLVA_PLASTIC_MOVE_CHECK` prints per call
/// and level the error |Δ i| (eq. 3) of the reused and the fresh rows against the exact
/// products of the level's casters (it evaluates them all, so it is slow).
struct Knobs {
    delta_max: usize,
    budget: usize,
    check: bool,
}

fn knobs() -> &'static Knobs {
    static K: std::sync::OnceLock<Knobs> = std::sync::OnceLock::new();
    K.get_or_init(|| {
        let v = |n: &str| std::env::var(n).ok();
        Knobs {
            delta_max: v("SYLVA_PLASTIC_MOVE_DELTA_MAX").and_then(|x| x.parse().ok()).unwrap_or(MOVE_DELTA_MAX),
            budget: v("SYLVA_PLASTIC_MOVE_BUDGET").and_then(|x| x.parse().ok()).unwrap_or(MOVE_PATCH_BUDGET),
            check: v("SYLVA_PLASTIC_MOVE_CHECK").is_some(),
        }
    })
}

/// Per level: reused rows, sum and max of |Δ i| against the exact products; the same of the
/// fresh rows; reused rows holding a dark ray and their sum (`SYLVA_PLASTIC_MOVE_CHECK`).
static CHECK_ERR: std::sync::Mutex<Vec<[f64; 8]>> = std::sync::Mutex::new(Vec::new());

impl MoveCache {
    pub(crate) fn new(tol_m: f32) -> MoveCache {
        MoveCache { tol_m, nodes: RowCache::default(), stages: Vec::new() }
    }

    /// Forgets every row and snapshot (the next call evaluates every query exactly).
    pub(crate) fn clear(&mut self) {
        self.nodes = RowCache::default();
        self.stages.clear();
    }

    /// The level of stage `s` with casters `shade` (sorted by key): its epoch and the changed
    /// casters (snapshot version, version now) against its snapshot, taking a new
    /// snapshot (a new epoch, no changed casters) when there is none or the changes are many.
    fn level(&mut self, s: usize, shade: &[(u64, Occluder)]) -> (u32, Vec<(Option<Occluder>, Option<Occluder>)>) {
        if self.stages.len() <= s {
            self.stages.resize_with(s + 1, StageCache::default);
        }
        let kn = knobs();
        let (tol, dmax) = (self.tol_m, kn.delta_max);
        let st = &mut self.stages[s];
        let mut delta = Vec::new();
        if st.epoch > 0 {
            by_key(&st.snapshot, shade, |a, b| {
                match (a, b) {
                    (Some(a), Some(b)) if a.center.distance(b.center) + (a.radius - b.radius).abs() <= tol && (a.gamma - b.gamma).abs() <= MOVE_GAMMA_TOL => {}
                    pair => delta.push(pair),
                }
                delta.len() <= dmax
            });
        }
        if st.epoch == 0 || delta.len() > dmax || 2 * delta.len() > shade.len() || st.patched + delta.len() > kn.budget {
            st.patched = 0;
            st.snapshot = std::sync::Arc::new(shade.to_vec());
            st.epoch += 1;
            delta.clear();
        } else {
            st.patched += delta.len();
        }
        (st.epoch, delta)
    }
}

/// Sky directions as lanes ([`hit_dirs`]): x, y, z of up to 32 unit directions (0 in unused
/// lanes), and the cone that holds them ([`DirLanes::cone`]).
struct DirLanes {
    x: [f32; 32],
    y: [f32; 32],
    z: [f32; 32],
    /// Axis of the cone (unit): the brightest sky point.
    axis: Vec3,
    /// (cos α, sin α) of the cone's half-angle α: every direction of the mask given to
    /// [`DirLanes::new`] lies within α of `axis`; cos α = −2 (no cone) when α ≥ 90°.
    cone: (f32, f32),
}

impl DirLanes {
    /// The directions `dirs` as lanes, and the cone about `axis` that holds those of `used`
    /// (bit k: direction k).
    fn new(dirs: &[Vec3], axis: Vec3, used: u32) -> DirLanes {
        let mut l = DirLanes { x: [0.0; 32], y: [0.0; 32], z: [0.0; 32], axis, cone: (-2.0, 1.0) };
        for (k, d) in dirs.iter().take(32).enumerate() {
            (l.x[k], l.y[k], l.z[k]) = (d.x, d.y, d.z);
        }
        let cos_a = dirs.iter().take(32).enumerate().filter(|(k, _)| used & (1 << k) != 0).map(|(_, d)| d.dot(axis)).fold(1.0f32, f32::min);
        if cos_a > 1e-3 && axis.is_finite() {
            l.cone = (cos_a, (1.0 - cos_a * cos_a).max(0.0).sqrt());
        }
        l
    }
}

/// Bits of the directions of `want` whose ray from `p` passes the sphere `o` ahead of `p`, as
/// the shadow volumes test a caster (the sphere ahead along the ray, the ray within its
/// radius, `p` outside it: no direction when `p` is inside); every lane at once.
#[inline]
fn hit_dirs(l: &DirLanes, o: &Occluder, p: Vec3, want: u32) -> u32 {
    let v = o.center - p;
    let (l2, r2) = (v.length_squared(), o.radius * o.radius);
    if !(l2 > r2) {
        return 0;
    }
    // per lane an all-ones mask where the ray meets the sphere, kept on the lane's bit and
    // OR-reduced (the lanes' bits by a table, so the loop vectorises)
    let mut m = 0u32;
    for k in 0..32 {
        let along = v.x * l.x[k] + v.y * l.y[k] + v.z * l.z[k];
        let hit = 0u32.wrapping_sub(((along > 0.0) & (l2 - along * along <= r2)) as u32);
        m |= hit & LANE_BIT[k];
    }
    m & want
}

/// Bit k of lane k ([`hit_dirs`]).
const LANE_BIT: [u32; 32] = {
    let mut b = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        b[k] = 1 << k;
        k += 1;
    }
    b
};

/// Casters of the move light model laid out for many queries ([`CasterSet::factors`]): centre,
/// radius and the factor each multiplies a ray's transmittance by where the ray meets it.
#[derive(Default)]
struct CasterSet {
    /// Casters (the arrays hold whole blocks of 8, the slots after `len` never pass).
    len: usize,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    r: Vec<f32>,
    f: Vec<f32>,
}

impl CasterSet {
    /// The changed casters of a level (`delta`: (its snapshot version, its version now) per
    /// caster, either `None` when added or removed): the versions now with factor γ, the
    /// snapshot versions with 1/γ (γ at least 10⁻⁶).
    fn of_delta(delta: &[(Option<Occluder>, Option<Occluder>)]) -> CasterSet {
        let mut c = CasterSet::default();
        for (old, new) in delta {
            if let Some(o) = old {
                c.push(o, 1.0 / o.gamma.max(1e-6));
            }
            if let Some(o) = new {
                c.push(o, o.gamma);
            }
        }
        c
    }

    /// Every caster of `occ` with factor γ.
    fn of(occ: &[Occluder]) -> CasterSet {
        let mut c = CasterSet::default();
        occ.iter().for_each(|o| c.push(o, o.gamma));
        c
    }

    fn push(&mut self, o: &Occluder, f: f32) {
        // runs padded to whole blocks of 8 with casters that never pass (centre NaN)
        if self.len % 8 == 0 {
            for v in [&mut self.x, &mut self.y, &mut self.z] {
                v.extend([f32::NAN; 8]);
            }
            self.r.extend([0.0; 8]);
            self.f.extend([1.0; 8]);
        }
        let i = self.len;
        (self.x[i], self.y[i], self.z[i], self.r[i], self.f[i]) = (o.center.x, o.center.y, o.center.z, o.radius, f);
        self.len += 1;
    }

    fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The factor per direction of `want` (1 where no caster is hit; every caster's factor
    /// multiplied in, in caster order, where its sphere is hit as [`hit_dirs`] tests it) of the
    /// rays from `p`; `None` when no caster is hit. A caster is first tested against the cone
    /// of the sky directions ([`DirLanes`]: axis a, half-angle α): a ray within α of a meets a
    /// sphere of radius r at distance |v| only if the angle θ between v and a is at most α + β,
    /// sin β = r/|v|, so cos θ ≥ cos(α + β) = cos α cos β − sin α sin β (with a slack of 10⁻³
    /// for rounding); the casters outside (beside or below the point, for a sky about the
    /// zenith most of a crown) take no direction test.
    fn factors(&self, l: &DirLanes, p: Vec3, want: u32) -> Option<[f32; 32]> {
        let mut out: Option<[f32; 32]> = None;
        if want == 0 {
            return out;
        }
        let (cos_a, sin_a) = l.cone;
        let (a, c2) = (l.axis, cos_a * cos_a);
        let no_cone = cos_a < -1.0;
        for ((((xs, ys), zs), rs), fs) in self.x.chunks_exact(8).zip(self.y.chunks_exact(8)).zip(self.z.chunks_exact(8)).zip(self.r.chunks_exact(8)).zip(self.f.chunks_exact(8)) {
            // the cone test of a block of 8 casters, without a root: with D = v·a and |v|² = l2,
            // cos θ ≥ cos(α + β) ⇔ D + r sin α ≥ cos α √(l2 − r²) ⇔ D + r sin α ≥ 0 and
            // (D + r sin α)² ≥ cos²α (l2 − r²) (slack 10⁻³ (1 + l2) for rounding)
            let (Ok(xs), Ok(ys), Ok(zs), Ok(rs)) = (<&[f32; 8]>::try_from(xs), <&[f32; 8]>::try_from(ys), <&[f32; 8]>::try_from(zs), <&[f32; 8]>::try_from(rs)) else {
                continue; // unreachable: whole blocks
            };
            let mut pass = 0u32;
            for j in 0..8 {
                let (vx, vy, vz, r) = (xs[j] - p.x, ys[j] - p.y, zs[j] - p.z, rs[j]);
                let l2 = vx * vx + vy * vy + vz * vz;
                let r2 = r * r;
                let lhs = vx * a.x + vy * a.y + vz * a.z + r * sin_a;
                let slack = 1e-3 * (1.0 + l2);
                let cone = no_cone | ((lhs >= -slack) & (lhs * lhs >= c2 * (l2 - r2) - slack));
                pass |= 0u32.wrapping_sub(((l2 > r2) & cone) as u32) & LANE_BIT[j];
            }
            while pass != 0 {
                let j = pass.trailing_zeros() as usize;
                pass &= pass - 1;
                let mut h = hit_dirs(l, &Occluder { center: Vec3::new(xs[j], ys[j], zs[j]), radius: rs[j], gamma: 1.0 }, p, want);
                if h == 0 {
                    continue;
                }
                let f = out.get_or_insert([1.0; 32]);
                let g = fs[j];
                while h != 0 {
                    let k = h.trailing_zeros() as usize;
                    h &= h - 1;
                    f[k] *= g;
                }
            }
        }
        out
    }
}

/// Eq. (3) at the points `pts` (slot in `rc`, point) under the move light model
/// ([`MoveCache`]). The rows hold, per direction, the transmittance from the row's point through
/// the level's casters as they were at its snapshot (epoch `epoch`). A slot whose row is of
/// `epoch` and was taken within `tol` of its point reuses it: its transmittance now is the row's
/// times the factors of the casters changed since the snapshot (`delta`, [`CasterSet::factors`]:
/// the changed casters' new γ multiplied in, their snapshot γ divided out, where their rays meet
/// them from the point now), with no grid built. Any other slot gets a fresh row of every direction above
/// the terrain (also those the solids block now, so a later call with the wall elsewhere finds
/// them) from the level's grids, stored back in the snapshot's terms (the same factors
/// inverted). Returns (i in 0–1, average light direction) per point, summed in direction order
/// over the directions the solids leave open now: with no changed caster (the first call, or a
/// level just given a new snapshot) the values of [`light_many_among`] bit for bit (the same
/// products, summed in the same order). A transmittance below 10⁻⁴ is 0, as
/// [`ShadowVolumes::transmittance`] gives it; a ray stored dark stays dark.
#[allow(clippy::too_many_arguments)]
fn light_cached(sky: &super::light::Sky, solids: &SkyMask, vols: &ShadowVolumes, rc: &mut RowCache, epoch: u32, delta: &CasterSet, patched: bool, tol: f32, pts: &[(usize, Vec3)], stats: &mut [usize; 4], lvl: usize) -> Vec<(f32, Vec3)> {
    let nd = sky.dirs.len();
    let weighted = (0..nd).filter(|&k| sky.weights[k] != 0.0).fold(0u32, |m, k| m | 1 << k);
    let fill = sky_bits(sky) & !solids.below_ground() & weighted;
    let lanes = DirLanes::new(&sky.dirs, sky.brightest, fill);
    // whether each point's row is reused (a cheap serial pass: it decides how the fresh rows
    // are computed, before the one parallel pass below)
    let valid: Vec<bool> = pts.iter().map(|&(i, p)| rc.valid(i, epoch, p, tol)).collect();
    let fresh_pts = valid.iter().filter(|&&v| !v).count();
    let reusing = fresh_pts < pts.len();
    // a few points to evaluate in a call that reuses rows (or at a level patched since its
    // snapshot, `patched`: a batch of a few fresh points alone): every caster of the level
    // tested from each point (the sky-cone test first), all directions at once, instead of
    // building the level's grids; more fresh points: the level's grids, built over the cores
    // before the pass
    let scan = (fresh_pts > 0 && (reusing || patched) && fresh_pts <= MOVE_SCAN_MAX_POINTS).then(|| CasterSet::of(vols.occluders()));
    if scan.is_none() && fresh_pts > 0 {
        vols.prepare(fill);
    }
    // one pass over the cores, in chunks of `light_chunk` points (a depth batch of a few dozen
    // nodes is one task with chunks of LIGHT_CHUNK; rounds 36–41 took two passes and summed the
    // points serially): per point the solids' mask, the changed casters' factors (for a reused
    // row only in the directions the solids leave open now: the row keeps the snapshot's terms,
    // and the blocked directions add nothing to eq. 3), a fresh row where the row is not
    // reused (stored back below, in the snapshot's terms), and the sums of eq. (3). Every
    // point's values are its own, taken in direction order as before, so they are the same bit
    // for bit whatever the chunks
    let ndc = nd.max(1);
    let chunk = light_chunk(pts.len());
    let mut fresh = vec![f32::NAN; pts.len() * ndc];
    let mut res: Vec<(f32, Vec3, u32, bool)> = vec![(0.0, Vec3::Z, 0, false); pts.len()];
    let rc_ref = &*rc;
    fresh.par_chunks_mut(chunk * ndc).zip(res.par_chunks_mut(chunk)).zip(pts.par_chunks(chunk).zip(valid.par_chunks(chunk))).for_each(|((rows, res), (pts, valid))| {
        let mut fs: Vec<Option<[f32; 32]>> = Vec::with_capacity(pts.len());
        for (j, (&(_, p), &v)) in pts.iter().zip(valid).enumerate() {
            let m = solids.mask(p);
            let want = if v { fill & !m } else { fill };
            fs.push(if delta.is_empty() { None } else { delta.factors(&lanes, p, want) });
            res[j].2 = m;
            if v {
                continue;
            }
            if let Some(casters) = scan.as_ref() {
                let t = casters.factors(&lanes, p, fill).unwrap_or([1.0; 32]);
                let row = &mut rows[j * nd..(j + 1) * nd];
                for k in 0..nd {
                    if fill & (1 << k) != 0 {
                        row[k] = if t[k] < 1e-4 { 0.0 } else { t[k] };
                    }
                }
            }
        }
        if scan.is_none() {
            // direction by direction (each direction's grid read while in cache)
            for k in 0..nd {
                if fill & (1 << k) == 0 {
                    continue;
                }
                for (j, (&(_, p), &v)) in pts.iter().zip(valid).enumerate() {
                    if !v {
                        rows[j * nd + k] = vols.transmittance(k, p);
                    }
                }
            }
        }
        for (j, ((&(i, _), &v), f)) in pts.iter().zip(valid).zip(fs).enumerate() {
            let m = res[j].2;
            let (mut s, mut d) = (0.0f32, Vec3::ZERO);
            let mut add = |k: usize, tk: f32| {
                let wk = sky.weights[k];
                if wk == 0.0 || m & (1 << k) != 0 {
                    return;
                }
                s += wk * tk;
                d += sky.dirs[k] * (wk * tk);
            };
            if v {
                // a reused row is read, not written (its block stays shared)
                let row = rc_ref.row(i);
                for k in 0..nd {
                    let tk = match f {
                        None => row[k],
                        Some(f) => {
                            let t = (row[k] * f[k]).min(1.0);
                            if t < 1e-4 {
                                0.0
                            } else {
                                t
                            }
                        }
                    };
                    add(k, tk);
                }
            } else {
                let row = &mut rows[j * nd..(j + 1) * nd];
                for k in 0..nd {
                    let t = row[k];
                    add(k, t);
                    // stored in the snapshot's terms
                    row[k] = match f {
                        None => t,
                        Some(f) => (t / f[k]).min(1.0),
                    };
                }
            }
            res[j] = (s, d.normalize_or(Vec3::Z), m, f.is_some());
        }
    });
    stats[0] += pts.len();
    stats[1] += valid.iter().zip(&res).filter(|(&v, r)| v && !r.3).count();
    stats[2] += valid.iter().zip(&res).filter(|(&v, r)| v && r.3).count();
    stats[3] += fresh_pts * fill.count_ones() as usize;
    // the fresh rows stored (their blocks copied first when shared)
    for (j, (&(i, p), _)) in pts.iter().zip(&valid).enumerate().filter(|(_, (_, &v))| !v) {
        rc.fill(i, p, epoch).copy_from_slice(&fresh[j * nd..(j + 1) * nd]);
    }
    let out: Vec<(f32, Vec3)> = res.iter().map(|&(s, d, _, _)| (s, d)).collect();
    if knobs().check {
        vols.prepare(fill);
        let mut e = CHECK_ERR.lock().unwrap_or_else(|p| p.into_inner());
        if e.len() <= lvl {
            e.resize(lvl + 1, [0.0; 8]);
        }
        for (j, ((&(i, p), &valid), &(_, _, m, _))) in pts.iter().zip(&valid).zip(&res).enumerate() {
            let mut s = 0.0f32;
            for k in 0..nd {
                let wk = sky.weights[k];
                if wk == 0.0 || m & (1 << k) != 0 {
                    continue;
                }
                s += wk * vols.transmittance(k, p);
            }
            let d = (out[j].0 - s).abs() as f64;
            let dark = valid && (0..nd).any(|k| fill & !m & (1 << k) != 0 && rc.row(i)[k] == 0.0);
            let b = &mut e[lvl];
            let o = if valid { 0 } else { 3 };
            b[o] += 1.0;
            b[o + 1] += d;
            b[o + 2] = b[o + 2].max(d);
            if dark {
                b[6] += 1.0;
                b[7] += d;
            }
        }
    }
    out
}

/// Largest group whose signatures use shadow volumes of the other trees' clusters built per
/// tree (O(N²) caster copies and grid filtering) instead of one shared set whose queries skip
/// the tree's own clusters: per tree, a query then scans no cell full of its own clusters
/// (measured on the bench's two 2,506-node trees: the signatures took 18 % of the call).
const OWN_OTHERS_MAX: usize = 8;

/// Fewest nodes (or stage clusters) per task when a tree's signatures (or stage occluders) are
/// split over the cores.
const SIG_CHUNK: usize = 256;

/// Most points whose light one task of a level evaluates ([`level`]: the level's clusters and
/// each depth batch of its nodes are split into chunks over the cores).
const LIGHT_CHUNK: usize = 64;

/// Points per task for a batch of `n` light queries: about four tasks per thread, 8 to
/// [`LIGHT_CHUNK`] points each. A depth batch of a level holds a few dozen nodes; with the old
/// fixed chunks of 64 it was one task, and a second core had nothing to take (measured on the
/// 9,133-node bench tree: two threads 50 ms against 53 ms on one). Every point's sums are its
/// own, so the values do not depend on the chunks.
fn light_chunk(n: usize) -> usize {
    n.div_ceil(4 * rayon::current_num_threads()).clamp(8, LIGHT_CHUNK)
}

/// Bits of every direction of `sky` (bit k: direction k), for [`ShadowVolumes::prepare`].
fn sky_bits(sky: &super::light::Sky) -> u32 {
    let n = sky.dirs.len().min(32);
    if n == 32 {
        u32::MAX
    } else {
        (1u32 << n) - 1
    }
}

/// Turn (radians, 0.057°) below which a recomputed node's children are not recomputed: they keep
/// their rotation and follow the node's displacement.
pub const ROTATION_EPS: f32 = 1e-3;

/// One level (stage `s`) of one tree: bend its recomputed season-`s` nodes, refresh the light on
/// its recomputed stage clusters, prune by eq. (11).
/// The light of the clusters is taken direction by direction; a direction of a cluster whose
/// occluder is the same as at the previous level reuses that level's transmittance when no
/// changed caster (`reuse.delta`) lies on the ray: the same casters hit, multiplied in the same
/// order, so the value is the one a recomputation gives, bit for bit. Returns the stage's
/// transmittances.
#[allow(clippy::too_many_arguments)]
fn level(t: &mut PlasticTree, s: usize, w: &mut Work, occ: &[Option<Occluder>], env: &Environment, solids: &SkyMask, vols: &ShadowVolumes, fixed: Option<&ShadowVolumes>, reuse: Option<Reuse>) -> Rows {
    // a level that recomputes every node of its season with the exact light bends the season's
    // chains side by side (`bend_by_chains`: the same values, fewer joins of the cores)
    // (not with shared bending light, `PlasticTree::bend_light_cell_m`: the depth batches share it)
    let by_chains = w.mc.is_none() && t.bend_light_cell_m == 0.0 && !forced(Forced::DepthBatches) && w.season(s).iter().all(|&k| w.own[k as usize]);
    if by_chains {
        bend_by_chains(t, s, w, env, solids, vols, fixed);
    }
    let n = t.input.nodes.len();
    let a = &t.analysis;
    let sky = &env.sky;
    let nd = sky.dirs.len();
    // else the season's nodes by depth below the older wood: a node's parent is placed before it
    // (depth − 1, or older than the season), so each depth's bending light is taken as a batch
    // (direction by direction, over the cores) and the nodes of a depth are then bent in index
    // order as before, bit for bit the values of a node-by-node pass
    let mut buckets: Vec<Vec<usize>> = Vec::new();
    if !by_chains {
        let mut depth = std::mem::take(&mut w.depth);
        for &k in w.season(s) {
            let k = k as usize;
            let par = t.input.nodes[k].parent.unwrap_or(0) as usize;
            let d = if par > 0 && a.season[par] as usize == s { depth[par] + 1 } else { 0 };
            depth[k] = d;
            if buckets.len() <= d as usize {
                buckets.push(Vec::new());
            }
            buckets[d as usize].push(k);
        }
        w.depth = depth;
    }
    let mut at: Vec<Vec3> = Vec::new();
    let mut at_k: Vec<(usize, Vec3)> = Vec::new();
    // the cubes whose bending light this level took (`PlasticTree::bend_light_whole_level`)
    let mut seen: Option<LevelLight> = (t.bend_light_whole_level && t.bend_light_cell_m > 0.0).then(LevelLight::default);
    if let Some(mc) = w.mc.as_mut() {
        mc.nodes.ensure(n, nd);
    }
    for bucket in &buckets {
        // pass 1: fates, the nodes kept, and where the recomputed ones would stand unbent
        at.clear();
        at_k.clear();
        for &k in bucket {
            let par = t.input.nodes[k].parent.unwrap_or(0) as usize;
            if t.fate[par] != Fate::Alive {
                t.fate[k] = t.fate[par];
            }
            if !(w.own[k] || w.moved[par]) {
                // not recomputed: keeps its rotation, follows its parent's (small) displacement
                if w.shifted[par] {
                    t.pos[k] = t.pos[par] + t.rot[k] * (t.input.nodes[k].pos - t.input.nodes[par].pos);
                    w.shifted[k] = t.pos[k] != w.before[k];
                    if t.fate[k] == Fate::Alive && collides(env, t.pos[par], t.pos[k], clearance(t, k)) {
                        t.fate[k] = Fate::Collision;
                    }
                }
                continue;
            }
            let seg = t.input.nodes[k].pos - t.input.nodes[par].pos;
            if seg.length() > 0.0 {
                at.push(t.pos[par] + t.rot[par] * seg);
                at_k.push((k, t.pos[par] + t.rot[par] * seg));
            }
        }
        let lights = match w.mc.as_mut() {
            Some(mc) => light_cached(sky, solids, vols, &mut mc.nodes, w.mc_epoch, &w.mc_delta, !w.mc_new, mc.tol_m, &at_k, &mut w.mc_stats, s),
            None => light_many_shared(sky, solids, vols, fixed, &at, t.bend_light_cell_m, seen.as_mut()),
        };
        // pass 2: bend the recomputed nodes
        let mut lights = lights.into_iter();
        for &k in bucket {
            let par = t.input.nodes[k].parent.unwrap_or(0) as usize;
            if !(w.own[k] || w.moved[par]) {
                continue;
            }
            w.done[k] = true;
            let (old_pos, old_rot) = (w.before[k], t.rot[k]);
            let seg = t.input.nodes[k].pos - t.input.nodes[par].pos;
            let len = seg.length();
            let l_new = if len > 0.0 { lights.next().unwrap_or((0.0, Vec3::Z)).1 } else { Vec3::Z };
            let (q, bend) = bend_of(t, k, par, t.rot[par], seg, l_new);
            t.rot[k] = q;
            t.bend[k] = bend;
            t.pos[k] = t.pos[par] + q * seg;
            w.shifted[k] = t.pos[k] != old_pos;
            // the children are recomputed when this node turned by more than ROTATION_EPS
            let turn = 2.0 * (t.rot[k] * old_rot.inverse()).xyz().length().min(1.0).asin();
            w.moved[k] = turn > ROTATION_EPS;
            if t.fate[k] == Fate::Alive && collides(env, t.pos[par], t.pos[k], clearance(t, k)) {
                t.fate[k] = Fate::Collision;
            }
        }
    }
    // light on this stage's clusters that were recomputed: the pruning of eq. (11) at this
    // level needs it, and the last level's is the leaf clusters' light (eqs. 12–13); a tree
    // that eq. (11) cannot shed (`Work::prunes`) needs the last level's only
    let clusters = &a.stages[s];
    let needs_light = w.prunes || s == a.seasons as usize;
    let mut lit = Vec::new();
    for (ci, c) in clusters.iter().enumerate().filter(|_| needs_light) {
        let touched = match c.lobe {
            Some(l) => a.lobes[l as usize].nodes.iter().any(|&k| w.done[k as usize]),
            None => w.done[c.anchor as usize],
        };
        if touched {
            match occ[ci] {
                Some(o) => lit.push((ci, o.center)),
                None => t.light_cache[s][ci] = 0.0,
            }
        }
    }
    let mut rows = Rows { start: vec![u32::MAX; clusters.len()], t: vec![f32::NAN; lit.len() * nd] };
    if let Some(mc) = w.mc.as_mut() {
        // the move light model: the stage's stored rows, only what the change can alter
        // recomputed (no rows kept for the next level: a lone tree reuses none)
        let rc = &mut mc.stages[s].rows;
        rc.ensure(clusters.len(), nd);
        let lights = light_cached(sky, solids, vols, rc, w.mc_epoch, &w.mc_delta, !w.mc_new, mc.tol_m, &lit, &mut w.mc_stats, s);
        for (&(ci, _), (l, _)) in lit.iter().zip(lights) {
            t.light_cache[s][ci] = l;
        }
        rows.t.clear();
        return prune(t, s, w, occ, rows);
    }
    // a tree that eq. (11) cannot shed: its last level's clusters of one cube (and the same
    // solids) share the first one's light (`PlasticTree::leaf_light_cell_m`): `share` holds
    // every cluster to light and, per cluster, its representative's index in `lit`
    let share = (!w.prunes && s == a.seasons as usize && t.leaf_light_cell_m > 0.0 && lit.len() > 1).then(|| {
        let all = std::mem::take(&mut lit);
        let (reps, of) = shared_points(&all.iter().map(|&(_, c)| c).collect::<Vec<_>>(), t.leaf_light_cell_m, |j| solids.mask(all[j].1));
        lit = reps.iter().map(|&j| all[j]).collect();
        (all, of)
    });
    if share.is_some() {
        rows.t = vec![f32::NAN; lit.len() * nd];
    }
    // (mask, previous row) of every cluster lit
    let from: Vec<(u32, Option<&[f32]>)> = lit
        .par_iter()
        .with_min_len(LIGHT_CHUNK)
        .map(|&(ci, c)| {
            let old = reuse.as_ref().and_then(|r| {
                let pj = r.map[ci]? as usize;
                let st = r.rows.start[pj];
                (st != u32::MAX && same_occluder(&r.occ[pj], &occ[ci])).then(|| &r.rows.t[st as usize..st as usize + nd])
            });
            (solids.mask(c), old)
        })
        .collect();
    let mut sums = vec![0.0f32; lit.len()];
    // the grids of the directions open at some cluster to be computed, built over the cores
    // first (of the changed casters too, which the reused values are checked against)
    let open = !from.iter().fold(u32::MAX, |a, &(m, _)| a & m);
    vols.prepare(open);
    if let Some(f) = fixed {
        f.prepare(open);
    }
    if let Some(r) = reuse.as_ref() {
        r.delta.prepare(open);
    }
    // chunks of clusters over the cores; within a chunk direction by direction (each direction's
    // grid read while in cache), every cluster's sum taken in direction order as before, so the
    // values are the same bit for bit whatever the thread count
    let reuse_ref = reuse.as_ref();
    let chunk = light_chunk(lit.len());
    rows.t.par_chunks_mut(chunk * nd.max(1)).zip(sums.par_chunks_mut(chunk)).zip(lit.par_chunks(chunk).zip(from.par_chunks(chunk))).for_each(|((t_rows, sums), (lit, from))| {
        for k in 0..nd {
            let wk = sky.weights[k];
            if wk == 0.0 {
                continue;
            }
            for (j, (&(_, c), &(mask, old))) in lit.iter().zip(from).enumerate() {
                if mask & (1 << k) != 0 {
                    continue;
                }
                // the fixed trees' part of a reused value is unchanged: they do not move
                let tk = match (old, reuse_ref) {
                    (Some(o), Some(r)) if !o[k].is_nan() && !r.delta.shaded(k, c) => o[k],
                    _ => through_both(vols, fixed, k, c),
                };
                t_rows[j * nd + k] = tk;
                sums[j] += wk * tk;
            }
        }
    });
    match share {
        None => {
            for (j, &(ci, _)) in lit.iter().enumerate() {
                rows.start[ci] = (j * nd) as u32;
                t.light_cache[s][ci] = sums[j];
            }
        }
        Some((all, of)) => {
            // every cluster takes its representative's sum and row
            for (&(ci, _), &r) in all.iter().zip(&of) {
                rows.start[ci] = r * nd as u32;
                t.light_cache[s][ci] = sums[r as usize];
            }
        }
    }
    prune(t, s, w, occ, rows)
}

/// Tests only: switches that make a call take its serial or older path where a faster one gives
/// the same values bit for bit, to check that both give the same trees (any call meanwhile gets
/// the same values either way).
#[derive(Debug, Clone, Copy)]
enum Forced {
    /// [`level`] bends by depth batches where it would bend by chains ([`bend_by_chains`]).
    DepthBatches,
    /// [`Pruning::of`] puts every node outside the subtrees, so [`prune`] takes one pass over
    /// the nodes (the serial pass).
    SerialPrune,
    /// [`adapt_among`] builds every level's grids afresh instead of merging them from the level
    /// before's ([`ShadowVolumes::after`]).
    FreshGrids,
}

/// The state of each [`Forced`] switch.
#[cfg(test)]
static FORCED: [std::sync::atomic::AtomicBool; 3] = [std::sync::atomic::AtomicBool::new(false), std::sync::atomic::AtomicBool::new(false), std::sync::atomic::AtomicBool::new(false)];

/// Whether switch `f` is set (never outside tests).
#[cfg(test)]
fn forced(f: Forced) -> bool {
    FORCED[f as usize].load(std::sync::atomic::Ordering::Relaxed)
}

#[cfg(not(test))]
fn forced(_: Forced) -> bool {
    false
}

/// The bend of node `k` of `t` (parent `par`, input segment `seg` from the parent, m) at its
/// level: the rotation that takes its input direction to the direction of eq. (6), the
/// weighted sum of its original direction turned by its parent's rotation `q_par`, the
/// tropism towards the light direction `l_new` (eq. 3's average direction, unit) blended by
/// the flexibility of its age, and the analysis residual; and the angle (radians) between that
/// direction and the direction the parent's rotation alone gives. A segment of length 0 keeps
/// the parent's rotation, bend 0.
fn bend_of(t: &PlasticTree, k: usize, par: usize, q_par: Quat, seg: Vec3, l_new: Vec3) -> (Quat, f32) {
    let len = seg.length();
    if !(len > 0.0) {
        return (q_par, 0.0);
    }
    let a = &t.analysis;
    let last = a.seasons as f32;
    let h = seg / len;
    let t_old = tropism(&t.params, a.light_dir[k]);
    // flexibility by age (step 3): the tip's season of eq. (2), the base's (t_{s_p}) for a
    // forest-grown tree's lengthened bole
    let born = if t.bole.map(|b| b as usize) == Some(k) { a.season[par] } else { a.season[k] };
    let kappa = 1.0 - (last - born as f32) / (last + 1.0);
    let t_eff = (t_old + kappa * (tropism(&t.params, l_new) - t_old)).normalize_or(t_old);
    let ws = a.w_s[k];
    let h_rigid = q_par * h;
    // eq. (6) plus the analysis residual (zero where eq. 9 has a root): exact identity when
    // nothing changed
    let h_new = (ws * (q_par * a.d_o[k]) + (1.0 - ws) * t_eff + q_par * a.residual[k]).normalize_or(h_rigid);
    (Quat::from_rotation_arc(h, h_new), h_rigid.dot(h_new).clamp(-1.0, 1.0).acos())
}

/// One season node as [`bend_by_chains`] leaves it: the values that [`level`]'s two passes
/// write (position (m), rotation, bend angle (radians), fate, and the `moved`, `shifted`,
/// `done` flags of [`Work`]).
#[derive(Debug, Clone, Copy)]
struct Bent {
    pos: Vec3,
    rot: Quat,
    bend: f32,
    fate: Fate,
    moved: bool,
    shifted: bool,
    done: bool,
}

/// Fewest nodes of the season that one task of [`bend_by_chains`] bends (whole chains).
const CHAIN_TASK: usize = 32;

/// The bending of [`level`] for a level that recomputes every node of season `s` with the exact
/// light (no move light model): the season's nodes fall into chains, each rooted at a node
/// whose parent is older than the season (or the root), and a node depends only on its chain's
/// earlier nodes and on older wood, which the level does not move (its light comes from the
/// level's grids, built before the level bends anything). So whole chains are bent side by side
/// over the cores, each node by the two passes of [`level`] (fates inherited, followers
/// displaced, the light of eq. (3) summed in direction order as [`light_many_among`] sums it,
/// the bend of eq. (6)), in index order within its chain: the same values bit for bit as the
/// depth batches give, whatever the thread count, with one join of the cores per level instead
/// of three per depth batch. The grids of the directions open at the season's nodes as
/// [`preposition`] placed them are built first, over the cores (a direction first opened by a
/// bend is built when first asked for: the same grid).
fn bend_by_chains(t: &mut PlasticTree, s: usize, w: &mut Work, env: &Environment, solids: &SkyMask, vols: &ShadowVolumes, fixed: Option<&ShadowVolumes>) {
    let sky = &env.sky;
    let mut slot = std::mem::take(&mut w.depth);
    let (season, a, input) = (w.season(s), &t.analysis, &t.input);
    let parent = |k: usize| input.nodes[k].parent.unwrap_or(0) as usize;
    let in_chain = |par: usize| par > 0 && a.season[par] as usize == s;
    // every season node's chain (its index in `size`), then its place in `flat`, where each
    // chain's nodes lie together in index order
    let mut size: Vec<u32> = Vec::new();
    for &k in season {
        let (k, par) = (k as usize, parent(k as usize));
        let c = if in_chain(par) {
            slot[par]
        } else {
            size.push(0);
            size.len() as u32 - 1
        };
        slot[k] = c;
        size[c as usize] += 1;
    }
    let mut next = Vec::with_capacity(size.len());
    let mut tasks: Vec<(usize, usize)> = Vec::new();
    let (mut run, mut from) = (0usize, 0usize);
    for &n in &size {
        next.push(run as u32);
        run += n as usize;
        if run - from >= CHAIN_TASK {
            tasks.push((from, run));
            from = run;
        }
    }
    if run > from {
        tasks.push((from, run));
    }
    let mut flat = vec![0u32; season.len()];
    for &k in season {
        let c = slot[k as usize] as usize;
        flat[next[c] as usize] = k;
        slot[k as usize] = next[c];
        next[c] += 1;
    }
    // the solids' mask of every node (in `flat`'s order) where it stands before the level bends
    // it, and the grids of the directions open at some node
    let masks: Vec<u32> = flat
        .par_iter()
        .with_min_len(SIG_CHUNK)
        .map(|&k| {
            let k = k as usize;
            let seg = input.nodes[k].pos - input.nodes[parent(k)].pos;
            if seg.length() > 0.0 {
                solids.mask(t.pos[k])
            } else {
                u32::MAX
            }
        })
        .collect();
    let open = !masks.iter().fold(u32::MAX, |x, &y| x & y) & sky_bits(sky);
    vols.prepare(open);
    if let Some(f) = fixed {
        f.prepare(open);
    }
    let tr: &PlasticTree = t;
    let (own, moved, shifted, before, done, slot_ref) = (&w.own, &w.moved, &w.shifted, &w.before, &w.done, &slot);
    let bent: Vec<Vec<Bent>> = tasks
        .par_iter()
        .map(|&(lo, hi)| {
            let mut out: Vec<Bent> = Vec::with_capacity(hi - lo);
            for (i, &k) in flat.iter().enumerate().take(hi).skip(lo) {
                let k = k as usize;
                let par = parent(k);
                // the parent as it stands now: bent before in this chain, or older wood
                let (p_pos, p_rot, p_fate, p_moved, p_shifted) = if in_chain(par) {
                    let b = &out[slot_ref[par] as usize - lo];
                    (b.pos, b.rot, b.fate, b.moved, b.shifted)
                } else {
                    (tr.pos[par], tr.rot[par], tr.fate[par], moved[par], shifted[par])
                };
                let mut b = Bent { pos: tr.pos[k], rot: tr.rot[k], bend: tr.bend[k], fate: tr.fate[k], moved: moved[k], shifted: shifted[k], done: done[k] };
                // pass 1: the fate, and a node kept follows its parent's displacement
                if p_fate != Fate::Alive {
                    b.fate = p_fate;
                }
                let seg = input.nodes[k].pos - input.nodes[par].pos;
                if !(own[k] || p_moved) {
                    if p_shifted {
                        b.pos = p_pos + b.rot * seg;
                        b.shifted = b.pos != before[k];
                        if b.fate == Fate::Alive && collides(env, p_pos, b.pos, clearance(tr, k)) {
                            b.fate = Fate::Collision;
                        }
                    }
                    out.push(b);
                    continue;
                }
                // pass 2: the bend, from the light where the node stands unbent
                b.done = true;
                let l_new = if seg.length() > 0.0 {
                    // a node on older wood stands where `preposition` placed it: its mask is known
                    let at = p_pos + p_rot * seg;
                    let mask = if in_chain(par) { solids.mask(at) } else { masks[i] };
                    light_by(sky, mask, |d| through_both(vols, fixed, d, at)).1
                } else {
                    Vec3::Z
                };
                let (q, bend) = bend_of(tr, k, par, p_rot, seg, l_new);
                let old_rot = b.rot;
                (b.rot, b.bend, b.pos) = (q, bend, p_pos + q * seg);
                b.shifted = b.pos != before[k];
                let turn = 2.0 * (b.rot * old_rot.inverse()).xyz().length().min(1.0).asin();
                b.moved = turn > ROTATION_EPS;
                if b.fate == Fate::Alive && collides(env, p_pos, b.pos, clearance(tr, k)) {
                    b.fate = Fate::Collision;
                }
                out.push(b);
            }
            out
        })
        .collect();
    for (&k, b) in flat.iter().zip(bent.iter().flatten()) {
        let k = k as usize;
        (t.pos[k], t.rot[k], t.bend[k], t.fate[k]) = (b.pos, b.rot, b.bend, b.fate);
        (w.moved[k], w.shifted[k], w.done[k]) = (b.moved, b.shifted, b.done);
    }
    w.depth = slot;
}

/// The pruning of eqs. (10)–(11) after level `s` of [`level`] (the stage's light in
/// `t.light_cache[s]`); returns `rows`. A tree that eq. (11) can shed is pruned over the cores
/// ([`prune_parts`]), any other serially; the same fates either way.
fn prune(t: &mut PlasticTree, s: usize, w: &mut Work, occ: &[Option<Occluder>], rows: Rows) -> Rows {
    // pruning (eqs. 10–11); the fates of shed parents are inherited in any case
    // the nodes of season ≤ s: the pruning below changes no other node. A tree that eq. (11)
    // cannot shed and whose nodes are all alive has nothing to prune or pass on (the loop below
    // would change no fate): skipped, its stage list brought up to date when next needed
    if !w.prunes && t.fate.iter().all(|f| *f == Fate::Alive) {
        return rows;
    }
    if w.prunes {
        prune_parts(t, s, w, occ);
        return rows;
    }
    w.stage_to(s);
    let a = &t.analysis;
    for &k in &w.stage {
        let k = k as usize;
        let par = t.input.nodes[k].parent.unwrap_or(0) as usize;
        if t.fate[par] != Fate::Alive && t.fate[k] == Fate::Alive && a.season[k] as usize <= s {
            t.fate[k] = t.fate[par];
        }
    }
    rows
}

/// [`prune`] for a tree that eq. (11) can shed: ψ_s(t) of eq. (10) for the nodes of season ≤ s
/// (ζ from the stage's clusters, 2π r_c² i_c with the light normalised per stage; l the branch
/// length of the stage subtree; summed from the tips down as `analysis::psi_at_stage` sums them),
/// then in index order a node whose parent is shed inherits its fate and a node judged at this
/// stage with ψ below its ψ_s,min (eq. 11) is shed for light. Over the cores: the subtrees of
/// [`Pruning::parts`] take their sums side by side, the nodes outside them ([`Pruning::top`])
/// then take theirs, adding each subtree root's sums where the serial pass added them (in
/// decreasing index order of the children), and their fates; then the subtrees take their
/// fates side by side. Every sum is taken term for term in the order of one pass over the
/// nodes in decreasing index order, and every fate from its parent's final fate, so the values
/// are the same bit for bit whatever the thread count.
fn prune_parts(t: &mut PlasticTree, s: usize, w: &mut Work, occ: &[Option<Occluder>]) {
    let a = &t.analysis;
    let clusters = &a.stages[s];
    let light = normalised(&t.light_cache[s], |ci| occ[ci].is_some());
    let pr = w.pruning.get_or_insert_with(|| Pruning::of(&t.input, &t.analysis));
    pr.zeta.iter_mut().for_each(|z| *z = 0.0);
    pr.len.iter_mut().for_each(|z| *z = 0.0);
    for (c, &i) in clusters.iter().zip(&light) {
        if t.fate[c.anchor as usize] == Fate::Alive {
            pr.zeta[c.anchor as usize] += 2.0 * std::f32::consts::PI * c.radius * c.radius * i;
        }
    }
    let Pruning { parent, seg, zeta, len, psi, parts, top } = pr;
    let fate = &t.fate;
    // the subtrees' sums, from the tips down (a node of a later season is in no sum, and its
    // entries are not read)
    let s16 = s as u16;
    parts.par_iter_mut().for_each(|p| {
        for (j, &k) in p.nodes.iter().enumerate() {
            if p.season[j] <= s16 {
                (p.zeta[j], p.len[j]) = (zeta[k as usize], 0.0);
            }
        }
        for j in (0..p.nodes.len()).rev() {
            if p.season[j] > s16 || fate[p.nodes[j] as usize] != Fate::Alive {
                p.psi[j] = f32::NAN;
                continue;
            }
            p.len[j] += p.seg[j];
            p.psi[j] = if p.len[j] > 0.0 { p.zeta[j] / p.len[j] } else { f32::NAN };
            let q = p.par[j];
            if q != u32::MAX {
                let (z, l) = (p.zeta[j], p.len[j]);
                p.zeta[q as usize] += z;
                p.len[q as usize] += l;
            }
        }
    });
    // the nodes outside them, the subtrees' roots added in their places (the root, node 0, is
    // in no stage: neither judged nor given a fate)
    for &(k, pi, j) in top.iter().rev() {
        let k = k as usize;
        if k == 0 || a.season[k] as usize > s || fate[k] != Fate::Alive {
            continue;
        }
        let (z, l) = if pi == u32::MAX {
            len[k] += seg[k];
            psi[k] = if len[k] > 0.0 { zeta[k] / len[k] } else { f32::NAN };
            (zeta[k], len[k])
        } else {
            let p = &parts[pi as usize];
            (p.zeta[j as usize], p.len[j as usize])
        };
        let q = parent[k] as usize;
        zeta[q] += z;
        len[q] += l;
    }
    // fates: the nodes outside the subtrees, then the subtrees side by side
    let judge = |season: u16, psi_min: f32, own: Fate, from: Fate, psi: f32| -> Fate {
        if from != Fate::Alive {
            if own == Fate::Alive {
                return from;
            }
        } else if own == Fate::Alive && judged(season, s16) && psi < psi_min {
            return Fate::Light;
        }
        own
    };
    let fate = &mut t.fate;
    for &(k, pi, _) in top.iter() {
        let k = k as usize;
        if pi != u32::MAX || k == 0 || a.season[k] > s16 {
            continue;
        }
        fate[k] = judge(a.season[k], a.psi_min[k], fate[k], fate[parent[k] as usize], psi[k]);
    }
    let fate_now: &[Fate] = fate;
    parts.par_iter_mut().for_each(|p| {
        p.changed.clear();
        for j in 0..p.nodes.len() {
            if p.season[j] > s16 {
                continue;
            }
            let k = p.nodes[j] as usize;
            let q = p.par[j];
            // (a parent of a later season, not in the stage, keeps its fate)
            let from = if q == u32::MAX || p.season[q as usize] > s16 { fate_now[parent[k] as usize] } else { p.fate[q as usize] };
            let own = fate_now[k];
            let f = judge(p.season[j], p.psi_min[j], own, from, p.psi[j]);
            p.fate[j] = f;
            if f != own {
                p.changed.push((k as u32, f));
            }
        }
    });
    for p in parts.iter() {
        for &(k, f) in &p.changed {
            fate[k as usize] = f;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`shared_points`]: points share the first point of their cube of side `cell` (world
    /// coordinates, ⌊p / cell⌋, so −0.1 and 0.1 lie in different cubes) when their solids'
    /// masks are equal; with cell 0 every point is its own.
    #[test]
    fn shared_points_take_the_first_of_their_cube_and_mask() {
        let at = [Vec3::new(0.1, 0.1, 0.1), Vec3::new(0.4, 0.2, 0.3), Vec3::new(-0.1, 0.1, 0.1), Vec3::new(0.45, 0.45, 0.45), Vec3::new(0.6, 0.1, 0.1), Vec3::new(0.2, 0.2, 0.2)];
        let masks = [0u32, 0, 0, 1, 0, 0];
        let (reps, of) = shared_points(&at, 0.5, |i| masks[i]);
        // cube (0,0,0) mask 0: points 0, 1, 5; cube (−1,0,0): 2; cube (0,0,0) mask 1: 3; cube (1,0,0): 4
        assert_eq!(reps, vec![0, 2, 3, 4]);
        assert_eq!(of, vec![0, 0, 1, 2, 3, 0]);
        let (reps, of) = shared_points(&at, 0.0, |i| masks[i]);
        assert_eq!((reps, of), ((0..6).collect::<Vec<_>>(), (0..6).collect::<Vec<u32>>()));
    }

    /// [`light_many_shared`] over a whole level ([`LevelLight`]): batch after batch, every point
    /// takes, bit for bit, the light [`light_many_among`] gives the first point of the level
    /// (over every batch so far, in order) in its cube of side `cell` with the same solids'
    /// mask: the reference keeps a plain list of the cubes met and queries each
    /// representative alone. The cases test something: points of a batch share a cube met in an
    /// earlier batch, points share within a batch, and a wall splits cubes by mask.
    #[test]
    fn whole_level_light_is_the_first_point_of_its_cube_over_the_level() {
        let sky = crate::structure::plastic::Sky::from_latitude(47.0);
        let occ: Vec<Occluder> = (0..300)
            .map(|i| {
                let f = i as f32;
                let r = 0.3 + 0.4 * (f * 0.37).sin().abs();
                Occluder { center: Vec3::new((f * 0.71).sin() * 3.0, (f * 0.53).cos() * 3.0, 4.0 + (f * 0.29).sin().abs() * 5.0), radius: r, gamma: 0.5f32.powf(r) }
            })
            .collect();
        let vols = ShadowVolumes::new(&sky, occ);
        let env = wall_at(0.5);
        let solids = SkyMask::new(Solids { obstacles: &env.obstacles, ground: Some(super::super::Ground::flat(0.0)) }, &sky);
        let cell = 0.5;
        let mut seen = LevelLight::default();
        let mut met: Vec<((IVec3, u32), Vec3)> = Vec::new();
        let (mut earlier, mut within, mut masks) = (0, 0, std::collections::BTreeSet::new());
        for b in 0..4 {
            let at: Vec<Vec3> = (0..150).map(|j| {
                let f = (b * 150 + j) as f32;
                Vec3::new((f * 0.113).sin() * 1.2, (f * 0.071).cos() * 1.2, 3.0 + (f * 0.037).sin().abs() * 2.0)
            }).collect();
            let got = light_many_shared(&sky, &solids, &vols, None, &at, cell, Some(&mut seen));
            let before = met.len();
            for (p, g) in at.iter().zip(&got) {
                let key = ((*p / cell).floor().as_ivec3(), solids.mask(*p));
                masks.insert(key.1);
                let rep = match met.iter().position(|(k, _)| *k == key) {
                    Some(r) => {
                        if r < before { earlier += 1 } else { within += 1 }
                        met[r].1
                    }
                    None => {
                        met.push((key, *p));
                        *p
                    }
                };
                let want = light_many_among(&sky, &solids, &vols, None, &[rep])[0];
                assert_eq!((g.0.to_bits(), g.1.to_array().map(f32::to_bits)), (want.0.to_bits(), want.1.to_array().map(f32::to_bits)), "batch {b}, point {p}");
            }
        }
        assert_eq!(seen.light.len(), met.len());
        assert!(earlier > 100 && within > 100 && masks.len() > 1, "{earlier} {within} {masks:?}");
    }

    /// [`PlasticTree::scaled`] is a clone scaled by [`PlasticTree::scale`], field for field (its
    /// `Debug` text: every position, rotation, fate, stage light and the analysis), for a tree
    /// fresh from its analysis and for one adapted beside a wall (whose state scaling resets).
    #[test]
    fn a_scaled_copy_is_a_scaled_clone() {
        let mut t = beech_at(3, 1.0);
        for step in 0..2 {
            for f in [0.8f32, 1.3] {
                let mut c = t.clone();
                c.scale(f).unwrap();
                assert_eq!(format!("{:?}", t.scaled(f).unwrap()), format!("{c:?}"), "step {step}, factor {f}");
                c.force = false;
                assert_eq!(format!("{:?}", t.scaled_grown_on_open_ground(f).unwrap()), format!("{c:?}"));
            }
            t.adapt(&wall_at(1.5)).unwrap();
            assert!(t.fate.iter().any(|f| *f != Fate::Alive) || t.bend.iter().any(|&b| b > 0.01));
        }
        assert!(t.scaled(0.0).is_err());
    }

    /// The refresh policy of [`MoveCache::level`]: a level whose casters changed (10 cm, the
    /// wall's step) is patched while one call changes at most [`MOVE_DELTA_MAX`] of them and
    /// the changes applied since its snapshot stay within [`MOVE_PATCH_BUDGET`]; then it takes a
    /// new snapshot (a new epoch, no changed casters), and changes within the tolerance are not
    /// applied. Round 39's 64 re-snapshotted at the first call's 200 changed casters.
    #[test]
    fn a_level_is_patched_within_its_budget_then_snapshot_anew() {
        let shade: Vec<(u64, Occluder)> = (0..1000).map(|i| (i as u64, Occluder { center: Vec3::new(i as f32, 0.0, 3.0), radius: 0.4, gamma: 0.6 })).collect();
        let grown = |n: usize, by: f32| -> Vec<(u64, Occluder)> { shade.iter().enumerate().map(|(i, &(k, o))| (k, if i < n { Occluder { radius: o.radius + by, ..o } } else { o })).collect() };
        let mut mc = MoveCache::new(0.05);
        let (e, d) = mc.level(2, &shade);
        assert_eq!((e, d.len()), (1, 0), "the first call takes the snapshot");
        let (e, d) = mc.level(2, &grown(200, 0.04));
        assert_eq!((e, d.len()), (1, 0), "changes within the tolerance are not applied");
        let (e, d) = mc.level(2, &grown(200, 0.1));
        assert_eq!((e, d.len()), (1, 200), "200 casters grown by 10 cm: patched");
        assert!(d.iter().all(|(a, b)| a.is_some_and(|a| a.radius == 0.4) && b.is_some_and(|b| (b.radius - 0.5).abs() < 1e-6)));
        // 200 + 250 applied since the snapshot: within the budget (512); 250 more pass it
        let n = 250;
        let (e, d) = mc.level(2, &grown(n, 0.1));
        assert_eq!((e, d.len()), (1, n), "patched within the budget");
        let (e, d) = mc.level(2, &grown(n, 0.1));
        assert_eq!((e, d.len()), (2, 0), "past the budget: a new snapshot");
        let (e, d) = mc.level(2, &grown(n, 0.1));
        assert_eq!((e, d.len()), (2, 0), "nothing changed since the new snapshot");
        let (e, d) = mc.level(2, &grown(n + MOVE_DELTA_MAX + 1, 0.1));
        assert_eq!((e, d.len()), (3, 0), "more than MOVE_DELTA_MAX in one call: a new snapshot");
        // another level keeps its own snapshot and budget
        assert_eq!(mc.level(5, &shade).0, 1);
    }

    /// A 25-year beech of the light-guided model (`grow_species_tree`, seed `seed`), analysed
    /// in the open and moved by `x` (m) along x.
    fn beech_at(seed: u64, x: f32) -> PlasticTree {
        let lib = crate::species::SpeciesLibrary::embedded().unwrap();
        let sp = &lib.species[lib.find("beech").unwrap() as usize];
        let g = crate::structure::species_tree::grow_species_tree(sp, crate::structure::species_tree::Model::Light, 25.0, &[], seed).unwrap();
        let mut t = PlasticTree::analyse(&g.skeleton, &sp.architecture.plastic, &Environment::open(), None).unwrap();
        t.translate(Vec3::new(x, 0.0, 0.0));
        t
    }

    /// Open space with a wall 0.2 m thick, 8 m long and 6 m high, centred at (x, 0, 3) m.
    fn wall_at(x: f32) -> Environment {
        Environment::with_obstacles(&[Obstacle::OrientedBox { center: Vec3::new(x, 0.0, 3.0), half: Vec3::new(0.1, 4.0, 3.0), yaw_deg: 0.0 }])
    }

    /// [`bend_by_chains`] against the depth batches of [`level`] ([`Forced::DepthBatches`]), and on
    /// one thread against two: a 25-year beech beside a wall alone, and two beeches adapted
    /// together among a fixed third (the fixed trees' shade multiplied in); every position,
    /// rotation, bend angle and fate equal bit for bit, and the reports equal. The cases test
    /// something: nodes bent by more than 1°, shed by light and by the wall.
    #[test]
    fn chains_bend_as_the_depth_batches() {
        use std::sync::atomic::Ordering;
        let tree = beech_at;
        let env = wall_at(1.2);
        let (lone, pair, fixed) = (vec![tree(7, 0.0)], vec![tree(8, 0.0), tree(9, -2.0)], vec![tree(10, -4.0)]);
        let run = |threads: usize, batches: bool, trees: &[PlasticTree], fixed: &[PlasticTree]| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            FORCED[Forced::DepthBatches as usize].store(batches, Ordering::Relaxed);
            let mut trees = trees.to_vec();
            let rep = pool.install(|| adapt_group_among(&mut trees, fixed, &env)).unwrap();
            FORCED[Forced::DepthBatches as usize].store(false, Ordering::Relaxed);
            let bits: Vec<(Vec<[u32; 3]>, Vec<[u32; 4]>, Vec<u32>, Vec<Fate>)> = trees
                .iter()
                .map(|t| (t.pos.iter().map(|v| v.to_array().map(f32::to_bits)).collect(), t.rot.iter().map(|q| q.to_array().map(f32::to_bits)).collect(), t.bend.iter().map(|b| b.to_bits()).collect(), t.fate.clone()))
                .collect();
            (rep, bits)
        };
        for (trees, fixed) in [(&lone, &[][..]), (&pair, &fixed[..])] {
            let (rep, bits) = run(1, false, trees, fixed);
            assert!(rep.trees.iter().all(|r| r.bent > 10), "{rep:?}");
            assert!(rep.trees.iter().map(|r| r.pruned_light).sum::<usize>() > 0 && rep.trees.iter().any(|r| r.pruned_collision > 0), "{rep:?}");
            let (rep_b, bits_b) = run(1, true, trees, fixed);
            assert_eq!(rep, rep_b);
            assert!(bits == bits_b, "chains and depth batches differ ({} trees)", trees.len());
            let (rep_2, bits_2) = run(2, false, trees, fixed);
            assert_eq!(rep, rep_2);
            assert!(bits == bits_2, "one thread and two differ ({} trees)", trees.len());
        }
    }

    /// Round 46 (issue 32): the levels' grids merged from the level before's
    /// ([`ShadowVolumes::after`]) against grids built afresh at every level
    /// ([`Forced::FreshGrids`], main's path until round 46), on one thread and on two: four
    /// beeches 1.5 m apart adapted together among a fixed fifth (every level's grids prepared
    /// for two or more trees at work, so merged). A checksum (FNV-1a) over the bits of every
    /// position, rotation, bend angle, fate and leaf cluster after the call is the same, and the
    /// reports are equal. The case tests something: nodes bent.
    #[test]
    fn merged_level_grids_adapt_the_trees_of_fresh_grids_bit_for_bit() {
        use std::sync::atomic::Ordering;
        let trees: Vec<PlasticTree> = (0..4).map(|i| beech_at(20 + i, 1.5 * i as f32)).collect();
        let fixed = vec![beech_at(30, -1.5)];
        let env = Environment::open();
        let run = |threads: usize, fresh: bool| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            FORCED[Forced::FreshGrids as usize].store(fresh, Ordering::Relaxed);
            let mut trees = trees.clone();
            let rep = pool.install(|| adapt_group_among(&mut trees, &fixed, &env)).unwrap();
            FORCED[Forced::FreshGrids as usize].store(false, Ordering::Relaxed);
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            let mut eat = |v: u32| h = (h ^ v as u64).wrapping_mul(0x0000_0100_0000_01b3);
            for t in &trees {
                t.pos.iter().for_each(|v| v.to_array().iter().for_each(|x| eat(x.to_bits())));
                t.rot.iter().for_each(|q| q.to_array().iter().for_each(|x| eat(x.to_bits())));
                t.bend.iter().for_each(|b| eat(b.to_bits()));
                t.fate.iter().for_each(|f| eat(*f as u32));
                for (c, r) in t.clusters() {
                    c.to_array().iter().for_each(|x| eat(x.to_bits()));
                    eat(r.to_bits());
                }
            }
            (rep, h)
        };
        let (rep, h) = run(1, true);
        assert!(rep.trees.iter().any(|r| r.bent > 0), "{rep:?}");
        for threads in [1, 2] {
            let (rep_m, h_m) = run(threads, false);
            assert_eq!(rep, rep_m, "{threads} threads");
            assert_eq!(h, h_m, "checksum of the adapted trees, {threads} threads: merged grids {h_m:016x}, fresh {h:016x}");
        }
    }

    /// [`prune_parts`] against one pass over the nodes ([`Forced::SerialPrune`]), on one thread and on
    /// two: a 25-year beech beside a wall, adapted and then moved 10 cm under the move light
    /// model (both pass through eq. 11), and two beeches adapted together among a fixed third;
    /// every fate, position and bend angle equal bit for bit, and the reports equal. The cases
    /// test something: the trees are split into several parts, and nodes are shed by light.
    #[test]
    fn pruning_by_subtrees_is_the_serial_pass() {
        use std::sync::atomic::Ordering;
        let tree = beech_at;
        let wall = wall_at;
        let mut lone = tree(7, 0.0);
        lone.set_move_light(Some(crate::structure::plastic::MOVE_LIGHT_TOL_M)).unwrap();
        let (pair, fixed) = (vec![tree(8, 0.0), tree(9, -2.0)], vec![tree(10, -4.0)]);
        assert!(Pruning::of(&lone.input, &lone.analysis).parts.len() >= 4, "the tree is split into parts");
        type Bits = Vec<(Vec<[u32; 3]>, Vec<u32>, Vec<Fate>)>;
        let run = |threads: usize, serial: bool, trees: &[PlasticTree], fixed: &[PlasticTree], moves: bool| -> (Vec<GroupReport>, Bits) {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            FORCED[Forced::SerialPrune as usize].store(serial, Ordering::Relaxed);
            let mut trees = trees.to_vec();
            let mut reps = vec![pool.install(|| adapt_group_among(&mut trees, fixed, &wall(1.2))).unwrap()];
            if moves {
                reps.push(pool.install(|| adapt_group_among(&mut trees, fixed, &wall(1.3))).unwrap());
            }
            FORCED[Forced::SerialPrune as usize].store(false, Ordering::Relaxed);
            let bits = trees.iter().map(|t| (t.pos.iter().map(|v| v.to_array().map(f32::to_bits)).collect(), t.bend.iter().map(|b| b.to_bits()).collect(), t.fate.clone())).collect();
            (reps, bits)
        };
        for (trees, fixed, moves) in [(vec![lone], &[][..], true), (pair, &fixed[..], false)] {
            let (rep, bits) = run(1, true, &trees, fixed, moves);
            assert!(rep.iter().all(|r| r.trees.iter().map(|t| t.pruned_light).sum::<usize>() > 0), "{rep:?}");
            if moves {
                assert!(rep[1].recomputed_nodes > 0 && rep[1].recomputed_nodes < trees[0].input.nodes.len(), "{rep:?}");
            }
            for threads in [1, 2] {
                let (rep_p, bits_p) = run(threads, false, &trees, fixed, moves);
                assert_eq!(rep, rep_p, "{threads} threads");
                assert!(bits == bits_p, "the subtrees and the serial pass differ ({} trees, {threads} threads)", trees.len());
            }
        }
    }

    /// A clone of a tree adapted under the move light model shares its input skeleton, its
    /// analysis and every block of stored rows; adapting the clone after a 10 cm wall move
    /// copies only the blocks it writes (fewer than half), leaves the original's rows as they
    /// were bit for bit, and gives the tree that the original gives after the same move.
    #[test]
    fn a_moved_clone_copies_only_the_rows_it_writes() {
        use std::sync::Arc;
        let mut a = beech_at(7, 0.0);
        a.set_move_light(Some(crate::structure::plastic::MOVE_LIGHT_TOL_M)).unwrap();
        let wall = wall_at;
        a.adapt(&wall(1.2)).unwrap();
        let blocks = |t: &PlasticTree| -> Vec<Arc<RowBlock>> {
            let mc = t.move_light.as_ref().unwrap();
            mc.nodes.blocks.iter().chain(mc.stages.iter().flat_map(|s| s.rows.blocks.iter())).cloned().collect()
        };
        let bits = |t: &PlasticTree| -> Vec<u32> { blocks(t).iter().flat_map(|b| b.row.iter().map(|v| v.to_bits()).chain(b.at.iter().flat_map(|p| p.to_array().map(f32::to_bits))).chain(b.epoch).collect::<Vec<_>>()).collect() };
        let rows_before = bits(&a);
        let mut b = a.clone();
        assert!(Arc::ptr_eq(&a.input, &b.input) && Arc::ptr_eq(&a.analysis, &b.analysis));
        let (of_a, of_b) = (blocks(&a), blocks(&b));
        assert!(of_a.len() == of_b.len() && of_a.iter().zip(&of_b).all(|(x, y)| Arc::ptr_eq(x, y)), "a clone shares every block");
        let rep = b.adapt(&wall(1.3)).unwrap();
        assert!(rep.recomputed_nodes > 0, "{rep:?}");
        let (of_a, of_b) = (blocks(&a), blocks(&b));
        assert_eq!(of_a.len(), of_b.len());
        let copied = of_a.iter().zip(&of_b).filter(|(x, y)| !Arc::ptr_eq(x, y)).count();
        assert!(copied > 0 && 2 * copied < of_a.len(), "{copied} of {} blocks copied", of_a.len());
        assert!(bits(&a) == rows_before, "the original's rows are as they were");
        a.adapt(&wall(1.3)).unwrap();
        let same = a.pos.iter().zip(&b.pos).all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits));
        assert!(same && a.fate == b.fate && a.bend.iter().zip(&b.bend).all(|(x, y)| x.to_bits() == y.to_bits()), "the original moved as its clone");
    }

    /// [`CasterSet::factors`] (the sky-cone test, then the direction test) against every caster
    /// tested in every direction with no cone ([`hit_dirs`] alone, the same order), bit for bit,
    /// at points inside, below and beside a cloud of casters of 0.1–1.5 m under three skies
    /// (brightest point at the zenith, 43° high, 20° high), for all directions and for a subset:
    /// the cone never drops a caster that a ray meets. The cases test something: the cone
    /// skips most casters, and many factors are not 1.
    #[test]
    fn the_sky_cone_drops_no_caster_a_ray_meets() {
        let cloud: Vec<Occluder> = (0..300)
            .map(|i| {
                let f = i as f32;
                let r = 0.1 + 1.4 * (f * 0.37).sin().abs();
                Occluder { center: Vec3::new((f * 0.71).sin() * 4.0, (f * 0.53).cos() * 4.0, 2.0 + (f * 0.29).sin().abs() * 8.0), radius: r, gamma: 0.3f32.powf(r) }
            })
            .collect();
        let set = CasterSet::of(&cloud);
        let (mut skipped, mut tested, mut shaded) = (0usize, 0usize, 0usize);
        for sky in [crate::structure::plastic::Sky::default(), crate::structure::plastic::Sky::from_latitude(47.0), crate::structure::plastic::Sky::from_latitude(70.0)] {
            let all = sky_bits(&sky);
            let lanes = DirLanes::new(&sky.dirs, sky.brightest, all);
            for j in 0..400 {
                let f = j as f32;
                let p = Vec3::new((f * 0.43).cos() * 6.0, (f * 0.61).sin() * 6.0, (f * 0.17).sin().abs() * 11.0);
                for want in [all, all & 0x00f0_f0f0] {
                    let mut brute: Option<[f32; 32]> = None;
                    for o in &cloud {
                        let mut h = hit_dirs(&lanes, o, p, want);
                        while h != 0 {
                            let k = h.trailing_zeros() as usize;
                            h &= h - 1;
                            brute.get_or_insert([1.0; 32])[k] *= o.gamma;
                        }
                    }
                    let got = set.factors(&lanes, p, want);
                    assert_eq!(got.map(|f| f.map(f32::to_bits)), brute.map(|f| f.map(f32::to_bits)), "point {p}, sky toward {}", sky.brightest);
                    shaded += got.map_or(0, |f| f.iter().filter(|&&x| x < 1.0).count());
                }
                for o in &cloud {
                    let v = o.center - p;
                    let (cos_a, sin_a) = lanes.cone;
                    let lhs = v.dot(lanes.axis) + o.radius * sin_a;
                    tested += 1;
                    skipped += (lhs < 0.0 || lhs * lhs < cos_a * cos_a * (v.length_squared() - o.radius * o.radius)) as usize;
                }
            }
        }
        assert!(skipped * 3 > tested && shaded > 10_000, "skipped {skipped} of {tested}; shaded rays {shaded}");
    }

    /// [`through_both`] against the plain product of the two transmittances, bit for bit, at
    /// points inside and below two dense clouds of clusters (a level's and the fixed trees'),
    /// where rays are dark through either cloud, through both, or lit: the skipped query of a
    /// ray the level's casters darken changes no value.
    #[test]
    fn a_ray_dark_through_the_level_skips_the_fixed_trees_and_keeps_the_product() {
        let sky = crate::structure::plastic::Sky::from_latitude(47.0);
        let cloud = |n: usize, x0: f32, g: f32| -> Vec<Occluder> {
            (0..n)
                .map(|i| {
                    let f = i as f32;
                    let r = 0.3 + 0.5 * (f * 0.37).sin().abs();
                    Occluder { center: Vec3::new(x0 + (f * 0.71).sin() * 3.0, (f * 0.53).cos() * 3.0, 4.0 + (f * 0.29).sin().abs() * 6.0), radius: r, gamma: g.powf(r) }
                })
                .collect()
        };
        let vols = ShadowVolumes::new(&sky, cloud(400, 0.0, 0.3));
        let fixed = ShadowVolumes::new(&sky, cloud(300, 2.5, 0.2));
        let (mut dark_level, mut dark_fixed_only, mut lit) = (0, 0, 0);
        for j in 0..300 {
            let f = j as f32;
            let p = Vec3::new((f * 0.43).cos() * 5.0, (f * 0.61).sin() * 4.0, 1.0 + (f * 0.17).sin().abs() * 8.0);
            for k in 0..sky.dirs.len() {
                let (a, b) = (vols.transmittance(k, p), fixed.transmittance(k, p));
                assert_eq!(through_both(&vols, Some(&fixed), k, p).to_bits(), (a * b).to_bits(), "point {p}, direction {k}");
                assert_eq!(through_both(&vols, None, k, p).to_bits(), a.to_bits());
                dark_level += (a == 0.0 && b > 0.0) as usize;
                dark_fixed_only += (a > 0.0 && b == 0.0) as usize;
                lit += (a * b > 0.0 && a * b < 1.0) as usize;
            }
        }
        // the cases test something: rays dark through the level's casters only (the skip),
        // through the fixed trees' only, and rays partly lit through both
        assert!(dark_level > 100 && dark_fixed_only > 100 && lit > 500, "{dark_level} {dark_fixed_only} {lit}");
    }
    use crate::species::SpeciesLibrary;
    use crate::structure::grow::space::Obstacle;
    use crate::structure::species_tree::{grow_species_tree, Model};

    /// Three 25-year beeches, the second and third 2 m apart (they shade each other and shed
    /// by light) 20 m from the first, and a wall moved beside the first only: from the third
    /// call on, the second and third trees have nothing to recompute and replay the levels
    /// recorded in the second call ([`QuietLevels`]). Their fates (light pruning included) and
    /// positions, and the first tree's, are bit for bit those of the same calls evaluated level
    /// by level (every record forgotten before each call).
    #[test]
    fn quiet_levels_replay_what_the_levels_give() {
        let lib = SpeciesLibrary::embedded().unwrap();
        let sp = &lib.species[lib.find("beech").unwrap() as usize];
        let p = sp.architecture.plastic;
        let trees: Vec<PlasticTree> = [(7u64, 0.0f32), (8, 20.0), (9, 22.0)]
            .iter()
            .map(|&(seed, x)| {
                let g = grow_species_tree(sp, Model::Light, 25.0, &[], seed).unwrap();
                let mut t = PlasticTree::analyse(&g.skeleton, &p, &Environment::open(), None).unwrap();
                t.translate(Vec3::new(x, 0.0, 0.0));
                t
            })
            .collect();
        let wall = |x: f32| Environment::with_obstacles(&[Obstacle::OrientedBox { center: Vec3::new(x, 0.0, 3.0), half: Vec3::new(0.1, 4.0, 3.0), yaw_deg: 0.0 }]);
        let (mut replayed, mut evaluated) = (trees.clone(), trees);
        let mut replays = 0;
        for step in 0..4 {
            let env = wall(1.2 + 0.1 * step as f32);
            for t in &mut evaluated {
                t.quiet = None;
            }
            let quiet_before = replayed[1].quiet.is_some();
            let a = adapt_group(&mut replayed, &env).unwrap();
            let b = adapt_group(&mut evaluated, &env).unwrap();
            if step > 0 {
                assert!(a.trees[0].recomputed_nodes > 0, "the wall moved beside the first tree");
            }
            if step >= 1 {
                for k in 1..3 {
                    assert_eq!(a.trees[k].recomputed_nodes, 0, "the far trees have nothing to recompute");
                    assert!(replayed[k].quiet.is_some(), "a quiet call records or keeps its levels");
                }
            }
            replays += quiet_before as usize;
            assert!(a.trees[1].pruned_light + a.trees[2].pruned_light > 0, "the far trees shed by light, so their fates must be replayed");
            assert_eq!(a.trees, b.trees);
            for (r, e) in replayed.iter().zip(&evaluated) {
                assert_eq!(r.fate, e.fate);
                assert!(r.pos.iter().zip(&e.pos).all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)));
            }
        }
        assert_eq!(replays, 2, "calls 3 and 4 replay the far trees' levels");
    }
}
