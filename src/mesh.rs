//! Plain triangle meshes shared by `structure` (which builds them) and `render`/`output`
//! (which draw and export them). Units: metres, z up (DESIGN.md world convention).

use serde::{Deserialize, Serialize};

/// Which material a mesh part uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MaterialKind {
    /// Bark (trunk and branches).
    Bark,
    /// Foliage (leaves, needles, leaf clusters, crown hulls, impostors).
    Leaf,
}

/// An indexed triangle mesh in one material.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {
    /// Vertex positions (m), z up.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates, one per position.
    pub uvs: Vec<[f32; 2]>,
    /// Triangle list, counter-clockwise seen from outside; length a multiple of 3.
    pub indices: Vec<u32>,
}

impl TriMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
    /// Bytes of the vertex and index data (positions and normals 12 B, texture coordinates 8 B
    /// per vertex, 4 B per index); the vectors' unused capacity is not counted.
    pub fn byte_size(&self) -> usize {
        12 * (self.positions.len() + self.normals.len()) + 8 * self.uvs.len() + 4 * self.indices.len()
    }
    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }
    /// Axis-aligned bounds `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        points_bounds(self.positions.iter())
    }
    /// Whether any triangle is a leaf-cluster card marked by [`CLUSTER_CARD_U`] (its first
    /// vertex's u above `CLUSTER_CARD_U / 2`, as the renderer tells them apart).
    pub fn has_cluster_cards(&self) -> bool {
        self.uvs.len() == self.positions.len() && self.indices.chunks_exact(3).any(|t| self.uvs[t[0] as usize][0] > 0.5 * CLUSTER_CARD_U)
    }
    /// Splits a level's foliage into its leaf cards and its leaf-cluster cards (the triangles
    /// marked by [`CLUSTER_CARD_U`], [`TriMesh::has_cluster_cards`]), the latter with u moved back
    /// to 0–1, so that writers can give each its own material (the glTF and OBJ writers, the
    /// previews). Each part keeps only the vertices its triangles use, in their first order.
    pub fn split_cluster_cards(&self) -> (TriMesh, TriMesh) {
        let mut parts = (TriMesh::default(), TriMesh::default());
        if !self.has_cluster_cards() {
            parts.0 = self.clone();
            return parts;
        }
        let mut remap = vec![[u32::MAX; 2]; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let k = usize::from(self.uvs[t[0] as usize][0] > 0.5 * CLUSTER_CARD_U);
            let m = if k == 0 { &mut parts.0 } else { &mut parts.1 };
            for &i in t {
                let i = i as usize;
                if remap[i][k] == u32::MAX {
                    remap[i][k] = m.positions.len() as u32;
                    m.positions.push(self.positions[i]);
                    if self.normals.len() == self.positions.len() {
                        m.normals.push(self.normals[i]);
                    }
                    let [u, v] = self.uvs[i];
                    m.uvs.push([if k == 1 { u - CLUSTER_CARD_U } else { u }, v]);
                }
                m.indices.push(remap[i][k]);
            }
        }
        parts
    }
}

/// Axis-aligned bounds `(min, max)` of points; `None` when there is none.
pub fn points_bounds<'a>(mut it: impl Iterator<Item = &'a [f32; 3]>) -> Option<([f32; 3], [f32; 3])> {
    let &first = it.next()?;
    let (mut lo, mut hi) = (first, first);
    for p in it {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Some((lo, hi))
}

/// A tree mesh at one level of detail: bark and foliage parts.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TreeMesh {
    /// Trunk and branches.
    pub bark: TriMesh,
    /// Leaves / leaf clusters / hull / impostor cards.
    pub leaves: TriMesh,
}

impl TreeMesh {
    /// Total triangles of both parts.
    pub fn triangle_count(&self) -> usize {
        self.bark.triangle_count() + self.leaves.triangle_count()
    }
}

/// Offset of the texture coordinate u (0–1 on a card) that marks a leaf-cluster card among a
/// level's leaf cards: the renderer draws a card whose u runs from `CLUSTER_CARD_U` to
/// `CLUSTER_CARD_U + 1` with its species' leaf-cluster texture instead of its leaf texture (the
/// sprigs that carry a full-detail tree's crown leaf area, `job::adapted::adapted_model`).
pub const CLUSTER_CARD_U: f32 = 2.0;

/// Number of levels of detail, defined once: the chain `structure::mesh::lod_chain` builds
/// (full mesh, reduced skeleton with leaf clusters, crown hull, impostor) and the levels the
/// renderer draws (`render::lod::drawn_levels`: the first three meshes, then its own billboard).
/// The culling shader `render/shaders/cull.wgsl` declares the same `const LOD_LEVELS` (checked
/// by a test in `render::lod`) and packs one level per word of its 4-word records, so changing
/// it means changing those records too (a compile-time assertion in `render::renderer` says so).
pub const LOD_LEVELS: usize = 4;

