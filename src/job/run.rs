//! The run driver shared by `sylva simulate` and `sylva run`: steps the years of the pure
//! simulation ([`crate::sim::step_year_with`]), writes the run directory of ARCHITECTURE.md
//! (scenario, stand table + plot, inventories, maps, checkpoint), reports progress and stops
//! cleanly after the current year when asked to. The simulation itself writes no files.

use super::checkpoint;
use crate::conditions::SiteConditions;
use crate::sim::scenario::Scenario;
use crate::sim::stats::StandRow;
use crate::sim::step::{step_year_with, YearReport};
use crate::sim::world::World;
use super::Result;
use crate::Error;
use crate::output::inventory::InventoryFormat;
use crate::output::{inventory, plot, stand_table};
use crate::species::{Season, SpeciesLibrary};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Progress after a simulated year.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Years completed.
    pub year: u32,
    /// Years of the scenario.
    pub years: u32,
    /// Living trees.
    pub trees: usize,
    /// Tree-years simulated per second of wall time in this year.
    pub trees_per_s: f64,
    /// Wall time (s) of each phase of the year, [`crate::sim::step::PHASES`] order.
    pub phase_seconds: [f64; crate::sim::step::N_PHASES],
    /// Wall time (s) of this year's outputs: snapshots, stand table and checkpoint (0 in years
    /// without any).
    pub output_seconds: f64,
}

/// What a run calls at every plain snapshot with the year and the in-memory world
/// ([`RunOptions::on_snapshot`]).
pub type OnSnapshot<'a> = dyn FnMut(u32, &World) + 'a;

/// Options of [`run_scenario`].
pub struct RunOptions<'a> {
    /// Run directory (created).
    pub out_dir: PathBuf,
    /// Continue from the checkpoint of `out_dir` (`checkpoint.bin`, or a tiled run's per-rank
    /// checkpoints: [`checkpoint::find`]).
    pub resume: bool,
    /// When set (e.g. by a Ctrl-C handler), the run stops after the current year with all
    /// outputs so far written and a checkpoint.
    pub stop: Option<Arc<AtomicBool>>,
    /// Called after every year.
    pub progress: Option<&'a mut dyn FnMut(&Progress)>,
    /// Longest side of the species and basal-area maps (pixels).
    pub map_px: usize,
    /// Write inventories, maps and plots (false: stand table and checkpoint only).
    pub write_snapshots: bool,
    /// Years whose inventory snapshots also get the GeoPackage inventory `year_NNNN.gpkg`
    /// (`None`: every snapshot with an inventory). The last year and a year stopped at always get it. A GeoPackage is ~115 bytes
    /// per tree (uncompressed), so the main job
    /// limits it to the years it renders; the CSV inventory is written at every snapshot.
    pub gpkg_years: Option<Vec<u32>>,
    /// Called with the year and the in-memory world at every plain snapshot (year 0 of a fresh
    /// run, every `snapshot_every` years, the end, a year stopped at), after its files are
    /// written; the main job builds its pictures' instances here instead of reading the
    /// inventories back. Not called when `write_snapshots` is off.
    pub on_snapshot: Option<&'a mut OnSnapshot<'a>>,
    /// File format of the inventories and regeneration tables (default Parquet).
    pub inventory: InventoryFormat,
    /// Called once the run's world is built (the scenario checked against the site: by the
    /// ranks together in a tiled run whose ranks hold their tiles only) and before the run
    /// writes anything; an error stops the run there. The main job writes the run's species
    /// files here, so a scenario the ranks refuse (a managed area without ground, a planting
    /// that plants nothing) leaves no folder behind over MPI either (issue 37 round 37).
    pub on_start: Option<&'a mut dyn FnMut() -> Result<()>>,
}

impl RunOptions<'_> {
    /// Defaults: no resume, no stop flag, no progress callback, 1024-pixel maps, snapshots on.
    pub fn new(out_dir: impl Into<PathBuf>) -> Self {
        RunOptions { out_dir: out_dir.into(), resume: false, stop: None, progress: None, map_px: 1024, write_snapshots: true, gpkg_years: None, on_snapshot: None, inventory: InventoryFormat::Parquet, on_start: None }
    }
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The world at the end. In a tiled run (rank 0) the year is the last one simulated; with
    /// an `on_snapshot` caller the rest as of the last year whose outputs needed the whole world
    /// (a snapshot, a stop), or as started when none did; without one (nothing reads the world
    /// whole: [`Stepper::shed`]) its site is rank 0's tile's cells, its stand holds no trees or
    /// cohorts (the ranks held them; `trees` counts them), its pool, library and extent the
    /// run's.
    pub world: World,
    /// Living trees at the end (the whole landscape's, in a tiled run too).
    pub trees: usize,
    /// Stand table, one row per year simulated (years 1 and on; year 0 is [`RunSummary::year0`]).
    pub rows: Vec<StandRow>,
    /// The stand table's year-0 row: the state after the `[[start]]` plantings, before any
    /// growth (the first row of `stand_table.csv`; trial 41, defect 7).
    pub year0: Option<StandRow>,
    /// True when stopped early by the stop flag.
    pub stopped: bool,
    /// Wall time of the years simulated in this call (s).
    pub seconds: f64,
}

