//! Per-tree skeletons of a stand (issue 14): every tree a picture draws up close gets its own
//! skeleton, the species' open-grown tree of its age class scaled to the tree's height and crown
//! from the simulation, with the branches below the simulated crown base shed, then adapted by
//! Plastic Trees (Pirk et al. 2012, `000_*.txt`, sections 5–6) together with its neighbours, to
//! the global light of the site's latitude, the terrain slope and the obstacles.
//!
//! Steps of [`adapt_stand`]:
//! 1. **Forest-grown skeleton per species, age class and crown-base class** ([`SkeletonCache`]):
//!    the EcoMod tree (`004_*.txt`, Algorithm 1) of the species with S·min(1, a/80)² strands
//!    ([`crate::structure::species_tree::ecomod_strands_at`], a the middle of the tree's
//!    5-year age class, S the species' strand count: what `sylva tree grow` gives at that age;
//!    at most [`SkeletonCache::new`]'s `max_strands`), and with no cap ([`FULL_STRANDS`])
//!    grown as a forest tree: its bole (EcoMod's first segment) is lengthened so that the first branch leaves the
//!    stem just above the simulated crown base and every strand stands in the crown (issue 32;
//!    until round 16 the open-grown tree was shed below the crown base, which removed four
//!    fifths of its nodes). Grown with a seed drawn from the scenario's
//!    seed, the species and the class ([`crate::rng::hash`]; EcoMod uses it for the wind sway,
//!    and the tree is turned about its stem by an angle drawn from it), normalised to 1 m
//!    height. A small cache: one entry per class met. With fewer strands than the full tree
//!    the leaves are made √(S_full/S_used) times longer (at most [`MAX_LEAF_GROWTH`]) so that
//!    the foliage area stays near that of the full tree. The context trees of step 3 (which
//!    only shade and block) have at most [`CONTEXT_MAX_STRANDS`].
//! 2. **Fitted to the tree**: positions scaled about the base by H vertically and by
//!    R / r₁ horizontally (H height, R crown radius from the simulation, r₁ the normalised
//!    tree's crown radius), radii and leaves by H; every branch leaving the main stem (Gravelius
//!    order 0) below the crown base is removed with its subtree (lower branches shed in the
//!    stand, as the simulation's crown base says). Trees are analysed (Plastic Trees section 4)
//!    alone on flat ground under the site's sky, one analysis per class and shared by the
//!    class's trees through uniform scaling about the base ([`PlasticTree::scale`], section 4's
//!    quantities scale with the tree): a class is the species, age class, crown-base class, the
//!    crown's shape R/H within [`StandOptions::shape_step`] (default [`SHAPE_STEP`], 10.25 %) and, for
//!    the adapted trees, the height within [`StandOptions::height_step`] (default
//!    [`HEIGHT_STEP`], 25 %). An adapted tree is its class's analysed tree scaled to its exact
//!    height (a factor within ±12 %: its clusters keep the transmittance of the class's
//!    clusters, γ_c0 of eq. 4 becoming γ_c0^(1/factor)), and after the adaptation its crown is
//!    stretched to its exact radius (at most ±5 % at the default shape step). A context tree (step 3) is analysed
//!    without light ([`PlasticTree::standing`]: it only shades and blocks), scaled to its exact
//!    height and given back its species' γ_c0, so it casts the shade of the tree at its size.
//!    Until round 23 a class was the height and the crown radius within 5 % each and every
//!    tree of the full-detail near field had nearly its own analysis (1,503 analyses for 1,000
//!    targets and 3,274 context trees in the stand bench, 40 % of its time).
//! 3. **Neighbourhoods**: the trees to adapt are binned into square cells of
//!    [`StandOptions::cell_m`]; each cell's trees are adapted together
//!    ([`super::plastic::adapt_group_among_once`]: they are adapted once, so each node's
//!    signature is queried only until it is known to change) among every other tree whose base lies within
//!    [`StandOptions::halo_m`] of the cell: those context trees are not adapted but stand as
//!    they are for the whole life span, as obstacles do in the paper's tree–obstacle interaction
//!    (section 6): their full-grown leaf clusters shade (eq. 4) and their wood blocks. (Until
//!    round 10 they were adapted with the cell's trees and their results dropped: 4.3 times as
//!    many trees adapted as drawn in the default close-up.) Each cell is adapted in its
//!    [`Environment`]: the sky of the
//!    latitude ([`Sky::from_latitude`], section 6 global light), a ground plane with the slope
//!    and aspect of the cell's first tree (in index order) lowered 5 cm below the lowest tree base of the group,
//!    and the obstacles. Cells run in parallel (rayon), each as soon as the classes of its
//!    trees are analysed (one graph of tasks for steps 2–3, the largest cells first; round 34:
//!    until then every analysis came first and a core waited for the other's last one); each
//!    cell's result depends only on its own trees, so the stand is the same for a seed
//!    whatever the thread count or the order.
//! 4. **Light pruning of forest-grown trees.** A tree grown as a forest tree (a cache of
//!    [`FULL_STRANDS`]) bends toward the light (eq. 6) and loses the branches that collide with
//!    its neighbours' wood and the obstacles, but is not shed by light (eq. 11: its c_ψ is 0):
//!    its bole already ends at the simulated crown base, which is the stand's light-driven
//!    shedding (the simulation's crown ratio), and its leaf area is the simulated crown's. Shed
//!    again by the neighbours' shade, against a reference analysed alone, the crown was
//!    counted twice: in the default run's year 150 (0.0625 ha, 138 trees, round 21) eq. 11
//!    took 37 % of the nodes, half of every silver birch (a 25 m birch kept 210 of 2,000, an
//!    18 m one 25) and 47 % of the sessile oaks, which stood as poles with tufts in the
//!    close-up (round 17). The open-grown trees of a capped cache are still shed by light
//!    among their neighbours (their crown base is what eq. 11 raises there).
//! 5. **A forest-grown tree's bole stands.** The lengthened bole of step 1 is one segment of
//!    43–108 internodes: eq. (7) gives it w_s ≈ 0, so eq. (6) sets its direction by the
//!    tropism alone, and with the flexibility κ of its tip's season (0.37–0.71 of the tree's T
//!    seasons, eq. 2) it turned like crown wood towards the light of the gaps: in round 35 the
//!    boles of the Blender stand (92 trees ≥ 24 m) leaned 2.0° median, up to 11.8°, where the
//!    fitted trees stand within 0.2°. It is bent with the flexibility of its base's age, a = T
//!    − t_{s_p} ([`PlasticTree::set_bole`]; section 5.1: segments are transformed "according to
//!    their estimated age", and this segment's base is the oldest wood of the tree); the
//!    crown above it bends as before. Trees of a capped cache (the open-grown tree shed below
//!    the crown base) and trees grown alone are not changed. BENCHMARKS.md, "Round 36 (issue
//!    32 stems)".
//! 6. **Shared light queries.** [`StandOptions::bend_light_cell_m`] lets the nodes an adapted
//!    tree bends at one level share the bending light of the first node of their cube (default
//!    [`BEND_LIGHT_CELL_M`], 0.25 m, since round 41; over the whole level since round 42,
//!    [`StandOptions::bend_light_whole_level`], where until then only the nodes of one depth
//!    batch shared), and [`StandOptions::leaf_light_cell_m`]
//!    lets a forest-grown tree's leaf clusters share the last level's light the same way (off by
//!    default: its error is three times the chaos floor) ([`PlasticTree::bend_light_cell_m`],
//!    [`PlasticTree::leaf_light_cell_m`]); [`StandOptions::shape_step`] coarsens the crown-shape
//!    classes (default [`SHAPE_STEP`], 10.25 %, since round 41). None is exact; what each saves
//!    and changes on the near field of `benches/stand.rs` is in BENCHMARKS.md, "Round 40 (r40n:
//!    ...)", "Round 41 (r41n: ...)" and "Round 42 (r42n: ...)"; 0, 0 and [`DIM_STEP`] give
//!    round 40's stands bit for bit (for targets in index order: a cell's trees are adapted
//!    in index order since round 42).
//! 7. **The near field's sky has 20 directions** ([`NEAR_FIELD_RINGS`], rings 4, 8, 8 of the
//!    importance-sampled sky of eq. 3, where a single tree's analysis keeps
//!    [`DEFAULT_RINGS`], 4, 8, 12: 24). The cost of the near field is about linear in the
//!    directions; the adapted near field of `benches/stand.rs` with 20 directions is as far
//!    from one adapted under a 32-direction sky as the 24-direction one (mean |Δ light| of the
//!    leaf clusters 0.0268 against 0.0292; crown radius per tree 2.66 % against 2.69 %), because
//!    the adaptation's own chaos sets that distance (BENCHMARKS.md, rounds 32 and 42), for
//!    about 14 % less time (round 47). Eq. (3)'s quadrature on one tree is coarser with 20
//!    directions (mean |Δi| 0.0203 against 0.0186 at a 5,872-direction reference, round 32).

