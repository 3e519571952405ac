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
