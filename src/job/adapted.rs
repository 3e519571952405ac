//! The near field of a picture with per-tree adapted skeletons (issue 14): the trees close to the
//! camera are adapted with their neighbours by [`crate::structure::stand::adapt_stand`] (Plastic
//! Trees, Pirk et al. 2012, `000_*.txt`) and get their own meshes at every level of detail; the
//! far field stays instanced species prototypes. The scenario's obstacles are meshed here too.
//!
//! At the mid level ([`CLUSTER_HULL_LEVEL`]) an adapted tree is drawn as the crown hull of its
//! adapted leaf clusters ([`crate::structure::crown_hull`]) on a stem, so a crown that its
//! neighbours or a wall made one-sided stays one-sided from afar; beyond it (billboards, canopy
//! layer) the species' look is drawn as for any tree.
//!
//! Memory and triangles stay bounded: at most [`AdaptOptions::max_trees`] trees, all within
//! [`AdaptOptions::near_m`] of the camera's eye and in front of it, get their own meshes.

use super::scene::{foliage, srgb_to_linear, Plant};
use crate::conditions::SiteConditions;
use crate::mesh::{LodChain, TreeMesh, TriMesh, LOD_LEVELS};
use crate::render::scene::{Camera, Prototype, TreeInstance};
use crate::sim::obstacle::ObstacleSpec;
use crate::species::{Season, SpeciesLibrary};
use crate::obstacle::Obstacle;
use crate::structure::stand::{adapt_stand, AdaptedTree, SkeletonCache, StandOptions, StandTree, FULL_STRANDS};
use crate::structure::{Leaves, Skeleton};
use glam::Vec3;
use rayon::prelude::*;

/// Which trees get adapted skeletons.
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptOptions {
    /// Largest horizontal distance (m) from the camera's eye of an adapted tree.
    pub near_m: f32,
    /// Most trees adapted (the nearest first).
    pub max_trees: usize,
    /// Neighbourhood cells and halo (m) of [`StandOptions`].
    pub cell_m: f32,
    /// See [`StandOptions::halo_m`].
    pub halo_m: f32,
    /// Height (px) of the picture the near field is drawn into.
    pub image_height_px: f32,
    /// Smallest projected height (px, [`Camera::projected_size_px`] of the tree's height at
    /// its middle) of a tree adapted at full detail (its species' strand count at its age,
    /// [`crate::structure::stand::FULL_STRANDS`]); smaller ones, which the picture draws at the
    /// coarser levels, get at most [`FAR_MAX_STRANDS`]. Default: where the renderer's full
    /// level begins to fade in, `switch_px[0] · (1 − band)` of
    /// [`crate::render::lod::LodParams::default`] (180 px).
    pub full_px: f32,
    /// Width (px) of the picture the near field is drawn into; with it (> 0) only trees inside
    /// the camera's view (their bounding spheres, [`crate::render::instanced::bounding_sphere`],
    /// in the frustum of `image_width_px × image_height_px`) are adapted, so that the
    /// [`AdaptOptions::max_trees`] are all in the picture. 0 (the default): every tree in front
    /// of the eye within [`AdaptOptions::near_m`] (until round 36 the stills' too: of the
    /// default run's close-up's 400 adapted trees, 60 were in view, and its foreground, about
    /// 80 m from the eye, was drawn with species prototypes).
    pub image_width_px: f32,
    /// Most trees adapted at full detail (the largest on screen first; the others of
    /// [`AdaptOptions::full_px`] get at most [`FAR_MAX_STRANDS`]): the adaptation's time and
    /// the frame's memory grow with the nodes and leaf cards. Default [`DEFAULT_MAX_FULL_TREES`].
    pub max_full_trees: usize,
    /// Most leaf cards and skeleton nodes of the full-detail trees together, counted on their
    /// species' open-grown trees at full detail ([`full_detail_cost`]; the adapted trees keep
    /// at most these): trees past it, the largest on screen first, get at most
    /// [`FAR_MAX_STRANDS`] like those past [`AdaptOptions::max_full_trees`]. The count of trees
    /// alone hid a multiplier of 20: a 65-year Norway spruce (6,000 strands, needle cards) holds
    /// about 20 times the leaf cards of a beech of the default close-up, and a dense spruce
    /// planting's close-up took 10.1 GiB (trial 39). Default [`DEFAULT_MAX_FULL_CARDS`].
    pub max_full_cards: usize,
}

/// Default of [`AdaptOptions::max_full_cards`]: 3,000,000 leaf cards and nodes. The default
/// run's close-up holds 1.3 M leaf cards on its 200 full-detail trees (BENCHMARKS.md, round 21),
/// so it is not cut; the close-up of a dense 65-year spruce planting (trial 39) is cut from 200
/// to the number of spruces whose cards fit.
pub const DEFAULT_MAX_FULL_CARDS: usize = 3_000_000;

/// What a tree of `key` ([`crate::structure::stand::FormKey`]) costs at full detail: the leaf
/// cards and skeleton nodes of its open-grown tree in `cache` (a cache of
/// [`crate::structure::stand::FULL_STRANDS`], prepared for the key; 0 when it is not grown).
pub fn full_detail_cost(cache: &SkeletonCache, key: crate::structure::stand::FormKey) -> usize {
    cache.get(key).map_or(0, |g| g.leaves.leaves.len() + g.skeleton.nodes.len())
}

/// Which of the trees drawn at the full level get full detail: `costs` are their
/// [`full_detail_cost`]s, the largest on screen first; each in turn is taken while fewer than
/// `max_trees` are taken and its cost fits in what is left of `max_cards` (a tree that does
/// not fit is passed over, and a smaller one after it may fit). Returns one flag per tree.
pub fn choose_full_detail(costs: &[usize], max_trees: usize, max_cards: usize) -> Vec<bool> {
    let (mut taken, mut cards) = (0usize, 0usize);
    costs
        .iter()
        .map(|&c| {
            let fits = taken < max_trees && cards.saturating_add(c) <= max_cards;
            if fits {
                taken += 1;
                cards += c;
            }
            fits
        })
        .collect()
}

