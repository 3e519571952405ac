//! Stills and timelapses of a run directory: the glue between inventory snapshots
//! ([`super::inventory`]), scene building ([`super::scene`]) and the headless renderer.

use super::inventory::{self, InventoryRow};
use super::scene::{self, Plant};
use crate::conditions::SiteConditions;
use crate::render::camera::{Camera, CameraPreset};
use crate::render::headless::Renderer;
use crate::render::scene::{Scene, TreeInstance};
use super::adapted::{self, AdaptOptions, AdaptStats};
use crate::sim::obstacle::ObstacleSpec;
use crate::render::timelapse;
use crate::species::{Season, SpeciesLibrary};
use super::Result;
use crate::Error;
use std::path::{Path, PathBuf};

/// Everything needed to draw any snapshot of one run: built once, reused for every frame.
pub struct Stage {
    /// Site conditions the run used.
    pub site: SiteConditions,
    /// Species library (indexes the prototypes).
    pub library: SpeciesLibrary,
    /// The scene drawn: terrain mesh, tree models (one prototype per library species), sea
    /// level (m) for the water plane when any cell is water. Built once; each frame only sets
    /// its instances and sun (no copy of the terrain or the prototypes per frame).
    pub scene: Scene,
    /// The renderer (wgpu device on a GPU or the software adapter).
    pub renderer: Renderer,
    /// The scenario's obstacles, drawn in every picture ([`Stage::set_scenario`]).
    pub obstacles: Vec<ObstacleSpec>,
    /// Adapted near field ([`super::adapted`]) in [`Stage::render_plants`]; `None`: every tree
    /// is an instanced species prototype.
    pub adapt: Option<AdaptOptions>,
    /// What the last [`Stage::render_plants`] adapted.
    pub last_adapt: AdaptStats,
    /// Prototypes of the species and obstacles: the first this many of the scene's (those
    /// after them, the adapted trees of one frame, are dropped after it). Not held twice:
    /// a second copy of the species' level-of-detail chains took about 200 MB (issue 34).
    n_base: usize,
    /// Instances of the obstacles.
    obstacle_instances: Vec<TreeInstance>,
    /// Index of the first stump prototype ([`scene::stump_prototypes`], after the species'
    /// and the obstacles').
    stump_first: u32,
    /// Instances of the stumps drawn in every picture until changed ([`Stage::set_stumps`]).
    stump_instances: Vec<TreeInstance>,
    /// Open-grown trees per species and age class (the scenario's seed).
    cache: adapted::NearCaches,
    /// The ground drawn: the site and its surroundings ([`Stage::set_surroundings`]), recoloured
    /// by each frame's canopy (forest floor under crowns).
    landscape: scene::Landscape,
}

/// Budget of tree triangles of a still (`sylva run`'s stills and close-up, `sylva render`'s
/// default, [`crate::render::lod::LodParams::max_triangles`]): when the trees at their levels
/// would cost more, the renderer raises every level switch by the smallest factor `2^(k/4)`
/// that fits ([`crate::render::lod::budget_scale`]), so that the trees smallest on screen (of
/// one height, the farthest) drop to their next levels first, down to billboards, and the
/// trees nearest the camera keep full detail. The stills are culled on the CPU, where the
/// factor from the histogram of projected sizes is then raised until the frame's exact cost
/// fits ([`crate::render::instanced::build_batches_of`]). Deterministic: integer counts over
/// the trees, whatever the order or thread count. 30 M: the default run's year-150 close-up
/// at 1280 × 720 drew 29.5 M (round 36); a small site's close-up costs no more.
pub const STILL_TRIANGLE_BUDGET: u32 = 30_000_000;

/// Tree triangles a film frame of `width` × `height` pixels may draw: [`STILL_TRIANGLE_BUDGET`]
/// (set for a 1280 × 720 still, about 33 triangles a pixel) in proportion to the frame's pixels,
/// at least 1,000,000 and at most the stills' budget: a 640 × 360 frame 7.5 M, 320 × 180 1.9 M.
/// A film's trees are no smaller on screen at a smaller frame than its pixels allow, so its
/// frames need no more triangles a pixel than a still (trial 43 defect 6: a 1.4 ha run's
/// 320 × 180 frames drew full-detail trees for about 55 s a frame on a software adapter).
/// The budget's effect is as for stills ([`crate::render::lod::budget_scale`]): the trees
/// smallest on screen drop to their next levels first.
pub fn frame_triangle_budget(width: u32, height: u32) -> u32 {
    let share = (width as f64 * height as f64) / (1280.0 * 720.0);
    (STILL_TRIANGLE_BUDGET as f64 * share).round().clamp(1_000_000.0, STILL_TRIANGLE_BUDGET as f64) as u32
}

/// Smallest [`AdaptOptions::near_m`] of the stills' near field (m, 120): the trees in the
/// picture within it are adapted ([`AdaptOptions::image_width_px`]), the nearest
/// [`AdaptOptions::max_trees`] of them.
pub const STILL_NEAR_M: f32 = 120.0;

/// [`crate::render::lod::LodParams::small_tree_m`] of the stills (25 m): every tree shorter
/// than it (down to a third of it) picks the level a 25 m tree would have where it stands, so a
/// 10 m tree beside a 25 m one is drawn at its level (trial 42 defect 4: hull "popcorn" beside
/// speckled cards at one distance); taller trees keep the level of their own size, never
/// coarser (round 43's 25 m reference, applied both ways, drew the close-up's canopy trees a
/// level coarser and was reverted). 25 m: about the top height of the default run's canopy,
/// where the switch sizes were tuned (H100 25.9 m at year 150, round 43's default run).
pub const STILL_SMALL_TREE_M: f32 = 25.0;

