//! Procedural leaf and bark textures (issue 19, Build 5), made by Sylva from the species file:
//! no image is copied from elsewhere. Pure: returns RGBA images ([`image::RgbaImage`], 8 bits
//! per channel, straight alpha), writes no file and needs no GPU, so the renderer and the
//! exporters use the same pictures.
//!
//! **Leaf cards.** [`leaf_texture`] draws one leaf (or, for conifers, one needle shoot: a leaf
//! card of a conifer stands for a shoot, not a single needle) of a [`LeafShape`] onto the card
//! that [`super::mesh::leaf_mesh`] builds: the card is `size` long and `size / 2` wide, texture
//! coordinate u runs across it (0 left, 1 right) and v along it (0 at the petiole, 1 at the
//! tip). Images are stored with row 0 at v = 1 (the tip at the top): the convention of glTF,
//! wgpu and PNG, whose texture origin is the top-left corner, once v is flipped (`1 − v`) as
//! `output::gltf` does; a sampler that keeps v as is sees the leaf upside down, nothing else.
//! The default image is [`LEAF_TEXTURE_W`] × [`LEAF_TEXTURE_H`] (1:2 like the card, so a texel
//! is square on the card). Alpha is the leaf's coverage of each texel (4 × 4 samples), meant
//! for alpha testing at [`ALPHA_CUTOFF`] (glTF `alphaMode: MASK`); RGB is a grey shading (midrib
//! and veins lighter, the margin darker, 0.70–1.0) to be multiplied by the foliage colour of
//! the season ([`tint`]); RGB is also set where alpha is 0 so that filtered and mip-mapped
//! samples at the edge keep the leaf's colour (no dark fringe).
//!
//! **Outlines** are built from one primitive, the *blade*: along an axis from base to tip
//! (parameter t ∈ [0, 1]) the half-width is `w · t^a (1 − t)^b / max`, a Beta-function profile
//! (a < b: widest below the middle, ovate; a = b = ½: an ellipse; a ≪ b: triangular), times a
//! lobing factor `1 − A_l (½ − ½ cos 2π n_l t)` and a serration factor `1 − A_s frac(n_s t)`.
//! Each [`LeafShape`] is a union of blades (one for simple leaves; leaflets on a rachis for
//! pinnate leaves; five radiating lobes for palmate ones; needles along a shoot for conifers)
//! and capsules (petiole, rachis, shoot). The proportions are drawn from the usual botanical
//! descriptions of the shapes (ESTIMATE, e.g. Stace 2019, *New Flora of the British Isles*,
//! glossary of leaf shapes); they are pictures, not measurements.
//!
//! **Level-of-detail pictures** ([`FoliageTextures`]): a *cluster* card (LOD1, the leaf-cluster
//! cards of [`super::mesh::reduced_mesh`]: 36 leaves scattered over a disc), a *crown* texture
//! (LOD2 hull: the cluster picture, opaque, over the shaded gaps between leaves) and an
//! *impostor* (LOD3 billboard: the tree's silhouette, a cone for conifers or an ellipse for
//! broadleaves filled with leaves, above a trunk).
//!
//! **Bark** ([`bark_texture`]): the species' bark colour with a periodic pattern (it tiles in u
//! and v, as the branch tubes of [`super::mesh::branch_mesh`] repeat it: about one repeat per
//! [`BARK_TILE_M`] round the stem, texels square along it) chosen by
//! [`BarkPattern::of_species`]; white bark carries the stills' lenticel marks
//! ([`lenticel_brightness`]).

use crate::species::schema::LEAF_TEXTURES;
use crate::species::{LeafType, Season, Species};
use glam::Vec2;
use image::{Rgba, RgbaImage};
use rayon::prelude::*;

/// Default leaf texture width (texels; across the card).
pub const LEAF_TEXTURE_W: u32 = 128;
/// Default leaf texture height (texels; along the card, twice the width like the card).
pub const LEAF_TEXTURE_H: u32 = 256;
/// Default side of the square cluster, crown, impostor and bark textures (texels).
pub const TEXTURE_PX: u32 = 256;
/// Alpha threshold of the leaf textures (0–1; glTF `alphaCutoff`): texels with a coverage
/// below it are discarded.
pub const ALPHA_CUTOFF: f32 = 0.5;

/// Outline of a species' leaf card: the `appearance.leaf_texture` field of a species file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LeafShape {
    /// Ovate, widest below the middle, wavy margin (beech, hornbeam, elm): `broad_ovate`.
    Ovate,
    /// Lobed, 4–5 rounded lobes a side, short petiole (oaks): `broad_lobed`.
    Lobed,
    /// Heart-shaped, two rounded basal lobes and a pointed tip (lime): `broad_cordate`.
    Cordate,
    /// Palmate, five pointed lobes from the petiole (maples, sycamore): `broad_palmate`.
    Palmate,
    /// Pinnate compound, leaflet pairs on a rachis and a terminal leaflet (ash, rowan):
    /// `broad_pinnate`.
    Pinnate,
    /// Round, long petiole (aspen, alder): `broad_round`.
    Round,
    /// Triangular (deltoid), doubly serrate, long-pointed tip (birch): `broad_triangular`.
    Triangular,
    /// A shoot with short needles all round it (spruce): `needle_short`.
    NeedleShort,
    /// A shoot with long paired needles in a brush towards its end (pine): `needle_long`.
    NeedleLong,
    /// A shoot with flat needles in two ranks, like a comb (fir): `needle_flat`.
    NeedleFlat,
    /// A shoot with tufts of needles on short side shoots (larch): `needle_tuft`.
    NeedleTuft,
}

impl LeafShape {
    /// Every shape, in the order of the species schema's names
    /// ([`crate::species::schema::LEAF_TEXTURES`], which ends with `"none"`: the default of
    /// [`LeafShape::default_for`]).
    pub const ALL: [LeafShape; 11] = [
        LeafShape::Ovate,
        LeafShape::Lobed,
        LeafShape::Cordate,
        LeafShape::Palmate,
        LeafShape::Pinnate,
        LeafShape::Round,
        LeafShape::Triangular,
        LeafShape::NeedleShort,
        LeafShape::NeedleLong,
        LeafShape::NeedleFlat,
        LeafShape::NeedleTuft,
    ];

    /// The species-file name of the shape, e.g. `"broad_lobed"`.
    pub fn name(self) -> &'static str {
        LEAF_TEXTURES[self as usize]
    }

    /// The shape of a species-file name; `None` for `"none"` or an unknown name.
    pub fn from_name(name: &str) -> Option<LeafShape> {
        Self::ALL.iter().copied().find(|s| s.name() == name)
    }

    /// The default shape of a leaf type: ovate for broadleaves, short needles for conifers.
    pub fn default_for(leaf_type: LeafType) -> LeafShape {
        match leaf_type {
            LeafType::Broadleaf => LeafShape::Ovate,
            LeafType::Conifer => LeafShape::NeedleShort,
        }
    }

    /// The shape of a species: its `appearance.leaf_texture`, or the default of its
    /// `identity.leaf_type` when that is `"none"` (the species schema refuses other names).
    pub fn of_species(sp: &Species) -> LeafShape {
        Self::from_name(&sp.appearance.leaf_texture).unwrap_or_else(|| Self::default_for(sp.identity.leaf_type))
    }

    /// Length of the needles drawn on a shoot card of this shape over the card's length
    /// (`None` for a broadleaf, whose card is the leaf: its length is the leaf's): the needle
    /// rays of the shoot outlines drawn by this module, 0.17 (`needle_short`, spruce), 0.42 (`needle_long`, pine:
    /// the mean of its 14 pairs, 0.55 − 0.02k), 0.21 (`needle_flat`, fir) and 0.10
    /// (`needle_tuft`, larch: the needles of a short shoot's tuft). A conifer's
    /// `appearance.leaf_length_m` is its shoot card's length, this share of which is the
    /// published needle length (species/README.md, "Leaf length"; `tests/species_leaf_length.rs`).
    pub fn needle_length_share(self) -> Option<f32> {
        match self {
            LeafShape::NeedleShort => Some(0.17),
            LeafShape::NeedleLong => Some(0.42),
            LeafShape::NeedleFlat => Some(0.21),
            LeafShape::NeedleTuft => Some(0.1),
            _ => None,
        }
    }

    /// True for the needle shoots of conifers.
    pub fn is_needle(self) -> bool {
        matches!(self, LeafShape::NeedleShort | LeafShape::NeedleLong | LeafShape::NeedleFlat | LeafShape::NeedleTuft)
    }
}

/// One blade of an outline (see the module documentation): card coordinates, x across
/// (−0.25–0.25), y along (0–1), in units of the card's length.
#[derive(Debug, Clone, Copy)]
struct Blade {
    base: Vec2,
    tip: Vec2,
    /// Largest half-width (card lengths).
    half_width: f32,
    a: f32,
    b: f32,
    lobe_amp: f32,
    lobes: f32,
    serr_amp: f32,
    serrations: f32,
}

