//! Tiled runs over MPI (issue 17; `cargo test --features mpi --test mpi`, needs Open MPI's
//! `mpirun`): `mpirun -np 2` and `-np 3` of `sylva simulate` write the run directory of one
//! process byte for byte (each rank's checkpoint its own file: assembled, they are the one
//! process's `checkpoint.bin`); a run stopped on 3 ranks and resumed on 2, and one stopped on
//! 2 and resumed on 2 (each rank reading its own checkpoint), end as the unbroken run; a
//! managed run (issue 35: `scenarios/thinning_beech.toml` shortened, thinned from below over
//! the whole site) on 2 ranks, and stopped and resumed on 2, writes the one process's run too;
//! so does a run with tree inventories every 10 years and maps every 5 (`inventory_every`);
//! and a run on a GeoTIFF site (issue 37 Build 1), whose ranks each derive their band of the
//! site from a window of the DEM read by window, on 2 and 3 ranks and resumed 3 → 2.
#![cfg(feature = "mpi")]

mod common;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Beech seed trees on a flat 800 m × 240 m site (10 m light cells; beech's 200 m kernel makes
/// a 250 m halo), sources at the tile edges of 2 ranks (x = 400 m) and of 3 ranks (x = 267 m),
/// none east of 533 m: rank 2 of 3 starts with no trees. Snapshots every 5 years, checkpoints
/// every 4.
fn scenario(years: u32) -> String {
    format!(
        "name = \"mpi\"\nyears = {years}\nseed = 7\nspecies = [\"beech\"]\nlight_cell_m = 10.0\nsnapshot_every = 5\ncheckpoint_every = 4\n\
         [terrain]\nuniform = {{ width = 40, height = 12, cell_m = 20.0, elevation_m = 300.0, indices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0] }}\n\
         [[start]]\nkind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[398.0, 118.0], [404.0, 60.0], [268.0, 200.0], [264.0, 40.0], [60.0, 200.0]]\ntrees_per_source = 3\n"
    )
}

fn sylva() -> &'static str {
    env!("CARGO_BIN_EXE_sylva")
}

fn write_scenario(dir: &Path, years: u32) -> PathBuf {
    let p = dir.join(format!("mpi_{years}.toml"));
    std::fs::write(&p, scenario(years)).unwrap();
    p
}

/// Runs `sylva simulate SC --out OUT [--resume]` on `ranks` MPI ranks (0: without mpirun).
fn simulate(ranks: usize, sc: &Path, out: &Path, resume: bool) {
    let mut c = if ranks == 0 {
        Command::new(sylva())
    } else {
        let mut c = Command::new("mpirun");
        c.args(["--allow-run-as-root", "--oversubscribe", "-np", &ranks.to_string(), sylva()]);
        c
    };
    c.arg("simulate").arg(sc).arg("--out").arg(out).args(["--threads", "1"]);
    if resume {
        c.arg("--resume");
    }
    let o = c.output().unwrap_or_else(|e| panic!("cannot start {} (is Open MPI's mpirun installed?): {e}", if ranks == 0 { sylva() } else { "mpirun" }));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{ranks} ranks failed: {}\n{err}", String::from_utf8_lossy(&o.stdout));
    // every rank took part as a tile (each prints its line), not N copies of one process
    for r in 0..ranks {
        assert!(err.contains(&format!("rank {r}/{ranks}: ")), "no line of rank {r} of {ranks}: {err}");
    }
}

/// The world of the scenario at its start, with the shipped species (as `sylva simulate`).
fn template(years: u32) -> sylva::sim::World {
    common::world_with(&scenario(years), &common::embedded()).1
}

