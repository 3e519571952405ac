//! Stand export (issue 14, Build 4; `sylva export RUN_DIR --year Y --area X0,Y0,X1,Y1 --out
//! stand.glb`): the live trees of an area of a run's snapshot, each with its own skeleton
//! adapted to its neighbours, the light and the obstacles by [`adapt_stand`] (Plastic Trees,
//! Pirk et al. 2012, `000_*.txt`; the same near-field adaptation `job::adapted` does for the
//! pictures), meshed with its levels of detail (the mid level: the crown hull of its adapted leaf
//! clusters, [`super::adapted::adapted_lod_chain`]), with the terrain patch under the area (its
//! leaf-litter texture, [`terrain_static`]), the regeneration layer's saplings ([`area_saplings`])
//! and the scenario's obstacles that reach into it, as one glTF scene
//! ([`crate::output::gltf::StandScene`]).
//!
//! **Instancing.** Trees whose adapted skeletons have the same topology and the same shape once
//! divided by their crown radius (x, y) and height (z), within [`SAME_SHAPE`], share one mesh
//! per level, each tree's node scaling it (trees of one species, age and size class that their
//! neighbours did not touch: the analysis is shared, `structure::stand`), the LOD3 billboard
//! (the model's own impostor: crown quads over its crown, a trunk quad to the root) included.
//!
//! **Coordinates.** The scene's origin is the area's centre at the lowest terrain elevation of
//! the patch (metres; x east, y north, z up in Sylva, y up in the file); the scene's `extras`
//! record the origin in the run's world coordinates, the run directory, the year and the area.

use super::adapted::{median_usize, obstacle_mesh, solids, stand_trees, tree_frame, OBSTACLE_RGB, STATS_MIN_HEIGHT_M};
use super::scene::plants_from_rows;
pub use super::leaf_area::{fill_leaf_area, sprig_cards, MAX_CARDS_PER_LEAF, MAX_CARD_GROWTH, SPRIG_MAX_INCLINATION};
use super::Result;
use crate::conditions::SiteConditions;
use crate::error::Error;
use crate::mesh::{TriMesh, LOD_LEVELS};
use crate::output::gltf::{Look, StandCounts, StandModel, StandNode, StaticMesh};
use crate::sim::Scenario;
use crate::species::{Season, SpeciesLibrary};
use crate::structure::mesh::LodOptions;
use crate::structure::stand::{adapt_stand, StandOptions};
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Forest-floor colour of the terrain patch (sRGB 82, 79, 60): the pictures' forest floor of
/// leaf litter, [`crate::render::terrain::FOREST_FLOOR`] (linear 0.085, 0.078, 0.045), in sRGB
/// (until round 40 an untextured 96, 84, 62).
pub const GROUND_RGB: [u8; 3] = [82, 79, 60];

/// The terrain patch of an export: the forest floor in [`GROUND_RGB`] with its leaf-litter
/// texture ([`crate::structure::texture::litter_texture`], repeating once a metre: the patch's
/// texture coordinates are metres east and north of the area's centre, [`terrain_patch`]), so
/// that an eye-level render shows a textured floor as the stills' ground view does (round 39's
/// trial: flat and untextured).
pub fn terrain_static(mesh: TriMesh) -> StaticMesh {
    let texture = crate::structure::texture::litter_texture(GROUND_RGB, crate::structure::texture::TEXTURE_PX, 0x6c69_7474);
    StaticMesh { name: "terrain".into(), mesh, rgb: GROUND_RGB, roughness: 0.95, texture: Some(texture) }
}

/// Largest difference (a fraction of the tree's height or crown radius; for leaf directions,
/// of a unit vector) between two trees' canonical shapes that still share one mesh: 10⁻³, 1 cm
/// on a 10 m tree, well above the rounding of adapting the same tree at another place.
pub const SAME_SHAPE: f32 = 1e-3;

/// Most trees an export adapts (the area's live trees; a larger area is refused).
pub const DEFAULT_MAX_TREES: usize = 5000;

/// Largest estimated file ([`estimate_stand_bytes`]) a stand export writes by default: 3.5 GiB,
/// below the GLB's 4 GiB limit (its length fields are 32 bits) with room for the estimate's
/// error. The command line lowers it to half the machine's available memory where that is
/// less ([`ExportOptions::max_bytes`]).
pub const DEFAULT_MAX_BYTES: u64 = 7 << 29;

/// Bytes a stand export writes per skeleton node of a tree at its full level (ESTIMATE, fitted
/// to full-detail exports of main `686ed97` and this round: bark rings, about 2.5 leaf cards a
/// node and the sprigs that carry the rest of the crown's leaf area, 0.86 a node whatever the
/// tree's age, since a younger tree of fewer strands draws larger cards; 13–14 triangles of
/// about 60 bytes a node). Measured per node: the default run's year 150, 25 m area
/// `1150,850,1175,875` (94 trees, 89,884 nodes by [`estimated_nodes`], 90,193 written) 72.1 MB,
/// 802 bytes; its 0.25 ha `1150,850,1200,900` (466 trees, 492,712 nodes) 387.4 MB, 786 bytes;
/// its hectare `1000,800,1100,900` (2,272 trees, 3.03 M nodes) 2.2 GB, about 730 bytes (trial
/// 37); 30-year beech planted at 5 m (160 trees, 48,000 nodes) 43.7 MB, 910 bytes; 25-year
/// Norway spruce (6 trees, 7,608 nodes: shoot cards, no leaf cards) 5.0 MB, 660 bytes. A
/// capped export (`--max-strands 48`) copies its few leaf cards to the crown's leaf area: about
/// 1,100 bytes a node (the 0.25 ha: 51 MB), above this estimate by 1.4×. These are float files
/// (`--no-quantize`); a default export, quantised since round 46, writes about half of them
/// (trial 45's 0.25 ha counted by `tools/glb_quantised_size.py`: 0.51), so the estimate is an
/// upper bound for the cap.
pub const EST_BYTES_PER_NODE: f64 = 800.0;

/// Bytes of an export besides its trees' levels: textures, terrain, obstacles, JSON
/// (ESTIMATE: 1–2 MB in the exports above).
pub const EST_FIXED_BYTES: f64 = 1.0e6;

/// Size of each level of detail against the full level (ESTIMATE from trial 37's hill export:
/// `--lod all` wrote 3.75 MB against 2.94 MB for the full level alone; the hull and the
/// billboard are small).
pub const EST_LEVEL_SHARE: [f64; LOD_LEVELS] = [1.0, 0.25, 0.02, 0.01];

/// Skeleton nodes a stand tree of species `sp` at `age_yr` gets from a skeleton cache of
/// `max_strands` strands: two a strand ([`crate::structure::species_tree::ecomod_strands_at`]
/// of the species' strand count at its age, at most `max_strands`).
pub fn estimated_nodes(sp: &crate::species::Species, age_yr: f32, max_strands: u32) -> usize {
    2 * crate::structure::species_tree::ecomod_strands_at(sp.architecture.ecomod.strands, age_yr).min(max_strands.max(8)) as usize
}

/// Size (bytes) of a stand export above which `sylva export` points at the options that
/// shrink it ([`large_export_hint`]): 300 MB (issue 32's artist trial 45: a 552 MB export took
/// Debian's Blender 3.4 391 s and 8.2 GB of memory to import).
pub const LARGE_EXPORT_BYTES: u64 = 300_000_000;

/// The line `sylva export` prints after writing a stand of `bytes` bytes, when that is above
/// [`LARGE_EXPORT_BYTES`]: the options that make it smaller, those not already given
/// (`quantized`: the meshes were quantised; `max_strands`: the skeletons' cap, `--max-strands`;
/// `levels`: the levels written). `None` for a smaller file.
pub fn large_export_hint(bytes: u64, quantized: bool, max_strands: u32, levels: &[usize]) -> Option<String> {
    if bytes <= LARGE_EXPORT_BYTES {
        return None;
    }
    let mut ways = Vec::new();
    if !quantized {
        ways.push("leave out --no-quantize (about a third of the bytes)".to_string());
    }
    if levels.len() > 1 {
        ways.push("--lod 0 (the full level only)".to_string());
    }
    if max_strands == crate::structure::stand::FULL_STRANDS {
        ways.push("--max-strands 48 (lighter skeletons: about a tenth of the bytes)".to_string());
    }
    ways.push("a smaller --area".to_string());
    ways.push("--instances (the whole forest as instances of shared models, a few MB)".to_string());
    Some(format!("the file is {:.0} MB (over {:.0} MB, slow to import: Blender 3.4 took 391 s and 8.2 GB for 552 MB); to make it smaller: {}", bytes as f64 / 1e6, LARGE_EXPORT_BYTES as f64 / 1e6, ways.join(", ")))
}

/// What an export of some trees will write, estimated before any tree is grown
/// ([`estimate_stand_bytes`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExportEstimate {
    /// Trees.
    pub trees: usize,
    /// Skeleton nodes ([`estimated_nodes`]).
    pub nodes: usize,
    /// Bytes of the file.
    pub bytes: u64,
}

/// The size of a stand export of `trees` (species index into `library` and age in years) at
/// `levels` with skeletons of at most `max_strands` strands, before any work:
/// [`EST_BYTES_PER_NODE`] × nodes × the written levels' [`EST_LEVEL_SHARE`] +
/// [`EST_FIXED_BYTES`]: within 0.9–1.4× of what the exports named at [`EST_BYTES_PER_NODE`]
/// wrote.
pub fn estimate_stand_bytes(trees: impl IntoIterator<Item = (usize, f32)>, library: &SpeciesLibrary, max_strands: u32, levels: &[usize]) -> ExportEstimate {
    let mut e = ExportEstimate::default();
    for (sp, age) in trees {
        let Some(sp) = library.species.get(sp) else { continue };
        e.trees += 1;
        e.nodes += estimated_nodes(sp, age, max_strands);
    }
    let share: f64 = levels.iter().filter_map(|&l| EST_LEVEL_SHARE.get(l)).sum();
    e.bytes = (EST_BYTES_PER_NODE * e.nodes as f64 * share + EST_FIXED_BYTES) as u64;
    e
}

