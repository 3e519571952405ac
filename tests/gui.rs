//! The two windows (issue 15): `sylva view` and `sylva edit`, driven without a window through
//! egui_kittest (year slider, clicking a tree; dragging a curve point, undo, redo, save), and
//! started for real under a virtual X display (Xvfb) on the software adapter, each writing a
//! `--screenshot` that must show the landscape or the tree. Without a display they fail with a
//! clear message, not a panic.
//!
//! The Xvfb tests print a note and pass when `Xvfb` is not installed, unless
//! `SYLVA_REQUIRE_XVFB` is set (CI sets it and installs xvfb).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use eframe::egui;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use sylva::edit::{doc::SpeciesDoc, Editor};
use sylva::view::data::RunData;
use sylva::view::Viewer;

const SCENARIO: &str = r#"name = "gui test"
years = 10
seed = 3
snapshot_every = 5
checkpoint_every = 0
species = ["beech", "silver_birch"]

[terrain]
generate = { size = 24, cell_m = 10.0, relief_m = 40.0, seed = 2 }

[[start]]
kind = "planted"
species = "beech"
spacing_m = 10.0
age_yr = 25.0
area = [20, 20, 220, 220]

[[start]]
kind = "planted"
species = "silver_birch"
spacing_m = 14.0
age_yr = 15.0
area = [40, 30, 200, 120]
"#;

/// A small run directory (24 × 24 cells of 10 m, 10 years, snapshots at 0, 5, 10), made once.
fn run_dir() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("s.toml"), SCENARIO).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "s.toml", "--out", "run"]).current_dir(d.path()).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        d
    })
    .path()
}

fn run_data() -> RunData {
    let run = run_dir().join("run");
    let sc = sylva::sim::Scenario::load(&run.join("scenario.toml")).unwrap();
    let site = sc.site().unwrap();
    let mut lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    lib.overlay_dir(&run.join("species")).unwrap();
    RunData::open(&run, site, lib, sc.species.clone()).unwrap()
}

#[test]
fn viewer_year_slider_moves_the_trees_and_a_click_selects_a_tree() {
    let viewer = Viewer::new(run_data(), 0.0, None).unwrap();
    assert_eq!(viewer.data.years, vec![0, 5, 10]);
    let mut h = Harness::builder().with_size(egui::vec2(1400.0, 900.0)).build_ui_state(|ui, v: &mut Viewer| v.ui(ui), viewer);
    h.run();
    assert_eq!(h.state().year, 10.0, "opens at the last snapshot");
    // (the trees standing at year 10, by id: since round 46's site suitability some of the
    // planted beech die of stress on this generated relief before year 10, so the sum over all
    // trees is no measure of growth; the survivors' is)
    let at_10: std::collections::HashMap<u64, f32> = h.state().trees().iter().map(|t| (t.id, t.height)).collect();
    // move the year slider to 2.5: half way between the snapshots of years 0 and 5
    h.get_by_role_and_label(egui::Role::Slider, "Year").set_value_accesskit(2.5);
    h.run();
    assert!((h.state().year - 2.5).abs() < 1e-3, "{}", h.state().year);
    let both: Vec<(f32, f32)> = h.state().trees().iter().filter_map(|t| at_10.get(&t.id).map(|&h10| (t.height, h10))).collect();
    assert!(both.len() > 100, "{} trees at both years", both.len());
    let (tall_2, tall_10): (f32, f32) = both.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    assert!(tall_2 < tall_10, "the survivors are shorter at year 2.5 ({tall_2}) than at 10 ({tall_10})");
    // interpolated: every planted tree's height lies between its heights at years 0 and 5
    let mut d = run_data();
    let (a, b) = (d.instances_at(0.0, sylva::species::Season::Summer).unwrap(), d.instances_at(5.0, sylva::species::Season::Summer).unwrap());
    let t = h.state().trees().iter().find(|t| a.iter().any(|x| x.id == t.id) && b.iter().any(|x| x.id == t.id)).unwrap();
    let (ha, hb) = (a.iter().find(|x| x.id == t.id).unwrap().height, b.iter().find(|x| x.id == t.id).unwrap().height);
    assert!((t.height - 0.5 * (ha + hb)).abs() < 1e-3, "{} vs {ha}..{hb}", t.height);
    // click the tallest tree whose crown centre is on screen
    let target = {
        let v = h.state();
        let r = egui::Rect::from_min_size(egui::pos2(0.0, 40.0), egui::vec2(1000.0, 820.0));
        let mut ts: Vec<_> = v.trees().iter().filter(|t| v.screen_pos_of(t.id).is_some_and(|p| r.contains(p))).collect();
        ts.sort_by(|a, b| b.height.total_cmp(&a.height));
        ts[0].id
    };
    let pos = h.state().screen_pos_of(target).unwrap();
    h.hover_at(pos);
    h.run();
    h.drag_at(pos);
    h.run();
    h.drop_at(pos);
    h.run();
    let v = h.state();
    let sel = v.selected.expect("a tree is selected");
    let info = v.info.as_ref().expect("its data are shown");
    assert_eq!(info.row.id, sel);
    assert!(["beech", "silver_birch"].contains(&info.row.species.as_str()));
    assert!(info.row.dbh_cm > 0.0 && info.row.height_m > 1.0);
    assert!(info.fate.starts_with("alive"), "{}", info.fate);
    // the side panel names what was clicked
    h.get_by_label_contains("DBH");
    h.get_by_label(&format!("{:.1} cm", info.row.dbh_cm));
}

