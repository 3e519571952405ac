//! A rank's part of the site (issue 37 Build 1): a GeoTIFF read by window equals the same
//! window of the whole raster, for stripped and tiled files of every encoding, reading only the
//! chunks the window overlaps; every field derived on a window with its halo equals the same
//! window of the whole raster's field bit for bit (real DEMs: the default Jacksboro DEM, 80 m,
//! stripped; the Coweeta basin, 10 m, tiled 256 × 256, nodata outside the basin; the
//! geographic Jacksboro DEM, Int16); the site's median insolation found by a selection over
//! counts equals the sorted median.
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use sylva::conditions::{self, Climate};
use sylva::grid::{Grid, Window};
use sylva::terrain::{fields, io};

fn root(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The DEMs read by window: (file, chunk layout as `gdalinfo` reports it).
const FILES: [(&str, &str); 12] = [
    ("terrains/jacksboro_fault_dem_utm16n.tif", "387 x 408, Float32, strips of 5 rows, Deflate"),
    ("terrains/coweeta_basin_10m_utm17n.tif", "619 x 624, Float32, tiles of 256 x 256, Deflate"),
    ("terrains/coweeta_10m_utm17n.tif", "345 x 256, Float32, strips of 5 rows"),
    ("terrains/jacksboro_fault_dem.tif", "403 x 344, Int16, geographic, strips of 10 rows"),
    ("tests/data/gis/float64_lzw_pred3_tiled.tif", "24 x 20, tiles of 16 x 16 (padded)"),
    ("tests/data/gis/uint16_lzw_tiled.tif", "24 x 20, tiles of 16 x 16"),
    ("tests/data/gis/float32_southup.tif", "south-up rows"),
    ("tests/data/gis/float32_pixelispoint.tif", "pixel is point"),
    ("tests/data/gis/float32_bigtiff.tif", "BigTIFF"),
    ("tests/data/gis/float32_zstd.tif", "ZSTD"),
    ("tests/data/gis/int32_packbits.tif", "PackBits"),
    ("tests/data/gis/int16_deflate_striped.tif", "Int16 strips"),
];

/// NaN-aware bit equality of two f32 grids, naming the first cell that differs.
fn assert_bits(a: &Grid<f32>, b: &Grid<f32>, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}: size");
    for (i, (x, y)) in a.data.iter().zip(&b.data).enumerate() {
        assert!(x.to_bits() == y.to_bits(), "{what}: cell {} (column {}, row {}): {x} vs {y}", i, i % a.width, i / a.width);
    }
}

/// Windows of a `w × h` raster: the whole, its corners' cells, a middle block across chunk
/// edges, an edge strip.
fn windows(w: usize, h: usize) -> Vec<Window> {
    vec![
        Window::full(w, h),
        Window { col0: 0, row0: 0, width: 1, height: 1 },
        Window { col0: w - 1, row0: h - 1, width: 1, height: 1 },
        Window { col0: w / 3, row0: h / 4, width: (w / 2).max(1), height: (h / 2).max(1) },
        Window { col0: 0, row0: h - 3.min(h), width: w, height: 3.min(h) },
        Window { col0: w - 7.min(w), row0: 1.min(h - 1), width: 7.min(w), height: h - 1.min(h - 1) },
    ]
}

#[test]
fn a_window_read_equals_the_window_of_a_whole_read() {
    for (file, layout) in FILES {
        let path = root(file);
        let whole = io::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let (w, h) = (whole.elevation.width, whole.elevation.height);
        let full = Window::full(w, h);
        for win in windows(w, h) {
            let got = io::load_window(&path, win).unwrap_or_else(|e| panic!("{file} ({layout}), {win}: {e}"));
            assert_bits(&got.elevation, &win.cut(&whole.elevation, &full), &format!("{file} ({layout}), {win}"));
            assert_eq!((got.window, got.full_width, got.full_height), (win, w, h), "{file}");
            assert_eq!(got.geo, whole.geo, "{file}: the whole raster's georeferencing");
            assert_eq!(got.nodata, whole.nodata, "{file}");
        }
        // a meaningful comparison: the middle block holds real elevations
        let mid = windows(w, h)[3];
        assert!(io::load_window(&path, mid).unwrap().elevation.data.iter().any(|v| v.is_finite()), "{file}");
    }
    // the ESRI ASCII grid (no random access) is read whole and cut
    let asc = root("tests/data/gis/grid.asc");
    let whole = io::load(&asc).unwrap();
    let win = Window { col0: 3, row0: 2, width: 10, height: 9 };
    assert_bits(&io::load_window(&asc, win).unwrap().elevation, &win.cut(&whole.elevation, &Window::full(24, 20)), "grid.asc");
}