use super::grow::ecomod;
use super::species_tree::{ecomod_strands_at, ECOMOD_FULL_AGE_YR};
use crate::obstacle::Obstacle;
use super::plastic::light::DEFAULT_RINGS;
use super::plastic::{adapt_group_among_once, Environment, Fate, Ground, LeafCluster, PlasticReport, PlasticTree, Sky};
use super::skeleton::{Leaves, Skeleton};
use crate::error::{Error, Result};
use crate::species::SpeciesLibrary;
use glam::Vec3;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// One tree of the stand as the simulation describes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandTree {
    /// Stable tree id.
    pub id: u64,
    /// Species (index into the [`SpeciesLibrary`]).
    pub species: u16,
    /// Stem base (m, world coordinates: x east, y north, z the ground elevation).
    pub base: Vec3,
    /// Age (years, ≥ 0).
    pub age_yr: f32,
    /// Height (m, > 0).
    pub height_m: f32,
    /// Crown radius (m, > 0).
    pub crown_radius_m: f32,
    /// Crown base height above the stem base (m, 0 ≤ crown base < height).
    pub crown_base_m: f32,
    /// Terrain slope at the base (degrees, 0–89).
    pub slope_deg: f32,
    /// Terrain aspect at the base (degrees clockwise from north, the downhill direction).
    pub aspect_deg: f32,
}

/// Width of the age classes (years) of the open-grown skeletons: a tree of age a is grown at
/// the middle of its class, so its strand count is within a few per cent of what `sylva tree
/// grow` gives the species at age a.
pub const AGE_CLASS_YR: f32 = 5.0;
/// The last age class: every tree of [`ECOMOD_FULL_AGE_YR`] (80 years) or older has the full
/// strand count and shares it.
pub const LAST_AGE_CLASS: u16 = (ECOMOD_FULL_AGE_YR / AGE_CLASS_YR) as u16;

/// Age class (0–[`LAST_AGE_CLASS`]) of a tree of `age_yr` years: ⌊a / [`AGE_CLASS_YR`]⌋.
pub fn age_class(age_yr: f32) -> u16 {
    ((age_yr.max(0.0) / AGE_CLASS_YR).floor() as u16).min(LAST_AGE_CLASS)
}

/// The age (years) each class grows its open-grown tree at: the middle of the class, and
/// [`ECOMOD_FULL_AGE_YR`] for the last.
pub fn class_age(class: u16) -> f32 {
    if class >= LAST_AGE_CLASS {
        ECOMOD_FULL_AGE_YR
    } else {
        (class as f32 + 0.5) * AGE_CLASS_YR
    }
}

/// Crown-base classes per tree height: a tree's crown-base ratio cb/h (0–0.9) is taken in
/// steps of 1/20.
pub const CROWN_BASE_CLASSES: f32 = 20.0;

/// Crown-base class (0–18) of a tree of height `height_m` with its crown base at `crown_base_m`
/// (m): cb/h in steps of 1/[`CROWN_BASE_CLASSES`], rounded, at most 0.9.
pub fn crown_base_class(height_m: f32, crown_base_m: f32) -> u16 {
    ((crown_base_m / height_m.max(0.1)).clamp(0.0, 0.9) * CROWN_BASE_CLASSES).round() as u16
}

/// Key of an open-grown skeleton in the [`SkeletonCache`]: species (index into the library),
/// age class ([`age_class`]) and crown-base class ([`crown_base_class`]).
pub type FormKey = (u16, u16, u16);

/// Relative step (5 %) of the crown-shape classes (crown radius over height, R/H) that share
/// one analysis ([`adapt_stand`] step 2) until round 40; the default since round 41 is
/// [`SHAPE_STEP`].
pub const DIM_STEP: f32 = 1.05;

/// Default relative step of the crown-shape classes ([`StandOptions::shape_step`]): 1.05²
/// (10.25 %), so an adapted crown is stretched to its exact radius by at most ±5 %. Round 40
/// measured it on the 1,000 targets of `benches/stand.rs`: 591 analyses instead of 836, −6.5 %
/// CPU, crowns that differ as other classes' crowns do; round 41 made it the default
/// (BENCHMARKS.md, "Round 40 (r40n: ...)" and "Round 41 (r41n: ...)").
pub const SHAPE_STEP: f32 = DIM_STEP * DIM_STEP;

/// Default rings of the near field's importance-sampled sky ([`StandOptions::sky_rings`]):
/// 4, 8 and 8 directions about the brightest sky point, 20 in all (17 above the horizon at
/// 47° N), since round 47; [`DEFAULT_RINGS`] (24) before. Module docs, step 7.
pub const NEAR_FIELD_RINGS: [usize; 3] = [4, 8, 8];

/// Default side (m) of the cubes within which an adapted tree's nodes bent at one level share
/// one bending-light query ([`StandOptions::bend_light_cell_m`]): 0.25 m. Round 40 measured it
/// on the 1,000 targets of `benches/stand.rs`: −6.4 % CPU, the leaf clusters' light moved by
/// 1.7·10⁻³ on average (p99 0.038), as much as f32-rounding-level changes move it in this
/// chaotic adaptation (round 38); round 41 made it the default (BENCHMARKS.md).
pub const BEND_LIGHT_CELL_M: f32 = 0.25;

/// Relative step (25 %) of the height classes of the adapted trees that share one analysis
/// ([`adapt_stand`] step 2): a tree is its class's tree scaled by a factor within
/// 1.25^(±1/2) (±12 %), which raises the translucency base γ_c0 of eq. (4) to the power
/// 1/factor ([`PlasticTree::scale`]).
pub const HEIGHT_STEP: f32 = 1.25;

/// Height (m) a context tree's class is analysed at before it is scaled to each tree's height
/// (any height would do: its shape-only analysis scales exactly).
const CONTEXT_CLASS_HEIGHT_M: f32 = 20.0;

/// Options of [`adapt_stand`].
#[derive(Debug, Clone, PartialEq)]
pub struct StandOptions {
    /// Side of the square neighbourhood cells (m, > 0).
    pub cell_m: f32,
    /// Distance around a cell within which other trees take part as neighbours (m, ≥ 0).
    pub halo_m: f32,
    /// Site latitude (degrees, −90–90) for the global light.
    pub latitude_deg: f32,
    /// Solid obstacles (world coordinates, m).
    pub obstacles: Vec<Obstacle>,
    /// Rings of the importance-sampled sky of eq. (3) (Plastic Trees, `000_*.txt`) that the
    /// analyses and the adaptation use: directions per ring around the brightest sky point,
    /// innermost first, each a positive multiple of 4, 1–32 in all ([`Sky::with_rings`]).
    /// Default [`NEAR_FIELD_RINGS`] (`[4, 8, 8]`, 20 directions, since round 47; module docs,
    /// step 7); [`DEFAULT_RINGS`] (`[4, 8, 12]`, 24) gives [`Sky::from_latitude`]'s sky bit for
    /// bit, the near field of rounds 11–46. The cost of the near field is about linear in the
    /// directions (issue 32); fewer are coarser: BENCHMARKS.md, rounds 11 and 32, gives the
    /// error of each ring set against a reference of 5,872 directions (`examples/sky_quadrature`),
    /// round 42 the adapted near field's distance from a 32-direction one.
    pub sky_rings: Vec<usize>,
    /// Relative step of the height classes of the adapted trees that share one analysis
    /// (> 1, at most 4): a tree is its class's analysed tree scaled by a factor within
    /// `height_step`^(±1/2), its translucency base γ_c0 raised to the power 1/factor
    /// ([`PlasticTree::scale`]; eq. (4) takes the cluster radius in metres, so a coarser step
    /// is not exact). Default [`HEIGHT_STEP`] (1.25, ±12 %); a coarser step shares analyses
    /// across the default's height classes (fewer analyses; BENCHMARKS.md, round 36, measures
    /// what 1.25² changes).
    pub height_step: f32,
    /// Relative step of the crown-shape classes (crown radius over height, R/H) that share one
    /// analysis (> 1, at most 2): a tree's crown is its class's, stretched after the adaptation
    /// to its exact radius by a factor within `shape_step`^(±1/2). Default [`SHAPE_STEP`]
    /// (1.1025, ±5 %; [`DIM_STEP`], 1.05, until round 40); a coarser step shares analyses across
    /// crown shapes (BENCHMARKS.md, rounds 40 and 41).
    pub shape_step: f32,
    /// Side (m, ≥ 0) of the cubes within which an adapted tree's nodes bent at one level share
    /// one bending-light query ([`PlasticTree::bend_light_cell_m`]; 0: every node its own, exact,
    /// as until round 40). Default [`BEND_LIGHT_CELL_M`] (0.25 m).
    pub bend_light_cell_m: f32,
    /// Side (m, ≥ 0) of the cubes within which a forest-grown adapted tree's leaf clusters share
    /// one light query at the last level ([`PlasticTree::leaf_light_cell_m`]: only the clusters'
    /// light and leaf density of eq. 12 change; 0: exact). Default 0.
    pub leaf_light_cell_m: f32,
    /// With `bend_light_cell_m` > 0: an adapted tree's nodes share their cube's bending light
    /// over the whole level, not only within one depth batch
    /// ([`PlasticTree::bend_light_whole_level`]; false: round 41's sharing). Default true.
    pub bend_light_whole_level: bool,
}