fn mkdir(p: &Path) -> Result<()> {
    Ok(std::fs::create_dir_all(p).map_err(|e| Error::io(p, e))?)
}

/// Checks that files can be created in `dir` (creates and removes a probe file), so a run
/// fails before it removes anything of an earlier run.
///
/// Errors: [`Error::Io`] naming the folder.
pub fn check_writable(dir: &Path) -> Result<()> {
    let probe = dir.join(format!(".sylva_write_probe.{}.tmp", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| {
        // a folder that exists but cannot hold a new file (procfs, sysfs) answers ENOENT, which
        // read as "No such file or directory" names a wrong reason (trial 35, `--out /proc/b.glb`)
        if e.kind() == std::io::ErrorKind::NotFound && dir.is_dir() {
            Error::io(dir, std::io::Error::other("the folder exists but takes no new files (a virtual file system such as /proc or /sys?); choose a folder on a disk"))
        } else {
            Error::io(dir, e)
        }
    })?;
    Ok(std::fs::remove_file(&probe).map_err(|e| Error::io(&probe, e))?)
}

/// With `--resume` and no checkpoint `ck`: whether a run was started in `dir` (its
/// `scenario.toml` or its `species/` folder, the first things a run writes, are there) and
/// stopped before its first checkpoint, so the resumed run starts from year 0.
///
/// Errors: [`Error::Format`] naming the checkpoint when `dir` holds no started run either.
pub(crate) fn started_here(dir: &Path, ck: &Path) -> Result<bool> {
    if dir.join("scenario.toml").is_file() || dir.join("species").is_dir() {
        return Ok(true);
    }
    Err(Error::format(ck, "--resume: no checkpoint in the run directory (and no run started there: no scenario.toml, no species/)").into())
}

/// Removes the snapshot files of an earlier run from `dir`: `inventory/year_*` and
/// `maps/species_*`, `maps/basal_area_*` (only these Sylva names; other files are kept), so a
/// fresh run into an existing run directory never mixes its snapshots with old ones.
///
/// Errors: [`Error::Io`] naming the folder or file that cannot be listed or removed.
pub fn clear_snapshots(dir: &Path) -> Result<()> {
    remove_prefixed(dir, &[("inventory", &["year_"]), ("maps", &["species_", "basal_area_"])]).map(drop)
}

/// Removes the files of the snapshot `label` (e.g. `year_0037`): `inventory/{label}.*`,
/// `inventory/{label}_*` (regeneration layer, seasons) and `maps/species_{label}.*`,
/// `maps/basal_area_{label}.*`; other files are kept. Returns what it removed, as
/// [`remove_prefixed`].
///
/// Errors: [`Error::Io`] naming the folder or file that cannot be listed or removed.
fn remove_snapshot(dir: &Path, label: &str) -> Result<Vec<String>> {
    let (i1, i2) = (format!("{label}."), format!("{label}_"));
    let (m1, m2) = (format!("species_{label}."), format!("basal_area_{label}."));
    remove_prefixed(dir, &[("inventory", &[&i1, &i2]), ("maps", &[&m1, &m2])])
}

/// Removes the plain files of each `dir/sub` whose name starts with one of its prefixes, and
/// the folders (with their files) whose name starts with one or is one without its final `.`
/// (a tiled run's partitioned snapshot `inventory/year_NNNN/` for the prefix `year_NNNN.`);
/// a missing folder is skipped. Returns the paths it removed relative to `dir` (`/`-separated,
/// a folder's with a trailing `/`), in each folder's name order.
///
/// Errors: [`Error::Io`] naming the folder or file that cannot be listed or removed.
fn remove_prefixed(dir: &Path, subs: &[(&str, &[&str])]) -> Result<Vec<String>> {
    let mut removed = Vec::new();
    for (sub, prefixes) in subs {
        let d = dir.join(sub);
        if !d.is_dir() {
            continue;
        }
        let mut entries = Vec::new();
        for e in std::fs::read_dir(&d).map_err(|e| Error::io(&d, e))? {
            let e = e.map_err(|err| Error::io(&d, err))?;
            entries.push((e.file_name().to_string_lossy().into_owned(), e.path()));
        }
        entries.sort();
        for (name, p) in entries {
            if prefixes.iter().any(|pre| name.starts_with(pre)) && p.is_file() {
                std::fs::remove_file(&p).map_err(|err| Error::io(&p, err))?;
                removed.push(format!("{sub}/{name}"));
            } else if p.is_dir() && prefixes.iter().any(|pre| name.starts_with(pre) || pre.strip_suffix('.') == Some(&*name)) {
                std::fs::remove_dir_all(&p).map_err(|err| Error::io(&p, err))?;
                removed.push(format!("{sub}/{name}/"));
            }
        }
    }
    Ok(removed)
}

/// Removes the tree inventory files of the snapshot `label` (`inventory/{label}.*`,
/// `inventory/{label}_*`: regeneration layer, seasons); its maps are kept. Returns what it
/// removed, as [`remove_prefixed`].
///
/// Errors: [`Error::Io`] naming the folder or file that cannot be listed or removed.
fn remove_inventory(dir: &Path, label: &str) -> Result<Vec<String>> {
    let (i1, i2) = (format!("{label}."), format!("{label}_"));
    remove_prefixed(dir, &[("inventory", &[&i1, &i2])])
}

/// The `note:` a resumed run prints when it removes files the earlier run wrote: what (the
/// paths of `removed`, relative to `dir`), why (`why`), and that the run then holds exactly the
/// files of an unbroken run.
fn resume_removal_note(dir: &Path, removed: &[String], why: &str) -> String {
    format!(
        "note: --resume removed {} from {}: {why}, so an unbroken run does not write {}; the resumed run's folder holds exactly an unbroken run's files",
        removed.join(", "),
        dir.display(),
        if removed.len() == 1 { "it" } else { "them" }
    )
}

/// The text of a run directory's `scenario.toml`: the scenario as run, under a comment naming
/// the Sylva version that wrote it (`# written by sylva 0.46.0`), so a methods section can cite
/// the model version of each run (trial 46, defect 9; Parquet files carry it as `created_by`).
/// Errors: [`Error::Serialize`] as [`Scenario::to_toml_string`].
pub fn scenario_as_run(scenario: &Scenario) -> crate::Result<String> {
    Ok(format!("# written by sylva {}, the scenario as run\n{}", env!("CARGO_PKG_VERSION"), scenario.to_toml_string()?))
}

/// A resume refused because the scenario's management differs from the checkpoint's
/// (`sim::checkpoint`'s identity holds a CRC-32 per entry) with the changes named field by
/// field, old → new ([`crate::sim::checkpoint::entry_changes`] against the run directory's
/// `scenario.toml`, the scenario as the checkpoint's run ran it), in place of the CRC-32s
/// (trial 38, item 8); any other refusal, or one whose `scenario.toml` is missing or shows no
/// change of an entry (an area file's polygons changed), unchanged.
fn name_management_changes(e: super::JobError, dir: &Path, scenario: &Scenario) -> super::JobError {
    let super::JobError::Input(Error::Format { path, message }) = &e else { return e };
    let Some(start) = message.find("; management: ").map(|k| k + 2).or_else(|| message.find(": management: ").map(|k| k + 2)) else { return e };
    if !message.starts_with("--resume refused") {
        return e;
    }
    let Ok(text) = std::fs::read_to_string(dir.join("scenario.toml")) else { return e };
    let Ok(old) = Scenario::from_toml_str(&text, &dir.join("scenario.toml").display().to_string()) else { return e };
    let changes = crate::sim::checkpoint::entry_changes(&old.management, &scenario.management);
    if changes.is_empty() {
        return e;
    }
    // the management part runs to the next change ("; ") or the closing explanation (" (a resumed")
    let rest = &message[start..];
    let close = rest.find(" (a resumed").unwrap_or(rest.len());
    let end = rest[..close].find("; ").unwrap_or(close);
    let named = format!("{} (the checkpoint's run as its scenario.toml gives it → this scenario)", changes.join(", "));
    Error::format(path.clone(), format!("{}{named}{}", &message[..start], &rest[end..])).into()
}

/// What a snapshot writes ([`Stepper::snapshot`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Parts {
    /// The tree inventory (Parquet or CSV), and with `maps` the regeneration table.
    pub inventory: bool,
    /// The GeoPackage inventory too (only with `inventory`).
    pub gpkg: bool,
    /// A plain snapshot: the species and basal-area maps (and with `inventory` the
    /// regeneration table); false for a seasonal snapshot (inventories only).
    pub maps: bool,
}

