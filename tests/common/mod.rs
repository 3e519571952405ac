//! Helpers shared by the sim_* tests.
#![allow(dead_code)]
use sylva::species::SpeciesLibrary;
use sylva::sim::stats::StandRow;
use sylva::sim::{fixtures, step_year, Scenario, World, YearReport};

/// Builds the world of a scenario with a uniform terrain, using the fixture species.
pub fn world(toml: &str) -> (Scenario, World) {
    world_with(toml, &fixtures::library())
}

/// Builds the world of a scenario (any terrain) with species from `lib`.
pub fn world_with(toml: &str, lib: &SpeciesLibrary) -> (Scenario, World) {
    let sc = Scenario::from_toml_str(toml, "test").unwrap();
    let site = sc.site().unwrap();
    let w = World::new(site, lib, &sc).unwrap();
    (sc, w)
}

/// The species shipped in species/.
pub fn embedded() -> SpeciesLibrary {
    SpeciesLibrary::embedded().unwrap()
}

/// Steps `n` years and returns the rows.
pub fn run(sc: &Scenario, w: &mut World, n: u32) -> Vec<StandRow> {
    (0..n)
        .map(|_| {
            let mut r = YearReport::default();
            step_year(w, sc, &mut r);
            r.row.unwrap()
        })
        .collect()
}

/// Least-squares slope of y on x.
pub fn slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// Runs `sc` into `dir`, stopped by its stop flag set after year `stop_after` (the run stops
/// after the next year and writes a checkpoint), then resumed there to its end: (the stopped
/// run's last year, the resumed run's summary).
pub fn run_stopped_and_resumed(sc: &Scenario, site: impl Fn() -> sylva::conditions::SiteConditions, lib: &SpeciesLibrary, dir: &std::path::Path, stop_after: u32) -> (u32, sylva::job::run::RunSummary) {
    use sylva::job::run::{run_scenario, RunOptions};
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let s2 = stop.clone();
    let mut cb = move |p: &sylva::job::run::Progress| {
        if p.year == stop_after {
            s2.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    };
    let mut o = RunOptions::new(dir);
    o.stop = Some(stop);
    o.progress = Some(&mut cb);
    let part = run_scenario(sc, site(), lib, o).unwrap();
    assert!(part.stopped);
    let mut o = RunOptions::new(dir);
    o.resume = true;
    (part.world.stand.year, run_scenario(sc, site(), lib, o).unwrap())
}

/// Scenario TOML for the sim tests, built from parts instead of repeating the preamble in every
/// test: top-level keys, one terrain, then the start conditions.
///
/// ```ignore
/// let toml = common::ScenarioToml::new("thinning", 120, 3).species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 1.2, 3.0).build();
/// ```
#[derive(Debug, Clone)]
pub struct ScenarioToml {
    head: Vec<String>,
    terrain: String,
    starts: Vec<String>,
}

/// Site indices `[L, T, K, F, R, N]` of the flat test sites: a fresh, base-rich, beech-suitable site.
pub const GOOD_SITE: [f32; 6] = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0];