#[test]
fn a_window_outside_the_raster_is_refused_naming_file_window_and_size() {
    let path = root("terrains/jacksboro_fault_dem_utm16n.tif");
    for win in [Window { col0: 380, row0: 0, width: 10, height: 5 }, Window { col0: 0, row0: 408, width: 1, height: 1 }, Window { col0: 5, row0: 5, width: 0, height: 3 }] {
        let e = io::load_window(&path, win).unwrap_err().to_string();
        assert!(e.contains("jacksboro_fault_dem_utm16n.tif") && e.contains("window") && e.contains(&win.to_string()) && e.contains("inside the 387 x 408 raster"), "{win}: {e}");
    }
}

/// A reader that counts the bytes read through it.
struct Counting<R> {
    inner: R,
    read: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        Ok(n)
    }
}

impl<R: Seek> Seek for Counting<R> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

#[test]
fn a_window_read_reads_only_the_chunks_it_overlaps() {
    // (file, window, largest share of the file read). The Deflate decoder (flate2's
    // `ZlibDecoder`) reads through a 32 KiB buffer, so every chunk read costs its compressed
    // bytes plus up to 32 KiB beyond them: one 256 × 256 tile of the 3 × 3 of the Coweeta basin
    // (the middle one holds most of the basin: the outer tiles are mostly nodata and compress
    // to little); one corner tile; one strip of 5 rows of the 82 of the default DEM (6.5 KB
    // compressed), then the four that rows 199..211 cross
    for (file, win, share) in [
        ("terrains/coweeta_basin_10m_utm17n.tif", Window { col0: 300, row0: 300, width: 10, height: 10 }, 0.4),
        ("terrains/coweeta_basin_10m_utm17n.tif", Window { col0: 520, row0: 300, width: 10, height: 10 }, 0.1),
        ("terrains/jacksboro_fault_dem_utm16n.tif", Window { col0: 100, row0: 200, width: 50, height: 5 }, 0.1),
        ("terrains/jacksboro_fault_dem_utm16n.tif", Window { col0: 100, row0: 199, width: 50, height: 12 }, 0.3),
    ] {
        let bytes = std::fs::read(root(file)).unwrap();
        let mut r = Counting { inner: std::io::Cursor::new(&bytes), read: 0 };
        let got = io::read_geotiff_window(&mut r, Path::new(file), win).unwrap();
        assert!(got.elevation.data.iter().all(|v| v.is_finite()));
        let frac = r.read as f64 / bytes.len() as f64;
        eprintln!("{file}: {win}: read {} of {} bytes ({:.1} %)", r.read, bytes.len(), 100.0 * frac);
        assert!(frac < share, "{file}: read {} of {} bytes", r.read, bytes.len());
        // the whole read reads it all
        let mut r = Counting { inner: std::io::Cursor::new(&bytes), read: 0 };
        io::read_geotiff(&mut r, Path::new(file)).unwrap();
        assert!(r.read as f64 > 0.9 * bytes.len() as f64, "{file}: whole read {} of {}", r.read, bytes.len());
    }
}

/// The whole raster's conditions and a partition of it into `nx × ny` windows.
fn partition(w: usize, h: usize, nx: usize, ny: usize) -> Vec<Window> {
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (c0, c1, r0, r1) = (i * w / nx, (i + 1) * w / nx, j * h / ny, (j + 1) * h / ny);
            out.push(Window { col0: c0, row0: r0, width: c1 - c0, height: r1 - r0 });
        }
    }
    out
}

/// The DEMs whose fields are compared, with partitions.
const DEMS: [(&str, usize, usize); 4] = [
    ("terrains/jacksboro_fault_dem_utm16n.tif", 2, 2),
    ("terrains/jacksboro_fault_dem_utm16n.tif", 3, 1),
    ("terrains/coweeta_basin_10m_utm17n.tif", 2, 2),
    ("terrains/jacksboro_fault_dem.tif", 1, 3),
];

/// The DEM window holding `out` and the fields' halo, read by window.
fn patch_for(path: &Path, out: &Window) -> io::DemWindow {
    let head = io::load_window(path, Window { col0: 0, row0: 0, width: 1, height: 1 }).unwrap();
    let halo = fields::window_halo_cells(&head.geo, head.full_height);
    io::load_window(path, out.with_halo(halo, head.full_width, head.full_height)).unwrap()
}