#[test]
fn viewer_overlays_recolour_the_terrain() {
    let mut v = Viewer::new(run_data(), 0.0, None).unwrap();
    v.refresh();
    let names: Vec<String> = v.overlays().into_iter().map(|o| o.1).collect();
    assert!(names.iter().any(|n| n.contains("Ellenberg-style F")) && names.iter().any(|n| n.contains("basal area")), "{names:?}");
    for (o, _) in v.overlays() {
        v.overlay = o;
        v.refresh();
    }
    assert!(v.status.is_none(), "{:?}", v.status);
}

#[test]
fn viewer_tree_info_tells_the_cause_of_death_or_that_it_went_unrecorded() {
    // a run directory of three snapshots made by hand on the test run's site
    let d = tempfile::tempdir().unwrap();
    let run = d.path();
    std::fs::create_dir_all(run.join("inventory")).unwrap();
    std::fs::copy(run_dir().join("run/scenario.toml"), run.join("scenario.toml")).unwrap();
    let head = "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status\n";
    let row = |id: u64, age: f32, h: f32, status: &str| format!("{id},beech,50.0,60.0,0.0,{age},{h},{},2.0,{},{status}\n", h * 1.5, h * 0.4);
    std::fs::write(run.join("inventory/year_0000.csv"), format!("{head}{}{}", row(1, 20.0, 10.0, "alive"), row(2, 30.0, 15.0, "alive"))).unwrap();
    std::fs::write(run.join("inventory/year_0005.csv"), format!("{head}{}{}", row(1, 25.0, 11.0, "dead:stress"), row(2, 35.0, 16.0, "alive"))).unwrap();
    std::fs::write(run.join("inventory/year_0010.csv"), head).unwrap();
    let sc = sylva::sim::Scenario::load(&run.join("scenario.toml")).unwrap();
    let mut data = RunData::open(run, sc.site().unwrap(), sylva::species::SpeciesLibrary::embedded().unwrap(), vec!["beech".into()]).unwrap();
    let one = data.tree_info(1, 0.0).unwrap().unwrap();
    assert_eq!(one.year, 0);
    assert_eq!(one.row.height_m, 10.0);
    assert_eq!(one.fate, "alive at year 0; dead: stress (year 5)");
    let two = data.tree_info(2, 6.0).unwrap().unwrap();
    assert_eq!((two.year, two.row.age_yr), (5, 35.0), "shown from the snapshot at or before the year");
    assert_eq!(two.fate, "alive at year 5; gone by year 10 (cause not recorded between snapshots)");
    assert!(data.tree_info(3, 0.0).unwrap().is_none());
    // the dead tree fades out between its last snapshots and is gone at year 10
    let at = |d: &mut RunData, y: f32| d.instances_at(y, sylva::species::Season::Summer).unwrap();
    assert_eq!(at(&mut data, 0.0).len(), 2);
    let mid = at(&mut data, 7.5);
    assert_eq!(mid.len(), 1);
    assert!((mid[0].opacity - 0.5).abs() < 1e-4, "fading out: {}", mid[0].opacity);
    assert!(at(&mut data, 10.0).is_empty());
}

