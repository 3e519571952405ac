//! Rendering: the terrain and thousands of trees with levels of detail, into any texture view
//! (a window's surface, an offscreen texture) or headless into stills and timelapses (issue 6).
//!
//! The renderer never reads the simulation: callers fill the plain data of [`scene`]
//! ([`scene::TerrainMesh`], [`scene::Prototype`], [`scene::TreeInstance`], [`scene::Sun`], ...)
//! and hand it with a [`scene::Camera`] to [`renderer::Renderer::render_to_view`] (a renderer
//! made with [`renderer::Renderer::from_device`] on the caller's device) or to the headless
//! [`headless`] layer's [`headless::Renderer::render`] (own adapter, texture and readback). It
//! runs on any wgpu adapter, including Mesa's lavapipe software rasteriser that CI uses.
//!
//! - [`renderer`]: the renderer (pipelines, uploads, culling paths, the frame into a view);
//!   [`headless`]: adapter, texture and readback on top of it.
//! - [`terrain`]: builds a [`scene::TerrainMesh`] from a height grid or a TIN, coloured by
//!   elevation/slope (land cover) or an overlay field.
//! - [`lod`]: level-of-detail selection by projected size (with dithered cross-fade bands and a
//!   per-frame triangle budget), frustum culling, the billboard [`lod::Silhouette`], stand-in
//!   tree chains.
//! - [`instanced`]: CPU culling/LOD pass that groups instances into one draw per
//!   (prototype, level, material). The same selection runs on the GPU in a compute pass
//!   (`shaders/cull.wgsl`) feeding indirect draws when the adapter allows it
//!   ([`headless::Culling`]).
//!
//! Each species is drawn with the chain's full, reduced and hull meshes near the camera and the
//! renderer's own 4-triangle billboard impostor (the species' silhouette carved procedurally)
//! below 40 px; bare (winter) crowns keep a dithered grey-brown twig haze at every level.
//! Below a few pixels (the far-field switch, raised so that at most
//! [`lod::LodParams::max_geometry_trees`] trees are geometry) crowns leave the geometry for the
//! [`canopy`] layer: splatted per frame into a terrain-texel grid of colour and coverage that
//! the terrain shader blends in, cross-faded with the billboards, so triangles per frame level
//! off as the tree count grows.
//! - [`farfield`]: the canopy layer baked once for a set of trees (a year of the viewer), the
//!   trees sorted into plan tiles so that a frame culls only those that may show as geometry.
//! - [`timelapse`]: interpolation of snapshots and frame sequences (the GIF/PNG/MP4 writers are
//!   in [`crate::output::pictures`]).

mod error;
pub use error::{RenderError, Result};

pub mod camera;
pub mod canopy;
pub mod farfield;
pub mod headless;
pub mod instanced;
pub mod lod;
pub mod overlay;
pub mod renderer;
pub mod scene;
pub mod terrain;
pub mod timelapse;
