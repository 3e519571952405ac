//! Management (the year's end, after mortality): the scenario's `[[management]]` entries due
//! this year ([`crate::sim::management`]), in scenario order: thinnings, clear-cuts and patch
//! cuts remove trees (recorded as dead with the cause [`DeathCause::Harvest`]), entries keeping
//! a clearing open remove the trees taller than their height (cause `harvest` too) and the
//! sapling cohorts above it ([`keep_open_cohorts`]), then plantings add lattices of trees. Deterministic: thinnings order trees by DBH and id, patches and
//! planted species are drawn from streams keyed by the seed, the entry and the year, and every
//! sum runs in tree order, so the result does not depend on the thread count.

use crate::rng::{mix64, salt};
use crate::sim::management::{patch_squares, Action, Operation, Target, SHELTER_OVERSTOREY, SHELTER_RADIUS_M};
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

/// Carries out the entries due this year. Returns the number of trees planted and one note per
/// thinning entry (`thinning` or crop trees) due this year that removed no tree, saying so:
/// `year Y: management[i] (thinning METHOD) removed nothing: WHY`, WHY being a trigger that
/// does not hold (with the area's figure), the area's figure at or below the target already,
/// or no stems of the growing stock (≥ 7 cm DBH) or of its main stand in its area; the run writes each to its log
/// (standard error) once.
pub fn run(m: Manage<'_>) -> (usize, Vec<String>) {
    let (n, notes, _, _, _) = run_by_entry(m);
    (n, notes)
}

