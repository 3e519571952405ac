//! Self-thinning: an even-aged single-species stand on a flat uniform site follows Reineke's
//! line. The fixture beech's maximum-density line has Reineke's slope −1.605 (Reineke 1933;
//! `sim::fixtures::beech_like`); the least-squares slope of ln N on ln Dq (stems ≥ 7 cm) over the
//! fully stocked phase — the years whose stand density index is at least 90 % of the run's
//! maximum, as in Pretzsch & Biber's (2005) fully stocked plots — must lie within
//! −1.605 ± 0.15 (Pretzsch & Biber's species slopes span −1.42 … −1.79). Over all years from the
//! first stress death on (old years, when the stand has fallen to 0.85–0.9 of its line,
//! included) it must lie within −1.605 ± 0.25.
mod common;
use sylva::sim::density::{sdi, REINEKE_SLOPE};

#[test]
fn reineke_slope() {
    let (sc, mut w) = common::world(&common::ScenarioToml::new("thinning", 120, 3).species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 1.2, 3.0).build());
    let rows = common::run(&sc, &mut w, 120);
    let first = rows.iter().position(|r| r.deaths[1] > 0 && r.qmd_7cm_cm > 0.0).expect("no self-thinning");
    let sdis: Vec<f64> = rows.iter().map(|r| sdi(r.stems_7cm_ha, r.qmd_7cm_cm, REINEKE_SLOPE)).collect();
    let top = sdis.iter().cloned().fold(0.0, f64::max);
    let pts: Vec<(f64, f64)> = rows[first..]
        .iter()
        .zip(&sdis[first..])
        .filter(|(r, s)| r.stems_7cm_ha > 0.0 && **s >= 0.9 * top)
        .map(|(r, _)| (r.qmd_7cm_cm.ln(), r.stems_7cm_ha.ln()))
        .collect();
    let s = common::slope(&pts);
    let all: Vec<(f64, f64)> = rows[first..].iter().filter(|r| r.stems_7cm_ha > 0.0 && r.qmd_7cm_cm > 0.0).map(|r| (r.qmd_7cm_cm.ln(), r.stems_7cm_ha.ln())).collect();
    let s_all = common::slope(&all);
    eprintln!("all self-thinning years: {} slope {s_all:.3}", all.len());
    eprintln!("self-thinning from year {} (max SDI {top:.0}), {} fully stocked years: slope {s:.3}", rows[first].year, pts.len());
    assert!(pts.len() > 40, "only {} fully stocked years", pts.len());
    assert!((s - REINEKE_SLOPE).abs() <= 0.15, "slope {s:.3}, want −1.605 ± 0.15");
    // over every year from the first stress death on, old years included (when the stand has
    // fallen to 0.85–0.9 of its line), the slope is steeper; within ± 0.25 of Reineke's
    assert!((s_all - REINEKE_SLOPE).abs() <= 0.25, "all-years slope {s_all:.3}, want −1.605 ± 0.25");
}
