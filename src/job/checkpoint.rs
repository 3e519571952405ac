//! Checkpoint files of a run directory: the simulation encodes and decodes its state
//! ([`crate::sim::checkpoint`]); this shell reads and writes the files. One process writes
//! `checkpoint.bin`; a tiled run (MPI ranks, `--tiles N`) writes one checkpoint per rank,
//! `checkpoint/year_YYYY_rank_RRRR.bin`, and then `checkpoint/manifest.toml` ([`Manifest`]:
//! year, layout, files), which commits them. A resume on the same layout reads each rank's own
//! file; on another layout, or in one process, the files are assembled into the world of one
//! process ([`load_ranks`]).

use super::Result;
use crate::Error;
use crate::sim::checkpoint::{restore, write_to};
use crate::sim::stats::StandRow;
use crate::sim::World;
use crate::sim::tiles::Layout;
use std::path::{Path, PathBuf};

/// Writes a checkpoint of `w` and the stand table `rows` to `path` atomically (streamed into a
/// temporary file, synced, renamed; [`crate::output::write_atomic_with`]): a failed write (a
/// full disk) leaves the earlier checkpoint whole.
///
/// Errors: [`crate::output::OutputError::Io`] naming the file and the reason.
pub fn save(path: &Path, w: &World, rows: &[StandRow]) -> Result<()> {
    Ok(crate::output::write_atomic_with(path, |f| write_to(w, rows, f))?)
}

/// Reads the checkpoint file `path` into `w`; returns the stand table so far.
///
/// Errors: [`Error::Io`] when the file cannot be read; [`Error::Format`] naming the file when it
/// is not a checkpoint of this layout, is truncated or corrupt, or belongs to a run whose seed,
/// species, terrain, site conditions, light cell, seed rain or obstacles differ (each change
/// named with its old and new value; [`crate::sim::checkpoint::restore`]).
pub fn load(path: &Path, w: &mut World) -> Result<Vec<StandRow>> {
    let b = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(restore(w, &b, path)?)
}

/// The checkpoint of one process in a run directory.
pub const FILE: &str = "checkpoint.bin";
/// Folder of a tiled run's per-rank checkpoints in a run directory.
pub const RANK_DIR: &str = "checkpoint";
/// The manifest of the per-rank checkpoints, in [`RANK_DIR`]: written last, it names the
/// files of the latest complete checkpoint.
pub const MANIFEST: &str = "manifest.toml";

/// Version of [`Manifest`]'s fields.
pub const MANIFEST_FORMAT: u32 = 1;

/// What `checkpoint/manifest.toml` says: the year, the layout of the tiled run that wrote the
/// per-rank checkpoints and their files (one per rank, rank order). Each file is an ordinary
/// checkpoint ([`crate::sim::checkpoint`]) of that rank's tile world: its own trees and
/// cohorts, the seed grids it held (the cells of its tile are the run's), its tallies (the
/// ranks' tallies add up to the run's; rank 0's holds those from before the tiled run began)
/// and, in rank 0's file only, the stand table.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// [`MANIFEST_FORMAT`].
    pub format: u32,
    /// Years completed at the checkpoint.
    pub year: u32,
    /// Ranks (= tiles) of the run that wrote it.
    pub ranks: usize,
    /// Tiles across (west to east).
    pub tiles_across: usize,
    /// Tiles up (south to north).
    pub tiles_up: usize,
    /// Column boundaries of the tiles in light cells ([`Layout::col_bounds`]).
    pub col_bounds: Vec<usize>,
    /// Row boundaries of the tiles in light cells ([`Layout::row_bounds`]).
    pub row_bounds: Vec<usize>,
    /// File of each rank, relative to the manifest's folder.
    pub files: Vec<String>,
}

impl Manifest {
    /// The manifest of a checkpoint at `year` of a run cut as `layout` (files [`rank_file`]).
    pub fn new(year: u32, layout: &Layout) -> Manifest {
        Manifest {
            format: MANIFEST_FORMAT,
            year,
            ranks: layout.len(),
            tiles_across: layout.nx,
            tiles_up: layout.ny,
            col_bounds: layout.col_bounds.clone(),
            row_bounds: layout.row_bounds.clone(),
            files: (0..layout.len()).map(|k| rank_file(year, k)).collect(),
        }
    }

