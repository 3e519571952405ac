//! Faults during a run (issue 16, Build 3), with the `sylva` binary on a small scenario:
//! - a run killed with SIGKILL at many points (in the middle of each kind of write, through the
//!   `SYLVA_FAULT_KILL_AT_WRITE` fault hook of `output::write_atomic`; after k checkpoint years;
//!   at seeded random moments from outside) and resumed with `--resume` ends with every file
//!   byte-identical to an unbroken run, and what a killed run leaves visible is whole;
//! - a file-size limit (RLIMIT_FSIZE, SIGXFSZ ignored: `write` returns EFBIG, as on a full disk)
//!   hit at several moments, and an unwritable folder, give an error naming the file and the
//!   reason and leave the last checkpoint valid;
//! - a truncated or corrupted checkpoint (every truncation length, a flip of every byte) is
//!   refused with a message naming the file;
//! - `--resume` with a changed seed, species pool, species parameter, DEM or light cell is
//!   refused naming the field with its old and new value, the run directory untouched, while
//!   more `years` continue the run.
//!
//! The counts each test reaches are printed (`--nocapture`) and recorded in docs/RELIABILITY.md.
mod common;
use common::files;
use std::collections::BTreeMap;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The small run: 8 × 8 cells of 20 m (2.56 ha), planted beech and birch seed rain; a snapshot
/// (with seasonal snapshots) and a checkpoint every 2 years.
fn scenario(years: u32, seed: u64, species: &str, light_cell: f64, terrain: &str) -> String {
    format!(
        r#"name = "faults"
years = {years}
seed = {seed}
snapshot_every = 2
seasonal_snapshots = true
checkpoint_every = 2
light_cell_m = {light_cell}
species = [{species}]
[terrain]
{terrain}
[[start]]
kind = "planted"
species = "beech"
spacing_m = 6.0
age_yr = 10.0
[[start]]
kind = "seed_rain"
species = "silver_birch"
seeds_per_ha = 3000.0
"#
    )
}

const UNIFORM: &str = "uniform = { width = 8, height = 8, cell_m = 20.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }";
const POOL: &str = r#""beech", "silver_birch""#;

fn small(years: u32) -> String {
    scenario(years, 11, POOL, 5.0, UNIFORM)
}

fn sylva() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sylva"));
    c.env_remove("SYLVA_FAULT_KILL_AT_WRITE").stdout(Stdio::null()).stderr(Stdio::piped());
    c
}

/// `sylva simulate SCENARIO --out OUT [--resume]` in `dir`.
fn simulate(dir: &Path, scenario: &str, out: &str, resume: bool) -> Command {
    let mut c = sylva();
    c.current_dir(dir).args(["simulate", scenario, "--out", out, "--threads", "2"]);
    if resume {
        c.arg("--resume");
    }
    c
}

fn ok(mut c: Command) -> Output {
    let o = c.output().unwrap();
    assert!(o.status.success(), "{:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
    o
}

/// Asserts that the run directory `got` holds exactly the files of `want`, byte for byte.
fn assert_same(got: &Path, want: &BTreeMap<String, Vec<u8>>, what: &str) {
    let g = files(got);
    let names = |m: &BTreeMap<String, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(&g), names(want), "{what}: the files differ from the unbroken run's");
    for (k, v) in want {
        assert!(g[k] == *v, "{what}: {k} differs from the unbroken run's ({} vs {} bytes)", g[k].len(), v.len());
    }
}

/// A temporary file of `output::write_atomic` (`.<name>.<pid>.tmp`) or of the write probe.
fn is_temporary(rel: &str) -> bool {
    Path::new(rel).file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with('.') && n.ends_with(".tmp"))
}

