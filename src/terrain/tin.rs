//! Triangulated irregular network (TIN): a Delaunay triangulation (`spade`) of an
//! error-bounded subset of the grid's cell centres.
//!
//! Greedy insertion after Garland & Heckbert (1995, "Fast polygonal approximation of terrains
//! and height fields", CMU-CS-95-181, algorithm III): start from the four corner cells; every
//! triangle's worst grid point (largest vertical error |z − plane(x, y)|) sits in a priority
//! queue; the worst of all is inserted, one point per step, and only the triangles around the
//! new vertex (all that Delaunay insertion creates) are rescanned; queue entries of destroyed
//! triangles (identified by their vertex triple) are dropped when popped. Stops when the largest
//! error ≤ tolerance or at the vertex limit.
//!
//! Coordinates are world metres (x east, y north, origin at the grid's south-west corner;
//! cell centres at `((c + 0.5)·dx, (h − r − 0.5)·dy)`, dx the mean east–west cell size).
//! Invalid (NaN) cells are not vertices' error targets; where a vertex falls on one it takes
//! the lowest valid elevation.

use super::Terrain;
use crate::error::{Error, Result};
use spade::handles::FixedVertexHandle;
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Default vertical tolerance (m) used by `sylva terrain info`.
pub const DEFAULT_TOLERANCE_M: f64 = 5.0;

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
/// of cell centres) and heights `z`: a scanline walk over the triangle's rows, each row's column
/// span found from the three barycentric coordinates (linear in the column), the plane height
/// advanced by one addition per cell.
fn worst_in(z: &[f32], w: usize, h: usize, p: [[f64; 2]; 3], zv: [f64; 3]) -> (u32, f32) {
    let (x0, y0) = (p[0][0], p[0][1]);
    let (ax, ay, bx, by) = (p[1][0] - x0, p[1][1] - y0, p[2][0] - x0, p[2][1] - y0);
    let det = ax * by - ay * bx;
    if det.abs() < 1e-12 {
        return (0, 0.0);
    }
    let rmin = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as usize;
    let rmax = (p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max).floor().max(0.0) as usize).min(h - 1);
    let cmin = p.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min).ceil().max(0.0);
    let cmax = p.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max).floor().min((w - 1) as f64);
    // u = (dx·by − dy·bx)/det, v = (ax·dy − ay·dx)/det with dx = c − x0, dy = r − y0.
    let (uc, vc) = (by / det, -ay / det);
    let (dz1, dz2) = (zv[1] - zv[0], zv[2] - zv[0]);
    let zc = uc * dz1 + vc * dz2;
    let eps = 1e-9;
    let mut best = (0u32, 0f32);
    for r in rmin..=rmax {
        let dy = r as f64 - y0;
        // values at c = x0 (dx = 0)
        let (u0, v0) = (-dy * bx / det, ax * dy / det);
        let (mut lo, mut hi) = (cmin, cmax);
        // each coordinate a + b·(c − x0) ≥ −eps
        for (a, b) in [(u0, uc), (v0, vc), (1.0 - u0 - v0, -uc - vc)] {
            if b > 0.0 {
                lo = lo.max(x0 + (-eps - a) / b);
            } else if b < 0.0 {
                hi = hi.min(x0 + (-eps - a) / b);
            } else if a < -eps {
                hi = f64::NEG_INFINITY;
            }
        }
        let (lo, hi) = (lo.ceil(), hi.floor());
        if !(lo <= hi) {
            continue;
        }
        let (c0, c1) = (lo as usize, hi as usize);
        let row = &z[r * w..(r + 1) * w];
        let mut zp = zv[0] + (u0 + uc * (c0 as f64 - x0)) * dz1 + (v0 + vc * (c0 as f64 - x0)) * dz2;
        for (c, &zz) in row[c0..=c1].iter().enumerate() {
            let e = (zz as f64 - zp).abs() as f32;
            // NaN cells compare false and are skipped
            if e > best.1 {
                best = ((r * w + c0 + c) as u32, e);
            }
            zp += zc;
        }
    }
    best
}

/// Sorted vertex triple of a face: its identity across insertions.
fn face_key(vs: [u32; 3]) -> [u32; 3] {
    let mut k = vs;
    k.sort_unstable();
    k
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
        let insert = |tri: &mut DelaunayTriangulation<V>, i: usize| -> Result<()> {
            tri.insert(V { p: world(i), z: zat(i) }).map_err(|e| bad("vertex", format!("cell {i}"), &format!("insertable ({e:?})")))?;
            Ok(())
        };
        for i in [0, w - 1, (h - 1) * w, h * w - 1] {
            insert(&mut tri, i)?;
        }
        let grid_xy = |q: Point2<f64>| [q.x / dx - 0.5, h as f64 - 0.5 - q.y / dy];
        // Candidates: (error bits, smaller cell first, face key). Non-negative f32 errors order
        // like their bit patterns. Entries of faces destroyed by later insertions go stale and
        // are skipped when popped.
        let mut heap: BinaryHeap<(u32, Reverse<u32>, [u32; 3])> = BinaryHeap::new();
        let scan = |f: spade::handles::FaceHandle<'_, spade::handles::InnerTag, V, (), (), ()>| {
            let vs = f.vertices();
            let key = face_key(vs.map(|v| v.fix().index() as u32));
            let (cell, err) = worst_in(&g.data, w, h, vs.map(|v| grid_xy(v.position())), vs.map(|v| v.data().z));
            (err.to_bits(), Reverse(cell), key)
        };
        for f in tri.inner_faces() {
            heap.push(scan(f));
        }
        let alive = |tri: &DelaunayTriangulation<V>, k: [u32; 3]| -> bool {
            let (a, b, c) = (FixedVertexHandle::from_index(k[0] as usize), FixedVertexHandle::from_index(k[1] as usize), k[2] as usize);
            match tri.get_edge_from_neighbors(a, b) {
                Some(e) => [e, e.rev()].iter().any(|e| e.face().as_inner().is_some() && e.opposite_vertex().map(|v| v.fix().index()) == Some(c)),
                None => false,
            }
        };
        let mut max_error_m = 0.0;
        while let Some((bits, Reverse(cell), key)) = heap.pop() {
            if !alive(&tri, key) {
                continue;
            }
            let err = f32::from_bits(bits) as f64;
            max_error_m = err;
            if err <= tolerance_m || tri.num_vertices() >= max_vertices {
                break;
            }
            insert(&mut tri, cell as usize)?;
            let vh = FixedVertexHandle::from_index(tri.num_vertices() - 1);
            for e in tri.vertex(vh).out_edges() {
                if let Some(f) = e.face().as_inner() {
                    heap.push(scan(f));
                }
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
