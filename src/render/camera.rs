//! Cameras: explicit eye/target/field of view, presets (overview, oblique, ground level,
//! top-down orthographic map) and an orbit path for timelapses.

use glam::{Mat4, Vec3};

use super::terrain::TerrainMesh;

/// Projection of a camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Perspective with vertical field of view in degrees (1..170).
    Perspective {
        /// Vertical field of view (degrees).
        fov_y_deg: f32,
    },
    /// Orthographic with the given half height of the view (m); width follows the aspect.
    Orthographic {
        /// Half of the visible height (m).
        half_height: f32,
    },
}

/// A camera looking at the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (m).
    pub eye: [f32; 3],
    /// Point looked at (m).
    pub target: [f32; 3],
    /// Up vector (usually +z).
    pub up: [f32; 3],
    /// Projection.
    pub projection: Projection,
    /// Near plane (m), > 0.
    pub near: f32,
    /// Far plane (m), > near.
    pub far: f32,
}

/// Named camera presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraPreset {
    /// High view of the whole terrain from the south.
    Overview,
    /// Lower oblique view from the south-west.
    Oblique,
    /// Eye 1.7 m above the ground at the south edge, looking north.
    Ground,
    /// Top-down orthographic map.
    Map,
}

impl std::str::FromStr for CameraPreset {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "overview" => Ok(CameraPreset::Overview),
            "oblique" => Ok(CameraPreset::Oblique),
            "ground" => Ok(CameraPreset::Ground),
            "map" | "top" | "topdown" => Ok(CameraPreset::Map),
            _ => Err(crate::Error::Invalid {
                context: "camera".into(),
                field: "preset".into(),
                value: s.into(),
                expected: "overview, oblique, ground or map".into(),
            }),
        }
    }
}

impl Camera {
    /// A perspective camera at `eye` looking at `target` with vertical field of view `fov_y_deg`.
    pub fn look_at(eye: [f32; 3], target: [f32; 3], fov_y_deg: f32) -> Self {
        let d = (Vec3::from(eye) - Vec3::from(target)).length().max(1.0);
        Camera { eye, target, up: [0.0, 0.0, 1.0], projection: Projection::Perspective { fov_y_deg }, near: (d * 0.002).max(0.05), far: d * 8.0 + 1000.0 }
    }

    /// A person's view from the ground: the eye 1.7 m above the drawn surface at `(x, y)`
    /// ([`TerrainMesh::height_at`]), looking north towards `y = target_y` at 60° field of
    /// view, pitched at the point 8 m above the surface there but never more than 12° up or
    /// 6° down (a hill or valley between would otherwise fill the frame with slope or sky),
    /// near plane 0.1 m.
    pub fn ground_at(terrain: &TerrainMesh, x: f32, y: f32, target_y: f32) -> Self {
        let gz = terrain.height_at(x, y).unwrap_or(0.0);
        let eye = [x, y, gz + 1.7];
        let tz = terrain.height_at(x, target_y).map_or(eye[2], |h| h + 8.0);
        let run = (target_y - y).abs().max(1.0);
        let rise = (tz - eye[2]).clamp(-run * 6f32.to_radians().tan(), run * 12f32.to_radians().tan());
        let mut cam = Camera::look_at(eye, [x, target_y.max(y + 1.0), eye[2] + rise], 60.0);
        cam.near = 0.1;
        cam
    }

    /// A preset framing the terrain's bounds ([`TerrainMesh::bounds`]: the simulated window
    /// without its surroundings) for a square picture; see [`Camera::preset_sized`].
    pub fn preset(p: CameraPreset, terrain: &TerrainMesh) -> Self {
        Camera::preset_sized(p, terrain, 1, 1)
    }

