//! The wgpu renderer: terrain, water, sky and instanced trees drawn into any texture view
//! ([`Renderer::render_to_view`], on a device given with [`Renderer::from_device`]). The
//! headless layer on top is [`super::headless`] ([`Renderer::new`] opens an adapter,
//! [`Renderer::render`] draws into its own texture and reads it back as an RGBA image).
//!
//! Passes per frame: (0) culling and level selection, on the CPU ([`build_batches`]) or in a
//! compute pass (`shaders/cull.wgsl`, see [`Culling`]), (1) sun shadow map (2048², depth only,
//! terrain and trees), (2) main pass with 4× MSAA and depth: sky gradient, terrain, trees (one
//! instanced draw — direct on the CPU path, indirect on the GPU path — per prototype, level and
//! material), water; resolved into the given view (headless: a texture read back with rows
//! padded to 256 bytes).
//!
//! Trees are opaque, depth-tested, and all fades (level cross-fades, timelapse opacity, leaf
//! amount) are screen-door dithers decided per pixel from the screen position and per-tree
//! constants, never by blending; so the image does not depend on the order in which instances
//! are drawn, and the GPU path's atomically compacted (unordered) instance lists give the same
//! pixels as the CPU path's ordered ones.


use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use super::camera::Camera;
use super::farfield::FarField;
pub use super::canopy::{canopy_light_height, tree_extent};
use super::instanced::{build_batches_of, instance_record, level_triangles, Batches, InstanceRaw};
use super::lod::{drawn_levels, Frustum, LodParams, Silhouette, SILHOUETTE_BINS};
use super::scene::{Scene, TreeInstance};
use crate::mesh::LOD_LEVELS;
use crate::structure::texture::{self, LeafShape};

// `shaders/cull.wgsl` keeps one drawn level per word of a 4-word record (the level costs of a
// prototype, `cost()`), so the number of levels is tied to that record width.
const _: () = assert!(LOD_LEVELS == 4, "cull.wgsl packs the level costs of a prototype into one vec4<u32>-sized record");
use super::{RenderError, Result};
use crate::Error;

/// Colour format of the headless texture (sRGB RGBA, read back as an image).
pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SHADOW_SIZE: u32 = 2048;
const SAMPLES: u32 = 4;
/// Triangles of the coarse terrain mesh of [`Renderer::coarse_terrain`] (at most about).
pub const COARSE_TERRAIN_TRIANGLES: usize = 100_000;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    light_view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    sun_dir: [f32; 4],
    sun_color: [f32; 4],
    sky_zenith: [f32; 4],
    sky_horizon: [f32; 4],
    wind: [f32; 4],
    params: [f32; 4],
    facing: [f32; 4],
    /// canopy grid: origin x, y (m), texel (m), on (1) / off (0)
    canopy0: [f32; 4],
    /// canopy grid: nx, ny, oblique-view factor k, height above the ground (m) at which the
    /// layer's crowns take their sun visibility ([`canopy_light_height`])
    canopy1: [f32; 4],
    /// shadow map: texel (uv), depth bias (depth units), texel (m), unused
    shadow: [f32; 4],
}

/// Per-prototype outline record of `shaders/scene.wgsl` (`Sil`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SilRaw {
    w: [f32; SILHOUETTE_BINS],
    info: [f32; 4],
    /// crown look: top flatness, plan cover, clumping, first leaf texture layer (−1: none)
    /// ([`super::lod::CrownLook`])
    look: [f32; 4],
}

/// Uniforms of `shaders/cull.wgsl` (`Params`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CullParams {
    planes: [[f32; 4]; 6],
    eye: [f32; 4],
    lod: [f32; 4],
    misc: [f32; 4],
    counts: [u32; 4],
    /// canopy grid origin x, y (m), texel (m); base far-field switch (px, 0 = off)
    canopy: [f32; 4],
    /// canopy grid nx, ny; geometry triangle budget of the far-field switch (0 = none); unused
    canopy_n: [u32; 4],
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
struct GpuSlot {
    prototype: usize,
    level: usize,
    /// First compacted instance of the slot and its capacity (instances).
    base: u32,
    cap: u32,
}

struct GpuCull {
    pipeline: wgpu::ComputePipeline,
    hist: wgpu::ComputePipeline,
    choose: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// src, protos, dst, args, readback (buffer, capacity in bytes)
    src: Option<(wgpu::Buffer, u64)>,
    protos: Option<(wgpu::Buffer, u64)>,
    dst: Option<(wgpu::Buffer, u64)>,
    args: Option<(wgpu::Buffer, u64)>,
    readback: Option<(wgpu::Buffer, u64)>,
}

struct GpuFrame {
    slots: Vec<GpuSlot>,
    /// Whether the `hist` and `choose` passes run (either triangle budget).
    budget: bool,
    invalid: usize,
    valid: usize,
    args_bytes: u64,
}

enum FrameDraws {
    Cpu(Batches),
    Gpu(GpuFrame),
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TerrainVertex {
    pos: [f32; 3],
    normal: [f32; 3],
    color: [f32; 3],
    /// dissolve into the sky 0..1 (`TerrainMesh::fade`)
    fade: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TreeVertex {
    pos: [f32; 3],
    normal: [f32; 3],
    mat: f32,
    /// Card coordinates 0..1 of leaf cards (carved into discs by the fragment shader); (−1,
    /// twig factor 0..1, see `twig_factor`) on bark; (−1, −1) elsewhere.
    uv: [f32; 2],
}

/// Side (texels) of each layer of the renderer's leaf texture array.
const LEAF_TEX_PX: u32 = 64;

/// The layers of the renderer's leaf texture array, in order: per [`LeafShape::ALL`] entry `k`,
/// layer `2k` its leaf card ([`texture::leaf_texture_sized`], the 1:2 card drawn into a square)
/// and layer `2k + 1` its leaf-cluster card ([`texture::cluster_texture`]); grey shading in RGB,
/// coverage in alpha (alpha-tested at [`texture::ALPHA_CUTOFF`] by the tree shader).
fn leaf_layers() -> Vec<image::RgbaImage> {
    LeafShape::ALL.iter().flat_map(|&s| [texture::leaf_texture_sized(s, LEAF_TEX_PX, LEAF_TEX_PX), texture::cluster_texture(s, LEAF_TEX_PX)]).collect()
}

/// Index of the first layer of `shape` in the leaf texture array (−1: no texture).
fn leaf_layer(shape: Option<LeafShape>) -> f32 {
    shape.and_then(|s| LeafShape::ALL.iter().position(|&x| x == s)).map(|k| 2.0 * k as f32).unwrap_or(-1.0)
}

/// Uploads [`leaf_layers`] as a 2-D texture array (RGBA8 linear: the RGB is a shading factor,
/// not a colour) with a bilinear clamped sampler.
fn leaf_texture_array(device: &wgpu::Device, queue: &wgpu::Queue) -> (wgpu::TextureView, wgpu::Sampler) {
    let layers = leaf_layers();
    let size = wgpu::Extent3d { width: LEAF_TEX_PX, height: LEAF_TEX_PX, depth_or_array_layers: layers.len() as u32 };
    let tex = device.create_texture(&wgpu::TextureDescriptor { label: Some("leaf textures"), size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format: wgpu::TextureFormat::Rgba8Unorm, usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST, view_formats: &[] });
    for (k, img) in layers.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo { texture: &tex, mip_level: 0, origin: wgpu::Origin3d { x: 0, y: 0, z: k as u32 }, aspect: wgpu::TextureAspect::All },
            img.as_raw(),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * LEAF_TEX_PX), rows_per_image: Some(LEAF_TEX_PX) },
            wgpu::Extent3d { width: LEAF_TEX_PX, height: LEAF_TEX_PX, depth_or_array_layers: 1 },
        );
    }
    let view = tex.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() });
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor { label: Some("leaf sampler"), mag_filter: wgpu::FilterMode::Linear, min_filter: wgpu::FilterMode::Linear, ..Default::default() });
    (view, sampler)
}

