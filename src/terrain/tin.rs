//! Triangulated irregular network (TIN): a Delaunay triangulation (`spade`) of an
//! error-bounded subset of the grid's cell centres.
//!
//! Greedy insertion after Garland & Heckbert (1995, "Fast polygonal approximation of terrains
//! and height fields", CMU-CS-95-181, algorithm III): start from the four corner cells; each
//! round finds, for every triangle, the grid point with the largest vertical error
//! |z − plane(x, y)| inside it, and inserts all those whose error exceeds the tolerance (the
//! batched variant; Garland & Heckbert insert one point per step). Triangles are keyed by their
//! vertex triple so that each is scanned once. Stops when the largest error ≤ tolerance or at
//! the vertex limit.
//!
//! Coordinates are world metres (x east, y north, origin at the grid's south-west corner;
//! cell centres at `((c + 0.5)·dx, (h − r − 0.5)·dy)`, dx the mean east–west cell size).
//! Invalid (NaN) cells are not vertices' error targets; where a vertex falls on one it takes
//! the lowest valid elevation.

use super::Terrain;
use crate::error::{Error, Result};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};
use std::collections::HashMap;

/// Default vertical tolerance (m) used by `sylva terrain info`.
pub const DEFAULT_TOLERANCE_M: f64 = 2.0;

#[derive(Debug, Clone, Copy)]
struct V {
    p: Point2<f64>,
    z: f64,
}

impl HasPosition for V {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.p
    }
}

/// An error-bounded TIN of a terrain.
pub struct Tin {
    tri: DelaunayTriangulation<V>,
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Largest vertical error (m) of the TIN against the valid grid cells.
    pub max_error_m: f64,
    /// The tolerance (m) it was built for.
    pub tolerance_m: f64,
}

impl std::fmt::Debug for Tin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Tin({} vertices, {} triangles, max error {:.3} m)", self.vertices.len(), self.triangles.len(), self.max_error_m)
    }
}

/// Worst cell (index, error m) inside the triangle with corners `p` (grid coordinates col,row
/// of cell centres) and heights `z`.
fn worst_in(z: &[f32], w: usize, h: usize, p: [[f64; 2]; 3], zv: [f64; 3]) -> (u32, f32) {
    let (x0, y0) = (p[0][0], p[0][1]);
    let (ax, ay, bx, by) = (p[1][0] - x0, p[1][1] - y0, p[2][0] - x0, p[2][1] - y0);
    let det = ax * by - ay * bx;
    if det.abs() < 1e-12 {
        return (0, 0.0);
    }
    let cmin = p.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as usize;
    let cmax = (p.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max).floor() as usize).min(w - 1);
    let rmin = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as usize;
    let rmax = (p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max).floor() as usize).min(h - 1);
    let mut best = (0u32, 0f32);
    let eps = 1e-9;
    for r in rmin..=rmax {
        for c in cmin..=cmax {
            let (dx, dy) = (c as f64 - x0, r as f64 - y0);
            let u = (dx * by - dy * bx) / det;
            let v = (ax * dy - ay * dx) / det;
            if u < -eps || v < -eps || u + v > 1.0 + eps {
                continue;
            }
            let zz = z[r * w + c];
            if !zz.is_finite() {
                continue;
            }
            let zp = zv[0] + u * (zv[1] - zv[0]) + v * (zv[2] - zv[0]);
            let e = (zz as f64 - zp).abs() as f32;
            if e > best.1 {
                best = ((r * w + c) as u32, e);
            }
        }
    }
    best
}

