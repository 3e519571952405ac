//! A full-detail tree's leaf area as cards (issue 32): the crown's leaf area
//! ([`crate::sim::phases::light::crown_leaf_area`], the leaf area the light model shades with)
//! given to the leaf cards of an adapted skeleton, lengthened and copied
//! ([`fill_leaf_area`]) or with leaf-cluster cards (sprigs, [`sprig_cards`]). Shared by the
//! stand exports ([`super::export`]) and the stills' and viewer's near field
//! ([`super::adapted`]); a module of its own so that neither imports the other.

use crate::mesh::TriMesh;
use glam::Vec3;

/// Largest factor by which [`fill_leaf_area`] lengthens a tree's leaf cards (1.5: a beech
/// card of 6 cm stays a leaf, not a board); the rest of the leaf area comes as more cards.
pub const MAX_CARD_GROWTH: f32 = 1.5;

/// Most cards [`fill_leaf_area`] makes of one leaf card (itself and its copies).
pub const MAX_CARDS_PER_LEAF: usize = 24;

/// Gives the leaf cards of `lv` (each `size × size/2`, [`crate::structure::mesh::leaf_mesh`],
/// of which the leaf texture covers the share `card_cover`,
/// [`crate::structure::texture::leaf_card_cover`]) a leaf area (one-sided) of `leaf_area_m2`,
/// the leaf area the light model gives the tree
/// ([`crate::sim::phases::light::crown_leaf_area`]: the crown's leaf-area index over its
/// projection), so that the exported crown is as dense as the simulation's. With the area
/// factor `F = leaf_area_m2 / current`, each card becomes `n = ceil(F / 1.5²)` cards (at most
/// [`MAX_CARDS_PER_LEAF`]) of length × `sqrt(F / n)`: the card itself and `n − 1` copies on
/// the same node, turned about the vertical by a hashed angle and moved by a hashed offset of
/// up to two card lengths (the stand skeleton's few dozen tips stand for a crown's hundreds of
/// shoots), kept within `crown_radius_m` (m) of the stem axis (the tree's frame: stem base at
/// the origin, z up). Fewer cards (F < 1) shrink instead. Deterministic: the offsets hash the
/// leaf's index and `seed` (the export passes the species, so that trees alike stay alike and
/// share their meshes). A tree without leaves, or a target of 0, is left as it is.
pub fn fill_leaf_area(lv: &mut crate::structure::Leaves, leaf_area_m2: f32, card_cover: f32, crown_radius_m: f32, seed: u64) {
    let now: f32 = lv.leaves.iter().map(|l| 0.5 * l.size * l.size * card_cover.clamp(0.05, 1.0)).sum();
    if now <= 0.0 || !(leaf_area_m2 > 0.0) {
        return;
    }
    let f = leaf_area_m2 / now;
    let n = ((f / (MAX_CARD_GROWTH * MAX_CARD_GROWTH)).ceil() as usize).clamp(1, MAX_CARDS_PER_LEAF);
    let k = (f / n as f32).sqrt();
    let rmax = crown_radius_m.max(0.05);
    let mut out = Vec::with_capacity(lv.leaves.len() * n);
    for (i, l) in lv.leaves.iter().enumerate() {
        let size = l.size * k;
        out.push(crate::structure::Leaf { size, ..*l });
        for j in 1..n {
            let u = |c: u64| crate::rng::unit_f32(crate::rng::hash(&[seed, i as u64, j as u64, c]));
            let turn = glam::Quat::from_rotation_z(u(0) * std::f32::consts::TAU);
            let off = Vec3::new(u(1) * 2.0 - 1.0, u(2) * 2.0 - 1.0, u(3) * 2.0 - 1.0) * (2.0 * size);
            let mut pos = l.pos + off;
            let rho = pos.truncate().length();
            if rho > rmax {
                pos = (pos.truncate() * (rmax / rho)).extend(pos.z);
            }
            out.push(crate::structure::Leaf { pos, dir: turn * l.dir, normal: turn * l.normal, size, node: l.node });
        }
    }
    lv.leaves = out;
}

/// Largest inclination of a sprig card's normal from the vertical (radians, 60°; see
/// [`sprig_cards`]).
pub const SPRIG_MAX_INCLINATION: f32 = std::f32::consts::FRAC_PI_3;

