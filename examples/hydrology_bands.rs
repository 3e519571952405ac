//! The hydrology by bands of rows (issue 37, round 34; `terrain::hydrology`): for a DEM cut into
//! 1, 2, 4 and 8 bands, each band a rank of a `LocalTransport` group on a thread of its own
//! (`hydrology_of_rank`), what each rank reads (its rows and 2 rows of halo, against the whole
//! DEM rank 0 read until round 33) and sends (halo rows to its neighbours, perimeter graphs to
//! rank 0; rank 0 the central solves' answers), the process's CPU seconds, and a check that
//! every band's filled levels and accumulation equal the whole raster's bit for bit. Counts, not
//! timings, are the figures (the CPU seconds include the threads' waits for each other).
//!
//! Command (BENCHMARKS.md round 34): `cargo run --release --example hydrology_bands -- [DEM |
//! gen:SIZE]` (default `terrains/coweeta_basin_10m_utm17n.tif`; `gen:SIZE` a generated
//! SIZE × SIZE terrain of 10 m cells, seed 42, 1500 m relief, as `benches/terrain.rs`).
use sylva::grid::Window;
use sylva::sim::tiles::{LocalTransport, Transport};
use sylva::job::hydrology_ranks;
use sylva::terrain::{fields, io};

#[path = "../benches/common/mod.rs"]
mod common;
use common::cpu;

fn main() {
    let arg = std::env::args().nth(1).unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/terrains/coweeta_basin_10m_utm17n.tif").into());
    let t = match arg.strip_prefix("gen:") {
        Some(n) => sylva::terrain::generate::generate(n.parse().expect("gen:SIZE"), 10.0, 1500.0, 42).expect("generated terrain"),
        None => io::load(std::path::Path::new(&arg)).expect("DEM"),
    };
    let m = fields::mask(&t, 0.0);
    let (w, h) = (m.width, m.height);
    let t0 = cpu();
    let filled = fields::fill_depressions(&t, &m);
    let dir = fields::flow_directions(&filled, &t.geo, &m);
    let acc = fields::flow_accumulation(&dir, &m);
    let whole_s = cpu() - t0;
    let raised = filled.data.iter().zip(&t.elevation.data).filter(|(a, b)| a > b).count();
    println!("{arg}: {w} x {h} cells ({} valid, {raised} raised by the fill); whole raster: {whole_s:.2} s CPU", m.data.iter().filter(|v| **v).count());
    let full = Window::full(w, h);
    for n in [1usize, 2, 4, 8] {
        let bands: Vec<Window> = (0..n).map(|k| sylva::job::site_ranks::band(k, n, w, h)).collect();
        let t0 = cpu();
        let per: Vec<_> = std::thread::scope(|s| {
            let hs: Vec<_> = LocalTransport::group(n)
                .into_iter()
                .map(|mut tr| {
                    let (bands, t, m) = (&bands, &t, &m);
                    s.spawn(move || {
                        let k = tr.rank();
                        let (r0, r1) = sylva::terrain::hydrology::read_rows(&bands[k], h);
                        let out = hydrology_ranks::hydrology_of_rank(&mut tr, bands, w, h, &t.elevation.data[r0 * w..r1 * w], &m.data[r0 * w..r1 * w], &t.geo, "bench").expect("hydrology");
                        ((r1 - r0) * w, tr.bytes_sent(), out)
                    })
                })
                .collect();
            hs.into_iter().map(|x| x.join().expect("rank")).collect()
        });
        let s = cpu() - t0;
        let mut same = true;
        for (b, (_, _, (f, a))) in bands.iter().zip(&per) {
            same &= f.data.iter().zip(&b.cut(&filled, &full).data).all(|(x, y)| x.to_bits() == y.to_bits());
            same &= a.data.iter().zip(&b.cut(&acc, &full).data).all(|(x, y)| x.to_bits() == y.to_bits());
        }
        let reads: Vec<String> = per.iter().map(|p| format!("{:.1} %", 100.0 * p.0 as f64 / (w * h) as f64)).collect();
        let sent: Vec<String> = per.iter().map(|p| format!("{:.1} KiB", p.1 as f64 / 1024.0)).collect();
        println!("{n} bands: {s:.2} s CPU; cells read per rank (of the DEM) [{}]; bytes sent per rank [{}]; equal to the whole raster's bit for bit: {same}", reads.join(", "), sent.join(", "));
        assert!(same, "{n} bands differ from the whole raster");
    }
}
