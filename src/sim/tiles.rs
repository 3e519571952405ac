//! Tiled runs: the landscape cut into rectangular tiles of light cells, each stepped by its own
//! process (an MPI rank) or thread, with the same result, byte for byte, as one process.
//!
//! Every tile holds the species and the site's per-cell grids of its own cells plus a halo
//! (read-only; issue 37 Build 1: the site conditions, relative insolation and suitability,
//! [`SITE_HALO_CELLS`]; the light cells' site arrays of its own cells) and only its own stand:
//! the trees standing on its light cells, the sapling cohorts of its cells.
//! Each year it runs the phases of [`crate::sim::step::PHASES`] on its own trees; what a phase
//! reads across a tile edge comes from copies of the neighbours' trees within the halo, passed
//! once before each phase that reads neighbours (seeds: a grid of sums), through a
//! [`Transport`]. Per-cell passes that only feed the tile's own cells run on them only (the
//! ground light, the spreading of seeds); the spatial hash and canopy of the light phase and the
//! crowding grid of growth are held over the cells of the tile's trees and halo copies
//! (`sim::phases::light::held_cells`, `sim::density::crowding`); the seed grids over the tile's
//! window ([`seed_window`]), the seed production within the kernel's reach of it only while it
//! is spread:
//! 1. **light**: the canopy of a cell holds every crown that covers it, and a tree's light
//!    reads its cell and the next cell towards the equator: trees within the largest crown
//!    radius plus two light cells of the tile;
//! 2. **regeneration** reads only its own cells (ground light, last autumn's seeds, cohorts):
//!    no exchange; recruits get partition-independent ids ([`crate::sim::trees::birth_id`]);
//! 3. **growth** reads the crowding of the 3 × 3 block of 10 m cells around each tree
//!    ([`crate::sim::density`]): trees within 30 m, after this spring's recruitment;
//! 4. **reproduction** gathers seeds over each species' dispersal kernel from the seed
//!    production of the seed cells within reach: no trees are copied (since issue 37; before,
//!    the *mature* trees within `(⌈max_m / cell⌉ + 2)` seed cells, 875 m for silver birch);
//!    every rank sums its own seed trees' production per seed cell and passes the sums of the
//!    cells within the other ranks' reach, a grid; seed cells across a tile edge, whose sum
//!    depends on the order of addition, get the (id, seeds) of their trees from every rank,
//!    summed in id order ([`Tile::reproduce`]);
//! 5. **mortality** draws each tree from its own stream: no exchange;
//!    (**climate**, first in the year, sets each cell's and each own tree's suitability from
//!    the site cells every tile holds: no exchange;)
//! 6. **management** (in a year with thinnings or harvests due): a thinning's target and
//!    triggers (basal area, stems/ha, relative density, top height) are figures over its whole
//!    area, and which trees it takes (smallest first, ties by id; crop trees and their
//!    competitors; a shelterwood's densest neighbourhoods) depends on every tree there; so every
//!    rank sends its trees standing in the areas of the year's thinnings and harvests to every
//!    other rank, each rank merges them with its own by id (the single process's store
//!    restricted to those areas and the rank's own trees, in the same order), carries out the
//!    year's entries on that store exactly as one process does (same sums in the same order,
//!    same choice, identically on every rank) and keeps its own trees, its own harvested dead
//!    and its own cells' plantings ([`Tile::step`]); plantings alone need no exchange (a
//!    lattice is drawn from the seed, the entry and the position); in a year whose due
//!    removals are all thinnings to a target only the keys of the areas' growing stock are
//!    sent (stems of at least 1.3 m and 7 cm DBH: all a thinning reads or takes; id,
//!    species, position, height, DBH: 26 bytes a tree; [`Tile::manage`]);
//! 7. **stats**: the stand table row is made of exact sums ([`super::stats::RowSums`]:
//!    integers, fixed point at 2⁻⁶⁴, whose order of addition does not matter): every rank sums
//!    its own trees and the sums of all ranks are added up ([`Transport::all_sum`], an
//!    `MPI_Allreduce`), so they are one process's bit for bit; the top height is found by a
//!    radix selection over summed counts ([`super::stats::top_height_by`]) and the heights of
//!    the selected trees summed the same way: nothing per tree crosses ranks ([`Tile::step`]).
//!    The year's harvest (stems, volume) is rank 0's sum over every harvested tree it saw in
//!    step 6, in the single process's order.
//!
//! Why the result is the same: every random stream is keyed by the scenario seed, a tree id or a
//! global cell index and the year; tree ids do not depend on the partition; the tree store is
//! kept sorted by id, so each tile's trees, with the halo's merged in by id, are a subsequence
//! of the single-process store in the same order, and every per-cell sum runs over the same
//! trees in the same order as in one process when the halo holds every tree the cell's value
//! depends on. [`min_halo_m`] is that width; [`Layout::new`] refuses a narrower halo and
//! [`Tile::step`] checks the crowns against it every year.

use super::cohorts::{Cohorts, RegenLedger, RegenYear, N_REGEN_CAUSES};
use super::density;
use super::step::{Halo, PHASES};
use super::light_grid::{CellRect, LightGrid};
use super::step::YearReport;
use super::codec::{self, Dec, Short};
use super::trees::{DeadTree, DeathCause, TreeStore, N_CAUSES, N_F32_COLUMNS};
use super::phases::reproduction;
use super::world::{Site, Tallies, World, KERNEL_CELLS, SEED_CELL_M};
use crate::error::{Error, Result};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

/// Passes byte messages between the ranks of a tiled run: one all-to-all exchange at a time,
/// every rank taking part in every exchange in the same order (MPI's model).
pub trait Transport {
    /// This rank (0-based; rank 0 gathers the stand table and drives the run).
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Sends `out[p]` to rank `p` for every `p` (`out.len() == size()`; `out[rank()]` comes back
    /// unchanged) and returns what every rank sent to this one, by rank.
    ///
    /// Errors: [`Error::Exchange`] naming the rank when a message cannot be passed.
    fn exchange(&mut self, out: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>>;
    /// Bytes this rank has sent to other ranks so far.
    fn bytes_sent(&self) -> u64;
    /// Element-wise wrapping sums of `v` over every rank, returned on every rank (every rank
    /// passes the same number of words): an `MPI_Allreduce` with `MPI_SUM`. This default
    /// passes every rank's words to rank 0 and the sums back (two exchanges).
    ///
    /// Errors: [`Error::Exchange`] from the transport, or naming a rank whose words are not as
    /// many as this one's.
    fn all_sum(&mut self, v: Vec<u64>) -> Result<Vec<u64>> {
        let (me, n, len) = (self.rank(), self.size(), v.len());
        let bytes = |w: &[u64]| w.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let words = |k: usize, m: &[u8]| -> Result<Vec<u64>> {
            if m.len() != 8 * len {
                return Err(Error::Exchange { peer: k, reason: format!("{} bytes of sums, expected {}", m.len(), 8 * len) });
            }
            Ok(m.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default())).collect())
        };
        let mut out = vec![Vec::new(); n];
        out[0] = bytes(&v);
        let got = self.exchange(out)?;
        let mut back = vec![Vec::new(); n];
        let mut sums = Vec::new();
        if me == 0 {
            sums = vec![0u64; len];
            for (k, m) in got.iter().enumerate() {
                for (s, w) in sums.iter_mut().zip(words(k, m)?) {
                    *s = s.wrapping_add(w);
                }
            }
            let b = bytes(&sums);
            back = vec![b; n];
            back[0] = Vec::new();
        }
        let got = self.exchange(back)?;
        if me == 0 {
            Ok(sums)
        } else {
            words(0, &got[0])
        }
    }
}

/// All ranks in one process, one thread each ([`LocalTransport::group`]): a shared mailbox and a
/// barrier, for tests and for `sylva simulate --tiles` without MPI.
pub struct LocalTransport {
    rank: usize,
    size: usize,
    shared: Arc<Shared>,
    sent: u64,
}

/// The mailbox of a [`LocalTransport`] group: `boxes[to][from]`, and the barrier the ranks
/// meet at twice per exchange.
struct Shared {
    boxes: Mutex<Vec<Vec<Vec<u8>>>>,
    meet: Mutex<Meet>,
    cv: Condvar,
}

/// State of the barrier: ranks arrived in this round, rounds completed, ranks gone (their
/// endpoint dropped: finished, or returned early with an error).
#[derive(Default)]
struct Meet {
    arrived: usize,
    round: u64,
    gone: usize,
}

impl LocalTransport {
    /// `n` connected endpoints (ranks 0..n), to be moved to one thread each.
    pub fn group(n: usize) -> Vec<LocalTransport> {
        let shared = Arc::new(Shared { boxes: Mutex::new(vec![vec![Vec::new(); n]; n]), meet: Mutex::new(Meet::default()), cv: Condvar::new() });
        (0..n).map(|rank| LocalTransport { rank, size: n, shared: shared.clone(), sent: 0 }).collect()
    }

    /// Waits until every rank has arrived. Unlike `std::sync::Barrier`, a rank whose endpoint
    /// is dropped (its thread stopped on an error) releases the others with
    /// [`Error::Exchange`] instead of leaving them waiting for ever.
    fn meet(&self) -> Result<()> {
        let lost = |reason: &str| Error::Exchange { peer: self.rank, reason: reason.into() };
        let mut m = self.shared.meet.lock().map_err(|_| lost("another rank's thread panicked"))?;
        if m.gone > 0 {
            return Err(lost("another rank stopped before this exchange"));
        }
        m.arrived += 1;
        if m.arrived == self.size {
            m.arrived = 0;
            m.round += 1;
            self.shared.cv.notify_all();
            return Ok(());
        }
        let round = m.round;
        // the round completing wins over a rank leaving after it (it had arrived)
        while m.round == round && m.gone == 0 {
            m = self.shared.cv.wait(m).map_err(|_| lost("another rank's thread panicked"))?;
        }
        if m.round != round {
            Ok(())
        } else {
            Err(lost("another rank stopped before this exchange"))
        }
    }
}

impl Drop for LocalTransport {
    fn drop(&mut self) {
        // a poisoned lock means another thread panicked: nobody to release then
        if let Ok(mut m) = self.shared.meet.lock() {
            m.gone += 1;
            self.shared.cv.notify_all();
        }
    }
}

impl Transport for LocalTransport {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn exchange(&mut self, out: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
        if out.len() != self.size {
            return Err(Error::Exchange { peer: self.rank, reason: format!("{} messages for {} ranks", out.len(), self.size) });
        }
        let poisoned = |_| Error::Exchange { peer: self.rank, reason: "another rank's thread panicked".into() };
        {
            let mut b = self.shared.boxes.lock().map_err(poisoned)?;
            for (to, m) in out.into_iter().enumerate() {
                if to != self.rank {
                    self.sent += m.len() as u64;
                }
                b[to][self.rank] = m;
            }
        }
        self.meet()?;
        let got = {
            let mut b = self.shared.boxes.lock().map_err(poisoned)?;
            std::mem::take(&mut b[self.rank])
        };
        // nobody writes the next round's messages before everyone has taken this round's
        {
            let mut b = self.shared.boxes.lock().map_err(poisoned)?;
            b[self.rank] = vec![Vec::new(); self.size];
        }
        self.meet()?;
        Ok(got)
    }
    fn bytes_sent(&self) -> u64 {
        self.sent
    }
}

/// The reach (m) of each kind of [`Halo`] on `site`: how far beyond a tile the trees a phase
/// reads can stand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Light ([`Halo::Crowns`]): the largest possible crown radius of the pool,
    /// `crown_c0 + crown_c1 · max_dbh_cm` (crowns only shrink from the open-grown radius), plus
    /// two light cells (the cell a crown covers and the next towards the equator, whose canopy
    /// the sun direction reads), or with `[light] diffuse = "sky"` the cell a crown covers and
    /// the cells the sky's rays read (`LightGrid::read_cells`).
    pub crowns_m: f64,
    /// Growth ([`Halo::Crowding`]): 3 × [`density::CROWD_CELL_M`] (the 3 × 3 block around a
    /// tree's cell, whose cell may reach one cell past the tile).
    pub crowding_m: f64,
    /// Reproduction ([`Halo::SeedSources`]): per pool species `(⌈max_m / cell⌉ + 2) · cell` with
    /// its seed cell `cell` ([`crate::sim::world::SeedGrid`]: the kernel's cells, the seed cell
    /// that overlaps the tile and the source's own cell), the longest of the pool.
    pub seeds_m: f64,
}

impl Reach {
    /// The reaches of `site`'s pool.
    pub fn of(site: &Site) -> Reach {
        let mut r = Reach { crowns_m: 2.0 * site.light.cell_m, crowding_m: 3.0 * density::CROWD_CELL_M, seeds_m: 0.0 };
        for &s in &site.pool {
            let sp = &site.lib.species[s as usize];
            let a = sp.life.allometry;
            let crown = (a.crown_c0 + a.crown_c1 * sp.life.max_dbh_cm.max(0.0)).max(a.crown_c0) as f64;
            // the cells a cell's light reads beyond its own (the sun's row, or the sky's reach)
            r.crowns_m = r.crowns_m.max(crown + (site.light.read_cells() + 1) as f64 * site.light.cell_m);
            let d = &sp.life.dispersal;
            let cell = SEED_CELL_M.max(d.max_m as f64 / KERNEL_CELLS);
            r.seeds_m = r.seeds_m.max(((d.max_m as f64 / cell).ceil() + 2.0) * cell);
        }
        r
    }
    /// The widest reach (m).
    pub fn max(&self) -> f64 {
        self.crowns_m.max(self.crowding_m).max(self.seeds_m)
    }
    /// The reach of `h` (m; 0 for [`Halo::None`]).
    pub fn of_halo(&self, h: Halo) -> f64 {
        match h {
            Halo::None => 0.0,
            Halo::Crowns => self.crowns_m,
            Halo::Crowding => self.crowding_m,
            Halo::SeedSources => self.seeds_m,
            // exchanged by area, not by reach (`Tile::manage`)
            Halo::Areas => 0.0,
        }
    }
    /// Every reach capped at `m` metres.
    fn capped(self, m: f64) -> Reach {
        Reach { crowns_m: self.crowns_m.min(m), crowding_m: self.crowding_m.min(m), seeds_m: self.seeds_m.min(m) }
    }
}

