// Sylva scene shader: sky gradient, terrain, water, instanced trees with LOD cross-fade,
// EcoMod wind sway (004_*.txt, Algorithm 1), seasonal colour, sun shadow map, aerial fog.

struct Globals {
    view_proj: mat4x4<f32>,
    light_view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    eye: vec4<f32>,          // xyz eye, w = 1 for orthographic
    sun_dir: vec4<f32>,      // xyz towards the sun
    sun_color: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    wind: vec4<f32>,         // direction x, y; directed w_g; undirected w_s
    params: vec4<f32>,       // time s, sea level m, shadow texel size, fog density 1/m
};

@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var shadow_map: texture_depth_2d;
@group(0) @binding(2) var shadow_sampler: sampler_comparison;

fn shadow_factor(world: vec3<f32>, n: vec3<f32>) -> f32 {
    let p = g.light_view_proj * vec4<f32>(world + n * 0.05, 1.0);
    let ndc = p.xyz / p.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, -ndc.y * 0.5 + 0.5);
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0 || ndc.z > 1.0) {
        return 1.0;
    }
    let t = g.params.z;
    var s = 0.0;
    for (var i = -1; i <= 1; i = i + 1) {
        for (var j = -1; j <= 1; j = j + 1) {
            s = s + textureSampleCompareLevel(shadow_map, shadow_sampler, uv + vec2<f32>(f32(i), f32(j)) * t, ndc.z - 0.0015);
        }
    }
    return s / 9.0;
}

fn sky_color(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.z, -1.0, 1.0);
    var c = mix(g.sky_horizon.rgb, g.sky_zenith.rgb, pow(max(up, 0.0), 0.6));
    if (up < 0.0) {
        c = g.sky_horizon.rgb * (1.0 + up * 0.4);
    }
    let sd = max(dot(dir, g.sun_dir.xyz), 0.0);
    c = c + g.sun_color.rgb * (pow(sd, 800.0) * 4.0 + pow(sd, 12.0) * 0.15);
    return c;
}

fn fog(c: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    var d = length(world - g.eye.xyz);
    if (g.eye.w > 0.5) {
        d = 0.0;
    }
    let f = 1.0 - exp(-d * g.params.w);
    return mix(c, g.sky_horizon.rgb, clamp(f, 0.0, 0.85));
}

fn shade(albedo: vec3<f32>, n: vec3<f32>, world: vec3<f32>, wrap: f32, ao: f32) -> vec3<f32> {
    let l = g.sun_dir.xyz;
    let ndl = max((dot(n, l) + wrap) / (1.0 + wrap), 0.0);
    let sh = shadow_factor(world, n);
    let amb_col = mix(vec3<f32>(0.55, 0.55, 0.5), mix(g.sky_horizon.rgb, g.sky_zenith.rgb, 0.5), 0.5);
    let sky_amb = amb_col * (0.25 + 0.17 * n.z);
    let lit = g.sun_color.rgb * ndl * sh + sky_amb * ao;
    return albedo * lit;
}

// ---------------------------------------------------------------- sky
struct SkyOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_sky(@builtin(vertex_index) vi: u32) -> SkyOut {
    let x = f32((vi << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vi & 2u) * 2.0 - 1.0;
    var o: SkyOut;
    o.pos = vec4<f32>(x, y, 1.0, 1.0);
    o.ndc = vec2<f32>(x, y);
    return o;
}

@fragment
fn fs_sky(i: SkyOut) -> @location(0) vec4<f32> {
    let a = g.inv_view_proj * vec4<f32>(i.ndc, 0.0, 1.0);
    let b = g.inv_view_proj * vec4<f32>(i.ndc, 1.0, 1.0);
    let dir = normalize(b.xyz / b.w - a.xyz / a.w);
    return vec4<f32>(sky_color(dir), 1.0);
}

// ---------------------------------------------------------------- terrain and water
struct TerrainIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
};

struct TerrainOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
};

@vertex
fn vs_terrain(v: TerrainIn) -> TerrainOut {
    var o: TerrainOut;
    o.clip = g.view_proj * vec4<f32>(v.pos, 1.0);
    o.world = v.pos;
    o.normal = v.normal;
    o.color = v.color;
    return o;
}

@fragment
fn fs_terrain(i: TerrainOut) -> @location(0) vec4<f32> {
    let n = normalize(i.normal);
    let c = shade(i.color, n, i.world, 0.0, 1.0);
    return vec4<f32>(fog(c, i.world), 1.0);
}

@fragment
fn fs_water(i: TerrainOut) -> @location(0) vec4<f32> {
    let v = normalize(g.eye.xyz - i.world);
    let fres = pow(1.0 - max(v.z, 0.0), 4.0);
    let refl = sky_color(reflect(-v, vec3<f32>(0.0, 0.0, 1.0)));
    let base = vec3<f32>(0.02, 0.08, 0.12) * (0.5 + 0.5 * shadow_factor(i.world, vec3<f32>(0.0, 0.0, 1.0)));
    let c = mix(base, refl, 0.15 + 0.75 * fres);
    return vec4<f32>(fog(c, i.world), 0.8);
}