/// What a killed or failed run left must be whole where a reader looks: every file but the
/// temporary ones equals the unbroken run's (files written once: snapshots, maps, species,
/// scenario), is a whole-line prefix of it (the stand table grows) or decodes (its plot);
/// the checkpoint is checked by resuming. Returns the number of files checked.
fn assert_whole(dir: &Path, reference: &BTreeMap<String, Vec<u8>>, what: &str) -> usize {
    let mut n = 0;
    for (k, v) in files(dir) {
        if is_temporary(&k) || k == "checkpoint.bin" {
            continue;
        }
        let want = reference.get(&k).unwrap_or_else(|| panic!("{what}: {k} is not a file of the unbroken run"));
        match k.as_str() {
            "stand_table.csv" | "stand_table_species.csv" => assert!(want.starts_with(&v) && v.ends_with(b"\n"), "{what}: {k} is not whole lines of the unbroken run's"),
            "stand_table.png" => assert!(image::load_from_memory(&v).is_ok(), "{what}: {k} does not decode"),
            _ => assert!(v == *want, "{what}: {k} ({} bytes) differs from the unbroken run's ({} bytes): half-written?", v.len(), want.len()),
        }
        n += 1;
    }
    n
}

struct Fixture {
    _tmp: tempfile::TempDir,
    dir: PathBuf,
    reference: BTreeMap<String, Vec<u8>>,
}

/// A temporary folder with `small.toml` (6 years) and its unbroken run in `ref/`.
fn fixture() -> Fixture {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().to_path_buf();
    std::fs::write(dir.join("small.toml"), small(6)).unwrap();
    ok(simulate(&dir, "small.toml", "ref", false));
    let reference = files(&dir.join("ref"));
    assert!(reference.contains_key("checkpoint.bin") && reference.contains_key("inventory/year_0006.parquet") && reference.contains_key("inventory/year_0004_autumn.parquet"), "{:?}", reference.keys());
    Fixture { _tmp: tmp, dir, reference }
}

/// Runs the small scenario into `out` with the fault hook set to kill the process in its
/// `k`-th atomic write; returns whether it was killed (false: the run had fewer writes).
fn killed_at_write(f: &Fixture, out: &str, k: u64) -> bool {
    let o = simulate(&f.dir, "small.toml", out, false).env("SYLVA_FAULT_KILL_AT_WRITE", k.to_string()).output().unwrap();
    if o.status.success() {
        return false;
    }
    assert_eq!(o.status.signal(), Some(libc::SIGKILL), "write {k}: {:?} {}", o.status, String::from_utf8_lossy(&o.stderr));
    true
}

#[test]
fn sigkill_in_the_middle_of_any_write_then_resume_is_byte_identical() {
    let f = fixture();
    let (mut kills, mut checked, mut temporaries) = (0, 0, 0);
    let mut k = 1;
    loop {
        let out = format!("w{k}");
        if !killed_at_write(&f, &out, k) {
            break;
        }
        kills += 1;
        let d = f.dir.join(&out);
        temporaries += files(&d).keys().filter(|n| is_temporary(n)).count();
        checked += assert_whole(&d, &f.reference, &format!("killed in write {k}"));
        ok(simulate(&f.dir, "small.toml", &out, true));
        assert_same(&d, &f.reference, &format!("killed in write {k}, resumed"));
        // every write for the first 12 (species, scenario, year 0, the first seasonal
        // snapshots, tables, checkpoint), then every 7th
        k += if k < 12 { 1 } else { 7 };
    }
    eprintln!("SIGKILL in the middle of a write: {kills} kill points (writes 1–12, then every 7th, of {} files), {checked} visible files whole, {temporaries} temporary files left and cleared, all resumed byte-identical", f.reference.len());
    assert!(kills >= 15, "only {kills} kill points: the run writes fewer files than expected");
    assert!(temporaries >= kills, "each kill leaves its half-written temporary file");
}

