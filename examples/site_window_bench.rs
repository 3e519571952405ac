//! Site derivation per window (issue 37 Build 1): the CPU seconds of deriving a DEM's whole
//! site conditions (`conditions::derive`, as every rank did until round 25) against one band of
//! rows of `n` (`job::site_ranks::band`) read by window with its halo and derived with
//! `conditions::derive_window`, and of the hydrology fallback rank 0 computes for all bands
//! (`fields::hydrology_windows`). Checks every band against the whole site's, bit for bit.
//!
//! Command (BENCHMARKS.md round 25): `RAYON_NUM_THREADS=1 cargo run --release --example
//! site_window_bench -- [DEM.tif] [n]` (default: `terrains/coweeta_basin_10m_utm17n.tif`, 2).
use std::path::PathBuf;
use sylva::conditions::{self, Climate};
use sylva::grid::Window;
use sylva::terrain::{fields, io};

#[path = "../benches/common/mod.rs"]
mod common;
use common::cpu;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = PathBuf::from(args.get(1).cloned().unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/terrains/coweeta_basin_10m_utm17n.tif").into()));
    let n: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(2);
    let climate = Climate::default();
    let t0 = cpu();
    let t = io::load(&path).expect("DEM");
    let site = conditions::derive(&t, &climate).expect("site");
    let whole_s = cpu() - t0;
    let (w, h) = (site.width(), site.height());
    let m = fields::mask(&t, climate.sea_level_m);
    let bands: Vec<Window> = (0..n).map(|k| sylva::job::site_ranks::band(k, n, w, h)).collect();
    let t0 = cpu();
    let hydro = fields::hydrology_windows(&t, &m, &bands).expect("hydrology");
    let hydro_s = cpu() - t0;
    println!("{}: {w} x {h} cells; whole site derived in {whole_s:.2} s CPU; hydrology (fill, directions, accumulation) of the whole DEM {hydro_s:.2} s", path.display());
    let halo = fields::window_halo_cells(&t.geo, h);
    let full = Window::full(w, h);
    for (k, (b, (filled, acc))) in bands.iter().zip(hydro).enumerate() {
        let t0 = cpu();
        let dem = io::load_window(&path, b.with_halo(halo, w, h)).expect("window");
        let read_s = cpu() - t0;
        let c = conditions::derive_window(&dem, b, &climate, filled, acc).expect("band");
        let derive_s = cpu() - t0 - read_s;
        let same = c.insolation_kwh_m2.data.iter().zip(&b.cut(&site.insolation_kwh_m2, &full).data).all(|(x, y)| x.to_bits() == y.to_bits())
            && c.indices.data == b.cut(&site.indices, &full).data
            && c.twi.data.iter().zip(&b.cut(&site.twi, &full).data).all(|(x, y)| x.to_bits() == y.to_bits());
        println!(
            "band {k} of {n}: rows {}..{} ({} cells), read by window with {halo} rows of halo ({} cells) in {read_s:.3} s, derived in {derive_s:.2} s CPU ({:.2} of the whole); equal to the whole's: {same}",
            b.row0,
            b.row1(),
            b.width * b.height,
            dem.window.width * dem.window.height,
            (read_s + derive_s) / whole_s
        );
    }
}
