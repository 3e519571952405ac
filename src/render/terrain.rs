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
}

impl TerrainMesh {
    /// Axis-aligned bounds `(min, max)` in metres; a unit box at the origin for an empty mesh.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut it = self.positions.iter();
        let Some(&first) = it.next() else { return ([0.0; 3], [1.0; 3]) };
        let (mut lo, mut hi) = (first, first);
        for p in it {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
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
        if self.indices.len() % 3 != 0 {
            return Err(bad("indices", self.indices.len().to_string(), "a multiple of 3".into()));
        }
        if let Some(&i) = self.indices.iter().find(|&&i| i as usize >= n) {
            return Err(bad("indices", i.to_string(), format!("< {n} (vertex count)")));
        }
        Ok(())
    }

    /// Height (m) of the vertex nearest to `(x, y)` in plan, or `None` for an empty mesh.
    /// A coarse lookup for camera placement, O(vertices).
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
        LandCover { sea_level: f32::NEG_INFINITY, tree_line: 1900.0, snow_line: 2700.0, rock_slope_deg: 38.0 }
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
/// NaN heights are replaced by the grid minimum.
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
    for r in 0..h as u32 - 1 {
        for c in 0..w as u32 - 1 {
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
    Ok(TerrainMesh { positions: vertices.to_vec(), normals, colors, indices })
}

#[cfg(test)]
mod tests {
    use super::*;

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
