//! Tiled runs with outputs (`mpirun -np N sylva simulate …`, `sylva simulate --tiles N`): the
//! landscape cut into one tile per rank ([`crate::sim::tiles`]); every rank steps its tile;
//! rank 0 also runs the run driver ([`run_scenario_with`]), whose world is cut to rank 0's
//! tile as the tiles take the stand ([`Root`]'s [`Stepper::begin_shed`], before rank 0's tile
//! is copied from it; unless a caller reads the world at every snapshot), so no rank keeps the
//! whole site's grids for the run (issue 37 Build 1; rank 0 still builds the scenario's whole
//! world at the start, the other ranks only their tile's part of the site from their band of
//! the conditions and the cells the band owners send them, [`work`], [`tile_site_by`]; the
//! layout is cut from the ranks' summed weights, [`layout_by`]). The run
//! directory holds what a single process writes, byte for byte where the layout is the same;
//! the checkpoint (one file per rank, below) and the inventories (one part per rank) are laid
//! out by rank and read back as one process's (issue 37 Build 4):
//! - `stand_table.csv`, `stand_table.png`, `scenario.toml`, `species/`, year 0's snapshot
//!   (single files, as one process): rank 0 (the stand table's row from the ranks' exact sums,
//!   added up every year: [`crate::sim::tiles::Tile::step`]);
//! - the inventories of the later snapshots, partitioned: every rank writes its own trees
//!   (living in id order, then this year's dead in id order) as a complete file,
//!   `inventory/year_NNNN/part-RRRRR.parquet` (or `.csv` with `--inventory csv`; each Parquet
//!   part with its GeoParquet metadata, so the folder is one dataset for pyarrow, DuckDB and
//!   GDAL), its cohorts as `inventory/year_NNNN_regeneration/part-RRRRR.parquet` and, in the
//!   GeoPackage years, `inventory/year_NNNN_gpkg/part-RRRRR.gpkg` ([`write_parts`]); nothing
//!   is merged or gathered on rank 0 (until Build 4 rank 0 merged the ranks' CSV lines into one
//!   file). [`crate::job::inventory::read`] reads a folder as one table, in one process's row
//!   order;
//! - `maps/species_*.png`, `maps/basal_area_*.png`: drawn by rank 0 from the basal area per
//!   map pixel and species: each rank sums its own trees per bin; a bin with trees on one rank
//!   takes that rank's sum, and only the trees of bins with trees on several ranks are sent to
//!   rank 0 and summed in id order ([`crate::sim::tiles::Tile::gather_bin_sums`]), so every
//!   bin is the f64 sum of one process;
//! - the whole world is gathered to rank 0 only when a caller reads the world at every
//!   snapshot (`RunOptions::on_snapshot`; then also at a stop, Ctrl-C); without one, the
//!   stop's snapshot is written by the ranks too, and the run driver's world holds rank 0's
//!   tile of the site only.
//!
//! Checkpoints and `--resume` per rank ([`super::checkpoint`]): in a checkpoint year every
//! rank writes its own tile's checkpoint, `checkpoint/year_YYYY_rank_RRRR.bin` (rank 0's with
//! the stand table), nothing gathered; once all have, rank 0 writes `checkpoint/manifest.toml`
//! (year, layout, files), which commits them, and removes the files it supersedes. A resume
//! (issue 37 Build 1, round 37) starts as a fresh run does, every rank holding its band and
//! building its tile's world only (no start's trees), then every rank reads its part of the
//! checkpoint from the files of the old tiles that overlap its own
//! ([`super::checkpoint::load_overlapping`]: its own file on the same layout; on another number
//! of ranks the 1–4 files its tile overlaps; a `checkpoint.bin` of one process as the one
//! file of a 1 × 1 layout), so a run stopped on 3 ranks can go on with 2 or with one process
//! without the world of one process on any rank. Only when a caller reads the world at every
//! snapshot (`RunOptions::on_snapshot`) does rank 0 build the world of one process, assemble
//! the files there ([`super::checkpoint::load_ranks`]) and send every rank its part.
//!
//! Protocol: before every collective step rank 0 sends every rank a command ([`Command`]); the
//! other ranks ([`work`]) wait for it, so all ranks take part in the same exchanges in the same
//! order.

use super::checkpoint::{self, Found, Manifest};
use super::run::{run_scenario_with, Lean, Parts, RunOptions, RunSummary, Stepper};
use super::Result;
use crate::sim::cohorts::RegenLedger;
use crate::sim::stats::StandRow;
use std::path::{Path, PathBuf};
use crate::conditions::SiteConditions;
use crate::output::inventory::InventoryFormat;
use crate::sim::scenario::Scenario;
use crate::sim::step::YearReport;
use crate::sim::tiles::{Layout, LocalTransport, Tile, Transport};
use crate::sim::world::{Tallies, World};
use crate::species::{Season, SpeciesLibrary};
use crate::Error;

/// What rank 0 tells the other ranks to do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Command {
    /// Take your part of rank 0's world ([`Tile::scatter`]).
    Begin = 1,
    /// Step a year (the stand table's sums added up over the ranks).
    Step = 2,
    /// Step a year, then send rank 0 the whole stand ([`Tile::gather`]).
    StepFull = 3,
    /// Send rank 0 the whole stand.
    Complete = 4,
    /// The run is over.
    End = 5,
    /// Write your tile's checkpoint to the path that follows ([`send_paths`], [`agree`]).
    Save = 6,
    /// Read your tile from the per-rank checkpoint at the path that follows.
    Resume = 7,
    /// Write your tile's part of the snapshot that follows ([`write_parts`]).
    Snapshot = 8,
    /// Count your band's part of the layout's weights; the parts are all-summed and every
    /// rank cuts the same layout ([`layout_by`]).
    Layout = 9,
    /// Derive your tile's site and place your start's trees (ids from the ranks' counts); send
    /// rank 0 what year 0's snapshot needs of your tile ([`start_tile`]; a fresh run whose rank
    /// 0 holds its tile only, issue 37 Build 1, round 33: instead of [`Command::Begin`]).
    Start = 10,
    /// Read your tile's part of the checkpoint whose manifest follows from the old ranks'
    /// files that overlap it ([`resume_tile`]; a resumed run whose rank 0 holds its tile only,
    /// issue 37 Build 1, round 37: instead of [`Command::Resume`] and [`Command::Begin`]).
    ResumeRanks = 11,
    /// Add up the stand table's row of the tiles as they stand, year 0's
    /// ([`Tile::start_row`]; round 42, trial 41 defect 7).
    Row = 12,
}

impl Command {
    fn from_byte(b: u8) -> Option<Command> {
        [Command::Begin, Command::Step, Command::StepFull, Command::Complete, Command::End, Command::Save, Command::Resume, Command::Snapshot, Command::Layout, Command::Start, Command::ResumeRanks, Command::Row].into_iter().find(|c| *c as u8 == b)
    }
}

/// Rank 0 sends `c` to every rank; the others pass `None` and get it.
///
/// Errors: [`Error::Exchange`] from the transport or an unknown command byte.
fn command(t: &mut dyn Transport, c: Option<Command>) -> Result<Command> {
    let n = t.size();
    let out = match c {
        Some(c) => vec![vec![c as u8]; n],
        None => vec![Vec::new(); n],
    };
    let got = t.exchange(out)?;
    let b = got.first().and_then(|m| m.first()).copied().unwrap_or(0);
    Ok(Command::from_byte(b).ok_or(Error::Exchange { peer: 0, reason: format!("unknown command byte {b} (expected 1–12)") })?)
}

/// Rank 0 sends every rank `k` the year and `paths[k]` (a per-rank checkpoint file); the others
/// pass `None`. Returns this rank's year and path.
///
/// Errors: [`Error::Exchange`] from the transport, a path that is not UTF-8 (named) or a
/// malformed message.
fn send_paths(t: &mut dyn Transport, paths: Option<(u32, Vec<PathBuf>)>) -> Result<(u32, PathBuf)> {
    let n = t.size();
    let mut out = vec![Vec::new(); n];
    if let Some((year, paths)) = paths {
        if paths.len() != n {
            return Err(Error::Exchange { peer: 0, reason: format!("{} checkpoint paths for {n} ranks", paths.len()) }.into());
        }
        for (m, p) in out.iter_mut().zip(&paths) {
            let s = p.to_str().ok_or_else(|| Error::Invalid { context: "tiled run".into(), field: "checkpoint path".into(), value: p.display().to_string(), expected: "a UTF-8 path (it is sent to the other ranks)".into() })?;
            m.extend_from_slice(&year.to_le_bytes());
            m.extend_from_slice(s.as_bytes());
        }
    }
    let got = t.exchange(out)?;
    let m = got.first().map(|m| m.as_slice()).unwrap_or(&[]);
    if m.len() < 4 {
        return Err(Error::Exchange { peer: 0, reason: format!("checkpoint path message of {} bytes (expected a year and a path)", m.len()) }.into());
    }
    let year = u32::from_le_bytes([m[0], m[1], m[2], m[3]]);
    let path = std::str::from_utf8(&m[4..]).map_err(|e| Error::Exchange { peer: 0, reason: format!("checkpoint path not UTF-8: {e}") })?;
    Ok((year, PathBuf::from(path)))
}

/// Every rank tells every other whether its part of a collective step (writing or reading its
/// checkpoint) failed (`failed`: the error's text); all ranks then fail together.
///
/// Errors: [`Error::Exchange`] from the transport, or naming the first rank that failed with
/// its error.
fn agree(t: &mut dyn Transport, failed: Option<String>) -> Result<()> {
    let n = t.size();
    let msg = failed.map(|e| e.into_bytes()).unwrap_or_default();
    let got = t.exchange(vec![msg; n])?;
    match got.iter().enumerate().find(|(_, m)| !m.is_empty()) {
        Some((k, m)) => Err(Error::Exchange { peer: k, reason: format!("rank {k} failed: {}", String::from_utf8_lossy(m)) }.into()),
        None => Ok(()),
    }
}

