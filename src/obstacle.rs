//! Solid obstacles, shared by the simulation (a scenario's `[[obstacle]]` entries stamped into
//! the light grid and blocking establishment, `sim::obstacle`), the growth models' voxel space
//! (`structure::grow::space`), Plastic Trees' light and collisions (`structure::plastic`) and the
//! pictures (`job::adapted`): boxes, spheres, walls, boxes turned about the vertical, vertical
//! prisms over a footprint polygon. Coordinates in metres, z up. A core module below `sim` and
//! `structure` (issue 33: it lived in one growth model's voxel space; the old path
//! `structure::grow::space::{Obstacle, Footprint, FOOTPRINT_MAX_POINTS, validate_obstacles}`
//! still names the same items).

use crate::error::{Error, Result};
use glam::{Vec2, Vec3};

/// Most vertices of an [`Obstacle::Prism`] footprint (stored inline so that [`Obstacle`] stays
/// `Copy`; a larger footprint is split into several prisms by the caller).
pub const FOOTPRINT_MAX_POINTS: usize = 16;

/// A simple polygon in the horizontal plane (x, y in m; 3 to [`FOOTPRINT_MAX_POINTS`] vertices,
/// either winding, convex or not, not self-intersecting): the footprint of an
/// [`Obstacle::Prism`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    points: [Vec2; FOOTPRINT_MAX_POINTS],
    len: u8,
}

impl Footprint {
    /// The polygon through `points` (m; the last vertex joins the first).
    ///
    /// Errors: [`Error::Invalid`] (context `footprint`) for fewer than 3 or more than
    /// [`FOOTPRINT_MAX_POINTS`] vertices, a non-finite coordinate, a zero area, or edges that
    /// cross each other.
    pub fn new(points: &[Vec2]) -> Result<Footprint> {
        let bad = |field: &str, value: String, expected: &str| Err(Error::Invalid { context: "footprint".into(), field: field.into(), value, expected: expected.into() });
        if !(3..=FOOTPRINT_MAX_POINTS).contains(&points.len()) {
            return bad("points", points.len().to_string(), "3 to 16 vertices (split larger footprints)");
        }
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return bad(&format!("point {i}"), points[i].to_string(), "finite coordinates (m)");
        }
        let mut f = Footprint { points: [Vec2::ZERO; FOOTPRINT_MAX_POINTS], len: points.len() as u8 };
        f.points[..points.len()].copy_from_slice(points);
        if !(f.area().abs() > 1e-9) {
            return bad("points", format!("{points:?}"), "a polygon of non-zero area");
        }
        let n = points.len();
        for i in 0..n {
            for j in i + 1..n {
                // adjacent edges share a vertex; test the others for a proper crossing
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                let (a, b) = f.edge(i);
                let (c, d) = f.edge(j);
                if segments_cross(a, b, c, d) {
                    return bad("points", format!("edges {i} and {j} cross"), "a simple (not self-intersecting) polygon");
                }
            }
        }
        Ok(f)
    }

    /// The vertices (m).
    pub fn points(&self) -> &[Vec2] {
        &self.points[..self.len as usize]
    }

    /// Signed area (m², > 0 counter-clockwise; shoelace formula).
    pub fn area(&self) -> f32 {
        (0..self.len as usize).map(|i| {
            let (a, b) = self.edge(i);
            a.perp_dot(b)
        }).sum::<f32>() * 0.5
    }

    fn edge(&self, i: usize) -> (Vec2, Vec2) {
        let n = self.len as usize;
        (self.points[i], self.points[(i + 1) % n])
    }

    /// True when `p` is inside (even–odd crossing rule; points on an edge may go either way).
    pub fn contains(&self, p: Vec2) -> bool {
        let mut inside = false;
        for i in 0..self.len as usize {
            let (a, b) = self.edge(i);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        inside
    }

    /// Signed distance from `p` to the polygon's boundary (m; negative inside).
    pub fn signed_distance(&self, p: Vec2) -> f32 {
        let d = (0..self.len as usize)
            .map(|i| {
                let (a, b) = self.edge(i);
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
                p.distance(a + ab * t)
            })
            .fold(f32::INFINITY, f32::min);
        if self.contains(p) {
            -d
        } else {
            d
        }
    }

    /// True when the segment `a`–`b` has a point inside the polygon or crosses its boundary.
    fn segment_meets(&self, a: Vec2, b: Vec2) -> bool {
        self.contains(a) || self.contains(b) || (0..self.len as usize).any(|i| {
            let (c, d) = self.edge(i);
            segments_cross(a, b, c, d)
        })
    }
}

