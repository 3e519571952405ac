//! A tree of a species sized to the species at an age (issue 32): its height from the
//! species' height–age curve, its DBH, crown base and crown width from the stand-grown (or
//! open-grown) functions of its species file ([`tree_form`]); the EcoMod tree of
//! [`crate::structure::species_tree`] fitted to them ([`grow_formed_tree`], what `sylva tree
//! grow` draws); and the measures a forester takes of a grown tree ([`ArchitectureMeasures`]).

use super::skeleton::{Leaves, Skeleton};
use super::species_tree::{ecomod_strands_at, grow_species_tree, GrownTree, Model};
use super::grow::ecomod;
use crate::error::{Error, Result};
use crate::obstacle::Obstacle;
use crate::species::{EcoModParams, Species};
use glam::Vec3;

/// How the tree of [`grow_formed_tree`] is dimensioned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Habit {
    /// A tree of a closed, even-aged stand (the default of `sylva tree grow`): DBH from the
    /// species' dense-stand height–diameter curve (`life.dense_hd`), crown base from its
    /// stand-grown crown-base function (`life.stand_crown_base`), crown width from its
    /// stand-grown crown-width function (`life.stand_crown`); where the species file has none of
    /// one, the open-grown value below.
    Forest,
    /// A tree grown alone: DBH from the open-grown allometry (`life.allometry.hd_a`, `hd_b`),
    /// crown base `(1 − crown_ratio)·h`, crown radius `c0 + c1·DBH` (`life.allometry`).
    Open,
}

/// Dimensions of a tree of one species at one age, from the species file: what
/// [`grow_formed_tree`] fits its EcoMod tree to and `sylva tree grow` prints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeForm {
    /// Age (years).
    pub age_yr: f32,
    /// Habit the dimensions are for.
    pub habit: Habit,
    /// Height (m): the species' potential height at the age, Chapman–Richards
    /// `H(t) = H_max (1 − e^(−k t))^p` (`life.growth`; [`Species::potential_height_m`]).
    pub height_m: f32,
    /// Site index (m): the same curve at 100 years, the `h100` of the crown-base function.
    pub site_index_m: f32,
    /// Diameter at breast height (cm); 0 below 1.3 m.
    pub dbh_cm: f32,
    /// Crown base (m): height of the lowest live branch, in [0, 0.9·height].
    pub crown_base_m: f32,
    /// Crown radius (m): half the crown width, as foresters measure it (mean of the radii to the
    /// drip line), at least 0.05 m.
    pub crown_radius_m: f32,
}

impl TreeForm {
    /// Crown length (m): height − crown base.
    pub fn crown_length_m(&self) -> f32 {
        self.height_m - self.crown_base_m
    }
    /// Share (0–0.9) of the height clear of live branches: crown base / height.
    pub fn clear_bole_share(&self) -> f32 {
        self.crown_base_m / self.height_m.max(1e-6)
    }
    /// Crown width / crown length (2·radius / (height − crown base)).
    pub fn width_to_length(&self) -> f32 {
        2.0 * self.crown_radius_m / self.crown_length_m().max(1e-6)
    }
}

/// Stand-grown DBH (cm) of a tree `h` m tall: the species' dense-stand curve
/// `h = 1.3 + k·D^(1+c)/100` solved for D (`life.dense_hd`, iLand HDhigh counted from breast
/// height, as the simulation's height bound `sim::phases::growth::dense_height_bound`; see
/// [`crate::species::DenseHd`]), or the open-grown DBH where the species has none; 0 below 1.3 m.
pub fn stand_dbh_cm(sp: &Species, h: f32) -> f32 {
    if h < 1.3 {
        return 0.0;
    }
    match sp.life.dense_hd {
        Some(d) if d.k > 0.0 && d.c > -1.0 => (100.0 * (h - 1.3) / d.k).powf(1.0 / (1.0 + d.c)),
        _ => sp.dbh_from_height_cm(h),
    }
}