    /// True when a run cut as `layout` can read the per-rank files as they are (same tiles).
    pub fn same_layout(&self, layout: &Layout) -> bool {
        self.tiles_across == layout.nx && self.tiles_up == layout.ny && self.col_bounds == layout.col_bounds && self.row_bounds == layout.row_bounds
    }
}

/// File name of rank `rank`'s checkpoint at `year`: `year_YYYY_rank_RRRR.bin`.
pub fn rank_file(year: u32, rank: usize) -> String {
    format!("year_{year:04}_rank_{rank:04}.bin")
}

/// Which checkpoint a run directory holds.
#[derive(Debug, Clone, PartialEq)]
pub enum Found {
    /// None.
    None,
    /// `checkpoint.bin` of one process (or of a tiled run before per-rank checkpoints).
    Single(PathBuf),
    /// Per-rank checkpoints, as the manifest names them.
    Ranks(Manifest),
}

/// The checkpoint of `dir`: `checkpoint.bin` or `checkpoint/manifest.toml`; when both are
/// there (a run stopped between writing one kind and removing the other), the newer file.
///
/// Errors: [`Error::Format`] naming the manifest when it cannot be read or parsed.
pub fn find(dir: &Path) -> Result<Found> {
    let (single, manifest) = (dir.join(FILE), dir.join(RANK_DIR).join(MANIFEST));
    let mtime = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    match (single.is_file(), manifest.is_file()) {
        (false, false) => Ok(Found::None),
        (true, false) => Ok(Found::Single(single)),
        (true, true) if mtime(&single) > mtime(&manifest) => Ok(Found::Single(single)),
        _ => Ok(Found::Ranks(read_manifest(dir)?)),
    }
}

/// True when `dir` holds a checkpoint of either kind ([`find`]).
pub fn exists(dir: &Path) -> bool {
    dir.join(FILE).is_file() || dir.join(RANK_DIR).join(MANIFEST).is_file()
}

/// Reads `dir/checkpoint/manifest.toml`.
///
/// Errors: [`Error::Io`] when it cannot be read; [`Error::Format`] naming the file when it is
/// not TOML of [`Manifest`]'s fields, of another format, or inconsistent (field named: a file
/// count other than `ranks`, tile counts that do not multiply to `ranks`, boundaries of the
/// wrong length).
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let p = dir.join(RANK_DIR).join(MANIFEST);
    let s = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, e))?;
    let m: Manifest = toml::from_str(&s).map_err(|e| Error::format(&p, format!("not a checkpoint manifest: {e}")))?;
    let bad = |field: &str, msg: String| -> super::JobError { Error::format(&p, format!("{field}: {msg}")).into() };
    if m.format != MANIFEST_FORMAT {
        return Err(bad("format", format!("{} (this Sylva reads {MANIFEST_FORMAT})", m.format)));
    }
    if m.tiles_across * m.tiles_up != m.ranks || m.ranks == 0 {
        return Err(bad("ranks", format!("{} with {} × {} tiles", m.ranks, m.tiles_across, m.tiles_up)));
    }
    if m.files.len() != m.ranks {
        return Err(bad("files", format!("{} names for {} ranks", m.files.len(), m.ranks)));
    }
    if m.col_bounds.len() != m.tiles_across + 1 || m.row_bounds.len() != m.tiles_up + 1 {
        return Err(bad("col_bounds/row_bounds", format!("{} and {} values for {} × {} tiles (expected one more than the tiles each)", m.col_bounds.len(), m.row_bounds.len(), m.tiles_across, m.tiles_up)));
    }
    if let Some(f) = m.files.iter().find(|f| f.contains('/') || f.contains('\\') || f.starts_with('.')) {
        return Err(bad("files", format!("{f:?} is not a file name of the manifest's folder")));
    }
    Ok(m)
}

