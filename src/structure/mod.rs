//! Tree architecture: branching skeletons grown by three models from the seed papers, meshes
//! with levels of detail, and the per-species representative tree the renderer instances.
//!
//! - [`skeleton`]: flat node arena, Strahler/Gravelius/Weibull orders, pipe-model radii.
//! - [`grow`]: EcoMod strands (`004_*.txt`), light-guided growth (`001_*.txt`), Laplacian growth
//!   (`003_*.txt`).
//! - [`mesh`]: generalized cylinders, leaf cards and the LOD chain.
//! - [`crown_hull`]: the mid-level crown hull of an adapted tree, shrink-wrapped onto its
//!   adapted leaf clusters (issue 14).
//! - [`params`]: the papers' parameter sets.
//! - [`species_tree`]: one tree of a species at an age by any model (what `sylva tree grow`
//!   runs); light-guided and Laplacian trees grow in the species' crown envelope
//!   ([`grow::envelope`]).
//! - [`edit_distance`]: constrained edit distance between skeletons (Zhang 1996), the
//!   comparison of Plastic Trees section 7.
//! - [`taper`]: stem taper from a tree's DBH and height (Kozak 1988; the meshed bole).
//! - [`texture`]: procedural leaf-card (per leaf shape), LOD and bark textures.
//! - [`plastic`]: Plastic Trees (`000_*.txt`): bends and prunes a grown skeleton for a new
//!   obstacle instead of regrowing it.

pub mod crown_hull;
pub mod edit_distance;
pub mod forest_form;
pub mod grow;
pub mod mesh;
pub mod params;
pub mod plastic;
pub mod skeleton;
pub mod species_tree;
pub mod stand;
pub mod taper;
pub mod texture;

pub use skeleton::{Leaf, Leaves, Node, NodeId, Role, Skeleton};

use crate::mesh::LodChain;
use crate::species::Species;
use glam::Vec3;

/// Translates the tree so the root is at the origin and scales positions, radii and leaves
/// uniformly so its height is `height_m` (m). Errors as [`Skeleton::scaled_to`] (a tree of
/// height 0 or a non-positive target).
pub fn normalised(sk: &Skeleton, leaves: &Leaves, height_m: f32) -> crate::Result<(Skeleton, Leaves)> {
    let h = sk.height();
    if !(height_m > 0.0 && height_m.is_finite()) || h <= 0.0 {
        return Err(crate::Error::Invalid { context: "structure::normalised".into(), field: "height".into(), value: format!("target {height_m}, tree {h}"), expected: "positive heights (m)".into() });
    }
    let s = height_m / h;
    let root = sk.nodes[0].pos;
    let mut out = sk.clone();
    for n in &mut out.nodes {
        n.pos = (n.pos - root) * s;
        n.radius *= s;
    }
    let mut lv = leaves.clone();
    for l in &mut lv.leaves {
        l.pos = (l.pos - root) * s;
        l.size *= s;
    }
    Ok((out, lv))
}

/// Representative tree of a species for the renderer: the EcoMod tree of the species'
/// `architecture.ecomod` parameters (Zamuda et al., seed 004, Algorithm 1; seed `seed`, t = 0),
/// normalised to height 1 m with its base at the origin, z up (m per m of height). Errors: the
/// species' EcoMod parameters cannot grow a tree ([`grow::ecomod::try_grow`]), or it has no
/// height ([`normalised`]).
pub fn species_tree(species: &Species, seed: u64) -> crate::Result<(Skeleton, Leaves)> {
    grow::ecomod::try_grow(&species.architecture.ecomod, seed, 0.0).and_then(|(sk, lv)| normalised(&sk, &lv, 1.0))
}

/// [`species_tree`] meshed with the default [`mesh::LodOptions`], its leaf cards as EcoMod
/// leaves them (the renderer's prototypes give the full level its crown's drawn leaf area on
/// top: `job::leaf_area::prototype_chain`); the renderer scales each instance by its height and
/// crown radius. Bad parameters give an empty chain (and a warning).
pub fn species_lod_chain(species: &Species, seed: u64) -> LodChain {
    match species_tree(species, seed) {
        Ok((sk, lv)) => mesh::lod_chain(&sk, &lv, &mesh::LodOptions::for_species(species)),
        Err(e) => {
            tracing::warn!("species {}: {e}", species.id);
            LodChain::default()
        }
    }
}

