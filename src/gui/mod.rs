//! What the two windows of Sylva share (`sylva view`, [`crate::view`]; `sylva edit`,
//! [`crate::edit`]): opening an eframe window on wgpu with the device limits the renderer needs,
//! a clear error instead of a panic when there is no display or no adapter, the 3-D viewport
//! (the scene drawn by [`crate::render::renderer::Renderer::render_to_view`] into an offscreen
//! texture that egui shows as an image), and `--screenshot PATH --frames N` (render N frames,
//! write a PNG of the whole window, close).
//!
//! A shell module: the core names none of it (`tests/layers.rs`).

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use eframe::{egui, egui_wgpu};

use crate::render::camera::Camera;
use crate::render::renderer::Renderer;
use crate::render::scene::Scene;

/// Errors of the windows.
#[derive(Debug, thiserror::Error)]
pub enum GuiError {
    /// Neither `DISPLAY` (X11) nor `WAYLAND_DISPLAY` is set.
    #[error("no display: neither DISPLAY nor WAYLAND_DISPLAY is set (on a machine without a screen run under a virtual one, e.g. `xvfb-run -s '-screen 0 1280x800x24' sylva …`)")]
    NoDisplay,
    /// wgpu found no adapter that can draw into the window.
    #[error("no graphics adapter can draw into the window ({0}); on a machine without a GPU install Mesa's software Vulkan driver (`apt-get install mesa-vulkan-drivers`)")]
    NoAdapter(String),
    /// The window system or the event loop failed.
    #[error("the window could not be opened: {0}")]
    Window(String),
    /// The renderer could not be built on the window's device.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// Writing the screenshot failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// The graphics device reported an error while the window was open (a feature the adapter
    /// lacks, a lost device); the window was closed instead of aborting.
    #[error("the graphics device failed ({0}); the window was closed, and what was saved before is kept. Another backend may work: set WGPU_BACKEND=vulkan, gl, metal or dx12")]
    Device(String),
    /// The screenshot did not arrive.
    #[error("screenshot {path}: {message}")]
    Screenshot {
        /// The PNG that was to be written.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// Result of the windows.
pub type Result<T> = std::result::Result<T, GuiError>;

/// How a window is opened.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowOptions {
    /// Inner size in logical points (width, height).
    pub size: (f32, f32),
    /// `--screenshot PATH`: write a PNG of the whole window after [`WindowOptions::frames`]
    /// frames, then close.
    pub screenshot: Option<PathBuf>,
    /// `--frames N` (≥ 1): frames drawn before the screenshot; the screenshot shows the N-th
    /// (the window then takes one or two more UI passes to receive the image, in which the
    /// viewer's 3-D view is not drawn again).
    pub frames: u32,
}

impl Default for WindowOptions {
    fn default() -> Self {
        WindowOptions { size: (1280.0, 800.0), screenshot: None, frames: 5 }
    }
}

/// Fails with [`GuiError::NoDisplay`] when no display server is named in the environment
/// (`DISPLAY` or `WAYLAND_DISPLAY`); winit would otherwise abort deep in its setup.
pub fn check_display() -> Result<()> {
    let set = |k: &str| std::env::var_os(k).is_some_and(|v| !v.is_empty());
    if cfg!(target_os = "linux") && !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
        return Err(GuiError::NoDisplay);
    }
    Ok(())
}

/// Device limits for the renderer: wgpu's defaults with the adapter's own buffer sizes (the
/// instance and culling buffers of a large forest) and storage buffers per stage (the compute
/// culling pass needs 5), as the headless renderer asks.
fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
    let al = adapter.limits();
    let base = if adapter.get_info().backend == wgpu::Backend::Gl { wgpu::Limits::downlevel_webgl2_defaults() } else { wgpu::Limits::default() };
    let mut limits = base.using_resolution(al.clone());
    limits.max_storage_buffer_binding_size = al.max_storage_buffer_binding_size;
    limits.max_buffer_size = al.max_buffer_size;
    limits.max_storage_buffers_per_shader_stage = al.max_storage_buffers_per_shader_stage;
    wgpu::DeviceDescriptor { label: Some("sylva window"), required_limits: limits, ..Default::default() }
}

