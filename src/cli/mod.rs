//! Subcommands of the `sylva` binary, one module per area.

pub mod export;
pub mod render;
pub mod run;
pub mod simulate;
pub mod species;
pub mod terrain;
pub mod tree;
pub mod view;

use sylva::sim::Scenario;

/// Sets up `tracing` to stderr: warnings by default, `-v` info, `-vv` debug; `RUST_LOG` wins.
pub fn init_logging(verbose: u8) {
    let level = match verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    // wgpu probes OpenGL/EGL too; on a headless machine that probe fails loudly although the
    // Vulkan (lavapipe) adapter works, so its messages are silenced unless RUST_LOG asks.
    let filter = tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(format!("{level},wgpu_hal::gles=off")));
    quiet_mesa_runtime_dir();
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let _ = tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).with_ansi(ansi).try_init();
}

/// A run stopped by Ctrl-C (or SIGTERM/SIGHUP, e.g. `timeout` or a closed terminal) after a
/// complete year, its outputs so far intact and no temporary file left: `sylva` exits with
/// status 130 (128 + SIGINT, the shell convention) so scripts can tell it from a finished run.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// A progress bar in Sylva's style (hidden when stderr is not a terminal or in tests).
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(len);
    let style = indicatif::ProgressStyle::with_template("{spinner} {prefix:>12} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> ");
    pb.set_style(style);
    pb.set_prefix(what.to_string());
    pb
}

/// Refuses a run directory argument (`what`: the command) that does not exist, is a file,
/// holds no `scenario.toml`, one that does not parse ([`Scenario::load`]) or no
/// `inventory/` folder, before it is read as a run (a missing folder was called "not a
/// Sylva run directory", round 30's trial; a folder without a scenario got an OS error from
/// `render` and `timelapse` and a different message from `export`, round 31's).
pub fn check_run_dir(dir: &std::path::Path, what: &str) -> anyhow::Result<()> {
    if !dir.exists() {
        anyhow::bail!("{what}: {}: no such folder (expected a run directory: the --out of `sylva run` or `sylva simulate`)", dir.display());
    }
    if !dir.is_dir() {
        anyhow::bail!("{what}: {} is a file, not a run directory (the --out folder of `sylva run` or `sylva simulate`)", dir.display());
    }
    if !dir.join("scenario.toml").is_file() {
        anyhow::bail!("{what}: {}: not a Sylva run directory (no scenario.toml; expected the --out folder of `sylva run` or `sylva simulate`)", dir.display());
    }
    // a scenario that does not parse is named with its error (round 33's trial: a garbage
    // scenario.toml got "no inventory snapshot for year 150 (years with an inventory: )")
    if let Err(e) = Scenario::load(&dir.join("scenario.toml")) {
        anyhow::bail!("{what}: {}: not a Sylva run directory (its scenario.toml does not parse: {e}; expected the scenario.toml that `sylva run` or `sylva simulate` writes)", dir.display());
    }
    // round 33's trial: a folder with only scenario.toml got "fake1/inventory: No such file or
    // directory (os error 2)"
    if !dir.join("inventory").is_dir() {
        anyhow::bail!("{what}: {}: not a Sylva run directory (no inventory/ folder; expected the --out folder of `sylva run` or `sylva simulate`, which writes the trees there)", dir.display());
    }
    Ok(())
}

/// Progress as plain lines where stderr is not a terminal (a log, `nohup`, CI), where the
/// bars of [`progress`] are not drawn: `what: done/total msg` for each item when `total` ≤ 20,
/// else at every tenth of `total` passed from 3 s after the process's first progress report on
/// (a short run says nothing) (`last` keeps the item or tenth said last; start it at 0).
/// Nothing on a terminal.
pub fn plain_progress(what: &str, done: u64, total: u64, last: &mut u64, msg: &str) {
    use std::io::IsTerminal;
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    let t0 = *START.get_or_init(std::time::Instant::now);
    if total == 0 || std::io::stderr().is_terminal() {
        return;
    }
    // at most 20 items: each one (by tenths, 12 stills were said as 2, 3, 4, 5, 6, 8, …;
    // trial 36); more: each tenth
    let step = if total <= 20 { done.min(total) } else { done.min(total) * 10 / total };
    if step > *last && (total <= 20 || t0.elapsed().as_secs_f64() >= 3.0) {
        *last = step;
        eprintln!("  {what}: {done}/{total} {msg}");
    }
}

