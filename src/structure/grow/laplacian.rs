//! Laplacian (dielectric-breakdown) growth (Jinasena & Sonnadara, `003_*.txt`, sections III–IV;
//! Niemeyer, Pietronero & Wiesmann 1984).
//!
//! The growth space is a voxel grid holding a potential φ: light-source voxels are held at
//! φ = 1, the grid boundary, obstacle voxels and voxels occupied by the tree at φ = 0, and the
//! rest solves Laplace's equation ∇²φ = 0 by successive over-relaxation (SOR, ω = 1.8, warm
//! started between steps). Each step adds one branch (one voxel step, fixed length): every bud
//! (a node with fewer than two children) proposes its free neighbour voxels in the forward
//! hemisphere, and one candidate is drawn with probability ∝ φ^η (DBM). Voxels with φ = 0 —
//! obstacles above all — therefore never receive a branch. Widths follow the Strahler order k:
//! W(k) = c·k^α (polynomial) or c·β^k (exponential), eq. (1) and Table I (c 0.67, α 1.15,
//! β 1.50); diameters are W(k)/W(1) × `base_width_m`.

use super::envelope::CrownEnvelope;
use super::space::VoxelSpace;
use crate::obstacle::Obstacle;
use crate::error::{Error, Result};
use crate::rng::{salt, Stream};
use crate::species::LaplacianParams;
use crate::structure::params::LAPLACIAN_ALPHA;
use crate::structure::skeleton::Skeleton;
use glam::{IVec3, Vec3};

/// Form of the width function W(k) (eq. 1 of `003_*.txt`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WidthForm {
    /// W(k) = c·k^α.
    Polynomial,
    /// W(k) = c·β^k.
    Exponential,
}

/// Paper's width W(k) (eq. 1, Table I: c = 0.67, α = 1.15, β = `rate` (1.50)); unitless.
pub fn width(k: u16, form: WidthForm, rate: f32) -> f32 {
    let c = 0.67;
    match form {
        WidthForm::Polynomial => c * (k.max(1) as f32).powf(LAPLACIAN_ALPHA),
        WidthForm::Exponential => c * rate.powi(k.max(1) as i32),
    }
}

/// Where the light comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightSource {
    /// The top voxel layer (diffuse sky).
    Sky,
    /// A sphere of voxels around a point (m) with a radius (m).
    Point(Vec3, f32),
    /// The species' crown envelope (our addition, see [`super::envelope`]): voxels outside it
    /// are held at φ = 0 and never grown into, its surface above the lowest quarter of the crown
    /// is the light source (φ = 1) with a short column of source voxels above the apex, and
    /// the trunk corridor below the crown stays free; the tree
    /// fills the crown from the inside and stops at the apex.
    Envelope(CrownEnvelope),
}

/// Options of the Laplacian model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaplacianOptions {
    /// Voxel edge = branch length unit (m).
    pub voxel_m: f32,
    /// Half-width of the grid around the root (m).
    pub extent_m: f32,
    /// Grid height (m).
    pub height_m: f32,
    /// Light source.
    pub source: LightSource,
    /// Width form.
    pub width_form: WidthForm,
    /// SOR sweeps after each added branch (warm start).
    pub sweeps_per_step: u32,
}

impl Default for LaplacianOptions {
    fn default() -> Self {
        LaplacianOptions { voxel_m: 0.25, extent_m: 3.0, height_m: 7.0, source: LightSource::Sky, width_form: WidthForm::Exponential, sweeps_per_step: 2 }
    }
}

/// A Laplacian growth run: grid, potential and the tree.
#[derive(Debug, Clone)]
pub struct LaplacianGrowth {
    /// Voxel grid with obstacles.
    pub space: VoxelSpace,
    /// Potential φ per voxel.
    pub phi: Vec<f32>,
    /// Fixed voxels (boundary, obstacle, tree, source).
    fixed: Vec<bool>,
    /// Grid cell of every node.
    cells: Vec<IVec3>,
    /// The tree.
    pub skeleton: Skeleton,
    params: LaplacianParams,
    options: LaplacianOptions,
    seed: u64,
    steps: u64,
}