/// [`crate::render::lod::LodParams::small_tree_floor_m`] of the stills (12 m): under a binding
/// triangle budget, or where it would add more than
/// [`crate::render::lod::SMALL_TREE_MAX_EXTRA`] to the frame's triangles, the reference
/// [`STILL_SMALL_TREE_M`] is lowered towards it before any tree drops a level, and the budget's switch factor is the one the 12 m reference gives, so no
/// tree is drawn coarser than with the stills' reference of rounds 36–43 (ESTIMATE of round
/// 36: about the height under which the trial's mid-ground trees were drawn as crown hulls of
/// a few dozen pixels, "balls on sticks").
pub const STILL_SMALL_TREE_FLOOR_M: f32 = 12.0;

impl Stage {
    /// Builds the stage: terrain mesh with cells ≤ 10 m (the site alone, its edges faded out;
    /// [`Stage::set_surroundings`] adds the terrain around it), one EcoMod prototype per species.
    ///
    /// # Errors
    /// [`super::JobError::Render`] ([`crate::render::RenderError::NoAdapter`]) when no wgpu adapter is found.
    pub fn new(site: SiteConditions, library: SpeciesLibrary, sea_level_m: f32) -> Result<Self> {
        let landscape = scene::Landscape::new(&site, None, 10.0, sea_level_m)?;
        let terrain = landscape.mesh(&[])?;
        let mut prototypes = scene::prototypes(&library);
        let stump_first = prototypes.len() as u32;
        prototypes.extend(scene::stump_prototypes());
        let mut renderer = Renderer::new()?;
        // Offline stills: a larger triangle budget than the interactive default keeps the trees
        // near the camera at full detail (trunks and branches) in the close views, and lower switch
        // sizes keep mid-distance crowns as meshes rather than billboards.
        renderer.lod.max_triangles = STILL_TRIANGLE_BUDGET;
        renderer.lod.switch_px = [110.0, 45.0, 18.0];
        // no far-field triangle budget for stills: only trees under `canopy_px` (6 px) go to
        // the canopy layer
        renderer.lod.max_geometry_triangles = 0;
        // trees under 25 m pick the level a 25 m tree has where they stand (young trees in the
        // mid-ground read as trees, not balls on sticks, and take their tall neighbours' level),
        // as far as the triangle budget allows at the switch factor of a 12 m reference
        // (issue 32, rounds 36 and 44)
        renderer.lod.small_tree_m = STILL_SMALL_TREE_M;
        renderer.lod.small_tree_floor_m = STILL_SMALL_TREE_FLOOR_M;
        // culled on the CPU, where the frame's exact cost is checked against the triangle
        // budget (`render::instanced::build_batches_of`); the GPU path's histogram estimate
        // let a small dense site's close-up draw 2.5 times its budget (round 36)
        renderer.culling = crate::render::headless::Culling::Cpu;
        // the tree draws over render passes of at most ~250,000 triangles each, each submitted
        // and waited for on a software adapter: lavapipe binned up to 64 scenes of 36 MB
        // (2.3 GB) of the year-150 still ahead of its rasterisers; now about 150 MB
        // (issue 34: 2,000,000 a pass, 1.9 GB resident in all; 500,000, 1.6 GB; 250,000,
        // 1.5 GB; 125,000, 1.46 GB; the frame's time the same within the machine's noise)
        renderer.pass_triangles = 250_000;
        // a tree in a cross-fade band draws one of its two levels whole: the complementary
        // Bayer masks of the two levels read as a screen-door dot pattern on the mid-ground's
        // crowns (trial 39, issue 32 round 40); a still has no camera motion that would show
        // a tree changing level
        renderer.fade_per_tree = true;
        // and the CPU records only that level (`LodParams::one_level_per_tree`): main's path
        // submitted the other record too, discarded whole by the fragment shader, so a banded
        // tree cost both levels' triangles (round 45 measured the default run's close-up at
        // 18.0 M triangles with one record against 27.4 M). Under a budget that the 25 m
        // reference cannot meet, the switch factor is lowered while the 12 m reference's exact
        // cost fits (round 46; BENCHMARKS.md, rounds 45 (r45k) and 46 (r46n))
        renderer.lod.one_level_per_tree = true;
        let has_water = site.mask.data.iter().zip(&site.elevation_m.data).any(|(m, z)| !*m && z.is_finite() && *z <= sea_level_m);
        let n_base = prototypes.len();
        let scene = scene::scene(terrain, prototypes, Vec::new(), site.geo.latitude_deg, Season::Summer, has_water.then_some(sea_level_m));
        Ok(Stage { site, library, scene, renderer, obstacles: Vec::new(), adapt: Some(AdaptOptions::default()), last_adapt: AdaptStats::default(), n_base, obstacle_instances: Vec::new(), stump_first, stump_instances: Vec::new(), cache: adapted::cache(0), landscape })
    }

    /// The stage of a scenario's pictures: [`Stage::new`] with its sea level, its seed and
    /// obstacles ([`Stage::set_scenario`]) and the terrain around its window
    /// ([`Stage::set_surroundings_of`]).
    ///
    /// Errors: as [`Stage::new`]; reading the scenario's terrain under "the terrain around the
    /// simulated window" ([`super::JobError::Context`]).
    pub fn for_scenario(sc: &crate::sim::Scenario, site: SiteConditions, library: SpeciesLibrary) -> Result<Self> {
        let mut stage = Stage::new(site, library, sc.climate.sea_level_m)?;
        stage.set_scenario(sc.seed, &sc.obstacles);
        stage.set_surroundings_of(sc).map_err(|e| super::JobError::Context { what: "the terrain around the simulated window".into(), source: Box::new(e) })?;
        Ok(stage)
    }

    /// Sets the most tree triangles a frame draws (`LodParams::max_triangles`; the stills'
    /// default is [`STILL_TRIANGLE_BUDGET`]): a frame that would cost more raises every tree's
    /// level switches by one factor until it fits (`sylva render --triangle-budget`).
    pub fn set_triangle_budget(&mut self, triangles: u32) {
        self.renderer.lod.max_triangles = triangles;
    }