impl Default for StandOptions {
    /// Cells of 12 m, a halo of 6 m, latitude 47° N, no obstacles, the near field's sky
    /// ([`NEAR_FIELD_RINGS`]), height classes of [`HEIGHT_STEP`], crown-shape classes of
    /// [`SHAPE_STEP`], bending light shared in cubes of [`BEND_LIGHT_CELL_M`], every leaf
    /// cluster its own light query.
    fn default() -> Self {
        StandOptions { cell_m: 12.0, halo_m: 6.0, latitude_deg: 47.0, obstacles: Vec::new(), sky_rings: NEAR_FIELD_RINGS.to_vec(), height_step: HEIGHT_STEP, shape_step: SHAPE_STEP, bend_light_cell_m: BEND_LIGHT_CELL_M, leaf_light_cell_m: 0.0, bend_light_whole_level: true }
    }
}

/// The sky of [`adapt_stand`]: [`Sky::from_latitude`] (its brightest point the noon sun at the
/// equinox) with the rings `rings`; exactly [`Sky::from_latitude`]'s sky for [`DEFAULT_RINGS`].
///
/// Errors: [`Error::Invalid`] naming `sky_rings` unless every ring is a positive multiple of 4
/// and there are 1–32 directions in all.
pub fn stand_sky(latitude_deg: f32, rings: &[usize]) -> Result<Sky> {
    let sky = Sky::from_latitude(latitude_deg);
    if rings == DEFAULT_RINGS {
        return Ok(sky);
    }
    Sky::with_rings(sky.brightest, rings).map_err(|_| Error::Invalid {
        context: "stand adaptation".into(),
        field: "sky_rings".into(),
        value: format!("{rings:?}"),
        expected: "rings of positive multiples of 4 directions, 1–32 directions in all (e.g. [4, 8, 12])".into(),
    })
}

/// The open-grown tree of one species and age class: EcoMod skeleton and leaves, 1 m tall, base
/// at the origin, z up.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenGrown {
    /// Skeleton (m per m of height).
    pub skeleton: Skeleton,
    /// Leaves.
    pub leaves: Leaves,
    /// Crown radius of the normalised tree as foresters measure it ([`mean_crown_radius`]: the
    /// mean of the radii to the crown's edge in eight directions; m per m of height; at least
    /// 0.05), the radius [`fit`] gives the simulated crown radius.
    pub crown_radius: f32,
    /// True when the skeleton's first segment (node 1, from the root) is the forest form's
    /// lengthened bole ([`SkeletonCache::prepare`] in a cache of [`FULL_STRANDS`]): one
    /// segment from the root to the crown base that stands for many internodes, which
    /// [`adapt_stand`] bends with the flexibility of its base ([`PlasticTree::set_bole`]).
    pub forest_bole: bool,
}

/// Open-grown trees per (species, age class), grown with the scenario's seed.
#[derive(Debug, Clone)]
pub struct SkeletonCache {
    seed: u64,
    max_strands: u32,
    map: BTreeMap<FormKey, Arc<OpenGrown>>,
    /// The context trees' skeletons (at most [`CONTEXT_MAX_STRANDS`] strands).
    context: BTreeMap<FormKey, Arc<OpenGrown>>,
}

/// Most strands of a context tree's skeleton (a neighbour that shades and blocks the adapted
/// trees but is not itself adapted or drawn from this adaptation, [`adapt_stand`] step 3): its
/// leaf clusters and wood are all the adaptation reads of it, and 250 strands (500 nodes, the
/// leaves lengthened as in [`SkeletonCache::prepare`]) give them; the full strand count made
/// the context trees' analyses half the cost of a stand export (BENCHMARKS.md, round 17).
pub const CONTEXT_MAX_STRANDS: u32 = 250;

/// Largest factor by which the leaves of a stand skeleton grow to make up for its fewer tips.
pub const MAX_LEAF_GROWTH: f32 = 2.0;

/// No cap on the strands of a stand skeleton: every tree has its species' strand count at its
/// age, as `sylva tree grow` gives it (2 nodes per strand).
pub const FULL_STRANDS: u32 = u32::MAX;

/// Default most EcoMod strands of a stand skeleton of a stand export: 48 (about 100 nodes).
/// [`FULL_STRANDS`] (`sylva export --full-detail`, and the trees a picture draws at the full
/// level) gives the detail of a tree grown alone, but after Plastic Trees has pruned it among
/// its neighbours its foliage covers less of the simulated crown than the 48-strand tree's
/// spread leaf cards (Blender's top view of a 40-year beech plantation: 0.40 against the crown
/// discs' 0.75, 48 strands 0.62; BENCHMARKS.md round 17), so it is not the default yet.
pub const DEFAULT_MAX_STRANDS: u32 = 48;

impl SkeletonCache {
    /// An empty cache for scenario seed `seed`, trees of at most `max_strands` strands (≥ 8).
    pub fn new(seed: u64, max_strands: u32) -> SkeletonCache {
        SkeletonCache { seed, max_strands: max_strands.max(8), map: BTreeMap::new(), context: BTreeMap::new() }
    }

    /// The scenario seed the trees are grown with.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Number of (species, age class) trees held.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// True when nothing was grown yet.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// Seed of the tree of `species` in age class `class`: a hash of the scenario's seed, the
    /// species, the class and the architecture salt (the crown-base classes of one age class
    /// share it: the same tree with a longer bole).
    pub fn seed_of(&self, species: u16, class: u16) -> u64 {
        form_seed(self.seed, species, class)
    }

    /// Grows the missing trees of `keys` ([`FormKey`]: species, age class, crown-base class) in
    /// parallel. In a cache of [`FULL_STRANDS`], a tree of crown-base class q > 0 is grown as a
    /// forest tree: its EcoMod trunk
    /// (the first segment, `trunk_length_m`) is lengthened to T′ = (q + ε)·C/(1 − q − ε), C the
    /// length of the open-grown crown above the first split and ε = 0.01, so that its first
    /// branch leaves the stem just above the crown base once normalised, and the whole
    /// open-grown crown (every strand) stands above it; a species whose own trunk is longer
    /// keeps it. A capped cache grows the open-grown tree for every crown-base class.
    ///
    /// Errors: [`Error::Invalid`] for a species index outside `lib` or bad EcoMod parameters.
    pub fn prepare(&mut self, lib: &SpeciesLibrary, keys: &[FormKey]) -> Result<()> {
        let (seed, cap) = (self.seed, self.max_strands);
        Self::grow_missing(&mut self.map, seed, cap, lib, keys)
    }

    /// [`SkeletonCache::prepare`] for context trees: at most [`CONTEXT_MAX_STRANDS`] strands.
    ///
    /// Errors: those of [`SkeletonCache::prepare`].
    pub fn prepare_context(&mut self, lib: &SpeciesLibrary, keys: &[FormKey]) -> Result<()> {
        let (seed, cap) = (self.seed, self.max_strands.min(CONTEXT_MAX_STRANDS));
        Self::grow_missing(&mut self.context, seed, cap, lib, keys)
    }

