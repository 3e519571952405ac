//! Laplacian (DBM) growth, Jinasena & Sonnadara `003_*.txt`.
use glam::Vec3;
use sylva::structure::grow::laplacian::{self, LaplacianOptions, WidthForm};
use sylva::structure::grow::space::Obstacle;
use sylva::structure::params::laplacian_paper;

#[test]
fn never_grows_into_obstacle_voxels() {
    let p = laplacian_paper();
    let o = LaplacianOptions::default();
    let obstacles = [Obstacle::Box { min: Vec3::new(-1.0, -1.0, 2.0), max: Vec3::new(0.6, 1.0, 2.6) }, Obstacle::Sphere { center: Vec3::new(1.0, 0.5, 3.5), radius: 0.7 }];
    let g = laplacian::grow(&p, &o, &obstacles, 4, 300).unwrap();
    assert!(g.skeleton.len() > 250, "grew {}", g.skeleton.len());
    for n in &g.skeleton.nodes {
        let i = g.space.index(g.space.cell(n.pos)).unwrap();
        assert!(!g.space.solid[i], "node in an obstacle voxel at {}", n.pos);
        assert!(obstacles.iter().all(|ob| !ob.contains(n.pos)));
    }
    // binary branching: at most two children
    assert!(g.skeleton.nodes.iter().all(|n| n.children.len() <= 2));
    eprintln!("height {} nodes {}", g.skeleton.height(), g.skeleton.len());
}

#[test]
fn grows_towards_a_light_source_and_is_deterministic() {
    let p = laplacian_paper();
    let o = LaplacianOptions { source: laplacian::LightSource::Point(Vec3::new(2.0, 0.0, 5.0), 0.5), ..Default::default() };
    let a = laplacian::grow(&p, &o, &[], 11, 200).unwrap();
    let b = laplacian::grow(&p, &o, &[], 11, 200).unwrap();
    assert_eq!(a.skeleton, b.skeleton);
    let mean: Vec3 = a.skeleton.nodes.iter().map(|n| n.pos).sum::<Vec3>() / a.skeleton.len() as f32;
    assert!(mean.x > 0.2, "leans towards the light at +x: {mean}");
}

#[test]
fn strahler_widths_follow_table_i() {
    // W(k) = 0.67 k^1.15 and 0.67 * 1.5^k
    assert!((laplacian::width(1, WidthForm::Polynomial, 1.5) - 0.67).abs() < 1e-6);
    assert!((laplacian::width(3, WidthForm::Polynomial, 1.5) - 0.67 * 3f32.powf(1.15)).abs() < 1e-5);
    assert!((laplacian::width(2, WidthForm::Exponential, 1.5) - 0.67 * 2.25).abs() < 1e-5);
    let g = laplacian::grow(&laplacian_paper(), &LaplacianOptions::default(), &[], 1, 120).unwrap();
    let k = g.skeleton.strahler();
    for (n, &k) in g.skeleton.nodes.iter().zip(&k) {
        let expect = 0.5 * 0.02 * 1.5f32.powi(k as i32 - 1);
        assert!((n.radius - expect).abs() < 1e-6);
    }
    assert!(k[0] >= 2);
}