/// Commits the per-rank checkpoint of `m` (its files already written and synced into
/// `dir/checkpoint/`): syncs the folder, writes the manifest atomically, syncs again, then
/// removes what it supersedes: the per-rank files it does not name and `checkpoint.bin`.
///
/// Errors: [`crate::output::OutputError::Io`] / [`Error::Io`] naming the file or folder.
pub fn commit_ranks(dir: &Path, m: &Manifest) -> Result<()> {
    let cd = dir.join(RANK_DIR);
    crate::output::sync_dir(&cd)?;
    let text = toml::to_string(m).map_err(|e| Error::format(cd.join(MANIFEST), format!("cannot write the manifest: {e}")))?;
    crate::output::write_atomic(&cd.join(MANIFEST), text.as_bytes())?;
    crate::output::sync_dir(&cd)?;
    remove_rank_files(&cd, &m.files)?;
    let single = dir.join(FILE);
    if single.exists() {
        std::fs::remove_file(&single).map_err(|e| Error::io(&single, e))?;
    }
    Ok(())
}

/// Removes the per-rank checkpoint files (`year_*_rank_*.bin`) of folder `cd` not in `keep`.
///
/// Errors: [`Error::Io`] naming the folder or file.
fn remove_rank_files(cd: &Path, keep: &[String]) -> Result<()> {
    if !cd.is_dir() {
        return Ok(());
    }
    for e in std::fs::read_dir(cd).map_err(|e| Error::io(cd, e))? {
        let e = e.map_err(|err| Error::io(cd, err))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with("year_") && name.contains("_rank_") && name.ends_with(".bin") && !keep.contains(&name) {
            let p = e.path();
            std::fs::remove_file(&p).map_err(|err| Error::io(&p, err))?;
        }
    }
    Ok(())
}

/// Removes the per-rank checkpoints of `dir` (the manifest first, then the files), e.g. once a
/// `checkpoint.bin` supersedes them or a fresh run starts. Other files of the folder are kept;
/// the folder itself is removed once empty (round 34's trial: a tiled run resumed in one
/// process left an empty `checkpoint/` beside `checkpoint.bin`).
///
/// Errors: [`Error::Io`] naming the file or folder.
pub fn remove_ranks(dir: &Path) -> Result<()> {
    let cd = dir.join(RANK_DIR);
    let m = cd.join(MANIFEST);
    if m.exists() {
        std::fs::remove_file(&m).map_err(|e| Error::io(&m, e))?;
    }
    remove_rank_files(&cd, &[])?;
    if cd.is_dir() && std::fs::read_dir(&cd).map_err(|e| Error::io(&cd, e))?.next().is_none() {
        std::fs::remove_dir(&cd).map_err(|e| Error::io(&cd, e))?;
    }
    Ok(())
}

/// Removes every checkpoint of `dir` (`checkpoint.bin` and the per-rank ones): a fresh run
/// must not be resumed from an earlier run's state.
///
/// Errors: [`Error::Io`] naming the file or folder.
pub fn remove_all(dir: &Path) -> Result<()> {
    let single = dir.join(FILE);
    if single.exists() {
        std::fs::remove_file(&single).map_err(|e| Error::io(&single, e))?;
    }
    remove_ranks(dir)
}

/// Reads rank `rank`'s file of `m` in `dir` into a copy of `template` (a world of the same
/// scenario, at its start) and returns it with the rows it holds (rank 0: the stand table);
/// its seed grids hold the rank's window ([`crate::sim::tiles::seed_window`] of the
/// manifest's layout), as the rank saved them.
///
/// Errors: as [`load`], naming the file; [`Error::Format`] naming it when its year is not the
/// manifest's, or naming the manifest when its layout is not one of this site's light grid.
pub fn load_rank(dir: &Path, m: &Manifest, rank: usize, template: &World) -> Result<(World, Vec<StandRow>)> {
    let Some(name) = m.files.get(rank) else {
        return Err(Error::format(dir.join(RANK_DIR).join(MANIFEST), format!("files: no file of rank {rank} ({} ranks)", m.ranks)).into());
    };
    let p = dir.join(RANK_DIR).join(name);
    let layout = manifest_layout(dir, m, template)?;
    let mut w = template.clone();
    crate::sim::tiles::hold_own_seeds(&mut w, &layout, rank)?;
    let rows = load(&p, &mut w)?;
    if w.stand.year != m.year {
        return Err(Error::format(&p, format!("year {} in a checkpoint whose manifest says year {}", w.stand.year, m.year)).into());
    }
    Ok((w, rows))
}