/// What to export.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    /// Snapshot year (`inventory/year_NNNN.csv`); `None`: the last one.
    pub year: Option<u32>,
    /// Area `[x0, y0, x1, y1]` (m, world coordinates from the terrain's south-west corner;
    /// x0 < x1, y0 < y1, inside the terrain).
    pub area: [f64; 4],
    /// Season of the foliage colours.
    pub season: Season,
    /// Levels of detail written (indices below [`LOD_LEVELS`]): by default only the full-detail
    /// mesh (level 0), so that every tree is one visible mesh in Blender, three.js or a glTF
    /// viewer, which show every node; [`all_levels`] for the LOD groups of game engines.
    pub levels: Vec<usize>,
    /// Most trees (refused beyond: [`DEFAULT_MAX_TREES`] by default).
    pub max_trees: usize,
    /// Largest estimated file (bytes, [`estimate_stand_bytes`]): a larger export is refused
    /// before any tree is grown ([`DEFAULT_MAX_BYTES`] by default).
    pub max_bytes: u64,
    /// What sets [`ExportOptions::max_bytes`], for the refusal's message (by default "the
    /// GLB's 4 GiB limit, less room for the estimate's error").
    pub max_bytes_source: String,
    /// Most EcoMod strands of a tree's skeleton (≥ 8; 2 nodes a strand):
    /// [`crate::structure::stand::DEFAULT_MAX_STRANDS`] by default;
    /// [`crate::structure::stand::FULL_STRANDS`] gives every tree its species' strand count at
    /// its age, as `sylva tree grow` gives it (`--full-detail`, `--max-strands`).
    pub max_strands: u32,
    /// Side (texels) of the leaf-cluster, crown, impostor and bark textures; the leaf card's
    /// is half as wide ([`crate::structure::texture::FoliageTextures::for_species_sized`]):
    /// [`crate::structure::texture::TEXTURE_PX`] by default, a power of two from 256 to 4096
    /// (`--texture-size`, [`crate::output::gltf::check_texture_size`]).
    pub texture_px: u32,
    /// Whether the trees' meshes are quantised (`KHR_mesh_quantization`,
    /// [`crate::output::gltf::Quant`]: 16-bit positions, 8-bit normals, 16-bit card texture
    /// coordinates and indices; about a third of the bytes): on by default, off with
    /// `--no-quantize` for an importer without the extension.
    pub quantize: bool,
}

impl ExportOptions {
    /// The last year, summer, the full-detail level only, [`DEFAULT_MAX_TREES`], full detail
    /// ([`crate::structure::stand::FULL_STRANDS`]: every strand of the species at the tree's
    /// age, grown as a forest tree; since round 22, when its adaptation became fast enough: the
    /// issue's 0.25 ha in about 10 s).
    pub fn new(area: [f64; 4]) -> ExportOptions {
        ExportOptions {
            year: None,
            area,
            season: Season::Summer,
            levels: vec![0],
            max_trees: DEFAULT_MAX_TREES,
            max_bytes: DEFAULT_MAX_BYTES,
            max_bytes_source: "the GLB's 4 GiB limit, less room for the estimate's error".into(),
            texture_px: crate::structure::texture::TEXTURE_PX,
            max_strands: crate::structure::stand::FULL_STRANDS,
            quantize: true,
        }
    }
}

/// Every level of detail, `0..LOD_LEVELS` (`--lod all`: `<name>_LOD0…3` under each tree's node,
/// as Unity's and Unreal's importers group them).
pub fn all_levels() -> Vec<usize> {
    (0..LOD_LEVELS).collect()
}

/// Parses `--lod` of `sylva export`: `all` ([`all_levels`]) or a comma-separated list of levels,
/// e.g. `0` or `0,1` ([`parse_levels_for`] with the command `sylva export`).
///
/// Errors: [`Error::Invalid`] naming `--lod` for anything else or a level ≥ [`LOD_LEVELS`].
pub fn parse_levels(s: &str) -> Result<Vec<usize>> {
    parse_levels_for("sylva export", s)
}

/// Parses `--lod` of `command` (e.g. `sylva tree grow`), as [`parse_levels`]; the error names
/// `command`, so a user of `tree grow` is not told about `sylva export` (round 39's trial).
///
/// Errors: [`Error::Invalid`] with context `command`, naming `--lod`, for anything but `all` or
/// levels 0–3 separated by commas.
pub fn parse_levels_for(command: &str, s: &str) -> Result<Vec<usize>> {
    if s.trim().eq_ignore_ascii_case("all") {
        return Ok(all_levels());
    }
    let v: Vec<Option<usize>> = s.split(',').map(|p| p.trim().parse::<usize>().ok().filter(|&l| l < LOD_LEVELS)).collect();
    match v.iter().copied().collect::<Option<Vec<usize>>>() {
        Some(mut l) if !l.is_empty() => {
            l.sort_unstable();
            l.dedup();
            Ok(l)
        }
        _ => Err(Error::Invalid {
            context: command.into(),
            field: "--lod".into(),
            value: s.into(),
            expected: format!("`all` or levels 0–{} separated by commas, e.g. 0 (full detail, the default) or 0,1,2,3", LOD_LEVELS - 1),
        }
        .into()),
    }
}

/// What [`export_stand`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportReport {
    /// The file.
    pub out: PathBuf,
    /// Snapshot year exported.
    pub year: u32,
    /// Trees in the scene.
    pub trees: usize,
    /// Saplings of the regeneration layer in the scene (a stand export's; 0 for
    /// [`export_instances`]).
    pub saplings: usize,
    /// Distinct tree models (sets of LOD meshes), the saplings' included.
    pub models: usize,
    /// Obstacles in the scene.
    pub obstacles: usize,
    /// Triangles of the terrain patch.
    pub terrain_triangles: usize,
    /// Meshes, mesh nodes and images written.
    pub counts: StandCounts,
    /// Wall time of the adaptation (s).
    pub adapt_s: f64,
    /// Size of the file (bytes).
    pub bytes: u64,
    /// Figures of the trees written ([`ExportStats`]).
    pub stats: ExportStats,
    /// Most bytes of tree meshes (vertex and index data, [`TriMesh::byte_size`], of the
    /// levels written) held in memory at once: a stand export meshes its trees a batch of
    /// [`MESH_BATCH_PER_THREAD`] a thread at a time and writes each batch's models to the
    /// file's scratch buffer while the next is meshed, so at most two batches are held (round
    /// 38: every tree's meshes were held until the file was written, about twice the file in
    /// memory). 0 for [`export_instances`].
    pub held_mesh_bytes_max: usize,
}

/// Trees a thread meshes per batch of a stand export ([`ExportReport::held_mesh_bytes_max`]):
/// enough to keep the threads busy while the batch is written, few enough that the meshes
/// held stay a few trees' (a canopy tree's full level is about 1 MB).
pub const MESH_BATCH_PER_THREAD: usize = 2;

/// Bytes of the vertex and index data of a stand model ([`TriMesh::byte_size`]): its chain's
/// levels and its sprigs.
fn model_bytes(m: &StandModel) -> usize {
    m.chain.levels.iter().map(|l| l.bark.byte_size() + l.leaves.byte_size()).sum::<usize>() + m.sprigs.byte_size()
}

/// Figures of an export (`sylva export --stats FILE.json`).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct ExportStats {
    /// Trees written.
    pub trees: usize,
    /// Saplings of the regeneration layer written (a stand export's, [`area_saplings`]; not
    /// counted in the other figures but `triangles`).
    pub saplings: usize,
    /// Trees of [`STATS_MIN_HEIGHT_M`] and taller among them.
    pub trees_15m: usize,
    /// Median skeleton node count of the adapted trees of [`STATS_MIN_HEIGHT_M`] and taller (0
    /// when there are none).
    pub nodes_median: usize,
    /// Smallest skeleton node count among them (0 when there are none).
    pub nodes_min: usize,
    /// Leaf cards of the full-detail meshes of all trees written (each tree counted, shared
    /// meshes too; conifers at full detail draw none: their shoot cards are counted in
    /// [`ExportStats::sprig_cards`]).
    pub leaf_cards: usize,
    /// Leaf-cluster cards of the full-detail meshes of all trees written: the sprigs of
    /// broadleaves ([`sprig_cards`]) and the shoot cards of conifers
    /// ([`super::leaf_area::shoot_cards`], two a shoot) at the full strand count; 0 otherwise.
    /// For [`export_instances`], the leaf-cluster cards of each tree's model at level 0
    /// ([`super::leaf_area::lone_chain`]), each tree counted.
    pub sprig_cards: usize,
    /// Wall time of the adaptation (s): growing and analysing the open-grown trees
    /// ([`ExportStats::analysis_s`]) and adapting the neighbourhoods
    /// ([`ExportStats::adaptation_s`]).
    pub adapt_s: f64,
    /// Wall time (s) from growing the open-grown skeletons until their last Plastic Trees
    /// analysis is done (`000_*.txt` section 4; one per class of species, age, height, crown
    /// radius and crown base); neighbourhoods whose classes are analysed are adapted meanwhile
    /// ([`crate::structure::stand::Stand::analysis_s`]).
    pub analysis_s: f64,
    /// Wall time (s) of adapting the neighbourhoods left after the last analysis (section 5).
    pub adaptation_s: f64,
    /// Wall time (s) of reading the snapshot's rows around the area and making the stand's
    /// trees, before the adaptation (a stand export's; 0 for [`export_instances`]).
    pub read_s: f64,
    /// Wall time (s) of meshing the adapted trees (leaf cards, sprigs, bark, the levels of
    /// detail; the threads' batches, [`MESH_BATCH_PER_THREAD`]) while no batch was being
    /// written: meshing that overlapped the writing of the batch before is in
    /// [`ExportStats::write_s`] (a stand export's; 0 for [`export_instances`]).
    pub mesh_s: f64,
    /// Wall time (s) of encoding the trees' models into the glb's buffer (quantisation,
    /// buffer views, its scratch file) and making their nodes, the meshing of the next batch
    /// running meanwhile (a stand export's; 0 for [`export_instances`]).
    pub write_s: f64,
    /// Wall time (s) of measuring the leaf covers ([`leaf_covers`]), baking the drawn species'
    /// textures (leaf, cluster, crown, impostor, bark: [`stand_look`]) and the terrain's litter,
    /// which run beside the adaptation on the threads it leaves idle (so this overlaps
    /// [`ExportStats::adapt_s`]), and of the saplings' models (a stand export's; 0 for
    /// [`export_instances`]).
    pub texture_s: f64,
    /// Wall time (s) of finishing the file: the looks' materials and PNG textures, the
    /// terrain and obstacles, the JSON, and copying the scratch buffer into the file
    /// (a stand export's; 0 for [`export_instances`]).
    pub finish_s: f64,
    /// Wall time (s) of the whole export, reading the snapshot to renaming the file (a stand
    /// export's; 0 for [`export_instances`]).
    pub total_s: f64,
    /// Distinct analyses.
    pub analyses: usize,
    /// Skeleton nodes of all the adapted trees together.
    pub nodes_total: usize,
    /// Nodes of the fitted skeletons before the adaptation, all trees together
    /// ([`crate::structure::plastic::PlasticReport::nodes_before`]).
    pub nodes_before_adaptation: usize,
    /// Nodes the adaptation pruned for too little light (eq. 10 threshold), all trees.
    pub pruned_light: usize,
    /// Nodes pruned inside obstacles or neighbours' wood, all trees.
    pub pruned_collision: usize,
    /// Triangles of the written levels of all trees and saplings (each counted, shared meshes
    /// too) plus the terrain and obstacles.
    pub triangles: usize,
    /// Levels of detail written.
    pub levels: Vec<usize>,
    /// The triangles of every tree and sapling at each level 0–3, whether written or not (what
    /// a viewer draws with that level alone, terrain and obstacles left out): the written
    /// levels' entries plus the terrain's and obstacles' triangles make `triangles`. Round 42
    /// (trial 42): a stand export's list was empty.
    pub level_triangles: Vec<usize>,
}

