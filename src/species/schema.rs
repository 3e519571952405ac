//! The field table of the species schema: every leaf field of a species file with its unit,
//! allowed range and meaning. Validation ([`super::Species::validate`]) and the field table of
//! `species/README.md` ([`readme_field_table`]) are both generated from [`FIELDS`], and a test
//! checks that every leaf of a serialised species appears here and vice versa, so the code, the
//! checks and the documentation cannot drift apart.

/// What kind of value a field holds and which values are allowed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// Free text; `non_empty` requires at least one character.
    Text {
        /// Whether the empty string is refused.
        non_empty: bool,
    },
    /// Identifier: lower-case ASCII letters, digits and `_`, starting with a letter.
    Ident,
    /// A list of free-text strings.
    TextList,
    /// `true` or `false`.
    Bool,
    /// One of the listed strings.
    Enum(&'static [&'static str]),
    /// A number in `[min, max]` (`min` excluded when `min_exclusive`).
    Range {
        /// Lower bound.
        min: f64,
        /// Upper bound (inclusive).
        max: f64,
        /// Whether `min` itself is refused (`> min` instead of `≥ min`).
        min_exclusive: bool,
    },
    /// An integer in `[min, max]`.
    Int {
        /// Lower bound.
        min: i64,
        /// Upper bound.
        max: i64,
    },
    /// An Ellenberg indicator: a number in `[1, max]` or the string `"x"` (indifferent).
    Indicator {
        /// Upper end of the scale (9, or 12 for moisture F).
        max: f64,
    },
    /// An EcoMod poly-line: ≥ 1 points `[x, y]`, x non-decreasing within `x`, y within `y`.
    PolyLine {
        /// Allowed abscissa range (Gravelius order 0–15 or Weibull order 0–50).
        x: (f64, f64),
        /// Allowed ordinate range (the paper's bound for the auxiliary parameter).
        y: (f64, f64),
    },
    /// An sRGB colour `[r, g, b]`, each 0–255.
    Colour,
}

/// One leaf field of the species schema.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldSpec {
    /// Dotted path in the TOML file, e.g. `life.growth.k`.
    pub path: &'static str,
    /// Unit (empty for dimensionless).
    pub unit: &'static str,
    /// Kind and allowed values.
    pub kind: Kind,
    /// One-line meaning, with the source of the model it parameterises.
    pub doc: &'static str,
}

const fn r(min: f64, max: f64) -> Kind {
    Kind::Range {
        min,
        max,
        min_exclusive: false,
    }
}
const fn rx(min: f64, max: f64) -> Kind {
    Kind::Range { min, max, min_exclusive: true }
}
const fn pl(x: (f64, f64), y: (f64, f64)) -> Kind {
    Kind::PolyLine { x, y }
}
const G: (f64, f64) = (0.0, 15.0);
const W: (f64, f64) = (0.0, 50.0);
const fn f(path: &'static str, unit: &'static str, kind: Kind, doc: &'static str) -> FieldSpec {
    FieldSpec { path, unit, kind, doc }
}

/// Ellenberg factor description used for the niche rows.
const LIGHT: &str = "Ellenberg light value L (1 deep shade … 9 full light) read as the ADULT tree's light demand (tree-stage value, '(n)' in Ellenberg's list); shade tolerance of young trees is `life.shade_tolerance`";

