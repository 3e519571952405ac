//! glTF 2.0 binary (`.glb`) writer for tree LOD chains (JSON checked with `gltf-json`).
//!
//! Layout: one buffer (the GLB BIN chunk); per LOD level one mesh named `LOD<i>` with up to two
//! primitives (bark, leaves; empty parts are left out) and one node named `LOD<i>`; two
//! materials, `bark` and `leaf` (double-sided), with the given base colours. Sylva's z-up
//! coordinates are converted to glTF's y-up: (x, y, z) ↦ (x, z, −y) (right-handed both ways).
//! Positions carry the min/max bounds the specification requires.

use super::{OutputError, Result};
use crate::error::Error;
use crate::mesh::{LodChain, TriMesh};
use serde_json::{json, Value};
use std::path::Path;

/// Options of [`write_glb`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlbOptions {
    /// Bark base colour (sRGB 0–255).
    pub bark_rgb: [u8; 3],
    /// Leaf base colour (sRGB 0–255).
    pub leaf_rgb: [u8; 3],
    /// Distance (m) between LOD nodes along x, so all levels can be seen side by side; 0 puts
    /// them on top of each other.
    pub spacing_m: f32,
}

impl Default for GlbOptions {
    fn default() -> Self {
        GlbOptions { bark_rgb: [96, 72, 52], leaf_rgb: [70, 120, 50], spacing_m: 0.0 }
    }
}

fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn y_up(p: [f32; 3]) -> [f32; 3] {
    [p[0], p[2], -p[1]]
}

// glTF component types and targets (glTF 2.0 specification, section 3.6).
const F32: u32 = 5126;
const U32: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// Builds the glTF JSON with `serde_json` (gltf-json's struct fields change with its "names"
/// feature, which the dev-dependency `gltf` turns on, so struct literals would not compile in
/// both builds); the result is checked by parsing it back with `gltf-json`.
struct Builder {
    views: Vec<Value>,
    accessors: Vec<Value>,
    bin: Vec<u8>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], stride: Option<usize>, target: u32) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target});
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

    fn primitive(&mut self, m: &TriMesh, material: usize) -> Option<Value> {
        if m.positions.is_empty() || m.indices.is_empty() {
            return None;
        }
        let pos: Vec<[f32; 3]> = m.positions.iter().map(|&p| y_up(p)).collect();
        let (mut lo, mut hi) = (pos[0], pos[0]);
        for p in &pos {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let n = pos.len();
        let pv = self.view(bytemuck::cast_slice(&pos), Some(12), ARRAY_BUFFER);
        let pa = self.accessor(pv, n, F32, "VEC3", Some((lo, hi)));
        let mut attributes = serde_json::Map::new();
        attributes.insert("POSITION".into(), json!(pa));
        if m.normals.len() == n {
            let nrm: Vec<[f32; 3]> = m.normals.iter().map(|&p| y_up(p)).collect();
            let nv = self.view(bytemuck::cast_slice(&nrm), Some(12), ARRAY_BUFFER);
            attributes.insert("NORMAL".into(), json!(self.accessor(nv, n, F32, "VEC3", None)));
        }
        if m.uvs.len() == n {
            let uv: Vec<[f32; 2]> = m.uvs.iter().map(|&[u, v]| [u, 1.0 - v]).collect();
            let uvv = self.view(bytemuck::cast_slice(&uv), Some(8), ARRAY_BUFFER);
            attributes.insert("TEXCOORD_0".into(), json!(self.accessor(uvv, n, F32, "VEC2", None)));
        }
        let iv = self.view(bytemuck::cast_slice(&m.indices), None, ELEMENT_ARRAY_BUFFER);
        let ia = self.accessor(iv, m.indices.len(), U32, "SCALAR", None);
        Some(json!({"attributes": attributes, "indices": ia, "material": material, "mode": 4}))
    }
}

fn material(name: &str, rgb: [u8; 3], double_sided: bool) -> Value {
    let c = [srgb_to_linear(rgb[0]), srgb_to_linear(rgb[1]), srgb_to_linear(rgb[2]), 1.0];
    json!({"name": name, "doubleSided": double_sided, "pbrMetallicRoughness": {"baseColorFactor": c, "metallicFactor": 0.0, "roughnessFactor": 0.9}})
}

