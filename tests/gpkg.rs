//! GeoPackage files (issue 34: the final year's inventory as a GeoPackage layer; issue 35:
//! management areas from `area_file = "parcels.gpkg"`).
//!
//! - A run's `inventory/year_NNNN.gpkg`, read back with SQLite, holds the GeoPackage tables
//!   (OGC GeoPackage 1.3: application_id, user_version, SRS with the DEM's EPSG code and WKT,
//!   contents with bounds, geometry columns) and one feature per tree of the world with the
//!   attributes of the CSV inventory; GDAL's `ogrinfo` opens it with the same feature count and
//!   CRS, and GDAL's `validate_gpkg.py` finds nothing wrong (where python3-gdal ships it). Skipped (with a message) when `ogrinfo` is missing, unless `SYLVA_REQUIRE_OGRINFO` is
//!   set (CI sets it), in which case a missing `ogrinfo` fails the test.
//! - Plantings into the polygons of a GeoPackage plant only inside them: a file written here
//!   with SQLite (Polygon, MultiPolygon Z, big-endian WKB, envelopes), one GDAL wrote
//!   (`tests/data/gis/parcels_ogr.gpkg`, and one converted now by `ogr2ogr` when it is on the
//!   machine); bad files and fields are refused naming the file, field, layer and feature.
mod common;
use common::{in_poly, ScenarioToml};
use rusqlite::Connection;
use std::path::Path;
use std::process::Command;
use sylva::job::run::{run_scenario, RunOptions};
use sylva::sim::Scenario;

/// Whether GDAL's tool `tool` (`ogrinfo`, `ogr2ogr`) can be started; when it cannot and
/// `SYLVA_REQUIRE_OGRINFO` is set, panics.
fn gdal_tool(tool: &str) -> bool {
    let ok = Command::new(tool).arg("--version").output().is_ok_and(|o| o.status.success());
    if !ok && std::env::var_os("SYLVA_REQUIRE_OGRINFO").is_some() {
        panic!("{tool} not found but SYLVA_REQUIRE_OGRINFO is set (install gdal-bin)");
    }
    if !ok {
        println!("skipped: {tool} not found");
    }
    ok
}

/// `ogrinfo -so -al path`: (stdout, stderr), asserting success.
fn ogrinfo(path: &Path) -> (String, String) {
    let o = Command::new("ogrinfo").args(["-so", "-al"]).arg(path).output().unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned());
    assert!(o.status.success(), "ogrinfo failed on {}:\n{out}\n{err}", path.display());
    (out, err)
}

