//! The mid-level (LOD2) crown hull of an adapted tree built from its adapted leaf clusters
//! (issue 14, Build 3): the union of the cluster spheres of Plastic Trees (Pirk et al. 2012,
//! section 5.2: each terminal lobe's cluster, its centre moved with its nodes and its radius cut
//! by obstacles, Fig. 4) shrink-wrapped onto an icosphere by casting rays from the crown centre.
//!
//! Why from the clusters: they are what the adaptation moved and cut, so a crown pushed away from
//! a wall or into a gap of the canopy keeps that shape at the mid level, where
//! [`crate::structure::mesh::hull_mesh`] would only follow the leaf cards' support function per
//! height band. The hull is star-shaped about the crown centre (the clusters' volume-weighted
//! mean), closed, outward-facing, with [`HULL_VERTICES`] vertices and [`HULL_TRIANGLES`]
//! triangles at the default [`HULL_SUBDIVISIONS`].
//!
//! Construction, per icosphere vertex direction `v` (unit) from the centre `c`:
//! 1. **Ray cast**: `R(v)` = the farthest exit `t = b + √(b² − |q|² + (r+g)²)`, `b = q·v`, of the
//!    ray `c + t·v` from any cluster sphere `(c + q, r)` grown by the gap `g` ([`gap_fill`]) that
//!    it meets (0 when it meets none);
//! 2. **Every cluster centre inside**: for each cluster at distance `D = |q|` and each vertex within
//!    the icosphere's longest edge angle `E` of its direction, `R(v) ≥ D / cos E`. A direction lies
//!    in a triangle of the icosphere whose corners are all within `E` of it, so the flat triangle
//!    over those corners passes at least `D` from the centre along it: the polyhedron contains
//!    the centre;
//! 3. **Smoothed**: [`SMOOTHING_PASSES`] passes of `R(v) ← ½ R(v) + ½ (mean R of its
//!    neighbours)`, never below the least radius of step 2 nor a quarter of the mean grown
//!    cluster radius (a ray between clusters, or towards a wall that took the foliage, does not
//!    collapse the surface to a spike); so every cluster centre stays inside.
//!
//! The LOD2 level itself ([`cluster_hull_mesh`]) is, since round 35, the hull of the same
//! clusters by height ([`cluster_band_hull`]: rings of height slabs about the main stem), not
//! this icosphere: star-shaped about one centre, the icosphere pinched the tall, narrow cones of
//! spruce in their middle like an hourglass.

use super::mesh::{hull_stem, LodOptions};
use super::plastic::LeafCluster;
use super::skeleton::Skeleton;
use crate::mesh::{TreeMesh, TriMesh};
use glam::Vec3;
use std::collections::HashMap;
use std::f32::consts::TAU;

/// Subdivisions of the icosahedron the hull is wrapped onto (2: 162 vertices, 320 triangles).
pub const HULL_SUBDIVISIONS: u32 = 2;
/// Vertices of a hull at [`HULL_SUBDIVISIONS`] (10·4^s + 2).
pub const HULL_VERTICES: usize = 162;
/// Triangles of a hull at [`HULL_SUBDIVISIONS`] (20·4^s).
pub const HULL_TRIANGLES: usize = 320;
/// Clusters more translucent than this (γ_c of eqs. 4 and 13, 0–1: a cluster that lost nearly
/// all its nodes lets nearly all light through) are left out of the hull.
pub const HULL_MAX_GAMMA: f32 = 0.98;
/// Smoothing passes over the hull's radii (each: half the vertex's own, half its neighbours'
/// mean).
pub const SMOOTHING_PASSES: usize = 2;

/// The gap (m) the cluster spheres are grown by before they are wrapped: the median distance
/// from a cluster centre to its nearest neighbour (0 for a single cluster). Terminal lobes are
/// small (≈ 0.4 m on a 4 m crown) and a few metres apart, so their bare union is a spray of
/// balls; grown by the gap they merge into one crown with a lump per cluster.
pub fn gap_fill(clusters: &[(Vec3, f32)]) -> f32 {
    let mut nn: Vec<f32> = clusters
        .iter()
        .enumerate()
        .filter_map(|(i, (a, _))| clusters.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, (b, _))| a.distance(*b)).min_by(f32::total_cmp))
        .collect();
    if nn.is_empty() {
        return 0.0;
    }
    nn.sort_by(f32::total_cmp);
    nn[nn.len() / 2]
}

