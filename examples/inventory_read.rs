//! Reading speed of an inventory snapshot (issue 34 Build 4: `sylva render` should spend ≤ 2 s
//! reading): `cargo run --release --example inventory_read -- FILE [FILE...]` reads each file
//! (Parquet or CSV, by its name) three times with `sylva::job::inventory::read` and prints the
//! rows and the fastest wall time.
fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        eprintln!("usage: inventory_read FILE [FILE...] (inventory/year_NNNN.parquet or .csv)");
        std::process::exit(2);
    }
    println!("| file | bytes | rows | read s (best of 3) |\n|---|---|---|---|");
    for f in files {
        let path = std::path::Path::new(&f);
        let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        let mut best = f64::INFINITY;
        let mut rows = 0;
        for _ in 0..3 {
            let t = std::time::Instant::now();
            match sylva::job::inventory::read(path) {
                Ok(r) => rows = r.len(),
                Err(e) => {
                    eprintln!("{e}");
                    std::process::exit(1);
                }
            }
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!("| {f} | {bytes} | {rows} | {best:.2} |");
    }
}
