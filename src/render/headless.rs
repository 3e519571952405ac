//! Headless wgpu renderer: terrain, water, sky and instanced trees into an RGBA image.
//!
//! Passes per frame: (1) sun shadow map (2048², depth only, terrain and trees), (2) main pass
//! with 4× MSAA and depth: sky gradient, terrain, trees (one instanced draw per prototype,
//! level and material), water; resolved and read back with rows padded to 256 bytes.

use std::hash::Hasher;

use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use super::camera::Camera;
use super::instanced::{build_batches, Batches, InstanceRaw};
use super::lod::LodParams;
use super::scene::Scene;
use crate::{Error, Result};

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SHADOW_SIZE: u32 = 2048;
const SAMPLES: u32 = 4;

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
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TerrainVertex {
    pos: [f32; 3],
    normal: [f32; 3],
    color: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TreeVertex {
    pos: [f32; 3],
    normal: [f32; 3],
    mat: f32,
}

struct GpuLevel {
    vb: wgpu::Buffer,
    ib: wgpu::Buffer,
    /// index ranges of bark and leaves
    bark: std::ops::Range<u32>,
    leaves: std::ops::Range<u32>,
}

struct GpuScene {
    fingerprint: u64,
    terrain_vb: Option<wgpu::Buffer>,
    terrain_ib: Option<wgpu::Buffer>,
    terrain_count: u32,
    water_vb: Option<wgpu::Buffer>,
    protos: Vec<Vec<GpuLevel>>,
}

struct Targets {
    size: (u32, u32),
    msaa: wgpu::TextureView,
    depth: wgpu::TextureView,
    resolve: wgpu::Texture,
    resolve_view: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
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
    /// Drawn instances per level of detail.
    pub per_level: [usize; 4],
}

/// A headless renderer bound to one wgpu device.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
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
    bind_main: wgpu::BindGroup,
    bind_shadow: wgpu::BindGroup,
    instance_buf: Option<(wgpu::Buffer, u64)>,
    scene: Option<GpuScene>,
    targets: Option<Targets>,
    /// Level-of-detail parameters used by [`Renderer::render`].
    pub lod: LodParams,
    last: FrameStats,
}

fn terrain_layout() -> wgpu::VertexBufferLayout<'static> {
    const A: [wgpu::VertexAttribute; 3] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
    wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TerrainVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &A }
}

fn tree_layouts() -> [wgpu::VertexBufferLayout<'static>; 2] {
    const V: [wgpu::VertexAttribute; 3] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32];
    const I: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![3 => Float32x4, 4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4];
    [
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TreeVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &V },
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<InstanceRaw>() as u64, step_mode: wgpu::VertexStepMode::Instance, attributes: &I },
    ]
}

