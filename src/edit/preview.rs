//! The editor's live 3-D preview: one tree of the edited species regrown on a worker thread
//! after each change (the window stays responsive; a change made while a tree grows is grown
//! next, intermediate ones are skipped), and the highlight of the part of the tree a hovered
//! control changes (EcoMod's "visual hint": the branches of the Gravelius or Weibull orders a
//! poly-line point acts on, `004_*.txt` §II.B).

use std::sync::mpsc;

use crate::mesh::{LodChain, TreeMesh, LOD_LEVELS};
use crate::render::scene::{Prototype, TreeInstance};
use crate::species::Species;
use crate::structure::mesh::{branch_mesh, lod_chain, LodOptions};
use crate::structure::species_tree::{grow_species_tree, Model};
use crate::structure::{crown_radius, normalised, Skeleton};

/// What a tree is grown from.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The species as edited.
    pub species: Species,
    /// Growth model.
    pub model: Model,
    /// Age (years, > 0).
    pub age_yr: f32,
    /// Random seed.
    pub seed: u64,
}

/// A grown preview tree.
#[derive(Debug, Clone)]
pub struct Grown {
    /// The request it answers.
    pub request: Request,
    /// Skeleton normalised to 1 m height (base at the origin).
    pub skeleton: Skeleton,
    /// Level-of-detail chain of the normalised tree.
    pub lods: LodChain,
    /// Height of the grown tree (m).
    pub height_m: f32,
    /// Crown radius of the grown tree (m).
    pub crown_radius_m: f32,
    /// Seconds the growth and meshing took.
    pub seconds: f32,
}

/// Grows one preview tree (what the worker runs).
///
/// # Errors
/// As [`grow_species_tree`] and [`normalised`] (bad parameters, a tree of height 0).
pub fn grow(r: &Request) -> crate::Result<Grown> {
    let t0 = std::time::Instant::now();
    let g = grow_species_tree(&r.species, r.model, r.age_yr, &[], r.seed)?;
    let h = g.skeleton.height();
    let cr = crown_radius(&g.skeleton, &g.leaves);
    let (sk, lv) = normalised(&g.skeleton, &g.leaves, 1.0)?;
    let lods = lod_chain(&sk, &lv, &LodOptions::default());
    Ok(Grown { request: r.clone(), skeleton: sk, lods, height_m: h, crown_radius_m: cr, seconds: t0.elapsed().as_secs_f32() })
}

/// The worker thread that regrows the preview.
pub struct Grower {
    tx: Option<mpsc::Sender<Request>>,
    rx: mpsc::Receiver<std::result::Result<Grown, String>>,
    busy: bool,
    queued: Option<Request>,
    /// The last request sent.
    pub last: Option<Request>,
}

impl Default for Grower {
    fn default() -> Self {
        Self::new()
    }
}

impl Grower {
    /// Starts the worker.
    pub fn new() -> Self {
        let (tx, wrx) = mpsc::channel::<Request>();
        let (wtx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            while let Ok(r) = wrx.recv() {
                if wtx.send(grow(&r).map_err(|e| e.to_string())).is_err() {
                    break;
                }
            }
        });
        Grower { tx: Some(tx), rx, busy: false, queued: None, last: None }
    }

    /// Asks for `r` unless it is the last one asked for.
    pub fn request(&mut self, r: Request) {
        if self.last.as_ref() == Some(&r) {
            return;
        }
        self.last = Some(r.clone());
        if self.busy {
            self.queued = Some(r);
        } else if let Some(tx) = &self.tx {
            self.busy = tx.send(r).is_ok();
        }
    }

    /// Whether a tree is growing.
    pub fn busy(&self) -> bool {
        self.busy
    }

    /// A finished tree (or the error of a failed growth), if one is ready; sends the queued
    /// request on.
    pub fn poll(&mut self) -> Option<std::result::Result<Grown, String>> {
        let got = self.rx.try_recv().ok()?;
        self.received(got)
    }

    /// A result arrived: the worker is free, so the queued request (if any) is sent now.
    fn received(&mut self, got: std::result::Result<Grown, String>) -> Option<std::result::Result<Grown, String>> {
        self.busy = false;
        if let Some(q) = self.queued.take() {
            if let Some(tx) = &self.tx {
                self.busy = tx.send(q).is_ok();
            }
        }
        Some(got)
    }

    /// Waits for the tree being grown (tests and screenshots).
    pub fn wait(&mut self) -> Option<std::result::Result<Grown, String>> {
        if !self.busy {
            return None;
        }
        let got = self.rx.recv().ok()?;
        self.received(got)
    }
}

/// Which branches a hovered control acts on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Highlight {
    /// Branches of Gravelius order in `lo..=hi`.
    Gravelius(f32, f32),
    /// Segments of Weibull order in `lo..=hi`.
    Weibull(f32, f32),
}

impl Highlight {
    /// Whether a node of orders `(g, w)` is highlighted.
    pub fn contains(&self, g: u16, w: u16) -> bool {
        match *self {
            Highlight::Gravelius(lo, hi) => (g as f32) >= lo - 0.5 && (g as f32) <= hi + 0.5,
            Highlight::Weibull(lo, hi) => (w as f32) >= lo - 0.5 && (w as f32) <= hi + 0.5,
        }
    }
}

