// Sylva scene shader: sky gradient, terrain, water, instanced trees with LOD cross-fade,
// EcoMod wind sway (004_*.txt, Algorithm 1), seasonal colour, sun shadow map, aerial fog.

struct Globals {
    view_proj: mat4x4<f32>,
    light_view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    eye: vec4<f32>,          // xyz eye, w = 1 for orthographic
    sun_dir: vec4<f32>,      // xyz towards the sun; w: light terms (render/renderer, LightTerms: 0 all, 1 no shadows, 2 sun only, 3 sky only)
    sun_color: vec4<f32>,    // rgb; w = 1: billboard crowns take the sun on their quad (Renderer::crown_sun_on_quad)
    sky_zenith: vec4<f32>,   // rgb; w: world size (m) of one pixel per metre of clip w (0: no stem widening)
    sky_horizon: vec4<f32>,  // rgb; w = 1: a tree in a cross-fade band draws one level whole (Renderer::fade_per_tree)
    wind: vec4<f32>,         // direction x, y; directed w_g; undirected w_s
    params: vec4<f32>,       // time s, sea level m, shadow texel size, fog density 1/m
    facing: vec4<f32>,       // xyz towards the viewer for billboards when w = 1 (ortho, sun); w = 0: use eye
    canopy0: vec4<f32>,      // canopy grid origin x, y (m), texel (m), on (1) / off (0)
    canopy1: vec4<f32>,      // canopy grid nx, ny, oblique-view factor k, crown light height m
    shadow: vec4<f32>,       // shadow map: texel (uv), depth bias (depth units), texel (m), fast shading (1: one tap)
};

// Billboard outline of one prototype (render/lod.rs, Silhouette).
struct Sil {
    w: array<vec4<f32>, 4>,  // 16 crown half-widths (relative to radius) by height bin
    info: vec4<f32>,         // crown bottom, crown top, trunk half-width, widest z
    look: vec4<f32>,         // top flatness, plan cover, clumping, unused (render/lod.rs, CrownLook)
};

@group(0) @binding(0) var<uniform> g: Globals;
@group(0) @binding(1) var shadow_map: texture_depth_2d;
@group(0) @binding(2) var shadow_sampler: sampler_comparison;
@group(0) @binding(3) var<storage, read> sils: array<Sil>;
// far-field canopy layer (render/canopy.rs): per texel coverage, r, g, b sums in 1/1024
@group(0) @binding(4) var<storage, read> canopy: array<vec4<u32>>;
// leaf alpha textures (structure/texture.rs via render/renderer.rs, leaf_layers): per leaf shape
// a leaf-card layer and a leaf-cluster layer; grey shading in rgb, coverage in a
@group(0) @binding(5) var leaf_tex: texture_2d_array<f32>;
@group(0) @binding(6) var leaf_samp: sampler;

// One percentage-closer tap of the sun's shadow map at `uv`, depth `z` (a linear comparison
// sampler: each tap is already a bilinear 2x2 PCF).
fn shadow_tap(uv: vec2<f32>, z: f32) -> f32 {
    return textureSampleCompareLevel(shadow_map, shadow_sampler, uv, z);
}

// Shadow-map coordinates (uv, depth) of a world point, nudged along its normal; w = 0 outside
// the map (lit).
fn shadow_coord(world: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    // normal offset of one texel and a depth bias of half a texel (world units): no acne on
    // ground lit at a grazing angle, contact shadows kept within a metre or two
    let p = g.light_view_proj * vec4<f32>(world + n * g.shadow.z, 1.0);
    let ndc = p.xyz / p.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, -ndc.y * 0.5 + 0.5);
    if (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0 || ndc.z > 1.0) {
        return vec4<f32>(uv, ndc.z, 0.0);
    }
    return vec4<f32>(uv, ndc.z - g.shadow.y, 1.0);
}

// Sun visibility 0..1: percentage-closer filtering over a 3x3 grid of bilinear comparison taps
// one texel apart (a 4x4-texel tent kernel: soft crown-shadow edges without stair steps).
fn shadow_factor(world: vec3<f32>, n: vec3<f32>) -> f32 {
    let c = shadow_coord(world, n);
    if (c.w < 0.5) {
        return 1.0;
    }
    // frames in motion (Renderer::fast_shading): one bilinear tap
    if (g.shadow.w > 0.5) {
        return shadow_tap(c.xy, c.z);
    }
    let t = g.shadow.x;
    var s = 0.0;
    for (var j = -1; j <= 1; j = j + 1) {
        for (var i = -1; i <= 1; i = i + 1) {
            s = s + shadow_tap(c.xy + vec2<f32>(f32(i), f32(j)) * t, c.z);
        }
    }
    return s / 9.0;
}

// Sky visibility 0..1 under the canopy: the sun's shadow map averaged over a wide ring (8 taps
// at 6 texels, the centre at weight 2), a cheap stand-in for the fraction of the sky hemisphere
// not hidden by crowns above (the canopy seen from the sun's direction, blurred over a few
// metres). Floors at 0.45 so that deep shade keeps some skylight.
fn sky_visibility(world: vec3<f32>, n: vec3<f32>) -> f32 {
    let c = shadow_coord(world, n);
    if (c.w < 0.5) {
        return 1.0;
    }
    if (g.shadow.w > 0.5) {
        return mix(0.45, 1.0, shadow_tap(c.xy, c.z));
    }
    let t = g.shadow.x * 6.0;
    var s = 2.0 * shadow_tap(c.xy, c.z);
    for (var k = 0; k < 8; k = k + 1) {
        let a = f32(k) * 0.7853982 + 0.39;
        s = s + shadow_tap(c.xy + vec2<f32>(cos(a), sin(a)) * t, c.z);
    }
    return mix(0.45, 1.0, s / 10.0);
}

// Below the horizon (terrain19): distant forested hills seen through haze, the horizon
// colour turning a darker blue-green the further down the view looks, so that the faded
// surroundings of the terrain end in a landscape horizon rather than in empty sky.
fn below_horizon(up: f32) -> vec3<f32> {
    let hills = g.sky_horizon.rgb * vec3<f32>(0.58, 0.68, 0.62);
    return mix(g.sky_horizon.rgb * 0.97, hills, smoothstep(0.0, 0.22, -up));
}

fn sky_color(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.z, -1.0, 1.0);
    var c = mix(g.sky_horizon.rgb, g.sky_zenith.rgb, pow(max(up, 0.0), 0.6));
    if (up < 0.0) {
        c = below_horizon(up);
    }
    let sd = max(dot(dir, g.sun_dir.xyz), 0.0);
    c = c + g.sun_color.rgb * (pow(sd, 800.0) * 4.0 + pow(sd, 12.0) * 0.15);
    return c;
}

// Aerial perspective: in-scattered sky light over the view distance, exp(-d * density), towards
// the horizon colour, a little warmer towards the sun (forward scattering); at most 85 %.
fn fog(c: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    var d = length(world - g.eye.xyz);
    if (g.eye.w > 0.5) {
        d = 0.0;
    }
    let f = 1.0 - exp(-d * g.params.w);
    let v = normalize(world - g.eye.xyz + vec3<f32>(0.0, 0.0, 1e-4));
    let sunward = pow(max(dot(v, g.sun_dir.xyz), 0.0), 8.0);
    let air = mix(g.sky_horizon.rgb, g.sky_horizon.rgb * 0.6 + g.sun_color.rgb * 0.4, sunward * 0.5);
    return mix(c, air, clamp(f, 0.0, 0.85));
}