impl Renderer {
    /// Opens the first available adapter (a GPU when there is one, else a software adapter
    /// such as lavapipe) and builds the pipelines.
    ///
    /// # Errors
    /// [`Error::Render`] `"no adapter ..."` when wgpu finds no adapter, or when the device
    /// cannot be created.
    pub fn new() -> Result<Self> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions { power_preference: wgpu::PowerPreference::HighPerformance, force_fallback_adapter: false, compatible_surface: None, ..Default::default() })) {
            Ok(a) => a,
            Err(_) => pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions { force_fallback_adapter: true, ..Default::default() }))
                .map_err(|e| Error::Render(format!("no adapter found (install a GPU driver or Mesa's lavapipe, Debian package mesa-vulkan-drivers): {e}")))?,
        };
        let adapter_info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sylva"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| Error::Render(format!("cannot create device on {}: {e}", adapter_info.name)))?;
        Self::with_device(device, queue, adapter_info)
    }

    fn with_device(device: wgpu::Device, queue: wgpu::Queue, adapter_info: wgpu::AdapterInfo) -> Result<Self> {
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("scene.wgsl"), source: wgpu::ShaderSource::Wgsl(include_str!("shaders/scene.wgsl").into()) });
        let uniform_entry = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
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
            ],
        });
        let layout_shadow = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("shadow"), entries: &[uniform_entry] });
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
        let opaque = [Some(wgpu::ColorTargetState { format: COLOR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let blended = [Some(wgpu::ColorTargetState { format: COLOR_FORMAT, blend: Some(wgpu::BlendState::ALPHA_BLENDING), write_mask: wgpu::ColorWrites::ALL })];
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
        let bind_main = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("main"),
            layout: &layout_main,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: globals.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&shadow_view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        let bind_shadow = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("shadow"), layout: &layout_shadow, entries: &[wgpu::BindGroupEntry { binding: 0, resource: shadow_globals.as_entire_binding() }] });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Render(format!("pipeline creation failed on {}: {e}", adapter_info.name)));
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
            bind_main,
            bind_shadow,
            instance_buf: None,
            scene: None,
            targets: None,
            lod: LodParams::default(),
            last: FrameStats::default(),
        })
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

    fn fingerprint(scene: &Scene) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let t = &scene.terrain;
        h.write_usize(t.positions.len());
        h.write_usize(t.indices.len());
        h.write(bytemuck::cast_slice(&t.positions));
        h.write(bytemuck::cast_slice(&t.normals));
        h.write(bytemuck::cast_slice(&t.colors));
        h.write(bytemuck::cast_slice(&t.indices));
        h.write_u32(scene.sea_level.map(f32::to_bits).unwrap_or(1));
        for p in &scene.prototypes {
            for l in &p.lods.levels {
                for m in [&l.bark, &l.leaves] {
                    h.write(bytemuck::cast_slice(&m.positions));
                    h.write(bytemuck::cast_slice(&m.normals));
                    h.write(bytemuck::cast_slice(&m.indices));
                }
            }
            h.write_u8(0xff);
        }
        h.finish()
    }

    fn upload(&mut self, scene: &Scene) -> Result<()> {
        let fp = Self::fingerprint(scene);
        if self.scene.as_ref().map(|s| s.fingerprint) == Some(fp) {
            return Ok(());
        }
        scene.terrain.validate()?;
        let d = &self.device;
        let t = &scene.terrain;
        let (terrain_vb, terrain_ib) = if t.indices.is_empty() {
            (None, None)
        } else {
            let verts: Vec<TerrainVertex> = (0..t.positions.len()).map(|i| TerrainVertex { pos: t.positions[i], normal: t.normals[i], color: t.colors[i] }).collect();
            (
                Some(d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("terrain vb"), contents: bytemuck::cast_slice(&verts), usage: wgpu::BufferUsages::VERTEX })),
                Some(d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("terrain ib"), contents: bytemuck::cast_slice(&t.indices), usage: wgpu::BufferUsages::INDEX })),
            )
        };
        let water_vb = scene.sea_level.filter(|s| s.is_finite()).map(|z| {
            let (lo, hi) = t.bounds();
            let c = |x: f32, y: f32| TerrainVertex { pos: [x, y, z], normal: [0.0, 0.0, 1.0], color: [0.0; 3] };
            let v = [c(lo[0], lo[1]), c(hi[0], lo[1]), c(hi[0], hi[1]), c(lo[0], lo[1]), c(hi[0], hi[1]), c(lo[0], hi[1])];
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("water"), contents: bytemuck::cast_slice(&v), usage: wgpu::BufferUsages::VERTEX })
        });
        let mut protos = Vec::new();
        for (pi, p) in scene.prototypes.iter().enumerate() {
            let mut levels = Vec::new();
            for (li, l) in p.lods.levels.iter().enumerate() {
                let mut verts = Vec::new();
                let mut idx = Vec::new();
                let mut ranges = Vec::new();
                for (m, mat) in [(&l.bark, 0.0f32), (&l.leaves, 1.0)] {
                    if m.normals.len() != m.positions.len() || m.indices.len() % 3 != 0 || m.indices.iter().any(|&i| i as usize >= m.positions.len()) {
                        return Err(Error::Invalid {
                            context: format!("render prototype {pi} `{}` level {li}", p.name),
                            field: if mat == 0.0 { "bark".into() } else { "leaves".into() },
                            value: format!("{} positions, {} normals, {} indices", m.positions.len(), m.normals.len(), m.indices.len()),
                            expected: "one normal per position, indices in range, a multiple of 3".into(),
                        });
                    }
                    let base = verts.len() as u32;
                    let start = idx.len() as u32;
                    verts.extend(m.positions.iter().zip(&m.normals).map(|(p, n)| TreeVertex { pos: *p, normal: *n, mat }));
                    idx.extend(m.indices.iter().map(|i| i + base));
                    ranges.push(start..idx.len() as u32);
                }
                if idx.is_empty() {
                    idx.extend_from_slice(&[0, 0, 0]);
                    verts.push(TreeVertex { pos: [0.0; 3], normal: [0.0, 0.0, 1.0], mat: 0.0 });
                }
                levels.push(GpuLevel {
                    vb: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("tree vb"), contents: bytemuck::cast_slice(&verts), usage: wgpu::BufferUsages::VERTEX }),
                    ib: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("tree ib"), contents: bytemuck::cast_slice(&idx), usage: wgpu::BufferUsages::INDEX }),
                    bark: ranges[0].clone(),
                    leaves: ranges[1].clone(),
                });
            }
            protos.push(levels);
        }
        self.scene = Some(GpuScene { fingerprint: fp, terrain_vb, terrain_ib, terrain_count: t.indices.len() as u32, water_vb, protos });
        Ok(())
    }

    fn ensure_targets(&mut self, w: u32, h: u32) {
        if self.targets.as_ref().map(|t| t.size) == Some((w, h)) {
            return;
        }
        let d = &self.device;
        let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
        let tex = |label: &str, format, samples, usage| {
            d.create_texture(&wgpu::TextureDescriptor { label: Some(label), size, mip_level_count: 1, sample_count: samples, dimension: wgpu::TextureDimension::D2, format, usage, view_formats: &[] })
        };
        let msaa = tex("msaa", COLOR_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        let depth = tex("depth", DEPTH_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        let resolve = tex("resolve", COLOR_FORMAT, 1, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC);
        let resolve_view = resolve.create_view(&Default::default());
        let padded_row = (w * 4).div_ceil(256) * 256;
        let readback = d.create_buffer(&wgpu::BufferDescriptor { label: Some("readback"), size: padded_row as u64 * h as u64, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        self.targets = Some(Targets { size: (w, h), msaa, depth, resolve, resolve_view, readback, padded_row });
    }

    /// Renders `scene` seen by `camera` into a `width` × `height` image (sRGB RGBA).
    ///
    /// GPU copies of the terrain and prototypes are cached between calls while they stay the
    /// same (content fingerprint), so a timelapse re-uploads only instances.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a zero or too large size (limit: the adapter's 2-D texture size)
    /// or inconsistent meshes; [`Error::Render`] when the GPU fails or the readback cannot be
    /// mapped.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(Error::Invalid { context: "render".into(), field: "size".into(), value: format!("{width}x{height}"), expected: format!("1..={max} pixels per side") });
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let r = self.render_inner(scene, camera, width, height);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Render(format!("GPU validation error: {e}")));
        }
        r
    }

    fn render_inner(&mut self, scene: &Scene, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        self.upload(scene)?;
        self.ensure_targets(width, height);
        let batches = build_batches(scene, camera, width, height, &self.lod);
        self.write_globals(scene, camera, width, height);
        self.write_instances(&batches);
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        self.encode_shadow(&mut enc, &batches);
        let (tree_tris, tree_draws) = self.encode_main(&mut enc, &batches);
        let (targets, gpu) = match (&self.targets, &self.scene) {
            (Some(t), Some(g)) => (t, g),
            _ => return Err(Error::Render("internal: targets not created".into())),
        };
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: &targets.resolve, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            wgpu::TexelCopyBufferInfo { buffer: &targets.readback, layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(targets.padded_row), rows_per_image: Some(height) } },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        let sub = self.queue.submit(Some(enc.finish()));
        let slice = targets.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).map_err(|e| Error::Render(format!("device poll failed: {e}")))?;
        rx.recv().map_err(|e| Error::Render(format!("readback channel: {e}")))?.map_err(|e| Error::Render(format!("readback map failed: {e}")))?;
        let mut img = image::RgbaImage::new(width, height);
        {
            let view = slice.get_mapped_range().map_err(|e| Error::Render(format!("readback range: {e}")))?;
            let row = (width * 4) as usize;
            for (y, out) in img.chunks_mut(row).enumerate() {
                let s = y * targets.padded_row as usize;
                out.copy_from_slice(&view[s..s + row]);
            }
        }
        targets.readback.unmap();
        let mut per_level = [0usize; 4];
        for (i, n) in batches.per_level.iter().enumerate() {
            per_level[i.min(3)] += n;
        }
        self.last = FrameStats {
            triangles: tree_tris + gpu.terrain_count as u64 / 3 + if gpu.water_vb.is_some() { 2 } else { 0 },
            tree_triangles: tree_tris,
            tree_draws,
            instances_drawn: batches.per_level.iter().sum(),
            culled: batches.culled,
            invalid: batches.invalid,
            per_level,
        };
        Ok(img)
    }

    fn light_matrix(scene: &Scene) -> (Mat4, f32) {
        let (lo, hi) = scene.terrain.bounds();
        let (mut lo, mut hi) = (Vec3::from(lo), Vec3::from(hi));
        let tallest = scene.instances.iter().map(|t| t.height).filter(|h| h.is_finite()).fold(0.0f32, f32::max);
        for t in &scene.instances {
            let p = Vec3::from(t.position);
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        hi.z += tallest;
        let c = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(1.0);
        let sun = Vec3::from(scene.sun.direction).normalize_or(Vec3::Z);
        let up = if sun.z.abs() > 0.99 { Vec3::Y } else { Vec3::Z };
        let view = glam::camera::rh::view::look_at_mat4(c + sun * 2.0 * r, c, up);
        let proj = glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, 0.5 * r, 3.5 * r);
        (proj * view, 2.0 * r / SHADOW_SIZE as f32)
    }

    fn write_globals(&self, scene: &Scene, camera: &Camera, w: u32, h: u32) {
        let aspect = w as f32 / h as f32;
        let vp = camera.view_proj(aspect);
        let (lvp, _texel_m) = Self::light_matrix(scene);
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
        };
        self.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        g.view_proj = g.light_view_proj;
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

    fn draw_trees<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, b: &Batches) -> (u64, u32) {
        let (Some(gpu), Some((ibuf, _))) = (&self.scene, &self.instance_buf) else { return (0, 0) };
        let mut tris = 0u64;
        let mut draws = 0u32;
        pass.set_vertex_buffer(1, ibuf.slice(..));
        for d in &b.draws {
            let Some(level) = gpu.protos.get(d.prototype).and_then(|p| p.get(d.level)) else { continue };
            pass.set_vertex_buffer(0, level.vb.slice(..));
            pass.set_index_buffer(level.ib.slice(..), wgpu::IndexFormat::Uint32);
            let inst = d.first..d.first + d.count;
            for r in [&level.bark, &level.leaves] {
                if !r.is_empty() {
                    pass.draw_indexed(r.clone(), 0, inst.clone());
                    tris += (r.len() as u64 / 3) * d.count as u64;
                    draws += 1;
                }
            }
        }
        (tris, draws)
    }

    fn encode_shadow(&self, enc: &mut wgpu::CommandEncoder, b: &Batches) {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: &self.shadow_view, depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }), stencil_ops: None }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.bind_shadow, &[]);
        if let Some(gpu) = &self.scene {
            if let (Some(vb), Some(ib)) = (&gpu.terrain_vb, &gpu.terrain_ib) {
                pass.set_pipeline(&self.terrain_shadow);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..gpu.terrain_count, 0, 0..1);
            }
        }
        pass.set_pipeline(&self.tree_shadow);
        self.draw_trees(&mut pass, b);
    }

    fn encode_main(&self, enc: &mut wgpu::CommandEncoder, b: &Batches) -> (u64, u32) {
        let Some(t) = &self.targets else { return (0, 0) };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("main"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment { view: &t.msaa, depth_slice: None, resolve_target: Some(&t.resolve_view), ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Discard } })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: &t.depth, depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }), stencil_ops: None }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.bind_main, &[]);
        pass.set_pipeline(&self.sky);
        pass.draw(0..3, 0..1);
        if let Some(gpu) = &self.scene {
            if let (Some(vb), Some(ib)) = (&gpu.terrain_vb, &gpu.terrain_ib) {
                pass.set_pipeline(&self.terrain);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..gpu.terrain_count, 0, 0..1);
            }
        }
        pass.set_pipeline(&self.tree);
        let r = self.draw_trees(&mut pass, b);
        if let Some(vb) = self.scene.as_ref().and_then(|g| g.water_vb.as_ref()) {
            pass.set_pipeline(&self.water);
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