impl Blade {
    fn new(base: Vec2, tip: Vec2, half_width: f32, a: f32, b: f32) -> Blade {
        Blade { base, tip, half_width, a, b, lobe_amp: 0.0, lobes: 0.0, serr_amp: 0.0, serrations: 0.0 }
    }
    fn lobed(mut self, amp: f32, n: f32) -> Blade {
        self.lobe_amp = amp;
        self.lobes = n;
        self
    }
    fn serrate(mut self, amp: f32, n: f32) -> Blade {
        self.serr_amp = amp;
        self.serrations = n;
        self
    }
    /// (t along, |s| across, half-width at t) when `p` lies inside, else `None`.
    fn inside(&self, p: Vec2) -> Option<(f32, f32, f32)> {
        let axis = self.tip - self.base;
        let len = axis.length();
        if len <= 0.0 {
            return None;
        }
        let d = axis / len;
        let rel = p - self.base;
        let t = rel.dot(d) / len;
        if !(0.0..=1.0).contains(&t) {
            return None;
        }
        let s = rel.perp_dot(d).abs();
        let peak = self.a / (self.a + self.b);
        let norm = peak.powf(self.a) * (1.0 - peak).powf(self.b);
        let mut w = self.half_width * t.powf(self.a) * (1.0 - t).powf(self.b) / norm;
        if self.lobes > 0.0 {
            w *= 1.0 - self.lobe_amp * (0.5 - 0.5 * (std::f32::consts::TAU * self.lobes * t).cos());
        }
        if self.serrations > 0.0 {
            w *= 1.0 - self.serr_amp * (self.serrations * t).fract();
        }
        (s <= w).then_some((t, s, w))
    }
}

/// A segment with round ends (petiole, rachis, shoot): card coordinates.
#[derive(Debug, Clone, Copy)]
struct Capsule {
    a: Vec2,
    b: Vec2,
    r: f32,
}

impl Capsule {
    fn contains(&self, p: Vec2) -> bool {
        let ab = self.b - self.a;
        let t = ((p - self.a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
        p.distance(self.a + ab * t) <= self.r
    }
}

/// The blades and capsules of a shape.
struct Outline {
    blades: Vec<Blade>,
    stems: Vec<Capsule>,
    /// Veins drawn on the blades (broadleaves).
    veins: bool,
}

fn v2(x: f32, y: f32) -> Vec2 {
    Vec2::new(x, y)
}

/// A blade of `len` from `base` at `angle_deg` from the +y axis (positive to the right).
fn ray(base: Vec2, angle_deg: f32, len: f32, half_width: f32, a: f32, b: f32) -> Blade {
    let (s, c) = angle_deg.to_radians().sin_cos();
    Blade::new(base, base + v2(s, c) * len, half_width, a, b)
}

fn outline(shape: LeafShape) -> Outline {
    let petiole = |y1: f32| Capsule { a: v2(0.0, 0.0), b: v2(0.0, y1), r: 0.011 };
    let shoot = |y0: f32, y1: f32| Capsule { a: v2(0.0, y0), b: v2(0.0, y1), r: 0.012 };
    match shape {
        LeafShape::Ovate => Outline { blades: vec![Blade::new(v2(0.0, 0.12), v2(0.0, 0.99), 0.2, 0.75, 1.05).lobed(0.06, 7.0)], stems: vec![petiole(0.14)], veins: true },
        LeafShape::Lobed => Outline { blades: vec![Blade::new(v2(0.0, 0.05), v2(0.0, 0.99), 0.24, 1.0, 0.9).lobed(0.42, 4.5)], stems: vec![petiole(0.07)], veins: true },
        LeafShape::Cordate => {
            let main = Blade::new(v2(0.0, 0.2), v2(0.0, 0.99), 0.235, 0.45, 1.1).serrate(0.05, 18.0);
            // the two basal lobes reach below the petiole's attachment
            let l = Blade::new(v2(0.03, 0.33), v2(-0.15, 0.17), 0.085, 0.5, 0.6);
            let r = Blade::new(v2(-0.03, 0.33), v2(0.15, 0.17), 0.085, 0.5, 0.6);
            Outline { blades: vec![main, l, r], stems: vec![petiole(0.26)], veins: true }
        }
        LeafShape::Palmate => {
            let c = v2(0.0, 0.3);
            let lobe = |ang: f32, len: f32| ray(c, ang, len, 0.1 * len / 0.6, 0.55, 1.15).serrate(0.08, 5.0);
            Outline { blades: vec![lobe(0.0, 0.68), lobe(-30.0, 0.5), lobe(30.0, 0.5), lobe(-75.0, 0.3), lobe(75.0, 0.3)], stems: vec![petiole(0.32)], veins: true }
        }
        LeafShape::Pinnate => {
            let mut blades = vec![Blade::new(v2(0.0, 0.8), v2(0.0, 0.995), 0.045, 0.6, 1.0).serrate(0.1, 6.0)];
            for k in 0..5 {
                let y = 0.2 + 0.13 * k as f32;
                let len = 0.22 - 0.015 * k as f32;
                for side in [-1.0f32, 1.0] {
                    blades.push(ray(v2(0.0, y), side * 55.0, len, 0.045, 0.6, 1.0).serrate(0.1, 6.0));
                }
            }
            Outline { blades, stems: vec![Capsule { a: v2(0.0, 0.0), b: v2(0.0, 0.85), r: 0.008 }], veins: true }
        }
        LeafShape::Round => Outline { blades: vec![Blade::new(v2(0.0, 0.45), v2(0.0, 0.99), 0.24, 0.5, 0.55).lobed(0.05, 9.0)], stems: vec![petiole(0.47)], veins: true },
        LeafShape::Triangular => Outline { blades: vec![Blade::new(v2(0.0, 0.2), v2(0.0, 0.995), 0.24, 0.28, 1.25).serrate(0.1, 16.0)], stems: vec![petiole(0.22)], veins: true },
        LeafShape::NeedleShort => {
            // needles all round the shoot, seen from the side: forward-pointing on both sides
            let mut blades = Vec::new();
            for k in 0..22 {
                let y = 0.06 + 0.042 * k as f32;
                for (side, jit) in [(-1.0f32, 0.0f32), (1.0, 0.021)] {
                    let ang = side * (50.0 + 12.0 * ((k * 7 + 3) % 5) as f32 / 4.0);
                    blades.push(ray(v2(0.0, y + jit), ang, 0.17, 0.009, 0.25, 0.6));
                }
            }
            Outline { blades, stems: vec![shoot(0.0, 0.99)], veins: false }
        }
        LeafShape::NeedleLong => {
            // long needle pairs in a brush from the upper half of the shoot
            let mut blades = Vec::new();
            for k in 0..14 {
                let y = 0.3 + 0.045 * k as f32;
                let ang = -38.0 + 76.0 * ((k * 5 + 2) % 14) as f32 / 13.0;
                for d in [-4.0f32, 4.0] {
                    blades.push(ray(v2(0.0, y), ang + d, 0.55 - 0.02 * k as f32, 0.007, 0.2, 0.5));
                }
            }
            Outline { blades, stems: vec![shoot(0.0, 0.9)], veins: false }
        }
        LeafShape::NeedleFlat => {
            let mut blades = Vec::new();
            for k in 0..30 {
                let y = 0.05 + 0.031 * k as f32;
                for side in [-1.0f32, 1.0] {
                    blades.push(ray(v2(0.0, y), side * 72.0, 0.21, 0.012, 0.15, 0.35));
                }
            }
            Outline { blades, stems: vec![shoot(0.0, 0.99)], veins: false }
        }
        LeafShape::NeedleTuft => {
            let mut blades = Vec::new();
            let mut stems = vec![Capsule { a: v2(0.0, 0.0), b: v2(0.0, 0.98), r: 0.01 }];
            for (k, &(x, y)) in [(-0.1f32, 0.2f32), (0.11, 0.36), (-0.11, 0.52), (0.1, 0.68), (-0.06, 0.84), (0.0, 0.95)].iter().enumerate() {
                let c = v2(x, y);
                stems.push(Capsule { a: v2(0.0, y - 0.06), b: c, r: 0.008 });
                for j in 0..13 {
                    let ang = -110.0 + 220.0 * j as f32 / 12.0 + 9.0 * k as f32;
                    blades.push(ray(c, ang, 0.1, 0.007, 0.2, 0.5));
                }
            }
            Outline { blades, stems, veins: false }
        }
    }
}

impl Outline {
    /// Grey shading at card point `p` when inside (0.70–1.0), else `None`; with `fine` (a
    /// texture of [`FINE_LEAF_TEXELS`] or more across) also the finer veins of
    /// [`leaf_texture_sized`].
    fn shade(&self, p: Vec2, fine: bool) -> Option<f32> {
        if self.stems.iter().any(|c| c.contains(p)) {
            return Some(0.9);
        }
        let mut best: Option<f32> = None;
        for b in &self.blades {
            if let Some((t, s, w)) = b.inside(p) {
                let across = if w > 0.0 { s / w } else { 1.0 };
                let mut g = 0.95 - 0.25 * across * across;
                if self.veins {
                    let len = (b.tip - b.base).length();
                    // midrib, then lateral veins running forward from it (8 pairs per blade)
                    if s < 0.006 {
                        g = 1.0;
                    } else if ((t * len - 0.8 * s) / (len / 8.0)).fract() < 0.1 {
                        g = (g + 0.1).min(1.0);
                    } else if fine {
                        // the minor veins between the laterals (four a gap, crossing them)
                        // and the areoles' mottle they enclose
                        let x = (t * len - 0.8 * s) / (len / 8.0);
                        let y = (s + 0.3 * t * len) / (len / 40.0);
                        if (x * 4.0).fract() < 0.08 || y.fract() < 0.06 {
                            g = (g + 0.045).min(1.0);
                        } else {
                            g -= 0.04 * unit(&[0xA2E0, (x * 4.0).floor() as i64 as u64, y.floor() as i64 as u64]);
                        }
                    }
                } else {
                    g = 0.8 + 0.2 * (1.0 - across);
                }
                best = Some(best.map_or(g, |x: f32| x.max(g)));
            }
        }
        best
    }
}

/// Width (texels) from which [`leaf_texture_sized`] draws a broad leaf's minor veins and
/// areoles (issue 32, round 43: a film texture must gain detail, not be an enlarged 128-texel
/// leaf): four minor veins between each pair of laterals, a cross-net 40 a blade long, and a
/// hashed mottle of ± 4 % in each areole (ESTIMATE, a look: net venation as in the usual
/// botanical descriptions of beech, oak and lime leaves).
pub const FINE_LEAF_TEXELS: u32 = 256;

/// The leaf card texture of `shape`, `width` × `height` texels (each at least 4; the card's
/// proportions are 1:2, see the module documentation): grey shading in RGB, coverage in alpha.
/// From [`FINE_LEAF_TEXELS`] across, broad leaves also carry their minor veins.
pub fn leaf_texture_sized(shape: LeafShape, width: u32, height: u32) -> RgbaImage {
    let (w, h) = (width.max(4), height.max(4));
    let fine = w >= FINE_LEAF_TEXELS;
    let o = outline(shape);
    const N: u32 = 4;
    let mut img = RgbaImage::new(w, h);
    // rows in parallel (each texel depends on its position alone: the same image whatever the
    // thread count; round 47: a stand export spent a fifth of its CPU time here, on one thread)
    let buf: &mut [u8] = &mut img;
    buf.par_chunks_mut(4 * w as usize).enumerate().for_each(|(py, row)| {
        for (px, texel) in row.chunks_exact_mut(4).enumerate() {
            let (mut cover, mut grey, mut hits) = (0u32, 0.0f32, 0u32);
            for sy in 0..N {
                for sx in 0..N {
                    let u = (px as f32 + (sx as f32 + 0.5) / N as f32) / w as f32;
                    let v = 1.0 - (py as f32 + (sy as f32 + 0.5) / N as f32) / h as f32;
                    if let Some(g) = o.shade(v2((u - 0.5) * 0.5, v), fine) {
                        cover += 1;
                        grey += g;
                        hits += 1;
                    }
                }
            }
            let g = if hits > 0 { grey / hits as f32 } else { 0.8 };
            let a = cover as f32 / (N * N) as f32;
            texel.copy_from_slice(&[q(g), q(g), q(g), q(a)]);
        }
    });
    img
}

/// The leaf card texture of `shape` at the default size ([`LEAF_TEXTURE_W`] ×
/// [`LEAF_TEXTURE_H`]); see [`leaf_texture_sized`].
pub fn leaf_texture(shape: LeafShape) -> RgbaImage {
    leaf_texture_sized(shape, LEAF_TEXTURE_W, LEAF_TEXTURE_H)
}

fn q(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// `img` with its RGB multiplied by the sRGB colour `rgb` (0–255; the multiplication is done on
/// the 0–1 sRGB values, as a glTF base colour factor of the same colour would in linear light
/// only approximately); alpha unchanged.
pub fn tint(img: &RgbaImage, rgb: [u8; 3]) -> RgbaImage {
    let mut out = img.clone();
    for p in out.pixels_mut() {
        for k in 0..3 {
            p.0[k] = ((p.0[k] as u32 * rgb[k] as u32 + 127) / 255) as u8;
        }
    }
    out
}

/// Bilinear sample of `img` at texture coordinates (u, v) ∈ [0, 1]² (v up, as in the module
/// documentation); outside: transparent.
fn sample(img: &RgbaImage, u: f32, v: f32) -> [f32; 4] {
    if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
        return [0.0; 4];
    }
    let (w, h) = (img.width() as f32, img.height() as f32);
    let x = (u * w - 0.5).clamp(0.0, w - 1.0);
    let y = ((1.0 - v) * h - 0.5).clamp(0.0, h - 1.0);
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let mut out = [0.0; 4];
    for (xx, yy, wt) in [(x0, y0, (1.0 - fx) * (1.0 - fy)), (x1, y0, fx * (1.0 - fy)), (x0, y1, (1.0 - fx) * fy), (x1, y1, fx * fy)] {
        let p = img.get_pixel(xx, yy).0;
        for k in 0..4 {
            out[k] += p[k] as f32 / 255.0 * wt;
        }
    }
    out
}

/// Uniform number in [0, 1) from a hash of `keys` ([`crate::rng::hash`]).
fn unit(keys: &[u64]) -> f32 {
    (crate::rng::hash(keys) >> 40) as f32 / (1u64 << 24) as f32
}

/// A leaf placed on a square picture: centre (u, v), direction angle, length (picture units).
#[derive(Clone, Copy)]
struct Placed {
    c: Vec2,
    angle: f32,
    len: f32,
    grey: f32,
}

/// Composites `leaves` (copies of `leaf`, a leaf card texture) over a square `size` picture;
/// returns coverage-weighted grey and alpha per texel (front-to-back "over").
fn scatter(leaf: &RgbaImage, leaves: &[Placed], size: u32) -> Vec<[f32; 2]> {
    let mut px = vec![[0.0f32, 0.0f32]; (size * size) as usize];
    for l in leaves {
        let (s, c) = l.angle.sin_cos();
        let along = Vec2::new(s, c);
        let across = Vec2::new(c, -s);
        // bounding square of the card (length len, width len/2) about its centre
        let r = l.len * 0.56;
        let (x0, x1) = (((l.c.x - r) * size as f32).floor().max(0.0) as u32, ((l.c.x + r) * size as f32).ceil().min(size as f32) as u32);
        let (y0, y1) = (((1.0 - l.c.y - r) * size as f32).floor().max(0.0) as u32, ((1.0 - l.c.y + r) * size as f32).ceil().min(size as f32) as u32);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = Vec2::new((x as f32 + 0.5) / size as f32, 1.0 - (y as f32 + 0.5) / size as f32) - l.c;
                let u = 0.5 + p.dot(across) / (l.len * 0.5);
                let v = 0.5 + p.dot(along) / l.len;
                let t = sample(leaf, u, v);
                if t[3] <= 0.0 {
                    continue;
                }
                let cell = &mut px[(y * size + x) as usize];
                // later leaves lie on top
                cell[0] = cell[0] * (1.0 - t[3]) + t[0] * l.grey * t[3];
                cell[1] = cell[1] * (1.0 - t[3]) + t[3];
            }
        }
    }
    px
}

