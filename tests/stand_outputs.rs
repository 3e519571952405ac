//! What a forester needs from a run's tables (round 42, trial 41's open defects 1, 2, 7, 14):
//! the per-species stand table adds up to the stand table and starts with year 0, the planted
//! state; the natural deaths' volume is written so gross total production can be summed; a
//! thinning's `max_removal_share` caps what one entry removes and the management table says
//! so; the disk estimate a run prints before it starts is within a factor of 2 of what the run
//! writes.
mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use sylva::job::run::{run_scenario, RunOptions, RunSummary};
use sylva::sim::stats::StandRow;
use sylva::sim::trees::DeathCause;
use sylva::sim::{step_year, Scenario, World, YearReport};

/// 1 ha: beech planted at 1.5 m aged 30 on the southern half, birch at 2 m aged 20 on the
/// northern; a thinning from below in year 6; 12 years, snapshots every 6.
fn mixed_toml() -> String {
    let head = common::ScenarioToml::new("mixed", 12, 5).species(&["beech", "silver_birch"]).line("snapshot_every = 6").line("checkpoint_every = 0").uniform(5, 5, 20.0, 200.0).build();
    head + "[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 1.5\nage_yr = 30.0\narea = [0.0, 0.0, 100.0, 50.0]\n\
             [[start]]\nkind = \"planted\"\nspecies = \"silver_birch\"\nspacing_m = 2.0\nage_yr = 20.0\narea = [0.0, 50.0, 100.0, 100.0]\n\
             [[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_relative_density = 0.5\nyears = [6]\n"
}

struct Run {
    _tmp: tempfile::TempDir,
    dir: PathBuf,
    start: World,
    summary: RunSummary,
    estimate: sylva::job::disk::DiskEstimate,
}

/// The mixed stand run once into a temporary folder, with the world it started from and the
/// disk estimate made for it.
fn run() -> &'static Run {
    static RUN: OnceLock<Run> = OnceLock::new();
    RUN.get_or_init(|| {
        let (sc, start) = common::world_with(&mixed_toml(), &common::embedded());
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let estimate = sylva::job::run::disk_estimate(&sc, &start, &RunOptions::new(&dir));
        let summary = run_scenario(&sc, sc.site().unwrap(), &common::embedded(), RunOptions::new(&dir)).unwrap();
        Run { _tmp: tmp, dir, start, summary, estimate }
    })
}

/// A CSV file as its header and rows of fields.
fn read_csv(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap().split(',').map(String::from).collect();
    (head, lines.map(|l| l.split(',').map(String::from).collect()).collect())
}

fn col(head: &[String], name: &str) -> usize {
    head.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name} in {head:?}"))
}

