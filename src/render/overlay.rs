//! Orientation drawn over a finished picture: a north arrow in its lower-right corner (issue
//! 32, trial 43 defect 12: the oblique stills, the close-up and the viewer carried none, so a
//! planner could not tell which parcel was which without the map camera).

use glam::Vec3;

use super::camera::Camera;

/// The direction (x right, y up on the picture; unit length) in which grid north (+y of the
/// site: the DEM's rows run north to south, its columns west to east) lies in the picture of
/// `camera`, read as a compass is: "up" is the direction on the ground the picture looks into
/// (the horizontal part of the camera's forward plus its up vector: forward for a camera
/// looking level or down at a slant, the picture's top for one looking straight down, where
/// this is the exact projection), "right" the camera's right, both in plan. So a camera looking
/// north draws the arrow straight up, one looking east draws it pointing left. `None` for a
/// degenerate camera (eye on its target, or up along the view).
pub fn north_on_screen(camera: &Camera) -> Option<[f32; 2]> {
    let f = (Vec3::from(camera.target) - Vec3::from(camera.eye)).normalize_or_zero();
    let right = f.cross(Vec3::from(camera.up)).normalize_or_zero();
    if f == Vec3::ZERO || right == Vec3::ZERO {
        return None;
    }
    let up = right.cross(f);
    // plan directions of the picture's right and of "into the picture"
    let r = Vec3::new(right.x, right.y, 0.0).normalize_or_zero();
    let ahead = Vec3::new(f.x + up.x, f.y + up.y, 0.0).normalize_or_zero();
    if r == Vec3::ZERO || ahead == Vec3::ZERO {
        return None;
    }
    let (x, y) = (r.y, ahead.y);
    let n = (x * x + y * y).sqrt();
    (n > 1e-6).then(|| [x / n, y / n])
}

/// Radius (px) of the north arrow's disc on a picture of `width` × `height` pixels: 1/20 of its
/// smaller side, 14–56 px (18 px on a 640 × 360 frame, 36 px on a 1280 × 720 still).
pub fn north_arrow_radius(width: u32, height: u32) -> f32 {
    (width.min(height) as f32 / 20.0).clamp(14.0, 56.0)
}

/// Centre (px, from the top-left corner) of the north arrow's disc on a picture of `width` ×
/// `height` pixels: 0.5 radius in from the lower-right corner.
pub fn north_arrow_centre(width: u32, height: u32) -> [f32; 2] {
    let r = north_arrow_radius(width, height);
    [width as f32 - 1.5 * r, height as f32 - 1.5 * r]
}

