//! `sylva view RUN_DIR`: the interactive viewer of a run directory (issue 15).
//!
//! The landscape is drawn by the same renderer as the stills ([`crate::render`], through
//! [`crate::gui::Viewport3d`]); orbit, pan, zoom and fly cameras ([`camera`]); a year slider with
//! play/pause, the trees interpolated between snapshots as the timelapse is ([`data`]);
//! overlays of every condition map and of the species and basal-area maps on the terrain; a
//! click on a tree shows its species, age, height, DBH, crown and fate; the stand table is
//! plotted beside the view (egui_plot); the help panel (F1 or H) lists the shortcuts; the frame
//! time is shown in the top bar.
//!
//! The ground is the stills' ([`scene::Landscape`]): the terrain beyond the simulated window
//! (from the scenario's DEM, [`Viewer::set_surroundings`]) with the window's trees mirrored onto
//! it, fading into the sky and the haze as in `sylva render`. Every tree of a year (a million
//! in the default run, several million with the surroundings) is baked once into a
//! [`FarField`]; a frame culls only the trees that may show as geometry, at most
//! [`MOTION_NEAR_TREES`] while the camera moves.
//!
//! A shell module: the core names none of it (`tests/layers.rs`).

pub mod camera;
pub mod data;
pub mod near;


use std::sync::Arc;

use eframe::egui;
use glam::Vec3;

use crate::gui::{self, FrameClock, GuiError, Screenshot, Viewport3d, WindowOptions};
use crate::job::scene;
use crate::render::farfield::FarField;
use crate::render::scene::{Scene, TreeInstance};
use crate::species::Season;
use camera::{CameraRig, Mode};
use data::{Overlay, RunData, TreeInfo};

/// Keyboard shortcuts of the viewer, as the help panel lists them.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Space", "play / pause the years"),
    ("Left / Right arrow", "previous / next snapshot"),
    ("Home / End", "first / last snapshot"),
    ("drag (left)", "orbit (orbit camera) or look around (fly camera)"),
    ("drag (right or middle)", "pan"),
    ("wheel", "zoom (orbit) or move forward (fly)"),
    ("click", "select the tree under the pointer"),
    ("W A S D", "move forward, left, back, right (Shift: faster)"),
    ("Q / E", "move down / up"),
    ("O / F", "orbit / fly camera"),
    ("R", "reset the view"),
    ("V", "next overlay"),
    ("Esc", "clear the selection"),
    ("F1 or H", "show / hide this help"),
];

/// Stand-table columns offered for the plot (when present in the run's table).
const PLOT_COLUMNS: &[(&str, &str)] = &[
    ("basal_area_m2_ha", "basal area (m²/ha)"),
    ("stems_ha", "stems (/ha)"),
    ("mean_height_m", "mean height (m)"),
    ("top_height_m", "top height (m)"),
    ("qmd_cm", "quadratic mean DBH (cm)"),
    ("regeneration_ha", "regeneration (stems/ha)"),
];

/// The viewer: run data, scene, camera, time and selection. [`Viewer::ui`] lays out the whole
/// window; without a GPU viewport (tests) the 3-D view is left blank but still takes clicks.
pub struct Viewer {
    /// The run shown.
    pub data: RunData,
    scene: Scene,
    base_colours: Vec<[f32; 3]>,
    gpu: Option<Viewport3d>,
    /// Camera.
    pub rig: CameraRig,
    /// The year shown (between the first and last snapshot).
    pub year: f32,
    /// Whether the years play.
    pub playing: bool,
    /// Years per second while playing.
    pub speed: f32,
    /// Season drawn.
    pub season: Season,
    /// Overlay painted on the terrain.
    pub overlay: Overlay,
    painted: Option<(Overlay, i64)>,
    shown: Option<(i64, Season)>,
    /// The ground drawn: the site and its surroundings, as in the stills.
    landscape: scene::Landscape,
    /// The year (× 1000) and season the ground colours and the far field were made for.
    baked: Option<(i64, Season)>,
    current: Vec<TreeInstance>,
    /// The selected tree's id.
    pub selected: Option<u64>,
    /// What is known of the selected tree.
    pub info: Option<TreeInfo>,
    /// Whether the help panel is open.
    pub show_help: bool,
    plot_column: String,
    clock: FrameClock,
    screenshot: Option<Screenshot>,
    /// Last error shown in the status line.
    pub status: Option<String>,
    view_rect: egui::Rect,
    pixels_per_point: f32,
    /// The camera of the last frame drawn ([`Viewer::in_motion`]).
    last_camera: Option<crate::render::camera::Camera>,
    /// When the viewer was made, and the frames drawn since (the first three are logged: a frame
    /// has been shown when the next one starts).
    opened: std::time::Instant,
    frames_drawn: u64,
    /// The texture of the last 3-D frame drawn, shown again (not redrawn) while a requested
    /// screenshot is on its way.
    last_frame: Option<egui::TextureId>,
    /// `SYLVA_VIEW_SPIN` is set: turn the camera every frame and log the frame times.
    spin: bool,
    spin_clock: std::time::Instant,
    /// Divisor of the resolution of frames in motion (1 ..= [`MOTION_SCALE_MAX`]), adapted to
    /// the time between them.
    motion_scale: f32,
    /// Whether the last frame was drawn in motion.
    motion_before: bool,
    /// Seconds between the last two frames.
    frame_dt: f32,
    /// Whether the year shown changed in the last [`Viewer::refresh`] (drawn as in motion).
    year_moving: bool,
    /// The adapted near field ([`near`]): its worker (started on the first request), the
    /// scenario's seed and obstacles it adapts with, the trees shown with their own meshes
    /// (prototypes `n_base..` of the scene), the request under way and what was last asked.
    near: Option<near::NearField>,
    near_on: bool,
    near_scenario: (u64, Vec<crate::sim::obstacle::ObstacleSpec>),
    near_shown: Vec<ShownTree>,
    n_base: usize,
    near_pending: Option<(u64, std::time::Instant)>,
    near_key: Option<(u32, crate::render::camera::Camera, u32, u32)>,
    /// The replaced instances must be made again (the trees or the season changed).
    near_dirty: bool,
    /// Log what the next still frame draws of the near field.
    near_report: bool,
    /// What the last 3-D frame drawn showed (camera, size, year, season, overlay, ground):
    /// while the near field is on its way an unchanged frame is not drawn again.
    frame_sig: Option<FrameSig>,
}

/// A tree of the near field shown with its own adapted meshes.
#[derive(Debug, Clone, Copy)]
struct ShownTree {
    id: u64,
    year: u32,
    tree: crate::structure::stand::StandTree,
    height: f32,
    r0: f32,
    nodes: usize,
    leaf_cards: usize,
    sprig_cards: usize,
}

