//! `sylva tree grow`: grows one tree with one of the three architecture models, exports its LOD
//! chain as `.glb` or `.obj` (by extension), writes a PNG preview (side views of the four LOD
//! levels, CPU rasterised) next to it and prints node/triangle counts per LOD. With
//! `--adapt-to`, the grown tree is then adapted to new obstacles by Plastic Trees (Pirk et al.
//! 2012, `000_*.txt`; [`sylva::structure::plastic::adapt`]) instead of being regrown.
use anyhow::Context;
use clap::{Subcommand, ValueEnum};
use glam::Vec3;
use std::path::{Path, PathBuf};
use sylva::structure::grow::space::Obstacle;
use sylva::structure::forest_form::{self, CrownProportions};
use sylva::job::leaf_area::lone_chain;
use sylva::structure::species_tree;
use sylva::structure::plastic::{adapt_group, Environment, Fate, PlasticTree, Sky};
use sylva::structure::{Leaves, Skeleton};

/// Growth model.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Model {
    /// EcoMod strand model (Zamuda et al.).
    Ecomod,
    /// Light-guided self-organising growth (Yi et al.).
    Light,
    /// Laplacian / dielectric-breakdown growth (Jinasena & Sonnadara).
    Laplacian,
}

/// Tree subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Grow one tree skeleton and export it.
    Grow {
        /// Species id or name (from the embedded species library).
        #[arg(long)]
        species: String,
        /// Growth model.
        #[arg(long, value_enum, default_value = "ecomod")]
        model: Model,
        /// Age in years: EcoMod scales the strands S·min(1, age/80)² (≥ 8); light-guided and Laplacian
        /// grow inside the species' crown envelope at that age (height, crown radius and length
        /// from the species file); light-guided runs `age` cycles (≤ 60); Laplacian adds 25
        /// branches per year (≤ 4000).
        #[arg(long, default_value_t = 80.0, allow_negative_numbers = true)]
        age: f32,
        /// Obstacles (light and laplacian models): box:x0,y0,z0,x1,y1,z1 | sphere:x,y,z,r | wall:x[,length[,height]]
        #[arg(long)]
        obstacle: Vec<String>,
        /// Obstacles that appear AFTER the tree has grown (any model; same forms as --obstacle):
        /// the grown skeleton is bent away and pruned by Plastic Trees (Pirk et al. 2012,
        /// eqs. 3, 6–11) instead of regrown; prints what was bent and pruned and the time taken
        /// against regrowing among the obstacles.
        #[arg(long = "adapt-to")]
        adapt_to: Vec<String>,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Grow the tree as a tree alone (open-grown: the species' open-grown DBH, crown ratio
        /// and crown radius) instead of a tree of a closed stand (the default: DBH, crown base
        /// and crown width of the species' stand-grown functions). EcoMod only.
        #[arg(long)]
        open_grown: bool,
        /// Folder of extra or edited species files, over the shipped library.
        #[arg(long)]
        species_dir: Option<PathBuf>,
        /// Output file, .glb or .obj; the preview goes to the same name with .png. A .glb gets
        /// its skeleton beside it (`NAME.skeleton.json`) for `sylva tree adapt --input`.
        #[arg(long)]
        out: PathBuf,
        /// Levels of detail written to `--out`, as `sylva export --lod`: `0`, the default, the
        /// full-detail mesh alone (what Blender and glTF viewers show: they draw every node, so
        /// the whole chain stacked the crown hull and billboard over the tree); `all` the chain
        /// `<species>_LOD0…3` for a game engine's LOD group; or a list such as `0,3`. The
        /// preview PNG always shows every level.
        #[arg(long, default_value = "0")]
        lod: String,
        /// Side of the exported textures in texels (bark, and the leaf-cluster, crown and
        /// impostor pictures of the levels written; the leaf card's is half as wide): a power
        /// of two from 256 to 4096, drawn at that size (finer leaf veins and bark grain from
        /// 512), not enlarged. 2048 by default, for a close-up; `sylva export` keeps 256.
        #[arg(long, default_value_t = 2048)]
        texture_size: u32,
        /// The full level's foliage as the stand exports draw it (the tree's leaf cards,
        /// lengthened by up to 1.5, and leaf-cluster cards for the rest of the crown's leaf
        /// area: some 50,000 triangles for a 100-year beech) instead of the default
        /// individual leaves (every leaf a card of the species' leaf length carrying the
        /// crown's whole leaf area: about 1.6 M triangles and 110 MB for that beech), and the
        /// stem without its root flare.
        #[arg(long)]
        leaf_clusters: bool,
    },
    /// Adapt a grown tree to obstacles and neighbours by Plastic Trees (Pirk et al. 2012)
    /// instead of regrowing it; writes the adapted tree and a before/after PNG (Fig. 6).
    Adapt(AdaptArgs),
}

