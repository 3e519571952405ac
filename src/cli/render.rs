//! `sylva render` and `sylva timelapse`: pictures of a run directory.

use anyhow::Context;
use std::path::{Path, PathBuf};
use sylva::job::pictures::{self, Stage, TimelapseOptions};
use sylva::render::camera::CameraPreset;
use sylva::sim::Scenario;
use sylva::species::Season;

/// `--fps` of `sylva run` and `sylva timelapse`: 1–100 frames per second.
pub(crate) fn parse_fps(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("fps `{s}`: expected a number"))?;
    if !(1.0..=100.0).contains(&v) {
        return Err(format!("fps `{s}`: expected 1–100 frames per second"));
    }
    Ok(v)
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("size `{s}`: expected WIDTHxHEIGHT, e.g. 1920x1080"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("size `{s}`: width is not a whole number"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("size `{s}`: height is not a whole number"))?;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        return Err(format!("size `{s}`: width and height must be 16–8192 pixels"));
    }
    Ok((w, h))
}

/// Says, before any work, that a picture larger than 4K UHD (3840 × 2160, 8.3 megapixels) costs
/// time and memory in proportion to its pixels (a trial: 8192 × 8192 of a small run took 275 s
/// and 6.1 GB on the software adapter).
fn warn_large_size((w, h): (u32, u32)) {
    let mp = w as f64 * h as f64 / 1e6;
    if mp > 3840.0 * 2160.0 / 1e6 {
        tracing::warn!("--size {w}x{h} is {mp:.0} megapixels: time and memory grow with the pixels (8192x8192 took minutes and about 6 GB on the software adapter); `sylva run` draws its stills at 1280x720");
    }
}

fn parse_camera(s: &str) -> Result<CameraPreset, String> {
    s.parse::<CameraPreset>().map_err(|_| format!("camera `{s}`: expected overview, oblique, ground or map"))
}

/// The camera of `sylva render`: a preset, or a hemispherical photograph at a place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RenderCamera {
    /// A camera preset of the renderer.
    Preset(CameraPreset),
    /// `hemi:X,Y`: an upward fisheye from 1.3 m at (X, Y) (m, world coordinates).
    Hemi(f64, f64),
    /// `closeup`: the close-up of `sylva run` (`stills/year_NNNN_closeup.png`,
    /// [`sylva::job::main_job::closeup_camera`]), drawn as the run draws it (without the
    /// regeneration layer).
    CloseUp,
    /// `eye:X,Y,Z:TX,TY,TZ[:FOV]`: a camera of one's own ([`EyeCamera`]).
    Eye(EyeCamera),
}

/// A camera of one's own (`--camera eye:X,Y,Z:TX,TY,TZ[:FOV]`): the eye and the point looked
/// at in site metres (x east and y north from the terrain's south-west corner, as the
/// inventory's `x_m`, `y_m` and `--area`; z the elevation above sea level, as the DEM's
/// heights, or with a leading `+` the height above the ground at that X, Y: `+1.7`), and the
/// vertical field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EyeCamera {
    /// Eye (m).
    pub eye: [f64; 3],
    /// Point looked at (m).
    pub target: [f64; 3],
    /// Whether the eye's Z was given as `+H`: a height above the ground at the eye's X, Y
    /// (the DEM's elevation there, [`sylva::conditions::SiteConditions::elevation_at`]), not an
    /// elevation (round 41, trial 40).
    pub eye_above_ground: bool,
    /// Whether the target's Z was given as `+H`, a height above the ground at its X, Y.
    pub target_above_ground: bool,
    /// Vertical field of view (degrees, 5–150; 50 when not given, the close-up's).
    pub fov_deg: f64,
}

/// Field of view (degrees) of `eye:…` when none is given: the close-up's 50°.
pub const EYE_DEFAULT_FOV_DEG: f64 = 50.0;

const EYE_FORM: &str = "eye:X,Y,Z:TX,TY,TZ[:FOV] with the eye X,Y,Z and the point looked at TX,TY,TZ in site metres (x east, y north from the terrain's south-west corner as the inventory's x_m, y_m; z the elevation, as the DEM's heights, or +H for H metres above the ground there, e.g. +1.7) and FOV the vertical field of view in degrees (5–150, default 50), e.g. eye:1000,700,1080:1250,950,930:55 (a view over the default site)";

