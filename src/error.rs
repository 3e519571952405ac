//! Error types of the library, one enum per layer (DESIGN.md: "handle each error once").
//!
//! Every variant names the file (where there is one), the field or line, and what was expected,
//! so that a user can fix the input without reading code. The binary wraps these in `anyhow`.

use std::path::PathBuf;

/// Errors from reading, validating or writing Sylva's inputs and outputs.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O error on `path`.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder involved.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file's contents are not what its format requires.
    #[error("{path}: {message}")]
    Format {
        /// The file involved.
        path: PathBuf,
        /// What is wrong and what was expected (names the field or line).
        message: String,
    },
    /// A value is outside its allowed range or otherwise invalid.
    #[error("{context}: field `{field}` = {value}: expected {expected}")]
    Invalid {
        /// File (and line) or object the value came from.
        context: String,
        /// Field name.
        field: String,
        /// The offending value, as text.
        value: String,
        /// The allowed range or form.
        expected: String,
    },
    /// A grid (or other allocation) larger than Sylva accepts, refused before allocating.
    #[error("{path}: grid of {width} x {height} cells is too large (limit {limit} cells)")]
    TooLarge {
        /// The file involved.
        path: PathBuf,
        /// Columns declared.
        width: u64,
        /// Rows declared.
        height: u64,
        /// Maximum number of cells accepted.
        limit: u64,
    },
    /// Encoding a picture or film (`format`: PNG, GIF, MP4) for `path` failed.
    #[error("{path}: {format} encoding failed: {message}")]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// The format being encoded.
        format: &'static str,
        /// What the encoder said.
        message: String,
    },
    /// Serialising `what` (a scenario, a species, a glTF document) to `format` failed.
    #[error("{what}: cannot write {format}: {message}")]
    Serialize {
        /// The object being written (names it).
        what: String,
        /// The target format (TOML, JSON, glTF).
        format: &'static str,
        /// What the serialiser said.
        message: String,
    },
    /// A resource compiled into the binary (e.g. the bundled font) cannot be used.
    #[error("bundled {what}: {message}")]
    Bundled {
        /// The resource.
        what: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// Rendering failed ([`RenderError`]: no adapter, device, GPU validation, readback).
    #[error("render: {0}")]
    Render(#[from] RenderError),
}

/// Errors of the render layer (`render`): the GPU side, independent of files and inputs.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// wgpu finds no adapter (neither a GPU nor a software adapter such as lavapipe).
    #[error("no adapter found (install a GPU driver or Mesa's lavapipe, Debian package mesa-vulkan-drivers): {0}")]
    NoAdapter(String),
    /// The adapter `adapter` refuses to create a device or a pipeline (`what`).
    #[error("cannot create {what} on {adapter}: {message}")]
    Create {
        /// What could not be created (device, pipeline).
        what: &'static str,
        /// The adapter's name.
        adapter: String,
        /// What wgpu said.
        message: String,
    },
    /// A wgpu validation error while drawing a frame.
    #[error("GPU validation error: {0}")]
    Validation(String),
    /// GPU culling was forced ([`crate::render::headless::Culling::Gpu`]) but cannot run.
    #[error("GPU culling forced but {0}")]
    GpuCullingUnavailable(String),
    /// Waiting for the GPU or reading a buffer back failed (`stage`: poll, map, range).
    #[error("readback ({stage}) failed: {message}")]
    Readback {
        /// Which step of the readback.
        stage: &'static str,
        /// What wgpu said.
        message: String,
    },
    /// An internal ordering invariant of the renderer was broken (a bug): `what` was missing.
    #[error("internal: {0} missing")]
    Internal(&'static str),
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
    /// A format error in `path`.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Format { path: path.into(), message: message.into() }
    }
}

/// Result alias of the library.
pub type Result<T> = std::result::Result<T, Error>;
