//! CPU culling and level-of-detail pass: turns [`TreeInstance`]s into per-instance GPU records
//! grouped so that each (prototype, level) is one contiguous range, drawn with one instanced
//! call per material (bark, foliage).

use glam::Vec3;
use rayon::prelude::*;

use super::camera::Camera;
use crate::mesh::LOD_LEVELS;
use super::canopy::crown_albedo;
use super::lod::{canopy_threshold, canopy_weight, drawn_levels, lod_px, select_lod_scaled, size_bin, Demotion, Frustum, LodParams, LodPick, BILLBOARD_TRIANGLES, MAX_SCALE_STEPS, SIZE_BINS};
use super::scene::{Prototype, Scene, TreeInstance};

/// Per-instance record read by the tree vertex shader (`shaders/scene.wgsl`, `TreeIn`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct InstanceRaw {
    /// Base x, y, z (m) and height (m).
    pub pos_h: [f32; 4],
    /// Horizontal scale (m per normalised unit), rotation (rad), fade threshold, fade side.
    pub p1: [f32; 4],
    /// Leaf colour (linear RGB), leaf amount 0..1.
    pub leaf: [f32; 4],
    /// Opacity 0..1, wind phases R_x, R_z (rad), flexibility 1 − k_f.
    pub p2: [f32; 4],
    /// Bark colour (linear RGB), dither salt.
    pub bark: [f32; 4],
    /// Prototype index, level drawn, crown radius for culling (m, 0 when unknown), crown
    /// radius drawn (m: horizontal scale × the prototype's normalised crown radius).
    pub p3: [f32; 4],
    /// Dissolve into the sky 0..1 ([`TreeInstance::sky_fade`]), crown base (fraction of the
    /// height, 0 = the prototype's own: [`TreeInstance::crown_base`]); unused ×2.
    pub p4: [f32; 4],
}

/// One crown for the canopy layer ([`super::canopy::CanopyGrid::splat`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CanopySplat {
    /// Plan position of the stem (m).
    pub x: f32,
    /// Plan position of the stem (m).
    pub y: f32,
    /// Crown radius (m).
    pub r: f32,
    /// Weight 0..1: canopy weight × opacity × foliage cover.
    pub w: f32,
    /// Crown albedo (linear RGB).
    pub rgb: [f32; 3],
}

/// One (prototype, level) range of [`Batches::instances`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DrawBatch {
    /// Prototype index.
    pub prototype: usize,
    /// Level of detail.
    pub level: usize,
    /// First instance in [`Batches::instances`].
    pub first: u32,
    /// Number of instances.
    pub count: u32,
}

/// Result of the culling/LOD pass.
#[derive(Debug, Clone, Default)]
pub struct Batches {
    /// Instance records, grouped by (prototype, level).
    pub instances: Vec<InstanceRaw>,
    /// Non-empty ranges, sorted by (prototype, level).
    pub draws: Vec<DrawBatch>,
    /// Triangles the tree draws submit (both materials, cross-fades counted twice).
    pub triangles: u64,
    /// Trees culled by the frustum or for being smaller than `min_px`.
    pub culled: usize,
    /// Trees skipped for invalid data (bad species index, non-positive or non-finite height).
    pub invalid: usize,
    /// Number of drawn instances per level (index = level).
    pub per_level: Vec<usize>,
    /// Factor applied to the switch sizes of the trees the triangle budget demotes (1 = none):
    /// [`Batches::demotion`]'s scale.
    pub lod_scale: f32,
    /// How the triangle budget demoted the frame's trees: the nearest kept their levels, those
    /// from [`Demotion::keep_within_m`] on took the factor [`Demotion::scale`]
    /// ([`demote_farthest`]); [`Demotion::NONE`] without a budget or when the frame fits.
    pub demotion: Demotion,
    /// Trees drawn at a coarser level than their size on screen asks for (the budget's
    /// demotion; a tree inside a cross-fade band counts by its finer level).
    pub demoted_trees: usize,
    /// Tree triangles the frame would draw without the budget (every visible tree at its own
    /// level, cross-fades counted twice, obstacles included); 0 without a budget.
    pub unbudgeted_triangles: u64,
    /// Far-field switch of the frame (px; 0 = canopy layer off), see
    /// [`super::lod::canopy_threshold`].
    pub canopy_px: f32,
    /// Crowns for the canopy layer, in instance order.
    pub canopy: Vec<CanopySplat>,
    /// Trees drawn only in the canopy layer (no geometry).
    pub canopy_only: usize,
}

