//! Uploads: the scene's terrain and prototypes (meshes, billboards, leaf textures), the frame
//! targets, and what each frame writes (globals, instances, canopy).

use super::*;

/// Side (texels) of each layer of the renderer's leaf texture array.
pub(super) const LEAF_TEX_PX: u32 = 64;

/// The layers of the renderer's leaf texture array, in order: per [`LeafShape::ALL`] entry `k`,
/// layer `2k` its leaf card ([`texture::leaf_texture_sized`], the 1:2 card drawn into a square)
/// and layer `2k + 1` its leaf-cluster card ([`texture::cluster_texture`]); grey shading in RGB,
/// coverage in alpha (alpha-tested at [`texture::ALPHA_CUTOFF`] by the tree shader).
pub(super) fn leaf_layers() -> Vec<image::RgbaImage> {
    LeafShape::ALL.iter().flat_map(|&s| [texture::leaf_texture_sized(s, LEAF_TEX_PX, LEAF_TEX_PX), texture::cluster_texture(s, LEAF_TEX_PX)]).collect()
}

/// Index of the first layer of `shape` in the leaf texture array (−1: no texture).
pub(super) fn leaf_layer(shape: Option<LeafShape>) -> f32 {
    shape.and_then(|s| LeafShape::ALL.iter().position(|&x| x == s)).map(|k| 2.0 * k as f32).unwrap_or(-1.0)
}

