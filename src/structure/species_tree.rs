//! One tree of a species at an age, grown by any of the three models: the library side of
//! `sylva tree grow`.
//!
//! - EcoMod: the species' strand count scaled by S·min(1, age/80)² (at least 8).
//! - Light-guided and Laplacian: the tree grows inside the species' crown envelope at that age
//!   ([`CrownEnvelope::for_species`]), in a voxel space with headroom above the apex
//!   (25 % of the height for light-guided, 20 % for Laplacian) and room around the crown.

use super::grow::envelope::CrownEnvelope;
use crate::obstacle::{validate_obstacles, Obstacle};
use super::grow::{ecomod, laplacian, light_guided};
use super::skeleton::{Leaf, Leaves, Skeleton};
use crate::error::{Error, Result};
use crate::rng::{salt, Stream};
use crate::species::{EcoModParams, LeafType, Species};
use glam::Vec3;

/// Growth model of [`grow_species_tree`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// EcoMod strand model (`004_*.txt`).
    EcoMod,
    /// Light-guided self-organising growth (`001_*.txt`).
    Light,
    /// Laplacian growth (`003_*.txt`).
    Laplacian,
}

/// A grown tree and the space it grew in.
#[derive(Debug, Clone)]
pub struct GrownTree {
    /// Skeleton, base at the origin, z up (m).
    pub skeleton: Skeleton,
    /// Leaves (the model's own for EcoMod, [`tip_leaves`] for the others).
    pub leaves: Leaves,
    /// Crown envelope the tree grew in (light-guided and Laplacian).
    pub envelope: Option<CrownEnvelope>,
    /// Top of the voxel space (m) and voxel edge (m) (light-guided and Laplacian).
    pub space: Option<(f32, f32)>,
}

/// Age (years) from which an EcoMod tree has its species' full strand count ([`ecomod_strands_at`]).
pub const ECOMOD_FULL_AGE_YR: f32 = 80.0;

/// Strand count of an EcoMod tree of `age_yr` years whose species has `full` strands:
/// S·min(1, a/[`ECOMOD_FULL_AGE_YR`])², at least 8 (and not more than `full` when that is at
/// least 8). Ours (EcoMod, `004_*.txt`, grows a tree of a given strand count, not an age): the
/// strands stand for the shoots, whose number grows with the crown's surface.
pub fn ecomod_strands_at(full: u32, age_yr: f32) -> u32 {
    let f = (age_yr / ECOMOD_FULL_AGE_YR).clamp(0.0, 1.0);
    ((full as f32 * f * f).round() as u32).max(8).min(full.max(8))
}