/// Gives a full-detail tree the leaf area `leaf_area_m2` (one-sided, m²; the crown's leaf-area
/// index over its projection, [`crate::sim::phases::light::crown_leaf_area`]) with few cards:
/// its leaf cards (`card_cover` of each `size × size/2` card shows leaf) are lengthened by up
/// to [`MAX_CARD_GROWTH`] (or shrunk when the tree has more leaf than that), and the rest of
/// the area comes as sprigs: square leaf-cluster cards (the cluster texture, 36 leaves,
/// `sprig_cover` of the card shows leaf, [`crate::structure::texture::cluster_card_cover`])
/// whose leaves are as long as the tree's cards (side = card length /
/// [`crate::structure::texture::cluster_leaf_length`] of a broad leaf, 0.26), each standing at
/// a leaf picked by a hash of `seed` and its index, moved by up to half a side and kept within
/// `crown_radius_m` of the stem axis, turned about the vertical by a hashed angle and inclined
/// planophile: a card's normal leans from the vertical by a hashed angle uniform in 0–60°
/// (mean 30°; broadleaf canopies are better described as planophile than spherical, whose mean
/// is 57°: Pisek et al. 2011, Trees 25:919–924; Chianucci et al. 2018, Annals of Forest Science
/// 75:50, a dataset of 138 temperate and boreal species), so a crown seen from above shows its
/// leaf area as the light model's crown does.
/// One sprig holds the leaf area of about twenty leaf cards, so a crown of 2,000 nodes carries
/// its leaf area with a few thousand cards, not the 30,000 copies of [`fill_leaf_area`]
/// (BENCHMARKS.md round 21). Returns the sprigs as a mesh (4 vertices and 2 triangles each, UV
/// 0–1 over the card, normals facing the card's front; the glTF cluster material is
/// double-sided). Deterministic; a tree without leaves, or a target of 0, gets none.
pub fn sprig_cards(lv: &mut crate::structure::Leaves, leaf_area_m2: f32, card_cover: f32, sprig_cover: f32, crown_radius_m: f32, seed: u64) -> TriMesh {
    let mut m = TriMesh::default();
    let cover = card_cover.clamp(0.05, 1.0);
    let now: f32 = lv.leaves.iter().map(|l| 0.5 * l.size * l.size * cover).sum();
    if now <= 0.0 || !(leaf_area_m2 > 0.0) {
        return m;
    }
    let k = (leaf_area_m2 / now).sqrt().min(MAX_CARD_GROWTH);
    lv.leaves.iter_mut().for_each(|l| l.size *= k);
    let rest = leaf_area_m2 - now * k * k;
    let mean_len = lv.leaves.iter().map(|l| l.size).sum::<f32>() / lv.leaves.len() as f32;
    let side = mean_len / 0.26;
    let per = side * side * sprig_cover.clamp(0.05, 1.0);
    if !(rest > 0.5 * per) {
        return m;
    }
    let n = (rest / per).round() as usize;
    let rmax = crown_radius_m.max(0.05);
    let nl = lv.leaves.len() as u64;
    m.positions.reserve(4 * n);
    for j in 0..n as u64 {
        let u = |c: u64| crate::rng::unit_f32(crate::rng::hash(&[seed, 0x5971_6753, j, c]));
        let l = &lv.leaves[(crate::rng::hash(&[seed, 0x5971_6753, j]) % nl) as usize];
        let mut c = l.pos + Vec3::new(u(1) - 0.5, u(2) - 0.5, u(3) - 0.5) * side;
        let rho = c.truncate().length();
        if rho > rmax {
            c = (c.truncate() * (rmax / rho)).extend(c.z);
        }
        let yaw = u(4) * std::f32::consts::TAU;
        let tilt = (u(5) * 2.0 - 1.0) * SPRIG_MAX_INCLINATION;
        let along = Vec3::new(yaw.cos(), yaw.sin(), 0.0);
        let across = Vec3::new(-yaw.sin(), yaw.cos(), 0.0);
        let v = (glam::Quat::from_axis_angle(along, tilt) * across) * (0.5 * side);
        crate::structure::mesh::quad(&mut m, c, along * (0.5 * side), v);
    }
    m
}
