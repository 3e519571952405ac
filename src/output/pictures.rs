//! Pictures on disk: PNG stills and frame sequences, animated GIFs (`image`), MP4 through
//! `ffmpeg` when it is on `PATH`. All files are written atomically (temporary file + rename).

use super::{OutputError, Result};
use crate::error::Error;
use std::path::{Path, PathBuf};

/// Writes `frames` as `dir/frame_00000.png`, ... (atomically, one file each) and returns the
/// paths.
///
/// # Errors
/// [`OutputError::Io`] when the folder cannot be created or a file written; [`OutputError::Encode`] when PNG
/// encoding fails.
pub fn write_png_frames(dir: &Path, frames: &[image::RgbaImage]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| OutputError::io(dir, e))?;
    let mut paths = Vec::new();
    for (i, f) in frames.iter().enumerate() {
        let p = dir.join(format!("frame_{i:05}.png"));
        write_png(&p, f)?;
        paths.push(p);
    }
    Ok(paths)
}

/// Writes one image as PNG atomically: an opaque image (every alpha 255: the renderer's
/// frames, stills and maps) as 8-bit RGB, others as RGBA, zlib's default level with adaptive
/// filters. Lossless either way; a reader's RGBA is the image given. Issue 34: the default
/// run's stills and frames are 13–20 % smaller than as RGBA at `image`'s fast default.
///
/// # Errors
/// [`OutputError::Io`] / [`OutputError::Encode`] as for [`write_png_frames`].
pub fn write_png(path: &Path, img: &image::RgbaImage) -> Result<()> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::{ExtendedColorType, ImageEncoder};
    let mut bytes = Vec::new();
    let enc = PngEncoder::new_with_quality(&mut bytes, CompressionType::Default, FilterType::Adaptive);
    let (w, h) = img.dimensions();
    let res = if img.pixels().all(|p| p.0[3] == 255) {
        let rgb: Vec<u8> = img.as_raw().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        enc.write_image(&rgb, w, h, ExtendedColorType::Rgb8)
    } else {
        enc.write_image(img.as_raw(), w, h, ExtendedColorType::Rgba8)
    };
    res.map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "PNG", message: e.to_string() })?;
    super::write_atomic(path, &bytes)
}

/// Writes `frames` as an endlessly looping animated GIF at `fps` frames per second (1..=100)
/// ([`GifWriter`] with every frame).
///
/// # Errors
/// [`Error::Invalid`] (in [`OutputError::Input`]) for no frames, frames of different sizes or a bad `fps`;
/// [`OutputError::Encode`] when encoding fails; [`OutputError::Io`] when writing fails.
pub fn write_gif(path: &Path, frames: &[image::RgbaImage], fps: f32) -> Result<()> {
    let mut w = GifWriter::new(path, fps)?;
    for f in frames {
        w.add(f.clone())?;
    }
    w.finish()
}

/// The encoded bytes of a [`GifWriter`], shared with its encoder.
#[derive(Clone, Default)]
struct SharedBytes(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl std::io::Write for SharedBytes {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// An endlessly looping animated GIF encoded frame by frame as the frames are made, so that
/// only the encoded file is held, not every frame (issue 34: the default run's 61 frames of
/// 640 × 360 were 56 MB held until the end of the film); written atomically by
/// [`GifWriter::finish`].
pub struct GifWriter {
    path: PathBuf,
    bytes: SharedBytes,
    enc: image::codecs::gif::GifEncoder<SharedBytes>,
    delay: image::Delay,
    size: Option<(u32, u32)>,
}

impl GifWriter {
    /// A GIF to be written to `path` at `fps` frames per second (1..=100).
    ///
    /// # Errors
    /// [`Error::Invalid`] (in [`OutputError::Input`]) for a bad `fps`; [`OutputError::Encode`]
    /// when the encoder refuses the loop setting.
    pub fn new(path: &Path, fps: f32) -> Result<GifWriter> {
        if !(fps >= 1.0 && fps <= 100.0) {
            return Err(Error::Invalid { context: path.display().to_string(), field: "fps".into(), value: fps.to_string(), expected: "1..=100 frames per second".into() }.into());
        }
        let bytes = SharedBytes::default();
        let mut enc = image::codecs::gif::GifEncoder::new_with_speed(bytes.clone(), 10);
        enc.set_repeat(image::codecs::gif::Repeat::Infinite).map_err(|e| OutputError::Encode { path: path.to_path_buf(), format: "GIF", message: e.to_string() })?;
        Ok(GifWriter { path: path.to_path_buf(), bytes, enc, delay: image::Delay::from_numer_denom_ms((1000.0 / fps).round() as u32, 1), size: None })
    }

    /// Encodes the next frame.
    ///
    /// # Errors
    /// [`Error::Invalid`] (in [`OutputError::Input`]) for a frame of another size than the
    /// first; [`OutputError::Encode`] when encoding fails.
    pub fn add(&mut self, frame: image::RgbaImage) -> Result<()> {
        let dims = frame.dimensions();
        if let Some((w, h)) = self.size.filter(|&s| s != dims) {
            return Err(Error::Invalid { context: self.path.display().to_string(), field: "frame size".into(), value: format!("{dims:?}"), expected: format!("all frames {w}x{h}") }.into());
        }
        self.size = Some(dims);
        self.enc.encode_frame(image::Frame::from_parts(frame, 0, 0, self.delay)).map_err(|e| OutputError::Encode { path: self.path.clone(), format: "GIF", message: e.to_string() })
    }

    /// Ends the GIF and writes it atomically.
    ///
    /// # Errors
    /// [`Error::Invalid`] (in [`OutputError::Input`]) when no frame was added; [`OutputError::Io`]
    /// when writing fails.
    pub fn finish(self) -> Result<()> {
        let GifWriter { path, bytes, enc, size, .. } = self;
        if size.is_none() {
            return Err(Error::Invalid { context: path.display().to_string(), field: "frames".into(), value: "0".into(), expected: "at least one frame".into() }.into());
        }
        // the encoder writes the GIF trailer when dropped
        drop(enc);
        let bytes = std::mem::take(&mut *bytes.0.borrow_mut());
        super::write_atomic(&path, &bytes)
    }
}

/// Path of `ffmpeg` when it is found on `PATH`.
pub fn find_ffmpeg() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join("ffmpeg")).find(|p| p.is_file())
}

