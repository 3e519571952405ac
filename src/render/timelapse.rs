//! Timelapses: interpolation between snapshots (growth, recruitment, death) and frame
//! sequences. Writing the frames (PNG, GIF, MP4) is [`crate::output::pictures`]'s.

use std::collections::HashMap;
use std::time::Instant;

use super::scene::TreeInstance;
use super::{RenderError, Result};
use crate::Error;

/// Trees at fraction `t` (0..1) between snapshot `a` and snapshot `b`, matched by
/// [`TreeInstance::id`]:
/// - in both: position, height, crown radius, colours and leaf amount interpolate linearly
///   (growth); species and rotation come from `b`;
/// - only in `b` (recruits): scale in from 30 % size and fade in (opacity × t);
/// - only in `a` (dead or harvested): fade out (opacity × (1 − t)), no growth.
///
/// The result is sorted by id, so it does not depend on input order. `t` is clamped to 0..1.
pub fn interpolate(a: &[TreeInstance], b: &[TreeInstance], t: f32) -> Vec<TreeInstance> {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let lerp = |x: f32, y: f32| x + (y - x) * t;
    let lerp3 = |x: [f32; 3], y: [f32; 3]| [lerp(x[0], y[0]), lerp(x[1], y[1]), lerp(x[2], y[2])];
    let in_b: HashMap<u64, &TreeInstance> = b.iter().map(|x| (x.id, x)).collect();
    let in_a: HashMap<u64, &TreeInstance> = a.iter().map(|x| (x.id, x)).collect();
    let mut out = Vec::with_capacity(a.len().max(b.len()));
    for x in a {
        match in_b.get(&x.id) {
            Some(y) => out.push(TreeInstance {
                position: lerp3(x.position, y.position),
                height: lerp(x.height, y.height),
                crown_radius: lerp(x.crown_radius, y.crown_radius),
                species: y.species,
                rotation: y.rotation,
                leaf_color: lerp3(x.leaf_color, y.leaf_color),
                leaf_amount: lerp(x.leaf_amount, y.leaf_amount),
                opacity: lerp(x.opacity, y.opacity),
                id: x.id,
                sky_fade: lerp(x.sky_fade, y.sky_fade),
                crown_base: lerp(x.crown_base, y.crown_base),
            }),
            None => out.push(TreeInstance { opacity: x.opacity * (1.0 - t), ..*x }),
        }
    }
    for y in b {
        if !in_a.contains_key(&y.id) {
            let s = 0.3 + 0.7 * t;
            out.push(TreeInstance { height: y.height * s, crown_radius: y.crown_radius * s, opacity: y.opacity * t, ..*y });
        }
    }
    out.sort_by_key(|x| x.id);
    out
}

/// Progress of a timelapse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Frames done.
    pub done: usize,
    /// Frames in total.
    pub total: usize,
    /// Mean frames per second so far.
    pub fps: f32,
}

/// A frame-rate meter that reports [`Progress`] to a callback.
pub struct ProgressMeter<F: FnMut(Progress)> {
    start: Instant,
    total: usize,
    done: usize,
    callback: F,
}

