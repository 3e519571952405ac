//! Tables of a run as Apache Parquet files with GeoParquet 1.1 metadata (issue 34): the tree
//! inventory and the regeneration layer of every snapshot, so that pandas/geopandas, R
//! (`arrow`, `sfarrow`), DuckDB and QGIS read them directly.
//!
//! A file holds the columns of the CSV table of the same name (names, types and units as
//! [`super::schema`] gives them; the values are the CSV's, so a
//! Parquet and a CSV run hold the same numbers), zstd-compressed, in row groups of
//! [`ROW_GROUP_ROWS`] rows, plus a `geometry` column: the point (`x_m`, `y_m`) in the DEM's
//! coordinate reference system as WKB (ISO 19125 well-known binary, little-endian 2-D point),
//! described by the `geo` key of the file's metadata (GeoParquet 1.1: version, primary column,
//! encoding `WKB`, geometry type `Point`, bbox, and the CRS as PROJJSON where Sylva knows it:
//! WGS 84 and the UTM zones of WGS 84, NAD83 and ETRS89 ([`projjson`]); `null`, "unknown", for other codes and
//! for local grids, with the EPSG code, when there is one, under `sylva:epsg`).
//!
//! The files are made from the CSV text of the table ([`csv_to_parquet`]); a tiled run's ranks
//! each write their own part this way (`inventory/year_NNNN/part-RRRRR.parquet`, each with its
//! own `geo` metadata and bounding box).

use super::georef::PointGeoRef;
use super::Result;
use parquet::basic::{Compression, ZstdLevel};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, FloatType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::file::metadata::KeyValue;
use std::path::Path;
use std::sync::Arc;

/// Rows per row group (a reader holds one row group of a column at a time).
pub const ROW_GROUP_ROWS: usize = 131_072;

/// zstd level of the pages. 6 (issue 34, disk): the default run's year-150 inventory is 7 %
/// smaller than at zstd's default 3 (23.7 against 25.4 MB, same encodings) for twice the
/// compression time (0.9 s); 9 and 12 saved 0.5 and 2.3 % more for 1.6 and 3.9 times the time
/// of 6 (BENCHMARKS.md, round 22).
const ZSTD_LEVEL: i32 = 6;

/// Columns written with `DELTA_BINARY_PACKED` and no dictionary: integers in ascending order
/// (tree ids; the regeneration layer's light cells), whose differences are small.
const DELTA_COLUMNS: [&str; 2] = ["id", "cell"];

/// Columns written as plain values without a dictionary: positions (`x_m`, `y_m`, `z_m` and the
/// `geometry` points), nearly every value distinct, so a dictionary costs more than it saves;
/// the plain values compress by the id order's spatial locality. Every other column keeps a
/// dictionary (species, status, sizes, ages, stem counts: few distinct values).
const PLAIN_COLUMNS: [&str; 4] = ["x_m", "y_m", "z_m", "geometry"];

/// The writer properties of a table (zstd at [`ZSTD_LEVEL`], encodings by column:
/// [`DELTA_COLUMNS`], [`PLAIN_COLUMNS`], a dictionary for the others). Sizes of the default
/// run's year-150 inventory (1.03 M trees): 30.9 MB with dictionaries everywhere at zstd 3 as
/// before, 23.7 MB so, the same values (BENCHMARKS.md, round 22).
fn writer_properties(table: &Table) -> std::io::Result<WriterProperties> {
    use parquet::basic::Encoding;
    use parquet::schema::types::ColumnPath;
    let mut b = WriterProperties::builder()
        .set_compression(Compression::ZSTD(ZstdLevel::try_new(ZSTD_LEVEL).map_err(std::io::Error::other)?))
        .set_created_by(format!("sylva {}", env!("CARGO_PKG_VERSION")));
    for name in table.columns.iter().map(|c| c.name).chain(["geometry"]) {
        let path = ColumnPath::from(name);
        if DELTA_COLUMNS.contains(&name) {
            b = b.set_column_dictionary_enabled(path.clone(), false).set_column_encoding(path, Encoding::DELTA_BINARY_PACKED);
        } else if PLAIN_COLUMNS.contains(&name) {
            b = b.set_column_dictionary_enabled(path, false);
        }
    }
    Ok(b.build())
}

