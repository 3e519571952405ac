//! The viewer's adapted near field (issue 32): when the camera rests on a snapshot year, the
//! trees near the camera that the frame draws at the full level get their own full-detail
//! meshes, adapted with their neighbours and the scenario's obstacles by Plastic Trees (Pirk et
//! al. 2012, `000_*.txt`; [`crate::structure::stand::adapt_stand`]) and meshed with their
//! crown's leaf area ([`crate::job::adapted::adapted_model`]) as the stills and the stand
//! exports do.
//!
//! **Which trees** ([`select_near`]): the live trees of the year shown whose bounding sphere is
//! in the view, whose stem stands within [`NEAR_M`] of the eye (horizontally) and that are at
//! least [`crate::render::lod::LodParams::switch_px`]`[0] · (1 − band)` tall on screen (where
//! the frame's full level begins to fade in), the largest on screen first, at most
//! [`MAX_FULL_TREES`].
//!
//! **Off the UI thread.** A worker thread ([`NearField`]) grows each tree's species skeleton at
//! its age as a forest tree, adapts the trees among their neighbours and meshes them; the UI
//! keeps drawing (the species' models stand in for them) and swaps the meshes in when they
//! arrive. Each request carries a generation: a camera that moves on supersedes it, and the
//! worker drops a superseded request before adapting or before meshing (an adaptation under
//! way finishes, its trees go to the cache).
//!
//! **Cache.** The adapted trees (skeleton, leaves, leaf clusters: about a tenth of their
//! meshes' bytes) are kept by (tree id, year), at most [`CACHE_TREES`], the least recently
//! wanted dropped first; a tree wanted again is meshed again, not adapted again. The meshes of
//! the trees shown are held by the scene (and the renderer's copy) only while they are shown.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use crate::conditions::SiteConditions;
use crate::job::adapted::{self, AdaptedModel, LeafCover};
use crate::job::inventory::InventoryRow;
use crate::render::camera::Camera;
use crate::render::lod::{Frustum, LodParams};
use crate::render::scene::TreeInstance;
use crate::sim::obstacle::ObstacleSpec;
use crate::species::SpeciesLibrary;
use crate::structure::stand::{adapt_stand, SkeletonCache, StandOptions, StandTree, FULL_STRANDS};
use crate::structure::Skeleton;

/// Largest horizontal distance (m) from the eye of a tree adapted in the viewer: 80 m, as the
/// stills' near field ([`crate::job::adapted::AdaptOptions`]).
pub const NEAR_M: f32 = 80.0;

/// Most trees of a view given their adapted full-detail meshes: 100 (half the stills'
/// [`crate::job::adapted::DEFAULT_MAX_FULL_TREES`]: a window is smaller than a still, and the
/// meshes are held while they are shown).
pub const MAX_FULL_TREES: usize = 100;

/// Most adapted trees kept in the worker's cache (skeletons and leaves, about 0.3 MB each at
/// full detail).
pub const CACHE_TREES: usize = 600;

/// A tree of a view's near field: its id, the snapshot year and where it stands in the
/// instances shown.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearTree {
    /// Tree id.
    pub id: u64,
    /// Projected height (px) in the view.
    pub px: f32,
}

/// The trees of `inst` that get adapted meshes in a view of `camera` `height_px` pixels tall
/// drawn with level parameters `lod`: in the view, within [`NEAR_M`] of the eye, at least
/// `lod.switch_px[0] · (1 − lod.band)` px tall, not faded out (opacity > 0.5), not stumps
/// (`is_stump`), the largest on screen first (ties: lower id), at most [`MAX_FULL_TREES`].
pub fn select_near(inst: &[TreeInstance], camera: &Camera, width_px: f32, height_px: f32, lod: &LodParams, is_stump: impl Fn(&TreeInstance) -> bool) -> Vec<NearTree> {
    let eye = Vec3::from(camera.eye);
    let frustum = Frustum::from_view_proj(camera.view_proj(width_px.max(1.0) / height_px.max(1.0)));
    let full_px = lod.switch_px[0] * (1.0 - lod.band);
    let mut near: Vec<NearTree> = inst
        .iter()
        .filter(|t| t.opacity > 0.5 && t.height > 0.0 && !is_stump(t))
        .filter(|t| (Vec3::from(t.position) - eye).truncate().length() <= NEAR_M)
        .filter_map(|t| {
            let (c, r) = crate::render::instanced::bounding_sphere(t);
            if !frustum.sphere_visible(c, r) {
                return None;
            }
            let px = camera.projected_size_px(Vec3::from(t.position) + Vec3::Z * (0.5 * t.height), t.height, height_px);
            (px >= full_px).then_some(NearTree { id: t.id, px })
        })
        .collect();
    near.sort_by(|a, b| b.px.total_cmp(&a.px).then(a.id.cmp(&b.id)));
    near.truncate(MAX_FULL_TREES);
    near
}

