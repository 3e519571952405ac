//! Command-line behaviour a script relies on: Ctrl-C ends a simulation with status 130 after a
//! complete year (outputs intact, resumable); a closed output pipe ends a command quietly.
use std::process::{Command, Stdio};

const LONG: &str = r#"
name = "long"
years = 1000
seed = 3
snapshot_every = 1
checkpoint_every = 1
species = ["beech"]
[terrain]
uniform = { width = 10, height = 10, cell_m = 20.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "planted"
species = "beech"
spacing_m = 2.0
age_yr = 10.0
"#;

#[test]
fn ctrl_c_stops_after_a_year_with_status_130_and_a_checkpoint() {
    stop_with(libc::SIGINT);
}

#[test]
fn sigterm_stops_like_ctrl_c_and_leaves_no_temporary_files() {
    let d = stop_with(libc::SIGTERM);
    let tmp: Vec<String> = std::fs::read_dir(d.path().join("run/inventory")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).filter(|n| n.ends_with(".tmp")).collect();
    assert!(tmp.is_empty(), "{tmp:?}");
}

/// Runs a long simulation, sends `sig` once year 2 is written, checks the graceful stop.
fn stop_with(sig: i32) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("long.toml"), LONG).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "long.toml", "--out", "run"]).current_dir(d).stderr(Stdio::piped()).spawn().unwrap();
    // wait until the simulation is under way (its Ctrl-C handler is installed before year 1)
    let marker = d.join("run/inventory/year_0002.parquet");
    while !marker.exists() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be interrupted");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    unsafe {
        libc::kill(child.id() as i32, sig);
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("--resume") && !err.contains("panicked"), "{err}");
    assert!(d.join("run/checkpoint.bin").exists());
    let table = std::fs::read_to_string(d.join("run/stand_table.csv")).unwrap();
    let years = table.lines().count() - 1;
    assert!((2..1000).contains(&years), "{years} rows");
    dir
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    let mut fds = [0i32; 2];
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // close the read end first: the first line the program prints meets a closed pipe
    unsafe {
        libc::close(fds[0]);
    }
    let write_end = unsafe { <std::os::fd::OwnedFd as std::os::fd::FromRawFd>::from_raw_fd(fds[1]) };
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["species", "list"]).stdout(Stdio::from(write_end)).stderr(Stdio::piped()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "ended by SIGPIPE like other Unix tools: {:?} {err}", out.status);
}