impl ExportStats {
    /// The figures as a JSON object.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }
}


fn invalid(field: &str, value: String, expected: String) -> super::JobError {
    Error::Invalid { context: "sylva export".into(), field: field.into(), value, expected }.into()
}

/// Parses an area `X0,Y0,X1,Y1` (m).
///
/// Errors: [`Error::Invalid`] naming `--area` for anything but four finite numbers with
/// x0 < x1 and y0 < y1.
pub fn parse_area(s: &str) -> Result<[f64; 4]> {
    let v: Vec<f64> = s.split(',').map(|p| p.trim().parse::<f64>().unwrap_or(f64::NAN)).collect();
    if v.len() != 4 || v.iter().any(|x| !x.is_finite()) {
        return Err(invalid("--area", s.into(), "four numbers X0,Y0,X1,Y1 (m), e.g. 100,100,160,160".into()));
    }
    if !(v[0] < v[2] && v[1] < v[3]) {
        return Err(invalid("--area", s.into(), "X0 < X1 and Y0 < Y1 (the south-west, then the north-east corner)".into()));
    }
    Ok([v[0], v[1], v[2], v[3]])
}

/// What both exports start from: the run's scenario and site, the snapshot year (`year`, or the
/// last one), the levels checked, the area (`area`, or the whole site) checked to lie inside
/// the terrain.
fn open_export(run_dir: &Path, year: Option<u32>, levels: &[usize], area: Option<[f64; 4]>) -> Result<(Scenario, SiteConditions, u32, [f64; 4])> {
    let sc = Scenario::load(&run_dir.join("scenario.toml"))?;
    let site = sc.site()?;
    let year = match year {
        Some(y) => y,
        None => super::inventory::snapshots(run_dir)?.iter().map(|s| s.0).max().ok_or_else(|| Error::format(run_dir, "no inventory snapshots (inventory/year_NNNN.parquet or .csv)"))?,
    };
    if let Some(&l) = levels.iter().find(|&&l| l >= LOD_LEVELS) {
        return Err(invalid("--lod", l.to_string(), format!("levels 0–{}", LOD_LEVELS - 1)));
    }
    let (w, h) = (site.width() as f64 * site.cell_x_m, site.height() as f64 * site.cell_y_m);
    let area = area.unwrap_or([0.0, 0.0, w, h]);
    let [x0, y0, x1, y1] = area;
    if !(x0 < x1 && y0 < y1) || x0 < 0.0 || y0 < 0.0 || x1 > w || y1 > h {
        return Err(invalid("--area", format!("{x0},{y0},{x1},{y1}"), format!("X0 < X1, Y0 < Y1 inside the terrain, 0–{w:.1} m east and 0–{h:.1} m north")));
    }
    Ok((sc, site, year, area))
}

/// Whether `(x, y)` (m) lies in `area` `[x0, y0, x1, y1]` of a site `w` × `h` m: half-open
/// (`x0 ≤ x < x1`), except that an edge of the area on the site's east or north edge is
/// closed, so that trees standing exactly on the site's edge (seeded or planted there) are
/// exported with the whole site (`--instances` dropped them: found by a trial).
fn in_area(x: f64, y: f64, [x0, y0, x1, y1]: [f64; 4], w: f64, h: f64) -> bool {
    x >= x0 && (x < x1 || (x1 >= w && x <= x1)) && y >= y0 && (y < y1 || (y1 >= h && y <= y1))
}

/// Whether `out`'s folder, with `free` bytes available (`None`: unknown, no check), has room
/// for an export of `expected` bytes (`trees` trees). Errors: [`Error::Invalid`] naming `--out`,
/// the megabytes needed and free (trial 47 D5).
fn room_for(out: &Path, expected: u64, trees: usize, free: Option<u64>) -> Result<()> {
    match free {
        Some(free) if expected > free => {
            let mb = |b: u64| b as f64 / 1e6;
            Err(invalid("--out", format!("{}: about {:.0} MB needed ({trees} trees), {:.0} MB free there", out.display(), mb(expected), mb(free)), "a folder with room for the file, or a smaller --area; nothing was grown or written".into()))
        }
        _ => Ok(()),
    }
}

