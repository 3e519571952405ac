//! The PNG preview `sylva tree grow` writes beside a tree: side views of every level of its LOD
//! chain, drawn on the CPU with the textures of its [`Look`] (the ones the `.glb` carries), so the
//! preview shows what a viewer of the `.glb` sees.
//!
//! Each level is seen along +y (orthographic, z up), scaled to fit its panel, z-buffered and
//! Lambert-shaded by the face normal (both sides lit, as the double-sided cards are). Texture
//! coordinates follow [`crate::output::gltf`]: the bark and LOD2 crown textures repeat (the crown
//! [`gltf::CROWN_REPEAT`] times round and up the hull), the leaf, leaf-cluster and billboard cards
//! clamp and are alpha-tested at [`ALPHA_CUTOFF`] (glTF `alphaMode: MASK`): a texel below the
//! cutoff leaves the pixel behind it (the background, or whatever is further back) unchanged.
//! Sampling is nearest-texel.

use crate::mesh::{LodChain, TreeMesh, TriMesh};
use crate::output::gltf::{self, Look};
use crate::structure::texture::ALPHA_CUTOFF;
use glam::Vec3;
use image::{Rgb, RgbImage, RgbaImage};

/// Background of the preview panels (sRGB): a light sky blue.
pub const BACKGROUND: [u8; 3] = [205, 225, 240];

/// Margin (pixels) between a level's drawing and its panel's edges.
const MARGIN: f32 = 10.0;

/// Side views of every level of `chain`, side by side, each in a `w × h` pixel panel (image
/// `w · levels × h`; one blank panel for an empty chain), on [`BACKGROUND`]: the bark of levels
/// 0–2 with `look`'s bark texture, the foliage of level 0 with its leaf card, level 1 its
/// leaf-cluster card, level 2 its crown texture and levels ≥ 3 its billboard (module
/// documentation). Each level is scaled on its own to fit its panel less a 10-pixel margin.
pub fn lod_preview(chain: &LodChain, look: &Look, w: u32, h: u32) -> RgbImage {
    let n = chain.levels.len().max(1) as u32;
    let mut img = RgbImage::from_pixel(w * n, h, Rgb(BACKGROUND));
    for (li, level) in chain.levels.iter().enumerate() {
        draw_level(&mut img, level, li, look, li as u32 * w, w, h);
    }
    img
}

/// How a part of a level is textured.
struct Skin<'a> {
    img: &'a RgbaImage,
    /// Multiplies the mesh's texture coordinates (as in the `.glb`).
    uv_scale: [f32; 2],
    /// Repeat (true) or clamp (false) outside 0–1.
    repeat: bool,
    /// Alpha-tested at [`ALPHA_CUTOFF`].
    mask: bool,
}

impl Skin<'_> {
    /// The texel at mesh texture coordinates `(u, v)` (v up, as the meshes store it; the image's
    /// row 0 is its top, as in glTF).
    fn sample(&self, u: f32, v: f32) -> [u8; 4] {
        let (tw, th) = self.img.dimensions();
        let (mut s, mut t) = (u * self.uv_scale[0], 1.0 - v * self.uv_scale[1]);
        if self.repeat {
            s = s.rem_euclid(1.0);
            t = t.rem_euclid(1.0);
        } else {
            s = s.clamp(0.0, 1.0);
            t = t.clamp(0.0, 1.0);
        }
        let x = ((s * tw as f32) as u32).min(tw - 1);
        let y = ((t * th as f32) as u32).min(th - 1);
        self.img.get_pixel(x, y).0
    }
}

