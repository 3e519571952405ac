//! Where each species grows in a scenario's run (round 45, trial 44 defect 1: do species sort
//! by ridge and cove?): runs the scenario in memory (no outputs) for `YEARS` years and prints
//! the last year's stems/ha, basal area and top height H100, each species' share of the basal
//! area, and each species' basal area (m²/ha of the tercile's own area) in the terciles of the
//! living cells by elevation and by topographic wetness index, and its mean F.
//!
//! `cargo run --release --example site_sort [-- SCENARIO.toml [YEARS]]` (default: the embedded
//! default scenario, its years).
use sylva::sim::{step_year, Scenario, World, YearReport};
use sylva::species::SpeciesLibrary;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let text = match args.first() {
        Some(p) => std::fs::read_to_string(p).expect("scenario file"),
        None => sylva::job::main_job::DEFAULT_SCENARIO.to_string(),
    };
    let sc = Scenario::from_toml_str(&text, "site_sort").expect("scenario");
    let years = args.get(1).map(|y| y.parse().expect("YEARS")).unwrap_or(sc.years);
    let lib = SpeciesLibrary::embedded().expect("species");
    let site = sc.site().expect("site");
    let mut w = World::new(site, &lib, &sc).expect("world");
    let mut row = None;
    for y in 0..years {
        let mut r = YearReport::default();
        step_year(&mut w, &sc, &mut r);
        row = r.row;
        if (y + 1) % 25 == 0 {
            eprintln!("year {}", y + 1);
        }
    }
    let row = row.expect("a year");
    let c = &w.site.conditions;
    let names: Vec<&str> = w.site.pool.iter().map(|&s| lib.species[s as usize].id.as_str()).collect();
    println!("year {years}: {:.0} stems/ha, basal area {:.1} m2/ha, H100 {:.1} m", row.stems_ha, row.basal_area_m2_ha, row.top_height_m);
    for (p, n) in names.iter().enumerate() {
        println!("  {n:<14} basal-area share {:5.1} %, stem share {:5.1} %", 100.0 * row.share_ba[p], 100.0 * row.share_stems[p]);
    }
    let valid: Vec<usize> = (0..c.mask.data.len()).filter(|&k| c.mask.data[k]).collect();
    let cell_ha = c.cell_x_m * c.cell_y_m / 10_000.0;
    let mut f: Vec<f32> = valid.iter().map(|&k| c.indices.data[k][3]).collect();
    f.sort_by(f32::total_cmp);
    println!("F of the living cells: 5 % {:.2}, median {:.2}, 95 % {:.2}", f[f.len() / 20], f[f.len() / 2], f[f.len() * 19 / 20]);
    for (what, field) in [("elevation", &c.elevation_m), ("TWI", &c.twi)] {
        let mut v: Vec<f32> = valid.iter().map(|&k| field.data[k]).collect();
        v.sort_by(f32::total_cmp);
        let (t1, t2) = (v[v.len() / 3], v[2 * v.len() / 3]);
        let third = |x: f32| if x < t1 { 0 } else if x < t2 { 1 } else { 2 };
        let mut ba = vec![[0.0f64; 3]; names.len()];
        let mut fsum = vec![(0.0f64, 0.0f64); names.len()];
        let t = &w.stand.trees;
        for i in 0..t.len() {
            let Some((col, r)) = c.cell_at(t.x[i] as f64, t.y[i] as f64) else { continue };
            let Some(k) = c.held_index(col, r) else { continue };
            let Some(p) = w.pool_index(t.species[i]) else { continue };
            let g = std::f64::consts::PI / 4.0 * (t.dbh[i] as f64 / 100.0).powi(2);
            ba[p][third(field.data[k])] += g;
            fsum[p].0 += g * c.indices.data[k][3] as f64;
            fsum[p].1 += g;
        }
        let area = valid.len() as f64 / 3.0 * cell_ha;
        println!("basal area (m2/ha) by {what} tercile (< {t1:.1}, {t1:.1}-{t2:.1}, > {t2:.1}):");
        for (p, n) in names.iter().enumerate() {
            println!("  {n:<14} {:6.2} {:6.2} {:6.2}   basal-area-weighted F {:.2}", ba[p][0] / area, ba[p][1] / area, ba[p][2] / area, fsum[p].0 / fsum[p].1.max(1e-12));
        }
    }
}
