//! Tree architecture: branching skeletons grown by three models from the seed papers, meshes
//! with levels of detail, and the per-species representative tree the renderer instances.
//!
//! - [`skeleton`]: flat node arena, Strahler/Gravelius/Weibull orders, pipe-model radii.
//! - [`grow`]: EcoMod strands (`004_*.txt`), light-guided growth (`001_*.txt`), Laplacian growth
//!   (`003_*.txt`).
//! - [`mesh`]: generalized cylinders, leaf cards and the LOD chain.
//! - [`params`]: the papers' parameter sets.

pub mod grow;
pub mod mesh;
pub mod params;
pub mod skeleton;

pub use skeleton::{Leaf, Leaves, Node, NodeId, Role, Skeleton};
