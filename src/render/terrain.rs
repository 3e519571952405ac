//! Terrain meshes for the renderer: from a height grid or a TIN, coloured by land cover
//! (elevation and slope) or by an overlay field.

use glam::Vec3;

use crate::grid::Grid;
use crate::{Error, Result};

/// The terrain as an indexed triangle mesh with per-vertex normals and colours.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TerrainMesh {
    /// Vertex positions (m), x east, y north, z up (elevation).
    pub positions: Vec<[f32; 3]>,
    /// Unit normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Linear RGB albedo in 0..1, one per position (land cover or overlay).
    pub colors: Vec<[f32; 3]>,
    /// Triangle list (counter-clockwise seen from above); length a multiple of 3.
    pub indices: Vec<u32>,
    /// Dissolve into the sky, one per position, 0 (solid ground) ..1 (the sky colour behind it,
    /// no edge): the surroundings beyond the simulated window fade out towards the edge of
    /// the DEM or of the drawn margin. Empty: 0 everywhere.
    pub fade: Vec<f32>,
    /// Plan rectangle `(min, max)` (m) of the simulated window when the mesh also holds its
    /// surroundings: [`TerrainMesh::bounds`] (camera presets, shadow map, canopy layer) covers
    /// only the vertices inside it. `None`: the whole mesh is the site.
    pub focus: Option<([f32; 2], [f32; 2])>,
    /// `[columns, rows]` when the positions are a row-major grid of that many vertices (north
    /// row first, as [`from_ground`] builds them): [`TerrainMesh::coarse_indices`] can then
    /// draw it with fewer triangles. `None`: any triangle mesh.
    pub grid: Option<[usize; 2]>,
}

impl TerrainMesh {
    /// Axis-aligned bounds `(min, max)` in metres of the site: the vertices inside
    /// [`TerrainMesh::focus`] when set (the simulated window, without its surroundings), else
    /// all; a unit box at the origin for an empty mesh.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let Some((lo, hi)) = self.focus else { return self.full_bounds() };
        crate::mesh::points_bounds(self.positions.iter().filter(|p| p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1])).unwrap_or_else(|| self.full_bounds())
    }

    /// Axis-aligned bounds `(min, max)` in metres of every vertex, surroundings included; a
    /// unit box at the origin for an empty mesh.
    pub fn full_bounds(&self) -> ([f32; 3], [f32; 3]) {
        crate::mesh::points_bounds(self.positions.iter()).unwrap_or(([0.0; 3], [1.0; 3]))
    }

    /// The triangles of a grid mesh ([`TerrainMesh::grid`]) over every `stride`-th column and
    /// row (and the last ones), for a coarser drawing of the same vertices (frames in motion):
    /// a quad where its four corners have finite positions, split as the full mesh's quads are.
    /// `None` for a mesh that is not a grid or a stride below 2.
    pub fn coarse_indices(&self, stride: usize) -> Option<Vec<u32>> {
        let [w, h] = self.grid?;
        if stride < 2 || w < 2 || h < 2 || self.positions.len() != w * h {
            return None;
        }
        let steps = |n: usize| -> Vec<usize> {
            let mut v: Vec<usize> = (0..n).step_by(stride).collect();
            if v.last() != Some(&(n - 1)) {
                v.push(n - 1);
            }
            v
        };
        let (cols, rows) = (steps(w), steps(h));
        let ok = |c: usize, r: usize| self.positions[r * w + c].iter().all(|v| v.is_finite());
        let mut out = Vec::with_capacity(cols.len() * rows.len() * 6);
        for rr in rows.windows(2) {
            for cc in cols.windows(2) {
                let (c0, c1, r0, r1) = (cc[0], cc[1], rr[0], rr[1]);
                if !(ok(c0, r0) && ok(c1, r0) && ok(c0, r1) && ok(c1, r1)) {
                    continue;
                }
                let i = |c: usize, r: usize| (r * w + c) as u32;
                let (sw, se, ne, nw) = (i(c0, r1), i(c1, r1), i(c1, r0), i(c0, r0));
                out.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
            }
        }
        Some(out)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Checks that the arrays agree and indices are in range.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] naming the offending field.
    pub fn validate(&self) -> crate::Result<()> {
        let n = self.positions.len();
        let bad = |field: &str, value: String, expected: String| crate::Error::Invalid {
            context: "render::TerrainMesh".into(),
            field: field.into(),
            value,
            expected,
        };
        if self.normals.len() != n {
            return Err(bad("normals", self.normals.len().to_string(), format!("{n} (one per position)")));
        }
        if self.colors.len() != n {
            return Err(bad("colors", self.colors.len().to_string(), format!("{n} (one per position)")));
        }
        if !self.fade.is_empty() && self.fade.len() != n {
            return Err(bad("fade", self.fade.len().to_string(), format!("0 or {n} (one per position)")));
        }
        if self.indices.len() % 3 != 0 {
            return Err(bad("indices", self.indices.len().to_string(), "a multiple of 3".into()));
        }
        if let Some(&i) = self.indices.iter().find(|&&i| i as usize >= n) {
            return Err(bad("indices", i.to_string(), format!("< {n} (vertex count)")));
        }
        Ok(())
    }

    /// Fade of vertex `i` (0 when the mesh has none).
    pub fn fade_at(&self, i: usize) -> f32 {
        self.fade.get(i).copied().unwrap_or(0.0)
    }

    /// Height (m) of the drawn surface at `(x, y)` in plan: the triangle that holds the point,
    /// interpolated linearly (barycentric), the highest where triangles overlap; the nearest
    /// vertex's height ([`TerrainMesh::nearest_height`]) where no triangle holds it; `None`
    /// for an empty mesh. O(triangles), for camera placement: an eye put at this height plus
    /// 1.7 m stands on the surface that is drawn (one put on the nearest vertex stood up to
    /// metres under Coweeta's slopes between coarse vertices, a trial's ground view from
    /// below the terrain).
    pub fn height_at(&self, x: f32, y: f32) -> Option<f32> {
        let mut best: Option<f32> = None;
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
            let det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
            if det.abs() < 1e-12 {
                continue;
            }
            let l1 = ((b[1] - c[1]) * (x - c[0]) + (c[0] - b[0]) * (y - c[1])) / det;
            let l2 = ((c[1] - a[1]) * (x - c[0]) + (a[0] - c[0]) * (y - c[1])) / det;
            let l3 = 1.0 - l1 - l2;
            const E: f32 = -1e-5;
            if l1 >= E && l2 >= E && l3 >= E {
                let z = l1 * a[2] + l2 * b[2] + l3 * c[2];
                best = Some(best.map_or(z, |m: f32| m.max(z)));
            }
        }
        best.or_else(|| self.nearest_height(x, y))
    }

    /// Height (m) of the vertex nearest to `(x, y)` in plan, or `None` for an empty mesh.
    /// A coarse lookup, O(vertices); [`TerrainMesh::height_at`] gives the drawn surface.
    pub fn nearest_height(&self, x: f32, y: f32) -> Option<f32> {
        self.positions
            .iter()
            .min_by(|a, b| {
                let da = (a[0] - x).powi(2) + (a[1] - y).powi(2);
                let db = (b[0] - x).powi(2) + (b[1] - y).powi(2);
                da.total_cmp(&db)
            })
            .map(|p| p[2])
    }
}