/// Reads the per-rank checkpoints of `m` in `dir` and assembles the world of one process in `w`
/// (built from the scenario; [`crate::sim::tiles::assemble`]); returns the stand table (rank
/// 0's). Every rank's file is in memory at once (a world per rank, the site included): for
/// resuming on another number of ranks or in one process.
///
/// Errors: as [`load_rank`] for each file; [`Error::Format`] naming the manifest when its layout
/// is not one of this site's light grid.
pub fn load_ranks(dir: &Path, m: &Manifest, w: &mut World) -> Result<Vec<StandRow>> {
    let layout = manifest_layout(dir, m, w)?;
    let mut tiles = Vec::with_capacity(m.ranks);
    let mut rows = Vec::new();
    let mut next_id = w.stand.trees.next_id;
    for k in 0..m.ranks {
        let (t, r) = load_rank(dir, m, k, w)?;
        if k == 0 {
            rows = r;
            next_id = t.stand.trees.next_id;
        }
        tiles.push(t);
    }
    w.stand.trees.next_id = next_id;
    crate::sim::tiles::assemble(w, &layout, tiles)?;
    w.scratch.dead.clear();
    w.scratch.regen_year = Default::default();
    Ok(rows)
}

/// The layout of manifest `m` of `dir` on `w`'s site: its bounds (tiles cut by area, or by
/// work since issue 37 Build 5), checked against this site's light grid.
///
/// Errors: [`Error::Format`] naming the manifest when its bounds do not fit the light grid or
/// are not the tiles it names.
fn manifest_layout(dir: &Path, m: &Manifest, w: &World) -> Result<Layout> {
    let mp = dir.join(RANK_DIR).join(MANIFEST);
    let layout = Layout::with_bounds(&w.site, m.col_bounds.clone(), m.row_bounds.clone()).map_err(|e| Error::format(&mp, format!("col_bounds, row_bounds: {e}")))?;
    if !m.same_layout(&layout) {
        return Err(Error::format(&mp, format!("col_bounds {:?}, row_bounds {:?}: not the {} × {} tiles they bound", m.col_bounds, m.row_bounds, m.tiles_across, m.tiles_up)).into());
    }
    Ok(layout)
}

/// Reads the checkpoint of `dir` ([`find`]) into `w`: `checkpoint.bin`, or the per-rank
/// checkpoints assembled ([`load_ranks`]); returns the stand table so far.
///
/// Errors: as [`load`] and [`load_ranks`]; [`Error::Format`] naming `checkpoint.bin` when
/// there is no checkpoint.
pub fn load_any(dir: &Path, w: &mut World) -> Result<Vec<StandRow>> {
    match find(dir)? {
        Found::None => Err(Error::format(dir.join(FILE), "--resume: no checkpoint in the run directory").into()),
        Found::Single(p) => load(&p, w),
        Found::Ranks(m) => load_ranks(dir, &m, w),
    }
}

