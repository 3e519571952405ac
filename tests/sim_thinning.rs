//! Self-thinning: an even-aged single-species stand on a flat uniform site follows Reineke's
//! line, log N against log QMD with slope in [−2.0, −1.2] (Reineke 1933: −1.605; Pretzsch &
//! Biber 2005 for beech: −1.789).
mod common;

#[test]
fn reineke_slope() {
    let (sc, mut w) = common::world(&common::ScenarioToml::new("thinning", 120, 3).species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 1.2, 3.0).build());
    let rows = common::run(&sc, &mut w, 120);
    // the self-thinning phase: from the year stress mortality sets in, trees ≥ 7 cm
    let first = rows.iter().position(|r| r.deaths[1] > 0 && r.qmd_7cm_cm > 0.0).expect("no self-thinning");
    let pts: Vec<(f64, f64)> = rows[first..].iter().filter(|r| r.stems_7cm_ha > 0.0).map(|r| (r.qmd_7cm_cm.ln(), r.stems_7cm_ha.ln())).collect();
    let s = common::slope(&pts);
    eprintln!("self-thinning from year {} over {} years: slope {s:.3}", rows[first].year, pts.len());
    assert!(pts.len() > 40);
    assert!((-2.0..=-1.2).contains(&s), "slope {s:.3}");
}
