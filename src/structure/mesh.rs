//! Meshes of a skeleton: generalized cylinders with parallel-transport frames (continuous normals
//! and UVs along each branch axis), leaves as quads (cards), and the level-of-detail chain
//! (DESIGN.md): LOD0 full mesh; LOD1 reduced skeleton with thin branches merged into leaf-cluster
//! cards; LOD2 crown hull (low-poly star-shaped hull fitted to the foliage) on a simple trunk; LOD3
//! billboard impostor (two crossed quads).
//!
//! Parallel transport: the ring frame is carried from one ring to the next by projecting the
//! previous normal onto the plane of the new tangent (the discrete rotation-minimising frame of
//! Bishop 1975 / Wang et al. 2008 to first order), so rings do not twist and the UV seam stays on
//! one side of a branch.

use crate::mesh::{LodChain, TreeMesh, TriMesh, LOD_LEVELS};
use crate::structure::skeleton::{Leaves, Skeleton};
use glam::Vec3;
use crate::structure::texture::{BARK_TILE_M, IMPOSTOR_CROWN_V, IMPOSTOR_TRUNK_U};
use std::f32::consts::TAU;

/// Options of [`lod_chain`] and [`branch_mesh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodOptions {
    /// Sides of the trunk tube at LOD0 (≥ 3); thinner branches get fewer (see `min_sides`).
    pub sides: u32,
    /// Fewest sides of any tube (≥ 3).
    pub min_sides: u32,
    /// Fraction (0–1] of branch nodes kept (the thickest) in the LOD1 reduced skeleton.
    pub reduced_keep_fraction: f32,
    /// Azimuth sectors of the LOD2 crown hull (≥ 3; its rings are [`HULL_RING_HEIGHTS`]).
    pub hull_segments: u32,
    /// Emit leaves at LOD0.
    pub leaves: bool,
    /// LOD1 of a conifer: the crown as tiers of limb sprays ([`limb_spray_mesh`]: one
    /// drooping card pair per first-order limb, following its foliage) instead of
    /// [`reduced_mesh`]'s crossed cluster cards, which merged a spruce's whorls into a smooth
    /// spire. Set for needle-leaved species by the callers that know the species.
    pub conifer_tiers: bool,
    /// The stem's taper (issue 32, round 42; [`super::taper`]): when set, [`branch_mesh`]
    /// draws the main stem up to the crown base (at least to breast height) with the taper
    /// equation's radii conditioned on the tree's DBH, with rings at the root collar, at
    /// 1.3 m and at most 2 m apart, and every other radius (the crown's stem and the
    /// branches) is the pipe model's times the one factor that meets the bole at the crown
    /// base ([`StemProfile`]). `None`: the skeleton's radii as they are.
    pub stem: Option<super::taper::StemTaper>,
}

/// Azimuth sectors of the crown-hull level by default ([`LodOptions::hull_segments`]): 8
/// (rounds 34–44: 10). The stills draw the level at 18–45 px (times the budget's switch
/// factor; `job::pictures`), where a crown is 10–40 px wide: an 8-gon's mean width is
/// `8·2r·sin(π/8)/π = 1.950 r` against the 10-gon's `1.967 r` (0.9 % narrower), and the renderer
/// spreads every hull to its crown disc's plan area ([`crate::render::lod::plan_spread`]), so
/// it draws the crown as wide as before with 96 triangles instead of 120 (issue 32, round 45:
/// a cheaper hull level so that the small-tree reference fits the budget;
/// `tests/structure_mesh.rs::the_cheaper_hull_level_keeps_its_silhouette`).
pub const HULL_SECTORS: u32 = 8;


impl Default for LodOptions {
    fn default() -> Self {
        LodOptions { sides: 8, min_sides: 3, reduced_keep_fraction: 0.12, hull_segments: HULL_SECTORS, leaves: true, conifer_tiers: false, stem: None }
    }
}

impl LodOptions {
    /// The default options for species `sp`: [`LodOptions::conifer_tiers`] for needle-leaved
    /// species.
    pub fn for_species(sp: &crate::species::Species) -> Self {
        LodOptions { conifer_tiers: sp.identity.leaf_type == crate::species::LeafType::Conifer, ..LodOptions::default() }
    }
}

/// Number of tube sides for radius `r` given the trunk radius `r0`: `sides` at the trunk,
/// decreasing with √(r/r0) down to `min_sides`.
fn sides_for(r: f32, r0: f32, o: &LodOptions) -> u32 {
    let s = (o.sides as f32 * (r / r0.max(1e-9)).sqrt()).round() as u32;
    s.clamp(o.min_sides.max(3), o.sides.max(3))
}

/// How [`branch_mesh`] draws the radii of a skeleton whose [`LodOptions::stem`] is set: the
/// main stem ([`main_stem`]'s nodes) from the base up to the bole's top `top` (the first stem
/// node with a branch off the stem, the crown base, or breast height where that is higher;
/// frame units above the root) follows the taper, and every other radius is the skeleton's
/// (pipe model) times `k`, the taper's radius at `top` over the pipe model's stem radius
/// there, so the crown's pipes carry the bole's cross-section (Shinozaki et al. 1964: the
/// stem below the crown base holds the pipes of the crown and of the shed branches).
pub struct StemProfile {
    taper: super::taper::StemTaper,
    on_stem: Vec<bool>,
    root_z: f32,
    /// Top of the tapered bole (frame units above the root).
    pub top: f32,
    /// Factor on the other radii.
    pub k: f32,
}

impl StemProfile {
    /// The profile of `sk` under `taper` (`None` for a skeleton of fewer than 2 nodes).
    pub fn new(sk: &Skeleton, taper: super::taper::StemTaper) -> Option<StemProfile> {
        let n = sk.nodes.len();
        if n < 2 {
            return None;
        }
        let mut on_stem = vec![false; n];
        let mut path = Vec::new();
        let mut cur = Some(0usize);
        while let Some(i) = cur {
            if on_stem[i] {
                break;
            }
            on_stem[i] = true;
            path.push(i);
            cur = sk.nodes[i].children.iter().map(|&c| c as usize).find(|&c| c < n && sk.nodes[c].gravelius == sk.nodes[i].gravelius);
        }
        let root_z = sk.nodes[0].pos.z;
        let cb = path.iter().copied().find(|&i| i != 0 && sk.nodes[i].children.iter().any(|&c| !on_stem[c as usize])).unwrap_or(*path.last()?);
        let bh = super::taper::BREAST_HEIGHT_M * taper.frame_scale;
        let top = (sk.nodes[cb].pos.z - root_z).max(bh);
        // the pipe model's stem radius at `top`: between the stem nodes around it
        let mut pipe = sk.nodes[cb].radius;
        for w in path.windows(2) {
            let (a, b) = (&sk.nodes[w[0]], &sk.nodes[w[1]]);
            let (za, zb) = (a.pos.z - root_z, b.pos.z - root_z);
            if za <= top && top <= zb && zb > za {
                pipe = b.radius;
                break;
            }
        }
        let want = taper.radius_in_frame(top);
        let k = if pipe > 0.0 && want > 0.0 { (want / pipe).clamp(0.05, 20.0) } else { 1.0 };
        Some(StemProfile { taper, on_stem, root_z, top, k })
    }

    /// Radius of the segment ending at node `i` of `sk` (frame units).
    pub fn radius(&self, sk: &Skeleton, i: usize) -> f32 {
        let z = sk.nodes[i].pos.z - self.root_z;
        if self.on_stem[i] && z <= self.top + 1e-6 {
            self.taper.radius_in_frame(z)
        } else {
            sk.nodes[i].radius * self.k
        }
    }

    /// Heights (frame units above the root) of the rings the bole gets between its nodes.
    fn ring_heights(&self) -> Vec<f32> {
        let s = self.taper.frame_scale;
        self.taper.rings_m(self.top / s).into_iter().map(|h| h * s).collect()
    }

    /// Relative amplitude of the buttress lobes at height `z` (frame units above the root;
    /// [`super::taper::StemTaper::lobe_amplitude`]).
    fn lobe_at(&self, z: f32) -> f32 {
        self.taper.lobe_amplitude(z / self.taper.frame_scale)
    }
}

