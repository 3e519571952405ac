//! The main job end to end, in process ([`sylva::job::main_job::main_job`], the whole of
//! `sylva run`) on a reduced scenario (a 12 × 12-cell corner of the shipped DEM that includes
//! nodata cells, 6 years, small frames). Checks that every output exists, parses and holds sane
//! values, and that the run writes nothing [`sylva::job::main_job::OUTPUTS`] does not list.
//! Renders on the software adapter in CI. One smoke test goes through the binary.

use std::path::Path;
use std::process::Command;
use sylva::job::main_job::{self, MainJobOptions};

const SCENARIO: &str = r#"
name = "reduced main job"
years = 6
seed = 7
snapshot_every = 3
checkpoint_every = 3
species = ["beech", "silver_birch", "scots_pine"]

[terrain]
default = true
window = [10, 5, 12, 12]

[climate]
latitude_deg = 36.59
reference_temperature_c = 9.5
reference_elevation_m = 360.0

[[start]]
kind = "planted"
species = "beech"
spacing_m = 6.0
age_yr = 20.0

[[start]]
kind = "seed_rain"
species = "silver_birch"
seeds_per_ha = 500.0

[[start]]
kind = "seed_sources"
species = "scots_pine"
points = [[700, 200]]
trees_per_source = 5
"#;

fn png_variance(path: &Path) -> f64 {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    let n = (img.width() * img.height()) as f64;
    let mean: f64 = img.pixels().map(|p| p[1] as f64).sum::<f64>() / n;
    img.pixels().map(|p| (p[1] as f64 - mean).powi(2)).sum::<f64>() / n
}

/// Every file under `dir`, as `/`-separated paths relative to it.
fn files(dir: &Path, base: &Path, out: &mut Vec<String>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, base, out);
        } else {
            out.push(p.strip_prefix(base).unwrap().to_string_lossy().replace('\\', "/"));
        }
    }
}