/// Land-cover colouring by elevation and slope (linear RGB albedo).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandCover {
    /// Sea level (m): vertices at or below get a sandy/wet colour.
    pub sea_level: f32,
    /// Tree line (m): above it grass gives way to alpine meadow and rock.
    pub tree_line: f32,
    /// Snow line (m).
    pub snow_line: f32,
    /// Slope (degrees) above which bare rock shows.
    pub rock_slope_deg: f32,
}

impl Default for LandCover {
    fn default() -> Self {
        LandCover { sea_level: f32::NEG_INFINITY, tree_line: 1900.0, snow_line: 2700.0, rock_slope_deg: 42.0 }
    }
}

fn lerp3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

impl LandCover {
    /// Albedo for elevation `z` (m) and unit normal `n`.
    pub fn color(&self, z: f32, n: [f32; 3]) -> [f32; 3] {
        let meadow = [0.20, 0.30, 0.09];
        let alpine = [0.33, 0.34, 0.18];
        let rock = [0.36, 0.34, 0.31];
        let snow = [0.85, 0.87, 0.9];
        let sand = [0.55, 0.5, 0.36];
        let slope = n[2].clamp(-1.0, 1.0).acos().to_degrees();
        if z <= self.sea_level + 0.5 {
            return sand;
        }
        let mut c = lerp3(meadow, alpine, (z - self.tree_line + 150.0) / 300.0);
        c = lerp3(c, rock, (slope - self.rock_slope_deg + 8.0) / 16.0);
        lerp3(c, snow, (z - self.snow_line + 100.0) / 200.0 * (1.0 - (slope - 45.0).max(0.0) / 20.0))
    }
}

/// Albedo (linear RGB) of the forest floor of leaf litter under a closed canopy in
/// [`LandCover::ground_color`] (before its ±12 % mottle); the stand export's ground texture has
/// this colour (`job::export::GROUND_RGB`).
pub const FOREST_FLOOR: [f32; 3] = [0.085, 0.078, 0.045];

