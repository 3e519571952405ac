//! GeoPackage files (OGC GeoPackage Encoding Standard 1.3.1, OGC 12-128r18), written and read
//! with SQLite (`rusqlite`, SQLite bundled) and no GDAL:
//! - [`crate::output::gpkg::csv_to_points`] writes a table of points (the final year's tree
//!   inventory) as a feature layer that GDAL/OGR and QGIS open;
//! - [`read_polygons`] reads the Polygon and MultiPolygon features of a layer (management
//!   areas, `area_file = "parcels.gpkg"`), as GDAL's `ogr2ogr` or QGIS write them.
//!
//! What a file holds (section numbers of the standard):
//! - §1.1.1.1.1 (Req 2): `PRAGMA application_id` 0x47504B47 ("GPKG") and `PRAGMA user_version`
//!   10300;
//! - §1.1.2 (Req 10, 11): `gpkg_spatial_ref_sys` with the three rows every GeoPackage has
//!   (EPSG 4326 WGS 84, −1 undefined Cartesian, 0 undefined geographic) and the CRS of the
//!   layer: `srs_id` = its EPSG code, `definition` its OGC WKT 1 where Sylva can write it
//!   ([`crate::output::gpkg::wkt`]; `undefined` for other EPSG codes);
//! - §1.1.3 (Req 13–18): `gpkg_contents`, one row per layer: `data_type` `features`, the
//!   points' bounds, the `srs_id`;
//! - §2.1.5 (Req 21–28): `gpkg_geometry_columns`: column `geom`, type `POINT`, z 0, m 0;
//! - §2.1.6 (Req 29–31): the feature table, an `INTEGER PRIMARY KEY AUTOINCREMENT` column
//!   `fid` (1, 2, … in row order), the `geom` column and the table's attribute columns;
//! - §2.1.3 (Req 19): geometries as GeoPackageBinary ([`geometry_blob`]): magic `GP`, version
//!   0, a flags byte (bit 0 byte order, bits 1–3 envelope contents indicator, bit 4 empty, bit
//!   5 extended type), the `srs_id` (int32), an optional envelope, then ISO WKB (§2.1.4, ISO
//!   13249-3 / OGC 06-103r4).
//!
//! This module knows nothing of Sylva's outputs or simulation (the writer of the inventory is
//! [`crate::output::gpkg`]). The bytes of a written file depend on its rows only (`last_change`
//! is the fixed time [`LAST_CHANGE`], not the clock), so two runs of a scenario write the same
//! file.

use rusqlite::{Connection, OpenFlags};
use std::path::Path;