fn to_image(px: &[[f32; 2]], size: u32, background: Option<f32>) -> RgbaImage {
    let mut img = RgbaImage::new(size, size);
    for (i, p) in img.pixels_mut().enumerate() {
        let [g, a] = px[i];
        let (g, a) = match background {
            // opaque: the gaps between leaves in shade
            Some(bg) => (g + bg * (1.0 - a), 1.0),
            // straight alpha: colour of the leaves where covered, a mid grey elsewhere
            None => (if a > 1e-3 { g / a } else { 0.75 }, a),
        };
        *p = Rgba([q(g), q(g), q(g), q(a)]);
    }
    img
}

/// Leaves of a cluster card: 36 leaves over a disc of radius 0.42 about the centre, pointing
/// outwards, the lower ones darker (self-shading), placed by hashes of `salt`.
fn cluster_leaves(shape: LeafShape, salt: u64) -> Vec<Placed> {
    let n = 36;
    let len = cluster_leaf_length(shape);
    (0..n)
        .map(|i| {
            let k = i as u64;
            let r = 0.42 * unit(&[salt, k, 1]).sqrt() * (1.0 - 0.5 * len);
            let th = unit(&[salt, k, 2]) * std::f32::consts::TAU;
            let c = Vec2::new(0.5 + r * th.cos(), 0.5 + r * th.sin());
            let out = (c - Vec2::splat(0.5)).normalize_or(Vec2::Y);
            let angle = out.x.atan2(out.y) + (unit(&[salt, k, 3]) - 0.5) * 1.2;
            let grey = 0.7 + 0.3 * (c.y - 0.08).clamp(0.0, 1.0);
            Placed { c: c + out * len * 0.3, angle, len, grey }
        })
        .collect()
}

/// Share (0–1) of a leaf card that its leaf covers: the fraction of the texels of
/// [`leaf_texture`]`(shape)` whose coverage reaches [`ALPHA_CUTOFF`], what an alpha-tested
/// card (glTF `alphaMode: MASK`) shows of its `size × size/2` quad. At least 0.05.
pub fn leaf_card_cover(shape: LeafShape) -> f32 {
    let img = leaf_texture(shape);
    let n = img.pixels().filter(|p| p.0[3] as f32 >= ALPHA_CUTOFF * 255.0).count();
    (n as f32 / (img.width() * img.height()).max(1) as f32).max(0.05)
}

/// Share (0–1) of a cluster card ([`cluster_texture`]) its leaves cover: the fraction of the
/// texels of a 128-texel cluster texture whose coverage reaches [`ALPHA_CUTOFF`]. At least 0.05.
pub fn cluster_card_cover(shape: LeafShape) -> f32 {
    let img = cluster_texture(shape, 128);
    let n = img.pixels().filter(|p| p.0[3] as f32 >= ALPHA_CUTOFF * 255.0).count();
    (n as f32 / (img.width() * img.height()).max(1) as f32).max(0.05)
}

/// Leaf length on a cluster card, in card sides ([`cluster_texture`]): 0.36 for needle shoots,
/// 0.26 for leaves.
pub fn cluster_leaf_length(shape: LeafShape) -> f32 {
    if shape.is_needle() {
        0.36
    } else {
        0.26
    }
}

/// The cluster card texture of `shape` (LOD1 leaf clusters): `size` × `size`, grey shading and
/// coverage as [`leaf_texture`].
pub fn cluster_texture(shape: LeafShape, size: u32) -> RgbaImage {
    let size = size.max(8);
    let leaf = leaf_texture_sized(shape, 64, 128);
    to_image(&scatter(&leaf, &cluster_leaves(shape, 0xC1), size), size, None)
}