/// Exports the area of a run directory's snapshot to `out` (`.glb`, atomically). `library`:
/// the species as simulated (the caller overlays the run's `species/` folder).
///
/// Errors: [`Error::Format`] / [`Error::Io`] when `RUN_DIR/scenario.toml`, its terrain or the
/// snapshot cannot be read (a missing year names the years present); [`Error::Invalid`] naming
/// `--area` for an area outside the terrain or holding no live tree of the library (it says
/// where the trees are), naming `--lod` for a level ≥ [`LOD_LEVELS`], for more trees than
/// `max_trees`, and for a file estimated above `max_bytes` ([`estimate_stand_bytes`]: refused
/// before any tree is grown, naming `--area`, `--lod`, the cap and the estimate); naming
/// `--out` when its folder has less free space than the file's expected size (half the
/// estimate for a quantised file); the errors of
/// [`adapt_stand`], of reading the regeneration layer ([`area_saplings`]) and of the glTF writer
/// (which writes the buffer through a scratch file beside `out`,
/// [`crate::output::gltf::StandGlbWriter`]).
pub fn export_stand(run_dir: &Path, library: &SpeciesLibrary, o: &ExportOptions, out: &Path) -> Result<ExportReport> {
    let t_start = std::time::Instant::now();
    let (sc, site, year, [x0, y0, x1, y1]) = open_export(run_dir, o.year, &o.levels, Some(o.area))?;
    let opts = StandOptions { latitude_deg: site.geo.latitude_deg as f32, obstacles: solids(&sc.obstacles, &site), ..StandOptions::default() };
    // only the rows that can take part: the area and every neighbour a target's cell may group
    // with it (cell + halo, and a metre for the f32 positions); the snapshot's other trees are
    // counted for the message below but not held (a million-tree snapshot took 340 MiB)
    let margin = (opts.cell_m + opts.halo_m) as f64 + 1.0;
    let (mut live, mut span): (usize, Option<([f64; 2], [f64; 2])>) = (0, None);
    let rows = super::pictures::snapshot_rows_where(run_dir, year, |r| {
        if r.status == "alive" && r.height_m >= super::scene::MIN_DRAWN_HEIGHT_M && library.find(&r.species).is_some() {
            live += 1;
            let p = [r.x_m, r.y_m];
            span = Some(span.map_or((p, p), |(lo, hi)| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])));
        }
        r.x_m >= x0 - margin && r.x_m < x1 + margin && r.y_m >= y0 - margin && r.y_m < y1 + margin
    })?;
    let plants = plants_from_rows(&rows);
    let stand = stand_trees(&plants, library, &site);
    let trees: Vec<_> = stand.iter().map(|(_, t)| *t).collect();
    // each tree's DBH from the inventory (cm): its stem's taper ([`LodOptions::stem`])
    let dbh: Vec<f32> = stand.iter().map(|(i, _)| rows[*i].dbh_cm).collect();
    let (sw, sh) = (site.width() as f64 * site.cell_x_m, site.height() as f64 * site.cell_y_m);
    let inside = |x: f32, y: f32| in_area(x as f64, y as f64, [x0, y0, x1, y1], sw, sh);
    let targets: Vec<usize> = (0..trees.len()).filter(|&k| inside(trees[k].base.x, trees[k].base.y)).collect();
    if targets.is_empty() {
        let where_ = match span {
            Some((lo, hi)) => format!("an area holding some of the year's {live} live trees (they stand within {:.0},{:.0},{:.0},{:.0})", lo[0], lo[1], hi[0], hi[1]),
            None => format!("a year with live trees (year {year} has none of the species library ≥ 1 m tall)"),
        };
        return Err(invalid("--area", format!("{x0},{y0},{x1},{y1}: no live tree in year {year}"), where_));
    }
    if targets.len() > o.max_trees {
        return Err(invalid("--area", format!("{x0},{y0},{x1},{y1}: {} trees", targets.len()), format!("at most {} trees: a smaller area, or `--instances` for the whole forest as instances of shared models", o.max_trees)));
    }
    // the file's size before any work (trial 37: a hectare wrote 2.2 GB and held 9.5 GB of
    // memory, and the GLB's 4 GiB limit was checked only once everything was made)
    let est = estimate_stand_bytes(targets.iter().map(|&k| (trees[k].species as usize, trees[k].age_yr)), library, o.max_strands, &o.levels);
    if est.bytes > o.max_bytes {
        let mb = |b: u64| b as f64 / 1e6;
        return Err(invalid(
            "--area",
            format!("{x0},{y0},{x1},{y1} at --lod {}: an estimated {:.0} MB glb ({} trees, about {} skeleton nodes)", o.levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(","), mb(est.bytes), est.trees, est.nodes),
            format!("at most {:.0} MB ({}): a smaller --area, --lod 0 (the full level only), --max-strands 48 (a lighter skeleton), or --instances (every tree as an instance of its species and age class); nothing was grown or written", mb(o.max_bytes), o.max_bytes_source),
        ));
    }
    // the free space of `out`'s folder against the file's expected size (trial 47 D5: a full
    // disk was found only after the adaptation, naming the scratch file): the estimate is a
    // float file's, a quantised one is about half of it (`EST_BYTES_PER_NODE`)
    let expected = if o.quantize { est.bytes / 2 } else { est.bytes };
    let folder = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    room_for(out, expected, est.trees, super::disk::free_bytes(folder))?;
    // the regeneration layer's saplings in the area (drawn after the trees)
    let saplings = area_saplings(run_dir, year, library, &site, o.season, o.area)?;
    let full = o.max_strands == crate::structure::stand::FULL_STRANDS;
    let read_s = t_start.elapsed().as_secs_f64();
    // the species drawn (trees and saplings), each once, in index order
    let mut drawn: Vec<usize> = targets.iter().map(|&k| trees[k].species as usize).chain(saplings.iter().map(|s| s.species as usize)).filter(|&sp| sp < library.species.len()).collect();
    drawn.sort_unstable();
    drawn.dedup();
    // the adaptation, and meanwhile, on the threads it leaves idle, what does not depend on
    // it: the leaf covers, the drawn species' looks (textures) and the terrain patch with its
    // litter texture (round 47: these took a third of the export's CPU time on one thread
    // after the adaptation)
    let mut cache = crate::structure::stand::SkeletonCache::new(sc.seed, o.max_strands);
    let (adapted, (cover, mut baked, (terrain, z0), bake_s)) = rayon::join(
        || {
            let t0 = std::time::Instant::now();
            adapt_stand(&trees, &targets, library, &mut cache, &opts).map(|st| (st, t0.elapsed().as_secs_f64()))
        },
        || {
            let tb = std::time::Instant::now();
            let (cover, (looks, terrain)) = rayon::join(
                || leaf_covers(library),
                || rayon::join(|| drawn.par_iter().map(|&sp| (sp, stand_look(&library.species[sp], o.season, full, o.texture_px))).collect::<Vec<_>>(), || {
                    let (mesh, z0) = terrain_patch(&site, o.area);
                    (terrain_static(mesh), z0)
                }),
            );
            let mut baked: Vec<Option<Look>> = vec![None; library.species.len()];
            for (sp, look) in looks {
                baked[sp] = Some(look);
            }
            (cover, baked, terrain, tb.elapsed().as_secs_f64())
        },
    );
    let (st, adapt_s) = adapted?;
    let origin = Vec3::new(((x0 + x1) * 0.5) as f32, ((y0 + y1) * 0.5) as f32, z0);
    // each tree in its own frame, with its topology key and canonical shape
    // per tree also (skeleton nodes, leaf cards of the full level, triangles of the levels written)
    let mesh_tree = |a: &crate::structure::stand::AdaptedTree| {
        let t = &trees[a.index];
        let (sk, mut lv, hgt) = tree_frame(a, t.base)?;
        let r = t.crown_radius_m.max(0.2);
        let sp = &library.species[t.species as usize];
        // full detail: the leaves grown to at most MAX_CARD_GROWTH, the rest of the leaf
        // area as sprigs (as the stills draw them); else copies of the few tips' cards
        // conifers: a pair of crossed shoot cards a shoot in place of the needle cards
        // (round 35: 110,000 needle cards of 6 cm read as an empty crown), which stay for
        // the lower levels
        let needles = full && crate::structure::texture::LeafShape::of_species(sp).is_needle();
        let mut sprigs = if needles {
            let leaf_area = super::leaf_area::drawn_leaf_area(sp, t.crown_radius_m);
            super::leaf_area::shoot_cards_with_sprays(&sk, &lv, leaf_area, cover.sprig[t.species as usize], t.crown_radius_m, t.species as u64, super::leaf_area::limb_spray(sp)).mesh
        } else if full {
            super::adapted::crown_leaf_cards(&mut lv, t, sp, &cover)
        } else {
            let leaf_area = super::leaf_area::drawn_leaf_area(sp, t.crown_radius_m);
            fill_leaf_area(&mut lv, leaf_area, cover.card[t.species as usize], t.crown_radius_m, t.species as u64);
            TriMesh::default()
        };
        let s = Vec3::new(r, r, hgt);
        // the bole tapered to the tree's own DBH (Kozak 1988, `structure::taper`)
        let stem = crate::structure::taper::StemTaper::new(crate::structure::taper::TaperForm::of_species(sp), dbh[a.index], t.height_m);
        let mut topology = vec![t.species as u64, sk.nodes.len() as u64];
        topology.extend(sk.nodes.iter().map(|n| n.parent.map_or(u64::MAX, |p| p as u64)));
        topology.extend(lv.leaves.iter().map(|l| l.node as u64));
        topology.push(sprigs.positions.len() as u64);
        let mut canon = Vec::with_capacity(sk.nodes.len() * 4 + lv.leaves.len() * 10);
        for n in &sk.nodes {
            let p = n.pos / s;
            canon.extend([p.x, p.y, p.z, n.radius / hgt]);
        }
        for l in &lv.leaves {
            let p = l.pos / s;
            canon.extend([p.x, p.y, p.z, l.size / hgt, l.dir.x, l.dir.y, l.dir.z, l.normal.x, l.normal.y, l.normal.z]);
        }
        for q in &sprigs.positions {
            let p = Vec3::from(*q) / s;
            canon.extend([p.x, p.y, p.z]);
        }
        // trees sharing a mesh are scaled across by their crown radius: their DBH over it too
        canon.push(stem.map_or(0.0, |st| 0.01 * st.dbh_cm / r));
        // the mid level: the crown hull of the adapted clusters, as in the pictures
        let (mut chain, _) = super::adapted::adapted_lod_chain(&sk, &lv, a, t.base, 1.0, &LodOptions { stem, ..LodOptions::default() });
        let n_sprigs = sprigs.positions.len() / 4;
        // a conifer's shoot cards are its full level's foliage cards, in the look's `_leaf`
        // material (which wears the shoot-cluster picture, [`stand_look`]) rather than beside
        // the needle cards they replace in `_cluster` (round 39's trial: no `_leaf` for Norway
        // spruce in a stand export)
        if needles {
            chain.levels[0].leaves = std::mem::take(&mut sprigs);
        }
        // the triangles of each level 0–3 as written (level 0 with its sprigs), whether or not
        // the export writes it: `--stats`' `level_triangles` (trial 42: it was empty)
        let mut per_level = [0usize; LOD_LEVELS];
        for (l, t) in per_level.iter_mut().enumerate() {
            *t = chain.levels.get(l).map_or(0, |m| m.triangle_count()) + if l == 0 { sprigs.indices.len() / 3 } else { 0 };
        }
        let tris = o.levels.iter().map(|&l| per_level[l]).sum();
        // the levels not written are not held (the writer leaves them out)
        for (l, m) in chain.levels.iter_mut().enumerate() {
            if !o.levels.contains(&l) {
                *m = Default::default();
            }
        }
        let figures = [sk.nodes.len(), if needles { 0 } else { lv.leaves.len() }, tris, n_sprigs];
        Some((crate::rng::hash(&topology), canon, StandModel { name: format!("{}_{}", sp.id, t.id), chain, look: t.species as usize, sprigs }, s.to_array(), t.base - origin, t.species as usize, figures, per_level))
    };

    // the adaptation's figures, then its trees meshed a batch at a time, each model's meshes
    // written to the glb's scratch file at once and dropped (round 38: all held until written,
    // about twice the file)
    let nodes_total = st.trees.iter().map(|a| a.skeleton.nodes.len()).sum();
    let nodes_before_adaptation = st.trees.iter().map(|a| a.report.nodes_before).sum();
    let pruned_light = st.trees.iter().map(|a| a.report.pruned_light).sum();
    let pruned_collision = st.trees.iter().map(|a| a.report.pruned_collision).sum();
    let (analysis_s, adaptation_s, analyses) = (st.analysis_s, st.adaptation_s, st.analyses);
    let mut w = crate::output::gltf::StandGlbWriter::create(out, &o.levels)?;
    w.set_quantized(o.quantize);
    let mut looks_of: HashMap<usize, usize> = HashMap::new();
    // topology key → (model, its size, its canonical shape) of the models with that topology
    let mut model_of: HashMap<u64, Vec<(usize, [f32; 3], Vec<f32>)>> = HashMap::new();
    let (mut n_trees, mut n_models, mut held_max) = (0usize, 0usize, 0usize);
    let (mut tall_nodes, mut leaf_cards, mut triangles, mut sprig_cards_n) = (Vec::new(), 0usize, 0usize, 0usize);
    let mut level_triangles = [0usize; LOD_LEVELS];
    let (mut mesh_s, mut write_s, mut texture_s) = (0.0f64, 0.0f64, bake_s);
    type Meshed = Option<(u64, Vec<f32>, StandModel, [f32; 3], Vec3, usize, [usize; 4], [usize; LOD_LEVELS])>;
    // one batch's models and nodes into the file, in the trees' order (the file does not
    // depend on the thread count); returns the seconds spent baking textures
    let mut write_batch = |chunk: Vec<crate::structure::stand::AdaptedTree>, meshed: Vec<Meshed>| -> Result<f64> {
        let mut bake_s = 0.0;
        for (m, a) in meshed.into_iter().zip(&chunk) {
            let Some((key, canon, mut model, size, pos, sp, [n_nodes, n_leaves, n_tris, n_sprigs], per_level)) = m else { continue };
            sprig_cards_n += n_sprigs;
            level_triangles.iter_mut().zip(per_level).for_each(|(a, t)| *a += t);
            if trees[a.index].height_m >= STATS_MIN_HEIGHT_M {
                tall_nodes.push(n_nodes);
            }
            leaf_cards += n_leaves;
            triangles += n_tris;
            let look = match looks_of.get(&sp) {
                Some(&l) => l,
                None => {
                    let tb = std::time::Instant::now();
                    let l = w.look(baked[sp].take().unwrap_or_else(|| stand_look(&library.species[sp], o.season, full, o.texture_px)));
                    bake_s += tb.elapsed().as_secs_f64();
                    looks_of.insert(sp, l);
                    l
                }
            };
            let t = &trees[a.index];
            let name = format!("{}_{}", library.species[sp].id, t.id);
            let same = model_of.get(&key).and_then(|c| c.iter().find(|(_, _, c)| c.iter().zip(&canon).all(|(a, b)| (a - b).abs() <= SAME_SHAPE)));
            let (mi, scale) = match same {
                Some(&(mi, s0, _)) => (mi, [size[0] / s0[0], size[1] / s0[1], size[2] / s0[2]]),
                None => {
                    model.look = look;
                    let mi = w.model(&model)?;
                    n_models += 1;
                    model_of.entry(key).or_default().push((mi, size, canon));
                    (mi, [1.0; 3])
                }
            };
            w.tree(&StandNode { name, model: mi, translation: pos.to_array(), scale })?;
            n_trees += 1;
        }
        Ok(bake_s)
    };
    // each batch is meshed by the threads while the batch before it is written (round 47:
    // the threads waited for the writing, and a batch's largest tree held one thread while
    // the other idled)
    let batch = rayon::current_num_threads().max(1) * MESH_BATCH_PER_THREAD;
    let mut adapted = st.trees.into_iter();
    let mut pending: Option<(Vec<crate::structure::stand::AdaptedTree>, Vec<Meshed>)> = None;
    loop {
        let chunk: Vec<_> = adapted.by_ref().take(batch).collect();
        if chunk.is_empty() && pending.is_none() {
            break;
        }
        let pending_bytes: usize = pending.as_ref().map_or(0, |(_, m)| m.iter().flatten().map(|m| model_bytes(&m.2)).sum());
        let tj = std::time::Instant::now();
        let (written, meshed) = rayon::join(
            || -> Result<(f64, f64)> {
                let tw = std::time::Instant::now();
                let bake = match pending.take() {
                    Some((c, m)) => write_batch(c, m)?,
                    None => 0.0,
                };
                Ok((tw.elapsed().as_secs_f64(), bake))
            },
            || chunk.par_iter().map(mesh_tree).collect::<Vec<Meshed>>(),
        );
        let (tw, bake) = written?;
        let tj = tj.elapsed().as_secs_f64();
        texture_s += bake;
        write_s += tw - bake;
        mesh_s += (tj - tw).max(0.0);
        held_max = held_max.max(pending_bytes + meshed.iter().flatten().map(|m| model_bytes(&m.2)).sum::<usize>());
        if !chunk.is_empty() {
            pending = Some((chunk, meshed));
        }
    }

    // the regeneration layer's saplings in the area (as the stills draw them), each an
    // instance of its species' youngest age-class model, after the trees
    let t_sap = std::time::Instant::now();
    let mut n_saplings = 0usize;
    let mut sapling_models: HashMap<usize, Option<(usize, f32, [usize; LOD_LEVELS])>> = HashMap::new();
    for s in saplings {
        let sp = s.species as usize;
        if !sapling_models.contains_key(&sp) {
            let made = match class_model(library, sp, 0) {
                Some((mut m, r0, _, tris, _)) => {
                    m.name = format!("{}_sapling", library.species[sp].id);
                    m.look = *looks_of.entry(sp).or_insert_with(|| w.look(baked[sp].take().unwrap_or_else(|| stand_look(&library.species[sp], o.season, full, o.texture_px))));
                    let mi = w.model(&m)?;
                    n_models += 1;
                    Some((mi, r0, tris))
                }
                None => None,
            };
            sapling_models.insert(sp, made);
        }
        let Some(&Some((mi, r0, per_level))) = sapling_models.get(&sp) else { continue };
        level_triangles.iter_mut().zip(per_level).for_each(|(a, t)| *a += t);
        let tris: usize = o.levels.iter().map(|&l| per_level[l]).sum();
        let r = s.crown_radius.max(0.05) / r0;
        let pos = Vec3::from(s.position) - origin;
        w.sapling(&StandNode { name: format!("{}_sapling_{}", library.species[sp].id, s.id & !super::scene::SAPLING_ID_BIT), model: mi, translation: pos.to_array(), scale: [r, r, s.height.max(0.05)] })?;
        n_saplings += 1;
        triangles += tris;
    }

    texture_s += t_sap.elapsed().as_secs_f64();

    // obstacles reaching into the area
    let t_finish = std::time::Instant::now();
    let mut statics = vec![terrain];
    let terrain_triangles = statics[0].mesh.triangle_count();
    let n_obstacles = push_obstacles(&mut statics, &sc, &site, o.area, origin);
    let geo = crate::output::georef::PointGeoRef::of_site(&site);
    let (mx, my) = geo.map(origin.x as f64, origin.y as f64);
    let extras = serde_json::json!({
        "sylva": {
            "run_dir": run_dir.display().to_string(), "year": year, "area_m": o.area,
            "origin_m": [origin.x, origin.y, origin.z],
            "origin_map": [mx, my, origin.z], "epsg": geo.epsg,
            "note": "scene coordinates are metres from origin_m (run world coordinates: x east, y north from the terrain's south-west corner, z elevation), y up; origin_map is the same point in the terrain's map coordinates (EPSG code epsg)",
        }
    });
    triangles += statics.iter().map(|m| m.mesh.triangle_count()).sum::<usize>();
    let mut stats = ExportStats {
        read_s,
        mesh_s,
        write_s,
        texture_s,
        finish_s: 0.0,
        total_s: 0.0,
        trees: n_trees,
        saplings: n_saplings,
        trees_15m: tall_nodes.len(),
        nodes_min: tall_nodes.iter().copied().min().unwrap_or(0),
        nodes_median: median_usize(&mut tall_nodes),
        leaf_cards,
        sprig_cards: sprig_cards_n,
        adapt_s,
        analysis_s,
        adaptation_s,
        analyses,
        nodes_total,
        nodes_before_adaptation,
        pruned_light,
        pruned_collision,
        triangles,
        levels: o.levels.clone(),
        level_triangles: level_triangles.to_vec(),
    };
    let counts = w.finish(&statics, &format!("stand_{year}"), &extras)?;
    stats.finish_s = t_finish.elapsed().as_secs_f64();
    stats.total_s = t_start.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    Ok(ExportReport { out: out.to_path_buf(), year, trees: n_trees, saplings: n_saplings, models: n_models, obstacles: n_obstacles, terrain_triangles, counts, adapt_s, bytes, stats, held_mesh_bytes_max: held_max })
}

