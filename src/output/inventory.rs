//! Tree inventories: CSV (columns fixed by ARCHITECTURE.md) and GeoJSON points.

use super::Result;
use crate::sim::World;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The inventory CSV header (ARCHITECTURE.md).
pub const HEADER: &str = "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status";

/// One inventory record.
struct Rec<'a> {
    id: u64,
    species: &'a str,
    v: [f32; 8],
    status: String,
}

fn records(w: &World) -> Vec<Rec<'_>> {
    let t = &w.stand.trees;
    let mut out: Vec<Rec> = (0..t.len())
        .map(|i| Rec { id: t.id[i], species: &w.site.lib.species[t.species[i] as usize].id, v: [t.x[i], t.y[i], t.z[i], t.age[i], t.height[i], t.dbh[i], t.crown_radius[i], t.crown_base[i]], status: "alive".into() })
        .collect();
    let mut dead: Vec<Rec> = w.scratch.dead.iter().map(|d| Rec { id: d.id, species: &w.site.lib.species[d.species as usize].id, v: [d.x, d.y, d.z, d.age, d.height, d.dbh, d.crown_radius, d.crown_base], status: format!("dead:{}", d.cause.name()) }).collect();
    dead.sort_by_key(|r| r.id);
    out.extend(dead);
    out
}

/// The inventory as CSV text: living trees (status `alive`) in id order, then the trees that
/// died in the current year (`dead:<cause>`). Positions and sizes in metres (DBH cm), 2 decimals.
pub fn inventory_csv(w: &World) -> String {
    let mut s = String::with_capacity(80 * (w.stand.trees.len() + 1));
    s.push_str(HEADER);
    s.push('\n');
    for r in records(w) {
        let v = r.v;
        let _ = writeln!(s, "{},{},{:.2},{:.2},{:.2},{:.0},{:.2},{:.2},{:.2},{:.2},{}", r.id, r.species, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], r.status);
    }
    s
}

/// The regeneration-layer CSV header.
pub const REGENERATION_HEADER: &str = "cell,species,x_m,y_m,stems,stems_per_ha,height_m,age_yr";

/// The regeneration layer (sapling cohorts below the recruitment height, [`crate::sim::regen`])
/// as CSV text, one row per cohort in (light cell, pool) order: light cell index, species id,
/// cell centre (m, world coordinates), stems, stems per hectare of the light cell, mean height
/// (m, 2 decimals), age (years).
pub fn regeneration_csv(w: &World) -> String {
    let c = &w.stand.cohorts;
    let per_ha = 10_000.0 / w.site.light.cell_area_m2();
    let mut s = String::with_capacity(48 * (c.len() + 1));
    s.push_str(REGENERATION_HEADER);
    s.push('\n');
    for i in 0..c.len() {
        let k = c.cell[i] as usize;
        let (x, y) = w.site.light.centre(k);
        let sp = w.site.pool.get(c.pool[i] as usize).map(|&s| w.site.lib.species[s as usize].id.as_str()).unwrap_or("?");
        let _ = writeln!(s, "{},{},{:.2},{:.2},{},{:.0},{:.2},{:.0}", k, sp, x, y, c.stems[i], c.stems[i] as f64 * per_ha, c.height[i], c.age[i]);
    }
    s
}

/// Writes the regeneration-layer CSV ([`regeneration_csv`]) atomically.
pub fn write_regeneration_csv(path: &Path, w: &World) -> Result<()> {
    crate::output::write_atomic(path, regeneration_csv(w).as_bytes())
}

/// Writes the inventory CSV atomically.
pub fn write_inventory_csv(path: &Path, w: &World) -> Result<()> {
    crate::output::write_atomic(path, inventory_csv(w).as_bytes())
}