// The light terms a frame draws (Renderer::light_terms, a diagnostic of the stills' lighting):
// the sun's shadow-map visibility `sh` (1 with the shadows off), and the gains of the sun and
// of the sky light.
fn light_sh(sh: f32) -> f32 {
    return select(sh, 1.0, abs(g.sun_dir.w - 1.0) < 0.5);
}
fn sun_gain() -> f32 {
    return select(1.0, 0.0, abs(g.sun_dir.w - 3.0) < 0.5);
}
fn sky_gain() -> f32 {
    return select(1.0, 0.0, abs(g.sun_dir.w - 2.0) < 0.5);
}

// Sun (Lambert with `wrap`, shadow-mapped) plus sky light: a hemisphere ambient between the
// ground-bounced light (down-facing normals) and the sky (up-facing), occluded by the canopy above
// (`sky_visibility`) and by `ao`.
fn shade(albedo: vec3<f32>, n: vec3<f32>, world: vec3<f32>, wrap: f32, ao: f32) -> vec3<f32> {
    return shade_sh(albedo, n, world, wrap, ao, shadow_factor(world, n));
}

// [`shade`] with the sun visibility `sh` given.
fn shade_sh(albedo: vec3<f32>, n: vec3<f32>, world: vec3<f32>, wrap: f32, ao: f32, sh: f32) -> vec3<f32> {
    let l = g.sun_dir.xyz;
    let ndl = max((dot(n, l) + wrap) / (1.0 + wrap), 0.0);
    let amb_col = mix(vec3<f32>(0.55, 0.55, 0.5), mix(g.sky_horizon.rgb, g.sky_zenith.rgb, 0.5), 0.5);
    let ground = amb_col * vec3<f32>(0.36, 0.38, 0.3);
    let sky_amb = mix(ground, amb_col * 0.42, clamp(0.5 + 0.5 * n.z, 0.0, 1.0));
    // foliage (wrapped light) has its own crown occlusion `ao`; the canopy's sky occlusion is
    // for the ground and stems under it
    var sv = 1.0;
    if (wrap < 0.3) {
        sv = light_sh(sky_visibility(world, n));
    }
    let lit = g.sun_color.rgb * ndl * light_sh(sh) * sun_gain() + sky_amb * ao * sv * sky_gain();
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
    @location(3) fade: f32,
};

struct TerrainOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) fade: f32,
};

@vertex
fn vs_terrain(v: TerrainIn) -> TerrainOut {
    var o: TerrainOut;
    o.clip = g.view_proj * vec4<f32>(v.pos, 1.0);
    o.world = v.pos;
    o.normal = v.normal;
    o.color = v.color;
    o.fade = v.fade;
    return o;
}


// ---- surroundings (terrain19): the terrain beyond the simulated window dissolves into the
// sky colour seen behind it (same sky_color as fs_sky), so the mesh ends without an edge.
fn view_dir_to(world: vec3<f32>) -> vec3<f32> {
    if (g.eye.w > 0.5) {
        return -normalize(g.facing.xyz);
    }
    return normalize(world - g.eye.xyz);
}

fn surroundings_fade(c: vec3<f32>, world: vec3<f32>, fade: f32) -> vec3<f32> {
    if (fade <= 0.0) {
        return c;
    }
    let f = smoothstep(0.0, 1.0, clamp(fade, 0.0, 1.0));
    return mix(c, sky_color(view_dir_to(world)), f);
}
// ---- end surroundings

fn canopy_texel(i: i32, j: i32) -> vec4<f32> {
    let nx = i32(g.canopy1.x);
    let ny = i32(g.canopy1.y);
    if (i < 0 || j < 0 || i >= nx || j >= ny) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(canopy[u32(j) * u32(nx) + u32(i)]) / 1024.0;
}

// Canopy layer at plan position p: (crown albedo, plan coverage 0..1), bilinear over texels.
fn canopy_at(p: vec2<f32>) -> vec4<f32> {
    let u = (p.x - g.canopy0.x) / g.canopy0.z - 0.5;
    let v = (p.y - g.canopy0.y) / g.canopy0.z - 0.5;
    let i = i32(floor(u));
    let j = i32(floor(v));
    let fu = u - floor(u);
    let fv = v - floor(v);
    let a = mix(canopy_texel(i, j), canopy_texel(i + 1, j), fu);
    let b = mix(canopy_texel(i, j + 1), canopy_texel(i + 1, j + 1), fu);
    let s = mix(a, b, fv);
    if (s.x <= 1e-4) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(s.yzw / s.x, min(s.x, 1.0));
}

// Coverage seen along the view ray of plan coverage `c`: 1 - (1 - c)^(1 + k cot(elevation)),
// crowns of height ~ their diameter hiding more ground the flatter the view (render/canopy.rs).
fn canopy_view_cover(c: f32, world: vec3<f32>) -> f32 {
    var sn = 1.0;
    if (g.eye.w > 0.5) {
        sn = abs(g.facing.z);
    } else {
        sn = normalize(g.eye.xyz - world).z;
    }
    sn = clamp(sn, 0.05, 1.0);
    let ex = min(1.0 + g.canopy1.z * sqrt(1.0 - sn * sn) / sn, 12.0);
    return 1.0 - pow(1.0 - clamp(c, 0.0, 0.999), ex);
}

// Scale (m) of the canopy layer's crown bumps: about the crown spacing of a closed canopy
// (crown radii 1.5–4 m; ESTIMATE), and how far the bumps tilt its normal.
const CROWN_BUMP_M: f32 = 6.0;
const CROWN_BUMP_TILT: f32 = 2.5;

