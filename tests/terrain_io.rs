//! Readers: real DEMs in three forms, bad input gives clear errors.
use std::path::{Path, PathBuf};
use sylva::grid::Crs;
use sylva::terrain::io;

fn terrains() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains")
}

#[test]
fn geographic_geotiff_cell_sizes() {
    let t = io::load(&terrains().join("jacksboro_fault_dem.tif")).unwrap();
    assert_eq!((t.elevation.width, t.elevation.height), (403, 344));
    assert_eq!(t.geo.crs, Crs::Geographic);
    assert_eq!(t.geo.epsg, Some(4326));
    let dx = t.geo.cell_x_m_at_row(t.elevation.height / 2);
    assert!((dx - 74.3).abs() < 0.5, "dx {dx}");
    assert!((t.geo.cell_y_m() - 92.6).abs() < 0.05, "dy {}", t.geo.cell_y_m());
    assert!((t.geo.latitude_deg - 36.59).abs() < 0.05, "lat {}", t.geo.latitude_deg);
    let (lo, hi) = t.elevation.data.iter().filter(|v| v.is_finite()).fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert_eq!((lo, hi), (236.0, 1076.0));
    assert_eq!(t.nodata, Some(-32768.0));
}

#[test]
fn asc_matches_geotiff() {
    let a = io::load(&terrains().join("jacksboro_fault_dem.asc")).unwrap();
    let t = io::load(&terrains().join("jacksboro_fault_dem.tif")).unwrap();
    assert_eq!(a.geo.crs, Crs::Geographic);
    assert_eq!(a.elevation.data, t.elevation.data);
    assert!((a.geo.origin_x - t.geo.origin_x).abs() < 1e-6 && (a.geo.origin_y - t.geo.origin_y).abs() < 1e-6);
    assert!((a.geo.pixel_w - t.geo.pixel_w).abs() < 1e-9);
}

#[test]
fn utm_default_terrain() {
    let t = io::default_terrain().unwrap();
    assert_eq!((t.elevation.width, t.elevation.height), (387, 408));
    assert_eq!(t.geo.crs, Crs::Projected);
    assert_eq!(t.geo.epsg, Some(32616));
    assert_eq!((t.geo.pixel_w, t.geo.pixel_h), (80.0, 80.0));
    assert!((t.geo.latitude_deg - 36.59).abs() < 1e-9);
    assert!(!t.elevation.get(0, 0).is_finite(), "nodata corner is NaN");
    // the file read from disk gives the same grid and a UTM-derived latitude near 36.6
    let f = io::load(&terrains().join("jacksboro_fault_dem_utm16n.tif")).unwrap();
    assert_eq!(f.elevation.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), t.elevation.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
    assert!((f.geo.latitude_deg - 36.59).abs() < 0.05, "lat {}", f.geo.latitude_deg);
}

#[test]
fn window_shifts_georeferencing() {
    let t = io::default_terrain().unwrap();
    let w = io::window(&t, 10, 20, 50, 40).unwrap();
    assert_eq!((w.elevation.width, w.elevation.height), (50, 40));
    assert_eq!(w.elevation.get(0, 0), t.elevation.get(10, 20));
    assert_eq!(w.geo.origin_x, t.geo.origin_x + 800.0);
    assert_eq!(w.geo.origin_y, t.geo.origin_y - 1600.0);
    assert!(io::window(&t, 380, 0, 10, 10).is_err());
}

#[test]
fn png_heightmap_scaling() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h.png");
    let img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(4, 3, |x, _| image::Luma([(x * 21845) as u16]));
    img.save(&p).unwrap();
    let t = io::load_png_heightmap(&p, 2.0, 100.0, 400.0).unwrap();
    assert_eq!(t.geo.crs, Crs::Local);
    assert_eq!(t.geo.pixel_w, 2.0);
    assert_eq!(*t.elevation.get(0, 1), 100.0);
    assert_eq!(*t.elevation.get(3, 2), 400.0);
    assert!((t.elevation.get(1, 0) - 200.0).abs() < 1e-3);
    // 8-bit gray is refused (round 33's trial: 256 levels read without a word gave terraces),
    // naming the file, the step and what is expected
    let p8 = dir.path().join("h8.png");
    image::ImageBuffer::<image::Luma<u8>, Vec<u8>>::from_fn(2, 2, |x, _| image::Luma([(x * 255) as u8])).save(&p8).unwrap();
    let e = io::load_png_heightmap(&p8, 1.0, 0.0, 51.0).unwrap_err().to_string();
    assert!(e.contains("h8.png") && e.contains("8-bit") && e.contains("steps of 0.20 m") && e.contains("16-bit grayscale PNG"), "{e}");
    // a colour PNG is refused with the file and colour type named
    let prgb = dir.path().join("photo.png");
    image::ImageBuffer::<image::Rgb<u8>, Vec<u8>>::from_fn(3, 3, |x, y| image::Rgb([x as u8 * 80, y as u8 * 80, 9])).save(&prgb).unwrap();
    let e = io::load_png_heightmap(&prgb, 1.0, 0.0, 100.0).unwrap_err().to_string();
    assert!(e.contains("photo.png") && e.contains("Rgb8") && e.contains("grayscale"), "{e}");
}

