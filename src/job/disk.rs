//! The disk a run's outputs will take, estimated before it starts, and the refusal of a run whose
//! estimate exceeds the free space of its output folder (round 42, trial 41 defect 14: an
//! inventory every year for 10,000 years would have written about 250 GB onto 30 GB free,
//! without a word). The estimate is the sum of the files the run driver writes
//! ([`super::run::run_scenario_with`]) from the scenario's schedule, the site's cells and an
//! expected tree count; the per-tree and per-file sizes are the ones measured on the default
//! run (docs/guide.md, "Cost"; BENCHMARKS.md, round 22's disk policy and round 42). It is an
//! estimate, not a bound: a stand denser than [`FULL_STAND_TREES_HA`] writes more.

use crate::output::inventory::InventoryFormat;
use crate::sim::scenario::Scenario;
use crate::sim::world::World;
use std::path::Path;

/// Trees per hectare of unmasked area the estimate expects of a stocked stand once it has
/// closed: individual trees of the tree store, stems and planted seedlings. The default run
/// holds about 1.0 M trees on its 432 ha at year 150 (2,340/ha; README, trial 41); an
/// unmanaged planting self-thins from its planting density towards the species' Reineke line
/// (trial 41: beech 4,444/ha at 1.5 m). A run starting with more trees counts its start's.
pub const FULL_STAND_TREES_HA: f64 = 2_500.0;

/// Years over which the estimate's stand fills from the start's trees to
/// [`FULL_STAND_TREES_HA`], with the square of the time (`(y / FILL_YEARS)²`): calibrated on the
/// default run, whose stand regenerates from seed sources on bare ground: 73 trees/ha at year
/// 30 (31,410 on 432 ha; round 42), 329 stems/ha at year 50 and 1,731 at 100, about 2,340 trees
/// at 150 (trial 41); the square gives 156, 434, 1,736 and 2,500. A planting is stocked from
/// the start (its own count holds). A choice of the estimate, not a model of the stand.
pub const FILL_YEARS: f64 = 120.0;

/// Bytes per tree of a GeoParquet inventory (zstd pages): about 23 (guide, "Cost": 43 MB for
/// the default run's 4 inventories of up to 1 M trees; round 22).
pub const PARQUET_BYTES_PER_TREE: f64 = 23.0;
/// Bytes per tree of a CSV inventory: about 65 (guide: 65 MB a year of a million trees).
pub const CSV_BYTES_PER_TREE: f64 = 65.0;
/// Bytes per tree of a GeoPackage inventory: about 130 (guide: 124 MB for the final year's
/// 1.0 M trees; SQLite stores each number in 8 bytes).
pub const GPKG_BYTES_PER_TREE: f64 = 130.0;
/// Bytes per tree of a checkpoint (zstd): about 34 (guide: 34 MB for 1.0 M trees; a 1 ha
/// run's 1,534 trees: 58 KB). The run keeps one (while it writes the next, two stand for a
/// moment: not counted).
pub const CHECKPOINT_BYTES_PER_TREE: f64 = 34.0;
/// Bytes per fine seed cell of a checkpoint (zstd): the seed grids of every pool species, one
/// `f32` a fine cell of at most [`crate::sim::world::FINE_SEED_CELL_M`] since round 45's
/// two-scale dispersal (16–25 times the coarse cells before), stored whole: about 3 (main's
/// default run at year 75, round 46: 4.58 MB for 1.47 M seed cells, 3.11 bytes a cell, the
/// parts of the checkpoint compressed apart; BENCHMARKS.md).
pub const CHECKPOINT_BYTES_PER_SEED_CELL: f64 = 3.0;
/// Bytes of a checkpoint's regeneration cohorts per light cell and pool species (zstd): about
/// 2.8 (the same checkpoint: 3.86 MB for 388,512 cohorts, 9.9 bytes a cohort, over 172,800
/// light cells and 8 species; until round 45 the estimate counted 0.5 for cohorts and seeds).
pub const CHECKPOINT_COHORT_BYTES_PER_CELL_SPECIES: f64 = 2.8;
/// Bytes of an inventory file's fixed part (schema, GeoParquet and PROJJSON metadata): about
/// 16 KB (a 1 ha run's Parquet inventories of 1,500–3,400 trees: 33–53 KB; round 42).
pub const FILE_BYTES: f64 = 16.0 * 1024.0;
/// Bytes of a GeoPackage's fixed part (SQLite pages, the GeoPackage and spatial reference
/// tables): about 96 KB.
pub const GPKG_FILE_BYTES: f64 = 96.0 * 1024.0;
/// Bytes of a snapshot's maps (species and basal area, PNG with legend and GeoTIFF) whatever the
/// site's size: about 56 KB (a 1 ha run's: 56.6 KB; round 42).
pub const MAP_SNAPSHOT_BYTES: f64 = 56.0 * 1024.0;
/// Bytes of a snapshot's maps per map cell of 20 m ([`crate::output::plot::MIN_MAP_CELL_M`]):
/// about 20 (the default run's 31 snapshots: 8 MB of maps over 432 ha, 10,800 cells).
pub const MAP_BYTES_PER_CELL: f64 = 20.0;
/// Bytes of the regeneration table per light cell at an inventory (the cohorts: a few per cell
/// and species): about 4 MB for the default run's 4 tables over 173,000 cells of 5 m.
pub const REGEN_BYTES_PER_CELL: f64 = 6.0;
/// Bytes of the stand table's plot (`stand_table.png`, 1200 × 1350 px): about 440 KB.
pub const PLOT_BYTES: f64 = 450.0 * 1024.0;

