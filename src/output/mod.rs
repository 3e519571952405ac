//! Writers for Sylva's artefacts: one module per format. Every writer writes to a temporary file
//! in the destination folder and renames it into place, so a reader never sees half a file.

mod error;
pub use error::{OutputError, Result};

pub mod georef;
pub mod gpkg;
pub mod inventory;
pub mod parquet;
pub mod plot;
pub mod schema;
pub mod stand_table;

use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
///
/// Errors: [`OutputError::Io`] naming `path` when the folder is missing or not writable, or
/// the disk is full (the temporary file is removed; an earlier file at `path` is kept whole).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// The temporary file [`write_atomic_with`] writes before renaming it to `path`:
/// `.<name>.<process id>.tmp` in the same folder.
pub fn temporary_path(path: &Path) -> PathBuf {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Like [`write_atomic`], with a closure that streams into a buffered writer.
///
/// The file is flushed and synced (`fsync`) before the rename, so after the rename it is whole
/// on disk; a process killed at any moment (SIGKILL included) leaves either the earlier file or
/// the new one at `path`, at worst a temporary file beside it, which
/// [`remove_stale_temporaries`] clears on the next run.
pub fn write_atomic_with(path: &Path, f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>) -> Result<()> {
    let tmp = temporary_path(path);
    let _pending = Pending::register(&tmp);
    let res = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        f(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        fault::maybe_kill(&file);
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = res {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::io(path, e));
    }
    Ok(())
}

/// The temporary files being written now ([`write_atomic_with`]), which
/// [`remove_pending_temporaries`] deletes when the process is stopped by a signal.
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary file listed in [`PENDING`] while it is written; unlisted when dropped.
struct Pending(PathBuf);

impl Pending {
    fn register(tmp: &Path) -> Pending {
        if let Ok(mut v) = PENDING.lock() {
            v.push(tmp.to_path_buf());
        }
        Pending(tmp.to_path_buf())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        if let Ok(mut v) = PENDING.lock() {
            if let Some(i) = v.iter().position(|p| *p == self.0) {
                v.swap_remove(i);
            }
        }
    }
}

/// Deletes the temporary files [`write_atomic_with`] is writing now. The commands that write
/// files without a stop flag of their own (`export`, `render`, `timelapse`, `tree`,
/// `terrain`) call it from their Ctrl-C / SIGTERM / SIGHUP handler before exiting, so that a
/// stopped export leaves neither a half-written output nor its hidden temporary (trial 35: a
/// SIGTERM during `sylva export --instances` left a 105 MB `.forest.glb.PID.tmp`).
pub fn remove_pending_temporaries() {
    if let Ok(v) = PENDING.lock() {
        for p in v.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// Finishes a file another library wrote at `tmp` (SQLite writes the GeoPackage through its
/// own file handle; [`temporary_path`] names `tmp`): syncs it (`fsync`) and renames it to
/// `path`, as [`write_atomic_with`] does, fault injection included.
///
/// Errors: the I/O error (the caller names `path` and removes `tmp`).
pub fn finish_temporary(tmp: &Path, path: &Path) -> std::io::Result<()> {
    let file = std::fs::OpenOptions::new().write(true).open(tmp)?;
    fault::maybe_kill(&file);
    file.sync_all()?;
    std::fs::rename(tmp, path)
}

/// Makes the entries of folder `dir` (files renamed into it) durable: `fsync` of the folder on
/// Unix, nothing elsewhere. The run driver calls it before each checkpoint, so that after a
/// power cut no output the checkpoint counts as written is missing.
///
/// Errors: [`OutputError::Io`] naming the folder.
pub fn sync_dir(dir: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        std::fs::File::open(dir).and_then(|d| d.sync_all()).map_err(|e| OutputError::io(dir, e))?;
    }
    let _ = dir;
    Ok(())
}

/// Whether process `pid` still runs (Unix: `kill(pid, 0)`; elsewhere assumed running, so
/// nothing is removed).
fn process_alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(p) = i32::try_from(pid) else { return false };
        // SAFETY: signal 0 only checks that the process exists; no signal is sent.
        let r = unsafe { libc::kill(p, 0) };
        r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes the temporary files `.<name>.<pid>.tmp` ([`temporary_path`]) that a killed process
/// left in `dir` (not those of this process or of a process still running); returns how many.
/// A missing folder has none.
///
/// Errors: [`OutputError::Io`] naming the folder or file that cannot be listed or removed.
pub fn remove_stale_temporaries(dir: &Path) -> Result<usize> {
    remove_stale_where(dir, |_| true)
}

/// [`remove_stale_temporaries`] for one output file `path`: only its own temporaries
/// `.<name>.<pid>.tmp` of processes no longer running (an export killed while writing left a
/// 207 MB hidden file beside its `--out`, found by a trial) and those of its glb buffer's
/// scratch file (`.<stem>.glb.bin.<pid>.tmp`, [`gltf::StandGlbWriter`]: trial 42 found 319 MB
/// of them left by an export killed with SIGKILL, which no rerun removed); other files are left
/// alone.
///
/// Errors: as [`remove_stale_temporaries`].
pub fn remove_stale_temporaries_of(path: &Path) -> Result<usize> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return Ok(0) };
    let scratch = gltf::glb_scratch_of(path).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    remove_stale_where(dir, |stem| stem == name || stem == scratch)
}

