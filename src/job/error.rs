//! Errors of the job layer (`job`): each layer's error wrapped unchanged, so that a run, a
//! render or a checkpoint reports what the layer that failed said (file, field or line,
//! expected value).

use crate::output::OutputError;
use crate::render::RenderError;

/// Errors from the main job: reading inputs, writing the run directory, rendering.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// Reading or validating an input, or an invalid option (the core's [`crate::Error`]).
    #[error(transparent)]
    Input(#[from] crate::Error),
    /// Writing an artefact ([`OutputError`]: I/O, encoding, serialising, bundled font).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Rendering on the GPU ([`RenderError`]: no adapter, device, validation, readback).
    #[error("render: {0}")]
    Render(RenderError),
    /// The pictures phase of the main job stopped by its stop flag (Ctrl-C, SIGTERM): the
    /// simulation's outputs are complete in the run directory; the message says how to draw
    /// the pictures.
    // trial 46 D10: the run directory keeps the pictures' key frames and state until the last
    // picture, so the same `sylva run` again finishes them without simulating
    #[error("pictures stopped (Ctrl-C or SIGTERM): the simulation's outputs are complete in {out}; run the same `sylva run` (same scenario, --out and picture options) again to draw only the missing pictures without simulating again", out = .0.display())]
    Stopped(std::path::PathBuf),
    /// An error of a step of the main job under the step's name (e.g. "simulating NAME"), as
    /// the command line prints it: the step, then the cause.
    #[error("{what}")]
    Context {
        /// The step that failed.
        what: String,
        /// Its error.
        #[source]
        source: Box<JobError>,
    },
}

impl From<RenderError> for JobError {
    /// A render error; an invalid argument inside it is reported as the input error it is.
    fn from(e: RenderError) -> Self {
        match e {
            RenderError::Input(e) => JobError::Input(e),
            e => JobError::Render(e),
        }
    }
}

/// Result alias of the job layer.
pub type Result<T> = std::result::Result<T, JobError>;