/// Levels of detail of one tree, finest first (DESIGN: full mesh, reduced skeleton with leaf
/// clusters, crown hull, billboard impostor).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LodChain {
    /// Meshes, index 0 = full detail (empty after [`LodChain::free_meshes`]).
    pub levels: Vec<TreeMesh>,
    /// The figures of the meshes [`LodChain::free_meshes`] let go of (the renderer holds its
    /// own copy of them); `None` while the meshes are here.
    #[serde(skip)]
    pub freed: Option<FreedMeshes>,
}

/// What a chain keeps of the meshes it freed ([`LodChain::free_meshes`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FreedMeshes {
    /// Triangles of each level (bark and leaves).
    pub triangles: Vec<usize>,
    /// Largest horizontal distance (m per m of height) of a level-0 foliage vertex from the axis.
    pub leaf_radius0: f32,
}

impl LodChain {
    /// A chain of the level meshes `levels`, finest first.
    pub fn new(levels: Vec<TreeMesh>) -> LodChain {
        LodChain { levels, freed: None }
    }

    /// Triangles of level `level` (0 when there is no such level), also after
    /// [`LodChain::free_meshes`].
    pub fn level_triangles(&self, level: usize) -> usize {
        match &self.freed {
            Some(f) => f.triangles.get(level).copied().unwrap_or(0),
            None => self.levels.get(level).map_or(0, |l| l.triangle_count()),
        }
    }

    /// Largest horizontal distance of a level-0 foliage vertex from the axis (0 without
    /// foliage), also after [`LodChain::free_meshes`].
    pub fn leaf_radius0(&self) -> f32 {
        match &self.freed {
            Some(f) => f.leaf_radius0,
            None => self.levels.first().map(|l| l.leaves.positions.iter().map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt()).fold(0.0f32, f32::max)).unwrap_or(0.0),
        }
    }

    /// Lets go of the level meshes once a renderer holds its own copy of them (issue 34: the
    /// adapted near field's meshes, 0.35 GB for the default run's ground view, were held twice
    /// during the frame), keeping the level count, each level's triangles and the level-0
    /// foliage radius. The chain cannot be uploaded again afterwards (its levels are empty).
    pub fn free_meshes(&mut self) {
        if self.freed.is_none() {
            let f = FreedMeshes { triangles: (0..self.levels.len()).map(|l| self.level_triangles(l)).collect(), leaf_radius0: self.leaf_radius0() };
            self.levels.iter_mut().for_each(|l| *l = TreeMesh::default());
            self.freed = Some(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn card(m: &mut TriMesh, x: f32, du: f32) {
        let b = m.positions.len() as u32;
        for (p, uv) in [([x, 0.0, 0.0], [0.0, 0.0]), ([x + 1.0, 0.0, 0.0], [1.0, 0.0]), ([x + 1.0, 0.0, 1.0], [1.0, 1.0]), ([x, 0.0, 1.0], [0.0, 1.0])] {
            m.positions.push(p);
            m.normals.push([0.0, -1.0, 0.0]);
            m.uvs.push([uv[0] + du, uv[1]]);
        }
        m.indices.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    }

    #[test]
    fn cluster_cards_split_from_leaf_cards_with_their_u_restored() {
        let mut m = TriMesh::default();
        card(&mut m, 0.0, 0.0);
        card(&mut m, 5.0, CLUSTER_CARD_U);
        card(&mut m, 10.0, 0.0);
        assert!(m.has_cluster_cards());
        let (cards, sprigs) = m.split_cluster_cards();
        assert_eq!((cards.triangle_count(), sprigs.triangle_count()), (4, 2));
        assert_eq!((cards.positions.len(), sprigs.positions.len()), (8, 4));
        // the sprig is the card at x = 5 with u back in 0–1
        assert_eq!(sprigs.positions[0], [5.0, 0.0, 0.0]);
        assert_eq!(sprigs.uvs.iter().map(|uv| uv[0]).fold(f32::MIN, f32::max), 1.0);
        assert_eq!(cards.positions[4], [10.0, 0.0, 0.0]);
        assert!(cards.indices.iter().all(|&i| (i as usize) < cards.positions.len()));
        // a mesh of leaf cards alone is returned whole
        let mut plain = TriMesh::default();
        card(&mut plain, 0.0, 0.0);
        assert!(!plain.has_cluster_cards());
        let (same, none) = plain.split_cluster_cards();
        assert_eq!(same, plain);
        assert!(none.indices.is_empty());
    }
}
