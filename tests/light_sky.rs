//! The light phase's diffuse part from the sky (`[light] diffuse = "sky"`, issue 32 item 4's
//! Must show, trial 44 defect 3): the virtual hemispherical photograph of a stand agrees with the
//! simulation's diffuse light in a closed stand and in a gap; the column model (the default)
//! misses the gap; tiled runs with the sky equal one process; a bad value is refused.
mod common;
use sylva::job::hemi::{hemispherical_photo, HemiOptions, HemiStats};
use sylva::sim::tiles::{run_local, Layout};

/// A flat 200 m × 200 m site (5 m light cells) planted with 80-year beech at 5 m, but for a
/// 40 m × 40 m gap at its centre (x, y 80–120 m), simulated one year.
fn gap_stand(dir: &std::path::Path, diffuse: &str) -> std::path::PathBuf {
    let mut toml = format!("name = \"gap\"\nyears = 1\nseed = 3\nsnapshot_every = 1\nspecies = [\"beech\"]\n[light]\ndiffuse = \"{diffuse}\"\n[terrain]\nuniform = {{ width = 8, height = 8, cell_m = 25.0, elevation_m = 310.0, indices = [5, 5, 2, 5, 6, 6] }}\n");
    for [x0, y0, x1, y1] in [[0.0, 0.0, 200.0, 80.0], [0.0, 120.0, 200.0, 200.0], [0.0, 80.0, 80.0, 120.0], [120.0, 80.0, 200.0, 120.0]] {
        toml += &format!("[[start]]\nkind = \"planted\"\nspecies = \"beech\"\nspacing_m = 5.0\nage_yr = 80.0\narea = [{x0:?}, {y0:?}, {x1:?}, {y1:?}]\n");
    }
    let sc = sylva::sim::Scenario::from_toml_str(&toml, "gap").unwrap();
    let run = dir.join(diffuse);
    let mut opts = sylva::job::run::RunOptions::new(&run);
    opts.map_px = 32;
    sylva::job::run::run_scenario(&sc, sc.site().unwrap(), &common::embedded(), opts).unwrap();
    run
}

/// Five places in the closed stand (three of them 20–45 m from the gap's edge), then the gap's
/// middle: centres of 5 m light cells, where the light phase takes a cell's light.
const PLACES: [(f64, f64); 6] = [(42.5, 42.5), (162.5, 42.5), (102.5, 167.5), (42.5, 102.5), (162.5, 152.5), (102.5, 102.5)];

fn photos(run: &std::path::Path) -> Vec<HemiStats> {
    let lib = common::embedded();
    PLACES.iter().map(|&(x, y)| hemispherical_photo(run, &lib, &HemiOptions { year: Some(1), x_m: x, y_m: y, size_px: 240 }).unwrap().1).collect()
}

/// The diffuse site factor of the photograph (its rays' transmission weighted by the standard
/// overcast sky's irradiance on a horizontal surface, as the simulation's diffuse part weights
/// its sectors) within ±0.10 of the simulated diffuse light at five places of a closed stand
/// and in a gap, with the sky model. The diffuse site factor, not the gap fraction: the gap
/// fraction weights every solid angle alike, so a gap whose zenith is open but whose lower sky
/// the stand around blocks has a gap fraction well under the light it receives (in this gap a
/// gap fraction of 0.30 against a diffuse site factor of 0.53). With the column model (the
/// default, what rounds 1–43 did) the gap's diffuse light is 1, nothing being straight above
/// it, and misses the photograph by 0.47; in the closed stand both agree. Measured (the CLI on
/// the same stand): closed places +0.072 to +0.094 with the sky (a thin layer per crown lets a
/// slanting ray slip between neighbouring layers), the gap −0.084.
#[test]
fn the_photograph_agrees_with_the_sky_model_in_a_closed_stand_and_a_gap() {
    let dir = tempfile::tempdir().unwrap();
    let sky = photos(&gap_stand(dir.path(), "sky"));
    let column = photos(&gap_stand(dir.path(), "column"));
    for (s, c, p) in sky.iter().zip(&column).zip(PLACES).map(|((s, c), p)| (s, c, p)) {
        eprintln!("{p:?}: sky run: gap fraction {:.3}, openness {:.3}, diffuse site factor {:.3}, simulated diffuse {:.3}, light {:.3}; column run: {:.3} {:.3} {:.3} {:.3} {:.3}", s.gap_fraction, s.openness, s.diffuse_site_factor, s.simulated_diffuse, s.simulated_light, c.gap_fraction, c.openness, c.diffuse_site_factor, c.simulated_diffuse, c.simulated_light);
    }
    // (each run grew its trees one year in its own light, so the two photographs differ a little)
    for (i, ((s, c), p)) in sky.iter().zip(&column).zip(PLACES).enumerate() {
        assert!((s.simulated_diffuse - s.diffuse_site_factor).abs() <= 0.10, "{p:?} with the sky: {s:?}");
        if i < 5 {
            // the closed stand: little sky, and the column model agrees there too
            assert!(s.diffuse_site_factor < 0.25 && (c.simulated_diffuse - c.diffuse_site_factor).abs() <= 0.10, "{p:?}: {s:?} {c:?}");
        }
    }
    let (gs, gc) = (&sky[5], &column[5]);
    assert!(gs.diffuse_site_factor > 0.3 && gs.diffuse_site_factor < 0.95, "the gap's zenith is open, its lower sky blocked: {gs:?}");
    assert!((gc.simulated_diffuse - 1.0).abs() < 1e-6 && gc.simulated_diffuse - gc.diffuse_site_factor > 0.10, "the column model misses the gap: {gc:?}");
    assert_eq!(gs.diffuse, sylva::sim::light_grid::Diffuse::Sky);
}

