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
    p3: vec4<f32>,   // prototype, level, crown radius (m, 0 unknown), unused
};

struct Params {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,      // xyz eye; w = 1 orthographic
    lod: vec4<f32>,      // switch px 0, 1, 2; band
    misc: vec4<f32>,     // min px; pixels per metre at 1 m (perspective f) or per metre (ortho); 0; 0
    counts: vec4<u32>,   // instances, workgroups along x, number of prototypes, 0
};

// Per prototype: number of drawn levels, first slot index.
struct Proto {
    n_levels: u32,
    first_slot: u32,
    pad0: u32,
    pad1: u32,
};

@group(0) @binding(0) var<uniform> cp: Params;
@group(0) @binding(1) var<storage, read> src: array<Inst>;
// protos[p] for p < n_protos, then slot_base[s] (first compacted instance of slot s) after them
@group(0) @binding(2) var<storage, read> protos: array<Proto>;
@group(0) @binding(3) var<storage, read_write> dst: array<Inst>;
// 10 words per slot (two DrawIndexedIndirect records), then 4 per-level counters
@group(0) @binding(4) var<storage, read_write> args: array<atomic<u32>>;

struct Pick {
    level: i32,
    blend: f32,
};

fn select_lod(size_px: f32, n_levels: u32) -> Pick {
    var r: Pick;
    r.level = -1;
    r.blend = 0.0;
    if (n_levels == 0u || !(size_px >= cp.misc.x)) {
        return r;
    }
    let b = 1.0 + max(cp.lod.w, 0.0);
    for (var i = 0u; i < 3u; i = i + 1u) {
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
    r.level = i32(min(3u, n_levels - 1u));
    return r;
}

fn slot_base(slot: u32) -> u32 {
    let k = cp.counts.z + slot / 4u;
    let p = protos[k];
    let j = slot % 4u;
    if (j == 0u) { return p.n_levels; }
    if (j == 1u) { return p.first_slot; }
    if (j == 2u) { return p.pad0; }
    return p.pad1;
}

fn append(slot: u32, inst: Inst) {
    let k = atomicAdd(&args[slot * 10u + 1u], 1u);
    atomicAdd(&args[slot * 10u + 6u], 1u);
    dst[slot_base(slot) + k] = inst;
}

@compute @workgroup_size(64)
fn cull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let idx = gid.x + gid.y * cp.counts.y * 64u;
    if (idx >= cp.counts.x) {
        return;
    }
    var t = src[idx];
    let h = t.pos_h.w;
    let c = t.pos_h.xyz + vec3<f32>(0.0, 0.0, 0.5 * h);
    let r = max(0.5 * h, t.p3.z) * 1.1;
    for (var k = 0u; k < 6u; k = k + 1u) {
        let pl = cp.planes[k];
        if (dot(pl.xyz, c) + pl.w < -r) {
            return;
        }
    }
    var px: f32;
    if (cp.eye.w > 0.5) {
        px = h * cp.misc.y;
    } else {
        px = h * cp.misc.y / max(length(c - cp.eye.xyz), 1e-3);
    }
    let p = u32(t.p3.x + 0.5);
    let pr = protos[p];
    let pick = select_lod(px, pr.n_levels);
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
