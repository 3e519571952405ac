//! Species library: shipped files, loader, validation errors, suitability, README/schema sync,
//! published parameter values, CLI.

use std::path::{Path, PathBuf};

use sylva::species::{self, schema, Indicator, LeafDistribution, Problem, Species, SpeciesLibrary, TOLERANCE_EDGE_SUITABILITY};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}
fn species_dir() -> PathBuf {
    root().join("species")
}
fn beech_text() -> String {
    std::fs::read_to_string(species_dir().join("beech.toml")).unwrap()
}
fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
/// The problems of a single bad file (beech with `edit` applied) in a fresh folder.
fn problems_of(edit: impl Fn(&str) -> String) -> (tempfile::TempDir, Vec<Problem>) {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "bad.toml", &edit(&beech_text()));
    let p = species::check_dir(d.path());
    (d, p)
}
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.starts_with(needle)).expect(needle) + 1
}

#[test]
fn shipped_files_validate() {
    let problems = species::check_dir(&species_dir());
    assert!(problems.is_empty(), "{}", problems.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("\n"));
    let lib = SpeciesLibrary::load_dir(&species_dir()).unwrap();
    assert!(lib.len() >= 15, "{} species", lib.len());
    for id in [
        "beech",
        "norway_spruce",
        "silver_fir",
        "scots_pine",
        "european_larch",
        "pedunculate_oak",
        "sessile_oak",
        "sycamore",
        "norway_maple",
        "ash",
        "silver_birch",
        "black_alder",
        "hornbeam",
        "small_leaved_lime",
        "rowan",
        "aspen",
    ] {
        assert!(lib.get(id).is_some(), "missing {id}");
    }
    // Sorted by id, unique.
    assert!(lib.species.windows(2).all(|w| w[0].id < w[1].id));
    // Lookup by scientific and common name.
    assert_eq!(lib.get("Fagus sylvatica").unwrap().id, "beech");
    assert_eq!(lib.get("scots pine").unwrap().id, "scots_pine");
    // One resolver: case, spaces, `_` and `-` do not matter (issue 32: `fagus_sylvatica` was refused).
    for name in ["fagus_sylvatica", "FAGUS SYLVATICA", " Fagus-sylvatica ", "fagus  sylvatica", "European_Beech", "BEECH"] {
        assert_eq!(lib.get(name).map(|s| s.id.as_str()), Some("beech"), "{name:?}");
    }
    assert_eq!(lib.get("Pinus sylvestris").unwrap().id, "scots_pine");
    assert_eq!(lib.get("picea_abies").unwrap().id, "norway_spruce");
    assert_eq!(lib.get("norway spruce").unwrap().id, "norway_spruce");
    assert_eq!(lib.get("quercus petraea").unwrap().id, "sessile_oak");
    assert!(lib.get("fagus").is_none());
    assert!(lib.get("").is_none());
    assert!(lib.get(" _ ").is_none());
}

#[test]
fn embedded_equals_folder() {
    let mut names: Vec<String> = species::species_files(&species_dir())
        .unwrap()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut embedded: Vec<String> = species::EMBEDDED_FILES.iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(
        names, embedded,
        "EMBEDDED_FILES in src/species/library.rs must list exactly the files of species/"
    );
    assert_eq!(SpeciesLibrary::embedded().unwrap(), SpeciesLibrary::load_dir(&species_dir()).unwrap());
}

#[test]
fn round_trip_is_lossless() {
    for s in SpeciesLibrary::embedded().unwrap().species {
        let text = s.to_toml_string().unwrap();
        let back = Species::from_toml_str(&text, "roundtrip.toml").unwrap();
        assert_eq!(back, s, "{}", s.id);
        assert_eq!(back.to_toml_string().unwrap(), text, "{}: second write differs", s.id);
    }
}