impl LaplacianGrowth {
    /// Sets up the grid around a root at the origin, the boundary conditions and an initial
    /// potential (200 SOR sweeps), with a one-voxel seedling.
    ///
    /// Errors: [`Error::Invalid`] for a bad η, widths or root position; errors of
    /// [`VoxelSpace::new`].
    pub fn new(params: LaplacianParams, options: LaplacianOptions, obstacles: &[Obstacle], seed: u64) -> Result<Self> {
        if !(params.eta >= 0.0 && params.eta.is_finite()) || !(params.base_width_m > 0.0) || !(params.width_rate > 0.0) {
            return Err(Error::Invalid { context: "Laplacian growth".into(), field: "eta/base_width_m/width_rate".into(), value: format!("{params:?}"), expected: "eta ≥ 0, widths > 0".into() });
        }
        let e = options.extent_m;
        let space = VoxelSpace::new(Vec3::new(-e, -e, 0.0), Vec3::new(e, e, options.height_m), options.voxel_m, obstacles)?;
        let n = space.len();
        let [nx, ny, nz] = space.dims;
        let mut phi = vec![0.0f32; n];
        let mut fixed = vec![false; n];
        // envelope with a corridor at least one voxel column wide around the root
        let env = match options.source {
            LightSource::Envelope(mut env) => {
                env.trunk_radius_m = env.trunk_radius_m.max(0.75 * options.voxel_m);
                Some(env)
            }
            _ => None,
        };
        let outside = |c: IVec3| env.map(|e| e.outside_m(space.center(c)) > 0.0).unwrap_or(false);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = (z * ny + y) * nx + x;
                    let c = IVec3::new(x as i32, y as i32, z as i32);
                    let boundary = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                    let source = match options.source {
                        LightSource::Sky => z == nz - 2 && !boundary,
                        LightSource::Point(p, r) => space.center(c).distance(p) <= r.max(options.voxel_m),
                        LightSource::Envelope(e) => {
                            let d = space.center(c) - e.base;
                            let (z, rho) = (d.z, d.truncate().length());
                            // the trunk corridor stays free so the leader can climb the narrow top
                            rho > env.map_or(0.0, |e| e.trunk_radius_m) && !outside(c) && z >= e.crown_base_m + 0.25 * e.crown_length_m() && [IVec3::X, -IVec3::X, IVec3::Y, -IVec3::Y, IVec3::Z, -IVec3::Z].iter().any(|&d| outside(c + d))
                        }
                    };
                    // the sky above the apex: a short column of source voxels over the crown
                    // top draws the leader up to the species' height
                    let apex = env.is_some_and(|e| {
                        let p = space.center(c) - e.base;
                        p.z > e.height_m && p.z <= e.height_m + 2.0 * options.voxel_m && p.truncate().length() <= e.trunk_radius_m
                    });
                    if apex && !space.solid[i] && !boundary {
                        fixed[i] = true;
                        phi[i] = 1.0;
                    } else if space.solid[i] || boundary || outside(c) {
                        fixed[i] = true;
                    } else if source {
                        fixed[i] = true;
                        phi[i] = 1.0;
                    }
                }
            }
        }
        let root_cell = space.cell(Vec3::new(0.0, 0.0, 0.5 * options.voxel_m)) + IVec3::Z;
        let first = space.index(root_cell + IVec3::Z);
        if space.index(root_cell).map(|i| fixed[i]).unwrap_or(true) || first.map(|i| fixed[i]).unwrap_or(true) {
            return Err(Error::Invalid { context: "Laplacian growth".into(), field: "root".into(), value: "origin".into(), expected: "a root voxel and the one above it free of obstacles".into() });
        }
        let mut sk = Skeleton::new();
        let base = space.center(root_cell) - Vec3::Z * (0.5 * options.voxel_m);
        sk.add_root(Vec3::new(0.0, 0.0, base.z.max(0.0)), params.base_width_m * 0.5);
        let mut g = LaplacianGrowth { space, phi, fixed, cells: vec![root_cell], skeleton: sk, params, options, seed, steps: 0 };
        g.occupy(root_cell);
        g.add_node(0, root_cell + IVec3::Z)?;
        g.relax(200);
        Ok(g)
    }

    fn occupy(&mut self, c: IVec3) {
        if let Some(i) = self.space.index(c) {
            self.fixed[i] = true;
            self.phi[i] = 0.0;
        }
    }

    fn add_node(&mut self, parent: usize, c: IVec3) -> Result<()> {
        let lateral = !self.skeleton.nodes[parent].children.is_empty();
        let pos = self.space.center(c);
        self.skeleton.add_child(parent as u32, pos, 0.0, lateral)?;
        self.cells.push(c);
        self.occupy(c);
        Ok(())
    }

    /// `sweeps` SOR sweeps (ω = 1.8) over the free voxels, in a fixed order (deterministic).
    pub fn relax(&mut self, sweeps: u32) {
        let [nx, ny, nz] = self.space.dims;
        let (sx, sy) = (1, nx);
        let sz = nx * ny;
        let w = 1.8f32;
        for _ in 0..sweeps {
            for z in 1..nz.saturating_sub(1) {
                for y in 1..ny.saturating_sub(1) {
                    let row = (z * ny + y) * nx;
                    for x in 1..nx.saturating_sub(1) {
                        let i = row + x;
                        if self.fixed[i] {
                            continue;
                        }
                        let p = &self.phi;
                        let avg = (p[i - sx] + p[i + sx] + p[i - sy] + p[i + sy] + p[i - sz] + p[i + sz]) / 6.0;
                        let v = p[i] + w * (avg - p[i]);
                        self.phi[i] = v.clamp(0.0, 1.0);
                    }
                }
            }
        }
    }

    /// Adds one branch (one DBM step). Returns false when no candidate has φ > 0.
    pub fn step(&mut self) -> bool {
        self.steps += 1;
        let mut cands: Vec<(usize, IVec3, f64)> = Vec::new();
        let mut total = 0.0f64;
        for (i, n) in self.skeleton.nodes.iter().enumerate() {
            if n.children.len() >= 2 || i == 0 {
                continue;
            }
            let c = self.cells[i];
            let dir = match n.parent {
                Some(p) => (c - self.cells[p as usize]).as_vec3().normalize_or(Vec3::Z),
                None => Vec3::Z,
            };
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let d = IVec3::new(dx, dy, dz);
                        if d == IVec3::ZERO || d.as_vec3().dot(dir) <= 0.0 {
                            continue;
                        }
                        let Some(j) = self.space.index(c + d) else { continue };
                        if self.fixed[j] || self.phi[j] <= 0.0 {
                            continue;
                        }
                        let p = (self.phi[j] as f64).powf(self.params.eta as f64);
                        if p > 0.0 {
                            total += p;
                            cands.push((i, c + d, p));
                        }
                    }
                }
            }
        }
        if total <= 0.0 || cands.is_empty() {
            return false;
        }
        let mut rng = Stream::new(self.seed, 0, self.steps, salt::ARCHITECTURE);
        let mut x = rng.uniform() * total;
        let mut pick = cands.len() - 1;
        for (k, c) in cands.iter().enumerate() {
            x -= c.2;
            if x <= 0.0 {
                pick = k;
                break;
            }
        }
        let (parent, cell, _) = cands[pick];
        if self.add_node(parent, cell).is_err() {
            return false;
        }
        self.relax(self.options.sweeps_per_step);
        true
    }

    /// Sets every node's radius from its Strahler order: W(k)/W(1) × `base_width_m` / 2.
    pub fn apply_widths(&mut self) {
        let k = self.skeleton.strahler();
        let w1 = width(1, self.options.width_form, self.params.width_rate);
        for (n, &k) in self.skeleton.nodes.iter_mut().zip(&k) {
            n.radius = 0.5 * self.params.base_width_m * width(k, self.options.width_form, self.params.width_rate) / w1;
        }
        self.skeleton.mark_tips();
    }
}

/// Grows a tree of up to `branches` branches (one voxel each) and applies the Strahler widths.
///
/// Errors: as [`LaplacianGrowth::new`].
pub fn grow(params: &LaplacianParams, options: &LaplacianOptions, obstacles: &[Obstacle], seed: u64, branches: u32) -> Result<LaplacianGrowth> {
    let mut g = LaplacianGrowth::new(*params, *options, obstacles, seed)?;
    for _ in 0..branches {
        if !g.step() {
            break;
        }
    }
    g.apply_widths();
    Ok(g)
}
