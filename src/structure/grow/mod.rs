//! Growth models that build skeletons: EcoMod strands ([`ecomod`]), light-guided
//! self-organisation ([`light_guided`]) and Laplacian growth ([`laplacian`]), plus the voxel
//! space and obstacles they share ([`space`]).

pub mod ecomod;
pub mod envelope;
pub mod laplacian;
pub mod light_guided;
pub mod space;