/// Parses `eye:X,Y,Z:TX,TY,TZ[:FOV]` (`None` when `s` does not start with `eye:`): numbers
/// only, finite, an eye other than the target, a field of view of 5–150°. Whether the eye is
/// inside the site and above its ground is checked against the site ([`check_eye`]).
fn parse_eye(s: &str) -> Option<Result<EyeCamera, String>> {
    let rest = s.strip_prefix("eye:").or_else(|| s.strip_prefix("EYE:"))?;
    let bad = |why: &str| Err(format!("--camera `{s}`: {why}; expected {EYE_FORM}"));
    let parts: Vec<&str> = rest.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return Some(bad("not an eye and a target separated by `:`"));
    }
    // (the point, whether its Z is a height above the ground: `+H`)
    let point = |p: &str| -> Option<([f64; 3], bool)> {
        let c: Vec<&str> = p.split(',').map(str::trim).collect();
        let rel = c.get(2).is_some_and(|z| z.starts_with('+'));
        let v: Vec<f64> = c.iter().map(|x| x.parse::<f64>().ok().filter(|v| v.is_finite())).collect::<Option<_>>()?;
        (v.len() == 3 && !(rel && v[2] < 0.0)).then(|| ([v[0], v[1], v[2]], rel))
    };
    let Some((eye, eye_above_ground)) = point(parts[0]) else { return Some(bad("the eye is not three numbers X,Y,Z (Z an elevation, or +H a height above the ground)")) };
    let Some((target, target_above_ground)) = point(parts[1]) else { return Some(bad("the target is not three numbers TX,TY,TZ (TZ an elevation, or +H a height above the ground)")) };
    let fov_deg = match parts.get(2) {
        None => EYE_DEFAULT_FOV_DEG,
        Some(f) => match f.trim().parse::<f64>() {
            Ok(v) if (5.0..=150.0).contains(&v) => v,
            _ => return Some(bad(&format!("field of view `{f}` is not 5–150 degrees"))),
        },
    };
    // (an eye and a target given one by elevation and one by height above the ground are
    // told apart on the site, [`check_eye`])
    if eye_above_ground == target_above_ground && (0..3).map(|k| (eye[k] - target[k]).powi(2)).sum::<f64>() < 1e-6 {
        return Some(bad("the eye and the target are the same point"));
    }
    Some(Ok(EyeCamera { eye, target, fov_deg, eye_above_ground, target_above_ground }))
}

/// `Z` of the eye of `e` as it was given (`+H` or an elevation).
fn eye_z(e: &EyeCamera) -> String {
    if e.eye_above_ground {
        format!("+{}", e.eye[2])
    } else {
        format!("{}", e.eye[2])
    }
}

/// The eye of `e` (site metres, z the elevation) checked against `site` alone: over the site
/// (0 ≤ X ≤ width, 0 ≤ Y ≤ height) and at least 0.1 m above its ground there. [`check_eye`]
/// does this and more; `render` calls it as soon as the site is read, before the species and
/// the stage are built and the inventory read (trial 46 D11: an eye outside the site was
/// refused only after 26 s of loading).
///
/// Errors: naming `--camera`, the site's extent or the ground's elevation under the eye.
pub fn check_eye_on_site(e: &EyeCamera, site: &sylva::conditions::SiteConditions) -> anyhow::Result<[f64; 3]> {
    let (w, h) = site.extent_m();
    let [x, y, z] = e.eye;
    let zs = eye_z(e);
    anyhow::ensure!((0.0..=w).contains(&x) && (0.0..=h).contains(&y), "--camera eye:{x},{y},{zs}: the eye is outside the site; expected X 0–{w:.1} m and Y 0–{h:.1} m (site metres from the terrain's south-west corner, as the inventory's x_m, y_m)");
    let g = site.elevation_at(x, y) as f64;
    if e.eye_above_ground {
        anyhow::ensure!(z >= 0.1, "--camera eye:{x},{y},{zs}: the eye is {z} m above the ground (at {g:.1} m there); expected +H with H at least 0.1 m, e.g. +1.7 for a person's eye");
    } else {
        anyhow::ensure!(z >= g + 0.1, "--camera eye:{x},{y},{z}: the eye is under the ground (the ground there is at {g:.1} m); expected Z at least {:.1} m (z is the elevation, as the DEM's heights: e.g. {:.1} for a person's eye 1.7 m above the ground, or +1.7)", g + 0.1, g + 1.7);
    }
    Ok([x, y, if e.eye_above_ground { g + z } else { z }])
}