/// `PRAGMA application_id` of a GeoPackage: ASCII "GPKG" (§1.1.1.1.1, Req 2).
pub const APPLICATION_ID: i32 = 0x4750_4B47;
/// `PRAGMA user_version` of a GeoPackage 1.3 file (§1.1.1.1.1, Req 2).
pub const USER_VERSION: i32 = 10300;
/// The `gpkg_contents.last_change` Sylva writes (ISO 8601, §1.1.3.1.1): a fixed time, so that
/// a file's bytes depend on its content only.
pub const LAST_CHANGE: &str = "2000-01-01T00:00:00.000Z";
/// The geometry column of the layers Sylva writes.
pub const GEOMETRY_COLUMN: &str = "geom";
/// The GeoPackageBinary of a 2-D point (§2.1.3): `GP`, version 0, flags 0b0000_0001
/// (little-endian, envelope indicator 0: no envelope, as the standard allows and GDAL writes
/// for points; not empty; standard type), `srs_id` (int32 LE), then the ISO WKB point
/// (byte order 1, type 1, x, y as f64 LE): 29 bytes.
pub fn geometry_blob(srs_id: i32, x: f64, y: f64) -> Vec<u8> {
    let mut b = Vec::with_capacity(29);
    b.extend_from_slice(b"GP");
    b.push(0);
    b.push(0b0000_0001);
    b.extend_from_slice(&srs_id.to_le_bytes());
    b.push(1);
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&x.to_le_bytes());
    b.extend_from_slice(&y.to_le_bytes());
    b
}
/// SQL of the GeoPackage's own tables (§1.1.2.1.1, §1.1.3.1.1, §2.1.5.1.1; Annex C of the
/// standard) and the three SRS rows every GeoPackage holds (§1.1.2.1.2, Req 11).
pub const SCHEMA: &str = "
CREATE TABLE gpkg_spatial_ref_sys (srs_name TEXT NOT NULL, srs_id INTEGER NOT NULL PRIMARY KEY, organization TEXT NOT NULL, organization_coordsys_id INTEGER NOT NULL, definition TEXT NOT NULL, description TEXT);
CREATE TABLE gpkg_contents (table_name TEXT NOT NULL PRIMARY KEY, data_type TEXT NOT NULL, identifier TEXT UNIQUE, description TEXT DEFAULT '', last_change DATETIME NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')), min_x DOUBLE, min_y DOUBLE, max_x DOUBLE, max_y DOUBLE, srs_id INTEGER, CONSTRAINT fk_gc_r_srs_id FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys(srs_id));
CREATE TABLE gpkg_geometry_columns (table_name TEXT NOT NULL, column_name TEXT NOT NULL, geometry_type_name TEXT NOT NULL, srs_id INTEGER NOT NULL, z TINYINT NOT NULL, m TINYINT NOT NULL, CONSTRAINT pk_geom_cols PRIMARY KEY (table_name, column_name), CONSTRAINT uk_gc_table_name UNIQUE (table_name), CONSTRAINT fk_gc_tn FOREIGN KEY (table_name) REFERENCES gpkg_contents(table_name), CONSTRAINT fk_gc_srs FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys (srs_id));
INSERT INTO gpkg_spatial_ref_sys VALUES ('Undefined Cartesian SRS', -1, 'NONE', -1, 'undefined', 'undefined Cartesian coordinate reference system');
INSERT INTO gpkg_spatial_ref_sys VALUES ('Undefined geographic SRS', 0, 'NONE', 0, 'undefined', 'undefined geographic coordinate reference system');
";
/// Quotes an SQL identifier (`"name"`, inner quotes doubled).
pub fn quote(name: &str) -> String {
    format!("\"{}\"", name.replace('"', "\"\""))
}
// ---- reading polygon layers

/// A polygon: rings of `[x, y]` points in the layer's coordinates, the first ring the outline,
/// further rings holes.
pub type Polygon = Vec<Vec<[f64; 2]>>;

/// The WKB of GeoPackageBinary `blob` (§2.1.3): `None` for an empty geometry (flags bit 4).
///
/// Errors (a message): no `GP` magic, a version other than 0, an extended geometry (flags bit
/// 5), an envelope indicator above 4, a blob shorter than its header.
pub fn blob_wkb(blob: &[u8]) -> Result<Option<&[u8]>, String> {
    if blob.len() < 8 || &blob[..2] != b"GP" {
        return Err(format!("a GeoPackageBinary geometry starting with \"GP\" (the blob has {} bytes starting {:02x?})", blob.len(), &blob[..blob.len().min(4)]));
    }
    if blob[2] != 0 {
        return Err(format!("GeoPackageBinary version 0 (the blob has version {})", blob[2]));
    }
    let flags = blob[3];
    if flags & 0b0010_0000 != 0 {
        return Err("a standard GeoPackageBinary geometry (the blob is an extended geometry type, flags bit 5)".into());
    }
    let env = match (flags >> 1) & 0b111 {
        0 => 0,
        1 => 32,
        2 | 3 => 48,
        4 => 64,
        e => return Err(format!("an envelope contents indicator 0-4 (the blob has {e})")),
    };
    if flags & 0b0001_0000 != 0 {
        return Ok(None);
    }
    blob.get(8 + env..).filter(|w| !w.is_empty()).map(Some).ok_or_else(|| format!("a GeoPackageBinary blob longer than its {}-byte header (it has {} bytes)", 8 + env, blob.len()))
}

/// The name of WKB geometry type `base` (1–7; OGC 06-103r4 Table 7).
fn wkb_type_name(base: u32) -> String {
    match base {
        1 => "Point".into(),
        2 => "LineString".into(),
        3 => "Polygon".into(),
        4 => "MultiPoint".into(),
        5 => "MultiLineString".into(),
        6 => "MultiPolygon".into(),
        7 => "GeometryCollection".into(),
        8 => "CircularString".into(),
        9 => "CompoundCurve".into(),
        10 => "CurvePolygon".into(),
        11 => "MultiCurve".into(),
        12 => "MultiSurface".into(),
        15 => "PolyhedralSurface".into(),
        16 => "TIN".into(),
        17 => "Triangle".into(),
        t => format!("geometry of WKB type {t}"),
    }
}

/// A cursor over WKB bytes.
struct Wkb<'a> {
    b: &'a [u8],
    pos: usize,
}