/// What lies on the ground at one terrain vertex besides its elevation and slope, each 0..1:
/// the inputs of [`LandCover::ground_color`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ground {
    /// Stream channel: 0 none, 1 a stream of the full width of a cell (from the flow
    /// accumulation, [`stream_strength`]).
    pub stream: f32,
    /// Soil wetness (from the topographic wetness index, [`wetness`]): 1 = wet meadow / seep.
    pub wetness: f32,
    /// Plan canopy cover above the vertex (0 open land, 1 closed forest): forest floor of leaf
    /// litter instead of grass.
    pub canopy: f32,
}

/// Stream strength 0..1 of a cell draining `area_m2` square metres: 0 below 10 ha of
/// contributing area, rising with the logarithm of the area to 1 at 150 ha. (Channel heads of
/// humid Southern Appalachian headwaters lie at ≈ 1–10 ha of contributing area; Montgomery &
/// Dietrich 1988, Nature 336:232–234, for the area–slope threshold of channel initiation.)
pub fn stream_strength(area_m2: f32) -> f32 {
    if !(area_m2 > 0.0) {
        return 0.0;
    }
    ((area_m2.ln() - 100_000f32.ln()) / (1_500_000f32.ln() - 100_000f32.ln())).clamp(0.0, 1.0)
}

/// Wetness 0..1 of a cell with topographic wetness index `twi` = ln(a / tan β) (Beven & Kirkby
/// 1979): 0 at TWI ≤ 7 (well-drained slopes), 1 at TWI ≥ 11 (hollows and valley floors).
pub fn wetness(twi: f32) -> f32 {
    if !twi.is_finite() {
        return 0.0;
    }
    ((twi - 7.0) / 4.0).clamp(0.0, 1.0)
}

