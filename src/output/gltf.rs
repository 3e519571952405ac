//! glTF 2.0 binary (`.glb`) writer for trees and stands (JSON checked with `gltf-json`; the
//! files pass the Khronos glTF validator with no error and no warning, `tests/export_gltf.rs`).
//!
//! **A tree** ([`glb_bytes`]): one buffer (the GLB BIN chunk, images included); per level of
//! detail one mesh named `<name>_LOD<i>` with up to two primitives (bark, foliage; empty parts
//! are left out) and one node of the same name, children of a node `<name>`: the naming by which
//! Unity's and Unreal's importers gather levels into a LOD group. **A stand**
//! ([`stand_glb_bytes`]): the same per tree (node `<tree>` with its translation and scale,
//! children `<tree>_LOD<i>`), meshes shared by every tree node that uses them (instancing: one
//! mesh, many nodes), the saplings of the regeneration layer so too (under node `saplings`),
//! plus static meshes (terrain, obstacles) under node `ground`.
//!
//! **Materials** per [`Look`] (a species in a season): `<look>_bark` (opaque, tiling bark
//! texture), `<look>_leaf` (LOD0 leaf cards), `<look>_cluster` (LOD1 leaf-cluster cards) and
//! `<look>_impostor` (LOD3 billboard), all three double-sided with `alphaMode: MASK` and
//! `alphaCutoff` [`ALPHA_CUTOFF`], and `<look>_crown` (LOD2 hull, opaque); a white-barked
//! species (silver birch) also `<look>_bark_base` (opaque), the dark base of its stems below
//! [`crate::structure::texture::BARK_BASE_M`] (a primitive of its own,
//! [`crate::structure::texture::split_bark_base`]; round 45). Each has a
//! `baseColorTexture` on `TEXCOORD_0`, a PNG embedded in the buffer, made by
//! [`crate::structure::texture`] with the colours baked in (base colour factor white);
//! identical images are stored once. Card textures clamp, bark and crown textures repeat.
//! Static meshes get an untextured material of their colour and no texture coordinates, or,
//! with a texture ([`StaticMesh::texture`]: the terrain's leaf litter), a material of their name
//! with it, repeating, on their texture coordinates.
//!
//! Sylva's z-up coordinates are converted to glTF's y-up: (x, y, z) ↦ (x, z, −y)
//! (right-handed both ways); texture v is flipped (glTF's origin is the image's top-left).
//! Positions carry the min/max bounds the specification requires.

use super::{OutputError, Result};
use crate::error::Error;
use crate::mesh::{LodChain, TriMesh};
use crate::species::{Season, Species};
use crate::structure::texture::{self, BarkPattern, FoliageTextures, LeafShape, ALPHA_CUTOFF};
use image::RgbaImage;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::Path;

/// The materials of one kind of tree: a name and its textures.
#[derive(Debug, Clone, PartialEq)]
pub struct Look {
    /// Name prefix of the materials (`<name>_bark`, `<name>_leaf`, …).
    pub name: String,
    /// The textures (colours baked in).
    pub textures: FoliageTextures,
}

impl Look {
    /// The look of species `sp` in `season` ([`FoliageTextures::for_species`]), named by its id.
    pub fn for_species(sp: &Species, season: Season) -> Look {
        Look { name: sp.id.clone(), textures: FoliageTextures::for_species(sp, season) }
    }

    /// [`Look::for_species`] with textures of `size` texels
    /// ([`FoliageTextures::for_species_sized`]; `--texture-size`, [`check_texture_size`]).
    pub fn for_species_sized(sp: &Species, season: Season, size: u32) -> Look {
        Look { name: sp.id.clone(), textures: FoliageTextures::for_species_sized(sp, season, size) }
    }

    /// This look with its billboard picture baked from `chain`'s own full level
    /// ([`texture::baked_impostor`], laid out as the chain's billboard, level 3, maps it), at the
    /// size of the look's impostor picture, the trunk in the bark picture's mean colour
    /// ([`texture::mean_rgb`]): the billboard of ONE tree (`sylva tree grow`, `tree adapt`)
    /// then has that tree's outline and coverage (issue 32, round 46). The look unchanged when
    /// the chain has no billboard level or no full level.
    pub fn with_tree_impostor(&self, chain: &crate::mesh::LodChain) -> Look {
        let t = &self.textures;
        let (Some(full), Some(bb)) = (chain.levels.first(), chain.levels.get(3)) else { return self.clone() };
        match texture::baked_impostor(full, bb, &t.leaf, &t.cluster, texture::mean_rgb(&t.bark), t.impostor.width()) {
            Some(img) => Look { name: self.name.clone(), textures: FoliageTextures { impostor: img, ..t.clone() } },
            None => self.clone(),
        }
    }

    /// A look from colours (sRGB 0–255), a leaf shape and a bark pattern.
    pub fn plain(name: &str, bark_rgb: [u8; 3], leaf_rgb: [u8; 3], shape: LeafShape, bark: BarkPattern) -> Look {
        let px = texture::TEXTURE_PX;
        Look {
            name: name.into(),
            textures: FoliageTextures {
                shape,
                leaf: texture::tint(&texture::leaf_texture(shape), leaf_rgb),
                cluster: texture::tint(&texture::cluster_texture(shape, px), leaf_rgb),
                crown: texture::tint(&texture::crown_texture(shape, px), leaf_rgb),
                impostor: texture::impostor_texture_coloured(shape, px, leaf_rgb, bark_rgb),
                bark: texture::bark_texture(bark_rgb, bark, px, 1),
                bark_base: None,
            },
        }
    }
}

impl Default for Look {
    /// `tree`: a brown fissured bark (96, 72, 52) and ovate leaves (70, 120, 50).
    fn default() -> Self {
        Look::plain("tree", [96, 72, 52], [70, 120, 50], LeafShape::Ovate, BarkPattern::Fissured)
    }
}

/// Smallest and largest `--texture-size` of the export commands (texels).
pub const TEXTURE_SIZES: [u32; 2] = [256, 4096];

/// Checks a `--texture-size` of the export commands: a power of two from 256 to 4096
/// ([`TEXTURE_SIZES`]); `option` names it in the error ("--texture-size").
///
/// Errors: [`Error::Invalid`] naming `option`, the value and the sizes expected.
pub fn check_texture_size(option: &str, size: u32) -> std::result::Result<u32, Error> {
    if size.is_power_of_two() && (TEXTURE_SIZES[0]..=TEXTURE_SIZES[1]).contains(&size) {
        Ok(size)
    } else {
        Err(Error::Invalid { context: option.into(), field: "texture size".into(), value: size.to_string(), expected: "a power of two from 256 to 4096 texels (256, 512, 1024, 2048 or 4096)".into() })
    }
}

/// Options of [`write_glb`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlbOptions {
    /// Name of the tree: the root node, and `<name>_LOD<i>` for the levels.
    pub name: String,
    /// Materials.
    pub look: Look,
    /// Distance (m) between LOD nodes along x, so all levels can be seen side by side; 0 (the
    /// default, what LOD groups expect) puts them on top of each other.
    pub spacing_m: f32,
}

impl Default for GlbOptions {
    /// Name `tree`, the default [`Look`], spacing 0.
    fn default() -> Self {
        GlbOptions { name: "tree".into(), look: Look::default(), spacing_m: 0.0 }
    }
}

/// Sylva's frame (x east, y north, z up) to the y-up frame of glTF and OBJ (x, z, −y):
/// right-handed, north along −z.
pub(crate) fn y_up(p: [f32; 3]) -> [f32; 3] {
    [p[0], p[2], -p[1]]
}

// glTF constants (glTF 2.0 specification, sections 3.6 and 5.26).
const F32: u32 = 5126;
const U32: u32 = 5125;
const U16: u32 = 5123;
const I16: u32 = 5122;
const I8: u32 = 5120;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const LINEAR: u32 = 9729;
const LINEAR_MIPMAP_LINEAR: u32 = 9987;
const CLAMP_TO_EDGE: u32 = 33071;
const REPEAT: u32 = 10497;
/// Repeats of the crown texture round (u) and up (v) the LOD2 hull, whose texture coordinates
/// go once round it (`structure::mesh::hull_mesh`): about one picture per metre of a crown
/// 6 m across.
pub const CROWN_REPEAT: [f32; 2] = [6.0, 3.0];
/// Whether quantised flat cards are written without their normals ([`normals_are_flat`]; 4 B a
/// card vertex, 36 MB of trial 45's 0.25 ha): off. Round 46's check in Debian's Blender 3.4
/// (12 trees of trial 45, Cycles): without them the crowns render lighter and greener than with
/// the written normals (Blender shades a card without custom normals by its winding), a visible
/// change; on only once the leaf cards' normals and winding agree.
const DROP_FLAT_CARD_NORMALS: bool = false;

/// What a primitive of a tree draws, for its quantisation ([`Doc::primitive_q`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    /// Bark: repeating texture coordinates ([`BARK_UV_STEPS`]).
    Bark,
    /// Double-sided flat cards (leaves, leaf clusters, billboards): normals left out where
    /// they are the faces' ([`normals_are_flat`]) if [`DROP_FLAT_CARD_NORMALS`].
    Cards,
    /// Anything else (the crown hull).
    Other,
}

/// Whether every vertex normal of `m` is its triangles' face normal or its opposite, within
/// 2° (a card's normal as its leaf faces; a zero-area triangle has none and passes): what a
/// double-sided card draws without its normals.
fn normals_are_flat(m: &TriMesh) -> bool {
    let cos_max = 2f32.to_radians().cos();
    m.indices.chunks_exact(3).all(|t| {
        let p = |k: usize| glam::Vec3::from(m.positions[t[k] as usize]);
        let face = (p(1) - p(0)).cross(p(2) - p(0));
        if face.length_squared() < 1e-20 {
            return true;
        }
        let face = face.normalize();
        t.iter().all(|&i| face.dot(glam::Vec3::from(m.normals[i as usize]).normalize_or_zero()).abs() >= cos_max)
    })
}

/// Sampler indices of [`Doc::new`].
const SAMPLER_CLAMP: usize = 0;
const SAMPLER_REPEAT: usize = 1;

/// Material indices of one [`Look`]: bark, then foliage per level (leaf, cluster, crown,
/// impostor); `None` for a material no written level uses.
#[derive(Debug, Clone, Copy)]
struct LookMaterials {
    bark: Option<usize>,
    foliage: [Option<usize>; 4],
    /// `<look>_bark_base`: the dark base of a white bark ([`FoliageTextures::bark_base`]).
    bark_base: Option<usize>,
}