/// Halo width (m) a tiled run of `site` needs so that it equals one process: the widest
/// [`Reach`] (for a pool with a long seed kernel, the seed reach: only mature trees are passed
/// that far).
pub fn min_halo_m(site: &Site) -> f64 {
    Reach::of(site).max()
}

/// How the light grid is cut: `nx × ny` rectangles of whole light cells (columns and rows split
/// as evenly as they go), tile `k = ty · nx + tx` (row 0 south), and the halo width.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The light grid that is cut.
    pub light: LightGrid,
    /// Tiles across (west to east).
    pub nx: usize,
    /// Tiles up (south to north).
    pub ny: usize,
    /// Column boundaries, `nx + 1` values from 0 to `light.cols`.
    pub col_bounds: Vec<usize>,
    /// Row boundaries, `ny + 1` values from 0 to `light.rows`.
    pub row_bounds: Vec<usize>,
    /// Halo width (m): the widest reach a tile's neighbours' trees are copied from.
    pub halo_m: f64,
    /// The reach of each phase's halo ([`Reach::of`] the site, each capped at `halo_m`).
    pub reach: Reach,
}

impl Layout {
    /// `nx × ny` tiles over the light grid of `site` with the halo [`min_halo_m`].
    ///
    /// Errors: [`Error::Invalid`] when a tile would have no column or row (`nx` above the
    /// grid's columns or `ny` above its rows, or either 0).
    pub fn new(site: &Site, nx: usize, ny: usize) -> Result<Layout> {
        Layout::with_halo(site, nx, ny, min_halo_m(site))
    }

    /// As [`Layout::new`] with a given halo width `halo_m` (m).
    ///
    /// Errors: [`Error::Invalid`] for the tile counts (as [`Layout::new`]) and for a halo
    /// narrower than [`min_halo_m`] (a tiled run would differ from one process).
    pub fn with_halo(site: &Site, nx: usize, ny: usize, halo_m: f64) -> Result<Layout> {
        let min = min_halo_m(site);
        if !(halo_m >= min) {
            return Err(Error::Invalid {
                context: "tiled run".into(),
                field: "halo_m".into(),
                value: format!("{halo_m} m"),
                expected: format!("at least {min} m (the pool's longest seed reach, crowding neighbourhood or largest crown plus two light cells), or the tiles would differ from one process"),
            });
        }
        let mut l = Layout::unchecked(site.light, nx, ny, halo_m)?;
        l.reach = Reach::of(site).capped(halo_m);
        Ok(l)
    }

    /// A layout with any halo, not checked against [`min_halo_m`] (to show what a narrow halo
    /// changes): every phase's reach is `halo_m`.
    ///
    /// Errors: [`Error::Invalid`] for the tile counts (as [`Layout::new`]).
    pub fn unchecked(light: LightGrid, nx: usize, ny: usize, halo_m: f64) -> Result<Layout> {
        if nx == 0 || ny == 0 || nx > light.cols || ny > light.rows {
            return Err(Error::Invalid {
                context: "tiled run".into(),
                field: "tiles".into(),
                value: format!("{nx} × {ny}"),
                expected: format!("1–{} across and 1–{} up (the light grid's columns and rows)", light.cols, light.rows),
            });
        }
        let col_bounds = (0..=nx).map(|i| light.cols * i / nx).collect();
        let row_bounds = (0..=ny).map(|j| light.rows * j / ny).collect();
        Ok(Layout { light, nx, ny, col_bounds, row_bounds, halo_m, reach: Reach { crowns_m: halo_m, crowding_m: halo_m, seeds_m: halo_m } })
    }

