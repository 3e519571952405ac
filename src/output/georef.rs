//! Map coordinates of the run's point outputs (inventories as GeoJSON and GeoParquet): how local
//! site metres become the terrain's coordinate reference system.

use crate::sim::World;

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
        PointGeoRef::of_site(&w.site.conditions)
    }

    /// The mapping for a site's conditions (from the terrain's GeoRef).
    pub fn of_site(site: &crate::conditions::SiteConditions) -> PointGeoRef {
        let g = &site.geo;
        let per_m = (g.pixel_w / site.cell_x_m.max(1e-12), g.pixel_h / site.cell_y_m.max(1e-12));
        let south = g.origin_y - site.height() as f64 * g.pixel_h;
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


/// A geographic CRS Sylva can describe without PROJ (for PROJJSON in GeoParquet and WKT in
/// GeoPackage): names and EPSG codes as the EPSG dataset gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnownDatum {
    /// Name of the geographic CRS (`WGS 84`).
    pub name: &'static str,
    /// Name of the datum (`World Geodetic System 1984`).
    pub datum: &'static str,
    /// Datum name in OGC WKT 1 style (`WGS_1984`).
    pub wkt_datum: &'static str,
    /// EPSG code of the datum (6326).
    pub datum_code: u32,
    /// Name of the ellipsoid (`WGS 84`).
    pub ellipsoid: &'static str,
    /// EPSG code of the ellipsoid (7030).
    pub ellipsoid_code: u32,
    /// Inverse flattening of the ellipsoid (semi-major axis 6 378 137 m for all three).
    pub inv_f: f64,
    /// EPSG code of the geographic CRS (4326).
    pub code: u32,
}

/// WGS 84 (EPSG 4326).
pub const WGS84: KnownDatum = KnownDatum { name: "WGS 84", datum: "World Geodetic System 1984", wkt_datum: "WGS_1984", datum_code: 6326, ellipsoid: "WGS 84", ellipsoid_code: 7030, inv_f: 298.257223563, code: 4326 };
/// NAD83 (EPSG 4269).
pub const NAD83: KnownDatum = KnownDatum { name: "NAD83", datum: "North American Datum 1983", wkt_datum: "North_American_Datum_1983", datum_code: 6269, ellipsoid: "GRS 1980", ellipsoid_code: 7019, inv_f: 298.257222101, code: 4269 };
/// ETRS89 (EPSG 4258).
pub const ETRS89: KnownDatum = KnownDatum { name: "ETRS89", datum: "European Terrestrial Reference System 1989", wkt_datum: "European_Terrestrial_Reference_System_1989", datum_code: 6258, ellipsoid: "GRS 1980", ellipsoid_code: 7019, inv_f: 298.257222101, code: 4258 };

/// The UTM zone of EPSG code `code`: (datum, zone 1–60, north) for the UTM zones of WGS 84
/// (32601–32660 north, 32701–32760 south), NAD83 (26901–26923) and ETRS89 (25828–25838);
/// `None` for other codes. UTM: Transverse Mercator, central meridian 6·zone − 183°, scale
/// 0.9996, false easting 500 000 m, false northing 0 (10 000 000 m south).
pub fn utm_zone(code: u32) -> Option<(KnownDatum, u32, bool)> {
    match code {
        32601..=32660 => Some((WGS84, code - 32600, true)),
        32701..=32760 => Some((WGS84, code - 32700, false)),
        26901..=26923 => Some((NAD83, code - 26900, true)),
        25828..=25838 => Some((ETRS89, code - 25800, true)),
        _ => None,
    }
}