    fn grow_missing(map: &mut BTreeMap<FormKey, Arc<OpenGrown>>, seed: u64, max_strands: u32, lib: &SpeciesLibrary, keys: &[FormKey]) -> Result<()> {
        let seed_of = |s: u16, c: u16| form_seed(seed, s, c);
        let mut missing: Vec<FormKey> = keys.iter().copied().filter(|k| !map.contains_key(k)).collect();
        missing.sort_unstable();
        missing.dedup();
        let grown: Vec<(FormKey, OpenGrown)> = missing
            .par_iter()
            .map(|&(s, c, q)| {
                let sp = lib.species.get(s as usize).ok_or_else(|| Error::Invalid { context: "stand skeletons".into(), field: "species".into(), value: s.to_string(), expected: format!("a species index below {}", lib.species.len()) })?;
                let mut p = sp.architecture.ecomod.clone();
                let full = ecomod_strands_at(p.strands, class_age(c));
                p.strands = full.min(max_strands);
                let (mut sk, mut lv) = ecomod::try_grow(&p, seed_of(s, c), 0.0)?;
                let qf = (q as f32 / CROWN_BASE_CLASSES).min(0.9) + 0.01;
                let crown = sk.height() - p.trunk_length_m;
                let trunk = qf * crown / (1.0 - qf);
                // a capped cache keeps the open-grown tree, shed below the crown base by [`fit`]
                // (its spread leaf cards fill the crown; see [`DEFAULT_MAX_STRANDS`])
                let forest_bole = max_strands == FULL_STRANDS && crown > 0.0 && trunk > p.trunk_length_m;
                if forest_bole {
                    p.trunk_length_m = trunk;
                    (sk, lv) = ecomod::try_grow(&p, seed_of(s, c), 0.0)?;
                }
                let (mut sk, mut lv) = super::normalised(&sk, &lv, 1.0)?;
                // EcoMod draws only its wind sway from the seed: the seed also turns the tree
                // about its stem, so that each scenario seed shows its own trees
                let turn = glam::Quat::from_rotation_z((seed_of(s, c) >> 11) as f32 / (1u64 << 53) as f32 * std::f32::consts::TAU);
                sk.nodes.iter_mut().for_each(|n| n.pos = turn * n.pos);
                lv.leaves.iter_mut().for_each(|l| {
                    l.pos = turn * l.pos;
                    l.dir = turn * l.dir;
                    l.normal = turn * l.normal;
                });
                let crown_radius = mean_crown_radius(&sk, &lv).max(0.05);
                // fewer strands, fewer tips: larger leaves keep the foliage area of the full tree
                let grow_leaf = (full as f32 / p.strands as f32).sqrt().min(MAX_LEAF_GROWTH);
                lv.leaves.iter_mut().for_each(|l| l.size *= grow_leaf);
                Ok(((s, c, q), OpenGrown { skeleton: sk, leaves: lv, crown_radius, forest_bole }))
            })
            .collect::<Result<_>>()?;
        for (k, g) in grown {
            map.insert(k, Arc::new(g));
        }
        Ok(())
    }

    /// The tree of `key` (species, age class, crown-base class), if grown.
    pub fn get(&self, key: FormKey) -> Option<&OpenGrown> {
        self.map.get(&key).map(|a| a.as_ref())
    }

    /// The context tree of `key` ([`SkeletonCache::prepare_context`]), if grown.
    pub fn get_context(&self, key: FormKey) -> Option<&OpenGrown> {
        self.context.get(&key).map(|a| a.as_ref())
    }
}

/// Crown radius (m) of a skeleton with its leaves as foresters measure it: the mean over eight
/// azimuth sectors of 45° about the root axis of the largest horizontal distance of a leaf tip
/// (or node) in the sector, a sector holding none counting 0: the usual field measure, crown
/// radii to the drip line in four to eight directions, averaged (e.g. Pretzsch 2009, Forest
/// Dynamics, Growth and Yield), which crown-width functions of stand-grown trees such as
/// those cited in the species files are fitted to. [`super::crown_radius`], the largest
/// distance of all, is up to a third larger for an irregular crown: a tree fitted to it drew a
/// crown narrower than the simulation's, whose discs the light model and the inventory use
/// (Blender's top-down cover of a full-detail export 0.63 against the discs' 0.75).
pub fn mean_crown_radius(sk: &Skeleton, leaves: &Leaves) -> f32 {
    let root = sk.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO);
    let mut sector = [0.0f32; 8];
    let mut eat = |p: Vec3| {
        let d = (p - root).truncate();
        let r = d.length();
        if r > 0.0 {
            let a = d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU);
            let k = ((a / std::f32::consts::FRAC_PI_4) as usize).min(7);
            sector[k] = sector[k].max(r);
        }
    };
    sk.nodes.iter().for_each(|n| eat(n.pos));
    leaves.leaves.iter().for_each(|l| eat(l.pos + l.dir * l.size));
    sector.iter().sum::<f32>() / 8.0
}

/// Seed of the open-grown tree of `species` in age class `class` for scenario seed `seed`.
fn form_seed(seed: u64, species: u16, class: u16) -> u64 {
    crate::rng::hash(&[seed, species as u64, class as u64, crate::rng::salt::ARCHITECTURE])
}

/// The open-grown tree `g` fitted to height `h`, crown radius `r` and crown base `cb` (m): the
/// scaling and crown-base shedding of step 2 of the module documentation, base at the origin.
pub fn fit(g: &OpenGrown, h: f32, r: f32, cb: f32) -> (Skeleton, Leaves) {
    let (sk, lf) = fit_skeleton(g, h, r, cb);
    let mut lv = Leaves { leaves: Vec::with_capacity(g.leaves.len()) };
    lv.leaves.extend(g.leaves.leaves.iter().filter_map(|l| lf.leaf(l)));
    (sk, lv)
}

/// How [`fit`] turns the open-grown tree's leaves into the fitted tree's: each leaf's position
/// scaled by `s`, its size by `h`, its node renumbered by `map` (`None`: the nodes kept as they
/// are; a leaf whose node was shed is dropped). Kept per class instead of the fitted leaves
/// themselves, which the adapted trees' leaves are made from one tree at a time
/// ([`adapted_with_leaves`]): a class's leaves are about 18 per node at full detail, and holding
/// them for every class took about 2 GiB of the near field bench's 6.6 GiB peak (round 27).
#[derive(Debug, Clone)]
struct LeafFit {
    s: Vec3,
    h: f32,
    map: Option<Vec<Option<u32>>>,
}

impl LeafFit {
    /// Leaf `l` of the open-grown tree as [`fit`] gives it: `None` when its node was shed.
    fn leaf(&self, l: &super::Leaf) -> Option<super::Leaf> {
        let node = match &self.map {
            Some(m) => m[l.node as usize]?,
            None => l.node,
        };
        Some(super::Leaf { pos: l.pos * self.s, size: l.size * self.h, node, ..*l })
    }
}

/// The skeleton of [`fit`], and how its leaves follow ([`LeafFit`]).
fn fit_skeleton(g: &OpenGrown, h: f32, r: f32, cb: f32) -> (Skeleton, LeafFit) {
    let s = Vec3::new(r / g.crown_radius, r / g.crown_radius, h);
    let mut sk = g.skeleton.clone();
    for n in &mut sk.nodes {
        n.pos *= s;
        n.radius *= h;
    }
    let cb = cb.clamp(0.0, 0.9 * h);
    let remove: Vec<bool> = sk
        .nodes
        .iter()
        .map(|n| match n.parent {
            Some(p) => {
                let par = &sk.nodes[p as usize];
                par.gravelius == 0 && n.gravelius > 0 && par.pos.z < cb
            }
            None => false,
        })
        .collect();
    let mut map = None;
    if remove.iter().any(|&x| x) {
        map = Some(sk.prune(&remove));
        sk.mark_tips();
    }
    (sk, LeafFit { s, h, map })
}

/// Lean of the main stem from the vertical (degrees, 0–180): (root → crown base, root → top),
/// where the main stem is the path of Gravelius order 0 from the root (node 0) along each
/// node's continuing child, the crown base its first node with a branch (a child of higher
/// order; the top when it has none) and the top its last node. Real forest trees' stems are
/// near vertical (a few degrees); issue 32's "tent poles" leaned 10–20° after the adaptation.
/// (0, 0) for a skeleton of one node or a stem of zero length.
pub fn stem_lean_deg(sk: &Skeleton) -> (f32, f32) {
    let Some(root) = sk.nodes.first() else { return (0.0, 0.0) };
    let mut k = 0usize;
    let mut cb = None;
    loop {
        let nd = &sk.nodes[k];
        if cb.is_none() && k != 0 && nd.children.iter().any(|&c| sk.nodes[c as usize].gravelius > 0) {
            cb = Some(k);
        }
        match nd.children.iter().find(|&&c| sk.nodes[c as usize].gravelius == 0) {
            Some(&c) => k = c as usize,
            None => break,
        }
    }
    let lean = |p: Vec3| {
        let d = p - root.pos;
        if d.length() <= 0.0 {
            0.0
        } else {
            (d.z / d.length()).clamp(-1.0, 1.0).acos().to_degrees()
        }
    };
    (lean(sk.nodes[cb.unwrap_or(k)].pos), lean(sk.nodes[k].pos))
}