#[test]
fn generated_is_deterministic() {
    let a = sylva::terrain::generate::generate(64, 10.0, 300.0, 7).unwrap();
    let b = sylva::terrain::generate::generate(64, 10.0, 300.0, 7).unwrap();
    let c = sylva::terrain::generate::generate(64, 10.0, 300.0, 8).unwrap();
    assert_eq!(a.elevation.data, b.elevation.data);
    assert_ne!(a.elevation.data, c.elevation.data);
    let (lo, hi) = a.elevation.data.iter().fold((f32::MAX, f32::MIN), |(x, y), &v| (x.min(v), y.max(v)));
    assert!((lo - 100.0).abs() < 1e-3 && (hi - 400.0).abs() < 1e-2);
}

fn err_of(r: sylva::Result<sylva::terrain::Terrain>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_tiffs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(terrains().join("jacksboro_fault_dem_utm16n.tif")).unwrap();
    let p = dir.path().join("trunc.tif");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let e = err_of(io::load(&p));
    assert!(e.contains("trunc.tif"), "{e}");
    let p = dir.path().join("junk.tif");
    std::fs::write(&p, b"II*\0garbage garbage").unwrap();
    let e = err_of(io::load(&p));
    assert!(e.contains("junk.tif") && e.contains("GeoTIFF"), "{e}");
    let p = dir.path().join("empty.tif");
    std::fs::write(&p, b"").unwrap();
    assert!(err_of(io::load(&p)).contains("empty.tif"));
}