#[test]
fn suitability_one_at_optimum_and_documented_value_at_tolerance_edge() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let beech = lib.get("beech").unwrap();
    // beech: L 3, T 5, K 2, F 5, R x, N x. An indifferent factor imposes no limit (round 46).
    let opt = [3.0, 5.0, 2.0, 5.0, 1.0, 9.0];
    assert!((beech.suitability(&opt) - 1.0).abs() < 1e-6);
    assert_eq!(beech.suitability_factors(&opt), [1.0; 6]);
    // Each numeric factor at optimum + tolerance gives exp(-1/2); indifferent ones stay 1.
    assert!((TOLERANCE_EDGE_SUITABILITY - (-0.5f32).exp()).abs() < 1e-7);
    let n = &beech.niche;
    for (i, f) in [&n.l, &n.t, &n.k, &n.f, &n.r, &n.n].into_iter().enumerate() {
        let mut x = opt;
        match f.value {
            Indicator::Value(v) => {
                for sign in [-1.0, 1.0] {
                    x[i] = v + sign * f.tolerance;
                    let s = beech.suitability_factors(&x)[i];
                    assert!((s - TOLERANCE_EDGE_SUITABILITY).abs() < 1e-5, "factor {i}: {s}");
                    // the site suitability: L left out (the light model's), the others by the
                    // minimum (on F's dry side times the drought limit)
                    let site = beech.suitability(&x);
                    if i == 0 {
                        assert_eq!(site, beech.suitability(&opt));
                    } else if i == 3 && sign < 0.0 {
                        let want = (1.0 - (f.tolerance / 10.0) / beech.life.drought_tolerance.unwrap()).max(0.0).sqrt();
                        assert!((site - want * TOLERANCE_EDGE_SUITABILITY).abs() < 1e-5, "dry F: {site} {want}");
                    } else {
                        assert!((site - TOLERANCE_EDGE_SUITABILITY).abs() < 1e-5, "factor {i}: {site}");
                    }
                }
            }
            Indicator::Indifferent(_) => {
                for v in [1.0, 5.0, 9.0] {
                    x[i] = v;
                    assert_eq!(beech.suitability_factors(&x)[i], 1.0, "x at {v}");
                    assert_eq!(beech.suitability(&x), 1.0, "x at {v}");
                }
            }
        }
    }
    // Liebig minimum: one factor 3 tolerances away excludes the species (exp(-4.5) = 0.011).
    let mut wet = opt;
    wet[3] = 5.0 + 3.0 * n.f.tolerance;
    assert!((beech.suitability(&wet) - (-4.5f32).exp()).abs() < 1e-4);
    // Symmetric and monotone away from the optimum (the factor's own response).
    let mut prev = 1.0;
    for k in 1..20 {
        let mut x = opt;
        x[1] = 5.0 + k as f32 * 0.2;
        let s = beech.suitability_factors(&x)[1];
        assert!(s < prev);
        x[1] = 5.0 - k as f32 * 0.2;
        assert!((beech.suitability_factors(&x)[1] - s).abs() < 1e-6);
        prev = s;
    }
    // Black alder (F 9) is clearly better than beech on wet ground and worse on dry-moist.
    let alder = lib.get("black_alder").unwrap();
    let wet_site = [5.0, 5.0, 3.0, 9.0, 6.0, 6.0];
    assert!(alder.suitability(&wet_site) > 0.85);
    assert!(beech.suitability(&wet_site) < 0.2);
    // on a fresh site (F 5) alder has its Gaussian F factor alone (the drought limit counts
    // below F 5, round 46), on a drier one (F 4: drought index 0.1 beyond fresh, more than its
    // ForClim tolerance 0.08) none
    let fresh = [5.0, 5.0, 3.0, 5.0, 6.0, 6.0];
    assert!((alder.suitability(&fresh) - (-0.5f32 * 1.6 * 1.6).exp()).abs() < 1e-5 && beech.suitability(&fresh) > 0.9, "{}", alder.suitability(&fresh));
    let drier = [5.0, 5.0, 3.0, 4.0, 6.0, 6.0];
    assert!(alder.suitability(&drier) == 0.0 && beech.suitability(&drier) > 0.5);
}

#[test]
fn beech_growth_matches_nwfva_yield_class_one() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let beech = lib.get("beech").unwrap();
    assert!((beech.potential_height_m(50.0) - 19.5).abs() < 0.3);
    assert!((beech.potential_height_m(100.0) - 32.5).abs() < 0.3);
    // the curve is fitted to the table's top heights at every age 35–145 with its own
    // asymptote (issue 35 round 39: RMS 0.16 m); its early shape puts a 3-year beech at
    // nursery-stock size (0.3–0.5 m), where the two-point fit grew linearly from 0 (0.91 m)
    let h3 = beech.potential_height_m(3.0);
    assert!((0.3..=0.5).contains(&h3), "H(3) = {h3} m");
    let mut rdr = csv::Reader::from_path(root().join("tests/data/stands/nwfva2021_yieldtable_et_bu.csv")).unwrap();
    let mut n = 0;
    for rec in rdr.records() {
        let r = rec.unwrap();
        if &r[0] != "1" {
            continue;
        }
        let age: f32 = r[1].parse().unwrap();
        let h100: f32 = r[4].parse().unwrap();
        let h = beech.potential_height_m(age);
        assert!((h - h100).abs() < 0.5, "age {age}: model {h} vs table {h100}");
        n += 1;
    }
    assert!(n >= 20);
    // Pioneers grow faster early than beech; all reach their maximum only asymptotically.
    let birch = lib.get("silver_birch").unwrap();
    assert!(birch.potential_height_m(10.0) > 1.5 * beech.potential_height_m(10.0));
    assert!(birch.potential_height_m(20.0) > beech.potential_height_m(20.0));
    for s in &lib.species {
        assert!(s.potential_height_m(s.life.max_age_yr) <= s.life.max_height_m);
        // Allometry inverse.
        let h = s.height_from_dbh_m(30.0);
        assert!((s.dbh_from_height_cm(h) - 30.0).abs() < 0.05, "{}", s.id);
    }
}

#[test]
fn light_demand_orders_pioneers_and_shade_tolerant_species() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let g = |id: &str| lib.get(id).unwrap().life.germination_min_light;
    for pioneer in ["silver_birch", "aspen", "european_larch", "scots_pine"] {
        assert!((0.4..=0.6).contains(&g(pioneer)), "{pioneer}");
    }
    for tolerant in ["beech", "silver_fir"] {
        assert!((0.02..=0.05).contains(&g(tolerant)), "{tolerant}");
        assert_eq!(lib.get(tolerant).unwrap().life.shade_tolerance, 5.0);
    }
    assert_eq!(lib.get("silver_birch").unwrap().life.shade_tolerance, 1.0);
}