pub use super::schema::{Kind, Table, INVENTORY, REGENERATION};

/// One column's values while a row group fills.
enum Col {
    I(Vec<i64>),
    S(Vec<ByteArray>),
    D(Vec<f64>),
    F(Vec<f32>),
}

impl Col {
    fn of(k: Kind) -> Col {
        match k {
            Kind::Int64 => Col::I(Vec::new()),
            Kind::Utf8 => Col::S(Vec::new()),
            Kind::Double => Col::D(Vec::new()),
            Kind::Float => Col::F(Vec::new()),
        }
    }
}

/// The Parquet schema of `t` (every column required, plus `geometry` as binary).
fn schema(t: &Table) -> String {
    let mut s = format!("message {} {{\n", t.name);
    for c in t.columns {
        let (name, k) = (c.name, c.kind);
        let ty = match k {
            Kind::Int64 => "int64",
            Kind::Utf8 => "binary",
            Kind::Double => "double",
            Kind::Float => "float",
        };
        let ann = if k == Kind::Utf8 { " (UTF8)" } else { "" };
        s.push_str(&format!("  required {ty} {name}{ann};\n"));
    }
    s.push_str("  required binary geometry;\n}\n");
    s
}

/// A 2-D point as ISO WKB, little-endian: byte order 1, type 1 (Point), x, y.
fn wkb_point(x: f64, y: f64) -> ByteArray {
    let mut b = Vec::with_capacity(21);
    b.push(1u8);
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&x.to_le_bytes());
    b.extend_from_slice(&y.to_le_bytes());
    ByteArray::from(b)
}

/// The CRS of `geo` as PROJJSON (PROJ's JSON encoding of ISO 19111), where Sylva can write it
/// without PROJ: WGS 84 (EPSG 4326), and the UTM zones of WGS 84 (EPSG 32601–32660 north,
/// 32701–32760 south), NAD83 (EPSG 26901–26923) and ETRS89 (EPSG 25828–25838); `None`
/// otherwise. UTM: Transverse Mercator, central meridian 6·zone − 183°, scale 0.9996, false
/// easting 500 000 m, false northing 0 (10 000 000 m south).
pub fn projjson(geo: &PointGeoRef) -> Option<serde_json::Value> {
    use super::georef::{utm_zone, KnownDatum, WGS84};
    use serde_json::json;
    let geographic = |d: KnownDatum| {
        json!({
            "type": "GeographicCRS", "name": d.name,
            "datum": {"type": "GeodeticReferenceFrame", "name": d.datum, "ellipsoid": {"name": d.ellipsoid, "semi_major_axis": 6378137, "inverse_flattening": d.inv_f}},
            "coordinate_system": {"subtype": "ellipsoidal", "axis": [
                {"name": "Geodetic latitude", "abbreviation": "Lat", "direction": "north", "unit": "degree"},
                {"name": "Geodetic longitude", "abbreviation": "Lon", "direction": "east", "unit": "degree"}]},
            "id": {"authority": "EPSG", "code": d.code}
        })
    };
    let schema = json!("https://proj.org/schemas/v0.7/projjson.schema.json");
    let code = geo.epsg?;
    if geo.degrees {
        return (code == 4326).then(|| {
            let mut g = geographic(WGS84);
            g["$schema"] = schema;
            g
        });
    }
    let (base, zone, north) = utm_zone(code)?;
    let lon0 = -183.0 + 6.0 * zone as f64;
    let hemi = if north { "N" } else { "S" };
    Some(json!({
        "$schema": schema,
        "type": "ProjectedCRS",
        "name": format!("{} / UTM zone {zone}{hemi}", base.name),
        "base_crs": geographic(base),
        "conversion": {
            "name": format!("UTM zone {zone}{hemi}"),
            "method": {"name": "Transverse Mercator", "id": {"authority": "EPSG", "code": 9807}},
            "parameters": [
                {"name": "Latitude of natural origin", "value": 0, "unit": "degree", "id": {"authority": "EPSG", "code": 8801}},
                {"name": "Longitude of natural origin", "value": lon0, "unit": "degree", "id": {"authority": "EPSG", "code": 8802}},
                {"name": "Scale factor at natural origin", "value": 0.9996, "unit": "unity", "id": {"authority": "EPSG", "code": 8805}},
                {"name": "False easting", "value": 500000, "unit": "metre", "id": {"authority": "EPSG", "code": 8806}},
                {"name": "False northing", "value": if north { 0 } else { 10_000_000 }, "unit": "metre", "id": {"authority": "EPSG", "code": 8807}}
            ]
        },
        "coordinate_system": {"subtype": "Cartesian", "axis": [
            {"name": "Easting", "abbreviation": "E", "direction": "east", "unit": "metre"},
            {"name": "Northing", "abbreviation": "N", "direction": "north", "unit": "metre"}]},
        "id": {"authority": "EPSG", "code": code}
    }))
}