/// Mesa prints "XDG_RUNTIME_DIR is invalid or not set" on headless machines; give it a private
/// folder (mode 0700) in the temporary directory when the variable is missing.
fn quiet_mesa_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    let dir = std::env::temp_dir().join("sylva-xdg-runtime");
    if std::fs::create_dir_all(&dir).is_ok() {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
        }
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}

/// Checks a `--stats FILE.json` path before any work: not a folder. A missing folder is made
/// when the figures are written ([`write_stats`]), as `--out`'s is.
///
/// Errors: naming `--stats` and the path.
pub fn check_stats_path(p: &std::path::Path) -> anyhow::Result<()> {
    anyhow::ensure!(!p.is_dir(), "--stats {}: is a folder; expected a .json file name", p.display());
    check_out_file(p, "--stats")
}

/// Checks before any work that the output file `p` of option `option` (e.g. `--out`) can be
/// written: not a folder, its folder (when it exists) a folder that takes a new file (a
/// temporary file made there and removed). A missing folder is left to the writer, which makes
/// it. Temporaries of this file that a killed earlier write left are removed
/// ([`sylva::output::remove_stale_temporaries_of`]).
///
/// Errors: naming the option, the path and what is wrong.
pub fn check_out_file(p: &std::path::Path, option: &str) -> anyhow::Result<()> {
    anyhow::ensure!(!p.is_dir(), "{option} {}: is a folder; expected a file name", p.display());
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    if dir.exists() {
        anyhow::ensure!(dir.is_dir(), "{option} {}: {} is a file, not a folder", p.display(), dir.display());
        sylva::job::run::check_writable(dir).map_err(|e| anyhow::anyhow!("{option} {}: cannot write into the folder {}: {e}", p.display(), dir.display()))?;
        // what an earlier, killed write of this file left beside it
        sylva::output::remove_stale_temporaries_of(p)?;
    }
    Ok(())
}

/// Checks before any work that the output folder `p` of option `option` (e.g. `--out` of a
/// run) can be made or written: not a file, and its nearest existing ancestor a folder that
/// takes a new file (a temporary file made there and removed). The folder itself is left to
/// the run, which makes it.
///
/// Errors: naming the option, the path and what is wrong (a trial got `base.toml/sub/species:
/// Not a directory`, naming neither the option nor the file in the way).
pub fn check_out_dir(p: &std::path::Path, option: &str) -> anyhow::Result<()> {
    anyhow::ensure!(!p.exists() || p.is_dir(), "{option} {}: is a file; expected a folder", p.display());
    // the run's own folders in it must be folders (round 32's trial: a file `inventory` gave
    // "File exists (os error 17)" after `species/` had been written)
    for sub in ["species", "inventory", "maps", "stills", "frames", "checkpoint"] {
        let q = p.join(sub);
        anyhow::ensure!(!q.exists() || q.is_dir(), "{option} {}: {} is a file where the run writes its folder {sub}/; move or rename it, or use another {option}", p.display(), q.display());
    }
    let mut dir = p;
    while !dir.exists() {
        match dir.parent() {
            Some(up) if !up.as_os_str().is_empty() => dir = up,
            _ => return Ok(()),
        }
    }
    anyhow::ensure!(dir.is_dir(), "{option} {}: {} is a file, not a folder", p.display(), dir.display());
    sylva::job::run::check_writable(dir).map_err(|e| anyhow::anyhow!("{option} {}: cannot write into the folder {}: {e}", p.display(), dir.display()))
}