#[test]
fn terrain_options_refuse_nan_and_out_of_range_values() {
    for (opt, val, want) in [("--latitude", "nan", "-90 to 90"), ("--latitude", "200", "-90 to 90"), ("--sea-level", "nan", "finite"), ("--max-height", "inf", "finite")] {
        let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info", &format!("{opt}={val}")]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(opt) && err.contains(want), "{opt}={val}: {err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info", "--latitude", "-30.5", "--generate", "--size", "16"]).output().unwrap();
    let so = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && so.contains("latitude:    -30.500° (--latitude"), "{so}");
}

#[test]
fn folders_and_files_mixed_up_get_plain_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("empty")).unwrap();
    std::fs::write(d.join("afile"), b"x").unwrap();
    std::fs::create_dir(d.join("with_file")).unwrap();
    std::fs::write(d.join("with_file/inventory"), b"x").unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(d).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    for (args, want) in [
        (&["species", "check", "empty"][..], "no species files"),
        (&["species", "show", "beech", "--dir", "nowhere"][..], "no such folder"),
        (&["terrain", "info", "empty"][..], "is a folder"),
        (&["run", "--out", "afile", "--years", "1"][..], "is a file"),
    ] {
        let (ok, err) = run(args);
        assert!(!ok && err.contains(want), "{args:?}: {err}");
    }
    // more tiles than one process can hold are refused before anything is written (4,000
    // overflowed a thread's stack, 1,000 were killed for memory)
    let (ok, err) = run(&["simulate", "nothere.toml", "--tiles", "4000", "--out", "t4000"]);
    assert!(!ok && err.contains("--tiles") && err.contains("1 to 64 tiles") && err.contains("got 4000") && err.contains("mpirun") && !d.join("t4000").exists(), "{err}");
    // a tile count the site's light grid cannot hold leaves no run folder (it left species/)
    std::fs::write(d.join("tiny.toml"), "name = \"tiny\"\nyears = 2\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 2, height = 2, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n").unwrap();
    let (ok, err) = run(&["simulate", "tiny.toml", "--tiles", "64", "--out", "tiny_out"]);
    assert!(!ok && err.contains("`tiles` = 64 (cut into 8 × 8 tiles)") && err.contains("light grid of 4 × 4 cells") && !d.join("tiny_out").exists(), "{err}");
    // `sylva simulate` writes the GeoPackage of the final year only, unless asked for every
    // snapshot (2.1 GB for the default scenario's 31 snapshots)
    std::fs::write(d.join("snap.toml"), "name = \"snap\"\nyears = 2\nseed = 1\nsnapshot_every = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n").unwrap();
    // a file where the run writes one of its folders is refused before anything is written
    for cmd in ["simulate", "run"] {
        let args: Vec<&str> = if cmd == "run" { vec!["run", "snap.toml", "--out", "with_file", "--no-pictures"] } else { vec!["simulate", "snap.toml", "--out", "with_file"] };
        let (ok, err) = run(&args);
        assert!(!ok && err.contains("with_file/inventory is a file where the run writes its folder inventory/"), "{cmd}: {err}");
        assert_eq!(std::fs::read_dir(d.join("with_file")).unwrap().count(), 1, "{cmd}: only the file is there");
    }
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_final"]);
    assert!(ok, "{err}");
    assert!(d.join("snap_final/inventory/year_0002.gpkg").is_file() && !d.join("snap_final/inventory/year_0001.gpkg").exists() && d.join("snap_final/inventory/year_0001.parquet").is_file());
    // the stand table's column after the climate is the site's unmasked area its per-hectare
    // columns divide by: 4 × 4 cells of 10 m = 0.16 ha (trial 36: it was written nowhere);
    // then the natural deaths' volume (round 42), the site's stems (round 46), and a row for
    // year 0
    let st = std::fs::read_to_string(d.join("snap_final/stand_table.csv")).unwrap();
    assert!(st.lines().next().unwrap().ends_with(",precipitation_factor,drought_index,area_ha,deaths_volume_m3_ha,stems"), "{st}");
    assert!(st.lines().skip(1).all(|l| l.rsplit(',').nth(2) == Some("0.1600")) && st.lines().count() == 4 && st.lines().nth(1).unwrap().starts_with("0,"), "{st}");
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_all", "--gpkg", "every-snapshot"]);
    assert!(ok && d.join("snap_all/inventory/year_0001.gpkg").is_file() && d.join("snap_all/inventory/year_0002.gpkg").is_file(), "{err}");
    // a site larger than the machine's memory is refused before it is built, naming the field
    // (a trial's 8000 × 8000 uniform site aborted with "memory allocation failed")
    std::fs::write(d.join("huge.toml"), "name = \"huge\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 8000, height = 8000, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sylva")).current_dir(d).args(["simulate", "huge.toml", "--out", "huge_out"]).env("SYLVA_MEM_AVAILABLE", "8000000000").output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("`terrain.uniform.width/height` = 8000 x 8000") && err.contains("64000000 cells need about 8.4 GB") && err.contains("8.0 GB are available") && !d.join("huge_out").exists(), "{err}");
    // --resume into a folder that holds no run (a mistyped --out) is refused, and makes no
    // folder (a trial's resume started a new run from year 0)
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_typo", "--resume"]);
    assert!(!ok && err.contains("no checkpoint in the run directory") && err.contains("no run started there") && !d.join("snap_typo/species").exists(), "{err}");
    // a second run into a run's folder says that it replaces the earlier run's files
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_all"]);
    assert!(ok && err.contains("snap_all holds an earlier run (snap)") && err.contains("--resume"), "{err}");
    // ... but not before refusing a scenario (round 30's trial: the note came first, then the
    // refusal, though nothing of the earlier run was touched)
    std::fs::write(d.join("snap_bad.toml"), std::fs::read_to_string(d.join("snap.toml")).unwrap().replace("species = [\"beech\"]", "species = [\"beech\"]\nclimate = { anomalies_file = \"missing.csv\" }")).unwrap();
    let table = std::fs::read(d.join("snap_all/stand_table.csv")).unwrap();
    for args in [&["simulate", "snap_bad.toml", "--out", "snap_all"][..], &["run", "snap_bad.toml", "--out", "snap_all", "--no-pictures"][..]] {
        let (ok, err) = run(args);
        assert!(!ok && err.contains("missing.csv") && !err.contains("holds an earlier run"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read(d.join("snap_all/stand_table.csv")).unwrap(), table, "the earlier run's stand table is kept");
    // a run directory that does not exist, or is a file, is called so (round 30's trial: "not
    // a Sylva run directory" for a mistyped path)
    for cmd in ["render", "export", "timelapse"] {
        let out = if cmd == "timelapse" { "t.gif" } else if cmd == "export" { "s.glb" } else { "x.png" };
        let (ok, err) = run(&[cmd, "no_such_run", "--out", out]);
        assert!(!ok && err.contains("no_such_run: no such folder"), "{cmd}: {err}");
        let (ok, err) = run(&[cmd, "snap.toml", "--out", out]);
        assert!(!ok && err.contains("snap.toml is a file, not a run directory"), "{cmd}: {err}");
        // a folder without scenario.toml: the same words from every command (round 31's
        // trial: an OS error from render and timelapse)
        std::fs::create_dir_all(d.join("not_a_run")).unwrap();
        let (ok, err) = run(&[cmd, "not_a_run", "--out", out]);
        assert!(!ok && err.contains("not_a_run: not a Sylva run directory (no scenario.toml"), "{cmd}: {err}");
    }
    // a year without an inventory is refused before the site is loaded, with the years there
    let (ok, err) = run(&["render", "snap_all", "--year", "999", "--out", "y.png"]);
    assert!(!ok && err.contains("year 999") && err.contains("years with an inventory"), "{err}");
    assert!(!d.join("y.png").exists());
    // a scenario with nothing to grow from is said to be so
    std::fs::write(d.join("empty.toml"), "name = \"empty\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n").unwrap();
    let (ok, err) = run(&["simulate", "empty.toml", "--out", "empty_out"]);
    assert!(ok && err.contains("no [[start]]") && err.contains("nothing will grow"), "{err}");
    std::fs::write(d.join("rain.toml"), std::fs::read_to_string(d.join("empty.toml")).unwrap() + "[[start]]\nkind = \"seed_rain\"\nspecies = \"beech\"\nseeds_per_ha = 100.0\n").unwrap();
    let (ok, err) = run(&["simulate", "rain.toml", "--out", "rain_out"]);
    assert!(ok && !err.contains("nothing will grow"), "{err}");
    // `sylva edit` of an unknown species says so before it looks for a display
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["edit", "no_such_species"]).env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").current_dir(d).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("no_such_species") && err.contains("beech"), "{err}");
    // and `sylva run` says it once the scenario is checked (after the conditions' step)
    let (ok, err) = run(&["run", "snap.toml", "--out", "snap_all", "--no-pictures"]);
    assert!(ok && err.contains("snap_all holds an earlier run (snap)"), "{err}");
    // an --out below a file is refused naming the option and the file in the way (it named
    // the run's species/ folder: found by a trial)
    for cmd in ["simulate", "run"] {
        let args: Vec<&str> = if cmd == "run" { vec!["run", "snap.toml", "--out", "snap.toml/sub", "--no-pictures"] } else { vec!["simulate", "snap.toml", "--out", "snap.toml/sub"] };
        let (ok, err) = run(&args);
        assert!(!ok && err.contains("--out snap.toml/sub: snap.toml is a file, not a folder"), "{cmd}: {err}");
    }
    // `simulate --years` runs a scenario for fewer years (a trial could not try the shipped
    // management scenarios briefly); the run directory's scenario records them
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_y", "--years", "1"]);
    assert!(ok && d.join("snap_y/inventory/year_0001.parquet").is_file() && !d.join("snap_y/inventory/year_0002.parquet").exists(), "{err}");
    assert!(std::fs::read_to_string(d.join("snap_y/scenario.toml")).unwrap().lines().any(|l| l.trim() == "years = 1"));
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_y0", "--years", "0"]);
    assert!(!ok && err.contains("--years") && !d.join("snap_y0").exists(), "{err}");
    // a negative count is read as one and refused with the option's range (clap's tip was to
    // write `-- -3`, which names a scenario: round 30's trial)
    let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_y0", "--years", "-3"]);
    assert!(!ok && err.contains("-3 is not in 1..=10000") && !err.contains("-- -3") && !d.join("snap_y0").exists(), "{err}");
    // under mpirun only rank 0 says it (each rank printed it in round 23); rank 0 still does
    for (rank, said) in [("1", false), ("0", true)] {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "snap.toml", "--out", "snap_all"]).env("OMPI_COMM_WORLD_RANK", rank).current_dir(d).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && err.contains("holds an earlier run") == said, "rank {rank}: {err}");
    }
    // a second run into a folder another run is writing into is refused (round 32's trial: two
    // runs into one --out mixed their files, both ending well); the lock is the folder's flock,
    // held here as a running `sylva simulate` holds it, and gone with its holder
    {
        use std::os::unix::io::AsRawFd;
        let held = std::fs::File::open(d.join("snap_all")).unwrap();
        // SAFETY: flock on a descriptor this test owns
        assert_eq!(unsafe { libc::flock(held.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) }, 0);
        let before = std::fs::read(d.join("snap_all/stand_table.csv")).unwrap();
        for cmd in ["simulate", "run"] {
            let args: Vec<&str> = if cmd == "run" { vec!["run", "snap.toml", "--out", "snap_all", "--no-pictures"] } else { vec!["simulate", "snap.toml", "--out", "snap_all", "--resume"] };
            let (ok, err) = run(&args);
            assert!(!ok && err.contains("--out snap_all: another Sylva run is writing into this folder"), "{cmd}: {err}");
        }
        assert_eq!(std::fs::read(d.join("snap_all/stand_table.csv")).unwrap(), before);
        drop(held);
        // an earlier `sylva run`'s pictures, condition maps and summary do not stay beside a new
        // simulation (round 32's trial); files that are not Sylva's stay
        for f in ["summary.md", "stills/year_0002_oblique.png", "maps/conditions/L.png", "frames/frame_00001.png", "timelapse.gif", "notes.txt", "stills/mine.png"] {
            std::fs::create_dir_all(d.join("snap_all").join(f).parent().unwrap()).unwrap();
            std::fs::write(d.join("snap_all").join(f), b"old").unwrap();
        }
        let (ok, err) = run(&["simulate", "snap.toml", "--out", "snap_all"]);
        assert!(ok && err.contains("removed 5 file(s) of the earlier run"), "{err}");
        for gone in ["summary.md", "stills/year_0002_oblique.png", "maps/conditions", "frames", "timelapse.gif"] {
            assert!(!d.join("snap_all").join(gone).exists(), "{gone}");
        }
        assert!(d.join("snap_all/notes.txt").is_file() && d.join("snap_all/stills/mine.png").is_file());
    }
    // output files whose folder is a file are refused before any work, naming the option
    for (args, opt) in [(&["render", "snap_final", "--out", "afile/x.png"][..], "--out"), (&["timelapse", "snap_final", "--out", "afile/t.gif"][..], "--out"), (&["export", "snap_final", "--out", "afile/s.glb"][..], "--out"), (&["render", "snap_final", "--out", "x.png", "--stats", "afile/s.json"][..], "--stats")] {
        let (ok, err) = run(args);
        assert!(!ok && err.contains(opt) && err.contains("afile is a file, not a folder"), "{args:?}: {err}");
    }
    assert!(!d.join("x.png").exists());
    // a folder that cannot be made is named as `--out`'s, as render names it (round 39's trial:
    // export said only "creating /proc/nope: No such file or directory")
    let (ok, err) = run(&["export", "snap_final", "--out", "/proc/sylva_no_such_folder/s.glb"]);
    assert!(!ok && err.contains("--out /proc/sylva_no_such_folder/s.glb: creating its folder"), "{err}");
    // a scenario's site mapped without simulating: the six Ellenberg indices among them
    let (ok, err) = run(&["terrain", "maps", "--scenario", "snap.toml", "--out", "smaps"]);
    assert!(ok, "{err}");
    for f in ["L", "T", "K", "F", "R", "N"] {
        assert!(d.join("smaps").join(format!("{f}.png")).is_file() && d.join("smaps").join(format!("{f}.tif")).is_file(), "{f}");
    }
    let (ok, err) = run(&["terrain", "maps", "x.tif", "--scenario", "snap.toml", "--out", "smaps2"]);
    assert!(!ok && err.contains("--scenario") && !d.join("smaps2").exists(), "{err}");
    // a DEM that is not there leaves no empty maps folder behind
    let (ok, err) = run(&["terrain", "maps", "nothere.tif", "--out", "maps_out"]);
    assert!(!ok && err.contains("nothere.tif") && !d.join("maps_out").exists(), "{err}");
    // without ./species, `species check` checks the shipped library
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["species", "check"]).current_dir(d).output().unwrap();
    assert!(o.status.success() && String::from_utf8_lossy(&o.stdout).contains("shipped library: 17 species"));
}