/// The leaf covers of every species of `library` ([`super::adapted::LeafCover::of`], the same
/// values): each leaf shape's measured once, the shapes in parallel (round 47: a stand export
/// spent a fifth of its CPU time measuring them one after another).
pub fn leaf_covers(library: &SpeciesLibrary) -> super::adapted::LeafCover {
    let shape = |sp: &crate::species::Species| crate::structure::texture::LeafShape::of_species(sp);
    let mut first: Vec<&crate::species::Species> = Vec::new();
    for sp in &library.species {
        if !first.iter().any(|f| shape(f) == shape(sp)) {
            first.push(sp);
        }
    }
    first.par_iter().for_each(|sp| {
        super::adapted::LeafCover::of_species(sp);
    });
    super::adapted::LeafCover::of(library)
}

/// The look of species `sp` in a stand export: [`Look::for_species_sized`] in `season` with
/// textures of `texture_px` texels ([`ExportOptions::texture_px`]), except that a
/// conifer at full detail (`full`), whose full level draws crossed shoot cards
/// ([`super::leaf_area::shoot_cards`]) as its foliage cards in place of its needle cards, wears
/// the shoot-cluster picture (its leaf-cluster texture) in its `_leaf` material, as the stills
/// draw those cards. Round 39's trial: a stand export's Norway spruce had no `_leaf` material
/// (its shoot cards were drawn in `_cluster`, and a material no mesh uses is left out), where
/// the guide promises one per species and the instanced export has it.
pub fn stand_look(sp: &crate::species::Species, season: Season, full: bool, texture_px: u32) -> Look {
    let mut look = Look::for_species_sized(sp, season, texture_px);
    if full && crate::structure::texture::LeafShape::of_species(sp).is_needle() {
        look.textures.leaf = look.textures.cluster.clone();
    }
    look
}

/// The saplings of the regeneration layer (`inventory/year_NNNN_regeneration.*`) that stand in
/// `area` (m, world coordinates) of a run's snapshot `year`, as the stills draw them
/// ([`super::scene::sapling_instances`]: per cohort of at least
/// [`super::scene::MIN_SAPLING_HEIGHT_M`] up to [`super::scene::MAX_SAPLINGS_PER_COHORT`]
/// instances scattered in its light cell, scaled to the cohort's height and clump crown
/// radius), none hidden (an export holds the understory trees too). Empty for a run written
/// without the layer.
///
/// Errors: [`Error::Format`] / [`Error::Io`] naming a regeneration file that cannot be read.
pub fn area_saplings(run_dir: &Path, year: u32, library: &SpeciesLibrary, site: &SiteConditions, season: Season, area: [f64; 4]) -> Result<Vec<crate::render::scene::TreeInstance>> {
    let [x0, y0, x1, y1] = area;
    let Some(rows) = super::inventory::read_regeneration(run_dir, year)? else { return Ok(Vec::new()) };
    let cohorts = super::scene::saplings_from_rows(&rows);
    // cohorts whose light cell reaches into the area (a cell's saplings scatter over it)
    let near: Vec<_> = cohorts.into_iter().filter(|c| c.x_m + c.cell_m >= x0 && c.x_m - c.cell_m <= x1 && c.y_m + c.cell_m >= y0 && c.y_m - c.cell_m <= y1).collect();
    let (w, h) = site.extent_m();
    Ok(super::scene::sapling_instances(&near, None, library, site, season).into_iter().filter(|s| in_area(s.position[0] as f64, s.position[1] as f64, area, w, h)).collect())
}

