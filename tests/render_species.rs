//! Species you can tell apart (issue 19, Build 2): the top-down still of a stand with known
//! single-species patches, read back per 20 m cell, names the right species by colour.
//!
//! Runs on whatever adapter wgpu finds (lavapipe in CI); without one it prints a note and passes,
//! unless `SYLVA_REQUIRE_ADAPTER` is set (CI), in which case it fails (tests/common/render.rs).

use glam::Vec3;
use sylva::render::camera::{Camera, CameraPreset};
use sylva::render::headless::{LightTerms, Renderer};
use sylva::render::scene::{Scene, Sky, Sun, TreeInstance, Wind};
use sylva::render::terrain::{from_grid, LandCover};
use sylva::species::{Season, SpeciesLibrary};

#[path = "common/render.rs"]
mod render_common;
use render_common::{out_dir, with_renderer};

/// Stand side (m) and analysis cell (m).
const SIDE: f32 = 320.0;
const CELL: f32 = 20.0;

/// The patch species, and per species (height m, crown radius m) of a mature canopy tree
/// (heights of yield class I at ~100 years; crown radii of closed stands).
const SPECIES: [(&str, f32, f32); 5] = [("beech", 30.0, 4.5), ("sessile_oak", 27.0, 5.0), ("silver_birch", 23.0, 3.2), ("norway_spruce", 33.0, 2.8), ("scots_pine", 25.0, 3.4)];

/// The species of the default run's canopy (its species map at year 150: beech, sessile oak,
/// Norway maple and silver birch patches, some Norway spruce), sized as [`SPECIES`].
const DEFAULT_RUN_SPECIES: [(&str, f32, f32); 5] = [("beech", 30.0, 4.5), ("sessile_oak", 27.0, 5.0), ("norway_maple", 27.0, 4.5), ("silver_birch", 23.0, 3.2), ("norway_spruce", 33.0, 2.8)];

/// Patch centres (m) of the Voronoi patches and their species (index into [`SPECIES`]).
const SEEDS: [(f32, f32, usize); 8] = [(50.0, 60.0, 0), (170.0, 40.0, 1), (280.0, 90.0, 2), (60.0, 190.0, 3), (160.0, 160.0, 4), (270.0, 230.0, 0), (90.0, 290.0, 1), (210.0, 290.0, 2)];

fn hash(mut x: u64) -> f32 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// The patch (species index) of a point: its nearest seed.
fn patch(x: f32, y: f32) -> usize {
    SEEDS.iter().min_by(|a, b| ((a.0 - x).hypot(a.1 - y)).total_cmp(&(b.0 - x).hypot(b.1 - y))).map(|s| s.2).unwrap_or(0)
}

/// Trees of the stand: per species a jittered grid of spacing 1.8 × its crown radius (a closed
/// canopy), kept where the point lies in one of its patches; sizes vary ±10 %. Returns
/// (species index, x, y, height, crown radius, id).
fn stand() -> Vec<(usize, f32, f32, f32, f32, u64)> {
    let mut out = Vec::new();
    let mut id = 1u64;
    for (s, &(_, h, r)) in SPECIES.iter().enumerate() {
        let sp = 1.8 * r;
        let n = (SIDE / sp).ceil() as u32;
        for j in 0..n {
            for i in 0..n {
                let k = (s as u64) << 40 | (j as u64) << 20 | i as u64;
                let x = (i as f32 + 0.2 + 0.6 * hash(k)) * sp;
                let y = (j as f32 + 0.2 + 0.6 * hash(k ^ 0x9e37)) * sp;
                if x >= SIDE || y >= SIDE || patch(x, y) != s {
                    continue;
                }
                let f = 0.9 + 0.2 * hash(k ^ 0x51ed);
                out.push((s, x, y, h * f, r * f, id));
                id += 1;
            }
        }
    }
    out
}

/// The scene of `trees` with the species of `lib` (in [`SPECIES`] order) in summer, on flat
/// terrain, the sun of 47° N in July at 14:00; `only`: every tree drawn as that species.
fn scene(lib: &SpeciesLibrary, protos: &[sylva::render::scene::Prototype], trees: &[(usize, f32, f32, f32, f32, u64)], only: Option<usize>) -> Scene {
    let n = (SIDE / 10.0) as usize + 1;
    let grid = sylva::grid::Grid::filled(n, n, 0.0f32);
    let terrain = from_grid(&grid, 10.0, 10.0, &LandCover::default(), None).unwrap();
    let inst = trees
        .iter()
        .map(|&(s, x, y, h, r, id)| {
            let s = only.unwrap_or(s);
            let (col, amount) = sylva::job::scene::foliage(&lib.species[s], Season::Summer);
            let mut t = TreeInstance::new(id, [x, y, 0.0], h, r, s as u32, col);
            t.leaf_amount = amount;
            t
        })
        .collect();
    Scene::new(terrain, None, protos.to_vec(), inst, Sun::from_position(47.0, 196.0, 14.0), Sky::default(), Wind::default())
}