/// What a run writes, as its options say (`job::run::RunOptions`; given apart so this module
/// needs nothing of the run driver).
#[derive(Debug, Clone, Copy)]
pub struct Writes<'a> {
    /// Snapshots (inventories, maps) are written.
    pub snapshots: bool,
    /// The inventories' format.
    pub inventory: InventoryFormat,
    /// The years with a GeoPackage besides the last (`None`: every inventory year).
    pub gpkg_years: Option<&'a [u32]>,
    /// Longest side of the maps (pixels).
    pub map_px: usize,
}

/// What a run's outputs will take, by part (bytes).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DiskEstimate {
    /// Tree inventories (Parquet or CSV; the seasonal ones too) and their regeneration tables.
    pub inventories: f64,
    /// GeoPackage inventories.
    pub geopackages: f64,
    /// Species and basal-area maps.
    pub maps: f64,
    /// The final checkpoint.
    pub checkpoint: f64,
    /// Stand, per-species and management tables and the stand table's plot.
    pub tables: f64,
    /// Snapshot years counted (year 0, the schedule, the years a management entry is due).
    pub snapshots: usize,
    /// Inventory years counted.
    pub inventory_years: usize,
    /// Trees expected at the end.
    pub trees: f64,
}

impl DiskEstimate {
    /// The whole estimate (bytes).
    pub fn total(&self) -> f64 {
        self.inventories + self.geopackages + self.maps + self.checkpoint + self.tables
    }
}

/// The trees the estimate expects at year `y`: the start's `n0`, or more as the stand fills
/// towards [`FULL_STAND_TREES_HA`] over `area_ha` ([`FILL_YEARS`]).
pub fn expected_trees(n0: f64, area_ha: f64, y: u32) -> f64 {
    let full = FULL_STAND_TREES_HA * area_ha;
    n0 + (full - n0).max(0.0) * (y as f64 / FILL_YEARS).min(1.0).powi(2)
}