/// True when the closed segments a–b and c–d have a point in common (orientation tests).
fn segments_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    let on = |p: Vec2, q: Vec2, r: Vec2| r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y);
    (d1 == 0.0 && on(c, d, a)) || (d2 == 0.0 && on(c, d, b)) || (d3 == 0.0 && on(a, b, c)) || (d4 == 0.0 && on(a, b, d))
}

/// Rotation of the horizontal components of `v` by −`yaw` radians about +z (world to the
/// frame of an [`Obstacle::OrientedBox`]).
fn unyaw(v: Vec3, yaw: f32) -> Vec3 {
    let (s, c) = yaw.sin_cos();
    unyaw_sc(v, s, c)
}

/// [`unyaw`] with the yaw's sine and cosine given (so a caller turning many vectors by one yaw
/// takes them once; the same values bit for bit).
pub(crate) fn unyaw_sc(v: Vec3, s: f32, c: f32) -> Vec3 {
    Vec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
}

/// A solid obstacle. Coordinates in metres, tree base at the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle {
    /// Axis-aligned box between two corners.
    Box {
        /// Lower corner (m).
        min: Vec3,
        /// Upper corner (m).
        max: Vec3,
    },
    /// Sphere.
    Sphere {
        /// Centre (m).
        center: Vec3,
        /// Radius (m).
        radius: f32,
    },
    /// Vertical wall filling the half-space beyond the plane x = `x` on the side away from the
    /// origin (x ≥ `x` when `x` > 0, x ≤ `x` when `x` < 0), at all heights.
    Wall {
        /// Plane position (m), ≠ 0.
        x: f32,
    },
    /// A finite vertical wall: the part of [`Obstacle::Wall`]'s half-space (beyond the plane
    /// x = `x`, away from the origin) with |y| ≤ `length`/2 and 0 ≤ z ≤ `height`. Rays can pass
    /// around its ends and over its top (Plastic Trees section 6 moves walls of finite size).
    FiniteWall {
        /// Plane position (m), ≠ 0.
        x: f32,
        /// Length along y (m, > 0; may be infinite), centred on y = 0.
        length: f32,
        /// Height above z = 0 (m, > 0; may be infinite).
        height: f32,
    },
    /// A box turned about the vertical: centre `center`, half extents `half` along its own x,
    /// y, z axes, its x axis at `yaw_deg` counter-clockwise from world +x (an angled wall or
    /// building; `yaw_deg` 0 is the axis-aligned box `center ± half`).
    OrientedBox {
        /// Centre (m).
        center: Vec3,
        /// Half extents (m, > 0, finite) along the box's own axes.
        half: Vec3,
        /// Turn about +z (degrees, counter-clockwise seen from above).
        yaw_deg: f32,
    },
    /// A vertical prism: the footprint polygon extruded from `bottom` to `top` (a building or
    /// wall footprint).
    Prism {
        /// Footprint in the horizontal plane (m).
        footprint: Footprint,
        /// Lowest z (m, finite).
        bottom: f32,
        /// Highest z (m, > `bottom`; may be infinite).
        top: f32,
    },
}

impl Obstacle {
    /// True when `p` is inside the obstacle.
    pub fn contains(&self, p: Vec3) -> bool {
        match *self {
            Obstacle::Box { min, max } => p.cmpge(min).all() && p.cmple(max).all(),
            Obstacle::Sphere { center, radius } => p.distance_squared(center) <= radius * radius,
            Obstacle::Wall { x } => {
                if x >= 0.0 {
                    p.x >= x
                } else {
                    p.x <= x
                }
            }
            Obstacle::FiniteWall { x, length, height } => Obstacle::Wall { x }.contains(p) && p.y.abs() <= 0.5 * length && p.z >= 0.0 && p.z <= height,
            Obstacle::OrientedBox { center, half, yaw_deg } => unyaw(p - center, yaw_deg.to_radians()).abs().cmple(half).all(),
            Obstacle::Prism { footprint, bottom, top } => p.z >= bottom && p.z <= top && footprint.contains(p.truncate()),
        }
    }