fn snapshot(dir: &Path, w: &World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat) -> Result<()> {
    snapshot_masked(dir, w, label, parts, map_px, format, None)
}

/// [`Stepper::snapshot`]'s default from `w`, with the maps' pixels whose centre is masked
/// given (`masked`, [`plot::map_masked_centres`] of the whole site; `None`: from `w`'s site,
/// which must then be whole): a tiled run's rank 0 that holds its tile's cells only writes
/// year 0 so, from the start's trees gathered from the ranks (issue 37 Build 1, round 33).
///
/// Errors: I/O errors naming the file.
pub(crate) fn snapshot_masked(dir: &Path, w: &World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat, masked: Option<&[bool]>) -> Result<()> {
    let inv = dir.join("inventory");
    if parts.inventory {
        match format {
            InventoryFormat::Csv => inventory::write_inventory_csv(&inv.join(format!("{label}.csv")), w)?,
            InventoryFormat::Parquet => inventory::write_inventory_parquet(&inv.join(format!("{label}.parquet")), w)?,
        }
        if parts.gpkg {
            inventory::write_inventory_gpkg(&inv.join(format!("{label}.gpkg")), w)?;
        }
    }
    if parts.maps {
        if parts.inventory {
            match format {
                InventoryFormat::Csv => inventory::write_regeneration_csv(&inv.join(format!("{label}_regeneration.csv")), w)?,
                InventoryFormat::Parquet => inventory::write_regeneration_parquet(&inv.join(format!("{label}_regeneration.parquet")), w)?,
            }
        }
        let m = dir.join("maps");
        let (sp, bp) = (m.join(format!("species_{label}.png")), m.join(format!("basal_area_{label}.png")));
        match masked {
            Some(masked) => plot::write_maps_masked(&sp, &bp, w, map_px, &plot::map_basal_area(w, map_px), masked)?,
            None => plot::write_maps(&sp, &bp, w, map_px)?,
        }
    }
    Ok(())
}