/// Reads tile `me` of `layout` from the per-rank checkpoint `path` of `year` into `template`
/// (the world of the scenario at its start, or a copy; its seed grids cut to the tile's window
/// first, as the rank saved them); returns it with the rows the file holds (rank 0's: the
/// stand table).
///
/// Errors: as [`checkpoint::load`] and [`Tile::resumed`]; [`Error::Format`] naming the file
/// when its year is not `year` (the manifest's).
fn load_tile(template: World, layout: &Layout, me: usize, path: &Path, year: u32) -> Result<(Tile, Vec<StandRow>)> {
    let mut w = template;
    crate::sim::tiles::hold_own_seeds(&mut w, layout, me)?;
    let rows = checkpoint::load(path, &mut w)?;
    if w.stand.year != year {
        return Err(Error::format(path, format!("year {} in a checkpoint whose manifest says year {year}", w.stand.year)).into());
    }
    Ok((Tile::resumed(w, layout.clone(), me)?, rows))
}

/// The checkpoint a resumed run reads per rank ([`resume_tile`]): the tiles of the run that
/// wrote it (one process's `checkpoint.bin` as the one tile of 1 × 1) and a file per tile.
#[derive(Debug, Clone, PartialEq)]
struct Source {
    /// The manifest's year (`None` for `checkpoint.bin`: its own).
    year: Option<u32>,
    /// Tiles across and up.
    tiles: (usize, usize),
    /// Column and row boundaries of the tiles (light cells), as the manifest gives them.
    col_bounds: Vec<usize>,
    row_bounds: Vec<usize>,
    /// The file of each tile, in tile order.
    paths: Vec<PathBuf>,
    /// The file that names them (the manifest, or `checkpoint.bin`), for errors.
    named: PathBuf,
}

impl Source {
    fn encode(&self) -> Result<Vec<u8>> {
        let utf8 = |p: &Path| -> Result<String> {
            Ok(p.to_str().ok_or_else(|| Error::Invalid { context: "tiled run".into(), field: "checkpoint path".into(), value: p.display().to_string(), expected: "a UTF-8 path (it is sent to the other ranks)".into() })?.to_string())
        };
        let mut e = crate::sim::codec::Enc(Vec::new());
        e.u64(self.year.map_or(u64::MAX, |y| y as u64));
        e.u64(self.tiles.0 as u64);
        e.u64(self.tiles.1 as u64);
        for b in [&self.col_bounds, &self.row_bounds] {
            e.u64(b.len() as u64);
            b.iter().for_each(|&v| e.u64(v as u64));
        }
        e.str(&utf8(&self.named)?);
        e.u64(self.paths.len() as u64);
        for p in &self.paths {
            e.str(&utf8(p)?);
        }
        Ok(e.0)
    }
    fn decode(m: &[u8]) -> Result<Source> {
        let fail = |s: crate::sim::codec::Short| Error::Exchange { peer: 0, reason: format!("checkpoint message cut short at byte {}", s.at()) };
        let mut d = crate::sim::codec::Dec::at(m, 0, &fail);
        let year = d.u64()?;
        let year = (year != u64::MAX).then_some(year as u32);
        let tiles = (d.u64()? as usize, d.u64()? as usize);
        let mut bounds = [Vec::new(), Vec::new()];
        for b in bounds.iter_mut() {
            let n = d.count(8)?;
            for _ in 0..n {
                b.push(d.u64()? as usize);
            }
        }
        let named = PathBuf::from(d.str()?);
        let n = d.count(8)?;
        let mut paths = Vec::with_capacity(n);
        for _ in 0..n {
            paths.push(PathBuf::from(d.str()?));
        }
        let [col_bounds, row_bounds] = bounds;
        Ok(Source { year, tiles, col_bounds, row_bounds, paths, named })
    }
}

/// A resumed run's tile read per rank (issue 37 Build 1, round 37; [`Command::ResumeRanks`]):
/// rank 0 sends every rank the checkpoint `src` (the others pass `None`); every rank, its tile
/// made by a lean start (its tile's site, no trees), cuts the checkpoint's tiles
/// (`Layout::with_bounds` of its bounds) and reads its part from the files that overlap its
/// tile ([`checkpoint::load_overlapping`]: at most the old tiles it overlaps, plus any whose
/// seed cells its windows need that those do not hold; no whole-site array, no other rank's
/// file in memory at once); all agree, then the next tree id of old rank 0's file (rank 0
/// reads it) is all-summed to every rank. Each rank prints on stderr the files it read and the
/// site cells it holds (`rank R/N: resumed year Y from K of M checkpoint files (…); holds site
/// cells …`). Returns the stand table so far (rank 0's; empty on the others).
///
/// Errors: [`Error::Exchange`] from the transport, a malformed message, or naming the first
/// rank that failed with its error: [`Error::Format`] naming the manifest when its bounds are
/// not tiles of this site's light grid; as [`checkpoint::load_overlapping`].
fn resume_tile(tile: &mut Tile, t: &mut dyn Transport, src: Option<&Source>) -> Result<Vec<StandRow>> {
    let (me, n) = (t.rank(), t.size());
    let out = match src {
        Some(s) => vec![s.encode()?; n],
        None => vec![Vec::new(); n],
    };
    let got = t.exchange(out)?;
    let src = Source::decode(got.first().map(|m| m.as_slice()).unwrap_or(&[]))?;
    let r = (|| -> Result<checkpoint::Overlap> {
        let bad = |e: String| Error::format(&src.named, format!("col_bounds, row_bounds: {e}"));
        let old = Layout::with_bounds(&tile.world.site, src.col_bounds.clone(), src.row_bounds.clone()).map_err(|e| bad(e.to_string()))?;
        if (old.nx, old.ny) != src.tiles {
            return Err(bad(format!("{:?} and {:?} are not the {} × {} tiles they bound", src.col_bounds, src.row_bounds, src.tiles.0, src.tiles.1)).into());
        }
        checkpoint::load_overlapping(&src.paths, src.year, &old, &tile.layout, me, &mut tile.world)
    })();
    let a = agree(t, r.as_ref().err().map(|e| e.to_string()));
    let ov = r?;
    a?;
    let ids = t.all_sum(vec![if me == 0 { ov.next_id.unwrap_or(0) } else { 0 }])?;
    tile.world.stand.trees.next_id = ids.first().copied().ok_or_else(|| Error::Exchange { peer: 0, reason: "no summed next tree id".into() })?;
    let names: Vec<String> = ov.read.iter().map(|&k| src.paths[k].file_name().map_or_else(|| src.paths[k].display().to_string(), |f| f.to_string_lossy().into_owned())).collect();
    let c = &tile.world.site.conditions;
    let line = format!("rank {me}/{n}: resumed year {} from {} of {} checkpoint files ({}); holds site cells {} of {} × {}\n", tile.world.stand.year, ov.read.len(), src.paths.len(), names.join(", "), c.held, c.full.0, c.full.1);
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    Ok(ov.rows)
}

/// A snapshot written by the ranks ([`write_parts`]).
#[derive(Debug, Clone, PartialEq)]
struct Snap {
    /// Run directory.
    dir: PathBuf,
    /// Snapshot label (`year_NNNN`).
    label: String,
    /// The tree inventory (and with `maps` the regeneration layer).
    inventory: bool,
    /// The GeoPackage parts of the inventory too (only with `inventory`).
    gpkg: bool,
    /// Maps too (a plain snapshot).
    maps: bool,
    /// Longest side of the maps (pixels).
    map_px: usize,
    /// File format of the inventory and regeneration parts.
    format: InventoryFormat,
}

impl Snap {
    fn encode(&self) -> Result<Vec<u8>> {
        let dir = self.dir.to_str().ok_or_else(|| Error::Invalid { context: "tiled run".into(), field: "run directory".into(), value: self.dir.display().to_string(), expected: "a UTF-8 path (it is sent to the other ranks)".into() })?;
        let csv = self.format == InventoryFormat::Csv;
        let mut m = vec![self.maps as u8 | (self.inventory as u8) << 1 | (self.gpkg as u8) << 2 | (csv as u8) << 3];
        m.extend_from_slice(&(self.map_px as u64).to_le_bytes());
        m.extend_from_slice(&(self.label.len() as u64).to_le_bytes());
        m.extend_from_slice(self.label.as_bytes());
        m.extend_from_slice(dir.as_bytes());
        Ok(m)
    }
    fn decode(m: &[u8]) -> Result<Snap> {
        let bad = |what: &str| Error::Exchange { peer: 0, reason: format!("snapshot message of {} bytes: {what}", m.len()) };
        if m.len() < 17 {
            return Err(bad("shorter than its header").into());
        }
        let map_px = u64::from_le_bytes(m[1..9].try_into().map_err(|_| bad("no map size"))?) as usize;
        let n = u64::from_le_bytes(m[9..17].try_into().map_err(|_| bad("no label length"))?) as usize;
        let label = m.get(17..17 + n).ok_or_else(|| bad("label cut short"))?;
        let label = std::str::from_utf8(label).map_err(|_| bad("label not UTF-8"))?.to_string();
        let dir = std::str::from_utf8(&m[17 + n..]).map_err(|_| bad("folder not UTF-8"))?;
        let format = if m[0] & 8 != 0 { InventoryFormat::Csv } else { InventoryFormat::Parquet };
        Ok(Snap { dir: PathBuf::from(dir), label, inventory: m[0] & 2 != 0, gpkg: m[0] & 4 != 0, maps: m[0] & 1 != 0, map_px, format })
    }
    /// Rank `rank`'s part of the partitioned output `folder` (e.g. `year_0150`) of the
    /// snapshot: `inventory/{folder}/part-RRRRR.{ext}`; the folder is made if missing.
    ///
    /// Errors: [`Error::Io`] naming the folder that cannot be made.
    fn part(&self, folder: &str, rank: usize, ext: &str) -> Result<PathBuf> {
        let d = self.dir.join("inventory").join(folder);
        std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        Ok(d.join(crate::output::inventory::part_name(rank, ext)))
    }
}

