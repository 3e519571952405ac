//! The viewer's interactive camera: orbit (drag to turn around a target, pan, zoom) and fly
//! (look around from the eye, move with the keys), and the pick ray through a pixel.

use glam::Vec3;

use crate::render::camera::Camera;

/// How the pointer and keys move the camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Turn around a target point; drag = orbit, right/middle drag = pan, wheel = zoom.
    Orbit,
    /// Turn the view from the eye; W/A/S/D forward/left/back/right, Q/E down/up.
    Fly,
}

/// Orbit/fly camera state. Angles in radians: `yaw` from +x (east) counter-clockwise seen from
/// above, `pitch` above the horizontal; the view direction is
/// (cos pitch cos yaw, cos pitch sin yaw, sin pitch) pointing from the eye to what is seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraRig {
    /// Current mode.
    pub mode: Mode,
    /// Point turned around in orbit mode (m).
    pub target: Vec3,
    /// Eye distance from the target in orbit mode (m), > 0.
    pub distance: f32,
    /// Heading of the view direction (rad).
    pub yaw: f32,
    /// Pitch of the view direction (rad, −89° … 89°; negative looks down).
    pub pitch: f32,
    /// Eye in fly mode (m).
    pub eye: Vec3,
    /// Vertical field of view (degrees).
    pub fov_y_deg: f32,
    /// Size of the scene (m): scales pan, zoom limits, fly speed and clip planes.
    pub scene_size: f32,
}

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