// ---------------------------------------------------------------- trees
struct TreeIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) mat: f32,          // 0 bark, 1 leaf
    @location(3) pos_h: vec4<f32>,  // base x y z, height m
    @location(4) p1: vec4<f32>,     // horizontal scale, rotation rad, fade threshold, fade side
    @location(5) leaf: vec4<f32>,   // leaf rgb, leaf amount
    @location(6) p2: vec4<f32>,     // opacity, phase R_x, phase R_z, flexibility (1 - k_f)
    @location(7) bark: vec4<f32>,   // bark rgb, dither salt
};

struct TreeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) @interpolate(flat) fade: vec4<f32>,  // threshold, side, opacity, leaf amount
    @location(4) mat_s: vec2<f32>,                      // material, normalised height
    @location(5) @interpolate(flat) salt: f32,
};

// World position of a tree vertex with EcoMod wind (Algorithm 1): directed bend
// alpha_w = k_w * w_g * s^2 towards the wind, undirected sway alpha_x(t) = sin(w t + R_x) w_s (1-k_f) l0,
// alpha_z(t) = sin(w t + R_z) w_s (1-k_f) l0 with l0 = s^2, small-angle displacement = angle * height.
fn tree_world(v: TreeIn) -> vec3<f32> {
    let h = v.pos_h.w;
    let sxy = v.p1.x;
    let c = cos(v.p1.y);
    let s = sin(v.p1.y);
    let lp = vec3<f32>(v.pos.x * sxy, v.pos.y * sxy, v.pos.z * h);
    let rp = vec3<f32>(c * lp.x - s * lp.y, s * lp.x + c * lp.y, lp.z);
    let sn = clamp(v.pos.z, 0.0, 1.2);
    let l0 = sn * sn;
    let t = g.params.x;
    let k_w = 0.02;
    let a_w = k_w * g.wind.z * l0;
    let a_x = sin(1.7 * t + v.p2.y) * g.wind.w * v.p2.w * l0 * k_w;
    let a_z = sin(1.3 * t + v.p2.z) * g.wind.w * v.p2.w * l0 * k_w;
    let disp = (g.wind.xy * a_w + vec2<f32>(a_x, a_z)) * lp.z;
    let dz = -0.5 * dot(disp, disp) / max(lp.z, 0.01);
    return v.pos_h.xyz + rp + vec3<f32>(disp, dz);
}

fn tree_vertex(v: TreeIn) -> TreeOut {
    var o: TreeOut;
    let w = tree_world(v);
    o.clip = g.view_proj * vec4<f32>(w, 1.0);
    o.world = w;
    let c = cos(v.p1.y);
    let s = sin(v.p1.y);
    let ln = vec3<f32>(v.normal.x / max(v.p1.x, 1e-4), v.normal.y / max(v.p1.x, 1e-4), v.normal.z / max(v.pos_h.w, 1e-4));
    let rn = vec3<f32>(c * ln.x - s * ln.y, s * ln.x + c * ln.y, ln.z);
    o.normal = normalize(rn);
    o.color = mix(v.bark.rgb, v.leaf.rgb, v.mat);
    o.fade = vec4<f32>(v.p1.z, v.p1.w, v.p2.x, v.leaf.w);
    o.mat_s = vec2<f32>(v.mat, v.pos.z);
    o.salt = v.bark.w;
    return o;
}

fn bayer4(p: vec2<f32>) -> f32 {
    let x = u32(p.x) & 3u;
    let y = u32(p.y) & 3u;
    var m = array<f32, 16>(0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0, 3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    return (m[y * 4u + x] + 0.5) / 16.0;
}

fn ign(p: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(p, vec2<f32>(0.06711056, 0.00583715))));
}

// Screen-door masks: LOD cross-fade (complementary Bayer patterns), timelapse opacity and
// leaf amount (interleaved gradient noise). Returns false when the fragment is dropped.
fn keep(i: TreeOut) -> bool {
    let d = bayer4(i.clip.xy);
    let f = i.fade.x;
    if (i.fade.y < 0.5) {
        if (d < f) { return false; }
    } else {
        if (d >= f) { return false; }
    }
    let e = ign(i.clip.xy + vec2<f32>(i.salt * 7.0, i.salt * 13.0));
    if (e >= i.fade.z) { return false; }
    if (i.mat_s.x > 0.5) {
        let e2 = ign(i.clip.yx * 1.37 + vec2<f32>(i.salt * 3.0, 5.0));
        if (e2 >= i.fade.w) { return false; }
    }
    return true;
}

@fragment
fn fs_tree(i: TreeOut, @builtin(front_facing) ff: bool) -> @location(0) vec4<f32> {
    if (!keep(i)) {
        discard;
    }
    var n = normalize(i.normal);
    if (!ff) {
        n = -n;
    }
    let leafy = i.mat_s.x;
    let ao = mix(1.0, mix(0.45, 1.0, clamp(i.mat_s.y * 1.3 - 0.2, 0.0, 1.0)), leafy);
    let c = shade(i.color, n, i.world, 0.35 * leafy, ao) * mix(1.0, ao * 0.4 + 0.6, leafy);
    return vec4<f32>(fog(c, i.world), 1.0);
}

@vertex
fn vs_tree(v: TreeIn) -> TreeOut {
    return tree_vertex(v);
}

@vertex
fn vs_tree_shadow(v: TreeIn) -> TreeOut {
    return tree_vertex(v);
}

@fragment
fn fs_tree_shadow(i: TreeOut) {
    if (!keep(i)) {
        discard;
    }
}
