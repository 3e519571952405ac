//! The light model of Plastic Trees section 4.2 (Pirk et al. 2012, `000_*.txt`): eq. (3) with the
//! sky intensity I = cos²(Δσ) around the brightest sky point and the sin θ weight, translucent
//! leaf clusters (eq. 4, γ_c = γ_c0^r_c), solid obstacles and the terrain surface, and shadow
//! volumes that pick the casters to test.

use crate::structure::grow::space::Obstacle;
use crate::error::{Error, Result};
use glam::{BVec4A, Vec2, Vec3, Vec4};

/// Rings of the default sky quadrature ([`Sky::toward`]): direction counts of the rings around
/// the brightest sky point, multiples of 4 so that a sky with its brightest point at the zenith
/// is symmetric under quarter turns about the vertical (no azimuth bias).
pub const DEFAULT_RINGS: [usize; 3] = [4, 8, 12];

/// Number of directions of the default sky with its brightest point at the zenith (fewer when
/// the brightest point is lower: directions below the horizon are dropped).
pub const SKY_DIRS: usize = 24;

/// Most sky directions a [`Sky`] may have: the sky masks of solids ([`Solids::mask`]) are `u32`
/// bit sets.
pub const MAX_SKY_DIRS: usize = 32;

/// The sky of eq. (3): directions over the upper hemisphere with quadrature weights of
/// c·I(θ, φ)·sin θ, I = cos²(Δσ) (Δσ: angle between the direction and the brightest sky point;
/// I = 0 beyond 90°, our reading: the paper's cos² would rise again below the horizon of the
/// brightest point), c such that Σ w_k = 1.
///
/// The default quadrature ([`Sky::toward`], [`Sky::with_rings`]) samples the integrand by
/// importance: rings around the brightest point at equal shares of the weight ∫ I dΩ (the
/// cumulative weight within Δσ of the brightest point is F(Δσ) = 1 − cos³Δσ, so ring r of a
/// set with cumulative shares F₀ < F₁ sits at Δσ = arccos((1 − (F₀ + F₁)/2)^⅓)), every direction
/// of equal weight before the directions below the horizon are dropped. Against a reference of
/// 5,872 directions, on the 2,506-node bench tree's nodes (open and beside a wall, brightest
/// point at the zenith or 40° high), its 24 directions give a mean |Δi| of 0.018–0.024 and a
/// light-direction error of 1.1–1.9°, smaller than the 32 directions of equal zenith bands
/// ([`Sky::zenith_rings`]: 0.021–0.031 and 1.2–2.2°), which spend 12 directions on the ring
/// that carries 4 % of the weight (`examples/sky_quadrature.rs`; BENCHMARKS.md).
#[derive(Debug, Clone, PartialEq)]
pub struct Sky {
    /// Unit direction towards the brightest sky point (z ≥ 0).
    pub brightest: Vec3,
    /// Unit sky directions (z > 0), exact in f32: components that are 0 analytically are 0.
    pub dirs: Vec<Vec3>,
    /// Weights (sum 1, ≥ 0), one per direction.
    pub weights: Vec<f32>,
}

impl Default for Sky {
    fn default() -> Self {
        Sky::toward(Vec3::Z)
    }
}

/// cos/sin of an angle computed in f64 with values below 1e-12 snapped to 0 (cos(3π/2) in f32
/// is +1.19e-8, which made infinite walls at +x darken −y rays).
fn exact_sin_cos(a: f64) -> (f32, f32) {
    let snap = |v: f64| if v.abs() < 1e-12 { 0.0 } else { v as f32 };
    (snap(a.sin()), snap(a.cos()))
}

/// Checks a ring set: 1 to [`MAX_SKY_DIRS`] directions in all, each ring a positive multiple of 4.
fn check_rings(rings: &[usize]) -> Result<()> {
    let total: usize = rings.iter().sum();
    if rings.is_empty() || rings.iter().any(|&n| n == 0 || n % 4 != 0) || total > MAX_SKY_DIRS {
        return Err(Error::Invalid {
            context: "Plastic Trees sky".into(),
            field: "rings".into(),
            value: format!("{rings:?}"),
            expected: format!("one or more rings of direction counts that are positive multiples of 4, at most {MAX_SKY_DIRS} directions in all"),
        });
    }
    Ok(())
}

/// The unit direction towards the brightest point `b`: normalised; the zenith when it is zero,
/// not finite or below the horizon.
fn brightest_or_zenith(b: Vec3) -> Vec3 {
    if b.is_finite() && b.z >= 0.0 {
        b.normalize_or(Vec3::Z)
    } else {
        Vec3::Z
    }
}

/// Weights scaled to sum 1 (left as they are when they sum to 0).
fn normalise(weights: &mut [f32]) {
    let sum: f32 = weights.iter().sum();
    if sum > 0.0 {
        weights.iter_mut().for_each(|w| *w /= sum);
    }
}

impl Sky {
    /// The default sky ([`DEFAULT_RINGS`], importance-sampled, see [`Sky`]) with its brightest
    /// point in direction `brightest` (normalised; the zenith when it is zero, not finite or
    /// below the horizon).
    pub fn toward(brightest: Vec3) -> Sky {
        Sky::importance(brightest_or_zenith(brightest), &DEFAULT_RINGS)
    }

    /// The importance-sampled sky of [`Sky`] with rings of `rings` directions around the
    /// brightest point (innermost first), e.g. `[4, 8]` for a faster, coarser sky of 12.
    ///
    /// Errors: [`Error::Invalid`] naming `rings` unless every ring is a positive multiple of 4
    /// and there are 1–[`MAX_SKY_DIRS`] directions in all.
    pub fn with_rings(brightest: Vec3, rings: &[usize]) -> Result<Sky> {
        check_rings(rings)?;
        Ok(Sky::importance(brightest_or_zenith(brightest), rings))
    }

    fn importance(b: Vec3, rings: &[usize]) -> Sky {
        let total: usize = rings.iter().sum();
        // the frame about b: exact axes for the zenith; else u horizontal, v = b × u
        let (u, v) = if b == Vec3::Z {
            (Vec3::X, Vec3::Y)
        } else {
            let u = b.cross(Vec3::Z).normalize_or(Vec3::X);
            (u, b.cross(u))
        };
        let (mut dirs, mut weights) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let mut cum = 0usize;
        for (r, &n) in rings.iter().enumerate() {
            // the ring's Δσ at the middle of its share of F(Δσ) = 1 − cos³Δσ
            let (f0, f1) = (cum as f64 / total as f64, (cum + n) as f64 / total as f64);
            cum += n;
            let (sd, cd) = exact_sin_cos((1.0 - 0.5 * (f0 + f1)).cbrt().acos());
            for k in 0..n {
                // rings offset by half a step alternately; both sets are symmetric under 90° turns
                let phi = (k as f64 + 0.5 * (r % 2) as f64) * std::f64::consts::TAU / n as f64;
                let (sp, cp) = exact_sin_cos(phi);
                let d = if b == Vec3::Z { Vec3::new(sd * cp, sd * sp, cd) } else { (b * cd + (u * cp + v * sp) * sd).normalize() };
                if d.z <= 0.0 {
                    continue; // below the horizon: no sky there
                }
                dirs.push(d);
                weights.push(((f1 - f0) / n as f64) as f32);
            }
        }
        normalise(&mut weights);
        Sky { brightest: b, dirs, weights }
    }

    /// A fine reference quadrature for checking the others: `bands` equal zenith-angle bands of
    /// 4·round(bands·sin θ) directions each (1,464 for 24 bands, 5,872 for 48), weights
    /// I·sin θ·Δθ·Δφ. It has more than [`MAX_SKY_DIRS`] directions, so it serves checks that
    /// trace rays themselves, not [`Solids::mask`] or [`light_at`].
    pub fn reference(brightest: Vec3, bands: usize) -> Sky {
        let bands = bands.max(1);
        let counts: Vec<usize> = (0..bands)
            .map(|r| {
                let theta = (r as f64 + 0.5) * std::f64::consts::FRAC_PI_2 / bands as f64;
                4 * (theta.sin() * bands as f64).round().max(1.0) as usize
            })
            .collect();
        Sky::zenith_bands(brightest_or_zenith(brightest), &counts)
    }

    /// The quadrature of rounds 1–10, kept for comparison: equal zenith-angle bands with `rings`
    /// directions each (the old default was `[4, 8, 8, 12]`), weights I·sin θ·Δθ·Δφ.
    ///
    /// Errors: as [`Sky::with_rings`].
    pub fn zenith_rings(brightest: Vec3, rings: &[usize]) -> Result<Sky> {
        check_rings(rings)?;
        Ok(Sky::zenith_bands(brightest_or_zenith(brightest), rings))
    }

    /// Equal zenith-angle bands of `counts[r]` directions (offset by half a step in odd bands),
    /// weights I·sin θ·Δθ·Δφ normalised; `b` the unit direction of the brightest point.
    fn zenith_bands(b: Vec3, counts: &[usize]) -> Sky {
        let dtheta = std::f64::consts::FRAC_PI_2 / counts.len() as f64;
        let mut dirs = Vec::new();
        let mut weights = Vec::new();
        for (r, &n) in counts.iter().enumerate() {
            let theta = (r as f64 + 0.5) * dtheta; // zenith angle
            let (st, ct) = exact_sin_cos(theta);
            for k in 0..n {
                let phi = (k as f64 + 0.5 * (r % 2) as f64) * std::f64::consts::TAU / n as f64;
                let (sp, cp) = exact_sin_cos(phi);
                let d = Vec3::new(st * cp, st * sp, ct);
                let cos_ds = d.dot(b).max(0.0);
                dirs.push(d);
                weights.push(cos_ds * cos_ds * st * (dtheta * std::f64::consts::TAU / n as f64) as f32);
            }
        }
        normalise(&mut weights);
        Sky { brightest: b, dirs, weights }
    }

    /// Global light (Plastic Trees section 6, "global light interaction"): the brightest sky
    /// point is the noon sun at the equinox, elevation 90° − |latitude| towards the equator
    /// (−y = south in the northern hemisphere, +y = north in the southern; +x east).
    /// `latitude_deg` in −90..=90.
    pub fn from_latitude(latitude_deg: f32) -> Sky {
        let lat = latitude_deg.clamp(-90.0, 90.0);
        let elev = crate::sun::noon_equinox_elevation_deg(lat).to_radians() as f64;
        let (se, ce) = exact_sin_cos(elev);
        Sky::toward(Vec3::new(0.0, crate::sun::equatorward(lat) * ce, se))
    }
}

/// The terrain surface as a plane through `point` with upward unit `normal`: points below it are
/// solid, rays going below it are blocked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// A point of the surface (m).
    pub point: Vec3,
    /// Upward unit normal.
    pub normal: Vec3,
}

impl Ground {
    /// Flat ground at height `z` (m).
    pub fn flat(z: f32) -> Ground {
        Ground { point: Vec3::new(0.0, 0.0, z), normal: Vec3::Z }
    }

    /// A slope of `slope_deg` (0–89°) through `point` falling towards azimuth `aspect_deg`
    /// (clockwise from north = +y: 90° = east = +x, 180° = south).
    pub fn slope(point: Vec3, slope_deg: f32, aspect_deg: f32) -> Ground {
        let s = slope_deg.clamp(0.0, 89.0).to_radians();
        let a = aspect_deg.to_radians();
        let downhill = Vec3::new(a.sin(), a.cos(), 0.0);
        Ground { point, normal: (Vec3::Z * s.cos() + downhill * s.sin()).normalize_or(Vec3::Z) }
    }

    /// Height of `p` above the surface along the normal (m; < 0 below).
    pub fn height_of(&self, p: Vec3) -> f32 {
        (p - self.point).dot(self.normal)
    }

    /// True when the ray from `p` in unit direction `d` is blocked by the terrain (it points
    /// below the surface, or starts below it).
    pub fn blocks(&self, p: Vec3, d: Vec3) -> bool {
        self.height_of(p) < 0.0 || d.dot(self.normal) <= 0.0
    }
}

/// A leaf cluster as a light occluder: a sphere of radius `r` (m) transmitting `gamma`
/// (eq. 4, γ_c = γ_c0^r_c, or eq. 13 after losses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Occluder {
    /// Centre (m).
    pub center: Vec3,
    /// Radius (m, > 0).
    pub radius: f32,
    /// Transmittance 0–1.
    pub gamma: f32,
}