fn smooth01(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A deterministic value in 0..1 for the integer cell `(i, j)` and a `salt` (a spatial hash
/// of the cell, then the SplitMix64 finaliser): per-cell variation of ground and canopy.
pub(crate) fn cell_hash(i: i64, j: i64, salt: u64) -> f32 {
    let k = (i.wrapping_mul(73_856_093) ^ j.wrapping_mul(19_349_663)) as u64 ^ salt;
    // (the finaliser's last `z ^ (z >> 31)` does not change the top 24 bits)
    crate::rng::unit_f32(k)
}

/// A small deterministic brightness variation (±1) of a plan position, in cells of ~7 m and
/// ~23 m, so that open land is not one flat colour.
fn mottle(x: f32, y: f32) -> f32 {
    let h = |x: f32, y: f32| cell_hash(x.floor() as i64, y.floor() as i64, 0) * 2.0 - 1.0;
    0.6 * h(x / 7.0, y / 7.0) + 0.4 * h(x / 23.0 + 0.5, y / 23.0 + 0.5)
}

impl LandCover {
    /// Albedo (linear RGB) of the ground at plan position `(x, y)` (m), elevation `z` (m), unit
    /// normal `n` and [`Ground`] `g`: meadow grass in open land (darker, lusher where wet), a
    /// brown forest floor of leaf litter under canopy, bare rock on slopes steeper than
    /// [`LandCover::rock_slope_deg`] (less under forest: roots hold soil), stream water in the
    /// channels, alpine meadow and snow high up as [`LandCover::color`].
    pub fn ground_color(&self, x: f32, y: f32, z: f32, n: [f32; 3], g: &Ground) -> [f32; 3] {
        let grass = [0.16, 0.25, 0.07];
        let wet = [0.09, 0.19, 0.06];
        let floor = FOREST_FLOOR;
        let rock = [0.30, 0.30, 0.28];
        let water = [0.03, 0.06, 0.08];
        let alpine = [0.33, 0.34, 0.18];
        let snow = [0.85, 0.87, 0.9];
        let slope = n[2].clamp(-1.0, 1.0).acos().to_degrees();
        if z <= self.sea_level + 0.5 {
            return [0.55, 0.5, 0.36];
        }
        let m = mottle(x, y);
        let mut c = lerp3(grass, wet, g.wetness);
        c = lerp3(c, alpine, (z - self.tree_line + 150.0) / 300.0);
        c = lerp3(c, floor, smooth01(g.canopy * 1.25));
        c = c.map(|v| v * (1.0 + 0.12 * m));
        let rock_t = smooth01((slope - self.rock_slope_deg + 6.0) / 12.0 + 0.15 * m) * (1.0 - 0.6 * g.canopy);
        c = lerp3(c, rock, rock_t);
        c = lerp3(c, water, 0.7 * g.stream.max(0.0).sqrt() * (1.0 - 0.4 * g.canopy));
        lerp3(c, snow, (z - self.snow_line + 100.0) / 200.0 * (1.0 - (slope - 45.0).max(0.0) / 20.0))
    }
}

/// A regular grid of ground samples to mesh ([`from_ground`]): heights and what lies on the
/// ground per sample, in world coordinates given by its south-west corner.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundGrid {
    /// Elevations (m), row 0 north; NaN: no ground (the quads around it are left out).
    pub heights: Grid<f32>,
    /// Sample spacing east–west (m), > 0.
    pub cell_x: f32,
    /// Sample spacing north–south (m), > 0.
    pub cell_y: f32,
    /// World position (m) of the grid's south-west corner: sample `(c, r)` sits at
    /// `x = origin[0] + (c + 0.5)·cell_x`, `y = origin[1] + (height − r − 0.5)·cell_y`.
    pub origin: [f32; 2],
    /// Stream strength 0..1 per sample ([`stream_strength`]); empty: none.
    pub stream: Vec<f32>,
    /// Wetness 0..1 per sample ([`wetness`]); empty: none.
    pub wetness: Vec<f32>,
    /// Fade into the sky 0..1 per sample ([`TerrainMesh::fade`]); empty: none.
    pub fade: Vec<f32>,
    /// The simulated window's plan rectangle ([`TerrainMesh::focus`]).
    pub focus: Option<([f32; 2], [f32; 2])>,
}

impl GroundGrid {
    /// Height (m) of the surface [`from_ground`] draws over the plan point `(x, y)` (m): the
    /// quad of samples around it split south-west to north-east into two triangles, linear on
    /// each. `None` outside the samples' centres or where a corner has no ground (NaN). A tree
    /// put at this height stands on the drawn ground (issue 32), where the site's own bilinear
    /// elevation ([`crate::conditions::SiteConditions::elevation_at`]) differs from the drawn
    /// triangles by up to a quarter of the quad's twist.
    pub fn height_at(&self, x: f32, y: f32) -> Option<f32> {
        self.quad_height(x, y).filter(|z| z.is_finite())
    }

    /// The ground next to a no-data hole: [`GroundGrid::height_at`] where the quad around
    /// `(x, y)` is drawn, else the mean of those of its four samples that have ground (the quad
    /// at a hole's rim is left out, and a tree standing on a valid cell there stood at the
    /// 0 m a no-data cell holds, deep in the hole: round 34); `None` where none has.
    /// Like [`GroundGrid::height_at`], `None` outside the samples' centres.
    pub fn height_near(&self, x: f32, y: f32) -> Option<f32> {
        let z = self.quad_height(x, y)?;
        if z.is_finite() {
            return Some(z);
        }
        let (w, h) = (self.heights.width, self.heights.height);
        let fc = (x - self.origin[0]) / self.cell_x - 0.5;
        let fr = h as f32 - (y - self.origin[1]) / self.cell_y - 0.5;
        let (c, r) = ((fc as usize).min(w - 2), (fr as usize).min(h - 2));
        let v: Vec<f32> = [(c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1)].iter().map(|&(c, r)| *self.heights.get(c, r)).filter(|z| z.is_finite()).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f32>() / v.len() as f32)
    }

    /// The triangle interpolation of [`GroundGrid::height_at`], NaN where a corner is.
    fn quad_height(&self, x: f32, y: f32) -> Option<f32> {
        let (w, h) = (self.heights.width, self.heights.height);
        if w < 2 || h < 2 || !(self.cell_x > 0.0 && self.cell_y > 0.0) {
            return None;
        }
        let fc = (x - self.origin[0]) / self.cell_x - 0.5;
        let fr = h as f32 - (y - self.origin[1]) / self.cell_y - 0.5;
        if !(fc >= 0.0 && fr >= 0.0 && fc <= (w - 1) as f32 && fr <= (h - 1) as f32) {
            return None;
        }
        let (c, r) = ((fc as usize).min(w - 2), (fr as usize).min(h - 2));
        // east of the west column, north of the south row (r + 1)
        let (u, v) = (fc - c as f32, (r + 1) as f32 - fr);
        let z = |c: usize, r: usize| *self.heights.get(c, r);
        let (sw, se, ne, nw) = (z(c, r + 1), z(c + 1, r + 1), z(c + 1, r), z(c, r));
        let zz = if u >= v { sw + u * (se - sw) + v * (ne - se) } else { sw + v * (nw - sw) + u * (ne - nw) };
        Some(zz)
    }
}