impl ScenarioToml {
    /// `name`, `years` and `seed`; no terrain yet.
    pub fn new(name: &str, years: u32, seed: u64) -> Self {
        ScenarioToml { head: vec![format!("name = {name:?}"), format!("years = {years}"), format!("seed = {seed}")], terrain: String::new(), starts: Vec::new() }
    }
    /// Any further top-level line, e.g. `light_cell_m = 10.0` or `climate = { latitude_deg = 51.0 }`.
    pub fn line(mut self, l: &str) -> Self {
        self.head.push(l.to_string());
        self
    }
    /// The species pool.
    pub fn species(self, ids: &[&str]) -> Self {
        let list: Vec<String> = ids.iter().map(|s| format!("{s:?}")).collect();
        self.line(&format!("species = [{}]", list.join(", ")))
    }
    /// A flat uniform terrain of `width × height` cells of `cell_m` m at `elevation_m` on [`GOOD_SITE`].
    pub fn uniform(self, width: usize, height: usize, cell_m: f64, elevation_m: f64) -> Self {
        self.uniform_indices(width, height, cell_m, elevation_m, GOOD_SITE)
    }
    /// A flat uniform terrain with site indices `[L, T, K, F, R, N]`.
    pub fn uniform_indices(mut self, width: usize, height: usize, cell_m: f64, elevation_m: f64, indices: [f32; 6]) -> Self {
        self.terrain = format!("[terrain]\nuniform = {{ width = {width}, height = {height}, cell_m = {cell_m:?}, elevation_m = {elevation_m:?}, indices = {indices:?} }}\n");
        self
    }
    /// A window `[col0, row0, width, height]` of the embedded default terrain (`terrains/`).
    pub fn default_terrain(mut self, window: [usize; 4]) -> Self {
        self.terrain = format!("[terrain]\ndefault = true\nwindow = {window:?}\n");
        self
    }
    /// A planted stand over the whole terrain.
    pub fn planted(mut self, species: &str, spacing_m: f64, age_yr: f64) -> Self {
        self.starts.push(format!("[[start]]\nkind = \"planted\"\nspecies = {species:?}\nspacing_m = {spacing_m:?}\nage_yr = {age_yr:?}\n"));
        self
    }
    /// Uniform seed rain (seeds per ha and year).
    pub fn seed_rain(mut self, species: &str, seeds_per_ha: f64) -> Self {
        self.starts.push(format!("[[start]]\nkind = \"seed_rain\"\nspecies = {species:?}\nseeds_per_ha = {seeds_per_ha:?}\n"));
        self
    }
    /// Mature seed trees around points `[x, y]` (m).
    pub fn seed_sources(mut self, species: &str, points: &[[f64; 2]], trees_per_source: u32) -> Self {
        let pts: Vec<String> = points.iter().map(|p| format!("[{:?}, {:?}]", p[0], p[1])).collect();
        self.starts.push(format!("[[start]]\nkind = \"seed_sources\"\nspecies = {species:?}\npoints = [{}]\ntrees_per_source = {trees_per_source}\n", pts.join(", ")));
        self
    }
    /// The TOML text.
    pub fn build(&self) -> String {
        format!("{}\n{}{}", self.head.join("\n"), self.terrain, self.starts.join(""))
    }
}

/// Every file under `dir` (relative path → bytes): a run directory to compare byte for byte.
pub fn files(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(root: &std::path::Path, d: &std::path::Path, out: &mut std::collections::BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap());
            }
        }
    }
    let mut m = std::collections::BTreeMap::new();
    walk(dir, dir, &mut m);
    m
}

/// The snapshot folder a tiled run's part `inventory/{label}/part-RRRRR.{ext}` belongs to
/// (`inventory/{label}`, where `label` is `year_NNNN`, `year_NNNN_regeneration` or
/// `year_NNNN_gpkg`), or `None` for any other file.
fn part_folder(k: &str) -> Option<&str> {
    let (folder, name) = k.rsplit_once('/')?;
    (folder.starts_with("inventory/year_") && name.starts_with("part-")).then_some(folder)
}

/// The rows of the `inventory` layer of the GeoPackages `paths` (a file, or a tiled run's
/// parts) as text, sorted by the tree id (the first column after the feature id).
fn gpkg_rows(paths: &[std::path::PathBuf]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for p in paths {
        let db = rusqlite::Connection::open(p).unwrap();
        let mut st = db.prepare("SELECT * FROM inventory").unwrap();
        let n = st.column_count();
        let names: Vec<String> = st.column_names().map(|c| c.to_string()).collect();
        let id = names.iter().position(|c| c == "id").unwrap_or_else(|| panic!("{}: no id column in {names:?}", p.display()));
        let fid = names.iter().position(|c| c == "fid");
        let got: Vec<(i64, Vec<String>)> = st
            .query_map([], |r| {
                let v: Vec<String> = (0..n).filter(|&i| Some(i) != fid).map(|i| format!("{:?}", r.get::<_, rusqlite::types::Value>(i).unwrap())).collect();
                Ok((r.get::<_, i64>(id).unwrap(), v))
            })
            .unwrap()
            .map(|r| r.unwrap())
            .collect();
        rows.extend(got);
    }
    rows.sort_by_key(|r| r.0);
    rows.into_iter().map(|r| r.1).collect()
}