/// The orders a poly-line point acts on: from its left neighbour's abscissa to its right one's
/// (the segments on both sides change when it moves); the whole range for `None` (the curve).
pub fn affected_range(pts: &[[f64; 2]], point: Option<usize>, x_range: (f64, f64)) -> (f32, f32) {
    match point {
        Some(i) if i < pts.len() => {
            let lo = if i > 0 { pts[i - 1][0] } else { x_range.0 };
            let hi = if i + 1 < pts.len() { pts[i + 1][0] } else { x_range.1 };
            (lo as f32, hi as f32)
        }
        _ => (x_range.0 as f32, x_range.1 as f32),
    }
}

/// The highlight prototype: the highlighted segments of `sk` (normalised; a segment is
/// highlighted when the node it ends at is) as tubes 1.6 × as thick, in bright magenta, at every level of detail, no leaves. Empty when nothing matches.
pub fn highlight_prototype(sk: &Skeleton, h: Highlight) -> Option<Prototype> {
    let keep: Vec<bool> = sk.nodes.iter().map(|n| h.contains(n.gravelius, n.weibull)).collect();
    if !keep.iter().skip(1).any(|&k| k) {
        return None;
    }
    // the other segments shrink to nothing (a tube ring of radius 0), so the highlighted
    // branches keep their places in the tree's axes
    let mut fat = sk.clone();
    for (n, k) in fat.nodes.iter_mut().zip(&keep) {
        n.radius = if *k { (n.radius * 1.6).max(0.0025) } else { 0.0 };
    }
    let bark = branch_mesh(&fat, &LodOptions::default(), None);
    let level = TreeMesh { bark, leaves: Default::default() };
    let levels: [TreeMesh; LOD_LEVELS] = std::array::from_fn(|_| level.clone());
    Some(Prototype { name: "highlight".into(), lods: LodChain::new(levels.into()), bark_color: [1.0, 0.05, 0.7], leaf_color: [1.0, 0.05, 0.7], stiffness: 1.0, look: None, rigid: false })
}

/// The instance of a preview prototype `p` for a tree of `height_m` at the origin: scaled
/// uniformly (the crown radius given is the prototype's own × height).
pub fn instance(p: &Prototype, index: u32, height_m: f32, leaf_amount: f32) -> TreeInstance {
    let mut t = TreeInstance::new(1, [0.0, 0.0, 0.0], height_m.max(0.1), p.normalised_crown_radius() * height_m.max(0.1), index, p.leaf_color);
    t.rotation = 0.0;
    t.leaf_amount = leaf_amount;
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affected_range_spans_the_neighbours() {
        let pts = [[0.0, 1.0], [7.5, 0.45], [15.0, 1.0]];
        assert_eq!(affected_range(&pts, Some(1), (0.0, 15.0)), (0.0, 15.0));
        assert_eq!(affected_range(&pts, Some(0), (0.0, 15.0)), (0.0, 7.5));
        assert_eq!(affected_range(&pts, None, (0.0, 50.0)), (0.0, 50.0));
        assert!(Highlight::Gravelius(1.0, 2.0).contains(2, 9) && !Highlight::Gravelius(1.0, 2.0).contains(3, 0));
        assert!(Highlight::Weibull(4.0, 4.0).contains(0, 4) && !Highlight::Weibull(4.0, 4.0).contains(4, 6));
    }

    #[test]
    fn a_beech_preview_grows_and_its_first_order_branches_highlight() {
        let lib = crate::species::SpeciesLibrary::embedded().unwrap();
        let sp = lib.get("beech").unwrap().clone();
        let g = grow(&Request { species: sp, model: Model::EcoMod, age_yr: 20.0, seed: 1 }).unwrap();
        assert!(g.height_m > 1.0 && g.crown_radius_m > 0.1, "{} {}", g.height_m, g.crown_radius_m);
        assert!((g.skeleton.height() - 1.0).abs() < 1e-3);
        let area = |p: &Prototype| {
            let m = &p.lods.levels[0].bark;
            m.indices.chunks(3).map(|t| {
                let v = |i: u32| glam::Vec3::from(m.positions[i as usize]);
                0.5 * (v(t[1]) - v(t[0])).cross(v(t[2]) - v(t[0])).length()
            }).sum::<f32>()
        };
        let first = highlight_prototype(&g.skeleton, Highlight::Gravelius(1.0, 1.0)).unwrap();
        let trunk = highlight_prototype(&g.skeleton, Highlight::Gravelius(0.0, 0.0)).unwrap();
        let both = highlight_prototype(&g.skeleton, Highlight::Gravelius(0.0, 1.0)).unwrap();
        let (a1, a0, a01) = (area(&first), area(&trunk), area(&both));
        assert!(a1 > 0.0 && a0 > 0.0, "{a1} {a0}");
        // the surfaces of disjoint orders add up (to the tapering rings where they meet)
        assert!((a01 - (a0 + a1)).abs() < 0.25 * a01, "{a01} vs {a0} + {a1}");
        assert!(highlight_prototype(&g.skeleton, Highlight::Gravelius(40.0, 50.0)).is_none());
    }
}