#[test]
fn sigkill_after_k_checkpoint_years_and_at_random_moments_then_resume_is_byte_identical() {
    let f = fixture();
    // after k checkpoint years: as soon as the checkpoint year's snapshot exists
    let mut points = 0;
    for year in [2u32, 4] {
        let out = format!("y{year}");
        let mut child = simulate(&f.dir, "small.toml", &out, false).spawn().unwrap();
        let marker = f.dir.join(&out).join(format!("inventory/year_{year:04}.parquet"));
        while !marker.exists() && child.try_wait().unwrap().is_none() {
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        child.kill().unwrap(); // SIGKILL
        let st = child.wait().unwrap();
        points += (st.signal() == Some(libc::SIGKILL)) as usize;
        assert_whole(&f.dir.join(&out), &f.reference, &format!("killed after year {year}"));
        ok(simulate(&f.dir, "small.toml", &out, true));
        assert_same(&f.dir.join(&out), &f.reference, &format!("killed after year {year}, resumed"));
    }
    // from outside at seeded random moments of an unbroken run's duration
    let t = std::time::Instant::now();
    ok(simulate(&f.dir, "small.toml", "timing", false));
    let dur = t.elapsed();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut random_kills = 0;
    for i in 0..6 {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let frac = 0.15 + 0.8 * ((state >> 11) as f64 / (1u64 << 53) as f64);
        let out = format!("r{i}");
        let mut child = simulate(&f.dir, "small.toml", &out, false).spawn().unwrap();
        std::thread::sleep(dur.mul_f64(frac));
        let _ = child.kill();
        let st = child.wait().unwrap();
        random_kills += (st.signal() == Some(libc::SIGKILL)) as usize;
        let d = f.dir.join(&out);
        assert_whole(&d, &f.reference, &format!("killed at {:.0} % of the run", 100.0 * frac));
        ok(simulate(&f.dir, "small.toml", &out, true));
        assert_same(&d, &f.reference, &format!("killed at {:.0} % of the run, resumed", 100.0 * frac));
    }
    eprintln!("SIGKILL after checkpoint years: {points} of 2 kill points reached; at random moments: {random_kills} of 6 runs killed before their end; all resumed byte-identical");
}

/// `sylva simulate` with a file-size limit of `limit` bytes (RLIMIT_FSIZE) and SIGXFSZ ignored,
/// so a write past the limit fails with EFBIG, as on a full disk.
fn with_file_limit(mut c: Command, limit: u64) -> Output {
    // SAFETY: only async-signal-safe calls (setrlimit, signal) between fork and exec.
    unsafe {
        c.pre_exec(move || {
            let lim = libc::rlimit { rlim_cur: limit, rlim_max: limit };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
    c.output().unwrap()
}

#[test]
fn a_full_disk_mid_run_names_the_file_and_leaves_the_last_checkpoint_valid() {
    let f = fixture();
    // limits between the sizes of the files the run writes: each stops the run at another write
    let mut sizes: Vec<u64> = f.reference.values().map(|v| v.len() as u64).collect();
    sizes.sort_unstable();
    sizes.dedup();
    let limits: Vec<u64> = [0.3, 0.5, 0.7, 0.85, 0.95].iter().map(|q| sizes[(q * (sizes.len() - 1) as f64) as usize] + 1).collect();
    let mut failed = 0;
    let mut with_checkpoint = 0;
    for (i, &limit) in limits.iter().enumerate() {
        let out = format!("f{i}");
        let o = with_file_limit(simulate(&f.dir, "small.toml", &out, false), limit);
        let err = String::from_utf8_lossy(&o.stderr);
        if o.status.success() {
            continue;
        }
        failed += 1;
        assert_eq!(o.status.code(), Some(1), "limit {limit}: {:?} {err}", o.status);
        assert!(err.contains("File too large") && !err.contains("panicked"), "limit {limit}: {err}");
        // the file named is one of the run's, and it is larger than the limit
        let d = f.dir.join(&out);
        let named = f.reference.keys().filter(|k| err.contains(&format!("{}/{k}", out))).max_by_key(|k| k.len()).unwrap_or_else(|| panic!("limit {limit}: no file of the run named: {err}"));
        assert!(f.reference[named].len() as u64 > limit, "limit {limit}: {named} ({} bytes) named", f.reference[named].len());
        assert!(files(&d).keys().all(|k| !is_temporary(k)), "limit {limit}: temporary file left");
        assert_whole(&d, &f.reference, &format!("limit {limit}"));
        with_checkpoint += d.join("checkpoint.bin").exists() as usize;
        // the last checkpoint is valid: resumed without the limit the run ends as the unbroken one
        ok(simulate(&f.dir, "small.toml", &out, true));
        assert_same(&d, &f.reference, &format!("limit {limit}, resumed"));
    }
    eprintln!("file-size limits {limits:?} B on a fresh run: {failed} runs stopped with a named EFBIG error ({with_checkpoint} after a checkpoint), all resumed byte-identical");
    assert!(failed >= 4, "only {failed} of {} limits were hit", limits.len());
}

/// A dense planting (14,400 trees) whose checkpoint is the largest file after year 0;
/// snapshots only at the first and last year, a checkpoint every year.
fn dense(years: u32) -> String {
    let s = scenario(years, 5, POOL, 5.0, "uniform = { width = 12, height = 12, cell_m = 20.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }");
    s.replace("snapshot_every = 2", "snapshot_every = 0").replace("seasonal_snapshots = true", "seasonal_snapshots = false").replace("checkpoint_every = 2", "checkpoint_every = 1").replace("spacing_m = 6.0", "spacing_m = 2.0")
}

#[test]
fn a_full_disk_while_writing_a_checkpoint_keeps_the_one_before() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("dense.toml"), dense(6)).unwrap();
    ok(simulate(d, "dense.toml", "ref", false));
    let reference = files(&d.join("ref"));
    // a limit between the plot and the checkpoint: the stand table and its plot are written,
    // the checkpoint after them is not
    let (png, last) = (reference["stand_table.png"].len() as u64, reference["checkpoint.bin"].len() as u64);
    assert!(png < last, "plot {png} B, checkpoint {last} B: the checkpoint must be the largest file");
    let limit = (png + last) / 2;
    for start in [1u32, 3] {
        let out = format!("c{start}");
        std::fs::write(d.join("start.toml"), dense(start)).unwrap();
        ok(simulate(d, "start.toml", &out, false));
        let dir = d.join(&out);
        let before = std::fs::read(dir.join("checkpoint.bin")).unwrap();
        let o = with_file_limit(simulate(d, "dense.toml", &out, true), limit);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "from year {start}: {:?} {err}", o.status);
        assert!(err.contains(&format!("{out}/checkpoint.bin: File too large")), "from year {start}: {err}");
        assert!(files(&dir).keys().all(|k| !is_temporary(k)), "from year {start}: temporary file left");
        // the year after was simulated and tabled, its checkpoint refused: the one before stays
        let table = std::fs::read_to_string(dir.join("stand_table.csv")).unwrap();
        // (a header, year 0's row, then one per year)
        assert_eq!(table.lines().count() - 2, start as usize + 1, "from year {start}");
        assert!(std::fs::read(dir.join("checkpoint.bin")).unwrap() == before, "from year {start}: the checkpoint before was changed");
        ok(simulate(d, "dense.toml", &out, true));
        // the shorter first run's last snapshot (year `start`) is not one of the long run's
        for (k, _) in files(&dir) {
            if k.contains(&format!("year_{start:04}")) {
                std::fs::remove_file(dir.join(k)).unwrap();
            }
        }
        assert_same(&dir, &reference, &format!("full disk at the checkpoint of year {}, resumed", start + 1));
    }
    eprintln!("full disk (limit {limit} B) while writing the checkpoints of years 2 and 4: named error, the checkpoint before kept byte for byte, resumed byte-identical");
}

#[test]
fn an_unwritable_output_names_the_folder_and_keeps_the_checkpoint() {
    let f = fixture();
    let d = &f.dir;
    // --out below a regular file
    std::fs::write(d.join("plain"), b"x").unwrap();
    let o = simulate(d, "small.toml", "plain/run", false).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--out plain/run: plain is a file, not a folder") && !err.contains("panicked"), "{err}");
    assert!(!d.join("plain/run").exists() && std::fs::read(d.join("plain")).unwrap() == b"x");

    // a run of 4 years, then its inventory folder made unwritable and the run extended to 6
    std::fs::write(d.join("four.toml"), small(4)).unwrap();
    ok(simulate(d, "four.toml", "ro", false));
    let ck = std::fs::read(d.join("ro/checkpoint.bin")).unwrap();
    let inv = d.join("ro/inventory");
    let mut perm = std::fs::metadata(&inv).unwrap().permissions();
    use std::os::unix::fs::PermissionsExt;
    perm.set_mode(0o555);
    std::fs::set_permissions(&inv, perm.clone()).unwrap();
    // root ignores the mode: put a file where the folder was instead
    let swapped = std::fs::write(inv.join(".probe"), b"").is_ok();
    if swapped {
        perm.set_mode(0o755);
        std::fs::set_permissions(&inv, perm.clone()).unwrap();
        std::fs::rename(&inv, d.join("ro/inventory.away")).unwrap();
        std::fs::write(&inv, b"not a folder").unwrap();
    }
    let o = simulate(d, "small.toml", "ro", true).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("ro/inventory") && !err.contains("panicked"), "{err}");
    // a file in the folder's place is named as such before anything is written (round 32;
    // it was the OS's "File exists")
    assert!(err.contains(if swapped { "ro/inventory is a file where the run writes its folder inventory/" } else { "Permission denied" }), "{err}");
    assert_eq!(std::fs::read(d.join("ro/checkpoint.bin")).unwrap(), ck, "the checkpoint was changed");
    if swapped {
        std::fs::remove_file(&inv).unwrap();
        std::fs::rename(d.join("ro/inventory.away"), &inv).unwrap();
        let _ = std::fs::remove_file(inv.join(".probe"));
    } else {
        perm.set_mode(0o755);
        std::fs::set_permissions(&inv, perm).unwrap();
    }
    // writable again, the run continues from its checkpoint to the unbroken run's files
    ok(simulate(d, "small.toml", "ro", true));
    assert_same(&d.join("ro"), &f.reference, "unwritable inventory, then resumed");
    eprintln!("unwritable output: --out below a file and {} refused with the path named", if swapped { "inventory/ replaced by a file (root ignores modes)" } else { "inventory/ mode 0555" });
}

