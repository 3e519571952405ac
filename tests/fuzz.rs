//! Bounded fuzzing run (issue 16, Build 1): every reader gets its real seed files and a fixed
//! number of mutated and generated inputs; each must end in `Ok` or an error naming the file,
//! with no panic and no allocation over `ALLOC_LIMIT`. Longer runs:
//! `cargo run --release --example fuzz -- --seconds N --target T` (docs/RELIABILITY.md).
#[path = "common/fuzz.rs"]
mod fuzz;

#[global_allocator]
static ALLOC: fuzz::CountingAlloc = fuzz::CountingAlloc;

/// Executions per target in the suite (fixed, so the run is the same on every machine).
const EXECS: u64 = 2000;

/// Aborts the process when one target runs far longer than it should (a hang), naming it.
fn watchdog(target: &'static str) -> std::sync::mpsc::Sender<()> {
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    std::thread::spawn(move || {
        if let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(std::time::Duration::from_secs(300)) {
            eprintln!("fuzz target {target}: no end after 300 s (a hang)");
            std::process::abort();
        }
    });
    tx
}

fn check(target: &'static str, seed: u64) {
    let done = watchdog(target);
    let r = fuzz::fuzz(target, seed, EXECS, None);
    let _ = done.send(());
    eprintln!("{target}: {} executions, {} ok, {} named errors, {} defects, largest allocation {} B", r.executions, r.ok, r.named, r.defect_count, r.largest_alloc);
    assert_eq!(r.executions, EXECS);
    assert!(r.defects.is_empty(), "{target}: {} defects, first: {:?}", r.defect_count, r.defects.iter().map(|(m, i)| (m, i.len())).collect::<Vec<_>>());
    // the seeds are real files the reader accepts, and mutation refuses some inputs
    assert!(r.ok >= r.seeds as u64, "{target}: {} accepted, {} seeds", r.ok, r.seeds);
    assert!(r.named > 0, "{target}: no input was refused: the mutations do not reach the reader");
}

#[test]
fn fuzz_scenario() {
    check("scenario", 1);
}
#[test]
fn fuzz_species() {
    check("species", 2);
}
#[test]
fn fuzz_geotiff() {
    check("geotiff", 3);
}
#[test]
fn fuzz_asc() {
    check("asc", 4);
}
#[test]
fn fuzz_png() {
    check("png", 5);
}
#[test]
fn fuzz_checkpoint() {
    check("checkpoint", 6);
}
#[test]
fn fuzz_skeleton() {
    check("skeleton", 7);
}

/// The seeds are accepted one by one (so a defect in the harness cannot hide as "all refused").
#[test]
fn every_seed_is_accepted() {
    for t in fuzz::TARGETS {
        for (i, s) in fuzz::seeds(t).iter().enumerate() {
            assert_eq!(fuzz::run_one(t, s), fuzz::Outcome::Ok, "{t} seed {i}");
        }
    }
}