/// How far a bark vertex at `p` (normalised model, m per m of height) is out among the twigs,
/// 0..1: 0 within 15 % of the crown radius `r0` of the stem axis, 1 beyond 55 % (smoothstep).
/// The tree shader darkens the bark towards the twig colour by it.
fn twig_factor(p: &[f32; 3], r0: f32) -> f32 {
    let t = (((p[0] * p[0] + p[1] * p[1]).sqrt() / r0 - 0.15) / 0.4).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Whether `m` is a set of leaf cards: quads of 4 vertices and 2 triangles each with texture
/// coordinates (0,0), (1,0), (1,1), (0,1) (`structure::mesh` cards).
fn is_cards(m: &crate::mesh::TriMesh) -> bool {
    let n = m.positions.len();
    n > 0
        && n % 4 == 0
        && m.uvs.len() == n
        && m.indices.len() == n / 4 * 6
        && m.uvs.chunks(4).all(|q| {
            let want = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            q.iter().zip(want).all(|(a, b)| (a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4)
        })
}

struct GpuLevel {
    vb: wgpu::Buffer,
    ib: wgpu::Buffer,
    /// index ranges of bark and leaves
    bark: std::ops::Range<u32>,
    leaves: std::ops::Range<u32>,
}

/// The scene's static data on the GPU, in two parts uploaded separately: the terrain (with the
/// water plane and the canopy grid over it) and the prototypes (meshes and silhouettes); each
/// part is uploaded again only when its [`super::scene::Version`] changes.
struct GpuScene {
    /// Version of the uploaded terrain and sea level.
    terrain_version: super::scene::Version,
    /// Version of the uploaded prototypes.
    protos_version: super::scene::Version,
    terrain_vb: Option<wgpu::Buffer>,
    terrain_ib: Option<wgpu::Buffer>,
    terrain_count: u32,
    /// The coarse terrain of frames in motion ([`Renderer::coarse_terrain`]) and its index count.
    terrain_coarse: Option<(wgpu::Buffer, u32)>,
    water_vb: Option<wgpu::Buffer>,
    /// Drawn levels per prototype (chain meshes, then the billboard).
    protos: Vec<Vec<GpuLevel>>,
    /// Silhouettes of the prototypes (storage buffer of `SilRaw`).
    sil_buf: wgpu::Buffer,
    /// Canopy layer: grid and its per-frame sums (`[u32; 4]` per texel).
    canopy_grid: super::canopy::CanopyGrid,
    canopy_buf: wgpu::Buffer,
    bind_main: wgpu::BindGroup,
    bind_shadow: wgpu::BindGroup,
}

/// The terrain part of [`GpuScene`].
struct GpuTerrain {
    vb: Option<wgpu::Buffer>,
    ib: Option<wgpu::Buffer>,
    count: u32,
    coarse: Option<(wgpu::Buffer, u32)>,
    water_vb: Option<wgpu::Buffer>,
    canopy_grid: super::canopy::CanopyGrid,
    canopy_buf: wgpu::Buffer,
}

/// The billboard impostor level of a prototype with outline `s`: a vertical quad (material 2,
/// turned towards the viewer in the vertex shader) spanning the crown width and the full height,
/// and a horizontal quad (material 3) in the upper crown, which the vertex shader shows only
/// for views from well above (top-down maps). Vertex normals carry the
/// outline coordinates the fragment shader carves with (side: a ∈ −1..1 across, z 0..1 up;
/// top: a, b ∈ −1..1).
fn billboard_vertices(s: &Silhouette) -> (Vec<TreeVertex>, Vec<u32>) {
    let r = s.radius;
    // the top quad sits a third of the way from the widest point to the top and is as wide as
    // the widest point: the crown's plan projection, which is what a view from above sees (a
    // spire's cone included), so that crowns of a closed stand close up in a map view
    let zc = s.widest_z + 0.35 * (s.crown_top - s.widest_z).max(0.0);
    let rt = r;
    let v = |x: f32, y: f32, z: f32, a: f32, b: f32, mat: f32| TreeVertex { pos: [x, y, z], normal: [a, b, 0.0], mat, uv: [-1.0, -1.0] };
    let verts = vec![
        v(-r, 0.0, 0.0, -1.0, 0.0, 2.0),
        v(r, 0.0, 0.0, 1.0, 0.0, 2.0),
        v(r, 0.0, 1.0, 1.0, 1.0, 2.0),
        v(-r, 0.0, 1.0, -1.0, 1.0, 2.0),
        v(-rt, -rt, zc, -1.0, -1.0, 3.0),
        v(rt, -rt, zc, 1.0, -1.0, 3.0),
        v(rt, rt, zc, 1.0, 1.0, 3.0),
        v(-rt, rt, zc, -1.0, 1.0, 3.0),
    ];
    (verts, vec![0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7])
}

/// Multisampled colour and depth targets of one frame size (any output view).
struct Targets {
    size: (u32, u32),
    msaa: wgpu::TextureView,
    depth: wgpu::TextureView,
    /// Depth of single-sample frames ([`Renderer::single_sample`]).
    depth1: wgpu::TextureView,
}

/// The main pass's pipelines without multisampling (sky, terrain, water, trees).
struct SinglePipelines {
    sky: wgpu::RenderPipeline,
    terrain: wgpu::RenderPipeline,
    water: wgpu::RenderPipeline,
    tree: wgpu::RenderPipeline,
}

/// The headless output ([`super::headless`]): a texture to draw into and a buffer to read it
/// back.
pub(super) struct Readback {
    pub(super) size: (u32, u32),
    pub(super) texture: wgpu::Texture,
    pub(super) view: wgpu::TextureView,
    pub(super) buffer: wgpu::Buffer,
    pub(super) padded_row: u32,
}

/// Statistics of the last frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Triangles submitted in the main pass (terrain + trees).
    pub triangles: u64,
    /// Tree triangles alone.
    pub tree_triangles: u64,
    /// Instanced draw calls of trees in the main pass.
    pub tree_draws: u32,
    /// Instances drawn (cross-fading ones count once).
    pub instances_drawn: usize,
    /// Instances culled (frustum or size).
    pub culled: usize,
    /// Instances skipped for invalid data.
    pub invalid: usize,
    /// Drawn instances per level of detail (level 3 = billboard impostor for 4-level chains).
    pub per_level: [usize; LOD_LEVELS],
    /// Whether culling and level selection ran in the GPU compute pass.
    pub gpu_culling: bool,
    /// Factor by which the level switch sizes were raised to meet
    /// [`LodParams::max_triangles`] (1 = not needed).
    pub lod_scale: f32,
    /// Far-field switch of the frame (px; 0 = canopy layer off): trees below it (less the
    /// cross-fade band) are drawn only in the canopy layer.
    pub canopy_px: f32,
    /// Trees drawn only in the canopy layer (no triangles).
    pub canopy_trees: usize,
    /// The terrain (and water plane) was uploaded for this frame (its content changed).
    pub uploaded_terrain: bool,
    /// The prototypes were uploaded for this frame (their content changed).
    pub uploaded_prototypes: bool,
}

/// The renderer, bound to one wgpu device: draws a [`Scene`] into any texture view of its target
/// format ([`Renderer::render_to_view`]: a window's surface, an offscreen texture). Built on an
/// existing device with [`Renderer::from_device`], or headless with [`Renderer::new`], which
/// opens its own adapter and adds a texture and a readback ([`Renderer::render`] returns an
/// image).
pub struct Renderer {
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    adapter_info: wgpu::AdapterInfo,
    sky: wgpu::RenderPipeline,
    terrain: wgpu::RenderPipeline,
    water: wgpu::RenderPipeline,
    tree: wgpu::RenderPipeline,
    terrain_shadow: wgpu::RenderPipeline,
    tree_shadow: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    shadow_globals: wgpu::Buffer,
    shadow_view: wgpu::TextureView,
    layout_main: wgpu::BindGroupLayout,
    layout_shadow: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    /// Leaf alpha textures, two layers per [`LeafShape`] (see [`leaf_layers`]), and their sampler.
    leaf_view: wgpu::TextureView,
    leaf_sampler: wgpu::Sampler,
    cull: Option<GpuCull>,
    instance_buf: Option<(wgpu::Buffer, u64)>,
    scene: Option<GpuScene>,
    targets: Option<Targets>,
    pub(super) readback: Option<Readback>,
    pub(super) format: wgpu::TextureFormat,
    /// Level-of-detail parameters used by [`Renderer::render`].
    pub lod: LodParams,
    /// Where culling and level selection run (default [`Culling::Auto`]).
    pub culling: Culling,
    /// Keep the sun's shadow map of the last frame instead of drawing it again (default false):
    /// the map depends on the scene and the sun, not on the camera, so a viewer moving its
    /// camera over an unchanged scene can skip the shadow pass (it is drawn anew after the
    /// terrain or the tree models change, and whenever this is false).
    pub reuse_shadow_map: bool,
    single: SinglePipelines,
    /// Draw the main pass without multisampling (default false: 4× MSAA): a quarter of the
    /// samples to rasterise, jagged edges; for frames in motion on a software adapter.
    pub single_sample: bool,
    /// Whether the shadow map holds a frame of the current terrain and models.
    shadow_ok: bool,
    /// The sun's view-projection the shadow map was drawn with (what a frame that reuses the
    /// map looks it up with).
    shadow_light: (Mat4, f32, f32),
    /// A far field baked for this scene (default `None`): when set, the renderer draws its
    /// trees instead of the scene's instances. Each frame takes from it the trees of the tiles
    /// that may show as geometry ([`FarField::near`], at most [`Renderer::max_near_trees`]) and
    /// culls only those; every other tree is drawn by the baked canopy layer. Its canopy grid
    /// must be the one of the scene's terrain (it is baked for a terrain, [`FarField::new`]);
    /// when it is not, the far field is not used.
    pub far_field: Option<std::sync::Arc<FarField>>,
    /// At most this many trees of [`Renderer::far_field`] are culled and drawn as geometry in a
    /// frame (0 = every tree that may be taller on screen than the far-field switch): the tiles
    /// whose trees may look tallest first, and the frame's far-field switch rises above the
    /// trees left to the canopy layer. For frames in motion.
    pub max_near_trees: usize,
    /// Cheaper shading (default false): one shadow-map tap for the sun and one for the sky light
    /// under the canopy instead of 9 and 9 per pixel; harder shadow edges, for frames in motion
    /// on a software adapter, where the terrain's pixels are most of a frame.
    pub fast_shading: bool,
    /// Draw the terrain's coarse mesh in the main pass (default false): a grid terrain of more
    /// than [`COARSE_TERRAIN_TRIANGLES`] triangles over every k-th vertex so that it has about
    /// that many ([`TerrainMesh::coarse_indices`]); the shadow pass keeps the full mesh. For
    /// frames in motion on a software adapter, where triangle setup is a fixed cost per frame.
    ///
    /// [`TerrainMesh::coarse_indices`]: super::terrain::TerrainMesh::coarse_indices
    pub coarse_terrain: bool,
    /// The far field the shadow map was drawn with (a new one redraws it).
    shadow_far: Option<std::sync::Arc<FarField>>,
    last: FrameStats,
}

fn terrain_layout() -> wgpu::VertexBufferLayout<'static> {
    const A: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32];
    wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TerrainVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &A }
}