/// An exclusive lock on a run folder, held while a run (`sylva simulate`, `sylva run`) writes
/// into it ([`lock_run_dir`]); let go when dropped, and by the system when the process ends in
/// any way (a killed run leaves no stale lock). Folders the lock made for the run are removed
/// again when they are still empty (a run refused before it wrote anything leaves nothing).
pub struct RunDirLock {
    _dir: Option<std::fs::File>,
    /// Folders made by [`lock_run_dir`], outermost first.
    made: Vec<std::path::PathBuf>,
}

impl Drop for RunDirLock {
    fn drop(&mut self) {
        for d in self.made.iter().rev() {
            // only while empty: remove_dir refuses a folder with anything in it
            let _ = std::fs::remove_dir(d);
        }
    }
}

/// The MPI rank this process has under `mpirun`, read from the environment before MPI starts
/// (Open MPI's and MPICH/PMI's variables); `None` outside `mpirun`.
pub fn mpi_rank_from_env() -> Option<String> {
    ["OMPI_COMM_WORLD_RANK", "PMI_RANK"].iter().find_map(|k| std::env::var(k).ok()).map(|r| r.trim().to_string())
}

/// The number of processes an MPI launcher started together with this one, read from the
/// environment before MPI starts: Open MPI's `OMPI_COMM_WORLD_SIZE`, MPICH/Hydra's (and
/// Slurm PMI's) `PMI_SIZE`, Slurm's `SLURM_NTASKS` only where a `PMI_*` variable shows that
/// `srun` started the tasks as MPI ranks (a batch script's own `SLURM_NTASKS` alone is not a
/// launch), and PMIx's `PMIX_RANK` (which names no size: a rank above 0 means at least
/// rank + 1 processes). Returns the size and the variable it came from; `None` outside a launcher
/// or where the size is unknown.
pub fn mpi_world_size_from_env() -> Option<(u64, String)> {
    let num = |k: &str| std::env::var(k).ok().and_then(|v| v.trim().parse::<u64>().ok());
    for k in ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"] {
        if let Some(n) = num(k) {
            return Some((n, format!("{k}={n}")));
        }
    }
    if std::env::vars_os().any(|(k, _)| k.to_str().is_some_and(|k| k.starts_with("PMI_"))) {
        if let Some(n) = num("SLURM_NTASKS") {
            return Some((n, format!("SLURM_NTASKS={n}")));
        }
    }
    num("PMIX_RANK").filter(|&r| r > 0).map(|r| (r + 1, format!("PMIX_RANK={r}")))
}

/// Refuses to start `command` under an MPI launcher (`mpirun`, `mpiexec`, `srun`) of more than
/// one process when this binary was built without the cargo feature `mpi`: every rank would
/// simulate the whole scenario into the same folder (round 34's trial: rc 0, twice the CPU,
/// and rank 0 said it replaced an earlier run that was rank 1's, being written). A build with
/// the feature runs the ranks of `sylva simulate` as the tiles of one run and passes;
/// `sylva run` (`over_mpi` false) runs in one process in any build and is refused too.
///
/// Errors: the launcher's size is above 1 in a build without `mpi`, or for a command that does
/// not run over MPI (saying how to run instead).
pub fn refuse_mpi_launch(command: &str, over_mpi: bool) -> anyhow::Result<()> {
    let Some((n, var)) = mpi_world_size_from_env().filter(|(n, _)| *n > 1) else {
        return Ok(());
    };
    if !over_mpi {
        anyhow::bail!(
            "sylva {command}: started by an MPI launcher with {n} processes ({var}), but `sylva {command}` runs in one process: each would run the whole job into the same folder. \
             Run it without mpirun, or simulate over MPI with `mpirun -np N sylva simulate SCENARIO --out DIR` (a build with `--features mpi`) and draw the pictures with `sylva render DIR` and `sylva timelapse DIR`"
        );
    }
    match cfg!(feature = "mpi") {
        false => anyhow::bail!(
            "sylva {command}: started by an MPI launcher with {n} processes ({var}), but this sylva was built without the `mpi` feature: \
             each process would run the whole scenario into the same folder. Rebuild with `cargo build --release --features mpi` (needs Open MPI: docs/guide.md, 'Regional runs over MPI') \
             to run the processes as the tiles of one run, run `sylva {command}` without mpirun, or split the site into tiles in one process with `--tiles N`"
        ),
        true => Ok(()),
    }
}

