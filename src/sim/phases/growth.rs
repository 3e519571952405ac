//! Growth (summer): height, DBH and crown increments from the species' potential growth ×
//! light response × site suitability, with the species' allometries.

use crate::rng::{salt, Stream};
use crate::sim::density::Crowding;
use crate::sim::rules;
use crate::sim::trees::{birth_id, TreeStore};
use crate::species::allometry::{HeightIncrement, OpenDbh, Table};
use crate::species::{BaiBwinpro, BaiCompetition, ClosedHdScope, DenseHd, Species, SpeciesId, SpeciesLibrary};
pub use crate::species::allometry::{effective_age, open_crown_radius, open_dbh, potential_height, potential_increment};
use rayon::prelude::*;

/// Light response (0–1) of growth to relative light `l` by shade tolerance `st` (1–5): the
/// JABOWA/ForClim curves (Botkin et al. 1972; Bugmann 2001) for tolerant
/// `1 − e^(−4.64 (l − 0.05))` and intolerant `2.24 (1 − e^(−1.136 (l − 0.08)))` species, each
/// normalised to 1 in full light and interpolated linearly in `st`.
pub fn light_response(l: f32, st: f32) -> f32 {
    let l = l.clamp(0.0, 1.0);
    let w = ((st - 1.0) / 4.0).clamp(0.0, 1.0);
    // At a weight of exactly 0 (ST 1) or 1 (ST 5) the other curve is not evaluated: it would
    // enter the sum as 0 · x with x finite and ≥ 0, which adds +0 and leaves the sum's bits as
    // they are.
    let tol = if w > 0.0 { ((1.0 - (-4.64 * (l - 0.05)).exp()) / (1.0 - (-4.64f32 * 0.95).exp())).max(0.0) } else { 0.0 };
    let intol = if w < 1.0 { ((1.0 - (-1.136 * (l - 0.08)).exp()) / (1.0 - (-1.136f32 * 0.92).exp())).max(0.0) } else { 0.0 };
    (w * tol + (1.0 - w) * intol).clamp(0.0, 1.0)
}

/// Relative density at which crowding starts to reduce diameter increment: 0.4 of the
/// maximum-density line (Long 1985, Forestry Chronicle 61:23–27: 35 % of SDI_max is the lower
/// limit of full site occupancy, 60 % the onset of self-thinning).
pub const RD_ONSET: f32 = 0.4;
/// Relative size `D / Dq` above which a tree takes only the dominants' share [`PHI_DOMINANT`] of
/// the crowding (size-asymmetric competition: Schwinning & Weiner 1998, Oecologia 113:447–455).
pub const S_DOMINANT: f32 = 1.3;
/// Share of the crowding pressure that dominant trees bear (0–1).
pub const PHI_DOMINANT: f32 = 0.3;
/// Standard deviation of the log of a tree's persistent diameter-growth factor (micro-site and
/// genotype: even-aged stands reach a DBH coefficient of variation of 20–30 % by age 30,
/// Pretzsch 2009 ch. 8; a lognormal factor of σ = 0.15 starts that differentiation).
pub const GROWTH_SIGMA: f64 = 0.15;

/// Crowding modifier (0–1) of diameter increment for a tree of relative size `s = D / Dq`
/// (DBH over the neighbourhood's quadratic mean DBH) at local relative density `rd`
/// ([`crate::sim::density`]): `m = clamp(1 − P · φ(s), 0, 1)` with the crowding pressure
/// `P = x³ (1 + 4 max(0, x − 1))`, `x = max(0, rd − RD_ONSET) / (1 − RD_ONSET)` (0 below the
/// onset, 1 on the maximum-density line, steep beyond it) and the size share
/// `φ(s) = clamp(S_DOMINANT + 0.2 − s, PHI_DOMINANT, 1)`: on the line suppressed trees
/// (`s` ≲ 0.5) stop growing in diameter, mean trees keep half their increment and dominants 70 %;
/// above it growth stops but for a floor `0.1 · clamp((s − 0.8) / 0.5, 0, 1)` that keeps the
/// dominants alive while the suppressed die. Model choice (ESTIMATE), in the spirit of the
/// relative-density growth modifiers of distance-independent models (e.g. Sterba's PROGNAUS,
/// Monserud & Sterba 1996, For. Ecol. Manage. 80:57–80).
pub fn crowding_modifier(rd: f32, s: f32) -> f32 {
    let x = (rd - RD_ONSET).max(0.0) / (1.0 - RD_ONSET);
    let p = x.powi(3) * (1.0 + 4.0 * (x - 1.0).max(0.0));
    let phi = (S_DOMINANT + 0.2 - s).clamp(PHI_DOMINANT, 1.0);
    let floor = 0.1 * ((s - 0.8) / 0.5).clamp(0.0, 1.0);
    (1.0 - p * phi).clamp(floor, 1.0)
}

/// Share (0.5–1) of the potential height increment that crowding leaves a tree of relative size
/// `s` with crowding modifier `m`: `1 − 0.5 (1 − m) · clamp((1.2 − s) / 0.7, 0, 1)`. Trees at
/// or above 1.2 × Dq keep their full height growth (height growth of dominants depends little
/// on density: Assmann 1970, The Principles of Forest Yield Study), suppressed trees (s ≤ 0.5)
/// lose up to half of it and fall behind.
pub fn height_share(m: f32, s: f32) -> f32 {
    1.0 - 0.5 * (1.0 - m) * ((1.2 - s) / 0.7).clamp(0.0, 1.0)
}

/// Competition modifier (0–1) of the diameter increment of a species with PROGNAUS's
/// competition terms `bc` ([`BaiCompetition`]): the basal-area increment model's response
/// relative to an open-grown tree, `min(1, (CR / CR_open)^b3 · exp(c1 BAL + c2 CCF))`
/// (Monserud & Sterba 1996, For. Ecol. Manage. 80:57–80, Eq. 3; coefficients Hasenauer 2000),
/// with `cr_rel = CR / CR_open` the tree's crown ratio over the species' open-grown one
/// (clamped to [0.01, 1]), `bal` the basal area of larger trees in its neighbourhood (m²/ha,
/// [`crate::sim::density::Crowding::bal`]) and `ccf` the neighbourhood's crown competition
/// factor (ratio; 1 = 100 %). A basal-area ratio at the same DBH is the same diameter-increment
/// ratio to first order, so it scales the diameter increment as the crowding modifier does.
pub fn bai_competition_modifier(bc: BaiCompetition, cr_rel: f32, bal: f32, ccf: f32) -> f32 {
    let cr = cr_rel.clamp(0.01, 1.0);
    (bc.crown_ratio * cr.ln() + bc.bal * bal + bc.ccf * ccf * 100.0).exp().min(1.0)
}

/// Crown surface area (m²) of a paraboloid crown of width `cw` (m) and length `len` (m, > 0):
/// `π r / (6 L²) ((4 L² + r²)^1.5 − r³)` with `r = cw / 2` (the crown measure of BWINPro's
/// diameter increment, `ForestSimulatorNWGermany6.xml`, Nagel et al. 2006). 0 for a crown
/// without width or length.
pub fn crown_surface_area(cw: f32, len: f32) -> f32 {
    if !(cw > 0.0 && len > 0.0) {
        return 0.0;
    }
    let (r, l2) = (0.5 * cw as f64, (len as f64) * (len as f64));
    (std::f64::consts::PI * r / (6.0 * l2) * ((4.0 * l2 + r * r).powf(1.5) - r * r * r)) as f32
}

/// BWINPro's 5-year basal-area increment (cm², ≥ 0) of a tree of DBH `d` (cm, ≥ 7), crown
/// surface area `csa` (m², [`crown_surface_area`]), age `age` (years, at least 1) and
/// crown-competition index `c66` ([`crate::sim::density::Crowding::c66`]):
/// `exp(a0 + csa · ln CSA + age · ln t + c66 · C66) + Σₖ biasₖ · Dᵏ` ([`BaiBwinpro`]), floored
/// at 0 (TreeGrOSS sets a negative increment to 0). A crown without surface has none.
pub fn bwinpro_bai5(bw: BaiBwinpro, d: f32, csa: f32, age: f32, c66: f32) -> f32 {
    if !(csa > 0.0) {
        return 0.0;
    }
    let core = (bw.a0 + bw.csa * csa.ln() + bw.age * age.max(1.0).ln() + bw.c66 * c66).exp();
    let bias = [bw.bias0, bw.bias1, bw.bias2, bw.bias3, bw.bias4, bw.bias5].iter().rev().fold(0.0f32, |acc, &b| acc * d + b);
    (core + bias).max(0.0)
}

