//! What the viewer reads from a run directory (ARCHITECTURE.md "Run directory"): the snapshot
//! years, each snapshot's inventory (read once, on first use) and render instances, the trees at
//! any year in between (interpolated as the timelapse is), the stand table, the overlays
//! (condition maps of the site; species and basal-area maps of a snapshot) and what is known of
//! one tree (species, age, height, DBH, crown, status or cause of death).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::conditions::SiteConditions;
use crate::grid::Grid;
use crate::job::inventory::{self, InventoryRow};
use crate::job::maps::Layer;
use crate::job::scene;
use crate::render::scene::TreeInstance;
use crate::render::timelapse;
use crate::species::{Season, SpeciesLibrary};
use crate::{Error, Result};

/// Side of the cells of the species and basal-area overlays (m), as the run's maps use at most.
pub const STAND_MAP_CELL_M: f64 = 20.0;

/// The stand table (`stand_table.csv`): column names and one row of numbers per year.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StandTable {
    /// Column names, `year` first.
    pub columns: Vec<String>,
    /// Rows of values in column order.
    pub rows: Vec<Vec<f64>>,
}

impl StandTable {
    /// Reads `stand_table.csv`.
    ///
    /// # Errors
    /// [`Error::Io`] when it cannot be read; [`Error::Format`] naming the line of a value that is
    /// not a number or a row of the wrong length.
    pub fn read(path: &Path) -> Result<Self> {
        let mut rdr = csv::Reader::from_path(path).map_err(|e| Error::format(path, e.to_string()))?;
        let columns: Vec<String> = rdr.headers().map_err(|e| Error::format(path, e.to_string()))?.iter().map(str::to_string).collect();
        let mut rows = Vec::new();
        for (i, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(|e| Error::format(path, format!("line {}: {e}", i + 2)))?;
            let row: std::result::Result<Vec<f64>, _> = rec.iter().map(|v| v.trim().parse::<f64>()).collect();
            rows.push(row.map_err(|e| Error::format(path, format!("line {}: {e} (expected numbers)", i + 2)))?);
        }
        Ok(StandTable { columns, rows })
    }

    /// The series `(year, value)` of column `name` (empty when there is no such column).
    pub fn series(&self, name: &str) -> Vec<[f64; 2]> {
        let Some(k) = self.columns.iter().position(|c| c == name) else { return Vec::new() };
        self.rows.iter().filter_map(|r| Some([*r.first()?, *r.get(k)?])).collect()
    }
}

/// What the viewer shows of one tree.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeInfo {
    /// The inventory row of the snapshot it was read from.
    pub row: InventoryRow,
    /// Year of that snapshot.
    pub year: u32,
    /// Status: `alive`, or the cause of death with the year it was recorded
    /// (`dead: stress (year 40)`), or the first snapshot without the tree when its death fell
    /// between snapshots (`gone by year 45 (cause not recorded between snapshots)`).
    pub fate: String,
}

/// An overlay painted on the terrain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Overlay {
    /// Land-cover colours (no overlay).
    None,
    /// The `k`-th condition map of [`crate::job::maps::site_layers`].
    Condition(usize),
    /// Dominant species by basal area per 20 m cell at the shown snapshot.
    Species,
    /// Basal area (m²/ha) per 20 m cell at the shown snapshot.
    BasalArea,
}

/// A run directory loaded for viewing.
pub struct RunData {
    /// The run directory.
    pub dir: PathBuf,
    /// The site the run simulated.
    pub site: SiteConditions,
    /// Species library (the shipped one overlaid by the run's `species/`).
    pub library: SpeciesLibrary,
    /// Species ids of the run's pool, in the order of the run's maps and legends.
    pub pool: Vec<String>,
    /// Snapshot years (plain snapshots with a tree inventory: with `inventory_every` the
    /// other snapshot years have maps only), ascending.
    pub years: Vec<u32>,
    paths: Vec<PathBuf>,
    rows: HashMap<u32, Vec<InventoryRow>>,
    instances: HashMap<(u32, u8), Vec<TreeInstance>>,
    /// The stumps of each snapshot's harvested trees (read on first use).
    stumps: HashMap<u32, Vec<scene::Stump>>,
    /// The stand table (empty when the run has none).
    pub stand_table: StandTable,
    /// Condition maps of the site (names, fields, ramps, ranges).
    pub layers: Vec<Layer>,
}

fn season_key(s: Season) -> u8 {
    match s {
        Season::Spring => 0,
        Season::Summer => 1,
        Season::Autumn => 2,
        Season::Winter => 3,
    }
}

