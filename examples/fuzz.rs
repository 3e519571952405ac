//! Longer fuzzing runs than the suite's (issue 16): `cargo run --release --example fuzz --
//! --seconds N [--target T|all] [--seed S]`. Prints one line per target (executions, accepted,
//! refused with a named error, defects, largest allocation, slowest input) and writes each
//! defect's input to `target/fuzz-defects/TARGET_K.bin`. Targets: scenario, species, geotiff,
//! asc, png, checkpoint, skeleton. Figures go into docs/RELIABILITY.md.
#[path = "../tests/common/fuzz.rs"]
mod fuzz;

#[global_allocator]
static ALLOC: fuzz::CountingAlloc = fuzz::CountingAlloc;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str| args.iter().position(|a| a == k).and_then(|i| args.get(i + 1)).cloned();
    let seconds: f64 = get("--seconds").and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let seed: u64 = get("--seed").and_then(|s| s.parse().ok()).unwrap_or(1);
    let target = get("--target").unwrap_or_else(|| "all".into());
    let targets: Vec<&str> = if target == "all" { fuzz::TARGETS.to_vec() } else { fuzz::TARGETS.iter().copied().filter(|t| *t == target).collect() };
    if targets.is_empty() {
        eprintln!("--target {target}: expected one of {} or all", fuzz::TARGETS.join(", "));
        std::process::exit(2);
    }
    let per = std::time::Duration::from_secs_f64(seconds / targets.len() as f64);
    let mut bad = 0;
    println!("| target | seconds | executions | accepted | named error | defects | largest allocation (B) | slowest input (s) |");
    println!("|---|---|---|---|---|---|---|---|");
    for t in targets {
        let t0 = std::time::Instant::now();
        let r = fuzz::fuzz(t, seed, u64::MAX, Some(per));
        println!("| {t} | {:.0} | {} | {} | {} | {} | {} | {:.3} |", t0.elapsed().as_secs_f64(), r.executions, r.ok, r.named, r.defect_count, r.largest_alloc, r.slowest_s);
        for (k, (m, input)) in r.defects.iter().enumerate() {
            let p = std::path::Path::new("target/fuzz-defects").join(format!("{t}_{k}.bin"));
            let _ = std::fs::create_dir_all("target/fuzz-defects");
            let _ = std::fs::write(&p, input);
            eprintln!("  {t} defect {k}: {m} (input in {})", p.display());
        }
        bad += r.defect_count;
    }
    std::process::exit(if bad > 0 { 1 } else { 0 });
}
