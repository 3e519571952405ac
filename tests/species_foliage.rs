//! Leaf area of drawn crowns (issue 32, round 37): every species file either gives a sourced
//! `life.foliage.crown_lai` (a published leaf-area index of closed pure stands, cited in the
//! file) or is one of the known exceptions listed here, whose drawn crowns keep the light
//! phase's unsourced `2 + 0.5 · shade tolerance`; a full-level stand tree and a species
//! prototype (the trees beyond the near field) carry that leaf area over their crown.

use glam::Vec3;
use sylva::job::leaf_area::{card_covers, drawn_crown_lai, drawn_leaf_area};
use sylva::mesh::TriMesh;
use sylva::species::SpeciesLibrary;

/// Species with a sourced `crown_lai`: (id, value in the file, the published value it rounds,
/// a word of the citation that the comment above the field must hold). Sources in
/// species/sources/SOURCES.md, "Leaf area of drawn crowns".
const SOURCED: [(&str, f32, f32, &str); 8] = [
    // Kram 1998, Polish J. Ecol. 46(1): spruce 10.0 (LAI-2000)
    ("norway_spruce", 10.0, 10.0, "Kram 1998"),
    // Černý, Haninec & Pokorný 2020, J. For. Res. 31(3): 4.5–5.1 / (1 − 0.151), mean 5.65
    ("beech", 5.7, 5.65, "Cerny, Haninec & Pokorny 2020"),
    // the same paper: 4.0 / (1 − 0.058) = 4.25
    ("sycamore", 4.2, 4.25, "Cerny, Haninec & Pokorny 2020"),
    // Eschenbach & Kappen 1996, J. Exp. Bot. 47(302): 4.8 (direct and litter)
    ("black_alder", 4.8, 4.8, "Eschenbach"),
    // Johansson 1999, Biomass and Bioenergy 17(6): 11 Swedish aspen stands, mean 2.58
    ("aspen", 2.6, 2.58, "Johansson 1999"),
    // Beadle, Talbot & Jarvis 1982, Forestry 55(2): Thetford Forest, maximum projected LAI 2.73
    ("scots_pine", 2.7, 2.73, "Beadle, Talbot & Jarvis 1982"),
    // Breda & Granier 1996, Ann. Sci. For. 53(2-3): a sessile oak stand's maximum LAI 3.3–6
    // over five years (half thinned in 1992); the closed canopy's 6
    ("sessile_oak", 6.0, 6.0, "Breda & Granier 1996"),
    // Eur. J. For. Res. 126 (2007), doi:10.1007/s10342-007-0171-9: an 8-year-old silver birch
    // stand, LAI 3.7
    ("silver_birch", 3.7, 3.7, "s10342-007-0171-9"),
];

/// Species without a source read for `crown_lai` (rounds 36–38): their drawn crowns keep the
/// light phase's crown LAI. A source found moves a species from here to [`SOURCED`].
const KNOWN_EXCEPTIONS: [&str; 9] = ["ash", "european_larch", "hornbeam", "norway_maple", "pedunculate_oak", "rowan", "silver_fir", "small_leaved_lime", "wych_elm"];

fn library() -> SpeciesLibrary {
    SpeciesLibrary::embedded().unwrap()
}

/// The crown LAI a species' drawn crowns must carry, read from its file: `life.foliage.crown_lai`,
/// else the light phase's `2 + 0.5 · shade tolerance`.
fn field_lai(sp: &sylva::species::Species) -> f32 {
    sp.life.foliage.map_or_else(|| sylva::sim::phases::light::crown_lai(sp.life.shade_tolerance), |f| f.crown_lai)
}

/// The comment line right above `foliage = ` (or, for an exception, the line that says none is
/// given) in a species file's text.
fn foliage_comment(text: &str) -> Option<&str> {
    let lines: Vec<&str> = text.lines().collect();
    if let Some(i) = lines.iter().position(|l| l.starts_with("foliage = ")) {
        return lines.get(i.checked_sub(1)?).copied().filter(|l| l.starts_with('#'));
    }
    lines.iter().copied().find(|l| l.starts_with("# Leaf area of drawn crowns"))
}

