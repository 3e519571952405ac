//! Plastic Trees (Pirk, Stava, Kratt, Massih Said, Neubert, Měch, Benes & Deussen 2012,
//! `000_*.txt`): adapts an already grown skeleton to a changed environment (an obstacle, a
//! neighbour's crown) by bending and pruning its branches, instead of regrowing it.
//!
//! Adaptation (our simplified reading of sections 4.2–5.1):
//! 1. **Light** (eq. 3): the light i(p) at a point is the mean over 25 sky directions (zenith;
//!    8 azimuths at 20°, 45°, 70°) of the transmittance Π γ along the ray: 0 through a solid
//!    obstacle, γ_c0 through each leaf cluster; the average light direction is the same mean of
//!    the unit directions. Leaf clusters are spheres on the tip nodes (radius = the mean tip
//!    segment length); a cluster containing the point does not shade it. Light is evaluated on
//!    the clusters; a branch segment uses the light-weighted mean direction of the clusters it
//!    carries.
//! 2. **Inverse tropism** (eqs. 6–9): every segment's direction h in the tree's original
//!    environment is the tropism-bent version of an untropic direction d_o,
//!    h = w_s·d_o + (1 − w_s)·t with t = (w_p·L + w_g·up)/(w_p + w_g) (L: average light
//!    direction, phototropism w_p, gravitropism w_g of the species) and
//!    w_s = (1 − w_p − w_g)^(l_s/l_i) (eq. 7). d_o is found from the quadratic (9), or from its
//!    closest point when it has no root.
//! 3. **Bending** (eq. 6 with the new light): h' = w_s·(Q_parent d_o) + (1 − w_s)·t', where
//!    Q_parent is the parent segment's rotation h → h' (so a turn propagates to the children
//!    without piling up along long axes). The tropism weight 1 − w_s is scaled by a flexibility
//!    1 − r/(0.3·r_base) (clamped to 0–1; r: segment radius): the trunk and main limbs stay
//!    put, twigs bend fully (our stand-in for the branch ages of section 4.1). The subtree is rebuilt from the root with the new
//!    directions and the old segment lengths.
//! 4. **Pruning** (eqs. 10–11): ζ_s = Σ 2π r_c² i_c over the leaf clusters of the subtree of s,
//!    l_s = the subtree's total branch length, ψ_s = ζ_s/l_s. The reference ψ_ref is the
//!    5th percentile of ψ_s in the original environment; a subtree is pruned when its ψ_s in
//!    the new environment falls below c_ψ·min(ψ_ref, ψ_s(original)) (eq. 11 with a single
//!    growth stage: the branch ages of section 4.1 are not reconstructed).
//! 5. **Collisions**: any node that ends inside an obstacle or below the ground after bending,
//!    or whose segment crosses an obstacle, is pruned with its subtree (section 5.2 prunes the leaf clusters an obstacle intersects).

use super::grow::space::{validate_obstacles, Obstacle};
use super::skeleton::Skeleton;
use crate::error::{Error, Result};
use crate::species::PlasticParams;
use glam::{Quat, Vec3};

/// What an adaptation did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlasticReport {
    /// Segments turned by more than 1°.
    pub bent: usize,
    /// Nodes removed by light pruning (eq. 11), subtrees included.
    pub pruned_light: usize,
    /// Nodes removed because they ended inside an obstacle, subtrees included.
    pub pruned_collision: usize,
}

fn sky_dirs() -> Vec<Vec3> {
    let mut dirs = vec![Vec3::Z];
    for e in [20.0f32, 45.0, 70.0] {
        let (se, ce) = e.to_radians().sin_cos();
        for k in 0..8 {
            let a = k as f32 * std::f32::consts::FRAC_PI_4;
            dirs.push(Vec3::new(ce * a.cos(), ce * a.sin(), se));
        }
    }
    dirs
}

/// Light model of eq. (3) with opaque obstacles and translucent leaf clusters.
struct Light<'a> {
    dirs: Vec<Vec3>,
    clusters: Vec<Vec3>,
    r_c: f32,
    gamma_c: f32,
    obstacles: &'a [Obstacle],
}

