//! Paper parameter sets for the growth models, used by tests, benches and the CLI until (or
//! besides) the species library.
//!
//! - EcoMod beech and pine: Zamuda et al., `004_*.txt`, section III.A and III.B (exact values).
//! - Light-guided: Yi et al., `001_*.txt`, Table 1 (row "Fig.4": λ 0.52, k 0.5, b 2, μ 1.5, γ 0.5,
//!   θ 45°, r_s 0.35).
//! - Laplacian: Jinasena & Sonnadara, `003_*.txt`, Table I (c 0.67, α 1.15, β 1.50).

use crate::species::{EcoModParams, LaplacianParams, LeafDistribution, LightGuidedParams, PolyLine};

fn pl(p: &[(f32, f32)]) -> PolyLine {
    p.iter().map(|&(x, y)| [x, y]).collect()
}

/// Evaluates a poly-line graph at `x`: linear interpolation between control points (sorted by
/// abscissa as given), constant beyond the ends; a vertical step (two points at the same
/// abscissa) takes the later point's value from that abscissa on. Empty graphs give 1 (the
/// neutral factor of eqs. 1–6).
pub fn eval_polyline(p: &PolyLine, x: f32) -> f32 {
    let Some(first) = p.first() else { return 1.0 };
    if x <= first[0] {
        // with a step at the first abscissa, the later value holds from there on
        let mut v = first[1];
        for q in p.iter() {
            if q[0] == first[0] && x >= first[0] {
                v = q[1];
            }
        }
        return v;
    }
    for w in p.windows(2) {
        let (a, b) = (w[0], w[1]);
        if x >= a[0] && x < b[0] {
            let t = (x - a[0]) / (b[0] - a[0]);
            return a[1] + t * (b[1] - a[1]);
        }
    }
    p[p.len() - 1][1]
}

impl EcoModParams {
    /// Beech (Fagus sylvatica) of EcoMod, `004_*.txt` section III.A: S = 1000, L₀ = 5 m,
    /// k_d = 0.01, α_p = 85°, k_c = 0.3, l_l = 0.2862 m, ρ_l = 5, Spiral leaves, w_g = 1.5, k_f = 1.
    /// The paper gives no undirected wind speed w_s: 0 is used (k_f = 1 cancels it anyway).
    pub fn beech_paper() -> Self {
        EcoModParams {
            strands: 1000,
            trunk_length_m: 5.0,
            k_d: 0.01,
            k_c: 0.3,
            phyllotaxis_deg: 85.0,
            leaf_density: 5.0,
            leaf_size_m: 0.2862,
            leaf_distribution: LeafDistribution::Spiral,
            wind_directed: 1.5,
            wind_undirected: 0.0,
            k_f: 1.0,
            ks_g: pl(&[(0.0, 0.75), (15.0, 0.9)]),
            ks_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            alpha_g: pl(&[(0.0, 45.0), (15.0, 45.0)]),
            alpha_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            alpha_m_g: pl(&[(0.0, 0.0), (15.0, 0.0)]),
            alpha_m_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            max_len_g: pl(&[(0.0, 1.0), (15.0, 1.0)]),
            max_len_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            kl_g: pl(&[(0.0, 1.0), (15.0, 1.0)]),
            kl_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            min_len_g: pl(&[(0.0, 1.0), (7.5, 0.45), (15.0, 1.0)]),
            min_len_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            whorls: None,
            limbs: None,
            crown_profile: None,
        }
    }

    /// Pine (Pinus) of EcoMod, `004_*.txt` section III.B: S = 6000, L₀ = 5.47 m, k_d = 0.005,
    /// α_p = 85°, k_c = 0.98, l_l = 0.1815 m, ρ_l = 30, Stacked leaves, w_g = 1.5, k_f = 1, and the
    /// published poly-lines.
    pub fn pine_paper() -> Self {
        EcoModParams {
            strands: 6000,
            trunk_length_m: 5.47,
            k_d: 0.005,
            k_c: 0.98,
            phyllotaxis_deg: 85.0,
            leaf_density: 30.0,
            leaf_size_m: 0.1815,
            leaf_distribution: LeafDistribution::Stacked,
            wind_directed: 1.5,
            wind_undirected: 0.0,
            k_f: 1.0,
            ks_g: pl(&[(0.0, 0.955), (0.7749, 0.9615), (1.827, 0.8288), (4.207, 0.8269), (15.0, 0.8294)]),
            ks_w: pl(&[(0.0, 1.0), (42.89, 1.005), (42.89, 0.654), (50.0, 0.6256)]),
            alpha_g: pl(&[(0.0, 128.8), (1.164, 17.91), (3.621, 45.21), (15.0, 35.83)]),
            alpha_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            alpha_m_g: pl(&[(0.0, 0.0), (0.3875, 34.62), (1.034, -4.265), (1.55, -4.154), (2.974, -5.972), (15.0, -0.8532)]),
            alpha_m_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            max_len_g: pl(&[(0.0, 0.9953), (15.0, 1.0)]),
            max_len_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            kl_g: pl(&[(0.0, 0.7109), (0.7749, 0.5385), (2.522, 1.327), (15.0, 1.0)]),
            kl_w: pl(&[(0.0, 1.014), (38.58, 1.014), (45.26, 0.5877), (50.0, 0.01896)]),
            min_len_g: pl(&[(0.0, 0.7109), (1.293, 0.8531), (15.0, 1.0)]),
            min_len_w: pl(&[(0.0, 1.0), (50.0, 1.0)]),
            whorls: None,
            limbs: None,
            crown_profile: None,
        }
    }
}

/// Light-guided defaults: Yi et al. `001_*.txt` Table 1, row "Fig.4" (a tree under a box).
pub fn light_guided_paper() -> LightGuidedParams {
    LightGuidedParams { lambda: 0.52, k: 0.5, b: 2.0, mu: 1.5, gamma: 0.5, theta_deg: 45.0, r_s: 0.35 }
}

/// Laplacian defaults: Jinasena & Sonnadara `003_*.txt` Table I: β = 1.50 (`width_rate`); the
/// paper's c = 0.67 is unitless and cancels, because diameters are W(k)/W(1) ×
/// `base_width_m` = 0.02 m (our choice: a 2 cm twig); η = 1 (the DBM exponent; the paper gives
/// no value, 1 is the classical dielectric-breakdown choice).
pub fn laplacian_paper() -> LaplacianParams {
    LaplacianParams { eta: 1.0, base_width_m: 0.02, width_rate: 1.5 }
}

/// Polynomial-form exponent α of W(k) = c·k^α (`003_*.txt` Table I).
pub const LAPLACIAN_ALPHA: f32 = 1.15;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polyline_interpolates_and_clamps() {
        let p = pl(&[(0.0, 1.0), (7.5, 0.45), (15.0, 1.0)]);
        assert_eq!(eval_polyline(&p, -1.0), 1.0);
        assert!((eval_polyline(&p, 3.75) - 0.725).abs() < 1e-6);
        assert_eq!(eval_polyline(&p, 7.5), 0.45);
        assert_eq!(eval_polyline(&p, 99.0), 1.0);
        let step = pl(&[(0.0, 1.0), (42.89, 1.005), (42.89, 0.654), (50.0, 0.6256)]);
        assert!((eval_polyline(&step, 42.89) - 0.654).abs() < 1e-6);
        assert!(eval_polyline(&step, 42.0) > 1.0);
        assert_eq!(eval_polyline(&Vec::new(), 3.0), 1.0);
    }
}
