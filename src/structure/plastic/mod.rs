//! Plastic Trees (Pirk, Stava, Kratt, Massih Said, Neubert, Měch, Benes & Deussen 2012,
//! `000_*.txt`): a grown skeleton is analysed once (section 4, [`analysis`]) and then bent and
//! pruned, level by level of branch age, whenever its light, obstacles or neighbouring trees
//! change (sections 5–6, [`transform`]), instead of being regrown.
//!
//! - [`light`]: eq. (3) with the sky intensity I = cos²(Δσ) and the sin θ weight, leaf-cluster
//!   translucency (eq. 4), obstacles, the terrain, shadow volumes.
//! - [`analysis`]: internode length by mean-shift, growth rate (eq. 1), season of every node
//!   (eq. 2), terminal lobes and their younger versions (eq. 5), the temporal light of the
//!   tree's life, inverse tropism (eqs. 6–9), pruning thresholds (eqs. 10–11).
//! - [`transform`]: bending by eq. (6) with the new light, rotations propagated to children,
//!   flexibility by age, pruning after every level, clusters moved and thinned (eqs. 12–13),
//!   obstacles cutting lobes (Fig. 4), tree–obstacle and tree–tree interaction, and incremental
//!   recomputation of only the subtrees whose light or obstacles changed.
//!
//! - [`evaluation`]: section 7, Table 1 (sets O, G, T; edit distances; t-tests).
//!
//! Use: [`PlasticTree::analyse`] each tree once (in the environment it grew in, alone), fit
//! it to a tree's size ([`PlasticTree::scale`], uniform about the root) and place it
//! ([`PlasticTree::translate`]), then call [`adapt_group`] with the trees that share a
//! neighbourhood and the [`Environment`] whenever something changes; [`PlasticTree::skeleton`]
//! gives the adapted skeleton. [`adapt`] does all of it for one tree.

pub mod analysis;
pub mod evaluation;
pub mod light;
pub mod transform;

pub use analysis::{inverse_tropism, Analysis};
pub use light::{Ground, Sky};
pub use transform::{adapt_group, adapt_group_among, adapt_group_among_once, cluster_density, GroupReport, MOVE_DELTA_MAX, MOVE_GAMMA_TOL, MOVE_PATCH_BUDGET};

/// Tolerance (m) of the move light model that the bench and the tests use
/// ([`PlasticTree::set_move_light`]): half the 10 cm step of issue 31's wall move. An ESTIMATE,
/// chosen before measuring; its errors against the exact moves are in BENCHMARKS.md, round 37.
pub const MOVE_LIGHT_TOL_M: f32 = 0.05;

use crate::error::{Error, Result};
use crate::species::PlasticParams;
use crate::structure::grow::space::{validate_obstacles, Obstacle};
use crate::structure::skeleton::Skeleton;
use glam::{Quat, Vec3};
use light::Occluder;
use std::sync::Arc;

/// Tropism direction t of eq. (6) for phototropism towards the light direction `light` and
/// gravitropism (negative geotropism, +z): (w_p·L + w_g·ẑ)/(w_p + w_g), normalised; +z when
/// both weights are 0.
pub fn tropism(p: &PlasticParams, light: Vec3) -> Vec3 {
    let (wp, wg) = (p.phototropism, p.gravitropism);
    if wp + wg <= 0.0 {
        return Vec3::Z;
    }
    ((wp * light + wg * Vec3::Z) / (wp + wg)).normalize_or(Vec3::Z)
}

/// What a tree adapts to: solid obstacles (boxes, finite or infinite walls, spheres, boxes
/// turned about the vertical — angled walls — and vertical prisms over a footprint polygon —
/// buildings), the terrain surface and the sky (global light, section 6).
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Solid obstacles (m, world coordinates).
    pub obstacles: Vec<Obstacle>,
    /// Terrain surface; `None`: no ground (nothing below is pruned).
    pub ground: Option<Ground>,
    /// The sky.
    pub sky: Sky,
}

impl Default for Environment {
    fn default() -> Self {
        Environment::open()
    }
}

impl Environment {
    /// Open space: flat ground at z = 0, the brightest sky point at the zenith, no obstacles.
    pub fn open() -> Environment {
        Environment { obstacles: Vec::new(), ground: Some(Ground::flat(0.0)), sky: Sky::default() }
    }