    /// Sets the adaptation of the near field ([`Stage::adapt`]; `None`: every tree an instanced
    /// prototype, and the open-grown skeletons grown for it so far are let go of); returns the
    /// one it replaces.
    pub fn set_adapt(&mut self, adapt: Option<AdaptOptions>) -> Option<AdaptOptions> {
        if adapt.is_none() {
            // the open-grown skeletons of the near field (full detail: thousands of nodes a class)
            // are grown again when adaptation is switched back on (issue 34)
            self.cache = adapted::cache(self.cache.full.seed());
        }
        std::mem::replace(&mut self.adapt, adapt)
    }

    /// Draws the terrain beyond the simulated window around it: `full` is the whole terrain
    /// the site was cut from with `window` (`[col0, row0, width, height]` in its cells), see
    /// [`scene::Landscape::new`].
    ///
    /// Errors: [`Error::Invalid`] when the window leaves `full`'s grid.
    pub fn set_surroundings(&mut self, full: &crate::terrain::Terrain, window: [usize; 4]) -> Result<()> {
        self.landscape = scene::Landscape::new(&self.site, Some((full, window)), 10.0, self.landscape.cover.sea_level)?;
        self.scene.set_terrain(self.landscape.mesh(&[])?);
        Ok(())
    }

    /// [`Stage::set_surroundings`] from a scenario with a `[terrain] window` of a DEM (nothing
    /// to do for other scenarios); the window's trees are mirrored into them unless the
    /// scenario designs its stand ([`crate::sim::Scenario::designs_its_stand`]).
    ///
    /// Errors: reading the scenario's terrain ([`crate::sim::Scenario::full_terrain`]).
    pub fn set_surroundings_of(&mut self, sc: &crate::sim::Scenario) -> Result<()> {
        if let Some(w) = sc.terrain.window {
            if let Some(t) = sc.full_terrain()? {
                self.set_surroundings(&t, w)?;
                self.landscape.mirror_trees = !sc.designs_its_stand();
            }
        }
        Ok(())
    }

    /// Sets what the scenario adds to the pictures: its seed (the open-grown trees of the
    /// adapted near field are grown with it) and its obstacles (drawn in every picture).
    pub fn set_scenario(&mut self, seed: u64, obstacles: &[ObstacleSpec]) {
        self.cache = adapted::cache(seed);
        self.obstacles = obstacles.to_vec();
        let n = self.library.species.len();
        let mut protos = std::mem::take(&mut self.scene.prototypes);
        protos.truncate(n);
        let (p, i) = adapted::obstacle_models(obstacles, &self.site, n as u32);
        protos.extend(p);
        self.stump_first = protos.len() as u32;
        protos.extend(scene::stump_prototypes());
        self.n_base = protos.len();
        self.stump_instances.clear();
        self.obstacle_instances = i;
        self.scene.set_prototypes(protos);
    }

    /// Sets the stumps drawn in the following pictures: those of `stumps` shown in a picture of
    /// `year` ([`scene::stump_instances`]: cut in the [`scene::STUMP_YEARS`] years up to it);
    /// an empty list draws none.
    pub fn set_stumps(&mut self, stumps: &[scene::Stump], year: u32) {
        self.stump_instances = scene::stump_instances(stumps, year, &self.site, self.stump_first);
    }

    /// The instances of the stumps of `stumps` shown in a picture of `year`, with this stage's
    /// stump prototypes ([`scene::stump_instances`]), e.g. to add to a timelapse's key frame.
    pub fn stump_instances_of(&self, stumps: &[scene::Stump], year: u32) -> Vec<TreeInstance> {
        scene::stump_instances(stumps, year, &self.site, self.stump_first)
    }

    /// Number of stump instances the following pictures draw (two per stump: bark and cut
    /// face).
    pub fn stump_instance_count(&self) -> usize {
        self.stump_instances.len()
    }

    /// Renders `rows` (an inventory snapshot) in `season` from `camera` at `width × height`.
    pub fn render_rows(&mut self, rows: &[InventoryRow], season: Season, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        self.render_plants(&scene::plants_from_rows(rows), season, camera, width, height)
    }

    /// Renders `plants` (e.g. [`scene::plants_from_world`] of the in-memory world) in `season`
    /// from `camera` at `width × height`.
    /// The trees near the camera are adapted with their neighbours and drawn with their own
    /// meshes when [`Stage::adapt`] is set ([`adapted::adapt_near_field`]; figures in
    /// [`Stage::last_adapt`]).
    ///
    /// Errors: rendering errors; [`crate::Error::Invalid`] from the adaptation.
    pub fn render_plants(&mut self, plants: &[Plant], season: Season, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        self.render_plants_with(plants, &[], season, camera, width, height)
    }

