//! Render benchmark: frame time and triangles drawn for 1,000 / 10,000 / 100,000 / 300,000 tree
//! instances at 1920×1080 on whatever adapter wgpu finds: the high-performance adapter (a
//! discrete GPU) when there is one, else a software one (lavapipe on CI machines). The adapter's
//! name, type and backend are printed first; the same program runs unchanged on a GPU.
//!
//! Run: `cargo bench --bench render` (env `SYLVA_BENCH_FRAMES=N` overrides the frame count,
//! `SYLVA_BENCH_SIZE=WxH` the resolution, `SYLVA_BENCH_CULLING=cpu|gpu` runs one culling path
//! only, `SYLVA_BENCH_COUNTS=1000,10000` the instance counts, `SYLVA_BENCH_CANOPY=off` turns the
//! far-field canopy layer off for comparison). Prints, per culling path (CPU rayon pass with direct draws; GPU compute pass with
//! indirect draws), the median over the timed frames after one warm-up frame, and the triangles
//! the same trees would cost all at level 0.

use std::time::Instant;

use sylva::render::camera::{Camera, CameraPreset};
use sylva::render::headless::{Culling, Renderer};
use sylva::render::instanced::build_batches;
use sylva::render::lod::LodParams;
use sylva::render::scene::demo_scene;

fn main() {
    let mut r = match Renderer::new() {
        Ok(r) => r,
        Err(e) => {
            println!("render bench: {e}");
            return;
        }
    };
    let (w, h) = std::env::var("SYLVA_BENCH_SIZE")
        .ok()
        .and_then(|s| {
            let (a, b) = s.split_once('x')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((1920u32, 1080u32));
    let frames_override: Option<usize> = std::env::var("SYLVA_BENCH_FRAMES").ok().and_then(|s| s.parse().ok());
    println!("adapter: {}", r.adapter_description());
    println!(
        "adapter type: {} (60 fps goal for 100,000 trees applies to a discrete GPU{})",
        if r.is_software() { "software rasteriser on the CPU" } else { "hardware GPU" },
        if r.is_software() { "; not measurable here" } else { "" }
    );
    let counts: Vec<usize> = std::env::var("SYLVA_BENCH_COUNTS")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .filter(|v: &Vec<usize>| !v.is_empty())
        .unwrap_or_else(|| vec![1_000, 10_000, 100_000, 300_000]);
    println!("{w}x{h}, demo_scene on 2 km x 2 km, oblique camera, shadow map 2048^2, MSAA 4x");
    let only = std::env::var("SYLVA_BENCH_CULLING").ok().map(|s| s.to_ascii_lowercase());
    let mut paths = vec![Culling::Cpu];
    if r.gpu_culling_supported() {
        paths.push(Culling::Gpu);
    } else {
        println!("(adapter without compute/indirect support: GPU culling path skipped)");
    }
    paths.retain(|c| only.as_deref().map(|o| format!("{c:?}").to_ascii_lowercase() == o).unwrap_or(true));
    println!("{:>7} {:>9} {:>7} {:>11} {:>11} {:>13} {:>9} {:>22} {:>9} {:>9} {:>16}", "culling", "instances", "frames", "median ms", "fps", "tree tris", "draws", "L0/L1/L2/L3", "canopy", "far px", "tris if all L0");
    if std::env::var("SYLVA_BENCH_CANOPY").map(|v| v == "off").unwrap_or(false) {
        r.lod.canopy_px = 0.0;
        println!("canopy layer off");
    }
    for &culling in &paths {
    r.culling = culling;
    for &n in &counts {
        let scene = demo_scene(n, 2000.0, 11);
        let cam = Camera::preset(CameraPreset::Oblique, &scene.terrain);
        let frames = frames_override.unwrap_or(if n >= 100_000 { 10 } else { 20 });
        // warm-up (shader compilation, uploads)
        if let Err(e) = r.render(&scene, &cam, w, h) {
            println!("render failed: {e}");
            return;
        }
        let mut times = Vec::new();
        for _ in 0..frames {
            let t = Instant::now();
            let img = r.render(&scene, &cam, w, h);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            if img.is_err() {
                println!("render failed");
                return;
            }
        }
        times.sort_by(f64::total_cmp);
        let med = times[times.len() / 2];
        let s = r.last_stats();
        let all0 = LodParams { switch_px: [0.0; 3], band: 0.0, min_px: 0.0, max_triangles: 0, canopy_px: 0.0, max_geometry_triangles: 0, small_tree_m: 0.0, small_tree_floor_m: 0.0 };
        let full = build_batches(&scene, &cam, w, h, &all0).triangles;
        println!(
            "{:>7} {:>9} {:>7} {:>11.1} {:>11.1} {:>13} {:>9} {:>22} {:>9} {:>9.1} {:>16}",
            format!("{culling:?}"),
            n,
            frames,
            med,
            1000.0 / med,
            s.tree_triangles,
            s.tree_draws,
            format!("{}/{}/{}/{}", s.per_level[0], s.per_level[1], s.per_level[2], s.per_level[3]),
            s.canopy_trees,
            s.canopy_px,
            full
        );
    }
    }
}
