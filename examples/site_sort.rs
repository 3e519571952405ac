//! Where each species grows in a scenario's run (rounds 45 and 46, trial 44 defect 1: do species
//! sort by ridge and cove?): the last year's basal area and each species' share of it, each
//! species' basal area (m²/ha of the tercile's own area) in the terciles of the living cells by
//! elevation and by topographic wetness index (TWI), and its basal-area-weighted F; with `--png`
//! a map: the TWI terciles (ridges tan, mid-slopes pale, coves blue) beside the species with the
//! most basal area on each 30 m block of cells.
//!
//! The trees come from a run in memory (`YEARS` years of the scenario, no outputs) or, with
//! `--inventory FILE.csv`, from a run's CSV inventory (`sylva simulate --inventory csv`; living
//! trees), read on this build's site conditions: the before/after of round 46 read main's
//! run and this branch's on the same TWI and elevation (F is this build's).
//!
//! `cargo run --example site_sort [-- [SCENARIO.toml] [YEARS] [--inventory FILE.csv] [--png OUT.png]]`
//! (default: the embedded default scenario, its years).
use image::{Rgb, RgbImage};
use sylva::sim::{step_year, Scenario, World, YearReport};
use sylva::species::SpeciesLibrary;

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut take = |flag: &str| -> Option<String> {
        let i = args.iter().position(|a| a == flag)?;
        let v = args.get(i + 1).cloned().expect("a value after the flag");
        args.drain(i..=i + 1);
        Some(v)
    };
    let inventory = take("--inventory");
    let png = take("--png");
    let text = match args.first() {
        Some(p) => std::fs::read_to_string(p).expect("scenario file"),
        None => sylva::job::main_job::DEFAULT_SCENARIO.to_string(),
    };
    let sc = Scenario::from_toml_str(&text, "site_sort").expect("scenario");
    let years = args.get(1).map(|y| y.parse().expect("YEARS")).unwrap_or(sc.years);
    let lib = SpeciesLibrary::embedded().expect("species");
    let site = sc.site().expect("site");
    let mut w = World::new(site, &lib, &sc).expect("world");
    let names: Vec<String> = w.site.pool.iter().map(|&s| lib.species[s as usize].id.clone()).collect();
    // (pool index, x, y, dbh cm) of the living trees
    let trees: Vec<(usize, f64, f64, f64)> = match &inventory {
        Some(path) => {
            let text = std::fs::read_to_string(path).expect("inventory");
            let mut lines = text.lines();
            let head: Vec<&str> = lines.next().expect("header").split(',').collect();
            let col = |n: &str| head.iter().position(|h| *h == n).unwrap_or_else(|| panic!("no column {n}"));
            let (cs, cx, cy, cd, cst) = (col("species"), col("x_m"), col("y_m"), col("dbh_cm"), col("status"));
            lines
                .map(|l| l.split(',').collect::<Vec<_>>())
                .filter(|f| f[cst] == "alive")
                .filter_map(|f| Some((names.iter().position(|n| n == f[cs])?, f[cx].parse().ok()?, f[cy].parse().ok()?, f[cd].parse().ok()?)))
                .collect()
        }
        None => {
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
            println!("year {years}: {:.0} stems/ha, basal area {:.1} m2/ha, H100 {:.1} m", row.stems_ha, row.basal_area_m2_ha, row.top_height_m);
            for (p, n) in names.iter().enumerate() {
                println!("  {n:<14} basal-area share {:5.1} %, stem share {:5.1} %", 100.0 * row.share_ba[p], 100.0 * row.share_stems[p]);
            }
            let t = &w.stand.trees;
            (0..t.len()).filter_map(|i| Some((w.pool_index(t.species[i])?, t.x[i] as f64, t.y[i] as f64, t.dbh[i] as f64))).collect()
        }
    };
    let c = &w.site.conditions;
    let valid: Vec<usize> = (0..c.mask.data.len()).filter(|&k| c.mask.data[k]).collect();
    let cell_ha = c.cell_x_m * c.cell_y_m / 10_000.0;
    let g = |d: f64| std::f64::consts::PI / 4.0 * (d / 100.0).powi(2);
    let total: f64 = trees.iter().map(|t| g(t.3)).sum();
    println!("{} living trees, basal area {:.2} m2/ha of the living cells", trees.len(), total / (valid.len() as f64 * cell_ha));
    for (p, n) in names.iter().enumerate() {
        let s: f64 = trees.iter().filter(|t| t.0 == p).map(|t| g(t.3)).sum();
        println!("  {n:<14} basal-area share {:5.1} %", 100.0 * s / total);
    }
    let mut f: Vec<f32> = valid.iter().map(|&k| c.indices.data[k][3]).collect();
    f.sort_by(f32::total_cmp);
    println!("F of the living cells: 5 % {:.2}, median {:.2}, 95 % {:.2}", f[f.len() / 20], f[f.len() / 2], f[f.len() * 19 / 20]);
    let cell_of = |x: f64, y: f64| c.cell_at(x, y).and_then(|(col, r)| c.held_index(col, r));
    let mut twi_cut = (0.0, 0.0);
    for (what, field) in [("elevation", &c.elevation_m), ("TWI", &c.twi)] {
        let mut v: Vec<f32> = valid.iter().map(|&k| field.data[k]).collect();
        v.sort_by(f32::total_cmp);
        let (t1, t2) = (v[v.len() / 3], v[2 * v.len() / 3]);
        if what == "TWI" {
            twi_cut = (t1, t2);
        }
        let third = |x: f32| if x < t1 { 0 } else if x < t2 { 1 } else { 2 };
        let mut ba = vec![[0.0f64; 3]; names.len()];
        let mut fsum = vec![(0.0f64, 0.0f64); names.len()];
        for &(p, x, y, d) in &trees {
            let Some(k) = cell_of(x, y) else { continue };
            ba[p][third(field.data[k])] += g(d);
            fsum[p].0 += g(d) * c.indices.data[k][3] as f64;
            fsum[p].1 += g(d);
        }
        let area = valid.len() as f64 / 3.0 * cell_ha;
        println!("basal area (m2/ha) by {what} tercile (< {t1:.1}, {t1:.1}-{t2:.1}, > {t2:.1}):");
        for (p, n) in names.iter().enumerate() {
            println!("  {n:<14} {:6.2} {:6.2} {:6.2}   basal-area-weighted F {:.2}", ba[p][0] / area, ba[p][1] / area, ba[p][2] / area, fsum[p].0 / fsum[p].1.max(1e-12));
        }
    }
    if let Some(out) = png {
        map(&w, &names, &trees, twi_cut, &out);
        eprintln!("wrote {out}");
    }
}