use crate::rng::unit_f32 as hash01;

/// Bounding sphere (centre, radius) of an instance, in metres: centred at half height, radius
/// 1.1 × the larger of half the height and the crown radius. The GPU culling shader
/// (`shaders/cull.wgsl`) uses the same rule.
pub fn bounding_sphere(t: &TreeInstance) -> (Vec3, f32) {
    let c = Vec3::from(t.position) + Vec3::new(0.0, 0.0, 0.5 * t.height);
    (c, (0.5 * t.height).max(t.crown_radius) * 1.1)
}

/// Triangles of drawn level `level` of `proto` (see [`drawn_levels`]): the chain's mesh for the
/// first levels, [`BILLBOARD_TRIANGLES`] for the last.
pub fn level_triangles(proto: &Prototype, level: usize) -> u64 {
    let n = drawn_levels(proto.lods.levels.len());
    if level + 1 >= n {
        BILLBOARD_TRIANGLES as u64
    } else {
        proto.lods.level_triangles(level) as u64
    }
}

/// Triangles of each drawn level of `proto` (0 beyond its levels), saturated to `u32`.
pub fn level_costs(proto: &Prototype) -> [u32; LOD_LEVELS] {
    let mut c = [0u32; LOD_LEVELS];
    for (l, v) in c.iter_mut().enumerate().take(drawn_levels(proto.lods.levels.len())) {
        *v = level_triangles(proto, l).min(u32::MAX as u64) as u32;
    }
    c
}

/// The prototype of `t` when [`instance_record`] makes a record of it (`None`: invalid data, a
/// bad species index, a non-positive or non-finite height or position), without making it.
pub fn record_prototype(t: &TreeInstance, protos: &[Prototype], crown_r0: &[f32]) -> Option<usize> {
    let s = t.species as usize;
    if s >= protos.len() || s >= crown_r0.len() || !(t.height > 0.0) || !t.height.is_finite() || !t.position.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(s)
}

/// The GPU record of `t` before level selection (fade and level fields zero), or `None` for
/// invalid data (species index out of range, non-positive or non-finite height or position).
/// `crown_r0` is the prototype's [`Prototype::normalised_crown_radius`].
pub fn instance_record(t: &TreeInstance, protos: &[Prototype], crown_r0: &[f32]) -> Option<InstanceRaw> {
    let s = record_prototype(t, protos, crown_r0)?;
    let proto = &protos[s];
    let valid_r = t.crown_radius > 0.0 && t.crown_radius.is_finite();
    let sxy = if valid_r { t.crown_radius / crown_r0[s] } else { t.height };
    Some(InstanceRaw {
        pos_h: [t.position[0], t.position[1], t.position[2], t.height],
        p1: [sxy, t.rotation, 0.0, 0.0],
        leaf: [t.leaf_color[0], t.leaf_color[1], t.leaf_color[2], t.leaf_amount.clamp(0.0, 1.0)],
        p2: [t.opacity.clamp(0.0, 1.0), hash01(t.id) * std::f32::consts::TAU, hash01(t.id ^ 0x5DEE_CE66) * std::f32::consts::TAU, (1.0 - proto.stiffness).clamp(0.0, 1.0)],
        bark: [proto.bark_color[0], proto.bark_color[1], proto.bark_color[2], (hash01(t.id ^ 0xA5A5) * 64.0).floor()],
        p3: [s as f32, 0.0, if valid_r { t.crown_radius } else { 0.0 }, sxy * crown_r0[s]],
        p4: [t.sky_fade.clamp(0.0, 1.0), if t.crown_base > 0.0 { t.crown_base.clamp(0.05, 0.85) } else { 0.0 }, 0.0, 0.0],
    })
}

