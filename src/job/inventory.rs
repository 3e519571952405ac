//! Reading inventory snapshots back from a run directory (ARCHITECTURE.md "Run directory").

use crate::output::schema::{INVENTORY_MEASURES, N_MEASURES};
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// One row of `inventory/year_NNNN.parquet` (or `.csv`): the columns of
/// [`crate::output::schema::INVENTORY`] (the field names are the column names).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct InventoryRow {
    /// Stable tree id.
    pub id: u64,
    /// Species id (as in `species/*.toml`).
    pub species: String,
    /// Easting from the site's south-west corner (m).
    pub x_m: f64,
    /// Northing from the site's south-west corner (m).
    pub y_m: f64,
    /// Ground elevation (m).
    pub z_m: f64,
    /// Age (years).
    pub age_yr: f32,
    /// Height (m).
    pub height_m: f32,
    /// Diameter at breast height (cm).
    pub dbh_cm: f32,
    /// Crown radius (m).
    pub crown_radius_m: f32,
    /// Height of the crown base (m).
    pub crown_base_m: f32,
    /// `alive` or `dead:<cause>`.
    pub status: String,
}

impl InventoryRow {
    /// A row from its id, species, measured values ([`INVENTORY_MEASURES`] order) and status.
    pub fn new(id: u64, species: String, v: [f32; N_MEASURES], status: String) -> InventoryRow {
        InventoryRow { id, species, x_m: v[0] as f64, y_m: v[1] as f64, z_m: v[2] as f64, age_yr: v[3], height_m: v[4], dbh_cm: v[5], crown_radius_m: v[6], crown_base_m: v[7], status }
    }
    /// The measured values in [`INVENTORY_MEASURES`] order.
    fn measures(&self) -> [f64; N_MEASURES] {
        [self.x_m, self.y_m, self.z_m, self.age_yr as f64, self.height_m as f64, self.dbh_cm as f64, self.crown_radius_m as f64, self.crown_base_m as f64]
    }
    /// The text a reader quotes for measure `k` (the value as its column's type prints it).
    fn measure_text(&self, k: usize) -> String {
        match k {
            0..=2 => self.measures()[k].to_string(),
            _ => (self.measures()[k] as f32).to_string(),
        }
    }
}

/// Reads one inventory: a file, Parquet (`.parquet`, [`crate::output::parquet::INVENTORY`]) or
/// CSV (any other name), or a partitioned snapshot of a tiled run, the folder `year_NNNN/` of
/// one part per rank (`part-RRRRR.parquet` or `.csv`, [`parts`]): its rows in the order of one
/// process's file (living trees in id order, then this year's dead in id order), so both
/// layouts read back the same rows.
///
/// # Errors
/// [`Error::Io`] when the file or folder cannot be read; [`Error::Format`] naming the line (CSV)
/// or the column (Parquet) when a file does not have the columns of ARCHITECTURE.md, or naming
/// a folder without parts.
pub fn read(path: &Path) -> Result<Vec<InventoryRow>> {
    read_filtered(path, |_| true)
}

/// The part files of the partitioned snapshot folder `dir` (a tiled run's
/// `inventory/year_NNNN/` or `year_NNNN_regeneration/`): `part-*.parquet`, else `part-*.csv`,
/// sorted by name (rank order). Other files (a part being written, `.part-….tmp`) are skipped.
///
/// # Errors
/// [`Error::Io`] when `dir` cannot be listed; [`Error::Format`] naming `dir` when it holds no
/// part.
pub fn parts(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let (mut pq, mut csv) = (Vec::new(), Vec::new());
    for e in rd {
        let e = e.map_err(|err| Error::io(dir, err))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if !name.starts_with("part-") {
            continue;
        }
        if name.ends_with(".parquet") {
            pq.push(e.path());
        } else if name.ends_with(".csv") {
            csv.push(e.path());
        }
    }
    let mut out = if pq.is_empty() { csv } else { pq };
    if out.is_empty() {
        return Err(Error::format(dir, "a partitioned snapshot folder without parts (expected part-RRRRR.parquet or part-RRRRR.csv files)").into());
    }
    out.sort();
    Ok(out)
}

/// Reads the rows of one inventory (a file or a partitioned folder, as [`read`]) for which
/// `keep` is true, in the order of one process's file, streaming within each file: the rows left
/// out are never held (an area of a snapshot of a million trees keeps only its own;
/// `sylva export`).
///
/// # Errors
/// As [`read`]; every row is parsed and checked, kept or not.
pub fn read_filtered(path: &Path, mut keep: impl FnMut(&InventoryRow) -> bool) -> Result<Vec<InventoryRow>> {
    if path.is_dir() {
        let mut rows = Vec::new();
        for p in parts(path)? {
            rows.extend(read_file_filtered(&p, &mut keep)?);
        }
        // each part is in (alive before dead, id) order: the parts merged in that order are the
        // rows of one process's file (a stable sort; ids are unique)
        rows.sort_by_key(|r| (r.status != "alive", r.id));
        return Ok(rows);
    }
    read_file_filtered(path, keep)
}

