//! The passes of a frame: the sun's light matrix, the shadow pass, the main pass and the tree draws
//! in them.

use super::*;

impl Renderer {
    /// The sun's orthographic view-projection over the scene's bounding sphere (radius r, depth
    /// range r..3r from an eye 2r towards the sun), the world size of a shadow texel (m) and the
    /// depth range (m). `trees`: the bounds of the trees' stems and the tallest tree
    /// ([`tree_extent`]).
    pub(super) fn light_matrix(scene: &Scene, trees: Option<([f32; 3], [f32; 3], f32)>) -> (Mat4, f32, f32) {
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

    /// The tree draws of a frame in groups of one render pass each ([`Renderer::pass_triangles`]):
    /// consecutive ranges of the GPU path's slots or the CPU path's draws that cover them all in
    /// order; one range when the frame is not split.
    pub(super) fn tree_pass_groups(&self, draws: &FrameDraws) -> Vec<std::ops::Range<usize>> {
        let tris = |p: usize, l: usize| self.level_tris(p, l);
        // an upper bound of the triangles of each slot or draw
        let cost: Vec<u64> = match draws {
            FrameDraws::Cpu(b) => b.draws.iter().map(|d| d.count as u64 * tris(d.prototype, d.level)).collect(),
            FrameDraws::Gpu(f) => f.slots.iter().map(|s| s.cap as u64 * tris(s.prototype, s.level)).collect(),
        };
        split_by_cost(&cost, self.pass_triangles)
    }

    /// Triangles of one instance of uploaded prototype `p` at drawn level `l` (both materials).
    fn level_tris(&self, p: usize, l: usize) -> u64 {
        self.scene.as_ref().and_then(|g| g.protos.get(p)).and_then(|p| p.get(l)).map_or(0, |l| (l.bark.len() + l.leaves.len()) as u64 / 3)
    }

    /// The CPU path's draws cut into consecutive instance ranges of at most about
    /// [`Renderer::pass_triangles`] triangles each, so that no render pass holds more than that
    /// (a draw of 600,000 billboards or 6,000 full meshes is several; issue 34). The instances
    /// keep their order, so the picture is the same. Unchanged when the frame is not split.
    pub(super) fn split_draws(&self, draws: &[DrawBatch]) -> Vec<DrawBatch> {
        if self.pass_triangles == 0 {
            return draws.to_vec();
        }
        let mut out = Vec::with_capacity(draws.len());
        for d in draws {
            let per = self.level_tris(d.prototype, d.level).max(1);
            let step = (self.pass_triangles / per).clamp(1, u32::MAX as u64) as u32;
            let mut first = d.first;
            let end = d.first + d.count;
            while first < end {
                let count = step.min(end - first);
                out.push(DrawBatch { first, count, ..*d });
                first += count;
            }
        }
        out
    }

    /// Whether each render pass of a split frame ([`Renderer::pass_triangles`]) is submitted
    /// and waited for before the next is recorded: on a software adapter. lavapipe (llvmpipe)
    /// bins the triangles of a command buffer into scenes of up to 36 MB each and queues them
    /// to its rasteriser threads without waiting, allocating new scenes (up to 64, 2.3 GB)
    /// while the rasterisers lag behind; the binning thread runs far ahead of a 4× MSAA frame's
    /// shading, so the default run's year 150 held all 64 (issue 34). A wait after each pass
    /// bounds what is binned and not yet drawn to one pass's triangles.
    pub(super) fn wait_between_passes(&self) -> bool {
        self.pass_triangles > 0 && self.is_software()
    }

    /// Submits what `enc` holds and waits until the device has executed it; `enc` starts anew.
    pub(super) fn submit_and_wait(&self, enc: &mut wgpu::CommandEncoder) -> Result<()> {
        let done = std::mem::replace(enc, self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") }));
        let sub = self.queue.submit(Some(done.finish()));
        self.device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).map_err(|e| RenderError::Readback { stage: "poll", message: e.to_string() })?;
        Ok(())
    }

    /// Records the tree draws of the slots (GPU path) or draws (CPU path) in `range`; returns the
    /// number of draw calls.
    pub(super) fn draw_trees<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, draws: &FrameDraws, range: std::ops::Range<usize>) -> u32 {
        let Some(gpu) = &self.scene else { return 0 };
        let mut n = 0u32;
        match draws {
            FrameDraws::Cpu(b) => {
                let Some((ibuf, _)) = &self.instance_buf else { return 0 };
                // the records written this frame, not the whole buffer: wgpu zeroes a bound
                // range that was never written first (the rest of a power-of-two capacity,
                // 59 MB of a 128 MiB buffer at the default run's year 150; issue 34)
                let end = b.draws.iter().map(|d| u64::from(d.first) + u64::from(d.count)).max().unwrap_or(0) * std::mem::size_of::<InstanceRaw>() as u64;
                if end == 0 {
                    return 0;
                }
                pass.set_vertex_buffer(1, ibuf.slice(..end));
                for d in b.draws.get(range).unwrap_or(&[]) {
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
                for (k, s) in f.slots.iter().enumerate().skip(range.start).take(range.len()) {
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

    /// The shadow pass; with [`Renderer::wait_between_passes`] each of its render passes is
    /// submitted and waited for (the last too: the main pass follows).
    pub(super) fn encode_shadow(&self, enc: &mut wgpu::CommandEncoder, draws: &FrameDraws) -> Result<()> {
        let Some(gpu) = &self.scene else { return Ok(()) };
        let wait = self.wait_between_passes();
        for (g, range) in self.tree_pass_groups(draws).into_iter().enumerate() {
            if g > 0 && wait {
                self.submit_and_wait(enc)?;
            }
            let load = if g == 0 { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: &self.shadow_view, depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }), stencil_ops: None }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &gpu.bind_shadow, &[]);
            if g == 0 {
                if let (Some(vb), Some(ib)) = (&gpu.terrain_vb, &gpu.terrain_ib) {
                    pass.set_pipeline(&self.terrain_shadow);
                    pass.set_vertex_buffer(0, vb.slice(..));
                    pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..gpu.terrain_count, 0, 0..1);
                }
            }
            pass.set_pipeline(&self.tree_shadow);
            self.draw_trees(&mut pass, draws, range);
        }
        if wait {
            self.submit_and_wait(enc)?;
        }
        Ok(())
    }

    /// The main pass; with [`Renderer::wait_between_passes`] each of its render passes but the
    /// last is submitted and waited for (the caller submits the last).
    pub(super) fn encode_main(&self, enc: &mut wgpu::CommandEncoder, draws: &FrameDraws, view: &wgpu::TextureView) -> Result<u32> {
        let (Some(t), Some(gpu)) = (&self.targets, &self.scene) else { return Ok(0) };
        let groups = self.tree_pass_groups(draws);
        let n = groups.len();
        let wait = self.wait_between_passes();
        let mut r = 0;
        for (g, range) in groups.into_iter().enumerate() {
            if g > 0 && wait {
                self.submit_and_wait(enc)?;
            }
            let (first, last) = (g == 0, g + 1 == n);
            let color_load = if first { wgpu::LoadOp::Clear(wgpu::Color::BLACK) } else { wgpu::LoadOp::Load };
            let depth_load = if first { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load };
            // the multisampled colour and the depth are kept for the next pass, resolved after the last
            let keep = if last { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("main"),
                color_attachments: &[Some(if self.single_sample {
                    wgpu::RenderPassColorAttachment { view, depth_slice: None, resolve_target: None, ops: wgpu::Operations { load: color_load, store: wgpu::StoreOp::Store } }
                } else {
                    wgpu::RenderPassColorAttachment { view: &t.msaa, depth_slice: None, resolve_target: last.then_some(view), ops: wgpu::Operations { load: color_load, store: keep } }
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: if self.single_sample { &t.depth1 } else { &t.depth }, depth_ops: Some(wgpu::Operations { load: depth_load, store: keep }), stencil_ops: None }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &gpu.bind_main, &[]);
            r += self.encode_main_pass(&mut pass, draws, range, first, last);
        }
        Ok(r)
    }

    /// The draws of one of the main pass's render passes: the sky and the terrain in the
    /// `first`, the trees of `range`, the water in the `last`.
    fn encode_main_pass<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, draws: &FrameDraws, range: std::ops::Range<usize>, first: bool, last: bool) -> u32 {
        let Some(gpu) = &self.scene else { return 0 };
        let (sky, terrain, water, tree) = if self.single_sample { (&self.single.sky, &self.single.terrain, &self.single.water, &self.single.tree) } else { (&self.sky, &self.terrain, &self.water, &self.tree) };
        if first {
            self.encode_ground(pass, sky, terrain);
        }
        pass.set_pipeline(tree);
        let r = self.draw_trees(pass, draws, range);
        if last {
            if let Some(vb) = &gpu.water_vb {
                pass.set_pipeline(water);
                pass.set_vertex_buffer(0, vb.slice(..));
                pass.draw(0..6, 0..1);
            }
        }
        r
    }

    /// The sky and the terrain of the main pass.
    fn encode_ground<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, sky: &'a wgpu::RenderPipeline, terrain: &'a wgpu::RenderPipeline) {
        let Some(gpu) = &self.scene else { return };
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
    }
}

/// Consecutive ranges covering `cost` in order, each of total cost at most `budget` where it
/// holds more than one item (an item over it stands alone); `budget` 0: one range of all.
pub(super) fn split_by_cost(cost: &[u64], budget: u64) -> Vec<std::ops::Range<usize>> {
    if budget == 0 || cost.is_empty() {
        return std::iter::once(0..cost.len()).collect();
    }
    let mut out = Vec::new();
    let (mut start, mut sum) = (0, 0u64);
    for (i, &c) in cost.iter().enumerate() {
        if i > start && sum + c > budget {
            out.push(start..i);
            (start, sum) = (i, 0);
        }
        sum += c;
    }
    out.push(start..cost.len());
    out
}

#[cfg(test)]
mod tests {
    use super::split_by_cost;

    #[test]
    fn passes_split_by_cost_in_order() {
        assert_eq!(split_by_cost(&[5, 5, 5], 0), vec![0..3]);
        assert_eq!(split_by_cost(&[], 10), vec![0..0]);
        assert_eq!(split_by_cost(&[4, 4, 4, 30, 1, 1], 10), vec![0..2, 2..3, 3..4, 4..6]);
        assert_eq!(split_by_cost(&[30], 10), vec![0..1]);
    }
}