/// Meshes a [`GroundGrid`]: vertices at the samples, normals from central differences, albedo
/// from [`LandCover::ground_color`] with the plan canopy cover `canopy(x, y)` (0..1) of the
/// frame's trees, fade and focus copied. Quads with a NaN corner are left out.
///
/// # Errors
/// [`Error::Invalid`] for a grid smaller than 2 × 2, non-positive spacings, or per-sample lists
/// of another length.
pub fn from_ground(g: &GroundGrid, cover: &LandCover, canopy: &dyn Fn(f32, f32) -> f32) -> Result<TerrainMesh> {
    let inv = |field: &str, value: String, expected: String| Error::Invalid { context: "render::terrain::from_ground".into(), field: field.into(), value, expected };
    let (w, h) = (g.heights.width, g.heights.height);
    let n = w * h;
    if w < 2 || h < 2 || g.heights.data.len() != n {
        return Err(inv("heights", format!("{w} x {h}"), "at least 2 x 2 samples".into()));
    }
    if !(g.cell_x > 0.0 && g.cell_y > 0.0) {
        return Err(inv("cell size", format!("{} x {}", g.cell_x, g.cell_y), "> 0 m".into()));
    }
    for (name, v) in [("stream", &g.stream), ("wetness", &g.wetness), ("fade", &g.fade)] {
        if !v.is_empty() && v.len() != n {
            return Err(inv(name, v.len().to_string(), format!("0 or {n} (one per sample)")));
        }
    }
    let at = |v: &Vec<f32>, i: usize| v.get(i).copied().unwrap_or(0.0);
    let min = g.heights.data.iter().copied().filter(|v| v.is_finite()).fold(f32::INFINITY, f32::min);
    let min = if min.is_finite() { min } else { 0.0 };
    let z = |c: usize, r: usize| {
        let v = *g.heights.get(c, r);
        if v.is_finite() {
            v
        } else {
            min
        }
    };
    let ok = |c: usize, r: usize| g.heights.get(c, r).is_finite();
    let mut m = TerrainMesh { positions: Vec::with_capacity(n), normals: Vec::with_capacity(n), colors: Vec::with_capacity(n), fade: Vec::with_capacity(n), focus: g.focus, grid: Some([w, h]), ..TerrainMesh::default() };
    for r in 0..h {
        for c in 0..w {
            let i = r * w + c;
            let x = g.origin[0] + (c as f32 + 0.5) * g.cell_x;
            let y = g.origin[1] + (h as f32 - r as f32 - 0.5) * g.cell_y;
            // one-sided differences next to missing samples
            let (cl, cr) = (if c > 0 && ok(c - 1, r) { c - 1 } else { c }, if c + 1 < w && ok(c + 1, r) { c + 1 } else { c });
            let (rn, rs) = (if r > 0 && ok(c, r - 1) { r - 1 } else { r }, if r + 1 < h && ok(c, r + 1) { r + 1 } else { r });
            let dzdx = if cr > cl { (z(cr, r) - z(cl, r)) / ((cr - cl) as f32 * g.cell_x) } else { 0.0 };
            let dzdy = if rs > rn { (z(c, rn) - z(c, rs)) / ((rs - rn) as f32 * g.cell_y) } else { 0.0 };
            let nrm = Vec3::new(-dzdx, -dzdy, 1.0).normalize().to_array();
            let zz = z(c, r);
            let gr = Ground { stream: at(&g.stream, i), wetness: at(&g.wetness, i), canopy: canopy(x, y).clamp(0.0, 1.0) };
            m.positions.push([x, y, zz]);
            m.normals.push(nrm);
            m.colors.push(cover.ground_color(x, y, zz, nrm, &gr));
            m.fade.push(at(&g.fade, i).clamp(0.0, 1.0));
        }
    }
    for r in 0..h - 1 {
        for c in 0..w - 1 {
            if !(ok(c, r) && ok(c + 1, r) && ok(c, r + 1) && ok(c + 1, r + 1)) {
                continue;
            }
            let i = |c: usize, r: usize| (r * w + c) as u32;
            let (sw, se, ne, nw) = (i(c, r + 1), i(c + 1, r + 1), i(c + 1, r), i(c, r));
            m.indices.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
        }
    }
    Ok(m)
}

/// A blue–green–yellow–red ramp for overlay values in 0..1 (values outside are clamped).
pub fn overlay_ramp(v: f32) -> [f32; 3] {
    let stops = [[0.05, 0.1, 0.5], [0.05, 0.45, 0.2], [0.85, 0.8, 0.1], [0.7, 0.08, 0.05]];
    let t = v.clamp(0.0, 1.0) * 3.0;
    let i = (t.floor() as usize).min(2);
    lerp3(stops[i], stops[i + 1], t - i as f32)
}