#[test]
fn final_inventory_geopackage_holds_every_tree_and_opens_in_gdal() {
    let toml = ScenarioToml::new("gpkg", 4, 7)
        .species(&["beech", "silver_birch"])
        .line("snapshot_every = 2")
        .default_terrain([10, 5, 12, 12])
        .planted("beech", 6.0, 20.0)
        .seed_rain("silver_birch", 800.0)
        .build();
    let sc = Scenario::from_toml_str(&toml, "gpkg").unwrap();
    let lib = common::embedded();
    let dir = tempfile::tempdir().unwrap();
    let mut o = RunOptions::new(dir.path());
    o.gpkg_years = Some(Vec::new());
    let sum = run_scenario(&sc, sc.site().unwrap(), &lib, o).unwrap();
    let inv = dir.path().join("inventory");
    assert!(!inv.join("year_0002.gpkg").exists() && !inv.join("year_0000.gpkg").exists(), "a GeoPackage for the final year only");
    let path = inv.join("year_0004.gpkg");
    assert!(!inv.join("year_0004.geojson").exists(), "no GeoJSON any more");
    let w = &sum.world;
    let geo = sylva::output::georef::PointGeoRef::of(w);
    let epsg = geo.epsg.expect("the default DEM has an EPSG code") as i64;

    let db = Connection::open(&path).unwrap();
    let pragma = |p: &str| db.query_row(&format!("PRAGMA {p}"), [], |r| r.get::<_, i64>(0)).unwrap();
    assert_eq!(pragma("application_id"), 0x4750_4B47, "application_id 'GPKG'");
    assert_eq!(pragma("user_version"), 10300);
    assert_eq!(db.query_row("PRAGMA integrity_check", [], |r| r.get::<_, String>(0)).unwrap(), "ok");
    assert_eq!(db.query_row("PRAGMA foreign_key_check", [], |r| r.get::<_, Option<String>>(0)).ok(), None, "no broken foreign keys");
    // the three required SRS rows and the DEM's, with its WKT
    let srs: Vec<(i64, String, i64, String)> = db.prepare("SELECT srs_id, organization, organization_coordsys_id, definition FROM gpkg_spatial_ref_sys ORDER BY srs_id").unwrap().query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))).unwrap().map(|r| r.unwrap()).collect();
    let ids: Vec<i64> = srs.iter().map(|s| s.0).collect();
    let mut want = vec![-1, 0, 4326, epsg];
    want.sort();
    assert_eq!(ids, want);
    let dem = srs.iter().find(|s| s.0 == epsg).unwrap();
    assert!(dem.1 == "EPSG" && dem.2 == epsg && dem.3.starts_with("PROJCS[") && dem.3.ends_with(&format!("AUTHORITY[\"EPSG\",\"{epsg}\"]]")), "{dem:?}");
    // contents and geometry columns
    let (name, kind, srs_id, b): (String, String, i64, [f64; 4]) = db
        .query_row("SELECT table_name, data_type, srs_id, min_x, min_y, max_x, max_y FROM gpkg_contents", [], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, [r.get(3)?, r.get(4)?, r.get(5)?, r.get(6)?])))
        .unwrap();
    assert_eq!((name.as_str(), kind.as_str(), srs_id), ("inventory", "features", epsg));
    let gc: (String, String, String, i64, i64, i64) = db.query_row("SELECT * FROM gpkg_geometry_columns", [], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?, r.get(5)?))).unwrap();
    assert_eq!(gc, ("inventory".into(), "geom".into(), "POINT".into(), epsg, 0, 0));

    // one feature per tree of the world (alive and this year's dead), the CSV's attributes
    let csv = sylva::output::inventory::inventory_csv(w);
    let mut rdr = csv::Reader::from_reader(csv.as_bytes());
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let recs: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert!(recs.len() > 50, "{} trees", recs.len());
    let cols: Vec<String> = db.prepare("PRAGMA table_info(inventory)").unwrap().query_map([], |r| r.get::<_, String>(1)).unwrap().map(|r| r.unwrap()).collect();
    assert_eq!(cols[..2], ["fid".to_string(), "geom".to_string()]);
    assert_eq!(cols[2..], header[..], "the inventory's columns, same names and order");
    let mut st = db.prepare(&format!("SELECT fid, geom, {} FROM inventory ORDER BY fid", header.join(", "))).unwrap();
    let mut rows = st.query([]).unwrap();
    let mut n = 0usize;
    let mut bb = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    while let Some(r) = rows.next().unwrap() {
        let rec = &recs[n];
        n += 1;
        assert_eq!(r.get::<_, i64>(0).unwrap(), n as i64, "fid 1, 2, … in inventory order");
        for (k, h) in header.iter().enumerate() {
            match h.as_str() {
                "id" => assert_eq!(r.get::<_, i64>(k + 2).unwrap().to_string(), rec[k]),
                "species" | "status" => assert_eq!(r.get::<_, String>(k + 2).unwrap(), rec[k]),
                _ => assert_eq!(r.get::<_, f64>(k + 2).unwrap(), rec[k].parse::<f64>().unwrap(), "{h} of tree {}", &rec[0]),
            }
        }
        let g: Vec<u8> = r.get(1).unwrap();
        assert_eq!((&g[..4], i32::from_le_bytes(g[4..8].try_into().unwrap()) as i64, g.len()), (&b"GP\x00\x01"[..], epsg, 29));
        let (x, y) = (f64::from_le_bytes(g[13..21].try_into().unwrap()), f64::from_le_bytes(g[21..29].try_into().unwrap()));
        let (mx, my) = geo.map(rec[2].parse().unwrap(), rec[3].parse().unwrap());
        assert!((x - mx).abs() < 1e-6 && (y - my).abs() < 1e-6, "tree {} at ({x}, {y}), expected ({mx}, {my})", &rec[0]);
        bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x), bb[3].max(y)];
    }
    assert_eq!(n, recs.len(), "one feature per tree");
    assert_eq!(b, bb, "gpkg_contents bounds");
    assert!((700_000.0..800_000.0).contains(&bb[0]) && (3_000_000.0..5_000_000.0).contains(&bb[1]), "UTM eastings/northings: {bb:?}");
    drop(rows);
    drop(st);
    drop(db);

    // deterministic: written again from the world, the same bytes
    let again = dir.path().join("again.gpkg");
    sylva::output::inventory::write_inventory_gpkg(&again, w).unwrap();
    assert!(std::fs::read(&again).unwrap() == std::fs::read(&path).unwrap(), "the GeoPackage's bytes depend on the trees only");
    assert!(std::fs::read_dir(&inv).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".tmp")), "no temporary left");

    // GDAL opens it: the feature count and the CRS
    if gdal_tool("ogrinfo") {
        let (out, err) = ogrinfo(&path);
        println!("{out}");
        assert!(!err.contains("ERROR") && !err.contains("Warning"), "ogrinfo complained: {err}");
        assert!(out.contains("using driver `GPKG'") && out.contains("Layer name: inventory") && out.contains("Geometry: Point"), "{out}");
        assert!(out.contains(&format!("Feature Count: {}", recs.len())), "{out}");
        assert!(out.contains(&format!("ID[\"EPSG\",{epsg}]]")) || out.contains(&format!("AUTHORITY[\"EPSG\",\"{epsg}\"]]")), "CRS EPSG:{epsg}: {out}");
        assert!(out.contains("species: String") && out.contains("dbh_cm: Real") && out.contains("id: Integer64"), "{out}");
        // GDAL's GeoPackage validator (python3-gdal, which gdal-bin depends on) checks the
        // standard's requirements one by one
        let script = ["/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py", "/usr/share/doc/python3-gdal/examples/validate_gpkg.py"].into_iter().map(Path::new).find(|p| p.is_file());
        match script {
            Some(s) => {
                let o = Command::new("python3").arg(s).arg(&path).output().unwrap();
                let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
                assert!(o.status.success() && text.trim().is_empty(), "validate_gpkg.py: {text}");
            }
            None => println!("skipped: GDAL's validate_gpkg.py not found"),
        }
    }
}

