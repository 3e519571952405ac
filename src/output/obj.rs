//! Wavefront OBJ writer for tree LOD chains: one object `LOD<i>` per level, groups `bark` and
//! `leaf` with `usemtl` names (no .mtl file is written), z up as in Sylva (Blender's OBJ importer
//! offers "Z up" in its options), vertices `v`, normals `vn`, texture coordinates `vt`.

use super::Result;
use crate::mesh::LodChain;
use std::io::Write;
use std::path::Path;

/// Writes `chain` to `path` as OBJ (atomically). Only the levels in `levels` are written (all
/// when `None`).
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_obj(path: &Path, chain: &LodChain, levels: Option<&[usize]>) -> Result<()> {
    super::write_atomic_with(path, |w| {
        writeln!(w, "# sylva tree, z up, metres")?;
        let mut base = 1usize;
        for (i, level) in chain.levels.iter().enumerate() {
            if levels.is_some_and(|l| !l.contains(&i)) {
                continue;
            }
            writeln!(w, "o LOD{i}")?;
            for (name, m) in [("bark", &level.bark), ("leaf", &level.leaves)] {
                if m.indices.is_empty() {
                    continue;
                }
                writeln!(w, "g LOD{i}_{name}\nusemtl {name}")?;
                for p in &m.positions {
                    writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
                }
                for n in &m.normals {
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