/// [`run`], also returning how many trees each entry removed this year (entry order; the
/// entries' harvested trees follow each other in `dead` in that order, after those recorded
/// before the phase): the management table's harvest per entry; and per entry whether its
/// `max_removal_share` stopped its thinning short of its target (the management table's
/// `capped`; a note says so too); and per entry the positions (m) of the trees it planted this
/// year (a tiled run's rank plants on the cells it holds, its halo's included, and counts those
/// it keeps; the ranks' counts are summed for the management table's `planted_ha`, trial 46 D5).
pub fn run_by_entry(m: Manage<'_>) -> (usize, Vec<String>, Vec<usize>, Vec<bool>, Vec<Vec<[f32; 2]>>) {
    let y = m.year + 1;
    let mut planted: Vec<(u32, NewTree)> = Vec::new();
    // the lattice points kept by this year's plantings so far ([`fill_gaps`])
    let mut year_points: Vec<Point> = Vec::new();
    let mut notes = Vec::new();
    let mut removed = vec![0usize; m.site.management.len()];
    let mut capped = vec![false; m.site.management.len()];
    let mut planted_by = vec![Vec::new(); m.site.management.len()];
    for (e, op) in m.site.management.iter().enumerate() {
        let Some(k) = op.spec.due(y) else { continue };
        let t = &*m.trees;
        let (remove, why): (Vec<bool>, Option<String>) = match &op.action {
            Action::Thinning { from_below, target, trigger_rd, trigger_top_height_m } => {
                let (r, why, cap) = thinning(m.site, t, op, *from_below, *target, *trigger_rd, *trigger_top_height_m);
                if let Some(c) = cap {
                    notes.push(format!("year {y}: management[{e}] (thinning {}) {c}", if *from_below { "from_below" } else { "from_above" }));
                    capped[e] = true;
                }
                (r, why)
            }
            Action::CropTrees { n_ha, distance_m, target, trigger_rd, trigger_top_height_m } => {
                let (r, why, cap) = crop_tree_thinning(m.site, t, op, *n_ha, *distance_m, *target, *trigger_rd, *trigger_top_height_m);
                if let Some(c) = cap {
                    notes.push(format!("year {y}: management[{e}] (thinning crop_trees) {c}"));
                    capped[e] = true;
                }
                (r, why)
            }
            Action::ClearCut => ((0..t.len()).map(|i| op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect(), None),
            Action::Shelterwood { shares } => (shelterwood(t, op, shares.get(k as usize).copied().unwrap_or(1.0)), None),
            Action::Patch { size_m, share } => (patches(m.seed, t, op, *size_m, *share, k), None),
            Action::KeepOpen { max_height_m } => ((0..t.len()).map(|i| t.height[i] as f64 > *max_height_m && op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect(), None),
            Action::Planting { spacing_m, age_yr, .. } => {
                let (trees, kept, skipped, lattice) = fill_gaps(m.site, t, &year_points, op, y, *spacing_m, *age_yr);
                if skipped > 0 {
                    notes.push(format!("year {y}: management[{e}] (planting) fills the gaps of its area: {} of its {lattice} lattice points planted, {skipped} left out for standing within {} m (half its spacing) of a tree at least as tall or of this year's earlier plantings", lattice - skipped, 0.5 * spacing_m));
                }
                year_points.extend(kept);
                planted_by[e] = trees.iter().map(|t| [t.x, t.y]).collect();
                planted.extend(trees.into_iter().map(|nt| (m.site.light.cell_of(nt.x, nt.y) as u32, nt)));
                continue;
            }
        };
        if let Some(why) = why {
            if !remove.iter().any(|&r| r) {
                let method = match &op.action {
                    Action::Thinning { from_below: true, .. } => "from_below",
                    Action::Thinning { from_below: false, .. } => "from_above",
                    _ => "crop_trees",
                };
                notes.push(format!("year {y}: management[{e}] (thinning {method}) removed nothing: {why}"));
            }
        }
        let d0 = m.dead.len();
        harvest(&m.site.lib, t, &remove, m.year, m.dead, m.deaths_total);
        removed[e] = m.dead.len() - d0;
        let keep: Vec<bool> = remove.iter().map(|r| !r).collect();
        m.trees.retain(&keep);
    }
    let n = planted.len();
    if n > 0 {
        insert_planted(m.trees, planted, m.year);
    }
    (n, notes, removed, capped, planted_by)
}

/// A lattice point of a planting: `(x, y, height)` (m, m, m; the position rounded to the f32
/// of the tree planted there).
type Point = (f64, f64, f32);

/// A planting after the start fills the gaps of its area (round 44, trial 43 defect 3: a second
/// planting of a parcel put its lattice on the first's, its trees a median 0.32 m from a
/// planted tree): of its lattice points inside its area ([`Site::plant_points`]) it leaves out
/// those closer than half its spacing `spacing_m` (m) to a point kept by a planting of the same
/// year earlier in the scenario (`year_points`, in its area; whatever its height: fresh plants
/// of one year are not planted among each other) or to a living tree of its area (in `t`) at
/// least as tall as the shortest tree the planting can plant of the point's species (its age
/// `age_yr` less the lattice's half-year jitter;
/// [`crate::species::allometry::potential_height`]). Half the spacing because a point farther
/// than that from every tree is where a planter working the lattice finds room (a gap of
/// about a spacing); trees shorter than the planting's (regeneration below planting height) are
/// planted among, as a planter plants among low regrowth. Returns the trees planted (of
/// [`Site::plant`], those on kept points), the points kept (appended to `year_points` by the
/// caller), the points left out and the lattice's points in the area. Points, not trees, are
/// counted and kept, and only the area's trees are read, so a tiled run's ranks (each holding
/// the area's trees, its own cells' planted trees) keep the same points as one process.
///
/// [`Site::plant_points`]: crate::sim::world::Site::plant_points
/// [`Site::plant`]: crate::sim::world::Site::plant
fn fill_gaps(site: &Site, t: &TreeStore, year_points: &[Point], op: &Operation, y: u32, spacing_m: f64, age_yr: f32) -> (Vec<NewTree>, Vec<Point>, usize, usize) {
    let mut pts: Vec<(crate::species::SpeciesId, Point)> = Vec::new();
    site.plant_points(op, y, |s, x, yy, a| pts.push((s, (x as f32 as f64, yy as f32 as f64, crate::species::allometry::potential_height(site.species(s), a).max(0.3)))));
    let n = pts.len();
    let r = 0.5 * spacing_m;
    let b = op.region.bbox;
    let (nx, ny) = ((((b[2] - b[0]) / r).ceil() as usize).max(1), (((b[3] - b[1]) / r).ceil() as usize).max(1));
    let cell = |x: f64, y: f64| (((x - b[0]) / r).floor().clamp(0.0, (nx - 1) as f64) as usize, ((y - b[1]) / r).floor().clamp(0.0, (ny - 1) as f64) as usize);
    // the standing trees and this year's earlier points of the area, bucketed in cells of side r
    let mut grid: Vec<Vec<Point>> = vec![Vec::new(); nx * ny];
    let standing = (0..t.len()).map(|i| (t.x[i] as f64, t.y[i] as f64, t.height[i])).chain(year_points.iter().copied());
    let mut any = false;
    for (x, yy, h) in standing {
        if op.region.contains(x, yy) {
            let (c, rr) = cell(x, yy);
            grid[rr * nx + c].push((x, yy, h));
            any = true;
        }
    }
    let floor = |s: crate::species::SpeciesId| crate::species::allometry::potential_height(site.species(s), (age_yr - 0.5).max(1.0)).max(0.3);
    let kept: Vec<Point> = pts
        .iter()
        .filter(|&&(s, (x, yy, _))| {
            if !any {
                return true;
            }
            let h0 = floor(s);
            let (c, rr) = cell(x, yy);
            !(rr.saturating_sub(1)..=(rr + 1).min(ny - 1)).any(|row| (c.saturating_sub(1)..=(c + 1).min(nx - 1)).any(|col| grid[row * nx + col].iter().any(|&(px, py, h)| h >= h0 && (px - x).hypot(py - yy) < r)))
        })
        // a point kept blocks later plantings of the year whatever their height (fresh plants
        // of one year are not planted among each other)
        .map(|p| (p.1 .0, p.1 .1, f32::INFINITY))
        .collect();
    let skipped = n - kept.len();
    let trees = if skipped == 0 {
        site.plant(op, y)
    } else {
        let keys: std::collections::HashSet<(u64, u64)> = kept.iter().map(|p| (p.0.to_bits(), p.1.to_bits())).collect();
        site.plant(op, y).into_iter().filter(|nt| keys.contains(&((nt.x as f64).to_bits(), (nt.y as f64).to_bits()))).collect()
    };
    (trees, kept, skipped, n)
}

/// The regeneration layer's part of the entries keeping a clearing open that are due this year
/// (`year` the years completed before it; entries due in `year + 1` act): every sapling cohort
/// of a light cell whose centre lies in the entry's area ([`crate::sim::management::Region::contains`])
/// and whose mean height is above the entry's `max_height_m` is removed (a cohort's stems
/// share its mean height, so a cohort goes whole). Returns the sapling stems removed per entry
/// (entry order; 0 for other entries). The cohorts are not in the regeneration ledger's deaths
/// (whose causes are shade and crowding): the management table's `cut_saplings_ha` counts them.
/// Cohort cells are cells of the whole light grid, so a tile removes its own cohorts as one
/// process does.
pub fn keep_open_cohorts(site: &Site, year: u32, cohorts: &mut crate::sim::cohorts::Cohorts) -> Vec<u64> {
    let y = year + 1;
    let mut cut = vec![0u64; site.management.len()];
    for (e, op) in site.management.iter().enumerate() {
        let Action::KeepOpen { max_height_m } = op.action else { continue };
        if op.spec.due(y).is_none() || cohorts.is_empty() {
            continue;
        }
        let c = std::mem::take(cohorts);
        for i in 0..c.len() {
            let (cx, cy) = site.light.centre(c.cell[i] as usize);
            if c.height[i] as f64 > max_height_m && op.region.contains(cx, cy) {
                cut[e] += c.stems[i] as u64;
            } else {
                cohorts.push(c.get(i));
            }
        }
    }
    cut
}

/// Records trees flagged in `remove` as harvested in `year`.
fn harvest(lib: &crate::species::SpeciesLibrary, t: &TreeStore, remove: &[bool], year: u32, dead: &mut Vec<DeadTree>, totals: &mut [u64; N_CAUSES]) {
    for i in (0..t.len()).filter(|&i| remove[i]) {
        dead.push(DeadTree { id: t.id[i], species: t.species[i], x: t.x[i], y: t.y[i], z: t.z[i], age: t.age[i], height: t.height[i], dbh: t.dbh[i], crown_radius: t.crown_outline(lib, i), crown_base: t.crown_base[i], year, cause: DeathCause::Harvest });
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

/// The stems (≥ 1.3 m, with a DBH) of an entry's area, in store order.
fn stems_in(t: &TreeStore, op: &Operation) -> Vec<usize> {
    (0..t.len()).filter(|&i| t.height[i] >= 1.3 && t.dbh[i] > 0.0 && op.region.contains(t.x[i] as f64, t.y[i] as f64)).collect()
}

/// The figures of stems `cand` of an area, and, where the thinning's triggers do not hold there
/// (the area's relative density and top height at least the triggers'), why not.
fn figures_and_triggers(site: &Site, t: &TreeStore, cand: &[usize], a: f64, trigger_rd: Option<f64>, trigger_h: Option<f64>) -> (Figures, Option<String>) {
    let ns = site.lib.species.len();
    let mut f = Figures { stems: 0.0, ba_m2: 0.0, n7: vec![0.0; ns], d2_7: vec![0.0; ns] };
    for &i in cand {
        f.add(t, i, 1.0);
    }
    if let Some(rd) = trigger_rd {
        let v = f.value(site, Target::RelativeDensity(rd), a);
        if v < rd {
            return (f, Some(format!("the area's relative density {v:.3} is below trigger_relative_density {rd}")));
        }
    }
    if let Some(h) = trigger_h {
        let dbh: Vec<f32> = cand.iter().map(|&i| t.dbh[i]).collect();
        let height: Vec<f32> = cand.iter().map(|&i| t.height[i]).collect();
        let v = crate::sim::stats::top_height(&dbh, &height, a);
        if v < h {
            return (f, Some(format!("the area's top height {v:.2} m is below trigger_top_height_m {h}")));
        }
    }
    (f, None)
}

/// Why a thinning to `target` removes nothing from an area whose figure is `value`: at or below
/// the target already.
fn at_target(target: Target, value: f64) -> String {
    let (area, verb, goal) = figure(target, value);
    format!("{area} {verb} at or below {goal} already")
}

/// The area's figure `value` for a target's messages (`the area's basal area 12.34 m²/ha`), its
/// verb, and the target (`the target 15 m²/ha`).
fn figure(target: Target, value: f64) -> (String, &'static str, String) {
    let g = goal(target);
    match target {
        Target::BasalArea(_) => (format!("the area's basal area {value:.2} m²/ha"), "is", format!("the target {g} m²/ha")),
        Target::Stems(_) => (format!("the area's {value:.0} stems/ha"), "are", format!("the target {g} stems/ha")),
        Target::RelativeDensity(_) => (format!("the area's relative density {value:.3}"), "is", format!("the target {g}")),
    }
}

/// The value of a target.
fn goal(target: Target) -> f64 {
    match target {
        Target::BasalArea(v) | Target::Stems(v) | Target::RelativeDensity(v) => v,
    }
}

/// The cap of an entry's `max_removal_share` ([`crate::sim::management::Management::max_removal_share`]):
/// at most `share` of `ba0_m2`, the basal area (m²) the thinning measures its target on before
/// it starts (the area's main stand; for crop trees every stem of the area), is removed in one
/// entry. [`Cap::admits`] says whether tree `i` can still go.
struct Cap {
    limit_m2: Option<f64>,
    ba0_m2: f64,
    removed_m2: f64,
    hit: bool,
}

impl Cap {
    fn new(op: &Operation, ba0_m2: f64) -> Cap {
        Cap { limit_m2: op.spec.max_removal_share.map(|s| s * ba0_m2), ba0_m2, removed_m2: 0.0, hit: false }
    }
    /// Whether removing tree `i` keeps the removed basal area within the cap (and counts it
    /// when it does); once it does not, the entry stops there (`hit`).
    fn admits(&mut self, t: &TreeStore, i: usize) -> bool {
        let b = t.basal_area_m2(i);
        if self.limit_m2.is_some_and(|l| self.removed_m2 + b > l) {
            self.hit = true;
            return false;
        }
        self.removed_m2 += b;
        true
    }
    /// The note of a thinning the cap stopped short of its target (`figure`: the area's figure
    /// left and the target); `None` when it did not.
    fn note(&self, op: &Operation, figure: String) -> Option<String> {
        self.hit.then(|| format!("stopped at max_removal_share = {} ({:.3} of {:.3} m² basal area removed) short of its target: {figure}", op.spec.max_removal_share.unwrap_or(1.0), self.removed_m2, self.ba0_m2))
    }
}

/// The area's figure `v` against the target, for [`Cap::note`].
fn left_of(target: Target, v: f64) -> String {
    let (area, _, goal) = figure(target, v);
    format!("{area} against {goal}")
}

/// Share of the area's top height ([`crate::sim::stats::top_height`]) below which a stem is
/// not of the main stand a thinning works on: the IUFRO tree classes' lower layer (under a
/// third of top height; upper layer above two thirds, middle layer between: Leibundgut 1958,
/// as used by Assmann 1970 and Pretzsch 2009, *Forest Dynamics, Growth and Yield*, §2 and
/// §9.3). The lower layer of an old stand is the ingrowth of the next generation, which the
/// yield tables leave out of the main stand and which a thinning from below (grades A–C,
/// Kraft classes 5, 4, then 3 of the main stand; Assmann 1970) does not work on.
pub const MAIN_STAND_SHARE: f32 = 1.0 / 3.0;

/// The trees a thinning removes: none unless its triggers hold over its area; else stems of
/// the area's main stand: the growing stock (DBH ≥ [`crate::sim::density::MIN_DBH_CM`], 7 cm)
/// at least [`MAIN_STAND_SHARE`] of the area's top height tall, from the smallest DBH
/// (`from_below`) or the largest, ties by id, until the main stand's figure (basal area, stems
/// or relative density of its stems) is at or below the target. The triggers and the target are
/// measured on the main stand. Smaller trees (the understorey, the regeneration, the ingrowth
/// under a third of top height) are left, so a thinning from below never takes a dominant tree
/// while a smaller stem of the main stand stands, nor uses up its target on the understorey.
/// With the trees, why none is removed where none is (a trigger, the target held already, no
/// stems of the main stand in the area).
fn thinning(site: &Site, t: &TreeStore, op: &Operation, from_below: bool, target: Target, trigger_rd: Option<f64>, trigger_h: Option<f64>) -> (Vec<bool>, Option<String>, Option<String>) {
    let (remove, why) = thinning_by(site, t, op, from_below, target, trigger_rd, trigger_h);
    match why {
        Why::Nothing(w) => (remove, Some(w), None),
        Why::Done(w) => (remove, w, None),
        Why::Capped(c) => (remove, None, Some(c)),
    }
}

/// How a thinning ended: removing nothing (why), done (at its target, or why none was
/// removed), or stopped by its `max_removal_share` (the note).
enum Why {
    Nothing(String),
    Done(Option<String>),
    Capped(String),
}

/// [`thinning`]'s work.
fn thinning_by(site: &Site, t: &TreeStore, op: &Operation, from_below: bool, target: Target, trigger_rd: Option<f64>, trigger_h: Option<f64>) -> (Vec<bool>, Why) {
    let mut remove = vec![false; t.len()];
    let a = op.region.area_ha.max(1e-9);
    // a thinning acts on the growing stock, the stems of at least 7 cm DBH (as the yield tables
    // and the relative density count them); the understorey and the regeneration below stay
    // (taking the smallest stems first used to clear every stem under 7 cm at each entry before
    // the relative density, which does not count them, moved at all: found by a trial)
    let stock: Vec<usize> = stems_in(t, op).into_iter().filter(|&i| t.dbh[i] >= crate::sim::density::MIN_DBH_CM).collect();
    if stock.is_empty() {
        return (remove, Why::Nothing("no stems of 7 cm DBH or more in its area".into()));
    }
    // and on the main stand only: the ingrowth under a third of top height used up the target
    // of a thinning from below in old stands, which then took dominant trees (found by a trial)
    let dbh: Vec<f32> = stock.iter().map(|&i| t.dbh[i]).collect();
    let height: Vec<f32> = stock.iter().map(|&i| t.height[i]).collect();
    let low = MAIN_STAND_SHARE * crate::sim::stats::top_height(&dbh, &height, a) as f32;
    let mut cand: Vec<usize> = stock.into_iter().filter(|&i| t.height[i] >= low).collect();
    if cand.is_empty() {
        return (remove, Why::Nothing("no stems of the main stand (7 cm DBH or more, a third of top height or more) in its area".into()));
    }
    let (mut f, why) = figures_and_triggers(site, t, &cand, a, trigger_rd, trigger_h);
    if let Some(w) = why {
        return (remove, Why::Nothing(w));
    }
    let v0 = f.value(site, target, a);
    let goal = goal(target);
    let mut cap = Cap::new(op, f.ba_m2);
    cand.sort_by(|&i, &j| {
        let o = t.dbh[i].total_cmp(&t.dbh[j]);
        (if from_below { o } else { o.reverse() }).then(t.id[i].cmp(&t.id[j]))
    });
    for &i in &cand {
        if f.value(site, target, a) <= goal || !cap.admits(t, i) {
            break;
        }
        remove[i] = true;
        f.add(t, i, -1.0);
    }
    if let Some(c) = cap.note(op, left_of(target, f.value(site, target, a))) {
        return (remove, Why::Capped(c));
    }
    (remove, Why::Done((v0 <= goal).then(|| at_target(target, v0))))
}

/// Crop trees are chosen among the stems whose vigour (realised over potential growth, 0–1) is at
/// least this: a suppressed tree responds little to a release (crop trees are chosen for
/// vitality, quality and spacing; Abetz & Klädtke 2002).
pub const CROP_MIN_VIGOUR: f32 = 0.5;

/// A crop tree's competitors are the trees whose crowns touch its crown or come within this
/// distance (m) of it. In the model the crowns of a closed stand abut rather than overlap
/// (crowding narrows them: 0.8 m radii at 1.5 m spacing), so touching alone finds few; a
/// release frees the crop tree's crown on all sides (the Z-Baum release, Abetz & Klädtke
/// 2002). A model choice, not fitted.
pub const RELEASE_GAP_M: f64 = 1.0;

/// Trees `idx` of a store bucketed in square cells of `cell_m` (m) over `bbox`, for neighbour
/// searches.
struct Buckets {
    x0: f64,
    y0: f64,
    cell_m: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<usize>>,
}

impl Buckets {
    fn new(t: &TreeStore, idx: &[usize], bbox: [f64; 4], cell_m: f64) -> Buckets {
        let nx = (((bbox[2] - bbox[0]) / cell_m).ceil() as usize).max(1);
        let ny = (((bbox[3] - bbox[1]) / cell_m).ceil() as usize).max(1);
        let mut b = Buckets { x0: bbox[0], y0: bbox[1], cell_m, nx, ny, cells: vec![Vec::new(); nx * ny] };
        for &i in idx {
            let c = b.cell(t.x[i] as f64, t.y[i] as f64);
            b.cells[c.1 * nx + c.0].push(i);
        }
        b
    }
    fn cell(&self, x: f64, y: f64) -> (usize, usize) {
        let c = ((x - self.x0) / self.cell_m).floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let r = ((y - self.y0) / self.cell_m).floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (c, r)
    }
    /// The trees within `r` (m) of `(x, y)` (the point's own tree included), in bucket order
    /// (rows, columns, then insertion): deterministic.
    fn near(&self, t: &TreeStore, x: f64, y: f64, r: f64) -> Vec<usize> {
        let k = (r / self.cell_m).ceil() as usize;
        let (c, rr) = self.cell(x, y);
        let mut out = Vec::new();
        for row in rr.saturating_sub(k)..=(rr + k).min(self.ny - 1) {
            for col in c.saturating_sub(k)..=(c + k).min(self.nx - 1) {
                for &j in &self.cells[row * self.nx + col] {
                    if (t.x[j] as f64 - x).hypot(t.y[j] as f64 - y) <= r {
                        out.push(j);
                    }
                }
            }
        }
        out
    }
}

/// The crop trees of an area (store indices, in selection order): among its stems (≥ 1.3 m)
/// with a vigour of at least [`CROP_MIN_VIGOUR`], from the largest DBH (ties by id), each
/// taken when no crop tree taken before stands within `distance_m` (m), until
/// `round(n_ha · area)` are taken (fewer where the stand has too few candidates).
pub fn crop_trees(t: &TreeStore, op: &Operation, n_ha: f64, distance_m: f64) -> Vec<usize> {
    let mut cand: Vec<usize> = stems_in(t, op).into_iter().filter(|&i| t.vigour[i] >= CROP_MIN_VIGOUR).collect();
    cand.sort_by(|&i, &j| t.dbh[j].total_cmp(&t.dbh[i]).then(t.id[i].cmp(&t.id[j])));
    let want = (n_ha * op.region.area_ha).round() as usize;
    let mut chosen = Buckets::new(t, &[], op.region.bbox, distance_m.max(1.0));
    let mut out = Vec::new();
    for i in cand {
        if out.len() >= want {
            break;
        }
        let (x, y) = (t.x[i] as f64, t.y[i] as f64);
        if chosen.near(t, x, y, distance_m).is_empty() {
            let c = chosen.cell(x, y);
            chosen.cells[c.1 * chosen.nx + c.0].push(i);
            out.push(i);
        }
    }
    out
}

/// Hegyi's competition index term of tree `j` on tree `i`: `(DBH_j / DBH_i) / distance` (1/m;
/// distance at least 0.1 m); Hegyi 1974, *A simulation model for managing jack-pine stands*.
pub fn hegyi_term(t: &TreeStore, i: usize, j: usize) -> f64 {
    let d = (t.x[j] as f64 - t.x[i] as f64).hypot(t.y[j] as f64 - t.y[i] as f64).max(0.1);
    t.dbh[j] as f64 / (t.dbh[i] as f64).max(0.1) / d
}

/// The trees a crop-tree thinning removes (none unless its triggers hold): the crop trees of
/// the area ([`crop_trees`], chosen anew at each entry by the same rule; released crop trees,
/// the largest, are mostly chosen again) are kept; their competitors are the other stems of the
/// area whose crown touches a crop tree's or comes within [`RELEASE_GAP_M`] of it (distance
/// below the sum of the crown radii plus the gap) and that reach into it (at least as tall as
/// its crown base). Without a target every competitor goes. With one, each crop tree's
/// strongest competitor (its largest Hegyi term on that crop tree, [`hegyi_term`]; ties by id)
/// goes whatever the area's figure: the release itself (round 44, trial 43 defect 9: a
/// release with a target removed nothing in a young stand below it); in the Z-Baum method crop
/// trees are released of their main competitor(s) (Bedränger) at every entry, whatever the
/// stand's density (Abetz & Klädtke 2002, *Die Z-Baum-Kontrollmethode*, Forstw. Cbl. 121).
/// Then the other competitors go in order of their largest Hegyi term on a crop tree until the
/// area's figure is at or below the target (or none is left): the target bounds only what goes
/// beyond the release. `max_removal_share` caps both, the release first.
#[allow(clippy::too_many_arguments)]
fn crop_tree_thinning(site: &Site, t: &TreeStore, op: &Operation, n_ha: f64, distance_m: f64, target: Option<Target>, trigger_rd: Option<f64>, trigger_h: Option<f64>) -> (Vec<bool>, Option<String>, Option<String>) {
    let mut remove = vec![false; t.len()];
    let a = op.region.area_ha.max(1e-9);
    let cand = stems_in(t, op);
    let (mut f, why) = figures_and_triggers(site, t, &cand, a, trigger_rd, trigger_h);
    if why.is_some() {
        return (remove, why, None);
    }
    let mut cap = Cap::new(op, f.ba_m2);
    let crops = crop_trees(t, op, n_ha, distance_m);
    let mut is_crop = vec![false; t.len()];
    for &c in &crops {
        is_crop[c] = true;
    }
    let max_cr = cand.iter().map(|&i| t.crown_radius[i] as f64).fold(0.0, f64::max);
    let grid = Buckets::new(t, &cand, op.region.bbox, (2.0 * max_cr + RELEASE_GAP_M).max(2.0));
    // each competitor with its strongest Hegyi term on a crop tree
    let mut strength: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    // each crop tree's strongest competitor (Hegyi term, then the smaller id)
    let mut mains: Vec<(usize, f64)> = Vec::new();
    for &c in &crops {
        let mut best: Option<(usize, f64)> = None;
        for j in grid.near(t, t.x[c] as f64, t.y[c] as f64, t.crown_radius[c] as f64 + max_cr + RELEASE_GAP_M) {
            let d = (t.x[j] as f64 - t.x[c] as f64).hypot(t.y[j] as f64 - t.y[c] as f64);
            if is_crop[j] || d >= (t.crown_radius[c] + t.crown_radius[j]) as f64 + RELEASE_GAP_M || t.height[j] < t.crown_base[c] {
                continue;
            }
            let h = hegyi_term(t, c, j);
            let e = strength.entry(j).or_insert(0.0);
            *e = e.max(h);
            if best.is_none_or(|(b, hb)| h > hb || (h == hb && t.id[j] < t.id[b])) {
                best = Some((j, h));
            }
        }
        mains.extend(best);
    }
    let mut order: Vec<(usize, f64)> = strength.into_iter().collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1).then(t.id[a.0].cmp(&t.id[b.0])));
    // with a target, the release first: each crop tree's strongest competitor, whatever the
    // area's figure (in the order of their strength)
    if target.is_some() {
        let mut main: Vec<usize> = Vec::new();
        for &(j, _) in &mains {
            if !main.contains(&j) {
                main.push(j);
            }
        }
        let rank: std::collections::HashMap<usize, usize> = order.iter().enumerate().map(|(k, &(j, _))| (j, k)).collect();
        main.sort_by_key(|j| rank[j]);
        for j in main {
            if !cap.admits(t, j) {
                break;
            }
            remove[j] = true;
            f.add(t, j, -1.0);
        }
    }
    for (j, _) in order {
        if remove[j] {
            continue;
        }
        if let Some(tg) = target {
            if f.value(site, tg, a) <= goal(tg) {
                break;
            }
        }
        if cap.hit || !cap.admits(t, j) {
            break;
        }
        remove[j] = true;
        f.add(t, j, -1.0);
    }
    // (a release removes the crop trees' strongest competitors whatever the area's figure, so
    // an entry removes nothing only where they have none)
    let why = "its crop trees have no competitors to remove".to_string();
    let left = match target {
        Some(tg) => left_of(tg, f.value(site, tg, a)),
        None => "competitors of its crop trees are left".into(),
    };
    (remove, Some(why), cap.note(op, left))
}

/// The trees a shelterwood stage removes: of the area's overstorey (stems at least
/// [`SHELTER_OVERSTOREY`] of the area's top height tall; the regeneration below is left),
/// `share` of the basal area: with `share` 1 all of it, else the tree with the densest
/// neighbourhood first (the basal area of the overstorey within [`SHELTER_RADIUS_M`], its own
/// included; ties by the larger DBH, then id), the neighbours' figures updated after each, until
/// the removed basal area reaches the share. So the canopy is opened evenly and the
/// best-spaced trees are left as the shelter.
fn shelterwood(t: &TreeStore, op: &Operation, share: f64) -> Vec<bool> {
    let mut remove = vec![false; t.len()];
    let cand = stems_in(t, op);
    let dbh: Vec<f32> = cand.iter().map(|&i| t.dbh[i]).collect();
    let height: Vec<f32> = cand.iter().map(|&i| t.height[i]).collect();
    let h100 = crate::sim::stats::top_height(&dbh, &height, op.region.area_ha.max(1e-9)) as f32;
    let over: Vec<usize> = cand.into_iter().filter(|&i| t.height[i] >= SHELTER_OVERSTOREY * h100).collect();
    if share >= 1.0 {
        for &i in &over {
            remove[i] = true;
        }
        return remove;
    }
    let total: f64 = over.iter().map(|&i| t.basal_area_m2(i)).sum();
    let grid = Buckets::new(t, &over, op.region.bbox, SHELTER_RADIUS_M);
    let mut score = vec![0.0f64; t.len()];
    let mut heap = std::collections::BinaryHeap::new();
    let key = |s: f64| s.max(0.0).to_bits();
    for &i in &over {
        score[i] = grid.near(t, t.x[i] as f64, t.y[i] as f64, SHELTER_RADIUS_M).iter().map(|&j| t.basal_area_m2(j)).sum();
        heap.push((key(score[i]), t.dbh[i].to_bits(), std::cmp::Reverse(t.id[i]), i));
    }
    let mut removed = 0.0;
    while removed < share * total {
        let Some((s, _, _, i)) = heap.pop() else { break };
        if remove[i] || s != key(score[i]) {
            continue;
        }
        remove[i] = true;
        let b = t.basal_area_m2(i);
        removed += b;
        for j in grid.near(t, t.x[i] as f64, t.y[i] as f64, SHELTER_RADIUS_M) {
            if !remove[j] {
                score[j] -= b;
                heap.push((key(score[j]), t.dbh[j].to_bits(), std::cmp::Reverse(t.id[j]), j));
            }
        }
    }
    remove
}

/// The trees of a patch cut's `k`-th entry: the area's bounding box is cut into squares of
/// `size_m`; the squares whose centre lies in the area are put in an order drawn once per entry
/// (seed, entry); entry `k` cuts the next of them ([`crate::sim::management::patch_range`]:
/// about `share · n`, at least 1), so each entry opens new patches until all are cut, and
/// entries whose shares sum to 1 cut every square. Every tree of a cut square inside the area goes.
fn patches(seed: u64, t: &TreeStore, op: &Operation, size_m: f64, share: f64, k: u32) -> Vec<bool> {
    let b = op.region.bbox;
    let (nx, ny, squares) = patch_squares(&op.region, size_m);
    let mut eligible: Vec<(u64, usize)> = squares
        .into_iter()
        .map(|p| (mix64(seed ^ mix64(salt::MANAGEMENT ^ ((op.index as u64) << 40) ^ p as u64)), p))
        .collect();
    eligible.sort_unstable();
    let (lo, hi) = crate::sim::management::patch_range(eligible.len(), share, k);
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