#[test]
fn truncated_and_corrupted_checkpoints_are_refused_naming_the_file() {
    let f = fixture();
    let good = f.reference["checkpoint.bin"].clone();
    let sc = sylva::sim::Scenario::load(&f.dir.join("small.toml")).unwrap();
    let lib = sylva::species::SpeciesLibrary::embedded().unwrap();
    let world = sylva::sim::World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    let p = Path::new("run/checkpoint.bin");
    // a refused checkpoint leaves the world alone, so one copy serves every variant
    let mut w = world.clone();
    let mut refuse = |bytes: &[u8], what: &str| {
        let e = sylva::sim::checkpoint::restore(&mut w, bytes, p).expect_err(what).to_string();
        assert!(e.starts_with("run/checkpoint.bin: "), "{what}: {e}");
        e
    };
    // (the stand table's rows: year 0's and 6 years')
    assert_eq!(sylva::sim::checkpoint::restore(&mut world.clone(), &good, p).unwrap().len(), 7);
    // every position of the first and last 4 KiB (header, identity, stand table, checksum),
    // about 12,000 spread evenly between
    let stride = (good.len() / 12_000).max(1);
    let positions: Vec<usize> = (0..good.len()).filter(|&i| i < 4096 || i + 4096 >= good.len() || i % stride == 0).collect();
    for &n in &positions {
        let e = refuse(&good[..n], &format!("truncated to {n}"));
        assert!(e.contains("truncated") || e.contains("not a Sylva checkpoint"), "truncated to {n}: {e}");
    }
    // bytes appended
    let mut long = good.clone();
    long.extend_from_slice(b"\0\0\0\0");
    assert!(refuse(&long, "appended").contains("corrupt"));
    // a flip of one bit (cycling through the bits) at each position, and of every bit of the
    // length field and the checksum
    let mut flips = 0;
    let mut b = good.clone();
    for &i in &positions {
        b[i] ^= 1 << (i % 8);
        let e = refuse(&b, &format!("byte {i} flipped"));
        assert!(e.contains("corrupt") || e.contains("truncated") || e.contains("not a Sylva checkpoint") || e.contains("layout version"), "byte {i}: {e}");
        b[i] = good[i];
        flips += 1;
    }
    for i in (12..20).chain(good.len() - 4..good.len()) {
        for bit in 0..8 {
            b[i] ^= 1 << bit;
            refuse(&b, &format!("byte {i} bit {bit}"));
            b[i] = good[i];
            flips += 1;
        }
    }
    // a checksum mismatch says so with both values
    let mut b = good.clone();
    b[good.len() / 2] ^= 0xff;
    let e = refuse(&b, "middle");
    assert!(e.contains("CRC-32 stored") && e.contains("computed"), "{e}");

    // through the binary: the file named, nothing overwritten
    for (what, bytes) in [("truncated", good[..good.len() / 3].to_vec()), ("corrupt", b)] {
        let out = format!("ck_{what}");
        let d = f.dir.join(&out);
        std::fs::create_dir_all(&d).unwrap();
        for (k, v) in &f.reference {
            std::fs::create_dir_all(d.join(k).parent().unwrap()).unwrap();
            std::fs::write(d.join(k), v).unwrap();
        }
        std::fs::write(d.join("checkpoint.bin"), &bytes).unwrap();
        let o = simulate(&f.dir, "small.toml", &out, true).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(&format!("{out}/checkpoint.bin")) && err.contains(what) && !err.contains("panicked"), "{what}: {err}");
        assert_eq!(std::fs::read(d.join("checkpoint.bin")).unwrap(), bytes, "{what}: the refused checkpoint was overwritten");
    }
    eprintln!("checkpoint of {} bytes: {} truncation lengths and {flips} bit flips refused with the file named", good.len(), positions.len());
}

