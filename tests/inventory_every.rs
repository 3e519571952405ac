//! `inventory_every` (issue 34): tree inventories and regeneration tables only every N years
//! (plus year 0, the last year, harvest years and a year stopped at), while the maps stay at
//! every snapshot. A stop at a snapshot year without an inventory writes one (so its state can
//! be viewed) and a resume removes it again; tiled runs write the same directory; the readers
//! offer the years that have an inventory and refuse the others, naming those that do.
mod common;
use std::path::Path;
use std::process::Command;
use sylva::job::run::{run_scenario, Progress, RunOptions};
use sylva::job::{inventory, pictures};
use sylva::sim::{fixtures, Scenario, World};

/// Beech planted at 3 m on a flat 100 m × 100 m site, 18 years: snapshots every 3 years,
/// inventories every 6, checkpoints every 4, a clear-cut of the western fifth in year 7 (not a
/// snapshot year) and of the next fifth in year 9 (a snapshot year without a scheduled inventory).
fn toml(years: u32) -> String {
    common::ScenarioToml::new("inventory_every", years, 5)
        .species(&["beech"])
        .line("snapshot_every = 3")
        .line("inventory_every = 6")
        .line("checkpoint_every = 4")
        .uniform(5, 5, 20.0, 200.0)
        .planted("beech", 3.0, 30.0)
        .build()
        + "[[management]]\nkind = \"harvest\"\nmethod = \"clear_cut\"\narea = [0.0, 0.0, 20.0, 100.0]\nyear = 7\n"
        // a harvest in a snapshot year that is not an inventory year (trial 46, defect 1)
        + "[[management]]\nkind = \"harvest\"\nmethod = \"clear_cut\"\narea = [20.0, 0.0, 40.0, 100.0]\nyear = 9\n"
}

fn scenario(years: u32) -> Scenario {
    Scenario::from_toml_str(&toml(years), "inventory_every.toml").unwrap()
}

fn run(sc: &Scenario, dir: &Path, resume: bool) -> sylva::job::run::RunSummary {
    let mut o = RunOptions::new(dir);
    o.map_px = 64;
    o.resume = resume;
    run_scenario(sc, sc.site().unwrap(), &fixtures::library(), o).unwrap()
}

/// The years of the files `sub/{prefix}NNNN{suffix}` in `dir`.
fn years(dir: &Path, sub: &str, prefix: &str, suffix: &str) -> Vec<u32> {
    let mut v: Vec<u32> = std::fs::read_dir(dir.join(sub))
        .unwrap()
        .filter_map(|e| {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            n.strip_prefix(prefix)?.strip_suffix(suffix)?.parse().ok()
        })
        .collect();
    v.sort();
    v
}

fn assert_same_files(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (common::files(a), common::files(b));
    assert_eq!(fa.keys().collect::<Vec<_>>(), fb.keys().collect::<Vec<_>>(), "{what}: different files");
    for (k, v) in &fa {
        assert!(v == &fb[k], "{what}: {k} differs");
    }
}