/// The crown hull texture of `shape` (LOD2): the cluster picture made opaque over the shade of
/// the gaps (grey 0.35), tiling poorly but without holes; `size` × `size`.
pub fn crown_texture(shape: LeafShape, size: u32) -> RgbaImage {
    let size = size.max(8);
    let leaf = leaf_texture_sized(shape, 64, 128);
    let mut leaves = cluster_leaves(shape, 0xC2);
    // fill the square, not only a disc: a second layer spread over the whole picture
    leaves.extend((0..60u64).map(|k| Placed { c: Vec2::new(unit(&[0xC3, k, 1]), unit(&[0xC3, k, 2])), angle: unit(&[0xC3, k, 3]) * std::f32::consts::TAU, len: 0.22, grey: 0.85 }));
    to_image(&scatter(&leaf, &leaves, size), size, Some(0.35))
}

/// Texture v (0–1, up) where the impostor texture's crown starts, for every leaf shape: the
/// crown (cone or ellipse) spans v [`IMPOSTOR_CROWN_V`, 0.98], only the trunk lies below.
/// [`crate::structure::mesh::impostor_mesh`] maps the tree's crown base to this v.
pub const IMPOSTOR_CROWN_V: f32 = 0.12;

/// Texture u range (0–1) of the impostor texture's trunk column (opaque, centred), which
/// [`crate::structure::mesh::impostor_mesh`] maps onto its trunk quads.
pub const IMPOSTOR_TRUNK_U: [f32; 2] = [0.48, 0.52];

/// The impostor texture of `shape` (LOD3 billboard, v up): a crown of scattered leaves over v
/// [`IMPOSTOR_CROWN_V`]–0.98 (u 0.04–0.96), a cone for needle shapes, an ellipse for broad
/// ones, above and over a dark trunk column (u 0.475–0.525, v below 0.6); `size` × `size`.
/// Greyscale; the drawn textures are [`impostor_texture_coloured`].
pub fn impostor_texture(shape: LeafShape, size: u32) -> RgbaImage {
    let (px, _) = impostor_layers(shape, size);
    to_image(&px, size.max(8), None)
}

/// The impostor texture of `shape` in colour: the leaves of [`impostor_texture`] tinted by
/// `leaf_rgb` (sRGB 0–255, as [`tint`] tints), the trunk column in the bark colour `bark_rgb`
/// (the species' textures pass their bark texture's mean, [`mean_rgb`]: what levels 0–2 wear;
/// rounds 35–45 drew it × 0.85, "the shaded side of a stem", and the billboard quad's own
/// shading made a birch's white stem grey, trial 45). Trial 35: the whole greyscale impostor
/// was tinted by the leaf colour, so its trunk (grey 0.3) became 0.3 × the leaf's dark green,
/// nearly black whatever the bark (beech's grey, birch's white). Straight alpha, `size` ×
/// `size`.
pub fn impostor_texture_coloured(shape: LeafShape, size: u32, leaf_rgb: [u8; 3], bark_rgb: [u8; 3]) -> RgbaImage {
    let (_, (trunk, leaf_px)) = impostor_layers(shape, size);
    let mut img = RgbaImage::new(size.max(8), size.max(8));
    for (i, p) in img.pixels_mut().enumerate() {
        let (t, [g, a]) = (trunk[i], leaf_px[i]);
        let alpha = a + t * (1.0 - a);
        let c = |k: usize| -> u8 {
            let leaf = leaf_rgb[k] as f32 / 255.0;
            let bark = bark_rgb[k] as f32 / 255.0;
            // premultiplied: the leaves' grey times the leaf colour over the trunk's bark
            let pre = leaf * g + bark * t * (1.0 - a);
            q(if alpha > 1e-3 { pre / alpha } else { 0.75 * leaf })
        };
        *p = Rgba([c(0), c(1), c(2), q(alpha)]);
    }
    img
}

/// The layers of the impostor texture: its greyscale composite (grey, alpha, premultiplied) and,
/// apart, the trunk column's coverage (0 or 1) and the leaves' (grey, alpha).
#[allow(clippy::type_complexity)]
fn impostor_layers(shape: LeafShape, size: u32) -> (Vec<[f32; 2]>, (Vec<f32>, Vec<[f32; 2]>)) {
    let size = size.max(8);
    let leaf = leaf_texture_sized(shape, 64, 128);
    let conifer = shape.is_needle();
    let len = 0.12;
    let inside = |p: Vec2| {
        if conifer {
            p.y > IMPOSTOR_CROWN_V && p.y < 0.98 && (p.x - 0.5).abs() < 0.46 * (0.98 - p.y) / (0.98 - IMPOSTOR_CROWN_V)
        } else {
            // the same v span as the cone: centre (0.98 + 0.12) / 2, half-height (0.98 − 0.12) / 2
            let e = Vec2::new((p.x - 0.5) / 0.46, (p.y - 0.5 * (0.98 + IMPOSTOR_CROWN_V)) / (0.5 * (0.98 - IMPOSTOR_CROWN_V)));
            e.length_squared() < 1.0
        }
    };
    let mut leaves = Vec::new();
    let mut k = 0u64;
    while leaves.len() < 260 && k < 5000 {
        let c = Vec2::new(unit(&[0x1A, k, 1]), unit(&[0x1A, k, 2]));
        if inside(c) {
            let grey = 0.65 + 0.35 * c.y;
            leaves.push(Placed { c, angle: unit(&[0x1A, k, 3]) * std::f32::consts::TAU, len, grey });
        }
        k += 1;
    }
    let mut px = vec![[0.0f32, 0.0f32]; (size * size) as usize];
    let mut trunk = vec![0.0f32; (size * size) as usize];
    // the trunk first, the leaves over it
    for y in 0..size {
        for x in 0..size {
            let p = Vec2::new((x as f32 + 0.5) / size as f32, 1.0 - (y as f32 + 0.5) / size as f32);
            if (p.x - 0.5).abs() < 0.025 && p.y < 0.6 {
                px[(y * size + x) as usize] = [0.3, 1.0];
                trunk[(y * size + x) as usize] = 1.0;
            }
        }
    }
    let leaf_px = scatter(&leaf, &leaves, size);
    for (d, s) in px.iter_mut().zip(&leaf_px) {
        d[0] = d[0] * (1.0 - s[1]) + s[0];
        d[1] = d[1] * (1.0 - s[1]) + s[1];
    }
    (px, (trunk, leaf_px))
}

/// Mean colour (sRGB 0–255) of `img`'s texels with alpha at or above [`ALPHA_CUTOFF`] (all of
/// them for an opaque texture); `[128, 128, 128]` for a texture without one.
pub fn mean_rgb(img: &RgbaImage) -> [u8; 3] {
    let (mut s, mut n) = ([0.0f64; 3], 0usize);
    for p in img.pixels().filter(|p| p.0[3] as f32 >= ALPHA_CUTOFF * 255.0) {
        for k in 0..3 {
            s[k] += p.0[k] as f64;
        }
        n += 1;
    }
    if n == 0 {
        return [128; 3];
    }
    s.map(|v| (v / n as f64).round().clamp(0.0, 255.0) as u8)
}

