//! The far-field canopy layer: crowns of trees too small on screen to be worth geometry,
//! splatted into a grid of terrain texels (coverage + colour) that the terrain shader blends in.
//!
//! This is the terrain-scale renderers' answer to "100,000 trees": beyond a few pixels a tree is
//! a patch of crown colour on the ground, so the far forest costs a fixed-size grid instead of
//! triangles per tree. The grid is rebuilt every frame from the instances below the far-field
//! switch ([`crate::render::lod::canopy_threshold`]): on the CPU by [`CanopyGrid::splat`], or on
//! the GPU by the culling compute pass (`shaders/cull.wgsl`, `splat`), with the same integer
//! arithmetic so both give the same sums whatever the order (integer additions commute).
//!
//! Per texel four `u32` sums in units of 1/[`CANOPY_ONE`]: crown coverage (area fraction of the
//! texel, overlapping crowns add up), and coverage-weighted linear RGB albedo. The terrain
//! shader (`shaders/scene.wgsl`, `canopy_at`) filters them bilinearly, divides colour by
//! coverage, and turns the plan coverage `c` into the coverage seen along an oblique view ray
//! with a Beer–Lambert-like exponent, `1 − (1 − c)^(1 + k·cot θ)`, θ the view's elevation
//! angle, k = 2.5 (the side area of a crown over its plan area: ≈ 1.5 for a crown as tall as
//! it is wide, more for the taller crowns of the stand-in and EcoMod trees; tuned so that the
//! layer matches the billboard forest it replaces, `tests/render_canopy.rs`).

/// Fixed-point unit of the canopy sums (1.0 = 1024).
pub const CANOPY_ONE: f32 = 1024.0;
/// Largest grid side (texels).
pub const CANOPY_MAX_SIDE: u32 = 1024;
/// Smallest texel (m).
pub const CANOPY_MIN_TEXEL_M: f32 = 2.0;
/// Largest footprint half-width of one splat (texels): crowns wider than 4 texels are spread
/// over at most 9 × 9 texels with their full area.
pub const SPLAT_HALF: i32 = 4;

/// The texel grid of the canopy layer over the terrain's plan bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanopyGrid {
    /// South-west corner (m): x, y of the terrain's minimum.
    pub origin: [f32; 2],
    /// Texel size (m).
    pub texel: f32,
    /// Texels along x and y (≥ 1).
    pub nx: u32,
    /// Texels along y.
    pub ny: u32,
}

impl CanopyGrid {
    /// Grid over plan bounds `lo..hi` (m): texel `max(extent / 1024, 2 m)` so the grid has at
    /// most 1024 texels per side.
    pub fn for_bounds(lo: [f32; 3], hi: [f32; 3]) -> Self {
        let ex = (hi[0] - lo[0]).max(1.0);
        let ey = (hi[1] - lo[1]).max(1.0);
        let texel = (ex.max(ey) / CANOPY_MAX_SIDE as f32).max(CANOPY_MIN_TEXEL_M);
        let nx = ((ex / texel).ceil() as u32).clamp(1, CANOPY_MAX_SIDE);
        let ny = ((ey / texel).ceil() as u32).clamp(1, CANOPY_MAX_SIDE);
        CanopyGrid { origin: [lo[0], lo[1]], texel, nx, ny }
    }

    /// Number of texels.
    pub fn len(&self) -> usize {
        self.nx as usize * self.ny as usize
    }

    /// Whether the grid has no texels (never, by construction).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Adds one crown to `sums` (`len()` records of coverage, r, g, b): a disc of radius `r`
    /// (m) at plan position `(x, y)` with weight `w` (0..1: canopy weight × opacity × foliage
    /// cover) and albedo `rgb`. Each texel within [`SPLAT_HALF`] of the centre texel gets the
    /// anti-aliased cover `clamp((r − d)/texel + 0.5, 0, 1)` of its centre at distance `d`,
    /// rescaled so the covers sum to the crown's area in texels (`π r² / texel²`), so that the
    /// plan coverage is area-true for crowns smaller or larger than a texel. Mirrors `splat` in
    /// `shaders/cull.wgsl`. Crowns outside the grid are clipped.
    pub fn splat(&self, sums: &mut [[u32; 4]], x: f32, y: f32, r: f32, w: f32, rgb: [f32; 3]) {
        if sums.len() < self.len() {
            return;
        }
        self.footprint(x, y, r, w, rgb, |k, add| {
            let s = &mut sums[k];
            for ch in 0..4 {
                s[ch] = s[ch].saturating_add(add[ch]);
            }
        });
    }