/// Default of [`AdaptOptions::max_full_trees`]: 200. The ground view of the default run's
/// year 150 (1280 × 720, `sylva render … --camera ground`) draws 210 adapted trees at the full
/// level; with 200 of them at full detail (median 2,000 nodes for the trees of 15 m and taller,
/// 1.3 M leaf cards) it took 10.3 s to adapt and 4.0 GiB at its peak, with every one of them
/// 4.5 GiB, with none 3.1 GiB (BENCHMARKS.md, round 21). Until round 20 it was 0: the
/// full-detail trees of light-demanding species were shed bare by Plastic Trees' light pruning
/// among their neighbours, which forest-grown trees no longer get
/// ([`crate::structure::stand`], step 4).
pub const DEFAULT_MAX_FULL_TREES: usize = 200;

/// Most EcoMod strands of the adapted trees under [`AdaptOptions::full_px`] (about 60 nodes
/// after shedding: the stand skeletons of round 16, enough for the crown hull and billboard
/// levels they are drawn at).
pub const FAR_MAX_STRANDS: u32 = 48;

impl Default for AdaptOptions {
    /// 80 m, 400 trees, cells of 12 m with a halo of 6 m, a picture 1,080 px tall, full detail
    /// from 180 px for the [`DEFAULT_MAX_FULL_TREES`] largest on screen within
    /// [`DEFAULT_MAX_FULL_CARDS`].
    fn default() -> Self {
        let lod = crate::render::lod::LodParams::default();
        AdaptOptions { near_m: 80.0, max_trees: 400, cell_m: 12.0, halo_m: 6.0, image_height_px: 1080.0, image_width_px: 0.0, full_px: lod.switch_px[0] * (1.0 - lod.band), max_full_trees: DEFAULT_MAX_FULL_TREES, max_full_cards: DEFAULT_MAX_FULL_CARDS }
    }
}

/// The open-grown skeletons of the near field for one scenario seed: full detail for the trees
/// drawn at the full level ([`AdaptOptions::full_px`]), at most [`FAR_MAX_STRANDS`] for the
/// others.
#[derive(Debug, Clone)]
pub struct NearCaches {
    /// Trees drawn at the full level.
    pub full: SkeletonCache,
    /// The others.
    pub far: SkeletonCache,
}

/// Height (m) from which a tree counts in the node-count figures of `--stats`
/// ([`AdaptStats::nodes_median`], `job::export::ExportStats`): the canopy trees whose detail a
/// close view shows (issue 32).
pub const STATS_MIN_HEIGHT_M: f32 = 15.0;

/// Median of `v` (sorted in place; the lower middle of an even count); 0 when empty.
pub fn median_usize(v: &mut [usize]) -> usize {
    if v.is_empty() {
        return 0;
    }
    v.sort_unstable();
    v[(v.len() - 1) / 2]
}

/// What the near field cost and holds (the `--stats` figures of `sylva render`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AdaptStats {
    /// Trees drawn with their own adapted mesh.
    pub adapted_trees: usize,
    /// Wall time of the adaptation (s).
    pub adapt_s: f64,
    /// Wall time of meshing the adapted trees (s).
    pub mesh_s: f64,
    /// Trees adapted in all, context neighbours included.
    pub trees_in_groups: usize,
    /// Adapted trees whose mid level ([`CLUSTER_HULL_LEVEL`]) is the crown hull of their
    /// adapted leaf clusters ([`crate::structure::crown_hull`]; the others keep the leaf-card
    /// hull of [`crate::structure::mesh::hull_mesh`]).
    pub cluster_hulls: usize,
    /// Triangles of those mid levels together (stem and hull; each drawn once per frame at most).
    pub hull_triangles: usize,
    /// Adapted trees by the level the frame drew them at (index [`CLUSTER_HULL_LEVEL`]: as their
    /// cluster hull; the last: billboard), filled by [`super::pictures::Stage`] after the frame:
    /// [`crate::render::lod::select_lod_scaled`] of each tree's projected size with the frame's
    /// switch-size factor, as the culling pass picks (a tree inside a cross-fade band counts at
    /// its finer level); trees outside the frustum, under the smallest size drawn or wholly in
    /// the canopy layer are not counted.
    pub per_level: [usize; LOD_LEVELS],
    /// Adapted trees of 15 m and taller ([`STATS_MIN_HEIGHT_M`]).
    pub trees_15m: usize,
    /// Median skeleton node count of those trees (the lower middle of an even count; 0 when
    /// there are none).
    pub nodes_median: usize,
    /// Smallest skeleton node count of those trees (0 when there are none).
    pub nodes_min: usize,
    /// Leaf cards of the adapted trees' full-detail skeletons together.
    pub leaf_cards: usize,
    /// Leaf-cluster cards (sprigs, [`crown_leaf_cards`]) of the full-detail trees together:
    /// the rest of their crowns' leaf area, drawn on their full level.
    pub sprig_cards: usize,
    /// Leaf area (m², one-sided) of the full-detail trees' leaf cards as Plastic Trees left them
    /// (what the stills drew of them until round 25), together.
    pub adapted_leaf_area_m2: f64,
    /// Leaf area (m², one-sided) the full-detail trees' full levels carry (their crowns' leaf
    /// area, [`crown_leaf_cards`]), together.
    pub leaf_area_m2: f64,
    /// Bytes of the adapted trees' level meshes on the CPU side (positions, normals, texture
    /// coordinates and indices of every level), held during the frame; the renderer's vertex
    /// and index buffers hold about as much again.
    pub mesh_bytes: usize,
    /// Adapted trees at least [`AdaptOptions::full_px`] tall on screen: those the picture may
    /// draw at its full level (the full-detail ones and, beyond [`AdaptOptions::max_full_trees`],
    /// coarser skeletons that still carry their crown's leaf area).
    pub full_level_trees: usize,
    /// Of [`AdaptStats::full_level_trees`], those whose full level carries under half of their
    /// crown's drawn leaf area ([`super::leaf_area::drawn_leaf_area`]): trees that read as
    /// bare up close (issue 32, round 36: the leafless foreground birches). 0 when every tree
    /// near the camera is in leaf.
    pub bare_full_level: usize,
    /// Adapted trees that Plastic Trees left without a leaf card (light-pruned bare among
    /// their neighbours); a full-level one gets leaves at its shoot tips
    /// ([`tip_leaves`]) so that it can carry its crown's leaf area.
    pub shed_bare: usize,
    /// Trees among the [`AdaptOptions::max_full_trees`] largest on screen that
    /// [`AdaptOptions::max_full_cards`] kept from full detail (they get at most
    /// [`FAR_MAX_STRANDS`]).
    pub full_held_back: usize,
}

