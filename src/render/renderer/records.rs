//! The records the renderer keeps on the GPU and writes each frame: uniforms, culling parameters,
//! silhouettes, vertices, the uploaded scene and terrain.

use super::*;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Globals {
    pub(super) view_proj: [[f32; 4]; 4],
    pub(super) light_view_proj: [[f32; 4]; 4],
    pub(super) inv_view_proj: [[f32; 4]; 4],
    pub(super) eye: [f32; 4],
    pub(super) sun_dir: [f32; 4],
    pub(super) sun_color: [f32; 4],
    pub(super) sky_zenith: [f32; 4],
    pub(super) sky_horizon: [f32; 4],
    pub(super) wind: [f32; 4],
    pub(super) params: [f32; 4],
    pub(super) facing: [f32; 4],
    /// canopy grid: origin x, y (m), texel (m), on (1) / off (0)
    pub(super) canopy0: [f32; 4],
    /// canopy grid: nx, ny, oblique-view factor k, height above the ground (m) at which the
    /// layer's crowns take their sun visibility ([`canopy_light_height`])
    pub(super) canopy1: [f32; 4],
    /// shadow map: texel (uv), depth bias (depth units), texel (m), unused
    pub(super) shadow: [f32; 4],
}

/// Per-prototype outline record of `shaders/scene.wgsl` (`Sil`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SilRaw {
    pub(super) w: [f32; SILHOUETTE_BINS],
    pub(super) info: [f32; 4],
    /// crown look: top flatness, plan cover, clumping, first leaf texture layer (−1: none)
    /// ([`crate::render::lod::CrownLook`])
    pub(super) look: [f32; 4],
}

/// Uniforms of `shaders/cull.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct CullParams {
    pub(super) planes: [[f32; 4]; 6],
    pub(super) eye: [f32; 4],
    pub(super) lod: [f32; 4],
    pub(super) misc: [f32; 4],
    pub(super) counts: [u32; 4],
    /// canopy grid origin x, y (m), texel (m); base far-field switch (px, 0 = off)
    pub(super) canopy: [f32; 4],
    /// canopy grid nx, ny; geometry triangle budget of the far-field switch (0 = none); bits of
    /// the small-tree height of the level choice (`LodParams::small_tree_m`, f32, 0 = off)
    pub(super) canopy_n: [u32; 4],
}

/// Where culling and level-of-detail selection run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Culling {
    /// On the GPU when the adapter supports compute shaders and indirect draws (and the
    /// compacted buffers fit its limits), else on the CPU.
    #[default]
    Auto,
    /// Always on the CPU (rayon), with direct instanced draws.
    Cpu,
    /// Always in the compute pass; [`Renderer::render`] fails with [`RenderError::GpuCullingUnavailable`] when the
    /// adapter cannot do it.
    Gpu,
}

/// Per-frame state of the GPU culling path: one slot per (prototype, drawn level).
pub(super) struct GpuSlot {
    pub(super) prototype: usize,
    pub(super) level: usize,
    /// First compacted instance of the slot and its capacity (instances).
    pub(super) base: u32,
    pub(super) cap: u32,
}

pub(super) struct GpuCull {
    pub(super) pipeline: wgpu::ComputePipeline,
    pub(super) hist: wgpu::ComputePipeline,
    pub(super) choose: wgpu::ComputePipeline,
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) params: wgpu::Buffer,
    /// src, protos, dst, args, readback (buffer, capacity in bytes)
    pub(super) src: Option<(wgpu::Buffer, u64)>,
    pub(super) protos: Option<(wgpu::Buffer, u64)>,
    pub(super) dst: Option<(wgpu::Buffer, u64)>,
    pub(super) args: Option<(wgpu::Buffer, u64)>,
    pub(super) readback: Option<(wgpu::Buffer, u64)>,
}

pub(super) struct GpuFrame {
    pub(super) slots: Vec<GpuSlot>,
    /// Whether the `hist` and `choose` passes run (either triangle budget).
    pub(super) budget: bool,
    pub(super) invalid: usize,
    pub(super) valid: usize,
    pub(super) args_bytes: u64,
}