/// Whether the year of stand table row `r` removed trees by management (thinning or harvest:
/// [`DeathCause::Harvest`](crate::sim::trees::DeathCause::Harvest) deaths). Such a year gets a
/// plain snapshot besides the scheduled ones ([`run_scenario`]).
pub fn harvested(r: &StandRow) -> bool {
    r.deaths[crate::sim::trees::DeathCause::Harvest.index()] > 0
}

/// The management table's file in a run directory (a run with `[[management]]`:
/// [`stand_table::management_table_csv`]).
pub const MANAGEMENT_TABLE: &str = "management_table.csv";

/// The disk a fresh run of `scenario` from `world` (year 0) with `opts` will write
/// ([`super::disk::estimate`]).
pub fn disk_estimate(scenario: &Scenario, world: &World, opts: &RunOptions) -> super::disk::DiskEstimate {
    let w = super::disk::Writes { snapshots: opts.write_snapshots, inventory: opts.inventory, gpkg_years: opts.gpkg_years.as_deref(), map_px: opts.map_px };
    super::disk::estimate(scenario, world, &w)
}

/// The per-species stand table's file in a run directory ([`stand_table::stand_table_species_csv`]).
pub const SPECIES_TABLE: &str = "stand_table_species.csv";

fn tables(dir: &Path, rows: &[StandRow], w: &World, png: bool) -> Result<()> {
    let names: Vec<&str> = w.site.pool.iter().map(|&s| w.site.lib.species[s as usize].id.as_str()).collect();
    stand_table::write_stand_table(&dir.join("stand_table.csv"), rows, &names, w.site.area_ha)?;
    stand_table::write_stand_table_species(&dir.join(SPECIES_TABLE), rows, &names)?;
    // a run with `[[management]]`: the figures of each entry's area (issue 35 round 38)
    if rows.iter().any(|r| !r.management.is_empty()) {
        stand_table::write_management_table(&dir.join(MANAGEMENT_TABLE), rows, &names)?;
    }
    // the plot from year 1, as before the year-0 row (round 42): its file stays the same
    let years = if rows.first().is_some_and(|r| r.year == 0) { &rows[1..] } else { rows };
    if png && years.len() >= 2 {
        plot::plot_stand_table(&dir.join("stand_table.png"), years, w)?;
    }
    Ok(())
}

