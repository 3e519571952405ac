//! Plastic Trees adaptation (Pirk et al. 2012, `000_*.txt`): a grown tree bends away from a
//! wall and sheds the branches that reach into it, without regrowing.
use glam::Vec3;
use sylva::species::SpeciesLibrary;
use sylva::structure::grow::space::Obstacle;
use sylva::structure::plastic::{adapt, inverse_tropism};
use sylva::structure::species_tree::{grow_species_tree, Model};

fn tip_centroid(sk: &sylva::structure::Skeleton) -> Vec3 {
    let tips: Vec<Vec3> = sk.nodes.iter().filter(|n| n.children.is_empty()).map(|n| n.pos).collect();
    tips.iter().copied().sum::<Vec3>() / tips.len() as f32
}

#[test]
fn inverse_tropism_undoes_eq6() {
    let d_o = Vec3::new(0.6, 0.0, 0.8);
    let t = Vec3::new(-0.3, 0.2, 0.93).normalize();
    for w_s in [0.3f32, 0.6, 0.9] {
        let h = (w_s * d_o + (1.0 - w_s) * t).normalize();
        let back = inverse_tropism(h, t, w_s);
        assert!((back - d_o).length() < 1e-4, "w_s {w_s}: {back} vs {d_o}");
    }
}

#[test]
fn branches_near_a_wall_are_bent_away_or_pruned() {
    let lib = SpeciesLibrary::embedded().unwrap();
    let sp = &lib.species[lib.find("beech").unwrap() as usize];
    let g = grow_species_tree(sp, Model::Light, 20.0, &[], 2).unwrap();
    let sk = &g.skeleton;
    let r = sylva::structure::crown_radius(sk, &Default::default());
    let wall = Obstacle::Wall { x: 0.5 * r };
    let internode = (g.envelope.unwrap().height_m / 40.0).max(0.15);
    let mut p = sp.architecture.plastic;
    p.phototropism = 0.25; // the paper's Tree 1 (section 7)
    p.gravitropism = 0.12;
    let (same, rep0) = adapt(sk, &p, &[], internode).unwrap();
    assert_eq!(&same, sk, "no change without obstacles");
    assert_eq!(rep0.bent + rep0.pruned_light + rep0.pruned_collision, 0);
    let (out, rep) = adapt(sk, &p, &[wall], internode).unwrap();
    let (c0, c1) = (tip_centroid(sk), tip_centroid(&out));
    eprintln!("{} nodes -> {} ({rep:?}), crown radius {r:.2} m, tip centroid x {:.2} -> {:.2} m", sk.len(), out.len(), c0.x, c1.x);
    assert!(sk.nodes.iter().any(|n| wall.contains(n.pos)), "the wall cuts the original crown");
    assert!(out.nodes.iter().all(|n| !wall.contains(n.pos) && n.pos.z >= 0.0), "no node inside the wall");
    assert!(rep.bent > 0 && rep.pruned_collision + rep.pruned_light > 0);
    assert!(c1.x < c0.x - 0.1, "the crown moves away from the wall");
    // the adapted tree is still one connected tree rooted at the base
    assert_eq!(out.nodes[0].pos, sk.nodes[0].pos);
    assert!(out.nodes.iter().skip(1).all(|n| n.parent.is_some()));
}