#[test]
fn huge_tiff_header_refused_before_allocating() {
    // A valid little-endian TIFF header declaring 100000 x 100000 Float32 with no real data.
    let mut b: Vec<u8> = b"II*\0".to_vec();
    b.extend_from_slice(&8u32.to_le_bytes());
    let entries: [(u16, u16, u32, u32); 10] = [(256, 4, 1, 100_000), (257, 4, 1, 100_000), (258, 3, 1, 32), (259, 3, 1, 1), (262, 3, 1, 1), (273, 4, 1, 0), (277, 3, 1, 1), (278, 4, 1, 100_000), (279, 4, 1, 400_000), (339, 3, 1, 3)];
    b.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, ty, n, v) in entries {
        b.extend_from_slice(&tag.to_le_bytes());
        b.extend_from_slice(&ty.to_le_bytes());
        b.extend_from_slice(&n.to_le_bytes());
        if ty == 3 {
            b.extend_from_slice(&(v as u16).to_le_bytes());
            b.extend_from_slice(&[0, 0]);
        } else {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b.extend_from_slice(&0u32.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("huge.tif");
    std::fs::write(&p, &b).unwrap();
    match io::load(&p) {
        Err(sylva::Error::TooLarge { width, height, .. }) => assert_eq!((width, height), (100_000, 100_000)),
        other => panic!("expected TooLarge, got {:?}", other.map(|_| ())),
    }
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn asc_errors_name_the_line() {
    let d = tempfile::tempdir().unwrap();
    let hdr = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n";
    let ok = write(d.path(), "ok.asc", &format!("{hdr}1 2 3\n4 5 6\n"));
    let t = io::load(&ok).unwrap();
    assert_eq!(t.elevation.data, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(t.geo.crs, Crs::Projected);
    let p = write(d.path(), "short.asc", &format!("{hdr}1 2 3\n4 5\n"));
    let e = err_of(io::load(&p));
    assert!(e.contains("short.asc") && e.contains("line 8") && e.contains("ncols = 3"), "{e}");
    let p = write(d.path(), "rows.asc", &format!("{hdr}1 2 3\n"));
    let e = err_of(io::load(&p));
    assert!(e.contains("nrows = 2"), "{e}");
    let p = write(d.path(), "nan.asc", &format!("{hdr}1 x 3\n4 5 6\n"));
    assert!(err_of(io::load(&p)).contains("line 7"));
    let p = write(d.path(), "nodata.asc", &format!("{hdr}-9999 -9999 -9999\n-9999 -9999 -9999\n"));
    let e = err_of(io::load(&p));
    assert!(e.contains("nodata.asc") && e.contains("nodata"), "{e}");
    let p = write(d.path(), "zero.asc", "ncols 0\nnrows 5\nxllcorner 0\nyllcorner 0\ncellsize 10\n");
    assert!(err_of(io::load(&p)).contains("zero size"));
    let p = write(d.path(), "big.asc", "ncols 1000000\nnrows 1000000\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2\n");
    assert!(matches!(io::load(&p), Err(sylva::Error::TooLarge { .. })));
    let p = write(d.path(), "hdr.asc", "ncols three\nnrows 5\n");
    let e = err_of(io::load(&p));
    assert!(e.contains("line 1") && e.contains("ncols"), "{e}");
}

#[test]
fn asc_in_degrees_without_prj_is_read_as_geographic() {
    let dir = tempfile::tempdir().unwrap();
    let grid = "ncols 3\nnrows 2\nxllcorner -84.4\nyllcorner 36.4\ncellsize 0.000833333333\n1 2 3\n4 5 6\n";
    std::fs::write(dir.path().join("deg.asc"), grid).unwrap();
    let t = io::load(&dir.path().join("deg.asc")).unwrap();
    assert_eq!(t.geo.crs, Crs::Geographic);
    assert!((t.geo.cell_y_m() - 92.6).abs() < 0.1, "N-S cell {} m", t.geo.cell_y_m());
    // the same header in metres (UTM-like corner, 10 m cells) stays projected
    let metres = grid.replace("-84.4", "748379").replace("36.4", "4046666").replace("0.000833333333", "10");
    std::fs::write(dir.path().join("m.asc"), metres).unwrap();
    assert_eq!(io::load(&dir.path().join("m.asc")).unwrap().geo.crs, Crs::Projected);
}

#[test]
fn undeclared_fill_values_are_refused_naming_the_cell() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fill.asc");
    std::fs::write(&p, "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2 3\n4 1e30 6\n").unwrap();
    let e = err_of(io::load(&p));
    assert!(e.contains("fill.asc") && e.contains("column 1, row 1") && e.contains("= 1000000") && e.contains("nodata"), "{e}");
}

#[test]
fn embedded_coweeta_basin_and_its_valid_rectangle() {
    // terrains/coweeta_basin_10m_utm17n.tif: USGS 3DEP 10 m, NAD83 / UTM 17N (EPSG:26917)
    let t = io::embedded_terrain("coweeta").unwrap();
    assert_eq!((t.elevation.width, t.elevation.height), (619, 624));
    assert_eq!(t.geo.epsg, Some(26917));
    assert!((t.geo.cell_y_m() - 10.0).abs() < 1e-9 && (t.geo.pixel_w - 10.0).abs() < 1e-9);
    // latitude by inverse projection of the grid's centre (the basin lies at ≈ 35.02–35.08° N)
    assert!((t.geo.latitude_deg - 35.05).abs() < 0.03, "latitude {}", t.geo.latitude_deg);
    let valid = t.elevation.data.iter().filter(|v| v.is_finite()).count() as f64 / t.elevation.data.len() as f64;
    assert!((valid - 0.47).abs() < 0.02, "basin outline: {valid} of the cells valid");
    // terrains/coweeta_10m_utm17n.tif is the basin's largest valid rectangle, cells 108.., 182..
    let rect = io::load(&terrains().join("coweeta_10m_utm17n.tif")).unwrap();
    let w = io::window(&t, 108, 182, 345, 256).unwrap();
    assert_eq!(rect.elevation.data, w.elevation.data);
    assert!(rect.elevation.data.iter().all(|v| v.is_finite()));
    assert!((rect.geo.origin_x - w.geo.origin_x).abs() < 1e-6 && (rect.geo.origin_y - w.geo.origin_y).abs() < 1e-6);
    // the default scenario's window lies inside it: 2.4 km × 1.8 km of ridges and coves
    let sc = sylva::sim::Scenario::from_toml_str(&std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/default.toml")).unwrap(), "default.toml").unwrap();
    assert_eq!(sc.terrain.embedded.as_deref(), Some("coweeta"));
    let [c0, r0, ww, wh] = sc.terrain.window.unwrap();
    assert!(c0 >= 108 && r0 >= 182 && c0 + ww <= 108 + 345 && r0 + wh <= 182 + 256);
    assert!(ww as f64 * wh as f64 * 100.0 >= 4.0e6, "at least 4 km²");
    let d = io::window(&t, c0, r0, ww, wh).unwrap();
    let (lo, hi) = d.elevation.data.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    assert!((740.0..760.0).contains(&lo) && (1270.0..1290.0).contains(&hi), "{lo}–{hi} m");
    assert!(io::embedded_terrain("nowhere").unwrap_err().to_string().contains("coweeta"));
}

/// A 4 × 3 Float32 GeoTIFF with the given GeoKeys (after the header) and GDAL_METADATA.
fn geotiff_with_keys(path: &Path, keys: &[u16], gdal_metadata: Option<&str>) {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let mut f = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(&mut f).unwrap();
    let mut img = enc.new_image::<colortype::Gray32Float>(4, 3).unwrap();
    let e = img.encoder();
    e.write_tag(Tag::ModelPixelScaleTag, &[10.0f64, 10.0, 0.0][..]).unwrap();
    e.write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 2_000_000.0, 700_000.0, 0.0][..]).unwrap();
    let mut k = vec![1u16, 1, 0, (keys.len() / 4) as u16];
    k.extend_from_slice(keys);
    e.write_tag(Tag::GeoKeyDirectoryTag, &k[..]).unwrap();
    if let Some(m) = gdal_metadata {
        e.write_tag(Tag::Unknown(42112), m).unwrap();
    }
    img.write_data(&[1000.0f32, 1001.0, 1002.0, 1003.0, 1004.0, 1005.0, 1006.0, 1007.0, 1008.0, 1009.0, 1010.0, 1011.0]).unwrap();
}

#[test]
fn dems_in_feet_are_refused_naming_the_unit() {
    let dir = tempfile::tempdir().unwrap();
    // NC State Plane (EPSG:2264) in US survey feet, as GDAL writes it: read as metres before
    // round 35 (3.28× too wide, 10.8× the area; trial 35)
    let p = dir.path().join("stateplane_ftus.tif");
    geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, 2264, 3076, 0, 1, 9003], None);
    let e = err_of(io::load(&p));
    assert!(e.contains("stateplane_ftus.tif") && e.contains("3076") && e.contains("US survey foot") && e.contains("gdalwarp"), "{e}");
    // the same file in metres (9001) is read
    let p = dir.path().join("utm_m.tif");
    geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, 32617, 3076, 0, 1, 9001, 4099, 0, 1, 9001], None);
    let t = io::load(&p).unwrap();
    assert_eq!((t.elevation.width, t.elevation.height, t.geo.pixel_w), (4, 3, 10.0));
    // elevations in feet: the vertical key, and GDAL's band unit
    let p = dir.path().join("vert_ft.tif");
    geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, 32617, 4099, 0, 1, 9002], None);
    let e = err_of(io::load(&p));
    assert!(e.contains("vert_ft.tif") && e.contains("4099") && e.contains("foot"), "{e}");
    let p = dir.path().join("band_ft.tif");
    let md = "<GDALMetadata>\n  <Item name=\"DESCRIPTION\" sample=\"0\" role=\"description\">elev</Item>\n  <Item name=\"UNITTYPE\" sample=\"0\" role=\"unittype\">ft</Item>\n</GDALMetadata>";
    geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, 32617], Some(md));
    let e = err_of(io::load(&p));
    assert!(e.contains("band_ft.tif") && e.contains("`ft`"), "{e}");
    let p = dir.path().join("band_m.tif");
    geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, 32617], Some(&md.replace(">ft<", ">m<")));
    assert!(io::load(&p).is_ok());
    // an ASCII grid whose .prj is in feet (ESRI WKT)
    let grid = "ncols 3\nnrows 2\nxllcorner 2000000\nyllcorner 700000\ncellsize 30\n1 2 3\n4 5 6\n";
    std::fs::write(dir.path().join("ft.asc"), grid).unwrap();
    std::fs::write(dir.path().join("ft.prj"), "PROJCS[\"NAD_1983_StatePlane_North_Carolina_FIPS_3200_Feet\",GEOGCS[\"GCS_North_American_1983\",DATUM[\"D_North_American_1983\",SPHEROID[\"GRS_1980\",6378137.0,298.257222101]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]],PROJECTION[\"Lambert_Conformal_Conic\"],PARAMETER[\"False_Easting\",2000000.002616666],PARAMETER[\"False_Northing\",0.0],PARAMETER[\"Central_Meridian\",-79.0],PARAMETER[\"Standard_Parallel_1\",34.33333333333334],PARAMETER[\"Standard_Parallel_2\",36.16666666666666],PARAMETER[\"Latitude_Of_Origin\",33.75],UNIT[\"Foot_US\",0.3048006096012192]]").unwrap();
    let e = err_of(io::load(&dir.path().join("ft.asc")));
    assert!(e.contains("ft.prj") && e.contains("Foot_US") && e.contains("expected metres"), "{e}");
}

