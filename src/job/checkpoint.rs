//! Checkpoint files of a run directory (`checkpoint.bin`): the simulation encodes and decodes
//! its state ([`crate::sim::checkpoint`]); this shell reads and writes the file.

use super::Result;
use crate::Error;
use crate::sim::checkpoint::{restore, write_to};
use crate::sim::stats::StandRow;
use crate::sim::World;
use std::path::Path;

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
