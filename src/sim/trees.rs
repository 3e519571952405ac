//! Tree storage: struct of arrays with stable ids, and a spatial hash grid for neighbour queries.

use super::light_grid::LightGrid;
use crate::species::SpeciesId;
use serde::{Deserialize, Serialize};

/// Stable tree identifier (never reused within a run). Trees of the start (planted, seed
/// sources) are numbered 0, 1, 2, … in the scenario's order; recruits get [`birth_id`], a
/// function of where and when they were born, so ids do not depend on how the landscape is cut
/// into tiles ([`crate::sim::tiles`]) and stay ascending in the tree store's order.
pub type TreeId = u64;

/// Bits of a recruit id ([`birth_id`]) for its index among the recruits of its cell and year.
pub const BIRTH_INDEX_BITS: u32 = 12;
/// Bits of a recruit id ([`birth_id`]) for its birth cell (light cells are `u32`).
pub const BIRTH_CELL_BITS: u32 = 32;

/// Id of the `k`-th tree recruited in light cell `cell` (row-major, row 0 south) in simulation
/// year `year` (years completed before it): `(year + 1) · 2⁴⁴ + cell · 2¹² + k`. Partition
/// independent (no counter shared by the whole landscape); larger than every start tree's id
/// (those stay below 2⁴⁴) and than every id of an earlier year, and ascending in (cell, k)
/// within a year, so recruits appended in cell order keep the store sorted by id. Ranges:
/// `year` < 2²⁰ − 1 (scenarios run at most 10,000 years), `k` < 4096 (a light cell of at most
/// 20 m holds at most about 100 stems at the recruitment height, `regen::max_density_ha`).
#[inline]
pub fn birth_id(year: u32, cell: u32, k: u32) -> TreeId {
    debug_assert!(k < 1 << BIRTH_INDEX_BITS && year < (1 << 20) - 1);
    ((year as u64 + 1) << (BIRTH_CELL_BITS + BIRTH_INDEX_BITS)) | (cell as u64) << BIRTH_INDEX_BITS | (k as u64 & ((1 << BIRTH_INDEX_BITS) - 1))
}

/// Why a tree died.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum DeathCause {
    /// Senescence: the tree reached its species' maximum age, or the intrinsic (background)
    /// mortality draw (an age-dependent hazard with 1 % survival to max_age, as Bugmann 2001's
    /// constant 4.605 / max_age per year: `sim::phases::mortality::p_intrinsic`) hit a tree at or above
    /// [`SENESCENT_AGE_SHARE`] of its maximum age.
    Age,
    /// Stress: suppressed growth over several years (JABOWA/ForClim tradition).
    Stress,
    /// Windthrow on exposed sites.
    Wind,
    /// Background: the intrinsic random mortality draw (`sim::phases::mortality::p_intrinsic`,
    /// Bugmann 2001) hit a tree younger than [`SENESCENT_AGE_SHARE`] of its maximum age —
    /// accidents, pathogens, lightning and other causes the model does not resolve.
    Background,
    /// Removed by a thinning or a harvest of the scenario's management
    /// (`sim::phases::management`).
    Harvest,
}

/// Share of the species' maximum age from which an intrinsic mortality draw counts as
/// senescence ([`DeathCause::Age`]) instead of [`DeathCause::Background`]. 0.8: a convention of
/// this model (reporting only; the death probabilities do not depend on it).
pub const SENESCENT_AGE_SHARE: f32 = 0.8;

/// Number of death causes ([`DeathCause::ALL`]).
pub const N_CAUSES: usize = 5;