#[test]
fn two_and_three_ranks_write_the_run_directory_of_one_process() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), 20);
    let one = tmp.path().join("one");
    simulate(0, &sc, &one, false);
    let f = common::files(&one);
    // a meaningful run: recruits (ids from 2^44 on) in the last inventory, on more than one tile
    assert!(f.contains_key("inventory/year_0020.parquet"), "{:?}", f.keys());
    let inv = sylva::job::inventory::read(&one.join("inventory/year_0020.parquet")).unwrap();
    let recruits: Vec<f64> = inv.iter().filter(|r| r.id >= 1 << 44).map(|r| r.x_m).collect();
    assert!(recruits.len() > 20, "only {} recruits", recruits.len());
    assert!(recruits.iter().any(|&x| x < 267.0) && recruits.iter().any(|&x| x > 400.0), "recruits on one side only");
    // the GeoPackage of the final year only (`sylva simulate --gpkg final`, the default)
    assert!(f.contains_key("checkpoint.bin") && f.contains_key("stand_table.csv") && f.contains_key("inventory/year_0020.gpkg") && !f.contains_key("inventory/year_0010.gpkg"));
    for n in [2, 3] {
        let d = tmp.path().join(format!("np{n}"));
        simulate(n, &sc, &d, false);
        let m = common::assert_same_run(&one, &d, &template(20), &format!("{n} ranks"));
        assert_eq!((m.year, m.ranks, m.tiles_across, m.tiles_up), (20, n, n, 1));
        // issue 37 Build 4: one inventory part per rank, nothing merged on rank 0
        let parts: Vec<String> = std::fs::read_dir(d.join("inventory/year_0020")).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        let want: Vec<String> = (0..n).map(|k| format!("part-{k:05}.parquet")).collect();
        let mut parts = parts;
        parts.sort();
        assert_eq!(parts, want, "{n} ranks");
        assert!(!d.join("inventory/year_0020.parquet").exists() && d.join(format!("inventory/year_0020_gpkg/part-{:05}.gpkg", n - 1)).is_file());
    }
}

#[test]
fn stopped_on_three_ranks_resumed_on_two() {
    let tmp = tempfile::tempdir().unwrap();
    let (short, long) = (write_scenario(tmp.path(), 9), write_scenario(tmp.path(), 18));
    let one = tmp.path().join("one");
    simulate(0, &long, &one, false);
    let d = tmp.path().join("split");
    simulate(3, &short, &d, false);
    // the 9-year run ended with its own checkpoint and snapshot; 2 ranks extend it to 18 years
    simulate(2, &long, &d, true);
    // scenario.toml: both runs write the scenario as run (18 years), from different files
    let m = common::assert_same_run(&one, &d, &template(18), "3 ranks for 9 years, resumed on 2 for 18");
    assert_eq!((m.year, m.ranks), (18, 2));
}

#[test]
fn stopped_on_two_ranks_resumed_on_two() {
    let tmp = tempfile::tempdir().unwrap();
    let (short, long) = (write_scenario(tmp.path(), 9), write_scenario(tmp.path(), 18));
    let one = tmp.path().join("one");
    simulate(0, &long, &one, false);
    let d = tmp.path().join("split");
    simulate(2, &short, &d, false);
    let m = sylva::job::checkpoint::read_manifest(&d).unwrap();
    assert_eq!((m.year, m.ranks, m.files.len()), (9, 2, 2));
    assert!(!d.join("checkpoint.bin").exists());
    // the same layout: each rank reads its own file
    simulate(2, &long, &d, true);
    let m = common::assert_same_run(&one, &d, &template(18), "2 ranks for 9 years, resumed on 2 for 18");
    assert_eq!((m.year, m.ranks), (18, 2));
}

/// [`common::short_thinning_toml`] written into `dir`.
fn write_thinning(dir: &Path, years: u32) -> PathBuf {
    let p = dir.join(format!("thinning_{years}.toml"));
    std::fs::write(&p, common::short_thinning_toml(years)).unwrap();
    p
}

#[test]
fn a_thinned_stand_on_two_ranks_and_stopped_and_resumed_writes_the_run_of_one_process() {
    let tmp = tempfile::tempdir().unwrap();
    let (short, long) = (write_thinning(tmp.path(), 32), write_thinning(tmp.path(), 43));
    let one = tmp.path().join("one");
    simulate(0, &long, &one, false);
    // a meaningful run: thinnings remove trees in years 32, 37 and 42 (issue 35 round 44; 22,
    // 27 and 32 before it); year 32's inventory
    // holds the thinned trees
    let table = std::fs::read_to_string(one.join("stand_table.csv")).unwrap();
    let head: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let col = head.iter().position(|h| *h == "harvest_stems_ha").unwrap();
    let thinned: Vec<u32> = table.lines().skip(1).filter(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap() > 0.0).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert_eq!(thinned, vec![32, 37, 42]);
    let inv = sylva::job::inventory::read(&one.join("inventory/year_0032.parquet")).unwrap();
    assert!(inv.iter().filter(|r| r.status == "dead:harvest").count() > 50);
    let lib = common::embedded();
    let sc = sylva::sim::Scenario::load(&long).unwrap();
    let template = sylva::sim::World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    let d = tmp.path().join("np2");
    simulate(2, &long, &d, false);
    let m = common::assert_same_run(&one, &d, &template, "thinning_beech on 2 ranks");
    assert_eq!((m.year, m.ranks), (43, 2));
    // stopped after the thinning of year 32 on 2 ranks, resumed on 2
    let d = tmp.path().join("split");
    simulate(2, &short, &d, false);
    simulate(2, &long, &d, true);
    let m = common::assert_same_run(&one, &d, &template, "thinning_beech on 2 ranks for 32 years, resumed on 2 for 43");
    assert_eq!((m.year, m.ranks), (43, 2));
}