/// What the worker is asked: adapt and mesh `wanted` (tree ids of snapshot `year`) among
/// `rows` (the snapshot's trees near the eye).
pub struct NearRequest {
    /// Generation ([`NearField::request`]); a newer one supersedes it.
    pub generation: u64,
    /// Snapshot year.
    pub year: u32,
    /// Trees wanted, in order.
    pub wanted: Vec<u64>,
    /// Those of them the viewer shows already (not meshed again).
    pub shown: Vec<u64>,
    /// The snapshot's inventory rows within reach of the wanted trees (targets and neighbours).
    pub rows: Vec<InventoryRow>,
}

/// One tree meshed by the worker.
pub struct NearModel {
    /// Tree id.
    pub id: u64,
    /// The stand tree it was adapted as (species, stem base, crown).
    pub tree: StandTree,
    /// Its meshes.
    pub model: AdaptedModel,
}

/// What the worker answers.
pub struct NearResult {
    /// The request's generation.
    pub generation: u64,
    /// Snapshot year.
    pub year: u32,
    /// Trees wanted, in order (as requested).
    pub wanted: Vec<u64>,
    /// The wanted trees not shown before, meshed.
    pub models: Vec<NearModel>,
    /// Trees adapted for this request (the others came from the cache).
    pub adapted: usize,
    /// Trees taken from the cache.
    pub from_cache: usize,
    /// Seconds adapting, and meshing.
    pub adapt_s: f64,
    /// Seconds meshing.
    pub mesh_s: f64,
    /// An error of the adaptation (the trees then keep their species' models).
    pub error: Option<String>,
}

/// An adapted tree kept by the worker: what meshing it again needs.
struct Kept {
    tree: StandTree,
    skeleton: Skeleton,
    /// Its leaves, made when it is meshed (16 B a node held instead of 44 B a leaf).
    leaves: crate::structure::stand::AdaptedLeaves,
    leaf_clusters: Vec<crate::structure::plastic::LeafCluster>,
    /// When it was last wanted (request counter).
    used: u64,
}