/// The glTF document being built, with `serde_json` (gltf-json's struct fields change with its
/// "names" feature, which the dev-dependency `gltf` turns on, so struct literals would not
/// compile in both builds); the result is checked by parsing it back with `gltf-json`.
struct Doc {
    views: Vec<Value>,
    accessors: Vec<Value>,
    /// The BIN chunk's first bytes, held, before the spilled ones: the textures of a stand
    /// written tree by tree ([`StandGlbWriter`]), known only once every tree is written; empty
    /// otherwise.
    head: Vec<u8>,
    /// The BIN chunk's bytes not yet spilled ([`Doc::spill`]).
    bin: Vec<u8>,
    /// Where the BIN chunk's bytes go once [`SPILL_BYTES`] are held (a stand written by
    /// [`StandGlbWriter`]: a scratch file beside the output, so that the buffer is not held
    /// in memory), the bytes already written there, and the first write error.
    spill: Option<Spill>,
    images: Vec<Value>,
    textures: Vec<Value>,
    materials: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    /// (PNG bytes, sampler) → texture index.
    texture_of: HashMap<(Vec<u8>, usize), usize>,
    /// Extensions the document uses (`extensionsUsed`).
    extensions_used: Vec<&'static str>,
    /// Extensions without which the document is wrong (`extensionsRequired`, a subset of
    /// `extensions_used`): an importer that lacks one refuses the file instead of showing
    /// something else.
    extensions_required: Vec<&'static str>,
    /// Whether tree meshes are written quantised ([`Quant`], `KHR_mesh_quantization`): stand
    /// exports, unless `--no-quantize`.
    quantize: bool,
    /// The dequantisation of each quantised mesh (by mesh index), which the nodes that draw it
    /// carry as their translation and scale.
    mesh_quant: HashMap<usize, Quant>,
}

/// `KHR_mesh_quantization` (Khronos, ratified 2020): the extension that lets vertex attributes
/// be 8- and 16-bit integers.
pub const MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

/// `KHR_texture_transform` (Khronos, ratified): the texture-coordinate transform by which a
/// quantised bark's integer texture coordinates are scaled back ([`BARK_UV_STEPS`]).
pub const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

/// Steps a bark texture repeat is divided into where the bark's texture coordinates are
/// quantised: they are stored as 16-bit unsigned integers of 1/64 repeat (after taking the
/// whole repeats below the primitive's lowest one away: the texture repeats), and the bark
/// materials scale them back by 1/64 (`KHR_texture_transform`). A texture coordinate moves by at
/// most 1/128 of a repeat; a primitive spanning more than 1,023 repeats keeps floats (times 64).
pub const BARK_UV_STEPS: f32 = 64.0;

/// Largest magnitude of a quantised position component (16-bit signed normalised:
/// glTF 2.0 specification, section 3.11, `f = max(c / 32767.0, -1.0)`).
pub const QUANT_MAX: f32 = 32767.0;

/// The dequantisation of a quantised tree mesh (`KHR_mesh_quantization`, which leaves it to the
/// node: "the extension relies on existing ways to specify geometry transformation"): its
/// positions (y up, m) are stored as 16-bit signed normalised integers q ∈ [−1, 1] per axis,
/// p = `offset` + `scale` · q, and every node drawing the mesh has translation `offset` and
/// uniform scale `scale` (uniform, so that normals need no correction). `scale` is half the
/// mesh's largest extent: the step between stored positions is `scale` / 32767 (0.46 mm for a
/// 30 m tree), and a position is within half a step of its unquantised value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quant {
    /// Centre of the mesh's bounds (m, y up).
    pub offset: [f32; 3],
    /// Half the mesh's largest extent (m, > 0).
    pub scale: f32,
}

impl Quant {
    /// The dequantisation of the meshes `parts` together (Sylva's z-up positions); `None` when
    /// they have no vertex.
    pub fn of<'a>(parts: impl IntoIterator<Item = &'a TriMesh>) -> Option<Quant> {
        let (lo, hi) = crate::mesh::points_bounds(parts.into_iter().flat_map(|m| m.positions.iter()))?;
        let (lo, hi) = (y_up(lo), y_up(hi));
        // y_up swaps and negates: the bounds again as min and max
        let (lo, hi) = ([lo[0].min(hi[0]), lo[1].min(hi[1]), lo[2].min(hi[2])], [lo[0].max(hi[0]), lo[1].max(hi[1]), lo[2].max(hi[2])]);
        let offset = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
        let scale = (0..3).map(|k| 0.5 * (hi[k] - lo[k])).fold(0.0f32, f32::max).max(1e-6);
        Some(Quant { offset, scale })
    }

    /// The stored integers of a y-up position `p` (m), padded to 4 components (the 4-byte
    /// alignment of vertex attributes, glTF 2.0 section 3.6.2.4).
    pub fn encode(&self, p: [f32; 3]) -> [i16; 4] {
        let q = |k: usize| ((p[k] - self.offset[k]) / self.scale * QUANT_MAX).round().clamp(-QUANT_MAX, QUANT_MAX) as i16;
        [q(0), q(1), q(2), 0]
    }

    /// The position (m, y up) of stored integers `q`: `offset + scale · q / 32767`.
    pub fn decode(&self, q: [i16; 3]) -> [f32; 3] {
        [0, 1, 2].map(|k| self.offset[k] + self.scale * (q[k] as f32 / QUANT_MAX).max(-1.0))
    }

    /// The step between stored positions (m): `scale` / 32767.
    pub fn step_m(&self) -> f32 {
        self.scale / QUANT_MAX
    }
}

/// Bytes of the BIN chunk a [`Doc`] with a scratch file holds before writing them there (8 MiB).
const SPILL_BYTES: usize = 8 << 20;

/// The scratch file of a [`Doc`]'s BIN chunk.
struct Spill {
    /// Held bytes from which they are written ([`SPILL_BYTES`]; less in tests).
    at: usize,
    path: std::path::PathBuf,
    w: std::io::BufWriter<std::fs::File>,
    written: usize,
    error: Option<std::io::Error>,
    _pending: super::Pending,
}

impl Drop for Spill {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

impl Doc {
    fn new() -> Doc {
        Doc { views: Vec::new(), accessors: Vec::new(), head: Vec::new(), bin: Vec::new(), spill: None, images: Vec::new(), textures: Vec::new(), materials: Vec::new(), meshes: Vec::new(), nodes: Vec::new(), texture_of: HashMap::new(), extensions_used: Vec::new(), extensions_required: Vec::new(), quantize: false, mesh_quant: HashMap::new() }
    }

    /// Marks extension `name` used, and required when `required`.
    fn uses(&mut self, name: &'static str, required: bool) {
        if !self.extensions_used.contains(&name) {
            self.extensions_used.push(name);
        }
        if required && !self.extensions_required.contains(&name) {
            self.extensions_required.push(name);
        }
    }

    /// A document whose BIN chunk goes to the scratch file `<tmp of out>.bin` beside `out`
    /// (removed when the document is dropped or finished).
    fn spilling(out: &Path, at: usize) -> Result<Doc> {
        let path = super::temporary_path(&glb_scratch_of(out));
        let pending = super::Pending::register(&path);
        let f = std::fs::File::create(&path).map_err(|e| OutputError::io(&path, e))?;
        let mut d = Doc::new();
        d.spill = Some(Spill { at, path, w: std::io::BufWriter::new(f), written: 0, error: None, _pending: pending });
        Ok(d)
    }

    /// Length of the BIN chunk so far (head, spilled and held).
    fn bin_len(&self) -> usize {
        self.head.len() + self.spill.as_ref().map_or(0, |s| s.written) + self.bin.len()
    }

