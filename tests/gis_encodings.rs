//! DEMs as GIS tools write them (issue 16, Build 2): the files in tests/data/gis/ were written
//! by GDAL 3.6.2 (`gdal_translate`; tests/data/gis/README.md) from one 24 × 20 window of the
//! default DEM (80 m cells, WGS 84 / UTM 16N) and one 20 × 16 window of the Coweeta DEM (10 m,
//! NAD83 / UTM 17N). Each encoding must read to the elevations and georeferencing of the plain
//! ESRI ASCII export of the same window; latitudes are checked against `gdaltransform`.
mod common;
use std::path::{Path, PathBuf};
use sylva::grid::Crs;
use sylva::terrain::io;

fn gis(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gis").join(name)
}

/// Centre latitude of the Jacksboro window: `echo 746299.219 4053226.162 | gdaltransform
/// -s_srs EPSG:32616 -t_srs EPSG:4326` → 36.5927550840438.
const JACKSBORO_LAT: f64 = 36.592_755_084_043_8;
/// Centre latitude of the Coweeta window: `echo 276060 3881650 | gdaltransform -s_srs
/// EPSG:26917 -t_srs EPSG:4326` → 35.0527520601622.
const COWEETA_LAT: f64 = 35.052_752_060_162_2;

#[test]
fn every_tiff_encoding_reads_to_the_same_grid() {
    let reference = io::load(&gis("grid.asc")).unwrap();
    assert_eq!((reference.elevation.width, reference.elevation.height), (24, 20));
    for (name, integer) in [
        ("float32_deflate_pred3.tif", false),
        ("float64_lzw_pred3_tiled.tif", false),
        ("float32_zstd.tif", false),
        ("float32_bigtiff.tif", false),
        ("float32_pixelispoint.tif", false),
        ("float32_southup.tif", false),
        ("int16_deflate_striped.tif", true),
        ("int32_packbits.tif", true),
        ("uint16_lzw_tiled.tif", true),
    ] {
        let t = io::load(&gis(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((t.elevation.width, t.elevation.height), (24, 20), "{name}");
        for (a, b) in t.elevation.data.iter().zip(&reference.elevation.data) {
            // GDAL rounds to the nearest integer for the integer types
            let tol = if integer { 0.5 + 1e-3 } else { 1e-3 };
            assert!((a - b).abs() <= tol, "{name}: {a} vs {b}");
        }
        let g = &t.geo;
        assert_eq!((g.crs, g.epsg), (Crs::Projected, Some(32616)), "{name}");
        assert!((g.origin_x - 745_339.219_465_8).abs() < 1e-6 && (g.origin_y - 4_054_026.162_225_3).abs() < 1e-6, "{name}: origin {} {}", g.origin_x, g.origin_y);
        assert_eq!((g.pixel_w, g.pixel_h), (80.0, 80.0), "{name}");
        assert!((g.latitude_deg - JACKSBORO_LAT).abs() < 1e-9, "{name}: latitude {}", g.latitude_deg);
    }
}

#[test]
fn wrapped_esri_rows_with_cell_centres_read_as_the_plain_grid() {
    let plain = io::load(&gis("grid.asc")).unwrap();
    let wrapped = io::load(&gis("grid_wrapped_center.asc")).unwrap();
    assert_eq!(wrapped.elevation.data, plain.elevation.data);
    assert!((wrapped.geo.origin_x - plain.geo.origin_x).abs() < 1e-6 && (wrapped.geo.origin_y - plain.geo.origin_y).abs() < 1e-6);
    assert!((plain.geo.latitude_deg - JACKSBORO_LAT).abs() < 1e-9, "{}", plain.geo.latitude_deg);
}

#[test]
fn coweeta_nad83_utm17n_gets_its_latitude_from_tiff_esri_and_ogc_wkt() {
    let tif = io::load(&gis("coweeta_nad83_utm17n.tif")).unwrap();
    assert_eq!(tif.geo.epsg, Some(26917));
    assert_eq!(io::epsg_projection(26917).unwrap().name, "NAD83 / UTM zone 17N");
    for t in [&tif, &io::load(&gis("coweeta_esri.asc")).unwrap(), &io::load(&gis("coweeta_ogc.asc")).unwrap()] {
        assert!((t.geo.latitude_deg - COWEETA_LAT).abs() < 1e-9, "{}: {}", t.source, t.geo.latitude_deg);
        assert_eq!((t.elevation.width, t.elevation.height), (20, 16));
        assert_eq!(t.elevation.data, tif.elevation.data);
    }
    let p = Path::new("x.prj");
    let esri = io::wkt_projection(&std::fs::read_to_string(gis("coweeta_esri.prj")).unwrap(), p).unwrap().unwrap();
    assert_eq!(esri.name, "NAD 1983 UTM Zone 17N");
    let ogc = io::wkt_projection(&std::fs::read_to_string(gis("coweeta_ogc.prj")).unwrap(), p).unwrap().unwrap();
    assert_eq!(ogc.name, "NAD83 / UTM zone 17N");
}

#[test]
fn what_cannot_be_read_is_refused_with_the_file_and_the_reason() {
    // GDAL's LZW + horizontal predictor in 16 × 16 tiles: tiff 0.11.3 finds no LZW end code
    let e = io::load(&gis("uint16_lzw_pred2_tiled.tif")).unwrap_err().to_string();
    assert!(e.contains("uint16_lzw_pred2_tiled.tif") && e.contains("lzw"), "{e}");
    // a WKT projection proj4wkt does not know
    let e = io::wkt_projection("PROJCS[\"odd\",GEOGCS[\"x\"],PROJECTION[\"No_Such_Projection\"]]", Path::new("odd.prj")).unwrap_err().to_string();
    assert!(e.starts_with("odd.prj") && e.contains("odd"), "{e}");
    // a rotated ModelTransformation
    let mut b = std::fs::read(gis("float32_southup.tif")).unwrap();
    let t = io::read_geotiff(std::io::Cursor::new(b.clone()), Path::new("south.tif")).unwrap();
    assert!((t.geo.latitude_deg - JACKSBORO_LAT).abs() < 1e-9);
    // find the transformation's b term (row 0, column 1: 0.0) after a = 80.0 and rotate it
    let a = 80.0f64.to_le_bytes();
    let at = b.windows(8).position(|w| w == a).expect("ModelTransformation a = 80");
    b[at + 8..at + 16].copy_from_slice(&5.0f64.to_le_bytes());
    let e = io::read_geotiff(std::io::Cursor::new(b), Path::new("south.tif")).unwrap_err().to_string();
    assert!(e.starts_with("south.tif") && e.contains("rotated"), "{e}");
}

/// Trial 37: the species codes are a Byte raster with a colour table and a nodata value: the
/// tags read back with the `tiff` decoder (which decodes no palette image), and, where GDAL is
/// installed, `gdalinfo` sees a Byte band with a colour table and nodata 255 and
/// `gdal_translate` gives the codes back.
#[test]
fn a_categorical_geotiff_is_a_byte_raster_with_a_colour_table() {
    use tiff::tags::Tag;
    let grid = sylva::grid::Grid { width: 3, height: 2, data: vec![0u8, 1, 2, 255, 1, 0] };
    let geo = sylva::grid::GeoRef::local(10.0, 47.0);
    let palette = [[250, 250, 250], [20, 120, 40], [200, 60, 30]];
    let bytes = sylva::output::geotiff::encode_u8_palette_band(&grid, &geo, Some(sylva::output::geotiff::Band { description: "Dominant species", unit: "code" }), &palette, 255).unwrap();
    let mut d = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes.clone())).unwrap();
    assert_eq!(d.get_tag_u32(Tag::PhotometricInterpretation).unwrap(), 3, "palette");
    assert_eq!(d.get_tag_u32(Tag::BitsPerSample).unwrap(), 8);
    assert_eq!(d.get_tag_u32(Tag::SampleFormat).unwrap_or(1), 1, "unsigned integers");
    let map = d.get_tag_u32_vec(Tag::ColorMap).unwrap();
    assert_eq!(map.len(), 768);
    for (k, c) in palette.iter().enumerate() {
        assert_eq!([map[k], map[256 + k], map[512 + k]], [c[0] as u32 * 257, c[1] as u32 * 257, c[2] as u32 * 257]);
    }
    assert_eq!(d.get_tag_ascii_string(Tag::GdalNodata).unwrap().trim_end_matches('\0'), "255");
    assert_eq!(common::palette_geotiff_codes(&bytes), (3, 2, grid.data.clone()), "the codes");
    let dir = tempfile::tempdir().unwrap();
    let tif = dir.path().join("codes.tif");
    std::fs::write(&tif, &bytes).unwrap();
    let Ok(o) = std::process::Command::new("gdalinfo").arg(&tif).output() else {
        eprintln!("gdalinfo not found: the GDAL checks are skipped");
        return;
    };
    let info = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && info.contains("Type=Byte") && info.contains("ColorInterp=Palette") && info.contains("NoData Value=255") && info.contains("0: 250,250,250,255") && info.contains("2: 200,60,30,255"), "{info}");
    let asc = dir.path().join("codes.asc");
    let o = std::process::Command::new("gdal_translate").args(["-q", "-of", "AAIGrid"]).arg(&tif).arg(&asc).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&asc).unwrap();
    let codes: Vec<u8> = text.lines().filter(|l| l.starts_with(' ') || l.chars().next().is_some_and(|c| c.is_ascii_digit())).flat_map(|l| l.split_whitespace().map(|v| v.parse::<u8>().unwrap()).collect::<Vec<_>>()).collect();
    assert_eq!(codes, grid.data, "{text}");
}