/// The camera of `e` on `site`, checked: the eye over the site (0 ≤ X ≤ width, 0 ≤ Y ≤ height)
/// and at least 0.1 m above its ground there ([`sylva::conditions::SiteConditions::elevation_at`]).
/// A Z given as `+H` is the ground's elevation at that point's X, Y plus H (the target's
/// ground where it lies on the site, else the nearest edge's, as `elevation_at` reads it).
///
/// The eye must also lie outside the scenario's `obstacles` as they are drawn (their solids on
/// the terrain, [`sylva::job::adapted::obstacle_around`]): trial 42 put an `eye:` inside a 12 m
/// building and got a grey wall, where `hemi:` at the same place is refused.
///
/// Errors: naming `--camera`, the site's extent, the ground's elevation under the eye, or the
/// obstacle (its kind and its place among the scenario's `[[obstacle]]` entries) around it.
pub fn check_eye(e: &EyeCamera, stage: &sylva::job::pictures::Stage) -> anyhow::Result<sylva::render::camera::Camera> {
    let site = &stage.site;
    let (w, h) = site.extent_m();
    let [x, y, _] = e.eye;
    let zs = eye_z(e);
    let eye = check_eye_on_site(e, site)?;
    if let Some((i, kind)) = sylva::job::adapted::obstacle_around(&stage.obstacles, site, eye) {
        anyhow::bail!("--camera eye:{x},{y},{zs}: expected a place outside the obstacles (the eye is inside the {kind}, [[obstacle]] {} of the scenario)", i + 1);
    }
    let [tx, ty, tz] = e.target;
    let target = [tx, ty, if e.target_above_ground { site.elevation_at(tx.clamp(0.0, w), ty.clamp(0.0, h)) as f64 + tz } else { tz }];
    anyhow::ensure!((0..3).map(|k| (eye[k] - target[k]).powi(2)).sum::<f64>() >= 1e-6, "--camera: the eye and the target are the same point on the site ({:.1}, {:.1}, {:.1}); expected {EYE_FORM}", eye[0], eye[1], eye[2]);
    let f = |p: [f64; 3]| [p[0] as f32, p[1] as f32, p[2] as f32];
    let mut cam = sylva::render::camera::Camera::look_at(f(eye), f(target), e.fov_deg as f32);
    cam.near = cam.near.min(0.1).max(0.05);
    Ok(cam)
}

fn parse_render_camera(s: &str) -> Result<RenderCamera, String> {
    if let Some(e) = parse_eye(s) {
        return e.map(RenderCamera::Eye);
    }
    match sylva::job::hemi::parse_hemi(s) {
        Some(Ok((x, y))) => Ok(RenderCamera::Hemi(x, y)),
        Some(Err(e)) => Err(e.to_string()),
        None if s.eq_ignore_ascii_case("closeup") || s.eq_ignore_ascii_case("close-up") => Ok(RenderCamera::CloseUp),
        None => s.parse::<CameraPreset>().map(RenderCamera::Preset).map_err(|_| format!("camera `{s}`: expected overview, oblique, ground, map, closeup, hemi:X,Y or eye:X,Y,Z:TX,TY,TZ[:FOV]")),
    }
}

fn parse_on_off(s: &str) -> Result<bool, String> {
    match s.to_ascii_lowercase().as_str() {
        "on" | "true" | "yes" => Ok(true),
        "off" | "false" | "no" => Ok(false),
        _ => Err(format!("`{s}`: expected on or off")),
    }
}

/// Parses a season name (spring, summer, autumn or fall, winter).
pub fn parse_season(s: &str) -> Result<Season, String> {
    match s.to_ascii_lowercase().as_str() {
        "spring" => Ok(Season::Spring),
        "summer" => Ok(Season::Summer),
        "autumn" | "fall" => Ok(Season::Autumn),
        "winter" => Ok(Season::Winter),
        _ => Err(format!("season `{s}`: expected spring, summer, autumn (or fall) or winter")),
    }
}

