//! A planted lattice self-thins tree by tree, without a pattern of the model's grids (issue 35,
//! round 43; trial 43 defect 1: dense plantings grew into an axis-aligned maze).
//!
//! Beech planted at 1.5 m (age 3) on a flat 150 m × 150 m site at its niche optimum, unmanaged,
//! to age 80 (year 77), when about half of the 10,000 planted trees' places are gone from the
//! upper layer. The upper layer: the trees of at least 2/3 of the stand's top height H100 (the
//! IUFRO upper height class, `sim::phases::mortality::UPPER_LAYER_SHARE`).
//!
//! - **No stripes along the grid axes.** The periodogram of the upper layer's stems,
//!   `P(k) = |Σ exp(−2πi k·x)|² / N` at the wave vectors `(j / 150 m, 0)` and `(0, j / 150 m)`,
//!   `j` = 5…10 (wavelengths 30–15 m, where the old 3 × 3 box of 10 m crowding cells had a
//!   negative Fourier transform and the maze's spectrum peaked), averages at most 3. A pattern
//!   without structure at those wavelengths (Poisson) has `E P = 1` at each of these 12
//!   ordinates, each exponentially distributed: their mean exceeds 3 with probability below
//!   10⁻⁶; a self-thinned stand is more regular than Poisson (below 1). With the box (main at
//!   d5ee5e6, `sylva simulate` of this scenario, seeds 1–4) the mean was 5.4–14.3; with the
//!   binomial weights 0.73–1.19.
//! - **Not locked to the crowding grid.** The share of the 10 m crowding cells
//!   (`sim::density::CROWD_CELL_M`) without an upper-layer stem is at most 1.5 × that of the
//!   same grid shifted by half a cell, plus 0.03 (a pattern that does not know the grid fills
//!   both alike). With the box 0.22–0.27 of the cells were empty (seeds 1–4) against none
//!   shifted; with the binomial weights none of either.
use sylva::sim::density::CROWD_CELL_M;
mod common;

const SIDE_M: f64 = 150.0;

/// The upper layer's stem positions (m) of the planted beech lattice at year `years`.
fn upper_layer(years: u32) -> Vec<(f64, f64)> {
    let toml = common::ScenarioToml::new("planted lattice", years, 1)
        .species(&["beech"])
        .line("climate = { latitude_deg = 51.0 }")
        .uniform_indices(15, 15, 10.0, 200.0, [3.0, 5.0, 2.0, 5.0, 6.0, 6.0])
        .planted("beech", 1.5, 3.0)
        .build();
    let (sc, mut w) = common::world_with(&toml, &common::embedded());
    let rows = common::run(&sc, &mut w, years);
    let h100 = rows.last().unwrap().top_height_m as f32;
    let t = &w.stand.trees;
    (0..t.len()).filter(|&i| t.height[i] >= 2.0 / 3.0 * h100).map(|i| (t.x[i] as f64, t.y[i] as f64)).collect()
}

/// The periodogram `|Σ exp(−2πi k·x)|² / N` of `pts` at wave vector `(kx, ky)` (cycles/m).
fn periodogram(pts: &[(f64, f64)], kx: f64, ky: f64) -> f64 {
    let (mut re, mut im) = (0.0, 0.0);
    for &(x, y) in pts {
        let a = -std::f64::consts::TAU * (kx * x + ky * y);
        re += a.cos();
        im += a.sin();
    }
    (re * re + im * im) / pts.len() as f64
}

/// Mean periodogram along both axes at wavelengths 30–15 m (`j / SIDE_M`, j = 5…10).
fn axis_power(pts: &[(f64, f64)]) -> f64 {
    let v: Vec<f64> = (5..=10).flat_map(|j| {
        let k = j as f64 / SIDE_M;
        [periodogram(pts, k, 0.0), periodogram(pts, 0.0, k)]
    }).collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// Share of the `cell`-metre cells of the grid offset by `off` m (whole cells inside the site)
/// that hold none of `pts`.
fn empty_share(pts: &[(f64, f64)], cell: f64, off: f64) -> f64 {
    let n = ((SIDE_M - off) / cell).floor() as usize;
    let mut full = vec![false; n * n];
    for &(x, y) in pts {
        let (c, r) = (((x - off) / cell).floor(), ((y - off) / cell).floor());
        if c >= 0.0 && r >= 0.0 && (c as usize) < n && (r as usize) < n {
            full[r as usize * n + c as usize] = true;
        }
    }
    full.iter().filter(|f| !**f).count() as f64 / (n * n) as f64
}

#[test]
fn the_periodogram_of_a_random_pattern_is_one_and_stripes_raise_it() {
    // the statistic itself: a uniform random pattern (E P = 1) stays far below the bound, and
    // stripes of 10 m lanes with 10 m gaps (the maze's period) exceed it many times
    let mut r = sylva::rng::Stream::new(7, 0, 0, 0);
    let random: Vec<(f64, f64)> = (0..2400).map(|_| (r.range(0.0, SIDE_M), r.range(0.0, SIDE_M))).collect();
    let p = axis_power(&random);
    assert!((0.4..1.8).contains(&p), "random pattern: {p}");
    assert!(empty_share(&random, CROWD_CELL_M, 0.0) < 0.01);
    let stripes: Vec<(f64, f64)> = random.iter().copied().filter(|&(x, _)| (x / 10.0).floor() as i64 % 2 == 0).collect();
    assert!(axis_power(&stripes) > 10.0, "stripes: {}", axis_power(&stripes));
    // every other column of cells empty on the grid, (nearly) none on the shifted grid
    let (e0, e5) = (empty_share(&stripes, CROWD_CELL_M, 0.0), empty_share(&stripes, CROWD_CELL_M, 5.0));
    assert!(e0 > 0.45 && e5 < 0.05 && e0 > 1.5 * e5 + 0.03, "stripes: {e0} {e5}");
}

#[test]
fn a_planted_lattice_self_thins_without_a_maze() {
    let up = upper_layer(77);
    let p = axis_power(&up);
    let (e0, e5) = (empty_share(&up, CROWD_CELL_M, 0.0), empty_share(&up, CROWD_CELL_M, 0.5 * CROWD_CELL_M));
    eprintln!("upper layer {} stems ({:.0}/ha); axis periodogram 30–15 m {p:.2}; empty 10 m cells {e0:.3}, shifted 5 m {e5:.3}", up.len(), up.len() as f64 / (SIDE_M * SIDE_M / 1e4));
    assert!(up.len() > 500, "the upper layer holds {} stems", up.len());
    assert!(p <= 3.0, "stripes along the axes at 15–30 m: mean periodogram {p:.2} (a pattern without them: 1)");
    assert!(e0 <= 1.5 * e5 + 0.03, "the upper layer follows the 10 m crowding grid: {e0:.3} of its cells empty against {e5:.3} of the grid shifted by 5 m");
}