/// One year's DBH (cm) under BWINPro's diameter growth ([`BaiBwinpro`]) of a tree of DBH `d`
/// (cm; 0 without one), height `h1` (m) after this season, age `age` (years), in a
/// neighbourhood of crown competition `c66` and top height `h100` (m)
/// ([`crate::sim::density::Crowding`]); `scale` multiplies the increment (the site's
/// suitability times the tree's [`growth_factor`]). Below 7 cm the DBH follows the height,
/// `max(d, h1 / youth_hd)` (0 while `h1` ≤ 1.3 m and the tree has none; TreeGrOSS's youth
/// growth, which does not see competition or site); from 7 cm it grows by a fifth of the
/// 5-year increment's DBH change `√(d² + 4 ΔG₅ / π) − d` ([`bwinpro_bai5`], TreeGrOSS
/// `Tree.grow` over one of its 5 years), with the crown of the species' stand-grown crown width
/// and crown base (`life.stand_crown`, `life.stand_crown_base` at `h100`) at the height `h`
/// before the season. `None` for a species without `stand_crown` or `stand_crown_base`.
#[allow(clippy::too_many_arguments)]
pub fn bwinpro_dbh(bw: BaiBwinpro, sp: &Species, h: f32, h1: f32, d: f32, age: f32, c66: f32, h100: f32, scale: f32) -> Option<f32> {
    let cbf = sp.life.stand_crown_base?;
    sp.life.stand_crown?;
    if d < crate::sim::density::MIN_DBH_CM {
        return Some(if h1 > BREAST_HEIGHT_M { d.max(h1 / bw.youth_hd) } else { d });
    }
    let cb = cbf.crown_base_m(h, d, h100.max(h));
    let cw = 2.0 * crate::species::allometry::stand_crown_radius(sp, d, h, cb)?;
    let g5 = bwinpro_bai5(bw, d, crown_surface_area(cw, h - cb), age, c66);
    let dd5 = ((d as f64) * (d as f64) + 4.0 * g5 as f64 / std::f64::consts::PI).sqrt() as f32 - d;
    Some(d + 0.2 * dd5 * scale)
}

/// The neighbourhood's top height (m) of tree `i` ([`crate::sim::density::Crowding`]'s `h100`),
/// or `h` where the crowding has none.
#[inline]
fn crowd_h100(crowd: &Crowding, i: usize, h: f32) -> f32 {
    crowd.h100.get(i).copied().unwrap_or(h)
}

/// Smallest crown ratio (crown length / height) the stand-grown crown base leaves a living tree
/// ([`stand_crown_base`]): 0.2, the ratio below which foresters class a crown as failing
/// (Burkhart & Tomé 2012, ch. 9); the fitted function is not used beyond it.
pub const STAND_CROWN_RATIO_MIN: f32 = 0.2;

/// Crown base (m) a tree of `sp` reaches in a closed stand (issue 32; trial 46, defect 13): the
/// species' stand-grown crown-base function ([`crate::species::StandCrownBase`], Döbbeler et al.
/// 2001/2002 as published in TreeGrOSS, `cb = h·(1 − e^(−|a + b·h/d + c·d + e·ln h100|))`) at
/// the new height `h1` (m), DBH `d1` (cm) and the neighbourhood's top height `h100` (m, at
/// least `h1`), weighted by the crowns' closure: 0 at a crown competition factor `ccf` of
/// [`CCF_FULL`] or less (open-grown crowns keep the light rule `light_cb`), all of it from
/// `2 · CCF_FULL` (Krajicek et al. 1961's CCF; the linear blend between is a Sylva choice).
/// At most `(1 − STAND_CROWN_RATIO_MIN)·h1`. `light_cb` (m) for a species without the
/// function or a tree under [`crate::sim::density::MIN_DBH_CM`] (the function is fitted on
/// trees of 7 cm DBH and more). Without it, canopy beech of 30 cm and more kept a crown ratio
/// of 0.69 at year 150 of the default run (the function: 0.48), drawn as pointed flames.
pub fn stand_crown_base(sp: &Species, ccf: f32, h100: f32, h1: f32, d1: f32, light_cb: f32) -> f32 {
    let Some(f) = sp.life.stand_crown_base else { return light_cb };
    if d1 < crate::sim::density::MIN_DBH_CM || !(h1 > 0.0) {
        return light_cb;
    }
    let w = ((ccf - CCF_FULL) / CCF_FULL).clamp(0.0, 1.0);
    let cb = f.crown_base_m(h1, d1, h100.max(h1)).min(h1 * (1.0 - STAND_CROWN_RATIO_MIN));
    if cb > light_cb {
        light_cb + w * (cb - light_cb)
    } else {
        light_cb
    }
}

/// Persistent diameter-growth factor of tree `id` (lognormal, median 1, σ = [`GROWTH_SIGMA`],
/// clamped to [0.6, 1.6]); drawn from the tree's own stream, so it needs no stored state.
pub fn growth_factor(seed: u64, id: u64) -> f32 {
    let z = Stream::new(seed, id, 0, salt::GROWTH).normal();
    (GROWTH_SIGMA * z).exp().clamp(0.6, 1.6) as f32
}

/// Length (years) of the periods of [`period_factor`]: TreeGrOSS's growth step (its increments
/// are 5-year increments, `ForestSimulatorNWGermany6.xml`).
pub const FACTOR_PERIOD_YR: u32 = 5;

/// Growth factor of tree `id` in the 5-year period that holds simulation year `year`
/// ([`FACTOR_PERIOD_YR`]; period `year / 5`): `exp(σ z)` with z standard normal from the tree's
/// stream keyed by the period, clamped to ±3, for species with
/// `life.bai_bwinpro.period_sigma` = σ (TreeGrOSS `Tree.grow` draws its increment error anew at
/// every step; [`crate::species::BaiBwinpro::period_sigma`]). A pure function of seed, id and
/// period: the same bits whatever the threads, tiles or resumes.
pub fn period_factor(seed: u64, id: u64, year: u32, sigma: f32) -> f32 {
    let z = Stream::new(seed, id, 1 + (year / FACTOR_PERIOD_YR) as u64, salt::GROWTH).normal().clamp(-3.0, 3.0);
    (sigma as f64 * z).exp() as f32
}

/// Crown competition factor at which the open-grown crowns of a neighbourhood just cover the
/// ground (Krajicek et al. 1961: CCF = 100 %).
pub const CCF_FULL: f32 = 1.0;

/// Crown plasticity under crowding (0–1): where the open-grown crowns of the neighbourhood
/// would cover more than [`CCF_FULL`] of the ground, every crown radius shrinks by
/// `sqrt(CCF_FULL / CCF)`, so that crown projections share the canopy instead of overlapping
/// several-fold (closed stands carry crowns narrower than open-grown ones: Pretzsch 2009 ch. 8).
pub fn crown_space(ccf: f32) -> f32 {
    if ccf > CCF_FULL {
        (CCF_FULL / ccf).sqrt()
    } else {
        1.0
    }
}

/// Breast height (m): a tree with a DBH is at least this tall, so the dense-stand bound
/// [`dense_height_bound`] rises from it (a tree at DBH 0 is breast height tall).
pub const BREAST_HEIGHT_M: f32 = 1.3;