#[test]
fn beech_and_pine_carry_ecomod_published_values_exactly() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let b = &lib.get("beech").unwrap().architecture.ecomod;
    assert_eq!(b.strands, 1000);
    assert_eq!(
        (b.trunk_length_m, b.k_d, b.phyllotaxis_deg, b.k_c, b.leaf_size_m, b.leaf_density),
        (5.0, 0.01, 85.0, 0.3, 0.2862, 5.0)
    );
    assert_eq!(b.leaf_distribution, LeafDistribution::Spiral);
    assert_eq!((b.wind_directed, b.k_f), (1.5, 1.0));
    assert_eq!(b.ks_g, vec![[0.0, 0.75], [15.0, 0.9]]);
    assert_eq!(b.ks_w, vec![[0.0, 1.0], [50.0, 1.0]]);
    assert_eq!(b.alpha_g, vec![[0.0, 45.0], [15.0, 45.0]]);
    assert_eq!(b.min_len_g, vec![[0.0, 1.0], [7.5, 0.45], [15.0, 1.0]]);
    assert_eq!(b.max_len_g, vec![[0.0, 1.0], [15.0, 1.0]]);
    assert_eq!(b.kl_g, vec![[0.0, 1.0], [15.0, 1.0]]);
    assert_eq!(b.alpha_m_g, vec![[0.0, 0.0], [15.0, 0.0]]);

    let p = &lib.get("scots_pine").unwrap().architecture.ecomod;
    assert_eq!(p.strands, 6000);
    assert_eq!(
        (p.trunk_length_m, p.k_d, p.phyllotaxis_deg, p.k_c, p.leaf_size_m, p.leaf_density),
        (5.47, 0.005, 85.0, 0.98, 0.1815, 30.0)
    );
    assert_eq!(p.leaf_distribution, LeafDistribution::Stacked);
    assert_eq!(p.ks_g, vec![[0.0, 0.955], [0.7749, 0.9615], [1.827, 0.8288], [4.207, 0.8269], [15.0, 0.8294]]);
    assert_eq!(p.ks_w, vec![[0.0, 1.0], [42.89, 1.005], [42.89, 0.654], [50.0, 0.6256]]);
    assert_eq!(p.alpha_g, vec![[0.0, 128.8], [1.164, 17.91], [3.621, 45.21], [15.0, 35.83]]);
    assert_eq!(p.min_len_g, vec![[0.0, 0.7109], [1.293, 0.8531], [15.0, 1.0]]);
    assert_eq!(p.max_len_g, vec![[0.0, 0.9953], [15.0, 1.0]]);
    assert_eq!(p.kl_g, vec![[0.0, 0.7109], [0.7749, 0.5385], [2.522, 1.327], [15.0, 1.0]]);
    assert_eq!(p.kl_w, vec![[0.0, 1.014], [38.58, 1.014], [45.26, 0.5877], [50.0, 0.01896]]);
    assert_eq!(
        p.alpha_m_g,
        vec![[0.0, 0.0], [0.3875, 34.62], [1.034, -4.265], [1.55, -4.154], [2.974, -5.972], [15.0, -0.8532]]
    );

    // Yi et al. Table 1 rows and Plastic Trees defaults for every species.
    let rows: [[f32; 7]; 7] = [
        [0.46, 0.5, 2.1, 1.5, 0.5, 45.0, 0.2],
        [0.54, 0.35, 1.9, 1.0, 0.5, 38.0, 0.35],
        [0.52, 0.5, 2.0, 1.5, 0.5, 45.0, 0.35],
        [0.52, 0.5, 2.0, 1.5, 0.5, 45.0, 0.35],
        [0.46, 0.5, 2.1, 1.0, 0.5, 45.0, 0.25],
        [0.54, 0.35, 2.2, 1.5, 0.2, 30.0, 0.25],
        [0.52, 0.35, 2.0, 1.0, 0.0, 38.0, 0.35],
    ];
    for s in &lib.species {
        let l = &s.architecture.light_guided;
        let row = [l.lambda, l.k, l.b, l.mu, l.gamma, l.theta_deg, l.r_s];
        assert!(rows.contains(&row), "{}: light-guided parameters are not a row of Yi et al. Table 1", s.id);
        assert_eq!(s.architecture.plastic.pruning_c_psi, 0.8);
        assert_eq!(s.architecture.plastic.translucency_gamma_c0, 0.5);
        assert_eq!(s.architecture.laplacian.width_rate, 1.5);
    }
}

