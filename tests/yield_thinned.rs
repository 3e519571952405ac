//! Issue 35's yield validation: the shipped thinning scenarios follow Wiedemann's
//! moderate-thinning tables, yield class I (tests/data/stands/), within ±20 % in stems/ha N,
//! quadratic mean DBH Dq and basal area BA (stems ≥ 7 cm DBH) at ages 50 and 100:
//! `scenarios/thinning_beech.toml` against the beech table (Wiedemann 1931) and
//! `scenarios/thinning_spruce.toml` against the Norway spruce table (Wiedemann 1936/42).
//! Both are planted at age 3 (age = 3 + simulated year) and thinned from below every 5 years
//! (docs/management.md, "Validation"). `sylva simulate` of the scenario, then
//! `python3 tools/thinning_check.py [--species spruce] OUT 3 50 100` gives the figures of all
//! stems ≥ 7 cm (the stand table's), which are the main stand's only until about age 70: later
//! they include the regeneration grown past 7 cm under the canopy (round 34: spruce at 100 N 657
//! and Dq 30.7 cm for all, 411 and 38.4 cm for the main stand this test checks).
//!
//! The beech test passes since round 44 (docs/management.md, "Round 44 (branch `r44t`)"):
//! beech's closed-stand diameter increment at TreeGrOSS's youth slenderness (`life.closed_hd` =
//! 140 m/m) holds at every DBH until a tree reaches beech's dense-stand height curve
//! (`life.dense_hd`, iLand's HDhigh), and a tree held at that curve grows along it
//! (`closed_hd_scope = "dense_curve"`), with the scenario planted at 1.0 m (Heukamp 1999): main
//! stand N 1,517 / 326 (−12 % / −19 %), Dq 14.7 / 34.6 cm (+3 % / +8 %), BA 25.7 / 30.7 m²/ha
//! (−7 % / −6 %) at ages 50 / 100 (the release run's inventory; `r43_trajectory.py`). Read the
//! figures with `cargo test --test yield_thinned -- --nocapture`. The history before it: round 33
//! (the dense-stand height bound counted from breast height): N 477 / 125 (−72 % / −69 %), Dq
//! 28.0 / 59.1 cm (+96 % / +85 %), BA 29.4 / 34.3 m²/ha at ages 50 / 100; with PROGNAUS's beech
//! competition response (Hasenauer 2000's Buche b3, c1, c2; measured, not adopted) N 713 / 185
//! (−58 % / −54 %): the young stand (ages 5–30) puts on too much basal area before any
//! thinning (docs/management.md, "Round 33"). Before round 33, with the
//! species' dense-stand height bound (`life.dense_hd`, issue 35 round 28, on for every species
//! that has one) beech misses by N −73 % / −70 %, Dq +98 % / +87 % at ages 50 / 100 (before it:
//! −72 % / −69 %, +96 % / +86 %): the thinned model stems are stouter than Wiedemann's (median
//! H/D 67 against 129 for beech at 50), so bounding slender trees cannot close the gap
//! (docs/management.md, "Dense-stand height bound"). Branches h35w (height–diameter allocation
//! after iLand), h35y/h35z (size-asymmetric competition, crown closure) measured other levers
//! there. Round 31 (docs/management.md, "Where the thinned stands' growth goes"): the thinned
//! beech stand loses its stems to the thinnings at ages 25–50 (3,403/ha, none to crowding)
//! because its young trees put on 2–4 times PROGNAUS's basal-area increment.
//! Round 35 (docs/management.md, "Round 35"; measured, not adopted): with beech's diameter
//! increment on the yield tables' thicket slenderness from crown closure
//! (`tools/experiments/r35_thicket_allocation.patch`, HD 126 from Wiedemann's mean tree at 30)
//! and the scenario planted at 1.0 m instead of 1.5 m, the main stand meets ±20 %: N −10 % /
//! +8 %, Dq +1 % / −8 %, BA −8 % / −8 % at 50 / 100; either change alone does not (N −36 % to
//! −46 % and −66 % at 50).
//! Round 36 (docs/management.md, "Round 36"; measured, not adopted): the same switch with a
//! sourced H/D, iLand's HDhigh of beech (`life.dense_hd`, as the H/D of the increments,
//! `tools/experiments/r36_iland_thicket.patch`), leaves N −70 % / −68 % at the shipped 1.5 m
//! and −55 % / −63 % at 1.0 m (Heukamp 1999's > 10,000 plants/ha): HDhigh falls to 87–76 at
//! 10–15 cm DBH where the tables' thicket keeps 109–126.
//! Round 37 (measured, not adopted): BWINPro/TreeGrOSS's beech growth (`life.bai_bwinpro`)
//! gives N +24 % / −41 %, Dq −15 % / +28 % at 50 / 100. Round 38 (measured, not adopted,
//! `tools/experiments/r38_bwinpro_c66c.patch`): with its release index C66c (+0.4521, a boost
//! after each thinning, not a damping) N +21 % / −45 %, Dq −14 % / +33 %.
//!
//! Round 41 (docs/management.md, "Round 41"): beech's closed-stand diameter increment at
//! TreeGrOSS's youth slenderness (`life.closed_hd` = 140 m/m, in place of the growth model's 60)
//! at every DBH, with the scenario planted at 1.0 m (Heukamp 1999), met the table (the test
//! `thinned_beech_at_treegross_slenderness_planted_at_one_metre_follows_the_table`, removed in
//! round 42: the field no longer means that). Round 42 (docs/management.md, "Round 42 (branch
//! `r42b`)") set it in a build and found the unmanaged stand's top height 10 % under NW-FVA's at
//! 100 and 120: beech's dense-stand height bound stops the slender dominants. Round 42's second
//! helper (r42h) limited `life.closed_hd` to the trees below 7 cm DBH, the scope of TreeGrOSS's
//! youth rule (`Tree.grow`): the unmanaged top height is kept
//! (`unmanaged_beech_keeps_its_top_height`, so named since round 44), but the thinned
//! beech at 140 below 7 cm and 1.0 m misses the table as before (N −64 % / −66 %, Dq +71 % /
//! +76 % at 50 / 100), so beech keeps 60.
//! Round 43 (docs/management.md, "Round 43 (branch `r43t`)"; measured, not adopted): iLand's
//! H/D of the increments between HDlow and HDhigh by the tree's light (`life.open_hd` with
//! `life.dense_hd`, iLand's fasy curves, at every density), with TreeGrOSS's 140 below 7 cm and
//! the scenario planted at 1.0 m, follows the table at ages 35–40 (N −13 % / −7 %), then N −41 %,
//! Dq +29 % at 50 and −62 %, +65 % at 100: the thinnings free the crowns, and iLand's rule
//! grows freed crowns at HDlow (40–43 m/m at 11–14 cm). iLand's rule alone: N −63 % at 50.
//!
//! The spruce test passes since round 32: Norway spruce's diameter increment takes PROGNAUS's
//! competition response (Monserud & Sterba 1996; `life.bai_competition` in
//! species/norway_spruce.toml) in place of the crowding modifier: N 1,176 / 397 (−11 % / −9 %),
//! Dq 20.4 / 39.2 cm (+6 % / +4 %), BA 38.5 / 47.9 m²/ha (0 % / −1 %) at ages 50 / 100 (before
//! it N −36 % / −30 %, Dq +28 % / +23 %); since round 33 (the height bound from breast height)
//! N 1,205 / 411 (−9 % / −6 %), Dq 20.1 / 38.4 cm (+4 % / +2 %), BA 38.3 / 47.6 m²/ha (−1 % /
//! −1 %). Its main stand's mean height h_q is 19.6 / 31.7 m, 1.6 m below the table's
//! (tests/management.rs, `thinning_spruce_follows_the_wiedemann_mean_height`, ignored).
//!
//! Measured on the main stand since round 32 (stems ≥ 7 cm at least a third of top height tall,
//! the stems the thinnings work on; the yield tables count the main stand, not a second layer):
//! the thinnings no longer take the beech/spruce ingrowth under an old canopy, which then stands
//! as a lower layer of stems ≥ 7 cm (all stems ≥ 7 cm at 100: beech N 444, Dq 32.3 cm; spruce
//! N 680, Dq 30.4 cm), while the main stand's figures are those the thinnings that took the
//! ingrowth left (beech N 124 / Dq 59.5 cm, spruce 397 / 39.2 cm at 100).
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