/// Shadow volumes of a set of clusters, one grid per sky direction: the shadow volume of a
/// cluster for direction d is the half-cylinder of its radius behind it (opposite d). Each
/// direction's grid bins the clusters by their projection on the plane ⟂ d, so a receiver tests
/// only the casters whose shadow volume contains it. A direction's grid is built the first time
/// it is queried (directions blocked by solids at every receiver cost nothing). At most
/// [`SCAN_MAX`] clusters build no grids: every query tests them all, in the same order (the
/// same product).
#[derive(Debug)]
pub struct ShadowVolumes {
    occ: Vec<Occluder>,
    /// Owner of every occluder (e.g. its tree in a group), or empty when not tagged
    /// ([`ShadowVolumes::with_owners`]).
    owners: Vec<u32>,
    dirs: Vec<Vec3>,
    grids: Vec<std::sync::OnceLock<DirGrid>>,
    /// Every occluder in one run, scanned whole by every query, when there are at most
    /// [`SCAN_MAX`] of them (then no grid is built: for a few casters, building up to 32 grids
    /// costs more than the queries they save).
    flat: Option<Casters>,
    /// Region (min, max corners, m) holding the query points, when known
    /// ([`ShadowVolumes::within`]): the grids then hold only the casters that can shade a point
    /// of it; a query outside it uses `full`.
    region: Option<(Vec3, Vec3)>,
    /// Grids of every occluder, built only for queries outside `region`.
    full: Vec<std::sync::OnceLock<DirGrid>>,
    /// Grid cell size in mean cluster radii, at least ([`CELL_RADII`], or
    /// [`COARSE_CELL_RADII`] after [`ShadowVolumes::coarse`]).
    cell_radii: f32,
    /// Whether the grids keep every slot's occluder index ([`ShadowVolumes::tracked`]).
    track: bool,
    /// The grids of the set these volumes follow ([`ShadowVolumes::after`]), merged from.
    base: Option<Box<Base>>,
}

/// What [`ShadowVolumes::after`] keeps of the set before: its grids (those built), its
/// occluders, the new index of each of them (`u32::MAX`: gone or changed) and the indices of
/// the occluders that are new or changed (ascending).
#[derive(Debug)]
struct Base {
    grids: Vec<Option<DirGrid>>,
    occ: Vec<Occluder>,
    map: Vec<u32>,
    fresh: Vec<u32>,
}

impl Clone for ShadowVolumes {
    fn clone(&self) -> Self {
        let mut c = ShadowVolumes::from_dirs(self.dirs.clone(), self.occ.clone(), self.owners.clone());
        c.region = self.region;
        c.cell_radii = self.cell_radii;
        c.track = self.track;
        c
    }
}

#[derive(Debug, Clone)]
struct DirGrid {
    d: Vec3,
    u: Vec3,
    v: Vec3,
    lo: Vec2,
    cell: f32,
    nx: usize,
    ny: usize,
    /// First block of every cell (cells in row order), and the end of the last.
    start: Vec<u32>,
    /// Depth along `d` (m) of every cell's first caster, the largest of the cell (−∞ for a cell
    /// without casters): a query at or ahead of it hits none of the cell's casters (their
    /// `along` = w − p·d ≤ top − p·d ≤ 0, the subtraction being monotone) and reads no block.
    top: Vec<f32>,
    /// The casters of every cell in blocks of [`LANES`], each cell's casters in descending depth
    /// along `d` (ties in occluder order), so a query stops at the first block behind it and
    /// the product of eq. 4 is taken in the same order whatever the grid; runs padded with
    /// casters that never hit.
    blocks: Vec<Block>,
    /// Transmittance of every slot of `blocks` (read only for the hits).
    gamma: Vec<[f32; LANES]>,
    /// Owner of every slot of `blocks`; empty when the occluders are not tagged.
    owner: Vec<[u32; LANES]>,
    /// Index in the occluders of every slot of `blocks` (`u32::MAX` for padding), kept only for
    /// the volumes a later set is merged from ([`ShadowVolumes::tracked`]); else empty.
    idx: Vec<[u32; LANES]>,
    /// Extent (m) of the casters' discs on the plane ⟂ d when the geometry was chosen, their
    /// number and the sum of their radii (m): what [`DirGrid::merged`] needs to tell whether
    /// the geometry still suits the casters.
    ext: Vec2,
    n: u32,
    rsum: f32,
}

/// The projection of `region`'s box on the plane of (`u`, `v`) (corners lo, hi, m) and its
/// nearest depth along `d` (m): what [`DirGrid::new`] tests each caster against.
fn region_bounds(region: Option<(Vec3, Vec3)>, d: Vec3, u: Vec3, v: Vec3) -> Option<(Vec2, Vec2, f32)> {
    region.map(|(lo, hi)| {
        let corners = (0..8).map(|i| Vec3::new(if i & 1 == 0 { lo.x } else { hi.x }, if i & 2 == 0 { lo.y } else { hi.y }, if i & 4 == 0 { lo.z } else { hi.z }));
        let (mut plo, mut phi, mut near) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY), f32::INFINITY);
        for c in corners {
            let q = Vec2::new(c.dot(u), c.dot(v));
            (plo, phi, near) = (plo.min(q), phi.max(q), near.min(c.dot(d)));
        }
        (plo, phi, near)
    })
}

/// Whether a caster projected at `q` (m), of depth `z` (m) and radius `r` (m), can shade a
/// point of the region of `bounds` ([`region_bounds`]; every caster without a region), with
/// a slack of 1 mm, far above the rounding of the projections.
#[inline]
fn in_region(bounds: Option<(Vec2, Vec2, f32)>, q: Vec2, z: f32, r: f32) -> bool {
    let e = 1e-3;
    match bounds {
        Some((plo, phi, near)) => z > near - e && (q + r + e).cmpge(plo).all() && (q - r - e).cmple(phi).all(),
        None => true,
    }
}

/// [`LANES`] casters of a grid cell in the coordinates of its direction's grid: `u`, `v` on
/// the plane ⟂ d and `w` along d (m; centre · axis), and the squared radius (m²). One block
/// is two cache lines; a padding slot has `r2` −1 (never hit) and `w` −∞ (behind every
/// receiver).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Block {
    u: [f32; LANES],
    v: [f32; LANES],
    w: [f32; LANES],
    r2: [f32; LANES],
}

const PAD_BLOCK: Block = Block { u: [0.0; LANES], v: [0.0; LANES], w: [f32::NEG_INFINITY; LANES], r2: [-1.0; LANES] };

/// Casters copied inline as structure-of-arrays (centre x, y, z (m), squared radius (m²),
/// transmittance, owner) so a query reads contiguous runs and tests [`LANES`] casters at a
/// time; runs are padded to whole blocks of [`LANES`] with casters that never hit (squared
/// radius −1: `l2 − along² ≤ −1` is false; transmittance 1; owner `u32::MAX`). Used for the
/// few occluders scanned whole ([`SCAN_MAX`]); grids hold [`Block`]s.
#[derive(Debug, Clone, Default)]
struct Casters {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    r2: Vec<f32>,
    gamma: Vec<f32>,
    /// Owner of every caster slot; empty when the occluders are not tagged.
    owner: Vec<u32>,
}

/// Casters tested together by [`ShadowVolumes::transmittance`] (the hit test vectorises); every
/// cell's run of casters is padded to a multiple of it.
const LANES: usize = 8;


const MAX_CELLS_PER_AXIS: usize = 96;


impl DirGrid {
    /// The grid of `occ` for direction `d`; `owners` is empty or holds one owner per occluder.
    /// With `region` (the box `lo`–`hi`, m) only the casters that can shade a point of the box
    /// are kept (see [`ShadowVolumes::within`]), tested on the projections the grid is built
    /// from (one pass, no copy of the casters kept).
    /// Cells are at least `cell_radii` mean caster radii wide.
    /// With `track` every slot also keeps its occluder's index (`idx`, for [`DirGrid::merged`]).
    fn new(d: Vec3, occ: &[Occluder], owners: &[u32], region: Option<(Vec3, Vec3)>, cell_radii: f32, track: bool) -> DirGrid {
        let (u, v) = d.any_orthonormal_pair();
        // every caster's projection on the plane ⟂ d and depth along d, then the ones kept
        let (mut proj, mut depth, mut kept): (Vec<Vec2>, Vec<f32>, Vec<u32>) = (Vec::with_capacity(occ.len()), Vec::with_capacity(occ.len()), Vec::with_capacity(occ.len()));
        let bounds = region_bounds(region, d, u, v);
        for (j, o) in occ.iter().enumerate() {
            let q = Vec2::new(o.center.dot(u), o.center.dot(v));
            let z = o.center.dot(d);
            if !in_region(bounds, q, z, o.radius) {
                continue;
            }
            proj.push(q);
            depth.push(z);
            kept.push(j as u32);
        }
        if kept.is_empty() {
            return DirGrid { d, u, v, lo: Vec2::ZERO, cell: 1.0, nx: 0, ny: 0, start: vec![0], top: Vec::new(), blocks: Vec::new(), gamma: Vec::new(), owner: Vec::new(), idx: Vec::new(), ext: Vec2::ZERO, n: 0, rsum: 0.0 };
        }
        let radius: Vec<f32> = kept.iter().map(|&j| occ[j as usize].radius).collect();
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        let mut rsum = 0.0;
        for (p, &r) in proj.iter().zip(&radius) {
            lo = lo.min(*p - r);
            hi = hi.max(*p + r);
            rsum += r;
        }
        let ext = (hi - lo).max(Vec2::splat(1e-3));
        let mean_r = rsum / kept.len() as f32;
        // about CELLS_PER_CASTER cells per cluster: the grid's size follows the cluster count
        let by_count = (ext.x * ext.y / (grid_knobs().1 * kept.len() as f32)).sqrt();
        let cell = (cell_radii * mean_r).max(by_count).max(ext.x / MAX_CELLS_PER_AXIS as f32).max(ext.y / MAX_CELLS_PER_AXIS as f32).max(1e-3);
        let nx = ((ext.x / cell).ceil() as usize).clamp(1, MAX_CELLS_PER_AXIS);
        let ny = ((ext.y / cell).ceil() as usize).clamp(1, MAX_CELLS_PER_AXIS);
        // cell range of each caster's disc; `as u32` truncates, which equals the floor for the
        // non-negative values kept by `max(0.0)` (and avoids a libm call per bound), clamped to
        // the last cell before the conversion (the floor of a value above it is above it too)
        let cx = |x: f32, n: usize| x.max(0.0).min((n - 1) as f32) as u32;
        let ranges: Vec<[u32; 4]> = proj
            .iter()
            .zip(&radius)
            .map(|(p, &r)| {
                let a = (*p - r - lo) / cell;
                let b = (*p + r - lo) / cell;
                [cx(a.x, nx), cx(b.x, nx), cx(a.y, ny), cx(b.y, ny)]
            })
            .collect();
        // the cell loops take half-open ranges and whole row slices: an inclusive range's
        // iteration and an index check per cell cost more than the work (measured, callgrind:
        // the grid builds of a wall move)
        let mut count = vec![0u32; nx * ny + 1];
        for &[x0, x1, y0, y1] in &ranges {
            let (x0, x1) = (x0 as usize, x1 as usize + 1);
            for y in y0 as usize..y1 as usize + 1 {
                let row = 1 + y * nx;
                for c in &mut count[row + x0..row + x1] {
                    *c += 1;
                }
            }
        }
        // slot offsets: every cell's run padded to whole blocks
        let mut run = 0u32;
        for c in &mut count {
            run += c.div_ceil(LANES as u32) * LANES as u32;
            *c = run;
        }
        let mut fill = count.clone();
        let len = count[nx * ny] as usize / LANES;
        let mut blocks = vec![PAD_BLOCK; len];
        let mut gamma = vec![[1.0f32; LANES]; len];
        let tagged = owners.len() == occ.len();
        let mut owner = if tagged { vec![[u32::MAX; LANES]; len] } else { Vec::new() };
        let mut idx = if track { vec![[u32::MAX; LANES]; len] } else { Vec::new() };
        // each cell's casters in descending depth along d (farthest ahead of any receiver first;
        // ties in occluder order), so a query can stop at the first block that lies behind it
        for j in depth_order(&depth) {
            let j = j as usize;
            let ([x0, x1, y0, y1], o) = (ranges[j], &occ[kept[j] as usize]);
            let r2 = o.radius * o.radius;
            let (pu, pv, pw, g) = (proj[j].x, proj[j].y, depth[j], o.gamma);
            let own = if tagged { owners[kept[j] as usize] } else { u32::MAX };
            let (x0, x1) = (x0 as usize, x1 as usize + 1);
            for y in y0 as usize..y1 as usize + 1 {
                let row = y * nx;
                for f in &mut fill[row + x0..row + x1] {
                    let (bi, l) = (*f as usize / LANES, *f as usize % LANES);
                    let b = &mut blocks[bi];
                    (b.u[l], b.v[l], b.w[l], b.r2[l]) = (pu, pv, pw, r2);
                    gamma[bi][l] = g;
                    if tagged {
                        owner[bi][l] = own;
                    }
                    if track {
                        idx[bi][l] = kept[j];
                    }
                    *f += 1;
                }
            }
        }
        for c in &mut count {
            *c /= LANES as u32;
        }
        let top = count.windows(2).map(|r| if r[0] < r[1] { blocks[r[0] as usize].w[0] } else { f32::NEG_INFINITY }).collect();
        DirGrid { d, u, v, lo, cell, nx, ny, start: count, top, blocks, gamma, owner, idx, ext, n: kept.len() as u32, rsum }
    }

