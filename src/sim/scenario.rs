//! Scenario files (TOML): terrain, climate, species pool, start, duration, seed and outputs.
//!
//! Every field is validated after parsing; errors name the file, the field, the offending value
//! and what was expected ([`crate::Error::Invalid`]).

use crate::conditions::Climate;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A simulation scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name of the scenario (free text, used in outputs).
    pub name: String,
    /// Where the terrain comes from.
    pub terrain: TerrainSection,
    /// Climate and soil constants (all fields default, see [`Climate`]).
    #[serde(default)]
    pub climate: Climate,
    /// Species ids of the pool (from the library); empty = all species of the library.
    #[serde(default)]
    pub species: Vec<String>,
    /// How the simulation starts (seed sources, seed rain, planted stands).
    #[serde(default)]
    pub start: Vec<Start>,
    /// Number of years to simulate (1–10 000).
    pub years: u32,
    /// Random seed.
    #[serde(default)]
    pub seed: u64,
    /// Write a snapshot (species and basal-area maps, the main job's key frame) every N years
    /// (0 = only the first and last year); tree inventories follow `inventory_every`.
    #[serde(default = "default_snapshot_every")]
    pub snapshot_every: u32,
    /// Write the tree inventories and regeneration tables every N years, at snapshots
    /// (absent: every snapshot, `snapshot_every`; 0 = only the first and last year); a
    /// multiple of `snapshot_every`. Year 0, the last year, every year whose management
    /// removed trees and a year stopped at get one whatever this is ([`Scenario::inventory_year`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inventory_every: Option<u32>,
    /// Years at which `sylva run` draws its stills from afar (`stills/year_NNNN_{oblique,topdown}.png`),
    /// each 0 to `years`, ascending, each once (`sylva run --still-years` overrides it); the
    /// run's last year is drawn too, with the close-up. Every still year is a snapshot year
    /// ([`Scenario::snapshot_year`]: its maps and the film's key frame are written). Absent: the
    /// years 0, 10, 25, 50, 100 and 150 that are snapshot years of the run
    /// (`crate::job::main_job::STILL_YEARS`). Round 41 (trial 40: a 60-year design got stills
    /// at 0, 10, 50 and 60, not the 20 and 40 it had inventories for).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub still_years: Option<Vec<u32>>,
    /// Also write snapshots after spring, summer and autumn of snapshot years.
    #[serde(default)]
    pub seasonal_snapshots: bool,
    /// Write a checkpoint every N years (0 = only at the end).
    #[serde(default = "default_checkpoint_every")]
    pub checkpoint_every: u32,
    /// Light grid cell size (m), 2–20; default 5.
    #[serde(default = "default_light_cell")]
    pub light_cell_m: f64,
    /// `[light]`: how the light phase takes its diffuse part (omitted: as rounds 1–43).
    #[serde(default, skip_serializing_if = "LightSection::is_default")]
    pub light: LightSection,
    /// Obstacles (`[[obstacle]]` entries: box, wall, sphere, footprint; see
    /// [`super::obstacle`]).
    #[serde(default, rename = "obstacle", skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<super::obstacle::ObstacleSpec>,
    /// Management (`[[management]]` entries: thinnings, harvests, plantings; see
    /// [`super::management`]); none by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub management: Vec<super::management::Management>,
    /// Where the scenario was read from (the file path given to [`Scenario::load`] or the
    /// `name` given to [`Scenario::from_toml_str`]); not part of the TOML, used in messages.
    #[serde(skip)]
    pub source: String,
}

fn default_snapshot_every() -> u32 {
    10
}
fn default_checkpoint_every() -> u32 {
    10
}
fn default_light_cell() -> f64 {
    5.0
}

/// `[light]`: the light phase's options (`sim::phases::light`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSection {
    /// `diffuse = "column"` (default: the diffuse part from the leaf area straight above the
    /// light cell) or `"sky"` (from the sky hemisphere under the standard overcast sky, each
    /// sector's ray through the neighbouring cells' canopy: Canham 1988's gap light index;
    /// docs/model.md "Light"). Any other value is refused naming `[light] diffuse`.
    #[serde(default)]
    pub diffuse: super::light_grid::Diffuse,
}

impl LightSection {
    /// True for the default (`diffuse = "column"`), which a written scenario leaves out.
    pub fn is_default(&self) -> bool {
        *self == LightSection::default()
    }
}

/// `[terrain]`: exactly one source, plus an optional window.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSection {
    /// Use the embedded default terrain (`terrains/`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default: Option<bool>,
    /// A terrain embedded in the binary by name (`"jacksboro"`, `"coweeta"`:
    /// [`crate::terrain::io::EMBEDDED_TERRAINS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub embedded: Option<String>,
    /// A DEM file (GeoTIFF, ESRI ASCII, PNG), relative to the scenario file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// A generated terrain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GenerateSpec>,
    /// A flat uniform site.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uniform: Option<UniformSpec>,
    /// Sub-window `[col0, row0, width, height]` in cells of the terrain grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<[usize; 4]>,
    /// PNG heightmaps only (they carry no georeferencing): cell size (m, > 0–1000), required with
    /// one (since round 40: until then 10 m was taken with a warning).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_m: Option<f64>,
    /// PNG heightmaps only: heights (m) of the smallest and largest pixel value (0 and 65535),
    /// required with one (since round 40: until then 0–1000 m was taken with a warning).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_range_m: Option<[f64; 2]>,
}

pub use super::management::MAX_PLANTED_TREES;

/// A generated (fractal noise) terrain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerateSpec {
    /// Cells per side.
    pub size: usize,
    /// Cell size (m).
    pub cell_m: f64,
    /// Relief (m).
    pub relief_m: f32,
    /// Generator seed.
    pub seed: u64,
}

/// A flat uniform site (for stand-level runs and tests).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UniformSpec {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell size (m).
    pub cell_m: f64,
    /// Elevation (m).
    #[serde(default)]
    pub elevation_m: f32,
    /// Ellenberg-style indices `[L, T, K, F, R, N]`.
    pub indices: [f32; 6],
}

/// The terrain source resolved from `[terrain]`; the caller (CLI) loads it.
#[derive(Debug, Clone, PartialEq)]
pub enum TerrainSpec {
    /// The embedded default terrain.
    Default,
    /// A terrain embedded in the binary, by name ([`crate::terrain::io::embedded_terrain`]).
    Embedded(String),
    /// A DEM file (absolute or relative to the working directory).
    Path(PathBuf),
    /// A generated terrain.
    Generate(GenerateSpec),
    /// A flat uniform site.
    Uniform(UniformSpec),
}

/// One start condition.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Start {
    /// Mature seed trees clustered (within 10 m) around points.
    SeedSources {
        /// World points `[x, y]` (m, origin SW corner).
        points: Vec<[f64; 2]>,
        /// Species id.
        species: String,
        /// Trees per point (1–1000).
        trees_per_source: u32,
    },
    /// Uniform external seed input every year (seeds per hectare per year).
    SeedRain {
        /// Species id.
        species: String,
        /// Seeds per hectare and year (≥ 0).
        seeds_per_ha: f64,
    },
    /// A planted stand on a square lattice.
    Planted {
        /// Species id.
        species: String,
        /// Spacing (m), 0.5–50.
        spacing_m: f64,
        /// Age at planting (years).
        #[serde(default)]
        age_yr: f32,
        /// Area `[x0, y0, x1, y1]` (m); the whole terrain when omitted.
        #[serde(default)]
        area: Option<[f64; 4]>,
    },
}

impl Start {
    /// Species id of this start.
    pub fn species(&self) -> &str {
        match self {
            Start::SeedSources { species, .. } | Start::SeedRain { species, .. } | Start::Planted { species, .. } => species,
        }
    }
}

fn invalid(ctx: &str, field: &str, value: impl ToString, expected: &str) -> Error {
    Error::Invalid { context: ctx.to_string(), field: field.to_string(), value: value.to_string(), expected: expected.to_string() }
}