impl Light<'_> {
    /// (i(p) in 0–1, average light direction (unit, up when dark)).
    fn at(&self, p: Vec3) -> (f32, Vec3) {
        let mut sum = 0.0;
        let mut dir = Vec3::ZERO;
        let r2 = self.r_c * self.r_c;
        for &d in &self.dirs {
            if self.obstacles.iter().any(|o| o.ray_hits(p, d, f32::INFINITY)) {
                continue;
            }
            let mut t = 1.0f32;
            // clusters sorted by height: those wholly below p cannot be on an upward ray
            let first = self.clusters.partition_point(|c| c.z + self.r_c < p.z);
            for &c in &self.clusters[first..] {
                let oc = c - p;
                if oc.length_squared() <= r2 {
                    continue;
                }
                let along = oc.dot(d);
                if along > 0.0 && oc.length_squared() - along * along <= r2 {
                    t *= self.gamma_c;
                    if t < 1e-3 {
                        break;
                    }
                }
            }
            sum += t;
            dir += d * t;
        }
        (sum / self.dirs.len() as f32, dir.normalize_or(Vec3::Z))
    }
}

/// Per node: light (tips only), light direction, and ψ_s = ζ_s / l_s of its subtree (eq. 10).
fn analyse(sk: &Skeleton, light: &Light) -> (Vec<f32>, Vec<Vec3>, Vec<f32>) {
    let n = sk.nodes.len();
    // light is evaluated on the leaf clusters (tips); a branch sees the light-weighted mean
    // direction of the clusters it carries
    let mut i_n = vec![0.0f32; n];
    let mut dsum = vec![Vec3::ZERO; n];
    let mut zeta = vec![0.0f32; n];
    let mut len = vec![0.0f32; n];
    let area = 2.0 * std::f32::consts::PI * light.r_c * light.r_c;
    for k in (1..n).rev() {
        if sk.nodes[k].children.is_empty() {
            let (i, d) = light.at(sk.nodes[k].pos);
            i_n[k] = i;
            dsum[k] += d * i.max(1e-3);
            zeta[k] += area * i;
        }
        len[k] += sk.segment_length(k);
        if let Some(p) = sk.nodes[k].parent {
            let (z, l, d) = (zeta[k], len[k], dsum[k]);
            zeta[p as usize] += z;
            len[p as usize] += l;
            dsum[p as usize] += d;
        }
    }
    let d_n = dsum.iter().map(|d| d.normalize_or(Vec3::Z)).collect();
    let psi = zeta.iter().zip(&len).map(|(z, l)| if *l > 0.0 { z / l } else { 0.0 }).collect();
    (i_n, d_n, psi)
}

/// Inverse tropism (eqs. 8–9): the untropic direction d_o with h = w_s·d_o + t_w (t_w =
/// (1 − w_s)·t), h and t unit vectors.
pub fn inverse_tropism(h: Vec3, t: Vec3, w_s: f32) -> Vec3 {
    if w_s <= 1e-6 {
        return h;
    }
    let tw = (1.0 - w_s) * t;
    let (a, b, c) = (h.length_squared(), h.dot(tw), tw.length_squared() - w_s * w_s);
    let disc = b * b - a * c;
    let p = if disc >= 0.0 { (b + disc.sqrt()) / a } else { b / a };
    ((p * h - tw) / w_s).normalize_or(h)
}

