//! The renderer draws into any texture view (issue 13): a renderer built with
//! `Renderer::from_device` on a device the caller owns (as a window would) draws with
//! `render_to_view` into the caller's texture, in the caller's format, and gives the picture the
//! headless `Renderer::render` gives. Without an adapter the test prints a note and passes,
//! unless `SYLVA_REQUIRE_ADAPTER` is set.

use sylva::render::camera::{Camera, CameraPreset};
use sylva::render::headless::{Culling, Renderer};
use sylva::render::scene::demo_scene;

/// A device and queue of our own, as a window's code would create them.
fn own_device() -> Option<(wgpu::Device, wgpu::Queue)> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .or_else(|_| pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions { force_fallback_adapter: true, ..Default::default() })));
    let adapter = match adapter {
        Ok(a) => a,
        Err(e) => {
            assert!(std::env::var_os("SYLVA_REQUIRE_ADAPTER").is_none(), "SYLVA_REQUIRE_ADAPTER is set but no adapter was found: {e}");
            eprintln!("skipping: {e}");
            return None;
        }
    };
    let limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
    Some(pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor { label: Some("test"), required_limits: limits, ..Default::default() })).unwrap())
}

/// Draws into a texture of `format` and reads it back as RGBA bytes (BGRA swapped).
fn draw_into_texture(device: &wgpu::Device, queue: &wgpu::Queue, r: &mut Renderer, format: wgpu::TextureFormat, w: u32, h: u32) -> image::RgbaImage {
    let scene = demo_scene(200, 300.0, 5);
    let cam = Camera::preset(CameraPreset::Oblique, &scene.terrain);
    let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
    let tex = device.create_texture(&wgpu::TextureDescriptor { label: Some("target"), size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format, usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC, view_formats: &[] });
    let view = tex.create_view(&Default::default());
    let stats = r.render_to_view(&scene, &cam, &view, w, h).unwrap();
    assert!(stats.instances_drawn > 0, "{stats:?}");
    let row = (w * 4).div_ceil(256) * 256;
    let buf = device.create_buffer(&wgpu::BufferDescriptor { label: Some("rb"), size: row as u64 * h as u64, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture: &tex, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
        wgpu::TexelCopyBufferInfo { buffer: &buf, layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) } },
        size,
    );
    let sub = queue.submit(Some(enc.finish()));
    buf.slice(..).map_async(wgpu::MapMode::Read, |r| r.unwrap());
    device.poll(wgpu::PollType::Wait { submission_index: Some(sub), timeout: None }).unwrap();
    let data = buf.slice(..).get_mapped_range().unwrap();
    let bgra = format == wgpu::TextureFormat::Bgra8UnormSrgb;
    image::RgbaImage::from_fn(w, h, |x, y| {
        let o = (y * row + x * 4) as usize;
        let p = &data[o..o + 4];
        image::Rgba(if bgra { [p[2], p[1], p[0], p[3]] } else { [p[0], p[1], p[2], p[3]] })
    })
}

fn mean_abs_diff(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.as_raw().iter().zip(b.as_raw()).map(|(x, y)| (*x as i32 - *y as i32).abs() as f64).sum::<f64>() / a.as_raw().len() as f64
}

#[test]
fn from_device_draws_into_the_callers_view_in_its_format() {
    let Some((device, queue)) = own_device() else { return };
    let (w, h) = (160, 120);
    // the headless path for reference
    let mut headless = Renderer::new().unwrap();
    headless.culling = Culling::Cpu;
    let scene = demo_scene(200, 300.0, 5);
    let cam = Camera::preset(CameraPreset::Oblique, &scene.terrain);
    let want = headless.render(&scene, &cam, w, h).unwrap();

    for format in [wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::TextureFormat::Bgra8UnormSrgb] {
        let mut r = Renderer::from_device(device.clone(), queue.clone(), format).unwrap();
        assert_eq!(r.target_format(), format);
        r.culling = Culling::Cpu;
        let got = draw_into_texture(&device, &queue, &mut r, format, w, h);
        let d = mean_abs_diff(&got, &want);
        assert!(d < 0.5, "{format:?}: mean abs difference {d} from the headless image");
        // a second frame into the same view reuses the uploaded terrain and prototypes
        let again = draw_into_texture(&device, &queue, &mut r, format, w, h);
        assert!(mean_abs_diff(&again, &got) < 0.5);
        if format != wgpu::TextureFormat::Rgba8UnormSrgb {
            let e = r.render(&scene, &cam, w, h).unwrap_err().to_string();
            assert!(e.contains("target format") && e.contains("render_to_view"), "{e}");
        }
    }
}

#[test]
/// Explicit change tracking ([`Scene::terrain_changed`], `set_*`): an unchanged version uploads
/// nothing, so this fails if the renderer uploaded every frame.
fn terrain_and_prototypes_are_uploaded_once_and_again_only_when_they_change() {
    let Some((device, queue)) = own_device() else { return };
    let mut r = Renderer::from_device(device.clone(), queue.clone(), wgpu::TextureFormat::Rgba8UnormSrgb).unwrap();
    r.culling = Culling::Cpu;
    let size = wgpu::Extent3d { width: 64, height: 48, depth_or_array_layers: 1 };
    let tex = device.create_texture(&wgpu::TextureDescriptor { label: None, size, mip_level_count: 1, sample_count: 1, dimension: wgpu::TextureDimension::D2, format: wgpu::TextureFormat::Rgba8UnormSrgb, usage: wgpu::TextureUsages::RENDER_ATTACHMENT, view_formats: &[] });
    let view = tex.create_view(&Default::default());
    let mut scene = demo_scene(50, 200.0, 3);
    let cam = Camera::preset(CameraPreset::Oblique, &scene.terrain);
    let mut frame = |scene: &sylva::render::scene::Scene| {
        let s = r.render_to_view(scene, &cam, &view, 64, 48).unwrap();
        (s.uploaded_terrain, s.uploaded_prototypes)
    };
    assert_eq!(frame(&scene), (true, true), "first frame uploads both");
    assert_eq!(frame(&scene), (false, false));
    scene.instances.truncate(10);
    scene.instances[0].height *= 1.5;
    assert_eq!(frame(&scene), (false, false), "new instances upload neither");
    scene.terrain.colors[0] = [1.0, 0.0, 0.0];
    scene.terrain_changed();
    assert_eq!(frame(&scene), (true, false), "a changed terrain uploads the terrain only");
    assert_eq!(frame(&scene), (false, false), "and only once");
    let mesh = scene.prototypes[0].lods.levels.iter_mut().flat_map(|l| [&mut l.bark, &mut l.leaves]).find(|m| !m.positions.is_empty()).expect("a prototype mesh");
    mesh.positions[0][2] += 0.1;
    scene.prototypes_changed();
    assert_eq!(frame(&scene), (false, true), "changed prototypes upload the prototypes only");
    assert_eq!(frame(&scene), (false, false), "and only once");
    scene.set_sea_level(Some(1.0));
    assert_eq!(frame(&scene), (true, false), "the sea level belongs to the terrain part");
    let protos = scene.prototypes.clone();
    scene.set_prototypes(protos);
    assert_eq!(frame(&scene), (false, true), "replaced prototypes are uploaded");
    // a clone shares the versions (same content: nothing to upload); another scene does not
    let twin = scene.clone();
    assert_eq!(frame(&twin), (false, false), "a clone of the drawn scene uploads nothing");
    let other = demo_scene(50, 200.0, 3);
    assert_eq!(frame(&other), (true, true), "another scene uploads both");
}