#[test]
fn inventories_every_n_years_maps_at_every_snapshot_same_with_tiles_stops_and_resumes() {
    let sc = scenario(18);
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let unbroken = run(&sc, &one, false);
    assert!(unbroken.rows.iter().any(|r| r.year == 7 && sylva::job::run::harvested(r)), "year 7 cut trees");
    assert!(unbroken.rows.iter().any(|r| r.year == 9 && sylva::job::run::harvested(r)), "year 9 cut trees");
    // tree inventories: year 0, every 6 years, the harvest years 7 and 9, the last year
    let inv = vec![0, 6, 7, 9, 12, 18];
    assert_eq!(years(&one, "inventory", "year_", ".parquet"), inv);
    assert_eq!(years(&one, "inventory", "year_", "_regeneration.parquet"), inv);
    // GeoPackages (every snapshot by default) only where there is an inventory
    assert_eq!(years(&one, "inventory", "year_", ".gpkg"), inv);
    // maps at every snapshot: every 3 years, the harvest year
    let snaps = vec![0, 3, 6, 7, 9, 12, 15, 18];
    assert_eq!(years(&one, "maps", "species_year_", ".png"), snaps);
    assert_eq!(years(&one, "maps", "basal_area_year_", ".tif"), snaps);
    assert_eq!(inventory::snapshots(&one).unwrap().iter().map(|s| s.0).collect::<Vec<_>>(), inv);
    let cut = inventory::read(&one.join("inventory/year_0007.parquet")).unwrap();
    assert!(cut.iter().any(|r| r.status == "dead:harvest"), "year 7's inventory holds the harvested trees");
    let cut9 = inventory::read(&one.join("inventory/year_0009.parquet")).unwrap();
    assert!(cut9.iter().any(|r| r.status == "dead:harvest" && r.x_m > 20.0), "year 9's inventory holds the trees cut in its strip");
    // the scenario as run keeps the field
    let as_run = std::fs::read_to_string(one.join("scenario.toml")).unwrap();
    assert!(as_run.contains("inventory_every = 6"));
    // the version that wrote the run (trial 46, defect 9)
    assert!(as_run.starts_with(&format!("# written by sylva {}", env!("CARGO_PKG_VERSION"))), "{as_run}");

    // the readers: a year with an inventory is read; a snapshot year without one is refused,
    // naming the field and the years that have one
    assert!(!pictures::snapshot_rows(&one, 12).unwrap().is_empty());
    let e = pictures::snapshot_rows(&one, 15).unwrap_err().to_string();
    assert!(e.contains("year 15") && e.contains("inventory_every") && e.contains("0, 6, 7, 9, 12, 18"), "{e}");
    let e = pictures::snapshot_rows(&one, 10).unwrap_err().to_string();
    assert!(e.contains("year 10") && e.contains("0, 6, 7, 9, 12, 18"), "{e}");
    // the viewer offers the years with an inventory
    let data = sylva::view::data::RunData::open(&one, sc.site().unwrap(), fixtures::library(), vec![]).unwrap();
    assert_eq!(data.years, inv);

    // 3 tiles write the same directory
    let lib = fixtures::library();
    let three = tmp.path().join("three");
    sylva::job::tiled::run_local_tiles(&sc, sc.site().unwrap(), &lib, RunOptions::new(&three), 3).unwrap();
    let template = World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    // (the tiled run's maps are 1024 px: compare with a one-process run of the same options)
    let one_1024 = tmp.path().join("one_1024");
    run_scenario(&sc, sc.site().unwrap(), &lib, RunOptions::new(&one_1024)).unwrap();
    common::assert_same_run(&one_1024, &three, &template, "one process and 3 tiles, inventory_every");

    // stopped in year 3 (maps, no inventory scheduled) and in year 8 (neither): the year
    // stopped at gets its inventory; the resumed run ends as the unbroken one
    for stop_year in [3, 8] {
        let d = tmp.path().join(format!("stop_{stop_year}"));
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let s2 = stop.clone();
        let mut cb = move |p: &Progress| {
            if p.year + 1 == stop_year {
                s2.store(true, std::sync::atomic::Ordering::SeqCst);
            }
        };
        let mut o = RunOptions::new(&d);
        o.map_px = 64;
        o.stop = Some(stop);
        o.progress = Some(&mut cb);
        let part = run_scenario(&sc, sc.site().unwrap(), &lib, o).unwrap();
        assert!(part.stopped && part.world.stand.year == stop_year);
        assert!(d.join(format!("inventory/year_{stop_year:04}.parquet")).is_file(), "stopped in {stop_year}: no inventory");
        assert!(d.join(format!("maps/species_year_{stop_year:04}.png")).is_file());
        let s = run(&sc, &d, true);
        assert_eq!(s.rows, unbroken.rows);
        assert_same_files(&one, &d, &format!("stopped in year {stop_year} and resumed"));
    }

    // a shorter run (its last year 15 has an inventory) extended to 18 years: year 15 keeps
    // its maps and loses its inventory, as in the unbroken run; on 3 tiles, then one process
    let d = tmp.path().join("extended");
    sylva::job::tiled::run_local_tiles(&scenario(15), scenario(15).site().unwrap(), &lib, { let mut o = RunOptions::new(&d); o.map_px = 64; o }, 3).unwrap();
    // (the tiles' snapshots partitioned: one part per rank, the GeoPackage's parts beside)
    assert!(d.join("inventory/year_0015/part-00002.parquet").is_file() && d.join("inventory/year_0015_gpkg/part-00000.gpkg").is_file());
    run(&sc, &d, true);
    assert!(!d.join("inventory/year_0015").exists() && !d.join("inventory/year_0015_gpkg").exists() && !d.join("inventory/year_0015_regeneration").exists());
    common::assert_same_outputs(&one, &d, "15 years on 3 tiles, extended to 18 in one process", |_| false);
}

#[test]
fn render_and_export_of_a_year_without_inventory_are_refused_naming_the_years() {
    let sc = scenario(18);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    run(&sc, &dir, false);
    let bin = env!("CARGO_BIN_EXE_sylva");
    let out = Command::new(bin).arg("render").arg(&dir).args(["--year", "15", "--out"]).arg(tmp.path().join("r.png")).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("year 15") && err.contains("inventory_every") && err.contains("0, 6, 7, 9, 12, 18"), "{err}");
    assert!(!tmp.path().join("r.png").exists());
    let out = Command::new(bin).arg("export").arg(&dir).args(["--year", "15", "--area", "0,0,50,50", "--out"]).arg(tmp.path().join("e.glb")).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("year 15") && err.contains("0, 6, 7, 9, 12, 18"), "{err}");
    assert!(!tmp.path().join("e.glb").exists());
}
