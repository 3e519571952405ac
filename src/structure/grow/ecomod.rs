//! EcoMod strand model (Zamuda, Brest, Guid & Žumer, `004_*.txt`, Algorithm 1, eqs. 1–6), after
//! Holton's strands (1994).
//!
//! Every branch segment carries S₀ strands; it has diameter d = k_d·√S₀ (Algorithm 1, "thickness
//! calculation from Mandelbrot"), and unless S₀ = 1 (a leaf-bearing tip) it splits into a major
//! sub-branch with S₁ = ⌈1 + k_s^{g,w}(S₀ − 2)⌉ strands and a minor one with S₂ = S₀ − S₁, so
//! strands are conserved and a tree of S strands has exactly 2S − 1 segments.
//!
//! Interpretation notes (the paper leaves these open):
//! - Coordinates: the paper's branch axis y is mapped to the local frame's second column; the
//!   trunk starts vertical (Sylva z up).
//! - The major sub-branch turns by +α₁ and the minor by −α₂ about the local z axis, so that
//!   α₁ + α₂ = α^{g,w} is the angle between them.
//! - Sub-branch actual length l_i = k_l^{g,w}·L_i (metres; L is relative, 1 for the trunk whose
//!   actual length is l₀^{0,0} = `trunk_length_m`).
//! - Directed wind R_{w₀}(α_w) is a rotation about the wind vector w (the paper's w = [0 1 0]ᵀ,
//!   its up axis, here world z), by α_w = (S₀/S)·w_g degrees.
//! - Gravimorphism R_{y×y_m}(α_m) turns the branch towards the vertical by α_m (negative: droops).
//! - Undirected wind α_x(t), α_z(t) = sin(t + R)·w_s·(1 − k_f)·l₀ degrees with a random phase R
//!   per segment.
//! - Posture limits (ours, so that published parameter sets give upright trees above the
//!   ground): the trunk's continuation tilts at most [`TRUNK_MAX_TILT_DEG`] from the vertical,
//!   branch axes droop at most [`MAX_DROOP_DEG`] below the horizontal, and no segment ends
//!   below z = 0.
//! - Leaves: ⌈ρ_l⌉ leaves of length l_l per tip segment, arranged by the leaf distribution.
//! - Whorled stems (ours; `[architecture.ecomod.whorls]`, [`crate::species::Whorls`]): Algorithm
//!   1 sets one branch on the stem at each split; a conifer sets a whorl of several at the top of
//!   each annual shoot of its leader, and interwhorl branches along it. With `whorls`, each split
//!   of the stem stands for an annual shoot: the strands Algorithm 1 gives its one branch are
//!   shared among the shoot's interwhorl and whorl branches, set one a split (so S strands still
//!   make 2S − 1 segments) along the shoot's length (Algorithm 1's segment length) and spread
//!   evenly about the stem; the Weibull order rises once a shoot. A whorl branch, with a share of
//!   the strands, would make fewer splits along its axis and so stay shorter than the one branch
//!   it replaces (the crown a cylinder of short limbs under a few long ones): every branch of the
//!   shoot is lengthened (its L) by the ratio of the reach of an axis of the shoot's branch
//!   strands to one of a whorl branch's (Algorithm 1's own recursion, `axis_reach`).

use crate::error::{Error, Result};
use crate::rng::{salt, Stream};
use crate::species::{CrownProfile, EcoModParams, Fork, LeafDistribution, Limbs, Whorls, WHORL_SEGMENT};
use crate::structure::params::eval_polyline;
use crate::structure::skeleton::{Leaf, Leaves, NodeId, Role, Skeleton};
use glam::{Mat3, Vec3};

/// Largest number of strands accepted (a tree of S strands has 2S nodes).
pub const MAX_STRANDS: u32 = 2_000_000;

/// Local parameters at orders (g, w), eqs. (1)–(6) of `004_*.txt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalParams {
    /// k_s^{g,w} ∈ [½, 1] (eq. 1).
    pub k_s: f32,
    /// α^{g,w} (degrees) ∈ [0, 180] (eq. 2).
    pub alpha: f32,
    /// α_m^{g,w} (degrees) ∈ [−180, 180] (eq. 3).
    pub alpha_m: f32,
    /// M^{g,w} (eq. 4).
    pub max_len: f32,
    /// k_l^{g,w} (eq. 5).
    pub k_l: f32,
    /// m^{g,w} (eq. 6).
    pub min_len: f32,
}

/// Evaluates eqs. (1)–(6) of `004_*.txt` at Gravelius order `g` and Weibull order `w`.
pub fn local_params(p: &EcoModParams, g: u32, w: u32) -> LocalParams {
    let (g, w) = (g as f32, w as f32);
    let e = eval_polyline;
    LocalParams {
        k_s: (e(&p.ks_g, g) * e(&p.ks_w, w)).min(1.0).max(0.5),
        alpha: (e(&p.alpha_g, g) * e(&p.alpha_w, w)).min(180.0),
        alpha_m: (e(&p.alpha_m_g, g) * e(&p.alpha_m_w, w)).clamp(-180.0, 180.0),
        max_len: e(&p.max_len_g, g) * e(&p.max_len_w, w),
        k_l: e(&p.kl_g, g) * e(&p.kl_w, w),
        min_len: e(&p.min_len_g, g) * e(&p.min_len_w, w),
    }
}