fn editor_in(dir: &Path) -> (Editor, PathBuf) {
    let p = dir.join("beech.toml");
    std::fs::write(&p, sylva::species::embedded_text("beech").unwrap()).unwrap();
    let doc = SpeciesDoc::open(&p).unwrap();
    (Editor::new(doc, dir.to_path_buf(), None), p)
}

#[test]
fn editor_drag_a_curve_point_undo_redo_and_save_keeps_comments() {
    let dir = tempfile::tempdir().unwrap();
    let (ed, path) = editor_in(dir.path());
    let field = "architecture.ecomod.ks_g";
    let before = ed.doc.polyline(field).unwrap();
    // 60 steps a second, so that two clicks one step apart make a double-click
    let mut h = Harness::builder().with_size(egui::vec2(1500.0, 4200.0)).with_step_dt(1.0 / 60.0).with_max_steps(120).build_ui_state(|ui, e: &mut Editor| e.ui(ui), ed);
    h.run();
    let c = h.get_by_label(&sylva::edit::curve::point_label(field, 0)).rect().center();
    h.hover_at(c);
    h.run();
    h.drag_at(c);
    h.run();
    for k in 1..=4 {
        h.hover_at(c + egui::vec2(0.0, -8.0 * k as f32));
        h.run();
    }
    h.drop_at(c + egui::vec2(0.0, -32.0));
    h.run();
    let dragged = h.state().doc.polyline(field).unwrap();
    assert_eq!(dragged.len(), before.len());
    assert_eq!(dragged[0][0], before[0][0], "the first point's order stays");
    assert!(dragged[0][1] > before[0][1] + 0.05, "dragged up: {:?} → {:?}", before, dragged);
    assert_eq!(dragged[1], before[1]);
    // one undo step for the whole drag
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run();
    assert_eq!(h.state().doc.polyline(field).unwrap(), before);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Y);
    h.run();
    assert_eq!(h.state().doc.polyline(field).unwrap(), dragged);
    // save through the button
    h.get_by_label("Save").click();
    h.run();
    let text = std::fs::read_to_string(&path).unwrap();
    let orig = sylva::species::embedded_text("beech").unwrap();
    let comments = |s: &str| s.lines().filter(|l| l.trim_start().starts_with('#')).map(str::to_string).collect::<Vec<_>>();
    assert_eq!(comments(&text), comments(orig), "every comment kept, in order");
    let sp = sylva::species::Species::from_toml_str(&text, "beech.toml").unwrap();
    assert_eq!(sp.architecture.ecomod.ks_g.iter().map(|p| [p[0] as f64, p[1] as f64]).collect::<Vec<_>>().len(), dragged.len());
    assert!((sp.architecture.ecomod.ks_g[0][1] as f64 - dragged[0][1]).abs() < 1e-4);
    let changed: Vec<(&str, &str)> = orig.lines().zip(text.lines()).filter(|(a, b)| a != b).collect();
    assert_eq!(changed.len(), 1, "only the ks_g line changed: {changed:?}");
    assert!(changed[0].1.starts_with("ks_g = [["));
    // right-click removes a point (min_len_g has three; adding by double-click is
    // `curve::add_point`, tested in src/edit/curve.rs)
    let ml = "architecture.ecomod.min_len_g";
    assert_eq!(h.state().doc.polyline(ml).unwrap().len(), 3);
    h.get_by_label(&sylva::edit::curve::point_label(ml, 1)).click_secondary();
    h.run();
    assert_eq!(h.state().doc.polyline(ml).unwrap(), vec![[0.0, 1.0], [15.0, 1.0]]);
    // the removal is one undo step
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run();
    assert_eq!(h.state().doc.polyline(ml).unwrap().len(), 3);
}

#[test]
fn editor_shows_the_species_check_message_beside_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let (mut ed, _) = editor_in(dir.path());
    ed.doc.set_number("architecture.ecomod.k_c", 1.4, false).unwrap();
    ed.revalidate();
    assert_eq!(ed.problems_of("architecture.ecomod.k_c").len(), 1);
    let expected = ed.problems_of("architecture.ecomod.k_c")[0].expected.clone();
    let mut h = Harness::builder().with_size(egui::vec2(1500.0, 4200.0)).build_ui_state(|ui, e: &mut Editor| e.ui(ui), ed);
    h.run();
    h.get_by_label(&format!("problem: {expected}"));
    h.get_by_label("1 problem(s)");
}