type FrameSig = (crate::render::camera::Camera, u32, u32, Option<(i64, Season)>, Overlay, Option<(i64, Season)>, usize);

impl Viewer {
    /// The viewer of `data`, drawing the sea at `sea_level_m` where cells are water, with a GPU
    /// viewport when given.
    ///
    /// # Errors
    /// [`GuiError::Render`] when the terrain mesh cannot be built.
    pub fn new(data: RunData, sea_level_m: f32, gpu: Option<Viewport3d>) -> gui::Result<Self> {
        let landscape = scene::Landscape::new(&data.site, None, 10.0, sea_level_m).map_err(input_error)?;
        let terrain = landscape.mesh(&[]).map_err(input_error)?;
        let mut prototypes = pool_prototypes(&data.library, &data.pool);
        // the stumps of harvested trees after the species (Viewer::refresh)
        prototypes.extend(scene::stump_prototypes());
        let site = &data.site;
        let has_water = site.mask.data.iter().zip(&site.elevation_m.data).any(|(m, z)| !*m && z.is_finite() && *z <= sea_level_m);
        let n_base = prototypes.len();
        let scene = scene::scene(terrain, prototypes, Vec::new(), site.geo.latitude_deg, Season::Summer, has_water.then_some(sea_level_m));
        let (lo, hi) = scene.terrain.bounds();
        let rig = CameraRig::framing(lo, hi);
        let base_colours = scene.terrain.colors.clone();
        let mut gpu = gpu;
        if let Some(g) = gpu.as_mut() {
            g.renderer.lod = still_lod();
        }
        let year = data.span().1 as f32;
        let plot_column = PLOT_COLUMNS.iter().map(|c| c.0).find(|c| data.stand_table.columns.iter().any(|x| x == c)).unwrap_or("basal_area_m2_ha").to_string();
        Ok(Viewer {
            data,
            scene,
            base_colours,
            gpu,
            rig,
            year,
            playing: false,
            speed: 10.0,
            season: Season::Summer,
            overlay: Overlay::None,
            painted: None,
            shown: None,
            landscape,
            baked: None,
            current: Vec::new(),
            selected: None,
            info: None,
            show_help: false,
            plot_column,
            clock: FrameClock::default(),
            screenshot: None,
            status: None,
            view_rect: egui::Rect::NOTHING,
            pixels_per_point: 1.0,
            last_camera: None,
            opened: std::time::Instant::now(),
            frames_drawn: 0,
            last_frame: None,
            spin: std::env::var_os("SYLVA_VIEW_SPIN").is_some(),
            spin_clock: std::time::Instant::now(),
            motion_scale: 2.0,
            motion_before: false,
            frame_dt: 0.0,
            year_moving: false,
            near: None,
            near_on: true,
            near_scenario: (0, Vec::new()),
            near_shown: Vec::new(),
            n_base,
            near_pending: None,
            near_key: None,
            near_dirty: false,
            near_report: false,
            frame_sig: None,
        })
    }

    /// Draws the terrain beyond the simulated window around it, as the stills do
    /// (`job::pictures::Stage::set_surroundings`): `full` is the whole terrain the site was cut
    /// from with `window` (`[col0, row0, width, height]` in its cells).
    ///
    /// # Errors
    /// [`GuiError::Render`] when the window leaves `full`'s grid.
    pub fn set_surroundings(&mut self, full: &crate::terrain::Terrain, window: [usize; 4]) -> gui::Result<()> {
        self.landscape = scene::Landscape::new(&self.data.site, Some((full, window)), 10.0, self.landscape.cover.sea_level).map_err(input_error)?;
        self.scene.set_terrain(self.landscape.mesh(&[]).map_err(input_error)?);
        self.base_colours = self.scene.terrain.colors.clone();
        self.painted = None;
        self.baked = None;
        Ok(())
    }

    /// Takes a `--screenshot` after the given frames.
    pub fn with_screenshot(mut self, s: Screenshot) -> Self {
        self.screenshot = Some(s);
        self
    }

    /// The scenario's seed and obstacles, with which the near field's trees are grown and
    /// adapted ([`near`]; by default seed 0 and no obstacles).
    pub fn set_scenario(&mut self, seed: u64, obstacles: Vec<crate::sim::obstacle::ObstacleSpec>) {
        self.near = None;
        self.near_scenario = (seed, obstacles);
        self.clear_near();
    }

    /// Whether the trees near a resting camera get their adapted full-detail meshes ([`near`];
    /// default on): off, every tree is drawn with its species' model.
    pub fn set_adapt(&mut self, on: bool) {
        self.near_on = on;
        if !on {
            self.clear_near();
            self.near = None;
        }
    }

    /// Looks as `cam` does (its eye, target and vertical field of view when perspective) with
    /// the fly camera.
    pub fn look(&mut self, cam: &crate::render::camera::Camera) {
        let (lo, hi) = self.scene.terrain.bounds();
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        self.rig = CameraRig::looking(Vec3::from(cam.eye), Vec3::from(cam.target), size);
        if let crate::render::camera::Projection::Perspective { fov_y_deg } = cam.projection {
            self.rig.fov_y_deg = fov_y_deg;
        }
        self.rig.set_mode(Mode::Fly);
    }

    /// The camera of a still's preset on this run ([`crate::render::camera::Camera::preset_sized`]
    /// for a view of `width` × `height` px; the ground preset stepped into the nearest clearing
    /// of the last snapshot, as the stills do, [`crate::job::pictures::step_into_clearing`]).
    ///
    /// # Errors
    /// As [`RunData::rows`].
    pub fn preset_camera(&mut self, preset: crate::render::camera::CameraPreset, width: u32, height: u32) -> crate::Result<crate::render::camera::Camera> {
        let cam = crate::render::camera::Camera::preset_sized(preset, &self.scene.terrain, width, height);
        if preset != crate::render::camera::CameraPreset::Ground {
            return Ok(cam);
        }
        let k = self.data.years.len() - 1;
        let site = self.data.site.clone();
        let rows = self.data.rows(k)?;
        Ok(crate::job::pictures::step_into_clearing(cam, &site, &self.scene.terrain, &scene::plants_from_rows(rows)))
    }

    /// Trees shown with their own adapted meshes ([`near`]) and the median of their skeleton
    /// nodes (0 when none).
    pub fn adapted_shown(&self) -> (usize, usize) {
        let mut n: Vec<usize> = self.near_shown.iter().map(|t| t.nodes).collect();
        (n.len(), crate::job::adapted::median_usize(&mut n))
    }

    /// Whether adapted meshes of the near field are on their way.
    pub fn near_pending(&self) -> bool {
        self.near_pending.is_some()
    }