/// The per-species rows add up to the stand table's stems, basal area and volume in every year
/// (within the printed rounding), their natural deaths' and harvest volumes to the stand table's
/// `deaths_volume_m3_ha` and `harvest_volume_m3_ha`; both tables start with year 0, the planted
/// state; each species' top height is the mean height of its 100 thickest stems per ha.
#[test]
fn the_species_table_adds_up_to_the_stand_table_from_year_0() {
    let r = run();
    let (sh, st) = read_csv(&r.dir.join("stand_table.csv"));
    let (ph, sp) = read_csv(&r.dir.join("stand_table_species.csv"));
    assert_eq!(st.len(), 13, "years 0–12");
    assert_eq!(sp.len(), 2 * 13, "two species a year");
    assert_eq!(sh[sh.len() - 2..], ["deaths_volume_m3_ha", "stems"]);
    // year 0: the planted trees, before any growth
    let y0 = r.summary.year0.as_ref().expect("a year-0 row");
    let t = &r.start.stand.trees;
    let stems0 = (0..t.len()).filter(|&i| t.height[i] >= 1.3).count() as f64;
    assert!(stems0 > 3000.0 && y0.year == 0 && (y0.stems_ha - stems0).abs() < 1e-9, "{} stems/ha at year 0, {stems0} planted", y0.stems_ha);
    assert_eq!(st[0][0], "0");
    assert_eq!(y0, &sylva::sim::stats::stand_row(&r.start));
    let f = |row: &[String], k: usize| row[k].parse::<f64>().unwrap();
    let mut natural_total = 0.0;
    for (k, s) in st.iter().enumerate() {
        let year = &s[0];
        let rows: Vec<&Vec<String>> = sp.iter().filter(|p| &p[0] == year).collect();
        assert_eq!(rows.len(), 2);
        assert_eq!((rows[0][1].as_str(), rows[1][1].as_str()), ("beech", "silver_birch"));
        for (a, b, tol) in [("stems_ha", "stems_ha", 0.11), ("basal_area_m2_ha", "basal_area_m2_ha", 0.0011), ("volume_m3_ha", "volume_m3_ha", 0.011), ("deaths_volume_m3_ha", "deaths_volume_m3_ha", 0.011), ("harvest_volume_m3_ha", "harvest_volume_m3_ha", 0.011), ("harvest_stems_ha", "harvest_stems_ha", 0.11)] {
            let sum: f64 = rows.iter().map(|p| f(p, col(&ph, b))).sum();
            let whole = f(s, col(&sh, a));
            assert!((sum - whole).abs() <= tol, "year {year}: the species' {b} sum to {sum}, the stand table's {a} is {whole}");
        }
        // the deaths by cause add up to their natural and harvest columns
        for p in &rows {
            let by_cause: Vec<f64> = DeathCause::ALL.iter().map(|c| f(p, col(&ph, &format!("deaths_{}_volume_m3_ha", c.name())))).collect();
            let natural: f64 = by_cause[..by_cause.len() - 1].iter().sum();
            assert!((natural - f(p, col(&ph, "deaths_volume_m3_ha"))).abs() <= 0.011 * 4.0, "{p:?}");
            assert!((by_cause[DeathCause::Harvest.index()] - f(p, col(&ph, "harvest_volume_m3_ha"))).abs() < 1e-9, "{p:?}");
        }
        natural_total += f(s, col(&sh, "deaths_volume_m3_ha"));
        if k == 6 {
            assert!(f(s, col(&sh, "harvest_volume_m3_ha")) > 1.0, "the thinning of year 6 removed volume: {s:?}");
        }
    }
    assert!(natural_total > 0.0, "trees of 7 cm or more died in 12 years of a dense planting");
    // each species' top height: the mean height of its 100 thickest stems (1 ha)
    let w = &r.summary.world;
    let last = r.summary.rows.last().unwrap();
    for (p, &sid) in w.site.pool.iter().enumerate() {
        let t = &w.stand.trees;
        let mut own: Vec<(f32, f32)> = (0..t.len()).filter(|&i| t.species[i] == sid && t.height[i] >= 1.3).map(|i| (t.dbh[i], t.height[i])).collect();
        own.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.total_cmp(&a.1)));
        let h100 = own[..100].iter().map(|x| x.1 as f64).sum::<f64>() / 100.0;
        let got = last.species[p].top_height_m;
        assert!((got - h100).abs() < 1e-6, "species {p}: H100 {got} against {h100} by a sort");
        let dq = (own.iter().map(|x| (x.0 as f64).powi(2)).sum::<f64>() / own.len() as f64).sqrt();
        assert!((last.species[p].qmd_cm - dq).abs() < 1e-6, "species {p}: Dq {} against {dq}", last.species[p].qmd_cm);
    }
    // no management-table row for year 0
    let (_, mt) = read_csv(&r.dir.join("management_table.csv"));
    assert_eq!(mt[0][0], "1", "{mt:?}");
}

/// The estimate made before the run is within a factor of 2 of what the run wrote.
#[test]
fn the_disk_estimate_is_within_a_factor_of_2_of_the_runs_files() {
    let r = run();
    let actual: u64 = common::files(&r.dir).values().map(|v| v.len() as u64).sum();
    let est = r.estimate.total();
    let ratio = est / actual as f64;
    eprintln!("estimate {est:.0} B ({:?}), written {actual} B: ratio {ratio:.2}", r.estimate);
    assert!((0.5..=2.0).contains(&ratio), "estimate {est:.0} B against {actual} B written ({ratio:.2}): {:?}", r.estimate);
    assert_eq!(r.estimate.snapshots, 3, "years 0, 6 and 12");
}

/// A 1 ha beech stand planted at 1.5 m, aged 30; `extra` appended.
fn beech(extra: &str) -> (Scenario, World) {
    common::world_with(&(common::ScenarioToml::new("cap", 1, 7).species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 1.5, 30.0).build() + extra), &common::embedded())
}

/// The harvested basal area (m²) of the year just stepped.
fn harvested_ba(w: &World) -> f64 {
    w.scratch.dead.iter().filter(|d| d.cause == DeathCause::Harvest).map(|d| std::f64::consts::FRAC_PI_4 * (d.dbh as f64 / 100.0).powi(2)).sum()
}