    /// Takes back what [`CanopyGrid::splat`] with the same arguments added (the same integer
    /// texel amounts, so a crown splatted and taken back leaves the sums as they were, whatever
    /// else was splatted in between, as long as no sum saturated); for a canopy layer baked once
    /// from many trees (`render::farfield`) from which the trees drawn as geometry in a frame
    /// are taken out. Sums never go below 0.
    pub fn unsplat(&self, sums: &mut [[u32; 4]], x: f32, y: f32, r: f32, w: f32, rgb: [f32; 3]) {
        if sums.len() < self.len() {
            return;
        }
        self.footprint(x, y, r, w, rgb, |k, sub| {
            let s = &mut sums[k];
            for ch in 0..4 {
                s[ch] = s[ch].saturating_sub(sub[ch]);
            }
        });
    }

    /// Calls `at(texel index, [coverage, r, g, b])` with the integer amounts one crown adds to
    /// each texel it covers (see [`CanopyGrid::splat`]).
    fn footprint(&self, x: f32, y: f32, r: f32, w: f32, rgb: [f32; 3], mut at: impl FnMut(usize, [u32; 4])) {
        if !(w > 0.0 && r > 0.0) {
            return;
        }
        let t = self.texel;
        let u = (x - self.origin[0]) / t;
        let v = (y - self.origin[1]) / t;
        let (ci, cj) = (u.floor() as i32, v.floor() as i32);
        let rt = r / t;
        let half = (rt.ceil() as i32).clamp(1, SPLAT_HALF);
        let mut total = 0.0f32;
        for dj in -half..=half {
            for di in -half..=half {
                let (du, dv) = ((ci + di) as f32 + 0.5 - u, (cj + dj) as f32 + 0.5 - v);
                total += (rt - (du * du + dv * dv).sqrt() + 0.5).clamp(0.0, 1.0);
            }
        }
        if !(total > 0.0) {
            return;
        }
        let k = std::f32::consts::PI * rt * rt / total * w * CANOPY_ONE;
        for dj in -half..=half {
            for di in -half..=half {
                let (i, j) = (ci + di, cj + dj);
                if i < 0 || j < 0 || i >= self.nx as i32 || j >= self.ny as i32 {
                    continue;
                }
                let (du, dv) = (i as f32 + 0.5 - u, j as f32 + 0.5 - v);
                let c = (rt - (du * du + dv * dv).sqrt() + 0.5).clamp(0.0, 1.0) * k;
                if !(c > 0.0) {
                    continue;
                }
                let mut add = [c.round() as u32, 0, 0, 0];
                for ch in 0..3 {
                    add[ch + 1] = (c * rgb[ch].clamp(0.0, 1.0)).round() as u32;
                }
                at(j as usize * self.nx as usize + i as usize, add);
            }
        }
    }
}

/// Albedo and cover factor of a crown in the canopy layer for leaf colour `leaf`, leaf amount
/// `la` (0..1) and bark colour `bark`: leaves cover `la` of the crown, bare twigs half of the
/// rest (the billboard's twig haze, `twig_density` of `shaders/scene.wgsl`) in the twig colour
/// `mix(bark, (0.16, 0.14, 0.12), 0.6)`. Returns (albedo, cover 0.5..1). Mirrors
/// `crown_albedo` of `shaders/cull.wgsl`.
pub fn crown_albedo(leaf: [f32; 3], la: f32, bark: [f32; 3]) -> ([f32; 3], f32) {
    let la = la.clamp(0.0, 1.0);
    let tw = 0.5 * (1.0 - la);
    let cover = la + tw;
    let twig = [0.16, 0.14, 0.12];
    let mut c = [0.0; 3];
    for k in 0..3 {
        let tc = bark[k] + (twig[k] - bark[k]) * 0.6;
        c[k] = (la * leaf[k] + tw * tc) / cover.max(1e-6);
    }
    (c, cover)
}