    /// The trees drawn now (interpolated at [`Viewer::year`]).
    pub fn trees(&self) -> &[TreeInstance] {
        &self.current
    }

    /// The overlays in menu order with their names.
    pub fn overlays(&self) -> Vec<(Overlay, String)> {
        let mut v = vec![(Overlay::None, "land cover".to_string())];
        v.extend(self.data.layers.iter().enumerate().map(|(k, l)| (Overlay::Condition(k), format!("{} ({})", l.title, l.units))));
        v.push((Overlay::Species, "species (dominant by basal area)".into()));
        v.push((Overlay::BasalArea, "basal area (m²/ha)".into()));
        v
    }

    /// Brings the scene up to date with the year, season and overlay.
    pub fn refresh(&mut self) {
        let key = ((self.year * 1000.0).round() as i64, self.season);
        // the year moved since the last frame (the slider dragged, the years playing)
        self.year_moving = self.shown.is_some() && self.shown != Some(key);
        if self.shown != Some(key) {
            match self.data.instances_at(self.year, self.season) {
                Ok(v) => self.current = v,
                Err(e) => self.status = Some(e.to_string()),
            }
            // the stumps of the trees harvested in the 20 years up to the year shown (drawn
            // near and far as the trees are; not on the ground's colouring nor mirrored)
            match self.data.stumps_at(self.year) {
                Ok(s) => self.current.extend(scene::stump_instances(&s, self.year.max(0.0).floor() as u32, &self.data.site, self.data.library.species.len() as u32)),
                Err(e) => self.status = Some(e.to_string()),
            }
            self.scene.sun = scene::season_sun(self.data.site.geo.latitude_deg, self.season);
            self.shown = Some(key);
            self.near_dirty = true;
            if let Some(id) = self.selected {
                self.info = self.data.tree_info(id, self.year).ok().flatten();
            }
        }
        // the ground and the far field: for the year shown, or while the year moves (the years
        // play, the slider is dragged) for the snapshot nearest to it (baking millions of trees
        // takes longer than a frame); the frame after it stops bakes the year shown
        let (k0, k1, t) = self.data.bracket(self.year);
        let bake_key = if self.playing || self.year_moving { ((self.data.years[if t >= 0.5 { k1 } else { k0 }] as f32 * 1000.0).round() as i64, self.season) } else { key };
        if self.baked != Some(bake_key) {
            self.bake(bake_key);
        }
        // species and basal-area overlays change with the snapshot shown, condition maps never
        let snap = match self.overlay {
            Overlay::Species | Overlay::BasalArea => self.data.years[if t >= 0.5 { k1 } else { k0 }] as i64,
            _ => -1,
        };
        if self.painted != Some((self.overlay, snap)) {
            let colours = match self.data.overlay_field(self.overlay, self.year) {
                Ok(Some((g, cell, ramp, range))) => data::overlay_colours(&self.scene.terrain.positions, &self.base_colours, &g, cell, self.data.site.extent_m().1, ramp, range, self.overlay == Overlay::Species),
                Ok(None) => self.base_colours.clone(),
                Err(e) => {
                    self.status = Some(e.to_string());
                    self.base_colours.clone()
                }
            };
            self.scene.terrain.colors = colours;
            self.scene.terrain_changed();
            self.painted = Some((self.overlay, snap));
        }
    }

    /// Makes the ground and the far field for `key` (year × 1000, season): the trees of that
    /// year with their mirror images on the surroundings ([`scene::Landscape::surroundings`]),
    /// the ground under their crowns coloured as forest floor ([`scene::Landscape::mesh`]), and
    /// with a GPU viewport all of them baked into the renderer's [`FarField`].
    fn bake(&mut self, key: (i64, Season)) {
        let trees = if key.0 == (self.year * 1000.0).round() as i64 && Some(key) == self.shown {
            Ok(self.current.clone())
        } else {
            self.data.instances_at(key.0 as f32 / 1000.0, key.1)
        };
        let mut all = match trees {
            Ok(v) => v,
            Err(e) => {
                self.status = Some(e.to_string());
                return;
            }
        };
        // the stumps go into the far field (which the renderer draws instead of the scene's
        // instances) but neither into the ground's colouring nor into the mirrored surroundings
        let stumps: Vec<TreeInstance> = all.iter().filter(|t| scene::is_stump(t)).copied().collect();
        all.retain(|t| !scene::is_stump(t));
        let t0 = std::time::Instant::now();
        let far = self.landscape.surroundings(&all);
        all.extend(far);
        match self.landscape.mesh(&all) {
            Ok(m) => {
                self.scene.set_terrain(m);
                self.base_colours = self.scene.terrain.colors.clone();
                self.painted = None;
            }
            Err(e) => self.status = Some(e.to_string()),
        }
        let t1 = std::time::Instant::now();
        let n = all.len();
        all.extend(stumps);
        if let Some(g) = self.gpu.as_mut() {
            g.renderer.far_field = Some(Arc::new(FarField::new(all, &self.scene.prototypes, &self.scene.terrain)));
        }
        tracing::info!("year {:.1}: {n} trees with the surroundings' (ground {:.2} s), far field baked in {:.2} s", key.0 as f32 / 1000.0, (t1 - t0).as_secs_f32(), t1.elapsed().as_secs_f32());
        self.baked = Some(key);
    }

    /// Moves to year `y` (clamped to the snapshots).
    pub fn set_year(&mut self, y: f32) {
        let (a, b) = self.data.span();
        self.year = y.clamp(a as f32, b as f32);
    }

    fn step_snapshot(&mut self, dir: i32) {
        let ys = &self.data.years;
        let y = self.year;
        let next = if dir > 0 { ys.iter().map(|&v| v as f32).find(|&v| v > y + 1e-3) } else { ys.iter().rev().map(|&v| v as f32).find(|&v| v < y - 1e-3) };
        if let Some(v) = next {
            self.year = v;
        }
    }

    /// Selects the tree under viewport pixel `(px, py)` (points from the viewport's top left);
    /// returns its id.
    pub fn pick_at(&mut self, px: f32, py: f32) -> Option<u64> {
        let (w, h) = (self.view_rect.width(), self.view_rect.height());
        let (o, d) = self.rig.ray(px, py, w, h);
        // trees faded out to nothing (dead between the snapshots shown) are not hit
        let seen: Vec<&TreeInstance> = self.current.iter().filter(|t| t.opacity > 0.05 && !scene::is_stump(t)).collect();
        let trees: Vec<(Vec3, f32, f32)> = seen.iter().map(|t| (Vec3::from(t.position), t.height, t.crown_radius)).collect();
        let hit = camera::pick(o, d, &trees).map(|i| seen[i].id);
        self.selected = hit;
        self.info = match hit {
            Some(id) => self.data.tree_info(id, self.year).ok().flatten(),
            None => None,
        };
        hit
    }

