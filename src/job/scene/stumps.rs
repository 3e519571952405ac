//! Stumps of harvested trees (issue 35): every tree a thinning or harvest removed (inventory
//! status `dead:harvest`) is drawn for [`STUMP_YEARS`] years after its cut as a short cylinder
//! of bark with a lighter cut face on top, greying and sinking as it weathers.
//!
//! A stump is two instances of the renderer's instanced machinery (as the scenario's obstacles
//! are): a bark prototype (the cylinder's side and a bark ring on top) and a cut-face prototype
//! (the disc inside the ring), one pair per weathering class ([`STUMP_CLASSES`]), appended
//! after the species' (and the obstacles') prototypes.

use super::*;
use crate::mesh::{LodChain, TreeMesh, TriMesh, LOD_LEVELS};
use crate::sim::trees::DeathCause;

/// Years a stump is drawn after its cut: a picture of year Y draws the trees harvested in
/// years Y − 19 ..= Y. A choice of this model (issue 35), not a measured decay time: a stump
/// of a broadleaf or spruce is rotten and overgrown within a few decades.
pub const STUMP_YEARS: u32 = 20;
/// Height of a fresh stump above the ground (m): a chainsaw cut about 0.3 m up, as forestry
/// guidelines ask (low stumps keep the wood in the log).
pub const STUMP_HEIGHT_M: f32 = 0.3;
/// Smallest stump radius drawn (m).
pub const STUMP_MIN_RADIUS_M: f32 = 0.05;
/// Stump radius over half the DBH: the stem flares towards its base (1.1).
pub const STUMP_FLARE: f32 = 1.1;
/// Weathering classes of [`STUMP_YEARS`] / this many years each; a class has its own colours.
pub const STUMP_CLASSES: usize = 4;
/// Number of stump prototypes ([`stump_prototypes`]): a bark and a cut-face prototype per class.
pub const STUMP_PROTOTYPES: usize = 2 * STUMP_CLASSES;
/// Height of the normalised stump models' top (their base at 0): an instance is
/// `1 / STUMP_MODEL_TOP` times as tall as the stump it draws. The renderer picks a model's level
/// (mesh, billboard, canopy layer) by the instance's height on screen, which suits trees; a
/// stump is wider than tall and would go to the canopy layer (under 6 px) already 13 m from a
/// 50° camera, so its instance stands for an object ten times as tall and the model fills its
/// lowest tenth (a billboard is carved from the model's outline, so it keeps the stump's shape).
pub const STUMP_MODEL_TOP: f32 = 0.1;
/// Radius of the normalised stump models (m per m of height): the renderer's horizontal scale
/// of a prototype without foliage is the instance's crown radius over 0.3
/// ([`Prototype::normalised_crown_radius`]), so with this radius an instance's crown radius is
/// the stump's radius.
const UNIT_RADIUS: f32 = 0.3;
/// The cut face's radius within the bark ring (share of the stump's radius).
const FACE_SHARE: f32 = 0.85;
/// Sides of the stump cylinder.
const SIDES: usize = 12;
/// Fresh bark (sRGB): a grey-brown between beech and oak bark.
const BARK_RGB: [u8; 3] = [96, 78, 62];
/// A fresh cut face (sRGB): pale wood.
const FACE_RGB: [u8; 3] = [214, 184, 140];
/// What both weather to (sRGB): silver-grey dead wood.
const WEATHERED_RGB: [u8; 3] = [128, 124, 116];

/// One harvested tree whose stump the pictures draw.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stump {
    /// Tree id.
    pub id: u64,
    /// Easting (m, world coordinates from the site's south-west corner).
    pub x_m: f64,
    /// Northing (m).
    pub y_m: f64,
    /// DBH at the cut (cm, > 0).
    pub dbh_cm: f32,
    /// Year of the cut (the snapshot's year).
    pub year: u32,
}

impl Stump {
    /// Radius of the fresh stump (m): [`STUMP_FLARE`] × DBH / 2, at least
    /// [`STUMP_MIN_RADIUS_M`].
    pub fn radius_m(&self) -> f32 {
        (STUMP_FLARE * self.dbh_cm / 200.0).max(STUMP_MIN_RADIUS_M)
    }
}