    /// Open space with `obstacles`.
    pub fn with_obstacles(obstacles: &[Obstacle]) -> Environment {
        Environment { obstacles: obstacles.to_vec(), ..Environment::open() }
    }

    /// Global light (section 6): the sky of [`Sky::from_latitude`] and a terrain slope of
    /// `slope_deg` (0–89°) through `point` falling towards `aspect_deg` (clockwise from
    /// north, +y).
    pub fn global(latitude_deg: f32, slope_deg: f32, aspect_deg: f32, point: Vec3, obstacles: &[Obstacle]) -> Environment {
        Environment { obstacles: obstacles.to_vec(), ground: Some(Ground::slope(point, slope_deg, aspect_deg)), sky: Sky::from_latitude(latitude_deg) }
    }

    /// Checks the obstacles ([`validate_obstacles`]) and the ground.
    ///
    /// Errors: [`Error::Invalid`] naming the bad obstacle or ground field.
    pub fn validate(&self) -> Result<()> {
        validate_obstacles(&self.obstacles)?;
        if let Some(g) = self.ground {
            if !g.point.is_finite() || !g.normal.is_finite() || g.normal.z <= 0.0 {
                return Err(Error::Invalid { context: "Plastic Trees environment".into(), field: "ground".into(), value: format!("point {}, normal {}", g.point, g.normal), expected: "finite values and an upward normal (z > 0)".into() });
            }
        }
        Ok(())
    }
}

/// Why a node of the input is missing from the adapted tree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fate {
    /// Present.
    Alive,
    /// Shed for lack of light (eq. 11), or below a shed node.
    Light,
    /// Removed because it (or its segment, or an ancestor) entered an obstacle, the ground or
    /// another tree's wood.
    Collision,
}

/// What an adaptation did to one tree.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlasticReport {
    /// Segments whose own direction turned by more than 1° relative to their parent's
    /// rotation (segments that only follow a bent parent are not counted).
    pub bent: usize,
    /// Nodes shed for lack of light (eq. 11), subtrees included.
    pub pruned_light: usize,
    /// Nodes removed by collisions (obstacles, ground, other trees' wood), subtrees included.
    pub pruned_collision: usize,
    /// Nodes of the input skeleton.
    pub nodes_before: usize,
    /// Nodes of the adapted skeleton.
    pub nodes_after: usize,
    /// Nodes whose bending was recomputed by this call (the subtrees whose light or obstacles
    /// changed since the previous call).
    pub recomputed_nodes: usize,
}

/// A leaf cluster of the adapted tree ([`PlasticTree::leaf_clusters`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeafCluster {
    /// Index of its terminal lobe in [`Analysis::lobes`].
    pub lobe: u32,
    /// Centre (m): the lobe's centroid moved by the mean offset of its nodes (section 5.2).
    pub center: Vec3,
    /// Radius (m), cut by obstacles (Fig. 4); 0 when deleted.
    pub radius: f32,
    /// Translucency γ_c (eq. 4, γ_c0^r_c, and eq. 13 after losing nodes), 0–1.
    pub gamma: f32,
    /// Nodes of the lobe in the input, n_0 of eq. (13).
    pub input_nodes: usize,
    /// Nodes of the lobe still alive, n_c of eq. (13).
    pub alive_nodes: usize,
    /// Light i_l0 on the cluster in the environment analysed (eq. 3, 0–1).
    pub light_input: f32,
    /// Light i on the cluster now (eq. 3, 0–1), as the last adaptation's final level computed it.
    pub light: f32,
    /// Leaf density ρ_l of eq. (12) relative to the input (ρ_l0 = 1, ρ(i) = i): i/i_l0; 0 for a
    /// deleted cluster.
    pub density: f32,
}