/// Generalized cylinders along the skeleton: one tube per branch axis (a chain that follows each
/// node's first child), rings at every node, `keep[i] == false` nodes skipped (their subtree is
/// cut). Tips taper to 30 % of their radius. UV: u around, 0 to n = max(1, round(c /
/// [`BARK_TILE_M`])) for a chain of base circumference c, and v = n × the distance along the
/// axis / c, so the bark texture's texels are square at each chain's base and one repeat
/// spans about [`BARK_TILE_M`] of bark on stems thicker than that (round 42; until then v was
/// the distance over the trunk's circumference on every branch). With
/// [`LodOptions::stem`] the radii are [`StemProfile`]'s and the root's chain gets rings at the
/// taper's heights ([`super::taper::StemTaper::rings_m`]) between its nodes below the
/// bole's top; with a lobed root flare ([`super::taper::Flare`]) the root chain's rings below
/// breast height have the radius r (1 + a cos(n θ)) at angle θ round the stem (n lobes, a the
/// taper's [`super::taper::StemTaper::lobe_amplitude`]), normals following the lobes.
pub fn branch_mesh(sk: &Skeleton, o: &LodOptions, keep: Option<&[bool]>) -> TriMesh {
    let mut m = TriMesh::default();
    if sk.nodes.len() < 2 {
        return m;
    }
    let kept = |i: usize| keep.map(|k| k[i]).unwrap_or(true);
    let profile = o.stem.and_then(|t| StemProfile::new(sk, t));
    let rad = |i: usize| profile.as_ref().map_or(sk.nodes[i].radius, |p| p.radius(sk, i));
    let bole_rings = profile.as_ref().map(|p| p.ring_heights()).unwrap_or_default();
    let r0 = rad(0).max(rad(1)).max(1e-6);
    let est = sk.nodes.len() * (o.sides as usize + 1);
    m.positions.reserve(est);
    m.normals.reserve(est);
    m.uvs.reserve(est);
    m.indices.reserve(est * 6);
    let mut chain: Vec<usize> = Vec::with_capacity(256);
    // ring centres and radii of a chain (the nodes, and the bole's rings between them)
    let mut rings: Vec<(Vec3, f32, f32)> = Vec::with_capacity(256);
    let lobes = o.stem.and_then(|t| t.flare).map_or(0, |f| f.lobes) as f32;
    // Chain starts: the root, and every non-first kept child.
    let mut starts: Vec<(usize, usize)> = vec![(0, 0)]; // (first point, first segment node)
    for (i, n) in sk.nodes.iter().enumerate() {
        if !kept(i) {
            continue;
        }
        let kids: Vec<usize> = n.children.iter().map(|&c| c as usize).filter(|&c| kept(c)).collect();
        for &c in kids.iter().skip(1) {
            starts.push((i, c));
        }
    }
    for &(p0, c0) in &starts {
        chain.clear();
        chain.push(p0);
        let root_chain = p0 == 0 && c0 == 0;
        let mut cur = if root_chain { sk.nodes[0].children.iter().map(|&c| c as usize).find(|&c| kept(c)) } else { Some(c0) };
        while let Some(c) = cur {
            chain.push(c);
            cur = sk.nodes[c].children.iter().map(|&c| c as usize).find(|&c| kept(c));
        }
        if chain.len() < 2 {
            continue;
        }
        let base_r = if root_chain && profile.is_some() { rad(0) } else { rad(chain[1]) };
        let sides = sides_for(base_r, r0, o);
        let ring = sides + 1;
        let circ = TAU * base_r.max(1e-6);
        let repeats = (circ / BARK_TILE_M).round().max(1.0);
        let vscale = repeats / circ;
        let n = chain.len();
        rings.clear();
        for k in 0..n {
            let pos = sk.nodes[chain[k]].pos;
            if k > 0 && root_chain {
                if let Some(p) = &profile {
                    // the bole's rings between the previous node and this one
                    let prev = sk.nodes[chain[k - 1]].pos;
                    let (za, zb) = (prev.z - p.root_z, pos.z - p.root_z);
                    if zb > za + 1e-6 {
                        for &h in bole_rings.iter().filter(|&&h| h > za + 1e-6 && h < zb - 1e-6 && h <= p.top) {
                            rings.push((prev.lerp(pos, (h - za) / (zb - za)), p.taper.radius_in_frame(h), p.lobe_at(h)));
                        }
                    }
                }
            }
            let mut r = if k == 0 { base_r } else { rad(chain[k]) };
            if k == n - 1 && sk.nodes[chain[k]].children.is_empty() {
                r *= 0.3;
            }
            let lobe = match &profile {
                Some(p) if root_chain && pos.z - p.root_z <= p.top + 1e-6 => p.lobe_at(pos.z - p.root_z),
                _ => 0.0,
            };
            rings.push((pos, r, lobe));
        }
        let mut normal = Vec3::ZERO;
        let mut v = 0.0f32;
        let first_vertex = m.positions.len() as u32;
        let nr = rings.len();
        for k in 0..nr {
            let (pos, r, lobe) = rings[k];
            let prev = rings[k.saturating_sub(1)].0;
            let next = rings[(k + 1).min(nr - 1)].0;
            let t = (next - prev).normalize_or(Vec3::Z);
            normal = if k == 0 { t.any_orthonormal_vector() } else { (normal - t * normal.dot(t)).normalize_or(t.any_orthonormal_vector()) };
            let binormal = t.cross(normal);
            if k > 0 {
                v += pos.distance(prev) * vscale;
            }
            for s in 0..ring {
                let a = s as f32 / sides as f32 * TAU;
                let (sa, ca) = a.sin_cos();
                let dir = normal * ca + binormal * sa;
                if lobe > 0.0 {
                    // r(θ) = r (1 + a cos nθ); the outward normal ∝ r(θ) d − r'(θ) d'
                    let (sn, cn) = (lobes * a).sin_cos();
                    let (rt, drt) = (r * (1.0 + lobe * cn), -r * lobe * lobes * sn);
                    let side = binormal * ca - normal * sa;
                    m.positions.push((pos + dir * rt).to_array());
                    m.normals.push((dir * rt - side * drt).normalize_or(dir).to_array());
                    m.uvs.push([repeats * s as f32 / sides as f32, v]);
                    continue;
                }
                m.positions.push((pos + dir * r).to_array());
                m.normals.push(dir.to_array());
                m.uvs.push([repeats * s as f32 / sides as f32, v]);
            }
        }
        for k in 0..(nr as u32 - 1) {
            let a = first_vertex + k * ring;
            let b = a + ring;
            for s in 0..sides {
                // counter-clockwise seen from outside: (a+s, a+s+1, b+s+1), (a+s, b+s+1, b+s)
                m.indices.extend_from_slice(&[a + s, a + s + 1, b + s + 1, a + s, b + s + 1, b + s]);
            }
        }
    }
    m
}

/// Leaves as quads (cards): each leaf a blade of length `size` and width `size/2` from its
/// attachment point along `dir`, facing `normal`; 4 vertices, 2 triangles, UV 0–1 over the card.
/// The glTF leaf material is double-sided.
pub fn leaf_mesh(leaves: &Leaves) -> TriMesh {
    let mut m = TriMesh::default();
    let n = leaves.len();
    m.positions.reserve(n * 4);
    m.normals.reserve(n * 4);
    m.uvs.reserve(n * 4);
    m.indices.reserve(n * 6);
    for l in &leaves.leaves {
        let side = l.normal.cross(l.dir) * (0.25 * l.size);
        let tip = l.dir * l.size;
        let base = m.positions.len() as u32;
        for (p, uv) in [(l.pos - side, [0.0, 0.0]), (l.pos + side, [1.0, 0.0]), (l.pos + side + tip, [1.0, 1.0]), (l.pos - side + tip, [0.0, 1.0])] {
            m.positions.push(p.to_array());
            m.normals.push(l.normal.to_array());
            m.uvs.push(uv);
        }
        m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    m
}

/// Options of [`hero_leaves`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeroLeafOptions {
    /// One-sided leaf area (m²) the leaves carry: the crown's drawn leaf area (the species'
    /// `life.foliage.crown_lai` over the crown projection, `job::leaf_area::drawn_leaf_area`).
    pub leaf_area_m2: f32,
    /// Length (m) of every leaf card: the species' `appearance.leaf_length_m`
    /// (`Species::drawn_leaf_length_m`).
    pub leaf_length_m: f32,
    /// Share (0–1] of a `size × size/2` card that the leaf texture covers
    /// ([`super::texture::leaf_card_cover`]).
    pub card_cover: f32,
    /// Divergence angle (degrees) between successive leaves round a shoot: the species'
    /// `architecture.ecomod.phyllotaxis_deg`.
    pub phyllotaxis_deg: f32,
    /// Leaves are kept within this distance (m) of the stem axis (the crown radius).
    pub crown_radius_m: f32,
    /// Seed of the hashed variations.
    pub seed: u64,
    /// Hanging sprays (a weeping birch's, the species'
    /// `architecture.ecomod.crown_profile.twig_droop_deg`): each spray lies along its anchor's
    /// shoot as grown (hanging with the twig), its plane facing outwards from the stem axis
    /// (the side light), instead of laid flat across the light.
    pub pendulous: bool,
}