/// Builds the terrain mesh of a height grid (m) with cells of `cell_x` × `cell_y` metres.
///
/// Vertices sit at cell centres (`x = (col + 0.5) · cell_x`, `y = (height − row − 0.5) · cell_y`,
/// grid.rs convention); normals from central differences; colours from `cover`, or from
/// `overlay` (values 0..1 through [`overlay_ramp`], blended 70 % over the land cover) when given.
/// A NaN height (no data) puts its vertex at the grid minimum, and the quads touching it are
/// left out: a hole, not a shaft down to the minimum (round 34).
///
/// # Errors
/// [`Error::Invalid`] for a grid smaller than 2 × 2, non-positive cell sizes or an overlay of
/// another size.
pub fn from_grid(heights: &Grid<f32>, cell_x: f32, cell_y: f32, cover: &LandCover, overlay: Option<&Grid<f32>>) -> Result<TerrainMesh> {
    let inv = |field: &str, value: String, expected: &str| Error::Invalid { context: "render::terrain::from_grid".into(), field: field.into(), value, expected: expected.into() };
    let (w, h) = (heights.width, heights.height);
    if w < 2 || h < 2 || heights.data.len() != w * h {
        return Err(inv("heights", format!("{w} x {h}"), "at least 2 x 2 cells"));
    }
    if !(cell_x > 0.0 && cell_y > 0.0) {
        return Err(inv("cell size", format!("{cell_x} x {cell_y}"), "> 0 m"));
    }
    if let Some(o) = overlay {
        if o.width != w || o.height != h {
            return Err(inv("overlay", format!("{} x {}", o.width, o.height), "the size of the height grid"));
        }
    }
    let min = heights.data.iter().copied().filter(|v| v.is_finite()).fold(f32::INFINITY, f32::min);
    let min = if min.is_finite() { min } else { 0.0 };
    let z = |c: usize, r: usize| {
        let v = *heights.get(c, r);
        if v.is_finite() {
            v
        } else {
            min
        }
    };
    let mut m = TerrainMesh::default();
    for r in 0..h {
        for c in 0..w {
            let x = (c as f32 + 0.5) * cell_x;
            let y = (h as f32 - r as f32 - 0.5) * cell_y;
            let (cl, cr) = (c.saturating_sub(1), (c + 1).min(w - 1));
            let (rn, rs) = (r.saturating_sub(1), (r + 1).min(h - 1));
            let dzdx = (z(cr, r) - z(cl, r)) / ((cr - cl) as f32 * cell_x);
            // row index grows southwards: dz/dy = (north - south) / distance
            let dzdy = (z(c, rn) - z(c, rs)) / ((rs - rn) as f32 * cell_y);
            let n = Vec3::new(-dzdx, -dzdy, 1.0).normalize().to_array();
            let zz = z(c, r);
            let mut col = cover.color(zz, n);
            if let Some(o) = overlay {
                let v = *o.get(c, r);
                if v.is_finite() {
                    col = lerp3(col, overlay_ramp(v), 0.7);
                }
            }
            m.positions.push([x, y, zz]);
            m.normals.push(n);
            m.colors.push(col);
        }
    }
    let ok = |c: u32, r: u32| heights.get(c as usize, r as usize).is_finite();
    for r in 0..h as u32 - 1 {
        for c in 0..w as u32 - 1 {
            // no-data holes stay holes (no walls down to the minimum), as in [`from_ground`]
            if !(ok(c, r) && ok(c + 1, r) && ok(c, r + 1) && ok(c + 1, r + 1)) {
                continue;
            }
            let i = |c: u32, r: u32| r * w as u32 + c;
            // (c, r+1) is south-west; counter-clockwise seen from above
            let (sw, se, ne, nw) = (i(c, r + 1), i(c + 1, r + 1), i(c + 1, r), i(c, r));
            m.indices.extend_from_slice(&[sw, se, ne, sw, ne, nw]);
        }
    }
    Ok(m)
}