impl Tin {
    /// Builds the TIN of `t` with largest vertical error ≤ `tolerance_m` (m), or stops at
    /// `max_vertices` (then [`Tin::max_error_m`] says what was reached).
    ///
    /// Errors: [`Error::Invalid`] for a tolerance not ≥ 0, a grid under 2 × 2 cells, or a
    /// triangulation failure.
    pub fn build(t: &Terrain, tolerance_m: f64, max_vertices: usize) -> Result<Tin> {
        let g = &t.elevation;
        let (w, h) = (g.width, g.height);
        let bad = |f: &str, v: String, e: &str| Error::Invalid { context: format!("TIN of {}", t.source), field: f.into(), value: v, expected: e.into() };
        if !(tolerance_m >= 0.0) {
            return Err(bad("tolerance_m", tolerance_m.to_string(), ">= 0 metres"));
        }
        if w < 2 || h < 2 {
            return Err(bad("grid", format!("{w} x {h}"), "at least 2 x 2 cells"));
        }
        let zmin = g.data.iter().filter(|v| v.is_finite()).fold(f64::INFINITY, |a, &v| a.min(v as f64));
        let zmin = if zmin.is_finite() { zmin } else { 0.0 };
        let dx = (0..h).map(|r| t.geo.cell_x_m_at_row(r)).sum::<f64>() / h as f64;
        let dy = t.geo.cell_y_m();
        let zat = |i: usize| -> f64 {
            let v = g.data[i];
            if v.is_finite() { v as f64 } else { zmin }
        };
        let world = |i: usize| Point2::new(((i % w) as f64 + 0.5) * dx, ((h - i / w) as f64 - 0.5) * dy);
        let mut tri: DelaunayTriangulation<V> = DelaunayTriangulation::new();
        let mut cell_of: Vec<u32> = Vec::new();
        let mut insert = |tri: &mut DelaunayTriangulation<V>, i: usize| -> Result<()> {
            tri.insert(V { p: world(i), z: zat(i) }).map_err(|e| bad("vertex", format!("cell {i}"), &format!("insertable ({e:?})")))?;
            cell_of.push(i as u32);
            Ok(())
        };
        for i in [0, w - 1, (h - 1) * w, h * w - 1] {
            insert(&mut tri, i)?;
        }
        let mut cache: HashMap<[u32; 3], (u32, f32)> = HashMap::new();
        let max_error_m;
        loop {
            let faces: Vec<([u32; 3], [[f64; 2]; 3], [f64; 3])> = tri
                .inner_faces()
                .map(|f| {
                    let vs = f.vertices();
                    let mut key = vs.map(|v| v.fix().index() as u32);
                    key.sort_unstable();
                    let p = vs.map(|v| {
                        let q = v.position();
                        [q.x / dx - 0.5, h as f64 - 0.5 - q.y / dy]
                    });
                    (key, p, vs.map(|v| v.data().z))
                })
                .collect();
            let fresh: Vec<([u32; 3], (u32, f32))> = faces.par_iter().filter(|(k, _, _)| !cache.contains_key(k)).map(|(k, p, z)| (*k, worst_in(&g.data, w, h, *p, *z))).collect();
            cache.extend(fresh);
            let mut next: HashMap<[u32; 3], (u32, f32)> = HashMap::with_capacity(faces.len());
            let mut cand: Vec<u32> = Vec::new();
            let mut worst = 0f32;
            for (k, _, _) in &faces {
                if let Some(&v) = cache.get(k) {
                    next.insert(*k, v);
                    worst = worst.max(v.1);
                    if v.1 as f64 > tolerance_m {
                        cand.push(v.0);
                    }
                }
            }
            cache = next;
            if cand.is_empty() || tri.num_vertices() >= max_vertices {
                max_error_m = worst as f64;
                break;
            }
            cand.sort_unstable();
            cand.dedup();
            for i in cand.into_iter().take(max_vertices.saturating_sub(tri.num_vertices())) {
                insert(&mut tri, i as usize)?;
            }
        }
        let vertices: Vec<[f64; 3]> = tri.vertices().map(|v| [v.position().x, v.position().y, v.data().z]).collect();
        let triangles: Vec<[u32; 3]> = tri.inner_faces().map(|f| f.vertices().map(|v| v.fix().index() as u32)).collect();
        Ok(Tin { tri, vertices, triangles, max_error_m, tolerance_m })
    }

