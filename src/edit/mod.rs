//! `sylva edit [SPECIES_FILE|SPECIES_ID]`: the species editor (issue 15).
//!
//! Every field of the species schema ([`crate::species::schema::FIELDS`]) gets a control with
//! the schema's bounds: EcoMod's global parameters as sliders with the bounds of its dialog
//! (`004_*.txt` §II.A: strands 0–5000, trunk 0–10 m, k_d 0–0.05, k_c 0–1, α_p 0–360°, ρ_l 0–30,
//! l_l 0–0.3, w_g and w_s 0–10), each poly-line parameter graph over the Gravelius or Weibull
//! order as a curve whose control points are dragged, added (double-click) and removed
//! (right-click) ([`curve`]); the niche (Ellenberg values with tolerances) drawn as its
//! response curves; the light-guided, Laplacian and Plastic Trees parameters; colours. A live 3-D
//! preview regrows the tree on a worker thread after each change ([`preview`]; EcoMod,
//! light-guided or Laplacian model, age slider); the branches the hovered curve point acts on
//! are highlighted. Validation messages are those of `sylva species check`, shown beside their
//! field; undo/redo; save keeps comments and order ([`doc`], `toml_edit`); "save as new species"
//! copies the file under a new id as `sylva species new` does.
//!
//! A shell module: the core names none of it (`tests/layers.rs`).

pub mod curve;
pub mod doc;
pub mod preview;

use std::path::{Path, PathBuf};

use eframe::egui;
use glam::Vec3;

use crate::gui::{self, FrameClock, Screenshot, Viewport3d, WindowOptions};
use crate::render::scene::{Scene, Sky, TerrainMesh, Wind};
use crate::species::schema::{self, Kind};
use crate::species::{Problem, Species};
use crate::structure::species_tree::Model;
use crate::view::camera::CameraRig;
use doc::SpeciesDoc;
use preview::{Grower, Highlight, Request};

/// Errors of the editor.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// A species file that cannot be read or parsed, or a bad edit (names the file or field).
    #[error(transparent)]
    Input(#[from] crate::Error),
    /// Writing the file failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// Result of the editor's operations.
pub type Result<T> = std::result::Result<T, EditError>;

/// Sections of the editor, by field path prefix, in order.
const SECTIONS: &[(&str, &str)] = &[
    ("identity.", "Identity"),
    ("niche.", "Niche (Ellenberg values and tolerances)"),
    ("life.", "Life history"),
    ("architecture.ecomod.", "EcoMod (Zamuda et al.)"),
    ("architecture.light_guided.", "Light-guided growth (Yi et al.)"),
    ("architecture.laplacian.", "Laplacian growth (Jinasena & Sonnadara)"),
    ("architecture.plastic.", "Plastic Trees (Pirk et al. 2012)"),
    ("architecture.mature_form.", "Mature form (EcoMod with age; optional)"),
    ("appearance.", "Appearance"),
];

/// Keyboard shortcuts of the editor.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Ctrl+Z", "undo"),
    ("Ctrl+Y or Ctrl+Shift+Z", "redo"),
    ("Ctrl+S", "save"),
    ("curve: drag a point", "move it (between its neighbours' orders)"),
    ("curve: double-click", "add a point"),
    ("curve: right-click a point", "remove it (two points stay)"),
    ("preview: drag / wheel", "orbit / zoom"),
    ("F1", "show / hide this help"),
];

/// The species editor: the document, its validation, the preview and the window state.
pub struct Editor {
    /// The file edited.
    pub doc: SpeciesDoc,
    /// Folder "save as new species" writes into.
    pub new_dir: PathBuf,
    /// Id typed for "save as new species".
    pub new_id: String,
    checked_text: String,
    species: Option<Species>,
    /// The problems of the current text (as `sylva species check` reports them).
    pub problems: Vec<Problem>,
    /// Growth model of the preview.
    pub model: Model,
    /// Age of the preview tree (years).
    pub age_yr: f32,
    grower: Grower,
    grown: Option<preview::Grown>,
    scene: Scene,
    highlight: Option<(Highlight, String)>,
    shown_highlight: Option<Highlight>,
    gpu: Option<Viewport3d>,
    rig: CameraRig,
    clock: FrameClock,
    screenshot: Option<Screenshot>,
    /// Status line (saved, errors).
    pub status: String,
    show_help: bool,
    /// Wait for each preview before drawing (screenshots: the picture shows the finished tree).
    pub wait_for_preview: bool,
    /// Grow previews even without a GPU viewport (tests of the preview; off by default, so a
    /// window-less editor in tests only edits).
    pub grow_without_gpu: bool,
}

