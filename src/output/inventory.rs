//! Tree inventories: CSV, Parquet ([`super::parquet`]) and the final year's GeoPackage point
//! layer ([`super::gpkg`]), columns as [`super::schema::INVENTORY`].

use super::schema::{INVENTORY_MEASURES, N_MEASURES};
use super::Result;
use crate::sim::trees::{DeadTree, TreeStore};
use crate::sim::World;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The inventory CSV header ([`super::schema::INVENTORY`]'s names; a test holds them equal).
pub const HEADER: &str = "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status";

/// One inventory record.
struct Rec<'a> {
    id: u64,
    species: &'a str,
    v: [f32; N_MEASURES],
    status: String,
}

/// The inventory's measured values ([`INVENTORY_MEASURES`]: x, y, z, age, height, DBH, crown
/// radius, crown base) of living tree `i` of `t`, species from `lib`; the crown radius is the
/// crown's outline as it stands ([`TreeStore::crown_outline`]).
pub fn tree_measures(lib: &crate::species::SpeciesLibrary, t: &TreeStore, i: usize) -> [f32; N_MEASURES] {
    [t.x[i], t.y[i], t.z[i], t.age[i], t.height[i], t.dbh[i], t.crown_outline(lib, i), t.crown_base[i]]
}

/// The inventory's measured values ([`INVENTORY_MEASURES`]) of dead tree `d`.
fn dead_measures(d: &DeadTree) -> [f32; N_MEASURES] {
    [d.x, d.y, d.z, d.age, d.height, d.dbh, d.crown_radius, d.crown_base]
}

fn records(w: &World) -> Vec<Rec<'_>> {
    records_where(w, |_, _| true)
}

/// The records of the living and this year's dead trees of `w` standing at `(x, y)` (m) where
/// `keep(x, y)`: living in store (id) order, then the dead in id order.
fn records_where(w: &World, keep: impl Fn(f32, f32) -> bool) -> Vec<Rec<'_>> {
    let t = &w.stand.trees;
    let mut out: Vec<Rec> = (0..t.len())
        .filter(|&i| keep(t.x[i], t.y[i]))
        .map(|i| Rec { id: t.id[i], species: &w.site.lib.species[t.species[i] as usize].id, v: tree_measures(&w.site.lib, t, i), status: "alive".into() })
        .collect();
    let mut dead: Vec<Rec> = w.scratch.dead.iter().filter(|d| keep(d.x, d.y)).map(|d| Rec { id: d.id, species: &w.site.lib.species[d.species as usize].id, v: dead_measures(d), status: format!("dead:{}", d.cause.name()) }).collect();
    dead.sort_by_key(|r| r.id);
    out.extend(dead);
    out
}

/// The inventory as CSV text: living trees (status `alive`) in id order, then the trees that
/// died in the current year (`dead:<cause>`). Positions and sizes in metres (DBH cm), 2 decimals.
pub fn inventory_csv(w: &World) -> String {
    let mut s = String::with_capacity(80 * (w.stand.trees.len() + 1));
    s.push_str(HEADER);
    s.push('\n');
    for r in records(w) {
        csv_line(&mut s, &r);
    }
    s
}

/// Appends the inventory CSV line of `r` (with its newline) to `s`: the measures with their
/// columns' decimals.
fn csv_line(s: &mut String, r: &Rec) {
    let _ = write!(s, "{},{}", r.id, r.species);
    for (v, c) in r.v.iter().zip(&INVENTORY_MEASURES) {
        let _ = write!(s, ",{v:.*}", c.decimals);
    }
    let _ = writeln!(s, ",{}", r.status);
}

/// The regeneration-layer CSV header.
pub const REGENERATION_HEADER: &str = "cell,species,x_m,y_m,stems,stems_per_ha,height_m,age_yr";