#[test]
fn inventories_every_ten_years_on_two_ranks_write_the_run_directory_of_one_process() {
    // `inventory_every` (issue 34): the ranks write their inventory parts only in the
    // inventory years, the maps at every snapshot
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("mpi_inv.toml");
    let text = scenario(20).replace("snapshot_every = 5\n", "snapshot_every = 5\ninventory_every = 10\n");
    std::fs::write(&sc, &text).unwrap();
    let one = tmp.path().join("one");
    simulate(0, &sc, &one, false);
    let f = common::files(&one);
    assert!(f.contains_key("inventory/year_0010.parquet") && !f.contains_key("inventory/year_0015.parquet") && f.contains_key("maps/species_year_0015.png"), "{:?}", f.keys());
    let d = tmp.path().join("np2");
    simulate(2, &sc, &d, false);
    let m = common::assert_same_run(&one, &d, &common::world_with(&text, &common::embedded()).1, "inventory_every on 2 ranks");
    assert_eq!((m.year, m.ranks), (20, 2));
}

/// Beech seed trees on a 600 m × 400 m window of the Coweeta DEM (10 m cells, slopes of
/// 10–40°: the conditions vary cell by cell), read from the GeoTIFF file.
fn dem_scenario(years: u32) -> String {
    let dem = Path::new(env!("CARGO_MANIFEST_DIR")).join("terrains/coweeta_10m_utm17n.tif");
    format!(
        "name = \"mpi_dem\"\nyears = {years}\nseed = 7\nspecies = [\"beech\"]\nlight_cell_m = 10.0\nsnapshot_every = 5\ncheckpoint_every = 4\n\
         [terrain]\npath = \"{}\"\nwindow = [140, 100, 60, 40]\n\
         [[start]]\nkind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[298.0, 198.0], [304.0, 60.0], [198.0, 300.0], [202.0, 40.0], [60.0, 300.0], [500.0, 200.0]]\ntrees_per_source = 3\n",
        dem.display()
    )
}

/// Runs as [`simulate`] and returns stderr, which must name every rank's band of the site.
fn simulate_dem(ranks: usize, sc: &Path, out: &Path, resume: bool) -> String {
    simulate_dem_with(ranks, sc, out, resume, &[])
}