/// One tree ready for adaptation: its input skeleton, the analysis of section 4 and its
/// current adapted state.
///
/// A clone shares the input skeleton and the analysis, which no adaptation changes (behind
/// [`Arc`], copied on write by [`PlasticTree::translate`] and [`PlasticTree::scale`]), and the
/// move light model's stored rows and snapshots (copied on write block by block: see
/// `MoveCache` in `transform.rs`), so cloning an adapted tree copies only its adapted state
/// (positions, rotations, bend angles, fates, signatures, stage light).
#[derive(Debug, Clone)]
pub struct PlasticTree {
    pub(crate) input: Arc<Skeleton>,
    pub(crate) params: PlasticParams,
    pub(crate) analysis: Arc<Analysis>,
    /// Smallest distance (m) every node keeps from obstacles (e.g. the leaf length, so leaf
    /// cards stay outside).
    pub clearance_m: f32,
    /// Segments of this radius (m) or thicker are solid wood for other trees.
    pub wood_radius_m: f32,
    /// Side (m, ≥ 0; 0: off, every node its own query, the default) of the cubes, in the
    /// tree's world coordinates, within which the nodes bent at one level of an adaptation
    /// (one season and depth batch, [`transform`] step 3) that see the same solids share one
    /// light query (eq. 3): the node first in index order is queried and the others take its
    /// average light direction L' for eq. (6). Not exact (our approximation, not the paper's:
    /// round 40 measures what it changes in the stand bench, BENCHMARKS.md); for stands
    /// ([`crate::structure::stand::StandOptions::bend_light_cell_m`]).
    pub bend_light_cell_m: f32,
    /// Side (m, ≥ 0; 0: off, the default) of the cubes within which the full-grown stage's leaf
    /// clusters of a tree that eq. (11) cannot shed (every ψ_min 0, e.g. a stand's forest-grown
    /// tree) share one light query at the last level: the cluster first in stage order is
    /// queried and the others of its cube that see the same solids take its light i (eq. 3),
    /// which then sets their leaf density (eq. 12). Such a tree's cluster light feeds no
    /// pruning and no bending, so only [`PlasticTree::leaf_clusters`]' light and density
    /// change. Not exact (round 40, BENCHMARKS.md); for stands
    /// ([`crate::structure::stand::StandOptions::leaf_light_cell_m`]).
    pub leaf_light_cell_m: f32,
    /// With [`PlasticTree::bend_light_cell_m`] > 0: the nodes bent at one level share the light
    /// of the first node of their cube (with the same solids) over the whole level, each depth
    /// batch taking the light of the cubes an earlier batch of the level queried, where without
    /// it only the nodes of one depth batch share. The level's casters stand still while it bends, so a cube's light is
    /// the same field either way. Not exact (our approximation, as the cubes are); default
    /// false; for stands ([`crate::structure::stand::StandOptions::bend_light_whole_level`];
    /// BENCHMARKS.md round 42).
    pub bend_light_whole_level: bool,
    pub(crate) pos: Vec<Vec3>,
    pub(crate) rot: Vec<Quat>,
    pub(crate) bend: Vec<f32>,
    pub(crate) fate: Vec<Fate>,
    pub(crate) light_cache: Vec<Vec<f32>>,
    pub(crate) sig: Vec<u64>,
    /// Key of the neighbours and fixed trees whose shade the high half of `sig` holds (0: none
    /// yet): the shade of the other trees' input-time clusters does not change while they
    /// and the sky stay as they are, so a call that only moves an obstacle reuses it.
    pub(crate) shade_key: u64,
    pub(crate) sky: Sky,
    /// Occluders of the full-grown stage's clusters after the last adaptation (empty before).
    pub(crate) final_occ: Vec<Option<Occluder>>,
    pub(crate) force: bool,
    pub(crate) report: PlasticReport,
    /// The levels of the last call in which no node of this tree was recomputed (none of its
    /// signatures changed), recorded so that the next such call replays them instead of
    /// re-evaluating the pruning of every node at every level (see
    /// [`transform::QuietLevels`]); cleared by any call with work and by every change of the
    /// tree's state outside a call.
    pub(crate) quiet: Option<Box<transform::QuietLevels>>,
    /// True for a tree made by [`PlasticTree::standing`] (shape only, no light): it can stand
    /// among adapted trees but cannot be adapted.
    pub(crate) standing: bool,
    /// The move light model and its stored transmittances ([`PlasticTree::set_move_light`]);
    /// `None`: every call exact.
    pub(crate) move_light: Option<Box<transform::MoveCache>>,
    /// The node whose segment is a forest-grown tree's lengthened bole ([`PlasticTree::set_bole`]),
    /// bent with the flexibility of its base's age; `None` for every other tree.
    pub(crate) bole: Option<u32>,
}

