//! Issue 32, round 46 (trial 45, defects 1–3): a tree's four levels of detail draw the same tree.
//! Each level of the chain `sylva tree grow` writes is drawn from the side at the full level's
//! scale and place (`output::tree_preview::level_view`, the preview's own rasteriser and the
//! `.glb`'s textures), and compared with the full level (LOD0):
//! - the outline: the intersection over union of the levels' row envelopes (per picture row,
//!   from its first to its last drawn pixel), so a sparse crown's gaps do not count, only its
//!   shape: a spruce's spire, a Scots pine's V, a beech's dome;
//! - the coverage of the billboard: the drawn share of its crown's envelope against the full
//!   level's (trial 45: "birch 40, beech 80, oak 120: LOD0 sparse, the billboard a full, opaque
//!   ellipse");
//! - the billboard's trunk: as bright as the full level's (trial 45: a birch's was grey).
//!
//! The trees are the trial's (beech 80, Norway spruce 60, Scots pine 100, silver birch 40,
//! stand-grown, seed 1) with the EcoMod model's own leaves (`structure::mesh::lod_chain`; the
//! command's hero leaves only add detail to level 0).

use sylva::output::gltf::Look;
use sylva::output::tree_preview::{level_view, BACKGROUND};
use sylva::species::{Season, SpeciesLibrary};
use sylva::structure::forest_form::{grow_formed_tree, Habit};
use sylva::structure::mesh::{lod_chain, LodOptions};
use sylva::structure::species_tree::Model;

const W: u32 = 240;
const H: u32 = 360;

struct Views {
    /// per level: drawn mask (W × H, row-major)
    mask: Vec<Vec<bool>>,
    /// per level: the picture
    img: Vec<image::RgbImage>,
}