    /// [`Stage::render_plants`] with the saplings of the regeneration layer `saplings` drawn
    /// below the trees ([`scene::instances_with_saplings`]).
    ///
    /// Errors: as [`Stage::render_plants`].
    pub fn render_plants_with(&mut self, plants: &[Plant], saplings: &[scene::SaplingCohort], season: Season, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        let mut inst = scene::instances_with_saplings(plants, saplings, &self.library, &self.site, season);
        self.last_adapt = AdaptStats::default();
        let Some(mut o) = self.adapt.clone() else {
            return self.render_instances(inst, season, camera, width, height);
        };
        o.image_height_px = height as f32;
        // the trees this renderer may draw at its full level (from its first switch size less
        // the cross-fade band: 88 px with the stills' switches) are adapted at full detail;
        // `AdaptOptions::default` assumes the interactive switches (180 px), which left the
        // stills' trees of 88–180 px drawn at the full level with 48-strand skeletons and their
        // few leaf cards (round 36, issue 32: leafless birches in the close-up's foreground)
        let lod = &self.renderer.lod;
        o.full_px = o.full_px.min(lod.switch_px[0] / (1.0 + lod.band.max(0.0)));
        // the trees adapted are those in the picture, to 120 m: the close-up's foreground lies
        // about 80 m from its eye (45 m up), where the 80 m near field ended (round 36)
        o.image_width_px = width as f32;
        o.near_m = o.near_m.max(STILL_NEAR_M);
        // the adapted trees' prototypes are appended to the scene's own (taken out meanwhile, not
        // copied) and dropped after the frame
        let base = self.n_base;
        let mut protos = std::mem::take(&mut self.scene.prototypes);
        let adapt = adapted::adapt_near_field(plants, &mut inst, &mut protos, &self.library, &self.site, &self.obstacles, camera, season, &mut self.cache, &o);
        // the adaptation's working memory back to the system before the meshes are uploaded
        release_freed_memory();
        let unchanged = !matches!(adapt, Ok(ref a) if a.adapted_trees > 0);
        if unchanged {
            // the base prototypes back, as they were (same version: nothing to upload again)
            protos.truncate(base);
            self.scene.prototypes = protos;
            self.last_adapt = adapt?;
            return self.render_instances(inst, season, camera, width, height);
        }
        self.last_adapt = adapt?;
        let adapted: Vec<(TreeInstance, usize)> = inst.iter().filter(|t| t.species as usize >= base).map(|t| (*t, protos[t.species as usize].lods.levels.len())).collect();
        self.scene.set_prototypes(protos);
        // the adapted trees' meshes are held once, by the renderer, during the frame (issue 34)
        if let Err(e) = self.renderer.upload_scene(&self.scene) {
            let mut protos = std::mem::take(&mut self.scene.prototypes);
            protos.truncate(base);
            self.scene.set_prototypes(protos);
            return Err(e.into());
        }
        self.scene.prototypes[base..].iter_mut().for_each(|p| p.lods.free_meshes());
        release_freed_memory();
        let img = self.render_instances(inst, season, camera, width, height);
        let mut protos = std::mem::take(&mut self.scene.prototypes);
        protos.truncate(base);
        self.scene.set_prototypes(protos);
        self.last_adapt.per_level = drawn_levels_of(&adapted, camera, width, height, &self.renderer.lod, &self.renderer.last_stats());
        img
    }

    /// Renders prepared instances.
    pub fn render_instances(&mut self, mut inst: Vec<TreeInstance>, season: Season, camera: &Camera, width: u32, height: u32) -> Result<image::RgbaImage> {
        // every tree standing on the drawn ground (issue 32)
        self.landscape.stand_on_ground(&mut inst);
        // the window's trees mirrored into the surroundings (scene::Landscape::surroundings)
        let far = self.landscape.surroundings(&inst);
        let mut all = inst;
        // grown once to its size (a doubling growth held up to twice the frame's instances)
        all.reserve_exact(far.len() + self.obstacle_instances.len());
        all.extend(far);
        all.extend_from_slice(&self.obstacle_instances);
        self.scene.instances = all;
        // the ground under this frame's crowns: forest floor instead of grass
        self.scene.set_terrain(self.landscape.mesh(&self.scene.instances)?);
        // the stumps after the ground's colouring (no crowns) and not mirrored around
        self.scene.instances.extend_from_slice(&self.stump_instances);
        self.scene.sun = scene::season_sun(self.site.geo.latitude_deg, season);
        let img = self.renderer.render(&self.scene, camera, width, height);
        self.scene.instances = Vec::new();
        release_freed_memory();
        Ok(img?)
    }

    /// The camera of a preset for this terrain (for a square picture).
    pub fn camera(&self, preset: CameraPreset) -> Camera {
        Camera::preset(preset, &self.scene.terrain)
    }

    /// The camera of a preset for this terrain and a picture of `width` × `height` pixels
    /// ([`Camera::preset_sized`]: the map fits the window to the picture's shape).
    pub fn camera_sized(&self, preset: CameraPreset, width: u32, height: u32) -> Camera {
        Camera::preset_sized(preset, &self.scene.terrain, width, height)
    }

    /// The camera of a preset for a snapshot and a picture of `width` × `height` pixels: as
    /// [`Stage::camera_sized`], except that the ground-level
    /// camera steps into the nearest clearing, so that it does not stand inside a trunk or a
    /// crown. Candidate eye points on a grid (1/60 of the site, up to 30 % of it across and 10 %
    /// forward of the preset's eye) are scored by their clearance, the horizontal distance to the
    /// nearest live tree taller than the eye (1.7 m) minus its crown radius; the eye moves to the
    /// best one (ties: the nearest to the preset) unless the preset already has ≥ 2 m clearance.
    /// Looks north at 8 m above the ground in the site's middle row, as the preset does.
    pub fn camera_for(&self, preset: CameraPreset, rows: &[InventoryRow], width: u32, height: u32) -> Camera {
        self.camera_for_plants(preset, &scene::plants_from_rows(rows), width, height)
    }

    /// [`Stage::camera_for`] over [`Plant`]s.
    pub fn camera_for_plants(&self, preset: CameraPreset, rows: &[Plant], width: u32, height: u32) -> Camera {
        let cam = self.camera_sized(preset, width, height);
        if preset != CameraPreset::Ground {
            return cam;
        }
        step_into_clearing(cam, &self.site, &self.scene.terrain, rows)
    }
}