#[test]
fn every_species_file_has_a_sourced_crown_lai_or_is_a_known_exception() {
    let lib = library();
    let mut ids: Vec<&str> = lib.species.iter().map(|s| s.id.as_str()).collect();
    ids.sort_unstable();
    let mut listed: Vec<&str> = SOURCED.iter().map(|s| s.0).chain(KNOWN_EXCEPTIONS).collect();
    listed.sort_unstable();
    assert_eq!(ids, listed, "every species is either sourced or a known exception, once");
    for (id, value, published, cite) in SOURCED {
        let sp = lib.get(id).unwrap();
        let f = sp.life.foliage.unwrap_or_else(|| panic!("{id}: no life.foliage.crown_lai"));
        assert_eq!(f.crown_lai, value, "{id}");
        assert!((value - published).abs() <= 0.05 * published, "{id}: {value} against the published {published}");
        // the drawn crowns take it, not the light phase's value
        assert_eq!(drawn_crown_lai(sp), value, "{id}: drawn crown LAI");
        let text = sylva::species::embedded_text(id).unwrap();
        let comment = foliage_comment(text).unwrap_or_else(|| panic!("{id}: no comment above foliage"));
        let plain = comment.replace(['č', 'ý'], "c").replace('Č', "C");
        assert!(plain.contains(cite) || comment.contains(cite), "{id}: the comment cites {cite:?}: {comment}");
        assert!(comment.contains("SOURCES.md"), "{id}: {comment}");
    }
    for id in KNOWN_EXCEPTIONS {
        let sp = lib.get(id).unwrap();
        assert!(sp.life.foliage.is_none(), "{id} has a crown_lai now: move it from KNOWN_EXCEPTIONS to SOURCED with its source");
        let light = sylva::sim::phases::light::crown_lai(sp.life.shade_tolerance);
        assert_eq!(drawn_crown_lai(sp), light, "{id}: without a source the drawn crown keeps the light phase's LAI");
        let text = sylva::species::embedded_text(id).unwrap();
        let comment = foliage_comment(text).unwrap_or_else(|| panic!("{id}: the file does not say that it has no source"));
        assert!(comment.contains("none given") && comment.contains("no source"), "{id}: {comment}");
    }
}

/// One-sided leaf area (m²) of a full level's leaves: its leaf cards (each triangle's area
/// times `card` cover) and its leaf-cluster cards (marked by `CLUSTER_CARD_U`, `cluster` cover).
fn mesh_leaf_area(leaves: &TriMesh, card: f32, cluster: f32) -> f32 {
    let (plain, clusters) = leaves.split_cluster_cards();
    let tri_area = |m: &TriMesh| -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(m.positions[i as usize]));
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    };
    tri_area(&plain) * card + tri_area(&clusters) * cluster
}

/// Leaf area (m², one-sided) of leaf cards `size × size/2` of which `card` shows leaf, and of
/// sprig quads (`cluster` shows leaf; `sprig_cards` returns them unmarked).
fn cards_and_sprigs(lv: &sylva::structure::Leaves, sprigs: &TriMesh, card: f32, cluster: f32) -> f32 {
    lv.leaves.iter().map(|l| 0.5 * l.size * l.size * card).sum::<f32>() + mesh_leaf_area(sprigs, cluster, cluster)
}