/// Opens a window titled `title` running the app that `make` builds (given the egui context and
/// the window's wgpu render state), and returns when it closes.
///
/// # Errors
/// [`GuiError::NoDisplay`] without a display, [`GuiError::NoAdapter`] when wgpu finds no
/// adapter, [`GuiError::Window`] for other window-system failures, and any error the app
/// reported through the shared `failure` slot (e.g. a screenshot that could not be written).
pub fn run_window<A: eframe::App + 'static>(title: &str, opts: &WindowOptions, make: impl FnOnce(&eframe::CreationContext<'_>, Arc<Mutex<Option<GuiError>>>) -> Result<A>) -> Result<()> {
    check_display()?;
    let failure: Arc<Mutex<Option<GuiError>>> = Arc::new(Mutex::new(None));
    let setup = egui_wgpu::WgpuSetupCreateNew { device_descriptor: Arc::new(device_descriptor), ..egui_wgpu::WgpuSetupCreateNew::without_display_handle() };
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_title(title).with_inner_size([opts.size.0, opts.size.1]).with_app_id("sylva"),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration { wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup), ..Default::default() },
        ..Default::default()
    };
    let f2 = failure.clone();
    let res = eframe::run_native(
        title,
        native,
        Box::new(move |cc| {
            // a device error never aborts: it is kept for the caller and the window closes
            if let Some(rs) = cc.wgpu_render_state.as_ref() {
                let (slot, ctx) = (f2.clone(), cc.egui_ctx.clone());
                rs.device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                    tracing::error!("graphics device error: {e}");
                    if let Ok(mut f) = slot.lock() {
                        f.get_or_insert(GuiError::Device(e.to_string()));
                    }
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }));
            }
            let app = make(cc, f2.clone()).map_err(|e| -> Box<dyn std::error::Error + Send + Sync> { Box::new(e) })?;
            Ok(Box::new(app))
        }),
    );
    if let Some(e) = failure.lock().ok().and_then(|mut f| f.take()) {
        return Err(e);
    }
    match res {
        Ok(()) => Ok(()),
        Err(eframe::Error::Wgpu(e)) => Err(GuiError::NoAdapter(e.to_string())),
        Err(eframe::Error::AppCreation(e)) => match e.downcast::<GuiError>() {
            Ok(g) => Err(*g),
            Err(e) => Err(GuiError::Window(e.to_string())),
        },
        Err(e) => Err(GuiError::Window(e.to_string())),
    }
}

/// Opens a window like [`run_window`] for an app with a 3-D viewport: `value` (the document or
/// run data, moved into the window once) is handed to `make` together with a [`Viewport3d`] on
/// the window's device and, with `opts.screenshot`, the [`Screenshot`] state the app must drive.
///
/// # Errors
/// As [`run_window`]; [`GuiError::NoAdapter`] when the window has no wgpu render state;
/// [`GuiError::Render`] when the viewport's renderer cannot be built; whatever `make` returns.
pub fn run_viewport_window<T: Send + 'static, A: eframe::App + 'static>(title: &str, opts: &WindowOptions, value: T, make: impl FnOnce(T, Viewport3d, Option<Screenshot>) -> Result<A>) -> Result<()> {
    let screenshot = opts.screenshot.clone().map(|p| (p, opts.frames));
    let slot = Arc::new(Mutex::new(Some(value)));
    run_window(title, opts, move |cc, failure| {
        let rs = cc.wgpu_render_state.as_ref().ok_or_else(|| GuiError::NoAdapter("the window has no wgpu render state".into()))?;
        let vp = Viewport3d::new(rs)?;
        let v = slot.lock().ok().and_then(|mut d| d.take()).ok_or_else(|| GuiError::Window("the window's document was taken twice".into()))?;
        make(v, vp, screenshot.map(|(p, frames)| Screenshot::new(&p, frames, failure)))
    })
}

