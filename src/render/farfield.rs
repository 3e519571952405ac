//! The far field baked once per set of trees (issue 36, the viewer's frame budget).
//!
//! The renderer's own far field ([`super::canopy`]) is rebuilt every frame: every tree is culled
//! and, when it is smaller on screen than the far-field switch, splatted into the canopy layer.
//! With a million trees (and the mirrored ones of the surroundings, several million) that pass
//! alone takes longer than a frame on a software adapter. A [`FarField`] does it once per set
//! of trees (a year and season of the viewer): every tree is splatted into the canopy layer with
//! its full weight, and the trees are sorted into square plan tiles of [`TILE_M`] with the
//! bounds of what stands in each. A frame then takes from it only the trees of the tiles in
//! which some tree may be taller on screen than the switch ([`FarField::near`]); those are culled
//! and drawn as usual and taken back out of the baked layer ([`super::canopy::CanopyGrid::unsplat`],
//! the same integer amounts), every other tree stays in the baked layer.
//!
//! Without a cap on the near trees this is the renderer's per-frame far field, except that the
//! crowns of trees outside the view frustum are in the layer too (they only reach texels at the
//! frustum's edge). With a cap ([`super::renderer::Renderer::max_near_trees`]), the tiles whose
//! trees may look tallest are taken first, and the far-field switch of the frame rises to the
//! tallest tree left in the layer: a coarser frame, for a camera in motion.

use glam::Vec3;
use rayon::prelude::*;

use super::camera::Camera;
use super::canopy::{crown_albedo, CanopyGrid};
use super::instanced::{bounding_sphere, instance_record, CanopySplat};
use super::lod::{Frustum, LodParams};
use super::scene::{Prototype, TerrainMesh, TreeInstance};

/// Side of the plan tiles the trees are sorted into (m).
pub const TILE_M: f32 = 32.0;

/// What stands in one tile: the bounds of its trees' bounding-sphere centres (m), their largest
/// height and bounding radius (m).
#[derive(Debug, Clone, Copy)]
struct Tile {
    lo: Vec3,
    hi: Vec3,
    max_h: f32,
    max_r: f32,
}

/// Trees sorted into plan tiles, with the canopy layer of all of them splatted once (see the
/// module's text).
#[derive(Debug, Clone)]
pub struct FarField {
    /// The trees, tile by tile.
    trees: Vec<TreeInstance>,
    /// Tile `k`'s trees are `trees[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    tiles: Vec<Tile>,
    /// The canopy grid (the renderer's for the terrain it was baked for).
    pub grid: CanopyGrid,
    /// The baked sums, [`CanopyGrid::splat`] of every valid tree with its full weight.
    sums: Vec<[u32; 4]>,
    /// [`super::canopy::canopy_light_height`] of all the trees (m).
    pub light_height: f32,
    /// Bounds of the trees' stems (m) and the tallest tree (m), [`super::canopy::tree_extent`].
    pub tree_bounds: Option<([f32; 3], [f32; 3], f32)>,
}

/// The trees a frame draws as geometry ([`FarField::near`]).
#[derive(Debug, Clone, Default)]
pub struct Near {
    /// Trees of the near tiles.
    pub instances: Vec<TreeInstance>,
    /// No tree left in the baked layer is taller on screen than this (px, an upper bound):
    /// the frame's far-field switch must put trees of this size wholly in the canopy layer.
    pub floor_px: f32,
    /// Trees left in the baked layer.
    pub far_trees: usize,
}

/// The crown of `t` in the canopy layer at full weight (opacity × foliage cover), as the
/// renderer's culling pass splats a tree below the far-field switch; `None` for a tree the
/// renderer skips as invalid. `crown_r0[s]` is prototype `s`'s
/// [`Prototype::normalised_crown_radius`].
pub fn full_splat(t: &TreeInstance, protos: &[Prototype], crown_r0: &[f32]) -> Option<CanopySplat> {
    let rec = instance_record(t, protos, crown_r0)?;
    let (rgb, cover) = crown_albedo([rec.leaf[0], rec.leaf[1], rec.leaf[2]], rec.leaf[3], [rec.bark[0], rec.bark[1], rec.bark[2]]);
    Some(CanopySplat { x: rec.pos_h[0], y: rec.pos_h[1], r: rec.p3[3], w: rec.p2[0] * cover, rgb })
}