/// Half the most leaves on one shoot of a hero spray ([`hero_leaves`]: √m, 3–16; ESTIMATE:
/// a beech long shoot carries some 5–12 leaves, a spray's side shoots fewer).
pub const HERO_LEAVES_PER_SHOOT: usize = 8;
/// Angle (degrees) between a shoot and its leaves' blades in [`hero_leaves`] (ESTIMATE).
pub const HERO_LEAF_ANGLE_DEG: f32 = 50.0;
/// Most leaves [`hero_leaves`] makes (8 M: 16 M triangles, about 1.2 GB of glb): a tree
/// whose leaf area needs more gets them larger.
pub const HERO_MAX_LEAVES: usize = 8_000_000;

/// Number of leaf cards [`hero_leaves`] makes: the leaf area over one card's
/// (½ · leaf_length² · card_cover), rounded, at most [`HERO_MAX_LEAVES`].
pub fn hero_leaf_count(o: &HeroLeafOptions) -> usize {
    let per = 0.5 * o.leaf_length_m * o.leaf_length_m * o.card_cover.clamp(0.05, 1.0);
    if !(per > 0.0) || !(o.leaf_area_m2 > 0.0) {
        return 0;
    }
    ((o.leaf_area_m2 / per).round() as usize).min(HERO_MAX_LEAVES)
}

/// Individual leaves for a close-up (issue 32, round 43: a 100-year beech of `sylva tree grow`
/// carried 98 % of its leaf area on leaf-cluster cards): the crown's whole leaf area
/// `o.leaf_area_m2` as [`hero_leaf_count`] cards of the species' leaf length, each a leaf
/// ([`leaf_mesh`]'s card), so that Σ ½ size² · cover is the leaf area (exactly, unless
/// [`HERO_MAX_LEAVES`] cuts the count: then the cards are lengthened to carry it).
///
/// **Where.** Every leaf card of `anchors` (the grown model's own leaves, on its shoots with
/// its leaf distribution) becomes a flat spray of current-year shoots, as the leaves of beech,
/// hornbeam or lime are held in layers (the skeleton's few thousand nodes stand for a crown's
/// hundred thousand shoots): a spray axis along the anchor's shoot (its node's segment) laid
/// into the spray's plane (below), √m
/// shoots (m the anchor's leaves) branching from it alternately left and right at 45° in the
/// spray's plane, 0.8 leaf lengths apart, carrying 1.3 to 0.5 of the mean √m leaves from the
/// spray's base to its tip (so a spray is about as wide as long); each shoot's leaves 0.45
/// leaf lengths apart, their azimuth round the shoot turning by `o.phyllotaxis_deg` leaf to
/// leaf, the blade at [`HERO_LEAF_ANGLE_DEG`] from the shoot on the side the azimuth points
/// to within the spray's plane. The leaves are shared equally among the anchors. Returns the
/// leaves and the twigs that carry them (each spray's axis and shoots, segments from base to
/// tip, for [`twig_mesh`]; none for sprays of fewer than [`HERO_TWIG_MIN_LEAVES`] leaves).
///
/// **Light.** A spray's plane faces the light its place in the crown gets: its normal is the
/// vertical leaned outwards by up to 40° in proportion to the anchor's distance from the stem
/// axis over the crown radius (the crown's outer leaves face the side sky, the inner ones
/// the zenith: planophile, as broadleaf canopies are, Pisek et al. 2011, Trees 25:919–924),
/// each leaf's blade turned about its own axis to face it, ± 15° hashed.
///
/// Leaves are kept within `o.crown_radius_m` of the stem axis (the root's vertical) by moving
/// them inwards, and out of the obstacles (`blocked(p)`: whether point `p` is inside one; a
/// tree adapted to a wall): a spray that would reach in is drawn in towards its anchor by the
/// largest of 1, 0.7, 0.5, 0.35, 0.25, 0.15 (else 0.1) that clears it, its leaves kept. Deterministic (hashes of `o.seed`, the anchor and the leaf). `node` of a leaf
/// is its anchor's. Empty for no anchors or no leaf area.
pub fn hero_leaves(sk: &Skeleton, anchors: &Leaves, o: &HeroLeafOptions, blocked: &dyn Fn(Vec3) -> bool) -> (Leaves, Vec<[Vec3; 2]>) {
    let n = hero_leaf_count(o);
    let na = anchors.leaves.len();
    let mut twigs = Vec::new();
    if n == 0 || na == 0 {
        return (Leaves::default(), twigs);
    }
    let per = 0.5 * o.leaf_length_m * o.leaf_length_m * o.card_cover.clamp(0.05, 1.0);
    // lengthened only where the count is capped
    let size = o.leaf_length_m * (o.leaf_area_m2 / (per * n as f32)).sqrt().max(1.0);
    let axis = sk.nodes.first().map_or(Vec3::ZERO, |r| r.pos);
    let rmax = o.crown_radius_m.max(0.05);
    let phyllo = o.phyllotaxis_deg.to_radians();
    let (leaf_angle, shoot_angle) = (HERO_LEAF_ANGLE_DEG.to_radians(), 45f32.to_radians());
    let mut out = Vec::with_capacity(n);
    twigs.reserve(na * 16);
    for (ai, a) in anchors.leaves.iter().enumerate() {
        let (out_from, twigs_from) = (out.len(), twigs.len());
        // this anchor's share of the leaves (the first `n % na` anchors one more)
        let m = n / na + usize::from(ai < n % na);
        if m == 0 {
            continue;
        }
        let h = |c: u64| crate::rng::unit_f32(crate::rng::hash(&[o.seed, 0x4e70_6c76, ai as u64, c]));
        let node = a.node as usize;
        let seg = sk.nodes.get(node).and_then(|nd| nd.parent.and_then(|p| sk.nodes.get(p as usize)).map(|par| nd.pos - par.pos)).unwrap_or(a.dir);
        let along = seg.normalize_or(a.dir.normalize_or(Vec3::X));
        // the light the place gets: up, leaned outwards with the distance from the stem axis
        let out_dir = (a.pos - axis).truncate();
        let rho = out_dir.length();
        let lean = 40f32.to_radians() * (rho / rmax).min(1.0);
        let outward = out_dir.normalize_or(glam::Vec2::X).extend(0.0);
        let light = (Vec3::Z * lean.cos() + outward * lean.sin()).normalize();
        // the spray's plane faces the light (a spray spreads across the light, as beech's
        // plagiotropic shoots do), its axis the anchor's shoot laid into that plane; a
        // hanging spray keeps its shoot's direction, its plane turned to face outwards
        let (np, along) = if o.pendulous {
            let mut n = outward - along * outward.dot(along);
            if n.length_squared() < 1e-4 {
                n = along.any_orthonormal_vector();
            }
            (n.normalize(), along)
        } else {
            let np = light;
            let mut flat = along - np * along.dot(np);
            if flat.length_squared() < 1e-4 {
                flat = outward - np * outward.dot(np);
            }
            (np, flat.normalize_or(np.any_orthonormal_vector()))
        };
        let across = np.cross(along).normalize_or(along.any_orthonormal_vector());
        // a hashed turn of the spray about its normal (± 20°)
        let turn = glam::Quat::from_axis_angle(np, (h(0) - 0.5) * 40f32.to_radians());
        let (along, across) = (turn * along, turn * across);
        // the spray: `ns` shoots of about √m leaves (so that it is about as wide as long),
        // alternately left and right along its axis 0.8 leaf lengths apart, the leaves per
        // shoot falling from 1.3 to 0.5 of the mean towards the spray's tip
        let q = ((m as f32).sqrt().round() as usize).clamp(3, 2 * HERO_LEAVES_PER_SHOOT);
        let ns = m.div_ceil(q);
        let w = |j: usize| 1.3 - 0.8 * j as f32 / (ns.max(2) - 1) as f32;
        let wsum: f32 = (0..ns).map(w).sum();
        let gap = 0.8 * o.leaf_length_m;
        let step = 0.45 * o.leaf_length_m;
        let within = |p: Vec3| {
            let d = (p - axis).truncate();
            let r = d.length();
            if r > rmax {
                (axis.truncate() + d * (rmax / r)).extend(p.z)
            } else {
                p
            }
        };
        // twigs only under sprays of a few leaves or more (a conifer's shoot cards, about
        // one a spray, are their own twigs)
        let twigged = m >= HERO_TWIG_MIN_LEAVES;
        if twigged {
            twigs.push([within(a.pos), within(a.pos + along * (gap * ns as f32))]);
        }
        let (mut given, mut acc) = (0usize, 0.0f32);
        for j in 0..ns {
            acc += w(j) / wsum * m as f32;
            let k_leaves = if j + 1 == ns { m - given } else { (acc.round() as usize).saturating_sub(given).min(m - given) };
            given += k_leaves;
            if k_leaves == 0 {
                continue;
            }
            let side = if j % 2 == 0 { 1.0 } else { -1.0 };
            let base = a.pos + along * (gap * (j as f32 + 0.5));
            let sdir = (along * shoot_angle.cos() + across * (side * shoot_angle.sin())).normalize();
            let sacross = np.cross(sdir).normalize_or(across);
            if twigged {
                twigs.push([within(base), within(base + sdir * (step * k_leaves as f32))]);
            }
            for i in 0..k_leaves {
                let hl = |c: u64| crate::rng::unit_f32(crate::rng::hash(&[o.seed, 0x4e70_6c77, ai as u64, j as u64, i as u64, c]));
                // the leaf's azimuth round the shoot, seen in the spray's plane: its side
                let az = (i as f32 * phyllo + h(1) * std::f32::consts::TAU).cos();
                let lside = if az.abs() < 0.2 { if i % 2 == 0 { 1.0 } else { -1.0 } } else { az.signum() };
                let dir = (sdir * leaf_angle.cos() + sacross * (lside * leaf_angle.sin())).normalize();
                // the blade faces the light, turned about its own axis by ± 15°
                let facing = (np - dir * np.dot(dir)).normalize_or(dir.any_orthonormal_vector());
                let normal = glam::Quat::from_axis_angle(dir, (hl(0) - 0.5) * 30f32.to_radians()) * facing;
                let pos = within(base + sdir * (step * (i as f32 + 0.5)));
                out.push(super::skeleton::Leaf { pos, dir, normal, size, node: a.node });
            }
        }
        // a spray that would reach into an obstacle is drawn in towards its anchor (its
        // leaves kept, closer together) by the largest of 1, 0.7, 0.5, … 0.1 that clears it
        let (l0, t0) = (out_from, twigs_from);
        let clears = |f: f32, out: &[super::skeleton::Leaf], twigs: &[[Vec3; 2]]| {
            let at = |p: Vec3| a.pos + (p - a.pos) * f;
            out[l0..].iter().all(|l| !blocked(at(l.pos)) && !blocked(at(l.pos) + l.dir * l.size)) && twigs[t0..].iter().all(|t| !blocked(at(t[0])) && !blocked(at(t[1])))
        };
        if !clears(1.0, &out, &twigs) {
            let f = [0.7f32, 0.5, 0.35, 0.25, 0.15].into_iter().find(|&f| clears(f, &out, &twigs)).unwrap_or(0.1);
            let at = |p: Vec3| a.pos + (p - a.pos) * f;
            out[l0..].iter_mut().for_each(|l| l.pos = at(l.pos));
            twigs[t0..].iter_mut().for_each(|t| *t = [at(t[0]), at(t[1])]);
        }
    }
    (Leaves { leaves: out }, twigs)
}

