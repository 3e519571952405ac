//! Light-guided self-organising growth (Yi, Li, Guo & Zhang, `001_*.txt`, section 3), after
//! Palubicki et al. 2009.
//!
//! Each iteration (one growth cycle, a year):
//! 1. **Light space**: voxels of half an internode. Every voxel starts at its sky openness (the
//!    fraction of 25 sky directions not blocked by obstacles: steep ones at any distance, low
//!    ones within [`SKY_RANGE_M`]; an addition so that walls and boxes shade from the side, the paper has
//!    only vertical shadows), less the shadow l_n = l_o − b^(−(q−1)) of obstacle
//!    voxels (fully occupied), times the crown envelope's light factor when one is given
//!    ([`LightOptions::envelope`]); every node then lowers the voxels beneath it by
//!    l_n = l_o − b^(−q), q = vertical voxel distance (q ≥ 1), over a pyramid widening by one
//!    voxel every two layers (paper section 3, "Calculation of environmental impact").
//! 2. **Resources**: each bud's light Q = its voxel's light as the papers compute it, by
//!    vertical shadow propagation (obstacle and node shadows), and the sky openness of step 1
//!    only where something stands above the voxel (its zenith is blocked: a roof); the side shade
//!    of a wall or box beside it is left out (see [`LightSpace::side_shade`]); Q is summed basipetally; the root
//!    resource α·Q_root is split at branch points by Borchert–Honda (eq. 1, weight λ of the main
//!    axis) and re-allocated among the buds of each axis by priority (eq. 2) with weights
//!    ω_r = max(0.1, 1 − k·r) for the r-th largest R_BH (r = 0, 1, …; the piecewise linear
//!    function of the paper's Fig. 3, which shows 1.0, 0.6, 0.3).
//! 3. **Shoots**: a bud receiving R grows n = ⌊R⌋ internodes (at most `max_shoot` per cycle) of
//!    length ℓ·R/n (capped at 1.5ℓ); direction V_u = V_d + μV_o + γV_t (eq. 3): V_d continues the
//!    parent (terminal buds) or leaves at the branching angle with phyllotaxis (lateral buds);
//!    V_o is the light-weighted mean direction of 12 random points in the cone of half-angle θ
//!    (the full light of step 1, side shade included, so shoots turn away from a wall);
//!    V_t is up. A shoot that would enter an obstacle or leave the space is not grown. Shadows are
//!    updated after every shoot, so later shoots see earlier ones.
//! 4. **Radii and shedding**: pipe model r^d = Σ r_j^d (d from the species), radii never shrink;
//!    a lateral branch whose light per internode falls below r_s times the tree's best-lit
//!    internode's light is shed (Takenaka 1994; the relative threshold is our choice); the light
//!    of step 2 times the share of the sky the side shade of obstacles leaves
//!    ([`LightSpace::shedding_light_at`]), so branches on a wall's dim side are shed as Plastic
//!    Trees sheds them ("shedding branches that are close to the wall", Pirk et al. 2012 section
//!    7.1; the obstacle casts "a shadow for the entire life span of its growth", section 5.3).
//!
//! Why the side shade of obstacles (our addition) is left out of the resource Q: with it there, a
//! tree beside a wall starved (a bud's resource falls below one internode, it grows nothing, and
//! the loss compounds every cycle: beside an infinite wall at half the open-grown crown radius,
//! trees of 10 cycles kept 19 % of the open-grown trees' nodes), where the papers' growth model
//! (Palubicki et al. 2009, vertical shadows only) grows a full-sized tree on the open side, as
//! trees at forest edges and beside buildings do. The shedding test is relative to the tree's
//! best-lit internode, so a uniformly dimmer site sheds nothing more; only the branches dim
//! relative to the rest of the crown, on the wall's side, are shed (round 39; up to round 38 the
//! side shade only steered V_o). Measured on the sets of Plastic Trees' Table 1
//! (`examples/plastic_table1`, `docs/plastic_table1.md`).
//!
//! Several trees and obstacles share one [`LightSpace`].

use super::envelope::CrownEnvelope;
use super::space::VoxelSpace;
use crate::obstacle::Obstacle;
use crate::error::{Error, Result};
use crate::rng::{salt, Stream};
use crate::species::LightGuidedParams;
use crate::structure::skeleton::{Role, Skeleton};
use glam::{IVec3, Mat3, Vec3};

