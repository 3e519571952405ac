//! The simulated world: site conditions, species pool, trees and the grids the phases share.

use super::light_grid::{CellRect, LightGrid};
use super::cohorts::{Cohorts, RegenLedger, RegenYear};
use super::scenario::{Scenario, Start};
use super::trees::{DeadTree, NewTree, SpatialGrid, TreeStore};
use crate::conditions::SiteConditions;
use crate::error::Result;
use crate::rng::{salt, Stream};
use crate::species::{allometry, Species, SpeciesId, SpeciesLibrary};
use rayon::prelude::*;

/// Smallest coarse seed cell (m), the cell of a dispersal kernel's long-distance tail.
pub const SEED_CELL_M: f64 = 20.0;
/// Largest dispersal kernel radius in coarse seed cells: a species' coarse seed cell is
/// `max(SEED_CELL_M, max_m / KERNEL_CELLS)`, so the tail has at most `(2·9+1)²` offsets.
pub const KERNEL_CELLS: f64 = 8.0;
/// Largest fine seed cell (m): a seed grid's cells are its coarse cell cut into
/// `⌈coarse / FINE_SEED_CELL_M⌉` per side (5 m for coarse cells of 20 and 25 m), the light
/// cell of the default scenarios, on which the regeneration reads its seeds (round 45).
pub const FINE_SEED_CELL_M: f64 = 5.0;
/// Radius (m) of the near field of a two-scale dispersal kernel: seeds landing within it of
/// their source are spread on the fine cells, the tail beyond on the coarse cells
/// ([`crate::sim::phases::reproduction::kernel`]; round 45, Sylva choice: 2.4 to 3 coarse
/// cells of the short-distance species, where the coarse grid blurred the kernel; at 50 m the
/// tail's coarse cells still bent the profile at 35–40 m by up to 15 %, at 60 m by 5 %:
/// `tests/sim_dispersal.rs`).
pub const NEAR_FIELD_M: f64 = 60.0;

/// Seeds per m² of one species on its own seed grid (row 0 south) of fine cells, `block ×
/// block` of them to a coarse cell (the kernel's tail; round 45): the whole grid in one
/// process; in a tiled run a tile holds the window of it that it reads (issue 37 Build 1 and 3,
/// [`crate::sim::tiles::seed_window`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SeedGrid {
    /// Fine cell size (m).
    pub cell_m: f64,
    /// Fine cells per coarse cell side (≥ 1); `cols` and `rows` are multiples of it.
    pub block: usize,
    /// Columns of the whole grid.
    pub cols: usize,
    /// Rows of the whole grid.
    pub rows: usize,
    /// The cells held (columns and rows of the whole grid): all of them, or a tile's window.
    pub held: CellRect,
    /// Seeds per m² of the cells held, row-major over `held`: cell `(col, row)` of the whole
    /// grid at `(row − held.row0) · held width + (col − held.col0)` ([`SeedGrid::index`]).
    pub data: Vec<f32>,
}

impl SeedGrid {
    /// The whole `cols × rows` grid of fine cells of `cell_m` metres, `block × block` to a
    /// coarse cell, no seeds.
    pub fn new(cell_m: f64, block: usize, cols: usize, rows: usize) -> SeedGrid {
        SeedGrid { cell_m, block, cols, rows, held: CellRect { col0: 0, row0: 0, col1: cols, row1: rows }, data: vec![0.0; cols * rows] }
    }

    /// Coarse cell size (m): `cell_m · block`.
    pub fn coarse_m(&self) -> f64 {
        self.cell_m * self.block as f64
    }

    /// True when the whole grid is held.
    pub fn holds_all(&self) -> bool {
        self.held == CellRect { col0: 0, row0: 0, col1: self.cols, row1: self.rows }
    }

    /// Element of [`SeedGrid::data`] of cell `(col, row)` of the whole grid, or `None` when the
    /// cell is not held.
    #[inline]
    pub fn index(&self, col: usize, row: usize) -> Option<usize> {
        let h = &self.held;
        h.contains(col, row).then(|| (row - h.row0) * (h.col1 - h.col0) + (col - h.col0))
    }

    /// Seeds per m² at world point `(x, y)` (clamped to the grid). Panics, naming the cell and
    /// the window, when its cell is not held (a tile reads the cells of its own light cells).
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> f32 {
        let c = ((x / self.cell_m) as usize).min(self.cols - 1);
        let r = ((y / self.cell_m) as usize).min(self.rows - 1);
        match self.index(c, r) {
            Some(i) => self.data[i],
            None => panic!("seed cell (column {c}, row {r}) outside the cells held ({:?})", self.held),
        }
    }

    /// The values of the cells of `r` (row-major over `r`), or `None` when `r` does not lie
    /// inside the cells held.
    pub fn window(&self, r: CellRect) -> Option<Vec<f32>> {
        let h = &self.held;
        if r.col0 < h.col0 || r.row0 < h.row0 || r.col1 > h.col1 || r.row1 > h.row1 || r.col0 > r.col1 || r.row0 > r.row1 {
            return None;
        }
        let w = h.col1 - h.col0;
        Some((r.row0..r.row1).flat_map(|row| self.data[(row - h.row0) * w + (r.col0 - h.col0)..][..r.col1 - r.col0].iter().copied()).collect())
    }