/// Lower bounds (years) of the age classes of [`export_instances`]: a tree instances the model
/// of its species and class, grown at the class's representative age ([`class_age`]).
pub const AGE_CLASSES_YR: [f32; 5] = [0.0, 20.0, 40.0, 80.0, 140.0];

/// Representative age (years) of age class `k` of [`AGE_CLASSES_YR`]: the middle of the class
/// (the last, open class: its lower bound + 30), at most `max_age_yr`.
pub fn class_age(k: usize, max_age_yr: f32) -> f32 {
    let lo = AGE_CLASSES_YR[k];
    let mid = AGE_CLASSES_YR.get(k + 1).map_or(lo + 30.0, |hi| 0.5 * (lo + hi));
    mid.min(max_age_yr).max(1.0)
}

/// The model of species `sp_i` of `library` for age class `class` ([`AGE_CLASSES_YR`]): the
/// species' EcoMod tree (Zamuda et al., `004_*.txt`) grown at [`class_age`] (seed: a hash of
/// species and class), normalised to 1 m, its full level carrying the crown's leaf area as
/// `sylva tree grow` gives it ([`super::leaf_area::lone_chain`]); named `<species>_age<lower
/// bound>`, its look index `sp_i`. Returns (model, normalised crown radius, skeleton nodes,
/// triangles of levels 0–3, [leaf cards, leaf-cluster cards] of level 0); `None` when the
/// species' parameters grow no tree. Deterministic.
#[allow(clippy::type_complexity)]
pub fn class_model(library: &SpeciesLibrary, sp_i: usize, class: usize) -> Option<(StandModel, f32, usize, [usize; 4], [usize; 2])> {
    let sp = library.species.get(sp_i)?;
    let age = class_age(class, sp.life.max_age_yr);
    let grown = crate::structure::species_tree::grow_species_tree(sp, crate::structure::species_tree::Model::EcoMod, age, &[], crate::rng::hash(&[sp_i as u64, class as u64])).ok()?;
    let (sk, mut lv) = crate::structure::normalised(&grown.skeleton, &grown.leaves, 1.0).ok()?;
    let r = crate::structure::crown_radius(&sk, &lv).max(0.05);
    // the full level carries the crown's leaf area as `sylva tree grow` gives it (one code
    // path: the crown LAI over the model's projection, its cards lengthened, the rest as
    // leaf-cluster cards; trial 35: the instanced crowns were sparse and dark)
    let (chain, fill) = super::leaf_area::lone_chain(&sk, &mut lv, sp);
    let tris = [0, 1, 2, 3].map(|l| chain.levels.get(l).map_or(0, |m| m.triangle_count()));
    let quads = chain.levels.first().map_or(0, |m| m.leaves.triangle_count() / 2);
    Some((StandModel { name: format!("{}_age{}", sp.id, AGE_CLASSES_YR[class] as u32), chain, look: sp_i, sprigs: TriMesh::default() }, r, sk.nodes.len(), tris, [quads.saturating_sub(fill.sprigs), fill.sprigs]))
}

/// Most triangles an instanced export draws by default ([`InstanceOptions::levels`] empty:
/// the finest single level whose triangles over all its trees stay within this): 20 million
/// (ESTIMATE, not from a publication: the order of what a current desktop GPU draws a frame
/// at interactive rates). The default run's year 150 (about a million trees) gets its
/// billboards (level 3, 8 triangles a tree); its full level would be about 23.6 billion
/// (round 39's trial).
pub const INSTANCE_MAX_TRIANGLES: u64 = 20_000_000;

/// Names of the levels of detail 0–3, for messages.
pub const LEVEL_NAMES: [&str; LOD_LEVELS] = ["full detail", "leaf clusters", "crown hulls", "billboards"];

/// The levels an instanced export writes: `given` when not empty; else the finest single level
/// whose triangles over all trees (`per_level[l]`, levels 0–3) are at most `max_triangles`,
/// the billboards (level 3) when none is.
pub fn instance_levels(given: &[usize], per_level: &[usize], max_triangles: u64) -> Vec<usize> {
    if !given.is_empty() {
        return given.to_vec();
    }
    let last = per_level.len().min(LOD_LEVELS).max(1) - 1;
    vec![(0..=last).find(|&l| per_level[l] as u64 <= max_triangles).unwrap_or(last)]
}

/// Age class (index into [`AGE_CLASSES_YR`]) of a tree of `age_yr` years.
pub fn age_class(age_yr: f32) -> usize {
    AGE_CLASSES_YR.iter().rposition(|&lo| age_yr >= lo).unwrap_or(0)
}

/// What [`export_instances`] exports: every live tree of a snapshot (or of an area of it).
#[derive(Debug, Clone, PartialEq)]
pub struct InstanceOptions {
    /// Snapshot year; `None`: the last one.
    pub year: Option<u32>,
    /// Area `[x0, y0, x1, y1]` (m, world coordinates); `None`: the whole site.
    pub area: Option<[f64; 4]>,
    /// Season of the foliage colours.
    pub season: Season,
    /// Levels of detail written, one instanced node per model and level (`[0, 1, 2, 3]`: each
    /// model's chain `<model>_LOD0…3` under a node `<model>`, for an engine's LOD groups); empty
    /// (`sylva export --instances` without `--lod`): the finest single level a whole forest can
    /// hold, [`instance_levels`] within [`InstanceOptions::max_triangles`] (round 39's trial:
    /// the full level on a million trees was 23.6 billion triangles).
    pub levels: Vec<usize>,
    /// Triangles the default level may draw over all trees ([`INSTANCE_MAX_TRIANGLES`]); levels
    /// given explicitly above it are written with a warning naming the total and `--lod`.
    pub max_triangles: u64,
}