/// Options of the light-guided model beyond the paper's Table 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightOptions {
    /// Internode length ℓ (m); voxels are ℓ/2.
    pub internode_m: f32,
    /// Resource per unit of light at the root (α of Palubicki et al. 2009).
    pub alpha: f32,
    /// Most internodes a bud grows per cycle.
    pub max_shoot: u32,
    /// Branching angle of lateral shoots (degrees).
    pub branch_angle_deg: f32,
    /// Phyllotaxis angle between successive lateral buds (degrees).
    pub phyllotaxis_deg: f32,
    /// Tip radius of the pipe model (m).
    pub tip_radius_m: f32,
    /// Pipe exponent d (2–3.5).
    pub pipe_exponent: f32,
    /// Half-width of the space around the trees (m) and its height (m).
    pub extent_m: f32,
    /// Height of the space (m).
    pub height_m: f32,
    /// Crown envelope (our addition, see [`super::envelope`]): the sky light is multiplied by
    /// its light factor (1 inside, 0 one internode outside) and no shoot ends more than one
    /// internode outside it, so the tree forms the species' crown and stops at its height.
    /// `None`: the whole space is open (the paper's setting).
    pub envelope: Option<CrownEnvelope>,
    /// Plagiotropic side branches (conifers; our addition): the tropism V_t of shoots off the
    /// main stem is their own horizontal direction instead of up, so they keep spreading
    /// sideways in tiers while the leader stays orthotropic (up).
    pub plagiotropic: bool,
}

impl Default for LightOptions {
    fn default() -> Self {
        LightOptions { internode_m: 0.4, alpha: 3.0, max_shoot: 3, branch_angle_deg: 45.0, phyllotaxis_deg: 137.5, tip_radius_m: 0.004, pipe_exponent: 2.5, extent_m: 6.0, height_m: 14.0, envelope: None, plagiotropic: false }
    }
}

/// One tree in a light space.
#[derive(Debug, Clone, PartialEq)]
pub struct LgTree {
    /// Skeleton (node 0 at the base).
    pub skeleton: Skeleton,
    /// Last bud azimuth index per node (phyllotaxis counter).
    phyllo: u32,
}

/// A shared light space with its trees.
#[derive(Debug, Clone, PartialEq)]
pub struct LightSpace {
    /// Voxel grid and obstacles (voxel = half an internode).
    pub space: VoxelSpace,
    /// Sky openness per voxel (0–1), the light before shading by nodes.
    pub sky: Vec<f32>,
    /// Light the side shade of obstacles takes from each voxel (0–1): the overhead sky light
    /// (the openness where the voxel's zenith is blocked, else 1; less the obstacles' vertical
    /// shadows, times the envelope's factor) less [`LightSpace::sky`]. Added back for the
    /// resource Q of a bud (see the module docs), not for steering; the shedding light is
    /// scaled by sky / (sky + side shade) ([`LightSpace::shedding_light_at`]).
    pub side_shade: Vec<f32>,
    /// Current light per voxel.
    pub light: Vec<f32>,
    /// Trees, in the order given.
    pub trees: Vec<LgTree>,
    /// Paper parameters.
    pub params: LightGuidedParams,
    /// Model options.
    pub options: LightOptions,
    /// Obstacles.
    pub obstacles: Vec<Obstacle>,
    seed: u64,
    year: u64,
}

/// Layers (voxels) a shadow reaches below a node or obstacle voxel.
pub const SHADOW_DEPTH: i32 = 10;