#[test]
fn readme_documents_every_field_of_the_schema() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let mut beech = lib.get("beech").unwrap().clone();
    // beech has every optional table but PROGNAUS's competition terms (Norway spruce's only)
    beech.life.bai_competition = lib.get("norway_spruce").unwrap().life.bai_competition;
    assert!(beech.life.bai_competition.is_some());
    // nor BWINPro's diameter growth (issue 35 round 37: no shipped file has it; beech's values)
    beech.life.bai_bwinpro = Some(sylva::species::BaiBwinpro { a0: 2.6518, csa: 1.0414, age: -0.6322, c66: -0.555, bias0: -22.77, bias1: 1.417, bias2: 0.03803, bias3: -0.002403, bias4: 0.00003191, bias5: -0.0000001202, youth_hd: 1.40, period_sigma: Some(0.15) });
    // nor the open-grown H/D curve (issue 35 round 43: no shipped file has it; iLand's fasy HDlow)
    beech.life.open_hd = Some(sylva::species::DenseHd { k: 100.877, c: -0.2427 });
    // nor the mature form (Scots pine's only)
    beech.architecture.mature_form = lib.get("scots_pine").unwrap().architecture.mature_form;
    assert!(beech.architecture.mature_form.is_some());
    // nor the whorled stem (Norway spruce's only)
    beech.architecture.ecomod.whorls = lib.get("norway_spruce").unwrap().architecture.ecomod.whorls;
    assert!(beech.architecture.ecomod.whorls.is_some());
    // nor the limbs' profile (Norway spruce's only, round 38)
    beech.architecture.ecomod.limbs = lib.get("norway_spruce").unwrap().architecture.ecomod.limbs;
    assert!(beech.architecture.ecomod.limbs.is_some());
    // nor hanging twigs (silver birch's only, round 46)
    if let Some(cp) = beech.architecture.ecomod.crown_profile.as_mut() {
        cp.twig_droop_deg = lib.get("silver_birch").unwrap().architecture.ecomod.crown_profile.and_then(|b| b.twig_droop_deg);
        assert!(cp.twig_droop_deg.is_some());
    }
    let mut leaves: Vec<String> = species::leaf_fields(&beech).unwrap().into_iter().map(|(p, _)| p).collect();
    let mut fields: Vec<String> = schema::FIELDS.iter().map(|f| f.path.to_string()).collect();
    leaves.sort();
    fields.sort();
    assert_eq!(leaves, fields, "schema::FIELDS must list exactly the leaf fields of a species");

    let readme_path = species_dir().join("README.md");
    let readme = std::fs::read_to_string(&readme_path).unwrap();
    let (head, rest) = readme.split_once("<!-- fields:begin -->\n").expect("README fields:begin marker");
    let (_, tail) = rest.split_once("<!-- fields:end -->").expect("README fields:end marker");
    let table = schema::readme_field_table();
    let expected = format!("{head}<!-- fields:begin -->\n{table}<!-- fields:end -->{tail}");
    if std::env::var_os("SYLVA_BLESS").is_some() {
        std::fs::write(&readme_path, &expected).unwrap();
        return;
    }
    assert_eq!(
        readme, expected,
        "species/README.md field table is out of date: run SYLVA_BLESS=1 cargo test --test species"
    );
    for f in schema::FIELDS {
        assert!(readme.contains(&format!("`{}`", f.path)), "{} not documented", f.path);
    }
}

// ---------- bad inputs: each kind gives a clear error with file, line, field, value, range ----------

#[test]
fn out_of_range_value_names_file_line_field_value_and_range() {
    let (_d, p) = problems_of(|t| t.replace("k_c = 0.3\n", "k_c = 1.7\n"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].file.ends_with("bad.toml"));
    assert_eq!(p[0].line, Some(line_of(&beech_text(), "k_c = ")));
    assert_eq!(p[0].field, "architecture.ecomod.k_c");
    assert_eq!(p[0].value, "1.7");
    assert_eq!(p[0].expected, "a number in [0, 1]");
    let msg = p[0].to_string();
    assert!(
        msg.contains("bad.toml:") && msg.contains("`architecture.ecomod.k_c` = 1.7: expected a number in [0, 1]"),
        "{msg}"
    );
    // Same through from_toml_str (an Error::Invalid).
    let err = Species::from_toml_str(&beech_text().replace("k_c = 0.3\n", "k_c = 1.7\n"), "x.toml").unwrap_err();
    assert!(matches!(err, sylva::Error::Invalid { .. }), "{err}");
    assert!(err.to_string().contains("k_c"), "{err}");
}

