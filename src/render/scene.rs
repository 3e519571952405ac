//! Plain data the renderer consumes: terrain mesh, tree prototypes and instances, sun, sky, wind.
//!
//! World convention (DESIGN.md): metres, x east, y north, z up.

use crate::mesh::LodChain;

pub use super::camera::{Camera, CameraPreset, Projection};
pub use super::terrain::TerrainMesh;

/// One species' tree model as the renderer draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct Prototype {
    /// Species name (for logs and legends).
    pub name: String,
    /// Levels of detail, finest first, of a *normalised* tree: base at the origin, height 1 m,
    /// z up. Instances scale it to their height and crown radius.
    pub lods: LodChain,
    /// Bark albedo, linear RGB 0..1.
    pub bark_color: [f32; 3],
    /// Default foliage albedo, linear RGB 0..1 (instances carry their own seasonal colour).
    pub leaf_color: [f32; 3],
    /// Wind flexibility `k_f` of EcoMod (004_*.txt, Algorithm 1), 0..1: 1 = stiff (no
    /// undirected sway), 0 = fully flexible.
    pub stiffness: f32,
    /// How the crown reads from afar (top shape, airiness, lumps) on the coarse levels; `None`:
    /// measured from the finest level ([`super::lod::Silhouette::from_chain`]).
    pub look: Option<super::lod::CrownLook>,
    /// Drawn at its finest level whatever its size on screen, never as a billboard nor in the
    /// far-field canopy layer: an obstacle (a building, a wall), whose few triangles have no
    /// tree-like stand-in (trial 35: a 40 m × 30 m building, 8 m tall, was in no still, as its
    /// height made it a few pixels "tall" and sent it to the canopy layer). `false` for trees.
    pub rigid: bool,
}

impl Prototype {
    /// Crown radius of the normalised model (m per m of height): the largest horizontal
    /// distance of a foliage vertex of level 0 from the axis; 0.3 when the model has no leaves.
    pub fn normalised_crown_radius(&self) -> f32 {
        let r = self.lods.leaf_radius0();
        if r > 1e-4 {
            r
        } else {
            0.3
        }
    }
}

/// One tree to draw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeInstance {
    /// Stem base position (m), x east, y north, z = ground elevation.
    pub position: [f32; 3],
    /// Tree height (m), > 0.
    pub height: f32,
    /// Crown radius (m), > 0; scales the model horizontally.
    pub crown_radius: f32,
    /// Index into [`Scene::prototypes`].
    pub species: u32,
    /// Rotation about the vertical axis (rad).
    pub rotation: f32,
    /// Foliage colour (linear RGB 0..1) for the season (leaf-out, summer, autumn; bare crowns
    /// use `opacity_leaves = 0`).
    pub leaf_color: [f32; 3],
    /// Foliage presence 0..1 (0 = bare winter crown, leaves dithered out).
    pub leaf_amount: f32,
    /// Overall presence 0..1 for fading in/out in timelapses (screen-door dithered).
    pub opacity: f32,
    /// Stable tree id (matches trees across snapshots).
    pub id: u64,
    /// Dissolve into the sky colour seen behind the tree, 0 (none) ..1 (sky only): trees on
    /// the faded surroundings of the simulated window fade with the ground they stand on
    /// ([`TerrainMesh::fade`]); 0 for the window's own trees.
    pub sky_fade: f32,
    /// Height of the crown's base as a fraction of the tree's height (0.05..0.85; 0: the
    /// prototype's own): the prototype is stretched vertically in two pieces, its stem below
    /// its lowest foliage to reach this height and its crown above it to span the rest, so
    /// that a forest-grown tree with a high crown base is drawn with a clear stem and a short
    /// crown rather than as a prototype's open-grown crown squeezed narrow (a poplar-like
    /// column).
    pub crown_base: f32,
}

impl TreeInstance {
    /// A fully present tree in summer foliage.
    pub fn new(id: u64, position: [f32; 3], height: f32, crown_radius: f32, species: u32, leaf_color: [f32; 3]) -> Self {
        TreeInstance { position, height, crown_radius, species, rotation: (id as f32 * 2.399_963).rem_euclid(std::f32::consts::TAU), leaf_color, leaf_amount: 1.0, opacity: 1.0, id, sky_fade: 0.0, crown_base: 0.0 }
    }
}

