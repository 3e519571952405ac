//! The one schema of a run's tables of trees and saplings: each column's name, type, unit,
//! decimals in the text files and the values a reader accepts. The writers
//! ([`super::inventory`]: CSV, through [`super::parquet`] Parquet, and the final year's GeoPackage) and the readers
//! (`job::inventory`: CSV and Parquet; `sylva view`, `sylva export`, the pictures) take the
//! columns from here; ARCHITECTURE.md ("Run directory") points here.
//!
//! **Tree inventory** (`inventory/year_NNNN.parquet` or `.csv`; [`INVENTORY`]), one row a tree:
//! living trees (status `alive`) in id order, then the trees that died in the snapshot's year
//! (`dead:<cause>`, causes as `sim::trees::DeathCause::name`) in id order.
//!
//! | column | type | unit | CSV decimals | accepted on reading |
//! |---|---|---|---|---|
//! | `id` | int64 | – | – | – |
//! | `species` | text | species id (`species/*.toml`) | – | – |
//! | `x_m` | double | m east of the site's south-west corner | 2 | finite, \|x\| ≤ 10⁷ |
//! | `y_m` | double | m north of the site's south-west corner | 2 | finite, \|y\| ≤ 10⁷ |
//! | `z_m` | double | m (ground elevation) | 2 | finite |
//! | `age_yr` | float | years | 0 | 0–10,000 |
//! | `height_m` | float | m | 2 | 0–200 |
//! | `dbh_cm` | float | cm (0 below 1.3 m) | 2 | 0–1,000 |
//! | `crown_radius_m` | float | m (the crown's outline: `sim::TreeStore::crown_outline`) | 2 | 0–100 |
//! | `crown_base_m` | float | m (height of the crown base) | 2 | 0–200 |
//! | `status` | text | `alive` or `dead:<cause>` | – | either form |
//!
//! The GeoPackage inventory (`inventory/year_NNNN.gpkg`, layer `inventory`) carries the same
//! columns, with a point geometry in the DEM's CRS.
//!
//! **Regeneration layer** (`inventory/year_NNNN_regeneration.parquet` or `.csv`;
//! [`REGENERATION`]), one row a sapling cohort, in (light cell, pool) order: `cell` (int64, light
//! cell index), `species` (text), `x_m`, `y_m` (double, m, the light cell's centre, 2 decimals),
//! `stems` (int64), `stems_per_ha` (double, stems per hectare of the light cell, 0 decimals),
//! `height_m` (float, mean height, m, 2 decimals), `age_yr` (float, years, 0 decimals).
//!
//! A Parquet file holds the same columns in the same order, plus `geometry` (the point as WKB,
//! [`super::parquet`]).

/// Physical type of a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// 64-bit integer.
    Int64,
    /// UTF-8 text.
    Utf8,
    /// 64-bit float.
    Double,
    /// 32-bit float.
    Float,
}

/// One column of a table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// Name (as in the CSV header and the Parquet schema).
    pub name: &'static str,
    /// Physical type.
    pub kind: Kind,
    /// Unit and meaning, for people.
    pub unit: &'static str,
    /// Decimals of a float in the text files (CSV, GeoJSON); 0 for the others.
    pub decimals: usize,
    /// Values a reader accepts (inclusive; non-finite values never); `None`: no check.
    pub valid: Option<(f64, f64)>,
    /// What a reader expects, said when a value is outside `valid`.
    pub expect: &'static str,
}

impl Column {
    const fn new(name: &'static str, kind: Kind, unit: &'static str) -> Column {
        Column { name, kind, unit, decimals: 0, valid: None, expect: "" }
    }
    const fn decimals(mut self, d: usize) -> Column {
        self.decimals = d;
        self
    }
    const fn valid(mut self, lo: f64, hi: f64, expect: &'static str) -> Column {
        self.valid = Some((lo, hi));
        self.expect = expect;
        self
    }
    /// True when a reader accepts `v` in this column (always, for a column without a range).
    pub fn accepts(&self, v: f64) -> bool {
        self.valid.is_none_or(|(lo, hi)| v.is_finite() && v >= lo && v <= hi)
    }
}

/// A table's columns, in file order.
#[derive(Debug, Clone, Copy)]
pub struct Table {
    /// Message name of the Parquet schema.
    pub name: &'static str,
    /// Columns.
    pub columns: &'static [Column],
}