fn ground(size: f32) -> TerrainMesh {
    let c = [0.30, 0.42, 0.20];
    TerrainMesh {
        positions: vec![[-size, -size, 0.0], [size, -size, 0.0], [size, size, 0.0], [-size, size, 0.0]],
        normals: vec![[0.0, 0.0, 1.0]; 4],
        colors: vec![c; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        ..TerrainMesh::default()
    }
}

impl Editor {
    /// The editor of `doc`; "save as new species" writes into `new_dir`.
    pub fn new(doc: SpeciesDoc, new_dir: PathBuf, gpu: Option<Viewport3d>) -> Self {
        let mut gpu = gpu;
        if let Some(g) = gpu.as_mut() {
            // one tree, always the full mesh: no triangle budgets, no far-field canopy layer
            g.renderer.lod.max_triangles = 0;
            g.renderer.lod.max_geometry_triangles = 0;
            g.renderer.lod.canopy_px = 0.0;
            g.renderer.lod.switch_px = [20.0, 10.0, 5.0];
        }
        let scene = Scene::new(ground(30.0), None, Vec::new(), Vec::new(), crate::job::scene::season_sun(46.0, crate::species::Season::Summer), Sky::default(), Wind { direction: [1.0, 0.0], directed: 0.0, undirected: 0.0, time_s: 0.0 });
        let rig = CameraRig::looking(Vec3::new(-14.0, -18.0, 9.0), Vec3::new(0.0, 0.0, 6.0), 30.0);
        let mut e = Editor {
            doc,
            new_dir,
            new_id: String::new(),
            checked_text: String::new(),
            species: None,
            problems: Vec::new(),
            model: Model::EcoMod,
            age_yr: 40.0,
            grower: Grower::new(),
            grown: None,
            scene,
            highlight: None,
            shown_highlight: None,
            gpu,
            rig,
            clock: FrameClock::default(),
            screenshot: None,
            status: String::new(),
            show_help: false,
            wait_for_preview: false,
            grow_without_gpu: false,
        };
        e.revalidate();
        e
    }

    /// Takes a `--screenshot` after the given frames (waiting for each preview tree).
    pub fn with_screenshot(mut self, s: Screenshot) -> Self {
        self.screenshot = Some(s);
        self.wait_for_preview = true;
        self
    }

    /// Validates the text again if it changed since the last check.
    pub fn revalidate(&mut self) {
        let t = self.doc.text();
        if t != self.checked_text {
            let (sp, problems) = self.doc.check();
            self.species = sp;
            self.problems = problems;
            self.checked_text = t;
        }
    }

    /// The problems of one field.
    pub fn problems_of(&self, field: &str) -> Vec<&Problem> {
        self.problems.iter().filter(|p| p.field == field).collect()
    }

    /// The highlight drawn in the preview (the orders the hovered curve point acts on).
    pub fn highlighted(&self) -> Option<Highlight> {
        self.shown_highlight
    }

    /// Prototypes in the preview scene: the tree, and the highlight when there is one.
    pub fn preview_prototypes(&self) -> usize {
        self.scene.prototypes.len()
    }

    /// The last grown preview tree.
    pub fn grown(&self) -> Option<&preview::Grown> {
        self.grown.as_ref()
    }

    /// Asks for a new preview when the species (valid), model or age changed; takes a finished
    /// one.
    pub fn update_preview(&mut self) {
        self.revalidate();
        if self.gpu.is_none() && !self.grow_without_gpu {
            return;
        }
        if let (Some(sp), true) = (&self.species, self.problems.is_empty()) {
            self.grower.request(Request { species: sp.clone(), model: self.model, age_yr: self.age_yr, seed: 1 });
        }
        let got = if self.wait_for_preview { self.grower.wait().or_else(|| self.grower.poll()) } else { self.grower.poll() };
        if let Some(r) = got {
            match r {
                Ok(g) => {
                    self.grown = Some(g);
                    self.shown_highlight = None;
                    self.rebuild_scene();
                }
                Err(e) => self.status = format!("preview: {e}"),
            }
        }
        let h = self.highlight.as_ref().map(|h| h.0);
        if h != self.shown_highlight {
            self.shown_highlight = h;
            self.rebuild_scene();
        }
    }

    /// Waits until the preview of the current text is grown (tests; grows without a GPU too).
    pub fn finish_preview(&mut self) {
        self.grow_without_gpu = true;
        self.update_preview();
        while self.grower.busy() {
            if let Some(Ok(g)) = self.grower.wait() {
                self.grown = Some(g);
            }
        }
        self.rebuild_scene();
    }

    fn rebuild_scene(&mut self) {
        let Some(g) = &self.grown else { return };
        let sp = &g.request.species;
        let srgb = crate::job::scene::srgb_to_linear;
        let main = crate::render::scene::Prototype { name: sp.id.clone(), lods: g.lods.clone(), bark_color: srgb(sp.appearance.bark), leaf_color: srgb(sp.appearance.leaf_summer), stiffness: 1.0, look: Some(crate::job::scene::crown_look(sp)), rigid: false };
        let mut protos = vec![main];
        let hl = self.shown_highlight.and_then(|h| preview::highlight_prototype(&g.skeleton, h));
        let mut inst = vec![preview::instance(&protos[0], 0, g.height_m, if hl.is_some() { 0.35 } else { 1.0 })];
        if let Some(p) = hl {
            protos.push(p);
            let mut t = preview::instance(&protos[1], 1, g.height_m, 0.0);
            t.id = 2;
            inst.push(t);
        }
        self.scene.set_prototypes(protos);
        self.scene.instances = inst;
        let size = (g.height_m.max(2.0 * g.crown_radius_m) * 1.5).max(6.0);
        self.scene.set_terrain(ground(size));
        self.rig.scene_size = size;
    }

    /// Frames the preview tree (called after a model or age change and at start).
    pub fn frame_tree(&mut self) {
        if let Some(g) = &self.grown {
            let h = g.height_m.max(1.0);
            let mode = self.rig.mode;
            self.rig = CameraRig::looking(Vec3::new(-0.9 * h, -1.3 * h, 0.65 * h), Vec3::new(0.0, 0.0, 0.5 * h), 2.0 * h);
            self.rig.set_mode(mode);
        }
    }

    /// Undoes the last edit.
    pub fn undo(&mut self) {
        if self.doc.undo() {
            self.status = "undone".into();
        }
    }

    /// Redoes the last undone edit.
    pub fn redo(&mut self) {
        if self.doc.redo() {
            self.status = "redone".into();
        }
    }

    /// Saves the file.
    pub fn save(&mut self) {
        self.status = match self.doc.save() {
            Ok(()) => format!("saved {}", self.doc.path.display()),
            Err(e) => format!("not saved: {e}"),
        };
    }

    /// Saves as a new species with id [`Editor::new_id`] in [`Editor::new_dir`].
    pub fn save_as_new(&mut self) {
        let id = self.new_id.trim().to_string();
        let dir = self.new_dir.clone();
        self.status = match self.doc.save_as_new(&id, &dir) {
            Ok(p) => format!("wrote {} (a copy under the id `{id}`); now editing it", p.display()),
            Err(e) => format!("not saved: {e}"),
        };
    }

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            ui.strong(format!("{}{}", self.doc.path.display(), if self.doc.is_dirty() { " (modified)" } else { "" }));
            ui.separator();
            if ui.add_enabled(self.doc.can_undo(), egui::Button::new("Undo")).on_hover_text("Ctrl+Z").clicked() {
                self.undo();
            }
            if ui.add_enabled(self.doc.can_redo(), egui::Button::new("Redo")).on_hover_text("Ctrl+Y").clicked() {
                self.redo();
            }
            if ui.button("Save").on_hover_text("Ctrl+S").clicked() {
                self.save();
            }
            ui.separator();
            ui.label("new id:");
            ui.add(egui::TextEdit::singleline(&mut self.new_id).desired_width(120.0).hint_text("my_beech"));
            if ui.add_enabled(!self.new_id.trim().is_empty(), egui::Button::new("Save as new species")).on_hover_text(format!("writes {}/ID.toml", self.new_dir.display())).clicked() {
                self.save_as_new();
            }
            ui.separator();
            if self.problems.is_empty() {
                ui.colored_label(egui::Color32::from_rgb(90, 170, 90), "valid");
            } else {
                ui.colored_label(egui::Color32::from_rgb(230, 90, 70), format!("{} problem(s)", self.problems.len()));
            }
            if ui.button("Help").on_hover_text("F1").clicked() {
                self.show_help = !self.show_help;
            }
            ui.label(format!("frame {:.1} ms", self.clock.frame_ms));
        });
    }

    fn field_ui(&mut self, ui: &mut egui::Ui, f: &schema::FieldSpec, prefix: &str) {
        let path = f.path;
        // the name within its section: `growth.k`, and `L value` for the niche
        let rest = path.strip_prefix(prefix).unwrap_or(path);
        let short_owned = if prefix == "niche." { let mut c = rest.replacen('.', " ", 1); c.replace_range(0..1, &c[0..1].to_ascii_uppercase()); c } else { rest.to_string() };
        let short = short_owned.as_str();
        let unit = if f.unit.is_empty() { String::new() } else { format!(" ({})", f.unit) };
        let merge_of = |r: &egui::Response| r.dragged() && !r.drag_started();
        let mut err: Option<String> = None;
        match f.kind {
            Kind::Range { min, max, .. } => {
                if let Some(mut v) = self.doc.number(path) {
                    let r = if max - min <= 1e4 {
                        ui.add(egui::Slider::new(&mut v, min..=max).text(format!("{short}{unit}")).clamping(egui::SliderClamping::Never))
                    } else {
                        ui.horizontal(|ui| {
                            let speed = (v.abs() * 0.01).max(0.01);
                            let r = ui.add(egui::DragValue::new(&mut v).range(min..=max).speed(speed));
                            ui.label(format!("{short}{unit}"));
                            r
                        })
                        .inner
                    };
                    let r = r.on_hover_text(f.doc);
                    if r.changed() {
                        err = self.doc.set_number(path, v, merge_of(&r)).err().map(|e| e.to_string());
                    }
                }
            }
            Kind::Int { min, max } => {
                if let Some(v) = self.doc.number(path) {
                    let mut i = v as i64;
                    // strands: the slider spans EcoMod's dialog (0–5000, 004 §II.A); the schema
                    // allows more (the paper's pine has 6000), typed or kept beyond the slider's end
                    let (lo, hi) = if path == "architecture.ecomod.strands" { (0, 5000) } else { (min, max) };
                    let r = ui.add(egui::Slider::new(&mut i, lo..=hi).text(format!("{short}{unit}")).clamping(egui::SliderClamping::Never)).on_hover_text(f.doc);
                    if r.changed() {
                        err = self.doc.set_number(path, i as f64, merge_of(&r)).err().map(|e| e.to_string());
                    }
                }
            }
            Kind::Enum(options) => {
                if let Some(cur) = self.doc.string(path) {
                    let mut sel = cur.clone();
                    egui::ComboBox::from_label(short).selected_text(sel.clone()).show_ui(ui, |ui| {
                        for o in options {
                            ui.selectable_value(&mut sel, o.to_string(), *o);
                        }
                    });
                    if sel != cur {
                        err = self.doc.set_string(path, &sel, false).err().map(|e| e.to_string());
                    }
                }
            }
            Kind::Bool => {
                if let Some(mut b) = self.doc.boolean(path) {
                    if ui.checkbox(&mut b, short).on_hover_text(f.doc).changed() {
                        err = self.doc.set_bool(path, b).err().map(|e| e.to_string());
                    }
                }
            }
            Kind::Text { .. } | Kind::Ident => {
                if let Some(mut s) = self.doc.string(path) {
                    let r = ui.horizontal(|ui| {
                        ui.label(short);
                        ui.text_edit_singleline(&mut s)
                    }).inner;
                    if r.changed() {
                        err = self.doc.set_string(path, &s, true).err().map(|e| e.to_string());
                    }
                }
            }
            Kind::Indicator { max } => {
                let num = self.doc.number(path);
                let mut indifferent = num.is_none();
                ui.horizontal(|ui| {
                    let mut v = num.unwrap_or(5.0);
                    let r = ui.add_enabled(!indifferent, egui::Slider::new(&mut v, 1.0..=max).text(short).step_by(0.5));
                    if r.changed() {
                        err = self.doc.set_number(path, v, merge_of(&r)).err().map(|e| e.to_string());
                    }
                    if ui.checkbox(&mut indifferent, "x (indifferent)").changed() {
                        let r = if indifferent { self.doc.set_string(path, "x", false) } else { self.doc.set_value(path, toml_edit::Value::from(5i64), false) };
                        err = r.err().map(|e| e.to_string());
                    }
                });
            }
            Kind::PolyLine { x, y } => {
                if let Some(mut pts) = self.doc.polyline(path) {
                    ui.label(format!("{short}{unit}: {}", f.doc));
                    let r = curve::curve_editor(ui, path, &mut pts, x, y);
                    if r.changed {
                        err = self.doc.set_polyline(path, &pts, !r.started).err().map(|e| e.to_string());
                    }
                    if let Some(p) = r.hovered_point.map(Some).or(r.hovered.then_some(None)) {
                        let (lo, hi) = preview::affected_range(&pts, p, x);
                        let h = if x.1 > 20.0 { Highlight::Weibull(lo, hi) } else { Highlight::Gravelius(lo, hi) };
                        self.highlight = Some((h, path.to_string()));
                    }
                }
            }
            Kind::Colour => {
                if let Some(mut c) = self.doc.colour(path) {
                    ui.horizontal(|ui| {
                        if ui.color_edit_button_srgb(&mut c).changed() {
                            err = self.doc.set_colour(path, c, true).err().map(|e| e.to_string());
                        }
                        ui.label(short);
                    });
                }
            }
            Kind::TextList => {
                ui.label(format!("{short}: a list, edited in the file"));
            }
        }
        if let Some(e) = err {
            self.status = e;
        }
        for p in self.problems_of(path) {
            ui.colored_label(egui::Color32::from_rgb(230, 90, 70), format!("problem: {}", p.expected));
        }
    }

    fn niche_curves(&self, ui: &mut egui::Ui) {
        let Some(sp) = &self.species else {
            ui.label("(fix the problems to see the response curves)");
            return;
        };
        let n = &sp.niche;
        let factors = [("L", &n.l, 9.0), ("T", &n.t, 9.0), ("K", &n.k, 9.0), ("F", &n.f, 12.0), ("R", &n.r, 9.0), ("N", &n.n, 9.0)];
        let colours = [[230, 180, 40], [220, 80, 60], [140, 100, 200], [60, 130, 220], [120, 170, 80], [160, 110, 60]];
        egui_plot::Plot::new("niche").height(160.0).x_axis_label("Ellenberg value").y_axis_label("suitability").include_y(0.0).include_y(1.05).allow_scroll(false).allow_drag(false).legend(egui_plot::Legend::default()).show(ui, |p| {
            for ((name, f, max), c) in factors.iter().zip(colours) {
                let pts: Vec<[f64; 2]> = (0..=110).map(|i| {
                    let x = 1.0 + (max - 1.0) * i as f64 / 110.0;
                    [x, f.suitability(x as f32) as f64]
                }).collect();
                p.line(egui_plot::Line::new(*name, egui_plot::PlotPoints::from(pts)).color(egui::Color32::from_rgb(c[0], c[1], c[2])));
            }
        });
        ui.small("Gaussian response exp(−½((x − value)/tolerance)²) per factor (ter Braak & Looman 1986); indifferent (x) = 1. Suitability is the least of the six (Liebig).");
    }

    fn fields_panel(&mut self, ui: &mut egui::Ui) {
        self.highlight = None;
        for (prefix, title) in SECTIONS {
            let open = matches!(*prefix, "architecture.ecomod." | "niche.");
            egui::CollapsingHeader::new(*title).default_open(open).show(ui, |ui| {
                if *prefix == "niche." {
                    self.niche_curves(ui);
                }
                for f in schema::FIELDS.iter().filter(|f| f.path.starts_with(prefix)) {
                    self.field_ui(ui, f, prefix);
                }
            });
        }
        let other: Vec<&Problem> = self.problems.iter().filter(|p| !schema::FIELDS.iter().any(|f| f.path == p.field)).collect();
        if !other.is_empty() {
            ui.separator();
            for p in other {
                ui.colored_label(egui::Color32::from_rgb(230, 90, 70), format!("problem: {p}"));
            }
        }
    }

    fn preview_panel(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("Model");
            let before = (self.model, self.age_yr);
            ui.radio_value(&mut self.model, Model::EcoMod, "EcoMod");
            ui.radio_value(&mut self.model, Model::Light, "light-guided");
            ui.radio_value(&mut self.model, Model::Laplacian, "Laplacian");
            ui.add(egui::Slider::new(&mut self.age_yr, 1.0..=150.0).text("age (yr)").step_by(1.0));
            if (self.model, self.age_yr) != before {
                self.status.clear();
            }
            if self.grower.busy() {
                ui.spinner();
                ui.label("growing…");
            } else if let Some(g) = &self.grown {
                ui.label(format!("{:.1} m tall, crown radius {:.1} m, {} nodes, grown in {:.2} s", g.height_m, g.crown_radius_m, g.skeleton.nodes.len(), g.seconds));
            }
            if ui.button("Frame").clicked() {
                self.frame_tree();
            }
        });
        if let Some((h, path)) = &self.highlight {
            let what = match h {
                Highlight::Gravelius(a, b) => format!("Gravelius orders {a:.1}–{b:.1}"),
                Highlight::Weibull(a, b) => format!("Weibull orders {a:.1}–{b:.1}"),
            };
            ui.colored_label(egui::Color32::from_rgb(255, 60, 190), format!("highlighted: branches of {what} ({path})"));
        }
        let framed = self.grown.as_ref().map(|g| g.height_m);
        self.update_preview();
        if framed.is_none() && self.grown.is_some() {
            self.frame_tree();
        }
        let (rect, resp) = ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        self.rig.drive(ui, &resp, rect.height());
        let ppp = ui.ctx().pixels_per_point();
        let cam = self.rig.camera();
        let drawn = if self.grown.is_some() { self.gpu.as_mut().map(|g| g.draw(&self.scene, &cam, (rect.width() * ppp) as u32, (rect.height() * ppp) as u32)) } else { None };
        match drawn {
            Some(Ok(tex)) => {
                ui.painter().image(tex, rect, egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)), egui::Color32::WHITE);
            }
            Some(Err(e)) => self.status = e.to_string(),
            None => {
                ui.painter().rect_filled(rect, 0.0, egui::Color32::from_gray(40));
                let msg = if self.gpu.is_none() { "3-D preview: no GPU viewport" } else { "growing the tree…" };
                ui.painter().text(rect.center(), egui::Align2::CENTER_CENTER, msg, egui::FontId::proportional(16.0), egui::Color32::LIGHT_GRAY);
            }
        }
        if self.grower.busy() {
            ui.ctx().request_repaint();
        }
    }

    fn keys(&mut self, ctx: &egui::Context) {
        let (undo, redo, save, help) = ctx.input_mut(|i| {
            let z = egui::KeyboardShortcut::new(egui::Modifiers::COMMAND, egui::Key::Z);
            let sz = egui::KeyboardShortcut::new(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
            let y = egui::KeyboardShortcut::new(egui::Modifiers::COMMAND, egui::Key::Y);
            let s = egui::KeyboardShortcut::new(egui::Modifiers::COMMAND, egui::Key::S);
            let redo = i.consume_shortcut(&sz) || i.consume_shortcut(&y);
            (i.consume_shortcut(&z), redo, i.consume_shortcut(&s), i.key_pressed(egui::Key::F1))
        });
        if undo {
            self.undo();
        }
        if redo {
            self.redo();
        }
        if save {
            self.save();
        }
        if help {
            self.show_help = !self.show_help;
        }
    }

    /// Lays out the whole window in `ui` (the root of an eframe window or a test harness).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        self.clock.tick();
        self.keys(&ctx);
        self.revalidate();
        egui::Panel::top("edit top").show(ui, |ui| self.top_bar(ui));
        egui::Panel::bottom("edit status").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.label(&self.status);
            });
        });
        egui::Panel::left("fields").default_size(520.0).resizable(true).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.fields_panel(ui));
        });
        self.revalidate();
        egui::CentralPanel::default().show(ui, |ui| self.preview_panel(ui));
        let mut open = self.show_help;
        egui::Window::new("Help: species editor").open(&mut open).collapsible(false).anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0]).show(&ctx, |ui| {
            egui::Grid::new("edit shortcuts").num_columns(2).striped(true).show(ui, |ui| {
                for (k, w) in SHORTCUTS {
                    ui.strong(*k);
                    ui.label(*w);
                    ui.end_row();
                }
            });
            ui.label("Bounds of the sliders: the species schema (EcoMod's dialog bounds, 004 §II.A; poly-line ordinates from eqs. 1–6).");
        });
        self.show_help = open;
        if let Some(s) = self.screenshot.as_mut() {
            s.frame(&ctx);
        }
    }
}