fn views(id: &str, age: f32, species_texture: bool) -> Views {
    let lib = SpeciesLibrary::embedded().unwrap();
    let sp = lib.species.iter().find(|s| s.id == id).unwrap();
    let (grown, _) = grow_formed_tree(sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
    let chain = lod_chain(&grown.skeleton, &grown.leaves, &LodOptions::for_species(sp));
    let look = Look::for_species(sp, Season::Summer);
    let look = if species_texture { look } else { look.with_tree_impostor(&chain) };
    let img: Vec<image::RgbImage> = (0..4).map(|l| level_view(&chain, &look, l, W, H)).collect();
    let mask = img.iter().map(|im| im.pixels().map(|p| p.0 != BACKGROUND).collect()).collect();
    Views { mask, img }
}

/// Row envelope of a mask: per row, every pixel from the first to the last drawn one.
fn envelope(m: &[bool]) -> Vec<bool> {
    let mut e = vec![false; m.len()];
    for y in 0..H as usize {
        let row = &m[y * W as usize..(y + 1) * W as usize];
        if let (Some(a), Some(b)) = (row.iter().position(|&v| v), row.iter().rposition(|&v| v)) {
            e[y * W as usize + a..=y * W as usize + b].iter_mut().for_each(|v| *v = true);
        }
    }
    e
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let i = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let u = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    i as f64 / u.max(1) as f64
}

/// Rows of the crown: where the full level's envelope is wider than 6 % of the picture.
fn crown_rows(full: &[bool]) -> Vec<usize> {
    let e = envelope(full);
    (0..H as usize).filter(|&y| e[y * W as usize..(y + 1) * W as usize].iter().filter(|&&v| v).count() > (W as usize * 6) / 100).collect()
}

/// Drawn share of the envelope over `rows`.
fn coverage(m: &[bool], rows: &[usize]) -> f64 {
    let e = envelope(m);
    let (mut d, mut n) = (0usize, 0usize);
    for &y in rows {
        for x in 0..W as usize {
            let k = y * W as usize + x;
            if e[k] {
                n += 1;
                d += m[k] as usize;
            }
        }
    }
    d as f64 / n.max(1) as f64
}

/// The trial's trees: the billboard (LOD3) has the full level's outline, the crown hull (LOD2)
/// its profile. Measured (r46b, this test): billboard IoU beech 0.769, Norway spruce 0.961,
/// Scots pine 0.753, silver birch 0.797, where the species' picture (main's billboard, drawn in
/// the same run) gives 0.495, 0.719, 0.424 (the pine's V drawn as a cone), 0.284: bound 0.74.
/// The hull: the spruce's top ring under 0.3 of its widest (a spire), the Scots pine's widest
/// ring in the crown's upper half (its flat top); hull IoU (the full level's envelope is jagged
/// where its model leaves are few: birch 0.341, beech 0.507, spruce 0.744, pine 0.732) at
/// least 0.3.
#[test]
fn the_coarse_levels_have_the_full_levels_outline() {
    for (id, age) in [("beech", 80.0), ("norway_spruce", 60.0), ("scots_pine", 100.0), ("silver_birch", 40.0)] {
        let v = views(id, age, false);
        let old = views(id, age, true);
        let e0 = envelope(&v.mask[0]);
        let (i2, i3, i3_species) = (iou(&e0, &envelope(&v.mask[2])), iou(&e0, &envelope(&v.mask[3])), iou(&e0, &envelope(&old.mask[3])));
        eprintln!("{id} {age}: outline IoU with the full level: hull {i2:.3}, billboard {i3:.3} (the species' billboard picture {i3_species:.3})");
        for (l, im) in v.img.iter().enumerate() {
            im.save(std::env::temp_dir().join(format!("lod_agreement_{id}_{l}.png"))).unwrap();
        }
        assert!(i3 > 0.74, "{id}: billboard outline IoU {i3:.3} (the species' picture {i3_species:.3})");
        assert!(i2 > 0.3, "{id}: hull outline IoU {i2:.3}");
        // the hull's ring radii (mean over the sectors), bottom to top
        let lib = SpeciesLibrary::embedded().unwrap();
        let sp = lib.species.iter().find(|s| s.id == id).unwrap();
        let (grown, _) = grow_formed_tree(sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
        let o = LodOptions::for_species(sp);
        let hull = sylva::structure::mesh::hull_mesh(&grown.skeleton, &grown.leaves, &o).leaves;
        let nl = o.hull_segments as usize;
        let r: Vec<f32> = (0..sylva::structure::mesh::HULL_RING_HEIGHTS.len())
            .map(|b| {
                let ring = &hull.positions[b * nl..(b + 1) * nl];
                let (cx, cy) = (ring.iter().map(|p| p[0]).sum::<f32>() / nl as f32, ring.iter().map(|p| p[1]).sum::<f32>() / nl as f32);
                ring.iter().map(|p| ((p[0] - cx).powi(2) + (p[1] - cy).powi(2)).sqrt()).sum::<f32>() / nl as f32
            })
            .collect();
        let widest = (0..r.len()).max_by(|&a, &b| r[a].total_cmp(&r[b])).unwrap();
        eprintln!("{id}: hull ring radii {r:?}");
        match id {
            "norway_spruce" => assert!(r[r.len() - 1] < 0.3 * r[widest], "{id}: a spire: {r:?}"),
            "scots_pine" => assert!(widest >= r.len() / 2, "{id}: a flat top: {r:?}"),
            _ => {}
        }
    }
}

/// The billboard's coverage follows the full level's, and its trunk is as bright: measured
/// (r46b) coverage beech 80 0.281 against the full level's 0.274, silver birch 40 0.300 against
/// 0.286, sessile oak 120 0.526 against 0.525, where the species' picture gives 0.79, 0.78,
/// 0.80; the trunk's luma 1.13, 1.10, 1.06 of the full level's (main's bark × 0.85: 0.96, 0.94,
/// 0.90).
#[test]
fn the_billboard_has_the_full_levels_coverage_and_bark() {
    for (id, age) in [("beech", 80.0), ("silver_birch", 40.0), ("sessile_oak", 120.0)] {
        let v = views(id, age, false);
        let old = views(id, age, true);
        let rows = crown_rows(&v.mask[0]);
        let (c0, c3, c3_species) = (coverage(&v.mask[0], &rows), coverage(&v.mask[3], &rows), coverage(&old.mask[3], &rows));
        // trunk brightness: the drawn pixels of the lowest quarter of the picture
        let lum = |im: &image::RgbImage, m: &[bool]| {
            let (mut s, mut n) = (0.0f64, 0usize);
            for y in (3 * H / 4)..H - 12 {
                for x in 0..W {
                    if m[(y * W + x) as usize] {
                        let p = im.get_pixel(x, y).0;
                        s += 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
                        n += 1;
                    }
                }
            }
            s / n.max(1) as f64
        };
        let (t0, t3) = (lum(&v.img[0], &v.mask[0]), lum(&v.img[3], &v.mask[3]));
        eprintln!("{id} {age}: coverage full {c0:.3}, billboard {c3:.3} (species' picture {c3_species:.3}); trunk luma full {t0:.1}, billboard {t3:.1}");
        assert!((c3 - c0).abs() < 0.05, "{id}: billboard coverage {c3:.3} against the full level's {c0:.3} (species' picture {c3_species:.3})");
        assert!(t3 > 0.98 * t0 && t3 < 1.25 * t0, "{id}: billboard trunk luma {t3:.1} against the full level's {t0:.1}");
    }
}