    /// Tiles over the light grid of `site` with the given boundaries (light cells; e.g. from
    /// [`cut_by_weight`] or a checkpoint's manifest) and the halo [`min_halo_m`].
    ///
    /// Errors: [`Error::Invalid`] naming `col_bounds` or `row_bounds` unless each runs strictly
    /// upwards from 0 to the light grid's columns (rows) with at least two values.
    pub fn with_bounds(site: &Site, col_bounds: Vec<usize>, row_bounds: Vec<usize>) -> Result<Layout> {
        for (name, b, end) in [("col_bounds", &col_bounds, site.light.cols), ("row_bounds", &row_bounds, site.light.rows)] {
            if b.len() < 2 || b[0] != 0 || b[b.len() - 1] != end || b.windows(2).any(|w| w[0] >= w[1]) {
                return Err(Error::Invalid { context: "tiled run".into(), field: name.into(), value: format!("{b:?}"), expected: format!("at least 2 values rising strictly from 0 to {end} (the light grid's cells)") });
            }
        }
        let mut l = Layout::new(site, col_bounds.len() - 1, row_bounds.len() - 1)?;
        l.col_bounds = col_bounds;
        l.row_bounds = row_bounds;
        Ok(l)
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// True for a layout without tiles (never, once built).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The light cells of tile `k`.
    pub fn rect(&self, k: usize) -> CellRect {
        let (tx, ty) = (k % self.nx, k / self.nx);
        CellRect { col0: self.col_bounds[tx], col1: self.col_bounds[tx + 1], row0: self.row_bounds[ty], row1: self.row_bounds[ty + 1] }
    }

    /// Tile owning light cell `(col, row)`.
    pub fn owner_of_cell(&self, col: usize, row: usize) -> usize {
        let tx = self.col_bounds[1..].partition_point(|&b| b <= col).min(self.nx - 1);
        let ty = self.row_bounds[1..].partition_point(|&b| b <= row).min(self.ny - 1);
        ty * self.nx + tx
    }

    /// Tile owning world point `(x, y)` (m): the tile of its light cell (clamped to the grid).
    pub fn owner_of(&self, x: f32, y: f32) -> usize {
        let (col, row) = self.light.col_row(self.light.cell_of(x, y));
        self.owner_of_cell(col, row)
    }

    /// True when world point `(x, y)` lies within `m` metres of tile `k` (its rectangle widened
    /// by `m` on every side).
    pub fn in_halo(&self, k: usize, x: f32, y: f32, m: f64) -> bool {
        let r = self.rect(k);
        let c = self.light.cell_m;
        let (x, y) = (x as f64, y as f64);
        x >= r.col0 as f64 * c - m && x < r.col1 as f64 * c + m && y >= r.row0 as f64 * c - m && y < r.row1 as f64 * c + m
    }
}

/// The work of a tiled run per light-grid column and per row of `site` (issue 37 Build 5), to
/// cut tiles by ([`cut_by_weight`]): the light cells where forest can grow, those whose site
/// cell is unmasked and where some species of the pool has a positive suitability (not masked
/// out, not above the tree line). Returns `(per column, per row)`, `light.cols` and
/// `light.rows` counts. From the site alone, so every rank and every resume cuts the same
/// tiles; a heuristic of where the trees will be (a planted part of an otherwise open site is
/// not seen: its trees are not the site's).
pub fn work_weights(site: &Site) -> (Vec<u64>, Vec<u64>) {
    work_weights_in(site, 0..site.light.rows)
}

/// The part of [`work_weights`] from the light rows `rows` (row 0 south) of `site`: the same
/// `light.cols` and `light.rows` counts, those of the light cells outside `rows` not counted
/// (the rows outside are 0). The counts are integers, so the parts of any cut of the rows into
/// ranges, added up in any order, are [`work_weights`] exactly (issue 37 Build 1: a rank counts
/// its band, [`weight_band`], and the ranks' parts are all-summed, `job::tiled::layout_by`).
/// `site` must hold the light cells of `rows` (one process's site: all of them; rows beyond
/// the grid are ignored).
pub fn work_weights_in(site: &Site, rows: std::ops::Range<usize>) -> (Vec<u64>, Vec<u64>) {
    let light = &site.light;
    let (mut wc, mut wr) = (vec![0u64; light.cols], vec![0u64; light.rows]);
    let rows = rows.start.min(light.rows)..rows.end.min(light.rows);
    let lo = rows.start * light.cols;
    let hi = rows.end.max(rows.start) * light.cols;
    for (k, &s) in site.light_site.iter().enumerate().take(hi).skip(lo) {
        let grows = s != u32::MAX && site.suitability.iter().any(|sp| sp.get(site.conditions.held(s as usize)).is_some_and(|&v| v > 0.0));
        if grows {
            let (c, r) = light.col_row(k);
            wc[c] += 1;
            wr[r] += 1;
        }
    }
    (wc, wr)
}

/// [`work_weights_in`] from the site conditions `c` and the pool `pool` of `lib` on the light
/// grid `light`, without a derived [`Site`] (no light cells' site cells, no suitability grids):
/// a light cell counts when the site cell under its centre is held and unmasked
/// ([`crate::sim::world::light_site_cell`]) and some pool species' suitability of that cell's
/// indices is positive (`Species::suitability`, what [`Site::suitability`] holds there). Equal
/// to [`work_weights_in`] of the world built on `c` for every range of rows whose site cells
/// `c` holds (tests/sim_tiles.rs); a tiled run's ranks count their band so before any world is
/// derived (`job::tiled::layout_by`, issue 37 Build 1).
pub fn work_weights_of(c: &crate::conditions::SiteConditions, lib: &crate::species::SpeciesLibrary, pool: &[crate::species::SpeciesId], light: &LightGrid, rows: std::ops::Range<usize>) -> (Vec<u64>, Vec<u64>) {
    let (mut wc, mut wr) = (vec![0u64; light.cols], vec![0u64; light.rows]);
    let rows = rows.start.min(light.rows)..rows.end.min(light.rows);
    for r in rows {
        for (col, n) in wc.iter_mut().enumerate() {
            let s = crate::sim::world::light_site_cell(c, light, r * light.cols + col);
            if s == u32::MAX {
                continue;
            }
            let ix = &c.indices.data[c.held(s as usize)];
            if pool.iter().any(|&p| lib.species[p as usize].suitability(ix) > 0.0) {
                *n += 1;
                wr[r] += 1;
            }
        }
    }
    (wc, wr)
}

/// The layout's weights per light column and row ([`work_weights_of`]) of the light cells
/// whose centre's site cell lies in the site rows `site_rows` (row 0 north) and is held by
/// `c`: the `n` ranks' bands of site rows ([`weight_band`] of the site's height) count every
/// light cell once, so their sums are [`work_weights_in`]'s of the whole site, whether a rank
/// holds its band only or the whole site (issue 37 Build 1, round 32).
pub fn work_weights_of_site_rows(c: &crate::conditions::SiteConditions, lib: &crate::species::SpeciesLibrary, pool: &[crate::species::SpeciesId], light: &LightGrid, site_rows: std::ops::Range<usize>) -> (Vec<u64>, Vec<u64>) {
    let (mut wc, mut wr) = (vec![0u64; light.cols], vec![0u64; light.rows]);
    let w = c.width().max(1);
    for (r, rn) in wr.iter_mut().enumerate() {
        for (col, n) in wc.iter_mut().enumerate() {
            let s = crate::sim::world::light_site_cell(c, light, r * light.cols + col);
            if s == u32::MAX || !site_rows.contains(&(s as usize / w)) {
                continue;
            }
            let ix = &c.indices.data[c.held(s as usize)];
            if pool.iter().any(|&p| lib.species[p as usize].suitability(ix) > 0.0) {
                *n += 1;
                *rn += 1;
            }
        }
    }
    (wc, wr)
}

/// Derives into `w` (a [`World::skeleton`] holding the whole site's conditions) the part of
/// the site that tile `me` of `layout` holds, as [`Tile::own`] cuts it from the world of one
/// process (issue 37 Build 1, item (a): the whole site's derived grids are never built on a
/// rank other than 0): the light cells' site cells, ground free of obstacles and ground light
/// of the tile's rectangle ([`super::light_grid::Span`]); the conditions cut to the site
/// cells under it plus [`SITE_HALO_CELLS`], with the whole site's checkpoint identity kept;
/// the relative insolation (÷ `median`, the whole site's median of unmasked insolation: from
/// [`super::world::insolation_median_by`] over the ranks' bands) and the pool's suitability
/// of those cells; each seed grid's window ([`seed_window`], no seeds: the scatter fills
/// them); the whole site's unmasked area; the management entries resolved against the whole
/// site (only when the scenario has some: they count light cells per area, so the light cells'
/// site cells are derived whole for that, transiently); no trees or cohorts. Every value is
/// the one [`Tile::own`] of [`World::new`] holds (tests/sim_tiles.rs).
///
/// Errors: [`Error::Invalid`] when `w`'s conditions are not whole; as
/// [`super::management::resolve`].
pub fn derive_tile_site(w: &mut World, scenario: &super::scenario::Scenario, layout: &Layout, me: usize, median: f32) -> Result<()> {
    derive_tile_site_with(w, scenario, layout, me, median, None)
}

/// What a rank holding only its tile's cells of the site conditions needs of the whole site
/// (issue 37 Build 1, item (a), round 32; `job::tiled::tile_site_by` gathers it): the checkpoint
/// identity ([`super::checkpoint::site_identity`] of the whole site, from rank 0, which holds
/// it) and the count of unmasked site cells (the ranks' bands' counts all-summed).
#[derive(Debug, Clone, PartialEq)]
pub struct WholeSite {
    /// [`super::checkpoint::site_identity`] of the whole site's conditions.
    pub identity: Vec<(String, String)>,
    /// Unmasked cells of the whole site (cells, 0 to width × height).
    pub valid_cells: u64,
}

/// [`derive_tile_site`] of a world whose conditions hold either the whole site (`whole`
/// unused) or exactly tile `me`'s window of it (the site cells under its rectangle plus
/// [`SITE_HALO_CELLS`], what `job::tiled::tile_site_by` moves to it from the ranks' bands) with
/// `whole` the whole site's identity and unmasked count; the values are the same bit for bit.
/// A scenario with management needs the whole site here (its areas count light cells over
/// it); [`derive_tile_site_by`] counts them with the other ranks.
///
/// Errors: [`Error::Invalid`] when `w`'s conditions hold neither the whole site nor the tile's
/// window with `whole` given, or hold a window with management entries in the scenario; as
/// [`super::management::resolve`].
pub fn derive_tile_site_with(w: &mut World, scenario: &super::scenario::Scenario, layout: &Layout, me: usize, median: f32, whole: Option<&WholeSite>) -> Result<()> {
    derive_tile_site_by(w, scenario, layout, me, median, whole, None)
}

/// [`derive_tile_site_with`], with `sum` (an all-sum over the ranks of a tiled run, every rank
/// calling this function at the same point) the scenario's management resolved from the
/// tile's cells only (issue 37, round 36): each entry's area is the all-sum of the ranks'
/// counts of unmasked light cells of their own rectangle ([`super::management::resolve_by`],
/// one process's integer count, so `area_ha` bit for bit), and each planting is refused when
/// the all-sum of the trees its first year plants on the ranks' own rectangles is 0
/// ([`World::check_plantings_by`], as one process refuses it). Then a scenario with
/// management needs no whole site on any rank: `w` may hold the tile's window. Without `sum`,
/// as [`derive_tile_site_with`].
///
/// Errors: as [`derive_tile_site_with`] (but a window with management is taken when `sum` is
/// given); `sum`'s. Every rank gets the same sums, so the same refusals.
pub fn derive_tile_site_by(w: &mut World, scenario: &super::scenario::Scenario, layout: &Layout, me: usize, median: f32, whole: Option<&WholeSite>, mut sum: Option<&mut dyn FnMut(Vec<u64>) -> Result<Vec<u64>>>) -> Result<()> {
    let c = &w.site.conditions;
    let light = w.site.light;
    let rect = layout.rect(me);
    let l = light.cell_m;
    let win = c.window_of(rect.col0 as f64 * l, rect.row0 as f64 * l, rect.col1 as f64 * l, rect.row1 as f64 * l, SITE_HALO_CELLS);
    let part = match whole {
        Some(ws) if !c.holds_all() && c.held == win && (scenario.management.is_empty() || sum.is_some()) => Some(ws),
        _ if c.holds_all() => None,
        _ => return Err(Error::Invalid { context: "tiled run".into(), field: "site conditions".into(), value: format!("cells {} of {} × {}", c.held, c.full.0, c.full.1), expected: format!("the whole site, or tile {me}'s cells {win} with the whole site's identity (a scenario without management)") }),
    };
    let span = super::light_grid::Span::new(Some(rect), &light);
    let valid = match part {
        Some(ws) => ws.valid_cells as usize,
        None => c.mask.data.iter().filter(|m| **m).count(),
    };
    w.site.area_ha = valid as f64 * c.cell_x_m * c.cell_y_m / 10_000.0;
    w.site.light_site = (0..span.len()).map(|k| super::world::light_site_cell(c, &light, span.cell(k))).collect();
    let (canopy, ground_free) = super::obstacle::light_cells(&w.site.obstacles, light.cols, light.rows, light.cell_m, super::light_grid::EXTINCTION_K);
    w.site.obstacle_canopy = canopy;
    w.site.ground_free = span.cut(&ground_free);
    drop(ground_free);
    if !scenario.management.is_empty() {
        w.site.management = match sum.as_mut() {
            Some(f) => {
                // the tile's light cells, their areas summed over the ranks
                let view = super::management::SiteView { conditions: c, extent: w.site.extent, light: &light, span, light_site: &w.site.light_site, pool: &w.site.pool };
                super::management::resolve_by(&scenario.management, &view, &w.site.lib, &scenario.context(), super::management::Areas::Summed(&mut **f))?
            }
            None => {
                let whole: Vec<u32> = (0..light.len()).map(|k| super::world::light_site_cell(c, &light, k)).collect();
                let all = super::light_grid::Span::new(None, &light);
                let view = super::management::SiteView { conditions: c, extent: w.site.extent, light: &light, span: all, light_site: &whole, pool: &w.site.pool };
                super::management::resolve(&scenario.management, &view, &w.site.lib, &scenario.context())?
            }
        };
    }
    if let Some(ws) = part {
        w.site.whole_identity = Some(ws.identity.clone());
    } else if win != c.held {
        w.site.whole_identity = Some(super::checkpoint::site_identity(c));
        w.site.conditions.hold(win);
    }
    let c = &w.site.conditions;
    w.site.rel_insolation = c.insolation_kwh_m2.data.iter().map(|v| (v / median).clamp(0.2, 1.5)).collect();
    let lib = &w.site.lib;
    w.site.suitability = w.site.pool.iter().map(|&s| c.indices.data.iter().zip(&c.mask.data).map(|(ix, m)| if *m { lib.species[s as usize].suitability(ix) } else { 0.0 }).collect()).collect();
    w.stand.seeds = super::world::seed_grids(lib, &w.site.pool, w.site.extent)
        .into_iter()
        .map(|g| {
            let r = seed_window(layout, me, &g);
            super::world::SeedGrid { data: vec![0.0; (r.col1 - r.col0) * (r.row1 - r.row0)], held: r, ..g }
        })
        .collect();
    w.scratch.ground_light = vec![1.0; span.len()];
    w.scratch.canopy_top = Vec::new();
    w.site.window = Some(rect);
    if let Some(f) = sum {
        // each planting's first-year trees on this tile's own rectangle, summed over the ranks
        let site = &w.site;
        w.check_plantings_by(&scenario.context(), &mut |op| {
            let n = site.plant(op, op.spec.first_year()).iter().filter(|t| layout.owner_of(t.x, t.y) == me).count() as u64;
            let v = f(vec![n])?;
            v.first().copied().ok_or_else(|| Error::Exchange { peer: 0, reason: format!("no summed count of management[{}]'s planting", op.index) })
        })?;
    }
    Ok(())
}

/// The light rows (row 0 south) whose part of the layout's weights rank `k` of `n` counts
/// ([`work_weights_in`]): `k · rows / n` to `(k + 1) · rows / n`, so the `n` bands cover the
/// `rows` rows once.
pub fn weight_band(k: usize, n: usize, rows: usize) -> std::ops::Range<usize> {
    let n = n.max(1);
    k * rows / n..(k + 1) * rows / n
}

/// Boundaries that cut the `w.len()` columns (or rows) of weights `w` into `n` runs of whole
/// columns of about equal weight: boundary `i` (of `n + 1`, from 0 to `w.len()`) is the last
/// column `c` whose weight before it is at most `i / n` of the total, `Σ w[..c] · n ≤ total ·
/// i` in integers, so equal weights give the area cut `w.len() · i / n` ([`Layout::new`]); then
/// every run keeps at least one column. All weights zero: the area cut. `n` must be 1 to
/// `w.len()`.
pub fn cut_by_weight(w: &[u64], n: usize) -> Vec<usize> {
    let len = w.len();
    let total: u128 = w.iter().map(|&v| v as u128).sum();
    let mut b = vec![0usize; n + 1];
    b[n] = len;
    let mut cum = vec![0u128; len + 1];
    for (c, &v) in w.iter().enumerate() {
        cum[c + 1] = cum[c] + v as u128;
    }
    for i in 1..n {
        let c = if total == 0 { len * i / n } else { cum.partition_point(|&s| s * n as u128 <= total * i as u128) - 1 };
        b[i] = c.max(b[i - 1] + 1).min(len - (n - i));
    }
    b
}

/// A message under way ([`super::codec`]).
type Enc = codec::Enc<Vec<u8>>;

/// The trees `idx` of `t`: count, ids, species, then each of [`TreeStore::f32_columns`].
pub(crate) fn put_trees(e: &mut Enc, t: &TreeStore, idx: &[usize]) {
    e.u64(idx.len() as u64);
    for &i in idx {
        e.u64(t.id[i]);
    }
    for &i in idx {
        e.u16(t.species[i]);
    }
    for c in t.f32_columns() {
        for &i in idx {
            e.f32(c[i]);
        }
    }
}

/// How a message from rank `peer` that ends early or holds too large a count is refused.
pub(crate) fn short_message(peer: usize) -> impl Fn(Short) -> Error {
    move |s| Error::Exchange {
        peer,
        reason: match s {
            Short::End { len, at, need } => format!("message of {len} bytes ends at byte {at} (expected {need} more)"),
            Short::Count { n, rest, .. } => format!("count {n} larger than the rest of the message ({rest} bytes)"),
            Short::Utf8 { at } => format!("text that is not UTF-8 ending at byte {at}"),
        },
    }
}

/// The trees of [`put_trees`].
///
/// Errors: [`Error::Exchange`] (through `d`'s failure) when the message is short.
pub(crate) fn get_trees(d: &mut Dec<'_>) -> Result<TreeStore> {
    let n = d.count(8 + 2 + N_F32_COLUMNS * 4)?;
    let mut t = TreeStore { id: d.u64s_n(n)?, ..Default::default() };
    t.species = d.u16s_n(n)?;
    for c in t.f32_columns_mut() {
        *c = d.f32s_n(n)?;
    }
    Ok(t)
}

/// Writes what a thinning reads of trees `idx` of `t` (issue 37, round 35: [`Tile::manage`]):
/// their count, ids, species, x, y (m), heights (m) and DBHs (cm): 26 bytes a tree, against
/// [`put_trees`]' 54.
pub(crate) fn put_stock(e: &mut Enc, t: &TreeStore, idx: &[usize]) {
    e.u64(idx.len() as u64);
    for &i in idx {
        e.u64(t.id[i]);
    }
    for &i in idx {
        e.u16(t.species[i]);
    }
    for c in [&t.x, &t.y, &t.height, &t.dbh] {
        for &i in idx {
            e.f32(c[i]);
        }
    }
}

/// Reads what [`put_stock`] wrote as a store whose other columns (z, age, crowns, light,
/// vigour, suitability) are 0: the copies a rank merges in for a thinning and drops after it,
/// which a thinning, its harvest record of the stand table ([`super::stats::harvest_sums`]:
/// species, DBH, height) and nothing else reads.
///
/// Errors: [`Error::Exchange`] (through `d`) when the message ends early.
pub(crate) fn get_stock(d: &mut Dec<'_>) -> Result<TreeStore> {
    let n = d.count(8 + 2 + 4 * 4)?;
    let mut t = TreeStore { id: d.u64s_n(n)?, ..Default::default() };
    t.species = d.u16s_n(n)?;
    t.x = d.f32s_n(n)?;
    t.y = d.f32s_n(n)?;
    t.height = d.f32s_n(n)?;
    t.dbh = d.f32s_n(n)?;
    for c in [&mut t.z, &mut t.age, &mut t.crown_radius, &mut t.crown_base, &mut t.light, &mut t.vigour, &mut t.suitability] {
        *c = vec![0.0; n];
    }
    Ok(t)
}

/// [`SeedPlan::owner`] of a seed cell across a tile edge.
const SHARED: u32 = u32::MAX;

/// The seed cells tile `k` of `layout` holds of a seed grid of `cols × rows` cells of `cell_m`
/// metres (columns and rows of seed cells, row 0 south): those of its light cells' centres
/// (regeneration reads them) and those whose centre it owns (its part of an assembled world,
/// [`merge_parts`]), with one cell of margin on each side, and to the grid's edge where the
/// tile is at the light grid's edge. Contains every seed cell the tile owns whole
/// ([`SeedPlan::owner`]).
fn seed_rect(layout: &Layout, k: usize, cols: usize, rows: usize, cell_m: f64) -> CellRect {
    let t = layout.rect(k);
    let lc = layout.light.cell_m;
    let axis = |a0: usize, a1: usize, la: usize, n: usize| -> (usize, usize) {
        let lo = if a0 == 0 { 0 } else { ((a0 as f64 * lc / cell_m) as usize).saturating_sub(1).min(n - 1) };
        let hi = if a1 >= la { n } else { (((a1 as f64 * lc / cell_m) as usize) + 2).min(n) };
        (lo, hi)
    };
    let (col0, col1) = axis(t.col0, t.col1, layout.light.cols, cols);
    let (row0, row1) = axis(t.row0, t.row1, layout.light.rows, rows);
    CellRect { col0, row0, col1, row1 }
}

/// The window of seed grid `g` that tile `k` of `layout` holds in a tiled run (issue 37 Build 1
/// and 3): the seed cells of its light cells' centres and those whose centre it owns, with one
/// cell of margin (to the grid's edge at the light grid's edge): about the tile's area, not the
/// site's. Columns and rows of `g`'s whole grid.
pub fn seed_window(layout: &Layout, k: usize, g: &super::world::SeedGrid) -> CellRect {
    seed_rect(layout, k, g.cols, g.rows, g.cell_m)
}

/// Cuts the seed grids of `w` to the windows tile `me` of `layout` holds ([`seed_window`]);
/// grids already cut to them are left as they are. A world whose seed grids hold other cells
/// (not the whole grid, not the window) is refused.
///
/// Errors: [`Error::Invalid`] naming the pool species whose grid does not hold the window.
pub fn hold_own_seeds(w: &mut World, layout: &Layout, me: usize) -> Result<()> {
    for (p, g) in w.stand.seeds.iter_mut().enumerate() {
        let r = seed_window(layout, me, g);
        if g.held != r && !g.hold(r) {
            return Err(Error::Invalid { context: "tiled run".into(), field: format!("seed grid of pool species {p}"), value: format!("cells {:?} of {} × {}", g.held, g.cols, g.rows), expected: format!("the whole grid or tile {me}'s window {r:?}") });
        }
    }
    Ok(())
}

/// How one pool species' seed grid lies over the tiles of a layout ([`Tile::reproduce`]).
struct SeedPlan {
    /// Columns and rows of the seed grid, its cell (m).
    cols: usize,
    rows: usize,
    cell_m: f64,
    /// The kernel's reach in fine seed cells ([`reproduction::TwoScale::reach`]).
    reach: usize,
    /// Fine cells per coarse cell side.
    block: usize,
    /// Tiles across in the layout.
    nx: usize,
    /// Per seed column (row), the column (row) of tiles that owns every light column (row) a
    /// tree in it can stand on (a tree's seed cell and light cell both come from its position,
    /// [`reproduction::source_cell`], [`LightGrid::cell_of`]; one light cell of margin on each
    /// side), or [`SHARED`]: `cols + rows` entries, not one per cell.
    col_tile: Vec<u32>,
    row_tile: Vec<u32>,
}

impl SeedPlan {
    /// The plan of seed grid `g` with kernel `k` over `layout`'s tiles.
    fn new(layout: &Layout, g: &super::world::SeedGrid, k: &reproduction::TwoScale) -> SeedPlan {
        let reach = k.reach();
        let lc = layout.light.cell_m;
        // light cells (first, last) under seed cells `i` of `n` along an axis of `ln` light cells
        let span = |i: usize, n: usize, ln: usize| -> (usize, usize) {
            let lo = ((i as f64 * g.cell_m / lc) as usize).saturating_sub(1).min(ln - 1);
            let hi = if i + 1 == n { ln - 1 } else { ((((i + 1) as f64 * g.cell_m / lc) as usize) + 1).min(ln - 1) };
            (lo, hi)
        };
        let nx = layout.nx;
        // the tiles' column of a light column, the tiles' row of a light row
        let tx = |col: usize| layout.owner_of_cell(col, 0) % nx;
        let ty = |row: usize| layout.owner_of_cell(0, row) / nx;
        let one = |lo: usize, hi: usize, f: &dyn Fn(usize) -> usize| if f(lo) == f(hi) { f(lo) as u32 } else { SHARED };
        let col_tile = (0..g.cols).map(|c| {
            let (lo, hi) = span(c, g.cols, layout.light.cols);
            one(lo, hi, &tx)
        }).collect();
        let row_tile = (0..g.rows).map(|r| {
            let (lo, hi) = span(r, g.rows, layout.light.rows);
            one(lo, hi, &ty)
        }).collect();
        SeedPlan { cols: g.cols, rows: g.rows, cell_m: g.cell_m, reach, block: g.block, nx, col_tile, row_tile }
    }