impl DeathCause {
    /// All causes in output order.
    pub const ALL: [DeathCause; N_CAUSES] = [DeathCause::Age, DeathCause::Stress, DeathCause::Wind, DeathCause::Background, DeathCause::Harvest];
    /// Lower-case name used in outputs (`dead:<name>`).
    pub fn name(self) -> &'static str {
        match self {
            DeathCause::Age => "age",
            DeathCause::Stress => "stress",
            DeathCause::Wind => "wind",
            DeathCause::Background => "background",
            DeathCause::Harvest => "harvest",
        }
    }
    /// Index in [`DeathCause::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// A tree that died, kept in the world's record of the year it died in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeadTree {
    /// Tree id.
    pub id: TreeId,
    /// Species.
    pub species: SpeciesId,
    /// Position (m).
    pub x: f32,
    /// Position (m).
    pub y: f32,
    /// Ground elevation (m).
    pub z: f32,
    /// Age at death (years).
    pub age: f32,
    /// Height at death (m).
    pub height: f32,
    /// DBH at death (cm).
    pub dbh: f32,
    /// Crown radius at death (m): the crown's outline as it stood
    /// ([`TreeStore::crown_outline`]), as the inventories report it.
    pub crown_radius: f32,
    /// Crown base height at death (m).
    pub crown_base: f32,
    /// Simulation year of death.
    pub year: u32,
    /// Cause.
    pub cause: DeathCause,
}

/// Number of `f32` columns of a [`TreeStore`] ([`TreeStore::f32_columns`]).
pub const N_F32_COLUMNS: usize = 11;

/// All living trees, one `Vec` per attribute (index `i` is one tree). Dead trees are removed at
/// the end of the mortality phase (order of the survivors is kept) and recorded as [`DeadTree`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TreeStore {
    /// Stable ids, strictly increasing in index order ([`birth_id`] for recruits).
    pub id: Vec<TreeId>,
    /// Species index.
    pub species: Vec<SpeciesId>,
    /// East (m, world coordinates).
    pub x: Vec<f32>,
    /// North (m).
    pub y: Vec<f32>,
    /// Ground elevation (m).
    pub z: Vec<f32>,
    /// Age (years).
    pub age: Vec<f32>,
    /// Height (m).
    pub height: Vec<f32>,
    /// Diameter at breast height (cm); 0 below 1.3 m.
    pub dbh: Vec<f32>,
    /// Crown-space radius (m): the open-grown crown radius shrunk by crowding and shade
    /// (`sim::phases::growth`), whose projection × the species' crown LAI is the tree's leaf area.
    /// The crown's outline, wider in closed stands, is [`TreeStore::crown_outline`].
    pub crown_radius: Vec<f32>,
    /// Crown base height (m).
    pub crown_base: Vec<f32>,
    /// Light resource of the crown (0–1) from the last light phase.
    pub light: Vec<f32>,
    /// Vigour memory (0–1): exponentially weighted growth response (light response × suitability
    /// with the drought factor; below the upper layer the suitability alone, shade acting there
    /// through `sim::phases::mortality::p_shade`) × crowding modifier
    /// (`sim::rules::vigour_memory`).
    pub vigour: Vec<f32>,
    /// Site suitability (0–1) of the tree's cell for its species (cached at establishment).
    pub suitability: Vec<f32>,
    /// Each tree's persistent diameter-growth factor (`sim::phases::growth::growth_factor`,
    /// a function of the scenario seed and the tree id only), computed the first time the
    /// tree grows and kept: NaN until then. A cache, not state: it is not written to
    /// checkpoints, and stores that differ only in it compare equal.
    #[serde(skip)]
    pub growth_factor: GrowthFactors,
    /// Next id [`TreeStore::push`] hands out (trees of the start; recruits get [`birth_id`]).
    pub next_id: TreeId,
}

/// The cached growth factors of a [`TreeStore`], one per tree (NaN: not yet drawn). Equal to
/// any other: the values are a pure function of the seed and the tree ids, so two stores with
/// the same trees have the same factors whether or not they were drawn yet.
#[derive(Debug, Clone, Default)]
pub struct GrowthFactors(pub Vec<f32>);

impl PartialEq for GrowthFactors {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// A new tree to add.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewTree {
    /// Species.
    pub species: SpeciesId,
    /// Position (m).
    pub x: f32,
    /// Position (m).
    pub y: f32,
    /// Ground elevation (m).
    pub z: f32,
    /// Age (years).
    pub age: f32,
    /// Height (m).
    pub height: f32,
    /// DBH (cm).
    pub dbh: f32,
    /// Crown radius (m).
    pub crown_radius: f32,
    /// Site suitability (0–1).
    pub suitability: f32,
}