#[test]
fn ground_camera_steps_out_of_a_trunk_into_a_clearing() {
    use sylva::job::inventory::InventoryRow;
    use sylva::render::camera::CameraPreset;
    let sc = sylva::sim::Scenario::from_toml_str(
        "name = \"g\"\nyears = 1\n[terrain]\nuniform = { width = 20, height = 20, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 4, 5, 6, 6] }\n",
        "g",
    )
    .unwrap();
    let stage = sylva::job::pictures::Stage::new(sc.site().unwrap(), sylva::species::SpeciesLibrary::embedded().unwrap(), 0.0).expect("a wgpu adapter (lavapipe in CI)");
    let preset = stage.camera(CameraPreset::Ground);
    let tree = |id: u64, x: f32, y: f32| InventoryRow { id, species: "beech".into(), x_m: x as f64, y_m: y as f64, z_m: 300.0, age_yr: 60.0, height_m: 25.0, dbh_cm: 30.0, crown_radius_m: 3.0, crown_base_m: 10.0, status: "alive".into() };
    // a beech right where the preset's eye stands, and a row of them along the southern edge
    let (x0, y0) = (preset.eye[0], preset.eye[1]);
    let mut rows: Vec<InventoryRow> = (0..8).map(|k| tree(k, x0 - 28.0 + 8.0 * k as f32, y0)).collect();
    rows.push(tree(99, x0, y0));
    let cam = stage.camera_for(CameraPreset::Ground, &rows, 1280, 720);
    let clear = rows.iter().map(|r| (r.x_m as f32 - cam.eye[0]).hypot(r.y_m as f32 - cam.eye[1]) - r.crown_radius_m).fold(f32::INFINITY, f32::min);
    assert!(clear > 0.5, "eye {:?} still inside a crown (clearance {clear} m)", cam.eye);
    assert!((cam.eye[2] - 301.7).abs() < 0.2, "eye at 1.7 m above the ground: {:?}", cam.eye);
    assert!(cam.target[1] > cam.eye[1], "still looking north");
    // with nobody in the way the preset is kept
    let far = [tree(1, 10.0, 190.0)];
    assert_eq!(stage.camera_for(CameraPreset::Ground, &far, 1280, 720).eye, preset.eye);
}