/// Fewest leaves of a spray for [`hero_leaves`] to give it twigs (4: a Norway spruce's
/// 120,000 needle-shoot cards, one a spray, got 1.2 M triangles of twigs without it).
pub const HERO_TWIG_MIN_LEAVES: usize = 4;

/// Radius (m) of the twigs [`hero_leaves`] gives a spray (its axis and shoots): 1.5 mm
/// (ESTIMATE: current-year beech shoots are 1–3 mm thick).
pub const HERO_TWIG_RADIUS_M: f32 = 0.0015;

/// The twigs of [`hero_leaves`]' sprays as bark: one triangular prism of radius `radius` (m)
/// per segment (3 sides, 6 triangles, open ends), UV u 0–1 around and v the length over
/// [`BARK_TILE_M`] (the bark texture's scale on the stems).
pub fn twig_mesh(twigs: &[[Vec3; 2]], radius: f32) -> TriMesh {
    let mut m = TriMesh::default();
    for &[a, b] in twigs {
        let t = (b - a).normalize_or(Vec3::Z);
        let (n0, n1) = (t.any_orthonormal_vector(), t.cross(t.any_orthonormal_vector()));
        let base = m.positions.len() as u32;
        let len = a.distance(b);
        for (end, v) in [(a, 0.0), (b, len / BARK_TILE_M)] {
            for k in 0..3 {
                let ang = k as f32 / 3.0 * TAU;
                let d = n0 * ang.cos() + n1 * ang.sin();
                m.positions.push((end + d * radius).to_array());
                m.normals.push(d.to_array());
                m.uvs.push([k as f32 / 3.0, v]);
            }
        }
        for k in 0..3u32 {
            let k1 = (k + 1) % 3;
            m.indices.extend_from_slice(&[base + k, base + k1, base + 3 + k1, base + k, base + 3 + k1, base + 3 + k]);
        }
    }
    m
}

/// Appends an axis-aligned-ish card: a quad centred at `c` spanned by half-vectors `u`, `v`.
pub(crate) fn quad(m: &mut TriMesh, c: Vec3, u: Vec3, v: Vec3) {
    let nrm = u.cross(v).normalize_or(Vec3::Z);
    let base = m.positions.len() as u32;
    for (p, uv) in [(c - u - v, [0.0, 0.0]), (c + u - v, [1.0, 0.0]), (c + u + v, [1.0, 1.0]), (c - u + v, [0.0, 1.0])] {
        m.positions.push(p.to_array());
        m.normals.push(nrm.to_array());
        m.uvs.push(uv);
    }
    m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
}

