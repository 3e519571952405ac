//! Constrained edit distance between unordered labelled trees (Zhang 1996, *Algorithmica* 15,
//! 205–222), as Plastic Trees section 7 (Pirk et al. 2012, `000_*.txt`, after Ferraro & Godin
//! 2000) uses it to compare tree skeletons: the cheapest sequence of node deletions (children
//! move to the parent), insertions and changes turning one tree into the other, where the
//! mapping is constrained (disjoint subtrees map to disjoint subtrees), which makes it
//! polynomial for unordered trees.
//!
//! Costs proportional to branch thickness (section 7): deleting or inserting a node costs its
//! radius r (the segment ending at it); changing node a into b costs |r_a − r_b| plus
//! ½(r_a + r_b)·θ/π, θ the angle between their segment directions (our direction term, so that
//! bending is measured too). Distances are in metres of radius; multiply by 100 for cm.
//!
//! Recurrences (Zhang 1996, section 3), with T[i] the subtree at i and F[i] the forest of its
//! children's subtrees:
//! - d(F1[i], F2[j]) = min{ d(θ, F2[j]) + min_t [d(F1[i], F2[j_t]) − d(θ, F2[j_t])],
//!   d(F1[i], θ) + min_s [d(F1[i_s], F2[j]) − d(F1[i_s], θ)], the minimum-cost matching of the
//!   children (unmatched ones deleted or inserted whole) };
//! - d(T1[i], T2[j]) = min{ d(θ, T2[j]) + min_t [d(T1[i], T2[j_t]) − d(θ, T2[j_t])],
//!   d(T1[i], θ) + min_s [d(T1[i_s], T2[j]) − d(T1[i_s], θ)], d(F1[i], F2[j]) + γ(i → j) }.
//!
//! The matching is solved exactly by dynamic programming over subsets of the smaller child set
//! (at most [`MAX_FANOUT`] children per node).

use crate::error::{Error, Result};
use crate::structure::Skeleton;
use glam::Vec3;

/// Largest number of children of a node on the smaller side of a child matching.
pub const MAX_FANOUT: usize = 16;

fn dirs(sk: &Skeleton) -> Vec<Vec3> {
    sk.nodes
        .iter()
        .map(|n| match n.parent {
            Some(p) => (n.pos - sk.nodes[p as usize].pos).normalize_or(Vec3::Z),
            None => Vec3::Z,
        })
        .collect()
}

