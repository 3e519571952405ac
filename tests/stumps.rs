//! Harvested areas in the pictures (issue 35, Build 4): a year whose management removed trees
//! gets a snapshot (so every harvested tree is in an inventory as `dead:harvest`), also when it
//! is off the `snapshot_every` schedule and across a stop and `--resume`; a picture of a later
//! year within 20 years draws a stump at every harvested tree (the stage's, the viewer's data
//! and its scene), and
//! the stumps show in a rendered picture (software adapter; without one the render part is
//! skipped unless `SYLVA_REQUIRE_ADAPTER` is set).
mod common;

use common::ScenarioToml;
use std::path::Path;
use sylva::job::inventory::{self, InventoryRow};
use sylva::job::pictures::{harvest_stumps, Stage};
use sylva::job::run::{run_scenario, RunOptions};
use sylva::job::scene::{self, Stump};
use sylva::render::camera::Camera;
use sylva::sim::Scenario;
use sylva::species::Season;

/// Year of the clear-cut: not a multiple of `snapshot_every` (10).
const CUT_YEAR: u32 = 7;

/// A 100 m × 100 m flat site of beech planted at 3 m, 40 years old at the start; the western
/// half (x < 50 m) clear-cut in year 7; 13 years, snapshots every 10.
fn scenario() -> Scenario {
    let toml = ScenarioToml::new("stumps", 13, 5).line("snapshot_every = 10").species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 3.0, 40.0).build()
        + &format!("[[management]]\nkind = \"harvest\"\nmethod = \"clear_cut\"\narea = [0.0, 0.0, 50.0, 100.0]\nyear = {CUT_YEAR}\n");
    Scenario::from_toml_str(&toml, "stumps.toml").unwrap()
}

fn harvested(dir: &Path, year: u32) -> Vec<InventoryRow> {
    let rows = inventory::read(&dir.join(format!("inventory/year_{year:04}.parquet"))).unwrap();
    rows.into_iter().filter(|r| r.status == "dead:harvest").collect()
}

#[test]
fn a_clear_cut_off_the_schedule_is_in_an_inventory_and_its_stumps_are_drawn() {
    let lib = common::embedded();
    let sc = scenario();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let run = run_scenario(&sc, sc.site().unwrap(), &lib, RunOptions::new(&dir)).unwrap();
    let cut_years: Vec<u32> = run.rows.iter().filter(|r| sylva::job::run::harvested(r)).map(|r| r.year).collect();
    assert_eq!(cut_years, vec![CUT_YEAR]);
    // the scheduled snapshots and the harvest's, nothing else
    let years: Vec<u32> = inventory::snapshots(&dir).unwrap().iter().map(|s| s.0).collect();
    assert_eq!(years, vec![0, CUT_YEAR, 10, 13]);
    assert!(dir.join(format!("maps/species_year_{CUT_YEAR:04}.png")).is_file(), "a harvest year's snapshot is a plain one, maps included");
    let cut = harvested(&dir, CUT_YEAR);
    let n_cut = run.rows[CUT_YEAR as usize - 1].deaths[sylva::sim::trees::DeathCause::Harvest.index()] as usize;
    assert_eq!(cut.len(), n_cut, "every harvested tree is in year {CUT_YEAR}'s inventory");
    assert!(cut.len() > 300, "{} trees cut on 0.5 ha of a 3 m planting", cut.len());
    assert!(cut.iter().all(|r| r.x_m < 50.0));
    assert!(cut.iter().all(|r| r.dbh_cm > 5.0), "40-year-old beech have DBHs");
    assert!(harvested(&dir, 10).is_empty() && harvested(&dir, 13).is_empty());
    // the stumps of a picture of year 12 (cut 5 years before) and of years before the cut
    let stumps = harvest_stumps(&dir, 12).unwrap();
    assert_eq!(stumps.len(), cut.len());
    for (s, r) in stumps.iter().zip(&cut) {
        assert_eq!((s.id, s.x_m, s.y_m, s.dbh_cm, s.year), (r.id, r.x_m, r.y_m, r.dbh_cm, CUT_YEAR));
    }
    assert!(harvest_stumps(&dir, CUT_YEAR - 1).unwrap().is_empty());
    assert_eq!(sylva::job::pictures::harvest_years(&dir), Some(vec![CUT_YEAR]));
    assert_eq!(harvest_stumps(&dir, CUT_YEAR).unwrap().len(), cut.len());
    // the viewer's year 12.4: the same stumps
    let site = sc.site().unwrap();
    let mut data = sylva::view::data::RunData::open(&dir, site.clone(), lib.clone(), vec!["beech".into()]).unwrap();
    assert_eq!(data.stumps_at(12.4).unwrap(), stumps);
    assert!(data.stumps_at(6.9).unwrap().is_empty());
    // the viewer at year 12 draws them (two instances each) besides its trees, at year 6 none
    let mut viewer = sylva::view::Viewer::new(sylva::view::data::RunData::open(&dir, site.clone(), lib.clone(), vec!["beech".into()]).unwrap(), 0.0, None).unwrap();
    viewer.set_year(12.0);
    viewer.refresh();
    let shown: Vec<_> = viewer.trees().iter().filter(|t| scene::is_stump(t)).collect();
    assert_eq!(shown.len(), 2 * stumps.len());
    assert!(viewer.trees().len() > shown.len(), "the trees of the uncut half too");
    viewer.set_year(6.0);
    viewer.refresh();
    assert!(!viewer.trees().iter().any(scene::is_stump));
    // without a stand table every inventory of the 20 years is read: the same stumps
    std::fs::rename(dir.join("stand_table.csv"), dir.join("stand_table.bak")).unwrap();
    assert_eq!(sylva::job::pictures::harvest_years(&dir), None);
    assert_eq!(harvest_stumps(&dir, 12).unwrap(), stumps);
    std::fs::rename(dir.join("stand_table.bak"), dir.join("stand_table.csv")).unwrap();
    // the instances: two per stump (bark, cut face), where the trees stood, on the ground
    let first = lib.species.len() as u32;
    let inst = scene::stump_instances(&stumps, 12, &site, first);
    assert_eq!(inst.len(), 2 * stumps.len());
    for (pair, s) in inst.chunks(2).zip(&stumps) {
        for t in pair {
            assert!(scene::is_stump(t));
            assert_eq!([t.position[0], t.position[1]], [s.x_m as f32, s.y_m as f32]);
            assert_eq!(t.position[2], site.elevation_at(s.x_m, s.y_m));
            let h = t.height * scene::STUMP_MODEL_TOP;
            assert!(h > 0.2 && h < scene::STUMP_HEIGHT_M, "weathered 5 years: {h} m");
            assert!(t.crown_radius >= 0.9 * (1.1 * s.dbh_cm / 200.0).max(scene::STUMP_MIN_RADIUS_M) && t.crown_radius <= 1.1 * s.dbh_cm / 200.0 + 1e-6);
            assert!(t.species >= first && t.species < first + scene::STUMP_PROTOTYPES as u32);
        }
    }
    render_check(&sc, &dir, &stumps);
}