/// The regeneration layer (sapling cohorts below the recruitment height, [`crate::sim::regen`])
/// as CSV text, one row per cohort in (light cell, pool) order: light cell index, species id,
/// cell centre (m, world coordinates), stems, stems per hectare of the light cell, mean height
/// (m, 2 decimals), age (years).
pub fn regeneration_csv(w: &World) -> String {
    let c = &w.stand.cohorts;
    let per_ha = 10_000.0 / w.site.light.cell_area_m2();
    let mut s = String::with_capacity(48 * (c.len() + 1));
    s.push_str(REGENERATION_HEADER);
    s.push('\n');
    for i in 0..c.len() {
        let k = c.cell[i] as usize;
        let (x, y) = w.site.light.centre(k);
        let sp = w.site.pool.get(c.pool[i] as usize).map(|&s| w.site.lib.species[s as usize].id.as_str()).unwrap_or("?");
        let _ = writeln!(s, "{},{},{:.2},{:.2},{},{:.0},{:.2},{:.0}", k, sp, x, y, c.stems[i], c.stems[i] as f64 * per_ha, c.height[i], c.age[i]);
    }
    s
}

/// Writes the regeneration-layer CSV ([`regeneration_csv`]) atomically.
pub fn write_regeneration_csv(path: &Path, w: &World) -> Result<()> {
    crate::output::write_atomic(path, regeneration_csv(w).as_bytes())
}

/// Writes the inventory CSV atomically.
pub fn write_inventory_csv(path: &Path, w: &World) -> Result<()> {
    crate::output::write_atomic(path, inventory_csv(w).as_bytes())
}

/// The file format of a run's inventories and regeneration tables (`--inventory`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InventoryFormat {
    /// Apache Parquet with GeoParquet metadata ([`super::parquet`]): `year_NNNN.parquet`,
    /// `year_NNNN_regeneration.parquet` (the default: about a tenth of the CSV's size).
    #[default]
    Parquet,
    /// CSV text: `year_NNNN.csv`, `year_NNNN_regeneration.csv`.
    Csv,
}

impl InventoryFormat {
    /// The file extension (`parquet` or `csv`).
    pub fn extension(self) -> &'static str {
        match self {
            InventoryFormat::Parquet => "parquet",
            InventoryFormat::Csv => "csv",
        }
    }
}

impl std::str::FromStr for InventoryFormat {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "parquet" => Ok(InventoryFormat::Parquet),
            "csv" => Ok(InventoryFormat::Csv),
            _ => Err(format!("inventory format {s:?}: expected \"parquet\" or \"csv\"")),
        }
    }
}

/// Writes the inventory of `w` as Parquet ([`super::parquet::INVENTORY`]) atomically: the values
/// of [`inventory_csv`], the points in the terrain's CRS ([`PointGeoRef::of`]).
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_inventory_parquet(path: &Path, w: &World) -> Result<()> {
    super::parquet::csv_to_parquet(inventory_csv(w).as_bytes(), "the inventory", path, &super::parquet::INVENTORY, &PointGeoRef::of(w))
}

/// Writes the regeneration layer of `w` as Parquet ([`super::parquet::REGENERATION`])
/// atomically: the values of [`regeneration_csv`].
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_regeneration_parquet(path: &Path, w: &World) -> Result<()> {
    super::parquet::csv_to_parquet(regeneration_csv(w).as_bytes(), "the regeneration layer", path, &super::parquet::REGENERATION, &PointGeoRef::of(w))
}

/// Rewrites the CSV table `csv` (an inventory or regeneration table, by `table`) as the Parquet
/// file beside it (same name, `.parquet`) and removes the CSV: a tiled run's rank 0 merges
/// the ranks' CSV parts, then this (the same bytes as one process's Parquet file).
///
/// Errors: [`super::OutputError::Io`] naming the file.
pub fn csv_file_to_parquet(csv: &Path, table: &super::parquet::Table, w: &World) -> Result<()> {
    csv_file_to_parquet_beside(csv, table, w)?;
    std::fs::remove_file(csv).map_err(|e| super::OutputError::io(csv, e))
}

/// As [`csv_file_to_parquet`], keeping the CSV (a tiled run's last rank writes the GeoPackage
/// from it meanwhile).
///
/// Errors: [`super::OutputError::Io`] naming the file.
pub fn csv_file_to_parquet_beside(csv: &Path, table: &super::parquet::Table, w: &World) -> Result<()> {
    let f = std::fs::File::open(csv).map_err(|e| super::OutputError::io(csv, e))?;
    super::parquet::csv_to_parquet(std::io::BufReader::new(f), &csv.display().to_string(), &csv.with_extension("parquet"), table, &PointGeoRef::of(w))
}