/// Smallest width and height (cells) of a `[terrain] window` (round 45, trial 44: a 1 × 1
/// window ran): slope and aspect (Horn 1981, as `gdaldem`), and through them the insolation,
/// wind exposure and flow routing, read each cell's 3 × 3 neighbourhood; a window narrower than
/// 3 cells holds that neighbourhood for none of its cells (every slope would come from cells
/// replicated at its edge).
pub const MIN_WINDOW_CELLS: usize = 3;

/// Memory of a simulated site per 10 m cell (bytes) besides its seed grids: its conditions,
/// indices, suitability and the light and crowding grids at the default light cell, before any
/// tree. Round 46 (after round 45's fine seed grids): a uniform site of N × N 10 m cells one
/// year, peak RSS with two species 233 MB (N = 1,000) and 671 MB (N = 2,000), with the
/// default's eight 396 MB and 1,181 MB (`sylva simulate`, BENCHMARKS.md round 46): 150 and 268
/// bytes a cell, 110 besides [`SEED_BYTES_PER_CELL_SPECIES`] per species (round 26: 149 with
/// two species on the coarse seed grids).
pub const SITE_BYTES_PER_CELL: u64 = 110;

/// Memory per 10 m cell and pool species (bytes) of its seed grid of fine cells of at most
/// [`crate::sim::world::FINE_SEED_CELL_M`] (5 m: 4 `f32` a 10 m cell, 16 bytes, and the
/// reproduction's spreading): 20, the slope of the measurements of [`SITE_BYTES_PER_CELL`]
/// between two and eight species ((268 − 150) / 6). It grows with the cell's area (a 20 m cell
/// holds 16 fine cells).
pub const SEED_BYTES_PER_CELL_SPECIES: u64 = 20;

/// Memory of a run besides its site (bytes): 70 MB, and [`BASE_BYTES_PER_SPECIES`] a species
/// (the measurements above: 89 MB with two species, 137 MB with eight, less their cells).
pub const BASE_BYTES: u64 = 70_000_000;

/// Memory of a run besides its site per pool species (bytes): 8 MB (see [`BASE_BYTES`]).
pub const BASE_BYTES_PER_SPECIES: u64 = 8_000_000;

/// Whether `id` is the id of a species of the embedded library (`species/*.toml`, the file stem);
/// a hint for telling which of two near names is misspelt, before any library is loaded.
fn is_embedded_id(id: &str) -> bool {
    crate::species::EMBEDDED_FILES.iter().any(|(f, _)| f.strip_suffix(".toml") == Some(id))
}

impl Scenario {
    /// The `[[management]]` entries that can never act in this run: those whose first year
    /// ([`super::management::Management::first_year`]) lies after the run's last year `years`
    /// (a planting at year 80 of a 60-year run plants nothing). As `(index, field, year)`,
    /// the field naming that first year (`year`, `years[0]`, `from_year`, `stages[0].year`).
    pub fn entries_never_acting(&self) -> Vec<(usize, String, u32)> {
        self.management
            .iter()
            .enumerate()
            .filter(|(_, m)| m.first_year() > self.years)
            .map(|(i, m)| {
                let (f, y) = m.first_year_field();
                (i, f, y)
            })
            .collect()
    }

    /// Refuses entries that can never act in the run ([`Scenario::entries_never_acting`]; trial
    /// 40: a planting whose only year lay past the end planted nothing and the run exited 0).
    /// `sylva run` and `sylva simulate` call it for the scenario's own `years` (or a longer
    /// `--years`); a run shortened with `--years` only warns ([`Scenario::never_acting_warnings`]).
    ///
    /// Errors: [`Error::Invalid`] naming `ctx`, `management[i].<field>` (the entry's first year),
    /// that year and the run's last year.
    pub fn refuse_entries_never_acting(&self, ctx: &str) -> Result<()> {
        if let Some((i, f, y)) = self.entries_never_acting().into_iter().next() {
            let m = &self.management[i];
            return Err(invalid(
                ctx,
                &format!("management[{i}].{f}"),
                y,
                &format!("a year within the run, at most its last year {} (`years`): this {} entry (\"{}\") would never act; extend `years`, or move or remove the entry", self.years, m.kind, m.display_name(i)),
            ));
        }
        Ok(())
    }

    /// One warning per entry that never acts in this run ([`Scenario::entries_never_acting`]),
    /// for a run that `--years` shortened on purpose: `management[i].FIELD = Y (KIND "NAME")
    /// lies after the run's last year N (--years): the entry never acts in this run`.
    pub fn never_acting_warnings(&self) -> Vec<String> {
        self.entries_never_acting()
            .into_iter()
            .map(|(i, f, y)| {
                let m = &self.management[i];
                format!("management[{i}].{f} = {y} ({} \"{}\") lies after the run's last year {} (--years): the entry never acts in this run", m.kind, m.display_name(i), self.years)
            })
            .collect()
    }

    /// Whether the scenario draws a design on its stand: a `[[management]]` planting, harvest or
    /// clearing kept open (parcels, patch cuts, clear-cuts, `keep_open`). Its pictures then do not mirror the window's trees into
    /// the surroundings beyond a DEM window ([`crate::job::scene::Landscape::mirror_trees`]),
    /// which would copy its parcels onto the neighbours' land (trial 40, a landscape architect:
    /// "about 9 planted blocks for 5 polygons"). Thinnings alone keep the mirrors.
    pub fn designs_its_stand(&self) -> bool {
        self.management.iter().any(|m| m.kind == "planting" || m.kind == "harvest" || m.kind == "keep_open")
    }
}

/// Whether `name` is the scientific or common name (or an id spelt with other case, spaces or
/// hyphens: [`crate::species::species_name_key`]) of an embedded species whose id is in `pool`.
fn names_a_pool_species(name: &str, pool: &[String]) -> bool {
    let Ok(lib) = crate::species::SpeciesLibrary::embedded() else { return false };
    lib.find(name).is_some_and(|id| pool.contains(&lib.species[id as usize].id))
}

/// What a species name outside the scenario's pool should be: a species of the library named
/// in `species = [...]` (with the id to add where `name` names one of the shipped library), or,
/// where it names none, a pointer to `sylva species list` and the library's nearest names
/// (trial 41, defect 9: "add it there" was said of `fagus`, which no library holds).
fn not_in_pool(name: &str, pool: &[String]) -> String {
    let lib = crate::species::SpeciesLibrary::embedded().ok();
    if let Some((lib, k)) = lib.as_ref().and_then(|l| l.find(name).map(|k| (l, k))) {
        let id = &lib.species[k as usize].id;
        return format!("one of the scenario's species = {pool:?} (add \"{id}\" there: it is the library's {})", lib.species[k as usize].identity.scientific_name);
    }
    // the nearest names by spelling, and the species of a genus named alone (`fagus`)
    let mut near: Vec<String> = Vec::new();
    if let Some(lib) = &lib {
        let key = crate::species::species_name_key(name);
        for s in lib.nearest(name, 3).into_iter().chain(lib.species.iter().filter(|s| {
            let genus = s.identity.scientific_name.split_whitespace().next().unwrap_or("");
            !key.is_empty() && crate::species::species_name_key(genus) == key
        })) {
            let n = format!("`{}` ({})", s.id, s.identity.scientific_name);
            if !near.contains(&n) {
                near.push(n);
            }
        }
    }
    let hint = if near.is_empty() { String::new() } else { format!("; nearest: {}", near.join(", ")) };
    format!("one of the scenario's species = {pool:?}, each a species id of the library: `{name}` is none (`sylva species list` lists the ids{hint})")
}

pub use crate::terrain::NO_SEA_LEVEL_M;