/// The stumps of inventory `rows` of the snapshot of `year`: the rows with status
/// `dead:harvest` and a DBH (trees shorter than 1.3 m leave no stump worth drawing).
pub fn stumps_from_rows(rows: &[InventoryRow], year: u32) -> Vec<Stump> {
    let status = format!("dead:{}", DeathCause::Harvest.name());
    rows.iter().filter(|r| r.status == status && r.dbh_cm > 0.0 && r.dbh_cm.is_finite()).map(|r| Stump { id: r.id, x_m: r.x_m, y_m: r.y_m, dbh_cm: r.dbh_cm, year }).collect()
}

/// The stumps of the trees `w` removed by management in its current year (its record of the
/// year's dead, as the inventory writes them), in id order.
pub fn stumps_from_world(w: &World) -> Vec<Stump> {
    let mut out: Vec<Stump> = w.scratch.dead.iter().filter(|d| d.cause == DeathCause::Harvest && d.dbh > 0.0 && d.dbh.is_finite()).map(|d| Stump { id: d.id, x_m: d.x as f64, y_m: d.y as f64, dbh_cm: d.dbh, year: w.stand.year }).collect();
    out.sort_by_key(|s| s.id);
    out
}

/// Whether a stump cut in `cut` is drawn in a picture of `year` ([`STUMP_YEARS`]).
pub fn stump_shown(cut: u32, year: u32) -> bool {
    cut <= year && year - cut < STUMP_YEARS
}

