//! Compares two single-band rasters of one grid (GeoTIFF, ESRI ASCII) cell by cell, e.g. a
//! condition map (`sylva terrain maps --scenario S --out DIR`, `DIR/twi.tif`) before and after a
//! change: the valid cells (finite in both), how many differ and by how much, each raster's mean
//! and quantiles (5, 25, 50, 75, 95 %) over those cells. Round 34 (issue 37) summarises the
//! default Coweeta site's TWI before and after the order-independent fill and flat routing with
//! it.
//!
//! Command: `cargo run --example raster_diff -- BEFORE.tif AFTER.tif`.
use std::path::PathBuf;
use sylva::terrain::io;

fn quantiles(mut v: Vec<f32>) -> Vec<f32> {
    v.sort_by(f32::total_cmp);
    [0.05, 0.25, 0.5, 0.75, 0.95].iter().map(|q| v[((v.len() - 1) as f64 * q).round() as usize]).collect()
}

fn main() {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if args.len() != 2 {
        eprintln!("usage: raster_diff BEFORE AFTER (two rasters of one grid)");
        std::process::exit(2);
    }
    let (a, b) = (io::load(&args[0]).expect("BEFORE"), io::load(&args[1]).expect("AFTER"));
    let (a, b) = (&a.elevation, &b.elevation);
    if (a.width, a.height) != (b.width, b.height) {
        eprintln!("the rasters differ in size: {} x {} against {} x {}", a.width, a.height, b.width, b.height);
        std::process::exit(1);
    }
    let both: Vec<(f32, f32)> = a.data.iter().zip(&b.data).filter(|(x, y)| x.is_finite() && y.is_finite()).map(|(x, y)| (*x, *y)).collect();
    if both.is_empty() {
        eprintln!("no cell is valid in both rasters");
        std::process::exit(1);
    }
    let n = both.len();
    let diffs: Vec<f32> = both.iter().map(|(x, y)| y - x).filter(|d| *d != 0.0).collect();
    let mean = |f: &dyn Fn(&(f32, f32)) -> f32| both.iter().map(|p| f(p) as f64).sum::<f64>() / n as f64;
    println!("{} x {} cells, {n} valid in both; {} differ ({:.2} %)", a.width, a.height, diffs.len(), 100.0 * diffs.len() as f64 / n as f64);
    if !diffs.is_empty() {
        let up = diffs.iter().filter(|d| **d > 0.0).count();
        let max = diffs.iter().fold(0f32, |m, d| if d.abs() > m.abs() { *d } else { m });
        println!("  of those {up} higher, {} lower; mean change {:+.4}, largest {max:+.4}", diffs.len() - up, diffs.iter().map(|d| *d as f64).sum::<f64>() / diffs.len() as f64);
    }
    let qa = quantiles(both.iter().map(|p| p.0).collect());
    let qb = quantiles(both.iter().map(|p| p.1).collect());
    println!("  before: mean {:.4}, quantiles 5/25/50/75/95 % {qa:?}", mean(&|p| p.0));
    println!("  after:  mean {:.4}, quantiles 5/25/50/75/95 % {qb:?}", mean(&|p| p.1));
}
