//! The north arrow of the stills, the films and the viewer (issue 32, trial 43 defect 12:
//! the oblique stills and the viewer carried no orientation). Needs no adapter.
use sylva::render::camera::Camera;
use sylva::render::overlay::{north_arrow_centre, north_arrow_radius, stamp_north_arrow};

/// The direction (degrees, counter-clockwise from the picture's right, y up) from the disc's
/// centre to the centroid of the arrow's dark pixels (the north half of the needle and the
/// "N"; the rim, a ring about the centre, cancels), and the pixels changed outside the disc.
fn arrow_direction(cam: &Camera, w: u32, h: u32) -> (f32, usize) {
    let grey = image::Rgba([120u8, 130, 110, 255]);
    let mut img = image::RgbaImage::from_pixel(w, h, grey);
    stamp_north_arrow(&mut img, cam);
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render");
    std::fs::create_dir_all(&dir).unwrap();
    img.save(dir.join(format!("north_arrow_{w}x{h}_{:.0}_{:.0}.png", cam.target[0] - cam.eye[0], cam.target[1] - cam.eye[1]))).unwrap();
    let [cx, cy] = north_arrow_centre(w, h);
    let r = north_arrow_radius(w, h);
    let (mut sx, mut sy, mut n, mut outside) = (0.0f64, 0.0f64, 0.0f64, 0);
    for (x, y, p) in img.enumerate_pixels() {
        let (dx, dy) = (x as f32 + 0.5 - cx, y as f32 + 0.5 - cy);
        if dx.hypot(dy) > r + 1.5 {
            outside += usize::from(*p != grey);
            continue;
        }
        // dark pixels inside the rim
        if dx.hypot(dy) < r - 2.5 && p.0[0] < 60 {
            sx += dx as f64;
            sy += dy as f64;
            n += 1.0;
        }
    }
    assert!(n > 20.0, "{n} dark pixels");
    ((-(sy / n)).atan2(sx / n).to_degrees() as f32, outside)
}

/// Smallest difference of two angles (degrees).
fn angle_gap(a: f32, b: f32) -> f32 {
    ((a - b + 540.0).rem_euclid(360.0) - 180.0).abs()
}

/// Cameras looking north, east, south-west (as the oblique preset does, down at a slant) and
/// straight down with north up: the arrow's dark pixels lie towards north as the camera sees
/// it (up, left, up and to the right, up), within 10°; nothing outside its disc changes.
/// Fails when the arrow ignores the heading (always up) or mirrors east and west.
#[test]
fn the_north_arrow_points_to_grid_north_for_each_heading() {
    let level = |dx: f32, dy: f32| Camera::look_at([500.0, 500.0, 20.0], [500.0 + 300.0 * dx, 500.0 + 300.0 * dy, 0.0], 50.0);
    let mut down = Camera::look_at([500.0, 500.0, 800.0], [500.0, 500.0, 0.0], 50.0);
    down.up = [0.0, 1.0, 0.0];
    // looking north-east from the south-west (the oblique preset's heading): north is ahead
    // and to the left, at 135° on the picture
    let ne = std::f32::consts::FRAC_1_SQRT_2;
    for (name, cam, want) in [("north", level(0.0, 1.0), 90.0f32), ("east", level(1.0, 0.0), 180.0), ("north-east", level(ne, ne), 135.0), ("south", level(0.0, -1.0), 270.0), ("down, north up", down, 90.0)] {
        for (w, h) in [(1280u32, 720u32), (320, 240)] {
            let (a, outside) = arrow_direction(&cam, w, h);
            eprintln!("{name} at {w}×{h}: arrow at {a:.1}° (want {want}°)");
            assert!(angle_gap(a, want) < 10.0, "{name} at {w}×{h}: the arrow points at {a:.1}°, north is at {want}°");
            assert_eq!(outside, 0, "{name}: pixels changed outside the arrow's disc");
        }
    }
}