/// The dimensions of a tree of `sp` at `age_yr` years (> 0) of `habit` ([`TreeForm`]).
///
/// Errors: [`Error::Invalid`] for an age that is not a positive finite number.
pub fn tree_form(sp: &Species, age_yr: f32, habit: Habit) -> Result<TreeForm> {
    if !(age_yr.is_finite() && age_yr > 0.0) {
        return Err(Error::Invalid { context: format!("tree of {}", sp.id), field: "age".into(), value: age_yr.to_string(), expected: "a positive number of years".into() });
    }
    let h = sp.potential_height_m(age_yr).max(0.05);
    let h100 = sp.potential_height_m(100.0);
    let open_cb = (1.0 - sp.life.allometry.crown_ratio).clamp(0.0, 0.9) * h;
    let (dbh, cb, r) = match habit {
        Habit::Open => {
            let d = if h < 1.3 { 0.0 } else { sp.dbh_from_height_cm(h) };
            (d, open_cb, crate::species::allometry::open_crown_radius(sp, h, d))
        }
        Habit::Forest => {
            let d = stand_dbh_cm(sp, h);
            let cb = match sp.life.stand_crown_base {
                Some(f) if d > 0.0 => f.crown_base_m(h, d, h100),
                _ => open_cb,
            };
            let cb = cb.clamp(0.0, 0.9 * h);
            let r = if d > 0.0 { crate::species::allometry::stand_crown_radius(sp, d, h, cb) } else { None };
            (d, cb, r.unwrap_or_else(|| crate::species::allometry::open_crown_radius(sp, h, d)))
        }
    };
    Ok(TreeForm { age_yr, habit, height_m: h, site_index_m: h100, dbh_cm: dbh, crown_base_m: cb.clamp(0.0, 0.9 * h), crown_radius_m: r.max(0.05) })
}

/// Grows one tree of `sp` at `age_yr` years as [`grow_species_tree`] does, and for EcoMod sizes
/// it to the species at that age ([`tree_form`] of `habit`): the EcoMod tree's trunk (its
/// first segment) is lengthened so that its first branch leaves the stem just above the crown
/// base (as the stand skeletons of [`crate::structure::stand::SkeletonCache::prepare`] are), then
/// the tree is scaled to the form's height and crown radius and shed below its crown base
/// ([`crate::structure::stand::fit`]), its wood radii scaled so the stem base is the form's DBH
/// (at least 1 cm) and its leaves kept at the species' leaf size (`leaf_size_m`), then its
/// crown narrowed or widened about the stem until its crown radius to the leaf tips
/// ([`crate::structure::stand::mean_crown_radius`]) is the form's (three passes). Light-guided
/// and Laplacian trees grow inside the species' crown envelope as before (not refitted).
///
/// Errors: those of [`grow_species_tree`] and [`tree_form`].
pub fn grow_formed_tree(sp: &Species, model: Model, age_yr: f32, obstacles: &[Obstacle], seed: u64, habit: Habit) -> Result<(GrownTree, TreeForm)> {
    let form = tree_form(sp, age_yr, habit)?;
    if model != Model::EcoMod {
        return Ok((grow_species_tree(sp, model, age_yr, obstacles, seed)?, form));
    }
    let mut p: EcoModParams = sp.architecture.ecomod.clone();
    p.strands = ecomod_strands_at(p.strands, age_yr);
    let (mut sk, mut lv) = ecomod::try_grow(&p, seed, 0.0)?;
    let qf = (form.crown_base_m / form.height_m).clamp(0.0, 0.89) + 0.01;
    let crown = sk.height() - p.trunk_length_m;
    let trunk = qf * crown / (1.0 - qf);
    if crown > 0.0 && trunk > p.trunk_length_m {
        p.trunk_length_m = trunk;
        (sk, lv) = ecomod::try_grow(&p, seed, 0.0)?;
    }
    let (sk, lv) = super::normalised(&sk, &lv, 1.0)?;
    let crown_radius = super::stand::mean_crown_radius(&sk, &lv).max(0.05);
    let g = super::stand::OpenGrown { skeleton: sk, leaves: lv, crown_radius };
    let (mut skeleton, mut leaves) = super::stand::fit(&g, form.height_m, form.crown_radius_m, form.crown_base_m);
    let r0 = skeleton.nodes.first().map(|n| n.radius).unwrap_or(0.0);
    if r0 > 0.0 && r0.is_finite() {
        let s = 0.005 * form.dbh_cm.max(2.0) / r0;
        skeleton.nodes.iter_mut().for_each(|n| n.radius *= s);
    }
    leaves.leaves.iter_mut().for_each(|l| l.size = p.leaf_size_m);
    // the species' leaf size is not scaled with the tree: a young tree's crown radius (measured
    // to the leaf tips) grew by it; three horizontal rescalings about the stem bring it back to
    // the form's radius (each one exact for the wood, the leaves' reach converging)
    for _ in 0..3 {
        let m = super::stand::mean_crown_radius(&skeleton, &leaves);
        if !(m > 0.0 && m.is_finite()) {
            break;
        }
        let k = form.crown_radius_m / m;
        let root = skeleton.nodes.first().map(|n| n.pos).unwrap_or(Vec3::ZERO);
        let sx = |q: Vec3| Vec3::new(root.x + (q.x - root.x) * k, root.y + (q.y - root.y) * k, q.z);
        skeleton.nodes.iter_mut().for_each(|n| n.pos = sx(n.pos));
        leaves.leaves.iter_mut().for_each(|l| l.pos = sx(l.pos));
    }
    Ok((GrownTree { skeleton, leaves, envelope: None, space: None }, form))
}

