//! The evaluation of Plastic Trees section 7 and Table 1 (Pirk et al. 2012, `000_*.txt`): trees
//! of three tropism types are grown by a growth model in the open (set O) and beside a wall
//! (set G), and the open-grown ones are adapted to the same wall by Plastic Trees (set T);
//! constrained edit distances ([`crate::structure::edit_distance`], Zhang 1996) between pairs
//! of trees (no tree used twice within a group) form the groups T–T, T–O, T–G and G–G, and
//! two-tailed t-tests compare T–G with G–G (the paper: not significant) and T–O with T–T (the
//! paper: significant).
//!
//! Our growth model is the light-guided one (Yi et al., `001_*.txt`) with its paper parameters;
//! a type's tropisms (w_p, w_g) enter its shoot direction V_u = V_d + μV_o + γV_t as
//! μ = w_p/(1 − w_p − w_g) and γ = w_g/(1 − w_p − w_g) (the same balance of own direction and
//! tropisms as eq. 6 over one internode), and Plastic Trees adapts with the same w_p, w_g,
//! c_ψ = 0.8 and γ_c0 = 0.5. The t-test is Welch's (unequal variances); p from Student's t
//! distribution (`statrs`).

use super::{Environment, PlasticTree};
use crate::error::{Error, Result};
use crate::species::PlasticParams;
use crate::structure::edit_distance::constrained_edit_distance;
use crate::structure::grow::light_guided::{self, LightOptions};
use crate::structure::grow::space::Obstacle;
use crate::structure::params;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// A tree type of section 7: phototropism and gravitropism weights (sum < 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeType {
    /// Phototropism w_p.
    pub phototropism: f32,
    /// Gravitropism w_g.
    pub gravitropism: f32,
}

/// The paper's three types: (0.25, 0.12), (0.45, 0.44), (0.03, 0.23).
pub const PAPER_TYPES: [TreeType; 3] = [TreeType { phototropism: 0.25, gravitropism: 0.12 }, TreeType { phototropism: 0.45, gravitropism: 0.44 }, TreeType { phototropism: 0.03, gravitropism: 0.23 }];

/// How the sets are made.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalOptions {
    /// Distances per group (the paper: 50); each set holds 2× as many trees.
    pub pairs: usize,
    /// Growth cycles (years) of the light-guided model.
    pub cycles: u32,
    /// Light-guided options (space, internode).
    pub light: LightOptions,
    /// The wall of sets G and T.
    pub wall: Obstacle,
    /// Seed of the first tree (tree k has seed `seed0 + k`).
    pub seed0: u64,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions { pairs: 50, cycles: 10, light: LightOptions::default(), wall: Obstacle::Wall { x: 1.5 }, seed0: 1 }
    }
}

/// Mean, standard deviation (n − 1) and values of one group of distances (cm of radius).
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Mean (cm).
    pub mean: f64,
    /// Sample standard deviation (cm).
    pub sd: f64,
    /// The distances (cm).
    pub values: Vec<f64>,
}