/// The clusters of `leaf` that carry foliage, as (centre (m), radius (m)) in the clusters'
/// frame: alive nodes, radius > 0 (not deleted by an obstacle), leaf density > 0 (eq. 12) and
/// translucency γ_c ≤ [`HULL_MAX_GAMMA`]; finite only; in the given order.
pub fn foliage_clusters(leaf: &[LeafCluster]) -> Vec<(Vec3, f32)> {
    leaf.iter()
        .filter(|c| c.alive_nodes > 0 && c.radius > 0.0 && c.density > 0.0 && c.gamma <= HULL_MAX_GAMMA && c.center.is_finite() && c.radius.is_finite())
        .map(|c| (c.center, c.radius))
        .collect()
}

/// A unit icosphere: `(vertices, triangles)`, the icosahedron's faces split `subdivisions`
/// times into four (edge midpoints pushed onto the sphere), counter-clockwise seen from outside;
/// 10·4^s + 2 vertices and 20·4^s triangles.
pub fn icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [[-1.0, t, 0.0], [1.0, t, 0.0], [-1.0, -t, 0.0], [1.0, -t, 0.0], [0.0, -1.0, t], [0.0, 1.0, t], [0.0, -1.0, -t], [0.0, 1.0, -t], [t, 0.0, -1.0], [t, 0.0, 1.0], [-t, 0.0, -1.0], [-t, 0.0, 1.0]]
        .iter()
        .map(|p| Vec3::from(*p).normalize())
        .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for tri in &f {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    v.push((v[a as usize] + v[b as usize]).normalize());
                    (v.len() - 1) as u32
                });
            }
            next.extend_from_slice(&[[tri[0], m[0], m[2]], [tri[1], m[1], m[0]], [tri[2], m[2], m[1]], [m[0], m[1], m[2]]]);
        }
        f = next;
    }
    (v, f)
}

/// A crown hull ([`cluster_hull`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CrownHull {
    /// The closed hull: positions (m, the clusters' frame), outward area-weighted normals, UVs
    /// (u = azimuth / 2π, v = (1 + z of the direction) / 2), counter-clockwise from outside.
    pub mesh: TriMesh,
    /// The crown centre the rays start from (m): the clusters' mean weighted by r³.
    pub centre: Vec3,
    /// Clusters wrapped.
    pub clusters: usize,
}

