//! Built-in test species (a beech-like and a birch-like tree) for tests and benches that must
//! not depend on the species files. Parameters are round literature-like values (beech height
//! growth fitted to NW-FVA 2021 class I top heights, `tests/data/stands/`), not a library.

use crate::species::*;

fn factor(v: f32, tol: f32) -> Factor {
    Factor { value: Indicator::Value(v), tolerance: tol }
}

fn arch() -> Architecture {
    let pl = |v: f32| vec![[0.0, v], [3.0, v]];
    Architecture {
        ecomod: EcoModParams {
            strands: 1000,
            trunk_length_m: 2.0,
            k_d: 0.02,
            k_c: 0.5,
            phyllotaxis_deg: 137.5,
            leaf_density: 10.0,
            leaf_size_m: 0.08,
            leaf_distribution: LeafDistribution::Spiral,
            wind_directed: 0.0,
            wind_undirected: 0.0,
            k_f: 0.5,
            ks_g: pl(0.5),
            ks_w: pl(0.5),
            alpha_g: pl(40.0),
            alpha_w: pl(40.0),
            alpha_m_g: pl(0.0),
            alpha_m_w: pl(0.0),
            max_len_g: pl(1.0),
            max_len_w: pl(1.0),
            kl_g: pl(1.0),
            kl_w: pl(1.0),
            min_len_g: pl(0.1),
            min_len_w: pl(0.1),
            whorls: None,
            limbs: None,
            crown_profile: None,
        },
        light_guided: LightGuidedParams { lambda: 0.5, k: 1.0, b: 2.0, mu: 0.5, gamma: 0.2, theta_deg: 45.0, r_s: 0.1 },
        laplacian: LaplacianParams { eta: 1.0, base_width_m: 0.01, width_rate: 1.5 },
        plastic: PlasticParams { phototropism: 0.5, gravitropism: 0.3, pruning_c_psi: 0.8, translucency_gamma_c0: 0.5 },
        mature_form: None,
    }
}

fn appearance(leaf: [u8; 3]) -> Appearance {
    Appearance { bark: [110, 105, 100], leaf_spring: leaf, leaf_summer: leaf, leaf_autumn: [190, 120, 40], leaf_winter: [90, 80, 70], leaf_texture: "none".into(), leaf_out_doy: 115.0, autumn_doy: 285.0, leaf_fall_doy: 303.0, crown_top_flatness: 0.6, crown_cover: 0.9, crown_clump: 0.3, leaf_length_m: None }
}

/// A beech-like species (Fagus sylvatica): L 3, shade tolerance 5, H_max 40 m, 300 years.
pub fn beech_like() -> Species {
    Species {
        id: "beech".into(),
        identity: Identity { scientific_name: "Fagus sylvatica".into(), common_name: "European beech".into(), leaf_type: LeafType::Broadleaf, deciduous: true, sources: vec![] },
        niche: Niche { l: factor(3.0, 3.0), t: factor(5.0, 1.5), k: factor(2.0, 2.5), f: factor(5.0, 1.5), r: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 }, n: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 } },
        life: LifeHistory {
            max_age_yr: 300.0,
            max_height_m: 40.0,
            max_dbh_cm: 120.0,
            maturity_age_yr: 50.0,
            shade_tolerance: 4.5,
            seeds_per_m2_crown: 30.0,
            dispersal: Dispersal { kernel: KernelType::NegativeExponential, mean_m: 15.0, max_m: 60.0 },
            germination_min_light: 0.03,
            establishment_rate: 0.05,
            growth: Growth { k: 0.0222, p: 1.79, h_max_m: None },
            allometry: Allometry { hd_a: 0.035, hd_b: 1.2, crown_c0: 1.0, crown_c1: 0.13, crown_ratio: 0.6, pipe_exponent: 2.5 },
            density: Density { sdi_max: 1000.0, reineke_slope: -1.605 },
            form_factor: crate::species::default_form_factor(),
            stand_crown: None,
            stand_crown_base: None,
            dense_hd: None,
            bai_competition: None,
            bai_bwinpro: None,
            foliage: None,
            drought_tolerance: None,
            shade_survival_class: None,
            closed_hd: None,
            closed_hd_scope: None,
            closed_hd_mixed: None,
            open_hd: None,
        },
        architecture: arch(),
        appearance: appearance([60, 120, 40]),
    }
}

/// A birch-like pioneer (Betula pendula): L 7, shade tolerance 1, H_max 27 m, 120 years.
pub fn birch_like() -> Species {
    Species {
        id: "birch".into(),
        identity: Identity { scientific_name: "Betula pendula".into(), common_name: "Silver birch".into(), leaf_type: LeafType::Broadleaf, deciduous: true, sources: vec![] },
        niche: Niche { l: factor(7.0, 3.0), t: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 }, k: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 }, f: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 }, r: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 }, n: Factor { value: Indicator::Indifferent("x".into()), tolerance: 3.0 } },
        life: LifeHistory {
            max_age_yr: 120.0,
            max_height_m: 27.0,
            max_dbh_cm: 60.0,
            maturity_age_yr: 12.0,
            shade_tolerance: 1.0,
            seeds_per_m2_crown: 200.0,
            dispersal: Dispersal { kernel: KernelType::TwoDt, mean_m: 60.0, max_m: 300.0 },
            germination_min_light: 0.5,
            establishment_rate: 0.02,
            growth: Growth { k: 0.06, p: 1.3, h_max_m: None },
            allometry: Allometry { hd_a: 0.06, hd_b: 1.1, crown_c0: 0.5, crown_c1: 0.12, crown_ratio: 0.5, pipe_exponent: 2.5 },
            density: Density { sdi_max: 650.0, reineke_slope: -1.605 },
            form_factor: crate::species::default_form_factor(),
            stand_crown: None,
            stand_crown_base: None,
            dense_hd: None,
            bai_competition: None,
            bai_bwinpro: None,
            foliage: None,
            drought_tolerance: None,
            shade_survival_class: None,
            closed_hd: None,
            closed_hd_scope: None,
            closed_hd_mixed: None,
            open_hd: None,
        },
        architecture: arch(),
        appearance: appearance([120, 170, 60]),
    }
}

/// A library of the two fixture species (sorted by id: beech = 0, birch = 1).
pub fn library() -> SpeciesLibrary {
    SpeciesLibrary { species: vec![beech_like(), birch_like()] }
}