    /// The tile that owns every light cell a tree in seed cell `cell` (`row · cols + col`) can
    /// stand on, or [`SHARED`] for a cell across a tile edge.
    #[inline]
    fn owner(&self, cell: usize) -> u32 {
        let (a, b) = (self.col_tile[cell % self.cols], self.row_tile[cell / self.cols]);
        if a == SHARED || b == SHARED {
            SHARED
        } else {
            b * self.nx as u32 + a
        }
    }

    /// The seed cells tile `k` reads and holds ([`seed_window`]).
    fn read(&self, layout: &Layout, k: usize) -> CellRect {
        seed_rect(layout, k, self.cols, self.rows, self.cell_m)
    }

    /// The seed cells whose production tile `k` needs: [`SeedPlan::read`] widened by the reach
    /// and out to whole coarse cells ([`reproduction::disperse`] sums them).
    fn need(&self, layout: &Layout, k: usize) -> CellRect {
        let r = self.read(layout, k);
        let b = self.block;
        let down = |v: usize| v.saturating_sub(self.reach) / b * b;
        let up = |v: usize, n: usize| ((v + self.reach).div_ceil(b) * b).min(n);
        CellRect { col0: down(r.col0), col1: up(r.col1, self.cols), row0: down(r.row0), row1: up(r.row1, self.rows) }
    }
}

/// True when cell index `cell` of a grid of `cols` columns lies in `r`.
#[inline]
fn contains_cell(r: CellRect, cell: usize, cols: usize) -> bool {
    r.contains(cell % cols, cell / cols)
}

/// One tile of a tiled run: a [`World`] whose stand holds only the tile's trees and cohorts,
/// and the layout it belongs to.
pub struct Tile {
    /// The tile's world: the whole site, the tile's stand.
    pub world: World,
    /// The layout of the run.
    pub layout: Layout,
    /// This tile's index in the layout (= its rank).
    pub me: usize,
    /// Bytes sent for halo copies since the start (the stand-table and output gathers not
    /// counted).
    pub halo_bytes: u64,
    /// While halo copies are merged in: their rows, ascending.
    halo_rows: Vec<usize>,
    /// This year's harvest of the whole landscape (stems ≥ 1.3 m, volume m³;
    /// [`super::stats::harvest_sums`]), as the management phase found it (every rank sees every
    /// harvested tree); rank 0 puts it in the stand-table row.
    harvest: (u64, f64),
    /// Trees and bytes this rank has sent to other ranks for the management phase since the
    /// start ([`Tile::manage`]): the trees of the due areas, or only their growing stock in a
    /// year whose due removals are all thinnings to a target.
    pub manage_sent: (u64, u64),
    /// Wall time (s) per phase of [`PHASES`] summed over the years stepped, exchanges and the
    /// waits in them included (for profiling: `SYLVA_PHASE_TIMES=1`, [`Tile::phase_line`]).
    pub phase_seconds: [f64; super::step::N_PHASES],
    /// The part of [`Tile::phase_seconds`] spent passing halos (encoding, the exchange and the
    /// wait in it, merging the copies in, dropping them after).
    pub halo_seconds: [f64; super::step::N_PHASES],
}

impl Tile {
    /// Tile `me` of `layout`, cut from `global`, the world of one process (its trees and
    /// cohorts on the tile's cells; its window of the seed grids, [`seed_window`]), copying only
    /// the tile's part of the site (`clone_for_tile`), not the whole world first. The tile's
    /// tallies start at zero ([`Tile::gather`] adds them to the global world's).
    ///
    /// Errors: [`Error::Invalid`] when `global`'s seed grids hold neither the whole grid nor the
    /// tile's window ([`hold_own_seeds`]).
    pub fn new(global: &World, layout: Layout, me: usize) -> Result<Tile> {
        Tile::own(clone_for_tile(global, &layout, me)?, layout, me)
    }

    /// As [`Tile::new`], taking `world` (the world of one process) instead of copying it: a rank
    /// that no longer needs the whole world (every rank but 0, once its tile exists) then holds
    /// one copy of the site, not two, and not the start's trees of other tiles.
    ///
    /// Errors: as [`Tile::new`].
    pub fn own(mut world: World, layout: Layout, me: usize) -> Result<Tile> {
        keep_own(&mut world, &layout, me);
        hold_own_cells(&mut world, layout.rect(me));
        hold_own_seeds(&mut world, &layout, me)?;
        world.tallies.deaths_total = [0; N_CAUSES];
        world.tallies.regen_ledger = RegenLedger::new(world.site.pool.len());
        world.scratch.dead.clear();
        Ok(Tile { world, layout, me, halo_bytes: 0, halo_rows: Vec::new(), harvest: (0, 0.0), manage_sent: (0, 0), phase_seconds: [0.0; super::step::N_PHASES], halo_seconds: [0.0; super::step::N_PHASES] })
    }

    /// Tile `me` of `layout` from `world`, a tile's world as it was saved (its own trees and
    /// cohorts, the window of the seed grids it held, its tallies: a run's per-rank checkpoint
    /// read back); tallies are kept, this year's dead cleared.
    ///
    /// Errors: as [`Tile::new`].
    pub fn resumed(mut world: World, layout: Layout, me: usize) -> Result<Tile> {
        hold_own_cells(&mut world, layout.rect(me));
        hold_own_seeds(&mut world, &layout, me)?;
        world.scratch.dead.clear();
        Ok(Tile { world, layout, me, halo_bytes: 0, halo_rows: Vec::new(), harvest: (0, 0.0), manage_sent: (0, 0), phase_seconds: [0.0; super::step::N_PHASES], halo_seconds: [0.0; super::step::N_PHASES] })
    }

    /// Rank 0 sends every rank its part of `global` (rank 0's world after a fresh start or a
    /// resume); every rank's tile takes it as its stand, with tallies from zero. Other ranks
    /// pass `None`.
    ///
    /// Errors: [`Error::Exchange`] from the transport or a malformed message.
    pub fn scatter(&mut self, global: Option<&World>, t: &mut dyn Transport) -> Result<()> {
        let n = t.size();
        let mut out = vec![Vec::new(); n];
        if let (0, Some(g)) = (t.rank(), global) {
            out = Tile::parts(g, &self.layout, n)?;
        }
        self.scatter_parts(out, t)
    }

    /// The messages of [`Tile::scatter`] from `global` (rank 0's world): every tile's part of
    /// its stand (trees, cohorts, seed windows, year) for tiles `0..n` of `layout`. Encoded
    /// before the scatter, they let rank 0 cut its world to its tile before the exchange
    /// (`job::tiled`'s `Root::begin_shed`), so the whole world and its tile's copy are not
    /// held at once.
    ///
    /// Errors: [`Error::Invalid`] from the encoding (a seed grid that does not hold a window).
    pub fn parts(global: &World, layout: &Layout, n: usize) -> Result<Vec<Vec<u8>>> {
        (0..n).map(|k| encode_part(global, layout, k)).collect()
    }

    /// [`Tile::scatter`] with the messages `out` already encoded ([`Tile::parts`] on rank 0;
    /// empty messages on the others).
    ///
    /// Errors: as [`Tile::scatter`].
    pub fn scatter_parts(&mut self, out: Vec<Vec<u8>>, t: &mut dyn Transport) -> Result<()> {
        let got = t.exchange(out)?;
        let p = decode_part(&got[0], 0)?;
        let w = &mut self.world;
        if p.seeds.len() != w.stand.seeds.len() || p.seeds.iter().zip(&w.stand.seeds).any(|(a, b)| a.len() != b.data.len()) {
            return Err(Error::Exchange { peer: 0, reason: "seed grids of another shape than this rank's window".into() });
        }
        w.stand.year = p.year;
        // rank 0's next tree id: a tile built without the start's trees has none of its own
        w.stand.trees = p.trees;
        w.stand.trees.next_id = p.next_id;
        w.stand.cohorts = p.cohorts;
        for (g, d) in w.stand.seeds.iter_mut().zip(p.seeds) {
            g.data = d;
        }
        w.tallies.deaths_total = [0; N_CAUSES];
        w.tallies.regen_ledger = RegenLedger::new(w.site.pool.len());
        w.scratch.dead.clear();
        Ok(())
    }

    /// Copies of the other tiles' trees that phases reading `halo` need (within its reach; for
    /// seed sources only the mature trees), merged into the tile's trees by id. For
    /// [`Halo::Crowns`], checks that no crown of any tile is wider than the reach allows.
    fn add_halo(&mut self, t: &mut dyn Transport, halo: Halo) -> Result<()> {
        let n = t.size();
        let tr = &self.world.stand.trees;
        let max_r = tr.crown_radius.iter().fold(0f32, |a, &b| a.max(b));
        let m = self.layout.reach.of_halo(halo);
        let lib = &self.world.site.lib;
        // as reproduction: trees below their species' maturity age produce no seeds
        let source = |i: usize| halo != Halo::SeedSources || tr.age[i] >= lib.species[tr.species[i] as usize].life.maturity_age_yr;
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let mut e = codec::Enc(Vec::new());
            e.f32(max_r);
            if k != self.me {
                let idx: Vec<usize> = (0..tr.len()).filter(|&i| source(i) && self.layout.in_halo(k, tr.x[i], tr.y[i], m)).collect();
                put_trees(&mut e, tr, &idx);
            } else {
                put_trees(&mut e, tr, &[]);
            }
            out.push(e.0);
        }
        let sent0 = t.bytes_sent();
        let got = t.exchange(out)?;
        self.halo_bytes += t.bytes_sent() - sent0;
        let mut parts = Vec::with_capacity(n);
        let mut crown = 0f32;
        for (k, m) in got.iter().enumerate() {
            let fail = short_message(k);
            let mut d = Dec::new(m, &fail);
            crown = crown.max(d.f32()?);
            let p = get_trees(&mut d)?;
            if k != self.me {
                parts.push(p);
            }
        }
        crown = crown.max(max_r);
        let reach = crown as f64 + 2.0 * self.layout.light.cell_m;
        if halo == Halo::Crowns && reach > m {
            return Err(Error::Invalid {
                context: format!("tiled run, year {}", self.world.stand.year + 1),
                field: "halo_m".into(),
                value: format!("{m} m (the light phase's reach)"),
                expected: format!("at least {reach} m: a crown of {crown} m radius plus two light cells"),
            });
        }
        // the copies merged among themselves by id (few), then inserted among the tile's own
        // trees by id (runs moved, [`TreeStore::insert_by_id`]): the order of merge_by_id
        let copies = if parts.len() == 1 { parts.pop().unwrap_or_default() } else { TreeStore::merge_by_id(&parts, 0).0 };
        self.halo_rows = self.world.stand.trees.insert_by_id(&copies);
        Ok(())
    }

