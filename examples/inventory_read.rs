//! Reading speed of an inventory snapshot (issue 34 Build 4: `sylva render` should spend ≤ 2 s
//! reading): `cargo run --release --example inventory_read -- FILE [FILE...]` reads each file
//! (Parquet or CSV, by its name) three times with `sylva::job::inventory::read` and prints the
//! rows and the fastest wall time. `-- --run DIR --year N` times instead what `sylva render DIR
//! --year N` reads before it draws (the same calls, best of 3): the snapshot's trees
//! (`job::pictures::snapshot_rows`), its regeneration layer (`job::inventory::read_regeneration`)
//! and the stumps of the harvests of the 20 years before (`job::pictures::harvest_stumps`).
fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.len() == 4 && files[0] == "--run" && files[2] == "--year" {
        return render_reads(std::path::Path::new(&files[1]), files[3].parse().expect("a year"));
    }
    if files.is_empty() {
        eprintln!("usage: inventory_read FILE [FILE...] (inventory/year_NNNN.parquet or .csv), or --run DIR --year N");
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

/// The reads of `sylva render dir --year year`, timed (best of 3 each).
fn render_reads(dir: &std::path::Path, year: u32) {
    let best = |f: &mut dyn FnMut() -> usize| {
        let mut b = f64::INFINITY;
        let mut n = 0;
        for _ in 0..3 {
            let t = std::time::Instant::now();
            n = f();
            b = b.min(t.elapsed().as_secs_f64());
        }
        (n, b)
    };
    let (trees, a) = best(&mut || sylva::job::pictures::snapshot_rows(dir, year).unwrap().len());
    let (regen, b) = best(&mut || sylva::job::inventory::read_regeneration(dir, year).unwrap().map_or(0, |r| r.len()));
    let (stumps, c) = best(&mut || sylva::job::pictures::harvest_stumps(dir, year).unwrap().len());
    println!("| {} year {year} | trees {trees}: {a:.2} s | regeneration {regen}: {b:.2} s | stumps {stumps}: {c:.2} s | reading {:.2} s |", dir.display(), a + b + c);
}