/// Culls and picks levels for every instance of `scene` seen by `camera` in a `width` ×
/// `height` pixel frame. Deterministic (instance order preserved within each range).
///
/// Levels are those of [`drawn_levels`]: the chain's meshes, then the billboard impostor.
/// Inside a cross-fade band the instance is recorded twice: at its level with fade side 0 and
/// at the next coarser level with fade side 1, both with the same fade threshold `blend`, so
/// that the shader's complementary Bayer masks split the pixels between them.
pub fn build_batches(scene: &Scene, camera: &Camera, width: u32, height: u32, params: &LodParams) -> Batches {
    build_batches_of(&scene.instances, &scene.prototypes, camera, width, height, params)
}

/// [`build_batches`] of `instances` drawn with `prototypes` (a scene's, or the near trees of a
/// [`super::farfield::FarField`]).
pub fn build_batches_of(instances: &[TreeInstance], prototypes: &[Prototype], camera: &Camera, width: u32, height: u32, params: &LodParams) -> Batches {
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    let frustum = Frustum::from_view_proj(camera.view_proj(aspect));
    let levels: Vec<usize> = prototypes.iter().map(|p| drawn_levels(p.lods.levels.len())).collect();
    let crown_r0: Vec<f32> = prototypes.iter().map(|p| p.normalised_crown_radius()).collect();
    // per instance: invalid, culled by the frustum, or its projected size (px); no record yet
    // (2.8 M records of the default run's mirrored year 150 were 330 MB twice over; issue 34)
    let seen: Vec<Seen> = instances
        .par_iter()
        .map(|t| {
            if record_prototype(t, prototypes, &crown_r0).is_none() {
                return Seen::Invalid;
            }
            let (c, r) = bounding_sphere(t);
            if !frustum.sphere_visible(c, r) {
                return Seen::Culled;
            }
            Seen::Visible(camera.projected_size_px(c, t.height, height as f32), eye_distance(camera, c))
        })
        .collect();
    // histogram of projected sizes per prototype (trees of at least min_px), then the far-field
    // switch (tree cap); the triangle budget is met with the exact costs below
    let canopy_on = params.canopy_px > 0.0;
    let need_hist = canopy_on && params.max_geometry_triangles > 0;
    let mut hist = vec![[0u32; SIZE_BINS]; levels.len()];
    if need_hist {
        for (t, v) in instances.iter().zip(&seen) {
            if let Seen::Visible(px, _) = *v {
                if px >= params.min_px {
                    hist[t.species as usize][size_bin(lod_px(px, t.height, params))] += 1;
                }
            }
        }
    }
    let costs: Vec<[u32; LOD_LEVELS]> = prototypes.iter().map(level_costs).collect();
    let canopy_px = canopy_threshold(&hist, &costs, &levels, params);
    // the histogram prices each tree at its bin's centre and undercounted the frames of small
    // dense sites (round 36: 6.1 M triangles drawn under a 2.4 M budget), and one factor on every
    // tree took the nearest trees off the full level too (round 36): the frame's exact cost
    // (every visible tree at its pick, with its cross-fade partner) decides, farthest trees
    // first ([`Demotion`])
    let (demotion, unbudgeted) = if params.max_triangles > 0 { demote_farthest(instances, prototypes, &seen, &levels, canopy_px, params) } else { (Demotion::NONE, 0) };
    let mut out = Batches { lod_scale: demotion.scale, demotion, unbudgeted_triangles: unbudgeted, canopy_px, ..Batches::default() };
    let max_levels = levels.iter().copied().max().unwrap_or(0);
    out.per_level = vec![0; max_levels];
    // the record of a visible instance as drawn: its canopy-layer share taken out of its
    // opacity, its level picked; `None` when it goes wholly to the canopy layer or is too small
    let pick = |t: &TreeInstance, px: f32, dist: f32, canopy: Option<&mut Vec<CanopySplat>>| -> Option<(LodPick, InstanceRaw, bool)> {
        let mut rec = instance_record(t, prototypes, &crown_r0)?;
        // an obstacle: its own mesh at any size (no billboard, no canopy splat)
        if prototypes[rec.p3[0] as usize].rigid {
            return Some((LodPick { level: 0, blend: 0.0 }, rec, false));
        }
        let wc = canopy_weight(px, canopy_px, params.band);
        if wc > 0.0 {
            if let Some(c) = canopy {
                let (rgb, cover) = crown_albedo([rec.leaf[0], rec.leaf[1], rec.leaf[2]], rec.leaf[3], [rec.bark[0], rec.bark[1], rec.bark[2]]);
                c.push(CanopySplat { x: rec.pos_h[0], y: rec.pos_h[1], r: rec.p3[3], w: wc * rec.p2[0] * cover, rgb });
            }
            if wc >= 1.0 {
                return Some((LodPick { level: 0, blend: 0.0 }, rec, true));
            }
            rec.p2[0] *= 1.0 - wc;
        }
        // the level by the size biased for small trees (LodParams::small_tree_m); the smallest
        // drawn and the canopy layer by the size itself
        if !(px >= params.min_px) {
            return None;
        }
        // the level at the frame's factor for this tree's distance (the budget's Demotion)
        select_lod_scaled(lod_px(px, t.height, params), demotion.scale_at(dist), params, levels[rec.p3[0] as usize]).map(|p| (p, rec, false))
    };
    // the canopy splats reserved to their number (a doubling growth held up to twice them:
    // most of the 2.3 M trees of a 640 × 360 timelapse frame of the default run; issue 34)
    if canopy_px > 0.0 {
        let n = seen.par_iter().filter(|v| matches!(v, Seen::Visible(px, _) if canopy_weight(*px, canopy_px, params.band) > 0.0)).count();
        out.canopy.reserve_exact(n);
    }
    // first pass: the canopy splats (in instance order), the statistics and the size of each
    // (prototype, level) range
    let mut counts: Vec<Vec<usize>> = levels.iter().map(|&n| vec![0; n]).collect();
    for (t, v) in instances.iter().zip(&seen) {
        let (px, dist) = match *v {
            Seen::Invalid => {
                out.invalid += 1;
                continue;
            }
            Seen::Culled => {
                out.culled += 1;
                continue;
            }
            Seen::Visible(px, d) => (px, d),
        };
        let Some((p, _, canopy_only)) = pick(t, px, dist, Some(&mut out.canopy)) else {
            out.culled += 1;
            continue;
        };
        if canopy_only {
            out.canopy_only += 1;
            out.culled += 1;
            continue;
        }
        let s = t.species as usize;
        counts[s][p.level] += 1;
        out.per_level[p.level] += 1;
        // drawn coarser than its size on screen asks for (the budget's demotion)
        if demotion.scale_at(dist) > 1.0 && !prototypes[s].rigid && select_lod_scaled(lod_px(px, t.height, params), 1.0, params, levels[s]).is_some_and(|n| n.level < p.level) {
            out.demoted_trees += 1;
        }
        if p.blend > 0.0 && p.level + 1 < levels[s] {
            counts[s][p.level + 1] += 1;
        }
    }
    out.culled = out.culled.saturating_sub(out.canopy_only);
    // the ranges in (prototype, level) order, then the records written into them in instance
    // order (the same records again: one list of exactly the drawn records, no buckets)
    let mut next: Vec<Vec<usize>> = counts.iter().map(|c| vec![0; c.len()]).collect();
    let mut total = 0usize;
    for (p, lv) in counts.iter().enumerate() {
        for (l, &n) in lv.iter().enumerate() {
            next[p][l] = total;
            if n == 0 {
                continue;
            }
            out.triangles += level_triangles(&prototypes[p], l) * n as u64;
            out.draws.push(DrawBatch { prototype: p, level: l, first: total as u32, count: n as u32 });
            total += n;
        }
    }
    out.instances = vec![<InstanceRaw as bytemuck::Zeroable>::zeroed(); total];
    for (t, v) in instances.iter().zip(&seen) {
        let Seen::Visible(px, dist) = *v else { continue };
        let Some((pick, mut base, false)) = pick(t, px, dist, None) else { continue };
        let s = t.species as usize;
        base.p1[2] = pick.blend;
        base.p3[1] = pick.level as f32;
        out.instances[next[s][pick.level]] = base;
        next[s][pick.level] += 1;
        if pick.blend > 0.0 && pick.level + 1 < levels[s] {
            let mut coarse = base;
            coarse.p1[3] = 1.0;
            coarse.p3[1] = (pick.level + 1) as f32;
            out.instances[next[s][pick.level + 1]] = coarse;
            next[s][pick.level + 1] += 1;
        }
    }
    out
}