/// Map coordinates of the inventory's points: how local site metres (x east, y north from the
/// site's south-west corner) become the terrain's coordinate reference system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointGeoRef {
    /// Map x of local (0, 0) (the site's south-west corner): easting (m) or longitude (°).
    pub x0: f64,
    /// Map y of local (0, 0): northing (m) or latitude (°).
    pub y0: f64,
    /// Map units per local metre east and north (1 for projected grids; degrees per metre at the
    /// site's centre for geographic grids: E-W from the centre row's cell width).
    pub per_m: (f64, f64),
    /// EPSG code of the map coordinates; `None` for a local grid without georeferencing.
    pub epsg: Option<u32>,
    /// True for longitude/latitude (7 decimals), false for metres (2 decimals).
    pub degrees: bool,
}

impl PointGeoRef {
    /// The mapping for a world's site (from the terrain's GeoRef, as the map GeoTIFFs use).
    pub fn of(w: &World) -> PointGeoRef {
        let g = &w.site.conditions.geo;
        let per_m = (g.pixel_w / w.site.conditions.cell_x_m.max(1e-12), g.pixel_h / w.site.conditions.cell_y_m.max(1e-12));
        let south = g.origin_y - w.site.conditions.height() as f64 * g.pixel_h;
        let (epsg, degrees) = match g.crs {
            crate::grid::Crs::Geographic => (Some(g.epsg.unwrap_or(4326)), true),
            crate::grid::Crs::Projected => (g.epsg, false),
            crate::grid::Crs::Local => (None, false),
        };
        PointGeoRef { x0: g.origin_x, y0: south, per_m, epsg, degrees }
    }
    /// Map coordinates of local site metres `(x, y)`.
    pub fn map(&self, x: f64, y: f64) -> (f64, f64) {
        (self.x0 + x * self.per_m.0, self.y0 + y * self.per_m.1)
    }
}

/// Writes the inventory as a GeoJSON FeatureCollection of points `[x, y, ground elevation m]`
/// in the terrain's coordinate reference system, so the trees overlay the map GeoTIFFs in a GIS:
/// - geographic terrain: WGS 84 longitude/latitude (RFC 7946, no `crs` member);
/// - projected terrain with an EPSG code (e.g. UTM): eastings/northings in metres with the
///   GeoJSON 2008 `crs` member `urn:ogc:def:crs:EPSG::<code>` (read by GDAL/QGIS);
/// - otherwise local metres from the site's south-west corner, with no `crs`.
///
/// Every feature also carries the local `x_m`, `y_m` of the CSV inventory.
pub fn write_inventory_geojson(path: &Path, w: &World) -> Result<()> {
    let geo = PointGeoRef::of(w);
    crate::output::write_atomic_with(path, |f| {
        f.write_all(b"{\"type\":\"FeatureCollection\",")?;
        match geo.epsg {
            Some(code) if !geo.degrees => write!(f, "\"crs\":{{\"type\":\"name\",\"properties\":{{\"name\":\"urn:ogc:def:crs:EPSG::{code}\"}}}},")?,
            None => f.write_all(b"\"sylva_coordinates\":\"local metres from the site's south-west corner (no georeferencing)\",")?,
            _ => {}
        }
        f.write_all(b"\"features\":[\n")?;
        for (k, r) in records(w).iter().enumerate() {
            let v = r.v;
            if k > 0 {
                f.write_all(b",\n")?;
            }
            let (mx, my) = geo.map(v[0] as f64, v[1] as f64);
            let prec = if geo.degrees { 7 } else { 2 };
            write!(
                f,
                "{{\"type\":\"Feature\",\"geometry\":{{\"type\":\"Point\",\"coordinates\":[{mx:.prec$},{my:.prec$},{:.2}]}},\"properties\":{{\"id\":{},\"species\":\"{}\",\"x_m\":{:.2},\"y_m\":{:.2},\"age_yr\":{:.0},\"height_m\":{:.2},\"dbh_cm\":{:.2},\"crown_radius_m\":{:.2},\"crown_base_m\":{:.2},\"status\":\"{}\"}}}}",
                v[2], r.id, r.species, v[0], v[1], v[3], v[4], v[5], v[6], v[7], r.status
            )?;
        }
        f.write_all(b"\n]}\n")
    })
}