    /// Drops the halo copies, keeping the tile's own trees (their order kept).
    fn drop_halo(&mut self) {
        let rows = std::mem::take(&mut self.halo_rows);
        self.world.stand.trees.remove_rows(&rows);
    }

    /// Simulates one year of the tile (the phases of [`crate::sim::step::PHASES`], with the halo
    /// exchanges of the module docs). Every rank calls it in the same year. On rank 0 the
    /// report carries the stand-table row of the whole landscape; on the others the row is
    /// `None`. The counts (trees, established, died) are the whole landscape's on every rank.
    ///
    /// Errors: [`Error::Exchange`] from the transport; [`Error::Invalid`] when a crown grew
    /// wider than the halo allows.
    pub fn step(&mut self, t: &mut dyn Transport) -> Result<YearReport> {
        let mut report = YearReport::default();
        self.world.scratch.dead.clear();
        self.harvest = (0, 0.0);
        let stats = PHASES.len() - 1;
        for (k, phase) in PHASES.iter().enumerate().take(stats) {
            let t0 = Instant::now();
            if phase.halo == Halo::Areas {
                self.manage(t, phase.run, &mut report)?;
                report.phase_seconds[k] = t0.elapsed().as_secs_f64();
                continue;
            }
            if phase.halo == Halo::SeedSources {
                // seeds by grid, not by copies of the seed trees (module docs, step 4)
                let halo_s = self.reproduce(t)?;
                report.phase_seconds[k] = t0.elapsed().as_secs_f64();
                self.halo_seconds[k] += halo_s;
                continue;
            }
            if phase.halo != Halo::None {
                self.add_halo(t, phase.halo)?;
            }
            let t1 = Instant::now();
            (phase.run)(&mut self.world, &mut report);
            let t2 = Instant::now();
            if phase.halo != Halo::None {
                self.drop_halo();
            }
            report.phase_seconds[k] = t0.elapsed().as_secs_f64();
            if phase.halo != Halo::None {
                self.halo_seconds[k] += report.phase_seconds[k] - (t2 - t1).as_secs_f64();
            }
        }
        // stats: the stand table's row from every rank's sums (exact, so their sum is one
        // process's) and counts, added up by all_sum; the top height by a selection over all_sum
        // of counts (`stats::top_height_by`); nothing per tree crosses ranks
        let t0 = Instant::now();
        self.world.stand.year += 1;
        self.stats(t, &mut report)?;
        report.phase_seconds[stats] = t0.elapsed().as_secs_f64();
        for (a, b) in self.phase_seconds.iter_mut().zip(report.phase_seconds) {
            *a += b;
        }
        Ok(report)
    }

    /// The stand table's row of the tiles as they stand now, before any year is stepped (year
    /// 0: the start's trees; rank 0 gets it, the others `None`): the sums of [`Tile::step`]'s
    /// stats over the ranks, without a management table row (trial 41, defect 7). Every rank
    /// calls it together.
    ///
    /// Errors: [`Error::Exchange`] from the transport.
    pub fn start_row(&mut self, t: &mut dyn Transport) -> Result<Option<super::stats::StandRow>> {
        let mut report = YearReport::default();
        self.stats(t, &mut report)?;
        Ok(report.row)
    }

    /// The stats phase of [`Tile::step`] (the world's year already set): the stand table's row
    /// into `report` (rank 0), with the per-species rows and, after year 0, the management
    /// table's rows.
    ///
    /// Errors: [`Error::Exchange`] from the transport or a message cut short.
    fn stats(&mut self, t: &mut dyn Transport, report: &mut YearReport) -> Result<()> {
        let w = &self.world;
        let np = w.site.pool.len();
        let mut words = super::stats::RowSums::of(&w.site, &w.stand.trees).words();
        for c in DeathCause::ALL {
            words.push(w.scratch.dead.iter().filter(|d| d.cause == c).count() as u64);
        }
        let ry = &w.scratch.regen_year;
        words.extend([w.stand.cohorts.total_stems(), ry.germinated, ry.recruited, report.established as u64, w.scratch.dead.len() as u64]);
        words.extend(ry.dead);
        // the drought index over each rank's own light cells (round 44)
        let (dn, ds) = super::stats::drought_sums(&w.site, w.stand.year);
        words.extend([dn, ds]);
        // the dead per species and cause (stems, volume) for the per-species table, last
        words.extend(super::stats::DeadSums::of(&w.site, &w.scratch.dead).words());
        let got = t.all_sum(words)?;
        let nw = super::stats::RowSums::n_words(np);
        let sums = super::stats::RowSums::from_words(&got, np);
        let mut rest = got[nw..].iter().copied();
        let mut next = || rest.next().ok_or_else(|| Error::Exchange { peer: 0, reason: "stand-table sums cut short".into() });
        let mut deaths = [0u64; N_CAUSES];
        for v in deaths.iter_mut() {
            *v = next()?;
        }
        let stems = next()?;
        let mut ry = RegenYear { germinated: next()?, recruited: next()?, ..Default::default() };
        let (est, died) = (next()? as usize, next()? as usize);
        for v in ry.dead.iter_mut() {
            *v = next()?;
        }
        let drought = (next()?, next()?);
        let dw: Vec<u64> = rest.collect();
        if dw.len() != super::stats::DeadSums::n_words(np) {
            return Err(Error::Exchange { peer: 0, reason: "stand-table sums of the dead cut short".into() });
        }
        let dead = super::stats::DeadSums::from_words(&dw, np);
        let tr = &w.stand.trees;
        let h100 = super::stats::top_height_by(&tr.dbh, &tr.height, w.site.area_ha.max(1e-9), sums.stems, &mut |v| t.all_sum(v))?;
        let hs = super::stats::species_top_heights(&w.site, tr, &sums.stems_sp, &mut |v| t.all_sum(v))?;
        let ho = super::stats::species_own_area_top_heights(&w.site, tr, &sums, &mut |v| t.all_sum(v))?;
        report.trees = sums.trees as usize;
        report.established = est;
        report.died = died;
        report.row = (t.rank() == 0).then(|| {
            let mut r = super::stats::row_of(&w.site, w.stand.year, &sums, h100, stems, deaths, ry, self.harvest);
            r.drought_index = super::stats::drought_mean(drought);
            (r.species, r.deaths_volume_m3_ha) = super::stats::species_rows(&w.site, &sums, &dead, &hs, &ho);
            r
        });
        // the management table's rows: each entry's area summed over the ranks as the stand
        // table is (exact sums, one all-sum for every entry; top heights by selection), and
        // each entry's harvest as the management phase found it (every rank sees every
        // harvested tree there)
        if !w.site.management.is_empty() && w.stand.year > 0 {
            let es = super::stats::entry_sums(&w.site, tr);
            let ne = es.len();
            // the saplings a clearing kept open cut are each rank's own cohorts': summed with
            // the areas' sums (the removed trees every rank saw whole)
            // and so are the trees a planting planted (each rank plants the lattice points on its
            // own cells, `phases::management::fill_gaps`)
            let saplings = (0..ne).map(|e| w.scratch.entry_harvest.get(e).map_or(0, |h| h.saplings));
            let planted = (0..ne).map(|e| w.scratch.entry_harvest.get(e).map_or(0, |h| h.planted));
            let got = t.all_sum(es.iter().flat_map(|s| s.words()).chain(saplings).chain(planted).collect())?;
            if got.len() != nw * ne + 2 * ne {
                return Err(Error::Exchange { peer: 0, reason: "management-table sums cut short".into() });
            }
            let harvest: Vec<super::stats::EntryHarvest> = (0..ne).map(|e| super::stats::EntryHarvest { saplings: got[nw * ne + e], planted: got[nw * ne + ne + e], ..w.scratch.entry_harvest.get(e).copied().unwrap_or_default() }).collect();
            let es: Vec<super::stats::RowSums> = got[..nw * ne].chunks(nw).map(|c| super::stats::RowSums::from_words(c, np)).collect();
            let stems: Vec<u64> = es.iter().map(|s| s.stems).collect();
            let h = super::stats::entry_top_heights(&w.site, tr, &stems, &mut |v| t.all_sum(v))?;
            if let Some(r) = report.row.as_mut() {
                r.management = super::stats::entry_rows(&w.site, &es, &h, &harvest);
            }
        }
        Ok(())
    }