/// Shrink-wraps the union of the spheres `clusters` (centre (m), radius (m); radius ≤ 0 or
/// non-finite ones ignored) onto an icosphere of `subdivisions` (module documentation, steps
/// 1–3). `None` without a usable cluster.
pub fn cluster_hull(clusters: &[(Vec3, f32)], subdivisions: u32) -> Option<CrownHull> {
    let cl: Vec<(Vec3, f32)> = clusters.iter().copied().filter(|(c, r)| c.is_finite() && r.is_finite() && *r > 0.0).collect();
    if cl.is_empty() {
        return None;
    }
    let w: f32 = cl.iter().map(|(_, r)| r * r * r).sum();
    let centre = cl.iter().map(|(c, r)| *c * (r * r * r)).sum::<Vec3>() / w.max(f32::MIN_POSITIVE);
    let (dirs, tris) = icosphere(subdivisions);
    // the longest edge angle E (as its cosine) and the neighbours of each vertex
    let mut cos_e = 1.0f32;
    let mut nbr: Vec<Vec<u32>> = vec![Vec::new(); dirs.len()];
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            cos_e = cos_e.min(dirs[a as usize].dot(dirs[b as usize]));
            if !nbr[a as usize].contains(&b) {
                nbr[a as usize].push(b);
            }
            if !nbr[b as usize].contains(&a) {
                nbr[b as usize].push(a);
            }
        }
    }
    // the gap between neighbouring clusters: their median nearest-neighbour distance
    let gap = gap_fill(&cl);
    // 1. ray cast: the farthest exit from any sphere grown by the gap
    let ray: Vec<f32> = dirs
        .iter()
        .map(|v| {
            cl.iter().fold(0.0f32, |m, (c, r)| {
                let q = *c - centre;
                let b = q.dot(*v);
                let re = r + gap;
                let disc = b * b - q.length_squared() + re * re;
                if disc >= 0.0 {
                    m.max(b + disc.sqrt())
                } else {
                    m
                }
            })
        })
        .collect();
    // 2. every cluster centre inside: the least radius per vertex
    let mut need = vec![0.0f32; dirs.len()];
    for (c, _) in &cl {
        let q = *c - centre;
        let d = q.length();
        if d <= 1e-6 {
            continue;
        }
        let u = q / d;
        let n = d / cos_e.max(0.1) * (1.0 + 1e-4);
        for (k, v) in dirs.iter().enumerate() {
            if v.dot(u) >= cos_e {
                need[k] = need[k].max(n);
            }
        }
    }
    // 3. smoothed (lumps of a few clusters remain), never below the least radius or the floor
    let floor = 0.25 * cl.iter().map(|(_, r)| *r + gap).sum::<f32>() / cl.len() as f32;
    let mut rad: Vec<f32> = ray.iter().zip(&need).map(|(r, n)| r.max(*n).max(floor)).collect();
    for _ in 0..SMOOTHING_PASSES {
        let src = rad.clone();
        for (k, r) in rad.iter_mut().enumerate() {
            let mean = nbr[k].iter().map(|&j| src[j as usize]).sum::<f32>() / nbr[k].len().max(1) as f32;
            *r = (0.5 * src[k] + 0.5 * mean).max(need[k]).max(floor);
        }
    }
    let mut mesh = TriMesh::default();
    for (v, r) in dirs.iter().zip(&rad) {
        mesh.positions.push((centre + *v * *r).to_array());
        mesh.uvs.push([v.y.atan2(v.x) / TAU + 0.5, 0.5 * (1.0 + v.z)]);
    }
    let mut nrm = vec![Vec3::ZERO; dirs.len()];
    for t in &tris {
        let [a, b, c] = t.map(|i| Vec3::from(mesh.positions[i as usize]));
        let f = (b - a).cross(c - a);
        for &i in t {
            nrm[i as usize] += f;
        }
        mesh.indices.extend_from_slice(t);
    }
    // a vertex whose faces cancel (never seen in practice) keeps its ray direction
    mesh.normals = nrm.iter().zip(&dirs).map(|(n, v)| n.try_normalize().unwrap_or(*v).to_array()).collect();
    Some(CrownHull { mesh, centre, clusters: cl.len() })
}

/// Azimuth sectors of [`cluster_band_hull`] (16).
pub const BAND_HULL_SECTORS: usize = 16;
/// Height bands of [`cluster_band_hull`] (7; with a dome ring below and two above, 10 rings:
/// [`HULL_VERTICES`] vertices and [`HULL_TRIANGLES`] triangles, as the icosphere hull).
pub const BAND_HULL_BANDS: usize = 7;

