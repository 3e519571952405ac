//! Obstacles of a scenario (`[[obstacle]]` entries, issue 14): buildings, walls and rocks that
//! shade the light grid, keep trees from establishing where they stand on the ground, bend and
//! prune the trees drawn beside them (Plastic Trees, `structure::stand`) and are drawn in renders.
//!
//! World coordinates (m, x east, y north, origin at the site's south-west corner); heights are
//! above the ground at the obstacle's reference point ([`ObstacleSpec::anchor`]): the centre of
//! its footprint's bounding box.
//!
//! ```toml
//! [[obstacle]]
//! kind = "box"          # min = [x0, y0, z0], max = [x1, y1, z1] (z above the ground)
//! min = [100.0, 80.0, 0.0]
//! max = [112.0, 95.0, 9.0]
//! [[obstacle]]
//! kind = "wall"         # from start to end, height_m tall, thickness_m thick
//! start = [50.0, 50.0]
//! end = [90.0, 50.0]
//! height_m = 3.0
//! thickness_m = 0.5
//! [[obstacle]]
//! kind = "sphere"       # a boulder; centre z above the ground
//! center = [30.0, 40.0, 1.0]
//! radius_m = 2.5
//! [[obstacle]]
//! kind = "footprint"    # a building's ground plan (≥ 3 corners, no repeated corner), height_m tall
//! points = [[10.0, 10.0], [30.0, 10.0], [30.0, 25.0], [10.0, 25.0]]
//! height_m = 12.0
//! ```

use crate::error::{Error, Result};
use crate::obstacle::{Footprint, Obstacle, FOOTPRINT_MAX_POINTS};
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// One `[[obstacle]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObstacleSpec {
    /// An axis-aligned box between two corners (x, y world; z above the ground).
    Box {
        /// Lower corner `[x0, y0, z0]` (m).
        min: [f64; 3],
        /// Upper corner `[x1, y1, z1]` (m).
        max: [f64; 3],
    },
    /// A straight wall from `start` to `end` (its centre line), standing on the ground.
    Wall {
        /// One end `[x, y]` (m).
        start: [f64; 2],
        /// The other end `[x, y]` (m).
        end: [f64; 2],
        /// Height (m, 0.1–200).
        height_m: f64,
        /// Thickness (m, 0.05–50).
        thickness_m: f64,
    },
    /// A sphere (a boulder); the centre's z is above the ground.
    Sphere {
        /// Centre `[x, y, z]` (m).
        center: [f64; 3],
        /// Radius (m, 0.1–200).
        radius_m: f64,
    },
    /// A vertical prism over a ground plan (a building), standing on the ground.
    Footprint {
        /// Corners `[x, y]` (m) in order around the polygon (3–1000, simple polygon).
        points: Vec<[f64; 2]>,
        /// Height (m, 0.1–500).
        height_m: f64,
    },
}

/// Edge (m) of the axis-aligned boxes that stand in for walls at an angle and for footprints in
/// the Plastic Trees obstacles ([`ObstacleSpec::solids`]).
pub const SOLID_STEP_M: f64 = 0.5;

fn invalid(ctx: &str, field: String, value: impl ToString, expected: &str) -> Error {
    Error::Invalid { context: ctx.to_string(), field, value: value.to_string(), expected: expected.to_string() }
}

