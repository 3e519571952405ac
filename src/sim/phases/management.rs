//! Management (the year's end, after mortality): the scenario's `[[management]]` entries due
//! this year ([`crate::sim::management`]), in scenario order: thinnings, clear-cuts and patch
//! cuts remove trees (recorded as dead with the cause [`DeathCause::Harvest`]), then plantings
//! add lattices of trees. Deterministic: thinnings order trees by DBH and id, patches and
//! planted species are drawn from streams keyed by the seed, the entry and the year, and every
//! sum runs in tree order, so the result does not depend on the thread count.

use crate::rng::{mix64, salt};
use crate::sim::management::{Action, Operation, Target};
use crate::sim::trees::{birth_id, DeadTree, DeathCause, NewTree, TreeStore, N_CAUSES};
use crate::sim::world::Site;
use crate::species::SpeciesLibrary;

/// First per-cell index of the ids of trees planted during a run ([`birth_id`]`(year, cell,
/// PLANT_INDEX_BASE + k)`): recruits of a light cell and year use the indices below it (at most
/// about 100, `regen::max_density_ha`), so planted trees never share a recruit's id, and their
/// ids follow the recruits' of the same cell and year. A light cell of at most 20 m holds at
/// most 41² = 1,681 trees of a 0.5 m lattice, below the 2,048 indices left.
pub const PLANT_INDEX_BASE: u32 = 2048;

/// What the management phase reads (site: the resolved entries, species, cells) and writes.
pub struct Manage<'a> {
    /// Scenario seed.
    pub seed: u64,
    /// The year being simulated (years completed before it); entries due in year `year + 1`
    /// act.
    pub year: u32,
    /// The fixed site (its `management` entries).
    pub site: &'a Site,
    /// Trees: the harvested are removed, the planted added (in id order).
    pub trees: &'a mut TreeStore,
    /// Appended: this year's harvested trees.
    pub dead: &'a mut Vec<DeadTree>,
    /// Incremented: deaths since the start by cause.
    pub deaths_total: &'a mut [u64; N_CAUSES],
}