/// LOD1: keeps the thickest `reduced_keep_fraction` of nodes (by radius; the root always), and
/// replaces every cut subtree by a leaf-cluster blob of three crossed cards centred on its
/// leaves (or its nodes when leafless), sized by their spread plus one leaf length.
pub fn reduced_mesh(sk: &Skeleton, leaves: &Leaves, o: &LodOptions) -> TreeMesh {
    let n = sk.nodes.len();
    if n == 0 {
        return TreeMesh::default();
    }
    let mut radii: Vec<f32> = sk.nodes.iter().map(|n| n.radius).collect();
    radii.sort_by(|a, b| b.total_cmp(a));
    let keep_n = ((n as f32 * o.reduced_keep_fraction.clamp(0.0, 1.0)).ceil() as usize).clamp(2.min(n), n);
    let r_cut = radii[keep_n - 1];
    let mut keep = vec![false; n];
    let mut cluster = vec![u32::MAX; n];
    let mut n_clusters = 0u32;
    for i in 0..n {
        let node = &sk.nodes[i];
        match node.parent {
            None => keep[i] = true,
            Some(p) => {
                let p = p as usize;
                if keep[p] && node.radius >= r_cut {
                    keep[i] = true;
                } else if keep[p] {
                    cluster[i] = n_clusters;
                    n_clusters += 1;
                } else {
                    cluster[i] = cluster[p];
                }
            }
        }
    }
    let bark = branch_mesh(sk, o, Some(&keep));
    // accumulate cluster points
    let nc = n_clusters as usize;
    let mut sum = vec![Vec3::ZERO; nc];
    let mut sum2 = vec![0.0f32; nc];
    let mut cnt = vec![0u32; nc];
    let mut leaf_size = vec![0.0f32; nc];
    let mut add = |c: u32, p: Vec3, s: f32| {
        let c = c as usize;
        sum[c] += p;
        sum2[c] += p.length_squared();
        cnt[c] += 1;
        leaf_size[c] = leaf_size[c].max(s);
    };
    let mut has_leaf = vec![false; nc];
    for l in &leaves.leaves {
        let c = cluster.get(l.node as usize).copied().unwrap_or(u32::MAX);
        if c != u32::MAX {
            add(c, l.pos + l.dir * (0.5 * l.size), l.size);
            has_leaf[c as usize] = true;
        }
    }
    for i in 0..n {
        let c = cluster[i];
        if c != u32::MAX && !has_leaf[c as usize] {
            add(c, sk.nodes[i].pos, 0.0);
        }
    }
    let mut foliage = TriMesh::default();
    for c in 0..nc {
        if cnt[c] == 0 {
            continue;
        }
        let k = cnt[c] as f32;
        let mean = sum[c] / k;
        let var = (sum2[c] / k - mean.length_squared()).max(0.0);
        let r = var.sqrt() + 0.5 * leaf_size[c].max(1e-3);
        // three crossed cards (6 triangles)
        quad(&mut foliage, mean, Vec3::X * r, Vec3::Z * r);
        quad(&mut foliage, mean, Vec3::Y * r, Vec3::Z * r);
        quad(&mut foliage, mean, Vec3::X * r, Vec3::Y * r);
    }
    TreeMesh { bark, leaves: foliage }
}

/// Least half-width of a limb spray, relative to its length (a limb with all its foliage on
/// one line still reads as a spray of twigs, not a stick).
pub const SPRAY_MIN_WIDTH: f32 = 0.22;

/// LOD1 of a conifer (`LodOptions::conifer_tiers`): the main stem as a tube (the nodes of its
/// Gravelius order from the root, [`branch_mesh`]) and each first-order limb (a child of a
/// stem node off the stem) as a spray of two cards that follow the limb's foliage (its leaf
/// centres, or its nodes when leafless): a strip from the stem out to the limb's farthest
/// foliage along the limb's bearing, through the mean height of the foliage in its inner,
/// middle and outer thirds (so a Norway spruce's limbs droop and turn up at the tips as the
/// skeleton's do), widening from 0.35 of its half-width at the stem to the whole at the tip
/// (half-width: twice the standard deviation of the foliage across the bearing plus half a
/// leaf, at least [`SPRAY_MIN_WIDTH`] of the length), and a vertical strip along the same
/// line, so the spray shows from the side, as high as the foliage spreads about the line (twice
/// its standard deviation up and down plus a quarter leaf, at most half the width): a flat
/// spray stays a thin card and the whorls keep the sky between them. Foliage on the stem itself (the
/// leader) gets two crossed vertical cards. The limbs sit in the skeleton's whorls, so the
/// crown reads as tiers of drooping branches with gaps between them and a ragged outline,
/// the cards cut by the leaf-cluster texture (UV 0..1 across and along). 8 triangles per limb.
/// Issue 32, round 41: [`reduced_mesh`]'s crossed cluster cards (each cut subtree's spread
/// about its mean) overlapped into a smooth dark spire.
pub fn limb_spray_mesh(sk: &Skeleton, leaves: &Leaves, o: &LodOptions) -> TreeMesh {
    let n = sk.nodes.len();
    if n < 2 {
        return reduced_mesh(sk, leaves, o);
    }
    // stem nodes: the root's Gravelius order followed up from the root
    let mut on_stem = vec![false; n];
    let mut cur = Some(0usize);
    while let Some(i) = cur {
        if on_stem[i] {
            break;
        }
        on_stem[i] = true;
        cur = sk.nodes[i].children.iter().map(|&c| c as usize).find(|&c| c < n && sk.nodes[c].gravelius == sk.nodes[i].gravelius);
    }
    // limb of each node (u32::MAX: the stem); parents come before their children
    let mut limb = vec![u32::MAX; n];
    let mut bases: Vec<Vec3> = Vec::new();
    for i in 0..n {
        if on_stem[i] {
            continue;
        }
        match sk.nodes[i].parent {
            Some(p) if on_stem[p as usize] => {
                limb[i] = bases.len() as u32;
                bases.push(sk.nodes[p as usize].pos);
            }
            Some(p) => limb[i] = limb[p as usize],
            None => {}
        }
    }
    let nl = bases.len();
    let mut pts: Vec<Vec<(Vec3, f32)>> = vec![Vec::new(); nl];
    let mut leader: Vec<(Vec3, f32)> = Vec::new();
    let mut has_leaf = vec![false; nl];
    for l in &leaves.leaves {
        let c = l.pos + l.dir * (0.5 * l.size);
        match limb.get(l.node as usize) {
            Some(&k) if k != u32::MAX => {
                pts[k as usize].push((c, l.size));
                has_leaf[k as usize] = true;
            }
            Some(_) => leader.push((c, l.size)),
            None => {}
        }
    }
    for i in 0..n {
        let k = limb[i];
        if k != u32::MAX && !has_leaf[k as usize] {
            pts[k as usize].push((sk.nodes[i].pos, 0.0));
        }
    }
    let bark = branch_mesh(sk, o, Some(&on_stem));
    let mut foliage = TriMesh::default();
    for (k, ps) in pts.iter().enumerate() {
        let b = bases[k];
        let mean = ps.iter().fold(Vec3::ZERO, |a, p| a + p.0) / ps.len().max(1) as f32;
        let u = (mean - b).truncate().normalize_or_zero();
        if ps.is_empty() || u == glam::Vec2::ZERO {
            continue;
        }
        let u = u.extend(0.0);
        let v = Vec3::Z.cross(u);
        let len = ps.iter().map(|p| (p.0 - b).dot(u)).fold(0.0f32, f32::max);
        if !(len > 1e-5) {
            continue;
        }
        let leaf = ps.iter().map(|p| p.1).fold(0.0f32, f32::max);
        let side_sd = (ps.iter().map(|p| (p.0 - b).dot(v).powi(2)).sum::<f32>() / ps.len() as f32).sqrt();
        let hw = (2.0 * side_sd + 0.5 * leaf).max(SPRAY_MIN_WIDTH * len);
        // mean foliage height (relative to the base) in the inner, middle and outer thirds
        let mut zs = [(0.0f32, 0u32); 3];
        for p in ps {
            let t = ((p.0 - b).dot(u) / len * 3.0).clamp(0.0, 2.999) as usize;
            zs[t].0 += p.0.z - b.z;
            zs[t].1 += 1;
        }
        let outer = if zs[2].1 > 0 { zs[2].0 / zs[2].1 as f32 } else { ps.iter().map(|p| p.0.z - b.z).sum::<f32>() / ps.len() as f32 };
        let mid = if zs[1].1 > 0 { zs[1].0 / zs[1].1 as f32 } else { 0.5 * outer };
        let line = [b, b + u * (0.5 * len) + Vec3::Z * mid, b + u * len + Vec3::Z * outer];
        // the foliage's spread about the line, up and down: a flat spray is a thin card from
        // the side, and the whorl above stays apart from it
        let line_z = |t: f32| if t < 0.5 { mid * t / 0.5 } else { mid + (outer - mid) * (t - 0.5) / 0.5 };
        let up_sd = (ps.iter().map(|p| (p.0.z - b.z - line_z(((p.0 - b).dot(u) / len).clamp(0.0, 1.0))).powi(2)).sum::<f32>() / ps.len() as f32).sqrt();
        let vh = (2.0 * up_sd + 0.25 * leaf).min(0.5 * hw);
        let widths = [0.35 * hw, 0.7 * hw, hw];
        spray_strip(&mut foliage, &line, &widths, v, Vec3::Z);
        spray_strip(&mut foliage, &line, &[0.35 * vh, 0.7 * vh, vh], Vec3::Z, v);
    }
    if !leader.is_empty() {
        let (lo, hi) = leader.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p.0.z), hi.max(p.0.z)));
        let leaf = leader.iter().map(|p| p.1).fold(0.0f32, f32::max);
        let r0 = sk.nodes[0].pos.truncate();
        let reach = leader.iter().map(|p| (p.0.truncate() - r0).length()).fold(0.0f32, f32::max) + 0.5 * leaf;
        let (lo, hi) = (lo - 0.5 * leaf, hi + 0.5 * leaf);
        let c = Vec3::new(r0.x, r0.y, 0.5 * (lo + hi));
        let half = (0.5 * (hi - lo)).max(1e-4);
        quad(&mut foliage, c, Vec3::X * reach.max(1e-4), Vec3::Z * half);
        quad(&mut foliage, c, Vec3::Y * reach.max(1e-4), Vec3::Z * half);
    }
    TreeMesh { bark, leaves: foliage }
}

