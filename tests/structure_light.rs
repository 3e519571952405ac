//! Light-guided growth (Yi et al., `001_*.txt`) with obstacles and shared light space.
use glam::Vec3;
use sylva::structure::grow::light_guided::{self, LightOptions, LightSpace};
use sylva::structure::grow::space::Obstacle;
use sylva::structure::params::light_guided_paper;

fn centroid(sk: &sylva::structure::Skeleton) -> Vec3 {
    let tips: Vec<Vec3> = sk.nodes.iter().filter(|n| n.children.is_empty()).map(|n| n.pos).collect();
    tips.iter().copied().sum::<Vec3>() / tips.len() as f32
}

#[test]
fn tree_beside_wall_grows_away_and_never_into_it() {
    let p = light_guided_paper();
    let o = LightOptions::default();
    let wall = Obstacle::Wall { x: 1.5 };
    let sk = light_guided::grow(&p, &o, &[wall], 5, 12).unwrap();
    let free = light_guided::grow(&p, &o, &[], 5, 12).unwrap();
    let c = centroid(&sk);
    let cf = centroid(&free);
    eprintln!("nodes {} (free {}), crown centroid {c} (free {cf}), height {}", sk.len(), free.len(), sk.height());
    assert!(sk.len() > 50, "the tree grows");
    assert!(sk.nodes.iter().all(|n| n.pos.x < 1.5), "no node inside the wall");
    assert!(c.x < -0.1, "crown centroid displaced away from the wall: {c}");
    assert!(c.x < cf.x - 0.1, "more displaced than the free-standing tree");
}

#[test]
fn two_trees_share_light_and_deterministic() {
    let p = light_guided_paper();
    let o = LightOptions { extent_m: 4.0, height_m: 10.0, ..Default::default() };
    let roots = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
    let mut a = LightSpace::new(&roots, &[], p, o, 9).unwrap();
    a.grow(8);
    let mut b = LightSpace::new(&roots, &[], p, o, 9).unwrap();
    b.grow(8);
    assert_eq!(a.trees, b.trees, "same seed, same skeletons");
    // each crown leans away from its neighbour
    let c0 = centroid(&a.trees[0].skeleton);
    let c1 = centroid(&a.trees[1].skeleton);
    eprintln!("centroids {c0} {c1}");
    assert!(c0.x < -1.0 && c1.x > 1.0);
    // pipe model radii: parent radius >= each child's
    for t in &a.trees {
        let sk = &t.skeleton;
        for n in &sk.nodes {
            for &c in &n.children {
                assert!(n.radius + 1e-6 >= sk.nodes[c as usize].radius);
            }
        }
    }
}

#[test]
fn box_obstacle_is_avoided() {
    let p = light_guided_paper();
    let o = LightOptions::default();
    let b = Obstacle::Box { min: Vec3::new(-1.5, -1.5, 2.5), max: Vec3::new(1.5, 1.5, 3.0) };
    let sk = light_guided::grow(&p, &o, &[b], 2, 12).unwrap();
    assert!(sk.nodes.iter().all(|n| !b.contains(n.pos)));
}

#[test]
fn obstacle_parsing() {
    assert_eq!(Obstacle::parse("wall:2").unwrap(), Obstacle::Wall { x: 2.0 });
    assert!(matches!(Obstacle::parse("sphere:0,0,3,1").unwrap(), Obstacle::Sphere { .. }));
    assert!(Obstacle::parse("box:1,2,3").is_err());
    assert!(Obstacle::parse("cone:1").is_err());
}