/// The GeoParquet 1.1 `geo` metadata of a file whose points span `bbox` = [xmin, ymin, xmax,
/// ymax] (map units; `None` for a file without rows).
fn geo_metadata(geo: &PointGeoRef, bbox: Option<[f64; 4]>) -> String {
    let mut col = serde_json::json!({"encoding": "WKB", "geometry_types": ["Point"], "crs": projjson(geo)});
    if let Some(b) = bbox {
        col["bbox"] = serde_json::json!(b);
    }
    if let Some(code) = geo.epsg {
        col["sylva:epsg"] = serde_json::json!(code);
    }
    serde_json::json!({"version": "1.1.0", "primary_column": "geometry", "columns": {"geometry": col}}).to_string()
}

/// The column names of `table` after checking that the header of the CSV `rdr` (of `what`)
/// names them, in order.
///
/// Errors: `InvalidData` naming `what`, the header found and the one expected.
pub fn check_header<R: std::io::Read>(rdr: &mut csv::Reader<R>, what: &str, table: &Table) -> std::io::Result<Vec<&'static str>> {
    let header = rdr.headers().map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{what}: {e}")))?.clone();
    let names: Vec<&'static str> = table.columns.iter().map(|c| c.name).collect();
    if header.iter().collect::<Vec<_>>() != names {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{what}: header {:?}, expected {:?}", header.iter().collect::<Vec<_>>(), names)));
    }
    Ok(names)
}

