//! Tiled runs (issue 17): the landscape cut into tiles with halos, each tile stepped by its own
//! thread over the in-process transport (`sim::tiles::run_local`), ends byte-identical to one
//! process: the checkpoint bytes (trees, cohorts, seeds, tallies, stand table) and the
//! inventory (with this year's dead) are compared.
mod common;
use sylva::output::inventory::inventory_csv;
use sylva::sim::checkpoint::to_bytes;
use sylva::sim::stats::StandRow;
use sylva::sim::tiles::{Transport as _, min_halo_m, run_local, Layout, Tile};
use sylva::sim::{Scenario, World};

const YEARS: u32 = 25;

/// Beech seed trees on a flat 400 m × 240 m site (10 m light cells: 40 × 24), sources at and
/// near the boundaries of 2, 3, 5 and 2 × 2 tiles (x = 200, 133, 160, 240; y = 120).
fn edges() -> String {
    common::ScenarioToml::new("tiles", YEARS, 7)
        .species(&["beech"])
        .line("light_cell_m = 10.0")
        .uniform(20, 12, 20.0, 300.0)
        .seed_sources("beech", &[[198.0, 118.0], [203.0, 60.0], [134.0, 200.0], [161.0, 30.0], [241.0, 122.0], [60.0, 200.0]], 3)
        .build()
}

fn one_process(toml: &str, years: u32) -> (Scenario, World, Vec<StandRow>) {
    let (sc, mut w) = common::world(toml);
    let rows = common::run(&sc, &mut w, years);
    (sc, w, rows)
}

/// Asserts that the tiled run `nx × ny` of `toml` equals one process after `years`.
fn assert_tiles_equal(toml: &str, nx: usize, ny: usize, years: u32, one: &(Scenario, World, Vec<StandRow>)) {
    let (_, w0) = common::world(toml);
    let layout = Layout::new(&w0.site, nx, ny).unwrap();
    let (w, rows, bytes) = run_local(&w0, &layout, years).unwrap();
    assert_eq!(rows.len(), years as usize);
    assert_eq!(rows, one.2, "{nx} × {ny} tiles: stand table differs");
    assert_eq!(w.stand.trees, one.1.stand.trees, "{nx} × {ny} tiles: trees differ");
    assert_eq!(w.stand.cohorts, one.1.stand.cohorts, "{nx} × {ny} tiles: cohorts differ");
    assert!(w.stand.seeds == one.1.stand.seeds, "{nx} × {ny} tiles: seed grids differ");
    assert!(inventory_csv(&w) == inventory_csv(&one.1), "{nx} × {ny} tiles: inventories differ");
    assert!(to_bytes(&w, &rows) == to_bytes(&one.1, &one.2), "{nx} × {ny} tiles: checkpoints differ");
    // the tiles did exchange halo copies
    assert!(bytes.iter().sum::<u64>() > 0, "{nx} × {ny}: no bytes exchanged");
}

#[test]
fn two_three_five_and_2x2_tiles_equal_one_process() {
    let toml = edges();
    let one = one_process(&toml, YEARS);
    let w = &one.1;
    // a meaningful run: recruits (birth ids above 2^44), deaths, cohorts, and a halo narrower
    // than the site, so tiles do not simply hold every tree
    let recruits = w.stand.trees.id.iter().filter(|&&id| id >= 1 << 44).count();
    assert!(recruits > 50, "only {recruits} recruits");
    assert!(w.stand.trees.len() > 100 && !w.stand.cohorts.is_empty());
    assert!(w.tallies.deaths_total.iter().sum::<u64>() > 0);
    let halo = min_halo_m(&w.site);
    assert!(halo == 100.0, "beech's 60 m kernel on 20 m seed cells: (3 + 2) × 20 m, got {halo}");
    for (nx, ny) in [(2, 1), (3, 1), (5, 1), (2, 2)] {
        assert_tiles_equal(&toml, nx, ny, YEARS, &one);
    }
}

#[test]
fn a_seed_kernel_crossing_two_tiles() {
    // 10 tiles of 40 m across; one seed tree near x = 198 m, y = 120 m: beech's 60 m kernel
    // reaches from tile 3 (120–160 m) to tile 6 (240–280 m)
    let toml = common::ScenarioToml::new("kernel", 6, 11).species(&["beech"]).line("light_cell_m = 10.0").uniform(20, 12, 20.0, 300.0).seed_sources("beech", &[[198.0, 120.0]], 1).build();
    let one = one_process(&toml, 6);
    let g = &one.1.stand.seeds[0];
    let seeded_x: Vec<f64> = (0..g.cols).filter(|&c| (0..g.rows).any(|r| g.data[r * g.cols + c] > 0.0)).map(|c| (c as f64 + 0.5) * g.cell_m).collect();
    let (lo, hi) = (seeded_x[0], seeded_x[seeded_x.len() - 1]);
    assert!(lo < 160.0 && hi > 240.0, "seeds from {lo} to {hi} m: the kernel should cross two tile edges each way");
    let (_, w0) = common::world(&toml);
    let layout = Layout::new(&w0.site, 10, 1).unwrap();
    // the seeds of the one source land on at least four tiles: the kernel crosses two tile edges
    // or more on one side of the source's tile
    let (src, west, east) = (layout.owner_of(w0.stand.trees.x[0], w0.stand.trees.y[0]), layout.owner_of(lo as f32, 120.0), layout.owner_of(hi as f32, 120.0));
    assert_eq!(w0.stand.trees.len(), 1);
    assert!(east - west >= 3 && (src - west >= 2 || east - src >= 2), "source on tile {src}, seeds on tiles {west}–{east}");
    assert_tiles_equal(&toml, 10, 1, 6, &one);
}

#[test]
fn a_tile_without_trees() {
    // seed trees only in the west: the eastern of four tiles starts empty
    let toml = common::ScenarioToml::new("empty", 12, 5).species(&["beech"]).line("light_cell_m = 10.0").uniform(20, 12, 20.0, 300.0).seed_sources("beech", &[[40.0, 60.0], [90.0, 180.0]], 3).build();
    let (_, w0) = common::world(&toml);
    let layout = Layout::new(&w0.site, 4, 1).unwrap();
    let east = Tile::new(&w0, layout.clone(), 3).unwrap();
    assert_eq!(east.world.stand.trees.len(), 0, "the eastern tile should start without trees");
    assert!(Tile::new(&w0, layout, 0).unwrap().world.stand.trees.len() > 0);
    let one = one_process(&toml, 12);
    assert_tiles_equal(&toml, 4, 1, 12, &one);
}

