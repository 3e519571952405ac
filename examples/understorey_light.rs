//! The light under closed stands and the suppressed sessile oaks (issue 35, round 41).
//!
//! 1. Pure, unmanaged stands of beech, sessile oak and Norway spruce (`sim::pure_stand`: planted
//!    at 1.5 m, age 3, flat site at the niche optimum, 51° N; `--side` m square, default 100):
//!    at ages 80, 100, 120 and 150 the mean and quartiles of the relative light at the floor and
//!    at 5 m over the light cells (`sim::phases::light::cell_light_at`), and the stand's leaf-area
//!    index (the light phase's leaf area of every crown over the plot's area).
//! 2. The default scenario (`scenarios/default.toml`) to year 150 (`--years`): at years 100, 125
//!    and 150 the floor and 5 m light of the light cells under closed stands (the 3 × 3 cells
//!    around a cell hold ≥ 30 m²/ha of basal area, the cell's local top height is ≥ 18 m, one
//!    species holds ≥ 70 % of that basal area), by that species; and, from year 100 on, the
//!    sessile oaks aged ≥ 60 years under 10 m tall: their light each year, and by light class
//!    their annual mortality and height and DBH increments.
//!
//! `cargo run --release --example understorey_light [-- --side 100 --years 150 --skip-default]`
use std::collections::HashMap;
use sylva::sim::phases::light::{cell_light_at, crown_leaf_area};
use sylva::sim::pure_stand::pure_stand_toml;
use sylva::sim::step::{step_year, step_year_with, YearReport};
use sylva::sim::{Scenario, World};
use sylva::species::{Season, SpeciesLibrary};