/// Strand split of Algorithm 1: `(S₁, S₂)` with S₁ = ⌈1 + k_s(S₀ − 2)⌉, S₂ = S₀ − S₁, for S₀ ≥ 2.
pub fn split_strands(s0: u32, k_s: f32) -> (u32, u32) {
    let s1 = (1.0 + k_s as f64 * (s0 as f64 - 2.0)).ceil().clamp(1.0, (s0 - 1) as f64) as u32;
    (s1, s0 - s1)
}

fn check(p: &EcoModParams) -> Result<()> {
    let bad = |f: &str, v: String, e: &str| Err(Error::Invalid { context: "EcoMod parameters".into(), field: f.into(), value: v, expected: e.into() });
    if p.strands == 0 || p.strands > MAX_STRANDS {
        return bad("strands", p.strands.to_string(), "1 ..= 2000000 strands");
    }
    let scalars = [
        ("trunk_length_m", p.trunk_length_m),
        ("k_d", p.k_d),
        ("k_c", p.k_c),
        ("phyllotaxis_deg", p.phyllotaxis_deg),
        ("leaf_density", p.leaf_density),
        ("leaf_size_m", p.leaf_size_m),
        ("wind_directed", p.wind_directed),
        ("wind_undirected", p.wind_undirected),
        ("k_f", p.k_f),
    ];
    for (f, v) in scalars {
        if !v.is_finite() || v < 0.0 && f != "phyllotaxis_deg" {
            return bad(f, v.to_string(), "a finite number ≥ 0");
        }
    }
    if p.leaf_density > 1000.0 {
        return bad("leaf_density", p.leaf_density.to_string(), "0 ..= 1000 leaves per tip (paper: 0–30)");
    }
    for (f, l) in [("ks_g", &p.ks_g), ("ks_w", &p.ks_w), ("alpha_g", &p.alpha_g), ("alpha_w", &p.alpha_w), ("alpha_m_g", &p.alpha_m_g), ("alpha_m_w", &p.alpha_m_w), ("max_len_g", &p.max_len_g), ("max_len_w", &p.max_len_w), ("kl_g", &p.kl_g), ("kl_w", &p.kl_w), ("min_len_g", &p.min_len_g), ("min_len_w", &p.min_len_w)] {
        for (i, q) in l.iter().enumerate() {
            if !q[0].is_finite() || !q[1].is_finite() || (i > 0 && q[0] < l[i - 1][0]) {
                return bad(f, format!("{:?}", q), "finite control points with non-decreasing abscissae");
            }
        }
    }
    Ok(())
}

/// Rotation about a world axis (unit or not; a zero axis gives the identity), angle in degrees.
fn rot(axis: Vec3, deg: f32) -> Mat3 {
    let a = axis.normalize_or_zero();
    if a == Vec3::ZERO || deg == 0.0 {
        Mat3::IDENTITY
    } else {
        Mat3::from_axis_angle(a, deg.to_radians())
    }
}

/// Options of [`grow_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EcoModOptions {
    /// Directed wind vector w (the paper: [0 1 0]ᵀ in its y-up frame = world up).
    pub wind: Vec3,
    /// Animation time t (radians of the sway phase).
    pub t: f32,
}

/// Grows an EcoMod tree (Algorithm 1 of `004_*.txt`) at animation time `t`.
/// Same as [`grow_with`] with the paper's wind vector (up). Invalid parameters give an empty
/// skeleton; use [`try_grow`] to see the error.
pub fn grow(p: &EcoModParams, seed: u64, t: f32) -> (Skeleton, Leaves) {
    try_grow(p, seed, t).unwrap_or_default()
}

/// Like [`grow`], returning parameter errors ([`Error::Invalid`] naming the field).
pub fn try_grow(p: &EcoModParams, seed: u64, t: f32) -> Result<(Skeleton, Leaves)> {
    grow_with(p, seed, &EcoModOptions { wind: Vec3::Z, t })
}

struct Pending {
    parent: NodeId,
    g: u32,
    w: u32,
    s0: u32,
    big_l: f32,
    l: f32,
    frame: Mat3,
    lateral: bool,
    /// A stem segment of a whorled stem ([`Whorls`]): the annual shoot it belongs to.
    shoot: Option<Shoot>,
    /// A main limb of the leader's fork ([`Fork`]): its index (0 … limbs − 1).
    fork: Option<u32>,
}

/// Where a stem segment of a whorled stem stands in its annual shoot ([`Whorls`]).
#[derive(Clone, Copy)]
struct Shoot {
    /// Index of the split at this segment's end among the shoot's splits (interwhorl branches
    /// first, then the whorl).
    k: u32,
    /// Strands of the shoot's first segment (S₀ of Algorithm 1's split it stands for).
    s_start: u32,
    /// Strands the shoot's branches take together (S₀ − S₁ of that split).
    lateral: u32,
    /// Length (m) of the shoot: Algorithm 1's length of the stem segment it stands for.
    len: f32,
}