impl LightSpace {
    /// A space spanning `extent_m` around the given roots (m, on the ground z = 0) and
    /// `height_m` up, with obstacles; one seedling (a single internode) per root.
    ///
    /// Errors: [`Error::Invalid`] for bad parameters or a root inside an obstacle; errors of
    /// [`VoxelSpace::new`].
    pub fn new(roots: &[Vec3], obstacles: &[Obstacle], params: LightGuidedParams, options: LightOptions, seed: u64) -> Result<Self> {
        let bad = |f: &str, v: String, e: &str| Error::Invalid { context: "light-guided growth".into(), field: f.into(), value: v, expected: e.into() };
        if !(params.b > 1.0 && params.b.is_finite()) {
            return Err(bad("b", params.b.to_string(), "> 1 (l_n = l_o - b^-q)"));
        }
        if !(0.0..=1.0).contains(&params.lambda) {
            return Err(bad("lambda", params.lambda.to_string(), "0 ..= 1"));
        }
        if !(options.internode_m > 0.0) || !(options.extent_m > 0.0) || !(options.height_m > 0.0) {
            return Err(bad("internode_m/extent_m/height_m", format!("{:?}", options), "positive lengths (m)"));
        }
        let (mut lo, mut hi) = (Vec3::new(-options.extent_m, -options.extent_m, 0.0), Vec3::new(options.extent_m, options.extent_m, options.height_m));
        for r in roots {
            lo = lo.min(*r - Vec3::new(options.extent_m, options.extent_m, 0.0));
            hi = hi.max(*r + Vec3::new(options.extent_m, options.extent_m, options.height_m));
        }
        let space = VoxelSpace::new(lo, hi, options.internode_m * 0.5, obstacles)?;
        let (mut sky, mut vertical) = sky_openness(&space, obstacles);
        obstacle_shadows(&space, params.b, &mut sky);
        obstacle_shadows(&space, params.b, &mut vertical);
        if let Some(env) = &options.envelope {
            for z in 0..space.dims[2] {
                for y in 0..space.dims[1] {
                    for x in 0..space.dims[0] {
                        let i = (z * space.dims[1] + y) * space.dims[0] + x;
                        let f = env.light_factor(space.center(IVec3::new(x as i32, y as i32, z as i32)), options.internode_m);
                        sky[i] *= f;
                        vertical[i] *= f;
                    }
                }
            }
        }
        let side_shade: Vec<f32> = vertical.iter().zip(&sky).map(|(v, s)| (v - s).max(0.0)).collect();
        let mut trees = Vec::new();
        for (i, &r) in roots.iter().enumerate() {
            if space.blocked(r) || space.blocked(r + Vec3::Z * options.internode_m) {
                return Err(bad("root", format!("tree {i} at {r}"), "a root outside obstacles, inside the space"));
            }
            let mut sk = Skeleton::new();
            sk.add_root(r, options.tip_radius_m);
            sk.add_child(0, r + Vec3::Z * options.internode_m, options.tip_radius_m, false)?;
            sk.mark_tips();
            trees.push(LgTree { skeleton: sk, phyllo: 0 });
        }
        let light = sky.clone();
        Ok(LightSpace { space, sky, side_shade, light, trees, params, options, obstacles: obstacles.to_vec(), seed, year: 0 })
    }

    /// Light (0–1) at `p`; 0 outside the space or in obstacles.
    pub fn light_at(&self, p: Vec3) -> f32 {
        match self.space.index(self.space.cell(p)) {
            Some(i) if !self.space.solid[i] => self.light[i],
            _ => 0.0,
        }
    }

    fn shade(&mut self, p: Vec3, sign: f32) {
        let c = self.space.cell(p);
        let b = self.params.b;
        for q in 1..=SHADOW_DEPTH {
            let w = b.powi(-q) * sign;
            let r = q / 2;
            for dy in -r..=r {
                for dx in -r..=r {
                    if let Some(i) = self.space.index(c + IVec3::new(dx, dy, -q)) {
                        self.light[i] -= w;
                    }
                }
            }
        }
    }

    /// Recomputes the light field from sky openness, solid voxels and all nodes.
    pub fn update_light(&mut self) {
        self.light.copy_from_slice(&self.sky);
        let nodes: Vec<Vec3> = self.trees.iter().flat_map(|t| t.skeleton.nodes.iter().skip(1).map(|n| n.pos)).collect();
        for p in nodes {
            self.shade(p, 1.0);
        }
    }

    fn light_clamped(&self, p: Vec3) -> f32 {
        self.light_at(p).clamp(0.0, 1.0)
    }

    /// Light (0–1) at `p` for the resource Q of a bud: [`LightSpace::light_at`] with the side
    /// shade of obstacles added back ([`LightSpace::side_shade`]); 0 outside the space or in
    /// obstacles.
    pub fn resource_light_at(&self, p: Vec3) -> f32 {
        match self.space.index(self.space.cell(p)) {
            Some(i) if !self.space.solid[i] => (self.light[i] + self.side_shade[i]).clamp(0.0, 1.0),
            _ => 0.0,
        }
    }