/// Constrained edit distance between two skeletons (m of radius; see the module docs for the
/// costs). Both must have parents before children (as every [`Skeleton`] does). O(n1·n2·k)
/// time (k: the matching's cost per node pair), O(n1·n2) memory.
///
/// Errors: [`Error::Invalid`] for an empty skeleton, or a pair of nodes whose smaller child set
/// exceeds [`MAX_FANOUT`].
pub fn constrained_edit_distance(a: &Skeleton, b: &Skeleton) -> Result<f32> {
    let (n1, n2) = (a.nodes.len(), b.nodes.len());
    if n1 == 0 || n2 == 0 {
        return Err(Error::Invalid { context: "constrained edit distance".into(), field: "nodes".into(), value: format!("{n1} and {n2}"), expected: "two non-empty skeletons".into() });
    }
    let (da, db) = (dirs(a), dirs(b));
    let change = |i: usize, j: usize| {
        let (ra, rb) = (a.nodes[i].radius, b.nodes[j].radius);
        (ra - rb).abs() + 0.5 * (ra + rb) * da[i].angle_between(db[j]) / std::f32::consts::PI
    };
    // deletion / insertion of whole subtrees and forests
    let whole = |sk: &Skeleton| {
        let n = sk.nodes.len();
        let (mut t, mut f) = (vec![0.0f32; n], vec![0.0f32; n]);
        for i in (0..n).rev() {
            t[i] = f[i] + sk.nodes[i].radius;
            if let Some(p) = sk.nodes[i].parent {
                f[p as usize] += t[i];
            }
        }
        (t, f)
    };
    let (t1, f1) = whole(a);
    let (t2, f2) = whole(b);
    let mut dt = vec![0.0f32; n1 * n2];
    let mut df = vec![0.0f32; n1 * n2];
    let at = |i: usize, j: usize| i * n2 + j;
    for i in (0..n1).rev() {
        let ci = &a.nodes[i].children;
        for j in (0..n2).rev() {
            let cj = &b.nodes[j].children;
            // forests
            let fv = if ci.is_empty() {
                f2[j]
            } else if cj.is_empty() {
                f1[i]
            } else {
                let ins = f2[j] + cj.iter().map(|&t| df[at(i, t as usize)] - f2[t as usize]).fold(f32::INFINITY, f32::min);
                let del = f1[i] + ci.iter().map(|&s| df[at(s as usize, j)] - f1[s as usize]).fold(f32::INFINITY, f32::min);
                let m = matching(ci, cj, |s, t| dt[at(s, t)], |s| t1[s], |t| t2[t])?;
                ins.min(del).min(m)
            };
            df[at(i, j)] = fv;
            // trees
            let mut tv = fv + change(i, j);
            if !cj.is_empty() {
                tv = tv.min(t2[j] + cj.iter().map(|&t| dt[at(i, t as usize)] - t2[t as usize]).fold(f32::INFINITY, f32::min));
            }
            if !ci.is_empty() {
                tv = tv.min(t1[i] + ci.iter().map(|&s| dt[at(s as usize, j)] - t1[s as usize]).fold(f32::INFINITY, f32::min));
            }
            dt[at(i, j)] = tv;
        }
    }
    Ok(dt[0])
}