#[test]
fn main_job_reduced_scenario_writes_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let sc = sylva::sim::Scenario::from_toml_str(SCENARIO, "reduced.toml").unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let out = dir.path().join("out");
    // leftovers of an earlier, longer run into the same folder must not survive
    for stale in ["stills/year_0099_oblique.png", "frames/frame_00042.png"] {
        std::fs::create_dir_all(out.join(stale).parent().unwrap()).unwrap();
        std::fs::write(out.join(stale), b"old").unwrap();
    }
    std::fs::write(out.join("stills/notes.txt"), b"mine").unwrap();
    let mut opts = MainJobOptions::new(&out);
    opts.size = (320, 180);
    opts.timelapse_size = (160, 90);
    opts.frames_between = 1;
    let mut events: Vec<String> = Vec::new();
    let summary = main_job::main_job(&sc, &lib, &opts, &mut |e| {
        let name = format!("{e:?}");
        let name = name.split([' ', '(']).next().unwrap_or("").to_string();
        if events.last() != Some(&name) {
            events.push(name);
        }
    })
    .unwrap();
    assert!(!summary.sim.stopped && summary.sim.year == 6 && summary.sim.rows.len() == 6);
    let (table, shares) = summary.tables();
    assert!(table.contains("basal area") && shares.contains("beech"), "{table}\n{shares}");
    // the species as the maps' legends name them (trial 46 D14: the ids, `norway_maple`)
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    for id in &summary.sim.pool {
        let name = &lib.get(id).unwrap().identity.common_name;
        assert!(shares.contains(&format!("| {name} |")) && (name == id || !shares.contains(&format!("| {id} |"))), "{id}: {shares}");
    }
    assert_eq!(events, ["Begin", "Conditions", "Simulating", "Year", "Simulated", "Stills", "Still", "CloseUpBegin", "CloseUp", "StillsDone", "Timelapse", "Frame", "TimelapseDone"], "the job's steps, in order");
    assert_eq!(summary.stills.len(), 2 * 2 + 1, "oblique and top-down at year 0 (the still year within the run) and 6 (the last), one close-up: {:?}", summary.stills);
    assert_eq!(summary.film.as_ref().map(|f| f.frames), Some(5));

    // The run wrote only what OUTPUTS lists (and kept the file it did not write).
    let mut written = Vec::new();
    files(&out, &out, &mut written);
    let unlisted: Vec<&String> = written.iter().filter(|f| !main_job::is_output(f) && f.as_str() != "stills/notes.txt").collect();
    assert!(unlisted.is_empty(), "files not in main_job::OUTPUTS: {unlisted:?}");

    // Files exist.
    for f in [
        "summary.md",
        "scenario.toml",
        "stand_table.csv",
        "stand_table.png",
        "inventory/year_0000.parquet",
        "inventory/year_0006.parquet",
        "inventory/year_0006_regeneration.parquet",
        "inventory/year_0006.gpkg",
        "maps/conditions/elevation.png",
        "maps/conditions/elevation.tif",
        "maps/conditions/L.png",
        "maps/conditions/F.tif",
        "stills/year_0000_oblique.png",
        "stills/year_0006_topdown.png",
        "timelapse.gif",
        "frames/frame_00000.png",
    ] {
        assert!(out.join(f).is_file(), "missing output {f}");
    }

    // The stand table parses; species shares of basal area sum to 1 once there is basal area.
    let mut rdr = csv::Reader::from_path(out.join("stand_table.csv")).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 7, "one row per year, and year 0's (the planting)");
    let last = rows.last().unwrap();
    let ba: f64 = last[headers.iter().position(|h| h == "basal_area_m2_ha").unwrap()].parse().unwrap();
    assert!(ba > 0.5, "the planted beech has basal area, got {ba}");
    let share: f64 = headers.iter().enumerate().filter(|(_, h)| h.starts_with("ba_share_")).map(|(i, _)| last[i].parse::<f64>().unwrap()).sum();
    assert!((share - 1.0).abs() < 1e-3, "species shares sum to {share}");

    // No tree stands on a masked (nodata) cell of the window.
    let t = sylva::terrain::io::default_terrain().unwrap();
    let w = sylva::terrain::io::window(&t, 10, 5, 12, 12).unwrap();
    let masked = w.elevation.data.iter().filter(|v| !v.is_finite()).count();
    assert!(masked > 20 && masked < 120, "the window mixes nodata and valid cells ({masked} nodata)");
    let rows = sylva::job::inventory::read(&out.join("inventory/year_0006.parquet")).unwrap();
    assert!(rows.len() > 50, "trees in the final inventory: {}", rows.len());
    let cell = w.geo.cell_y_m();
    for r in rows.iter().filter(|r| r.status == "alive") {
        let col = (r.x_m / cell) as usize;
        let row = w.elevation.height - 1 - (r.y_m / cell) as usize;
        assert!(w.is_valid(col, row), "tree {} at ({}, {}) stands on a nodata cell", r.id, r.x_m, r.y_m);
        assert!(r.height_m > 0.0 && r.dbh_cm >= 0.0 && r.crown_radius_m > 0.0);
    }

    // The final year's GeoPackage has one feature per tree, georeferenced like the map
    // GeoTIFFs: UTM 16N eastings/northings, a constant offset from the local metres of the
    // inventory (tests/gpkg.rs checks the file in full and with GDAL)
    let db = rusqlite::Connection::open(out.join("inventory/year_0006.gpkg")).unwrap();
    let srs: i64 = db.query_row("SELECT srs_id FROM gpkg_geometry_columns WHERE table_name = 'inventory'", [], |r| r.get(0)).unwrap();
    assert_eq!(srs, 32616);
    let feats: Vec<(f64, f64, Vec<u8>)> = db.prepare("SELECT x_m, y_m, geom FROM inventory ORDER BY fid").unwrap().query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?))).unwrap().map(|r| r.unwrap()).collect();
    assert_eq!(feats.len(), rows.len());
    let off = |f: &(f64, f64, Vec<u8>)| (f64::from_le_bytes(f.2[13..21].try_into().unwrap()) - f.0, f64::from_le_bytes(f.2[21..29].try_into().unwrap()) - f.1);
    let (ox, oy) = off(&feats[0]);
    assert!((700_000.0..800_000.0).contains(&ox) && (4_000_000.0..4_100_000.0).contains(&oy), "offset {ox} {oy}");
    assert!(feats.iter().all(|f| (off(f).0 - ox).abs() < 0.02 && (off(f).1 - oy).abs() < 0.02));
    // summary.md says where the site's south-west corner is on the map: the same offset, so a
    // user can place the local metres (x_m, y_m, --area) in GIS without working it out
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    let corner = format!("south-west corner, at map x {ox:.2}, y {oy:.2}: map x = {ox:.2} + x_m, map y = {oy:.2} + y_m");
    assert!(md.contains("## Site and coordinates") && md.contains(&corner) && md.contains("EPSG:32616") && md.contains(&format!("{:.0} m × {:.0} m (12 × 12 cells of {} m)", 12.0 * cell, 12.0 * cell, cell)), "{corner}\n{md}");

    // Pictures are not blank: terrain and trees give contrast.
    for f in ["stills/year_0006_oblique.png", "stills/year_0006_topdown.png", "stand_table.png", "maps/conditions/elevation.png"] {
        let v = png_variance(&out.join(f));
        assert!(v > 20.0, "{f} looks blank (variance {v})");
    }
    // snapshots at years 0, 3, 6 with one interpolated frame between each pair: 5 frames
    let frames: Vec<String> = std::fs::read_dir(out.join("frames")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert_eq!(frames.len(), 5, "{frames:?}");
    assert!(!out.join("stills/year_0099_oblique.png").exists() && !out.join("frames/frame_00042.png").exists(), "stale stills/frames removed");
    assert!(out.join("stills/notes.txt").exists(), "files Sylva did not write are kept");
    let gif = std::fs::read(out.join("timelapse.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("stills/year_0006_oblique.png") && md.contains("timelapse.gif"));
    assert!(md.contains("(maps/species_year_0006.png)") && md.contains("(maps/basal_area_year_0006.png)"), "{md}");

    // `sylva render --camera closeup` draws the run's close-up again from the run directory:
    // the same camera, trees and near field, so nearly the same picture (the inventory's
    // rounded positions and heights aside); the oblique preset is another view
    let again = dir.path().join("closeup.png");
    let oblique = dir.path().join("oblique.png");
    for (cam, png) in [("closeup", &again), ("oblique", &oblique)] {
        let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["render", out.to_str().unwrap(), "--camera", cam, "--size", "320x180", "--out", png.to_str().unwrap()]).output().unwrap();
        assert!(res.status.success(), "render --camera {cam}: {}", String::from_utf8_lossy(&res.stderr));
    }
    let still = image::open(out.join("stills/year_0006_closeup.png")).unwrap().to_rgb8();
    let diff = |p: &Path| {
        let img = image::open(p).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), still.dimensions());
        img.pixels().zip(still.pixels()).map(|(a, b)| (0..3).map(|k| (a[k] as f64 - b[k] as f64).abs()).sum::<f64>() / 3.0).sum::<f64>() / (320.0 * 180.0)
    };
    let (d_close, d_obl) = (diff(&again), diff(&oblique));
    eprintln!("mean |Δ| against the run's close-up: render --camera closeup {d_close:.2}, oblique {d_obl:.2} grey levels");
    assert!(d_close < 2.0 && d_obl > 4.0 * d_close.max(1.0), "closeup {d_close:.2}, oblique {d_obl:.2}");
}