    /// Light (0–1) at `p` for the shedding test: [`LightSpace::resource_light_at`] (the vertical
    /// shadows of nodes and obstacles) times the share of the overhead sky that the side shade
    /// of obstacles leaves, [`LightSpace::sky`] / ([`LightSpace::sky`] + [`LightSpace::side_shade`])
    /// (1 where there is no side shade). The product, not the difference: the directions a wall
    /// blocks give no light whatever the crown does, and the crown's shade (the vertical
    /// shadow) dims the directions the wall leaves open, as the visibility O = 1 − Πγ of each
    /// sky direction combines solids and clusters in Plastic Trees' eq. (3) (Pirk et al. 2012,
    /// section 4.2). Subtracting both (as [`LightSpace::light_at`] does for steering) counted the
    /// crown's shade again on top of the wall's and starved trees beside a wall (round 39: set G
    /// of type 2 kept 41 % of the open-grown trees' nodes). 0 outside the space or in obstacles.
    pub fn shedding_light_at(&self, p: Vec3) -> f32 {
        match self.space.index(self.space.cell(p)) {
            Some(i) if !self.space.solid[i] => {
                let vertical = (self.light[i] + self.side_shade[i]).clamp(0.0, 1.0);
                if self.side_shade[i] > 0.0 {
                    vertical * self.sky[i] / (self.sky[i] + self.side_shade[i])
                } else {
                    vertical
                }
            }
            _ => 0.0,
        }
    }

    /// One growth cycle for every tree (in order).
    pub fn step(&mut self) {
        self.year += 1;
        self.update_light();
        for t in 0..self.trees.len() {
            self.grow_tree(t);
        }
        for t in 0..self.trees.len() {
            self.shed(t);
            let sk = &mut self.trees[t].skeleton;
            let old: Vec<f32> = sk.nodes.iter().map(|n| n.radius).collect();
            let _ = sk.pipe_radii(self.options.tip_radius_m, self.options.pipe_exponent);
            for (n, r) in sk.nodes.iter_mut().zip(old) {
                n.radius = n.radius.max(r);
                n.age += 1.0;
            }
            sk.mark_tips();
        }
    }

    /// Runs `years` cycles.
    pub fn grow(&mut self, years: u32) {
        for _ in 0..years {
            self.step();
        }
    }

