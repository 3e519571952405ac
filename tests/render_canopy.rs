//! Far-field canopy layer: triangles per frame level off as the tree count grows, and the far
//! forest still reads as forest (not bare terrain).
//!
//! Runs on whatever adapter wgpu finds (lavapipe in CI). Without an adapter the tests print a
//! note and pass, unless `SYLVA_REQUIRE_ADAPTER` is set, in which case they fail (as in
//! `tests/render.rs`).


use sylva::render::camera::{Camera, CameraPreset};
use sylva::render::headless::{Culling, FrameStats, Renderer};
use sylva::render::lod::LodParams;
use sylva::render::scene::{demo_scene, Scene};

#[path = "common/render.rs"]
mod render_common;
use render_common::{out_dir, with_renderer};

fn paths(r: &Renderer) -> Vec<Culling> {
    if r.gpu_culling_supported() {
        vec![Culling::Cpu, Culling::Gpu]
    } else {
        vec![Culling::Cpu]
    }
}

fn render(r: &mut Renderer, culling: Culling, lod: LodParams, scene: &Scene, cam: &Camera, w: u32, h: u32) -> (image::RgbaImage, FrameStats) {
    r.culling = culling;
    r.lod = lod;
    let img = r.render(scene, cam, w, h).unwrap();
    let s = r.last_stats();
    r.culling = Culling::Auto;
    r.lod = LodParams::default();
    (img, s)
}

#[test]
fn triangles_level_off_when_the_same_area_holds_four_times_the_trees() {
    // 2 km × 2 km, oblique preset, default levels: 8,000 and 32,000 trees. Without the canopy
    // layer every visible tree costs ≥ 4 triangles, so the 4× scene costs ~4× the triangles;
    // with it the far trees cost none and the far-field switch rises until the geometry fits
    // its budget. The frame is small (320 × 180), so the budget is lowered with it (1,000
    // triangles instead of 100,000 at 1080p).
    let (w, h) = (320, 180);
    let small = demo_scene(8_000, 2000.0, 11);
    let big = demo_scene(32_000, 2000.0, 11);
    let cam = Camera::preset(CameraPreset::Oblique, &small.terrain);
    let lod = LodParams { max_geometry_triangles: 1_000, ..LodParams::default() };
    let off = LodParams { canopy_px: 0.0, max_geometry_triangles: 0, ..lod };
    with_renderer(|r| {
        for c in paths(r) {
            let (_, s1) = render(r, c, lod, &small, &cam, w, h);
            let (_, s4) = render(r, c, lod, &big, &cam, w, h);
            let (_, o1) = render(r, c, off, &small, &cam, w, h);
            let (_, o4) = render(r, c, off, &big, &cam, w, h);
            eprintln!("{c:?}: canopy on {s1:?}\n  {s4:?}\n  off {o1:?}\n  {o4:?}");
            // without the layer: linear in the tree count (more than 3.5×)
            assert!(o4.tree_triangles as f64 > 3.5 * o1.tree_triangles as f64, "{c:?}: {} vs {}", o4.tree_triangles, o1.tree_triangles);
            // with it: far less than 4× (the cap binds for the big scene), and far below the
            // layer-less cost
            let ratio = s4.tree_triangles as f64 / s1.tree_triangles as f64;
            assert!(ratio < 1.5, "{c:?}: {} vs {} triangles (×{ratio:.2})", s4.tree_triangles, s1.tree_triangles);
            assert!(s4.tree_triangles * 3 < o4.tree_triangles, "{c:?}: {} vs {}", s4.tree_triangles, o4.tree_triangles);
            // within the budget (it is estimated at the histogram bins' centre sizes)
            assert!(s4.tree_triangles <= (lod.max_geometry_triangles as f64 * 1.25) as u64, "{c:?}: {}", s4.tree_triangles);
            assert!(s1.tree_triangles <= (lod.max_geometry_triangles as f64 * 1.25) as u64, "{c:?}: {}", s1.tree_triangles);
            assert!(s4.canopy_trees > 20_000 && s4.canopy_px > lod.canopy_px, "{c:?}: {s4:?}");
            // every visible tree is in the geometry or the layer
            assert!(s4.canopy_trees + s4.instances_drawn + s4.culled == 32_000, "{c:?}: {s4:?}");
        }
    });
}