/// The ranks' part of a snapshot: rank 0 sends every rank `snap` (others pass `None`); every
/// rank writes its own trees' inventory as its part of the partitioned snapshot,
/// `inventory/year_NNNN/part-RRRRR.parquet` (or `.csv`), with `gpkg` also
/// `inventory/year_NNNN_gpkg/part-RRRRR.gpkg`, and with `maps` its cohorts as
/// `inventory/year_NNNN_regeneration/part-RRRRR.parquet` ([`crate::output::inventory::write_inventory_part`]);
/// nothing is merged. All agree; then, with `maps`, the basal area per map bin
/// ([`crate::output::plot::map_bin`], summed exactly as one process: [`Tile::gather_bin_sums`])
/// goes to rank 0, which gets the sums back.
///
/// Errors: [`Error::Exchange`] from the transport or naming a rank that failed to write its
/// parts (with its I/O error naming the file).
fn write_parts(tile: &Tile, t: &mut dyn Transport, snap: Option<&Snap>) -> Result<Option<Vec<f64>>> {
    let n = t.size();
    let mut out = vec![Vec::new(); n];
    if let Some(s) = snap {
        out = vec![s.encode()?; n];
    }
    let got = t.exchange(out)?;
    let s = Snap::decode(got.first().map(|m| m.as_slice()).unwrap_or(&[]))?;
    let me = t.rank();
    let ext = s.format.extension();
    let r = (|| -> Result<()> {
        let layout = &tile.layout;
        if s.inventory {
            let p = s.part(&s.label, me, ext)?;
            let g = if s.gpkg { Some(s.part(&format!("{}_gpkg", s.label), me, "gpkg")?) } else { None };
            crate::output::inventory::write_inventory_part(&p, g.as_deref(), &tile.world, |x, y| layout.owner_of(x, y) == me, s.format)?;
            if s.maps {
                let p = s.part(&format!("{}_regeneration", s.label), me, ext)?;
                crate::output::inventory::write_regeneration_part(&p, &tile.world, s.format)?;
            }
        }
        Ok(())
    })();
    let a = agree(t, r.as_ref().err().map(|e| e.to_string()));
    r?;
    a?;
    if !s.maps {
        return Ok(None);
    }
    let dims = crate::output::plot::map_dims(&tile.world, s.map_px);
    let np = tile.world.site.lib.species.len();
    Ok(tile.gather_bin_sums(t, dims.0 * dims.1 * np, |tr, i| crate::output::plot::map_bin(tr, i, dims, np), |tr, i| tr.basal_area_m2(i))?)
}

/// The start of a fresh tiled run on every rank (issue 37 Build 1, round 33; [`Command::Start`]):
/// rank 0 sends every rank the maps' longest side, whether year 0's snapshot is written and
/// whether the run resumes from a checkpoint (`start`: `Some((map_px, year0, resume))` on rank
/// 0, `None` on the others); every rank derives its
/// tile's site into `w` (its skeleton holding the tile's cells,
/// [`crate::sim::tiles::derive_tile_site_by`], the management's areas and plantings counted
/// with the other ranks: one all-sum of a word per entry, a second for an area narrower than a
/// light cell, one per planting; a failure is every rank's), places its start's trees and
/// year 0's plantings with one process's ids ([`World::place_start_tile`]: one all-sum of a word
/// per run of the start's places; not when the run resumes: its stand comes from the
/// checkpoint, [`resume_tile`]) and makes its tile; then sends rank 0 the flags of the map
/// pixels whose centre it owns (masked or not, 1 byte each; [`crate::output::plot::map_masked_centres`]
/// of the whole site, assembled) and, with `year0`, its start's trees (54 bytes each). Rank 0
/// gets `Some((trees, flags))`: every rank's start's trees merged by id (one process's store
/// at year 0) and the whole map's flags; the others `None`. Nothing else of the stand is sent
/// (the seed grids are zero and there are no cohorts at year 0; [`Tile::scatter`] sent them
/// before).
///
/// Errors: [`Error::Exchange`] from the transport or a malformed message; as
/// [`crate::sim::tiles::derive_tile_site_with`] (on every rank), [`World::place_start_tile`]
/// and [`Tile::own`].
#[allow(clippy::too_many_arguments)]
fn start_tile(mut w: World, scenario: &Scenario, layout: &Layout, median: f32, whole: Option<&crate::sim::tiles::WholeSite>, start: Option<(usize, bool, bool)>, t: &mut dyn Transport) -> Result<(Tile, Option<(crate::sim::TreeStore, Vec<bool>)>)> {
    use crate::sim::codec::{Dec, Enc, Short};
    let (me, n) = (t.rank(), t.size());
    let mut out = vec![Vec::new(); n];
    if let Some((px, year0, resume)) = start {
        let mut e = Enc(Vec::new());
        e.u64(px as u64);
        e.u64(year0 as u64);
        e.u64(resume as u64);
        out = vec![e.0; n];
    }
    let got = t.exchange(out)?;
    let fail = |s: Short| Error::Exchange { peer: 0, reason: format!("start message cut short at byte {}", s.at()) };
    let mut d = Dec::at(got.first().map(|m| m.as_slice()).unwrap_or(&[]), 0, &fail);
    let (px, year0, resume) = (d.u64()? as usize, d.u64()? != 0, d.u64()? != 0);
    // a scenario with management resolves its areas from the ranks' tiles (issue 37 round 36)
    let r = crate::sim::tiles::derive_tile_site_by(&mut w, scenario, layout, me, median, whole, Some(&mut |v| t.all_sum(v)));
    let a = agree(t, r.as_ref().err().map(|e| e.to_string()));
    r?;
    a?;
    if !resume {
        w.place_start_tile(scenario, &|x, y| layout.owner_of(x, y), me, &mut |v| t.all_sum(v))?;
    }
    let tile = Tile::own(w, layout.clone(), me)?;
    let tw = &tile.world;
    let dims = crate::output::plot::map_dims(tw, px);
    let owner = |i: usize| {
        let (x, y) = crate::output::plot::map_centre(dims, i);
        (layout.owner_of(x as f32, y as f32), x, y)
    };
    let flags: Vec<u8> = (0..dims.0 * dims.1).filter_map(|i| {
        let (k, x, y) = owner(i);
        (k == me).then(|| tw.site_cell(x, y).is_none() as u8)
    }).collect();
    let mut e = Enc(Vec::new());
    e.u64(flags.len() as u64);
    e.bytes(&flags);
    drop(flags);
    if year0 {
        let all: Vec<usize> = (0..tw.stand.trees.len()).collect();
        crate::sim::tiles::put_trees(&mut e, &tw.stand.trees, &all);
    }
    let mut out = vec![Vec::new(); n];
    out[0] = e.0;
    let got = t.exchange(out)?;
    if me != 0 {
        return Ok((tile, None));
    }
    let mut parts = Vec::with_capacity(n);
    let mut flag_parts: Vec<Vec<u8>> = Vec::with_capacity(n);
    for (k, m) in got.iter().enumerate() {
        let fail = crate::sim::tiles::short_message(k);
        let mut d = Dec::at(m, 0, &fail);
        let nf = d.count(1)?;
        flag_parts.push(d.take(nf)?.to_vec());
        parts.push(if year0 { crate::sim::tiles::get_trees(&mut d)? } else { crate::sim::TreeStore::default() });
    }
    let mut next = vec![0usize; n];
    let mut masked = Vec::with_capacity(dims.0 * dims.1);
    for i in 0..dims.0 * dims.1 {
        let (k, ..) = owner(i);
        let f = flag_parts[k].get(next[k]).ok_or_else(|| Error::Exchange { peer: k, reason: format!("{} map pixel flags from rank {k}, more expected", flag_parts[k].len()) })?;
        next[k] += 1;
        masked.push(*f != 0);
    }
    let trees = crate::sim::TreeStore::merge_by_id(&parts, tile.world.stand.trees.next_id).0;
    Ok((tile, Some((trees, masked))))
}

/// The run driver's world on rank 0 of a lean start ([`Stepper::world`]) from its tile's world
/// `w`: a copy of everything but the site's cells (the conditions an empty window at the
/// tile's corner, no relative insolation, suitability, light cells' arrays or ground light) and
/// the trees: what the driver reads of its world (the year, pool, library, extent, light grid,
/// georeferencing, the whole site's identity) without a second copy of the tile's site (the
/// copy `begin_shed` kept until round 33: about 70 bytes a site cell of the tile, rank 0's
/// surplus over the other ranks). `w` is given back whole.
fn driver_of(w: &mut World) -> World {
    let c = &w.site.conditions;
    let held = crate::grid::Window { col0: c.held.col0, row0: c.held.row0, width: 0, height: 0 };
    let none = super::site_ranks::conditions_of(c.geo.clone(), c.cell_x_m, c.cell_y_m, held, c.full, Vec::new());
    let conditions = std::mem::replace(&mut w.site.conditions, none);
    let site = &mut w.site;
    let kept = (std::mem::take(&mut site.rel_insolation), std::mem::take(&mut site.suitability), std::mem::take(&mut site.light_site), std::mem::take(&mut site.ground_free), std::mem::take(&mut w.scratch.ground_light), std::mem::take(&mut w.stand.trees));
    let mut d = w.clone();
    d.stand.trees.next_id = kept.5.next_id;
    w.site.conditions = conditions;
    (w.site.rel_insolation, w.site.suitability, w.site.light_site, w.site.ground_free, w.scratch.ground_light, w.stand.trees) = kept;
    d
}