pub use super::georef::PointGeoRef;

/// Writes the inventory of `w` as a GeoPackage ([`super::gpkg::csv_to_points`]) atomically: one
/// point layer `inventory` with the columns and values of [`inventory_csv`] (names and units of
/// [`super::parquet::INVENTORY`]) and the point (`x_m`, `y_m`) in the terrain's CRS
/// ([`PointGeoRef::of`]; EPSG code as `srs_id`, or the undefined Cartesian SRS −1 on a local
/// grid), so the trees overlay the map GeoTIFFs in QGIS.
///
/// Errors: [`super::OutputError::Io`] naming `path`.
pub fn write_inventory_gpkg(path: &Path, w: &World) -> Result<()> {
    gpkg_from(inventory_csv(w).as_bytes(), "the inventory", path, w)
}

/// Writes the inventory CSV file `csv` as the GeoPackage `gpkg` ([`write_inventory_gpkg`]'s
/// bytes for the same rows; a tiled run's rank 0 writes it from the merged CSV). The CSV stays.
///
/// Errors: [`super::OutputError::Io`] naming `gpkg` (and the CSV in the message).
pub fn csv_file_to_gpkg(csv: &Path, gpkg: &Path, w: &World) -> Result<()> {
    let f = std::fs::File::open(csv).map_err(|e| super::OutputError::io(csv, e))?;
    gpkg_from(std::io::BufReader::new(f), &csv.display().to_string(), gpkg, w)
}

/// The inventory GeoPackage `path` from CSV text `csv` (of `what`) on `w`'s site.
fn gpkg_from(csv: impl std::io::Read, what: &str, path: &Path, w: &World) -> Result<()> {
    let desc = "Sylva tree inventory (columns and units as the CSV and Parquet inventories: ARCHITECTURE.md)";
    super::gpkg::csv_to_points(csv, what, path, &super::parquet::INVENTORY, &PointGeoRef::of(w), desc).map_err(|e| super::OutputError::io(path, e))
}

// ---- parts of a tiled run (issue 17): each rank writes the lines of its own trees and
// cohorts, in the order of the whole file; rank 0 merges the parts by their keys into the file
// one process writes, byte for byte.

/// Writes a rank's part of the inventory: the CSV lines (no header) of the trees of `w`
/// standing where `keep(x, y)` to `csv`; living trees in id order, then the dead in id order.
/// Written atomically like every file ([`crate::output::write_atomic_with`]); the part files
/// are temporaries that [`merge_inventory_csv`] reads.
///
/// Errors: [`super::OutputError::Io`] naming the part file.
pub fn write_inventory_part(csv: &Path, w: &World, keep: impl Fn(f32, f32) -> bool) -> Result<()> {
    let recs = records_where(w, keep);
    crate::output::write_atomic_with(csv, |f| {
        let mut s = String::with_capacity(96);
        for r in &recs {
            s.clear();
            csv_line(&mut s, r);
            f.write_all(s.as_bytes())?;
        }
        Ok(())
    })
}

/// Writes a rank's part of the regeneration CSV: the lines (no header) of every cohort of `w`
/// (the rank's own), in (light cell, pool) order.
///
/// Errors: [`super::OutputError::Io`] naming the part file.
pub fn write_regeneration_part(path: &Path, w: &World) -> Result<()> {
    let text = regeneration_csv(w);
    let body = text.split_once('\n').map_or("", |(_, b)| b);
    crate::output::write_atomic(path, body.as_bytes())
}

/// Merge key of an inventory line: living (0, `alive_end` ends the line) before dead (1),
/// then the tree id.
fn inventory_key(line: &str, alive_end: &str, id_field: impl Fn(&str) -> Option<&str>) -> Option<(u8, u64)> {
    let dead = !line.ends_with(alive_end);
    let id = id_field(line)?.parse().ok()?;
    Some((dead as u8, id))
}