    /// The grid that [`DirGrid::new`] (with `track`) would give of `occ` for the same
    /// direction, region and cell size, made from `old`, the grid of `old_occ` built with
    /// `track`, where `map[j]` is the index in `occ` of `old_occ[j]` when it is the same
    /// occluder bit for bit (`u32::MAX` where it is gone or changed; the indices kept must
    /// rise with j) and `fresh` lists, ascending, the indices of `occ` that no `map` entry names.
    /// Issue 32 (round 46): from level to level of an adaptation two thirds of the casters,
    /// and 76–97 % in the large late levels, are the same bit for bit (BENCHMARKS.md, round 45
    /// (r45f)); they are copied cell by cell instead of projected, sorted and binned again.
    ///
    /// Each cell's run is the old run without the casters gone, merged with the fresh casters
    /// covering the cell, in descending depth along d with ties by the new index, the order of
    /// [`depth_order`]: unchanged casters keep their depth bits and their relative order (the
    /// map rises), so every cell holds the casters of a fresh build in a fresh build's order
    /// and every product of eq. (4) (Pirk et al. 2012) is the same bit for bit. The geometry
    /// (`lo`, `cell`, `nx`, `ny`) is the old one, which changes no answer, only the cost (the
    /// `SYLVA_GRID_*` hooks, round 43). `None` (build afresh) where a fresh caster's disc
    /// leaves the old grid, where the cell a fresh build would choose differs from the old by
    /// more than a quarter (the queries would scan too many or too few casters per cell), or
    /// where `old` is empty, untracked or tagged with owners.
    fn merged(old: &DirGrid, occ: &[Occluder], old_occ: &[Occluder], map: &[u32], fresh: &[u32], region: Option<(Vec3, Vec3)>, cell_radii: f32) -> Option<DirGrid> {
        if old.nx == 0 || !old.owner.is_empty() || old.idx.len() != old.blocks.len() || map.len() != old_occ.len() {
            return None;
        }
        let (d, u, v, lo, cell, nx, ny) = (old.d, old.u, old.v, old.lo, old.cell, old.nx, old.ny);
        let bounds = region_bounds(region, d, u, v);
        // the casters gone from the grid: their number and radii
        let (mut gone_n, mut gone_r) = (0u32, 0.0f32);
        for (o, _) in old_occ.iter().zip(map).filter(|(_, &m)| m == u32::MAX) {
            if in_region(bounds, Vec2::new(o.center.dot(u), o.center.dot(v)), o.center.dot(d), o.radius) {
                gone_n += 1;
                gone_r += o.radius;
            }
        }
        // the fresh casters kept, each inside the old grid
        let (mut proj, mut depth, mut kept, mut fresh_r) = (Vec::with_capacity(fresh.len()), Vec::with_capacity(fresh.len()), Vec::with_capacity(fresh.len()), 0.0f32);
        let (fx, fy) = (nx as f32, ny as f32);
        for &j in fresh {
            let o = &occ[j as usize];
            let q = Vec2::new(o.center.dot(u), o.center.dot(v));
            let z = o.center.dot(d);
            if !in_region(bounds, q, z, o.radius) {
                continue;
            }
            let (a, b) = ((q - o.radius - lo) / cell, (q + o.radius - lo) / cell);
            if !(a.x >= 0.0 && a.y >= 0.0 && b.x < fx && b.y < fy) {
                return None;
            }
            proj.push(q);
            depth.push(z);
            kept.push(j);
            fresh_r += o.radius;
        }
        let n = (old.n + kept.len() as u32).checked_sub(gone_n).filter(|&n| n > 0)?;
        let rsum = (old.rsum - gone_r + fresh_r).max(0.0);
        let ext = old.ext;
        let want = (cell_radii * rsum / n as f32).max((ext.x * ext.y / (grid_knobs().1 * n as f32)).sqrt()).max(ext.x / MAX_CELLS_PER_AXIS as f32).max(ext.y / MAX_CELLS_PER_AXIS as f32).max(1e-3);
        if !(want <= 1.25 * cell && 1.25 * want >= cell) {
            return None;
        }
        let cx = |x: f32, n: usize| x.max(0.0).min((n - 1) as f32) as u32;
        let ranges: Vec<[u32; 4]> = proj
            .iter()
            .zip(&kept)
            .map(|(p, &j)| {
                let r = occ[j as usize].radius;
                let a = (*p - r - lo) / cell;
                let b = (*p + r - lo) / cell;
                [cx(a.x, nx), cx(b.x, nx), cx(a.y, ny), cx(b.y, ny)]
            })
            .collect();
        // the fresh casters of every cell, in depth order (ties by index: `kept` rises)
        let cells = nx * ny;
        let mut fstart = vec![0u32; cells + 1];
        for &[x0, x1, y0, y1] in &ranges {
            for y in y0 as usize..y1 as usize + 1 {
                let row = 1 + y * nx;
                for c in &mut fstart[row + x0 as usize..row + x1 as usize + 1] {
                    *c += 1;
                }
            }
        }
        for c in 1..=cells {
            fstart[c] += fstart[c - 1];
        }
        let mut ffill = fstart.clone();
        let mut flist = vec![0u32; fstart[cells] as usize];
        for j in depth_order(&depth) {
            let [x0, x1, y0, y1] = ranges[j as usize];
            for y in y0 as usize..y1 as usize + 1 {
                let row = y * nx;
                for f in &mut ffill[row + x0 as usize..row + x1 as usize + 1] {
                    flist[*f as usize] = j;
                    *f += 1;
                }
            }
        }
        // every cell's run: the old casters kept and the fresh ones, padded to whole blocks
        let slot = |s: usize| (s / LANES, s % LANES);
        let mut start = vec![0u32; cells + 1];
        for c in 0..cells {
            let mut k = fstart[c + 1] - fstart[c];
            for s in old.start[c] as usize * LANES..old.start[c + 1] as usize * LANES {
                let (bi, l) = slot(s);
                let i = old.idx[bi][l];
                k += u32::from(i != u32::MAX && map[i as usize] != u32::MAX);
            }
            start[c + 1] = start[c] + k.div_ceil(LANES as u32);
        }
        let len = start[cells] as usize;
        let mut blocks = vec![PAD_BLOCK; len];
        let mut gamma = vec![[1.0f32; LANES]; len];
        let mut idx = vec![[u32::MAX; LANES]; len];
        for c in 0..cells {
            let mut at = start[c] as usize * LANES;
            let mut put = |pu: f32, pv: f32, pw: f32, r2: f32, g: f32, i: u32| {
                let (bi, l) = slot(at);
                let b = &mut blocks[bi];
                (b.u[l], b.v[l], b.w[l], b.r2[l]) = (pu, pv, pw, r2);
                gamma[bi][l] = g;
                idx[bi][l] = i;
                at += 1;
            };
            let (mut s, s_end) = (old.start[c] as usize * LANES, old.start[c + 1] as usize * LANES);
            let mut f = fstart[c] as usize;
            loop {
                // the next old caster kept, with its new index
                while s < s_end {
                    let (bi, l) = slot(s);
                    let i = old.idx[bi][l];
                    if i != u32::MAX && map[i as usize] != u32::MAX {
                        break;
                    }
                    s += 1;
                }
                let fresh_next = flist[f..fstart[c + 1] as usize].first().map(|&j| (depth[j as usize], kept[j as usize], j as usize));
                let old_next = (s < s_end).then(|| {
                    let (bi, l) = slot(s);
                    (old.blocks[bi].w[l], map[old.idx[bi][l] as usize], bi, l)
                });
                match (old_next, fresh_next) {
                    (None, None) => break,
                    (Some((w, i, bi, l)), fr) if fr.map_or(true, |(fw, fi, _)| w.total_cmp(&fw).then(fi.cmp(&i)).is_gt()) => {
                        let b = &old.blocks[bi];
                        put(b.u[l], b.v[l], w, b.r2[l], old.gamma[bi][l], i);
                        s += 1;
                    }
                    (_, Some((fw, fi, j))) => {
                        let o = &occ[fi as usize];
                        put(proj[j].x, proj[j].y, fw, o.radius * o.radius, o.gamma, fi);
                        f += 1;
                    }
                    (Some(_), None) => unreachable!("taken by the arm above"),
                }
            }
        }
        let top = start.windows(2).map(|r| if r[0] < r[1] { blocks[r[0] as usize].w[0] } else { f32::NEG_INFINITY }).collect();
        Some(DirGrid { d, u, v, lo, cell, nx, ny, start, top, blocks, gamma, owner: Vec::new(), idx, ext, n, rsum })
    }

    /// Π γ of the casters hit by the ray from `p` along the grid's direction (the ray passes
    /// through a caster's sphere ahead of `p`, and `p` is outside it: in the grid's coordinates,
    /// along = w − p·d > 0, lateral² = Δu² + Δv² ≤ r², lateral² + along² > r²), multiplied in
    /// the cell's depth order, leaving out `skip`'s casters; `None` as soon as the product falls
    /// below `stop`. Scans the blocks of the cell of `p` and stops after the first block whose
    /// last caster lies more than [`DEPTH_SLACK`] behind `p` (every later caster is further
    /// behind; none can be hit).
    #[inline]
    fn product(&self, p: Vec3, stop: f32, skip: Option<u32>) -> Option<f32> {
        if self.nx == 0 {
            return Some(1.0);
        }
        let (pu, pv) = (p.dot(self.u), p.dot(self.v));
        let q = (Vec2::new(pu, pv) - self.lo) / self.cell;
        if q.x < 0.0 || q.y < 0.0 {
            return Some(1.0);
        }
        // through i32 (q ≥ 0 here): the same cell as the conversion to usize, whose saturating
        // form for f32 takes about twice the instructions on x86-64 (callgrind: 2.3 % of the
        // stand bench's instructions were this line; BENCHMARKS.md round 44). A q at or above
        // 2³¹ saturates to i32::MAX, NaN gives 0, as to usize: the cell tests below agree
        let (x, y) = (q.x as i32 as usize, q.y as i32 as usize);
        if x >= self.nx || y >= self.ny {
            return Some(1.0);
        }
        let c = y * self.nx + x;
        let pw = p.dot(self.d);
        // no caster of the cell lies ahead of p:
        // the product is 1, as the scan would find, without reading a block (the blocks are
        // most of a query's memory traffic; round 43)
        if !(self.top[c] - pw > 0.0) {
            return Some(1.0);
        }
        let at = (Vec4::splat(pu), Vec4::splat(pv), Vec4::splat(pw));
        let mut t = 1.0f32;
        for bi in self.start[c] as usize..self.start[c + 1] as usize {
            let b = &self.blocks[bi];
            // per half block a lane mask of the casters hit
            let (mut lo, mut hi) = (b.hits(0, at), b.hits(4, at));
            if let Some(own) = skip {
                let (olo, ohi) = others(&self.owner[bi], own);
                (lo, hi) = (lo & olo, hi & ohi);
            }
            if (lo | hi).any() {
                t = hit_product(t, &self.gamma[bi], lo, hi);
                if t < stop {
                    return None;
                }
            }
            if b.w[LANES - 1] - pw < -DEPTH_SLACK {
                break;
            }
        }
        Some(t)
    }
}

/// Indices of `depth` in descending depth, ties in index order: the order of
/// [`DirGrid::new`]'s cells. Each depth's bits are mapped to an unsigned order (`f32::total_cmp`'s)
/// and inverted, so ascending keys are descending depths; a few casters are sorted as
/// (key, index) pairs, more by a stable radix sort of the indices on the key, four passes of a
/// byte (a pass whose byte all keys share, such as the sign and exponent of depths of one
/// binade, is skipped), which gives the same order (the indices start in ascending order).
/// The comparison sort was about a fifth of the grid builds of the near field of
/// `benches/stand.rs` (perf, round 43).
fn depth_order(depth: &[f32]) -> Vec<u32> {
    let key = |z: f32| {
        let b = z.to_bits() as i32;
        !((b ^ ((((b >> 31) as u32) >> 1) as i32)) as u32 ^ 0x8000_0000)
    };
    let n = depth.len();
    if n < RADIX_MIN {
        let mut order: Vec<u64> = depth.iter().enumerate().map(|(j, &z)| ((key(z) as u64) << 32) | j as u64).collect();
        order.sort_unstable();
        return order.into_iter().map(|k| k as u32).collect();
    }
    let keys: Vec<u32> = depth.iter().map(|&z| key(z)).collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut spare = vec![0u32; n];
    for shift in [0u32, 8, 16, 24] {
        let mut count = [0u32; 256];
        for &k in &keys {
            count[(k >> shift & 0xff) as usize] += 1;
        }
        if count[(keys[0] >> shift & 0xff) as usize] as usize == n {
            continue; // every key has this byte: the order stands
        }
        let mut run = 0u32;
        for c in count.iter_mut() {
            (*c, run) = (run, run + *c);
        }
        for &j in &order {
            let d = (keys[j as usize] >> shift & 0xff) as usize;
            spare[count[d] as usize] = j;
            count[d] += 1;
        }
        std::mem::swap(&mut order, &mut spare);
    }
    order
}

