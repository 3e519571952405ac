//! How well sky quadratures evaluate eq. (3) of Plastic Trees (Pirk et al. 2012, `000_*.txt`):
//! the light i and the light direction at every node of a light-guided tree (Yi et al. paper
//! parameters; cycles and seed as arguments, default 11 4: the 2,506-node tree of
//! `benches/plastic.rs`), lit through its leaf clusters (eq. 4), open and beside the bench's
//! finite wall, under a sky whose brightest point is at the zenith or 40° high (latitude 50°),
//! against [`Sky::reference`] with 48 bands (5,872 directions). Prints the mean |Δi|, its bias
//! and the mean angle between light directions for the equal-zenith-band skies of rounds 1–10
//! (`zen`, [`Sky::zenith_rings`]) and the importance-sampled ones (`imp`, [`Sky::with_rings`],
//! the default `4,8,12`). Command: `cargo run --release --example sky_quadrature [CYCLES SEED]`.
use glam::Vec3;
use sylva::species::SpeciesLibrary;
use sylva::structure::grow::light_guided::{self, LightOptions};
use sylva::structure::grow::space::Obstacle;
use sylva::structure::params;
use sylva::structure::plastic::light::{Occluder, ShadowVolumes};
use sylva::structure::plastic::{Environment, Ground, PlasticTree, Sky};

/// (i, light direction) of eq. (3) at every point of `pts`: solids tested per ray, the clusters
/// `occ` by shadow volumes.
fn light(sky: &Sky, occ: &[Occluder], obs: &[Obstacle], g: Ground, pts: &[Vec3]) -> Vec<(f32, Vec3)> {
    let vols = ShadowVolumes::new(sky, occ.to_vec());
    pts.iter()
        .map(|&p| {
            let (mut s, mut dir) = (0.0f32, Vec3::ZERO);
            for (k, &d) in sky.dirs.iter().enumerate() {
                if g.blocks(p, d) || obs.iter().any(|o| o.ray_hits(p, d, f32::INFINITY)) {
                    continue;
                }
                let t = vols.transmittance(k, p);
                s += sky.weights[k] * t;
                dir += d * sky.weights[k] * t;
            }
            (s, dir.normalize_or(Vec3::Z))
        })
        .collect()
}

fn main() {
    let args: Vec<u32> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let (years, seed) = (args.first().copied().unwrap_or(11), args.get(1).copied().unwrap_or(4) as u64);
    let lib = SpeciesLibrary::embedded().unwrap();
    let sp = &lib.species[lib.find("beech").unwrap() as usize];
    let p = sp.architecture.plastic;
    let lp = params::light_guided_paper();
    let lo = LightOptions { extent_m: 12.0, height_m: 22.0, ..LightOptions::default() };
    let sk = light_guided::grow(&lp, &lo, &[], seed, years).unwrap();
    let tree = PlasticTree::analyse(&sk, &p, &Environment::open(), None).unwrap();
    let occ: Vec<Occluder> = tree.leaf_clusters().iter().map(|c| Occluder { center: c.center, radius: c.radius, gamma: c.gamma }).collect();
    let pts: Vec<Vec3> = sk.nodes.iter().map(|n| n.pos + Vec3::Z * 1e-3).collect();
    let (lo_b, hi_b) = sk.bounds().unwrap();
    let r = 0.5 * (hi_b.x - lo_b.x).max(hi_b.y - lo_b.y);
    let wall = Obstacle::FiniteWall { x: 0.5 * r, length: 4.0 * r, height: 1.2 * (hi_b.z - lo_b.z) };
    println!("{} nodes, {} clusters", sk.len(), occ.len());
    for (bname, b) in [("zenith", Vec3::Z), ("lat50", Vec3::new(0.0, -(40f32.to_radians().cos()), 40f32.to_radians().sin()))] {
        let reference = Sky::reference(b, 48);
        for (oname, obs) in [("open", vec![]), ("wall", vec![wall])] {
            let rf = light(&reference, &occ, &obs, Ground::flat(0.0), &pts);
            let mean_ref = rf.iter().map(|x| x.0).sum::<f32>() / rf.len() as f32;
            println!("\n{bname} {oname}: reference {} dirs, mean i {mean_ref:.4}", reference.dirs.len());
            let cands: Vec<(String, Sky)> = vec![
                ("zen 4,8,8,12".into(), Sky::zenith_rings(b, &[4, 8, 8, 12]).expect("rings")),
                ("zen 4,4,8".into(), Sky::zenith_rings(b, &[4, 4, 8]).expect("rings")),
                ("zen 4,8".into(), Sky::zenith_rings(b, &[4, 8]).expect("rings")),
                ("zen 4,4".into(), Sky::zenith_rings(b, &[4, 4]).expect("rings")),
                ("imp 4,8,8,12".into(), Sky::with_rings(b, &[4, 8, 8, 12]).expect("rings")),
                ("imp 4,8,12".into(), Sky::with_rings(b, &[4, 8, 12]).expect("rings")),
                ("imp 4,8,8".into(), Sky::with_rings(b, &[4, 8, 8]).expect("rings")),
                ("imp 4,4,8".into(), Sky::with_rings(b, &[4, 4, 8]).expect("rings")),
                ("imp 8,8".into(), Sky::with_rings(b, &[8, 8]).expect("rings")),
                ("imp 4,8".into(), Sky::with_rings(b, &[4, 8]).expect("rings")),
                ("imp 4,4".into(), Sky::with_rings(b, &[4, 4]).expect("rings")),
            ];
            for (name, sky) in cands {
                let l = light(&sky, &occ, &obs, Ground::flat(0.0), &pts);
                let n = l.len() as f32;
                let mae = l.iter().zip(&rf).map(|(a, b)| (a.0 - b.0).abs()).sum::<f32>() / n;
                let bias = l.iter().zip(&rf).map(|(a, b)| a.0 - b.0).sum::<f32>() / n;
                let ang = l.iter().zip(&rf).map(|(a, b)| a.1.dot(b.1).clamp(-1.0, 1.0).acos().to_degrees()).sum::<f32>() / n;
                println!("{name:14} {:3} dirs: |Δi| {mae:.4} bias {bias:+.4}  angle {ang:5.2}°", sky.dirs.len());
            }
        }
    }
}