    /// Where a tree's crown centre is on screen (egui points), when it is in front of the camera;
    /// for tests and tooltips.
    pub fn screen_pos_of(&self, id: u64) -> Option<egui::Pos2> {
        let t = self.current.iter().find(|t| t.id == id)?;
        let r = self.view_rect;
        let p = Vec3::from(t.position) + Vec3::Z * 0.6 * t.height;
        let clip = self.rig.camera().view_proj(r.width().max(1.0) / r.height().max(1.0)) * p.extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(egui::pos2(r.left() + (ndc.x + 1.0) * 0.5 * r.width(), r.top() + (1.0 - ndc.y) * 0.5 * r.height()))
    }

    fn keys(&mut self, ctx: &egui::Context, dt: f32) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        use egui::Key;
        let (mut fwd, mut right, mut up) = (0.0f32, 0.0f32, 0.0f32);
        let mut fast = false;
        ctx.input(|i| {
            if i.key_pressed(Key::Space) {
                self.playing = !self.playing;
            }
            if i.key_pressed(Key::F1) || i.key_pressed(Key::H) {
                self.show_help = !self.show_help;
            }
            if i.key_pressed(Key::O) {
                self.rig.set_mode(Mode::Orbit);
            }
            if i.key_pressed(Key::F) {
                self.rig.set_mode(Mode::Fly);
            }
            if i.key_pressed(Key::Escape) {
                self.selected = None;
                self.info = None;
            }
            let held = |k| if i.key_down(k) { 1.0 } else { 0.0 };
            fwd = held(Key::W) - held(Key::S);
            right = held(Key::D) - held(Key::A);
            up = held(Key::E) - held(Key::Q);
            fast = i.modifiers.shift;
        });
        let pressed = |k| ctx.input(|i| i.key_pressed(k));
        if pressed(Key::ArrowRight) {
            self.step_snapshot(1);
        }
        if pressed(Key::ArrowLeft) {
            self.step_snapshot(-1);
        }
        if pressed(Key::Home) {
            self.year = self.data.span().0 as f32;
        }
        if pressed(Key::End) {
            self.year = self.data.span().1 as f32;
        }
        if pressed(Key::R) {
            let (lo, hi) = self.scene.terrain.bounds();
            let mode = self.rig.mode;
            self.rig = CameraRig::framing(lo, hi);
            self.rig.set_mode(mode);
        }
        if pressed(Key::V) {
            let all = self.overlays();
            let k = all.iter().position(|o| o.0 == self.overlay).unwrap_or(0);
            self.overlay = all[(k + 1) % all.len()].0;
        }
        if fwd != 0.0 || right != 0.0 || up != 0.0 {
            self.rig.fly(fwd, right, up, dt.min(0.1), fast);
            ctx.request_repaint();
        }
    }

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            let (a, b) = self.data.span();
            if ui.button(if self.playing { "Pause" } else { "Play" }).on_hover_text("Space").clicked() {
                self.playing = !self.playing;
            }
            let mut y = self.year;
            let slider = egui::Slider::new(&mut y, a as f32..=b as f32).text("Year").fixed_decimals(1).step_by(0.0);
            if ui.add_sized([320.0, 18.0], slider).changed() {
                self.year = y;
                self.playing = false;
            }
            ui.add(egui::DragValue::new(&mut self.speed).range(0.5..=100.0).suffix(" yr/s").speed(0.2));
            ui.separator();
            egui::ComboBox::from_label("Season").selected_text(format!("{:?}", self.season)).show_ui(ui, |ui| {
                for s in [Season::Spring, Season::Summer, Season::Autumn, Season::Winter] {
                    ui.selectable_value(&mut self.season, s, format!("{s:?}"));
                }
            });
            let overlays = self.overlays();
            let name = overlays.iter().find(|o| o.0 == self.overlay).map(|o| o.1.clone()).unwrap_or_default();
            egui::ComboBox::from_label("Overlay").width(220.0).selected_text(name).show_ui(ui, |ui| {
                for (o, n) in &overlays {
                    ui.selectable_value(&mut self.overlay, *o, n);
                }
            });
            ui.separator();
            let mut mode = self.rig.mode;
            ui.radio_value(&mut mode, Mode::Orbit, "Orbit").on_hover_text("O");
            ui.radio_value(&mut mode, Mode::Fly, "Fly").on_hover_text("F");
            if mode != self.rig.mode {
                self.rig.set_mode(mode);
            }
            if ui.button("Help").on_hover_text("F1").clicked() {
                self.show_help = !self.show_help;
            }
            ui.separator();
            let gpu_ms = self.gpu.as_ref().map_or(0.0, |g| g.last_ms);
            let st = self.gpu.as_ref().map(|g| g.renderer.last_stats());
            ui.label(format!("frame {:.1} ms (3-D {:.1} ms){}", self.clock.frame_ms, gpu_ms, st.map_or(String::new(), |s| format!(", {} trees drawn, {} k triangles", s.instances_drawn, s.triangles / 1000))));
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading(format!("Year {:.1}", self.year));
        let alive = self.current.iter().filter(|t| t.opacity > 0.5 && !scene::is_stump(t)).count();
        ui.label(format!("{} trees in the scene (live, at least 1 m tall, not hidden under taller crowns), from the snapshots of {}", alive, {
            let (k0, k1, _) = self.data.bracket(self.year);
            if k0 == k1 { format!("year {}", self.data.years[k0]) } else { format!("years {}–{}", self.data.years[k0], self.data.years[k1]) }
        }));
        ui.separator();
        ui.strong("Selected tree");
        match &self.info {
            Some(info) => {
                let r = &info.row;
                let name = self.data.library.get(&r.species).map(|s| format!("{} ({})", s.identity.common_name, s.identity.scientific_name)).unwrap_or_else(|| r.species.clone());
                egui::Grid::new("tree").num_columns(2).show(ui, |ui| {
                    let mut row = |k: &str, v: String| {
                        ui.label(k);
                        ui.label(v);
                        ui.end_row();
                    };
                    row("id", r.id.to_string());
                    row("species", name);
                    row("age", format!("{:.0} years", r.age_yr));
                    row("height", format!("{:.1} m", r.height_m));
                    row("DBH", format!("{:.1} cm", r.dbh_cm));
                    row("crown radius", format!("{:.1} m", r.crown_radius_m));
                    row("crown base", format!("{:.1} m", r.crown_base_m));
                    row("position", format!("{:.0} m E, {:.0} m N", r.x_m, r.y_m));
                    row("status", info.fate.clone());
                    row("from snapshot", format!("year {}", info.year));
                });
            }
            None => {
                ui.label("Click a tree in the view.");
            }
        }
        ui.separator();
        self.legend(ui);
        ui.separator();
        ui.strong("Stand table");
        let cols: Vec<(&str, &str)> = PLOT_COLUMNS.iter().copied().filter(|c| self.data.stand_table.columns.iter().any(|x| x == c.0)).collect();
        if cols.is_empty() {
            ui.label("(no stand_table.csv in the run directory)");
            return;
        }
        let label = cols.iter().find(|c| c.0 == self.plot_column).map_or(self.plot_column.clone(), |c| c.1.to_string());
        egui::ComboBox::from_label("column").selected_text(label.clone()).show_ui(ui, |ui| {
            for c in &cols {
                ui.selectable_value(&mut self.plot_column, c.0.to_string(), c.1);
            }
        });
        let pts = self.data.stand_table.series(&self.plot_column);
        let year = self.year as f64;
        egui_plot::Plot::new("stand table plot").height(220.0).x_axis_label("year").y_axis_label(label.clone()).allow_scroll(false).show(ui, |p| {
            p.line(egui_plot::Line::new(label, egui_plot::PlotPoints::from(pts)).color(egui::Color32::from_rgb(40, 120, 40)));
            p.vline(egui_plot::VLine::new("year shown", year).color(egui::Color32::from_rgb(200, 80, 40)));
        });
    }

    fn legend(&mut self, ui: &mut egui::Ui) {
        ui.strong("Overlay");
        match self.overlay {
            Overlay::None => {
                ui.label("land cover (elevation and slope colours)");
            }
            Overlay::Species => {
                for (p, id) in self.data.pool.iter().enumerate() {
                    ui.horizontal(|ui| {
                        let [r, g, b] = RunData::species_colour(p);
                        let (rect, _) = ui.allocate_exact_size(egui::vec2(18.0, 12.0), egui::Sense::hover());
                        ui.painter().rect_filled(rect, 2.0, egui::Color32::from_rgb(r, g, b));
                        ui.label(id);
                    });
                }
            }
            o => {
                let (ramp, range, title) = match o {
                    Overlay::Condition(k) => {
                        let l = &self.data.layers[k];
                        let range = l.range.or_else(|| crate::output::maps::percentile_range(&l.grid, Some(&self.data.site.mask), 0.02, 0.98)).unwrap_or((0.0, 1.0));
                        (l.ramp, range, format!("{} ({})", l.title, l.units))
                    }
                    _ => (crate::output::maps::Ramp::Viridis, (0.0, 60.0), "basal area (m²/ha) per 20 m cell".to_string()),
                };
                ui.label(title);
                let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width().min(260.0), 14.0), egui::Sense::hover());
                let n = 32;
                for i in 0..n {
                    let [r, g, b] = ramp.color((i as f32 + 0.5) / n as f32);
                    let x0 = rect.left() + rect.width() * i as f32 / n as f32;
                    let x1 = rect.left() + rect.width() * (i + 1) as f32 / n as f32;
                    ui.painter().rect_filled(egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range()), 0.0, egui::Color32::from_rgb(r, g, b));
                }
                ui.horizontal(|ui| {
                    ui.label(format!("{:.1}", range.0));
                    ui.add_space((rect.width() - 80.0).max(0.0));
                    ui.label(format!("{:.1}", range.1));
                });
            }
        }
    }

    /// Whether this frame is drawn in motion ([`motion_lod`]): the first frame, and every frame
    /// whose camera differs from the last one's, while the years play or the year shown moves
    /// (the slider dragged); a still frame then
    /// follows at full detail ([`still_lod`]). With a `--screenshot` pending every frame is
    /// still, so screenshots show the full detail.
    fn in_motion(&mut self, cam: &crate::render::camera::Camera) -> bool {
        let moved = self.last_camera.as_ref() != Some(cam) || self.playing || self.year_moving;
        self.last_camera = Some(*cam);
        moved && !self.screenshot.as_ref().is_some_and(|s| s.pending())
    }

    /// The snapshot year shown when [`Viewer::year`] sits on one and the years do not play.
    fn snapshot_shown(&self) -> Option<u32> {
        if self.playing {
            return None;
        }
        self.data.years.iter().copied().find(|&y| (y as f32 - self.year).abs() < 1e-3)
    }

    /// Lets go of the adapted near field: the trees drawn with their species' models again.
    fn clear_near(&mut self) {
        if let Some(n) = &self.near {
            n.cancel();
        }
        self.near_pending = None;
        self.near_key = None;
        if !self.near_shown.is_empty() {
            self.near_shown.clear();
            let mut p = std::mem::take(&mut self.scene.prototypes);
            p.truncate(self.n_base);
            self.scene.set_prototypes(p);
        }
        if let Some(g) = self.gpu.as_mut() {
            g.renderer.replaced.clear();
        }
    }

    /// The near field for this frame ([`near`]): takes the worker's results, and when the camera
    /// rests on a snapshot year asks for the trees of this view (superseding what was asked
    /// before); a camera in motion supersedes the request under way.
    fn update_near(&mut self, cam: &crate::render::camera::Camera, motion: bool, w: u32, h: u32) {
        if self.gpu.is_none() || !self.near_on {
            return;
        }
        self.take_near_results();
        let snap = self.snapshot_shown();
        if self.near_shown.first().is_some_and(|t| Some(t.year) != snap) {
            self.clear_near();
        }
        if self.near_dirty {
            self.rebuild_replaced();
        }
        if motion || snap.is_none() {
            if let (Some(n), Some(_)) = (&self.near, self.near_pending.take()) {
                n.cancel();
            }
            self.near_key = None;
            return;
        }
        let Some(year) = snap else { return };
        let key = (year, *cam, w, h);
        if self.near_key == Some(key) {
            return;
        }
        self.near_key = Some(key);
        let sel = near::select_near(&self.current, cam, w as f32, h as f32, &still_lod(), scene::is_stump);
        let wanted: Vec<u64> = sel.iter().map(|t| t.id).collect();
        let shown: Vec<u64> = self.near_shown.iter().map(|t| t.id).collect();
        if wanted == shown {
            if let (Some(n), Some(_)) = (&self.near, self.near_pending.take()) {
                n.cancel();
            }
            return;
        }
        // the snapshot's trees within reach: the wanted ones and their neighbours
        let Some(k) = self.data.years.iter().position(|&y| y == year) else { return };
        let so = crate::structure::stand::StandOptions::default();
        let reach = near::NEAR_M + so.cell_m + so.halo_m + 2.0;
        let eye = Vec3::from(cam.eye);
        let rows = match self.data.rows(k) {
            Ok(r) => r.iter().filter(|r| r.status == "alive" && ((r.x_m - eye.x as f64).hypot(r.y_m - eye.y as f64) as f32) <= reach).cloned().collect(),
            Err(e) => {
                self.status = Some(e.to_string());
                return;
            }
        };
        let (seed, obstacles) = self.near_scenario.clone();
        let (lib, site) = (&self.data.library, &self.data.site);
        let nf = self.near.get_or_insert_with(|| near::NearField::start(lib.clone(), site.clone(), obstacles, seed));
        let g = nf.request(near::NearRequest { generation: 0, year, wanted, shown, rows });
        self.near_pending = Some((g, std::time::Instant::now()));
    }

    /// Installs the worker's latest answer (older ones are dropped).
    fn take_near_results(&mut self) {
        let Some(nf) = &self.near else { return };
        let mut latest = None;
        while let Some(r) = nf.poll() {
            if r.generation == nf.generation() {
                latest = Some(r);
            }
        }
        let Some(r) = latest else { return };
        let since = self.near_pending.take().map_or(0.0, |p| p.1.elapsed().as_secs_f64());
        if let Some(e) = &r.error {
            self.status = Some(format!("near field: {e}"));
        }
        // the trees still wanted keep their meshes; the new ones join; the others go
        let mut protos = std::mem::take(&mut self.scene.prototypes);
        let old = protos.split_off(self.n_base);
        let mut had: std::collections::HashMap<u64, (ShownTree, crate::render::scene::Prototype)> = self.near_shown.drain(..).zip(old).map(|(t, p)| (t.id, (t, p))).collect();
        let mut new: std::collections::HashMap<u64, near::NearModel> = r.models.into_iter().map(|m| (m.id, m)).collect();
        for id in &r.wanted {
            let (t, p) = match (had.remove(id), new.remove(id)) {
                (Some(x), _) => x,
                (None, Some(m)) => (ShownTree { id: *id, year: r.year, tree: m.tree, height: m.model.height, r0: m.model.r0, nodes: m.model.nodes, leaf_cards: m.model.leaf_cards, sprig_cards: m.model.sprig_cards }, m.model.prototype),
                _ => continue,
            };
            self.near_shown.push(t);
            protos.push(p);
        }
        drop(had);
        self.scene.set_prototypes(protos);
        self.rebuild_replaced();
        self.near_report = true;
        let (n, med) = self.adapted_shown();
        tracing::info!("near field of year {}: {n} trees with their adapted full-detail meshes ({} adapted with their neighbours, {} from the cache; adapting {:.2} s, meshing {:.2} s), median {med} nodes, {:.2} s after the camera came to rest", r.year, r.adapted, r.from_cache, r.adapt_s, r.mesh_s, since);
    }

    /// The instances the renderer draws instead of the near field's trees
    /// ([`crate::render::renderer::Renderer::replaced`]).
    fn rebuild_replaced(&mut self) {
        self.near_dirty = false;
        let Some(g) = self.gpu.as_mut() else { return };
        g.renderer.replaced.clear();
        if self.near_shown.is_empty() {
            return;
        }
        let at: std::collections::HashMap<u64, usize> = self.near_shown.iter().enumerate().map(|(k, t)| (t.id, k)).collect();
        for inst in &self.current {
            let Some(&k) = at.get(&inst.id) else { continue };
            let t = &self.near_shown[k];
            let Some(sp) = self.data.library.species.get(t.tree.species as usize) else { continue };
            let mut i = *inst;
            crate::job::adapted::place_adapted(&mut i, t.height, t.r0, &t.tree, sp, self.season, (self.n_base + k) as u32);
            g.renderer.replaced.insert(t.id, i);
        }
    }

    fn view_3d(&mut self, ui: &mut egui::Ui) {
        let size = ui.available_size();
        let (rect, resp) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
        self.view_rect = rect;
        self.pixels_per_point = ui.ctx().pixels_per_point();
        self.rig.drive(ui, &resp, rect.height());
        // `SYLVA_VIEW_SPIN=1`: the camera turns a little every frame and the frame times are
        // logged (how fast the viewer draws in motion, BENCHMARKS.md)
        if self.spin {
            self.rig.rotate(4.0, 0.0);
            ui.ctx().request_repaint();
        }
        if resp.clicked() {
            if let Some(p) = resp.interact_pointer_pos() {
                self.pick_at(p.x - rect.left(), p.y - rect.top());
            }
        }
        // `--screenshot`: once the last of the --frames frames is drawn and its screenshot asked
        // for, the passes until the image arrives show that frame again instead of drawing it
        if let (Some(tex), true) = (self.last_frame, self.screenshot.as_ref().is_some_and(|s| s.requested())) {
            ui.painter().image(tex, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
            crate::gui::paint_north_arrow(ui.painter(), rect, &self.rig.camera());
            return;
        }
        self.refresh();
        let (w, h) = ((rect.width() * self.pixels_per_point) as u32, (rect.height() * self.pixels_per_point) as u32);
        let cam = self.rig.camera();
        let motion = self.in_motion(&cam);
        self.update_near(&cam, motion, w, h);
        if self.near_pending.is_some() {
            // the worker's answer is polled while the UI waits
            ui.ctx().request_repaint_after(std::time::Duration::from_millis(100));
        }
        // while the near field is on its way, an unchanged still frame is shown again, not
        // drawn again; with a --screenshot pending nothing is drawn before it has arrived
        let sig: FrameSig = (cam, w, h, self.shown, self.overlay, self.baked, self.scene.prototypes.len());
        let waiting = self.near_pending.is_some() && !motion;
        let shot = self.screenshot.as_ref().is_some_and(|s| s.pending());
        if waiting && (shot || self.frame_sig == Some(sig)) {
            match self.last_frame.filter(|_| self.frame_sig == Some(sig)) {
                Some(tex) => {
                    ui.painter().image(tex, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
                    crate::gui::paint_north_arrow(ui.painter(), rect, &cam);
                }
                None => {
                    ui.painter().rect_filled(rect, 0.0, egui::Color32::from_gray(40));
                    ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, "adapting the trees near the camera…", egui::FontId::proportional(16.0), egui::Color32::LIGHT_GRAY);
                }
            }
            return;
        }
        self.frame_sig = Some(sig);
        self.scene.instances = std::mem::take(&mut self.current);
        if let Some(g) = self.gpu.as_mut() {
            g.renderer.lod = if motion { motion_lod() } else { still_lod() };
            g.renderer.max_near_trees = if motion { MOTION_NEAR_TREES } else { 0 };
            g.renderer.fast_shading = motion;
            g.renderer.coarse_terrain = motion;
            g.renderer.single_sample = motion;
            // the sun's shadows do not move with the camera: in motion the last map serves
            g.renderer.reuse_shadow_map = motion;
        }
        if motion {
            // the full-detail frame once the camera rests
            ui.ctx().request_repaint();
        }
        // in motion at a fraction of the resolution (on a software adapter the frame is spent
        // rasterising), egui scales it to the view; the fraction follows the time between
        // frames in motion: coarser while they take longer than MOTION_FRAME_S, finer while
        // they take less than 60 % of it
        if motion && self.motion_before && self.frame_dt > 0.0 {
            if self.frame_dt > MOTION_FRAME_S {
                self.motion_scale = (self.motion_scale * 1.2).min(MOTION_SCALE_MAX);
            } else if self.frame_dt < 0.6 * MOTION_FRAME_S {
                self.motion_scale = (self.motion_scale / 1.2).max(1.0);
            }
        }
        self.motion_before = motion;
        let (w, h) = if motion { (((w as f32 / self.motion_scale) as u32).max(16), ((h as f32 / self.motion_scale) as u32).max(16)) } else { (w, h) };
        let drawn = self.gpu.as_mut().map(|g| g.draw(&self.scene, &cam, w, h));
        self.frames_drawn += 1;
        if self.spin && self.frames_drawn % 10 == 0 {
            let st = self.gpu.as_ref().map(|g| (g.last_ms, g.renderer.last_stats())).unwrap_or_default();
            tracing::info!("frames {}–{}: {:.0} ms per frame (last: 3-D {:.0} ms on the CPU side, {} trees as geometry, {} k triangles, far-field switch {:.0} px), 1/{:.2} resolution)", self.frames_drawn - 9, self.frames_drawn, self.spin_clock.elapsed().as_secs_f32() * 100.0, st.0, st.1.instances_drawn, st.1.triangles / 1000, st.1.canopy_px, self.motion_scale);
            self.spin_clock = std::time::Instant::now();
        }
        if self.frames_drawn <= 3 {
            tracing::info!("frame {} ({}) drawn {:.1} s after the viewer opened its data", self.frames_drawn, if motion { "in motion" } else { "still" }, self.opened.elapsed().as_secs_f32());
        }
        // the near field drawn: its adapted trees by the level the frame drew them at
        if self.near_report && !motion && drawn.as_ref().is_some_and(|d| d.is_ok()) {
            self.near_report = false;
            if let Some(g) = self.gpu.as_ref() {
                let trees: Vec<(TreeInstance, usize)> = self.near_shown.iter().enumerate().filter_map(|(k, t)| Some((*g.renderer.replaced.get(&t.id)?, self.scene.prototypes.get(self.n_base + k)?.lods.levels.len()))).collect();
                let levels = crate::job::pictures::drawn_levels_of(&trees, &cam, w, h, &g.renderer.lod, &g.renderer.last_stats());
                let (n, med) = self.adapted_shown();
                let (cards, sprigs): (usize, usize) = self.near_shown.iter().fold((0, 0), |a, t| (a.0 + t.leaf_cards, a.1 + t.sprig_cards));
                tracing::info!("near field drawn: {n} adapted trees, {} at the full level (per level {levels:?}), median {med} nodes, {cards} leaf cards and {sprigs} leaf-cluster cards", levels[0]);
            }
        }
        self.current = std::mem::take(&mut self.scene.instances);
        match drawn {
            Some(Ok(tex)) => {
                self.last_frame = Some(tex);
                ui.painter().image(tex, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
                crate::gui::paint_north_arrow(ui.painter(), rect, &cam);
            }
            Some(Err(e)) => {
                self.status = Some(e.to_string());
            }
            None => {
                ui.painter().rect_filled(rect, 0.0, egui::Color32::from_gray(40));
                ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, "3-D view: no GPU viewport", egui::FontId::proportional(16.0), egui::Color32::LIGHT_GRAY);
            }
        }
        // the selected tree: a ring at its foot and its label
        if let Some(id) = self.selected {
            if let Some(t) = self.current.iter().find(|t| t.id == id) {
                let cam = self.rig.camera();
                let vp = cam.view_proj(rect.width().max(1.0) / rect.height().max(1.0));
                let to_screen = |p: Vec3| {
                    let c = vp * p.extend(1.0);
                    (c.w > 0.0).then(|| egui::pos2(rect.left() + (c.x / c.w + 1.0) * 0.5 * rect.width(), rect.top() + (1.0 - c.y / c.w) * 0.5 * rect.height()))
                };
                let base = Vec3::from(t.position);
                let pts: Vec<egui::Pos2> = (0..=32).filter_map(|k| {
                    let a = k as f32 / 32.0 * std::f32::consts::TAU;
                    to_screen(base + Vec3::new(a.cos(), a.sin(), 0.0) * t.crown_radius.max(1.0) + Vec3::Z * 0.3)
                }).collect();
                ui.painter().add(egui::Shape::line(pts, egui::Stroke::new(2.0, egui::Color32::YELLOW)));
                if let Some(top) = to_screen(base + Vec3::Z * t.height) {
                    ui.painter().text(top, egui::Align2::CENTER_BOTTOM, format!("#{id}"), egui::FontId::proportional(13.0), egui::Color32::YELLOW);
                }
            }
        }
    }

    fn help(&mut self, ctx: &egui::Context) {
        let mut open = self.show_help;
        egui::Window::new("Help: keyboard and mouse").open(&mut open).resizable(false).collapsible(false).anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0]).show(ctx, |ui| {
            egui::Grid::new("shortcuts").num_columns(2).striped(true).show(ui, |ui| {
                for (k, what) in SHORTCUTS {
                    ui.strong(*k);
                    ui.label(*what);
                    ui.end_row();
                }
            });
            ui.separator();
            ui.label(format!("Run: {}", self.data.dir.display()));
            ui.label("Trees between snapshots are interpolated (growth; recruits fade in; the dead fade out), as in the timelapse.");
        });
        self.show_help = open;
    }

    /// Lays out the whole window in `ui` (the root of an eframe window or a test harness).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let dt = self.clock.tick();
        self.frame_dt = dt;
        if self.playing {
            let (a, b) = self.data.span();
            self.year += dt * self.speed;
            if self.year >= b as f32 {
                self.year = b as f32;
                self.playing = false;
            }
            self.year = self.year.max(a as f32);
            ctx.request_repaint();
        }
        self.keys(&ctx, dt);
        egui::Panel::top("top bar").show(ui, |ui| self.top_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.label(format!("{}  |  {} snapshots, years {}–{}", self.data.dir.display(), self.data.years.len(), self.data.span().0, self.data.span().1));
                if let Some(g) = &self.gpu {
                    ui.label(format!("|  {}", g.renderer.adapter_description()));
                }
                if let Some(s) = &self.status {
                    ui.colored_label(egui::Color32::from_rgb(220, 80, 60), s);
                }
            });
        });
        egui::Panel::right("side").default_size(340.0).resizable(true).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
        });
        egui::CentralPanel::no_frame().show(ui, |ui| self.view_3d(ui));
        self.help(&ctx);
        if let Some(s) = self.screenshot.as_mut() {
            // --screenshot waits for the adapted near field
            if self.near_pending.is_some() && !s.requested() {
                s.hold();
            }
            s.frame(&ctx);
        }
    }
}