/// WKB of a polygon (outline, holes), 2-D, byte order `le`.
fn wkb_polygon(le: bool, rings: &[Vec<[f64; 2]>]) -> Vec<u8> {
    let u = |v: u32| if le { v.to_le_bytes() } else { v.to_be_bytes() };
    let mut b = vec![le as u8];
    b.extend_from_slice(&u(3));
    b.extend_from_slice(&u(rings.len() as u32));
    for r in rings {
        b.extend_from_slice(&u(r.len() as u32));
        for p in r {
            for c in p {
                b.extend_from_slice(&if le { c.to_le_bytes() } else { c.to_be_bytes() });
            }
        }
    }
    b
}

/// WKB of a LineString (0, 0)–(100, 100).
fn wkb_line() -> Vec<u8> {
    let mut b = vec![1u8];
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&2u32.to_le_bytes());
    for c in [0.0f64, 0.0, 100.0, 100.0] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b
}

/// WKB of a MultiPolygon Z (ISO type 1006) of one polygon at height `z`.
fn wkb_multipolygon_z(ring: &[[f64; 2]], z: f64) -> Vec<u8> {
    let mut b = vec![1u8];
    b.extend_from_slice(&1006u32.to_le_bytes());
    b.extend_from_slice(&1u32.to_le_bytes());
    b.push(1);
    b.extend_from_slice(&1003u32.to_le_bytes());
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&(ring.len() as u32).to_le_bytes());
    for p in ring {
        for c in [p[0], p[1], z] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b
}