    /// A preset framing the terrain's bounds for a picture of `width` × `height` pixels. The
    /// top-down map ([`CameraPreset::Map`]) fits the whole window into the picture with 2 %
    /// to spare on the axis that limits it (half height 0.51 · max(Δy, Δx · height/width)), so
    /// a wide still shows the window, not kilometres of surroundings beside it; the other
    /// presets do not depend on the picture's shape (their field of view is vertical).
    pub fn preset_sized(p: CameraPreset, terrain: &TerrainMesh, width: u32, height: u32) -> Self {
        let (lo, hi) = terrain.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let c = (lo + hi) * 0.5;
        let size = (hi - lo).truncate().max_element().max(1.0);
        match p {
            CameraPreset::Overview => {
                let eye = c + Vec3::new(0.0, -0.95 * size, 0.75 * size + (hi.z - lo.z));
                Camera::look_at(eye.to_array(), [c.x, c.y, lo.z + 0.3 * (hi.z - lo.z)], 45.0)
            }
            CameraPreset::Oblique => {
                let eye = c + Vec3::new(-0.55 * size, -0.7 * size, 0.3 * size + (hi.z - lo.z) * 0.5);
                Camera::look_at(eye.to_array(), [c.x, c.y, lo.z + 0.3 * (hi.z - lo.z)], 45.0)
            }
            CameraPreset::Ground => {
                let x = c.x;
                let y = lo.y + 0.05 * size;
                let mut cam = Camera::ground_at(terrain, x, y, c.y);
                if terrain.height_at(x, y).is_none() {
                    cam.eye[2] = lo.z + 1.7;
                }
                cam
            }
            CameraPreset::Map => {
                let across = (hi.x - lo.x) * height.max(1) as f32 / width.max(1) as f32;
                let half = 0.51 * (hi.y - lo.y).max(across);
                Camera {
                    eye: [c.x, c.y, hi.z + size],
                    target: [c.x, c.y, lo.z],
                    up: [0.0, 1.0, 0.0],
                    projection: Projection::Orthographic { half_height: half.max(1.0) },
                    near: 1.0,
                    far: (hi.z - lo.z) + 2.0 * size + 10.0,
                }
            }
        }
    }

    /// A point on an orbit around the terrain centre at parameter `u` in 0..1 (one full turn,
    /// starting south of the centre, counter-clockwise seen from above), at the overview's
    /// distance and height.
    pub fn orbit(terrain: &TerrainMesh, u: f32) -> Self {
        let (lo, hi) = terrain.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let c = (lo + hi) * 0.5;
        let size = (hi - lo).truncate().max_element().max(1.0);
        let a = -std::f32::consts::FRAC_PI_2 + u * std::f32::consts::TAU;
        let r = 0.85 * size;
        let eye = Vec3::new(c.x + r * a.cos(), c.y + r * a.sin(), hi.z + 0.35 * size);
        Camera::look_at(eye.to_array(), [c.x, c.y, lo.z + 0.3 * (hi.z - lo.z)], 45.0)
    }

