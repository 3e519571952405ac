// Sylva GPU culling and level-of-detail selection (issue 6): one invocation per tree instance.
// Same rules as the CPU path (render/instanced.rs build_batches, render/lod.rs select_lod):
// bounding sphere at half height with radius 1.1 * max(h/2, crown radius), frustum test against
// six normalised planes (Gribb & Hartmann 2001), projected height in pixels, level by the switch
// sizes with a log-linear cross-fade band. Visible instances are appended (atomics) to the
// compacted range of their (prototype, level) slot, and the instance counts of that slot's two
// DrawIndexedIndirect records (bark, leaves) are incremented; a tree in a cross-fade band is also
// appended to the next coarser level with the complementary fade side.

struct Inst {
    pos_h: vec4<f32>,
    p1: vec4<f32>,
    leaf: vec4<f32>,
    p2: vec4<f32>,
    bark: vec4<f32>,
    p3: vec4<f32>,   // prototype, level, crown radius (m, 0 unknown), crown radius drawn (m)
    p4: vec4<f32>,   // sky fade 0..1, crown base (fraction of the height, 0 = prototype's), unused x2
};

struct Params {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,      // xyz eye; w = 1 orthographic
    lod: vec4<f32>,      // switch px 0, 1, 2; band
    misc: vec4<f32>,     // min px; pixels per metre at 1 m (perspective f) or per metre (ortho);
                         // triangle budget (0 = none); index of the first cost record in protos
    counts: vec4<u32>,   // instances, workgroups along x, number of prototypes, word offset of
                         // the per-level counters in args (= 10 * slots)
    canopy: vec4<f32>,   // canopy grid origin x, y (m), texel (m); base far-field switch px (0 off)
    canopy_n: vec4<u32>, // canopy grid nx, ny; geometry triangle budget of the far switch (0 none);
                         // bits of the small-tree height of the level choice (f32 m, 0 off)
};

// Per prototype: number of drawn levels, first slot index, 1 for a rigid prototype (an
// obstacle: drawn at level 0 whatever its size, never splatted; Prototype::rigid).
struct Proto {
    n_levels: u32,
    first_slot: u32,
    rigid: u32,
    pad1: u32,
};

@group(0) @binding(0) var<uniform> cp: Params;
@group(0) @binding(1) var<storage, read> src: array<Inst>;
// protos[p] for p < n_protos, then slot_base[s] (first compacted instance of slot s) packed 4 per
// record, then from record misc.w one record per prototype with the triangles of levels 0..3
@group(0) @binding(2) var<storage, read> protos: array<Proto>;
@group(0) @binding(3) var<storage, read_write> dst: array<Inst>;
// 10 words per slot (two DrawIndexedIndirect records), then 4 per-level counters, then the size
// histogram (64 bins per prototype), then the switch-size factor (f32 bits) chosen for the budget
@group(0) @binding(4) var<storage, read_write> args: array<atomic<u32>>;
// canopy layer sums (render/canopy.rs): per texel coverage, r, g, b in units of 1/1024
@group(0) @binding(5) var<storage, read_write> canopy: array<atomic<u32>>;

// Levels of detail drawn per prototype: crate::mesh::LOD_LEVELS (checked by a test in render/lod.rs).
const LOD_LEVELS: u32 = 4u;
const SMALL_TREE_MAX_BIAS: f32 = 3.0; // render/lod.rs SMALL_TREE_MAX_BIAS

struct Pick {
    level: i32,
    blend: f32,
};

// select_lod of render/lod.rs without the minimum-size test (done on the unscaled size)
fn select_lod(size_px: f32, n_levels: u32) -> Pick {
    var r: Pick;
    r.level = -1;
    r.blend = 0.0;
    if (n_levels == 0u) {
        return r;
    }
    let b = 1.0 + max(cp.lod.w, 0.0);
    for (var i = 0u; i < LOD_LEVELS - 1u; i = i + 1u) {
        r.level = i32(i);
        if (i + 1u >= n_levels) {
            return r;
        }
        let s = cp.lod[i];
        let hi = s * b;
        let lo = s / b;
        if (size_px >= hi) {
            return r;
        }
        if (size_px > lo) {
            let f = (log(hi) - log(size_px)) / (log(hi) - log(lo));
            r.blend = clamp(f, 0.0, 1.0);
            return r;
        }
    }
    r.level = i32(min(LOD_LEVELS - 1u, n_levels - 1u));
    return r;
}

fn slot_base(slot: u32) -> u32 {
    let k = cp.counts.z + slot / 4u;
    let p = protos[k];
    let j = slot % 4u;
    if (j == 0u) { return p.n_levels; }
    if (j == 1u) { return p.first_slot; }
    if (j == 2u) { return p.rigid; }
    return p.pad1;
}

fn append(slot: u32, inst: Inst) {
    let k = atomicAdd(&args[slot * 10u + 1u], 1u);
    atomicAdd(&args[slot * 10u + 6u], 1u);
    dst[slot_base(slot) + k] = inst;
}

