//! Crown envelope: the volume a species' open-grown crown occupies at an age, used to give the
//! light-guided and Laplacian trees a natural crown (ovoid for broadleaves, conical for
//! conifers) with its apex at the species' height instead of a crown that fills its voxel
//! space and spreads flat under the top.
//!
//! Sizes come from the species file: height H(t) from the Chapman–Richards curve
//! ([`allometry::potential_height`]), crown radius from the simulation's crown allometry
//! ([`allometry::open_crown_radius`] of the open-grown DBH at that height), crown length from
//! `life.allometry.crown_ratio`. The envelope's profile is our choice (crown-shape models of the
//! kind of Pretzsch 2009, ch. 8: a cone for conifers, an egg widest at 40 % of the crown length
//! for broadleaves).

use crate::species::{allometry, LeafType, Species};
use glam::Vec3;

/// Profile of the crown envelope.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CrownShape {
    /// Egg-shaped: widest at 40 % of the crown length above the crown base, elliptic below,
    /// R·√(1 − t²)·(1 − 0.35 t²) above (t = 0 at the widest point, 1 at the apex): a rounded
    /// point (broadleaves).
    Ovoid,
    /// Cone from the crown base (rounded over its lowest 15 %) to the apex (conifers).
    Conical,
}

/// A crown envelope around the vertical axis through `center` (the tree base), z up, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrownEnvelope {
    /// Tree base (m); the axis is vertical through it.
    pub base: Vec3,
    /// Apex height above the base (m), > 0.
    pub height_m: f32,
    /// Height of the crown base above the tree base (m), 0 ≤ crown base < height.
    pub crown_base_m: f32,
    /// Largest crown radius (m), > 0.
    pub radius_m: f32,
    /// Profile.
    pub shape: CrownShape,
    /// Radius of the free trunk corridor below and inside the crown (m): the leader can always
    /// grow up it.
    pub trunk_radius_m: f32,
}

impl CrownEnvelope {
    /// Envelope of `sp` at `age_yr` years: height H(t) (≥ 1.5 m), radius from the crown
    /// allometry (≥ 0.5 m, ≤ 0.45 H for conifers and 0.6 H for broadleaves so young trees are
    /// not wider than tall), crown length `crown_ratio`·H (0.3–0.95 of H), shape by leaf type.
    pub fn for_species(sp: &Species, age_yr: f32, base: Vec3) -> Self {
        Self::for_species_height(sp, allometry::potential_height(sp, age_yr), base)
    }

    /// [`CrownEnvelope::for_species`] of a tree `height_m` tall (m; at least 1.5 m is used)
    /// whatever its age: the same radius, crown length and shape.
    pub fn for_species_height(sp: &Species, height_m: f32, base: Vec3) -> Self {
        let h = height_m.max(1.5);
        let conifer = sp.identity.leaf_type == LeafType::Conifer;
        let r = allometry::open_crown_radius(sp, h, allometry::open_dbh(sp, h)).max(0.5).min(if conifer { 0.45 } else { 0.6 } * h);
        let ratio = sp.life.allometry.crown_ratio.clamp(0.3, 0.95);
        CrownEnvelope { base, height_m: h, crown_base_m: h * (1.0 - ratio), radius_m: r, shape: if conifer { CrownShape::Conical } else { CrownShape::Ovoid }, trunk_radius_m: (h / 40.0).max(0.1) }
    }

    /// Crown length (m).
    pub fn crown_length_m(&self) -> f32 {
        self.height_m - self.crown_base_m
    }

    /// Envelope radius (m) at height `z` above the base (m); 0 below the crown base and above
    /// the apex.
    pub fn radius_at(&self, z: f32) -> f32 {
        let l = self.crown_length_m();
        if l <= 0.0 {
            return 0.0;
        }
        let u = (z - self.crown_base_m) / l;
        if !(0.0..=1.0).contains(&u) {
            return 0.0;
        }
        match self.shape {
            CrownShape::Ovoid => {
                let w = 0.4;
                if u < w {
                    let t = (w - u) / w;
                    self.radius_m * (1.0 - t * t).max(0.0).sqrt()
                } else {
                    let t = (u - w) / (1.0 - w);
                    self.radius_m * (1.0 - t * t).max(0.0).sqrt() * (1.0 - 0.35 * t * t)
                }
            }
            CrownShape::Conical => {
                let skirt = (u / 0.15).min(1.0);
                self.radius_m * (1.0 - u) * (1.0 - (1.0 - skirt) * (1.0 - skirt)).sqrt()
            }
        }
    }

    /// Signed distance-like measure (m) of `p` outside the envelope: ≤ 0 inside the crown or in
    /// the trunk corridor (from the ground to 90 % of the height), > 0 outside (horizontal
    /// distance beyond the profile, or height above the apex).
    pub fn outside_m(&self, p: Vec3) -> f32 {
        let d = p - self.base;
        let rho = (d.x * d.x + d.y * d.y).sqrt();
        let z = d.z;
        if z > self.height_m {
            return (z - self.height_m).max(rho - self.trunk_radius_m);
        }
        if z < 0.9 * self.height_m && rho <= self.trunk_radius_m {
            return rho - self.trunk_radius_m;
        }
        let r = self.radius_at(z);
        if r > 0.0 {
            rho - r
        } else if z < self.crown_base_m {
            // below the crown (whose profile starts at radius 0): outside the corridor
            (rho - self.trunk_radius_m).max(self.crown_base_m - z).max(1e-3)
        } else {
            // at the apex
            (rho - self.trunk_radius_m).max(z - self.height_m).max(1e-3)
        }
    }

    /// Light factor (0–1) of the envelope at `p`: 1 inside, falling linearly to 0 over
    /// `margin_m` outside.
    pub fn light_factor(&self, p: Vec3, margin_m: f32) -> f32 {
        let o = self.outside_m(p);
        if o <= 0.0 {
            1.0
        } else {
            (1.0 - o / margin_m.max(1e-6)).clamp(0.0, 1.0)
        }
    }

    /// True when `p` is inside the crown or the trunk corridor.
    pub fn contains(&self, p: Vec3) -> bool {
        self.outside_m(p) <= 0.0
    }
}