/// Arguments of `sylva tree adapt`.
#[derive(clap::Args)]
pub struct AdaptArgs {
    /// A .glb written by `sylva tree grow` (its skeleton sidecar NAME.skeleton.json is read);
    /// without it the tree is grown here from --species/--model/--age/--seed.
    #[arg(long)]
    input: Option<PathBuf>,
    /// Species id or name (the tree's species: its Plastic Trees parameters and leaves). With
    /// --input it may be left out: the species recorded in the tree's skeleton sidecar is used
    /// (given, it must be that species).
    #[arg(long)]
    species: Option<String>,
    /// Growth model of a tree grown here and of the neighbours (with --input: of the neighbours).
    #[arg(long, value_enum, default_value = "light")]
    model: Model,
    /// Age (years) of a tree grown here, of neighbours without their own age, and of the
    /// light-guided regrowth timed for `regrow_ms` (also with --input).
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true)]
    age: f32,
    /// Random seed of a tree grown here and of its regrowth (neighbours use seed + 1, + 2, …).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Obstacle to adapt to: box:x0,y0,z0,x1,y1,z1 | sphere:x,y,z,r | wall:x[,length[,height]]
    /// (m). A wall fills the space beyond the plane at x (away from the trunk) from the ground
    /// up; with a length it runs along y, centred on y = 0, and with a height it ends there
    /// (without them it is endless and as high as the sky).
    #[arg(long)]
    obstacle: Vec<String>,
    /// Neighbour tree SPECIES@X,Y[,AGE] (m, years), grown and adapted together with the tree.
    #[arg(long)]
    neighbour: Vec<String>,
    /// Latitude (degrees, −90..90) for global light (Plastic Trees section 6): the brightest
    /// sky point is the equinox noon sun, 90° − |latitude| high towards the equator (−y in the
    /// north); without it, the zenith.
    #[arg(long, allow_hyphen_values = true)]
    latitude: Option<f32>,
    /// Sky quadrature of eq. (3): direction counts of the rings around the brightest sky point,
    /// each a multiple of 4, at most 32 in all. The default 4,8,12 (24 directions) is within
    /// 0.02 of a 5,872-direction reference in light; 4,8 (12 directions) adapts about 1.9×
    /// faster at about twice the error (BENCHMARKS.md, Plastic Trees sky).
    #[arg(long, value_delimiter = ',', default_value = "4,8,12", allow_negative_numbers = true)]
    sky_rings: Vec<usize>,
    /// Folder of extra or edited species files, over the shipped library.
    #[arg(long)]
    species_dir: Option<PathBuf>,
    /// Output .glb (adapted tree; skeleton sidecar beside it); the before/after PNG goes to the
    /// same name with .png.
    #[arg(long)]
    out: PathBuf,
    /// Levels of detail written to `--out`, as `sylva tree grow --lod`: `0`, the default, the
    /// adapted tree's full-detail mesh alone (Blender and glTF viewers draw every node: the
    /// whole chain stacked the crown hull and billboard over the tree, trial 39); `all` the
    /// chain `<species>_LOD0…3`; or a list such as `0,3`.
    #[arg(long, default_value = "0")]
    lod: String,
    /// Side of the exported textures in texels, as `sylva tree grow --texture-size`: a power
    /// of two from 256 to 4096; 2048 by default.
    #[arg(long, default_value_t = 2048)]
    texture_size: u32,
    /// The full level's foliage as leaf cards and leaf-cluster cards, as `sylva tree grow
    /// --leaf-clusters`, instead of the default individual leaves.
    #[arg(long)]
    leaf_clusters: bool,
    /// Print one JSON object on stdout (nodes_before, nodes_after, bent, pruned, pruned_light,
    /// pruned_collision, recomputed_nodes, adapt_ms, regrow_ms, neighbours, out, png).
    #[arg(long)]
    json: bool,
}

/// Runs a tree subcommand.
pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Grow { species, model, age, obstacle, adapt_to, seed, open_grown, species_dir, out, lod, texture_size, leaf_clusters } => {
            let habit = if open_grown { forest_form::Habit::Open } else { forest_form::Habit::Forest };
            let look = LookChoice { texture_px: texture_size, hero: !leaf_clusters };
            grow(&species, model, age, &obstacle, &adapt_to, seed, habit, species_dir.as_deref(), &out, &lod, look)
        }
        Command::Adapt(a) => adapt(&a),
    }
}

/// The species `name` (id or name) of `lib`, or an error naming `what` (the option, or
/// "species") and listing the ids.
fn find_species(lib: &sylva::species::SpeciesLibrary, name: &str, what: &str) -> anyhow::Result<sylva::species::Species> {
    lib.find(name).map(|i| lib.species[i as usize].clone()).with_context(|| format!("{what} {name:?}: not in the library{} (ids: {})", lib.did_you_mean(name), lib.species.iter().map(|s| s.id.as_str()).collect::<Vec<_>>().join(", ")))
}

/// The levels `levels` of `chain` (indices 0–3, from [`sylva::job::export::parse_levels`]),
/// the others left empty: the glTF writer skips levels without triangles.
fn only_levels(chain: &sylva::mesh::LodChain, levels: &[usize]) -> sylva::mesh::LodChain {
    sylva::mesh::LodChain { levels: chain.levels.iter().enumerate().map(|(i, l)| if levels.contains(&i) { l.clone() } else { Default::default() }).collect(), freed: None }
}

/// Refuses `--age` beyond the species' maximum age.
fn check_age(age: f32, sp: &sylva::species::Species) -> anyhow::Result<()> {
    anyhow::ensure!(age <= sp.life.max_age_yr, "--age {age}: expected at most the maximum age of {} ({} years, `life.max_age_yr` in its species file)", sp.id, sp.life.max_age_yr);
    Ok(())
}

/// How `tree grow` and `tree adapt` draw the tree they write: `--texture-size` and whether
/// the full level carries individual leaves (the default) or `--leaf-clusters`.
#[derive(Debug, Clone, Copy)]
struct LookChoice {
    texture_px: u32,
    hero: bool,
}