/// Side views of the full level (level 0) of several trees at ONE scale, side by side, each in a
/// `w × h` pixel panel (image `w · trees × h`) on [`BACKGROUND`], the ground of every panel at
/// the same row, with a dark tick on the left edge of every panel every 5 m of height: trees of
/// different ages or species compare by size, which [`lod_preview`] (each level scaled to fit)
/// does not show. The scale is that of the tallest tree (or of `min_height_m`, m, if taller)
/// filling a panel's height less the margins. Trees are centred on their base's x.
pub fn same_scale_preview(trees: &[(&TreeMesh, &Look)], w: u32, h: u32, min_height_m: f32) -> RgbImage {
    let n = trees.len().max(1) as u32;
    let mut img = RgbImage::from_pixel(w * n, h, Rgb(BACKGROUND));
    let tallest = trees
        .iter()
        .filter_map(|(m, _)| crate::mesh::points_bounds(m.bark.positions.iter().chain(&m.leaves.positions)))
        .map(|(lo, hi)| hi[2] - lo[2].min(0.0))
        .fold(min_height_m.max(1e-3), f32::max);
    let s = (h as f32 - 2.0 * MARGIN) / tallest;
    for (i, (m, look)) in trees.iter().enumerate() {
        let x0 = i as u32 * w;
        draw_level_at(&mut img, m, 0, look, x0, w, h, Some((s, 0.0, 0.0)));
        let mut z = 0.0;
        while z <= tallest + 1e-3 {
            let y = (h as f32 - MARGIN - z * s).round();
            if y >= 0.0 && (y as u32) < h {
                for x in x0..(x0 + 8).min(img.width()) {
                    img.put_pixel(x, y as u32, Rgb([40, 40, 40]));
                }
            }
            z += 5.0;
        }
    }
    img
}

/// Side view (along +y, as [`lod_preview`] draws it) of level `level` of `chain` in a `w × h`
/// picture on [`BACKGROUND`], at the scale and place where level 0 (the full level) fits the
/// picture less the margins: the levels' views lie on top of each other, so their outlines and
/// coverage compare pixel for pixel (issue 32, round 46: `tests/lod_agreement.rs`). A blank
/// picture for a level the chain lacks or an empty full level.
pub fn level_view(chain: &LodChain, look: &Look, level: usize, w: u32, h: u32) -> RgbImage {
    let mut img = RgbImage::from_pixel(w, h, Rgb(BACKGROUND));
    let (Some(full), Some(m)) = (chain.levels.first(), chain.levels.get(level)) else { return img };
    let Some((lo, hi)) = crate::mesh::points_bounds(full.bark.positions.iter().chain(&full.leaves.positions)) else { return img };
    let s = ((w as f32 - 2.0 * MARGIN) / (hi[0] - lo[0]).max(1e-3)).min((h as f32 - 2.0 * MARGIN) / (hi[2] - lo[2]).max(1e-3));
    draw_level_at(&mut img, m, level, look, 0, w, h, Some((s, 0.5 * (lo[0] + hi[0]), lo[2])));
    img
}

fn draw_level(img: &mut RgbImage, m: &TreeMesh, level: usize, look: &Look, x0: u32, w: u32, h: u32) {
    draw_level_at(img, m, level, look, x0, w, h, None)
}

/// [`draw_level`] at scale `fixed` = (pixels per metre, centre x, ground z) when given, else
/// scaled to fit its panel.
#[allow(clippy::too_many_arguments)]
fn draw_level_at(img: &mut RgbImage, m: &TreeMesh, level: usize, look: &Look, x0: u32, w: u32, h: u32, fixed: Option<(f32, f32, f32)>) {
    let Some((lo, hi)) = crate::mesh::points_bounds(m.bark.positions.iter().chain(&m.leaves.positions)) else { return };
    let (s, cx, z0) = fixed.unwrap_or_else(|| (((w as f32 - 2.0 * MARGIN) / (hi[0] - lo[0]).max(1e-3)).min((h as f32 - 2.0 * MARGIN) / (hi[2] - lo[2]).max(1e-3)), 0.5 * (lo[0] + hi[0]), lo[2]));
    let to_px = |p: [f32; 3]| -> [f32; 3] { [x0 as f32 + w as f32 * 0.5 + (p[0] - cx) * s, h as f32 - MARGIN - (p[2] - z0) * s, p[1]] };
    let t = &look.textures;
    let bark = Skin { img: &t.bark, uv_scale: [1.0, 1.0], repeat: true, mask: false };
    let foliage = match level {
        0 => Skin { img: &t.leaf, uv_scale: [1.0, 1.0], repeat: false, mask: true },
        1 => Skin { img: &t.cluster, uv_scale: [1.0, 1.0], repeat: false, mask: true },
        2 => Skin { img: &t.crown, uv_scale: gltf::CROWN_REPEAT, repeat: true, mask: false },
        _ => Skin { img: &t.impostor, uv_scale: [1.0, 1.0], repeat: false, mask: true },
    };
    let mut zbuf = vec![f32::MAX; (w * h) as usize];
    let light = Vec3::new(-0.4, -0.6, 0.7).normalize();
    // the full level's leaf-cluster cards (a lone tree's crown leaf area) with the cluster card
    let (cards, sprigs) = if level == 0 && m.leaves.has_cluster_cards() { m.leaves.split_cluster_cards() } else { (m.leaves.clone(), TriMesh::default()) };
    let cluster = Skin { img: &t.cluster, uv_scale: [1.0, 1.0], repeat: false, mask: true };
    for (mesh, skin) in [(&m.bark, &bark), (&cards, &foliage), (&sprigs, &cluster)] {
        draw_mesh(img, &mut zbuf, mesh, skin, &to_px, light, x0, w, h);
    }
}

