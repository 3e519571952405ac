//! Fuzzing harness shared by `tests/fuzz.rs` (a bounded run in the suite) and
//! `examples/fuzz.rs` (longer runs): seeded mutation of real input files and structure-aware
//! generation, on the stable toolchain.
//!
//! Every execution feeds one input to one reader and classifies the outcome: `Ok`, a named
//! error (its message names the input's file), or a defect: a panic (caught with
//! `catch_unwind`), an error that does not name the file, or an allocation larger than
//! [`ALLOC_LIMIT`] (tracked by [`CountingAlloc`], which the binary installs as its global
//! allocator). Inputs come from [`sylva::rng::Stream`], so a run is reproducible from its seed.
#![allow(dead_code)]

use arbitrary::{Arbitrary, Unstructured};
use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use sylva::rng::Stream;

/// Largest single allocation any reader may make (bytes): the DEM readers' grid limit
/// ([`sylva::terrain::io::MAX_CELLS`] cells) at 8 bytes a sample, 2 GiB.
pub const ALLOC_LIMIT: usize = (sylva::terrain::io::MAX_CELLS as usize) * 8;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

/// A global allocator that records the largest single request (it allocates as [`System`]).
pub struct CountingAlloc;

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        LARGEST.fetch_max(l.size(), Ordering::Relaxed);
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        LARGEST.fetch_max(n, Ordering::Relaxed);
        unsafe { System.realloc(p, l, n) }
    }
}

/// The fuzz targets: one reader each.
pub const TARGETS: [&str; 7] = ["scenario", "species", "geotiff", "asc", "png", "checkpoint", "skeleton"];

/// Name of the input file in messages; every error must name it.
fn input_name(target: &str) -> &'static str {
    match target {
        "scenario" => "fuzz/input_scenario.toml",
        "species" => "fuzz/input_species.toml",
        "geotiff" => "fuzz/input.tif",
        "asc" => "fuzz/input.asc",
        "png" => "fuzz/input.png",
        "checkpoint" => "fuzz/checkpoint.bin",
        _ => "fuzz/input.skeleton.json",
    }
}

/// Outcome of one execution.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The reader accepted the input.
    Ok,
    /// The reader refused it with a message naming the file.
    Named,
    /// A defect: panic, anonymous error, allocation over the limit (with the message).
    Defect(String),
}

/// Counts of one target's run.
#[derive(Debug, Default, Clone)]
pub struct Report {
    pub target: String,
    pub executions: u64,
    pub ok: u64,
    pub named: u64,
    /// Defects with the input that caused each (first 5 kept).
    pub defects: Vec<(String, Vec<u8>)>,
    pub defect_count: u64,
    pub seeds: usize,
    /// Largest single allocation seen during the run (bytes).
    pub largest_alloc: usize,
    /// Slowest execution (seconds): a hang shows here (the suite also has a watchdog).
    pub slowest_s: f64,
}

fn data(rel: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// A small world for the checkpoint target, and a real checkpoint of it after 3 years.
struct CkFixture {
    scenario: sylva::sim::Scenario,
    world: sylva::sim::World,
    bytes: Vec<u8>,
}

fn ck_fixture() -> &'static CkFixture {
    static F: OnceLock<CkFixture> = OnceLock::new();
    F.get_or_init(|| {
        let toml = "name = \"fuzz\"\nyears = 6\nseed = 5\nspecies = [\"beech\", \"birch\"]\n[terrain]\nuniform = { width = 4, height = 4, cell_m = 20.0, elevation_m = 200.0, indices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0] }\n[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 4.0\nage_yr = 10.0\n[[start]]\nkind = \"seed_rain\"\nspecies = \"birch\"\nseeds_per_ha = 2000.0\n";
        let scenario = sylva::sim::Scenario::from_toml_str(toml, "fuzz").expect("fixture scenario");
        let lib = sylva::sim::fixtures::library();
        let world = sylva::sim::World::new(scenario.site().expect("site"), &lib, &scenario).expect("world");
        let mut w = world.clone();
        let mut rows = Vec::new();
        for _ in 0..3 {
            let mut r = sylva::sim::YearReport::default();
            sylva::sim::step_year(&mut w, &scenario, &mut r);
            rows.extend(r.row);
        }
        let bytes = sylva::sim::checkpoint::to_bytes(&w, &rows);
        CkFixture { scenario, world, bytes }
    })
}