impl RunData {
    /// Loads the index of `dir`: its snapshot years, stand table and condition maps (the
    /// inventories are read when first shown).
    ///
    /// # Errors
    /// [`Error::Io`] / [`Error::Format`] naming the folder when it has no `inventory/` snapshots
    /// or its stand table cannot be read.
    pub fn open(dir: &Path, site: SiteConditions, library: SpeciesLibrary, pool: Vec<String>) -> Result<Self> {
        let snaps: Vec<(u32, PathBuf)> = inventory::snapshots(dir)?.into_iter().filter(|(_, s, _)| s.is_empty()).map(|(y, _, p)| (y, p)).collect();
        if snaps.is_empty() {
            return Err(Error::format(dir, "no inventory snapshots (inventory/year_NNNN.parquet or .csv): is this a run directory of `sylva run` or `sylva simulate`?"));
        }
        let st = dir.join("stand_table.csv");
        let stand_table = if st.is_file() { StandTable::read(&st)? } else { StandTable::default() };
        let layers = crate::job::maps::site_layers(&site, None, None);
        let pool = if pool.is_empty() { library.species.iter().map(|s| s.id.clone()).collect() } else { pool };
        Ok(RunData { dir: dir.to_path_buf(), site, library, pool, years: snaps.iter().map(|s| s.0).collect(), paths: snaps.into_iter().map(|s| s.1).collect(), rows: HashMap::new(), instances: HashMap::new(), stumps: HashMap::new(), stand_table, layers })
    }

    /// First and last snapshot years.
    pub fn span(&self) -> (u32, u32) {
        (self.years[0], self.years[self.years.len() - 1])
    }

    /// The inventory of snapshot `k` (read on first use).
    ///
    /// # Errors
    /// As [`inventory::read`].
    pub fn rows(&mut self, k: usize) -> Result<&[InventoryRow]> {
        let y = self.years[k];
        if !self.rows.contains_key(&y) {
            let r = inventory::read(&self.paths[k])?;
            self.rows.insert(y, r);
        }
        Ok(self.rows.get(&y).map(|v| v.as_slice()).unwrap_or(&[]))
    }

    fn snapshot_instances(&mut self, k: usize, season: Season) -> Result<Vec<TreeInstance>> {
        let key = (self.years[k], season_key(season));
        if let Some(v) = self.instances.get(&key) {
            return Ok(v.clone());
        }
        self.rows(k)?;
        let rows = self.rows.get(&self.years[k]).map(|v| v.as_slice()).unwrap_or(&[]);
        let inst = scene::instances(&scene::plants_from_rows(rows), &self.library, &self.site, season);
        self.instances.insert(key, inst.clone());
        Ok(inst)
    }

    /// The stumps drawn at `year` (its whole part): the trees removed by management
    /// (`dead:harvest`, [`scene::stumps_from_rows`]) in the snapshots of the
    /// [`scene::STUMP_YEARS`] years up to it. Each snapshot's are read once, on first use, and
    /// only those of years whose `deaths_harvest` in the stand table is above 0 (every
    /// snapshot's when the run has no stand table).
    ///
    /// # Errors
    /// As [`inventory::read_filtered`] (naming the file).
    pub fn stumps_at(&mut self, year: f32) -> Result<Vec<scene::Stump>> {
        let y = year.max(0.0).floor() as u32;
        let status = format!("dead:{}", crate::sim::trees::DeathCause::Harvest.name());
        // only the snapshots of years that removed trees by the stand table (all without one)
        let cut: Option<Vec<u32>> = self.stand_table.columns.iter().any(|c| c == "deaths_harvest").then(|| self.stand_table.series("deaths_harvest").iter().filter(|p| p[1] > 0.0).map(|p| p[0] as u32).collect());
        let mut out = Vec::new();
        for k in 0..self.years.len() {
            let sy = self.years[k];
            if !scene::stump_shown(sy, y) || cut.as_ref().is_some_and(|c| !c.contains(&sy)) {
                continue;
            }
            if !self.stumps.contains_key(&sy) {
                let rows = match self.rows.get(&sy) {
                    Some(r) => r.iter().filter(|r| r.status == status).cloned().collect(),
                    None => inventory::read_filtered(&self.paths[k], |r| r.status == status)?,
                };
                self.stumps.insert(sy, scene::stumps_from_rows(&rows, sy));
            }
            out.extend_from_slice(&self.stumps[&sy]);
        }
        Ok(out)
    }

    /// The snapshots around `year`: `(k0, k1, t)` with `years[k0] ≤ year ≤ years[k1]` and
    /// `t` the fraction between them (clamped to the first and last snapshot).
    pub fn bracket(&self, year: f32) -> (usize, usize, f32) {
        let n = self.years.len();
        if year <= self.years[0] as f32 || n == 1 {
            return (0, 0, 0.0);
        }
        for k in 1..n {
            let (a, b) = (self.years[k - 1] as f32, self.years[k] as f32);
            if year <= b {
                return (k - 1, k, ((year - a) / (b - a).max(1e-6)).clamp(0.0, 1.0));
            }
        }
        (n - 1, n - 1, 0.0)
    }