/// The ground camera `cam` of [`Stage::camera_for`] on `site` (whose terrain mesh is
/// `terrain`) stepped into the nearest clearing among `rows` (the viewer's `--camera ground`
/// too).
pub fn step_into_clearing(cam: Camera, site: &SiteConditions, terrain: &crate::render::terrain::TerrainMesh, rows: &[Plant]) -> Camera {
    {
        let (ex, ey) = site.extent_m();
        let size = ex.max(ey) as f32;
        let tall: Vec<(f32, f32, f32)> = rows.iter().filter(|r| r.alive && r.height_m > 1.7).map(|r| (r.x_m as f32, r.y_m as f32, r.crown_radius_m)).collect();
        let clearance = |x: f32, y: f32| tall.iter().map(|&(tx, ty, cr)| ((tx - x).hypot(ty - y) - cr).max(0.0)).fold(f32::INFINITY, f32::min);
        let [x0, y0, _] = cam.eye;
        if clearance(x0, y0) >= 2.0 {
            return cam;
        }
        let step = (size / 60.0).max(1.0);
        let mut best = (clearance(x0, y0), 0.0f32, x0, y0);
        for j in 0..=((0.1 * size / step) as i32) {
            for i in -((0.15 * size / step) as i32)..=((0.15 * size / step) as i32) {
                let (x, y) = (x0 + i as f32 * step, y0 + j as f32 * step);
                if x < 0.0 || y < 0.0 || x > ex as f32 || y > ey as f32 {
                    continue;
                }
                let (c, d) = (clearance(x, y), (i as f32).hypot(j as f32));
                if c > best.0 + 1e-3 || ((c - best.0).abs() <= 1e-3 && d < best.1) {
                    best = (c, d, x, y);
                }
            }
        }
        let (_, _, x, y) = best;
        let mut moved = Camera::ground_at(terrain, x, y, cam.target[1]);
        if terrain.height_at(x, y).is_none() {
            moved.eye[2] = cam.eye[2];
        }
        moved.near = cam.near;
        moved
    }
}

/// Hands the memory freed by a frame back to the operating system (glibc on Linux:
/// `malloc_trim`). A software adapter's rasteriser threads free the triangles they binned
/// (about 200 bytes each, 1.3 GB for a still of the default run's year 150) into their own
/// malloc arenas, which kept them resident between frames (issue 34). Elsewhere nothing.
fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free heap pages to the system; it takes no pointers
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Instances `trees` (with their chains' level counts) by the level a frame of `width` ×
/// `height` seen by `camera` with level parameters `lod` drew them at, from its stats `st`
/// ([`AdaptStats::per_level`]).
pub fn drawn_levels_of(trees: &[(TreeInstance, usize)], camera: &Camera, width: u32, height: u32, lod: &crate::render::lod::LodParams, st: &crate::render::renderer::FrameStats) -> [usize; crate::mesh::LOD_LEVELS] {
    use crate::render::lod::{canopy_weight, drawn_levels, select_lod_scaled, Frustum};
    // the reference height the frame used (lowered under a binding budget)
    let lod = &crate::render::lod::LodParams { small_tree_m: st.small_tree_m, ..*lod };
    let frustum = Frustum::from_view_proj(camera.view_proj(width.max(1) as f32 / height.max(1) as f32));
    let mut out = [0; crate::mesh::LOD_LEVELS];
    for (t, n) in trees {
        let (c, r) = crate::render::instanced::bounding_sphere(t);
        if !frustum.sphere_visible(c, r) {
            continue;
        }
        let px = camera.projected_size_px(c, t.height, height as f32);
        if canopy_weight(px, st.canopy_px, lod.band) >= 1.0 || !(px >= lod.min_px) {
            continue;
        }
        if let Some(mut p) = select_lod_scaled(crate::render::lod::lod_px(px, t.height, lod), st.lod_scale, lod, drawn_levels(*n)) {
            if lod.one_level_per_tree {
                p = crate::render::instanced::drawn_pick(p, crate::render::instanced::dither_salt(t.id), drawn_levels(*n));
            }
            out[p.level.min(crate::mesh::LOD_LEVELS - 1)] += 1;
        }
    }
    out
}

/// The stumps a picture of `year` of the run in `run_dir` draws: the trees removed by
/// management (`dead:harvest` with a DBH, [`scene::stumps_from_rows`]) in the plain snapshots
/// of the [`scene::STUMP_YEARS`] years up to `year`. A run writes a snapshot in every year its
/// management removed trees (`job::run::run_scenario`), so these are all of them; a run
/// directory written before that holds only the harvests of its scheduled snapshot years.
///
/// # Errors
/// As [`inventory::snapshots`] and [`inventory::read_filtered`] (naming the file).
pub fn harvest_stumps(run_dir: &Path, year: u32) -> Result<Vec<scene::Stump>> {
    harvest_stumps_where(run_dir, |y| scene::stump_shown(y, year))
}

/// The stumps of the trees removed by management in the plain snapshots of `run_dir` whose
/// year passes `keep_year`, as [`harvest_stumps`].
///
/// Errors: as [`harvest_stumps`].
pub fn harvest_stumps_where(run_dir: &Path, keep_year: impl Fn(u32) -> bool) -> Result<Vec<scene::Stump>> {
    let status = format!("dead:{}", crate::sim::trees::DeathCause::Harvest.name());
    // only the inventories of years that removed trees are read (a run without management:
    // none), when the stand table tells
    let cut = harvest_years(run_dir);
    let mut out = Vec::new();
    for (y, season, path) in inventory::snapshots(run_dir)? {
        if season.is_empty() && keep_year(y) && cut.as_ref().is_none_or(|c| c.contains(&y)) {
            let rows = inventory::read_filtered(&path, |r| r.status == status)?;
            out.extend(scene::stumps_from_rows(&rows, y));
        }
    }
    Ok(out)
}

/// The years whose management removed trees (`deaths_harvest` > 0) by the stand table of
/// `run_dir` (`stand_table.csv`); `None` when it cannot be read or has no such column (the
/// caller then reads every inventory).
pub fn harvest_years(run_dir: &Path) -> Option<Vec<u32>> {
    let mut rdr = csv::Reader::from_path(run_dir.join("stand_table.csv")).ok()?;
    let head = rdr.headers().ok()?.clone();
    let (ky, kh) = (head.iter().position(|c| c == "year")?, head.iter().position(|c| c == "deaths_harvest")?);
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.ok()?;
        let n: f64 = rec.get(kh)?.trim().parse().ok()?;
        if n > 0.0 {
            out.push(rec.get(ky)?.trim().parse().ok()?);
        }
    }
    Some(out)
}