/// One adapted tree of [`adapt_stand`].
#[derive(Debug, Clone)]
pub struct AdaptedTree {
    /// Index of the tree in the `trees` given to [`adapt_stand`].
    pub index: usize,
    /// Adapted skeleton (world coordinates, m).
    pub skeleton: Skeleton,
    /// Its leaves, moved with their nodes (world coordinates), made when read
    /// ([`AdaptedLeaves::build`]): held as the class's open-grown leaves, the class's fit and
    /// each node's displacement (16 B a node instead of 44 B a leaf; about 13 leaves a node at
    /// full detail), the same leaves bit for bit.
    pub leaves: AdaptedLeaves,
    /// What the adaptation did.
    pub report: PlasticReport,
    /// Leaf clusters (centre, radius; m) of the fitted tree before adaptation.
    pub clusters_before: Vec<(Vec3, f32)>,
    /// Leaf clusters after adaptation (moved, dead ones left out).
    pub clusters_after: Vec<(Vec3, f32)>,
    /// The adapted leaf clusters of [`PlasticTree::leaf_clusters`] (section 5.2; world
    /// coordinates, m, scaled like [`AdaptedTree::clusters_after`]): one per terminal lobe of the
    /// full-grown stage, centre moved with its nodes, radius cut by obstacles (Fig. 4; 0 when
    /// deleted), translucency γ_c (eqs. 4, 13) and leaf density (eq. 12). The mid-level crown
    /// hull of the pictures is built from them ([`crate::structure::crown_hull`]).
    pub leaf_clusters: Vec<crate::structure::plastic::LeafCluster>,
}

/// What [`adapt_stand`] returns.
#[derive(Debug, Clone)]
pub struct Stand {
    /// The adapted trees, in the order of `targets`.
    pub trees: Vec<AdaptedTree>,
    /// Neighbourhood cells adapted.
    pub cells: usize,
    /// Trees in the neighbourhoods in all: the adapted trees and their context trees (which
    /// shade and block them as they stand, without being adapted).
    pub trees_in_groups: usize,
    /// Distinct analyses (shared by trees of the same class).
    pub analyses: usize,
    /// Wall time (s) from the start of step 1 (growing the open-grown trees) until the last
    /// class is analysed (step 2); cells whose classes are analysed already run meanwhile.
    pub analysis_s: f64,
    /// Wall time (s) of adapting the cells left after the last analysis (step 3; the two
    /// times add up to steps 1–3).
    pub adaptation_s: f64,
}

/// Analysis class of a tree ([`adapt_stand`] step 2): species, age class, crown-shape class
/// (R/H in steps of [`StandOptions::shape_step`], default [`SHAPE_STEP`]), crown-base class,
/// height class (steps of [`StandOptions::height_step`], default [`HEIGHT_STEP`]; 0 for a
/// context tree) and whether it is a context tree.
type ClassKey = (u16, u16, i32, u16, i32, bool);

/// The class steps (height, crown shape) of [`StandOptions::height_step`] and
/// [`StandOptions::shape_step`].
type Steps = (f32, f32);

fn class_of(t: &StandTree, context: bool, (height_step, shape_step): Steps) -> ClassKey {
    let q = |v: f32, step: f32| (v.max(1e-3).ln() / step.ln()).round() as i32;
    let height = if context { 0 } else { q(t.height_m, height_step) };
    (t.species, age_class(t.age_yr), q(t.crown_radius_m / t.height_m, shape_step), crown_base_class(t.height_m, t.crown_base_m), height, context)
}

/// Height, crown radius and crown base (m) a class of steps `(height, shape)` is analysed at.
fn class_dims(k: &ClassKey, (height_step, shape_step): Steps) -> (f32, f32, f32) {
    let h = if k.5 { CONTEXT_CLASS_HEIGHT_M } else { height_step.powi(k.4) };
    (h, shape_step.powi(k.2) * h, k.3 as f32 / CROWN_BASE_CLASSES * h)
}

/// Checks one stand tree.
fn validate_tree(i: usize, t: &StandTree, lib: &SpeciesLibrary) -> Result<()> {
    let bad = |field: &str, value: String, expected: &str| Err(Error::Invalid { context: format!("stand tree {i} (id {})", t.id), field: field.into(), value, expected: expected.into() });
    if t.species as usize >= lib.species.len() {
        return bad("species", t.species.to_string(), &format!("a species index below {}", lib.species.len()));
    }
    if !t.base.is_finite() {
        return bad("base", t.base.to_string(), "finite coordinates (m)");
    }
    if !(t.height_m > 0.0 && t.height_m.is_finite()) {
        return bad("height_m", t.height_m.to_string(), "a finite height > 0 m");
    }
    if !(t.crown_radius_m > 0.0 && t.crown_radius_m.is_finite()) {
        return bad("crown_radius_m", t.crown_radius_m.to_string(), "a finite crown radius > 0 m");
    }
    if !(t.crown_base_m >= 0.0 && t.crown_base_m < t.height_m) {
        return bad("crown_base_m", t.crown_base_m.to_string(), "0 ≤ crown base < height (m)");
    }
    if !(t.age_yr >= 0.0 && t.age_yr.is_finite()) {
        return bad("age_yr", t.age_yr.to_string(), "a finite age ≥ 0 years");
    }
    if !(t.slope_deg >= 0.0 && t.slope_deg < 90.0) || !t.aspect_deg.is_finite() {
        return bad("slope_deg/aspect_deg", format!("{}/{}", t.slope_deg, t.aspect_deg), "a slope 0–89° and a finite aspect");
    }
    Ok(())
}