impl eframe::App for Editor {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        Editor::ui(self, ui);
    }
}

/// Opens the species file to edit: `arg` is a file (`.toml`, or any existing path) or a species
/// id/name; an id is looked up as `dir/ID.toml` first, then in the shipped library (saved to
/// `dir/ID.toml`). Without `arg`, the shipped beech.
///
/// # Errors
/// [`EditError::Input`] when the file cannot be read or parsed, or no species has that name.
pub fn open_target(arg: Option<&str>, dir: &Path) -> Result<SpeciesDoc> {
    let arg = arg.unwrap_or("beech");
    let p = Path::new(arg);
    if p.is_file() || arg.ends_with(".toml") {
        return SpeciesDoc::open(p);
    }
    let local = dir.join(format!("{arg}.toml"));
    if local.is_file() {
        return SpeciesDoc::open(&local);
    }
    let lib = crate::species::SpeciesLibrary::embedded()?;
    let sp = lib.get(arg).ok_or_else(|| crate::Error::Invalid { context: "sylva edit".into(), field: "species".into(), value: arg.into(), expected: format!("a species file or one of: {}", lib.species.iter().map(|s| s.id.as_str()).collect::<Vec<_>>().join(", ")) })?;
    let text = match crate::species::embedded_text(&sp.id) {
        Some(t) => t.to_string(),
        None => sp.to_toml_string()?,
    };
    SpeciesDoc::parse(&text, &dir.join(format!("{}.toml", sp.id)))
}

/// Opens the editor window on `doc` and returns when it is closed (or after the screenshot).
///
/// # Errors
/// As [`gui::run_window`].
pub fn run(doc: SpeciesDoc, new_dir: PathBuf, model: Model, age_yr: f32, opts: &WindowOptions) -> gui::Result<()> {
    let title = format!("Sylva species editor — {}", doc.path.display());
    gui::run_viewport_window(&title, opts, doc, move |d, vp, shot| {
        let mut e = Editor::new(d, new_dir, Some(vp));
        e.model = model;
        e.age_yr = age_yr;
        if let Some(s) = shot {
            e = e.with_screenshot(s);
        }
        Ok(e)
    })
}
