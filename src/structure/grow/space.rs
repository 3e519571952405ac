//! Voxel space shared by the light-guided and Laplacian models: a regular grid of cubic voxels
//! (edge `voxel_m`, z up) with solid obstacles (boxes, spheres, walls, boxes turned about the
//! vertical, vertical prisms over a footprint polygon). The obstacles are [`crate::obstacle`]'s,
//! re-exported here under their old path.

use crate::error::{Error, Result};
pub use crate::obstacle::{validate_obstacles, Footprint, Obstacle, FOOTPRINT_MAX_POINTS};
use glam::{IVec3, Vec3};

/// Largest voxel count accepted.
pub const MAX_VOXELS: usize = 16_000_000;

/// A regular voxel grid with a solid mask.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelSpace {
    /// Position of the lower corner of voxel (0, 0, 0) (m).
    pub origin: Vec3,
    /// Voxel edge (m).
    pub voxel_m: f32,
    /// Voxel counts along x, y, z.
    pub dims: [usize; 3],
    /// Solid voxels (obstacles), x fastest.
    pub solid: Vec<bool>,
}

impl VoxelSpace {
    /// A grid covering `[min, max]` with voxels of edge `voxel_m`, solid where an obstacle
    /// contains the voxel centre.
    ///
    /// Errors: [`Error::Invalid`] for a non-positive voxel, an empty box or an invalid obstacle
    /// ([`validate_obstacles`]); [`Error::TooLarge`] above [`MAX_VOXELS`].
    pub fn new(min: Vec3, max: Vec3, voxel_m: f32, obstacles: &[Obstacle]) -> Result<Self> {
        if !(voxel_m > 0.0 && voxel_m.is_finite()) || !(max.cmpgt(min).all()) || !min.is_finite() || !max.is_finite() {
            return Err(Error::Invalid { context: "VoxelSpace::new".into(), field: "bounds/voxel".into(), value: format!("{min}..{max}, {voxel_m} m"), expected: "max > min and voxel > 0 m".into() });
        }
        let d = ((max - min) / voxel_m).ceil();
        let dims = [d.x as usize, d.y as usize, d.z as usize];
        let total = dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]);
        if total > MAX_VOXELS {
            return Err(Error::TooLarge { path: "voxel space".into(), width: (dims[0] * dims[1]) as u64, height: dims[2] as u64, limit: MAX_VOXELS as u64 });
        }
        validate_obstacles(obstacles)?;
        let mut s = VoxelSpace { origin: min, voxel_m, dims, solid: vec![false; total] };
        if !obstacles.is_empty() {
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        let c = s.center(IVec3::new(x as i32, y as i32, z as i32));
                        if obstacles.iter().any(|o| o.contains(c)) {
                            s.solid[(z * dims[1] + y) * dims[0] + x] = true;
                        }
                    }
                }
            }
        }
        Ok(s)
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.solid.len()
    }

    /// True for a grid without voxels (never built by [`VoxelSpace::new`]).
    pub fn is_empty(&self) -> bool {
        self.solid.is_empty()
    }

    /// Voxel coordinates containing `p` (may be outside the grid).
    pub fn cell(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) / self.voxel_m).floor().as_ivec3()
    }

    /// Centre of voxel `c` (m).
    pub fn center(&self, c: IVec3) -> Vec3 {
        self.origin + (c.as_vec3() + 0.5) * self.voxel_m
    }

    /// Flat index of voxel `c`, `None` outside the grid.
    pub fn index(&self, c: IVec3) -> Option<usize> {
        if c.x < 0 || c.y < 0 || c.z < 0 {
            return None;
        }
        let (x, y, z) = (c.x as usize, c.y as usize, c.z as usize);
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return None;
        }
        Some((z * self.dims[1] + y) * self.dims[0] + x)
    }

    /// True when `p` is outside the grid or in a solid voxel.
    pub fn blocked(&self, p: Vec3) -> bool {
        self.index(self.cell(p)).map(|i| self.solid[i]).unwrap_or(true)
    }

    /// True when the segment a→b passes through a solid voxel or leaves the grid (sampled at a
    /// quarter voxel).
    pub fn segment_blocked(&self, a: Vec3, b: Vec3) -> bool {
        let n = ((b - a).length() / (0.25 * self.voxel_m)).ceil().max(1.0) as usize;
        (1..=n).any(|k| self.blocked(a + (b - a) * (k as f32 / n as f32)))
    }
}