/// The binary's `sylva run`: argument parsing, the printed summary, the exit status
/// (without pictures).
#[test]
fn sylva_run_binary_smoke() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("reduced.toml");
    std::fs::write(&sc, SCENARIO).unwrap();
    let out = dir.path().join("out");
    let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap(), "--years", "2", "--no-pictures"]).output().unwrap();
    let stdout = String::from_utf8_lossy(&res.stdout);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "sylva run failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("basal area") && stdout.contains("outputs in"), "summary table printed: {stdout}");

    assert!(stderr.contains("[1/4] conditions") && stderr.contains("[2/4] simulating 2 years"), "steps reported: {stderr}");
    assert!(out.join("summary.md").is_file() && out.join("inventory/year_0002.gpkg").is_file() && !out.join("stills").exists());
    // a run without pictures into an earlier run's folder removes that run's pictures (they
    // would pass for this run's: found by a trial); files Sylva did not write stay
    let again = dir.path().join("again");
    for f in ["stills/year_0150_oblique.png", "frames/frame_00001.png", "timelapse.gif", "stills/notes.txt"] {
        std::fs::create_dir_all(again.join(f).parent().unwrap()).unwrap();
        std::fs::write(again.join(f), b"old").unwrap();
    }
    let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["run", sc.to_str().unwrap(), "--out", again.to_str().unwrap(), "--years", "1", "--no-pictures"]).output().unwrap();
    assert!(res.status.success(), "{}", String::from_utf8_lossy(&res.stderr));
    assert!(!again.join("stills/year_0150_oblique.png").exists() && !again.join("frames/frame_00001.png").exists() && !again.join("timelapse.gif").exists(), "an earlier run's pictures are left");
    assert!(again.join("stills/notes.txt").is_file(), "a file Sylva did not write was removed");
}

