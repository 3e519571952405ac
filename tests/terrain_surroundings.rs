//! The ground drawn beyond the end of a DEM (`sylva::job::scene::Landscape::new`).

use sylva::grid::{GeoRef, Grid};
use sylva::job::scene::Landscape;

/// Trial 39: beyond the end of a DEM the ground was the edge samples stretched outwards
/// (streaks) and a site alone faded into the sky within 150 m of its edge (an island). Now the
/// ground there is the DEM's mirror image: on an 800 m site sloping up 0.2 m per m eastwards and
/// 0.05 m per m northwards, a sample 45 m beyond the east edge has the height of the point 45 m
/// inside it (9 m below the edge, where the stretched edge sample stood 9 m above), one beyond
/// the south edge that of the point as far north of it, a corner sample is mirrored on both
/// axes; and the ground 200 m out (of the 400 m margin) is drawn, fading into the haze only
/// towards the margin's end.
#[test]
fn ground_beyond_the_dem_is_its_mirror_image_fading_with_the_margin() {
    let n = 80usize;
    let z = |x: f32, y: f32| 500.0 + 0.2 * x + 0.05 * y;
    let mut e = Grid::filled(n, n, 0.0f32);
    for r in 0..n {
        for c in 0..n {
            *e.get_mut(c, r) = z((c as f32 + 0.5) * 10.0, ((n - r) as f32 - 0.5) * 10.0);
        }
    }
    let t = sylva::terrain::Terrain { elevation: e, geo: GeoRef::local(10.0, 47.0), nodata: None, source: "test".into() };
    let site = sylva::conditions::derive(&t, &sylva::climate::Climate::default()).unwrap();
    let l = Landscape::new(&site, None, 10.0, f32::NEG_INFINITY).unwrap();
    let g = &l.ground;
    let at = |x: f32, y: f32| {
        let c = ((x - g.origin[0]) / g.cell_x - 0.5).round() as usize;
        let r = (g.heights.height as f32 - (y - g.origin[1]) / g.cell_y - 0.5).round() as usize;
        r * g.heights.width + c
    };
    let h = |x: f32, y: f32| g.heights.data[at(x, y)];
    assert_eq!((g.cell_x, g.origin[0], g.heights.width), (10.0, -400.0, 160));
    // inside: the site's own ground
    assert!((h(405.0, 405.0) - z(405.0, 405.0)).abs() < 1e-3);
    // east, south and a corner beyond the edge: mirrored
    assert!((h(845.0, 405.0) - z(755.0, 405.0)).abs() < 1e-3, "{} against the mirrored {} (the edge {})", h(845.0, 405.0), z(755.0, 405.0), z(795.0, 405.0));
    assert!((h(405.0, -45.0) - z(405.0, 45.0)).abs() < 1e-3, "{}", h(405.0, -45.0));
    assert!((h(-45.0, 845.0) - z(45.0, 755.0)).abs() < 1e-3, "{}", h(-45.0, 845.0));
    // 395 m east (beyond the 400 m of the site's half-width mirrored): the west edge's mirror
    assert!((h(1195.0, 405.0) - z(405.0, 405.0)).abs() < 1e-3, "{}", h(1195.0, 405.0));
    // the fade into the sky: none near the edge, from 35 % of the margin (140 m) to its end
    let f = |x: f32| g.fade[at(x, 405.0)];
    assert!(f(845.0) == 0.0 && f(1005.0) < 0.5 && f(1005.0) < f(1145.0) && f(1195.0) > 0.95, "{} {} {} {}", f(845.0), f(1005.0), f(1145.0), f(1195.0));
}