@fragment
fn fs_terrain(i: TerrainOut) -> @location(0) vec4<f32> {
    let n = normalize(i.normal);
    // the pixel's footprint on the ground: the canopy is box-filtered over it so that texels
    // smaller than a pixel do not alias into noise
    let fx = dpdx(i.world.xy);
    let fy = dpdy(i.world.xy);
    var c = shade(i.color, n, i.world, 0.0, 1.0);
    if (g.canopy0.w > 0.5) {
        // one bilinear tap when the footprint is within 1.5 texels, else 3 taps spread along
        // its longer axis (the depth direction of oblique views)
        let lx = length(fx);
        let ly = length(fy);
        var ax = fx;
        if (ly > lx) {
            ax = fy;
        }
        var taps = 0;
        if (max(lx, ly) / g.canopy0.z > 1.5) {
            taps = 1;
        }
        var acc = vec4<f32>(0.0);
        for (var a = -taps; a <= taps; a = a + 1) {
            let s = canopy_at(i.world.xy + ax * (f32(a) / 3.0));
            acc = acc + vec4<f32>(s.rgb * s.w, s.w);
        }
        var cv = vec4<f32>(0.0);
        if (acc.w > 1e-5) {
            cv = vec4<f32>(acc.rgb / acc.w, acc.w / f32(2 * taps + 1));
        }
        if (cv.w > 0.0) {
            // crowns lit like the billboards' rounded crowns: wrapped light on an up-facing
            // normal, the crown's mean ambient occlusion and self-shading; sun visibility at the
            // height of the upper crowns (render/renderer.rs, canopy_light_height), not in the
            // shadow the trees drawn as geometry cast on the ground
            // crowns as rounded bumps of CROWN_BUMP_M (round 35: the layer was lit as one flat
            // sheet, a carpet): the normal tilts with the slope of a smooth noise of that
            // scale, each bump lit on its sun side and shaded on the other; faded out where a
            // pixel's footprint is wider than a bump (no aliasing into speckle)
            let q = i.world.xy / CROWN_BUMP_M;
            let e = 0.35;
            let gx = vnoise(q + vec2<f32>(e, 0.0), 7.0) - vnoise(q - vec2<f32>(e, 0.0), 7.0);
            let gy = vnoise(q + vec2<f32>(0.0, e), 7.0) - vnoise(q - vec2<f32>(0.0, e), 7.0);
            let kb = 1.0 - smoothstep(0.5 * CROWN_BUMP_M, 1.2 * CROWN_BUMP_M, min(lx, ly));
            let cn = normalize(n + vec3<f32>(0.0, 0.0, 1.5) - vec3<f32>(gx, gy, 0.0) * (CROWN_BUMP_TILT * kb));
            let top = i.world + vec3<f32>(0.0, 0.0, g.canopy1.w);
            let cc = shade(cv.rgb, cn, top + cn * 0.5, 0.35, 0.75) * 0.85;
            c = mix(c, cc, canopy_view_cover(cv.w, i.world));
        }
    }
    return vec4<f32>(surroundings_fade(fog(c, i.world), i.world, i.fade), 1.0);
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
    @location(1) normal: vec3<f32>, // billboards: local outline coordinates (a, z or b, 0)
    @location(2) mat: f32,          // 0 bark, 1 leaf, 2 billboard side quad, 3 billboard top quad
    @location(3) pos_h: vec4<f32>,  // base x y z, height m
    @location(4) p1: vec4<f32>,     // horizontal scale, rotation rad, fade threshold, fade side
    @location(5) leaf: vec4<f32>,   // leaf rgb, leaf amount
    @location(6) p2: vec4<f32>,     // opacity, phase R_x, phase R_z, flexibility (1 - k_f)
    @location(7) bark: vec4<f32>,   // bark rgb, dither salt
    @location(8) p3: vec4<f32>,     // prototype, level, crown radius (culling), crown radius drawn
    @location(9) uv: vec2<f32>,     // leaf-card coordinates 0..1 (carved into discs); -1 elsewhere
    @location(10) p4: vec4<f32>,    // sky fade 0..1 (TreeInstance::sky_fade), crown base (TreeInstance::crown_base), unused x2
};

struct TreeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) @interpolate(flat) fade: vec4<f32>,  // threshold, side, opacity, leaf amount
    @location(4) mat_s: vec2<f32>,                      // material, normalised height
    @location(5) @interpolate(flat) salt: f32,
    @location(6) bb: vec2<f32>,                         // billboard outline coordinates
    @location(7) @interpolate(flat) info: vec4<f32>,   // prototype, level, sky fade 0..1, crown base (0: prototype's)
    @location(8) @interpolate(flat) bark: vec3<f32>,   // bark colour (billboard trunks, twigs)
    @location(9) cdir: vec3<f32>,                       // direction from the crown centre (meshes)
    @location(10) uv: vec2<f32>,                        // leaf-card coordinates (-1: not a card)
    @location(11) @interpolate(flat) rad: f32,          // crown radius drawn (m)
    // meshes: xyz the point in the tree's own frame (m from the stem base, turned with the
    // tree, before the wind: the crown-hull level's leaf clumps are fixed to the tree); w the
    // share of a widened coarse stem's width the real stem covers (1: not widened)
    @location(12) lp: vec4<f32>,
};

// Direction from a tree towards the viewer (or the sun in the shadow pass).
fn facing_dir(base: vec3<f32>) -> vec3<f32> {
    if (g.facing.w > 0.5) {
        return normalize(g.facing.xyz);
    }
    let d = g.eye.xyz - base;
    if (dot(d, d) < 1e-8) {
        return vec3<f32>(0.0, -1.0, 0.0);
    }
    return normalize(d);
}

// Horizontal unit vector to the right of a viewer looking along -f.
fn right_of(f: vec3<f32>) -> vec3<f32> {
    let h = vec2<f32>(-f.y, f.x);
    let l = length(h);
    if (l < 1e-4) {
        return vec3<f32>(1.0, 0.0, 0.0);
    }
    return vec3<f32>(h / l, 0.0);
}

// World position of a tree vertex with EcoMod wind (Algorithm 1): directed bend
// alpha_w = k_w * w_g * s^2 towards the wind, undirected sway alpha_x(t) = sin(w t + R_x) w_s (1-k_f) l0,
// alpha_z(t) = sin(w t + R_z) w_s (1-k_f) l0 with l0 = s^2, small-angle displacement = angle * height.
// `rp` is the vertex offset from the stem base (m), `sn` its normalised height.
fn sway(v: TreeIn, rp: vec3<f32>, sn_in: f32) -> vec3<f32> {
    let sn = clamp(sn_in, 0.0, 1.2);
    let l0 = sn * sn;
    let t = g.params.x;
    let k_w = 0.02;
    let a_w = k_w * g.wind.z * l0;
    let a_x = sin(1.7 * t + v.p2.y) * g.wind.w * v.p2.w * l0 * k_w;
    let a_z = sin(1.3 * t + v.p2.z) * g.wind.w * v.p2.w * l0 * k_w;
    let disp = (g.wind.xy * a_w + vec2<f32>(a_x, a_z)) * rp.z;
    let dz = -0.5 * dot(disp, disp) / max(rp.z, 0.01);
    return v.pos_h.xyz + rp + vec3<f32>(disp, dz);
}

// Two-piece linear map of a normalised height `z` taking `z0` to `z1` (both inside 0..1) and
// keeping 0 and 1.
fn two_piece(z: f32, z0: f32, z1: f32) -> f32 {
    if (z <= z0) {
        return z * z1 / z0;
    }
    return z1 + (z - z0) * (1.0 - z1) / (1.0 - z0);
}

// Whether a prototype whose foliage starts at `b0` is drawn with its crown from `b`
// (TreeInstance::crown_base; 0: the prototype's own): not for a prototype without a stem below
// its foliage (conifers to the ground).
fn crown_moved(b0: f32, b: f32) -> bool {
    return b > 0.0 && b0 >= 0.05 && b0 <= 0.9;
}

// Drawn normalised height of a prototype point at normalised height `z`: the stem below the
// prototype's foliage `b0` stretched or shortened to the crown base `b`, the crown above it to
// span `b`..1.
fn crown_remap(z: f32, b0: f32, b: f32) -> f32 {
    if (!crown_moved(b0, b)) {
        return z;
    }
    return two_piece(z, b0, b);
}

// The inverse of `crown_remap`: the prototype's normalised height of a drawn one.
fn crown_unmap(z: f32, b0: f32, b: f32) -> f32 {
    if (!crown_moved(b0, b)) {
        return z;
    }
    return two_piece(z, b, b0);
}

// Least width (px) of a tree's stem drawn at the crown-hull or billboard level (issue 32: small
// trees' stems, thinner than a pixel, vanished and their crowns floated over the ground).
const MIN_STEM_PX: f32 = 1.2;
// Least share of its bark colour a widened coarse stem keeps (fs_tree): a birch's white is
// dimmed to a grey under the crown hull rather than a white stick, a small tree's stem stays
// visible.
const MIN_STEM_BARK: f32 = 0.4;

// Linear albedo of the shaded stand interior behind a distant tree's trunk (dark foliage and
// twigs under the canopy): what a widened trunk's pixel shows beside the real trunk.
const STAND_SHADE: vec3<f32> = vec3<f32>(0.035, 0.045, 0.03);