/// Exports every live tree (at least [`super::scene::MIN_DRAWN_HEIGHT_M`] tall) of a run's
/// snapshot, or of an area of it, to `out` (`.glb`, atomically) for game engines and Blender:
/// each tree an instance (`EXT_mesh_gpu_instancing`) of the model of its species and age class
/// ([`AGE_CLASSES_YR`]: the species' EcoMod tree, Zamuda et al. `004_*.txt`, grown at the class's
/// representative age and normalised to 1 m; its full level carries the crown's leaf area as
/// `sylva tree grow` gives it, [`super::leaf_area::lone_chain`]: the species' crown LAI over the
/// model's crown projection, as its leaf cards and leaf-cluster cards in the look's `_cluster`
/// material), scaled to its height (vertical) and crown radius
/// (horizontal: the inventory's `crown_radius_m` over the model's normalised crown radius),
/// turned about the vertical by a hash of its id, with the terrain under the area and the
/// obstacles. Coordinates as [`export_stand`]'s (metres from the area's centre at the lowest
/// terrain elevation, y up); the scene's `extras` give the origin in the run's world
/// coordinates and in the terrain's map coordinates with its EPSG code.
///
/// Errors: as [`export_stand`] (a run directory or snapshot that cannot be read, an area
/// outside the terrain or holding no live tree, naming `--area`; a level ≥ [`LOD_LEVELS`],
/// naming `--lod`); the glTF writer's.
pub fn export_instances(run_dir: &Path, library: &SpeciesLibrary, o: &InstanceOptions, out: &Path) -> Result<ExportReport> {
    use crate::output::gltf::{InstanceGroup, InstancedScene};
    let (sc, site, year, area) = open_export(run_dir, o.year, &o.levels, o.area)?;
    let [x0, y0, x1, y1] = area;
    let (sw, sh) = (site.width() as f64 * site.cell_x_m, site.height() as f64 * site.cell_y_m);
    let mut unknown = 0usize;
    let rows = super::pictures::snapshot_rows_where(run_dir, year, |r| {
        let live = r.status == "alive" && r.height_m >= super::scene::MIN_DRAWN_HEIGHT_M && in_area(r.x_m, r.y_m, area, sw, sh);
        let known = library.find(&r.species).is_some();
        unknown += (live && !known) as usize;
        live && known
    })?;
    if unknown > 0 {
        tracing::warn!("{unknown} live trees are of species not in the library and are left out (give their species files with --species-dir)");
    }
    if rows.is_empty() {
        let why = if unknown > 0 { format!(" of the species library ({unknown} of unknown species)") } else { String::new() };
        return Err(match o.area {
            Some(_) => invalid("--area", format!("{x0},{y0},{x1},{y1}: no live tree{why} in year {year}"), "an area (or a year) with live trees of the species library at least 1 m tall".into()),
            None => invalid("--year", format!("{year}: no live tree{why} on the site"), "a year with live trees of the species library at least 1 m tall (or --species-dir with the run's species files)".into()),
        });
    }
    let (terrain, z0) = terrain_patch(&site, area);
    let origin = Vec3::new(((x0 + x1) * 0.5) as f32, ((y0 + y1) * 0.5) as f32, z0);
    // the (species, age class) pairs present, each one model
    let mut keys: Vec<(usize, usize)> = rows.iter().filter_map(|r| Some((library.find(&r.species)? as usize, age_class(r.age_yr)))).collect();
    keys.sort_unstable();
    keys.dedup();
    // per model: (model, normalised crown radius, skeleton nodes, triangles per level, (leaf
    // cards, leaf-cluster cards) of level 0)
    #[allow(clippy::type_complexity)]
    let built: Vec<Option<(StandModel, f32, usize, [usize; 4], [usize; 2])>> = keys.par_iter().map(|&(sp_i, class)| class_model(library, sp_i, class)).collect();
    // looks of the species used, and the groups
    let mut looks_of: HashMap<usize, usize> = HashMap::new();
    let mut looks: Vec<Look> = Vec::new();
    let mut models: Vec<StandModel> = Vec::new();
    #[allow(clippy::type_complexity)]
    let mut model_of: HashMap<(usize, usize), (usize, f32, usize, [usize; 4], [usize; 2])> = HashMap::new();
    for (key, b) in keys.iter().zip(built) {
        let Some((mut m, r, nodes, tris, cards)) = b else {
            tracing::warn!("species {}: no model for age class {}; its trees are left out", library.species[key.0].id, key.1);
            continue;
        };
        m.look = *looks_of.entry(key.0).or_insert_with(|| {
            looks.push(Look::for_species(&library.species[key.0], o.season));
            looks.len() - 1
        });
        models.push(m);
        model_of.insert(*key, (models.len() - 1, r, nodes, tris, cards));
    }
    let mut groups: Vec<InstanceGroup> = (0..models.len()).map(|model| InstanceGroup { model, ..Default::default() }).collect();
    let (mut tall_nodes, mut cards_all, mut per_level) = (Vec::new(), [0usize; 2], [0usize; LOD_LEVELS]);
    for r in &rows {
        let Some(sp_i) = library.find(&r.species) else { continue };
        let Some(&(mi, r0, nodes, tris, cards)) = model_of.get(&(sp_i as usize, age_class(r.age_yr))) else { continue };
        let g = &mut groups[mi];
        let z = site.elevation_at(r.x_m, r.y_m);
        g.translations.push([(r.x_m - origin.x as f64) as f32, (r.y_m - origin.y as f64) as f32, z - origin.z]);
        g.yaw.push((crate::rng::hash(&[r.id, 0x7961_77]) >> 11) as f32 / (1u64 << 53) as f32 * std::f32::consts::TAU);
        let s = r.crown_radius_m.max(0.2) / r0;
        g.scales.push([s, s, r.height_m.max(0.1)]);
        g.ids.push(r.id);
        if r.height_m >= STATS_MIN_HEIGHT_M {
            tall_nodes.push(nodes);
        }
        cards_all[0] += cards[0];
        cards_all[1] += cards[1];
        for (l, t) in per_level.iter_mut().enumerate() {
            *t += tris[l];
        }
    }
    // the regeneration layer's saplings, as a stand export of the same area draws them
    // ([`area_saplings`]; trial 42: the instanced export had none where the stand export had
    // 479): each an instance of its species' sapling model (the youngest age class, named
    // `<species>_sapling`, as in a stand export) under node `saplings`, scaled to its height
    // and crown radius, its id the regeneration layer's (with [`super::scene::SAPLING_ID_BIT`])
    let mut sapling_group: HashMap<usize, Option<(usize, f32, [usize; LOD_LEVELS])>> = HashMap::new();
    let mut n_saplings = 0usize;
    for sa in area_saplings(run_dir, year, library, &site, o.season, area)? {
        let sp = sa.species as usize;
        let made = sapling_group.entry(sp).or_insert_with(|| {
            let (mut m, r0, _, tris, _) = class_model(library, sp, 0)?;
            m.name = format!("{}_sapling", library.species[sp].id);
            m.look = *looks_of.entry(sp).or_insert_with(|| {
                looks.push(Look::for_species(&library.species[sp], o.season));
                looks.len() - 1
            });
            models.push(m);
            groups.push(InstanceGroup { model: models.len() - 1, sapling: true, ..Default::default() });
            Some((groups.len() - 1, r0, tris))
        });
        let Some((gi, r0, tris)) = *made else { continue };
        let g = &mut groups[gi];
        g.translations.push([sa.position[0] - origin.x, sa.position[1] - origin.y, sa.position[2] - origin.z]);
        g.yaw.push((crate::rng::hash(&[sa.id, 0x7961_77]) >> 11) as f32 / (1u64 << 53) as f32 * std::f32::consts::TAU);
        let s = sa.crown_radius.max(0.05) / r0;
        g.scales.push([s, s, sa.height.max(0.05)]);
        g.ids.push(sa.id);
        for (l, t) in per_level.iter_mut().enumerate() {
            *t += tris[l];
        }
        n_saplings += 1;
    }
    let levels = instance_levels(&o.levels, &per_level, o.max_triangles);
    let drawn: usize = levels.iter().map(|&l| per_level[l]).sum();
    // the levels asked for: a warning where one of them alone is more than a forest can hold
    // (the whole chain is for an engine's LOD groups, which draw one level a tree)
    if !o.levels.is_empty() && levels.len() < LOD_LEVELS && drawn as u64 > o.max_triangles {
        let each: Vec<String> = per_level.iter().enumerate().map(|(l, t)| format!("LOD{l} {t}")).collect();
        tracing::warn!(
            "sylva export --instances: --lod {} draws {drawn} triangles over its {} trees ({}), above the {} a whole forest can hold; --lod 3 (billboards) or 2 (crown hulls) for a viewer, --lod all for an engine's LOD groups, or leave --lod out for the finest level within it",
            levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(","),
            rows.len(),
            each.join(", "),
            o.max_triangles
        );
    }
    let (leaf_cards, sprig_cards) = if levels.contains(&0) { (cards_all[0], cards_all[1]) } else { (0, 0) };
    let mut triangles = drawn;
    let trees: usize = groups.iter().filter(|g| !g.sapling).map(|g| g.translations.len()).sum();
    let mut statics = vec![terrain_static(terrain)];
    let terrain_triangles = statics[0].mesh.triangle_count();
    let n_obstacles = push_obstacles(&mut statics, &sc, &site, area, origin);
    triangles += statics.iter().map(|m| m.mesh.triangle_count()).sum::<usize>();
    let geo = crate::output::georef::PointGeoRef::of_site(&site);
    let (mx, my) = geo.map(origin.x as f64, origin.y as f64);
    let scene = InstancedScene {
        name: format!("forest_{year}"),
        looks,
        models,
        groups,
        statics,
        levels: levels.clone(),
        extras: serde_json::json!({
            "sylva": {
                "run_dir": run_dir.display().to_string(), "year": year, "area_m": area,
                "origin_m": [origin.x, origin.y, origin.z],
                "origin_map": [mx, my, origin.z], "epsg": geo.epsg,
                "age_classes_yr": AGE_CLASSES_YR,
                "note": "scene coordinates are metres from origin_m (run world coordinates: x east, y north from the terrain's south-west corner, z elevation), y up; origin_map is the same point in the terrain's map coordinates (EPSG code epsg); each tree is an EXT_mesh_gpu_instancing instance of the model of its species and age class, _ID its inventory id (or, where an id exceeds 32 bits, _ID_LO and _ID_HI: id = _ID_HI * 2^32 + _ID_LO)",
            }
        }),
    };
    let counts = crate::output::gltf::write_instanced_glb(out, &scene)?;
    let bytes = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    let stats = ExportStats { trees, trees_15m: tall_nodes.len(), nodes_min: tall_nodes.iter().copied().min().unwrap_or(0), nodes_median: median_usize(&mut tall_nodes), leaf_cards, sprig_cards, triangles, levels, level_triangles: per_level.to_vec(), saplings: n_saplings, ..Default::default() };
    Ok(ExportReport { out: out.to_path_buf(), year, trees, saplings: n_saplings, models: scene.models.len(), obstacles: n_obstacles, terrain_triangles, counts, adapt_s: 0.0, bytes, stats, held_mesh_bytes_max: 0 })
}

/// Appends the meshes of the scenario's obstacles that reach into `area` to `statics`, moved to
/// `origin`; returns how many.
fn push_obstacles(statics: &mut Vec<StaticMesh>, sc: &Scenario, site: &SiteConditions, area: [f64; 4], origin: Vec3) -> usize {
    let [x0, y0, x1, y1] = area;
    let mut n = 0;
    for (k, ob) in sc.obstacles.iter().enumerate() {
        let mut m = obstacle_mesh(ob, site);
        let Some((lo, hi)) = m.bounds() else { continue };
        if (hi[0] as f64) < x0 || (lo[0] as f64) > x1 || (hi[1] as f64) < y0 || (lo[1] as f64) > y1 {
            continue;
        }
        for p in &mut m.positions {
            *p = (Vec3::from(*p) - origin).to_array();
        }
        statics.push(StaticMesh { name: format!("obstacle_{k}_{}", ob.kind()), mesh: m, rgb: OBSTACLE_RGB, roughness: 0.9, texture: None });
        n += 1;
    }
    n
}

/// Largest vertex spacing of the terrain patch (m): finer than the DEM's cells so that the
/// patch follows the bilinear surface the trees stand on ([`SiteConditions::elevation_at`]).
pub const TERRAIN_STEP_M: f64 = 5.0;