fn pct(v: &mut [f32], p: f64) -> f32 {
    if v.is_empty() {
        return f32::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn mean(v: &[f32]) -> f32 {
    v.iter().map(|&x| x as f64).sum::<f64>() as f32 / v.len().max(1) as f32
}

/// Light at height z over every cell of the world's light grid.
fn light_at(w: &World, z: f32) -> Vec<f32> {
    cell_light_at(&w.stand.trees, &w.site.light, &w.site.conditions, &w.site.lib, &w.site.light_site, &w.site.rel_insolation, &w.site.obstacle_canopy, z)
}

fn summary(label: &str, v: &mut [f32]) -> String {
    let m = mean(v);
    format!("{label} mean {:.3} p25 {:.3} p50 {:.3} p75 {:.3}", m, pct(v, 0.25), pct(v, 0.5), pct(v, 0.75))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| args.iter().position(|a| a == k).and_then(|i| args.get(i + 1)).cloned();
    let side: f64 = arg("--side").map(|s| s.parse()).transpose()?.unwrap_or(100.0);
    let years: u32 = arg("--years").map(|s| s.parse()).transpose()?.unwrap_or(150);
    let lib = SpeciesLibrary::embedded()?;
    println!("== pure stands ({side} m square, planted at 1.5 m, age 3)");
    for id in ["beech", "sessile_oak", "norway_spruce"] {
        let sp = lib.species.iter().find(|s| s.id == id).ok_or("species")?;
        let sc = Scenario::from_toml_str(&pure_stand_toml(sp, side, 1.5, 3.0, 147, 7), "pure stand")?;
        let mut w = World::new(sc.site()?, &lib, &sc)?;
        for _ in 0..147 {
            let mut r = YearReport::default();
            step_year(&mut w, &sc, &mut r);
            let age = 3 + w.stand.year;
            if [80, 100, 120, 150].contains(&age) {
                let t = &w.stand.trees;
                let la: f64 = (0..t.len()).map(|i| crown_leaf_area(lib.species[t.species[i] as usize].life.shade_tolerance, t.crown_radius[i]) as f64).sum();
                let lai = la / (side * side);
                let row = r.row.as_ref().ok_or("row")?;
                // the light of this year's canopy (the stand after the year's growth and deaths)
                let mut g0 = light_at(&w, 0.0);
                let mut g5 = light_at(&w, 5.0);
                println!(
                    "{id:<14} age {age:>3}: N {:>5.0}/ha BA {:>5.1} H100 {:>4.1} LAI {:>4.2} | {} | {}",
                    row.stems_ha,
                    row.basal_area_m2_ha,
                    row.top_height_m,
                    lai,
                    summary("floor", &mut g0),
                    summary("5 m", &mut g5)
                );
            }
        }
    }
    if args.iter().any(|a| a == "--skip-default") {
        return Ok(());
    }
    println!("== default scenario");
    let sc = sylva::job::main_job::default_scenario()?;
    let mut w = World::new(sc.site()?, &lib, &sc)?;
    let oak = lib.find("sessile_oak").ok_or("oak")?;
    // id -> (light, height, dbh) of the suppressed oaks at last year's spring
    let mut last: HashMap<u64, (f32, f32, f32)> = HashMap::new();
    // per light class: (tree-years, deaths, sum dh, sum ddbh, survivors)
    const CLASSES: [f32; 6] = [0.0, 0.05, 0.1, 0.2, 0.3, f32::INFINITY];
    let mut acc = [(0u64, 0u64, 0f64, 0f64, 0u64); 5];
    let class = |l: f32| CLASSES.windows(2).position(|b| l >= b[0] && l < b[1]).unwrap_or(4);
    for _ in 0..years {
        let mut r = YearReport::default();
        let mut spring: Option<HashMap<u64, (f32, f32, f32)>> = None;
        let mut report_light: Option<String> = None;
        let year = w.stand.year + 1;
        step_year_with(&mut w, &sc, &mut r, &mut |season, w| {
            if season != Season::Spring {
                return;
            }
            let t = &w.stand.trees;
            if year >= 100 {
                let mut now = HashMap::new();
                for i in 0..t.len() {
                    if t.species[i] == oak && t.age[i] >= 60.0 && t.height[i] < 10.0 {
                        now.insert(t.id[i], (t.light[i], t.height[i], t.dbh[i]));
                    }
                }
                spring = Some(now);
            }
            if [100, 125, 150].contains(&year) {
                let lg = &w.site.light;
                let (cols, rows) = (lg.cols, lg.rows);
                let n = lg.len();
                let nsp = w.site.lib.species.len();
                let mut ba = vec![0f64; n * nsp];
                for i in 0..t.len() {
                    let c = lg.cell_of(t.x[i], t.y[i]);
                    let d = t.dbh[i] as f64 / 200.0;
                    ba[c * nsp + t.species[i] as usize] += std::f64::consts::PI * d * d;
                }
                let g0 = light_at(w, 0.0);
                let g5 = light_at(w, 5.0);
                let block_ha = 9.0 * lg.cell_area_m2() / 1e4;
                let mut by: Vec<(Vec<f32>, Vec<f32>)> = vec![(Vec::new(), Vec::new()); nsp];
                for row in 1..rows.saturating_sub(1) {
                    for col in 1..cols.saturating_sub(1) {
                        let c = row * cols + col;
                        if w.scratch.canopy_top[c] < 18.0 {
                            continue;
                        }
                        let mut s = vec![0f64; nsp];
                        for dr in [-1isize, 0, 1] {
                            for dc in [-1isize, 0, 1] {
                                let k = (row as isize + dr) as usize * cols + (col as isize + dc) as usize;
                                for (j, v) in s.iter_mut().enumerate() {
                                    *v += ba[k * nsp + j];
                                }
                            }
                        }
                        let tot: f64 = s.iter().sum();
                        if tot / block_ha < 30.0 {
                            continue;
                        }
                        if let Some(j) = (0..nsp).find(|&j| s[j] >= 0.7 * tot) {
                            by[j].0.push(g0[c]);
                            by[j].1.push(g5[c]);
                        }
                    }
                }
                let mut out = String::new();
                for (j, (a, b)) in by.iter_mut().enumerate() {
                    if a.len() >= 20 {
                        out += &format!("  year {year} closed {:<14} cells {:>5}: {} | {}\n", w.site.lib.species[j].id, a.len(), summary("floor", a), summary("5 m", b));
                    }
                }
                report_light = Some(out);
            }
        });
        if let Some(s) = report_light {
            print!("{s}");
        }
        if let Some(now) = spring {
            // last year's suppressed oaks: alive now or not
            for (id, &(l, h, d)) in &last {
                let k = class(l);
                acc[k].0 += 1;
                match w.stand.trees.id.binary_search(id) {
                    Ok(i) => {
                        acc[k].2 += (w.stand.trees.height[i] - h) as f64;
                        acc[k].3 += (w.stand.trees.dbh[i] - d) as f64;
                        acc[k].4 += 1;
                    }
                    Err(_) => acc[k].1 += 1,
                }
            }
            if [100, 125, 150].contains(&year) {
                let mut l: Vec<f32> = now.values().map(|v| v.0).collect();
                println!("  year {year} oaks aged >= 60 under 10 m: {} | {}", l.len(), summary("light", &mut l));
            }
            last = now;
        }
    }
    println!("  suppressed oaks (aged >= 60, < 10 m) from year 100: by light class, tree-years, annual mortality, mean dh (m/yr), mean dDBH (cm/yr)");
    for (k, a) in acc.iter().enumerate() {
        println!(
            "   light [{:.2}, {:.2}): {:>7} tree-yr, mortality {:.4}/yr, dh {:.3}, dDBH {:.3}",
            CLASSES[k],
            CLASSES[k + 1],
            a.0,
            a.1 as f64 / a.0.max(1) as f64,
            a.2 / a.4.max(1) as f64,
            a.3 / a.4.max(1) as f64
        );
    }
    Ok(())
}