    /// Keeps only the cells of `r` (issue 37 Build 1: a tile's window). Returns `false`, keeping
    /// the grid as it is, when `r` does not lie inside the cells held.
    pub fn hold(&mut self, r: CellRect) -> bool {
        match self.window(r) {
            Some(v) => {
                self.data = v;
                self.held = r;
                true
            }
            None => false,
        }
    }
}

/// Everything the yearly phases read and write, in four parts by lifetime: the fixed site
/// (inputs, never written after [`World::new`]), the stand's state (what a checkpoint keeps),
/// per-year scratch (rebuilt or cleared every year) and running tallies. Each phase takes only
/// the parts it reads and writes ([`crate::sim::step::PHASES`]).
#[derive(Debug, Clone)]
pub struct World {
    /// Fixed inputs: site conditions, species, derived per-cell grids.
    pub site: Site,
    /// The stand's evolving state: trees, regeneration cohorts, seeds, year.
    pub stand: Stand,
    /// Per-year scratch shared between the phases of one year.
    pub scratch: Scratch,
    /// Running totals since the start.
    pub tallies: Tallies,
}

/// The fixed site of a [`World`]: set by [`World::new`], read by every phase, written by none.
#[derive(Debug, Clone)]
pub struct Site {
    /// Site conditions (terrain grid, row 0 north).
    pub conditions: SiteConditions,
    /// Species library (the pool indexes into it).
    pub lib: SpeciesLibrary,
    /// Species taking part, ascending ids.
    pub pool: Vec<SpeciesId>,
    /// Scenario seed.
    pub seed: u64,
    /// World extent (m).
    pub extent: (f64, f64),
    /// Area of unmasked cells (ha).
    pub area_ha: f64,
    /// The light grid (canopy, ground light, spatial hash and regeneration cells; row 0 south).
    pub light: LightGrid,
    /// Site cell index (row-major, row 0 north) of each light cell; `u32::MAX` where masked.
    /// One process: every light cell; a tile ([`super::tiles::Tile`], `window` set): its own
    /// cells only, indexed by [`super::light_grid::Span`] (issue 37 Build 1).
    pub light_site: Vec<u32>,
    /// Relative insolation (cell insolation / median of unmasked cells, clamped 0.2–1.5) per site
    /// cell held (element [`SiteConditions::held`] of a site cell: every cell in one process, a
    /// tile's cells plus halo on a tile, [`super::tiles::Tile`]; issue 37 Build 1).
    pub rel_insolation: Vec<f32>,
    /// Suitability (0–1) per pool species (outer, pool order) per site cell held (as
    /// `rel_insolation`): of the base climate, or, under a changing climate, of the current
    /// year's (set by the climate phase, `sim::phases::climate`; the only field of the site
    /// written after [`World::new`]).
    pub suitability: Vec<Vec<f32>>,
    /// The checkpoint identity's `terrain` and `site conditions` entries of the whole site
    /// ([`super::checkpoint::identity`]), kept when the site is cut to a tile's cells (which no
    /// longer give them); `None` while the whole site is held.
    pub whole_identity: Option<Vec<(String, String)>>,
    /// External seed rain per pool species (seeds per m² and year).
    pub seed_rain: Vec<f32>,
    /// The scenario's obstacles ([`super::obstacle`]).
    pub obstacles: Vec<super::obstacle::ObstacleSpec>,
    /// Canopy entries of the obstacles on the light grid ([`super::obstacle::light_cells`]).
    pub obstacle_canopy: Vec<(u64, f32)>,
    /// Fraction (0–1) of each light cell's ground not covered by a solid obstacle. A tile holds
    /// its own cells only, as `light_site`.
    pub ground_free: Vec<f32>,
    /// The light cells whose regeneration this world steps: a tile's (`sim::tiles`); `None`
    /// (one process): all.
    pub window: Option<super::light_grid::CellRect>,
    /// The scenario's `[[management]]` entries resolved against the site
    /// ([`super::management::resolve`]); empty when none.
    pub management: Vec<super::management::Operation>,
    /// The climate's change over the run (`[climate] warming_k_per_century`, `anomalies_file`).
    pub climate_change: super::climate_change::ClimateChange,
    /// The stand table's drought-index sums of the base climate over this world's light cells
    /// ([`super::stats::drought_sums`]), computed on first use; empty on a new or cut site.
    pub drought_base: std::sync::OnceLock<(u64, u64)>,
}

/// The stand's state: everything that evolves from year to year and that a checkpoint keeps.
#[derive(Debug, Clone, Default)]
pub struct Stand {
    /// Living trees.
    pub trees: TreeStore,
    /// Years completed so far (the next year to simulate).
    pub year: u32,
    /// The regeneration layer: sapling cohorts below the recruitment height ([`super::phases::regen`]).
    pub cohorts: Cohorts,
    /// Seeds per m² per pool species (pool order), from the last autumn.
    pub seeds: Vec<SeedGrid>,
}