/// Round 37 (the closing check of round 36, D1): a UTM DEM on another datum than WGS 84 (NAD83
/// EPSG:269xx, ETRS89 EPSG:258xx) got its insolation at the climate's latitude (46° unless set),
/// not its own; only EPSG 326xx/327xx took the grid's. Now every projected grid whose CRS the
/// reader inverts takes its own, and the site's latitude (the pictures' sun, the stands' sky)
/// is the one the insolation used.
#[test]
fn a_utm_dem_on_any_datum_takes_its_own_latitude_for_insolation() {
    use sylva::conditions::{self, Climate};
    use sylva::terrain::fields::row_latitude;
    // NAD83 / UTM 17N, the real Coweeta rectangle (EPSG:26917), ≈ 35.05° N
    let t = io::load(&terrains().join("coweeta_10m_utm17n.tif")).unwrap();
    assert_eq!(t.geo.epsg, Some(26917));
    assert!(t.geo.latitude_from_crs && (t.geo.latitude_deg - 35.05).abs() < 0.03, "{:?}", t.geo);
    assert_eq!(row_latitude(&t.geo, 0, 46.0), t.geo.latitude_deg);
    let w = io::window(&t, 100, 100, 40, 40).unwrap();
    let at = |lat: f64| conditions::derive(&w, &Climate { latitude_deg: lat, ..Climate::default() }).unwrap();
    let (a, b) = (at(46.0), at(60.0));
    assert_eq!(a.insolation_kwh_m2.data, b.insolation_kwh_m2.data, "the climate's latitude must not move a NAD83 DEM's insolation");
    assert!((a.geo.latitude_deg - t.geo.latitude_deg).abs() < 1e-9);
    // the same cells as a grid without a CRS: the climate's latitude is used, and is the site's
    let mut local = w.clone();
    local.geo.crs = Crs::Local;
    local.geo.epsg = None;
    local.geo.latitude_from_crs = false;
    let (c, d) = (conditions::derive(&local, &Climate { latitude_deg: 35.05, ..Climate::default() }).unwrap(), conditions::derive(&local, &Climate { latitude_deg: 60.0, ..Climate::default() }).unwrap());
    assert_eq!(d.geo.latitude_deg, 60.0);
    let mean = |s: &conditions::SiteConditions| s.insolation_kwh_m2.data.iter().map(|&v| v as f64).sum::<f64>() / s.insolation_kwh_m2.data.len() as f64;
    // at its own latitude the NAD83 grid gets what the same cells get when told 35.05° (±1 %),
    // and 60° N would give markedly less (the fault: 46° gave 1,450 against 1,750 kWh/m²/yr)
    assert!((mean(&a) / mean(&c) - 1.0).abs() < 0.01, "{} vs {}", mean(&a), mean(&c));
    assert!(mean(&d) < 0.85 * mean(&c), "{} vs {}", mean(&d), mean(&c));
    // ETRS89 / UTM 32N (EPSG:25832) and WGS 84 / UTM 32N (32632) at the same coordinates: the
    // same latitude, taken from the CRS (the two ellipsoids differ by < 1e-4° here)
    let dir = tempfile::tempdir().unwrap();
    let lat_of = |epsg: u16| {
        let p = dir.path().join(format!("e{epsg}.tif"));
        geotiff_with_keys(&p, &[1024, 0, 1, 1, 3072, 0, 1, epsg], None);
        let t = io::load(&p).unwrap();
        assert!(t.geo.latitude_from_crs, "EPSG:{epsg}");
        row_latitude(&t.geo, 0, 46.0)
    };
    let (etrs, wgs) = (lat_of(25832), lat_of(32632));
    assert!((etrs - wgs).abs() < 1e-3 && (etrs - 46.0).abs() > 1.0, "ETRS89 {etrs}, WGS 84 {wgs}");
}