/// Renders year 13 from 12 m above the cut half looking along it, with and without the stumps:
/// the stumps change pixels in the cut half only, brownish-grey ones (red ≥ blue).
fn render_check(sc: &Scenario, dir: &Path, stumps: &[Stump]) {
    let lib = common::embedded();
    let mut stage = match Stage::for_scenario(sc, sc.site().unwrap(), lib) {
        Ok(s) => s,
        Err(e) => {
            if std::env::var_os("SYLVA_REQUIRE_ADAPTER").is_some() {
                panic!("SYLVA_REQUIRE_ADAPTER is set but no adapter was found: {e}");
            }
            eprintln!("skipping the picture: {e}");
            return;
        }
    };
    stage.set_adapt(None);
    let rows = sylva::job::pictures::snapshot_rows(dir, 13).unwrap();
    let plants = scene::plants_from_rows(&rows);
    let (w, h) = (320, 240);
    let cam = Camera::look_at([25.0, 8.0, 212.0], [25.0, 40.0, 200.0], 50.0);
    stage.set_stumps(&[], 13);
    let bare = stage.render_plants(&plants, Season::Summer, &cam, w, h).unwrap();
    stage.set_stumps(stumps, 13);
    assert_eq!(stage.stump_instance_count(), 2 * stumps.len());
    let with = stage.render_plants(&plants, Season::Summer, &cam, w, h).unwrap();
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stumps");
    std::fs::create_dir_all(&out).unwrap();
    with.save(out.join("year_13_stumps.png")).unwrap();
    bare.save(out.join("year_13_bare.png")).unwrap();
    let mut changed = 0usize;
    let mut brownish = 0usize;
    for (a, b) in with.pixels().zip(bare.pixels()) {
        if a != b {
            changed += 1;
            if a[0] as i32 >= a[2] as i32 {
                brownish += 1;
            }
        }
    }
    eprintln!("{} stumps: {changed} pixels changed, {brownish} of them brownish or grey", stumps.len());
    assert!(changed > 500, "the stumps show: {changed} pixels changed");
    assert!(brownish as f64 > 0.8 * changed as f64, "{brownish} of {changed} changed pixels brownish or grey");
}

/// A run stopped right after the harvest year (its checkpoint's year) and resumed keeps the
/// harvest year's snapshot and ends byte for byte as the unbroken run.
#[test]
fn a_run_stopped_in_a_harvest_year_and_resumed_equals_the_unbroken_run() {
    let lib = common::embedded();
    let sc = scenario();
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    run_scenario(&sc, sc.site().unwrap(), &lib, RunOptions::new(&one)).unwrap();
    let split = tmp.path().join("split");
    let (stopped, _) = common::run_stopped_and_resumed(&sc, || sc.site().unwrap(), &lib, &split, CUT_YEAR - 1);
    assert_eq!(stopped, CUT_YEAR, "stopped in the harvest year");
    let (fa, fb) = (common::files(&one), common::files(&split));
    assert_eq!(fa.keys().collect::<Vec<_>>(), fb.keys().collect::<Vec<_>>());
    for (k, v) in &fa {
        assert!(v == &fb[k], "stopped after the harvest year and resumed: {k} differs");
    }
    assert!(fa.contains_key(&format!("inventory/year_{CUT_YEAR:04}.parquet")));
}