fn tree_layouts() -> [wgpu::VertexBufferLayout<'static>; 2] {
    const V: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32, 9 => Float32x2];
    const I: [wgpu::VertexAttribute; 7] = wgpu::vertex_attr_array![3 => Float32x4, 4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 10 => Float32x4];
    [
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TreeVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &V },
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<InstanceRaw>() as u64, step_mode: wgpu::VertexStepMode::Instance, attributes: &I },
    ]
}

impl Renderer {
    /// Builds the renderer on an existing device and queue (e.g. those of a window), drawing
    /// into views of `target_format` ([`Renderer::render_to_view`]). GPU culling is used
    /// ([`Culling::Auto`]) when the device's limits allow compute passes with 5 storage buffers
    /// and 64-wide workgroups; on a downlevel device without indirect draws set
    /// [`Culling::Cpu`].
    ///
    /// # Errors
    /// [`RenderError::Create`] when the pipelines cannot be created on the device (e.g. a
    /// `target_format` that is not renderable).
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, target_format: wgpu::TextureFormat) -> Result<Self> {
        let al = device.limits();
        let gpu_ok = al.max_storage_buffers_per_shader_stage >= 5 && al.max_compute_invocations_per_workgroup >= 64 && al.max_compute_workgroup_size_x >= 64;
        let info = device.adapter_info();
        Self::with_device(device, queue, info, gpu_ok, target_format)
    }

    /// The colour format of the views this renderer draws into.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.format
    }

    pub(super) fn with_device(device: wgpu::Device, queue: wgpu::Queue, adapter_info: wgpu::AdapterInfo, gpu_ok: bool, format: wgpu::TextureFormat) -> Result<Self> {
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("scene.wgsl"), source: wgpu::ShaderSource::Wgsl(include_str!("shaders/scene.wgsl").into()) });
        let uniform_entry = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        // silhouettes: the vertex stage reads the prototype's crown bottom (crown_remap)
        let sil_entry = wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: true }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let leaf_tex_entry = wgpu::BindGroupLayoutEntry {
            binding: 5,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture { sample_type: wgpu::TextureSampleType::Float { filterable: true }, view_dimension: wgpu::TextureViewDimension::D2Array, multisampled: false },
            count: None,
        };
        let leaf_samp_entry = wgpu::BindGroupLayoutEntry { binding: 6, visibility: wgpu::ShaderStages::FRAGMENT, ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering), count: None };
        let layout_main = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("main"),
            entries: &[
                uniform_entry,
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture { sample_type: wgpu::TextureSampleType::Depth, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry { binding: 2, visibility: wgpu::ShaderStages::FRAGMENT, ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison), count: None },
                sil_entry,
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: true }, has_dynamic_offset: false, min_binding_size: None },
                    count: None,
                },
                leaf_tex_entry,
                leaf_samp_entry,
            ],
        });
        let layout_shadow = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("shadow"), entries: &[uniform_entry, sil_entry, leaf_tex_entry, leaf_samp_entry] });
        let pl_main = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: Some("main"), bind_group_layouts: &[Some(&layout_main)], immediate_size: 0 });
        let pl_shadow = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: Some("shadow"), bind_group_layouts: &[Some(&layout_shadow)], immediate_size: 0 });

        let depth = |write: bool, cmp: wgpu::CompareFunction, bias: wgpu::DepthBiasState| wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(cmp),
            stencil: Default::default(),
            bias,
        };
        let ms = wgpu::MultisampleState { count: SAMPLES, mask: !0, alpha_to_coverage_enabled: false };
        let tl = [Some(terrain_layout())];
        let trl = tree_layouts();
        let trl = [Some(trl[0].clone()), Some(trl[1].clone())];
        let opaque = [Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let blended = [Some(wgpu::ColorTargetState { format, blend: Some(wgpu::BlendState::ALPHA_BLENDING), write_mask: wgpu::ColorWrites::ALL })];
        let make = |label: &str, layout: &wgpu::PipelineLayout, vs: &str, buffers: &[Option<wgpu::VertexBufferLayout>], fs: Option<(&str, &[Option<wgpu::ColorTargetState>])>, ds: wgpu::DepthStencilState, msaa: bool, cull: Option<wgpu::Face>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState { module: &shader, entry_point: Some(vs), compilation_options: Default::default(), buffers },
                primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleList, cull_mode: cull, ..Default::default() },
                depth_stencil: Some(ds),
                multisample: if msaa { ms } else { wgpu::MultisampleState::default() },
                fragment: fs.map(|(entry, targets)| wgpu::FragmentState { module: &shader, entry_point: Some(entry), compilation_options: Default::default(), targets }),
                multiview_mask: None,
                cache: None,
            })
        };
        let nob = wgpu::DepthBiasState::default();
        let sb = wgpu::DepthBiasState { constant: 2, slope_scale: 2.5, clamp: 0.0 };
        let sky = make("sky", &pl_main, "vs_sky", &[], Some(("fs_sky", &opaque)), depth(false, wgpu::CompareFunction::Always, nob), true, None);
        let terrain = make("terrain", &pl_main, "vs_terrain", &tl, Some(("fs_terrain", &opaque)), depth(true, wgpu::CompareFunction::Less, nob), true, None);
        let single = SinglePipelines {
            sky: make("sky 1x", &pl_main, "vs_sky", &[], Some(("fs_sky", &opaque)), depth(false, wgpu::CompareFunction::Always, nob), false, None),
            terrain: make("terrain 1x", &pl_main, "vs_terrain", &tl, Some(("fs_terrain", &opaque)), depth(true, wgpu::CompareFunction::Less, nob), false, None),
            water: make("water 1x", &pl_main, "vs_terrain", &tl, Some(("fs_water", &blended)), depth(false, wgpu::CompareFunction::Less, nob), false, None),
            tree: make("tree 1x", &pl_main, "vs_tree", &trl, Some(("fs_tree", &opaque)), depth(true, wgpu::CompareFunction::Less, nob), false, None),
        };
        let water = make("water", &pl_main, "vs_terrain", &tl, Some(("fs_water", &blended)), depth(false, wgpu::CompareFunction::Less, nob), true, None);
        let tree = make("tree", &pl_main, "vs_tree", &trl, Some(("fs_tree", &opaque)), depth(true, wgpu::CompareFunction::Less, nob), true, None);
        let terrain_shadow = make("terrain shadow", &pl_shadow, "vs_terrain", &tl, None, depth(true, wgpu::CompareFunction::Less, sb), false, None);
        let tree_shadow = make("tree shadow", &pl_shadow, "vs_tree_shadow", &trl, Some(("fs_tree_shadow", &[])), depth(true, wgpu::CompareFunction::Less, sb), false, None);

        let zero = <Globals as bytemuck::Zeroable>::zeroed();
        let globals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("globals"), contents: bytemuck::bytes_of(&zero), usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST });
        let shadow_globals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("shadow globals"), contents: bytemuck::bytes_of(&zero), usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST });
        let shadow_tex = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d { width: SHADOW_SIZE, height: SHADOW_SIZE, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let shadow_view = shadow_tex.create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let (leaf_view, leaf_sampler) = leaf_texture_array(&device, &queue);
        let cull = if gpu_ok { Some(Self::cull_pipeline(&device)) } else { None };
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Create { what: "pipelines", adapter: adapter_info.name.clone(), message: e.to_string() }.into());
        }
        Ok(Renderer {
            device,
            queue,
            adapter_info,
            sky,
            terrain,
            water,
            tree,
            terrain_shadow,
            tree_shadow,
            globals,
            shadow_globals,
            shadow_view,
            layout_main,
            layout_shadow,
            sampler,
            leaf_view,
            leaf_sampler,
            cull,
            instance_buf: None,
            scene: None,
            targets: None,
            readback: None,
            format,
            lod: LodParams::default(),
            culling: Culling::Auto,
            reuse_shadow_map: false,
            single,
            single_sample: false,
            shadow_ok: false,
            shadow_light: (Mat4::IDENTITY, 1.0, 1.0),
            far_field: None,
            max_near_trees: 0,
            fast_shading: false,
            coarse_terrain: false,
            shadow_far: None,
            last: FrameStats::default(),
        })
    }

    fn cull_pipeline(device: &wgpu::Device) -> GpuCull {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("cull.wgsl"), source: wgpu::ShaderSource::Wgsl(include_str!("shaders/cull.wgsl").into()) });
        let buf = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None }, count: None };
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let rw = wgpu::BufferBindingType::Storage { read_only: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cull"),
            entries: &[buf(0, wgpu::BufferBindingType::Uniform), buf(1, ro), buf(2, ro), buf(3, rw), buf(4, rw), buf(5, rw)],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: Some("cull"), bind_group_layouts: &[Some(&layout)], immediate_size: 0 });
        let make = |entry: &str| device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor { label: Some(entry), layout: Some(&pl), module: &shader, entry_point: Some(entry), compilation_options: Default::default(), cache: None });
        let (pipeline, hist, choose) = (make("cull"), make("hist"), make("choose"));
        let params = device.create_buffer(&wgpu::BufferDescriptor { label: Some("cull params"), size: std::mem::size_of::<CullParams>() as u64, usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        GpuCull { pipeline, hist, choose, layout, params, src: None, protos: None, dst: None, args: None, readback: None }
    }

    /// Whether this adapter can cull and select levels in a compute pass with indirect draws
    /// (wgpu downlevel flags `COMPUTE_SHADERS` and `INDIRECT_EXECUTION`, ≥ 5 storage buffers).
    pub fn gpu_culling_supported(&self) -> bool {
        self.cull.is_some()
    }

    /// Name and kind of the adapter in use (e.g. "llvmpipe (LLVM 19.1.7, 256 bits)", Cpu).
    pub fn adapter_description(&self) -> String {
        format!("{} ({:?}, {:?})", self.adapter_info.name, self.adapter_info.device_type, self.adapter_info.backend)
    }

    /// Whether the adapter is a software rasteriser (lavapipe, llvmpipe, WARP).
    pub fn is_software(&self) -> bool {
        self.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// Statistics of the last rendered frame.
    pub fn last_stats(&self) -> FrameStats {
        self.last
    }

    /// Uploads what changed of the scene's static data: the terrain part when its version
    /// ([`Scene::terrain_version`]) differs from the uploaded one, the prototypes when theirs
    /// does, nothing when neither does (no pass over the meshes).
    fn upload(&mut self, scene: &Scene) -> Result<(bool, bool)> {
        let (tfp, pfp) = (scene.terrain_version(), scene.prototypes_version());
        let old = self.scene.take();
        if old.as_ref().is_some_and(|g| g.terrain_version == tfp && g.protos_version == pfp) {
            self.scene = old;
            return Ok((false, false));
        }
        let (mut terrain, mut protos) = (None, None);
        if let Some(g) = old {
            if g.terrain_version == tfp {
                terrain = Some(GpuTerrain { vb: g.terrain_vb, ib: g.terrain_ib, count: g.terrain_count, coarse: g.terrain_coarse, water_vb: g.water_vb, canopy_grid: g.canopy_grid, canopy_buf: g.canopy_buf });
            }
            if g.protos_version == pfp {
                protos = Some((g.protos, g.sil_buf));
            }
        }
        let uploaded = (terrain.is_none(), protos.is_none());
        let terrain = match terrain {
            Some(t) => t,
            None => self.upload_terrain(scene)?,
        };
        let (protos, sil_buf) = match protos {
            Some(p) => p,
            None => self.upload_prototypes(scene)?,
        };
        let d = &self.device;
        let bind_main = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("main"),
            layout: &self.layout_main,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.globals.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&self.shadow_view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                wgpu::BindGroupEntry { binding: 3, resource: sil_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: terrain.canopy_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&self.leaf_view) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::Sampler(&self.leaf_sampler) },
            ],
        });
        let bind_shadow = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow"),
            layout: &self.layout_shadow,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.shadow_globals.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: sil_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&self.leaf_view) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::Sampler(&self.leaf_sampler) },
            ],
        });
        let GpuTerrain { vb: terrain_vb, ib: terrain_ib, count: terrain_count, coarse: terrain_coarse, water_vb, canopy_grid, canopy_buf } = terrain;
        self.scene = Some(GpuScene { terrain_version: tfp, protos_version: pfp, terrain_vb, terrain_ib, terrain_count, terrain_coarse, water_vb, protos, sil_buf, canopy_grid, canopy_buf, bind_main, bind_shadow });
        Ok(uploaded)
    }

    /// The terrain part: vertex and index buffers, the water plane, the canopy grid over the
    /// terrain's bounds and its buffer.
    fn upload_terrain(&self, scene: &Scene) -> Result<GpuTerrain> {
        scene.terrain.validate()?;
        let d = &self.device;
        let t = &scene.terrain;
        let (terrain_vb, terrain_ib) = if t.indices.is_empty() {
            (None, None)
        } else {
            let verts: Vec<TerrainVertex> = (0..t.positions.len()).map(|i| TerrainVertex { pos: t.positions[i], normal: t.normals[i], color: t.colors[i], fade: t.fade_at(i) }).collect();
            (
                Some(d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("terrain vb"), contents: bytemuck::cast_slice(&verts), usage: wgpu::BufferUsages::VERTEX })),
                Some(d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("terrain ib"), contents: bytemuck::cast_slice(&t.indices), usage: wgpu::BufferUsages::INDEX })),
            )
        };
        let water_vb = scene.sea_level.filter(|s| s.is_finite()).map(|z| {
            let (lo, hi) = t.bounds();
            let c = |x: f32, y: f32| TerrainVertex { pos: [x, y, z], normal: [0.0, 0.0, 1.0], color: [0.0; 3], fade: 0.0 };
            let v = [c(lo[0], lo[1]), c(hi[0], lo[1]), c(hi[0], hi[1]), c(lo[0], lo[1]), c(hi[0], hi[1]), c(lo[0], hi[1])];
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("water"), contents: bytemuck::cast_slice(&v), usage: wgpu::BufferUsages::VERTEX })
        });
        // over the surroundings too: trees stand beyond the window (job::scene::Landscape)
        let (lo, hi) = t.full_bounds();
        let canopy_grid = super::canopy::CanopyGrid::for_bounds(lo, hi);
        let canopy_buf = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("canopy"),
            size: (canopy_grid.len() as u64 * 16).max(256),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // a grid of more than COARSE_TERRAIN_TRIANGLES triangles: every stride-th vertex too
        let coarse = (t.triangle_count() > COARSE_TERRAIN_TRIANGLES)
            .then(|| t.coarse_indices((t.triangle_count() as f64 / COARSE_TERRAIN_TRIANGLES as f64).sqrt().ceil() as usize))
            .flatten()
            .filter(|ix| !ix.is_empty())
            .map(|ix| (d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("terrain ib (coarse)"), contents: bytemuck::cast_slice(&ix), usage: wgpu::BufferUsages::INDEX }), ix.len() as u32));
        Ok(GpuTerrain { vb: terrain_vb, ib: terrain_ib, count: t.indices.len() as u32, coarse, water_vb, canopy_grid, canopy_buf })
    }

    /// The prototypes part: one vertex and index buffer per drawn level (chain meshes, then the
    /// billboard) and the silhouettes' storage buffer.
    ///
    /// Errors: [`RenderError::Input`] ([`Error::Invalid`]) naming the prototype and level of an inconsistent mesh.
    fn upload_prototypes(&self, scene: &Scene) -> Result<(Vec<Vec<GpuLevel>>, wgpu::Buffer)> {
        let d = &self.device;
        let sils: Vec<Silhouette> = scene
            .prototypes
            .iter()
            .map(|p| {
                let mut s = Silhouette::from_chain(&p.lods);
                s.radius = p.normalised_crown_radius();
                if let Some(l) = p.look {
                    s.look = l;
                }
                s
            })
            .collect();
        let mut protos = Vec::new();
        for (pi, p) in scene.prototypes.iter().enumerate() {
            let mut levels = Vec::new();
            let n_mesh = drawn_levels(p.lods.levels.len()) - 1;
            for (li, l) in p.lods.levels.iter().take(n_mesh).enumerate() {
                let mut verts = Vec::new();
                let mut idx = Vec::new();
                let mut ranges = Vec::new();
                for (m, mat) in [(&l.bark, 0.0f32), (&l.leaves, 1.0)] {
                    if m.normals.len() != m.positions.len() || m.indices.len() % 3 != 0 || m.indices.iter().any(|&i| i as usize >= m.positions.len()) {
                        return Err(RenderError::Input(Error::Invalid {
                            context: format!("render prototype {pi} `{}` level {li}", p.name),
                            field: if mat == 0.0 { "bark".into() } else { "leaves".into() },
                            value: format!("{} positions, {} normals, {} indices", m.positions.len(), m.normals.len(), m.indices.len()),
                            expected: "one normal per position, indices in range, a multiple of 3".into(),
                        }));
                    }
                    let base = verts.len() as u32;
                    let start = idx.len() as u32;
                    let cards = mat > 0.5 && is_cards(m);
                    let r0 = sils[pi].radius.max(1e-3);
                    verts.extend(m.positions.iter().zip(&m.normals).enumerate().map(|(k, (p, n))| {
                        let uv = if cards {
                            m.uvs[k]
                        } else if mat < 0.5 {
                            [-1.0, twig_factor(p, r0)]
                        } else {
                            [-1.0, -1.0]
                        };
                        TreeVertex { pos: *p, normal: *n, mat, uv }
                    }));
                    idx.extend(m.indices.iter().map(|i| i + base));
                    ranges.push(start..idx.len() as u32);
                }
                if idx.is_empty() {
                    idx.extend_from_slice(&[0, 0, 0]);
                    verts.push(TreeVertex { pos: [0.0; 3], normal: [0.0, 0.0, 1.0], mat: 0.0, uv: [-1.0, -1.0] });
                }
                levels.push(GpuLevel {
                    vb: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("tree vb"), contents: bytemuck::cast_slice(&verts), usage: wgpu::BufferUsages::VERTEX }),
                    ib: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("tree ib"), contents: bytemuck::cast_slice(&idx), usage: wgpu::BufferUsages::INDEX }),
                    bark: ranges[0].clone(),
                    leaves: ranges[1].clone(),
                });
            }
            let (verts, idx) = billboard_vertices(&sils[pi]);
            levels.push(GpuLevel {
                vb: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("billboard vb"), contents: bytemuck::cast_slice(&verts), usage: wgpu::BufferUsages::VERTEX }),
                ib: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("billboard ib"), contents: bytemuck::cast_slice(&idx), usage: wgpu::BufferUsages::INDEX }),
                bark: 0..0,
                leaves: 0..idx.len() as u32,
            });
            protos.push(levels);
        }
        let mut sil_raw: Vec<SilRaw> = sils.iter().map(|s| SilRaw { w: s.width, info: [s.crown_bottom, s.crown_top, s.trunk_half_width, s.widest_z], look: [s.look.top_flatness, s.look.cover, s.look.clump, leaf_layer(s.look.leaf_shape)] }).collect();
        if sil_raw.is_empty() {
            sil_raw.push(<SilRaw as bytemuck::Zeroable>::zeroed());
        }
        let sil_buf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("silhouettes"), contents: bytemuck::cast_slice(&sil_raw), usage: wgpu::BufferUsages::STORAGE });
        Ok((protos, sil_buf))
    }

    fn ensure_targets(&mut self, w: u32, h: u32) {
        if self.targets.as_ref().map(|t| t.size) == Some((w, h)) {
            return;
        }
        let d = &self.device;
        let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
        let tex = |label: &str, format, usage| d.create_texture(&wgpu::TextureDescriptor { label: Some(label), size, mip_level_count: 1, sample_count: SAMPLES, dimension: wgpu::TextureDimension::D2, format, usage, view_formats: &[] });
        let msaa = tex("msaa", self.format, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        let depth = tex("depth", DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        let depth1 = d.create_texture(&wgpu::TextureDescriptor { label: Some("depth 1x"), size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format: DEPTH_FORMAT, usage: wgpu::TextureUsages::RENDER_ATTACHMENT, view_formats: &[] }).create_view(&Default::default());
        self.targets = Some(Targets { size: (w, h), msaa, depth, depth1 });
    }

    pub(super) fn check_size(&self, width: u32, height: u32) -> Result<()> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Input(Error::Invalid { context: "render".into(), field: "size".into(), value: format!("{width}x{height}"), expected: format!("1..={max} pixels per side") }));
        }
        Ok(())
    }

    /// Draws `scene` seen by `camera` into `view` (`width` × `height` pixels, the renderer's
    /// [`Renderer::target_format`], usage `RENDER_ATTACHMENT`): a window's surface texture or an
    /// offscreen texture. The GPU copies of the terrain and prototypes are kept between frames
    /// while their versions ([`Scene::terrain_version`], [`Scene::prototypes_version`]) stay the same (change tracking, no hashing); the instances are uploaded each frame. Returns the frame's
    /// statistics (also [`Renderer::last_stats`]).
    ///
    /// # Errors
    /// [`RenderError::Input`] ([`Error::Invalid`]) for a zero or too large size or inconsistent meshes;
    /// [`RenderError`] when the GPU fails.
    pub fn render_to_view(&mut self, scene: &Scene, camera: &Camera, view: &wgpu::TextureView, width: u32, height: u32) -> Result<FrameStats> {
        self.check_size(width, height)?;
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let r = self.render_inner(scene, camera, view, width, height);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Validation(e.to_string()).into());
        }
        r
    }

    fn render_inner(&mut self, scene: &Scene, camera: &Camera, view: &wgpu::TextureView, width: u32, height: u32) -> Result<FrameStats> {
        let (uploaded_terrain, uploaded_prototypes) = self.upload(scene)?;
        self.ensure_targets(width, height);
        // a far field baked for this terrain: its near trees instead of the scene's instances
        let far = self.far_field.clone().filter(|f| self.scene.as_ref().is_some_and(|g| g.canopy_grid == f.grid && f.sums().len() == f.grid.len()));
        let near = far.as_ref().map(|f| f.near(camera, width, height, &self.lod, self.max_near_trees));
        let instances: &[TreeInstance] = near.as_ref().map_or(&scene.instances, |n| &n.instances);
        // trees left in the baked layer go wholly to the canopy layer in this frame too
        let lod = match &near {
            Some(n) if self.lod.canopy_px > 0.0 => LodParams { canopy_px: self.lod.canopy_px.max(n.floor_px * (1.0 + self.lod.band.max(0.0))), ..self.lod },
            _ => self.lod,
        };
        let gpu_frame = match self.culling {
            Culling::Cpu => None,
            // the near trees of a far field are few: culled on the CPU
            Culling::Auto if far.is_some() => None,
            Culling::Auto => {
                if self.cull.is_some() {
                    self.prepare_gpu_cull(scene, camera, width, height)?
                } else {
                    None
                }
            }
            Culling::Gpu => {
                if self.cull.is_none() {
                    return Err(RenderError::GpuCullingUnavailable(format!("{} lacks compute shaders or indirect draws", self.adapter_info.name)).into());
                }
                if far.is_some() {
                    return Err(RenderError::GpuCullingUnavailable("a baked far field is culled on the CPU".into()));
                }
                match self.prepare_gpu_cull(scene, camera, width, height)? {
                    Some(f) => Some(f),
                    None => return Err(RenderError::GpuCullingUnavailable(format!("{} instances exceed the adapter's storage buffer limits", scene.instances.len())).into()),
                }
            }
        };
        let draws = match gpu_frame {
            Some(f) => FrameDraws::Gpu(f),
            None => {
                let b = build_batches_of(instances, &scene.prototypes, camera, width, height, &lod);
                self.write_instances(&b);
                if let Some(f) = &far {
                    self.write_far_canopy(f, instances, &scene.prototypes, &b);
                } else if !b.canopy.is_empty() {
                    self.write_canopy(&b);
                }
                FrameDraws::Cpu(b)
            }
        };
        let canopy_used = match &draws {
            FrameDraws::Cpu(b) => far.is_some() || !b.canopy.is_empty(),
            FrameDraws::Gpu(_) => true,
        };
        if uploaded_terrain || uploaded_prototypes || !same_far(&far, &self.shadow_far) {
            self.shadow_ok = false;
        }
        let redraw_shadow = !(self.reuse_shadow_map && self.shadow_ok);
        let (extent, light_height) = match &far {
            Some(f) => (f.tree_bounds, f.light_height),
            None => (tree_extent(&scene.instances), canopy_light_height(&scene.instances)),
        };
        if redraw_shadow {
            self.shadow_light = Self::light_matrix(scene, extent);
            self.shadow_far = far.clone();
        }
        self.write_globals(scene, camera, width, height, canopy_used, self.shadow_light, light_height);
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        if let FrameDraws::Gpu(f) = &draws {
            if let Some(gs) = &self.scene {
                enc.clear_buffer(&gs.canopy_buf, 0, None);
            }
            self.encode_cull(&mut enc, f);
        }
        if redraw_shadow {
            self.encode_shadow(&mut enc, &draws);
            self.shadow_ok = true;
        }
        let tree_draws = self.encode_main(&mut enc, &draws, view);
        let Some(gpu) = &self.scene else { return Err(RenderError::Internal("uploaded scene").into()) };
        let cull_rb = match (&draws, &self.cull) {
            (FrameDraws::Gpu(f), Some(GpuCull { args: Some((args, _)), readback: Some((rb, _)), .. })) => {
                enc.copy_buffer_to_buffer(args, 0, rb, 0, f.args_bytes);
                Some(rb)
            }
            _ => None,
        };
        let sub = self.queue.submit(Some(enc.finish()));
        let (tx, rx) = std::sync::mpsc::channel();
        let args_bytes = if let FrameDraws::Gpu(f) = &draws { f.args_bytes } else { 0 };
        if let Some(rb) = cull_rb {
            rb.slice(..args_bytes).map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
        } else {
            drop(tx);
        }
        if cull_rb.is_some() {
            // the GPU path's statistics are read back from the culling pass
            self.device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).map_err(|e| RenderError::Readback { stage: "poll", message: e.to_string() })?;
            rx.recv().map_err(|e| RenderError::Readback { stage: "channel", message: e.to_string() })?.map_err(|e| RenderError::Readback { stage: "map", message: e.to_string() })?;
        }
        let mut per_level = [0usize; LOD_LEVELS];
        let mut lod_scale = 1.0f32;
        let (mut canopy_px, mut canopy_trees) = (0.0f32, 0usize);
        let (tree_tris, culled, invalid, drawn) = match &draws {
            FrameDraws::Cpu(b) => {
                for (i, n) in b.per_level.iter().enumerate() {
                    per_level[i.min(LOD_LEVELS - 1)] += n;
                }
                lod_scale = b.lod_scale;
                canopy_px = b.canopy_px;
                canopy_trees = b.canopy_only + near.as_ref().map_or(0, |n| n.far_trees);
                (b.triangles, b.culled, b.invalid, b.per_level.iter().sum())
            }
            FrameDraws::Gpu(f) => {
                let mut tris = 0u64;
                if let Some(rb) = cull_rb {
                    {
                        let view = rb.slice(..args_bytes).get_mapped_range().map_err(|e| RenderError::Readback { stage: "culling range", message: e.to_string() })?;
                        let words: &[u32] = bytemuck::cast_slice(&view);
                        for (k, sl) in f.slots.iter().enumerate() {
                            let n = words[k * 10 + 1] as u64;
                            tris += n * level_triangles(&scene.prototypes[sl.prototype], sl.level);
                        }
                        let off = f.slots.len() * 10;
                        for l in 0..LOD_LEVELS {
                            per_level[l] = words[off + l] as usize;
                        }
                        let tail = words.len().saturating_sub(3);
                        if let [sc, cp, cn] = words[tail..] {
                            lod_scale = f32::from_bits(sc);
                            canopy_px = f32::from_bits(cp);
                            canopy_trees = cn as usize;
                        }
                    }
                    rb.unmap();
                }
                let drawn: usize = per_level.iter().sum();
                (tris, f.valid.saturating_sub(drawn + canopy_trees), f.invalid, drawn)
            }
        };
        self.last = FrameStats {
            triangles: tree_tris + u64::from(match &gpu.terrain_coarse { Some((_, n)) if self.coarse_terrain => *n, _ => gpu.terrain_count }) / 3 + if gpu.water_vb.is_some() { 2 } else { 0 },
            tree_triangles: tree_tris,
            tree_draws,
            instances_drawn: drawn,
            culled,
            invalid,
            per_level,
            gpu_culling: matches!(draws, FrameDraws::Gpu(_)),
            lod_scale,
            canopy_px,
            canopy_trees,
            uploaded_terrain,
            uploaded_prototypes,
        };
        Ok(self.last)
    }

    /// Uploads the instance records and culling parameters for the compute pass. `None` when
    /// the compacted buffers would exceed the adapter's limits (the caller falls back to the
    /// CPU path or fails).
    fn prepare_gpu_cull(&mut self, scene: &Scene, camera: &Camera, width: u32, height: u32) -> Result<Option<GpuFrame>> {
        use rayon::prelude::*;
        let crown_r0: Vec<f32> = scene.prototypes.iter().map(|p| p.normalised_crown_radius()).collect();
        let recs: Vec<Option<InstanceRaw>> = scene.instances.par_iter().map(|t| instance_record(t, &scene.prototypes, &crown_r0)).collect();
        let invalid = recs.iter().filter(|r| r.is_none()).count();
        let src: Vec<InstanceRaw> = recs.into_iter().flatten().collect();
        let n_protos = scene.prototypes.len();
        let mut per_proto = vec![0u32; n_protos];
        for r in &src {
            per_proto[r.p3[0] as usize] += 1;
        }
        // slots: (prototype, level), capacity = instances of the prototype
        let mut slots = Vec::new();
        let mut proto_words: Vec<[u32; 4]> = Vec::with_capacity(n_protos);
        let mut base = 0u64;
        for (p, proto) in scene.prototypes.iter().enumerate() {
            let n = drawn_levels(proto.lods.levels.len());
            proto_words.push([n as u32, slots.len() as u32, 0, 0]);
            for l in 0..n {
                slots.push(GpuSlot { prototype: p, level: l, base: base as u32, cap: per_proto[p] });
                base += per_proto[p] as u64;
            }
        }
        let limits = self.device.limits();
        let rec = std::mem::size_of::<InstanceRaw>() as u64;
        let dst_bytes = (base * rec).max(256);
        let src_bytes = (src.len() as u64 * rec).max(256);
        let max_bind = limits.max_storage_buffer_binding_size;
        if dst_bytes > max_bind || dst_bytes > limits.max_buffer_size || src_bytes > max_bind || base > u32::MAX as u64 / 2 {
            return Ok(None);
        }
        // slot bases packed after the prototype records, 4 per record
        for c in slots.chunks(4) {
            let mut w = [0u32; 4];
            for (k, s) in c.iter().enumerate() {
                w[k] = s.base;
            }
            proto_words.push(w);
        }
        // triangles per drawn level, one record per prototype
        let cost_first = proto_words.len();
        for p in &scene.prototypes {
            proto_words.push(super::instanced::level_costs(p));
        }
        if proto_words.is_empty() {
            proto_words.push([0; 4]);
        }
        // indirect args: per slot bark and leaves records, then LOD_LEVELS per-level counters
        let mut args: Vec<u32> = Vec::with_capacity(slots.len() * 10 + LOD_LEVELS);
        let Some(gs) = &self.scene else { return Err(RenderError::Internal("uploaded scene").into()) };
        for s in &slots {
            let lv = gs.protos.get(s.prototype).and_then(|p| p.get(s.level));
            for r in lv.map(|l| [l.bark.clone(), l.leaves.clone()]).unwrap_or([0..0, 0..0]) {
                args.extend_from_slice(&[r.len() as u32, 0, r.start, 0, 0]);
            }
        }
        // per-level counters, size histogram, budget factor (1.0 unless `choose` runs)
        args.extend(std::iter::repeat_n(0u32, LOD_LEVELS + n_protos * super::lod::SIZE_BINS));
        // the `choose` results (or their defaults when it does not run): switch-size factor,
        // far-field switch; then the count of canopy-only trees
        args.push(1.0f32.to_bits());
        args.push(if self.lod.canopy_px > 0.0 { self.lod.canopy_px } else { 0.0 }.to_bits());
        args.push(0);
        let args_bytes = (args.len() * 4) as u64;
        let aspect = width as f32 / height as f32;
        let vp = camera.view_proj(aspect);
        let fr = Frustum::from_view_proj(vp);
        let ortho = matches!(camera.projection, super::camera::Projection::Orthographic { .. });
        let ppm = match camera.projection {
            super::camera::Projection::Perspective { fov_y_deg } => height as f32 / (2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            super::camera::Projection::Orthographic { half_height } => height as f32 / (2.0 * half_height.max(1e-3)),
        };
        let groups = (src.len() as u32).div_ceil(64);
        let gx = groups.min(limits.max_compute_workgroups_per_dimension.max(1));
        let params = CullParams {
            planes: fr.planes().map(|p| p.to_array()),
            eye: [camera.eye[0], camera.eye[1], camera.eye[2], if ortho { 1.0 } else { 0.0 }],
            lod: [self.lod.switch_px[0], self.lod.switch_px[1], self.lod.switch_px[2], self.lod.band],
            misc: [self.lod.min_px, ppm, self.lod.max_triangles as f32, cost_first as f32],
            counts: [src.len() as u32, gx, n_protos as u32, (slots.len() * 10) as u32],
            canopy: [gs.canopy_grid.origin[0], gs.canopy_grid.origin[1], gs.canopy_grid.texel, self.lod.canopy_px.max(0.0)],
            canopy_n: [gs.canopy_grid.nx, gs.canopy_grid.ny, self.lod.max_geometry_triangles, 0],
        };
        let Some(cull) = self.cull.as_mut() else { return Ok(None) };
        let d = &self.device;
        let ensure = |slot: &mut Option<(wgpu::Buffer, u64)>, need: u64, usage: wgpu::BufferUsages, label: &str| {
            if slot.as_ref().map(|(_, c)| *c < need).unwrap_or(true) {
                let cap = need.next_power_of_two();
                *slot = Some((d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: cap, usage, mapped_at_creation: false }), cap));
            }
        };
        use wgpu::BufferUsages as U;
        ensure(&mut cull.src, src_bytes, U::STORAGE | U::COPY_DST, "cull src");
        ensure(&mut cull.protos, (proto_words.len() * 16) as u64, U::STORAGE | U::COPY_DST, "cull protos");
        ensure(&mut cull.dst, dst_bytes, U::STORAGE | U::VERTEX, "cull dst");
        ensure(&mut cull.args, args_bytes.max(64), U::STORAGE | U::INDIRECT | U::COPY_SRC | U::COPY_DST, "cull args");
        ensure(&mut cull.readback, args_bytes.max(64), U::MAP_READ | U::COPY_DST, "cull readback");
        if let (Some((sb, _)), Some((pb, _)), Some((ab, _))) = (&cull.src, &cull.protos, &cull.args) {
            if !src.is_empty() {
                self.queue.write_buffer(sb, 0, bytemuck::cast_slice(&src));
            }
            self.queue.write_buffer(pb, 0, bytemuck::cast_slice(&proto_words));
            self.queue.write_buffer(ab, 0, bytemuck::cast_slice(&args));
        }
        self.queue.write_buffer(&cull.params, 0, bytemuck::bytes_of(&params));
        let valid = src.len();
        let budget = self.lod.max_triangles > 0 || (self.lod.canopy_px > 0.0 && self.lod.max_geometry_triangles > 0);
        Ok(Some(GpuFrame { slots, budget, invalid, valid, args_bytes }))
    }

    fn encode_cull(&self, enc: &mut wgpu::CommandEncoder, f: &GpuFrame) {
        let (Some(cull), Some(gs)) = (&self.cull, &self.scene) else { return };
        let (Some((sb, _)), Some((pb, _)), Some((db, _)), Some((ab, _))) = (&cull.src, &cull.protos, &cull.dst, &cull.args) else { return };
        if f.valid == 0 {
            return;
        }
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cull"),
            layout: &cull.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: cull.params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: sb.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: pb.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: db.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: ab.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: gs.canopy_buf.as_entire_binding() },
            ],
        });
        let groups = (f.valid as u32).div_ceil(64);
        let gx = groups.min(self.device.limits().max_compute_workgroups_per_dimension.max(1));
        let gy = groups.div_ceil(gx);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("cull"), timestamp_writes: None });
        pass.set_bind_group(0, &bind, &[]);
        if f.budget {
            pass.set_pipeline(&cull.hist);
            pass.dispatch_workgroups(gx, gy, 1);
            pass.set_pipeline(&cull.choose);
            pass.dispatch_workgroups(1, 1, 1);
        }
        pass.set_pipeline(&cull.pipeline);
        pass.dispatch_workgroups(gx, gy, 1);
    }

    /// The sun's orthographic view-projection over the scene's bounding sphere (radius r, depth
    /// range r..3r from an eye 2r towards the sun), the world size of a shadow texel (m) and the
    /// depth range (m). `trees`: the bounds of the trees' stems and the tallest tree
    /// ([`tree_extent`]).
    fn light_matrix(scene: &Scene, trees: Option<([f32; 3], [f32; 3], f32)>) -> (Mat4, f32, f32) {
        let (lo, hi) = scene.terrain.bounds();
        let (mut lo, mut hi) = (Vec3::from(lo), Vec3::from(hi));
        let mut tallest = 0.0f32;
        if let Some((a, b, t)) = trees {
            lo = lo.min(Vec3::from(a));
            hi = hi.max(Vec3::from(b));
            tallest = t;
        }
        hi.z += tallest;
        let c = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(1.0);
        let sun = Vec3::from(scene.sun.direction).normalize_or(Vec3::Z);
        let up = if sun.z.abs() > 0.99 { Vec3::Y } else { Vec3::Z };
        let view = glam::camera::rh::view::look_at_mat4(c + sun * 2.0 * r, c, up);
        let proj = glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, 0.9 * r, 3.1 * r);
        (proj * view, 2.0 * r / SHADOW_SIZE as f32, 2.2 * r)
    }

    /// `canopy_used`: whether the terrain shader reads the canopy layer (false when the CPU
    /// path splatted nothing this frame); `light`: the sun's matrix of the shadow map
    /// ([`Renderer::light_matrix`]); `light_height`: [`canopy_light_height`] of the trees.
    #[allow(clippy::too_many_arguments)]
    fn write_globals(&self, scene: &Scene, camera: &Camera, w: u32, h: u32, canopy_used: bool, light: (Mat4, f32, f32), light_height: f32) {
        let aspect = w as f32 / h as f32;
        let vp = camera.view_proj(aspect);
        let (lvp, texel_m, depth_m) = light;
        let (lo, hi) = scene.terrain.bounds();
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
        let ortho = matches!(camera.projection, super::camera::Projection::Orthographic { .. });
        let v3 = |a: [f32; 3], w: f32| [a[0], a[1], a[2], w];
        let sun = Vec3::from(scene.sun.direction).normalize_or(Vec3::Z).to_array();
        let wd = glam::Vec2::from(scene.wind.direction).normalize_or(glam::Vec2::X);
        let mut g = Globals {
            view_proj: vp.to_cols_array_2d(),
            light_view_proj: lvp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            eye: v3(camera.eye, if ortho { 1.0 } else { 0.0 }),
            sun_dir: v3(sun, 0.0),
            sun_color: v3(scene.sun.color, 0.0),
            sky_zenith: v3(scene.sky.zenith, 0.0),
            sky_horizon: v3(scene.sky.horizon, 0.0),
            wind: [wd.x, wd.y, scene.wind.directed, scene.wind.undirected],
            params: [scene.wind.time_s, scene.sea_level.unwrap_or(f32::NEG_INFINITY).max(-1e30), 1.0 / SHADOW_SIZE as f32, 0.1 / size],
            canopy0: [0.0; 4],
            canopy1: [0.0; 4],
            shadow: [1.0 / SHADOW_SIZE as f32, 0.5 * texel_m / depth_m, texel_m, if self.fast_shading { 1.0 } else { 0.0 }],
            facing: if ortho { v3((Vec3::from(camera.eye) - Vec3::from(camera.target)).normalize_or(Vec3::Z).to_array(), 1.0) } else { [0.0; 4] },
        };
        if let Some(gs) = &self.scene {
            let cg = gs.canopy_grid;
            g.canopy0 = [cg.origin[0], cg.origin[1], cg.texel, if self.lod.canopy_px > 0.0 && canopy_used { 1.0 } else { 0.0 }];
            g.canopy1 = [cg.nx as f32, cg.ny as f32, 2.5, light_height];
        }
        self.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        g.view_proj = g.light_view_proj;
        g.facing = v3(sun, 1.0);
        self.queue.write_buffer(&self.shadow_globals, 0, bytemuck::bytes_of(&g));
    }

    fn write_instances(&mut self, b: &Batches) {
        let bytes: &[u8] = bytemuck::cast_slice(&b.instances);
        let need = (bytes.len() as u64).max(256);
        if self.instance_buf.as_ref().map(|(_, cap)| *cap < need).unwrap_or(true) {
            let cap = need.next_power_of_two();
            let buf = self.device.create_buffer(&wgpu::BufferDescriptor { label: Some("instances"), size: cap, usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
            self.instance_buf = Some((buf, cap));
        }
        if let Some((buf, _)) = &self.instance_buf {
            if !bytes.is_empty() {
                self.queue.write_buffer(buf, 0, bytes);
            }
        }
    }

    /// Splats the CPU path's canopy crowns into the grid and uploads the sums.
    fn write_canopy(&self, b: &Batches) {
        let Some(gs) = &self.scene else { return };
        let g = gs.canopy_grid;
        let mut sums = vec![[0u32; 4]; g.len()];
        for c in &b.canopy {
            g.splat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
        }
        self.queue.write_buffer(&gs.canopy_buf, 0, bytemuck::cast_slice(&sums));
    }

    /// The canopy layer of a frame drawn from far field `far`: its baked sums, less the full
    /// splats of the `near` trees the frame culled itself, plus the splats of those of them
    /// the frame put in the canopy layer (`b.canopy`); uploaded.
    fn write_far_canopy(&self, far: &FarField, near: &[TreeInstance], prototypes: &[super::scene::Prototype], b: &Batches) {
        let Some(gs) = &self.scene else { return };
        let g = gs.canopy_grid;
        let mut sums = far.sums().to_vec();
        let crown_r0: Vec<f32> = prototypes.iter().map(|p| p.normalised_crown_radius()).collect();
        for t in near {
            if let Some(c) = super::farfield::full_splat(t, prototypes, &crown_r0) {
                g.unsplat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
            }
        }
        for c in &b.canopy {
            g.splat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
        }
        self.queue.write_buffer(&gs.canopy_buf, 0, bytemuck::cast_slice(&sums));
    }

    /// Records the tree draws; returns the number of draw calls.
    fn draw_trees<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, draws: &FrameDraws) -> u32 {
        let Some(gpu) = &self.scene else { return 0 };
        let mut n = 0u32;
        match draws {
            FrameDraws::Cpu(b) => {
                let Some((ibuf, _)) = &self.instance_buf else { return 0 };
                pass.set_vertex_buffer(1, ibuf.slice(..));
                for d in &b.draws {
                    let Some(level) = gpu.protos.get(d.prototype).and_then(|p| p.get(d.level)) else { continue };
                    pass.set_vertex_buffer(0, level.vb.slice(..));
                    pass.set_index_buffer(level.ib.slice(..), wgpu::IndexFormat::Uint32);
                    let inst = d.first..d.first + d.count;
                    for r in [&level.bark, &level.leaves] {
                        if !r.is_empty() {
                            pass.draw_indexed(r.clone(), 0, inst.clone());
                            n += 1;
                        }
                    }
                }
            }
            FrameDraws::Gpu(f) => {
                let Some(GpuCull { dst: Some((dst, _)), args: Some((args, _)), .. }) = &self.cull else { return 0 };
                let rec = std::mem::size_of::<InstanceRaw>() as u64;
                for (k, s) in f.slots.iter().enumerate() {
                    if s.cap == 0 {
                        continue;
                    }
                    let Some(level) = gpu.protos.get(s.prototype).and_then(|p| p.get(s.level)) else { continue };
                    pass.set_vertex_buffer(0, level.vb.slice(..));
                    pass.set_index_buffer(level.ib.slice(..), wgpu::IndexFormat::Uint32);
                    // indirect first_instance must be 0 without INDIRECT_FIRST_INSTANCE: bind the
                    // slot's range of the compacted buffer instead
                    pass.set_vertex_buffer(1, dst.slice(s.base as u64 * rec..(s.base as u64 + s.cap as u64) * rec));
                    for (m, r) in [&level.bark, &level.leaves].into_iter().enumerate() {
                        if !r.is_empty() {
                            pass.draw_indexed_indirect(args, (k * 40 + m * 20) as u64);
                            n += 1;
                        }
                    }
                }
            }
        }
        n
    }

    fn encode_shadow(&self, enc: &mut wgpu::CommandEncoder, draws: &FrameDraws) {
        let Some(gpu) = &self.scene else { return };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: &self.shadow_view, depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }), stencil_ops: None }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &gpu.bind_shadow, &[]);
        if let (Some(vb), Some(ib)) = (&gpu.terrain_vb, &gpu.terrain_ib) {
            pass.set_pipeline(&self.terrain_shadow);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..gpu.terrain_count, 0, 0..1);
        }
        pass.set_pipeline(&self.tree_shadow);
        self.draw_trees(&mut pass, draws);
    }

    fn encode_main(&self, enc: &mut wgpu::CommandEncoder, draws: &FrameDraws, view: &wgpu::TextureView) -> u32 {
        let (Some(t), Some(gpu)) = (&self.targets, &self.scene) else { return 0 };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("main"),
            color_attachments: &[Some(if self.single_sample {
                wgpu::RenderPassColorAttachment { view, depth_slice: None, resolve_target: None, ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store } }
            } else {
                wgpu::RenderPassColorAttachment { view: &t.msaa, depth_slice: None, resolve_target: Some(view), ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Discard } }
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: if self.single_sample { &t.depth1 } else { &t.depth }, depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }), stencil_ops: None }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &gpu.bind_main, &[]);
        let (sky, terrain, water, tree) = if self.single_sample { (&self.single.sky, &self.single.terrain, &self.single.water, &self.single.tree) } else { (&self.sky, &self.terrain, &self.water, &self.tree) };
        pass.set_pipeline(sky);
        pass.draw(0..3, 0..1);
        if let (Some(vb), Some(ib)) = (&gpu.terrain_vb, &gpu.terrain_ib) {
            pass.set_pipeline(terrain);
            pass.set_vertex_buffer(0, vb.slice(..));
            match &gpu.terrain_coarse {
                Some((cib, n)) if self.coarse_terrain => {
                    pass.set_index_buffer(cib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..*n, 0, 0..1);
                }
                _ => {
                    pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..gpu.terrain_count, 0, 0..1);
                }
            }
        }
        pass.set_pipeline(tree);
        let r = self.draw_trees(&mut pass, draws);
        if let Some(vb) = &gpu.water_vb {
            pass.set_pipeline(water);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.draw(0..6, 0..1);
        }
        r
    }
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer").field("adapter", &self.adapter_description()).finish()
    }
}

/// Whether two far fields are the same one (both `None` counts).
fn same_far(a: &Option<std::sync::Arc<FarField>>, b: &Option<std::sync::Arc<FarField>>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => std::sync::Arc::ptr_eq(a, b),
        (None, None) => true,
        _ => false,
    }
}