/// Issue 37 Build 1 (a): the part of the site that a rank other than 0 derives for tile `k`
/// from a skeleton of the scenario's world (`World::skeleton`, `tiles::derive_tile_site`; no
/// whole-site grid derived, no start trees) equals, bit for bit, the tile `Tile::own` cuts from
/// the world of one process: every conditions grid, the relative insolation, suitability, light
/// cells' arrays, seed windows, identity, area, management and the checkpoint bytes; the
/// median from the ranks' bands (`layout_by` over a `LocalTransport`) is `World::new`'s.
fn assert_derived_tiles_equal_cut_tiles(toml: &str, nx: usize, ny: usize) {
    let (sc, w0) = common::world(toml);
    let lib = sylva::sim::fixtures::library();
    let layout = Layout::new(&w0.site, nx, ny).unwrap();
    let n = layout.len();
    let want = sylva::sim::world::insolation_median_by(&w0.site.conditions.insolation_kwh_m2, &w0.site.conditions.mask, &mut sylva::sim::select::alone).unwrap();
    // the ranks' bands select the median with each other (the weights' layout: tested below)
    let medians: Vec<f32> = std::thread::scope(|s| {
        let hs: Vec<_> = sylva::sim::tiles::LocalTransport::group(n)
            .into_iter()
            .map(|mut t| {
                let (sc, lib) = (&sc, &lib);
                s.spawn(move || sylva::job::tiled::layout_by(&World::skeleton(sc.site().unwrap(), lib, sc).unwrap(), &mut t).unwrap().1)
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(medians.iter().all(|m| m.to_bits() == want.to_bits()), "{medians:?} vs {want}");
    for k in 0..n {
        let owned = Tile::own(w0.clone(), layout.clone(), k).unwrap();
        let mut w = World::skeleton(sc.site().unwrap(), &lib, &sc).unwrap();
        assert!(w.site.light_site.is_empty() && w.site.rel_insolation.is_empty() && w.stand.seeds.is_empty() && w.stand.trees.is_empty());
        sylva::sim::tiles::derive_tile_site(&mut w, &sc, &layout, k, medians[k]).unwrap();
        // the start's trees come from rank 0's scatter: compare the site and the empty stand
        let mut o = owned.world;
        o.stand.trees = Default::default();
        o.stand.trees.next_id = w.stand.trees.next_id;
        o.stand.cohorts = Default::default();
        let d = Tile::own(w, layout.clone(), k).unwrap().world;
        let (a, b) = (&d.site, &o.site);
        let (ca, cb) = (&a.conditions, &b.conditions);
        let what = format!("tile {k} of {nx} × {ny}");
        assert_eq!((ca.held, ca.full, &ca.mask), (cb.held, cb.full, &cb.mask), "{what}");
        for (x, y) in [(&ca.slope_deg, &cb.slope_deg), (&ca.aspect_deg, &cb.aspect_deg), (&ca.twi, &cb.twi), (&ca.insolation_kwh_m2, &cb.insolation_kwh_m2), (&ca.temperature_c, &cb.temperature_c), (&ca.elevation_m, &cb.elevation_m), (&ca.wind_exposure, &cb.wind_exposure)] {
            assert!(x.data.iter().map(|v| v.to_bits()).eq(y.data.iter().map(|v| v.to_bits())), "{what}");
        }
        assert!(ca.indices.data.iter().flatten().map(|v| v.to_bits()).eq(cb.indices.data.iter().flatten().map(|v| v.to_bits())), "{what}");
        assert!(a.rel_insolation.iter().chain(a.suitability.iter().flatten()).map(|v| v.to_bits()).eq(b.rel_insolation.iter().chain(b.suitability.iter().flatten()).map(|v| v.to_bits())), "{what}: relative insolation or suitability");
        assert_eq!((&a.light_site, a.window, &a.whole_identity, a.area_ha.to_bits(), &a.obstacle_canopy), (&b.light_site, b.window, &b.whole_identity, b.area_ha.to_bits(), &b.obstacle_canopy), "{what}");
        assert!(a.ground_free.iter().map(|v| v.to_bits()).eq(b.ground_free.iter().map(|v| v.to_bits())), "{what}: ground free");
        assert_eq!((&a.management, &a.seed_rain, &a.pool), (&b.management, &b.seed_rain, &b.pool), "{what}");
        assert_eq!((&d.stand.seeds, &d.scratch.ground_light), (&o.stand.seeds, &o.scratch.ground_light), "{what}");
        assert_eq!(sylva::sim::checkpoint::identity(&d), sylva::sim::checkpoint::identity(&w0), "{what}");
        assert!(sylva::sim::checkpoint::to_bytes(&d, &[]) == sylva::sim::checkpoint::to_bytes(&o, &[]), "{what}: checkpoint bytes");
        // the band weights from the conditions equal those of the derived world of one process
        let band = sylva::sim::tiles::weight_band(k, n, w0.site.light.rows);
        assert_eq!(sylva::sim::tiles::work_weights_of(&w0.site.conditions, &lib, &w0.site.pool, &w0.site.light, band.clone()), sylva::sim::tiles::work_weights_in(&w0.site, band), "{what}");
    }
}

/// Issue 37 Build 1 (a), round 32: ranks other than 0 that hold only their band of site rows
/// (rank 0 the whole site) cut the layout with each other (`layout_by`: the weights from the
/// bands; then `tile_site_by`: each tile's cells plus halo moved from the bands' owners) and derive their
/// tile's part (`tiles::derive_tile_site_with`); each equals, bit for bit, the tile
/// `Tile::own` cuts from the world of one process with `layout_for`'s layout: every
/// conditions grid, the whole site's identity and area, the checkpoint bytes.
fn assert_band_ranks_equal_cut_tiles(toml: &str, n: usize) {
    let (sc, w0) = common::world(toml);
    let lib = sylva::sim::fixtures::library();
    let want = sylva::job::tiled::layout_for(&w0, n).unwrap();
    let got: Vec<_> = std::thread::scope(|s| {
        let hs: Vec<_> = sylva::sim::tiles::LocalTransport::group(n)
            .into_iter()
            .map(|mut t| {
                let (sc, lib) = (&sc, &lib);
                s.spawn(move || {
                    let k = t.rank();
                    let mut site = sc.site().unwrap();
                    if k != 0 {
                        let b = sylva::sim::tiles::weight_band(k, n, site.height());
                        site.hold(sylva::grid::Window { col0: 0, row0: b.start, width: site.width(), height: b.len() });
                    }
                    let mut w = World::skeleton(site, lib, sc).unwrap();
                    let (l, median) = sylva::job::tiled::layout_by(&w, &mut t).unwrap();
                    let c = std::mem::replace(&mut w.site.conditions, sylva::conditions::SiteConditions::uniform(1, 0, 1.0, 0.0, [0.0; 6], 0.0));
                    let whole = k == 0;
                    let c = if whole { std::borrow::Cow::Borrowed(&c) } else { std::borrow::Cow::Owned(c.clone()) };
                    let part = sylva::job::tiled::tile_site_by(c, None, w.site.light.cell_m, &l, &mut t).unwrap();
                    if whole {
                        w.site.conditions = sc.site().unwrap();
                    }
                    assert_eq!(part.is_some(), k != 0, "rank {k}");
                    let ws = part.map(|(c, ws)| {
                        w.site.conditions = c;
                        ws
                    });
                    sylva::sim::tiles::derive_tile_site_with(&mut w, sc, &l, k, median, ws.as_ref()).unwrap();
                    (l, w)
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (k, (l, w)) in got.into_iter().enumerate().skip(1) {
        let what = format!("rank {k} of {n}");
        assert_eq!((l.col_bounds.clone(), l.row_bounds.clone()), (want.col_bounds.clone(), want.row_bounds.clone()), "{what}");
        let mut o = Tile::own(w0.clone(), want.clone(), k).unwrap().world;
        o.stand.trees = Default::default();
        let d = Tile::own(w, want.clone(), k).unwrap().world;
        o.stand.trees.next_id = d.stand.trees.next_id;
        o.stand.cohorts = Default::default();
        let (a, b) = (&d.site, &o.site);
        let (ca, cb) = (&a.conditions, &b.conditions);
        assert_ne!(ca.held, sylva::grid::Window::full(ca.full.0, ca.full.1), "{what}: a tile's window");
        assert_eq!((ca.held, ca.full, &ca.mask, ca.cell_x_m.to_bits(), ca.cell_y_m.to_bits()), (cb.held, cb.full, &cb.mask, cb.cell_x_m.to_bits(), cb.cell_y_m.to_bits()), "{what}");
        for (x, y) in [(&ca.slope_deg, &cb.slope_deg), (&ca.aspect_deg, &cb.aspect_deg), (&ca.twi, &cb.twi), (&ca.insolation_kwh_m2, &cb.insolation_kwh_m2), (&ca.temperature_c, &cb.temperature_c), (&ca.elevation_m, &cb.elevation_m), (&ca.wind_exposure, &cb.wind_exposure)] {
            assert!(x.data.iter().map(|v| v.to_bits()).eq(y.data.iter().map(|v| v.to_bits())), "{what}");
        }
        assert!(ca.indices.data.iter().flatten().map(|v| v.to_bits()).eq(cb.indices.data.iter().flatten().map(|v| v.to_bits())), "{what}");
        assert!(a.rel_insolation.iter().chain(a.suitability.iter().flatten()).map(|v| v.to_bits()).eq(b.rel_insolation.iter().chain(b.suitability.iter().flatten()).map(|v| v.to_bits())), "{what}: relative insolation or suitability");
        assert_eq!((&a.light_site, a.window, &a.whole_identity, a.area_ha.to_bits()), (&b.light_site, b.window, &b.whole_identity, b.area_ha.to_bits()), "{what}");
        assert!(a.whole_identity.is_some(), "{what}");
        assert_eq!(sylva::sim::checkpoint::identity(&d), sylva::sim::checkpoint::identity(&w0), "{what}");
        assert!(sylva::sim::checkpoint::to_bytes(&d, &[]) == sylva::sim::checkpoint::to_bytes(&o, &[]), "{what}: checkpoint bytes");
    }
}

#[test]
fn ranks_holding_their_band_get_their_tiles_cells_from_the_bands_owners() {
    let building = "[[obstacle]]\nkind = \"footprint\"\npoints = [[180.0, 80.0], [225.0, 80.0], [225.0, 150.0], [180.0, 150.0]]\nheight_m = 12.0\n";
    let toml = format!("{}{building}", edges());
    for n in [2, 3, 4] {
        assert_band_ranks_equal_cut_tiles(&toml, n);
    }
    // a window of the default DEM (insolation, wind, indices vary), no management
    let dem = common::ScenarioToml::new("bands", 15, 11)
        .species(&["beech", "birch"])
        .line("light_cell_m = 10.0")
        .default_terrain([150, 150, 12, 10])
        .seed_sources("beech", &[[478.0, 402.0], [485.0, 300.0], [200.0, 600.0]], 3)
        .build();
    let (_, w0) = common::world(&dem);
    assert!(w0.site.rel_insolation.iter().any(|&v| v != w0.site.rel_insolation[0]));
    for n in [2, 4, 6] {
        assert_band_ranks_equal_cut_tiles(&dem, n);
    }
}

#[test]
fn a_rank_derives_only_its_tiles_part_of_the_site() {
    // a building across the tile edges (ground free, obstacle canopy)
    let building = "[[obstacle]]\nkind = \"footprint\"\npoints = [[180.0, 80.0], [225.0, 80.0], [225.0, 150.0], [180.0, 150.0]]\nheight_m = 12.0\n";
    let toml = format!("{}{building}", edges());
    for (nx, ny) in [(2, 1), (3, 1), (2, 2)] {
        assert_derived_tiles_equal_cut_tiles(&toml, nx, ny);
    }
    // a window of the default DEM (insolation, wind, indices vary; beech and birch) with a
    // planting area and a thinning (management resolved against the whole site)
    let dem = common::ScenarioToml::new("held", 15, 11)
        .species(&["beech", "birch"])
        .line("light_cell_m = 10.0")
        .default_terrain([150, 150, 12, 10])
        .seed_sources("beech", &[[478.0, 402.0], [485.0, 300.0], [200.0, 600.0]], 3)
        .build();
    let mgmt = "[[management]]\nkind = \"planting\"\nmix = { beech = 1.0 }\nspacing_m = 4.0\nage_yr = 4.0\nyear = 0\narea = [100.0, 100.0, 500.0, 400.0]\n[[management]]\nkind = \"thinning\"\nmethod = \"from_below\"\ntarget_relative_density = 0.45\nyear = 10\n";
    let toml = format!("{dem}{mgmt}");
    let (_, w0) = common::world(&toml);
    assert!(w0.site.rel_insolation.iter().any(|&v| v != w0.site.rel_insolation[0]) && w0.site.management.len() == 2);
    for (nx, ny) in [(2, 1), (2, 2), (3, 2)] {
        assert_derived_tiles_equal_cut_tiles(&toml, nx, ny);
    }
}

#[test]
fn a_tile_holds_the_light_cells_site_arrays_of_its_own_cells_only() {
    // issue 37 Build 1: the site cell per light cell, the ground free of obstacles and the ground
    // light are held for the tile's rectangle only, in light-cell order; a building across the
    // tile edge at x = 200 m (its ground free of 0 under the roof) and beech regenerating by
    // it: 2 and 2 × 2 tiles end as one process
    let building = "[[obstacle]]\nkind = \"footprint\"\npoints = [[180.0, 80.0], [225.0, 80.0], [225.0, 150.0], [180.0, 150.0]]\nheight_m = 12.0\n";
    let toml = format!("{}{building}", edges());
    let (_, w0) = common::world(&toml);
    let (lg, whole) = (w0.site.light, &w0.site.light_site);
    assert_eq!(whole.len(), lg.len());
    let roofed = w0.site.ground_free.iter().filter(|&&f| f == 0.0).count();
    assert!(roofed > 20, "{roofed} light cells under the roof");
    for (nx, ny) in [(2, 1), (2, 2)] {
        let layout = Layout::new(&w0.site, nx, ny).unwrap();
        let mut held = 0;
        let mut roofed_held = 0;
        for k in 0..layout.len() {
            let r = layout.rect(k);
            let tile = Tile::new(&w0, layout.clone(), k).unwrap();
            let s = &tile.world.site;
            let cells: Vec<usize> = (r.row0..r.row1).flat_map(|row| (r.col0..r.col1).map(move |col| row * lg.cols + col)).collect();
            assert_eq!((s.light_site.len(), s.ground_free.len(), tile.world.scratch.ground_light.len()), (r.len(), r.len(), r.len()), "tile {k} of {nx} × {ny}");
            assert_eq!(s.light_site, cells.iter().map(|&c| whole[c]).collect::<Vec<u32>>(), "tile {k}");
            assert!(s.ground_free.iter().zip(&cells).all(|(f, &c)| f.to_bits() == w0.site.ground_free[c].to_bits()), "tile {k}");
            held += r.len();
            roofed_held += s.ground_free.iter().filter(|&&f| f == 0.0).count();
        }
        assert_eq!((held, roofed_held), (lg.len(), roofed), "{nx} × {ny}: every light cell held by one tile");
    }
    let one = one_process(&toml, YEARS);
    assert!(one.1.stand.cohorts.len() > 50, "{} cohorts", one.1.stand.cohorts.len());
    assert_tiles_equal(&toml, 2, 1, YEARS, &one);
    assert_tiles_equal(&toml, 2, 2, YEARS, &one);
}

#[test]
fn a_tile_holds_the_site_grids_of_its_cells_and_halo_only() {
    // issue 37 Build 1: a tile keeps the site conditions, relative insolation and suitability
    // of the site cells under its light cells plus a halo of SITE_HALO_CELLS, read through
    // offsets; on a window of the default DEM (80 m cells: elevation, wind exposure and indices
    // vary) under a warming climate (the climate phase rewrites the suitability of every cell
    // and tree held every year), with beech and birch seeding in across the tile edges, 2 and
    // 2 x 2 tiles end as one process
    let toml = common::ScenarioToml::new("held", 15, 11)
        .species(&["beech", "birch"])
        .line("light_cell_m = 10.0")
        .line("climate = { warming_k_per_century = 4.0 }")
        .default_terrain([150, 150, 12, 10])
        .seed_sources("beech", &[[478.0, 402.0], [485.0, 300.0], [200.0, 600.0]], 3)
        .seed_sources("birch", &[[470.0, 395.0], [700.0, 420.0]], 3)
        .build();
    let (_, w0) = common::world(&toml);
    let c0 = &w0.site.conditions;
    assert!(c0.holds_all() && (c0.width(), c0.height()) == (12, 10));
    let wind: Vec<u32> = c0.wind_exposure.data.iter().map(|v| v.to_bits()).collect();
    assert!(wind.iter().any(|&v| v != wind[0]), "the window's wind exposure should vary");
    let whole_id = sylva::sim::checkpoint::site_identity(c0);
    let (lg, light_cell) = (w0.site.light, w0.site.light.cell_m);
    for (nx, ny) in [(2, 1), (2, 2)] {
        let layout = Layout::new(&w0.site, nx, ny).unwrap();
        for k in 0..layout.len() {
            let r = layout.rect(k);
            let tile = Tile::new(&w0, layout.clone(), k).unwrap();
            let s = &tile.world.site;
            let c = &s.conditions;
            let h = c.held;
            // the whole site's size, a part of its cells: those under the tile plus the halo
            assert_eq!((c.width(), c.height(), c.extent_m()), (12, 10, c0.extent_m()), "tile {k} of {nx} x {ny}");
            assert!(!c.holds_all() && h.width * h.height < 12 * 10, "tile {k} of {nx} x {ny} holds {h}");
            let under = c0.window_of(r.col0 as f64 * light_cell, r.row0 as f64 * light_cell, r.col1 as f64 * light_cell, r.row1 as f64 * light_cell, 0);
            assert_eq!(h, under.with_halo(sylva::sim::tiles::SITE_HALO_CELLS, 12, 10), "tile {k} of {nx} x {ny}");
            let n = h.width * h.height;
            assert_eq!((c.mask.data.len(), c.indices.data.len(), s.rel_insolation.len()), (n, n, n));
            assert!(s.suitability.iter().all(|v| v.len() == n));
            for row in h.row0..h.row1() {
                for col in h.col0..h.col1() {
                    let (i, g) = (c.held_index(col, row).unwrap(), c0.mask.idx(col, row));
                    assert_eq!(c.held(g), i);
                    assert_eq!((c.mask.data[i], c.elevation_m.data[i].to_bits(), c.wind_exposure.data[i].to_bits(), c.indices.data[i].map(f32::to_bits)), (c0.mask.data[g], c0.elevation_m.data[g].to_bits(), c0.wind_exposure.data[g].to_bits(), c0.indices.data[g].map(f32::to_bits)), "tile {k}, cell ({col}, {row})");
                    assert_eq!(s.rel_insolation[i].to_bits(), w0.site.rel_insolation[g].to_bits());
                    assert!(s.suitability.iter().zip(&w0.site.suitability).all(|(a, b)| a[i].to_bits() == b[g].to_bits()));
                }
            }
            assert_eq!(c.held_index(h.col1(), h.row0), None);
            // every point of the tile's own light cells reads its cell and elevation as the whole site does
            for lc in (r.row0..r.row1).flat_map(|row| (r.col0..r.col1).map(move |col| row * lg.cols + col)) {
                let (x, y) = lg.centre(lc);
                assert_eq!(s.site_cell(x, y), w0.site.site_cell(x, y));
                assert_eq!(c.elevation_at(x + 4.9, y - 4.9).to_bits(), c0.elevation_at(x + 4.9, y - 4.9).to_bits());
            }
            // Tile::new copies only the tile's part of the site (rank 0's tile is made so from
            // the run driver's whole world): the same tile as one cut from a whole copy
            let owned = Tile::own(w0.clone(), layout.clone(), k).unwrap();
            let (o, oc) = (&owned.world.site, &owned.world.site.conditions);
            assert_eq!((h, c.full), (oc.held, oc.full));
            for (a, b) in [(&c.slope_deg, &oc.slope_deg), (&c.aspect_deg, &oc.aspect_deg), (&c.twi, &oc.twi), (&c.insolation_kwh_m2, &oc.insolation_kwh_m2), (&c.temperature_c, &oc.temperature_c), (&c.elevation_m, &oc.elevation_m), (&c.wind_exposure, &oc.wind_exposure)] {
                assert!(a.data.iter().map(|v| v.to_bits()).eq(b.data.iter().map(|v| v.to_bits())), "tile {k} of {nx} x {ny}");
            }
            assert!(s.rel_insolation.iter().chain(s.suitability.iter().flatten()).map(|v| v.to_bits()).eq(o.rel_insolation.iter().chain(o.suitability.iter().flatten()).map(|v| v.to_bits())));
            assert_eq!((&s.light_site, &s.ground_free, s.window, &s.whole_identity), (&o.light_site, &o.ground_free, o.window, &o.whole_identity));
            assert_eq!((&tile.world.stand.seeds, &tile.world.scratch.ground_light), (&owned.world.stand.seeds, &owned.world.scratch.ground_light));
            assert!(tile.world.stand.seeds.iter().all(|g| !g.holds_all()) || layout.len() == 1);
            assert_eq!(sylva::sim::checkpoint::to_bytes(&tile.world, &[]), sylva::sim::checkpoint::to_bytes(&owned.world, &[]), "tile {k} of {nx} x {ny}");
            // the checkpoint identity stays the whole site's
            assert_eq!(s.whole_identity.as_ref(), Some(&whole_id));
            assert_eq!(sylva::sim::checkpoint::identity(&tile.world), sylva::sim::checkpoint::identity(&w0));
        }
    }
    let one = one_process(&toml, 15);
    assert!(one.1.stand.trees.len() > 40 && one.1.stand.cohorts.len() > 50, "{} trees, {} cohorts", one.1.stand.trees.len(), one.1.stand.cohorts.len());
    assert_tiles_equal(&toml, 2, 1, 15, &one);
    assert_tiles_equal(&toml, 2, 2, 15, &one);
}

#[test]
fn a_too_narrow_halo_is_refused_and_would_differ() {
    let toml = edges();
    let (_, w0) = common::world(&toml);
    let e = Layout::with_halo(&w0.site, 2, 1, 20.0).unwrap_err().to_string();
    assert!(e.contains("halo_m") && e.contains("20 m") && e.contains("at least 100 m"), "{e}");
    // forced through: a 20 m halo misses seed sources and crowding beyond it, and the run differs
    let years = 12;
    let one = one_process(&toml, years);
    let layout = Layout::unchecked(w0.site.light, 2, 1, 25.0).unwrap();
    match run_local(&w0, &layout, years) {
        Ok((w, rows, _)) => assert!(to_bytes(&w, &rows) != to_bytes(&one.1, &one.2), "a 25 m halo should change the result"),
        // or a crown outgrew it (also a refusal naming the halo)
        Err(e) => assert!(e.to_string().contains("halo_m"), "{e}"),
    }
}

#[test]
fn tiles_in_threads_write_the_run_directory_of_one_process() {
    // `sylva simulate --tiles 3`: job::tiled over the in-process transport, with outputs
    let toml = edge_toml("tiles_dir", 12);
    let sc = Scenario::from_toml_str(&toml, "tiles_dir").unwrap();
    let lib = sylva::sim::fixtures::library();
    let tmp = tempfile::tempdir().unwrap();
    let (one, three) = (tmp.path().join("one"), tmp.path().join("three"));
    let a = sylva::job::run::run_scenario(&sc, sc.site().unwrap(), &lib, sylva::job::run::RunOptions::new(&one)).unwrap();
    let (b, bytes) = sylva::job::tiled::run_local_tiles(&sc, sc.site().unwrap(), &lib, sylva::job::run::RunOptions::new(&three), 3).unwrap();
    assert_eq!(a.rows, b.rows);
    assert!(bytes.len() == 3 && bytes.iter().all(|&n| n > 0), "bytes sent per rank: {bytes:?}");
    // issue 37 Build 1: rank 0's run driver holds its tile, not the whole site, once the
    // tiles hold the stand (the maps, below, are still the whole site's, byte for byte)
    let (ws, wa) = (&b.world.site, &a.world.site);
    assert!(wa.conditions.holds_all() && !ws.conditions.holds_all(), "rank 0's driver still holds the whole site: {}", ws.conditions.held);
    assert!(ws.conditions.held.width < ws.conditions.width(), "{} of {} columns", ws.conditions.held.width, ws.conditions.width());
    assert!(ws.light_site.len() * 2 < wa.light_site.len() && ws.rel_insolation.len() * 2 < wa.rel_insolation.len(), "{} of {} light cells", ws.light_site.len(), wa.light_site.len());
    assert!(b.world.stand.seeds.iter().all(|g| !g.holds_all()));
    assert_eq!((b.world.stand.trees.len(), b.world.stand.cohorts.len(), b.world.stand.year, b.trees), (0, 0, 12, a.trees));
    let fa = common::files(&one);
    assert!(fa.contains_key("checkpoint.bin") && fa.contains_key("inventory/year_0010.parquet") && fa.len() > 10, "{:?}", fa.keys());
    let template = sylva::sim::World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    let m = common::assert_same_run(&one, &three, &template, "one process and 3 tiles");
    assert_eq!((m.year, m.ranks, m.tiles_across, m.tiles_up), (12, 3, 3, 1), "{m:?}");
    // issue 37 Build 4: the tiles' snapshots are partitioned, one Parquet part per rank (and
    // its regeneration and GeoPackage parts), nothing merged; year 0 (rank 0) a single file
    let fb = common::files(&three);
    for k in 0..3 {
        for f in [format!("inventory/year_0010/part-0000{k}.parquet"), format!("inventory/year_0010_regeneration/part-0000{k}.parquet"), format!("inventory/year_0012_gpkg/part-0000{k}.gpkg")] {
            assert!(fb.contains_key(&f), "{f} missing: {:?}", fb.keys());
        }
    }
    assert!(fb.contains_key("inventory/year_0000.parquet") && !fb.contains_key("inventory/year_0010.parquet") && !fb.contains_key("inventory/year_0012.gpkg"));
    let parts: Vec<usize> = (0..3).map(|k| sylva::job::inventory::read(&three.join(format!("inventory/year_0012/part-0000{k}.parquet"))).unwrap().len()).collect();
    assert!(parts.iter().filter(|&&n| n > 0).count() >= 2, "trees on fewer than 2 tiles: {parts:?}");
    // every reader reads both layouts alike: the snapshots' list, the rows of `render` and
    // `export` (`pictures::snapshot_rows`), the regeneration layer, the viewer's years and
    // inventories, the instanced export's trees
    let snaps = |d: &std::path::Path| sylva::job::inventory::snapshots(d).unwrap().into_iter().map(|s| (s.0, s.1)).collect::<Vec<_>>();
    assert_eq!(snaps(&one), snaps(&three));
    for y in [0, 5, 10, 12] {
        let a = sylva::job::pictures::snapshot_rows(&one, y).unwrap();
        assert!(a == sylva::job::pictures::snapshot_rows(&three, y).unwrap(), "year {y}: rows read back differ");
        assert_eq!(sylva::job::inventory::read_regeneration(&one, y).unwrap(), sylva::job::inventory::read_regeneration(&three, y).unwrap(), "year {y}");
    }
    let (mut va, mut vb) = (sylva::view::data::RunData::open(&one, sc.site().unwrap(), lib.clone(), vec![]).unwrap(), sylva::view::data::RunData::open(&three, sc.site().unwrap(), lib.clone(), vec![]).unwrap());
    assert_eq!(va.years, vb.years);
    for k in 0..va.years.len() {
        assert!(va.rows(k).unwrap().to_vec() == vb.rows(k).unwrap().to_vec(), "the viewer's snapshot {k}");
    }
    use sylva::job::export::{export_instances, InstanceOptions};
    let o = InstanceOptions { year: Some(12), area: None, season: sylva::species::Season::Summer, levels: vec![0], max_triangles: sylva::job::export::INSTANCE_MAX_TRIANGLES };
    let (ga, gb) = (tmp.path().join("a.glb"), tmp.path().join("b.glb"));
    let emb = common::embedded();
    // (the file names the run directory: both exported from the same path)
    let ra = export_instances(&one, &emb, &o, &ga).unwrap();
    let aside = tmp.path().join("one_aside");
    std::fs::rename(&one, &aside).unwrap();
    std::fs::rename(&three, &one).unwrap();
    let rb = export_instances(&one, &emb, &o, &gb).unwrap();
    std::fs::rename(&one, &three).unwrap();
    std::fs::rename(&aside, &one).unwrap();
    assert!(ra.trees > 0 && ra.trees == rb.trees);
    assert!(std::fs::read(&ga).unwrap() == std::fs::read(&gb).unwrap(), "the instanced exports differ");
    assert_eq!(m.files, ["year_0012_rank_0000.bin", "year_0012_rank_0001.bin", "year_0012_rank_0002.bin"]);
    // seasonal snapshots need every tile in the middle of a year: refused
    let seasonal = Scenario::from_toml_str(&toml.replace("snapshot_every = 5", "snapshot_every = 5\nseasonal_snapshots = true"), "tiles_dir").unwrap();
    let e = sylva::job::tiled::run_local_tiles(&seasonal, seasonal.site().unwrap(), &lib, sylva::job::run::RunOptions::new(tmp.path().join("s")), 2).unwrap_err().to_string();
    assert!(e.contains("seasonal_snapshots"), "{e}");
}

/// Beech seed trees at the tile edges of 2 and 3 tiles; snapshots every 5 years, checkpoints
/// every 4.
fn resume_scenario(years: u32) -> Scenario {
    Scenario::from_toml_str(&edge_toml("resume", years), "resume").unwrap()
}

/// The TOML of [`resume_scenario`] named `name` (seed 7, `years` years).
fn edge_toml(name: &str, years: u32) -> String {
    common::ScenarioToml::new(name, years, 7)
        .species(&["beech"])
        .line("light_cell_m = 10.0")
        .line("snapshot_every = 5")
        .line("checkpoint_every = 4")
        .uniform(20, 12, 20.0, 300.0)
        .seed_sources("beech", &[[198.0, 118.0], [134.0, 200.0], [268.0, 125.0]], 3)
        .build()
}

/// Runs `sc` into `dir` as one process (`n` = 1) or `n` tiles in threads.
fn run_n(sc: &Scenario, dir: &std::path::Path, n: usize, resume: bool) -> Result<sylva::job::run::RunSummary, sylva::job::JobError> {
    let lib = sylva::sim::fixtures::library();
    let mut o = sylva::job::run::RunOptions::new(dir);
    o.resume = resume;
    if n == 1 {
        sylva::job::run::run_scenario(sc, sc.site().unwrap(), &lib, o)
    } else {
        sylva::job::tiled::run_local_tiles(sc, sc.site().unwrap(), &lib, o, n).map(|r| r.0)
    }
}

#[test]
fn per_rank_checkpoints_resume_on_the_same_and_other_counts() {
    let (short, long) = (resume_scenario(9), resume_scenario(18));
    let lib = sylva::sim::fixtures::library();
    let template = World::new(long.site().unwrap(), &lib, &long).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let unbroken = run_n(&long, &one, 1, false).unwrap();
    assert_eq!(unbroken.rows.len(), 18);
    assert!(unbroken.trees > 20 && unbroken.trees == unbroken.world.stand.trees.len(), "{} trees", unbroken.trees);
    // 3 → 3: every rank reads its own file; 3 → 2 and 2 → 3: every rank the files over its
    // tile (issue 37 round 37); 3 → 1: the files assembled; 1 → 3: checkpoint.bin read by
    // every tile as the one file of a 1 × 1 layout
    for (first, then) in [(3, 3), (3, 2), (2, 3), (3, 1), (1, 3)] {
        let d = tmp.path().join(format!("{first}_then_{then}"));
        let s = run_n(&short, &d, first, false).unwrap();
        assert!(s.rows.len() == 9 && s.trees > 0, "{} rows, {} trees", s.rows.len(), s.trees);
        if first > 1 {
            let m = sylva::job::checkpoint::read_manifest(&d).unwrap();
            assert_eq!((m.year, m.ranks), (9, first));
            assert!(!d.join("checkpoint.bin").exists());
        }
        let s = run_n(&long, &d, then, true).unwrap();
        assert_eq!(s.rows, unbroken.rows, "{first} then {then}: stand table");
        assert_eq!(s.trees, unbroken.trees, "{first} then {then}: living trees");
        let what = format!("{first} tiles for 9 years, resumed on {then} for 18");
        if then == 1 {
            // the years written by 3 tiles have partitioned inventories (read back the same),
            // the rest byte for byte, checkpoint.bin included
            common::assert_same_outputs(&one, &d, &what, |_| false);
            // and no empty checkpoint/ of the tiles is left beside checkpoint.bin (round 34's trial)
            assert!(d.join("checkpoint.bin").is_file() && !d.join("checkpoint").exists(), "{what}: checkpoint/ left");
        } else {
            let m = common::assert_same_run(&one, &d, &template, &what);
            assert_eq!((m.year, m.ranks), (18, then));
        }
    }
    // the same count reads each rank's own file: a corrupt file of rank 2 is reported by rank 2,
    // and the checkpoint is left as it was
    let d = tmp.path().join("corrupt");
    run_n(&short, &d, 3, false).unwrap();
    let m = sylva::job::checkpoint::read_manifest(&d).unwrap();
    let p = d.join("checkpoint").join(&m.files[2]);
    let mut b = std::fs::read(&p).unwrap();
    let mid = b.len() / 2;
    b[mid] ^= 0x55;
    std::fs::write(&p, &b).unwrap();
    let e = run_n(&long, &d, 3, true).unwrap_err().to_string();
    assert!(e.contains("rank 2 failed") && e.contains(&m.files[2]) && e.contains("CRC"), "{e}");
    assert_eq!(sylva::job::checkpoint::read_manifest(&d).unwrap(), m);
}

/// Issue 37 Build 1, round 37: resume per rank. A run stopped after 18 years on 2 or 3 tiles
/// leaves one checkpoint file per tile; every tile of a new layout of 2 or 3 tiles, built as a
/// lean start builds it (its tile's site and seed windows, no trees), reads only the files of
/// the old tiles whose rectangle overlaps its own (`checkpoint::files_to_read`: on 2 → 3 the
/// outer tiles read one file each; on 3 → 2 each tile two of three) and gets exactly the part
/// of one process's world at year 18 that `Tile::new` cuts for it: trees with every column,
/// cohorts, its windows of the seed grids, the year; rank 0 the stand table and next tree id;
/// the tallies (deaths by cause, regeneration ledger) of the tiles sum to one process's.
#[test]
fn each_tile_of_a_resume_reads_only_the_checkpoint_files_over_it_and_gets_one_process_part() {
    use sylva::job::checkpoint::{load_any, load_overlapping, read_manifest, RANK_DIR};
    let short = resume_scenario(18);
    let lib = sylva::sim::fixtures::library();
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    run_n(&short, &one, 1, false).unwrap();
    let template = World::new(short.site().unwrap(), &lib, &short).unwrap();
    let mut whole = template.clone();
    let rows_one = load_any(&one, &mut whole).unwrap();
    let l = &whole.tallies.regen_ledger;
    assert!(whole.stand.trees.len() > 20 && whole.stand.cohorts.len() > 100 && l.germinated[0] > 0 && l.dead[0].iter().sum::<u64>() > 0, "{} trees, {} cohorts, ledger {l:?}", whole.stand.trees.len(), whole.stand.cohorts.len());
    assert!(whole.stand.seeds.iter().all(|g| g.data.iter().any(|&v| v > 0.0)), "no seeds on the grid at year 9");
    let overlap = |a: sylva::sim::light_grid::CellRect, b: sylva::sim::light_grid::CellRect| a.col0 < b.col1 && b.col0 < a.col1 && a.row0 < b.row1 && b.row0 < a.row1;
    for first in [2, 3] {
        let d = tmp.path().join(format!("t{first}"));
        run_n(&short, &d, first, false).unwrap();
        let m = read_manifest(&d).unwrap();
        let old = Layout::with_bounds(&template.site, m.col_bounds.clone(), m.row_bounds.clone()).unwrap();
        let paths: Vec<std::path::PathBuf> = m.files.iter().map(|f| d.join(RANK_DIR).join(f)).collect();
        for then in [2, 3] {
            let what = format!("{first} → {then} tiles");
            let new = sylva::job::tiled::layout_for(&template, then).unwrap();
            let mut deaths = [0u64; sylva::sim::trees::N_CAUSES];
            let mut ledger = sylva::sim::cohorts::RegenLedger::new(whole.site.pool.len());
            let mut reads = Vec::new();
            for me in 0..then {
                let mut tw = Tile::new(&template, new.clone(), me).unwrap().world;
                tw.stand.trees = Default::default();
                tw.stand.cohorts = Default::default();
                let ov = load_overlapping(&paths, Some(18), &old, &new, me, &mut tw).unwrap();
                let overlaps: Vec<usize> = (0..old.len()).filter(|&k| overlap(old.rect(k), new.rect(me))).collect();
                assert_eq!(ov.read, overlaps, "{what}: tile {me} read other files than those over it");
                reads.push(ov.read.len());
                let want = Tile::new(&whole, new.clone(), me).unwrap().world;
                assert!(!want.stand.trees.is_empty(), "{what}: tile {me} has no trees");
                assert_eq!(tw.stand.trees.id, want.stand.trees.id, "{what}: tile {me}'s trees");
                // the next id is old rank 0's, all-summed to every rank (`job::tiled`)
                tw.stand.trees.next_id = whole.stand.trees.next_id;
                assert!(tw.stand.trees == want.stand.trees, "{what}: tile {me}'s trees' columns");
                assert!(tw.stand.cohorts == want.stand.cohorts, "{what}: tile {me}'s cohorts");
                for (a, b) in tw.stand.seeds.iter().zip(&want.stand.seeds) {
                    assert!(a.held == b.held && a.data == b.data, "{what}: tile {me}'s seed window {:?}", b.held);
                }
                assert_eq!(tw.stand.year, 18);
                // old rank 0's file holds the stand table and the run's next id; new tile 0
                // always reads it
                let zero = ov.read.contains(&0);
                assert!(zero || me != 0, "{what}: tile 0 did not read old tile 0's file");
                assert_eq!((ov.rows.is_empty(), ov.next_id), (!zero, zero.then_some(whole.stand.trees.next_id)), "{what}: tile {me}'s stand table and next id");
                if zero {
                    assert_eq!(ov.rows, rows_one, "{what}: the stand table so far");
                }
                for (a, b) in deaths.iter_mut().zip(tw.tallies.deaths_total) {
                    *a += b;
                }
                let t = &tw.tallies.regen_ledger;
                for p in 0..t.germinated.len() {
                    ledger.germinated[p] += t.germinated[p];
                    ledger.recruited[p] += t.recruited[p];
                    for (a, b) in ledger.dead[p].iter_mut().zip(t.dead[p]) {
                        *a += b;
                    }
                }
            }
            assert_eq!((deaths, &ledger), (whole.tallies.deaths_total, &whole.tallies.regen_ledger), "{what}: the tiles' tallies");
            // on another count a tile reads fewer files than there are (2 → 3: 1, 2, 1; 3 → 2: 2, 2)
            let want: Vec<usize> = match (first, then) {
                (2, 2) => vec![1, 1],
                (2, 3) => vec![1, 2, 1],
                (3, 2) => vec![2, 2],
                _ => vec![1, 1, 1],
            };
            assert_eq!(reads, want, "{what}: files read per tile");
        }
    }
}

#[test]
fn map_sums_over_tiles_are_one_process_sums() {
    use sylva::output::plot::{map_basal_area, map_bin, map_dims};
    let toml = edges();
    let (sc, mut w) = common::world(&toml);
    common::run(&sc, &mut w, YEARS);
    let px = 1024;
    let dims = map_dims(&w, px);
    let np = w.site.lib.species.len();
    let bins = dims.0 * dims.1 * np;
    let want = map_basal_area(&w, px);
    let layout = Layout::new(&w.site, 3, 1).unwrap();
    // some bins hold trees of two tiles (the map's 20 m pixels across the tile edges at 130 m
    // and 260 m), so both ways of summing are used
    let t = &w.stand.trees;
    let mut owners: std::collections::HashMap<usize, std::collections::BTreeSet<usize>> = Default::default();
    for i in 0..t.len() {
        owners.entry(map_bin(t, i, dims, np)).or_default().insert(layout.owner_of(t.x[i], t.y[i]));
    }
    let shared = owners.values().filter(|o| o.len() > 1).count();
    assert!(shared > 0 && owners.len() > shared + 10, "{shared} shared of {} bins with trees", owners.len());
    let got: Vec<Option<Vec<f64>>> = std::thread::scope(|s| {
        let h: Vec<_> = sylva::sim::tiles::LocalTransport::group(3)
            .into_iter()
            .map(|mut tr| {
                let (w, layout) = (&w, layout.clone());
                s.spawn(move || {
                    use sylva::sim::tiles::Transport;
                    let tile = Tile::new(w, layout, tr.rank()).unwrap();
                    tile.gather_bin_sums(&mut tr, bins, |t, i| map_bin(t, i, dims, np), |t, i| t.basal_area_m2(i)).unwrap()
                })
            })
            .collect();
        h.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(got[1].is_none() && got[2].is_none());
    let got = got[0].as_ref().unwrap();
    assert_eq!(got.len(), bins);
    assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "the sums differ from one process's");
    assert!(want.iter().sum::<f64>() > 0.0);
}

#[test]
fn halo_copies_inserted_by_id_and_removed_as_a_merge_and_a_retain() {
    // the tiles' halo copies (issue 37): `insert_by_id` gives the store `merge_by_id` gives,
    // and `remove_rows` of the rows it returns gives the store back
    let toml = edges();
    let (sc, mut w) = common::world(&toml);
    common::run(&sc, &mut w, YEARS);
    let all = w.stand.trees.clone();
    assert!(all.len() > 100, "{} trees", all.len());
    // every third tree is a "halo copy" (arriving without growth factors), the rest the tile's
    let keep: Vec<bool> = (0..all.len()).map(|i| i % 3 != 1).collect();
    let mut own = all.clone();
    own.retain(&keep);
    let mut copies = all.clone();
    copies.retain(&keep.iter().map(|k| !k).collect::<Vec<_>>());
    copies.growth_factor.0.clear();
    let (want, from) = sylva::sim::trees::TreeStore::merge_by_id(&[copies.clone(), own.clone()], own.next_id);
    let mut got = own.clone();
    let rows = got.insert_by_id(&copies);
    assert_eq!(rows, (0..all.len()).filter(|&i| from[i] == 0).collect::<Vec<_>>());
    assert_eq!(got.id, all.id, "ids not in order");
    assert_eq!(got.id, want.id);
    assert_eq!(got.species, want.species);
    assert!(got.f32_columns().iter().zip(want.f32_columns()).all(|(a, b)| a.iter().map(|v| v.to_bits()).eq(b.iter().map(|v| v.to_bits()))), "columns differ from merge_by_id's");
    // the copies' growth factors are NaN, the tile's kept
    assert!(rows.iter().all(|&i| got.growth_factor.0[i].is_nan()));
    got.remove_rows(&rows);
    assert_eq!(got.id, own.id);
    assert!(got.f32_columns().iter().zip(own.f32_columns()).all(|(a, b)| a.iter().map(|v| v.to_bits()).eq(b.iter().map(|v| v.to_bits()))));
}

/// Issue 37 Build 5: on a site whose east half is masked (no forest can grow there), the tiles
/// are cut by the light cells where forest can grow, not by area: 2 tiles split the west half
/// (the area cut would give the east tile nothing to do), and the runs on 2 and 3 such tiles
/// write the run of one process.
#[test]
fn tiles_cut_by_forest_on_a_half_masked_site_write_the_run_of_one_process() {
    let toml = common::ScenarioToml::new("half", 14, 7)
        .species(&["beech"])
        .line("light_cell_m = 10.0")
        .line("snapshot_every = 7")
        .line("checkpoint_every = 7")
        .uniform(40, 12, 20.0, 300.0)
        .seed_sources("beech", &[[60.0, 118.0], [190.0, 60.0], [210.0, 200.0], [330.0, 120.0], [100.0, 40.0], [290.0, 210.0], [250.0, 110.0], [150.0, 160.0]], 4)
        .build();
    let sc = Scenario::from_toml_str(&toml, "half").unwrap();
    let lib = sylva::sim::fixtures::library();
    // the east half (x ≥ 400 m) masked
    let site = || {
        let mut s = sc.site().unwrap();
        let w = s.width();
        for r in 0..s.height() {
            for c in w / 2..w {
                let i = s.mask.idx(c, r);
                s.mask.data[i] = false;
            }
        }
        s
    };
    let template = World::new(site(), &lib, &sc).unwrap();
    let (wc, wr) = sylva::sim::tiles::work_weights(&template.site);
    assert_eq!(wc.iter().filter(|&&v| v > 0).count(), 40, "forest on the west 40 of 80 light columns");
    assert!(wc[..40].iter().all(|&v| v == 24) && wr.iter().all(|&v| v == 40), "{wc:?} {wr:?}");
    // by forest: 2 tiles of 20 columns of forest each (area: 40 and 40, all forest on tile 0)
    assert_eq!(sylva::job::tiled::layout_for(&template, 2).unwrap().col_bounds, vec![0, 20, 80]);
    assert_eq!(sylva::job::tiled::layout_for(&template, 3).unwrap().col_bounds, vec![0, 13, 26, 80]);
    // issue 37 Build 1: the ranks count the weights of their bands of light rows and add them
    // up; the parts cover the rows once and add up to the whole site's counts
    let rows = template.site.light.rows;
    assert_eq!(rows, 24);
    for n in 1..=5 {
        let (mut sc_, mut sr) = (vec![0u64; wc.len()], vec![0u64; wr.len()]);
        for k in 0..n {
            let band = sylva::sim::tiles::weight_band(k, n, rows);
            let (pc, pr) = sylva::sim::tiles::work_weights_in(&template.site, band.clone());
            // a band counts its own rows only: 40 forest cells each, the others 0
            assert!(pr.iter().enumerate().all(|(r, &v)| v == if band.contains(&r) { 40 } else { 0 }), "rank {k} of {n}: {pr:?}");
            assert_eq!(pc.iter().sum::<u64>(), 40 * band.len() as u64);
            sc_.iter_mut().zip(&pc).for_each(|(a, b)| *a += b);
            sr.iter_mut().zip(&pr).for_each(|(a, b)| *a += b);
        }
        assert_eq!((&sc_, &sr), (&wc, &wr), "{n} bands");
    }
    // the layout the ranks cut from their parts (all-summed over a LocalTransport) is
    // layout_for's of the whole site on every rank
    for n in [2, 3, 4] {
        let want = sylva::job::tiled::layout_for(&template, n).unwrap();
        let got: Vec<Layout> = std::thread::scope(|s| {
            let hs: Vec<_> = sylva::sim::tiles::LocalTransport::group(n)
                .into_iter()
                .map(|mut t| {
                    let w = &template;
                    s.spawn(move || sylva::job::tiled::layout_by(w, &mut t).unwrap().0)
                })
                .collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(got.len(), n);
        assert!(got.iter().all(|l| *l == want), "{n} ranks: {:?} vs {:?}", got.iter().map(|l| &l.col_bounds).collect::<Vec<_>>(), want.col_bounds);
    }
    // an even site is cut by area as before
    let even = World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    assert_eq!(sylva::job::tiled::layout_for(&even, 3).unwrap().col_bounds, vec![0, 26, 53, 80]);
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let a = sylva::job::run::run_scenario(&sc, site(), &lib, sylva::job::run::RunOptions::new(&one)).unwrap();
    let xs: Vec<f32> = a.world.stand.trees.x.clone();
    assert!(xs.len() > 20 && xs.iter().all(|&x| x < 400.0), "{} trees, some in the masked half", xs.len());
    // both tiles of 2 hold trees (the area cut's east tile would hold none)
    assert!(xs.iter().any(|&x| x < 200.0) && xs.iter().any(|&x| x >= 200.0), "trees on one side of x = 200 m only");
    for n in [2, 3] {
        let d = tmp.path().join(format!("n{n}"));
        let (b, _) = sylva::job::tiled::run_local_tiles(&sc, site(), &lib, sylva::job::run::RunOptions::new(&d), n).unwrap();
        assert_eq!(a.rows, b.rows, "{n} tiles: stand table");
        let m = common::assert_same_run(&one, &d, &template, &format!("{n} tiles cut by forest"));
        assert_eq!(m.col_bounds, if n == 2 { vec![0, 20, 80] } else { vec![0, 13, 26, 80] });
    }
    // stopped on 3 such tiles, resumed on 2: the manifest's bounds are read back
    let (short, long) = (Scenario::from_toml_str(&toml.replace("years = 14", "years = 7"), "half").unwrap(), sc.clone());
    let d = tmp.path().join("split");
    sylva::job::tiled::run_local_tiles(&short, site(), &lib, sylva::job::run::RunOptions::new(&d), 3).unwrap();
    let mut o = sylva::job::run::RunOptions::new(&d);
    o.resume = true;
    let (b, _) = sylva::job::tiled::run_local_tiles(&long, site(), &lib, o, 2).unwrap();
    assert_eq!(a.rows, b.rows, "3 tiles then 2: stand table");
    common::assert_same_run(&one, &d, &template, "3 tiles cut by forest, resumed on 2");
}

#[test]
fn the_light_phase_holds_its_grids_over_the_tiles_trees_and_cells() {
    // issue 37 Build 1: the spatial hash (and the canopy on its cells) of a tile covers the
    // cells of its trees and halo copies and its own cells, one row wider on each side, not the
    // whole grid; one process holds the whole grid
    use sylva::sim::light_grid::{CellRect, LightGrid};
    use sylva::sim::phases::light::held_cells;
    use sylva::sim::trees::{NewTree, SpatialGrid, TreeStore};
    let lg = LightGrid::new((40.0, 30.0), 5.0); // 8 × 6 cells
    let mut t = TreeStore::default();
    for (x, y) in [(6.0, 11.0), (12.0, 12.0), (18.0, 14.0), (24.0, 6.0), (13.0, 13.0)] {
        t.push(NewTree { species: 0, x, y, z: 0.0, age: 1.0, height: 1.0, dbh: 0.0, crown_radius: 0.3, suitability: 1.0 });
    }
    assert_eq!(held_cells(&t, &lg, None), CellRect { col0: 0, row0: 0, col1: 8, row1: 6 });
    // trees in columns 1..5, rows 1..3; the tile's own cells columns 2..4, rows 3..4
    let win = CellRect { col0: 2, row0: 3, col1: 4, row1: 4 };
    let rect = held_cells(&t, &lg, Some(win));
    assert_eq!(rect, CellRect { col0: 1, row0: 0, col1: 5, row1: 5 });
    // no trees: the own cells and a row either side; neither: one cell
    assert_eq!(held_cells(&TreeStore::default(), &lg, Some(win)), CellRect { col0: 2, row0: 2, col1: 4, row1: 5 });
    assert_eq!(held_cells(&TreeStore::default(), &lg, Some(CellRect::default())).len(), 1);
    // the grid over it: cell indices of the rectangle, the same neighbours as the whole grid's
    let h = SpatialGrid::build_in(&t, &lg, rect);
    let g = SpatialGrid::build(&t, &lg);
    assert_eq!((h.cols, h.rows, h.col0, h.row0, h.start.len(), g.start.len()), (4, 5, 1, 0, 21, 49));
    assert_eq!(h.cell_of(6.5, 1.0), 0);
    assert_eq!(h.cell(h.cell_of(12.0, 12.0)), &[1, 4]);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (x, y, r) in [(13.0, 12.0, 6.0), (20.0, 10.0, 8.0), (0.0, 0.0, 2.0), (39.0, 29.0, 3.0), (10.0, 10.0, 40.0)] {
        h.within(&t, x, y, r, &mut a);
        g.within(&t, x, y, r, &mut b);
        a.sort();
        b.sort();
        assert_eq!(a, b, "within {r} m of ({x}, {y})");
    }
}

#[test]
fn a_tile_holds_its_window_of_the_seed_grids_only() {
    // issue 37 Build 1 and 3: a tile keeps of each seed grid the cells of its light cells'
    // centres and those whose centre it owns (one cell of margin), not the whole grid; the
    // production of the cells within the kernel's reach is passed as sums and spread onto the
    // window only, and the runs stay one process's (the tests above)
    use sylva::sim::light_grid::CellRect;
    use sylva::sim::tiles::{hold_own_seeds, seed_window};
    let toml = edges();
    let (_, w0) = common::world(&toml);
    // a world with seeds on its grid (8 years of beech seeding)
    let one = one_process(&toml, 8);
    let g1 = &one.1.stand.seeds[0];
    // fine cells of 5 m (round 45: the two-scale kernel), whole coarse cells of the 400 m × 240 m site
    let (cols, rows, f) = (g1.cols, g1.rows, g1.cell_m);
    assert!(g1.holds_all() && f == 5.0 && cols % g1.block == 0 && rows % g1.block == 0 && cols as f64 * f >= 400.0 && rows as f64 * f >= 240.0, "{cols} × {rows} of {f} m");
    assert!(g1.data.iter().filter(|&&v| v > 0.0).count() > 20, "seeds on too few cells");
    let lg = w0.site.light;
    for (nx, ny) in [(2, 1), (3, 1), (5, 1), (10, 1), (2, 2)] {
        let layout = Layout::new(&w0.site, nx, ny).unwrap();
        let mut owners = vec![0u32; cols * rows];
        for k in 0..layout.len() {
            let tile = Tile::new(&one.1, layout.clone(), k).unwrap();
            let g = &tile.world.stand.seeds[0];
            let win = seed_window(&layout, k, g1);
            assert_eq!((g.held, g.data.len(), g.cols, g.rows), (win, win.len(), cols, rows), "tile {k} of {nx} × {ny}");
            assert!(!g.holds_all() && win.len() < cols * rows, "tile {k} of {nx} × {ny} holds {win:?}");
            // its values are the whole grid's
            for cell in win.cells(cols) {
                let (c, r) = (cell % cols, cell / cols);
                assert_eq!(g.data[g.index(c, r).unwrap()].to_bits(), g1.data[cell].to_bits(), "tile {k}, seed cell ({c}, {r})");
            }
            // regeneration reads the seed cells of its light cells' centres
            let rect = layout.rect(k);
            for lc in rect.cells(lg.cols) {
                let (x, y) = lg.centre(lc);
                assert_eq!(g.at(x, y).to_bits(), g1.at(x, y).to_bits());
            }
            // the cells whose centre it owns (its part of an assembled world) lie in it
            for cell in 0..cols * rows {
                let (c, r) = (cell % cols, cell / cols);
                if layout.owner_of(((c as f64 + 0.5) * f) as f32, ((r as f64 + 0.5) * f) as f32) == k {
                    assert!(win.contains(c, r), "tile {k} of {nx} × {ny}: seed cell ({c}, {r})");
                    owners[cell] += 1;
                }
            }
        }
        assert!(owners.iter().all(|&n| n == 1), "{nx} × {ny}: every seed cell owned once");
    }
    // 2 tiles of 20 light columns (200 m): seed columns 0..40 (+ 2 of margin) and 40..cols (− 1)
    let layout = Layout::new(&w0.site, 2, 1).unwrap();
    assert_eq!(seed_window(&layout, 0, g1), CellRect { col0: 0, row0: 0, col1: 42, row1: rows });
    assert_eq!(seed_window(&layout, 1, g1), CellRect { col0: 39, row0: 0, col1: cols, row1: rows });
    // a per-rank checkpoint that holds the whole grid (an earlier Sylva's) read into a tile's
    // window: cut to it
    let bytes = to_bytes(&one.1, &one.2);
    let mut t = w0.clone();
    hold_own_seeds(&mut t, &layout, 1).unwrap();
    sylva::sim::checkpoint::restore(&mut t, &bytes, std::path::Path::new("rank_0001.bin")).unwrap();
    let g = &t.stand.seeds[0];
    assert_eq!((g.held, g.data.clone()), (seed_window(&layout, 1, g1), g1.window(seed_window(&layout, 1, g1)).unwrap()));
    // a world holding another tile's window is refused
    let mut t0 = w0.clone();
    hold_own_seeds(&mut t0, &layout, 0).unwrap();
    let e = hold_own_seeds(&mut t0, &layout, 1).unwrap_err().to_string();
    assert!(e.contains("seed grid") && e.contains("tile 1"), "{e}");
}

/// Issue 37 Build 1, round 33: a fresh tiled run's rank 0 builds its tile's world only (its
/// band of the site, its tile's cells from the bands' owners, its own start's trees, ids from
/// the ranks' counts) and year 0's snapshot comes from the ranks' start's trees and masked
/// pixels: on a window of the default DEM with a planted start (3 m lattice, its rows jittered
/// across the tile edges) and seed sources at the tile edges, on 2, 3 and 2 × 2 tiles the run
/// directory is one process's byte for byte (year 0 included: ids in one process's order);
/// the whole site's identity joined from bands is `site_identity`'s.
#[test]
fn rank_0_builds_its_tiles_world_only_and_the_start_ids_are_one_process() {
    let toml = common::ScenarioToml::new("lean", 4, 5)
        .species(&["beech", "birch"])
        .line("light_cell_m = 10.0")
        .line("snapshot_every = 2")
        .default_terrain([150, 150, 12, 10])
        .planted("birch", 3.0, 4.0)
        .seed_sources("beech", &[[120.0, 100.0], [121.0, 60.0], [60.0, 101.0]], 3)
        .build();
    let sc = Scenario::from_toml_str(&toml, "lean").unwrap();
    let lib = sylva::sim::fixtures::library();
    let site = sc.site().unwrap();
    // the identity from bands (any cut into rows) equals the whole site's
    let h = site.height();
    for cuts in [vec![0, h], vec![0, 3, h], vec![0, 0, 4, 7, h]] {
        let parts: Vec<_> = cuts.windows(2).map(|r| {
            let mut b = site.clone();
            b.hold(sylva::grid::Window { col0: 0, row0: r[0], width: site.width(), height: r[1] - r[0] });
            sylva::sim::checkpoint::identity_part(&b, 0..r[1] - r[0])
        }).collect();
        assert_eq!(sylva::sim::checkpoint::site_identity_of(site.width(), h, site.cell_x_m, site.cell_y_m, &parts), sylva::sim::checkpoint::site_identity(&site), "bands {cuts:?}");
    }
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("one");
    let a = sylva::job::run::run_scenario(&sc, sc.site().unwrap(), &lib, sylva::job::run::RunOptions::new(&one)).unwrap();
    let template = World::new(sc.site().unwrap(), &lib, &sc).unwrap();
    assert!(template.stand.trees.len() > 500, "{} start trees", template.stand.trees.len());
    for n in [2, 3, 4] {
        let d = tmp.path().join(format!("t{n}"));
        let (b, _) = sylva::job::tiled::run_local_tiles(&sc, sc.site().unwrap(), &lib, sylva::job::run::RunOptions::new(&d), n).unwrap();
        assert_eq!(a.rows, b.rows, "{n} tiles");
        let ws = &b.world.site;
        assert!(!ws.conditions.holds_all() && ws.whole_identity.as_ref() == Some(&sylva::sim::checkpoint::site_identity(&template.site.conditions)), "{n} tiles: {}", ws.conditions.held);
        common::assert_same_run(&one, &d, &template, &format!("one process and {n} tiles"));
        let fa = common::files(&one);
        let fb = common::files(&d);
        for f in ["inventory/year_0000.parquet", "maps/species_year_0000.png", "maps/basal_area_year_0000.png"] {
            assert!(fa[f] == fb[f], "{n} tiles: {f} differs");
        }
    }
}