/// Uploads [`leaf_layers`] as a 2-D texture array (RGBA8 linear: the RGB is a shading factor,
/// not a colour) with a bilinear clamped sampler.
pub(super) fn leaf_texture_array(device: &wgpu::Device, queue: &wgpu::Queue) -> (wgpu::TextureView, wgpu::Sampler) {
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
pub(super) fn twig_factor(p: &[f32; 3], r0: f32) -> f32 {
    let t = (((p[0] * p[0] + p[1] * p[1]).sqrt() / r0 - 0.15) / 0.4).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Whether `m` is a set of leaf cards: quads of 4 vertices and 2 triangles each with texture
/// coordinates (0,0), (1,0), (1,1), (0,1) (`structure::mesh` cards).
pub(super) fn is_cards(m: &crate::mesh::TriMesh) -> bool {
    let n = m.positions.len();
    n > 0
        && n % 4 == 0
        && m.uvs.len() == n
        && m.indices.len() == n / 4 * 6
        && m.uvs.chunks(4).all(|q| {
            let want = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            // a leaf card, or a leaf-cluster card (u offset by CLUSTER_CARD_U)
            let du = if q[0][0] > 0.5 * crate::mesh::CLUSTER_CARD_U { crate::mesh::CLUSTER_CARD_U } else { 0.0 };
            q.iter().zip(want).all(|(a, b)| (a[0] - du - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4)
        })
}

/// The billboard impostor level of a prototype with outline `s`: a vertical quad (material 2,
/// turned towards the viewer in the vertex shader) spanning the crown width and the full height,
/// and a horizontal quad (material 3) in the upper crown, which the vertex shader shows only
/// for views from well above (top-down maps). Vertex normals carry the
/// outline coordinates the fragment shader carves with (side: a ∈ −1..1 across, z 0..1 up;
/// top: a, b ∈ −1..1).
pub(super) fn billboard_vertices(s: &Silhouette) -> (Vec<TreeVertex>, Vec<u32>) {
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

/// Bytes of prototype meshes uploaded between two flushes of the staging copies
/// ([`Renderer::flush_uploads`]): 64 MiB. A buffer created with its contents is filled through a
/// staging buffer that the device frees only after the next submission has run, so uploading
/// the meshes of a near field of adapted trees (about 0.7 GB for the 400 trees of the default
/// run's ground view, 200 at full detail) in one go held every staging copy beside its buffer
/// (issue 34).
pub const UPLOAD_FLUSH_BYTES: usize = 64 << 20;

impl Renderer {
    /// Submits the uploads recorded so far and waits until the device has run them, so that
    /// their staging copies are freed.
    ///
    /// Errors: [`RenderError::Readback`] (stage `poll`) when the device is lost.
    pub(super) fn flush_uploads(&self) -> Result<()> {
        let sub = self.queue.submit(std::iter::empty());
        self.device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).map_err(|e| RenderError::Readback { stage: "poll", message: e.to_string() })?;
        Ok(())
    }

    /// Uploads what changed of the scene's static data: the terrain part when its version
    /// ([`Scene::terrain_version`]) differs from the uploaded one, the prototypes when theirs
    /// does, nothing when neither does (no pass over the meshes).
    pub(super) fn upload(&mut self, scene: &Scene) -> Result<(bool, bool)> {
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
    pub(super) fn upload_terrain(&self, scene: &Scene) -> Result<GpuTerrain> {
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
        let canopy_grid = crate::render::canopy::CanopyGrid::for_bounds(lo, hi);
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
    pub(super) fn upload_prototypes(&self, scene: &Scene) -> Result<(Vec<Vec<GpuLevel>>, wgpu::Buffer)> {
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
        // bytes handed to the device since the staging copies were last flushed
        let mut staged = 0usize;
        for (pi, p) in scene.prototypes.iter().enumerate() {
            if staged >= UPLOAD_FLUSH_BYTES {
                self.flush_uploads()?;
                staged = 0;
            }
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
                    // the reduced level's leaf-cluster cards grown about their centres to the
                    // crown disc's plan area (lod::card_spread)
                    let spread_m;
                    let m = if cards && li == REDUCED_LEVEL && !p.rigid {
                        spread_m = spread_cards(m, card_spread(m, r0));
                        &spread_m
                    } else {
                        m
                    };
                    // the crown hull spread to the crown disc's plan area (lod::plan_spread)
                    let spread = if mat > 0.5 && li == CROWN_HULL_LEVEL && !p.rigid { plan_spread(m, r0) } else { 1.0 };
                    let spread_v = |p: &[f32; 3], n: &[f32; 3]| -> ([f32; 3], [f32; 3]) {
                        if spread == 1.0 {
                            return (*p, *n);
                        }
                        ([p[0] * spread, p[1] * spread, p[2]], Vec3::new(n[0] / spread, n[1] / spread, n[2]).normalize_or(Vec3::Z).to_array())
                    };
                    verts.extend(m.positions.iter().zip(&m.normals).enumerate().map(|(k, (p, n))| {
                        let (p, n) = spread_v(p, n);
                        let (p, n) = (&p, &n);
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
                staged += std::mem::size_of_val(verts.as_slice()) + std::mem::size_of_val(idx.as_slice());
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

    pub(super) fn ensure_targets(&mut self, w: u32, h: u32) {
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

    /// `canopy_used`: whether the terrain shader reads the canopy layer (false when the CPU
    /// path splatted nothing this frame); `light`: the sun's matrix of the shadow map
    /// ([`Renderer::light_matrix`]); `light_height`: [`canopy_light_height`] of the trees.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn write_globals(&self, scene: &Scene, camera: &Camera, w: u32, h: u32, canopy_used: bool, light: (Mat4, f32, f32), light_height: f32) {
        let aspect = w as f32 / h as f32;
        let vp = camera.view_proj(aspect);
        let (lvp, texel_m, depth_m) = light;
        let (lo, hi) = scene.terrain.bounds();
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
        let ortho = matches!(camera.projection, crate::render::camera::Projection::Orthographic { .. });
        let v3 = |a: [f32; 3], w: f32| [a[0], a[1], a[2], w];
        let sun = Vec3::from(scene.sun.direction).normalize_or(Vec3::Z).to_array();
        let wd = glam::Vec2::from(scene.wind.direction).normalize_or(glam::Vec2::X);
        let mut g = Globals {
            view_proj: vp.to_cols_array_2d(),
            light_view_proj: lvp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            eye: v3(camera.eye, if ortho { 1.0 } else { 0.0 }),
            sun_dir: v3(sun, self.light_terms.code()),
            sun_color: v3(scene.sun.color, if self.crown_sun_on_quad { 1.0 } else { 0.0 }),
            sky_zenith: v3(scene.sky.zenith, pixel_m_per_depth(camera, h)),
            sky_horizon: v3(scene.sky.horizon, if self.fade_per_tree { 1.0 } else { 0.0 }),
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
        // no stem widening in the sun's shadow map
        g.sky_zenith[3] = 0.0;
        self.queue.write_buffer(&self.shadow_globals, 0, bytemuck::bytes_of(&g));
    }

    pub(super) fn write_instances(&mut self, b: &Batches) {
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
    pub(super) fn write_canopy(&self, b: &Batches) {
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
    pub(super) fn write_far_canopy(&self, far: &FarField, near: &[TreeInstance], prototypes: &[crate::render::scene::Prototype], b: &Batches) {
        let Some(gs) = &self.scene else { return };
        let g = gs.canopy_grid;
        let mut sums = far.sums().to_vec();
        let crown_r0: Vec<f32> = prototypes.iter().map(|p| p.normalised_crown_radius()).collect();
        for t in near {
            if let Some(c) = crate::render::farfield::full_splat(t, prototypes, &crown_r0) {
                g.unsplat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
            }
        }
        for c in &b.canopy {
            g.splat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
        }
        self.queue.write_buffer(&gs.canopy_buf, 0, bytemuck::cast_slice(&sums));
    }
}

/// World size (m) of one pixel of a `height_px` tall frame per metre of clip-space w (view
/// depth) of `camera`: `2 tan(fov_y / 2) / height_px` in perspective, `2 · half_height /
/// height_px` orthographic (clip w = 1). The tree shader widens the stems of coarse levels to
/// `MIN_STEM_PX` with it (`shaders/scene.wgsl`, issue 32).
pub(crate) fn pixel_m_per_depth(camera: &Camera, height_px: u32) -> f32 {
    let h = height_px.max(1) as f32;
    match camera.projection {
        crate::render::camera::Projection::Perspective { fov_y_deg } => 2.0 * (fov_y_deg.to_radians() * 0.5).tan() / h,
        crate::render::camera::Projection::Orthographic { half_height } => 2.0 * half_height.max(0.0) / h,
    }
}