// `top_scale`: size of the billboard's top quad (1: the crown's plan disc, in both passes).
fn tree_vertex(v: TreeIn, top_scale: f32) -> TreeOut {
    var o: TreeOut;
    o.cdir = vec3<f32>(0.0, 0.0, 1.0);
    o.lp = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    let h = v.pos_h.w;
    // the crown drawn from the instance's crown base (render/scene.rs, TreeInstance::crown_base)
    let zd = crown_remap(v.pos.z, sils[u32(v.p3.x + 0.5)].info.x, v.p4.y);
    let sxy = v.p1.x;
    var w: vec3<f32>;
    if (v.mat > 1.5) {
        // billboard impostor: side quad turned towards the viewer about the stem, top quad flat
        let f = facing_dir(v.pos_h.xyz + vec3<f32>(0.0, 0.0, 0.5 * h));
        var rp: vec3<f32>;
        if (v.mat < 2.5) {
            rp = right_of(f) * (v.pos.x * sxy) + vec3<f32>(0.0, 0.0, zd * h);
            o.normal = f;
        } else {
            // the top quad only shows from above: it shrinks to nothing as the view flattens
            // (continuous, so an orbiting camera sees no pop)
            let k = smoothstep(0.45, 0.8, f.z) * top_scale;
            rp = vec3<f32>(v.pos.x * sxy * k, v.pos.y * sxy * k, zd * h);
            o.normal = vec3<f32>(0.0, 0.0, 1.0);
        }
        w = sway(v, rp, v.pos.z);
        o.bb = v.normal.xy;
    } else {
        let c = cos(v.p1.y);
        let s = sin(v.p1.y);
        var lp = vec3<f32>(v.pos.x * sxy, v.pos.y * sxy, zd * h);
        if (v.mat > 0.5 && v.p3.y > 1.5) {
            // the crown hull's shell spread about the stem: its lobes (fs_tree, hull_clumps)
            // reach the crown radius the tree is drawn with, as the leaves do
            lp = vec3<f32>(lp.xy * HULL_SPREAD, lp.z);
        }
        // the stem of the crown-hull level (and coarser meshes) at least MIN_STEM_PX wide on
        // screen: a small tree's real stem is thinner than a pixel, and without it its crown
        // floats over the ground (issue 32)
        if (v.mat < 0.5 && v.p3.y > 1.5 && g.sky_zenith.w > 0.0) {
            let cw = (g.view_proj * vec4<f32>(v.pos_h.xyz + vec3<f32>(0.0, 0.0, lp.z), 1.0)).w;
            let rmin = 0.5 * MIN_STEM_PX * max(cw, 0.0) * g.sky_zenith.w;
            let r = length(lp.xy);
            if (r > 1e-6 && r < rmin) {
                lp = vec3<f32>(lp.xy * (rmin / r), lp.z);
                o.lp.w = r / rmin;
            }
        }
        let rp = vec3<f32>(c * lp.x - s * lp.y, s * lp.x + c * lp.y, lp.z);
        w = sway(v, rp, v.pos.z);
        let ln = vec3<f32>(v.normal.x / max(sxy, 1e-4), v.normal.y / max(sxy, 1e-4), v.normal.z / max(h, 1e-4));
        let rn = vec3<f32>(c * ln.x - s * ln.y, s * ln.x + c * ln.y, ln.z);
        o.normal = normalize(rn);
        o.bb = vec2<f32>(0.0, 0.0);
        // outward direction of the crown as an ellipsoid about (0, 0, 0.6 h) with half-height
        // 0.4 h: bends leaf-cluster normals into a rounded crown shade
        o.cdir = vec3<f32>(rp.x / max(sxy, 1e-4), rp.y / max(sxy, 1e-4), (v.pos.z - 0.6) * 0.8);
        o.lp = vec4<f32>(rp, o.lp.w);
    }
    o.clip = g.view_proj * vec4<f32>(w, 1.0);
    o.world = w;
    o.color = mix(v.bark.rgb, v.leaf.rgb, min(v.mat, 1.0));
    o.fade = vec4<f32>(v.p1.z, v.p1.w, v.p2.x, v.leaf.w);
    o.mat_s = vec2<f32>(v.mat, v.pos.z);
    o.salt = v.bark.w;
    o.info = vec4<f32>(v.p3.xy, v.p4.x, v.p4.y);
    o.bark = v.bark.rgb;
    o.uv = v.uv;
    o.rad = v.p3.w;
    return o;
}

// Whether a card is a leaf-cluster card among the full level's leaf cards: its u runs from
// 2 to 3 (mesh.rs CLUSTER_CARD_U, the sprigs of a full-detail tree's crown leaf area).
fn cluster_card(i: TreeOut) -> bool {
    return i.uv.x > 1.5;
}

// A card's own coordinates 0..1 (a leaf-cluster card's u less CLUSTER_CARD_U).
fn card_uv(i: TreeOut) -> vec2<f32> {
    return select(i.uv, i.uv - vec2<f32>(2.0, 0.0), cluster_card(i));
}

// The leaf texture texel of a leaf card (full level: the leaf, reduced level and the full
// level's leaf-cluster cards: the leaf cluster) of a prototype with a leaf shape; a = −1 when
// it has none or this is not a card. Texture rows run from the leaf tip down (v flipped).
fn card_texel(i: TreeOut) -> vec4<f32> {
    if (i.uv.x < -0.5 || i.mat_s.x < 0.5 || i.mat_s.x > 1.5 || i.info.y > 1.5) {
        return vec4<f32>(1.0, 1.0, 1.0, -1.0);
    }
    let layer = sils[u32(i.info.x + 0.5)].look.w;
    if (layer < -0.5) {
        return vec4<f32>(1.0, 1.0, 1.0, -1.0);
    }
    let l = i32(layer + 0.5) + max(i32(i.info.y + 0.5), select(0, 1, cluster_card(i)));
    let uv = card_uv(i);
    return textureSampleLevel(leaf_tex, leaf_samp, vec2<f32>(uv.x, 1.0 - uv.y), l, 0.0);
}