/// Per-year scratch: written by one phase and read by later phases of the same year (or the
/// outputs after it); rebuilt or cleared every year, not checkpointed.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    /// Spatial hash of the trees at the last light phase (cells of the light grid).
    pub grid: SpatialGrid,
    /// Relative light at the ground (0–1.5) per light cell, from the last light phase; a tile
    /// ([`Site::window`] set) holds its own cells only, as [`Site::light_site`].
    pub ground_light: Vec<f32>,
    /// Local top height (m, ≥ 0) per light cell, from the last light phase
    /// ([`crate::sim::phases::light::Light::canopy_top`]: the tallest crown or obstacle over the
    /// cell); held over the same cells as `ground_light`. Read in the same year by regeneration
    /// and mortality (which layer a tree or sapling stands in), so not checkpointed.
    pub canopy_top: Vec<f32>,
    /// Trees that died in the current year (cleared at the start of each year).
    pub dead: Vec<DeadTree>,
    /// Counts of the regeneration layer in the current year.
    pub regen_year: RegenYear,
    /// This year's harvest of each `[[management]]` entry (stems ≥ 1.3 m, their basal area,
    /// stem volume m³ of the trees it removed, sapling stems a `keep_open` entry cut; entry
    /// order; set by the management phase, empty without management): the management table's
    /// harvest columns. In a tiled run the saplings are the tile's own cohorts' (summed over
    /// the ranks by the stats phase, `sim::tiles`).
    pub entry_harvest: Vec<EntryHarvest>,
    /// Positions (m) of the trees each `[[management]]` entry planted this year (entry order;
    /// set by the management phase): a tiled run's rank counts those on its own cells
    /// (`sim::tiles`; trial 46 D5).
    pub planted_at: Vec<Vec<[f32; 2]>>,
}

/// What one `[[management]]` entry removed in a year ([`Scratch::entry_harvest`]):
/// the management table's harvest columns before they are divided by the area.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EntryHarvest {
    /// Removed stems (≥ 1.3 m).
    pub stems: u64,
    /// Their basal area (m²).
    pub basal_area_m2: f64,
    /// Stem volume (m³, [`super::stats::stem_volume_m3`], DBH ≥ 7 cm) of the removed trees.
    pub volume_m3: f64,
    /// Sapling stems of the regeneration layer removed (`keep_open`,
    /// [`crate::sim::phases::management::keep_open_cohorts`]).
    pub saplings: u64,
    /// The entry's `max_removal_share` stopped its thinning short of its target.
    pub capped: bool,
    /// Trees a planting entry planted in the year (0 for the other kinds; trial 46 D5).
    pub planted: u64,
}

/// Running totals since the start of the run (checkpointed).
#[derive(Debug, Clone, Default)]
pub struct Tallies {
    /// Deaths by cause ([`super::trees::DeathCause::ALL`] order).
    pub deaths_total: [u64; super::trees::N_CAUSES],
    /// Cumulative counts of the regeneration layer per pool species.
    pub regen_ledger: RegenLedger,
}

/// The insolation (kWh/m²/yr) that [`Site::rel_insolation`] divides by: the median of the
/// unmasked cells' insolation (the value at index `n / 2` of the `n` unmasked cells sorted in
/// `f32::total_cmp` order), or 1 when that is not positive or no cell is unmasked. `insolation`
/// and `mask` are a part of the site (a rank's window, or the whole site); `reduce` sums counts
/// over the parts ([`super::select::alone`] for one part), and the count of unmasked cells and
/// the selection ([`super::select::kth_smallest_by`], 3 reductions) pass counts, no values, so
/// the parts find the whole site's median bit for bit.
///
/// Errors: those of `reduce`.
pub fn insolation_median_by(insolation: &crate::grid::Grid<f32>, mask: &crate::grid::Grid<bool>, reduce: &mut super::select::Reduce) -> Result<f32> {
    let ins: Vec<f32> = insolation.data.iter().zip(&mask.data).filter(|(_, m)| **m).map(|(v, _)| *v).collect();
    let n = reduce(vec![ins.len() as u64])?.first().copied().unwrap_or(0);
    Ok(super::select::kth_smallest_by(&ins, n / 2, reduce)?.filter(|m| *m > 0.0).unwrap_or(1.0))
}

/// The coarse seed cell (m) of a kernel reaching `max_m` metres,
/// `max(SEED_CELL_M, max_m / KERNEL_CELLS)`, and the fine cells per side of it,
/// `⌈coarse / FINE_SEED_CELL_M⌉`.
pub fn seed_cells(max_m: f64) -> (f64, usize) {
    let coarse = SEED_CELL_M.max(max_m / KERNEL_CELLS);
    (coarse, ((coarse / FINE_SEED_CELL_M).ceil() as usize).max(1))
}

/// The seed grids of `pool` over a site of `extent` (m): per pool species a whole grid of fine
/// cells, `block × block` to a coarse cell of `max(SEED_CELL_M, max_m / KERNEL_CELLS)` metres
/// (its dispersal kernel's longest reach `max_m`; [`seed_cells`]), at least one coarse cell
/// each way, no seeds.
pub fn seed_grids(lib: &SpeciesLibrary, pool: &[SpeciesId], extent: (f64, f64)) -> Vec<SeedGrid> {
    pool.iter()
        .map(|&s| {
            let (coarse, block) = seed_cells(lib.species[s as usize].life.dispersal.max_m as f64);
            let (cols, rows) = (((extent.0 / coarse).ceil() as usize).max(1), ((extent.1 / coarse).ceil() as usize).max(1));
            SeedGrid::new(coarse / block as f64, block, cols * block, rows * block)
        })
        .collect()
}

/// External seed rain per pool species (seeds per m² and year): the scenario's `seed_rain`
/// starts (seeds per ha) of each pool species, summed, ÷ 10,000.
fn seed_rain(scenario: &Scenario, lib: &SpeciesLibrary, pool: &[SpeciesId]) -> Vec<f32> {
    let mut seed_rain = vec![0.0f32; pool.len()];
    for st in &scenario.start {
        if let Start::SeedRain { species, seeds_per_ha } = st {
            if let Some(p) = lib.find(species).and_then(|id| pool.iter().position(|&q| q == id)) {
                seed_rain[p] += (*seeds_per_ha / 10_000.0) as f32;
            }
        }
    }
    seed_rain
}