    /// The trees drawn at `year` (any value between snapshots): interpolated between the two
    /// snapshots around it with [`timelapse::interpolate`] (growth, recruits fading in, the dead
    /// fading out), as the timelapse is.
    ///
    /// # Errors
    /// As [`RunData::rows`].
    pub fn instances_at(&mut self, year: f32, season: Season) -> Result<Vec<TreeInstance>> {
        let (k0, k1, t) = self.bracket(year);
        let a = self.snapshot_instances(k0, season)?;
        if k0 == k1 || t <= 0.0 {
            return Ok(a);
        }
        let b = self.snapshot_instances(k1, season)?;
        if t >= 1.0 {
            // exactly at a snapshot: its trees, without the faded-out dead of the one before
            return Ok(b);
        }
        Ok(timelapse::interpolate(&a, &b, t))
    }

    /// What is known of tree `id` at `year`: its row in the snapshot at or before `year`, and its
    /// fate from the later snapshots.
    ///
    /// # Errors
    /// As [`RunData::rows`].
    pub fn tree_info(&mut self, id: u64, year: f32) -> Result<Option<TreeInfo>> {
        let (k0, k1, t) = self.bracket(year);
        // the snapshot the tree is shown from: the earlier one, or the later for a recruit
        let mut from = None;
        for k in [if t >= 0.5 { k1 } else { k0 }, k0, k1] {
            if let Some(r) = self.rows(k)?.iter().find(|r| r.id == id) {
                from = Some((k, r.clone()));
                break;
            }
        }
        let Some((k, row)) = from else { return Ok(None) };
        let mut fate = if row.status == "alive" { "alive".to_string() } else { format!("{} (year {})", row.status.replacen(':', ": ", 1), self.years[k]) };
        if row.status == "alive" {
            for j in k + 1..self.years.len() {
                let later = self.rows(j)?.iter().find(|r| r.id == id).map(|r| r.status.clone());
                match later {
                    Some(s) if s == "alive" => continue,
                    Some(s) => {
                        fate = format!("alive at year {}; {} (year {})", self.years[k], s.replacen(':', ": ", 1), self.years[j]);
                        break;
                    }
                    None => {
                        fate = format!("alive at year {}; gone by year {} (cause not recorded between snapshots)", self.years[k], self.years[j]);
                        break;
                    }
                }
            }
        }
        Ok(Some(TreeInfo { row, year: self.years[k], fate }))
    }

    /// The field of an overlay on a grid over the site (row 0 north), its colour ramp and value
    /// range, or `None` for [`Overlay::None`]. Species maps hold the pool position + 1 of the
    /// dominant species by basal area (0: no tree ≥ 1.3 m); basal area is in m²/ha.
    ///
    /// # Errors
    /// As [`RunData::rows`].
    pub fn overlay_field(&mut self, o: Overlay, year: f32) -> Result<Option<(Grid<f32>, f64, crate::output::maps::Ramp, (f32, f32))>> {
        use crate::output::maps::Ramp;
        let cell_site = self.site.cell_x_m;
        match o {
            Overlay::None => Ok(None),
            Overlay::Condition(k) => {
                let Some(l) = self.layers.get(k) else { return Ok(None) };
                let range = l.range.or_else(|| crate::output::maps::percentile_range(&l.grid, Some(&self.site.mask), 0.02, 0.98)).unwrap_or((0.0, 1.0));
                Ok(Some((l.grid.clone(), cell_site, l.ramp, range)))
            }
            Overlay::Species | Overlay::BasalArea => {
                let (k0, k1, t) = self.bracket(year);
                let k = if t >= 0.5 { k1 } else { k0 };
                let (ex, ey) = self.site.extent_m();
                let cell = STAND_MAP_CELL_M;
                let (cols, rows) = (((ex / cell).ceil() as usize).max(1), ((ey / cell).ceil() as usize).max(1));
                let np = self.pool.len();
                let pool = self.pool.clone();
                let mut ba = vec![0f64; cols * rows * np.max(1)];
                for r in self.rows(k)?.iter().filter(|r| r.status == "alive" && r.height_m >= 1.3) {
                    let Some(p) = pool.iter().position(|s| *s == r.species) else { continue };
                    let c = ((r.x_m / cell) as usize).min(cols - 1);
                    let rr = rows - 1 - ((r.y_m / cell) as usize).min(rows - 1);
                    let d = r.dbh_cm as f64 / 100.0;
                    ba[(rr * cols + c) * np + p] += std::f64::consts::PI * d * d / 4.0;
                }
                let area_ha = cell * cell / 10_000.0;
                let mut g = Grid::filled(cols, rows, 0.0f32);
                for i in 0..cols * rows {
                    let v = &ba[i * np..(i + 1) * np];
                    let tot: f64 = v.iter().sum();
                    g.data[i] = if o == Overlay::BasalArea {
                        (tot / area_ha) as f32
                    } else if tot <= 0.0 {
                        0.0
                    } else {
                        v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0.0, |(p, _)| p as f32 + 1.0)
                    };
                }
                if o == Overlay::BasalArea {
                    Ok(Some((g, cell, Ramp::Viridis, (0.0, 60.0))))
                } else {
                    Ok(Some((g, cell, Ramp::Grey, (0.0, np as f32))))
                }
            }
        }
    }

    /// Colour (sRGB) of the `p`-th pool species in the species overlay and legend (the palette of
    /// the run's species maps).
    pub fn species_colour(p: usize) -> [u8; 3] {
        crate::output::plot::SPECIES_PALETTE[p % crate::output::plot::SPECIES_PALETTE.len()]
    }
}