/// Writes the CSV text `csv` (header and rows of `table`, as Sylva writes them) as the Parquet
/// file `out`, atomically (a temporary file renamed; nothing half-written at `out`), with the
/// GeoParquet `geo` metadata of `geo`. Streams: one row group in memory.
///
/// Errors: [`super::OutputError::Io`] naming `out`: a header other than `table`'s columns, a
/// value that does not parse (naming the CSV line and column, `what` naming the source), or
/// the file not written.
pub fn csv_to_parquet(csv: impl std::io::Read, what: &str, out: &Path, table: &Table, geo: &PointGeoRef) -> Result<()> {
    let bad = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, m);
    crate::output::write_atomic_with(out, |f| {
        let mut rdr = csv::Reader::from_reader(csv);
        let names = check_header(&mut rdr, what, table)?;
        let ix = names.iter().position(|n| *n == "x_m").unwrap_or(0);
        let iy = names.iter().position(|n| *n == "y_m").unwrap_or(0);
        let ty = Arc::new(parquet::schema::parser::parse_message_type(&schema(table)).map_err(std::io::Error::other)?);
        let props = writer_properties(table)?;
        let mut w = SerializedFileWriter::new(f, ty, Arc::new(props)).map_err(std::io::Error::other)?;
        let mut cols: Vec<Col> = table.columns.iter().map(|c| Col::of(c.kind)).collect();
        let mut geom: Vec<ByteArray> = Vec::new();
        let mut bbox: Option<[f64; 4]> = None;
        let mut rec = csv::StringRecord::new();
        let mut line = 1usize;
        let mut rows = 0usize;
        loop {
            let more = rdr.read_record(&mut rec).map_err(|e| bad(format!("{what}: {e}")))?;
            if more {
                line += 1;
                let num = |k: usize| -> std::io::Result<f64> { rec[k].parse::<f64>().map_err(|_| bad(format!("{what} line {line}: column {} is {:?}, expected a number", names[k], &rec[k]))) };
                for (k, c) in cols.iter_mut().enumerate() {
                    match c {
                        Col::I(v) => v.push(rec[k].parse::<i64>().map_err(|_| bad(format!("{what} line {line}: column {} is {:?}, expected an integer", names[k], &rec[k])))?),
                        Col::S(v) => v.push(ByteArray::from(rec[k].as_bytes().to_vec())),
                        Col::D(v) => v.push(num(k)?),
                        // parsed as f32, as the CSV reader does (not rounded twice through f64)
                        Col::F(v) => v.push(rec[k].parse::<f32>().map_err(|_| bad(format!("{what} line {line}: column {} is {:?}, expected a number", names[k], &rec[k])))?),
                    }
                }
                let (mx, my) = geo.map(num(ix)?, num(iy)?);
                geom.push(wkb_point(mx, my));
                bbox = Some(match bbox {
                    None => [mx, my, mx, my],
                    Some(b) => [b[0].min(mx), b[1].min(my), b[2].max(mx), b[3].max(my)],
                });
                rows += 1;
            }
            if rows == ROW_GROUP_ROWS || (!more && (rows > 0 || w.flushed_row_groups().is_empty())) {
                let mut rg = w.next_row_group().map_err(std::io::Error::other)?;
                for c in cols.iter_mut() {
                    let mut cw = rg.next_column().map_err(std::io::Error::other)?.ok_or_else(|| std::io::Error::other("schema: fewer columns than the table"))?;
                    let r = match c {
                        Col::I(v) => cw.typed::<Int64Type>().write_batch(v, None, None).map(|_| v.clear()),
                        Col::S(v) => cw.typed::<ByteArrayType>().write_batch(v, None, None).map(|_| v.clear()),
                        Col::D(v) => cw.typed::<DoubleType>().write_batch(v, None, None).map(|_| v.clear()),
                        Col::F(v) => cw.typed::<FloatType>().write_batch(v, None, None).map(|_| v.clear()),
                    };
                    r.map_err(std::io::Error::other)?;
                    cw.close().map_err(std::io::Error::other)?;
                }
                let mut cw = rg.next_column().map_err(std::io::Error::other)?.ok_or_else(|| std::io::Error::other("schema: no geometry column"))?;
                cw.typed::<ByteArrayType>().write_batch(&geom, None, None).map_err(std::io::Error::other)?;
                cw.close().map_err(std::io::Error::other)?;
                geom.clear();
                rg.close().map_err(std::io::Error::other)?;
                rows = 0;
            }
            if !more {
                break;
            }
        }
        w.append_key_value_metadata(KeyValue::new("geo".to_string(), geo_metadata(geo, bbox)));
        w.close().map_err(std::io::Error::other)?;
        Ok(())
    })
}

