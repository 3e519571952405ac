//! From simulation results to a render [`Scene`]: the terrain mesh of the site, one prototype per
//! species (its EcoMod skeleton meshed into a level-of-detail chain), and one instance per live
//! tree of an inventory snapshot.
//!
//! [`prototypes`] builds one open-grown tree per species; the trees near the camera get their own
//! adapted skeletons and meshes in [`super::adapted`] (Plastic Trees, Pirk et al. 2012,
//! `000_*.txt`).

use crate::conditions::SiteConditions;
use crate::grid::Grid;
use crate::job::inventory::InventoryRow;
use crate::sim::World;
use crate::render::scene::{Prototype, Scene, Sky, Sun, TerrainMesh, TreeInstance, Wind};
use crate::render::terrain::{from_grid, LandCover};
use crate::species::{Season, Species, SpeciesLibrary};
use crate::Result;

pub use crate::species::srgb_to_linear;

mod canopy;
mod colour;
mod instances;
mod prototypes;
mod saplings;
mod stumps;
mod surroundings;

pub use canopy::*;
pub use colour::*;
pub use instances::*;
pub use prototypes::*;
pub use saplings::*;
pub use stumps::*;
pub use surroundings::*;

/// A full scene for one snapshot: terrain, prototypes, instances, the sun of the site's
/// latitude on the season's day at 14:00 solar time, and a light westerly breeze.
pub fn scene(terrain: TerrainMesh, prototypes: Vec<Prototype>, instances: Vec<TreeInstance>, latitude_deg: f64, season: Season, sea_level: Option<f32>) -> Scene {
    Scene::new(terrain, sea_level, prototypes, instances, season_sun(latitude_deg, season), Sky::default(), Wind { direction: [1.0, 0.0], directed: 1.5, undirected: 1.0, time_s: 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: u64, x: f64, y: f64, h: f32, r: f32) -> InventoryRow {
        InventoryRow { id, species: "beech".into(), x_m: x, y_m: y, z_m: 0.0, age_yr: 10.0, height_m: h, dbh_cm: 10.0, crown_radius_m: r, crown_base_m: h * 0.5, status: "alive".into() }
    }

    #[test]
    fn understory_under_a_crown_is_hidden_and_open_trees_are_kept() {
        let rows = vec![
            row(1, 50.0, 50.0, 30.0, 6.0), // canopy tree
            row(2, 52.0, 51.0, 8.0, 2.0),  // under its crown: hidden (8 < 0.6·30)
            row(3, 53.0, 50.0, 25.0, 4.0), // co-dominant under the crown edge: kept (25 ≥ 18)
            row(4, 80.0, 80.0, 5.0, 2.0),  // in the open: kept
            row(5, 90.0, 90.0, 0.5, 0.3),  // seedling: not drawn
            InventoryRow { status: "dead:stress".into(), ..row(6, 20.0, 20.0, 20.0, 3.0) },
        ];
        assert_eq!(visible_rows(&rows, (100.0, 100.0)), vec![0, 2, 3]);
    }

    fn cohort(cell: u32, stems: u32, h: f32) -> SaplingCohort<'static> {
        // 40 light cells of 5 m per row, row 0 south
        let (c, r) = (cell % 40, cell / 40);
        SaplingCohort { cell, species: "beech", x_m: (c as f64 + 0.5) * 5.0, y_m: (r as f64 + 0.5) * 5.0, cell_m: 5.0, stems, height_m: h }
    }

    #[test]
    fn a_stand_of_only_cohorts_draws_saplings_in_proportion_to_their_density() {
        use std::f64::consts::PI;
        let lib = SpeciesLibrary::embedded().unwrap();
        let beech = &lib.species[lib.find("beech").unwrap() as usize];
        let cond = SiteConditions::uniform(20, 20, 10.0, 500.0, [5.0; 6], 47.0);
        // three bands of 1.5 m beech saplings: rows 0-9 one stem per 5 m cell, rows 10-19 two,
        // rows 20-29 none; row 30 a dense thicket of 400 stems of 3 m per cell
        let mut cohorts = Vec::new();
        for cell in 0..40 * 31u32 {
            let band = cell / 400;
            let stems = [1, 2, 0, 400][band as usize];
            let h = if band == 3 { 3.0 } else { 1.5 };
            cohorts.push(cohort(cell, stems, h));
        }
        let inst = instances_with_saplings(&[], &cohorts, &lib, &cond, Season::Summer);
        assert!(inst.iter().all(|t| t.id & SAPLING_ID_BIT != 0 && t.height > 1.0 && t.height < 4.0));
        let band_of = |t: &TreeInstance| (t.position[1] / 50.0) as usize;
        let count = |b: usize| inst.iter().filter(|t| band_of(t) == b && t.position[1] < 150.0).count();
        let area = |b: usize| inst.iter().filter(|t| band_of(t) == b && t.position[1] < 150.0).map(|t| PI * (t.crown_radius as f64).powi(2)).sum::<f64>();
        // one instance per stem in the sparse bands, none without stems
        assert_eq!((count(0), count(1), count(2)), (400, 800, 0));
        // drawn plan cover = the Poisson cover of the cohorts' sapling-form crowns
        let r = sapling_form(beech, 1.5).1 as f64;
        assert!((r - 0.5 * 0.45 * 1.5).abs() < 1e-6, "beech sapling crown radius {r} m");
        let lambda = PI * r * r / 25.0;
        assert!(lambda > 0.005 && lambda < 0.5, "beech sapling crown radius {r} m");
        let want1 = 400.0 * 25.0 * (1.0 - (-lambda).exp());
        assert!((area(0) / want1 - 1.0).abs() < 1e-3, "band 1: {} m² drawn, {want1} m² covered", area(0));
        // twice the density: the cover of 2 stems, (1 + e^-λ) times that of one: ~ proportional
        let ratio = area(1) / area(0);
        assert!((ratio - (1.0 + (-lambda).exp())).abs() < 1e-3 && ratio > 1.6, "ratio {ratio}");
        // the thicket covers its cells (clumps of at most 3 instances per cohort)
        let thicket: Vec<&TreeInstance> = inst.iter().filter(|t| t.position[1] >= 150.0).collect();
        assert_eq!(thicket.len(), 40 * 3);
        let cover = thicket.iter().map(|t| PI * (t.crown_radius as f64).powi(2)).sum::<f64>() / (40.0 * 25.0);
        assert!(cover > 0.95 && cover < 1.01, "thicket cover {cover}");
        // deterministic, and inside their light cells
        assert_eq!(inst, instances_with_saplings(&[], &cohorts, &lib, &cond, Season::Summer));
        for (t, c) in inst.iter().zip(cohorts.iter().filter(|c| c.stems > 0).flat_map(|c| std::iter::repeat_n(c, sapling_clumps(beech, c.stems, c.height_m, 5.0).0 as usize))) {
            assert!((t.position[0] as f64 - c.x_m).abs() <= 2.5 && (t.position[1] as f64 - c.y_m).abs() <= 2.5);
        }
    }

    #[test]
    fn young_trees_and_saplings_are_drawn_with_the_sapling_form_of_tree_grow() {
        // issue 32, round 35: the stills drew the simulation's young trees and the cohorts'
        // saplings as round tufts on sticks; now their crowns are the sapling form that `sylva
        // tree grow` gives the species (one function, forest_form::sapling_blend)
        use crate::structure::forest_form::{tree_form, Habit};
        let lib = SpeciesLibrary::embedded().unwrap();
        let cond = SiteConditions::uniform(20, 20, 10.0, 500.0, [5.0; 6], 47.0);
        // (issue 35, round 40: the young tree is re-based on its size, not its age: beech's
        // height–age curve refitted in round 39 puts a 5-year beech at 0.84 m, below the
        // drawn 1 m (`MIN_DRAWN_HEIGHT_M`), so the beech is 8 years old, 1.75 m, the size the
        // test was written for (its old curve's 5-year tree, 1.67 m); all are saplings of full
        // sapling weight, younger than 10 years)
        for (id, wh, age) in [("beech", 0.45, 8.0), ("sessile_oak", 0.45, 5.0), ("norway_spruce", 0.5, 5.0), ("scots_pine", 0.5, 5.0)] {
            let sp = &lib.species[lib.find(id).unwrap() as usize];
            // a young tree of `tree grow`'s height, with a lollipop crown from the simulation
            // (a 0.1 m tuft above a 60 % clear bole), and a 60-year tree
            let form = tree_form(sp, age, Habit::Forest).unwrap();
            let h = form.height_m;
            let young = Plant { id: 1, species: id, x_m: 52.0, y_m: 52.0, height_m: h, crown_radius_m: 0.1, age_yr: age, crown_base_m: 0.6 * h, alive: true };
            let old = Plant { id: 2, species: id, x_m: 152.0, y_m: 152.0, height_m: 25.0, crown_radius_m: 3.0, age_yr: 60.0, crown_base_m: 12.0, alive: true };
            let inst = instances(&[young, old], &lib, &cond, Season::Summer);
            let (y, o) = (inst.iter().find(|t| t.id == 1).unwrap(), inst.iter().find(|t| t.id == 2).unwrap());
            let w = 2.0 * y.crown_radius / y.height;
            assert!((w - wh).abs() < 1e-4 && (w - 2.0 * form.crown_radius_m / h).abs() < 0.02 * wh, "{id}: drawn crown width / height {w}, tree grow {}", 2.0 * form.crown_radius_m / h);
            assert!((y.crown_base - 0.1).abs() < 1e-4 && (form.crown_base_m / h - 0.1).abs() < 1e-3, "{id}: crown base {} of the height", y.crown_base);
            // a tree of 20 years or more keeps the simulation's crown
            assert_eq!((o.crown_radius, o.crown_base), (3.0, 12.0 / 25.0), "{id}");
            // the stand trees of the near field and the exports alike
            let st = crate::job::adapted::stand_trees(&[young, old], &lib, &cond);
            assert!((st[0].1.crown_radius_m - y.crown_radius).abs() < 1e-5 && (st[0].1.crown_base_m - 0.1 * h).abs() < 1e-4, "{id}: {:?}", st[0].1);
            assert_eq!((st[1].1.crown_radius_m, st[1].1.crown_base_m), (3.0, 12.0), "{id}");
            // a cohort's single sapling: crown width / cohort height 0.45–0.5 of the sapling form
            // (its own height jittered ±15 %), live crown from 0.1 of its height
            let c = SaplingCohort { cell: 0, species: id, x_m: 2.5, y_m: 2.5, cell_m: 5.0, stems: 1, height_m: 2.0 };
            let s = sapling_instances(&[c], None, &lib, &cond, Season::Summer);
            assert_eq!(s.len(), 1, "{id}");
            let ws = 2.0 * s[0].crown_radius / 2.0;
            // (the Poisson cover of one stem in its 5 m cell takes < 1 % off the radius)
            assert!((ws - wh).abs() < 0.01 * wh && (s[0].crown_base - 0.1).abs() < 1e-4, "{id}: sapling width / cohort height {ws}, crown base {}", s[0].crown_base);
        }
    }

    #[test]
    fn saplings_under_a_canopy_and_seedlings_are_not_drawn() {
        let lib = SpeciesLibrary::embedded().unwrap();
        let cond = SiteConditions::uniform(20, 20, 10.0, 500.0, [5.0; 6], 47.0);
        let tree = Plant { id: 1, species: "beech", x_m: 102.5, y_m: 102.5, height_m: 25.0, crown_radius_m: 6.0, age_yr: 60.0, crown_base_m: 12.0, alive: true };
        let under = cohort(20 * 40 + 20, 5, 2.0); // centre (102.5, 102.5), under the crown
        let open = cohort(2 * 40 + 2, 5, 2.0);
        let seedlings = cohort(5 * 40 + 5, 50, 0.3);
        let inst = instances_with_saplings(&[tree], &[under, open, seedlings], &lib, &cond, Season::Summer);
        let saplings: Vec<&TreeInstance> = inst.iter().filter(|t| t.id & SAPLING_ID_BIT != 0).collect();
        assert_eq!(inst.len() - saplings.len(), 1, "the tree");
        assert!(!saplings.is_empty() && saplings.iter().all(|t| (t.position[0] - 12.5).abs() < 2.6), "only the open cohort: {saplings:?}");
    }

    /// A 2 km × 2 km ground of 10 m samples around a 1 km window filled with crowns of two
    /// species (70 % / 30 %), flat except a cliff south of y = −300 m, faded into the sky west
    /// of x = −400 m (half) and x = −450 m (wholly); the surroundings are the window mirrored.
    #[test]
    fn surroundings_mirror_the_window_stand() {
        let (w, h) = (200, 200);
        let (mut heights, mut fade) = (vec![500.0f32; w * h], vec![0.0f32; w * h]);
        for r in 0..h {
            for c in 0..w {
                let (x, y) = (-500.0 + (c as f32 + 0.5) * 10.0, -500.0 + (h as f32 - r as f32 - 0.5) * 10.0);
                if y < -300.0 {
                    heights[r * w + c] = 500.0 + 2.0 * (-300.0 - y); // 63°: bare rock
                }
                fade[r * w + c] = if x < -450.0 { 1.0 } else if x < -400.0 { 0.5 } else { 0.0 };
            }
        }
        let ground = crate::render::terrain::GroundGrid {
            heights: Grid { width: w, height: h, data: heights },
            cell_x: 10.0,
            cell_y: 10.0,
            origin: [-500.0, -500.0],
            stream: vec![],
            wetness: vec![],
            fade,
            focus: Some(([0.0, 0.0], [1000.0, 1000.0])),
        };
        let mut land = Landscape { ground, cover: LandCover::default(), mirror_trees: true };
        let mut trees = Vec::new();
        for j in 0..125 {
            for i in 0..125 {
                let id = (j * 125 + i) as u64 + 1;
                let sp = if (i * 7 + j * 3) % 10 < 7 { 0 } else { 1 };
                let id = if sp == 1 { id | SAPLING_ID_BIT } else { id };
                trees.push(TreeInstance::new(id, [4.0 + 8.0 * i as f32, 4.0 + 8.0 * j as f32, 500.0], 25.0, 4.5, sp, [0.1, 0.4, 0.1]));
            }
        }
        assert!(land.surroundings(&[]).is_empty(), "nothing beyond a bare window");
        let far = land.surroundings(&trees);
        assert_eq!(far, land.surroundings(&trees), "deterministic");
        let by_id: std::collections::HashMap<u64, &TreeInstance> = trees.iter().map(|t| (t.id, t)).collect();
        let (mut n, mut sp1) = (0usize, 0usize);
        for t in &far {
            let [x, y, z] = t.position;
            assert!(!((0.0..=1000.0).contains(&x) && (0.0..=1000.0).contains(&y)), "beyond the window: {x} {y}");
            // the image of a window tree across the edges it is beyond
            let k = ((t.id >> 48) & 0xF) as usize;
            assert!((1..=8).contains(&k));
            let src = by_id[&(t.id ^ ((k as u64) << 48))];
            let (mx, my) = MIRRORS[k - 1];
            let mirror = |v: f32, m: i8| match m {
                -1 => -v,
                1 => 2000.0 - v,
                _ => v,
            };
            assert_eq!((x, y), (mirror(src.position[0], mx), mirror(src.position[1], my)));
            assert_eq!((t.species, t.height, t.crown_radius, t.id & SAPLING_ID_BIT), (src.species, src.height, src.crown_radius, src.id & SAPLING_ID_BIT));
            // on the ground there, off the cliff, not where it has faded away, fading with it
            assert!(y > -305.0 && (z - 500.0).abs() < 1e-3, "{x} {y} {z}");
            assert!(x > -455.0, "{x}");
            assert_eq!(t.sky_fade, if x < -400.0 { 0.5 } else { 0.0 }, "{x}");
            n += 1;
            sp1 += t.species as usize;
        }
        // all the ground that keeps trees does, at the window's density (15,625 trees per km²):
        // x from −450 m, y from −300 m to the grid's end at 1500 m, less the window; the
        // window's mix beyond it
        let want = 15_625.0 * (1950.0 * 1800.0 - 1e6) / 1e6;
        assert!((n as f64 / want - 1.0).abs() < 0.05, "{n} trees beyond the window, {want} expected");
        assert!((sp1 as f64 / n as f64 - 0.3).abs() < 0.02, "{sp1} of {n}");
        // a scenario that designs its stand (plantings, harvests) mirrors none (trial 40)
        land.mirror_trees = false;
        assert!(land.surroundings(&trees).is_empty(), "no phantom parcels beyond the window");
    }

    /// A valley running at 30° to the grid: its D8 channel is a staircase of east and
    /// north-east steps. Drawn per cell (as before), the stream's centre in each column jumps
    /// about a straight line by a good part of a cell; drawn along the corner-cut centre lines
    /// of `stream_lines`, it runs straight.
    #[test]
    fn streams_are_drawn_without_the_d8_staircase() {
        use crate::grid::GeoRef;
        let n = 120usize;
        let (ca, sa) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let mut e = Grid::filled(n, n, 0.0f32);
        for r in 0..n {
            for c in 0..n {
                // window-local metres (x east, y north) of the cell centre, from the grid's centre
                let (x, y) = ((c as f32 + 0.5 - 0.5 * n as f32) * 10.0, (0.5 * n as f32 - r as f32 - 0.5) * 10.0);
                let (along, across) = (x * ca + y * sa, -x * sa + y * ca);
                *e.get_mut(c, r) = 500.0 + 0.08 * along + 0.25 * across.abs();
            }
        }
        let t = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: None, source: "test".into() };
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let g = &l.ground;
        let (w, h) = (g.heights.width, g.heights.height);
        // the same channel drawn per cell: the strength of the flow cell under each sample
        let m = crate::terrain::fields::mask(&t, f32::NEG_INFINITY);
        let filled = crate::terrain::fields::fill_depressions(&t, &m);
        let dir = crate::terrain::fields::flow_directions(&filled, &t.geo, &m);
        let acc = crate::terrain::fields::flow_accumulation(&dir, &m);
        let per_cell = |x: f32, y: f32| {
            let (c, r) = ((x / 10.0).floor(), n as f32 - 1.0 - (y / 10.0).floor());
            if c < 0.0 || r < 0.0 || c >= n as f32 || r >= n as f32 {
                return 0.0;
            }
            crate::render::terrain::stream_strength(*acc.get(c as usize, r as usize) * 100.0)
        };
        // per sample column inside the site: the strength-weighted mean y of the stream, then the
        // RMS of these means about their least-squares line (m)
        let roughness = |value: &dyn Fn(usize, usize) -> f32| {
            let mut pts = Vec::new();
            for c in 0..w {
                let x = g.origin[0] + (c as f32 + 0.5) * g.cell_x;
                if !(50.0..=1150.0).contains(&x) {
                    continue;
                }
                let (mut sw, mut sy) = (0.0f64, 0.0f64);
                for r in 0..h {
                    let y = g.origin[1] + (h as f32 - r as f32 - 0.5) * g.cell_y;
                    if (0.0..=1200.0).contains(&y) {
                        let v = value(c, r) as f64;
                        sw += v;
                        sy += v * y as f64;
                    }
                }
                if sw > 0.0 {
                    pts.push((x as f64, sy / sw));
                }
            }
            let k = pts.len() as f64;
            let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / k, pts.iter().map(|p| p.1).sum::<f64>() / k);
            let b = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            let rms = (pts.iter().map(|p| (p.1 - my - b * (p.0 - mx)).powi(2)).sum::<f64>() / k).sqrt();
            (pts.len(), b.atan().to_degrees(), rms)
        };
        let drawn = roughness(&|c, r| g.stream[r * w + c]);
        let raw = roughness(&|c, r| per_cell(g.origin[0] + (c as f32 + 0.5) * g.cell_x, g.origin[1] + (h as f32 - r as f32 - 0.5) * g.cell_y));
        eprintln!("stream columns, direction, RMS about the line: drawn {drawn:?}, per cell {raw:?}");
        // a long stream at about 30°
        assert!(drawn.0 >= 40 && (drawn.1 - 30.0).abs() < 3.0, "{drawn:?}");
        // per cell, the staircase shows (RMS of a few metres on 10 m cells); drawn, it is gone
        assert!(raw.2 > 2.0, "the per-cell drawing should show the staircase: {raw:?}");
        assert!(drawn.2 < 0.3 * raw.2 && drawn.2 < 0.8, "drawn {drawn:?}, per cell {raw:?}");
    }

    #[test]
    fn landscape_shows_the_dem_beyond_the_window_and_fades_out_at_its_edge() {
        use crate::grid::GeoRef;
        // a 60 x 40 DEM of 10 m: a plane rising 0.2 m/m eastwards, cut by a valley along row 20
        // draining west; a nodata block in the north-east
        let (w, h) = (60usize, 40usize);
        let mut e = Grid::filled(w, h, 0.0f32);
        for r in 0..h {
            for c in 0..w {
                *e.get_mut(c, r) = if c >= 40 && r < 8 { f32::NAN } else { 500.0 + 2.0 * c as f32 + 3.0 * (r as f32 - 20.0).abs() };
            }
        }
        let full = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: None, source: "test".into() };
        let win = [20, 10, 20, 20];
        let t = crate::terrain::io::window(&full, win[0], win[1], win[2], win[3]).unwrap();
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, Some((&full, win)), 10.0, f32::NEG_INFINITY).unwrap();
        let g = &l.ground;
        // margin: half the window's side (100 m = 10 samples) on every side
        assert_eq!((g.heights.width, g.heights.height, g.origin), (40, 40, [-100.0, -100.0]));
        let at = |x: f32, y: f32| {
            let c = ((x - g.origin[0]) / g.cell_x - 0.5).round() as usize;
            let r = (g.heights.height as f32 - (y - g.origin[1]) / g.cell_y - 0.5).round() as usize;
            r * g.heights.width + c
        };
        // inside the window: the site's heights, no fade
        let i = at(55.0, 75.0);
        assert_eq!(g.heights.data[i], site.elevation_at(55.0, 75.0));
        assert_eq!(g.fade[i], 0.0);
        // beyond it: the DEM (column 20 + (x - 5)/10 - ..., row of y) and a fade rising outwards
        let (x, y) = (-45.0f32, 75.0f32); // column 15, row 10 + 20 - 8 - 1 = 22 (north of the window's south edge)
        let (c, r) = ((20.0 + (x / 10.0) - 0.5).round() as usize, (10.0 + 20.0 - y / 10.0 - 0.5).round() as usize);
        assert_eq!(g.heights.data[at(x, y)], *full.elevation.get(c, r));
        let f_near = g.fade[at(-5.0, 75.0)];
        let f_mid = g.fade[at(-55.0, 75.0)];
        let f_far = g.fade[at(-95.0, 75.0)];
        assert!(f_near == 0.0 && f_mid > 0.0 && f_mid < f_far && f_far > 0.95, "{f_near} {f_mid} {f_far}");
        // the nodata corner (columns 40-59, rows 0-7: x ≥ 205 m, y ≥ 225 m) is filled flat and
        // faded out, although it is near the window
        let k = at(215.0, 235.0);
        assert!(g.heights.data[k].is_finite() && g.fade[k] > 0.95, "{}", g.fade[k]);
        assert!(g.fade[at(215.0, 165.0)] < 0.5, "the DEM south of it is shown: {}", g.fade[at(215.0, 165.0)]);
        // the valley floor (row 20: y = 95 m) is a stream, the slopes are not
        assert!(g.stream[at(-95.0, 95.0)] > 0.0 && g.stream[at(-95.0, 45.0)] == 0.0, "{} {}", g.stream[at(-95.0, 95.0)], g.stream[at(-95.0, 45.0)]);
        // the mesh's bounds are the window's: cameras frame the site, not its surroundings
        let m = l.mesh(&[]).unwrap();
        m.validate().unwrap();
        let (lo, hi) = m.bounds();
        assert!(lo[0] >= 0.0 && lo[1] >= 0.0 && hi[0] <= 200.0 && hi[1] <= 200.0 && hi[0] > 190.0, "{lo:?} {hi:?}");
        assert!(m.full_bounds().0[0] < -90.0);
        // forest floor under a crown
        let tree = TreeInstance::new(1, [105.0, 105.0, 600.0], 20.0, 20.0, 0, [0.1, 0.3, 0.1]);
        let m2 = l.mesh(&[tree]).unwrap();
        let v = at(105.0, 105.0);
        assert!(m2.colors[v][0] > m2.colors[v][1] && m.colors[v][1] > m.colors[v][0], "{:?} vs {:?}", m2.colors[v], m.colors[v]);
        // without surroundings the site's mirror image fades out by the end of the margin
        let alone = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let ga = &alone.ground;
        assert!(ga.fade.iter().all(|f| (0.0..=1.0).contains(f)) && ga.fade[0] > 0.99);
    }

    /// Issue 32: a tree put at the site's bilinear elevation stood above or below the drawn
    /// ground on a twisted slope (30 m DEM cells, 10 m render samples); after
    /// [`Landscape::stand_on_ground`] every stem base is on the drawn triangles
    /// ([`crate::render::terrain::TerrainMesh::height_at`]) within 1 cm.
    #[test]
    fn trees_stand_on_the_drawn_ground() {
        use crate::grid::GeoRef;
        let n = 24usize;
        let mut e = Grid::filled(n, n, 0.0f32);
        for r in 0..n {
            for c in 0..n {
                let (x, y) = ((c as f32 + 0.5) * 30.0, ((n - r) as f32 - 0.5) * 30.0);
                // a slope of ~30 % with ridges across it: twisted cells
                *e.get_mut(c, r) = 600.0 + 0.3 * y + 12.0 * (x / 70.0).sin() * (y / 55.0).cos();
            }
        }
        let t = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(30.0, 47.0), nodata: None, source: "test".into() };
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let mesh = l.mesh(&[]).unwrap();
        let mut inst: Vec<TreeInstance> = (0..400u64)
            .map(|k| {
                let (x, y) = (20.0 + 680.0 * super::saplings::unit(k) as f32, 20.0 + 680.0 * super::saplings::unit(k ^ 0xabcd) as f32);
                TreeInstance::new(k, [x, y, site.elevation_at(x as f64, y as f64)], 4.0, 0.6, 0, [0.1, 0.3, 0.1])
            })
            .collect();
        let off = |inst: &[TreeInstance]| inst.iter().map(|t| (t.position[2] - mesh.height_at(t.position[0], t.position[1]).unwrap()).abs()).fold(0.0f32, f32::max);
        let before = off(&inst);
        l.stand_on_ground(&mut inst);
        let after = off(&inst);
        eprintln!("largest stem base off the drawn ground: {before:.3} m at the site's elevation, {after:.4} m on the ground");
        assert!(before > 0.05, "the test slope must be twisted enough to matter: {before} m");
        assert!(after < 0.01, "{after} m off the drawn ground");
    }

    /// Round 34 (issue 32): a DEM's no-data hole is a hole in the ground drawn — no triangle over
    /// it and no wall around it — in every view (the stills, `sylva render`, `sylva view` and the
    /// export draw this mesh or the same samples). It was drawn at the 0 m the site holds in a
    /// no-data cell: a shaft hundreds of metres deep, walled (the top-down map showed a dark
    /// square with bright walls). A 30 × 30 slope of 10 m cells with a 6 × 4-cell hole (x
    /// 100–160 m, y 150–190 m); the cells beside it keep their own heights.
    #[test]
    fn no_data_holes_are_drawn_as_holes_without_walls() {
        use crate::grid::GeoRef;
        let n = 30;
        let mut e = Grid::filled(n, n, 0.0f32);
        let in_hole = |c: usize, r: usize| (10..16).contains(&c) && (11..15).contains(&r);
        for r in 0..n {
            for c in 0..n {
                *e.get_mut(c, r) = if in_hole(c, r) { f32::NAN } else { 400.0 + 2.0 * c as f32 + 1.0 * (n - r) as f32 };
            }
        }
        let t = crate::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: Some(-9999.0), source: "test".into() };
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let l = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
        let m = l.mesh(&[]).unwrap();
        m.validate().unwrap();
        let hole = |x: f32, y: f32| (100.0..160.0).contains(&x) && (150.0..190.0).contains(&y);
        let (mut over, mut steep, mut beside) = (0, 0.0f32, 0usize);
        for tri in m.indices.chunks(3) {
            let p: Vec<glam::Vec3> = tri.iter().map(|&k| glam::Vec3::from(m.positions[k as usize])).collect();
            let c = (p[0] + p[1] + p[2]) / 3.0;
            if hole(c.x, c.y) {
                over += 1;
            }
            // the slope of every triangle of the window (the ground's own: 12.6°): a wall would
            // be near 90°
            if (0.0..300.0).contains(&c.x) && (0.0..300.0).contains(&c.y) {
                let nz = (p[1] - p[0]).cross(p[2] - p[0]).normalize().z;
                steep = steep.max(nz.clamp(-1.0, 1.0).acos().to_degrees());
            }
            if (90.0..170.0).contains(&c.x) && (140.0..200.0).contains(&c.y) {
                beside += 1;
            }
        }
        assert_eq!(over, 0, "triangles over the no-data hole");
        assert!(steep < 15.0, "steepest triangle {steep}° (the slope is 12.6°): a wall at the hole's rim");
        assert!(beside > 0, "the ground beside the hole is drawn");
        // the samples of the hole are NaN (no apron), those beside it on the slope
        for (x, y) in [(130.0f32, 170.0f32), (105.0, 155.0), (155.0, 185.0)] {
            assert!(l.ground.height_at(x, y).is_none(), "({x}, {y}) is in the hole");
        }
        for (x, y) in [(95.0f64, 165.0f64), (165.0, 165.0), (130.0, 145.0), (130.0, 195.0)] {
            let want = 400.0 + 2.0 * (x / 10.0 - 0.5) + (n as f64 - (n as f64 - y / 10.0 - 0.5));
            let got = site.elevation_at_valid(x, y, f32::NEG_INFINITY) as f64;
            assert!((got - want).abs() < 1e-3, "({x}, {y}): {got} m, the slope there {want} m");
        }
        assert!(site.elevation_at_valid(130.0, 170.0, f32::NEG_INFINITY).is_nan());
        // a tree on a valid cell at the hole's rim (its quad left out) stands on the ground
        // beside the hole, not at the 0 m the site holds in the hole (it showed deep in it)
        let rim = [(97.0f32, 170.0f32), (163.0, 152.0), (130.0, 192.0), (130.0, 147.0)];
        let mut inst: Vec<TreeInstance> = rim.iter().enumerate().map(|(k, &(x, y))| TreeInstance::new(k as u64, [x, y, site.elevation_at(x as f64, y as f64)], 20.0, 3.0, 0, [0.1, 0.3, 0.1])).collect();
        assert!(inst.iter().any(|t| t.position[2] < 400.0), "the site's bilinear elevation at the rim is pulled towards 0 m");
        l.stand_on_ground(&mut inst);
        for t in &inst {
            let want = 400.0 + 2.0 * (t.position[0] / 10.0 - 0.5) + (t.position[1] / 10.0 + 0.5);
            assert!((t.position[2] - want).abs() < 3.0, "{:?}: {} m, the slope there {want} m", t.position, t.position[2]);
        }
    }
}