/// Seasonal foliage colour of a deciduous broadleaf crown (linear RGB) and leaf amount for
/// day-of-year `doy` (1..=365): bare until leaf-out (~day 110), light green flush, summer green,
/// autumn yellow-orange from ~day 270, bare after ~day 310 (Central-European phenology,
/// ECOLOGY.md). Evergreen crowns should keep their summer colour.
pub fn deciduous_season(doy: f32, summer: [f32; 3]) -> ([f32; 3], f32) {
    let flush = [0.35, 0.55, 0.12];
    let autumn = [0.65, 0.38, 0.06];
    let lerp = |a: [f32; 3], b: [f32; 3], t: f32| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t];
    let d = doy.rem_euclid(365.0);
    if d < 105.0 || d > 315.0 {
        (autumn, 0.0)
    } else if d < 125.0 {
        (flush, (d - 105.0) / 20.0)
    } else if d < 160.0 {
        (lerp(flush, summer, (d - 125.0) / 35.0), 1.0)
    } else if d < 260.0 {
        (summer, 1.0)
    } else if d < 290.0 {
        (lerp(summer, autumn, (d - 260.0) / 30.0), 1.0)
    } else {
        (autumn, 1.0 - (d - 290.0) / 25.0)
    }
}

/// The sun: direction and colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Unit vector from the ground towards the sun (x east, y north, z up).
    pub direction: [f32; 3],
    /// Light colour × intensity, linear RGB (1 = full midday sun).
    pub color: [f32; 3],
}

impl Sun {
    /// The sun's direction for latitude `latitude_deg` (−90..90), day of year `day_of_year`
    /// (1..=366) and local solar time `hour` (0..24).
    ///
    /// The direction is [`crate::sun::position`] (declination by Cooper 1969, 23.45°; hour angle
    /// 15°/h; computed in f64). Below the horizon the light is clamped to a dim twilight 2°
    /// above it; the colour warms as the sun sinks.
    pub fn from_position(latitude_deg: f32, day_of_year: f32, hour: f32) -> Self {
        let [east, north, up] = crate::sun::position(latitude_deg as f64, day_of_year as f64, hour as f64).map(|v| v as f32);
        let min_up = (2.0f32).to_radians().sin();
        let mut d = glam::Vec3::new(east, north, up.max(min_up));
        d = d.normalize_or(glam::Vec3::Z);
        let elev = up.clamp(-1.0, 1.0).asin();
        // warm and dim near the horizon
        let k = (elev / 0.5).clamp(0.0, 1.0);
        let color = [1.0, 0.55 + 0.4 * k, 0.35 + 0.55 * k];
        let intensity = 0.25 + 0.75 * k;
        Sun { direction: d.to_array(), color: [color[0] * intensity, color[1] * intensity, color[2] * intensity] }
    }

    /// Solar elevation above the horizon (degrees) of this direction.
    pub fn elevation_deg(&self) -> f32 {
        self.direction[2].clamp(-1.0, 1.0).asin().to_degrees()
    }
}

impl Default for Sun {
    fn default() -> Self {
        Sun::from_position(47.0, 172.0, crate::sun::REFERENCE_HOUR)
    }
}

/// Sky colours (linear RGB) for the gradient behind the scene; also the ambient light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    /// Colour straight up.
    pub zenith: [f32; 3],
    /// Colour at the horizon.
    pub horizon: [f32; 3],
}

impl Default for Sky {
    fn default() -> Self {
        Sky { zenith: [0.13, 0.28, 0.65], horizon: [0.55, 0.68, 0.85] }
    }
}

/// Wind driving the sway of trees (EcoMod, 004_*.txt, Algorithm 1).
///
/// Per vertex at normalised height `s` (0 at the base, 1 at the top) the tree bends by
/// `α_w(s) = k_w · w_g · s²` rad along `direction` (directed wind, EcoMod `α_w = S_0/S · w_g`:
/// the strand ratio `S_0/S` falls towards the top, which we model by the height fraction) and
/// sways by `α_x(t) = sin(t + R_x) · w_s · (1 − k_f) · l_0`, `α_z(t) = sin(t + R_z) · …` (undirected
/// wind) with `l_0 = s²` and phases `R_x, R_z` from the tree id; `k_w = 0.02 rad` per unit of
/// wind speed (EcoMod's speeds are 0..10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    /// Unit 2-D direction the wind blows *towards* (x east, y north).
    pub direction: [f32; 2],
    /// Directed wind speed `w_g` (EcoMod units 0..10, ≈ Beaufort).
    pub directed: f32,
    /// Undirected (gusty) wind speed `w_s` (0..10).
    pub undirected: f32,
    /// Animation time `t` (s).
    pub time_s: f32,
}

impl Default for Wind {
    fn default() -> Self {
        Wind { direction: [1.0, 0.0], directed: 0.0, undirected: 0.0, time_s: 0.0 }
    }
}

/// The version of one part of a [`Scene`] (its terrain, its prototypes): a number unique in the
/// process, taken anew whenever the part is replaced or marked changed, so that a renderer
/// uploads the part again only when its version differs from the one it uploaded (explicit
/// change tracking: no hashing of the meshes per frame). A clone of a scene shares its versions,
/// which is right as long as neither is changed without a new version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Version(u64);