    /// Vertices `[x, y, z]` (m, world coordinates).
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }
    /// Triangles as counter-clockwise (seen from above) vertex index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }
    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    fn face_at(&self, x: f64, y: f64) -> Option<[[f64; 3]; 3]> {
        let fh = match self.tri.locate(Point2::new(x, y)) {
            PositionInTriangulation::OnFace(f) => self.tri.face(f),
            PositionInTriangulation::OnEdge(e) => {
                let e = self.tri.directed_edge(e);
                e.face().as_inner().or_else(|| e.rev().face().as_inner())?
            }
            PositionInTriangulation::OnVertex(v) => self.tri.vertex(v).out_edges().find_map(|e| e.face().as_inner())?,
            _ => return None,
        };
        Some(fh.vertices().map(|v| [v.position().x, v.position().y, v.data().z]))
    }

    /// Height (m) of the TIN at world point `(x, y)` (m), linear within the triangle; `None`
    /// outside the convex hull of the cell centres.
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let [a, b, c] = self.face_at(x, y)?;
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if det.abs() < 1e-12 {
            return Some(a[2]);
        }
        let u = ((x - a[0]) * (c[1] - a[1]) - (y - a[1]) * (c[0] - a[0])) / det;
        let v = ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) / det;
        Some(a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]))
    }

    /// Unit upward normal of the triangle under `(x, y)`; `None` outside the hull.
    pub fn normal_at(&self, x: f64, y: f64) -> Option<[f64; 3]> {
        let [a, b, c] = self.face_at(x, y)?;
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let mut n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        if n[2] < 0.0 {
            n = n.map(|x| -x);
        }
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        (l > 0.0).then(|| n.map(|x| x / l))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GeoRef, Grid};

    fn terrain(w: usize, h: usize, cell: f64, f: impl Fn(f64, f64) -> f32) -> Terrain {
        let mut data = Vec::new();
        for r in 0..h {
            for c in 0..w {
                data.push(f((c as f64 + 0.5) * cell, (h as f64 - r as f64 - 0.5) * cell));
            }
        }
        Terrain { elevation: Grid { width: w, height: h, data }, geo: GeoRef::local(cell, 45.0), nodata: None, source: "test".into() }
    }

    #[test]
    fn plane_needs_only_corners() {
        let t = terrain(50, 40, 10.0, |x, y| (100.0 + 0.3 * x - 0.2 * y) as f32);
        let tin = Tin::build(&t, 0.01, usize::MAX).unwrap();
        assert_eq!(tin.num_vertices(), 4);
        assert_eq!(tin.num_triangles(), 2);
        let z = tin.height_at(123.0, 222.0).unwrap();
        assert!((z - (100.0 + 0.3 * 123.0 - 0.2 * 222.0)).abs() < 1e-3, "{z}");
        let n = tin.normal_at(123.0, 222.0).unwrap();
        let l = (0.3f64 * 0.3 + 0.2 * 0.2 + 1.0).sqrt();
        assert!((n[0] + 0.3 / l).abs() < 1e-4 && (n[1] - 0.2 / l).abs() < 1e-4 && (n[2] - 1.0 / l).abs() < 1e-4);
    }

    #[test]
    fn error_bound_holds_on_every_cell() {
        let t = terrain(64, 64, 5.0, |x, y| (200.0 + 20.0 * (x / 40.0).sin() * (y / 55.0).cos() + 0.05 * x) as f32);
        for tol in [0.5, 2.0] {
            let tin = Tin::build(&t, tol, usize::MAX).unwrap();
            assert!(tin.max_error_m <= tol);
            let mut worst = 0f64;
            for r in 0..64 {
                for c in 0..64 {
                    let (x, y) = ((c as f64 + 0.5) * 5.0, (64.0 - r as f64 - 0.5) * 5.0);
                    let z = tin.height_at(x, y).unwrap();
                    worst = worst.max((z - *t.elevation.get(c, r) as f64).abs());
                }
            }
            assert!(worst <= tol + 1e-4, "tol {tol}: worst {worst}");
            assert!(tin.num_vertices() < 64 * 64 / 2, "{}", tin.num_vertices());
        }
    }
}