/// How a run steps its years: in this process ([`OneProcess`]: [`step_year_with`]) or as tiles
/// on several ranks (`job::tiled`). The run driver ([`run_scenario_with`]) writes every output
/// from the `world` it passes; a stepper makes that world whole whenever outputs follow.
pub trait Stepper {
    /// The world the run driver starts from: `scenario` on `site` at year 0 ([`World::new`],
    /// the default). `lean` is `Some` when nothing will read the world whole (no `on_snapshot`
    /// caller): a tiled run's rank 0 may then hold only its band of `site` and build only its
    /// tile's world ([`Lean`]: with the start's trees of every rank gathered when a year-0
    /// snapshot follows, [`Stepper::start_snapshot`]; without the start's trees when the run
    /// resumes from a checkpoint, which [`Stepper::resume`] then reads per rank; issue 37
    /// Build 1, rounds 33 and 37).
    ///
    /// Errors: as [`World::new`]; the stepper's.
    fn world(&mut self, site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario, lean: Option<Lean>) -> Result<World> {
        let _ = lean;
        Ok(World::new(site, lib, scenario)?)
    }
    /// Writes the year-0 snapshot `label` of `world` (as [`Stepper::snapshot`]'s default; a
    /// stepper whose world holds a part of the site gives the maps' masked pixels).
    ///
    /// Errors: I/O errors naming the file.
    fn start_snapshot(&mut self, dir: &Path, world: &World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat) -> Result<()> {
        snapshot(dir, world, label, parts, map_px, format)
    }
    /// Called once before the first year with the world as started (year 0) or resumed.
    ///
    /// Errors: the stepper's (a tiled run's exchange).
    fn begin(&mut self, world: &World) -> Result<()>;
    /// The stand table's year-0 row of a fresh run, after [`Stepper::begin`] (or
    /// [`Stepper::begin_shed`]): the start's trees, before any growth. Default: one process's
    /// [`crate::sim::stats::stand_row`] of `world`.
    ///
    /// Errors: the stepper's (a tiled run's exchange).
    fn start_row(&mut self, world: &World) -> Result<StandRow> {
        Ok(crate::sim::stats::stand_row(world))
    }
    /// Simulates one year of `world` into `report`, calling `on_season` after the phases that
    /// end a season when `seasonal`. With `full` false the stepper may leave `world` partly
    /// stale (a tiled run's rank 0 then holds only the year and the stand table row);
    /// [`Stepper::complete`] makes it whole.
    ///
    /// Errors: the stepper's (a tiled run's exchange, a halo too narrow).
    fn step(&mut self, world: &mut World, scenario: &Scenario, report: &mut YearReport, full: bool, on_season: &mut dyn FnMut(Season, &World)) -> Result<()>;
    /// Makes `world` whole after a [`Stepper::step`] with `full` false.
    ///
    /// Errors: the stepper's.
    fn complete(&mut self, world: &mut World) -> Result<()>;
    /// Reads the checkpoint of run directory `dir` into `world` (built from the scenario) for a
    /// resumed run, before [`Stepper::begin`]; returns the stand table so far. Default: one
    /// process's [`checkpoint::load_any`] (`checkpoint.bin`, or per-rank checkpoints
    /// assembled).
    ///
    /// Errors: as [`checkpoint::load_any`]; the stepper's.
    fn resume(&mut self, dir: &Path, world: &mut World) -> Result<Vec<StandRow>> {
        checkpoint::load_any(dir, world)
    }
    /// Writes the checkpoint of the year into run directory `dir` (the folders of the outputs
    /// it counts as written are synced before). Default: `checkpoint.bin` of `world` and
    /// `rows` ([`checkpoint::save`]), then the per-rank checkpoints it supersedes removed.
    ///
    /// Errors: I/O errors naming the file; the stepper's.
    fn save(&mut self, dir: &Path, world: &World, rows: &[StandRow]) -> Result<()> {
        checkpoint::save(&dir.join(checkpoint::FILE), world, rows)?;
        crate::output::sync_dir(dir)?;
        checkpoint::remove_ranks(dir)
    }
    /// True when [`Stepper::save`] reads `world` (so a checkpoint year steps with `full`);
    /// false when the stepper saves from its own state (a tiled run's per-rank checkpoints).
    fn save_reads_world(&self) -> bool {
        true
    }
    /// Writes the snapshot `label` (e.g. `year_0010`) into run directory `dir`: what `parts`
    /// asks for of the inventory, the GeoPackage inventory, the regeneration table and the
    /// species and basal-area maps (longest side `map_px`). Default: from `world`.
    ///
    /// Errors: I/O errors naming the file; the stepper's.
    fn snapshot(&mut self, dir: &Path, world: &mut World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat) -> Result<()> {
        snapshot(dir, world, label, parts, map_px, format)
    }
    /// True when [`Stepper::snapshot`] reads `world` (so a snapshot year steps with `full`);
    /// false when the stepper writes snapshots from its own state (a tiled run's ranks).
    fn snapshot_reads_world(&self) -> bool {
        true
    }
    /// Called once after [`Stepper::begin`] when nothing reads `world` whole again (the
    /// stepper neither snapshots nor saves from it, and no `on_snapshot` caller reads it): the
    /// stepper may cut `world` to what the run driver still reads of it (the year, the pool
    /// and library, the extent and georeferencing) and what [`Stepper::snapshot`] needs, with
    /// maps of longest side `map_px` (issue 37 Build 1: a tiled run's rank 0 then holds its
    /// tile, not the whole site). Default: nothing.
    ///
    /// Errors: the stepper's.
    fn shed(&mut self, _world: &mut World, _map_px: usize) -> Result<()> {
        Ok(())
    }
    /// [`Stepper::begin`] then [`Stepper::shed`], for a run in which nothing reads `world`
    /// whole after the start (the driver calls this instead of the two): a stepper may then
    /// cut `world` while it begins (a tiled run's rank 0: its world becomes its tile's without
    /// a copy of its tile beside the whole world). Default: the two in turn.
    ///
    /// Errors: as the two.
    fn begin_shed(&mut self, world: &mut World, map_px: usize) -> Result<()> {
        self.begin(world)?;
        self.shed(world, map_px)
    }
}

/// How the run starts when nothing will read its world whole ([`Stepper::world`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lean {
    /// Longest side of the maps (pixels): a tiled run's rank 0 keeps the maps' masked pixels
    /// of this size from the ranks.
    pub map_px: usize,
    /// A year-0 snapshot follows (a fresh run writing snapshots): the start's trees of every
    /// rank are gathered into the driver's world for it.
    pub year0: bool,
    /// The run resumes from the run directory's checkpoint (`--resume` with one there): no
    /// start's trees are placed; the stand comes from the checkpoint ([`Stepper::resume`]).
    pub resume: bool,
}

/// The stepper of one process: [`step_year_with`] on the whole world.
pub struct OneProcess;

impl Stepper for OneProcess {
    fn begin(&mut self, _: &World) -> Result<()> {
        Ok(())
    }
    fn step(&mut self, world: &mut World, scenario: &Scenario, report: &mut YearReport, _full: bool, on_season: &mut dyn FnMut(Season, &World)) -> Result<()> {
        step_year_with(world, scenario, report, on_season);
        Ok(())
    }
    fn complete(&mut self, _: &mut World) -> Result<()> {
        Ok(())
    }
}