fn lerp_rgb(a: [u8; 3], b: [u8; 3], t: f32) -> [f32; 3] {
    let a = srgb_to_linear(a);
    let b = srgb_to_linear(b);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// Share weathered (0 fresh .. 1 grey) of class `k`.
fn weathering(k: usize) -> f32 {
    k as f32 / (STUMP_CLASSES - 1).max(1) as f32
}

/// Bark and cut-face colours (linear RGB) of weathering class `k`: fresh bark and pale wood,
/// both greying to silver-grey dead wood (the face fully, the bark by half).
pub fn stump_colors(k: usize) -> ([f32; 3], [f32; 3]) {
    let t = weathering(k);
    (lerp_rgb(BARK_RGB, WEATHERED_RGB, 0.5 * t), lerp_rgb(FACE_RGB, WEATHERED_RGB, t))
}

/// The normalised bark of a stump: the side of a cylinder of radius [`UNIT_RADIUS`] from 0 to
/// [`STUMP_MODEL_TOP`], and a ring on top from [`FACE_SHARE`] of the radius out.
fn bark_mesh() -> TriMesh {
    let mut m = TriMesh::default();
    let tau = std::f32::consts::TAU;
    for i in 0..=SIDES {
        let a = tau * i as f32 / SIDES as f32;
        let (s, c) = a.sin_cos();
        for z in [0.0, 1.0] {
            m.positions.push([UNIT_RADIUS * c, UNIT_RADIUS * s, z * STUMP_MODEL_TOP]);
            m.normals.push([c, s, 0.0]);
            m.uvs.push([i as f32 / SIDES as f32, 0.0]);
        }
    }
    for i in 0..SIDES as u32 {
        let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        m.indices.extend_from_slice(&[b0, b1, t1, b0, t1, t0]);
    }
    let base = m.positions.len() as u32;
    for i in 0..=SIDES {
        let a = tau * i as f32 / SIDES as f32;
        let (s, c) = a.sin_cos();
        for r in [FACE_SHARE * UNIT_RADIUS, UNIT_RADIUS] {
            m.positions.push([r * c, r * s, STUMP_MODEL_TOP]);
            m.normals.push([0.0, 0.0, 1.0]);
            m.uvs.push([i as f32 / SIDES as f32, 0.0]);
        }
    }
    for i in 0..SIDES as u32 {
        let (i0, o0, i1, o1) = (base + 2 * i, base + 2 * i + 1, base + 2 * i + 2, base + 2 * i + 3);
        m.indices.extend_from_slice(&[i0, o0, o1, i0, o1, i1]);
    }
    m
}

/// The normalised cut face: a disc of [`FACE_SHARE`] × [`UNIT_RADIUS`] at [`STUMP_MODEL_TOP`].
fn face_mesh() -> TriMesh {
    let mut m = TriMesh::default();
    m.positions.push([0.0, 0.0, STUMP_MODEL_TOP]);
    m.normals.push([0.0, 0.0, 1.0]);
    m.uvs.push([0.5, 0.0]);
    let tau = std::f32::consts::TAU;
    for i in 0..SIDES {
        let (s, c) = (tau * i as f32 / SIDES as f32).sin_cos();
        m.positions.push([FACE_SHARE * UNIT_RADIUS * c, FACE_SHARE * UNIT_RADIUS * s, STUMP_MODEL_TOP]);
        m.normals.push([0.0, 0.0, 1.0]);
        m.uvs.push([i as f32 / SIDES as f32, 0.0]);
    }
    for i in 0..SIDES as u32 {
        m.indices.extend_from_slice(&[0, 1 + i, 1 + (i + 1) % SIDES as u32]);
    }
    // a skirt inside the bark, a tenth of the stump deep: hidden, but it gives the face's
    // outline a height, which the billboard is carved from (a flat outline would give the
    // renderer's default crown, as tall as the instance)
    let base = m.positions.len() as u32;
    for i in 0..=SIDES {
        let (s, c) = (tau * i as f32 / SIDES as f32).sin_cos();
        for z in [0.9, 1.0] {
            m.positions.push([FACE_SHARE * UNIT_RADIUS * c, FACE_SHARE * UNIT_RADIUS * s, z * STUMP_MODEL_TOP]);
            m.normals.push([c, s, 0.0]);
            m.uvs.push([i as f32 / SIDES as f32, 0.0]);
        }
    }
    for i in 0..SIDES as u32 {
        let (b0, t0, b1, t1) = (base + 2 * i, base + 2 * i + 1, base + 2 * i + 2, base + 2 * i + 3);
        m.indices.extend_from_slice(&[b0, b1, t1, b0, t1, t0]);
    }
    m
}

/// The stump prototypes, [`STUMP_PROTOTYPES`] of them: for weathering class `k` (0 fresh ..
/// [`STUMP_CLASSES`] − 1), `2k` the bark and `2k + 1` the cut face. Normalised to a height of
/// [`STUMP_MODEL_TOP`] in a model 1 m tall (instances scale them), bark only at every mesh level (no foliage,
/// stiff: no sway), as the obstacles' models are.
pub fn stump_prototypes() -> Vec<Prototype> {
    let mut out = Vec::with_capacity(STUMP_PROTOTYPES);
    for k in 0..STUMP_CLASSES {
        let (bark, face) = stump_colors(k);
        for (part, mesh, rgb) in [("bark", bark_mesh(), bark), ("cut face", face_mesh(), face)] {
            let level = TreeMesh { bark: mesh, leaves: TriMesh::default() };
            out.push(Prototype { name: format!("stump {part} (weathering class {k})"), lods: LodChain::new(vec![level; LOD_LEVELS - 1]), bark_color: rgb, leaf_color: rgb, stiffness: 1.0, look: None, rigid: false });
        }
    }
    out
}

/// The instances drawing the stumps of `stumps` shown in a picture of `year`
/// ([`stump_shown`]), standing on the ground of `cond`, with the prototypes of
/// [`stump_prototypes`] from index `first`. A stump cut `a` years before `year` (0..19) is of
/// weathering class `a · STUMP_CLASSES / STUMP_YEARS`, [`STUMP_HEIGHT_M`] × (1 − a / 40) tall
/// (settling to 0.16 m; the instance's height is that over [`STUMP_MODEL_TOP`]) and its radius
/// shrinks likewise by up to 15 % (not below [`STUMP_MIN_RADIUS_M`]). Ids: the tree's id
/// with the top bit set (the cut face's also with the next bit), so that they never match a
/// living tree's in the timelapse or the viewer. The instances' leaf colour is the part's
/// colour with full leaf amount, so that the billboard and the canopy layer of a stump far off
/// have its colour.
pub fn stump_instances(stumps: &[Stump], year: u32, cond: &SiteConditions, first: u32) -> Vec<TreeInstance> {
    let mut out = Vec::new();
    for s in stumps.iter().filter(|s| stump_shown(s.year, year)) {
        let age = (year - s.year) as f32;
        let k = ((age * STUMP_CLASSES as f32 / STUMP_YEARS as f32) as usize).min(STUMP_CLASSES - 1);
        let shrink = 1.0 - age / (2.0 * STUMP_YEARS as f32);
        let h = STUMP_HEIGHT_M * shrink;
        let r = (s.radius_m() * (1.0 - 0.3 * (1.0 - shrink))).max(STUMP_MIN_RADIUS_M);
        let z = cond.elevation_at(s.x_m, s.y_m);
        let (bark, face) = stump_colors(k);
        for (part, rgb) in [(0u32, bark), (1, face)] {
            let id = s.id | (1 << 63) | ((part as u64) << 62);
            let mut t = TreeInstance::new(id, [s.x_m as f32, s.y_m as f32, z], h / STUMP_MODEL_TOP, r, first + 2 * k as u32 + part, rgb);
            t.rotation = 0.0;
            out.push(t);
        }
    }
    out
}

/// Whether instance `t` is a stump's (its id has the top bit set: [`stump_instances`]).
pub fn is_stump(t: &TreeInstance) -> bool {
    t.id >> 63 == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stumps_are_drawn_for_twenty_years_and_weather() {
        let cond = SiteConditions::uniform(10, 10, 10.0, 400.0, [5.0; 6], 47.0);
        let s = [Stump { id: 7, x_m: 20.0, y_m: 30.0, dbh_cm: 40.0, year: 50 }, Stump { id: 8, x_m: 40.0, y_m: 30.0, dbh_cm: 2.0, year: 60 }];
        assert_eq!(stump_instances(&s, 49, &cond, 3).len(), 0);
        let fresh = stump_instances(&s, 50, &cond, 3);
        assert_eq!(fresh.len(), 2);
        assert_eq!(fresh[0].species, 3);
        assert_eq!(fresh[1].species, 4);
        assert!((fresh[0].crown_radius - 0.22).abs() < 1e-6 && (fresh[0].height * STUMP_MODEL_TOP - STUMP_HEIGHT_M).abs() < 1e-6);
        assert!(fresh.iter().all(is_stump) && fresh[0].id != fresh[1].id);
        let later = stump_instances(&s, 69, &cond, 3);
        assert_eq!(later.len(), 4);
        assert_eq!(later[0].species, 3 + 2 * (STUMP_CLASSES as u32 - 1));
        assert!(later[0].height * STUMP_MODEL_TOP < 0.6 * STUMP_HEIGHT_M && later[0].crown_radius < 0.22);
        // the 2 cm tree: the smallest stump
        assert!((later[2].crown_radius - STUMP_MIN_RADIUS_M).abs() < 1e-6);
        assert_eq!(stump_instances(&s, 70, &cond, 3).len(), 2);
        let p = stump_prototypes();
        assert_eq!(p.len(), STUMP_PROTOTYPES);
        assert!(p.iter().all(|p| (p.normalised_crown_radius() - UNIT_RADIUS).abs() < 1e-6));
        // the billboards' outlines end at the stump's top, not at the instance's
        for p in &p {
            let sil = crate::render::lod::Silhouette::from_chain(&p.lods);
            assert!(sil.crown_top <= STUMP_MODEL_TOP + 1e-6 && sil.crown_top > sil.crown_bottom, "{}: {sil:?}", p.name);
        }
        // the cut face lighter than the bark when fresh, both greyer later
        let lum = |c: [f32; 3]| c[0] + c[1] + c[2];
        let ((b0, f0), (b3, f3)) = (stump_colors(0), stump_colors(STUMP_CLASSES - 1));
        assert!(lum(f0) > 2.0 * lum(b0));
        assert!((f3[0] - f3[2]) < (f0[0] - f0[2]) && (b3[0] - b3[2]) < (b0[0] - b0[2]));
    }

    #[test]
    fn only_harvested_trees_with_a_dbh_leave_stumps() {
        let row = |id: u64, status: &str, dbh: f32| InventoryRow { id, species: "beech".into(), x_m: 1.0, y_m: 2.0, z_m: 0.0, age_yr: 30.0, height_m: 12.0, dbh_cm: dbh, crown_radius_m: 2.0, crown_base_m: 6.0, status: status.into() };
        let rows = [row(1, "alive", 20.0), row(2, "dead:harvest", 20.0), row(3, "dead:stress", 20.0), row(4, "dead:harvest", 0.0)];
        assert_eq!(stumps_from_rows(&rows, 12), vec![Stump { id: 2, x_m: 1.0, y_m: 2.0, dbh_cm: 20.0, year: 12 }]);
    }
}