/// The `--screenshot` state machine of a window: counts frames, asks egui for a screenshot of
/// the whole window after the last one, writes it as PNG and closes the window.
pub struct Screenshot {
    path: PathBuf,
    frames: u32,
    frame: u32,
    requested_at: Option<u32>,
    image: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    failure: Arc<Mutex<Option<GuiError>>>,
    done: bool,
    /// This pass does not count ([`Screenshot::hold`]).
    held: bool,
    /// Passes held in a row.
    holds: u32,
}

impl Screenshot {
    /// A screenshot of the window into `path` after `frames` frames (at least 1); errors go to
    /// `failure`, which [`run_window`] returns.
    pub fn new(path: &Path, frames: u32, failure: Arc<Mutex<Option<GuiError>>>) -> Self {
        Screenshot { path: path.to_path_buf(), frames: frames.max(1), frame: 0, requested_at: None, image: Arc::new(Mutex::new(None)), failure, done: false, held: false, holds: 0 }
    }

    /// Whether the window is still drawing the frames before its screenshot.
    pub fn pending(&self) -> bool {
        !self.done
    }

    /// Whether the screenshot has been asked of the window system: the last of the `frames`
    /// frames has been drawn, and the frames until the image arrives (one or two UI passes)
    /// need not draw the 3-D view again (a trial saw `--frames 2` draw three full-detail frames
    /// of 16–18 s each).
    pub fn requested(&self) -> bool {
        self.requested_at.is_some()
    }

    /// The app waits for something the screenshot must show (the viewer's adapted near field):
    /// this pass does not count among the `frames`, unless the app has held for
    /// [`MAX_HOLD_PASSES`] passes in a row (then it is logged and the frames count again). Call
    /// before [`Screenshot::frame`].
    pub fn hold(&mut self) {
        if self.holds < MAX_HOLD_PASSES {
            self.held = true;
        } else if self.holds == MAX_HOLD_PASSES {
            tracing::warn!("screenshot {}: waited {MAX_HOLD_PASSES} passes; taken without what the window waited for", self.path.display());
        }
    }