    fn grow_tree(&mut self, t: usize) {
        let p = self.params;
        let o = self.options;
        let sk = &self.trees[t].skeleton;
        let n = sk.nodes.len();
        // Buds: terminal (no children) and lateral (exactly one child, not the root).
        // Light of a bud = resource light of its node's voxel (vertical shadows only).
        let bud_light: Vec<f32> = sk.nodes.iter().map(|nd| self.resource_light_at(nd.pos)).collect();
        let has_term = |i: usize| sk.nodes[i].children.is_empty();
        let has_lat = |i: usize| i > 0 && sk.nodes[i].children.len() == 1;
        // Basipetal accumulation: q[i] = light of the subtree at i incl. its buds.
        let mut q = vec![0.0f32; n];
        for i in (0..n).rev() {
            let own = if has_term(i) || has_lat(i) { bud_light[i] } else { 0.0 };
            q[i] += own;
            if let Some(par) = sk.nodes[i].parent {
                let v = q[i];
                q[par as usize] += v;
            }
        }
        // Acropetal Borchert–Honda (eq. 1): v[i] = resource entering node i's subtree.
        let mut v = vec![0.0f32; n];
        v[0] = o.alpha * q[0];
        let mut r_bh_term = vec![0.0f32; n];
        let mut r_bh_lat = vec![0.0f32; n];
        let split = |res: f32, lm: f32, ll: f32| -> (f32, f32) {
            let den = p.lambda * lm + (1.0 - p.lambda) * ll;
            if den <= 0.0 {
                return (0.0, 0.0);
            }
            let lat = res * (1.0 - p.lambda) * ll / den;
            (res - lat, lat)
        };
        for i in 0..n {
            let ch = &sk.nodes[i].children;
            let res = v[i];
            if ch.is_empty() {
                r_bh_term[i] = res;
            } else if ch.len() == 1 {
                let m = ch[0] as usize;
                if has_lat(i) {
                    let (vm, vl) = split(res, q[m], bud_light[i]);
                    v[m] = vm;
                    r_bh_lat[i] = vl;
                } else {
                    v[m] = res;
                }
            } else {
                let m = ch[0] as usize;
                let lat_q: f32 = ch[1..].iter().map(|&c| q[c as usize]).sum();
                let (vm, vl) = split(res, q[m], lat_q);
                v[m] = vm;
                for &c in &ch[1..] {
                    v[c as usize] = if lat_q > 0.0 { vl * q[c as usize] / lat_q } else { 0.0 };
                }
            }
        }
        // Priority (eq. 2) within each axis (chain of first children): gather buds per axis.
        let mut axis_of = vec![0u32; n];
        let mut axes: Vec<Vec<(usize, bool, f32)>> = vec![Vec::new()];
        for i in 1..n {
            let par = sk.nodes[i].parent.unwrap_or(0) as usize;
            let first = sk.nodes[par].children.first().map(|&c| c as usize) == Some(i);
            axis_of[i] = if first && i != 0 { axis_of[par] } else {
                axes.push(Vec::new());
                (axes.len() - 1) as u32
            };
        }
        for i in 0..n {
            if has_term(i) && i > 0 {
                axes[axis_of[i] as usize].push((i, true, r_bh_term[i]));
            }
            if has_lat(i) {
                axes[axis_of[i] as usize].push((i, false, r_bh_lat[i]));
            }
        }
        let mut shoots: Vec<(usize, bool, f32)> = Vec::new();
        for buds in &mut axes {
            let total: f32 = buds.iter().map(|b| b.2).sum();
            if total <= 0.0 {
                continue;
            }
            let mut order: Vec<usize> = (0..buds.len()).collect();
            order.sort_by(|&a, &b| buds[b].2.total_cmp(&buds[a].2).then(a.cmp(&b)));
            let mut w = vec![0.0f32; buds.len()];
            for (rank, &k) in order.iter().enumerate() {
                w[k] = (1.0 - p.k * rank as f32).max(0.1);
            }
            let den: f32 = buds.iter().zip(&w).map(|(b, w)| b.2 * w).sum();
            for (b, w) in buds.iter().zip(&w) {
                let r = if den > 0.0 { total * b.2 * w / den } else { 0.0 };
                if r >= 1.0 {
                    shoots.push((b.0, b.1, r));
                }
            }
        }
        shoots.sort_by_key(|s| (s.0, s.1));
        for (node, terminal, r) in shoots {
            self.shoot(t, node, terminal, r);
        }
    }

    fn shoot(&mut self, t: usize, node: usize, terminal: bool, r: f32) {
        let p = self.params;
        let o = self.options;
        let count = (r.floor() as u32).min(o.max_shoot).max(1);
        let len = (o.internode_m * (r / count as f32)).min(1.5 * o.internode_m);
        let mut rng = Stream::new(self.seed, (t as u64) << 32 | node as u64, self.year, salt::ARCHITECTURE ^ terminal as u64);
        let sk = &self.trees[t].skeleton;
        let pos = sk.nodes[node].pos;
        let parent_dir = match sk.nodes[node].parent {
            Some(pp) => (pos - sk.nodes[pp as usize].pos).normalize_or(Vec3::Z),
            None => Vec3::Z,
        };
        // on the main stem: every node up to the root is its parent's first child
        let on_stem = {
            let mut i = node;
            let mut stem = terminal;
            while stem {
                match sk.nodes[i].parent {
                    Some(par) => {
                        stem = sk.nodes[par as usize].children.first().map(|&c| c as usize) == Some(i);
                        i = par as usize;
                    }
                    None => break,
                }
            }
            stem
        };
        let mut vd = parent_dir;
        if !terminal {
            let k = self.trees[t].phyllo;
            self.trees[t].phyllo += 1;
            let az = (k as f32 * o.phyllotaxis_deg).to_radians();
            let side = Mat3::from_axis_angle(parent_dir, az) * parent_dir.any_orthonormal_vector();
            let axis = parent_dir.cross(side).normalize_or(Vec3::X);
            vd = Mat3::from_axis_angle(axis, o.branch_angle_deg.to_radians()) * parent_dir;
        }
        let mut cur = node as u32;
        let mut cur_pos = pos;
        let mut lateral = !terminal;
        for _ in 0..count {
            // V_o: light-weighted mean of random points in the cone of half-angle θ around V_d.
            let th = p.theta_deg.to_radians();
            let frame_x = vd.any_orthonormal_vector();
            let frame_y = vd.cross(frame_x);
            let mut vo = Vec3::ZERO;
            for _ in 0..12 {
                let cos_a = 1.0 - rng.uniform() as f32 * (1.0 - th.cos());
                let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                let phi = rng.range(0.0, std::f64::consts::TAU) as f32;
                let dir = vd * cos_a + (frame_x * phi.cos() + frame_y * phi.sin()) * sin_a;
                let dist = o.internode_m * rng.range(1.0, 3.0) as f32;
                let lp = self.light_clamped(cur_pos + dir * dist);
                vo += dir * lp;
            }
            let vo = vo.normalize_or_zero();
            let vt = if o.plagiotropic && !on_stem { (vd * Vec3::new(1.0, 1.0, 0.0)).normalize_or(Vec3::Z) } else { Vec3::Z };
            let vu = (vd + p.mu * vo + p.gamma * vt).normalize_or(vd);
            let next = cur_pos + vu * len;
            if self.space.segment_blocked(cur_pos, next) {
                break;
            }
            if let Some(env) = &o.envelope {
                if env.outside_m(next) > o.internode_m {
                    break;
                }
            }
            let sk = &mut self.trees[t].skeleton;
            let Ok(id) = sk.add_child(cur, next, o.tip_radius_m, lateral) else { break };
            sk.nodes[id as usize].role = Role::Tip;
            self.shade(next, 1.0);
            cur = id;
            cur_pos = next;
            vd = vu;
            lateral = false;
        }
    }

