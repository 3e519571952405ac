//! Plan canopy cover of a frame's crowns, which colours the ground under them.

use super::*;

/// Plan canopy cover (0..1) per sample of `g` from the crowns of `instances` (saplings count
/// with weight `0.3 · h / 4 m`: grass still grows among young saplings): each crown of radius `r` adds to the samples within it the anti-aliased cover
/// `clamp((r − d)/s + 0.5, 0, 1)` of their centre at distance `d` (`s` the sample spacing),
/// then a 3 × 3 box blur softens the forest edge.
pub fn canopy_cover(instances: &[TreeInstance], g: &crate::render::terrain::GroundGrid) -> Vec<f32> {
    let (w, h) = (g.heights.width, g.heights.height);
    let mut cov = vec![0.0f32; w * h];
    let s = g.cell_x.min(g.cell_y).max(1e-3);
    for t in instances {
        let weight = if t.id & SAPLING_ID_BIT != 0 { 0.3 * (t.height / 4.0).min(1.0) } else { 1.0 } * t.opacity.clamp(0.0, 1.0);
        let r = t.crown_radius.max(0.3);
        let (x, y) = (t.position[0], t.position[1]);
        let c0 = (((x - r - g.origin[0]) / g.cell_x - 0.5).floor().max(0.0)) as usize;
        let c1 = ((((x + r - g.origin[0]) / g.cell_x - 0.5).ceil()).max(0.0) as usize).min(w - 1);
        let rr0 = ((h as f32 - (y + r - g.origin[1]) / g.cell_y - 0.5).floor().max(0.0)) as usize;
        let rr1 = (((h as f32 - (y - r - g.origin[1]) / g.cell_y - 0.5).ceil()).max(0.0) as usize).min(h - 1);
        for rr in rr0..=rr1 {
            let py = g.origin[1] + (h as f32 - rr as f32 - 0.5) * g.cell_y;
            for c in c0..=c1 {
                let px = g.origin[0] + (c as f32 + 0.5) * g.cell_x;
                let d = (px - x).hypot(py - y);
                let a = ((r - d) / s + 0.5).clamp(0.0, 1.0);
                if a > 0.0 {
                    cov[rr * w + c] += a * weight;
                }
            }
        }
    }
    let mut out = vec![0.0f32; w * h];
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut k) = (0.0, 0.0);
            for rr in r.saturating_sub(1)..=(r + 1).min(h - 1) {
                for cc in c.saturating_sub(1)..=(c + 1).min(w - 1) {
                    sum += cov[rr * w + cc].min(1.0);
                    k += 1.0;
                }
            }
            out[r * w + c] = sum / k;
        }
    }
    out
}