/// A canopy tree of each species (DBH 30 cm; height from the species' height–diameter curve,
/// crown radius from its stand-grown crown width where it has one, crown base at 40 % of the
/// height), drawn at the full level as the stills' and viewer's near field draw it
/// (`job::adapted::crown_leaf_cards`, the stand export's broadleaves likewise): its cards and
/// sprigs carry the species' drawn crown LAI (the file's `crown_lai`, else the light phase's)
/// over π r², within half a sprig.
#[test]
fn a_full_level_stand_tree_carries_its_species_crown_lai_over_its_crown() {
    use sylva::structure::species_tree::{grow_species_tree, tip_leaves, Model};
    let lib = library();
    let cover = sylva::job::adapted::LeafCover::of(&lib);
    for (k, sp) in lib.species.iter().enumerate() {
        let dbh = 30.0;
        let h = sylva::species::allometry::height_from_dbh(sp, dbh);
        let cb = 0.4 * h;
        let r = sylva::species::allometry::stand_crown_radius(sp, dbh, h, cb).unwrap_or(0.25 * h).clamp(1.0, 6.0);
        let g = grow_species_tree(sp, Model::EcoMod, 25.0, &[], 5).unwrap();
        let mut lv = tip_leaves(&g.skeleton, &sp.architecture.ecomod);
        let root = g.skeleton.nodes[0].pos;
        lv.leaves.iter_mut().for_each(|l| l.pos -= root);
        let t = sylva::structure::stand::StandTree { id: 1, species: k as u16, base: Vec3::ZERO, age_yr: 60.0, height_m: h, crown_radius_m: r, crown_base_m: cb, slope_deg: 0.0, aspect_deg: 0.0 };
        let sprigs = sylva::job::adapted::crown_leaf_cards(&mut lv, &t, sp, &cover);
        let got = cards_and_sprigs(&lv, &sprigs, cover.card[k], cover.sprig[k]);
        let want = field_lai(sp) * std::f32::consts::PI * r * r;
        assert!((want - drawn_leaf_area(sp, r)).abs() < 1e-3 * want);
        let side = sprigs.positions.get(1).map_or(0.0, |p| (Vec3::from(*p) - Vec3::from(sprigs.positions[0])).length());
        let slack = 0.5 * side * side * cover.sprig[k] + 0.01 * want;
        eprintln!("{}: r {r:.2} m, LAI {:.2}: {got:.1} of {want:.1} m² ({} sprigs)", sp.id, drawn_crown_lai(sp), sprigs.positions.len() / 4);
        assert!((got - want).abs() <= slack, "{}: the full level carries {got:.1} m², its crown {want:.1} m² (LAI {})", sp.id, drawn_crown_lai(sp));
    }
}

/// Crown projection (m²) of a level's vertices about the z axis: the octagon of the largest
/// horizontal distance in each 45° sector (as `structure::crown_projection_area` measures a
/// tree by its eight crown radii).
fn octagon_projection(levels: &[&TriMesh]) -> f32 {
    let mut r = [0.0f32; 8];
    let sector = std::f32::consts::TAU / 8.0;
    for m in levels {
        for p in &m.positions {
            let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
            if rho > 0.0 {
                let k = ((p[1].atan2(p[0]) / sector).round() as i32).rem_euclid(8) as usize;
                r[k] = r[k].max(rho);
            }
        }
    }
    0.5 * (sector).sin() * (0..8).map(|k| r[k] * r[(k + 1) % 8]).sum::<f32>()
}

/// Round 37: the species prototypes (the trees the stills and the viewer draw beyond the near
/// field, `job::scene::prototypes`) carry their crown's drawn leaf area at the full level: the
/// leaf area of level 0 (leaf cards and leaf-cluster cards, each weighted by the share its
/// texture covers) over the crown projection of level 0's own vertices is the species' drawn
/// crown LAI within 15 % (the vertex octagon reaches a sprig's corner beyond the eight crown
/// radii of leaf tips that `lone_chain` measures, and thinned needle cards round to whole cards).
/// Before, a prototype's level 0 carried EcoMod's own leaf cards only.
#[test]
fn a_species_prototype_carries_its_crown_lai_over_its_projection() {
    let lib = library();
    let protos = sylva::job::scene::prototypes(&lib);
    assert_eq!(protos.len(), lib.species.len());
    for (sp, p) in lib.species.iter().zip(&protos) {
        let full = &p.lods.levels[0];
        let (card, cluster) = card_covers(sp);
        let area = mesh_leaf_area(&full.leaves, card, cluster);
        let proj = octagon_projection(&[&full.leaves, &full.bark]);
        let lai = field_lai(sp);
        let got = area / proj;
        // the old prototype (EcoMod's own cards) for comparison
        let old = sylva::structure::species_lod_chain(sp, 42);
        let old_lai = mesh_leaf_area(&old.levels[0].leaves, card, cluster) / octagon_projection(&[&old.levels[0].leaves, &old.levels[0].bark]);
        eprintln!("{}: prototype leaf area / projection {got:.2} (old {old_lai:.2}), drawn crown LAI {lai:.2}; normalised crown radius {:.3} (old {:.3}); level-0 triangles {} (old {})", sp.id, p.normalised_crown_radius(), old.leaf_radius0(), p.lods.level_triangles(0), old.level_triangles(0));
        // the crown is drawn as wide as before (the renderer scales by this radius)
        assert!((p.normalised_crown_radius() - old.leaf_radius0()).abs() <= 0.02 * old.leaf_radius0(), "{}: normalised crown radius {} (before {})", sp.id, p.normalised_crown_radius(), old.leaf_radius0());
        assert!((got - lai).abs() <= 0.15 * lai, "{}: the prototype's full level carries {got:.2} m² of leaf per m² of its crown projection, the species' drawn crown LAI is {lai:.2}", sp.id);
    }
    // deterministic
    assert_eq!(sylva::job::scene::prototypes(&lib), protos);
}

