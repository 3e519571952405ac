//! How much of a drawn tree's crown its wood and foliage cover, seen from the side and from
//! above (issue 32, round 37: the stand spruces of Blender were poles with few limbs, whatever
//! their leaf area). The full level of an adapted tree (bark triangles, and leaf or leaf-cluster
//! cards alpha-tested with their texture as glTF `alphaMode: MASK` draws them) is rasterised by
//! orthographic projection on a grid and compared with the crown the simulation gives the tree:
//! its disc `π R²` from above, and from the side its silhouette between the crown base and the
//! top, a cone for a conifer (half-width `R (h − z)/(h − cb)` at height z) and a cylinder
//! (half-width R) otherwise.

use crate::mesh::TriMesh;
use glam::{Vec2, Vec3};
use image::RgbaImage;

/// Shape of the crown silhouette the side cover is taken over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Silhouette {
    /// A cone from the crown base (radius R) to the top (a conifer's excurrent crown).
    Cone,
    /// A cylinder of radius R from the crown base to the top.
    Cylinder,
}

/// The crown the cover is measured against (m; the tree's frame: stem base at the origin, z up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrownShape {
    /// Height of the top (m, > crown base).
    pub height_m: f32,
    /// Crown base (m, ≥ 0).
    pub crown_base_m: f32,
    /// Crown radius R (m, > 0).
    pub crown_radius_m: f32,
    /// Side silhouette.
    pub silhouette: Silhouette,
}

/// Cover of a crown by a drawn tree (shares 0–1 of the crown's disc and silhouette whose
/// pixels a triangle covers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrownCover {
    /// Share of the crown disc covered seen from straight above.
    pub top: f32,
    /// Share of the side silhouette covered seen along +y (mean of the views along x and y).
    pub side: f32,
}

/// Pixels across the crown diameter of [`crown_cover`]'s grids.
pub const COVER_PX: usize = 160;

/// Rasterises the meshes `layers` — each with its texture: `None` for bark (every pixel a
/// triangle covers counts), `Some(picture)` for cards (a pixel counts where the picture, UV
/// 0–1 over each card as [`crate::structure::mesh`] builds them, v down the picture as in glTF,
/// a u beyond 1 taken modulo 1 so that cluster cards marked by [`crate::mesh::CLUSTER_CARD_U`]
/// read it the same, has alpha ≥ [`crate::structure::texture::ALPHA_CUTOFF`]) — onto
/// grids of [`COVER_PX`] pixels across the crown's diameter, from above and from two sides (x
/// and y), and returns the shares of the crown's disc and side silhouette ([`CrownShape`])
/// covered. Deterministic.
pub fn crown_cover(layers: &[(&TriMesh, Option<&RgbaImage>)], crown: &CrownShape) -> CrownCover {
    cover_grids(layers, crown).0
}

/// [`crown_cover`] with its grids as pictures (for looking at them): from above ([`COVER_PX`]²)
/// and from the side along y (crown base at the bottom), covered pixels dark green, the crown's
/// disc or silhouette left uncovered light grey, outside white.
pub fn cover_pictures(layers: &[(&TriMesh, Option<&RgbaImage>)], crown: &CrownShape) -> (CrownCover, RgbaImage, RgbaImage) {
    cover_grids(layers, crown)
}