/// A thinning from below to half the basal area removes, with `max_removal_share = 0.2`, at
/// most a fifth of the main stand's basal area (and no less than a fifth less one tree's), stops
/// short of its target, and says so in the management table (`capped`) and the log; without
/// the cap it removes far more. A bad share is refused naming the field.
#[test]
fn a_removal_cap_stops_a_thinning_at_its_share_of_basal_area() {
    let thin = |cap: &str| format!("[[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_basal_area_m2_ha = 15.0\nyears = [1]\n{cap}");
    let step = |extra: &str| -> (World, YearReport) {
        let (sc, mut w) = beech(extra);
        let mut rep = YearReport::default();
        step_year(&mut w, &sc, &mut rep);
        (w, rep)
    };
    let (free, rep_free) = step(&thin(""));
    let (capped, rep) = step(&thin("max_removal_share = 0.2\n"));
    let row: &StandRow = rep.row.as_ref().unwrap();
    let free_row = rep_free.row.as_ref().unwrap();
    assert!(!free_row.management[0].capped && row.management[0].capped, "{:?}", row.management);
    // the note names the removed and the main stand's basal area
    let note = rep.notes.iter().find(|n| n.contains("max_removal_share")).unwrap_or_else(|| panic!("no note: {:?}", rep.notes));
    let seg = note.split(" m² basal area removed").next().unwrap().rsplit('(').next().unwrap();
    let (removed, base) = seg.split_once(" of ").map(|(a, b)| (a.parse::<f64>().unwrap(), b.parse::<f64>().unwrap())).unwrap_or_else(|| panic!("{note}"));
    let cut = harvested_ba(&capped);
    let largest = capped.scratch.dead.iter().map(|d| std::f64::consts::FRAC_PI_4 * (d.dbh as f64 / 100.0).powi(2)).fold(0.0, f64::max);
    assert!((cut - removed).abs() < 1e-3, "the note's {removed} m² against {cut} m² harvested");
    assert!(cut <= 0.2 * base + 1e-9 && cut > 0.2 * base - largest - 1e-3, "removed {cut:.3} m² of {base:.3} m²: not the cap's fifth");
    assert!((row.management[0].harvest_basal_area_m2_ha - cut).abs() < 1e-3, "1 ha: the table's {} m²/ha", row.management[0].harvest_basal_area_m2_ha);
    assert!(row.basal_area_m2_ha > 15.5, "stopped short of the target: {}", row.basal_area_m2_ha);
    let free_cut = harvested_ba(&free);
    assert!(free_cut > 1.5 * cut && free_row.basal_area_m2_ha < 15.5, "without the cap {free_cut:.2} m² removed, to {:.2} m²/ha", free_row.basal_area_m2_ha);
    let names: Vec<&str> = capped.site.pool.iter().map(|&p| capped.site.lib.species[p as usize].id.as_str()).collect();
    let table = sylva::output::stand_table::management_table_csv(&[row.clone()], &names);
    assert!(table.lines().next().unwrap().ends_with(",capped,planted_ha,seedlings_ha") && table.lines().nth(1).unwrap().contains(",true,"), "{table}");
    // refused: 0, above 1, on a harvest
    for (extra, want) in [(thin("max_removal_share = 0.0\n"), "a share of the basal area > 0 and ≤ 1"), (thin("max_removal_share = 1.5\n"), "a share of the basal area > 0 and ≤ 1"), ("[[management]]\nkind = \"harvest\"\nmethod = \"clear_cut\"\nyears = [1]\nmax_removal_share = 0.2\n".to_string(), "only with kind = \"thinning\"")] {
        let toml = common::ScenarioToml::new("cap", 1, 7).species(&["beech"]).uniform(5, 5, 20.0, 200.0).planted("beech", 1.5, 30.0).build() + &extra;
        let e = Scenario::from_toml_str(&toml, "cap.toml").map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("cap.toml") && e.contains("management[0].max_removal_share") && e.contains(want), "{e}");
    }
}

/// Trial 46 D6: the stand table's last column `stems` is the site's count of trees ≥ 1.3 m, so
/// the tree balance `stems(t) = stems(t−1) + regen_recruited(t) − Σ deaths_*(t)` closes exactly
/// from the table alone in every year (no planting here: the starts are planted before year 0),
/// and it equals `stems_ha · area_ha` and the run's living trees at the end. Before, the
/// table had only `stems_ha` rounded to 0.1, which missed the balance by up to 28 trees.
#[test]
fn the_stand_table_closes_the_tree_balance_with_its_site_total_stems() {
    let r = run();
    let (sh, st) = read_csv(&r.dir.join("stand_table.csv"));
    let v = |row: &[String], name: &str| -> f64 { row[col(&sh, name)].parse().unwrap() };
    let deaths: Vec<String> = DeathCause::ALL.iter().map(|c| format!("deaths_{}", c.name())).collect();
    let (mut died, mut thinned) = (0.0, 0.0);
    for k in 1..st.len() {
        let (prev, row) = (&st[k - 1], &st[k]);
        let d: f64 = deaths.iter().map(|c| v(row, c)).sum();
        died += d;
        thinned += v(row, "deaths_harvest");
        let want = v(prev, "stems") + v(row, "regen_recruited") - d;
        assert_eq!(v(row, "stems"), want, "year {}: {} stems, {} + {} recruited − {d} dead", v(row, "year"), v(row, "stems"), v(prev, "stems"), v(row, "regen_recruited"));
        // the per-hectare figure, rounded to 0.1, is the same count over the area
        assert!((v(row, "stems_ha") * v(row, "area_ha") - v(row, "stems")).abs() <= 0.05 * v(row, "area_ha") + 1e-6, "year {}", v(row, "year"));
    }
    assert!(died > thinned && thinned > 0.0, "the balance is tested on natural deaths ({died} in all) and a thinning ({thinned})");
    // every tree of this run stands 1.3 m or more (planted at 20 and 30 years, recruits enter
    // taller), so the living trees at the end are its stems
    assert_eq!(v(st.last().unwrap(), "stems"), r.summary.trees as f64, "the last year's stems against the run's living trees");
}
