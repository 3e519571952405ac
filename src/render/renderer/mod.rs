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
use super::instanced::{build_batches_of, instance_record, level_triangles, Batches, DrawBatch, InstanceRaw};
use super::lod::{card_spread, drawn_levels, plan_spread, spread_cards, Frustum, LodParams, Silhouette, CROWN_HULL_LEVEL, REDUCED_LEVEL, SILHOUETTE_BINS};
use super::scene::{Scene, TreeInstance};
use crate::mesh::LOD_LEVELS;
use crate::structure::texture::{self, LeafShape};

// `shaders/cull.wgsl` keeps one drawn level per word of a 4-word record (the level costs of a
// prototype, `cost()`), so the number of levels is tied to that record width.
const _: () = assert!(LOD_LEVELS == 4, "cull.wgsl packs the level costs of a prototype into one vec4<u32>-sized record");
use super::{RenderError, Result};
use crate::Error;

mod culling;
mod passes;
mod pipelines;
mod records;
mod upload;

pub use records::*;
use upload::*;

/// Colour format of the headless texture (sRGB RGBA, read back as an image).
pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SHADOW_SIZE: u32 = 2048;
const SAMPLES: u32 = 4;
/// Triangles of the coarse terrain mesh of [`Renderer::coarse_terrain`] (at most about).
pub const COARSE_TERRAIN_TRIANGLES: usize = 100_000;

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
    /// Reference height (m) of the small trees' level bias the frame used
    /// ([`LodParams::small_tree_m`]; on the CPU path lowered towards
    /// [`LodParams::small_tree_floor_m`] where the triangle budget binds).
    pub small_tree_m: f32,
    /// Trees the frame drew at a finer level than the bias of
    /// [`LodParams::small_tree_floor_m`] gives at the same switch factor (CPU path; 0 on the GPU
    /// path): those the higher reference raised (none is drawn coarser).
    pub levels_raised: usize,
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
    /// Trees drawn as another instance (default none): a culled tree whose id is a key is drawn
    /// as the instance it maps to (e.g. the viewer's adapted near field: the tree's own
    /// prototype, height and crown, `view::near`), on the CPU culling path (a frame with
    /// replacements is culled on the CPU). The far field's canopy layer still takes out the
    /// tree as it was baked.
    pub replaced: std::collections::HashMap<u64, TreeInstance>,
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
    /// Split the tree draws of the shadow and main passes over several render passes of at most
    /// about this many triangles each (an upper bound: every instance a slot may hold at its
    /// level); 0 (default): one pass each. The CPU path's draws are cut into instance ranges to
    /// fit; a GPU-path slot over it gets a pass of its own. On a software adapter each pass is
    /// submitted and waited for before the next is recorded ([`Renderer::wait_between_passes`]):
    /// lavapipe's binning thread otherwise runs ahead of its rasterisers, up to 64 binned scenes
    /// of 36 MB (2.3 GB) for the default run's year 150 at 1920 × 1080 (issue 34). The picture
    /// is the same (the draws keep their order; the multisampled colour and the depth are
    /// stored between the passes and resolved after the last); each extra pass stores and loads
    /// the targets once more.
    pub pass_triangles: u64,
    /// The light terms drawn (default [`LightTerms::All`]): a diagnostic of the stills'
    /// lighting (issue 32, round 35), e.g. the share of a still's crowns in the sun's shadow.
    pub light_terms: LightTerms,
    /// Billboard crowns take the sun's visibility on their camera-facing quad, as before round
    /// 35 (default false: at the crown surface the pixel shows; `shaders/scene.wgsl`,
    /// `fs_tree`). Kept to measure the change (`tests/render_species.rs`).
    pub crown_sun_on_quad: bool,
    /// A tree inside a level cross-fade band draws one of its two levels whole, chosen by a
    /// threshold of its own (its dither salt), instead of both levels split by complementary
    /// per-pixel Bayer masks (default false: the viewer, whose moving camera would see trees
    /// pop). For stills (`job::pictures::Stage`), where the two masks read as a screen-door dot
    /// pattern on crowns of the mid-ground (issue 32, round 40, trial 39); the same share of
    /// the band's trees draws each level.
    pub fade_per_tree: bool,
    /// The far field the shadow map was drawn with (a new one redraws it).
    shadow_far: Option<std::sync::Arc<FarField>>,
    last: FrameStats,
}