/// Real files a target's mutations start from.
pub fn seeds(target: &str) -> Vec<Vec<u8>> {
    let gis = |names: &[&str]| names.iter().map(|n| data(&format!("tests/data/gis/{n}"))).collect::<Vec<_>>();
    match target {
        "scenario" => vec![data("scenarios/default.toml"), data("tests/data/fuzz/scenario_uniform.toml")],
        "species" => ["beech", "norway_spruce", "silver_birch", "scots_pine"].iter().map(|s| data(&format!("species/{s}.toml"))).collect(),
        "geotiff" => gis(&[
            "int16_deflate_striped.tif",
            "uint16_lzw_tiled.tif",
            "float32_zstd.tif",
            "float32_pixelispoint.tif",
            "int32_packbits.tif",
            "float32_deflate_pred3.tif",
            "float64_lzw_pred3_tiled.tif",
            "float32_bigtiff.tif",
            "float32_southup.tif",
            "coweeta_nad83_utm17n.tif",
        ]),
        "asc" => gis(&["grid.asc", "grid_wrapped_center.asc", "coweeta_esri.asc"]),
        // the 8-bit heightmap is no seed since 8-bit PNGs are refused (round 33's trial)
        "png" => vec![data("tests/data/fuzz/heightmap16.png")],
        "checkpoint" => vec![ck_fixture().bytes.clone()],
        _ => vec![data("tests/data/fuzz/tree.skeleton.json")],
    }
}

/// Runs one input through the target's reader (inside `catch_unwind` by the caller).
/// `Ok(true)` = accepted, `Ok(false)` = refused with a message naming the file, `Err` = an
/// error that does not name it.
fn exec(target: &str, input: &[u8]) -> Result<bool, String> {
    let name = input_name(target);
    let path = Path::new(name);
    let named = |msg: String| if msg.contains(name) { Ok(false) } else { Err(format!("error does not name {name}: {msg}")) };
    match target {
        "scenario" => {
            let Ok(text) = std::str::from_utf8(input) else { return Ok(false) }; // Scenario::load: read_to_string names the file
            match sylva::sim::Scenario::from_toml_str(text, name) {
                Ok(sc) => {
                    // build the site only for small generated terrains (a DEM path is not fuzzed here)
                    let spec = sc.terrain_spec();
                    let small = match &spec {
                        sylva::sim::scenario::TerrainSpec::Uniform(u) => u.width.saturating_mul(u.height) <= 4096,
                        sylva::sim::scenario::TerrainSpec::Generate(g) => g.size <= 64,
                        _ => false,
                    };
                    if small {
                        if let Err(e) = sc.site() {
                            return named(e.to_string());
                        }
                    }
                    Ok(true)
                }
                Err(e) => named(e.to_string()),
            }
        }
        "species" => {
            let (sp, problems) = sylva::species::parse_bytes(input, path);
            if problems.is_empty() && sp.is_some() {
                Ok(true)
            } else if problems.iter().all(|p| p.to_string().contains(name)) && !problems.is_empty() {
                Ok(false)
            } else {
                Err(format!("species problems do not name the file: {problems:?}"))
            }
        }
        "geotiff" => match sylva::terrain::io::read_geotiff(std::io::Cursor::new(input), path) {
            Ok(_) => Ok(true),
            Err(e) => named(e.to_string()),
        },
        "asc" => {
            let Ok(text) = std::str::from_utf8(input) else { return Ok(false) };
            match sylva::terrain::io::read_asc(text, None, path) {
                Ok(_) => Ok(true),
                Err(e) => named(e.to_string()),
            }
        }
        "png" => match sylva::terrain::io::read_png_heightmap(std::io::Cursor::new(input), path, 2.0, 100.0, 900.0) {
            Ok(_) => Ok(true),
            Err(e) => named(e.to_string()),
        },
        "checkpoint" => {
            // the bytes as mutated (the length field and the CRC-32 refuse nearly all of them),
            // then resealed so that the body's own checks are reached too
            let f = ck_fixture();
            let mut sealed = input.to_vec();
            sylva::sim::checkpoint::reseal(&mut sealed);
            let mut accepted = false;
            for b in [input, &sealed[..]] {
                let mut w = f.world.clone();
                match sylva::sim::checkpoint::restore(&mut w, b, path) {
                    Ok(_) => {
                        // a restored world must step on without panicking
                        let mut r = sylva::sim::YearReport::default();
                        sylva::sim::step_year(&mut w, &f.scenario, &mut r);
                        accepted = true;
                    }
                    Err(e) => {
                        named(e.to_string())?;
                    }
                }
            }
            Ok(accepted)
        }
        _ => {
            let Ok(text) = std::str::from_utf8(input) else { return Ok(false) };
            match sylva::output::gltf::parse_skeleton_sidecar(text, path) {
                Ok(sk) => {
                    // what `sylva tree adapt` does next: analyse it for Plastic Trees
                    if sk.nodes.len() <= 5000 {
                        let sp = sylva::species::SpeciesLibrary::embedded().map_err(|e| e.to_string())?;
                        let beech = sp.get("beech").ok_or("no beech")?;
                        if let Err(e) = sylva::structure::plastic::PlasticTree::analyse(&sk, &beech.architecture.plastic, &sylva::structure::plastic::Environment::open(), None) {
                            let _ = e.to_string(); // the analysis names the skeleton, not the file
                        }
                    }
                    Ok(true)
                }
                Err(e) => named(e.to_string()),
            }
        }
    }
}

