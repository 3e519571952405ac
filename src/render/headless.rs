//! The headless layer over [`super::renderer`]: opens an adapter and a device of its own
//! ([`Renderer::new`]: a GPU when there is one, else a software adapter such as lavapipe),
//! draws into its own texture and reads it back as an RGBA image ([`Renderer::render`]). The
//! stills, the timelapses and the tests use it; a window uses [`Renderer::from_device`] and
//! [`Renderer::render_to_view`] directly.

pub use super::renderer::{Culling, FrameStats, LightTerms, Renderer};
use super::camera::Camera;
use super::renderer::{Readback, COLOR_FORMAT};
use super::scene::Scene;
use super::{RenderError, Result};
use crate::Error;

/// The adapter the headless renderer draws on: a GPU when there is one, else a software adapter
/// such as lavapipe; the backends wgpu tries follow `WGPU_BACKEND` (e.g. `vulkan`, `gl`).
///
/// # Errors
/// [`RenderError::NoAdapter`] when wgpu finds none.
fn open_adapter() -> Result<wgpu::Adapter> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions { power_preference: wgpu::PowerPreference::HighPerformance, force_fallback_adapter: false, compatible_surface: None, ..Default::default() })) {
        Ok(a) => Ok(a),
        Err(_) => pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions { force_fallback_adapter: true, ..Default::default() })).map_err(|e| RenderError::NoAdapter(e.to_string())),
    }
}

/// Whether the headless renderer finds an adapter, without opening a device: its name and
/// backend (e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"). `sylva run` asks before it
/// simulates, so that a machine without one is told at once rather than after the simulation.
///
/// # Errors
/// [`RenderError::NoAdapter`] when wgpu finds none (the message names the package to install).
pub fn probe_adapter() -> Result<String> {
    let info = open_adapter()?.get_info();
    Ok(format!("{} ({:?})", info.name, info.backend))
}

impl Renderer {
    /// Opens the first available adapter (a GPU when there is one, else a software adapter
    /// such as lavapipe) and builds the pipelines.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when wgpu finds no adapter, [`RenderError::Create`] when the device
    /// cannot be created.
    pub fn new() -> Result<Self> {
        let adapter = open_adapter()?;
        let adapter_info = adapter.get_info();
        let al = adapter.limits();
        let flags = adapter.get_downlevel_capabilities().flags;
        // GPU culling needs compute shaders, indirect draws and 5 storage buffers per stage
        let gpu_ok = flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS | wgpu::DownlevelFlags::INDIRECT_EXECUTION)
            && al.max_storage_buffers_per_shader_stage >= 5
            && al.max_compute_invocations_per_workgroup >= 64
            && al.max_compute_workgroup_size_x >= 64;
        let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(al.clone());
        limits.max_storage_buffer_binding_size = al.max_storage_buffer_binding_size;
        limits.max_buffer_size = al.max_buffer_size;
        limits.max_storage_buffers_per_shader_stage = al.max_storage_buffers_per_shader_stage.max(limits.max_storage_buffers_per_shader_stage);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor { label: Some("sylva"), required_features: wgpu::Features::empty(), required_limits: limits, ..Default::default() }))
            .map_err(|e| RenderError::Create { what: "device", adapter: adapter_info.name.clone(), message: e.to_string() })?;
        Self::with_device(device, queue, adapter_info, gpu_ok, COLOR_FORMAT)
    }

    fn ensure_readback(&mut self, w: u32, h: u32) {
        if self.readback.as_ref().map(|t| t.size) == Some((w, h)) {
            return;
        }
        let d = &self.device;
        let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
        let texture = d.create_texture(&wgpu::TextureDescriptor { label: Some("resolve"), size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format: self.format, usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC, view_formats: &[] });
        let view = texture.create_view(&Default::default());
        let padded_row = (w * 4).div_ceil(256) * 256;
        let buffer = d.create_buffer(&wgpu::BufferDescriptor { label: Some("readback"), size: padded_row as u64 * h as u64, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        self.readback = Some(Readback { size: (w, h), texture, view, buffer, padded_row });
    }

    /// Renders `scene` seen by `camera` into a `width` × `height` image (sRGB RGBA).
    ///
    /// GPU copies of the terrain and of the prototypes are kept between calls and each is
    /// uploaded again only when its content changes ([`FrameStats::uploaded_terrain`],
    /// [`FrameStats::uploaded_prototypes`]), so a timelapse uploads only instances.
    ///
    /// # Errors
    /// [`RenderError::Input`] ([`Error::Invalid`]) for a zero or too large size (limit: the adapter's 2-D texture size)
    /// or inconsistent meshes; [`RenderError`] when the GPU fails or the readback cannot be
    /// mapped.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        self.check_size(width, height)?;
        if self.format != COLOR_FORMAT {
            return Err(RenderError::Input(Error::Invalid { context: "render".into(), field: "target format".into(), value: format!("{:?}", self.format), expected: format!("{COLOR_FORMAT:?} to read an image back (draw other formats with render_to_view)") }));
        }
        self.ensure_readback(width, height);
        let Some(rb) = self.readback.take() else { return Err(RenderError::Internal("readback target").into()) };
        let r = self.render_to_view(scene, camera, &rb.view, width, height).and_then(|_| self.read_back(&rb, width, height));
        self.readback = Some(rb);
        r
    }

    /// Copies the headless texture to the readback buffer and into an image.
    fn read_back(&self, rb: &Readback, width: u32, height: u32) -> Result<image::RgbaImage> {
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: &rb.texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            wgpu::TexelCopyBufferInfo { buffer: &rb.buffer, layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(rb.padded_row), rows_per_image: Some(height) } },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        let sub = self.queue.submit(Some(enc.finish()));
        let slice = rb.buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).map_err(|e| RenderError::Readback { stage: "poll", message: e.to_string() })?;
        rx.recv().map_err(|e| RenderError::Readback { stage: "channel", message: e.to_string() })?.map_err(|e| RenderError::Readback { stage: "map", message: e.to_string() })?;
        let mut img = image::RgbaImage::new(width, height);
        {
            let view = slice.get_mapped_range().map_err(|e| RenderError::Readback { stage: "range", message: e.to_string() })?;
            let row = (width * 4) as usize;
            for (y, out) in img.chunks_mut(row).enumerate() {
                let s = y * rb.padded_row as usize;
                out.copy_from_slice(&view[s..s + row]);
            }
        }
        rb.buffer.unmap();
        Ok(img)
    }
}