    /// Reproduction over tiles (module docs, step 4): seeds are passed as a grid, not as
    /// copies of the seed trees. Per pool species every seed cell is either *pure* (every light
    /// cell a tree in it can stand on belongs to one tile, [`SeedPlan`]) or *shared* (across a
    /// tile edge). Each rank sums its own seed trees' production ([`reproduction::seeds_of`])
    /// per pure cell in id order (f32, as one process adds them) and sends every other rank
    /// the sums of the pure cells it owns within that rank's reach (the cells the rank reads,
    /// [`SeedPlan::read`], widened by the kernel), 4 bytes per cell, and its seed trees in
    /// shared cells there as (cell, id, seeds), 20 bytes each; a rank sums each shared cell's
    /// trees in id order, so every seed cell's production is one process's bit for bit. Then it
    /// spreads the production by the two-scale kernel ([`reproduction::disperse`]) onto the cells it holds,
    /// its window ([`seed_window`]: the cells of its light cells' centres, and of the seed cells
    /// whose centre it owns). What a rank holds of each species grows with its tile, not the
    /// site (issue 37 Build 1): its window (kept), its own production over the window and the
    /// production within the kernel's reach of it (for the year's spreading only), and the
    /// plan's owner per seed column and row. One exchange a year whatever the kernel's length;
    /// no seed tree crosses ranks unless it stands in a seed cell across a tile edge. Returns
    /// the seconds spent passing the sums.
    ///
    /// Errors: [`Error::Exchange`] from the transport or a malformed message.
    fn reproduce(&mut self, t: &mut dyn Transport) -> Result<f64> {
        let (n, me) = (t.size(), self.me);
        let w = &mut self.world;
        let (site, stand) = (&w.site, &mut w.stand);
        let (lib, tr) = (&site.lib, &stand.trees);
        let np = site.pool.len();
        let kernels: Vec<reproduction::TwoScale> = (0..np).map(|p| reproduction::kernel(&lib.species[site.pool[p] as usize].life.dispersal, stand.seeds[p].cell_m, stand.seeds[p].block, super::world::NEAR_FIELD_M)).collect();
        let plans: Vec<SeedPlan> = (0..np).map(|p| SeedPlan::new(&self.layout, &stand.seeds[p], &kernels[p])).collect();
        let pidx: Vec<Option<usize>> = (0..lib.species.len()).map(|s| site.pool_index(s as u16)).collect();
        // own production: per pure cell it owns (over its window, which holds them all), and
        // the trees in shared cells (cell, id, seeds), in id order
        let wins: Vec<CellRect> = plans.iter().map(|pl| pl.read(&self.layout, me)).collect();
        let mut pure: Vec<Vec<f32>> = wins.iter().map(|r| vec![0f32; r.len()]).collect();
        let mut shared: Vec<Vec<(u64, u64, f32)>> = vec![Vec::new(); np];
        for i in 0..tr.len() {
            let Some(p) = pidx[tr.species[i] as usize] else { continue };
            let Some(v) = reproduction::seeds_of(tr, i, lib) else { continue };
            let g = &stand.seeds[p];
            let (c, r) = reproduction::source_cell(g, tr.x[i], tr.y[i]);
            let cell = r * g.cols + c;
            match plans[p].owner(cell) {
                SHARED => shared[p].push((cell as u64, tr.id[i], v)),
                o if o as usize == me && wins[p].contains(c, r) => pure[p][(r - wins[p].row0) * (wins[p].col1 - wins[p].col0) + (c - wins[p].col0)] += v,
                o => {
                    return Err(Error::Exchange { peer: o as usize, reason: format!("tree {} of tile {me} at ({}, {}) m in a seed cell of tile {o} (this tile's window {:?})", tr.id[i], tr.x[i], tr.y[i], wins[p]) });
                }
            }
        }
        // the production of pure cell `(c, r)` owned by this tile
        let own = |p: usize, c: usize, r: usize| pure[p][(r - wins[p].row0) * (wins[p].col1 - wins[p].col0) + (c - wins[p].col0)];
        let t0 = Instant::now();
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let mut e = codec::Enc(Vec::new());
            if k != me {
                for p in 0..np {
                    let (plan, cols) = (&plans[p], stand.seeds[p].cols);
                    let need = plan.need(&self.layout, k);
                    // the cells it owns lie in its window: `need` row-major, cut to the window
                    let w = &wins[p];
                    let (c0, c1, r0, r1) = (need.col0.max(w.col0), need.col1.min(w.col1), need.row0.max(w.row0), need.row1.min(w.row1));
                    let vals: Vec<f32> = (r0..r1.max(r0)).flat_map(|r| (c0..c1.max(c0)).map(move |c| (c, r))).filter(|&(c, r)| plan.owner(r * cols + c) as usize == me).map(|(c, r)| own(p, c, r)).collect();
                    e.f32s(&vals);
                    let sh: Vec<&(u64, u64, f32)> = shared[p].iter().filter(|x| contains_cell(need, x.0 as usize, cols)).collect();
                    e.u64(sh.len() as u64);
                    for x in sh {
                        e.u64(x.0);
                        e.u64(x.1);
                        e.f32(x.2);
                    }
                }
            }
            out.push(e.0);
        }
        let sent0 = t.bytes_sent();
        let got = t.exchange(out)?;
        self.halo_bytes += t.bytes_sent() - sent0;
        let halo_s = t0.elapsed().as_secs_f64();
        let fails: Vec<_> = (0..n).map(short_message).collect();
        let mut decs: Vec<Dec<'_>> = got.iter().enumerate().map(|(k, m)| Dec::new(m, &fails[k])).collect();
        for p in 0..np {
            let plan = &plans[p];
            let (cols, rows) = (stand.seeds[p].cols, stand.seeds[p].rows);
            let need = plan.need(&self.layout, me);
            // the production of every cell within reach (the window plus the kernel's reach):
            // pure cells from their owners, in the order they were sent; shared cells summed
            // over every rank's trees in id order
            let mut theirs: Vec<std::vec::IntoIter<f32>> = Vec::with_capacity(n);
            let mut entries: Vec<(u64, u64, f32)> = shared[p].iter().filter(|x| contains_cell(need, x.0 as usize, cols)).copied().collect();
            for (k, d) in decs.iter_mut().enumerate() {
                if k == me {
                    theirs.push(Vec::new().into_iter());
                    continue;
                }
                theirs.push(d.f32s()?.into_iter());
                let m = d.count(20)?;
                for _ in 0..m {
                    let (cell, id, v) = (d.u64()?, d.u64()?, d.f32()?);
                    if !contains_cell(need, cell as usize, cols) || plan.owner(cell as usize) != SHARED {
                        return Err(Error::Exchange { peer: k, reason: format!("seeds of tree {id} in seed cell {cell}, not a shared cell within reach") });
                    }
                    entries.push((cell, id, v));
                }
            }
            let (w_n, h_n) = (need.col1 - need.col0, need.row1 - need.row0);
            let mut src = vec![0f32; w_n * h_n];
            for (j, c) in need.cells(cols).enumerate() {
                let o = plan.owner(c);
                if o == SHARED {
                    continue;
                }
                src[j] = if o as usize == me {
                    own(p, c % cols, c / cols)
                } else {
                    theirs[o as usize].next().ok_or_else(|| Error::Exchange { peer: o as usize, reason: format!("seed production cut short for pool species {p}") })?
                };
            }
            entries.sort_unstable_by_key(|x| (x.0, x.1));
            for &(cell, _, v) in &entries {
                let (c, r) = (cell as usize % cols, cell as usize / cols);
                src[(r - need.row0) * w_n + (c - need.col0)] += v;
            }
            if let Some(k) = theirs.iter().position(|it| it.len() > 0) {
                return Err(Error::Exchange { peer: k, reason: format!("{} seed production values too many for pool species {p}", theirs[k].len()) });
            }
            let g = &mut stand.seeds[p];
            let read = wins[p];
            if g.held != read {
                return Err(Error::Exchange { peer: me, reason: format!("seed grid of pool species {p} holds {:?}, not this tile's window {read:?}", g.held) });
            }
            // onto the window, row-major: the grid's data in its order
            g.data = reproduction::disperse(&kernels[p], cols, rows, g.cell_m, need, &src, read);
        }
        Ok(halo_s)
    }

    /// One line of this rank's wall time per phase over the years stepped, with the part spent
    /// on halos in brackets (`phase times rank R: light 3.1 s (halo 0.4 s), …`), for
    /// `SYLVA_PHASE_TIMES=1`.
    pub fn phase_line(&self) -> String {
        let list: Vec<String> = PHASES
            .iter()
            .enumerate()
            .map(|(k, p)| if self.halo_seconds[k] > 0.0 { format!("{} {:.1} s (halo {:.1} s)", p.name, self.phase_seconds[k], self.halo_seconds[k]) } else { format!("{} {:.1} s", p.name, self.phase_seconds[k]) })
            .collect();
        format!("phase times rank {}: {}; management sent {} trees, {} bytes", self.me, list.join(", "), self.manage_sent.0, self.manage_sent.1)
    }

    /// The management phase `run` over tiles (module docs, step 6): in a year with thinnings,
    /// harvests or plantings due (a planting fills the gaps of its area's trees; round 44), every rank's trees standing in their areas go to every other rank and are
    /// merged with the rank's own by id; `run` carries out the year's entries on that store as
    /// one process does; the rank keeps its own trees (planted ones on its cells included) and
    /// the harvested dead it owns (the harvest tally follows), and records the year's harvest
    /// sums over every harvested tree (in the order one process records them) for the stand
    /// table. One exchange in such a year, none otherwise; every rank calls it in the same year.
    ///
    /// In a year whose due removals are all thinnings to a target ([`Action::Thinning`]; issue
    /// 37, round 35) only the areas' **growing stock** is sent, and only what a thinning reads
    /// of it ([`put_stock`]: id, species, position, height, DBH; 26 bytes a tree instead of
    /// 54): the stems of at least 1.3 m and [`super::density::MIN_DBH_CM`] DBH. A thinning
    /// reads nothing else (its top height,
    /// main stand, figures, ranking and cut are all over that stock, in id order,
    /// `phases::management::thinning`), and it removes only such stems, so the harvest sums
    /// and every removal are one process's; the understorey and regeneration of the areas
    /// (most of the trees of a young stand) no longer cross ranks. Crop-tree thinnings,
    /// shelterwood, patch and clear cuts (which read or remove trees of every size, or their
    /// neighbours) keep the whole areas' trees.
    ///
    /// [`Action::Thinning`]: super::management::Action::Thinning
    ///
    /// Errors: [`Error::Exchange`] from the transport or a malformed message.
    fn manage(&mut self, t: &mut dyn Transport, run: fn(&mut World, &mut YearReport), report: &mut YearReport) -> Result<()> {
        if self.world.site.management.is_empty() {
            // nothing to do (as `run` finds): no exchange, no pass over the trees
            self.harvest = super::stats::harvest_sums(&self.world.site, &[]);
            return Ok(());
        }
        let year = self.world.stand.year + 1;
        let site = &self.world.site;
        use super::management::Action;
        // a planting reads the trees of its area too (it fills their gaps,
        // `phases::management::fill_gaps`; round 44), so its area's trees are exchanged as a
        // removal's are
        let due: Vec<&super::management::Operation> = site.management.iter().filter(|op| op.spec.due(year).is_some()).collect();
        if !due.is_empty() {
            let stock_only = due.iter().all(|op| matches!(op.action, Action::Thinning { .. }));
            let tr = &self.world.stand.trees;
            let idx: Vec<usize> = (0..tr.len()).filter(|&i| (!stock_only || (tr.height[i] >= 1.3 && tr.dbh[i] >= super::density::MIN_DBH_CM)) && due.iter().any(|op| op.region.contains(tr.x[i] as f64, tr.y[i] as f64))).collect();
            let mut e = codec::Enc(Vec::new());
            if stock_only {
                put_stock(&mut e, tr, &idx);
            } else {
                put_trees(&mut e, tr, &idx);
            }
            let k = t.size().saturating_sub(1) as u64;
            self.manage_sent.0 += idx.len() as u64 * k;
            self.manage_sent.1 += e.0.len() as u64 * k;
            let mut out = vec![e.0; t.size()];
            out[self.me] = Vec::new();
            let got = t.exchange(out)?;
            let mut parts = Vec::with_capacity(got.len());
            for (k, m) in got.iter().enumerate().filter(|&(k, _)| k != self.me) {
                let fail = short_message(k);
                let mut d = Dec::new(m, &fail);
                parts.push(if stock_only { get_stock(&mut d)? } else { get_trees(&mut d)? });
            }
            let own = std::mem::take(&mut self.world.stand.trees);
            let next = own.next_id;
            parts.push(own);
            self.world.stand.trees = TreeStore::merge_by_id(&parts, next).0;
        }
        let dead0 = self.world.scratch.dead.len();
        run(&mut self.world, report);
        let w = &mut self.world;
        self.harvest = super::stats::harvest_sums(&w.site, &w.scratch.dead[dead0..]);
        let (layout, me) = (&self.layout, self.me);
        let tr = &w.stand.trees;
        let keep: Vec<bool> = (0..tr.len()).map(|i| layout.owner_of(tr.x[i], tr.y[i]) == me).collect();
        // the trees each planting planted on this rank's own cells (it planted its halo's too),
        // summed over the ranks by the stats phase
        for (h, at) in w.scratch.entry_harvest.iter_mut().zip(&w.scratch.planted_at) {
            h.planted = at.iter().filter(|p| layout.owner_of(p[0], p[1]) == me).count() as u64;
        }
        w.stand.trees.retain(&keep);
        let mut k = 0;
        let before = w.scratch.dead.len();
        w.scratch.dead.retain(|d| {
            k += 1;
            k <= dead0 || layout.owner_of(d.x, d.y) == me
        });
        w.tallies.deaths_total[DeathCause::Harvest.index()] -= (before - w.scratch.dead.len()) as u64;
        Ok(())
    }

    /// Sums per bin over every tile's trees, exactly as one process sums them (f64, in id
    /// order), without sending rank 0 the trees: `bin(store, i)` is tree `i`'s bin (of `bins`),
    /// `value(store, i)` what it adds. Each rank sums its own trees per bin and sends the bins it
    /// has trees in (16 bytes each); a bin with trees on one rank only takes that rank's sum (the
    /// same trees in the same order as in one process); rank 0 names the bins with trees on
    /// several ranks, and only their trees (id, bin, value: 24 bytes each) are sent and summed
    /// in id order. Rank 0 returns the sums (0 for bins without trees); other ranks `None`.
    /// Three exchanges.
    ///
    /// Errors: [`Error::Exchange`] from the transport, a malformed message or a bin out of range.
    pub fn gather_bin_sums(&self, t: &mut dyn Transport, bins: usize, bin: impl Fn(&TreeStore, usize) -> usize, value: impl Fn(&TreeStore, usize) -> f64) -> Result<Option<Vec<f64>>> {
        let tr = &self.world.stand.trees;
        let n = t.size();
        let of: Vec<usize> = (0..tr.len()).map(|i| bin(tr, i)).collect();
        let mut sums: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
        for (i, &b) in of.iter().enumerate() {
            *sums.entry(b).or_insert(0.0) += value(tr, i);
        }
        let mut pairs: Vec<(usize, f64)> = sums.into_iter().collect();
        pairs.sort_unstable_by_key(|p| p.0);
        let mut e = codec::Enc(Vec::new());
        e.u64(pairs.len() as u64);
        for (b, v) in &pairs {
            e.u64(*b as u64);
            e.u64(v.to_bits());
        }
        let mut out = vec![Vec::new(); n];
        out[0] = e.0;
        let got = t.exchange(out)?;
        // rank 0: the sums of bins on one rank; the bins on several
        let mut acc = Vec::new();
        let mut shared = Vec::new();
        if t.rank() == 0 {
            acc = vec![0f64; bins];
            let mut seen = vec![0u8; bins];
            for (k, m) in got.iter().enumerate() {
                let fail = short_message(k);
                let mut d = Dec::new(m, &fail);
                let c = d.count(16)?;
                for _ in 0..c {
                    let b = d.u64()? as usize;
                    let v = f64::from_bits(d.u64()?);
                    if b >= bins {
                        return Err(Error::Exchange { peer: k, reason: format!("map bin {b} out of range (0–{})", bins - 1) });
                    }
                    acc[b] = v;
                    seen[b] = seen[b].saturating_add(1);
                }
            }
            shared = (0..bins).filter(|&b| seen[b] > 1).collect::<Vec<usize>>();
        }
        let mut e = codec::Enc(Vec::new());
        e.u64(shared.len() as u64);
        shared.iter().for_each(|&b| e.u64(b as u64));
        let got = t.exchange(vec![e.0; n])?;
        let fail = short_message(0);
        let mut d = Dec::new(&got[0], &fail);
        let c = d.count(8)?;
        let shared: std::collections::HashSet<usize> = (0..c).map(|_| d.u64().map(|b| b as usize)).collect::<Result<_>>()?;
        let mut e = codec::Enc(Vec::new());
        let mine: Vec<usize> = (0..tr.len()).filter(|&i| shared.contains(&of[i])).collect();
        e.u64(mine.len() as u64);
        for &i in &mine {
            e.u64(tr.id[i]);
            e.u64(of[i] as u64);
            e.u64(value(tr, i).to_bits());
        }
        let mut out = vec![Vec::new(); n];
        out[0] = e.0;
        let got = t.exchange(out)?;
        if t.rank() != 0 {
            return Ok(None);
        }
        let mut trees: Vec<(u64, usize, f64)> = Vec::new();
        for (k, m) in got.iter().enumerate() {
            let fail = short_message(k);
            let mut d = Dec::new(m, &fail);
            let c = d.count(24)?;
            for _ in 0..c {
                let (id, b, v) = (d.u64()?, d.u64()? as usize, f64::from_bits(d.u64()?));
                if !shared.contains(&b) {
                    return Err(Error::Exchange { peer: k, reason: format!("map bin {b} was not asked for") });
                }
                trees.push((id, b, v));
            }
        }
        trees.sort_unstable_by_key(|e| e.0);
        for &b in &shared {
            acc[b] = 0.0;
        }
        for (_, b, v) in trees {
            acc[b] += v;
        }
        Ok(Some(acc))
    }

    /// Every rank sends its whole stand (trees, cohorts, its seed cells, this year's dead,
    /// tallies) to rank 0, which writes it into `global` (the world of one process at the same
    /// year: what the outputs and the checkpoint read). Tallies: `base` (the global world's at
    /// the start of the tiled run) plus every tile's. Other ranks pass `None`.
    ///
    /// Errors: [`Error::Exchange`] from the transport or a malformed message.
    pub fn gather(&self, global: Option<(&mut World, &Tallies)>, t: &mut dyn Transport) -> Result<()> {
        let mut out = vec![Vec::new(); t.size()];
        out[0] = encode_part(&self.world, &self.layout, self.me)?;
        let got = t.exchange(out)?;
        let Some((g, base)) = global else { return Ok(()) };
        if t.rank() != 0 {
            return Ok(());
        }
        let parts = got.iter().enumerate().map(|(k, m)| decode_part(m, k)).collect::<Result<Vec<_>>>()?;
        merge_parts(g, base, &self.layout, parts)
    }
}