/// Which files of a checkpoint of the tiles `old` tile `me` of the run's layout `new` reads to
/// resume per rank (issue 37 Build 1, round 37; [`load_overlapping`]): the old tiles whose
/// rectangle of light cells overlaps tile `me`'s (every tree and cohort of its cells is in one
/// of them: a tree belongs to the tile of its light cell), and, for any seed cell of its
/// windows of the seed grids `grids` ([`crate::sim::tiles::seed_window`]; one cell of margin
/// beyond its rectangle) that none of those old tiles' windows holds, the old tile owning the
/// cell's centre (it holds the cell: [`crate::sim::tiles::seed_window`]). Old tile indices,
/// ascending. `old` and `new` cut the same light grid.
pub fn files_to_read(old: &Layout, new: &Layout, me: usize, grids: &[crate::sim::world::SeedGrid]) -> Vec<usize> {
    let r = new.rect(me);
    let mut read: Vec<bool> = (0..old.len())
        .map(|k| {
            let o = old.rect(k);
            o.col0 < r.col1 && r.col0 < o.col1 && o.row0 < r.row1 && r.row0 < o.row1
        })
        .collect();
    for g in grids {
        let wins: Vec<_> = (0..old.len()).map(|k| crate::sim::tiles::seed_window(old, k, g)).collect();
        for cell in crate::sim::tiles::seed_window(new, me, g).cells(g.cols) {
            let (c, row) = (cell % g.cols, cell / g.cols);
            if (0..old.len()).any(|k| read[k] && wins[k].contains(c, row)) {
                continue;
            }
            let (x, y) = (((c as f64 + 0.5) * g.cell_m) as f32, ((row as f64 + 0.5) * g.cell_m) as f32);
            read[old.owner_of(x, y)] = true;
        }
    }
    (0..old.len()).filter(|&k| read[k]).collect()
}

/// What tile `me` read of a checkpoint to resume per rank ([`load_overlapping`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Overlap {
    /// The stand table so far: the rows of old tile 0's file when read (new tile 0 always
    /// reads it: both hold light cell (0, 0)), else none.
    pub rows: Vec<StandRow>,
    /// The old tiles whose files were read ([`files_to_read`]), ascending.
    pub read: Vec<usize>,
    /// The next tree id of old tile 0's file when read ([`crate::sim::TreeStore::next_id`]:
    /// the run's, as an assembled checkpoint takes it).
    pub next_id: Option<u64>,
}