/// The level of an adapted tree's chain that is its crown hull (LOD2: 40–100 px tall on screen
/// with the default [`crate::render::lod::LodParams`]).
pub const CLUSTER_HULL_LEVEL: usize = 2;

/// Stand trees of `plants` (live, of a species in `library`, at least 1 m tall) with the ground
/// elevation, slope and aspect of `site`, a tree younger than 20 years with the sapling form
/// blended into its crown ([`crate::structure::forest_form::sapling_blend`], as `sylva tree
/// grow`); returns (plant index, stand tree) pairs.
pub fn stand_trees(plants: &[Plant], library: &SpeciesLibrary, site: &SiteConditions) -> Vec<(usize, StandTree)> {
    plants
        .iter()
        .enumerate()
        .filter(|(_, p)| p.alive && p.height_m >= super::scene::MIN_DRAWN_HEIGHT_M)
        .filter_map(|(i, p)| {
            let s = library.find(p.species)?;
            let (slope, aspect) = match site.cell_at(p.x_m, p.y_m) {
                Some((c, r)) => (*site.slope_deg.get(c, r), *site.aspect_deg.get(c, r)),
                None => (0.0, 180.0),
            };
            let (slope, aspect) = if aspect < 0.0 || !slope.is_finite() { (0.0, 180.0) } else { (slope.clamp(0.0, 60.0), aspect) };
            let h = p.height_m;
            // a young tree: the sapling form of `sylva tree grow` (round 35, issue 32)
            let (cb, r) = crate::structure::forest_form::sapling_blend(&library.species[s as usize], p.age_yr.max(0.0), h, p.crown_base_m, p.crown_radius_m);
            Some((
                i,
                StandTree {
                    id: p.id,
                    species: s,
                    base: Vec3::new(p.x_m as f32, p.y_m as f32, site.elevation_at(p.x_m, p.y_m)),
                    age_yr: p.age_yr.max(0.0),
                    height_m: h,
                    crown_radius_m: r.max(0.2),
                    crown_base_m: cb.clamp(0.0, 0.9 * h),
                    slope_deg: slope,
                    aspect_deg: aspect,
                },
            ))
        })
        .collect()
}

/// The first of `obstacles` on `site` whose solids (as drawn and as the light sees them:
/// [`ground_under`], [`ObstacleSpec::solids_on`]) hold the point `p` (m, world coordinates, z
/// the elevation): its index in `obstacles` and its kind ([`ObstacleSpec::kind`]); `None` when
/// `p` is outside them all. `sylva render --camera eye:` refuses such an eye (trial 42: an eye
/// inside a building rendered a grey wall).
pub fn obstacle_around(obstacles: &[ObstacleSpec], site: &SiteConditions, p: [f64; 3]) -> Option<(usize, &'static str)> {
    let q = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
    obstacles.iter().enumerate().find_map(|(i, o)| {
        let (g, low) = ground_under(o, site);
        o.solids_on(g as f64, low as f64).iter().any(|s| s.contains(q)).then(|| (i, o.kind()))
    })
}

/// The Plastic Trees solids of `obstacles` on `site` (world coordinates, heights above the
/// ground at each obstacle's anchor, walls and footprints down to below the lowest ground under
/// them: [`ground_under`], [`ObstacleSpec::solids_on`]).
pub fn solids(obstacles: &[ObstacleSpec], site: &SiteConditions) -> Vec<Obstacle> {
    obstacles
        .iter()
        .flat_map(|o| {
            let (g, low) = ground_under(o, site);
            o.solids_on(g as f64, low as f64)
        })
        .collect()
}

/// The ground under an obstacle on `site` (m, elevations of [`SiteConditions::elevation_at`]):
/// `(under its anchor, lowest under it)`. The lowest is taken over the solid's corners, its
/// sides every quarter of a DEM cell (the bilinear surface's least along a side may lie
/// between grid lines) and its inside on a grid of half a cell: within a few centimetres of
/// the least of the bilinear surface over the plan, which lies at a corner, on a side or at a
/// DEM node inside. A sphere (a boulder, placed in the air or on the ground) gives its
/// anchor's ground for both.
pub fn ground_under(o: &ObstacleSpec, site: &SiteConditions) -> (f32, f32) {
    let a = o.anchor();
    let g = site.elevation_at(a[0], a[1]);
    let corners: Vec<[f64; 2]> = match o {
        ObstacleSpec::Sphere { .. } => return (g, g),
        ObstacleSpec::Box { min, max } => vec![[min[0], min[1]], [max[0], min[1]], [max[0], max[1]], [min[0], max[1]]],
        ObstacleSpec::Wall { start, end, thickness_m, .. } => {
            let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
            let l = (dx * dx + dy * dy).sqrt().max(1e-9);
            let (sx, sy) = (-dy / l * 0.5 * thickness_m, dx / l * 0.5 * thickness_m);
            vec![[start[0] + sx, start[1] + sy], [end[0] + sx, end[1] + sy], [end[0] - sx, end[1] - sy], [start[0] - sx, start[1] - sy]]
        }
        ObstacleSpec::Footprint { points, .. } => points.clone(),
    };
    let cell = site.cell_x_m.min(site.cell_y_m).max(0.01);
    let mut low = g;
    let mut at = |x: f64, y: f64| low = low.min(site.elevation_at(x, y));
    for k in 0..corners.len() {
        let (p, q) = (corners[k], corners[(k + 1) % corners.len()]);
        let n = (((q[0] - p[0]).hypot(q[1] - p[1]) / (0.25 * cell)).ceil() as usize).clamp(1, 100_000);
        for i in 0..n {
            let t = i as f64 / n as f64;
            at(p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]));
        }
    }
    let b = o.bounds_xy();
    let step = 0.5 * cell;
    let (nx, ny) = ((((b[2] - b[0]) / step).ceil() as usize).clamp(1, 2000), (((b[3] - b[1]) / step).ceil() as usize).clamp(1, 2000));
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (b[0] + (b[2] - b[0]) * i as f64 / nx as f64, b[1] + (b[3] - b[1]) * j as f64 / ny as f64);
            if matches!(o, ObstacleSpec::Box { .. }) || o.top_at(x, y).is_some() {
                at(x, y);
            }
        }
    }
    (g, low)
}

