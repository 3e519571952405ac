//! The species' allometries, one implementation used by the simulation (`sim`), the crown
//! envelopes of the growth models (`structure::grow::envelope`) and the [`Species`] methods:
//! potential height over age (Chapman–Richards), the height–DBH curve and its inverse, the
//! crown radius. Units: heights in metres, DBH in centimetres, ages in years.

use super::Species;

/// Potential (open-grown, fully suitable site) height (m) at age `t` (years):
/// Chapman–Richards `H(t) = H_max (1 − e^(−k t))^p` (species file, `life.growth`).
pub fn potential_height(sp: &Species, t: f32) -> f32 {
    let g = sp.life.growth;
    sp.life.max_height_m * (1.0 - (-g.k * t.max(0.0)).exp()).powf(g.p)
}

/// Effective age (years) of height `h` on the Chapman–Richards curve (its inverse).
pub fn effective_age(sp: &Species, h: f32) -> f32 {
    let g = sp.life.growth;
    let q = (h / sp.life.max_height_m).clamp(1e-6, 0.9995).powf(1.0 / g.p);
    -(1.0 - q).ln() / g.k
}

/// One year's potential height increment (m) of a tree of height `h` (m) on the
/// Chapman–Richards curve: `H(t_eff + 1) − H(t_eff)` with `t_eff` = [`effective_age`]`(h)`, in
/// closed form — with q = (h / H_max)^(1/p) = 1 − e^(−k t_eff),
/// `H(t_eff + 1) = H_max (1 − e^(−k) (1 − q))^p` — which saves the logarithm and one exponential
/// of the round trip (same clamping of h / H_max to [10⁻⁶, 0.9995]).
#[inline]
pub fn potential_increment(sp: &Species, h: f32) -> f32 {
    let g = sp.life.growth;
    let hm = sp.life.max_height_m;
    let rel = (h / hm).clamp(1e-6, 0.9995);
    let q = rel.powf(1.0 / g.p);
    let h0 = hm * rel;
    let h1 = hm * (1.0 - (-g.k).exp() * (1.0 - q)).powf(g.p);
    (h1 - h0).max(0.0)
}

/// Height (m) of a tree of diameter `dbh` (cm) from the species' height–DBH allometry
/// `H = 1.3 + (H_max − 1.3)(1 − e^(−a D))^b` (species file `life.allometry.hd_a`, `hd_b`;
/// the Chapman–Richards form of height–diameter curves, Richards 1959), `D` floored at 0.
pub fn height_from_dbh(sp: &Species, dbh: f32) -> f32 {
    let a = sp.life.allometry;
    1.3 + (sp.life.max_height_m - 1.3) * (1.0 - (-a.hd_a * dbh.max(0.0)).exp()).powf(a.hd_b)
}

/// Open-grown DBH (cm) of a tree of height `h` (m): the inverse of [`height_from_dbh`], with
/// `(H − 1.3)/(H_max − 1.3)` clamped to 0–0.999; 0 at or below 1.3 m; capped at
/// `life.max_dbh_cm`.
pub fn open_dbh(sp: &Species, h: f32) -> f32 {
    let a = sp.life.allometry;
    let hm = sp.life.max_height_m;
    if h <= 1.3 {
        return 0.0;
    }
    let q = ((h - 1.3) / (hm - 1.3)).clamp(0.0, 0.999).powf(1.0 / a.hd_b);
    (-(1.0 - q).ln() / a.hd_a).min(sp.life.max_dbh_cm)
}

/// Open-grown crown radius (m) of a tree of diameter `dbh` (cm): the linear crown allometry
/// `r = c0 + c1 · D` (species file, `life.allometry`; the form of Pretzsch 2009, ch. 8, fitted
/// per species), with `D` floored at 0.
pub fn crown_radius(sp: &Species, dbh: f32) -> f32 {
    let a = sp.life.allometry;
    a.crown_c0 + a.crown_c1 * dbh.max(0.0)
}

/// Open-grown crown radius (m) of a tree of height `h` (m) and diameter `dbh` (cm):
/// [`crown_radius`] at and above breast height; below it (no DBH yet) `c0 · h / 1.3`, at least
/// 0.05 m.
pub fn open_crown_radius(sp: &Species, h: f32, dbh: f32) -> f32 {
    let a = sp.life.allometry;
    if h < 1.3 {
        (a.crown_c0 * h / 1.3).max(0.05)
    } else {
        crown_radius(sp, dbh)
    }
}
