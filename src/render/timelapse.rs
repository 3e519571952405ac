//! Timelapses: interpolation between snapshots (growth, recruitment, death), frame writers
//! (PNG per frame, animated GIF with `image`, MP4 through `ffmpeg` when it is on `PATH`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::scene::TreeInstance;
use crate::{Error, Result};

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

/// Writes `frames` as `dir/frame_00000.png`, ... (atomically, one file each) and returns the
/// paths.
///
/// # Errors
/// [`Error::Io`] when the folder cannot be created or a file written; [`Error::Render`] when PNG
/// encoding fails.
pub fn write_png_frames(dir: &Path, frames: &[image::RgbaImage]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut paths = Vec::new();
    for (i, f) in frames.iter().enumerate() {
        let p = dir.join(format!("frame_{i:05}.png"));
        write_png(&p, f)?;
        paths.push(p);
    }
    Ok(paths)
}

/// Writes one image as PNG atomically.
///
/// # Errors
/// [`Error::Io`] / [`Error::Render`] as for [`write_png_frames`].
pub fn write_png(path: &Path, img: &image::RgbaImage) -> Result<()> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(|e| Error::Render(format!("{}: PNG encoding failed: {e}", path.display())))?;
    crate::output::write_atomic(path, &bytes)
}

/// Writes `frames` as an endlessly looping animated GIF at `fps` frames per second (1..=100).
///
/// # Errors
/// [`Error::Invalid`] for no frames, frames of different sizes or a bad `fps`;
/// [`Error::Render`] when encoding fails; [`Error::Io`] when writing fails.
pub fn write_gif(path: &Path, frames: &[image::RgbaImage], fps: f32) -> Result<()> {
    let inv = |field: &str, value: String, expected: &str| Error::Invalid { context: path.display().to_string(), field: field.into(), value, expected: expected.into() };
    if frames.is_empty() {
        return Err(inv("frames", "0".into(), "at least one frame"));
    }
    if !(fps >= 1.0 && fps <= 100.0) {
        return Err(inv("fps", fps.to_string(), "1..=100 frames per second"));
    }
    let (w, h) = frames[0].dimensions();
    if let Some(f) = frames.iter().find(|f| f.dimensions() != (w, h)) {
        return Err(inv("frame size", format!("{:?}", f.dimensions()), &format!("all frames {w}x{h}")));
    }
    let mut bytes = Vec::new();
    {
        let mut enc = image::codecs::gif::GifEncoder::new_with_speed(&mut bytes, 10);
        enc.set_repeat(image::codecs::gif::Repeat::Infinite).map_err(|e| Error::Render(format!("{}: GIF: {e}", path.display())))?;
        let delay = image::Delay::from_numer_denom_ms((1000.0 / fps).round() as u32, 1);
        for f in frames {
            enc.encode_frame(image::Frame::from_parts(f.clone(), 0, 0, delay)).map_err(|e| Error::Render(format!("{}: GIF encoding failed: {e}", path.display())))?;
        }
    }
    crate::output::write_atomic(path, &bytes)
}

/// Path of `ffmpeg` when it is found on `PATH`.
pub fn find_ffmpeg() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join("ffmpeg")).find(|p| p.is_file())
}

/// Encodes the PNG frames `dir/frame_%05d.png` into an H.264 MP4 at `fps` with `ffmpeg` when it
/// is installed. Returns `Ok(false)` (and writes nothing) when `ffmpeg` is not on `PATH`.
///
/// # Errors
/// [`Error::Render`] when `ffmpeg` runs but fails.
pub fn write_mp4(dir: &Path, fps: f32, out: &Path) -> Result<bool> {
    let Some(ff) = find_ffmpeg() else { return Ok(false) };
    let status = std::process::Command::new(ff)
        .args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-i")
        .arg(dir.join("frame_%05d.png"))
        .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", "-c:v", "libx264"])
        .arg(out)
        .status()
        .map_err(|e| Error::Render(format!("cannot run ffmpeg: {e}")))?;
    if !status.success() {
        return Err(Error::Render(format!("ffmpeg failed ({status}) writing {}", out.display())));
    }
    Ok(true)
}
