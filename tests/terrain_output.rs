//! GeoTIFF writer round trip (our reader, and gdalinfo when installed); map PNG written.
use std::path::Path;
use std::process::Command;
use sylva::output::{geotiff, maps};
use sylva::terrain::{fields, io};

#[test]
fn geotiff_roundtrip_keeps_georeferencing() {
    let t = io::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/jacksboro_fault_dem.tif")).unwrap();
    let m = fields::mask(&t, 0.0);
    let (s, _) = fields::slope_aspect(&t, &m);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("slope.tif");
    geotiff::write_f32(&p, &s, &t.geo).unwrap();
    let back = io::load(&p).unwrap();
    assert_eq!(back.geo.crs, t.geo.crs);
    assert_eq!(back.geo.epsg, Some(4326));
    assert_eq!((back.geo.origin_x, back.geo.origin_y, back.geo.pixel_w, back.geo.pixel_h), (t.geo.origin_x, t.geo.origin_y, t.geo.pixel_w, t.geo.pixel_h));
    assert_eq!(back.elevation.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), s.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>());

    let u = io::default_terrain().unwrap();
    let q = dir.path().join("utm.tif");
    geotiff::write_f32(&q, &u.elevation, &u.geo).unwrap();
    match Command::new("gdalinfo").arg(&q).output() {
        Ok(o) => {
            let txt = String::from_utf8_lossy(&o.stdout);
            assert!(o.status.success(), "gdalinfo failed: {}", String::from_utf8_lossy(&o.stderr));
            assert!(txt.contains("32616") || txt.contains("UTM zone 16N"), "{txt}");
            assert!(txt.contains("Pixel Size = (80.000000000000000,-80.000000000000000)"), "{txt}");
            assert!(txt.contains("NoData Value=nan"), "{txt}");
        }
        Err(_) => println!("skipped gdalinfo check: gdalinfo not found"),
    }
}

#[test]
fn map_png_has_legend_area() {
    let t = io::default_terrain().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("elev.png");
    maps::write_field_png(&t.elevation, None, maps::Ramp::Terrain, "Elevation", "m", &p).unwrap();
    let img = image::open(&p).unwrap().to_rgb8();
    assert!(img.width() > 387 && img.height() > 408);
    assert_eq!(img.get_pixel(12, 44).0, [215, 215, 215], "nodata corner is grey");
}