/// Two leaf cards along the polyline `line` (3 points): one from the first point to the
/// second, one from the second to the third, each a quad of half-widths `widths` at its ends
/// across `side`, its normal turned to the side of `up`; UV (0,0), (1,0), (1,1), (0,1) from
/// the inner end (cards, as `quad` makes them, so the renderer cuts them with the leaf-cluster
/// texture).
fn spray_strip(m: &mut TriMesh, line: &[Vec3; 3], widths: &[f32; 3], side: Vec3, up: Vec3) {
    for j in 0..2 {
        let (a, b) = (line[j], line[j + 1]);
        let nrm = side.cross(b - a).normalize_or(up);
        let nrm = if nrm.dot(up) < 0.0 { -nrm } else { nrm };
        let base = m.positions.len() as u32;
        for (p, uv) in [(a - side * widths[j], [0.0, 0.0]), (a + side * widths[j], [1.0, 0.0]), (b + side * widths[j + 1], [1.0, 1.0]), (b - side * widths[j + 1], [0.0, 1.0])] {
            m.positions.push(p.to_array());
            m.normals.push(nrm.to_array());
            m.uvs.push(uv);
        }
        m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
}

/// Foliage points of a tree: leaf centres, or tip nodes when there are no leaves.
fn foliage_points(sk: &Skeleton, leaves: &Leaves) -> Vec<Vec3> {
    if leaves.is_empty() {
        sk.nodes.iter().filter(|n| n.children.is_empty()).map(|n| n.pos).collect()
    } else {
        leaves.leaves.iter().map(|l| l.pos + l.dir * (0.5 * l.size)).collect()
    }
}

fn bounds(pts: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *pts.first()?;
    Some(pts.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
}

/// Heights of the rings of the LOD2 crown hull ([`hull_mesh`]), as fractions of the crown's
/// length from its lowest (3rd-percentile) to its highest foliage point: six rings (as many as
/// round 45's three bands and three dome rings, so the level keeps its 96 foliage triangles at
/// 8 sectors), closed by a point on the stem at the crown's bottom and an apex over its highest
/// foliage point. Spread over the whole crown, with the top ring at 0.95, the hull's outline
/// is the crown's own from its base to its top (issue 32, round 46): a spruce's rings narrow to
/// a spire, a Scots pine's widen to a flat top, a beech's round off; round 45's three bands with
/// dome rings at 45° and 75° above the top band drew every crown as a rounded egg.
pub const HULL_RING_HEIGHTS: [f32; 6] = [0.04, 0.22, 0.42, 0.62, 0.8, 0.95];

/// LOD2: a low-poly crown hull that follows the full-detail tree's own outline, per height and
/// azimuth (issue 32, round 46): the crown from the 3rd percentile of its foliage heights (leaf
/// centres, or tips) to its highest foliage point carries six rings at [`HULL_RING_HEIGHTS`] and
/// `hull_segments` (≥ 3) azimuth sectors around the skeleton's main stem where it crosses the
/// ring ([`main_stem`]; above the stem's tip, around its tip; round 34: a leaning crown's rings
/// follow the lean). A ring's radius in a sector is the support function of the foliage in the
/// ring's slab (from half-way to the ring below to half-way to the ring above; the lowest slab
/// from the crown's bottom, the highest to its top) along the sector's middle direction: the
/// farthest horizontal reach of that foliage (m), at least 2 % of the crown radius; a slab
/// without foliage takes the mean of the slabs beside it ([`fill_empty_bands`]); then one
/// smoothing pass along each ring (½ the radius, ¼ each neighbour), none across rings, so the
/// crown keeps its profile by height and its lumps by azimuth. A fan closes the hull to a point
/// on the stem at the crown's bottom and to an apex over the highest foliage point at its
/// height: a conifer's top is a spire, a flat-topped crown's a low cone over its widest ring.
/// Crowns made one-sided by a neighbour or a wall (Plastic Trees) stay one-sided. Normals are
/// area-weighted face normals, outward. Sits on a 5-sided trunk ([`hull_stem`]) that follows
/// the main stem from the root to a quarter of the way up the crown. `2 · hull_segments · 6`
/// foliage triangles (96 at the default 8).
pub fn hull_mesh(sk: &Skeleton, leaves: &Leaves, o: &LodOptions) -> TreeMesh {
    let mut pts = foliage_points(sk, leaves);
    let Some((mut lo, mut hi)) = bounds(&pts) else { return TreeMesh::default() };
    // the crown spans the 3rd percentile of foliage height (a few low leaves on the trunk,
    // epicormic shoots, do not stretch the hull down it) to the highest foliage point: the
    // levels beside it reach the crown's top (round 39: a hull stopping short left a dotted cap
    // in the cross-fade)
    let mut zs: Vec<f32> = pts.iter().map(|p| p.z).collect();
    zs.sort_by(f32::total_cmp);
    lo.z = zs[(zs.len() * 3 / 100).min(zs.len() - 1)];
    hi.z = zs[zs.len() - 1].max(lo.z + 1e-3);
    pts.retain(|p| p.z >= lo.z && p.z <= hi.z);
    let top_xy = pts.iter().copied().fold(Vec3::new(0.0, 0.0, f32::MIN), |a, p| if p.z > a.z { p } else { a });
    let c = 0.5 * (lo + hi);
    let r = (0.5 * (hi - lo)).max(Vec3::splat(1e-3));
    let nlon = o.hull_segments.max(3) as usize;
    let f = HULL_RING_HEIGHTS;
    let nb = f.len();
    let (z0, dz) = (lo.z, (hi.z - lo.z).max(1e-3));
    let ring_z = |b: usize| z0 + f[b] * dz;
    // slab edges (fractions): half-way between rings, the crown's ends outside
    let edge = |b: usize| if b == 0 { 0.0 } else if b == nb { 1.0 } else { 0.5 * (f[b - 1] + f[b]) };
    let slab_of = |z: f32| {
        let t = (z - z0) / dz;
        (1..nb).take_while(|&b| t >= edge(b)).count()
    };
    // each ring's axis is the main stem where it crosses the ring (a leaning stem carries its
    // crown: the rings follow it rather than a vertical line over the root)
    let stem = main_stem(sk);
    let axis_at = |z: f32| stem_xy_at(&stem, z).map_or(Vec3::new(c.x, c.y, z), |v| v.extend(z));
    let ring_axis: Vec<Vec3> = (0..nb).map(|b| axis_at(ring_z(b))).collect();
    // support function per (slab, sector): the farthest reach of the slab's foliage along the
    // sector's direction (< 0: an empty slab)
    let dirs: Vec<(f32, f32)> = (0..nlon).map(|k| ((k as f32 + 0.5) / nlon as f32 * TAU).sin_cos()).map(|(s, c)| (c, s)).collect();
    let mut rad = vec![-1.0f32; nb * nlon];
    for p in &pts {
        let b = slab_of(p.z).min(nb - 1);
        let d = (*p - ring_axis[b]).truncate();
        for (k, &(cx, cy)) in dirs.iter().enumerate() {
            let cell = &mut rad[b * nlon + k];
            *cell = cell.max(d.x * cx + d.y * cy);
        }
    }
    let floor = 0.02 * r.x.max(r.y);
    for b in 0..nb {
        if (0..nlon).any(|k| rad[b * nlon + k] >= 0.0) {
            for k in 0..nlon {
                // a one-sided slab: the far side closes in near the axis
                rad[b * nlon + k] = rad[b * nlon + k].max(floor);
            }
        }
    }
    let filled: Vec<bool> = (0..nb).map(|b| rad[b * nlon] >= 0.0).collect();
    fill_empty_bands(&mut rad, nlon, &filled, r.x.max(r.y));
    // one smoothing pass along each ring (the profile by height is kept as measured)
    let src = rad.clone();
    for b in 0..nb {
        for k in 0..nlon {
            let at = |kk: usize| src[b * nlon + kk % nlon];
            rad[b * nlon + k] = (0.5 * at(k) + 0.25 * (at(k + 1) + at(k + nlon - 1))).max(1e-3);
        }
    }
    let rings: Vec<(f32, Vec3, Vec<f32>)> = (0..nb).map(|b| (ring_z(b), ring_axis[b], rad[b * nlon..(b + 1) * nlon].to_vec())).collect();
    let hull = ring_hull(&rings, nlon, top_xy.with_z(hi.z), axis_at(lo.z).with_z(lo.z));
    // trunk: a quarter of the way up into the crown, so the hull sits on it
    TreeMesh { bark: hull_stem(sk, c.z - 0.5 * r.z, o), leaves: hull }
}

/// The closed mesh of a ring hull ([`hull_mesh`], [`super::crown_hull::cluster_hull_mesh`]):
/// `rings` from the bottom up, each (height (m), axis point (m; its x, y centre the ring),
/// `nlon` radii (m) at azimuths (k + ½)/`nlon` · 2π), closed by a fan to `base` below the first
/// ring and to `apex` above the last. UV: u = k / `nlon`, v = (ring + ½) / rings (0.5, 1 at the
/// apex and 0.5, 0 at the base); area-weighted face normals, outward (counter-clockwise seen
/// from outside for radii > 0). `nlon` (≥ 3) · rings + 2 vertices, 2 · `nlon` · rings
/// triangles.
pub(crate) fn ring_hull(rings: &[(f32, Vec3, Vec<f32>)], nlon: usize, apex: Vec3, base: Vec3) -> TriMesh {
    let nr = rings.len();
    let mut hull = TriMesh::default();
    for (j, (z, axis, rr)) in rings.iter().enumerate() {
        for (k, &r_k) in rr.iter().enumerate() {
            let a = (k as f32 + 0.5) / nlon as f32 * TAU;
            hull.positions.push([axis.x + r_k * a.cos(), axis.y + r_k * a.sin(), *z]);
            hull.uvs.push([k as f32 / nlon as f32, (j as f32 + 0.5) / nr as f32]);
        }
    }
    let (apex_i, base_i) = (hull.positions.len() as u32, hull.positions.len() as u32 + 1);
    hull.positions.push(apex.to_array());
    hull.positions.push(base.to_array());
    hull.uvs.extend_from_slice(&[[0.5, 1.0], [0.5, 0.0]]);
    let v = |b: usize, k: usize| (b * nlon + k % nlon) as u32;
    for k in 0..nlon {
        hull.indices.extend_from_slice(&[base_i, v(0, k + 1), v(0, k)]);
        for b in 0..nr - 1 {
            hull.indices.extend_from_slice(&[v(b, k), v(b, k + 1), v(b + 1, k + 1), v(b, k), v(b + 1, k + 1), v(b + 1, k)]);
        }
        hull.indices.extend_from_slice(&[v(nr - 1, k), v(nr - 1, k + 1), apex_i]);
    }
    let mut nrm = vec![Vec3::ZERO; hull.positions.len()];
    for t in hull.indices.chunks_exact(3) {
        let [a, b, c2] = [t[0], t[1], t[2]].map(|i| Vec3::from(hull.positions[i as usize]));
        let f = (b - a).cross(c2 - a);
        for &i in t {
            nrm[i as usize] += f;
        }
    }
    hull.normals = nrm.iter().map(|n| n.normalize_or(Vec3::Z).to_array()).collect();
    hull
}

/// The skeleton's main stem: the root and then, from each node, its first child of the same
/// Gravelius order (the stem's continuation, not a limb: [`Skeleton::add_child`],
/// [`Skeleton::recompute_orders`]), up to the stem's tip; positions and radii (m, the
/// skeleton's frame). Empty for an empty skeleton.
pub(crate) fn main_stem(sk: &Skeleton) -> Vec<(Vec3, f32)> {
    let mut out = Vec::new();
    let mut cur = if sk.nodes.is_empty() { None } else { Some(0usize) };
    while let Some(i) = cur {
        let n = &sk.nodes[i];
        out.push((n.pos, n.radius));
        cur = n.children.iter().map(|&c| c as usize).find(|&c| c < sk.nodes.len() && c != i && sk.nodes[c].gravelius == n.gravelius);
        if out.len() > sk.nodes.len() {
            break;
        }
    }
    out
}

/// Horizontal position (x, y; m) of the main stem `stem` ([`main_stem`]) at height `z`:
/// interpolated between the two stem points around `z`; below the root the root's, above the
/// stem's highest point that point's. The stem's heights need not rise monotonically (a
/// bent stem): the first stretch that crosses `z` counts.
pub(crate) fn stem_xy_at(stem: &[(Vec3, f32)], z: f32) -> Option<glam::Vec2> {
    let (first, last) = (stem.first()?.0, stem.iter().map(|p| p.0).fold(stem[0].0, |a, p| if p.z > a.z { p } else { a }));
    if z <= first.z {
        return Some(first.truncate());
    }
    for w in stem.windows(2) {
        let (a, b) = (w[0].0, w[1].0);
        if (a.z <= z && z <= b.z) || (b.z <= z && z <= a.z) {
            let t = if (b.z - a.z).abs() < 1e-6 { 0.0 } else { (z - a.z) / (b.z - a.z) };
            return Some(a.truncate().lerp(b.truncate(), t));
        }
    }
    Some(last.truncate())
}

/// Most segments of the crown-hull level's stem ([`hull_stem`]): 3 (rounds 34–44: 6). The
/// level is drawn at 18–45 px in the stills, its stem a quarter of the way up the crown a few
/// pixels long and about one wide: three segments follow a leaning or bent stem's lean within
/// a pixel and cost 30 triangles instead of 60 (issue 32, round 45).
pub const HULL_STEM_SEGMENTS: usize = 3;

/// The stem of the crown-hull level: a 5-sided tapered tube (radius that of the root, or of its
/// first child when larger, tapering to 70 % at the top; with [`LodOptions::stem`] the taper's
/// radius at each of its points) that follows the skeleton's main stem
/// ([`main_stem`]) from the root up to height `top_z` (m, same frame; at least 1 mm above the
/// root), through at most [`HULL_STEM_SEGMENTS`] of its points spread evenly along it, so a
/// leaning or bent stem carries the hull where the crown is (round 34; until then the tube
/// stood straight up from the root under a leaning crown). Where the stem ends below `top_z`
/// the tube goes on straight up from its tip. Empty for an empty skeleton.
pub(crate) fn hull_stem(sk: &Skeleton, top_z: f32, o: &LodOptions) -> TriMesh {
    hull_stem_of(sk, top_z, o, HULL_STEM_SEGMENTS)
}

/// [`hull_stem`] through at most `segments` (≥ 1) of the stem's points (rounds 34–44 drew
/// 6; `tests/structure_mesh.rs` compares the level with that one).
pub fn hull_stem_of(sk: &Skeleton, top_z: f32, o: &LodOptions, segments: usize) -> TriMesh {
    let segments = segments.max(1);
    let mut bark = TriMesh::default();
    let Some(root) = sk.nodes.first() else { return bark };
    let top_z = top_z.max(root.pos.z + 1e-3);
    let rr = root.radius.max(sk.nodes.get(1).map(|n| n.radius).unwrap_or(0.0));
    // the stem's points below top_z, then the point at top_z (interpolated, or straight above
    // the stem's tip)
    let stem = main_stem(sk);
    let mut pts: Vec<Vec3> = vec![root.pos];
    for w in stem.windows(2) {
        let (a, b) = (w[0].0, w[1].0);
        if b.z >= top_z {
            let t = if b.z - a.z > 1e-6 { ((top_z - a.z) / (b.z - a.z)).clamp(0.0, 1.0) } else { 1.0 };
            pts.push(a.lerp(b, t).with_z(top_z));
            break;
        }
        pts.push(b);
    }
    let last = *pts.last().unwrap_or(&root.pos);
    if last.z < top_z - 1e-4 {
        pts.push(last.with_z(top_z));
    }
    // at most `segments` segments, points spread evenly along the stem (ends kept)
    let n = pts.len();
    let keep: Vec<Vec3> = if n - 1 <= segments { pts } else { (0..=segments).map(|k| pts[(k * (n - 1) + segments / 2) / segments]).collect() };
    // with a taper (LodOptions::stem) the tube takes the taper's radius at each point (no
    // rings added: the level stays cheap); else the root's radius tapering to 70 % at the top
    let dz = (top_z - root.pos.z).max(1e-3);
    let r_at = |p: Vec3| match o.stem {
        Some(st) => st.radius_in_frame(p.z - root.pos.z).max(1e-4),
        None => rr * (1.0 - 0.3 * ((p.z - root.pos.z) / dz).clamp(0.0, 1.0)),
    };
    let mut t = Skeleton::new();
    let mut parent = t.add_root(keep[0], r_at(keep[0]));
    for p in keep.iter().skip(1) {
        match t.add_child(parent, *p, r_at(*p), false) {
            Ok(id) => parent = id,
            Err(_) => return bark,
        }
    }
    if t.nodes.len() >= 2 {
        bark = branch_mesh(&t, &LodOptions { sides: 5, min_sides: 5, stem: None, ..*o }, None);
    }
    bark
}

/// A quad like [`quad`] whose UVs run from `uv0` (corner `c − u − v`) to `uv1` (corner
/// `c + u + v`), both in 0–1.
fn quad_uv(m: &mut TriMesh, c: Vec3, u: Vec3, v: Vec3, uv0: [f32; 2], uv1: [f32; 2]) {
    let base = m.uvs.len();
    quad(m, c, u, v);
    for t in &mut m.uvs[base..] {
        *t = [uv0[0] + t[0] * (uv1[0] - uv0[0]), uv0[1] + t[1] * (uv1[1] - uv0[1])];
    }
}

/// LOD3: billboard impostor, per crossed vertical plane (x–z and y–z) a crown quad and a trunk
/// quad, leaf material, UVs within 0–1, v up (8 triangles; 4 when the crown reaches the root).
///
/// The crown quad spans the tree's own crown: from its lowest to its highest foliage point
/// (leaf tips, or branch tips when leafless) mapped to v [`IMPOSTOR_CROWN_V`]–0.98 of
/// [`crate::structure::texture::impostor_texture`] (the quad runs on to v 1), and horizontally
/// the foliage's extent along the plane, centred on the foliage's centre (a leaning crown is
/// drawn where it is), mapped to u 0.04–0.96 (the texture crown's width). The trunk quad runs
/// from the root (its foot centred on the root) up to the crown base under the crown's centre
/// (slanted for a leaning crown), as wide as the root's diameter (at
/// most 15 % of the crown's width, at least 2 cm), mapped to the texture's trunk column
/// ([`IMPOSTOR_TRUNK_U`], v 0–0.05, trunk only). Empty for a tree without nodes.
pub fn impostor_mesh(sk: &Skeleton, leaves: &Leaves) -> TreeMesh {
    let Some(root) = sk.nodes.first() else { return TreeMesh::default() };
    let Some((lo, hi)) = bounds(&foliage_points(sk, leaves)) else { return TreeMesh::default() };
    let r = root.pos;
    let base = lo.z.max(r.z);
    let top = hi.z.max(base + 1e-3);
    // foliage z [base, top] ↔ v [IMPOSTOR_CROWN_V, 0.98]; the quad runs on to v 1
    let per_v = (top - base) / (0.98 - IMPOSTOR_CROWN_V);
    let crown_top = top + 0.02 * per_v;
    let crown_h = 0.5 * (crown_top - base);
    let c = Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), base + crown_h);
    // foliage extent ↔ u 0.04–0.96
    let half = |e: f32| (0.5 * e / 0.92).max(1e-3);
    let (hx, hy) = (half(hi.x - lo.x), half(hi.y - lo.y));
    let mut m = TriMesh::default();
    let crown_uv = ([0.0, IMPOSTOR_CROWN_V], [1.0, 1.0]);
    quad_uv(&mut m, c, Vec3::X * hx, Vec3::Z * crown_h, crown_uv.0, crown_uv.1);
    quad_uv(&mut m, c, Vec3::Y * hy, Vec3::Z * crown_h, crown_uv.0, crown_uv.1);
    if base > r.z + 1e-3 {
        let rr = root.radius.max(sk.nodes.get(1).map(|n| n.radius).unwrap_or(0.0));
        let tw = rr.max(0.02).min(0.15 * hx.min(hy));
        // foot centred on the root, head under the crown's centre (a leaning tree's trunk
        // slants to its crown rather than standing apart from it)
        let head = Vec3::new(c.x, c.y, base);
        let (tc, tv) = ((r + head) * 0.5, (head - r) * 0.5);
        let trunk_uv = ([IMPOSTOR_TRUNK_U[0], 0.0], [IMPOSTOR_TRUNK_U[1], 0.05]);
        quad_uv(&mut m, tc, Vec3::X * tw, tv, trunk_uv.0, trunk_uv.1);
        quad_uv(&mut m, tc, Vec3::Y * tw, tv, trunk_uv.0, trunk_uv.1);
    }
    TreeMesh { bark: TriMesh::default(), leaves: m }
}