#[allow(clippy::too_many_arguments)]
fn draw_mesh(img: &mut RgbImage, zbuf: &mut [f32], mesh: &TriMesh, skin: &Skin, to_px: &dyn Fn([f32; 3]) -> [f32; 3], light: Vec3, x0: u32, w: u32, h: u32) {
    let has_uv = mesh.uvs.len() == mesh.positions.len();
    for t in mesh.indices.chunks_exact(3) {
        let [ia, ib, ic] = [t[0] as usize, t[1] as usize, t[2] as usize];
        let (a, b, c) = (to_px(mesh.positions[ia]), to_px(mesh.positions[ib]), to_px(mesh.positions[ic]));
        let nrm = Vec3::from(mesh.normals[ia]) + Vec3::from(mesh.normals[ib]) + Vec3::from(mesh.normals[ic]);
        let shade = 0.35 + 0.65 * nrm.normalize_or(Vec3::Z).dot(light).abs();
        let uv = |i: usize| if has_uv { mesh.uvs[i] } else { [0.5, 0.5] };
        let (ua, ub, uc) = (uv(ia), uv(ib), uv(ic));
        let minx = a[0].min(b[0]).min(c[0]).floor().max(x0 as f32) as i64;
        let maxx = a[0].max(b[0]).max(c[0]).ceil().min((x0 + w - 1) as f32) as i64;
        let miny = a[1].min(b[1]).min(c[1]).floor().max(0.0) as i64;
        let maxy = a[1].max(b[1]).max(c[1]).ceil().min((h - 1) as f32) as i64;
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        let shaded = |texel: [u8; 4]| Rgb([0, 1, 2].map(|k| (texel[k] as f32 * shade) as u8));
        if area.abs() < 1e-9 {
            // seen edge-on: a twig keeps one pixel so it stays visible; a card seen edge-on
            // (alpha-tested) is not drawn, as a renderer draws nothing of it
            if !skin.mask && minx <= maxx && miny <= maxy {
                img.put_pixel(minx as u32, miny as u32, shaded(skin.sample(ua[0], ua[1])));
            }
            continue;
        }
        for y in miny..=maxy {
            for x in minx..=maxx {
                let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                let w0 = ((b[0] - fx) * (c[1] - fy) - (c[0] - fx) * (b[1] - fy)) / area;
                let w1 = ((c[0] - fx) * (a[1] - fy) - (a[0] - fx) * (c[1] - fy)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                let zi = (y as u32 * w + (x as u32 - x0)) as usize;
                if z >= zbuf[zi] {
                    continue;
                }
                let texel = skin.sample(w0 * ua[0] + w1 * ub[0] + w2 * uc[0], w0 * ua[1] + w1 * ub[1] + w2 * uc[1]);
                if skin.mask && (texel[3] as f32) < ALPHA_CUTOFF * 255.0 {
                    continue;
                }
                zbuf[zi] = z;
                img.put_pixel(x as u32, y as u32, shaded(texel));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::texture::{BarkPattern, LeafShape};

    /// A look with plain colours and `shape`'s textures.
    fn look(shape: LeafShape) -> Look {
        Look::plain("t", [110, 80, 50], [40, 110, 40], shape, BarkPattern::Smooth)
    }

    /// A chain of one level: the billboard quad `[-1, 1] × [0, 4]` m (x, z) facing −y, UV 0–1
    /// over it (v up), as [`crate::structure::mesh::impostor_mesh`] makes it.
    fn billboard_chain() -> LodChain {
        let leaves = TriMesh {
            positions: vec![[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 4.0], [-1.0, 0.0, 4.0]],
            normals: vec![[0.0, -1.0, 0.0]; 4],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            indices: vec![0, 1, 2, 0, 2, 3],
        };
        let mut levels = vec![TreeMesh::default(); 3];
        levels.push(TreeMesh { bark: TriMesh::default(), leaves });
        LodChain { levels, ..LodChain::default() }
    }

    /// The billboard panel shows the impostor texture alpha-tested: inside its quad, the pixels
    /// whose texel is below the cutoff are background, the others are drawn (a flat-filled
    /// rectangle, what the preview drew before, has no background inside the quad).
    #[test]
    fn billboard_is_alpha_tested_not_a_filled_rectangle() {
        let lk = look(LeafShape::Ovate);
        let (w, h) = (120u32, 250u32);
        let img = lod_preview(&billboard_chain(), &lk, w, h);
        assert_eq!(img.dimensions(), (4 * w, h));
        // the 2 m × 4 m quad fits the panel's width less the margins (50 px/m), centred,
        // its foot on the bottom margin
        let s = ((w as f32 - 2.0 * MARGIN) / 2.0).min((h as f32 - 2.0 * MARGIN) / 4.0);
        assert_eq!(s, 50.0);
        let (qx0, qx1) = ((3 * w) as f32 + w as f32 * 0.5 - s, (3 * w) as f32 + w as f32 * 0.5 + s);
        let (qy0, qy1) = (h as f32 - MARGIN - 4.0 * s, h as f32 - MARGIN);
        let skin = Skin { img: &lk.textures.impostor, uv_scale: [1.0, 1.0], repeat: false, mask: true };
        let (mut bg_where_clear, mut clear, mut drawn_where_opaque, mut opaque) = (0, 0, 0, 0);
        for y in (qy0 as u32 + 1)..(qy1 as u32 - 1) {
            for x in (qx0.max((3 * w) as f32) as u32 + 1)..(qx1.min((4 * w) as f32) as u32 - 1) {
                let (u, v) = ((x as f32 + 0.5 - qx0) / (qx1 - qx0), 1.0 - (y as f32 + 0.5 - qy0) / (qy1 - qy0));
                let a = skin.sample(u, v)[3] as f32 / 255.0;
                let bg = img.get_pixel(x, y).0 == BACKGROUND;
                // texels right at the cutoff may round either way at a pixel's centre
                if a < ALPHA_CUTOFF - 0.1 {
                    clear += 1;
                    bg_where_clear += bg as u32;
                } else if a > ALPHA_CUTOFF + 0.1 {
                    opaque += 1;
                    drawn_where_opaque += !bg as u32;
                }
            }
        }
        assert!(clear > 500 && opaque > 500, "the impostor texture has clear and opaque parts: {clear} clear, {opaque} opaque pixels");
        assert!(bg_where_clear as f64 >= 0.95 * clear as f64, "background shows where the billboard texture is clear: {bg_where_clear} of {clear}");
        assert!(drawn_where_opaque as f64 >= 0.95 * opaque as f64, "the billboard is drawn where its texture is opaque: {drawn_where_opaque} of {opaque}");
        // the other (empty) panels stay background
        assert!((0..3 * w).all(|x| (0..h).all(|y| img.get_pixel(x, y).0 == BACKGROUND)));
    }

    /// Drawn pixels take the texture's colour (the leaf colour baked in), shaded by at most
    /// the Lambert factor: no pixel is brighter than the texture's brightest texel.
    #[test]
    fn drawn_pixels_are_the_texture_colours_shaded() {
        let lk = look(LeafShape::NeedleLong);
        let img = lod_preview(&billboard_chain(), &lk, 120, 250);
        let max_g = lk.textures.impostor.pixels().filter(|p| p.0[3] >= 128).map(|p| p.0[1]).max().unwrap();
        let drawn: Vec<[u8; 3]> = img.pixels().map(|p| p.0).filter(|p| *p != BACKGROUND).collect();
        assert!(!drawn.is_empty());
        // leaf-green crown pixels, and the trunk in the bark's brown (round 36: it was drawn in
        // 0.3 × the leaf colour, nearly black)
        let leafy = |p: &[u8; 3]| p[1] <= max_g && p[1] >= p[0] && p[1] >= p[2];
        let barky = |p: &[u8; 3]| p[0] > p[1] && p[1] > p[2];
        assert!(drawn.iter().all(|p| leafy(p) || barky(p)), "leaf-green or bark-brown pixels only");
        assert!(drawn.iter().any(|p| barky(p)) && drawn.iter().filter(|p| leafy(p)).count() > drawn.len() / 2);
    }
}