    /// View matrix (right-handed).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(Vec3::from(self.eye), Vec3::from(self.target), Vec3::from(self.up))
    }

    /// Projection matrix for `aspect` = width / height (depth range 0..1).
    pub fn proj(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { fov_y_deg } => glam::camera::rh::proj::directx::perspective(fov_y_deg.clamp(1.0, 170.0).to_radians(), aspect, self.near, self.far),
            Projection::Orthographic { half_height } => {
                let hw = half_height * aspect;
                glam::camera::rh::proj::directx::orthographic(-hw, hw, -half_height, half_height, self.near, self.far)
            }
        }
    }

    /// `proj · view`.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.proj(aspect) * self.view()
    }

    /// Size in pixels on screen of an object of `size_m` metres at `pos` for a viewport
    /// `height_px` tall (perspective: `size · f / distance` with `f = h / (2 tan(fov/2))`;
    /// orthographic: `size · h / (2 · half_height)`).
    pub fn projected_size_px(&self, pos: Vec3, size_m: f32, height_px: f32) -> f32 {
        match self.projection {
            Projection::Perspective { fov_y_deg } => {
                let f = height_px / (2.0 * (fov_y_deg.to_radians() * 0.5).tan());
                let d = (pos - Vec3::from(self.eye)).length().max(1e-3);
                size_m * f / d
            }
            Projection::Orthographic { half_height } => size_m * height_px / (2.0 * half_height.max(1e-3)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ground view stands 1.7 m above the drawn surface of a 35° slope of 30 m cells
    /// (between vertices; the nearest vertex put it metres under the slope, a trial's ground
    /// view from below the terrain) and looks north at most 12° up.
    #[test]
    fn ground_view_stands_on_a_steep_slope() {
        let plane = |x: f32, y: f32| 0.7 * x + 0.9 * y;
        let t = crate::render::terrain::tests::plane_mesh(40, 40, 30.0, plane);
        let cam = Camera::preset(CameraPreset::Ground, &t);
        let [x, y, z] = cam.eye;
        assert!((z - plane(x, y) - 1.7).abs() < 1e-2, "eye {:?}, surface {}", cam.eye, plane(x, y));
        let d = Vec3::from(cam.target) - Vec3::from(cam.eye);
        assert!(d.y > 0.0 && d.x.abs() < 1e-3, "looks north: {d:?}");
        let pitch = d.z.atan2(d.y).to_degrees();
        assert!(pitch <= 12.0 + 1e-3 && pitch >= -6.0 - 1e-3, "pitch {pitch}");
    }

    /// A flat terrain mesh of `w` × `h` m (four corner vertices, z 0–10 m).
    fn window(w: f32, h: f32) -> TerrainMesh {
        TerrainMesh { positions: vec![[0.0, 0.0, 0.0], [w, 0.0, 10.0], [0.0, h, 5.0], [w, h, 0.0]], ..TerrainMesh::default() }
    }

    fn half_extents(cam: &Camera, width: u32, height: u32) -> (f32, f32) {
        let Projection::Orthographic { half_height } = cam.projection else { panic!("the map is orthographic") };
        (half_height * width as f32 / height as f32, half_height)
    }

    #[test]
    fn map_fits_the_window_to_the_pictures_shape() {
        // (window w, h (m), picture width, height, the axis that limits it: x or y)
        for (w, h, pw, ph, by_x) in [(3450.0, 2560.0, 1600, 900, false), (1000.0, 3000.0, 1600, 900, false), (4000.0, 500.0, 1600, 900, true), (2000.0, 2000.0, 900, 1600, true)] {
            let cam = Camera::preset_sized(CameraPreset::Map, &window(w, h), pw, ph);
            let (hx, hy) = half_extents(&cam, pw, ph);
            // the whole window shows, centred
            assert!(hx >= 0.5 * w && hy >= 0.5 * h, "{w} x {h} in {pw} x {ph}: {hx} x {hy}");
            assert_eq!((cam.eye[0], cam.eye[1]), (0.5 * w, 0.5 * h));
            // with 2 % to spare on the limiting axis, not more
            let (have, need) = if by_x { (hx, 0.5 * w) } else { (hy, 0.5 * h) };
            assert!((have / need - 1.02).abs() < 1e-4, "{w} x {h} in {pw} x {ph}: {have} for {need}");
        }
        // the old framing of a wide still showed 2.4 times the window's width; now 1.36 times
        let cam = Camera::preset_sized(CameraPreset::Map, &window(3450.0, 2560.0), 1280, 720);
        let (hx, _) = half_extents(&cam, 1280, 720);
        assert!((2.0 * hx / 3450.0 - 1.347).abs() < 0.01, "{}", 2.0 * hx / 3450.0);
        // square pictures and the perspective presets are as before
        let t = window(3450.0, 2560.0);
        assert_eq!(Camera::preset(CameraPreset::Map, &t), Camera::preset_sized(CameraPreset::Map, &t, 7, 7));
        assert_eq!(half_extents(&Camera::preset(CameraPreset::Map, &t), 1, 1).1, 0.51 * 3450.0);
        for p in [CameraPreset::Overview, CameraPreset::Oblique, CameraPreset::Ground] {
            assert_eq!(Camera::preset_sized(p, &t, 1600, 900), Camera::preset(p, &t));
        }
    }
}