/// The site cell (row-major over the whole site, row 0 north) under the centre of light cell
/// `c` of `light` when it is held and unmasked, else `u32::MAX`: an element of
/// [`Site::light_site`].
pub fn light_site_cell(site: &SiteConditions, light: &LightGrid, c: usize) -> u32 {
    let (x, y) = light.centre(c);
    match site.cell_at(x, y) {
        Some((sc, sr)) => match site.held_index(sc, sr) {
            Some(i) if site.mask.data[i] => (sr * site.width() + sc) as u32,
            _ => u32::MAX,
        },
        None => u32::MAX,
    }
}

impl Site {
    /// A new tree of species `s` at world point `(x, y)` of age `age` (yr): its potential height
    /// at that age, the start DBH and open-grown crown of that height, its cell's suitability;
    /// `None` on a masked cell, under a solid obstacle or for a species outside the pool.
    pub fn new_tree(&self, s: SpeciesId, x: f64, y: f64, age: f32) -> Option<NewTree> {
        let cell = self.site_cell(x, y)?;
        if self.obstacles.iter().any(|o| o.solid_at_ground(x, y)) {
            return None;
        }
        let p = self.pool_index(s)?;
        let sp = self.species(s);
        let h = allometry::potential_height(sp, age).max(0.3);
        let d = super::rules::start_dbh(sp, h);
        Some(NewTree { species: s, x: x as f32, y: y as f32, z: self.conditions.elevation_at(x, y), age: age.max(1.0), height: h, dbh: d, crown_radius: allometry::open_crown_radius(sp, h, d), suitability: self.suitability[p][self.conditions.held(cell)] })
    }

    /// A planted square lattice: the points `x0 + (i + 0.5 + u) · spacing_m`, `y0 + (j + 0.5 + v)
    /// · spacing_m` of `bbox = [x0, y0, x1, y1]` (m, clipped to the site; `u`, `v` uniform in
    /// ±0.15, an age jitter of ±0.5 yr on `age_yr`), rows `j` then columns `i`, each drawn from
    /// the stream `stream(i, j)` (three draws: x, y, age; then `species` draws the species), kept
    /// where `inside(x, y)` and a tree may stand ([`Site::new_tree`]). The start's planted stands
    /// and management plantings (`sim::phases::management`) both use it.
    pub fn lattice(&self, bbox: [f64; 4], spacing_m: f64, age_yr: f32, stream: impl Fn(u64, u64) -> Stream, inside: impl Fn(f64, f64) -> bool, species: impl Fn(&mut Stream) -> SpeciesId) -> Vec<NewTree> {
        let mut out = Vec::new();
        self.lattice_inside(bbox, spacing_m, age_yr, stream, inside, species, |s, x, y, a| {
            if let Some(t) = self.new_tree(s, x, y, a) {
                out.push(t);
            }
        });
        out
    }

    /// The points of [`Site::lattice`] inside the area, before the site is read: `each(species,
    /// x, y, age)` (m, m, yr) for every point where `inside(x, y)`, with its species drawn, in
    /// the lattice's order. [`Site::lattice`] keeps those where a tree may stand; a tiled run's
    /// start ([`World::place_start_tile`]) walks them for a year-0 planting.
    #[allow(clippy::too_many_arguments)]
    pub fn lattice_inside(&self, bbox: [f64; 4], spacing_m: f64, age_yr: f32, stream: impl Fn(u64, u64) -> Stream, inside: impl Fn(f64, f64) -> bool, species: impl Fn(&mut Stream) -> SpeciesId, mut each: impl FnMut(SpeciesId, f64, f64, f32)) {
        self.lattice_each(bbox, spacing_m, age_yr, stream, |x, y, a, r| {
            if inside(x, y) {
                each(species(r), x, y, a);
            }
        });
    }

    /// The points of [`Site::lattice`] before any is kept: `each(x, y, age, stream)` for every
    /// lattice point (m, m, yr) in the lattice's order, with the point's stream after its three
    /// draws. The lattice and a tiled run's start per tile ([`World::place_start_tile`]) both
    /// walk it, so they draw the same numbers.
    pub fn lattice_each(&self, bbox: [f64; 4], spacing_m: f64, age_yr: f32, stream: impl Fn(u64, u64) -> Stream, mut each: impl FnMut(f64, f64, f32, &mut Stream)) {
        let [x0, y0, x1, y1] = bbox;
        let (x0, y0, x1, y1) = (x0.max(0.0), y0.max(0.0), x1.min(self.extent.0), y1.min(self.extent.1));
        let nx = ((x1 - x0) / spacing_m).floor().max(0.0) as u64;
        let ny = ((y1 - y0) / spacing_m).floor().max(0.0) as u64;
        for j in 0..ny {
            for i in 0..nx {
                let mut r = stream(i, j);
                let x = x0 + (i as f64 + 0.5 + r.range(-0.15, 0.15)) * spacing_m;
                let y = y0 + (j as f64 + 0.5 + r.range(-0.15, 0.15)) * spacing_m;
                let a = (age_yr + r.range(-0.5, 0.5) as f32).max(1.0);
                each(x, y, a, &mut r);
            }
        }
    }