/// Tallies of zero for `world`'s pool.
fn zero_tallies(world: &World) -> Tallies {
    Tallies { deaths_total: Default::default(), regen_ledger: RegenLedger::new(world.site.pool.len()) }
}

/// Tiles across and up for `n` ranks on a light grid of `cols × rows` cells: the factor pair
/// `nx · ny = n` whose tiles are closest to square (`|ln(cols / nx) − ln(rows / ny)|` least),
/// more tiles across on a tie.
pub fn grid_for(n: usize, cols: usize, rows: usize) -> (usize, usize) {
    let n = n.max(1);
    (1..=n)
        .filter(|nx| n % nx == 0)
        .map(|nx| (nx, n / nx))
        .min_by(|a, b| {
            let f = |(nx, ny): (usize, usize)| ((cols as f64 / nx as f64).ln() - (rows as f64 / ny as f64).ln()).abs();
            f(*a).total_cmp(&f(*b)).then(b.0.cmp(&a.0))
        })
        .unwrap_or((n, 1))
}

/// Refuses what a tiled run does not do: seasonal snapshots (they would need every rank's
/// stand in the middle of a year).
///
/// Errors: [`Error::Invalid`] naming the scenario and the field.
fn check(scenario: &Scenario) -> Result<()> {
    if scenario.seasonal_snapshots {
        return Err(Error::Invalid { context: scenario.name.clone(), field: "seasonal_snapshots".into(), value: "true".into(), expected: "false in a tiled run (MPI ranks or --tiles): run seasonal snapshots in one process".into() }.into());
    }
    Ok(())
}

/// The layout of a run of `n` ranks on `world`'s site: a near-square grid of tiles
/// ([`grid_for`]) whose columns and rows are cut by the work of the scenario's start (issue 37
/// Build 5: [`crate::sim::tiles::work_weights`], the light cells where forest can grow;
/// [`crate::sim::tiles::cut_by_weight`]), so an uneven site (half of it masked or above the
/// tree line) gives each rank about as much forest; an even site is cut by area as before
/// ([`Layout::new`]). Only the site counts, not `world`'s trees: a resumed world and the
/// scenario's start cut the same tiles. A tiled run's ranks cut it from their parts of the
/// weights ([`layout_by`]); this one counts the whole site (`--tiles`' check before the threads
/// start, tests).
///
/// Errors: [`Error::Invalid`] when the light grid has fewer columns or rows than the tiles.
pub fn layout_for(world: &World, n: usize) -> Result<Layout> {
    let (wc, wr) = crate::sim::tiles::work_weights(&world.site);
    layout_weighted(world, n, &wc, &wr)
}

/// [`layout_for`] with the weights counted by the ranks of `t` (issue 37 Build 1), and the
/// median of the site's unmasked insolation that its relative insolation divides by: rank `k`
/// of `N` counts the light rows of its band ([`crate::sim::tiles::weight_band`],
/// [`crate::sim::tiles::work_weights_of`], from the site conditions and the pool: `world` may
/// be a [`World::skeleton`]) and the parts are all-summed ([`Transport::all_sum`],
/// `light.cols + light.rows` words), so no rank reads the whole site's weights; the counts are
/// integers, so every rank gets [`layout_for`]'s layout of `world` exactly. Then every rank
/// takes the site rows `k · h / N .. (k + 1) · h / N` of the conditions and the ranks select
/// the median over them ([`crate::sim::world::insolation_median_by`]: a count and three
/// all-sums of 1–2 K counts), which is [`World::new`]'s median bit for bit. Every rank of `t`
/// must call it at the same point (rank 0 after [`Command::Layout`]); `world`'s conditions
/// must hold the rank's band of site rows (rank 0 the whole site; since round 32 the others
/// may hold their band only: the weights are counted over the light cells whose centre lies in
/// the rank's band of site rows, [`crate::sim::tiles::work_weights_of_site_rows`]).
///
/// Then the ranks move each tile whose rank holds its band only its cells ([`tile_site_by`]).
///
/// Errors: [`Error::Exchange`] from the transport or parts of another length (a rank with
/// another light grid); as [`layout_for`] and [`tile_site_by`].
pub fn layout_by(world: &World, t: &mut dyn Transport) -> Result<(Layout, f32)> {
    let site = &world.site;
    let light = &site.light;
    let (mut v, wr) = crate::sim::tiles::work_weights_of_site_rows(&site.conditions, &site.lib, &site.pool, light, crate::sim::tiles::weight_band(t.rank(), t.size(), site.conditions.height()));
    v.extend(wr);
    let sums = t.all_sum(v)?;
    if sums.len() != light.cols + light.rows {
        return Err(Error::Exchange { peer: 0, reason: format!("{} summed weights, expected {} (light columns and rows)", sums.len(), light.cols + light.rows) }.into());
    }
    let (wc, wr) = sums.split_at(light.cols);
    let layout = layout_weighted(world, t.size(), wc, wr)?;
    let c = &site.conditions;
    let band = crate::sim::tiles::weight_band(t.rank(), t.size(), c.height());
    let win = crate::grid::Window { col0: 0, row0: band.start, width: c.width(), height: band.len() };
    let (ins, mask) = (win.cut(&c.insolation_kwh_m2, &c.held), win.cut(&c.mask, &c.held));
    let median = crate::sim::world::insolation_median_by(&ins, &mask, &mut |v| t.all_sum(v))?;
    Ok((layout, median))
}

/// Moves to every rank whose site conditions are not whole (issue 37 Build 1, item (a),
/// round 32: a rank other than 0 that keeps its band of site rows, [`work`]) its tile's
/// window of them (the site cells under its rectangle of `layout` plus
/// [`crate::sim::tiles::SITE_HALO_CELLS`]) from the ranks that own those rows: rank `k` owns
/// the band of site rows [`crate::sim::tiles::weight_band`]`(k, N, height)` and sends each
/// such tile the rows of its band that the window holds, over the window's columns; a tile's
/// rows come in rank order, so they are laid end to end. One grid at a time (mask, elevation,
/// slope, aspect, TWI, insolation, wind exposure, temperature, indices: nine exchanges), and a
/// rank that owns its band (`c` owned) drops each grid of its band once that grid is sent, so
/// it holds about its band plus its window at most, not both twice. Rank 0 (which holds the
/// whole site) sends the whole site's checkpoint identity (`identity`, or
/// [`crate::sim::checkpoint::site_identity`] of its conditions) with its first rows; the count
/// of unmasked cells is the all-sum of the bands' counts. One all-sum of `N + 1` words first
/// says which ranks need a window (none: nothing more is sent). Every value is the one of the
/// whole site's cells, bit for bit. Every rank of `t` calls it after [`layout_by`], with the
/// same layout and light cell size `light_cell_m` (m). Returns this rank's window with the
/// whole site's identity and count when its conditions are not whole, else `None`.
///
/// Errors: [`Error::Invalid`] when a rank does not hold its band; [`Error::Exchange`] from the
/// transport, naming a rank whose message is short or whose rows do not follow.
pub fn tile_site_by(c: std::borrow::Cow<'_, SiteConditions>, identity: Option<&[(String, String)]>, light_cell_m: f64, layout: &Layout, t: &mut dyn Transport) -> Result<Option<(SiteConditions, crate::sim::tiles::WholeSite)>> {
    use crate::grid::Window;
    let mut c = c;
    let (me, n) = (t.rank(), t.size());
    let (w, h) = c.full;
    let band = crate::sim::tiles::weight_band(me, n, h);
    let bw = Window { col0: 0, row0: band.start, width: w, height: band.len() };
    if !c.held.contains(&bw) {
        return Err(Error::Invalid { context: "tiled run".into(), field: "site conditions".into(), value: format!("cells {} of rank {me}", c.held), expected: format!("its band of site rows {bw}") }.into());
    }
    let valid: u64 = band.clone().map(|r| (0..w).filter(|&col| c.held_index(col, r).is_some_and(|i| c.mask.data[i])).count() as u64).sum();
    let mut v = vec![0u64; n + 1];
    v[0] = valid;
    v[1 + me] = !c.holds_all() as u64;
    let sums = t.all_sum(v)?;
    if sums.len() != n + 1 {
        return Err(Error::Exchange { peer: 0, reason: format!("{} summed words, expected {} (unmasked cells and the ranks' needs)", sums.len(), n + 1) }.into());
    }
    if sums[1..].iter().all(|&x| x == 0) {
        return Ok(None);
    }
    let l = light_cell_m;
    let win_of = |c: &SiteConditions, k: usize| {
        let r = layout.rect(k);
        c.window_of(r.col0 as f64 * l, r.row0 as f64 * l, r.col1 as f64 * l, r.row1 as f64 * l, crate::sim::tiles::SITE_HALO_CELLS)
    };
    let wins: Vec<Window> = (0..n).map(|k| win_of(&c, k)).collect();
    let win = wins[me];
    let need = sums[1 + me] != 0;
    // rank 0 holding its band only (a fresh run without management, round 33): the whole
    // site's identity joined from every rank's band (every rank knows from the sums)
    let joined = if sums[1] != 0 { identity_by(&c, band.start - c.held.row0..band.end - c.held.row0, t)? } else { None };
    let mut identity_got = Vec::new();
    // the window's grids, one field at a time ([`super::site_ranks::field_values`])
    let mut fields: Vec<Vec<f32>> = Vec::new();
    for f in 0..super::site_ranks::FIELDS {
        let mut out = vec![Vec::new(); n];
        for (k, o) in out.iter_mut().enumerate() {
            if sums[1 + k] == 0 {
                continue;
            }
            let mut e = crate::sim::codec::Enc(Vec::new());
            if me == 0 && f == 0 {
                let own;
                let id: &[(String, String)] = match identity.or(joined.as_deref()) {
                    Some(i) => i,
                    None => {
                        own = crate::sim::checkpoint::site_identity(&c);
                        &own
                    }
                };
                e.u64(id.len() as u64);
                for (a, b) in id {
                    e.str(a);
                    e.str(b);
                }
            }
            let wk = wins[k];
            let (r0, r1) = (band.start.max(wk.row0), band.end.min(wk.row1()));
            let piece = Window { col0: wk.col0, row0: r0, width: wk.width, height: r1.saturating_sub(r0) };
            e.u64(piece.row0 as u64);
            e.u64(piece.height as u64);
            if piece.height > 0 {
                e.f32s(&super::site_ranks::field_values(&c, f, piece));
            }
            *o = e.0;
        }
        let got = t.exchange(out)?;
        // this field of the band is sent: an owned band gives it up
        if let std::borrow::Cow::Owned(o) = &mut c {
            super::site_ranks::drop_field(o, f);
        }
        if !need {
            continue;
        }
        let per = if f == 8 { 6 } else { 1 };
        let mut data: Vec<f32> = Vec::with_capacity(per * win.width * win.height);
        let mut next_row = win.row0;
        for (k, m) in got.into_iter().enumerate() {
            let fail = |s: crate::sim::codec::Short| Error::Exchange { peer: k, reason: format!("site cells message cut short at byte {}", s.at()) };
            let mut d = crate::sim::codec::Dec::at(&m, 0, &fail);
            if k == 0 && f == 0 {
                let ni = d.count(16)?;
                for _ in 0..ni {
                    identity_got.push((d.str()?, d.str()?));
                }
            }
            let (row0, rows) = (d.u64()? as usize, d.u64()? as usize);
            if rows == 0 {
                continue;
            }
            let bad = |what: String| Error::Exchange { peer: k, reason: format!("site cells of rank {k} for {win}, grid {f}: {what}") };
            if row0 != next_row {
                return Err(bad(format!("rows from {row0}, expected from {next_row}")).into());
            }
            let v = d.f32s()?;
            if v.len() != per * win.width * rows {
                return Err(bad(format!("{} values, expected {}", v.len(), per * win.width * rows)).into());
            }
            data.extend_from_slice(&v);
            next_row += rows;
        }
        if next_row != win.row1() {
            return Err(Error::Exchange { peer: 0, reason: format!("site cells for {win}, grid {f}: rows up to {next_row} arrived, expected up to {}", win.row1()) }.into());
        }
        fields.push(data);
    }
    if !need {
        return Ok(None);
    }
    let part = super::site_ranks::conditions_of(c.geo.clone(), c.cell_x_m, c.cell_y_m, win, c.full, fields);
    Ok(Some((part, crate::sim::tiles::WholeSite { identity: identity_got, valid_cells: sums[0] })))
}