/// `life.closed_hd` (issue 35 round 41) and `life.closed_hd_scope` (round 44): optional
/// (without them 60 m/m from 7 cm, TreeGrOSS's youth scope), the shipped beech has 140 up to its
/// dense-stand curve (`dense_curve`), read where given, and a value outside 40–250 m/m or a scope
/// other than `youth` / `dense_curve` is refused naming the file, line, field and allowed values.
#[test]
fn closed_stand_slenderness_is_optional_read_and_range_checked() {
    use sylva::species::ClosedHdScope;
    let life = SpeciesLibrary::embedded().unwrap().get("beech").unwrap().life.clone();
    assert_eq!((life.closed_hd, life.closed_hd_scope), (Some(140.0), Some(ClosedHdScope::DenseCurve)));
    let (hd, scope) = ("closed_hd = 140.0\n", "closed_hd_scope = \"dense_curve\"\n");
    assert!(beech_text().contains(hd) && beech_text().contains(scope));
    let without = Species::from_toml_str(&beech_text().replace(hd, "").replace(scope, ""), "x.toml").unwrap();
    assert_eq!((without.life.closed_hd, without.life.closed_hd_scope), (None, None));
    let with = |v: &str| beech_text().replace(hd, &format!("closed_hd = {v}\n"));
    assert_eq!(Species::from_toml_str(&with("120.0"), "x.toml").unwrap().life.closed_hd, Some(120.0));
    let youth = beech_text().replace(scope, "closed_hd_scope = \"youth\"\n");
    assert_eq!(Species::from_toml_str(&youth, "x.toml").unwrap().life.closed_hd_scope, Some(ClosedHdScope::Youth));
    let (_d, p) = problems_of(|t| t.replace(hd, "closed_hd = 300.0\n"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].file.ends_with("bad.toml"));
    assert_eq!(p[0].line, Some(line_of(&with("300.0"), "closed_hd = ")));
    assert_eq!((p[0].field.as_str(), p[0].value.as_str(), p[0].expected.as_str()), ("life.closed_hd", "300", "a number in [40, 250]"));
    let bad_scope = |t: &str| t.replace(scope, "closed_hd_scope = \"always\"\n");
    let (_d, p) = problems_of(bad_scope);
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].line, Some(line_of(&bad_scope(&beech_text()), "closed_hd_scope = ")));
    assert_eq!((p[0].field.as_str(), p[0].expected.as_str()), ("life.closed_hd_scope", "one of \"youth\", \"dense_curve\""));
}

/// `life.closed_hd_mixed` (issue 35 round 45, beech's crown plasticity in mixture): optional,
/// the shipped beech gives way from 140 to 60 m/m among other species, read where given, and a
/// value outside 40–250 m/m is refused naming the file, line, field and range.
#[test]
fn mixed_slenderness_is_optional_read_and_range_checked() {
    let life = SpeciesLibrary::embedded().unwrap().get("beech").unwrap().life.clone();
    assert_eq!(life.closed_hd_mixed, Some(60.0));
    let line = "closed_hd_mixed = 60.0\n";
    assert!(beech_text().contains(line));
    assert_eq!(Species::from_toml_str(&beech_text().replace(line, ""), "x.toml").unwrap().life.closed_hd_mixed, None);
    let with = |v: &str| beech_text().replace(line, &format!("closed_hd_mixed = {v}\n"));
    assert_eq!(Species::from_toml_str(&with("80.0"), "x.toml").unwrap().life.closed_hd_mixed, Some(80.0));
    let (_d, p) = problems_of(|t| t.replace(line, "closed_hd_mixed = 20.0\n"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].line, Some(line_of(&with("20.0"), "closed_hd_mixed = ")));
    assert_eq!((p[0].field.as_str(), p[0].value.as_str(), p[0].expected.as_str()), ("life.closed_hd_mixed", "20", "a number in [40, 250]"));
}

#[test]
fn ellenberg_value_out_of_scale_and_bad_indicator_string() {
    let (_d, p) = problems_of(|t| {
        t.replace("t = { value = 5,", "t = { value = 10,")
            .replace("f = { value = 5,", "f = { value = 12,")
    });
    assert_eq!(p.len(), 1, "{p:?}"); // F may reach 12, T may not
    assert_eq!(p[0].field, "niche.t.value");
    assert!(p[0].expected.contains("[1, 9]"));
    let (_d, p) = problems_of(|t| t.replace("r = { value = \"x\"", "r = { value = \"y\""));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "niche.r.value");
    assert_eq!(p[0].value, "\"y\"");
    assert!(p[0].expected.contains("\"x\""));
}

#[test]
fn wrong_type_is_reported() {
    let (_d, p) = problems_of(|t| t.replace("max_age_yr = 600.0", "max_age_yr = \"old\""));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "life.max_age_yr");
    assert_eq!(p[0].value, "\"old\"");
    assert_eq!(p[0].line, Some(line_of(&beech_text(), "max_age_yr")));
    assert!(p[0].expected.contains("a number"));
}

