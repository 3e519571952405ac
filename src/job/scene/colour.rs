//! The colours and light of a season: the day drawn for it, its reference sun, a species' foliage
//! colour.

use super::*;

/// Day of year (1–365) used to draw each season: mid-May, mid-July, mid-October, mid-January.
pub fn season_day(season: Season) -> f32 {
    match season {
        Season::Spring => 135.0,
        Season::Summer => 196.0,
        Season::Autumn => 290.0,
        Season::Winter => 15.0,
    }
}

/// The sun of every picture of `season` at latitude `latitude_deg`: its [`season_day`] at
/// [`crate::sun::REFERENCE_HOUR`] (14:00 local solar time).
pub fn season_sun(latitude_deg: f64, season: Season) -> Sun {
    Sun::from_position(latitude_deg as f32, season_day(season), crate::sun::REFERENCE_HOUR)
}

/// Range of a tree's own foliage value about its species' colour ([`tree_tint`]): ×0.85 to
/// ×1.15. ESTIMATE: trees of one species in one stand differ in leaf reflectance in the visible by
/// about this much (leaf chlorophyll and thickness vary with light and age: sun and shade
/// crowns, Hovi et al. 2022, Silva Fennica 56(2) 10683, their spread between trees), and
/// crowns seen from afar differ more by their leaf amount and shading.
pub const TREE_VALUE_RANGE: (f32, f32) = (0.85, 1.15);
/// Largest shift of a tree's red and blue shares against green ([`tree_tint`]): ±4 %, a hue
/// change of a few degrees (ESTIMATE), well under the species' differences (species/README.md).
pub const TREE_HUE_SHIFT: f32 = 0.04;

/// A tree's own factors (linear RGB) on its species' foliage colour, fixed by its `id`: a value
/// in [`TREE_VALUE_RANGE`] on all three channels and a small opposite shift of red and blue
/// ([`TREE_HUE_SHIFT`]), so that a stand of one species is not one flat colour and species
/// patches blend at their edges (round 46, trial 45 defect 13: "painted by numbers"). Each
/// factor lies in [0.85 × 0.96, 1.15 × 1.04]; the same `id` always gives the same factors.
pub fn tree_tint(id: u64) -> [f32; 3] {
    // splitmix64 finaliser of the id: two independent uniforms in [0, 1)
    let mut z = id.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    let u = (z >> 40) as f32 / (1u64 << 24) as f32;
    let w = ((z >> 16) & 0xFF_FFFF) as f32 / (1u64 << 24) as f32;
    let v = TREE_VALUE_RANGE.0 + (TREE_VALUE_RANGE.1 - TREE_VALUE_RANGE.0) * u;
    let h = TREE_HUE_SHIFT * (2.0 * w - 1.0);
    [v * (1.0 + h), v, v * (1.0 - h)]
}

/// Foliage colour (linear RGB) and leaf amount (0–1) of `species` in `season`: its
/// [`foliage_on_day`] on the season's [`season_day`], so that species with different leaf-out and
/// autumn dates differ in the same picture (in mid-May a birch is past its flush while an oak is
/// still unfolding; in mid-October a birch is yellow and thinning while an oak is still turning).
pub fn foliage(species: &Species, season: Season) -> ([f32; 3], f32) {
    foliage_on_day(species, season_day(season))
}

/// Foliage colour (linear RGB) and leaf amount (0–1) of `species` on day of year `doy`
/// (1–365, wrapped), from its phenology (`appearance.leaf_out_doy`, `autumn_doy`,
/// `leaf_fall_doy`; sources in `species/README.md`) and its four colours, blended in linear RGB.
///
/// Deciduous (with `o` = leaf-out, `a` = autumn colour, `f` = leaf fall): bare before `o`;
/// leaves unfold over `o..o+15` (amount 0 → 1, spring colour); spring → summer colour over
/// `o+15..o+45`; summer → autumn colour over `a−20..a`; leaves fall over `f−10..f+14`
/// (amount 1 → 0; BBCH 95 at `f` ≈ half fallen). Evergreen: winter colour from `f` until
/// 30 days before the flush, back to summer by `o`, the light new shoots (spring colour, blended
/// half-way) over `o..o+45`, summer → winter colour over `a..f`; always fully leaved.
pub fn foliage_on_day(species: &Species, doy: f32) -> ([f32; 3], f32) {
    let a = &species.appearance;
    let (spring, summer, autumn, winter) = (srgb_to_linear(a.leaf_spring), srgb_to_linear(a.leaf_summer), srgb_to_linear(a.leaf_autumn), srgb_to_linear(a.leaf_winter));
    let lerp = |x: [f32; 3], y: [f32; 3], t: f32| {
        let t = t.clamp(0.0, 1.0);
        [x[0] + (y[0] - x[0]) * t, x[1] + (y[1] - x[1]) * t, x[2] + (y[2] - x[2]) * t]
    };
    let ramp = |d: f32, from: f32, to: f32| ((d - from) / (to - from).max(1e-3)).clamp(0.0, 1.0);
    let d = doy.rem_euclid(365.0);
    let (o, au, f) = (a.leaf_out_doy, a.autumn_doy, a.leaf_fall_doy);
    if species.identity.deciduous {
        if d < o || d > f + 14.0 {
            return (autumn, 0.0);
        }
        let amount = ramp(d, o, o + 15.0) * (1.0 - ramp(d, f - 10.0, f + 14.0));
        let c = if d < au - 20.0 { lerp(spring, summer, ramp(d, o + 15.0, o + 45.0)) } else { lerp(summer, autumn, ramp(d, au - 20.0, au)) };
        (c, amount)
    } else {
        let c = if d >= f || d < o - 30.0 {
            winter
        } else if d < o {
            lerp(winter, summer, ramp(d, o - 30.0, o))
        } else if d < au {
            // the flush: new shoots half-way to the spring colour, fading into the summer colour
            let k = 0.5 * (1.0 - ramp(d, o + 15.0, o + 45.0)) * ramp(d, o, o + 5.0);
            lerp(summer, spring, k)
        } else {
            lerp(summer, winter, ramp(d, au, f))
        };
        (c, 1.0)
    }
}