/// The billboard picture of ONE tree, baked from its own full-detail level (issue 32, round 46:
/// the species' picture, a cone or an ellipse of scattered leaves, drew a Scots pine's V as a
/// spruce's cone and a sparse birch as a full, opaque ellipse). `full` (level 0 of the chain)
/// is seen along +y (orthographic, z up) into a `size` × `size` picture laid out as `billboard`'s
/// (level 3, [`crate::structure::mesh::impostor_mesh`]) first crown quad maps it: u and v
/// linear in x and z, from its corners' positions and texture coordinates. Its leaf cards are
/// alpha-tested with `leaf` (the leaf card picture; leaf-cluster cards, [`crate::mesh::TriMesh::has_cluster_cards`],
/// with `cluster`) at [`ALPHA_CUTOFF`], its bark drawn in `bark_rgb` (sRGB 0–255), the nearest
/// surface kept, each texel shaded as the preview shades (0.35 + 0.65 |n·l|, l from the upper
/// left front) divided by the preview's shading of a quad facing the viewer (0.74), at most 1:
/// the billboard, itself shaded as a quad facing the viewer, shows about the full level's
/// brightness. So the billboard's
/// coverage (its opaque share) is the full level's at the picture's resolution, gaps and all,
/// and its outline is the tree's. Below the crown ([`IMPOSTOR_CROWN_V`]) only the trunk column
/// ([`IMPOSTOR_TRUNK_U`], the billboard's trunk quads) is kept, in `bark_rgb`. Transparent texels
/// carry the mean leaf colour × 0.75 (no dark fringe when filtered). `None` when `billboard`
/// has no crown quad (fewer than 4 vertices or a flat mapping).
pub fn baked_impostor(full: &crate::mesh::TreeMesh, billboard: &crate::mesh::TreeMesh, leaf: &RgbaImage, cluster: &RgbaImage, bark_rgb: [u8; 3], size: u32) -> Option<RgbaImage> {
    let size = size.max(8);
    let q4 = billboard.leaves.positions.get(..4)?;
    let t4 = billboard.leaves.uvs.get(..4)?;
    // u = u0 + (x − x0)·su, v = v0 + (z − z0)·sv over the quad's corners
    let (i0, i1) = ((0..4).min_by(|&a, &b| q4[a][0].total_cmp(&q4[b][0]))?, (0..4).max_by(|&a, &b| q4[a][0].total_cmp(&q4[b][0]))?);
    let (j0, j1) = ((0..4).min_by(|&a, &b| q4[a][2].total_cmp(&q4[b][2]))?, (0..4).max_by(|&a, &b| q4[a][2].total_cmp(&q4[b][2]))?);
    let (dx, dz) = (q4[i1][0] - q4[i0][0], q4[j1][2] - q4[j0][2]);
    if !(dx.abs() > 1e-6 && dz.abs() > 1e-6) {
        return None;
    }
    let su = (t4[i1][0] - t4[i0][0]) / dx;
    let sv = (t4[j1][1] - t4[j0][1]) / dz;
    let (x0, u0, z0, v0) = (q4[i0][0], t4[i0][0], q4[j0][2], t4[j0][1]);
    let s = size as f32;
    // texel coordinates (column, row from the top, depth along +y)
    let to_px = |p: [f32; 3]| [(u0 + (p[0] - x0) * su) * s, (1.0 - (v0 + (p[2] - z0) * sv)) * s, p[1]];
    let light = glam::Vec3::new(-0.4, -0.6, 0.7).normalize();
    let facing = 0.35 + 0.65 * glam::Vec3::Y.dot(light).abs();
    let n = (size * size) as usize;
    let mut rgba = vec![[0.0f32; 4]; n];
    let mut zbuf = vec![f32::MAX; n];
    let sample = |img: &RgbaImage, uv: [f32; 2]| {
        let (w, h) = img.dimensions();
        let x = ((uv[0].clamp(0.0, 1.0) * w as f32) as u32).min(w - 1);
        let y = (((1.0 - uv[1]).clamp(0.0, 1.0) * h as f32) as u32).min(h - 1);
        img.get_pixel(x, y).0
    };
    let (cards, sprigs) = if full.leaves.has_cluster_cards() { full.leaves.split_cluster_cards() } else { (full.leaves.clone(), crate::mesh::TriMesh::default()) };
    let bark_px = Rgba([bark_rgb[0], bark_rgb[1], bark_rgb[2], 255]);
    let plain = RgbaImage::from_pixel(1, 1, bark_px);
    for (mesh, img, mask) in [(&full.bark, &plain, false), (&cards, leaf, true), (&sprigs, cluster, true)] {
        let has_uv = mesh.uvs.len() == mesh.positions.len();
        for t in mesh.indices.chunks_exact(3) {
            let [ia, ib, ic] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let (Some(&pa), Some(&pb), Some(&pc)) = (mesh.positions.get(ia), mesh.positions.get(ib), mesh.positions.get(ic)) else { continue };
            let (a, b, c) = (to_px(pa), to_px(pb), to_px(pc));
            let nrm = [ia, ib, ic].iter().filter_map(|&i| mesh.normals.get(i)).fold(glam::Vec3::ZERO, |acc, v| acc + glam::Vec3::from(*v));
            let shade = ((0.35 + 0.65 * nrm.normalize_or(glam::Vec3::Z).dot(light).abs()) / facing).min(1.0);
            let uv = |i: usize| if has_uv { mesh.uvs[i] } else { [0.5, 0.5] };
            let (ua, ub, uc) = (uv(ia), uv(ib), uv(ic));
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            let minx = a[0].min(b[0]).min(c[0]).floor().max(0.0) as i64;
            let maxx = a[0].max(b[0]).max(c[0]).ceil().min(s - 1.0) as i64;
            let miny = a[1].min(b[1]).min(c[1]).floor().max(0.0) as i64;
            let maxy = a[1].max(b[1]).max(c[1]).ceil().min(s - 1.0) as i64;
            if area.abs() < 1e-9 {
                // a thin twig seen edge-on keeps its texel, as the preview draws it
                if !mask && minx <= maxx && miny <= maxy {
                    let i = (miny as u32 * size + minx as u32) as usize;
                    let p = img.get_pixel(0, 0).0;
                    rgba[i] = [p[0] as f32 * shade, p[1] as f32 * shade, p[2] as f32 * shade, 255.0];
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
                    let i = (y as u32 * size + x as u32) as usize;
                    let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                    if z >= zbuf[i] {
                        continue;
                    }
                    let p = if mask { sample(img, [w0 * ua[0] + w1 * ub[0] + w2 * uc[0], w0 * ua[1] + w1 * ub[1] + w2 * uc[1]]) } else { img.get_pixel(0, 0).0 };
                    if mask && (p[3] as f32) < ALPHA_CUTOFF * 255.0 {
                        continue;
                    }
                    zbuf[i] = z;
                    rgba[i] = [p[0] as f32 * shade, p[1] as f32 * shade, p[2] as f32 * shade, 255.0];
                }
            }
        }
    }
    let fill = mean_rgb(leaf).map(|c| 0.75 * c as f32);
    let mut out = RgbaImage::new(size, size);
    for (i, px) in out.pixels_mut().enumerate() {
        let (x, y) = (i as u32 % size, i as u32 / size);
        let (u, v) = ((x as f32 + 0.5) / s, 1.0 - (y as f32 + 0.5) / s);
        let mut c = rgba[i];
        if v < IMPOSTOR_CROWN_V {
            // below the crown: the trunk column only (the billboard's trunk quads)
            c = if u >= IMPOSTOR_TRUNK_U[0] - 0.005 && u <= IMPOSTOR_TRUNK_U[1] + 0.005 { [bark_rgb[0] as f32, bark_rgb[1] as f32, bark_rgb[2] as f32, 255.0] } else { [0.0; 4] };
        }
        *px = if c[3] > 0.0 { Rgba([q(c[0] / 255.0), q(c[1] / 255.0), q(c[2] / 255.0), 255]) } else { Rgba([fill[0] as u8, fill[1] as u8, fill[2] as u8, 0]) };
    }
    Some(out)
}

/// Bark pattern of a species.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BarkPattern {
    /// Smooth, faint mottling (beech, hornbeam, young maples).
    Smooth,
    /// Vertical ridges and furrows (oak, ash, lime, elm).
    Fissured,
    /// Scaly plates (pine, spruce, larch, fir).
    Plated,
    /// Light bark with dark horizontal lenticel bands (birch).
    Lenticelled,
}

impl BarkPattern {
    /// The pattern of a species (ESTIMATE, a rule of thumb from the bark colour and leaf type,
    /// the species files having no bark-texture field): conifers are plated; a broadleaf whose
    /// bark is light (Rec. 709 luma > 200 of 255) is lenticelled; a grey one (channels within
    /// 20 of each other, luma 120–190) smooth; other broadleaves fissured.
    pub fn of_species(sp: &Species) -> BarkPattern {
        let [r, g, b] = sp.appearance.bark.map(|c| c as f32);
        let luma = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let spread = r.max(g).max(b) - r.min(g).min(b);
        match sp.identity.leaf_type {
            LeafType::Conifer => BarkPattern::Plated,
            LeafType::Broadleaf if luma > 200.0 => BarkPattern::Lenticelled,
            LeafType::Broadleaf if spread <= 20.0 && (120.0..=190.0).contains(&luma) => BarkPattern::Smooth,
            LeafType::Broadleaf => BarkPattern::Fissured,
        }
    }
}

/// Periodic value noise on the unit square with `cells` lattice cells per side (`cx` × `cy`),
/// smoothstep interpolated, in [0, 1): tiles seamlessly.
fn periodic_noise(u: f32, v: f32, cx: u32, cy: u32, salt: u64) -> f32 {
    let (x, y) = (u.rem_euclid(1.0) * cx as f32, v.rem_euclid(1.0) * cy as f32);
    let (i, j) = (x.floor() as u32, y.floor() as u32);
    let (fx, fy) = (x - i as f32, y - j as f32);
    let l = |a: u32, b: u32| unit(&[salt, (a % cx) as u64, (b % cy) as u64]);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let top = l(i, j) * (1.0 - sx) + l(i + 1, j) * sx;
    let bot = l(i, j + 1) * (1.0 - sx) + l(i + 1, j + 1) * sx;
    top * (1.0 - sy) + bot * sy
}

/// The fine grain of a bark texture of `size` texels at (u, v) (issue 32, round 43: a film
/// texture must gain detail, not be an enlarged 256-texel one): periodic noise octaves of 128,
/// 256, 512, 1024 cells a repeat, each only where the texture has at least 4 texels a cell
/// (none at 256 texels, so the default textures are unchanged), amplitudes ± 0.09, 0.065,
/// 0.045, 0.03 of the brightness (ESTIMATE, a look: the grain of bark seen at arm's length,
/// cells of 4–0.5 mm on a [`BARK_TILE_M`] repeat).
pub fn bark_grain(u: f32, v: f32, size: u32, seed: u64) -> f32 {
    let mut g = 0.0;
    for (k, (cells, amp)) in [(128u32, 0.09f32), (256, 0.065), (512, 0.045), (1024, 0.03)].into_iter().enumerate() {
        if cells * 4 > size {
            break;
        }
        g += amp * 2.0 * (periodic_noise(u, v, cells, cells, seed ^ (0x9a1 + k as u64)) - 0.5);
    }
    g
}

/// The bark texture: `size` × `size`, opaque, the sRGB colour `rgb` (0–255) modulated by
/// `pattern` (brightness 0.45–1.25 of the colour) and, from 512 texels, by [`bark_grain`],
/// tiling in u and v; `seed` varies the pattern.
pub fn bark_texture(rgb: [u8; 3], pattern: BarkPattern, size: u32, seed: u64) -> RgbaImage {
    let size = size.max(8);
    let mut img = RgbaImage::new(size, size);
    for y in 0..size {
        for x in 0..size {
            let (u, v) = ((x as f32 + 0.5) / size as f32, 1.0 - (y as f32 + 0.5) / size as f32);
            let n1 = periodic_noise(u, v, 8, 8, seed ^ 1);
            let n2 = periodic_noise(u, v, 24, 24, seed ^ 2);
            let m = match pattern {
                BarkPattern::Smooth => 0.92 + 0.12 * n1 + 0.06 * n2,
                BarkPattern::Fissured => {
                    // ridges along v: a warped periodic ridge profile across u
                    let warp = periodic_noise(u, v, 4, 6, seed ^ 3) * 0.5;
                    let ridge = (0.5 + 0.5 * ((u * 10.0 + warp) * std::f32::consts::TAU).cos()).powf(0.6);
                    0.5 + 0.55 * ridge + 0.15 * n2
                }
                BarkPattern::Plated => {
                    let p = periodic_noise(u, v, 10, 14, seed ^ 4);
                    let crack = periodic_noise(u, v, 20, 28, seed ^ 5);
                    let plate = if (p * 7.0).fract() < 0.14 || crack < 0.18 { 0.5 } else { 1.0 };
                    plate * (0.9 + 0.2 * n2)
                }
                BarkPattern::Lenticelled => lenticel_brightness(u, v, seed) * (1.0 + 0.06 * n2),
            };
            let m = m * (1.0 + bark_grain(u, v, size, seed));
            let c = rgb.map(|c| ((c as f32 * m).round().clamp(0.0, 255.0)) as u8);
            img.put_pixel(x, y, Rgba([c[0], c[1], c[2], 255]));
        }
    }
    img
}

