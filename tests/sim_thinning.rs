//! Self-thinning: an even-aged single-species stand on a flat uniform site follows Reineke's
//! line, log N against log QMD with slope in [−2.0, −1.2] (Reineke 1933: −1.605; Pretzsch &
//! Biber 2005 for beech: −1.789).
mod common;

#[test]
fn reineke_slope() {
    let (sc, mut w) = common::world(r#"
name = "thinning"
years = 120
seed = 3
species = ["beech"]
[terrain]
uniform = { width = 5, height = 5, cell_m = 20.0, elevation_m = 200.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "planted"
species = "beech"
spacing_m = 1.2
age_yr = 3
"#);
    let rows = common::run(&sc, &mut w, 120);
    // the self-thinning phase: from the year stress mortality sets in, trees ≥ 7 cm
    let first = rows.iter().position(|r| r.deaths[1] > 0 && r.qmd_7cm_cm > 0.0).expect("no self-thinning");
    let pts: Vec<(f64, f64)> = rows[first..].iter().filter(|r| r.stems_7cm_ha > 0.0).map(|r| (r.qmd_7cm_cm.ln(), r.stems_7cm_ha.ln())).collect();
    let s = common::slope(&pts);
    eprintln!("self-thinning from year {} over {} years: slope {s:.3}", rows[first].year, pts.len());
    assert!(pts.len() > 40);
    assert!((-2.0..=-1.2).contains(&s), "slope {s:.3}");
}
