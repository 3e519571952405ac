//! QA fixes of the simulation: fresh runs clear old snapshots, start conditions outside the
//! site and bad climate values are rejected with errors naming the field.
mod common;
use sylva::job::run::{run_scenario, RunOptions};
use sylva::sim::{fixtures, Scenario, TerrainSpec};

const SC: &str = r#"
name = "qa"
years = 2
seed = 1
snapshot_every = 1
[terrain]
uniform = { width = 4, height = 3, cell_m = 25.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "seed_sources"
species = "beech"
points = [[20.0, 20.0], [80.0, 50.0]]
trees_per_source = 2
"#;

fn site(sc: &Scenario) -> sylva::conditions::SiteConditions {
    let TerrainSpec::Uniform(u) = sc.terrain_spec() else { panic!() };
    sylva::conditions::SiteConditions::uniform(u.width, u.height, u.cell_m, u.elevation_m, u.indices, sc.climate.latitude_deg)
}

fn names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn fresh_run_removes_old_snapshots() {
    let lib = fixtures::library();
    let dir = tempfile::tempdir().unwrap();
    let inv = dir.path().join("inventory");
    let maps = dir.path().join("maps");
    std::fs::create_dir_all(&inv).unwrap();
    std::fs::create_dir_all(&maps).unwrap();
    for f in ["year_0050.csv", "year_0050.geojson", "year_0050.gpkg"] {
        std::fs::write(inv.join(f), "old").unwrap();
    }
    for f in ["species_year_0050.png", "basal_area_year_0050.png", "notes.txt"] {
        std::fs::write(maps.join(f), "old").unwrap();
    }
    std::fs::write(inv.join("mine.csv"), "keep").unwrap();
    let sc = Scenario::from_toml_str(SC, "qa").unwrap();
    let mut opts = RunOptions::new(dir.path());
    opts.map_px = 64;
    run_scenario(&sc, site(&sc), &lib, opts).unwrap();
    let inv_names = names(&inv);
    assert!(!inv_names.iter().any(|n| n.contains("0050")), "{inv_names:?}");
    assert!(inv_names.contains(&"year_0002.parquet".to_string()) && inv_names.contains(&"mine.csv".to_string()), "{inv_names:?}");
    let map_names = names(&maps);
    assert!(!map_names.iter().any(|n| n.contains("0050")), "{map_names:?}");
    assert!(map_names.contains(&"notes.txt".to_string()) && map_names.contains(&"species_year_0002.png".to_string()), "{map_names:?}");
}

#[test]
fn start_outside_site_is_an_error() {
    let lib = fixtures::library();
    // site: 4 x 3 cells of 25 m = 100 m x 75 m
    let sc = Scenario::from_toml_str(&SC.replace("[80.0, 50.0]", "[80.0, 150.0]"), "qa").unwrap();
    let e = sylva::sim::World::new(site(&sc), &lib, &sc).unwrap_err().to_string();
    assert!(e.contains("start[0].points[1]") && e.contains("[80, 150]") && e.contains("75"), "{e}");
    let planted = format!("{SC}\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 2.0\narea = [10.0, 10.0, 150.0, 50.0]\n");
    let sc = Scenario::from_toml_str(&planted, "qa").unwrap();
    let e = sylva::sim::World::new(site(&sc), &lib, &sc).unwrap_err().to_string();
    assert!(e.contains("start[1].area") && e.contains("150") && e.contains("100 m"), "{e}");
    let inside = planted.replace("150.0, 50.0]", "100.0, 75.0]");
    let sc = Scenario::from_toml_str(&inside, "qa").unwrap();
    let w = sylva::sim::World::new(site(&sc), &lib, &sc).unwrap();
    // 45 x 32 lattice of 2 m in the 90 m x 65 m area, plus 2 x 2 seed-source trees
    assert_eq!(w.stand.trees.len(), 45 * 32 + 4);
}

#[test]
fn bad_climate_is_an_error() {
    let cases = [
        ("lapse_rate_k_per_km = nan", "climate.lapse_rate_k_per_km", "NaN"),
        ("reference_temperature_c = inf", "climate.reference_temperature_c", "inf"),
        ("latitude_deg = 120.0", "climate.latitude_deg", "120"),
        ("lapse_rate_k_per_km = -40.0", "climate.lapse_rate_k_per_km", "-40"),
        ("reference_temperature_c = 55.0", "climate.reference_temperature_c", "55"),
        ("continentality_k = 0.0", "climate.continentality_k", "0"),
        ("reaction_r = 12.0", "climate.reaction_r", "12"),
        ("nitrogen_n = -1.0", "climate.nitrogen_n", "-1"),
        ("wind_from_deg = 400.0", "climate.wind_from_deg", "400"),
    ];
    for (line, field, value) in cases {
        let text = format!("{SC}\n[climate]\n{line}\n");
        let e = Scenario::from_toml_str(&text, "qa.toml").unwrap_err().to_string();
        assert!(e.contains("qa.toml") && e.contains(field) && e.contains(value), "{line}: {e}");
    }
    let ok = format!("{SC}\n[climate]\nlapse_rate_k_per_km = -5.0\nwind_from_deg = 360.0\nreference_temperature_c = -2.5\n");
    assert!(Scenario::from_toml_str(&ok, "qa.toml").is_ok());
}

#[test]
fn young_random_deaths_are_background_not_age() {
    use sylva::sim::DeathCause;
    let (sc, mut w) = {
        let lib = fixtures::library();
        let sc = Scenario::from_toml_str(&SC.replace("years = 2", "years = 30").replace("trees_per_source = 2", "trees_per_source = 60"), "qa").unwrap();
        let w = sylva::sim::World::new(site(&sc), &lib, &sc).unwrap();
        (sc, w)
    };
    let mut seen = [0u64; 4];
    for _ in 0..30 {
        sylva::sim::step_year(&mut w, &sc, &mut sylva::sim::YearReport::default());
        for d in &w.scratch.dead {
            seen[d.cause.index()] += 1;
            let max = w.site.lib.species[d.species as usize].life.max_age_yr;
            match d.cause {
                DeathCause::Age => assert!(d.age >= sylva::sim::trees::SENESCENT_AGE_SHARE * max, "age death at {} of max {max}", d.age),
                DeathCause::Background => assert!(d.age < sylva::sim::trees::SENESCENT_AGE_SHARE * max),
                _ => {}
            }
        }
    }
    assert!(seen[DeathCause::Background.index()] > 0, "no background deaths: {seen:?}");
    let names: Vec<&str> = w.site.pool.iter().map(|&s| w.site.lib.species[s as usize].id.as_str()).collect();
    let csv = sylva::output::stand_table::stand_table_csv(&[sylva::sim::stats::stand_row(&w)], &names);
    assert!(csv.lines().next().unwrap().contains(",deaths_age,deaths_stress,deaths_wind,deaths_background,deaths_harvest,volume_m3_ha,harvest_stems_ha,harvest_volume_m3_ha,temperature_offset_k,precipitation_factor"), "{csv}");
    assert_eq!(csv.lines().nth(1).unwrap().split(',').count(), csv.lines().next().unwrap().split(',').count());
}

#[test]
fn scenario_errors_in_plain_words_and_name_the_file() {
    let e = Scenario::from_toml_str(&SC.replace("years = 2", "years = -5"), "dir/qa.toml").unwrap_err().to_string();
    assert!(e.contains("dir/qa.toml") && e.contains("whole number") && !e.contains("u32"), "{e}");
    let lib = fixtures::library();
    let sc = Scenario::from_toml_str(&format!("species = [\"beech\", \"baobab\"]\n{SC}"), "dir/qa.toml").unwrap();
    let e = sylva::sim::World::new(site(&sc), &lib, &sc).unwrap_err().to_string();
    assert!(e.contains("dir/qa.toml") && e.contains("species[1]") && e.contains("baobab"), "{e}");
}

#[test]
fn threads_out_of_range_is_rejected() {
    let exe = env!("CARGO_BIN_EXE_sylva");
    for bad in ["0", "257", "-1", "many"] {
        let out = std::process::Command::new(exe).args(["simulate", "no_such.toml", &format!("--threads={bad}")]).output().unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--threads") && err.contains("1 to 256"), "{bad}: {err}");
    }
}

#[test]
fn maps_are_large_with_legend_and_distinct_species_colours() {
    use sylva::output::plot::{species_color, SPECIES_PALETTE};
    let lib = fixtures::library();
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{SC}\n[[start]]\nkind = \"planted\"\nspecies = \"birch\"\nspacing_m = 2.0\narea = [0.0, 0.0, 40.0, 75.0]\n").replace("years = 2", "years = 3");
    let sc = Scenario::from_toml_str(&text, "qa").unwrap();
    let mut opts = RunOptions::new(dir.path());
    opts.map_px = 64;
    let sum = run_scenario(&sc, site(&sc), &lib, opts).unwrap();
    let w = &sum.world;
    // distinct categorical colours per pool species
    let cols: Vec<[u8; 3]> = w.site.pool.iter().map(|&s| species_color(w, s)).collect();
    for (i, a) in cols.iter().enumerate() {
        assert!(cols[..i].iter().all(|b| b != a), "{cols:?}");
    }
    assert_eq!(cols[0], SPECIES_PALETTE[0]);
    // every two colours of the palette are told apart: CIE 1976 ΔE*ab ≥ 25, ≥ 35 among the first
    // 8 (sRGB → CIELAB, D65; the palette before round 24 had beech and sycamore at 12.9)
    let lab = |c: [u8; 3]| {
        let lin = |u: u8| {
            let u = u as f64 / 255.0;
            if u > 0.04045 { ((u + 0.055) / 1.055).powf(2.4) } else { u / 12.92 }
        };
        let (r, g, b) = (lin(c[0]), lin(c[1]), lin(c[2]));
        let f = |t: f64| if t > 0.008856 { t.cbrt() } else { 7.787 * t + 16.0 / 116.0 };
        let (x, y, z) = (f((0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047), f(0.2126 * r + 0.7152 * g + 0.0722 * b), f((0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883));
        [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
    };
    for (i, a) in SPECIES_PALETTE.iter().enumerate() {
        for b in &SPECIES_PALETTE[..i] {
            let (p, q) = (lab(*a), lab(*b));
            let de = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            // the first 8 (a pool as large as the default run's) farther apart still
            let least = if i < 8 { 35.0 } else { 25.0 };
            assert!(de >= least, "{a:?} and {b:?} (colours {i} and before): ΔE*ab {de:.1}");
        }
    }
    for name in ["species_year_0003.png", "basal_area_year_0003.png"] {
        let p = dir.path().join("maps").join(name);
        let img = image::open(&p).unwrap().to_rgb8();
        assert!(img.width().max(img.height()) >= 512, "{name}: {}x{}", img.width(), img.height());
        if std::env::var("SYLVA_KEEP").is_ok() {
            std::fs::copy(&p, format!("/tmp/{name}")).unwrap();
            std::fs::copy(dir.path().join("stand_table.png"), "/tmp/stand_table.png").unwrap();
        }
    }
    // GeoTIFF twins: basal area (m²/ha) summed over the map's cells gives back the trees'
    // basal area (mass balance); species codes are 0 or a pool position listed in the CSV.
    let ba = sylva::terrain::io::load(&dir.path().join("maps/basal_area_year_0003.tif")).unwrap();
    let cell_m = ba.geo.pixel_w;
    let total_ba: f64 = ba.elevation.data.iter().filter(|v| v.is_finite()).map(|&v| v as f64 * cell_m * cell_m / 10_000.0).sum();
    let trees_ba: f64 = (0..w.stand.trees.len()).map(|i| w.stand.trees.basal_area_m2(i)).sum();
    assert!(trees_ba > 0.01 && (total_ba - trees_ba).abs() < 1e-3 * trees_ba, "map {total_ba} m² vs trees {trees_ba} m²");
    // (a Byte raster with a colour table since trial 37; 255 marks masked cells)
    let (sw, sh, codes) = common::palette_geotiff_codes(&std::fs::read(dir.path().join("maps/species_year_0003.tif")).unwrap());
    assert_eq!((sw as usize, sh as usize), (ba.elevation.width, ba.elevation.height));
    let codes: Vec<u8> = codes.into_iter().filter(|&c| c != 255).collect();
    assert!(codes.iter().all(|&c| c as usize <= w.site.pool.len()), "{codes:?}");
    assert!(codes.iter().any(|&c| c >= 1));
    let csv_text = std::fs::read_to_string(dir.path().join("maps/species_codes.csv")).unwrap();
    assert!(csv_text.starts_with("code,species\n0,none\n1,"), "{csv_text}");
    assert_eq!(csv_text.lines().count(), w.site.pool.len() + 2);

    // the legend swatch of the first pool species (right of the map) has its colour
    let img = image::open(dir.path().join("maps/species_year_0003.png")).unwrap().to_rgb8();
    let found = img.pixels().filter(|p| p.0 == cols[0]).count();
    assert!(found >= 16 * 12, "legend swatch missing: {found} px");

    // the basal-area map carries the species map's caption under its map ("… m × … m, map cell
    // … m"; found by a trial: it had none): the caption's pixels, cut from under the species
    // map (its left edge at x = 12, the map starting at y = 44), recur in the basal-area map
    // (to within 2 levels of 255: the anti-aliasing rounds alike, not bit for bit)
    let white = [255u8, 255, 255];
    let mh = (44..img.height()).take_while(|&y| img.get_pixel(12, y).0 != white).count() as u32;
    let (cx0, cx1) = (12u32, 260u32);
    let band: Vec<Vec<[u8; 3]>> = (44 + mh + 1..44 + mh + 21).map(|y| (cx0..cx1).map(|x| img.get_pixel(x, y).0).collect()).collect();
    let dark = band.iter().flatten().filter(|p| p[0] < 100).count();
    assert!(dark > 100, "the species map's caption: {dark} dark pixels");
    let ba_img = image::open(dir.path().join("maps/basal_area_year_0003.png")).unwrap().to_rgb8();
    let found = (0..ba_img.height().saturating_sub(band.len() as u32)).find(|&y0| band.iter().enumerate().all(|(i, row)| row.iter().enumerate().all(|(j, p)| ba_img.get_pixel(cx0 + j as u32, y0 + i as u32).0.iter().zip(p).all(|(a, b)| a.abs_diff(*b) <= 2))));
    assert!(found.is_some_and(|y| y > 44), "the basal-area map lacks the species map's caption");
}

#[test]
fn pool_and_png_terrain_keys_are_checked() {
    // a start whose species is not in the pool, and a species listed twice
    let e = Scenario::from_toml_str(&format!("species = [\"silver_birch\"]\n{SC}"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("p.toml") && e.contains("start[0].species") && e.contains("beech"), "{e}");
    // a pool entry misspelt (two letters from the start's species) is named, not the start
    let e = Scenario::from_toml_str(&format!("species = [\"silver_birch\", \"beeech\"]\n{SC}"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("species[1]") && e.contains("beeech") && !e.contains("start[0].species"), "{e}");
    // and a start's species misspelt is named, not the pool entry it is near (round 26 trial)
    let e = Scenario::from_toml_str(&format!("species = [\"beech\", \"silver_birch\"]\n{}", SC.replace("species = \"beech\"", "species = \"beeech\"")), "p.toml").unwrap_err().to_string();
    assert!(e.contains("`start[0].species` = beeech") && e.contains("did you mean `beech`"), "{e}");
    // a wrong-length array in the second [[start]] (serde points at the first one): the
    // table's index, the key and its line (round 26 trial); an inner array too short as well
    let two = format!("{SC}[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 2.0\narea = [10, 10, 50]\n");
    let line = two.lines().position(|l| l.starts_with("area")).unwrap() + 1;
    let e = Scenario::from_toml_str(&two, "p.toml").unwrap_err().to_string();
    assert!(e.contains(&format!("`start[1].area` (line {line}): expected an array of 4 numbers")), "{e}");
    let line = SC.lines().position(|l| l.starts_with("points")).unwrap() + 1;
    let e = Scenario::from_toml_str(&SC.replace("[80.0, 50.0]]", "[80.0, 50.0, 3.0]]"), "p.toml").unwrap_err().to_string();
    assert!(e.contains(&format!("`start[0].points` (line {line}): expected an array of 2 numbers")), "{e}");
    // a blank name and a height no land has are refused (round 26 trial)
    let e = Scenario::from_toml_str(&SC.replace("name = \"qa\"", "name = \" \""), "p.toml").unwrap_err().to_string();
    assert!(e.contains("`name`") && e.contains("a name for the scenario"), "{e}");
    let e = Scenario::from_toml_str(&SC.replace("elevation_m = 300.0", "elevation_m = nan"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("`terrain.uniform.elevation_m` = NaN") && e.contains("-500–9000 m"), "{e}");
    // a negative year count: the field's range, not the type's as well
    let e = Scenario::from_toml_str(&SC.replace("years = 2", "years = -5"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("`years`: expected the number of years to simulate") && e.contains("1–10000") && !e.contains("4294967295"), "{e}");
    let e = Scenario::from_toml_str(&format!("species = [\"beech\", \"beech\"]\n{SC}"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("species[1]") && e.contains("once"), "{e}");
    // cell size and height range only for PNG heightmaps, and then they are used
    let e = Scenario::from_toml_str(&SC.replace("[terrain]\n", "[terrain]\ncell_m = 2.0\n"), "p.toml").unwrap_err().to_string();
    assert!(e.contains("terrain.cell_m") && e.contains("PNG"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("h.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(8, 6, |x, _| image::Luma([(x * 9000) as u16])).save(&png).unwrap();
    let text = format!(
        "name = \"png\"\nyears = 1\n[terrain]\npath = \"{}\"\ncell_m = 25.0\nheight_range_m = [200.0, 700.0]\n",
        png.display()
    );
    let site = Scenario::from_toml_str(&text, "png.toml").unwrap().site().unwrap();
    assert_eq!(site.extent_m(), (200.0, 150.0));
    let z: Vec<f32> = site.elevation_m.data.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = z.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!((lo - 200.0).abs() < 0.5 && hi > 200.0 && hi <= 700.0 + 1e-3, "{lo} … {hi}");
}

#[test]
fn absurd_planting_and_seed_rain_are_refused() {
    let big = "name = \"big\"\nyears = 1\n[terrain]\nuniform = { width = 200, height = 200, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 0.5\n";
    let sc = Scenario::from_toml_str(big, "big.toml").unwrap();
    let e = sylva::sim::World::new(site(&sc), &fixtures::library(), &sc).err().expect("16 M trees refused").to_string();
    assert!(e.contains("start[0].spacing_m") && e.contains("5000000"), "{e}");
    let ok = big.replace("spacing_m = 0.5", "spacing_m = 2.0");
    let sc = Scenario::from_toml_str(&ok, "big.toml").unwrap();
    assert!(sylva::sim::World::new(site(&sc), &fixtures::library(), &sc).is_ok(), "1 M trees at 2 m are fine");
    let rain = SC.replace("kind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[20.0, 20.0], [80.0, 50.0]]\ntrees_per_source = 2", "kind = \"seed_rain\"\nspecies = \"beech\"\nseeds_per_ha = 1e12");
    let e = Scenario::from_toml_str(&rain, "r.toml").unwrap_err().to_string();
    assert!(e.contains("seeds_per_ha") && e.contains("100,000,000"), "{e}");
}

/// Round 40 (trial 39): a scenario's PNG heightmap without `terrain.cell_m` or
/// `terrain.height_range_m` is refused naming the scenario file, the missing field(s) and an
/// example (it ran with a warning on 10 m cells and 0–1000 m, a 512 px heightmap a 5 km site);
/// with both it runs; a GeoTIFF needs neither.
#[test]
fn a_png_heightmap_without_its_scale_is_refused_naming_the_fields() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("gaea.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(8, 6, |x, _| image::Luma([(x * 9000) as u16])).save(&png).unwrap();
    let sc = |extra: &str| format!("name = \"png\"\nyears = 1\n[terrain]\npath = \"{}\"\n{extra}", png.display());
    for (extra, want, not) in [
        ("", &["terrain.cell_m and terrain.height_range_m", "gaea.png", "cell_m = 10.0", "height_range_m = [250.0, 1250.0]"][..], "§"),
        ("cell_m = 5.0\n", &["terrain.height_range_m", "gaea.png", "metres a pixel"][..], "terrain.cell_m and"),
        ("height_range_m = [0.0, 300.0]\n", &["terrain.cell_m", "gaea.png"][..], "terrain.height_range_m`"),
    ] {
        let e = Scenario::from_toml_str(&sc(extra), "my_scenario.toml").unwrap_err().to_string();
        assert!(e.contains("my_scenario.toml") && want.iter().all(|w| e.contains(w)) && !e.contains(not), "{extra:?}: {e}");
    }
    let site = Scenario::from_toml_str(&sc("cell_m = 5.0\nheight_range_m = [0.0, 300.0]\n"), "my_scenario.toml").unwrap().site().unwrap();
    assert_eq!(site.extent_m(), (40.0, 30.0));
    let tif = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/coweeta_10m_utm17n.tif");
    Scenario::from_toml_str(&format!("name = \"tif\"\nyears = 1\n[terrain]\npath = \"{}\"\n", tif.display()), "t.toml").unwrap();
}

/// Trial 41, defect 9: a start's or a mix's species that no library holds (`fagus`) was told
/// "add it there", to the scenario's pool, which cannot help; it now points to `sylva species
/// list` and the library's species of that genus. A library species outside the pool is still
/// told to be added, by its id.
#[test]
fn a_species_no_library_holds_points_to_the_library() {
    let sc = format!("species = [\"beech\"]\n{}", SC.replace("species = \"beech\"", "species = \"fagus\""));
    let e = Scenario::from_toml_str(&sc, "u.toml").unwrap_err().to_string();
    assert!(e.contains("`start[0].species` = fagus") && e.contains("sylva species list") && e.contains("`beech` (Fagus sylvatica)") && !e.contains("add it there"), "{e}");
    let sc = format!("species = [\"silver_birch\"]\n{}", SC.replace("species = \"beech\"", "species = \"Fagus sylvatica\""));
    let e = Scenario::from_toml_str(&sc, "u.toml").unwrap_err().to_string();
    assert!(e.contains("add \"beech\" there") && !e.contains("sylva species list"), "{e}");
    // a management mix likewise
    let mix = format!("species = [\"beech\"]\n{SC}[[management]]\nkind = \"planting\"\nyear = 1\nspacing_m = 2.0\nmix = {{ quercus = 1.0 }}\n");
    let e = Scenario::from_toml_str(&mix, "u.toml").unwrap_err().to_string();
    assert!(e.contains("management[0].mix.quercus") && e.contains("sylva species list") && e.contains("`sessile_oak` (Quercus petraea)"), "{e}");
}

/// Trial 41, defect 8: `spacing_m = "1.5m"` in a `[[start]]` got serde's "invalid type: string
/// \"1.5m\", expected a number" at the first `[[start]]` header, naming neither the field nor its
/// line. The key holding that value is now named with its table's index and line.
#[test]
fn a_wrong_type_in_a_start_names_the_start_and_field() {
    let two = format!("{SC}[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = \"1.5m\"\n");
    let line = two.lines().position(|l| l.starts_with("spacing_m")).unwrap() + 1;
    let e = Scenario::from_toml_str(&two, "p.toml").unwrap_err().to_string();
    assert!(e.contains(&format!("the wrong value is `start[1].spacing_m` (line {line})")), "{e}");
    let neg = SC.replace("trees_per_source = 2", "trees_per_source = -2");
    let line = neg.lines().position(|l| l.starts_with("trees_per_source")).unwrap() + 1;
    let e = Scenario::from_toml_str(&neg, "p.toml").unwrap_err().to_string();
    assert!(e.contains(&format!("`start[0].trees_per_source` (line {line})")), "{e}");
}

/// Trial 44: a 1 × 1-cell `window` ran. A window narrower than 3 cells either way is refused,
/// naming `terrain.window`, the window and the size expected (`MIN_WINDOW_CELLS`, why: Horn's
/// 3 × 3 neighbourhood of slope and aspect); 3 × 3 is accepted.
#[test]
fn a_window_too_small_to_simulate_is_refused_naming_window_and_size() {
    use sylva::sim::scenario::MIN_WINDOW_CELLS;
    assert_eq!(MIN_WINDOW_CELLS, 3);
    let text = |w: &str| format!("name = \"w\"\nyears = 2\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nembedded = \"coweeta\"\nwindow = {w}\n");
    for (w, shown) in [("[160, 220, 1, 1]", "[160, 220, 1, 1]"), ("[160, 220, 2, 40]", "[160, 220, 2, 40]"), ("[160, 220, 40, 2]", "[160, 220, 40, 2]"), ("[160, 220, 0, 5]", "[160, 220, 0, 5]")] {
        let e = Scenario::from_toml_str(&text(w), "small.toml").unwrap_err().to_string();
        assert!(e.contains("small.toml") && e.contains("terrain.window") && e.contains(shown) && e.contains("at least 3 cells") && e.contains("3 x 3 neighbourhood"), "{w}: {e}");
    }
    assert!(Scenario::from_toml_str(&text("[160, 220, 3, 3]"), "small.toml").is_ok());
}