/// Round 33's trial, items 5–9: bad input named before any work, with the option or file and
/// what is expected, leaving nothing behind.
#[test]
fn round_33_bad_outputs_runs_and_dems_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(d).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let files = || {
        let mut v: Vec<String> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    std::fs::write(d.join("afile"), b"x").unwrap();
    // item 6: `tree grow --out` a folder is refused before the tree is grown, in render's and
    // export's words (it wrote d3.mtl and five textures, then "d3.obj: Is a directory")
    for name in ["d3.obj", "dir.glb"] {
        std::fs::create_dir(d.join(name)).unwrap();
        let before = files();
        let (ok, err) = run(&["tree", "grow", "--species", "beech", "--age", "20", "--out", name]);
        assert!(!ok && err.contains(&format!("--out {name}: is a folder; expected a file name")), "{name}: {err}");
        assert_eq!(files(), before, "{name}: nothing written");
    }
    // item 7: an --out under a file names the option and the file in the way
    for cmd in ["grow", "adapt"] {
        let (ok, err) = run(&["tree", cmd, "--species", "beech", "--age", "20", "--out", "afile/t.glb"]);
        assert!(!ok && err.contains("--out afile/t.glb: afile is a file, not a folder"), "{cmd}: {err}");
    }
    let (ok, err) = run(&["tree", "grow", "--species", "beech", "--age", "20", "--out", "t.fbx"]);
    assert!(!ok && err.contains("--out t.fbx: expected a .glb or .obj file name"), "{err}");
    // a DEM with a 4 × 4-cell no-data hole (x, y 30–70 m) and no .prj
    let mut asc = String::from("ncols 10\nnrows 10\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n");
    for r in 0..10 {
        let row: Vec<String> = (0..10).map(|c| if (3..7).contains(&r) && (3..7).contains(&c) { "-9999".into() } else { format!("{}", 300 + c) }).collect();
        asc += &(row.join(" ") + "\n");
    }
    std::fs::write(d.join("holes.asc"), asc).unwrap();
    // item 9: the missing .prj is said to be missing (it was "holes.prj: projected CRS without
    // EPSG code not known")
    let (ok, err) = run(&["terrain", "info", "holes.asc"]);
    assert!(ok && err.contains("holes.asc: no .prj beside it (holes.prj is missing)") && !err.contains("without EPSG code"), "{err}");
    // item 7: `terrain maps --out` an existing file ("creating holes.asc: File exists")
    let (ok, err) = run(&["terrain", "maps", "holes.asc", "--out", "afile"]);
    assert!(!ok && err.contains("--out afile: is a file; expected a folder"), "{err}");
    std::fs::write(d.join("snap.toml"), "name = \"snap\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n").unwrap();
    let (ok, err) = run(&["terrain", "maps", "--scenario", "snap.toml", "--out", "afile"]);
    assert!(!ok && err.contains("--out afile: is a file; expected a folder"), "{err}");
    // item 7: a folder with a scenario but no inventory/, and one whose scenario.toml does not
    // parse ("fake1/inventory: No such file or directory"; "years with an inventory: ")
    std::fs::create_dir_all(d.join("fake1")).unwrap();
    std::fs::copy(d.join("snap.toml"), d.join("fake1/scenario.toml")).unwrap();
    std::fs::create_dir_all(d.join("fake4/inventory")).unwrap();
    std::fs::write(d.join("fake4/scenario.toml"), "garbage [[[").unwrap();
    for cmd in ["render", "export", "timelapse"] {
        let out = if cmd == "timelapse" { "t.gif" } else if cmd == "export" { "s.glb" } else { "x.png" };
        let year: &[&str] = if cmd == "timelapse" { &[] } else { &["--year", "0"] };
        let (ok, err) = run(&[&[cmd, "fake1", "--out", out][..], year].concat());
        assert!(!ok && err.contains("fake1: not a Sylva run directory (no inventory/ folder"), "{cmd}: {err}");
        let (ok, err) = run(&[&[cmd, "fake4", "--out", out][..], year].concat());
        assert!(!ok && err.contains("fake4: not a Sylva run directory (its scenario.toml does not parse") && !err.contains("years with an inventory"), "{cmd}: {err}");
        assert!(!d.join(out).exists());
    }
    // item 5: a hemispherical photograph on a no-data cell is refused as one off the site is
    std::fs::write(d.join("holes.toml"), "name = \"holes\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\npath = \"holes.asc\"\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 5.0\nage_yr = 5.0\n").unwrap();
    let (ok, err) = run(&["simulate", "holes.toml", "--out", "holes_run"]);
    assert!(ok, "{err}");
    let (ok, err) = run(&["render", "holes_run", "--year", "1", "--camera", "hemi:50,50", "--size", "64x64", "--out", "h1.png"]);
    assert!(!ok && err.contains("--camera") && err.contains("hemi:50,50") && err.contains("no-data"), "{err}");
    assert!(!d.join("h1.png").exists());
    let (ok, err) = run(&["render", "holes_run", "--year", "1", "--camera", "hemi:15,85", "--size", "64x64", "--out", "h2.png"]);
    assert!(ok && d.join("h2.png").is_file(), "a valid cell beside the hole: {err}");
    // item 8: an 8-bit PNG is refused, saying why and what is expected (it was read as 256
    // levels without a word)
    image::ImageBuffer::<image::Luma<u8>, Vec<u8>>::from_fn(8, 8, |x, y| image::Luma([(x * 30 + y) as u8])).save(d.join("p8.png")).unwrap();
    let (ok, err) = run(&["terrain", "info", "p8.png"]);
    assert!(!ok && err.contains("p8.png") && err.contains("8-bit") && err.contains("256 height levels") && err.contains("16-bit grayscale PNG"), "{err}");
}