#[test]
fn slope_and_aspect_of_a_window_with_a_one_cell_halo_equal_the_whole() {
    for (file, nx, ny) in DEMS {
        let path = root(file);
        let t = io::load(&path).unwrap();
        let m = fields::mask(&t, 0.0);
        let (slope, aspect) = fields::slope_aspect(&t, &m);
        let full = Window::full(m.width, m.height);
        for out in partition(m.width, m.height, nx, ny) {
            // only the one cell of halo, read by window
            let dem = io::load_window(&path, out.with_halo(1, m.width, m.height)).unwrap();
            let pm = dem.elevation.map(|z| z.is_finite() && *z > 0.0);
            let p = fields::Patch { z: &dem.elevation, m: &pm, at: dem.window, full_w: m.width, full_h: m.height, geo: &dem.geo };
            let (s, a) = fields::slope_aspect_window(&p, &out).unwrap();
            assert_bits(&s, &out.cut(&slope, &full), &format!("{file} slope {out}"));
            assert_bits(&a, &out.cut(&aspect, &full), &format!("{file} aspect {out}"));
            // without the halo it is refused, naming what it needs
            let bare = io::load_window(&path, out).unwrap();
            let bm = bare.elevation.map(|z| z.is_finite() && *z > 0.0);
            let p = fields::Patch { z: &bare.elevation, m: &bm, at: out, full_w: m.width, full_h: m.height, geo: &bare.geo };
            if out.with_halo(1, m.width, m.height) != out {
                let e = fields::slope_aspect_window(&p, &out).unwrap_err().to_string();
                assert!(e.contains("slope and aspect") && e.contains("1 cells around it"), "{e}");
            }
        }
    }
}

#[test]
fn insolation_and_wind_of_a_window_with_the_horizon_halo_equal_the_whole() {
    let sky = fields::SkyParams::default();
    for (file, nx, ny) in DEMS {
        let path = root(file);
        let t = io::load(&path).unwrap();
        let m = fields::mask(&t, 0.0);
        let (ins, wind) = fields::insolation_and_wind(&t, &m, 45.0, 270.0, &sky);
        let full = Window::full(m.width, m.height);
        let halo = fields::horizon_halo_cells(&t.geo, m.height, &sky);
        // the largest geometric step (×1.5) within the 128-cell cap: 86 cells (6.9 km on 80 m
        // cells, 0.86 km on 10 m), on the geographic grid as well
        assert_eq!(halo, 86, "{file}");
        for out in partition(m.width, m.height, nx, ny) {
            let dem = patch_for(&path, &out);
            assert!(dem.window != full, "{file}: the patch of {out} should not be the whole raster");
            let pm = dem.elevation.map(|z| z.is_finite() && *z > 0.0);
            let p = fields::Patch { z: &dem.elevation, m: &pm, at: dem.window, full_w: m.width, full_h: m.height, geo: &dem.geo };
            let (i, w) = fields::insolation_and_wind_window(&p, &out, 45.0, 270.0, &sky).unwrap();
            assert_bits(&i, &out.cut(&ins, &full), &format!("{file} insolation {out}"));
            assert_bits(&w, &out.cut(&wind, &full), &format!("{file} wind {out}"));
            // a patch one cell short of the halo on a side that has room is refused
            let short = out.with_halo(halo - 1, m.width, m.height);
            if short != out.with_halo(halo, m.width, m.height) {
                let sh = io::load_window(&path, short).unwrap();
                let sm = sh.elevation.map(|z| z.is_finite() && *z > 0.0);
                let p = fields::Patch { z: &sh.elevation, m: &sm, at: short, full_w: m.width, full_h: m.height, geo: &sh.geo };
                let e = fields::insolation_and_wind_window(&p, &out, 45.0, 270.0, &sky).unwrap_err().to_string();
                assert!(e.contains("insolation") && e.contains("86 cells around it"), "{e}");
            }
        }
    }
}