/// (N, Dq) of the main stand of `w` (stems ≥ 7 cm DBH at least
/// [`sylva::sim::phases::management::MAIN_STAND_SHARE`] of their top height tall, as the
/// thinnings take them; the yield tables count the main stand, not a second layer of ingrowth),
/// and of all its stems ≥ 7 cm, per ha.
fn main_stand(w: &sylva::sim::World) -> ((f64, f64), (f64, f64)) {
    let t = &w.stand.trees;
    let a = w.site.area_ha;
    let stock: Vec<usize> = (0..t.len()).filter(|&i| t.height[i] >= 1.3 && t.dbh[i] >= 7.0).collect();
    let d: Vec<f32> = stock.iter().map(|&i| t.dbh[i]).collect();
    let h: Vec<f32> = stock.iter().map(|&i| t.height[i]).collect();
    let top = sylva::sim::stats::top_height_by(&d, &h, a, stock.len() as u64, &mut sylva::sim::stats::alone).unwrap();
    let low = sylva::sim::phases::management::MAIN_STAND_SHARE * top as f32;
    let nd = |keep: &dyn Fn(usize) -> bool| {
        let dd: Vec<f64> = stock.iter().filter(|&&i| keep(i)).map(|&i| (t.dbh[i] as f64).powi(2)).collect();
        (dd.len() as f64 / a, (dd.iter().sum::<f64>() / dd.len().max(1) as f64).sqrt())
    };
    (nd(&|i| t.height[i] >= low), nd(&|_| true))
}