// Leaf cards: alpha-tested against the species' leaf texture (cutoff 0.5, structure/texture.rs
// ALPHA_CUTOFF) where the prototype has a leaf shape; else carved into discs with a dithered
// rim (radius 0.7..1 of the half-side), so leaf clusters of crossed cards read as soft round
// clumps, not squares.
fn card_kept(i: TreeOut) -> bool {
    if (i.uv.x < -0.5 || i.mat_s.x < 0.5 || i.mat_s.x > 1.5) {
        return true;
    }
    let t = card_texel(i);
    if (t.a > -0.5) {
        return t.a >= 0.5;
    }
    let d = length(card_uv(i) * 2.0 - vec2<f32>(1.0, 1.0));
    return d < 1.0 - 0.3 * hash2(i.clip.xy, i.salt + 17.0);
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

fn sil_width(p: u32, z: f32) -> f32 {
    let s = sils[p];
    if (z < s.info.x || z > s.info.y) {
        return 0.0;
    }
    let x = clamp(z * 16.0 - 0.5, 0.0, 15.0);
    let i = min(u32(x), 15u);
    let j = min(i + 1u, 15u);
    let t = x - f32(i);
    let a = s.w[i / 4u][i % 4u];
    let b = s.w[j / 4u][j % 4u];
    return mix(a, b, t);
}

// Lattice hash 0..1 of an integer cell and a salt.
fn lattice(c: vec2<f32>, salt: f32) -> f32 {
    return fract(sin(dot(c, vec2<f32>(127.1, 311.7)) + salt * 17.13) * 43758.5453);
}

// Smooth value noise 0..1 (bicubic-faded bilinear over the lattice): the foliage lumps.
fn vnoise(p: vec2<f32>, salt: f32) -> f32 {
    let c = floor(p);
    let f = p - c;
    let u = f * f * (3.0 - 2.0 * f);
    let a = lattice(c, salt);
    let b = lattice(c + vec2<f32>(1.0, 0.0), salt);
    let d = lattice(c + vec2<f32>(0.0, 1.0), salt);
    let e = lattice(c + vec2<f32>(1.0, 1.0), salt);
    return mix(mix(a, b, u.x), mix(d, e, u.x), u.y);
}

// Foliage lumps of a crown point `q` (outline coordinates, −1..1 across the crown): 0..1, lumps
// the larger the more clumped the species' foliage (`look.z`), fixed per tree by its salt.
fn lumps(q: vec2<f32>, look: vec4<f32>, salt: f32) -> f32 {
    let f = mix(4.5, 2.5, look.z);
    return 0.65 * vnoise(q * f, salt) + 0.35 * vnoise(q * f * 2.3 + vec2<f32>(5.2, 1.3), salt + 3.0);
}

// Whether a crown point with lump value `l` is a gap (sky or ground seen through an airy crown):
// the species' plan cover `look.y` sets how much of the crown opens (none above 0.95).
fn crown_gap(l: f32, look: vec4<f32>) -> bool {
    return l < (0.95 - look.y) * 0.9;
}

// The crown-hull level's leaf clumps (issue 32, round 40: the hull was a smooth shell, an
// egg on a stick in the mid-ground). A crown of a few metres is a handful of leaf clusters
// about the ends of its main branches (Pirk et al. 2012, section 5.2: a cluster per terminal
// lobe); the hull's surface is cut into clumps of HULL_CLUMP_CELL × the crown radius by a
// cellular (Worley 1996) pattern of points in the tree's own frame. Each clump is a low dome
// (its normal tilted along the surface away from the clump's centre), the seams between clumps
// are shaded (crevices), and near the outline only the clumps' middles are drawn, so the
// silhouette is a row of lobes rather than a smooth curve.
const HULL_CLUMP_CELL: f32 = 0.42;
// Horizontal spread of the crown hull's shell about the stem, beyond the renderer's own
// (render::lod::plan_spread, which gives the hull the plan area of the crown disc): the lobes
// cut at the outline (HULL_RIM) take that much of it back; with this spread the crown hulls of
// a stand seen from straight above cover the union of their crown discs
// (tests/render_species.rs, the_coarse_levels_from_above_cover_the_crowns_of_the_simulation).
const HULL_SPREAD: f32 = 1.16;
// Fewest and most metres of a clump (a spruce's whorl segments, a big oak's limbs' foliage).
const HULL_CLUMP_MIN_M: f32 = 0.5;
const HULL_CLUMP_MAX_M: f32 = 3.0;
// How far a clump's dome tilts the normal at its rim (relative to the surface normal).
const HULL_CLUMP_TILT: f32 = 1.1;
// Sky and sun light left in the seams between clumps, and in a clump's middle (about 1 on the
// crown's mean, so the crown keeps its brightness).
const HULL_CREVICE: f32 = 0.65;
const HULL_CLUMP_LIGHT: f32 = 1.1;
// Facing (|n·v|) under which the outline is cut into lobes: at the outline only the clumps'
// middles stay, from this facing on the whole surface.
const HULL_RIM: f32 = 0.6;

struct Clumps {
    // 0 on a seam between two clumps .. 1 in a clump's middle
    body: f32,
    // the dome's tilt along the surface (world axes; length up to about 1)
    tilt: vec3<f32>,
    // brightness of this clump's foliage (each clump a little lighter or darker)
    tint: f32,
};

fn hash3(c: vec3<f32>, salt: f32) -> vec3<f32> {
    var h = vec3<u32>(vec3<i32>(c) + vec3<i32>(i32(salt) * 7919));
    h = h * 1664525u + 1013904223u;
    h.x = h.x + h.y * h.z;
    h.y = h.y + h.z * h.x;
    h.z = h.z + h.x * h.y;
    h = h ^ (h >> vec3<u32>(16u));
    h.x = h.x + h.y * h.z;
    h.y = h.y + h.z * h.x;
    h.z = h.z + h.x * h.y;
    return vec3<f32>(h & vec3<u32>(0xffffffu)) / 16777216.0;
}

// The cellular pattern (Worley 1996) of the leaf clumps at `q` (cell units), in space: each
// lattice cell holds one clump centre anywhere in the cell (its hash) with a size weight of its
// own, HULL_CLUMP_SIZE_MIN..MAX (a multiplicatively weighted Voronoi pattern: distances divided
// by the weight), so the clumps differ in size and spacing as a crown's branch ends do, and
// a cell whose fourth hash is under HULL_CLUMP_EMPTY holds none (its neighbours' clumps fill
// it: a few larger lumps). `f1`, `f2` the weighted squared distances to the nearest and
// second-nearest centre, `d1` the offset from the nearest over its weight, `h1` its hash; the
// 27 cells about `q` are searched.
struct Cells {
    f1: f32,
    f2: f32,
    d1: vec3<f32>,
    h1: f32,
};

// Least and largest size weight of a clump (relative to the mean cell), and the share of cells
// without a clump (issue 32, round 41: with every clump one size and one per cell the hull's
// clumps read as a regular cauliflower).
const HULL_CLUMP_SIZE_MIN: f32 = 0.55;
const HULL_CLUMP_SIZE_MAX: f32 = 1.45;
const HULL_CLUMP_EMPTY: f32 = 0.2;

fn cells(q: vec3<f32>, salt: f32) -> Cells {
    let c0 = floor(q);
    var r: Cells;
    r.f1 = 1e9;
    r.f2 = 1e9;
    r.d1 = vec3<f32>(0.0);
    r.h1 = 0.0;
    for (var z = -1; z <= 1; z = z + 1) {
        for (var y = -1; y <= 1; y = y + 1) {
            for (var x = -1; x <= 1; x = x + 1) {
                let k = c0 + vec3<f32>(f32(x), f32(y), f32(z));
                let h = hash3(k, salt);
                let h4 = fract(h.x * 13.37 + h.y * 7.91 + h.z * 3.17);
                if (h4 < HULL_CLUMP_EMPTY) {
                    continue;
                }
                let wt = mix(HULL_CLUMP_SIZE_MIN, HULL_CLUMP_SIZE_MAX, fract(h.z * 29.7 + h.x * 5.3));
                let d = (q - (k + h)) / wt;
                let dd = dot(d, d);
                if (dd < r.f1) {
                    r.f2 = r.f1;
                    r.f1 = dd;
                    r.d1 = d;
                    r.h1 = h.x;
                } else if (dd < r.f2) {
                    r.f2 = dd;
                }
            }
        }
    }
    return r;
}

// The clump cell (m) of a crown of radius `rad` (m).
fn clump_cell(rad: f32) -> f32 {
    return clamp(HULL_CLUMP_CELL * rad, HULL_CLUMP_MIN_M, HULL_CLUMP_MAX_M);
}

// Range of a tree's own clump size about `clump_cell` (by its salt): trees of one size and
// species do not share one grain.
const HULL_TREE_GRAIN: vec2<f32> = vec2<f32>(0.8, 1.25);

fn hull_clumps(i: TreeOut, n: vec3<f32>) -> Clumps {
    let grain = mix(HULL_TREE_GRAIN.x, HULL_TREE_GRAIN.y, fract(i.salt * 0.618034));
    let c = cells(i.lp.xyz / (clump_cell(i.rad) * grain), i.salt);
    var r: Clumps;
    r.body = smoothstep(0.0, 0.45, sqrt(c.f2) - sqrt(c.f1));
    r.tilt = c.d1 - n * dot(c.d1, n);
    r.tint = 0.86 + 0.28 * c.h1;
    return r;
}

// Radius (of the crown radius) out to which the billboard's top quad draws its lumpy disc.
// The billboards carry no leaf clumps (round 41): a stand's clumped billboards (round 40, a
// wider lobed top 1.24 of the crown radius) covered their crown discs from above, but broke
// their hand-over to the far-field canopy layer, whose crowns have no clumps
// (tests/render_canopy.rs: mean distance to the geometry forest 19.2 against 14.2).
const BB_TOP_R: f32 = 0.92;

// Gaps of the crown-hull level (a closed polyhedron): the species' airy or lumpy foliage cut
// into it with the same lumps as the billboard, over the crown direction `cdir`.
fn hull_gap(i: TreeOut) -> bool {
    let look = sils[u32(i.info.x + 0.5)].look;
    let q = vec2<f32>(i.cdir.x + 0.6 * i.cdir.y, i.cdir.z * 1.6 - 0.4 * i.cdir.y);
    return crown_gap(lumps(q, look, i.salt), look);
}

// Billboard outline test. Returns 0 outside (discard), 1 crown, 2 trunk; `n` gets a rounded
// pseudo-normal for the crown, shaped by the species' look (dome, spire, flat top, lumps).
struct Carve {
    kind: u32,
    n: vec3<f32>,
    z: f32,
    // side quad: how far the crown's surface seen at this pixel lies in front of the quad,
    // towards the viewer (outline units, relative to the crown radius; × `rad`: m): w·√(1 −
    // (a/w)²) of the crown's half-width w at this height, the crown taken as round in plan
    depth: f32,
    // trunk: the share of the drawn (widened) trunk's width the real trunk covers (0..1)
    cover: f32,
    // side quad's crown: the normal of the crown as a round solid (an ellipsoid about its
    // middle, no lumps): where its surface turns from the sun
    ns: vec3<f32>,
};

// `apx`: outline units (`i.bb.x`) per pixel across the quad (fwidth, taken in uniform control
// flow by the caller): the trunk is at least MIN_STEM_PX wide.
fn carve(i: TreeOut, apx: f32) -> Carve {
    var r: Carve;
    r.kind = 0u;
    r.n = vec3<f32>(0.0, 0.0, 1.0);
    r.depth = 0.0;
    r.cover = 1.0;
    r.ns = vec3<f32>(0.0, 0.0, 1.0);
    let p = u32(i.info.x + 0.5);
    let s = sils[p];
    let look = s.look;
    // a lumpy edge, fixed per tree: the more clumped the foliage, the deeper the lumps
    let depth = 0.05 + 0.22 * look.z;
    if (i.mat_s.x < 2.5) {
        let a = i.bb.x;
        // the outline's height on the quad is the drawn one: back to the prototype's
        let z = crown_unmap(i.bb.y, s.info.x, i.info.w);
        r.z = z;
        let zq = (z - s.info.x) / max(s.info.y - s.info.x, 1e-3) * 2.0 - 1.0;
        let l = lumps(vec2<f32>(a, zq * 1.4), look, i.salt);
        let ws = sil_width(p, z);
        let w = ws * (1.0 - depth + depth * 2.0 * l);
        if (abs(a) < w) {
            if (crown_gap(l, look)) {
                return r;
            }
            r.kind = 1u;
            let f = normalize(i.normal);
            let na = a / max(w, 1e-3);
            r.depth = w * sqrt(max(1.0 - na * na, 0.0));
            let zc = 0.5 * (s.info.x + s.info.y);
            let nz = clamp((z - zc) / max(0.5 * (s.info.y - s.info.x), 1e-3), -1.0, 1.0);
            // (the round solid's normal leans up by 0.6 of the relative height, round 46; was 0.8)
            r.ns = normalize(right_of(f) * na + vec3<f32>(0.0, 0.0, 0.6 * nz) + f * sqrt(max(1.0 - na * na, 0.0)));
            r.n = normalize(right_of(f) * na * 0.8 + vec3<f32>(0.0, 0.0, 0.3 * nz + 0.35) + f * sqrt(max(1.0 - na * na, 0.0)));
            // each lump is a small dome of its own: its shading bends the normal about it
            r.n = normalize(r.n + right_of(f) * (l - 0.5) * look.z * 1.5);
        } else if (abs(a) < max(s.info.z, 0.5 * MIN_STEM_PX * apx) && z < s.info.x + 0.3 * (s.info.y - s.info.x)) {
            r.kind = 2u;
            r.n = normalize(i.normal);
            r.cover = clamp(s.info.z / max(0.5 * MIN_STEM_PX * apx, 1e-6), 0.0, 1.0);
        }
    } else {
        let q = i.bb;
        let d = length(q);
        r.z = i.mat_s.y;
        let l = lumps(q, look, i.salt);
        if (d < BB_TOP_R * (1.0 - depth + depth * 2.0 * l)) {
            if (crown_gap(l, look)) {
                return r;
            }
            r.kind = 1u;
            // seen from above: a spire's flanks slope steeply away from its tip, a dome rounds
            // off, a flat umbrella faces the sky
            let k = mix(1.4, 0.2, smoothstep(0.1, 0.9, look.x));
            let bump = vec2<f32>(vnoise(q * 5.0 + vec2<f32>(0.5, 0.0), i.salt) - vnoise(q * 5.0 - vec2<f32>(0.5, 0.0), i.salt), vnoise(q * 5.0 + vec2<f32>(0.0, 0.5), i.salt) - vnoise(q * 5.0 - vec2<f32>(0.0, 0.5), i.salt));
            r.n = normalize(vec3<f32>(q * k + bump * (0.3 + 1.2 * look.z), sqrt(max(1.0 - d * d, 0.0)) + 0.2));
        }
    }
    return r;
}

// Screen-door masks: LOD cross-fade (complementary Bayer patterns) and timelapse opacity
// (interleaved gradient noise). Returns false when the fragment is dropped.
fn keep(i: TreeOut) -> bool {
    var d = bayer4(i.clip.xy);
    if (g.sky_horizon.w > 0.5) {
        // stills (Renderer::fade_per_tree): each tree in a cross-fade band draws one level
        // whole, by a threshold of its own; no screen-door dots where two levels meet
        d = (i.salt + 0.5) / 64.0;
    }
    let f = i.fade.x;
    if (i.fade.y < 0.5) {
        if (d < f) { return false; }
    } else {
        if (d >= f) { return false; }
    }
    let e = ign(i.clip.xy + vec2<f32>(i.salt * 7.0, i.salt * 13.0));
    if (e >= i.fade.z) { return false; }
    return true;
}

// Foliage of leaf amount `fade.w`: a fragment of a crown surface is a leaf (1) with probability
// leaf amount, else a twig (2) with probability `twig` (bare crowns read as a grey-brown haze of
// twigs), else dropped (0).
fn hash2(p: vec2<f32>, salt: f32) -> f32 {
    // integer hash of the pixel (white noise: no visible hatching), PCG-style mixing
    var h = u32(p.x) * 1973u + u32(p.y) * 9277u + u32(salt) * 26699u;
    h = (h ^ 61u) ^ (h >> 16u);
    h = h * 9u;
    h = h ^ (h >> 4u);
    h = h * 0x27d4eb2du;
    h = h ^ (h >> 15u);
    return f32(h & 0xffffffu) / 16777216.0;
}

fn foliage(i: TreeOut, twig: f32) -> u32 {
    let e2 = hash2(i.clip.xy, i.salt + 5.0);
    let la = i.fade.w;
    if (e2 < la) { return 1u; }
    if (e2 < la + (1.0 - la) * twig) { return 2u; }
    return 0u;
}

fn twig_density(i: TreeOut) -> f32 {
    if (i.mat_s.x > 1.5) {
        return 0.5;
    }
    return 0.25 + 0.08 * i.info.y;
}

fn twig_color(bark: vec3<f32>) -> vec3<f32> {
    return mix(bark, vec3<f32>(0.16, 0.14, 0.12), 0.6);
}

// Colour of thin outer twigs of mesh levels: dark red-brown, only a fifth of the stem's colour.
fn fine_twig_color(bark: vec3<f32>) -> vec3<f32> {
    return mix(bark, vec3<f32>(0.09, 0.065, 0.05), 0.8);
}

// White bark (issue 32, round 41: near birches were white poles of one colour). A bark whose
// Rec. 709 luma is above that of sRGB 200 (0.578 linear) is lenticelled, the rule
// `structure::texture::BarkPattern::of_species` gives the exported bark textures (the shipped
// library: silver birch). Silver birch's white bark carries dark horizontal lenticels and
// marks, and the base of an older stem turns rough and blackish (Atkinson 1992, Biological
// Flora of the British Isles: Betula pendula Roth and B. pubescens Ehrh., J. Ecol. 80,
// 837-870). Rows of marks every BIRCH_ROW_M up the stem, cells of BIRCH_CELL_M around it,
// BIRCH_MARKS of them marked (ESTIMATE, from photographs: marks of 1-4 cm in rows a hand apart);
// the dark base up to BIRCH_BASE_M (ESTIMATE: 1-2 m on a stem of 12 cm DBH and more, none on
// a stem under 3 cm), its upper edge ragged.
const BIRCH_LUMA: f32 = 0.578;
const BIRCH_ROW_M: f32 = 0.09;
const BIRCH_CELL_M: f32 = 0.07;
const BIRCH_MARKS: f32 = 0.7;
const BIRCH_BASE_M: f32 = 1.6;
const BIRCH_DARK: vec3<f32> = vec3<f32>(0.045, 0.04, 0.035);
const BIRCH_EDGE_M: f32 = 0.15;
// A stem counts as widened to MIN_STEM_PX (fs_tree) where its interpolated `lp.w` (r / rmin,
// exactly 1 at every vertex of an unwidened stem) is under this. Not `< 1.0`: across a
// triangle whose vertices all carry 1.0 the interpolated value came out a rounding error under
// 1 at scattered pixels, which then skipped the bark pattern; a birch's dark base at eye level
// showed the white bark through as salt-and-pepper dots (issue 32, round 43, trial 42 defect 8).
// A stem widened by under 0.5 % is drawn as itself.
const WIDENED_BELOW: f32 = 0.995;

fn white_bark(b: vec3<f32>) -> bool {
    return dot(b, vec3<f32>(0.2126, 0.7152, 0.0722)) > BIRCH_LUMA;
}

// The colour of white bark `b` at the point `lp` of a stem (m from the stem base, the tree's
// frame), `zpx` the metres of stem height a pixel spans and `xypx` the metres across the stem
// (`length(fwidth(lp.xy))`, large where the stem turns away at its outline). Filtered by the
// pixel's footprint (issue 32, round 43, trial 42 defect 8: the base of a birch at eye level
// sparkled salt-and-pepper): a mark fades to the pattern's mean where it would be under four
// pixels tall or wide, gone at 1.5 (before: sharp down to one pixel in height, whatever its
// width), and the ragged upper edge of the dark base (one step per BIRCH_EDGE_M of girth) to
// its mean where a step is under three pixels wide.
fn birch_bark(b: vec3<f32>, lp: vec3<f32>, zpx: f32, xypx: f32, salt: f32) -> vec3<f32> {
    let r = max(length(lp.xy), 0.01);
    let arc = atan2(lp.y, lp.x) * r;
    let row = floor(lp.z / BIRCH_ROW_M);
    let t = fract(lp.z / BIRCH_ROW_M);
    let cell = floor(arc / BIRCH_CELL_M);
    let u = fract(arc / BIRCH_CELL_M);
    let h = hash3(vec3<f32>(cell, row, 3.0), salt);
    // a mark: a horizontal dash of 0.15-0.35 of the row's height, 0.3-1 of the cell's width
    let th = mix(0.15, 0.35, h.y);
    let half = mix(0.25, 0.5, h.z);
    var m = 1.0;
    if (h.x < BIRCH_MARKS && abs(t - 0.5) < 0.5 * th && abs(u - 0.5) < half) {
        m = 0.25;
    }
    // the pattern's mean: marks of 0.75 darkness over 0.25 of a row and 0.75 of a cell
    let mean = 1.0 - 0.75 * BIRCH_MARKS * 0.25 * 0.75;
    let sharp = (1.0 - smoothstep(0.25, 0.67, zpx / (0.25 * BIRCH_ROW_M))) * (1.0 - smoothstep(0.25, 0.67, xypx / (0.5 * BIRCH_CELL_M)));
    var c = b * mix(mean, m, sharp);
    // the dark base, on stems over 1.5 cm radius, up to BIRCH_BASE_M at 6 cm and more
    let jag = mix(lattice(vec2<f32>(floor(arc / BIRCH_EDGE_M), 1.0), salt), 0.5, smoothstep(0.15, 0.35, xypx / BIRCH_EDGE_M));
    let top = BIRCH_BASE_M * smoothstep(0.015, 0.06, r) * (0.75 + 0.5 * jag);
    let dark = 1.0 - smoothstep(0.55 * top, top, lp.z);
    return mix(c, BIRCH_DARK, dark * 0.85);
}

@fragment
fn fs_tree(i: TreeOut, @builtin(front_facing) ff: bool) -> @location(0) vec4<f32> {
    let apx = fwidth(i.bb.x);
    let zpx = fwidth(i.lp.z);
    let xypx = length(fwidth(i.lp.xy));
    if (!keep(i) || !card_kept(i)) {
        discard;
    }
    var n = normalize(i.normal);
    var leafy = min(i.mat_s.x, 1.0);
    var albedo = i.color;
    let tex = card_texel(i);
    if (tex.a > -0.5) {
        // the leaf's veins and margin (grey 0.7..1 in the texture)
        albedo = albedo * tex.rgb;
    }
    var hz = i.mat_s.y;
    // where the sun's visibility is looked up: the fragment, or for a billboard's crown the
    // point of the crown's surface it shows (below)
    var sun_at = i.world;
    var crown_bb = false;
    var crown_k = 0.0;
    var ns = n;
    // leaf clumps' own shade (crevices between the crown hull's clumps; 1 elsewhere)
    var clump_ao = 1.0;
    if (i.mat_s.x > 1.5) {
        let c = carve(i, apx);
        if (c.kind == 0u) {
            discard;
        }
        n = c.n;
        hz = c.z;
        if (c.kind == 1u && i.mat_s.x < 2.5) {
            // the side quad stands in the plane of the stem, facing the viewer, while in the
            // sun's shadow map the same crown is a quad through its stem facing the sun. With
            // texels under a tenth of the crown radius the quad's own shadow on the far half is
            // a fair shaded side, and it is kept. With coarse texels (the default run's 3.1 m:
            // 1–3 a crown) the map cannot resolve a crown, and the crowns were lit almost
            // uniformly (issue 32, round 35: 1.4 % of the crown pixels out of the sun in
            // `tests/render_species.rs`): there the sun is looked up at the crown surface the
            // pixel shows, `depth` in front of the quad towards the viewer, then a quarter of
            // the crown radius out along the pseudo-normal (only other crowns and the relief
            // shade it), and the crown shades its far side itself (below); blended in from a
            // tenth to half the crown radius. Renderer::crown_sun_on_quad (sun_color.w = 1)
            // keeps the old lookup, to measure the change.
            let kc = smoothstep(0.1, 0.5, g.shadow.z / max(i.rad, 1e-3));
            if (g.sun_color.w < 0.5 && kc > 0.0) {
                let fh = normalize(i.normal);
                sun_at = i.world + (fh * (c.depth * i.rad) + n * (0.25 * i.rad)) * kc;
                crown_bb = true;
                crown_k = kc;
                ns = c.ns;
            }
        }
        if (c.kind == 2u) {
            leafy = 0.0;
            // a trunk widened to MIN_STEM_PX shows its bark over the share of the pixel the
            // real trunk covers, the shaded stand behind it over the rest (round 35: a birch's
            // white bark, 1.2 px wide on every distant birch, frosted the oblique still)
            albedo = mix(STAND_SHADE, i.bark, c.cover);
        }
    } else {
        if (!ff) {
            n = -n;
        }
        if (i.mat_s.x > 0.5) {
            // leaf clusters: dither away faces seen edge-on (soft, rounded cluster outlines
            // instead of box edges) and bend normals towards the crown's outward direction
            // (rounded crown shade); more at the reduced and hull levels, whose clusters are
            // coarse polyhedra
            let coarse = i.info.y > 0.5;
            var vd = g.facing.xyz;
            if (g.facing.w < 0.5) {
                vd = g.eye.xyz - i.world;
            }
            let e = abs(dot(n, normalize(vd)));
            var soft = 0.12;
            var bend = 0.35;
            if (coarse) {
                soft = 0.45;
                bend = 0.7;
            }
            let cd = i.cdir;
            if (i.info.y > 1.5) {
                // the crown hull: leaf clumps instead of a smooth shell (issue 32, round 40)
                let cl = hull_clumps(i, n);
                if (e < HULL_RIM * (1.0 - cl.body) || hull_gap(i)) {
                    discard;
                }
                if (dot(cd, cd) > 1e-8) {
                    n = normalize(mix(n, normalize(cd), 0.5));
                }
                n = normalize(n + cl.tilt * HULL_CLUMP_TILT);
                clump_ao = mix(HULL_CREVICE, HULL_CLUMP_LIGHT, cl.body);
                albedo = albedo * cl.tint;
            } else {
                if (hash2(i.clip.xy, i.salt + 11.0) > smoothstep(0.0, soft, e)) {
                    discard;
                }
                if (dot(cd, cd) > 1e-8) {
                    n = normalize(mix(n, normalize(cd), bend));
                }
            }
        }
    }
    if (leafy > 0.5) {
        let fo = foliage(i, twig_density(i));
        if (fo == 0u) {
            discard;
        }
        if (fo == 2u) {
            albedo = twig_color(i.bark);
            leafy = 0.3;
        }
    } else if (i.mat_s.x < 0.5 && i.lp.w < WIDENED_BELOW) {
        // a coarse level's stem widened to MIN_STEM_PX: its bark over the share of the width
        // the real stem covers, the shaded stand behind it over the rest, as the billboard's
        // trunk (round 40: birches' white stems, widened, read as white sticks under the
        // crown hulls from above)
        // (at least MIN_STEM_BARK of it: a small tree's stem still reads as a stem, issue 32
        // round 36)
        albedo = mix(STAND_SHADE, albedo, max(i.lp.w, MIN_STEM_BARK));
    } else if (i.mat_s.x < 0.5 && i.uv.y >= 0.0) {
        // mesh bark away from the stem: fine twigs are dark whatever the stem's colour (a
        // birch's white bark is on its stem and main limbs only)
        var b = i.bark;
        if (white_bark(b)) {
            b = birch_bark(b, i.lp.xyz, zpx, xypx, i.salt);
        }
        albedo = mix(b, fine_twig_color(i.bark), i.uv.y);
    }
    let ao = mix(1.0, mix(0.45, 1.0, clamp(hz * 1.3 - 0.2, 0.0, 1.0)), leafy) * clump_ao;
    let sh0 = shadow_factor(sun_at, n);
    var sh = sh0;
    var wrap = 0.35 * leafy;
    // the share of the sun's transmitted light that reaches the leaves seen
    var through = 1.0;
    if (crown_bb && leafy > 0.5) {
        // a billboard crown's own shade, now that its quad casts none on it (above): no sun where
        // the crown's surface as a round solid turns away from it (a soft terminator), less
        // wrapped light (0.3, still foliage to `shade_sh`), and the far side's leaves lit
        // through the crown by a third of the transmitted light (ESTIMATE): a lit and a shaded
        // side, as a rounded crown has. The terminator lies at 0.05–0.45 of the cosine of the
        // sun's incidence (ESTIMATE; rounds 35–45: −0.15–0.25): leaves the sun meets at a
        // grazing angle are shaded by the crown's own foliage in front of them. Round 46: the
        // round-45 crown profiles, wide to their tops, hid each other's shaded sides in an
        // oblique view of a closed stand (tests/render_species.rs, 0.017 against round 38's 0.072)
        sh = sh0 * mix(1.0, smoothstep(0.05, 0.45, dot(ns, g.sun_dir.xyz)), crown_k);
        wrap = mix(0.35, 0.3, crown_k);
        through = mix(1.0, 0.35, crown_k);
    }
    var c = shade_sh(albedo, n, i.world, wrap, ao, sh) * mix(1.0, ao * 0.4 + 0.6, leafy);
    if (leafy > 0.5) {
        // leaves are translucent: the side facing away from the sun glows with transmitted,
        // yellower light (a thin-leaf transmittance of ~0.3 of the sunlight), so crowns seen from
        // below or against the sun are not black
        let back = max(-dot(n, g.sun_dir.xyz), 0.0);
        let trans = albedo * vec3<f32>(1.1, 1.15, 0.6) * g.sun_color.rgb * (0.3 * back * light_sh(sh0) * through * sun_gain());
        c = c + trans * ao;
    }
    // trees on the faded surroundings dissolve into the sky with their ground
    return vec4<f32>(surroundings_fade(fog(c, i.world), i.world, i.info.z), 1.0);
}

@vertex
fn vs_tree(v: TreeIn) -> TreeOut {
    return tree_vertex(v, 1.0);
}

@vertex
fn vs_tree_shadow(v: TreeIn) -> TreeOut {
    return tree_vertex(v, 1.0);
}

@fragment
fn fs_tree_shadow(i: TreeOut) {
    if (!keep(i) || !card_kept(i)) {
        discard;
    }
    var leafy = i.mat_s.x > 0.5;
    if (i.mat_s.x > 1.5) {
        let c = carve(i, 0.0);
        if (c.kind == 0u) {
            discard;
        }
        leafy = c.kind == 1u;
    }
    if (leafy && foliage(i, twig_density(i)) == 0u) {
        discard;
    }
}
