//! Pure, unmanaged stands of sessile and pedunculate oak, Scots pine, Norway spruce and beech
//! (planted at 1.5 m on a flat 1 ha site at the species' niche optimum,
//! [`sylva::sim::pure_stand::run_pure_stand`]) against references for UNMANAGED stands, at ages
//! 30, 50, 100 and 120 (spruce: 30, 50, 100, where its NW-FVA class I ends):
//!
//! - **Density: the species' self-thinning line** (`common::Line`: SDI_max and the slope
//!   from species/*.toml with their sources; slope Pretzsch & Biber 2005, Forest Science
//!   51(4):304–320, fitted on fully stocked UNTHINNED long-term plots). Stems/ha ≥ 7 cm at their
//!   Dq must lie at relative density `common::RD_CLOSED` (0.8–1.1) of the line at ages 50–120
//!   and `common::RD_30` (0.6–1.1) at age 30 (why: see the constants).
//! - **Height: the table's top height H100** (NW-FVA 2021, yield class I; Albert et al. 2021;
//!   tests/data/stands/nwfva2021_yieldtable_et_{ei,ki,fi,bu}.csv) within 0.85–1.15 × at ages
//!   50–120. H100 is the mean height of the 100 thickest stems/ha; a thinning from below (the
//!   tables' regime takes mostly small and mid-sized stems) barely changes it, so the managed
//!   table's H100 is a reference for the unmanaged stand too. Not at 30, where the tables use a
//!   juvenile site-index fan modified from the height curves (NW-FVA 2021 user notes, "in der
//!   Jugend modifizierter Bonitätsfächer") and the simulated stand starts from 3-year-old
//!   planted seedlings.
//!
//! Until issue 35 round 36 this test held the unmanaged stands' N, basal area and Dq within
//! bands around the NW-FVA tables' own, which are of heavily thinned stands (RD 0.5–0.8 of the
//! species' line): an unmanaged stand differs from them by as much as its thinning regime does,
//! and the bands (N up to 4.2 × the table's) failed any slimmer young stand while passing
//! wide errors. The table's N, G and Dg are printed beside the simulation, not checked.
//!
//! Every check can fail: [`common::Line::check_and_mutants`] asserts that the same stand with
//! twice or half its stems fails the density band (a band narrower than a factor of 2), and
//! `checks_fail_a_stand_off_by_two` below feeds a stand off by ×2 in N or H100 through the same
//! checks.
use sylva::sim::density::sdi;
use sylva::sim::pure_stand::{run_pure_stand, PureStandYear};
mod common;
use common::Line;

/// H100 band against the table's H100 at ages 50–120.
const H100: (f64, f64) = (0.85, 1.15);

/// Rows `(age, [H100, N, G, Dg])` of yield class `ekl` of an NW-FVA 2021 table in tests/data/stands/.
fn nwfva(file: &str, ekl: f64) -> Vec<(f64, [f64; 4])> {
    let text = std::fs::read_to_string(format!("{}/tests/data/stands/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(|h| h.trim_matches('"').to_string()).collect();
    let ix = |name: &str| head.iter().position(|h| h == name).unwrap_or_else(|| panic!("{file}: no column {name}"));
    let (e, a, h, n, g, d) = (ix("Ekl"), ix("Alter"), ix("H100"), ix("N"), ix("G"), ix("Dg"));
    lines
        .filter_map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(f64::NAN)).collect();
            (f[e] == ekl).then(|| (f[a], [f[h], f[n], f[g], f[d]]))
        })
        .collect()
}

/// The checks of one age: `Err` for each failed one. `n_ha`, `dq_cm`: stems ≥ 7 cm; `h100_m`
/// the stand's top height; `t` the table row `[H100, N, G, Dg]`.
fn check_age(line: &Line, age: f64, n_ha: f64, dq_cm: f64, h100_m: f64, t: [f64; 4]) -> Vec<String> {
    let what = format!("{} age {age}", line.species);
    let band = Line::band(age);
    let mut bad: Vec<String> = line.check_and_mutants(&what, n_ha, dq_cm, band).err().into_iter().collect();
    if age >= 50.0 {
        let q = h100_m / t[0];
        if !(H100.0..=H100.1).contains(&q) {
            bad.push(format!("{what}: H100 {h100_m:.1} m vs table {} (ratio {q:.2}, want {:.2}–{:.2})", t[0], H100.0, H100.1));
        }
    }
    bad
}