    /// Every place a tree of `scenario`'s start may stand, `each(species, x, y, age)` (m, m,
    /// yr), in the order of one process's tree ids: each `[[start]]` entry in turn, a planted
    /// stand's lattice ([`Site::lattice_each`]), a seed source's trees (up to 10 m around each
    /// point); seed rain places none. A tree stands where [`Site::new_tree`] gives one.
    pub fn start_candidates(&self, scenario: &Scenario, mut each: impl FnMut(SpeciesId, f64, f64, f32)) {
        for (k, st) in scenario.start.iter().enumerate() {
            let Some(s) = self.lib.find(st.species()) else { continue };
            match st {
                Start::Planted { spacing_m, age_yr, area, .. } => {
                    let bbox = area.unwrap_or([0.0, 0.0, self.extent.0, self.extent.1]);
                    let seed = self.seed;
                    self.lattice_each(bbox, *spacing_m, *age_yr, |i, j| Stream::new(seed, (k as u64) << 48 | j << 24 | i, 0, salt::INIT), |x, y, a, _| each(s, x, y, a));
                }
                Start::SeedSources { points, trees_per_source, .. } => {
                    let age = self.species(s).life.maturity_age_yr + 20.0;
                    for (pi, p) in points.iter().enumerate() {
                        for t in 0..*trees_per_source as u64 {
                            let mut r = Stream::new(self.seed, (k as u64) << 48 | (pi as u64) << 24 | t, 0, salt::INIT);
                            let (a, d) = (r.range(0.0, std::f64::consts::TAU), 10.0 * r.uniform().sqrt());
                            each(s, p[0] + d * a.cos(), p[1] + d * a.sin(), age);
                        }
                    }
                }
                Start::SeedRain { .. } => {}
            }
        }
    }

    /// The trees management entry `op` plants in simulation year `y` (0: at the start): the
    /// lattice of the start's planted stands ([`Site::lattice`]) over the entry's bounding box,
    /// the points inside its region, each tree's species drawn from its mix (streams keyed by the
    /// seed, the entry and the year). None for an entry that is not a planting.
    pub fn plant(&self, op: &super::management::Operation, y: u32) -> Vec<NewTree> {
        let mut out = Vec::new();
        self.plant_points(op, y, |s, x, y, a| {
            if let Some(t) = self.new_tree(s, x, y, a) {
                out.push(t);
            }
        });
        out
    }

    /// The lattice points of planting `op` in year `y` inside its region, each with its species
    /// and age, before the site is read ([`Site::lattice_inside`]): `each(species, x, y, age)`
    /// in [`Site::plant`]'s order. None for an entry that is not a planting.
    pub fn plant_points(&self, op: &super::management::Operation, y: u32, each: impl FnMut(SpeciesId, f64, f64, f32)) {
        let super::management::Action::Planting { mix, spacing_m, age_yr } = &op.action else { return };
        let key = (op.index as u64) << 48;
        let pick = |r: &mut Stream| {
            let u = r.uniform();
            mix.iter().find(|(_, c)| u < *c).or(mix.last()).map(|m| m.0).unwrap_or(0)
        };
        self.lattice_inside(op.region.bbox, *spacing_m, *age_yr, |i, j| Stream::new(self.seed, key | j << 24 | i, y as u64, salt::MANAGEMENT), |x, y| op.region.contains(x, y), pick, each)
    }

    /// Position of species `s` in the pool.
    pub fn pool_index(&self, s: SpeciesId) -> Option<usize> {
        self.pool.iter().position(|&q| q == s)
    }

    /// Species record of `s`.
    #[inline]
    pub fn species(&self, s: SpeciesId) -> &Species {
        &self.lib.species[s as usize]
    }

    /// Site cell index (row-major over the whole site) of world point `(x, y)` when unmasked
    /// (and held: [`SiteConditions::unmasked_cell`]).
    pub fn site_cell(&self, x: f64, y: f64) -> Option<usize> {
        self.conditions.unmasked_cell(x, y)
    }
}

impl World {
    /// Builds the world of `scenario` on `site` with species from `lib`, placing the start
    /// (planted stands, seed-source trees) at year 0.
    ///
    /// Errors: unknown species names, seed-source points or planted areas outside the site
    /// ([`Scenario::validate_extent`]), management entries that do not resolve
    /// ([`super::management::resolve`]: species, areas, area files), a planting where no tree of
    /// its lattice can stand ([`World::check`]), an unreadable or malformed climate anomalies
    /// file ([`super::climate_change::ClimateChange::of`]) ([`crate::Error::Invalid`]).
    ///
    /// Logs a warning (`tracing::warn`) for every management year beyond the run's last year
    /// ([`super::management::warnings`]) and for climate anomalies of years beyond it
    /// ([`super::climate_change::ClimateChange::years_beyond`]), and when the scenario has
    /// neither a start nor a planting (nothing would grow).
    pub fn new(site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario) -> Result<World> {
        World::build(site, lib, scenario, true)
    }

    /// [`World::new`], logging its warnings only when `warn` is true: the ranks of a tiled run
    /// other than 0 build the same world and stay quiet, so a warning is printed once, by rank
    /// 0's run driver, not once per rank (`job::tiled::work`).
    ///
    /// Errors: as [`World::new`].
    pub fn build(site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario, warn: bool) -> Result<World> {
        let mut w = World::bare(site, lib, scenario)?;
        w.check_plantings(&scenario.context())?;
        if warn {
            w.warn(scenario);
        }
        w.place_start(scenario);
        // plantings of year 0 stand with the start
        for op in &w.site.management {
            if op.spec.due(0).is_some() {
                for t in w.site.plant(op, 0) {
                    w.stand.trees.push(t);
                }
            }
        }
        Ok(w)
    }