/// Adapts the trees `targets` (indices into `trees`) with their neighbours among `trees`
/// (module documentation, steps 1–3); grows what `cache` lacks.
///
/// Errors: [`Error::Invalid`] naming the bad tree field, a target index outside `trees`, bad
/// options (cell ≤ 0 m, halo < 0 m, latitude outside −90–90°, sky rings that are not positive
/// multiples of 4 or not 1–32 directions, [`stand_sky`]), an invalid obstacle, or the
/// errors of [`SkeletonCache::prepare`] and [`PlasticTree::analyse`].
pub fn adapt_stand(trees: &[StandTree], targets: &[usize], lib: &SpeciesLibrary, cache: &mut SkeletonCache, opts: &StandOptions) -> Result<Stand> {
    let bad = |field: &str, value: String, expected: &str| Error::Invalid { context: "stand adaptation".into(), field: field.into(), value, expected: expected.into() };
    if !(opts.cell_m > 0.0 && opts.cell_m.is_finite()) {
        return Err(bad("cell_m", opts.cell_m.to_string(), "a cell side > 0 m"));
    }
    if !(opts.halo_m >= 0.0 && opts.halo_m.is_finite()) {
        return Err(bad("halo_m", opts.halo_m.to_string(), "a halo ≥ 0 m"));
    }
    if !(-90.0..=90.0).contains(&opts.latitude_deg) {
        return Err(bad("latitude_deg", opts.latitude_deg.to_string(), "−90–90°"));
    }
    super::grow::space::validate_obstacles(&opts.obstacles)?;
    let sky = stand_sky(opts.latitude_deg, &opts.sky_rings)?;
    if !(opts.height_step > 1.0 && opts.height_step <= 4.0) {
        return Err(bad("height_step", opts.height_step.to_string(), "a relative step of the height classes > 1 and ≤ 4 (default 1.25)"));
    }
    if !(opts.shape_step > 1.0 && opts.shape_step <= 2.0) {
        return Err(bad("shape_step", opts.shape_step.to_string(), "a relative step of the crown-shape classes > 1 and ≤ 2 (default 1.05)"));
    }
    for (field, v) in [("bend_light_cell_m", opts.bend_light_cell_m), ("leaf_light_cell_m", opts.leaf_light_cell_m)] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(bad(field, v.to_string(), "a cube side ≥ 0 m (0: every point its own light query)"));
        }
    }
    let hs: Steps = (opts.height_step, opts.shape_step);
    for &i in targets {
        if i >= trees.len() {
            return Err(bad("targets", i.to_string(), &format!("tree indices below {}", trees.len())));
        }
    }
    // 3. cells and their groups (targets first, then the context trees), in a fixed order
    let cell_of = |t: &StandTree| ((t.base.x / opts.cell_m).floor() as i64, (t.base.y / opts.cell_m).floor() as i64);
    let mut cells: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    for (k, &i) in targets.iter().enumerate() {
        cells.entry(cell_of(&trees[i])).or_default().push(k);
    }
    // a cell's trees in the order of their indices, not of the targets: the cell's first tree
    // sets its ground plane, and the group's order its casters' order, so the stand is the
    // same whatever the order of the targets (until round 41 the first target of a cell set
    // the plane, so a reordered list adapted sloped cells otherwise)
    for ks in cells.values_mut() {
        ks.sort_by_key(|&k| (targets[k], k));
    }
    // a hash of all trees by cell for the halo search
    let mut by_cell: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
    for (i, t) in trees.iter().enumerate() {
        by_cell.entry(cell_of(t)).or_default().push(i);
    }
    let reach = (opts.halo_m / opts.cell_m).ceil() as i64;
    let groups: Vec<((i64, i64), Vec<usize>, Vec<usize>)> = cells
        .iter()
        .map(|(&(cx, cy), ks)| {
            let mine: Vec<usize> = ks.iter().map(|&k| targets[k]).collect();
            let (x0, y0) = (cx as f32 * opts.cell_m - opts.halo_m, cy as f32 * opts.cell_m - opts.halo_m);
            let (x1, y1) = ((cx + 1) as f32 * opts.cell_m + opts.halo_m, (cy + 1) as f32 * opts.cell_m + opts.halo_m);
            let mut ctx = Vec::new();
            for gy in cy - reach..=cy + reach {
                for gx in cx - reach..=cx + reach {
                    for &i in by_cell.get(&(gx, gy)).map(|v| v.as_slice()).unwrap_or(&[]) {
                        let b = trees[i].base;
                        if b.x >= x0 && b.x < x1 && b.y >= y0 && b.y < y1 && !mine.contains(&i) {
                            ctx.push(i);
                        }
                    }
                }
            }
            ctx.sort_unstable();
            ((cx, cy), ks.clone(), [mine, ctx].concat())
        })
        .collect();
    for g in &groups {
        for &i in &g.2 {
            validate_tree(i, &trees[i], lib)?;
        }
    }
    // 1. open-grown trees
    let t0 = std::time::Instant::now();
    // each cell's own trees at full detail, its context trees at [`CONTEXT_MAX_STRANDS`]
    let class_in = |g: &((i64, i64), Vec<usize>, Vec<usize>), j: usize| class_of(&trees[g.2[j]], j >= g.1.len(), hs);
    let mut classes: Vec<ClassKey> = groups.iter().flat_map(|g| (0..g.2.len()).map(move |j| class_in(g, j))).collect();
    classes.sort_unstable();
    classes.dedup();
    let form = |k: &ClassKey| (k.0, k.1, k.3);
    cache.prepare(lib, &classes.iter().filter(|k| !k.5).map(form).collect::<Vec<_>>())?;
    cache.prepare_context(lib, &classes.iter().filter(|k| k.5).map(form).collect::<Vec<_>>())?;
    // 2–3. one analysis per class and the cells, as one graph of tasks over the pool: a cell
    // starts as soon as the classes of its trees are analysed (no barrier between the two
    // steps: with one, a core waited for the other's last analysis), the largest cells first and
    // each cell's analyses in the order of the first cell that needs them, so the last tasks
    // are the small cells; a class's analysis is dropped after the last cell that uses it. Each
    // task depends only on its inputs, so the stand is the same whatever the order or the
    // thread count.
    let alone = Environment { obstacles: Vec::new(), ground: Some(Ground::flat(0.0)), sky: sky.clone() };
    let forest_grown = cache.max_strands == FULL_STRANDS;
    let cache = &*cache;
    let class_index = |k: &ClassKey| classes.binary_search(k).expect("every class of a group is listed");
    let needs: Vec<Vec<usize>> = groups
        .iter()
        .map(|g| {
            let mut v: Vec<usize> = (0..g.2.len()).map(|j| class_index(&class_in(g, j))).collect();
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect();
    // sizes for the order: a class's open-grown nodes (a context tree's analysis holds no light:
    // after the targets' classes), a cell's its targets' classes' nodes
    let nodes_of = |k: &ClassKey| {
        let g = if k.5 { cache.get_context(form(k)) } else { cache.get(form(k)) };
        g.map_or(0, |g| g.skeleton.nodes.len())
    };
    let class_cost: Vec<(bool, usize)> = classes.iter().map(|k| (k.5, nodes_of(k))).collect();
    let mut cell_order: Vec<usize> = (0..groups.len()).collect();
    let cell_cost: Vec<usize> = groups.iter().map(|g| (0..g.1.len()).map(|j| class_cost[class_index(&class_in(g, j))].1).sum()).collect();
    cell_order.sort_by_key(|&c| (std::cmp::Reverse(cell_cost[c]), c));
    let mut cell_rank = vec![0usize; groups.len()];
    let mut class_rank = vec![usize::MAX; classes.len()];
    let mut next = 0;
    for (r, &c) in cell_order.iter().enumerate() {
        cell_rank[c] = r;
        let mut fresh: Vec<usize> = needs[c].iter().copied().filter(|&k| class_rank[k] == usize::MAX).collect();
        fresh.sort_by_key(|&k| (class_cost[k].0, std::cmp::Reverse(class_cost[k].1), k));
        for k in fresh {
            class_rank[k] = next;
            next += 1;
        }
    }
    let mut by_rank: Vec<usize> = (0..classes.len()).collect();
    by_rank.sort_by_key(|&k| class_rank[k]);
    let mut cells_of: Vec<Vec<usize>> = vec![Vec::new(); classes.len()];
    for (c, need) in needs.iter().enumerate() {
        need.iter().for_each(|&k| cells_of[k].push(c));
    }
    let graph = Graph {
        queue: Mutex::new(by_rank.iter().map(|&k| Reverse((1u8, class_rank[k], k))).collect()),
        analysed: (0..classes.len()).map(|_| Mutex::new(None)).collect(),
        users: cells_of.iter().map(|v| AtomicUsize::new(v.len())).collect(),
        pending: needs.iter().map(|v| AtomicUsize::new(v.len())).collect(),
        cells: (0..groups.len()).map(|_| Mutex::new(None)).collect(),
        analysis_errors: Mutex::new(BTreeMap::new()),
        analyses_left: AtomicUsize::new(classes.len()),
        analyses_done: Mutex::new(None),
    };
    let analyse = |k: &ClassKey| -> Result<Analysed> {
        let g = if k.5 { cache.get_context(form(k)) } else { cache.get(form(k)) };
        let g = g.ok_or_else(|| bad("species/age class", format!("{}/{}", k.0, k.1), "a grown open-grown tree"))?;
        let (h, r, cb) = class_dims(k, hs);
        let (sk, lf) = fit_skeleton(g, h, r, cb);
        let sp = &lib.species[k.0 as usize];
        // a forest-grown tree (a cache of every strand) is not shed by light (eq. 11): its
        // bole already ends at the simulated crown base, the light-driven shedding of the
        // simulation; see the module docs, step 4
        let mut params = sp.architecture.plastic;
        if forest_grown && !k.5 {
            params.pruning_c_psi = 0.0;
        }
        // the forest form's lengthened bole is bent with the flexibility of its base (step 5)
        let bole = (g.forest_bole && !k.5 && sk.nodes.get(1).is_some_and(|n| n.parent == Some(0) && n.gravelius == 0)).then_some(1u32);
        let (mut t, lf) = if k.5 { (PlasticTree::standing(&sk, &params, &sky, None)?, None) } else { (PlasticTree::analyse(&sk, &params, &alone, None)?, Some(Arc::new(lf))) };
        t.set_bole(bole)?;
        t.clearance_m = sp.architecture.ecomod.leaf_size_m.max(0.0);
        Ok((t, lf))
    };
    // 3. one cell: its trees adapted together among its context trees
    let adapt_cell = |c: usize| -> Result<Vec<(usize, AdaptedTree)>> {
        let ((cx, cy), ks, members) = &groups[c];
        let analysed: BTreeMap<ClassKey, Arc<Analysed>> = needs[c].iter().map(|&k| (classes[k], graph.analysed[k].lock().expect("analysis slot").clone().expect("analysed before its cells"))).collect();
        // the class's tree scaled to the tree's height (an adapted tree keeps its
        // class's signatures and cluster transmittance; a context tree gets its species'
        // γ_c0 back: its shape-only analysis holds no light to stay consistent with) and
        // placed at its base
        let placed = |(j, &i): (usize, &usize)| -> Result<PlasticTree> {
            let key = class_of(&trees[i], j >= ks.len(), hs);
            let f = trees[i].height_m / class_dims(&key, hs).0;
            let class = &analysed[&key].0;
            let mut t;
            if key.5 {
                t = class.scaled(f)?;
                t.params.translucency_gamma_c0 = lib.species[key.0 as usize].architecture.plastic.translucency_gamma_c0;
            } else {
                t = class.scaled_grown_on_open_ground(f)?;
                (t.bend_light_cell_m, t.leaf_light_cell_m, t.bend_light_whole_level) = (opts.bend_light_cell_m, opts.leaf_light_cell_m, opts.bend_light_whole_level);
            }
            t.translate(trees[i].base);
            Ok(t)
        };
        // the cell's trees are adapted; the context trees stand as they are
        let mut group: Vec<PlasticTree> = members[..ks.len()].iter().enumerate().map(placed).collect::<Result<_>>()?;
        let context: Vec<PlasticTree> = members.iter().enumerate().skip(ks.len()).map(placed).collect::<Result<_>>()?;
        let first = &trees[members[0]];
        let mut ground = Ground::slope(first.base, first.slope_deg, first.aspect_deg);
        let lowest = members.iter().map(|&i| ground.height_of(trees[i].base)).fold(0.0f32, f32::min);
        ground.point += ground.normal * (lowest - 0.05);
        let centre = Vec3::new((*cx as f32 + 0.5) * opts.cell_m, (*cy as f32 + 0.5) * opts.cell_m, first.base.z);
        let tallest = members.iter().map(|&i| trees[i].height_m + trees[i].crown_radius_m).fold(0.0f32, f32::max);
        let near = opts.cell_m + opts.halo_m + 2.0 * tallest;
        let obstacles: Vec<Obstacle> = opts.obstacles.iter().copied().filter(|o| o.signed_distance(centre.with_z(centre.z + 0.5 * tallest)) < near).collect();
        let env = Environment { obstacles, ground: Some(ground), sky: sky.clone() };
        let before: Vec<Vec<(Vec3, f32)>> = group[..ks.len()].iter().map(|t| t.clusters()).collect();
        let rep = adapt_group_among_once(&mut group, &context, &env)?;
        drop(context);
        // each tree's output (its leaves are most of the near field's memory and the cell's
        // last serial work) built as a task of its own, so the other core can take a share of
        // a cell's trees (round 35); each tree's result depends only on its own inputs
        let out: Vec<(usize, AdaptedTree)> = ks
            .par_iter()
            .zip(before.into_par_iter())
            .enumerate()
            .map(|(j, (&k, before))| {
                let i = members[j];
                let st = &trees[i];
                let key = class_of(st, false, hs);
                let (h, r, _) = class_dims(&key, hs);
                let f = st.height_m / h;
                let t = &group[j];
                let open = cache.map.get(&form(&key)).cloned();
                // the exact crown radius: stretched about the base by the crown-shape class's
                // rounding (the height is exact)
                let sx = st.crown_radius_m / (r * f);
                let s = Vec3::new(sx, sx, 1.0);
                let at = |p: Vec3| st.base + (p - st.base) * s;
                let (skeleton, leaves) = adapted_with_leaves(t, open, analysed[&key].1.clone(), f, st.base, s, at);
                let scale_c = |v: Vec<(Vec3, f32)>| v.into_iter().map(|(c, rad)| (at(c), rad * s.x.max(s.z))).collect::<Vec<_>>();
                (k, AdaptedTree { index: i, skeleton, leaves, report: rep.trees[j], clusters_before: scale_c(before), clusters_after: scale_c(t.clusters()), leaf_clusters: t.leaf_clusters().into_iter().map(|c| LeafCluster { center: at(c.center), radius: c.radius * s.x.max(s.z), ..c }).collect() })
            })
            .collect();
        Ok(out)
    };
    let run = |task: (u8, usize, usize)| -> Vec<(u8, usize, usize)> {
        let (kind, _, x) = task;
        let mut ready = Vec::new();
        if kind == 1 {
            match analyse(&classes[x]) {
                Ok(a) => {
                    *graph.analysed[x].lock().expect("analysis slot") = Some(Arc::new(a));
                    for &c in &cells_of[x] {
                        if graph.pending[c].fetch_sub(1, Ordering::AcqRel) == 1 {
                            ready.push((0u8, cell_rank[c], c));
                        }
                    }
                }
                Err(e) => {
                    graph.analysis_errors.lock().expect("errors").insert(x, e);
                }
            }
            if graph.analyses_left.fetch_sub(1, Ordering::AcqRel) == 1 {
                *graph.analyses_done.lock().expect("time") = Some(t0.elapsed().as_secs_f64());
            }
        } else {
            let out = adapt_cell(x);
            *graph.cells[x].lock().expect("cell slot") = Some(out);
            // a class's analysis is dropped with the last cell that uses it
            for &k in &needs[x] {
                if graph.users[k].fetch_sub(1, Ordering::AcqRel) == 1 {
                    graph.analysed[k].lock().expect("analysis slot").take();
                }
            }
        }
        ready
    };
    rayon::scope(|s| {
        for _ in 0..classes.len() {
            s.spawn(|s| graph.step(s, &run));
        }
    });
    let errors = graph.analysis_errors.into_inner().expect("errors");
    if let Some((_, e)) = errors.into_iter().next() {
        return Err(e);
    }
    let total_s = t0.elapsed().as_secs_f64();
    let analysis_s = graph.analyses_done.into_inner().expect("time").unwrap_or(0.0);
    let mut slots: Vec<Option<AdaptedTree>> = vec![None; targets.len()];
    for cell in graph.cells {
        for (k, a) in cell.into_inner().expect("cell slot").expect("every cell adapted")? {
            slots[k] = Some(a);
        }
    }
    Ok(Stand { trees: slots.into_iter().flatten().collect(), cells: groups.len(), trees_in_groups: groups.iter().map(|g| g.2.len()).sum(), analyses: classes.len(), analysis_s, adaptation_s: total_s - analysis_s })
}

/// A class's analysed tree and how its leaves follow from the open-grown tree's (none for a
/// context tree).
type Analysed = (PlasticTree, Option<Arc<LeafFit>>);

/// The task graph of [`adapt_stand`]'s steps 2–3. A task is (kind, rank, index): kind 0 a cell
/// (index into the groups), 1 a class's analysis (index into the classes); the pool's jobs take
/// the task of the smallest (kind, rank) ready: a ready cell before any analysis, the largest
/// first.
struct Graph {
    /// The ready tasks, smallest (kind, rank) first.
    queue: Mutex<BinaryHeap<Reverse<(u8, usize, usize)>>>,
    /// Each class's analysis, from its task until the last cell that uses it is adapted.
    analysed: Vec<Mutex<Option<Arc<Analysed>>>>,
    /// Cells still to adapt that use each class.
    users: Vec<AtomicUsize>,
    /// Classes each cell still waits for.
    pending: Vec<AtomicUsize>,
    /// Each cell's adapted trees (index in `targets`, tree).
    cells: Vec<Mutex<Option<Result<Vec<(usize, AdaptedTree)>>>>>,
    /// Failed analyses by class index (the first is reported; their cells never start).
    analysis_errors: Mutex<BTreeMap<usize, Error>>,
    analyses_left: AtomicUsize,
    /// Wall time (s) from the start of step 2 until the last analysis was done.
    analyses_done: Mutex<Option<f64>>,
}

impl Graph {
    /// One job of the pool: runs the first ready task with `run`, which returns the tasks it
    /// made ready; each gets a job of its own.
    fn step<'s, F>(&'s self, s: &rayon::Scope<'s>, run: &'s F)
    where
        F: Fn((u8, usize, usize)) -> Vec<(u8, usize, usize)> + Sync,
    {
        let Some(Reverse(task)) = self.queue.lock().expect("task queue").pop() else { return };
        let ready = run(task);
        if ready.is_empty() {
            return;
        }
        let mut q = self.queue.lock().expect("task queue");
        for t in ready {
            q.push(Reverse(t));
            s.spawn(move |s| self.step(s, run));
        }
    }
}

