//! The two-scale dispersal kernel (round 45): a point source on a flat site of 2 km × 2 km
//! spreads its seeds over the seed grid's fine cells (5 m) within `NEAR_FIELD_M` of it and its
//! coarse cells (20–87.5 m) beyond. The seeds are conserved (their sum over the grid equals
//! the seeds produced, within 1e-4), the near field follows the species' kernel (Clark et al.
//! 1999's 2Dt, or the negative exponential) at 5–40 m, every 5 m ring within 6 %, where the
//! coarse cells alone (the grid before round 45, `near_m = 0`) miss it by 30–40 % at 5–10 m,
//! and the bits do not depend on the threads.
use sylva::sim::light_grid::CellRect;
use sylva::sim::phases::reproduction::{self, density, disperse, kernel, Reproduction};
use sylva::sim::trees::{NewTree, TreeStore};
use sylva::sim::world::{seed_grids, SeedGrid, NEAR_FIELD_M};
use sylva::species::SpeciesLibrary;

const SIDE_M: f64 = 2000.0;
/// The source: in the site's middle, off the centres of its fine and coarse cells.
const SRC: (f32, f32) = (1003.3, 991.2);

/// One mature tree of `species` at [`SRC`] in full light: the seed grid of that species after
/// reproduction, and the seeds it produced.
fn point_source(lib: &SpeciesLibrary, species: &str) -> (SeedGrid, f64) {
    let s = lib.find(species).unwrap();
    let mut t = TreeStore::default();
    t.push(NewTree { species: s, x: SRC.0, y: SRC.1, z: 0.0, age: 120.0, height: 30.0, dbh: 50.0, crown_radius: 6.0, suitability: 1.0 });
    let i = 0;
    t.light[i] = 1.0;
    let produced = reproduction::seeds_of(&t, i, lib).unwrap() as f64;
    assert!(produced > 30.0, "{species}: {produced} seeds");
    let mut seeds = seed_grids(lib, &[s], (SIDE_M, SIDE_M));
    reproduction::run(Reproduction { trees: &t, lib, pool: &[s], seeds: &mut seeds });
    (seeds.pop().unwrap(), produced)
}

/// Seeds on the grid: Σ seeds/m² × fine cell area (f64).
fn total(g: &SeedGrid) -> f64 {
    g.data.iter().map(|v| *v as f64).sum::<f64>() * g.cell_m * g.cell_m
}

#[test]
fn a_point_source_s_seeds_are_conserved() {
    let lib = SpeciesLibrary::embedded().unwrap();
    // 2Dt (beech: coarse 25 m), negative exponential (alder: 20 m; birch: 87.5 m, 700 m reach)
    for (sp, coarse) in [("beech", 25.0), ("black_alder", 20.0), ("silver_birch", 87.5), ("scots_pine", 37.5)] {
        let (g, produced) = point_source(&lib, sp);
        assert!((g.coarse_m() - coarse).abs() < 1e-9 && g.cell_m <= 5.0 + 1e-9, "{sp}: coarse {} m, fine {} m", g.coarse_m(), g.cell_m);
        let got = total(&g);
        assert!((got / produced - 1.0).abs() < 1e-4, "{sp}: {got} seeds on the grid of {produced} produced");
    }
}

/// Seeds per m² expected at distance `r` from a source of `produced` seeds: its kernel's density,
/// over the kernel's mass within `max_m` (the cut).
fn expected(d: &sylva::species::Dispersal, produced: f64, r: f64) -> f64 {
    // the mass within max_m, by the midpoint rule in 0.05 m rings
    let n = (d.max_m as f64 / 0.05) as usize;
    let mass: f64 = (0..n).map(|i| (i as f64 + 0.5) * 0.05).map(|x| std::f64::consts::TAU * x * density(d, x) * 0.05).sum();
    produced * density(d, r) / mass
}

/// The profile at 5–40 m from the source's fine cell centre: per ring of 5 m, the seeds of its
/// fine cells over [`expected`]'s at their centres, minus 1; and the mean absolute deviation
/// of the cells.
fn near_field_profile(g: &SeedGrid, d: &sylva::species::Dispersal, produced: f64) -> (Vec<f64>, f64) {
    let f = g.cell_m;
    let (sc, sr) = ((SRC.0 as f64 / f) as usize, (SRC.1 as f64 / f) as usize);
    let (mut got, mut want) = (vec![0f64; 7], vec![0f64; 7]);
    let (mut sum, mut n) = (0f64, 0usize);
    for r in sr - 10..=sr + 10 {
        for c in sc - 10..=sc + 10 {
            let dist = (((c as f64 - sc as f64).powi(2) + (r as f64 - sr as f64).powi(2)).sqrt()) * f;
            if !(5.0..40.0).contains(&dist) {
                continue;
            }
            let (v, e) = (g.data[r * g.cols + c] as f64, expected(d, produced, dist));
            let ring = ((dist - 5.0) / 5.0) as usize;
            got[ring] += v;
            want[ring] += e;
            sum += (v / e - 1.0).abs();
            n += 1;
        }
    }
    (got.iter().zip(&want).map(|(a, b)| a / b - 1.0).collect(), sum / n as f64)
}