/// Asserts that run directory `other` holds the outputs of run directory `one` (files for which
/// `skip` is true left out): every file of the same name byte for byte; where `other` is a tiled
/// run's partitioned snapshot (`inventory/year_NNNN/part-RRRRR.parquet`, `_regeneration/`,
/// `_gpkg/`; issue 37 Build 4) and `one` has the single file, what the readers read back
/// (`sylva::job::inventory::read`, `read_regeneration`) is the same, and the GeoPackage parts'
/// rows are the file's (sorted by tree id; the feature ids differ). Every file of either side
/// is accounted for.
pub fn assert_same_outputs(one: &std::path::Path, other: &std::path::Path, what: &str, skip: impl Fn(&str) -> bool) {
    let (fa, fb) = (files(one), files(other));
    let (fa, fb): (std::collections::BTreeMap<_, _>, std::collections::BTreeMap<_, _>) = (fa.into_iter().filter(|(k, _)| !skip(k)).collect(), fb.into_iter().filter(|(k, _)| !skip(k)).collect());
    // byte for byte where both have the file
    for (k, v) in &fa {
        if let Some(w) = fb.get(k) {
            assert!(v == w, "{what}: {k} differs");
        }
    }
    // the folders of parts on either side, each against the other side's single file
    let folders = |f: &std::collections::BTreeMap<String, Vec<u8>>| -> std::collections::BTreeSet<String> { f.keys().filter_map(|k| part_folder(k)).map(str::to_string).collect() };
    let (pa, pb) = (folders(&fa), folders(&fb));
    for (side, parts, whole) in [("one", &pa, &fb), ("other", &pb, &fa)] {
        for folder in parts {
            let (dir, tdir) = if side == "one" { (one, other) } else { (other, one) };
            let label = folder.strip_prefix("inventory/").unwrap();
            let single: Vec<&String> = whole.keys().filter(|k| k.strip_prefix("inventory/").and_then(|n| n.rsplit_once('.')).is_some_and(|(stem, ext)| stem == label && (ext == "parquet" || ext == "csv"))).collect();
            if let Some(year) = label.strip_suffix("_regeneration") {
                let y: u32 = year.strip_prefix("year_").unwrap().parse().unwrap();
                assert_eq!(single.len(), 1, "{what}: {folder} ({side}) against {single:?}");
                let (a, b) = (sylva::job::inventory::read_regeneration(dir, y).unwrap(), sylva::job::inventory::read_regeneration(tdir, y).unwrap());
                assert!(a.is_some() && a == b, "{what}: the regeneration layer of year {y} reads back differently");
            } else if let Some(stem) = label.strip_suffix("_gpkg") {
                let file = format!("inventory/{stem}.gpkg");
                assert!(whole.contains_key(&file), "{what}: {folder} ({side}) without {file} on the other side");
                let mut ps: Vec<std::path::PathBuf> = std::fs::read_dir(dir.join(folder)).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "gpkg")).collect();
                ps.sort();
                let (a, b) = (gpkg_rows(&ps), gpkg_rows(&[tdir.join(&file)]));
                assert!(!b.is_empty() || a.is_empty(), "{what}: {file}");
                assert!(a == b, "{what}: the GeoPackage parts {folder} and {file} hold different rows");
            } else {
                assert_eq!(single.len(), 1, "{what}: {folder} ({side}) against {single:?}");
                let (a, b) = (sylva::job::inventory::read(&dir.join(folder)).unwrap(), sylva::job::inventory::read(&tdir.join(single[0])).unwrap());
                assert!(a == b, "{what}: {folder} and {} read back differently ({} and {} rows)", single[0], a.len(), b.len());
            }
        }
    }
    // no file on one side only but for those accounted for by the folders of parts
    let stem_of = |k: &str| k.strip_prefix("inventory/").and_then(|n| n.rsplit_once('.')).map(|(s, _)| format!("inventory/{s}"));
    for (side, f, other_folders, other_files) in [("one", &fa, &pb, &fb), ("other", &fb, &pa, &fa)] {
        for k in f.keys() {
            if other_files.contains_key(k) {
                continue;
            }
            let covered = match part_folder(k) {
                Some(folder) => {
                    let label = folder.strip_prefix("inventory/").unwrap();
                    other_files.keys().any(|o| stem_of(o).as_deref() == Some(folder) || (label.ends_with("_gpkg") && o == &format!("inventory/{}.gpkg", label.trim_end_matches("_gpkg"))))
                }
                None => stem_of(k).is_some_and(|s| other_folders.contains(&s) || (k.ends_with(".gpkg") && other_folders.contains(&format!("{s}_gpkg")))),
            };
            assert!(covered, "{what}: {k} only in {side}");
        }
    }
}