/// Distance (m) from `camera`'s eye to `c` (a tree's bounding-sphere centre,
/// [`bounding_sphere`]): the order in which the triangle budget demotes trees, farthest first
/// ([`Demotion`]).
pub fn eye_distance(camera: &Camera, c: Vec3) -> f32 {
    (c - Vec3::from(camera.eye)).length()
}

/// Exact tree triangles of `t` (visible, `px` tall on screen) drawn with its switch sizes
/// multiplied by `s`: its level's, plus the next level's inside a cross-fade band; an obstacle
/// its own mesh at any size; 0 when it goes wholly to the canopy layer (far-field switch
/// `canopy_px`) or is under `params.min_px`. `levels`: drawn levels per prototype.
fn tree_cost(t: &TreeInstance, px: f32, s: f32, prototypes: &[Prototype], levels: &[usize], canopy_px: f32, params: &LodParams) -> u64 {
    let p = t.species as usize;
    if prototypes[p].rigid {
        return level_triangles(&prototypes[p], 0);
    }
    if canopy_weight(px, canopy_px, params.band) >= 1.0 || !(px >= params.min_px) {
        return 0;
    }
    let Some(pick) = select_lod_scaled(lod_px(px, t.height, params), s, params, levels[p]) else { return 0 };
    let mut c = level_triangles(&prototypes[p], pick.level);
    if pick.blend > 0.0 && pick.level + 1 < levels[p] {
        c += level_triangles(&prototypes[p], pick.level + 1);
    }
    c
}

