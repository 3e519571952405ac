//! Rendering: the terrain and thousands of trees with levels of detail, headless into stills and
//! timelapses (issue 6).
//!
//! The renderer never reads the simulation: callers fill the plain data of [`scene`]
//! ([`scene::TerrainMesh`], [`scene::Prototype`], [`scene::TreeInstance`], [`scene::Sun`], ...)
//! and hand it to [`headless::Renderer::render`] with a [`scene::Camera`]. It runs on any wgpu
//! adapter, including Mesa's lavapipe software rasteriser that CI uses.
//!
//! - [`terrain`]: builds a [`scene::TerrainMesh`] from a height grid or a TIN, coloured by
//!   elevation/slope (land cover) or an overlay field.
//! - [`lod`]: level-of-detail selection by projected size, frustum culling, stand-in tree chains.
//! - [`instanced`]: CPU culling/LOD pass that groups instances into one draw per
//!   (prototype, level, material).
//! - [`timelapse`]: interpolation of snapshots, GIF/PNG/MP4 writers.

pub mod camera;
pub mod headless;
pub mod instanced;
pub mod lod;
pub mod scene;
pub mod terrain;
pub mod timelapse;