/// Runs `scenarios/<name>.toml` to age 100 and checks N, Dq, BA of the main stand at ages 50
/// and 100 against `table`.
fn check(name: &str, table: &str) {
    let text = std::fs::read_to_string(format!("{}/scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    check_with(name, &text, &common::embedded(), table);
}

/// As [`check`], for scenario text `text` (named `name` in the messages) grown with `lib`.
fn check_with(name: &str, text: &str, lib: &sylva::species::SpeciesLibrary, table: &str) {
    let (sc, mut w) = common::world_with(text, lib);
    let mut bad = Vec::new();
    let mut year = 0;
    for age in [50.0, 100.0] {
        let to = (age - 3.0) as u32;
        common::run(&sc, &mut w, to - year);
        year = to;
        let ((n, dq), (n_all, dq_all)) = main_stand(&w);
        let ba = std::f64::consts::PI / 4.0 * n * dq * dq / 1e4;
        let t = table_row(table, age);
        eprintln!("{name} age {age}: main stand N {n:.0} (table {}), Dq {dq:.1} cm ({}), BA {ba:.1} m²/ha ({}); all stems ≥ 7 cm N {n_all:.0}, Dq {dq_all:.1} cm", t.0, t.1, t.2);
        for (lab, s, x) in [("N", n, t.0), ("Dq", dq, t.1), ("BA", ba, t.2)] {
            let rel = s / x - 1.0;
            if rel.abs() > 0.2 {
                bad.push(format!("age {age}: {lab} {s:.1} vs table {x} ({:+.0} %)", rel * 100.0));
            }
        }
    }
    assert!(bad.is_empty(), "{name} misses Wiedemann's table by more than 20 %: {bad:?}");
}

/// Met since round 44 (module doc): N, Dq and BA of the main stand within ±20 % of Wiedemann's
/// class I at 50 and 100. It fails on main (round 43: N −71 % / −69 %, Dq +93 % / +84 %) and on
/// every earlier model (module doc). Round 41's variant (140 at every DBH without the dense
/// curve's slope; the mutation `closed_slenderness_held` → `closed_slenderness`) passes it too
/// (N −9 % / +13 %, Dq +1 % / −10 %), with h_q 28.1 m against 31.95 at 100: that mutation is
/// caught by the unmanaged top height below, not here.
#[test]
fn thinned_beech_follows_wiedemanns_moderate_thinning_table() {
    check("thinning_beech", "ForestElementsR_fe_ytable_beech_wiedemann_moderate_1931.csv");
}

/// Met since round 32: Norway spruce's diameter increment takes PROGNAUS's competition response
/// (`life.bai_competition`; docs/management.md).
#[test]
fn thinned_spruce_follows_wiedemanns_moderate_thinning_table() {
    check("thinning_spruce", "ForestElementsR_fe_ytable_spruce_wiedemann_moderate_1936_42.csv");
}

/// Issue 35 rounds 42 and 44 (docs/management.md, "Round 44 (branch `r44t`)"): with the
/// shipped beech's closed-stand slenderness (`life.closed_hd` = 140 m/m at every DBH up to its
/// dense-stand curve, `closed_hd_scope = "dense_curve"`), the unmanaged stand keeps its top
/// height. Top height H100 (the 100 thickest stems/ha) is the stand quantity a thinning from
/// below changes least, and beech's height–age curve is fitted to the NW-FVA 2021 table's H100
/// of class I (RMS 0.16 m; species/beech.toml), so the unmanaged stand at the niche optimum
/// (1 ha planted at 1.5 m, `sim_density`'s seed 7) keeps it within ±5 % at ages 100 and 120
/// (32.5 and 35.4 m, tests/data/stands/nwfva2021_yieldtable_et_bu.csv): 31.7 / 34.6 m
/// (0.975 / 0.979) in the release run of this round.
///
/// Fails without the curve's slope for the trees held at it (the mutation
/// `closed_slenderness_held` → `closed_slenderness` in the growth phase, i.e. round 41's 140 at
/// every DBH): 28.4 / 30.5 m (0.875 / 0.861; round 42 measured 0.901 / 0.897 before round 43's
/// crowding weights). The slender dominants are then held at the curve (1.3 + 3.236 D^0.632 m,
/// 29.0 m at 30 cm) while their diameter grows at 140, so their height grows at the curve's
/// slope over 140 of its potential, 0.42 of it at 30 cm.
#[test]
fn unmanaged_beech_keeps_its_top_height() {
    let lib = common::embedded();
    let beech = lib.species.iter().find(|s| s.id == "beech").unwrap();
    assert_eq!((beech.life.closed_hd, beech.life.closed_hd_scope), (Some(140.0), Some(sylva::species::ClosedHdScope::DenseCurve)), "species/beech.toml's slenderness is no longer the one this test cites");
    let rows = sylva::sim::pure_stand::run_pure_stand(&lib, "beech", 100.0, 1.5, 3.0, 120.0, 7).unwrap();
    let text = std::fs::read_to_string(format!("{}/tests/data/stands/nwfva2021_yieldtable_et_bu.csv", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut bad = Vec::new();
    for age in [100.0, 120.0] {
        let t: f64 = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.trim_matches('"').parse::<f64>().unwrap_or(f64::NAN)).collect::<Vec<_>>())
            .find(|f| f[0] == 1.0 && f[1] == age)
            .map(|f| f[4])
            .unwrap();
        let r = rows.iter().find(|r| r.age == age).unwrap();
        let q = r.h100_m / t;
        eprintln!("beech age {age}: H100 {:.1} m, NW-FVA class I {t} m (ratio {q:.3}); N {:.0}, Dq {:.1} cm", r.h100_m, r.d7.n_ha, r.d7.dq_cm);
        if !(0.95..=1.05).contains(&q) {
            bad.push(format!("age {age}: H100 {:.1} m vs {t} m ({q:.3})", r.h100_m));
        }
    }
    assert!(bad.is_empty(), "unmanaged beech loses its top height: {bad:?}");
}