/// Sides of the trunk's tube in a tree with individual leaves (the root flare's lobes need
/// them: 5 lobes of 24 / 5 sides each); thinner branches get fewer (`LodOptions::sides`).
const HERO_SIDES: u32 = 24;

/// The chain `tree grow` and `tree adapt` write for `sk` with its leaf cards `lv` (of species
/// `sp`, a stem of `dbh_cm` when known): with individual leaves ([`LookChoice::hero`]) the
/// hero chain (`hero_chain`: every leaf a card, the stem tapered to the DBH with its root
/// flare, Kozak 1988; its leaf sprays kept out of `obstacles`), else `lone_chain`; and the
/// line that says what the full level carries.
fn tree_chain(sk: &Skeleton, lv: &mut Leaves, sp: &sylva::species::Species, dbh_cm: f32, look: LookChoice, obstacles: &[Obstacle]) -> (sylva::mesh::LodChain, String, serde_json::Value) {
    use sylva::structure::taper::{Flare, StemTaper, TaperForm};
    if look.hero {
        let stem = StemTaper::new(TaperForm::of_species(sp), dbh_cm, sk.height()).map(|t| t.with_flare(Flare::of_species(sp)));
        let o = sylva::structure::mesh::LodOptions { stem, sides: HERO_SIDES, ..sylva::structure::mesh::LodOptions::for_species(sp) };
        let blocked = |p: Vec3| obstacles.iter().any(|ob| ob.contains(p));
        let (chain, h) = sylva::job::leaf_area::hero_chain(sk, lv, sp, &o, &blocked);
        let line = format!(
            "leaf area {:.1} m² (crown LAI {:.1} over a crown projection of {:.1} m²): {} individual leaves of {:.3} m carry {:.1} m²{}",
            h.target_m2,
            h.lai,
            h.projection_m2,
            h.leaves,
            h.leaf_length_m,
            h.leaves_m2,
            stem.map_or(String::new(), |t| format!("; stem tapered to DBH {:.1} cm with its root flare ({} lobes)", t.dbh_cm, t.flare.map_or(0, |f| f.lobes)))
        );
        let j = serde_json::json!({"crown_projection_m2": h.projection_m2, "leaf_area_m2": h.target_m2, "leaf_cluster_cards": 0, "leaf_cards": h.leaves, "leaf_cards_m2": h.leaves_m2});
        (chain, line, j)
    } else {
        let (chain, f) = lone_chain(sk, lv, sp);
        let j = serde_json::json!({"crown_projection_m2": f.projection_m2, "leaf_area_m2": f.target_m2.max(f.cards_m2), "leaf_cluster_cards": f.sprigs});
        (chain, fill_line(&f), j)
    }
}