    /// The obstacle as an axis-aligned box (min, max corners, m; infinite extents as ±∞), or
    /// `None` for a sphere, an oriented box or a prism. The one definition used by the ray tests here and by the Plastic
    /// Trees sky mask (`structure::plastic::light::SkyMask`).
    pub(crate) fn as_box(&self) -> Option<(Vec3, Vec3)> {
        let inf = f32::INFINITY;
        match *self {
            Obstacle::Box { min, max } => Some((min, max)),
            Obstacle::Sphere { .. } | Obstacle::OrientedBox { .. } | Obstacle::Prism { .. } => None,
            Obstacle::Wall { x } => Obstacle::FiniteWall { x, length: inf, height: inf }.as_box().map(|(lo, hi)| (lo.with_z(-inf), hi)),
            Obstacle::FiniteWall { x, length, height } => {
                let (x0, x1) = if x >= 0.0 { (x, inf) } else { (-inf, x) };
                Some((Vec3::new(x0, -0.5 * length, 0.0), Vec3::new(x1, 0.5 * length, height)))
            }
        }
    }

    /// Axis-aligned bounding box (min, max corners, m; ±∞ where the obstacle is unbounded).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Obstacle::Sphere { center, radius } => (center - radius, center + radius),
            Obstacle::OrientedBox { center, half, yaw_deg } => {
                let (s, c) = yaw_deg.to_radians().sin_cos();
                let e = Vec3::new(c.abs() * half.x + s.abs() * half.y, s.abs() * half.x + c.abs() * half.y, half.z);
                (center - e, center + e)
            }
            Obstacle::Prism { footprint, bottom, top } => {
                let (lo, hi) = footprint.points().iter().fold((Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)), |(lo, hi), q| (lo.min(*q), hi.max(*q)));
                (lo.extend(bottom), hi.extend(top))
            }
            _ => self.as_box().unwrap_or((Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY))),
        }
    }

    /// Signed distance from `p` to the obstacle's surface (m): negative inside, 0 on it,
    /// positive outside (exact for every kind: boxes, walls, spheres, oriented boxes, prisms).
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        match *self {
            Obstacle::Sphere { center, radius } => p.distance(center) - radius,
            Obstacle::OrientedBox { center, half, yaw_deg } => {
                let q = unyaw(p - center, yaw_deg.to_radians());
                let d = q.abs() - half;
                d.max(Vec3::ZERO).length() + d.max_element().min(0.0)
            }
            Obstacle::Prism { footprint, bottom, top } => {
                // an extrusion: the 2-D signed distance combined with the z slab's like a box's axes
                let d = Vec2::new(footprint.signed_distance(p.truncate()), (bottom - p.z).max(p.z - top));
                d.max(Vec2::ZERO).length() + d.max_element().min(0.0)
            }
            _ => {
                let Some((lo, hi)) = self.as_box() else { return f32::INFINITY };
                // per axis: distance outside the slab (> 0) or depth inside (< 0)
                let d = Vec3::new((lo.x - p.x).max(p.x - hi.x), (lo.y - p.y).max(p.y - hi.y), (lo.z - p.z).max(p.z - hi.z));
                let outside = d.max(Vec3::ZERO).length();
                outside + d.max_element().min(0.0)
            }
        }
    }

    /// True when the ray `p + t·d`, 0 < t ≤ `max_t`, meets the obstacle (analytic: slab test,
    /// sphere quadratic, plane crossing).
    /// Slab axes parallel to the ray are handled exactly (no 0·∞), so a ray with d.x = 0 never
    /// meets a wall it starts outside of.
    pub fn ray_hits(&self, p: Vec3, d: Vec3, max_t: f32) -> bool {
        match *self {
            Obstacle::Box { min, max } => slab_hit(p, d, max_t, min, max),
            Obstacle::FiniteWall { .. } => match self.as_box() {
                Some((lo, hi)) => slab_hit(p, d, max_t, lo, hi),
                None => false,
            },
            Obstacle::Sphere { center, radius } => {
                let oc = p - center;
                let b = oc.dot(d);
                let c = oc.length_squared() - radius * radius;
                let a = d.length_squared();
                let disc = b * b - a * c;
                if disc < 0.0 {
                    return false;
                }
                let sq = disc.sqrt();
                let (ta, tb) = ((-b - sq) / a, (-b + sq) / a);
                tb > 0.0 && ta <= max_t
            }
            Obstacle::Wall { x } => {
                if self.contains(p) {
                    return true;
                }
                if d.x == 0.0 {
                    return false;
                }
                let t = (x - p.x) / d.x;
                t > 0.0 && t <= max_t
            }
            Obstacle::OrientedBox { center, half, yaw_deg } => {
                // the slab test in the box's own frame (a turn keeps the ray's parameter t)
                let yaw = yaw_deg.to_radians();
                slab_hit(unyaw(p - center, yaw), unyaw(d, yaw), max_t, -half, half)
            }
            Obstacle::Prism { footprint, bottom, top } => {
                // the part of the ray inside the z slab, then its horizontal shadow against the polygon
                let (mut t0, mut t1) = (0.0f32, max_t);
                if d.z == 0.0 {
                    if p.z < bottom || p.z > top {
                        return false;
                    }
                } else {
                    let (ta, tb) = ((bottom - p.z) / d.z, (top - p.z) / d.z);
                    t0 = t0.max(ta.min(tb));
                    t1 = t1.min(ta.max(tb));
                }
                if !(t0 <= t1) {
                    return false;
                }
                // an unbounded ray: clip far enough to cross the whole footprint
                if !t1.is_finite() {
                    let reach = footprint.points().iter().map(|q| q.distance(p.truncate())).fold(0.0f32, f32::max);
                    let h = d.truncate().length();
                    t1 = if h > 0.0 { t0 + reach / h + 1.0 } else { t0 };
                }
                footprint.segment_meets((p + d * t0).truncate(), (p + d * t1).truncate())
            }
        }
    }

    /// Checks the obstacle's numbers: finite coordinates, a box with `min < max` on every axis
    /// (not inverted, not flat), a sphere radius > 0 m, a wall plane ≠ 0 (the tree base is at
    /// the origin).
    ///
    /// Errors: [`Error::Invalid`] with `context` as given (e.g. `obstacle 2` or `--obstacle`),
    /// the field (`box`, `sphere radius`, `wall x`, …) and the expected value.
    pub fn validate(&self, context: &str) -> Result<()> {
        let bad = |field: &str, value: String, expected: &str| Err(Error::Invalid { context: context.into(), field: field.into(), value, expected: expected.into() });
        match *self {
            Obstacle::Box { min, max } => {
                if !min.is_finite() || !max.is_finite() {
                    return bad("box", format!("min {min}, max {max}"), "finite corner coordinates (m)");
                }
                if !max.cmpgt(min).all() {
                    return bad("box", format!("min {min}, max {max}"), "x0 < x1, y0 < y1 and z0 < z1 (lower corner first, metres)");
                }
            }
            Obstacle::Sphere { center, radius } => {
                if !center.is_finite() {
                    return bad("sphere centre", center.to_string(), "finite coordinates (m)");
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return bad("sphere radius", radius.to_string(), "a finite radius > 0 m");
                }
            }
            Obstacle::Wall { x } => {
                if !x.is_finite() || x == 0.0 {
                    return bad("wall x", x.to_string(), "a finite plane position ≠ 0 m (the tree stands at x = 0)");
                }
            }
            Obstacle::FiniteWall { x, length, height } => {
                Obstacle::Wall { x }.validate(context)?;
                if !(length > 0.0) {
                    return bad("wall length", length.to_string(), "a length > 0 m");
                }
                if !(height > 0.0) {
                    return bad("wall height", height.to_string(), "a height > 0 m");
                }
            }
            Obstacle::OrientedBox { center, half, yaw_deg } => {
                if !center.is_finite() || !yaw_deg.is_finite() {
                    return bad("oriented box", format!("centre {center}, yaw {yaw_deg}°"), "finite centre (m) and yaw (degrees)");
                }
                if !(half.is_finite() && half.cmpgt(Vec3::ZERO).all()) {
                    return bad("oriented box half extents", half.to_string(), "finite half extents > 0 m");
                }
            }
            Obstacle::Prism { footprint, bottom, top } => {
                Footprint::new(footprint.points()).map_err(|e| match e {
                    Error::Invalid { field, value, expected, .. } => Error::Invalid { context: context.into(), field: format!("prism footprint {field}"), value, expected },
                    e => e,
                })?;
                if !bottom.is_finite() || !(top > bottom) || top.is_nan() {
                    return bad("prism bottom/top", format!("{bottom}/{top}"), "a finite bottom and a top above it (m; the top may be infinite)");
                }
            }
        }
        Ok(())
    }

    /// Parses `box:x0,y0,z0,x1,y1,z1`, `sphere:x,y,z,r`, `wall:x` (infinite) or
    /// `wall:x,length[,height]` (a [`Obstacle::FiniteWall`]) (metres) and checks it with
    /// [`Obstacle::validate`] (a box's first corner must be the lower one on every axis).
    ///
    /// Errors: [`Error::Invalid`] with context `--obstacle`, naming the text or the bad field
    /// and the expected form or value.
    pub fn parse(s: &str) -> Result<Obstacle> {
        let form = "box:x0,y0,z0,x1,y1,z1 | sphere:x,y,z,r | wall:x[,length[,height]] (metres, finite numbers)";
        let bad = || Error::Invalid { context: "--obstacle".into(), field: "obstacle".into(), value: s.into(), expected: form.into() };
        let (kind, rest) = s.split_once(':').ok_or_else(bad)?;
        let v: Vec<f32> = rest.split(',').map(|t| t.trim().parse::<f32>()).collect::<std::result::Result<_, _>>().map_err(|_| bad())?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(Error::Invalid { context: "--obstacle".into(), field: kind.trim().into(), value: s.into(), expected: "finite numbers (no NaN or infinity), metres".into() });
        }
        let o = match (kind.trim(), v.len()) {
            ("box", 6) => Obstacle::Box { min: Vec3::new(v[0], v[1], v[2]), max: Vec3::new(v[3], v[4], v[5]) },
            ("sphere", 4) => Obstacle::Sphere { center: Vec3::new(v[0], v[1], v[2]), radius: v[3] },
            ("wall", 1) => Obstacle::Wall { x: v[0] },
            ("wall", 2) => Obstacle::FiniteWall { x: v[0], length: v[1], height: f32::INFINITY },
            ("wall", 3) => Obstacle::FiniteWall { x: v[0], length: v[1], height: v[2] },
            _ => return Err(bad()),
        };
        o.validate(&format!("--obstacle {s}"))?;
        Ok(o)
    }
}

/// Ray–box slab test for 0 < t ≤ `max_t` with possibly infinite bounds; axes where the ray is
/// parallel (d = 0) only test whether `p` lies inside that slab.
fn slab_hit(p: Vec3, d: Vec3, max_t: f32, lo: Vec3, hi: Vec3) -> bool {
    let (mut t0, mut t1) = (0.0f32, max_t);
    for a in 0..3 {
        if d[a] == 0.0 {
            if p[a] < lo[a] || p[a] > hi[a] {
                return false;
            }
            continue;
        }
        let inv = 1.0 / d[a];
        let (mut ta, mut tb) = ((lo[a] - p[a]) * inv, (hi[a] - p[a]) * inv);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Checks every obstacle with [`Obstacle::validate`] (context `obstacle i`, 0-based).
///
/// Errors: the first invalid obstacle's [`Error::Invalid`].
pub fn validate_obstacles(obstacles: &[Obstacle]) -> Result<()> {
    for (i, o) in obstacles.iter().enumerate() {
        o.validate(&format!("obstacle {i}"))?;
    }
    Ok(())
}