/// Names of the [`TreeStore::f32_columns`], in their order (the fields' names).
pub const F32_COLUMN_NAMES: [&str; N_F32_COLUMNS] = ["x", "y", "z", "age", "height", "dbh", "crown_radius", "crown_base", "light", "vigour", "suitability"];

impl NewTree {
    /// The tree's values of the [`TreeStore::f32_columns`] when it joins a store with light
    /// `light` and vigour `vigour`: its crown base [`super::rules::start_crown_base`].
    #[inline]
    pub fn f32_columns(&self, light: f32, vigour: f32) -> [f32; N_F32_COLUMNS] {
        [self.x, self.y, self.z, self.age, self.height, self.dbh, self.crown_radius, super::rules::start_crown_base(self.height), light, vigour, self.suitability]
    }
}

impl TreeStore {
    /// Crown radius (m) of tree `i` as it stands ([`super::rules::crown_outline_radius`] of its
    /// species in `lib`): what inventories report and pictures draw; `crown_radius[i]` holds its
    /// crown-space radius (leaf area).
    #[inline]
    pub fn crown_outline(&self, lib: &crate::species::SpeciesLibrary, i: usize) -> f32 {
        super::rules::crown_outline_radius(&lib.species[self.species[i] as usize], self.height[i], self.dbh[i], self.crown_base[i], self.light[i], self.crown_radius[i])
    }