/// Arguments of `sylva render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: PathBuf,
    /// Snapshot year (default: the last one).
    #[arg(long)]
    pub year: Option<u32>,
    /// Camera preset: overview, oblique, ground, map, closeup (the close-up still of `sylva run`,
    /// drawn as the run draws it); or `hemi:X,Y`, a virtual hemispherical
    /// photograph (upward equisolid fisheye from 1.3 m at X, Y in metres; a square image of the
    /// size's smaller side; `--stats` gives gap_fraction, openness and simulated_light); or
    /// `eye:X,Y,Z:TX,TY,TZ[:FOV]`, a camera of one's own: the eye and the point looked at in
    /// site metres (x, y from the terrain's south-west corner as the inventory's x_m, y_m; z the
    /// elevation, as the DEM's heights, or `+H` for H metres above the ground at that x, y, e.g.
    /// `eye:380,330,+1.7:450,160,+10`), the vertical field of view in degrees (default 50).
    #[arg(long, default_value = "oblique", value_parser = parse_render_camera)]
    pub camera: RenderCamera,
    /// Season of the foliage: spring, summer, autumn (or fall), winter.
    #[arg(long, default_value = "summer", value_parser = parse_season)]
    pub season: Season,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    pub out: PathBuf,
    /// Folder of extra or edited species files, over the shipped library and the run's own
    /// `species/` folder (written by `simulate`/`run`).
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// Trees near the camera adapted to their neighbours and obstacles (Plastic Trees) with
    /// their own meshes (on), or every tree its species' open-grown prototype (off).
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    pub adapt: bool,
    /// Most tree triangles the frame draws (1,000–1,000,000,000): when the trees at their
    /// levels would cost more, the level switches are raised so that the trees smallest on
    /// screen (the farthest of a height) drop to coarser levels first, never below billboards
    /// (one factor on every tree's switch sizes: under a tight budget the nearest trees leave
    /// full detail too). `--stats` says whether it demoted
    /// (`demoted`, `lod_scale`). Default: the stills' budget of `sylva run`.
    #[arg(long, default_value_t = sylva::job::pictures::STILL_TRIANGLE_BUDGET, value_parser = clap::value_parser!(u32).range(1_000..=1_000_000_000))]
    pub triangle_budget: u32,
    /// Write the frame's figures as JSON (adapted_trees, adapt_s, unique_meshes (one chain of
    /// level meshes per species, obstacle and adapted tree), cluster_hulls and hull_triangles
    /// (the adapted trees' mid-level crown hulls of their leaf clusters, in those chains),
    /// instanced_trees, triangles (drawn), per_level (instances drawn per level),
    /// adapted_per_level (the adapted trees among them), frame_s; trees (live trees of the
    /// snapshot), trees_15m, nodes_median and nodes_min (skeleton nodes of the adapted trees of
    /// 15 m and taller), leaf_cards (of the adapted trees), sprig_cards (leaf-cluster cards carrying the rest of the full-detail trees' crown leaf area, as exports do), adapted_leaf_area_m2 and leaf_area_m2 (one-sided leaf area of the full-detail trees: their adapted leaf cards, and what their full level carries: the crowns' leaf area), mesh_bytes (CPU bytes of the adapted trees' level meshes), full_held_back (trees among the 200 largest on screen kept from full detail by the budget of 3 M leaf cards and nodes), stumps (harvested trees drawn as
    /// stumps: cut in the 20 years up to the year; their two instances each are among the
    /// instances drawn); tree_triangles (the trees' share of triangles), triangle_budget,
    /// demoted (whether the budget raised the level switches) and lod_scale (by what factor),
    /// small_tree_m (the reference height under which trees took the level of a tree that tall
    /// where they stand: 25 m, lowered to 12 m at the least where the budget binds) and
    /// levels_raised (trees it drew finer than the 12 m reference would), full_level_trees and bare_full_level (adapted trees tall enough on screen for the full
    /// level, and those of them carrying under half their crown's leaf area)). Its folder is
    /// made when missing.
    #[arg(long)]
    pub stats: Option<PathBuf>,
}

/// Arguments of `sylva timelapse`.
#[derive(clap::Args)]
pub struct TimelapseArgs {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: PathBuf,
    /// Camera preset (overview, oblique, ground, map); a slow orbit when omitted.
    #[arg(long, value_parser = parse_camera)]
    pub camera: Option<CameraPreset>,
    /// Frames per second (1–100; checked before any frame is drawn).
    #[arg(long, default_value_t = 12.0, value_parser = parse_fps)]
    pub fps: f32,
    /// Interpolated frames between snapshots a regular interval apart (0–50; 0: one frame per snapshot); shorter or longer intervals get frames in proportion to their years.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=50))]
    pub frames_between: u32,
    /// Frame size WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Season of the foliage: spring, summer, autumn (or fall), winter.
    #[arg(long, default_value = "summer", value_parser = parse_season)]
    pub season: Season,
    /// Output GIF (frames go to a `frames/` folder beside it; MP4 too when ffmpeg is found).
    #[arg(long, default_value = "forest.gif")]
    pub out: PathBuf,
    /// Folder of extra or edited species files, over the shipped library and the run's own
    /// `species/` folder (written by `simulate`/`run`).
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
}