/// Round 34's trial: `mpirun -np 2` of a build without the `mpi` feature ran the whole
/// scenario on each rank into one folder, rc 0. The launcher's variables, set here on the
/// child as mpirun/mpiexec/srun set them, now stop it before any folder is made, saying how to
/// run; a launch of one process, and Slurm's `SLURM_NTASKS` without any `PMI_*` (a batch
/// script's own variable), still run.
#[test]
fn an_mpi_launch_of_a_build_without_mpi_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("short.toml"), LONG.replace("years = 1000", "years = 1").replace("snapshot_every = 1\n", "")).unwrap();
    let sylva = |args: &[&str], env: &[(&str, &str)]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_sylva"));
        c.args(args).current_dir(d);
        for (k, v) in env {
            c.env(k, v);
        }
        let o = c.output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let launches: [&[(&str, &str)]; 4] = [
        &[("OMPI_COMM_WORLD_SIZE", "2"), ("OMPI_COMM_WORLD_RANK", "1")],
        &[("PMI_SIZE", "4"), ("PMI_RANK", "0")],
        &[("SLURM_NTASKS", "3"), ("PMI_FD", "5")],
        &[("PMIX_RANK", "1")],
    ];
    for (i, env) in launches.iter().enumerate() {
        let out = format!("o{i}");
        // `sylva run` runs in one process in every build
        let (ok, err) = sylva(&["run", "short.toml", "--out", &out, "--no-pictures"], env);
        assert!(!ok && err.contains("started by an MPI launcher") && err.contains("runs in one process") && err.contains("sylva simulate"), "{env:?}: {err}");
        assert!(!d.join(&out).exists(), "{env:?}");
        if cfg!(feature = "mpi") {
            continue;
        }
        let (ok, err) = sylva(&["simulate", "short.toml", "--out", &out], env);
        let (n, var) = env.iter().find(|(k, _)| k.ends_with("SIZE") || *k == "SLURM_NTASKS").map_or(("2", "PMIX_RANK=1".to_string()), |(k, v)| (*v, format!("{k}={v}")));
        assert!(!ok && err.contains(&format!("with {n} processes ({var})")) && err.contains("built without the `mpi` feature") && err.contains("--features mpi") && err.contains("--tiles N") && err.contains("without mpirun"), "{env:?}: {err}");
        assert!(!d.join(&out).exists(), "{env:?}");
    }
    for env in [&[("OMPI_COMM_WORLD_SIZE", "1"), ("OMPI_COMM_WORLD_RANK", "0")][..], &[("SLURM_NTASKS", "8")][..]] {
        let (ok, err) = sylva(&["simulate", "short.toml", "--out", "one"], env);
        assert!(ok && d.join("one/stand_table.csv").is_file(), "{env:?}: {err}");
    }
}