/// Architecture of a grown tree as a forester would measure it, for comparing species
/// ([`ArchitectureMeasures::of`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArchitectureMeasures {
    /// Height (m): highest node above the base.
    pub height_m: f32,
    /// Crown base (m): height of the lowest node where a branch (Gravelius order ≥ 1) leaves the
    /// trunk (order 0); the height when none does.
    pub crown_base_m: f32,
    /// Crown radius (m): [`crate::structure::stand::mean_crown_radius`] (mean of the radii to the
    /// drip line in eight sectors).
    pub crown_radius_m: f32,
    /// Mean angle (degrees, 0 up … 90 horizontal … 180 down) from the vertical of the first
    /// segments of the order-1 branches (the branches on the trunk); NaN when there are none.
    pub branch_angle_deg: f32,
    /// Order-1 branches counted for `branch_angle_deg`.
    pub branches: usize,
}

impl ArchitectureMeasures {
    /// Measures `sk` with its leaves (base at the root node, z up).
    pub fn of(sk: &Skeleton, leaves: &Leaves) -> ArchitectureMeasures {
        let h = sk.height();
        let z0 = sk.nodes.first().map(|n| n.pos.z).unwrap_or(0.0);
        let mut cb = f32::INFINITY;
        let (mut sum, mut k) = (0.0f64, 0usize);
        for n in &sk.nodes {
            let Some(p) = n.parent else { continue };
            let par = &sk.nodes[p as usize];
            if par.gravelius == 0 && n.gravelius == 1 {
                cb = cb.min(par.pos.z - z0);
                let d = (n.pos - par.pos).normalize_or_zero();
                if d != Vec3::ZERO {
                    sum += d.z.clamp(-1.0, 1.0).acos().to_degrees() as f64;
                    k += 1;
                }
            }
        }
        ArchitectureMeasures {
            height_m: h,
            crown_base_m: if cb.is_finite() { cb.max(0.0) } else { h },
            crown_radius_m: super::stand::mean_crown_radius(sk, leaves),
            branch_angle_deg: if k > 0 { (sum / k as f64) as f32 } else { f32::NAN },
            branches: k,
        }
    }
    /// Crown length (m): height − crown base.
    pub fn crown_length_m(&self) -> f32 {
        self.height_m - self.crown_base_m
    }
    /// Share of the height clear of branches: crown base / height.
    pub fn clear_bole_share(&self) -> f32 {
        self.crown_base_m / self.height_m.max(1e-6)
    }
    /// Crown width / crown length.
    pub fn width_to_length(&self) -> f32 {
        2.0 * self.crown_radius_m / self.crown_length_m().max(1e-6)
    }
}
