//! Writers for Sylva's artefacts: one module per format. Every writer writes to a temporary file
//! in the destination folder and renames it into place, so a reader never sees half a file.

mod error;
pub use error::{OutputError, Result};

pub mod inventory;
pub mod plot;
pub mod stand_table;

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
///
/// Errors: [`OutputError::Io`] naming `path` when the folder is missing or not writable.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], with a closure that streams into a buffered writer.
pub fn write_atomic_with(path: &Path, f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>) -> Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let res = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        f(&mut w)?;
        w.flush()?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = res {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::io(path, e));
    }
    Ok(())
}

pub mod gltf;
pub mod obj;
pub mod geotiff;
pub mod maps;
pub mod pictures;