/// Without any graphics adapter (here: wgpu limited to a backend this machine lacks), `sylva
/// run` says so before it simulates, naming the package to install, writes every output that
/// needs no rendering, and exits non-zero; `--no-pictures` runs the same machine cleanly.
#[test]
fn without_an_adapter_sylva_run_writes_what_needs_no_rendering_and_fails() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("reduced.toml");
    std::fs::write(&sc, SCENARIO).unwrap();
    let out = dir.path().join("out");
    // Metal exists only on Apple systems: on Linux no adapter is found
    let no_gpu = if cfg!(target_os = "macos") { "dx12" } else { "metal" };
    let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap(), "--years", "2"]).env("WGPU_BACKEND", no_gpu).output().unwrap();
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(!res.status.success(), "exits non-zero without an adapter: {stderr}");
    let warn = stderr.find("mesa-vulkan-drivers").expect("names the package to install");
    let sim = stderr.find("[2/4] simulating").expect("simulates");
    assert!(warn < sim, "told before the simulation: {stderr}");
    for f in ["stand_table.csv", "inventory/year_0002.parquet", "inventory/year_0002.gpkg", "maps/conditions/elevation.tif", "summary.md"] {
        assert!(out.join(f).is_file(), "{f} written without an adapter");
    }
    assert!(!out.join("stills").exists() && !out.join("timelapse.gif").exists());
    let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap(), "--years", "2", "--no-pictures"]).env("WGPU_BACKEND", no_gpu).output().unwrap();
    assert!(res.status.success(), "--no-pictures needs no adapter: {}", String::from_utf8_lossy(&res.stderr));
}