/// Tallest height (m) a tree of DBH `d_cm` (> 0) may reach under the species' dense-stand
/// height–diameter curve ([`DenseHd`], iLand's `HDhigh`, Seidl et al. 2012):
/// `BREAST_HEIGHT_M + k · D^(1 + c) / 100`. iLand grows a tree's height by its diameter
/// increment times the H/D of the increments, which in a dense stand (LRI 0) is `HDhigh =
/// (1 + c) · k · D^c` (`Tree::relative_height_growth`; Seidl et al. 2012, stem growth); a stem
/// that has put on every increment since breast height at that H/D (the slenderest stem the
/// curve allows) stands at the integral of it from `D = 0`, where a tree is breast height
/// tall by the definition of DBH: `h = 1.3 + k · D^(1 + c) / 100`. Suppressed trees stall in
/// height as their stems stop thickening. (Until issue 35 round 33 the bound was
/// `max(1.3, k · D^(1 + c) / 100)`, the integral without its constant, 1.3 m lower at every
/// DBH: it held Wiedemann's thinned spruce mean tree 2 m below the table's h_q.) A tree
/// without a DBH (below breast height) is not bounded (see [`run`]).
pub fn dense_height_bound(hd: DenseHd, d_cm: f32) -> f32 {
    BREAST_HEIGHT_M + hd.k * d_cm.powf(1.0 + hd.c) / 100.0
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

/// What growth reads (the seed for the trees' growth factors, the species, the neighbourhoods'
/// crowding) and writes (height, DBH, crown, vigour and age of every tree).
pub struct Growth<'a> {
    /// Scenario seed (each tree's persistent [`growth_factor`]).
    pub seed: u64,
    /// The year being simulated (years completed before it): trees recruited this spring
    /// (ids from [`birth_id`]`(year, 0, 0)` on) have had this year's season in their cohort and
    /// are not grown again.
    pub year: u32,
    /// Species library.
    pub lib: &'a SpeciesLibrary,
    /// Species taking part (their curves are tabulated once a year).
    pub pool: &'a [SpeciesId],
    /// Local crowding of every tree, tree-index order ([`crate::sim::density::crowding`]).
    pub crowd: &'a Crowding,
    /// The light grid (the cell of a tree, for its local top height).
    pub light: &'a crate::sim::light_grid::LightGrid,
    /// The light cells `canopy_top` holds (a tile's, [`crate::sim::tiles`]); `None`: every cell.
    pub window: Option<crate::sim::light_grid::CellRect>,
    /// Local top height (m) per light cell of the span of `window`, from this year's light
    /// phase ([`super::light::Light::canopy_top`]): which layer a tree stands in (its vigour,
    /// [`run`]). A tree whose cell it does not hold (a halo copy, whose values are dropped; an
    /// empty array) counts as below the upper layer.
    pub canopy_top: &'a [f32],
    /// Trees: light and suitability read; size, vigour and age written.
    pub trees: &'a mut TreeStore,
}

/// Grows every tree by one season. With `f = f(L) · S` ([`light_response`] × site suitability)
/// and `m` the crowding modifier ([`crowding_modifier`]) of the tree's neighbourhood:
/// height `ΔH = (H(t_eff + 1) − H(t_eff)) · f · (0.5 + 0.5 m)` with `t_eff` the effective age of
/// the current height (dominants' height growth depends little on density, suppressed trees fall
/// behind); DBH `ΔD = (D_open(H + ΔH_pot) − D_open(H)) · f · m · g` (D_open from the height–DBH
/// allometry, `g` the tree's [`growth_factor`]), so crowded and suppressed trees stay thin.
/// Under crowding the potential increment `D_open(H + ΔH_pot) − D_open(H)` blends, with weight
/// `x = clamp((RD − 0.4) / 0.2, 0, 1)`, into the closed-stand increment [`closed_increment`]
/// `min(max(100 ΔH_pot / HD, 30 / HD cm), open increment)` (closed-stand slenderness HD the
/// species' `life.closed_hd` below 7 cm DBH, or at every DBH with `life.closed_hd_scope =
/// "dense_curve"`, where a tree held at its dense-stand curve grows at most at that curve's
/// slope; blended towards `life.closed_hd_mixed` by the tree's own species' share of its
/// neighbourhood's crown projection where the species has that field, [`mixed_closed_hd`];
/// for species with `life.open_hd` and `life.dense_hd`, iLand's H/D between them by the
/// tree's light; else [`HD_CLOSED`] = 60 m/m with its 5 mm/yr floor, ESTIMATE;
/// [`closed_slenderness_held`]).
/// Crown radius: open-grown radius of the new DBH, shrunk by [`rules::shaded_crown`]
/// `0.5 + 0.5 L` in shade (crown plasticity); crown base rises to
/// `H (1 − crown_ratio (0.4 + 0.6 L))` and never falls (natural pruning). Vigour memory
/// [`rules::vigour_memory`] `v ← 0.5 v + 0.5 f · m` (a half-life of one year, so that crowding
/// is felt within a few years; `S` in `f` is the site suitability with the species' drought
/// factor) feeds stress mortality, which thins crowded stands along the species'
/// maximum-density line. A tree below the upper layer ([`super::mortality::below_upper_layer`]
/// of its light cell's local top height, `canopy_top`) takes `S` in place of `f`: there the
/// light's part is the shade mortality [`super::mortality::p_shade`] by shade tolerance (issue
/// 35, rounds 39–40), so light does not count twice; in the upper layer, where shade mortality
/// does not act, the vigour keeps the light response as before round 39 (the JABOWA/ForClim
/// slow-growth mortality among the canopy trees). `H(t_eff + 1) − H(t_eff)` and `D_open` are
/// read from the species' tables ([`crate::species::allometry::Table`], within 5 · 10⁻⁵ of
/// the curves' ranges; since session 11 of issue 16).
///
/// Species with PROGNAUS's competition terms (`life.bai_competition`; issue 35, round 31: Norway
/// spruce) take [`bai_competition_modifier`] of the tree's crown ratio, basal area of larger
/// trees and the neighbourhood's CCF in place of `m` in the DBH increment (trees with a DBH
/// above breast height; `m` still sets the height share and vigour, and a tree with `m = 0`
/// does not grow in diameter).
///
/// Species with BWINPro's diameter growth (`life.bai_bwinpro`; issue 35, round 37) take their
/// DBH from [`bwinpro_dbh`] instead (youth rule below 7 cm, the basal-area increment with the
/// crown-competition index C66 from 7 cm, scaled by the site's suitability and the tree's
/// growth factor, the persistent [`growth_factor`] or, where `life.bai_bwinpro.period_sigma`
/// is given, a [`period_factor`] drawn anew every 5 years; light and the crowding modifier do
/// not enter it); their height, crown and vigour grow as above.
///
/// Dense-stand height bound (issue 35; for species with `life.dense_hd`, none without): after
/// the season, a tree with a DBH `D₁ > 0` may not be taller than
/// [`dense_height_bound`]`(D₁)`: `H₁ ← max(H, min(H₁, h_max(D₁)))` — the height increment is
/// cut to what the species' dense-stand H/D curve allows at the new DBH, and a tree already
/// above it (planted, recruited or grown so before) keeps its height until its DBH catches up
/// (trees do not shrink). Trees below breast height (no DBH) are not bounded. The diameter
/// increment does not see the bound: it reads the height before the season and the potential
/// height increment.
///
/// This year's recruits (ids ≥ [`birth_id`]`(year, 0, 0)`: recruits of this spring; trees
/// planted by management get their ids after the growth phase, at the year's end) are left as
/// they are: their cohort grew them and aged them this spring
/// ([`crate::sim::phases::regen`]), so a second season the same year would double their first
/// year's height growth and age (issue 35, round 29).
pub fn run(w: Growth<'_>) {
    let crowd = w.crowd;
    let lib = &w.lib;
    let seed = w.seed;
    let year = w.year;
    let recruited = birth_id(w.year, 0, 0);
    let t = &mut *w.trees;
    // the species' curves, tabulated once per species (`allometry::Table`: within 5 · 10⁻⁵ of
    // the curves' ranges, without their powers and logarithms per tree)
    // (pool species only: trees belong to the pool)
    let curves: Vec<Curves> = lib
        .species
        .iter()
        .enumerate()
        .map(|(s, sp)| {
            let (inc, dbh) = (HeightIncrement::of(sp), OpenDbh::of(sp));
            let (inc, dbh) = if w.pool.contains(&(s as SpeciesId)) { (inc.table(), dbh.table()) } else { (Table::exact(inc), Table::exact(dbh)) };
            // the curve's H/D at the species' largest DBH: the lowest it reaches, so a tree no
            // slenderer than that is never bounded (its power is not evaluated)
            let bound = sp.life.dense_hd.map(|hd| (hd, hd.k * sp.life.max_dbh_cm.powf(hd.c)));
            (inc, dbh, bound)
        })
        .collect();
    let curves = &curves[..];
    // read-only columns, then the written ones updated in place (each tree on its own)
    // trees restored from a checkpoint have no cached growth factors yet (NaN: drawn below)
    t.growth_factor.0.resize(t.id.len(), f32::NAN);
    let (species, light, suitability, id) = (&t.species, &t.light, &t.suitability, &t.id);
    let (x, y) = (&t.x, &t.y);
    let (lg, top) = (w.light, w.canopy_top);
    let span = crate::sim::light_grid::Span::new(w.window, lg);
    (&mut t.height, &mut t.dbh, &mut t.crown_radius, &mut t.crown_base, &mut t.vigour, &mut t.age, &mut t.growth_factor.0)
        .into_par_iter()
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, (hr, dr, rr, cbr, vr, ar, gr))| {
            if id[i] >= recruited {
                return;
            }
            let below = span.index(lg.cell_of(x[i], y[i])).and_then(|k| top.get(k)).is_none_or(|&th| super::mortality::below_upper_layer(*hr, th));
            let g = grow(lib, curves, crowd, seed, year, species[i], light[i], suitability[i], below, id[i], *hr, *dr, *cbr, *vr, *ar, gr, i);
            *hr = g.h;
            *dr = g.d;
            *rr = g.r;
            *cbr = g.cb;
            *vr = g.v;
            *ar += 1.0;
        });
}