/// Fewest casters [`depth_order`] sorts by radix: below, a comparison sort of the pairs costs
/// less than four passes over 256 counters. An ESTIMATE, not tuned.
const RADIX_MIN: usize = 256;

/// Distance (m) behind a query point beyond which a depth-sorted scan stops: far above the
/// rounding of the along-ray distances (metres at f32), so no caster ahead is ever skipped.
const DEPTH_SLACK: f32 = 1e-3;

impl Block {
    /// Lane mask of the casters `o..o + 4` of the block hit by the ray from the point at
    /// `(u, v, w)` (each splat over the lanes; the grid's coordinates, m) along the grid's
    /// direction: along = w_c − w > 0, lateral² = Δu² + Δv² ≤ r², lateral² + along² > r², the
    /// operations of [`DirGrid::product`]'s test in the same order (the same bits).
    #[inline(always)]
    fn hits(&self, o: usize, (u, v, w): (Vec4, Vec4, Vec4)) -> BVec4A {
        let du = Vec4::from_slice(&self.u[o..o + 4]) - u;
        let dv = Vec4::from_slice(&self.v[o..o + 4]) - v;
        let along = Vec4::from_slice(&self.w[o..o + 4]) - w;
        let r2 = Vec4::from_slice(&self.r2[o..o + 4]);
        let lat2 = du * du + dv * dv;
        along.cmpgt(Vec4::ZERO) & lat2.cmple(r2) & (lat2 + along * along).cmpgt(r2)
    }
}

/// Lane masks (slots 0–3, 4–7) of a block's casters whose owner is not `own`: the casters a
/// query that leaves out `own`'s tree may hit.
#[inline]
fn others(os: &[u32; LANES], own: u32) -> (BVec4A, BVec4A) {
    let m = |k: usize| BVec4A::new(os[k] != own, os[k + 1] != own, os[k + 2] != own, os[k + 3] != own);
    (m(0), m(4))
}

/// `t` multiplied by the transmittance `gamma` of every slot of a block whose lane is set in
/// `lo` (slots 0–3) or `hi` (slots 4–7), in slot order: a slot missed multiplies by exactly 1,
/// so the product is the hits' product in slot order, bit for bit. The factors are chosen by
/// vector selects (γ where hit, 1 elsewhere); a select per slot written on scalars was compiled
/// into a conditional branch per slot, which mispredicts on the hit pattern (perf annotate of
/// the round-40 stand bench: those branches held 17 % of the query's samples; BENCHMARKS.md,
/// round 41).
#[inline(always)]
fn hit_product(t: f32, gamma: &[f32; LANES], lo: BVec4A, hi: BVec4A) -> f32 {
    let a = Vec4::select(lo, Vec4::from_slice(&gamma[..4]), Vec4::ONE);
    let b = Vec4::select(hi, Vec4::from_slice(&gamma[4..]), Vec4::ONE);
    t * a.x * a.y * a.z * a.w * b.x * b.y * b.z * b.w
}

impl Casters {
    /// Every occluder of `occ` in order, tagged with `owners` when it holds one per occluder,
    /// padded to a whole block.
    fn flat(occ: &[Occluder], owners: &[u32]) -> Casters {
        let len = occ.len().div_ceil(LANES) * LANES;
        let mut c = Casters { x: vec![0.0; len], y: vec![0.0; len], z: vec![0.0; len], r2: vec![-1.0; len], gamma: vec![1.0; len], owner: Vec::new() };
        for (f, o) in occ.iter().enumerate() {
            (c.x[f], c.y[f], c.z[f], c.r2[f], c.gamma[f]) = (o.center.x, o.center.y, o.center.z, o.radius * o.radius, o.gamma);
        }
        if owners.len() == occ.len() {
            c.owner = vec![u32::MAX; len];
            c.owner[..owners.len()].copy_from_slice(owners);
        }
        c
    }

    /// Multiplies `t` by the transmittance of every caster of the block of [`LANES`] casters
    /// from `i` that the ray from p along d (given per component, each splat over the lanes:
    /// `d` = (d.x, d.y, d.z), `p` likewise) hits (the ray passes through the caster's sphere
    /// ahead of `p`, and `p` is outside it), in caster order, leaving out the casters owned by
    /// `skip` (when given; the casters are then tagged), and returns it: the arithmetic of
    /// glam's `Vec3::dot`/`length_squared` written per component, four lanes at a time ([`Vec4`]), in
    /// the same order (the same bits), and the factors chosen as in [`hit_product`].
    #[inline]
    fn block(&self, (dx, dy, dz): (Vec4, Vec4, Vec4), i: usize, (px, py, pz): (Vec4, Vec4, Vec4), t: f32, skip: Option<u32>) -> f32 {
        let (Ok(xs), Ok(ys), Ok(zs), Ok(rs), Ok(gs)) = (
            <&[f32; LANES]>::try_from(&self.x[i..i + LANES]),
            <&[f32; LANES]>::try_from(&self.y[i..i + LANES]),
            <&[f32; LANES]>::try_from(&self.z[i..i + LANES]),
            <&[f32; LANES]>::try_from(&self.r2[i..i + LANES]),
            <&[f32; LANES]>::try_from(&self.gamma[i..i + LANES]),
        ) else {
            return t; // unreachable: runs are padded to whole blocks
        };
        let hits = |o: usize| {
            let (ox, oy, oz) = (Vec4::from_slice(&xs[o..o + 4]) - px, Vec4::from_slice(&ys[o..o + 4]) - py, Vec4::from_slice(&zs[o..o + 4]) - pz);
            let along = ox * dx + oy * dy + oz * dz;
            let l2 = ox * ox + oy * oy + oz * oz;
            let r2 = Vec4::from_slice(&rs[o..o + 4]);
            along.cmpgt(Vec4::ZERO) & l2.cmpgt(r2) & (l2 - along * along).cmple(r2)
        };
        let (mut lo, mut hi) = (hits(0), hits(4));
        if let Some(own) = skip {
            let Ok(os) = <&[u32; LANES]>::try_from(&self.owner[i..i + LANES]) else {
                return t; // unreachable: tagged casters have an owner per slot
            };
            let (olo, ohi) = others(os, own);
            (lo, hi) = (lo & olo, hi & ohi);
        }
        // most blocks hit nothing: one test of the whole block, then the hits in order
        if (lo | hi).any() {
            hit_product(t, gs, lo, hi)
        } else {
            t
        }
    }

    /// Π γ of the casters of the slots `r` (whole blocks) hit by the ray from `p` along `d`,
    /// multiplied in slot order, leaving out `skip`'s casters; `None` as soon as the product
    /// falls below `stop` (the product never rises again, so stopping after the block that
    /// crosses `stop` gives the same answer as stopping at the caster that crosses it).
    #[inline]
    fn product_until(&self, d: Vec3, r: std::ops::Range<usize>, p: Vec3, stop: f32, skip: Option<u32>) -> Option<f32> {
        let mut t = 1.0f32;
        let mut i = r.start;
        let (dv, pv) = ((Vec4::splat(d.x), Vec4::splat(d.y), Vec4::splat(d.z)), (Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)));
        while i < r.end {
            t = self.block(dv, i, pv, t, skip);
            if t < stop {
                return None;
            }
            i += LANES;
        }
        Some(t)
    }
}

/// Most occluders that [`ShadowVolumes`] scans whole instead of building its direction grids
/// (measured on the stand bench, `benches/stand.rs`, 100 targets, callgrind: 64 saves 11 % of
/// the instructions against always building grids; 256 costs 49 % more).
const SCAN_MAX: usize = 64;

/// Grid cell size, in mean cluster radii, at least.
const CELL_RADII: f32 = 2.0;
/// Grid cell size, in mean cluster radii, at least, of [`ShadowVolumes::coarse`] volumes: twice
/// [`CELL_RADII`], so fewer cells and slots to build, and a query scans a little more
/// (measured, callgrind, one thread, the 9,133-node bench tree, round 34: a 10 cm wall move
/// −3.0 % instructions with 3 radii, −3.9 % with 4; 3 radii in every call cost the analysis and
/// first adaptation +2.2 %, as their grids answer many more queries each, so only calls that
/// recompute part of their trees take them).
const COARSE_CELL_RADII: f32 = 4.0;
/// Grid cells per cluster over the grid's area, at most (the cell is at least that coarse).
const CELLS_PER_CASTER: f32 = 2.0;

/// Measurement hooks of the grids' geometry (round 43), read once from the environment:
/// `SYLVA_GRID_CELL_RADII` and `SYLVA_GRID_CELLS_PER_CASTER` override [`CELL_RADII`] and
/// [`CELLS_PER_CASTER`]. The geometry changes no answer (a query tests every caster whose disc
/// covers its cell, in the same depth order), only what a grid costs to build and to query.
fn grid_knobs() -> (f32, f32) {
    static K: std::sync::OnceLock<(f32, f32)> = std::sync::OnceLock::new();
    *K.get_or_init(|| {
        let var = |name: &str, default: f32| std::env::var(name).ok().and_then(|v| v.trim().parse::<f32>().ok()).filter(|v| *v > 0.0 && v.is_finite()).unwrap_or(default);
        (var("SYLVA_GRID_CELL_RADII", CELL_RADII), var("SYLVA_GRID_CELLS_PER_CASTER", CELLS_PER_CASTER))
    })
}

impl ShadowVolumes {
    /// Shadow volumes of `occ` for every direction of `sky`.
    pub fn new(sky: &Sky, occ: Vec<Occluder>) -> ShadowVolumes {
        ShadowVolumes::from_dirs(sky.dirs.clone(), occ, Vec::new())
    }

    /// Shadow volumes of `occ` for every direction of `sky`, each occluder tagged with an owner
    /// (`owners[i]` owns `occ[i]`, e.g. the tree of a group it belongs to), so that
    /// [`ShadowVolumes::shaded_except`] can leave one owner's occluders out: one set of grids
    /// serves every member of a group instead of one set per member built from the others'
    /// occluders. Owners beyond `occ` are ignored; missing ones are `u32::MAX`.
    pub fn with_owners(sky: &Sky, occ: Vec<Occluder>, mut owners: Vec<u32>) -> ShadowVolumes {
        owners.resize(occ.len(), u32::MAX);
        ShadowVolumes::from_dirs(sky.dirs.clone(), occ, owners)
    }

    fn from_dirs(dirs: Vec<Vec3>, occ: Vec<Occluder>, owners: Vec<u32>) -> ShadowVolumes {
        let grids = dirs.iter().map(|_| std::sync::OnceLock::new()).collect();
        let flat = (occ.len() <= SCAN_MAX).then(|| Casters::flat(&occ, &owners));
        let full = dirs.iter().map(|_| std::sync::OnceLock::new()).collect();
        ShadowVolumes { occ, owners, dirs, grids, flat, region: None, full, cell_radii: grid_knobs().0, track: false, base: None }
    }

    /// The same shadow volumes, whose grids keep the index of every slot's occluder, so that a
    /// later set can be merged from them ([`ShadowVolumes::after`]); the answers are the same.
    pub(crate) fn tracked(mut self) -> ShadowVolumes {
        self.track = true;
        self
    }

    /// The same shadow volumes (built [`ShadowVolumes::tracked`]), told that they follow
    /// `prev`, a tracked set of the same directions, region and cell size whose occluder `j`
    /// is this set's occluder `map[j]` bit for bit (`u32::MAX`: gone or changed; the indices
    /// kept rise with j): each direction's grid that `prev` built is then merged from it
    /// ([`DirGrid::merged`]: the unchanged casters copied cell by cell, the others projected
    /// and sorted) instead of built afresh, with the same answers bit for bit (issue 32, round
    /// 46: the levels of an adaptation). `prev` is left as it is where it does not qualify.
    pub(crate) fn after(mut self, prev: ShadowVolumes, map: Vec<u32>) -> ShadowVolumes {
        let same = prev.track && self.track && prev.flat.is_none() && self.flat.is_none() && prev.owners.is_empty() && self.owners.is_empty() && prev.region == self.region && prev.cell_radii == self.cell_radii && prev.dirs == self.dirs && map.len() == prev.occ.len();
        if !same {
            return self;
        }
        let mut named = vec![false; self.occ.len()];
        let mut last = None;
        for &m in map.iter().filter(|&&m| m != u32::MAX) {
            // the kept indices must rise (their order is the fresh build's tie order)
            if m as usize >= named.len() || last.is_some_and(|l| l >= m) {
                return self;
            }
            named[m as usize] = true;
            last = Some(m);
        }
        let fresh = (0..self.occ.len() as u32).filter(|&j| !named[j as usize]).collect();
        let grids = prev.grids.into_iter().map(|g| g.into_inner()).collect();
        self.base = Some(Box::new(Base { grids, occ: prev.occ, map, fresh }));
        self
    }

