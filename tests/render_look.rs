//! Round 46 (issue 32 item 6, trial 45 defect 8): the pictures' haze, on
//! the adapter wgpu finds (lavapipe here and in CI). These tests FAIL without an adapter (they
//! measure the picture; a skip would pass a broken renderer).
//!
//! - Aerial perspective follows Koschmieder's law at the stated meteorological range
//!   (`METEOROLOGICAL_RANGE_M`, 40 km): the extinction measured from three distances of one
//!   uniform plain is that of the law, and the ground 5 km away keeps a contrast against the
//!   horizon sky that leaves the next ridge legible. On main (before round 46) the haze was
//!   `0.1 / terrain size` per metre whatever the air, capped at 85 %: the measured extinction
//!   was that of a 120 km range on this 12 km terrain (and 400 km on the default run's).

use glam::Vec3;
use sylva::render::camera::Camera;
use sylva::render::headless::Renderer;
use sylva::render::renderer::{aerosol_extinction, METEOROLOGICAL_RANGE_M, RAYLEIGH_RGB_PER_M};
use sylva::render::scene::{demo_scene, Scene, Sky, Sun, Wind};
use sylva::render::terrain::{from_grid, LandCover};

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("no adapter: the picture tests need one (lavapipe: apt install mesa-vulkan-drivers): {e}"))
}

/// A flat plain of `n` × `n` cells of `cell` m at z = 0, no trees, the sun high behind the camera.
fn plain(n: usize, cell: f32) -> Scene {
    let grid = sylva::grid::Grid::filled(n, n, 0.0f32);
    let terrain = from_grid(&grid, cell, cell, &LandCover::default(), None).unwrap();
    let mut s = demo_scene(0, 200.0, 1);
    s.set_terrain(terrain);
    s.instances.clear();
    // mid-July, 14:00, 47° N: the sun in the south-west, high
    s.sun = Sun::from_position(47.0, 196.0, 14.0);
    s.sky = Sky::default();
    s.wind = Wind::default();
    s
}