/// Grows one tree of `sp` at `age_yr` years (> 0) with `model` among `obstacles` (ignored by
/// EcoMod), seed `seed`. Light-guided runs `age` cycles (1–60), lateral shoots at 80° from the
/// parent and plagiotropic side branches for conifers, 45° for broadleaves, with an internode of
/// max(min(H/40, R/5), 0.15 m) (H height, R crown radius of the envelope); Laplacian adds 25
/// branches per year (≤ 4000) on voxels of max(H/28, 0.1 m). Both have their radii scaled
/// uniformly (which keeps the pipe model and the Strahler width ratios) so that the trunk base
/// is the species' DBH at the tree's height ([`Species::dbh_from_height_cm`], at least 2 cm).
///
/// Errors: [`Error::Invalid`] for a bad age, an invalid obstacle (naming it) or bad species
/// parameters; [`Error::TooLarge`] for an oversized voxel space.
pub fn grow_species_tree(sp: &Species, model: Model, age_yr: f32, obstacles: &[Obstacle], seed: u64) -> Result<GrownTree> {
    if !(age_yr.is_finite() && age_yr > 0.0) {
        return Err(Error::Invalid { context: format!("tree of {}", sp.id), field: "age".into(), value: age_yr.to_string(), expected: "a positive number of years".into() });
    }
    validate_obstacles(obstacles)?;
    match model {
        Model::EcoMod => {
            let mut p: EcoModParams = sp.architecture.ecomod.clone();
            p.strands = ecomod_strands_at(p.strands, age_yr);
            let (skeleton, leaves) = ecomod::try_grow(&p, seed, 0.0)?;
            Ok(GrownTree { skeleton, leaves, envelope: None, space: None })
        }
        Model::Light => grow_light_guided_tree(sp, crate::species::allometry::potential_height(sp, age_yr).max(1.5), age_yr.round().clamp(1.0, 60.0) as u32, obstacles, seed),
        Model::Laplacian => {
            let env = CrownEnvelope::for_species(sp, age_yr, Vec3::ZERO);
            let (h, r) = (env.height_m, env.radius_m);
            let voxel = (h / 28.0).min(r / 5.0).max(0.1);
            let lo = laplacian::LaplacianOptions { voxel_m: voxel, extent_m: (r + 3.0 * voxel).max(1.2 * r), height_m: 1.2 * h, source: laplacian::LightSource::Envelope(env), ..Default::default() };
            let mut g = laplacian::grow(&sp.architecture.laplacian, &lo, obstacles, seed, (age_yr * 25.0).round().clamp(1.0, 4000.0) as u32)?;
            scale_radii_to_dbh(&mut g.skeleton, sp);
            relax_lattice(&mut g.skeleton, voxel, obstacles, seed);
            let top = g.space.origin.z + g.space.dims[2] as f32 * voxel;
            let leaves = tip_leaves(&g.skeleton, &sp.architecture.ecomod);
            Ok(GrownTree { skeleton: g.skeleton, leaves, envelope: Some(env), space: Some((top, voxel)) })
        }
    }
}

/// The light-guided tree of [`grow_species_tree`] by its size and growth history rather than
/// its age: `cycles` (1–60) cycles of the light-guided model (`001_*.txt`) inside the species'
/// crown envelope of a tree `height_m` tall ([`CrownEnvelope::for_species_height`]; at least
/// 1.5 m). [`grow_species_tree`] grows the envelope of the species' height–age curve at the
/// tree's age in one cycle per year. Tests of the Plastic Trees adaptation name both, so that
/// their trees keep their size and architecture when a species' height curve is refitted (issue
/// 35, round 40): the pruning of eq. 11 compares a branch's light with its minimum over the
/// growth stages, so a tree grown in more cycles to the same height sheds less.
///
/// Errors: [`Error::Invalid`] for a height that is not a positive finite number (m), for
/// `cycles` outside 1–60, for an invalid obstacle (naming it) or bad species parameters.
pub fn grow_light_guided_tree(sp: &Species, height_m: f32, cycles: u32, obstacles: &[Obstacle], seed: u64) -> Result<GrownTree> {
    if !(height_m.is_finite() && height_m > 0.0) {
        return Err(Error::Invalid { context: format!("tree of {}", sp.id), field: "height".into(), value: height_m.to_string(), expected: "a positive height in m".into() });
    }
    if !(1..=60).contains(&cycles) {
        return Err(Error::Invalid { context: format!("tree of {}", sp.id), field: "cycles".into(), value: cycles.to_string(), expected: "1 to 60 light-guided growth cycles".into() });
    }
    validate_obstacles(obstacles)?;
    let env = CrownEnvelope::for_species_height(sp, height_m, Vec3::ZERO);
    let (h, r) = (env.height_m, env.radius_m);
    let internode = (h / 40.0).min(r / 5.0).max(0.15);
    let o = light_guided::LightOptions {
        pipe_exponent: sp.life.allometry.pipe_exponent,
        internode_m: internode,
        height_m: 1.25 * h,
        extent_m: (r + 3.0 * internode).max(1.3 * r).max(2.0),
        envelope: Some(env),
        // conifers carry their branches near-horizontal in whorls, broadleaves at ~45°
        branch_angle_deg: if sp.identity.leaf_type == LeafType::Conifer { 80.0 } else { 45.0 },
        plagiotropic: sp.identity.leaf_type == LeafType::Conifer,
        ..Default::default()
    };
    let mut skeleton = light_guided::grow(&sp.architecture.light_guided, &o, obstacles, seed, cycles)?;
    scale_radii_to_dbh(&mut skeleton, sp);
    let leaves = tip_leaves(&skeleton, &sp.architecture.ecomod);
    let top = (1.25 * h / (0.5 * internode)).ceil() * 0.5 * internode;
    Ok(GrownTree { skeleton, leaves, envelope: Some(env), space: Some((top, 0.5 * internode)) })
}

