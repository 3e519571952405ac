//! Inventories as GeoParquet by default and CSV on request (issue 34): the two formats hold the
//! same rows, the Parquet files carry GeoParquet 1.1 metadata, the readers take either, and a
//! run directory written as CSV (by `--inventory csv` or an earlier version) is still read.
use sylva::job::inventory;
use sylva::job::run::{run_scenario, RunOptions};
use sylva::output::inventory::InventoryFormat;
use sylva::sim::{fixtures, Scenario, TerrainSpec};

const SC: &str = r#"
name = "formats"
years = 6
seed = 3
snapshot_every = 3
[terrain]
uniform = { width = 6, height = 5, cell_m = 25.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "seed_sources"
species = "beech"
points = [[30.0, 30.0], [110.0, 80.0]]
trees_per_source = 12
"#;

fn run(dir: &std::path::Path, format: InventoryFormat) {
    let sc = Scenario::from_toml_str(SC, "formats").unwrap();
    let TerrainSpec::Uniform(u) = sc.terrain_spec() else { panic!() };
    let site = sylva::conditions::SiteConditions::uniform(u.width, u.height, u.cell_m, u.elevation_m, u.indices, sc.climate.latitude_deg);
    let mut o = RunOptions::new(dir);
    o.map_px = 64;
    o.inventory = format;
    run_scenario(&sc, site, &fixtures::library(), o).unwrap();
}

#[test]
fn parquet_and_csv_runs_hold_the_same_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let (pq, csv) = (tmp.path().join("pq"), tmp.path().join("csv"));
    run(&pq, InventoryFormat::Parquet);
    run(&csv, InventoryFormat::Csv);
    let names = |d: &std::path::Path| {
        let mut v: Vec<String> = std::fs::read_dir(d.join("inventory")).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    let (np, nc) = (names(&pq), names(&csv));
    assert!(np.contains(&"year_0006.parquet".to_string()) && np.contains(&"year_0006_regeneration.parquet".to_string()), "{np:?}");
    assert!(!np.iter().any(|n| n.ends_with(".csv")), "{np:?}");
    assert!(nc.contains(&"year_0006.csv".to_string()) && !nc.iter().any(|n| n.ends_with(".parquet")), "{nc:?}");
    // the same snapshots, found by the same reader
    let (sp, sc) = (inventory::snapshots(&pq).unwrap(), inventory::snapshots(&csv).unwrap());
    assert_eq!(sp.iter().map(|s| (s.0, s.1.clone())).collect::<Vec<_>>(), sc.iter().map(|s| (s.0, s.1.clone())).collect::<Vec<_>>());
    assert_eq!(sp.iter().filter(|s| s.1.is_empty()).map(|s| s.0).collect::<Vec<_>>(), vec![0, 3, 6]);
    let mut trees = 0;
    for (a, b) in sp.iter().zip(&sc) {
        let (ra, rb) = (inventory::read(&a.2).unwrap(), inventory::read(&b.2).unwrap());
        assert_eq!(ra, rb, "year {} {}: Parquet and CSV rows differ", a.0, a.1);
        trees += ra.len();
    }
    assert!(trees > 30, "the run has trees to compare: {trees}");
    let (ga, gb) = (inventory::read_regeneration(&pq, 6).unwrap().unwrap(), inventory::read_regeneration(&csv, 6).unwrap().unwrap());
    assert_eq!(ga, gb);
    // a filtered read streams the same rows out of either file
    let keep = |r: &inventory::InventoryRow| r.x_m < 70.0;
    let (fa, fb) = (inventory::read_filtered(&sp[sp.len() - 1].2, keep).unwrap(), inventory::read_filtered(&sc[sc.len() - 1].2, keep).unwrap());
    assert_eq!(fa, fb);
    assert!(!fa.is_empty() && fa.len() < inventory::read(&sp[sp.len() - 1].2).unwrap().len());
    // GeoParquet metadata: a local grid has no CRS (null: unknown), the points' bbox is set
    let g: serde_json::Value = serde_json::from_str(&sylva::output::parquet::geo_key(&pq.join("inventory/year_0006.parquet")).unwrap().unwrap()).unwrap();
    assert_eq!(g["version"], "1.1.0");
    assert_eq!(g["columns"]["geometry"]["encoding"], "WKB");
    assert!(g["columns"]["geometry"]["crs"].is_null(), "{g}");
    let bbox: Vec<f64> = g["columns"]["geometry"]["bbox"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let rows = inventory::read(&pq.join("inventory/year_0006.parquet")).unwrap();
    let xmin = rows.iter().map(|r| r.x_m).fold(f64::INFINITY, f64::min);
    assert!((bbox[0] - xmin).abs() < 1e-9, "bbox {bbox:?} against x min {xmin}");
    // the Parquet files are smaller than the CSV
    let size = |p: std::path::PathBuf| std::fs::metadata(p).unwrap().len();
    assert!(size(pq.join("inventory/year_0006.parquet")) < size(csv.join("inventory/year_0006.csv")) + 4096);
}

#[test]
fn a_damaged_parquet_inventory_is_an_error_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let inv = tmp.path().join("inventory");
    std::fs::create_dir_all(&inv).unwrap();
    std::fs::write(inv.join("year_0001.parquet"), b"PAR1 not really").unwrap();
    let snaps = inventory::snapshots(tmp.path()).unwrap();
    assert_eq!(snaps.len(), 1);
    let e = inventory::read(&snaps[0].2).unwrap_err().to_string();
    assert!(e.contains("year_0001.parquet"), "{e}");
    // a Parquet file without the inventory's columns names the missing column
    let reg = inv.join("year_0002.parquet");
    sylva::output::parquet::csv_to_parquet(format!("{}\n", sylva::output::inventory::REGENERATION_HEADER).as_bytes(), "t", &reg, &sylva::output::parquet::REGENERATION, &sylva::output::inventory::PointGeoRef { x0: 0.0, y0: 0.0, per_m: (1.0, 1.0), epsg: None, degrees: false }).unwrap();
    let e = inventory::read(&reg).unwrap_err().to_string();
    assert!(e.contains("year_0002.parquet") && e.contains("\"id\""), "{e}");
}
