//! Establishment (spring): seedlings appear on unmasked light cells where the ground light
//! reaches the species' `germination_min_light`, at a rate
//! `λ = seeds/m² · cell area · establishment_rate · suitability` (Poisson per cell, species and
//! year), limited to [`MAX_SAPLINGS_PER_100M2`] trees below 1.3 m per 100 m².

use super::super::trees::NewTree;
use super::super::world::World;
use crate::rng::{salt, Stream};
use rayon::prelude::*;

/// Maximum number of trees shorter than 1.3 m per 100 m² of light cell (regeneration layer
/// capacity, 1600 per ha at the default).
pub const MAX_SAPLINGS_PER_100M2: f64 = 16.0;

/// Adds this year's seedlings.
pub fn run(w: &mut World) {
    let g = &w.grid;
    let cell = w.light_cell_m;
    let cap = ((MAX_SAPLINGS_PER_100M2 * cell * cell / 100.0).round() as usize).max(1);
    let t = &w.trees;
    let (seed, year) = (w.seed, w.year as u64);
    let per_cell: Vec<Vec<NewTree>> = (0..g.cols * g.rows)
        .into_par_iter()
        .map(|c| {
            let site = w.light_site[c];
            if site == u32::MAX {
                return Vec::new();
            }
            let small = g.cell(c).iter().filter(|&&i| t.height[i as usize] < 1.3).count();
            if small >= cap {
                return Vec::new();
            }
            let gl = w.ground_light[c];
            let (col, row) = (c % g.cols, c / g.cols);
            let (cx, cy) = ((col as f64 + 0.5) * cell, (row as f64 + 0.5) * cell);
            let mut r = Stream::new(seed, c as u64, year, salt::ESTABLISH);
            let mut out = Vec::new();
            for (p, &s) in w.pool.iter().enumerate() {
                let sp = &w.lib.species[s as usize];
                if gl < sp.life.germination_min_light {
                    continue;
                }
                if w.suitability[p][site as usize] < 0.05 {
                    continue;
                }
                let seeds = (w.seeds[p].at(cx, cy) + w.seed_rain[p]) as f64 * cell * cell;
                let lambda = seeds * sp.life.establishment_rate as f64 * w.suitability[p][site as usize] as f64;
                let n = r.poisson(lambda.min(4.0 * cap as f64));
                for _ in 0..n {
                    let x = (col as f64 + r.uniform()) * cell;
                    let y = (row as f64 + r.uniform()) * cell;
                    // the tree's own site cell decides (light cells may straddle masked cells)
                    let Some(sc) = w.site_cell(x, y) else { continue };
                    let suit = w.suitability[p][sc];
                    if suit < 0.05 {
                        continue;
                    }
                    out.push(NewTree { species: s, x: x as f32, y: y as f32, z: w.site.elevation_at(x, y), age: 1.0, height: 0.3, dbh: 0.0, crown_radius: super::growth::open_crown_radius(sp, 0.3, 0.0), suitability: suit });
                }
            }
            let room = cap - small;
            if out.len() > room {
                // deterministic partial Fisher–Yates: a random subset of `room` seedlings
                for k in 0..room {
                    let j = k + r.below((out.len() - k) as u64) as usize;
                    out.swap(k, j);
                }
                out.truncate(room);
            }
            out
        })
        .collect();
    for v in per_cell {
        for nt in v {
            w.trees.push(nt);
        }
    }
}
