//! From simulation results to a render [`Scene`]: the terrain mesh of the site, one prototype per
//! species (its EcoMod skeleton meshed into a level-of-detail chain), and one instance per live
//! tree of an inventory snapshot.
//!
//! This is where an adapted skeleton (Plastic Trees, Pirk et al. 2012, `000_*.txt`) will replace
//! the open-grown one: [`prototypes`] builds one open-grown tree per species; a later step can
//! build per-tree chains and point instances at them.

use crate::conditions::SiteConditions;
use crate::grid::Grid;
use crate::job::inventory::InventoryRow;
use crate::render::scene::{deciduous_season, Prototype, Scene, Sky, Sun, TerrainMesh, TreeInstance, Wind};
use crate::render::terrain::{from_grid, LandCover};
use crate::species::{Season, Species, SpeciesLibrary};
use crate::Result;

/// sRGB (0–255) to linear RGB (0–1), IEC 61966-2-1.
pub fn srgb_to_linear(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| {
        let s = v as f32 / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    })
}

/// Day of year (1–365) used to draw each season: mid-May, mid-July, mid-October, mid-January.
pub fn season_day(season: Season) -> f32 {
    match season {
        Season::Spring => 135.0,
        Season::Summer => 196.0,
        Season::Autumn => 290.0,
        Season::Winter => 15.0,
    }
}

/// Foliage colour (linear RGB) and leaf amount (0–1) of `species` in `season`.
pub fn foliage(species: &Species, season: Season) -> ([f32; 3], f32) {
    let a = &species.appearance;
    if !species.identity.deciduous {
        let c = if season == Season::Winter { a.leaf_winter } else { a.leaf_summer };
        return (srgb_to_linear(c), 1.0);
    }
    match season {
        Season::Spring => (srgb_to_linear(a.leaf_spring), 1.0),
        Season::Summer => (srgb_to_linear(a.leaf_summer), 1.0),
        Season::Autumn => (srgb_to_linear(a.leaf_autumn), 1.0),
        Season::Winter => {
            let (c, amount) = deciduous_season(season_day(Season::Winter), srgb_to_linear(a.leaf_summer));
            (c, amount)
        }
    }
}

/// One prototype per species of `library`, in library order (so `SpeciesId` indexes them):
/// the species' EcoMod tree (004_*.txt, Algorithm 1) normalised to 1 m height, meshed into its
/// LOD chain by [`crate::structure::species_lod_chain`]. A species whose model cannot be built
/// falls back to the renderer's stand-in chain (logged).
pub fn prototypes(library: &SpeciesLibrary) -> Vec<Prototype> {
    use rayon::prelude::*;
    library
        .species
        .par_iter()
        .map(|s| {
            let mut lods = crate::structure::species_lod_chain(s, 42);
            if lods.levels.is_empty() {
                lods = crate::render::lod::placeholder_chain(s.identity.leaf_type == crate::species::LeafType::Conifer);
            }
            Prototype {
                name: s.id.clone(),
                lods,
                bark_color: srgb_to_linear(s.appearance.bark),
                leaf_color: srgb_to_linear(s.appearance.leaf_summer),
                stiffness: s.architecture.ecomod.k_f.clamp(0.0, 1.0),
            }
        })
        .collect()
}

/// Bilinearly upsamples the site's elevation so that render cells are at most `max_cell_m`
/// metres; masked (NaN) cells take the minimum valid elevation. Returns the grid and its cell
/// sizes (m).
pub fn render_heights(cond: &SiteConditions, max_cell_m: f64) -> (Grid<f32>, f32, f32) {
    let f = ((cond.cell_x_m.max(cond.cell_y_m) / max_cell_m).ceil() as usize).clamp(1, 16);
    let (w, h) = (cond.width() * f, cond.height() * f);
    let (cx, cy) = (cond.cell_x_m / f as f64, cond.cell_y_m / f as f64);
    let ymax = cond.height() as f64 * cond.cell_y_m;
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        let y = ymax - (r as f64 + 0.5) * cy;
        for c in 0..w {
            let x = (c as f64 + 0.5) * cx;
            data.push(cond.elevation_at(x, y));
        }
    }
    let min = data.iter().copied().filter(|v| v.is_finite()).fold(f32::INFINITY, f32::min);
    for v in &mut data {
        if !v.is_finite() {
            *v = if min.is_finite() { min } else { 0.0 };
        }
    }
    (Grid { width: w, height: h, data }, cx as f32, cy as f32)
}

/// The terrain mesh of the site (cells ≤ `max_cell_m` m), land-cover coloured, with an optional
/// overlay field (values 0–1) on the site grid.
pub fn terrain_mesh(cond: &SiteConditions, max_cell_m: f64, sea_level: f32) -> Result<TerrainMesh> {
    let (g, cx, cy) = render_heights(cond, max_cell_m);
    let cover = LandCover { sea_level, ..LandCover::default() };
    from_grid(&g, cx, cy, &cover, None)
}

/// Render instances of the live trees of `rows` for `season`; trees of species not in
/// `library` are skipped. Positions are in the site's world coordinates with z from the terrain.
pub fn instances(rows: &[InventoryRow], library: &SpeciesLibrary, cond: &SiteConditions, season: Season) -> Vec<TreeInstance> {
    rows.iter()
        .filter(|r| r.status == "alive" && r.height_m > 0.0)
        .filter_map(|r| {
            let sid = library.find(&r.species)?;
            let sp = &library.species[sid as usize];
            let (col, amount) = foliage(sp, season);
            let z = cond.elevation_at(r.x_m, r.y_m);
            let mut inst = TreeInstance::new(r.id, [r.x_m as f32, r.y_m as f32, z], r.height_m, r.crown_radius_m.max(0.2), sid as u32, col);
            inst.leaf_amount = amount;
            Some(inst)
        })
        .collect()
}

/// A full scene for one snapshot: terrain, prototypes, instances, the sun of the site's
/// latitude on the season's day at 14:00 solar time, and a light westerly breeze.
pub fn scene(terrain: TerrainMesh, prototypes: Vec<Prototype>, instances: Vec<TreeInstance>, latitude_deg: f64, season: Season, sea_level: Option<f32>) -> Scene {
    Scene {
        terrain,
        sea_level,
        prototypes,
        instances,
        sun: Sun::from_position(latitude_deg as f32, season_day(season), 14.0),
        sky: Sky::default(),
        wind: Wind { direction: [1.0, 0.0], directed: 1.5, undirected: 1.0, time_s: 0.0 },
    }
}
