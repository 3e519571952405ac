//! Growth (summer): height, DBH and crown increments from the species' potential growth ×
//! light response × site suitability, with the species' allometries.

use crate::sim::trees::TreeStore;
use crate::species::SpeciesLibrary;
pub use crate::species::allometry::{effective_age, open_crown_radius, open_dbh, potential_height, potential_increment};
use rayon::prelude::*;

/// Light response (0–1) of growth to relative light `l` by shade tolerance `st` (1–5): the
/// JABOWA/ForClim curves (Botkin et al. 1972; Bugmann 2001) for tolerant
/// `1 − e^(−4.64 (l − 0.05))` and intolerant `2.24 (1 − e^(−1.136 (l − 0.08)))` species, each
/// normalised to 1 in full light and interpolated linearly in `st`.
pub fn light_response(l: f32, st: f32) -> f32 {
    let l = l.clamp(0.0, 1.0);
    let tol = ((1.0 - (-4.64 * (l - 0.05)).exp()) / (1.0 - (-4.64f32 * 0.95).exp())).max(0.0);
    let intol = ((1.0 - (-1.136 * (l - 0.08)).exp()) / (1.0 - (-1.136f32 * 0.92).exp())).max(0.0);
    let w = ((st - 1.0) / 4.0).clamp(0.0, 1.0);
    (w * tol + (1.0 - w) * intol).clamp(0.0, 1.0)
}

/// Updated state of one tree after a growing season.
#[derive(Clone, Copy)]
struct Grown {
    h: f32,
    d: f32,
    r: f32,
    cb: f32,
    v: f32,
}

/// What growth reads (the species) and writes (height, DBH, crown, vigour and age of every tree).
pub struct Growth<'a> {
    /// Species library.
    pub lib: &'a SpeciesLibrary,
    /// Trees: light and suitability read; size, vigour and age written.
    pub trees: &'a mut TreeStore,
}

/// Grows every tree by one season. Height: `ΔH = (H(t_eff + 1) − H(t_eff)) · f(L) · S` with
/// `t_eff` the effective age of the current height, `f` [`light_response`], `S` site suitability.
/// DBH: `ΔD = (D_open(H + ΔH_pot) − D_open(H)) · f(L) · S` (D_open from the height–DBH allometry),
/// so shaded trees become slender. Crown radius: open-grown radius of the new DBH, shrunk by
/// `0.5 + 0.5 L` in shade (crown plasticity); crown base rises to `H (1 − crown_ratio (0.4 + 0.6 L))`
/// and never falls (natural pruning). Vigour memory `v ← 0.7 v + 0.3 f(L)·S` feeds stress mortality.
pub fn run(w: Growth<'_>) {
    let t = &w.trees;
    let lib = &w.lib;
    let out: Vec<Grown> = (0..t.len())
        .into_par_iter()
        .map(|i| {
            let sp = &lib.species[t.species[i] as usize];
            let (h, d) = (t.height[i], t.dbh[i]);
            let l = t.light[i];
            let f = light_response(l, sp.life.shade_tolerance) * t.suitability[i];
            let dh_pot = potential_increment(sp, h);
            let h1 = (h + dh_pot * f).min(sp.life.max_height_m);
            let hp = (h + dh_pot).min(sp.life.max_height_m * 0.999);
            let dd_pot = (open_dbh(sp, hp) - open_dbh(sp, h.min(hp))).max(if h > 1.3 { 0.05 } else { 0.0 });
            let mut d1 = d + dd_pot * f;
            if d1 == 0.0 && h1 > 1.3 {
                d1 = open_dbh(sp, h1) * 0.5;
            }
            let d1 = d1.min(sp.life.max_dbh_cm);
            let lc = l.clamp(0.0, 1.0);
            let r = open_crown_radius(sp, h1, d1) * (0.5 + 0.5 * lc);
            let cb = t.crown_base[i].max(h1 * (1.0 - sp.life.allometry.crown_ratio * (0.4 + 0.6 * lc))).min(h1 * 0.95);
            let v = 0.7 * t.vigour[i] + 0.3 * f;
            Grown { h: h1, d: d1, r, cb, v }
        })
        .collect();
    let t = &mut *w.trees;
    for (i, g) in out.into_iter().enumerate() {
        t.height[i] = g.h;
        t.dbh[i] = g.d;
        t.crown_radius[i] = g.r;
        t.crown_base[i] = g.cb;
        t.vigour[i] = g.v;
        t.age[i] += 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::fixtures::beech_like;

    #[test]
    fn inverses_match() {
        let b = beech_like();
        let h = potential_height(&b, 60.0);
        assert!((effective_age(&b, h) - 60.0).abs() < 0.01);
        let d = open_dbh(&b, 25.0);
        let a = b.life.allometry;
        let h2 = 1.3 + (40.0 - 1.3) * (1.0 - (-a.hd_a * d).exp()).powf(a.hd_b);
        assert!((h2 - 25.0).abs() < 0.01);
        // beech fixture fitted to NW-FVA class I top heights (19.5 m at 50, 32.5 m at 100)
        assert!((potential_height(&b, 50.0) - 19.5).abs() < 0.8, "{}", potential_height(&b, 50.0));
        assert!((potential_height(&b, 100.0) - 32.5).abs() < 0.8);
        for h in [0.2f32, 1.0, 5.0, 20.0, 35.0] {
            let te = effective_age(&b, h);
            let want = (potential_height(&b, te + 1.0) - potential_height(&b, te)).max(0.0);
            assert!((potential_increment(&b, h) - want).abs() < 1e-3 + 1e-3 * want, "h {h}: {} vs {want}", potential_increment(&b, h));
        }
        assert!(light_response(1.0, 1.0) > 0.99 && light_response(0.1, 1.0) < 0.05 && light_response(0.1, 5.0) > 0.15);
    }
}