/// Estimates the bytes a fresh run of `scenario` writes, from its world at year 0 (`world`: the
/// start's trees, the site's unmasked area, light cells and species pool) and the run's options
/// (snapshots on or off, the inventory format, the GeoPackage years, the maps' size): every
/// snapshot year ([`Scenario::snapshot_year`], and every year a management entry other than a
/// planting is due, which the driver snapshots when it removes trees) has two maps; every
/// inventory year ([`Scenario::inventory_year`], the same management years) an inventory of the
/// trees expected then ([`expected_trees`]; four with `seasonal_snapshots`), a regeneration
/// table and, in the GeoPackage years, a GeoPackage; the checkpoint of the final stand; the
/// tables a few hundred bytes per year and species, and the stand table's plot. The pictures of `sylva run` (frames, film,
/// stills: about 50 MB for the default run) are not counted.
pub fn estimate(scenario: &Scenario, world: &World, opts: &Writes<'_>) -> DiskEstimate {
    let area = world.site.area_ha.max(0.0);
    let n0 = world.stand.trees.len() as f64;
    let np = world.site.pool.len() as f64;
    let cells = world.site.light.len() as f64;
    let years = scenario.years;
    let managed = |y: u32| world.site.management.iter().any(|op| !matches!(op.action, crate::sim::management::Action::Planting { .. }) && op.spec.due(y).is_some());
    let per_tree = match opts.inventory {
        InventoryFormat::Parquet => PARQUET_BYTES_PER_TREE,
        InventoryFormat::Csv => CSV_BYTES_PER_TREE,
    };
    let mut e = DiskEstimate { trees: expected_trees(n0, area, years), ..Default::default() };
    if opts.snapshots {
        // the maps' cells: 20 m ones, at most `map_px` on the longer side
        let map_cells = (area * 1e4 / (crate::output::plot::MIN_MAP_CELL_M * crate::output::plot::MIN_MAP_CELL_M)).min((opts.map_px * opts.map_px) as f64);
        for y in 0..=years {
            let cut = y > 0 && managed(y);
            if !(scenario.snapshot_year(y) || cut) {
                continue;
            }
            e.snapshots += 1;
            e.maps += MAP_SNAPSHOT_BYTES + MAP_BYTES_PER_CELL * map_cells;
            if !(scenario.inventory_year(y) || cut) {
                continue;
            }
            e.inventory_years += 1;
            let n = expected_trees(n0, area, y);
            let copies = if scenario.seasonal_snapshots && y > 0 && scenario.inventory_year(y) { 4.0 } else { 1.0 };
            e.inventories += copies * (FILE_BYTES + n * per_tree) + 1024.0 + cells * REGEN_BYTES_PER_CELL;
            let gpkg = y == years || opts.gpkg_years.is_none_or(|ys| ys.contains(&y));
            if gpkg {
                e.geopackages += copies * (GPKG_FILE_BYTES + n * GPKG_BYTES_PER_TREE);
            }
        }
    }
    // the checkpoint of the final stand, with the seed grids and cohorts
    let seed_cells: f64 = world.stand.seeds.iter().map(|g| g.data.len() as f64).sum();
    e.checkpoint = checkpoint_bytes(e.trees, seed_cells, cells, np);
    // stand table ~ 200 B + 24 B per species a row, the per-species table ~ 160 B per species
    // and year, and the plot
    e.tables = (years as f64 + 1.0) * (200.0 + 24.0 * np + 160.0 * np) + PLOT_BYTES;
    e
}

/// Bytes of a checkpoint (`sim::checkpoint`, zstd) of a stand of `trees` trees whose pool of
/// `species` species has `seed_cells` fine seed cells in all (the lengths of the world's seed
/// grids, `World::stand.seeds`) over `light_cells` light cells: 4 KB of identity and stand
/// table, [`CHECKPOINT_BYTES_PER_TREE`] a tree, [`CHECKPOINT_BYTES_PER_SEED_CELL`] a seed cell
/// and [`CHECKPOINT_COHORT_BYTES_PER_CELL_SPECIES`] a light cell and species for the cohorts.
/// Within ±25 % of a real checkpoint (`tests/checkpoint_size.rs`; the default run's, round 46:
/// BENCHMARKS.md).
pub fn checkpoint_bytes(trees: f64, seed_cells: f64, light_cells: f64, species: f64) -> f64 {
    4096.0 + trees * CHECKPOINT_BYTES_PER_TREE + seed_cells * CHECKPOINT_BYTES_PER_SEED_CELL + light_cells * species * CHECKPOINT_COHORT_BYTES_PER_CELL_SPECIES
}