impl Version {
    /// A version no other call has returned in this process.
    pub fn new() -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Version(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

impl Default for Version {
    /// A fresh version ([`Version::new`]).
    fn default() -> Self {
        Version::new()
    }
}

/// Everything the renderer draws.
///
/// The terrain (with the sea level) and the prototypes are uploaded to the GPU once and kept
/// there while their [`Version`]s stay the same; the instances, sun, sky and wind are read every
/// frame. Replace them with [`Scene::set_terrain`], [`Scene::set_sea_level`] and
/// [`Scene::set_prototypes`], or after changing them in place call [`Scene::terrain_changed`] or
/// [`Scene::prototypes_changed`]: a change made without either is not seen by a renderer that
/// has already drawn the scene. Equality (`==`) compares the content, not the versions.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// The ground.
    pub terrain: TerrainMesh,
    /// Sea level (m): a water plane is drawn there when set.
    pub sea_level: Option<f32>,
    /// Tree models, indexed by [`TreeInstance::species`].
    pub prototypes: Vec<Prototype>,
    /// Trees.
    pub instances: Vec<TreeInstance>,
    /// Sun.
    pub sun: Sun,
    /// Sky.
    pub sky: Sky,
    /// Wind.
    pub wind: Wind,
    /// Version of `terrain` and `sea_level`.
    terrain_version: Version,
    /// Version of `prototypes`.
    prototypes_version: Version,
}

impl PartialEq for Scene {
    /// Same content (terrain, sea level, prototypes, instances, sun, sky, wind), whatever the versions.
    fn eq(&self, o: &Self) -> bool {
        let Scene { terrain, sea_level, prototypes, instances, sun, sky, wind, terrain_version: _, prototypes_version: _ } = self;
        *terrain == o.terrain && *sea_level == o.sea_level && *prototypes == o.prototypes && *instances == o.instances && *sun == o.sun && *sky == o.sky && *wind == o.wind
    }
}

impl Scene {
    /// A scene of these parts, each static part with a fresh [`Version`].
    pub fn new(terrain: TerrainMesh, sea_level: Option<f32>, prototypes: Vec<Prototype>, instances: Vec<TreeInstance>, sun: Sun, sky: Sky, wind: Wind) -> Self {
        Scene { terrain, sea_level, prototypes, instances, sun, sky, wind, terrain_version: Version::new(), prototypes_version: Version::new() }
    }
    /// Replaces the terrain (a new terrain version: uploaded again on the next frame).
    pub fn set_terrain(&mut self, terrain: TerrainMesh) {
        self.terrain = terrain;
        self.terrain_changed();
    }
    /// Sets the sea level in metres, `None` for no water plane (part of the terrain version).
    pub fn set_sea_level(&mut self, sea_level: Option<f32>) {
        self.sea_level = sea_level;
        self.terrain_changed();
    }
    /// Replaces the prototypes (a new prototypes version: uploaded again on the next frame).
    pub fn set_prototypes(&mut self, prototypes: Vec<Prototype>) {
        self.prototypes = prototypes;
        self.prototypes_changed();
    }
    /// Marks the terrain or the sea level as changed in place (a new terrain version).
    pub fn terrain_changed(&mut self) {
        self.terrain_version = Version::new();
    }
    /// Marks the prototypes as changed in place (a new prototypes version).
    pub fn prototypes_changed(&mut self) {
        self.prototypes_version = Version::new();
    }
    /// The version of the terrain and sea level.
    pub fn terrain_version(&self) -> Version {
        self.terrain_version
    }
    /// The version of the prototypes.
    pub fn prototypes_version(&self) -> Version {
        self.prototypes_version
    }
}

use crate::rng::unit_f32 as hash01;

/// A synthetic scene for tests, benchmarks and demos: a `size_m` × `size_m` terrain of gentle
/// analytic hills (≈ 1 vertex per `size_m / 128` m, heights 0..~0.12·size), two stand-in
/// prototypes (broadleaf 0, conifer 1) and `n_trees` trees 12–30 m tall placed by a hash of
/// `seed` (deterministic), summer noon sun at 47° N.
pub fn demo_scene(n_trees: usize, size_m: f32, seed: u64) -> Scene {
    let n = 129usize;
    let cell = size_m / (n - 1) as f32;
    let amp = 0.06 * size_m;
    let height = |x: f32, y: f32| {
        let (u, v) = (x / size_m * std::f32::consts::TAU, y / size_m * std::f32::consts::TAU);
        amp * (1.0 + 0.6 * (u * 1.3).sin() * (v * 0.9).cos() + 0.3 * (u * 2.7 + 1.0).cos() * (v * 2.1).sin()) * 0.6
    };
    let mut heights = crate::grid::Grid::filled(n, n, 0.0f32);
    for r in 0..n {
        for c in 0..n {
            // cell centres: x = (c + 0.5)·cell, y = (n − r − 0.5)·cell
            *heights.get_mut(c, r) = height((c as f32 + 0.5) * cell, (n as f32 - r as f32 - 0.5) * cell);
        }
    }
    let terrain = super::terrain::from_grid(&heights, cell, cell, &super::terrain::LandCover::default(), None).unwrap_or_default();
    let prototypes = vec![
        Prototype { name: "broadleaf".into(), lods: super::lod::placeholder_chain(false), bark_color: [0.3, 0.2, 0.12], leaf_color: [0.12, 0.3, 0.05], stiffness: 0.6, look: Some(super::lod::CrownLook { top_flatness: 0.6, cover: 1.0, clump: 0.15, leaf_shape: None }), rigid: false },
        Prototype { name: "conifer".into(), lods: super::lod::placeholder_chain(true), bark_color: [0.26, 0.15, 0.09], leaf_color: [0.04, 0.16, 0.06], stiffness: 0.8, look: Some(super::lod::CrownLook { top_flatness: 0.0, cover: 1.0, clump: 0.2, leaf_shape: None }), rigid: false },
    ];
    let mut instances = Vec::with_capacity(n_trees);
    for i in 0..n_trees as u64 {
        let k = seed.wrapping_mul(0x1000_0000_01B3) ^ (i << 8);
        let x = (0.5 + hash01(k)) * cell + hash01(k ^ 1) * (size_m - 2.0 * cell);
        let y = (0.5 + hash01(k ^ 2)) * cell + hash01(k ^ 3) * (size_m - 2.0 * cell);
        let species = (hash01(k ^ 4) < 0.45) as u32;
        let h = 12.0 + 18.0 * hash01(k ^ 5);
        let cr = if species == 1 { 0.2 * h } else { 0.3 * h } * (0.8 + 0.4 * hash01(k ^ 6));
        let leaf = prototypes[species as usize].leaf_color;
        let tint = 0.85 + 0.3 * hash01(k ^ 7);
        instances.push(TreeInstance::new(i, [x, y, height(x, y) - 0.3], h, cr, species, [leaf[0] * tint, leaf[1] * tint, leaf[2] * tint]));
    }
    Scene::new(terrain, None, prototypes, instances, Sun::default(), Sky::default(), Wind::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_at_noon_equinox_stands_at_colatitude_in_the_south() {
        // day 80 ≈ March equinox: declination ≈ 0, noon elevation = 90° − latitude
        let s = Sun::from_position(47.0, 80.0, 12.0);
        assert!((s.elevation_deg() - 43.0).abs() < 1.0, "{}", s.elevation_deg());
        assert!(s.direction[1] < 0.0 && s.direction[0].abs() < 1e-3, "{:?}", s.direction);
        // summer solstice: δ = 23.44°, elevation 66.4°
        let s = Sun::from_position(47.0, 172.0, 12.0);
        assert!((s.elevation_deg() - 66.44).abs() < 0.2, "{}", s.elevation_deg());
        // morning sun in the east, afternoon in the west
        assert!(Sun::from_position(47.0, 172.0, 9.0).direction[0] > 0.3);
        assert!(Sun::from_position(47.0, 172.0, 15.0).direction[0] < -0.3);
        // night is clamped just above the horizon, dimmed
        let n = Sun::from_position(47.0, 172.0, 0.0);
        assert!(n.elevation_deg() > 1.0 && n.elevation_deg() < 3.0);
        assert!(n.color[1] < 0.5);
    }

    #[test]
    fn season_colours() {
        let summer = [0.1, 0.3, 0.05];
        assert_eq!(deciduous_season(200.0, summer), (summer, 1.0));
        assert_eq!(deciduous_season(30.0, summer).1, 0.0);
        let (c, a) = deciduous_season(295.0, summer);
        assert!(c[0] > c[1] && a > 0.5 && a < 1.0, "{c:?} {a}");
        assert!(deciduous_season(115.0, summer).1 > 0.0 && deciduous_season(115.0, summer).1 < 1.0);
    }

    #[test]
    fn demo_scene_is_valid_and_deterministic() {
        let a = demo_scene(50, 300.0, 5);
        let b = demo_scene(50, 300.0, 5);
        assert_eq!(a, b);
        a.terrain.validate().unwrap();
        assert_eq!(a.instances.len(), 50);
        let (lo, hi) = a.terrain.bounds();
        for t in &a.instances {
            assert!(t.position[0] >= lo[0] && t.position[0] <= hi[0] && t.position[1] >= lo[1] && t.position[1] <= hi[1]);
            // stands on the ground: within 2 m of the nearest vertex height
            let g = a.terrain.nearest_height(t.position[0], t.position[1]).unwrap();
            assert!((t.position[2] - g).abs() < 2.0, "{} vs {g}", t.position[2]);
        }
    }
}