/// Side (m of bark) of one repeat of a bark texture on the tubes of
/// [`super::mesh::branch_mesh`]: a stem of circumference c takes max(1, round(c / 0.5 m))
/// repeats around, and as many per metre along as keep the texels square (issue 32, round 42:
/// until then a texture repeat was one trunk circumference on every branch, so its marks
/// stretched along thin branches).
pub const BARK_TILE_M: f32 = 0.5;
/// Height (m) of a row of a white bark's lenticel marks, as the stills draw them
/// (`BIRCH_ROW_M` of `render/shaders/scene.wgsl`; ESTIMATE, from photographs: marks of 1–4 cm
/// in rows a hand apart).
pub const BIRCH_ROW_M: f32 = 0.09;
/// Width (m) of a cell of a row (`BIRCH_CELL_M` of the shader; ESTIMATE).
pub const BIRCH_CELL_M: f32 = 0.07;
/// Share of the cells that carry a mark (`BIRCH_MARKS` of the shader; ESTIMATE).
pub const BIRCH_MARKS: f32 = 0.7;

/// Brightness (0.25 in a mark, else 1) of a lenticelled (white) bark at texture coordinates
/// (`u`, `v`) of one [`BARK_TILE_M`] repeat: the stills' pattern (`birch_bark` of the
/// shader): rows of [`BIRCH_ROW_M`] up the stem, cells of [`BIRCH_CELL_M`] around (rounded
/// to whole rows and cells of the repeat, so it tiles), [`BIRCH_MARKS`] of the cells marked by
/// a horizontal dash 0.15–0.35 of the row high and 0.5–1 of the cell wide, placed by `seed`.
pub fn lenticel_brightness(u: f32, v: f32, seed: u64) -> f32 {
    let rows = (BARK_TILE_M / BIRCH_ROW_M).round().max(1.0);
    let cells = (BARK_TILE_M / BIRCH_CELL_M).round().max(1.0);
    // the cells' edges half a cell off the repeat's edge, so no dash is cut by it
    let (y, x) = (v.rem_euclid(1.0) * rows, u.rem_euclid(1.0) * cells + 0.5);
    let (row, cell) = (y.floor() as u64, x.floor().rem_euclid(cells) as u64);
    let (t, c) = (y.fract(), x.fract());
    let h = |k: u64| unit(&[seed, 0x6c65_6e74, row, cell, k]);
    let th = 0.15 + 0.2 * h(1);
    let half = 0.25 + 0.25 * h(2);
    if h(0) < BIRCH_MARKS && (t - 0.5).abs() < 0.5 * th && (c - 0.5).abs() < half {
        0.25
    } else {
        1.0
    }
}

/// Fallen leaves drawn on a [`litter_texture`].
pub const LITTER_LEAVES: u32 = 700;

/// A forest floor of leaf litter: `size` × `size` (≥ 8), opaque, tiling in u and v (every
/// distance is taken round the tile), the sRGB colour `rgb` (0–255) modulated: soil mottled by
/// periodic noise (brightness 0.7–1.0) under [`LITTER_LEAVES`] fallen leaves, ellipses 2.4–7 %
/// of the tile long and about 0.45 as wide, turned at random, each of its own brightness
/// (0.75–1.3) with a darker midrib; `seed` varies it. The stand export lays it on the terrain
/// at one tile a metre (texture coordinates in metres): leaves of 2.4–7 cm, as beech and oak
/// litter (ESTIMATE, a look: no measured litter).
pub fn litter_texture(rgb: [u8; 3], size: u32, seed: u64) -> RgbaImage {
    let size = size.max(8);
    // per leaf: centre (u, v), half-length, half-width, direction (cos, sin), brightness
    let leaves: Vec<[f32; 7]> = (0..LITTER_LEAVES)
        .map(|k| {
            let r = |s: u64| unit(&[seed, 0x1177_e5, k as u64, s]);
            let a = 0.012 + 0.023 * r(3);
            let t = r(5) * std::f32::consts::PI;
            [r(1), r(2), a, a * (0.35 + 0.2 * r(4)), t.cos(), t.sin(), 0.75 + 0.55 * r(6)]
        })
        .collect();
    let mut img = RgbaImage::new(size, size);
    let wrap = |d: f32| d - d.round();
    for y in 0..size {
        for x in 0..size {
            let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
            let mut m = 0.7 + 0.2 * periodic_noise(u, v, 6, 6, seed ^ 11) + 0.1 * periodic_noise(u, v, 32, 32, seed ^ 12);
            // the later leaves lie on top
            for l in &leaves {
                let (du, dv) = (wrap(u - l[0]), wrap(v - l[1]));
                if du.abs() > l[2] || dv.abs() > l[2] {
                    continue;
                }
                let (a, b) = (du * l[4] + dv * l[5], -du * l[5] + dv * l[4]);
                let e = (a / l[2]).powi(2) + (b / l[3]).powi(2);
                if e <= 1.0 {
                    let rib = if b.abs() < 0.08 * l[3] + 0.5 / size as f32 { 0.8 } else { 1.0 };
                    m = l[6] * rib * (0.92 + 0.08 * (1.0 - e));
                }
            }
            let c = rgb.map(|c| ((c as f32 * m).round().clamp(0.0, 255.0)) as u8);
            img.put_pixel(x, y, Rgba([c[0], c[1], c[2], 255]));
        }
    }
    img
}

/// The textures of one species for one season: what the exporters embed and the renderer may
/// upload. Leaf, cluster and impostor textures are alpha-tested ([`ALPHA_CUTOFF`]); crown and
/// bark are opaque. Colours are baked in (sRGB, the species' foliage colour of the season and
/// its bark colour), so a material's base colour factor is white.
#[derive(Debug, Clone, PartialEq)]
pub struct FoliageTextures {
    /// Shape drawn.
    pub shape: LeafShape,
    /// Leaf card (LOD0), [`LEAF_TEXTURE_W`] × [`LEAF_TEXTURE_H`].
    pub leaf: RgbaImage,
    /// Leaf-cluster card (LOD1), [`TEXTURE_PX`]².
    pub cluster: RgbaImage,
    /// Crown hull (LOD2), opaque, [`TEXTURE_PX`]².
    pub crown: RgbaImage,
    /// Billboard impostor (LOD3), [`TEXTURE_PX`]².
    pub impostor: RgbaImage,
    /// Bark, opaque, tiling, [`TEXTURE_PX`]².
    pub bark: RgbaImage,
    /// The dark base of a white ([`BarkPattern::Lenticelled`]) bark (`None` for other barks):
    /// [`BARK_BASE_RGB`], fissured, tiling, as `bark`; the exports draw the stem below
    /// [`BARK_BASE_M`] with it ([`split_bark_base`]).
    pub bark_base: Option<RgbaImage>,
}

/// Colour (sRGB) of the dark, rough base of a white-barked stem in the exports: the stills'
/// `BIRCH_DARK` (linear 0.045, 0.04, 0.035; `render/shaders/scene.wgsl`) in sRGB. Silver
/// birch's white bark turns rough and blackish at the base of an older stem (Atkinson 1992,
/// Biological Flora of the British Isles: Betula pendula Roth and B. pubescens Ehrh., J. Ecol.
/// 80, 837–870), which the stills draw (issue 32, round 41) and the exports drew white to the
/// ground until round 45.
pub const BARK_BASE_RGB: [u8; 3] = [60, 56, 52];

/// Height (m) below which a white-barked stem of [`BARK_BASE_MIN_RADIUS_M`] and more is drawn
/// dark in the exports ([`split_bark_base`]): 1.6 m, the stills' `BIRCH_BASE_M` (ESTIMATE: 1–2
/// m on a stem of 12 cm DBH and more).
pub const BARK_BASE_M: f32 = 1.6;

/// Least stem radius (m) of a dark base ([`BARK_BASE_M`]): 3 cm (the stills' base reaches its
/// full height from 6 cm and is none under 1.5 cm).
pub const BARK_BASE_MIN_RADIUS_M: f32 = 0.03;

/// Splits a white-barked tree's bark mesh (metres, the tree's frame: its stem base at the
/// origin, z up) into the bark above its dark base and the base: the triangles whose centroid
/// lies below [`BARK_BASE_M`] and at least [`BARK_BASE_MIN_RADIUS_M`] from the z axis (the
/// stem's surface; a thin sapling or twig keeps its white bark). The stem's rings lie at the
/// root collar, at 1.3 m and at most 2 m apart (`structure::mesh::LodOptions::stem`), so the
/// dark base of an exported birch ends at its first ring above the ground, 1.3 m. Vertices
/// are copied as they are (each part indexes its own).
pub fn split_bark_base(bark: &crate::mesh::TriMesh) -> (crate::mesh::TriMesh, crate::mesh::TriMesh) {
    let mut parts = [crate::mesh::TriMesh::default(), crate::mesh::TriMesh::default()];
    let mut remap = [vec![u32::MAX; bark.positions.len()], vec![u32::MAX; bark.positions.len()]];
    for t in bark.indices.chunks_exact(3) {
        let c = t.iter().fold([0.0f32; 3], |a, &i| {
            let p = bark.positions[i as usize];
            [a[0] + p[0] / 3.0, a[1] + p[1] / 3.0, a[2] + p[2] / 3.0]
        });
        let k = usize::from(c[2] < BARK_BASE_M && (c[0] * c[0] + c[1] * c[1]).sqrt() >= BARK_BASE_MIN_RADIUS_M);
        for &i in t {
            let i = i as usize;
            if remap[k][i] == u32::MAX {
                let m = &mut parts[k];
                remap[k][i] = m.positions.len() as u32;
                m.positions.push(bark.positions[i]);
                m.normals.push(bark.normals.get(i).copied().unwrap_or([0.0, 0.0, 1.0]));
                if !bark.uvs.is_empty() {
                    m.uvs.push(bark.uvs.get(i).copied().unwrap_or([0.0, 0.0]));
                }
            }
            parts[k].indices.push(remap[k][i]);
        }
    }
    let [upper, base] = parts;
    (upper, base)
}