    /// The same shadow volumes, told that queries come from inside the box `lo`–`hi` (m): each
    /// direction's grid then holds only the casters that can shade a point of the box (a
    /// caster's disc on the plane ⟂ d overlaps the box's projection, and its centre lies ahead
    /// of the box's nearest corner along d), so a few receivers among many casters (a stand
    /// where a wall moved near some trees) do not build grids of every caster. The answers are
    /// the same bit for bit: the casters left out are never hit, and those kept keep their
    /// order. A query outside the box is answered from grids of every caster.
    pub fn within(mut self, lo: Vec3, hi: Vec3) -> ShadowVolumes {
        if lo.cmple(hi).all() && lo.is_finite() && hi.is_finite() {
            self.region = Some((lo, hi));
        }
        self
    }

    /// The same shadow volumes with coarser grid cells ([`COARSE_CELL_RADII`] mean caster radii
    /// at least, against [`CELL_RADII`]): cheaper to build, a little dearer to query, for
    /// volumes asked few queries per direction (a call that recomputes part of a tree). The
    /// answers are the same bit for bit: a query still tests every caster whose disc covers
    /// its cell, in the same depth order.
    pub fn coarse(mut self) -> ShadowVolumes {
        self.cell_radii = COARSE_CELL_RADII;
        self
    }

    /// The occluders.
    pub fn occluders(&self) -> &[Occluder] {
        &self.occ
    }

    /// Builds, over the cores, the grids of the directions whose bit is set in `dirs` (bit k:
    /// direction k) that are not built yet, so that the queries that follow do not wait for one
    /// another's lazy builds (a query waits while another thread builds the grid it needs).
    /// Nothing to do when the occluders are scanned whole ([`SCAN_MAX`]). The grids are the
    /// ones a lazy build gives, so the answers do not change.
    pub fn prepare(&self, dirs: u32) {
        use rayon::prelude::*;
        if self.flat.is_some() {
            return;
        }
        // the directions to build, found first: with none (a level's later batches) the cores
        // are not woken for nothing
        let todo: Vec<usize> = (0..self.dirs.len()).filter(|&k| dirs & (1 << k) != 0 && self.grids[k].get().is_none()).collect();
        match todo[..] {
            [] => {}
            [k] => {
                self.grid(k);
            }
            _ => todo.into_par_iter().for_each(|k| {
                self.grid(k);
            }),
        }
    }

    fn grid(&self, k: usize) -> &DirGrid {
        self.grids[k].get_or_init(|| {
            if let Some(Some(old)) = self.base.as_ref().map(|b| (b, b.grids.get(k))).and_then(|(b, g)| g.and_then(Option::as_ref).map(|g| DirGrid::merged(g, &self.occ, &b.occ, &b.map, &b.fresh, self.region, self.cell_radii))) {
                return old;
            }
            DirGrid::new(self.dirs[k], &self.occ, &self.owners, self.region, self.cell_radii, self.track)
        })
    }

    /// The grid of direction `k` for a query at `p`: the region's, or every caster's when `p`
    /// lies outside the region.
    fn grid_for(&self, k: usize, p: Vec3) -> &DirGrid {
        match self.region {
            Some((lo, hi)) if !(p.cmpge(lo).all() && p.cmple(hi).all()) => self.full[k].get_or_init(|| DirGrid::new(self.dirs[k], &self.occ, &self.owners, None, self.cell_radii, false)),
            _ => self.grid(k),
        }
    }

    /// [`ShadowVolumes::shaded`] counting only the occluders not owned by `owner`: the answer
    /// that shadow volumes of those occluders alone would give (the same casters hit, in the
    /// same order). Without owner tags ([`ShadowVolumes::new`]) every occluder counts.
    pub fn shaded_except(&self, k: usize, p: Vec3, owner: u32) -> bool {
        let skip = (!self.owners.is_empty()).then_some(owner);
        self.product_until_except(k, p, 1.0, skip).is_none()
    }

    /// True when [`ShadowVolumes::transmittance`] of the same ray is below 1, found at the first
    /// cluster that brings the product below 1 (the product never rises again).
    pub fn shaded(&self, k: usize, p: Vec3) -> bool {
        self.product_until(k, p, 1.0).is_none()
    }

    /// Transmittance Π γ of the clusters on the ray from `p` along sky direction `k`; clusters
    /// containing `p` do not shade it. A product below 10⁻⁴ is returned as 0 (the ray is dark).
    pub fn transmittance(&self, k: usize, p: Vec3) -> f32 {
        self.product_until(k, p, 1e-4).unwrap_or(0.0)
    }

    /// Π γ of the clusters hit by the ray from `p` along direction `k`, multiplied in caster
    /// order; `None` as soon as the product falls below `stop`.
    fn product_until(&self, k: usize, p: Vec3, stop: f32) -> Option<f32> {
        self.product_until_except(k, p, stop, None)
    }

    /// [`ShadowVolumes::product_until`] leaving out the occluders owned by `skip`: the whole
    /// run of occluders when they are few ([`SCAN_MAX`]), else the casters of the grid cell of
    /// `p` (the same casters hit, in the same order).
    fn product_until_except(&self, k: usize, p: Vec3, stop: f32, skip: Option<u32>) -> Option<f32> {
        match &self.flat {
            Some(c) => c.product_until(self.dirs[k], 0..c.x.len(), p, stop, skip),
            None => self.grid_for(k, p).product(p, stop, skip),
        }
    }
}

/// Solid things of eq. (3) (transmittance 0): obstacles and the terrain surface.
#[derive(Debug, Clone, Copy)]
pub struct Solids<'a> {
    /// Obstacles.
    pub obstacles: &'a [Obstacle],
    /// Terrain surface, if any.
    pub ground: Option<Ground>,
}

impl Solids<'_> {
    /// Bit k set when sky direction k is blocked at `p` by an obstacle or the terrain.
    pub fn mask(&self, sky: &Sky, p: Vec3) -> u32 {
        let mut m = 0u32;
        for (k, &d) in sky.dirs.iter().enumerate() {
            if self.ground.is_some_and(|g| g.blocks(p, d)) || self.obstacles.iter().any(|o| o.ray_hits(p, d, f32::INFINITY)) {
                m |= 1 << k;
            }
        }
        m
    }
}

/// [`Solids::mask`] prepared for one sky: the boxes of boxes and finite walls, 1/d per axis and
/// the directions below the terrain are computed once, so a mask costs three multiplications per
/// box and direction. Gives the same bits as [`Solids::mask`] (the same operations in the same
/// order as [`Obstacle::ray_hits`]; spheres and infinite walls call it).
#[derive(Debug, Clone)]
pub struct SkyMask<'a> {
    solids: Solids<'a>,
    dirs: Vec<Vec3>,
    below_ground: u32,
    /// The sky directions as lanes for the boxes' slab tests ([`SlabLanes`]).
    lanes: SlabLanes,
    slabs: Vec<(Vec3, Vec3)>,
    /// Oriented boxes: (centre (m), sine and cosine of the yaw, half extents (m), the sky
    /// directions in the box's frame as lanes), so a point is turned into the frame once and
    /// the directions are slab tests, as `Obstacle::ray_hits` tests them.
    oriented: Vec<(Vec3, f32, f32, Vec3, SlabLanes)>,
    others: Vec<Obstacle>,
}

/// Up to [`MAX_SKY_DIRS`] ray directions laid out for [`slab_mask`]: per axis, 1/d of every
/// direction (one lane each, ±∞ where d is 0 on the axis; 0 in unused lanes) and the bits of
/// the directions whose d is 0 on the axis.
#[derive(Debug, Clone)]
struct SlabLanes {
    inv: [[f32; MAX_SKY_DIRS]; 3],
    zero: [u32; 3],
    /// Bits of the lanes in use.
    used: u32,
}

impl SlabLanes {
    fn new(dirs: impl Iterator<Item = Vec3>) -> SlabLanes {
        let mut l = SlabLanes { inv: [[0.0; MAX_SKY_DIRS]; 3], zero: [0; 3], used: 0 };
        for (k, d) in dirs.take(MAX_SKY_DIRS).enumerate() {
            for ax in 0..3 {
                l.inv[ax][k] = 1.0 / d[ax];
                l.zero[ax] |= ((d[ax] == 0.0) as u32) << k;
            }
            l.used |= 1 << k;
        }
        l
    }
}

/// [`slab_hits`] for every direction of `lanes` at once: bit k set when the unbounded ray from
/// `p` along direction k hits the box `lo`–`hi`. The same operations on the same values as
/// [`slab_hits`], lane by lane, without its branches: the entry distance only grows and the exit
/// distance only shrinks as the axes narrow them (`f32::max`/`min` ignore NaN), so the span is
/// empty at the end exactly when it was empty after some axis. An axis where d is 0 fails the
/// ray when `p` is outside that slab (the lanes of `zero`); inside it (lo − p ≤ 0 ≤ hi − p) the
/// distances times 1/d = ±∞ are −∞ and +∞, or NaN on a face, which leave the span as it is,
/// as [`slab_hits`] skipping the axis does. So the same bits, and the lanes vectorise.
#[inline]
fn slab_mask(lanes: &SlabLanes, p: Vec3, lo: Vec3, hi: Vec3) -> u32 {
    let (a, b) = (lo - p, hi - p);
    let mut near = [0.0f32; MAX_SKY_DIRS];
    let mut far = [f32::INFINITY; MAX_SKY_DIRS];
    let mut outside = 0u32;
    for ax in 0..3 {
        let (aa, bb) = (a[ax], b[ax]);
        let inv = &lanes.inv[ax];
        for k in 0..MAX_SKY_DIRS {
            let (ta, tb) = (aa * inv[k], bb * inv[k]);
            let (n, f) = if ta > tb { (tb, ta) } else { (ta, tb) };
            near[k] = near[k].max(n);
            far[k] = far[k].min(f);
        }
        if p[ax] < lo[ax] || p[ax] > hi[ax] {
            outside |= lanes.zero[ax];
        }
    }
    let mut m = 0u32;
    for k in (0..MAX_SKY_DIRS).rev() {
        m = (m << 1) | !(near[k] > far[k]) as u32;
    }
    m & !outside & lanes.used
}