    /// Checks `scenario` against `site` and `lib` as [`World::new`] does, without placing its
    /// start: a run calls it before it creates any output folder, so a refused scenario leaves
    /// none behind. Takes the site and gives it back (it is not copied: until round 31 a copy
    /// of the whole site's conditions, 53 B a site cell, was held beside the site for the
    /// check, which set the start's peak memory of one process and of a tiled run's rank 0 on
    /// a fine grid; issue 37); the site's derived grids are built for the check and dropped.
    ///
    /// Errors: as [`World::new`].
    pub fn check(site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario) -> Result<SiteConditions> {
        if !site.holds_all() {
            // a band of the site (a tiled run's rank 0 of a fresh run, issue 37 round 33):
            // what needs no whole site (species, extent, climate anomalies; the management
            // entries but their areas' unmasked ground, round 36); the rest (the areas, the
            // plantings' lattices) is checked by the ranks together as the run begins
            // ([`super::tiles::derive_tile_site_by`])
            let w = World::skeleton(site, lib, scenario)?;
            if !scenario.management.is_empty() {
                let light_site: Vec<u32> = Vec::new();
                let span = super::light_grid::Span::new(Some(CellRect { col0: 0, row0: 0, col1: 0, row1: 0 }), &w.site.light);
                let view = super::management::SiteView { conditions: &w.site.conditions, extent: w.site.extent, light: &w.site.light, span, light_site: &light_site, pool: &w.site.pool };
                super::management::resolve_by(&scenario.management, &view, lib, &scenario.context(), super::management::Areas::Unmeasured)?;
            }
            return Ok(w.site.conditions);
        }
        let w = World::bare(site, lib, scenario)?;
        w.check_plantings(&scenario.context())?;
        Ok(w.site.conditions)
    }

    /// Refuses a planting none of whose lattice points (in its first year) lies on unmasked
    /// ground inside its area and outside solid obstacles (found by a break-it pass: a planting
    /// wholly inside a building planted nothing and said nothing).
    fn check_plantings(&self, ctx: &str) -> Result<()> {
        self.check_plantings_by(ctx, &mut |op| Ok(self.site.plant(op, op.spec.first_year()).len() as u64))
    }

    /// [`World::check_plantings`] with each planting's trees in its first year counted by
    /// `count` (a tiled run's ranks: the trees on their own tile, all-summed; issue 37 round
    /// 36), called once per planting in entry order.
    ///
    /// Errors: [`crate::Error::Invalid`] naming the first planting whose count is 0; `count`'s.
    pub fn check_plantings_by(&self, ctx: &str, count: &mut dyn FnMut(&super::management::Operation) -> Result<u64>) -> Result<()> {
        for op in &self.site.management {
            let super::management::Action::Planting { spacing_m, .. } = op.action else { continue };
            if count(op)? == 0 {
                let m = &op.spec;
                let field = if m.area.is_some() { "area" } else if m.area_file.is_some() { "area_file" } else if m.polygons.is_some() { "polygons" } else { "spacing_m" };
                let under = if self.site.obstacles.is_empty() { "" } else { ", outside the scenario's solid obstacles" };
                return Err(crate::Error::Invalid {
                    context: ctx.to_string(),
                    field: format!("management[{}].{field}", op.index),
                    value: {
                        let b = op.region.bbox;
                        // an area file's box in the coordinates it was given in (the DEM's CRS),
                        // a rectangle's and inline polygons' in the site's metres (trial 36: a
                        // file's box came out in site metres with float noise)
                        let (p0, p1) = match &m.area_file {
                            None => ([b[0], b[1]], [b[2], b[3]]),
                            Some(_) => (super::management::world_to_crs(&self.site.conditions, b[0], b[1]), super::management::world_to_crs(&self.site.conditions, b[2], b[3])),
                        };
                        let (x0, x1, y0, y1) = (p0[0].min(p1[0]), p0[0].max(p1[0]), p0[1].min(p1[1]), p0[1].max(p1[1]));
                        let frame = match &m.area_file {
                            None => "m from the site's SW corner".to_string(),
                            Some(_) => match self.site.conditions.geo.epsg.filter(|_| self.site.conditions.geo.crs != crate::grid::Crs::Local) {
                                Some(c) => format!("EPSG:{c}"),
                                None => "the site's own coordinates".to_string(),
                            },
                        };
                        let file = m.area_file.as_ref().map(|f| format!("{}: ", f.display())).unwrap_or_default();
                        format!("{file}x {x0:.2}–{x1:.2}, y {y0:.2}–{y1:.2} ({frame}; the part on the site; 0 trees of a {spacing_m} m lattice)")
                    },
                    expected: format!("an area where the planting's lattice has at least one point on unmasked ground inside it{under} (a smaller spacing, or another area)"),
                });
            }
        }
        Ok(())
    }