#[allow(clippy::too_many_arguments)]
fn grow(species: &str, model: Model, age: f32, obstacles: &[String], adapt_to: &[String], seed: u64, habit: forest_form::Habit, species_dir: Option<&Path>, out: &Path, lod: &str, look: LookChoice) -> anyhow::Result<()> {
    anyhow::ensure!(age.is_finite() && age > 0.0, "--age {age}: expected a positive number of years");
    let lod_levels = sylva::job::export::parse_levels_for("sylva tree grow", lod)?;
    sylva::output::gltf::check_texture_size("--texture-size", look.texture_px)?;
    // the output is checked before any work, as `render` and `export` check theirs (round 33's
    // trial: a folder named d3.obj was found only after the tree was grown and its textures
    // written, with a bare "Is a directory")
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    anyhow::ensure!(matches!(ext.as_str(), "glb" | "obj"), "--out {}: expected a .glb or .obj file name", out.display());
    super::check_out_file(out, "--out")?;
    let lib = super::simulate::library(species_dir.as_slice())?;
    let sp = find_species(&lib, species, "--species")?;
    check_age(age, &sp)?;
    let png = out.with_extension("png");
    if png.is_dir() {
        anyhow::bail!("{}: the preview would go there, but it is a folder", png.display());
    }
    let obs: Vec<Obstacle> = obstacles.iter().map(|s| Obstacle::parse(s)).collect::<Result<_, _>>()?;
    let parse_later = |s: &String| Obstacle::parse(s).map_err(|e| anyhow::anyhow!("{}", e.to_string().replace("--obstacle", "--adapt-to")));
    let later: Vec<Obstacle> = adapt_to.iter().map(parse_later).collect::<Result<_, _>>()?;
    let t0 = std::time::Instant::now();
    let m = match model {
        Model::Ecomod => {
            // refused rather than ignored with a warning few saw (found by a trial): EcoMod's
            // strands grow without an environment (Zamuda et al.)
            anyhow::ensure!(
                obs.is_empty(),
                "--obstacle {}: the EcoMod model grows without obstacles; use --adapt-to with the same obstacle to bend and prune the grown tree away from it (Plastic Trees), or --model light or laplacian to grow among it",
                obstacles.join(" --obstacle ")
            );
            species_tree::Model::EcoMod
        }
        Model::Light => species_tree::Model::Light,
        Model::Laplacian => species_tree::Model::Laplacian,
    };
    anyhow::ensure!(habit == forest_form::Habit::Forest || m == species_tree::Model::EcoMod, "--open-grown: only the EcoMod model is sized to the species' open-grown dimensions; the light-guided and Laplacian models grow inside the open-grown crown envelope already");
    let (grown, form) = forest_form::grow_formed_tree(&sp, m, age, &obs, seed, habit)?;
    let (mut sk, mut leaves): (Skeleton, Leaves) = (grown.skeleton, grown.leaves);
    let grow_s = t0.elapsed().as_secs_f64();
    let mut adapted = None;
    if !later.is_empty() {
        let all: Vec<Obstacle> = obs.iter().chain(&later).copied().collect();
        // analysed in the environment it grew in (its own obstacles), adapted to all of them:
        // the obstacles it grew beside are not counted twice
        let mut pt = PlasticTree::analyse(&sk, &sp.architecture.plastic, &Environment::with_obstacles(&obs), Some(mean_internode(&sk)))?;
        pt.clearance_m = sp.architecture.ecomod.leaf_size_m.max(0.0);
        let ta = std::time::Instant::now();
        let rep = pt.adapt(&Environment::with_obstacles(&all))?;
        let new_sk = pt.skeleton();
        let adapt_s = ta.elapsed().as_secs_f64();
        // the model's own leaves hang on node ids that pruning renumbers: re-leaf the tips
        leaves = species_tree::tip_leaves(&new_sk, &sp.architecture.ecomod);
        sk = new_sk;
        // regrowing among the obstacles is only the time comparison: when the model cannot
        // (a wall through the root: round 33's trial got "field root … expected a root outside
        // obstacles" naming neither the option nor the wall), the adapted tree is still written
        let tr = std::time::Instant::now();
        let regrow_s = match species_tree::grow_species_tree(&sp, m, age, &all, seed) {
            Ok(_) => Some(tr.elapsed().as_secs_f64()),
            Err(e) => {
                eprintln!("warning: --adapt-to {}: the tree cannot be regrown among these obstacles for the time comparison ({e}); the grown tree, bent and pruned, is written", adapt_to.join(" --adapt-to "));
                None
            }
        };
        adapted = Some((rep, adapt_s, regrow_s));
    }
    let t1 = std::time::Instant::now();
    let all_obstacles: Vec<Obstacle> = obs.iter().chain(&later).copied().collect();
    let (chain, fill, _) = tree_chain(&sk, &mut leaves, &sp, form.dbh_cm, look, &all_obstacles);
    let mesh_s = t1.elapsed().as_secs_f64();
    let mut glb_o = glb_options_sized(&sp, look.texture_px, &lod_levels);
    // the billboard shows this tree, baked from its full level (issue 32, round 46)
    glb_o.look = glb_o.look.with_tree_impostor(&chain);
    // a missing output folder is made (as `tree adapt`, `render` and `run` do), naming the
    // option when it cannot be (a bare OS error was all a trial got)
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("--out {}: creating its folder {}", out.display(), dir.display()))?;
    }
    // the levels not asked for written empty (the writers skip levels without triangles)
    let written = only_levels(&chain, &lod_levels);
    match ext.as_str() {
        "glb" => {
            sylva::output::gltf::write_glb(out, &written, &glb_o)?;
            sylva::output::gltf::write_skeleton_sidecar(out, &sk, Some(&sp.id))?;
        }
        "obj" => sylva::output::obj::write_obj(out, &chain, Some(&lod_levels), &sp.id, &glb_o.look)?,
        _ => anyhow::bail!("--out {}: expected a .glb or .obj file name", out.display()),
    }
    let img = sylva::output::tree_preview::lod_preview(&chain, &glb_options(&sp).look.with_tree_impostor(&chain), 360, 540);
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    sylva::output::write_atomic(&png, &bytes)?;
    println!("species {} ({}), model {:?}, seed {seed}, age {age} yr", sp.id, sp.identity.scientific_name, model);
    // said where the model's cycles stop short of the age (found by a trial: `--age 500` looked
    // like 500 years of light-guided growth)
    if matches!(model, Model::Light) && age.round() > 60.0 {
        println!("light-guided: 60 cycles, the model's most, inside the crown envelope of a {age}-year tree");
    }
    println!("nodes {}, leaves {}, height {:.2} m, crown radius {:.2} m", sk.len(), leaves.len(), sk.height(), sylva::structure::crown_radius(&sk, &leaves));
    // the species at this age (issue 32: previews scaled to fit hid whether the height followed
    // the species' curve)
    let habit_name = if form.habit == forest_form::Habit::Forest { "stand-grown" } else { "open-grown" };
    println!(
        "species at {age} yr ({habit_name}): height {:.2} m (site index h100 {:.1} m), DBH {:.1} cm, crown base {:.2} m ({:.0} % of the height clear), crown radius {:.2} m, crown length {:.2} m, crown width/length {:.2}",
        form.height_m,
        form.site_index_m,
        form.dbh_cm,
        form.crown_base_m,
        100.0 * form.clear_bole_share(),
        form.crown_radius_m,
        form.crown_length_m(),
        form.width_to_length()
    );
    let ms = forest_form::ArchitectureMeasures::of(&sk, &leaves);
    println!(
        "measured tree: height {:.2} m, crown base {:.2} m ({:.0} % clear), crown radius {:.2} m (mean of 8 sectors), crown width/length {:.2}, order-1 branches {} at {:.0}° from the vertical (mean), their ends at {:.0}°, crown widest at {:.2} of its length",
        ms.height_m,
        ms.crown_base_m,
        100.0 * ms.clear_bole_share(),
        ms.crown_radius_m,
        ms.width_to_length(),
        ms.branches,
        ms.branch_angle_deg,
        ms.limb_end_angle_deg,
        ms.widest_at
    );
    println!("{fill}");
    for (i, l) in chain.levels.iter().enumerate() {
        println!("LOD{i}: {:>8} triangles (bark {}, foliage {})", l.triangle_count(), l.bark.triangle_count(), l.leaves.triangle_count());
    }
    println!("grow {:.1} ms, mesh {:.1} ms", grow_s * 1e3, mesh_s * 1e3);
    if let Some((rep, adapt_s, regrow_s)) = adapted {
        let (b, pl, pc) = (rep.bent, rep.pruned_light, rep.pruned_collision);
        let regrow = regrow_s.map_or("not possible (see the warning)".to_string(), |r| format!("{:.1} ms", r * 1e3));
        println!("adapted (Plastic Trees): bent {b}, pruned {pl} for light + {pc} in obstacles; adapt {:.1} ms, regrowing among the obstacles {regrow}", adapt_s * 1e3);
    }
    println!("wrote {} and {}", out.display(), png.display());
    Ok(())
}