/// Checks `[climate]`: every value finite; latitude −90–90°, lapse rate −15–5 K/km,
/// reference temperature −30–40 °C, K/R/N 1–9, wind direction 0–360°, elevations
/// (reference, sea level) −500–9000 m, precipitation 50–10000 mm, annual temperature range
/// 0–60 K, soil water capacity 10–1000 mm, warming −20–20 K per century. `ctx` names the scenario file.
///
/// Errors: [`Error::Invalid`] naming `climate.<field>`, the value and the range.
pub fn validate_climate(c: &Climate, ctx: &str) -> Result<()> {
    let checks: [(&str, f64, String, f64, f64, &str); 12] = [
        ("latitude_deg", c.latitude_deg, c.latitude_deg.to_string(), -90.0, 90.0, "degrees"),
        ("reference_temperature_c", c.reference_temperature_c as f64, c.reference_temperature_c.to_string(), -30.0, 40.0, "°C"),
        ("reference_elevation_m", c.reference_elevation_m as f64, c.reference_elevation_m.to_string(), -500.0, 9000.0, "m"),
        ("lapse_rate_k_per_km", c.lapse_rate_k_per_km as f64, c.lapse_rate_k_per_km.to_string(), -15.0, 5.0, "K/km"),
        ("continentality_k", c.continentality_k.unwrap_or(5.0) as f64, c.continentality_k.map_or(String::new(), |k| k.to_string()), 1.0, 9.0, "(index; leave it out to derive it from temperature_range_k)"),
        ("reaction_r", c.reaction_r as f64, c.reaction_r.to_string(), 1.0, 9.0, "(index)"),
        ("nitrogen_n", c.nitrogen_n as f64, c.nitrogen_n.to_string(), 1.0, 9.0, "(index)"),
        ("sea_level_m", c.sea_level_m as f64, c.sea_level_m.to_string(), -500.0, 9000.0, "m"),
        ("wind_from_deg", c.wind_from_deg as f64, c.wind_from_deg.to_string(), 0.0, 360.0, "degrees"),
        ("precipitation_mm", c.precipitation_mm as f64, c.precipitation_mm.to_string(), 50.0, 10_000.0, "mm per year"),
        ("temperature_range_k", c.temperature_range_k as f64, c.temperature_range_k.to_string(), 0.0, 60.0, "K (warmest minus coldest monthly mean)"),
        ("soil_water_capacity_mm", c.soil_water_capacity_mm as f64, c.soil_water_capacity_mm.to_string(), 10.0, 1000.0, "mm of plant-available water"),
    ];
    for (field, v, shown, lo, hi, unit) in checks {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(invalid(ctx, &format!("climate.{field}"), shown, &format!("a finite number {lo}–{hi} {unit}")));
        }
    }
    let w = c.warming_k_per_century;
    if !(w.is_finite() && (-20.0..=20.0).contains(&w)) {
        return Err(invalid(ctx, "climate.warming_k_per_century", w, "a finite number −20–20 K per century"));
    }
    Ok(())
}

/// Rewrites serde's Rust type names in a TOML error message into plain words
/// (`expected u32` → `expected a whole number ≥ 0`).
fn plain_type_words(msg: &str) -> String {
    let mut m = msg.to_string();
    for (rust, plain) in [
        ("expected u32", "expected a whole number from 0 to 4294967295"),
        ("expected u64", "expected a whole number ≥ 0"),
        ("expected usize", "expected a whole number ≥ 0"),
        ("expected u16", "expected a whole number from 0 to 65535"),
        ("expected u8", "expected a whole number from 0 to 255"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected a boolean", "expected true or false"),
        ("expected a string", "expected a text in quotes"),
    ] {
        m = m.replace(rust, plain);
    }
    m
}

/// The lengths `(G, N)` of serde's "invalid length G, expected an array of length N" (or
/// "expected N elements in sequence", for an array inside an array) in `msg`; `G` is `None`
/// where the message does not give it.
fn wrong_length(msg: &str) -> Option<(Option<usize>, usize)> {
    let num = |rest: &str| rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok();
    // the length given ("invalid length 3"), where serde says it
    let got = msg.split("invalid length ").nth(1).and_then(num);
    if let Some(rest) = msg.split("expected an array of length ").nth(1) {
        return num(rest).map(|want| (got, want));
    }
    // serde's words for a fixed-size array inside an array (`points = [[50, 50, 3]]`)
    let before = msg.split(" elements in sequence").next().filter(|b| b.len() < msg.len())?;
    num(before.rsplit("expected ").next()?).map(|want| (got, want))
}

/// The lengths of the innermost one-line arrays of a TOML value (`[1, 2]` → [2];
/// `[[1, 2], [3, 4, 5]]` → [2, 3]).
fn innermost_array_lengths(value: &str) -> Vec<usize> {
    let mut out = Vec::new();
    let mut open: Option<usize> = None;
    for (i, c) in value.char_indices() {
        match c {
            '[' => open = Some(i + 1),
            ']' => {
                if let Some(o) = open.take() {
                    out.push(value[o..i].split(',').filter(|x| !x.trim().is_empty()).count());
                }
            }
            _ => {}
        }
    }
    out
}

/// A `key = value` line of a TOML table ([`table_entries`]).
struct Entry<'a> {
    /// The array of tables and the table's index in it (`[[start]]` #1: `("start", 1)`), or
    /// `None` for a plain table.
    array: Option<(&'a str, usize)>,
    /// The key and its value as written (trimmed).
    key: &'a str,
    value: &'a str,
    /// Line number (1-based).
    line: usize,
}

/// The `key = value` lines of the TOML table whose header or line holds byte `at` of `text`
/// (from `at`'s line to the next table header). When `at`'s line is the header of an array of
/// tables (`[[start]]`: serde places the errors of any of its tables at the first header),
/// those of every table of the array, in order.
fn table_entries(text: &str, at: usize) -> Vec<Entry<'_>> {
    fn array_name(line: &str) -> Option<&str> {
        line.trim().strip_prefix("[[").and_then(|h| h.strip_suffix("]]")).map(str::trim)
    }
    fn table_at<'a>(text: &'a str, from: usize, array: Option<(&'a str, usize)>, out: &mut Vec<Entry<'a>>) {
        let first = text[..from].lines().count();
        for (i, line) in text[from..].lines().enumerate() {
            let t = line.trim();
            if i > 0 && t.starts_with('[') {
                break;
            }
            if let Some((key, value)) = t.split_once('=') {
                out.push(Entry { array, key: key.trim().trim_matches('"'), value: value.trim(), line: first + i + 1 });
            }
        }
    }
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let mut out = Vec::new();
    match array_name(text[start..].lines().next().unwrap_or("")) {
        Some(name) => {
            let (mut k, mut pos) = (0, 0);
            for line in text.split_inclusive('\n') {
                if array_name(line) == Some(name) {
                    table_at(text, pos, Some((name, k)), &mut out);
                    k += 1;
                }
                pos += line.len();
            }
        }
        None => table_at(text, start, None, &mut out),
    }
    out
}

/// The first key whose value holds a one-line array of numbers with a length other than
/// `want` (of length `got` where that is known; `None` when there is none), in backquotes, in
/// the TOML table whose header or line holds byte `at` of `text` ([`table_entries`]); a key of
/// an array of tables is named with its index and line: "`start[1].area` (line 22)".
fn key_with_array_len_not(text: &str, at: usize, got: Option<usize>, want: usize) -> Option<String> {
    // an array of the length given where serde says it (another key of another table of the
    // array may rightly hold arrays of other lengths: `points` beside `area`)
    let e = table_entries(text, at).into_iter().find(|e| innermost_array_lengths(e.value).iter().any(|&n| n != want && got.is_none_or(|g| g == n)))?;
    Some(match e.array {
        Some((name, k)) => format!("`{name}[{k}].{}` (line {})", e.key, e.line),
        None => format!("`{}`", e.key),
    })
}

/// The field named by a serde "unknown field `NAME`" message.
fn unknown_field(msg: &str) -> Option<String> {
    let rest = &msg[msg.find("unknown field `")? + "unknown field `".len()..];
    Some(rest[..rest.find('`')?].to_string())
}

/// What serde's "invalid type: WHAT, expected …" or "invalid value: WHAT, expected …" names as
/// the value it got (`string "1.5m"`, `integer `-1``, `floating point `1.5``, `boolean `true``,
/// `sequence`, `map`).
fn invalid_type_value(msg: &str) -> Option<&str> {
    let (i, p) = ["invalid type: ", "invalid value: "].into_iter().find_map(|p| msg.find(p).map(|i| (i, p)))?;
    let rest = &msg[i + p.len()..];
    Some(&rest[..rest.find(", expected")?])
}

