//! One prototype per species (its EcoMod skeleton meshed into a level-of-detail chain) and the
//! site's terrain mesh.

use super::*;

/// The crown look of `species` from afar (`appearance.crown_top_flatness`, `crown_cover`,
/// `crown_clump`), which the renderer's coarse levels draw, and its leaf outline
/// (`appearance.leaf_texture`) for the leaf cards.
pub fn crown_look(species: &Species) -> crate::render::lod::CrownLook {
    let a = &species.appearance;
    crate::render::lod::CrownLook { top_flatness: a.crown_top_flatness, cover: a.crown_cover, clump: a.crown_clump, leaf_shape: Some(crate::structure::texture::LeafShape::of_species(species)) }
}

/// One prototype per species of `library`, in library order (so `SpeciesId` indexes them):
/// the species' EcoMod tree (004_*.txt, Algorithm 1) normalised to 1 m height, meshed into its
/// LOD chain with its full level carrying the crown's drawn leaf area
/// ([`crate::job::leaf_area::prototype_chain`]: the species' crown leaf-area index over the
/// model's crown projection, round 37). A species whose model cannot be built falls back to
/// the renderer's stand-in chain (logged).
pub fn prototypes(library: &SpeciesLibrary) -> Vec<Prototype> {
    use rayon::prelude::*;
    library
        .species
        .par_iter()
        .map(|s| {
            let lods = match crate::job::leaf_area::prototype_chain(s, 42) {
                Some((lods, _)) if !lods.levels.is_empty() => lods,
                _ => crate::render::lod::placeholder_chain(s.identity.leaf_type == crate::species::LeafType::Conifer),
            };
            Prototype {
                name: s.id.clone(),
                lods,
                bark_color: srgb_to_linear(s.appearance.bark),
                leaf_color: srgb_to_linear(s.appearance.leaf_summer),
                stiffness: s.architecture.ecomod.k_f.clamp(0.0, 1.0),
                look: Some(crown_look(s)),
                rigid: false,
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