fn project(cam: &Camera, w: u32, h: u32, p: Vec3) -> (f32, f32) {
    let c = cam.view_proj(w as f32 / h as f32) * p.extend(1.0);
    let ndc = c.truncate() / c.w;
    ((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32)
}

fn srgb_to_linear(v: u8) -> f64 {
    let c = v as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Mean linear value of channel `ch` over a 7 × 1 window at (x, y) (one row: the plain's
/// distance changes fast from row to row near the horizon).
fn mean_linear(img: &image::RgbaImage, x: f32, y: f32, ch: usize) -> f64 {
    let (cx, cy) = (x.round() as i64, y.round() as i64);
    let mut s = 0.0;
    let mut n = 0.0;
    for dy in 0..=0 {
        for dx in -3..=3 {
            let (px, py) = (cx + dx, cy + dy);
            if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                s += srgb_to_linear(img.get_pixel(px as u32, py as u32).0[ch]);
                n += 1.0;
            }
        }
    }
    s / n
}

/// The extinction β (1/m) for which L(d) = L_h + A e^(−βd) passes through the three
/// (distance, value) points: (L2 − L1) / (L1 − L0) = (e^(−βd2) − e^(−βd1)) / (e^(−βd1) − e^(−βd0)),
/// solved by bisection (the right side falls monotonically with β for d0 < d1 < d2).
fn fitted_extinction(d: [f64; 3], l: [f64; 3]) -> f64 {
    let want = (l[2] - l[1]) / (l[1] - l[0]);
    let ratio = |b: f64| ((-b * d[2]).exp() - (-b * d[1]).exp()) / ((-b * d[1]).exp() - (-b * d[0]).exp());
    let (mut lo, mut hi) = (1e-9f64, 1e-2f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if ratio(mid) > want {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

/// Koschmieder's law on a uniform 12 km plain seen from 2 km up (as an oblique still looks):
/// the plain's red, green and blue at three distances (2.2, 4.9 and 9.2 km) give the
/// extinction the picture applies per colour; each is the aerosol's (3.912 / V less the
/// Rayleigh part at 550 nm, V = 40 km the default meteorological range) plus that colour's
/// Rayleigh part within 15 % (green: Koschmieder's 3.912 / V whole), blue's larger than red's (distant ground turns blue), and the ground at 4.9 km
/// keeps over 35 % of the contrast against its horizon sky that it has at no distance: the
/// next ridge legible. Before round 46 the fitted green extinction was 0.1 / 12 km = 8.3e-6
/// per metre against the 9.8e-5 of the law (the test fails there).
#[test]
fn haze_follows_koschmieder_at_the_stated_visibility() {
    assert_eq!(METEOROLOGICAL_RANGE_M, 40_000.0);
    let want_green = 3.912 / METEOROLOGICAL_RANGE_M as f64;
    assert!((aerosol_extinction(METEOROLOGICAL_RANGE_M) as f64 + RAYLEIGH_RGB_PER_M[1] as f64 - want_green).abs() < 1e-9);
    assert_eq!(aerosol_extinction(f32::INFINITY), 0.0);
    assert_eq!(aerosol_extinction(0.0), 0.0);
    let mut r = renderer();
    assert_eq!(r.visibility_m, METEOROLOGICAL_RANGE_M);
    let (n, cell) = (49usize, 250.0f32);
    let mut scene = plain(n, cell);
    // no direct sun: the ground lit by the sky alone, dark against the horizon sky, so that the
    // haze's share is measured with a wide margin over the 8-bit steps
    scene.sun.color = [0.0; 3];
    let (w, h) = (640u32, 640u32);
    let eye = Vec3::new(6000.0, 0.0, 2000.0);
    let cam = Camera::look_at(eye.to_array(), [6000.0, 4000.0, 0.0], 90.0);
    let img = r.render(&scene, &cam, w, h).unwrap();
    let _ = img.save(std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("haze_plain.png"));
    let ys = [1000.0f32, 4500.0, 9000.0];
    let pts: Vec<Vec3> = ys.iter().map(|&y| Vec3::new(6000.0, y, 0.0)).collect();
    let d: Vec<f64> = pts.iter().map(|p| (*p - eye).length() as f64).collect();
    let px: Vec<(f32, f32)> = pts.iter().map(|p| project(&cam, w, h, *p)).collect();
    let mut beta = [0.0f64; 3];
    for ch in 0..3 {
        let l: Vec<f64> = px.iter().map(|&(x, y)| mean_linear(&img, x, y, ch)).collect();
        beta[ch] = fitted_extinction([d[0], d[1], d[2]], [l[0], l[1], l[2]]);
        eprintln!("channel {ch}: values {l:?} at {d:?} m (pixels {px:?}): fitted extinction {:.3e} /m", beta[ch]);
    }
    // per channel: the aerosol's grey extinction plus the Rayleigh part of that colour
    let mie = aerosol_extinction(METEOROLOGICAL_RANGE_M) as f64;
    for ch in 0..3 {
        let want = mie + RAYLEIGH_RGB_PER_M[ch] as f64;
        assert!((beta[ch] / want - 1.0).abs() < 0.15, "channel {ch}: extinction {:.3e} /m against {want:.3e} (green: Koschmieder's 3.912 / 40 km = {want_green:.3e})", beta[ch]);
    }
    assert!(beta[2] > beta[0], "blue extinction {:.3e} not above red {:.3e}", beta[2], beta[0]);
    // the contrast kept at the middle distance: e^(−β d1) in green
    let kept = (-beta[1] * d[1]).exp();
    assert!(kept > 0.35, "the ground {:.0} m away keeps {kept:.2} of its contrast", d[1]);
}

/// Not a check: a tool that draws a run's year-150 close-up and oblique (960 × 540, summer,
/// the shipped species library, as `sylva render --camera closeup|oblique` draws them but
/// without the run's own `species/` folder, whose colours may predate round 46) for looking at
/// them, with this build's renderer. `SYLVA_LOOK_RUN` the run directory, `SYLVA_LOOK_OUT` the
/// folder written (`oblique.png`, `closeup.png`). Round 46 drew `docs/gallery/*_r46.png` so.
#[test]
#[ignore = "a tool, not a check: needs SYLVA_LOOK_RUN and SYLVA_LOOK_OUT (see its doc comment)"]
fn draw_run_pictures_for_inspection() {
    use sylva::render::camera::CameraPreset;
    let run = std::path::PathBuf::from(std::env::var("SYLVA_LOOK_RUN").expect("SYLVA_LOOK_RUN: a run directory"));
    let out = std::path::PathBuf::from(std::env::var("SYLVA_LOOK_OUT").expect("SYLVA_LOOK_OUT: a folder"));
    std::fs::create_dir_all(&out).unwrap();
    let sc = sylva::sim::Scenario::load(&run.join("scenario.toml")).unwrap();
    let site = sc.site().unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let mut stage = sylva::job::pictures::Stage::for_scenario(&sc, site, lib).unwrap();
    let year = 150;
    let rows = sylva::job::pictures::snapshot_rows(&run, year).unwrap();
    let plants = sylva::job::scene::plants_from_rows(&rows);
    let regen = sylva::job::inventory::read_regeneration(&run, year).unwrap().unwrap_or_default();
    let (w, h) = (960u32, 540u32);
    let which: Vec<String> = std::env::var("SYLVA_LOOK_CAMERAS").map(|s| s.split(',').map(String::from).collect()).unwrap_or_else(|_| vec!["oblique".into(), "closeup".into()]);
    for name in which {
        let closeup = name == "closeup";
        let cam = if closeup { sylva::job::main_job::closeup_camera(&stage.site) } else { stage.camera_for(CameraPreset::Oblique, &rows, w, h) };
        let saplings = if closeup { Vec::new() } else { sylva::job::scene::saplings_from_rows(&regen) };
        let t = std::time::Instant::now();
        let mut img = stage.render_plants_with(&plants, &saplings, sylva::species::Season::Summer, &cam, w, h).unwrap();
        sylva::render::overlay::stamp_north_arrow(&mut img, &cam);
        img.save(out.join(format!("{name}.png"))).unwrap();
        eprintln!("{name}: {:.1} s", t.elapsed().as_secs_f64());
    }
}