/// Strands of branch `k` of an annual shoot of `w` ([`Whorls`]) whose branches take `total`
/// strands together: its share (interwhorl branches `interwhorl_share`, whorl branches 1) of
/// `total`, rounded, at least 1.
fn shoot_branch_strands(w: &Whorls, k: u32, total: u32) -> u32 {
    let weight = |k: u32| if k < w.interwhorl { w.interwhorl_share } else { 1.0 };
    let sum = w.interwhorl as f32 * w.interwhorl_share + w.branches as f32;
    ((total as f32 * weight(k) / sum.max(1e-6)).round() as u32).max(1)
}

/// Reach (relative length, eq. 4–6 units) of the main axis of a branch of Gravelius order `g`
/// whose first split has Weibull order `w` and `s` strands: the sum of its segments' k_l·L as
/// Algorithm 1 grows them (each split keeping S₁ = ⌈1 + k_s(S₀ − 2)⌉ strands on the axis and L
/// scaled by √(S₁/S₀) within [m, M]), from a relative length 1.
fn axis_reach(p: &EcoModParams, g: u32, w: u32, s: u32) -> f32 {
    let (mut s, mut w, mut big, mut reach) = (s, w, 1.0f32, 0.0f32);
    while w < 1000 {
        let lp = local_params(p, g, w);
        reach += lp.k_l * big;
        if s < 2 {
            break;
        }
        let (s1, _) = split_strands(s, lp.k_s);
        big *= ((s1 as f32 / s as f32).sqrt().min(lp.max_len)).max(lp.min_len);
        s = s1;
        w += 1;
    }
    reach
}

/// Length (m) of the stem segment that ends at split `k` of an annual shoot of length `len`
/// ([`Whorls`]): [`WHORL_SEGMENT`] of the shoot between the whorl's branches, and the rest cut
/// evenly by its interwhorl branches and its whorl's first branch (the segments add up to `len`).
fn shoot_segment(w: &Whorls, k: u32, len: f32) -> f32 {
    let whorl = WHORL_SEGMENT * len;
    if k <= w.interwhorl {
        (len - whorl * w.branches.saturating_sub(1) as f32).max(0.0) / (w.interwhorl + 1) as f32
    } else {
        whorl
    }
}