/// Builds the render stage of a run directory from its `scenario.toml`.
///
/// Species: the shipped library, overlaid by the run's `species/` folder when it has one, then
/// by `species_dir`.
pub fn stage_for(run_dir: &Path, species_dir: Option<&Path>) -> anyhow::Result<Stage> {
    stage_for_checked(run_dir, species_dir, &|_| Ok(()))
}

/// [`stage_for`] with `check` called on the run's site as soon as it is read, before the
/// species files are read and the stage built (a camera checked against the site: trial 46
/// D11).
///
/// Errors: those of [`stage_for`] and of `check`.
pub fn stage_for_checked(run_dir: &Path, species_dir: Option<&Path>, check: &dyn Fn(&sylva::conditions::SiteConditions) -> anyhow::Result<()>) -> anyhow::Result<Stage> {
    super::check_run_dir(run_dir, "RUN")?;
    let sc_path = run_dir.join("scenario.toml");
    let sc = Scenario::load(&sc_path).with_context(|| format!("{} is not a Sylva run directory", run_dir.display()))?;
    let site = super::simulate::load_site(&sc)?;
    check(&site)?;
    let run_species = super::simulate::run_species_dir(run_dir);
    let mut dirs: Vec<&Path> = Vec::new();
    if run_species.is_dir() {
        dirs.push(&run_species);
    }
    dirs.extend(species_dir);
    let lib = super::simulate::library(&dirs)?;
    Ok(Stage::for_scenario(&sc, site, lib)?)
}

/// Renders a still.
pub fn render(a: RenderArgs) -> anyhow::Result<()> {
    if a.out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) != Some("png".into()) {
        anyhow::bail!("--out {}: stills are written as PNG; give a file name ending in .png", a.out.display());
    }
    super::check_out_file(&a.out, "--out")?;
    // the folders --out needs are made now (so that a folder that cannot be made is said before
    // the picture is drawn) and removed again, if still empty, when the render fails (trial 37:
    // a failed render left an empty folder tree)
    let made = missing_folders(&a.out);
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("--out {}: creating its folder {}", a.out.display(), dir.display()))?;
    }
    let res = render_checked(a);
    if res.is_err() {
        for d in made.iter() {
            let _ = std::fs::remove_dir(d); // only an empty folder goes
        }
    }
    res
}

/// The folders above `p` that do not exist yet, deepest first.
fn missing_folders(p: &Path) -> Vec<std::path::PathBuf> {
    p.ancestors().skip(1).filter(|d| !d.as_os_str().is_empty()).take_while(|d| !d.exists()).map(Path::to_path_buf).collect()
}