/// An ESRI ASCII grid of 8 × 8 cells of 20 m, a gentle slope (`bump` raises one cell).
fn dem(bump: f32) -> String {
    let mut s = String::from("ncols 8\nnrows 8\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n");
    for r in 0..8 {
        let row: Vec<String> = (0..8).map(|c| format!("{}", 300.0 + 2.0 * c as f32 + r as f32 + if (r, c) == (3, 4) { bump } else { 0.0 })).collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    s
}

#[test]
fn resume_with_a_changed_run_is_refused_by_name_and_more_years_continue() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("dem.asc"), dem(0.0)).unwrap();
    let terrain = "path = \"dem.asc\"";
    let write = |name: &str, text: String| std::fs::write(d.join(name), text).unwrap();
    write("base.toml", scenario(4, 7, POOL, 5.0, terrain));
    ok(simulate(d, "base.toml", "run", false));
    let before = files(&d.join("run"));

    let refused = |name: &str, wants: &[&str]| {
        let o = simulate(d, name, "run", true).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success() && err.contains("run/checkpoint.bin") && err.contains("--resume refused") && !err.contains("panicked"), "{name}: {err}");
        for w in wants {
            assert!(err.contains(w), "{name}: `{w}` not in: {err}");
        }
        assert!(files(&d.join("run")) == before, "{name}: the run directory changed");
    };
    write("seed.toml", scenario(4, 8, POOL, 5.0, terrain));
    refused("seed.toml", &["seed: checkpoint 7, now 8"]);
    write("pool.toml", scenario(4, 7, r#""beech", "silver_birch", "scots_pine""#, 5.0, terrain));
    refused("pool.toml", &["species pool: checkpoint beech, silver_birch, now beech, scots_pine, silver_birch", "species `scots_pine`: not in the checkpoint's pool"]);
    write("light.toml", scenario(4, 7, POOL, 4.0, terrain));
    refused("light.toml", &["light_cell_m: checkpoint 5, now 4"]);
    // the DEM's content: one cell 5 m higher
    std::fs::write(d.join("dem.asc"), dem(5.0)).unwrap();
    refused("base.toml", &["terrain: checkpoint 8 × 8 cells", "CRC-32", ", now 8 × 8 cells", "site conditions: checkpoint CRC-32"]);
    std::fs::write(d.join("dem.asc"), dem(0.0)).unwrap();
    // a species parameter, in the run's own species files (what --resume reads)
    let beech = d.join("run/species/beech.toml");
    let text = std::fs::read_to_string(&beech).unwrap();
    let line = text.lines().find(|l| l.starts_with("max_age_yr = ")).unwrap().to_string();
    std::fs::write(&beech, text.replace(&line, "max_age_yr = 123.0")).unwrap();
    let mut edited = before.clone();
    edited.insert("species/beech.toml".into(), std::fs::read(&beech).unwrap());
    let o = simulate(d, "base.toml", "run", true).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let old = line.trim_start_matches("max_age_yr = ");
    assert!(!o.status.success() && err.contains(&format!("species `beech` changed: life.max_age_yr: checkpoint {old}, now 123.0")), "{err}");
    assert!(files(&d.join("run")) == edited, "edited species: the run directory changed");
    std::fs::write(&beech, text).unwrap();
    // fewer years than the checkpoint's: refused, naming the field and the checkpoint's year
    // (it reported success and left `scenario.toml` at 2 years beside a 4-year stand table)
    write("shorter.toml", scenario(2, 7, POOL, 5.0, terrain));
    let o = simulate(d, "shorter.toml", "run", true).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("field `years` = 2: expected at least 4") && !err.contains("panicked"), "{err}");
    assert!(files(&d.join("run")) == before, "fewer years: the run directory changed");

    // more years continue the run: the same files as an unbroken 8-year run
    write("longer.toml", scenario(8, 7, POOL, 5.0, terrain));
    let o = ok(simulate(d, "longer.toml", "run", true));
    // the 4-year run's final GeoPackages are removed, and it says so (found by a trial: they
    // went without a word)
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(before.contains_key("inventory/year_0004.gpkg"), "{:?}", before.keys().collect::<Vec<_>>());
    assert!(err.contains("note: --resume removed inventory/year_0004.gpkg") && err.contains("GeoPackages are written for a run's final year (now year 8), and year 4 was the earlier run's"), "{err}");
    ok(simulate(d, "longer.toml", "unbroken", false));
    let unbroken = files(&d.join("unbroken"));
    assert_same(&d.join("run"), &unbroken, "4 years, resumed to 8");
    eprintln!("--resume refused by name for: seed, species pool, light cell, DEM content, a species parameter; 4 → 8 years continued byte-identical");
}