/// [`read_filtered`] of one inventory file, Parquet or CSV, in file order.
fn read_file_filtered(path: &Path, mut keep: impl FnMut(&InventoryRow) -> bool) -> Result<Vec<InventoryRow>> {
    if is_parquet(path) {
        return read_parquet(path, keep);
    }
    let mut rdr = csv::Reader::from_path(path).map_err(|e| Error::format(path, e.to_string()))?;
    let mut rows = Vec::new();
    let mut rec = csv::StringRecord::new();
    let headers = rdr.headers().map_err(|e| Error::format(path, e.to_string()))?.clone();
    let mut line = 2usize;
    while rdr.read_record(&mut rec).map_err(|e| Error::format(path, format!("line {line}: {e}")))? {
        let row: InventoryRow = rec.deserialize(Some(&headers)).map_err(|e| Error::format(path, format!("line {line}: {}", csv_field_error(&e, &headers, &rec))))?;
        check_row(path, || format!("line {line}"), &row)?;
        if keep(&row) {
            rows.push(row);
        }
        line += 1;
    }
    Ok(rows)
}

/// A CSV value error told by its column: `column NAME = VALUE: what is wrong` (the csv crate
/// says only "field N").
fn csv_field_error(e: &csv::Error, headers: &csv::StringRecord, rec: &csv::StringRecord) -> String {
    if let csv::ErrorKind::Deserialize { err, .. } = e.kind() {
        if let Some(f) = err.field() {
            let name = headers.get(f as usize).unwrap_or("?");
            let value = rec.get(f as usize).unwrap_or("");
            return format!("column {name} = {value:?}: {}", err.kind());
        }
    }
    e.to_string()
}

/// A Parquet reading error of `path` as [`Error::Format`] naming the file once.
fn parquet_error(path: &Path, e: crate::output::OutputError) -> Error {
    match e {
        crate::output::OutputError::Io { source, .. } => Error::format(path, source.to_string()),
        e => Error::format(path, e.to_string()),
    }
}

/// Checks that the values of inventory row `r` (at `at()`, e.g. "line 7") can be a tree: each
/// measure within its column's accepted values ([`INVENTORY_MEASURES`]: finite positions
/// (|x|, |y| ≤ 10⁷ m), age 0–10,000 years, height 0–200 m, DBH 0–1,000 cm, crown radius 0–100 m,
/// crown base 0–200 m), status `alive` or `dead:<cause>`.
///
/// # Errors
/// [`Error::Format`] naming the file, the row, the tree id, the column, the value and what was
/// expected.
fn check_row(path: &Path, at: impl Fn() -> String, r: &InventoryRow) -> Result<()> {
    let bad = |col: &str, v: String, want: &str| -> Result<()> { Err(Error::format(path, format!("{} (tree id {}): column {col} = {v}: expected {want}", at(), r.id)).into()) };
    // the text of a value only for the error (formatting every value of a million rows took
    // most of `sylva render`'s reading time; issue 34)
    for (k, (v, c)) in r.measures().into_iter().zip(&INVENTORY_MEASURES).enumerate() {
        if !c.accepts(v) {
            return bad(c.name, r.measure_text(k), c.expect);
        }
    }
    if r.status != "alive" && !r.status.starts_with("dead:") {
        return bad("status", format!("{:?}", r.status), "\"alive\" or \"dead:<cause>\"");
    }
    Ok(())
}

/// True for a `.parquet` file name.
fn is_parquet(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "parquet")
}

/// A Parquet column of `table` that [`crate::output::parquet::read_table`] guarantees.
fn column<'a, T>(c: Option<&'a [T]>, path: &Path, name: &str) -> Result<&'a [T]> {
    c.ok_or_else(|| Error::format(path, format!("no column {name:?}")))
}