/// Grows an EcoMod tree with explicit options. Node 0 is the trunk base at the origin; node
/// i > 0 is the end of one branch segment (2S − 1 segments). Radii are d/2 with d = k_d√S₀;
/// `strands`, `gravelius` and `weibull` are the algorithm's S₀, g and w.
///
/// Errors: [`Error::Invalid`] for out-of-range parameters.
pub fn grow_with(p: &EcoModParams, seed: u64, o: &EcoModOptions) -> Result<(Skeleton, Leaves)> {
    check(p)?;
    let s_total = p.strands;
    let mut sk = Skeleton { nodes: Vec::with_capacity(2 * s_total as usize) };
    let root_r = 0.5 * p.k_d * (s_total as f32).sqrt();
    sk.add_root(Vec3::ZERO, root_r);
    sk.nodes[0].strands = s_total;
    let mut leaves = Leaves::default();
    let n_leaves = p.leaf_density.ceil() as u32;
    let up = Vec3::Z;
    // Frame columns: x, y = branch axis, z. Trunk axis = world up.
    let frame0 = Mat3::from_cols(Vec3::X, Vec3::Z, -Vec3::Y);
    let whorls = p.whorls.filter(|w| w.branches > 0);
    let mut stack = vec![Pending { parent: 0, g: 0, w: 0, s0: s_total, big_l: 1.0, l: p.trunk_length_m, frame: frame0, lateral: false, shoot: None, fork: None }];
    let sway = p.wind_undirected * (1.0 - p.k_f);
    // the limbs' profile by depth into the crown ([`Limbs`]): the stem's top (m) and the longest
    // limb's reach, known once the stem is grown (Algorithm 1 pops a split's continuation
    // before its branch, so the whole stem is grown before its first limb)
    let mut stem_top = f32::NEG_INFINITY;
    let mut longest: Option<f32> = None;
    // a broadleaf's crown profile ([`CrownProfile`]): the limbs' strands, planned before the
    // stem is grown (not with a whorled stem)
    let profile = p.crown_profile.filter(|_| whorls.is_none());
    let plan = profile.map(|cp| limb_strands(p, &cp));
    // the leader's fork ([`Fork`]): the stem split it starts at, the planned stem's top (m) and
    // crown length, and the azimuth (radians) of its first main limb
    let fork = profile.and_then(|cp| fork_split(p, &cp));
    let fork_azimuth = Stream::new(seed, u64::from(MAX_STRANDS) * 2 + 1, 0, salt::ARCHITECTURE).range(0.0, std::f64::consts::TAU) as f32;
    let twig_droop = profile.and_then(|cp| cp.twig_droop_deg);
    while let Some(mut b) = stack.pop() {
        if let Some(cp) = profile {
            if b.g == 1 && sk.nodes[b.parent as usize].gravelius == 0 {
                let base = sk.nodes.get(1).map_or(0.0, |n| n.pos.z);
                let (insertion, reach) = (sk.nodes[b.parent as usize].pos, limb_reach(p, b.w, b.s0, b.big_l));
                // a forked stem ends below the crown's top: the limbs' depth is the planned
                // stem's (Algorithm 1's, vertical)
                let top = fork.map_or(stem_top, |f| f.top);
                let aim = match (fork, b.fork) {
                    (Some(f), Some(j)) => {
                        let phi = fork_azimuth + j as f32 * std::f32::consts::TAU / f.fork.limbs as f32;
                        Some((f.fork.angle_deg, Vec3::new(phi.cos(), phi.sin(), 0.0)))
                    }
                    _ => None,
                };
                profile_limb(&cp, &mut b, insertion, base, top, reach, aim);
            }
        } else if let Some(lm) = p.limbs {
            if b.g == 1 && sk.nodes[b.parent as usize].gravelius == 0 {
                let longest = *longest.get_or_insert_with(|| {
                    stack.iter().chain(std::iter::once(&b)).filter(|q| q.g == 1 && sk.nodes[q.parent as usize].gravelius == 0).map(|q| limb_reach(p, q.w, q.s0, q.big_l)).fold(0.0f32, f32::max)
                });
                let base = sk.nodes.get(1).map_or(0.0, |n| n.pos.z);
                let (insertion, reach) = (sk.nodes[b.parent as usize].pos, limb_reach(p, b.w, b.s0, b.big_l));
                shape_limb(&lm, &mut b, insertion, base, stem_top, longest, reach);
            }
        }
        let id = sk.nodes.len() as NodeId;
        let start = sk.nodes[b.parent as usize].pos;
        let axis = b.frame.y_axis;
        let end = start + axis * b.l;
        let mut rng = Stream::new(seed, id as u64, 0, salt::ARCHITECTURE);
        let d = p.k_d * (b.s0 as f32).sqrt();
        let nid = sk.add_child(b.parent, end, 0.5 * d, b.lateral)?;
        {
            let n = &mut sk.nodes[nid as usize];
            n.strands = b.s0;
            n.gravelius = b.g.min(u16::MAX as u32) as u16;
            n.weibull = b.w.min(u16::MAX as u32) as u16;
            n.role = if b.s0 == 1 { Role::Tip } else if b.g == 0 { Role::Trunk } else { Role::Branch };
        }
        if b.g == 0 {
            stem_top = stem_top.max(end.z);
        }
        if b.s0 == 1 {
            place_leaves(&mut leaves, p.leaf_distribution, n_leaves, p.leaf_size_m, p.phyllotaxis_deg, start, &b.frame, b.l, nid, &mut rng);
            continue;
        }
        let lp = local_params(p, b.g, b.w);
        let r = |s: u32, of: u32| ((s as f32 / of as f32).sqrt().min(lp.max_len)).max(lp.min_len);
        // a whorled stem: this split is one of its annual shoot's ([`Whorls`]); the shoot is
        // Algorithm 1's split of its first segment's strands
        let shoot = match (whorls, b.g) {
            (Some(w), 0) => Some(b.shoot.unwrap_or_else(|| {
                // the stem's first split, at the top of its first segment (the bole): a whorl
                // without interwhorl branches (they would stand on the bole), as long as
                // Algorithm 1's next stem segment
                let (s1, _) = split_strands(b.s0, lp.k_s);
                Shoot { k: w.interwhorl, s_start: b.s0, lateral: b.s0 - s1, len: lp.k_l * r(s1, b.s0) * b.big_l }
            })),
            _ => None,
        };
        let (s1, s2) = match (whorls, shoot) {
            (Some(w), Some(sh)) => {
                let s2 = shoot_branch_strands(&w, sh.k, sh.lateral).min(b.s0 - 1);
                (b.s0 - s2, s2)
            }
            // a forked stem: split j of the fork gives its lateral main limb an equal share of
            // the strands left to the limbs still to set
            _ if fork.is_some_and(|f| b.g == 0 && b.w >= f.split) => {
                let f = fork.unwrap();
                let left = f.fork.limbs.saturating_sub(b.w - f.split).max(2);
                let s2 = ((b.s0 as f32 / left as f32).round() as u32).clamp(1, b.s0 - 1);
                (b.s0 - s2, s2)
            }
            // a crown profile's stem: the limb of split w gets its planned strands
            _ => match plan.as_ref().and_then(|pl| if b.g == 0 { pl.get(b.w as usize) } else { None }) {
                Some(&s2) => {
                    let s2 = s2.clamp(1, b.s0 - 1);
                    (b.s0 - s2, s2)
                }
                None => split_strands(b.s0, lp.k_s),
            },
        };
        // the next stem segment: within the shoot, or the next shoot (Algorithm 1's
        // continuation of the whole shoot's split)
        let n_shoot = whorls.map_or(1, |w| w.interwhorl + w.branches);
        let next = match (whorls, shoot) {
            (Some(w), Some(sh)) if sh.k + 1 < n_shoot => Some((Shoot { k: sh.k + 1, ..sh }, b.big_l, shoot_segment(&w, sh.k + 1, sh.len), b.w)),
            (Some(w), Some(sh)) => {
                let big = r(s1, sh.s_start) * b.big_l;
                let len = lp.k_l * big;
                let lp_next = local_params(p, 0, b.w + 1);
                let (n1, _) = if s1 >= 2 { split_strands(s1, lp_next.k_s) } else { (s1, 0) };
                Some((Shoot { k: 0, s_start: s1, lateral: s1 - n1, len }, big, shoot_segment(&w, 0, len), b.w + 1))
            }
            _ => None,
        };
        let (big_l1, mut big_l2) = (r(s1, b.s0) * b.big_l, r(s2, b.s0) * b.big_l);
        // a whorled stem's branches reach as far as Algorithm 1's one branch of the shoot would
        // (its strands give its axis more splits): each is lengthened by the ratio of the two
        // axes' reach (an interwhorl branch, with fewer strands, stays shorter)
        if let (Some(w), Some(sh)) = (whorls, shoot) {
            let whorl_strands = shoot_branch_strands(&w, w.interwhorl, sh.lateral).min(sh.lateral);
            let (one, each) = (axis_reach(p, 1, b.w + 1, sh.lateral), axis_reach(p, 1, b.w + 1, whorl_strands));
            if each > 0.0 && one > each {
                big_l2 *= one / each;
            }
        }
        let (l1, l2) = (lp.k_l * big_l1, lp.k_l * big_l2);
        let (big_l1, l1, w1, shoot1) = match next {
            Some((sh, big, len, w)) => (big, len, w, Some(sh)),
            None => (big_l1, l1, b.w + 1, None),
        };
        let a1 = p.k_c * (s2 as f32 / b.s0 as f32).sqrt() * lp.alpha;
        let a2 = lp.alpha - a1;
        let (rx, rz) = (rng.range(0.0, std::f64::consts::TAU) as f32, rng.range(0.0, std::f64::consts::TAU) as f32);
        let ax = (o.t + rx).sin() * sway * b.l;
        let az = (o.t + rz).sin() * sway * b.l;
        let aw = b.s0 as f32 / s_total as f32 * p.wind_directed;
        // M_i = R_w(α_w) R_z(±α_i + α_z) R_x(α_x) R_y(α_p) R_{y×y_m}(α_m) T_y(l₀) M₀ (row-vector
        // form); in column form the child frame is R_wind · R_grav · F₀ · R_y · R_x · R_z.
        let grav = rot(axis.cross(up), lp.alpha_m);
        let wind = rot(o.wind, aw);
        // a whorled stem spreads its shoot's branches evenly about the stem, and turns each
        // shoot from the last by the phyllotaxis angle
        let twist_deg = match shoot {
            Some(sh) if sh.k > 0 => 360.0 / n_shoot as f32,
            _ => p.phyllotaxis_deg,
        };
        let twist = Mat3::from_rotation_y(twist_deg.to_radians()) * Mat3::from_rotation_x(ax.to_radians());
        let child = |angle: f32| wind * grav * b.frame * twist * Mat3::from_rotation_z((angle + az).to_radians());
        // the leader's fork: split j sets main limb j; the stem between its splits is
        // [`FORK_GAP`] of the crown length; at its last split the stem's continuation is the
        // last main limb (the stem ends)
        let fork_j = fork.filter(|f| b.g == 0 && b.w >= f.split).map(|f| (f, b.w - f.split));
        let (g1, l1, limb1) = match fork_j {
            Some((f, j)) if j + 2 >= f.fork.limbs => (1, l1, Some(f.fork.limbs - 1)),
            Some((f, _)) => (0, FORK_GAP * f.len, None),
            None => (b.g, l1, None),
        };
        let mut f1 = constrain(orthonormal(child(a1)), end, l1, g1 == 0);
        let mut f2 = constrain(orthonormal(child(-a2)), end, l2, false);
        // hanging twigs ([`CrownProfile::twig_droop_deg`]): a leaf-bearing tip off the stem
        if let Some(deg) = twig_droop {
            if s1 == 1 && g1 > 0 {
                f1 = hang(f1, deg, end, l1);
            }
            if s2 == 1 {
                f2 = hang(f2, deg, end, l2);
            }
        }
        stack.push(Pending { parent: nid, g: b.g + 1, w: b.w + 1, s0: s2, big_l: big_l2, l: l2, frame: f2, lateral: true, shoot: None, fork: fork_j.map(|(_, j)| j) });
        stack.push(Pending { parent: nid, g: g1, w: w1, s0: s1, big_l: big_l1, l: l1, frame: f1, lateral: g1 != b.g, shoot: shoot1, fork: limb1 });
    }
    Ok((sk, leaves))
}