/// Locks the run folder `out` (made when missing) for this run: a second `sylva simulate` or
/// `sylva run` into the same folder while this one writes is refused, rather than mixing the
/// two runs' files (round 32's trial: two runs into one `--out` both ended well, the folder
/// holding one's scenario and the other's stand table and checkpoint). An advisory `flock` on
/// the folder itself (Linux and other Unix; no file is added to the run). The ranks of an
/// `mpirun` of a build with the `mpi` feature write one run together: rank 0 holds the lock,
/// the others take none.
///
/// Errors: the folder cannot be made or opened, or another process holds its lock for more
/// than 2 s (naming `option` and the folder).
pub fn lock_run_dir(out: &std::path::Path, option: &str) -> anyhow::Result<RunDirLock> {
    let mut made = Vec::new();
    let mut missing = Vec::new();
    let mut d = out;
    while !d.as_os_str().is_empty() && !d.exists() {
        missing.push(d.to_path_buf());
        d = d.parent().unwrap_or(std::path::Path::new(""));
    }
    for m in missing.into_iter().rev() {
        match std::fs::create_dir(&m) {
            Ok(()) => made.push(m),
            // made meanwhile by another process: the ranks of one `mpirun` start together
            // (round 33's CI: rank 1 lost the race to rank 0 and stopped the run)
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && m.is_dir() => {}
            Err(e) => anyhow::bail!("{option} {}: cannot make the folder {}: {e}", out.display(), m.display()),
        }
    }
    let mut lock = RunDirLock { _dir: None, made };
    // only a build with MPI runs its ranks together (one without refuses an `mpirun` of more
    // than one process: `refuse_mpi_launch`)
    if cfg!(feature = "mpi") && mpi_rank_from_env().is_some_and(|r| r != "0") {
        return Ok(lock);
    }
    #[cfg(unix)]
    {
        use std::os::unix::io::AsRawFd;
        let f = std::fs::File::open(out).map_err(|e| anyhow::anyhow!("{option} {}: cannot open the folder: {e}", out.display()))?;
        // A lock held only for a moment is waited for (up to LOCK_WAIT): a process forked by
        // another thread of the program that started this run holds a copy of every descriptor
        // until its exec (close-on-exec), so a lock just released can still look held for some
        // milliseconds on a loaded machine (CI's 2 cores at load 13 saw it: round 33).
        const LOCK_WAIT: std::time::Duration = std::time::Duration::from_secs(2);
        let start = std::time::Instant::now();
        // SAFETY: flock on a file descriptor this function owns (open until the guard drops).
        while unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let e = std::io::Error::last_os_error();
            if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
                if start.elapsed() < LOCK_WAIT {
                    std::thread::sleep(std::time::Duration::from_millis(50));
                    continue;
                }
                anyhow::bail!("{option} {}: another Sylva run is writing into this folder; wait until it ends, or use another {option}", out.display());
            }
            anyhow::bail!("{option} {}: cannot lock the folder for this run: {e}", out.display());
        }
        lock._dir = Some(f);
    }
    Ok(lock)
}

/// Writes the `--stats` figures `json` to `p` whole (a temporary file renamed), making its
/// folder first when missing.
///
/// Errors: the folder cannot be made or the file written (naming the path).
pub fn write_stats(p: &std::path::Path, json: &serde_json::Value) -> anyhow::Result<()> {
    if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("--stats {}: cannot make its folder {}: {e}", p.display(), dir.display()))?;
    }
    sylva::output::write_atomic(p, serde_json::to_string_pretty(json)?.as_bytes())?;
    Ok(())
}