/// Encodes the PNG frames `dir/frame_%05d.png` into an H.264 MP4 at `fps` with `ffmpeg` when it
/// is installed. Returns `Ok(false)` (and writes nothing) when `ffmpeg` is not on `PATH`.
///
/// ffmpeg writes a temporary file beside `out` ([`super::temporary_path`]), renamed to `out`
/// when it succeeds, so no half-encoded film is left at `out`.
///
/// # Errors
/// [`OutputError::Encode`] when `ffmpeg` cannot be run or fails; [`OutputError::Io`] when the
/// rename fails.
pub fn write_mp4(dir: &Path, fps: f32, out: &Path) -> Result<bool> {
    let Some(ff) = find_ffmpeg() else { return Ok(false) };
    // ffmpeg writes a temporary file (`-f mp4`: its name has no .mp4 suffix), renamed when done
    let tmp = super::temporary_path(out);
    let status = std::process::Command::new(ff)
        .args(["-y", "-loglevel", "error", "-framerate"])
        .arg(format!("{fps}"))
        .arg("-i")
        .arg(dir.join("frame_%05d.png"))
        .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", "-c:v", "libx264", "-f", "mp4"])
        .arg(&tmp)
        .status();
    let failed = match status {
        Ok(s) if s.success() => None,
        Ok(s) => Some(format!("ffmpeg failed ({s})")),
        Err(e) => Some(format!("cannot run ffmpeg: {e}")),
    };
    if let Some(message) = failed {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::Encode { path: out.to_path_buf(), format: "MP4", message });
    }
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::io(out, e)
    })?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gif_and_png_frames_are_written_and_decodable() {
        let dir = tempfile::tempdir().unwrap();
        let frames: Vec<image::RgbaImage> = (0..3).map(|i| image::RgbaImage::from_pixel(8, 6, image::Rgba([i * 80, 100, 50, 255]))).collect();
        let gif = dir.path().join("a.gif");
        write_gif(&gif, &frames, 12.0).unwrap();
        let dec = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(std::fs::File::open(&gif).unwrap())).unwrap();
        use image::AnimationDecoder;
        let got = dec.into_frames().collect_frames().unwrap();
        assert_eq!(got.len(), 3);
        assert_eq!(got[0].buffer().dimensions(), (8, 6));
        let paths = write_png_frames(&dir.path().join("frames"), &frames).unwrap();
        assert_eq!(paths.len(), 3);
        assert_eq!(image::open(&paths[2]).unwrap().to_rgba8().get_pixel(0, 0).0, [160, 100, 50, 255]);
        // opaque images as RGB, the others as RGBA; both read back as given
        assert_eq!(image::open(&paths[2]).unwrap().color(), image::ColorType::Rgb8);
        let mut see_through = frames[1].clone();
        see_through.put_pixel(3, 2, image::Rgba([1, 2, 3, 4]));
        let p = dir.path().join("alpha.png");
        write_png(&p, &see_through).unwrap();
        let back = image::open(&p).unwrap();
        assert_eq!((back.color(), back.to_rgba8()), (image::ColorType::Rgba8, see_through));
        assert_eq!(image::open(&paths[1]).unwrap().to_rgba8(), frames[1]);
        assert!(write_gif(&gif, &[], 12.0).is_err());
        assert!(write_gif(&gif, &frames, 0.0).is_err());
    }
}