/// [`simulate_dem`] with `extra` arguments after `--threads 1` (e.g. `--years 6`).
fn simulate_dem_with(ranks: usize, sc: &Path, out: &Path, resume: bool, extra: &[&str]) -> String {
    let mut c = Command::new("mpirun");
    c.args(["--allow-run-as-root", "--oversubscribe", "-np", &ranks.to_string(), sylva()]);
    c.arg("simulate").arg(sc).arg("--out").arg(out).args(["--threads", "1"]).args(extra);
    if resume {
        c.arg("--resume");
    }
    let o = c.output().unwrap_or_else(|e| panic!("cannot start mpirun (is Open MPI's mpirun installed?): {e}"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{ranks} ranks failed: {}\n{err}", String::from_utf8_lossy(&o.stdout));
    for r in 0..ranks {
        let (r0, r1) = (r * 40 / ranks, (r + 1) * 40 / ranks);
        assert!(err.contains(&format!("rank {r}/{ranks}: site rows {r0}..{r1} of 40 derived from a window of")), "rank {r} of {ranks} did not derive its band: {err}");
        // round 34: its hydrology from its rows and two rows of halo, not the whole DEM on rank 0
        let (h0, h1) = (r0.saturating_sub(2), (r1 + 2).min(40));
        assert!(err.contains(&format!("hydrology from rows {h0}..{h1})")), "rank {r} of {ranks} did not read its band's rows for the hydrology: {err}");
    }
    err.into_owned()
}

/// Issue 37 Build 1, round 37: the checkpoint files each rank of a resumed run on `ranks`
/// ranks said it read (`rank R/N: resumed year Y from K of M checkpoint files (…); holds site
/// cells columns a..b, rows c..d of W × H` on stderr `err`), checked against the manifests
/// before (`old`) and after (`new`) the resume: every rank read only files of old tiles whose
/// light columns overlap its own (tiles across only: the layouts of 2 and 3 ranks here), old
/// rank 0's among them on rank 0, and holds a window of the site of its tile's columns plus at
/// most 3 cells a side, not the whole site. Returns the old tiles each rank read.
fn resumed_reads(err: &str, ranks: usize, old: &sylva::job::checkpoint::Manifest, new: &sylva::job::checkpoint::Manifest, what: &str) -> Vec<Vec<usize>> {
    assert_eq!((old.tiles_up, new.tiles_up, new.ranks), (1, 1, ranks), "{what}: layouts of tiles across only");
    (0..ranks)
        .map(|r| {
            let head = format!("rank {r}/{ranks}: resumed year {} from ", old.year);
            let line = err.lines().find(|l| l.starts_with(&head)).unwrap_or_else(|| panic!("{what}: rank {r} did not say what it resumed from: {err}"));
            let files = line.split_once(" checkpoint files (").unwrap().1.split_once(')').unwrap().0;
            let read: Vec<usize> = files.split(", ").map(|f| old.files.iter().position(|g| g == f).unwrap_or_else(|| panic!("{what}: {f} is not a file of the manifest {:?}", old.files))).collect();
            assert!(line.contains(&format!(" from {} of {} checkpoint files", read.len(), old.ranks)), "{what}: {line}");
            let (c0, c1) = (new.col_bounds[r], new.col_bounds[r + 1]);
            for &k in &read {
                let (o0, o1) = (old.col_bounds[k], old.col_bounds[k + 1]);
                assert!(o0 < c1 && c0 < o1, "{what}: rank {r} (light columns {c0}..{c1}) read the file of old tile {k} (columns {o0}..{o1}), which it does not overlap: {line}");
            }
            assert!(r != 0 || read.contains(&0), "{what}: rank 0 did not read old rank 0's file (the stand table): {line}");
            // the site cells it holds: its tile's columns (10 m light cells on 10 m site cells)
            let held = line.split_once("holds site cells columns ").unwrap().1;
            let (cols, rest) = held.split_once(", rows ").unwrap();
            let (a, b) = cols.split_once("..").unwrap();
            let (a, b): (usize, usize) = (a.parse().unwrap(), b.parse().unwrap());
            assert!(rest.ends_with(" of 60 × 40") && a + 3 >= c0 && b <= c1 + 3 && b - a < 60, "{what}: rank {r} (light columns {c0}..{c1}) holds {held}");
            read
        })
        .collect()
}

#[test]
fn a_dem_read_by_window_on_two_and_three_ranks_writes_the_run_of_one_process() {
    let tmp = tempfile::tempdir().unwrap();
    let (short, long) = (tmp.path().join("dem_11.toml"), tmp.path().join("dem_24.toml"));
    std::fs::write(&short, dem_scenario(11)).unwrap();
    std::fs::write(&long, dem_scenario(24)).unwrap();
    let one = tmp.path().join("one");
    simulate(0, &long, &one, false);
    let (_, template) = common::world_with(&dem_scenario(24), &common::embedded());
    // a meaningful site: the conditions vary over the window
    let s = &template.site.conditions;
    let (lo, hi) = s.slope_deg.data.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi - lo > 10.0 && s.mask.data.iter().all(|m| *m), "slopes {lo}–{hi}°");
    // recruits (ids from 2^44 on) in the last inventory, on more than one band and tile
    let inv = sylva::job::inventory::read(&one.join("inventory/year_0024.parquet")).unwrap();
    let recruits: Vec<f64> = inv.iter().filter(|r| r.id >= 1 << 44).map(|r| r.x_m).collect();
    assert!(recruits.len() > 100 && recruits.iter().any(|&x| x < 200.0) && recruits.iter().any(|&x| x > 400.0), "{} recruits", recruits.len());
    for n in [2, 3] {
        let d = tmp.path().join(format!("np{n}"));
        simulate_dem(n, &long, &d, false);
        let m = common::assert_same_run(&one, &d, &template, &format!("DEM site on {n} ranks"));
        assert_eq!((m.year, m.ranks), (24, n));
    }
    // resumed per rank (issue 37 round 37): 3 → 2 (each rank reads the two files over it),
    // 2 → 3 (the outer ranks one file each, the middle one two) and 2 → 2 (its own file)
    for (first, then, want) in [(3, 2, vec![vec![0, 1], vec![1, 2]]), (2, 3, vec![vec![0], vec![0, 1], vec![1]]), (2, 2, vec![vec![0], vec![1]])] {
        let what = format!("DEM site on {first} ranks for 11 years, resumed on {then} for 24");
        let d = tmp.path().join(format!("split_{first}_{then}"));
        simulate_dem(first, &short, &d, false);
        let old = sylva::job::checkpoint::read_manifest(&d).unwrap();
        let err = simulate_dem(then, &long, &d, true);
        let m = common::assert_same_run(&one, &d, &template, &what);
        assert_eq!((m.year, m.ranks), (24, then));
        assert_eq!(resumed_reads(&err, then, &old, &m, &what), want, "{what}: files read per rank");
    }
}

/// The scenario's warnings ([`sylva::sim::World::new`]: nothing to grow from, a management year
/// beyond the run) are printed once, by rank 0's run driver, not once per rank: on 3 MPI ranks
/// and on 3 tiles in one process (`--tiles 3`), as by one process.
#[test]
fn the_scenarios_warnings_are_printed_once_on_three_ranks() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("bare.toml");
    std::fs::write(
        &sc,
        "name = \"bare\"\nyears = 2\nseed = 7\nspecies = [\"beech\"]\nlight_cell_m = 10.0\n\
         [terrain]\nuniform = { width = 40, height = 12, cell_m = 20.0, elevation_m = 300.0, indices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0] }\n\
         [[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_stems_ha = 100\nyears = [1, 30]\n",
    )
    .unwrap();
    for (how, ranks) in [("one process", 0), ("mpirun -np 3", 3), ("--tiles 3", 0)] {
        let out = tmp.path().join(how.replace(' ', "_"));
        let mut c = if ranks == 0 { Command::new(sylva()) } else { Command::new("mpirun") };
        if ranks > 0 {
            c.args(["--allow-run-as-root", "--oversubscribe", "-np", &ranks.to_string(), sylva()]);
        }
        c.arg("simulate").arg(&sc).arg("--out").arg(&out).args(["--threads", "1"]);
        if how == "--tiles 3" {
            c.args(["--tiles", "3"]);
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{how} failed: {err}");
        if ranks > 0 {
            assert!(err.contains("rank 2/3: "), "{how}: no line of rank 2: {err}");
        }
        assert_eq!(err.matches("nothing will grow").count(), 1, "{how}: {err}");
        assert_eq!(err.matches("management[0].years[1] = 30").count(), 1, "{how}: {err}");
    }
}

/// [`dem_scenario`] with management over the tile edges of 2 and 3 ranks (issue 37, round 36):
/// a beech and spruce planting of year 0 in a triangle, a thinning from below over it, a
/// clear-cut strip narrower than a light cell and a planting of year 7.
fn dem_managed(years: u32) -> String {
    dem_scenario(years).replace("name = \"mpi_dem\"", "name = \"mpi_dem_managed\"").replace("species = [\"beech\"]", "species = [\"beech\", \"norway_spruce\"]")
        + "[[management]]\nkind = \"planting\"\nmix = { beech = 0.7, norway_spruce = 0.3 }\nspacing_m = 3.0\nage_yr = 25.0\nyear = 0\npolygons = [[[[150.0, 100.0], [450.0, 120.0], [300.0, 300.0]]]]\n\
           [[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_stems_ha = 250\narea = [150.0, 100.0, 450.0, 300.0]\nyears = [5, 10]\n\
           [[management]]\nkind = \"harvest\"\nmethod = \"clear_cut\"\narea = [0.0, 198.0, 600.0, 202.0]\nyears = [9]\n\
           [[management]]\nkind = \"planting\"\nmix = { beech = 1.0 }\nspacing_m = 4.0\nyear = 7\narea = [250.0, 20.0, 350.0, 90.0]\n"
}

/// Issue 37, round 36, step 1: a scenario with management on a GeoTIFF site, whose ranks each
/// derive their band of the site from a window of the DEM, hold their band and tile only and
/// resolve the management's areas and plantings from their tiles (rank 0 too: until round 36
/// every rank held the whole site of a managed scenario), writes one process's run directory
/// byte for byte on 2 and 3 ranks.
#[test]
fn a_managed_dem_run_on_two_and_three_ranks_writes_the_run_of_one_process() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("dem_managed.toml");
    std::fs::write(&sc, dem_managed(12)).unwrap();
    let one = tmp.path().join("one");
    simulate(0, &sc, &one, false);
    let (_, template) = common::world_with(&dem_managed(12), &common::embedded());
    // a meaningful run: the planting stands at the start, the thinnings and the strip remove trees
    assert!(template.stand.trees.len() > 2_500, "{} trees at the start", template.stand.trees.len());
    let table = std::fs::read_to_string(one.join("stand_table.csv")).unwrap();
    let head: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let col = head.iter().position(|h| *h == "harvest_stems_ha").unwrap();
    let cut: Vec<u32> = table.lines().skip(1).filter(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap() > 0.0).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert!(cut.contains(&9) && cut.len() >= 2, "harvests in years {cut:?}");
    for n in [2, 3] {
        let d = tmp.path().join(format!("np{n}"));
        simulate_dem(n, &sc, &d, false);
        let m = common::assert_same_run(&one, &d, &template, &format!("managed DEM site on {n} ranks"));
        assert_eq!((m.year, m.ranks), (12, n));
    }
    // resumed per rank (issue 37 round 37): stopped after year 6 (before the planting of year
    // 7, the strip of 9 and the thinning of 10) on 3 and 2 ranks, resumed on 2, 3 and 2; every
    // rank holds its band and tile, reads only the files over its tile and resolves the
    // management with the others from its tile. The first part runs the 12-year scenario
    // shortened by `--years 6` (round 41: a scenario whose own last year is 6 refuses the strip
    // of year 9 as an entry that could never act; a run shortened on the command line warns).
    for (first, then, want) in [(3, 2, vec![vec![0, 1], vec![1, 2]]), (2, 3, vec![vec![0], vec![0, 1], vec![1]]), (2, 2, vec![vec![0], vec![1]])] {
        let what = format!("managed DEM site on {first} ranks for 6 years, resumed on {then} for 12");
        let d = tmp.path().join(format!("split_{first}_{then}"));
        let err6 = simulate_dem_with(first, &sc, &d, false, &["--years", "6"]);
        assert!(err6.contains("warning:") && err6.contains("harvest#2"), "{what}: no warning that the strip of year 9 does not act in 6 years: {err6}");
        let old = sylva::job::checkpoint::read_manifest(&d).unwrap();
        assert_eq!(old.year, 6);
        let err = simulate_dem(then, &sc, &d, true);
        let m = common::assert_same_run(&one, &d, &template, &what);
        assert_eq!((m.year, m.ranks), (12, then));
        assert_eq!(resumed_reads(&err, then, &old, &m, &what), want, "{what}: files read per rank");
    }
}

