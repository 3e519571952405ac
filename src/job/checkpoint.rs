//! Checkpoint files of a run directory (`checkpoint.bin`): the simulation encodes and decodes
//! its state ([`crate::sim::checkpoint`]); this shell reads and writes the file.

use super::Result;
use crate::Error;
use crate::sim::checkpoint::{restore, to_bytes};
use crate::sim::stats::StandRow;
use crate::sim::World;
use std::path::Path;

/// Writes a checkpoint of `w` and the stand table `rows` to `path` atomically (temporary file
/// + rename).
///
/// Errors: [`crate::output::OutputError::Io`] naming the file.
pub fn save(path: &Path, w: &World, rows: &[StandRow]) -> Result<()> {
    Ok(crate::output::write_atomic(path, &to_bytes(w, rows))?)
}

/// Reads the checkpoint file `path` into `w`; returns the stand table so far.
///
/// Errors: [`Error::Io`] when the file cannot be read; [`Error::Format`] naming the file when it
/// is not a checkpoint of this layout or does not match the scenario.
pub fn load(path: &Path, w: &mut World) -> Result<Vec<StandRow>> {
    let b = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(restore(w, &b, path)?)
}