/// Round 34 (issue 32): a 1 × 1 DEM was described by `sylva terrain info` (then "TIN of one.asc:
/// field `grid` = 1 x 1", exit 1) and drawn by `sylva terrain maps` (15 maps of one cell, exit
/// 0). Both refuse it now with the same error, naming the file and the minimum size, and
/// `maps` writes nothing; a 2 × 2 DEM passes both.
#[test]
fn terrain_info_and_maps_refuse_a_one_cell_dem_alike() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(d).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let head = "xllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n";
    std::fs::write(d.join("one.asc"), format!("ncols 1\nnrows 1\n{head}500\n")).unwrap();
    std::fs::write(d.join("row.asc"), format!("ncols 3\nnrows 1\n{head}500 501 502\n")).unwrap();
    std::fs::write(d.join("two.asc"), format!("ncols 2\nnrows 2\n{head}500 501\n502 503\n")).unwrap();
    for (file, size) in [("one.asc", "1 x 1"), ("row.asc", "3 x 1")] {
        let want = format!("DEM {file}: field `grid` = {size} cells: expected at least 2 x 2 cells");
        let (ok, out, err) = run(&["terrain", "info", file]);
        assert!(!ok && err.contains(&want), "info {file}: {err}");
        assert!(out.is_empty(), "info describes nothing of a refused DEM: {out}");
        let (ok, _, err2) = run(&["terrain", "maps", file, "--out", "maps1"]);
        assert!(!ok && err2.contains(&want), "maps {file}: {err2}");
        assert!(!d.join("maps1").exists(), "maps of a refused DEM leave no folder");
        let line = |e: &str| e.lines().find(|l| l.contains("error:")).map(str::to_string);
        assert_eq!(line(&err), line(&err2), "the same error from info and maps");
    }
    let (ok, out, err) = run(&["terrain", "info", "two.asc"]);
    assert!(ok && out.contains("2 x 2 cells") && out.contains("TIN:"), "{out}{err}");
    let (ok, _, err) = run(&["terrain", "maps", "two.asc", "--out", "maps2"]);
    assert!(ok && d.join("maps2/elevation.png").is_file(), "{err}");
}

/// Trial 35: a SIGTERM during `sylva export` left its hidden temporary (up to 105 MB) beside the
/// output. A command without a stop flag of its own now removes the file it is writing when
/// stopped: here `tree grow` is sent SIGTERM (fault injection) while its `.glb` is written,
/// before the rename, and exits with 130 leaving nothing in the output folder.
#[test]
fn sigterm_while_a_file_is_written_leaves_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t").join("beech.glb");
    let res = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["tree", "grow", "--species", "beech", "--model", "ecomod", "--age", "10", "--out", out.to_str().unwrap()]).env("SYLVA_FAULT_TERM_AT_WRITE", "1").output().unwrap();
    let err = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(130), "{err}");
    assert!(err.contains("nothing half-written") && !err.contains("panicked"), "{err}");
    let left: Vec<String> = std::fs::read_dir(dir.path().join("t")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// Trial 35: a 16-bit PNG heightmap read without `--cell` / `--min-height` / `--max-height`
/// took 10 m cells and 0–1000 m silently; and `--out /proc/b.glb` was refused with "No such
/// file or directory" for a folder that exists.
#[test]
fn a_png_heightmaps_assumed_scale_is_said_and_a_virtual_folder_gets_the_right_reason() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("park16.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(8, 8, |x, y| image::Luma([(x * 4000 + y * 3000) as u16])).save(&p).unwrap();
    let info = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(&p).args(extra).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (_, err) = info(&[]);
    assert!(err.contains("park16.png") && err.contains("carries no scale") && err.contains("cells of 10 m (set --cell)") && err.contains("heights 0–1000 m") && err.contains("--min-height/--max-height"), "{err}");
    let (_, err) = info(&["--cell", "2"]);
    assert!(err.contains("heights 0–1000 m") && !err.contains("cells of"), "{err}");
    let (out, err) = info(&["--cell", "2", "--min-height", "100", "--max-height", "400"]);
    assert!(!err.contains("carries no scale"), "{err}");
    assert!(out.contains("100.0") || out.contains("100 "), "the given range is used: {out}");
    // a file that cannot be read gets its error alone, not first a claim of an assumed scale
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(dir.path().join("missing.png")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("missing.png") && !err.contains("carries no scale"), "{err}");
    if std::path::Path::new("/proc/self").is_dir() {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["tree", "grow", "--species", "beech", "--age", "5", "--out", "/proc/b.glb"]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("/proc") && err.contains("takes no new files") && !err.contains("No such file"), "{err}");
    }
}

/// A scenario whose DEM is not there is refused naming the scenario file, the field
/// `terrain.path`, the path as written and where it was looked for (a check of the final binary
/// got the file's "No such file" under "[terrain]" without the field).
#[test]
fn a_missing_dem_is_refused_naming_terrain_path() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad3.toml"), "name = \"bad3\"\nyears = 2\nseed = 1\nspecies = [\"beech\"]\n[terrain]\npath = \"nothere.tif\"\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "bad3.toml", "--out", "o"]).current_dir(dir.path()).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("bad3.toml") && err.contains("terrain.path") && err.contains("nothere.tif (") && err.contains("an existing DEM file") && !dir.path().join("o").exists(), "{err}");
}

/// A TIFF without georeferencing tags (a heightmap saved by a paint program, or a GeoTIFF whose
/// grid tags were lost) was read silently as 1 m cells (trial 37): now said, with the way out.
#[test]
fn a_tiff_without_georeferencing_is_said_to_be_read_as_one_metre_cells() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("painted.tif");
    let mut f = std::fs::File::create(&p).unwrap();
    let data: Vec<f32> = (0..64).map(|i| 100.0 + i as f32).collect();
    TiffEncoder::new(&mut f).unwrap().write_image::<colortype::Gray32Float>(8, 8, &data).unwrap();
    drop(f);
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(&p).output().unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{err}");
    assert!(err.contains("painted.tif") && err.contains("no georeferencing") && err.contains("1 m cells") && err.contains("gdal_translate"), "{err}");
    assert!(out.contains("8 x 8"), "{out}");
    // a georeferenced GeoTIFF says nothing of the kind
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/coweeta_10m_utm17n.tif")).output().unwrap();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("no georeferencing"));
}