/// Draws a north arrow into `img`, the picture of `camera`, in its lower-right corner
/// ([`north_arrow_centre`], [`north_arrow_radius`]): a white disc (80 % opaque, dark rim), a
/// compass needle along [`north_on_screen`] (its north half black, its south half white with a
/// black outline) and an upright "N" at the north tip. Nothing for a degenerate camera or a
/// picture under 48 px.
pub fn stamp_north_arrow(img: &mut image::RgbaImage, camera: &Camera) {
    let (w, h) = img.dimensions();
    let Some(d) = north_on_screen(camera) else { return };
    if w.min(h) < 48 {
        return;
    }
    let rad = north_arrow_radius(w, h);
    let [cx, cy] = north_arrow_centre(w, h);
    // needle: the picture's y runs down
    let (dx, dy) = (d[0], -d[1]);
    let (nx, ny) = (-dy, dx);
    let tip = (cx + 0.5 * rad * dx, cy + 0.5 * rad * dy);
    let tail = (cx - 0.55 * rad * dx, cy - 0.55 * rad * dy);
    let half = 0.2 * rad;
    let left = (cx + half * nx, cy + half * ny);
    let right = (cx - half * nx, cy - half * ny);
    // the letter: centred 0.7 radius out along the needle, 0.28 radius tall, inside the rim
    let (lx, ly, lh) = (cx + 0.7 * rad * dx, cy + 0.7 * rad * dy, 0.14 * rad);
    let lw = 0.1 * rad;
    let strokes = [((lx - lw, ly + lh), (lx - lw, ly - lh)), ((lx - lw, ly - lh), (lx + lw, ly + lh)), ((lx + lw, ly + lh), (lx + lw, ly - lh))];
    let stroke = (0.045 * rad).max(0.8);
    // what covers a point: 0 outside, 1 disc, 2 needle's white half, 3 black
    let cover = |x: f32, y: f32| -> u8 {
        let r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
        if r2 > rad * rad {
            return 0;
        }
        if r2 > (rad - 1.5).powi(2) {
            return 3;
        }
        if strokes.iter().any(|&(a, b)| segment_distance((x, y), a, b) <= stroke) {
            return 3;
        }
        if in_triangle((x, y), tip, left, right) {
            return 3;
        }
        if in_triangle((x, y), tail, right, left) {
            let edge = segment_distance((x, y), tail, left).min(segment_distance((x, y), tail, right)).min(segment_distance((x, y), left, right));
            return if edge <= 1.0 { 3 } else { 2 };
        }
        1
    };
    let (x0, x1) = ((cx - rad).floor().max(0.0) as u32, ((cx + rad).ceil() as u32 + 1).min(w));
    let (y0, y1) = ((cy - rad).floor().max(0.0) as u32, ((cy + rad).ceil() as u32 + 1).min(h));
    for y in y0..y1 {
        for x in x0..x1 {
            // 3 × 3 samples a pixel
            let (mut white, mut black, mut n) = (0.0f32, 0.0f32, 0.0f32);
            for j in 0..3 {
                for i in 0..3 {
                    match cover(x as f32 + (i as f32 + 0.5) / 3.0, y as f32 + (j as f32 + 0.5) / 3.0) {
                        0 => {}
                        1 => {
                            white += 0.8;
                            n += 1.0;
                        }
                        2 => {
                            white += 1.0;
                            n += 1.0;
                        }
                        _ => {
                            black += 1.0;
                            n += 1.0;
                        }
                    }
                }
            }
            if n == 0.0 {
                continue;
            }
            let p = img.get_pixel_mut(x, y);
            for c in 0..3 {
                let v = p.0[c] as f32;
                // the share of white covers, the black share darkens to 20
                let v = v + (255.0 - v) * white / 9.0;
                let v = v + (20.0 - v) * black / 9.0;
                p.0[c] = v.round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: (f32, f32), a: (f32, f32), b: (f32, f32)) -> f32 {
    let (vx, vy) = (b.0 - a.0, b.1 - a.1);
    let l2 = vx * vx + vy * vy;
    let t = if l2 > 0.0 { (((p.0 - a.0) * vx + (p.1 - a.1) * vy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    let (qx, qy) = (a.0 + t * vx - p.0, a.1 + t * vy - p.1);
    (qx * qx + qy * qy).sqrt()
}

/// Whether `p` lies inside the triangle `a`, `b`, `c` (either winding).
fn in_triangle(p: (f32, f32), a: (f32, f32), b: (f32, f32), c: (f32, f32)) -> bool {
    let s = |u: (f32, f32), v: (f32, f32)| (v.0 - u.0) * (p.1 - u.1) - (v.1 - u.1) * (p.0 - u.0);
    let (d1, d2, d3) = (s(a, b), s(b, c), s(c, a));
    let neg = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let pos = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(neg && pos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Level cameras looking north, east, south and west, and one looking straight down with
    /// the picture's top to the north-east.
    #[test]
    fn north_lies_where_a_compass_reads_it() {
        let level = |dx: f32, dy: f32| Camera::look_at([500.0, 500.0, 10.0], [500.0 + 100.0 * dx, 500.0 + 100.0 * dy, 10.0], 50.0);
        let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-5;
        assert!(close(north_on_screen(&level(0.0, 1.0)).unwrap(), [0.0, 1.0]));
        assert!(close(north_on_screen(&level(1.0, 0.0)).unwrap(), [-1.0, 0.0]));
        assert!(close(north_on_screen(&level(0.0, -1.0)).unwrap(), [0.0, -1.0]));
        assert!(close(north_on_screen(&level(-1.0, 0.0)).unwrap(), [1.0, 0.0]));
        // looking down at a slant towards the east: north to the left
        let oblique = Camera::look_at([0.0, 0.0, 300.0], [400.0, 0.0, 0.0], 50.0);
        assert!(close(north_on_screen(&oblique).unwrap(), [-1.0, 0.0]));
        // straight down, the picture's top to the north-east: north up and to the left
        let mut down = Camera::look_at([0.0, 0.0, 300.0], [0.0, 0.0, 0.0], 50.0);
        down.up = [1.0, 1.0, 0.0];
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!(close(north_on_screen(&down).unwrap(), [-s, s]), "{:?}", north_on_screen(&down));
        // the eye on its target
        assert!(north_on_screen(&Camera { target: [0.0, 0.0, 300.0], ..down }).is_none());
    }
}