/// Runs `scenario` on `site` with species from `lib`, writing the run directory.
///
/// Snapshots (species and basal-area maps; with the tree inventory, Parquet or CSV, the
/// GeoPackage `year_NNNN.gpkg` in the years of `gpkg_years` and the regeneration layer
/// `year_NNNN_regeneration.{parquet,csv}`) at year 0, every `snapshot_every` years, in every
/// year whose management removed trees ([`harvested`]: so every harvested tree is in some
/// inventory as `dead:harvest`) and at the end, labelled `year_NNNN`; the tree inventory only
/// at year 0, every `inventory_every` years ([`Scenario::inventory_year`]), harvest years, the
/// end and a year stopped at (plus `_spring`, `_summer`, `_autumn` when `seasonal_snapshots`,
/// in the scheduled inventory years only); checkpoint every `checkpoint_every` years and at the
/// end.
///
/// A fresh run (not `resume`) first removes the snapshots and the checkpoint of an earlier run
/// in the same directory ([`clear_snapshots`]), after checking that the run, inventory and
/// maps folders are writable (so a run that cannot write loses nothing of the earlier one).
/// A resumed run continues from `checkpoint.bin` or a tiled run's per-rank checkpoints
/// ([`checkpoint::find`]; its identity must match the scenario's:
/// [`crate::sim::checkpoint::restore`]; more `years` extend the run) and rewrites
/// `scenario.toml`; with no checkpoint yet but a `scenario.toml` or `species/` (a run killed
/// before its first checkpoint) it starts from year 0. Every start removes the temporary files a killed run
/// left ([`crate::output::remove_stale_temporaries`]). Before each checkpoint the run, inventory
/// and maps folders are synced ([`crate::output::sync_dir`]), so a resume after SIGKILL or a
/// power cut ends byte-identical to an unbroken run (tests/faults.rs).
///
/// Errors: I/O errors naming the file and the reason (a full disk, a file-size limit, an
/// unwritable folder; the last checkpoint stays whole); unknown species; with `resume`, no
/// run in the directory, or a checkpoint that is truncated, corrupt or of a different run.
pub fn run_scenario(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: RunOptions) -> Result<RunSummary> {
    run_scenario_with(scenario, site, lib, opts, &mut OneProcess)
}