/// Bounds of the stems of `instances` (m, those with a finite position) and the tallest
/// finite height (m, over all of them); `None` when no position is finite.
pub fn tree_extent(instances: &[super::scene::TreeInstance]) -> Option<([f32; 3], [f32; 3], f32)> {
    let (lo, hi) = crate::mesh::points_bounds(instances.iter().map(|t| &t.position).filter(|p| p.iter().all(|v| v.is_finite())))?;
    Some((lo, hi, instances.iter().map(|t| t.height).filter(|h| h.is_finite()).fold(0.0f32, f32::max)))
}

/// Height above the ground (m) at which the canopy layer's crowns take their sun visibility from
/// the shadow map: 0.85 × the crown-area-weighted mean height of `instances` (about the sunlit
/// upper crown of the mean tree; 0 without trees). Looked up at the ground instead, the layer
/// would lie in the shadow of every tree drawn as geometry above it and read darker than the
/// same crowns drawn as billboards.
pub fn canopy_light_height(instances: &[super::scene::TreeInstance]) -> f32 {
    let (mut a, mut ah) = (0.0f64, 0.0f64);
    for t in instances.iter().filter(|t| t.height.is_finite() && t.height > 0.0 && t.crown_radius.is_finite()) {
        let w = f64::from(t.crown_radius * t.crown_radius * t.opacity.clamp(0.0, 1.0));
        a += w;
        ah += w * f64::from(t.height);
    }
    if a > 0.0 {
        (0.85 * ah / a) as f32
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splats_conserve_crown_area_and_colour() {
        let g = CanopyGrid::for_bounds([0.0, 0.0, 0.0], [200.0, 100.0, 10.0]);
        assert_eq!((g.nx, g.ny, g.texel), (100, 50, 2.0));
        for r in [0.5f32, 1.3, 3.0, 7.0] {
            let mut s = vec![[0u32; 4]; g.len()];
            g.splat(&mut s, 101.3, 50.7, r, 1.0, [0.1, 0.4, 0.05]);
            let cov: u64 = s.iter().map(|v| v[0] as u64).sum();
            let area = std::f32::consts::PI * r * r / 4.0 * CANOPY_ONE;
            // 9 × 9 texels hold a crown of radius ≤ 9 m with its full area (rounding aside)
            assert!((cov as f32 - area).abs() <= 81.0, "r {r}: {cov} vs {area}");
            let g_sum: u64 = s.iter().map(|v| v[2] as u64).sum();
            assert!((g_sum as f32 / cov as f32 - 0.4).abs() < 0.01);
        }
        // outside the grid: clipped, no panic
        let mut s = vec![[0u32; 4]; g.len()];
        g.splat(&mut s, -50.0, 20.0, 3.0, 1.0, [1.0; 3]);
        assert!(s.iter().all(|v| v[0] == 0));
        g.splat(&mut s, 0.5, 0.5, 3.0, 0.0, [1.0; 3]);
        assert!(s.iter().all(|v| v[0] == 0));
    }

    #[test]
    fn a_crown_taken_back_leaves_the_other_sums_as_they_were() {
        let g = CanopyGrid::for_bounds([0.0, 0.0, 0.0], [200.0, 100.0, 10.0]);
        let mut s = vec![[0u32; 4]; g.len()];
        g.splat(&mut s, 50.3, 40.1, 3.2, 0.8, [0.2, 0.5, 0.1]);
        let before = s.clone();
        g.splat(&mut s, 51.7, 41.9, 5.1, 0.6, [0.3, 0.4, 0.2]);
        assert_ne!(s, before);
        g.unsplat(&mut s, 51.7, 41.9, 5.1, 0.6, [0.3, 0.4, 0.2]);
        assert_eq!(s, before);
    }

    #[test]
    fn bare_crowns_are_half_covered_in_twig_colour() {
        let (c, f) = crown_albedo([0.1, 0.5, 0.1], 1.0, [0.3, 0.2, 0.1]);
        assert_eq!((c, f), ([0.1, 0.5, 0.1], 1.0));
        let (c, f) = crown_albedo([0.1, 0.5, 0.1], 0.0, [0.3, 0.2, 0.1]);
        assert_eq!(f, 0.5);
        assert!((c[0] - (0.3 + (0.16 - 0.3) * 0.6)).abs() < 1e-6);
    }
}
