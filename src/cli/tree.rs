//! `sylva tree grow`: grows one tree with one of the three architecture models, exports its LOD
//! chain as `.glb` or `.obj` (by extension), writes a PNG preview (side views of the four LOD
//! levels, CPU rasterised) next to it and prints node/triangle counts per LOD. With
//! `--adapt-to`, the grown tree is then adapted to new obstacles by Plastic Trees (Pirk et al.
//! 2012, `000_*.txt`; [`sylva::structure::plastic::adapt`]) instead of being regrown.
use anyhow::Context;
use clap::{Subcommand, ValueEnum};
use glam::Vec3;
use std::path::{Path, PathBuf};
use sylva::mesh::{LodChain, TreeMesh};
use sylva::structure::grow::space::Obstacle;
use sylva::structure::species_tree;
use sylva::structure::mesh::{lod_chain, LodOptions};
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
        #[arg(long, default_value_t = 80.0)]
        age: f32,
        /// Obstacles (light and laplacian models): box:x0,y0,z0,x1,y1,z1 | sphere:x,y,z,r | wall:x
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
        /// Folder of extra or edited species files, over the shipped library.
        #[arg(long)]
        species_dir: Option<PathBuf>,
        /// Output file, .glb or .obj; the preview goes to the same name with .png.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Runs a tree subcommand.
pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Grow { species, model, age, obstacle, adapt_to, seed, species_dir, out } => grow(&species, model, age, &obstacle, &adapt_to, seed, species_dir.as_deref(), &out),
    }
}

#[allow(clippy::too_many_arguments)]
fn grow(species: &str, model: Model, age: f32, obstacles: &[String], adapt_to: &[String], seed: u64, species_dir: Option<&Path>, out: &Path) -> anyhow::Result<()> {
    anyhow::ensure!(age.is_finite() && age > 0.0, "--age {age}: expected a positive number of years");
    let lib = super::simulate::library(species_dir.as_slice())?;
    let sp = lib.find(species).map(|i| lib.species[i as usize].clone());
    let sp = sp.with_context(|| format!("--species {species}: not in the library (ids: {})", lib.species.iter().map(|s| s.id.as_str()).collect::<Vec<_>>().join(", ")))?;
    anyhow::ensure!(age <= sp.life.max_age_yr, "--age {age}: expected at most the maximum age of {} ({} years, `life.max_age_yr` in its species file)", sp.id, sp.life.max_age_yr);
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
            if !obs.is_empty() {
                tracing::warn!("EcoMod ignores obstacles");
            }
            species_tree::Model::EcoMod
        }
        Model::Light => species_tree::Model::Light,
        Model::Laplacian => species_tree::Model::Laplacian,
    };
    let grown = species_tree::grow_species_tree(&sp, m, age, &obs, seed)?;
    let (mut sk, mut leaves): (Skeleton, Leaves) = (grown.skeleton, grown.leaves);
    let grow_s = t0.elapsed().as_secs_f64();
    let mut adapted = None;
    if !later.is_empty() {
        let all: Vec<Obstacle> = obs.iter().chain(&later).copied().collect();
        let ta = std::time::Instant::now();
        let (new_sk, rep) = sylva::structure::plastic::adapt(&sk, &sp.architecture.plastic, &all, mean_internode(&sk))?;
        let adapt_s = ta.elapsed().as_secs_f64();
        // the model's own leaves hang on node ids that pruning renumbers: re-leaf the tips
        leaves = species_tree::tip_leaves(&new_sk, &sp.architecture.ecomod);
        sk = new_sk;
        let tr = std::time::Instant::now();
        species_tree::grow_species_tree(&sp, m, age, &all, seed)?;
        adapted = Some((rep, adapt_s, tr.elapsed().as_secs_f64()));
    }
    let t1 = std::time::Instant::now();
    let chain = lod_chain(&sk, &leaves, &LodOptions::default());
    let mesh_s = t1.elapsed().as_secs_f64();
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let bark = sp.appearance.bark;
    let leaf = sp.appearance.leaf_summer;
    match ext.as_str() {
        "glb" => {
            let width = sk.bounds().map(|(lo, hi)| (hi - lo).x.max((hi - lo).y)).unwrap_or(1.0);
            sylva::output::gltf::write_glb(out, &chain, &sylva::output::gltf::GlbOptions { bark_rgb: bark, leaf_rgb: leaf, spacing_m: width * 1.2 })?
        }
        "obj" => sylva::output::obj::write_obj(out, &chain, None)?,
        _ => anyhow::bail!("--out {}: expected a .glb or .obj file name", out.display()),
    }
    let img = preview(&chain, bark, leaf, 360, 540);
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    sylva::output::write_atomic(&png, &bytes)?;
    println!("species {} ({}), model {:?}, seed {seed}, age {age} yr", sp.id, sp.identity.scientific_name, model);
    println!("nodes {}, leaves {}, height {:.2} m, crown radius {:.2} m", sk.len(), leaves.len(), sk.height(), sylva::structure::crown_radius(&sk, &leaves));
    for (i, l) in chain.levels.iter().enumerate() {
        println!("LOD{i}: {:>8} triangles (bark {}, foliage {})", l.triangle_count(), l.bark.triangle_count(), l.leaves.triangle_count());
    }
    println!("grow {:.1} ms, mesh {:.1} ms", grow_s * 1e3, mesh_s * 1e3);
    if let Some((rep, adapt_s, regrow_s)) = adapted {
        let (b, pl, pc) = (rep.bent, rep.pruned_light, rep.pruned_collision);
        println!("adapted (Plastic Trees): bent {b}, pruned {pl} for light + {pc} in obstacles; adapt {:.1} ms, regrowing among the obstacles {:.1} ms", adapt_s * 1e3, regrow_s * 1e3);
    }
    println!("wrote {} and {}", out.display(), png.display());
    Ok(())
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