#[test]
fn editor_regrows_the_preview_and_highlights_the_orders_of_the_hovered_point() {
    let dir = tempfile::tempdir().unwrap();
    let (mut ed, _) = editor_in(dir.path());
    ed.age_yr = 20.0;
    ed.finish_preview();
    let n0 = ed.grown().unwrap().skeleton.nodes.len();
    let h0 = ed.grown().unwrap().height_m;
    ed.doc.set_number("architecture.ecomod.trunk_length_m", 8.0, false).unwrap();
    ed.finish_preview();
    let g = ed.grown().unwrap();
    assert_eq!(g.request.species.architecture.ecomod.trunk_length_m, 8.0, "regrown from the edited text");
    assert!(g.height_m != h0 || g.skeleton.nodes.len() != n0, "the tree changed");
    assert_eq!(ed.preview_prototypes(), 1);
    // hover the second point of alpha_g (order 15 end): the orders from its left neighbour on
    let mut h = Harness::builder().with_size(egui::vec2(1500.0, 4200.0)).build_ui_state(|ui, e: &mut Editor| e.ui(ui), ed);
    h.run();
    let c = h.get_by_label(&sylva::edit::curve::point_label("architecture.ecomod.alpha_g", 1)).rect().center();
    h.hover_at(c);
    h.run();
    h.run();
    assert_eq!(h.state().highlighted(), Some(sylva::edit::preview::Highlight::Gravelius(0.0, 15.0)));
    assert_eq!(h.state().preview_prototypes(), 2, "the highlight is drawn");
    h.hover_at(egui::pos2(1400.0, 4000.0));
    h.run();
    h.run();
    assert_eq!(h.state().highlighted(), None);
}