/// The adapted skeleton of `t` ([`PlasticTree::skeleton`]) and the leaves of its input
/// ([`AdaptedLeaves`], made when read): the open-grown tree's leaves `open` as its class's fit
/// gives them (`fit`: [`LeafFit::leaf`], in the frame of the class's analysis, base at the
/// origin; no leaves without it), then, with `f` the uniform scale and `base` the translation
/// applied to the tree since, each leaf scaled, moved by its node's displacement and dropped with
/// its node; finally every node and leaf position p becomes `at(p)` = base + (p − base) · `s`
/// (the crown's stretch to its exact radius). The same leaves, bit for bit, as from the class's
/// fitted leaves held whole and stretched after (rounds 34–35).
fn adapted_with_leaves(t: &PlasticTree, open: Option<Arc<OpenGrown>>, fit: Option<Arc<LeafFit>>, f: f32, base: Vec3, s: Vec3, at: impl Fn(Vec3) -> Vec3) -> (Skeleton, AdaptedLeaves) {
    let mut sk = t.skeleton();
    sk.nodes.iter_mut().for_each(|n| n.pos = at(n.pos));
    let (Some(open), Some(fit)) = (open, fit) else { return (sk, AdaptedLeaves::default()) };
    let input = t.input();
    let fates = t.fates();
    let pos = t.positions();
    // the id map of Skeleton::prune: removed nodes and their descendants are gone
    let n = input.nodes.len();
    let mut gone = vec![false; n];
    let mut nodes = Vec::with_capacity(n);
    let mut next = 0u32;
    for k in 0..n {
        let p = input.nodes[k].parent.map(|p| p as usize);
        gone[k] = k > 0 && (fates[k] != Fate::Alive || p.is_some_and(|p| gone[p]));
        if gone[k] {
            nodes.push((GONE, Vec3::ZERO));
        } else {
            nodes.push((next, pos[k] - input.nodes[k].pos));
            next += 1;
        }
    }
    (sk, AdaptedLeaves(LeafSource::Made(MadeLeaves { open, fit, nodes, f, base, s })))
}