/// Values that break parsers: extremes, NaN, infinities, negatives, huge counts.
const EXTREME_TEXT: [&str; 16] = ["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "4294967296", "18446744073709551615", "9223372036854775807", "-9223372036854775808", "1e-320", "\"\"", "[]", "{}", "99999999"];
const EXTREME_U32: [u32; 10] = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 0xffff, 0x1_0000, 65535 * 65535, 0x7fc0_0000 /* NaN */, 0x7f80_0000 /* inf */];

/// Structure-aware value for TOML documents (driven by `arbitrary`).
#[derive(Debug, Arbitrary)]
enum GenValue {
    Int(i64),
    Float(f64),
    Extreme(u8),
    Bool(bool),
    Str(String),
    Arr(Vec<i16>),
    Table,
}

impl GenValue {
    fn to_toml(&self) -> toml::Value {
        match self {
            GenValue::Int(i) => toml::Value::Integer(*i),
            GenValue::Float(f) => toml::Value::Float(*f),
            GenValue::Extreme(k) => toml::Value::Float([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 1e308, -1e-308, f64::MIN_POSITIVE][*k as usize % 7]),
            GenValue::Bool(b) => toml::Value::Boolean(*b),
            GenValue::Str(s) => toml::Value::String(s.clone()),
            GenValue::Arr(a) => toml::Value::Array(a.iter().map(|&x| toml::Value::Integer(x as i64)).collect()),
            GenValue::Table => toml::Value::Table(Default::default()),
        }
    }
}

/// Paths (as key lists) of every value in a TOML table.
fn value_paths(t: &toml::Table, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    for (k, v) in t {
        prefix.push(k.clone());
        out.push(prefix.clone());
        match v {
            toml::Value::Table(s) => value_paths(s, prefix, out),
            toml::Value::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    if let toml::Value::Table(s) = e {
                        prefix.push(format!("#{i}"));
                        value_paths(s, prefix, out);
                        prefix.pop();
                    }
                }
            }
            _ => {}
        }
        prefix.pop();
    }
}

fn value_at<'a>(t: &'a mut toml::Table, path: &[String]) -> Option<&'a mut toml::Value> {
    let (first, rest) = path.split_first()?;
    let mut v = t.get_mut(first)?;
    for k in rest {
        v = match (v, k.strip_prefix('#')) {
            (toml::Value::Array(a), Some(i)) => a.get_mut(i.parse::<usize>().ok()?)?,
            (toml::Value::Table(s), None) => s.get_mut(k)?,
            _ => return None,
        };
    }
    Some(v)
}

/// Structure-aware TOML mutation: parse the seed, replace / delete / add values chosen by
/// `arbitrary` from random bytes, and write the document back.
fn toml_generate(seed: &[u8], rng: &mut Stream) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(seed).ok()?;
    let mut t: toml::Table = toml::from_str(text).ok()?;
    let raw: Vec<u8> = (0..64).map(|_| rng.next_u64() as u8).collect();
    let mut u = Unstructured::new(&raw);
    let n = 1 + rng.below(3) as usize;
    for _ in 0..n {
        let mut paths = Vec::new();
        value_paths(&t, &mut Vec::new(), &mut paths);
        if paths.is_empty() {
            break;
        }
        let p = paths[rng.below(paths.len() as u64) as usize].clone();
        let g = GenValue::arbitrary(&mut u).ok()?;
        match rng.below(4) {
            0 => {
                // delete the value
                let (last, parent) = p.split_last()?;
                if parent.is_empty() {
                    t.remove(last);
                } else if let Some(toml::Value::Table(s)) = value_at(&mut t, parent) {
                    s.remove(last);
                }
            }
            1 => {
                // an unknown key beside it
                let (_, parent) = p.split_last()?;
                let key = format!("k{}", rng.below(100));
                if parent.is_empty() {
                    t.insert(key, g.to_toml());
                } else if let Some(toml::Value::Table(s)) = value_at(&mut t, parent) {
                    s.insert(key, g.to_toml());
                }
            }
            _ => {
                if let Some(v) = value_at(&mut t, &p) {
                    *v = g.to_toml();
                }
            }
        }
    }
    toml::to_string(&t).ok().map(String::into_bytes)
}