/// A virtual display for one test, or `None` (with a note) when Xvfb is not installed.
struct Xvfb {
    child: std::process::Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM, so that the server removes its lock file and socket (SIGKILL left them,
        // and the display numbers ran out over many runs); SIGKILL if it is still there
        let _ = Command::new("kill").arg(self.child.id().to_string()).status();
        for _ in 0..40 {
            if self.child.try_wait().ok().flatten().is_some() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(25));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn xvfb(n: u32) -> Option<Xvfb> {
    let found = Command::new("sh").args(["-c", "command -v Xvfb"]).output().map(|o| o.status.success()).unwrap_or(false);
    if !found {
        assert!(std::env::var_os("SYLVA_REQUIRE_XVFB").is_none(), "SYLVA_REQUIRE_XVFB is set but Xvfb is not installed");
        eprintln!("skipping: Xvfb is not installed (apt-get install xvfb)");
        return None;
    }
    // display numbers handed out once per process, from 57 on (`n` is a hint kept for the
    // callers), skipping those in use; a server that fails to start (another one took its
    // number meanwhile) is replaced by the next number. Tests start servers in parallel: with
    // a "first free number from n on" per test, two could pick the same one (seen in CI).
    static NEXT: std::sync::Mutex<u32> = std::sync::Mutex::new(57);
    let _ = n;
    let mut next = NEXT.lock().unwrap_or_else(|e| e.into_inner());
    for _ in 0..200 {
        let k = *next;
        *next += 1;
        // a live server's socket: taken (a stale lock of a killed server, Xvfb removes itself)
        let sock = PathBuf::from(format!("/tmp/.X11-unix/X{k}"));
        if sock.exists() && Path::new(&format!("/tmp/.X{k}-lock")).exists() {
            continue;
        }
        let display = format!(":{k}");
        let mut child = Command::new("Xvfb").args([display.as_str(), "-screen", "0", "1400x900x24", "-nolisten", "tcp"]).stderr(std::process::Stdio::null()).spawn().unwrap();
        let mut up = false;
        for _ in 0..400 {
            if sock.exists() {
                // a server that finds its display taken exits at once: give it that moment
                std::thread::sleep(std::time::Duration::from_millis(150));
                up = child.try_wait().ok().flatten().is_none();
                break;
            }
            if child.try_wait().ok().flatten().is_some() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(25));
        }
        if up {
            return Some(Xvfb { child, display });
        }
        let _ = child.kill();
        let _ = child.wait();
    }
    panic!("no virtual display could be started (Xvfb on :57 to :256)");
}

/// Runs `sylva ARGS` on the display with a private runtime folder; returns (success, stderr).
fn sylva_on(display: Option<&str>, args: &[&str], env: &[(&str, &str)]) -> (bool, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sylva"));
    c.args(args).env_remove("WAYLAND_DISPLAY").env_remove("DISPLAY");
    if let Some(d) = display {
        c.env("DISPLAY", d);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Share of pixels of `img` inside `r` (x0, y0, x1, y1) that are "vegetation or ground": more
/// green than blue, not grey UI.
fn greenish(img: &image::RgbaImage, r: (u32, u32, u32, u32)) -> f64 {
    let mut n = 0;
    let mut g = 0;
    for y in r.1..r.3 {
        for x in r.0..r.2 {
            let p = img.get_pixel(x, y).0;
            n += 1;
            let (rr, gg, bb) = (p[0] as i32, p[1] as i32, p[2] as i32);
            if gg > bb + 8 && gg >= rr - 10 && (gg - rr.min(bb)) > 12 {
                g += 1;
            }
        }
    }
    g as f64 / n.max(1) as f64
}

fn distinct_colours(img: &image::RgbaImage, r: (u32, u32, u32, u32)) -> usize {
    let mut s = std::collections::HashSet::new();
    for y in (r.1..r.3).step_by(2) {
        for x in (r.0..r.2).step_by(2) {
            let p = img.get_pixel(x, y).0;
            s.insert([p[0] >> 3, p[1] >> 3, p[2] >> 3]);
        }
    }
    s.len()
}

/// Screenshots of `sylva view` on the test run and of `sylva edit beech` on the display, with
/// `WGPU_BACKEND` set to `backend` when given; asserts that they show the landscape and the
/// tree, and returns them (view, edit).
fn window_screenshots(x: &Xvfb, backend: Option<&str>) -> (image::RgbaImage, image::RgbaImage) {
    let env: Vec<(&str, &str)> = backend.map(|b| ("WGPU_BACKEND", b)).into_iter().collect();
    let out = tempfile::tempdir().unwrap();
    let run = run_dir().join("run");
    let shot = out.path().join("view.png");
    let (ok, err) = sylva_on(Some(&x.display), &["view", run.to_str().unwrap(), "--screenshot", shot.to_str().unwrap(), "--frames", "2", "--window", "1000x640", "-v"], &env);
    assert!(ok && !err.contains("panicked"), "backend {backend:?}: {err}");
    // --frames 2 draws two frames of the 3-D view, not three (found by a trial)
    assert!(err.contains("frame 2 (") && !err.contains("frame 3 ("), "backend {backend:?}: {err}");
    let view_img = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(view_img.dimensions(), (1000, 640), "the whole window");
    // the 3-D view (left of the 340 px side panel, under the top bar): terrain and crowns
    let view = (20, 60, 640, 600);
    assert!(greenish(&view_img, view) > 0.2, "backend {backend:?}: green share {:.2}: {err}", greenish(&view_img, view));
    assert!(distinct_colours(&view_img, view) > 200, "backend {backend:?}: {} colours", distinct_colours(&view_img, view));
    // the editor's preview of beech
    let shot = out.path().join("edit.png");
    let (ok, err) = sylva_on(Some(&x.display), &["edit", "beech", "--dir", out.path().to_str().unwrap(), "--screenshot", shot.to_str().unwrap(), "--frames", "2", "--age", "30", "--window", "1000x640"], &env);
    assert!(ok && !err.contains("panicked"), "backend {backend:?}: {err}");
    let edit_img = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(edit_img.dimensions(), (1000, 640));
    let preview = (560, 80, 980, 600);
    assert!(greenish(&edit_img, preview) > 0.05, "backend {backend:?}: green share {:.3}: {err}", greenish(&edit_img, preview));
    assert!(distinct_colours(&edit_img, preview) > 100, "backend {backend:?}: {} colours", distinct_colours(&edit_img, preview));
    assert!(!out.path().join("beech.toml").exists(), "a screenshot saves nothing");
    (view_img, edit_img)
}

/// Mean absolute difference (0–255) of the RGB channels of two images inside `r`.
fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage, r: (u32, u32, u32, u32)) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for y in r.1..r.3 {
        for x in r.0..r.2 {
            let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
            sum += (0..3).map(|c| (p[c] as f64 - q[c] as f64).abs()).sum::<f64>() / 3.0;
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn view_and_edit_screenshots_under_xvfb_show_the_landscape_and_the_tree() {
    let Some(x) = xvfb(57) else { return };
    window_screenshots(&x, None);
}

/// Issue 36: the windows on an OpenGL adapter (Mesa's llvmpipe through `WGPU_BACKEND=gl`), which
/// lacks view formats (the viewport is then drawn into an sRGB texture of its own and copied):
/// no panic, and the same pictures as on Vulkan (lavapipe), colour for colour.
#[test]
fn the_windows_run_on_an_opengl_adapter_and_draw_what_vulkan_draws() {
    let Some(x) = xvfb(59) else { return };
    let (view_vk, edit_vk) = window_screenshots(&x, Some("vulkan"));
    let (view_gl, edit_gl) = window_screenshots(&x, Some("gl"));
    let d_view = mean_difference(&view_vk, &view_gl, (20, 60, 640, 600));
    let d_edit = mean_difference(&edit_vk, &edit_gl, (560, 80, 980, 600));
    eprintln!("mean colour difference Vulkan vs OpenGL: view {d_view:.3}, editor {d_edit:.3}");
    // measured: 0 on both (the same rasteriser behind both APIs); a gamma slip would be ≳ 20
    assert!(d_view < 4.0 && d_edit < 4.0, "mean colour difference Vulkan vs OpenGL: view {d_view:.2}, editor {d_edit:.2}");
}

#[test]
fn without_a_display_or_adapter_the_windows_fail_with_a_clear_message() {
    let run = run_dir().join("run");
    let (ok, err) = sylva_on(None, &["view", run.to_str().unwrap()], &[]);
    assert!(!ok && err.contains("no display") && err.contains("DISPLAY") && !err.contains("panicked"), "{err}");
    let (ok, err) = sylva_on(None, &["edit", "beech"], &[]);
    assert!(!ok && err.contains("no display") && !err.contains("panicked"), "{err}");
    // a display, but only a backend this machine does not have
    let Some(x) = xvfb(58) else { return };
    let (ok, err) = sylva_on(Some(&x.display), &["view", run.to_str().unwrap(), "--screenshot", "/tmp/never.png"], &[("WGPU_BACKEND", "dx12")]);
    assert!(!ok && err.contains("adapter") && !err.contains("panicked"), "{err}");
}

/// A run on a 200 m window of the embedded Coweeta DEM (issue 36: the viewer draws the terrain
/// around the window as the stills do), made once.
fn dem_run_dir() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let sc = r#"name = "gui surroundings"
years = 5
seed = 3
snapshot_every = 5
checkpoint_every = 0
species = ["beech"]

[terrain]
embedded = "coweeta"
window = [250, 280, 20, 20]

[[start]]
kind = "planted"
species = "beech"
spacing_m = 8.0
age_yr = 40.0
"#;
        std::fs::write(d.path().join("s.toml"), sc).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "s.toml", "--out", "run"]).current_dir(d.path()).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        d
    })
    .path()
}

