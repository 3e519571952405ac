//! Wavefront OBJ writer for tree LOD chains, with its material library and textures.
//!
//! `NAME.obj` holds one object `<tree>_LOD<i>` per level, groups `LOD<i>_bark` and `LOD<i>_leaf`
//! with `usemtl` names, y up as OBJ importers expect (Blender's, game engines': Sylva's x east,
//! y north, z up written as x, z, −y; round 33's trial found the z-up file lying on its side),
//! vertices `v`, normals `vn`, texture coordinates `vt` (v up, OBJ's convention). Beside it,
//! `NAME.mtl` (referenced by `mtllib`) defines the five materials of the [`Look`] as
//! `output::gltf` does (`<look>_bark`, `<look>_leaf`, `<look>_cluster`, `<look>_crown`,
//! `<look>_impostor`), each with `map_Kd` and, for the alpha-tested cards, `map_d` naming PNG
//! textures `NAME_<look>_<part>.png` written beside it. Every file is written atomically.

use super::gltf::Look;
use super::Result;
use crate::mesh::LodChain;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Material part names per level's foliage (leaf cards, clusters, crown hull, billboard).
const FOLIAGE: [&str; 4] = ["leaf", "cluster", "crown", "impostor"];

/// The files [`write_obj`] writes beside `path`: the `.mtl` and the textures, in that order.
pub fn companion_paths(path: &Path, look: &Look) -> Vec<PathBuf> {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "tree".into());
    let mut v = vec![path.with_extension("mtl")];
    for part in ["bark", "leaf", "cluster", "crown", "impostor"] {
        v.push(path.with_file_name(format!("{stem}_{}_{part}.png", look.name)));
    }
    v
}

/// Writes `chain` to `path` as OBJ (atomically) with its `.mtl` and textures beside it (module
/// documentation); `name` names the objects. Only the levels in `levels` are written (all when
/// `None`).
///
/// Errors: [`super::OutputError::Io`] naming the file that cannot be written;
/// [`super::OutputError::Encode`] when a texture cannot be encoded.
pub fn write_obj(path: &Path, chain: &LodChain, levels: Option<&[usize]>, name: &str, look: &Look) -> Result<()> {
    let files = companion_paths(path, look);
    let fname = |p: &PathBuf| p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let t = &look.textures;
    for (p, img) in files[1..].iter().zip([&t.bark, &t.leaf, &t.cluster, &t.crown, &t.impostor]) {
        super::pictures::write_png(p, img)?;
    }
    let l = &look.name;
    super::write_atomic_with(&files[0], |w| {
        writeln!(w, "# sylva materials for {}", fname(&path.to_path_buf()))?;
        for (k, part) in ["bark", "leaf", "cluster", "crown", "impostor"].iter().enumerate() {
            writeln!(w, "\nnewmtl {l}_{part}\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nNs 10\nd 1\nillum 1")?;
            // the crown hull's coordinates go once round it: repeat its leafy picture
            let repeat = if *part == "crown" { "-s 6 3 1 " } else { "" };
            writeln!(w, "map_Kd {repeat}{}", fname(&files[k + 1]))?;
            if matches!(*part, "leaf" | "cluster" | "impostor") {
                writeln!(w, "map_d {}", fname(&files[k + 1]))?;
            }
        }
        Ok(())
    })?;
    super::write_atomic_with(path, |w| {
        writeln!(w, "# sylva tree, y up (x east, y up, z south), metres")?;
        writeln!(w, "mtllib {}", fname(&files[0]))?;
        let mut base = 1usize;
        for (i, level) in chain.levels.iter().enumerate() {
            if levels.is_some_and(|l| !l.contains(&i)) {
                continue;
            }
            writeln!(w, "o {name}_LOD{i}")?;
            // leaf-cluster cards marked among the full level's leaves get the cluster material
            let (cards, sprigs) = if i == 0 && level.leaves.has_cluster_cards() { level.leaves.split_cluster_cards() } else { (level.leaves.clone(), crate::mesh::TriMesh::default()) };
            for (part, mtl, m) in [("bark", "bark", &level.bark), ("leaf", FOLIAGE[i.min(3)], &cards), ("sprig", FOLIAGE[1], &sprigs)] {
                if m.indices.is_empty() {
                    continue;
                }
                writeln!(w, "g LOD{i}_{part}\nusemtl {l}_{mtl}")?;
                for p in m.positions.iter().map(|&p| super::gltf::y_up(p)) {
                    writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
                }
                for n in m.normals.iter().map(|&n| super::gltf::y_up(n)) {
                    writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
                }
                for t in &m.uvs {
                    writeln!(w, "vt {} {}", t[0], t[1])?;
                }
                let has_n = m.normals.len() == m.positions.len();
                let has_t = m.uvs.len() == m.positions.len();
                for t in m.indices.chunks_exact(3) {
                    let f = |k: u32| {
                        let k = k as usize + base;
                        match (has_t, has_n) {
                            (true, true) => format!("{k}/{k}/{k}"),
                            (false, true) => format!("{k}//{k}"),
                            (true, false) => format!("{k}/{k}"),
                            _ => format!("{k}"),
                        }
                    };
                    writeln!(w, "f {} {} {}", f(t[0]), f(t[1]), f(t[2]))?;
                }
                base += m.positions.len();
            }
        }
        Ok(())
    })
}