/// Encodes a LOD chain as GLB bytes (see the module docs for the layout).
///
/// Errors: [`Error::Invalid`] (in [`OutputError::Input`]) when the chain has no triangles; [`OutputError::Serialize`] when the JSON
/// cannot be written or does not parse back as valid glTF.
pub fn glb_bytes(chain: &LodChain, o: &GlbOptions) -> Result<Vec<u8>> {
    if chain.levels.iter().all(|l| l.triangle_count() == 0) {
        return Err(Error::Invalid { context: "glb".into(), field: "LOD chain".into(), value: "0 triangles".into(), expected: "at least one level with triangles".into() }.into());
    }
    let mut b = Builder { views: Vec::new(), accessors: Vec::new(), bin: Vec::new() };
    let materials = vec![material("bark", o.bark_rgb, false), material("leaf", o.leaf_rgb, true)];
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (i, level) in chain.levels.iter().enumerate() {
        let prims: Vec<Value> = [b.primitive(&level.bark, 0), b.primitive(&level.leaves, 1)].into_iter().flatten().collect();
        if prims.is_empty() {
            continue;
        }
        meshes.push(json!({"name": format!("LOD{i}"), "primitives": prims}));
        let mut node = json!({"name": format!("LOD{i}"), "mesh": meshes.len() - 1});
        if o.spacing_m != 0.0 {
            node["translation"] = json!([o.spacing_m * i as f32, 0.0, 0.0]);
        }
        nodes.push(node);
    }
    while b.bin.len() % 4 != 0 {
        b.bin.push(0);
    }
    let scene_nodes: Vec<usize> = (0..nodes.len()).collect();
    let root = json!({
        "asset": {"version": "2.0", "generator": format!("sylva {}", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": "tree", "nodes": scene_nodes}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": b.bin.len()}],
    });
    let mut js = serde_json::to_vec(&root).map_err(|e| OutputError::Serialize { what: "glb".into(), format: "JSON", message: e.to_string() })?;
    json_check(&js)?;
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + b.bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(b.bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b.bin);
    Ok(out)
}

/// Parses the JSON chunk back with `gltf-json` and runs its validation.
fn json_check(js: &[u8]) -> Result<()> {
    use gltf_json::validation::Validate;
    let root = gltf_json::Root::from_slice(js).map_err(|e| OutputError::Serialize { what: "glb".into(), format: "glTF", message: format!("produced JSON is not glTF: {e}") })?;
    let mut errs = Vec::new();
    root.validate(&root, gltf_json::Path::new, &mut |path, err| errs.push(format!("{}: {err}", path())));
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

/// Path of the skeleton sidecar of a `.glb`: `tree.glb` → `tree.skeleton.json`.
pub fn skeleton_sidecar_path(glb: &Path) -> std::path::PathBuf {
    glb.with_extension("skeleton.json")
}

/// Format tag of the skeleton sidecar.
const SKELETON_FORMAT: &str = "sylva-skeleton";

/// Writes the skeleton of the tree in `glb` to its sidecar ([`skeleton_sidecar_path`]) as JSON:
/// `{"format": "sylva-skeleton", "version": 1, "nodes": [[x, y, z, parent, radius, age,
/// gravelius, weibull, strands], …]}` with Sylva's z-up metres, parent −1 for the root, radius in
/// m, age in years; written to a temporary file then renamed. `sylva tree adapt` reads it back
/// with [`read_skeleton_sidecar`].
///
/// Errors: [`OutputError::Io`] when the file cannot be written.
pub fn write_skeleton_sidecar(glb: &Path, sk: &crate::structure::Skeleton) -> Result<()> {
    let nodes: Vec<Value> = sk
        .nodes
        .iter()
        .map(|n| json!([n.pos.x, n.pos.y, n.pos.z, n.parent.map(|p| p as i64).unwrap_or(-1), n.radius, n.age, n.gravelius, n.weibull, n.strands]))
        .collect();
    let doc = json!({ "format": SKELETON_FORMAT, "version": 1, "nodes": nodes });
    crate::output::write_atomic(&skeleton_sidecar_path(glb), doc.to_string().as_bytes())
}

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
