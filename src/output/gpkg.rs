//! The tree inventory as a GeoPackage point layer (issue 34; OGC GeoPackage 1.3, the format and
//! the reading side in [`crate::gpkg`]): the schema, the DEM's CRS as an SRS row with its OGC
//! WKT 1, and the rows of the inventory CSV, written by SQLite into a temporary file that is
//! synced and renamed.

use super::georef::{utm_zone, KnownDatum, PointGeoRef, WGS84};
use super::parquet::{Kind, Table};
use crate::gpkg::{geometry_blob, quote, APPLICATION_ID, GEOMETRY_COLUMN, LAST_CHANGE, SCHEMA, USER_VERSION};
use rusqlite::{params, Connection};
use std::path::Path;

/// OGC WKT 1 (OGC 01-009) of a geographic CRS.
fn geogcs_wkt(d: &KnownDatum) -> String {
    format!(
        "GEOGCS[\"{}\",DATUM[\"{}\",SPHEROID[\"{}\",6378137,{},AUTHORITY[\"EPSG\",\"{}\"]],AUTHORITY[\"EPSG\",\"{}\"]],PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],AXIS[\"Latitude\",NORTH],AXIS[\"Longitude\",EAST],AUTHORITY[\"EPSG\",\"{}\"]]",
        d.name, d.wkt_datum, d.ellipsoid, d.inv_f, d.ellipsoid_code, d.datum_code, d.code
    )
}
/// The OGC WKT 1 definition (`gpkg_spatial_ref_sys.definition`, §1.1.2.1.1) of EPSG code
/// `code`, where Sylva can write it without PROJ: WGS 84 (4326) and the UTM zones of WGS 84,
/// NAD83 and ETRS89 ([`utm_zone`]); `None` for other codes.
pub fn wkt(code: u32) -> Option<String> {
    if code == 4326 {
        return Some(geogcs_wkt(&WGS84));
    }
    let (d, zone, north) = utm_zone(code)?;
    let hemi = if north { "N" } else { "S" };
    Some(format!(
        "PROJCS[\"{} / UTM zone {zone}{hemi}\",{},PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\",{}],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],PARAMETER[\"false_northing\",{}],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],AXIS[\"Northing\",NORTH],AUTHORITY[\"EPSG\",\"{code}\"]]",
        d.name,
        geogcs_wkt(&d),
        -183 + 6 * zone as i64,
        if north { 0 } else { 10_000_000 },
    ))
}
/// The SRS of points mapped by `geo`: (srs_id, srs_name, organization, organization_coordsys_id,
/// definition). An EPSG code gives `srs_id` = the code; a local grid the undefined Cartesian
/// SRS −1 (§1.1.2.1.2, Req 11).
fn srs_row(geo: &PointGeoRef) -> (i32, String, &'static str, i32, String) {
    match geo.epsg {
        Some(code) => {
            let name = match (code, utm_zone(code)) {
                (4326, _) => "WGS 84".to_string(),
                (_, Some((d, zone, north))) => format!("{} / UTM zone {zone}{}", d.name, if north { "N" } else { "S" }),
                _ => format!("EPSG:{code}"),
            };
            (code as i32, name, "EPSG", code as i32, wkt(code).unwrap_or_else(|| "undefined".into()))
        }
        None => (-1, "Undefined Cartesian SRS".into(), "NONE", -1, "undefined".into()),
    }
}
/// Writes the CSV text `csv` (header and rows of `table`, as Sylva writes them: the inventory)
/// as the GeoPackage `out` with one point layer named `table.name`, atomically (SQLite writes a
/// temporary file beside `out` that is synced and renamed, [`super::finish_temporary`];
/// nothing half-written at `out`). The layer's attribute columns are the table's, same names
/// and order (texts `TEXT`, integers `INTEGER`, `Double` columns `DOUBLE`, `Float` columns
/// `FLOAT`, each holding the CSV's decimal value), after `fid` and `geom`: the point
/// (`x_m`, `y_m`) mapped by `geo` into the DEM's CRS (`srs_id` as [`srs_row`]). `description`
/// goes to `gpkg_contents`.
///
/// Errors: I/O errors (the caller names `out`): a header other than `table`'s columns or a
/// value that does not parse (naming `what`, the CSV line and the column), SQLite failing
/// (its message).
pub fn csv_to_points(csv: impl std::io::Read, what: &str, out: &Path, table: &Table, geo: &PointGeoRef, description: &str) -> std::io::Result<()> {
    let tmp = crate::output::temporary_path(out);
    let _ = std::fs::remove_file(&tmp);
    let r = write_points(csv, what, &tmp, table, geo, description).and_then(|_| crate::output::finish_temporary(&tmp, out));
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}
fn write_points(csv: impl std::io::Read, what: &str, path: &Path, table: &Table, geo: &PointGeoRef, description: &str) -> std::io::Result<()> {
    let bad = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, m);
    let mut rdr = csv::Reader::from_reader(csv);
    let names = crate::output::parquet::check_header(&mut rdr, what, table)?;
    let ix = names.iter().position(|n| *n == "x_m").unwrap_or(0);
    let iy = names.iter().position(|n| *n == "y_m").unwrap_or(0);
    let mut db = Connection::open(path).map_err(|e| std::io::Error::other(format!("SQLite: {e}")))?;
    // SAFETY: the raw handle is only read by `sqlite3_system_errno`, while `db` is open (every
    // use of `sql` below comes before `db` is closed, or gets it back from a failed close).
    let handle = unsafe { db.handle() };
    let sql = |e: rusqlite::Error| system_error(e, handle);
    // atomicity comes from the rename: no journal, no syncs until the file is whole; pages of
    // 16 KiB (SQLite's default 4 KiB: the default run's year-150 layer 1.4 % larger; issue 34)
    db.execute_batch(&format!("PRAGMA page_size = 16384; PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; PRAGMA application_id = {APPLICATION_ID}; PRAGMA user_version = {USER_VERSION};")).map_err(sql)?;
    let tx = db.transaction().map_err(sql)?;
    tx.execute_batch(SCHEMA).map_err(sql)?;
    let (srs_id, srs_name, org, org_id, def) = srs_row(geo);
    if srs_id != 4326 {
        tx.execute("INSERT INTO gpkg_spatial_ref_sys VALUES ('WGS 84 geodetic', 4326, 'EPSG', 4326, ?1, 'longitude/latitude coordinates in decimal degrees on the WGS 84 spheroid')", [geogcs_wkt(&WGS84)]).map_err(sql)?;
    }
    if srs_id != -1 {
        tx.execute("INSERT INTO gpkg_spatial_ref_sys VALUES (?1, ?2, ?3, ?4, ?5, NULL)", params![srs_name, srs_id, org, org_id, def]).map_err(sql)?;
    }
    let cols: Vec<String> = table
        .columns
        .iter()
        .map(|c| {
            let (n, k) = (c.name, c.kind);
            let ty = match k {
                Kind::Int64 => "INTEGER",
                Kind::Utf8 => "TEXT",
                Kind::Double => "DOUBLE",
                Kind::Float => "FLOAT",
            };
            format!("{} {ty} NOT NULL", quote(n))
        })
        .collect();
    let t = quote(table.name);
    tx.execute_batch(&format!("CREATE TABLE {t} (fid INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, {GEOMETRY_COLUMN} POINT, {});", cols.join(", "))).map_err(sql)?;
    let mut bbox: Option<[f64; 4]> = None;
    {
        let marks: Vec<String> = (0..=table.columns.len()).map(|k| format!("?{}", k + 1)).collect();
        let names_sql: Vec<String> = std::iter::once(GEOMETRY_COLUMN.to_string()).chain(table.columns.iter().map(|c| quote(c.name))).collect();
        let mut ins = tx.prepare(&format!("INSERT INTO {t} ({}) VALUES ({})", names_sql.join(", "), marks.join(", "))).map_err(sql)?;
        let mut rec = csv::StringRecord::new();
        let mut line = 1usize;
        while rdr.read_record(&mut rec).map_err(|e| bad(format!("{what}: {e}")))? {
            line += 1;
            let num = |k: usize| -> std::io::Result<f64> { rec[k].parse::<f64>().map_err(|_| bad(format!("{what} line {line}: column {} is {:?}, expected a number", names[k], &rec[k]))) };
            let (mx, my) = geo.map(num(ix)?, num(iy)?);
            bbox = Some(match bbox {
                None => [mx, my, mx, my],
                Some(b) => [b[0].min(mx), b[1].min(my), b[2].max(mx), b[3].max(my)],
            });
            ins.raw_bind_parameter(1, geometry_blob(srs_id, mx, my)).map_err(sql)?;
            for (k, c) in table.columns.iter().enumerate() {
                let n = c.name;
                let r = match c.kind {
                    Kind::Int64 => ins.raw_bind_parameter(k + 2, rec[k].parse::<i64>().map_err(|_| bad(format!("{what} line {line}: column {n} is {:?}, expected an integer", &rec[k])))?),
                    Kind::Utf8 => ins.raw_bind_parameter(k + 2, &rec[k]),
                    Kind::Double | Kind::Float => ins.raw_bind_parameter(k + 2, num(k)?),
                };
                r.map_err(sql)?;
            }
            ins.raw_execute().map_err(sql)?;
        }
    }
    let b = bbox.map(|b| b.map(Some)).unwrap_or([None; 4]);
    tx.execute(
        "INSERT INTO gpkg_contents (table_name, data_type, identifier, description, last_change, min_x, min_y, max_x, max_y, srs_id) VALUES (?1, 'features', ?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
        params![table.name, description, LAST_CHANGE, b[0], b[1], b[2], b[3], srs_id],
    )
    .map_err(sql)?;
    tx.execute("INSERT INTO gpkg_geometry_columns VALUES (?1, ?2, 'POINT', ?3, 0, 0)", params![table.name, GEOMETRY_COLUMN, srs_id]).map_err(sql)?;
    tx.commit().map_err(sql)?;
    db.close().map_err(|(_, e)| sql(e))
}
/// The I/O error behind SQLite error `e` on connection `handle`: for an I/O failure, a full
/// disk or a file that cannot be opened, the operating system's error (`sqlite3_system_errno`:
/// "File too large", "No space left on device", …) with SQLite's message; otherwise SQLite's
/// message.
fn system_error(e: rusqlite::Error, handle: *mut rusqlite::ffi::sqlite3) -> std::io::Error {
    use rusqlite::ErrorCode::{CannotOpen, DiskFull, SystemIoFailure};
    if matches!(e.sqlite_error_code(), Some(SystemIoFailure | DiskFull | CannotOpen)) {
        // SAFETY: `handle` is an open connection (see `write_points`).
        let errno = unsafe { rusqlite::ffi::sqlite3_system_errno(handle) };
        if errno != 0 {
            let os = std::io::Error::from_raw_os_error(errno);
            return std::io::Error::new(os.kind(), format!("{os} (SQLite: {e})"));
        }
    }
    std::io::Error::other(format!("SQLite: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wkt_of_utm_and_wgs84() {
        let w = wkt(26917).unwrap();
        assert!(w.starts_with("PROJCS[\"NAD83 / UTM zone 17N\",GEOGCS[\"NAD83\"") && w.contains("PARAMETER[\"central_meridian\",-81]") && w.ends_with("AUTHORITY[\"EPSG\",\"26917\"]]"), "{w}");
        assert!(wkt(32733).unwrap().contains("PARAMETER[\"false_northing\",10000000]"));
        assert!(wkt(4326).unwrap().starts_with("GEOGCS[\"WGS 84\""));
        assert_eq!(wkt(2056), None);
    }
}