/// What [`lone_chain`] gave the full level, as a line.
fn fill_line(f: &sylva::job::leaf_area::LoneLeafArea) -> String {
    let what = if f.card_growth < 1.0 {
        format!("shortened ×{:.2} and {} removed", f.card_growth, f.cards_removed)
    } else {
        format!("lengthened ×{:.2}, and {} leaf-cluster cards added", f.card_growth, f.sprigs)
    };
    format!("leaf area {:.1} m² (crown LAI {:.1} over a crown projection of {:.1} m²): leaf cards {:.1} m² before, {what}", f.target_m2, f.lai, f.projection_m2, f.cards_m2)
}

/// glTF options of a tree of `sp`: named by its species id, its summer look, LOD levels on top
/// of each other (a LOD group).
fn glb_options(sp: &sylva::species::Species) -> sylva::output::gltf::GlbOptions {
    sylva::output::gltf::GlbOptions { name: sp.id.clone(), look: sylva::output::gltf::Look::for_species(sp, sylva::species::Season::Summer), spacing_m: 0.0 }
}

/// [`glb_options`] with textures of `texture_px` texels for the levels `levels` (leaf and
/// bark always; `FoliageTextures::for_species_levels`).
fn glb_options_sized(sp: &sylva::species::Species, texture_px: u32, levels: &[usize]) -> sylva::output::gltf::GlbOptions {
    let textures = sylva::structure::texture::FoliageTextures::for_species_levels(sp, sylva::species::Season::Summer, texture_px, levels);
    sylva::output::gltf::GlbOptions { look: sylva::output::gltf::Look { name: sp.id.clone(), textures }, ..glb_options(sp) }
}

/// Mean segment length of the skeleton (m, ≥ 0.05): the internode length l_i of Plastic Trees
/// eq. 7 for a tree grown by any model.
fn mean_internode(sk: &Skeleton) -> f32 {
    let n = sk.nodes.len();
    if n < 2 {
        return 0.15;
    }
    ((1..n).map(|k| sk.segment_length(k)).sum::<f32>() / (n - 1) as f32).max(0.05)
}

/// A `--neighbour SPECIES@X,Y[,AGE]`.
/// Farthest a `--neighbour` may stand from the adapted tree (m).
const MAX_NEIGHBOUR_M: f32 = 100.0;

fn parse_neighbour(s: &str, default_age: f32) -> anyhow::Result<(String, Vec3, f32)> {
    let form = "--neighbour SPECIES@X,Y[,AGE] (metres, years; e.g. beech@3,0,20)";
    let (sp, rest) = s.split_once('@').with_context(|| format!("--neighbour {s}: expected {form}"))?;
    let v: Vec<f32> = rest.split(',').map(|t| t.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| anyhow::anyhow!("--neighbour {s}: expected {form}"))?;
    anyhow::ensure!(v.len() == 2 || v.len() == 3, "--neighbour {s}: expected {form}");
    anyhow::ensure!(v.iter().all(|x| x.is_finite()), "--neighbour {s}: expected finite numbers (no NaN or infinity)");
    let age = v.get(2).copied().unwrap_or(default_age);
    anyhow::ensure!(age > 0.0, "--neighbour {s}: age {age}: expected a positive number of years");
    anyhow::ensure!(v[0].hypot(v[1]) <= MAX_NEIGHBOUR_M, "--neighbour {s}: {:.0} m from the tree; expected a neighbour within {MAX_NEIGHBOUR_M} m (trees farther apart do not interact)", v[0].hypot(v[1]));
    Ok((sp.trim().to_string(), Vec3::new(v[0], v[1], 0.0), age))
}

