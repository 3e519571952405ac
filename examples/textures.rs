//! Contact sheet of Sylva's procedural textures (`structure::texture`): every leaf shape's card
//! (top row, over a dark background so the alpha shows), then per shape the cluster, crown and
//! billboard pictures, and the four bark patterns.
//! Run: `cargo run --example textures -- docs/gallery/textures.png`
use image::{Rgba, RgbaImage};
use sylva::structure::texture::*;

fn over(dst: &mut RgbaImage, src: &RgbaImage, x0: u32, y0: u32, w: u32, h: u32) {
    for y in 0..h {
        for x in 0..w {
            let p = src.get_pixel(x * src.width() / w, y * src.height() / h).0;
            let a = p[3] as f32 / 255.0;
            let d = dst.get_pixel_mut(x0 + x, y0 + y);
            for k in 0..3 {
                d.0[k] = (p[k] as f32 * a + d.0[k] as f32 * (1.0 - a)).round() as u8;
            }
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "textures.png".into());
    let green = [80, 130, 50];
    let n = LeafShape::ALL.len() as u32;
    let (cw, ch) = (96u32, 192u32);
    let mut sheet = RgbaImage::from_pixel(n * cw, ch + 3 * cw + cw, Rgba([40, 40, 44, 255]));
    for (i, s) in LeafShape::ALL.iter().enumerate() {
        let x = i as u32 * cw;
        over(&mut sheet, &tint(&leaf_texture(*s), green), x, 0, cw, ch);
        over(&mut sheet, &tint(&cluster_texture(*s, 128), green), x, ch, cw, cw);
        over(&mut sheet, &tint(&crown_texture(*s, 128), green), x, ch + cw, cw, cw);
        over(&mut sheet, &tint(&impostor_texture(*s, 128), green), x, ch + 2 * cw, cw, cw);
    }
    for (i, p) in [BarkPattern::Smooth, BarkPattern::Fissured, BarkPattern::Plated, BarkPattern::Lenticelled].iter().enumerate() {
        let rgb = if *p == BarkPattern::Lenticelled { [235, 235, 228] } else { [130, 110, 90] };
        over(&mut sheet, &bark_texture(rgb, *p, 128, 1), i as u32 * cw, ch + 3 * cw, cw, cw);
    }
    sylva::output::pictures::write_png(std::path::Path::new(&out), &sheet)?;
    println!("wrote {out}");
    Ok(())
}