/// TIFF-aware mutation: overwrite one field (tag, type, count or value) of one entry of the
/// first IFD with an extreme value (classic TIFF; BigTIFF falls back to byte mutation).
fn tiff_tag_mutation(b: &mut [u8], rng: &mut Stream) -> bool {
    if b.len() < 8 || &b[..2] != b"II" || b[2] != 42 {
        return false;
    }
    let ifd = u32::from_le_bytes([b[4], b[5], b[6], b[7]]) as usize;
    let Some(n) = b.get(ifd..ifd + 2).map(|s| u16::from_le_bytes([s[0], s[1]]) as usize) else { return false };
    if n == 0 {
        return false;
    }
    let e = ifd + 2 + 12 * rng.below(n as u64) as usize;
    if e + 12 > b.len() {
        return false;
    }
    let x = EXTREME_U32[rng.below(EXTREME_U32.len() as u64) as usize];
    match rng.below(4) {
        0 => b[e..e + 2].copy_from_slice(&(x as u16).to_le_bytes()),         // tag id
        1 => b[e + 2..e + 4].copy_from_slice(&(rng.below(20) as u16).to_le_bytes()), // field type
        2 => b[e + 4..e + 8].copy_from_slice(&x.to_le_bytes()),              // count
        _ => b[e + 8..e + 12].copy_from_slice(&x.to_le_bytes()),             // value / offset
    }
    true
}

/// One mutated input from `seeds`.
pub fn mutate(target: &str, seeds: &[Vec<u8>], rng: &mut Stream) -> Vec<u8> {
    let s = &seeds[rng.below(seeds.len() as u64) as usize];
    let text_target = matches!(target, "scenario" | "species" | "asc" | "skeleton");
    if matches!(target, "scenario" | "species") && rng.below(3) == 0 {
        if let Some(g) = toml_generate(s, rng) {
            return g;
        }
    }
    let mut b = s.clone();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        if b.is_empty() {
            b.push(rng.next_u64() as u8);
        }
        let len = b.len() as u64;
        let at = rng.below(len) as usize;
        match rng.below(if text_target { 9 } else { 8 }) {
            0 => b[at] ^= 1 << rng.below(8),
            1 => b.truncate(at),
            2 => {
                // splice: a chunk of another seed (or this one) at a random place
                let o = &seeds[rng.below(seeds.len() as u64) as usize];
                let from = rng.below(o.len() as u64) as usize;
                let take = (rng.below(64) as usize).min(o.len() - from);
                b.splice(at..at, o[from..from + take].iter().copied());
            }
            3 => {
                let x = EXTREME_U32[rng.below(EXTREME_U32.len() as u64) as usize].to_le_bytes();
                let end = (at + 4).min(b.len());
                b[at..end].copy_from_slice(&x[..end - at]);
            }
            4 => {
                let end = (at + 1 + rng.below(32) as usize).min(b.len());
                b.drain(at..end);
            }
            5 => b[at] = [0u8, 0xff, 0x7f, 0x80, b'\n', b'"', b'[', b'-'][rng.below(8) as usize],
            6 => {
                if target == "geotiff" && tiff_tag_mutation(&mut b, rng) {
                    continue;
                }
                let end = (at + 1 + rng.below(16) as usize).min(b.len());
                let chunk = b[at..end].to_vec();
                b.splice(at..at, chunk);
            }
            7 if !text_target => {
                // an aligned 8-byte field (u64 length, f64) set to an extreme
                let at8 = at & !7;
                let x = [u64::MAX, 1 << 40, 0, f64::NAN.to_bits(), f64::INFINITY.to_bits(), (-1.0f64).to_bits(), u32::MAX as u64][rng.below(7) as usize];
                let end = (at8 + 8).min(b.len());
                b[at8..end].copy_from_slice(&x.to_le_bytes()[..end - at8]);
            }
            _ => {
                // replace a number in the text with an extreme token
                let text = String::from_utf8_lossy(&b).into_owned();
                let starts: Vec<usize> = text.char_indices().filter(|(i, c)| c.is_ascii_digit() && (*i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric())).map(|(i, _)| i).collect();
                if let Some(&st) = starts.get(rng.below(starts.len().max(1) as u64) as usize) {
                    let en = text[st..].find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+')).map_or(text.len(), |e| st + e);
                    let tok = EXTREME_TEXT[rng.below(EXTREME_TEXT.len() as u64) as usize];
                    b = format!("{}{}{}", &text[..st], tok, &text[en..]).into_bytes();
                }
            }
        }
    }
    b
}