/// The keys of the tables holding byte `at` of `text` ([`table_entries`]) whose value is the one
/// serde names (`what`, [`invalid_type_value`]), in backquotes with the table's index and the
/// line: "`start[0].spacing_m` (line 12)"; several joined by "or"; `None` when none is.
fn keys_holding(text: &str, at: usize, what: &str) -> Option<String> {
    let same = |value: &str| -> bool {
        let Some(v) = format!("x = {value}").parse::<toml::Table>().ok().and_then(|mut t| t.remove("x")) else { return false };
        let num = |p: &str| what.strip_prefix(p).map(|r| r.trim_matches('`')).and_then(|r| r.parse::<f64>().ok());
        match v {
            toml::Value::String(s) => what == format!("string {s:?}"),
            toml::Value::Integer(i) => num("integer ").is_some_and(|n| n == i as f64),
            toml::Value::Float(f) => num("floating point ").is_some_and(|n| n == f || (n.is_nan() && f.is_nan())),
            toml::Value::Boolean(b) => what == format!("boolean `{b}`"),
            toml::Value::Array(_) => what == "sequence",
            toml::Value::Table(_) => what == "map",
            toml::Value::Datetime(_) => false,
        }
    };
    let found: Vec<String> = table_entries(text, at)
        .into_iter()
        .filter(|e| same(e.value))
        .map(|e| match e.array {
            Some((name, k)) => format!("`{name}[{k}].{}` (line {})", e.key, e.line),
            None => format!("`{}` (line {})", e.key, e.line),
        })
        .collect();
    (!found.is_empty()).then(|| found.join(" or "))
}

/// The line number (1-based) of the `key = value` line of `text` in the table (or array of
/// tables) that holds byte `at` ([`table_entries`]), or `None` when it has no such line or
/// that line is `at`'s own (serde's span already points at it).
fn key_line_in_table(text: &str, at: usize, key: &str) -> Option<usize> {
    let own = text[..at.min(text.len())].matches('\n').count() + 1;
    table_entries(text, at).into_iter().find(|e| e.key == key).map(|e| e.line).filter(|&l| l != own)
}

/// The key of the `key = value` line of `text` holding byte `at` (`None` when that line is no
/// such line, e.g. inside a table header or an inline table).
fn key_at(text: &str, at: usize) -> Option<String> {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next()?;
    let (key, _) = line.split_once('=')?;
    let key = key.trim();
    (!key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')).then(|| key.to_string())
}

/// What the top-level scenario field `key` holds, for a type error on it (the type alone, e.g.
/// "a whole number from 0 to 4294967295", does not say which values make sense).
fn field_hint(key: &str) -> Option<&'static str> {
    Some(match key {
        "years" => "the number of years to simulate, a whole number 1–10000",
        "seed" => "the random seed, a whole number ≥ 0",
        "snapshot_every" => "years between snapshots (maps, key frames), a whole number ≥ 0 (0: only the first and last year)",
        "inventory_every" => "years between tree inventories, a whole number: a multiple of snapshot_every, or 0 for only the first and last year (omit it for every snapshot)",
        "still_years" => "the years of the stills of `sylva run`, a list of whole numbers within the run, ascending, e.g. [20, 40]",
        "checkpoint_every" => "years between checkpoints, a whole number ≥ 0 (0: only at the end)",
        "light_cell_m" => "the light grid's cell size, a number 2–20 (m)",
        "diffuse" => "[light] diffuse: \"column\" (the leaf area straight above) or \"sky\" (the sky hemisphere through the neighbouring canopy)",
        "seasonal_snapshots" => "true or false",
        // [[management]]'s years (round 30's trial read "0 to 4294967295" for every_years)
        "every_years" => "years between two operations of a [[management]] entry, a whole number 1–1000",
        "year" | "from_year" | "until_year" => "a simulated year of a [[management]] entry, a whole number 0–10000 (1–10000 for thinnings and harvests: they act at a year's end)",
        _ => return None,
    })
}

impl Scenario {
    /// Context for error messages: the scenario file (or source name) and the scenario's `name`.
    pub fn context(&self) -> String {
        if self.source.is_empty() || self.source == self.name {
            format!("scenario {}", self.name)
        } else {
            format!("{} (scenario {})", self.source, self.name)
        }
    }
}

impl Scenario {
    /// Parses and validates a scenario from TOML text; `name` (usually the file path) appears in
    /// error messages.
    ///
    /// Errors: [`Error::Format`] for TOML syntax, unknown fields or wrong types (with line);
    /// [`Error::Invalid`] for out-of-range values.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Scenario> {
        let mut s: Scenario = toml::from_str(text).map_err(|e| {
            let mut msg = plain_type_words(&e.to_string());
            // a wrong type on a top-level field: what the field holds besides its type
            if let Some(hint) = e.span().and_then(|sp| key_at(text, sp.start)).and_then(|k| field_hint(&k).map(|h| (k, h))) {
                // the type's own range ("from 0 to 4294967295") gives way to the field's (a
                // trial read two ranges in one message for `years = -5`)
                let msg_type = match msg.trim_end().rfind(", expected ") {
                    Some(i) => msg[..i].to_string(),
                    None => msg.trim_end().to_string(),
                };
                msg = format!("{msg_type}\n`{}`: expected {}", hint.0, hint.1);
            }
            // a wrong-length array inside a tagged table (an `[[obstacle]]`): serde points at
            // the table and names no field, so the field is found in the table's lines (a trial
            // could not tell which of `center` and `half` was meant)
            if let Some(((got, want), sp)) = wrong_length(&msg).zip(e.span()) {
                if let Some(key) = key_with_array_len_not(text, sp.start, got, want) {
                    msg = format!("{}\n{key}: expected an array of {want} numbers", msg.trim_end());
                }
            }
            // an unknown field inside a tagged table (`[[start]]`, `[[obstacle]]`): serde points
            // at the table's header, so the field's own line is found in the table's lines
            // (round 30's trial: `spaceing_m` on line 26 was reported at line 23)
            if let Some((key, line_no)) = unknown_field(&msg).zip(e.span()).and_then(|(k, sp)| key_line_in_table(text, sp.start, &k).map(|l| (k, l))) {
                msg = format!("{}
the unknown field `{key}` is on line {line_no}", msg.trim_end());
            }
            // a wrong type inside a tagged table (`spacing_m = "1.5m"` in a `[[start]]`): serde
            // points at the array's first header and names no field, so the key holding the
            // value serde names is found in the tables' lines (trial 41, defect 8)
            if let Some(at) = e.span().map(|sp| sp.start).filter(|&at| key_at(text, at).is_none()) {
                if let Some(keys) = invalid_type_value(&msg).and_then(|v| keys_holding(text, at, v)) {
                    msg = format!("{}\nthe wrong value is {keys}", msg.trim_end());
                }
            }
            Error::format(name, msg)
        })?;
        // a PNG heightmap has no sea unless the scenario says where it is: its value 0 is the
        // bottom of its height range, not the sea (trial 37: the lowest pixel became water)
        let png = s.terrain.path.as_ref().and_then(|p| p.extension()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if png && text.parse::<toml::Table>().ok().is_some_and(|t| t.get("climate").and_then(|c| c.get("sea_level_m")).is_none()) {
            s.climate.sea_level_m = NO_SEA_LEVEL_M;
        }
        s.validate(name)?;
        s.source = name.to_string();
        Ok(s)
    }

    /// Reads, parses and validates a scenario file. A relative `terrain.path`,
    /// `climate.anomalies_file` or `management[i].area_file` is resolved against the scenario's
    /// folder (the files themselves are read by [`crate::sim::World::new`]).
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let mut s = Scenario::from_toml_str(&text, &path.display().to_string())?;
        // A relative terrain path is relative to the scenario file; store it absolute so that
        // the copy written into a run directory (`RUN_DIR/scenario.toml`) still finds it.
        let given = s.terrain.path.as_ref().map(|p| p.display().to_string());
        if let Some(p) = &s.terrain.path {
            if p.is_relative() {
                let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
                let joined = dir.join(p);
                s.terrain.path = Some(std::path::absolute(&joined).unwrap_or(joined));
            }
        }
        // a DEM that is not there is named with its field (a check of the final binary got the
        // file's "No such file" under "[terrain]" without the field)
        if let (Some(given), Some(p)) = (given, &s.terrain.path) {
            if !p.exists() {
                return Err(Error::Invalid {
                    context: path.display().to_string(),
                    field: "terrain.path".into(),
                    value: if Path::new(&given) == p.as_path() { given } else { format!("{given} ({})", p.display()) },
                    expected: "an existing DEM file (.tif/.tiff GeoTIFF, .asc ESRI grid or 16-bit .png); a relative path is relative to the scenario file's folder".into(),
                });
            }
        }
        // so are the climate anomalies and management area files
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let abs = |p: &mut PathBuf| {
            if p.is_relative() {
                let joined = dir.join(&*p);
                *p = std::path::absolute(&joined).unwrap_or(joined);
            }
        };
        if let Some(p) = s.climate.anomalies_file.as_mut() {
            abs(p);
        }
        for m in s.management.iter_mut() {
            if let Some(p) = m.area_file.as_mut() {
                abs(p);
            }
        }
        Ok(s)
    }