/// Leaves for models without their own: ⌈ρ_l⌉ (1–30) leaves of the species' EcoMod leaf size
/// (≥ 2 cm) along every tip segment, spread at the golden angle, 53° from the shoot axis.
pub fn tip_leaves(sk: &Skeleton, p: &EcoModParams) -> Leaves {
    let mut lv = Leaves::default();
    let n = p.leaf_density.ceil().clamp(1.0, 30.0) as u32;
    for (i, node) in sk.nodes.iter().enumerate() {
        let Some(par) = node.parent else { continue };
        if !node.children.is_empty() {
            continue;
        }
        let start = sk.nodes[par as usize].pos;
        let axis = (node.pos - start).normalize_or(Vec3::Z);
        let x = axis.any_orthonormal_vector();
        let y = axis.cross(x);
        for k in 0..n {
            let a = (k as f32 * 137.5 + i as f32 * 37.0).to_radians();
            let radial = x * a.cos() + y * a.sin();
            let dir = (axis * 0.6 + radial * 0.8).normalize();
            let normal = dir.cross(axis).cross(dir).normalize_or(Vec3::Z);
            let t = (k + 1) as f32 / n as f32;
            lv.leaves.push(Leaf { pos: start + (node.pos - start) * t, dir, normal, size: p.leaf_size_m.max(0.02), node: i as u32 });
        }
    }
    lv
}

/// Scales all radii of `sk` by one factor so the base radius is half the species' DBH at the
/// tree's height (≥ 1 cm); a uniform factor keeps r^d = Σ r_j^d and W(k) ratios.
fn scale_radii_to_dbh(sk: &mut Skeleton, sp: &Species) {
    let r0 = sk.nodes.first().map(|n| n.radius).unwrap_or(0.0);
    let target = 0.005 * sp.dbh_from_height_cm(sk.height()).max(2.0);
    if r0 > 0.0 && r0.is_finite() {
        let s = target / r0;
        for n in &mut sk.nodes {
            n.radius *= s;
        }
    }
}

/// Takes the voxel-lattice look off a Laplacian skeleton (for display; the grown tree's voxel
/// cells are unchanged in [`super::grow::laplacian::LaplacianGrowth`]): every node but the root
/// moves by a random offset of up to ±0.3 voxel per axis (seeded by `seed` and the node), then
/// every node with one parent and one child moves halfway to the mean of the two (one smoothing
/// pass). Moves that would put a node inside an obstacle or below the ground are skipped.
pub fn relax_lattice(sk: &mut Skeleton, voxel_m: f32, obstacles: &[Obstacle], seed: u64) {
    let ok = |p: Vec3| p.z >= 0.0 && !obstacles.iter().any(|o| o.contains(p));
    for i in 1..sk.nodes.len() {
        let mut rng = Stream::new(seed, i as u64, 0, salt::ARCHITECTURE ^ 0x1A77);
        let mut d = || rng.range(-0.3, 0.3) as f32 * voxel_m;
        let p = sk.nodes[i].pos + Vec3::new(d(), d(), d());
        if ok(p) {
            sk.nodes[i].pos = p;
        }
    }
    let old: Vec<Vec3> = sk.nodes.iter().map(|n| n.pos).collect();
    for (i, n) in sk.nodes.iter_mut().enumerate() {
        if let (Some(par), [c]) = (n.parent, n.children.as_slice()) {
            let p = 0.5 * old[i] + 0.25 * (old[par as usize] + old[*c as usize]);
            if i > 0 && ok(p) {
                n.pos = p;
            }
        }
    }
}