/// Distance (m) from `p` to the segment a–b.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Even–odd point-in-polygon test.
fn inside_polygon(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

impl ObstacleSpec {
    /// Short name of the kind (`box`, `wall`, `sphere`, `footprint`).
    pub fn kind(&self) -> &'static str {
        match self {
            ObstacleSpec::Box { .. } => "box",
            ObstacleSpec::Wall { .. } => "wall",
            ObstacleSpec::Sphere { .. } => "sphere",
            ObstacleSpec::Footprint { .. } => "footprint",
        }
    }

    /// Checks the numbers of entry `i`: finite; a box with min < max on every axis; a wall of
    /// 0.1–200 m height, 0.05–50 m thickness and distinct ends; a sphere of 0.1–200 m radius; a
    /// footprint of 3–1000 distinct corners and 0.1–500 m height. `ctx` names the scenario file.
    ///
    /// Errors: [`Error::Invalid`] naming `obstacle[i].<field>`, the value and what is expected.
    pub fn validate(&self, i: usize, ctx: &str) -> Result<()> {
        let f = |x: &str| format!("obstacle[{i}].{x}");
        let finite = |name: &str, v: &[f64]| -> Result<()> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(invalid(ctx, f(name), format!("{v:?}"), "finite numbers (m)"))
            }
        };
        let range = |name: &str, v: f64, lo: f64, hi: f64| -> Result<()> {
            if v >= lo && v <= hi {
                Ok(())
            } else {
                Err(invalid(ctx, f(name), v, &format!("{lo}–{hi} m")))
            }
        };
        match self {
            ObstacleSpec::Box { min, max } => {
                finite("min", min)?;
                finite("max", max)?;
                if !(0..3).all(|a| max[a] > min[a]) {
                    return Err(invalid(ctx, f("max"), format!("{max:?} (min {min:?})"), "max > min on x, y and z (lower corner in min, metres)"));
                }
            }
            ObstacleSpec::Wall { start, end, height_m, thickness_m } => {
                finite("start", start)?;
                finite("end", end)?;
                range("height_m", *height_m, 0.1, 200.0)?;
                range("thickness_m", *thickness_m, 0.05, 50.0)?;
                if start == end {
                    return Err(invalid(ctx, f("end"), format!("{end:?}"), "an end point other than start"));
                }
            }
            ObstacleSpec::Sphere { center, radius_m } => {
                finite("center", center)?;
                range("radius_m", *radius_m, 0.1, 200.0)?;
            }
            ObstacleSpec::Footprint { points, height_m } => {
                if !(3..=1000).contains(&points.len()) {
                    return Err(invalid(ctx, f("points"), format!("{} corners", points.len()), "3–1000 [x, y] corners"));
                }
                for (j, p) in points.iter().enumerate() {
                    finite(&format!("points[{j}]"), p)?;
                    if points[..j].contains(p) {
                        return Err(invalid(ctx, f(&format!("points[{j}]")), format!("{p:?}"), "each corner once"));
                    }
                }
                range("height_m", *height_m, 0.1, 500.0)?;
            }
        }
        Ok(())
    }

    /// Bounding box of the footprint `[x0, y0, x1, y1]` (m).
    pub fn bounds_xy(&self) -> [f64; 4] {
        match self {
            ObstacleSpec::Box { min, max } => [min[0], min[1], max[0], max[1]],
            ObstacleSpec::Wall { start, end, thickness_m, .. } => {
                let h = 0.5 * thickness_m;
                [start[0].min(end[0]) - h, start[1].min(end[1]) - h, start[0].max(end[0]) + h, start[1].max(end[1]) + h]
            }
            ObstacleSpec::Sphere { center, radius_m } => [center[0] - radius_m, center[1] - radius_m, center[0] + radius_m, center[1] + radius_m],
            ObstacleSpec::Footprint { points, .. } => points.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]),
        }
    }

    /// Reference point `[x, y]` (m): the centre of [`ObstacleSpec::bounds_xy`]; heights are
    /// above the ground there.
    pub fn anchor(&self) -> [f64; 2] {
        let b = self.bounds_xy();
        [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])]
    }

    /// Height of the solid's top above the ground over point `(x, y)` (m), `None` where the
    /// obstacle is not above the point.
    pub fn top_at(&self, x: f64, y: f64) -> Option<f64> {
        match self {
            ObstacleSpec::Box { min, max } => (x >= min[0] && x <= max[0] && y >= min[1] && y <= max[1]).then_some(max[2]),
            ObstacleSpec::Wall { start, end, height_m, thickness_m } => (segment_distance([x, y], *start, *end) <= 0.5 * thickness_m).then_some(*height_m),
            ObstacleSpec::Sphere { center, radius_m } => {
                let d2 = (x - center[0]).powi(2) + (y - center[1]).powi(2);
                (d2 <= radius_m * radius_m && center[2] + (radius_m * radius_m - d2).sqrt() > 0.0).then(|| center[2] + (radius_m * radius_m - d2).sqrt())
            }
            ObstacleSpec::Footprint { points, height_m } => inside_polygon([x, y], points).then_some(*height_m),
        }
    }

    /// True when the solid stands on the ground at `(x, y)` (no tree can establish there): walls
    /// and footprints; a box whose bottom is at or below the ground; a sphere whose lower surface
    /// over the point is at or below the ground.
    pub fn solid_at_ground(&self, x: f64, y: f64) -> bool {
        match self {
            ObstacleSpec::Box { min, .. } => min[2] <= 0.0 && self.top_at(x, y).is_some(),
            ObstacleSpec::Sphere { center, radius_m } => {
                let d2 = (x - center[0]).powi(2) + (y - center[1]).powi(2);
                d2 <= radius_m * radius_m && center[2] - (radius_m * radius_m - d2).sqrt() <= 0.0 && center[2] + (radius_m * radius_m - d2).sqrt() >= 0.0
            }
            _ => self.top_at(x, y).is_some(),
        }
    }

    /// The obstacle as Plastic Trees solids ([`Obstacle`]) in world coordinates with the ground
    /// at `ground_z` (m) under the anchor: a box, a sphere, an axis-parallel wall as one box, a
    /// wall at an angle as one [`Obstacle::OrientedBox`], a footprint of up to
    /// [`FOOTPRINT_MAX_POINTS`] vertices as one [`Obstacle::Prism`]; a larger footprint as
    /// axis-aligned boxes of [`SOLID_STEP_M`] along x (one per run of covered cells of each row).
    /// Walls, footprints and their boxes reach 1 m below the ground so that no gap opens on a
    /// slope.
    pub fn solids(&self, ground_z: f64) -> Vec<Obstacle> {
        self.solids_on(ground_z, ground_z)
    }

    /// [`ObstacleSpec::solids`] on a slope: heights are above `ground_z` (the ground under the
    /// anchor), while walls, footprints and their boxes reach 1 m below `lowest_z`, the lowest
    /// ground under the solid (m; `job::adapted::ground_under`), so that the downhill side
    /// stands on the terrain as a foundation does (trial 37: a building on a slope floated 5 m
    /// above its downhill side).
    pub fn solids_on(&self, ground_z: f64, lowest_z: f64) -> Vec<Obstacle> {
        let bury = (lowest_z.min(ground_z) - ground_z) - 1.0;
        let v = |x: f64, y: f64, z: f64| Vec3::new(x as f32, y as f32, (ground_z + z) as f32);
        match self {
            ObstacleSpec::Box { min, max } => vec![Obstacle::Box { min: v(min[0], min[1], min[2]), max: v(max[0], max[1], max[2]) }],
            ObstacleSpec::Sphere { center, radius_m } => vec![Obstacle::Sphere { center: v(center[0], center[1], center[2]), radius: *radius_m as f32 }],
            ObstacleSpec::Wall { start, end, height_m, thickness_m } if start[0] == end[0] || start[1] == end[1] => {
                let b = self.bounds_xy();
                let h = 0.5 * thickness_m;
                let (x0, x1) = if start[0] == end[0] { (start[0] - h, start[0] + h) } else { (b[0] + h, b[2] - h) };
                let (y0, y1) = if start[1] == end[1] { (start[1] - h, start[1] + h) } else { (b[1] + h, b[3] - h) };
                vec![Obstacle::Box { min: v(x0, y0, bury), max: v(x1, y1, *height_m) }]
            }
            // a wall at an angle: one box turned about the vertical along it
            ObstacleSpec::Wall { start, end, height_m, thickness_m } => {
                let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
                let (len, z0) = ((dx * dx + dy * dy).sqrt(), bury);
                let center = v(0.5 * (start[0] + end[0]), 0.5 * (start[1] + end[1]), 0.5 * (z0 + height_m));
                let half = Vec3::new((0.5 * len) as f32, (0.5 * thickness_m) as f32, (0.5 * (height_m - z0)) as f32);
                vec![Obstacle::OrientedBox { center, half, yaw_deg: dy.atan2(dx).to_degrees() as f32 }]
            }
            // a footprint of up to 16 vertices: the polygon extruded (larger ones: boxes below)
            ObstacleSpec::Footprint { points, height_m } if points.len() <= FOOTPRINT_MAX_POINTS && Footprint::new(&points.iter().map(|p| Vec2::new(p[0] as f32, p[1] as f32)).collect::<Vec<_>>()).is_ok() => {
                let pts: Vec<Vec2> = points.iter().map(|p| Vec2::new(p[0] as f32, p[1] as f32)).collect();
                match Footprint::new(&pts) {
                    Ok(footprint) => vec![Obstacle::Prism { footprint, bottom: (ground_z + bury) as f32, top: (ground_z + height_m) as f32 }],
                    Err(_) => Vec::new(), // unreachable: checked by the guard
                }
            }
            _ => {
                let b = self.bounds_xy();
                let top = match self {
                    ObstacleSpec::Wall { height_m, .. } | ObstacleSpec::Footprint { height_m, .. } => *height_m,
                    _ => 0.0,
                };
                let s = SOLID_STEP_M;
                let (nx, ny) = (((b[2] - b[0]) / s).ceil().max(1.0) as usize, ((b[3] - b[1]) / s).ceil().max(1.0) as usize);
                let mut out = Vec::new();
                for j in 0..ny {
                    let y = b[1] + (j as f64 + 0.5) * s;
                    let mut run: Option<usize> = None;
                    for i in 0..=nx {
                        let covered = i < nx && self.top_at(b[0] + (i as f64 + 0.5) * s, y).is_some();
                        match (covered, run) {
                            (true, None) => run = Some(i),
                            (false, Some(i0)) => {
                                out.push(Obstacle::Box { min: v(b[0] + i0 as f64 * s, y - 0.5 * s, bury), max: v(b[0] + i as f64 * s, y + 0.5 * s, top) });
                                run = None;
                            }
                            _ => {}
                        }
                    }
                }
                out
            }
        }
    }
}