/// Side views (looking along +y, orthographic, z up) of every LOD level side by side, flat
/// shaded with a z-buffer.
fn preview(chain: &LodChain, bark: [u8; 3], leaf: [u8; 3], w: u32, h: u32) -> image::RgbImage {
    let n = chain.levels.len().max(1) as u32;
    let mut img = image::RgbImage::from_pixel(w * n, h, image::Rgb([205, 225, 240]));
    for (li, level) in chain.levels.iter().enumerate() {
        draw_level(&mut img, level, li as u32 * w, w, h, bark, leaf);
    }
    img
}

fn draw_level(img: &mut image::RgbImage, m: &TreeMesh, x0: u32, w: u32, h: u32, bark: [u8; 3], leaf: [u8; 3]) {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    for p in m.bark.positions.iter().chain(&m.leaves.positions) {
        lo = lo.min(Vec3::from(*p));
        hi = hi.max(Vec3::from(*p));
    }
    if lo.x > hi.x {
        return;
    }
    let margin = 10.0;
    let s = ((w as f32 - 2.0 * margin) / (hi.x - lo.x).max(1e-3)).min((h as f32 - 2.0 * margin) / (hi.z - lo.z).max(1e-3));
    let cx = 0.5 * (lo.x + hi.x);
    let to_px = |p: [f32; 3]| -> (f32, f32, f32) { (x0 as f32 + w as f32 * 0.5 + (p[0] - cx) * s, h as f32 - margin - (p[2] - lo.z) * s, p[1]) };
    let mut zbuf = vec![f32::MAX; (w * h) as usize];
    let light = Vec3::new(-0.4, -0.6, 0.7).normalize();
    for (mesh, col) in [(&m.bark, bark), (&m.leaves, leaf)] {
        for t in mesh.indices.chunks_exact(3) {
            let (a, b, c) = (to_px(mesh.positions[t[0] as usize]), to_px(mesh.positions[t[1] as usize]), to_px(mesh.positions[t[2] as usize]));
            let nrm = Vec3::from(mesh.normals[t[0] as usize]) + Vec3::from(mesh.normals[t[1] as usize]) + Vec3::from(mesh.normals[t[2] as usize]);
            let shade = 0.35 + 0.65 * nrm.normalize_or(Vec3::Z).dot(light).abs();
            let px = image::Rgb([(col[0] as f32 * shade) as u8, (col[1] as f32 * shade) as u8, (col[2] as f32 * shade) as u8]);
            let minx = a.0.min(b.0).min(c.0).floor().max(x0 as f32) as i64;
            let maxx = a.0.max(b.0).max(c.0).ceil().min((x0 + w - 1) as f32) as i64;
            let miny = a.1.min(b.1).min(c.1).floor().max(0.0) as i64;
            let maxy = a.1.max(b.1).max(c.1).ceil().min((h - 1) as f32) as i64;
            let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            if area.abs() < 1e-9 {
                // degenerate on screen: plot the vertex so thin twigs stay visible
                if minx <= maxx && miny <= maxy {
                    img.put_pixel(minx as u32, miny as u32, px);
                }
                continue;
            }
            for y in miny..=maxy {
                for x in minx..=maxx {
                    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                    let w0 = ((b.0 - fx) * (c.1 - fy) - (c.0 - fx) * (b.1 - fy)) / area;
                    let w1 = ((c.0 - fx) * (a.1 - fy) - (a.0 - fx) * (c.1 - fy)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * a.2 + w1 * b.2 + w2 * c.2;
                    let zi = (y as u32 * w + (x as u32 - x0)) as usize;
                    if z < zbuf[zi] {
                        zbuf[zi] = z;
                        img.put_pixel(x as u32, y as u32, px);
                    }
                }
            }
        }
    }
}