/// Reach (m) of the main axis of a first-order limb whose first segment has Weibull order `w`,
/// `s` strands and relative length `big_l` ([`axis_reach`] × `big_l`, the trunk's length units).
fn limb_reach(p: &EcoModParams, w: u32, s: u32, big_l: f32) -> f32 {
    axis_reach(p, 1, w, s) * big_l
}

/// Shapes the limb `b` (a pending branch of Gravelius order 1 on the stem node at `insertion`)
/// by its depth into the crown ([`Limbs`]): depth = (stem top − insertion height) / (stem top −
/// crown base `base_z`), 0–1; turns its frame about the horizontal axis across it to the
/// insertion angle from the vertical `angle_top_deg + depth · (angle_base_deg − angle_top_deg)`
/// (azimuth kept; the ground limit of [`constrain`] still applies) and scales its relative
/// and actual lengths (so its whole subtree) by `min(1, depth / widest_depth) · longest / reach`,
/// `reach` its own axis' reach and `longest` the longest limb's (m).
fn shape_limb(lm: &Limbs, b: &mut Pending, insertion: Vec3, base_z: f32, top_z: f32, longest: f32, reach: f32) {
    let len = top_z - base_z;
    let depth = if len > 1e-6 { ((top_z - insertion.z) / len).clamp(0.0, 1.0) } else { 1.0 };
    let theta = (lm.angle_top_deg + depth * (lm.angle_base_deg - lm.angle_top_deg)).to_radians();
    let y = b.frame.y_axis;
    let h = Vec3::new(y.x, y.y, 0.0);
    let h = if h.length_squared() > 1e-10 { h.normalize() } else { Vec3::new(b.frame.x_axis.x, b.frame.x_axis.y, 0.0).normalize_or(Vec3::X) };
    let target = h * theta.sin() + Vec3::Z * theta.cos();
    let q = glam::Quat::from_rotation_arc(y.normalize_or(Vec3::Z), target);
    if reach > 0.0 && longest > 0.0 {
        let f = (depth / lm.widest_depth.max(1e-3)).clamp(0.02, 1.0) * longest / reach;
        b.big_l *= f;
        b.l *= f;
    }
    b.frame = constrain(orthonormal(Mat3::from_quat(q) * b.frame), insertion, b.l, false);
}