    /// Sheds lateral branches (≥ 3 internodes) whose light per internode is below r_s × the best
    /// internode's light; the light is [`LightSpace::shedding_light_at`] (module docs step 4).
    fn shed(&mut self, t: usize) {
        let sk = &self.trees[t].skeleton;
        let n = sk.nodes.len();
        let mut q = vec![0.0f32; n];
        let mut size = vec![0u32; n];
        for i in (1..n).rev() {
            q[i] += self.shedding_light_at(sk.nodes[i].pos);
            size[i] += 1;
            if let Some(par) = sk.nodes[i].parent {
                let (a, b) = (q[i], size[i]);
                q[par as usize] += a;
                size[par as usize] += b;
            }
        }
        // threshold relative to the best-lit internode of the tree, so that uniformly dim sites
        // (a roof's shade, the flat part of a wall's) slow growth without shedding everything
        let best = sk.nodes.iter().skip(1).map(|nd| self.shedding_light_at(nd.pos)).fold(0.0f32, f32::max);
        let threshold = self.params.r_s * best;
        let mut remove = vec![false; n];
        let mut any = false;
        for i in 1..n {
            let par = sk.nodes[i].parent.unwrap_or(0) as usize;
            let lateral = sk.nodes[par].children.first().map(|&c| c as usize) != Some(i);
            if lateral && size[i] >= 3 && q[i] / (size[i] as f32) < threshold {
                remove[i] = true;
                any = true;
            }
        }
        if any {
            let sk = &mut self.trees[t].skeleton;
            sk.prune(&remove);
            self.update_light();
        }
    }
}