/// The map: TWI terciles (left) and the species with the most basal area per block of
/// `BLOCK × BLOCK` cells (right), north up, 2 pixels a cell, with a legend.
fn map(w: &World, names: &[String], trees: &[(usize, f64, f64, f64)], (t1, t2): (f32, f32), out: &str) {
    const BLOCK: usize = 3;
    const PX: u32 = 2;
    let c = &w.site.conditions;
    let (cw, ch) = (c.width(), c.height());
    let (bw, bh) = (cw.div_ceil(BLOCK), ch.div_ceil(BLOCK));
    let mut ba = vec![vec![0.0f64; names.len()]; bw * bh];
    for &(p, x, y, d) in trees {
        let Some((col, row)) = c.cell_at(x, y) else { continue };
        ba[(row / BLOCK) * bw + col / BLOCK][p] += (d / 100.0).powi(2);
    }
    let pane = (cw as u32 * PX, ch as u32 * PX);
    let (gap, legend_h) = (20u32, 30 + 22 * names.len().div_ceil(4) as u32);
    let mut img = RgbImage::from_pixel(2 * pane.0 + 3 * gap, pane.1 + 2 * gap + legend_h + 20, Rgb([255, 255, 255]));
    let font = ab_glyph::FontRef::try_from_slice(FONT).expect("font");
    let (ox2, oy) = (2 * gap + pane.0, gap + 20);
    for row in 0..ch {
        for col in 0..cw {
            let Some(k) = c.held_index(col, row) else { continue };
            let masked = !c.mask.data[k];
            let t = c.twi.data[k];
            let left = if masked { [200, 200, 200] } else if t < t1 { [205, 170, 110] } else if t < t2 { [235, 232, 200] } else { [80, 140, 210] };
            let b = &ba[(row / BLOCK) * bw + col / BLOCK];
            let (best, v) = b.iter().enumerate().fold((0, 0.0), |m, (p, &v)| if v > m.1 { (p, v) } else { m });
            let right = if masked { [200, 200, 200] } else if v <= 0.0 { [250, 250, 250] } else { sylva::output::plot::SPECIES_PALETTE[best % sylva::output::plot::SPECIES_PALETTE.len()] };
            for dy in 0..PX {
                for dx in 0..PX {
                    img.put_pixel(gap + col as u32 * PX + dx, oy + row as u32 * PX + dy, Rgb(left));
                    img.put_pixel(ox2 + col as u32 * PX + dx, oy + row as u32 * PX + dy, Rgb(right));
                }
            }
        }
    }
    let text = |img: &mut RgbImage, x: u32, y: u32, s: &str| sylva::output::maps::draw_text(img, &font, x as f32, y as f32, 14.0, s);
    text(&mut img, gap, 4, &format!("TWI terciles: < {t1:.1} ridges (tan), {t1:.1}-{t2:.1}, > {t2:.1} coves (blue)"));
    text(&mut img, ox2, 4, &format!("species with the most basal area per {0} x {0} cells", BLOCK));
    let ly = oy + pane.1 + 12;
    for (p, n) in names.iter().enumerate() {
        let (x, y) = (gap + (p % 4) as u32 * 230, ly + (p / 4) as u32 * 22);
        let col = sylva::output::plot::SPECIES_PALETTE[p % sylva::output::plot::SPECIES_PALETTE.len()];
        for dy in 0..14 {
            for dx in 0..14 {
                img.put_pixel(x + dx, y + dy, Rgb(col));
            }
        }
        text(&mut img, x + 20, y, n);
    }
    img.save(out).expect("png");
}