/// Minimum-cost matching of child sets `ci`, `cj`: matched pairs cost `pair`, unmatched children
/// are deleted (`del`) or inserted (`ins`) whole. Exact, by dynamic programming over subsets of
/// the smaller set.
fn matching(ci: &[u32], cj: &[u32], pair: impl Fn(usize, usize) -> f32, del: impl Fn(usize) -> f32, ins: impl Fn(usize) -> f32) -> Result<f32> {
    let swap = ci.len() > cj.len();
    let (small, large) = if swap { (cj, ci) } else { (ci, cj) };
    if small.len() > MAX_FANOUT {
        return Err(Error::Invalid { context: "constrained edit distance".into(), field: "children".into(), value: small.len().to_string(), expected: format!("at most {MAX_FANOUT} children on the smaller side of a node pair") });
    }
    let cost = |s: usize, l: usize| if swap { pair(large[l] as usize, small[s] as usize) } else { pair(small[s] as usize, large[l] as usize) };
    let lone_small = |s: usize| if swap { ins(small[s] as usize) } else { del(small[s] as usize) };
    let lone_large = |l: usize| if swap { del(large[l] as usize) } else { ins(large[l] as usize) };
    let full = 1usize << small.len();
    let mut dp = vec![f32::INFINITY; full];
    dp[0] = 0.0;
    for l in 0..large.len() {
        let mut next = vec![f32::INFINITY; full];
        for mask in 0..full {
            let v = dp[mask];
            if !v.is_finite() {
                continue;
            }
            let skip = v + lone_large(l);
            if skip < next[mask] {
                next[mask] = skip;
            }
            for s in 0..small.len() {
                if mask & (1 << s) == 0 {
                    let m = mask | (1 << s);
                    let c = v + cost(s, l);
                    if c < next[m] {
                        next[m] = c;
                    }
                }
            }
        }
        dp = next;
    }
    let mut best = f32::INFINITY;
    for (mask, &v) in dp.iter().enumerate() {
        let rest: f32 = (0..small.len()).filter(|s| mask & (1 << s) == 0).map(lone_small).sum();
        best = best.min(v + rest);
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertical chain/branching built from (parent, radius) with every segment along +z.
    fn tree(spec: &[(Option<u32>, f32)]) -> Skeleton {
        let mut s = Skeleton::new();
        for (i, &(p, r)) in spec.iter().enumerate() {
            match p {
                None => {
                    s.add_root(Vec3::ZERO, r);
                }
                Some(p) => {
                    let pos = s.nodes[p as usize].pos + Vec3::Z;
                    s.add_child(p, pos, r, i > 1).unwrap();
                }
            }
        }
        s
    }

    #[test]
    fn identical_trees_are_at_distance_zero() {
        let t = tree(&[(None, 1.0), (Some(0), 0.5), (Some(1), 0.3), (Some(1), 0.2)]);
        assert_eq!(constrained_edit_distance(&t, &t).unwrap(), 0.0);
    }

    #[test]
    fn deleting_a_leaf_costs_its_radius() {
        let a = tree(&[(None, 1.0), (Some(0), 0.5)]);
        let b = tree(&[(None, 1.0)]);
        assert!((constrained_edit_distance(&a, &b).unwrap() - 0.5).abs() < 1e-6);
        assert!((constrained_edit_distance(&b, &a).unwrap() - 0.5).abs() < 1e-6, "insertion is symmetric");
    }

    #[test]
    fn children_order_does_not_matter() {
        // root → {a 0.5, b 0.3} vs root → {b 0.3, a 0.5}
        let a = tree(&[(None, 1.0), (Some(0), 0.5), (Some(0), 0.3)]);
        let b = tree(&[(None, 1.0), (Some(0), 0.3), (Some(0), 0.5)]);
        assert!(constrained_edit_distance(&a, &b).unwrap().abs() < 1e-6);
    }

    #[test]
    fn deleting_an_inner_node_moves_its_children_up() {
        // root → x(0.4) → {p 0.2, q 0.1} vs root → {p, q}: delete x (0.4), keep p and q. The
        // directions do not change (all segments vertical).
        let a = tree(&[(None, 1.0), (Some(0), 0.4), (Some(1), 0.2), (Some(1), 0.1)]);
        let b = tree(&[(None, 1.0), (Some(0), 0.2), (Some(0), 0.1)]);
        assert!((constrained_edit_distance(&a, &b).unwrap() - 0.4).abs() < 1e-6);
    }

    #[test]
    fn relabelling_is_cheaper_than_delete_plus_insert() {
        // |0.5 − 0.2| = 0.3 < 0.5 + 0.2
        let a = tree(&[(None, 1.0), (Some(0), 0.5)]);
        let b = tree(&[(None, 1.0), (Some(0), 0.2)]);
        assert!((constrained_edit_distance(&a, &b).unwrap() - 0.3).abs() < 1e-6);
        // a bend of 90° between equal radii 0.2: ½·0.4·(π/2)/π = 0.1
        let mut c = b.clone();
        c.nodes[1].pos = Vec3::X;
        assert!((constrained_edit_distance(&b, &c).unwrap() - 0.1).abs() < 1e-6);
    }

    #[test]
    fn the_mapping_is_constrained() {
        // a: root → {x → {p, q}, y}; b: root → {x' → {p'}, y' → {q'}} (all radii 0.1, vertical).
        // Unconstrained mappings could send p, q under different parents for free; the
        // constrained one must map disjoint subtrees to disjoint subtrees, so q or q' goes:
        // cost 2 × 0.1 (delete q, insert q') = 0.2.
        let a = tree(&[(None, 0.1), (Some(0), 0.1), (Some(1), 0.1), (Some(1), 0.1), (Some(0), 0.1)]);
        let b = tree(&[(None, 0.1), (Some(0), 0.1), (Some(1), 0.1), (Some(0), 0.1), (Some(3), 0.1)]);
        assert!((constrained_edit_distance(&a, &b).unwrap() - 0.2).abs() < 1e-6);
    }
}