    /// Call once per frame, after the UI is laid out.
    pub fn frame(&mut self, ctx: &egui::Context) {
        if self.done {
            return;
        }
        if std::mem::take(&mut self.held) {
            self.holds += 1;
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
            return;
        }
        self.frame += 1;
        ctx.request_repaint();
        let got = self.image.lock().ok().and_then(|mut g| g.take());
        if let Some(img) = got {
            let r = write_color_image(&self.path, &img);
            if let Err(e) = r {
                if let Ok(mut f) = self.failure.lock() {
                    *f = Some(e);
                }
            } else {
                tracing::info!("screenshot {}×{} → {}", img.size[0], img.size[1], self.path.display());
            }
            self.done = true;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        match self.requested_at {
            None if self.frame >= self.frames => {
                let slot = self.image.clone();
                ctx.request_screenshot(move |img| {
                    if let Ok(mut s) = slot.lock() {
                        *s = Some(img);
                    }
                });
                self.requested_at = Some(self.frame);
            }
            Some(at) if self.frame > at + 120 => {
                if let Ok(mut f) = self.failure.lock() {
                    *f = Some(GuiError::Screenshot { path: self.path.clone(), message: "the window system returned no image within 120 frames".into() });
                }
                self.done = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            _ => {}
        }
    }
}

/// Most passes in a row a [`Screenshot`] waits for the app ([`Screenshot::hold`]): 12,000
/// (at least 10 minutes: a held pass is repainted after 50 ms at the soonest).
pub const MAX_HOLD_PASSES: u32 = 12_000;

/// Writes an egui screenshot (sRGB, unmultiplied alpha made opaque) as PNG (atomically).
///
/// # Errors
/// [`GuiError::Output`] naming the file.
pub fn write_color_image(path: &Path, img: &egui::ColorImage) -> Result<()> {
    let [w, h] = img.size;
    let mut out = image::RgbaImage::new(w as u32, h as u32);
    for (p, c) in out.pixels_mut().zip(&img.pixels) {
        *p = image::Rgba([c.r(), c.g(), c.b(), 255]);
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| crate::output::OutputError::io(dir, e))?;
    }
    crate::output::pictures::write_png(path, &out)?;
    Ok(())
}

/// The 3-D viewport of a window: the renderer on the window's device, drawing into an offscreen
/// texture of the viewport's size in pixels that egui shows as an image.
///
/// The texture is `Rgba8Unorm` (what egui samples, its bytes read as sRGB-encoded values) and
/// the renderer draws through an `Rgba8UnormSrgb` view of it, so its linear output is encoded
/// to sRGB on write exactly as in the stills. Where the device cannot view a texture in another
/// format (OpenGL/GLES adapters lack `DownlevelFlags::VIEW_FORMATS`), the renderer draws into an
/// `Rgba8UnormSrgb` texture of its own that is copied into the `Rgba8Unorm` one after each frame
/// (the bytes are the same: the formats differ only in how they are read).
pub struct Viewport3d {
    /// The renderer (its `lod` parameters can be tuned).
    pub renderer: Renderer,
    device: wgpu::Device,
    queue: wgpu::Queue,
    egui_renderer: Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
    target: Option<ViewportTarget>,
    /// Whether the device can view a texture in another format (`DownlevelFlags::VIEW_FORMATS`).
    view_formats: bool,
    /// Milliseconds the last [`Viewport3d::draw`] took on the CPU side (culling, uploads,
    /// command recording and submission).
    pub last_ms: f32,
}

/// The viewport's textures: what egui shows, the view the renderer draws into, and (without
/// view formats) the sRGB texture it draws into that is copied into the shown one.
struct ViewportTarget {
    shown: wgpu::Texture,
    view: wgpu::TextureView,
    staging: Option<wgpu::Texture>,
    id: egui::TextureId,
    size: (u32, u32),
}

impl Viewport3d {
    /// The viewport on the window's render state.
    ///
    /// # Errors
    /// [`GuiError::Render`] when the renderer's pipelines cannot be built on this device.
    pub fn new(rs: &egui_wgpu::RenderState) -> Result<Self> {
        let renderer = Renderer::from_device(rs.device.clone(), rs.queue.clone(), wgpu::TextureFormat::Rgba8UnormSrgb)?;
        let view_formats = rs.adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::VIEW_FORMATS);
        Ok(Viewport3d { renderer, device: rs.device.clone(), queue: rs.queue.clone(), egui_renderer: rs.renderer.clone(), target: None, view_formats, last_ms: 0.0 })
    }