/// The terrain under `area` (m, world coordinates) as a grid mesh with vertices every
/// [`TERRAIN_STEP_M`] or the site's cell size if smaller (at most 256 × 256 quads, at least
/// 0.5 m apart), elevations by [`SiteConditions::elevation_at_valid`] (masked cells, no-data or
/// sea: holes, their quads left out), normals from central differences; positions relative to the area's
/// centre and the patch's lowest elevation, which is returned; texture coordinates the
/// position's metres east and north of the area's centre (u = x, v = y: a tiling texture
/// repeats once a metre).
pub fn terrain_patch(site: &SiteConditions, area: [f64; 4]) -> (TriMesh, f32) {
    let [x0, y0, x1, y1] = area;
    let step = site.cell_x_m.min(site.cell_y_m).min(TERRAIN_STEP_M).max((x1 - x0).max(y1 - y0) / 256.0).max(0.5);
    let nx = ((x1 - x0) / step).ceil().max(1.0) as usize;
    let ny = ((y1 - y0) / step).ceil().max(1.0) as usize;
    let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
    let at = |i: usize, j: usize| (x0 + (x1 - x0) * i as f64 / nx as f64, y0 + (y1 - y0) * j as f64 / ny as f64);
    let mut z = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = at(i, j);
            z.push(site.elevation_at_valid(x, y, f32::NEG_INFINITY));
        }
    }
    let z0 = z.iter().copied().fold(f32::INFINITY, f32::min);
    let z0 = if z0.is_finite() { z0 } else { 0.0 };
    // no-data points (NaN) are holes: their quads are left out and their vertices, unused,
    // put at z0 (a glTF position must be finite; round 34)
    let ok: Vec<bool> = z.iter().map(|v| v.is_finite()).collect();
    z.iter_mut().filter(|v| !v.is_finite()).for_each(|v| *v = z0);
    let mut m = TriMesh::default();
    let (dx, dy) = ((x1 - x0) as f32 / nx as f32, (y1 - y0) as f32 / ny as f32);
    let zi = |i: usize, j: usize| z[j * (nx + 1) + i];
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = at(i, j);
            m.positions.push([(x - cx) as f32, (y - cy) as f32, zi(i, j) - z0]);
            m.uvs.push([(x - cx) as f32, (y - cy) as f32]);
            let (il, ir) = (i.saturating_sub(1), (i + 1).min(nx));
            let (jd, ju) = (j.saturating_sub(1), (j + 1).min(ny));
            let gx = (zi(ir, j) - zi(il, j)) / (dx * (ir - il) as f32);
            let gy = (zi(i, ju) - zi(i, jd)) / (dy * (ju - jd) as f32);
            m.normals.push(Vec3::new(-gx, -gy, 1.0).normalize().to_array());
        }
    }
    let v = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            if ![v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)].iter().all(|&k| ok[k as usize]) {
                continue;
            }
            // counter-clockwise seen from above (x east, y north)
            m.indices.extend_from_slice(&[v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    (m, z0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trial 47 D5: an export larger than its folder's free space is refused before any work,
    /// naming `--out` and both sizes; room enough, or an unknown free space, passes.
    #[test]
    fn an_export_without_room_is_refused_naming_out() {
        let out = Path::new("full/x.glb");
        let e = room_for(out, 176_000_000, 534, Some(20_000_000)).unwrap_err().to_string();
        assert!(e.contains("--out") && e.contains("full/x.glb") && e.contains("176 MB needed") && e.contains("20 MB free"), "{e}");
        assert!(room_for(out, 176_000_000, 534, Some(176_000_000)).is_ok());
        assert!(room_for(out, 176_000_000, 534, None).is_ok());
    }

    /// The export's ground colour is the pictures' forest floor in sRGB (within one step of
    /// 255 per channel), and its terrain is textured with texture coordinates in metres.
    #[test]
    fn the_export_ground_is_the_pictures_forest_floor() {
        let lin = crate::species::srgb_to_linear(GROUND_RGB);
        for k in 0..3 {
            let f = crate::render::terrain::FOREST_FLOOR[k];
            let step = crate::species::srgb_to_linear([GROUND_RGB[k].saturating_add(1); 3])[0] - lin[k];
            assert!((lin[k] - f).abs() <= step, "channel {k}: {} against {f}", lin[k]);
        }
        let m = TriMesh { positions: vec![[1.0, 2.0, 0.0]], uvs: vec![[1.0, 2.0]], ..Default::default() };
        let t = terrain_static(m);
        assert!(t.texture.is_some() && t.name == "terrain");
    }

    #[test]
    fn area_edges_on_the_site_edge_are_closed() {
        let site = [0.0, 0.0, 2400.0, 1800.0];
        // on the east and north edges of the site: in
        assert!(in_area(2400.0, 900.0, site, 2400.0, 1800.0) && in_area(100.0, 1800.0, site, 2400.0, 1800.0) && in_area(2400.0, 1800.0, site, 2400.0, 1800.0));
        // an inner area stays half-open: its east edge belongs to the next area
        assert!(!in_area(1200.0, 900.0, [0.0, 0.0, 1200.0, 1800.0], 2400.0, 1800.0) && in_area(1200.0, 900.0, [1200.0, 0.0, 2400.0, 1800.0], 2400.0, 1800.0));
        assert!(!in_area(-0.01, 5.0, site, 2400.0, 1800.0) && !in_area(5.0, 1800.01, site, 2400.0, 1800.0));
    }
    use crate::structure::{Leaf, Leaves};

    #[test]
    fn leaf_cards_carry_the_crowns_leaf_area() {
        let leaf = |size: f32, x: f32| Leaf { pos: Vec3::new(x, 0.0, 5.0), dir: Vec3::Z, normal: Vec3::X, size, node: 0 };
        let area = |lv: &Leaves| lv.leaves.iter().map(|l| 0.25 * l.size * l.size).sum::<f32>();
        // two cards of 0.5 · size² each, half of it leaf: 0.5 · 0.5 · (0.04 + 0.16) = 0.05 m²
        let mut lv = Leaves { leaves: vec![leaf(0.2, 0.0), leaf(0.4, 1.0)] };
        fill_leaf_area(&mut lv, 2.0, 0.5, 1.2, 7);
        // F = 40: 18 cards per leaf, each 1.49 × as long
        assert_eq!(lv.len(), 36);
        assert!((area(&lv) - 2.0).abs() < 1e-3, "{}", area(&lv));
        assert!(lv.leaves.iter().all(|l| l.pos.truncate().length() <= 1.2 + 1e-4), "within the crown radius");
        assert!(lv.leaves.iter().all(|l| l.size <= 0.4 * MAX_CARD_GROWTH + 1e-5));
        let mut again = Leaves { leaves: vec![leaf(0.2, 0.0), leaf(0.4, 1.0)] };
        fill_leaf_area(&mut again, 2.0, 0.5, 1.2, 7);
        assert_eq!(again, lv, "deterministic");
        // a smaller target shrinks the cards; no leaves or no target: unchanged
        let mut lv = Leaves { leaves: vec![leaf(1.0, 0.0)] };
        fill_leaf_area(&mut lv, 0.125, 1.0, 2.0, 1);
        assert_eq!(lv.len(), 1);
        assert!((lv.leaves[0].size - 0.5).abs() < 1e-6);
        let mut none = Leaves::default();
        fill_leaf_area(&mut none, 10.0, 1.0, 2.0, 1);
        assert!(none.is_empty());
        // a beech crown of 2.5 m: crown LAI 4.5 (shade tolerance 5) over 19.6 m²
        assert!((crate::sim::phases::light::crown_leaf_area(5.0, 2.5) - 4.5 * std::f32::consts::PI * 6.25).abs() < 1e-3);
        // leaf textures cover part of their cards
        for s in crate::structure::texture::LeafShape::ALL {
            let c = crate::structure::texture::leaf_card_cover(s);
            assert!((0.05..1.0).contains(&c), "{s:?} {c}");
        }
    }

    /// `sprig_cards`: the leaf cards grow by at most 1.5 and the sprigs carry the rest of the
    /// leaf area (each side² × cover), within half a sprig's share, inclined planophile; the
    /// same call gives the same mesh; a target the cards reach needs no sprig.
    #[test]
    fn sprigs_carry_the_leaf_area_beyond_the_cards() {
        use crate::structure::{Leaf, Leaves};
        let leaf = |i: usize| Leaf { pos: Vec3::new(0.1 * (i % 10) as f32, 0.1 * (i / 10) as f32, 5.0), dir: Vec3::Z, normal: Vec3::X, size: 0.1, node: i as u32 };
        let make = || Leaves { leaves: (0..200).map(leaf).collect() };
        let (cover, sprig_cover) = (0.6, 0.45);
        let mut lv = make();
        let m = sprig_cards(&mut lv, 20.0, cover, sprig_cover, 3.0, 7);
        assert!(lv.leaves.iter().all(|l| (l.size - 0.15).abs() < 1e-6));
        let cards: f32 = lv.leaves.iter().map(|l| 0.5 * l.size * l.size * cover).sum();
        let side = 0.15 / 0.26;
        let n = m.positions.len() / 4;
        let total = cards + n as f32 * side * side * sprig_cover;
        assert!((total - 20.0).abs() <= 0.5 * side * side * sprig_cover, "{cards} + {n} sprigs = {total}");
        assert_eq!((m.indices.len(), m.uvs.len()), (6 * n, 4 * n));
        assert!(m.positions.iter().all(|p| (p[0] * p[0] + p[1] * p[1]).sqrt() <= 3.0 + side));
        // planophile: every normal within 60° of the vertical, 30° on average (mean cos 0.83)
        assert!(m.normals.iter().all(|nm| nm[2] >= SPRIG_MAX_INCLINATION.cos() - 1e-5), "a sprig inclined beyond 60°");
        let mean_cos = m.normals.iter().map(|nm| nm[2]).sum::<f32>() / m.normals.len() as f32;
        assert!((0.78..0.88).contains(&mean_cos), "mean cosine of the sprigs' inclination {mean_cos}");
        let mut again = make();
        assert_eq!(sprig_cards(&mut again, 20.0, cover, sprig_cover, 3.0, 7).positions, m.positions);
        let mut small = make();
        assert!(sprig_cards(&mut small, 0.5, cover, sprig_cover, 3.0, 7).positions.is_empty());
        assert!(small.leaves[0].size < 0.15);
    }

    /// Round 34: the terrain patch of an export over a DEM's no-data hole leaves the hole open
    /// (no triangle over it, no wall) and writes no NaN position (it wrote NaN elevations,
    /// which glTF does not allow); the ground beside the hole is there.
    #[test]
    fn terrain_patch_leaves_no_data_holes_open() {
        let n = 12;
        let mut e = crate::grid::Grid::filled(n, n, 0.0f32);
        for r in 0..n {
            for c in 0..n {
                *e.get_mut(c, r) = if (4..7).contains(&c) && (4..7).contains(&r) { f32::NAN } else { 300.0 + c as f32 };
            }
        }
        let t = crate::terrain::Terrain { elevation: e, geo: crate::grid::GeoRef::local(10.0, 47.0), nodata: Some(-9999.0), source: "test".into() };
        let site = crate::conditions::derive(&t, &crate::climate::Climate::default()).unwrap();
        let (m, z0) = terrain_patch(&site, [0.0, 0.0, 120.0, 120.0]);
        assert_eq!(z0, 300.0);
        assert!(m.positions.iter().all(|p| p.iter().all(|v| v.is_finite())), "a NaN position");
        let (mut over, mut kept) = (0, 0);
        for tri in m.indices.chunks(3) {
            let p: Vec<Vec3> = tri.iter().map(|&k| Vec3::from(m.positions[k as usize])).collect();
            // patch coordinates: from the area's centre (60, 60)
            let c = (p[0] + p[1] + p[2]) / 3.0 + Vec3::new(60.0, 60.0, 0.0);
            if (40.0..70.0).contains(&c.x) && (50.0..80.0).contains(&c.y) {
                over += 1;
            }
            kept += 1;
            let nz = (p[1] - p[0]).cross(p[2] - p[0]).normalize().z;
            assert!(nz > 0.9, "a steep triangle (a wall?) at {c:?}");
        }
        assert_eq!(over, 0, "triangles over the hole");
        assert!(kept > 300, "{kept} triangles: the ground around the hole");
    }
}