/// The crown hull of the clusters `clusters` (centre (m), radius (m); radius ≤ 0 or
/// non-finite ones ignored; the frame of `sk`) by height (round 35): the crown from the lowest
/// to the highest point of the cluster spheres is cut into [`BAND_HULL_BANDS`] horizontal
/// slabs and [`BAND_HULL_SECTORS`] azimuths about the skeleton's main stem where it crosses
/// each slab's middle ([`super::mesh::main_stem`]; a leaning crown's rings follow it); a
/// slab's ring lies, in each azimuth, at the support function of the discs the spheres cut
/// from the slab (the farthest horizontal reach of any sphere within the slab along that
/// azimuth; a sphere whose centre lies outside the slab counts with its disc at the slab's
/// nearer face), at least 2 % of the widest ring (a one-sided crown's far side closes in
/// near the stem); slabs no sphere reaches take the mean of the filled slabs beside them; one
/// smoothing pass along each ring (½ the radius, ¼ each neighbour: the profile by height is
/// kept as it is). Dome rings round it off as [`super::mesh::hull_mesh`]'s do (one below at
/// 50°, two above at 45° and 75°), a base point on the stem at the lowest height and an apex
/// over the highest sphere's centre at the highest ([`super::mesh::ring_hull`]). So the hull
/// follows the crown's radius at each height, a spruce's cone widest near its crown base;
/// the icosphere of [`cluster_hull`], star-shaped about one centre, pinched a tall narrow
/// crown in its middle like an hourglass (round 34's stand export in Blender: its rays
/// towards the crown's upper and lower parts leave the crown near the stem, and the smoothing
/// over directions pulled the sides in). `None` without a usable cluster.
pub fn cluster_band_hull(sk: &Skeleton, clusters: &[(Vec3, f32)]) -> Option<TriMesh> {
    let cl: Vec<(Vec3, f32)> = clusters.iter().copied().filter(|(c, r)| c.is_finite() && r.is_finite() && *r > 0.0).collect();
    if cl.is_empty() {
        return None;
    }
    let lo = cl.iter().map(|(c, r)| c.z - r).fold(f32::INFINITY, f32::min);
    let hi = cl.iter().map(|(c, r)| c.z + r).fold(f32::NEG_INFINITY, f32::max).max(lo + 1e-3);
    let (nb, nlon) = (BAND_HULL_BANDS, BAND_HULL_SECTORS);
    let dz = (hi - lo) / nb as f32;
    let band_z = |b: usize| lo + (b as f32 + 0.5) * dz;
    let stem = super::mesh::main_stem(sk);
    let centre = cl.iter().map(|(c, _)| *c).sum::<Vec3>() / cl.len() as f32;
    let axis_at = |z: f32| super::mesh::stem_xy_at(&stem, z).map_or(Vec3::new(centre.x, centre.y, z), |v| v.extend(z));
    let band_axis: Vec<Vec3> = (0..nb).map(|b| axis_at(band_z(b))).collect();
    let dirs: Vec<(f32, f32)> = (0..nlon).map(|k| ((k as f32 + 0.5) / nlon as f32 * TAU).sin_cos()).map(|(s, c)| (c, s)).collect();
    // support function per (slab, azimuth); < 0: no sphere reaches the slab
    let mut rad = vec![f32::NEG_INFINITY; nb * nlon];
    for b in 0..nb {
        let (z0, z1) = (band_z(b) - 0.5 * dz, band_z(b) + 0.5 * dz);
        for (c, r) in &cl {
            // the sphere's widest disc within the slab
            let off = if c.z < z0 { z0 - c.z } else if c.z > z1 { c.z - z1 } else { 0.0 };
            if off >= *r {
                continue;
            }
            let disc = (r * r - off * off).sqrt();
            let d = (*c - band_axis[b]).truncate();
            for (k, &(cx, cy)) in dirs.iter().enumerate() {
                let cell = &mut rad[b * nlon + k];
                *cell = cell.max(d.x * cx + d.y * cy + disc);
            }
        }
    }
    let widest = rad.iter().copied().fold(0.0f32, f32::max);
    let floor = (0.02 * widest).max(1e-3);
    let filled: Vec<bool> = (0..nb).map(|b| rad[b * nlon..(b + 1) * nlon].iter().any(|r| r.is_finite())).collect();
    for b in 0..nb {
        if filled[b] {
            rad[b * nlon..(b + 1) * nlon].iter_mut().for_each(|r| *r = r.max(floor));
        }
    }
    crate::structure::mesh::fill_empty_bands(&mut rad, nlon, &filled, floor);
    let src = rad.clone();
    for b in 0..nb {
        for k in 0..nlon {
            let at = |kk: usize| src[b * nlon + kk % nlon];
            rad[b * nlon + k] = (0.5 * at(k) + 0.25 * (at(k + 1) + at(k + nlon - 1))).max(floor);
        }
    }
    let (zb, zt) = (band_z(0), band_z(nb - 1));
    let mut rings: Vec<(f32, Vec3, Vec<f32>)> = Vec::with_capacity(nb + 3);
    let th = 50f32.to_radians();
    rings.push((zb - (zb - lo) * th.sin(), band_axis[0], (0..nlon).map(|k| rad[k] * th.cos()).collect()));
    for b in 0..nb {
        rings.push((band_z(b), band_axis[b], rad[b * nlon..(b + 1) * nlon].to_vec()));
    }
    for deg in [45f32, 75.0] {
        let t = deg.to_radians();
        rings.push((zt + (hi - zt) * t.sin(), band_axis[nb - 1], (0..nlon).map(|k| rad[(nb - 1) * nlon + k] * t.cos()).collect()));
    }
    let top = cl.iter().fold(cl[0], |a, p| if p.0.z + p.1 > a.0.z + a.1 { *p } else { a }).0;
    Some(super::mesh::ring_hull(&rings, nlon, top.with_z(hi), axis_at(lo).with_z(lo)))
}