/// Inventory snapshot of `year` (plain, not seasonal) in `run_dir`.
///
/// # Errors
/// [`Error::Format`] naming the run directory when no snapshot of that year exists.
pub fn snapshot_rows(run_dir: &Path, year: u32) -> Result<Vec<InventoryRow>> {
    snapshot_rows_where(run_dir, year, |_| true)
}

/// The rows of [`snapshot_rows`] for which `keep` is true ([`inventory::read_filtered`]: the
/// others are never held).
///
/// Errors: those of [`snapshot_rows`].
pub fn snapshot_rows_where(run_dir: &Path, year: u32, keep: impl FnMut(&InventoryRow) -> bool) -> Result<Vec<InventoryRow>> {
    let snaps = inventory::snapshots(run_dir)?;
    let path = snaps
        .iter()
        .find(|(y, s, _)| *y == year && s.is_empty())
        .map(|(_, _, p)| p.clone())
        .ok_or_else(|| Error::format(run_dir, no_inventory(run_dir, year, &snaps)))?;
    Ok(inventory::read_filtered(&path, keep)?)
}

/// Refuses a `year` without a tree inventory in `run_dir` (the error of [`snapshot_rows`],
/// without reading a row): a command checks it before it loads the site (`sylva render
/// --year 120` took 4 s to say so; round 31's trial).
///
/// Errors: [`Error::Format`] naming the run directory, the year and the years that have one.
pub fn check_snapshot_year(run_dir: &Path, year: u32) -> Result<()> {
    let snaps = inventory::snapshots(run_dir)?;
    if snaps.iter().any(|(y, s, _)| *y == year && s.is_empty()) {
        Ok(())
    } else {
        Err(Error::format(run_dir, no_inventory(run_dir, year, &snaps)).into())
    }
}

/// Why `year` has no tree inventory in `run_dir`, with the years that have one: a snapshot
/// year (its maps are there) of a run that writes inventories every `inventory_every` years is
/// said to be one. A picture or export of such a year is refused rather than drawn from
/// another year's trees under this year's name.
fn no_inventory(run_dir: &Path, year: u32, snaps: &[(u32, String, PathBuf)]) -> String {
    let mut ys: Vec<u32> = snaps.iter().filter(|s| s.1.is_empty()).map(|s| s.0).collect();
    ys.dedup();
    let list = ys.iter().map(|y| y.to_string()).collect::<Vec<_>>().join(", ");
    let maps = run_dir.join("maps").join(format!("species_year_{year:04}.png")).is_file();
    let every = crate::sim::Scenario::load(&run_dir.join("scenario.toml")).ok().and_then(|s| s.inventory_every);
    match (maps, every) {
        (true, Some(0)) => format!("year {year} is a snapshot (maps) without a tree inventory: this run writes inventories only for the first and last year (`inventory_every = 0` in scenario.toml), plus harvest years; years with an inventory: {list}"),
        (true, Some(n)) => format!("year {year} is a snapshot (maps) without a tree inventory: this run writes inventories every {n} years (`inventory_every` in scenario.toml), plus year 0, the last year and harvest years; years with an inventory: {list}"),
        (true, None) => format!("year {year} is a snapshot (maps) without a tree inventory; years with an inventory: {list}"),
        _ => format!("no inventory snapshot for year {year} (years with an inventory: {list})"),
    }
}

/// Removes the `frame_NNNNN.png` files Sylva wrote into `dir` (nothing else).
///
/// Errors: [`Error::Io`] naming the folder or file.
pub(crate) fn remove_frames(dir: &Path) -> Result<()> {
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let p = e.map_err(|e| Error::io(dir, e))?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let is_frame = name.len() == "frame_00000.png".len() && name.starts_with("frame_") && name.ends_with(".png") && name[6..11].bytes().all(|b| b.is_ascii_digit());
        if is_frame {
            std::fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
        }
    }
    Ok(())
}

/// Options of [`timelapse`].
#[derive(Debug, Clone)]
pub struct TimelapseOptions {
    /// Frame width (px).
    pub width: u32,
    /// Frame height (px).
    pub height: u32,
    /// Frames per second of the GIF/MP4.
    pub fps: f32,
    /// Interpolated frames between consecutive snapshots a regular interval apart (0–50; 0: one
    /// frame per snapshot); shorter and longer intervals get frames in proportion
    /// ([`frame_steps`]).
    pub frames_between: u32,
    /// Camera: a preset, or `None` for a slow orbit (a quarter turn over the film).
    pub camera: Option<CameraPreset>,
    /// Season drawn.
    pub season: Season,
}

/// Renders a timelapse of all plain snapshots of `run_dir` into `out_gif` (frames as PNG in
/// `frames_dir`, an MP4 beside the GIF when `ffmpeg` is on PATH), with the stumps of the trees
/// harvested in the 20 years up to each key frame's year ([`harvest_stumps`]). Growth between snapshots is
/// interpolated per tree id ([`timelapse::interpolate`]); every frame is captioned with its
/// (interpolated) year. Frames of an earlier film in `frames_dir` are removed first. Calls
/// `progress(done, total)` per frame.
/// Returns the number of frames and whether an MP4 was written.
pub fn timelapse(stage: &mut Stage, run_dir: &Path, frames_dir: &Path, out_gif: &Path, opts: &TimelapseOptions, progress: &mut dyn FnMut(usize, usize)) -> Result<(usize, bool)> {
    let snaps: Vec<(u32, PathBuf)> = inventory::snapshots(run_dir)?.into_iter().filter(|(_, s, _)| s.is_empty()).map(|(y, _, p)| (y, p)).collect();
    if snaps.is_empty() {
        return Err(Error::format(run_dir, "no inventory snapshots to make a timelapse from").into());
    }
    let years: Vec<u32> = snaps.iter().map(|s| s.0).collect();
    let season = opts.season;
    // every stump of the run, each key frame drawing those of its 20 years (they fade in and
    // out between key frames as trees do)
    let stumps = harvest_stumps_where(run_dir, |_| true)?;
    stage.set_stumps(&[], 0);
    timelapse_from(
        stage,
        &years,
        &mut |stage, k| {
            let regen = inventory::read_regeneration(run_dir, years[k])?.unwrap_or_default();
            let mut inst = scene::instances_with_saplings(&scene::plants_from_rows(&inventory::read(&snaps[k].1)?), &scene::saplings_from_rows(&regen), &stage.library, &stage.site, season);
            inst.extend(stage.stump_instances_of(&stumps, years[k]));
            Ok(inst)
        },
        frames_dir,
        out_gif,
        opts,
        progress,
    )
}