/// Reads into `w`, the world of tile `me` of the layout `new` (its tile's site, seed grids cut
/// to its windows, no trees), its part of the checkpoint of a run cut as `old` whose tile `k`
/// was saved to `paths[k]` (per-rank checkpoints of one `year`, or one process's
/// `checkpoint.bin` as the one tile of a 1 × 1 layout with `year` `None`): only the files
/// [`files_to_read`] names, one at a time, each checked as [`load`] checks it. It keeps what
/// [`load_ranks`] then [`crate::sim::tiles::Tile::parts`] would give the tile, without the
/// world of one process on any rank (issue 37 Build 1, round 37): the trees whose light cell
/// is the tile's (merged by id), the cohorts of its light cells (in (cell, pool) order), every
/// seed cell of its windows (from the old tile owning the cell's centre when read, else from
/// the first read file whose window holds it: every tile recomputes its whole window each year
/// from the whole site's production, so the values are the same bits), and the tallies (deaths
/// by cause, the regeneration ledger) of the old files assigned to it, each old tile `k` to the
/// new tile owning `k`'s first light cell (which reads it): summed over the new tiles they are
/// the run's, as [`crate::sim::tiles::assemble`] adds them. The year is the checkpoint's; this
/// year's dead and regeneration counts are cleared. The next tree id is left to the caller
/// ([`Overlap::next_id`]).
///
/// Errors: as [`load`] for each file read, naming it; [`Error::Format`] naming a file whose
/// year is not `year` (or not the first file's), and [`Error::Invalid`] when `paths` has not
/// one file per tile of `old`.
pub fn load_overlapping(paths: &[PathBuf], year: Option<u32>, old: &Layout, new: &Layout, me: usize, w: &mut World) -> Result<Overlap> {
    use crate::sim::cohorts::{Cohorts, RegenLedger};
    if paths.len() != old.len() {
        return Err(Error::Invalid { context: "resume per rank".into(), field: "checkpoint files".into(), value: paths.len().to_string(), expected: format!("{} (one per tile of the checkpoint's {} × {} tiles)", old.len(), old.nx, old.ny) }.into());
    }
    let read = files_to_read(old, new, me, &w.stand.seeds);
    let mut mine = std::mem::take(&mut w.stand.seeds);
    // per seed cell of the windows: 0 not yet read, 1 from a file whose window holds it, 2 from
    // the file of the tile owning its centre
    let mut got: Vec<Vec<u8>> = mine.iter().map(|g| vec![0u8; g.data.len()]).collect();
    let np = w.site.pool.len();
    let (mut deaths, mut ledger) = ([0u64; crate::sim::trees::N_CAUSES], RegenLedger::new(np));
    let (mut parts, mut cohorts) = (Vec::with_capacity(read.len()), Vec::new());
    let mut out = Overlap { rows: Vec::new(), read: read.clone(), next_id: None };
    let mut year = year;
    for &k in &read {
        let p = &paths[k];
        // the file's seed grids are old tile k's windows
        w.stand.seeds = mine.iter().map(|g| {
            let r = crate::sim::tiles::seed_window(old, k, g);
            crate::sim::world::SeedGrid { cell_m: g.cell_m, block: g.block, cols: g.cols, rows: g.rows, held: r, data: vec![0.0; r.len()] }
        }).collect();
        let rows = load(p, w)?;
        match year {
            Some(y) if y != w.stand.year => return Err(Error::format(p, format!("year {} in a checkpoint whose manifest (or first file) says year {y}", w.stand.year)).into()),
            _ => year = Some(w.stand.year),
        }
        if k == 0 {
            out.rows = rows;
            out.next_id = Some(w.stand.trees.next_id);
        }
        let mut t = std::mem::take(&mut w.stand.trees);
        let keep: Vec<bool> = (0..t.len()).map(|i| new.owner_of(t.x[i], t.y[i]) == me).collect();
        t.retain(&keep);
        parts.push(t);
        let c = std::mem::take(&mut w.stand.cohorts);
        for i in 0..c.len() {
            let (col, row) = new.light.col_row(c.cell[i] as usize);
            if new.owner_of_cell(col, row) == me {
                cohorts.push(c.get(i));
            }
        }
        for ((g, s), state) in mine.iter_mut().zip(&w.stand.seeds).zip(got.iter_mut()) {
            for (j, cell) in g.held.cells(g.cols).enumerate() {
                let (c, row) = (cell % g.cols, cell / g.cols);
                if state[j] == 2 || !s.held.contains(c, row) {
                    continue;
                }
                let (x, y) = (((c as f64 + 0.5) * g.cell_m) as f32, ((row as f64 + 0.5) * g.cell_m) as f32);
                let centre = old.owner_of(x, y) == k;
                if centre || state[j] == 0 {
                    g.data[j] = s.data[(row - s.held.row0) * (s.held.col1 - s.held.col0) + (c - s.held.col0)];
                    state[j] = if centre { 2 } else { 1 };
                }
            }
        }
        let first = old.rect(k);
        if new.owner_of_cell(first.col0, first.row0) == me {
            for (a, b) in deaths.iter_mut().zip(w.tallies.deaths_total) {
                *a += b;
            }
            let l = &w.tallies.regen_ledger;
            for q in 0..np.min(l.germinated.len()) {
                ledger.germinated[q] += l.germinated[q];
                ledger.recruited[q] += l.recruited[q];
                for (a, b) in ledger.dead[q].iter_mut().zip(l.dead[q]) {
                    *a += b;
                }
            }
        }
    }
    if let Some((p, _)) = got.iter().enumerate().find(|(_, s)| s.contains(&0)) {
        // cannot happen: files_to_read adds the owner of every cell no other file holds
        return Err(Error::Invalid { context: "resume per rank".into(), field: format!("seed grid of pool species {p}"), value: format!("tile {me}'s window {:?}", mine[p].held), expected: "every cell held by a checkpoint file read".into() }.into());
    }
    w.stand.seeds = mine;
    let next = w.stand.trees.next_id;
    w.stand.trees = crate::sim::TreeStore::merge_by_id(&parts, next).0;
    cohorts.sort_unstable_by_key(|c| (c.cell, c.pool));
    let mut c = Cohorts::default();
    for x in cohorts {
        c.push(x);
    }
    w.stand.cohorts = c;
    w.stand.year = year.unwrap_or(w.stand.year);
    w.tallies.deaths_total = deaths;
    w.tallies.regen_ledger = ledger;
    w.scratch.dead.clear();
    w.scratch.regen_year = Default::default();
    Ok(out)
}