/// Mean colour of the block `(bx, by)` (8 × 8 px).
fn block_mean(img: &image::RgbaImage, bx: u32, by: u32) -> [f64; 3] {
    let mut m = [0.0; 3];
    for y in by * 8..by * 8 + 8 {
        for x in bx * 8..bx * 8 + 8 {
            let p = img.get_pixel(x, y).0;
            for k in 0..3 {
                m[k] += p[k] as f64 / 64.0;
            }
        }
    }
    m
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn far_forest_stays_forest_coloured_in_the_canopy_layer() {
    // The same 24,000-tree scene three ways: all trees as geometry (layer off), with the
    // canopy layer, and bare terrain. Where the geometry forest differs clearly from bare
    // ground, the canopy rendering must be much closer to the forest than to the ground, on
    // both culling paths, and the two paths must agree.
    let (w, h) = (320, 184);
    let scene = demo_scene(24_000, 2000.0, 5);
    let mut bare = scene.clone();
    bare.instances.clear();
    let cam = Camera::preset(CameraPreset::Oblique, &scene.terrain);
    let off = LodParams { canopy_px: 0.0, max_geometry_triangles: 0, ..LodParams::default() };
    // a far switch at 24 px: most of the forest is in the layer
    let on = LodParams { canopy_px: 24.0, max_geometry_triangles: 0, ..LodParams::default() };
    with_renderer(|r| {
        let (geo, _) = render(r, Culling::Cpu, off, &scene, &cam, w, h);
        let (ground, _) = render(r, Culling::Cpu, off, &bare, &cam, w, h);
        geo.save(out_dir().join("canopy_off.png")).unwrap();
        ground.save(out_dir().join("canopy_bare.png")).unwrap();
        let mut imgs = Vec::new();
        for c in paths(r) {
            let (img, s) = render(r, c, on, &scene, &cam, w, h);
            img.save(out_dir().join(format!("canopy_{c:?}.png"))).unwrap();
            assert!(s.canopy_trees > 12_000, "{c:?}: {s:?}");
            let (mut n, mut good) = (0, 0);
            let (mut dc, mut dg) = (0.0, 0.0);
            for by in 0..h / 8 {
                for bx in 0..w / 8 {
                    let (f, g, k) = (block_mean(&geo, bx, by), block_mean(&ground, bx, by), block_mean(&img, bx, by));
                    if dist(f, g) < 20.0 {
                        continue;
                    }
                    n += 1;
                    dc += dist(k, f);
                    dg += dist(k, g);
                    if dist(k, f) < dist(k, g) {
                        good += 1;
                    }
                }
            }
            eprintln!("{c:?}: {good}/{n} forest blocks closer to the forest; mean distance to forest {:.1}, to ground {:.1}", dc / n as f64, dg / n as f64);
            assert!(n > 200, "too few forest blocks: {n}");
            assert!(good as f64 > 0.85 * n as f64, "{c:?}: {good}/{n}");
            assert!(dc < 0.5 * dg, "{c:?}: {dc} vs {dg}");
            imgs.push(img);
        }
        if imgs.len() == 2 {
            let s: u64 = imgs[0].as_raw().iter().zip(imgs[1].as_raw()).map(|(x, y)| (*x as i32 - *y as i32).unsigned_abs() as u64).sum();
            let d = s as f64 / imgs[0].as_raw().len() as f64;
            assert!(d < 1.0, "CPU and GPU canopy images differ by {d}");
        }
    });
}

/// The far forest beyond a simulated window (`job::scene::FarForest`) is drawn by the terrain
/// shader as crowns: looking steeply down (about 70°) on the surroundings from 120 m above them, the far-forest mesh
/// shows darker, greener ground with a crown pattern (lit domes and gaps: a spread of pixel
/// brightness several times that of plain meadow), while the same view of the plain mesh shows
/// meadow.
#[test]
fn far_forest_beyond_the_window_is_drawn_as_crowns() {
    use sylva::job::scene::{canopy_cover, FarForest};
    use sylva::render::scene::TreeInstance;
    use sylva::render::terrain::{from_ground, GroundGrid, LandCover};
    let n = 100;
    let g = GroundGrid {
        heights: sylva::grid::Grid { width: n, height: n, data: vec![300.0; n * n] },
        cell_x: 10.0,
        cell_y: 10.0,
        origin: [0.0, 0.0],
        stream: vec![],
        wetness: vec![],
        fade: vec![],
        focus: Some(([300.0, 300.0], [700.0, 700.0])),
    };
    // a closed window stand of one species (crowns 4.5 m wide every 8 m, 25 m tall)
    let mut trees = Vec::new();
    for j in 0..50 {
        for i in 0..50 {
            trees.push(TreeInstance::new((j * 50 + i + 1) as u64, [304.0 + 8.0 * i as f32, 304.0 + 8.0 * j as f32, 300.0], 25.0, 4.5, 0, [0.09, 0.2, 0.03]));
        }
    }
    let cover = LandCover::default();
    let plain = from_ground(&g, &cover, &|_, _| 0.0).unwrap();
    let far = FarForest::of(&trees, &g, &canopy_cover(&trees, &g)).expect("a stocked window");
    let mut forest = plain.clone();
    far.apply(&mut forest, &g, &cover);
    assert!(forest.forest.iter().filter(|&&f| f > 0.5).count() > n * n / 2);
    // steeply down on the surroundings, 150 m south-west of the window
    let cam = Camera::look_at([150.0, 100.0, 300.0 + 25.0 + 120.0], [150.0, 150.0, 300.0], 40.0);
    let stats = |img: &image::RgbaImage| {
        let px: Vec<[f64; 3]> = img.pixels().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
        let k = px.len() as f64;
        let mean = px.iter().fold([0.0; 3], |m, p| [m[0] + p[0] / k, m[1] + p[1] / k, m[2] + p[2] / k]);
        let lum: Vec<f64> = px.iter().map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]).collect();
        let lm = lum.iter().sum::<f64>() / k;
        let sd = (lum.iter().map(|l| (l - lm) * (l - lm)).sum::<f64>() / k).sqrt();
        (mean, lm, sd)
    };
    with_renderer(|r| {
        let mut scene = demo_scene(0, 1000.0, 3);
        scene.set_terrain(plain.clone());
        let meadow = r.render(&scene, &cam, 256, 256).unwrap();
        scene.set_terrain(forest.clone());
        let crowns = r.render(&scene, &cam, 256, 256).unwrap();
        let _ = crowns.save(out_dir().join("far_forest_crowns.png"));
        let (mm, ml, msd) = stats(&meadow);
        let (fm, fl, fsd) = stats(&crowns);
        eprintln!("meadow mean {mm:?} lum {ml:.1} sd {msd:.2}; far forest mean {fm:?} lum {fl:.1} sd {fsd:.2}");
        // forest canopy: darker than sunlit meadow, green dominant, and textured by crowns
        assert!(fl < ml, "far forest luminance {fl:.1} vs meadow {ml:.1}");
        assert!(fm[1] > fm[0] && fm[1] > fm[2], "green canopy {fm:?}");
        assert!(fsd > 3.0 * msd.max(1.0), "crown pattern: brightness spread {fsd:.2} vs meadow {msd:.2}");
    });
}
