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

