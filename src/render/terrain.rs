//! Terrain meshes for the renderer: from a height grid or a TIN, coloured by land cover
//! (elevation and slope) or by an overlay field.

use glam::Vec3;

use super::scene::TerrainMesh;
use crate::grid::Grid;
use crate::{Error, Result};

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
