//! Terrain benchmark: a generated N × N grid (default 4096, env `SYLVA_BENCH_SIZE`) through
//! every field and the TIN, with the time of each stage; then `gdaldem slope` on the same grid
//! (written as GeoTIFF) for comparison. Prints the figures; see BENCHMARKS.md.
use std::time::Instant;
use sylva::conditions::{self, Climate};
use sylva::terrain::{fields, generate, tin::Tin};

fn main() {
    let n: usize = std::env::var("SYLVA_BENCH_SIZE").ok().and_then(|s| s.parse().ok()).unwrap_or(4096);
    let tol: f64 = std::env::var("SYLVA_BENCH_TIN_TOL").ok().and_then(|s| s.parse().ok()).unwrap_or(5.0);
    println!("terrain bench: {n} x {n} cells, 10 m, relief 1500 m, {} rayon threads", rayon::current_num_threads());
    let all = Instant::now();
    let stage = |name: &str, t: Instant| println!("{name:<28} {:>8.3} s", t.elapsed().as_secs_f64());
    let t0 = Instant::now();
    let t = generate::generate(n, 10.0, 1500.0, 42).expect("generate");
    stage("generate (fBm + ridged)", t0);
    let climate = Climate::default();
    let fields_start = Instant::now();
    let t0 = Instant::now();
    let m = fields::mask(&t, climate.sea_level_m);
    let (slope, _aspect) = fields::slope_aspect(&t, &m);
    stage("slope + aspect (Horn)", t0);
    let t0 = Instant::now();
    let filled = fields::fill_depressions(&t, &m);
    stage("priority-flood fill", t0);
    let t0 = Instant::now();
    let dir = fields::flow_directions(&filled, &t.geo, &m);
    let acc = fields::flow_accumulation(&dir, &m);
    stage("D8 flow accumulation", t0);
    let t0 = Instant::now();
    let twi = fields::twi(&acc, &slope, &t.geo, &m);
    stage("TWI", t0);
    let t0 = Instant::now();
    let p = fields::SkyParams::default();
    let (ins, _wind) = fields::insolation_and_wind(&t, &m, climate.latitude_deg, climate.wind_from_deg as f64, &p);
    stage("insolation + wind (horizons)", t0);
    let t0 = Instant::now();
    let temp = fields::temperature(&t, &m, &climate);
    stage("temperature", t0);
    let t0 = Instant::now();
    let _hs = fields::hillshade(&t, &m, 315.0, 45.0);
    stage("hillshade", t0);
    let sequential_fields = fields_start.elapsed().as_secs_f64();
    println!("{:<28} {:>8.3} s", "sum of the stages above", sequential_fields);
    // What Sylva runs: fields::compute overlaps its independent branches (the sequential
    // depression filling runs beside the parallel per-cell fields).
    let t0 = Instant::now();
    let f = fields::compute(&t, &climate, &|_| {}).expect("compute");
    let compute_s = t0.elapsed().as_secs_f64();
    println!("{:<28} {:>8.3} s", "fields::compute (all)", compute_s);
    let t0 = Instant::now();
    let s = conditions::from_fields(&t, &climate, f);
    stage("Ellenberg indices", t0);
    let t0 = Instant::now();
    let tin = Tin::build(&t, tol, usize::MAX).expect("tin");
    let tin_s = t0.elapsed().as_secs_f64();
    println!("{:<28} {:>8.3} s", format!("TIN tol {tol} m"), tin_s);
    println!("  TIN: {} vertices, {} triangles, max error {:.3} m", tin.num_vertices(), tin.num_triangles(), tin.max_error_m);
    println!("{:<28} {:>8.3} s", "all fields + TIN", compute_s + tin_s);
    println!("{:<28} {:>8.3} s", "total (incl. generate)", all.elapsed().as_secs_f64());
    let _ = (twi.len(), ins.len(), temp.len(), s.width());

    let dir = std::env::temp_dir().join(format!("sylva_bench_terrain_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let dem = dir.join("dem.tif");
    sylva::output::geotiff::write_f32(&dem, &t.elevation, &t.geo).expect("write dem");
    let t0 = Instant::now();
    match std::process::Command::new("gdaldem").args(["slope", "-q"]).arg(&dem).arg(dir.join("slope.tif")).status() {
        Ok(st) if st.success() => stage("gdaldem slope (same grid)", t0),
        Ok(st) => println!("gdaldem slope failed: {st}"),
        Err(_) => println!("gdaldem slope: skipped (gdaldem not found)"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}