/// Adapts the near field of `camera` and meshes it: replaces the instances of `inst` (built by
/// [`super::scene::instances`] from `plants`) of the adapted trees by instances of their own
/// prototypes, appended to `prototypes` (index `prototypes.len()` onwards). `cache` holds the
/// open-grown trees (the scenario's seed). Returns the stats.
///
/// Errors: those of [`adapt_stand`] (invalid obstacles or trees).
#[allow(clippy::too_many_arguments)]
pub fn adapt_near_field(plants: &[Plant], inst: &mut [TreeInstance], prototypes: &mut Vec<Prototype>, library: &SpeciesLibrary, site: &SiteConditions, obstacles: &[ObstacleSpec], camera: &Camera, season: Season, cache: &mut NearCaches, o: &AdaptOptions) -> crate::Result<AdaptStats> {
    let t0 = std::time::Instant::now();
    let eye = Vec3::from(camera.eye);
    let fwd = (Vec3::from(camera.target) - eye).with_z(0.0).normalize_or(Vec3::Y);
    let frustum = (o.image_width_px > 0.0 && o.image_height_px > 0.0).then(|| crate::render::lod::Frustum::from_view_proj(camera.view_proj(o.image_width_px / o.image_height_px)));
    let in_view = |t: &TreeInstance| {
        frustum.as_ref().is_none_or(|f| {
            let (c, r) = crate::render::instanced::bounding_sphere(t);
            f.sphere_visible(c, r)
        })
    };
    let stand = stand_trees(plants, library, site);
    let by_id: std::collections::HashMap<u64, usize> = stand.iter().enumerate().map(|(k, (_, t))| (t.id, k)).collect();
    // the drawn trees near the eye and not behind it, nearest first
    let mut near: Vec<(f32, usize, usize)> = inst
        .iter()
        .enumerate()
        .filter_map(|(j, t)| {
            let k = *by_id.get(&t.id)?;
            let d = (Vec3::from(t.position) - eye).with_z(0.0);
            (d.length() <= o.near_m && d.dot(fwd) > -t.crown_radius.max(2.0) && in_view(t)).then_some((d.length(), j, k))
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    near.truncate(o.max_trees);
    if near.is_empty() {
        return Ok(AdaptStats::default());
    }
    let trees: Vec<StandTree> = stand.iter().map(|(_, t)| *t).collect();
    let opts = StandOptions { cell_m: o.cell_m, halo_m: o.halo_m, latitude_deg: site.geo.latitude_deg as f32, obstacles: solids(obstacles, site), ..StandOptions::default() };
    // the full-detail trees first (nearest first), then the coarser ones (each adapted among all)
    let px = |n: &(f32, usize, usize)| {
        let t = &inst[n.1];
        camera.projected_size_px(Vec3::from(t.position) + Vec3::Z * (0.5 * t.height), t.height, o.image_height_px)
    };
    // the largest on screen (ties: nearest first) of those over full_px
    let mut by_size: Vec<(f32, usize)> = near.iter().enumerate().map(|(k, n)| (px(n), k)).filter(|(p, _)| *p >= o.full_px).collect();
    by_size.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    // full detail within a budget of leaf cards, not only of trees (trial 39): the candidates'
    // open-grown trees are grown first (adapt_stand would grow them anyway)
    let form_of = |k: usize| {
        let t = &stand[near[k].2].1;
        (t.species, crate::structure::stand::age_class(t.age_yr), crate::structure::stand::crown_base_class(t.height_m, t.crown_base_m))
    };
    let keys: Vec<_> = by_size.iter().map(|&(_, k)| form_of(k)).collect();
    cache.full.prepare(library, &keys)?;
    let costs: Vec<usize> = by_size.iter().map(|&(_, k)| full_detail_cost(&cache.full, form_of(k))).collect();
    let mut is_full = vec![false; near.len()];
    let chosen = choose_full_detail(&costs, o.max_full_trees, o.max_full_cards);
    by_size.iter().zip(&chosen).filter(|(_, &c)| c).for_each(|(&(_, k), _)| is_full[k] = true);
    let full_held_back = chosen.iter().take(o.max_full_trees).filter(|&&c| !c).count();
    // every tree the picture may draw at its full level carries its crown's leaf area there,
    // also those past `max_full_trees` (coarser skeletons; until round 36 they were drawn with
    // the few leaf cards of a 48-strand skeleton: sticks)
    let mut at_full = vec![false; near.len()];
    by_size.iter().for_each(|&(_, k)| at_full[k] = true);
    let (mut near, rest): (Vec<_>, Vec<_>) = near.into_iter().zip(is_full).zip(at_full).map(|((n, f), a)| (n, f, a)).partition(|(_, f, _)| *f);
    let split = near.len();
    near.extend(rest);
    let at_full: Vec<bool> = near.iter().map(|n| n.2).collect();
    let near: Vec<(f32, usize, usize)> = near.into_iter().map(|(n, _, _)| n).collect();
    let mut st_trees = Vec::with_capacity(near.len());
    let (mut trees_in_groups, mut n_full) = (0, 0);
    for (part, c) in [(&near[..split], &mut cache.full), (&near[split..], &mut cache.far)] {
        if !part.is_empty() {
            let targets: Vec<usize> = part.iter().map(|n| n.2).collect();
            let st = adapt_stand(&trees, &targets, library, c, &opts)?;
            trees_in_groups += st.trees_in_groups;
            st_trees.extend(st.trees);
        }
        // the full-detail trees are the first adapted
        n_full = n_full.max(st_trees.len().min(split));
    }
    let adapt_s = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    // the full-detail trees (the first `n_full` adapted) carry their crown's leaf area, as the
    // stand export's do (crown_leaf_cards)
    let cover = LeafCover::of(library);
    // each adapted tree's skeleton and leaves are moved into its meshing and freed with it, not
    // held beside every tree's meshes (issue 34)
    let meshed: Vec<Option<AdaptedModel>> = st_trees
        .into_par_iter()
        .enumerate()
        .map(|(k, a)| {
            let t = &trees[a.index];
            adapted_model(a, t, &library.species[t.species as usize], (k < n_full || at_full.get(k) == Some(&true)).then_some(&cover))
        })
        .collect();
    let (mut full_level_trees, mut bare_full_level, mut shed_bare) = (0, 0, 0);
    let (mut adapted, mut hulls, mut hull_triangles) = (0, 0, 0);
    let (mut nodes_15m, mut leaf_cards, mut sprigs, mut mesh_bytes) = (Vec::new(), 0, 0, 0);
    let (mut adapted_area, mut area) = (0.0f64, 0.0f64);
    for (k, (m, n)) in meshed.into_iter().zip(&near).enumerate() {
        let Some(m) = m else { continue };
        shed_bare += m.shed_bare as usize;
        if at_full.get(k) == Some(&true) {
            full_level_trees += 1;
            let t = &trees[n.2];
            let want = super::leaf_area::drawn_leaf_area(&library.species[t.species as usize], t.crown_radius_m);
            if m.leaf_area_m2 < 0.5 * want {
                bare_full_level += 1;
            }
        }
        if trees[n.2].height_m >= STATS_MIN_HEIGHT_M {
            nodes_15m.push(m.nodes);
        }
        leaf_cards += m.leaf_cards;
        sprigs += m.sprig_cards;
        if k < n_full {
            adapted_area += m.adapted_leaf_area_m2 as f64;
            area += m.leaf_area_m2 as f64;
        }
        mesh_bytes += m.prototype.lods.levels.iter().map(|l| l.bark.byte_size() + l.leaves.byte_size()).sum::<usize>();
        if m.hulled {
            hulls += 1;
            hull_triangles += m.prototype.lods.levels.get(CLUSTER_HULL_LEVEL).map_or(0, |l| l.triangle_count());
        }
        let t = &trees[n.2];
        m.place(&mut inst[n.1], t, &library.species[t.species as usize], season, prototypes.len() as u32);
        prototypes.push(m.prototype);
        adapted += 1;
    }
    Ok(AdaptStats { adapted_trees: adapted, adapt_s, mesh_s: t1.elapsed().as_secs_f64(), trees_in_groups, cluster_hulls: hulls, hull_triangles, per_level: [0; LOD_LEVELS], trees_15m: nodes_15m.len(), nodes_min: nodes_15m.iter().copied().min().unwrap_or(0), nodes_median: median_usize(&mut nodes_15m), leaf_cards, sprig_cards: sprigs, adapted_leaf_area_m2: adapted_area, leaf_area_m2: area, mesh_bytes, full_level_trees, bare_full_level, shed_bare, full_held_back })
}

/// The share of a leaf card and of a leaf-cluster card that their textures cover, per species
/// of a library ([`crate::structure::texture::leaf_card_cover`],
/// [`crate::structure::texture::cluster_card_cover`] of its leaf shape): what
/// [`crown_leaf_cards`] needs to give a tree its crown's leaf area.
#[derive(Debug, Clone, PartialEq)]
pub struct LeafCover {
    /// Leaf card cover (0–1) per species index.
    pub card: Vec<f32>,
    /// Leaf-cluster card cover (0–1) per species index.
    pub sprig: Vec<f32>,
}

impl LeafCover {
    /// The covers of every species of `library`, in library order.
    pub fn of(library: &SpeciesLibrary) -> LeafCover {
        let (card, sprig) = library.species.iter().map(Self::of_species).unzip();
        LeafCover { card, sprig }
    }

    /// The leaf card's and the leaf-cluster card's cover of species `sp`.
    pub fn of_species(sp: &crate::species::Species) -> (f32, f32) {
        super::leaf_area::card_covers(sp)
    }
}

/// Gives the full-detail tree `t` (of species `sp`) its crown's leaf area, as the stand export
/// and the stills draw it: the species' drawn crown leaf-area index over its crown projection
/// ([`super::leaf_area::drawn_leaf_area`]: the species file's sourced `life.foliage.crown_lai`
/// × π r², else the light model's `2 + 0.5 · shade tolerance`), its leaf cards `lv` (in the tree's own frame,
/// stem base at the origin, m) lengthened by at most 1.5 and the rest as leaf-cluster cards
/// ([`super::leaf_area::sprig_cards`], which returns them as a mesh in the same frame).
pub fn crown_leaf_cards(lv: &mut Leaves, t: &StandTree, sp: &crate::species::Species, cover: &LeafCover) -> TriMesh {
    let k = t.species as usize;
    // (round 38: setting the cards to the species' leaf length here, `appearance.leaf_length_m`,
    // made a beech stand's sprigs a quarter as wide, clumped at the skeleton's tips: Blender's
    // top-down cover of tests/blender.rs fell from 0.707 to 0.598 against the crown discs' 0.745;
    // not done until the sprigs spread over the crown)
    let leaf_area = super::leaf_area::drawn_leaf_area(sp, t.crown_radius_m);
    super::leaf_area::sprig_cards(lv, leaf_area, cover.card[k], cover.sprig[k], t.crown_radius_m, t.species as u64)
}

/// One adapted tree meshed for drawing ([`adapted_model`]).
#[derive(Debug, Clone)]
pub struct AdaptedModel {
    /// Its own prototype (normalised to 1 m: the instance scales it to [`AdaptedModel::height`]).
    pub prototype: Prototype,
    /// Height (m, highest node or leaf above the stem base).
    pub height: f32,
    /// Crown radius of the normalised model (m per m of height).
    pub r0: f32,
    /// Whether its mid level is the crown hull of its adapted leaf clusters.
    pub hulled: bool,
    /// Skeleton nodes.
    pub nodes: usize,
    /// Leaf cards of the full level.
    pub leaf_cards: usize,
    /// Leaf-cluster cards (sprigs) of the full level ([`crown_leaf_cards`]; 0 unless given the
    /// crown's leaf area).
    pub sprig_cards: usize,
    /// Leaf area (m², one-sided: each card's area times the share its texture covers) of the
    /// adapted tree's own leaf cards as Plastic Trees left them.
    pub adapted_leaf_area_m2: f32,
    /// Leaf area (m², one-sided) of the full level drawn: its leaf cards and sprigs (with the
    /// crown's leaf area: [`super::leaf_area::drawn_leaf_area`] within half a sprig);
    /// without, the adapted cards'.
    pub leaf_area_m2: f32,
    /// Whether Plastic Trees left the tree without a leaf card ([`AdaptStats::shed_bare`]).
    pub shed_bare: bool,
}

impl AdaptedModel {
    /// Makes `inst` (the instance of stand tree `t` of species `sp`) draw this model as
    /// prototype `proto` ([`place_adapted`]).
    pub fn place(&self, inst: &mut TreeInstance, t: &StandTree, sp: &crate::species::Species, season: Season, proto: u32) {
        place_adapted(inst, self.height, self.r0, t, sp, season, proto);
    }
}

/// Makes `inst` (the instance of stand tree `t` of species `sp`) draw an adapted model of
/// height `height` (m) and normalised crown radius `r0` as prototype `proto`: its height, crown
/// radius, ground elevation and foliage of `season`, unturned (the skeleton stands as it was
/// adapted).
pub fn place_adapted(inst: &mut TreeInstance, height: f32, r0: f32, t: &StandTree, sp: &crate::species::Species, season: Season, proto: u32) {
    let (col, amount) = foliage(sp, season);
    inst.species = proto;
    inst.height = height;
    inst.crown_radius = r0 * height;
    inst.rotation = 0.0;
    inst.position[2] = t.base.z;
    inst.leaf_color = col;
    inst.leaf_amount = amount;
}

/// Meshes the adapted tree `a` (of stand tree `t`, species `sp`; its skeleton and leaves are
/// moved in, not copied): its level-of-detail chain ([`adapted_lod_chain`]) normalised to 1 m.
/// With `leaf_area` (full-detail trees), its leaf cards first carry the crown's leaf area
/// ([`crown_leaf_cards`]) and the leaf-cluster cards join the full level's leaves, marked by
/// [`crate::mesh::CLUSTER_CARD_U`] (drawn with the leaf-cluster texture). `None` for a tree
/// under 0.1 m or without levels.
pub fn adapted_model(mut a: AdaptedTree, t: &StandTree, sp: &crate::species::Species, leaf_area: Option<&LeafCover>) -> Option<AdaptedModel> {
    let (mut sk, mut lv, h) = frame_of(std::mem::take(&mut a.skeleton), std::mem::take(&mut a.leaves).into_leaves(), t.base)?;
    let k = t.species as usize;
    let shed_bare = lv.leaves.is_empty();
    if shed_bare && leaf_area.is_some() {
        lv = tip_leaves(&sk, sp.architecture.ecomod.leaf_size_m, t.crown_base_m);
    }
    let (card, sprig) = leaf_area.map_or_else(|| { let c = LeafCover::of_species(sp); (c.0, c.1) }, |c| (c.card[k], c.sprig[k]));
    let cards_area = |lv: &Leaves| lv.leaves.iter().map(|l| 0.5 * l.size * l.size * card.clamp(0.05, 1.0)).sum::<f32>();
    let adapted_leaf_area_m2 = cards_area(&lv);
    let mut sprigs = leaf_area.map(|c| crown_leaf_cards(&mut lv, t, sp, c)).unwrap_or_default();
    let (n_nodes, n_leaves, n_sprigs) = (sk.nodes.len(), lv.leaves.len(), sprigs.positions.len() / 4);
    // a sprig's side² × its cover (quad: half-diagonals u, v of the card)
    let sprig_area: f32 = sprigs.positions.chunks(4).map(|q| (Vec3::from(q[1]) - Vec3::from(q[0])).length() * (Vec3::from(q[3]) - Vec3::from(q[0])).length() * sprig.clamp(0.05, 1.0)).sum();
    let leaf_area_m2 = cards_area(&lv) + sprig_area;
    let s = 1.0 / h;
    sk.nodes.iter_mut().for_each(|n| {
        n.pos *= s;
        n.radius *= s;
    });
    lv.leaves.iter_mut().for_each(|l| {
        l.pos *= s;
        l.size *= s;
    });
    // the bole tapered (Kozak 1988, `structure::taper`) to the stand-grown DBH of the tree's
    // height (the pictures' trees carry no DBH: `forest_form::stand_dbh_cm`), in the 1 m frame
    let stem = crate::structure::taper::StemTaper::new(crate::structure::taper::TaperForm::of_species(sp), crate::structure::forest_form::stand_dbh_cm(sp, t.height_m), t.height_m).map(|st| st.in_frame(s));
    let (mut lods, hulled) = adapted_lod_chain(&sk, &lv, &a, t.base, s, &crate::structure::mesh::LodOptions { stem, ..crate::structure::mesh::LodOptions::for_species(sp) });
    let full = lods.levels.first_mut()?;
    if n_sprigs > 0 && full.leaves.uvs.len() == full.leaves.positions.len() {
        sprigs.positions.iter_mut().for_each(|p| *p = (Vec3::from(*p) * s).to_array());
        sprigs.uvs.iter_mut().for_each(|uv| uv[0] += crate::mesh::CLUSTER_CARD_U);
        full.leaves.append(&sprigs);
    }
    let prototype = Prototype { name: format!("{}#{}", sp.id, t.id), lods, bark_color: srgb_to_linear(sp.appearance.bark), leaf_color: srgb_to_linear(sp.appearance.leaf_summer), stiffness: sp.architecture.ecomod.k_f.clamp(0.0, 1.0), look: Some(super::scene::crown_look(sp)), rigid: false };
    let r0 = prototype.normalised_crown_radius();
    Some(AdaptedModel { prototype, height: h, r0, hulled, nodes: n_nodes, leaf_cards: n_leaves, sprig_cards: n_sprigs, adapted_leaf_area_m2, leaf_area_m2, shed_bare })
}

/// Leaves for a skeleton `sk` (in its own frame, stem base at the origin, m) that Plastic
/// Trees left bare: one leaf of length `leaf_size_m` (the species' EcoMod leaf size, at least
/// 2 cm) at every shoot tip (a node without children) at least `crown_base_m` above the base,
/// pointing along its shoot, blade horizontal across it. What [`crown_leaf_cards`] then needs
/// to give the tree its crown's leaf area (it places none on a tree without leaves). Empty
/// when no tip is in the crown.
pub fn tip_leaves(sk: &Skeleton, leaf_size_m: f32, crown_base_m: f32) -> Leaves {
    let size = leaf_size_m.max(0.02);
    let leaves = sk
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| n.children.is_empty() && n.pos.z >= crown_base_m && n.parent.is_some())
        .map(|(i, n)| {
            let from = n.parent.map_or(Vec3::ZERO, |p| sk.nodes[p as usize].pos);
            let dir = (n.pos - from).normalize_or(Vec3::Z);
            let across = dir.cross(Vec3::Z).normalize_or(Vec3::X);
            let normal = across.cross(dir).normalize_or(Vec3::Z);
            crate::structure::skeleton::Leaf { pos: n.pos, dir, normal, size, node: i as u32 }
        })
        .collect();
    Leaves { leaves }
}

/// The level-of-detail chain of the adapted tree `a` from its skeleton `sk` and leaves `lv` in
/// its own frame (world coordinates less the stem base `base`, times `scale`; see
/// [`tree_frame`]): [`crate::structure::mesh::lod_chain`] with the mid level
/// ([`CLUSTER_HULL_LEVEL`]) replaced by the crown hull of its adapted leaf clusters
/// ([`crate::structure::crown_hull::cluster_hull_mesh`], one-sided where they are), and whether
/// it was (a tree without a foliage cluster keeps the leaf-card hull).
pub fn adapted_lod_chain(sk: &Skeleton, lv: &Leaves, a: &AdaptedTree, base: Vec3, scale: f32, o: &crate::structure::mesh::LodOptions) -> (LodChain, bool) {
    let mut lods = crate::structure::mesh::lod_chain(sk, lv, o);
    let clusters: Vec<(Vec3, f32)> = crate::structure::crown_hull::foliage_clusters(&a.leaf_clusters).into_iter().map(|(c, r)| ((c - base) * scale, r * scale)).collect();
    match (crate::structure::crown_hull::cluster_hull_mesh(sk, &clusters, o), lods.levels.get_mut(CLUSTER_HULL_LEVEL)) {
        (Some(m), Some(level)) => {
            *level = m;
            (lods, true)
        }
        _ => (lods, false),
    }
}

/// The adapted tree `a` in its own frame (stem base `base` moved to the origin) with its height
/// (m, highest node or leaf); `None` for a tree under 0.1 m.
pub fn tree_frame(a: &AdaptedTree, base: Vec3) -> Option<(Skeleton, Leaves, f32)> {
    frame_of(a.skeleton.clone(), a.leaves.build(), base)
}

/// [`tree_frame`] of a skeleton `sk` and leaves `lv` taken by value (moved, not copied).
fn frame_of(mut sk: Skeleton, mut lv: Leaves, base: Vec3) -> Option<(Skeleton, Leaves, f32)> {
    sk.nodes.iter_mut().for_each(|n| n.pos -= base);
    lv.leaves.iter_mut().for_each(|l| l.pos -= base);
    let h = sk.nodes.iter().map(|n| n.pos.z).fold(0.0f32, f32::max).max(lv.leaves.iter().map(|l| l.pos.z).fold(0.0, f32::max));
    (h > 0.1).then_some((sk, lv, h))
}

/// New open-grown tree caches for scenario seed `seed` ([`NearCaches`]).
pub fn cache(seed: u64) -> NearCaches {
    NearCaches { full: SkeletonCache::new(seed, FULL_STRANDS), far: SkeletonCache::new(seed, FAR_MAX_STRANDS) }
}

/// Grey of the obstacles (sRGB 150, 146, 140: weathered stone and concrete).
pub const OBSTACLE_RGB: [u8; 3] = [150, 146, 140];

/// Triangle mesh of one obstacle in world coordinates (heights above the ground at its
/// anchor's elevation on `site`), outward normals, counter-clockwise from outside: boxes and
/// walls as 12 triangles, a sphere as 16 × 10 quads, a footprint as its side walls and a roof
/// (ear clipping). On a slope a building stands on the terrain: walls and footprints reach
/// 1 m below the lowest ground under them ([`ground_under`]; below the anchor's ground this is
/// the foundation on the downhill side), and a box whose bottom is at or below the ground
/// reaches as far below the lowest ground as it does below its anchor's (trial 37: the
/// downhill wall of a footprint set at its anchor's ground hung 5 m in the air).
pub fn obstacle_mesh(o: &ObstacleSpec, site: &SiteConditions) -> TriMesh {
    let (g, low) = ground_under(o, site);
    let low = low.min(g);
    let mut m = TriMesh::default();
    let mut quad = |m: &mut TriMesh, p: [Vec3; 4]| {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Z);
        let b = m.positions.len() as u32;
        for (k, q) in p.iter().enumerate() {
            m.positions.push(q.to_array());
            m.normals.push(n.to_array());
            m.uvs.push([(k == 1 || k == 2) as u8 as f32, (k >= 2) as u8 as f32]);
        }
        m.indices.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    };
    // a prism over the counter-clockwise polygon `poly` from z0 to z1 (absolute)
    let prism = |m: &mut TriMesh, poly: &[Vec3], z0: f32, z1: f32, quad: &mut dyn FnMut(&mut TriMesh, [Vec3; 4])| {
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            quad(m, [p.with_z(z0), q.with_z(z0), q.with_z(z1), p.with_z(z1)]);
        }
        let b = m.positions.len() as u32;
        for p in poly {
            m.positions.push(p.with_z(z1).to_array());
            m.normals.push([0.0, 0.0, 1.0]);
            m.uvs.push([0.0, 0.0]);
        }
        for t in ear_clip(poly) {
            m.indices.extend_from_slice(&[b + t[0], b + t[1], b + t[2]]);
        }
    };
    let v2 = |x: f64, y: f64| Vec3::new(x as f32, y as f32, 0.0);
    match o {
        ObstacleSpec::Box { min, max } => {
            let poly = [v2(min[0], min[1]), v2(max[0], min[1]), v2(max[0], max[1]), v2(min[0], max[1])];
            // a box standing on the ground reaches below its lowest ground as below its anchor's
            let z = if min[2] <= 0.0 { low + min[2] as f32 } else { g + min[2] as f32 };
            prism(&mut m, &poly, z, g + max[2] as f32, &mut quad);
            quad(&mut m, [poly[0].with_z(z), poly[3].with_z(z), poly[2].with_z(z), poly[1].with_z(z)]);
        }
        ObstacleSpec::Wall { start, end, height_m, thickness_m } => {
            let (s, e) = (v2(start[0], start[1]), v2(end[0], end[1]));
            let side = (e - s).normalize_or(Vec3::X).cross(Vec3::Z) * (0.5 * *thickness_m as f32);
            let poly = [s + side, e + side, e - side, s - side];
            // counter-clockwise seen from above
            let poly: Vec<Vec3> = if signed_area(&poly) < 0.0 { poly.iter().rev().copied().collect() } else { poly.to_vec() };
            prism(&mut m, &poly, low - 1.0, g + *height_m as f32, &mut quad);
        }
        ObstacleSpec::Footprint { points, height_m } => {
            let mut poly: Vec<Vec3> = points.iter().map(|p| v2(p[0], p[1])).collect();
            if signed_area(&poly) < 0.0 {
                poly.reverse();
            }
            prism(&mut m, &poly, low - 1.0, g + *height_m as f32, &mut quad);
        }
        ObstacleSpec::Sphere { center, radius_m } => {
            let c = Vec3::new(center[0] as f32, center[1] as f32, g + center[2] as f32);
            let r = *radius_m as f32;
            let (nu, nv) = (16u32, 10u32);
            for j in 0..=nv {
                for i in 0..=nu {
                    let (th, ph) = (i as f32 / nu as f32 * std::f32::consts::TAU, j as f32 / nv as f32 * std::f32::consts::PI);
                    let n = Vec3::new(ph.sin() * th.cos(), ph.sin() * th.sin(), -ph.cos());
                    m.positions.push((c + n * r).to_array());
                    m.normals.push(n.to_array());
                    m.uvs.push([i as f32 / nu as f32, j as f32 / nv as f32]);
                }
            }
            for j in 0..nv {
                for i in 0..nu {
                    let (a0, a1) = (j * (nu + 1) + i, (j + 1) * (nu + 1) + i);
                    m.indices.extend_from_slice(&[a0, a0 + 1, a1 + 1, a0, a1 + 1, a1]);
                }
            }
        }
    }
    m
}