pub(super) enum FrameDraws {
    Cpu(Batches),
    Gpu(GpuFrame),
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct TerrainVertex {
    pub(super) pos: [f32; 3],
    pub(super) normal: [f32; 3],
    pub(super) color: [f32; 3],
    /// dissolve into the sky 0..1 (`TerrainMesh::fade`)
    pub(super) fade: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct TreeVertex {
    pub(super) pos: [f32; 3],
    pub(super) normal: [f32; 3],
    pub(super) mat: f32,
    /// Card coordinates 0..1 of leaf cards (carved into discs by the fragment shader); (−1,
    /// twig factor 0..1, see `twig_factor`) on bark; (−1, −1) elsewhere.
    pub(super) uv: [f32; 2],
}

pub(super) struct GpuLevel {
    pub(super) vb: wgpu::Buffer,
    pub(super) ib: wgpu::Buffer,
    /// index ranges of bark and leaves
    pub(super) bark: std::ops::Range<u32>,
    pub(super) leaves: std::ops::Range<u32>,
}

/// The scene's static data on the GPU, in two parts uploaded separately: the terrain (with the
/// water plane and the canopy grid over it) and the prototypes (meshes and silhouettes); each
/// part is uploaded again only when its [`crate::render::scene::Version`] changes.
pub(super) struct GpuScene {
    /// Version of the uploaded terrain and sea level.
    pub(super) terrain_version: crate::render::scene::Version,
    /// Version of the uploaded prototypes.
    pub(super) protos_version: crate::render::scene::Version,
    pub(super) terrain_vb: Option<wgpu::Buffer>,
    pub(super) terrain_ib: Option<wgpu::Buffer>,
    pub(super) terrain_count: u32,
    /// The coarse terrain of frames in motion ([`Renderer::coarse_terrain`]) and its index count.
    pub(super) terrain_coarse: Option<(wgpu::Buffer, u32)>,
    pub(super) water_vb: Option<wgpu::Buffer>,
    /// Drawn levels per prototype (chain meshes, then the billboard).
    pub(super) protos: Vec<Vec<GpuLevel>>,
    /// Silhouettes of the prototypes (storage buffer of `SilRaw`).
    pub(super) sil_buf: wgpu::Buffer,
    /// Canopy layer: grid and its per-frame sums (`[u32; 4]` per texel).
    pub(super) canopy_grid: crate::render::canopy::CanopyGrid,
    pub(super) canopy_buf: wgpu::Buffer,
    pub(super) bind_main: wgpu::BindGroup,
    pub(super) bind_shadow: wgpu::BindGroup,
}

/// The terrain part of [`GpuScene`].
pub(super) struct GpuTerrain {
    pub(super) vb: Option<wgpu::Buffer>,
    pub(super) ib: Option<wgpu::Buffer>,
    pub(super) count: u32,
    pub(super) coarse: Option<(wgpu::Buffer, u32)>,
    pub(super) water_vb: Option<wgpu::Buffer>,
    pub(super) canopy_grid: crate::render::canopy::CanopyGrid,
    pub(super) canopy_buf: wgpu::Buffer,
}

/// Multisampled colour and depth targets of one frame size (any output view).
pub(super) struct Targets {
    pub(super) size: (u32, u32),
    pub(super) msaa: wgpu::TextureView,
    pub(super) depth: wgpu::TextureView,
    /// Depth of single-sample frames ([`Renderer::single_sample`]).
    pub(super) depth1: wgpu::TextureView,
}

/// The main pass's pipelines without multisampling (sky, terrain, water, trees).
pub(super) struct SinglePipelines {
    pub(super) sky: wgpu::RenderPipeline,
    pub(super) terrain: wgpu::RenderPipeline,
    pub(super) water: wgpu::RenderPipeline,
    pub(super) tree: wgpu::RenderPipeline,
}