fn cover_grids(layers: &[(&TriMesh, Option<&RgbaImage>)], crown: &CrownShape) -> (CrownCover, RgbaImage, RgbaImage) {
    let r = crown.crown_radius_m.max(1e-3);
    let len = (crown.height_m - crown.crown_base_m).max(1e-3);
    let px = 2.0 * r / COVER_PX as f32;
    let nz = (len / px).ceil() as usize;
    // top: x, y over [-R, R]²
    let top = Grid::new(COVER_PX, COVER_PX, Vec2::new(-r, -r), px);
    let side = Grid::new(COVER_PX, nz, Vec2::new(-r, crown.crown_base_m), px);
    let mut g_top = vec![false; COVER_PX * COVER_PX];
    let mut g_x = vec![false; COVER_PX * nz];
    let mut g_y = vec![false; COVER_PX * nz];
    for &(mesh, tex) in layers {
        for t in mesh.indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|i| Vec3::from(mesh.positions[t[i] as usize]));
            let uv = [0, 1, 2].map(|i| mesh.uvs.get(t[i] as usize).map_or(Vec2::ZERO, |u| Vec2::from(*u)));
            let keep = |b: [f32; 3]| match tex {
                None => true,
                Some(img) => {
                    let u = b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2];
                    let (w, h) = (img.width(), img.height());
                    let x = ((u.x.rem_euclid(1.0)) * w as f32).min(w as f32 - 1.0) as u32;
                    let y = (u.y.clamp(0.0, 1.0) * h as f32).min(h as f32 - 1.0) as u32;
                    img.get_pixel(x, y).0[3] as f32 >= crate::structure::texture::ALPHA_CUTOFF * 255.0
                }
            };
            top.fill(&mut g_top, [p[0].truncate(), p[1].truncate(), p[2].truncate()], keep);
            side.fill(&mut g_x, [Vec2::new(p[0].x, p[0].z), Vec2::new(p[1].x, p[1].z), Vec2::new(p[2].x, p[2].z)], keep);
            side.fill(&mut g_y, [Vec2::new(p[0].y, p[0].z), Vec2::new(p[1].y, p[1].z), Vec2::new(p[2].y, p[2].z)], keep);
        }
    }
    let paint = |hit: bool, inside: bool| image::Rgba(if hit { [30, 80, 40, 255] } else if inside { [210, 210, 210, 255] } else { [255, 255, 255, 255] });
    let mut pic_top = RgbaImage::new(COVER_PX as u32, COVER_PX as u32);
    let mut pic_side = RgbaImage::new(COVER_PX as u32, nz as u32);
    let (mut disc, mut disc_hit) = (0usize, 0usize);
    for j in 0..COVER_PX {
        for i in 0..COVER_PX {
            let inside = top.centre(i, j).length() <= r;
            if inside {
                disc += 1;
                disc_hit += g_top[j * COVER_PX + i] as usize;
            }
            pic_top.put_pixel(i as u32, (COVER_PX - 1 - j) as u32, paint(g_top[j * COVER_PX + i], inside));
        }
    }
    let (mut sil, mut sil_hit) = (0usize, 0usize);
    for j in 0..nz {
        for i in 0..COVER_PX {
            let c = side.centre(i, j);
            let half = match crown.silhouette {
                Silhouette::Cone => r * (crown.height_m - c.y) / len,
                Silhouette::Cylinder => r,
            };
            let inside = c.y <= crown.height_m && c.x.abs() <= half;
            if inside {
                sil += 2;
                sil_hit += g_x[j * COVER_PX + i] as usize + g_y[j * COVER_PX + i] as usize;
            }
            pic_side.put_pixel(i as u32, (nz - 1 - j) as u32, paint(g_x[j * COVER_PX + i], inside));
        }
    }
    (CrownCover { top: disc_hit as f32 / disc.max(1) as f32, side: sil_hit as f32 / sil.max(1) as f32 }, pic_top, pic_side)
}

/// A pixel grid of `w × h` pixels of side `px` whose corner (pixel (0, 0)'s lower left) is `o`.
struct Grid {
    w: usize,
    h: usize,
    o: Vec2,
    px: f32,
}