impl CameraRig {
    /// Looking at the centre of the box `lo..hi` from the south-west and above, as the oblique
    /// still does (`CameraPreset::Oblique`).
    pub fn framing(lo: [f32; 3], hi: [f32; 3]) -> Self {
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let size = (hi - lo).truncate().max_element().max(1.0);
        let target = Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z + 0.3 * (hi.z - lo.z));
        let eye = Vec3::new(target.x - 0.55 * size, target.y - 0.7 * size, target.z + 0.3 * size + 0.2 * (hi.z - lo.z));
        Self::looking(eye, target, size)
    }

    /// A rig in orbit mode with its eye at `eye` looking at `target`.
    pub fn looking(eye: Vec3, target: Vec3, scene_size: f32) -> Self {
        let d = target - eye;
        let distance = d.length().max(0.1);
        let yaw = d.y.atan2(d.x);
        let pitch = (d.z / distance).clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        CameraRig { mode: Mode::Orbit, target, distance, yaw, pitch, eye, fov_y_deg: 45.0, scene_size: scene_size.max(1.0) }
    }

    /// Unit view direction (from the eye towards what is seen).
    pub fn forward(&self) -> Vec3 {
        Vec3::new(self.pitch.cos() * self.yaw.cos(), self.pitch.cos() * self.yaw.sin(), self.pitch.sin())
    }

    /// Unit right vector (horizontal).
    pub fn right(&self) -> Vec3 {
        Vec3::new(self.yaw.sin(), -self.yaw.cos(), 0.0)
    }

    /// The eye position (m).
    pub fn eye_position(&self) -> Vec3 {
        match self.mode {
            Mode::Orbit => self.target - self.forward() * self.distance,
            Mode::Fly => self.eye,
        }
    }

    /// Switches mode keeping the view: to fly, the eye stays where it is; to orbit, the target
    /// is the point at the current distance ahead.
    pub fn set_mode(&mut self, mode: Mode) {
        if mode == self.mode {
            return;
        }
        match mode {
            Mode::Fly => self.eye = self.eye_position(),
            Mode::Orbit => self.target = self.eye + self.forward() * self.distance,
        }
        self.mode = mode;
    }

    /// Turns the view by a pointer drag of `dx, dy` pixels (0.3° per pixel): in orbit mode
    /// the eye moves around the target, in fly mode the view turns around the eye. Dragging
    /// right turns the view to the left (the scene follows the pointer), up raises the eye.
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        let k = 0.3f32.to_radians();
        self.yaw -= dx * k;
        self.pitch = (self.pitch + dy * k * if self.mode == Mode::Orbit { -1.0 } else { 1.0 }).clamp(-MAX_PITCH, MAX_PITCH);
        if self.mode == Mode::Orbit {
            self.pitch = self.pitch.min(-0.01);
        }
    }

    /// Moves the target (orbit) or eye (fly) in the view plane so that the point under the
    /// pointer follows a drag of `dx, dy` pixels in a viewport `height_px` tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height_px: f32) {
        let depth = match self.mode {
            Mode::Orbit => self.distance,
            Mode::Fly => 0.05 * self.scene_size,
        };
        let m_per_px = 2.0 * depth * (0.5 * self.fov_y_deg.to_radians()).tan() / height_px.max(1.0);
        let up = self.right().cross(self.forward());
        let d = (-self.right() * dx + up * dy) * m_per_px;
        match self.mode {
            Mode::Orbit => self.target += d,
            Mode::Fly => self.eye += d,
        }
    }

    /// Applies a 3-D view's pointer input to the camera, the same way in the viewer and the
    /// editor: primary drag turns ([`CameraRig::rotate`]), secondary or middle drag pans
    /// ([`CameraRig::pan`], `rect_height_px` the view's height in points), the wheel over the
    /// view zooms ([`CameraRig::zoom`], one step per 50 points of scroll).
    pub fn drive(&mut self, ui: &eframe::egui::Ui, resp: &eframe::egui::Response, rect_height_px: f32) {
        use eframe::egui::PointerButton;
        if resp.dragged_by(PointerButton::Primary) {
            let d = resp.drag_delta();
            self.rotate(d.x, d.y);
        }
        if resp.dragged_by(PointerButton::Secondary) || resp.dragged_by(PointerButton::Middle) {
            let d = resp.drag_delta();
            self.pan(d.x, d.y, rect_height_px);
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.zoom(scroll / 50.0);
            }
        }
    }

    /// Zooms by `steps` wheel notches (positive: closer): the orbit distance is multiplied by
    /// 0.9^steps (kept within 1 m … 4 × the scene size); in fly mode the eye moves forward by
    /// 2 % of the scene size per notch.
    pub fn zoom(&mut self, steps: f32) {
        match self.mode {
            Mode::Orbit => self.distance = (self.distance * 0.9f32.powf(steps)).clamp(1.0, 4.0 * self.scene_size),
            Mode::Fly => self.eye += self.forward() * steps * 0.02 * self.scene_size,
        }
    }

    /// Flies for `dt` seconds with the keys held: `forward`, `right`, `up` in −1…1; speed 10 % of
    /// the scene size per second (×4 with `fast`). In orbit mode the target moves instead.
    pub fn fly(&mut self, forward: f32, right: f32, up: f32, dt: f32, fast: bool) {
        let speed = 0.1 * self.scene_size * if fast { 4.0 } else { 1.0 };
        let flat = Vec3::new(self.yaw.cos(), self.yaw.sin(), 0.0);
        let along = if self.mode == Mode::Fly { self.forward() } else { flat };
        let d = (along * forward + self.right() * right + Vec3::Z * up) * speed * dt;
        match self.mode {
            Mode::Orbit => self.target += d,
            Mode::Fly => self.eye += d,
        }
    }

    /// The render camera (perspective, clip planes from the distance and the scene size).
    pub fn camera(&self) -> Camera {
        let eye = self.eye_position();
        let target = eye + self.forward() * self.distance.max(1.0);
        let mut c = Camera::look_at(eye.to_array(), target.to_array(), self.fov_y_deg);
        c.near = match self.mode {
            Mode::Orbit => (self.distance * 0.002).clamp(0.05, 5.0),
            Mode::Fly => 0.1,
        };
        c.far = 6.0 * self.scene_size + 2.0 * self.distance + 1000.0;
        c
    }

    /// The ray through pixel `(px, py)` of a `w × h` viewport (origin top left): origin at the
    /// eye, unit direction.
    pub fn ray(&self, px: f32, py: f32, w: f32, h: f32) -> (Vec3, Vec3) {
        let cam = self.camera();
        let aspect = w.max(1.0) / h.max(1.0);
        let inv = cam.view_proj(aspect).inverse();
        let ndc = glam::Vec2::new(2.0 * px / w.max(1.0) - 1.0, 1.0 - 2.0 * py / h.max(1.0));
        let near = inv.project_point3(Vec3::new(ndc.x, ndc.y, 0.0));
        let far = inv.project_point3(Vec3::new(ndc.x, ndc.y, 1.0));
        let eye = Vec3::from(cam.eye);
        (eye, (far - near).normalize_or(self.forward()))
    }
}

/// The tree hit first by the ray `origin + s·dir` (s > 0) among `trees` given as
/// `(base position, height, crown radius)` (m): each tree is the vertical segment from its base to
/// its top with radius max(crown radius, 0.5 m); returns the index of the nearest hit along the
/// ray, or `None`.
pub fn pick(origin: Vec3, dir: Vec3, trees: &[(Vec3, f32, f32)]) -> Option<usize> {
    let mut best: Option<(f32, usize)> = None;
    for (i, &(base, h, r)) in trees.iter().enumerate() {
        let (dist, s) = ray_segment(origin, dir, base, base + Vec3::Z * h.max(0.1));
        if s > 0.0 && dist <= r.max(0.5) && best.is_none_or(|b| s < b.0) {
            best = Some((s, i));
        }
    }
    best.map(|b| b.1)
}