/// Bytes free to an unprivileged user on the file system holding `dir`, or the nearest folder
/// above it that exists (statvfs: available blocks × fragment size); `None` where unknown.
pub fn free_bytes(dir: &Path) -> Option<u64> {
    let mut p = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    while !p.exists() {
        p = match p.parent() {
            Some(q) if !q.as_os_str().is_empty() => q,
            _ => Path::new("."),
        };
        if p == Path::new(".") {
            break;
        }
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let c = std::ffi::CString::new(p.as_os_str().as_bytes()).ok()?;
        // SAFETY: statvfs writes into the zeroed struct we own; `c` is a valid C string.
        let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
        // SAFETY: as above.
        if unsafe { libc::statvfs(c.as_ptr(), &mut s) } != 0 {
            return None;
        }
        Some((s.f_bavail as u64).saturating_mul(s.f_frsize as u64))
    }
    #[cfg(not(unix))]
    {
        let _ = p;
        None
    }
}

/// `b` bytes as people read them: `12.3 MB`, `4.56 GB` (decimal units, as `df -H`).
pub fn human(b: f64) -> String {
    match b {
        b if b >= 1e12 => format!("{:.2} TB", b / 1e12),
        b if b >= 1e9 => format!("{:.2} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.1} MB", b / 1e6),
        b => format!("{:.0} kB", (b / 1e3).max(1.0)),
    }
}

/// The line the run prints before it starts: the estimate, its parts and the free space of
/// `dir` (`free`, bytes; `None` where unknown).
pub fn note(e: &DiskEstimate, dir: &Path, free: Option<u64>) -> String {
    format!(
        "note: the outputs of this run will take about {} in {} (estimate: {} inventories {}, GeoPackages {}, {} snapshots' maps {}, checkpoint {}, tables {}; about {:.0} trees at the end){}",
        human(e.total()),
        dir.display(),
        e.inventory_years,
        human(e.inventories),
        human(e.geopackages),
        e.snapshots,
        human(e.maps),
        human(e.checkpoint),
        human(e.tables),
        e.trees,
        free.map_or(String::new(), |f| format!("; {} free there", human(f as f64)))
    )
}

/// Refuses a run whose estimate `e` exceeds `free`, the bytes free for `dir` (nothing refused
/// where `free` is unknown).
///
/// Errors: [`crate::Error::Io`] naming `dir`, the estimate and the free space, and what takes
/// less (fewer inventories, fewer years, no GeoPackage at every snapshot, Parquet not CSV).
pub fn check(e: &DiskEstimate, dir: &Path, free: Option<u64>) -> crate::Result<()> {
    let Some(f) = free else { return Ok(()) };
    if e.total() > f as f64 {
        return Err(crate::Error::io(
            dir,
            std::io::Error::other(format!(
                "not enough free space for this run's outputs: they would take about {} (estimate: {} inventories {}, GeoPackages {}, maps {}, checkpoint {}), and {} is free there; free space, choose another --out, or write less (a larger inventory_every or snapshot_every, fewer years, --inventory parquet rather than csv, GeoPackages of the final year only)",
                human(e.total()),
                e.inventory_years,
                human(e.inventories),
                human(e.geopackages),
                human(e.maps),
                human(e.checkpoint),
                human(f as f64)
            )),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stand_fills_from_its_start_and_a_planting_counts_its_own() {
        // bare ground, 432 ha: 0 at the start, a quarter at 60 years, full (1.08 M) from 120
        assert_eq!(expected_trees(0.0, 432.0, 0), 0.0);
        assert!((expected_trees(0.0, 432.0, 60) - 270_000.0).abs() < 1e-6);
        assert!((expected_trees(0.0, 432.0, 150) - 1_080_000.0).abs() < 1e-6);
        // a 1 ha planting of 4,444 keeps its own count
        assert_eq!(expected_trees(4444.0, 1.0, 100), 4444.0);
    }

    #[test]
    fn a_run_larger_than_the_free_space_is_refused_naming_folder_estimate_and_free_space() {
        let e = DiskEstimate { inventories: 250e9, ..Default::default() };
        let dir = Path::new("/data/runs/long");
        let err = check(&e, dir, Some(30_000_000_000)).unwrap_err().to_string();
        assert!(err.contains("/data/runs/long") && err.contains("250.00 GB") && err.contains("30.00 GB is free"), "{err}");
        assert!(check(&e, dir, Some(300_000_000_000)).is_ok());
        assert!(check(&e, dir, None).is_ok());
        assert_eq!(human(1234.0), "1 kB");
        assert_eq!(human(12_345_678.0), "12.3 MB");
    }
}
