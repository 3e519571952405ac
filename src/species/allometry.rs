//! The species' allometries, one implementation used by the simulation (`sim`), the crown
//! envelopes of the growth models (`structure::grow::envelope`) and the [`Species`] methods:
//! potential height over age (Chapman–Richards), the height–DBH curve and its inverse, the
//! crown radius. Units: heights in metres, DBH in centimetres, ages in years.

use super::Species;

/// Potential (open-grown, fully suitable site) height (m) at age `t` (years):
/// Chapman–Richards `H(t) = H_max (1 − e^(−k t))^p` (species file, `life.growth`; `H_max` its
/// asymptote `h_max_m`, else `max_height_m`).
pub fn potential_height(sp: &Species, t: f32) -> f32 {
    let g = sp.life.growth;
    g.asymptote_m(sp.life.max_height_m) * (1.0 - (-g.k * t.max(0.0)).exp()).powf(g.p)
}

/// Effective age (years) of height `h` on the Chapman–Richards curve (its inverse).
pub fn effective_age(sp: &Species, h: f32) -> f32 {
    let g = sp.life.growth;
    let q = (h / g.asymptote_m(sp.life.max_height_m)).clamp(1e-6, 0.9995).powf(1.0 / g.p);
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
        HeightIncrement { hm: g.asymptote_m(sp.life.max_height_m), p: g.p, inv_p: 1.0 / g.p, e_k: (-g.k).exp() }
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

/// A curve of height (m) that [`Table`] samples: [`HeightIncrement`], [`OpenDbh`].
pub trait Curve {
    /// The curve's value at height `h` (m), exact.
    fn at(&self, h: f32) -> f32;
}

impl Curve for HeightIncrement {
    #[inline]
    fn at(&self, h: f32) -> f32 {
        HeightIncrement::at(self, h)
    }
}

/// Steps of a [`Table`] (its samples: one more).
pub const TABLE_STEPS: usize = 4096;

/// A species' curve `c` of height read from [`TABLE_STEPS`] equal steps of heights `lo..hi`
/// (m) by linear interpolation between the samples `c.at(lo + k · step)`, and from `c` itself
/// (exact) outside that range, where it bends too sharply for the table: the growth phase's
/// per-tree curves without a power or logarithm per tree (about 13 % of the load bench's CPU
/// was their `powf`/`logf`, BENCHMARKS.md). Within `lo..hi` the value differs from `c.at` by
/// at most 5 · 10⁻⁵ of the curve's range (tested for the embedded species: at most 3.7 · 10⁻⁵
/// for the height increment, of silver fir, about 10⁻⁵ m a year; below 10⁻⁶ for the open-grown
/// DBH); ESTIMATE of what the model tolerates: far below the spread of the trees' growth
/// factors (σ = 0.15).
#[derive(Debug, Clone, PartialEq)]
pub struct Table<C> {
    exact: C,
    lo: f32,
    hi: f32,
    inv_step: f32,
    v: Vec<f32>,
}

impl<C: Curve> Table<C> {
    /// Samples `exact` on `lo..hi` (m; `lo < hi`, finite).
    pub fn new(exact: C, lo: f32, hi: f32) -> Self {
        let step = (hi as f64 - lo as f64) / TABLE_STEPS as f64;
        let v = (0..=TABLE_STEPS).map(|k| exact.at((lo as f64 + k as f64 * step) as f32)).collect();
        Table { exact, lo, hi, inv_step: (1.0 / step) as f32, v }
    }

    /// No table: [`Table::at`] is `exact.at` everywhere (for species that grow no trees).
    pub fn exact(exact: C) -> Self {
        Table { exact, lo: 0.0, hi: 0.0, inv_step: 0.0, v: Vec::new() }
    }

    /// The curve at height `h` (m): interpolated in `lo..hi`, exact elsewhere (and for NaN).
    #[inline]
    pub fn at(&self, h: f32) -> f32 {
        if !(h >= self.lo && h < self.hi) {
            return self.exact.at(h);
        }
        let u = (h - self.lo) * self.inv_step;
        let k = (u as usize).min(TABLE_STEPS - 1);
        let t = u - k as f32;
        let (a, b) = (self.v[k], self.v[k + 1]);
        a + t * (b - a)
    }
}

impl HeightIncrement {
    /// [`HeightIncrement::at`] as a [`Table`] on heights from `H_max / 64` (below, the curve's
    /// root `(h / H_max)^(1/p)` is too steep for a table) to `0.99 · H_max` (near the clamp at
    /// 0.9995).
    pub fn table(self) -> Table<HeightIncrement> {
        let hm = self.hm;
        Table::new(self, hm / 64.0, 0.99 * hm)
    }
}

impl OpenDbh {
    /// [`OpenDbh::at`] as a [`Table`] on `(H − 1.3) / (H_max − 1.3)` from 1/64 (below, the root
    /// `x^(1/b)` is too steep) to 0.9 (above, `−ln(1 − q)` is).
    pub fn table(self) -> Table<OpenDbh> {
        let span = self.span;
        Table::new(self, 1.3 + span / 64.0, 1.3 + 0.9 * span)
    }
}

impl Curve for OpenDbh {
    #[inline]
    fn at(&self, h: f32) -> f32 {
        OpenDbh::at(self, h)
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

/// Stand-grown crown radius (m) of a tree of DBH `dbh` (cm), height `h` (m) and crown base `cb`
/// (m): half the crown width of the species' [`crate::species::StandCrown`],
/// `CW = (a + b · d^p) · (1 − e^(−(d / c)^e)) · (h − cb)^g` (Döbbeler et al. 2001/2002 as in
/// BWINPro/TreeGrOSS), at least 0 m; `None` for a species without one. 0 m below breast height
/// (no DBH).
pub fn stand_crown_radius(sp: &Species, dbh: f32, h: f32, cb: f32) -> Option<f32> {
    let c = sp.life.stand_crown?;
    if dbh <= 0.0 {
        return Some(0.0);
    }
    let sat = 1.0 - (-(dbh / c.c).powf(c.e)).exp();
    let len = if c.g == 0.0 { 1.0 } else { (h - cb).max(0.1).powf(c.g) };
    Some((0.5 * (c.a + c.b * dbh.powf(c.p)) * sat * len).max(0.0))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The tables of every embedded species agree with the exact curves to 5 · 10⁻⁵ of the
    /// curve's range, on a sweep of heights finer than the table's steps and across its ends.
    #[test]
    fn tables_follow_the_exact_curves() {
        let lib = crate::species::SpeciesLibrary::embedded().unwrap();
        for sp in &lib.species {
            let (inc, dbh) = (HeightIncrement::of(sp), OpenDbh::of(sp));
            let (ti, td) = (inc.table(), dbh.table());
            let hm = sp.life.max_height_m;
            let n = 200_000;
            let hs: Vec<f32> = (0..=n).map(|k| 1.01 * hm * k as f32 / n as f32).collect();
            let range = |f: &dyn Fn(f32) -> f32| hs.iter().map(|&h| f(h)).fold(0f32, f32::max);
            let (ri, rd) = (range(&|h| inc.at(h)), range(&|h| dbh.at(h)));
            let (mut ei, mut ed) = (0f32, 0f32);
            for &h in &hs {
                ei = ei.max((ti.at(h) - inc.at(h)).abs());
                ed = ed.max((td.at(h) - dbh.at(h)).abs());
            }
            eprintln!("{}: height increment within {:.2e} of its range, open-grown DBH within {:.2e}", sp.id, ei / ri, ed / rd);
            assert!(ei <= 5e-5 * ri, "{}: height increment off by {ei} m (range {ri} m)", sp.id);
            assert!(ed <= 5e-5 * rd, "{}: open-grown DBH off by {ed} cm (range {rd} cm)", sp.id);
            // outside the tables' ranges: the exact curves, bit for bit
            // (the height increment's table spans its curve's asymptote, which may differ
            // from the species' maximum height: `life.growth.h_max_m`)
            let ha = sp.life.growth.asymptote_m(hm);
            for h in [0.0f32, 0.3, ha / 65.0, 0.995 * ha, ha, 1.2, 1.3 + (ha - 1.3) * 0.95] {
                if !(h >= ha / 64.0 && h < 0.99 * ha) {
                    assert_eq!(ti.at(h).to_bits(), inc.at(h).to_bits(), "{} at {h} m", sp.id);
                }
            }
            assert_eq!(td.at(1.3 + (hm - 1.3) * 0.95).to_bits(), dbh.at(1.3 + (hm - 1.3) * 0.95).to_bits());
        }
    }
}