    /// The scenario as TOML text: tables and arrays of tables as sections, arrays inline (one
    /// line a field: the pretty form put each number of a nested array on a line of its own, a
    /// seed source's 8 points over 50 lines; round 30's trial).
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Serialize { what: format!("scenario {}", self.name), format: "TOML", message: e.to_string() })
    }

    /// Years between tree inventories: `inventory_every`, or `snapshot_every` when absent.
    pub fn inventory_interval(&self) -> u32 {
        self.inventory_every.unwrap_or(self.snapshot_every)
    }

    /// Whether year `y` (1..=years) is a scheduled snapshot year: every `snapshot_every` years,
    /// the `still_years` and the last (year 0 always has one; so do years whose management removed trees and a
    /// year stopped at, which the run driver adds).
    pub fn snapshot_year(&self, y: u32) -> bool {
        y == 0 || y == self.years || (self.snapshot_every > 0 && y.is_multiple_of(self.snapshot_every)) || self.still_years.as_ref().is_some_and(|s| s.contains(&y))
    }

    /// Whether the scheduled snapshot of year `y` also writes the tree inventory and
    /// regeneration table: year 0, the last year and every [`Scenario::inventory_interval`]
    /// years (the run driver adds the years whose management removed trees and a year stopped
    /// at).
    pub fn inventory_year(&self, y: u32) -> bool {
        let every = self.inventory_interval();
        y == 0 || y == self.years || (every > 0 && y.is_multiple_of(every))
    }

    /// Checks ranges; `ctx` names the file.
    pub fn validate(&self, ctx: &str) -> Result<()> {
        // the name heads every progress line and summary (a blank one printed " year 5: …")
        if self.name.trim().is_empty() {
            return Err(invalid(ctx, "name", format!("{:?}", self.name), "a name for the scenario (e.g. \"coweeta\")"));
        }
        let t = &self.terrain;
        let n = t.default.filter(|d| *d).is_some() as u8 + t.embedded.is_some() as u8 + t.path.is_some() as u8 + t.generate.is_some() as u8 + t.uniform.is_some() as u8;
        if n != 1 {
            return Err(invalid(ctx, "terrain", format!("{n} sources"), "exactly one of default = true, embedded, path, generate, uniform"));
        }
        if let Some(e) = &t.embedded {
            if !crate::terrain::io::EMBEDDED_TERRAINS.contains(&e.as_str()) {
                return Err(invalid(ctx, "terrain.embedded", e, &format!("one of {}", crate::terrain::io::EMBEDDED_TERRAINS.join(", "))));
            }
        }
        if let Some(g) = &t.generate {
            if !(16..=8192).contains(&g.size) {
                return Err(invalid(ctx, "terrain.generate.size", g.size, "16–8192 cells"));
            }
            if !(g.cell_m > 0.0 && g.cell_m <= 1000.0) {
                return Err(invalid(ctx, "terrain.generate.cell_m", g.cell_m, "> 0 and ≤ 1000 m"));
            }
            if !(g.relief_m >= 0.0 && g.relief_m <= 9000.0) {
                return Err(invalid(ctx, "terrain.generate.relief_m", g.relief_m, "0–9000 m"));
            }
        }
        if let Some(u) = &t.uniform {
            if u.width == 0 || u.height == 0 || u.width.saturating_mul(u.height) > 64_000_000 {
                return Err(invalid(ctx, "terrain.uniform.width/height", format!("{} x {}", u.width, u.height), "≥ 1 and at most 64 million cells"));
            }
            if !(u.cell_m > 0.0 && u.cell_m <= 1000.0) {
                return Err(invalid(ctx, "terrain.uniform.cell_m", u.cell_m, "> 0 and ≤ 1000 m"));
            }
            // NaN or infinity ran (a trial), as a height no land has
            if !(u.elevation_m >= -500.0 && u.elevation_m <= 9000.0) {
                return Err(invalid(ctx, "terrain.uniform.elevation_m", u.elevation_m, "-500–9000 m"));
            }
            for (i, v) in u.indices.iter().enumerate() {
                let max = if i == crate::conditions::factor::F { 12.0 } else { 9.0 };
                if !(*v >= 1.0 && *v <= max) {
                    return Err(invalid(ctx, &format!("terrain.uniform.indices[{i}] ({})", crate::conditions::factor::NAMES[i]), v, &format!("1–{max}")));
                }
            }
        }
        let is_png = t.path.as_ref().is_some_and(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")));
        if (t.cell_m.is_some() || t.height_range_m.is_some()) && !is_png {
            return Err(invalid(ctx, "terrain.cell_m/height_range_m", "given", "only with a PNG heightmap path (other DEMs carry their own cell size and heights)"));
        }
        // a PNG carries no scale: one taken by default makes a wrong site without a word
        // (round 39's trial: a 512 px heightmap became a 5 km site of 0–1000 m), so both are
        // asked for; GeoTIFFs and ESRI grids carry their own
        if is_png && (t.cell_m.is_none() || t.height_range_m.is_none()) {
            let missing: Vec<&str> = [("terrain.cell_m", t.cell_m.is_none()), ("terrain.height_range_m", t.height_range_m.is_none())].into_iter().filter(|m| m.1).map(|m| m.0).collect();
            let path = t.path.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
            return Err(invalid(
                ctx,
                &missing.join(" and "),
                format!("missing for the PNG heightmap {path}"),
                "the PNG's scale, which a PNG does not carry: under [terrain] both terrain.cell_m (metres a pixel) and terrain.height_range_m (the heights in metres of pixel values 0 and 65535), e.g. `cell_m = 10.0` and `height_range_m = [250.0, 1250.0]`",
            ));
        }
        if let Some(c) = t.cell_m {
            if !(c > 0.0 && c <= 1000.0) {
                return Err(invalid(ctx, "terrain.cell_m", c, "> 0 and ≤ 1000 m"));
            }
        }
        if let Some([lo, hi]) = t.height_range_m {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(invalid(ctx, "terrain.height_range_m", format!("[{lo}, {hi}]"), "[lowest, highest] in metres with lowest < highest"));
            }
        }
        // a start listing a species outside the pool would grow a species the scenario excludes
        for (i, st) in self.start.iter().enumerate() {
            if !self.species.is_empty() && !self.species.iter().any(|p| p == st.species()) {
                // a pool species named by its scientific or common name (trial 38, item 12: it
                // was refused as not in the pool, though other commands take such names): the
                // id to write, which the pool lists
                if !is_embedded_id(st.species()) {
                    if let Some(id) = crate::species::SpeciesLibrary::embedded().ok().and_then(|l| l.find(st.species()).map(|k| l.species[k as usize].id.clone())) {
                        if let Some(j) = self.species.iter().position(|p| *p == id) {
                            return Err(invalid(ctx, &format!("start[{i}].species"), st.species(), &format!("the species' id as the scenario's species list names it: species = \"{id}\" (species[{j}]); a start names its species by id")));
                        }
                    }
                }
                // a pool entry one or two letters from the start's species is most likely the
                // misspelt one (a trial's `species = ["beeech"]` was blamed on the start); which
                // of the two is misspelt is told by the embedded library's ids where one of them
                // is one (a start's `species = "beeech"` was then blamed on the pool, round 26)
                let near = self.species.iter().enumerate().find(|(_, p)| strsim::damerau_levenshtein(p, st.species()) <= 2);
                if let Some((j, p)) = near {
                    if is_embedded_id(st.species()) && !is_embedded_id(p) {
                        return Err(invalid(ctx, &format!("species[{j}]"), p, &format!("a species id of the library; start[{i}] names `{}`: is that meant? (`sylva species list` lists the ids)", st.species())));
                    }
                    return Err(invalid(ctx, &format!("start[{i}].species"), st.species(), &format!("one of the scenario's species = {:?}; did you mean `{p}` (species[{j}])?", self.species)));
                }
                return Err(invalid(ctx, &format!("start[{i}].species"), st.species(), &not_in_pool(st.species(), &self.species)));
            }
        }
        for (i, sp) in self.species.iter().enumerate() {
            if self.species[..i].contains(sp) {
                return Err(invalid(ctx, &format!("species[{i}]"), sp, "each species once"));
            }
        }
        if let Some(w) = &t.window {
            if w[2] < MIN_WINDOW_CELLS || w[3] < MIN_WINDOW_CELLS {
                return Err(invalid(ctx, "terrain.window", format!("{w:?}"), &format!("[col0, row0, width, height] with width and height at least {MIN_WINDOW_CELLS} cells (the window is {} x {} cells): slope and aspect (Horn 1981), and so insolation, wind exposure and flow routing, read each cell's 3 x 3 neighbourhood, which a narrower window holds for no cell", w[2], w[3])));
            }
        }
        validate_climate(&self.climate, ctx)?;
        if !(1..=10_000).contains(&self.years) {
            return Err(invalid(ctx, "years", self.years, "1–10000"));
        }
        if let Some(n) = self.inventory_every {
            // inventories are written at snapshots: their years must be snapshot years
            let ok = match self.snapshot_every {
                0 => n == 0,
                s => n.is_multiple_of(s),
            };
            if !ok {
                let expected = match self.snapshot_every {
                    0 => "0 (only the first and last year), as snapshot_every = 0".to_string(),
                    s => format!("a multiple of snapshot_every = {s} (e.g. {}, {}), or 0 for only the first and last year", s, 5 * s),
                };
                return Err(invalid(ctx, "inventory_every", n, &expected));
            }
        }
        if let Some(ys) = &self.still_years {
            for (k, &y) in ys.iter().enumerate() {
                if y > self.years {
                    return Err(invalid(ctx, &format!("still_years[{k}]"), y, &format!("a year within the run, 0–{} (its last year, `years`)", self.years)));
                }
                if k > 0 && y <= ys[k - 1] {
                    return Err(invalid(ctx, &format!("still_years[{k}]"), y, &format!("a year after the previous one ({}): the years ascending, each once", ys[k - 1])));
                }
            }
        }
        if !(self.light_cell_m >= 2.0 && self.light_cell_m <= 20.0) {
            return Err(invalid(ctx, "light_cell_m", self.light_cell_m, "2–20 m"));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            o.validate(i, ctx)?;
        }
        for (i, m) in self.management.iter().enumerate() {
            m.validate(i, ctx)?;
            // a name names the entry's rows in management_table.csv: two entries of one name
            // would mix their rows there (round 43's trial: accepted without a word)
            if let Some(n) = &m.name {
                if let Some(j) = self.management[..i].iter().position(|o| o.name.as_deref() == Some(n.as_str())) {
                    return Err(invalid(ctx, &format!("management[{i}].name"), format!("{n:?}"), &format!("a name no other entry has (management[{j}] has it): it names the entry's rows in management_table.csv")));
                }
            }
            for sp in m.mix.iter().flat_map(|x| x.keys()) {
                // a scientific or common name of a pool species is accepted, as `tree grow
                // --species` accepts it (trial 40: `"Fagus sylvatica" = 0.6` was refused); the
                // run's own library resolves it again when the plan is built
                if !self.species.is_empty() && !self.species.contains(sp) && !names_a_pool_species(sp, &self.species) {
                    return Err(invalid(ctx, &format!("management[{i}].mix.{sp}"), sp, &not_in_pool(sp, &self.species)));
                }
            }
        }
        for (i, s) in self.start.iter().enumerate() {
            let f = |x: &str| format!("start[{i}].{x}");
            match s {
                Start::SeedSources { points, trees_per_source, .. } => {
                    if points.is_empty() {
                        return Err(invalid(ctx, &f("points"), "[]", "at least one [x, y] point"));
                    }
                    if !(1..=1000).contains(trees_per_source) {
                        return Err(invalid(ctx, &f("trees_per_source"), trees_per_source, "1–1000"));
                    }
                }
                Start::SeedRain { seeds_per_ha, .. } => {
                    if !(*seeds_per_ha >= 0.0 && *seeds_per_ha <= 1e8) {
                        return Err(invalid(ctx, &f("seeds_per_ha"), seeds_per_ha, "0–100,000,000 seeds per ha per year (a beech mast year gives up to ~2·10⁷)"));
                    }
                }
                Start::Planted { spacing_m, age_yr, area, .. } => {
                    if !(*spacing_m >= 0.5 && *spacing_m <= 50.0) {
                        return Err(invalid(ctx, &f("spacing_m"), spacing_m, "0.5–50 m"));
                    }
                    if !(*age_yr >= 0.0 && *age_yr <= 1000.0) {
                        return Err(invalid(ctx, &f("age_yr"), age_yr, "0–1000 years"));
                    }
                    if let Some(a) = area {
                        if !(a[2] > a[0] && a[3] > a[1]) {
                            return Err(invalid(ctx, &f("area"), format!("{a:?}"), "[x0, y0, x1, y1] with x1 > x0 and y1 > y0"));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks that seed-source points (`start[i].points[j]`) lie inside the site and planted
    /// areas (`start[i].area`) lie within it; `extent` is the site extent `(x, y)` in metres
    /// (origin SW corner, [`crate::conditions::SiteConditions::extent_m`]), `ctx` names the
    /// scenario. Called by [`crate::sim::World::new`].
    ///
    /// Errors: [`Error::Invalid`] naming the field, the value and the site extent.
    pub fn validate_extent(&self, extent: (f64, f64), ctx: &str) -> Result<()> {
        let (ex, ey) = extent;
        let site = format!("inside the site, 0 ≤ x < {ex} m and 0 ≤ y < {ey} m (origin SW corner)");
        for (i, s) in self.start.iter().enumerate() {
            match s {
                Start::SeedSources { points, .. } => {
                    for (j, p) in points.iter().enumerate() {
                        if !(p[0] >= 0.0 && p[0] < ex && p[1] >= 0.0 && p[1] < ey) {
                            return Err(invalid(ctx, &format!("start[{i}].points[{j}]"), format!("[{}, {}]", p[0], p[1]), &site));
                        }
                    }
                }
                Start::Planted { area: Some(a), .. } => {
                    if !(a[0] >= 0.0 && a[1] >= 0.0 && a[2] <= ex && a[3] <= ey) {
                        return Err(invalid(
                            ctx,
                            &format!("start[{i}].area"),
                            format!("[{}, {}, {}, {}]", a[0], a[1], a[2], a[3]),
                            &format!("[x0, y0, x1, y1] within the site, 0 ≤ x0 < x1 ≤ {ex} m and 0 ≤ y0 < y1 ≤ {ey} m"),
                        ));
                    }
                }
                _ => {}
            }
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            let b = o.bounds_xy();
            if !(b[2] > 0.0 && b[3] > 0.0 && b[0] < ex && b[1] < ey) {
                return Err(invalid(ctx, &format!("obstacle[{i}]"), format!("{} over x {}–{} m, y {}–{} m", o.kind(), b[0], b[2], b[1], b[3]), &format!("an obstacle overlapping the site, 0 ≤ x < {ex} m and 0 ≤ y < {ey} m (origin SW corner)")));
            }
        }
        // planted trees over the site: each is an individual in memory and in every inventory
        let mut planted = 0u64;
        for (i, s) in self.start.iter().enumerate() {
            if let Start::Planted { spacing_m, area, .. } = s {
                let [x0, y0, x1, y1] = area.unwrap_or([0.0, 0.0, ex, ey]);
                planted += (((x1 - x0) / spacing_m).floor().max(0.0) as u64) * (((y1 - y0) / spacing_m).floor().max(0.0) as u64);
                if planted > MAX_PLANTED_TREES {
                    return Err(invalid(ctx, &format!("start[{i}].spacing_m"), spacing_m, &format!("a spacing that plants at most {MAX_PLANTED_TREES} trees in all ({planted} so far on {:.0} ha; widen the spacing or give an area)", ex * ey / 10_000.0)));
                }
            }
        }
        Ok(())
    }

    /// Cells of the simulated site where the scenario alone tells them: a window's
    /// `width × height`, a uniform site's, a generated terrain's `size²`; `None` for a whole DEM
    /// file (its size is in the file).
    pub fn site_cells(&self) -> Option<u64> {
        if let Some([_, _, w, h]) = self.terrain.window {
            return Some(w as u64 * h as u64);
        }
        match self.terrain_spec() {
            TerrainSpec::Uniform(u) => Some(u.width as u64 * u.height as u64),
            TerrainSpec::Generate(g) => Some(g.size as u64 * g.size as u64),
            _ => None,
        }
    }

    /// The memory (bytes) the site of this scenario needs before any tree where the scenario
    /// alone tells its cells ([`Scenario::site_cells`]): per cell [`SITE_BYTES_PER_CELL`] and
    /// per species [`SEED_BYTES_PER_CELL_SPECIES`] (scaled by the cell's area over a 10 m
    /// cell's where the scenario gives the cell size, a window of a DEM counting as 10 m), plus
    /// [`BASE_BYTES`] and [`BASE_BYTES_PER_SPECIES`] per species; `None` for a whole DEM file.
    pub fn site_memory_bytes(&self) -> Option<u64> {
        let cells = self.site_cells()?;
        let cell_m = match (self.terrain.window, self.terrain_spec()) {
            (None, TerrainSpec::Uniform(u)) => u.cell_m,
            (None, TerrainSpec::Generate(g)) => g.cell_m,
            _ => 10.0,
        };
        let species = self.species.len().max(1) as u64;
        let seed = ((SEED_BYTES_PER_CELL_SPECIES * species) as f64 * (cell_m / 10.0).powi(2).max(1.0)).ceil() as u64;
        Some(cells.saturating_mul(SITE_BYTES_PER_CELL + seed).saturating_add(BASE_BYTES + BASE_BYTES_PER_SPECIES * species))
    }

    /// Refuses a site whose conditions and grids alone need more memory than `available_bytes`
    /// (the machine's available memory): [`Scenario::site_memory_bytes`], before any tree. A
    /// trial's 8000 × 8000 uniform site passed validation and aborted with "memory allocation
    /// failed" on an 8 GB machine.
    ///
    /// Errors: [`Error::Invalid`] naming the terrain field, the bytes needed and available.
    pub fn check_site_memory(&self, available_bytes: u64) -> Result<()> {
        let (Some(cells), Some(need)) = (self.site_cells(), self.site_memory_bytes()) else { return Ok(()) };
        if need <= available_bytes {
            return Ok(());
        }
        let t = &self.terrain;
        let (field, value) = match (t.window, t.uniform, t.generate) {
            (Some(w), _, _) => ("terrain.window", format!("{w:?}")),
            (None, Some(u), _) => ("terrain.uniform.width/height", format!("{} x {}", u.width, u.height)),
            (None, None, Some(g)) => ("terrain.generate.size", g.size.to_string()),
            _ => ("terrain", format!("{cells} cells")),
        };
        let gb = |b: u64| b as f64 / 1e9;
        Err(invalid(&self.context(), field, value, &format!("a site this machine can hold: {cells} cells need about {:.1} GB ({:.0} bytes a cell for the conditions, grids and {} species' seed grids, before any tree) and {:.1} GB are available; use a smaller site or window, or coarser cells", gb(need), need as f64 / cells as f64, self.species.len(), gb(available_bytes))))
    }

    /// The terrain source to load.
    pub fn terrain_spec(&self) -> TerrainSpec {
        let t = &self.terrain;
        if let Some(u) = t.uniform {
            TerrainSpec::Uniform(u)
        } else if let Some(g) = t.generate {
            TerrainSpec::Generate(g)
        } else if let Some(p) = &t.path {
            TerrainSpec::Path(p.clone())
        } else if let Some(e) = &t.embedded {
            TerrainSpec::Embedded(e.clone())
        } else {
            TerrainSpec::Default
        }
    }

    /// Checks that every species named in `species` and `start` exists in `lib`; returns the
    /// pool's species ids (all species of the library when `species` is empty).
    pub fn resolve_species(&self, lib: &crate::species::SpeciesLibrary, ctx: &str) -> Result<Vec<crate::species::SpeciesId>> {
        let known = || lib.species.iter().map(|s| s.id.as_str()).collect::<Vec<_>>().join(", ");
        let mut pool = Vec::new();
        if self.species.is_empty() {
            pool = (0..lib.species.len() as u16).collect();
        } else {
            for (i, s) in self.species.iter().enumerate() {
                let id = lib.find(s).ok_or_else(|| invalid(ctx, &format!("species[{i}]"), s, &format!("one of: {}{}; or a species file of your own, in a folder given with `--species-dir DIR`", known(), lib.did_you_mean(s))))?;
                pool.push(id);
            }
        }
        for (i, st) in self.start.iter().enumerate() {
            let id = lib.find(st.species()).ok_or_else(|| invalid(ctx, &format!("start[{i}].species"), st.species(), &format!("one of: {}{}; or a species file of your own, in a folder given with `--species-dir DIR`", known(), lib.did_you_mean(st.species()))))?;
            if !pool.contains(&id) {
                pool.push(id);
            }
        }
        pool.sort_unstable();
        pool.dedup();
        Ok(pool)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = r#"
name = "t"
years = 5
seed = 3
[terrain]
uniform = { width = 4, height = 4, cell_m = 25.0, indices = [5, 5, 4, 5, 6, 5] }
[[start]]
kind = "planted"
species = "beech"
spacing_m = 2.0
"#;

    #[test]
    fn written_with_arrays_inline() {
        let text = OK.replace("spacing_m = 2.0", "spacing_m = 2.0\n[[start]]\nkind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[10.0, 20.0], [30.0, 40.0]]\ntrees_per_source = 3");
        let s = Scenario::from_toml_str(&text, "t.toml").unwrap();
        // a misspelt field in the second table of an array is found there (serde points at
        // the first header)
        let e = Scenario::from_toml_str(&text.replace("trees_per_source", "trees_per_point"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("the unknown field `trees_per_point` is on line 15"), "{e}");
        let w = s.to_toml_string().unwrap();
        assert!(w.lines().any(|l| l.trim() == "points = [[10.0, 20.0], [30.0, 40.0]]"), "{w}");
        assert!(w.contains("[[start]]") && w.contains("[terrain.uniform]"), "{w}");
        assert_eq!(Scenario::from_toml_str(&w, "t.toml").unwrap(), s, "read back the same");
    }

    #[test]
    fn parses_and_resolves() {
        let s = Scenario::from_toml_str(OK, "t.toml").unwrap();
        assert_eq!(s.years, 5);
        assert!(matches!(s.terrain_spec(), TerrainSpec::Uniform(_)));
        assert_eq!(s.snapshot_every, 10);
    }

    #[test]
    fn errors_name_field_and_value() {
        let e = Scenario::from_toml_str(&OK.replace("years = 5", "years = 0"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("t.toml") && e.contains("years") && e.contains("1–10000"), "{e}");
        let e = Scenario::from_toml_str(&OK.replace("spacing_m = 2.0", "spacing_m = 0.1"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("start[0].spacing_m") && e.contains("0.1"), "{e}");
        let e = Scenario::from_toml_str(&OK.replace("seed = 3", "seed = 3\nbogus = 1"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("bogus"), "{e}");
        // a management year of the wrong type names the field and its range, not u32's
        let m = format!("{OK}[[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_stems_ha = 500.0\nfrom_year = 5\nevery_years = \"5\"\n");
        let e = Scenario::from_toml_str(&m, "t.toml").unwrap_err().to_string();
        assert!(e.contains("`every_years`: expected") && e.contains("1–1000") && !e.contains("4294967295"), "{e}");
        let e = Scenario::from_toml_str(&m.replace("from_year = 5", "from_year = -3").replace("\"5\"", "5"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("`from_year`: expected") && e.contains("0–10000") && !e.contains("4294967295"), "{e}");
        // a misspelt field of a tagged table is named with its own line (line 10 of OK: the
        // table's header is line 7), not only the header's (round 30's trial)
        let e = Scenario::from_toml_str(&OK.replace("spacing_m = 2.0", "spaceing_m = 2.0"), "t.toml").unwrap_err().to_string();
        assert!(e.contains("unknown field `spaceing_m`") && e.contains("the unknown field `spaceing_m` is on line 10"), "{e}");
        assert_eq!(key_line_in_table("[[a]]\nx = 1\n[[b]]\ny = 2\n", 0, "y"), None, "another table's line is not taken");
        assert_eq!(key_line_in_table("[[a]]\nx = 1\ny = 2\n", 0, "y"), Some(3));
    }

    #[test]
    fn inventory_every_defaults_to_snapshot_every_and_must_be_a_multiple() {
        let s = Scenario::from_toml_str(&OK.replace("seed = 3", "seed = 3\nsnapshot_every = 2"), "t.toml").unwrap();
        assert_eq!((s.inventory_every, s.inventory_interval()), (None, 2));
        // absent stays absent in the scenario written to a run directory
        assert!(!s.to_toml_string().unwrap().contains("inventory_every"));
        let s = Scenario::from_toml_str(&OK.replace("seed = 3", "seed = 3\nsnapshot_every = 2\ninventory_every = 4"), "t.toml").unwrap();
        assert_eq!(s.inventory_interval(), 4);
        assert_eq!((1..=5).filter(|&y| s.snapshot_year(y)).collect::<Vec<_>>(), vec![2, 4, 5]);
        assert_eq!((0..=5).filter(|&y| s.inventory_year(y)).collect::<Vec<_>>(), vec![0, 4, 5]);
        assert!(s.to_toml_string().unwrap().contains("inventory_every = 4"));
        for (snap, inv) in [(2, 3), (5, 1), (0, 5)] {
            let e = Scenario::from_toml_str(&OK.replace("seed = 3", &format!("seed = 3\nsnapshot_every = {snap}\ninventory_every = {inv}")), "t.toml").unwrap_err().to_string();
            assert!(e.contains("t.toml") && e.contains("inventory_every") && e.contains(&inv.to_string()) && e.contains("snapshot_every"), "{e}");
        }
        assert!(Scenario::from_toml_str(&OK.replace("seed = 3", "seed = 3\nsnapshot_every = 5\ninventory_every = 0"), "t.toml").is_ok());
        // a wrong type says what the field holds, not only the type's range
        for bad in ["-1", "\"x\"", "2.5"] {
            let e = Scenario::from_toml_str(&OK.replace("seed = 3", &format!("seed = 3\nsnapshot_every = 5\ninventory_every = {bad}")), "t.toml").unwrap_err().to_string();
            assert!(e.contains("t.toml") && e.contains("`inventory_every`: expected years between tree inventories") && e.contains("multiple of snapshot_every"), "{e}");
        }
    }
}

/// Cuts the window `[col0, row0, width, height]` (cells, row 0 north) out of `site`.
///
/// Errors: [`Error::Invalid`] when the window leaves the grid.
pub fn crop_site(site: &crate::conditions::SiteConditions, window: [usize; 4]) -> Result<crate::conditions::SiteConditions> {
    let [c0, r0, w, h] = window;
    if w == 0 || h == 0 || c0 + w > site.width() || r0 + h > site.height() {
        return Err(invalid("scenario", "terrain.window", format!("{window:?}"), &format!("inside the {} x {} terrain grid", site.width(), site.height())));
    }
    let (win, full) = (crate::grid::Window { col0: c0, row0: r0, width: w, height: h }, crate::grid::Window::full(site.width(), site.height()));
    let cut = |g: &crate::grid::Grid<f32>| win.cut(g, &full);
    let mut geo = site.geo.clone();
    geo.origin_x += c0 as f64 * geo.pixel_w;
    geo.origin_y -= r0 as f64 * geo.pixel_h;
    Ok(crate::conditions::SiteConditions {
        geo,
        cell_x_m: site.cell_x_m,
        cell_y_m: site.cell_y_m,
        mask: win.cut(&site.mask, &full),
        elevation_m: cut(&site.elevation_m),
        slope_deg: cut(&site.slope_deg),
        aspect_deg: cut(&site.aspect_deg),
        twi: cut(&site.twi),
        insolation_kwh_m2: cut(&site.insolation_kwh_m2),
        wind_exposure: cut(&site.wind_exposure),
        temperature_c: cut(&site.temperature_c),
        indices: win.cut(&site.indices, &full),
        held: crate::grid::Window::full(w, h),
        full: (w, h),
    })
}

impl Scenario {
    /// The whole terrain this scenario names (embedded, file or generated), before its window;
    /// `None` for a uniform site. The pictures draw the terrain beyond the window around the
    /// simulated area (`job::scene::Landscape`).
    ///
    /// Errors: terrain reading errors (file, format).
    pub fn full_terrain(&self) -> Result<Option<crate::terrain::Terrain>> {
        Ok(Some(match self.terrain_spec() {
            TerrainSpec::Uniform(_) => return Ok(None),
            TerrainSpec::Default => crate::terrain::io::default_terrain()?,
            TerrainSpec::Embedded(name) => crate::terrain::io::embedded_terrain(&name)?,
            TerrainSpec::Path(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) => {
                crate::terrain::io::load_png_heightmap_or_default(&p, self.terrain.cell_m, self.terrain.height_range_m, ("terrain.cell_m", "terrain.height_range_m"))?
            }
            TerrainSpec::Path(p) => crate::terrain::io::load(&p)?,
            TerrainSpec::Generate(g) => crate::terrain::generate::generate(g.size, g.cell_m, g.relief_m as f64, g.seed)?,
        }))
    }

    /// Loads the terrain this scenario names (embedded default, file, generated or uniform),
    /// applies the window and derives the site conditions under the scenario's climate
    /// ([`crate::conditions::derive`]).
    ///
    /// Errors: terrain reading errors (file, format, window outside the grid), no valid cell.
    pub fn site(&self) -> Result<crate::conditions::SiteConditions> {
        if let TerrainSpec::Uniform(u) = self.terrain_spec() {
            let site = crate::conditions::SiteConditions::uniform(u.width, u.height, u.cell_m, u.elevation_m, u.indices, self.climate.latitude_deg);
            return match self.terrain.window {
                Some(w) => crop_site(&site, w),
                None => Ok(site),
            };
        }
        let Some(t) = self.full_terrain()? else {
            return Err(invalid("scenario", "terrain", "uniform", "a terrain with elevations"));
        };
        let t = match self.terrain.window {
            Some([c0, r0, w, h]) => crate::terrain::io::window(&t, c0, r0, w, h)?,
            None => t,
        };
        crate::conditions::derive(&t, &self.climate)
    }
}