/// The full-detail tree mesh (LOD0): tubes plus leaf cards.
pub fn full_mesh(sk: &Skeleton, leaves: &Leaves, o: &LodOptions) -> TreeMesh {
    TreeMesh { bark: branch_mesh(sk, o, None), leaves: if o.leaves { leaf_mesh(leaves) } else { TriMesh::default() } }
}

/// The LOD chain: `[full, reduced, hull, impostor]` (triangle counts via
/// `TreeMesh::triangle_count`, decreasing along the chain for any tree with more than a few
/// dozen nodes).
pub fn lod_chain(sk: &Skeleton, leaves: &Leaves, o: &LodOptions) -> LodChain {
    let reduced = if o.conifer_tiers { limb_spray_mesh(sk, leaves, o) } else { reduced_mesh(sk, leaves, o) };
    let levels: [TreeMesh; LOD_LEVELS] = [full_mesh(sk, leaves, o), reduced, hull_mesh(sk, leaves, o), impostor_mesh(sk, leaves)];
    LodChain::new(levels.into())
}

/// Fills the empty height bands of a hull's radii `rad` (`filled.len()` bands of `nlon`
/// directions each, band-major): each direction of an empty band takes the mean of the nearest
/// filled bands below and above it, or `none` (m) when no band is filled. Used by the LOD2
/// crown hull of leaf cards (here) and of adapted leaf clusters
/// ([`crate::structure::crown_hull`]).
pub(crate) fn fill_empty_bands(rad: &mut [f32], nlon: usize, filled: &[bool], none: f32) {
    let nb = filled.len();
    for b in 0..nb {
        if filled[b] {
            continue;
        }
        let below = (0..b).rev().find(|&j| filled[j]);
        let above = (b + 1..nb).find(|&j| filled[j]);
        for k in 0..nlon {
            let v: Vec<f32> = [below, above].iter().flatten().map(|&j| rad[j * nlon + k]).collect();
            rad[b * nlon + k] = if v.is_empty() { none } else { v.iter().sum::<f32>() / v.len() as f32 };
        }
    }
}