impl PlasticTree {
    /// Analyses `sk` (section 4) as grown in `grown_in` (the obstacles it grew beside and its
    /// sky, without neighbours), with the species' Plastic Trees parameters; `internode_m`
    /// overrides the mean-shift internode estimate. The adapted state starts as the input.
    ///
    /// Errors: see [`analysis::analyse`].
    pub fn analyse(sk: &Skeleton, params: &PlasticParams, grown_in: &Environment, internode_m: Option<f32>) -> Result<PlasticTree> {
        let analysis = analysis::analyse(sk, params, grown_in, internode_m)?;
        let sig = analysis.mask.iter().map(|&m| m as u64).collect();
        Ok(PlasticTree::with_analysis(sk, params, analysis, sig, false))
    }

    /// A tree of input `sk` with `analysis`, signatures `sig`, its adapted state the input.
    fn with_analysis(sk: &Skeleton, params: &PlasticParams, analysis: Analysis, sig: Vec<u64>, standing: bool) -> PlasticTree {
        let n = sk.nodes.len();
        PlasticTree {
            input: Arc::new(sk.clone()),
            params: *params,
            light_cache: analysis.stage_light.clone(),
            sig,
            shade_key: 0,
            sky: analysis.sky.clone(),
            final_occ: Vec::new(),
            analysis: Arc::new(analysis),
            clearance_m: 0.0,
            wood_radius_m: 0.02,
            bend_light_cell_m: 0.0,
            leaf_light_cell_m: 0.0,
            bend_light_whole_level: false,
            pos: sk.nodes.iter().map(|nd| nd.pos).collect(),
            rot: vec![Quat::IDENTITY; n],
            bend: vec![0.0; n],
            fate: vec![Fate::Alive; n],
            force: false,
            report: PlasticReport { nodes_before: n, nodes_after: n, ..Default::default() },
            quiet: None,
            standing,
            move_light: None,
            bole: None,
        }
    }

    /// A tree that only stands among adapted ones, unadapted (the `fixed` trees of
    /// [`adapt_group_among`]): its shade (its full-grown leaf clusters, grouped by foliage lobe)
    /// and its wood are those of [`PlasticTree::analyse`]'s tree, bit for bit, but its analysis
    /// holds no light ([`analysis::analyse_shape`]; `sky` is recorded as the analysis sky), so
    /// it costs a fraction of a full analysis. Adapting it (as one of the `trees` of
    /// [`adapt_group`] or [`adapt_group_among`]) is an error.
    ///
    /// Errors: see [`analysis::analyse_shape`].
    pub fn standing(sk: &Skeleton, params: &PlasticParams, sky: &Sky, internode_m: Option<f32>) -> Result<PlasticTree> {
        let analysis = analysis::analyse_shape(sk, params, sky, internode_m)?;
        Ok(PlasticTree::with_analysis(sk, params, analysis, Vec::new(), true))
    }

    /// True for a tree of [`PlasticTree::standing`], which can stand among adapted trees but
    /// not be adapted.
    pub fn is_standing(&self) -> bool {
        self.standing
    }

    /// Moves the tree (input, analysis and state) by `offset` (m). Obstacles of the
    /// environment it grew in are not moved; call before adapting it among others.
    pub fn translate(&mut self, offset: Vec3) {
        self.quiet = None;
        self.forget_move_light();
        for nd in &mut Arc::make_mut(&mut self.input).nodes {
            nd.pos += offset;
        }
        for p in &mut self.pos {
            *p += offset;
        }
        for l in &mut Arc::make_mut(&mut self.analysis).lobes {
            l.center += offset;
        }
    }