fn adapt(a: &AdaptArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.age.is_finite() && a.age > 0.0, "--age {}: expected a positive number of years", a.age);
    let ext = a.out.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    anyhow::ensure!(ext == "glb", "--out {}: expected a .glb file name", a.out.display());
    super::check_out_file(&a.out, "--out")?;
    // the three files written (glb, skeleton sidecar, before/after PNG), checked before any is
    // written, so that a bad path does not leave a partial set behind
    let outputs = [a.out.clone(), sylva::output::gltf::skeleton_sidecar_path(&a.out), a.out.with_extension("png")];
    for f in &outputs {
        anyhow::ensure!(!f.is_dir(), "--out {}: {} is a folder; expected to write a file there", a.out.display(), f.display());
    }
    // checked before anything is grown (a bad level names `--lod`, as `tree grow` does)
    let lod_levels = sylva::job::export::parse_levels_for("sylva tree adapt", &a.lod)?;
    sylva::output::gltf::check_texture_size("--texture-size", a.texture_size)?;
    let lib = super::simulate::library(a.species_dir.as_deref().as_slice())?;
    let find = |name: &str| find_species(&lib, name, "species");
    // the input tree is read first, so that a missing or wrong file is named as such (a trial
    // was told that the sidecar of a missing file records no species)
    let input_skeleton = match &a.input {
        Some(glb) => {
            anyhow::ensure!(!glb.is_dir(), "--input {}: is a folder; expected a .glb written by `sylva tree grow`", glb.display());
            anyhow::ensure!(glb.is_file(), "--input {}: no such file", glb.display());
            // a PNG preview (or any other file) beside the tree shares its skeleton's name, so
            // its extension is checked (a trial gave the PNG and got the tree adapted)
            let in_ext = glb.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
            anyhow::ensure!(in_ext == "glb", "--input {}: expected a .glb written by `sylva tree grow` or `sylva tree adapt`", glb.display());
            let side = sylva::output::gltf::skeleton_sidecar_path(glb);
            anyhow::ensure!(side.is_file(), "--input {}: no skeleton beside it (expected {}, written by `sylva tree grow --out NAME.glb`)", glb.display(), side.display());
            Some(sylva::output::gltf::read_skeleton_sidecar(glb)?)
        }
        None => None,
    };
    // the species: given, or (with --input) the one the tree's sidecar records
    let recorded = match &a.input {
        Some(glb) => sylva::output::gltf::read_skeleton_sidecar_species(glb)?,
        None => None,
    };
    let species = match (&a.species, &recorded) {
        (Some(s), _) => s.clone(),
        (None, Some(r)) => r.clone(),
        (None, None) if a.input.is_some() => anyhow::bail!("--species: expected the tree's species (the skeleton sidecar of --input records none: it was written before round 24)"),
        (None, None) => anyhow::bail!("--species: expected the species of the tree to grow and adapt (e.g. --species beech), or --input with a tree written by `sylva tree grow`"),
    };
    let sp = find_species(&lib, &species, "--species")?;
    if a.input.is_none() {
        check_age(a.age, &sp)?;
    }
    let obstacles: Vec<Obstacle> = a.obstacle.iter().map(|s| Obstacle::parse(s)).collect::<Result<_, _>>()?;
    // the trunk base: the origin for a tree grown here, wherever a file's tree stands
    let check_base = |base: Vec3| -> anyhow::Result<()> {
        for (o, text) in obstacles.iter().zip(&a.obstacle) {
            anyhow::ensure!(!o.contains(base) && o.signed_distance(base) > 0.0, "--obstacle {text}: contains the trunk base at ({}, {}, {}); expected an obstacle beside the tree", base.x, base.y, base.z);
        }
        Ok(())
    };
    if a.input.is_none() {
        check_base(Vec3::ZERO)?;
    }
    let neighbours: Vec<(String, Vec3, f32)> = a.neighbour.iter().map(|s| parse_neighbour(s, a.age)).collect::<anyhow::Result<_>>()?;
    let model = match a.model {
        Model::Ecomod => species_tree::Model::EcoMod,
        Model::Light => species_tree::Model::Light,
        Model::Laplacian => species_tree::Model::Laplacian,
    };
    let sk = match (&a.input, input_skeleton) {
        (Some(glb), Some(sk)) => {
            let side = sylva::output::gltf::skeleton_sidecar_path(glb);
            // a tree grown as another species would be adapted with this species' parameters
            // and leaves without a word (found by a trial); sidecars before round 24 carry no id
            if let Some(grown_as) = &recorded {
                anyhow::ensure!(*grown_as == sp.id, "--species {species}: the tree in --input {} was grown as {grown_as} (its skeleton sidecar {}); expected --species {grown_as} (or no --species)", glb.display(), side.display());
            }
            check_base(sk.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO))?;
            sk
        }
        _ => species_tree::grow_species_tree(&sp, model, a.age, &[], a.seed)?.skeleton,
    };
    // the sky the trees grew under (brightest point at the zenith) and the one they adapt to
    // (global light from --latitude), both with the --sky-rings quadrature, so that the
    // quadrature alone changes nothing
    let brightest = match a.latitude {
        Some(lat) => {
            anyhow::ensure!(lat.is_finite() && (-90.0..=90.0).contains(&lat), "--latitude {lat}: expected degrees from -90 to 90");
            Sky::from_latitude(lat).brightest
        }
        None => Vec3::Z,
    };
    let rings = |b: Vec3| Sky::with_rings(b, &a.sky_rings).map_err(|e| anyhow::anyhow!("--sky-rings {}: {e}", a.sky_rings.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(",")));
    let grown_in = Environment { sky: rings(Vec3::Z)?, ..Environment::open() };
    let adapt_sky = rings(brightest)?;
    let base_r = sk.nodes.first().map(|n| n.radius).unwrap_or(0.0);
    let mut trees = vec![PlasticTree::analyse(&sk, &sp.architecture.plastic, &grown_in, None)?];
    trees[0].clearance_m = sp.architecture.ecomod.leaf_size_m.max(0.0);
    let mut spots = vec![Vec3::ZERO];
    for (i, (name, at, age)) in neighbours.iter().enumerate() {
        let nsp = find(name).with_context(|| format!("--neighbour {}", a.neighbour[i]))?;
        // refused as --age is (it was cut to the maximum age without a word: found by a trial)
        anyhow::ensure!(*age <= nsp.life.max_age_yr, "--neighbour {}: age {age}: expected at most the maximum age of {} ({} years, `life.max_age_yr` in its species file)", a.neighbour[i], nsp.id, nsp.life.max_age_yr);
        for (j, s) in spots.iter().enumerate() {
            anyhow::ensure!(s.distance(*at) >= 0.5, "--neighbour {}: at {:.2} m from {} at ({}, {}); expected trees at least 0.5 m apart", a.neighbour[i], s.distance(*at), if j == 0 { "the tree".to_string() } else { format!("neighbour {j}") }, s.x, s.y);
        }
        for (o, text) in obstacles.iter().zip(&a.obstacle) {
            anyhow::ensure!(o.signed_distance(*at) > 0.0, "--neighbour {}: stands inside --obstacle {text}", a.neighbour[i]);
        }
        spots.push(*at);
        let g = species_tree::grow_species_tree(&nsp, model, age.min(nsp.life.max_age_yr), &[], a.seed + 1 + i as u64)?;
        let mut t = PlasticTree::analyse(&g.skeleton, &nsp.architecture.plastic, &grown_in, None)?;
        t.translate(*at);
        trees.push(t);
    }
    let before: Vec<PlasticTree> = trees.clone();
    let env = Environment { sky: adapt_sky, ..Environment::with_obstacles(&obstacles) };
    let ta = std::time::Instant::now();
    let rep = adapt_group(&mut trees, &env)?;
    let adapt_ms = ta.elapsed().as_secs_f64() * 1e3;
    // our light-guided model regrowing the same tree beside the same obstacles, in this run
    let tr = std::time::Instant::now();
    species_tree::grow_species_tree(&sp, species_tree::Model::Light, a.age.min(sp.life.max_age_yr), &obstacles, a.seed)?;
    let regrow_ms = tr.elapsed().as_secs_f64() * 1e3;
    let adapted = trees[0].skeleton();
    let mut leaves = species_tree::tip_leaves(&adapted, &sp.architecture.ecomod);
    // the stem's DBH from the species' stand-grown height–diameter curve at the tree's height
    let dbh = sylva::structure::forest_form::stand_dbh_cm(&sp, adapted.height());
    let (chain, fill_text, fill) = tree_chain(&adapted, &mut leaves, &sp, dbh, LookChoice { texture_px: a.texture_size, hero: !a.leaf_clusters }, &obstacles);
    // a missing output folder is created (as `sylva render` and `sylva run` do) once the
    // input has been checked, just before the files are written
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("--out {}: creating its folder {}", a.out.display(), dir.display()))?;
    }
    let mut glb_o = glb_options_sized(&sp, a.texture_size, &lod_levels);
    glb_o.look = glb_o.look.with_tree_impostor(&chain);
    sylva::output::gltf::write_glb(&a.out, &only_levels(&chain, &lod_levels), &glb_o)?;
    sylva::output::gltf::write_skeleton_sidecar(&a.out, &adapted, Some(&sp.id))?;
    let png = a.out.with_extension("png");
    let (drawing, along) = before_after(&before, &trees, &obstacles, 420, 480);
    // a strip above the drawing for its caption
    const STRIP: u32 = 56;
    let mut img = image::RgbaImage::from_pixel(drawing.width(), drawing.height() + STRIP, image::Rgba([235, 240, 245, 255]));
    for (x, y, p) in drawing.enumerate_pixels() {
        img.put_pixel(x, y + STRIP, image::Rgba([p.0[0], p.0[1], p.0[2], 255]));
    }
    // the height is the adapted tree's (brown); with neighbours (green) in view, say so
    let what = if neighbours.is_empty() { format!("{:.1} m high", sk.height()) } else { format!("brown tree {:.1} m", sk.height()) };
    sylva::output::maps::stamp_caption(&mut img, &format!("before | after: {what}, seen along {along}"))?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    sylva::output::write_atomic(&png, &bytes)?;
    let r = rep.trees[0];
    if a.json {
        let j = serde_json::json!({
            "species": sp.id, "nodes_before": r.nodes_before, "nodes_after": r.nodes_after, "bent": r.bent,
            "pruned": r.pruned_light + r.pruned_collision, "pruned_light": r.pruned_light, "pruned_collision": r.pruned_collision,
            "recomputed_nodes": rep.recomputed_nodes, "adapt_ms": adapt_ms, "regrow_ms": regrow_ms, "neighbours": neighbours.len(),
            "trunk_base_radius_m": base_r, "out": a.out.display().to_string(), "png": png.display().to_string(),
        });
        let mut j = j;
        if let (Some(o), Some(f)) = (j.as_object_mut(), fill.as_object()) {
            o.extend(f.clone());
        }
        println!("{j}");
    } else {
        println!("species {}: {} -> {} nodes, bent {}, pruned {} for light + {} in obstacles, {} nodes recomputed", sp.id, r.nodes_before, r.nodes_after, r.bent, r.pruned_light, r.pruned_collision, rep.recomputed_nodes);
        println!("adapt {adapt_ms:.1} ms, regrowing it{} {regrow_ms:.1} ms", if obstacles.is_empty() { "" } else { " among the obstacles" });
        println!("{fill_text}");
        println!("wrote {}, {} and {}", a.out.display(), sylva::output::gltf::skeleton_sidecar_path(&a.out).display(), png.display());
    }
    Ok(())
}