/// The whole site's checkpoint identity ([`crate::sim::checkpoint::site_identity`]) on rank 0
/// from the ranks' bands: every rank sends rank 0 the [`crate::sim::checkpoint::IdentityPart`]
/// of its band, the held rows `rows` of `c` (136 bytes), and rank 0 joins them in rank order
/// ([`crate::sim::checkpoint::site_identity_of`]); the strings are those of the whole site bit
/// for bit. Every rank of `t` calls it at the same point. Returns `Some` on rank 0.
///
/// Errors: [`Error::Exchange`] from the transport or a message of another length.
fn identity_by(c: &SiteConditions, rows: std::ops::Range<usize>, t: &mut dyn Transport) -> Result<Option<Vec<(String, String)>>> {
    let p = crate::sim::checkpoint::identity_part(c, rows);
    let mut e = crate::sim::codec::Enc(Vec::new());
    for (crc, len) in p.crcs {
        e.u64(crc as u64);
        e.u64(len);
    }
    e.u64(p.valid);
    e.u64(p.lo.to_bits() as u64);
    e.u64(p.hi.to_bits() as u64);
    let mut out = vec![Vec::new(); t.size()];
    out[0] = e.0;
    let got = t.exchange(out)?;
    if t.rank() != 0 {
        return Ok(None);
    }
    let mut parts = Vec::with_capacity(got.len());
    for (k, m) in got.iter().enumerate() {
        let fail = |s: crate::sim::codec::Short| Error::Exchange { peer: k, reason: format!("site identity part cut short at byte {}", s.at()) };
        let mut d = crate::sim::codec::Dec::at(m, 0, &fail);
        let mut crcs = [(0u32, 0u64); 7];
        for x in crcs.iter_mut() {
            *x = (d.u64()? as u32, d.u64()?);
        }
        let (valid, lo, hi) = (d.u64()?, f32::from_bits(d.u64()? as u32), f32::from_bits(d.u64()? as u32));
        parts.push(crate::sim::checkpoint::IdentityPart { crcs, valid, lo, hi });
    }
    Ok(Some(crate::sim::checkpoint::site_identity_of(c.width(), c.height(), c.cell_x_m, c.cell_y_m, &parts)))
}

/// The layout of [`layout_for`] from the weights per light column `wc` and row `wr`.
fn layout_weighted(world: &World, n: usize, wc: &[u64], wr: &[u64]) -> Result<Layout> {
    let (nx, ny) = grid_for(n, world.site.light.cols, world.site.light.rows);
    // the message names the count asked for, not only the grid it was cut into
    let (cols, rows) = (world.site.light.cols, world.site.light.rows);
    let named = |e: Error| match e {
        Error::Invalid { context, field, value, expected } if field == "tiles" => Error::Invalid {
            context,
            field,
            value: format!("{n} (cut into {value} tiles)"),
            expected: format!("a count whose near-square grid of tiles fits this site's light grid of {cols} × {rows} cells ({expected})"),
        },
        e => e,
    };
    let even = Layout::new(&world.site, nx, ny).map_err(named)?;
    let (cb, rb) = (crate::sim::tiles::cut_by_weight(wc, nx), crate::sim::tiles::cut_by_weight(wr, ny));
    if cb == even.col_bounds && rb == even.row_bounds {
        return Ok(even);
    }
    Ok(Layout::with_bounds(&world.site, cb, rb)?)
}

/// Checks, before anything is written, that `n` tiles fit the light grid of `site` under
/// `scenario` (the check [`layout_for`] makes once the world is built; a refused count used to
/// leave the run's `species/` behind: found by a trial).
///
/// Errors: [`Error::Invalid`] naming the count, the grid of tiles it is cut into and the light
/// grid's columns and rows.
pub fn check_tile_count(site: &SiteConditions, scenario: &Scenario, n: usize) -> Result<()> {
    let light = crate::sim::LightGrid::new(site.extent_m(), scenario.light_cell_m);
    let (nx, ny) = grid_for(n, light.cols, light.rows);
    if nx == 0 || ny == 0 || nx > light.cols || ny > light.rows {
        return Err(Error::Invalid {
            context: "tiled run".into(),
            field: "tiles".into(),
            value: format!("{n} (cut into {nx} × {ny} tiles)"),
            expected: format!("a count whose near-square grid of tiles fits this site's light grid of {} × {} cells (1–{} across and 1–{} up (the light grid's columns and rows))", light.cols, light.rows, light.cols, light.rows),
        }
        .into());
    }
    Ok(())
}

/// Rank 0's [`Stepper`]: its own tile, the transport, the tallies at the start (zero once
/// they are in rank 0's tile: its tallies then count from the run's start).
pub struct Root<'t> {
    t: &'t mut dyn Transport,
    tile: Option<Tile>,
    base: Tallies,
    /// The other ranks were told to end (or failed with rank 0 in a collective step).
    done: bool,
    /// Once the run driver's world is cut to rank 0's tile ([`Stepper::shed`]): the maps'
    /// longest side and, per map pixel, whether its centre is masked
    /// ([`crate::output::plot::map_masked_centres`] of the whole site, taken before the cut).
    map_masked: Option<(usize, Vec<bool>)>,
    /// The layout, once the ranks have cut it ([`Root::layout`]).
    layout: Option<Layout>,
    /// Rank 0 holds its tile's part of the site only, from the start ([`Stepper::world`] of a
    /// fresh run, issue 37 Build 1, round 33).
    lean: bool,
}

impl<'t> Root<'t> {
    /// Rank 0 of the transport `t`.
    pub fn new(t: &'t mut dyn Transport) -> Self {
        Root { t, tile: None, base: Tallies::default(), done: false, map_masked: None, layout: None, lean: false }
    }

    /// The run's layout: the first call tells the ranks [`Command::Layout`] and cuts it with
    /// them from their parts of the weights ([`layout_by`], `world` the site's); later calls
    /// return it. A failure there is every rank's (the same sums, the same error), so the
    /// others are not told to end afterwards.
    ///
    /// Errors: as [`layout_by`].
    fn layout(&mut self, world: &World) -> Result<Layout> {
        if let Some(l) = &self.layout {
            return Ok(l.clone());
        }
        command(self.t, Some(Command::Layout))?;
        // the median is rank 0's part of the ranks' selection; its world has it already
        let r = layout_by(world, self.t).and_then(|(l, _)| {
            // rank 0 holds the whole site: it sends the other ranks' tiles their cells
            let c = &world.site.conditions;
            tile_site_by(std::borrow::Cow::Borrowed(c), world.site.whole_identity.as_deref().filter(|_| !c.holds_all()), world.site.light.cell_m, &l, self.t)?;
            Ok(l)
        });
        if r.is_err() {
            self.done = true;
        }
        let l = r?;
        self.layout = Some(l.clone());
        Ok(l)
    }

