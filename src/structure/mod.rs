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
//! - [`texture`]: procedural leaf-card (per leaf shape), LOD and bark textures.
//! - [`plastic`]: Plastic Trees (`000_*.txt`): bends and prunes a grown skeleton for a new
//!   obstacle instead of regrowing it.

pub mod crown_hull;
pub mod edit_distance;
pub mod grow;
pub mod mesh;
pub mod params;
pub mod plastic;
pub mod skeleton;
pub mod species_tree;
pub mod stand;
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
/// `architecture.ecomod` parameters (seed `seed`, t = 0), normalised to height 1 m with its base
/// at the origin, z up, meshed with the default [`mesh::LodOptions`]; the renderer scales each
/// instance by its height and crown radius. Bad parameters give an empty chain (and a warning).
pub fn species_lod_chain(species: &Species, seed: u64) -> LodChain {
    let grown = grow::ecomod::try_grow(&species.architecture.ecomod, seed, 0.0).and_then(|(sk, lv)| normalised(&sk, &lv, 1.0));
    match grown {
        Ok((sk, lv)) => mesh::lod_chain(&sk, &lv, &mesh::LodOptions::default()),
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
