//! CPU culling and level-of-detail pass: turns [`TreeInstance`]s into per-instance GPU records
//! grouped so that each (prototype, level) is one contiguous range, drawn with one instanced
//! call per material (bark, foliage).

use glam::Vec3;
use rayon::prelude::*;

use super::camera::Camera;
use crate::mesh::LOD_LEVELS;
use super::canopy::crown_albedo;
use super::lod::{budget_scale, canopy_threshold, canopy_weight, drawn_levels, lod_px, select_lod_scaled, size_bin, Frustum, LodParams, LodPick, BILLBOARD_TRIANGLES, SIZE_BINS};
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
    /// Factor applied to the switch sizes to meet the triangle budget (1 = none).
    pub lod_scale: f32,
    /// Far-field switch of the frame (px; 0 = canopy layer off), see
    /// [`super::lod::canopy_threshold`].
    pub canopy_px: f32,
    /// Crowns for the canopy layer, in instance order.
    pub canopy: Vec<CanopySplat>,
    /// Trees drawn only in the canopy layer (no geometry).
    pub canopy_only: usize,
    /// The reference height of the small trees' level bias the frame used
    /// ([`LodParams::small_tree_m`], lowered towards [`LodParams::small_tree_floor_m`] where
    /// the triangle budget binds; see [`super::lod::small_tree_ladder`]).
    pub small_tree_m: f32,
    /// Trees drawn at a finer level than with the bias of `small_tree_floor_m` (and the same
    /// switch factor): those the higher reference raised. None is drawn coarser.
    pub raised: usize,
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

/// The dither salt of the tree with id `id` (0, 1, …, 63; [`InstanceRaw::bark`]'s w): its
/// Bayer threshold in the shaders, and in the stills its threshold `(salt + ½) / 64` against a
/// cross-fade band's blend ([`drawn_pick`]).
pub fn dither_salt(id: u64) -> f32 {
    (hash01(id ^ 0xA5A5) * 64.0).floor()
}

