//! Tree inventories: CSV, Parquet ([`super::parquet`]) and the final year's GeoPackage point
//! layer ([`super::gpkg`]), columns as [`super::schema::INVENTORY`].

use super::schema::{INVENTORY_MEASURES, N_MEASURES};
use super::Result;
use crate::sim::trees::{DeadTree, TreeStore};
use crate::sim::World;
use std::fmt::Write as _;
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
    inventory_csv_where(w, |_, _| true)
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

/// The inventory GeoPackage `path` from CSV text `csv` (of `what`) on `w`'s site.
fn gpkg_from(csv: impl std::io::Read, what: &str, path: &Path, w: &World) -> Result<()> {
    let desc = "Sylva tree inventory (columns and units as the CSV and Parquet inventories: ARCHITECTURE.md)";
    super::gpkg::csv_to_points(csv, what, path, &super::parquet::INVENTORY, &PointGeoRef::of(w), desc).map_err(|e| super::OutputError::io(path, e))
}

// ---- parts of a tiled run (issue 37 Build 4): each rank writes its own trees and cohorts as
// a complete file of the snapshot's partitioned dataset; nothing is merged (until Build 4 the
// ranks wrote CSV lines that rank 0 merged by tree id into the file of one process).

/// The file name of rank `rank`'s part of a partitioned snapshot (`part-RRRRR.EXT`, five
/// digits: the names sort in rank order), `ext` e.g. `parquet`, `csv`, `gpkg`.
pub fn part_name(rank: usize, ext: &str) -> String {
    format!("part-{rank:05}.{ext}")
}

/// The inventory CSV text (header and lines, as [`inventory_csv`]) of the trees of `w` standing
/// where `keep(x, y)` (m): living trees in id order, then this year's dead in id order.
fn inventory_csv_where(w: &World, keep: impl Fn(f32, f32) -> bool) -> String {
    let recs = records_where(w, keep);
    let mut s = String::with_capacity(80 * (recs.len() + 1));
    s.push_str(HEADER);
    s.push('\n');
    for r in &recs {
        csv_line(&mut s, r);
    }
    s
}

/// Writes a rank's part of an inventory snapshot: the trees of `w` standing where `keep(x, y)`
/// (m; a rank's own trees) as a complete inventory file of `format` at `path` (header, living
/// trees in id order, then this year's dead in id order; the Parquet part with its own
/// GeoParquet metadata, its bounding box that of its rows), and with `gpkg` the same rows as the
/// GeoPackage `gpkg` ([`write_inventory_gpkg`]'s layer). The parts of all ranks, read back as one
/// table ([`crate::job::inventory::read`] merges them by status and id), are the rows of one
/// process's file. Written atomically; the CSV lines are streamed to a temporary file
/// (`.NAME.csv.PID.tmp` beside `path`, removed after) that the Parquet and GeoPackage writers
/// read, so the rank's inventory text is never held in memory.
///
/// Errors: [`super::OutputError::Io`] naming the file.
pub fn write_inventory_part(path: &Path, gpkg: Option<&Path>, w: &World, keep: impl Fn(f32, f32) -> bool, format: InventoryFormat) -> Result<()> {
    use std::io::Write as _;
    let recs = records_where(w, keep);
    let lines = |f: &mut std::io::BufWriter<std::fs::File>| -> std::io::Result<()> {
        f.write_all(HEADER.as_bytes())?;
        f.write_all(b"\n")?;
        let mut s = String::with_capacity(96);
        for r in &recs {
            s.clear();
            csv_line(&mut s, r);
            f.write_all(s.as_bytes())?;
        }
        f.flush()
    };
    let csv = match format {
        InventoryFormat::Csv => {
            crate::output::write_atomic_with(path, lines)?;
            path.to_path_buf()
        }
        InventoryFormat::Parquet => {
            // (through write_atomic like every file: a killed run leaves only temporaries)
            let tmp = crate::output::temporary_path(&path.with_extension("csv"));
            crate::output::write_atomic_with(&tmp, lines)?;
            tmp
        }
    };
    drop(recs);
    let open = || std::fs::File::open(&csv).map(std::io::BufReader::new).map_err(|e| super::OutputError::io(&csv, e));
    let r = (|| -> Result<()> {
        if format == InventoryFormat::Parquet {
            super::parquet::csv_to_parquet(open()?, "the inventory part", path, &super::parquet::INVENTORY, &PointGeoRef::of(w))?;
        }
        if let Some(g) = gpkg {
            gpkg_from(open()?, "the inventory part", g, w)?;
        }
        Ok(())
    })();
    if format == InventoryFormat::Parquet {
        let _ = std::fs::remove_file(&csv);
    }
    r
}