/// Every leaf field of a species file, in file order.
pub const FIELDS: &[FieldSpec] = &[
    f(
        "id",
        "",
        Kind::Ident,
        "Short unique identifier (unique in a folder); by convention the file name without `.toml`",
    ),
    f(
        "identity.scientific_name",
        "",
        Kind::Text { non_empty: true },
        "Scientific name, e.g. `Fagus sylvatica`",
    ),
    f("identity.common_name", "", Kind::Text { non_empty: true }, "Common English name"),
    f("identity.leaf_type", "", Kind::Enum(&["broadleaf", "conifer"]), "Broad-leaved or needle-leaved"),
    f(
        "identity.deciduous",
        "",
        Kind::Bool,
        "Sheds its foliage in winter (larch is a deciduous conifer)",
    ),
    f(
        "identity.sources",
        "",
        Kind::TextList,
        "Sources of the numbers in the file, one per entry (optional)",
    ),
    f("niche.l.value", "Ellenberg", Kind::Indicator { max: 9.0 }, LIGHT),
    f(
        "niche.l.tolerance",
        "Ellenberg",
        rx(0.0, 12.0),
        "Tolerance width of L: suitability is exp(−½) ≈ 0.61 at value ± tolerance",
    ),
    f(
        "niche.t.value",
        "Ellenberg",
        Kind::Indicator { max: 9.0 },
        "Temperature value T (1 alpine cold … 9 Mediterranean warm)",
    ),
    f("niche.t.tolerance", "Ellenberg", rx(0.0, 12.0), "Tolerance width of T"),
    f(
        "niche.k.value",
        "Ellenberg",
        Kind::Indicator { max: 9.0 },
        "Continentality value K (1 oceanic … 9 continental)",
    ),
    f("niche.k.tolerance", "Ellenberg", rx(0.0, 12.0), "Tolerance width of K"),
    f(
        "niche.f.value",
        "Ellenberg",
        Kind::Indicator { max: 12.0 },
        "Moisture value F (1 very dry … 9 wet, 10–12 flooded/aquatic)",
    ),
    f("niche.f.tolerance", "Ellenberg", rx(0.0, 12.0), "Tolerance width of F"),
    f(
        "niche.r.value",
        "Ellenberg",
        Kind::Indicator { max: 9.0 },
        "Soil reaction value R (1 very acid … 9 basic/calcareous)",
    ),
    f("niche.r.tolerance", "Ellenberg", rx(0.0, 12.0), "Tolerance width of R"),
    f(
        "niche.n.value",
        "Ellenberg",
        Kind::Indicator { max: 9.0 },
        "Nitrogen (fertility) value N (1 very poor … 9 very rich)",
    ),
    f("niche.n.tolerance", "Ellenberg", rx(0.0, 12.0), "Tolerance width of N"),
    f("life.max_age_yr", "yr", rx(0.0, 5000.0), "Maximum age"),
    f(
        "life.max_height_m",
        "m",
        rx(0.0, 120.0),
        "Maximum height H_max (asymptote of the growth curve and height–DBH allometry)",
    ),
    f("life.max_dbh_cm", "cm", rx(0.0, 1000.0), "Maximum diameter at breast height (1.3 m)"),
    f(
        "life.maturity_age_yr",
        "yr",
        rx(0.0, 1000.0),
        "Age at which seed production starts; must be below `life.max_age_yr`",
    ),
    f(
        "life.shade_tolerance",
        "class",
        r(1.0, 5.0),
        "Shade tolerance, 1 intolerant … 5 very tolerant (LandClim/iLand scale)",
    ),
    f(
        "life.seeds_per_m2_crown",
        "seeds/m²/yr",
        r(0.0, 1.0e6),
        "Mean seeds per m² of crown projection area per year of a mature tree",
    ),
    f(
        "life.dispersal.kernel",
        "",
        Kind::Enum(&["negative_exponential", "two_dt"]),
        "Dispersal kernel: negative exponential (wind) or 2Dt fat-tailed (Clark et al. 1999; animals)",
    ),
    f("life.dispersal.mean_m", "m", rx(0.0, 1.0e4), "Mean dispersal distance"),
    f(
        "life.dispersal.max_m",
        "m",
        rx(0.0, 1.0e5),
        "Maximum dispersal distance (kernel truncation); must be ≥ `life.dispersal.mean_m`",
    ),
    f(
        "life.germination_min_light",
        "fraction",
        r(0.0, 1.0),
        "Minimum relative light at the ground (0–1) for germination",
    ),
    f(
        "life.establishment_rate",
        "probability",
        r(0.0, 1.0),
        "Probability that a seed on a suitable, lit cell becomes a seedling",
    ),
    f(
        "life.growth.k",
        "1/yr",
        Kind::Range {
            min: 0.0,
            max: 1.0,
            min_exclusive: true,
        },
        "Chapman–Richards rate k in H(t) = H_max (1 − e^(−k t))^p",
    ),
    f("life.growth.p", "", r(1.0, 10.0), "Chapman–Richards shape p (≥ 1)"),
    f("life.growth.h_max_m", "m", r(1.0, 150.0), "Chapman–Richards asymptote H_max (m; optional, default life.max_height_m)"),
    f(
        "life.allometry.hd_a",
        "1/cm",
        rx(0.0, 1.0),
        "Height–DBH H = 1.3 + (H_max − 1.3)(1 − e^(−a·D))^b: coefficient a",
    ),
    f("life.allometry.hd_b", "", rx(0.0, 10.0), "Height–DBH exponent b"),
    f(
        "life.allometry.crown_c0",
        "m",
        r(0.0, 10.0),
        "Open-grown crown radius r = c0 + c1·D: intercept c0",
    ),
    f("life.allometry.crown_c1", "m/cm", r(0.0, 1.0), "Crown radius slope c1 per cm of DBH"),
    f(
        "life.allometry.crown_ratio",
        "fraction",
        rx(0.0, 1.0),
        "Crown length / height of an open-grown tree",
    ),
    f(
        "life.allometry.pipe_exponent",
        "",
        r(2.0, 3.0),
        "Pipe-model exponent d in r^d = Σ r_j^d (2 = da Vinci/pipe model)",
    ),
    f(
        "life.density.sdi_max",
        "stems/ha",
        rx(0.0, 5000.0),
        "Maximum stand density index SDI_max: stems/ha of a fully stocked unmanaged pure stand at a quadratic mean DBH of 25 cm (Reineke 1933)",
    ),
    f(
        "life.density.reineke_slope",
        "",
        r(-3.0, -1.0),
        "Slope b of ln N on ln Dq along the maximum-density line (Reineke 1933: −1.605; Pretzsch & Biber 2005 per species)",
    ),
    f(
        "life.form_factor",
        "",
        r(0.3, 0.7),
        "Form factor f of the merchantable stem (≥ 7 cm): stem volume V = f · g · h (g basal area at 1.3 m, h height; Kramer & Akça 2008); optional, default 0.5",
    ),
    f("life.stand_crown.a", "m", r(-10.0, 30.0), "Stand-grown crown width CW = (a + b·d^p)(1 − e^(−(d/c)^e))(h − cb)^g (Döbbeler et al. 2001/2002, BWINPro/TreeGrOSS; optional): intercept a"),
    f("life.stand_crown.b", "m/cm^p", r(-1.0, 2.0), "Stand-grown crown width: slope b"),
    f("life.stand_crown.p", "", r(0.2, 2.0), "Stand-grown crown width: DBH exponent p of the slope term (default 1)"),
    f("life.stand_crown.c", "cm", rx(0.0, 200.0), "Stand-grown crown width: scale c of the saturating factor 1 − e^(−(d/c)^e) (1e-6: factor 1)"),
    f("life.stand_crown.e", "", rx(0.0, 5.0), "Stand-grown crown width: shape e of the saturating factor"),
    f("life.stand_crown.g", "", r(0.0, 1.0), "Stand-grown crown width: exponent g of the crown length h − cb (m) (default 0)"),
    f("life.stand_crown_base.a", "", r(-10.0, 10.0), "Stand-grown crown base cb = h·(1 − e^(−|a + b·h/d + c·d + e·ln h100|)) (m; h m, d DBH cm, h100 site index m; Döbbeler et al. 2001/2002, BWINPro/TreeGrOSS; optional; the drawn trees, and the simulation's canopy trees of 7 cm and more in closed stands): intercept a"),
    f("life.stand_crown_base.b", "cm/m", r(-5.0, 5.0), "Stand-grown crown base: coefficient b of the slenderness h/d"),
    f("life.stand_crown_base.c", "1/cm", r(-1.0, 1.0), "Stand-grown crown base: coefficient c of the DBH"),
    f("life.stand_crown_base.e", "", r(-5.0, 5.0), "Stand-grown crown base: coefficient e of ln h100"),
    f("life.dense_hd.k", "m/m", rx(0.0, 1000.0), "Dense-stand height–diameter curve h/d = k·D^c (h m, D cm; a tree's height is bounded by 1.3 + k·D^(1+c)/100 m; iLand HDhigh a·b·(1+c)·d^c is its derivative, k = a·b; Seidl et al. 2012; optional): coefficient k"),
    f("life.dense_hd.c", "", r(-1.0, 0.0), "Dense-stand height–diameter curve: DBH exponent c"),
    f("life.bai_competition.crown_ratio", "", r(0.0, 2.0), "Basal-area increment's competition terms ln BAI = … + b3·ln CR + c1·BAL + c2·CCF (PROGNAUS, Monserud & Sterba 1996; Hasenauer 2000; optional): crown-ratio exponent b3"),
    f("life.bai_competition.bal", "1/(m²/ha)", r(-1.0, 0.0), "Basal-area increment's competition terms: coefficient c1 of the basal area of larger trees"),
    f("life.bai_competition.ccf", "1/%", r(-0.1, 0.0), "Basal-area increment's competition terms: coefficient c2 of the crown competition factor (%)"),
    f("life.bai_bwinpro.a0", "", r(-20.0, 20.0), "BWINPro/TreeGrOSS diameter growth (Nagel et al. 2006; optional; needs stand_crown and stand_crown_base): 5-year basal-area increment ΔG5 = exp(a0 + csa·ln CSA + age·ln t + c66·C66) + Σ biask·D^k (cm²) from 7 cm DBH: intercept a0"),
    f("life.bai_bwinpro.csa", "", r(0.0, 3.0), "BWINPro diameter growth: coefficient of ln crown surface area (m²)"),
    f("life.bai_bwinpro.age", "", r(-3.0, 1.0), "BWINPro diameter growth: coefficient of ln age (years)"),
    f("life.bai_bwinpro.c66", "", r(-5.0, 0.0), "BWINPro diameter growth: coefficient of the crown-competition index C66 (m²/m²)"),
    f("life.bai_bwinpro.bias0", "cm²", r(-1000.0, 1000.0), "BWINPro diameter growth: bias polynomial, coefficient of D^0"),
    f("life.bai_bwinpro.bias1", "cm²/cm", r(-100.0, 100.0), "BWINPro diameter growth: bias polynomial, coefficient of D^1"),
    f("life.bai_bwinpro.bias2", "cm²/cm²", r(-10.0, 10.0), "BWINPro diameter growth: bias polynomial, coefficient of D^2"),
    f("life.bai_bwinpro.bias3", "cm²/cm³", r(-1.0, 1.0), "BWINPro diameter growth: bias polynomial, coefficient of D^3"),
    f("life.bai_bwinpro.bias4", "cm²/cm⁴", r(-0.1, 0.1), "BWINPro diameter growth: bias polynomial, coefficient of D^4"),
    f("life.bai_bwinpro.bias5", "cm²/cm⁵", r(-0.01, 0.01), "BWINPro diameter growth: bias polynomial, coefficient of D^5"),
    f("life.bai_bwinpro.period_sigma", "", r(0.0, 1.0), "BWINPro diameter growth: σ of a growth factor exp(σ z) drawn anew per tree every 5-year period (TreeGrOSS Tree.grow's increment error; optional: a persistent factor without it)"),
    f("life.bai_bwinpro.youth_hd", "m/cm", rx(0.3, 5.0), "BWINPro diameter growth: youth height–diameter ratio, D = h / youth_hd below 7 cm (TreeGrOSS Tree.grow)"),
    f("life.drought_tolerance", "drought index", r(0.05, 0.6), "Drought tolerance: the largest drought index (0–1; ForClim's growing-season 1 − AET/PET: `climate::water::drought_index`) at which the species grows; the site suitability's drought limit is sqrt(1 − DI / tolerance) of the drought beyond the species' F optimum, DI = (min(F optimum, 5) − F) / 10, F optimum 5 for an indifferent F (ForClim, Bugmann & Cramer 1998; values: ForClim 2.x's kDrTol for that water balance, species/sources/SOURCES.md; optional: without it no drought limit)"),
    f("life.closed_hd", "m/m", r(40.0, 250.0), "Slenderness H/D of the closed-stand diameter increment of the youth below the inventory threshold (DBH < 7 cm; from 7 cm on 60, as TreeGrOSS's youth rule grows only the trees below 7 cm): under crowding the potential diameter increment is 100·ΔH_pot/closed_hd cm a year (floored at that of a 0.3 m height growth, never above the open-grown increment; `sim::phases::growth::closed_increment`, `closed_slenderness`; optional: without it 60 at every DBH)"),
    f("life.closed_hd_scope", "", Kind::Enum(&["youth", "dense_curve"]), "Where closed_hd holds: `youth` below 7 cm DBH only (TreeGrOSS's scope; the default), or `dense_curve` at every DBH until the tree reaches the species' dense-stand height–diameter curve (life.dense_hd), along which a tree held at the curve then grows, at the curve's slope dh/dD = (1 + c)·k·D^c where that is stouter than closed_hd (`sim::phases::growth::closed_slenderness_held`; optional: youth)"),
    f("life.closed_hd_mixed", "m/m", r(40.0, 250.0), "Crown plasticity in mixture: the closed-stand slenderness that closed_hd gives way to among other species, H/D = closed_hd_mixed + (closed_hd − closed_hd_mixed)·share, share the tree's own species' share of its neighbourhood's open-grown crown projection (1 pure: closed_hd; `sim::density::Crowding::own_share`, `sim::phases::growth::mixed_closed_hd`; optional: without it the slenderness does not depend on the mixture)"),
    f("life.open_hd.k", "m/m", rx(0.0, 1000.0), "Open-grown height–diameter curve (iLand HDlow a·b·(1+c)·d^c, k = a·b; Seidl et al. 2012; optional, with dense_hd): with dense_hd the closed-stand diameter increment from 7 cm DBH follows the H/D HDhigh − (HDhigh − HDlow)·light of the increments (iLand Tree::relative_height_growth; `sim::phases::growth::closed_slenderness`; without it 60): coefficient k"),
    f("life.open_hd.c", "", r(-1.0, 0.0), "Open-grown height–diameter curve: DBH exponent c"),
    f("life.shade_survival_class", "class", r(1.0, 5.0), "Shade tolerance class of survival in shade, 1 least … 5 most tolerant (LandClim's ShadeTolerance after Ellenberg 1996): sets the shade mortality (`sim::phases::mortality::p_shade`; optional: without it `life.shade_tolerance`)"),
    f("life.foliage.crown_lai", "m²/m²", r(1.0, 15.0), "Leaf area of drawn crowns: one-sided leaf area per m² of crown projection, a published leaf-area index of closed pure stands of the species (species/sources/SOURCES.md; optional: without it drawn crowns carry the light model's 2 + 0.5·shade tolerance; pictures and exports only, not the simulation)"),
    f(
        "architecture.ecomod.strands",
        "",
        Kind::Int { min: 1, max: 10000 },
        "EcoMod number of strands S (dialog 0–5000; the paper's pine uses 6000)",
    ),
    f("architecture.ecomod.trunk_length_m", "m", r(0.0, 10.0), "EcoMod base trunk length L₀"),
    f(
        "architecture.ecomod.k_d",
        "",
        r(0.0, 0.05),
        "EcoMod branch thickness coefficient k_d (d = k_d √S)",
    ),
    f("architecture.ecomod.k_c", "", r(0.0, 1.0), "EcoMod gravicentrism k_c"),
    f("architecture.ecomod.phyllotaxis_deg", "°", r(0.0, 360.0), "EcoMod phyllotaxis angle α_p"),
    f("architecture.ecomod.leaf_density", "", r(0.0, 30.0), "EcoMod leaf density ρ_l"),
    f("architecture.ecomod.leaf_size_m", "m", r(0.0, 0.3), "EcoMod leaf size l_l"),
    f(
        "architecture.ecomod.leaf_distribution",
        "",
        Kind::Enum(&["Spiral", "Stacked", "Staggered", "Bunched", "Coniferous"]),
        "EcoMod leaf distribution l_type",
    ),
    f("architecture.ecomod.wind_directed", "", r(0.0, 10.0), "EcoMod directed wind speed w_g"),
    f("architecture.ecomod.wind_undirected", "", r(0.0, 10.0), "EcoMod undirected wind speed w_s"),
    f("architecture.ecomod.k_f", "", r(0.0, 1.0), "EcoMod wind flexibility k_f"),
    f("architecture.ecomod.ks_g", "", pl(G, (0.5, 1.0)), "EcoMod k_s^g over Gravelius order g (eq. 1)"),
    f("architecture.ecomod.ks_w", "", pl(W, (0.0, 2.0)), "EcoMod k_s^w over Weibull order w (eq. 1)"),
    f("architecture.ecomod.alpha_g", "°", pl(G, (0.0, 180.0)), "EcoMod branching angle α^g (eq. 2)"),
    f("architecture.ecomod.alpha_w", "", pl(W, (0.0, 2.0)), "EcoMod α^w (eq. 2)"),
    f(
        "architecture.ecomod.alpha_m_g",
        "°",
        pl(G, (-180.0, 180.0)),
        "EcoMod gravimorphism α_m^g (eq. 3)",
    ),
    f("architecture.ecomod.alpha_m_w", "", pl(W, (0.0, 2.0)), "EcoMod α_m^w (eq. 3)"),
    f(
        "architecture.ecomod.max_len_g",
        "",
        pl(G, (0.0, 10.0)),
        "EcoMod maximum relative branch length M^g (eq. 4)",
    ),
    f("architecture.ecomod.max_len_w", "", pl(W, (0.0, 2.0)), "EcoMod M^w (eq. 4)"),
    f("architecture.ecomod.kl_g", "", pl(G, (0.0, 10.0)), "EcoMod branch length scaling k_l^g (eq. 5)"),
    f("architecture.ecomod.kl_w", "", pl(W, (0.0, 2.0)), "EcoMod k_l^w (eq. 5)"),
    f(
        "architecture.ecomod.min_len_g",
        "",
        pl(G, (0.0, 10.0)),
        "EcoMod minimum relative branch length m^g (eq. 6)",
    ),
    f("architecture.ecomod.min_len_w", "", pl(W, (0.0, 2.0)), "EcoMod m^w (eq. 6)"),
    f("architecture.ecomod.whorls.branches", "", Kind::Int { min: 1, max: 12 }, "Whorled stem (conifers; optional, ours: each stem split of EcoMod is an annual shoot of the leader): first-order branches of the whorl at the top of each annual shoot"),
    f("architecture.ecomod.whorls.interwhorl", "", Kind::Int { min: 0, max: 12 }, "Whorled stem: interwhorl branches along each annual shoot, below its whorl"),
    f("architecture.ecomod.whorls.interwhorl_share", "", r(0.05, 1.0), "Whorled stem: strands of an interwhorl branch over a whorl branch's"),
    f("architecture.ecomod.limbs.angle_top_deg", "°", r(20.0, 120.0), "First-order limbs by depth into the crown (optional, ours): insertion angle from the vertical of a limb at the top of the stem (0 up, 90 horizontal)"),
    f("architecture.ecomod.limbs.angle_base_deg", "°", r(20.0, 120.0), "First-order limbs: insertion angle from the vertical of a limb at the crown base (linear in depth from the top's)"),
    f("architecture.ecomod.limbs.spray", "", r(0.0, 2.0), "First-order limbs: relative width of a limb's flat spray of foliage per metre of its distance from the stem (pictures and exports only: the full level's shoot cards; 0 none)"),
    f("architecture.ecomod.limbs.widest_depth", "", r(0.05, 1.0), "First-order limbs: relative depth into the crown (0 top, 1 crown base) below which the limbs are as long as the longest (above it their reach falls linearly to the top)"),
    f("architecture.ecomod.crown_profile.angle_base_deg", "°", r(10.0, 120.0), "Broadleaf crown profile: insertion angle from the vertical of a limb at the crown base (linear in depth from the top's)"),
    f("architecture.ecomod.crown_profile.angle_top_deg", "°", r(10.0, 120.0), "Broadleaf crown profile (optional, ours; the stem's strands shared among its limbs by the crown volume each serves, each limb reaching the profile's surface): insertion angle from the vertical of a limb at the top of the stem"),
    f("architecture.ecomod.crown_profile.base_share", "", r(0.0, 1.0), "Broadleaf crown profile: crown radius at the crown base over the largest (below the widest point the radius falls as 1 − (1 − base_share)·t²)"),
    f("architecture.ecomod.crown_profile.fork_angle_deg", "°", r(5.0, 60.0), "Broadleaf crown profile: angle from the vertical of the main limbs the leader forks into (optional; default 25)"),
    f("architecture.ecomod.crown_profile.fork_depth", "", r(0.05, 0.95), "Broadleaf crown profile (optional, round 46): relative depth below the crown's top (0 top, 1 crown base) at which the leader forks into a few main limbs that carry the crown's top (decurrent habit; absent: the stem runs to the top)"),
    f("architecture.ecomod.crown_profile.fork_limbs", "", Kind::Int { min: 2, max: 4 }, "Broadleaf crown profile: number of main limbs the leader forks into (optional; default 3)"),
    f("architecture.ecomod.crown_profile.top_exponent", "", r(0.2, 1.0), "Broadleaf crown profile: exponent b of the light crown above the widest point, radius (depth / widest_depth)^b (0.5 a paraboloid)"),
    f("architecture.ecomod.crown_profile.twig_droop_deg", "°", r(0.0, 90.0), "Broadleaf crown profile (optional, round 46): angle below the horizontal of every leaf-bearing tip twig off the stem, its leaves hanging with it (weeping birch); absent: the tips keep EcoMod's direction"),
    f("architecture.ecomod.crown_profile.widest_depth", "", r(0.1, 0.9), "Broadleaf crown profile: relative depth below the crown's top of its widest point (0 top, 1 crown base)"),
    f("architecture.ecomod.crown_profile.width_to_length", "", r(0.2, 2.0), "Broadleaf crown profile: crown width over crown length of the grown model before it is fitted to the simulated crown (sets the profile's aspect and so the limbs' lengths)"),
    f(
        "architecture.light_guided.lambda",
        "",
        r(0.0, 1.0),
        "Light-guided λ: main-axis weight of the Borchert–Honda allocation (Yi et al. eq. 1)",
    ),
    f(
        "architecture.light_guided.k",
        "",
        r(0.0, 1.0),
        "Light-guided priority allocation coefficient k (Yi et al. Table 1)",
    ),
    f(
        "architecture.light_guided.b",
        "",
        rx(1.0, 10.0),
        "Light-guided shadow propagation base b (Yi et al. Table 1)",
    ),
    f(
        "architecture.light_guided.mu",
        "",
        r(0.0, 10.0),
        "Light-guided weight μ of the optimal light direction",
    ),
    f(
        "architecture.light_guided.gamma",
        "",
        r(0.0, 10.0),
        "Light-guided weight γ of the tropism direction",
    ),
    f(
        "architecture.light_guided.theta_deg",
        "°",
        rx(0.0, 90.0),
        "Light-guided half-angle θ of the perception cone",
    ),
    f("architecture.light_guided.r_s", "", r(0.0, 1.0), "Light-guided shedding threshold r_s"),
    f("architecture.laplacian.eta", "", r(0.0, 10.0), "Laplacian (DBM) exponent η in p ∝ φ^η"),
    f(
        "architecture.laplacian.base_width_m",
        "m",
        rx(0.0, 1.0),
        "Laplacian width W(1) of a Strahler order-1 branch",
    ),
    f(
        "architecture.laplacian.width_rate",
        "",
        r(1.0, 5.0),
        "Laplacian width growth per Strahler order β in W(k) = W(1)·β^(k−1) (Jinasena & Sonnadara Table I)",
    ),
    f("architecture.plastic.phototropism", "", r(0.0, 1.0), "Plastic Trees phototropism weight"),
    f("architecture.plastic.gravitropism", "", r(0.0, 1.0), "Plastic Trees gravitropism weight"),
    f(
        "architecture.plastic.pruning_c_psi",
        "",
        r(0.0, 2.0),
        "Plastic Trees pruning strength c_ψ (paper default 0.8)",
    ),
    f(
        "architecture.plastic.translucency_gamma_c0",
        "",
        r(0.0, 1.0),
        "Plastic Trees base leaf-cluster translucency γ_c0 (paper default 0.5, eq. 4)",
    ),
    f("architecture.mature_form.from_age_yr", "yr", r(0.0, 1000.0), "EcoMod model's change with age (optional; `sylva tree grow` only): age up to which the species' EcoMod model holds unchanged, blended linearly to the values below by `full_age_yr`"),
    f("architecture.mature_form.full_age_yr", "yr", rx(0.0, 1000.0), "Mature form: age from which its values hold in full; must exceed `architecture.mature_form.from_age_yr`"),
    f("architecture.mature_form.trunk_k_s", "", r(0.5, 1.0), "Mature form: k_s^g at Gravelius order 0 (eq. 1), the stem's share of the strands at each split"),
    f("architecture.mature_form.trunk_alpha_deg", "°", r(0.0, 180.0), "Mature form: α^g at order 0 (eq. 2), the angle between the stem's continuation and a limb"),
    f("architecture.mature_form.limb_alpha_m_deg", "°", r(-180.0, 180.0), "Mature form: α_m^g at order 1 (eq. 3), the limbs' gravimorphism (+ turns up)"),
    f("architecture.mature_form.crown_profile.angle_base_deg", "°", r(10.0, 120.0), "Mature form's crown profile: insertion angle from the vertical of a limb at the crown base"),
    f("architecture.mature_form.crown_profile.angle_top_deg", "°", r(10.0, 120.0), "Mature form's crown profile (optional; `architecture.ecomod.crown_profile`'s fields, used from the middle of the blend on): insertion angle from the vertical of a limb at the top of the stem"),
    f("architecture.mature_form.crown_profile.base_share", "", r(0.0, 1.0), "Mature form's crown profile: crown radius at the crown base over the largest"),
    f("architecture.mature_form.crown_profile.top_exponent", "", r(0.2, 1.0), "Mature form's crown profile: exponent b of the light crown above the widest point, radius (depth / widest_depth)^b (small: a flat top)"),
    f("architecture.mature_form.crown_profile.widest_depth", "", r(0.1, 0.9), "Mature form's crown profile: relative depth below the crown's top of its widest point (0 top, 1 crown base)"),
    f("architecture.mature_form.crown_profile.width_to_length", "", r(0.2, 2.0), "Mature form's crown profile: crown width over crown length of the grown model before it is fitted"),
    f(
        "architecture.mature_form.leaf_distribution",
        "",
        Kind::Enum(&["Spiral", "Stacked", "Staggered", "Bunched", "Coniferous"]),
        "Mature form: EcoMod leaf distribution l_type from the middle of the blend on",
    ),
    f("appearance.bark", "sRGB", Kind::Colour, "Bark colour"),
    f("appearance.leaf_spring", "sRGB", Kind::Colour, "Foliage colour at leaf-out"),
    f("appearance.leaf_summer", "sRGB", Kind::Colour, "Foliage colour in summer"),
    f("appearance.leaf_autumn", "sRGB", Kind::Colour, "Foliage colour in autumn"),
    f(
        "appearance.leaf_winter",
        "sRGB",
        Kind::Colour,
        "Foliage colour in winter (evergreens; deciduous trees are drawn bare)",
    ),
    f(
        "appearance.leaf_texture",
        "",
        Kind::Enum(&LEAF_TEXTURES),
        "Leaf-card outline drawn by structure::texture (none: ovate for broadleaves, short needles for conifers)",
    ),
    f(
        "appearance.leaf_out_doy",
        "day of year",
        r(1.0, 366.0),
        "Leaf unfolding (BBCH 11; evergreens: new-shoot flush), Central-European lowland mean",
    ),
    f(
        "appearance.autumn_doy",
        "day of year",
        r(1.0, 366.0),
        "Half the foliage in autumn colour (BBCH 94; evergreens: start of the turn to the winter colour); after leaf_out_doy",
    ),
    f(
        "appearance.leaf_fall_doy",
        "day of year",
        r(1.0, 366.0),
        "Half the leaves fallen (BBCH 95; evergreens: winter colour reached); after autumn_doy",
    ),
    f(
        "appearance.crown_top_flatness",
        "",
        r(0.0, 1.0),
        "Crown top seen from afar: 0 pointed spire, about 0.6 rounded dome, 1 flat umbrella",
    ),
    f(
        "appearance.crown_cover",
        "",
        r(0.0, 1.0),
        "Fraction of the crown's plan area covered by foliage (1 dense, lower = airy)",
    ),
    f(
        "appearance.crown_clump",
        "",
        r(0.0, 1.0),
        "Clumping of the foliage: 0 smooth even surface, 1 separate lumps with gaps",
    ),
    f(
        "appearance.leaf_length_m",
        "m",
        r(0.01, 0.5),
        "Length of a drawn leaf card of `sylva tree grow`: a broadleaf's leaf length from a flora (a pinnate leaf's whole length); a conifer's shoot card, whose drawn needles are `LeafShape::needle_length_share` of it (0.17 needle_short, 0.42 needle_long, 0.21 needle_flat, 0.10 needle_tuft) (optional: without it EcoMod's leaf_size_m; every shipped species gives one, tests/species_leaf_length.rs; the stand exports' and stills' trees keep EcoMod's leaf size)",
    ),
];