/// A render that fails leaves no folder behind that it made for `--out` (trial 37: a refused
/// `--stats` left `x/y/` empty after the render made them).
#[test]
fn a_failed_render_removes_the_empty_folders_it_made_for_its_picture() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x/y/pic.png");
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["render"]).arg(dir.path().join("no_run")).arg("--out").arg(&out).arg("--stats").arg(dir.path()).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--stats"), "{err}");
    assert!(!dir.path().join("x").exists(), "the failed render left {}", dir.path().join("x/y").display());
    // a folder that was there before is kept
    std::fs::create_dir_all(dir.path().join("keep")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["render"]).arg(dir.path().join("no_run")).arg("--out").arg(dir.path().join("keep/pic.png")).output().unwrap();
    assert!(!o.status.success());
    assert!(dir.path().join("keep").is_dir());
}

/// Trial 37: `sylva render` had no camera of one's own. `--camera eye:X,Y,Z:TX,TY,TZ[:FOV]`
/// (site metres, z the elevation, or `+H` above the ground since round 41) draws the picture
/// from there; an eye outside the site or
/// under its ground, an eye on its target, a field of view out of range and a malformed value
/// are refused naming `--camera` and what is expected, and no picture is written.
#[test]
fn a_camera_of_ones_own_is_drawn_and_checked_against_the_site() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(d).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    std::fs::write(d.join("eye.toml"), "name = \"eye\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 5.0\nage_yr = 20.0\n").unwrap();
    let (ok, err) = run(&["simulate", "eye.toml", "--out", "eye_run"]);
    assert!(ok, "{err}");
    let (ok, err) = run(&["render", "eye_run", "--camera", "eye:2,2,301.7:30,30,306:60", "--size", "64x48", "--out", "own.png"]);
    assert!(ok && d.join("own.png").is_file(), "{err}");
    // round 41 (trial 40, item 8): Z as `+H`, a height above the ground at that X, Y (the
    // eye's and the target's): on this 300 m site the same camera, so the same picture
    let (ok, err) = run(&["render", "eye_run", "--camera", "eye:2,2,+1.7:30,30,+6:60", "--size", "64x48", "--out", "rel.png"]);
    assert!(ok, "{err}");
    assert!(std::fs::read(d.join("own.png")).unwrap() == std::fs::read(d.join("rel.png")).unwrap(), "eye:2,2,+1.7:30,30,+6 draws another picture than eye:2,2,301.7:30,30,306");
    // another eye draws another picture
    let (ok, err) = run(&["render", "eye_run", "--camera", "eye:38,38,330:20,20,300", "--size", "64x48", "--out", "own2.png"]);
    assert!(ok, "{err}");
    assert_ne!(std::fs::read(d.join("own.png")).unwrap(), std::fs::read(d.join("own2.png")).unwrap());
    for (cam, want) in [
        ("eye:-5,2,302:30,30,306", &["--camera", "outside the site", "X 0–40.0 m"][..]),
        ("eye:2,45,302:30,30,306", &["--camera", "outside the site", "Y 0–40.0 m"][..]),
        ("eye:2,2,299:30,30,306", &["--camera", "under the ground", "300.0 m", "301.7"][..]),
        ("eye:2,2,+0.05:30,30,306", &["--camera", "0.05 m above the ground", "at least 0.1 m", "+1.7"][..]),
        ("eye:2,2,+-1:30,30,306", &["--camera", "three numbers", "+H"][..]),
        ("eye:2,2,302:2,2,302", &["--camera", "the same point", "eye:X,Y,Z:TX,TY,TZ"][..]),
        ("eye:2,2,302:30,30,306:200", &["--camera", "5–150 degrees"][..]),
        ("eye:2,2:30,30,306", &["--camera", "three numbers"][..]),
        ("eye:2,2,302", &["--camera", "an eye and a target"][..]),
    ] {
        let (ok, err) = run(&["render", "eye_run", "--camera", cam, "--size", "64x48", "--out", "bad.png"]);
        assert!(!ok && want.iter().all(|w| err.contains(w)), "{cam}: {err}");
        assert!(!d.join("bad.png").exists(), "{cam}");
    }
    // trial 46 D11: an eye outside the site or under its ground is refused as soon as the site
    // is read, before the species files are read and the stage built (26 s on the trial's
    // run): with a malformed --species-dir the camera's error comes, not the species file's
    // (before, the species file's); a good camera then meets the species file's error
    std::fs::create_dir_all(d.join("badsp")).unwrap();
    std::fs::write(d.join("badsp/beech.toml"), "this is = = not toml\n").unwrap();
    for (cam, want) in [("eye:1e9,0,0:1,1,1:50", "outside the site"), ("eye:2,2,-500:30,30,306", "under the ground")] {
        let (ok, err) = run(&["render", "eye_run", "--camera", cam, "--species-dir", "badsp", "--size", "64x48", "--out", "bad.png"]);
        assert!(!ok && err.contains(want) && !err.contains("beech.toml"), "{cam}: {err}");
    }
    let (ok, err) = run(&["render", "eye_run", "--camera", "eye:2,2,+1.7:30,30,+6", "--species-dir", "badsp", "--size", "64x48", "--out", "bad.png"]);
    assert!(!ok && err.contains("beech.toml") && !d.join("bad.png").exists(), "{err}");
}