impl<F: FnMut(Progress)> ProgressMeter<F> {
    /// Starts timing `total` frames.
    pub fn new(total: usize, callback: F) -> Self {
        ProgressMeter { start: Instant::now(), total, done: 0, callback }
    }
    /// Records one finished frame and calls the callback.
    pub fn tick(&mut self) {
        self.done += 1;
        let s = self.start.elapsed().as_secs_f32().max(1e-6);
        (self.callback)(Progress { done: self.done, total: self.total, fps: self.done as f32 / s });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(id: u64, h: f32) -> TreeInstance {
        TreeInstance::new(id, [id as f32, 0.0, 0.0], h, h * 0.3, 0, [0.1, 0.3, 0.05])
    }

    #[test]
    fn growing_recruit_and_dying_trees() {
        let a = vec![tree(1, 10.0), tree(2, 20.0)];
        let b = vec![tree(3, 4.0), tree(1, 14.0)];
        let m = interpolate(&a, &b, 0.25);
        assert_eq!(m.iter().map(|t| t.id).collect::<Vec<_>>(), vec![1, 2, 3]);
        assert!((m[0].height - 11.0).abs() < 1e-5);
        assert_eq!(m[0].opacity, 1.0);
        // dying tree fades out without growing
        assert_eq!(m[1].height, 20.0);
        assert!((m[1].opacity - 0.75).abs() < 1e-6);
        // recruit scales and fades in
        assert!((m[2].opacity - 0.25).abs() < 1e-6);
        assert!((m[2].height - 4.0 * (0.3 + 0.7 * 0.25)).abs() < 1e-5);
        // end points
        let end = interpolate(&a, &b, 1.0);
        assert_eq!(end[1].opacity, 0.0);
        assert_eq!(end[0].height, 14.0);
        assert_eq!(end[2].height, 4.0);
        assert_eq!(interpolate(&a, &b, 0.0)[0].height, 10.0);
        // order independence
        let mut b2 = b.clone();
        b2.reverse();
        assert_eq!(interpolate(&a, &b2, 0.4), interpolate(&a, &b, 0.4));
    }

    #[test]
    fn progress_meter_counts_frames() {
        let mut seen = Vec::new();
        let mut m = ProgressMeter::new(2, |p: Progress| seen.push(p.done));
        m.tick();
        m.tick();
        assert_eq!(seen, vec![1, 2]);
    }
}

/// Renders a timelapse through a series of snapshots: `steps_per_snapshot` frames between each
/// consecutive pair (growth interpolated with [`interpolate`]), plus the last snapshot, so
/// `(snapshots − 1) · steps + 1` frames (one frame for a single snapshot). `camera(u)` gives
/// the camera at film position `u` in 0..1 (e.g. [`super::camera::Camera::orbit`]); the wind
/// time advances by `1 / fps` per frame. `progress` is called after every frame.
///
/// # Errors
/// [`Error::Invalid`] when there is no snapshot or `steps_per_snapshot` is 0; rendering errors
/// from [`super::headless::Renderer::render`].
#[allow(clippy::too_many_arguments)]
pub fn render_sequence(
    renderer: &mut super::headless::Renderer,
    base: &super::scene::Scene,
    snapshots: &[Vec<TreeInstance>],
    steps_per_snapshot: usize,
    fps: f32,
    camera: impl Fn(f32) -> super::camera::Camera,
    size: (u32, u32),
    progress: impl FnMut(Progress),
) -> Result<Vec<image::RgbaImage>> {
    if snapshots.is_empty() || steps_per_snapshot == 0 {
        return Err(RenderError::Input(Error::Invalid {
            context: "render::timelapse::render_sequence".into(),
            field: if snapshots.is_empty() { "snapshots".into() } else { "steps_per_snapshot".into() },
            value: "0".into(),
            expected: "at least 1".into(),
        }));
    }
    let total = (snapshots.len() - 1) * steps_per_snapshot + 1;
    let mut meter = ProgressMeter::new(total, progress);
    let mut scene = base.clone();
    let mut frames = Vec::with_capacity(total);
    for k in 0..total {
        let (i, j) = (k / steps_per_snapshot, k % steps_per_snapshot);
        scene.instances = if i + 1 >= snapshots.len() { snapshots[snapshots.len() - 1].clone() } else { interpolate(&snapshots[i], &snapshots[i + 1], j as f32 / steps_per_snapshot as f32) };
        scene.wind.time_s = base.wind.time_s + k as f32 / fps.max(1e-3);
        let u = if total > 1 { k as f32 / (total - 1) as f32 } else { 0.0 };
        frames.push(renderer.render(&scene, &camera(u), size.0, size.1)?);
        meter.tick();
    }
    Ok(frames)
}
