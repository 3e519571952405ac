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

/// A Parquet inventory as other tools write it (pandas/geopandas: optional columns; pyarrow's
/// default snappy compression) is read; a null in a column is refused naming the column.
#[test]
fn parquet_from_other_tools_optional_columns_and_snappy_is_read() {
    use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, FloatType, Int64Type};
    use std::sync::Arc;
    let tmp = tempfile::tempdir().unwrap();
    let write = |path: &std::path::Path, null_dbh: bool| {
        let schema = "message schema { optional int64 id; optional binary species (UTF8); optional double x_m; optional double y_m; optional double z_m; optional float age_yr; optional float height_m; optional float dbh_cm; optional float crown_radius_m; optional float crown_base_m; optional binary status (UTF8); }";
        let ty = Arc::new(parquet::schema::parser::parse_message_type(schema).unwrap());
        let props = Arc::new(parquet::file::properties::WriterProperties::builder().set_compression(parquet::basic::Compression::SNAPPY).build());
        let mut w = parquet::file::writer::SerializedFileWriter::new(std::fs::File::create(path).unwrap(), ty, props).unwrap();
        let mut rg = w.next_row_group().unwrap();
        let def = [1i16, 1];
        let mut k = 0;
        while let Some(mut c) = rg.next_column().unwrap() {
            match k {
                0 => c.typed::<Int64Type>().write_batch(&[4, 9], Some(&def), None).unwrap(),
                1 => c.typed::<ByteArrayType>().write_batch(&[ByteArray::from("beech"), ByteArray::from("oak")], Some(&def), None).unwrap(),
                10 => c.typed::<ByteArrayType>().write_batch(&[ByteArray::from("alive"), ByteArray::from("alive")], Some(&def), None).unwrap(),
                2..=4 => c.typed::<DoubleType>().write_batch(&[10.5, 20.25], Some(&def), None).unwrap(),
                7 if null_dbh => c.typed::<FloatType>().write_batch(&[30.0], Some(&[1, 0]), None).unwrap(),
                _ => c.typed::<FloatType>().write_batch(&[12.0, 30.0], Some(&def), None).unwrap(),
            };
            c.close().unwrap();
            k += 1;
        }
        rg.close().unwrap();
        w.close().unwrap();
    };
    let ok = tmp.path().join("year_0001.parquet");
    write(&ok, false);
    let rows = inventory::read(&ok).unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!((rows[1].id, rows[1].species.as_str(), rows[1].y_m, rows[1].dbh_cm), (9, "oak", 20.25, 30.0));
    let holes = tmp.path().join("year_0002.parquet");
    write(&holes, true);
    let e = inventory::read(&holes).unwrap_err().to_string();
    assert!(e.contains("year_0002.parquet") && e.contains("\"dbh_cm\"") && e.contains("null"), "{e}");
    assert_eq!(e.matches("year_0002.parquet").count(), 1, "the file is named once: {e}");
}

/// Values that cannot be a tree are refused on reading, in either format, naming the file, the
/// line or row, the column and what was expected (a single infinite crown radius used to empty
/// the far-field canopy of a render without a word).
#[test]
fn impossible_values_are_refused_naming_file_row_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let head = sylva::output::inventory::HEADER;
    let cases = [
        ("1,beech,10.00,20.00,500.00,30,12.00,15.00,inf,5.00,alive", "crown_radius_m", "line 2"),
        ("1,beech,10.00,20.00,500.00,30,12.00,NaN,2.00,5.00,alive", "dbh_cm", "line 2"),
        ("1,beech,10.00,20.00,500.00,30,1e30,15.00,2.00,5.00,alive", "height_m", "line 2"),
        ("1,beech,1e300,20.00,500.00,30,12.00,15.00,2.00,5.00,alive", "x_m", "line 2"),
        ("1,beech,10.00,20.00,500.00,30,12.00,15.00,2.00,5.00,zombie", "status", "line 2"),
    ];
    for (row, col, at) in cases {
        let csv = tmp.path().join("year_0003.csv");
        std::fs::write(&csv, format!("{head}\n{row}\n")).unwrap();
        let e = inventory::read(&csv).unwrap_err().to_string();
        assert!(e.contains("year_0003.csv") && e.contains(col) && e.contains(at) && e.contains("expected"), "{row}: {e}");
        // the same values in a Parquet file (the writer keeps what it is given)
        let pq = tmp.path().join("year_0003.parquet");
        let geo = sylva::output::inventory::PointGeoRef { x0: 0.0, y0: 0.0, per_m: (1.0, 1.0), epsg: None, degrees: false };
        sylva::output::parquet::csv_to_parquet(format!("{head}\n{row}\n").as_bytes(), "t", &pq, &sylva::output::parquet::INVENTORY, &geo).unwrap();
        let e = inventory::read(&pq).unwrap_err().to_string();
        assert!(e.contains("year_0003.parquet") && e.contains(col) && e.contains("row 1"), "{row}: {e}");
    }
}

/// A resumed run keeps its run directory's format: a CSV run extended by `--resume` (without
/// `--inventory csv`) writes its new snapshots as CSV, not a mix of both.
#[test]
fn a_resumed_csv_run_stays_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    run(&dir, InventoryFormat::Csv);
    let sc = Scenario::from_toml_str(&SC.replace("years = 6", "years = 9"), "formats").unwrap();
    let TerrainSpec::Uniform(u) = sc.terrain_spec() else { panic!() };
    let site = sylva::conditions::SiteConditions::uniform(u.width, u.height, u.cell_m, u.elevation_m, u.indices, sc.climate.latitude_deg);
    let mut o = RunOptions::new(&dir);
    o.map_px = 64;
    o.resume = true;
    let r = run_scenario(&sc, site, &fixtures::library(), o).unwrap();
    assert_eq!(r.world.stand.year, 9);
    let inv = dir.join("inventory");
    assert!(inv.join("year_0009.csv").is_file() && inv.join("year_0009_regeneration.csv").is_file());
    let parquet: Vec<_> = std::fs::read_dir(&inv).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).filter(|n| n.ends_with(".parquet")).collect();
    assert!(parquet.is_empty(), "{parquet:?}");
}