impl Wkb<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let s = self.b.get(self.pos..self.pos + N).ok_or_else(|| format!("WKB of at least {} bytes (it has {}: cut short)", self.pos + N, self.b.len()))?;
        self.pos += N;
        Ok(s.try_into().unwrap_or([0; N]))
    }
    fn u32(&mut self, le: bool) -> Result<u32, String> {
        let a = self.take::<4>()?;
        Ok(if le { u32::from_le_bytes(a) } else { u32::from_be_bytes(a) })
    }
    fn f64(&mut self, le: bool) -> Result<f64, String> {
        let a = self.take::<8>()?;
        Ok(if le { f64::from_le_bytes(a) } else { f64::from_be_bytes(a) })
    }
    /// A count of items of at least `min_bytes` each that the rest of the bytes can hold.
    fn count(&mut self, le: bool, min_bytes: usize) -> Result<usize, String> {
        let n = self.u32(le)? as usize;
        if n.saturating_mul(min_bytes) > self.b.len() - self.pos {
            return Err(format!("WKB whose counts fit its {} bytes (cut short: a count of {n} needs at least {} more bytes, {} are left)", self.b.len(), n.saturating_mul(min_bytes), self.b.len() - self.pos));
        }
        Ok(n)
    }
    /// A geometry's header: (little-endian, base type 1–7, coordinates per point 2–4).
    /// ISO WKB types (1000 Z, 2000 M, 3000 ZM) and the EWKB flags (Z 0x8000_0000, M
    /// 0x4000_0000, SRID 0x2000_0000 with its SRID skipped) are understood.
    fn header(&mut self) -> Result<(bool, u32, usize), String> {
        let le = match self.take::<1>()?[0] {
            0 => false,
            1 => true,
            o => return Err(format!("WKB byte order 0 or 1 (it is {o})")),
        };
        let t = self.u32(le)?;
        let (ez, em) = (t & 0x8000_0000 != 0, t & 0x4000_0000 != 0);
        if t & 0x2000_0000 != 0 {
            self.u32(le)?;
        }
        let code = t & 0x0FFF_FFFF;
        let (base, iso) = (code % 1000, code / 1000);
        let dims = 2 + (ez || iso == 1 || iso == 3) as usize + (em || iso == 2 || iso == 3) as usize;
        Ok((le, base, dims))
    }
    /// The rings of a Polygon body (after its header).
    fn polygon(&mut self, le: bool, dims: usize) -> Result<Polygon, String> {
        let nr = self.count(le, 4)?;
        let mut rings = Vec::with_capacity(nr);
        for _ in 0..nr {
            let np = self.count(le, 8 * dims)?;
            let mut ring = Vec::with_capacity(np);
            for _ in 0..np {
                let x = self.f64(le)?;
                let y = self.f64(le)?;
                for _ in 2..dims {
                    self.f64(le)?;
                }
                ring.push([x, y]);
            }
            rings.push(ring);
        }
        Ok(rings)
    }
}