/// The stem of `p` as Algorithm 1 grows it (order 0, no whorls): the heights (m, along a
/// vertical stem) of its splits and of its top. Each stem segment is k_l·L long, L scaled at
/// every split by √(S₁/S₀) within [m, M] (eqs. 1, 4–6), the first `trunk_length_m`.
fn stem_heights(p: &EcoModParams) -> (Vec<f32>, f32) {
    let (mut s, mut w, mut big, mut z) = (p.strands, 0u32, 1.0f32, p.trunk_length_m);
    let mut at = Vec::new();
    while s >= 2 && w < MAX_STRANDS {
        at.push(z);
        let lp = local_params(p, 0, w);
        let (s1, _) = split_strands(s, lp.k_s);
        big *= ((s1 as f32 / s as f32).sqrt().min(lp.max_len)).max(lp.min_len);
        z += lp.k_l * big;
        s = s1;
        w += 1;
    }
    (at, z)
}

/// Strands of each limb of the stem of `p` with crown profile `cp` ([`CrownProfile`]), from
/// the lowest: as many limbs as Algorithm 1's stem has splits ([`stem_heights`]), one strand
/// each and the other S − 1 − n shared by the crown volume a limb serves, ρ(d)² × half the
/// stem length between its neighbours (d its depth below the stem's top over the crown length
/// from the first split), by largest remainder (ties to the lower limb). They add up to S − 1:
/// the stem's top keeps one strand.
fn limb_strands(p: &EcoModParams, cp: &CrownProfile) -> Vec<u32> {
    let (at, top) = stem_heights(p);
    let n = at.len();
    if n == 0 {
        return Vec::new();
    }
    let len = (top - at[0]).max(1e-6);
    let z = |k: isize| if k < 0 { at[0] } else if k as usize >= n { top } else { at[k as usize] };
    let weight: Vec<f64> = (0..n as isize).map(|k| f64::from(cp.radius_at((top - z(k)) / len).powi(2) * 0.5 * (z(k + 1) - z(k - 1)).max(0.0))).collect();
    let spare = (p.strands as usize).saturating_sub(1 + n) as f64;
    let sum: f64 = weight.iter().sum();
    let share: Vec<f64> = weight.iter().map(|w| if sum > 0.0 { spare * w / sum } else { spare / n as f64 }).collect();
    let mut out: Vec<u32> = share.iter().map(|q| 1 + q.floor() as u32).collect();
    let mut left = (p.strands as usize - 1).saturating_sub(out.iter().map(|&v| v as usize).sum());
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| (share[b] - share[b].floor()).total_cmp(&(share[a] - share[a].floor())).then(a.cmp(&b)));
    for &k in order.iter().cycle() {
        if left == 0 {
            break;
        }
        out[k] += 1;
        left -= 1;
    }
    out
}

