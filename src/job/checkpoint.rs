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
