//! Command-line behaviour a script relies on: Ctrl-C ends a simulation with status 130 after a
//! complete year (outputs intact, resumable); a closed output pipe ends a command quietly.
use std::process::{Command, Stdio};

const LONG: &str = r#"
name = "long"
years = 1000
seed = 3
snapshot_every = 1
checkpoint_every = 1
species = ["beech"]
[terrain]
uniform = { width = 10, height = 10, cell_m = 20.0, elevation_m = 300.0, indices = [5, 5, 2, 5, 6, 6] }
[[start]]
kind = "planted"
species = "beech"
spacing_m = 2.0
age_yr = 10.0
"#;

#[test]
fn ctrl_c_stops_after_a_year_with_status_130_and_a_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("long.toml"), LONG).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["simulate", "long.toml", "--out", "run"]).current_dir(d).stderr(Stdio::piped()).spawn().unwrap();
    // wait until the simulation is under way (its Ctrl-C handler is installed before year 1)
    let marker = d.join("run/inventory/year_0002.csv");
    while !marker.exists() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be interrupted");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("--resume") && !err.contains("panicked"), "{err}");
    assert!(d.join("run/checkpoint.bin").exists());
    let table = std::fs::read_to_string(d.join("run/stand_table.csv")).unwrap();
    let years = table.lines().count() - 1;
    assert!((2..1000).contains(&years), "{years} rows");
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    let mut fds = [0i32; 2];
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // close the read end first: the first line the program prints meets a closed pipe
    unsafe {
        libc::close(fds[0]);
    }
    let write_end = unsafe { <std::os::fd::OwnedFd as std::os::fd::FromRawFd>::from_raw_fd(fds[1]) };
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["species", "list"]).stdout(Stdio::from(write_end)).stderr(Stdio::piped()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "ended by SIGPIPE like other Unix tools: {:?} {err}", out.status);
}

#[test]
fn terrain_options_refuse_nan_and_out_of_range_values() {
    for (opt, val, want) in [("--latitude", "nan", "-90 to 90"), ("--latitude", "200", "-90 to 90"), ("--sea-level", "nan", "finite"), ("--max-height", "inf", "finite")] {
        let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info", &format!("{opt}={val}")]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(opt) && err.contains(want), "{opt}={val}: {err}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(["terrain", "info", "--latitude", "-30.5", "--generate", "--size", "16"]).output().unwrap();
    let so = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && so.contains("latitude:    -30.500° (--latitude"), "{so}");
}