/// Ctrl-C (SIGINT) mid-run: the stopped run writes a checkpoint and a snapshot of the year it
/// stopped at (off the schedule of every 7 years, so it can be viewed); resumed, the directory
/// holds exactly the files of an unbroken run, that extra snapshot removed.
#[test]
fn ctrl_c_then_resume_is_byte_identical_to_an_unbroken_run() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let text = small(60).replace("snapshot_every = 2", "snapshot_every = 7").replace("checkpoint_every = 2", "checkpoint_every = 7");
    std::fs::write(d.join("s.toml"), text).unwrap();
    ok(simulate(d, "s.toml", "unbroken", false));
    let unbroken = files(&d.join("unbroken"));
    // the Ctrl-C handler is installed before the first snapshot is written
    let mut child = simulate(d, "s.toml", "run", false).spawn().unwrap();
    let marker = d.join("run/inventory/year_0000.parquet");
    while !marker.exists() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be interrupted");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(d.join("run/stand_table.csv")).unwrap();
    let stopped_at = table.lines().count() as u32 - 2;
    assert!((1..60).contains(&stopped_at), "{stopped_at}");
    let extra = format!("inventory/year_{stopped_at:04}.parquet");
    if stopped_at % 7 != 0 {
        assert!(files(&d.join("run")).contains_key(&extra), "the stopped run has no snapshot of year {stopped_at}");
        assert!(!unbroken.contains_key(&extra));
    }
    let o = ok(simulate(d, "s.toml", "run", true));
    // the stopped run's extra snapshot is removed, and it says so, naming the files
    let err = String::from_utf8_lossy(&o.stderr);
    if stopped_at % 7 != 0 {
        assert!(err.contains("note: --resume removed ") && err.contains(&extra) && err.contains(&format!("year {stopped_at}, where the earlier run stopped, is not a snapshot year of this run (snapshot_every = 7)")), "{err}");
    } else {
        assert!(!err.contains("note: --resume removed"), "{err}");
    }
    assert_same(&d.join("run"), &unbroken, &format!("stopped by Ctrl-C after year {stopped_at}, resumed"));
    eprintln!("Ctrl-C after year {stopped_at} of 60, resumed: byte-identical to the unbroken run");
}