/// Per light cell (`cols` × `rows` cells of `cell_m` m, row 0 south): the canopy entries the
/// obstacles add to the light grid and the fraction of the ground free for establishment.
///
/// Each cell is sampled at 4 × 4 points; where f of them lie under obstacles (tallest top H over
/// the cell), the cell gets an opaque entry at height H of leaf-area index
/// min(−ln(1 − f)/k, 20) with the light phase's extinction k = `k_ext` (so the light under it is
/// the uncovered fraction 1 − f, Beer–Lambert), and the ground free fraction is the share of
/// points not on a solid ([`ObstacleSpec::solid_at_ground`]). Entries are
/// `(cell << 32 | (u32::MAX − H bits), LAI)`, the light phase's key.
pub fn light_cells(obstacles: &[ObstacleSpec], cols: usize, rows: usize, cell_m: f64, k_ext: f32) -> (Vec<(u64, f32)>, Vec<f32>) {
    let mut entries = Vec::new();
    let mut free = vec![1.0f32; cols * rows];
    if obstacles.is_empty() {
        return (entries, free);
    }
    for (oi, o) in obstacles.iter().enumerate() {
        let b = o.bounds_xy();
        let c0 = ((b[0] / cell_m).floor().max(0.0) as usize).min(cols);
        let c1 = ((b[2] / cell_m).floor().max(-1.0) as i64 + 1).clamp(0, cols as i64) as usize;
        let r0 = ((b[1] / cell_m).floor().max(0.0) as usize).min(rows);
        let r1 = ((b[3] / cell_m).floor().max(-1.0) as i64 + 1).clamp(0, rows as i64) as usize;
        for r in r0..r1 {
            for c in c0..c1 {
                let (mut n, mut solid, mut top) = (0u32, 0u32, 0.0f64);
                for sj in 0..4 {
                    for si in 0..4 {
                        let (x, y) = ((c as f64 + (si as f64 + 0.5) / 4.0) * cell_m, (r as f64 + (sj as f64 + 0.5) / 4.0) * cell_m);
                        // a point under an earlier obstacle is counted there only
                        if obstacles[..oi].iter().any(|p| p.top_at(x, y).is_some()) {
                            continue;
                        }
                        if let Some(h) = o.top_at(x, y) {
                            n += 1;
                            top = top.max(h);
                            solid += o.solid_at_ground(x, y) as u32;
                        }
                    }
                }
                if n > 0 {
                    let f = n as f32 / 16.0;
                    let lai = if f >= 1.0 { 20.0 } else { (-(1.0 - f).ln() / k_ext).min(20.0) };
                    let cell = (r * cols + c) as u64;
                    entries.push((cell << 32 | (u32::MAX - (top.max(0.0) as f32).to_bits()) as u64, lai));
                    free[r * cols + c] = (free[r * cols + c] - solid as f32 / 16.0).max(0.0);
                }
            }
        }
    }
    (entries, free)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprint_and_wall_geometry() {
        let l = ObstacleSpec::Footprint { points: vec![[0.0, 0.0], [10.0, 0.0], [10.0, 4.0], [4.0, 4.0], [4.0, 10.0], [0.0, 10.0]], height_m: 6.0 };
        assert_eq!(l.top_at(2.0, 8.0), Some(6.0));
        assert_eq!(l.top_at(8.0, 8.0), None); // the notch of the L
        let w = ObstacleSpec::Wall { start: [0.0, 0.0], end: [10.0, 10.0], height_m: 3.0, thickness_m: 1.0 };
        assert_eq!(w.top_at(5.0, 5.3), Some(3.0));
        assert_eq!(w.top_at(5.0, 6.0), None);
        // the diagonal wall's boxes cover its centre line and not the far corners
        let boxes = w.solids(100.0);
        assert!(boxes.iter().any(|b| b.contains(Vec3::new(5.0, 5.0, 101.0))));
        assert!(!boxes.iter().any(|b| b.contains(Vec3::new(9.0, 1.0, 101.0))));
        // a floating sphere is not on the ground; a half-buried one is
        assert!(!ObstacleSpec::Sphere { center: [0.0, 0.0, 5.0], radius_m: 1.0 }.solid_at_ground(0.0, 0.0));
        assert!(ObstacleSpec::Sphere { center: [0.0, 0.0, 0.0], radius_m: 1.0 }.solid_at_ground(0.5, 0.0));
    }

    #[test]
    fn light_cells_cover_exactly_the_footprint() {
        // a box covering cells (1, 1) fully and (2, 1) half (cells of 10 m)
        let o = [ObstacleSpec::Box { min: [10.0, 10.0, 0.0], max: [25.0, 20.0, 8.0] }];
        let (e, free) = light_cells(&o, 4, 4, 10.0, 0.5);
        assert_eq!(e.len(), 2);
        assert_eq!(free[4 + 1], 0.0);
        assert_eq!(free[4 + 2], 0.5);
        let lai_half = e.iter().find(|x| x.0 >> 32 == 6).unwrap().1;
        assert!(((-0.5 * lai_half).exp() - 0.5).abs() < 1e-6, "half covered: half the light");
        assert_eq!(f32::from_bits(u32::MAX - e[0].0 as u32), 8.0);
    }
}
