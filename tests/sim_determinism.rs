//! Determinism: byte-identical inventories with 1 and 2 threads; checkpoint/resume gives the
//! same final state as an uninterrupted run.
mod common;
use sylva::output::inventory::inventory_csv;
use sylva::job::run::{run_scenario, RunOptions};
use sylva::sim::{fixtures, Scenario, TerrainSpec};

/// Birch seed rain and beech seed trees on a 100 m × 75 m flat site, 40 years.
fn sc_text() -> String {
    common::ScenarioToml::new("det", 40, 5)
        .line("snapshot_every = 20")
        .line("checkpoint_every = 15")
        .uniform(4, 3, 25.0, 300.0)
        .seed_rain("birch", 1500.0)
        .seed_sources("beech", &[[20.0, 20.0], [80.0, 50.0]], 3)
        .build()
}

fn inventory_with_threads(n: usize) -> String {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    pool.install(|| {
        let (sc, mut w) = common::world(&sc_text());
        common::run(&sc, &mut w, 40);
        inventory_csv(&w)
    })
}

#[test]
fn same_inventory_with_one_and_two_threads() {
    let a = inventory_with_threads(1);
    let b = inventory_with_threads(2);
    assert!(a.lines().count() > 100, "too few trees to be a meaningful test: {}", a.lines().count());
    assert!(a == b, "inventories differ between 1 and 2 threads");
}

fn site(sc: &Scenario) -> sylva::conditions::SiteConditions {
    let TerrainSpec::Uniform(u) = sc.terrain_spec() else { panic!() };
    sylva::conditions::SiteConditions::uniform(u.width, u.height, u.cell_m, u.elevation_m, u.indices, sc.climate.latitude_deg)
}

#[test]
fn resume_equals_uninterrupted() {
    let lib = fixtures::library();
    let sc = Scenario::from_toml_str(&sc_text(), "det").unwrap();
    let full_dir = tempfile::tempdir().unwrap();
    let full = run_scenario(&sc, site(&sc), &lib, RunOptions::new(full_dir.path())).unwrap();
    // interrupted run: stop after year 17 (checkpoints at 15 and on stop)
    let dir = tempfile::tempdir().unwrap();
    let (stopped, resumed) = common::run_stopped_and_resumed(&sc, || site(&sc), &lib, dir.path(), 16);
    assert_eq!(stopped, 17, "stops after the year in which the flag was set");
    assert_eq!(resumed.world.stand.year, 40);
    assert_eq!(resumed.world.stand.trees, full.world.stand.trees, "tree store differs after resume");
    assert!(!full.world.stand.cohorts.is_empty(), "the run should have a regeneration layer");
    assert_eq!(resumed.world.stand.cohorts, full.world.stand.cohorts, "regeneration cohorts differ after resume");
    assert_eq!(resumed.world.tallies.regen_ledger, full.world.tallies.regen_ledger, "regeneration ledger differs after resume");
    assert_eq!(resumed.rows, full.rows);
    for f in ["stand_table.csv", "inventory/year_0040.parquet", "inventory/year_0040.gpkg", "inventory/year_0040_regeneration.parquet"] {
        let a = std::fs::read(full_dir.path().join(f)).unwrap();
        let b = std::fs::read(dir.path().join(f)).unwrap();
        assert!(a == b, "{f} differs");
    }
    assert!(dir.path().join("stand_table.png").exists() && dir.path().join("maps/species_year_0040.png").exists());
}

/// The growth factors cached in the tree store (drawn when a tree first grows, kept through
/// mortality's compaction and regeneration's appends) are every tree's own
/// `growth_factor(seed, id)`: a misaligned cache would give trees each other's factors.
#[test]
fn cached_growth_factors_belong_to_their_trees() {
    let (sc, mut w) = common::world(&sc_text());
    common::run(&sc, &mut w, 30);
    let t = &w.stand.trees;
    assert_eq!(t.growth_factor.0.len(), t.len());
    let mut drawn = 0;
    for (i, g) in t.growth_factor.0.iter().enumerate() {
        if !g.is_nan() {
            assert_eq!(g.to_bits(), sylva::sim::phases::growth::growth_factor(sc.seed, t.id[i]).to_bits(), "tree {i} (id {})", t.id[i]);
            drawn += 1;
        }
    }
    // most trees have grown in diameter at least once, and deaths have compacted the store
    assert!(drawn > t.len() / 2, "{drawn} of {}", t.len());
    assert!(w.tallies.deaths_total.iter().sum::<u64>() > 0, "no tree died: the compaction is untested");
}