/// The columns of a Parquet table read back: one vector per column of the table, by name.
#[derive(Debug, Default)]
pub struct Columns {
    /// Int64 columns.
    pub ints: Vec<(String, Vec<i64>)>,
    /// UTF-8 columns.
    pub texts: Vec<(String, Vec<String>)>,
    /// Double columns.
    pub doubles: Vec<(String, Vec<f64>)>,
    /// Float columns.
    pub floats: Vec<(String, Vec<f32>)>,
    /// Rows.
    pub rows: usize,
}

impl Columns {
    /// The int64 column `name`.
    pub fn int(&self, name: &str) -> Option<&[i64]> {
        self.ints.iter().find(|c| c.0 == name).map(|c| c.1.as_slice())
    }
    /// The text column `name`.
    pub fn text(&self, name: &str) -> Option<&[String]> {
        self.texts.iter().find(|c| c.0 == name).map(|c| c.1.as_slice())
    }
    /// The double column `name`.
    pub fn double(&self, name: &str) -> Option<&[f64]> {
        self.doubles.iter().find(|c| c.0 == name).map(|c| c.1.as_slice())
    }
    /// The float column `name`.
    pub fn float(&self, name: &str) -> Option<&[f32]> {
        self.floats.iter().find(|c| c.0 == name).map(|c| c.1.as_slice())
    }
}

/// Reads the columns of `table` from the Parquet file `path` (any other columns, `geometry`
/// included, are skipped), row group by row group.
///
/// Errors: [`super::OutputError::Io`] naming `path`: the file cannot be read, is not Parquet, or
/// lacks a column of `table` or has it with another type (named, with the expected type).
pub fn read_table(path: &Path, table: &Table) -> Result<Columns> {
    let res = (|| -> std::io::Result<Columns> {
        let bad = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, m);
        let file = std::fs::File::open(path)?;
        let reader = SerializedFileReader::new(file).map_err(|e| bad(format!("not a Parquet file ({e})")))?;
        let schema = reader.metadata().file_metadata().schema_descr_ptr();
        let mut idx = Vec::new();
        for c in table.columns {
            let (name, kind) = (&c.name, c.kind);
            let i = (0..schema.num_columns()).find(|&i| schema.column(i).name() == *name).ok_or_else(|| bad(format!("no column {name:?} (expected the columns of ARCHITECTURE.md's {} table)", table.name)))?;
            let phys = schema.column(i).physical_type();
            let want = match kind {
                Kind::Int64 => parquet::basic::Type::INT64,
                Kind::Utf8 => parquet::basic::Type::BYTE_ARRAY,
                Kind::Double => parquet::basic::Type::DOUBLE,
                Kind::Float => parquet::basic::Type::FLOAT,
            };
            if phys != want {
                return Err(bad(format!("column {name:?} is {phys}, expected {want}")));
            }
            idx.push(i);
        }
        let mut out = Columns::default();
        for (c, _) in table.columns.iter().zip(&idx) {
            let name = c.name;
            match c.kind {
                Kind::Int64 => out.ints.push((name.to_string(), Vec::new())),
                Kind::Utf8 => out.texts.push((name.to_string(), Vec::new())),
                Kind::Double => out.doubles.push((name.to_string(), Vec::new())),
                Kind::Float => out.floats.push((name.to_string(), Vec::new())),
            }
        }
        for g in 0..reader.num_row_groups() {
            let rg = reader.get_row_group(g).map_err(std::io::Error::other)?;
            let n = rg.metadata().num_rows() as usize;
            for (c, &i) in table.columns.iter().zip(&idx) {
                let (name, kind) = (&c.name, c.kind);
                let cr = rg.get_column_reader(i).map_err(std::io::Error::other)?;
                let max_def = schema.column(i).max_def_level();
                match kind {
                    Kind::Int64 => {
                        let v = read_column::<Int64Type>(cr, n, name, g, max_def)?;
                        out.ints.iter_mut().filter(|c| c.0 == *name).for_each(|c| c.1.extend_from_slice(&v));
                    }
                    Kind::Utf8 => {
                        let mut texts = Vec::with_capacity(n);
                        for b in read_column::<ByteArrayType>(cr, n, name, g, max_def)? {
                            texts.push(String::from_utf8(b.data().to_vec()).map_err(|_| bad(format!("column {name:?}: not UTF-8 text")))?);
                        }
                        out.texts.iter_mut().filter(|c| c.0 == *name).for_each(|c| c.1.append(&mut texts));
                    }
                    Kind::Double => {
                        let v = read_column::<DoubleType>(cr, n, name, g, max_def)?;
                        out.doubles.iter_mut().filter(|c| c.0 == *name).for_each(|c| c.1.extend_from_slice(&v));
                    }
                    Kind::Float => {
                        let v = read_column::<FloatType>(cr, n, name, g, max_def)?;
                        out.floats.iter_mut().filter(|c| c.0 == *name).for_each(|c| c.1.extend_from_slice(&v));
                    }
                }
            }
            out.rows += n;
        }
        Ok(out)
    })();
    res.map_err(|e| super::OutputError::io(path, e))
}

