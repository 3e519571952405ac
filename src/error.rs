//! Errors of the core (`grid`, `terrain`, `conditions`, `species`, `sim`, `structure`): reading
//! and validating inputs. One enum per layer (DESIGN.md: "thiserror enums per layer; anyhow only
//! in the binary"; "handle each error once"):
//! - [`Error`] here, the core's: I/O while reading, a malformed file, an invalid value, a grid
//!   too large, a document that cannot be serialised to TOML;
//! - [`crate::output::OutputError`], the output shell's: writing files (atomic writes' I/O),
//!   encoding PNG/GIF/MP4/GeoTIFF, serialising JSON/glTF, the bundled font;
//! - [`crate::render::RenderError`], the renderer's: adapter, device, GPU validation, readback;
//! - [`crate::job::JobError`], the main job's: wraps each of the above unchanged.
//!
//! A shell's enum wraps the core's (`Input(#[from] Error)`, shown unchanged) for an invalid
//! argument it checks; the core names none of the shells' types. Every variant names the file
//! (where there is one), the field or line, and what was expected, so that a user can fix the
//! input without reading code. The binary wraps these in `anyhow`.

use std::path::PathBuf;

/// Errors from reading and validating Sylva's inputs (the core's error).
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
    /// Serialising `what` (a scenario, a species) to `format` in memory failed.
    #[error("{what}: cannot write {format}: {message}")]
    Serialize {
        /// The object being written (names it).
        what: String,
        /// The target format (TOML).
        format: &'static str,
        /// What the serialiser said.
        message: String,
    },
    /// A message between the tiles of a tiled run ([`crate::sim::tiles`]) could not be passed
    /// or decoded.
    #[error("tile exchange with rank {peer}: {reason}")]
    Exchange {
        /// The other rank.
        peer: usize,
        /// What went wrong and what was expected.
        reason: String,
    },
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