/// Tiled runs with the sky model (whose rays read cells 150 m away) end as one process does:
/// the crowns' halo grows by the sky's reach ([`sylva::sim::tiles::Reach`]) and each tile holds
/// the cells its rays read.
#[test]
fn tiles_with_the_sky_equal_one_process() {
    let toml = common::ScenarioToml::new("tiles", 8, 7)
        .species(&["beech"])
        .line("light_cell_m = 10.0")
        .line("light = { diffuse = \"sky\" }")
        .uniform(20, 12, 20.0, 300.0)
        .seed_sources("beech", &[[198.0, 118.0], [203.0, 60.0], [134.0, 200.0], [161.0, 30.0], [241.0, 122.0], [60.0, 200.0]], 3)
        .build();
    let (sc, mut one) = common::world(&toml);
    assert_eq!(one.site.light.diffuse, sylva::sim::light_grid::Diffuse::Sky);
    let (_, w0) = common::world(&toml);
    let rows = common::run(&sc, &mut one, 8);
    // the sky reaches 150 m: 16 cells of 10 m beyond a tile, plus the crown and one cell
    let reach = Layout::new(&w0.site, 2, 1).unwrap().reach.crowns_m;
    assert!(reach >= 170.0, "{reach}");
    for (nx, ny) in [(2, 1), (2, 2)] {
        let layout = Layout::new(&w0.site, nx, ny).unwrap();
        let (w, trows, _) = run_local(&w0, &layout, 8).unwrap();
        assert_eq!(trows, rows, "{nx} × {ny} tiles: stand table differs");
        assert_eq!(w.stand.trees, one.stand.trees, "{nx} × {ny} tiles: trees differ");
        assert_eq!(w.stand.cohorts, one.stand.cohorts, "{nx} × {ny} tiles: cohorts differ");
    }
}

/// `[light] diffuse` takes "column" or "sky"; anything else is refused naming the field and
/// the values it takes.
#[test]
fn a_bad_diffuse_value_is_refused() {
    let base = common::ScenarioToml::new("bad", 1, 1).species(&["beech"]).uniform(2, 2, 25.0, 300.0);
    let e = sylva::sim::Scenario::from_toml_str(&base.clone_with("light = { diffuse = \"sun\" }"), "bad.toml").unwrap_err().to_string();
    assert!(e.contains("diffuse") && e.contains("column") && e.contains("sky"), "{e}");
    let e = sylva::sim::Scenario::from_toml_str(&base.clone_with("light = { difuse = \"sky\" }"), "bad.toml").unwrap_err().to_string();
    assert!(e.contains("difuse"), "{e}");
    // the default is the column, and a written scenario leaves the section out
    let sc = sylva::sim::Scenario::from_toml_str(&base.build(), "ok.toml").unwrap();
    assert_eq!(sc.light.diffuse, sylva::sim::light_grid::Diffuse::Column);
}

/// Beech crowns whose equal-area squares fill the 5 m light cells of a 400 m × 400 m grid (one
/// crown a cell, at its centre) from `base` to `top` m, but where `keep(x, y)` is false, with the
/// diffuse part from the sky; and the leaf-area index each crown gives its cell.
fn crown_carpet(base: f32, top: f32, keep: impl Fn(f32, f32) -> bool) -> (sylva::sim::trees::TreeStore, sylva::sim::light_grid::LightGrid, f32) {
    let lib = common::embedded();
    let beech = lib.find("beech").unwrap();
    let r = 2.5 / 0.886_226_9; // the equal-area square's half side is 2.5 m
    let mut t = sylva::sim::trees::TreeStore::default();
    for row in 0..80 {
        for col in 0..80 {
            let (x, y) = (col as f32 * 5.0 + 2.5, row as f32 * 5.0 + 2.5);
            if keep(x, y) {
                t.push(sylva::sim::trees::NewTree { species: beech, x, y, z: 300.0, age: 80.0, height: top, dbh: 30.0, crown_radius: r, suitability: 1.0 });
                *t.crown_base.last_mut().unwrap() = base;
            }
        }
    }
    let light = sylva::sim::light_grid::LightGrid::new((400.0, 400.0), 5.0).with_diffuse(sylva::sim::light_grid::Diffuse::Sky);
    let lai = sylva::sim::phases::light::crown_leaf_area(lib.species[beech as usize].life.shade_tolerance, r) / 25.0;
    (t, light, lai)
}

