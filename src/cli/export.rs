//! `sylva export RUN_DIR --year Y --area X0,Y0,X1,Y1 --out stand.glb [--lod all] [--stats s.json]`:
//! the adapted trees of an area with the terrain patch and the obstacles as one glTF scene
//! ([`sylva::job::export`]); `sylva export RUN_DIR --year Y --instances --out forest.glb`: every
//! live tree of the run (or of `--area`) as an instance of its species and age class
//! (`EXT_mesh_gpu_instancing`).
use anyhow::Context;
use std::path::PathBuf;
use sylva::species::Season;

/// Arguments of `sylva export`.
#[derive(clap::Args)]
pub struct Args {
    /// Run directory written by `sylva run` / `sylva simulate`.
    pub run_dir: PathBuf,
    /// Snapshot year (default: the last one).
    #[arg(long)]
    pub year: Option<u32>,
    /// Area X0,Y0,X1,Y1 (m, world coordinates from the terrain's south-west corner, as in the
    /// inventory's x_m, y_m).
    /// Required for a stand export; with `--instances` optional (default: the whole site).
    #[arg(long, allow_hyphen_values = true)]
    pub area: Option<String>,
    /// Export every live tree (of the whole site, or of `--area`) as an instance of its species
    /// and age class, and the regeneration layer's saplings as instances of their species'
    /// sapling model (`EXT_mesh_gpu_instancing`, required: read by three.js, Babylon.js, Unity
    /// glTFast and Blender 4.1+; refused by Blender before 4.1, released Godot 4 and Unreal's
    /// glTF importer, see docs/guide.md), not adapted one by one: the whole forest for a game
    /// engine.
    #[arg(long)]
    pub instances: bool,
    /// Season of the foliage colours: spring, summer, autumn (or fall), winter.
    #[arg(long, default_value = "summer", value_parser = super::render::parse_season)]
    pub season: Season,
    /// Levels of detail to write: `0` (full detail), the default of a stand export, one
    /// full-detail mesh per tree (what Blender, three.js and glTF viewers show: they draw every
    /// node); `all` the LOD chain `<name>_LOD0…3` of each tree (with `--instances`, of each
    /// species and age-class model) for game engines' LOD groups; or a list such as `0,1`.
    /// With `--instances` the default is the finest single level whose triangles over all the
    /// trees stay within 20 million (a whole forest: its billboards, level 3).
    #[arg(long)]
    pub lod: Option<String>,
    /// Write the export's figures as JSON (trees, trees_15m, nodes_median and nodes_min over
    /// the trees of 15 m and taller, leaf_cards, adapt_s, triangles, levels, saplings,
    /// level_triangles (the triangles of the trees and saplings at each level 0–3, written or
    /// not: what each level alone would draw, terrain and obstacles left out); for a stand
    /// export also analysis_s and adaptation_s (the two parts of adapt_s), analyses (distinct
    /// Plastic Trees analyses: one per class of species, 5-year age, 5 % height and crown
    /// radius and crown base, of the exported trees and of their neighbours within the halo),
    /// nodes_total and nodes_before_adaptation (all exported trees), pruned_light and
    /// pruned_collision (nodes the adaptation removed), sprig_cards (leaf-cluster cards of
    /// `--full-detail`, or of the instanced models' full level, each tree counted); a stand
    /// export's wall times (s) of its phases: read_s, mesh_s, write_s, texture_s (beside the
    /// adaptation), finish_s and total_s). Its folder is made when missing.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// A lighter stand export: the open-grown skeleton of each tree capped at this many EcoMod
    /// strands (at least 8; 48 was the default before full detail), shed below the simulated
    /// crown base, so a tree keeps far fewer than two nodes a strand (48 strands: about 25–60 nodes),
    /// its leaf cards enlarged to the crown's leaf area. By default every tree has full detail
    /// (see `--full-detail`).
    #[arg(long, conflicts_with_all = ["full_detail", "instances"])]
    pub max_strands: Option<u32>,
    /// The default (kept for scripts): every tree of a stand export with its species' strand
    /// count at its age, as `sylva tree grow` gives it (hundreds to thousands of nodes a canopy
    /// tree), grown as a forest tree above the simulated crown base, bent by Plastic Trees and
    /// pruned where it meets its neighbours' wood; its crown's leaf area as its leaf cards
    /// plus leaf-cluster cards (sprigs). The 0.25 ha `1150,850,1200,900` of the default run's
    /// year 150: about 10 s and 460 MB (`--max-strands 48`: about 4 s and 50 MB).
    #[arg(long, conflicts_with = "instances")]
    pub full_detail: bool,
    /// Side of the exported textures in texels (leaf-cluster, crown, impostor and bark; the
    /// leaf card's is half as wide): a power of two from 256 to 4096. Stand exports keep 256
    /// by default (a few species' pictures shared by hundreds of trees); `sylva tree grow`
    /// defaults to 2048 for a close-up. Each picture is drawn at that size (finer leaf veins
    /// and bark grain from 512), not enlarged. Not with `--instances`.
    #[arg(long, default_value_t = 256, conflicts_with = "instances")]
    pub texture_size: u32,
    /// Write the trees' meshes as 32-bit floats instead of quantised (`KHR_mesh_quantization`:
    /// 16-bit positions, 8-bit normals, 16-bit card texture coordinates and indices, about a
    /// third of the bytes, which Blender 3.4, three.js and the Khronos viewer read): for an
    /// importer that refuses the extension. Not with `--instances` (never quantised).
    #[arg(long, conflicts_with = "instances")]
    pub no_quantize: bool,
    /// Folder of extra or edited species files, over the shipped library and the run's own
    /// `species/` folder.
    #[arg(long)]
    pub species_dir: Option<PathBuf>,
    /// Output `.glb`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `sylva export`.
pub fn run(a: Args) -> anyhow::Result<()> {
    // checked before the run is read (as `tree grow` checks it before growing)
    sylva::output::gltf::check_texture_size("--texture-size", a.texture_size)?;
    if a.out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) != Some("glb".into()) {
        anyhow::bail!("--out {}: the stand is written as binary glTF; give a file name ending in .glb", a.out.display());
    }
    super::check_run_dir(&a.run_dir, "sylva export")?;
    super::check_out_file(&a.out, "--out")?;
    let area = a.area.as_deref().map(sylva::job::export::parse_area).transpose()?;
    // `--instances` without `--lod`: no levels, the finest one a whole forest can hold
    let levels = match (&a.lod, a.instances) {
        (Some(l), _) => sylva::job::export::parse_levels(l)?,
        (None, true) => Vec::new(),
        (None, false) => vec![0],
    };
    if let Some(p) = &a.stats {
        super::check_stats_path(p)?;
        anyhow::ensure!(p != &a.out, "--stats {}: the same file as --out; give the statistics their own file (e.g. stats.json)", p.display());
    }
    // the folders made for the output (from the topmost missing one) are removed again when
    // the export is refused: nothing is left behind
    let made = a.out.ancestors().skip(1).filter(|d| !d.as_os_str().is_empty() && !d.exists()).last().map(|d| d.to_path_buf());
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("--out {}: creating its folder {}", a.out.display(), dir.display()))?;
    }
    let r = export(&a, area, levels);
    if let (Err(_), Some(dir)) = (&r, &made) {
        let _ = std::fs::remove_dir_all(dir);
    }
    r
}