/// Checks a species' pure stand against its line and class I of `file` at ages 30, 50, 100
/// and 120 (those the table has); returns the failures (empty when all pass).
fn check_species(id: &str, file: &str) -> Vec<String> {
    let lib = common::embedded();
    let line = Line::of(&lib, id);
    let rows: Vec<PureStandYear> = run_pure_stand(&lib, id, 100.0, 1.5, 3.0, 120.0, 7).unwrap();
    let tab = nwfva(file, 1.0);
    let mut bad = Vec::new();
    for age in [30.0, 50.0, 100.0, 120.0] {
        let Some(t) = tab.iter().find(|t| t.0 == age).map(|t| t.1) else { continue };
        let r = rows.iter().find(|r| r.age == age).unwrap();
        let rd_t = sdi(t[1], t[3], line.slope) / line.sdi_max;
        eprintln!(
            "{id} age {age}: sim H100 {:.1} N {:.0} BA {:.1} Dq {:.1} RD {:.2} (all stems N {:.0} Dq {:.1} RD {:.2}) | NW-FVA I (thinned) H100 {} N {} G {} Dg {} RD {rd_t:.2}",
            r.h100_m,
            r.d7.n_ha,
            r.d7.ba_m2_ha,
            r.d7.dq_cm,
            line.rd(r.d7.n_ha, r.d7.dq_cm),
            r.all.n_ha,
            r.all.dq_cm,
            line.rd(r.all.n_ha, r.all.dq_cm),
            t[0],
            t[1],
            t[2],
            t[3]
        );
        bad.extend(check_age(&line, age, r.d7.n_ha, r.d7.dq_cm, r.h100_m, t));
    }
    bad
}

/// Every species with an NW-FVA 2021 table: both oaks (the table is for oak, Eiche, without
/// separating Quercus robur and Q. petraea), Scots pine, Norway spruce and beech; all failures are
/// listed at once.
#[test]
fn unmanaged_species_on_their_lines_at_the_tables_top_height() {
    let species = [
        ("sessile_oak", "nwfva2021_yieldtable_et_ei.csv"),
        ("pedunculate_oak", "nwfva2021_yieldtable_et_ei.csv"),
        ("scots_pine", "nwfva2021_yieldtable_et_ki.csv"),
        ("norway_spruce", "nwfva2021_yieldtable_et_fi.csv"),
        ("beech", "nwfva2021_yieldtable_et_bu.csv"),
    ];
    let bad: Vec<String> = species.iter().flat_map(|(id, file)| check_species(id, file)).collect();
    assert!(bad.is_empty(), "{bad:#?}");
}

/// The checks fail a stand off by ×2: a stand on Norway spruce's line (RD 1.0) at NW-FVA's top
/// height passes at 30, 50 and 100; with twice or half the stems, or twice or half the top
/// height (ages ≥ 50), it fails.
#[test]
fn checks_fail_a_stand_off_by_two() {
    let lib = common::embedded();
    let line = Line::of(&lib, "norway_spruce");
    let tab = nwfva("nwfva2021_yieldtable_et_fi.csv", 1.0);
    for (age, dq) in [(30.0, 12.0), (50.0, 19.0), (100.0, 32.0)] {
        let t = tab.iter().find(|t| t.0 == age).unwrap().1;
        let n = sylva::sim::density::max_stems(line.sdi_max, line.slope, dq);
        assert!((line.rd(n, dq) - 1.0).abs() < 1e-9);
        assert!(check_age(&line, age, n, dq, t[0], t).is_empty(), "age {age}: {:?}", check_age(&line, age, n, dq, t[0], t));
        for k in [2.0, 0.5] {
            let off = check_age(&line, age, k * n, dq, t[0], t);
            assert!(off.len() == 1 && off[0].contains(&format!("is RD {:.2}", k)), "age {age}, {k} × N: {off:?}");
            if age >= 50.0 {
                let off = check_age(&line, age, n, dq, k * t[0], t);
                assert!(off.len() == 1 && off[0].contains("H100"), "age {age}, {k} × H100: {off:?}");
            }
        }
    }
}

#[test]
fn nwfva_tables_are_read() {
    // the reader returns the published rows: oak class I at 100 (N 221, G 24.1, Dg 37.3, H100 27.0)
    let t = nwfva("nwfva2021_yieldtable_et_ei.csv", 1.0);
    let r = t.iter().find(|r| r.0 == 100.0).unwrap().1;
    assert_eq!(r, [27.0, 221.0, 24.1, 37.3]);
    let p = nwfva("nwfva2021_yieldtable_et_ki.csv", 1.0);
    assert_eq!(p.iter().find(|r| r.0 == 50.0).unwrap().1, [20.3, 829.0, 28.4, 20.5]);
}