    /// Number of living trees.
    pub fn len(&self) -> usize {
        self.id.len()
    }
    /// True when no tree lives.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }
    /// The per-tree `f32` columns, in the one order the checkpoint (`sim::checkpoint`) and the
    /// tile messages (`sim::tiles`) store them: x, y, z, age, height, DBH, crown radius, crown
    /// base, light, vigour, suitability (units at the fields). A new `f32` attribute is added
    /// here, in [`TreeStore::columns_mut`], in [`F32_COLUMN_NAMES`] and in
    /// [`NewTree::f32_columns`] (and the checkpoint layout version raised); `push`, `retain`,
    /// `merge_by_id`, regeneration's recruits, the checkpoint and the tile codec follow.
    pub fn f32_columns(&self) -> [&Vec<f32>; N_F32_COLUMNS] {
        [&self.x, &self.y, &self.z, &self.age, &self.height, &self.dbh, &self.crown_radius, &self.crown_base, &self.light, &self.vigour, &self.suitability]
    }
    /// [`TreeStore::f32_columns`], mutable.
    pub fn f32_columns_mut(&mut self) -> [&mut Vec<f32>; N_F32_COLUMNS] {
        self.columns_mut().2
    }
    /// Every column, mutable: ids, species, the [`TreeStore::f32_columns`], the growth-factor
    /// cache.
    pub fn columns_mut(&mut self) -> (&mut Vec<TreeId>, &mut Vec<SpeciesId>, [&mut Vec<f32>; N_F32_COLUMNS], &mut Vec<f32>) {
        let TreeStore { id, species, x, y, z, age, height, dbh, crown_radius, crown_base, light, vigour, suitability, growth_factor, next_id: _ } = self;
        (id, species, [x, y, z, age, height, dbh, crown_radius, crown_base, light, vigour, suitability], &mut growth_factor.0)
    }
    /// Adds a tree and returns its new id.
    pub fn push(&mut self, t: NewTree) -> TreeId {
        let id = self.next_id;
        self.next_id += 1;
        self.id.push(id);
        self.species.push(t.species);
        for (c, v) in self.f32_columns_mut().into_iter().zip(t.f32_columns(1.0, 1.0)) {
            c.push(v);
        }
        self.growth_factor.0.push(f32::NAN);
        id
    }
    /// Removes every tree whose `keep` flag is false, keeping the order of the others (the
    /// columns compacted in parallel, one task per column).
    pub fn retain(&mut self, keep: &[bool]) {
        fn r<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
            let mut j = 0;
            for i in 0..v.len() {
                if keep[i] {
                    v[j] = v[i];
                    j += 1;
                }
            }
            v.truncate(j);
        }
        let (id, species, columns, growth_factor) = self.columns_mut();
        // a store restored from a checkpoint has no cached factors yet: give it NaN ones
        growth_factor.resize(id.len(), f32::NAN);
        rayon::scope(|sc| {
            sc.spawn(|_| r(id, keep));
            sc.spawn(|_| r(species, keep));
            for v in columns.into_iter().chain([growth_factor]) {
                sc.spawn(move |_| r(v, keep));
            }
        });
    }
    /// The trees of `parts` in one store sorted by id (each part sorted by id, ids unique), and the
    /// part each row came from. Lean parts (id, species, height and DBH only) give a lean store.
    /// `next_id` is `next_id`. (Tiled runs merge halos and gather stand tables with it; the
    /// management phase merges planted trees.)
    pub fn merge_by_id(parts: &[TreeStore], next_id: u64) -> (TreeStore, Vec<usize>) {
        // k-way merge of the sorted parts (a heap of their next ids): O(n log k)
        let mut all: Vec<(u64, usize, usize)> = Vec::with_capacity(parts.iter().map(|p| p.len()).sum());
        let mut heap: std::collections::BinaryHeap<std::cmp::Reverse<(u64, usize, usize)>> = parts.iter().enumerate().filter(|(_, p)| !p.is_empty()).map(|(k, p)| std::cmp::Reverse((p.id[0], k, 0))).collect();
        while let Some(std::cmp::Reverse((id, k, i))) = heap.pop() {
            all.push((id, k, i));
            if let Some(&next) = parts[k].id.get(i + 1) {
                heap.push(std::cmp::Reverse((next, k, i + 1)));
            }
        }
        let full = parts.iter().all(|p| p.x.len() == p.len());
        let mut t = TreeStore { next_id, ..Default::default() };
        t.id = all.iter().map(|e| e.0).collect();
        t.species = all.iter().map(|e| parts[e.1].species[e.2]).collect();
        let of_parts: Vec<[&Vec<f32>; N_F32_COLUMNS]> = parts.iter().map(|p| p.f32_columns()).collect();
        let col = |k: usize| all.iter().map(|e| of_parts[e.1][k][e.2]).collect::<Vec<f32>>();
        if full {
            for (k, c) in t.f32_columns_mut().into_iter().enumerate() {
                *c = col(k);
            }
            // cached growth factors where a part has them (the tile's own rows), NaN (drawn again
            // when needed, the same bits) for halo copies, which arrive without
            t.growth_factor.0 = all.iter().map(|e| if parts[e.1].growth_factor.0.len() == parts[e.1].len() { parts[e.1].growth_factor.0[e.2] } else { f32::NAN }).collect();
        } else {
            // a lean store: the columns the stand table reads
            t.height = all.iter().map(|e| parts[e.1].height[e.2]).collect();
            t.dbh = all.iter().map(|e| parts[e.1].dbh[e.2]).collect();
        }
        (t, all.iter().map(|e| e.1).collect())
    }
    /// Inserts the rows of `extra` (sorted by id, none of its ids in `self`) into `self` (sorted
    /// by id) so that the result is sorted by id: the rows of `merge_by_id(&[self, extra])`
    /// in place, each column moved by runs (memmove) instead of row by row. Growth factors of
    /// `extra` are NaN (drawn again when needed) unless it has them for every row; `next_id` is
    /// kept. Returns the rows of `extra` in the result, ascending (for [`TreeStore::remove_rows`]).
    pub fn insert_by_id(&mut self, extra: &TreeStore) -> Vec<usize> {
        let m = extra.len();
        if m == 0 {
            return Vec::new();
        }
        // insertion point of each extra row among self's rows (non-decreasing)
        let pos: Vec<usize> = extra.id.iter().map(|id| self.id.partition_point(|x| x < id)).collect();
        fn ins<T: Copy + Send>(v: &mut Vec<T>, pos: &[usize], val: impl Fn(usize) -> T) {
            let (n, m) = (v.len(), pos.len());
            v.resize(n + m, val(0));
            let mut end = n;
            for j in (0..m).rev() {
                let p = pos[j];
                v.copy_within(p..end, p + j + 1);
                v[p + j] = val(j);
                end = p;
            }
        }
        let gf_extra = extra.growth_factor.0.len() == m;
        let ex_cols = extra.f32_columns();
        let n = self.len();
        let (id, species, columns, growth_factor) = self.columns_mut();
        growth_factor.resize(n, f32::NAN);
        let pos = &pos[..];
        rayon::scope(|sc| {
            sc.spawn(|_| ins(id, pos, |j| extra.id[j]));
            sc.spawn(|_| ins(species, pos, |j| extra.species[j]));
            for (v, e) in columns.into_iter().zip(ex_cols) {
                sc.spawn(move |_| ins(v, pos, |j| e[j]));
            }
            sc.spawn(|_| ins(growth_factor, pos, |j| if gf_extra { extra.growth_factor.0[j] } else { f32::NAN }));
        });
        pos.iter().enumerate().map(|(j, &p)| p + j).collect()
    }
    /// Removes the rows `rows` (ascending, each below `len()`), keeping the order of the rest:
    /// `retain` with those rows false, each column moved by runs.
    pub fn remove_rows(&mut self, rows: &[usize]) {
        if rows.is_empty() {
            return;
        }
        fn rm<T: Copy + Send>(v: &mut Vec<T>, rows: &[usize]) {
            let mut w = rows[0];
            for (j, &q) in rows.iter().enumerate() {
                let end = rows.get(j + 1).copied().unwrap_or(v.len());
                v.copy_within(q + 1..end, w);
                w += end - q - 1;
            }
            v.truncate(w);
        }
        let n = self.len();
        let (id, species, columns, growth_factor) = self.columns_mut();
        growth_factor.resize(n, f32::NAN);
        rayon::scope(|sc| {
            sc.spawn(|_| rm(id, rows));
            sc.spawn(|_| rm(species, rows));
            for v in columns.into_iter().chain([growth_factor]) {
                sc.spawn(move |_| rm(v, rows));
            }
        });
    }
    /// Basal area of tree `i` (m²).
    #[inline]
    pub fn basal_area_m2(&self, i: usize) -> f64 {
        let d = self.dbh[i] as f64 / 100.0;
        std::f64::consts::FRAC_PI_4 * d * d
    }
    /// Approximate heap size in bytes.
    pub fn heap_bytes(&self) -> usize {
        self.id.capacity() * 8 + self.species.capacity() * 2 + N_F32_COLUMNS * self.x.capacity() * 4 + self.growth_factor.0.capacity() * 4
    }
}