    /// The world of `scenario` with its site, species and resolved management, and no trees.
    fn bare(site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario) -> Result<World> {
        let ctx = scenario.context();
        let pool = scenario.resolve_species(lib, &ctx)?;
        let extent = site.extent_m();
        scenario.validate_extent(extent, &ctx)?;
        let light = LightGrid::new(extent, scenario.light_cell_m).with_diffuse(scenario.light.diffuse);
        let light_site: Vec<u32> = (0..light.len())
            .into_par_iter()
            .map(|c| {
                let (x, y) = light.centre(c);
                match site.cell_at(x, y) {
                    Some((sc, sr)) if *site.mask.get(sc, sr) => site.mask.idx(sc, sr) as u32,
                    _ => u32::MAX,
                }
            })
            .collect();
        let median = insolation_median_by(&site.insolation_kwh_m2, &site.mask, &mut super::select::alone)?;
        let rel_insolation = site.insolation_kwh_m2.data.iter().map(|v| (v / median).clamp(0.2, 1.5)).collect();
        let suitability = pool.iter().map(|&s| site.indices.data.par_iter().zip(&site.mask.data).map(|(ix, m)| if *m { lib.species[s as usize].suitability(ix) } else { 0.0 }).collect()).collect();
        let valid = site.mask.data.iter().filter(|m| **m).count();
        let area_ha = valid as f64 * site.cell_x_m * site.cell_y_m / 10_000.0;
        let seeds = seed_grids(lib, &pool, extent);
        let seed_rain = seed_rain(scenario, lib, &pool);
        let (obstacle_canopy, ground_free) = super::obstacle::light_cells(&scenario.obstacles, light.cols, light.rows, light.cell_m, super::light_grid::EXTINCTION_K);
        let np = pool.len();
        let mut w = World {
            site: Site {
                conditions: site,
                lib: lib.clone(),
                pool,
                seed: scenario.seed,
                extent,
                area_ha,
                light,
                light_site,
                rel_insolation,
                suitability,
                whole_identity: None,
                seed_rain,
                obstacles: scenario.obstacles.clone(),
                obstacle_canopy,
                ground_free,
                window: None,
                management: Vec::new(),
                climate_change: super::climate_change::ClimateChange::of(&scenario.climate, &ctx)?,
                drought_base: std::sync::OnceLock::new(),
            },
            stand: Stand { trees: TreeStore::default(), year: 0, cohorts: Cohorts::default(), seeds },
            scratch: Scratch { grid: SpatialGrid::default(), ground_light: vec![1.0; light.len()], canopy_top: Vec::new(), dead: Vec::new(), regen_year: RegenYear::default(), entry_harvest: Vec::new(), planted_at: Vec::new() },
            tallies: Tallies { deaths_total: [0; super::trees::N_CAUSES], regen_ledger: RegenLedger::new(np) },
        };
        let span = super::light_grid::Span::new(None, &w.site.light);
        let view = super::management::SiteView { conditions: &w.site.conditions, extent: w.site.extent, light: &w.site.light, span, light_site: &w.site.light_site, pool: &w.site.pool };
        w.site.management = super::management::resolve(&scenario.management, &view, lib, &ctx)?;
        Ok(w)
    }

    /// The world of `scenario` on `site` with its pool, extent, light grid, seed rain,
    /// obstacles and climate change, and nothing derived from the site: no light cells' arrays,
    /// relative insolation, suitability, seed grids or management (all empty), `area_ha` 0, no
    /// trees. A tiled run's rank other than 0 holds it until its tile's part of the site is
    /// derived into it ([`super::tiles::derive_tile_site`], issue 37 Build 1): the whole site's
    /// derived grids (relative insolation, suitability, the light cells' site cells, ground free
    /// and ground light, seed grids) and the start's trees are never built on that rank. `site`
    /// is moved in, not copied.
    ///
    /// Errors: unknown species names, an extent the scenario's points do not fit
    /// ([`Scenario::validate_extent`]), a malformed climate anomalies file
    /// ([`super::climate_change::ClimateChange::of`]).
    pub fn skeleton(site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario) -> Result<World> {
        let ctx = scenario.context();
        let pool = scenario.resolve_species(lib, &ctx)?;
        let extent = site.extent_m();
        scenario.validate_extent(extent, &ctx)?;
        let light = LightGrid::new(extent, scenario.light_cell_m).with_diffuse(scenario.light.diffuse);
        let np = pool.len();
        Ok(World {
            site: Site {
                conditions: site,
                lib: lib.clone(),
                seed_rain: seed_rain(scenario, lib, &pool),
                pool,
                seed: scenario.seed,
                extent,
                area_ha: 0.0,
                light,
                light_site: Vec::new(),
                rel_insolation: Vec::new(),
                suitability: Vec::new(),
                whole_identity: None,
                obstacles: scenario.obstacles.clone(),
                obstacle_canopy: Vec::new(),
                ground_free: Vec::new(),
                window: None,
                management: Vec::new(),
                climate_change: super::climate_change::ClimateChange::of(&scenario.climate, &ctx)?,
                drought_base: std::sync::OnceLock::new(),
            },
            stand: Stand::default(),
            scratch: Scratch::default(),
            tallies: Tallies { deaths_total: [0; super::trees::N_CAUSES], regen_ledger: RegenLedger::new(np) },
        })
    }

    /// Position of species `s` in the pool ([`Site::pool_index`]).
    pub fn pool_index(&self, s: SpeciesId) -> Option<usize> {
        self.site.pool_index(s)
    }

    /// Species record of `s` ([`Site::species`]).
    #[inline]
    pub fn species(&self, s: SpeciesId) -> &Species {
        self.site.species(s)
    }