/// Writes into `g` the world of one process made of the tile parts `parts` (part `k` from tile
/// `k` of `layout`): trees merged by id, cohorts sorted by (cell, species), each seed cell from
/// the tile owning its centre (part `k`'s seeds: its window, [`seed_window`]; `g`'s grids
/// whole), this year's dead sorted by id, tallies `base` plus every part's,
/// the year of the last part. `g.stand.trees.next_id` is kept.
///
/// Errors: [`Error::Exchange`] naming the part whose seed grids have another shape than `g`'s.
fn merge_parts(g: &mut World, base: &Tallies, layout: &Layout, parts: Vec<Part>) -> Result<()> {
    let mut trees = Vec::with_capacity(parts.len());
    let mut cohorts: Vec<(u32, u16, usize, usize)> = Vec::new();
    let mut coh_parts = Vec::with_capacity(parts.len());
    let mut dead: Vec<DeadTree> = Vec::new();
    g.tallies.deaths_total = base.deaths_total;
    g.tallies.regen_ledger = base.regen_ledger.clone();
    if g.tallies.regen_ledger.germinated.len() != g.site.pool.len() {
        g.tallies.regen_ledger = RegenLedger::new(g.site.pool.len());
    }
    g.scratch.regen_year = RegenYear::default();
    for (k, w) in parts.into_iter().enumerate() {
        trees.push(w.trees);
        for i in 0..w.cohorts.len() {
            cohorts.push((w.cohorts.cell[i], w.cohorts.pool[i], k, i));
        }
        coh_parts.push(w.cohorts);
        dead.extend(w.dead);
        for (a, b) in g.tallies.deaths_total.iter_mut().zip(w.deaths_total) {
            *a += b;
        }
        let (l, m) = (&mut g.tallies.regen_ledger, &w.ledger);
        for p in 0..l.germinated.len().min(m.germinated.len()) {
            l.germinated[p] += m.germinated[p];
            l.recruited[p] += m.recruited[p];
            for q in 0..N_REGEN_CAUSES {
                l.dead[p][q] += m.dead[p][q];
            }
        }
        let ry = &mut g.scratch.regen_year;
        ry.germinated += w.regen_year.germinated;
        ry.recruited += w.regen_year.recruited;
        for q in 0..N_REGEN_CAUSES {
            ry.dead[q] += w.regen_year.dead[q];
        }
        // the seed cells this tile owns (the tile of the seed cell's centre), all in its window
        if w.seeds.len() != g.stand.seeds.len() {
            return Err(Error::Exchange { peer: k, reason: format!("{} seed grids, expected {}", w.seeds.len(), g.stand.seeds.len()) });
        }
        for (gs, s) in g.stand.seeds.iter_mut().zip(&w.seeds) {
            let win = seed_window(layout, k, gs);
            if s.len() != win.len() || !gs.holds_all() {
                return Err(Error::Exchange { peer: k, reason: format!("seed window of {} cells, expected {} (of a whole grid of {} × {})", s.len(), win.len(), gs.cols, gs.rows) });
            }
            for (j, cell) in win.cells(gs.cols).enumerate() {
                let (c, r) = (cell % gs.cols, cell / gs.cols);
                let (x, y) = (((c as f64 + 0.5) * gs.cell_m) as f32, ((r as f64 + 0.5) * gs.cell_m) as f32);
                if layout.owner_of(x, y) == k {
                    gs.data[cell] = s[j];
                }
            }
        }
        g.stand.year = w.year;
    }
    let next = g.stand.trees.next_id;
    g.stand.trees = TreeStore::merge_by_id(&trees, next).0;
    cohorts.sort_unstable_by_key(|e| (e.0, e.1));
    let mut c = Cohorts::default();
    for (_, _, k, i) in cohorts {
        c.push(coh_parts[k].get(i));
    }
    g.stand.cohorts = c;
    dead.sort_by_key(|d| d.id);
    g.scratch.dead = dead;
    Ok(())
}

/// Writes into `global` the world of one process made of the tile worlds `tiles` (tile `k` of
/// `layout`, e.g. read back from a run's per-rank checkpoints): as [`Tile::gather`], with every
/// tile's tallies added to zero (the tiles' tallies add up to the run's: rank 0's holds the
/// tallies from before the tiled run began). `global.stand.trees.next_id` is kept.
///
/// Errors: [`Error::Invalid`] when `tiles` does not hold one world per tile of `layout`;
/// [`Error::Exchange`] naming the tile whose seed grids have another shape than `global`'s.
pub fn assemble(global: &mut World, layout: &Layout, tiles: Vec<World>) -> Result<()> {
    if tiles.len() != layout.len() {
        return Err(Error::Invalid { context: "tiled run".into(), field: "tiles".into(), value: format!("{} tile worlds", tiles.len()), expected: format!("{} (the layout's {} × {} tiles)", layout.len(), layout.nx, layout.ny) });
    }
    let zero = Tallies { deaths_total: [0; N_CAUSES], regen_ledger: RegenLedger::new(global.site.pool.len()) };
    let parts = tiles
        .into_iter()
        .enumerate()
        .map(|(k, w)| Part {
            year: w.stand.year,
            next_id: w.stand.trees.next_id,
            // the tile's window (a tile world holds it; a whole grid is cut to it)
            seeds: w.stand.seeds.into_iter().map(|g| g.window(seed_window(layout, k, &g)).unwrap_or_default()).collect(),
            trees: w.stand.trees,
            cohorts: w.stand.cohorts,
            dead: w.scratch.dead,
            deaths_total: w.tallies.deaths_total,
            ledger: w.tallies.regen_ledger,
            regen_year: w.scratch.regen_year,
        })
        .collect();
    merge_parts(global, &zero, layout, parts)
}

/// Makes `w` the world of the tile whose light cells are `rect` (its `site.window`) and cuts
/// the per-light-cell arrays that a tile reads on its own cells only to them (issue 37 Build 1,
/// [`super::light_grid::Span`]): the site cell of each light cell (`site.light_site`: the light
/// phase lights the tile's trees by it, regeneration steps its cells by it), the ground free
/// of obstacles (`site.ground_free`) and the ground light (`scratch.ground_light`, written by
/// the light phase on the tile's cells, read by regeneration there). Arrays already cut (a
/// world that is a tile's) are left as they are.
fn hold_own_cells(w: &mut World, rect: super::light_grid::CellRect) {
    let light = w.site.light;
    let span = super::light_grid::Span::new(Some(rect), &light);
    if w.site.light_site.len() == light.len() {
        w.site.light_site = span.cut(&w.site.light_site);
    }
    if w.site.ground_free.len() == light.len() {
        w.site.ground_free = span.cut(&w.site.ground_free);
    }
    if w.scratch.ground_light.len() == light.len() {
        w.scratch.ground_light = span.cut(&w.scratch.ground_light);
    }
    if w.scratch.canopy_top.len() == light.len() {
        w.scratch.canopy_top = span.cut(&w.scratch.canopy_top);
    }
    w.site.window = Some(rect);
    hold_own_site(w, rect);
}

/// Site cells a tile holds around its own light cells (issue 37 Build 1): its trees and
/// recruits stand on its own cells, and a point there reads its site cell and (the bilinear
/// elevation of a new tree) the next cell on each side; one more for the rounding of the cell
/// boundaries.
pub const SITE_HALO_CELLS: usize = 2;

/// Cuts the site grids of `w` (the conditions, relative insolation and suitability, per site
/// cell) to the site cells under the light cells `rect` plus [`SITE_HALO_CELLS`] (issue 37
/// Build 1): what a tile's phases read of the site (the light of its trees and its ground, its
/// regeneration and recruits, the suitability of its trees under a changing climate, the wind
/// exposure of its trees, the plantings on its cells). The checkpoint identity of the whole
/// site is kept first ([`Site::whole_identity`]). A site already cut is left as it is.
fn hold_own_site(w: &mut World, rect: CellRect) {
    let c = &w.site.conditions;
    if !c.holds_all() {
        return;
    }
    let l = w.site.light.cell_m;
    let win = c.window_of(rect.col0 as f64 * l, rect.row0 as f64 * l, rect.col1 as f64 * l, rect.row1 as f64 * l, SITE_HALO_CELLS);
    if win == c.held {
        return;
    }
    w.site.whole_identity = Some(super::checkpoint::site_identity(c));
    let full = c.held;
    let cut = |v: Vec<f32>| win.cut(&crate::grid::Grid { width: full.width, height: full.height, data: v }, &full).data;
    w.site.rel_insolation = cut(std::mem::take(&mut w.site.rel_insolation));
    for s in w.site.suitability.iter_mut() {
        *s = cut(std::mem::take(s));
    }
    w.site.conditions.hold(win);
}

/// Cuts `w`, the world of one process that a tiled run's driver keeps on rank 0 besides its
/// tile, to what the driver reads once the tiles hold the stand (issue 37 Build 1,
/// `job::run::Stepper::shed`): the site cut to tile `me`'s cells as [`Tile::own`] cuts it (the
/// light cells' arrays to its rectangle, the conditions, relative insolation and suitability
/// to its site cells plus [`SITE_HALO_CELLS`], the whole site's checkpoint identity kept), the
/// seed grids to its window ([`seed_window`]), and no trees or cohorts (the tiles hold them;
/// the next tree id is kept). The year, tallies, pool, library, extent and georeferencing are
/// kept. Arrays already cut are left as they are.
///
/// Errors: as [`hold_own_seeds`].
pub fn shed_to_tile(w: &mut World, layout: &Layout, me: usize) -> Result<()> {
    let next_id = w.stand.trees.next_id;
    w.stand.trees = TreeStore::default();
    w.stand.trees.next_id = next_id;
    w.stand.cohorts = Cohorts::default();
    w.scratch.grid = Default::default();
    w.scratch.dead = Vec::new();
    hold_own_cells(w, layout.rect(me));
    hold_own_seeds(w, layout, me)
}

/// A copy of `global` for tile `me` of `layout` that copies only the tile's part of the site
/// and seed grids (issue 37 Build 1: rank 0 makes its tile from the run driver's world, which
/// stays whole until [`shed_to_tile`]; copying it whole first held the whole site twice for a
/// moment): the conditions, relative insolation and suitability of the site cells
/// [`hold_own_site`] keeps, the light cells' arrays of the tile's rectangle, each seed grid's
/// window ([`seed_window`]), with the whole site's checkpoint identity; the stand's trees and
/// cohorts and the rest copied as they are (the tile keeps its own, [`Tile::own`]). The values
/// are those [`Tile::own`] cuts from a whole copy. A `global` whose site is already cut is
/// copied whole.
///
/// Errors: [`Error::Invalid`] naming the pool species whose seed grid holds neither the whole
/// grid nor the tile's window (as [`hold_own_seeds`]).
fn clone_for_tile(global: &World, layout: &Layout, me: usize) -> Result<World> {
    let g = &global.site;
    let c = &g.conditions;
    if !c.holds_all() {
        return Ok(global.clone());
    }
    let rect = layout.rect(me);
    let light = g.light;
    let span = super::light_grid::Span::new(Some(rect), &light);
    let l = light.cell_m;
    let win = c.window_of(rect.col0 as f64 * l, rect.row0 as f64 * l, rect.col1 as f64 * l, rect.row1 as f64 * l, SITE_HALO_CELLS);
    let full = c.held;
    // the window's cells of a per-site-cell vector over the whole grid (as `hold_own_site`)
    let cut = |v: &[f32]| -> Vec<f32> {
        let mut out = Vec::with_capacity(win.width * win.height);
        for r in win.row0..win.row1() {
            let i = (r - full.row0) * full.width + (win.col0 - full.col0);
            out.extend_from_slice(&v[i..i + win.width]);
        }
        out
    };
    let conditions = crate::conditions::SiteConditions {
        geo: c.geo.clone(),
        cell_x_m: c.cell_x_m,
        cell_y_m: c.cell_y_m,
        mask: win.cut(&c.mask, &full),
        elevation_m: win.cut(&c.elevation_m, &full),
        slope_deg: win.cut(&c.slope_deg, &full),
        aspect_deg: win.cut(&c.aspect_deg, &full),
        twi: win.cut(&c.twi, &full),
        insolation_kwh_m2: win.cut(&c.insolation_kwh_m2, &full),
        wind_exposure: win.cut(&c.wind_exposure, &full),
        temperature_c: win.cut(&c.temperature_c, &full),
        indices: win.cut(&c.indices, &full),
        held: win,
        full: c.full,
    };
    let whole_identity = if win == full { g.whole_identity.clone() } else { Some(super::checkpoint::site_identity(c)) };
    let per_light = |v: &[f32]| if v.len() == light.len() { span.cut(v) } else { v.to_vec() };
    let site = Site {
        conditions,
        lib: g.lib.clone(),
        pool: g.pool.clone(),
        seed: g.seed,
        extent: g.extent,
        area_ha: g.area_ha,
        light,
        light_site: if g.light_site.len() == light.len() { span.cut(&g.light_site) } else { g.light_site.clone() },
        rel_insolation: cut(&g.rel_insolation),
        suitability: g.suitability.iter().map(|v| cut(v)).collect(),
        whole_identity,
        seed_rain: g.seed_rain.clone(),
        obstacles: g.obstacles.clone(),
        obstacle_canopy: g.obstacle_canopy.clone(),
        ground_free: per_light(&g.ground_free),
        window: Some(rect),
        management: g.management.clone(),
        climate_change: g.climate_change.clone(),
        drought_base: std::sync::OnceLock::new(),
    };
    let mut seeds = Vec::with_capacity(global.stand.seeds.len());
    for (p, sg) in global.stand.seeds.iter().enumerate() {
        let r = seed_window(layout, me, sg);
        let data = sg.window(r).ok_or_else(|| Error::Invalid { context: "tiled run".into(), field: format!("seed grid of pool species {p}"), value: format!("cells {:?} of {} × {}", sg.held, sg.cols, sg.rows), expected: format!("the whole grid or tile {me}'s window {r:?}") })?;
        seeds.push(super::world::SeedGrid { cell_m: sg.cell_m, block: sg.block, cols: sg.cols, rows: sg.rows, held: r, data });
    }
    let stand = super::world::Stand { trees: global.stand.trees.clone(), year: global.stand.year, cohorts: global.stand.cohorts.clone(), seeds };
    let scratch = super::world::Scratch { grid: global.scratch.grid.clone(), ground_light: per_light(&global.scratch.ground_light), canopy_top: per_light(&global.scratch.canopy_top), dead: global.scratch.dead.clone(), regen_year: global.scratch.regen_year.clone(), entry_harvest: global.scratch.entry_harvest.clone(), planted_at: Vec::new() };
    Ok(World { site, stand, scratch, tallies: global.tallies.clone() })
}