/// Every file Sylva writes goes through `output::write_atomic` (temporary file + rename): no
/// other place in `src/` creates or writes a file (the write probe of `job::run`, ffmpeg's
/// temporary output, the key-frame scratch file of `job::keyframes`, unlinked as soon as it
/// is opened or, for `sylva run`, kept until its pictures are drawn (its index is committed
/// atomically in `.sylva_pictures.json`), never an output, and a stand export's BIN scratch file of `output::gltf`, removed
/// when the export ends, aside, all named here).
#[test]
fn every_writer_goes_through_write_atomic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut stack = vec![root.clone()];
    let mut bad = Vec::new();
    let mut scanned = 0;
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().is_none_or(|x| x != "rs") {
                continue;
            }
            scanned += 1;
            let text = std::fs::read_to_string(&p).unwrap();
            // tests of the module are not writers
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            let rel = p.strip_prefix(&root).unwrap().to_string_lossy().into_owned();
            for (i, l) in code.lines().enumerate() {
                let l = l.trim();
                if l.starts_with("//") {
                    continue;
                }
                let writes = ["File::create", "fs::write(", "OpenOptions", "fs::copy(", ".save(\"", "BitMapBackend::new(", "Connection::open("].iter().any(|w| l.contains(w));
                // SQLite writes the GeoPackage into the temporary file that
                // output::finish_temporary syncs and renames (output::gpkg::csv_to_points)
                let allowed = (rel == "output/mod.rs" && (l.contains("File::create(&tmp)") || l.contains("OpenOptions::new().write(true).open(tmp)")))
                    || (rel == "job/run.rs" && l.contains("fs::write(&probe"))
                    || (rel == "output/gpkg.rs" && l.contains("Connection::open(path)"))
                    || (rel == "job/keyframes.rs" && l.contains("OpenOptions::new().read(true).write(true).create(true).truncate(true).open(&path)"))
                    // a stand export's BIN chunk spills into a scratch file beside the output
                    // (registered as pending, removed on drop); the .glb itself is written with
                    // output::write_atomic_with (output::gltf::Doc::spilling, round 38)
                    || (rel == "output/gltf.rs" && l.contains("std::fs::File::create(&path).map_err(|e| OutputError::io(&path, e))?;"));
                if writes && !allowed {
                    bad.push(format!("src/{rel}:{}: {l}", i + 1));
                }
            }
        }
    }
    assert!(scanned > 50, "{scanned} files");
    assert!(bad.is_empty(), "files written without output::write_atomic:\n{}", bad.join("\n"));
}
