//! Succession: birch (pioneer, L 7, shade tolerance 1) and beech (L 3, tolerance 5) arrive
//! together by seed rain on bare, beech-suitable flat land. Birch must dominate basal area at
//! year 30 and beech at year 200.
mod common;

#[test]
fn birch_then_beech() {
    let lib = common::embedded();
    let toml = common::ScenarioToml::new("succession", 200, 11)
        .species(&["beech", "silver_birch"])
        .uniform(5, 5, 20.0, 300.0)
        .seed_rain("silver_birch", 10000.0)
        .seed_rain("beech", 300.0)
        .build();
    let (sc, mut w) = common::world_with(&toml, &lib);
    let rows = common::run(&sc, &mut w, 200);
    for r in rows.iter().filter(|r| r.year % 20 == 0 || r.year == 30) {
        eprintln!("year {} N {:.0} BA {:.1} H100 {:.1} share_ba beech {:.2} birch {:.2}", r.year, r.stems_ha, r.basal_area_m2_ha, r.top_height_m, r.share_ba[0], r.share_ba[1]);
    }
    let (y30, y200) = (&rows[29], &rows[199]);
    // pool order: beech = 0, birch = 1
    assert!(y30.share_ba[1] > 0.5, "birch share of BA at year 30: {:.2}", y30.share_ba[1]);
    assert!(y200.share_ba[0] > 0.5, "beech share of BA at year 200: {:.2}", y200.share_ba[0]);
    assert!(y200.basal_area_m2_ha > 10.0, "closed forest expected, BA {:.1}", y200.basal_area_m2_ha);
}