/// Which light terms a frame draws ([`Renderer::light_terms`]): all (the pictures), or one term
/// alone to see what lights what.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LightTerms {
    /// Sun (shadow-mapped), sky light and the leaves' transmitted sunlight: the pictures.
    #[default]
    All,
    /// As [`LightTerms::All`] with every point seeing the sun and the whole sky (no shadow map
    /// lookups take effect).
    NoShadows,
    /// The sun alone (shadow-mapped, with the leaves' transmitted sunlight), no sky light.
    SunOnly,
    /// The sky light alone, no sun.
    SkyOnly,
}

impl LightTerms {
    /// The code `shaders/scene.wgsl` reads from `Globals::sun_dir.w`: 0 all, 1 no shadows,
    /// 2 sun only, 3 sky only.
    pub fn code(self) -> f32 {
        match self {
            LightTerms::All => 0.0,
            LightTerms::NoShadows => 1.0,
            LightTerms::SunOnly => 2.0,
            LightTerms::SkyOnly => 3.0,
        }
    }
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

    /// Uploads what changed of `scene`'s terrain and prototypes now rather than at the next
    /// frame (so that the caller may free its meshes, [`crate::mesh::LodChain::free_meshes`],
    /// before drawing).
    ///
    /// Errors: as [`Renderer::render`]'s upload (an inconsistent mesh, a lost device).
    pub fn upload_scene(&mut self, scene: &Scene) -> Result<()> {
        self.upload(scene).map(|_| ())
    }

    fn render_inner(&mut self, scene: &Scene, camera: &Camera, view: &wgpu::TextureView, width: u32, height: u32) -> Result<FrameStats> {
        let (uploaded_terrain, uploaded_prototypes) = self.upload(scene)?;
        self.ensure_targets(width, height);
        // a far field baked for this terrain: its near trees instead of the scene's instances
        let far = self.far_field.clone().filter(|f| self.scene.as_ref().is_some_and(|g| g.canopy_grid == f.grid && f.sums().len() == f.grid.len()));
        let near = far.as_ref().map(|f| f.near(camera, width, height, &self.lod, self.max_near_trees));
        let instances: &[TreeInstance] = near.as_ref().map_or(&scene.instances, |n| &n.instances);
        // the trees drawn as another instance (Renderer::replaced); `instances` stay as baked
        let swapped: Option<Vec<TreeInstance>> = (!self.replaced.is_empty()).then(|| instances.iter().map(|t| self.replaced.get(&t.id).copied().unwrap_or(*t)).collect());
        let drawn_inst: &[TreeInstance] = swapped.as_deref().unwrap_or(instances);
        // trees left in the baked layer go wholly to the canopy layer in this frame too
        let lod = match &near {
            Some(n) if self.lod.canopy_px > 0.0 => LodParams { canopy_px: self.lod.canopy_px.max(n.floor_px * (1.0 + self.lod.band.max(0.0))), ..self.lod },
            _ => self.lod,
        };
        let gpu_frame = match self.culling {
            Culling::Cpu => None,
            // the near trees of a far field are few: culled on the CPU
            Culling::Auto if far.is_some() || swapped.is_some() => None,
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
                let mut b = build_batches_of(drawn_inst, &scene.prototypes, camera, width, height, &lod);
                b.draws = self.split_draws(&b.draws);
                self.write_instances(&b);
                // on their way to the device (the queue's staging copy): not held for the frame
                b.instances = Vec::new();
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
            self.encode_shadow(&mut enc, &draws)?;
            self.shadow_ok = true;
        }
        let tree_draws = self.encode_main(&mut enc, &draws, view)?;
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
        let (mut small_tree_m, mut levels_raised) = (self.lod.small_tree_m, 0usize);
        let (tree_tris, culled, invalid, drawn) = match &draws {
            FrameDraws::Cpu(b) => {
                for (i, n) in b.per_level.iter().enumerate() {
                    per_level[i.min(LOD_LEVELS - 1)] += n;
                }
                lod_scale = b.lod_scale;
                canopy_px = b.canopy_px;
                small_tree_m = b.small_tree_m;
                levels_raised = b.raised;
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
            small_tree_m,
            levels_raised,
            uploaded_terrain,
            uploaded_prototypes,
        };
        Ok(self.last)
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