impl Table {
    /// The CSV header line (names joined by commas, no newline).
    pub fn header(&self) -> String {
        self.columns.iter().map(|c| c.name).collect::<Vec<_>>().join(",")
    }
    /// The column named `name`.
    pub fn column(&self, name: &str) -> Option<&'static Column> {
        self.columns.iter().find(|c| c.name == name)
    }
}

/// Number of the inventory's measured columns ([`INVENTORY_MEASURES`]).
pub const N_MEASURES: usize = 8;

/// The tree inventory's measured columns, the numbers of a tree between `species` and
/// `status`: x_m, y_m, z_m, age_yr, height_m, dbh_cm, crown_radius_m, crown_base_m.
pub const INVENTORY_MEASURES: [Column; N_MEASURES] = [
    Column::new("x_m", Kind::Double, "m east of the site's south-west corner").decimals(2).valid(-1e7, 1e7, "a finite easting in metres"),
    Column::new("y_m", Kind::Double, "m north of the site's south-west corner").decimals(2).valid(-1e7, 1e7, "a finite northing in metres"),
    Column::new("z_m", Kind::Double, "m, ground elevation").decimals(2).valid(f64::NEG_INFINITY, f64::INFINITY, "a finite ground elevation in metres"),
    Column::new("age_yr", Kind::Float, "years").valid(0.0, 10_000.0, "an age of 0–10,000 years"),
    Column::new("height_m", Kind::Float, "m").decimals(2).valid(0.0, 200.0, "a height of 0–200 m"),
    Column::new("dbh_cm", Kind::Float, "cm, 0 below 1.3 m").decimals(2).valid(0.0, 1000.0, "a DBH of 0–1,000 cm"),
    Column::new("crown_radius_m", Kind::Float, "m").decimals(2).valid(0.0, 100.0, "a crown radius of 0–100 m"),
    Column::new("crown_base_m", Kind::Float, "m, height of the crown base").decimals(2).valid(0.0, 200.0, "a crown base height of 0–200 m"),
];

const INVENTORY_COLUMNS: [Column; N_MEASURES + 3] = {
    let m = INVENTORY_MEASURES;
    [
        Column::new("id", Kind::Int64, "stable tree id"),
        Column::new("species", Kind::Utf8, "species id (species/*.toml)"),
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5],
        m[6],
        m[7],
        Column::new("status", Kind::Utf8, "alive or dead:<cause>"),
    ]
};

/// The tree inventory (`inventory/year_NNNN.parquet` or `.csv`): id, species, the
/// [`INVENTORY_MEASURES`], status.
pub const INVENTORY: Table = Table { name: "inventory", columns: &INVENTORY_COLUMNS };

/// The regeneration layer (`inventory/year_NNNN_regeneration.parquet` or `.csv`): light cell
/// index, species id, cell centre x_m, y_m (m), stems, stems_per_ha, mean height_m (m), age_yr.
pub const REGENERATION: Table = Table {
    name: "regeneration",
    columns: &[
        Column::new("cell", Kind::Int64, "light cell index"),
        Column::new("species", Kind::Utf8, "species id"),
        Column::new("x_m", Kind::Double, "m, light-cell centre").decimals(2),
        Column::new("y_m", Kind::Double, "m, light-cell centre").decimals(2),
        Column::new("stems", Kind::Int64, "stems of the cohort"),
        Column::new("stems_per_ha", Kind::Double, "stems per hectare of the light cell"),
        Column::new("height_m", Kind::Float, "m, mean height").decimals(2),
        Column::new("age_yr", Kind::Float, "years"),
    ],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inventory_is_id_species_measures_status() {
        assert_eq!(INVENTORY.header(), "id,species,x_m,y_m,z_m,age_yr,height_m,dbh_cm,crown_radius_m,crown_base_m,status");
        assert_eq!(&INVENTORY.columns[2..2 + N_MEASURES], &INVENTORY_MEASURES[..]);
        assert!(INVENTORY.column("z_m").unwrap().accepts(-5.0));
        assert!(!INVENTORY.column("z_m").unwrap().accepts(f64::NAN));
        assert!(!INVENTORY.column("height_m").unwrap().accepts(-0.1));
        assert!(INVENTORY.column("status").unwrap().accepts(f64::NAN));
    }
}