/// Share of pixels of `img` inside `r` that are sky: bluer than they are red or green.
fn sky_share(img: &image::RgbaImage, r: (u32, u32, u32, u32)) -> f64 {
    let mut n = 0;
    let mut s = 0;
    for y in r.1..r.3 {
        for x in r.0..r.2 {
            let p = img.get_pixel(x, y).0;
            n += 1;
            if p[2] as i32 > p[0] as i32 + 20 && p[2] as i32 >= p[1] as i32 {
                s += 1;
            }
        }
    }
    s as f64 / n.max(1) as f64
}

/// First row (px from the top) of the 3-D view under the viewer's top bar: the first row from the
/// top whose pixels in columns 20–640 have a mean brightness above 100 (the bar is dark grey with
/// light text; the view's top rows are sky or lit terrain); the image height if none.
fn view_top(img: &image::RgbaImage) -> u32 {
    (0..img.height())
        .find(|&y| (20..640).map(|x| img.get_pixel(x, y).0[..3].iter().map(|&c| c as u32).sum::<u32>() / 3).sum::<u32>() / 620 > 100)
        .unwrap_or(img.height())
}

/// Issue 36 item 3: the viewer shows the landscape as the stills do, not as a slab in an empty
/// sky: above the horizon the sky, below it the terrain around the window (the DEM beyond it,
/// the window's trees mirrored onto it, fading into the haze) out to the view's edges.
#[test]
fn the_viewer_draws_the_terrain_around_the_window_and_the_sky_above_it() {
    let Some(x) = xvfb(60) else { return };
    let out = tempfile::tempdir().unwrap();
    let run = dem_run_dir().join("run");
    let shot = out.path().join("view.png");
    let (ok, err) = sylva_on(Some(&x.display), &["view", run.to_str().unwrap(), "--screenshot", shot.to_str().unwrap(), "--frames", "2", "--window", "1000x640"], &[]);
    assert!(ok && !err.contains("panicked"), "{err}");
    let img = image::open(&shot).unwrap().to_rgba8();
    let _ = img.save(std::env::temp_dir().join("sylva_gui_surroundings.png"));
    // the 3-D view is left of the 340 px side panel, under the top bar (whose height depends on
    // how its controls wrap at this width: one or two rows)
    let v = view_top(&img);
    assert!((20..=120).contains(&v), "the 3-D view starts under the top bar, at y {v}");
    let top = sky_share(&img, (20, v + 2, 640, v + 12));
    let lower = sky_share(&img, (20, 320, 640, 600));
    let corners = [sky_share(&img, (20, 500, 120, 600)), sky_share(&img, (540, 500, 640, 600))];
    eprintln!("sky share: top {top:.3}, lower half {lower:.3}, bottom corners {corners:?}");
    assert!(top > 0.9, "the sky above the horizon: {top:.3}");
    assert!(lower < 0.02, "the ground below it, out to the view's edges: sky share {lower:.3}");
    assert!(corners.iter().all(|&c| c < 0.02), "the terrain around the window in the bottom corners: {corners:?}");
}