/// The renderer's level settings of the offline stills (`job::pictures::Stage::new`).
fn still_lod(r: &mut Renderer) {
    r.lod.max_triangles = 30_000_000;
    r.lod.switch_px = [110.0, 45.0, 18.0];
    r.lod.max_geometry_triangles = 0;
}

/// Mean sRGB colour of the pixels of each analysis cell (row-major, south to north).
fn cell_means(img: &image::RgbaImage, cam: &Camera) -> Vec<[f64; 3]> {
    let (w, h) = img.dimensions();
    let vp = cam.view_proj(w as f32 / h as f32);
    let px = |x: f32, y: f32| {
        let c = vp * Vec3::new(x, y, 0.0).extend(1.0);
        let ndc = c.truncate() / c.w;
        ((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32)
    };
    let n = (SIDE / CELL) as usize;
    let mut out = Vec::with_capacity(n * n);
    for cy in 0..n {
        for cx in 0..n {
            let (x0, y0) = px(cx as f32 * CELL, (cy + 1) as f32 * CELL);
            let (x1, y1) = px((cx + 1) as f32 * CELL, cy as f32 * CELL);
            let (mut s, mut k) = ([0.0f64; 3], 0.0f64);
            for y in (y0.ceil().max(0.0) as u32)..(y1.floor().min(h as f32) as u32) {
                for x in (x0.ceil().max(0.0) as u32)..(x1.floor().min(w as f32) as u32) {
                    let p = img.get_pixel(x, y).0;
                    for c in 0..3 {
                        s[c] += p[c] as f64;
                    }
                    k += 1.0;
                }
            }
            out.push(s.map(|v| v / k.max(1.0)));
        }
    }
    out
}

/// Trees of a mixed stand with the patches of [`SEEDS`] as the default run grows them (issue
/// 19): in the default scenario's final year the species that dominates a 20 m cell of the
/// species map holds only about half of the crown area of its tall trees, the rest shared by the
/// other species. A jittered grid of 7 m; each tree is of its patch's species with probability
/// `purity`, else of one of the other species alike; heights and crown radii of `species`
/// (crowns capped at 4 m), ±10 %. Returns rows as [`stand`] does.
fn mixed_stand(purity: f32, species: &[(&str, f32, f32); 5]) -> Vec<(usize, f32, f32, f32, f32, u64)> {
    let sp = 7.0;
    let n = (SIDE / sp).ceil() as u32;
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let k = 0x77u64 << 48 | (j as u64) << 20 | i as u64;
            let x = (i as f32 + 0.2 + 0.6 * hash(k)) * sp;
            let y = (j as f32 + 0.2 + 0.6 * hash(k ^ 0x9e37)) * sp;
            if x >= SIDE || y >= SIDE {
                continue;
            }
            let own = patch(x, y);
            let u = hash(k ^ 0x3c3c);
            let s = if u < purity { own } else { (own + 1 + ((u - purity) / (1.0 - purity) * (SPECIES.len() - 1) as f32) as usize % (SPECIES.len() - 1)) % SPECIES.len() };
            let f = 0.9 + 0.2 * hash(k ^ 0x51ed);
            out.push((s, x, y, species[s].1 * f, species[s].2.min(4.0) * f, (j * n + i + 1) as u64));
        }
    }
    out
}

/// The species holding at least 75 % of the crown area of the trees standing in each cell
/// (row-major like [`cell_means`]), `None` for mixed or empty cells.
fn dominant(trees: &[(usize, f32, f32, f32, f32, u64)]) -> Vec<Option<usize>> {
    let n = (SIDE / CELL) as usize;
    let mut area = vec![[0.0f32; SPECIES.len()]; n * n];
    for &(s, x, y, _, r, _) in trees {
        let (cx, cy) = (((x / CELL) as usize).min(n - 1), ((y / CELL) as usize).min(n - 1));
        area[cy * n + cx][s] += r * r;
    }
    area.iter()
        .map(|a| {
            let tot: f32 = a.iter().sum();
            (0..SPECIES.len()).find(|&s| tot > 0.0 && a[s] >= 0.75 * tot)
        })
        .collect()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
}

/// The reference colour of each species: the mean cell colour of the stand `trees` drawn as
/// that species alone, seen by `cam` at `size` × `size` pixels.
fn reference_colours(r: &mut Renderer, lib: &SpeciesLibrary, protos: &[sylva::render::scene::Prototype], trees: &[(usize, f32, f32, f32, f32, u64)], cam: &Camera, size: u32) -> Vec<[f64; 3]> {
    (0..SPECIES.len())
        .map(|s| {
            let m = cell_means(&r.render(&scene(lib, protos, trees, Some(s)), cam, size, size).unwrap(), cam);
            let k = m.len() as f64;
            m.iter().fold([0.0f64; 3], |a, c| [a[0] + c[0] / k, a[1] + c[1] / k, a[2] + c[2] / k])
        })
        .collect()
}