impl FarField {
    /// Bakes `trees` (drawn with `protos`) over `terrain`: the canopy grid is the renderer's
    /// for that terrain ([`CanopyGrid::for_bounds`] of its full bounds), the tiles cover the
    /// trees' plan bounds. Splatting runs on all cores (one grid per worker, then summed).
    pub fn new(trees: Vec<TreeInstance>, protos: &[Prototype], terrain: &TerrainMesh) -> Self {
        let (lo, hi) = terrain.full_bounds();
        let grid = CanopyGrid::for_bounds(lo, hi);
        let crown_r0: Vec<f32> = protos.iter().map(|p| p.normalised_crown_radius()).collect();
        let sums = trees
            .par_chunks(1 << 15)
            .fold(
                || vec![[0u32; 4]; grid.len()],
                |mut s, chunk| {
                    for t in chunk {
                        if let Some(c) = full_splat(t, protos, &crown_r0) {
                            grid.splat(&mut s, c.x, c.y, c.r, c.w, c.rgb);
                        }
                    }
                    s
                },
            )
            .reduce(
                || vec![[0u32; 4]; grid.len()],
                |mut a, b| {
                    for (x, y) in a.iter_mut().zip(&b) {
                        for k in 0..4 {
                            x[k] = x[k].saturating_add(y[k]);
                        }
                    }
                    a
                },
            );
        let light_height = super::canopy::canopy_light_height(&trees);
        // plan bounds of the stems, then a counting sort by tile
        let tree_bounds = super::canopy::tree_extent(&trees);
        let (origin, nx, ny) = match tree_bounds {
            Some((a, b, _)) => ([a[0], a[1]], (((b[0] - a[0]) / TILE_M).floor() as usize + 1).min(4096), (((b[1] - a[1]) / TILE_M).floor() as usize + 1).min(4096)),
            None => ([0.0, 0.0], 1, 1),
        };
        let tile_of = |t: &TreeInstance| {
            let i = (((t.position[0] - origin[0]) / TILE_M).floor().max(0.0) as usize).min(nx - 1);
            let j = (((t.position[1] - origin[1]) / TILE_M).floor().max(0.0) as usize).min(ny - 1);
            j * nx + i
        };
        let mut counts = vec![0u32; nx * ny + 1];
        for t in &trees {
            counts[tile_of(t) + 1] += 1;
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let starts = counts.clone();
        let mut sorted = trees.clone();
        for t in trees {
            let k = tile_of(&t);
            sorted[counts[k] as usize] = t;
            counts[k] += 1;
        }
        let tiles = (0..nx * ny)
            .map(|k| {
                let mut tile = Tile { lo: Vec3::splat(f32::INFINITY), hi: Vec3::splat(f32::NEG_INFINITY), max_h: 0.0, max_r: 0.0 };
                for t in &sorted[starts[k] as usize..starts[k + 1] as usize] {
                    let (c, r) = bounding_sphere(t);
                    if c.is_finite() && r.is_finite() && t.height.is_finite() {
                        tile.lo = tile.lo.min(c);
                        tile.hi = tile.hi.max(c);
                        tile.max_h = tile.max_h.max(t.height);
                        tile.max_r = tile.max_r.max(r);
                    }
                }
                tile
            })
            .collect();
        FarField { trees: sorted, starts, tiles, grid, sums, light_height, tree_bounds }
    }

    /// Number of trees baked.
    pub fn len(&self) -> usize {
        self.trees.len()
    }

    /// Whether no tree was baked.
    pub fn is_empty(&self) -> bool {
        self.trees.is_empty()
    }

    /// The baked sums ([`CanopyGrid::len`] records of coverage, r, g, b in units of
    /// 1/[`super::canopy::CANOPY_ONE`]).
    pub fn sums(&self) -> &[[u32; 4]] {
        &self.sums
    }

    /// The trees a frame of `width` × `height` px seen by `camera` with level parameters `lod`
    /// draws as geometry: those of every tile in the view frustum in which a tree may be taller
    /// on screen than `lod.canopy_px / (1 + band)` (the height of its tallest tree at the
    /// distance of the tile's nearest point: an upper bound), all of them when the canopy
    /// layer is off. With `cap > 0` and more trees than `cap` in those tiles, the tiles are
    /// taken tallest on screen first while the trees fit, and [`Near::floor_px`] is the bound
    /// of the first tile left out.
    pub fn near(&self, camera: &Camera, width: u32, height: u32, lod: &LodParams, cap: usize) -> Near {
        let frustum = Frustum::from_view_proj(camera.view_proj(width.max(1) as f32 / height.max(1) as f32));
        let eye = Vec3::from(camera.eye);
        let floor = if lod.canopy_px > 0.0 { lod.canopy_px / (1.0 + lod.band.max(0.0)) } else { -1.0 };
        let mut cand: Vec<(f32, usize)> = Vec::new();
        for (k, t) in self.tiles.iter().enumerate() {
            // max_h is a maximum of finite heights from 0: never NaN
            if self.starts[k] == self.starts[k + 1] || t.max_h <= 0.0 {
                continue;
            }
            let mid = 0.5 * (t.lo + t.hi);
            if !frustum.sphere_visible(mid, 0.5 * (t.hi - t.lo).length() + t.max_r) {
                continue;
            }
            let px = camera.projected_size_px(eye.clamp(t.lo, t.hi), t.max_h, height as f32);
            if px > floor {
                cand.push((px, k));
            }
        }
        let total: usize = cand.iter().map(|&(_, k)| (self.starts[k + 1] - self.starts[k]) as usize).sum();
        let mut floor_px = floor.max(0.0);
        if cap > 0 && total > cap {
            cand.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let mut n = 0usize;
            let mut keep = cand.len();
            for (i, &(px, k)) in cand.iter().enumerate() {
                let m = (self.starts[k + 1] - self.starts[k]) as usize;
                if n + m > cap {
                    keep = i;
                    floor_px = px;
                    break;
                }
                n += m;
            }
            cand.truncate(keep);
            // tile order, so that the trees keep a stable order between frames
            cand.sort_by_key(|&(_, k)| k);
        }
        let mut instances = Vec::new();
        for &(_, k) in &cand {
            instances.extend_from_slice(&self.trees[self.starts[k] as usize..self.starts[k + 1] as usize]);
        }
        let far_trees = self.trees.len() - instances.len();
        Near { instances, floor_px, far_trees }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::Camera;

    fn proto() -> Vec<Prototype> {
        vec![Prototype { name: "p".into(), lods: crate::render::lod::placeholder_chain(false), bark_color: [0.3, 0.2, 0.1], leaf_color: [0.1, 0.4, 0.1], stiffness: 1.0, look: None, rigid: false }]
    }

    fn flat(size: f32) -> TerrainMesh {
        let g = crate::grid::Grid { width: 2, height: 2, data: vec![0.0f32; 4] };
        crate::render::terrain::from_grid(&g, size, size, &Default::default(), None).unwrap()
    }

    /// A stand of 10 m trees every 8 m over 1 km: from a camera at one corner, the near tiles are
    /// those around it; with a cap the nearest tiles are kept and the floor rises; the baked
    /// layer less the near trees' splats is what the far trees alone splat.
    #[test]
    fn near_tiles_are_the_ones_near_the_camera_and_the_bake_is_exact() {
        let mut trees = Vec::new();
        for j in 0..125 {
            for i in 0..125 {
                trees.push(TreeInstance::new((j * 125 + i) as u64, [4.0 + 8.0 * i as f32, 4.0 + 8.0 * j as f32, 0.0], 10.0, 3.0, 0, [0.1, 0.4, 0.1]));
            }
        }
        let protos = proto();
        let terrain = flat(1000.0);
        let far = FarField::new(trees.clone(), &protos, &terrain);
        assert_eq!(far.len(), trees.len());
        let cam = Camera::look_at([-20.0, -20.0, 30.0], [500.0, 500.0, 0.0], 45.0);
        let lod = LodParams::default();
        let all = far.near(&cam, 400, 300, &lod, 0);
        assert!(!all.instances.is_empty() && all.far_trees > 0, "{} near", all.instances.len());
        assert!((all.floor_px - 6.0 / 1.25).abs() < 1e-4);
        // every tree left out is smaller on screen than the floor
        let near_ids: std::collections::HashSet<u64> = all.instances.iter().map(|t| t.id).collect();
        let frustum = Frustum::from_view_proj(cam.view_proj(400.0 / 300.0));
        for t in trees.iter().filter(|t| !near_ids.contains(&t.id)) {
            let (c, r) = bounding_sphere(t);
            assert!(!frustum.sphere_visible(c, r) || cam.projected_size_px(c, t.height, 300.0) <= all.floor_px, "tree {}", t.id);
        }
        let capped = far.near(&cam, 400, 300, &lod, 500);
        assert!(capped.instances.len() <= 500 && !capped.instances.is_empty());
        assert!(capped.floor_px > all.floor_px);
        // the bake less the near trees = the far trees' own splats
        let crown_r0: Vec<f32> = protos.iter().map(|p| p.normalised_crown_radius()).collect();
        let mut sums = far.sums().to_vec();
        for t in &capped.instances {
            let c = full_splat(t, &protos, &crown_r0).unwrap();
            far.grid.unsplat(&mut sums, c.x, c.y, c.r, c.w, c.rgb);
        }
        let kept: std::collections::HashSet<u64> = capped.instances.iter().map(|t| t.id).collect();
        let mut own = vec![[0u32; 4]; far.grid.len()];
        for t in trees.iter().filter(|t| !kept.contains(&t.id)) {
            let c = full_splat(t, &protos, &crown_r0).unwrap();
            far.grid.splat(&mut own, c.x, c.y, c.r, c.w, c.rgb);
        }
        assert_eq!(sums, own);
    }
}