/// A species' height-increment and open-grown DBH curves (tabulated), and, where the species
/// has a dense-stand height–diameter curve, that curve with its H/D at the species' largest DBH.
type Curves = (Table<HeightIncrement>, Table<OpenDbh>, Option<(DenseHd, f32)>);

/// Slenderness H/D (m/m) of the closed-stand diameter increment of a species without
/// `life.closed_hd`: under crowding, diameter increment follows height increment at the
/// slenderness of trees in closed stands, not the open-grown curve (whose H/D of 30–60 m/m at
/// 25–35 m comes from each species' record DBH and differs 2-fold between species). Dominants of
/// closed Central European stands carry H/D ≈ 60–80 m/m, mean trees 80–100 (Assmann 1970;
/// Pretzsch 2009 ch. 8; the Wiedemann beech and spruce tables give 100 and 89 at age 100); this
/// is the potential (uncrowded-share m = 1) value, ESTIMATE within that range.
pub const HD_CLOSED: f32 = 60.0;

/// Floor (cm/yr) of the closed-stand diameter increment at [`HD_CLOSED`]: after height growth
/// culminates, dominants of closed stands keep putting on diameter (basal-area increment of
/// mature stands stays nearly level: Assmann 1970); ESTIMATE: 5 mm, about twice the Dq increment
/// of Wiedemann's and Assmann & Franz's mean trees at ages 100–120. It is the closed-stand
/// increment of a height growth of `DD_CLOSED_MIN · HD_CLOSED / 100` = 0.3 m a year.
pub const DD_CLOSED_MIN: f32 = 0.5;

/// Potential closed-stand diameter increment (cm/yr) of a tree with potential height increment
/// `dh_pot` (m/yr) and open-grown diameter increment `dd_open` (cm/yr) at slenderness `hd` (m/m,
/// > 0; [`closed_slenderness`]): `min(max(100 dh_pot / hd, DD_CLOSED_MIN
/// · HD_CLOSED / hd), dd_open)`. The floor is the increment of the same 0.3 m height growth at
/// every `hd` ([`DD_CLOSED_MIN`] at 60); crowding does not speed diameter growth, so never more
/// than the open-grown increment. At `hd` = [`HD_CLOSED`] it is bit for bit the growth model's
/// closed-stand increment before round 41 (issue 35).
pub fn closed_increment(dh_pot: f32, dd_open: f32, hd: f32) -> f32 {
    (dh_pot * 100.0 / hd).max(DD_CLOSED_MIN * HD_CLOSED / hd).min(dd_open)
}

/// Slenderness H/D (m/m) of the closed-stand diameter increment ([`closed_increment`]) of a tree
/// of species `sp` with DBH `d_cm` (cm) and light `l` (the crown's light resource, 0–1, clamped):
/// - below the inventory threshold [`crate::sim::density::MIN_DBH_CM`] (7 cm), the species'
///   `life.closed_hd` where it has one. The switch is hard, as in TreeGrOSS/BWINPro, whose youth
///   rule (`D = h / 1.40` for beech) grows only the trees below the 7 cm threshold, and whose
///   stand model grows those above it (issue 35, round 42): the DBH stays continuous, its
///   yearly increment steps up by `closed_hd / HD_CLOSED` where the tree passes 7 cm;
/// - otherwise, for a species with both `life.open_hd` (iLand's `HDlow`) and `life.dense_hd`
///   (`HDhigh`), the H/D of the increments interpolated between them by the tree's light, as
///   iLand's `Tree::relative_height_growth` does by the light resource index LRI (Seidl et al.
///   2012, Ecol. Model. 231:87–100, stem growth): `HDhigh(D) − (HDhigh(D) − HDlow(D)) · l`, with
///   `HD(D) = (1 + c) · k · D^c` ([`DenseHd`]) and `D` taken as at least 1 cm (the curves' H/D
///   at 1 cm; they rise without bound towards D = 0). Full light gives `HDlow`, none `HDhigh`;
///   iLand's fasy gives 48–100 m/m at 7 cm and 37–68 at 20 cm (issue 35, round 43);
/// - [`HD_CLOSED`] else.
///
/// With `life.closed_hd_scope = "dense_curve"` ([`ClosedHdScope::DenseCurve`]) and a
/// `life.dense_hd` curve, `life.closed_hd` holds at every DBH (before the light interpolation);
/// [`closed_slenderness_held`] then bounds it for trees held at the curve (issue 35, round 44).
pub fn closed_slenderness(sp: &Species, d_cm: f32, l: f32) -> f32 {
    closed_slenderness_among(sp, d_cm, l, 1.0)
}

/// Closed-stand slenderness H/D (m/m) of a species with `life.closed_hd` = `closed_hd` and
/// `life.closed_hd_mixed` = `mixed` for a tree whose own species holds `share` (0–1, clamped)
/// of its neighbourhood's open-grown crown projection
/// ([`crate::sim::density::Crowding::own_share`]): `mixed + (closed_hd − mixed) · share`;
/// `closed_hd` itself at a share of 1 (a pure neighbourhood) and wherever `mixed` is `None`.
///
/// Why (issue 35, round 45): beech's `closed_hd` 140 (TreeGrOSS's youth rule, round 44) is the
/// slenderness of beech among beech. Among other species beech's crown widens (Bayer, Seifert &
/// Pretzsch 2013, Trees 27:1035–1047: greater crown volumes and flatter branch angles in mixture
/// with spruce; Bayer & Pretzsch 2017, Silva Fennica 51(5) 7748: beech invests gains in
/// horizontal space occupation; Pretzsch 2014, For. Ecol. Manage. 327:251–264), and a beech's
/// diameter growth follows its crown's horizontal extension (Seidel et al. 2015, iForest
/// 8:735–742: crown projection area and mean crown radius the crown measures most closely
/// related to basal-area increment). With 140 in mixture a beech as tall as its neighbours
/// carried 60/140 of their DBH, counted as suppressed in the size share of the crowding
/// modifier ([`crowding_modifier`], `s = D / Dq`), and lost the mixtures (round 44: no beech
/// left in `tests/sim_density.rs`'s mixed stand, 20.9 % of the default run's basal area). Beech
/// sets `mixed` to [`HD_CLOSED`], the closed-stand slenderness of the species it grows among;
/// the linear blend by the crown-projection share is a Sylva choice (ESTIMATE).
pub fn mixed_closed_hd(closed_hd: f32, mixed: Option<f32>, share: f32) -> f32 {
    match mixed {
        Some(m) if share < 1.0 => m + (closed_hd - m) * share.clamp(0.0, 1.0),
        _ => closed_hd,
    }
}

/// [`closed_slenderness`] of a tree whose own species holds `share` (0–1) of its
/// neighbourhood's crown projection: where the species' `closed_hd` holds, it is taken as
/// [`mixed_closed_hd`] of the share (the species' `life.closed_hd_mixed`; unchanged without
/// it); `closed_slenderness` is this at a share of 1.
pub fn closed_slenderness_among(sp: &Species, d_cm: f32, l: f32, share: f32) -> f32 {
    let every_dbh = sp.life.closed_hd_scope == Some(ClosedHdScope::DenseCurve) && sp.life.dense_hd.is_some();
    match (sp.life.closed_hd, sp.life.open_hd, sp.life.dense_hd) {
        (Some(hd), _, _) if d_cm < crate::sim::density::MIN_DBH_CM || every_dbh => mixed_closed_hd(hd, sp.life.closed_hd_mixed, share),
        (_, Some(lo), Some(hi)) => {
            let d = d_cm.max(1.0);
            let (lo, hi) = ((1.0 + lo.c) * lo.k * d.powf(lo.c), (1.0 + hi.c) * hi.k * d.powf(hi.c));
            hi - (hi - lo) * l.clamp(0.0, 1.0)
        }
        _ => HD_CLOSED,
    }
}

/// Share of [`dense_height_bound`] at or above which a tree counts as held at its species'
/// dense-stand curve in [`closed_slenderness_held`]: the bound sets such a tree's height to the
/// curve's value in `f32`, so 0.1 % (3 cm at 30 m) takes the rounding of the power, and a tree
/// that fell short of it by more grew below the curve that season.
pub const HELD_AT_CURVE: f32 = 0.999;