/// [`render`] once the folder of `--out` exists.
fn render_checked(a: RenderArgs) -> anyhow::Result<()> {
    super::check_out_file(&a.out, "--out")?;
    // the statistics file is checked before the picture is drawn, so that a bad path does not
    // leave the picture without its statistics
    if let Some(p) = &a.stats {
        super::check_stats_path(p)?;
        anyhow::ensure!(p != &a.out, "--stats {}: the same file as --out; give the statistics their own file (e.g. stats.json)", p.display());
    }
    warn_large_size(a.size);
    let (camera, closeup, eye) = match a.camera {
        RenderCamera::Preset(p) => (p, false, None),
        RenderCamera::CloseUp => (CameraPreset::Oblique, true, None),
        RenderCamera::Eye(e) => (CameraPreset::Oblique, false, Some(e)),
        RenderCamera::Hemi(x, y) => return hemi(&a, x, y),
    };
    super::check_run_dir(&a.run_dir, "RUN")?;
    if let Some(y) = a.year {
        pictures::check_snapshot_year(&a.run_dir, y)?;
    }
    // a camera of one's own is checked against the site as soon as that is read, before the
    // species and the stage (trial 46 D11), and against the stage's obstacles once it is built,
    // all before the snapshot is read
    let mut stage = stage_for_checked(&a.run_dir, a.species_dir.as_deref(), &|site| eye.as_ref().map_or(Ok(()), |e| check_eye_on_site(e, site).map(|_| ())))?;
    let eye = eye.map(|e| check_eye(&e, &stage)).transpose()?;
    let year = match a.year {
        Some(y) => y,
        None => sylva::job::inventory::snapshots(&a.run_dir)?.iter().map(|s| s.0).max().with_context(|| format!("{}: the run directory has no snapshots (inventory/year_NNNN.parquet or .csv)", a.run_dir.display()))?,
    };
    let rows = pictures::snapshot_rows(&a.run_dir, year)?;
    let unknown = rows.iter().filter(|r| stage.library.find(&r.species).is_none()).count();
    if unknown > 0 {
        tracing::warn!("{unknown} trees of species not in the library are not drawn (give their species files with --species-dir)");
    }
    let cam = match eye {
        Some(c) => c,
        None if closeup => sylva::job::main_job::closeup_camera(&stage.site),
        None => stage.camera_for(camera, &rows, a.size.0, a.size.1),
    };
    if !a.adapt {
        stage.set_adapt(None);
    }
    stage.set_triangle_budget(a.triangle_budget);
    let t = std::time::Instant::now();
    // the regeneration layer of the same snapshot, drawn as saplings (runs without it: none)
    let regen = if closeup { Vec::new() } else { sylva::job::inventory::read_regeneration(&a.run_dir, year)?.unwrap_or_default() };
    // the stumps of the trees harvested in the 20 years up to the picture's year
    let stumps = pictures::harvest_stumps(&a.run_dir, year)?;
    stage.set_stumps(&stumps, year);
    let stumps_drawn = stage.stump_instance_count() / 2;
    // the rows' figures for the statistics now: the rows (two strings a tree) and the
    // regeneration table are not held while the frame is drawn (issue 34)
    let trees = rows.iter().filter(|r| r.status == "alive" && stage.library.find(&r.species).is_some()).count();
    let mut names: Vec<String> = rows.iter().map(|r| r.species.as_str()).chain(regen.iter().map(|r| r.species.as_str())).collect::<std::collections::BTreeSet<_>>().into_iter().map(String::from).collect();
    names.shrink_to_fit();
    let name = |s: &str| names.binary_search_by(|n| n.as_str().cmp(s)).map_or("", |i| names[i].as_str());
    let plants: Vec<sylva::job::scene::Plant> = sylva::job::scene::plants_from_rows(&rows)
        .into_iter()
        .map(|p| sylva::job::scene::Plant { id: p.id, species: name(p.species), x_m: p.x_m, y_m: p.y_m, height_m: p.height_m, crown_radius_m: p.crown_radius_m, age_yr: p.age_yr, crown_base_m: p.crown_base_m, alive: p.alive })
        .collect();
    drop(rows);
    let saplings: Vec<sylva::job::scene::SaplingCohort> = sylva::job::scene::saplings_from_rows(&regen)
        .into_iter()
        .map(|c| sylva::job::scene::SaplingCohort { cell: c.cell, species: name(c.species), x_m: c.x_m, y_m: c.y_m, cell_m: c.cell_m, stems: c.stems, height_m: c.height_m })
        .collect();
    drop(regen);
    let mut img = stage.render_plants_with(&plants, &saplings, a.season, &cam, a.size.0, a.size.1)?;
    drop((plants, saplings));
    // a north arrow on every picture but the map's (north up)
    if closeup || eye.is_some() || camera != CameraPreset::Map {
        sylva::render::overlay::stamp_north_arrow(&mut img, &cam);
    }
    let frame_s = t.elapsed().as_secs_f64();
    sylva::output::pictures::write_png(&a.out, &img)?;
    let st = stage.renderer.last_stats();
    if let Some(path) = &a.stats {
        let ad = stage.last_adapt;
        let j = serde_json::json!({
            "year": year, "adapt": a.adapt, "adapted_trees": ad.adapted_trees, "adapt_s": ad.adapt_s, "mesh_s": ad.mesh_s,
            "trees_in_groups": ad.trees_in_groups, "unique_meshes": stage.library.species.len() + stage.obstacles.len() + ad.adapted_trees,
            "cluster_hulls": ad.cluster_hulls, "hull_triangles": ad.hull_triangles, "per_level": st.per_level, "adapted_per_level": ad.per_level,
            "instanced_trees": st.instances_drawn.saturating_sub(ad.adapted_trees), "instances_drawn": st.instances_drawn, "triangles": st.triangles, "frame_s": frame_s,
            "trees": trees,
            "stumps": stumps_drawn, "trees_15m": ad.trees_15m, "nodes_median": ad.nodes_median, "nodes_min": ad.nodes_min, "leaf_cards": ad.leaf_cards, "sprig_cards": ad.sprig_cards, "adapted_leaf_area_m2": ad.adapted_leaf_area_m2, "leaf_area_m2": ad.leaf_area_m2, "mesh_bytes": ad.mesh_bytes, "full_held_back": ad.full_held_back,
            "tree_triangles": st.tree_triangles, "triangle_budget": a.triangle_budget, "demoted": st.lod_scale > 1.0, "lod_scale": st.lod_scale,
            "small_tree_m": st.small_tree_m, "levels_raised": st.levels_raised,
            "full_level_trees": ad.full_level_trees, "bare_full_level": ad.bare_full_level, "shed_bare": ad.shed_bare,
        });
        super::write_stats(path, &j)?;
    }
    let stumps_note = if stumps_drawn > 0 { format!(", {stumps_drawn} stumps of harvested trees") } else { String::new() };
    let demoted = if st.lod_scale > 1.0 { format!(" (the triangle budget of {} lowered the trees' levels: switch sizes ×{:.2})", a.triangle_budget, st.lod_scale) } else { String::new() };
    eprintln!("year {year}: {} trees drawn as meshes or billboards, {} more in the far-field canopy layer{stumps_note}, {} triangles{demoted} → {}", st.instances_drawn, st.canopy_trees, st.triangles, a.out.display());
    Ok(())
}