/// The values of `appearance.leaf_texture`: the leaf-card outlines of
/// `structure::texture::LeafShape`, in its order, then `"none"` (the default of the leaf type).
pub const LEAF_TEXTURES: [&str; 12] = [
    "broad_ovate",
    "broad_lobed",
    "broad_cordate",
    "broad_palmate",
    "broad_pinnate",
    "broad_round",
    "broad_triangular",
    "needle_short",
    "needle_long",
    "needle_flat",
    "needle_tuft",
    "none",
];

/// Looks up the spec of a dotted field path.
pub fn field(path: &str) -> Option<&'static FieldSpec> {
    FIELDS.iter().find(|f| f.path == path)
}

fn num(x: f64) -> String {
    // Shortest representation that round-trips through f32, as in the files.
    format!("{}", x as f32)
}

impl Kind {
    /// The allowed values in words, e.g. `a number in [0, 1]`.
    pub fn expected(&self) -> String {
        match *self {
            Kind::Text { non_empty: true } => "a non-empty string".into(),
            Kind::Text { non_empty: false } => "a string".into(),
            Kind::Ident => "lower-case letters, digits and `_`, starting with a letter".into(),
            Kind::TextList => "a list of strings".into(),
            Kind::Bool => "true or false".into(),
            Kind::Enum(v) => format!("one of {}", v.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ")),
            Kind::Range { min, max, min_exclusive } => {
                format!("a number in {}{}, {}]", if min_exclusive { "(" } else { "[" }, num(min), num(max))
            }
            Kind::Int { min, max } => format!("an integer in [{min}, {max}]"),
            Kind::Indicator { max } => format!("a number in [1, {}] or \"x\" (indifferent)", num(max)),
            Kind::PolyLine { x, y } => format!(
                "a list of ≥ 1 points [x, y] with x non-decreasing in [{}, {}] and y in [{}, {}]",
                num(x.0),
                num(x.1),
                num(y.0),
                num(y.1)
            ),
            Kind::Colour => "[r, g, b] with each in [0, 255]".into(),
        }
    }
}

/// The Markdown table of all fields (path, unit, allowed values, meaning), generated from
/// [`FIELDS`]; `species/README.md` contains it verbatim (checked by a test).
pub fn readme_field_table() -> String {
    let mut s = String::from("| Field | Unit | Allowed | Meaning |\n|---|---|---|---|\n");
    for f in FIELDS {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} |\n",
            f.path,
            f.unit,
            f.kind.expected().replace('|', "\\|"),
            f.doc.replace('|', "\\|")
        ));
    }
    s
}