/// [`read_filtered`] of a Parquet inventory.
fn read_parquet(path: &Path, mut keep: impl FnMut(&InventoryRow) -> bool) -> Result<Vec<InventoryRow>> {
    let mut c = crate::output::parquet::read_table(path, &crate::output::parquet::INVENTORY).map_err(|e| parquet_error(path, e))?;
    // the text columns moved into the rows, not copied
    let mut take = |name: &str| c.texts.iter_mut().find(|t| t.0 == name).map(|t| std::mem::take(&mut t.1)).ok_or_else(|| Error::format(path, format!("no column {name:?}")));
    let (sp, st) = (take("species")?, take("status")?);
    let id = column(c.int("id"), path, "id")?;
    let (x, y, z) = (column(c.double("x_m"), path, "x_m")?, column(c.double("y_m"), path, "y_m")?, column(c.double("z_m"), path, "z_m")?);
    let f = |n: &str| column(c.float(n), path, n);
    let (age, h, d, cr, cb) = (f("age_yr")?, f("height_m")?, f("dbh_cm")?, f("crown_radius_m")?, f("crown_base_m")?);
    let mut rows = Vec::new();
    for (i, (species, status)) in sp.into_iter().zip(st).enumerate().take(c.rows) {
        let row = InventoryRow { id: id[i] as u64, species, x_m: x[i], y_m: y[i], z_m: z[i], age_yr: age[i], height_m: h[i], dbh_cm: d[i], crown_radius_m: cr[i], crown_base_m: cb[i], status };
        check_row(path, || format!("row {}", i + 1), &row)?;
        if keep(&row) {
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Snapshot files of a run directory as `(year, season suffix or "", path)`, sorted by year then
/// season order (spring, summer, autumn, winter, then plain); `year_NNNN.parquet`, the folder
/// `year_NNNN/` of a tiled run's parts (one per rank, [`parts`]; [`read`] reads it as one
/// table) or, from runs written with `--inventory csv` or before Parquet, `year_NNNN.csv` (when
/// several are there: the Parquet file, then the folder, then the CSV); the regeneration-layer
/// files `year_NNNN_regeneration.*` and the GeoPackage parts `year_NNNN_gpkg/` are not tree
/// inventories and are skipped.
pub fn snapshots(run_dir: &Path) -> Result<Vec<(u32, String, PathBuf)>> {
    let dir = run_dir.join("inventory");
    let rd = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut out = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| Error::io(&dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        // a partitioned snapshot of a tiled run: the folder `year_NNNN/` of its ranks' parts
        let folder = entry.path().is_dir();
        let stem = match folder {
            true => name.strip_prefix("year_"),
            false => name.strip_prefix("year_").and_then(|s| s.strip_suffix(".parquet").or_else(|| s.strip_suffix(".csv"))),
        };
        let Some(stem) = stem else { continue };
        let (num, season) = match stem.split_once('_') {
            Some((n, s)) => (n, s.to_string()),
            None => (stem, String::new()),
        };
        if season == "regeneration" || season == "gpkg" {
            // the regeneration layer's cohorts (`year_NNNN_regeneration.csv`) and a tiled run's
            // GeoPackage parts (`year_NNNN_gpkg/`), not tree inventories
            continue;
        }
        if let Ok(y) = num.parse::<u32>() {
            out.push((y, season, entry.path()));
        }
    }
    let order = |s: &str| match s {
        "spring" => 0,
        "summer" => 1,
        "autumn" => 2,
        "winter" => 3,
        _ => 4,
    };
    // Parquet file, then partitioned folder, then CSV file within a snapshot; then one per
    // snapshot
    let kind = |p: &Path| if is_parquet(p) { 0 } else if p.is_dir() { 1 } else { 2 };
    out.sort_by_key(|a| (a.0, order(&a.1), kind(&a.2)));
    out.dedup_by(|b, a| {
        let same = a.0 == b.0 && a.1 == b.1;
        if same {
            // said once per process and file pair: a run extended by an older version, or a
            // file converted by hand, may hold both
            static TOLD: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
            if let Ok(mut told) = TOLD.lock() {
                if !told.contains(&b.2) {
                    tracing::warn!("{} and {} hold the same snapshot: reading the first, not the second", a.2.display(), b.2.display());
                    told.push(b.2.clone());
                }
            }
        }
        same
    });
    Ok(out)
}

/// The living trees of `w` as inventory rows (status `alive`), in tree-store order, as the
/// inventory CSV of the same year would hold them.
pub fn rows_from_world(w: &crate::sim::World) -> Vec<InventoryRow> {
    let t = &w.stand.trees;
    (0..t.len()).map(|i| InventoryRow::new(t.id[i], w.site.lib.species[t.species[i] as usize].id.clone(), crate::output::inventory::tree_measures(&w.site.lib, t, i), "alive".into())).collect()
}

/// One row of `inventory/year_NNNN_regeneration.csv` (the regeneration layer: one sapling
/// cohort per light cell and species, ARCHITECTURE.md).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct RegenRow {
    /// Light cell index.
    pub cell: u32,
    /// Species id.
    pub species: String,
    /// Light-cell centre, easting (m).
    pub x_m: f64,
    /// Light-cell centre, northing (m).
    pub y_m: f64,
    /// Stems of the cohort.
    pub stems: u32,
    /// Stems per hectare of the light cell.
    pub stems_per_ha: f64,
    /// Mean height (m).
    pub height_m: f32,
    /// Age (years).
    pub age_yr: f32,
}

/// The regeneration-layer file of the plain snapshot of `year` in `run_dir`
/// (`inventory/year_NNNN_regeneration.parquet`, else `.csv`, else a tiled run's folder
/// `year_NNNN_regeneration/` of one part per rank, read as one table in light-cell order as one
/// process writes it), read when it exists; `None` when none does (runs written without it).
///
/// # Errors
/// [`Error::Format`] naming the file and line of a row without the columns of ARCHITECTURE.md.
pub fn read_regeneration(run_dir: &Path, year: u32) -> Result<Option<Vec<RegenRow>>> {
    let inv = run_dir.join("inventory");
    let pq = inv.join(format!("year_{year:04}_regeneration.parquet"));
    let path = inv.join(format!("year_{year:04}_regeneration.csv"));
    let folder = inv.join(format!("year_{year:04}_regeneration"));
    if pq.is_file() {
        return Ok(Some(read_regeneration_file(&pq)?));
    }
    if path.is_file() {
        return Ok(Some(read_regeneration_file(&path)?));
    }
    if folder.is_dir() {
        let mut rows = Vec::new();
        for p in parts(&folder)? {
            rows.extend(read_regeneration_file(&p)?);
        }
        // all of a light cell's cohorts are in its owner's part, in pool order: a stable sort
        // by cell gives one process's order
        rows.sort_by_key(|r| r.cell);
        return Ok(Some(rows));
    }
    // a run that wrote the layer for other years lost this one: say so (the saplings of that
    // year are not drawn), rather than thinning the pictures without a word
    let others = std::fs::read_dir(&inv).map(|rd| rd.flatten().any(|e| e.file_name().to_string_lossy().contains("_regeneration"))).unwrap_or(false);
    if others {
        tracing::warn!("{}: no regeneration layer for year {year} (neither {}, {} nor {}); its saplings are left out", run_dir.display(), pq.display(), path.display(), folder.display());
    }
    Ok(None)
}

/// The rows of one regeneration-layer file, Parquet (`.parquet`) or CSV.
///
/// # Errors
/// [`Error::Io`] / [`Error::Format`] naming the file (and the line of a bad CSV row).
fn read_regeneration_file(path: &Path) -> Result<Vec<RegenRow>> {
    if is_parquet(path) {
        let pq = path;
        let c = crate::output::parquet::read_table(pq, &crate::output::parquet::REGENERATION).map_err(|e| parquet_error(pq, e))?;
        let (cell, sp, stems) = (column(c.int("cell"), pq, "cell")?, column(c.text("species"), pq, "species")?, column(c.int("stems"), pq, "stems")?);
        let (x, y, per_ha) = (column(c.double("x_m"), pq, "x_m")?, column(c.double("y_m"), pq, "y_m")?, column(c.double("stems_per_ha"), pq, "stems_per_ha")?);
        let (h, age) = (column(c.float("height_m"), pq, "height_m")?, column(c.float("age_yr"), pq, "age_yr")?);
        return Ok((0..c.rows).map(|i| RegenRow { cell: cell[i] as u32, species: sp[i].clone(), x_m: x[i], y_m: y[i], stems: stems[i] as u32, stems_per_ha: per_ha[i], height_m: h[i], age_yr: age[i] }).collect());
    }
    let mut rdr = csv::Reader::from_path(path).map_err(|e| Error::format(path, e.to_string()))?;
    let mut rows = Vec::new();
    for (i, rec) in rdr.deserialize().enumerate() {
        let row: RegenRow = rec.map_err(|e| Error::format(path, format!("line {}: {e}", i + 2)))?;
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_filtered_read_keeps_the_chosen_rows_in_order_and_checks_the_others() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("year_0001.csv");
        let head = "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status\n";
        let rows: String = (0..6).map(|i| format!("{i},beech,{}.5,10.0,500.0,30,12.0,15.0,2.0,5.0,alive\n", i * 10)).collect();
        std::fs::write(&path, format!("{head}{rows}")).unwrap();
        let all = read(&path).unwrap();
        assert_eq!(all.len(), 6);
        let mut seen = 0;
        let near = read_filtered(&path, |r| {
            seen += 1;
            r.x_m > 15.0 && r.x_m < 45.0
        })
        .unwrap();
        assert_eq!(seen, 6);
        assert_eq!(near.iter().map(|r| r.id).collect::<Vec<_>>(), vec![2, 3, 4]);
        assert_eq!(near[0], all[2]);
        // a bad row is an error naming its line, even when it would have been left out
        std::fs::write(&path, format!("{head}{rows}9,beech,x,10.0,500.0,30,12.0,15.0,2.0,5.0,alive\n")).unwrap();
        let e = read_filtered(&path, |_| false).unwrap_err().to_string();
        assert!(e.contains("line 8"), "{e}");
    }
}