#[test]
fn unknown_field_is_reported() {
    let (_d, p) = problems_of(|t| t.replace("k_c = 0.3\n", "k_c = 0.3\nk_cc = 0.5\n"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "architecture.ecomod.k_cc");
    assert_eq!(p[0].line, Some(line_of(&beech_text(), "k_c = ") + 1));
    assert!(p[0].expected.contains("unknown field") && p[0].expected.contains("k_c"), "{}", p[0].expected);
}

#[test]
fn missing_field_is_reported() {
    let (_d, p) = problems_of(|t| {
        t.replace("growth = { k = 0.0198, p = 1.652, h_max_m = 41.75 }", "growth = { k = 0.0198, h_max_m = 41.75 }")
            .replace("max_dbh_cm = 150.0", "")
    });
    assert_eq!(p.len(), 2, "{p:?}");
    let fields: Vec<&str> = p.iter().map(|p| p.field.as_str()).collect();
    assert!(fields.contains(&"life.growth.p") && fields.contains(&"life.max_dbh_cm"), "{fields:?}");
    assert!(p.iter().all(|p| p.expected.starts_with("missing field")));
    assert!(p.iter().all(|p| p.line.is_some()));
    // `sources` is optional.
    let text = beech_text();
    let start = text.find("sources = [").unwrap();
    let end = start + text[start..].find("]\n").unwrap() + 2;
    let s = Species::from_toml_str(&format!("{}{}", &text[..start], &text[end..]), "nosources.toml").unwrap();
    assert!(s.identity.sources.is_empty());
}

#[test]
fn cross_field_rules() {
    let (_d, p) = problems_of(|t| {
        t.replace("maturity_age_yr = 55.0", "maturity_age_yr = 700.0")
            .replace("max_m = 200.0", "max_m = 10.0")
            .replace("h_max_m = 41.75", "h_max_m = 100.0")
    });
    let fields: Vec<&str> = p.iter().map(|p| p.field.as_str()).collect();
    assert_eq!(fields.len(), 3, "{p:?}");
    assert!(fields.contains(&"life.maturity_age_yr") && fields.contains(&"life.dispersal.max_m") && fields.contains(&"life.growth.h_max_m"));
    let h = p.iter().find(|p| p.field == "life.growth.h_max_m").unwrap();
    assert!(h.expected.contains("at most life.max_height_m = 48"), "{h:?}");
}

#[test]
fn syntax_error_and_non_utf8_are_reported() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "syntax.toml", "id = \"a\"\n[identity\n");
    std::fs::write(d.path().join("latin1.toml"), b"id = \"buche\"\n# H\xf6he\n").unwrap();
    let p = species::check_dir(d.path());
    assert_eq!(p.len(), 2, "{p:?}");
    let utf = p.iter().find(|p| p.file.ends_with("latin1.toml")).unwrap();
    assert_eq!(utf.line, Some(2));
    assert!(utf.expected.contains("UTF-8"));
    let syn = p.iter().find(|p| p.file.ends_with("syntax.toml")).unwrap();
    assert_eq!(syn.line, Some(2));
    assert!(syn.expected.contains("TOML syntax error"));
}

#[test]
fn duplicate_species_names_both_files() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "beech.toml", &beech_text());
    write(d.path(), "beech_copy.toml", &beech_text());
    let p = species::check_dir(d.path());
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "id");
    assert!(
        p[0].expected.contains("beech.toml") && p[0].expected.contains("beech_copy.toml"),
        "{}",
        p[0].expected
    );
    let err = SpeciesLibrary::load_dir(d.path()).unwrap_err().to_string();
    assert!(err.contains("unique id"), "{err}");
    // still reported when the copy also has a type error (which stops its parsing)
    let bad = beech_text().replacen("max_height_m = 48.0", "max_height_m = \"tall\"", 1);
    assert_ne!(bad, beech_text());
    write(d.path(), "beech_copy.toml", &bad);
    let p = species::check_dir(d.path());
    assert!(p.iter().any(|q| q.field == "id" && q.expected.contains("beech_copy.toml")), "{p:?}");
    assert!(p.iter().any(|q| q.field.ends_with("max_height_m")), "{p:?}");
}

#[test]
fn check_dir_reports_every_problem_of_every_file_at_once() {
    let d = tempfile::tempdir().unwrap();
    let t = beech_text();
    write(
        d.path(),
        "a.toml",
        &t.replace("id = \"beech\"", "id = \"a\"")
            .replace("k_c = 0.3\n", "k_c = 1.7\n")
            .replace("strands = 1000", "strands = 0"),
    );
    write(
        d.path(),
        "b.toml",
        &t.replace("id = \"beech\"", "id = \"b\"")
            .replace("leaf_type = \"broadleaf\"", "leaf_type = \"palm\"")
            .replace("bark = [150, 150, 140]", "bark = [300, 150, 140]"),
    );
    write(d.path(), "ok.toml", &t);
    let p = species::check_dir(d.path());
    assert_eq!(p.len(), 4, "{p:?}");
    assert_eq!(p.iter().filter(|p| p.file.ends_with("a.toml")).count(), 2);
    assert_eq!(p.iter().filter(|p| p.file.ends_with("b.toml")).count(), 2);
    // Problems of one file come in line order.
    let a: Vec<usize> = p.iter().filter(|p| p.file.ends_with("a.toml")).map(|p| p.line.unwrap()).collect();
    assert!(a[0] < a[1]);
    // load_dir gathers all of them into one error.
    let err = SpeciesLibrary::load_dir(d.path()).unwrap_err().to_string();
    assert!(err.contains("4 problems"), "{err}");
}

#[test]
fn replace_id_keeps_comments() {
    let t = beech_text();
    let n = species::replace_id(&t, "my_beech", Path::new("x.toml")).unwrap();
    assert!(n.contains("id = \"my_beech\""));
    assert_eq!(
        n.lines().filter(|l| l.starts_with('#')).count(),
        t.lines().filter(|l| l.starts_with('#')).count()
    );
    assert_eq!(Species::from_toml_str(&n, "x.toml").unwrap().id, "my_beech");
}