/// Level-of-detail settings of a still frame, as the stills (`job::pictures::Stage`): lower
/// switch sizes keep mid-distance crowns as meshes, and no far-field triangle budget (only
/// trees under 6 px go to the canopy layer); the default budget of 6 M triangles per frame stays.
pub fn still_lod() -> crate::render::lod::LodParams {
    crate::render::lod::LodParams { switch_px: [110.0, 45.0, 18.0], max_geometry_triangles: 0, ..Default::default() }
}

/// Level-of-detail settings of a frame in motion (issue 36's frame budget): the renderer's
/// defaults, so coarser levels and at most [`MOTION_GEOMETRY_TRIANGLES`] triangles of tree
/// geometry, the rest of the forest in the baked canopy layer (at most [`MOTION_NEAR_TREES`]
/// trees culled); such a frame is also drawn at a fraction of the view's resolution (half at
/// first, then adapted to [`MOTION_FRAME_S`]), with the renderer's one-tap shadows
/// (`Renderer::fast_shading`), its coarse terrain mesh (`Renderer::coarse_terrain`) and without
/// multisampling (`Renderer::single_sample`).
pub fn motion_lod() -> crate::render::lod::LodParams {
    crate::render::lod::LodParams { max_geometry_triangles: MOTION_GEOMETRY_TRIANGLES, ..Default::default() }
}

