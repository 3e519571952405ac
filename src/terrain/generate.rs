//! Seeded synthetic terrain: fractional Brownian motion blended with ridged multifractal noise
//! (Musgrave, in Ebert et al. 2003, "Texturing and Modeling", ch. 16) from the `noise` crate.

use super::Terrain;
use crate::error::{Error, Result};
use crate::grid::{GeoRef, Grid};
use noise::{Fbm, MultiFractal, NoiseFn, Perlin, RidgedMulti};
use rayon::prelude::*;

/// Generates a `size × size` terrain of `cell_m`-metre cells whose elevations span
/// 0…`relief_m` metres (plus a 100 m base), deterministic for `seed`. Local CRS, latitude 46°N.
///
/// The height is `0.6·fBm + 0.4·ridged` (6 octaves each, base wavelength = grid extent / 3),
/// rescaled to the range. Errors: `size` 0 or above 16384, `cell_m` or `relief_m` not > 0.
pub fn generate(size: usize, cell_m: f64, relief_m: f64, seed: u64) -> Result<Terrain> {
    let bad = |f: &str, v: String, e: &str| Error::Invalid { context: "terrain generate".into(), field: f.into(), value: v, expected: e.into() };
    if size == 0 || size > 16384 {
        return Err(bad("size", size.to_string(), "1..=16384 cells"));
    }
    if !(cell_m > 0.0) || !cell_m.is_finite() {
        return Err(bad("cell_m", cell_m.to_string(), "> 0 metres"));
    }
    if !(relief_m > 0.0) || !relief_m.is_finite() {
        return Err(bad("relief_m", relief_m.to_string(), "> 0 metres"));
    }
    let s32 = (seed ^ (seed >> 32)) as u32;
    let fbm = Fbm::<Perlin>::new(s32).set_octaves(6).set_frequency(1.0);
    let ridged = RidgedMulti::<Perlin>::new(s32.wrapping_add(1)).set_octaves(6).set_frequency(1.0);
    let scale = 3.0 / size as f64;
    let mut data = vec![0f32; size * size];
    data.par_chunks_mut(size).enumerate().for_each(|(r, row)| {
        for (c, v) in row.iter_mut().enumerate() {
            let p = [c as f64 * scale + 0.123, r as f64 * scale + 0.456];
            *v = (0.6 * fbm.get(p) + 0.4 * ridged.get(p)) as f32;
        }
    });
    let (lo, hi) = data.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = (hi - lo).max(1e-6);
    for v in &mut data {
        *v = 100.0 + (*v - lo) / span * relief_m as f32;
    }
    Ok(Terrain {
        elevation: Grid { width: size, height: size, data },
        geo: GeoRef::local(cell_m, 46.0),
        nodata: None,
        source: format!("generated size={size} cell={cell_m}m relief={relief_m}m seed={seed}"),
    })
}
