//! Issue 32: trees that look like their species. `sylva tree grow` sizes its EcoMod tree to the
//! species at its age (height from the species' height–age curve, crown base and crown width
//! from the stand-grown functions the species files cite), and the species' architectures
//! differ where a forester sees them differ: oak ≠ beech, Scots pine ≠ Norway spruce.
use sylva::species::{Species, SpeciesLibrary};
use sylva::structure::forest_form::{grow_formed_tree, tree_form, ArchitectureMeasures, CrownProportions, Habit, TreeForm};
use sylva::structure::species_tree::Model;

fn species(id: &str) -> Species {
    let lib = SpeciesLibrary::embedded().unwrap();
    lib.get(id).unwrap().clone()
}

/// Crown base of Döbbeler et al. (2001/2002) as written in the TreeGrOSS species file
/// `ForestSimulatorNWGermany6.xml` (github:rnuske/TreeGrOSSinR @ 659d30d, `data-raw/`),
/// element `Crownbase`, coefficients typed here from the file (not read from the species files).
fn treegross_crown_base(id: &str, h: f32, d: f32, h100: f32) -> f32 {
    let (a, b, c, e) = match id {
        "beech" => (0.25704, 0.11819, -0.002065, 0.13831),                 // 211 Buche
        "sessile_oak" | "pedunculate_oak" => (-0.5268, 0.2287, -0.00453, 0.4712), // 110 Eiche
        "norway_spruce" => (2.0417, -0.3335, 0.00906, -0.9004),          // 511 Fichte
        "scots_pine" => (1.2085, -0.2392, 0.00742, -0.7897),             // 711 Kiefer
        _ => unreachable!(),
    };
    h * (1.0 - (-(a + b * h / d + c * d + e * h100.ln()).abs()).exp())
}

/// Crown width of Döbbeler et al. / Nagel 1999 as in the same file, element `Crownwidth`.
fn treegross_crown_width(id: &str, d: f32) -> f32 {
    let (a, b, c, e) = match id {
        "beech" => (2.0837, 0.15, 5.7292, 1.3341),
        "sessile_oak" | "pedunculate_oak" => (2.6618, 0.1152, 8.3381, 1.4083),
        "norway_spruce" => (1.2644, 0.1072, 0.000001, 1.0),
        "scots_pine" => (1.2783, 0.11388, 8.70522, 1.33944),
        _ => unreachable!(),
    };
    (a + b * d) * (1.0 - (-(d / c).powf(e)).exp())
}

const FOUR: [&str; 4] = ["beech", "sessile_oak", "scots_pine", "norway_spruce"];

#[test]
fn the_form_at_an_age_follows_the_species_curves_and_the_cited_functions() {
    for id in FOUR {
        let sp = species(id);
        for age in [20.0f32, 80.0, 120.0] {
            let f = tree_form(&sp, age, Habit::Forest).unwrap();
            let h = sp.potential_height_m(age);
            assert!((f.height_m - h).abs() < 1e-4, "{id} {age}: height {} vs the curve's {h}", f.height_m);
            assert!((f.site_index_m - sp.potential_height_m(100.0)).abs() < 1e-4);
            // stand-grown DBH on the dense-stand curve h = 1.3 + k D^(1+c) / 100 (the
            // simulation's height bound, counted from breast height)
            let hd = sp.life.dense_hd.unwrap();
            assert!((1.3 + hd.k * f.dbh_cm.powf(1.0 + hd.c) / 100.0 - h).abs() < 0.01 * h, "{id} {age}: DBH {} off the dense-stand curve", f.dbh_cm);
            let cb = treegross_crown_base(id, h, f.dbh_cm, f.site_index_m);
            assert!((f.crown_base_m - cb).abs() < 0.01 * h, "{id} {age}: crown base {} vs TreeGrOSS {cb}", f.crown_base_m);
            let cw = treegross_crown_width(id, f.dbh_cm);
            assert!((2.0 * f.crown_radius_m - cw).abs() < 0.01 * cw, "{id} {age}: crown width {} vs TreeGrOSS {cw}", 2.0 * f.crown_radius_m);
        }
    }
    // the open-grown habit keeps the species' open-grown allometry
    let sp = species("beech");
    let f = tree_form(&sp, 80.0, Habit::Open).unwrap();
    assert!((f.crown_base_m - (1.0 - sp.life.allometry.crown_ratio) * f.height_m).abs() < 1e-3);
    assert!(tree_form(&sp, 0.0, Habit::Forest).is_err() && tree_form(&sp, f32::NAN, Habit::Forest).is_err());
}