fn hist_off() -> u32 {
    return cp.counts.w + LOD_LEVELS;
}

fn scale_word() -> u32 {
    return hist_off() + cp.counts.z * 64u;
}

// canopy_weight of render/lod.rs
fn canopy_weight(px: f32, c: f32) -> f32 {
    if (!(c > 0.0)) {
        return 0.0;
    }
    let b = 1.0 + max(cp.lod.w, 0.0);
    let hi = c * b;
    let lo = c / b;
    if (px <= lo) {
        return 1.0;
    }
    if (px >= hi) {
        return 0.0;
    }
    return clamp((log(hi) - log(px)) / (log(hi) - log(lo)), 0.0, 1.0);
}

// crown_albedo of render/canopy.rs: (albedo, cover)
fn crown_albedo(t: Inst) -> vec4<f32> {
    let la = clamp(t.leaf.w, 0.0, 1.0);
    let tw = 0.5 * (1.0 - la);
    let cover = la + tw;
    let tc = t.bark.rgb + (vec3<f32>(0.16, 0.14, 0.12) - t.bark.rgb) * 0.6;
    return vec4<f32>((la * t.leaf.rgb + tw * tc) / max(cover, 1e-6), cover);
}

// CanopyGrid::splat of render/canopy.rs
fn splat(x: f32, y: f32, r: f32, w: f32, rgb: vec3<f32>) {
    if (!(w > 0.0 && r > 0.0)) {
        return;
    }
    let t = cp.canopy.z;
    let u = (x - cp.canopy.x) / t;
    let v = (y - cp.canopy.y) / t;
    let ci = i32(floor(u));
    let cj = i32(floor(v));
    let rt = r / t;
    let half = clamp(i32(ceil(rt)), 1, 4);
    var total = 0.0;
    for (var dj = -half; dj <= half; dj = dj + 1) {
        for (var di = -half; di <= half; di = di + 1) {
            let du = f32(ci + di) + 0.5 - u;
            let dv = f32(cj + dj) + 0.5 - v;
            total = total + clamp(rt - sqrt(du * du + dv * dv) + 0.5, 0.0, 1.0);
        }
    }
    if (!(total > 0.0)) {
        return;
    }
    let k = 3.14159265 * rt * rt / total * w * 1024.0;
    let c3 = clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    for (var dj = -half; dj <= half; dj = dj + 1) {
        for (var di = -half; di <= half; di = di + 1) {
            let i = ci + di;
            let j = cj + dj;
            if (i < 0 || j < 0 || i >= i32(cp.canopy_n.x) || j >= i32(cp.canopy_n.y)) {
                continue;
            }
            let du = f32(i) + 0.5 - u;
            let dv = f32(j) + 0.5 - v;
            let c = clamp(rt - sqrt(du * du + dv * dv) + 0.5, 0.0, 1.0) * k;
            if (!(c > 0.0)) {
                continue;
            }
            let o = (u32(j) * cp.canopy_n.x + u32(i)) * 4u;
            atomicAdd(&canopy[o], u32(round(c)));
            atomicAdd(&canopy[o + 1u], u32(round(c * c3.x)));
            atomicAdd(&canopy[o + 2u], u32(round(c * c3.y)));
            atomicAdd(&canopy[o + 3u], u32(round(c * c3.z)));
        }
    }
}

// Frustum test and projected size (px); negative when culled.
fn visible_px(t: Inst) -> f32 {
    let h = t.pos_h.w;
    let c = t.pos_h.xyz + vec3<f32>(0.0, 0.0, 0.5 * h);
    let r = max(0.5 * h, t.p3.z) * 1.1;
    for (var k = 0u; k < 6u; k = k + 1u) {
        let pl = cp.planes[k];
        if (dot(pl.xyz, c) + pl.w < -r) {
            return -1.0;
        }
    }
    if (cp.eye.w > 0.5) {
        return h * cp.misc.y;
    }
    return h * cp.misc.y / max(length(c - cp.eye.xyz), 1e-3);
}

// lod_px of render/lod.rs: a small tree picks its level as if larger on screen
fn lod_px(px: f32, h: f32) -> f32 {
    let m = bitcast<f32>(cp.canopy_n.w);
    if (m > 0.0 && h < m) {
        return px * min(m / max(h, 1e-3), SMALL_TREE_MAX_BIAS);
    }
    return px;
}

// size_bin of render/lod.rs
fn size_bin(px: f32) -> u32 {
    return u32(clamp(i32(floor(log2(px) * 4.0)) + 4, 0, 63));
}