impl FoliageTextures {
    /// The textures of `sp` in `season` (the foliage colour of [`Season`]: `leaf_spring`,
    /// `leaf_summer`, `leaf_autumn` or `leaf_winter`); the bark pattern is seeded by a hash of
    /// the species id so it is the same in every run.
    pub fn for_species(sp: &Species, season: Season) -> FoliageTextures {
        Self::for_species_sized(sp, season, TEXTURE_PX)
    }

    /// [`FoliageTextures::for_species`] at `size` texels (a power of two from 256; the
    /// export commands' `--texture-size`): the cluster, crown, impostor and bark textures
    /// `size` × `size`, the leaf card `size / 2` × `size` (1:2 like the card). Every texture
    /// is drawn at that size (the leaf's outline, veins and [`FINE_LEAF_TEXELS`] detail, the
    /// bark's [`bark_grain`]), not enlarged; at [`TEXTURE_PX`] it is
    /// [`FoliageTextures::for_species`]'s exactly.
    pub fn for_species_sized(sp: &Species, season: Season, size: u32) -> FoliageTextures {
        Self::for_species_levels(sp, season, size, &[0, 1, 2, 3])
    }

    /// [`FoliageTextures::for_species_sized`] for a file that holds only the levels of detail
    /// `levels` (0–3): the leaf card and the bark at `size`, the cluster (level 1), crown
    /// (2) and impostor (3) pictures at `size` where their level is written, else at
    /// [`TEXTURE_PX`] (a 2048-texel picture no mesh wears costs a second to draw).
    pub fn for_species_levels(sp: &Species, season: Season, size: u32, levels: &[usize]) -> FoliageTextures {
        let at = |l: usize| if levels.contains(&l) { size } else { TEXTURE_PX };
        let a = &sp.appearance;
        let rgb = match season {
            Season::Spring => a.leaf_spring,
            Season::Summer => a.leaf_summer,
            Season::Autumn => a.leaf_autumn,
            Season::Winter => a.leaf_winter,
        };
        let shape = LeafShape::of_species(sp);
        let seed = sp.id.bytes().fold(0xB4u64, |h, b| crate::rng::hash(&[h, b as u64]));
        let bark = bark_texture(a.bark, BarkPattern::of_species(sp), size, seed);
        FoliageTextures {
            shape,
            leaf: tint(&if size == TEXTURE_PX { leaf_texture(shape) } else { leaf_texture_sized(shape, size / 2, size) }, rgb),
            cluster: tint(&cluster_texture(shape, at(1)), rgb),
            crown: tint(&crown_texture(shape, at(2)), rgb),
            impostor: impostor_texture_coloured(shape, at(3), rgb, mean_rgb(&bark)),
            bark,
            bark_base: (BarkPattern::of_species(sp) == BarkPattern::Lenticelled).then(|| bark_texture(BARK_BASE_RGB, BarkPattern::Fissured, size, seed ^ 0xBA5E)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The leaf-litter texture tiles: across its edges (column 255 to 0, row 255 to 0) the
    /// colour steps no more than between neighbouring columns and rows inside it (a texture
    /// that did not wrap its leaves and noise would show a seam once a metre on the ground);
    /// its mean brightness stays within 0.8–1.05 of the colour it is given, so the export's
    /// ground keeps the pictures' forest-floor colour; deterministic.
    #[test]
    fn the_litter_texture_tiles_and_keeps_its_colour() {
        let rgb = [82u8, 79, 60];
        let img = litter_texture(rgb, 128, 3);
        assert_eq!(img, litter_texture(rgb, 128, 3));
        let n = 128;
        let px = |x: u32, y: u32| img.get_pixel(x % n, y % n).0;
        let step = |a: [u8; 4], b: [u8; 4]| (0..3).map(|k| (a[k] as f64 - b[k] as f64).abs()).sum::<f64>();
        let mean = |f: &dyn Fn(u32) -> f64| (0..n).map(f).sum::<f64>() / n as f64;
        let seam_x = mean(&|y| step(px(n - 1, y), px(0, y)));
        let seam_y = mean(&|x| step(px(x, n - 1), px(x, 0)));
        let inner: f64 = (1..n - 1).map(|c| mean(&|y| step(px(c - 1, y), px(c, y)))).sum::<f64>() / (n - 2) as f64;
        assert!(seam_x <= 1.5 * inner && seam_y <= 1.5 * inner, "seams {seam_x:.1}, {seam_y:.1} against {inner:.1} inside");
        let b: f64 = img.pixels().map(|p| p.0[1] as f64).sum::<f64>() / (n * n) as f64 / rgb[1] as f64;
        assert!((0.8..1.05).contains(&b), "mean brightness {b:.3} of the colour");
        assert!(img.pixels().all(|p| p.0[3] == 255), "opaque");
    }

    /// Trial 35: the billboards' trunks were drawn nearly black (0.3 × the leaf colour). Now
    /// the trunk column of the coloured impostor has the bark's colour (round 46: as it is, no
    /// longer × 0.85, which greyed a birch's white stem, trial 45): beech's grey
    /// bark stays grey and light, not the leaves' dark green; the leaves keep the leaf tint.
    #[test]
    fn the_impostor_trunk_has_the_bark_colour() {
        let (leaf, bark) = ([40u8, 80, 30], [150u8, 150, 145]);
        let img = impostor_texture_coloured(LeafShape::Ovate, 128, leaf, bark);
        // the trunk column below the crown (u 0.5, v 0.05): opaque, the bark's colour
        let p = img.get_pixel(64, 127 - 6).0;
        assert_eq!(p[3], 255, "{p:?}");
        for k in 0..3 {
            assert!((p[k] as f32 - bark[k] as f32).abs() <= 2.0, "trunk {p:?}, bark {bark:?}");
        }
        // the greyscale tinted by the leaf colour (the old way) gives a trunk 0.3 × the leaf's
        let old = tint(&impostor_texture(LeafShape::Ovate, 128), leaf).get_pixel(64, 127 - 6).0;
        assert!(old[0] < 20 && old[1] < 30, "{old:?}");
        // leaves: where no trunk is, the same as the tinted greyscale (within rounding)
        let grey = tint(&impostor_texture(LeafShape::Ovate, 128), leaf);
        let mut n = 0;
        for (x, y) in [(20u32, 40u32), (100, 50), (64, 20), (40, 70)] {
            let (a, b) = (img.get_pixel(x, y).0, grey.get_pixel(x, y).0);
            if a[3] > 0 {
                n += 1;
                assert!(a.iter().zip(b).all(|(a, b)| (*a as i32 - b as i32).abs() <= 2), "{x},{y}: {a:?} against {b:?}");
            }
        }
        assert!(n >= 1);
    }

    /// Fraction of texels at or above the alpha cutoff.
    fn cover(img: &RgbaImage) -> f64 {
        img.pixels().filter(|p| p.0[3] as f32 >= ALPHA_CUTOFF * 255.0).count() as f64 / (img.width() * img.height()) as f64
    }

    #[test]
    fn names_round_trip_and_match_the_schema() {
        for s in LeafShape::ALL {
            assert_eq!(LeafShape::from_name(s.name()), Some(s));
        }
        assert_eq!(LeafShape::from_name("none"), None);
        assert_eq!(LEAF_TEXTURES.len(), LeafShape::ALL.len() + 1);
        assert_eq!(LEAF_TEXTURES[LeafShape::ALL.len()], "none");
        let spec = crate::species::schema::field("appearance.leaf_texture").unwrap();
        assert_eq!(spec.kind, crate::species::schema::Kind::Enum(&LEAF_TEXTURES));
    }

    #[test]
    fn every_shipped_species_has_a_named_shape() {
        let lib = crate::species::SpeciesLibrary::embedded().unwrap();
        for sp in &lib.species {
            assert!(LeafShape::from_name(&sp.appearance.leaf_texture).is_some(), "{}: {}", sp.id, sp.appearance.leaf_texture);
            assert_eq!(LeafShape::of_species(sp).is_needle(), sp.identity.leaf_type == LeafType::Conifer, "{}", sp.id);
        }
    }

    #[test]
    fn an_elliptic_blade_covers_the_area_of_its_ellipse() {
        // a = b = 1/2: half-width w·sqrt(t(1−t))/(1/2): an ellipse of semi-axes L/2 and w
        let b = Blade::new(v2(0.0, 0.0), v2(0.0, 1.0), 0.2, 0.5, 0.5);
        let n = 400;
        let mut hits = 0;
        for i in 0..n {
            for j in 0..n {
                let p = v2(-0.25 + 0.5 * (i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                hits += b.inside(p).is_some() as u32;
            }
        }
        let area = hits as f64 / (n * n) as f64 * 0.5;
        let want = std::f64::consts::PI * 0.5 * 0.2;
        assert!((area - want).abs() / want < 0.01, "{area} vs {want}");
    }

    #[test]
    fn textures_are_deterministic_and_leaves_fill_part_of_their_card() {
        for s in LeafShape::ALL {
            let t = leaf_texture(s);
            assert_eq!((t.width(), t.height()), (LEAF_TEXTURE_W, LEAF_TEXTURE_H));
            assert_eq!(t, leaf_texture(s), "{s:?} not deterministic");
            let c = cover(&t);
            // a leaf is neither a speck nor the whole card
            let (lo, hi) = if s.is_needle() { (0.08, 0.6) } else { (0.2, 0.75) };
            assert!(c > lo && c < hi, "{s:?}: cover {c:.3}");
            // coverage has soft edges (antialiased), not only 0 and 255
            assert!(t.pixels().any(|p| p.0[3] > 0 && p.0[3] < 255), "{s:?}");
        }
    }

    #[test]
    fn lobed_oak_is_narrower_between_lobes_than_the_ovate_leaf() {
        // rows of an oak leaf alternate between wide (lobes) and narrow (sinuses): the row
        // widths vary far more than those of the ovate beech leaf
        let width_var = |img: &RgbaImage| {
            let rows: Vec<f64> = (60..200).map(|y| (0..img.width()).filter(|&x| img.get_pixel(x, y).0[3] >= 128).count() as f64).collect();
            let mut d = 0.0;
            for w in rows.windows(2) {
                d += (w[1] - w[0]).abs();
            }
            d
        };
        let oak = width_var(&leaf_texture(LeafShape::Lobed));
        let beech = width_var(&leaf_texture(LeafShape::Ovate));
        assert!(oak > 2.0 * beech, "oak {oak}, beech {beech}");
    }

    #[test]
    fn the_leaf_points_up_in_the_image() {
        // the petiole (v = 0) is at the bottom: the blade's widest row lies in the upper part
        // of a triangular birch leaf and the bottom rows hold only the thin petiole
        let t = leaf_texture(LeafShape::Triangular);
        let row = |y: u32| (0..t.width()).filter(|&x| t.get_pixel(x, y).0[3] >= 128).count();
        let widest = (0..t.height()).max_by_key(|&y| row(y)).unwrap();
        assert!(widest < t.height() * 3 / 4 && widest > t.height() / 4, "widest row {widest}");
        // the petiole is a few texels wide, the blade tens
        assert!(row(t.height() - 3) <= 8, "petiole row {}", row(t.height() - 3));
        assert!(row(widest) > 60, "widest row {}", row(widest));
    }

    #[test]
    fn tint_multiplies_colour_and_keeps_alpha() {
        let t = tint(&leaf_texture(LeafShape::Round), [255, 128, 0]);
        let o = leaf_texture(LeafShape::Round);
        for (a, b) in t.pixels().zip(o.pixels()) {
            assert_eq!(a.0[3], b.0[3]);
            assert_eq!(a.0[0], b.0[0]);
            assert_eq!(a.0[2], 0);
            assert!((a.0[1] as i32 - (b.0[1] as i32 * 128 / 255)).abs() <= 1);
        }
    }

    #[test]
    fn lod_pictures_have_the_expected_coverage() {
        let cl = cluster_texture(LeafShape::Ovate, 128);
        let c = cover(&cl);
        assert!(c > 0.25 && c < 0.7, "cluster cover {c}");
        assert!(cover(&crown_texture(LeafShape::Ovate, 64)) == 1.0);
        let imp = impostor_texture(LeafShape::NeedleShort, 128);
        let ci = cover(&imp);
        assert!(ci > 0.15 && ci < 0.6, "impostor cover {ci}");
        // a cone: more cover in the lower than in the upper half of the crown
        let half = |y0: u32, y1: u32| (y0..y1).flat_map(|y| (0..128).map(move |x| (x, y))).filter(|&(x, y)| imp.get_pixel(x, y).0[3] >= 128).count();
        assert!(half(64, 100) > half(10, 46), "{} vs {}", half(64, 100), half(10, 46));
    }

    /// Issue 32, round 42: the exported white bark carries the stills' lenticel marks: dark
    /// dashes (0.25 of the colour) in rows of [`BIRCH_ROW_M`] (whole rows of a
    /// [`BARK_TILE_M`] repeat), each dash within its row's middle 0.35, covering 5–25 % of the
    /// texture. Round 41's lenticelled bark (noise bands of 40 a repeat) fails the rows.
    #[test]
    fn white_bark_has_lenticel_rows() {
        let (px, rgb) = (256u32, [230u8, 228, 220]);
        let b = bark_texture(rgb, BarkPattern::Lenticelled, px, 11);
        let rows = (BARK_TILE_M / BIRCH_ROW_M).round();
        let mut dark = 0;
        for (_, y, p) in b.enumerate_pixels() {
            if (p.0[1] as f32) < 0.5 * rgb[1] as f32 {
                dark += 1;
                let v = 1.0 - (y as f32 + 0.5) / px as f32;
                let t = (v * rows).fract();
                assert!((t - 0.5).abs() <= 0.5 * 0.35 + 1.0 / px as f32 * rows, "a mark at v {v}, {t} of its row");
            }
        }
        let share = dark as f32 / (px * px) as f32;
        assert!((0.05..=0.25).contains(&share), "marks cover {share}");
    }

    /// Issue 32, round 43: a texture of 1024 texels is drawn at that size, not enlarged: the
    /// bark's texel-to-texel contrast (mean |Δ| between neighbours) is at least 1.25 × that of
    /// the 256-texel texture enlarged 4 × (nearest neighbour; measured 2.29 against 1.75 for
    /// the fissured bark, whose ridges an enlargement keeps), and a 512 × 1024 leaf's over
    /// the middle of its blade at least 1.5 × that of the 128 × 256 leaf enlarged (bilinear;
    /// an enlargement keeps the total variation, new detail adds to it); the 256-texel bark
    /// has no grain (unchanged).
    #[test]
    fn film_textures_gain_detail_rather_than_being_enlarged() {
        let contrast = |img: &RgbaImage, x0: u32, n: u32, scale: u32| {
            let mut d = 0.0f64;
            for y in 0..n {
                for x in 0..n - 1 {
                    let (a, b) = (img.get_pixel((x0 + x) / scale, y / scale).0, img.get_pixel((x0 + x + 1) / scale, y / scale).0);
                    d += (a[1] as f64 - b[1] as f64).abs();
                }
            }
            d / (n * (n - 1)) as f64
        };
        for p in [BarkPattern::Smooth, BarkPattern::Fissured] {
            let (small, big) = (bark_texture([150, 150, 140], p, 256, 5), bark_texture([150, 150, 140], p, 1024, 5));
            let (c_big, c_up) = (contrast(&big, 0, 256, 1), contrast(&small, 0, 256, 4));
            assert!(c_big >= 1.25 * c_up, "{p:?}: {c_big:.3} against {c_up:.3} enlarged");
        }
        assert_eq!(bark_grain(0.3, 0.7, 256, 5), 0.0);
        let (small, big) = (leaf_texture_sized(LeafShape::Ovate, 128, 256), leaf_texture_sized(LeafShape::Ovate, 512, 1024));
        // a band across the blade's middle (inside the leaf): mean |Δ| between opaque neighbours
        let strip = |img: &RgbaImage| {
            let (w, h) = (img.width(), img.height());
            let (mut d, mut n) = (0.0f64, 0u32);
            for y in h * 2 / 5..h * 3 / 5 {
                for x in w / 2 + w / 32..w / 2 + w * 5 / 16 {
                    let (b, c) = (img.get_pixel(x, y).0, img.get_pixel(x + 1, y).0);
                    if b[3] == 255 && c[3] == 255 {
                        d += (b[1] as f64 - c[1] as f64).abs();
                        n += 1;
                    }
                }
            }
            assert!(n > 1000, "{n} texels");
            d / n as f64
        };
        let big_c = strip(&big);
        let up = image::imageops::resize(&small, 512, 1024, image::imageops::FilterType::Triangle);
        let up_c = strip(&up);
        assert!(big_c >= 1.5 * up_c, "leaf: {big_c:.3} against {up_c:.3} enlarged");
    }

    #[test]
    fn bark_tiles_and_follows_the_species() {
        let lib = crate::species::SpeciesLibrary::embedded().unwrap();
        let pat = |id: &str| BarkPattern::of_species(&lib.species[lib.find(id).unwrap() as usize]);
        assert_eq!(pat("silver_birch"), BarkPattern::Lenticelled);
        assert_eq!(pat("beech"), BarkPattern::Smooth);
        assert_eq!(pat("norway_spruce"), BarkPattern::Plated);
        assert_eq!(pat("pedunculate_oak"), BarkPattern::Fissured);
        for p in [BarkPattern::Smooth, BarkPattern::Fissured, BarkPattern::Plated, BarkPattern::Lenticelled] {
            let b = bark_texture([120, 100, 80], p, 64, 7);
            // seamless: the first and last columns (and rows) differ as little as neighbours do
            let diff = |a: (u32, u32), c: (u32, u32)| (0..3).map(|k| (b.get_pixel(a.0, a.1).0[k] as i32 - b.get_pixel(c.0, c.1).0[k] as i32).abs()).sum::<i32>();
            let seam: i32 = (0..64).map(|y| diff((0, y), (63, y))).sum::<i32>() + (0..64).map(|x| diff((x, 0), (x, 63))).sum::<i32>();
            let inner: i32 = (0..64).map(|y| diff((31, y), (32, y))).sum::<i32>() + (0..64).map(|x| diff((x, 31), (x, 32))).sum::<i32>();
            assert!(seam <= 3 * inner.max(20), "{p:?}: seam {seam}, inner {inner}");
            assert!(b.pixels().all(|p| p.0[3] == 255));
        }
    }
}