/// [`run_scenario`] with the years stepped by `stepper` (one process, or a tiled run's rank 0:
/// `job::tiled`); every output is written here from the world the stepper keeps whole.
///
/// Errors: as [`run_scenario`], and the stepper's.
pub fn run_scenario_with(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, mut opts: RunOptions, stepper: &mut dyn Stepper) -> Result<RunSummary> {
    let dir = opts.out_dir.clone();
    // the world first: a refused scenario makes no folder (a tiled run's rank 0 of a run that
    // nothing reads whole builds its tile's world only: `lean`; a resumed one without the
    // start's trees, issue 37 round 37)
    let resuming = opts.resume && checkpoint::exists(&dir);
    let lean = opts.on_snapshot.is_none().then_some(Lean { map_px: opts.map_px, year0: opts.write_snapshots && !resuming, resume: resuming });
    // a resumed run says the scenario's warnings (entries beyond the run, ...) only once its
    // checkpoint is read and its years accepted, not before a refusal (trial 38, item 9)
    let mut world = if resuming {
        tracing::subscriber::with_default(tracing::subscriber::NoSubscriber::default(), || stepper.world(site, lib, scenario, lean))?
    } else {
        stepper.world(site, lib, scenario, lean)?
    };
    // the disk its outputs will take, said before a fresh run starts, and a run that would
    // fill the disk refused before it writes anything (round 42, trial 41 defect 14)
    if !resuming {
        let e = disk_estimate(scenario, &world, &opts);
        let free = super::disk::free_bytes(&dir);
        eprintln!("{}", super::disk::note(&e, &dir, free));
        super::disk::check(&e, &dir, free)?;
    }
    if let Some(f) = opts.on_start.as_mut() {
        f()?;
    }
    mkdir(&dir)?;
    if opts.write_snapshots {
        mkdir(&dir.join("inventory"))?;
        mkdir(&dir.join("maps"))?;
    }
    // temporary files a killed run left behind (never read, but they would pile up)
    // (the folders of a tiled run's partitioned snapshots too: `inventory/year_NNNN/`)
    let inv_dir = dir.join("inventory");
    let mut subs = vec![dir.clone(), inv_dir.clone(), dir.join("maps"), dir.join("maps").join("conditions"), dir.join("species"), dir.join(checkpoint::RANK_DIR)];
    if inv_dir.is_dir() {
        for e in std::fs::read_dir(&inv_dir).map_err(|err| Error::io(&inv_dir, err))? {
            let p = e.map_err(|err| Error::io(&inv_dir, err))?.path();
            if p.is_dir() && p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("year_")) {
                subs.push(p);
            }
        }
    }
    for sub in subs {
        crate::output::remove_stale_temporaries(&sub)?;
    }
    let ck = dir.join(checkpoint::FILE);
    let gp_years = opts.gpkg_years.clone();
    let last_year = scenario.years;
    let gp = move |y: u32| y == last_year || gp_years.as_ref().is_none_or(|ys| ys.contains(&y));
    let mut rows = Vec::new();
    let resume = opts.resume && (checkpoint::exists(&dir) || !started_here(&dir, &ck)?);
    if opts.resume && !resume {
        tracing::warn!("{}: no checkpoint yet (the run was stopped before its first one): starting from year 0", dir.display());
    }
    // a resumed run keeps the format its inventories were written in: a run directory holds
    // one format (year 0 is always there; `--inventory` only chooses for a fresh run)
    let format = match resume {
        true if dir.join("inventory").join("year_0000.csv").is_file() && !dir.join("inventory").join("year_0000.parquet").is_file() => InventoryFormat::Csv,
        true if dir.join("inventory").join("year_0000.parquet").is_file() => InventoryFormat::Parquet,
        _ => opts.inventory,
    };
    if format != opts.inventory {
        tracing::warn!("{}: resuming a run written as {}: its inventories stay {}", dir.display(), format.extension(), format.extension());
    }
    if resume {
        rows = stepper.resume(&dir, &mut world).map_err(|e| name_management_changes(e, &dir, scenario))?;
        // a run cannot be resumed to fewer years than it has already simulated: nothing would
        // be run, and `scenario.toml` would disagree with the stand table and the snapshots
        if world.stand.year > scenario.years {
            return Err(Error::Invalid {
                context: format!("--resume of {}", dir.display()),
                field: "years".into(),
                value: scenario.years.to_string(),
                expected: format!("at least {}, the year of the run's checkpoint (to run it longer, set years higher; to end it earlier, start a fresh run)", world.stand.year),
            }
            .into());
        }
        world.warn(scenario);
        if world.stand.year == scenario.years {
            // (trial 38, item 9: it printed a normal summary of 0 years)
            eprintln!("note: nothing to do: the run in {} is already at year {} (years = {}); to run it longer, set years higher", dir.display(), world.stand.year, scenario.years);
        }
        // a snapshot off this run's schedule at the checkpoint's year (one a stopped run wrote
        // so its state could be viewed, or the end of a shorter run now extended) is not one an
        // unbroken run writes: removed, so the resumed directory equals the unbroken run's
        let yc = world.stand.year;
        let cut = rows.last().is_some_and(|r| r.year == yc && harvested(r));
        // said on stderr, naming the files (found by a trial: they went without a word)
        let mut removed = Vec::new();
        let mut why = String::new();
        if !(scenario.snapshot_year(yc) || cut) {
            removed = remove_snapshot(&dir, &format!("year_{yc:04}"))?;
            why = format!("year {yc}, where the earlier run stopped, is not a snapshot year of this run (snapshot_every = {})", scenario.snapshot_every);
        } else if !(scenario.inventory_year(yc) || cut) {
            // a snapshot year of this run without a tree inventory (`inventory_every`): the
            // inventory a stopped run wrote there is removed, its maps stay
            removed = remove_inventory(&dir, &format!("year_{yc:04}"))?;
            why = format!("year {yc}, where the earlier run stopped, is not a tree-inventory year of this run (inventory_every)");
        } else if !gp(yc) {
            // the GeoPackages of a shorter run's final year, now extended, are not ones the
            // unbroken run writes (only its final year's, unless every snapshot's are asked for)
            let inv = dir.join("inventory");
            let stem = format!("year_{yc:04}");
            if inv.is_dir() {
                for e in std::fs::read_dir(&inv).map_err(|err| Error::io(&inv, err))? {
                    let e = e.map_err(|err| Error::io(&inv, err))?;
                    let (name, p) = (e.file_name().to_string_lossy().into_owned(), e.path());
                    if name.starts_with(&stem) && name.ends_with(".gpkg") && p.is_file() {
                        std::fs::remove_file(&p).map_err(|err| Error::io(&p, err))?;
                        removed.push(format!("inventory/{name}"));
                    } else if name == format!("{stem}_gpkg") && p.is_dir() {
                        // a tiled run's GeoPackage parts
                        std::fs::remove_dir_all(&p).map_err(|err| Error::io(&p, err))?;
                        removed.push(format!("inventory/{name}/"));
                    }
                }
            }
            removed.sort();
            why = format!("GeoPackages are written for a run's final year (now year {}), and year {yc} was the earlier run's", scenario.years);
        }
        if !removed.is_empty() {
            eprintln!("{}", resume_removal_note(&dir, &removed, &why));
        }
        // the scenario as run, `years` included (a resume may extend the run)
        crate::output::write_atomic(&dir.join("scenario.toml"), scenario_as_run(scenario)?.as_bytes())?;
    } else {
        // an old run's snapshots are only removed once the new files can be written beside them
        for sub in [dir.clone(), dir.join("inventory"), dir.join("maps")] {
            if sub.is_dir() {
                check_writable(&sub)?;
            }
        }
        clear_snapshots(&dir)?;
        // an earlier run's management table (this run may have no management)
        let mt = dir.join(MANAGEMENT_TABLE);
        if mt.is_file() {
            std::fs::remove_file(&mt).map_err(|e| Error::io(&mt, e))?;
        }
        // an earlier run's checkpoint must not be resumed after this run is interrupted
        checkpoint::remove_all(&dir)?;
        crate::output::write_atomic(&dir.join("scenario.toml"), scenario_as_run(scenario)?.as_bytes())?;
        if opts.write_snapshots {
            stepper.start_snapshot(&dir, &world, "year_0000", Parts { inventory: true, gpkg: gp(0), maps: true }, opts.map_px, format)?;
            if let Some(f) = opts.on_snapshot.as_mut() {
                f(0, &world);
            }
        }
    }
    let mut trees = world.stand.trees.len();
    // whether snapshots and checkpoints need the world whole on this process (one process, or
    // a caller that reads the world at snapshots); a tiled run writes them from the ranks
    let snap_world = stepper.snapshot_reads_world() || opts.on_snapshot.is_some();
    let save_world = stepper.save_reads_world();
    if !snap_world && !save_world {
        // nothing reads the world whole again (`complete` is never called): the stepper may
        // cut it to what the driver reads (a tiled run's rank 0: its tile, issue 37 Build 1)
        // as it begins
        stepper.begin_shed(&mut world, opts.map_px)?;
    } else {
        stepper.begin(&world)?;
    }
    // a fresh run's stand table starts with year 0, the start's trees before any growth
    // (trial 41, defect 7); a resumed run's rows hold it already (from its checkpoint)
    if !resume {
        rows.push(stepper.start_row(&world)?);
    }
    let t0 = Instant::now();
    let mut stopped = false;
    while world.stand.year < scenario.years {
        let y = world.stand.year + 1;
        let snap_year = opts.write_snapshots && scenario.snapshot_year(y);
        // the tree inventory (and regeneration table) of a snapshot year: every
        // `inventory_every` years, the last year; a harvest year and a stop add theirs below
        let inv_year = snap_year && scenario.inventory_year(y);
        let ty = Instant::now();
        let mut rep = YearReport::default();
        let mut err: Option<super::JobError> = None;
        let seasonal = inv_year && scenario.seasonal_snapshots;
        let (d, px, gp_y, fmt) = (dir.clone(), opts.map_px, gp(y), format);
        let checkpoint_year = y == scenario.years || (scenario.checkpoint_every > 0 && y % scenario.checkpoint_every == 0);
        let stop_before = opts.stop.as_ref().is_some_and(|s| s.load(Ordering::SeqCst));
        let full = (snap_year && snap_world) || (checkpoint_year && save_world) || (stop_before && (snap_world || save_world));
        stepper.step(&mut world, scenario, &mut rep, full, &mut |season, w| {
            if seasonal && season != Season::Winter && err.is_none() {
                let name = match season {
                    Season::Spring => "spring",
                    Season::Summer => "summer",
                    _ => "autumn",
                };
                if let Err(e) = snapshot(&d, w, &format!("year_{y:04}_{name}"), Parts { inventory: true, gpkg: gp_y, maps: false }, px, fmt) {
                    err = Some(e);
                }
            }
        })?;
        if let Some(e) = err {
            return Err(e);
        }
        // the year's notes (a thinning that removed nothing, and why), once: this loop runs on
        // rank 0 only, with rank 0's report
        for n in &rep.notes {
            eprintln!("{n}");
        }
        let trees_yr = rep.trees.max(1) as f64;
        trees = rep.trees;
        if let Some(r) = rep.row {
            rows.push(r);
        }
        let t_out = Instant::now();
        // a year whose management removed trees is a snapshot year too: its inventory holds
        // the removed trees (`dead:harvest`), whose stumps the pictures draw (issue 35)
        // (a harvest in a snapshot year that is not an inventory year gets its inventory too:
        // trial 46 found year 35's 702 cut trees in no file)
        let harvest = opts.write_snapshots && rows.last().is_some_and(|r| r.year == y && harvested(r));
        let cut = harvest && !snap_year;
        if cut && !full && snap_world {
            stepper.complete(&mut world)?;
        }
        let snap_year = snap_year || cut;
        let inv_year = inv_year || harvest;
        if snap_year {
            stepper.snapshot(&dir, &mut world, &format!("year_{y:04}"), Parts { inventory: inv_year, gpkg: gp(y), maps: true }, opts.map_px, format)?;
            tables(&dir, &rows, &world, true)?;
            if let Some(f) = opts.on_snapshot.as_mut() {
                f(y, &world);
            }
        }
        let stop_now = opts.stop.as_ref().is_some_and(|s| s.load(Ordering::SeqCst));
        if stop_now && !full && !cut && ((opts.write_snapshots && snap_world) || save_world) {
            stepper.complete(&mut world)?;
        }
        if checkpoint_year || stop_now {
            tables(&dir, &rows, &world, opts.write_snapshots)?;
            // what the checkpoint counts as written is on disk before the checkpoint is
            if opts.write_snapshots {
                for sub in [dir.join("inventory"), dir.join("maps")] {
                    crate::output::sync_dir(&sub)?;
                }
            }
            crate::output::sync_dir(&dir)?;
            stepper.save(&dir, &world, &rows)?;
        }
        if let Some(p) = opts.progress.as_mut() {
            let output_seconds = t_out.elapsed().as_secs_f64();
            p(&Progress { year: y, years: scenario.years, trees: rep.trees, trees_per_s: trees_yr / ty.elapsed().as_secs_f64().max(1e-9), phase_seconds: rep.phase_seconds, output_seconds });
        }
        if stop_now && y < scenario.years {
            stopped = true;
            // the year stopped at gets a whole snapshot, its tree inventory included, so its
            // state can be viewed; a resume removes what is off the schedule
            if opts.write_snapshots && !inv_year {
                stepper.snapshot(&dir, &mut world, &format!("year_{y:04}"), Parts { inventory: true, gpkg: true, maps: true }, opts.map_px, format)?;
                if !snap_year {
                    if let Some(f) = opts.on_snapshot.as_mut() {
                        f(y, &world);
                    }
                }
            }
            break;
        }
    }
    let year0 = (rows.first().is_some_and(|r| r.year == 0)).then(|| rows.remove(0));
    Ok(RunSummary { world, trees, rows, year0, stopped, seconds: t0.elapsed().as_secs_f64() })
}