/// The [`Demotion`] that keeps a frame within `params.max_triangles` (> 0), farthest trees
/// first, and the frame's exact tree triangles without it. `seen`: what culling found of each
/// of `instances`; `levels`: drawn levels per prototype; `canopy_px`: the frame's far-field
/// switch.
///
/// First the smallest factor `2^(k_all/4)` with which every tree fits (round 36's one factor,
/// bisection over k = 1..=`MAX_SCALE_STEPS`: the cost falls as the factor grows). Then, with
/// the trees sorted by [`eye_distance`] (ties: instance order), the nearest `K` keep their
/// levels for the largest `K` (cut only between distinct distances) for which their cost plus
/// the others' at the far factor `2^((k_all + 4)/4)` (one octave more, at most the coarsest)
/// fits (obstacles always cost their mesh); the others then take the smallest factor with
/// which the frame fits. Nothing demoted when the frame fits as it is; with `K` = 0 every tree
/// takes the one factor; when even the coarsest does not fit, every tree takes it (billboards
/// are the floor: the budget never hides trees).
/// Integer sums: deterministic for any thread count.
fn demote_farthest(instances: &[TreeInstance], prototypes: &[Prototype], seen: &[Seen], levels: &[usize], canopy_px: f32, params: &LodParams) -> (Demotion, u64) {
    let budget = params.max_triangles as u64;
    let cost = |i: u32, s: f32| -> u64 {
        let Seen::Visible(px, _) = seen[i as usize] else { return 0 };
        tree_cost(&instances[i as usize], px, s, prototypes, levels, canopy_px, params)
    };
    // the obstacles' meshes are a fixed cost; every other visible tree may be demoted
    let (mut fixed, mut order) = (0u64, Vec::new());
    for (i, (t, v)) in instances.iter().zip(seen).enumerate() {
        let Seen::Visible(_, d) = *v else { continue };
        if prototypes[t.species as usize].rigid {
            fixed += cost(i as u32, 1.0);
        } else {
            order.push((d, i as u32, 0u64));
        }
    }
    order.par_iter_mut().for_each(|o| o.2 = cost(o.1, 1.0));
    let unbudgeted = fixed + order.iter().map(|o| o.2).sum::<u64>();
    // (obstacles alone over the budget: nothing to demote)
    if unbudgeted <= budget || order.is_empty() {
        return (Demotion::NONE, unbudgeted);
    }
    order.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // the smallest step k in lo+1..=hi whose factor 2^(k/4) on the trees from `from` on fits
    // with the nearer ones at their levels (the cost falls as the factor grows; `hi` fits or
    // is the coarsest)
    let smallest_fit = |from: usize, lo: u32, hi: u32| -> u32 {
        let kept_cost = fixed + order[..from].iter().map(|o| o.2).sum::<u64>();
        let fits = |k: u32| kept_cost + order[from..].par_iter().map(|o| cost(o.1, (k as f32 / 4.0).exp2())).sum::<u64>() <= budget;
        let (mut lo, mut hi) = (lo, hi);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if fits(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    };
    // one factor for every tree (round 36's rule; factor 1 does not fit), then the far trees'
    // factor: one octave above it, so that the mid-ground drops one level more rather than to
    // billboards (round 37: with the far trees at the coarsest factor the default close-up's
    // mid-ground under a 5 M budget was billboards from 76 m on)
    let k_all = smallest_fit(0, 0, MAX_SCALE_STEPS);
    let k_far = (k_all + 4).min(MAX_SCALE_STEPS);
    let floor: Vec<u64> = order.par_iter().map(|o| cost(o.1, (k_far as f32 / 4.0).exp2())).collect();
    // the nearest trees kept while the rest at the far factor fit
    let mut acc = (fixed + floor.iter().sum::<u64>()) as i128;
    let mut kept = 0;
    if acc <= budget as i128 {
        for j in 0..order.len() {
            acc += order[j].2 as i128 - floor[j] as i128;
            if acc > budget as i128 {
                break;
            }
            if j + 1 == order.len() || order[j + 1].0 > order[j].0 {
                kept = j + 1;
            }
        }
    }
    // (kept < order.len(): all of them at their levels cost more than the budget); none kept:
    // one factor for all, as before
    let keep_within_m = order[kept].0;
    let hi = if kept == 0 { k_all } else { smallest_fit(kept, 0, k_far) };
    (Demotion { keep_within_m, scale: (hi as f32 / 4.0).exp2() }, unbudgeted)
}

/// What the first pass of [`build_batches_of`] found of an instance.
#[derive(Clone, Copy)]
enum Seen {
    /// Invalid data ([`record_prototype`]).
    Invalid,
    /// Outside the frustum.
    Culled,
    /// Visible, this many pixels tall on screen, this far (m) from the eye ([`eye_distance`]).
    Visible(f32, f32),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lod::placeholder_chain;

    /// Per tree (by its position's y, m): (level, fade side) of its primary record.
    fn levels_by_y(b: &Batches) -> std::collections::BTreeMap<i32, usize> {
        b.instances.iter().filter(|r| r.p1[3] == 0.0).map(|r| (r.pos_h[1].round() as i32, r.p3[1] as usize)).collect()
    }

    /// Issue 32, round 37: under a budget that forces demotion the nearest trees keep their
    /// levels and the demoted ones are the farthest. Sixty 20 m broadleaves (stand-in chain:
    /// full 20-segment crown, reduced, hull, billboard) in a row 10–187 m in front of the eye,
    /// 640 × 480, 60°: the nearest are drawn at the full level unconstrained. With a quarter of
    /// their triangles as the budget: at most the budget is drawn; every tree nearer than
    /// `keep_within_m` keeps its level, at least the nearest three (the full level); every
    /// demoted tree is farther than every kept one; one more kept tree would not fit with the
    /// others as drawn; the same in reverse instance order and on one thread.
    #[test]
    fn the_budget_demotes_the_farthest_trees_first() {
        let proto = Prototype { name: "stand-in".into(), lods: placeholder_chain(false), bark_color: [0.3; 3], leaf_color: [0.2, 0.5, 0.2], stiffness: 0.5, look: None, rigid: false };
        let protos = vec![proto];
        let inst: Vec<TreeInstance> = (0..60).map(|k| TreeInstance::new(k as u64 + 1, [if k % 2 == 0 { -2.0 } else { 2.0 }, 10.0 + 3.0 * k as f32, 0.0], 20.0, 5.0, 0, [0.2, 0.5, 0.2])).collect();
        let cam = Camera::look_at([0.0, 0.0, 10.0], [0.0, 100.0, 10.0], 60.0);
        let free_p = LodParams { max_triangles: 0, canopy_px: 0.0, max_geometry_triangles: 0, ..LodParams::default() };
        let free = build_batches_of(&inst, &protos, &cam, 640, 480, &free_p);
        let free_lv = levels_by_y(&free);
        assert_eq!(free_lv.len(), 60);
        assert!(free_lv.values().take(3).all(|&l| l == 0), "{free_lv:?}");
        assert_eq!(free.demotion, Demotion::NONE);
        let budget = (free.triangles / 4) as u32;
        let p = LodParams { max_triangles: budget, ..free_p };
        let b = build_batches_of(&inst, &protos, &cam, 640, 480, &p);
        let lv = levels_by_y(&b);
        eprintln!("free {} triangles {:?}; budget {budget}: {} triangles {:?}, {:?}, {} demoted", free.triangles, free.per_level, b.triangles, b.per_level, b.demotion, b.demoted_trees);
        assert!(b.triangles <= budget as u64 && b.demotion.demotes(), "{} triangles, {:?}", b.triangles, b.demotion);
        assert_eq!(b.unbudgeted_triangles, free.triangles);
        assert_eq!(lv.len(), 60, "the budget hides no tree");
        let dist = |y: i32| eye_distance(&cam, Vec3::new(2.0, y as f32, 10.0));
        let kept: Vec<i32> = lv.keys().copied().filter(|&y| dist(y) < b.demotion.keep_within_m).collect();
        let demoted: Vec<i32> = lv.iter().filter(|(y, l)| **l > free_lv[y]).map(|(y, _)| *y).collect();
        assert!(kept.len() >= 3, "kept {kept:?}");
        assert!(kept.iter().all(|y| lv[y] == free_lv[y]), "the nearest keep their levels: {lv:?} vs {free_lv:?}");
        assert!(!demoted.is_empty() && demoted.iter().all(|d| kept.iter().all(|k| d > k)), "demoted {demoted:?}, kept {kept:?}");
        assert_eq!(b.demoted_trees, demoted.len());
        // the cut is the largest: the first tree beyond it at its own level instead of its
        // demoted one (the farther ones as drawn) costs more than the budget
        let cost_in = |bt: &Batches, y: i32| bt.instances.iter().filter(|r| r.pos_h[1].round() as i32 == y).map(|r| level_triangles(&protos[0], r.p3[1] as usize)).sum::<u64>();
        let first = *lv.keys().nth(kept.len()).unwrap();
        let more = b.triangles - cost_in(&b, first) + cost_in(&free, first);
        assert!(more > budget as u64, "{more} ≤ {budget}: one more tree could have kept its level");
        // deterministic: whatever the instance order or the threads
        let rev: Vec<TreeInstance> = inst.iter().rev().copied().collect();
        let br = build_batches_of(&rev, &protos, &cam, 640, 480, &p);
        assert_eq!((levels_by_y(&br), br.triangles, br.demotion), (lv.clone(), b.triangles, b.demotion));
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| build_batches_of(&inst, &protos, &cam, 640, 480, &p));
        assert_eq!((levels_by_y(&one), one.triangles, one.demotion), (lv, b.triangles, b.demotion));
    }
}