impl Group {
    fn of(values: Vec<f64>) -> Group {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n.max(1.0);
        let sd = if n > 1.0 { (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { 0.0 };
        Group { mean, sd, values }
    }
}

/// One row block of Table 1.
#[derive(Debug, Clone, PartialEq)]
pub struct TypeResult {
    /// The type.
    pub ty: TreeType,
    /// T–G distances.
    pub tg: Group,
    /// G–G distances.
    pub gg: Group,
    /// T–O distances.
    pub to: Group,
    /// T–T distances.
    pub tt: Group,
    /// Two-tailed p of T–G vs G–G.
    pub p_tg_gg: f64,
    /// Two-tailed p of T–O vs T–T.
    pub p_to_tt: f64,
}

/// Two-tailed p-value of Welch's t-test between two samples (each ≥ 2 values); 1 when both
/// have zero variance and equal means, 0 when zero variance and different means.
///
/// Errors: [`Error::Invalid`] for a sample with fewer than 2 values.
pub fn welch_p(a: &[f64], b: &[f64]) -> Result<f64> {
    if a.len() < 2 || b.len() < 2 {
        return Err(Error::Invalid { context: "t-test".into(), field: "samples".into(), value: format!("{} and {} values", a.len(), b.len()), expected: "at least 2 values each".into() });
    }
    let (ga, gb) = (Group::of(a.to_vec()), Group::of(b.to_vec()));
    let (va, vb) = (ga.sd.powi(2) / a.len() as f64, gb.sd.powi(2) / b.len() as f64);
    if va + vb == 0.0 {
        return Ok(if ga.mean == gb.mean { 1.0 } else { 0.0 });
    }
    let t = (ga.mean - gb.mean) / (va + vb).sqrt();
    let df = (va + vb).powi(2) / (va.powi(2) / (a.len() as f64 - 1.0) + vb.powi(2) / (b.len() as f64 - 1.0));
    let dist = StudentsT::new(0.0, 1.0, df).map_err(|e| Error::Invalid { context: "t-test".into(), field: "degrees of freedom".into(), value: format!("{df} ({e})"), expected: "> 0".into() })?;
    Ok(2.0 * (1.0 - dist.cdf(t.abs())))
}

/// Builds the sets O, G, T of one type and the four groups of distances (Table 1).
///
/// Errors: those of the light-guided growth, of Plastic Trees and of the edit distance.
pub fn evaluate_type(ty: TreeType, o: &EvalOptions) -> Result<TypeResult> {
    let rest = 1.0 - ty.phototropism - ty.gravitropism;
    let mut lp = params::light_guided_paper();
    lp.mu = ty.phototropism / rest;
    lp.gamma = ty.gravitropism / rest;
    let pp = PlasticParams { phototropism: ty.phototropism, gravitropism: ty.gravitropism, pruning_c_psi: 0.8, translucency_gamma_c0: 0.5 };
    let n = 2 * o.pairs;
    let wall = [o.wall];
    let env = Environment::with_obstacles(&wall);
    let grown: Vec<(crate::structure::Skeleton, crate::structure::Skeleton, crate::structure::Skeleton)> = (0..n)
        .into_par_iter()
        .map(|k| {
            let seed = o.seed0 + k as u64;
            let open = light_guided::grow(&lp, &o.light, &[], seed, o.cycles)?;
            let beside = light_guided::grow(&lp, &o.light, &wall, seed, o.cycles)?;
            let mut t = PlasticTree::analyse(&open, &pp, &Environment::open(), None)?;
            t.adapt(&env)?;
            Ok((open, beside, t.skeleton()))
        })
        .collect::<Result<_>>()?;
    let d = |a: &crate::structure::Skeleton, b: &crate::structure::Skeleton| constrained_edit_distance(a, b).map(|v| 100.0 * v as f64);
    let m = o.pairs;
    let groups: Vec<Vec<f64>> = (0..4)
        .into_par_iter()
        .map(|g| {
            (0..m)
                .map(|k| match g {
                    0 => d(&grown[k].2, &grown[k + m].1),         // T–G
                    1 => d(&grown[2 * k].1, &grown[2 * k + 1].1), // G–G
                    2 => d(&grown[k].2, &grown[k + m].0),         // T–O
                    _ => d(&grown[2 * k].2, &grown[2 * k + 1].2), // T–T
                })
                .collect::<Result<Vec<f64>>>()
        })
        .collect::<Result<_>>()?;
    let [tg, gg, to, tt]: [Vec<f64>; 4] = groups.try_into().map_err(|_| Error::Invalid { context: "Table 1".into(), field: "groups".into(), value: "≠ 4".into(), expected: "4 groups".into() })?;
    let p_tg_gg = welch_p(&tg, &gg)?;
    let p_to_tt = welch_p(&to, &tt)?;
    Ok(TypeResult { ty, tg: Group::of(tg), gg: Group::of(gg), to: Group::of(to), tt: Group::of(tt), p_tg_gg, p_to_tt })
}

/// Table 1 as Markdown (means and standard deviations in cm of radius, p-values), with the
/// paper's finding checked per type at α = 0.05.
pub fn table_markdown(rows: &[TypeResult]) -> String {
    let mut s = String::from("| Type (w_p, w_g) | T–G mean ± sd | G–G mean ± sd | p (T–G vs G–G) | T–O mean ± sd | T–T mean ± sd | p (T–O vs T–T) | paper's finding |\n|---|---|---|---|---|---|---|---|\n");
    for (i, r) in rows.iter().enumerate() {
        let ok = r.p_tg_gg >= 0.05 && r.p_to_tt < 0.05;
        s += &format!(
            "| {} ({}, {}) | {:.2} ± {:.2} | {:.2} ± {:.2} | {:.3} | {:.2} ± {:.2} | {:.2} ± {:.2} | {:.3} | {} |\n",
            i + 1,
            r.ty.phototropism,
            r.ty.gravitropism,
            r.tg.mean,
            r.tg.sd,
            r.gg.mean,
            r.gg.sd,
            r.p_tg_gg,
            r.to.mean,
            r.to.sd,
            r.tt.mean,
            r.tt.sd,
            r.p_to_tt,
            if ok { "reproduced" } else { "not reproduced" }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_p_values() {
        // identical samples: p = 1; far apart: p ≈ 0
        let a = [1.0, 2.0, 3.0, 4.0];
        assert!((welch_p(&a, &a).unwrap() - 1.0).abs() < 1e-12);
        assert!(welch_p(&a, &[101.0, 102.0, 103.0, 104.0]).unwrap() < 1e-6);
        // hand-computed: means 2.5 and 3.5, variances 5/3 each, n = 4: t = −1/√(5/6) = −1.0954,
        // df = 6, two-tailed p = 0.3153
        let p = welch_p(&a, &[2.0, 3.0, 4.0, 5.0]).unwrap();
        assert!((p - 0.3153).abs() < 1e-3, "p {p}");
        assert!(welch_p(&[1.0], &a).is_err());
    }
}