/// Time between frames in motion the viewer aims at (s): 5 frames per second (issue 36).
pub const MOTION_FRAME_S: f32 = 0.2;

/// Largest divisor of the resolution of frames in motion (they start at half the view's).
pub const MOTION_SCALE_MAX: f32 = 4.0;

/// Trees culled and drawn as geometry while the camera moves (the rest of the far field is its
/// baked canopy layer, [`crate::render::renderer::Renderer::max_near_trees`]).
pub const MOTION_NEAR_TREES: usize = 30_000;

/// Tree triangles drawn as geometry while the camera moves (the far-field switch rises until
/// they fit; `render::lod`).
pub const MOTION_GEOMETRY_TRIANGLES: u32 = 50_000;

fn input_error(e: crate::Error) -> GuiError {
    GuiError::Render(crate::render::RenderError::Input(e))
}

/// One prototype per species of `library` (in library order, as the instances index them): the
/// EcoMod model of [`scene::prototypes`] for the species of `pool`, the renderer's cheap stand-in
/// for the others (no tree of theirs is in the run).
fn pool_prototypes(library: &crate::species::SpeciesLibrary, pool: &[String]) -> Vec<crate::render::scene::Prototype> {
    let used = crate::species::SpeciesLibrary { species: library.species.iter().filter(|s| pool.contains(&s.id)).cloned().collect() };
    let mut built = scene::prototypes(&used).into_iter();
    library
        .species
        .iter()
        .map(|s| {
            if pool.contains(&s.id) {
                if let Some(p) = built.next() {
                    return p;
                }
            }
            let conifer = s.identity.leaf_type == crate::species::LeafType::Conifer;
            crate::render::scene::Prototype { name: s.id.clone(), lods: crate::render::lod::placeholder_chain(conifer), bark_color: scene::srgb_to_linear(s.appearance.bark), leaf_color: scene::srgb_to_linear(s.appearance.leaf_summer), stiffness: 1.0, look: Some(scene::crown_look(s)), rigid: false }
        })
        .collect()
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        Viewer::ui(self, ui);
    }
}