#[test]
fn every_condition_of_a_window_equals_the_whole_sites() {
    // mask, elevation, temperature, TWI (cell by cell, from the window's hydrology: the
    // fallback derives it on the whole raster), slope, aspect, insolation, wind and the indices
    let climate = Climate::default();
    for (file, nx, ny) in DEMS {
        let path = root(file);
        let t = io::load(&path).unwrap();
        let site = conditions::derive(&t, &climate).unwrap();
        let m = fields::mask(&t, climate.sea_level_m);
        let parts = partition(m.width, m.height, nx, ny);
        let hydro = fields::hydrology_windows(&t, &m, &parts).unwrap();
        let full = Window::full(m.width, m.height);
        let mut masked = 0;
        for (out, (filled, acc)) in parts.iter().zip(hydro) {
            let dem = patch_for(&path, out);
            let c = conditions::derive_window(&dem, out, &climate, filled, acc).unwrap();
            let what = |f: &str| format!("{file} {f} {out}");
            assert_eq!(c.mask, out.cut(&site.mask, &full), "{}", what("mask"));
            for (name, a, b) in [
                ("elevation", &c.elevation_m, &site.elevation_m),
                ("slope", &c.slope_deg, &site.slope_deg),
                ("aspect", &c.aspect_deg, &site.aspect_deg),
                ("TWI", &c.twi, &site.twi),
                ("insolation", &c.insolation_kwh_m2, &site.insolation_kwh_m2),
                ("wind", &c.wind_exposure, &site.wind_exposure),
                ("temperature", &c.temperature_c, &site.temperature_c),
            ] {
                assert_bits(a, &out.cut(b, &full), &what(name));
            }
            let idx = out.cut(&site.indices, &full);
            assert!(c.indices.data.iter().zip(&idx.data).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)), "{}", what("indices"));
            assert_eq!((c.cell_x_m.to_bits(), c.cell_y_m.to_bits(), &c.geo), (site.cell_x_m.to_bits(), site.cell_y_m.to_bits(), &site.geo), "{}", what("cell size"));
            masked += c.mask.data.iter().filter(|v| !**v).count();
        }
        // the projected DEMs' nodata corners or outline fall in the windows (the geographic
        // one has none)
        assert_eq!(masked > 0, !file.ends_with("jacksboro_fault_dem.tif"), "{file}: {masked} masked cells");
    }
}

#[test]
fn the_median_insolation_by_selection_over_windows_equals_the_sorted_median() {
    use sylva::sim::tiles::{LocalTransport, Transport};
    let climate = Climate::default();
    for (file, nx, ny) in DEMS {
        let t = io::load(&root(file)).unwrap();
        let site = conditions::derive(&t, &climate).unwrap();
        let mut all: Vec<f32> = site.insolation_kwh_m2.data.iter().zip(&site.mask.data).filter(|(_, m)| **m).map(|(v, _)| *v).collect();
        all.sort_by(|a, b| a.total_cmp(b));
        let want = all[all.len() / 2];
        let full = Window::full(site.width(), site.height());
        let parts = partition(site.width(), site.height(), nx, ny);
        let ends = LocalTransport::group(parts.len());
        let got: Vec<f32> = std::thread::scope(|s| {
            let hs: Vec<_> = parts
                .iter()
                .zip(ends)
                .map(|(out, mut tr)| {
                    let (ins, m) = (out.cut(&site.insolation_kwh_m2, &full), out.cut(&site.mask, &full));
                    s.spawn(move || sylva::sim::world::insolation_median_by(&ins, &m, &mut |v| tr.all_sum(v)).unwrap())
                })
                .collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for g in &got {
            assert_eq!(g.to_bits(), want.to_bits(), "{file}: {g} vs {want}");
        }
        // and in one part
        let one = sylva::sim::world::insolation_median_by(&site.insolation_kwh_m2, &site.mask, &mut sylva::sim::stats::alone).unwrap();
        assert_eq!(one.to_bits(), want.to_bits(), "{file}");
    }
}

/// Bit equality of two sites' every grid and scalar.
fn assert_same_site(a: &conditions::SiteConditions, b: &conditions::SiteConditions, what: &str) {
    assert_eq!((&a.geo, a.cell_x_m.to_bits(), a.cell_y_m.to_bits(), &a.mask), (&b.geo, b.cell_x_m.to_bits(), b.cell_y_m.to_bits(), &b.mask), "{what}");
    for (name, x, y) in [
        ("elevation", &a.elevation_m, &b.elevation_m),
        ("slope", &a.slope_deg, &b.slope_deg),
        ("aspect", &a.aspect_deg, &b.aspect_deg),
        ("TWI", &a.twi, &b.twi),
        ("insolation", &a.insolation_kwh_m2, &b.insolation_kwh_m2),
        ("wind", &a.wind_exposure, &b.wind_exposure),
        ("temperature", &a.temperature_c, &b.temperature_c),
    ] {
        assert_bits(x, y, &format!("{what}: {name}"));
    }
    assert!(a.indices.data.iter().zip(&b.indices.data).all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)) && a.indices.data.len() == b.indices.data.len(), "{what}: indices");
}