/// The one level a tree with dither salt `salt` ([`dither_salt`]) draws of `pick` when each
/// tree in a cross-fade band draws one level whole ([`LodParams::one_level_per_tree`], the
/// stills' `Renderer::fade_per_tree`): `shaders/scene.wgsl` (`keep`) keeps the finer record
/// (fade side 0) where `d = (salt + ½) / 64 ≥ blend` and the coarser (side 1) where `d <
/// blend`, in `f32` as here. Returned with blend 0 (drawn whole); `pick` as it is outside a
/// band, or where the chain of `n_levels` levels has no coarser level.
pub fn drawn_pick(pick: LodPick, salt: f32, n_levels: usize) -> LodPick {
    if !(pick.blend > 0.0) || pick.level + 1 >= n_levels {
        return pick;
    }
    let d = (salt + 0.5) / 64.0;
    LodPick { level: if d < pick.blend { pick.level + 1 } else { pick.level }, blend: 0.0 }
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
        bark: [proto.bark_color[0], proto.bark_color[1], proto.bark_color[2], dither_salt(t.id)],
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
            Seen::Visible(camera.projected_size_px(c, t.height, height as f32))
        })
        .collect();
    // the budget is found with the small trees biased by the least reference height
    // (`LodParams::small_tree_floor_m`), then the reference raised as far as the budget allows
    // at that switch factor: biasing small trees never costs another tree its level (round 44)
    let ladder = super::lod::small_tree_ladder(params);
    let floor_params = LodParams { small_tree_m: *ladder.last().unwrap_or(&params.small_tree_m), ..*params };
    // histogram of projected sizes per prototype (trees of at least min_px), then the far-field
    // switch (tree cap) and the switch-size factor (triangle budget) of the geometry left
    let canopy_on = params.canopy_px > 0.0;
    let need_hist = params.max_triangles > 0 || (canopy_on && params.max_geometry_triangles > 0);
    let mut hist = vec![[0u32; SIZE_BINS]; levels.len()];
    if need_hist {
        for (t, v) in instances.iter().zip(&seen) {
            if let Seen::Visible(px) = *v {
                if px >= params.min_px {
                    hist[t.species as usize][size_bin(lod_px(px, t.height, &floor_params))] += 1;
                }
            }
        }
    }
    let costs: Vec<[u32; LOD_LEVELS]> = prototypes.iter().map(level_costs).collect();
    let canopy_px = canopy_threshold(&hist, &costs, &levels, &floor_params);
    let floor = if canopy_px > 0.0 { canopy_px / (1.0 + params.band.max(0.0)) } else { 0.0 };
    let mut scale = if params.max_triangles > 0 {
        budget_scale(&hist, &costs, &levels, &floor_params, floor)
    } else {
        1.0
    };
    let mut chosen = params.small_tree_m;
    // the histogram prices each tree at its bin's centre and undercounted the frames of small
    // dense sites (round 36: 6.1 M triangles drawn under a 2.4 M budget); the frame's exact
    // cost (every visible tree at its pick, with its cross-fade partner) is checked and the
    // factor raised step by step until it fits, so the budget holds on this path
    if params.max_triangles > 0 {
        let exact = |s: f32, pp: &LodParams| -> u64 {
            instances
                .par_iter()
                .zip(&seen)
                .map(|(t, v)| {
                    let Seen::Visible(px) = *v else { return 0 };
                    let p = t.species as usize;
                    if prototypes[p].rigid {
                        return level_triangles(&prototypes[p], 0);
                    }
                    if canopy_weight(px, canopy_px, params.band) >= 1.0 || !(px >= params.min_px) {
                        return 0;
                    }
                    let Some(mut pick) = select_lod_scaled(lod_px(px, t.height, pp), s, pp, levels[p]) else { return 0 };
                    if pp.one_level_per_tree {
                        pick = drawn_pick(pick, dither_salt(t.id), levels[p]);
                    }
                    let mut c = level_triangles(&prototypes[p], pick.level);
                    if pick.blend > 0.0 && pick.level + 1 < levels[p] {
                        c += level_triangles(&prototypes[p], pick.level + 1);
                    }
                    c
                })
                .sum()
        };
        let mut k = (4.0 * scale.log2()).round().max(0.0) as u32;
        while k < super::lod::MAX_SCALE_STEPS && exact(scale, &floor_params) > params.max_triangles as u64 {
            k += 1;
            scale = (k as f32 / 4.0).exp2();
        }
        // the histogram prices a band's tree at both its levels; drawn at one, the frame may
        // fit at a smaller factor: lowered step by step while its exact cost with the full
        // reference (`params.small_tree_m`, the ladder's first) fits, so the reference is
        // raised before the factor is lowered (round 45: lowered while the floor's fitted,
        // the finer factor took the room the reference needed) and no factor is larger than
        // the floor's alone would be. Where the full reference does not fit even at the
        // factor found, the factor is lowered while the floor reference's exact cost fits
        // (round 46): main's procedure priced as drawn, so the frame is as fine as the budget
        // allows (round 45 kept the histogram's ×1.68 for a small dense site's close-up under a
        // third of its cost, 0.91 M of a 1.90 M budget, and drew 47 of its 400 adapted trees as
        // crown hulls)
        if params.one_level_per_tree {
            let top = LodParams { small_tree_m: ladder[0], ..*params };
            let by = if exact(scale, &top) <= params.max_triangles as u64 { &top } else { &floor_params };
            while k > 0 && exact(((k - 1) as f32 / 4.0).exp2(), by) <= params.max_triangles as u64 {
                k -= 1;
                scale = (k as f32 / 4.0).exp2();
            }
        }
        chosen = floor_params.small_tree_m;
        // the higher references within the budget and within SMALL_TREE_MAX_EXTRA of the
        // floor's cost (raising trees a few pixels tall costs much and shows nothing)
        let cap = if ladder.len() > 1 {
            let base = exact(scale, &floor_params) as f64;
            let extra = super::lod::SMALL_TREE_MAX_EXTRA * base.max(0.2 * params.max_triangles as f64);
            (params.max_triangles as u64).min((base + extra) as u64)
        } else {
            0
        };
        for &m in &ladder[..ladder.len() - 1] {
            if exact(scale, &LodParams { small_tree_m: m, ..*params }) <= cap {
                chosen = m;
                break;
            }
        }
    }
    let params = &LodParams { small_tree_m: chosen, ..*params };
    let mut out = Batches { lod_scale: scale, canopy_px, small_tree_m: chosen, ..Batches::default() };
    let max_levels = levels.iter().copied().max().unwrap_or(0);
    out.per_level = vec![0; max_levels];
    // the record of a visible instance as drawn: its canopy-layer share taken out of its
    // opacity, its level picked; `None` when it goes wholly to the canopy layer or is too small
    let pick = |t: &TreeInstance, px: f32, canopy: Option<&mut Vec<CanopySplat>>| -> Option<(LodPick, InstanceRaw, bool)> {
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
        let n = levels[rec.p3[0] as usize];
        let p = select_lod_scaled(lod_px(px, t.height, params), scale, params, n)?;
        // stills: the one level the tree draws whole (LodParams::one_level_per_tree)
        Some((if params.one_level_per_tree { drawn_pick(p, rec.bark[3], n) } else { p }, rec, false))
    };
    // the canopy splats reserved to their number (a doubling growth held up to twice them:
    // most of the 2.3 M trees of a 640 × 360 timelapse frame of the default run; issue 34)
    if canopy_px > 0.0 {
        let n = seen.par_iter().filter(|v| matches!(v, Seen::Visible(px) if canopy_weight(*px, canopy_px, params.band) > 0.0)).count();
        out.canopy.reserve_exact(n);
    }
    // first pass: the canopy splats (in instance order), the statistics and the size of each
    // (prototype, level) range
    let mut counts: Vec<Vec<usize>> = levels.iter().map(|&n| vec![0; n]).collect();
    for (t, v) in instances.iter().zip(&seen) {
        let px = match *v {
            Seen::Invalid => {
                out.invalid += 1;
                continue;
            }
            Seen::Culled => {
                out.culled += 1;
                continue;
            }
            Seen::Visible(px) => px,
        };
        let Some((p, _, canopy_only)) = pick(t, px, Some(&mut out.canopy)) else {
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
        if chosen != floor_params.small_tree_m {
            let at_floor = select_lod_scaled(lod_px(px, t.height, &floor_params), scale, &floor_params, levels[s]).map(|f| if params.one_level_per_tree { drawn_pick(f, dither_salt(t.id), levels[s]) } else { f });
            if !prototypes[s].rigid && at_floor.is_some_and(|f| f.level > p.level) {
                out.raised += 1;
            }
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
        let Seen::Visible(px) = *v else { continue };
        let Some((pick, mut base, false)) = pick(t, px, None) else { continue };
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

/// What the first pass of [`build_batches_of`] found of an instance.
#[derive(Clone, Copy)]
enum Seen {
    /// Invalid data ([`record_prototype`]).
    Invalid,
    /// Outside the frustum.
    Culled,
    /// Visible, this many pixels tall on screen.
    Visible(f32),
}