/// How the viewer starts: the scenario's seed and obstacles (the near field's trees are grown
/// and adapted with them, [`near`]) and a camera preset of the stills (`None`: the whole
/// terrain framed by the orbit camera).
#[derive(Debug, Clone, Default)]
pub struct ViewStart {
    /// Scenario seed.
    pub seed: u64,
    /// Scenario obstacles.
    pub obstacles: Vec<crate::sim::obstacle::ObstacleSpec>,
    /// Camera preset (`sylva view --camera`).
    pub camera: Option<crate::render::camera::CameraPreset>,
    /// Whether the near field is adapted ([`Viewer::set_adapt`]; `sylva view --adapt`).
    pub adapt: bool,
    /// Whether the window's trees are mirrored into the surroundings
    /// ([`crate::job::scene::Landscape::mirror_trees`]: not for a scenario that designs its
    /// stand, [`crate::sim::Scenario::designs_its_stand`]).
    pub mirror_trees: bool,
}

/// Opens the viewer window on `data` and returns when it is closed (or, with
/// `opts.screenshot`, after the screenshot is written). `surroundings`: the whole terrain the
/// site was cut from and the window it was cut with ([`Viewer::set_surroundings`]); `start`:
/// the scenario's seed and obstacles and the first camera.
///
/// # Errors
/// As [`gui::run_window`]; [`GuiError::Render`] when the renderer cannot be built on the
/// window's device or the window leaves the terrain.
pub fn run(data: RunData, sea_level_m: f32, surroundings: Option<(crate::terrain::Terrain, [usize; 4])>, start: &ViewStart, opts: &WindowOptions) -> gui::Result<()> {
    let title = format!("Sylva — {}", data.dir.display());
    let start = start.clone();
    let size = opts.size;
    gui::run_viewport_window(&title, opts, data, move |d, vp, shot| {
        let mut v = Viewer::new(d, sea_level_m, Some(vp))?;
        if let Some((full, window)) = &surroundings {
            v.set_surroundings(full, *window)?;
            v.landscape.mirror_trees = start.mirror_trees;
        }
        v.set_scenario(start.seed, start.obstacles.clone());
        v.set_adapt(start.adapt);
        if let Some(p) = start.camera {
            // the 3-D view's size is not known yet: the window's less the side panel
            let cam = v.preset_camera(p, ((size.0 - 340.0).max(64.0)) as u32, ((size.1 - 60.0).max(64.0)) as u32).map_err(input_error)?;
            v.look(&cam);
        }
        if let Some(s) = shot {
            v = v.with_screenshot(s);
        }
        Ok(v)
    })
}