/// Horizontal crown radius of a skeleton with its leaves: the largest horizontal distance of a
/// leaf (or node) from the root axis (m).
pub fn crown_radius(sk: &Skeleton, leaves: &Leaves) -> f32 {
    let root = sk.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO);
    let d = |p: Vec3| ((p - root) * Vec3::new(1.0, 1.0, 0.0)).length();
    let a = sk.nodes.iter().map(|n| d(n.pos)).fold(0.0, f32::max);
    leaves.leaves.iter().map(|l| d(l.pos + l.dir * l.size)).fold(a, f32::max)
}

/// Number of compass directions of [`crown_radii`] (8, one each 45°).
pub const CROWN_RADII: usize = 8;

/// Crown radii of a skeleton with its leaves in the [`CROWN_RADII`] compass directions (m): in
/// each 45° sector around direction `k · 45°` (counter-clockwise from +x), the largest
/// horizontal distance from the root axis of a node or a leaf tip in it; 0 for a sector the
/// crown does not reach (a crown made one-sided by a wall). The forest-mensuration practice of
/// measuring a crown's projection by eight radii (Pretzsch 2009, *Forest Dynamics, Growth and
/// Yield*, Springer: crown projection areas from crown radii in the eight compass directions).
pub fn crown_radii(sk: &Skeleton, leaves: &Leaves) -> [f32; CROWN_RADII] {
    let root = sk.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO);
    let mut r = [0.0f32; CROWN_RADII];
    let sector = std::f32::consts::TAU / CROWN_RADII as f32;
    let mut add = |p: Vec3| {
        let d = (p - root).truncate();
        let rho = d.length();
        if rho > 0.0 {
            let k = ((d.y.atan2(d.x) / sector).round() as i32).rem_euclid(CROWN_RADII as i32) as usize;
            r[k] = r[k].max(rho);
        }
    };
    sk.nodes.iter().for_each(|n| add(n.pos));
    leaves.leaves.iter().for_each(|l| add(l.pos + l.dir * l.size));
    r
}

/// Crown projection area (m²) of a skeleton with its leaves: the octagon of its eight
/// [`crown_radii`], `A = ½ · sin 45° · Σ r_k · r_(k+1)` (a circle of radius R gives 2√2 R²,
/// 0.90 of π R²; a crown cut in half by a wall about half of that).
pub fn crown_projection_area(sk: &Skeleton, leaves: &Leaves) -> f32 {
    let r = crown_radii(sk, leaves);
    let s = (std::f32::consts::TAU / CROWN_RADII as f32).sin();
    0.5 * s * (0..CROWN_RADII).map(|k| r[k] * r[(k + 1) % CROWN_RADII]).sum::<f32>()
}

#[cfg(test)]
mod crown_projection_tests {
    use super::*;

    /// A trunk from the origin to 2 m and leaves whose tips lie on a circle of radius 3 m at
    /// the given compass angles (degrees).
    fn ring(angles: impl Iterator<Item = f32>) -> (Skeleton, Leaves) {
        let mut sk = Skeleton::new();
        let root = sk.add_root(Vec3::ZERO, 0.1);
        let top = sk.add_child(root, Vec3::new(0.0, 0.0, 2.0), 0.05, false).unwrap();
        let mut lv = Leaves::default();
        for a in angles {
            let d = Vec3::new(a.to_radians().cos(), a.to_radians().sin(), 0.0);
            lv.leaves.push(Leaf { pos: d * 2.9 + Vec3::Z * 2.0, dir: d, normal: Vec3::Z, size: 0.1, node: top });
        }
        (sk, lv)
    }

    #[test]
    fn a_round_crown_projects_as_the_octagon_of_its_radius() {
        let (sk, lv) = ring((0..72).map(|k| k as f32 * 5.0));
        let r = crown_radii(&sk, &lv);
        assert!(r.iter().all(|&x| (x - 3.0).abs() < 1e-4), "{r:?}");
        // 2√2 R² = 25.456 m² for R = 3 m
        assert!((crown_projection_area(&sk, &lv) - 2.0 * 2f32.sqrt() * 9.0).abs() < 1e-3);
    }

    #[test]
    fn a_crown_cut_by_a_wall_projects_about_half() {
        // leaves only on the +x side (−90°..90°): sectors 3, 4, 5 (135°, 180°, 225°) empty
        let (sk, lv) = ring((0..37).map(|k| -90.0 + k as f32 * 5.0));
        let r = crown_radii(&sk, &lv);
        assert_eq!((r[3], r[4], r[5]), (0.0, 0.0, 0.0));
        let full = 2.0 * 2f32.sqrt() * 9.0;
        let a = crown_projection_area(&sk, &lv);
        // the four triangles between the five radii that are 3 m: 4/8 of the octagon
        assert!((a - 0.5 * full).abs() < 1e-3, "{a} vs {}", 0.5 * full);
    }
}
