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

/// Trial 36: the maps' GeoTIFFs carried no band description or unit (only the PNG legends
/// did). Each band now says what it is and its unit in GDAL_METADATA, in ASCII.
#[test]
fn a_maps_geotiff_says_what_its_band_is_and_its_unit() {
    let u = io::default_terrain().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let q = dir.path().join("insolation.tif");
    geotiff::write_f32_band(&q, &u.elevation, &u.geo, Some(geotiff::Band { description: "Annual clear-sky insolation (flat 1530)", unit: "kWh/m²/yr" })).unwrap();
    let mut dec = tiff::decoder::Decoder::new(std::io::BufReader::new(std::fs::File::open(&q).unwrap())).unwrap();
    let xml = dec.get_tag_ascii_string(tiff::tags::Tag::Unknown(42112)).unwrap();
    assert!(xml.contains(r#"role="description">Annual clear-sky insolation (flat 1530)</Item>"#) && xml.contains(r#"role="unittype">kWh/m2/yr</Item>"#), "{xml}");
    // still read back as a DEM (its unit is not a foot) with the same values
    assert_eq!(io::load(&q).unwrap().elevation.data.len(), u.elevation.data.len());
    assert_eq!(geotiff::ascii_text("1–9 °C × m³ <a&b>"), "1-9 degC x m3 &lt;a&amp;b&gt;");
    if let Ok(o) = Command::new("gdalinfo").arg(&q).output() {
        let txt = String::from_utf8_lossy(&o.stdout);
        assert!(txt.contains("Description = Annual clear-sky insolation (flat 1530)") && txt.contains("Unit Type: kWh/m2/yr"), "{txt}");
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