/// Sky openness: the share of 25 equally weighted sky directions (zenith; 8 azimuths at 20°,
/// 45° and 70° elevation) that reach each voxel centre unblocked by obstacles (analytic ray
/// tests). Steep directions (≥ 60° elevation) are blocked by obstacles at any distance, also
/// above the voxel space (a roof); low ones only within [`SKY_RANGE_M`], so that an endless
/// wall shades its near side more than its far side.
///
/// Returns (openness, overhead openness): the second is the openness where something stands
/// above the point (its zenith is blocked: a roof, a canopy of boxes) and 1 where the zenith is
/// open (the shade of a wall or box beside the point is side shade), the sky the resources and
/// shedding see.
fn sky_openness(s: &VoxelSpace, obstacles: &[Obstacle]) -> (Vec<f32>, Vec<f32>) {
    if obstacles.is_empty() {
        return (vec![1.0; s.len()], vec![1.0; s.len()]);
    }
    let mut dirs = vec![(Vec3::Z, 1.0f32, f32::INFINITY)];
    for e in [20.0f32, 45.0, 70.0] {
        let (se, ce) = e.to_radians().sin_cos();
        for k in 0..8 {
            let a = k as f32 * std::f32::consts::FRAC_PI_4;
            // exact zeros at the azimuths 90° and 270° (f32 cos(3π/2) is 1.2e-8, which made an
            // endless wall parallel to the direction block it at 70°: 15/25 instead of 16/25)
            let snap = |c: f32| if c.abs() < 1e-6 { 0.0 } else { c };
            dirs.push((Vec3::new(snap(ce * a.cos()), snap(ce * a.sin()), se), 1.0, if e >= 60.0 { f32::INFINITY } else { SKY_RANGE_M }));
        }
    }
    let total: f32 = dirs.iter().map(|d| d.1).sum();
    let mut out = vec![0.0f32; s.len()];
    let mut overhead = vec![0.0f32; s.len()];
    for z in 0..s.dims[2] {
        for y in 0..s.dims[1] {
            for x in 0..s.dims[0] {
                let i = (z * s.dims[1] + y) * s.dims[0] + x;
                if s.solid[i] {
                    continue;
                }
                let p = s.center(IVec3::new(x as i32, y as i32, z as i32));
                let (mut open, mut zenith_open) = (0.0f32, true);
                for (k, d) in dirs.iter().enumerate() {
                    if !obstacles.iter().any(|o| o.ray_hits(p, d.0, d.2)) {
                        open += d.1;
                    } else if k == 0 {
                        zenith_open = false;
                    }
                }
                out[i] = open / total;
                overhead[i] = if zenith_open { 1.0 } else { out[i] };
            }
        }
    }
    (out, overhead)
}