/// Twice the signed area of a polygon in the xy plane (> 0 counter-clockwise).
fn signed_area(poly: &[Vec3]) -> f32 {
    (0..poly.len()).map(|k| {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        p.x * q.y - q.x * p.y
    }).sum()
}

/// Triangles of a simple counter-clockwise polygon by ear clipping (indices into `poly`).
fn ear_clip(poly: &[Vec3]) -> Vec<[u32; 3]> {
    let mut idx: Vec<u32> = (0..poly.len() as u32).collect();
    let mut out = Vec::new();
    let cross = |a: Vec3, b: Vec3, c: Vec3| (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    let mut guard = 0;
    while idx.len() > 3 && guard < 10 * poly.len() {
        guard += 1;
        let n = idx.len();
        let mut clipped = false;
        for k in 0..n {
            let (i0, i1, i2) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
            let (a, b, c) = (poly[i0 as usize], poly[i1 as usize], poly[i2 as usize]);
            if cross(a, b, c) <= 0.0 {
                continue;
            }
            let inside = idx.iter().any(|&j| j != i0 && j != i1 && j != i2 && {
                let p = poly[j as usize];
                cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
            });
            if !inside {
                out.push([i0, i1, i2]);
                idx.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break;
        }
    }
    if idx.len() == 3 {
        out.push([idx[0], idx[1], idx[2]]);
    }
    out
}

/// Prototypes and instances drawing `obstacles` on `site`: one prototype per obstacle (its mesh
/// as bark at every level, normalised so the instance's height scales it uniformly), one
/// instance each (ids from `u64::MAX` down), prototype indices from `first`.
pub fn obstacle_models(obstacles: &[ObstacleSpec], site: &SiteConditions, first: u32) -> (Vec<Prototype>, Vec<TreeInstance>) {
    let mut protos = Vec::new();
    let mut inst = Vec::new();
    for (k, o) in obstacles.iter().enumerate() {
        let a = o.anchor();
        let mut mesh = obstacle_mesh(o, site);
        // the instance's base: the mesh's lowest point (on a slope the foundation reaches below
        // the anchor's ground)
        let bottom = mesh.positions.iter().map(|p| p[2]).fold(site.elevation_at(a[0], a[1]) - 1.0, f32::min);
        let base = Vec3::new(a[0] as f32, a[1] as f32, bottom);
        let top = mesh.positions.iter().map(|p| p[2] - base.z).fold(0.0f32, f32::max).max(0.1);
        for p in &mut mesh.positions {
            *p = ((Vec3::from(*p) - base) / top).to_array();
        }
        let level = TreeMesh { bark: mesh, leaves: TriMesh::default() };
        let p = Prototype { name: format!("obstacle {k} ({})", o.kind()), lods: LodChain::new(vec![level; LOD_LEVELS - 1]), bark_color: srgb_to_linear(OBSTACLE_RGB), leaf_color: [0.0; 3], stiffness: 1.0, look: None, rigid: true };
        let r0 = p.normalised_crown_radius();
        protos.push(p);
        let mut t = TreeInstance::new(u64::MAX - k as u64, base.to_array(), top, r0 * top, first + k as u32, [0.0; 3]);
        t.rotation = 0.0;
        t.leaf_amount = 0.0;
        inst.push(t);
    }
    (protos, inst)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ear_clipping_an_l_covers_its_area() {
        let l: Vec<Vec3> = [[0.0, 0.0], [10.0, 0.0], [10.0, 4.0], [4.0, 4.0], [4.0, 10.0], [0.0, 10.0]].iter().map(|p| Vec3::new(p[0], p[1], 0.0)).collect();
        let tris = ear_clip(&l);
        assert_eq!(tris.len(), 4);
        let area: f32 = tris.iter().map(|t| 0.5 * signed_area(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]])).sum();
        assert!((area - 64.0).abs() < 1e-4, "{area}");
    }
}
