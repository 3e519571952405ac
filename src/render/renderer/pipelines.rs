//! The render and compute pipelines: vertex layouts, shaders, bind-group layouts.

use super::*;

pub(super) fn terrain_layout() -> wgpu::VertexBufferLayout<'static> {
    const A: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32];
    wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TerrainVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &A }
}

pub(super) fn tree_layouts() -> [wgpu::VertexBufferLayout<'static>; 2] {
    const V: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32, 9 => Float32x2];
    const I: [wgpu::VertexAttribute; 7] = wgpu::vertex_attr_array![3 => Float32x4, 4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 10 => Float32x4];
    [
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<TreeVertex>() as u64, step_mode: wgpu::VertexStepMode::Vertex, attributes: &V },
        wgpu::VertexBufferLayout { array_stride: std::mem::size_of::<InstanceRaw>() as u64, step_mode: wgpu::VertexStepMode::Instance, attributes: &I },
    ]
}

impl Renderer {
    pub(in crate::render) fn with_device(device: wgpu::Device, queue: wgpu::Queue, adapter_info: wgpu::AdapterInfo, gpu_ok: bool, format: wgpu::TextureFormat) -> Result<Self> {
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        // a development aid: SYLVA_SCENE_WGSL names a file whose text replaces the built-in
        // scene shader (to tune the pictures' look without rebuilding)
        let source: std::borrow::Cow<'static, str> = match std::env::var_os("SYLVA_SCENE_WGSL") {
            Some(path) => std::fs::read_to_string(&path)
                .map_err(|e| RenderError::Create { what: "scene shader", adapter: adapter_info.name.clone(), message: format!("SYLVA_SCENE_WGSL = {}: {e}", std::path::Path::new(&path).display()) })?
                .into(),
            None => include_str!("../shaders/scene.wgsl").into(),
        };
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("scene.wgsl"), source: wgpu::ShaderSource::Wgsl(source) });
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
            replaced: std::collections::HashMap::new(),
            fast_shading: false,
            coarse_terrain: false,
            pass_triangles: 0,
            light_terms: LightTerms::All,
            crown_sun_on_quad: false,
            fade_per_tree: false,
            shadow_far: None,
            last: FrameStats::default(),
        })
    }

    pub(super) fn cull_pipeline(device: &wgpu::Device) -> GpuCull {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("cull.wgsl"), source: wgpu::ShaderSource::Wgsl(include_str!("../shaders/cull.wgsl").into()) });
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
}