/// Yi et al.'s shadow l_n = l_o − b^(−q) cast by obstacle voxels, treated as fully occupied:
/// every solid voxel above a free one lowers the free voxels of the pyramid below it (widening
/// by one voxel every two layers, [`SHADOW_DEPTH`] layers) by b^(−(q−1)), so the layer right
/// under an obstacle loses all its light (occupancy 1) and the shade fades downwards as for
/// nodes.
fn obstacle_shadows(s: &VoxelSpace, b: f32, sky: &mut [f32]) {
    let [nx, ny, nz] = s.dims;
    for z in 1..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = (z * ny + y) * nx + x;
                if !s.solid[i] || s.solid[i - nx * ny] {
                    continue;
                }
                let c = IVec3::new(x as i32, y as i32, z as i32);
                for q in 1..=SHADOW_DEPTH {
                    let w = b.powi(-(q - 1));
                    let r = q / 2;
                    for dy in -r..=r {
                        for dx in -r..=r {
                            if let Some(j) = s.index(c + IVec3::new(dx, dy, -q)) {
                                if !s.solid[j] {
                                    sky[j] -= w;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    for v in sky.iter_mut() {
        *v = v.max(0.0);
    }
}

/// Range (m) within which obstacles block the sky in [`LightSpace`]'s openness.
pub const SKY_RANGE_M: f32 = 6.0;

/// Grows one tree at the origin for `years` cycles among `obstacles`.
///
/// Errors: as [`LightSpace::new`].
pub fn grow(params: &LightGuidedParams, options: &LightOptions, obstacles: &[Obstacle], seed: u64, years: u32) -> Result<Skeleton> {
    let mut ls = LightSpace::new(&[Vec3::ZERO], obstacles, *params, *options, seed)?;
    ls.grow(years);
    Ok(ls.trees.swap_remove(0).skeleton)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::params::light_guided_paper;

    /// The shedding rule sees the side shade of a wall (round 39), checked by hand. An infinite
    /// wall x ≥ 4 m; two horizontal lateral branches of 3 nodes each at z = 2.1 m (voxel centres):
    /// one towards the wall (x = 1.9–2.3 m, 1.7–2.1 m from it), one away (x = −1.7 to −2.1 m,
    /// 5.7–6.1 m from it). Of the 25 sky directions (zenith; 8 azimuths at 20°, 45°, 70°) the
    /// wall blocks, for the near branch, the 3 azimuths facing it (0°, ±45°) at every elevation:
    /// ray lengths to the wall s/(cos e · cos a) ≤ 2.1/(0.940 · 0.707) = 3.2 m ≤ [`SKY_RANGE_M`]
    /// (6 m), and the 70° ones at any range: openness 16/25 = 0.64. For the far branch only the
    /// 70° ones (5.7/0.940 = 6.07 m > 6 m for 20°, and more for 45°): 22/25 = 0.88. The zenith is
    /// open at both, so the resource light is 1 at both, except under one node of the main axis
    /// 0.2 m (q = 1 voxel) above the near branch's middle node: 1 − 2^−1 = 0.5 there (b = 2).
    /// The shedding light is the product: 0.64, 0.5 × 0.64 = 0.32, 0.64 (mean 0.533) near,
    /// 0.88 far; the steering light subtracts (0.64 − 0.5 = 0.14). With r_s = 0.8 the threshold
    /// is 0.8 × 0.88 = 0.704 (the far branch is the best lit): the near branch is shed, the far
    /// one kept. Before round 39 the shedding used the resource light (1, 0.5, 1 and 1) and shed
    /// neither.
    #[test]
    fn shedding_sees_a_walls_side_shade() {
        let mut p = light_guided_paper();
        p.r_s = 0.8;
        let o = LightOptions { extent_m: 8.0, height_m: 24.0, ..LightOptions::default() };
        let mut ls = LightSpace::new(&[Vec3::ZERO], &[Obstacle::Wall { x: 4.0 }], p, o, 1).unwrap();
        let mut sk = Skeleton::new();
        let root = sk.add_root(Vec3::ZERO, 0.004);
        let mut s = root;
        for z in [0.5f32, 1.3, 2.1] {
            s = sk.add_child(s, Vec3::new(0.1, 0.1, z), 0.004, false).unwrap();
        }
        let main = sk.add_child(s, Vec3::new(0.1, 0.3, 2.1), 0.004, false).unwrap();
        let above = sk.add_child(main, Vec3::new(2.1, 0.1, 2.3), 0.004, false).unwrap();
        let branch = |sk: &mut Skeleton, xs: [f32; 3]| -> Vec<u32> {
            let mut ids = Vec::new();
            let mut at = s;
            for (k, x) in xs.into_iter().enumerate() {
                at = sk.add_child(at, Vec3::new(x, 0.1, 2.1), 0.004, k == 0).unwrap();
                ids.push(at);
            }
            ids
        };
        let near = branch(&mut sk, [1.9, 2.1, 2.3]);
        let far = branch(&mut sk, [-1.7, -1.9, -2.1]);
        assert_eq!(sk.nodes[s as usize].children[0], main);
        ls.trees[0].skeleton = sk;
        ls.update_light();
        assert_eq!(ls.trees[0].skeleton.nodes[main as usize].children, vec![above]);
        for (k, &i) in near.iter().enumerate() {
            let pos = ls.trees[0].skeleton.nodes[i as usize].pos;
            let shade = if k == 1 { 0.5 } else { 0.0 };
            assert!((ls.resource_light_at(pos) - (1.0 - shade)).abs() < 1e-6, "near {pos}: {}", ls.resource_light_at(pos));
            assert!((ls.light_at(pos) - (0.64 - shade)).abs() < 1e-6, "near {pos}: {}", ls.light_at(pos));
            assert!((ls.shedding_light_at(pos) - (1.0 - shade) * 0.64).abs() < 1e-6, "near {pos}: {}", ls.shedding_light_at(pos));
        }
        for &i in &far {
            let pos = ls.trees[0].skeleton.nodes[i as usize].pos;
            assert!((ls.light_at(pos) - 0.88).abs() < 1e-6, "far {pos}: {}", ls.light_at(pos));
            assert!((ls.resource_light_at(pos) - 1.0).abs() < 1e-6);
            assert!((ls.shedding_light_at(pos) - 0.88).abs() < 1e-6);
        }
        let before = ls.trees[0].skeleton.len();
        ls.shed(0);
        let sk = &ls.trees[0].skeleton;
        assert_eq!(sk.len(), before - 3, "only the near branch's 3 nodes are shed");
        let xs: Vec<f32> = sk.nodes.iter().map(|n| n.pos.x).collect();
        assert_eq!(xs.iter().filter(|&&x| x > 1.0).count(), 1, "the near branch is gone, the node above it kept: {xs:?}");
        assert_eq!(xs.iter().filter(|&&x| x < -1.0).count(), 3, "the far branch is kept: {xs:?}");
    }
}