/// Keeps in `w` only the trees and cohorts of tile `me` of `layout`.
fn keep_own(w: &mut World, layout: &Layout, me: usize) {
    let t = &w.stand.trees;
    let keep: Vec<bool> = (0..t.len()).map(|i| layout.owner_of(t.x[i], t.y[i]) == me).collect();
    w.stand.trees.retain(&keep);
    let c = &w.stand.cohorts;
    let mut own = Cohorts::default();
    for i in 0..c.len() {
        let (col, row) = layout.light.col_row(c.cell[i] as usize);
        if layout.owner_of_cell(col, row) == me {
            own.push(c.get(i));
        }
    }
    w.stand.cohorts = own;
}

/// The part of `w` that tile `k` owns: year, trees, cohorts, tile `k`'s window of each seed
/// grid ([`seed_window`]; `w` holds the whole grids, or is tile `k`'s world), this year's
/// dead, tallies, this year's regeneration counts.
///
/// Errors: [`Error::Exchange`] naming tile `k` when a seed grid of `w` does not hold its window.
fn encode_part(w: &World, layout: &Layout, k: usize) -> Result<Vec<u8>> {
    let mut e = codec::Enc(Vec::new());
    e.u64(w.stand.year as u64);
    e.u64(w.stand.trees.next_id);
    let t = &w.stand.trees;
    let idx: Vec<usize> = (0..t.len()).filter(|&i| layout.owner_of(t.x[i], t.y[i]) == k).collect();
    put_trees(&mut e, t, &idx);
    let c = &w.stand.cohorts;
    let own: Vec<usize> = (0..c.len()).filter(|&i| {
        let (col, row) = layout.light.col_row(c.cell[i] as usize);
        layout.owner_of_cell(col, row) == k
    }).collect();
    e.u64(own.len() as u64);
    for &i in &own {
        e.u64(c.cell[i] as u64);
        e.u64(c.pool[i] as u64);
        e.u64(c.stems[i] as u64);
        e.f32(c.height[i]);
        e.f32(c.age[i]);
        e.f32(c.vigour[i]);
        e.u64(c.stress_years[i] as u64);
    }
    e.u64(w.stand.seeds.len() as u64);
    for s in &w.stand.seeds {
        let r = seed_window(layout, k, s);
        let v = s.window(r).ok_or_else(|| Error::Exchange { peer: k, reason: format!("seed grid holding {:?}, not tile {k}'s window {r:?}", s.held) })?;
        e.u64(v.len() as u64);
        v.iter().for_each(|&x| e.f32(x));
    }
    let dead: Vec<&DeadTree> = w.scratch.dead.iter().filter(|d| layout.owner_of(d.x, d.y) == k).collect();
    e.u64(dead.len() as u64);
    for d in dead {
        e.u64(d.id);
        e.u64(d.species as u64);
        for v in [d.x, d.y, d.z, d.age, d.height, d.dbh, d.crown_radius, d.crown_base] {
            e.f32(v);
        }
        e.u64(d.year as u64);
        e.u64(d.cause.index() as u64);
    }
    w.tallies.deaths_total.iter().for_each(|&v| e.u64(v));
    let l = &w.tallies.regen_ledger;
    e.u64(l.germinated.len() as u64);
    for p in 0..l.germinated.len() {
        e.u64(l.germinated[p]);
        e.u64(l.recruited[p]);
        l.dead[p].iter().for_each(|&v| e.u64(v));
    }
    let ry = &w.scratch.regen_year;
    e.u64(ry.germinated);
    e.u64(ry.recruited);
    ry.dead.iter().for_each(|&v| e.u64(v));
    Ok(e.0)
}

/// A tile's part of a world, as passed by [`encode_part`].
struct Part {
    year: u32,
    /// The sender's next tree id ([`TreeStore::next_id`]): rank 0's whole world's in a
    /// scatter, which a tile built without the start's trees takes
    /// ([`World::skeleton`], [`derive_tile_site`]).
    next_id: u64,
    trees: TreeStore,
    cohorts: Cohorts,
    seeds: Vec<Vec<f32>>,
    dead: Vec<DeadTree>,
    deaths_total: [u64; N_CAUSES],
    ledger: RegenLedger,
    regen_year: RegenYear,
}

/// Reads a message of [`encode_part`] from rank `peer`.
fn decode_part(m: &[u8], peer: usize) -> Result<Part> {
    let fail = short_message(peer);
    let mut d = Dec::new(m, &fail);
    let bad = |what: &str, v: u64| Error::Exchange { peer, reason: format!("{what} {v} out of range") };
    let year = d.u64()?;
    let year = u32::try_from(year).map_err(|_| bad("year", year))?;
    let next_id = d.u64()?;
    let trees = get_trees(&mut d)?;
    let n = d.count(4 * 8 + 3 * 4)?;
    let mut cohorts = Cohorts::default();
    for _ in 0..n {
        let (cell, pool, stems) = (d.u64()?, d.u64()?, d.u64()?);
        let (height, age, vigour) = (d.f32()?, d.f32()?, d.f32()?);
        let sy = d.u64()?;
        let stress_years = u16::try_from(sy).map_err(|_| bad("cohort stress years", sy))?;
        cohorts.push(super::cohorts::Cohort { cell: u32::try_from(cell).map_err(|_| bad("cohort cell", cell))?, pool: u16::try_from(pool).map_err(|_| bad("cohort pool", pool))?, stems: u32::try_from(stems).map_err(|_| bad("cohort stems", stems))?, height, age, vigour, stress_years });
    }
    let ns = d.count(8)?;
    let mut seeds = Vec::with_capacity(ns);
    for _ in 0..ns {
        let n = d.count(4)?;
        seeds.push(d.f32s_n(n)?);
    }
    let n = d.count(8 * 4 + 8 * 4)?;
    let mut dead = Vec::with_capacity(n);
    for _ in 0..n {
        let (id, species) = (d.u64()?, d.u64()?);
        let v = d.f32s_n(8)?;
        let (year, cause) = (d.u64()?, d.u64()?);
        let cause = *DeathCause::ALL.get(cause as usize).ok_or_else(|| bad("cause of death", cause))?;
        dead.push(DeadTree { id, species: species as u16, x: v[0], y: v[1], z: v[2], age: v[3], height: v[4], dbh: v[5], crown_radius: v[6], crown_base: v[7], year: year as u32, cause });
    }
    let mut deaths_total = [0u64; N_CAUSES];
    for v in deaths_total.iter_mut() {
        *v = d.u64()?;
    }
    let np = d.count(8 * (2 + N_REGEN_CAUSES))?;
    let mut ledger = RegenLedger::new(np);
    for p in 0..np {
        ledger.germinated[p] = d.u64()?;
        ledger.recruited[p] = d.u64()?;
        for q in 0..N_REGEN_CAUSES {
            ledger.dead[p][q] = d.u64()?;
        }
    }
    let mut regen_year = RegenYear { germinated: d.u64()?, recruited: d.u64()?, ..Default::default() };
    for q in 0..N_REGEN_CAUSES {
        regen_year.dead[q] = d.u64()?;
    }
    Ok(Part { year, next_id, trees, cohorts, seeds, dead, deaths_total, ledger, regen_year })
}

/// Runs `years` years of `world` as `nx × ny` tiles, one thread per tile, over a
/// [`LocalTransport`], and returns the stand-table rows and the world of one process at the
/// end (gathered on rank 0), with the bytes each rank sent for halo copies. For tests and
/// benches of the tiling itself; the run driver with outputs is `job::tiled`.
///
/// Errors: as [`Tile::step`] and [`Tile::gather`].
pub fn run_local(world: &World, layout: &Layout, years: u32) -> Result<(World, Vec<super::stats::StandRow>, Vec<u64>)> {
    let n = layout.len();
    let base = world.tallies.clone();
    let results: Vec<Result<(Option<(World, Vec<super::stats::StandRow>)>, u64)>> = std::thread::scope(|s| {
        let handles: Vec<_> = LocalTransport::group(n)
            .into_iter()
            .map(|mut tr| {
                let layout = layout.clone();
                let base = base.clone();
                s.spawn(move || -> Result<(Option<(World, Vec<super::stats::StandRow>)>, u64)> {
                    let me = tr.rank();
                    let mut tile = Tile::new(world, layout, me)?;
                    let mut rows = Vec::new();
                    for _ in 0..years {
                        let r = tile.step(&mut tr)?;
                        rows.extend(r.row);
                    }
                    if me == 0 {
                        let mut g = world.clone();
                        tile.gather(Some((&mut g, &base)), &mut tr)?;
                        Ok((Some((g, rows)), tile.halo_bytes))
                    } else {
                        tile.gather(None, &mut tr)?;
                        Ok((None, tile.halo_bytes))
                    }
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|_| Err(Error::Exchange { peer: 0, reason: "a tile's thread panicked".into() }))).collect()
    });
    let mut out = None;
    let mut bytes = Vec::with_capacity(n);
    for r in results {
        let (g, b) = r?;
        bytes.push(b);
        if g.is_some() {
            out = g;
        }
    }
    let (g, rows) = out.ok_or_else(|| Error::Exchange { peer: 0, reason: "rank 0 returned no world".into() })?;
    Ok((g, rows, bytes))
}

#[cfg(test)]
mod tests {
    /// A rank that stops (its endpoint dropped) releases the others with an error instead of
    /// a hang; ranks that all finish release each other as before.
    #[test]
    fn a_rank_that_stops_releases_the_others() {
        use super::{LocalTransport, Transport};
        let mut g = LocalTransport::group(3);
        let gone = g.pop();
        let handles: Vec<_> = g
            .into_iter()
            .map(|mut t| {
                std::thread::spawn(move || {
                    let first = t.exchange(vec![vec![1]; 3]);
                    (first.is_ok(), t.exchange(vec![vec![2]; 3]).is_err())
                })
            })
            .collect();
        // rank 2 takes part in the first exchange only
        let mut last = gone.unwrap();
        assert!(last.exchange(vec![vec![3]; 3]).is_ok());
        drop(last);
        for h in handles {
            assert_eq!(h.join().unwrap(), (true, true));
        }
    }

    use super::*;

    #[test]
    fn layout_owners_and_halos() {
        let light = LightGrid::new((100.0, 60.0), 10.0);
        let l = Layout::unchecked(light, 3, 2, 15.0).unwrap();
        assert_eq!(l.col_bounds, vec![0, 3, 6, 10]);
        assert_eq!(l.row_bounds, vec![0, 3, 6]);
        assert_eq!(l.rect(4), CellRect { col0: 3, col1: 6, row0: 3, row1: 6 });
        assert_eq!(l.owner_of(35.0, 31.0), 4);
        assert_eq!(l.owner_of(29.9, 29.9), 0);
        assert_eq!(l.owner_of(500.0, 500.0), 5, "clamped to the grid");
        assert!(l.in_halo(0, 44.0, 10.0, 15.0) && !l.in_halo(0, 45.0, 10.0, 15.0));
        assert!(Layout::unchecked(light, 11, 1, 1.0).is_err());
        // every cell has exactly one owner
        for row in 0..6 {
            for col in 0..10 {
                let k = l.owner_of_cell(col, row);
                assert!(l.rect(k).contains(col, row));
            }
        }
    }

    #[test]
    fn local_transport_passes_messages() {
        let got: Vec<Vec<Vec<u8>>> = std::thread::scope(|s| {
            let h: Vec<_> = LocalTransport::group(3)
                .into_iter()
                .map(|mut t| s.spawn(move || {
                    let me = t.rank() as u8;
                    let a = t.exchange((0..3).map(|p| vec![me, p as u8]).collect()).unwrap();
                    let b = t.exchange((0..3).map(|_| Vec::new()).collect()).unwrap();
                    assert!(b.iter().all(|m| m.is_empty()));
                    a
                }))
                .collect();
            h.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (me, g) in got.iter().enumerate() {
            assert_eq!(*g, (0..3).map(|p| vec![p as u8, me as u8]).collect::<Vec<_>>());
        }
    }
}