// Pass 1 (only with a budget): histogram of projected sizes per prototype.
@compute @workgroup_size(64)
fn hist(@builtin(global_invocation_id) gid: vec3<u32>) {
    let idx = gid.x + gid.y * cp.counts.y * 64u;
    if (idx >= cp.counts.x) {
        return;
    }
    let t = src[idx];
    let px = visible_px(t);
    if (!(px >= cp.misc.x)) {
        return;
    }
    let p = u32(t.p3.x + 0.5);
    atomicAdd(&args[hist_off() + p * 64u + size_bin(lod_px(px, t.pos_h.w))], 1u);
}

fn cost(p: u32, l: u32) -> u32 {
    let c = protos[u32(cp.misc.w + 0.5) + p];
    let j = min(l, LOD_LEVELS - 1u);
    if (j == 0u) { return c.n_levels; }
    if (j == 1u) { return c.first_slot; }
    if (j == 2u) { return c.rigid; }
    return c.pad1;
}

// hist_cost of render/lod.rs: estimated triangles of the histogram's bins from floor_px up,
// switch sizes scaled by s
fn hist_cost(s: f32, floor_px: f32) -> f32 {
    var total = 0.0;
    for (var p = 0u; p < cp.counts.z; p = p + 1u) {
        let nl = protos[p].n_levels;
        for (var bb = 0u; bb < 64u; bb = bb + 1u) {
            let n = atomicLoad(&args[hist_off() + p * 64u + bb]);
            let px = exp2((f32(bb) - 4.0 + 0.5) / 4.0);
            if (n == 0u || px < floor_px) {
                continue;
            }
            let pick = select_lod(px / s, nl);
            if (pick.level < 0) {
                continue;
            }
            let lv = u32(pick.level);
            var c = cost(p, lv);
            if (pick.blend > 0.0 && lv + 1u < nl) {
                c = c + cost(p, lv + 1u);
            }
            total = total + f32(n) * f32(c);
        }
    }
    return total;
}

// Pass 2 (one invocation): canopy_threshold, then budget_scale of render/lod.rs.
@compute @workgroup_size(1)
fn choose() {
    let b = 1.0 + max(cp.lod.w, 0.0);
    var cthr = 0.0;
    if (cp.canopy.w > 0.0) {
        cthr = cp.canopy.w;
        if (cp.canopy_n.z > 0u) {
            for (var k = 0u; k <= 40u; k = k + 1u) {
                cthr = cp.canopy.w * exp2(f32(k) / 4.0);
                if (hist_cost(1.0, cthr / b) <= f32(cp.canopy_n.z)) {
                    break;
                }
            }
        }
    }
    var floor_px = 0.0;
    if (cthr > 0.0) {
        floor_px = cthr / b;
    }
    atomicStore(&args[scale_word() + 1u], bitcast<u32>(cthr));
    var s = 1.0;
    if (cp.misc.z > 0.0) {
        for (var k = 0u; k <= 40u; k = k + 1u) {
            s = exp2(f32(k) / 4.0);
            if (hist_cost(s, floor_px) <= cp.misc.z) {
                break;
            }
        }
    }
    atomicStore(&args[scale_word()], bitcast<u32>(s));
}

// Pass 3: culling, level selection with the chosen factor, compaction.
@compute @workgroup_size(64)
fn cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let idx = gid.x + gid.y * cp.counts.y * 64u;
    if (idx >= cp.counts.x) {
        return;
    }
    var t = src[idx];
    let px = visible_px(t);
    if (!(px >= 0.0)) {
        return;
    }
    let pr0 = protos[u32(t.p3.x + 0.5)];
    if (pr0.rigid == 1u) {
        atomicAdd(&args[cp.counts.w], 1u);
        t.p1.z = 0.0;
        t.p1.w = 0.0;
        t.p3.y = 0.0;
        append(pr0.first_slot, t);
        return;
    }
    let wc = canopy_weight(px, bitcast<f32>(atomicLoad(&args[scale_word() + 1u])));
    if (wc > 0.0) {
        let ca = crown_albedo(t);
        splat(t.pos_h.x, t.pos_h.y, t.p3.w, wc * t.p2.x * ca.w, ca.xyz);
        if (wc >= 1.0) {
            atomicAdd(&args[scale_word() + 2u], 1u);
            return;
        }
        t.p2.x = t.p2.x * (1.0 - wc);
    }
    if (!(px >= cp.misc.x)) {
        return;
    }
    let scale = bitcast<f32>(atomicLoad(&args[scale_word()]));
    let p = u32(t.p3.x + 0.5);
    let pr = protos[p];
    let pick = select_lod(lod_px(px, t.pos_h.w) / scale, pr.n_levels);
    if (pick.level < 0) {
        return;
    }
    let lv = u32(pick.level);
    atomicAdd(&args[cp.counts.w + lv], 1u);
    t.p1.z = pick.blend;
    t.p1.w = 0.0;
    t.p3.y = f32(lv);
    append(pr.first_slot + lv, t);
    if (pick.blend > 0.0 && lv + 1u < pr.n_levels) {
        t.p1.w = 1.0;
        t.p3.y = f32(lv + 1u);
        append(pr.first_slot + lv + 1u, t);
    }
}