/// Shapes the limb `b` (a pending branch of Gravelius order 1 on the stem node at `insertion`)
/// by a broadleaf's crown profile ([`CrownProfile`]): depth d = (stem top − insertion height) /
/// (stem top − crown base `base_z`), 0–1; turns its frame about the horizontal axis across it
/// to the insertion angle θ = `angle_top_deg` + d·(`angle_base_deg` − `angle_top_deg`) from the
/// vertical (azimuth kept; the ground limit of [`constrain`] still applies), and scales its
/// relative and actual lengths (its whole subtree) by t / `reach`, t (m) the distance along θ
/// from the insertion to the crown surface of radius A·ρ at each height (A = ½
/// `width_to_length` × crown length; bisection, 40 steps) and `reach` its own axis' reach.
/// `aim` (a main limb of the leader's fork, [`Fork`]): θ (degrees) and the horizontal
/// azimuth (a unit vector) to use instead of the depth's angle and the limb's own azimuth.
fn profile_limb(cp: &CrownProfile, b: &mut Pending, insertion: Vec3, base_z: f32, top_z: f32, reach: f32, aim: Option<(f32, Vec3)>) {
    let len = top_z - base_z;
    let depth = |z: f32| if len > 1e-6 { (top_z - z) / len } else { 1.0 };
    let d = depth(insertion.z).clamp(0.0, 1.0);
    let theta = aim.map_or(cp.angle_top_deg + d * (cp.angle_base_deg - cp.angle_top_deg), |a| a.0).to_radians();
    let y = b.frame.y_axis;
    let h = aim.map_or(Vec3::new(y.x, y.y, 0.0), |a| a.1);
    let h = if h.length_squared() > 1e-10 { h.normalize() } else { Vec3::new(b.frame.x_axis.x, b.frame.x_axis.y, 0.0).normalize_or(Vec3::X) };
    let target = h * theta.sin() + Vec3::Z * theta.cos();
    let q = glam::Quat::from_rotation_arc(y.normalize_or(Vec3::Z), target);
    let a = 0.5 * cp.width_to_length * len.max(1e-6);
    // inside the crown at distance t along θ: its distance from the stem within the profile
    let inside = |t: f32| {
        let z = insertion.z + t * theta.cos();
        let dz = depth(z);
        (0.0..=1.0).contains(&dz) && t * theta.sin() <= a * cp.radius_at(dz)
    };
    let (mut lo, mut hi) = (0.0f32, 2.0 * (len + a).max(1e-6));
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if inside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if reach > 0.0 && lo > 0.0 {
        let f = lo / reach;
        b.big_l *= f;
        b.l *= f;
    }
    b.frame = constrain(orthonormal(Mat3::from_quat(q) * b.frame), insertion, b.l, false);
}

/// Length (relative crown length) of each stem segment between the splits of the leader's
/// fork ([`Fork`]): the main limbs leave the stem within a few per cent of the crown length,
/// as a fork's limbs leave one crotch (ours).
pub const FORK_GAP: f32 = 0.02;

/// Where the leader of `p` forks ([`Fork`] of `cp`): the stem's split at which it starts.
#[derive(Debug, Clone, Copy)]
struct ForkAt {
    fork: Fork,
    /// Index of the stem split (its Weibull order) of the fork's first main limb.
    split: u32,
    /// Height (m) of the planned stem's top ([`stem_heights`], vertical).
    top: f32,
    /// Crown length (m) of the planned stem: its top less its first split's height.
    len: f32,
}

/// The stem split of `p` at which the leader forks (issue 32, round 46; [`Fork`] of `cp`): the
/// lowest of Algorithm 1's stem splits ([`stem_heights`]) at depth ≤ `fork.depth` below the
/// planned stem's top over its crown length. The limbs below it keep their planned strands
/// ([`limb_strands`]); the strands the stem has left there, which Algorithm 1 would spend on
/// the limbs above, are shared equally by the fork's main limbs (the volume of the crown above
/// the fork is theirs). None without a fork or where the stem has no split that high (a young
/// tree of few strands).
///
/// The fork is the architecture's, after Hallé, Oldeman & Tomlinson (1978, Tropical Trees and
/// Forests, Springer): beech's sympodial, plagiotropic axes (Troll's model) and the oaks' and
/// maples' rhythmic orthotropic ones (Rauh's model) lose a single leader in the crown; Roloff
/// (1984, Morphologie der Verzweigung von Fagus sylvatica L., Ber. Forschungszentrum
/// Waldökosysteme Göttingen 3:1–25: the architectural model of beech and the phases of its
/// top's growth) has the top of a grown beech carried by several leading shoots, the
/// acrotonically favoured side limbs filling the space between them.
fn fork_split(p: &EcoModParams, cp: &CrownProfile) -> Option<ForkAt> {
    let fork = cp.fork()?;
    let (at, top) = stem_heights(p);
    let len = (top - *at.first()?).max(1e-6);
    let k = at.iter().position(|&z| (top - z) / len <= fork.depth)?;
    Some(ForkAt { fork, split: k as u32, top, len })
}

/// Turns a tip's frame `f` so that its axis points `deg` degrees below the horizontal, azimuth
/// kept (a twig that hangs: [`CrownProfile::twig_droop_deg`]); a segment of length `len` from
/// `start` still ends at z ≥ 0 (it droops less where it would not).
fn hang(f: Mat3, deg: f32, start: Vec3, len: f32) -> Mat3 {
    let y = f.y_axis;
    let h = Vec3::new(y.x, y.y, 0.0);
    let h = if h.length_squared() > 1e-10 { h.normalize() } else { Vec3::new(f.x_axis.x, f.x_axis.y, 0.0).normalize_or(Vec3::X) };
    let mut down = deg.clamp(0.0, 90.0).to_radians();
    if len > 0.0 {
        down = down.min((start.z / len).clamp(0.0, 1.0).asin());
    }
    let target = h * down.cos() - Vec3::Z * down.sin();
    orthonormal(Mat3::from_quat(glam::Quat::from_rotation_arc(y.normalize_or(Vec3::Z), target)) * f)
}