fn export(a: &Args, area: Option<[f64; 4]>, levels: Vec<usize>) -> anyhow::Result<()> {
    let lib = super::simulate::run_library(&a.run_dir, a.species_dir.as_deref())?;
    let r = if a.instances {
        let o = sylva::job::export::InstanceOptions { year: a.year, area, season: a.season, levels, max_triangles: sylva::job::export::INSTANCE_MAX_TRIANGLES };
        sylva::job::export::export_instances(&a.run_dir, &lib, &o, &a.out)?
    } else {
        let area = area.ok_or_else(|| anyhow::anyhow!("--area X0,Y0,X1,Y1 is required for a stand export (or give --instances to export every tree as instances)"))?;
        let mut o = sylva::job::export::ExportOptions::new(area);
        o.year = a.year;
        o.season = a.season;
        o.levels = levels;
        o.texture_px = a.texture_size;
        o.quantize = !a.no_quantize;
        if a.full_detail {
            o.max_strands = sylva::structure::stand::FULL_STRANDS;
        }
        if let Some(m) = a.max_strands {
            anyhow::ensure!(m >= 8, "--max-strands {m}: expected at least 8 strands");
            o.max_strands = m;
        }
        // the estimated file must fit the GLB's limit and half the available memory (the trees'
        // meshes are held until written); SYLVA_EXPORT_MAX_BYTES sets the cap (tests)
        if let Some(cap) = std::env::var("SYLVA_EXPORT_MAX_BYTES").ok().and_then(|v| v.trim().parse::<u64>().ok()) {
            o.max_bytes = cap;
            o.max_bytes_source = "SYLVA_EXPORT_MAX_BYTES".into();
        } else if let Some(avail) = super::simulate::available_memory_bytes().filter(|&m| m / 2 < o.max_bytes) {
            o.max_bytes = avail / 2;
            o.max_bytes_source = format!("half of the machine's {:.1} GB of available memory: the meshes are held until written", avail as f64 / 1e9);
        }
        sylva::job::export::export_stand(&a.run_dir, &lib, &o, &a.out)?
    };
    if let Some(p) = &a.stats {
        super::write_stats(p, &r.stats.to_json())?;
    }
    let saplings = if r.saplings > 0 { format!(", {} saplings", r.saplings) } else { String::new() };
    println!(
        "year {}: {} trees{saplings} ({} tree models), {} obstacles, terrain {} triangles; {} meshes, {} mesh nodes, {} images; adapt {:.2} s → {} ({:.1} MB)",
        r.year, r.trees, r.models, r.obstacles, r.terrain_triangles, r.counts.meshes, r.counts.mesh_nodes, r.counts.images, r.adapt_s, r.out.display(), r.bytes as f64 / 1e6
    );
    if !a.instances {
        let max_strands = a.max_strands.unwrap_or(sylva::structure::stand::FULL_STRANDS);
        if let Some(hint) = sylva::job::export::large_export_hint(r.bytes, !a.no_quantize, max_strands, &r.stats.levels) {
            println!("{hint}");
        }
    }
    // the instanced export's level, chosen or given, and what the others would draw
    if a.instances {
        let names = sylva::job::export::LEVEL_NAMES;
        let written: Vec<String> = r.stats.levels.iter().map(|&l| format!("LOD{l} ({})", names.get(l).unwrap_or(&"?"))).collect();
        let each: Vec<String> = r.stats.level_triangles.iter().enumerate().map(|(l, t)| format!("LOD{l} {:.1} M", *t as f64 / 1e6)).collect();
        let why = if a.lod.is_none() { format!(": the finest level within {} M triangles", sylva::job::export::INSTANCE_MAX_TRIANGLES / 1_000_000) } else { String::new() };
        println!("levels written: {}{why}; triangles over all trees and saplings per level: {}; --lod all gives each model's chain for an engine's LOD groups", written.join(", "), each.join(", "));
    }
    Ok(())
}
