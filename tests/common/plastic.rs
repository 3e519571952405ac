//! Helpers shared by the Plastic Trees tests (`tests/structure_plastic*.rs`): the species, the
//! paper's Tree 1 tropisms, a grown light-guided tree and the centroid of its tips.
#![allow(dead_code)]
use glam::Vec3;
use sylva::species::{PlasticParams, Species, SpeciesLibrary};
use sylva::structure::species_tree::{grow_species_tree, GrownTree, Model};
use sylva::structure::Skeleton;

/// Mean position (m) of the skeleton's terminal nodes.
pub fn tip_centroid(sk: &Skeleton) -> Vec3 {
    let tips: Vec<Vec3> = sk.nodes.iter().filter(|n| n.children.is_empty()).map(|n| n.pos).collect();
    tips.iter().copied().sum::<Vec3>() / tips.len() as f32
}

/// The embedded beech.
pub fn beech() -> Species {
    let lib = SpeciesLibrary::embedded().unwrap();
    lib.species[lib.find("beech").unwrap() as usize].clone()
}

/// The paper's Tree 1 tropisms (section 6): phototropism 0.25, gravitropism 0.12.
pub fn tree1(sp: &Species) -> PlasticParams {
    let mut p = sp.architecture.plastic;
    p.phototropism = 0.25;
    p.gravitropism = 0.12;
    p
}

/// A light-guided tree of `sp` grown in the open to `age` years with `seed`.
pub fn grow(sp: &Species, age: f32, seed: u64) -> GrownTree {
    grow_species_tree(sp, Model::Light, age, &[], seed).unwrap()
}

/// Height (m) that beech's height–age curve gave at `age` years before its refit of issue 35
/// round 39 (Chapman–Richards `48 (1 − e^(−0.0129 t))^1.211`, fitted through the NW-FVA 2021
/// class I top heights at 50 and 100 years), in the f32 arithmetic of
/// `allometry::potential_height`: the sizes the Plastic Trees tests were written for.
pub fn beech_height_before_round_39(age: f32) -> f32 {
    48.0f32 * (1.0 - (-0.0129f32 * age).exp()).powf(1.211)
}

/// The light-guided beech that [`grow`] gave at `age` years before round 39: a tree of
/// [`beech_height_before_round_39`] grown in `age` cycles (`grow_light_guided_tree`), so a test
/// keeps its tree's size and growth history (and so its node count and shedding) whatever
/// beech's height curve (issue 35, round 40).
pub fn grow_beech_sized_as_before_round_39(sp: &Species, age: u32, seed: u64) -> GrownTree {
    sylva::structure::species_tree::grow_light_guided_tree(sp, beech_height_before_round_39(age as f32), age, &[], seed).unwrap()
}