#[test]
fn cli_check_new_list_show() {
    let exe = env!("CARGO_BIN_EXE_sylva");
    let run = |args: &[&str]| std::process::Command::new(exe).args(args).current_dir(root()).output().unwrap();
    let o = run(&["species", "check"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&["species", "list"]);
    assert!(o.status.success());
    let list = String::from_utf8_lossy(&o.stdout);
    assert!(list.contains("Fagus sylvatica"));
    // the two heights side by side and explained (trial 41, defect 13): beech's H_max 48 m,
    // its height curve's asymptote 41.75 m
    let beech = list.lines().find(|l| l.starts_with("beech ")).unwrap();
    assert!(beech.contains("48m") && beech.contains("41.8m"), "{beech}");
    assert!(list.contains("H_max: life.max_height_m") && list.contains("H_curve: life.growth.h_max_m"), "{list}");
    let o = run(&["species", "show", "beech"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), beech_text());

    let d = tempfile::tempdir().unwrap();
    let dir = d.path().to_str().unwrap();
    let o = run(&["species", "new", "red_beech", "--from", "beech", "--dir", dir]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lib = SpeciesLibrary::load_dir(d.path()).unwrap();
    assert_eq!(lib.species[0].id, "red_beech");
    // Refuses to overwrite.
    let before = std::fs::read(d.path().join("red_beech.toml")).unwrap();
    let o = run(&["species", "new", "red_beech", "--from", "scots_pine", "--dir", dir]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("already exists"));
    assert_eq!(std::fs::read(d.path().join("red_beech.toml")).unwrap(), before);
    // A name that is not an id is refused as the name, with an id offered; no file written.
    let o = run(&["species", "new", "Bad Name", "--from", "beech", "--dir", dir]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("species name \"Bad Name\"") && e.contains("e.g. `bad_name`"), "{e}");
    assert!(!d.path().join("Bad Name.toml").exists());
    assert!(sylva::species::is_species_id("oak2") && !sylva::species::is_species_id("2oak") && !sylva::species::is_species_id(""));
    assert_eq!(sylva::species::species_id_suggestion("  Red-Oak 2 "), "red_oak_2");
    assert_eq!(sylva::species::species_id_suggestion("2 Oak"), "sp_2_oak");
    // check exits non-zero and prints every problem.
    write(
        d.path(),
        "bad.toml",
        &beech_text()
            .replace("id = \"beech\"", "id = \"bad\"")
            .replace("k_c = 0.3\n", "k_c = 1.7\n")
            .replace("k_f = 1.0", "k_f = -1.0"),
    );
    let o = run(&["species", "check", dir]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("architecture.ecomod.k_c") && err.contains("architecture.ecomod.k_f"), "{err}");
}

#[test]
fn every_shipped_species_grows_an_ecomod_tree() {
    // The architecture parameters are usable by the structure module (EcoMod strand model).
    for s in SpeciesLibrary::embedded().unwrap().species {
        let (sk, _leaves) = sylva::structure::grow::ecomod::try_grow(&s.architecture.ecomod, 1, 0.0).unwrap_or_else(|e| panic!("{}: {e}", s.id));
        let _ = sk;
    }
}

/// An empty (or blank) species file is one problem naming the file, not every field missing
/// (a trial got 88 lines of `missing field`).
#[test]
fn an_empty_species_file_is_one_problem() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "empty.toml", " \n\n");
    let p = species::check_dir(d.path());
    assert_eq!(p.len(), 1, "{p:?}");
    let msg = p[0].to_string();
    assert!(msg.contains("empty.toml") && msg.contains("the file is empty"), "{msg}");
}