    /// Bytes rank 0 has sent to other ranks (halo copies, its part of the gathers, commands).
    pub fn bytes_sent(&self) -> u64 {
        self.t.bytes_sent()
    }

    /// Tells the other ranks the run is over.
    ///
    /// Errors: [`Error::Exchange`] from the transport.
    pub fn end(&mut self) -> Result<()> {
        if !self.done {
            self.done = true;
            command(self.t, Some(Command::End))?;
            if let Some(tl) = self.tile.as_ref() {
                // rank 0's outputs are timed by the run driver (`output` in its phase times)
                print_phase_times(tl, None);
            }
        }
        Ok(())
    }

    /// Runs `f` on the tile and the transport; an error there is every rank's (the collective
    /// steps fail together), so the others are not told to end afterwards.
    fn collective<T>(&mut self, f: impl FnOnce(&mut Tile, &mut dyn Transport) -> Result<T>) -> Result<T> {
        let Some(tile) = self.tile.as_mut() else {
            return Err(Error::Exchange { peer: 0, reason: "a year stepped before the run began".into() }.into());
        };
        let r = f(tile, self.t);
        if r.is_err() {
            self.done = true;
        }
        r
    }
}

impl Drop for Root<'_> {
    fn drop(&mut self) {
        // rank 0 failed outside a collective step (an output it could not write): release the
        // others, which wait for a command
        let _ = self.end();
    }
}

impl Root<'_> {
    /// [`Stepper::resume`] of a lean start: finds the checkpoint of `dir` ([`checkpoint::find`]),
    /// tells the ranks [`Command::ResumeRanks`] and reads rank 0's part with them
    /// ([`resume_tile`]); sets `world`'s year and next tree id (the driver's world holds no
    /// trees) and returns the stand table so far.
    ///
    /// Errors: [`Error::Format`] when `dir` holds no checkpoint; as [`checkpoint::find`] and
    /// [`resume_tile`].
    fn resume_ranks(&mut self, dir: &Path, world: &mut World) -> Result<Vec<StandRow>> {
        let light = world.site.light;
        let src = match checkpoint::find(dir)? {
            Found::Ranks(m) => {
                let cd = dir.join(checkpoint::RANK_DIR);
                Source { year: Some(m.year), col_bounds: m.col_bounds.clone(), row_bounds: m.row_bounds.clone(), tiles: (m.tiles_across, m.tiles_up), paths: m.files.iter().map(|f| cd.join(f)).collect(), named: cd.join(checkpoint::MANIFEST) }
            }
            Found::Single(p) => Source { year: None, col_bounds: vec![0, light.cols], row_bounds: vec![0, light.rows], tiles: (1, 1), paths: vec![p.clone()], named: p },
            Found::None => return Err(Error::format(dir.join(checkpoint::FILE), "--resume: no checkpoint in the run directory").into()),
        };
        command(self.t, Some(Command::ResumeRanks))?;
        let rows = self.collective(|tile, t| resume_tile(tile, t, Some(&src)))?;
        let tile = self.tile.as_ref().ok_or_else(|| Error::Exchange { peer: 0, reason: "resumed before the run began".into() })?;
        world.stand.year = tile.world.stand.year;
        world.stand.trees.next_id = tile.world.stand.trees.next_id;
        self.base = zero_tallies(world);
        Ok(rows)
    }

    /// [`Stepper::world`]'s lean start on rank 0 (`w` the skeleton of its band): the layout
    /// with the ranks ([`layout_by`]), its tile's cells from the bands' owners
    /// ([`tile_site_by`]), then [`start_tile`]. Returns the layout, rank 0's tile and what
    /// year 0 needs (every rank's start's trees when `year0`, the maps' masked pixels).
    ///
    /// Errors: as [`layout_by`], [`tile_site_by`] and [`start_tile`].
    fn lean_start(&mut self, mut w: World, scenario: &Scenario, lean: Lean) -> Result<(Layout, Tile, Option<(crate::sim::TreeStore, Vec<bool>)>)> {
        command(self.t, Some(Command::Layout))?;
        let (l, median) = layout_by(&w, self.t)?;
        let c = &mut w.site.conditions;
        let band = std::mem::replace(c, SiteConditions::uniform(c.width(), 0, c.cell_x_m, 0.0, [0.0; 6], 0.0));
        let (c, ws) = tile_site_by(std::borrow::Cow::Owned(band), None, w.site.light.cell_m, &l, self.t)?.ok_or_else(|| Error::Exchange { peer: 0, reason: "rank 0 holds its band of the site but got no tile's cells".into() })?;
        w.site.conditions = c;
        command(self.t, Some(Command::Start))?;
        let (tile, start) = start_tile(w, scenario, &l, median, Some(&ws), Some((lean.map_px, lean.year0, lean.resume)), self.t)?;
        Ok((l, tile, start))
    }
}