/// Asserts that the tiled run directory `tiled` (per-rank checkpoints, partitioned inventories)
/// holds the outputs of the one-process run directory `one` (`checkpoint.bin`): every other
/// file as [`assert_same_outputs`] (byte for byte, or read back the same where the tiled run
/// wrote one part per rank), and the per-rank checkpoints, assembled into a copy of `template`
/// (the scenario's world at its start), encode to `checkpoint.bin`'s bytes. Returns the
/// manifest.
pub fn assert_same_run(one: &std::path::Path, tiled: &std::path::Path, template: &World, what: &str) -> sylva::job::checkpoint::Manifest {
    let is_ck = |k: &str| k == "checkpoint.bin" || k.starts_with("checkpoint/");
    assert_same_outputs(one, tiled, what, is_ck);
    let (fa, fb) = (files(one), files(tiled));
    assert!(fa.contains_key("checkpoint.bin"), "{what}: one process wrote no checkpoint.bin");
    assert!(!fb.contains_key("checkpoint.bin"), "{what}: the tiled run wrote checkpoint.bin");
    let m = sylva::job::checkpoint::read_manifest(tiled).unwrap();
    let ck: Vec<&String> = fb.keys().filter(|k| k.starts_with("checkpoint/") && k.ends_with(".bin")).collect();
    let named: Vec<String> = m.files.iter().map(|f| format!("checkpoint/{f}")).collect();
    assert_eq!(ck, named.iter().collect::<Vec<_>>(), "{what}: per-rank files other than the manifest's");
    let mut w = template.clone();
    let rows = sylva::job::checkpoint::load_any(tiled, &mut w).unwrap();
    assert!(sylva::sim::checkpoint::to_bytes(&w, &rows) == fa["checkpoint.bin"], "{what}: the per-rank checkpoints assembled differ from checkpoint.bin");
    m
}

/// Even-odd point-in-polygon (a second implementation, for the tests: the simulator's is
/// `sim::management::Region::contains`).
pub fn in_poly(p: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut c = false;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        if (a[1] > y) != (b[1] > y) && x < a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) {
            c = !c;
        }
    }
    c
}

/// The shipped `scenarios/thinning_beech.toml` shortened to `years` years (its thinnings from
/// below over the whole 1 ha site are due in years 17, 22, 27, 32, …; since issue 35 round 44,
/// beech's slender thicket planted at 1.0 m, the first three find the stand below its target
/// and the first cut is in year 32), with snapshots and checkpoints every 16 years (year 32's
/// inventory holds that year's thinned trees; every 11 years, year 22, before round 44), as TOML.
pub fn short_thinning_toml(years: u32) -> String {
    let text = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/thinning_beech.toml")).unwrap();
    assert!(text.contains("\nyears = 137\n") && text.contains("snapshot_every = 0") && text.contains("checkpoint_every = 0"));
    text.replace("\nyears = 137\n", &format!("\nyears = {years}\n")).replace("snapshot_every = 0", "snapshot_every = 16").replace("checkpoint_every = 0", "checkpoint_every = 16")
}

/// A species' self-thinning line, `ln N = ln SDI_max + b · ln(Dq / 25 cm)` (stems/ha ≥ 7 cm,
/// Dq cm), read from its species file's `life.density` (`sdi_max` stems/ha at Dq 25 cm and the
/// slope `reineke_slope`; each with its source in species/*.toml: SDI_max from Vospernik &
/// Sterba 2015's Austrian NFI line × 0.82, the slope from Pretzsch & Biber 2005, Forest Science
/// 51(4):304–320). The reference for UNMANAGED stands (issue 35 rounds 35–36): an unthinned
/// even-aged stand in self-thinning lies on its line; yield tables are of thinned stands.
pub struct Line {
    pub species: String,
    pub sdi_max: f64,
    pub slope: f64,
}

/// RD band of stems ≥ 7 cm on the species' line for an unmanaged planting (1.5 m, 4,444
/// stems/ha) at ages 50 and later: an unthinned stand in self-thinning lies on its line (RD 1);
/// 0.8 leaves room for the stems < 7 cm, which take part of the site (additive SDI) but are not
/// counted; 1.1 is the ceiling `sim_density` puts on every pure stand. The band of `sim_yield`
/// (issue 35 round 35, the lead's decision).
pub const RD_CLOSED: (f64, f64) = (0.8, 1.1);
/// RD band at age 30 (the same planting): its crowns closed at 10–16 (issue 35 round 33, beech)
/// and it is in the self-thinning zone, which starts at 0.6 of the maximum (Long 1985, Forestry
/// Chronicle 61:23–27), but part of its stems are still < 7 cm and not counted.
pub const RD_30: (f64, f64) = (0.6, 1.1);