/// Largest tilt of the trunk (the g = 0 axis) from the vertical (degrees): apical control keeps
/// the leader upright. Our addition: Algorithm 1 turns the major sub-branch by α₁ at every split,
/// which with the published pine angles (α = 128.8° at g = 0) makes the trunk wander and lean.
pub const TRUNK_MAX_TILT_DEG: f32 = 6.0;

/// Largest droop of a branch axis below the horizontal (degrees). Our addition: a negative
/// gravimorphism angle α_m (the pine's −4° … −6°) applied at every one of a long branch's splits
/// turns it all the way down; real branches sag at most a few tens of degrees.
pub const MAX_DROOP_DEG: f32 = 30.0;

/// Applies the trunk tilt limit ([`TRUNK_MAX_TILT_DEG`], for the trunk's continuation), the
/// droop limit ([`MAX_DROOP_DEG`]) and the ground (a segment of length `len` from `start` must
/// end at z ≥ 0) to a child frame, by turning it towards the vertical about y × up.
fn constrain(f: Mat3, start: Vec3, len: f32, trunk: bool) -> Mat3 {
    let y = f.y_axis;
    let mut min_sin = if trunk { (90.0 - TRUNK_MAX_TILT_DEG).to_radians().sin() } else { (-MAX_DROOP_DEG).to_radians().sin() };
    if len > 0.0 && start.z + y.z * len < 0.0 {
        min_sin = min_sin.max((-start.z / len).clamp(-1.0, 0.0));
    }
    if y.z >= min_sin {
        return f;
    }
    let axis = y.cross(Vec3::Z);
    let axis = if axis.length_squared() > 1e-12 { axis.normalize() } else { f.x_axis };
    let turn = min_sin.clamp(-1.0, 1.0).asin() - y.z.clamp(-1.0, 1.0).asin();
    orthonormal(Mat3::from_axis_angle(axis, turn) * f)
}

/// Re-orthonormalises a frame (Gram–Schmidt on y, then x) against drift over deep recursions.
fn orthonormal(m: Mat3) -> Mat3 {
    let y = m.y_axis.normalize_or(Vec3::Z);
    let x = (m.x_axis - y * m.x_axis.dot(y)).normalize_or(y.any_orthonormal_vector());
    Mat3::from_cols(x, y, x.cross(y))
}

/// Places `n` leaves on a tip segment from `start` along `frame.y` of length `len` by one of the
/// five leaf distributions of EcoMod (section II.A).
#[allow(clippy::too_many_arguments)]
fn place_leaves(out: &mut Leaves, kind: LeafDistribution, n: u32, size: f32, phyllo_deg: f32, start: Vec3, frame: &Mat3, len: f32, node: NodeId, rng: &mut Stream) {
    if n == 0 || size <= 0.0 {
        return;
    }
    let axis = frame.y_axis;
    let jitter = rng.range(0.0, 360.0) as f32;
    for i in 0..n {
        let fi = i as f32;
        let nf = n as f32;
        // (position along the segment 0..1, azimuth degrees, angle from the axis degrees)
        let (t, az, tilt) = match kind {
            LeafDistribution::Spiral => ((fi + 1.0) / nf, fi * phyllo_deg.max(137.5 * (phyllo_deg == 0.0) as u8 as f32), 50.0),
            LeafDistribution::Staggered => ((fi + 1.0) / nf, fi * 180.0, 55.0),
            LeafDistribution::Stacked => {
                let per = 4u32.min(n);
                let whorls = n.div_ceil(per) as f32;
                (((i / per) as f32 + 1.0) / whorls, (i % per) as f32 * 360.0 / per as f32 + (i / per) as f32 * 45.0, 60.0)
            }
            LeafDistribution::Bunched => (1.0, fi * 360.0 / nf, 35.0 + 40.0 * ((i % 3) as f32) / 2.0),
            LeafDistribution::Coniferous => ((fi + 0.5) / nf, fi * 137.5, 70.0),
        };
        let a = (az + jitter).to_radians();
        let radial = frame.x_axis * a.cos() + frame.z_axis * a.sin();
        let tl = tilt.to_radians();
        let dir = (axis * tl.cos() + radial * tl.sin()).normalize_or(axis);
        let side = dir.cross(axis).normalize_or(frame.x_axis);
        let normal = side.cross(dir).normalize_or(Vec3::Z);
        out.leaves.push(Leaf { pos: start + axis * (len * t), dir, normal, size, node });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strand_split_conserves() {
        for s0 in 2..200u32 {
            for ks in [0.5f32, 0.75, 0.9, 1.0] {
                let (a, b) = split_strands(s0, ks);
                assert_eq!(a + b, s0);
                assert!(a >= 1 && b >= 1 && a >= b);
            }
        }
    }

    #[test]
    fn local_params_clamp_eq1() {
        let p = EcoModParams::beech_paper();
        let lp = local_params(&p, 0, 0);
        assert_eq!(lp.k_s, 0.75);
        assert_eq!(lp.alpha, 45.0);
        assert_eq!(lp.min_len, 1.0);
        let lp = local_params(&p, 15, 3);
        assert!((lp.k_s - 0.9).abs() < 1e-6);
    }
}