impl Grid {
    fn new(w: usize, h: usize, o: Vec2, px: f32) -> Grid {
        Grid { w, h, o, px }
    }
    fn centre(&self, i: usize, j: usize) -> Vec2 {
        self.o + Vec2::new((i as f32 + 0.5) * self.px, (j as f32 + 0.5) * self.px)
    }
    /// Marks the pixels whose centre lies in triangle `p` (either winding) and `keep` accepts at
    /// the centre's barycentric coordinates.
    fn fill(&self, g: &mut [bool], p: [Vec2; 3], keep: impl Fn([f32; 3]) -> bool) {
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area.abs() < 1e-12 {
            return;
        }
        let lo = p[0].min(p[1]).min(p[2]);
        let hi = p[0].max(p[1]).max(p[2]);
        let i0 = (((lo.x - self.o.x) / self.px - 0.5).ceil().max(0.0)) as usize;
        let j0 = (((lo.y - self.o.y) / self.px - 0.5).ceil().max(0.0)) as usize;
        let i1 = ((hi.x - self.o.x) / self.px - 0.5).floor();
        let j1 = ((hi.y - self.o.y) / self.px - 0.5).floor();
        if i1 < 0.0 || j1 < 0.0 {
            return;
        }
        let (i1, j1) = ((i1 as usize).min(self.w.saturating_sub(1)), (j1 as usize).min(self.h.saturating_sub(1)));
        for j in j0..=j1 {
            for i in i0..=i1 {
                if g[j * self.w + i] {
                    continue;
                }
                let c = self.centre(i, j);
                let b1 = (c - p[0]).perp_dot(p[2] - p[0]) / area;
                let b2 = (p[1] - p[0]).perp_dot(c - p[0]) / area;
                let b0 = 1.0 - b1 - b2;
                if b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 && keep([b0, b1, b2]) {
                    g[j * self.w + i] = true;
                }
            }
        }
    }
}

/// The cover of the full level of adapted tree `a` (of stand tree `t`, species `sp`) as the stand
/// export draws it ([`super::export::export_stand`] at full detail): bark of level 0, and for a
/// conifer its crossed shoot cards ([`super::leaf_area::shoot_cards`], the leaf-cluster picture),
/// for a broadleaf its leaf cards (the leaf picture) and sprigs ([`super::adapted::crown_leaf_cards`],
/// the cluster picture); against the crown of `t` (a cone for a conifer, a cylinder otherwise).
/// `None` for a tree under 0.1 m.
pub fn drawn_cover(a: &crate::structure::stand::AdaptedTree, t: &crate::structure::stand::StandTree, sp: &crate::species::Species) -> Option<CrownCover> {
    drawn_cover_pictures(a, t, sp).map(|c| c.0)
}

/// [`drawn_cover`] with [`cover_pictures`]'s pictures (from above, from the side).
pub fn drawn_cover_pictures(a: &crate::structure::stand::AdaptedTree, t: &crate::structure::stand::StandTree, sp: &crate::species::Species) -> Option<(CrownCover, RgbaImage, RgbaImage)> {
    use crate::structure::texture::{cluster_texture, leaf_texture, LeafShape};
    let (sk, mut lv, _) = super::adapted::tree_frame(a, t.base)?;
    let (card, sprig) = super::leaf_area::card_covers(sp);
    let shape = LeafShape::of_species(sp);
    let needles = shape.is_needle();
    let sprigs = if needles {
        super::leaf_area::shoot_cards_with_sprays(&sk, &lv, super::leaf_area::drawn_leaf_area(sp, t.crown_radius_m), sprig, t.crown_radius_m, t.species as u64, super::leaf_area::limb_spray(sp)).mesh
    } else {
        let cover = super::adapted::LeafCover { card: vec![card; t.species as usize + 1], sprig: vec![sprig; t.species as usize + 1] };
        super::adapted::crown_leaf_cards(&mut lv, t, sp, &cover)
    };
    let (chain, _) = super::adapted::adapted_lod_chain(&sk, &lv, a, t.base, 1.0, &crate::structure::mesh::LodOptions::default());
    let (leaf_pic, cluster_pic) = (leaf_texture(shape), cluster_texture(shape, 128));
    let empty = TriMesh::default();
    let leaves = if needles { &empty } else { &chain.levels[0].leaves };
    let crown = CrownShape {
        height_m: t.height_m,
        crown_base_m: t.crown_base_m,
        crown_radius_m: t.crown_radius_m,
        silhouette: if needles { Silhouette::Cone } else { Silhouette::Cylinder },
    };
    Some(cover_grids(&[(&chain.levels[0].bark, None), (leaves, Some(&leaf_pic)), (&sprigs, Some(&cluster_pic))], &crown))
}