/// The temporaries of dead processes in `dir` whose file name (`stem` of `.<stem>.<pid>.tmp`)
/// `name_ok` accepts, removed.
fn remove_stale_where(dir: &Path, name_ok: impl Fn(&str) -> bool) -> Result<usize> {
    if !dir.is_dir() {
        return Ok(0);
    }
    let mut n = 0;
    for e in std::fs::read_dir(dir).map_err(|e| OutputError::io(dir, e))? {
        let e = e.map_err(|err| OutputError::io(dir, err))?;
        let name = e.file_name();
        let name = name.to_string_lossy();
        let Some(stem) = name.strip_prefix('.').and_then(|s| s.strip_suffix(".tmp")) else { continue };
        let Some((file, pid)) = stem.rsplit_once('.').and_then(|(f, p)| Some((f, p.parse::<u32>().ok()?))) else { continue };
        if !name_ok(file) || pid == std::process::id() || process_alive(pid) {
            continue;
        }
        let p = e.path();
        if p.is_file() {
            std::fs::remove_file(&p).map_err(|err| OutputError::io(&p, err))?;
            n += 1;
        }
    }
    Ok(n)
}

/// Fault injection for the fault tests (`tests/faults.rs`): with the environment variable
/// `SYLVA_FAULT_KILL_AT_WRITE=N`, the process kills itself with SIGKILL in its N-th atomic
/// write (counted from 1), after cutting the temporary file to half its length: exactly what a
/// kill in the middle of writing leaves behind. Unset (the normal case) it does nothing.
mod fault {
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::OnceLock;

    static AT: OnceLock<Option<u64>> = OnceLock::new();
    static COUNT: AtomicU64 = AtomicU64::new(0);

    static TERM_AT: OnceLock<Option<u64>> = OnceLock::new();

    pub(super) fn maybe_kill(file: &std::fs::File) {
        let term_at = *TERM_AT.get_or_init(|| std::env::var("SYLVA_FAULT_TERM_AT_WRITE").ok().and_then(|v| v.parse().ok()));
        let kill_at = *AT.get_or_init(|| std::env::var("SYLVA_FAULT_KILL_AT_WRITE").ok().and_then(|v| v.parse().ok()));
        if term_at.is_none() && kill_at.is_none() {
            return;
        }
        let n = COUNT.fetch_add(1, Ordering::SeqCst) + 1;
        // SIGTERM (catchable) at the N-th write: the stop handler must clear the temporary
        // (tests/cli_qa.rs); this thread waits for the handler to end the process
        if term_at == Some(n) {
            #[cfg(unix)]
            // SAFETY: raising a signal at this process.
            unsafe {
                libc::raise(libc::SIGTERM);
            }
            std::thread::sleep(std::time::Duration::from_secs(10));
        }
        if kill_at == Some(n) {
            let len = file.metadata().map(|m| m.len()).unwrap_or(0);
            let _ = file.set_len(len / 2);
            #[cfg(unix)]
            // SAFETY: raising a signal at this process; SIGKILL cannot be caught.
            unsafe {
                libc::raise(libc::SIGKILL);
            }
            std::process::abort();
        }
    }
}

pub mod gltf;
pub mod obj;
pub mod geotiff;
pub mod maps;
pub mod pictures;
pub mod tree_preview;

#[cfg(test)]
mod stale_tests {
    use super::*;

    /// Only the output file's own temporaries of dead processes go: not another file's, not
    /// this process's, not a user's file of another pattern.
    #[test]
    fn an_outputs_stale_temporaries_are_removed_and_nothing_else() {
        let d = std::env::temp_dir().join(format!("sylva_stale_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let dead = 4_000_000_000u32; // above any pid: no such process
        // and the glb buffer's scratch files (trial 42): a dead process's goes, this one's stays
        let files = [format!(".a.glb.{dead}.tmp"), format!(".b.glb.{dead}.tmp"), format!(".a.glb.{}.tmp", std::process::id()), "a.glb.tmp".into(), format!(".a.glb.{dead}.tmp.keep"), format!(".a.glb.bin.{dead}.tmp"), format!(".a.glb.bin.{}.tmp", std::process::id()), format!(".b.glb.bin.{dead}.tmp")];
        for f in &files {
            std::fs::write(d.join(f), b"x").unwrap();
        }
        assert_eq!(remove_stale_temporaries_of(&d.join("a.glb")).unwrap(), 2);
        let left: Vec<bool> = files.iter().map(|f| d.join(f).exists()).collect();
        assert_eq!(left, [false, true, true, true, true, false, true, true]);
        assert_eq!(remove_stale_temporaries(&d).unwrap(), 2, "the whole folder's: b's and its scratch");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