/// Carries out the entries due this year. Returns the number of trees planted.
pub fn run(m: Manage<'_>) -> usize {
    let y = m.year + 1;
    let mut planted: Vec<(u32, NewTree)> = Vec::new();
    for op in &m.site.management {
        let Some(k) = op.spec.due(y) else { continue };
        let t = &*m.trees;
        let remove: Vec<bool> = match &op.action {
            Action::Thinning { from_below, target, trigger_rd, trigger_top_height_m } => thinning(m.site, t, op, *from_below, *target, *trigger_rd, *trigger_top_height_m),
            Action::ClearCut => (0..t.len()).map(|i| op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect(),
            Action::Patch { size_m, share } => patches(m.seed, t, op, *size_m, *share, k),
            Action::Planting { .. } => {
                planted.extend(m.site.plant(op, y).into_iter().map(|nt| (m.site.light.cell_of(nt.x, nt.y) as u32, nt)));
                continue;
            }
        };
        harvest(t, &remove, m.year, m.dead, m.deaths_total);
        let keep: Vec<bool> = remove.iter().map(|r| !r).collect();
        m.trees.retain(&keep);
    }
    let n = planted.len();
    if n > 0 {
        insert_planted(m.trees, planted, m.year);
    }
    n
}

/// Records trees flagged in `remove` as harvested in `year`.
fn harvest(t: &TreeStore, remove: &[bool], year: u32, dead: &mut Vec<DeadTree>, totals: &mut [u64; N_CAUSES]) {
    for i in (0..t.len()).filter(|&i| remove[i]) {
        dead.push(DeadTree { id: t.id[i], species: t.species[i], x: t.x[i], y: t.y[i], z: t.z[i], age: t.age[i], height: t.height[i], dbh: t.dbh[i], crown_radius: t.crown_radius[i], crown_base: t.crown_base[i], year, cause: DeathCause::Harvest });
        totals[DeathCause::Harvest.index()] += 1;
    }
}

/// The stand figures of a thinning's area, kept up to date as trees are removed: stems ≥ 1.3 m,
/// their basal area, and per species the count and squared-DBH sum of stems ≥ 7 cm DBH (for
/// the relative density).
struct Figures {
    stems: f64,
    ba_m2: f64,
    n7: Vec<f64>,
    d2_7: Vec<f64>,
}

impl Figures {
    fn add(&mut self, t: &TreeStore, i: usize, sign: f64) {
        self.stems += sign;
        self.ba_m2 += sign * t.basal_area_m2(i);
        if t.dbh[i] >= crate::sim::density::MIN_DBH_CM {
            let s = t.species[i] as usize;
            self.n7[s] += sign;
            self.d2_7[s] += sign * (t.dbh[i] as f64).powi(2);
        }
    }
    fn value(&self, site: &Site, target: Target, a: f64) -> f64 {
        match target {
            Target::BasalArea(_) => self.ba_m2 / a,
            Target::Stems(_) => self.stems / a,
            Target::RelativeDensity(_) => stand_rd(&site.lib, &self.n7, &self.d2_7, a),
        }
    }
}

/// Relative density of trees: the sum over species of Reineke's SDI of the species' stems with a
/// DBH of at least [`crate::sim::density::MIN_DBH_CM`] per hectare of `area_ha`, over its
/// SDI_max (`life.density`; 1 = on the maximum-density line), as
/// [`crate::sim::density::stand_density`]'s `rd`. `n[s]` and `d2[s]` are the count and the sum of
/// squared DBH (cm²) per library species.
pub fn stand_rd(lib: &SpeciesLibrary, n: &[f64], d2: &[f64], area_ha: f64) -> f64 {
    let mut rd = 0.0;
    for s in 0..n.len() {
        if n[s] > 0.0 {
            let d = &lib.species[s].life.density;
            rd += crate::sim::density::sdi(n[s] / area_ha, (d2[s] / n[s]).sqrt(), d.reineke_slope as f64) / d.sdi_max as f64;
        }
    }
    rd
}

/// The trees a thinning removes: none unless its triggers hold over its area; else the stems
/// (≥ 1.3 m) of its area from the smallest DBH (`from_below`) or the largest, ties by id,
/// until the area's figure is at or below the target.
fn thinning(site: &Site, t: &TreeStore, op: &Operation, from_below: bool, target: Target, trigger_rd: Option<f64>, trigger_h: Option<f64>) -> Vec<bool> {
    let mut remove = vec![false; t.len()];
    let a = op.region.area_ha.max(1e-9);
    let mut cand: Vec<usize> = (0..t.len()).filter(|&i| t.height[i] >= 1.3 && t.dbh[i] > 0.0 && op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect();
    let ns = site.lib.species.len();
    let mut f = Figures { stems: 0.0, ba_m2: 0.0, n7: vec![0.0; ns], d2_7: vec![0.0; ns] };
    for &i in &cand {
        f.add(t, i, 1.0);
    }
    if let Some(rd) = trigger_rd {
        if f.value(site, Target::RelativeDensity(rd), a) < rd {
            return remove;
        }
    }
    if let Some(h) = trigger_h {
        let dbh: Vec<f32> = cand.iter().map(|&i| t.dbh[i]).collect();
        let height: Vec<f32> = cand.iter().map(|&i| t.height[i]).collect();
        if crate::sim::stats::top_height(&dbh, &height, a) < h {
            return remove;
        }
    }
    let goal = match target {
        Target::BasalArea(v) | Target::Stems(v) | Target::RelativeDensity(v) => v,
    };
    cand.sort_by(|&i, &j| {
        let o = t.dbh[i].total_cmp(&t.dbh[j]);
        (if from_below { o } else { o.reverse() }).then(t.id[i].cmp(&t.id[j]))
    });
    for &i in &cand {
        if f.value(site, target, a) <= goal {
            break;
        }
        remove[i] = true;
        f.add(t, i, -1.0);
    }
    remove
}

/// The trees of a patch cut's `k`-th entry: the area's bounding box is cut into squares of
/// `size_m`; the squares whose centre lies in the area are put in an order drawn once per entry
/// (seed, entry); entry `k` cuts the next `round(share · n)` (at least 1) of them, so each entry
/// opens new patches until all are cut. Every tree of a cut square inside the area goes.
fn patches(seed: u64, t: &TreeStore, op: &Operation, size_m: f64, share: f64, k: u32) -> Vec<bool> {
    let b = op.region.bbox;
    let nx = (((b[2] - b[0]) / size_m).ceil() as usize).max(1);
    let ny = (((b[3] - b[1]) / size_m).ceil() as usize).max(1);
    let mut eligible: Vec<(u64, usize)> = (0..nx * ny)
        .filter(|&p| op.region.contains(b[0] + ((p % nx) as f64 + 0.5) * size_m, b[1] + ((p / nx) as f64 + 0.5) * size_m))
        .map(|p| (mix64(seed ^ mix64(salt::MANAGEMENT ^ ((op.index as u64) << 40) ^ p as u64)), p))
        .collect();
    eligible.sort_unstable();
    let per = ((share * eligible.len() as f64).round() as usize).max(1);
    let lo = (k as usize).saturating_mul(per).min(eligible.len());
    let hi = (lo + per).min(eligible.len());
    let mut cut = vec![false; nx * ny];
    for &(_, p) in &eligible[lo..hi] {
        cut[p] = true;
    }
    (0..t.len())
        .map(|i| {
            let (x, y) = (t.x[i] as f64, t.y[i] as f64);
            if !op.region.contains(x, y) {
                return false;
            }
            let c = (((x - b[0]) / size_m) as usize).min(nx - 1);
            let r = (((y - b[1]) / size_m) as usize).min(ny - 1);
            cut[r * nx + c]
        })
        .collect()
}

/// Adds trees planted during the simulation of `year` (years completed before it) with their
/// light cells: ids [`birth_id`]`(year, cell, PLANT_INDEX_BASE + k)`, `k` counting each cell's
/// planted trees in planting order; merged into the store in id order.
fn insert_planted(trees: &mut TreeStore, planted: Vec<(u32, NewTree)>, year: u32) {
    let mut count: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    let mut with_ids: Vec<(u64, NewTree)> = planted
        .into_iter()
        .map(|(c, nt)| {
            let k = count.entry(c).or_insert(0);
            let id = birth_id(year, c, PLANT_INDEX_BASE + *k);
            *k += 1;
            (id, nt)
        })
        .collect();
    with_ids.sort_by_key(|e| e.0);
    let mut add = TreeStore::default();
    for (_, nt) in &with_ids {
        add.push(*nt);
    }
    add.id = with_ids.iter().map(|e| e.0).collect();
    let own = std::mem::take(trees);
    let next = own.next_id;
    *trees = TreeStore::merge_by_id(&[own, add], next).0;
}