/// Closest approach of the ray `o + s·d` (unit `d`) and the segment `a..b`: (distance, s).
fn ray_segment(o: Vec3, d: Vec3, a: Vec3, b: Vec3) -> (f32, f32) {
    let u = b - a;
    let w = o - a;
    let (aa, bb, cc, dd, ee) = (d.dot(d), d.dot(u), u.dot(u), d.dot(w), u.dot(w));
    let den = aa * cc - bb * bb;
    let mut t = if den.abs() < 1e-9 { 0.0 } else { ((aa * ee - bb * dd) / den).clamp(0.0, 1.0) };
    let mut s = (bb * t - dd) / aa;
    if s < 0.0 {
        s = 0.0;
        t = if cc > 0.0 { (ee / cc).clamp(0.0, 1.0) } else { 0.0 };
    }
    let p = o + d * s;
    let q = a + u * t;
    ((p - q).length(), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_looks_at_the_centre_from_the_south_west() {
        let r = CameraRig::framing([0.0, 0.0, 0.0], [100.0, 100.0, 10.0]);
        let eye = r.eye_position();
        assert!(eye.x < 50.0 && eye.y < 50.0 && eye.z > 3.0, "{eye}");
        let f = r.forward();
        let to_target = (r.target - eye).normalize();
        assert!((f - to_target).length() < 1e-4);
        assert!((r.target - Vec3::new(50.0, 50.0, 3.0)).length() < 1e-4);
    }

    #[test]
    fn orbit_keeps_the_distance_and_zoom_shrinks_it() {
        let mut r = CameraRig::framing([0.0, 0.0, 0.0], [100.0, 100.0, 10.0]);
        let d0 = (r.eye_position() - r.target).length();
        r.rotate(200.0, -30.0);
        assert!(((r.eye_position() - r.target).length() - d0).abs() < 1e-3);
        r.zoom(2.0);
        assert!((r.distance - d0 * 0.81).abs() < 1e-3);
        // a half turn of yaw puts the eye on the other side of the target
        let mut h = CameraRig::looking(Vec3::new(-10.0, 0.0, 10.0), Vec3::ZERO, 100.0);
        h.rotate(180.0 / 0.3, 0.0);
        assert!((h.eye_position().x - 10.0).abs() < 1e-3, "{}", h.eye_position());
    }

    #[test]
    fn pan_moves_the_target_by_the_dragged_ground_distance() {
        // looking straight down from 100 m with 90° fov: the viewport is 200 m tall
        let mut r = CameraRig::looking(Vec3::new(0.0, -0.001, 100.0), Vec3::ZERO, 500.0);
        r.fov_y_deg = 90.0;
        let t0 = r.target;
        r.pan(0.0, 100.0, 200.0);
        // 100 of 200 px → 100 m, moving the target "up" in the picture (north, the yaw side)
        let moved = r.target - t0;
        assert!((moved.length() - 100.0).abs() < 0.5, "{moved}");
    }

    #[test]
    fn fly_mode_moves_the_eye_and_switching_back_keeps_the_view() {
        let mut r = CameraRig::framing([0.0, 0.0, 0.0], [100.0, 100.0, 10.0]);
        let before = r.camera();
        r.set_mode(Mode::Fly);
        assert_eq!(r.camera().eye, before.eye);
        r.fly(1.0, 0.0, 0.0, 1.0, false);
        let moved = r.eye - Vec3::from(before.eye);
        assert!((moved.length() - 10.0).abs() < 1e-3 && moved.dot(r.forward()) > 9.99);
        r.set_mode(Mode::Orbit);
        assert!((r.eye_position() - r.eye).length() < 1e-3);
    }

    #[test]
    fn the_centre_ray_picks_the_tree_in_front_and_misses_the_others() {
        let r = CameraRig::looking(Vec3::new(0.0, -50.0, 5.0), Vec3::new(0.0, 0.0, 5.0), 100.0);
        let (o, d) = r.ray(400.0, 300.0, 800.0, 600.0);
        assert!((d - Vec3::Y).length() < 1e-3, "{d}");
        let trees = [(Vec3::new(20.0, 0.0, 0.0), 20.0, 3.0), (Vec3::new(0.5, 10.0, 0.0), 20.0, 2.0), (Vec3::new(0.0, 30.0, 0.0), 20.0, 4.0)];
        assert_eq!(pick(o, d, &trees), Some(1));
        // a ray over the trees' tops hits nothing
        let (o2, d2) = r.ray(400.0, 0.0, 800.0, 600.0);
        assert!(d2.z > 0.3);
        assert_eq!(pick(o2, d2, &trees), None);
    }
}