/// Trial 46 D10: `sylva run` stopped after its simulation while drawing its pictures finishes
/// them when run again with the same scenario, species and options: it does not simulate (no
/// `Simulating` event; the stand table and the checkpoint are not rewritten), keeps the stills
/// drawn before as they are (one is replaced by a red picture here, which must survive),
/// draws the missing ones and the whole film, writes `summary.md` and `timings.csv`, and
/// removes the pictures' state; its close-up is the one an unbroken run draws. Another seed
/// runs afresh. On round 46's code the second run simulated again (the key frames were gone).
#[test]
fn a_stopped_runs_pictures_are_finished_without_simulating_again() {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    use sylva::job::main_job::Event;
    let dir = tempfile::tempdir().unwrap();
    let sc = sylva::sim::Scenario::from_toml_str(SCENARIO, "reduced.toml").unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let name_of = |e: &Event| format!("{e:?}").split([' ', '(']).next().unwrap_or("").to_string();
    let options = |out: &Path| {
        let mut o = MainJobOptions::new(out);
        o.size = (320, 180);
        o.timelapse_size = (160, 90);
        o
    };
    // the unbroken run
    let whole = dir.path().join("whole");
    main_job::main_job(&sc, &lib, &options(&whole), &mut |_| {}).unwrap();

    // stopped at the first still from afar: year 0's two are drawn (a stop is seen between
    // years), year 6's, the close-up and the film are not
    let out = dir.path().join("out");
    let stop = Arc::new(AtomicBool::new(false));
    let mut opts = options(&out);
    opts.stop = Some(stop.clone());
    let r = main_job::main_job(&sc, &lib, &opts, &mut |e| {
        if matches!(e, Event::Still) {
            stop.store(true, Ordering::SeqCst);
        }
    });
    assert!(matches!(r, Err(sylva::job::JobError::Stopped(_))), "{:?}", r.map(|s| s.sim.year));
    for f in ["stills/year_0000_oblique.png", "stills/year_0000_topdown.png", "stand_table.csv", "checkpoint.bin", ".sylva_pictures.json", ".sylva_keyframes.bin"] {
        assert!(out.join(f).is_file(), "{f} after the stop");
    }
    for f in ["stills/year_0006_oblique.png", "stills/year_0006_closeup.png", "timelapse.gif", "summary.md", "timings.csv"] {
        assert!(!out.join(f).exists(), "{f} before the stop's pictures are finished");
    }
    let red = image::RgbaImage::from_pixel(320, 180, image::Rgba([200, 0, 0, 255]));
    red.save(out.join("stills/year_0000_oblique.png")).unwrap();
    let red_bytes = std::fs::read(out.join("stills/year_0000_oblique.png")).unwrap();
    let stamp = |f: &str| (std::fs::read(out.join(f)).unwrap(), std::fs::metadata(out.join(f)).unwrap().modified().unwrap());
    let (table, checkpoint) = (stamp("stand_table.csv"), stamp("checkpoint.bin"));

    // run again: only the missing pictures
    let mut events: Vec<String> = Vec::new();
    let mut resumed_with = None;
    let summary = main_job::main_job(&sc, &lib, &options(&out), &mut |e| {
        if let Event::Resuming { year, stills_drawn, frames_drawn } = e {
            resumed_with = Some((*year, *stills_drawn, *frames_drawn));
        }
        let n = name_of(e);
        if events.last() != Some(&n) {
            events.push(n);
        }
    })
    .unwrap();
    assert_eq!(events, ["Begin", "Resuming", "Stills", "Still", "CloseUpBegin", "CloseUp", "StillsDone", "Timelapse", "Frame", "TimelapseDone"], "no simulation");
    assert_eq!(resumed_with, Some((6, 2, 0)));
    assert!(summary.resumed && summary.sim.year == 6 && summary.sim.rows.len() == 6 && summary.stills.len() == 5);
    assert_eq!(summary.film.as_ref().map(|f| f.frames), Some(5));
    assert_eq!(std::fs::read(out.join("stills/year_0000_oblique.png")).unwrap(), red_bytes, "a still drawn before is kept, not drawn again");
    assert_eq!(stamp("stand_table.csv"), table);
    assert_eq!(stamp("checkpoint.bin"), checkpoint);
    for f in ["stills/year_0006_oblique.png", "stills/year_0006_topdown.png", "stills/year_0006_closeup.png", "timelapse.gif", "frames/frame_00004.png", "summary.md", "timings.csv"] {
        assert!(out.join(f).is_file(), "{f} drawn when finishing");
    }
    assert!(!out.join(".sylva_pictures.json").exists() && !out.join(".sylva_keyframes.bin").exists(), "the pictures' state is removed");
    let mut written = Vec::new();
    files(&out, &out, &mut written);
    assert!(written.iter().all(|f| main_job::is_output(f)), "{written:?}");
    // the same figures as the unbroken run, and its close-up (trees from the final checkpoint)
    let unbroken = main_job::main_job(&sc, &lib, &options(&dir.path().join("whole2")), &mut |_| {}).unwrap();
    assert_eq!(summary.tables().1, unbroken.tables().1);
    let (a, b) = (image::open(out.join("stills/year_0006_closeup.png")).unwrap().to_rgb8(), image::open(whole.join("stills/year_0006_closeup.png")).unwrap().to_rgb8());
    let d = a.pixels().zip(b.pixels()).map(|(p, q)| (0..3).map(|k| (p[k] as f64 - q[k] as f64).abs()).sum::<f64>() / 3.0).sum::<f64>() / (320.0 * 180.0);
    assert!(d < 0.5, "mean |Δ| of the finished close-up against the unbroken run's: {d:.3} grey levels");
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("pictures finished by a second `sylva run`") && md.contains("## Where the time went"), "{md}");
    let csv = std::fs::read_to_string(out.join("timings.csv")).unwrap();
    assert!(csv.contains("finishing the pictures: the final checkpoint read") && csv.contains("\"simulation ("), "{csv}");

    // stopped again; then another seed is another run: simulated afresh, the state removed
    stop.store(false, Ordering::SeqCst);
    let r = main_job::main_job(&sc, &lib, &opts, &mut |e| {
        if matches!(e, Event::Still) {
            stop.store(true, Ordering::SeqCst);
        }
    });
    assert!(matches!(r, Err(sylva::job::JobError::Stopped(_))) && out.join(".sylva_pictures.json").is_file());
    let mut sc2 = sc.clone();
    sc2.seed += 1;
    let mut events: Vec<String> = Vec::new();
    main_job::main_job(&sc2, &lib, &options(&out), &mut |e| events.push(name_of(e))).unwrap();
    assert!(events.iter().any(|e| e == "Simulating") && !events.iter().any(|e| e == "Resuming"), "{events:?}");
    assert!(!out.join(".sylva_pictures.json").exists() && !out.join(".sylva_keyframes.bin").exists());
}

