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
    HeightIncrement::of(sp).at(h)
}

/// The species' constants of [`potential_increment`] (`H_max`, `p`, `1 / p`, `e^(−k)`), computed
/// once for many trees of a species; [`HeightIncrement::at`] gives the same bits as
/// `potential_increment`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightIncrement {
    hm: f32,
    p: f32,
    inv_p: f32,
    e_k: f32,
}

impl HeightIncrement {
    /// The constants of species `sp`.
    #[inline]
    pub fn of(sp: &Species) -> Self {
        let g = sp.life.growth;
        HeightIncrement { hm: sp.life.max_height_m, p: g.p, inv_p: 1.0 / g.p, e_k: (-g.k).exp() }
    }

    /// [`potential_increment`] at height `h` (m).
    #[inline]
    pub fn at(&self, h: f32) -> f32 {
        let hm = self.hm;
        let rel = (h / hm).clamp(1e-6, 0.9995);
        let q = rel.powf(self.inv_p);
        let h0 = hm * rel;
        let h1 = hm * (1.0 - self.e_k * (1.0 - q)).powf(self.p);
        (h1 - h0).max(0.0)
    }
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
    OpenDbh::of(sp).at(h)
}

/// The species' constants of [`open_dbh`] (`H_max − 1.3`, `1 / b`, `a`, the DBH cap), computed
/// once for many trees of a species; [`OpenDbh::at`] gives the same bits as `open_dbh`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenDbh {
    span: f32,
    inv_b: f32,
    a: f32,
    max_dbh: f32,
}

impl OpenDbh {
    /// The constants of species `sp`.
    #[inline]
    pub fn of(sp: &Species) -> Self {
        let a = sp.life.allometry;
        OpenDbh { span: sp.life.max_height_m - 1.3, inv_b: 1.0 / a.hd_b, a: a.hd_a, max_dbh: sp.life.max_dbh_cm }
    }

    /// [`open_dbh`] at height `h` (m).
    #[inline]
    pub fn at(&self, h: f32) -> f32 {
        if h <= 1.3 {
            return 0.0;
        }
        let q = ((h - 1.3) / self.span).clamp(0.0, 0.999).powf(self.inv_b);
        (-(1.0 - q).ln() / self.a).min(self.max_dbh)
    }
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
