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