/// `timings.csv` (round 47): where the main job's time went, a row per phase with wall and
/// CPU seconds, each phase of the job named, the total the sum of the phases.
#[test]
fn the_main_job_says_where_its_time_went() {
    let dir = tempfile::tempdir().unwrap();
    let sc = sylva::sim::Scenario::from_toml_str(SCENARIO, "reduced.toml").unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let out = dir.path().join("out");
    let mut opts = MainJobOptions::new(&out);
    opts.size = (320, 180);
    opts.timelapse_size = (160, 90);
    let summary = main_job::main_job(&sc, &lib, &opts, &mut |_| {}).unwrap();
    let mut rdr = csv::Reader::from_path(out.join("timings.csv")).unwrap();
    assert_eq!(rdr.headers().unwrap(), vec!["phase", "wall_s", "cpu_s"]);
    let rows: Vec<(String, f64, Option<f64>)> = rdr.records().map(|r| r.unwrap()).map(|r| (r[0].to_string(), r[1].parse().unwrap(), r[2].parse().ok())).collect();
    let phases: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    for p in ["conditions", "simulation (", "simulation: of which outputs", "simulation: of which the pictures' key frames", "pictures: setting up", "stills from afar: oblique", "stills from afar: top-down", "close-up (", "close-up: of which adapting", "timelapse: frames (5 drawn, 0 read back)", "timelapse: encoding", "total"] {
        assert!(phases.iter().any(|q| q.starts_with(p)), "{p} in {phases:?}");
    }
    for (p, wall, cpu) in &rows {
        assert!(*wall >= 0.0 && cpu.is_none_or(|c| c >= 0.0), "{p}: {wall} {cpu:?}");
    }
    // the process did work in each of these: CPU time was spent
    for p in ["simulation (", "stills from afar: oblique", "close-up (", "timelapse: frames"] {
        let r = rows.iter().find(|r| r.0.starts_with(p)).unwrap();
        assert!(r.2.unwrap() > 0.0 && r.1 > 0.0, "{r:?}");
    }
    let parts: f64 = rows.iter().filter(|r| !r.0.contains("of which") && r.0 != "total").map(|r| r.1).sum();
    let total = rows.last().unwrap();
    assert!((total.1 - parts).abs() < 0.05 && total.1 <= summary.total_s + 0.05, "{total:?} vs {parts} and {}", summary.total_s);
    assert_eq!(summary.timings.len() + 1, rows.len());
}

/// Round 47: the pictures' key frames hold a snapshot of more than 65,535 trees, each with its
/// own tint (round 46's `tree_tint`), bit for bit. On main's head (`457e8c7`) the tinted colour
/// went into the snapshot's 16-bit palette, and the default `sylva run` ended after its
/// simulation with "more than 65535 distinct foliages in year 50", drawing no picture.
#[test]
fn key_frames_keep_a_snapshot_of_many_tinted_trees() {
    use sylva::job::keyframes::KeyFrames;
    use sylva::render::scene::TreeInstance;
    let dir = tempfile::tempdir().unwrap();
    let inst: Vec<TreeInstance> = (0..70_000u64)
        .map(|id| {
            let k = sylva::job::scene::tree_tint(id);
            let mut t = TreeInstance::new(id, [id as f32 * 0.5, 3.0, 800.0], 20.0, 3.0, (id % 4) as u32, [0.1 * k[0], 0.2 * k[1], 0.05 * k[2]]);
            t.leaf_amount = 0.9;
            t
        })
        .collect();
    let mut tints: Vec<[u32; 3]> = inst.iter().map(|t| t.leaf_color.map(f32::to_bits)).collect();
    tints.sort_unstable();
    tints.dedup();
    assert!(tints.len() > 65_535, "{} distinct foliage colours", tints.len());
    let mut k = KeyFrames::new(dir.path()).unwrap();
    k.push(50, &inst).unwrap();
    k.push(55, &inst[..10]).unwrap();
    assert_eq!(k.get_year(50).unwrap(), inst);
    assert_eq!(k.get_year(55).unwrap(), inst[..10].to_vec());
}
