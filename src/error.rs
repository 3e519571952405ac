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
    /// Rendering failed (no adapter, device lost, ...).
    #[error("render: {0}")]
    Render(String),
    /// Anything else, with a message that says what and where.
    #[error("{0}")]
    Other(String),
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