impl Stepper for Root<'_> {
    /// With `lean` (a run that nothing reads whole, fresh or, since round 37, resumed: then
    /// no start's trees are placed and [`Stepper::resume`] reads the stand per rank) on 2
    /// ranks or more (with management
    /// too since round 36: its areas are resolved by the ranks from their tiles,
    /// [`crate::sim::tiles::derive_tile_site_by`], and its warnings printed once they are):
    /// rank 0 holds its band of `site` only (cut so when given whole), checks what needs
    /// no whole site ([`World::skeleton`], [`World::warn`]) and builds its tile's world only,
    /// as the other ranks do ([`Root::lean_start`]: the layout, its tile's cells from the bands'
    /// owners, [`start_tile`]); the world it returns is its tile's without the site's cells
    /// ([`driver_of`]) holding every rank's start's trees (year 0's snapshot reads them;
    /// [`Stepper::begin_shed`] drops them), and
    /// the maps' masked pixels are kept from the ranks (issue 37 Build 1, round 33: until then
    /// rank 0 built the world of one process, [`World::new`], and cut its tile from it).
    /// Otherwise [`World::new`] of the whole site.
    ///
    /// Errors: as [`World::new`] and [`Root::lean_start`]; [`Error::Invalid`] when `site` is
    /// not whole and the start is not lean.
    fn world(&mut self, site: SiteConditions, lib: &SpeciesLibrary, scenario: &Scenario, lean: Option<Lean>) -> Result<World> {
        let n = self.t.size();
        let Some(lean) = lean.filter(|_| n > 1) else {
            if !site.holds_all() {
                return Err(Error::Invalid { context: scenario.context(), field: "site conditions".into(), value: format!("cells {} of {} × {} on rank 0", site.held, site.full.0, site.full.1), expected: "the whole site on rank 0 (a caller that reads the world at snapshots)".into() }.into());
            }
            return Ok(World::new(site, lib, scenario)?);
        };
        let mut site = site;
        if site.holds_all() {
            let b = crate::sim::tiles::weight_band(0, n, site.height());
            site.hold(crate::grid::Window { col0: 0, row0: b.start, width: site.width(), height: b.len() });
        }
        let w = World::skeleton(site, lib, scenario)?;
        w.warn(scenario);
        let r = self.lean_start(w, scenario, lean);
        if r.is_err() {
            self.done = true;
        }
        let (l, mut tile, start) = r?;
        // the management's warnings, once its areas are resolved (by the ranks together)
        for m in crate::sim::management::warnings(&tile.world.site.management, scenario.years, &scenario.context()) {
            tracing::warn!("{m}");
        }
        let mut world = driver_of(&mut tile.world);
        if let Some((trees, masked)) = start {
            if lean.year0 {
                world.stand.trees = trees;
            }
            self.map_masked = Some((lean.map_px, masked));
        }
        self.base = zero_tallies(&world);
        self.layout = Some(l);
        self.tile = Some(tile);
        self.lean = true;
        Ok(world)
    }
    /// Year 0's snapshot: from `world` as one process writes it; when rank 0 holds its tile
    /// only ([`Stepper::world`]'s lean start) `world` holds every rank's start's trees and the
    /// maps' masked pixels come from the ranks.
    ///
    /// Errors: I/O errors naming the file; [`Error::Invalid`] for maps of another size than
    /// the run began with.
    fn start_snapshot(&mut self, dir: &Path, world: &World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat) -> Result<()> {
        match (&self.map_masked, self.lean) {
            (_, false) => super::run::snapshot_masked(dir, world, label, parts, map_px, format, None),
            (Some((px, masked)), true) if *px == map_px => super::run::snapshot_masked(dir, world, label, parts, map_px, format, Some(masked)),
            _ => Err(Error::Invalid { context: "tiled run".into(), field: "map_px".into(), value: map_px.to_string(), expected: "the maps' size the run began with (rank 0 holds the masked pixels of that size only)".into() }.into()),
        }
    }
    fn begin(&mut self, world: &World) -> Result<()> {
        if self.tile.is_some() {
            // resumed from the per-rank checkpoints: every rank holds its tile already
            return Ok(());
        }
        let layout = self.layout(world)?;
        command(self.t, Some(Command::Begin))?;
        self.tile = Some(Tile::new(world, layout, 0)?);
        self.collective(|tile, t| Ok(tile.scatter(Some(world), t)?))?;
        // the tallies so far go into rank 0's tile, so the ranks' tallies add up to the run's
        // (what each rank's checkpoint holds)
        self.base = zero_tallies(world);
        if let Some(tile) = self.tile.as_mut() {
            tile.world.tallies = world.tallies.clone();
        }
        Ok(())
    }
    /// [`Stepper::begin`] and [`Stepper::shed`] without a copy of rank 0's tile beside the
    /// whole world (issue 37 Build 1): every rank's part of the stand is encoded from the whole
    /// world ([`Tile::parts`]) and the maps' masked pixels taken, then the driver's world is
    /// cut to rank 0's tile ([`crate::sim::tiles::shed_to_tile`]) and rank 0's tile made from
    /// a copy of what is left (the tile's site, no trees) before the parts are exchanged. The
    /// tile and the driver's world are those of `begin` then `shed`.
    ///
    /// Errors: as [`Stepper::begin`] and [`Stepper::shed`].
    fn begin_shed(&mut self, world: &mut World, map_px: usize) -> Result<()> {
        if self.tile.is_some() {
            // resumed from the per-rank checkpoints: every rank holds its tile already
            return self.shed(world, map_px);
        }
        let layout = self.layout(world)?;
        command(self.t, Some(Command::Begin))?;
        let parts = Tile::parts(world, &layout, self.t.size())?;
        if self.map_masked.is_none() {
            self.map_masked = Some((map_px, crate::output::plot::map_masked_centres(world, map_px)));
        }
        crate::sim::tiles::shed_to_tile(world, &layout, 0)?;
        self.tile = Some(Tile::own(world.clone(), layout, 0)?);
        self.collective(|tile, t| Ok(tile.scatter_parts(parts, t)?))?;
        self.base = zero_tallies(world);
        if let Some(tile) = self.tile.as_mut() {
            tile.world.tallies = world.tallies.clone();
        }
        Ok(())
    }
    /// Year 0's row from the ranks' tiles ([`Command::Row`], [`Tile::start_row`]).
    ///
    /// Errors: [`Error::Exchange`] from the transport.
    fn start_row(&mut self, _: &World) -> Result<StandRow> {
        command(self.t, Some(Command::Row))?;
        let r = self.collective(|tile, t| Ok(tile.start_row(t)?))?;
        Ok(r.ok_or_else(|| Error::Exchange { peer: 0, reason: "rank 0 got no year-0 row".into() })?)
    }
    fn step(&mut self, world: &mut World, _: &Scenario, report: &mut YearReport, full: bool, _: &mut dyn FnMut(Season, &World)) -> Result<()> {
        command(self.t, Some(if full { Command::StepFull } else { Command::Step }))?;
        let base = self.base.clone();
        *report = self.collective(|tile, t| {
            let r = tile.step(t)?;
            if full {
                tile.gather(Some((world, &base)), t)?;
            }
            Ok(r)
        })?;
        world.stand.year = report.row.as_ref().map_or(world.stand.year + 1, |r| r.year);
        Ok(())
    }
    fn complete(&mut self, world: &mut World) -> Result<()> {
        command(self.t, Some(Command::Complete))?;
        let base = self.base.clone();
        self.collective(|tile, t| Ok(tile.gather(Some((world, &base)), t)?))
    }
    /// When every rank holds its tile only ([`Stepper::world`]'s lean start of a resumed run,
    /// issue 37 Build 1, round 37): every rank reads its part of the checkpoint from the files
    /// that overlap its tile ([`resume_tile`]), on any number of ranks, from per-rank
    /// checkpoints or one process's `checkpoint.bin`. Otherwise (a caller reads the world at
    /// snapshots): per-rank checkpoints with the same layout have every rank read its own file;
    /// else rank 0 reads `checkpoint.bin` or assembles the per-rank files, and
    /// [`Stepper::begin`] sends the ranks their parts.
    fn resume(&mut self, dir: &Path, world: &mut World) -> Result<Vec<StandRow>> {
        if self.lean {
            return self.resume_ranks(dir, world);
        }
        let m = match checkpoint::find(dir)? {
            Found::Ranks(m) => m,
            _ => return checkpoint::load_any(dir, world),
        };
        let layout = self.layout(world)?;
        if m.ranks != self.t.size() || !m.same_layout(&layout) {
            return checkpoint::load_ranks(dir, &m, world);
        }
        command(self.t, Some(Command::Resume))?;
        let cd = dir.join(checkpoint::RANK_DIR);
        let r = (|| -> Result<(Tile, Vec<StandRow>)> {
            let (year, p) = send_paths(self.t, Some((m.year, m.files.iter().map(|f| cd.join(f)).collect())))?;
            let r = load_tile(world.clone(), &layout, 0, &p, year);
            let a = agree(self.t, r.as_ref().err().map(|e| e.to_string()));
            let r = r?;
            a?;
            Ok(r)
        })();
        if r.is_err() {
            self.done = true;
        }
        let (tile, rows) = r?;
        world.stand.year = tile.world.stand.year;
        world.stand.trees.next_id = tile.world.stand.trees.next_id;
        self.base = zero_tallies(world);
        self.tile = Some(tile);
        Ok(rows)
    }
    /// Every rank writes its tile's checkpoint (rank 0's with `rows`); rank 0 then commits
    /// them with the manifest. `world` is not read.
    fn save(&mut self, dir: &Path, _: &World, rows: &[StandRow]) -> Result<()> {
        let Some(tile) = self.tile.as_ref() else {
            return Err(Error::Exchange { peer: 0, reason: "a checkpoint before the run began".into() }.into());
        };
        let m = Manifest::new(tile.world.stand.year, &tile.layout);
        let cd = dir.join(checkpoint::RANK_DIR);
        std::fs::create_dir_all(&cd).map_err(|e| Error::io(&cd, e))?;
        command(self.t, Some(Command::Save))?;
        let paths: Vec<PathBuf> = m.files.iter().map(|f| cd.join(f)).collect();
        self.collective(|tile, t| {
            let (_, p) = send_paths(t, Some((m.year, paths)))?;
            let r = checkpoint::save(&p, &tile.world, rows);
            agree(t, r.as_ref().err().map(|e| e.to_string()))?;
            r
        })?;
        checkpoint::commit_ranks(dir, &m)
    }
    fn save_reads_world(&self) -> bool {
        false
    }
    /// Every rank writes its parts of the snapshot ([`write_parts`]: its inventory, GeoPackage
    /// and regeneration parts); rank 0 draws the maps from the ranks' basal area per map bin.
    #[allow(clippy::too_many_arguments)]
    fn snapshot(&mut self, dir: &Path, world: &mut World, label: &str, parts: Parts, map_px: usize, format: InventoryFormat) -> Result<()> {
        let Parts { inventory, gpkg, maps } = parts;
        let snap = Snap { dir: dir.to_path_buf(), label: label.to_string(), inventory, gpkg: inventory && gpkg, maps, map_px, format };
        command(self.t, Some(Command::Snapshot))?;
        let ba = self.collective(|tile, t| write_parts(tile, t, Some(&snap)))?;
        if maps {
            let ba = ba.ok_or_else(|| Error::Exchange { peer: 0, reason: "no map sums gathered".into() })?;
            let m = dir.join("maps");
            let (sp, bp) = (m.join(format!("species_{label}.png")), m.join(format!("basal_area_{label}.png")));
            match &self.map_masked {
                Some((px, masked)) if *px == map_px => crate::output::plot::write_maps_masked(&sp, &bp, world, map_px, &ba, masked)?,
                Some((px, _)) => return Err(Error::Invalid { context: "tiled run".into(), field: "map_px".into(), value: map_px.to_string(), expected: format!("{px}, the maps' size the run began with (rank 0 holds the masked pixels of that size only)") }.into()),
                None => crate::output::plot::write_maps_from(&sp, &bp, world, map_px, &ba)?,
            }
        }
        Ok(())
    }
    fn snapshot_reads_world(&self) -> bool {
        false
    }
    /// Cuts the run driver's world to rank 0's tile ([`crate::sim::tiles::shed_to_tile`]):
    /// every output of the run comes from the ranks' parts (inventories, the maps' basal area
    /// per bin, the stand table's sums, per-rank checkpoints), and the maps' masked pixels
    /// (from the whole site) are kept first, so rank 0 holds no whole-site array for the rest
    /// of the run (issue 37 Build 1).
    ///
    /// Errors: [`Error::Exchange`] before the run began; as [`crate::sim::tiles::shed_to_tile`].
    fn shed(&mut self, world: &mut World, map_px: usize) -> Result<()> {
        let Some(tile) = self.tile.as_ref() else {
            return Err(Error::Exchange { peer: 0, reason: "the run driver's world cut before the run began".into() }.into());
        };
        if self.map_masked.is_none() {
            self.map_masked = Some((map_px, crate::output::plot::map_masked_centres(world, map_px)));
        }
        Ok(crate::sim::tiles::shed_to_tile(world, &tile.layout, 0)?)
    }
}

