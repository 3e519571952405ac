//! Culling and level selection on the GPU: the frame's compute pass and its buffers.

use super::*;

impl Renderer {
    /// Uploads the instance records and culling parameters for the compute pass. `None` when
    /// the compacted buffers would exceed the adapter's limits (the caller falls back to the
    /// CPU path or fails).
    pub(super) fn prepare_gpu_cull(&mut self, scene: &Scene, camera: &Camera, width: u32, height: u32) -> Result<Option<GpuFrame>> {
        use rayon::prelude::*;
        let crown_r0: Vec<f32> = scene.prototypes.iter().map(|p| p.normalised_crown_radius()).collect();
        let n_protos = scene.prototypes.len();
        // the valid instances per prototype, counted before any record is made: a frame whose
        // compacted buffers exceed the limits falls back to the CPU path without building the
        // records first (260 MB for the default run's year 150 on lavapipe; issue 34)
        let per_proto: Vec<u32> = scene
            .instances
            .par_iter()
            .fold(
                || vec![0u32; n_protos],
                |mut c, t| {
                    if let Some(s) = crate::render::instanced::record_prototype(t, &scene.prototypes, &crown_r0) {
                        c[s] += 1;
                    }
                    c
                },
            )
            .reduce(
                || vec![0u32; n_protos],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        let valid = per_proto.iter().map(|&n| n as usize).sum::<usize>();
        let invalid = scene.instances.len() - valid;
        // slots: (prototype, level), capacity = instances of the prototype
        let mut slots = Vec::new();
        let mut proto_words: Vec<[u32; 4]> = Vec::with_capacity(n_protos);
        let mut base = 0u64;
        for (p, proto) in scene.prototypes.iter().enumerate() {
            let n = drawn_levels(proto.lods.levels.len());
            proto_words.push([n as u32, slots.len() as u32, proto.rigid as u32, 0]);
            for l in 0..n {
                slots.push(GpuSlot { prototype: p, level: l, base: base as u32, cap: per_proto[p] });
                base += per_proto[p] as u64;
            }
        }
        let limits = self.device.limits();
        let rec = std::mem::size_of::<InstanceRaw>() as u64;
        let dst_bytes = (base * rec).max(256);
        let src_bytes = (valid as u64 * rec).max(256);
        let max_bind = limits.max_storage_buffer_binding_size;
        if dst_bytes > max_bind || dst_bytes > limits.max_buffer_size || src_bytes > max_bind || base > u32::MAX as u64 / 2 {
            return Ok(None);
        }
        // the valid records in instance order, without a second list of them all (issue 34)
        let src: Vec<InstanceRaw> = scene.instances.par_iter().filter_map(|t| instance_record(t, &scene.prototypes, &crown_r0)).collect();
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
            proto_words.push(crate::render::instanced::level_costs(p));
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
        args.extend(std::iter::repeat_n(0u32, LOD_LEVELS + n_protos * crate::render::lod::SIZE_BINS));
        // the `choose` results (or their defaults when it does not run): switch-size factor,
        // far-field switch; then the count of canopy-only trees
        args.push(1.0f32.to_bits());
        args.push(if self.lod.canopy_px > 0.0 { self.lod.canopy_px } else { 0.0 }.to_bits());
        args.push(0);
        let args_bytes = (args.len() * 4) as u64;
        let aspect = width as f32 / height as f32;
        let vp = camera.view_proj(aspect);
        let fr = Frustum::from_view_proj(vp);
        let ortho = matches!(camera.projection, crate::render::camera::Projection::Orthographic { .. });
        let ppm = match camera.projection {
            crate::render::camera::Projection::Perspective { fov_y_deg } => height as f32 / (2.0 * (fov_y_deg.to_radians() * 0.5).tan()),
            crate::render::camera::Projection::Orthographic { half_height } => height as f32 / (2.0 * half_height.max(1e-3)),
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
            canopy_n: [gs.canopy_grid.nx, gs.canopy_grid.ny, self.lod.max_geometry_triangles, self.lod.small_tree_m.max(0.0).to_bits()],
        };
        let Some(cull) = self.cull.as_mut() else { return Ok(None) };
        let d = &self.device;
        let ensure = |slot: &mut Option<(wgpu::Buffer, u64)>, need: u64, usage: wgpu::BufferUsages, label: &str| {
            if slot.as_ref().map(|(_, c)| *c < need).unwrap_or(true) {
                let cap = buffer_capacity(need);
                // the old buffer goes before the new one is made, not after
                *slot = None;
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
        let budget = self.lod.max_triangles > 0 || (self.lod.canopy_px > 0.0 && self.lod.max_geometry_triangles > 0);
        Ok(Some(GpuFrame { slots, budget, invalid, valid, args_bytes }))
    }

    pub(super) fn encode_cull(&self, enc: &mut wgpu::CommandEncoder, f: &GpuFrame) {
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
}

/// Capacity (bytes) of a culling buffer for `need` bytes: the next power of two up to 64 MiB,
/// above it the next multiple of 1/16 of the next power of two. Whole powers of two reserved
/// up to twice the bytes needed (the compacted instances of the default run's year 150,
/// 1.25 GB, in a 2 GiB buffer; issue 34: on lavapipe only the pages written count, so the
/// resident memory did not change, but a GPU's does); steps of 1/16 leave at most about 6 %
/// unused and still few reallocations as a film's forest grows.
pub(super) fn buffer_capacity(need: u64) -> u64 {
    let p = need.max(1).next_power_of_two();
    if p <= 64 << 20 {
        return p;
    }
    let step = p / 16;
    need.div_ceil(step) * step
}

#[cfg(test)]
mod tests {
    use super::buffer_capacity;

    #[test]
    fn culling_buffers_grow_in_sixteenths_above_64_mib() {
        assert_eq!(buffer_capacity(0), 1);
        assert_eq!(buffer_capacity(1000), 1024);
        assert_eq!(buffer_capacity(64 << 20), 64 << 20);
        let need = (1u64 << 30) + (1u64 << 28) + 5; // 1.25 GiB + 5 B
        let cap = buffer_capacity(need);
        assert!(cap >= need && cap - need <= (2u64 << 30) / 16 && cap % ((2u64 << 30) / 16) == 0, "{cap}");
    }
}