/// The polygons of WKB `wkb`: a Polygon (one) or a MultiPolygon (its polygons), with or without
/// Z or M (dropped).
///
/// Errors (a message): another geometry type (named), bytes cut short or malformed.
pub fn wkb_polygons(wkb: &[u8]) -> Result<Vec<Polygon>, String> {
    let mut r = Wkb { b: wkb, pos: 0 };
    let (le, base, dims) = r.header()?;
    match base {
        3 => Ok(vec![r.polygon(le, dims)?]),
        6 => {
            let n = r.count(le, 9)?;
            let mut out = Vec::with_capacity(n);
            for k in 0..n {
                let (le, base, dims) = r.header()?;
                if base != 3 {
                    return Err(format!("a MultiPolygon of Polygons (its part {k} is a {})", wkb_type_name(base)));
                }
                out.push(r.polygon(le, dims)?);
            }
            Ok(out)
        }
        // the curved types of ISO SQL/MM (GeoPackage 1.3 Annex E): not linearised here
        t @ 8..=12 => Err(format!("a Polygon or MultiPolygon, the only geometry types an area is read from (it is a {}; curved geometries are not read: linearise them, e.g. `ogr2ogr -nlt MULTIPOLYGON out.gpkg in.gpkg`)", wkb_type_name(t))),
        t => Err(format!("a Polygon or MultiPolygon, the only geometry types an area is read from (it is a {})", wkb_type_name(t))),
    }
}

/// One feature layer of a GeoPackage: its table, geometry column, geometry type name and
/// `srs_id`, with the SRS's organization and code.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerInfo {
    /// Table name.
    pub table: String,
    /// Geometry column.
    pub column: String,
    /// Geometry type name of `gpkg_geometry_columns` (`POLYGON`, `MULTIPOLYGON`, `GEOMETRY`, …).
    pub geometry_type: String,
    /// `srs_id`.
    pub srs_id: i64,
    /// The SRS's `organization` (`EPSG`, `NONE`, …) and `organization_coordsys_id`.
    pub organization: Option<(String, i64)>,
}

/// A value of a feature's attribute, for filters: texts as texts, integers and reals as
/// numbers, `BOOLEAN` columns as booleans (0 false), `NULL` and blobs as JSON `null`.
pub type Attribute = serde_json::Value;

/// The polygons read from a layer, each with its feature's `fid`.
#[derive(Debug, Clone)]
pub struct PolygonLayer {
    /// The layer read.
    pub layer: LayerInfo,
    /// (fid, polygon) in `fid` order; a MultiPolygon gives one entry per polygon.
    pub polygons: Vec<(i64, Polygon)>,
    /// Features that passed the filter (with a geometry, empty or not).
    pub features: usize,
    /// Features (rows) of the layer, filtered or not (an empty layer: 0).
    pub rows: usize,
}

/// Why [`read_polygons`] failed: what was expected, and what was found.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadError(pub String);