/// The worker thread of the viewer's near field and the channels to it. Dropping it stops the
/// worker (after the request under way).
pub struct NearField {
    tx: Option<mpsc::Sender<NearRequest>>,
    rx: mpsc::Receiver<NearResult>,
    latest: Arc<AtomicU64>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl NearField {
    /// Starts the worker for the trees of `library` on `site` with the scenario's `obstacles`,
    /// growing the skeletons with the scenario's `seed`.
    pub fn start(library: SpeciesLibrary, site: SiteConditions, obstacles: Vec<ObstacleSpec>, seed: u64) -> NearField {
        let (tx, req_rx) = mpsc::channel::<NearRequest>();
        let (res_tx, rx) = mpsc::channel::<NearResult>();
        let latest = Arc::new(AtomicU64::new(0));
        let l2 = latest.clone();
        let handle = std::thread::Builder::new()
            .name("sylva near field".into())
            .spawn(move || worker(library, site, obstacles, seed, req_rx, res_tx, l2))
            .ok();
        NearField { tx: Some(tx), rx, latest, handle }
    }

    /// Asks for `req` (its generation is set here, superseding every earlier request); returns
    /// the generation.
    pub fn request(&self, mut req: NearRequest) -> u64 {
        let g = self.latest.fetch_add(1, Ordering::SeqCst) + 1;
        req.generation = g;
        if let Some(tx) = &self.tx {
            let _ = tx.send(req);
        }
        g
    }

    /// Supersedes every request sent (the camera moved on); returns the new generation.
    pub fn cancel(&self) -> u64 {
        self.latest.fetch_add(1, Ordering::SeqCst) + 1
    }

    /// The latest generation.
    pub fn generation(&self) -> u64 {
        self.latest.load(Ordering::SeqCst)
    }

    /// A result, when one has arrived.
    pub fn poll(&self) -> Option<NearResult> {
        self.rx.try_recv().ok()
    }
}

impl Drop for NearField {
    fn drop(&mut self) {
        self.latest.fetch_add(1, Ordering::SeqCst);
        self.tx = None;
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn worker(library: SpeciesLibrary, site: SiteConditions, obstacles: Vec<ObstacleSpec>, seed: u64, rx: mpsc::Receiver<NearRequest>, tx: mpsc::Sender<NearResult>, latest: Arc<AtomicU64>) {
    let mut cache = SkeletonCache::new(seed, FULL_STRANDS);
    let mut kept: HashMap<(u64, u32), Kept> = HashMap::new();
    let cover = LeafCover::of(&library);
    let opts = StandOptions { latitude_deg: site.geo.latitude_deg as f32, obstacles: adapted::solids(&obstacles, &site), ..StandOptions::default() };
    let mut counter = 0u64;
    while let Ok(mut req) = rx.recv() {
        // only the newest request waiting counts
        while let Ok(r) = rx.try_recv() {
            req = r;
        }
        if req.generation != latest.load(Ordering::SeqCst) {
            continue;
        }
        counter += 1;
        let t0 = std::time::Instant::now();
        let plants = crate::job::scene::plants_from_rows(&req.rows);
        let stand = adapted::stand_trees(&plants, &library, &site);
        let trees: Vec<StandTree> = stand.iter().map(|(_, t)| *t).collect();
        let by_id: HashMap<u64, usize> = trees.iter().enumerate().map(|(k, t)| (t.id, k)).collect();
        let shown: std::collections::HashSet<u64> = req.shown.iter().copied().collect();
        let missing: Vec<usize> = req.wanted.iter().filter(|id| !kept.contains_key(&(**id, req.year))).filter_map(|id| by_id.get(id).copied()).collect();
        let from_cache = req.wanted.len() - missing.len();
        let mut error = None;
        if !missing.is_empty() {
            match adapt_stand(&trees, &missing, &library, &mut cache, &opts) {
                Ok(st) => {
                    for a in st.trees {
                        let t = trees[a.index];
                        kept.insert((t.id, req.year), Kept { tree: t, skeleton: a.skeleton, leaves: a.leaves, leaf_clusters: a.leaf_clusters, used: counter });
                    }
                }
                Err(e) => error = Some(e.to_string()),
            }
        }
        let adapt_s = t0.elapsed().as_secs_f64();
        for id in &req.wanted {
            if let Some(k) = kept.get_mut(&(*id, req.year)) {
                k.used = counter;
            }
        }
        // the least recently wanted beyond CACHE_TREES go
        if kept.len() > CACHE_TREES {
            let mut by_use: Vec<((u64, u32), u64)> = kept.iter().map(|(k, v)| (*k, v.used)).collect();
            by_use.sort_by_key(|&(k, u)| (u, k));
            for (k, _) in by_use.iter().take(kept.len() - CACHE_TREES) {
                kept.remove(k);
            }
        }
        if req.generation != latest.load(Ordering::SeqCst) {
            continue;
        }
        let t1 = std::time::Instant::now();
        let todo: Vec<(u64, &Kept)> = req.wanted.iter().filter(|id| !shown.contains(id)).filter_map(|id| kept.get(&(*id, req.year)).map(|k| (*id, k))).collect();
        let models: Vec<NearModel> = todo
            .par_iter()
            .filter_map(|(id, k)| {
                let a = crate::structure::stand::AdaptedTree { index: 0, skeleton: k.skeleton.clone(), leaves: k.leaves.clone(), report: Default::default(), clusters_before: Vec::new(), clusters_after: Vec::new(), leaf_clusters: k.leaf_clusters.clone() };
                let model = adapted::adapted_model(a, &k.tree, &library.species[k.tree.species as usize], Some(&cover))?;
                Some(NearModel { id: *id, tree: k.tree, model })
            })
            .collect();
        let res = NearResult { generation: req.generation, year: req.year, wanted: std::mem::take(&mut req.wanted), models, adapted: missing.len(), from_cache, adapt_s, mesh_s: t1.elapsed().as_secs_f64(), error };
        if tx.send(res).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trees in view, within NEAR_M and tall enough on screen for the full level, largest
    /// first, at most MAX_FULL_TREES; none behind the camera, beyond 80 m or faded out.
    #[test]
    fn the_near_field_is_the_full_level_trees_in_view_within_80_m() {
        let cam = Camera::look_at([0.0, 0.0, 1.7], [0.0, 100.0, 8.0], 60.0);
        let lod = crate::render::lod::LodParams { switch_px: [110.0, 45.0, 18.0], ..Default::default() };
        let tree = |id: u64, x: f32, y: f32, h: f32| TreeInstance::new(id, [x, y, 0.0], h, 0.2 * h, 0, [0.1, 0.4, 0.1]);
        let mut inst = vec![
            tree(1, 0.0, 10.0, 20.0),  // near, tall on screen
            tree(2, 0.0, 40.0, 20.0),  // farther: smaller on screen
            tree(3, 0.0, -30.0, 20.0), // behind the eye
            tree(4, 0.0, 90.0, 30.0),  // beyond 80 m
            tree(5, 0.0, 70.0, 2.0),   // too small on screen for the full level
            tree(6, 3.0, 12.0, 20.0),
        ];
        inst[5].opacity = 0.2; // faded out (dead between snapshots)
        let sel = select_near(&inst, &cam, 800.0, 600.0, &lod, |_| false);
        let ids: Vec<u64> = sel.iter().map(|t| t.id).collect();
        assert_eq!(ids, vec![1, 2], "{sel:?}");
        assert!(sel[0].px > sel[1].px && sel[1].px >= 110.0 * 0.75);
        // at most MAX_FULL_TREES, the largest on screen
        let many: Vec<TreeInstance> = (0..300).map(|k| tree(100 + k, (k % 20) as f32 * 2.0 - 20.0, 8.0 + (k / 20) as f32 * 3.0, 18.0)).collect();
        let sel = select_near(&many, &cam, 800.0, 600.0, &lod, |_| false);
        assert_eq!(sel.len(), MAX_FULL_TREES);
        assert!(sel.windows(2).all(|w| w[0].px >= w[1].px));
        // stumps are left out
        assert!(select_near(&inst, &cam, 800.0, 600.0, &lod, |t| t.id == 1).iter().all(|t| t.id != 1));
    }
}