#[test]
fn the_near_field_follows_the_kernel_at_5_to_40_m_where_the_coarse_grid_does_not() {
    let lib = SpeciesLibrary::embedded().unwrap();
    for sp in ["beech", "black_alder", "sycamore"] {
        let (g, produced) = point_source(&lib, sp);
        let d = lib.get(sp).unwrap().life.dispersal;
        let pct = |v: &[f64]| v.iter().map(|x| format!("{:+.1} %", 100.0 * x)).collect::<Vec<_>>().join(", ");
        let (rings, cells) = near_field_profile(&g, &d, produced);
        println!("{sp}: two-scale kernel, rings 5–10 … 35–40 m against the kernel: {}; cells' mean deviation {:.1} %", pct(&rings), 100.0 * cells);
        assert!(rings.iter().all(|e| e.abs() < 0.06) && cells < 0.02, "{sp}: two-scale near field off the kernel: rings {}, cells {:.1} %", pct(&rings), 100.0 * cells);
        // the same source on the coarse cells alone (the seed grid before round 45)
        let mut src = vec![0f32; g.cols * g.rows];
        let (sc, sr) = ((SRC.0 as f64 / g.cell_m) as usize, (SRC.1 as f64 / g.cell_m) as usize);
        src[sr * g.cols + sc] = produced as f32;
        let whole = CellRect { col0: 0, row0: 0, col1: g.cols, row1: g.rows };
        let coarse = SeedGrid { data: disperse(&kernel(&d, g.cell_m, g.block, 0.0), g.cols, g.rows, g.cell_m, whole, &src, whole), ..g.clone() };
        let (crings, ccells) = near_field_profile(&coarse, &d, produced);
        println!("{sp}: coarse cells alone: {}; cells' mean deviation {:.1} %", pct(&crings), 100.0 * ccells);
        assert!(crings.iter().any(|e| e.abs() > 0.25) && ccells > 0.1, "{sp}: the coarse cells alone should miss the near field: rings {}, cells {:.1} %", pct(&crings), 100.0 * ccells);
        assert!((total(&coarse) / produced - 1.0).abs() < 1e-4);
    }
}

#[test]
fn dispersal_is_the_same_on_one_thread_and_on_four() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let d = lib.get("beech").unwrap().life.dispersal;
    let g = &seed_grids(&lib, &[lib.find("beech").unwrap()], (600.0, 500.0))[0];
    // sources in every third fine cell, of varied production
    let src: Vec<f32> = (0..g.cols * g.rows).map(|i| if i % 3 == 0 { (i % 97) as f32 * 1.7 } else { 0.0 }).collect();
    let whole = CellRect { col0: 0, row0: 0, col1: g.cols, row1: g.rows };
    let k = kernel(&d, g.cell_m, g.block, NEAR_FIELD_M);
    let on = |n: usize| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| disperse(&k, g.cols, g.rows, g.cell_m, whole, &src, whole));
    let (a, b) = (on(1), on(4));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert!(a.iter().any(|v| *v > 0.0));
}

/// The cost of one year's spreading on the default scenario's window (2.4 km × 1.8 km) for
/// each species of its pool, with a seed source in every fine cell (a closed mature stand):
/// the two-scale kernel against the coarse cells alone (`near_m = 0`, the grid before round
/// 45), interleaved. Prints wall times; asserts nothing about them (`cargo test --release
/// --test sim_dispersal -- --ignored --nocapture`; BENCHMARKS.md, round 45 r45d).
#[test]
#[ignore = "a cost measurement: prints wall times of the fine and coarse seed spreading on the default window, asserts nothing"]
fn cost_on_the_default_window() {
    let lib = SpeciesLibrary::embedded().unwrap();
    for sp in ["beech", "sycamore", "norway_maple", "scots_pine", "silver_birch", "norway_spruce", "sessile_oak", "black_alder"] {
        let s = lib.find(sp).unwrap();
        let d = lib.get(sp).unwrap().life.dispersal;
        let g = &seed_grids(&lib, &[s], (2400.0, 1800.0))[0];
        let src: Vec<f32> = (0..g.cols * g.rows).map(|i| 1.0 + (i % 7) as f32).collect();
        let whole = CellRect { col0: 0, row0: 0, col1: g.cols, row1: g.rows };
        let (two, one) = (kernel(&d, g.cell_m, g.block, NEAR_FIELD_M), kernel(&d, g.cell_m, g.block, 0.0));
        let mut t = [0f64; 2];
        for _ in 0..3 {
            for (j, k) in [&one, &two].into_iter().enumerate() {
                let t0 = std::time::Instant::now();
                std::hint::black_box(disperse(k, g.cols, g.rows, g.cell_m, whole, &src, whole));
                t[j] += t0.elapsed().as_secs_f64() / 3.0;
            }
        }
        println!("{sp}: {} × {} fine cells of {:.2} m, {} near and {} tail offsets: coarse alone {:.3} s, two-scale {:.3} s", g.cols, g.rows, g.cell_m, two.near.len(), two.far.len(), t[0], t[1]);
    }
}