/// Issue 37 round 37: a planting that plants nothing (50 m spacing in a 4 m square), which the
/// ranks of an MPI run refuse together as they build their tiles (each holding its band only),
/// is refused before anything is written, as one process refuses it: the same message naming
/// the entry's area, and no run folder (until round 37 the MPI run left the folder with its
/// `species/` files).
#[test]
fn a_planting_that_plants_nothing_is_refused_on_two_ranks_before_any_folder_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("bad.toml");
    std::fs::write(&sc, scenario(2) + "[[management]]\nkind = \"planting\"\nmix = { beech = 1.0 }\nspacing_m = 50.0\nyear = 1\narea = [1.0, 1.0, 5.0, 5.0]\n").unwrap();
    for (how, ranks) in [("one process", 0), ("mpirun -np 2", 2)] {
        let out = tmp.path().join(how.replace(' ', "_"));
        let mut c = if ranks == 0 { Command::new(sylva()) } else { Command::new("mpirun") };
        if ranks > 0 {
            c.args(["--allow-run-as-root", "--oversubscribe", "-np", &ranks.to_string(), sylva()]);
        }
        let o = c.arg("simulate").arg(&sc).arg("--out").arg(&out).args(["--threads", "1"]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{how}: a planting that plants nothing ran");
        assert!(err.contains("management[0].area"), "{how}: {err}");
        assert!(!out.exists(), "{how}: the refused run left {:?}", common::files(&out).keys().collect::<Vec<_>>());
    }
}