/// The light phase's diffuse part at height `z` (m) over the centre of cell (col, row).
fn diffuse_at(t: &sylva::sim::trees::TreeStore, light: &sylva::sim::light_grid::LightGrid, (col, row): (usize, usize), z: f32) -> f32 {
    let win = sylva::sim::light_grid::CellRect { col0: col, row0: row, col1: col + 1, row1: row + 1 };
    sylva::sim::phases::light::light_parts_at(t, light, 50.0, &common::embedded(), &[], Some(win), z)[0].0
}

/// `Σ w_j e^(−k L_j / cos θ_j)` over the sky's sectors, `L_j = lai(tan θ_j, cos φ_j)`.
fn sky_sum(lai: impl Fn(f32, f32) -> f32) -> f32 {
    let k = sylva::sim::phases::light::K_EXT;
    sylva::sim::phases::light::Sky::standard_overcast().sectors.iter().map(|&([_, cy], tan, sec, w)| w * (-k * lai(tan, cy) * sec).exp()).sum()
}

/// A uniform boundless canopy (crowns 8–16 m filling every cell, leaf-area index L = 4.5, beech's
/// crown LAI): from the ground every ray crosses all of it, so the fast sky's transmission is
/// the standard overcast sky's weighted `Σ w_j e^(−k L / cos θ_j)` (Beer–Lambert, Monsi &
/// Saeki 1953; 0.0508 against the column's e^(−k L) = 0.105), and from within the crowns at
/// 12 m and 13 m the same with the leaf area above them (L/2, 3L/8, the crowns' leaf area spread
/// over their depth); a tree at the canopy's top sees the whole sky.
#[test]
fn the_fast_sky_through_a_uniform_canopy_is_beer_lambert_per_sector() {
    let (t, light, l) = crown_carpet(8.0, 16.0, |_, _| true);
    for (z, above) in [(0.0f32, l), (12.0, l / 2.0), (13.0, 3.0 * l / 8.0), (16.0, 0.0)] {
        let got = diffuse_at(&t, &light, (40, 40), z);
        let want = sky_sum(|_, _| above);
        assert!((got - want).abs() < 2e-4, "at {z} m: {got} against {want}");
    }
    let ground = diffuse_at(&t, &light, (40, 40), 0.0);
    assert!(ground < (-0.5f32 * l).exp() - 0.04, "{ground}: the slanting rays cross more leaf area than the column");
}

/// A round gap of radius R = 30 m in that canopy (no crown whose centre lies within R of the
/// place): from the gap's centre on the ground a ray of zenith angle θ leaves the gap at the
/// height `R / tan θ` and meets the crowns' leaf area above `max(8 m, R / tan θ)`:
/// `L_j = L · (16 − clamp(R / tan θ_j, 8, 16)) / 8` (0 in the four upper bands). The grid (5 m
/// cells, 2 m layers, one cell a ray and layer) gives the analytic 0.832 within 0.03 (the column model gives 1).
#[test]
fn the_fast_sky_in_a_round_gap_is_the_analytic_one() {
    let (cx, cy, r) = (202.5f32, 202.5f32, 30.0f32);
    let (t, light, l) = crown_carpet(8.0, 16.0, |x, y| (x - cx).hypot(y - cy) >= r);
    let got = diffuse_at(&t, &light, (40, 40), 0.0);
    let want = sky_sum(|tan, _| l * (16.0 - (r / tan).clamp(8.0, 16.0)) / 8.0);
    eprintln!("round gap: fast sky {got}, analytic {want}");
    assert!((got - want).abs() < 0.03 && want > 0.8 && want < 0.87, "{got} against {want}");
}

/// A wall of crowns (2–10 m) north of y = 60 m, the place on the ground 2.5 m south of it: the
/// southern half of the sky stays open; a northern sector's ray (zenith angle θ, azimuth φ)
/// meets the wall at the height `h = 2.5 m / (tan θ cos φ)` and crosses its leaf area above
/// `max(2 m, h)` (0.673 with L = 4.5). The fast sky within 0.03 of that.
#[test]
fn the_fast_sky_sees_a_wall_on_one_side() {
    let (t, light, l) = crown_carpet(2.0, 10.0, |_, y| y > 60.0);
    let got = diffuse_at(&t, &light, (40, 11), 0.0);
    let want = sky_sum(|tan, cy| if cy <= 0.0 { 0.0 } else { l * (10.0 - (2.5 / (tan * cy)).clamp(2.0, 10.0)) / 8.0 });
    eprintln!("wall: fast sky {got}, analytic {want}");
    assert!((got - want).abs() < 0.03 && want > 0.55 && want < 0.75, "{got} against {want}");
}

trait With {
    fn clone_with(&self, line: &str) -> String;
}
impl With for common::ScenarioToml {
    fn clone_with(&self, line: &str) -> String {
        // the line goes among the top-level ones, before [terrain]
        let t = self.build();
        let at = t.find("[terrain]").unwrap();
        format!("{}{line}\n{}", &t[..at], &t[at..])
    }
}
