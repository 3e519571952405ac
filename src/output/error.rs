//! Errors of the output shell (`output`): encoding pictures and films, serialising documents,
//! writing files atomically, the bundled font. An invalid argument or an input read back (a
//! skeleton sidecar) is the core's [`crate::Error`], wrapped unchanged in [`OutputError::Input`].

use std::path::PathBuf;

/// Errors from writing Sylva's artefacts (see [`crate::output`]).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An operating-system I/O error while writing `path` (temporary file, flush, rename).
    #[error("{path}: {source}")]
    Io {
        /// The file or folder being written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Encoding a picture or film (`format`: PNG, GIF, MP4, GeoTIFF) for `path` failed.
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
    /// An invalid argument (map style, frame sizes, empty LOD chain) or a file read back
    /// (skeleton sidecar): the core's error, message unchanged.
    #[error(transparent)]
    Input(#[from] crate::Error),
}

impl OutputError {
    /// An I/O error while writing `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        OutputError::Io { path: path.into(), source }
    }
}

/// Result alias of the output shell.
pub type Result<T> = std::result::Result<T, OutputError>;