/// Colours (linear RGB) of terrain vertices at `positions` for an overlay `field` of `cell` m
/// cells (row 0 north, over a site `extent_y` m tall): ramp colour of the value scaled into
/// `range`, or the species palette (value = pool position + 1, 0 = beige "no tree") when
/// `species` is set; mixed 85 % over the land-cover colour `base`, which NaN cells and the
/// vertices beyond the site (the surroundings) keep.
pub fn overlay_colours(positions: &[[f32; 3]], base: &[[f32; 3]], field: &Grid<f32>, cell: f64, extent_y: f64, ramp: crate::output::maps::Ramp, range: (f32, f32), species: bool) -> Vec<[f32; 3]> {
    positions
        .iter()
        .zip(base)
        .map(|(p, b)| {
            // the surroundings beyond the site keep their colours
            let (x, y) = (p[0] as f64, p[1] as f64);
            if x < 0.0 || y < 0.0 || x > field.width as f64 * cell || y > extent_y {
                return *b;
            }
            let c = ((p[0] as f64 / cell).floor().max(0.0) as usize).min(field.width - 1);
            let r = (((extent_y - p[1] as f64) / cell).floor().max(0.0) as usize).min(field.height - 1);
            let v = field.data[r * field.width + c];
            if !v.is_finite() {
                return *b;
            }
            let srgb = if species {
                if v < 0.5 {
                    [235, 225, 200]
                } else {
                    RunData::species_colour(v as usize - 1)
                }
            } else {
                let t = ((v - range.0) / (range.1 - range.0).max(1e-6)).clamp(0.0, 1.0);
                ramp.color(t)
            };
            let o = scene::srgb_to_linear(srgb);
            [0.85 * o[0] + 0.15 * b[0], 0.85 * o[1] + 0.15 * b[1], 0.85 * o[2] + 0.15 * b[2]]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stand_table_series_reads_a_column() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("stand_table.csv");
        std::fs::write(&p, "year,stems_ha,basal_area_m2_ha\n0,100,1.5\n5,120,2.25\n").unwrap();
        let t = StandTable::read(&p).unwrap();
        assert_eq!(t.series("basal_area_m2_ha"), vec![[0.0, 1.5], [5.0, 2.25]]);
        assert!(t.series("nope").is_empty());
        std::fs::write(&p, "year,stems_ha\n0,abc\n").unwrap();
        let e = StandTable::read(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("stand_table.csv"), "{e}");
    }

    #[test]
    fn overlay_colours_follow_the_field_and_keep_nan_cells() {
        // 2 × 1 cells of 10 m over a 10 m tall site: west 0, east NaN
        let g = Grid { width: 2, height: 1, data: vec![0.0, f32::NAN] };
        let pos = [[5.0, 5.0, 0.0], [15.0, 5.0, 0.0], [-20.0, 5.0, 0.0], [5.0, 30.0, 0.0]];
        let base = [[0.1, 0.2, 0.3]; 4];
        let c = overlay_colours(&pos, &base, &g, 10.0, 10.0, crate::output::maps::Ramp::Grey, (0.0, 1.0), false);
        assert_eq!(c[1], base[1]);
        // beyond the site (the surroundings): the land-cover colour
        assert_eq!((c[2], c[3]), (base[2], base[3]));
        // grey ramp at 0 is black: 15 % of the base remains
        assert!((c[0][0] - 0.015).abs() < 1e-3 && (c[0][2] - 0.045).abs() < 1e-3, "{:?}", c[0]);
    }
}