/// A node of [`MadeLeaves::nodes`] shed by the adaptation (its leaves are dropped).
const GONE: u32 = u32::MAX;

/// The leaves of an adapted tree ([`AdaptedTree::leaves`]), made when read: the open-grown
/// tree's leaves of its class, the class's fit and, per node of the fitted tree, its id in the
/// adapted skeleton and its displacement by the adaptation (m). A near field's adapted trees
/// hold about 13 leaves a node at full detail (66.7 M leaves, 2.9 GB, for the 1,000 targets of
/// `benches/stand.rs`); held this way they take 16 B a node, and each consumer (export, stills,
/// viewer) makes one tree's leaves at a time ([`AdaptedLeaves::build`]), the same leaves bit for
/// bit as the adaptation made them until round 35 (BENCHMARKS.md, round 36).
#[derive(Debug, Clone, Default)]
pub struct AdaptedLeaves(LeafSource);

#[derive(Debug, Clone)]
enum LeafSource {
    /// Leaves given whole ([`AdaptedLeaves::from`]).
    Held(Leaves),
    /// Leaves made from the class's open-grown tree.
    Made(MadeLeaves),
}

impl Default for LeafSource {
    fn default() -> Self {
        LeafSource::Held(Leaves::default())
    }
}

#[derive(Debug, Clone)]
struct MadeLeaves {
    /// The class's open-grown tree (its leaves are read).
    open: Arc<OpenGrown>,
    /// How the class's fit turns them into the fitted tree's.
    fit: Arc<LeafFit>,
    /// Per node of the fitted tree: its id in the adapted skeleton ([`GONE`] when shed) and its
    /// displacement by the adaptation (m, in the frame scaled by `f`).
    nodes: Vec<(u32, Vec3)>,
    /// Uniform scale from the class's height to the tree's.
    f: f32,
    /// Stem base (m, world coordinates).
    base: Vec3,
    /// The crown's stretch about `base` to its exact radius (x, y; z is 1).
    s: Vec3,
}

impl AdaptedLeaves {
    /// Calls `each` on every leaf in order (world coordinates, m), as [`AdaptedLeaves::build`]
    /// holds them.
    pub fn for_each(&self, mut each: impl FnMut(super::Leaf)) {
        match &self.0 {
            LeafSource::Held(lv) => lv.leaves.iter().copied().for_each(each),
            LeafSource::Made(m) => {
                let (f, base, s) = (m.f, m.base, m.s);
                for l in m.open.leaves.leaves.iter().filter_map(|l| m.fit.leaf(l)) {
                    if let Some(&(nk, d)) = m.nodes.get(l.node as usize) {
                        if nk != GONE {
                            let p = l.pos * f + base + d;
                            each(super::Leaf { pos: base + (p - base) * s, size: l.size * f, node: nk, ..l });
                        }
                    }
                }
            }
        }
    }

    /// The leaves, made (a copy when they were given whole).
    pub fn build(&self) -> Leaves {
        match &self.0 {
            LeafSource::Held(lv) => lv.clone(),
            LeafSource::Made(_) => {
                let mut lv = Leaves { leaves: Vec::with_capacity(self.len()) };
                self.for_each(|l| lv.leaves.push(l));
                lv
            }
        }
    }

    /// The leaves, made, taking them when they were given whole.
    pub fn into_leaves(self) -> Leaves {
        match self.0 {
            LeafSource::Held(lv) => lv,
            made @ LeafSource::Made(_) => AdaptedLeaves(made).build(),
        }
    }

    /// Number of leaves (counted without making them when they are made when read).
    pub fn len(&self) -> usize {
        match &self.0 {
            LeafSource::Held(lv) => lv.len(),
            LeafSource::Made(m) => m.open.leaves.leaves.iter().filter_map(|l| m.fit.leaf(l)).filter(|l| m.nodes.get(l.node as usize).is_some_and(|&(nk, _)| nk != GONE)).count(),
        }
    }

    /// True when there are no leaves.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes this tree's leaves hold of their own (bytes): the leaves given whole, or the
    /// per-node table of leaves made when read (the open-grown tree and the fit are shared
    /// by the class).
    pub fn held_bytes(&self) -> usize {
        match &self.0 {
            LeafSource::Held(lv) => lv.leaves.capacity() * std::mem::size_of::<super::Leaf>(),
            LeafSource::Made(m) => m.nodes.capacity() * std::mem::size_of::<(u32, Vec3)>(),
        }
    }
}

impl From<Leaves> for AdaptedLeaves {
    fn from(lv: Leaves) -> Self {
        AdaptedLeaves(LeafSource::Held(lv))
    }
}

/// Overlap of the leaf clusters of different trees: Σ over pairs of clusters of two different
/// trees of the volume of the intersection of their spheres (m³; lens volume
/// π(r₁ + r₂ − d)²(d² + 2d(r₁ + r₂) − 3(r₁ − r₂)²)/(12d), the smaller sphere's volume when one
/// holds the other). `clusters[i]` are tree i's (centre, radius) pairs.
pub fn cluster_overlap(clusters: &[Vec<(Vec3, f32)>]) -> f64 {
    let mut total = 0.0f64;
    for i in 0..clusters.len() {
        for j in i + 1..clusters.len() {
            for &(a, ra) in &clusters[i] {
                for &(b, rb) in &clusters[j] {
                    total += sphere_intersection(a.distance(b) as f64, ra as f64, rb as f64);
                }
            }
        }
    }
    total
}

/// Volume (m³) of the intersection of two spheres of radii `r1`, `r2` (m) at centre distance `d`
/// (m): 0 when apart, the smaller sphere's volume when inside the other, the lens volume
/// otherwise (see [`cluster_overlap`]).
pub fn sphere_intersection(d: f64, r1: f64, r2: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= r1 + r2 {
        return 0.0;
    }
    if d <= (r1 - r2).abs() {
        let r = r1.min(r2);
        return 4.0 / 3.0 * PI * r * r * r;
    }
    PI * (r1 + r2 - d).powi(2) * (d * d + 2.0 * d * (r1 + r2) - 3.0 * (r1 - r2).powi(2)) / (12.0 * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_intersection_limits() {
        // apart, touching, contained, identical
        assert_eq!(sphere_intersection(3.0, 1.0, 1.0), 0.0);
        assert_eq!(sphere_intersection(2.0, 1.0, 1.0), 0.0);
        let v1 = 4.0 / 3.0 * std::f64::consts::PI;
        assert!((sphere_intersection(0.5, 2.0, 1.0) - v1).abs() < 1e-12);
        assert!((sphere_intersection(1e-9, 1.0, 1.0) - v1).abs() < 1e-6);
        // two unit spheres at d = 1: 5π/12
        assert!((sphere_intersection(1.0, 1.0, 1.0) - 5.0 * std::f64::consts::PI / 12.0).abs() < 1e-12);
    }

    #[test]
    fn age_classes() {
        assert_eq!(age_class(0.0), 0);
        assert_eq!(age_class(4.9), 0);
        assert_eq!(age_class(5.0), 1);
        assert_eq!(age_class(79.0), 15);
        assert_eq!(age_class(80.0), LAST_AGE_CLASS);
        assert_eq!(age_class(500.0), LAST_AGE_CLASS);
        assert_eq!(class_age(15), 77.5);
        assert_eq!(class_age(LAST_AGE_CLASS), 80.0);
        assert_eq!(crown_base_class(20.0, 8.0), 8);
        assert_eq!(crown_base_class(20.0, 19.9), 18);
    }
}