    /// Site cell index (row-major) of world point `(x, y)` when unmasked ([`Site::site_cell`]).
    pub fn site_cell(&self, x: f64, y: f64) -> Option<usize> {
        self.site.site_cell(x, y)
    }

    fn place_start(&mut self, scenario: &Scenario) {
        let mut trees = Vec::new();
        self.site.start_candidates(scenario, |s, x, y, a| trees.extend(self.site.new_tree(s, x, y, a)));
        for t in trees {
            self.stand.trees.push(t);
        }
    }

    /// The start's trees of tile `me` placed into `self` (a tile's world:
    /// [`super::tiles::derive_tile_site_with`]), with the ids one process gives them (issue 37
    /// Build 1, round 33: a tiled run's ranks place their own start, no rank the whole): every
    /// rank walks the start's places in id order ([`Site::start_candidates`], then since round
    /// 36 the lattice points of each planting of year 0 in entry order, [`Site::plant_points`],
    /// as [`World::build`] adds them after the start: positions only, no site read) and cuts them into runs of consecutive places with one owning tile
    /// (`owner_of(x, y)`, m: the layout's [`super::tiles::Layout::owner_of`]; a function, so
    /// that the world does not import the tiles); the owner of a run counts the trees that stand in
    /// it ([`Site::new_tree`], read from its own cells); the counts, one word a run, are summed
    /// over the ranks by `sum` (an all-reduce: each run has one owner) and the exclusive prefix
    /// sum of the summed counts is each run's first id, so every tree gets its id in one
    /// process's order. The next id is the start's tree count. Every rank of the run calls it
    /// with the same layout's owners (a collective step). Cost: every rank walks every place of the start
    /// (three random draws each), not only its own: for a planted start of the whole site that is
    /// the site's lattice on every rank, a CPU cost, not memory (the runs: 8 bytes per lattice
    /// row and tile column).
    ///
    /// Errors: `sum`'s (a failed exchange), or its answer of another length
    /// ([`crate::Error::Exchange`]).
    pub fn place_start_tile(&mut self, scenario: &Scenario, owner_of: &dyn Fn(f32, f32) -> usize, me: usize, sum: &mut dyn FnMut(Vec<u64>) -> Result<Vec<u64>>) -> Result<()> {
        let mut runs: Vec<u64> = Vec::new();
        let mut owner: Option<usize> = None;
        let mut mine: Vec<(usize, NewTree)> = Vec::new();
        let site = &self.site;
        let mut place = |s: SpeciesId, x: f64, y: f64, a: f32| {
            let o = owner_of(x as f32, y as f32);
            if owner != Some(o) {
                runs.push(0);
                owner = Some(o);
            }
            if o == me {
                if let Some(t) = site.new_tree(s, x, y, a) {
                    let r = runs.len() - 1;
                    runs[r] += 1;
                    mine.push((r, t));
                }
            }
        };
        site.start_candidates(scenario, &mut place);
        // the plantings of year 0 stand after the start, entry by entry ([`World::build`];
        // issue 37 round 36: a scenario with management starts per tile too)
        for op in site.management.iter().filter(|op| op.spec.due(0).is_some()) {
            site.plant_points(op, 0, &mut place);
        }
        let n = runs.len();
        let sums = sum(runs)?;
        if sums.len() != n {
            return Err(crate::Error::Exchange { peer: 0, reason: format!("{} summed counts of the start's runs, expected {n}", sums.len()) });
        }
        let mut first = Vec::with_capacity(n);
        let mut total = 0u64;
        for c in &sums {
            first.push(total);
            total += c;
        }
        let trees = &mut self.stand.trees;
        let mut last = None;
        let mut k = 0u64;
        for (r, t) in mine {
            k = if last == Some(r) { k + 1 } else { 0 };
            last = Some(r);
            trees.next_id = first[r] + k;
            trees.push(t);
        }
        trees.next_id = total;
        Ok(())
    }

    /// Logs [`World::new`]'s warnings about `scenario` (management years beyond the run, no
    /// start and no planting, climate anomalies beyond the run or with gaps), once: by one
    /// process, or by a tiled run's rank 0.
    pub fn warn(&self, scenario: &Scenario) {
        for m in super::management::warnings(&self.site.management, scenario.years, &scenario.context()) {
            tracing::warn!("{m}");
        }
        // nothing to grow from: no start and no planting (round 30's trial ran such a
        // scenario for a minute to no tree, without a word)
        if scenario.start.is_empty() && !scenario.management.iter().any(|m| m.kind == "planting") {
            tracing::warn!("{}: no [[start]] (seed sources, seed rain, a planted stand) and no planting in [[management]]: nothing will grow on this site", scenario.context());
        }
        let late = self.site.climate_change.years_beyond(scenario.years);
        if let Some(first) = late.first() {
            tracing::warn!("{}: climate.anomalies_file has {} year(s) beyond the run's last year {} (from year {first}): they do not act", scenario.context(), late.len(), scenario.years);
        }
        let gaps = self.site.climate_change.anomaly_gaps();
        if !gaps.is_empty() {
            let shown: Vec<String> = gaps.iter().take(8).map(u32::to_string).collect();
            tracing::warn!("{}: climate.anomalies_file has no line for {} year(s) between its first and last ({}{}): they take no anomaly (0 K, precipitation factor 1)", scenario.context(), gaps.len(), shown.join(", "), if gaps.len() > 8 { ", …" } else { "" });
        }
    }
}