impl<'a> SkyMask<'a> {
    /// Prepares the mask of `solids` for the directions of `sky` (at most 32).
    pub fn new(solids: Solids<'a>, sky: &Sky) -> SkyMask<'a> {
        let dirs = sky.dirs.clone();
        let lanes = SlabLanes::new(dirs.iter().copied());
        let below_ground = match solids.ground {
            Some(g) => dirs.iter().enumerate().filter(|(_, d)| d.dot(g.normal) <= 0.0).fold(0u32, |m, (k, _)| m | 1 << k),
            None => 0,
        };
        let (mut slabs, mut oriented, mut others) = (Vec::new(), Vec::new(), Vec::new());
        for &o in solids.obstacles {
            match (o, o.as_box()) {
                // boxes and finite walls as `Obstacle::ray_hits` tests them (`space.rs`, `as_box`)
                (Obstacle::Box { .. } | Obstacle::FiniteWall { .. }, Some(b)) => slabs.push(b),
                (Obstacle::OrientedBox { center, half, yaw_deg }, _) => {
                    let (s, c) = yaw_deg.to_radians().sin_cos();
                    let turned = SlabLanes::new(dirs.iter().map(|&d| crate::obstacle::unyaw_sc(d, s, c)));
                    oriented.push((center, s, c, half, turned));
                }
                _ => others.push(o),
            }
        }
        SkyMask { solids, dirs, below_ground, lanes, slabs, oriented, others }
    }

    /// Bits of the sky directions that point below the terrain (blocked at every point; 0
    /// without terrain).
    pub fn below_ground(&self) -> u32 {
        self.below_ground
    }

    /// Bit k set when sky direction k is blocked at `p` by an obstacle or the terrain (equal to
    /// [`Solids::mask`]).
    pub fn mask(&self, p: Vec3) -> u32 {
        let n = self.dirs.len();
        let mut m = 0u32;
        if let Some(g) = self.solids.ground {
            if g.height_of(p) < 0.0 {
                return (0..n).fold(0u32, |m, k| m | 1 << k);
            }
            m = self.below_ground;
        }
        for &(lo, hi) in &self.slabs {
            m |= slab_mask(&self.lanes, p, lo, hi);
        }
        for (centre, s, c, half, turned) in &self.oriented {
            let q = crate::obstacle::unyaw_sc(p - *centre, *s, *c);
            m |= slab_mask(turned, q, -*half, *half);
        }
        for o in &self.others {
            for k in 0..n {
                if m & (1 << k) == 0 && o.ray_hits(p, self.dirs[k], f32::INFINITY) {
                    m |= 1 << k;
                }
            }
        }
        m
    }
}

/// The slab test of `Obstacle::ray_hits` for an unbounded ray from `p` along `d` (1/d per axis
/// `inv`) against the box `lo`–`hi`, with `a = lo − p`, `b = hi − p`: the reference of
/// [`slab_mask`].
#[cfg(test)]
fn slab_hits(p: Vec3, d: Vec3, inv: Vec3, lo: Vec3, hi: Vec3, a: Vec3, b: Vec3) -> bool {
    // the entry and exit distances (t0, t1) narrowed axis by axis; parallel axes test the slab
    let mut span = (0.0f32, f32::INFINITY);
    (0..3).all(|ax| {
        if d[ax] == 0.0 {
            return !(p[ax] < lo[ax] || p[ax] > hi[ax]);
        }
        let (ta, tb) = (a[ax] * inv[ax], b[ax] * inv[ax]);
        let (near, far) = if ta > tb { (tb, ta) } else { (ta, tb) };
        span = (span.0.max(near), span.1.min(far));
        !(span.0 > span.1)
    })
}

/// Light at `p` by eq. (3): (i(p) in 0–1, average light direction: the same integral of the unit
/// directions, normalised; straight up when no light arrives). `blocked` is the
/// [`Solids::mask`] at `p`.
pub fn light_at(sky: &Sky, blocked: u32, vols: &ShadowVolumes, p: Vec3) -> (f32, Vec3) {
    light_by(sky, blocked, |k| vols.transmittance(k, p))
}

/// Eq. (3) with the transmittance of sky direction k given by `transmittance(k)`: (i in 0–1,
/// average light direction, straight up when no light arrives); directions set in `blocked`
/// and directions of weight 0 are skipped.
pub fn light_by(sky: &Sky, blocked: u32, transmittance: impl Fn(usize) -> f32) -> (f32, Vec3) {
    let mut sum = 0.0f32;
    let mut dir = Vec3::ZERO;
    for k in 0..sky.dirs.len() {
        let w = sky.weights[k];
        if blocked & (1 << k) != 0 || w == 0.0 {
            continue;
        }
        let t = transmittance(k);
        sum += w * t;
        dir += sky.dirs[k] * (w * t);
    }
    (sum, dir.normalize_or(Vec3::Z))
}

/// [`light_at`] for many points at once, `points` as (position, [`Solids::mask`] there):
/// the same sums in the same order (bit for bit the values of [`light_at`]), computed direction
/// by direction so that each direction's shadow-volume grid is read while it is in cache.
pub fn light_many(sky: &Sky, vols: &ShadowVolumes, points: &[(Vec3, u32)]) -> Vec<(f32, Vec3)> {
    let mut acc = vec![(0.0f32, Vec3::ZERO); points.len()];
    for k in 0..sky.dirs.len() {
        let w = sky.weights[k];
        if w == 0.0 {
            continue;
        }
        let d = sky.dirs[k];
        for ((p, blocked), a) in points.iter().zip(acc.iter_mut()) {
            if blocked & (1 << k) != 0 {
                continue;
            }
            let t = vols.transmittance(k, *p);
            a.0 += w * t;
            a.1 += d * (w * t);
        }
    }
    acc.into_iter().map(|(s, d)| (s, d.normalize_or(Vec3::Z))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`depth_order`] against the sort of (key, index) pairs it replaces for many casters:
    /// the same order for depths with ties, ±0 and negative values, below and above
    /// [`RADIX_MIN`], with keys that differ in every radix digit, keys that share the high
    /// digits (depths within one binade) and keys that share the low ones (halves of integers,
    /// so a skipped pass comes before the passes that sort).
    /// Round 46: a level's grids merged from the level before's ([`ShadowVolumes::after`]) hold,
    /// cell by cell, exactly the casters a fresh build of the new occluders with the old grid's
    /// geometry holds, in the fresh build's order (descending depth, ties by index), and every
    /// query's product is the fresh volumes' bit for bit. The new set drops every seventh
    /// occluder, moves every fifth, changes the γ of every eleventh, adds new ones among them
    /// and ties depths; a region is set, as in the adaptation's levels.
    #[test]
    fn merged_grids_are_fresh_grids_slot_for_slot() {
        let sky = Sky::default();
        let f = |i: usize, a: f32| (i as f32 * a).sin();
        let old: Vec<Occluder> = (0..900).map(|i| Occluder { center: Vec3::new(f(i, 0.71) * 6.0, f(i, 0.53) * 6.0, 2.0 + f(i, 0.29).abs() * 12.0), radius: 0.25 + 0.2 * f(i, 0.37).abs(), gamma: 0.5 }).collect();
        // the new list: old occluders kept (in order), changed or dropped, and new ones between
        let (mut new, mut map) = (Vec::new(), Vec::new());
        for (i, o) in old.iter().enumerate() {
            if i % 13 == 4 {
                new.push(Occluder { center: o.center + Vec3::new(0.1, -0.2, 0.05), radius: 0.3, gamma: 0.4 });
            }
            if i % 7 == 3 {
                map.push(u32::MAX);
                continue;
            }
            let changed = if i % 5 == 1 {
                Some(Occluder { center: o.center + Vec3::new(0.05, 0.0, 0.3), ..*o })
            } else if i % 11 == 2 {
                Some(Occluder { gamma: 0.3, ..*o })
            } else if i % 17 == 6 {
                // a tie in depth along every direction with the kept occluder before it
                Some(*new.last().unwrap_or(o))
            } else {
                None
            };
            match changed {
                Some(c) => {
                    map.push(u32::MAX);
                    new.push(c);
                }
                None => {
                    map.push(new.len() as u32);
                    new.push(*o);
                }
            }
        }
        let region = (Vec3::new(-4.0, -4.0, 0.0), Vec3::new(4.0, 5.0, 10.0));
        let before = ShadowVolumes::new(&sky, old.clone()).within(region.0, region.1).tracked();
        before.prepare(u32::MAX >> (32 - sky.dirs.len()));
        let old_geometry: Vec<(Vec2, f32, usize, usize)> = (0..sky.dirs.len()).map(|k| before.grid(k)).map(|g| (g.lo, g.cell, g.nx, g.ny)).collect();
        let merged = ShadowVolumes::new(&sky, new.clone()).within(region.0, region.1).tracked().after(before, map);
        assert!(merged.base.is_some());
        let fresh = ShadowVolumes::new(&sky, new.clone()).within(region.0, region.1);
        let bounds_of = |g: &DirGrid| region_bounds(Some(region), g.d, g.u, g.v);
        let mut merged_dirs = 0;
        for (k, &(lo, cell, nx, ny)) in old_geometry.iter().enumerate() {
            let g = merged.grid(k);
            if (g.lo, g.cell, g.nx, g.ny) != (lo, cell, nx, ny) {
                continue; // built afresh (the geometry no longer suited)
            }
            merged_dirs += 1;
            let d = sky.dirs[k];
            let bounds = bounds_of(g);
            let mut order: Vec<usize> = (0..new.len()).collect();
            order.sort_by(|&a, &b| new[b].center.dot(d).total_cmp(&new[a].center.dot(d)).then(a.cmp(&b)));
            let cx = |x: f32, n: usize| x.max(0.0).min((n - 1) as f32) as usize;
            for y in 0..ny {
                for x in 0..nx {
                    let c = y * nx + x;
                    let want: Vec<u32> = order
                        .iter()
                        .copied()
                        .filter(|&j| {
                            let o = &new[j];
                            let q = Vec2::new(o.center.dot(g.u), o.center.dot(g.v));
                            let (a, b) = ((q - o.radius - lo) / cell, (q + o.radius - lo) / cell);
                            in_region(bounds, q, o.center.dot(d), o.radius) && (cx(a.x, nx)..=cx(b.x, nx)).contains(&x) && (cx(a.y, ny)..=cx(b.y, ny)).contains(&y)
                        })
                        .map(|j| j as u32)
                        .collect();
                    let slots: Vec<usize> = (g.start[c] as usize * LANES..g.start[c + 1] as usize * LANES).collect();
                    let got: Vec<u32> = slots.iter().map(|&s| g.idx[s / LANES][s % LANES]).filter(|&i| i != u32::MAX).collect();
                    assert_eq!(got, want, "direction {k}, cell ({x}, {y})");
                    assert_eq!(slots.len(), want.len().div_ceil(LANES) * LANES, "padded to whole blocks");
                    for (&s, &j) in slots.iter().zip(&want) {
                        let (b, l, o) = (&g.blocks[s / LANES], s % LANES, &new[j as usize]);
                        let bits = [b.u[l], b.v[l], b.w[l], b.r2[l], g.gamma[s / LANES][l]].map(f32::to_bits);
                        assert_eq!(bits, [o.center.dot(g.u), o.center.dot(g.v), o.center.dot(d), o.radius * o.radius, o.gamma].map(f32::to_bits));
                    }
                    assert_eq!(g.top[c].to_bits(), if want.is_empty() { f32::NEG_INFINITY } else { new[want[0] as usize].center.dot(d) }.to_bits());
                }
            }
        }
        assert!(merged_dirs >= sky.dirs.len() / 2, "{merged_dirs} of {} directions merged", sky.dirs.len());
        // every query the same bit for bit, inside the region and outside it
        let mut hit = 0;
        for i in 0..3000 {
            let p = Vec3::new(f(i, 0.917) * 5.0, f(i, 0.613) * 5.5, 1.0 + f(i, 0.377).abs() * 11.0);
            for k in 0..sky.dirs.len() {
                let (a, b) = (merged.product_until(k, p, 0.0), fresh.product_until(k, p, 0.0));
                assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "point {p}, direction {k}");
                hit += usize::from(a.is_some_and(|t| t < 1.0));
            }
        }
        assert!(hit > 10_000, "{hit} shaded rays");
    }

    #[test]
    fn depth_order_is_the_pair_sort() {
        let pairs = |depth: &[f32]| -> Vec<u32> {
            // descending depth by total_cmp, ties by index
            let mut order: Vec<u32> = (0..depth.len() as u32).collect();
            order.sort_by(|&a, &b| depth[b as usize].total_cmp(&depth[a as usize]).then(a.cmp(&b)));
            order
        };
        for n in [5usize, 300, RADIX_MIN, 3000] {
            for spread in [1.0f32, 1000.0, 0.0] {
                let depth: Vec<f32> = (0..n)
                    .map(|j| match j % 7 {
                        _ if spread == 0.0 => (j % 37) as f32 * 0.5 + 1.0,
                        0 => 0.0,
                        1 => -0.0,
                        2 => 4.5, // ties
                        _ => 1.5 + ((j as f32) * 0.618).sin() * spread,
                    })
                    .collect();
                assert_eq!(depth_order(&depth), pairs(&depth), "{n} depths, spread {spread}");
            }
        }
    }