/// Paper Fig. 6 style before/after side view (z up), and the direction it looks along: left the
/// input with the parts that will be
/// pruned in blue, right the adapted tree with every segment red by its own bend angle (0° dark
/// brown → ≥ 5° red); neighbours in green behind the tree, obstacles grey (spheres as discs,
/// other solids as their bounding rectangles). The view looks along +y (x to the right) unless
/// there is no obstacle and the adapted tree moved more along y than along x (global light from
/// `--latitude` bends it north or south): then it looks along −x (y to the right), so that the
/// change shows.
fn before_after(before: &[PlasticTree], after: &[PlasticTree], obstacles: &[Obstacle], w: u32, h: u32) -> (image::RgbImage, &'static str) {
    let shift = match (before.first(), after.first()) {
        (Some(b), Some(a)) => b.positions().iter().zip(a.positions()).zip(a.fates()).filter(|(_, f)| **f == Fate::Alive).map(|((p, q), _)| (*q - *p).abs()).sum::<Vec3>(),
        _ => Vec3::ZERO,
    };
    // horizontal axis of the picture: 0 = x, 1 = y
    let axis = if obstacles.is_empty() && shift.y > shift.x { 1 } else { 0 };
    let hor = |p: Vec3| if axis == 0 { p.x } else { p.y };
    let mut img = image::RgbImage::from_pixel(2 * w, h, image::Rgb([235, 240, 245]));
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    for t in before.iter().chain(after) {
        for p in t.positions() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let (lo_h, hi_h) = (hor(lo), hor(hi));
    let margin = 12.0;
    let s = ((w as f32 - 2.0 * margin) / (hi_h - lo_h).max(1e-3)).min((h as f32 - 2.0 * margin) / (hi.z - lo.z).max(1e-3));
    let px = |x0: u32, p: Vec3| (x0 as f32 + margin + (hor(p) - lo_h) * s, h as f32 - margin - (p.z - lo.z) * s);
    let grey = image::Rgb([150, 150, 150]);
    for x0 in [0, w] {
        for o in obstacles {
            if let Obstacle::Sphere { center, radius } = *o {
                let (cx, cy) = px(x0, center);
                let r = radius * s;
                for y in (cy - r).max(0.0) as u32..((cy + r).min(h as f32 - 1.0).max(0.0) as u32) {
                    for x in (cx - r).max(x0 as f32) as u32..((cx + r).min((x0 + w - 1) as f32).max(0.0) as u32) {
                        if (x as f32 + 0.5 - cx).hypot(y as f32 + 0.5 - cy) <= r {
                            img.put_pixel(x, y, grey);
                        }
                    }
                }
                continue;
            }
            let (a, b) = match *o {
                Obstacle::Box { min, max } => (min, max),
                Obstacle::Sphere { center, radius } => (center - radius, center + radius),
                // the half-space beyond x, away from the origin: towards +x or towards −x
                Obstacle::Wall { x } => (Vec3::new(if x > 0.0 { x } else { lo.x.min(x) - 10.0 }, 0.0, lo.z), Vec3::new(if x > 0.0 { hi.x.max(x) + 10.0 } else { x }, 0.0, hi.z + 10.0)),
                Obstacle::FiniteWall { x, height, .. } => (Vec3::new(if x > 0.0 { x } else { lo.x.min(x) - 10.0 }, 0.0, 0.0), Vec3::new(if x > 0.0 { hi.x.max(x) + 10.0 } else { x }, 0.0, height.min(hi.z + 10.0))),
                Obstacle::OrientedBox { .. } | Obstacle::Prism { .. } => o.bounds(),
            };
            let (a, b) = (a.min(b), a.max(b));
            let (ax, ay) = px(x0, Vec3::new(a.x.max(lo.x - 10.0), a.y.max(lo.y - 10.0), a.z));
            let (bx, by) = px(x0, Vec3::new(b.x, b.y, b.z));
            for y in by.max(0.0) as u32..(ay.min(h as f32 - 1.0).max(0.0) as u32) {
                for x in ax.max(x0 as f32) as u32..(bx.min((x0 + w - 1) as f32).max(0.0) as u32) {
                    img.put_pixel(x, y, grey);
                }
            }
        }
    }
    // neighbours first, so that the adapted tree is drawn over them
    let order = (1..before.len()).chain(0..before.len().min(1));
    for i in order {
        let (b, t) = (&before[i], &after[i]);
        let sk = b.input();
        for k in 1..sk.len() {
            let p = sk.nodes[k].parent.unwrap_or(0) as usize;
            let pruned = t.fates()[k] != Fate::Alive;
            let col = if i > 0 { [60, 150, 60] } else if pruned { [40, 80, 230] } else { [90, 60, 40] };
            line(&mut img, px(0, sk.nodes[p].pos), px(0, sk.nodes[k].pos), col, 0, w);
            if !pruned {
                let a = (t.bend_angles()[k].to_degrees() / 5.0).clamp(0.0, 1.0);
                let col = if i > 0 { [60, 150, 60] } else { [(90.0 + 165.0 * a) as u8, (60.0 * (1.0 - a)) as u8, (40.0 * (1.0 - a)) as u8] };
                line(&mut img, px(w, t.positions()[p]), px(w, t.positions()[k]), col, w, 2 * w);
            }
        }
    }
    (img, if axis == 0 { "y (x to the right)" } else { "-x (y to the right)" })
}

fn line(img: &mut image::RgbImage, a: (f32, f32), b: (f32, f32), col: [u8; 3], x0: u32, x1: u32) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    for i in 0..=n {
        let t = i as f32 / n as f32;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        if x >= x0 as f32 && x < x1 as f32 && y >= 0.0 && (y as u32) < img.height() {
            img.put_pixel(x as u32, y as u32, image::Rgb(col));
        }
    }
}