/// Names each cell with a species in `truth` by the nearest of the reference colours `refs`:
/// the cells named right and the confusion matrix (row = truth, column = name).
fn name_cells(means: &[[f64; 3]], truth: &[Option<usize>], refs: &[[f64; 3]]) -> (usize, Vec<[usize; SPECIES.len()]>) {
    let mut right = 0usize;
    let mut confusion = vec![[0usize; SPECIES.len()]; SPECIES.len()];
    for (m, t) in means.iter().zip(truth) {
        let Some(t) = *t else { continue };
        let guess = (0..SPECIES.len()).min_by(|&a, &b| dist(*m, refs[a]).total_cmp(&dist(*m, refs[b]))).unwrap();
        confusion[t][guess] += 1;
        right += (guess == t) as usize;
    }
    (right, confusion)
}

#[test]
fn top_down_still_names_the_species_of_each_patch_by_colour() {
    let all = SpeciesLibrary::embedded().unwrap();
    let lib = SpeciesLibrary { species: SPECIES.iter().map(|(id, _, _)| all.species[all.find(id).unwrap() as usize].clone()).collect() };
    let protos = sylva::job::scene::prototypes(&lib);
    let trees = stand();
    let truth = dominant(&trees);
    let judged = truth.iter().filter(|t| t.is_some()).count();
    assert!(judged >= 150, "the stand must have mostly single-species cells: {judged} of 256");
    with_renderer(|r| {
        still_lod(r);
        // the gallery's top-down still is 1600 m in 720 px (2.2 m/px): billboards; also a closer
        // map at 1 m/px, where the crowns are crown hulls
        let mut failures = Vec::new();
        for (size, name) in [(320u32, "near"), (160, "far")] {
            let mixed = scene(&lib, &protos, &trees, None);
            let cam = Camera::preset(CameraPreset::Map, &mixed.terrain);
            let img = r.render(&mixed, &cam, size, size).unwrap();
            img.save(out_dir().join(format!("species_patches_{name}.png"))).unwrap();
            // reference colour of each species: the mean cell colour of the same stand drawn as
            // that species alone
            let refs = reference_colours(r, &lib, &protos, &trees, &cam, size);
            let (right, confusion) = name_cells(&cell_means(&img, &cam), &truth, &refs);
            let frac = right as f64 / judged as f64;
            eprintln!("{name} ({size} px): reference colours {refs:.0?}; confusion (row = truth) {confusion:?}; {right}/{judged} = {:.1} %", 100.0 * frac);
            if frac < 0.75 {
                failures.push(format!("{name}: the nearest species colour matches the species map on {:.1} % of single-species cells (< 75 %); confusion {confusion:?}", 100.0 * frac));
            }
            // and the references themselves are apart: no two species within 3 sRGB levels
            for a in 0..SPECIES.len() {
                for b in a + 1..SPECIES.len() {
                    if dist(refs[a], refs[b]) <= 3.0 {
                        failures.push(format!("{name}: {} and {} render alike: {:?} vs {:?}", SPECIES[a].0, SPECIES[b].0, refs[a], refs[b]));
                    }
                }
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
    });
}

#[test]
fn top_down_still_shows_the_patches_of_a_mixed_stand() {
    // the default run's pattern: patches where one species holds about half the crowns; cells
    // of 40 m (a patch as the eye reads it from the air) are named by the nearest of the
    // species' colours mixed as the stand mixes them, which must find the species holding at
    // least half of their crown area in most of them (chance: 20 %)
    let all = SpeciesLibrary::embedded().unwrap();
    let lib = SpeciesLibrary { species: DEFAULT_RUN_SPECIES.iter().map(|(id, _, _)| all.species[all.find(id).unwrap() as usize].clone()).collect() };
    let protos = sylva::job::scene::prototypes(&lib);
    let purity = 0.55;
    let trees = mixed_stand(purity as f32, &DEFAULT_RUN_SPECIES);
    let cell = 2.0 * CELL;
    let n = (SIDE / cell) as usize;
    // per 40 m cell: the truth, and the mean of the four 20 m cells' colours
    let mut area = vec![[0.0f32; SPECIES.len()]; n * n];
    for &(s, x, y, _, r, _) in &trees {
        area[((y / cell) as usize).min(n - 1) * n + ((x / cell) as usize).min(n - 1)][s] += r * r;
    }
    let truth: Vec<Option<usize>> = area
        .iter()
        .map(|a| {
            let tot: f32 = a.iter().sum();
            (0..SPECIES.len()).find(|&s| a[s] >= 0.5 * tot)
        })
        .collect();
    let judged = truth.iter().filter(|t| t.is_some()).count();
    assert!(judged >= 30, "about half the 40 m cells have a species holding half the crowns: {judged} of {}", n * n);
    let coarse = |m: &[[f64; 3]]| -> Vec<[f64; 3]> {
        let k = 2 * n;
        (0..n * n)
            .map(|c| {
                let (cx, cy) = (c % n, c / n);
                let mut a = [0.0f64; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    for ch in 0..3 {
                        a[ch] += m[(2 * cy + dy) * k + 2 * cx + dx][ch] / 4.0;
                    }
                }
                a
            })
            .collect()
    };
    with_renderer(|r| {
        still_lod(r);
        let size = 320u32;
        let mixed = scene(&lib, &protos, &trees, None);
        let cam = Camera::preset(CameraPreset::Map, &mixed.terrain);
        let img = r.render(&mixed, &cam, size, size).unwrap();
        img.save(out_dir().join("species_patches_mixed.png")).unwrap();
        // a patch reads as its species' colour mixed with the others' as the stand mixes them
        let pure = reference_colours(r, &lib, &protos, &trees, &cam, size);
        let refs: Vec<[f64; 3]> = (0..SPECIES.len())
            .map(|s| {
                let others = (1.0 - purity) / (SPECIES.len() - 1) as f64;
                let mut c = [0.0f64; 3];
                for (o, p) in pure.iter().enumerate() {
                    let w = if o == s { purity } else { others };
                    for k in 0..3 {
                        c[k] += w * p[k];
                    }
                }
                c
            })
            .collect();
        let (right, confusion) = name_cells(&coarse(&cell_means(&img, &cam)), &truth, &refs);
        let frac = right as f64 / judged as f64;
        eprintln!("mixed stand: reference colours {refs:.0?}; confusion (row = truth) {confusion:?}; {right}/{judged} = {:.1} %", 100.0 * frac);
        assert!(frac >= 0.5, "the nearest species colour names the leading species of {:.1} % of the 40 m cells of a mixed stand (< 50 %); confusion {confusion:?}", 100.0 * frac);
        // and the patches are apart to the eye: a stand leaning to one species differs from one
        // leaning to any other by more than 2.5 sRGB levels (the summer colours before issue 19
        // gave 2 between beech and birch; issue 19's colours more than 4). Round 46 makes the
        // summer colours one canopy (trial 45's "painted by numbers", tests/species_colours.rs):
        // beech against sessile oak 3.1 levels on lavapipe, the smallest pair; the nearest
        // colour still names the leading species of most cells (above)
        for a in 0..SPECIES.len() {
            for b in a + 1..SPECIES.len() {
                assert!(dist(refs[a], refs[b]) > 2.5, "{} and {} patches read alike: {:?} vs {:?}", DEFAULT_RUN_SPECIES[a].0, DEFAULT_RUN_SPECIES[b].0, refs[a], refs[b]);
            }
        }
    });
}

#[test]
fn patch_stand_from_oblique_and_ground_has_no_black_foliage() {
    // writes target/tmp/render/species_patches_{oblique,ground}.png for inspection, and checks
    // the defect of the last round (near-black leaf clusters seen from below): in the ground
    // view, fewer than 0.5 % of the pixels are near black (all channels < 14)
    let all = SpeciesLibrary::embedded().unwrap();
    let lib = SpeciesLibrary { species: SPECIES.iter().map(|(id, _, _)| all.species[all.find(id).unwrap() as usize].clone()).collect() };
    let protos = sylva::job::scene::prototypes(&lib);
    let trees = stand();
    let scene = scene(&lib, &protos, &trees, None);
    with_renderer(|r| {
        still_lod(r);
        let oblique = Camera::preset(CameraPreset::Oblique, &scene.terrain);
        let img = r.render(&scene, &oblique, 640, 360).unwrap();
        img.save(out_dir().join("species_patches_oblique.png")).unwrap();
        // from a clearing at the beech / oak / birch border, looking north-east under the crowns
        let mut ground = Camera::look_at([118.0, 95.0, 1.7], [200.0, 160.0, 9.0], 60.0);
        ground.near = 0.1;
        // a tighter triangle budget than the stills' keeps the test fast on a software adapter
        r.lod.max_triangles = 2_000_000;
        let img = r.render(&scene, &ground, 480, 270).unwrap();
        img.save(out_dir().join("species_patches_ground.png")).unwrap();
        let black = img.pixels().filter(|p| p.0[..3].iter().all(|&c| c < 14)).count() as f64 / (480.0 * 270.0);
        eprintln!("ground view: {:.2} % near-black pixels; {:?}", 100.0 * black, r.last_stats());
        assert!(black < 0.005, "{:.2} % of the ground view is near black", 100.0 * black);
    });
}

#[test]
fn crown_looks_follow_the_species_habit() {
    // the species files' crown looks reach the prototypes: spire < dome < umbrella, the birch
    // airier than the beech, the oak lumpier than the beech, and every species has leaf cards
    let all = SpeciesLibrary::embedded().unwrap();
    let look = |id: &str| sylva::job::scene::crown_look(&all.species[all.find(id).unwrap() as usize]);
    let (beech, oak, birch, spruce, pine) = (look("beech"), look("sessile_oak"), look("silver_birch"), look("norway_spruce"), look("scots_pine"));
    assert!(spruce.top_flatness < beech.top_flatness && beech.top_flatness < pine.top_flatness, "{spruce:?} {beech:?} {pine:?}");
    assert!(birch.cover < beech.cover && oak.clump > beech.clump, "{birch:?} {oak:?} {beech:?}");
    for l in [beech, oak, birch, spruce, pine] {
        assert!(l.leaf_shape.is_some(), "{l:?}");
    }
    assert_ne!(beech.leaf_shape, oak.leaf_shape);
}

/// Linear luminance (Rec. 709) of an sRGB pixel, 0..1.
fn lin_lum(p: &image::Rgba<u8>) -> f64 {
    let l = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    0.2126 * l(p.0[0]) + 0.7152 * l(p.0[1]) + 0.0722 * l(p.0[2])
}

/// What a still's crowns show of the sun (issue 32, round 35), from renders of one view:
/// `all` (the picture), `free` (no shadows), `sky` (the sky light alone) and `bare` (the same
/// scene without trees: the pixels that differ are the trees'). Returns (share of the tree
/// pixels in the sun's shadow: their sunlight `all − sky` under half of `free − sky`; mean over
/// the crowns of (sun side − far side) / mean of each crown's linear luminance in its projected
/// disc; the crowns counted).
fn crown_light(all: &image::RgbaImage, free: &image::RgbaImage, sky: &image::RgbaImage, bare: &image::RgbaImage, trees: &[(usize, f32, f32, f32, f32, u64)], cam: &Camera, sun: Vec3) -> (f64, f64, usize) {
    let (w, h) = all.dimensions();
    let tree_px = |x: u32, y: u32| {
        let (a, b) = (all.get_pixel(x, y).0, bare.get_pixel(x, y).0);
        (0..3).any(|c| a[c].abs_diff(b[c]) > 4)
    };
    let (mut n, mut shaded) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            if !tree_px(x, y) {
                continue;
            }
            let s = lin_lum(sky.get_pixel(x, y));
            let (got, full) = (lin_lum(all.get_pixel(x, y)) - s, lin_lum(free.get_pixel(x, y)) - s);
            if full > 0.01 {
                n += 1;
                shaded += (got < 0.5 * full) as usize;
            }
        }
    }
    let vp = cam.view_proj(w as f32 / h as f32);
    let px = |p: Vec3| {
        let c = vp * p.extend(1.0);
        let ndc = c.truncate() / c.w;
        glam::Vec2::new((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32)
    };
    let sun_h = Vec3::new(sun.x, sun.y, 0.0).normalize_or(Vec3::X);
    let (mut sum, mut k) = (0.0f64, 0usize);
    for &(_, x, y, th, r, _) in trees {
        let c3 = Vec3::new(x, y, 0.7 * th);
        let c = px(c3);
        let rho = (px(c3 + Vec3::new(0.0, 0.0, r)) - c).length();
        let s = (px(c3 + sun_h * r) - c).normalize_or_zero();
        if rho < 5.0 || c.x < rho || c.y < rho || c.x > w as f32 - rho || c.y > h as f32 - rho || s == glam::Vec2::ZERO {
            continue;
        }
        let (mut ls, mut ns, mut lf, mut nf) = (0.0f64, 0usize, 0.0f64, 0usize);
        for py in (c.y - rho) as u32..=(c.y + rho) as u32 {
            for pxx in (c.x - rho) as u32..=(c.x + rho) as u32 {
                let d = glam::Vec2::new(pxx as f32 + 0.5, py as f32 + 0.5) - c;
                if d.length() > 0.8 * rho || !tree_px(pxx, py) {
                    continue;
                }
                let l = lin_lum(all.get_pixel(pxx, py));
                let t = d.dot(s) / rho;
                if t > 0.25 {
                    ls += l;
                    ns += 1;
                } else if t < -0.25 {
                    lf += l;
                    nf += 1;
                }
            }
        }
        if ns >= 4 && nf >= 4 {
            let (a, b) = (ls / ns as f64, lf / nf as f64);
            sum += (a - b) / (0.5 * (a + b)).max(1e-4);
            k += 1;
        }
    }
    (shaded as f64 / n.max(1) as f64, sum / k.max(1) as f64, k)
}

/// Standard deviation of the sRGB luminance (0..255) of the tree pixels of `all` (those that
/// differ from `bare`, the scene without trees).
fn canopy_sd(all: &image::RgbaImage, bare: &image::RgbaImage) -> f64 {
    let v: Vec<f64> = all
        .pixels()
        .zip(bare.pixels())
        .filter(|(a, b)| (0..3).any(|c| a.0[c].abs_diff(b.0[c]) > 4))
        .map(|(a, _)| 0.2126 * a.0[0] as f64 + 0.7152 * a.0[1] as f64 + 0.0722 * a.0[2] as f64)
        .collect();
    let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

// Round 45: failed since r45c's broadleaf crown profiles (0.017 against 0.008 with the sun on the
// quad; 3.4 % of the tree pixels in their own shade). Round 46 (r46b) found the cause in the
// crowns' shape, not in the shader: with the profiles removed from the same species the same
// shader gave round 38's 0.072 and 7.7 % again; with them, in a stand of half the trees (every
// other 7 m cell), 0.149 against the quad's 0.088. The profiles' crowns are wide to their tops
// (the prototypes' top bin 0.5–0.7 of their widest, 0.15–0.3 before) and their widest point
// moved up (0.41–0.59 of the height, 0.28–0.41 before): in the 7 m stand seen obliquely each
// crown's upper half hides the shaded lower far side of the crown behind it. The terminator of
// a billboard crown's own shade now lies at 0.05–0.45 of the cosine of the sun's incidence on
// the crown as a round solid (was −0.15–0.25) and the solid's normal leans less upward (0.6 of
// its relative height, was 0.8): the leaves the sun meets at a grazing angle are shaded by the
// crown's own foliage in front of them. Measured: 0.050 against 0.008, 17.5 % of the tree
// pixels in their own shade (without the profiles 0.154; half the trees 0.247).
#[test]
fn oblique_billboard_crowns_have_a_sunlit_and_a_shaded_side() {
    // issue 32, round 35: the oblique still read as a carpet. A billboard crown took the sun's
    // visibility on its camera-facing quad through the stem, in a shadow map of ~3 m a texel
    // (the default run's site and surroundings, ~4.5 km, in 2048 texels) that cannot resolve a
    // crown: the crowns were lit almost uniformly. Where the texels are coarse against the
    // crown, the sun is now looked up at the crown surface the pixel shows, outside its own
    // quad, and the crown shades its far side itself; with fine texels as before. The default run's canopy species (7 m mixed stand), every tree drawn as a
    // billboard, seen obliquely from 200 m, the sun from the side (10:00, July, 47° N) and, for
    // the record, behind the camera (14:00, the stills' sun), on a 320 m ground (shadow texel
    // 0.2 m) and in the middle of a 4.5 km one (3.1 m, as the default run). Fails, not skips,
    // without an adapter.
    let all_sp = SpeciesLibrary::embedded().unwrap();
    let lib = SpeciesLibrary { species: DEFAULT_RUN_SPECIES.iter().map(|(id, _, _)| all_sp.species[all_sp.find(id).unwrap() as usize].clone()).collect() };
    let protos = sylva::job::scene::prototypes(&lib);
    let stand = mixed_stand(0.6, &DEFAULT_RUN_SPECIES);
    let (w, h) = (480, 270);
    let mut r = Renderer::new().expect("this test renders: it needs an adapter (lavapipe on the CPU)");
    still_lod(&mut r);
    // every tree a billboard (the level of the stills' far crowns, under 18 px)
    r.lod.switch_px = [1e9, 1e9, 1e9];
    r.lod.canopy_px = 0.0;
    // (ground m, hour, sun on the quad) → (shadow share, sun side − far side, crowns, sd)
    let mut got = std::collections::HashMap::new();
    for ground in [SIDE, 4500.0] {
        let off = 0.5 * (ground - SIDE);
        let trees: Vec<_> = stand.iter().map(|&(s, x, y, th, cr, id)| (s, x + off, y + off, th, cr, id)).collect();
        let mut scene = scene(&lib, &protos, &trees, None);
        let n = (ground / 50.0) as usize + 1;
        scene.terrain = from_grid(&sylva::grid::Grid::filled(n, n, 0.0f32), ground / (n - 1) as f32, ground / (n - 1) as f32, &LandCover::default(), None).unwrap();
        let mut bare = scene.clone();
        bare.instances.clear();
        let c = Vec3::new(0.5 * ground, 0.5 * ground, 15.0);
        let eye = c + Vec3::new(-0.55, -0.7, 0.42).normalize() * 200.0;
        let cam = Camera::look_at(eye.to_array(), c.to_array(), 45.0);
        let mut shot = |terms: LightTerms, quad: bool, s: &Scene| {
            r.light_terms = terms;
            r.crown_sun_on_quad = quad;
            r.render(s, &cam, w, h).unwrap()
        };
        let bare_img = shot(LightTerms::All, false, &bare);
        for hour in [10.0, 14.0] {
            scene.sun = Sun::from_position(47.0, 196.0, hour);
            let sun = Vec3::from(scene.sun.direction);
            for quad in [true, false] {
                let all = shot(LightTerms::All, quad, &scene);
                let free = shot(LightTerms::NoShadows, quad, &scene);
                let sky = shot(LightTerms::SkyOnly, quad, &scene);
                let name = format!("{}m_{hour}h_{}", ground as u32, if quad { "before" } else { "after" });
                all.save(out_dir().join(format!("crown_light_{name}.png"))).unwrap();
                let (shaded, contrast, crowns) = crown_light(&all, &free, &sky, &bare_img, &trees, &cam, sun);
                let sd = canopy_sd(&all, &bare_img);
                eprintln!("{name} (sun on the {}): {:.1} % of the tree pixels in shadow, crowns' sun side − far side {contrast:.3} of their mean ({crowns} crowns), canopy luminance sd {sd:.1}", if quad { "quad" } else { "crown surface" }, 100.0 * shaded);
                got.insert((ground as u32, hour as u32, quad), (shaded, contrast, crowns, sd));
            }
        }
    }
    // the default run's coarse shadow map, sun from the side: crowns had hardly a shaded side
    // (1.4 % of the tree pixels without sun, sun side 0.11 brighter than the far side); now
    // they shade their far side themselves (round 35, lavapipe: 12.7 %, 0.19; round 37, with the
    // prototypes' full leaf area: 10.1 %, 0.131)
    let ((s0, c0, _, sd0), (s1, c1, k1, sd1)) = (got[&(4500, 10, true)], got[&(4500, 10, false)]);
    assert!(k1 > 100, "{k1} crowns measured");
    // round 37: the prototypes carry their crown's leaf area (0.86–1.00 of the species' LAI,
    // 0.06–0.18 before for broadleaves), so more sky-lit cards fill the far side: lavapipe 0.131
    // against 0.075 with the sun on the quad (was 0.19 against 0.11 with the sparse crowns)
    // round 38: sessile oak's and silver birch's crowns carry their sourced LAI (6.0 and 3.7,
    // r38c), denser still: lavapipe 0.072 against 0.031 with the sun on the quad, and 7.7 % of
    // the tree pixels in their own shade against 0.4 %; the crowns still shade their far side
    // themselves, at twice the quad's contrast
    // round 46: the profiles' rounder crowns hide each other's shaded sides in this stand (see
    // above): 0.050 against 0.008 with the sun on the quad; bound 0.045 and twice the quad's.
    // Merged with r46c's forked broadleaf crowns and r46v's one-canopy colours: 0.036 against
    // 0.004 with the sun on the quad (9 times its contrast), 32 % of the tree pixels in shadow;
    // bound 0.03 and twice the quad's
    assert!(c1 > 0.03 && c1 > 2.0 * c0, "sun side − far side of the crowns: {c0:.3} before, {c1:.3} now");
    assert!(s1 > s0 + 0.05, "share of tree pixels in their own shade: {s0:.3} before, {s1:.3} now");
    assert!(sd1 > sd0, "canopy luminance sd {sd0:.1} before, {sd1:.1} now");
    // a fine shadow map (texels under a tenth of the crown radius): the quad's own shadow is a
    // fair shaded side (0.25; round 38, with oak's and birch's sourced LAI: 0.157) and is kept
    // as it was
    let ((s0, c0, _, _), (s1, c1, _, _)) = (got[&(320, 10, true)], got[&(320, 10, false)]);
    // round 46: 0.063 with the round-45 crown profiles (the wide tops hide the quads' shaded
    // halves here too; this case takes no crown shade, so round 46's shader leaves it as it is):
    // bound 0.05
    assert!(c1 > 0.05 && (c1 - c0).abs() < 0.01 && (s1 - s0).abs() < 0.01, "fine shadow map: shadow share {s0:.3} before, {s1:.3} now; sun side − far side {c0:.3}, {c1:.3}");
}

/// Share of the pixels of the box `[x0, x1) × [y0, y1)` where `with` differs from `bare`
/// (summed |Δ| of the sRGB channels over 12): the pixels the trees cover.
fn drawn_cover(with: &image::RgbaImage, bare: &image::RgbaImage, (x0, y0, x1, y1): (u32, u32, u32, u32)) -> f64 {
    let mut n = 0usize;
    for y in y0..y1 {
        for x in x0..x1 {
            let (a, b) = (with.get_pixel(x, y).0, bare.get_pixel(x, y).0);
            n += ((0..3).map(|c| (a[c] as i32 - b[c] as i32).abs()).sum::<i32>() > 12) as usize;
        }
    }
    n as f64 / ((x1 - x0) * (y1 - y0)).max(1) as f64
}

/// Share of the square `[lo, hi]²` (m) inside at least one crown disc of `trees` (the union of
/// the inventory's crown discs, as the crown cover of the simulation), sampled on a 0.25 m grid.
fn disc_union(trees: &[(usize, f32, f32, f32, f32, u64)], lo: f32, hi: f32) -> f64 {
    let n = ((hi - lo) / 0.25) as usize;
    let mut hit = vec![false; n * n];
    for &(_, x, y, _, r, _) in trees {
        let cell = |v: f32| ((v - lo) / 0.25).floor();
        let (i0, i1) = (cell(x - r).max(0.0) as usize, (cell(x + r) + 1.0).clamp(0.0, n as f32) as usize);
        let (j0, j1) = (cell(y - r).max(0.0) as usize, (cell(y + r) + 1.0).clamp(0.0, n as f32) as usize);
        for j in j0..j1 {
            for i in i0..i1 {
                let (px, py) = (lo + (i as f32 + 0.5) * 0.25, lo + (j as f32 + 0.5) * 0.25);
                if (px - x).powi(2) + (py - y).powi(2) <= r * r {
                    hit[j * n + i] = true;
                }
            }
        }
    }
    hit.iter().filter(|h| **h).count() as f64 / (n * n).max(1) as f64
}

#[test]
fn the_coarse_levels_from_above_cover_the_crowns_of_the_simulation() {
    // issue 32, round 40 (trial 39): from 150 m up the mid-distance forest was "blobs on white
    // sticks over brown ground, not a closed canopy". Seen from straight above, each coarse level
    // of the stand of [`stand`] (five species in patches, crowns 1.8 radii apart) must cover the
    // union of the crown discs the trees are drawn with (the simulation's crown cover) within
    // ±0.10 over the stand's central 200 m: the crown hull forced on every tree (the reduced
    // level and the billboard are measured and printed). Covered pixels are those that differ
    // from the bare ground drawn the same way (no sun shadows, which fall on the ground beside
    // the crowns).
    let all = SpeciesLibrary::embedded().unwrap();
    let lib = SpeciesLibrary { species: SPECIES.iter().map(|(id, _, _)| all.species[all.find(id).unwrap() as usize].clone()).collect() };
    let protos = sylva::job::scene::prototypes(&lib);
    let trees = stand();
    let (lo, hi) = (60.0f32, 260.0f32);
    let union = disc_union(&trees, lo, hi);
    assert!(union > 0.6 && union < 0.95, "the stand's crown cover {union:.3}");
    with_renderer(|r| {
        still_lod(r);
        r.light_terms = LightTerms::NoShadows;
        let size = 640u32;
        let with = scene(&lib, &protos, &trees, None);
        let mut bare = with.clone();
        bare.instances.clear();
        let cam = Camera::preset(CameraPreset::Map, &with.terrain);
        // the central square's pixel box
        let vp = cam.view_proj(1.0);
        let px = |x: f32, y: f32| {
            let c = vp * Vec3::new(x, y, 0.0).extend(1.0);
            let ndc = c.truncate() / c.w;
            ((ndc.x * 0.5 + 0.5) * size as f32, (0.5 - ndc.y * 0.5) * size as f32)
        };
        let ((x0, y0), (x1, y1)) = (px(lo, hi), px(hi, lo));
        let bx = (x0.round() as u32, y0.round() as u32, x1.round() as u32, y1.round() as u32);
        let bare_img = r.render(&bare, &cam, size, size).unwrap();
        let mut failures = Vec::new();
        for (level, name, switch) in [(1usize, "reduced", [1e9f32, 1.0, 0.5]), (2, "crown hull", [1e9, 1e8, 1.0]), (3, "billboard", [1e9, 1e8, 1e7])] {
            // no triangle budget: it would demote the forced level
            r.lod = sylva::render::lod::LodParams { switch_px: switch, max_triangles: 0, ..r.lod };
            let img = r.render(&with, &cam, size, size).unwrap();
            let s = r.last_stats();
            img.save(out_dir().join(format!("cover_from_above_level{level}.png"))).unwrap();
            let drawn = drawn_cover(&img, &bare_img, bx);
            eprintln!("level {level} ({name}): drawn cover {drawn:.3}, crown discs {union:.3}, per level {:?}", s.per_level);
            assert_eq!(s.per_level[level], s.instances_drawn, "every tree drawn at level {level}: {:?}", s.per_level);
            // the reduced level's leaf-cluster cards are grown towards the crown disc's plan
            // area too (render::lod::card_spread: 0.48 → 0.61 here) but stay short of it, and
            // the billboards keep their look (0.70; shaders/scene.wgsl BB_TOP_R: the far-field
            // canopy layer is matched to them); the crown hull, the mid-distance level, is held
            // to the crown cover
            if level == 2 && (drawn - union).abs() > 0.10 {
                failures.push(format!("{name}: cover from above {drawn:.3}, the crown discs' {union:.3}"));
            }
        }
        r.light_terms = LightTerms::All;
        still_lod(r);
        assert!(failures.is_empty(), "{failures:#?}");
    });
}