/// `site_ranks::site_by_ranks_held(.., false)` over `n` in-process ranks: rank 0 holds `one`,
/// rank `k` its band of rows `k · h / n .. (k + 1) · h / n` of it, bit for bit.
fn assert_bands_of(sc: &sylva::sim::Scenario, one: &conditions::SiteConditions, n: usize, what: &str) {
    use sylva::sim::tiles::LocalTransport;
    let got: Vec<conditions::SiteConditions> = std::thread::scope(|s| {
        let hs: Vec<_> = LocalTransport::group(n).into_iter().map(|mut t| s.spawn(move || sylva::job::site_ranks::site_by_ranks_held(sc, &mut t, false).unwrap())).collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (k, site) in got.iter().enumerate() {
        let mut want = one.clone();
        if k != 0 {
            want.hold(sylva::job::site_ranks::band(k, n, one.width(), one.height()));
        }
        assert_eq!((site.held, site.full), (want.held, want.full), "{what}, rank {k}");
        assert_same_site(site, &want, &format!("{what}, rank {k} (band)"));
    }
}

#[test]
fn ranks_deriving_their_bands_of_a_geotiff_site_hold_the_site_of_one_process() {
    // `job::site_ranks::site_by_ranks` over the in-process transport (the exchanges of an
    // `mpirun`): a scenario's window of a file, a whole stripped file with nodata corners, the
    // geographic DEM; 2, 3 and 5 ranks (5 bands of a 40-row site: some bands lie wholly in
    // another's halo)
    use sylva::sim::tiles::LocalTransport;
    for (terrain, what) in [
        (format!("path = \"{}\"\nwindow = [140, 100, 60, 40]", root("terrains/coweeta_10m_utm17n.tif").display()), "Coweeta window"),
        (format!("path = \"{}\"", root("terrains/jacksboro_fault_dem_utm16n.tif").display()), "default DEM"),
        (format!("path = \"{}\"\nwindow = [10, 20, 200, 150]", root("terrains/jacksboro_fault_dem.tif").display()), "geographic window"),
    ] {
        let toml = format!("name = \"bands\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\nlight_cell_m = 10.0\n[terrain]\n{terrain}\n");
        let sc = sylva::sim::Scenario::from_toml_str(&toml, "bands").unwrap();
        let one = sc.site().unwrap();
        for n in [2, 3, 5] {
            let got: Vec<conditions::SiteConditions> = std::thread::scope(|s| {
                let hs: Vec<_> = LocalTransport::group(n).into_iter().map(|mut t| { let sc = &sc; s.spawn(move || sylva::job::site_ranks::site_by_ranks(sc, &mut t).unwrap()) }).collect();
                hs.into_iter().map(|h| h.join().unwrap()).collect()
            });
            for (k, site) in got.iter().enumerate() {
                assert_same_site(site, &one, &format!("{what}, rank {k} of {n}"));
            }
            // issue 37 round 32: ranks other than 0 keep only their band (rank 0 the whole)
            assert_bands_of(&sc, &one, n, &format!("{what}, {n} ranks"));
        }
    }
    // a uniform site (its band built directly) and an ASCII grid (derived whole, then cut)
    let asc = std::env::temp_dir().join(format!("sylva-bands-{}.asc", std::process::id()));
    let mut grid = String::from("ncols 7\nnrows 9\nxllcorner 0\nyllcorner 0\ncellsize 25\nNODATA_value -9999\n");
    for r in 0..9 {
        grid.push_str(&(0..7).map(|c| if (r + c) % 5 == 0 { "-9999".to_string() } else { format!("{}", 400 + 3 * r + c) }).collect::<Vec<_>>().join(" "));
        grid.push('\n');
    }
    std::fs::write(&asc, grid).unwrap();
    for terrain in ["uniform = { width = 13, height = 11, cell_m = 20.0, elevation_m = 500.0, indices = [5, 5, 3, 5, 6, 6] }".to_string(), format!("path = \"{}\"", asc.display())] {
        let toml = format!("name = \"bands\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\nlight_cell_m = 10.0\n[terrain]\n{terrain}\n");
        let sc = sylva::sim::Scenario::from_toml_str(&toml, "bands").unwrap();
        let one = sc.site().unwrap();
        for n in [2, 3, 12] {
            assert_bands_of(&sc, &one, n, &format!("{terrain}, {n} ranks"));
        }
    }
    let _ = std::fs::remove_file(&asc);
    // a window outside the file fails on every rank as one process fails
    let toml = format!("name = \"bands\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\npath = \"{}\"\nwindow = [300, 0, 100, 10]\n", root("terrains/coweeta_10m_utm17n.tif").display());
    let sc = sylva::sim::Scenario::from_toml_str(&toml, "bands").unwrap();
    let want = sc.site().unwrap_err().to_string();
    let errs: Vec<String> = std::thread::scope(|s| {
        let hs: Vec<_> = LocalTransport::group(2).into_iter().map(|mut t| { let sc = &sc; s.spawn(move || sylva::job::site_ranks::site_by_ranks(sc, &mut t).unwrap_err().to_string()) }).collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(errs.iter().all(|e| *e == want), "{errs:?} vs {want}");
}

#[test]
fn the_kth_smallest_by_counts_is_the_sorted_kth_for_every_k() {
    use sylva::sim::stats::{alone, kth_smallest_by};
    use sylva::sim::tiles::{LocalTransport, Transport};
    // duplicates, both zeros, negatives, infinities, subnormals and a NaN, in total_cmp order
    let mut x = 99u64;
    let mut v: Vec<f32> = (0..400)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x % 2001) as f32 - 1000.0) / 8.0
        })
        .collect();
    v.extend([0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE / 4.0, f32::NAN, 3.0, 3.0]);
    let mut sorted = v.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    for k in 0..v.len() {
        let got = kth_smallest_by(&v, k as u64, &mut alone).unwrap().unwrap();
        assert_eq!(got.to_bits(), sorted[k].to_bits(), "k = {k}: {got} vs {}", sorted[k]);
    }
    assert_eq!(kth_smallest_by(&v, v.len() as u64, &mut alone).unwrap(), None);
    assert_eq!(kth_smallest_by(&[], 0, &mut alone).unwrap(), None);
    // in three parts of different sizes, over the in-process transport
    let parts = [&v[..50], &v[50..51], &v[51..]];
    for k in [0, 1, 203, 204, v.len() - 1] {
        let got: Vec<Option<f32>> = std::thread::scope(|s| {
            let hs: Vec<_> = LocalTransport::group(3).into_iter().zip(parts).map(|(mut t, p)| s.spawn(move || kth_smallest_by(p, k as u64, &mut |c| t.all_sum(c)).unwrap())).collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert!(got.iter().all(|g| g.map(f32::to_bits) == Some(sorted[k].to_bits())), "k = {k}: {got:?} vs {}", sorted[k]);
    }
}

#[test]
fn hydrology_by_bands_equals_the_whole_rasters_on_real_dems() {
    // round 34 (issue 37): the fill, flat routing and accumulation of each band of rows,
    // computed from its rows, two rows of halo and the three perimeter exchanges
    // (`terrain::hydrology`, `job::hydrology_ranks`), equal the whole raster's bit for bit for
    // 1, 2, 3 and 7 bands; the Int16 Jacksboro DEM and the Coweeta basin's nodata edge give
    // flats and inner outlets
    let climate = Climate::default();
    for file in ["terrains/coweeta_basin_10m_utm17n.tif", "terrains/coweeta_10m_utm17n.tif", "terrains/jacksboro_fault_dem.tif", "terrains/jacksboro_fault_dem_utm16n.tif"] {
        let t = io::load(&root(file)).unwrap();
        let m = fields::mask(&t, climate.sea_level_m);
        let filled = fields::fill_depressions(&t, &m);
        let dir = fields::flow_directions(&filled, &t.geo, &m);
        let acc = fields::flow_accumulation(&dir, &m);
        let full = Window::full(m.width, m.height);
        let raised = filled.data.iter().zip(&t.elevation.data).filter(|(a, b)| a > b).count();
        eprintln!("{file}: {} x {} cells, {raised} raised by the fill", m.width, m.height);
        for n in [1, 2, 3, 7] {
            let bands: Vec<Window> = (0..n).map(|k| sylva::job::site_ranks::band(k, n, m.width, m.height)).collect();
            let got = sylva::job::hydrology_ranks::hydrology_by_bands(&t, &m, &bands).unwrap();
            for (b, (f, a)) in bands.iter().zip(got) {
                assert_bits(&f, &b.cut(&filled, &full), &format!("{file} {n} bands: filled {b}"));
                assert_bits(&a, &b.cut(&acc, &full), &format!("{file} {n} bands: accumulation {b}"));
            }
        }
    }
}
