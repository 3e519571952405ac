//! The size estimates a run makes before it starts (round 46, after round 45's fine seed grids):
//! the memory of a site (`Scenario::site_memory_bytes`, the refusal of a site the machine cannot
//! hold) against peak memory measured with `/usr/bin/time -v sylva simulate`, and the
//! checkpoint's bytes (`job::disk::checkpoint_bytes`, part of the disk estimate) against a real
//! checkpoint written by `job::checkpoint::save`.

mod common;
use sylva::job::disk::checkpoint_bytes;
use sylva::sim::Scenario;

/// A uniform site of `n × n` 10 m cells with `species`, one year (the measured scenarios of
/// BENCHMARKS.md round 46).
fn uniform(n: usize, species: &[&str]) -> Scenario {
    let toml = format!(
        "name = \"u\"\nseed = 1\nyears = 1\nsnapshot_every = 0\ncheckpoint_every = 0\nspecies = {species:?}\n[terrain.uniform]\nwidth = {n}\nheight = {n}\ncell_m = 10.0\nelevation_m = 300.0\nindices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0]\n[[start]]\nkind = \"seed_rain\"\nspecies = \"silver_birch\"\nseeds_per_ha = 10.0\n"
    );
    Scenario::from_toml_str(&toml, "u").unwrap()
}

/// The memory estimate is within 5 % of the peak memory of `sylva simulate` on uniform sites of
/// 1 and 4 million 10 m cells with two species and with the default scenario's eight (release
/// binary of main 4f37a58, round 46: 233,224 / 671,456 kB and 396,036 / 1,181,296 kB); the
/// seed grids of round 45's fine cells make a species cost about 20 bytes a cell, which the
/// estimate of rounds 26–45 (150 bytes a cell whatever the species) missed: it put the
/// eight-species site of 4 million cells at 0.67 GB against 1.21 GB.
#[test]
fn the_site_memory_estimate_follows_the_measured_peaks() {
    let two = ["beech", "silver_birch"];
    let eight = ["beech", "silver_birch", "sessile_oak", "norway_maple", "sycamore", "norway_spruce", "black_alder", "scots_pine"];
    for (n, species, kb) in [(1000, &two[..], 233_224.0), (2000, &two[..], 671_456.0), (1000, &eight[..], 396_036.0), (2000, &eight[..], 1_181_296.0)] {
        let sc = uniform(n, species);
        let est = sc.site_memory_bytes().unwrap() as f64;
        let measured = kb * 1024.0;
        eprintln!("{n} x {n}, {} species: estimate {:.0} MB, measured {:.0} MB", species.len(), est / 1e6, measured / 1e6);
        assert!((est / measured - 1.0).abs() < 0.05, "{n} x {n} cells, {} species: {est} B against {measured} B", species.len());
        // and the refusal uses it
        assert!(sc.check_site_memory(est as u64).is_ok() && sc.check_site_memory(est as u64 - 1).is_err());
    }
    // a coarser cell holds more fine seed cells: 20 m cells cost 4 times the seed grids of 10 m
    let coarse = Scenario::from_toml_str(&format!("name = \"c\"\nseed = 1\nyears = 1\nspecies = {eight:?}\n[terrain.uniform]\nwidth = 1000\nheight = 1000\ncell_m = 20.0\nelevation_m = 300.0\nindices = [5.0, 5.0, 2.0, 5.0, 6.0, 6.0]\n"), "c").unwrap();
    let fine = uniform(1000, &eight);
    let per_cell = |s: &Scenario| (s.site_memory_bytes().unwrap() - 70_000_000 - 8 * 8_000_000) as f64 / 1e6;
    assert!((per_cell(&coarse) - (110.0 + 4.0 * 160.0)).abs() < 1e-6 && (per_cell(&fine) - 270.0).abs() < 1e-6, "{} {}", per_cell(&coarse), per_cell(&fine));
}

/// A mixed stand of four species on 5.8 ha (mature enough to seed: its seed grids fill, and
/// cohorts establish under it) run 6 years and checkpointed: the file is within ±25 % of
/// `checkpoint_bytes` of its trees, seed cells, light cells and species (1.12 when written); the
/// estimate of rounds 42–45 (coarse seed grids) gives 0.52 of it.
#[test]
fn the_checkpoint_estimate_is_within_a_quarter_of_a_real_checkpoint() {
    let mut toml = common::ScenarioToml::new("ckpt_size", 6, 3).species(&["beech", "sessile_oak", "norway_maple", "silver_birch"]).uniform(24, 24, 10.0, 300.0).build();
    for (i, sp) in ["beech", "sessile_oak", "norway_maple", "silver_birch"].iter().enumerate() {
        let (x0, y0) = ((i % 2) as f64 * 120.0, (i / 2) as f64 * 120.0);
        toml += &format!("[[start]]\nkind = \"planted\"\nspecies = {sp:?}\nspacing_m = 7.0\nage_yr = 60.0\narea = [{x0:?}, {y0:?}, {:?}, {:?}]\n", x0 + 120.0, y0 + 120.0);
    }
    let (sc, mut w) = common::world_with(&toml, &common::embedded());
    let rows = common::run(&sc, &mut w, sc.years);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.bin");
    sylva::job::checkpoint::save(&path, &w, &rows).unwrap();
    let actual = std::fs::metadata(&path).unwrap().len() as f64;
    let trees = w.stand.trees.len() as f64;
    let seed_cells: f64 = w.stand.seeds.iter().map(|g| g.data.len() as f64).sum();
    let filled = w.stand.seeds.iter().flat_map(|g| g.data.iter()).filter(|&&v| v > 0.0).count() as f64 / seed_cells;
    let (cells, np) = (w.site.light.len() as f64, w.site.pool.len() as f64);
    let est = checkpoint_bytes(trees, seed_cells, cells, np);
    eprintln!("checkpoint {actual:.0} B, estimate {est:.0} B ({trees} trees, {} cohorts, {seed_cells} seed cells of which {:.0} % with seeds, {cells} light cells, {np} species): ratio {:.2}", w.stand.cohorts.len(), 100.0 * filled, est / actual);
    assert!(filled > 0.5, "the seed grids fill: {filled}");
    assert!((est / actual - 1.0).abs() <= 0.25, "estimate {est:.0} B against {actual:.0} B");
    // round 45's estimate (34 bytes a tree, half a byte a light cell and species for the seeds
    // and cohorts of the coarse grids) falls short by more than a quarter
    let old = 4096.0 + trees * 34.0 + cells * np * 0.5;
    assert!(old < 0.75 * actual, "round 45's estimate {old:.0} B against {actual:.0} B");
}
