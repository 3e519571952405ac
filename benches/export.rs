//! Stand export benchmark (issue 32, "Must show": `sylva export RUN --year 150 --area
//! 1150,850,1200,900 --out stand.glb`, the 0.25 ha of the default run, in ≤ 30 s on 2 cores).
//! Plain program: `cargo bench --bench export` (threads: `RAYON_NUM_THREADS`).
//!
//! `SYLVA_EXPORT_RUN=DIR` exports an existing run directory (the figure of BENCHMARKS.md: the
//! default run of `sylva simulate`, year 150); `SYLVA_EXPORT_YEAR=Y` (default 150) and
//! `SYLVA_EXPORT_AREA=X0,Y0,X1,Y1` (m, default `1150,850,1200,900`) choose the snapshot and the
//! area. Without `SYLVA_EXPORT_RUN` it first simulates a small fixture run (a 100 m flat site,
//! beech planted at 5 m at 30 years and Norway spruce at 25, one year; the run of
//! `tests/export.rs`) and exports its area `0,0,50,100`, so that CI can build and run it in a
//! few seconds; that figure is not the issue's.
//!
//! Prints the export's wall time split into its phases (`ExportStats`: `read_s`, `adapt_s`
//! = `analysis_s` + `adaptation_s`, `mesh_s`, `write_s`, `texture_s`, `finish_s`, `total_s`),
//! the trees, models and bytes written, and an FNV-1a fingerprint of the file's bytes: the same
//! for any `RAYON_NUM_THREADS` (the export is deterministic for a given seed), so a speed-up
//! can be checked to write the same file byte for byte (on `SYLVA_EXPORT_RUN`: the fixture lies
//! in a new temporary folder each time, whose path the scene's `extras` record, so its
//! fingerprint changes from run to run). `SYLVA_EXPORT_OUT=FILE` keeps the file
//! (default: a temporary folder, removed).
use std::path::{Path, PathBuf};

/// FNV-1a (64 bits) over `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// The library a run was simulated with: the shipped species overlaid by the run's `species/`.
fn run_library(run: &Path) -> sylva::species::SpeciesLibrary {
    let mut lib = sylva::species::SpeciesLibrary::embedded().expect("embedded species");
    let dir = run.join("species");
    if dir.is_dir() {
        lib.overlay_dir(&dir).unwrap_or_else(|e| panic!("species of {}: {e}", run.display()));
    }
    lib
}

/// The fixture run of `tests/export.rs` (`small_run`) in `dir`.
fn fixture_run(dir: &Path) {
    let mut toml = String::from(
        r#"
name = "export_bench"
years = 1
seed = 5
snapshot_every = 1
species = ["beech", "norway_spruce"]
[terrain]
uniform = { width = 4, height = 4, cell_m = 25.0, elevation_m = 310.0, indices = [5, 5, 2, 5, 6, 6] }
"#,
    );
    for (sp, age, x0, x1) in [("beech", 30.0, 0.0, 40.0), ("norway_spruce", 25.0, 40.0, 50.0)] {
        toml += &format!("[[start]]\nkind = \"planted\"\nspecies = \"{sp}\"\nspacing_m = 5.0\nage_yr = {age:?}\narea = [{x0:?}, 0.0, {x1:?}, 100.0]\n");
    }
    let sc = sylva::sim::Scenario::from_toml_str(&toml, "export_bench").expect("fixture scenario");
    let site = sc.site().expect("fixture site");
    let mut opts = sylva::job::run::RunOptions::new(dir);
    opts.map_px = 32;
    sylva::job::run::run_scenario(&sc, site, &run_library(dir), opts).expect("fixture run");
}

fn main() {
    let tmp = tempfile::tempdir().expect("temporary folder");
    let (run, year, area) = match std::env::var_os("SYLVA_EXPORT_RUN") {
        Some(r) => {
            let year = std::env::var("SYLVA_EXPORT_YEAR").ok().map_or(150, |y| y.trim().parse().expect("SYLVA_EXPORT_YEAR: a year"));
            let area = sylva::job::export::parse_area(&std::env::var("SYLVA_EXPORT_AREA").unwrap_or_else(|_| "1150,850,1200,900".into())).expect("SYLVA_EXPORT_AREA");
            (PathBuf::from(r), Some(year), area)
        }
        None => {
            let run = tmp.path().join("run");
            fixture_run(&run);
            (run, None, [0.0, 0.0, 50.0, 100.0])
        }
    };
    let out = std::env::var_os("SYLVA_EXPORT_OUT").map_or_else(|| tmp.path().join("stand.glb"), PathBuf::from);
    let lib = run_library(&run);
    let mut o = sylva::job::export::ExportOptions::new(area);
    o.year = year;
    let t = std::time::Instant::now();
    let r = sylva::job::export::export_stand(&run, &lib, &o, &out).unwrap_or_else(|e| panic!("export of {}: {e}", run.display()));
    let wall = t.elapsed().as_secs_f64();
    let s = &r.stats;
    let bytes = std::fs::read(&out).expect("the written file");
    println!("stand export of {} year {} area {:?}, {} threads", run.display(), r.year, area, rayon::current_num_threads());
    println!("  {} trees, {} saplings, {} models, {:.1} MB, fingerprint {:016x}", r.trees, r.saplings, r.models, r.bytes as f64 / 1e6, fnv1a(&bytes));
    println!(
        "  wall {wall:.2} s: read {:.2}, adapt {:.2} (analysis {:.2} + adaptation {:.2}), mesh {:.2}, write {:.2}, textures {:.2}, finish {:.2}; total {:.2} s",
        s.read_s, s.adapt_s, s.analysis_s, s.adaptation_s, s.mesh_s, s.write_s, s.texture_s, s.finish_s, s.total_s
    );
    println!("  adaptation's share of the export: {:.0} %", 100.0 * s.adapt_s / s.total_s.max(1e-9));
}