    #[test]
    fn sky_weights_and_exact_directions() {
        let s = Sky::default();
        assert_eq!(s.dirs.len(), SKY_DIRS);
        assert!((s.weights.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        // importance sampling: every direction carries the same weight
        assert!(s.weights.iter().all(|w| (w - 1.0 / SKY_DIRS as f32).abs() < 1e-6));
        // a direction at azimuth 270° has x exactly 0 (f32 cos(3π/2) would be 1.19e-8)
        assert!(s.dirs.iter().any(|d| d.x == 0.0 && d.y < 0.0));
        // symmetric: the weighted mean direction is the zenith
        let m: Vec3 = s.dirs.iter().zip(&s.weights).map(|(d, w)| *d * *w).sum();
        assert!(m.x.abs() < 1e-6 && m.y.abs() < 1e-6 && m.z > 0.5);
        // rings at the middle of their shares of F(Δσ) = 1 − cos³Δσ: the innermost ring (share
        // 0–1/6) at arccos((11/12)^⅓) = 13.7°, the outermost (1/2–1) at arccos(0.25^⅓) = 51.0°
        let zenith_deg = |d: &Vec3| d.z.acos().to_degrees();
        assert!((zenith_deg(&s.dirs[0]) - 13.73).abs() < 0.01, "{}", zenith_deg(&s.dirs[0]));
        assert!((zenith_deg(&s.dirs[SKY_DIRS - 1]) - 50.95).abs() < 0.01, "{}", zenith_deg(&s.dirs[SKY_DIRS - 1]));
        // a brightest point 40° high: the directions below the horizon are dropped, the weighted
        // mean direction leans towards it
        let low = Sky::from_latitude(50.0);
        assert!(low.dirs.len() < SKY_DIRS && low.dirs.iter().all(|d| d.z > 0.0));
        let m: Vec3 = low.dirs.iter().zip(&low.weights).map(|(d, w)| *d * *w).sum();
        assert!(m.y < -0.3 && m.x.abs() < 1e-6, "{m}");
        // ring sets are checked
        assert!(Sky::with_rings(Vec3::Z, &[4, 8]).is_ok_and(|s| s.dirs.len() == 12));
        for bad in [&[][..], &[3, 8], &[4, 0], &[8, 12, 16]] {
            let e = Sky::with_rings(Vec3::Z, bad).unwrap_err().to_string();
            assert!(e.contains("rings") && e.contains("multiples of 4"), "{e}");
        }
        // the old quadrature: equal zenith bands, the zenith ring outweighs the horizon
        let old = Sky::zenith_rings(Vec3::Z, &[4, 8, 8, 12]).unwrap();
        assert_eq!(old.dirs.len(), 32);
        assert!(old.weights[0] > old.weights[31]);
    }

    /// Eq. (3) at `p` by brute force over any number of directions (the sky masks are limited
    /// to 32): solids tested per ray, then the product of eq. (4) over every occluder hit.
    fn light_by_rays(sky: &Sky, occ: &[Occluder], obstacles: &[Obstacle], ground: Ground, p: Vec3) -> (f32, Vec3) {
        let (mut i, mut dir) = (0.0f32, Vec3::ZERO);
        for (k, &d) in sky.dirs.iter().enumerate() {
            if ground.blocks(p, d) || obstacles.iter().any(|o| o.ray_hits(p, d, f32::INFINITY)) {
                continue;
            }
            let mut t = 1.0f32;
            for o in occ {
                let oc = o.center - p;
                let (along, l2, r2) = (oc.dot(d), oc.length_squared(), o.radius * o.radius);
                if along > 0.0 && l2 > r2 && l2 - along * along <= r2 {
                    t *= o.gamma;
                }
            }
            i += sky.weights[k] * t;
            dir += d * (sky.weights[k] * t);
        }
        (i, dir.normalize_or(Vec3::Z))
    }

    /// The default 24-direction sky against a reference quadrature of 1,464 directions (24
    /// zenith bands of 4·round(24 sin θ) directions) in a crown of 200 translucent clusters,
    /// open and beside a wall, brightest point at the zenith and 40° high: with 8 directions
    /// fewer, the mean error of eq. (3)'s i is at most 10 % larger than with the 32 directions of
    /// equal zenith bands it replaced (measured: 2 % larger open under a zenith sky, smaller in
    /// the other cases), the mean error of the light direction at most 0.25° larger, and both
    /// small.
    #[test]
    fn default_sky_is_at_least_as_faithful_as_the_old_32_directions() {
        let occ: Vec<Occluder> = (0..200)
            .map(|i| {
                let f = i as f32;
                let (a, b, c) = ((f * 0.754).sin(), (f * 1.377).cos(), (f * 0.513).sin());
                let r = 0.4 + 0.6 * (f * 2.17).sin().abs();
                Occluder { center: Vec3::new(4.0 * a * c.abs().sqrt(), 4.0 * b * c.abs().sqrt(), 8.0 + 5.0 * (f * 0.291).cos()), radius: r, gamma: 0.5f32.powf(r) }
            })
            .collect();
        let receivers: Vec<Vec3> = (0..150)
            .map(|j| {
                let f = j as f32;
                Vec3::new(3.5 * (f * 0.619).sin(), 3.5 * (f * 0.887).cos(), 4.0 + 8.0 * (f * 0.137).sin().abs())
            })
            .collect();
        let wall = Obstacle::FiniteWall { x: 2.5, length: 16.0, height: 15.0 };
        for (b, obstacles) in [(Vec3::Z, vec![]), (Vec3::Z, vec![wall]), (Sky::from_latitude(50.0).brightest, vec![wall])] {
            let reference = Sky::reference(b, 24);
            assert_eq!(reference.dirs.len(), 1464);
            let exact: Vec<(f32, Vec3)> = receivers.iter().map(|&p| light_by_rays(&reference, &occ, &obstacles, Ground::flat(0.0), p)).collect();
            let errors = |sky: &Sky| {
                let (mut di, mut da) = (0.0f32, 0.0f32);
                for (&p, &(ir, dr)) in receivers.iter().zip(&exact) {
                    let (i, d) = light_by_rays(sky, &occ, &obstacles, Ground::flat(0.0), p);
                    di += (i - ir).abs();
                    da += d.dot(dr).clamp(-1.0, 1.0).acos().to_degrees();
                }
                (di / receivers.len() as f32, da / receivers.len() as f32)
            };
            let (new_i, new_a) = errors(&Sky::toward(b));
            let (old_i, old_a) = errors(&Sky::zenith_rings(b, &[4, 8, 8, 12]).unwrap());
            eprintln!("brightest {b}, {} obstacles: default |Δi| {new_i:.4}, {new_a:.2}°; old 32 directions {old_i:.4}, {old_a:.2}°", obstacles.len());
            assert!(new_i <= 1.1 * old_i && new_a <= old_a + 0.25, "brightest {b}: default {new_i} {new_a}°, old {old_i} {old_a}°");
            assert!(new_i < 0.03 && new_a < 3.0, "brightest {b}: {new_i} {new_a}°");
        }
    }

    #[test]
    fn infinite_wall_does_not_darken_rays_parallel_to_it() {
        let s = Sky::default();
        let wall = [Obstacle::Wall { x: 1.0 }];
        let m = Solids { obstacles: &wall, ground: None }.mask(&s, Vec3::new(0.0, 0.0, 2.0));
        // rays with d.x > 0 can reach x = 1; rays with d.x ≤ 0 cannot
        for (k, d) in s.dirs.iter().enumerate() {
            assert_eq!(m & (1 << k) != 0, d.x > 0.0, "direction {d}");
        }
    }

    #[test]
    fn prepared_mask_equals_plain_mask() {
        let obstacles = [
            Obstacle::FiniteWall { x: 1.0, length: 4.0, height: 3.0 },
            Obstacle::FiniteWall { x: -2.0, length: 2.0, height: 1.0 },
            Obstacle::Box { min: Vec3::new(-1.0, 1.0, 0.5), max: Vec3::new(0.5, 2.0, 4.0) },
            Obstacle::Sphere { center: Vec3::new(0.0, -2.0, 3.0), radius: 0.7 },
            Obstacle::Wall { x: 3.0 },
            Obstacle::OrientedBox { center: Vec3::new(1.5, 0.5, 1.0), half: Vec3::new(0.1, 2.0, 1.5), yaw_deg: 0.0 },
            Obstacle::OrientedBox { center: Vec3::new(-1.0, 1.5, 2.0), half: Vec3::new(0.8, 0.3, 2.5), yaw_deg: 37.0 },
        ];
        for sky in [Sky::default(), Sky::from_latitude(50.0)] {
            for (i, o) in obstacles.iter().enumerate() {
                for ground in [None, Some(Ground::slope(Vec3::ZERO, 20.0, 135.0))] {
                    let solids = Solids { obstacles: std::slice::from_ref(o), ground };
                    let fast = SkyMask::new(solids, &sky);
                    let mut blocked = 0;
                    for j in 0..400 {
                        let f = j as f32;
                        let p = Vec3::new((f * 0.37).sin() * 3.0, (f * 0.71).cos() * 3.0, (f * 0.13).sin() * 2.0 + 1.5);
                        let m = solids.mask(&sky, p);
                        assert_eq!(fast.mask(p), m, "obstacle {i}, point {p}");
                        blocked += m.count_ones();
                    }
                    // the cases test something: some directions are blocked, not all
                    assert!(blocked > 0 && blocked < 400 * 32, "obstacle {i}: {blocked}");
                }
            }
        }
    }

    /// [`slab_mask`] against [`slab_hits`] direction by direction: the same bits, for points
    /// inside, outside and on the faces of boxes, and directions with zero components (the
    /// default sky's, exact) and without (a sky 40° high, turned by a yaw).
    #[test]
    fn slab_mask_equals_slab_hits() {
        let boxes = [(Vec3::new(-1.0, -2.0, 0.0), Vec3::new(1.0, 2.0, 3.0)), (Vec3::new(0.5, -0.1, 0.0), Vec3::new(0.7, 0.1, 6.0))];
        let turned: Vec<Vec3> = Sky::from_latitude(50.0).dirs.iter().map(|&d| crate::obstacle::unyaw_sc(d, 0.6f32.sin(), 0.6f32.cos())).collect();
        let (mut hits, mut total) = (0, 0);
        for dirs in [Sky::default().dirs, turned] {
            assert!(dirs.len() <= MAX_SKY_DIRS);
            let lanes = SlabLanes::new(dirs.iter().copied());
            for (lo, hi) in boxes {
                for j in 0..600 {
                    let f = j as f32;
                    // every tenth point on a face of the box, the others scattered around it
                    let mut p = Vec3::new((f * 0.37).sin() * 3.0, (f * 0.71).cos() * 3.0, (f * 0.13).sin() * 2.0 + 1.5);
                    if j % 10 == 0 {
                        p[j / 10 % 3] = if j % 20 == 0 { lo[j / 10 % 3] } else { hi[j / 10 % 3] };
                    }
                    let m = slab_mask(&lanes, p, lo, hi);
                    for (k, &d) in dirs.iter().enumerate() {
                        let inv = Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
                        let h = slab_hits(p, d, inv, lo, hi, lo - p, hi - p);
                        assert_eq!(m & (1 << k) != 0, h, "point {p}, direction {d}, box {lo}–{hi}");
                        (hits, total) = (hits + h as usize, total + 1);
                    }
                    assert_eq!(m >> dirs.len(), 0, "unused lanes are clear");
                }
            }
        }
        // the cases test something: rays that hit (measured: 4,760 of 54,000) and rays that miss
        assert!(hits > 1000 && hits < total - 1000, "{hits} hits of {total}");
    }

    /// The grid path (lazy grids, padded blocks) against the product over every occluder in
    /// occluder order (the grids: in their depth order and coordinates), and `light_many`
    /// against `light_at`: equal bit for bit.
    #[test]
    fn grid_products_equal_the_plain_product() {
        // 300 occluders: the grid path; 40: the whole run scanned (SCAN_MAX)
        for n in [300, 40] {
            products_equal_the_plain_product(n);
        }
    }

    fn products_equal_the_plain_product(n: usize) {
        assert_eq!(n > SCAN_MAX, ShadowVolumes::new(&Sky::default(), vec![Occluder { center: Vec3::Z, radius: 1.0, gamma: 0.5 }; n]).flat.is_none());
        let sky = Sky::from_latitude(50.0);
        let occ: Vec<Occluder> = (0..n)
            .map(|i| {
                let f = i as f32;
                let r = 0.2 + 0.3 * (f * 0.37).sin().abs();
                Occluder { center: Vec3::new((f * 0.71).sin() * 3.0, (f * 0.53).cos() * 3.0, 2.0 + (f * 0.29).sin().abs() * 5.0), radius: r, gamma: 0.5f32.powf(r) }
            })
            .collect();
        let vols = ShadowVolumes::new(&sky, occ.clone());
        let mut shaded = 0;
        let mut points = Vec::new();
        for j in 0..200 {
            let f = j as f32;
            let p = Vec3::new((f * 0.43).cos() * 3.5, (f * 0.61).sin() * 3.5, 1.0 + (f * 0.17).sin().abs() * 6.0);
            for (k, &d) in sky.dirs.iter().enumerate() {
                let mut t = 1.0f32;
                if n > SCAN_MAX {
                    // the grid's order and arithmetic: descending depth along d (ties in
                    // occluder order), coordinates on the plane ⟂ d and along d
                    let (u, v) = d.any_orthonormal_pair();
                    let mut order: Vec<usize> = (0..n).collect();
                    order.sort_by(|&a, &b| occ[b].center.dot(d).total_cmp(&occ[a].center.dot(d)).then(a.cmp(&b)));
                    for &j in &order {
                        let o = &occ[j];
                        let (du, dv, along) = (o.center.dot(u) - p.dot(u), o.center.dot(v) - p.dot(v), o.center.dot(d) - p.dot(d));
                        let (lat2, r2) = (du * du + dv * dv, o.radius * o.radius);
                        if along > 0.0 && lat2 <= r2 && lat2 + along * along > r2 {
                            t *= o.gamma;
                        }
                    }
                } else {
                    for o in &occ {
                        let oc = o.center - p;
                        let along = oc.dot(d);
                        let l2 = oc.length_squared();
                        if along > 0.0 && l2 > o.radius * o.radius && l2 - along * along <= o.radius * o.radius {
                            t *= o.gamma;
                        }
                    }
                }
                let plain = if t < 1e-4 { 0.0 } else { t };
                assert_eq!(vols.transmittance(k, p).to_bits(), plain.to_bits(), "point {p}, direction {k}");
                assert_eq!(vols.shaded(k, p), t < 1.0);
                shaded += (t < 1.0) as usize;
            }
            points.push((p, (j as u32).wrapping_mul(2_654_435_761) & 0x0f0f_0f0f));
        }
        assert!(shaded > 100 && shaded < 200 * SKY_DIRS - 200, "{n} occluders: {shaded}");
        for ((p, m), (i, d)) in points.iter().zip(light_many(&sky, &vols, &points)) {
            let (i2, d2) = light_at(&sky, *m, &vols, *p);
            assert_eq!((i.to_bits(), d.to_array().map(f32::to_bits)), (i2.to_bits(), d2.to_array().map(f32::to_bits)));
        }
    }

    /// A direction grid's layout against its definition, for every sky direction, both cell
    /// sizes, tagged and untagged casters, with ties in depth (every third caster a copy of the
    /// one before with another transmittance and owner) and grids of 40 to 700 casters: each
    /// cell's slots hold, in order, exactly the casters whose disc's cell range covers the cell
    /// (floor of (projection ∓ radius − lo) / cell, clamped to the grid), in descending depth
    /// along d with ties in occluder order, in the grid's coordinates, bit for bit; then padding
    /// slots (never hit) to a whole block. It pins the layout that a faster build must keep.
    #[test]
    fn grid_cells_hold_their_casters_in_depth_order() {
        let sky = Sky::from_latitude(50.0);
        for n in [700, 150, 40] {
            let mut occ: Vec<Occluder> = Vec::new();
            for i in 0..n {
                let f = i as f32;
                let o = if i % 3 == 2 {
                    Occluder { gamma: 0.3, ..occ[i - 1] }
                } else {
                    Occluder { center: Vec3::new((f * 0.71).sin() * 4.0, (f * 0.53).cos() * 4.0, 2.0 + (f * 0.29).sin().abs() * 9.0), radius: 0.2 + 0.3 * (f * 0.37).sin().abs(), gamma: 0.5 }
                };
                occ.push(o);
            }
            let owners: Vec<u32> = (0..n as u32).map(|i| i % 5).collect();
            let (mut ties, mut slots) = (0, 0);
            for (tag, cell_radii) in [(&owners[..], CELL_RADII), (&[][..], COARSE_CELL_RADII)] {
                for &d in &sky.dirs {
                    let g = DirGrid::new(d, &occ, tag, None, cell_radii, false);
                    assert!(g.nx > 0 && g.ny > 0 && g.nx <= MAX_CELLS_PER_AXIS && g.ny <= MAX_CELLS_PER_AXIS);
                    assert_eq!((g.start.len(), g.start[0] as usize, g.start[g.nx * g.ny] as usize), (g.nx * g.ny + 1, 0, g.blocks.len()));
                    assert_eq!((g.gamma.len(), g.owner.len()), (g.blocks.len(), if tag.is_empty() { 0 } else { g.blocks.len() }));
                    assert_eq!(g.top.len(), g.nx * g.ny);
                    let floor_cell = |x: f32, n: usize| ((x / g.cell).floor().max(0.0) as usize).min(n - 1);
                    let mut order: Vec<usize> = (0..n).collect();
                    order.sort_by(|&a, &b| occ[b].center.dot(d).total_cmp(&occ[a].center.dot(d)).then(a.cmp(&b)));
                    ties += order.windows(2).filter(|w| occ[w[0]].center.dot(d) == occ[w[1]].center.dot(d)).count();
                    for y in 0..g.ny {
                        for x in 0..g.nx {
                            let want: Vec<usize> = order
                                .iter()
                                .copied()
                                .filter(|&j| {
                                    let (o, q) = (&occ[j], Vec2::new(occ[j].center.dot(g.u), occ[j].center.dot(g.v)));
                                    let (x0, x1) = (floor_cell(q.x - o.radius - g.lo.x, g.nx), floor_cell(q.x + o.radius - g.lo.x, g.nx));
                                    let (y0, y1) = (floor_cell(q.y - o.radius - g.lo.y, g.ny), floor_cell(q.y + o.radius - g.lo.y, g.ny));
                                    (x0..=x1).contains(&x) && (y0..=y1).contains(&y)
                                })
                                .collect();
                            let c = y * g.nx + x;
                            let run = g.start[c] as usize..g.start[c + 1] as usize;
                            assert_eq!(run.len(), want.len().div_ceil(LANES), "direction {d}, cell {x}, {y}");
                            // the cell's top: its first (deepest ahead) caster's depth, −∞ when empty
                            assert_eq!(g.top[c].to_bits(), want.first().map_or(f32::NEG_INFINITY, |&j| occ[j].center.dot(d)).to_bits(), "direction {d}, cell {x}, {y}");
                            slots += want.len();
                            for (at, (bi, l)) in run.flat_map(|bi| (0..LANES).map(move |l| (bi, l))).enumerate() {
                                let b = &g.blocks[bi];
                                let got = (b.u[l].to_bits(), b.v[l].to_bits(), b.w[l].to_bits(), b.r2[l].to_bits(), g.gamma[bi][l].to_bits(), g.owner.get(bi).map_or(u32::MAX, |o| o[l]));
                                let expect = match want.get(at) {
                                    Some(&j) => {
                                        let o = &occ[j];
                                        (o.center.dot(g.u).to_bits(), o.center.dot(g.v).to_bits(), o.center.dot(d).to_bits(), (o.radius * o.radius).to_bits(), o.gamma.to_bits(), tag.get(j).copied().unwrap_or(u32::MAX))
                                    }
                                    None => (0f32.to_bits(), 0f32.to_bits(), f32::NEG_INFINITY.to_bits(), (-1f32).to_bits(), 1f32.to_bits(), u32::MAX),
                                };
                                assert_eq!(got, expect, "direction {d}, cell {x}, {y}, slot {at}");
                            }
                        }
                    }
                }
            }
            // the cases test something: ties in depth, casters in several cells each
            assert!(ties >= n / 3 && slots > 2 * n * sky.dirs.len(), "{n} casters: {ties} ties, {slots} slots");
        }
    }

    /// Shadow volumes told where their queries come from ([`ShadowVolumes::within`]) give the
    /// answers of the plain ones bit for bit, inside the region (grids of the casters that can
    /// reach it) and outside it (grids of every caster); and inside, the grids hold fewer casters.
    #[test]
    fn region_grids_answer_as_the_full_grids() {
        let sky = Sky::from_latitude(50.0);
        let occ: Vec<Occluder> = (0..600)
            .map(|i| {
                let f = i as f32;
                let r = 0.2 + 0.3 * (f * 0.37).sin().abs();
                Occluder { center: Vec3::new((f * 0.71).sin() * 20.0, (f * 0.53).cos() * 20.0, 2.0 + (f * 0.29).sin().abs() * 8.0), radius: r, gamma: 0.5f32.powf(r) }
            })
            .collect();
        let (lo, hi) = (Vec3::new(-3.0, -3.0, 0.0), Vec3::new(3.0, 3.0, 6.0));
        let plain = ShadowVolumes::new(&sky, occ.clone());
        let near = ShadowVolumes::new(&sky, occ).within(lo, hi);
        let (mut inside, mut outside, mut shaded) = (0, 0, 0);
        for j in 0..400 {
            let f = j as f32;
            let p = Vec3::new((f * 0.43).cos() * 4.5, (f * 0.61).sin() * 4.5, 1.0 + (f * 0.17).sin().abs() * 5.0);
            let within = p.cmpge(lo).all() && p.cmple(hi).all();
            (inside, outside) = (inside + within as usize, outside + !within as usize);
            for k in 0..sky.dirs.len() {
                let t = plain.transmittance(k, p);
                assert_eq!(near.transmittance(k, p).to_bits(), t.to_bits(), "point {p}, direction {k}");
                shaded += (t < 1.0) as usize;
            }
        }
        assert!(inside > 50 && outside > 50 && shaded > 500, "{inside} inside, {outside} outside, {shaded} shaded");
        let held = |v: &ShadowVolumes| v.grids.iter().filter_map(|g| g.get()).map(|g| g.blocks.len()).sum::<usize>();
        assert!(held(&near) * 2 < held(&plain), "region grids {} blocks, full {}", held(&near), held(&plain));
    }

    /// Shadow volumes of three owners' occluders, queried leaving one owner out, against shadow
    /// volumes of the other owners' occluders alone: the same answer for every ray.
    #[test]
    fn shaded_except_equals_the_others_alone() {
        // the grid path and the scanned run (SCAN_MAX)
        for n in [240, 60] {
            shaded_except_case(n);
        }
    }

    fn shaded_except_case(n: u32) {
        let sky = Sky::from_latitude(47.0);
        let occ: Vec<Occluder> = (0..n)
            .map(|i| {
                let f = i as f32;
                let r = 0.2 + 0.4 * (f * 0.31).sin().abs();
                Occluder { center: Vec3::new((f * 0.77).sin() * 4.0, (f * 0.41).cos() * 4.0, 2.0 + (f * 0.23).sin().abs() * 6.0), radius: r, gamma: 0.6f32.powf(r) }
            })
            .collect();
        let owners: Vec<u32> = (0..occ.len() as u32).map(|i| (i * 7) % 3).collect();
        let all = ShadowVolumes::with_owners(&sky, occ.clone(), owners.clone());
        let (mut differ, mut shaded) = (0, 0);
        for skip in 0..3u32 {
            let rest: Vec<Occluder> = occ.iter().zip(&owners).filter(|(_, &w)| w != skip).map(|(o, _)| *o).collect();
            let alone = ShadowVolumes::new(&sky, rest);
            for j in 0..150 {
                let f = j as f32;
                let p = Vec3::new((f * 0.47).cos() * 4.5, (f * 0.59).sin() * 4.5, 1.0 + (f * 0.19).sin().abs() * 7.0);
                for k in 0..sky.dirs.len() {
                    let s = alone.shaded(k, p);
                    assert_eq!(all.shaded_except(k, p, skip), s, "owner {skip}, point {p}, direction {k}");
                    shaded += s as usize;
                    differ += (all.shaded(k, p) != s) as usize;
                }
            }
        }
        // the cases test something: shaded and unshaded rays, and rays that only the skipped
        // owner's occluders shade
        assert!(shaded > 200 && shaded < 3 * 150 * sky.dirs.len() - 500, "{n} occluders: {shaded}");
        assert!(differ > 50, "{n} occluders: {differ}");
        // untagged volumes count every occluder
        let plain = ShadowVolumes::new(&sky, occ);
        assert!((0..sky.dirs.len()).all(|k| plain.shaded_except(k, Vec3::new(0.0, 0.0, 1.0), 0) == plain.shaded(k, Vec3::new(0.0, 0.0, 1.0))));
    }

    #[test]
    fn cluster_transmittance_eq4() {
        let s = Sky::default();
        let c = Occluder { center: Vec3::new(0.0, 0.0, 5.0), radius: 1.0, gamma: 0.5f32.powf(1.0) };
        let v = ShadowVolumes::new(&s, vec![c, Occluder { center: Vec3::new(0.0, 0.0, 8.0), ..c }]);
        // the low ring (zenith angle 78.75°) passes beside both clusters
        assert_eq!(v.transmittance(SKY_DIRS - 1, Vec3::ZERO), 1.0);
        // straight up through both clusters: 0.5²
        let up = ShadowVolumes::new(&Sky { brightest: Vec3::Z, dirs: vec![Vec3::Z], weights: vec![1.0] }, v.occluders().to_vec());
        assert!((up.transmittance(0, Vec3::ZERO) - 0.25).abs() < 1e-6);
        // inside a cluster: not shaded by it
        assert!((up.transmittance(0, Vec3::new(0.0, 0.0, 5.2)) - 0.5).abs() < 1e-6);
        // shaded: transmittance below 1
        assert!(up.shaded(0, Vec3::ZERO) && up.shaded(0, Vec3::new(0.0, 0.0, 5.2)));
        assert!(!v.shaded(SKY_DIRS - 1, Vec3::ZERO) && !up.shaded(0, Vec3::new(0.0, 0.0, 9.5)));
        let (i, _) = light_at(&Sky { brightest: Vec3::Z, dirs: vec![Vec3::Z], weights: vec![1.0] }, 0, &up, Vec3::ZERO);
        assert!((i - 0.25).abs() < 1e-6);
    }
}