/// Writes a rank's part of a regeneration table: every cohort of `w` (a rank's tile holds only
/// its own) as a complete regeneration file of `format` at `path`, in (light cell, pool) order.
///
/// Errors: [`super::OutputError::Io`] naming the file.
pub fn write_regeneration_part(path: &Path, w: &World, format: InventoryFormat) -> Result<()> {
    match format {
        InventoryFormat::Csv => write_regeneration_csv(path, w),
        InventoryFormat::Parquet => write_regeneration_parquet(path, w),
    }
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

    /// Parts split by position (the tiles of a tiled run), each a complete file in its
    /// partitioned folder: read back as one table ([`crate::job::inventory::read`],
    /// [`crate::job::inventory::read_regeneration`]) they are the rows of the whole world's file,
    /// in its order, in both formats; each GeoPackage part holds its band's trees; with no
    /// trees at all, the parts hold no rows.
    #[test]
    fn parts_read_back_as_the_whole_files() {
        let toml = "name = \"parts\"\nyears = 22\nseed = 3\nspecies = [\"beech\"]\nlight_cell_m = 10.0\n\
            [terrain]\nuniform = { width = 20, height = 12, cell_m = 20.0, elevation_m = 300.0, indices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0] }\n\
            [[start]]\nkind = \"seed_sources\"\nspecies = \"beech\"\npoints = [[100.0, 100.0], [300.0, 150.0]]\ntrees_per_source = 4\n";
        let sc = Scenario::from_toml_str(toml, "parts").unwrap();
        let mut w = World::new(sc.site().unwrap(), &crate::sim::fixtures::library(), &sc).unwrap();
        for _ in 0..22 {
            step_year(&mut w, &sc, &mut YearReport::default());
        }
        assert!(w.stand.trees.len() > 8 && !w.stand.cohorts.is_empty(), "{} trees, {} cohorts", w.stand.trees.len(), w.stand.cohorts.len());
        // a dead tree of this year among them: the parts' dead come after every part's living
        let dead = DeadTree { id: 1, species: 0, x: 390.0, y: 10.0, z: 300.0, age: 5.0, height: 2.0, dbh: 1.0, crown_radius: 1.0, crown_base: 0.5, year: 22, cause: crate::sim::trees::DeathCause::Stress };
        w.scratch.dead.push(dead);
        let tmp = tempfile::tempdir().unwrap();
        for (case, trees) in [("trees", true), ("empty", false)] {
            for format in [InventoryFormat::Parquet, InventoryFormat::Csv] {
                let d = tmp.path().join(format!("{case}_{}", format.extension())).join("inventory");
                let (fol, rfol, gfol) = (d.join("year_0022"), d.join("year_0022_regeneration"), d.join("year_0022_gpkg"));
                for f in [&fol, &rfol, &gfol] {
                    std::fs::create_dir_all(f).unwrap();
                }
                let mut w = w.clone();
                if !trees {
                    w.stand.trees = Default::default();
                    w.scratch.dead.clear();
                    w.stand.cohorts = Default::default();
                }
                let ext = format.extension();
                let whole = d.join(format!("year_0022.{ext}"));
                match format {
                    InventoryFormat::Parquet => write_inventory_parquet(&whole, &w).unwrap(),
                    InventoryFormat::Csv => write_inventory_csv(&whole, &w).unwrap(),
                }
                let rwhole = d.join(format!("year_0021_regeneration.{ext}"));
                write_regeneration_part(&rwhole, &w, format).unwrap();
                let mut gpkg_rows = 0;
                for k in 0..3 {
                    let band = move |x: f32, _: f32| ((x / 134.0) as usize).min(2) == k;
                    let g = gfol.join(part_name(k, "gpkg"));
                    write_inventory_part(&fol.join(part_name(k, ext)), Some(&g), &w, band, format).unwrap();
                    let conn = rusqlite::Connection::open(&g).unwrap();
                    let n: i64 = conn.query_row("SELECT count(*) FROM inventory", [], |r| r.get(0)).unwrap();
                    let want = (0..w.stand.trees.len()).filter(|&i| band(w.stand.trees.x[i], w.stand.trees.y[i])).count() + w.scratch.dead.iter().filter(|t| band(t.x, t.y)).count();
                    assert_eq!(n as usize, want, "{case} {ext}: GeoPackage part {k}");
                    gpkg_rows += n as usize;
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
                    write_regeneration_part(&rfol.join(part_name(k, ext)), &wk, format).unwrap();
                }
                assert_eq!(gpkg_rows, w.stand.trees.len() + w.scratch.dead.len());
                let (a, b) = (crate::job::inventory::read(&whole).unwrap(), crate::job::inventory::read(&fol).unwrap());
                assert_eq!(a.len(), w.stand.trees.len() + w.scratch.dead.len());
                assert!(a == b, "{case} {ext}: the parts read back differ from the whole file");
                if trees {
                    // the parts split the trees: each holds some, none all
                    let sizes: Vec<usize> = (0..3).map(|k| crate::job::inventory::read(&fol.join(part_name(k, ext))).unwrap().len()).collect();
                    assert!(sizes.iter().all(|&n| n > 0 && n < a.len()), "{sizes:?}");
                    // living first, then the dead (id 1 among them, from the east part)
                    let first_dead = b.iter().position(|r| r.status != "alive").unwrap();
                    assert!(first_dead > 0 && b[first_dead..].iter().all(|r| r.status.starts_with("dead:")) && b[first_dead..].iter().any(|r| r.id == 1));
                }
                // the regeneration layer: the whole file (read as year 21) and the parts (year 22)
                let ra = crate::job::inventory::read_regeneration(d.parent().unwrap(), 21).unwrap().unwrap();
                let rb = crate::job::inventory::read_regeneration(d.parent().unwrap(), 22).unwrap().unwrap();
                assert_eq!(ra.len(), w.stand.cohorts.len());
                assert!(ra == rb, "{case} {ext}: the regeneration parts read back differ");
            }
        }
        // a folder without parts is refused naming it
        let e = crate::job::inventory::read(tmp.path()).unwrap_err().to_string();
        assert!(e.contains("without parts"), "{e}");
    }
}