/// Builds the terrain mesh of a TIN given as vertices (m) and triangles (indices into
/// `vertices`). Normals are area-weighted averages of the adjacent faces; triangles are
/// re-oriented to face up. `colors` (one per vertex) overrides the land cover when given.
///
/// # Errors
/// [`Error::Invalid`] for an index out of range or a colour list of another length.
pub fn from_tin(vertices: &[[f32; 3]], triangles: &[[u32; 3]], cover: &LandCover, colors: Option<&[[f32; 3]]>) -> Result<TerrainMesh> {
    let n = vertices.len();
    let inv = |field: &str, value: String, expected: String| Error::Invalid { context: "render::terrain::from_tin".into(), field: field.into(), value, expected };
    if let Some(c) = colors {
        if c.len() != n {
            return Err(inv("colors", c.len().to_string(), format!("{n} (one per vertex)")));
        }
    }
    let mut normals = vec![Vec3::ZERO; n];
    let mut indices = Vec::with_capacity(triangles.len() * 3);
    for (k, t) in triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
            return Err(inv(&format!("triangles[{k}]"), bad.to_string(), format!("< {n} (vertex count)")));
        }
        let [a, b, c] = t.map(|i| Vec3::from(vertices[i as usize]));
        let mut fnorm = (b - a).cross(c - a);
        let mut tri = *t;
        if fnorm.z < 0.0 {
            fnorm = -fnorm;
            tri.swap(1, 2);
        }
        for &i in &tri {
            normals[i as usize] += fnorm;
        }
        indices.extend_from_slice(&tri);
    }
    let normals: Vec<[f32; 3]> = normals.iter().map(|v| v.normalize_or(Vec3::Z).to_array()).collect();
    let colors = match colors {
        Some(c) => c.to_vec(),
        None => vertices.iter().zip(&normals).map(|(p, nn)| cover.color(p[2], *nn)).collect(),
    };
    Ok(TerrainMesh { positions: vertices.to_vec(), normals, colors, indices, ..TerrainMesh::default() })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A mesh of `w` × `h` cells of `cell` m ([`from_grid`]) whose cell centres lie on `plane`
    /// (x = (c + 0.5)·cell east, y = (h − 1 − r + 0.5)·cell north).
    pub(crate) fn plane_mesh(w: usize, h: usize, cell: f32, plane: impl Fn(f32, f32) -> f32) -> TerrainMesh {
        let mut g = Grid::filled(w, h, 0.0f32);
        for r in 0..h {
            for c in 0..w {
                *g.get_mut(c, r) = plane((c as f32 + 0.5) * cell, ((h - 1 - r) as f32 + 0.5) * cell);
            }
        }
        from_grid(&g, cell, cell, &LandCover::default(), None).unwrap()
    }

    /// The drawn surface's height on a 35° plane of 30 m cells (z = 0.7·x + 0.1·y): exact
    /// between vertices (linear triangles on a plane), where the nearest vertex is metres off;
    /// outside the mesh the nearest vertex; an empty mesh `None`.
    #[test]
    fn height_at_interpolates_the_drawn_surface() {
        let plane = |x: f32, y: f32| 0.7 * x + 0.1 * y;
        let m = plane_mesh(6, 5, 30.0, plane);
        assert_eq!(m.positions[0], [15.0, 135.0, plane(15.0, 135.0)]);
        for (x, y) in [(29.0, 29.0), (44.9, 100.2), (100.0, 60.0), (15.0, 15.0), (160.0, 130.0)] {
            let z = m.height_at(x, y).unwrap();
            assert!((z - plane(x, y)).abs() < 1e-3, "({x}, {y}): {z} vs {}", plane(x, y));
        }
        // half a cell from a vertex the nearest vertex is 0.7·15 = 10.5 m off: an eye 1.7 m over
        // it stood under the drawn slope
        assert!((m.nearest_height(29.0, 29.0).unwrap() - plane(29.0, 29.0)).abs() > 5.0);
        assert_eq!(m.height_at(-50.0, 15.0), m.nearest_height(-50.0, 15.0));
        let empty = TerrainMesh { positions: vec![], normals: vec![], colors: vec![], indices: vec![], fade: vec![], focus: None, grid: None };
        assert_eq!(empty.height_at(0.0, 0.0), None);
    }

    #[test]
    fn plane_grid_has_analytic_normals_and_positions() {
        // z = 0.5·x (slope 26.57° facing west)
        let (w, h, cell) = (5, 4, 10.0f32);
        let mut g = Grid::filled(w, h, 0.0f32);
        for r in 0..h {
            for c in 0..w {
                *g.get_mut(c, r) = 0.5 * (c as f32 + 0.5) * cell;
            }
        }
        let m = from_grid(&g, cell, cell, &LandCover::default(), None).unwrap();
        m.validate().unwrap();
        assert_eq!(m.triangle_count(), 2 * (w - 1) * (h - 1));
        // row 0 is north: its y is the largest
        assert_eq!(m.positions[0], [5.0, 35.0, 2.5]);
        let want = Vec3::new(-0.5, 0.0, 1.0).normalize();
        for n in &m.normals {
            assert!((Vec3::from(*n) - want).length() < 1e-5, "{n:?}");
        }
        // triangles face up (counter-clockwise from above)
        for t in m.indices.chunks(3) {
            let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(m.positions[t[k] as usize]));
            assert!((b - a).cross(c - a).z > 0.0);
        }
    }

    #[test]
    fn tin_normals_and_orientation() {
        let v = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [10.0, 10.0, 0.0]];
        let t = [[0, 2, 1], [1, 2, 3]]; // first one clockwise from above
        let m = from_tin(&v, &t, &LandCover::default(), None).unwrap();
        for n in &m.normals {
            assert_eq!(*n, [0.0, 0.0, 1.0]);
        }
        assert_eq!(&m.indices[..3], &[0, 1, 2]);
        assert!(from_tin(&v, &[[0, 1, 9]], &LandCover::default(), None).is_err());
    }

    #[test]
    fn ground_colours_follow_land_cover() {
        let lc = LandCover::default();
        let flat = [0.0, 0.0, 1.0];
        let steep = [0.8, 0.0, 0.6]; // 53°
        let open = lc.ground_color(10.0, 10.0, 800.0, flat, &Ground::default());
        assert!(open[1] > open[0] && open[1] > open[2], "grass is green: {open:?}");
        let forest = lc.ground_color(10.0, 10.0, 800.0, flat, &Ground { canopy: 1.0, ..Ground::default() });
        assert!(forest[0] > forest[1] && forest[1] > forest[2], "forest floor is brown: {forest:?}");
        let rock = lc.ground_color(10.0, 10.0, 800.0, steep, &Ground::default());
        assert!((rock[0] - rock[1]).abs() < 0.03 && rock[0] > 0.25, "bare rock is grey: {rock:?}");
        let stream = lc.ground_color(10.0, 10.0, 800.0, flat, &Ground { stream: 1.0, ..Ground::default() });
        assert!(stream.iter().sum::<f32>() < 0.6 * open.iter().sum::<f32>() && stream[2] >= stream[0], "water is dark and bluish: {stream:?}");
        // streams start at 10 ha and are full at 150 ha; wetness from TWI 7 to 11
        assert_eq!(stream_strength(90_000.0), 0.0);
        assert!((stream_strength(1_500_000.0) - 1.0).abs() < 1e-5);
        let mid = stream_strength((100_000f32 * 1_500_000.0).sqrt());
        assert!((mid - 0.5).abs() < 1e-3, "{mid}");
        assert_eq!((wetness(6.0), wetness(9.0), wetness(12.0), wetness(f32::NAN)), (0.0, 0.5, 1.0, 0.0));
    }

    #[test]
    fn ground_grid_skips_missing_samples_and_focuses_bounds() {
        // 4 x 3 samples of 10 m, one missing corner sample; the focus covers the two west columns
        let mut hts = Grid::filled(4, 3, 100.0f32);
        *hts.get_mut(3, 0) = f32::NAN;
        *hts.get_mut(0, 2) = 50.0;
        let g = GroundGrid { heights: hts, cell_x: 10.0, cell_y: 10.0, origin: [-20.0, -10.0], stream: vec![], wetness: vec![], fade: vec![0.5; 12], focus: Some(([-20.0, -10.0], [0.0, 20.0])) };
        let m = from_ground(&g, &LandCover::default(), &|_, _| 0.0).unwrap();
        m.validate().unwrap();
        // 3 x 2 quads, the one touching the missing sample left out
        assert_eq!(m.triangle_count(), 2 * 5);
        assert_eq!(m.positions[0], [-15.0, 15.0, 100.0]);
        assert_eq!(m.fade_at(7), 0.5);
        let (lo, hi) = m.bounds();
        assert_eq!((lo, hi), ([-15.0, -5.0, 50.0], [-5.0, 15.0, 100.0]));
        assert_eq!(m.full_bounds().1[0], 15.0);
        let bad = GroundGrid { stream: vec![0.0; 3], ..g };
        assert!(from_ground(&bad, &LandCover::default(), &|_, _| 0.0).is_err());
    }

    #[test]
    fn land_cover_rock_and_snow() {
        let lc = LandCover::default();
        let flat = [0.0, 0.0, 1.0];
        let steep = [0.8, 0.0, 0.6]; // 53°
        let meadow = lc.color(500.0, flat);
        assert!(meadow[1] > meadow[0] && meadow[1] > meadow[2]);
        let rock = lc.color(500.0, steep);
        assert!((rock[0] - 0.36).abs() < 1e-3);
        let snow = lc.color(3200.0, flat);
        assert!(snow[2] > 0.8);
        assert_eq!(overlay_ramp(-1.0), overlay_ramp(0.0));
    }
}