/// GeoPackageBinary of `wkb` with srs_id `srs`, and an xy envelope when `envelope`.
fn blob(wkb: &[u8], srs: i32, envelope: bool) -> Vec<u8> {
    let mut b = b"GP\x00".to_vec();
    b.push(if envelope { 0b011 } else { 0b001 });
    b.extend_from_slice(&srs.to_le_bytes());
    if envelope {
        for v in [0.0f64, 200.0, 0.0, 200.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b.extend_from_slice(wkb);
    b
}

/// A GeoPackage written with plain SQL (independent of Sylva's writer): the layers
/// `(name, geometry type, srs_id, [(fid, parcel, n, geometry blob)])`.
fn write_gpkg(path: &Path, layers: &[(&str, &str, i32, Vec<(i64, &str, i64, Vec<u8>)>)]) {
    let db = Connection::open(path).unwrap();
    db.execute_batch(
        "PRAGMA application_id = 1196444487; PRAGMA user_version = 10300;
         CREATE TABLE gpkg_spatial_ref_sys (srs_name TEXT NOT NULL, srs_id INTEGER NOT NULL PRIMARY KEY, organization TEXT NOT NULL, organization_coordsys_id INTEGER NOT NULL, definition TEXT NOT NULL, description TEXT);
         INSERT INTO gpkg_spatial_ref_sys VALUES ('Undefined Cartesian SRS', -1, 'NONE', -1, 'undefined', NULL), ('Undefined geographic SRS', 0, 'NONE', 0, 'undefined', NULL), ('WGS 84', 4326, 'EPSG', 4326, 'GEOGCS[\"WGS 84\"]', NULL);
         CREATE TABLE gpkg_contents (table_name TEXT NOT NULL PRIMARY KEY, data_type TEXT NOT NULL, identifier TEXT UNIQUE, description TEXT DEFAULT '', last_change DATETIME NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')), min_x DOUBLE, min_y DOUBLE, max_x DOUBLE, max_y DOUBLE, srs_id INTEGER);
         CREATE TABLE gpkg_geometry_columns (table_name TEXT NOT NULL, column_name TEXT NOT NULL, geometry_type_name TEXT NOT NULL, srs_id INTEGER NOT NULL, z TINYINT NOT NULL, m TINYINT NOT NULL);",
    )
    .unwrap();
    for (name, ty, srs, feats) in layers {
        db.execute_batch(&format!("CREATE TABLE {name} (fid INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, shape {ty}, parcel TEXT, n INTEGER);")).unwrap();
        db.execute("INSERT INTO gpkg_contents (table_name, data_type, identifier, srs_id) VALUES (?1, 'features', ?1, ?2)", rusqlite::params![name, srs]).unwrap();
        db.execute("INSERT INTO gpkg_geometry_columns VALUES (?1, 'shape', ?2, ?3, 0, 0)", rusqlite::params![name, ty, srs]).unwrap();
        for (fid, parcel, n, g) in feats {
            db.execute(&format!("INSERT INTO {name} VALUES (?1, ?2, ?3, ?4)"), rusqlite::params![fid, g, parcel, n]).unwrap();
        }
    }
}

/// The parcels of the tests: a triangle A, a square B (a MultiPolygon Z) and a square with a
/// square hole C, on a 120 m × 120 m uniform site, in world metres (origin SW corner).
const TRI: [[f64; 2]; 3] = [[10.0, 10.0], [110.0, 20.0], [40.0, 100.0]];
const SQUARE: [[f64; 2]; 4] = [[70.0, 70.0], [115.0, 70.0], [115.0, 115.0], [70.0, 115.0]];

/// Ring `p` (world metres) closed, in the coordinates an area file of the 120 m site is in:
/// the outputs' (origin NW corner, y = world y − 120 m; `sim::management::crs_to_world`).
fn closed(p: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = p.iter().map(|q| [q[0], q[1] - 120.0]).collect();
    v.push(v[0]);
    v
}

/// The scenario planting the parcels of `file` (TOML `extra` after `area_file`).
fn planting(file: &Path, extra: &str) -> String {
    let base = ScenarioToml::new("parcels", 2, 3).species(&["beech", "sessile_oak"]).uniform(6, 6, 20.0, 200.0).build();
    format!("{base}[[management]]\nkind = \"planting\"\nmix = {{ beech = 0.5, sessile_oak = 0.5 }}\nspacing_m = 2.0\nage_yr = 4.0\nyear = 0\narea_file = {:?}\n{extra}", file.display().to_string())
}

/// Build the world of `toml`: the error's text, or the trees' positions.
fn plant(toml: &str) -> Result<Vec<(f64, f64)>, String> {
    let sc = Scenario::from_toml_str(toml, "parcels.toml").map_err(|e| e.to_string())?;
    let w = sylva::sim::World::new(sc.site().map_err(|e| e.to_string())?, &common::embedded(), &sc).map_err(|e| e.to_string())?;
    let t = &w.stand.trees;
    Ok((0..t.len()).map(|i| (t.x[i] as f64, t.y[i] as f64)).collect())
}

#[test]
fn polygon_planting_from_geopackage_plants_only_inside_its_polygons() {
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("parcels.gpkg");
    let hole = [[20.0, 20.0], [50.0, 20.0], [50.0, 50.0], [20.0, 50.0]];
    let outer = [[0.0, 0.0], [60.0, 0.0], [60.0, 60.0], [0.0, 60.0]];
    write_gpkg(
        &f,
        &[
            // a layer of lines first: a `layer` picks the parcels
            ("roads", "LINESTRING", -1, vec![(1, "road", 0, blob(&wkb_line(), -1, false))]),
            (
                "parcels",
                "GEOMETRY",
                -1,
                vec![
                    (7, "A", 1, blob(&wkb_polygon(false, &[closed(&TRI)]), -1, true)),
                    (9, "B", 2, blob(&wkb_multipolygon_z(&closed(&SQUARE), 300.0), -1, false)),
                    (12, "C", 3, blob(&wkb_polygon(true, &[closed(&outer), closed(&hole)]), -1, false)),
                ],
            ),
        ],
    );
    // parcel A by a text filter
    let a = plant(&planting(&f, "layer = \"parcels\"\nfilter = { property = \"parcel\", equals = \"A\" }\n")).unwrap();
    assert!(a.len() > 500, "{} trees planted in A", a.len());
    assert!(a.iter().all(|&(x, y)| in_poly(&TRI, x, y)), "a tree outside parcel A");
    // parcel B (MultiPolygon Z) by a number
    let b = plant(&planting(&f, "layer = \"parcels\"\nfilter = { property = \"n\", equals = 2 }\n")).unwrap();
    assert!(b.len() > 300 && b.iter().all(|&(x, y)| in_poly(&SQUARE, x, y)), "{} trees, all in B", b.len());
    // parcel C keeps its hole
    let c = plant(&planting(&f, "layer = \"parcels\"\nfilter = { property = \"parcel\", equals = \"C\" }\n")).unwrap();
    assert!(c.len() > 400 && c.iter().all(|&(x, y)| in_poly(&outer, x, y) && !in_poly(&hole, x, y)), "{} trees, all in C outside its hole", c.len());
    // all parcels
    let all = plant(&planting(&f, "layer = \"parcels\"\n")).unwrap();
    assert!(all.len() > c.len() && all.iter().all(|&(x, y)| in_poly(&TRI, x, y) || in_poly(&SQUARE, x, y) || (in_poly(&outer, x, y) && !in_poly(&hole, x, y))), "{} trees, all in the parcels", all.len());

    // errors name the file, the field, the layer and the feature
    let e = plant(&planting(&f, "")).unwrap_err();
    assert!(e.contains("parcels.toml") && e.contains("management[0].area_file") && e.contains("parcels.gpkg") && e.contains("layer `roads`") && e.contains("feature fid = 1") && e.contains("it is a LineString") && e.contains("Polygon or MultiPolygon"), "{e}");
    let e = plant(&planting(&f, "layer = \"fields\"\n")).unwrap_err();
    assert!(e.contains("management[0].area_file") && e.contains("a feature layer named `fields`") && e.contains("`roads`, `parcels`"), "{e}");
    let e = plant(&planting(&f, "layer = \"parcels\"\nfilter = { property = \"owner\", equals = \"x\" }\n")).unwrap_err();
    assert!(e.contains("column `owner`") && e.contains("`parcel`") && e.contains("`n`"), "{e}");
    let e = plant(&planting(&f, "layer = \"parcels\"\nfilter = { property = \"parcel\", equals = \"Z\" }\n")).unwrap_err();
    assert!(e.contains("equals \"Z\" (none does, of its 3 features)"), "{e}");
    let junk = d.path().join("junk.gpkg");
    std::fs::write(&junk, "not a database, just text that is long enough to be read as a header").unwrap();
    let e = plant(&planting(&junk, "")).unwrap_err();
    assert!(e.contains("management[0].area_file") && e.contains("junk.gpkg") && e.contains("GeoPackage"), "{e}");
    let e = plant(&planting(&d.path().join("missing.gpkg"), "")).unwrap_err();
    assert!(e.contains("missing.gpkg") && e.contains("no such file"), "{e}");
    let e = plant(&format!("{}layer = \"parcels\"\n", planting(&d.path().join("p.geojson"), ""))).unwrap_err();
    assert!(e.contains("management[0].layer") && e.contains("GeoPackage"), "{e}");
    // a broken geometry blob
    let broken = d.path().join("broken.gpkg");
    write_gpkg(&broken, &[("parcels", "POLYGON", -1, vec![(4, "A", 1, blob(&wkb_polygon(true, &[closed(&TRI)])[..30], -1, false))])]);
    let e = plant(&planting(&broken, "")).unwrap_err();
    assert!(e.contains("broken.gpkg") && e.contains("feature fid = 4") && e.contains("cut short"), "{e}");
    // a layer in another CRS than the DEM's is refused (the DEM in EPSG:26917)
    let wgs = d.path().join("wgs84.gpkg");
    write_gpkg(&wgs, &[("parcels", "POLYGON", 4326, vec![(1, "A", 1, blob(&wkb_polygon(true, &[closed(&TRI)]), 4326, false))])]);
    let e = sylva::sim::management::read_gpkg_polygons(&wgs, None, None, Some(26917), "x.toml", "management[0].area_file").unwrap_err().to_string();
    assert!(e.contains("EPSG:26917") && e.contains("EPSG:4326") && e.contains("ogr2ogr -t_srs"), "{e}");
    assert_eq!(sylva::sim::management::read_gpkg_polygons(&wgs, None, None, None, "x.toml", "f").unwrap().len(), 1);
    // srs_id 0 (the undefined geographic SRS: degrees) and an srs_id the file does not define
    // are refused, on a georeferenced DEM or not (both were read as the DEM's metres)
    for (srs, file, want) in [(0, "geo0.gpkg", "srs_id 0, the GeoPackage's undefined geographic SRS"), (999_999, "srs999999.gpkg", "srs_id 999999, which the file does not define")] {
        let f = d.path().join(file);
        write_gpkg(&f, &[("parcels", "POLYGON", srs, vec![(1, "A", 1, blob(&wkb_polygon(true, &[closed(&TRI)]), srs, false))])]);
        for dem in [Some(26917), None] {
            let e = sylva::sim::management::read_gpkg_polygons(&f, None, None, dem, "x.toml", "management[0].area_file").unwrap_err().to_string();
            assert!(e.contains(file) && e.contains("management[0].area_file") && e.contains("layer `parcels`") && e.contains(want), "{e}");
        }
    }
    // a CurvePolygon (ISO SQL/MM type 10) names the type and the types that are accepted
    let curved = d.path().join("curved.gpkg");
    let mut curve = vec![1u8];
    curve.extend_from_slice(&10u32.to_le_bytes());
    curve.extend_from_slice(&0u32.to_le_bytes());
    write_gpkg(&curved, &[("parcels", "CURVEPOLYGON", -1, vec![(3, "A", 1, blob(&curve, -1, false))])]);
    let e = plant(&planting(&curved, "")).unwrap_err();
    assert!(e.contains("management[0].area_file") && e.contains("curved.gpkg") && e.contains("feature fid = 3") && e.contains("it is a CurvePolygon") && e.contains("only geometry types an area is read from") && e.contains("ogr2ogr -nlt MULTIPOLYGON"), "{e}");
    // a NULL geometry names its feature (it was skipped without a word); left out by a filter
    // it is no matter
    let nulls = d.path().join("nulls.gpkg");
    write_gpkg(&nulls, &[("parcels", "POLYGON", -1, vec![(4, "A", 1, blob(&wkb_polygon(true, &[closed(&TRI)]), -1, false)), (5, "B", 2, Vec::new())])]);
    rusqlite::Connection::open(&nulls).unwrap().execute("UPDATE parcels SET shape = NULL WHERE fid = 5", []).unwrap();
    let e = plant(&planting(&nulls, "")).unwrap_err();
    assert!(e.contains("nulls.gpkg") && e.contains("layer `parcels`") && e.contains("feature fid = 5") && e.contains("the geometry is NULL"), "{e}");
    assert!(plant(&planting(&nulls, "filter = { property = \"parcel\", equals = \"A\" }\n")).unwrap().len() > 500);
    // a polygon wholly outside the site names the file, its feature, and both extents
    let outside = d.path().join("outside.gpkg");
    let north = [[10.0, 130.0], [50.0, 130.0], [50.0, 170.0], [10.0, 170.0]];
    write_gpkg(&outside, &[("parcels", "POLYGON", -1, vec![(1, "A", 1, blob(&wkb_polygon(true, &[closed(&TRI)]), -1, false)), (2, "B", 2, blob(&wkb_polygon(true, &[closed(&north)]), -1, false))])]);
    let e = plant(&planting(&outside, "")).unwrap_err();
    assert!(e.contains("outside.gpkg") && e.contains("polygon 1 of the file (layer `parcels`, feature 2) lies wholly outside") && e.contains("x 10.00–50.00, y 10.00–50.00") && e.contains("x 0.00–120.00, y -120.00–0.00"), "{e}");
}

/// Parcels as GDAL writes them: the committed `tests/data/gis/parcels_ogr.gpkg` (made by
/// `ogr2ogr` from `tests/data/gis/parcels_ogr.geojson`; see `tests/data/gis/README.md`) and, where
/// `ogr2ogr` is on the machine, the same GeoJSON converted now; the GeoPackage plants the trees
/// the GeoJSON plants.
#[test]
fn geopackages_written_by_gdal_plant_what_their_geojson_plants() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gis");
    let gj = data.join("parcels_ogr.geojson");
    let mut files = vec![data.join("parcels_ogr.gpkg")];
    let d = tempfile::tempdir().unwrap();
    if gdal_tool("ogr2ogr") {
        let out = d.path().join("converted.gpkg");
        let o = Command::new("ogr2ogr").args(["-f", "GPKG"]).arg(&out).arg(&gj).args(["-nln", "parcels"]).output().unwrap();
        assert!(o.status.success(), "ogr2ogr: {}", String::from_utf8_lossy(&o.stderr));
        files.push(out);
    }
    for filter in ["filter = { property = \"parcel\", equals = \"A\" }\n", "filter = { property = \"n\", equals = 2 }\n", ""] {
        let want = plant(&planting(&gj, filter)).unwrap();
        assert!(want.len() > 300, "{} trees from the GeoJSON", want.len());
        for f in &files {
            assert_eq!(plant(&planting(f, filter)).unwrap(), want, "{} with {filter:?}", f.display());
        }
    }
}

/// The shipped `scenarios/parcels.gpkg` (GDAL's conversion of `scenarios/parcels.geojson`)
/// holds the GeoJSON's polygons, in the DEM's CRS (NAD83 / UTM 17N, EPSG 26917), and
/// `scenarios/parcels.toml` names it.
#[test]
fn shipped_parcels_geopackage_equals_its_geojson() {
    use sylva::sim::management::{read_geojson_polygons, read_gpkg_polygons, AreaFilter};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    for parcel in ["north", "east", "central"] {
        let f = AreaFilter { property: "parcel".into(), equals: toml::Value::String(parcel.into()) };
        let g = read_gpkg_polygons(&dir.join("parcels.gpkg"), None, Some(&f), Some(26917), "parcels.toml", "area_file").unwrap();
        let j = read_geojson_polygons(&dir.join("parcels.geojson"), Some(&f), Some(26917), "parcels.toml", "area_file").unwrap();
        assert_eq!(g, j, "parcel {parcel}");
    }
    let sc = std::fs::read_to_string(dir.join("parcels.toml")).unwrap();
    assert!(sc.contains("area_file = \"parcels.gpkg\"") && !sc.contains("area_file = \"parcels.geojson\""));
}