/// Reads the Polygon and MultiPolygon features of a GeoPackage feature layer: `layer` by name,
/// or the first feature layer of `gpkg_contents` (in the order its rows were written) when
/// `None`. `filter`: only features whose attribute column `.0` equals (by `keep`) the value.
/// Coordinates as stored (the layer's CRS, [`LayerInfo`]).
///
/// Errors: [`ReadError`] saying what was expected: a readable SQLite file with the GeoPackage
/// tables (`gpkg_contents`, `gpkg_geometry_columns`), a feature layer (of that name: the
/// layers there are listed), a filter column the layer has (its columns listed), geometries
/// that are GeoPackageBinary Polygons or MultiPolygons (naming the layer, the feature's fid
/// and the type found; a NULL or empty geometry of a feature the filter keeps is refused too).
pub fn read_polygons(path: &Path, layer: Option<&str>, filter: Option<(&str, &dyn Fn(&Attribute) -> bool)>) -> Result<PolygonLayer, ReadError> {
    let e = |m: String| ReadError(m);
    if !path.is_file() {
        return Err(e("a readable GeoPackage file (there is no such file)".into()));
    }
    let db = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX).map_err(|x| e(format!("a readable GeoPackage file ({x})")))?;
    let layers: Vec<LayerInfo> = (|| -> rusqlite::Result<Vec<LayerInfo>> {
        let mut st = db.prepare(
            "SELECT c.table_name, g.column_name, g.geometry_type_name, g.srs_id, s.organization, s.organization_coordsys_id FROM gpkg_contents c JOIN gpkg_geometry_columns g ON g.table_name = c.table_name LEFT JOIN gpkg_spatial_ref_sys s ON s.srs_id = g.srs_id WHERE c.data_type = 'features' ORDER BY c.rowid",
        )?;
        let rows = st.query_map([], |r| {
            let org: Option<String> = r.get(4)?;
            let code: Option<i64> = r.get(5)?;
            Ok(LayerInfo { table: r.get(0)?, column: r.get(1)?, geometry_type: r.get(2)?, srs_id: r.get(3)?, organization: org.zip(code) })
        })?;
        rows.collect()
    })()
    .map_err(|x| e(format!("a GeoPackage: an SQLite file with the tables gpkg_contents and gpkg_geometry_columns ({x})")))?;
    let names = || layers.iter().map(|l| format!("`{}`", l.table)).collect::<Vec<_>>().join(", ");
    let info = match layer {
        Some(n) => layers.iter().find(|l| l.table == n).cloned().ok_or_else(|| e(format!("a feature layer named `{n}` (the file's feature layers: {})", if layers.is_empty() { "none".into() } else { names() })))?,
        None => layers.first().cloned().ok_or_else(|| e("a GeoPackage with a feature layer (gpkg_contents lists none with data_type 'features')".into()))?,
    };
    let t = quote(&info.table);
    let sqlerr = |x: rusqlite::Error| e(format!("layer `{}` readable as a GeoPackage feature table ({x})", info.table));
    // columns: name, declared type, primary key
    let cols: Vec<(String, String, bool)> = {
        let mut st = db.prepare(&format!("PRAGMA table_info({t})")).map_err(sqlerr)?;
        let rows = st.query_map([], |r| Ok((r.get::<_, String>(1)?, r.get::<_, String>(2)?, r.get::<_, i64>(5)? > 0))).map_err(sqlerr)?;
        rows.collect::<rusqlite::Result<_>>().map_err(sqlerr)?
    };
    let fid = cols.iter().find(|c| c.2).map(|c| c.0.clone()).unwrap_or_else(|| "rowid".into());
    let mut select = format!("SELECT {}, {}", quote(&fid), quote(&info.column));
    let mut boolean = false;
    if let Some((name, _)) = filter {
        let Some(c) = cols.iter().find(|c| c.0 == name) else {
            let list: Vec<String> = cols.iter().filter(|c| c.0 != info.column).map(|c| format!("`{}`", c.0)).collect();
            return Err(e(format!("an attribute column `{name}` in layer `{}` for the filter (its columns: {})", info.table, list.join(", "))));
        };
        boolean = c.1.eq_ignore_ascii_case("BOOLEAN");
        select.push_str(&format!(", {}", quote(name)));
    }
    let mut st = db.prepare(&format!("{select} FROM {t} ORDER BY {}", quote(&fid))).map_err(sqlerr)?;
    let mut rows = st.query([]).map_err(sqlerr)?;
    let mut out = PolygonLayer { layer: info.clone(), polygons: Vec::new(), features: 0, rows: 0 };
    while let Some(r) = rows.next().map_err(sqlerr)? {
        out.rows += 1;
        let id: i64 = r.get(0).map_err(sqlerr)?;
        if let Some((_, keep)) = filter {
            use rusqlite::types::ValueRef;
            let v = match r.get_ref(2).map_err(sqlerr)? {
                ValueRef::Integer(i) if boolean => Attribute::Bool(i != 0),
                ValueRef::Integer(i) => Attribute::from(i),
                ValueRef::Real(x) => Attribute::from(x),
                ValueRef::Text(s) => Attribute::String(String::from_utf8_lossy(s).into_owned()),
                _ => Attribute::Null,
            };
            if !keep(&v) {
                continue;
            }
        }
        let feature = |m: String| e(format!("Polygon or MultiPolygon geometries in layer `{}` (feature {fid} = {id}: {m})", info.table));
        let blob = match r.get_ref(1).map_err(sqlerr)? {
            rusqlite::types::ValueRef::Null => return Err(feature("the geometry is NULL; give it a polygon, or leave the feature out with a `filter`".into())),
            rusqlite::types::ValueRef::Blob(b) => b,
            other => return Err(feature(format!("the geometry is a {:?} value, not a blob", other.data_type()))),
        };
        out.features += 1;
        let Some(wkb) = blob_wkb(blob).map_err(feature)? else {
            return Err(feature("the geometry is empty; give it a polygon, or leave the feature out with a `filter`".into()));
        };
        for p in wkb_polygons(wkb).map_err(feature)? {
            out.polygons.push((id, p));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// WKB of a polygon with Z (ISO type 1003), little- or big-endian.
    fn polygon_z(le: bool, rings: &[&[[f64; 3]]]) -> Vec<u8> {
        let u = |v: u32| if le { v.to_le_bytes() } else { v.to_be_bytes() };
        let f = |v: f64| if le { v.to_le_bytes() } else { v.to_be_bytes() };
        let mut b = vec![le as u8];
        b.extend_from_slice(&u(1003));
        b.extend_from_slice(&u(rings.len() as u32));
        for r in rings {
            b.extend_from_slice(&u(r.len() as u32));
            for p in *r {
                for c in p {
                    b.extend_from_slice(&f(*c));
                }
            }
        }
        b
    }

    #[test]
    fn point_blob_is_geopackage_binary() {
        let b = geometry_blob(26917, 270_000.5, 3_880_000.25);
        assert_eq!(&b[..4], &[b'G', b'P', 0, 1]);
        assert_eq!(i32::from_le_bytes(b[4..8].try_into().unwrap()), 26917);
        assert_eq!(b[8], 1);
        assert_eq!(u32::from_le_bytes(b[9..13].try_into().unwrap()), 1);
        assert_eq!(f64::from_le_bytes(b[13..21].try_into().unwrap()), 270_000.5);
        assert_eq!(f64::from_le_bytes(b[21..29].try_into().unwrap()), 3_880_000.25);
        assert_eq!(blob_wkb(&b).unwrap().unwrap(), &b[8..]);
    }

    #[test]
    fn polygons_with_z_envelopes_and_both_byte_orders_are_read() {
        let sq: &[[f64; 3]] = &[[0.0, 0.0, 5.0], [10.0, 0.0, 5.0], [10.0, 10.0, 5.0], [0.0, 0.0, 5.0]];
        for le in [true, false] {
            let p = polygon_z(le, &[sq]);
            // a MultiPolygon Z (1006) of two of them, in a blob with an xy envelope (indicator 1)
            let mut m = vec![1u8];
            m.extend_from_slice(&1006u32.to_le_bytes());
            m.extend_from_slice(&2u32.to_le_bytes());
            m.extend_from_slice(&p);
            m.extend_from_slice(&p);
            let mut blob = b"GP\x00\x03".to_vec();
            blob.extend_from_slice(&0i32.to_le_bytes());
            blob.extend_from_slice(&[0u8; 32]);
            blob.extend_from_slice(&m);
            let ps = wkb_polygons(blob_wkb(&blob).unwrap().unwrap()).unwrap();
            assert_eq!(ps.len(), 2);
            assert_eq!(ps[1][0][2], [10.0, 10.0]);
        }
        // other types and broken bytes are refused with what was expected
        let line = [1u8, 2, 0, 0, 0, 0, 0, 0, 0];
        assert!(wkb_polygons(&line).unwrap_err().contains("it is a LineString"));
        let p = polygon_z(true, &[sq]);
        assert!(wkb_polygons(&p[..p.len() - 3]).unwrap_err().contains("cut short"));
        let mut huge = p.clone();
        huge[5..9].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(wkb_polygons(&huge).unwrap_err().contains("a count of 4294967295 needs"));
        assert!(blob_wkb(b"XX\x00\x01\x00\x00\x00\x00").unwrap_err().contains("\"GP\""));
        assert_eq!(blob_wkb(b"GP\x00\x11\x00\x00\x00\x00").unwrap(), None, "empty geometry");
    }
}
