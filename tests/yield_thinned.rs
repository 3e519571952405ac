//! Issue 35's yield validation: the shipped thinning scenarios follow Wiedemann's
//! moderate-thinning tables, yield class I (tests/data/stands/), within ±20 % in stems/ha N,
//! quadratic mean DBH Dq and basal area BA (stems ≥ 7 cm DBH) at ages 50 and 100:
//! `scenarios/thinning_beech.toml` against the beech table (Wiedemann 1931) and
//! `scenarios/thinning_spruce.toml` against the Norway spruce table (Wiedemann 1936/42).
//! Both are planted at age 3 (age = 3 + simulated year) and thinned from below every 5 years
//! (docs/management.md, "Validation"). The same figures: `sylva simulate` of the scenario, then
//! `python3 tools/thinning_check.py [--species spruce] OUT 3 50 100`.
//!
//! Both are ignored: neither is met by the model of main. Run them with
//! `cargo test --release --test yield_thinned -- --ignored`, and with the experiment switch of
//! branch h35w in front, `SYLVA_HDX` (competition-dependent allocation between height and
//! diameter after iLand; `sim::phases::growth::HD_ALLOCATION_SWITCH`): with `SYLVA_HDX=67`
//! (iLand's form) beech misses by N −68 % / −68 %, Dq +81 % / +82 % and spruce by N −34 % /
//! −28 %; at the lever's bound `SYLVA_HDX=85` (every tree on the dense-stand allocation) beech
//! by N −49 % / −59 %, Dq +40 % / +59 %, spruce only on N at 50 (−23 %); every such variant fails
//! unmanaged density tests (docs/management.md, "Height–diameter allocation by competition
//! (branch h35w)"). Branches h35y/h35z measured size-asymmetric competition and crown closure
//! (docs/management.md of those branches).
mod common;

/// The table's (N, Dq, BA) at `age`, yield class I.
fn table_row(file: &str, age: f64) -> (f64, f64, f64) {
    let text = std::fs::read_to_string(format!("{}/tests/data/stands/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let ix = |n: &str| head.iter().position(|h| *h == n).unwrap_or_else(|| panic!("{file}: no column {n}"));
    let (si, a, n, dq, ba) = (ix("site_index"), ix("age"), ix("n_ha"), ix("d_q_cm"), ix("ba_m2_ha"));
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap_or(f64::NAN)).collect::<Vec<_>>())
        .find(|f| f[si] == 1.0 && f[a] == age)
        .map(|f| (f[n], f[dq], f[ba]))
        .unwrap_or_else(|| panic!("{file}: no class I row at age {age}"))
}

/// Runs `scenarios/<name>.toml` in full and checks N, Dq, BA at ages 50 and 100 against `table`.
fn check(name: &str, table: &str) {
    let text = std::fs::read_to_string(format!("{}/scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let (sc, mut w) = common::world_with(&text, &common::embedded());
    let rows = common::run(&sc, &mut w, sc.years);
    let mut bad = Vec::new();
    for age in [50.0, 100.0] {
        let r = rows.iter().find(|r| r.year as f64 + 3.0 == age).unwrap();
        let (n, dq) = (r.stems_7cm_ha, r.qmd_7cm_cm);
        let ba = std::f64::consts::PI / 4.0 * n * dq * dq / 1e4;
        let t = table_row(table, age);
        eprintln!("{name} age {age}: N {n:.0} (table {}), Dq {dq:.1} cm ({}), BA {ba:.1} m²/ha ({})", t.0, t.1, t.2);
        for (lab, s, x) in [("N", n, t.0), ("Dq", dq, t.1), ("BA", ba, t.2)] {
            let rel = s / x - 1.0;
            if rel.abs() > 0.2 {
                bad.push(format!("age {age}: {lab} {s:.1} vs table {x} ({:+.0} %)", rel * 100.0));
            }
        }
    }
    assert!(bad.is_empty(), "{name} misses Wiedemann's table by more than 20 %: {bad:?}");
}

#[test]
#[ignore = "issue 35: not met (N -72 %, Dq +96 % at age 50 on main; -49 %, +40 % at the bound of the h35w allocation switch, SYLVA_HDX=85): docs/management.md"]
fn thinned_beech_follows_wiedemanns_moderate_thinning_table() {
    check("thinning_beech", "ForestElementsR_fe_ytable_beech_wiedemann_moderate_1931.csv");
}

#[test]
#[ignore = "issue 35: not met (N -35 % at age 50 on main; -23 % with SYLVA_HDX=85, which fails unmanaged density tests): docs/management.md"]
fn thinned_spruce_follows_wiedemanns_moderate_thinning_table() {
    check("thinning_spruce", "ForestElementsR_fe_ytable_spruce_wiedemann_moderate_1936_42.csv");
}