/// A spatial hash grid on the [`LightGrid`] (cells of `cell_m` metres, row 0 south), trees
/// listed per cell (counting sort, O(trees)); rebuilt every year. It holds the rectangle of
/// light cells `col0..col0 + cols`, `row0..row0 + rows` of the whole grid: the whole grid in one
/// process, a tile's trees' and own cells in a tiled run ([`SpatialGrid::build_in`]; issue 37
/// Build 1). Cell indices (`c = row * cols + col`) are the rectangle's.
#[derive(Debug, Clone, Default)]
pub struct SpatialGrid {
    /// Cell size (m).
    pub cell_m: f64,
    /// Columns held.
    pub cols: usize,
    /// Rows held.
    pub rows: usize,
    /// Column of the whole light grid of the first column held.
    pub col0: usize,
    /// Row of the whole light grid of the first row held (southernmost).
    pub row0: usize,
    /// `start[c]..start[c+1]` indexes `items` for cell `c = row * cols + col`.
    pub start: Vec<u32>,
    /// Tree indices, grouped by cell, ascending within a cell.
    pub items: Vec<u32>,
}

impl SpatialGrid {
    /// Cell index of world point `(x, y)`, clamped to the cells held (for a point of a cell
    /// held, the whole grid's clamped cell: [`LightGrid::cell_of`]).
    #[inline]
    pub fn cell_of(&self, x: f32, y: f32) -> usize {
        let c = (((x as f64 / self.cell_m) as isize) - self.col0 as isize).clamp(0, self.cols as isize - 1) as usize;
        let r = (((y as f64 / self.cell_m) as isize) - self.row0 as isize).clamp(0, self.rows as isize - 1) as usize;
        r * self.cols + c
    }
    /// The grid of all of `light`'s cells.
    pub fn build(trees: &TreeStore, light: &LightGrid) -> SpatialGrid {
        Self::build_in(trees, light, super::light_grid::CellRect { col0: 0, row0: 0, col1: light.cols, row1: light.rows })
    }
    /// The grid of the cells `rect` of `light` (clipped to it; at least one cell): `rect` must
    /// hold every tree's cell ([`LightGrid::cell_of`]), or the trees outside are listed in its
    /// nearest edge cell.
    pub fn build_in(trees: &TreeStore, light: &LightGrid, rect: super::light_grid::CellRect) -> SpatialGrid {
        let col1 = rect.col1.min(light.cols).max(1);
        let row1 = rect.row1.min(light.rows).max(1);
        let (col0, row0) = (rect.col0.min(col1 - 1), rect.row0.min(row1 - 1));
        let mut g = SpatialGrid { cell_m: light.cell_m, cols: col1 - col0, rows: row1 - row0, col0, row0, start: Vec::new(), items: Vec::new() };
        let (start, items) = super::bucket::bucket(trees.len(), g.cols * g.rows, |i| g.cell_of(trees.x[i], trees.y[i]) as u32, |i| i as u32);
        g.start = start;
        g.items = items;
        g
    }
    /// Trees of cell `c`.
    #[inline]
    pub fn cell(&self, c: usize) -> &[u32] {
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
    /// Indices of trees within `r` metres of `(x, y)` (ascending cell order).
    pub fn within(&self, trees: &TreeStore, x: f32, y: f32, r: f32, out: &mut Vec<u32>) {
        out.clear();
        let (oc, or) = (self.col0 as isize, self.row0 as isize);
        let c0 = (crate::grid::floor_index((x - r) as f64 / self.cell_m) - oc).max(0);
        let c1 = (crate::grid::floor_index((x + r) as f64 / self.cell_m) - oc).min(self.cols as isize - 1);
        let r0 = (crate::grid::floor_index((y - r) as f64 / self.cell_m) - or).max(0);
        let r1 = (crate::grid::floor_index((y + r) as f64 / self.cell_m) - or).min(self.rows as isize - 1);
        for row in r0..=r1 {
            for col in c0..=c1 {
                for &i in self.cell(row as usize * self.cols + col as usize) {
                    let dx = trees.x[i as usize] - x;
                    let dy = trees.y[i as usize] - y;
                    if dx * dx + dy * dy <= r * r {
                        out.push(i);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn birth_ids_order_by_year_then_cell_then_index() {
        assert_eq!(birth_id(0, 0, 0), 1 << 44);
        assert_eq!(birth_id(0, 3, 5), (1 << 44) + (3 << 12) + 5);
        assert!(birth_id(0, 3, 4095) < birth_id(0, 4, 0));
        assert!(birth_id(0, u32::MAX, 4095) < birth_id(1, 0, 0));
        assert!(birth_id(9_999, u32::MAX, 4095) > birth_id(9_998, 0, 0));
    }

    #[test]
    fn ids_are_stable_and_grid_finds_neighbours() {
        let mut t = TreeStore::default();
        for k in 0..10 {
            t.push(NewTree { species: 0, x: k as f32 * 3.0, y: 1.0, z: 0.0, age: 1.0, height: 1.0, dbh: 0.0, crown_radius: 0.3, suitability: 1.0 });
        }
        let keep: Vec<bool> = (0..10).map(|k| k % 2 == 0).collect();
        t.retain(&keep);
        assert_eq!(t.id, vec![0, 2, 4, 6, 8]);
        t.push(NewTree { species: 0, x: 1.0, y: 1.0, z: 0.0, age: 1.0, height: 1.0, dbh: 0.0, crown_radius: 0.3, suitability: 1.0 });
        assert_eq!(*t.id.last().unwrap(), 10);
        let g = SpatialGrid::build(&t, &LightGrid::new((40.0, 10.0), 5.0));
        let mut out = vec![];
        g.within(&t, 0.0, 1.0, 2.0, &mut out);
        out.sort();
        assert_eq!(out, vec![0, 5]);
    }
}