/// H/D (m/m) of the dense-stand curve's own increments at DBH `d_cm` (cm, taken as at least
/// 1 cm): the slope `100 dh/dD = (1 + c) · k · D^c` of `h = 1.3 + k · D^(1 + c) / 100`
/// ([`dense_height_bound`]), i.e. iLand's `HDhigh` as iLand writes it, `a · b · (1 + c) · d^c`
/// (Seidl et al. 2012; [`DenseHd`]). Beech (k 323.63, c −0.3676): 98.1 at 7.4 cm, 77.0 at
/// 14.3 cm, 57.2 at 32 cm.
pub fn dense_curve_slenderness(hd: DenseHd, d_cm: f32) -> f32 {
    (1.0 + hd.c) * hd.k * d_cm.max(1.0).powf(hd.c)
}

/// Slenderness H/D (m/m) of the closed-stand diameter increment ([`closed_increment`]) of a tree
/// of species `sp` with DBH `d_cm` (cm), height `h_m` (m) and light `l`: [`closed_slenderness`],
/// and for a species with `life.closed_hd_scope = "dense_curve"` and a dense-stand curve
/// `life.dense_hd`, a tree held at that curve (`h_m` at least [`HELD_AT_CURVE`] of
/// [`dense_height_bound`]`(d_cm)`) grows at most as slender as the curve's own increments,
/// [`dense_curve_slenderness`]: its diameter increment is then what lets its potential height
/// increment stay within the bound, where a slenderer increment would leave it stuck at the
/// curve with its height growth cut. Issue 35, round 44: with beech's 140 m/m at every DBH and
/// no such cap, the dominants of an unmanaged stand were held at the curve near 30 cm and its
/// top height fell to 0.88 of NW-FVA's at 100 (round 42: 0.90); with it 0.975.
///
/// `share` is the tree's own species' share of its neighbourhood's crown projection
/// ([`closed_slenderness_among`]; 1 in a pure stand).
pub fn closed_slenderness_held(sp: &Species, d_cm: f32, h_m: f32, l: f32, share: f32) -> f32 {
    let hd = closed_slenderness_among(sp, d_cm, l, share);
    match (sp.life.closed_hd_scope, sp.life.dense_hd) {
        (Some(ClosedHdScope::DenseCurve), Some(c)) if d_cm > 0.0 && h_m >= dense_height_bound(c, d_cm) * HELD_AT_CURVE => hd.min(dense_curve_slenderness(c, d_cm)),
        _ => hd,
    }
}

/// One tree's season ([`run`]) in simulation year `year`: species `s`, light `l`, suitability,
/// whether it stands `below` the upper layer (its vigour: [`run`]), id, height `h`, DBH `d`,
/// crown base and vigour before it, its cached [`growth_factor`] (NaN until first drawn, then
/// kept); `i` its index in the crowding.
#[allow(clippy::too_many_arguments)]
#[inline]
fn grow(lib: &SpeciesLibrary, curves: &[Curves], crowd: &Crowding, seed: u64, year: u32, s: u16, l: f32, suitability: f32, below: bool, id: u64, h: f32, d: f32, crown_base: f32, vigour: f32, age: f32, factor: &mut f32, i: usize) -> Grown {
    let sp = &lib.species[s as usize];
    let (inc, dbh_of, bound) = &curves[s as usize];
    let f = light_response(l, sp.life.shade_tolerance) * suitability;
    // the vigour's growth response: without light below the upper layer (shade mortality)
    let fv = if below { suitability } else { f };
    let dq = crowd.dq_cm[i];
    let s = if d > 0.0 && dq > 0.0 { d / dq } else { 1.0 };
    let m = crowding_modifier(crowd.rd[i], s);
    let dh_pot = inc.at(h);
    let h1 = (h + dh_pot * f * height_share(m, s)).min(sp.life.max_height_m);
    // BWINPro's diameter growth (issue 35, round 37) in place of the potential × light × crowding
    if let Some(bw) = sp.life.bai_bwinpro {
        let (c66, h100) = (crowd.c66.get(i).copied().unwrap_or(0.0), crowd_h100(crowd, i, h));
        let mut scale = suitability;
        if d >= crate::sim::density::MIN_DBH_CM && scale > 0.0 {
            match bw.period_sigma {
                // a factor per 5-year period (not cached: it changes with the period)
                Some(sigma) => scale *= period_factor(seed, id, year, sigma),
                None => {
                    if factor.is_nan() {
                        *factor = growth_factor(seed, id);
                    }
                    scale *= *factor;
                }
            }
        }
        if let Some(d1) = bwinpro_dbh(bw, sp, h, h1, d, age, c66, h100, scale) {
            return finish(sp, dbh_of, *bound, crowd.ccf[i], crowd_h100(crowd, i, h), l, h, h1, d1, crown_base, vigour, fv, m);
        }
    }
    // Diameter increment below is `dd_pot · f · m` with dd_pot finite and ≥ 0: a tree with no
    // light response or fully suppressed by crowding (f = 0 or m = 0) gets +0 whatever dd_pot
    // is, so its open-grown curve (two powers and two logarithms) is not evaluated.
    if f == 0.0 || m == 0.0 {
        // `d + 0.0`, as `d + dd` below with dd = +0 (−0 becomes +0 there too)
        return finish(sp, dbh_of, *bound, crowd.ccf[i], crowd_h100(crowd, i, h), l, h, h1, d + 0.0, crown_base, vigour, fv, m);
    }
    let hp = (h + dh_pot).min(sp.life.max_height_m * 0.999);
    let dd_open = (dbh_of.at(hp) - dbh_of.at(h.min(hp))).max(if h > 1.3 { 0.05 } else { 0.0 });
    // Closed-stand allometry ([`closed_increment`]): under crowding, diameter increment
    // follows height increment at the slenderness H/D of trees in closed stands. The weight
    // x of the closed-stand allometry rises from 0 at RD_ONSET (0.4, lower limit of full
    // site occupancy) to 1 at RD 0.6 (onset of self-thinning, canopy closed: Long 1985).
    // A species with iLand's H/D range (`life.open_hd` and `life.dense_hd`) takes it at every
    // density: iLand has no open-grown curve besides it (HDlow is the H/D in full light), and
    // the tree's light sets where between HDlow and HDhigh it grows (issue 35, round 43).
    let x = if sp.life.open_hd.is_some() && sp.life.dense_hd.is_some() { 1.0 } else { ((crowd.rd[i] - RD_ONSET).max(0.0) / 0.2).min(1.0) };
    let share = crowd.own_share.get(i).copied().unwrap_or(1.0);
    let dd_closed = if h > 1.3 { closed_increment(dh_pot, dd_open, closed_slenderness_held(sp, d, h, l, share)) } else { dd_open };
    let dd_pot = (1.0 - x) * dd_open + x * dd_closed;
    // the tree's growth factor only matters for a non-zero increment (a zero times the factor,
    // which is finite and > 0, is that same zero), so it is not drawn for trees that do not
    // grow; once drawn it is kept (a pure function of seed and id: the same bits every year)
    // PROGNAUS's competition response in place of the crowding modifier, for species with
    // `life.bai_competition` (issue 35, round 31): trees with a DBH above breast height
    let m_d = match sp.life.bai_competition {
        Some(bc) if d > 0.0 && h > 1.3 => bai_competition_modifier(bc, (h - crown_base) / h / sp.life.allometry.crown_ratio, crowd.bal[i], crowd.ccf[i]),
        _ => m,
    };
    let dd = dd_pot * f * m_d;
    let d1 = d + if dd == 0.0 {
        dd
    } else {
        if factor.is_nan() {
            *factor = growth_factor(seed, id);
        }
        dd * *factor
    };
    finish(sp, dbh_of, *bound, crowd.ccf[i], crowd_h100(crowd, i, h), l, h, h1, d1, crown_base, vigour, fv, m)
}