/// A part file being merged: its reader, its current line, the line's number.
type PartReader = (std::io::BufReader<std::fs::File>, String, usize);
/// A part's current line in the merge heap: its key and the part's index, least first.
type HeapEntry = std::cmp::Reverse<((u8, u64), usize)>;

/// Merges the sorted part files `parts` (one line per record, each sorted by `key`) into `out`,
/// writing `sep` between records; records of equal key keep their part's order (a light cell's
/// cohorts come from one part). Streams: one line per part in memory.
///
/// Errors: I/O errors; a line without a key (`InvalidData`, naming the part file and line).
fn merge_lines(out: &mut impl Write, parts: &[std::path::PathBuf], key: impl Fn(&str) -> Option<(u8, u64)>, sep: &[u8]) -> std::io::Result<()> {
    use std::io::BufRead;
    let mut readers = Vec::with_capacity(parts.len());
    for p in parts {
        let f = std::fs::File::open(p).map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", p.display())))?;
        readers.push((std::io::BufReader::new(f), String::new(), 0usize));
    }
    let mut heap = std::collections::BinaryHeap::new();
    let next = |k: usize, r: &mut PartReader| -> std::io::Result<Option<HeapEntry>> {
        r.1.clear();
        if r.0.read_line(&mut r.1)? == 0 {
            return Ok(None);
        }
        r.2 += 1;
        let k2 = key(r.1.trim_end_matches('\n')).ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{} line {}: no key in {:?}", parts[k].display(), r.2, r.1)))?;
        Ok(Some(std::cmp::Reverse((k2, k))))
    };
    for (k, r) in readers.iter_mut().enumerate() {
        if let Some(e) = next(k, r)? {
            heap.push(e);
        }
    }
    let mut first = true;
    while let Some(std::cmp::Reverse((_, k))) = heap.pop() {
        if !first {
            out.write_all(sep)?;
        }
        first = false;
        let r = &mut readers[k];
        out.write_all(r.1.trim_end_matches('\n').as_bytes())?;
        if let Some(e) = next(k, r)? {
            heap.push(e);
        }
    }
    Ok(())
}

/// Writes the inventory CSV `path` atomically from the ranks' parts ([`write_inventory_part`]):
/// the bytes [`write_inventory_csv`] writes for the whole world.
///
/// Errors: [`super::OutputError::Io`] naming `path` (and in the message the part file).
pub fn merge_inventory_csv(path: &Path, parts: &[std::path::PathBuf]) -> Result<()> {
    merge_csv(path, HEADER, parts, |l| inventory_key(l, ",alive", |l| l.split(',').next()))
}

/// Writes the CSV `path` atomically: `header`, then the lines of the sorted `parts` merged by
/// `key` ([`merge_lines`]), every line ending with a newline (none after the header when no
/// part has a line).
///
/// Errors: [`super::OutputError::Io`] naming `path` (and in the message the part file).
fn merge_csv(path: &Path, header: &str, parts: &[std::path::PathBuf], key: impl Fn(&str) -> Option<(u8, u64)>) -> Result<()> {
    crate::output::write_atomic_with(path, |f| {
        f.write_all(header.as_bytes())?;
        f.write_all(b"\n")?;
        merge_lines(f, parts, key, b"\n")?;
        if parts.iter().any(|p| std::fs::metadata(p).is_ok_and(|m| m.len() > 0)) {
            f.write_all(b"\n")?;
        }
        Ok(())
    })
}

/// Writes the regeneration CSV `path` atomically from the ranks' parts
/// ([`write_regeneration_part`]): the bytes [`write_regeneration_csv`] writes for the whole
/// world (cohorts in light-cell order; a cell's cohorts all come from the rank owning it).
///
/// Errors: [`super::OutputError::Io`] naming `path` (and in the message the part file).
pub fn merge_regeneration_csv(path: &Path, parts: &[std::path::PathBuf]) -> Result<()> {
    merge_csv(path, REGENERATION_HEADER, parts, |l| l.split(',').next()?.parse().ok().map(|c| (0, c)))
}

#[cfg(test)]
mod tests {