/// Trial 42 (defect 1): an `eye:` camera inside an obstacle was accepted and drew a grey wall,
/// where `hemi:` at the same place is refused. An eye inside a building's footprint (given as
/// `+H` or as an elevation) or inside a boulder is now refused as `hemi:` is, naming `--camera`
/// and the obstacle; an eye above the roof or the boulder is drawn; an eye under the ground is
/// refused; no picture is written for a refused camera.
#[test]
fn a_camera_inside_an_obstacle_or_under_the_ground_is_refused_as_hemi_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).current_dir(d).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    // a 60 m site at 300 m: a 12 m building on [10, 30] x [10, 25] and a boulder of 3 m radius
    // centred 1 m above the ground at (45, 45)
    let toml = "name = \"obs\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\nuniform = { width = 6, height = 6, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 6.0\nage_yr = 20.0\n[[obstacle]]\nkind = \"footprint\"\npoints = [[10.0, 10.0], [30.0, 10.0], [30.0, 25.0], [10.0, 25.0]]\nheight_m = 12.0\n[[obstacle]]\nkind = \"sphere\"\ncenter = [45.0, 45.0, 1.0]\nradius_m = 3.0\n";
    std::fs::write(d.join("obs.toml"), toml).unwrap();
    let (ok, err) = run(&["simulate", "obs.toml", "--out", "obs_run"]);
    assert!(ok, "{err}");
    // hemi: at the building's place is refused (as before)
    let (ok, err) = run(&["render", "obs_run", "--camera", "hemi:20,17", "--size", "64x64", "--out", "bad.png"]);
    assert!(!ok && err.contains("--camera") && err.contains("outside the obstacles"), "{err}");
    for (cam, want) in [
        ("eye:20,17,+1.7:55,55,+5", &["--camera", "expected a place outside the obstacles", "inside the footprint", "[[obstacle]] 1"][..]),
        ("eye:20,17,305:55,55,305", &["--camera", "expected a place outside the obstacles", "inside the footprint"][..]),
        ("eye:45,45,+1.5:5,55,+5", &["--camera", "expected a place outside the obstacles", "inside the sphere", "[[obstacle]] 2"][..]),
        ("eye:50,5,299:5,55,305", &["--camera", "under the ground", "300.0 m"][..]),
    ] {
        let (ok, err) = run(&["render", "obs_run", "--camera", cam, "--size", "64x48", "--out", "bad.png"]);
        assert!(!ok && want.iter().all(|w| err.contains(w)), "{cam}: {err}");
        assert!(!d.join("bad.png").exists(), "{cam}");
    }
    // above the roof (12 m) and above the boulder (its top 4 m up): drawn
    for (cam, out) in [("eye:20,17,+13:55,55,+5", "roof.png"), ("eye:45,45,+4.5:5,55,+5", "boulder.png")] {
        let (ok, err) = run(&["render", "obs_run", "--camera", cam, "--size", "64x48", "--out", out]);
        assert!(ok && d.join(out).is_file(), "{cam}: {err}");
    }
}

/// Trial 37: a 16-bit PNG heightmap's lowest pixel (value 0, the bottom of its height range)
/// was sea-level water. A PNG now has no sea unless `--sea-level` or the scenario's
/// `climate.sea_level_m` says where it is; other DEMs keep sea level 0 m.
#[test]
fn a_png_heightmaps_lowest_pixel_is_no_sea_unless_a_sea_level_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h16.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(8, 8, |x, y| image::Luma([(x * 4000 + y * 3000) as u16])).save(&p).unwrap();
    let info = |extra: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(&p).args(["--cell", "10", "--min-height", "0", "--max-height", "1000"]).args(extra).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let out = info(&[]);
    assert!(out.contains("water:       none") && out.contains("--sea-level"), "{out}");
    let out = info(&["--sea-level", "0"]);
    assert!(out.contains("water:       1 cells at or below sea level 0 m"), "{out}");
    // a scenario on the PNG: no sea unless it gives one; the lowest cell is on the site
    let toml = |climate: &str| format!("name = \"png\"\nyears = 1\nseed = 1\nspecies = [\"beech\"]\n[terrain]\npath = \"{}\"\ncell_m = 10.0\nheight_range_m = [0.0, 1000.0]\n{climate}", p.display());
    let sc = sylva::sim::Scenario::from_toml_str(&toml(""), "png").unwrap();
    assert_eq!(sc.climate.sea_level_m, sylva::sim::scenario::NO_SEA_LEVEL_M);
    let site = sc.site().unwrap();
    assert!(site.mask.data.iter().all(|&m| m), "a masked cell: {} of 64 on the site", site.mask.data.iter().filter(|&&m| m).count());
    let sc = sylva::sim::Scenario::from_toml_str(&toml("[climate]\nsea_level_m = 0.0\n"), "png").unwrap();
    assert_eq!(sc.climate.sea_level_m, 0.0);
    assert_eq!(sc.site().unwrap().mask.data.iter().filter(|&&m| !m).count(), 1, "the given sea level floods the lowest cell");
    // another DEM keeps sea level 0 m
    let sc = sylva::sim::Scenario::from_toml_str("name = \"u\"\nyears = 1\nseed = 1\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 10.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }\n", "u").unwrap();
    assert_eq!(sc.climate.sea_level_m, 0.0);
}

/// Trial 41, defect 10: `sylva terrain info` on an ESRI grid whose cells held `nan` and `inf`
/// reported "nodata: 2 cells (file value -9999)". Such cells are nodata, as the file's own
/// nodata value is, and the line now says both.
#[test]
fn terrain_info_says_nan_and_infinite_cells_are_nodata() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nan.asc");
    std::fs::write(&p, "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n500 501 502\n503 nan 505\n506 507 inf\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info"]).arg(&p).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let line = out.lines().find(|l| l.starts_with("nodata:")).unwrap_or_default();
    assert!(line.contains("2 cells") && line.contains("NaN or infinite") && !line.ends_with("(file value -9999)"), "{line}");
}