/// The `n` values of row group `g`'s chunk of the required column `name`, read by `cr`.
///
/// Errors: `InvalidData` when the chunk holds fewer values.
fn read_column<T: parquet::data_type::DataType>(cr: parquet::column::reader::ColumnReader, n: usize, name: &str, g: usize, max_def: i16) -> std::io::Result<Vec<T::T>> {
    let bad = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("column {name:?}: {m}"));
    let mut v = Vec::with_capacity(n);
    // optional columns (as pandas and geopandas write them) carry definition levels; a value is
    // still required in every row
    let mut def = (max_def > 0).then(|| Vec::with_capacity(n));
    let (r, values, _) = parquet::column::reader::get_typed_column_reader::<T>(cr).read_records(n, def.as_mut(), None, &mut v).map_err(|e| bad(e.to_string()))?;
    if r != n {
        return Err(bad(format!("{r} values in row group {g}, expected {n}")));
    }
    if values != n {
        return Err(bad(format!("{} missing (null) values in row group {g}; expected a value in every row", n - values)));
    }
    Ok(v)
}

/// The `geo` key of the Parquet file `path` (GeoParquet metadata), if any.
///
/// Errors: [`super::OutputError::Io`] naming `path` when it cannot be read as Parquet.
pub fn geo_key(path: &Path) -> Result<Option<String>> {
    let res = (|| -> std::io::Result<Option<String>> {
        let reader = SerializedFileReader::new(std::fs::File::open(path)?).map_err(std::io::Error::other)?;
        let kv = reader.metadata().file_metadata().key_value_metadata();
        Ok(kv.and_then(|kv| kv.iter().find(|k| k.key == "geo").and_then(|k| k.value.clone())))
    })();
    res.map_err(|e| super::OutputError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn utm17() -> PointGeoRef {
        PointGeoRef { x0: 270_000.0, y0: 3_880_000.0, per_m: (1.0, 1.0), epsg: Some(32617), degrees: false }
    }

    #[test]
    fn inventory_round_trip_with_geoparquet_metadata() {
        let dir = tempfile::tempdir().unwrap();
        let csv = format!("{}\n1,beech,10.25,20.50,500.00,30,12.00,15.00,2.00,5.00,alive\n7,oak,0.00,1.00,501.50,80,25.50,40.25,4.75,9.00,dead:stress\n", "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status");
        let out = dir.path().join("y.parquet");
        csv_to_parquet(csv.as_bytes(), "test csv", &out, &INVENTORY, &utm17()).unwrap();
        let c = read_table(&out, &INVENTORY).unwrap();
        assert_eq!(c.rows, 2);
        assert_eq!(c.int("id").unwrap(), &[1, 7]);
        assert_eq!(c.text("species").unwrap(), &["beech".to_string(), "oak".to_string()]);
        assert_eq!(c.double("x_m").unwrap(), &[10.25, 0.0]);
        assert_eq!(c.float("dbh_cm").unwrap(), &[15.0, 40.25]);
        assert_eq!(c.text("status").unwrap()[1], "dead:stress");
        let g: serde_json::Value = serde_json::from_str(&geo_key(&out).unwrap().unwrap()).unwrap();
        assert_eq!(g["version"], "1.1.0");
        assert_eq!(g["primary_column"], "geometry");
        let col = &g["columns"]["geometry"];
        assert_eq!(col["encoding"], "WKB");
        // bbox in map coordinates: origin + local metres
        assert_eq!(col["bbox"], serde_json::json!([270_000.0, 3_880_001.0, 270_010.25, 3_880_020.5]));
        assert_eq!(col["crs"]["id"]["code"], 32617);
        assert_eq!(col["crs"]["conversion"]["parameters"][1]["value"], -81.0);
    }

    /// Three row groups of trees with the encodings of [`writer_properties`] (delta-coded ids,
    /// plain positions and points, dictionaries for the rest) read back bit for bit, points
    /// included; the column chunks carry those encodings.
    #[test]
    fn many_rows_with_the_column_encodings_read_back_equal() {
        use parquet::basic::Encoding;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("big.parquet");
        let n = 2 * ROW_GROUP_ROWS + 1234;
        let species = ["beech", "sessile_oak", "silver_birch"];
        let mut csv = format!("{}\n", INVENTORY.header());
        let mut want = Vec::new();
        for i in 0..n {
            // ids ascending with gaps, positions wandering in cm steps, sizes from a few values
            let id = i as i64 * 3 + (i as i64 % 7);
            let (x, y) = (((i * 7919) % 240_000) as f64 / 100.0, ((i * 104_729) % 180_000) as f64 / 100.0);
            let (sp, st) = (species[i % 3], if i % 50 == 0 { "dead:stress" } else { "alive" });
            let line = format!("{id},{sp},{x:.2},{y:.2},{:.2},{},{:.2},{:.2},{:.2},{:.2},{st}\n", 700.0 + (i % 9000) as f64 / 100.0, i % 150, (i % 4000) as f32 / 100.0, (i % 9000) as f32 / 100.0, (i % 700) as f32 / 100.0, (i % 2000) as f32 / 100.0);
            csv.push_str(&line);
            want.push((id, sp, x, y));
        }
        let g = utm17();
        csv_to_parquet(csv.as_bytes(), "test csv", &out, &INVENTORY, &g).unwrap();
        let c = read_table(&out, &INVENTORY).unwrap();
        assert_eq!(c.rows, n);
        let (ids, xs, ys, sps) = (c.int("id").unwrap(), c.double("x_m").unwrap(), c.double("y_m").unwrap(), c.text("species").unwrap());
        for (i, (id, sp, x, y)) in want.iter().enumerate() {
            assert_eq!((ids[i], sps[i].as_str(), xs[i].to_bits(), ys[i].to_bits()), (*id, *sp, x.to_bits(), y.to_bits()), "row {i}");
        }
        assert_eq!(c.float("dbh_cm").unwrap()[8999], 89.99);
        assert_eq!(c.float("crown_radius_m").unwrap()[1234], 5.34);
        assert_eq!(c.double("z_m").unwrap()[12], 700.12);
        assert_eq!(c.text("status").unwrap().iter().filter(|s| *s == "dead:stress").count(), n.div_ceil(50));
        // the WKB points: the map coordinates of (x_m, y_m)
        let reader = SerializedFileReader::new(std::fs::File::open(&out).unwrap()).unwrap();
        let schema = reader.metadata().file_metadata().schema_descr_ptr();
        let gi = (0..schema.num_columns()).find(|&i| schema.column(i).name() == "geometry").unwrap();
        let mut row = 0;
        for k in 0..reader.num_row_groups() {
            let rg = reader.get_row_group(k).unwrap();
            let m = rg.metadata().num_rows() as usize;
            for p in read_column::<ByteArrayType>(rg.get_column_reader(gi).unwrap(), m, "geometry", k, 0).unwrap() {
                let (x, y) = g.map(want[row].2, want[row].3);
                assert_eq!(p.data(), wkb_point(x, y).data(), "point of row {row}");
                row += 1;
            }
            let enc = |name: &str| rg.metadata().columns().iter().find(|c| c.column_path().string() == name).unwrap().encodings().collect::<Vec<_>>();
            assert!(enc("id").contains(&Encoding::DELTA_BINARY_PACKED) && !enc("id").contains(&Encoding::RLE_DICTIONARY), "id: {:?}", enc("id"));
            for name in ["x_m", "y_m", "z_m", "geometry"] {
                assert!(enc(name).contains(&Encoding::PLAIN) && !enc(name).contains(&Encoding::RLE_DICTIONARY), "{name}: {:?}", enc(name));
            }
            for name in ["species", "dbh_cm", "status"] {
                assert!(enc(name).contains(&Encoding::RLE_DICTIONARY), "{name}: {:?}", enc(name));
            }
        }
        assert_eq!((row, reader.num_row_groups()), (n, 3));
    }

    #[test]
    fn nad83_and_etrs89_utm_zones_have_their_datum() {
        let nad = projjson(&PointGeoRef { epsg: Some(26917), ..utm17() }).unwrap();
        assert_eq!(nad["name"], "NAD83 / UTM zone 17N");
        assert_eq!(nad["base_crs"]["datum"]["ellipsoid"]["inverse_flattening"], 298.257222101);
        assert_eq!(nad["conversion"]["parameters"][1]["value"], -81.0);
        let etrs = projjson(&PointGeoRef { epsg: Some(25832), ..utm17() }).unwrap();
        assert_eq!(etrs["conversion"]["parameters"][1]["value"], 9.0);
        assert_eq!(projjson(&PointGeoRef { epsg: Some(32733), ..utm17() }).unwrap()["conversion"]["parameters"][4]["value"], 10_000_000);
        assert!(projjson(&PointGeoRef { epsg: Some(2056), ..utm17() }).is_none(), "codes Sylva cannot describe: null");
    }

    #[test]
    fn wkb_point_is_iso_little_endian() {
        let b = wkb_point(1.5, -2.0);
        let d = b.data();
        assert_eq!(d.len(), 21);
        assert_eq!(d[0], 1);
        assert_eq!(u32::from_le_bytes(d[1..5].try_into().unwrap()), 1);
        assert_eq!(f64::from_le_bytes(d[5..13].try_into().unwrap()), 1.5);
        assert_eq!(f64::from_le_bytes(d[13..21].try_into().unwrap()), -2.0);
    }

    #[test]
    fn bad_rows_name_the_line_and_column_and_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("y.parquet");
        let csv = format!("{}\n1,beech,ten,20.50,500.00,30,12.00,15.00,2.00,5.00,alive\n", "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status");
        let e = csv_to_parquet(csv.as_bytes(), "year_0001.csv", &out, &INVENTORY, &utm17()).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("x_m") && e.contains("ten"), "{e}");
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "no temporary left");
        let e = read_table(&dir.path().join("none.parquet"), &INVENTORY).unwrap_err().to_string();
        assert!(e.contains("none.parquet"), "{e}");
    }

    #[test]
    fn an_empty_table_is_a_valid_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("r.parquet");
        csv_to_parquet(format!("{}\n", "cell,species,x_m,y_m,stems,stems_per_ha,height_m,age_yr").as_bytes(), "empty", &out, &REGENERATION, &utm17()).unwrap();
        assert_eq!(read_table(&out, &REGENERATION).unwrap().rows, 0);
    }
}