/// Most frames one gap between key frames gets in [`frame_steps`], in multiples of a regular
/// gap's (`frames_between + 1`): a long gap (a run's first and last year alone) does not make
/// an endless film.
pub const MAX_GAP_STEPS: u32 = 10;

/// The frames of a film's gaps between consecutive key-frame years `years` (ascending): gap `j`
/// (`years[j]` to `years[j + 1]`) gets `(frames_between + 1) · gap / regular` frames, rounded,
/// at least 1 and at most [`MAX_GAP_STEPS`] times `frames_between + 1`, the last of them the
/// key frame; `regular` is the most frequent gap (the largest of equally frequent ones): the
/// snapshot interval of a run whose key frames follow `snapshot_every`. So film time follows
/// the years (round 41, trial 40: the thinning snapshot of year 55 between those of 50 and 60
/// got as much film as a decade); where every gap is the same, as in a run without management,
/// each gets `frames_between + 1`, as before.
pub fn frame_steps(years: &[u32], frames_between: u32) -> Vec<usize> {
    let gaps: Vec<u32> = years.windows(2).map(|w| w[1].saturating_sub(w[0]).max(1)).collect();
    let mut counts: std::collections::BTreeMap<u32, usize> = std::collections::BTreeMap::new();
    for &g in &gaps {
        *counts.entry(g).or_insert(0) += 1;
    }
    // the most frequent gap, ties to the larger (BTreeMap order: the last of the maxima)
    let regular = counts.iter().fold((1u32, 0usize), |best, (&g, &n)| if n >= best.1 { (g, n) } else { best }).0;
    let per = frames_between as f64 + 1.0;
    gaps.iter().map(|&g| (per * g as f64 / regular as f64).round().clamp(1.0, per * MAX_GAP_STEPS as f64) as usize).collect()
}

/// [`timelapse`] from key frames given by `key(stage, k)`: the render instances (in
/// `opts.season`) of the snapshot of `years[k]`, asked for once each, in order, e.g. from
/// instances the main job kept from the in-memory world at each snapshot.
///
/// Errors: as [`timelapse`]; [`Error::Invalid`] when `years` is empty.
pub fn timelapse_from(stage: &mut Stage, years: &[u32], key: &mut dyn FnMut(&Stage, usize) -> Result<Vec<TreeInstance>>, frames_dir: &Path, out_gif: &Path, opts: &TimelapseOptions, progress: &mut dyn FnMut(usize, usize)) -> Result<(usize, bool)> {
    let mut times = FilmTimes::default();
    timelapse_timed(stage, years, key, frames_dir, out_gif, opts, false, &mut times, progress)
}

/// Where a film's time went ([`timelapse_timed`]): wall and process CPU seconds
/// ([`crate::job::timing::process_cpu_s`]; 0 where the platform gives none).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FilmTimes {
    /// Frames drawn (instances interpolated, rendered, captioned) and written as PNG: wall, CPU (s).
    pub frames: (f64, f64),
    /// Frames read back from an earlier, stopped run ([`timelapse_timed`]'s `reuse`).
    pub reused: usize,
    /// The GIF's encoding (quantising each frame, writing it) and the MP4's (ffmpeg, a child
    /// process: its CPU is not the process's): wall, CPU (s).
    pub encoding: (f64, f64),
}

/// [`timelapse_from`], adding where its time went to `times`. With `reuse`, frames
/// `frames_dir/frame_NNNNN.png` of an earlier run of the same film (a `sylva run` stopped
/// while drawing it; trial 46 D10) are read back instead of drawn, when they decode at the
/// film's size, and the folder's frames are not removed first.
///
/// Errors: as [`timelapse_from`].
#[allow(clippy::too_many_arguments)]
pub fn timelapse_timed(stage: &mut Stage, years: &[u32], key: &mut dyn FnMut(&Stage, usize) -> Result<Vec<TreeInstance>>, frames_dir: &Path, out_gif: &Path, opts: &TimelapseOptions, reuse: bool, times: &mut FilmTimes, progress: &mut dyn FnMut(usize, usize)) -> Result<(usize, bool)> {
    if years.is_empty() {
        return Err(Error::Invalid { context: "timelapse".into(), field: "snapshots".into(), value: "none".into(), expected: "at least one snapshot year".into() }.into());
    }
    let snaps = years;
    std::fs::create_dir_all(frames_dir).map_err(|e| Error::io(frames_dir, e))?;
    // frames of an earlier, longer film would otherwise remain beside the new ones (a film
    // finished after a stop has the same frames: they are read back)
    if !reuse {
        remove_frames(frames_dir)?;
    }
    let steps_of = frame_steps(snaps, opts.frames_between);
    // a film frame's triangles in proportion to its pixels (the stage's budget is restored below)
    let budget = stage.renderer.lod.max_triangles;
    stage.set_triangle_budget(frame_triangle_budget(opts.width, opts.height).min(if budget > 0 { budget } else { u32::MAX }));
    let film = film_frames(stage, snaps, &steps_of, key, frames_dir, out_gif, opts, reuse, times, progress);
    stage.set_triangle_budget(budget);
    film
}