/// Issue 32: `sylva view --camera ground --screenshot` waits for the adapted near field and the
/// screenshot draws it: the trees near the camera that the frame draws at the full level are
/// their own adapted full-detail meshes (the viewer logs them by the level the frame drew them
/// at), not the species' models, with the skeleton nodes of full-detail trees (hundreds; the
/// stills' 48-strand trees have about 60).
#[test]
fn the_viewer_screenshot_shows_the_adapted_near_field() {
    let Some(x) = xvfb(61) else { return };
    let out = tempfile::tempdir().unwrap();
    let run = run_dir().join("run");
    let shot = out.path().join("near.png");
    let (ok, err) = sylva_on(Some(&x.display), &["view", run.to_str().unwrap(), "--camera", "ground", "--screenshot", shot.to_str().unwrap(), "--frames", "2", "--window", "1000x640", "-v"], &[]);
    assert!(ok && !err.contains("panicked"), "{err}");
    let line = err.lines().find(|l| l.contains("near field drawn:")).unwrap_or_else(|| panic!("no near field drawn: {err}"));
    eprintln!("{line}");
    let num_after = |key: &str| -> usize {
        let rest = &line[line.find(key).unwrap_or_else(|| panic!("`{key}` in {line}")) + key.len()..];
        rest.trim_start().split(|c: char| !c.is_ascii_digit()).next().unwrap().parse().unwrap()
    };
    let adapted = num_after("near field drawn:");
    let full = num_after("adapted trees,");
    let nodes = num_after("median");
    assert!(adapted >= 1 && full >= 1 && full <= adapted, "{line}");
    assert!(nodes >= 200, "full-detail skeletons: median {nodes} nodes ({line})");
    // the screenshot was taken after them: two frames drawn, the first with the adapted trees
    let pos = |s: &str| err.find(s).unwrap_or_else(|| panic!("`{s}` in {err}"));
    assert!(pos("near field of year 10:") < pos("frame 1 ("), "the first frame waits for the near field: {err}");
    assert!(err.contains("frame 2 (") && !err.contains("frame 3 ("), "{err}");
    let img = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (1000, 640));
    assert!(greenish(&img, (20, 60, 640, 600)) > 0.05, "green share {:.3}", greenish(&img, (20, 60, 640, 600)));
}
