//! Yield: an unmanaged beech stand planted at 1.5 m on a good site against the NW-FVA 2021
//! beech yield table, class I (tests/data/stands/nwfva2021_yieldtable_et_bu.csv).
use sylva::conditions::SiteConditions;
use sylva::sim::{fixtures, step_year, Scenario, World, YearReport};

fn table() -> Vec<(f64, f64, f64, f64)> {
    // (age, N, H100, Dg) of yield class 1
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/stands/nwfva2021_yieldtable_et_bu.csv")).unwrap();
    text.lines().skip(1).filter_map(|l| {
        let f: Vec<f64> = l.split(',').map(|x| x.trim_matches('"').parse().unwrap_or(f64::NAN)).collect();
        (f[0] == 1.0).then(|| (f[1], f[2], f[4], f[6]))
    }).collect()
}

#[test]
fn beech_yield_class_one() {
    let lib = fixtures::library();
    let sc = Scenario::from_toml_str(r#"
name = "yield"
years = 100
seed = 7
species = ["beech"]
[terrain]
uniform = { width = 3, height = 3, cell_m = 20.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "planted"
species = "beech"
spacing_m = 1.5
age_yr = 3
"#, "yield").unwrap();
    let site = SiteConditions::uniform(3, 3, 20.0, 200.0, [5.0, 5.0, 2.0, 5.0, 6.0, 6.0], 51.0);
    let mut w = World::new(site, &lib, &sc).unwrap();
    let mut rows = vec![];
    for _ in 0..97 {
        let mut r = YearReport::default();
        step_year(&mut w, &sc, &mut r);
        let row = r.row.unwrap();
        if row.year % 10 == 7 {
            eprintln!("age {} N {:.0} seedl {:.0} H100 {:.1} Dg {:.1} BA {:.1} N7 {:.0} Dg7 {:.1} deaths {:?}", row.year + 3, row.stems_ha, row.seedlings_ha, row.top_height_m, row.qmd_cm, row.basal_area_m2_ha, row.stems_7cm_ha, row.qmd_7cm_cm, row.deaths);
        }
        rows.push(row);
    }
    let tab = table();
    for age in [50.0, 100.0] {
        let r = &rows[(age as usize) - 4];
        let t = tab.iter().find(|t| t.0 == age).unwrap();
        eprintln!("age {age}: sim N {:.0} H100 {:.1} Dg {:.1} | table N {} H100 {} Dg {}", r.stems_ha, r.top_height_m, r.qmd_cm, t.1, t.2, t.3);
    }
}
