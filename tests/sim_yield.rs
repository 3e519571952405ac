//! Yield: an unmanaged beech stand planted at 1.5 m spacing on a good site against the NW-FVA
//! 2021 beech yield table, class I (tests/data/stands/nwfva2021_yieldtable_et_bu.csv): top
//! height at ages 50 and 100 within 20 %, stems/ha and quadratic mean DBH (trees ≥ 7 cm, the
//! table's threshold) within a factor of 2. Writes docs/yield_beech.png.
mod common;
use sylva::output::plot::{plot_panels_png, Panel, Series};

/// (age, N, H100, Dg) of yield class I.
fn table() -> Vec<(f64, f64, f64, f64)> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/stands/nwfva2021_yieldtable_et_bu.csv")).unwrap();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.trim_matches('"').parse().unwrap_or(f64::NAN)).collect();
            (f[0] == 1.0).then(|| (f[1], f[2], f[4], f[6]))
        })
        .collect()
}

const PLANT_AGE: u32 = 3;

#[test]
fn beech_yield_class_one() {
    let lib = common::embedded();
    let toml = common::ScenarioToml::new("yield", 117, 7).species(&["beech"]).line("climate = { latitude_deg = 51.0 }").uniform(5, 5, 20.0, 200.0).planted("beech", 1.5, PLANT_AGE as f64).build();
    let (sc, mut w) = common::world_with(&toml, &lib);
    let rows = common::run(&sc, &mut w, 117);
    let age = |r: &sylva::sim::stats::StandRow| (r.year + PLANT_AGE) as f64;
    let tab = table();
    for a in [50.0, 100.0] {
        let r = rows.iter().find(|r| age(r) == a).unwrap();
        let t = tab.iter().find(|t| t.0 == a).unwrap();
        eprintln!("age {a}: simulated N {:.0} H100 {:.1} Dg {:.1} | table N {} H100 {} Dg {}", r.stems_7cm_ha, r.top_height_m, r.qmd_7cm_cm, t.1, t.2, t.3);
        assert!((r.top_height_m / t.2 - 1.0).abs() <= 0.2, "H100 at {a}: {:.1} vs {}", r.top_height_m, t.2);
        let n = r.stems_7cm_ha / t.1;
        assert!((0.5..=2.0).contains(&n), "N at {a}: {:.0} vs {}", r.stems_7cm_ha, t.1);
        let d = r.qmd_7cm_cm / t.3;
        assert!((0.5..=2.0).contains(&d), "Dg at {a}: {:.1} vs {}", r.qmd_7cm_cm, t.3);
    }
    // picture: simulated against tabulated development
    let sim = |f: &dyn Fn(&sylva::sim::stats::StandRow) -> f64| rows.iter().filter(|r| f(r) > 0.0).map(|r| (age(r), f(r))).collect::<Vec<_>>();
    let tb = |f: &dyn Fn(&(f64, f64, f64, f64)) -> f64| tab.iter().filter(|t| t.0 <= 120.0).map(|t| (t.0, f(t))).collect::<Vec<_>>();
    let pair = |title: &str, unit: &str, s: Vec<(f64, f64)>, t: Vec<(f64, f64)>| Panel {
        title: title.into(),
        x_label: "age (years)".into(),
        y_label: unit.into(),
        series: vec![
            Series { name: "Sylva, unmanaged (DBH ≥ 7 cm)".into(), points: s, color: [30, 110, 40], markers: false },
            Series { name: "NW-FVA 2021 class I (thinned)".into(), points: t, color: [200, 60, 30], markers: true },
        ],
    };
    let panels = vec![
        pair("Top height H100", "m", sim(&|r| r.top_height_m), tb(&|t| t.2)),
        pair("Stems per hectare", "stems/ha", sim(&|r| r.stems_7cm_ha), tb(&|t| t.1)),
        pair("Quadratic mean DBH", "cm", sim(&|r| r.qmd_7cm_cm), tb(&|t| t.3)),
    ];
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    std::fs::create_dir_all(&docs).unwrap();
    plot_panels_png(&docs.join("yield_beech.png"), &panels, 3, (1500, 480)).unwrap();
}