/// The crown-hull level (LOD2) of an adapted tree from its clusters: the hull by height of
/// `clusters` ([`cluster_band_hull`], the frame of `sk`; round 35, until then the icosphere
/// of [`cluster_hull`], which pinched conical crowns) as foliage, on the stem of
/// [`crate::structure::mesh::hull_mesh`] (5 sides, along the main stem from the root to a
/// quarter of the way up the hull). `None` without a usable cluster (keep the chain's own hull
/// then).
pub fn cluster_hull_mesh(sk: &Skeleton, clusters: &[(Vec3, f32)], o: &LodOptions) -> Option<TreeMesh> {
    let mesh = cluster_band_hull(sk, clusters)?;
    let (lo, hi) = mesh.positions.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| (lo.min(p[2]), hi.max(p[2])));
    Some(TreeMesh { bark: hull_stem(sk, lo + 0.25 * (hi - lo), o), leaves: mesh })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Winding number of the closed mesh `m` about `p` (1 inside, 0 outside): the sum of the
    /// triangles' signed solid angles (Van Oosterom & Strackee 1983) over 4π.
    fn winding(m: &TriMesh, p: Vec3) -> f32 {
        let mut w = 0.0f64;
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| (Vec3::from(m.positions[i as usize]) - p).as_dvec3());
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let num = a.dot(b.cross(c));
            let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            w += 2.0 * num.atan2(den);
        }
        (w / (4.0 * std::f64::consts::PI)) as f32
    }

    /// Volume and volume centroid of a closed mesh (tetrahedra from the origin).
    fn volume_centroid(m: &TriMesh) -> (f32, Vec3) {
        let (mut vol, mut c) = (0.0f32, Vec3::ZERO);
        for t in m.indices.chunks_exact(3) {
            let [a, b, d] = [t[0], t[1], t[2]].map(|i| Vec3::from(m.positions[i as usize]));
            let v = a.dot(b.cross(d)) / 6.0;
            vol += v;
            c += v * (a + b + d) / 4.0;
        }
        (vol, c / vol)
    }

    /// Clusters of a crown around a stem at the origin (crown from 6 to 14 m, radius 4 m), in a
    /// fixed pseudo-random layout, radii 0.35–0.5 m like a stand tree's terminal lobes; `one_sided`: only those east of the stem (x > 0.5 m), as
    /// beside a wall to the west.
    fn crown(one_sided: bool) -> Vec<(Vec3, f32)> {
        let mut out = Vec::new();
        let mut s = 12345u32;
        let mut rnd = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        while out.len() < 60 {
            let (x, y, z) = (rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0, rnd() * 8.0 + 6.0);
            let e = (x * x + y * y) / 16.0 + ((z - 10.0) / 4.0).powi(2);
            if e > 1.0 || (one_sided && x < 0.5) {
                continue;
            }
            out.push((Vec3::new(x, y, z), 0.35 + 0.15 * rnd()));
        }
        out
    }

    #[test]
    fn an_icosphere_has_the_expected_counts_and_is_closed() {
        let (v, f) = icosphere(HULL_SUBDIVISIONS);
        assert_eq!((v.len(), f.len()), (HULL_VERTICES, HULL_TRIANGLES));
        // closed: every edge in exactly two triangles, once each way
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &f {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1)));
        // outward: every face normal points away from the centre
        assert!(f.iter().all(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            (b - a).cross(c - a).dot(a + b + c) > 0.0
        }));
    }

    #[test]
    fn the_hull_of_a_one_sided_crown_is_one_sided_and_holds_every_cluster_centre() {
        for one_sided in [false, true] {
            let cl = crown(one_sided);
            let h = cluster_hull(&cl, HULL_SUBDIVISIONS).unwrap();
            assert_eq!((h.mesh.positions.len(), h.mesh.indices.len() / 3, h.clusters), (HULL_VERTICES, HULL_TRIANGLES, 60));
            // closed and outward: winding number 1 at the centre, 0 far away
            assert!((winding(&h.mesh, h.centre) - 1.0).abs() < 1e-3, "{}", winding(&h.mesh, h.centre));
            assert!(winding(&h.mesh, Vec3::new(30.0, 0.0, 10.0)).abs() < 1e-3);
            for (c, _) in &cl {
                let w = winding(&h.mesh, *c);
                assert!((w - 1.0).abs() < 1e-3, "cluster centre {c} outside the hull (winding {w}, one-sided {one_sided})");
            }
            let lo = h.mesh.positions.iter().fold(Vec3::splat(f32::INFINITY), |a, p| a.min(Vec3::from(*p)));
            let hi = h.mesh.positions.iter().fold(Vec3::splat(f32::NEG_INFINITY), |a, p| a.max(Vec3::from(*p)));
            let slo = cl.iter().fold(Vec3::splat(f32::INFINITY), |a, (c, r)| a.min(*c - Vec3::splat(*r)));
            let shi = cl.iter().fold(Vec3::splat(f32::NEG_INFINITY), |a, (c, r)| a.max(*c + Vec3::splat(*r)));
            let (vol, cen) = volume_centroid(&h.mesh);
            let mean = cl.iter().map(|(c, _)| *c).sum::<Vec3>() / cl.len() as f32;
            // the hull reaches the spheres' extremes (smoothing pulls them in by < 0.3 gap) and
            // overshoots them by at most the gap they were grown by
            let g = gap_fill(&cl);
            assert!(g > 0.5 && g < 1.2, "median nearest-neighbour distance {g} m");
            assert!(lo.cmple(slo + Vec3::splat(0.3 * g)).all() && hi.cmpge(shi - Vec3::splat(0.3 * g)).all(), "hull {lo}..{hi}, spheres {slo}..{shi}");
            assert!(lo.cmpge(slo - Vec3::splat(g + 0.05)).all() && hi.cmple(shi + Vec3::splat(g + 0.05)).all(), "hull {lo}..{hi}, spheres {slo}..{shi}, gap {g}");
            if one_sided {
                // shifted east of the stem like the clusters, by a similar amount
                assert!(mean.x > 1.5, "{mean}");
                assert!(cen.x > 0.6 * mean.x && cen.x < 1.4 * mean.x, "hull centroid {cen}, clusters' mean {mean}");
                assert!(lo.x > -1.0, "nothing reaches the west: {lo}");
                // about half the two-sided crown's (measured 142 against 245 m³)
                // less than half the two-sided crown's (measured 144 against 343 m³)
                assert!(vol > 110.0 && vol < 175.0, "{vol} m³");
            } else {
                assert!(cen.x.abs() < 0.5 && cen.y.abs() < 0.5, "{cen}");
                // near the ellipsoid's 4/3·π·4·4·4 = 268 m³ the clusters fill (measured 245 m³)
                // the ellipsoid's 4/3·π·4·4·4 = 268 m³ grown by the gap (measured 343 m³)
                assert!(vol > 300.0 && vol < 400.0, "{vol} m³");
            }
        }
    }

    #[test]
    fn clusters_without_foliage_are_left_out() {
        let c = |x: f32, radius: f32, alive: usize, gamma: f32, density: f32| LeafCluster { lobe: 0, center: Vec3::new(x, 0.0, 5.0), radius, gamma, input_nodes: 4, alive_nodes: alive, light_input: 1.0, light: 1.0, density };
        let all = [c(1.0, 1.0, 4, 0.5, 1.0), c(2.0, 0.0, 4, 0.5, 0.0), c(3.0, 1.0, 0, 1.0, 0.0), c(4.0, 1.0, 1, 0.99, 0.2), c(5.0, 0.8, 2, 0.7, 0.4)];
        assert_eq!(foliage_clusters(&all), vec![(Vec3::new(1.0, 0.0, 5.0), 1.0), (Vec3::new(5.0, 0.0, 5.0), 0.8)]);
        assert!(cluster_hull(&[], 2).is_none());
        assert!(cluster_hull(&[(Vec3::ZERO, 0.0)], 2).is_none());
        // one sphere: the hull is that sphere (every vertex within 1 % of its surface)
        let h = cluster_hull(&[(Vec3::new(1.0, 2.0, 3.0), 2.0)], 2).unwrap();
        assert!(h.mesh.positions.iter().all(|p| ((Vec3::from(*p) - Vec3::new(1.0, 2.0, 3.0)).length() - 2.0).abs() < 0.02));
        let sk = {
            let mut s = Skeleton::new();
            s.add_root(Vec3::ZERO, 0.2);
            s
        };
        let m = cluster_hull_mesh(&sk, &[(Vec3::new(0.0, 0.0, 6.0), 2.0)], &LodOptions::default()).unwrap();
        let top = m.bark.positions.iter().map(|p| p[2]).fold(0.0f32, f32::max);
        assert!((top - 5.0).abs() < 0.05, "stem to a quarter of the hull's height: {top}");
        assert_eq!(m.leaves.indices.len() / 3, HULL_TRIANGLES);
    }
}