/// The frames of [`timelapse_from`], drawn at the stage's triangle budget.
#[allow(clippy::too_many_arguments)]
fn film_frames(stage: &mut Stage, snaps: &[u32], steps_of: &[usize], key: &mut dyn FnMut(&Stage, usize) -> Result<Vec<TreeInstance>>, frames_dir: &Path, out_gif: &Path, opts: &TimelapseOptions, reuse: bool, times: &mut FilmTimes, progress: &mut dyn FnMut(usize, usize)) -> Result<(usize, bool)> {
    use crate::job::timing::Clock;
    let total = 1 + steps_of.iter().sum::<usize>();
    // the GIF is encoded as the frames come (issue 34: not every frame held to the end)
    let mut gif = crate::output::pictures::GifWriter::new(out_gif, opts.fps)?;
    let mut frames = 0usize;
    let mut prev = key(stage, 0)?;
    let mut k = 0usize;
    let mut emit = |stage: &mut Stage, inst: &dyn Fn() -> Vec<TreeInstance>, k: usize, year: f32| -> Result<image::RgbaImage> {
        let clock = Clock::start();
        let path = frames_dir.join(format!("frame_{k:05}.png"));
        // a frame an earlier, stopped run wrote whole (PNGs are written atomically)
        if reuse {
            if let Ok(img) = image::open(&path) {
                if img.width() == opts.width && img.height() == opts.height {
                    times.reused += 1;
                    return Ok(img.to_rgba8());
                }
            }
        }
        let u = if total > 1 { k as f32 / (total - 1) as f32 } else { 0.0 };
        let cam = match opts.camera {
            Some(p) => stage.camera_sized(p, opts.width, opts.height),
            None => Camera::orbit(&stage.scene.terrain, 0.05 + 0.25 * u),
        };
        let mut img = stage.render_instances(inst(), opts.season, &cam, opts.width, opts.height)?;
        crate::output::maps::stamp_caption(&mut img, &format!("year {}", year.round() as u32))?;
        // a north arrow, but on the map's film (north up)
        if opts.camera != Some(CameraPreset::Map) {
            crate::render::overlay::stamp_north_arrow(&mut img, &cam);
        }
        crate::output::pictures::write_png(&path, &img)?;
        clock.add_to(&mut times.frames);
        Ok(img)
    };
    let encode = |gif: &mut crate::output::pictures::GifWriter, img: image::RgbaImage, times_enc: &mut (f64, f64)| -> Result<()> {
        let clock = Clock::start();
        gif.add(img)?;
        clock.add_to(times_enc);
        Ok(())
    };
    let mut enc = (0.0, 0.0);
    let first = emit(stage, &|| prev.clone(), k, snaps[0] as f32)?;
    encode(&mut gif, first, &mut enc)?;
    frames += 1;
    progress(1, total);
    for (j, w) in snaps.windows(2).enumerate() {
        let (y0, y1) = (&w[0], &w[1]);
        let next = key(stage, j + 1)?;
        let steps = steps_of[j];
        for s in 1..=steps {
            k += 1;
            let t = s as f32 / steps as f32;
            let img = emit(stage, &|| timelapse::interpolate(&prev, &next, t), k, *y0 as f32 + t * (*y1 as f32 - *y0 as f32))?;
            encode(&mut gif, img, &mut enc)?;
            frames += 1;
            progress(k + 1, total);
        }
        prev = next;
    }
    let clock = Clock::start();
    gif.finish()?;
    let mp4 = out_gif.with_extension("mp4");
    let wrote_mp4 = crate::output::pictures::write_mp4(frames_dir, opts.fps, &mp4).unwrap_or(false);
    clock.add_to(&mut enc);
    times.encoding.0 += enc.0;
    times.encoding.1 += enc.1;
    Ok((frames, wrote_mp4))
}

#[cfg(test)]
mod tests {
    use super::frame_steps;

    /// Round 41 (trial 40, item 5): film time follows the years between key frames.
    #[test]
    fn a_film_frames_triangles_follow_its_pixels() {
        use super::{frame_triangle_budget, STILL_TRIANGLE_BUDGET};
        assert_eq!(frame_triangle_budget(1280, 720), STILL_TRIANGLE_BUDGET);
        assert_eq!(frame_triangle_budget(640, 360), 7_500_000);
        assert_eq!(frame_triangle_budget(320, 180), 1_875_000);
        // never above the stills' budget, never below a million
        assert_eq!(frame_triangle_budget(3840, 2160), STILL_TRIANGLE_BUDGET);
        assert_eq!(frame_triangle_budget(64, 64), 1_000_000);
    }

    #[test]
    fn film_time_follows_the_years_between_key_frames() {
        // key frames every 10 years and a thinning snapshot at 55: half a decade's film each
        let y = [0, 10, 20, 30, 40, 50, 55, 60];
        assert_eq!(frame_steps(&y, 1), vec![2, 2, 2, 2, 2, 1, 1]);
        assert_eq!(frame_steps(&y, 3), vec![4, 4, 4, 4, 4, 2, 2]);
        // the default run's key frames every 5 years: every gap as before
        let d: Vec<u32> = (0..=150).step_by(5).collect();
        assert!(frame_steps(&d, 1).iter().all(|&s| s == 2));
        // a longer gap gets more frames, at most MAX_GAP_STEPS regular gaps' worth
        assert_eq!(frame_steps(&[0, 10, 20, 40], 1), vec![2, 2, 4]);
        assert_eq!(frame_steps(&[0, 1, 2, 1000], 0), vec![1, 1, 10]);
        // equally frequent gaps: the larger is the regular one
        assert_eq!(frame_steps(&[0, 50, 55], 1), vec![2, 1]);
        assert!(frame_steps(&[7], 1).is_empty());
    }
}