impl Line {
    /// [`RD_CLOSED`] from age 50 on, [`RD_30`] before.
    pub fn band(age: f64) -> (f64, f64) {
        if age >= 50.0 {
            RD_CLOSED
        } else {
            RD_30
        }
    }

    /// The line of species `id` of `lib`; panics naming the id when the library has none.
    pub fn of(lib: &SpeciesLibrary, id: &str) -> Line {
        let sp = lib.species.iter().find(|s| s.id == id).unwrap_or_else(|| panic!("no species {id}"));
        Line { species: id.into(), sdi_max: sp.life.density.sdi_max as f64, slope: sp.life.density.reineke_slope as f64 }
    }

    /// Relative density RD = N (Dq / 25)^(−b) / SDI_max of `n_ha` stems/ha at `dq_cm` (1 on the line).
    pub fn rd(&self, n_ha: f64, dq_cm: f64) -> f64 {
        sylva::sim::density::sdi(n_ha, dq_cm, self.slope) / self.sdi_max
    }

    /// `Ok(RD)` when `n_ha` stems/ha at `dq_cm` lie within `band` (lo, hi) of RD on the line, or
    /// the message naming `what`, the stand, the line's N at that Dq and the band.
    pub fn check(&self, what: &str, n_ha: f64, dq_cm: f64, band: (f64, f64)) -> Result<f64, String> {
        let rd = self.rd(n_ha, dq_cm);
        if (band.0..=band.1).contains(&rd) {
            Ok(rd)
        } else {
            let line_n = sylva::sim::density::max_stems(self.sdi_max, self.slope, dq_cm);
            Err(format!("{what}: N {n_ha:.0} stems/ha at Dq {dq_cm:.1} cm is RD {rd:.2} on {}'s line (SDI_max {:.0}, slope {:.3}; the line holds {line_n:.0}); want {:.2}–{:.2}", self.species, self.sdi_max, self.slope, band.0, band.1))
        }
    }

    /// Like [`Line::check`], and asserts that the check can fail: `band` is narrower than a
    /// factor of 2 (hi < 2 lo), and the same stand with twice or half its stems fails it (the
    /// mutation a wrong stem count, ×2, must not survive) when the stand itself passes. Returns the
    /// stand's own result.
    pub fn check_and_mutants(&self, what: &str, n_ha: f64, dq_cm: f64, band: (f64, f64)) -> Result<f64, String> {
        assert!(band.1 < 2.0 * band.0, "{what}: band {band:?} is a factor of 2 or more wide: a ×2 error in N could pass");
        let own = self.check(what, n_ha, dq_cm, band);
        if own.is_ok() {
            for k in [2.0, 0.5] {
                let off = self.check(what, k * n_ha, dq_cm, band);
                assert!(off.is_err(), "{what}: {k} × N passes as RD {:.2}", off.unwrap());
            }
        }
        own
    }
}

/// The codes of a categorical palette GeoTIFF (Byte, PhotometricInterpretation 3, as Sylva
/// writes the species maps): `(width, height, codes)`. The `tiff` decoder decodes no palette
/// image, so a copy whose PhotometricInterpretation entry says 1 (grey, an inline SHORT of the
/// little-endian first IFD) is decoded instead; panics on anything else.
pub fn palette_geotiff_codes(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    assert_eq!(&bytes[..4], b"II*\0", "a little-endian classic TIFF");
    let mut b = bytes.to_vec();
    let ifd = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(b[ifd..ifd + 2].try_into().unwrap()) as usize;
    let entry = (0..n).map(|k| ifd + 2 + 12 * k).find(|&e| u16::from_le_bytes(b[e..e + 2].try_into().unwrap()) == 262).expect("a PhotometricInterpretation entry");
    assert_eq!(u16::from_le_bytes(b[entry + 8..entry + 10].try_into().unwrap()), 3, "a palette image");
    b[entry + 8..entry + 10].copy_from_slice(&1u16.to_le_bytes());
    let mut d = tiff::decoder::Decoder::new(std::io::Cursor::new(b)).unwrap();
    let (w, h) = d.dimensions().unwrap();
    match d.read_image().unwrap() {
        tiff::decoder::DecodingResult::U8(v) => (w, h, v),
        _ => panic!("not a Byte raster"),
    }
}