/// A rank other than 0: holds `site` in a [`World::skeleton`] of `scenario` (nothing derived
/// from the site, no trees; a whole `site` cut to its band of site rows first unless the
/// scenario has management: the ranks of a run whose rank 0 builds the world of one process
/// (a caller reads it at snapshots) resolve its areas against the whole site, while a lean
/// run's ranks, fresh or resumed, resolve them together from their tiles (`start_tile`), so an
/// MPI rank is given its band only, `sylva simulate`), cuts the layout
/// with the other ranks ([`layout_by`]: the weights and the insolation's median from its
/// band; then its tile's cells from the band owners, [`tile_site_by`]), derives only its
/// tile's part of the site into it ([`crate::sim::tiles::derive_tile_site_with`]; issue 37
/// Build 1: until round 32 every rank
/// built the whole world of one process, `World::new`, and cut its tile from it), then follows
/// rank 0's commands until [`Command::End`]. Its tile's stand and the next tree id come from
/// rank 0 ([`Tile::scatter`]) or from the checkpoint (its own file, [`Command::Resume`], or
/// the files overlapping its tile, [`Command::ResumeRanks`]). Writes no files. The scenario's checks
/// and warnings are rank 0's (its run driver builds the world of one process).
///
/// Errors: unknown species or points outside the site (as [`World::skeleton`]); management
/// entries that do not resolve; the tiles' errors (a halo too narrow, a failed exchange); a
/// command out of order.
pub fn work(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, t: &mut dyn Transport) -> Result<()> {
    check(scenario)?;
    let me = t.rank();
    let mut site = site;
    if scenario.management.is_empty() && t.size() > 1 && me != 0 && site.holds_all() {
        // only this rank's band of site rows (what `site_ranks::site_by_ranks_held` gives an
        // MPI rank); its tile's cells come from the bands' owners with the layout
        let b = crate::sim::tiles::weight_band(me, t.size(), site.height());
        site.hold(crate::grid::Window { col0: 0, row0: b.start, width: site.width(), height: b.len() });
    }
    let world = World::skeleton(site, lib, scenario)?;
    // the whole site's identity and unmasked count, when this rank holds its tile's cells only
    let mut whole: Option<crate::sim::tiles::WholeSite> = None;
    // the layout and the insolation's median, found with the other ranks on [`Command::Layout`]
    let mut layout: Option<(Layout, f32)> = None;
    let laid = |l: &Option<(Layout, f32)>, c: Command| l.clone().ok_or_else(|| Error::Exchange { peer: 0, reason: format!("command {c:?} before the layout was cut (command Layout)") });
    // the skeleton of the scenario's world, until this rank's tile's site is derived into it
    // (Begin, or Resume before its checkpoint is read into it): then the tile holds the site
    let mut world = Some(world);
    let template = |w: &mut Option<World>, c: Command| w.take().ok_or_else(|| Error::Exchange { peer: 0, reason: format!("command {c:?} after this rank's tile was made") });
    let mut tile: Option<Tile> = None;
    // wall time (s) in the snapshots' and checkpoints' collective steps (SYLVA_PHASE_TIMES=1)
    let mut output_s = 0.0;
    loop {
        let c = command(t, None)?;
        let t0 = std::time::Instant::now();
        match (c, tile.as_mut()) {
            (Command::End, _) => {
                if let Some(tl) = tile.as_ref() {
                    print_phase_times(tl, Some(output_s));
                }
                return Ok(());
            }
            (Command::Layout, _) => {
                let w = world.as_mut().ok_or_else(|| Error::Exchange { peer: 0, reason: "command Layout after this rank's tile was made".into() })?;
                let (l, median) = layout_by(w, t)?;
                // a band gives way to the tile's cells (given up grid by grid as it is sent)
                let c = &mut w.site.conditions;
                let held = if c.holds_all() {
                    tile_site_by(std::borrow::Cow::Borrowed(c), None, w.site.light.cell_m, &l, t)?;
                    None
                } else {
                    let band = std::mem::replace(c, SiteConditions::uniform(c.width(), 0, c.cell_x_m, 0.0, [0.0; 6], 0.0));
                    tile_site_by(std::borrow::Cow::Owned(band), None, w.site.light.cell_m, &l, t)?
                };
                if let Some((c, ws)) = held {
                    w.site.conditions = c;
                    whole = Some(ws);
                }
                layout = Some((l, median));
            }
            (Command::Begin, _) => {
                let (l, median) = laid(&layout, c)?;
                let mut w = template(&mut world, c)?;
                crate::sim::tiles::derive_tile_site_with(&mut w, scenario, &l, me, median, whole.as_ref())?;
                let mut tl = Tile::own(w, l, me)?;
                tl.scatter(None, t)?;
                tile = Some(tl);
            }
            (Command::Start, None) => {
                let (l, median) = laid(&layout, c)?;
                let w = template(&mut world, c)?;
                tile = Some(start_tile(w, scenario, &l, median, whole.as_ref(), None, t)?.0);
            }
            (Command::ResumeRanks, Some(tl)) => {
                resume_tile(tl, t, None)?;
            }
            (Command::Step, Some(tl)) => {
                tl.step(t)?;
            }
            (Command::Row, Some(tl)) => {
                tl.start_row(t)?;
            }
            (Command::StepFull, Some(tl)) => {
                tl.step(t)?;
                tl.gather(None, t)?;
            }
            (Command::Complete, Some(tl)) => tl.gather(None, t)?,
            (Command::Save, Some(tl)) => {
                let (_, p) = send_paths(t, None)?;
                let r = checkpoint::save(&p, &tl.world, &[]);
                agree(t, r.as_ref().err().map(|e| e.to_string()))?;
                r?;
            }
            (Command::Resume, None) => {
                let (year, p) = send_paths(t, None)?;
                let r = laid(&layout, c).and_then(|l| Ok((template(&mut world, c)?, l))).map_err(super::JobError::from).and_then(|(mut w, (l, median))| {
                    crate::sim::tiles::derive_tile_site_with(&mut w, scenario, &l, me, median, whole.as_ref())?;
                    load_tile(w, &l, me, &p, year)
                });
                let a = agree(t, r.as_ref().err().map(|e| e.to_string()));
                let (tl, _) = r?;
                a?;
                tile = Some(tl);
            }
            (Command::Snapshot, Some(tl)) => {
                write_parts(tl, t, None)?;
            }
            (Command::Resume, Some(_)) => return Err(Error::Exchange { peer: 0, reason: "command Resume after the run began".into() }.into()),
            (Command::Start, Some(_)) => return Err(Error::Exchange { peer: 0, reason: "command Start after the run began".into() }.into()),
            (c, None) => return Err(Error::Exchange { peer: 0, reason: format!("command {c:?} before the run began") }.into()),
        }
        if matches!(c, Command::Save | Command::Snapshot) {
            output_s += t0.elapsed().as_secs_f64();
        }
    }
}

/// With `SYLVA_PHASE_TIMES=1` in the environment, prints `tile`'s wall time per phase
/// ([`Tile::phase_line`]) and `output_s`, the seconds of its snapshots and checkpoints (rank 0:
/// `None`, its run driver times them), to stderr in one write.
fn print_phase_times(tile: &Tile, output_s: Option<f64>) {
    if std::env::var_os("SYLVA_PHASE_TIMES").is_some() {
        let out = output_s.map_or(String::new(), |s| format!(", outputs {s:.1} s"));
        let line = format!("{}{out}\n", tile.phase_line());
        let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    }
}

/// Runs `scenario` as a tiled run over the transport `t`, one tile per rank: rank 0 drives the
/// run and returns its summary, the other ranks return `None`. Every rank writes into the run
/// directory of `opts` (its checkpoint, its part files of the inventories), so it must be a
/// folder all ranks share.
///
/// Errors: as [`run_scenario_with`] on rank 0 and [`work`] on the others; a scenario with
/// seasonal snapshots.
pub fn run_tiled(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: RunOptions, t: &mut dyn Transport) -> Result<Option<RunSummary>> {
    check(scenario)?;
    if t.rank() != 0 {
        work(scenario, site, lib, t)?;
        return Ok(None);
    }
    let mut root = Root::new(t);
    let s = run_scenario_with(scenario, site, lib, opts, &mut root)?;
    root.end()?;
    Ok(Some(s))
}

/// Runs `scenario` as `n` tiles in this process, one thread per tile over a
/// [`LocalTransport`] (the same exchanges as over MPI); writes the run directory of `opts`.
/// Returns the summary and the bytes each rank sent to the others.
///
/// Errors: as [`run_tiled`]; the light grid too small for `n` tiles.
pub fn run_local_tiles(scenario: &Scenario, site: SiteConditions, lib: &SpeciesLibrary, opts: RunOptions, n: usize) -> Result<(RunSummary, Vec<u64>)> {
    check(scenario)?;
    // the layout is checked before any thread waits for another (quietly: the run driver
    // prints the scenario's warnings)
    layout_for(&World::build(site.clone(), lib, scenario, false)?, n)?;
    let mut ends = LocalTransport::group(n.max(1)).into_iter();
    let Some(mut t0) = ends.next() else {
        return Err(Error::Exchange { peer: 0, reason: "no ranks".into() }.into());
    };
    std::thread::scope(|s| {
        let workers: Vec<_> = ends
            .map(|mut t| {
                let site = site.clone();
                s.spawn(move || work(scenario, site, lib, &mut t).map(|_| t.bytes_sent()))
            })
            .collect();
        let root = (|| {
            let mut root = Root::new(&mut t0);
            let s = run_scenario_with(scenario, site, lib, opts, &mut root)?;
            root.end()?;
            Ok::<_, super::JobError>((s, root.bytes_sent()))
        })();
        let mut bytes = vec![0u64];
        let mut first_err = None;
        for w in workers {
            match w.join() {
                Ok(Ok(b)) => bytes.push(b),
                Ok(Err(e)) => {
                    first_err.get_or_insert(e);
                }
                Err(_) => {
                    first_err.get_or_insert(Error::Exchange { peer: 1, reason: "a tile's thread panicked".into() }.into());
                }
            }
        }
        let (s, b0) = root?;
        if let Some(e) = first_err {
            return Err(e);
        }
        bytes[0] = b0;
        Ok((s, bytes))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_grids_are_close_to_square() {
        assert_eq!(grid_for(1, 100, 50), (1, 1));
        assert_eq!(grid_for(2, 100, 50), (2, 1));
        assert_eq!(grid_for(3, 100, 50), (3, 1));
        assert_eq!(grid_for(4, 100, 100), (2, 2));
        assert_eq!(grid_for(8, 100, 50), (4, 2));
        assert_eq!(grid_for(6, 40, 120), (2, 3), "a tie (1 × 6, 2 × 3) goes to more tiles across");
        for c in [Command::Begin, Command::Step, Command::StepFull, Command::Complete, Command::End, Command::Save, Command::Resume, Command::Snapshot, Command::Layout, Command::Start, Command::ResumeRanks] {
            assert_eq!(Command::from_byte(c as u8), Some(c));
        }
        assert_eq!(Command::from_byte(0), None);
    }
}