    /// Draws `scene` from `camera` at `w × h` pixels and returns the egui texture to show.
    ///
    /// # Errors
    /// [`GuiError::Render`] when the frame fails.
    pub fn draw(&mut self, scene: &Scene, camera: &Camera, w: u32, h: u32) -> Result<egui::TextureId> {
        let (w, h) = (w.max(16), h.max(16));
        let t0 = std::time::Instant::now();
        if self.target.as_ref().map(|t| t.size) != Some((w, h)) {
            let views = self.view_formats;
            let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
            let texture = |label, format, usage, view_formats: &[wgpu::TextureFormat]| {
                self.device.create_texture(&wgpu::TextureDescriptor { label: Some(label), size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format, usage, view_formats })
            };
            let srgb_format = wgpu::TextureFormat::Rgba8UnormSrgb;
            let (shown, view, staging) = if views {
                let shown = texture("viewport", wgpu::TextureFormat::Rgba8Unorm, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING, &[srgb_format]);
                let view = shown.create_view(&wgpu::TextureViewDescriptor { format: Some(srgb_format), ..Default::default() });
                (shown, view, None)
            } else {
                let shown = texture("viewport", wgpu::TextureFormat::Rgba8Unorm, wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING, &[]);
                let staging = texture("viewport (sRGB)", srgb_format, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC, &[]);
                let view = staging.create_view(&Default::default());
                (shown, view, Some(staging))
            };
            let plain = shown.create_view(&Default::default());
            let mut er = self.egui_renderer.write();
            let id = match self.target.take() {
                Some(t) => {
                    er.update_egui_texture_from_wgpu_texture(&self.device, &plain, wgpu::FilterMode::Linear, t.id);
                    t.id
                }
                None => er.register_native_texture(&self.device, &plain, wgpu::FilterMode::Linear),
            };
            self.target = Some(ViewportTarget { shown, view, staging, id, size: (w, h) });
        }
        let Some(t) = self.target.as_ref() else { return Err(GuiError::Window("viewport texture missing".into())) };
        self.renderer.render_to_view(scene, camera, &t.view, w, h)?;
        if let Some(staging) = &t.staging {
            let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("viewport copy") });
            enc.copy_texture_to_texture(staging.as_image_copy(), t.shown.as_image_copy(), wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 });
            self.queue.submit([enc.finish()]);
        }
        let id = t.id;
        self.last_ms = t0.elapsed().as_secs_f32() * 1000.0;
        Ok(id)
    }
}

/// Frame timing shown in the windows: an exponential moving average of the time between frames.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameClock {
    last: Option<std::time::Instant>,
    /// Smoothed time between frames (ms).
    pub frame_ms: f32,
}

impl FrameClock {
    /// Records a new frame; returns the seconds since the previous one (0 on the first).
    pub fn tick(&mut self) -> f32 {
        let now = std::time::Instant::now();
        let dt = self.last.map_or(0.0, |l| (now - l).as_secs_f32());
        self.last = Some(now);
        if dt > 0.0 {
            let ms = dt * 1000.0;
            self.frame_ms = if self.frame_ms == 0.0 { ms } else { 0.9 * self.frame_ms + 0.1 * ms };
        }
        dt
    }
}

/// Paints the north arrow of [`crate::render::overlay::stamp_north_arrow`] over the 3-D
/// viewport `rect` seen by `camera`: a white disc in its lower-right corner with a compass
/// needle towards grid north ([`crate::render::overlay::north_on_screen`]: black north half,
/// white south half) and an "N" at the north tip (trial 43 defect 12). Nothing for a degenerate
/// camera.
pub fn paint_north_arrow(painter: &egui::Painter, rect: egui::Rect, camera: &Camera) {
    use crate::render::overlay::{north_arrow_centre, north_arrow_radius, north_on_screen};
    let Some(d) = north_on_screen(camera) else { return };
    let (w, h) = (rect.width().max(1.0) as u32, rect.height().max(1.0) as u32);
    let r = north_arrow_radius(w, h);
    let [cx, cy] = north_arrow_centre(w, h);
    let c = egui::pos2(rect.left() + cx, rect.top() + cy);
    // the screen's y runs down
    let dir = egui::vec2(d[0], -d[1]);
    let side = egui::vec2(-dir.y, dir.x) * 0.2 * r;
    let black = egui::Color32::from_gray(20);
    painter.circle(c, r, egui::Color32::from_white_alpha(204), egui::Stroke::new(1.5, black));
    painter.add(egui::Shape::convex_polygon(vec![c + dir * 0.5 * r, c + side, c - side], black, egui::Stroke::NONE));
    painter.add(egui::Shape::convex_polygon(vec![c - dir * 0.55 * r, c - side, c + side], egui::Color32::WHITE, egui::Stroke::new(1.0, black)));
    painter.text(c + dir * 0.7 * r, egui::Align2::CENTER_CENTER, "N", egui::FontId::proportional(0.36 * r), black);
}