/// The grown tree of `id` at 80 years, measured, with its form.
fn grown(id: &str, seed: u64) -> (ArchitectureMeasures, TreeForm) {
    let sp = species(id);
    let (g, f) = grow_formed_tree(&sp, Model::EcoMod, 80.0, &[], seed, Habit::Forest).unwrap();
    (ArchitectureMeasures::of(&g.skeleton, &g.leaves), f)
}

#[test]
fn grown_trees_have_their_species_dimensions_at_two_ages() {
    for id in FOUR {
        let sp = species(id);
        for age in [20.0f32, 80.0] {
            let (g, f) = grow_formed_tree(&sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
            let m = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
            let h = sp.potential_height_m(age);
            assert!((m.height_m - h).abs() < 0.02 * h, "{id} {age}: height {} vs the species curve's {h}", m.height_m);
            // the lowest branch leaves the stem at the crown base (within 5 % of the height)
            assert!((m.clear_bole_share() - f.clear_bole_share()).abs() < 0.05, "{id} {age}: clear bole {} vs {}", m.clear_bole_share(), f.clear_bole_share());
            // crown width / crown length within ±20 % of the cited functions'
            let (a, b) = (m.width_to_length(), f.width_to_length());
            assert!((a / b - 1.0).abs() < 0.2, "{id} {age}: crown width/length {a} vs {b}");
            assert!(g.skeleton.nodes.iter().all(|n| n.pos.z >= -1e-3));
        }
        let h20 = sp.potential_height_m(20.0);
        let h80 = sp.potential_height_m(80.0);
        assert!(h80 > 1.5 * h20, "{id}: {h20} m at 20 years, {h80} m at 80");
    }
}

/// Oak ≠ beech, Scots pine ≠ Norway spruce, in measures a forester takes (round 32's trial saw
/// the same tree twice). Measured at 80 years, seed 1 (values of round 33 in BENCHMARKS.md):
/// oak's crown is broader for its length than beech's (TreeGrOSS: 0.75 against 0.52) and its
/// limbs wider (its EcoMod α = 70° against the paper's 45° for beech); Scots pine's crown is
/// shorter and broader on a longer clear bole than Norway spruce's (TreeGrOSS at 80 years: 74 %
/// clear against 68 %, crown width/length 0.85 against 0.53).
#[test]
fn oak_differs_from_beech_and_scots_pine_from_norway_spruce() {
    let (beech, _) = grown("beech", 1);
    let (oak, _) = grown("sessile_oak", 1);
    let (pine, _) = grown("scots_pine", 1);
    let (spruce, _) = grown("norway_spruce", 1);
    assert!(oak.width_to_length() > 1.25 * beech.width_to_length(), "crown width/length: oak {} beech {}", oak.width_to_length(), beech.width_to_length());
    assert!(oak.branch_angle_deg > beech.branch_angle_deg + 10.0, "order-1 branch angle: oak {} beech {}", oak.branch_angle_deg, beech.branch_angle_deg);
    assert!(oak.clear_bole_share() > beech.clear_bole_share() + 0.05, "clear bole: oak {} beech {}", oak.clear_bole_share(), beech.clear_bole_share());
    assert!(pine.clear_bole_share() > spruce.clear_bole_share() + 0.03, "clear bole: pine {} spruce {}", pine.clear_bole_share(), spruce.clear_bole_share());
    assert!(pine.width_to_length() > 1.4 * spruce.width_to_length(), "crown width/length: pine {} spruce {}", pine.width_to_length(), spruce.width_to_length());
    // every one within ±0.05 clear bole and ±20 % crown width/length of the cited functions
    for (id, m) in [("beech", beech), ("sessile_oak", oak), ("scots_pine", pine), ("norway_spruce", spruce)] {
        let f = tree_form(&species(id), 80.0, Habit::Forest).unwrap();
        assert!((m.clear_bole_share() - f.clear_bole_share()).abs() < 0.05, "{id}: {m:?} {f:?}");
        assert!((m.width_to_length() / f.width_to_length() - 1.0).abs() < 0.2, "{id}: {m:?} {f:?}");
        assert!(m.branches >= 10, "{id}: {m:?}");
    }
}

/// Issue 32 (round 33, second pass): an 80-year-old stand-grown Scots pine has a short,
/// flat-topped crown widest high up, of few heavy limbs whose ends turn upward; a Norway spruce
/// a conical crown widest in its lower half with limbs that end level or hanging. The paper's EcoMod
/// pine (`004_*.txt`, asserted by `tests/structure_ecomod.rs`) is kept exactly for the young tree
/// (up to 30 years: `MatureForm::scots_pine`), and beech, oak and spruce keep their models at
/// every age. Measured (seed 1, BENCHMARKS.md round 33): pine limb ends 55°, widest at 0.85 of
/// the crown length, 24 limbs; spruce 117°, 0.05, 57 limbs. Round 46 gave the old pine its crown
/// profile (`[architecture.mature_form.crown_profile]`): its limb ends spread (about 95°) and
/// its flat top is measured instead (`half_width_depth`).
#[test]
fn an_old_scots_pine_has_a_flat_top_and_upturned_limbs_a_spruce_does_not() {
    use sylva::structure::forest_form::{grow_formed_tree_with, MatureForm};
    let (pine, _) = grown("scots_pine", 1);
    let (spruce, _) = grown("norway_spruce", 1);
    // round 46: the old pine's limbs end spreading (its crown profile, about 95° from the
    // vertical: round 33's upturned ends, 55°, drew with the fit a V-shaped broom), so the limb
    // ends no longer tell it from a spruce; the flat top does: the pine's crown reaches half its
    // width within its top 15 % (measured 0.11, seed 1), the spruce's cone lower (0.24)
    eprintln!("limb ends from the vertical: pine {} spruce {}", pine.limb_end_angle_deg, spruce.limb_end_angle_deg);
    let top = |id: &str| {
        let (g, _) = grow_formed_tree(&species(id), Model::EcoMod, 80.0, &[], 1, Habit::Forest).unwrap();
        half_width_depth(&ArchitectureMeasures::of(&g.skeleton, &g.leaves), &g)
    };
    let (tp, ts) = (top("scots_pine"), top("norway_spruce"));
    assert!(tp <= 0.15 && ts >= 0.2, "depth of half the crown's width below its top: pine {tp} spruce {ts}");
    // round 38 (r38c): Norway spruce's limbs below half the crown depth are as long as its
    // longest (Colin & Houllier 1991's branch-length profile), so its widest point lies anywhere
    // in the lower half of the crown (measured 0.35, seed 1), still far below the pine's
    assert!(pine.widest_at >= 0.5 && spruce.widest_at <= 0.4, "crown widest at: pine {} spruce {}", pine.widest_at, spruce.widest_at);
    assert!(pine.branches < spruce.branches * 2 / 3, "order-1 limbs: pine {} spruce {}", pine.branches, spruce.branches);
    // the paper's pine at 80 years (no mature form) still reads as a spruce by these measures
    let sp = species("scots_pine");
    let (g, _) = grow_formed_tree_with(&sp, Model::EcoMod, 80.0, &[], 1, Habit::Forest, None).unwrap();
    let paper = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
    assert!(paper.limb_end_angle_deg > 95.0 && paper.widest_at <= 0.25, "{paper:?}");
    // the young pine is the paper's model exactly
    let m = MatureForm::for_species(&sp).unwrap();
    let mut p = sp.architecture.ecomod.clone();
    m.apply(&mut p, 30.0);
    assert_eq!(p, sp.architecture.ecomod);
    let (a, _) = grow_formed_tree_with(&sp, Model::EcoMod, 20.0, &[], 1, Habit::Forest, None).unwrap();
    let (b, _) = grow_formed_tree_with(&sp, Model::EcoMod, 20.0, &[], 1, Habit::Forest, Some(m)).unwrap();
    assert_eq!(a.skeleton.nodes.len(), b.skeleton.nodes.len());
    assert!(a.skeleton.nodes.iter().zip(&b.skeleton.nodes).all(|(x, y)| x.pos == y.pos && x.radius == y.radius));
    // at 80 only the stem's k_s and α (order 0) and the limbs' α_m (order 1) change; every
    // other order keeps the paper's values
    let mut p = sp.architecture.ecomod.clone();
    m.apply(&mut p, 80.0);
    let e = sylva::structure::params::eval_polyline;
    let q = &sp.architecture.ecomod;
    assert!((e(&p.ks_g, 0.0) - 0.70).abs() < 1e-6 && (e(&p.alpha_g, 0.0) - 97.0).abs() < 1e-4 && (e(&p.alpha_m_g, 1.0) + 1.0).abs() < 1e-6);
    for g in 1..=20 {
        let g = g as f32;
        assert_eq!(e(&p.ks_g, g), e(&q.ks_g, g), "k_s at order {g}");
        assert_eq!(e(&p.alpha_g, g), e(&q.alpha_g, g), "α at order {g}");
        if g != 1.0 {
            assert_eq!(e(&p.alpha_m_g, g), e(&q.alpha_m_g, g), "α_m at order {g}");
        }
    }
    assert_eq!(e(&p.alpha_m_g, 0.0), e(&q.alpha_m_g, 0.0));
    // only Scots pine has a mature form
    for id in ["beech", "sessile_oak", "pedunculate_oak", "norway_spruce", "silver_fir", "european_larch"] {
        assert!(MatureForm::for_species(&species(id)).is_none(), "{id}");
    }
}

/// Round 34: 2–10-year-old stand-grown trees are saplings, not sticks with a disc or a tuft on
/// top: crown base at most a third of the height (was 76–90 % from 5 years on, the TreeGrOSS
/// crown-base function extrapolated below its data), crown width / height within ±25 % of the
/// sapling ESTIMATE `sapling_width_to_height` (0.45 broadleaves, 0.5 conifers; was 0.02 for a
/// 5-year beech, a 10 cm tuft on 1.7 m, and a 3-year spruce's crown 7.4 times as wide as long),
/// measured on the grown skeleton (leaf tips). 20 years and older: the stand functions alone
/// (the test above, unchanged).
#[test]
fn young_trees_have_the_sapling_form() {
    use sylva::structure::forest_form::{sapling_weight, sapling_width_to_height, SAPLING_CLEAR_BOLE};
    assert_eq!((sapling_weight(5.0), sapling_weight(10.0), sapling_weight(15.0), sapling_weight(20.0), sapling_weight(80.0)), (1.0, 1.0, 0.5, 0.0, 0.0));
    for id in FOUR {
        let sp = species(id);
        let want = sapling_width_to_height(&sp);
        for age in [3.0f32, 5.0, 7.0, 10.0] {
            let f = tree_form(&sp, age, Habit::Forest).unwrap();
            assert!((f.crown_base_m - SAPLING_CLEAR_BOLE * f.height_m).abs() < 1e-4 && (2.0 * f.crown_radius_m / f.height_m - want).abs() < 1e-4, "{id} {age}: {f:?}");
            let (g, _) = grow_formed_tree(&sp, Model::EcoMod, age, &[], 1, Habit::Forest).unwrap();
            let m = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
            let wh = 2.0 * m.crown_radius_m / m.height_m;
            eprintln!("{id} {age}: height {:.2} m, clear bole {:.2}, crown width/height {wh:.2} (want {want})", m.height_m, m.clear_bole_share());
            assert!((m.height_m - f.height_m).abs() < 0.05 * f.height_m, "{id} {age}: height {} vs {}", m.height_m, f.height_m);
            assert!(m.clear_bole_share() < 0.34, "{id} {age}: clear bole {}", m.clear_bole_share());
            assert!((wh / want - 1.0).abs() < 0.25, "{id} {age}: crown width/height {wh} vs {want}");
        }
    }
}

/// Relative depth (0 top … 1 crown base) below the crown's top where the crown first reaches
/// half its largest radius (leaves' horizontal distance from the stem base's vertical, the crown
/// length from the lowest limb to the top cut into 40 slices): small for a flat or domed top,
/// about ½ for a cone widest at its base. NaN without leaves in the crown.
fn half_width_depth(m: &ArchitectureMeasures, g: &sylva::structure::species_tree::GrownTree) -> f32 {
    let root = g.skeleton.nodes[0].pos;
    let len = m.height_m - m.crown_base_m;
    let mut w = [0.0f32; 40];
    for l in &g.leaves.leaves {
        let d = (m.height_m - (l.pos.z - root.z)) / len;
        if (0.0..=1.0).contains(&d) {
            let i = ((d * 40.0) as usize).min(39);
            w[i] = w[i].max((l.pos.truncate() - root.truncate()).length());
        }
    }
    let max = w.iter().copied().fold(0.0f32, f32::max);
    w.iter().position(|&x| x >= 0.5 * max).map_or(f32::NAN, |i| (i as f32 + 0.5) / 40.0)
}

/// Issue 32 (round 46, round 45's trial defect 1): a 100-year-old stand-grown Scots pine is the
/// flat, umbrella-like crown of an old pine on its long clear bole, not a V-shaped broom. Its
/// limbs leave the stem spreading (mean insertion 40–75° from the vertical: ascending in the
/// upper crown, near level below; round 45's mature form drew 16°, the limbs squeezed towards
/// the stem by the fit to the stand crown's width), end spreading (mean end segment ≥ 75° from
/// the vertical; round 45: 55°, a V), and the crown is wide right under its top (it reaches half
/// its largest radius within the top 15 % of its length; a cone widest at its base reaches it
/// half-way down). The limits are ESTIMATEs from the habit (species/scots_pine.toml,
/// `[architecture.mature_form.crown_profile]`); round 45's form (the mature form without its
/// crown profile) is grown here too and fails the insertion and end angles. Measured (seed 1):
/// 24 limbs at 56°, ends 98°, widest at 0.65 of the crown length, half width at depth 0.11.
#[test]
fn a_100_year_scots_pine_has_an_umbrella_crown_not_a_broom() {
    use sylva::structure::forest_form::{grow_formed_tree_with, MatureForm};
    let sp = species("scots_pine");
    let m = MatureForm::for_species(&sp).unwrap();
    assert!(m.crown_profile.is_some(), "the shipped pine's mature form has its crown profile");
    let measure = |mf: MatureForm, seed: u64| {
        let (g, _) = grow_formed_tree_with(&sp, Model::EcoMod, 100.0, &[], seed, Habit::Forest, Some(mf)).unwrap();
        let a = ArchitectureMeasures::of(&g.skeleton, &g.leaves);
        let hw = half_width_depth(&a, &g);
        (a, hw)
    };
    // (EcoMod's pine has no undirected wind, w_s = 0: the seed does not change the tree)
    for seed in [1u64] {
        let (a, hw) = measure(m, seed);
        eprintln!("seed {seed}: limbs {} at {:.0}° from the vertical, ends {:.0}°, widest at {:.2}, half width at depth {hw:.3}", a.branches, a.branch_angle_deg, a.limb_end_angle_deg, a.widest_at);
        assert!((40.0..=75.0).contains(&a.branch_angle_deg), "seed {seed}: limbs leave the stem at {}° from the vertical", a.branch_angle_deg);
        assert!(a.limb_end_angle_deg >= 75.0, "seed {seed}: limb ends at {}° from the vertical", a.limb_end_angle_deg);
        assert!(hw <= 0.15, "seed {seed}: the crown reaches half its width {hw} of its length below the top");
        assert!(a.widest_at >= 0.5, "seed {seed}: crown widest at {} of its length", a.widest_at);
    }
    // round 45's form (no crown profile): the broom, failing the angles above (its V is also
    // widest at the top, 0.013: the flatness alone does not tell it; measured 16° and 55°)
    let (old, hw) = measure(MatureForm { crown_profile: None, ..m }, 1);
    eprintln!("round 45's form: limbs at {:.0}°, ends {:.0}°, half width at depth {hw:.3}", old.branch_angle_deg, old.limb_end_angle_deg);
    assert!(old.branch_angle_deg < 40.0 && old.limb_end_angle_deg < 75.0, "{old:?}");
}