    /// Scales the tree uniformly by `factor` about its root (the base node): node positions
    /// relative to the root, branch radii, the internode length l_i, the lobes' centres and
    /// radii and every stage cluster's radius r_c, so the analysis stays the analysis of the
    /// scaled skeleton in every length. Ratios are unchanged (growth rates of eq. 1, seasons of
    /// eq. 2, w_s of eq. 7 since l_s/l_i is kept, the untropic directions of eqs. 8–9); the
    /// pruning thresholds ψ_s,min and ψ_ref of eq. (11) scale with `factor` (ψ = ζ/l of eq. 10 is
    /// a leaf area, ∝ r_c², per branch length). The translucency base γ_c0 of eq. (4) becomes
    /// γ_c0^(1/factor), so every cluster keeps its transmittance γ_c = γ_c0^r_c: every ray of
    /// eq. (3) meets the scaled clusters as it met the originals, and the light of the analysis
    /// (eq. 3: stage light, light directions) is the scaled tree's own, unchanged. The adapted
    /// state is reset to the scaled input and the next adaptation recomputes every node. Use it to fit one analysed prototype to trees of
    /// several heights without analysing each again.
    ///
    /// Errors: [`Error::Invalid`] (field `scale`) unless `factor` is finite and > 0.
    pub fn scale(&mut self, factor: f32) -> Result<()> {
        if !(factor > 0.0 && factor.is_finite()) {
            return Err(Error::Invalid { context: "PlasticTree::scale".into(), field: "scale".into(), value: factor.to_string(), expected: "a finite factor > 0".into() });
        }
        self.quiet = None;
        self.forget_move_light();
        let root = self.input.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO);
        let about = |p: Vec3| root + (p - root) * factor;
        for nd in &mut Arc::make_mut(&mut self.input).nodes {
            nd.pos = about(nd.pos);
            nd.radius *= factor;
        }
        let a = Arc::make_mut(&mut self.analysis);
        a.internode_m *= factor;
        for l in &mut a.lobes {
            l.center = about(l.center);
            l.radius *= factor;
        }
        for c in a.stages.iter_mut().flatten() {
            c.radius *= factor;
        }
        a.psi_ref *= factor;
        a.psi_min.iter_mut().for_each(|m| *m *= factor);
        self.params.translucency_gamma_c0 = self.params.translucency_gamma_c0.powf(1.0 / factor);
        let n = self.input.nodes.len();
        self.pos = self.input.nodes.iter().map(|nd| nd.pos).collect();
        self.rot = vec![Quat::IDENTITY; n];
        self.bend = vec![0.0; n];
        self.fate = vec![Fate::Alive; n];
        self.light_cache = self.analysis.stage_light.clone();
        self.final_occ.clear();
        self.force = true;
        self.report = PlasticReport { nodes_before: n, nodes_after: n, ..Default::default() };
        Ok(())
    }

    /// A copy of this tree scaled by `factor`: the tree a clone followed by
    /// [`PlasticTree::scale`] gives, field for field, without first copying the adapted state
    /// that scaling resets (positions, rotations, bend angles, fates, stage light, final
    /// occluders). A stand places every tree of a neighbourhood this way from its class's
    /// analysed tree ([`crate::structure::stand`]; perf, the near field of `benches/stand.rs`:
    /// the clones under `scale` and their drops were about 3.7 % of its time, BENCHMARKS.md
    /// round 43).
    ///
    /// Errors: as [`PlasticTree::scale`].
    pub fn scaled(&self, factor: f32) -> Result<PlasticTree> {
        let mut t = PlasticTree {
            input: self.input.clone(),
            params: self.params,
            analysis: self.analysis.clone(),
            clearance_m: self.clearance_m,
            wood_radius_m: self.wood_radius_m,
            bend_light_cell_m: self.bend_light_cell_m,
            leaf_light_cell_m: self.leaf_light_cell_m,
            bend_light_whole_level: self.bend_light_whole_level,
            pos: Vec::new(),
            rot: Vec::new(),
            bend: Vec::new(),
            fate: Vec::new(),
            light_cache: Vec::new(),
            sig: self.sig.clone(),
            shade_key: self.shade_key,
            sky: self.sky.clone(),
            final_occ: Vec::new(),
            force: self.force,
            report: self.report,
            quiet: None,
            standing: self.standing,
            move_light: self.move_light.clone(),
            bole: self.bole,
        };
        t.scale(factor)?;
        Ok(t)
    }

    /// [`PlasticTree::scaled`] for a tree analysed on open ground, as
    /// [`PlasticTree::scale_grown_on_open_ground`] scales it (the caller vouches for the
    /// environment of the analysis).
    ///
    /// Errors: as [`PlasticTree::scale`].
    pub fn scaled_grown_on_open_ground(&self, factor: f32) -> Result<PlasticTree> {
        let mut t = self.scaled(factor)?;
        t.force = false;
        Ok(t)
    }

    /// [`PlasticTree::scale`] for a tree analysed on a ground plane through its root and
    /// without obstacles (as [`crate::structure::stand`] analyses its classes): the sky
    /// directions blocked at a node are then those of the side of the plane it stands on
    /// ([`Ground::blocks`]), which scaling about the root keeps, so every node keeps its
    /// signature and the next adaptation recomputes, as for the tree analysed at that size,
    /// only the nodes whose light changed (`scale` recomputes every node: with obstacles a
    /// scaled node can move into or out of their shadow). The caller vouches for the
    /// environment of the analysis.
    ///
    /// Errors: as [`PlasticTree::scale`].
    pub fn scale_grown_on_open_ground(&mut self, factor: f32) -> Result<()> {
        self.scale(factor)?;
        self.force = false;
        Ok(())
    }

    /// The analysis (section 4).
    pub fn analysis(&self) -> &Analysis {
        &self.analysis
    }

    /// The Plastic Trees parameters in use (γ_c0 as changed by [`PlasticTree::scale`]).
    pub fn params(&self) -> &PlasticParams {
        &self.params
    }

    /// The input skeleton (as analysed, translated, scaled).
    pub fn input(&self) -> &Skeleton {
        &self.input
    }

    /// Fate of every input node after the last adaptation.
    pub fn fates(&self) -> &[Fate] {
        &self.fate
    }

    /// Current positions of every input node (m; pruned nodes keep their last computed place).
    pub fn positions(&self) -> &[Vec3] {
        &self.pos
    }

    /// Own bend angle of every input node (radians; 0 for the root).
    pub fn bend_angles(&self) -> &[f32] {
        &self.bend
    }

    /// Report of the last adaptation.
    pub fn report(&self) -> PlasticReport {
        self.report
    }

    /// Marks the segment from node `node`'s parent to `node` as a forest-grown tree's bole, or
    /// clears the mark (`None`, the default of every tree). Section 5.1 of the paper transforms
    /// "individual branch segments according to their estimated age": the bending of eq. (6)
    /// moves the tropism a segment grew with, t, towards the tropism of its new light by the
    /// flexibility κ = 1 − a/(T + 1) (transform step 3), a the segment's age. For every segment a
    /// is taken at its tip, a = T − t_s (t_s its season of eq. 2). The marked segment takes it
    /// at its base, a = T − t_{s_p} (t_{s_p} its parent's season of eq. 2): it stands for many
    /// internodes of different ages, and it turns about its base, the oldest wood of the stem.
    /// The forest form of [`crate::structure::stand`] lengthens the open-grown tree's first
    /// segment to the simulated crown base (43–108 internodes of the tree's own l_i, round 35):
    /// its eq. (7) weight w_s = (1 − w_p − w_g)^(l_s/l_i) is about 0, so eq. (6) sets its direction by
    /// t' alone, and with its tip's season (0.37–0.71 T) it bent like crown wood: boles leaning
    /// 2.0° median and up to 11.8° among neighbours (BENCHMARKS.md, rounds 35 and 36). A tree
    /// without a mark (lone trees, Plastic Trees' own set-ups) is bent as before, bit for bit.
    /// When the mark changes the next adaptation recomputes every node.
    ///
    /// Errors: [`Error::Invalid`] (field `bole`) when `node` is the root (0) or not a node of
    /// the input skeleton.
    pub fn set_bole(&mut self, node: Option<u32>) -> Result<()> {
        if let Some(k) = node {
            if k == 0 || k as usize >= self.input.nodes.len() {
                return Err(Error::Invalid { context: "PlasticTree::set_bole".into(), field: "bole".into(), value: k.to_string(), expected: format!("a node 1..{} of the input skeleton (not the root)", self.input.nodes.len().saturating_sub(1)) });
            }
        }
        if node != self.bole {
            self.bole = node;
            self.invalidate();
        }
        Ok(())
    }

    /// The node whose segment is marked as a forest-grown tree's bole ([`PlasticTree::set_bole`]).
    pub fn bole(&self) -> Option<u32> {
        self.bole
    }

    /// Makes the next adaptation recompute every node (not only the changed subtrees).
    pub fn invalidate(&mut self) {
        self.quiet = None;
        self.forget_move_light();
        self.force = true;
    }

    /// Forgets the move light model's stored rows (keeps the model on).
    fn forget_move_light(&mut self) {
        if let Some(mc) = self.move_light.as_mut() {
            mc.clear();
        }
    }

    /// Turns the move light model on with receiver and caster tolerance `tol_m` (m), or off
    /// (`None`, the default: every call exact). With the model on, each call of a tree adapted
    /// alone (a group of one, no fixed trees) stores, per light query of eq. (3) (a node's
    /// bending light, a stage cluster's light), the transmittance of every sky direction above
    /// the terrain through the level's leaf-cluster casters; a later call reuses a stored row when
    /// the query point is within `tol_m` of where it was taken, applying to it, ray by ray, the
    /// casters that changed by more than `tol_m` (centre plus radius) or
    /// [`transform::MOVE_GAMMA_TOL`] (transmittance) since the level's snapshot; the solids
    /// (the obstacles, the terrain) are tested anew at every query (see `MoveCache` in
    /// `transform.rs`). So a wall moved by a small step builds shadow grids only at the levels
    /// where many query points moved farther, or more than [`MOVE_DELTA_MAX`] (or half the
    /// casters) changed, or the changes applied since the level's snapshot pass
    /// [`MOVE_PATCH_BUDGET`], and the
    /// results differ from an exact call by what moves within the tolerances (measured in
    /// BENCHMARKS.md, rounds 37, 38 and 40, and bounded by the test
    /// `structure_plastic::the_move_light_model_stays_near_the_exact_moves`). The first call
    /// after turning it on, after [`PlasticTree::invalidate`], [`PlasticTree::scale`],
    /// [`PlasticTree::translate`], a change of the sky, and every call in a group or among fixed
    /// trees are exact (the first fills the rows: the same tree bit for bit, at the cost of the
    /// directions the solids block). Our model, not the paper's (Pirk et al. 2012 recompute
    /// "only when required").
    ///
    /// Errors: [`Error::Invalid`] (field `move_light`) unless `tol_m` is finite and ≥ 0.
    pub fn set_move_light(&mut self, tol_m: Option<f32>) -> Result<()> {
        match tol_m {
            Some(t) if !(t.is_finite() && t >= 0.0) => Err(Error::Invalid { context: "PlasticTree::set_move_light".into(), field: "move_light".into(), value: t.to_string(), expected: "a finite tolerance ≥ 0 m".into() }),
            Some(t) => {
                self.move_light = Some(Box::new(transform::MoveCache::new(t)));
                Ok(())
            }
            None => {
                self.move_light = None;
                Ok(())
            }
        }
    }

    /// The move light model's tolerance (m), `None` when every call is exact
    /// ([`PlasticTree::set_move_light`]).
    pub fn move_light(&self) -> Option<f32> {
        self.move_light.as_ref().map(|m| m.tol_m)
    }

    /// Current leaf clusters of the full-grown stage: (centre (m), radius (m)) of every lobe
    /// with a living node, moved with its nodes (section 5.2).
    pub fn clusters(&self) -> Vec<(Vec3, f32)> {
        self.analysis
            .lobes
            .iter()
            .filter(|l| l.nodes.iter().any(|&k| self.fate[k as usize] == Fate::Alive))
            .map(|l| {
                let off = l.nodes.iter().map(|&k| self.pos[k as usize] - self.input.nodes[k as usize].pos).sum::<Vec3>() / l.nodes.len() as f32;
                (l.center + off, l.radius)
            })
            .collect()
    }

    /// The leaf clusters of the full-grown tree after the last adaptation (section 5.2), one per
    /// terminal lobe, in the order of [`Analysis::stages`]`[T]`: centre moved with its nodes,
    /// radius cut by obstacles (Fig. 4), translucency by eqs. (4) and (13), light i (eq. 3) now
    /// and in the analysis, and the leaf density of eq. (12) relative to the input (ρ_l0 = 1,
    /// ρ(i) = i). Deleted clusters (no living node, or the centre inside an obstacle) have
    /// `alive_nodes` 0 or radius 0 and density 0. Before any adaptation: the input clusters, density 1.
    pub fn leaf_clusters(&self) -> Vec<LeafCluster> {
        let a = &self.analysis;
        let last = a.seasons as usize;
        a.stages[last]
            .iter()
            .enumerate()
            .map(|(ci, c)| {
                let lobe = c.lobe.unwrap_or(0);
                let nodes = a.lobes.get(lobe as usize).map(|l| l.nodes.as_slice()).unwrap_or(&[]);
                let alive = nodes.iter().filter(|&&k| self.fate[k as usize] == Fate::Alive).count();
                let centre = analysis::cluster_center(c, &a.lobes, &self.input, &self.pos);
                let i0 = a.stage_light[last][ci];
                let (radius, gamma, light) = match self.final_occ.get(ci) {
                    Some(Some(o)) => (o.radius, o.gamma, self.light_cache[last][ci]),
                    Some(None) => (0.0, 1.0, 0.0),
                    None => (c.radius, self.params.translucency_gamma_c0.powf(c.radius), i0),
                };
                let density = if alive == 0 || radius <= 0.0 { 0.0 } else { cluster_density(1.0, i0, light) };
                LeafCluster { lobe, center: centre, radius, gamma, input_nodes: nodes.len(), alive_nodes: alive, light_input: i0, light, density }
            })
            .collect()
    }

    /// Leaf density of eq. (12) (relative to the input, see [`PlasticTree::leaf_clusters`]) of
    /// every node of [`PlasticTree::skeleton`] (same order): the density of the lobe the node
    /// belongs to, 1 for nodes in no lobe (older wood keeps what it had).
    pub fn leaf_density(&self) -> Vec<f32> {
        let mut by_node = vec![1.0f32; self.input.nodes.len()];
        for c in self.leaf_clusters() {
            if let Some(l) = self.analysis.lobes.get(c.lobe as usize) {
                for &k in &l.nodes {
                    by_node[k as usize] = c.density;
                }
            }
        }
        by_node.iter().zip(&self.fate).filter(|(_, f)| **f == Fate::Alive).map(|(d, _)| *d).collect()
    }

    /// The adapted skeleton: input radii and topology with the current positions, pruned
    /// subtrees removed and tips re-marked (the input itself, bit for bit, when nothing moved
    /// or was pruned).
    pub fn skeleton(&self) -> Skeleton {
        let mut out = Skeleton::clone(&self.input);
        for (nd, &p) in out.nodes.iter_mut().zip(&self.pos) {
            nd.pos = p;
        }
        let remove: Vec<bool> = self.fate.iter().map(|f| *f != Fate::Alive).collect();
        if remove.iter().any(|&r| r) {
            out.prune(&remove);
            out.mark_tips();
        }
        out
    }

    /// Adapts this tree alone to `env` ([`adapt_group`] with one tree).
    ///
    /// Errors: see [`adapt_group`].
    pub fn adapt(&mut self, env: &Environment) -> Result<PlasticReport> {
        let g = adapt_group(std::slice::from_mut(self), env)?;
        Ok(g.trees[0])
    }
}

/// Adapts `sk`, grown in the open, to `obstacles` with the species' Plastic Trees parameters;
/// `internode_m` (> 0 m) is the internode length l_i of eq. (7) (instead of the mean-shift
/// estimate). Returns the adapted skeleton and the report; with no obstacles the tree is
/// returned unchanged. For a tree grown beside obstacles, or several trees, use
/// [`PlasticTree`] and [`adapt_group`].
///
/// Errors: [`Error::Invalid`] for an invalid obstacle or skeleton, `internode_m` ≤ 0, tropism
/// weights outside 0 ≤ w_p, w_g with w_p + w_g < 1, γ_c0 outside 0–1, or c_ψ < 0.
pub fn adapt(sk: &Skeleton, p: &PlasticParams, obstacles: &[Obstacle], internode_m: f32) -> Result<(Skeleton, PlasticReport)> {
    validate_obstacles(obstacles)?;
    let mut t = PlasticTree::analyse(sk, p, &Environment::open(), Some(internode_m))?;
    let rep = t.adapt(&Environment::with_obstacles(obstacles))?;
    Ok((t.skeleton(), rep))
}