/// Issue 32 (round 34): Scots pine's mature form (the EcoMod model's change with age that `sylva
/// tree grow` applies) is its species file's `[architecture.mature_form]`, not code: read from
/// the file, checked like every field (errors naming the file, line and field), optional (no
/// other shipped species has one; a user may give any species one).
#[test]
fn mature_form_is_read_from_the_species_file_and_checked() {
    use sylva::species::MatureForm;
    use sylva::structure::forest_form::MatureForm as FormMatureForm;
    let lib = SpeciesLibrary::embedded().unwrap();
    for s in &lib.species {
        let want = (s.id == "scots_pine").then_some(MatureForm { from_age_yr: 30.0, full_age_yr: 80.0, trunk_k_s: 0.70, trunk_alpha_deg: 97.0, limb_alpha_m_deg: -1.0, leaf_distribution: LeafDistribution::Bunched, crown_profile: Some(sylva::species::CrownProfile { widest_depth: 0.15, top_exponent: 0.25, base_share: 0.5, width_to_length: 1.2, angle_top_deg: 55.0, angle_base_deg: 80.0, fork_depth: None, fork_limbs: None, fork_angle_deg: None, twig_droop_deg: None }) });
        assert_eq!(s.architecture.mature_form, want, "{}", s.id);
        assert_eq!(FormMatureForm::for_species(s), want, "{}", s.id);
    }
    let pine = std::fs::read_to_string(species_dir().join("scots_pine.toml")).unwrap();
    let pine_problems = |edit: &dyn Fn(&str) -> String| {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "pine.toml", &edit(&pine));
        species::check_dir(d.path())
    };
    // out of range: file, line, field and range named
    let p = pine_problems(&|t| t.replace("trunk_k_s = 0.70", "trunk_k_s = 1.5"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].file.ends_with("pine.toml"));
    assert_eq!((p[0].field.as_str(), p[0].value.as_str(), p[0].expected.as_str()), ("architecture.mature_form.trunk_k_s", "1.5", "a number in [0.5, 1]"));
    assert_eq!(p[0].line, Some(line_of(&pine, "trunk_k_s")));
    assert!(p[0].to_string().contains("pine.toml:") && p[0].to_string().contains("architecture.mature_form.trunk_k_s"), "{}", p[0]);
    // the blend must end after it starts
    let p = pine_problems(&|t| t.replace("full_age_yr = 80.0", "full_age_yr = 20.0"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "architecture.mature_form.full_age_yr");
    assert!(p[0].expected.contains("architecture.mature_form.from_age_yr = 30"), "{}", p[0].expected);
    // a table given is given whole; an unknown field is named
    let p = pine_problems(&|t| t.replace("trunk_alpha_deg = 97.0\n", ""));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "architecture.mature_form.trunk_alpha_deg");
    assert!(p[0].expected.starts_with("missing field"), "{}", p[0].expected);
    let p = pine_problems(&|t| t.replace("trunk_alpha_deg = 97.0\n", "trunk_alpha_deg = 97.0\nleader_deg = 3.0\n"));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "architecture.mature_form.leader_deg");
    let p = pine_problems(&|t| t.replace("leaf_distribution = \"Bunched\"", "leaf_distribution = \"Tufted\""));
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(p[0].field, "architecture.mature_form.leaf_distribution");
    // any species may have one; the value read is the one the tree is grown with
    let text = beech_text().replace("[architecture.light_guided]", "[architecture.mature_form]\nfrom_age_yr = 50.0\nfull_age_yr = 120.0\ntrunk_k_s = 0.8\ntrunk_alpha_deg = 60.0\nlimb_alpha_m_deg = 5.0\nleaf_distribution = \"Spiral\"\n\n[architecture.light_guided]");
    let b = Species::from_toml_str(&text, "beech_old.toml").unwrap();
    let m = FormMatureForm::for_species(&b).unwrap();
    assert_eq!((m.from_age_yr, m.full_age_yr, m.trunk_k_s, m.trunk_alpha_deg, m.limb_alpha_m_deg, m.leaf_distribution), (50.0, 120.0, 0.8, 60.0, 5.0, LeafDistribution::Spiral));
    assert_eq!(Species::from_toml_str(&b.to_toml_string().unwrap(), "rt.toml").unwrap(), b, "round trip");
}

/// Every shipped species' `life.drought_tolerance` is ForClim 2.x's `kDrTol` of its scientific
/// name (round 47, the broadleaves checked as the brief asked; trial 46 D4). The table is the
/// 30-species Central European parameter set of ForClim 2.x as a ForClim-derived model ("ForDem",
/// a public R script in the code search corpus, `selected_species_pars`: kHMax, kDDMin, kDrTol,
/// ...) carries it, whose kDDMin column equals LandClim's minDegreeDays species by species
/// (species/sources/SOURCES.md, "Shade survival and drought tolerance"). Bugmann 1994's Tab.
/// 3.11 (FORCLIM-P's Thornthwaite-Mather DrT) differs for the conifers compared (spruce 0.06,
/// fir 0.18, Scots pine 0.3, larch 0.12) and its broadleaf rows were not legible in the copy at
/// hand; SOURCES.md says why the later set goes with Sylva's bucket water balance. The test
/// fails when a file's value leaves the published set, and checks the ranking trial 46 asked
/// for: both oaks at least as drought-tolerant as beech, sessile oak more.
#[test]
fn drought_tolerances_are_forclim_2_kdrtol() {
    let lib = SpeciesLibrary::load_dir(&species_dir()).unwrap();
    let forclim: [(&str, f32); 17] = [
        ("Abies alba", 0.23),
        ("Larix decidua", 0.25),
        ("Picea abies", 0.15),
        ("Pinus sylvestris", 0.37),
        ("Acer platanoides", 0.25),
        ("Acer pseudoplatanus", 0.25),
        ("Alnus glutinosa", 0.08),
        ("Betula pendula", 0.16),
        ("Carpinus betulus", 0.25),
        ("Fagus sylvatica", 0.25),
        ("Fraxinus excelsior", 0.16),
        ("Populus tremula", 0.25),
        ("Quercus petraea", 0.33),
        ("Quercus robur", 0.25),
        ("Sorbus aucuparia", 0.33),
        ("Tilia cordata", 0.33),
        ("Ulmus glabra", 0.25),
    ];
    let mut seen = 0;
    for sp in &lib.species {
        let name = sp.identity.scientific_name.as_str();
        let want = forclim.iter().find(|(n, _)| name.starts_with(n)).unwrap_or_else(|| panic!("{}: {name} not in ForClim 2.x's table", sp.id)).1;
        assert_eq!(sp.life.drought_tolerance, Some(want), "{} ({name})", sp.id);
        seen += 1;
    }
    assert_eq!(seen, 17, "every shipped species checked");
    let tol = |id: &str| lib.species[lib.find(id).unwrap() as usize].life.drought_tolerance.unwrap();
    assert!(tol("sessile_oak") > tol("beech") && tol("pedunculate_oak") >= tol("beech"));
}