/// Inputs generated from scratch for a target (structure-aware, beyond the seeds' mutations):
/// TIFFs written by the `tiff` encoder with arbitrary sizes and sample types, then mutated.
fn generated(target: &str, rng: &mut Stream) -> Option<Vec<u8>> {
    if target != "geotiff" {
        return None;
    }
    use tiff::encoder::{colortype, TiffEncoder};
    let (w, h) = (1 + rng.below(40) as u32, 1 + rng.below(40) as u32);
    let mut out = std::io::Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut out).ok()?;
    let n = (w * h) as usize;
    match rng.below(4) {
        0 => enc.write_image::<colortype::Gray32Float>(w, h, &(0..n).map(|i| [f32::NAN, f32::INFINITY, 1e30, 300.0][(i + rng.below(4) as usize) % 4]).collect::<Vec<_>>()).ok()?,
        1 => enc.write_image::<colortype::Gray16>(w, h, &(0..n).map(|_| rng.next_u64() as u16).collect::<Vec<_>>()).ok()?,
        2 => enc.write_image::<colortype::RGB8>(w, h, &vec![7u8; n * 3]).ok()?,
        _ => enc.write_image::<colortype::Gray64Float>(w, h, &(0..n).map(|_| rng.range(-20000.0, 20000.0)).collect::<Vec<_>>()).ok()?,
    }
    Some(out.into_inner())
}

thread_local! {
    static IN_READER: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Silences the panic message of a reader under test (it is reported as a defect instead);
/// other panics (the tests' own assertions) print as usual, and all do with SYLVA_FUZZ_VERBOSE.
fn quiet_panics() {
    static ONCE: OnceLock<()> = OnceLock::new();
    ONCE.get_or_init(|| {
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_READER.with(|f| f.get()) || std::env::var_os("SYLVA_FUZZ_VERBOSE").is_some() {
                prev(info)
            }
        }));
    });
}

/// Runs one input and classifies it.
pub fn run_one(target: &str, input: &[u8]) -> Outcome {
    quiet_panics();
    let before = LARGEST.swap(0, Ordering::Relaxed);
    IN_READER.with(|f| f.set(true));
    let r = catch_unwind(AssertUnwindSafe(|| exec(target, input)));
    IN_READER.with(|f| f.set(false));
    let big = LARGEST.swap(before, Ordering::Relaxed);
    LARGEST.fetch_max(big, Ordering::Relaxed);
    if big > ALLOC_LIMIT {
        return Outcome::Defect(format!("allocation of {big} bytes > limit {ALLOC_LIMIT}"));
    }
    match r {
        Ok(Ok(true)) => Outcome::Ok,
        Ok(Ok(false)) => Outcome::Named,
        Ok(Err(m)) => Outcome::Defect(m),
        Err(p) => Outcome::Defect(format!("panic: {}", p.downcast_ref::<String>().cloned().or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default())),
    }
}

/// Fuzzes `target` for `execs` executions or until `deadline`, whichever comes first,
/// starting from `seed`. The seeds themselves run first.
pub fn fuzz(target: &str, seed: u64, execs: u64, deadline: Option<Duration>) -> Report {
    let t0 = Instant::now();
    let seeds = seeds(target);
    let mut rng = Stream::from_keys(&[seed, 0xF022]);
    let mut rep = Report { target: target.into(), seeds: seeds.len(), ..Default::default() };
    LARGEST.store(0, Ordering::Relaxed);
    let mut i = 0u64;
    while i < execs && deadline.is_none_or(|d| t0.elapsed() < d) {
        let input = if (i as usize) < seeds.len() {
            seeds[i as usize].clone()
        } else if let Some(g) = (rng.below(4) == 0).then(|| generated(target, &mut rng)).flatten() {
            if rng.below(2) == 0 { mutate(target, &[g], &mut rng) } else { g }
        } else {
            mutate(target, &seeds, &mut rng)
        };
        let ts = Instant::now();
        let o = run_one(target, &input);
        rep.slowest_s = rep.slowest_s.max(ts.elapsed().as_secs_f64());
        rep.executions += 1;
        match o {
            Outcome::Ok => rep.ok += 1,
            Outcome::Named => rep.named += 1,
            Outcome::Defect(m) => {
                rep.defect_count += 1;
                if rep.defects.len() < 5 {
                    rep.defects.push((m, input));
                }
            }
        }
        i += 1;
    }
    rep.largest_alloc = LARGEST.load(Ordering::Relaxed);
    rep
}