/// Issue 32, round 38: the full-detail beech and birch draw leaves as long as their species'
/// (the trial of round 37 saw an 80-year open-grown beech with oversized leaf cards: EcoMod's
/// beech leaf of 0.2862 m, lengthened ×1.5 to carry the crown's leaf area, drew 43 cm leaves; a
/// stand tree's cards were that size times the tree's height over the EcoMod model's). The files'
/// `appearance.leaf_length_m` (beech 6.5 cm: Marshall Ward 1909's 4–9 cm; birch 5 cm: 3–7 cm) set
/// the cards' length before they carry the leaf area, by at most ×1.5 ([`MAX_CARD_GROWTH`]), and
/// the leaf-cluster cards' leaves are as long (their side is the mean card length over 0.26, the
/// broad-leaf cluster texture's leaf length). Asserted for `sylva tree grow`'s open-grown tree of
/// 80 years (`grow_formed_tree`, `lone_tree_sprigs`): every leaf card between the species' leaf
/// length and 1.5 times it, and within the flora's range × 1.5. (The stand exports' and stills'
/// full-detail trees keep EcoMod's leaf size: set to the leaf length there, a beech stand's small
/// sprigs clumped at the tips and Blender's cover from above fell from 0.707 to 0.598, round 38.)
#[test]
fn beech_and_birch_draw_leaf_cards_of_their_species_leaf_length() {
    use sylva::job::leaf_area::{lone_tree_sprigs, MAX_CARD_GROWTH};
    use sylva::structure::forest_form::{grow_formed_tree, Habit};
    use sylva::structure::species_tree::Model;
    let lib = library();
    // (species, flora's leaf length range m)
    for (id, lo, hi) in [("beech", 0.04f32, 0.09f32), ("silver_birch", 0.03, 0.07)] {
        let sp = &lib.species[lib.find(id).unwrap() as usize];
        let len = sp.drawn_leaf_length_m();
        assert!((lo..=hi).contains(&len), "{id}: drawn leaf length {len} m outside the flora's {lo}–{hi} m");
        let ok = |s: f32| s >= len * 0.999 && s <= len * MAX_CARD_GROWTH * 1.001 && s <= hi * MAX_CARD_GROWTH;
        // `sylva tree grow --open-grown --age 80`
        let (mut tree, _) = grow_formed_tree(sp, Model::EcoMod, 80.0, &[], 1, Habit::Open).unwrap();
        let (_, fill) = lone_tree_sprigs(&tree.skeleton, &mut tree.leaves, sp);
        let bad: Vec<f32> = tree.leaves.leaves.iter().map(|l| l.size).filter(|&s| !ok(s)).collect();
        assert!(bad.is_empty(), "{id}: tree grow's cards {:?}… outside {len}–{} m ({fill:?})", &bad[..bad.len().min(5)], len * MAX_CARD_GROWTH);
    }
}
