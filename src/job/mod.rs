//! The main job's glue (`sylva simulate`, `sylva run`, `sylva render`, `sylva timelapse`): the
//! run driver that steps the pure simulation and writes the run directory ([`run`],
//! [`checkpoint`]), and from a run directory or an in-memory world to pictures. The core
//! modules stay independent of each other and of the disk; this layer joins them.

mod error;
pub use error::{JobError, Result};

pub mod adapted;
pub mod checkpoint;
pub mod crown_cover;
pub mod disk;
pub mod export;
pub mod hemi;
pub mod hydrology_ranks;
pub mod inventory;
pub mod keyframes;
pub mod leaf_area;
pub mod main_job;
pub mod maps;
pub mod pictures;
pub mod run;
pub mod scene;
pub mod site_ranks;
pub mod tiled;
pub mod timing;
#[cfg(feature = "mpi")]
pub mod mpi_transport;