    fn view(&mut self, bytes: &[u8], stride: Option<usize>, target: Option<u32>) -> usize {
        while self.bin_len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin_len();
        self.bin.extend_from_slice(bytes);
        let held = self.bin.len();
        if let Some(sp) = self.spill.as_mut().filter(|sp| held >= sp.at) {
            use std::io::Write;
            if sp.error.is_none() {
                if let Err(e) = sp.w.write_all(&self.bin) {
                    sp.error = Some(e);
                }
            }
            sp.written += self.bin.len();
            self.bin.clear();
        }
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(&mut self, view: usize, count: usize, ct: u32, ty: &str, minmax: Option<([f32; 3], [f32; 3])>) -> usize {
        let mut a = json!({"bufferView": view, "byteOffset": 0, "count": count, "componentType": ct, "type": ty});
        if let Some((lo, hi)) = minmax {
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// The texture of `img` (PNG in the buffer) with `sampler`; identical ones are shared.
    fn texture(&mut self, img: &RgbaImage, sampler: usize) -> Result<usize> {
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).map_err(|e| OutputError::Serialize { what: "glb texture".into(), format: "PNG", message: e.to_string() })?;
        if let Some(&t) = self.texture_of.get(&(png.clone(), sampler)) {
            return Ok(t);
        }
        let view = self.view(&png, None, None);
        self.images.push(json!({"bufferView": view, "mimeType": "image/png"}));
        self.textures.push(json!({"source": self.images.len() - 1, "sampler": sampler}));
        let t = self.textures.len() - 1;
        self.texture_of.insert((png, sampler), t);
        Ok(t)
    }

    fn material(&mut self, m: Value) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    /// The materials of `look` (module documentation) that the LOD `levels` use: bark for
    /// levels 0–2, the foliage material of each level (levels ≥ 3: the impostor).
    fn look(&mut self, look: &Look, levels: &[usize]) -> Result<LookMaterials> {
        let t = &look.textures;
        let tex = |index: usize| json!({"index": index, "texCoord": 0});
        // a quantised stand's bark texture coordinates are integers of 1/64 repeat
        let quantize = self.quantize;
        let bark_tex = |index: usize| {
            let mut info = tex(index);
            if quantize {
                let mut ext = serde_json::Map::new();
                ext.insert(TEXTURE_TRANSFORM.into(), json!({"scale": [1.0 / BARK_UV_STEPS, 1.0 / BARK_UV_STEPS]}));
                info["extensions"] = Value::Object(ext);
            }
            info
        };
        if quantize && levels.iter().any(|&l| l < 3) {
            self.uses(TEXTURE_TRANSFORM, true);
        }
        let (mut bark, mut bark_base) = (None, None);
        if levels.iter().any(|&l| l < 3) {
            let bark_t = self.texture(&t.bark, SAMPLER_REPEAT)?;
            bark = Some(self.material(json!({"name": format!("{}_bark", look.name), "pbrMetallicRoughness": {"baseColorTexture": bark_tex(bark_t), "metallicFactor": 0.0, "roughnessFactor": 0.95}})));
            if let Some(img) = &t.bark_base {
                let ti = self.texture(img, SAMPLER_REPEAT)?;
                bark_base = Some(self.material(json!({"name": format!("{}_bark_base", look.name), "pbrMetallicRoughness": {"baseColorTexture": bark_tex(ti), "metallicFactor": 0.0, "roughnessFactor": 0.95}})));
            }
        }
        let mut foliage = [None; 4];
        for (k, (part, img, sampler)) in [("leaf", &t.leaf, SAMPLER_CLAMP), ("cluster", &t.cluster, SAMPLER_CLAMP), ("crown", &t.crown, SAMPLER_REPEAT), ("impostor", &t.impostor, SAMPLER_CLAMP)].into_iter().enumerate() {
            if !levels.iter().any(|&l| l.min(3) == k) {
                continue;
            }
            let ti = self.texture(img, sampler)?;
            let mut m = json!({"name": format!("{}_{part}", look.name), "pbrMetallicRoughness": {"baseColorTexture": tex(ti), "metallicFactor": 0.0, "roughnessFactor": 0.8}});
            if part != "crown" {
                m["alphaMode"] = json!("MASK");
                m["alphaCutoff"] = json!(ALPHA_CUTOFF);
                m["doubleSided"] = json!(true);
            }
            foliage[k] = Some(self.material(m));
        }
        Ok(LookMaterials { bark, foliage, bark_base })
    }

    /// A plain material of sRGB colour `rgb`.
    fn plain(&mut self, name: &str, rgb: [u8; 3], roughness: f32) -> usize {
        let [r, g, b] = crate::species::srgb_to_linear([rgb[0], rgb[1], rgb[2]]);
        let c = [r, g, b, 1.0];
        self.material(json!({"name": name, "pbrMetallicRoughness": {"baseColorFactor": c, "metallicFactor": 0.0, "roughnessFactor": roughness}}))
    }

    /// A primitive of `m` in `material`; texture coordinates only when `uv` (a textured
    /// material) and the mesh has them. `None` for an empty mesh.
    fn primitive(&mut self, m: &TriMesh, material: usize, uv: bool) -> Option<Value> {
        self.primitive_uv(m, material, uv, [1.0, 1.0])
    }

    /// [`Doc::primitive`] with texture coordinates multiplied by `uv_scale` (the crown hull's
    /// once-round coordinates repeat its leafy texture [`CROWN_REPEAT`] times).
    fn primitive_uv(&mut self, m: &TriMesh, material: usize, uv: bool, uv_scale: [f32; 2]) -> Option<Value> {
        self.primitive_q(m, material, uv, uv_scale, None, Part::Other)
    }

    /// [`Doc::primitive_uv`], quantised by `quant` where given (`KHR_mesh_quantization`):
    /// positions as 16-bit signed normalised integers ([`Quant`]; 8 bytes a vertex with the
    /// padding instead of 12), normals as 8-bit signed normalised (4 bytes instead of 12: a
    /// direction within 0.5° of the unquantised), texture coordinates within 0–1 (the cards')
    /// as 16-bit unsigned normalised (4 bytes instead of 8, a step of 1/65,535; others stay
    /// floats; a `bark` primitive's in 1/64 repeat steps, [`BARK_UV_STEPS`], which its material
    /// scales back), and indices 16-bit where the primitive has at most 65,535 vertices (core
    /// glTF).
    fn primitive_q(&mut self, m: &TriMesh, material: usize, uv: bool, uv_scale: [f32; 2], quant: Option<Quant>, part: Part) -> Option<Value> {
        let bark = part == Part::Bark;
        if m.positions.is_empty() || m.indices.is_empty() {
            return None;
        }
        let pos: Vec<[f32; 3]> = m.positions.iter().map(|&p| y_up(p)).collect();
        let n = pos.len();
        let mut attributes = serde_json::Map::new();
        match quant {
            Some(q) => {
                let enc: Vec<[i16; 4]> = pos.iter().map(|&p| q.encode(p)).collect();
                let (mut lo, mut hi) = ([i16::MAX; 3], [i16::MIN; 3]);
                for e in &enc {
                    for k in 0..3 {
                        lo[k] = lo[k].min(e[k]);
                        hi[k] = hi[k].max(e[k]);
                    }
                }
                let pv = self.view(bytemuck::cast_slice(&enc), Some(8), Some(ARRAY_BUFFER));
                let pa = self.accessor(pv, n, I16, "VEC3", None);
                // bounds as stored (glTF 2.0, accessor.min: "the normalized property has no
                // effect on array values: they always correspond to the actual values stored
                // in the buffer")
                self.accessors[pa]["normalized"] = json!(true);
                self.accessors[pa]["min"] = json!(lo);
                self.accessors[pa]["max"] = json!(hi);
                attributes.insert("POSITION".into(), json!(pa));
                self.uses(MESH_QUANTIZATION, true);
            }
            None => {
                let (mut lo, mut hi) = (pos[0], pos[0]);
                for p in &pos {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                let pv = self.view(bytemuck::cast_slice(&pos), Some(12), Some(ARRAY_BUFFER));
                let pa = self.accessor(pv, n, F32, "VEC3", Some((lo, hi)));
                attributes.insert("POSITION".into(), json!(pa));
            }
        }
        // flat double-sided cards whose normals are their faces' (either side) leave them out:
        // glTF's importers then use the faces' own ("client implementations MUST calculate
        // flat normals", glTF 2.0 section 3.7.2.1), the same shading
        let flat = DROP_FLAT_CARD_NORMALS && quant.is_some() && part == Part::Cards && m.normals.len() == n && normals_are_flat(m);
        if m.normals.len() == n && !flat {
            // unit length as the specification requires (a zero normal becomes up)
            let nrm: Vec<glam::Vec3> = m.normals.iter().map(|&p| glam::Vec3::from(y_up(p)).normalize_or(glam::Vec3::Y)).collect();
            let na = if quant.is_some() {
                let enc: Vec<[i8; 4]> = nrm.iter().map(|v| [v.x, v.y, v.z].map(|c| (c * 127.0).round().clamp(-127.0, 127.0) as i8)).map(|[x, y, z]| [x, y, z, 0]).collect();
                let nv = self.view(bytemuck::cast_slice(&enc), Some(4), Some(ARRAY_BUFFER));
                let a = self.accessor(nv, n, I8, "VEC3", None);
                self.accessors[a]["normalized"] = json!(true);
                a
            } else {
                let nrm: Vec<[f32; 3]> = nrm.iter().map(|v| v.to_array()).collect();
                let nv = self.view(bytemuck::cast_slice(&nrm), Some(12), Some(ARRAY_BUFFER));
                self.accessor(nv, n, F32, "VEC3", None)
            };
            attributes.insert("NORMAL".into(), json!(na));
        }
        if uv && m.uvs.len() == n {
            let uv: Vec<[f32; 2]> = m.uvs.iter().map(|&[u, v]| [u * uv_scale[0], 1.0 - v * uv_scale[1]]).collect();
            let ua = if quant.is_some() && bark {
                // the bark's: 1/64 repeat steps from the whole repeat below the lowest (BARK_UV_STEPS)
                let floor = [0, 1].map(|k| uv.iter().map(|t| t[k]).fold(f32::MAX, f32::min).floor());
                let steps: Vec<[f32; 2]> = uv.iter().map(|t| [0, 1].map(|k| ((t[k] - floor[k]) * BARK_UV_STEPS).round())).collect();
                if steps.iter().flatten().all(|&c| c <= u16::MAX as f32) {
                    let enc: Vec<[u16; 2]> = steps.iter().map(|t| t.map(|c| c as u16)).collect();
                    let uvv = self.view(bytemuck::cast_slice(&enc), Some(4), Some(ARRAY_BUFFER));
                    self.accessor(uvv, n, U16, "VEC2", None)
                } else {
                    let f: Vec<[f32; 2]> = uv.iter().map(|t| t.map(|c| c * BARK_UV_STEPS)).collect();
                    let uvv = self.view(bytemuck::cast_slice(&f), Some(8), Some(ARRAY_BUFFER));
                    self.accessor(uvv, n, F32, "VEC2", None)
                }
            } else if quant.is_some() && uv.iter().flatten().all(|c| (0.0..=1.0).contains(c)) {
                let enc: Vec<[u16; 2]> = uv.iter().map(|t| t.map(|c| (c * 65535.0).round() as u16)).collect();
                let uvv = self.view(bytemuck::cast_slice(&enc), Some(4), Some(ARRAY_BUFFER));
                let a = self.accessor(uvv, n, U16, "VEC2", None);
                self.accessors[a]["normalized"] = json!(true);
                a
            } else {
                let uvv = self.view(bytemuck::cast_slice(&uv), Some(8), Some(ARRAY_BUFFER));
                self.accessor(uvv, n, F32, "VEC2", None)
            };
            attributes.insert("TEXCOORD_0".into(), json!(ua));
        }
        let ia = if quant.is_some() && n <= u16::MAX as usize {
            // 65,535 itself is the primitive restart value, which glTF forbids
            let idx: Vec<u16> = m.indices.iter().map(|&i| i as u16).collect();
            let iv = self.view(bytemuck::cast_slice(&idx), None, Some(ELEMENT_ARRAY_BUFFER));
            self.accessor(iv, idx.len(), U16, "SCALAR", None)
        } else {
            let iv = self.view(bytemuck::cast_slice(&m.indices), None, Some(ELEMENT_ARRAY_BUFFER));
            self.accessor(iv, m.indices.len(), U32, "SCALAR", None)
        };
        Some(json!({"attributes": attributes, "indices": ia, "material": material, "mode": 4}))
    }

    /// A mesh named `name` of `prims`; `None` when all are empty.
    fn mesh(&mut self, name: &str, prims: Vec<Option<Value>>) -> Option<usize> {
        let prims: Vec<Value> = prims.into_iter().flatten().collect();
        if prims.is_empty() {
            return None;
        }
        self.meshes.push(json!({"name": name, "primitives": prims}));
        Some(self.meshes.len() - 1)
    }

    /// The meshes of a LOD chain, `<name>_LOD<i>`, for the levels in `levels` (`None`: empty or
    /// not written).
    fn chain(&mut self, name: &str, chain: &LodChain, mats: LookMaterials, levels: &[usize]) -> Vec<Option<usize>> {
        self.chain_with_sprigs(name, chain, &TriMesh::default(), mats, levels)
    }

    /// [`Doc::chain`] with leaf-cluster cards `sprigs` added to the full level (LOD0) as a
    /// third primitive in the look's cluster material (created by [`Doc::look`] when level 1
    /// is among its levels; without it the sprigs are left out), together with the cards of
    /// the full level's leaves marked by [`crate::mesh::CLUSTER_CARD_U`]
    /// ([`TriMesh::split_cluster_cards`]).
    fn chain_with_sprigs(&mut self, name: &str, chain: &LodChain, sprigs: &TriMesh, mats: LookMaterials, levels: &[usize]) -> Vec<Option<usize>> {
        let empty = TriMesh::default();
        chain
            .levels
            .iter()
            .enumerate()
            .map(|(i, level)| {
                if !levels.contains(&i) {
                    return None;
                }
                // a white bark's dark base in a material of its own (FoliageTextures::bark_base)
                let split_base = mats.bark_base.map(|_| texture::split_bark_base(&level.bark));
                let (upper, base): (&TriMesh, &TriMesh) = match &split_base {
                    Some((u, b)) => (u, b),
                    None => (&level.bark, &empty),
                };
                let scale = if i == 2 { CROWN_REPEAT } else { [1.0, 1.0] };
                // leaf-cluster cards marked among the full level's leaves (a lone tree's crown
                // leaf area, `job::leaf_area::lone_tree_sprigs`) go with the given sprigs
                let split = (i == 0 && level.leaves.has_cluster_cards()).then(|| {
                    let (cards, mut marked) = level.leaves.split_cluster_cards();
                    marked.append(sprigs);
                    (cards, marked)
                });
                let (cards, sprigs) = split.as_ref().map_or((&level.leaves, sprigs), |(c, s)| (c, s));
                let sprigs = if i == 0 { sprigs } else { &empty };
                // one dequantisation for all the level's parts: the node drawing it carries it
                let quant = if self.quantize { Quant::of([upper, base, cards, sprigs]) } else { None };
                let bark = mats.bark.and_then(|m| self.primitive_q(upper, m, true, [1.0, 1.0], quant, Part::Bark));
                let base = mats.bark_base.and_then(|m| self.primitive_q(base, m, true, [1.0, 1.0], quant, Part::Bark));
                let leaves = mats.foliage[i.min(3)].and_then(|m| self.primitive_q(cards, m, true, scale, quant, if i == 2 { Part::Other } else { Part::Cards }));
                let extra = if i == 0 && !sprigs.indices.is_empty() { mats.foliage[1].and_then(|m| self.primitive_q(sprigs, m, true, [1.0, 1.0], quant, Part::Cards)) } else { None };
                let mesh = self.mesh(&format!("{name}_LOD{i}"), vec![bark, base, leaves, extra]);
                if let (Some(mesh), Some(q)) = (mesh, quant) {
                    self.mesh_quant.insert(mesh, q);
                }
                mesh
            })
            .collect()
    }

    fn node(&mut self, n: Value) -> usize {
        self.nodes.push(n);
        self.nodes.len() - 1
    }

    /// The GLB bytes of the document with one scene of `roots`.
    fn finish(mut self, scene: Value) -> Result<Vec<u8>> {
        let (js, total) = self.finish_json(scene)?;
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(&glb_header(total, &js, self.bin_len()));
        out.extend_from_slice(&self.head);
        out.extend_from_slice(&self.bin);
        Ok(out)
    }

    /// Writes the GLB of the document with one scene to `path` (atomically), its BIN chunk
    /// copied from the scratch file of [`Doc::spilling`], which is then removed.
    fn finish_to(mut self, scene: Value, path: &Path) -> Result<()> {
        use std::io::{Read, Write};
        let (js, total) = self.finish_json(scene)?;
        let bin_len = self.bin_len();
        let Some(mut sp) = self.spill.take() else {
            let bytes = [glb_header(total, &js, bin_len), std::mem::take(&mut self.head), std::mem::take(&mut self.bin)].concat();
            return super::write_atomic(path, &bytes);
        };
        let spilled = (|| {
            if let Some(e) = sp.error.take() {
                return Err(e);
            }
            sp.w.flush()
        })();
        spilled.map_err(|e| OutputError::io(&sp.path, e))?;
        let scratch = std::fs::File::open(&sp.path).map_err(|e| OutputError::io(&sp.path, e))?;
        let held = std::mem::take(&mut self.bin);
        let head = std::mem::take(&mut self.head);
        super::write_atomic_with(path, |w| {
            w.write_all(&glb_header(total, &js, bin_len))?;
            w.write_all(&head)?;
            let copied = std::io::copy(&mut scratch.take(sp.written as u64), w)?;
            if copied != sp.written as u64 {
                return Err(std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "the scratch file of the glb's buffer is short"));
            }
            w.write_all(&held)
        })
        // `sp` dropped here: the scratch file is removed
    }

    /// Names each image after the first material that uses it (`<species>_bark`,
    /// `<species>_leaf`, `terrain`, …; a texture other than the base colour adds its slot:
    /// `<material>_normal`), so that an importer lists them by name rather than as
    /// `Image_0…` (trial 42). An image no material uses keeps no name.
    fn name_images(&mut self) {
        let slots = [("baseColorTexture", ""), ("metallicRoughnessTexture", "_metallic_roughness")];
        let other = [("normalTexture", "_normal"), ("occlusionTexture", "_occlusion"), ("emissiveTexture", "_emissive")];
        for m in &self.materials {
            let Some(name) = m["name"].as_str() else { continue };
            let refs = slots.iter().map(|(k, suffix)| (&m["pbrMetallicRoughness"][k], suffix)).chain(other.iter().map(|(k, suffix)| (&m[k], suffix)));
            for (r, suffix) in refs {
                let Some(t) = r["index"].as_u64() else { continue };
                let Some(src) = self.textures.get(t as usize).and_then(|t| t["source"].as_u64()) else { continue };
                if let Some(img) = self.images.get_mut(src as usize) {
                    if img.get("name").is_none() {
                        img["name"] = json!(format!("{name}{suffix}"));
                    }
                }
            }
        }
    }

    /// The JSON chunk (padded) and the GLB's total length; the BIN chunk padded to 4 bytes.
    ///
    /// Errors: a JSON that `gltf-json` refuses, and a GLB above 4 GiB.
    fn finish_json(&mut self, scene: Value) -> Result<(Vec<u8>, usize)> {
        self.name_images();
        while self.bin_len() % 4 != 0 {
            self.bin.push(0);
        }
        let samplers = json!([
            {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE},
            {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT, "wrapT": REPEAT},
        ]);
        let mut root = json!({
            "asset": {"version": "2.0", "generator": format!("sylva {}", env!("CARGO_PKG_VERSION"))},
            "scene": 0,
            "scenes": [scene],
            "nodes": std::mem::take(&mut self.nodes),
            "meshes": std::mem::take(&mut self.meshes),
            "materials": std::mem::take(&mut self.materials),
            "accessors": std::mem::take(&mut self.accessors),
            "bufferViews": std::mem::take(&mut self.views),
            "buffers": [{"byteLength": self.bin_len()}],
        });
        // sorted: the same file whatever order the parts were written in (a stand written tree
        // by tree names the materials' extensions last, one held in memory first)
        self.extensions_used.sort_unstable();
        self.extensions_required.sort_unstable();
        if !self.extensions_used.is_empty() {
            root["extensionsUsed"] = json!(self.extensions_used);
        }
        if !self.extensions_required.is_empty() {
            root["extensionsRequired"] = json!(self.extensions_required);
        }
        if !self.textures.is_empty() {
            root["images"] = json!(std::mem::take(&mut self.images));
            root["textures"] = json!(std::mem::take(&mut self.textures));
            root["samplers"] = samplers;
        }
        let mut js = serde_json::to_vec(&root).map_err(|e| OutputError::Serialize { what: "glb".into(), format: "JSON", message: e.to_string() })?;
        json_check(&js)?;
        while js.len() % 4 != 0 {
            js.push(b' ');
        }
        let total = 12 + 8 + js.len() + 8 + self.bin_len();
        if total > u32::MAX as usize {
            return Err(Error::Invalid { context: "glb".into(), field: "size".into(), value: format!("{total} bytes"), expected: "at most 4 GiB (the GLB length field is 32 bits): export a smaller area".into() }.into());
        }
        Ok((js, total))
    }
}

/// The GLB header, the JSON chunk (`js`, padded) and the BIN chunk's header (`bin_len` bytes
/// follow), for a file of `total` bytes (glTF 2.0 specification, section 4.4).
fn glb_header(total: usize, js: &[u8], bin_len: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(28 + js.len());
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(js);
    out.extend_from_slice(&(bin_len as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out
}

/// Encodes a LOD chain as GLB bytes (see the module docs for the layout).
///
/// Errors: [`Error::Invalid`] (in [`OutputError::Input`]) when the chain has no triangles;
/// [`OutputError::Serialize`] when a texture cannot be encoded or the JSON cannot be written or
/// does not parse back as valid glTF.
pub fn glb_bytes(chain: &LodChain, o: &GlbOptions) -> Result<Vec<u8>> {
    if chain.levels.iter().all(|l| l.triangle_count() == 0) {
        return Err(Error::Invalid { context: "glb".into(), field: "LOD chain".into(), value: "0 triangles".into(), expected: "at least one level with triangles".into() }.into());
    }
    let mut d = Doc::new();
    let all: Vec<usize> = (0..chain.levels.len()).filter(|&i| chain.levels[i].triangle_count() > 0).collect();
    // the cluster material also where the full level alone carries leaf-cluster cards (`sylva
    // tree grow --lod 0`), as the stand export does
    let mut mat_levels = all.clone();
    if all.contains(&0) && !all.contains(&1) && chain.levels[0].leaves.has_cluster_cards() {
        mat_levels.push(1);
    }
    let mats = d.look(&o.look, &mat_levels)?;
    let meshes = d.chain(&o.name, chain, mats, &all);
    let mut children = Vec::new();
    for (i, m) in meshes.iter().enumerate() {
        let Some(m) = *m else { continue };
        let mut node = json!({"name": format!("{}_LOD{i}", o.name), "mesh": m});
        if o.spacing_m != 0.0 {
            node["translation"] = json!([o.spacing_m * i as f32, 0.0, 0.0]);
        }
        children.push(d.node(node));
    }
    let root = d.node(json!({"name": o.name, "children": children}));
    d.finish(json!({"name": o.name, "nodes": [root]}))
}

/// Parses the JSON chunk back with `gltf-json` and runs its validation. `gltf-json` reports
/// every required extension it does not implement itself as an error; the extensions Sylva
/// requires on purpose (`EXT_mesh_gpu_instancing` of [`instanced_glb_bytes`]) are let through
/// (the Khronos validator, run by the export tests, checks them).
fn json_check(js: &[u8]) -> Result<()> {
    use gltf_json::validation::Validate;
    let root = gltf_json::Root::from_slice(js).map_err(|e| OutputError::Serialize { what: "glb".into(), format: "glTF", message: format!("produced JSON is not glTF: {e}") })?;
    let mut errs = Vec::new();
    root.validate(&root, gltf_json::Path::new, &mut |path, err| {
        // gltf-json names such an entry `extensionsRequired[i] = "NAME"`
        let p = path().to_string();
        if !(p.starts_with("extensionsRequired[") && (p.ends_with("= \"EXT_mesh_gpu_instancing\"") || p.ends_with(&format!("= \"{MESH_QUANTIZATION}\"")) || p.ends_with(&format!("= \"{TEXTURE_TRANSFORM}\"")))) {
            errs.push(format!("{p}: {err}"));
        }
    });
    if errs.is_empty() {
        Ok(())
    } else {
        Err(OutputError::Serialize { what: "glb".into(), format: "glTF", message: format!("validation failed: {}", errs.join("; ")) })
    }
}

/// Writes a LOD chain to `path` as `.glb` (atomically).
///
/// Errors: as [`glb_bytes`]; [`OutputError::Io`] naming `path`.
pub fn write_glb(path: &Path, chain: &LodChain, o: &GlbOptions) -> Result<()> {
    let bytes = glb_bytes(chain, o)?;
    super::write_atomic(path, &bytes)
}

/// One kind of tree mesh of a stand: a LOD chain in the tree's own frame (stem base at the
/// origin, z up, m) and the [`Look`] it wears.
#[derive(Debug, Clone, PartialEq)]
pub struct StandModel {
    /// Name of its meshes (`<name>_LOD<i>`).
    pub name: String,
    /// The levels of detail.
    pub chain: LodChain,
    /// Index into [`StandScene::looks`].
    pub look: usize,
    /// Leaf-cluster cards drawn with the full level (LOD0) in the look's cluster material (a
    /// sprig of leaves each, UV 0–1 over the card): the leaf area of a full-detail export's
    /// crown beyond its leaf cards (`job::export::sprig_cards`); empty for none.
    pub sprigs: TriMesh,
}

/// One tree of a stand: a node drawing a [`StandModel`].
#[derive(Debug, Clone, PartialEq)]
pub struct StandNode {
    /// Node name (`<name>`, levels `<name>_LOD<i>`).
    pub name: String,
    /// Index into [`StandScene::models`].
    pub model: usize,
    /// Stem base in the scene (m, Sylva's z up; converted to y up).
    pub translation: [f32; 3],
    /// Scale of the model along Sylva's x, y, z (> 0; 1 for a model made for this tree).
    pub scale: [f32; 3],
}

/// A plain mesh of a stand (terrain, obstacles): one colour, or a tiling texture.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticMesh {
    /// Node, mesh and material name.
    pub name: String,
    /// Triangles in scene coordinates (m, z up).
    pub mesh: TriMesh,
    /// sRGB colour (0–255) of an untextured material (a textured one is white: its colours are
    /// baked into the texture).
    pub rgb: [u8; 3],
    /// Roughness (0–1).
    pub roughness: f32,
    /// A texture that tiles (repeating sampler) on the mesh's texture coordinates
    /// ([`TriMesh::uvs`], one per vertex; the terrain's are metres east and north: one picture a
    /// metre), colours baked in; `None`: the plain colour `rgb`, no texture coordinates.
    pub texture: Option<RgbaImage>,
}

/// What [`stand_glb_bytes`] writes.
#[derive(Debug, Clone, PartialEq)]
pub struct StandScene {
    /// Scene name.
    pub name: String,
    /// Materials per kind of tree.
    pub looks: Vec<Look>,
    /// Tree meshes.
    pub models: Vec<StandModel>,
    /// Tree nodes.
    pub trees: Vec<StandNode>,
    /// Saplings of the regeneration layer, drawn under node `saplings` (their models among
    /// [`StandScene::models`]); empty for none.
    pub saplings: Vec<StandNode>,
    /// Terrain and obstacles.
    pub statics: Vec<StaticMesh>,
    /// Levels of detail written (indices into the chains, e.g. `[0, 1, 2, 3]` or `[0]`).
    pub levels: Vec<usize>,
    /// JSON stored as the scene's `extras` (provenance: run, year, area, origin).
    pub extras: Value,
}

/// Counts of a written stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StandCounts {
    /// glTF meshes written.
    pub meshes: usize,
    /// Nodes drawing a mesh.
    pub mesh_nodes: usize,
    /// Images embedded.
    pub images: usize,
}

/// Encodes a stand as GLB bytes (module documentation): node `trees` holds one node per tree,
/// node `saplings` one per sapling ([`StandScene::saplings`], when there are any), node
/// `ground` the static meshes. Every [`StandModel`]'s meshes are written once however many
/// trees use it, the LOD3 billboard included: the model's own impostor
/// ([`crate::structure::mesh::impostor_mesh`]: crown quads over its foliage from the crown base
/// to the top, where a leaning crown is, and a trunk quad slanting from the root to under the
/// crown), the same mesh `sylva tree grow` writes (round 34; until then one pair of unit cards
/// per look stretched over the model's bounds, root to top, drew the crown down to the ground).
///
/// Errors: [`Error::Invalid`] for a node naming a missing model or look, a non-positive or
/// non-finite scale, or nothing to draw; otherwise as [`glb_bytes`].
pub fn stand_glb_bytes(s: &StandScene) -> Result<(Vec<u8>, StandCounts)> {
    let (d, scene, counts) = stand_doc(s, Doc { quantize: true, ..Doc::new() })?;
    Ok((d.finish(scene)?, counts))
}

/// The document of [`stand_glb_bytes`] built in `d`: the document, its scene and the counts.
fn stand_doc(s: &StandScene, mut d: Doc) -> Result<(Doc, Value, StandCounts)> {
    let bad = |field: &str, value: String, expected: String| OutputError::from(Error::Invalid { context: format!("stand glb {}", s.name), field: field.into(), value, expected });
    for m in &s.models {
        if m.look >= s.looks.len() {
            return Err(bad("model look", format!("{} of {}", m.look, m.name), format!("a look index below {}", s.looks.len())));
        }
    }
    for t in s.trees.iter().chain(&s.saplings) {
        if t.model >= s.models.len() {
            return Err(bad("tree model", format!("{} of {}", t.model, t.name), format!("a model index below {}", s.models.len())));
        }
        if !t.scale.iter().all(|c| c.is_finite() && *c > 0.0) || !t.translation.iter().all(|c| c.is_finite()) {
            return Err(bad("tree transform", format!("{:?} {:?} of {}", t.translation, t.scale, t.name), "finite numbers, scales > 0".into()));
        }
    }
    if s.trees.is_empty() && s.statics.iter().all(|m| m.mesh.indices.is_empty()) {
        return Err(bad("scene", "no trees and no ground".into(), "at least one tree or mesh".into()));
    }
    let used_looks: std::collections::BTreeSet<usize> = s.trees.iter().chain(&s.saplings).map(|t| s.models[t.model].look).collect();
    let mut mats: Vec<Option<LookMaterials>> = vec![None; s.looks.len()];
    for &l in &used_looks {
        // a look whose models carry sprigs at the full level needs its cluster material
        let sprigs = s.levels.contains(&0) && s.models.iter().any(|m| m.look == l && !m.sprigs.indices.is_empty());
        let mut levels = s.levels.clone();
        if sprigs && !levels.contains(&1) {
            levels.push(1);
        }
        // no leaf material where no full level of the look has leaf cards (a conifer's full
        // level draws shoot cards in the cluster material, `job::leaf_area::shoot_cards`)
        if levels.iter().any(|&k| k != 0) && !s.models.iter().any(|m| m.look == l && m.chain.levels.first().is_some_and(|c| !c.leaves.indices.is_empty())) {
            levels.retain(|&k| k != 0);
        }
        mats[l] = Some(d.look(&s.looks[l], &levels)?);
    }
    // the models used, their meshes once (every level written, the billboard included: the
    // chain's own impostor, `structure::mesh::impostor_mesh`, drawn over the model's crown)
    let used_models: std::collections::BTreeSet<usize> = s.trees.iter().chain(&s.saplings).map(|t| t.model).collect();
    let mut model_meshes: Vec<Vec<Option<usize>>> = vec![Vec::new(); s.models.len()];
    for &mi in &used_models {
        let m = &s.models[mi];
        let Some(lm) = mats[m.look] else { continue };
        model_meshes[mi] = d.chain_with_sprigs(&m.name, &m.chain, &m.sprigs, lm, &s.levels);
    }
    let mut mesh_nodes = 0;
    let mut tree_nodes = Vec::new();
    for t in &s.trees {
        tree_nodes.push(tree_node(&mut d, t, &model_meshes[t.model], &mut mesh_nodes));
    }
    let mut sapling_nodes = Vec::new();
    for t in &s.saplings {
        sapling_nodes.push(tree_node(&mut d, t, &model_meshes[t.model], &mut mesh_nodes));
    }
    forest_doc(d, tree_nodes, sapling_nodes, mesh_nodes, &s.statics, &s.name, &s.extras)
}

/// The node of tree `t` in `d` drawing `meshes` (its model's, per level), its children one
/// node per level drawn (counted in `mesh_nodes`); returns its index.
fn tree_node(d: &mut Doc, t: &StandNode, meshes: &[Option<usize>], mesh_nodes: &mut usize) -> usize {
    let mut children = Vec::new();
    for (i, mesh) in meshes.iter().enumerate() {
        if let Some(mesh) = *mesh {
            let mut node = json!({"name": format!("{}_LOD{i}", t.name), "mesh": mesh});
            // a quantised mesh's dequantisation (Quant)
            if let Some(q) = d.mesh_quant.get(&mesh) {
                node["translation"] = json!(q.offset);
                node["scale"] = json!([q.scale, q.scale, q.scale]);
            }
            children.push(d.node(node));
            *mesh_nodes += 1;
        }
    }
    let [sx, sy, sz] = t.scale;
    let mut node = json!({"name": t.name, "children": children, "translation": y_up(t.translation)});
    if t.scale != [1.0; 3] {
        node["scale"] = json!([sx, sz, sy]);
    }
    if let (true, Some(o)) = (children.is_empty(), node.as_object_mut()) {
        o.remove("children");
    }
    d.node(node)
}

/// The trees of one model drawn by `EXT_mesh_gpu_instancing` ([`InstancedScene`]): one entry
/// per tree in every list.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InstanceGroup {
    /// Index into [`InstancedScene::models`].
    pub model: usize,
    /// Stem bases relative to the scene's origin (m, Sylva's frame: x east, y north, z up;
    /// converted to y up).
    pub translations: Vec<[f32; 3]>,
    /// Turn of each tree about the vertical (rad, counter-clockwise seen from above).
    pub yaw: Vec<f32>,
    /// Scale of the model along Sylva's x, y, z (> 0).
    pub scales: Vec<[f32; 3]>,
    /// Tree ids (the inventory's `id`), written as the custom instance attribute `_ID`
    /// (unsigned 32-bit) when every id of the group fits, otherwise as `_ID_LO` and `_ID_HI`
    /// (its low and high 32 bits: id = `_ID_HI` · 2³² + `_ID_LO`; a run's ids use the high
    /// bits, and the 64-bit ids were left out without a word, found by a trial); empty to
    /// leave them out.
    pub ids: Vec<u64>,
    /// Saplings of the regeneration layer: the group's nodes go under node `saplings` (as a
    /// stand export's saplings do), not under `trees`.
    pub sapling: bool,
}

/// What [`instanced_glb_bytes`] writes: tree models drawn many times through the
/// `EXT_mesh_gpu_instancing` extension (glTF 2.0 extension registry; read by three.js,
/// Babylon.js, Unity's glTFast and Blender 4.1+, not by released Godot 4 or Unreal's glTF
/// importer: docs/guide.md), and static meshes.
#[derive(Debug, Clone, PartialEq)]
pub struct InstancedScene {
    /// Scene name.
    pub name: String,
    /// Materials per kind of tree.
    pub looks: Vec<Look>,
    /// Tree models (each in its own frame: stem base at the origin, z up).
    pub models: Vec<StandModel>,
    /// The trees of each model.
    pub groups: Vec<InstanceGroup>,
    /// Terrain and obstacles.
    pub statics: Vec<StaticMesh>,
    /// Levels of detail written (indices into the chains): one instanced node per model and
    /// level, `<model>_LOD<i>`.
    pub levels: Vec<usize>,
    /// JSON stored as the scene's `extras`.
    pub extras: Value,
}

/// Encodes an [`InstancedScene`] as GLB bytes: node `trees` holds, per model and level, one node
/// `<model>_LOD<i>` (with several levels, the children of a node `<model>`) drawing the level's mesh (the full level with its leaf-cluster cards, the
/// model's [`StandModel::sprigs`] and those marked among its leaves by
/// [`crate::mesh::CLUSTER_CARD_U`], as a third primitive in the look's `_cluster` material) with the extension's `TRANSLATION`, `ROTATION`
/// (about the vertical) and `SCALE` attributes (and `_ID`, or `_ID_LO` and `_ID_HI`:
/// [`InstanceGroup::ids`]), one entry per tree; node `ground` the
/// static meshes. The extension is used, not required: a viewer without it shows each model
/// once at the origin.
///
/// Errors: [`Error::Invalid`] for a group naming a missing model or look, lists of different
/// lengths, a non-finite translation or a non-positive scale, or nothing to draw; otherwise as
/// [`glb_bytes`].
pub fn instanced_glb_bytes(s: &InstancedScene) -> Result<(Vec<u8>, StandCounts)> {
    let bad = |field: &str, value: String, expected: String| OutputError::from(Error::Invalid { context: format!("instanced glb {}", s.name), field: field.into(), value, expected });
    for m in &s.models {
        if m.look >= s.looks.len() {
            return Err(bad("model look", format!("{} of {}", m.look, m.name), format!("a look index below {}", s.looks.len())));
        }
    }
    for g in &s.groups {
        let n = g.translations.len();
        if g.model >= s.models.len() {
            return Err(bad("group model", g.model.to_string(), format!("a model index below {}", s.models.len())));
        }
        if g.yaw.len() != n || g.scales.len() != n || !(g.ids.is_empty() || g.ids.len() == n) {
            return Err(bad("group lengths", format!("{n} translations, {} turns, {} scales, {} ids", g.yaw.len(), g.scales.len(), g.ids.len()), "one entry per tree in every list".into()));
        }
        if !g.translations.iter().flatten().chain(&g.yaw).all(|c| c.is_finite()) || !g.scales.iter().flatten().all(|c| c.is_finite() && *c > 0.0) {
            return Err(bad("group transforms", format!("model {}", s.models[g.model].name), "finite numbers, scales > 0".into()));
        }
    }
    if s.groups.iter().all(|g| g.translations.is_empty()) && s.statics.iter().all(|m| m.mesh.indices.is_empty()) {
        return Err(bad("scene", "no trees and no ground".into(), "at least one tree or mesh".into()));
    }
    let mut d = Doc::new();
    d.extensions_used.push("EXT_mesh_gpu_instancing");
    // Required: without instancing the file shows each model once at the origin (round 33's
    // trial: Debian's Blender 3.4 imported a million-tree forest as 40 trees, without a word);
    // an importer that lacks the extension now refuses the file and names it.
    d.extensions_required.push("EXT_mesh_gpu_instancing");
    let used_models: std::collections::BTreeSet<usize> = s.groups.iter().filter(|g| !g.translations.is_empty()).map(|g| g.model).collect();
    let used_looks: std::collections::BTreeSet<usize> = used_models.iter().map(|&mi| s.models[mi].look).collect();
    let mut mats: Vec<Option<LookMaterials>> = vec![None; s.looks.len()];
    for &l in &used_looks {
        // a look whose models' full level carries leaf-cluster cards (the crown's leaf area,
        // `job::leaf_area::lone_chain`; trial 35: without them the crowns were sparse) needs
        // its cluster material
        let clusters = s.levels.contains(&0)
            && used_models.iter().map(|&mi| &s.models[mi]).any(|m| m.look == l && (!m.sprigs.indices.is_empty() || m.chain.levels.first().is_some_and(|c| c.leaves.has_cluster_cards())));
        let mut levels = s.levels.clone();
        if clusters && !levels.contains(&1) {
            levels.push(1);
        }
        mats[l] = Some(d.look(&s.looks[l], &levels)?);
    }
    let (mut tree_nodes, mut sapling_nodes) = (Vec::new(), Vec::new());
    let mut mesh_nodes = 0;
    let mut meshes_of: HashMap<usize, Vec<Option<usize>>> = HashMap::new();
    for g in s.groups.iter().filter(|g| !g.translations.is_empty()) {
        let m = &s.models[g.model];
        let Some(lm) = mats[m.look] else { continue };
        let meshes = match meshes_of.get(&g.model) {
            Some(v) => v.clone(),
            None => {
                let v = d.chain_with_sprigs(&m.name, &m.chain, &m.sprigs, lm, &s.levels);
                meshes_of.insert(g.model, v.clone());
                v
            }
        };
        let n = g.translations.len();
        // the instance attributes, shared by the group's levels
        let t: Vec<[f32; 3]> = g.translations.iter().map(|&p| y_up(p)).collect();
        let r: Vec<[f32; 4]> = g.yaw.iter().map(|&a| [0.0, (0.5 * a).sin(), 0.0, (0.5 * a).cos()]).collect();
        let sc: Vec<[f32; 3]> = g.scales.iter().map(|&[x, y, z]| [x, z, y]).collect();
        let tv = d.view(bytemuck::cast_slice(&t), None, None);
        let ta = d.accessor(tv, n, F32, "VEC3", None);
        let rv = d.view(bytemuck::cast_slice(&r), None, None);
        let ra = d.accessor(rv, n, F32, "VEC4", None);
        let sv = d.view(bytemuck::cast_slice(&sc), None, None);
        let sa = d.accessor(sv, n, F32, "VEC3", None);
        let mut attributes = json!({"TRANSLATION": ta, "ROTATION": ra, "SCALE": sa});
        if !g.ids.is_empty() {
            let mut id_attribute = |name: &str, ids: Vec<u32>| {
                let iv = d.view(bytemuck::cast_slice(&ids), None, None);
                attributes[name] = json!(d.accessor(iv, n, U32, "SCALAR", None));
            };
            if g.ids.iter().all(|&i| i <= u32::MAX as u64) {
                id_attribute("_ID", g.ids.iter().map(|&i| i as u32).collect());
            } else {
                id_attribute("_ID_LO", g.ids.iter().map(|&i| i as u32).collect());
                id_attribute("_ID_HI", g.ids.iter().map(|&i| (i >> 32) as u32).collect());
            }
        }
        let mut level_nodes = Vec::new();
        for (i, mesh) in meshes.iter().enumerate() {
            if let Some(mesh) = *mesh {
                level_nodes.push(d.node(json!({"name": format!("{}_LOD{i}", m.name), "mesh": mesh, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": attributes}}})));
                mesh_nodes += 1;
            }
        }
        // several levels: under one node `<model>`, as a stand export's trees and a tree's
        // levels are (the grouping by which Unity's and Unreal's importers make a LOD group;
        // trial 37: flat siblings were all drawn at once)
        let under = if g.sapling { &mut sapling_nodes } else { &mut tree_nodes };
        if level_nodes.len() > 1 {
            under.push(d.node(json!({"name": m.name, "children": level_nodes})));
        } else {
            under.extend(level_nodes);
        }
    }
    let (d, scene, counts) = forest_doc(d, tree_nodes, sapling_nodes, mesh_nodes, &s.statics, &s.name, &s.extras)?;
    Ok((d.finish(scene)?, counts))
}

/// Writes an [`InstancedScene`] to `path` as `.glb` (atomically); returns what was written.
///
/// Errors: as [`instanced_glb_bytes`]; [`OutputError::Io`] naming `path`.
pub fn write_instanced_glb(path: &Path, s: &InstancedScene) -> Result<StandCounts> {
    let (bytes, counts) = instanced_glb_bytes(s)?;
    super::write_atomic(path, &bytes)?;
    Ok(counts)
}

/// The end of a stand or forest document: the static meshes under node `ground` (a textured
/// one in a material of its own name with its texture, repeating, on `TEXCOORD_0`), the tree
/// nodes under node `trees`, the sapling nodes under node `saplings` (when there are any), the
/// scene named `name` with `extras`; `mesh_nodes` counts the tree and sapling nodes drawing a
/// mesh so far. Returns the document, its scene and the counts.
///
/// Errors: [`OutputError::Serialize`] when a static mesh's texture cannot be encoded.
fn forest_doc(mut d: Doc, tree_nodes: Vec<usize>, sapling_nodes: Vec<usize>, mut mesh_nodes: usize, statics: &[StaticMesh], name: &str, extras: &Value) -> Result<(Doc, Value, StandCounts)> {
    let mut ground_nodes = Vec::new();
    for g in statics {
        let textured = g.texture.is_some() && g.mesh.uvs.len() == g.mesh.positions.len();
        let mat = match g.texture.as_ref().filter(|_| textured) {
            Some(img) => {
                let t = d.texture(img, SAMPLER_REPEAT)?;
                d.material(json!({"name": g.name, "pbrMetallicRoughness": {"baseColorTexture": {"index": t, "texCoord": 0}, "metallicFactor": 0.0, "roughnessFactor": g.roughness}}))
            }
            None => d.plain(&g.name, g.rgb, g.roughness),
        };
        let p = d.primitive(&g.mesh, mat, textured);
        if let Some(mesh) = d.mesh(&g.name, vec![p]) {
            ground_nodes.push(d.node(json!({"name": g.name, "mesh": mesh})));
            mesh_nodes += 1;
        }
    }
    let mut roots = Vec::new();
    if !tree_nodes.is_empty() {
        roots.push(d.node(json!({"name": "trees", "children": tree_nodes})));
    }
    if !sapling_nodes.is_empty() {
        roots.push(d.node(json!({"name": "saplings", "children": sapling_nodes})));
    }
    if !ground_nodes.is_empty() {
        roots.push(d.node(json!({"name": "ground", "children": ground_nodes})));
    }
    let counts = StandCounts { meshes: d.meshes.len(), mesh_nodes, images: d.images.len() };
    let mut scene = json!({"name": name, "nodes": roots});
    if !extras.is_null() {
        scene["extras"] = extras.clone();
    }
    Ok((d, scene, counts))
}

/// Material slots of one look in a [`StandGlbWriter`]'s pending material numbers: bark, then
/// the foliage of levels 0–3, then a white bark's dark base ([`LookMaterials`]).
const LOOK_SLOTS: usize = 6;
/// Pending material numbers of a [`StandGlbWriter`]'s tree primitives start here (look ×
/// [`LOOK_SLOTS`] + slot above it); [`StandGlbWriter::finish`] replaces them by the materials'
/// indices, which are known only once every tree is written.
const PENDING_MATERIAL: usize = 1 << 40;

/// A stand written to a `.glb` tree by tree: each model's meshes go into the BIN chunk's
/// scratch file beside the output (`.<name>.glb.bin.<pid>.tmp`, 8 MiB written at a time, removed
/// when done or refused; trial 37: a 2.2 GB export held its buffer twice in memory, 9.5 GB in
/// all) as soon as the model is given,
/// so that a caller holds one tree's meshes at a time, not the stand's (round 38: a 0.25 ha
/// export held all its trees' meshes until written, about twice the file). What is held to the
/// end is the JSON (views, accessors, meshes, nodes) and at most [`SPILL_BYTES`] of the buffer.
///
/// The file is byte for byte the one [`stand_glb_bytes`] makes of a [`StandScene`] holding the
/// same looks, models (each given before the first tree that draws it, every model drawn by
/// some tree or sapling) and trees and saplings in the same order (the saplings given after
/// the last tree): the textures, which the held writer puts first in
/// the buffer, are made at [`StandGlbWriter::finish`] (which materials a look needs depends on
/// all its models: sprigs, leaf cards) and written before the scratch file's bytes, the tree
/// meshes' buffer views moved past them.
pub struct StandGlbWriter {
    path: std::path::PathBuf,
    doc: Doc,
    levels: Vec<usize>,
    looks: Vec<Look>,
    /// Per look: whether a model given has full-level leaf cards, leaf-cluster cards at the
    /// full level (sprigs), and a tree drawn.
    uses: Vec<[bool; 3]>,
    /// Per model: its look and its meshes per level.
    models: Vec<(usize, Vec<Option<usize>>)>,
    tree_nodes: Vec<usize>,
    sapling_nodes: Vec<usize>,
    mesh_nodes: usize,
}

impl StandGlbWriter {
    /// A writer of a stand to `path` with levels of detail `levels` (indices into the models'
    /// chains, e.g. `[0]` or `[0, 1, 2, 3]`); nothing is at `path` until
    /// [`StandGlbWriter::finish`] (a scratch file `.<name>.glb.bin.<pid>.tmp` beside it holds
    /// the buffer meanwhile, removed when the writer is finished or dropped).
    ///
    /// Errors: [`OutputError::Io`] naming the scratch file when it cannot be made.
    pub fn create(path: &Path, levels: &[usize]) -> Result<StandGlbWriter> {
        Self::spilling_at(path, levels, SPILL_BYTES)
    }

    /// [`StandGlbWriter::create`] writing the held buffer to the scratch file whenever `at`
    /// bytes (≥ 1) are held (tests take a few bytes).
    ///
    /// Errors: as [`StandGlbWriter::create`].
    pub fn spilling_at(path: &Path, levels: &[usize], at: usize) -> Result<StandGlbWriter> {
        Ok(StandGlbWriter { path: path.to_path_buf(), doc: Doc { quantize: true, ..Doc::spilling(path, at.max(1))? }, levels: levels.to_vec(), looks: Vec::new(), uses: Vec::new(), models: Vec::new(), tree_nodes: Vec::new(), sapling_nodes: Vec::new(), mesh_nodes: 0 })
    }

    /// Whether the tree meshes written after this call are quantised ([`Quant`],
    /// `KHR_mesh_quantization`; on by default): off for an importer without the extension
    /// (`sylva export --no-quantize`).
    pub fn set_quantized(&mut self, on: bool) {
        self.doc.quantize = on;
    }

    /// Adds a look; returns its index (as [`StandScene::looks`]).
    pub fn look(&mut self, look: Look) -> usize {
        self.looks.push(look);
        self.uses.push([false; 3]);
        self.looks.len() - 1
    }

    /// Writes the meshes of `m` (its look given before; `m.look` is that look's index) into
    /// the buffer now; returns the model's index (as [`StandScene::models`]) for
    /// [`StandGlbWriter::tree`]. `m` can be dropped once this returns.
    ///
    /// Errors: [`Error::Invalid`] for a look index not given.
    pub fn model(&mut self, m: &StandModel) -> Result<usize> {
        let l = m.look;
        if l >= self.looks.len() {
            return Err(Error::Invalid { context: format!("stand glb {}", self.path.display()), field: "model look".into(), value: format!("{l} of {}", m.name), expected: format!("a look index below {}", self.looks.len()) }.into());
        }
        let full = m.chain.levels.first();
        self.uses[l][0] |= full.is_some_and(|c| !c.leaves.indices.is_empty());
        self.uses[l][1] |= !m.sprigs.indices.is_empty() || full.is_some_and(|c| c.leaves.has_cluster_cards());
        // every material a primitive of this model can need (the look's final ones are a
        // superset of these: a leaf or sprig primitive exists only where this model has them,
        // which makes its look keep that material), numbered until finish
        let pending = |slot: usize| Some(PENDING_MATERIAL + l * LOOK_SLOTS + slot);
        let has = |k: usize| self.levels.iter().any(|&x| x.min(3) == k);
        let barked = self.levels.iter().any(|&x| x < 3);
        let mats = LookMaterials { bark: if barked { pending(0) } else { None }, foliage: [0, 1, 2, 3].map(|k| if has(k) || (k == 1 && has(0)) { pending(1 + k) } else { None }), bark_base: if barked && self.looks[l].textures.bark_base.is_some() { pending(5) } else { None } };
        let meshes = self.doc.chain_with_sprigs(&m.name, &m.chain, &m.sprigs, mats, &self.levels);
        self.models.push((l, meshes));
        Ok(self.models.len() - 1)
    }

    /// Adds a tree drawing model `t.model` (given before).
    ///
    /// Errors: [`Error::Invalid`] for a model not given, a non-positive or non-finite scale or
    /// a non-finite translation.
    pub fn tree(&mut self, t: &StandNode) -> Result<()> {
        let node = self.node(t)?;
        self.tree_nodes.push(node);
        Ok(())
    }

    /// Adds a sapling of the regeneration layer drawing model `t.model` (given before), under
    /// node `saplings`; saplings are given after the last tree ([`StandScene::saplings`]).
    ///
    /// Errors: as [`StandGlbWriter::tree`].
    pub fn sapling(&mut self, t: &StandNode) -> Result<()> {
        let node = self.node(t)?;
        self.sapling_nodes.push(node);
        Ok(())
    }

    /// The node of a tree or sapling (checked), its look marked drawn.
    fn node(&mut self, t: &StandNode) -> Result<usize> {
        let bad = |field: &str, value: String, expected: String| OutputError::from(Error::Invalid { context: format!("stand glb {}", self.path.display()), field: field.into(), value, expected });
        if t.model >= self.models.len() {
            return Err(bad("tree model", format!("{} of {}", t.model, t.name), format!("a model index below {}", self.models.len())));
        }
        if !t.scale.iter().all(|c| c.is_finite() && *c > 0.0) || !t.translation.iter().all(|c| c.is_finite()) {
            return Err(bad("tree transform", format!("{:?} {:?} of {}", t.translation, t.scale, t.name), "finite numbers, scales > 0".into()));
        }
        let (look, meshes) = &self.models[t.model];
        self.uses[*look][2] = true;
        let meshes = meshes.clone();
        Ok(tree_node(&mut self.doc, t, &meshes, &mut self.mesh_nodes))
    }

    /// Makes the looks' materials and textures, adds `statics` under node `ground`, names the
    /// scene `name` with `extras`, and writes the file (atomically); the scratch file is removed.
    ///
    /// Errors: [`Error::Invalid`] for nothing to draw; otherwise as [`stand_glb_bytes`];
    /// [`OutputError::Io`] naming the output or the scratch file.
    pub fn finish(mut self, statics: &[StaticMesh], name: &str, extras: &Value) -> Result<StandCounts> {
        if self.tree_nodes.is_empty() && statics.iter().all(|m| m.mesh.indices.is_empty()) {
            return Err(Error::Invalid { context: format!("stand glb {name}"), field: "scene".into(), value: "no trees and no ground".into(), expected: "at least one tree or mesh".into() }.into());
        }
        // the looks' materials as the held writer makes them (stand_doc), in a document of
        // their own whose buffer (the textures) goes first
        let mut head = Doc { quantize: self.doc.quantize, ..Doc::new() };
        let mut mats: Vec<Option<LookMaterials>> = vec![None; self.looks.len()];
        for (l, look) in self.looks.iter().enumerate() {
            let [leaves, sprigs, drawn] = self.uses[l];
            if !drawn {
                continue;
            }
            let mut levels = self.levels.clone();
            if sprigs && levels.contains(&0) && !levels.contains(&1) {
                levels.push(1);
            }
            if levels.iter().any(|&k| k != 0) && !leaves {
                levels.retain(|&k| k != 0);
            }
            mats[l] = Some(head.look(look, &levels)?);
        }
        while head.bin.len() % 4 != 0 {
            head.bin.push(0);
        }
        let (base, n_views) = (head.bin.len(), head.views.len());
        let d = &mut self.doc;
        for v in &mut d.views {
            let o = v["byteOffset"].as_u64().unwrap_or(0) as usize;
            v["byteOffset"] = json!(o + base);
        }
        for a in &mut d.accessors {
            let v = a["bufferView"].as_u64().unwrap_or(0) as usize;
            a["bufferView"] = json!(v + n_views);
        }
        for mesh in &mut d.meshes {
            for p in mesh["primitives"].as_array_mut().into_iter().flatten() {
                let k = p["material"].as_u64().unwrap_or(0) as usize;
                let Some(k) = k.checked_sub(PENDING_MATERIAL) else { continue };
                let lm = mats.get(k / LOOK_SLOTS).copied().flatten();
                let m = lm.and_then(|lm| match k % LOOK_SLOTS {
                    0 => lm.bark,
                    5 => lm.bark_base,
                    j => lm.foliage[j - 1],
                });
                let Some(m) = m else {
                    return Err(Error::Invalid { context: format!("stand glb {name}"), field: "material".into(), value: format!("slot {} of look {}", k % LOOK_SLOTS, k / LOOK_SLOTS), expected: "a material its look has".into() }.into());
                };
                p["material"] = json!(m);
            }
        }
        d.views.splice(0..0, std::mem::take(&mut head.views));
        d.head = std::mem::take(&mut head.bin);
        d.images = std::mem::take(&mut head.images);
        d.textures = std::mem::take(&mut head.textures);
        d.texture_of = std::mem::take(&mut head.texture_of);
        d.materials = std::mem::take(&mut head.materials);
        for (&e, required) in head.extensions_used.iter().map(|e| (e, head.extensions_required.contains(e))) {
            d.uses(e, required);
        }
        let doc = std::mem::replace(&mut self.doc, Doc::new());
        let (doc, scene, counts) = forest_doc(doc, std::mem::take(&mut self.tree_nodes), std::mem::take(&mut self.sapling_nodes), self.mesh_nodes, statics, name, extras)?;
        doc.finish_to(scene, &self.path)?;
        Ok(counts)
    }
}

/// Path of the skeleton sidecar of a `.glb`: `tree.glb` → `tree.skeleton.json`.
pub fn skeleton_sidecar_path(glb: &Path) -> std::path::PathBuf {
    glb.with_extension("skeleton.json")
}

/// Format tag of the skeleton sidecar.
const SKELETON_FORMAT: &str = "sylva-skeleton";

/// Writes the skeleton of the tree in `glb` to its sidecar ([`skeleton_sidecar_path`]) as JSON:
/// `{"format": "sylva-skeleton", "version": 1, "species": "beech", "nodes": [[x, y, z, parent,
/// radius, age, gravelius, weibull, strands], …]}` with Sylva's z-up metres, parent −1 for the
/// root, radius in m, age in years; `species` (the species id the tree was grown as) is written
/// when given. Written to a temporary file then renamed. `sylva tree adapt` reads it back with
/// [`read_skeleton_sidecar`] and [`read_skeleton_sidecar_species`].
///
/// Errors: [`OutputError::Io`] when the file cannot be written.
pub fn write_skeleton_sidecar(glb: &Path, sk: &crate::structure::Skeleton, species: Option<&str>) -> Result<()> {
    let nodes: Vec<Value> = sk
        .nodes
        .iter()
        .map(|n| json!([n.pos.x, n.pos.y, n.pos.z, n.parent.map(|p| p as i64).unwrap_or(-1), n.radius, n.age, n.gravelius, n.weibull, n.strands]))
        .collect();
    let mut doc = json!({ "format": SKELETON_FORMAT, "version": 1, "nodes": nodes });
    if let Some(id) = species {
        doc["species"] = json!(id);
    }
    crate::output::write_atomic(&skeleton_sidecar_path(glb), doc.to_string().as_bytes())
}

/// Largest distance (m) of a skeleton sidecar's node from the tree's base along any axis.
pub const SKELETON_MAX_M: f64 = 1000.0;

/// Reads the skeleton sidecar of `glb` written by [`write_skeleton_sidecar`]; roles are
/// rebuilt (Gravelius 0 = trunk, childless = tip).
///
/// Errors: [`Error::Io`] when the sidecar is missing or unreadable; [`Error::Format`] naming the
/// sidecar and the node for a wrong format tag, a malformed node, a non-finite value or a parent
/// that does not precede its child.
pub fn read_skeleton_sidecar(glb: &Path) -> Result<crate::structure::Skeleton> {
    let path = skeleton_sidecar_path(glb);
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io { path: path.clone(), source })?;
    parse_skeleton_sidecar(&text, &path)
}

/// The species id recorded in the skeleton sidecar of `glb` (`"species"`, written by
/// [`write_skeleton_sidecar`] since round 24), or `None` for a sidecar without one.
///
/// Errors: [`Error::Io`] when the sidecar is missing or unreadable; [`Error::Format`] naming the
/// sidecar when it is not JSON or its `species` is not a string.
pub fn read_skeleton_sidecar_species(glb: &Path) -> Result<Option<String>> {
    let path = skeleton_sidecar_path(glb);
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Io { path: path.clone(), source })?;
    let fmt = |message: String| OutputError::from(Error::Format { path: path.clone(), message });
    let doc: Value = serde_json::from_str(&text).map_err(|e| fmt(format!("not JSON: {e}")))?;
    match doc.get("species") {
        None => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.clone())),
        Some(v) => Err(fmt(format!("field `species`: {v}: expected a species id as a string"))),
    }
}

/// Parses the text of a skeleton sidecar as [`read_skeleton_sidecar`] does; `path` (the
/// sidecar) is only used in messages.
///
/// Errors: as [`read_skeleton_sidecar`], less the I/O.
pub fn parse_skeleton_sidecar(text: &str, path: &Path) -> Result<crate::structure::Skeleton> {
    use crate::structure::{Node, Role, Skeleton};
    let path = path.to_path_buf();
    let fmt = |message: String| OutputError::from(Error::Format { path: path.clone(), message });
    let doc: Value = serde_json::from_str(text).map_err(|e| fmt(format!("not JSON: {e}")))?;
    if doc.get("format").and_then(Value::as_str) != Some(SKELETON_FORMAT) {
        return Err(fmt(format!("field `format`: expected \"{SKELETON_FORMAT}\"")));
    }
    let nodes = doc.get("nodes").and_then(Value::as_array).ok_or_else(|| fmt("field `nodes`: expected an array of nodes".into()))?;
    let mut sk = Skeleton::new();
    for (i, v) in nodes.iter().enumerate() {
        let a = v.as_array().filter(|a| a.len() == 9).ok_or_else(|| fmt(format!("node {i}: expected [x, y, z, parent, radius, age, gravelius, weibull, strands]")))?;
        let f: Vec<f64> = a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect();
        if f.iter().any(|x| !x.is_finite()) {
            return Err(fmt(format!("node {i}: expected finite numbers")));
        }
        // the values of a tree (a position of 1e30 m was taken: found by a trial)
        if let Some(c) = f[..3].iter().find(|c| c.abs() > SKELETON_MAX_M) {
            return Err(fmt(format!("node {i}: position coordinate {c:e}: expected within ±{SKELETON_MAX_M} m of the tree's base")));
        }
        if !(0.0..=20.0).contains(&f[4]) {
            return Err(fmt(format!("node {i}: radius {}: expected 0–20 m", f[4])));
        }
        if !(0.0..=10_000.0).contains(&f[5]) {
            return Err(fmt(format!("node {i}: age {}: expected 0–10,000 years", f[5])));
        }
        if !(0.0..=65_535.0).contains(&f[6]) || !(0.0..=65_535.0).contains(&f[7]) || !(0.0..=u32::MAX as f64).contains(&f[8]) {
            return Err(fmt(format!("node {i}: gravelius, weibull and strands: expected whole numbers ≥ 0 (got {}, {}, {})", f[6], f[7], f[8])));
        }
        let parent = if f[3] < 0.0 { None } else { Some(f[3] as u32) };
        match parent {
            None if i != 0 => return Err(fmt(format!("node {i}: parent -1 (only node 0 is the root)"))),
            Some(p) if p as usize >= i => return Err(fmt(format!("node {i}: parent {p} must precede the node"))),
            _ => {}
        }
        let gravelius = f[6] as u16;
        sk.nodes.push(Node {
            pos: glam::Vec3::new(f[0] as f32, f[1] as f32, f[2] as f32),
            parent,
            children: Vec::new(),
            radius: f[4] as f32,
            age: f[5] as f32,
            role: if gravelius == 0 { Role::Trunk } else { Role::Branch },
            strands: f[8] as u32,
            gravelius,
            weibull: f[7] as u16,
        });
        if let Some(p) = parent {
            sk.nodes[p as usize].children.push(i as u32);
        }
    }
    if sk.nodes.is_empty() {
        return Err(fmt("field `nodes`: expected at least the root".into()));
    }
    sk.mark_tips();
    Ok(sk)
}

/// The file whose temporary (`.<name>.<pid>.tmp`, [`super::temporary_path`]) holds a glb's BIN
/// chunk while `out` is written: `out` with the extension `glb.bin` (`k.glb` → `k.glb.bin`).
/// One place for the writer and for [`super::remove_stale_temporaries_of`], which removes a
/// killed export's scratch by this name.
pub(crate) fn glb_scratch_of(out: &Path) -> std::path::PathBuf {
    out.with_extension("glb.bin")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ids that fit in 32 bits are `_ID`; a group with a larger id gets `_ID_LO` and `_ID_HI`,
    /// from which every id comes back exactly.
    #[test]
    fn instance_ids_of_64_bits_are_written_in_two_halves() {
        let mut sk = crate::structure::Skeleton::new();
        sk.add_root(glam::Vec3::ZERO, 0.1);
        sk.add_child(0, glam::Vec3::new(0.0, 0.0, 2.0), 0.05, false).unwrap();
        let chain = crate::structure::mesh::lod_chain(&sk, &Default::default(), &Default::default());
        let big: Vec<u64> = vec![246_290_789_933_056, 7, (1 << 40) | 0xdead_beef];
        for (ids, want) in [(vec![3u64, 9, u32::MAX as u64], vec!["_ID"]), (big.clone(), vec!["_ID_LO", "_ID_HI"])] {
            let n = ids.len();
            let scene = InstancedScene {
                name: "t".into(),
                looks: vec![Look::default()],
                models: vec![StandModel { name: "m".into(), chain: chain.clone(), look: 0, sprigs: TriMesh::default() }],
                groups: vec![InstanceGroup { model: 0, translations: vec![[0.0; 3]; n], yaw: vec![0.0; n], scales: vec![[1.0; 3]; n], ids: ids.clone(), sapling: false }],
                statics: vec![],
                levels: vec![0],
                extras: json!({}),
            };
            let (bytes, _) = instanced_glb_bytes(&scene).unwrap();
            let jl = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
            let js: Value = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
            let bin_at = 20 + jl + 8;
            let node = js["nodes"].as_array().unwrap().iter().find(|n| n["name"] == "m_LOD0").unwrap();
            let attrs = node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"].as_object().unwrap();
            let u32s = |name: &str| -> Vec<u64> {
                let a = &js["accessors"][attrs[name].as_u64().unwrap() as usize];
                let v = &js["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
                let off = bin_at + v["byteOffset"].as_u64().unwrap_or(0) as usize;
                bytes[off..off + 4 * n].chunks(4).map(|c| u32::from_le_bytes(c.try_into().unwrap()) as u64).collect()
            };
            let names: Vec<&str> = attrs.keys().map(|k| k.as_str()).filter(|k| k.starts_with("_ID")).collect();
            let mut sorted = want.clone();
            sorted.sort();
            assert_eq!(names, sorted);
            let back: Vec<u64> = if want.len() == 1 { u32s("_ID") } else { u32s("_ID_LO").iter().zip(u32s("_ID_HI")).map(|(lo, hi)| hi << 32 | lo).collect() };
            assert_eq!(back, ids);
        }
    }

    /// A sidecar of a root and one child, with the child's fields replaced by `child`.
    fn sidecar(child: &str) -> String {
        format!(r#"{{"format": "{SKELETON_FORMAT}", "nodes": [[0, 0, 0, -1, 0.1, 5, 0, 0, 10], {child}]}}"#)
    }

    #[test]
    fn skeleton_sidecars_are_checked_for_values_a_tree_can_have() {
        let p = Path::new("t.skeleton.json");
        let sk = parse_skeleton_sidecar(&sidecar("[0, 0, 1.5, 0, 0.05, 4, 0, 0, 10]"), p).unwrap();
        assert_eq!(sk.nodes.len(), 2);
        assert_eq!(sk.nodes[1].pos, glam::Vec3::new(0.0, 0.0, 1.5));
        for (child, want) in [
            ("[0, 0, 1e30, 0, 0.05, 4, 0, 0, 10]", "node 1: position coordinate 1e30: expected within ±1000 m"),
            ("[0, 0, 1, 0, -0.1, 4, 0, 0, 10]", "node 1: radius -0.1: expected 0–20 m"),
            ("[0, 0, 1, 0, 0.05, 1e9, 0, 0, 10]", "node 1: age 1000000000: expected 0–10,000 years"),
            ("[0, 0, 1, 0, 0.05, 4, -1, 0, 10]", "whole numbers ≥ 0"),
            ("[0, 0, 1, 1, 0.05, 4, 0, 0, 10]", "node 1: parent 1 must precede the node"),
        ] {
            let e = parse_skeleton_sidecar(&sidecar(child), p).unwrap_err().to_string();
            assert!(e.contains("t.skeleton.json") && e.contains(want), "{child}: {e}");
        }
    }
}