/// `sylva render --camera hemi:X,Y`: the hemispherical photograph ([`sylva::job::hemi`]).
fn hemi(a: &RenderArgs, x: f64, y: f64) -> anyhow::Result<()> {
    super::check_run_dir(&a.run_dir, "RUN")?;
    let lib = super::simulate::run_library(&a.run_dir, a.species_dir.as_deref())?;
    let o = sylva::job::hemi::HemiOptions { year: a.year, x_m: x, y_m: y, size_px: a.size.0.min(a.size.1) };
    let (img, st) = sylva::job::hemi::hemispherical_photo(&a.run_dir, &lib, &o)?;
    sylva::output::pictures::write_png(&a.out, &image::DynamicImage::ImageRgb8(img).to_rgba8())?;
    if let Some(path) = &a.stats {
        super::write_stats(path, &serde_json::to_value(&st)?)?;
    }
    eprintln!("year {}: hemispherical photograph at {x},{y} ({} trees within {} m): gap fraction {:.3}, simulated light {:.3} → {}", st.year, st.trees, sylva::job::hemi::VIEW_RADIUS_M, st.gap_fraction, st.simulated_light, a.out.display());
    Ok(())
}

/// Renders a timelapse.
pub fn timelapse(a: TimelapseArgs) -> anyhow::Result<()> {
    if a.out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) != Some("gif".into()) {
        anyhow::bail!("--out {}: the timelapse is written as an animated GIF (plus an MP4 beside it when ffmpeg is installed); give a file name ending in .gif", a.out.display());
    }
    super::check_out_file(&a.out, "--out")?;
    let mut stage = stage_for(&a.run_dir, a.species_dir.as_deref())?;
    let frames_dir = a.out.parent().unwrap_or(Path::new(".")).join("frames");
    warn_large_size(a.size);
    let opts = TimelapseOptions { width: a.size.0, height: a.size.1, fps: a.fps, frames_between: a.frames_between, camera: a.camera, season: a.season };
    let pb = super::progress(1, "timelapse");
    let t0 = std::time::Instant::now();
    let (n, mp4) = pictures::timelapse(&mut stage, &a.run_dir, &frames_dir, &a.out, &opts, &mut |done, total| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
        pb.set_message(format!("{:.1} frames/s", done as f64 / t0.elapsed().as_secs_f64().max(1e-3)));
    })?;
    pb.finish();
    let mp4_note = if mp4 {
        " (+ MP4)"
    } else if sylva::output::pictures::find_ffmpeg().is_none() {
        " (no MP4: ffmpeg is not on PATH)"
    } else {
        " (no MP4: ffmpeg failed)"
    };
    eprintln!("{n} frames → {}{mp4_note}", a.out.display());
    Ok(())
}