/// Adapts `sk` (grown without `obstacles`) to `obstacles` with the species' Plastic Trees
/// parameters; `internode_m` (> 0) is the internode length l_i of eq. (7). Returns the adapted
/// skeleton (radii kept, pruned subtrees removed, tips re-marked) and what was done. With no
/// obstacles the tree is returned unchanged.
///
/// Errors: [`Error::Invalid`] for an invalid obstacle, `internode_m` ≤ 0, tropism weights
/// outside 0 ≤ w_p, w_g with w_p + w_g < 1, or γ_c0 outside 0–1.
pub fn adapt(sk: &Skeleton, p: &PlasticParams, obstacles: &[Obstacle], internode_m: f32) -> Result<(Skeleton, PlasticReport)> {
    validate_obstacles(obstacles)?;
    let bad = |f: &str, v: String, e: &str| Err(Error::Invalid { context: "Plastic Trees".into(), field: f.into(), value: v, expected: e.into() });
    if !(internode_m > 0.0 && internode_m.is_finite()) {
        return bad("internode_m", internode_m.to_string(), "a length > 0 m");
    }
    let (wp, wg) = (p.phototropism, p.gravitropism);
    if !(wp >= 0.0 && wg >= 0.0 && wp + wg < 1.0) {
        return bad("phototropism/gravitropism", format!("{wp}/{wg}"), "weights ≥ 0 with a sum < 1 (eq. 7)");
    }
    if !(0.0..=1.0).contains(&p.translucency_gamma_c0) {
        return bad("translucency_gamma_c0", p.translucency_gamma_c0.to_string(), "0 ..= 1");
    }
    let mut report = PlasticReport { bent: 0, pruned_light: 0, pruned_collision: 0 };
    if obstacles.is_empty() || sk.nodes.len() < 2 {
        return Ok((sk.clone(), report));
    }
    let n = sk.nodes.len();
    let tips: Vec<usize> = (1..n).filter(|&k| sk.nodes[k].children.is_empty()).collect();
    let r_c = (tips.iter().map(|&k| sk.segment_length(k)).sum::<f32>() / tips.len().max(1) as f32).max(0.05);
    let mut clusters: Vec<Vec3> = tips.iter().map(|&k| sk.nodes[k].pos).collect();
    clusters.sort_by(|a, b| a.z.total_cmp(&b.z));
    let before = Light { dirs: sky_dirs(), clusters: clusters.clone(), r_c, gamma_c: p.translucency_gamma_c0, obstacles: &[] };
    let after = Light { dirs: sky_dirs(), clusters, r_c, gamma_c: p.translucency_gamma_c0, obstacles };
    let (_, d0, psi0) = analyse(sk, &before);
    let (_, d1, _) = analyse(sk, &after);
    // bending, parents before children
    let tropism = |l: Vec3| ((wp * l + wg * Vec3::Z) / (wp + wg).max(1e-6)).normalize_or(Vec3::Z);
    let mut out = sk.clone();
    let mut rot = vec![Quat::IDENTITY; n];
    let r_root = sk.nodes.iter().map(|nd| nd.radius).fold(0.0f32, f32::max).max(1e-6);
    for k in 1..n {
        let par = sk.nodes[k].parent.unwrap_or(0) as usize;
        let seg = sk.nodes[k].pos - sk.nodes[par].pos;
        let len = seg.length();
        let mut q = rot[par];
        if len > 0.0 && wp + wg > 0.0 {
            let h = seg / len;
            // stiffness: the trunk and main limbs (radius ≥ 30 % of the base radius) do not
            // bend, thinner branches bend more (our stand-in for the paper's branch ages)
            let flex = (1.0 - sk.nodes[k].radius / (0.3 * r_root)).clamp(0.0, 1.0);
            let w_s = 1.0 - (1.0 - (1.0 - wp - wg).powf(len / internode_m)) * flex;
            let d_o = inverse_tropism(h, tropism(d0[k]), w_s);
            // the untropic direction follows the parent's turn; the new tropism bends it once
            let h_new = (w_s * (rot[par] * d_o) + (1.0 - w_s) * tropism(d1[k])).normalize_or(h);
            q = Quat::from_rotation_arc(h, h_new);
            if h.angle_between(h_new) > 1f32.to_radians() {
                report.bent += 1;
            }
        }
        rot[k] = q;
        out.nodes[k].pos = out.nodes[par].pos + q * seg;
    }
    // pruning (eq. 11) in the adapted tree and collisions
    // the leaf clusters move with their bent branches (section 5.3)
    let mut moved: Vec<Vec3> = tips.iter().map(|&k| out.nodes[k].pos).collect();
    moved.sort_by(|a, b| a.z.total_cmp(&b.z));
    let after = Light { clusters: moved, ..after };
    let (_, _, psi1) = analyse(&out, &after);
    let mut sorted: Vec<f32> = psi0[1..].to_vec();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let psi_ref = sorted.get(sorted.len() / 20).copied().unwrap_or(0.0);
    let mut remove = vec![false; n];
    let mut light_cut = vec![false; n];
    for k in 1..n {
        let inside = out.nodes[k].pos.z < 0.0 || obstacles.iter().any(|o| o.contains(out.nodes[k].pos));
        let par = out.nodes[k].parent.unwrap_or(0) as usize;
        let crosses = obstacles.iter().any(|o| {
            let a = out.nodes[par].pos;
            let d = out.nodes[k].pos - a;
            let l = d.length();
            l > 0.0 && o.ray_hits(a, d / l, l)
        });
        if inside || crosses {
            remove[k] = true;
        } else if psi1[k] < p.pruning_c_psi * psi_ref.min(psi0[k]) {
            remove[k] = true;
            light_cut[k] = true;
        }
    }
    // count removed nodes by cause (a subtree counts for its topmost flagged node)
    let mut gone = vec![false; n];
    for k in 1..n {
        let par = out.nodes[k].parent.unwrap_or(0) as usize;
        if gone[par] && par != 0 {
            gone[k] = true;
            let mut a = par;
            while !remove[a] {
                a = out.nodes[a].parent.unwrap_or(0) as usize;
            }
            if light_cut[a] {
                report.pruned_light += 1;
            } else {
                report.pruned_collision += 1;
            }
        } else if remove[k] {
            gone[k] = true;
            if light_cut[k] {
                report.pruned_light += 1;
            } else {
                report.pruned_collision += 1;
            }
        }
    }
    out.prune(&remove);
    out.mark_tips();
    Ok((out, report))
}