    #[test]
    fn csv_headers_are_the_parquet_tables_columns() {
        // one list of columns: the CSV headers and the Parquet schemas name the same columns in
        // the same order (output::parquet::INVENTORY, REGENERATION)
        assert_eq!(HEADER, super::super::schema::INVENTORY.header());
        assert_eq!(REGENERATION_HEADER, super::super::schema::REGENERATION.header());
    }
    use super::*;
    use crate::sim::{step_year, Scenario, YearReport};

    /// Parts split by position (the tiles of a tiled run), merged: the bytes of the whole
    /// inventory CSV and regeneration CSV, and the GeoPackage written from the merged CSV is the
    /// one written from the whole world, byte for byte; with no trees at all, the header only.
    #[test]
    fn merged_parts_are_the_whole_files() {
        let toml = "name = \"parts\"\nyears = 22\nseed = 3\nspecies = [\"beech\"]\nlight_cell_m = 10.0\n\
            [terrain]\nuniform = { width = 20, height = 12, cell_m = 20.0, elevation_m = 300.0, indices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0] }\n\
            [[start]]\nkind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[100.0, 100.0], [300.0, 150.0]]\ntrees_per_source = 4\n";
        let sc = Scenario::from_toml_str(toml, "parts").unwrap();
        let mut w = World::new(sc.site().unwrap(), &crate::sim::fixtures::library(), &sc).unwrap();
        for _ in 0..22 {
            step_year(&mut w, &sc, &mut YearReport::default());
        }
        assert!(w.stand.trees.len() > 8 && !w.stand.cohorts.is_empty(), "{} trees, {} cohorts", w.stand.trees.len(), w.stand.cohorts.len());
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        for (case, trees) in [("trees", true), ("empty", false)] {
            let mut w = w.clone();
            if !trees {
                w.stand.trees = Default::default();
                w.scratch.dead.clear();
                w.stand.cohorts = Default::default();
            }
            let (csv, gp, rg) = (d.join(format!("{case}.csv")), d.join(format!("{case}.gpkg")), d.join(format!("{case}_r.csv")));
            write_inventory_csv(&csv, &w).unwrap();
            write_inventory_gpkg(&gp, &w).unwrap();
            write_regeneration_csv(&rg, &w).unwrap();
            let mut parts = (Vec::new(), Vec::new());
            for k in 0..3 {
                let band = move |x: f32, _: f32| ((x / 134.0) as usize).min(2) == k;
                let (pc, pr) = (d.join(format!("{case}.{k}.csv.part")), d.join(format!("{case}.{k}.r.part")));
                write_inventory_part(&pc, &w, band).unwrap();
                let mut wk = w.clone();
                let light = wk.site.light;
                let c = &w.stand.cohorts;
                let mut own = crate::sim::cohorts::Cohorts::default();
                for i in 0..c.len() {
                    let (x, y) = light.centre(c.cell[i] as usize);
                    if band(x as f32, y as f32) {
                        own.push(c.get(i));
                    }
                }
                wk.stand.cohorts = own;
                write_regeneration_part(&pr, &wk).unwrap();
                parts.0.push(pc);
                parts.1.push(pr);
            }
            let (mc, mg, mr) = (d.join(format!("{case}.m.csv")), d.join(format!("{case}.m.gpkg")), d.join(format!("{case}_r.m.csv")));
            merge_inventory_csv(&mc, &parts.0).unwrap();
            csv_file_to_gpkg(&mc, &mg, &w).unwrap();
            merge_regeneration_csv(&mr, &parts.1).unwrap();
            for (a, b) in [(&csv, &mc), (&gp, &mg), (&rg, &mr)] {
                assert!(std::fs::read(a).unwrap() == std::fs::read(b).unwrap(), "{case}: {} and {} differ", a.display(), b.display());
            }
            if !trees {
                assert_eq!(std::fs::read_to_string(&mc).unwrap(), format!("{HEADER}\n"));
            }
        }
        // a part line without a key is refused naming the part
        let bad = d.join("bad.part");
        std::fs::write(&bad, "not-an-id,beech\n").unwrap();
        let e = merge_inventory_csv(&d.join("bad.csv"), &[bad]).unwrap_err().to_string();
        assert!(e.contains("bad.part line 1"), "{e}");
    }
}
