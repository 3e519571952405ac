//! EcoMod strand model (`004_*.txt` Algorithm 1) with the paper's beech and pine parameters.
use sylva::species::EcoModParams;
use sylva::structure::grow::ecomod;

fn check_conservation(sk: &sylva::structure::Skeleton) {
    for n in &sk.nodes[1..] {
        if !n.children.is_empty() {
            let sum: u32 = n.children.iter().map(|&c| sk.nodes[c as usize].strands).sum();
            assert_eq!(sum, n.strands, "children's strands must sum to the parent's");
            assert_eq!(n.children.len(), 2);
        } else {
            assert_eq!(n.strands, 1, "tips carry one strand");
        }
    }
}

#[test]
fn beech_s1000_builds_with_paper_parameters() {
    let p = EcoModParams::beech_paper();
    let (sk, leaves) = ecomod::grow(&p, 1, 0.0);
    assert_eq!(sk.len(), 2 * 1000, "root + 2S-1 segments");
    check_conservation(&sk);
    let tips = sk.nodes.iter().filter(|n| n.children.is_empty()).count();
    assert_eq!(tips, 1000);
    assert_eq!(leaves.len(), 1000 * 5, "rho_l = 5 leaves per tip");
    // d = k_d sqrt(S): trunk diameter 0.01*sqrt(1000)
    assert!((sk.nodes[1].radius * 2.0 - 0.01 * 1000f32.sqrt()).abs() < 1e-5);
    // first trunk segment is L0 = 5 m, vertical
    assert!((sk.nodes[1].pos.z - 5.0).abs() < 1e-4);
    let h = sk.height();
    eprintln!("beech height {h} m, bounds {:?}", sk.bounds());
    assert!(h > 5.0 && h < 60.0, "height {h}");
    // pipe model with exponent 2 holds exactly because d ∝ sqrt(S)
    for n in &sk.nodes[1..] {
        if !n.children.is_empty() {
            let s: f32 = n.children.iter().map(|&c| sk.nodes[c as usize].radius.powi(2)).sum();
            assert!((s - n.radius.powi(2)).abs() < 1e-4 * n.radius.powi(2));
        }
    }
}

#[test]
fn pine_s6000_builds_with_paper_parameters() {
    let p = EcoModParams::pine_paper();
    let (sk, leaves) = ecomod::grow(&p, 1, 0.0);
    assert_eq!(sk.len(), 12000);
    check_conservation(&sk);
    assert_eq!(leaves.len(), 6000 * 30);
    let h = sk.height();
    eprintln!("pine height {h} m, bounds {:?}", sk.bounds());
    assert!(h > 5.47 && h < 80.0, "height {h}");
    for n in &sk.nodes {
        assert!(n.pos.is_finite());
    }
}

#[test]
fn same_seed_same_skeleton() {
    let mut p = EcoModParams::beech_paper();
    p.wind_undirected = 2.0;
    p.k_f = 0.5;
    let a = ecomod::grow(&p, 7, 1.0);
    let b = ecomod::grow(&p, 7, 1.0);
    assert_eq!(a, b);
    let c = ecomod::grow(&p, 8, 1.0);
    assert_ne!(a.0, c.0, "another seed changes the sway phases");
    // the wind sway animates with t
    let d = ecomod::grow(&p, 7, 2.0);
    assert_ne!(a.0.nodes[10].pos, d.0.nodes[10].pos);
}

#[test]
fn invalid_parameters_are_reported() {
    let mut p = EcoModParams::beech_paper();
    p.strands = 0;
    assert!(ecomod::try_grow(&p, 1, 0.0).is_err());
    p.strands = 10;
    p.k_d = f32::NAN;
    let e = ecomod::try_grow(&p, 1, 0.0).unwrap_err().to_string();
    assert!(e.contains("k_d"), "{e}");
}