/// The end of [`grow`] from the new height `h1` and diameter `d1` (before its floor and cap):
/// a first DBH for a tree that passed breast height without one, the dense-stand height bound
/// (`bound`: the species' curve and its H/D at the largest DBH, where it has one; `h` the
/// height before the season), the crown radius, crown base and vigour (from `f`, the tree's
/// growth response, [`run`]: light × site suitability with its drought factor in the upper
/// layer, the suitability alone below it, and the crowding modifier `m`).
#[allow(clippy::too_many_arguments)]
#[inline]
fn finish(sp: &Species, dbh_of: &Table<OpenDbh>, bound: Option<(DenseHd, f32)>, ccf: f32, h100: f32, l: f32, h: f32, h1: f32, mut d1: f32, crown_base: f32, vigour: f32, f: f32, m: f32) -> Grown {
    if d1 == 0.0 && h1 > 1.3 {
        d1 = dbh_of.at(h1) * 0.5;
    }
    let d1 = d1.min(sp.life.max_dbh_cm);
    let h1 = match bound {
        // a tree no slenderer than the curve's lowest H/D is within it at any DBH
        Some((hd, hd_min)) if d1 > 0.0 && h1 * 100.0 > hd_min * d1 => h1.min(dense_height_bound(hd, d1)).max(h),
        _ => h1,
    };
    let lc = l.clamp(0.0, 1.0);
    let r = open_crown_radius(sp, h1, d1) * rules::shaded_crown(l) * crown_space(ccf);
    let light_cb = h1 * (1.0 - sp.life.allometry.crown_ratio * (0.4 + 0.6 * lc));
    let cb = crown_base.max(light_cb).max(stand_crown_base(sp, ccf, h100, h1, d1, light_cb)).min(h1 * 0.95);
    let v = rules::vigour_memory(vigour, f, m);
    Grown { h: h1, d: d1, r, cb, v }
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
        // crowding: none below the onset; on the line suppressed trees stop, the mean tree keeps
        // half, dominants 70 %; far above it only the dominants' floor is left
        assert_eq!(crowding_modifier(0.4, 0.5), 1.0);
        assert!((crowding_modifier(1.0, 1.0) - 0.5).abs() < 1e-6);
        assert_eq!(crowding_modifier(1.0, 0.4), 0.0);
        assert!((crowding_modifier(1.0, 1.5) - 0.7).abs() < 1e-6);
        assert!((crowding_modifier(1.3, 1.5) - 0.1).abs() < 1e-6);
        assert!(crowding_modifier(0.8, 0.6) < crowding_modifier(0.8, 1.2));
        assert_eq!(height_share(1.0, 0.3), 1.0);
        assert_eq!(height_share(0.0, 0.3), 0.5);
        assert_eq!(height_share(0.0, 1.3), 1.0);
        assert_eq!(crown_space(0.8), 1.0);
        assert!((crown_space(4.0) - 0.5).abs() < 1e-6);
        let g: Vec<f32> = (0..2000).map(|id| growth_factor(1, id)).collect();
        let mean_ln = g.iter().map(|v| (*v as f64).ln()).sum::<f64>() / g.len() as f64;
        assert!(mean_ln.abs() < 0.02 && g.iter().all(|v| (0.6..=1.6).contains(v)), "{mean_ln}");
        assert!(light_response(1.0, 1.0) > 0.99 && light_response(0.1, 1.0) < 0.05 && light_response(0.1, 5.0) > 0.15);
    }

    /// The closed-stand diameter increment at a species' slenderness: 100 ΔH_pot / H/D (0.42 m of
    /// height: 0.7 cm at 60, 0.3 cm at 140), floored at the increment of a 0.3 m height growth
    /// (0.5 cm at 60, 0.3 / 1.4 = 0.2143 cm at 140), capped by the open-grown increment; at 60
    /// bit for bit the expression the growth model had before `life.closed_hd` (issue 35, round 41).
    #[test]
    fn closed_increment_follows_the_slenderness() {
        assert!((closed_increment(0.42, 2.0, HD_CLOSED) - 0.7).abs() < 1e-6);
        assert!((closed_increment(0.42, 2.0, 140.0) - 0.3).abs() < 1e-6);
        assert_eq!(closed_increment(0.1, 2.0, HD_CLOSED), 0.5);
        assert!((closed_increment(0.1, 2.0, 140.0) - 0.3 / 1.4).abs() < 1e-6, "{}", closed_increment(0.1, 2.0, 140.0));
        assert_eq!(closed_increment(0.42, 0.25, 140.0), 0.25);
        for k in 0..2000 {
            let (dh, open) = (k as f32 * 0.0007, 0.05 + (k % 37) as f32 * 0.03);
            assert_eq!(closed_increment(dh, open, HD_CLOSED).to_bits(), (dh * 100.0 / 60.0).max(0.5).min(open).to_bits(), "dh {dh} open {open}");
        }
    }

    /// The youth slenderness holds below the inventory threshold only (TreeGrOSS `Tree.grow`:
    /// `youthGrowth` while DBH < 7 cm): a species with `life.closed_hd` = 140 takes it at 0 and
    /// 6.99 cm and [`HD_CLOSED`] from 7 cm on; a species without it takes [`HD_CLOSED`] at every DBH.
    #[test]
    fn closed_slenderness_is_the_youths_below_seven_cm() {
        let mut b = beech_like();
        b.life.closed_hd = None;
        for d in [0.0, 3.0, 6.99, 7.0, 40.0] {
            assert_eq!(closed_slenderness(&b, d, 0.5), HD_CLOSED, "no closed_hd, DBH {d}");
        }
        b.life.closed_hd = Some(140.0);
        assert_eq!(closed_slenderness(&b, 0.0, 0.5), 140.0);
        assert_eq!(closed_slenderness(&b, 6.99, 0.5), 140.0);
        assert_eq!(closed_slenderness(&b, crate::sim::density::MIN_DBH_CM, 0.5), HD_CLOSED);
        assert_eq!(closed_slenderness(&b, 30.0, 0.5), HD_CLOSED);
    }

    /// iLand's H/D of the increments between HDlow (full light) and HDhigh (none) by the tree's
    /// light (`Tree::relative_height_growth`), for a species with `life.open_hd` and
    /// `life.dense_hd` (issue 35, round 43; iLand's fasy curves, species/sources/
    /// species_traits.csv): at 20 cm HDhigh = 0.6324 · 323.63 · 20^−0.3676 = 68.04 m/m, HDlow =
    /// 0.7573 · 100.877 · 20^−0.2427 = 36.92, 52.48 halfway; the light clamped to 0–1; DBH
    /// under 1 cm taken as 1 cm; `closed_hd` still rules below 7 cm; without `open_hd` 60.
    #[test]
    fn closed_slenderness_follows_ilands_light_interpolation() {
        let mut b = beech_like();
        b.life.closed_hd = None;
        b.life.dense_hd = Some(DenseHd { k: 323.63, c: -0.3676 });
        b.life.open_hd = None;
        assert_eq!(closed_slenderness(&b, 20.0, 0.5), HD_CLOSED);
        b.life.open_hd = Some(DenseHd { k: 100.877, c: -0.2427 });
        for (l, want) in [(0.0, 68.04), (1.0, 36.92), (0.5, 52.48), (-0.2, 68.04), (1.5, 36.92)] {
            let hd = closed_slenderness(&b, 20.0, l);
            assert!((hd - want).abs() < 0.01, "light {l}: {hd} vs {want}");
        }
        assert!((closed_slenderness(&b, 7.0, 0.0) - 100.09).abs() < 0.01);
        assert!((closed_slenderness(&b, 1.0, 0.0) - 204.66).abs() < 0.01);
        assert_eq!(closed_slenderness(&b, 0.3, 0.4), closed_slenderness(&b, 1.0, 0.4));
        b.life.closed_hd = Some(140.0);
        assert_eq!(closed_slenderness(&b, 6.99, 1.0), 140.0);
        assert!((closed_slenderness(&b, 20.0, 0.5) - 52.48).abs() < 0.01);
        b.life.dense_hd = None;
        assert_eq!(closed_slenderness(&b, 20.0, 0.5), HD_CLOSED);
    }

    /// Issue 35 round 44: with `closed_hd_scope = "dense_curve"` and beech's dense-stand curve
    /// (iLand's fasy HDhigh, k 323.63, c −0.3676), `closed_hd` 140 holds at every DBH below the
    /// curve, and a tree held at the curve (height = [`dense_height_bound`]) grows at the
    /// curve's slope where that is stouter: 68.04 m/m at 20 cm (204.66 · 20^−0.3676), 57.25 at
    /// 32 cm; at 2 cm the slope (158.6) is slenderer than 140, which stays. `youth` (or no
    /// scope) keeps TreeGrOSS's scope: 140 below 7 cm, 60 above, held or not.
    #[test]
    fn closed_slenderness_held_follows_the_dense_curve() {
        let mut b = beech_like();
        let curve = DenseHd { k: 323.63, c: -0.3676 };
        b.life.dense_hd = Some(curve);
        b.life.open_hd = None;
        b.life.closed_hd = Some(140.0);
        assert!((dense_curve_slenderness(curve, 20.0) - 68.04).abs() < 0.01, "{}", dense_curve_slenderness(curve, 20.0));
        assert!((dense_curve_slenderness(curve, 32.0) - 57.25).abs() < 0.01, "{}", dense_curve_slenderness(curve, 32.0));
        assert_eq!(dense_curve_slenderness(curve, 0.4), dense_curve_slenderness(curve, 1.0));
        for scope in [None, Some(ClosedHdScope::Youth)] {
            b.life.closed_hd_scope = scope;
            assert_eq!(closed_slenderness(&b, 30.0, 0.5), HD_CLOSED, "{scope:?}");
            assert_eq!(closed_slenderness_held(&b, 20.0, dense_height_bound(curve, 20.0), 0.5, 1.0), HD_CLOSED, "{scope:?}, held");
            assert_eq!(closed_slenderness_held(&b, 5.0, dense_height_bound(curve, 5.0), 0.5, 1.0), 140.0, "{scope:?}, youth held");
        }
        b.life.closed_hd_scope = Some(ClosedHdScope::DenseCurve);
        assert_eq!(closed_slenderness(&b, 30.0, 0.5), 140.0);
        // below the curve: 140 whatever the DBH
        for d in [5.0f32, 20.0, 32.0] {
            assert_eq!(closed_slenderness_held(&b, d, 0.95 * dense_height_bound(curve, d), 0.5, 1.0), 140.0, "DBH {d} below the curve");
        }
        // held at the curve (and above it, as a planted tree may stand): the curve's slope
        for (d, want) in [(20.0f32, 68.04f32), (32.0, 57.25)] {
            for h in [dense_height_bound(curve, d), 0.9995 * dense_height_bound(curve, d), 1.1 * dense_height_bound(curve, d)] {
                let hd = closed_slenderness_held(&b, d, h, 0.5, 1.0);
                assert!((hd - want).abs() < 0.01, "DBH {d}, height {h}: {hd} vs {want}");
            }
        }
        assert_eq!(closed_slenderness_held(&b, 2.0, dense_height_bound(curve, 2.0), 0.5, 1.0), 140.0);
        // without the curve the scope has nothing to follow: TreeGrOSS's scope
        b.life.dense_hd = None;
        assert_eq!(closed_slenderness(&b, 30.0, 0.5), HD_CLOSED);
        assert_eq!(closed_slenderness_held(&b, 30.0, 40.0, 0.5, 1.0), HD_CLOSED);
    }

    /// Issue 35 round 45: crown plasticity in mixture. Beech's 140 m/m holds in a pure
    /// neighbourhood (own share 1, bit for bit) and gives way to `closed_hd_mixed` 60 among
    /// other species: 100 at a share of 0.5, 76 at 0.2, 60 at 0; the dense curve's slope still
    /// bounds a tree held at it (57.25 at 32 cm); a species without `closed_hd_mixed` keeps 140
    /// whatever the share; the light interpolation and 60 of species without `closed_hd` do not
    /// see it.
    #[test]
    fn closed_slenderness_gives_way_in_mixture() {
        assert_eq!(mixed_closed_hd(140.0, Some(60.0), 1.0).to_bits(), 140f32.to_bits());
        assert_eq!(mixed_closed_hd(140.0, Some(60.0), 0.0), 60.0);
        assert!((mixed_closed_hd(140.0, Some(60.0), 0.5) - 100.0).abs() < 1e-4);
        assert!((mixed_closed_hd(140.0, Some(60.0), 0.2) - 76.0).abs() < 1e-4);
        assert_eq!(mixed_closed_hd(140.0, Some(60.0), -0.3), 60.0);
        assert_eq!(mixed_closed_hd(140.0, None, 0.2), 140.0);
        let mut b = beech_like();
        let curve = DenseHd { k: 323.63, c: -0.3676 };
        b.life.dense_hd = Some(curve);
        b.life.open_hd = None;
        b.life.closed_hd = Some(140.0);
        b.life.closed_hd_scope = Some(ClosedHdScope::DenseCurve);
        b.life.closed_hd_mixed = Some(60.0);
        assert_eq!(closed_slenderness(&b, 20.0, 0.5), 140.0);
        assert_eq!(closed_slenderness_among(&b, 20.0, 0.5, 1.0), 140.0);
        assert!((closed_slenderness_among(&b, 20.0, 0.5, 0.5) - 100.0).abs() < 1e-4);
        assert!((closed_slenderness_held(&b, 20.0, 0.95 * dense_height_bound(curve, 20.0), 0.5, 0.0) - 60.0).abs() < 1e-4);
        let hd = closed_slenderness_held(&b, 32.0, dense_height_bound(curve, 32.0), 0.5, 0.5);
        assert!((hd - 57.25).abs() < 0.01, "{hd}");
        // the youth scope: 140 below 7 cm, blended as well; 60 above it whatever the share
        b.life.closed_hd_scope = None;
        assert!((closed_slenderness_among(&b, 5.0, 0.5, 0.5) - 100.0).abs() < 1e-4);
        assert_eq!(closed_slenderness_among(&b, 20.0, 0.5, 0.5), HD_CLOSED);
        // without closed_hd_mixed the share is not read
        b.life.closed_hd_scope = Some(ClosedHdScope::DenseCurve);
        b.life.closed_hd_mixed = None;
        assert_eq!(closed_slenderness_among(&b, 20.0, 0.5, 0.0), 140.0);
        // without closed_hd: 60
        b.life.closed_hd = None;
        b.life.closed_hd_mixed = Some(60.0);
        assert_eq!(closed_slenderness_among(&b, 20.0, 0.5, 0.3), HD_CLOSED);
    }

    /// PROGNAUS's competition response (Norway spruce's terms, Hasenauer 2000): an open-grown
    /// tree keeps its increment, a crown ratio half the open-grown one with 20 m²/ha of larger
    /// trees at CCF 250 % keeps 0.402 of it; a crown ratio above the open-grown one counts as it.
    #[test]
    fn bai_competition_modifier_values() {
        let bc = BaiCompetition { crown_ratio: 0.634179, bal: -0.017369, ccf: -0.000497 };
        assert_eq!(bai_competition_modifier(bc, 1.0, 0.0, 0.0), 1.0);
        assert!((bai_competition_modifier(bc, 0.5, 20.0, 2.5) - 0.40203).abs() < 1e-4, "{}", bai_competition_modifier(bc, 0.5, 20.0, 2.5));
        assert_eq!(bai_competition_modifier(bc, 1.7, 0.0, 0.0), 1.0);
        assert!(bai_competition_modifier(bc, 0.5, 30.0, 2.5) < bai_competition_modifier(bc, 0.5, 20.0, 2.5));
    }

    /// BWINPro's beech diameter growth (species block 211, Nagel et al. 2006): the crown surface
    /// area of a paraboloid (CW 4 m, L 6 m: 52.14 m²), the 5-year basal-area increment of a
    /// Wiedemann-sized tree (7.4 cm, CSA 25 m², age 30) alone (36.08 cm²) and at C66 = 2
    /// (4.46 cm², the bias −11.08 cm² included), a year's DBH from it (+0.527 cm alone), and the
    /// youth rule below 7 cm (7 m tall: 5 cm; never shrinking; none below breast height).
    #[test]
    fn bwinpro_beech_increment_values() {
        let bw = BaiBwinpro { a0: 2.6518, csa: 1.0414, age: -0.6322, c66: -0.555, bias0: -22.77, bias1: 1.417, bias2: 0.03803, bias3: -0.002403, bias4: 0.00003191, bias5: -0.0000001202, youth_hd: 1.40, period_sigma: None };
        assert!((crown_surface_area(4.0, 6.0) - 52.1416).abs() < 1e-3, "{}", crown_surface_area(4.0, 6.0));
        assert_eq!(crown_surface_area(0.0, 6.0), 0.0);
        assert!((bwinpro_bai5(bw, 7.4, 25.0, 30.0, 0.0) - 36.085).abs() < 0.01, "{}", bwinpro_bai5(bw, 7.4, 25.0, 30.0, 0.0));
        assert!((bwinpro_bai5(bw, 7.4, 25.0, 30.0, 2.0) - 4.462).abs() < 0.01, "{}", bwinpro_bai5(bw, 7.4, 25.0, 30.0, 2.0));
        // more competition, less increment; a negative sum is no increment
        assert!(bwinpro_bai5(bw, 7.4, 25.0, 30.0, 3.0) < bwinpro_bai5(bw, 7.4, 25.0, 30.0, 2.0));
        assert_eq!(bwinpro_bai5(bw, 7.4, 25.0, 30.0, 6.0), 0.0);
        let mut b = beech_like();
        b.life.stand_crown = Some(crate::species::StandCrown { a: 2.0837, b: 0.15, p: 1.0, c: 5.7292, e: 1.3341, g: 0.0 });
        b.life.stand_crown_base = Some(crate::species::StandCrownBase { a: 0.25704, b: 0.11819, c: -0.002065, e: 0.13831 });
        assert_eq!(bwinpro_dbh(bw, &b, 6.5, 7.0, 3.0, 15.0, 0.0, 7.0, 1.0), Some(5.0));
        assert_eq!(bwinpro_dbh(bw, &b, 6.5, 7.0, 6.0, 15.0, 0.0, 7.0, 1.0), Some(6.0));
        assert_eq!(bwinpro_dbh(bw, &b, 1.0, 1.2, 0.0, 3.0, 0.0, 1.2, 1.0), Some(0.0));
        // from 7 cm: a fifth of the 5-year DBH change of the increment at the tree's own crown
        let (h, d, h100) = (10.65f32, 7.4f32, 11.7f32);
        let cb = b.life.stand_crown_base.unwrap().crown_base_m(h, d, h100);
        let cw = 2.0 * crate::species::allometry::stand_crown_radius(&b, d, h, cb).unwrap();
        let g5 = bwinpro_bai5(bw, d, crown_surface_area(cw, h - cb), 30.0, 2.0);
        let want = d + 0.2 * (((d * d) as f64 + 4.0 * g5 as f64 / std::f64::consts::PI).sqrt() as f32 - d);
        let got = bwinpro_dbh(bw, &b, h, h + 0.4, d, 30.0, 2.0, h100, 1.0).unwrap();
        assert!((got - want).abs() < 1e-5 && got > d, "{got} {want}");
        // without the stand-grown crown functions it does not apply
        b.life.stand_crown_base = None;
        assert_eq!(bwinpro_dbh(bw, &b, h, h + 0.4, d, 30.0, 2.0, h100, 1.0), None);
    }

    /// The stand-grown crown base (trial 46, defect 13): in a closed stand (CCF ≥ 2) a canopy
    /// beech of 29.7 m and 30 cm under a 25.5 m top height gets Döbbeler et al.'s crown base,
    /// 0.542 of its height (the function at h100 = max(h100, h)) (the light rule alone: 1 − 0.75 = 0.25); open-grown (CCF ≤ 1) the light
    /// rule; half-way between at CCF 1.5; thinner than 7 cm or without the function, the light rule.
    #[test]
    fn canopy_crown_base_follows_the_stand_grown_function_in_closed_stands() {
        let mut b = beech_like();
        b.life.stand_crown_base = Some(crate::species::StandCrownBase { a: 0.25704, b: 0.11819, c: -0.002065, e: 0.13831 });
        let (h, d, h100) = (29.7f32, 30.0f32, 25.5f32);
        let light_cb = h * 0.25;
        let x = 0.25704 + 0.11819 * h / d - 0.002065 * d + 0.13831 * h.ln();
        let want = h * (1.0 - (-x).exp());
        assert!((want / h - 0.542).abs() < 0.001, "{}", want / h);
        assert!((stand_crown_base(&b, 3.0, h100, h, d, light_cb) - want).abs() < 1e-4);
        assert_eq!(stand_crown_base(&b, 1.0, h100, h, d, light_cb), light_cb);
        assert!((stand_crown_base(&b, 1.5, h100, h, d, light_cb) - 0.5 * (light_cb + want)).abs() < 1e-4);
        assert_eq!(stand_crown_base(&b, 3.0, h100, 9.0, 6.9, 2.0), 2.0);
        // a light rule above the function stays (the crown base never falls)
        assert_eq!(stand_crown_base(&b, 3.0, h100, h, d, 0.6 * h), 0.6 * h);
        // a very slender pole keeps at least a fifth of its height in crown
        assert!(stand_crown_base(&b, 3.0, h100, 20.0, 7.0, 1.0) <= 0.8 * 20.0 + 1e-5);
        b.life.stand_crown_base = None;
        assert_eq!(stand_crown_base(&b, 3.0, h100, h, d, light_cb), light_cb);
    }

    /// The per-period growth factor (TreeGrOSS's increment error drawn per 5-year step): the
    /// same within a period, drawn anew in the next; over trees its log has mean 0 and sd σ;
    /// the draws of two periods are uncorrelated (so a thinning cannot select a lasting class),
    /// and σ 0 is no factor.
    #[test]
    fn period_factor_is_drawn_per_period() {
        let sigma = 0.15f32;
        assert_eq!(period_factor(1, 42, 10, sigma), period_factor(1, 42, 14, sigma));
        assert_ne!(period_factor(1, 42, 14, sigma), period_factor(1, 42, 15, sigma));
        assert_eq!(period_factor(1, 42, 13, 0.0), 1.0);
        let n = 20_000u64;
        let a: Vec<f64> = (0..n).map(|id| (period_factor(3, id, 20, sigma) as f64).ln()).collect();
        let b: Vec<f64> = (0..n).map(|id| (period_factor(3, id, 25, sigma) as f64).ln()).collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (ma, mb) = (mean(&a), mean(&b));
        let sd = (a.iter().map(|x| (x - ma).powi(2)).sum::<f64>() / n as f64).sqrt();
        let cov = a.iter().zip(&b).map(|(x, y)| (x - ma) * (y - mb)).sum::<f64>() / n as f64;
        let r = cov / (sd * sd);
        assert!(ma.abs() < 0.005 && (sd - 0.15).abs() < 0.005 && r.abs() < 0.03, "mean {ma} sd {sd} r {r}");
        // the persistent factor is the same tree's every year (its correlation is 1)
        assert_eq!(growth_factor(3, 7), growth_factor(3, 7));
    }

    /// The dense-stand height bound: beech's curve (iLand fasy `HDhigh` integrated from breast
    /// height) at 10 cm, 2 cm and 0.1 cm DBH, and a season's
    /// [`finish`]: a suppressed tree above the curve stalls, one below it grows to the curve,
    /// one within it and a tree below breast height keep their increment.
    #[test]
    fn dense_height_bound_holds() {
        let hd = DenseHd { k: 323.63, c: -0.3676 };
        // 1.3 + 323.63 · 10^0.6324 / 100 = 15.182 m (H/D 152); 2 cm: 6.317 m (H/D 316); 0.1 cm:
        // 2.055 m (a tree with a DBH stands above breast height)
        assert!((dense_height_bound(hd, 10.0) - 15.182).abs() < 0.01, "{}", dense_height_bound(hd, 10.0));
        assert!((dense_height_bound(hd, 2.0) - 6.317).abs() < 0.01, "{}", dense_height_bound(hd, 2.0));
        assert!((dense_height_bound(hd, 0.1) - 2.055).abs() < 0.01, "{}", dense_height_bound(hd, 0.1));
        let mut b = beech_like();
        b.life.dense_hd = Some(hd);
        let dbh_of = Table::exact(OpenDbh::of(&b));
        let bound = Some((hd, hd.k * b.life.max_dbh_cm.powf(hd.c)));
        let grown = |h: f32, h1: f32, d1: f32| finish(&b, &dbh_of, bound, 0.5, 10.0, 0.5, h, h1, d1, 0.0, 1.0, 1.0, 1.0).h;
        // 9.68 m on 2 cm (H/D 484, the round-27 trial's birch): no height growth until the DBH catches up
        assert_eq!(grown(9.68, 9.9, 2.0), 9.68);
        // 4 m growing to 7 m on 2 cm: cut to the curve; to 6 m: within it
        assert!((grown(4.0, 7.0, 2.0) - 6.317).abs() < 0.01);
        assert_eq!(grown(4.0, 6.0, 2.0), 6.0);
        // within the curve (20 m on 30 cm, H/D 67; the curve allows 29.1 m): unchanged
        assert_eq!(grown(19.5, 20.0, 30.0), 20.0);
        // below breast height, no DBH: unchanged
        assert_eq!(grown(0.8, 1.1, 0.0), 1.1);
        // a species without the curve: the unbounded height
        assert_eq!(finish(&b, &dbh_of, None, 0.5, 10.0, 0.5, 9.68, 9.9, 2.0, 0.0, 1.0, 1.0, 1.0).h, 9.9);
    }
}
