// Structs and helpers of the caustics-volume passes (seed 000), shared by the compute module
// (propagate.wgsl) and the raster module (raster.wgsl). Layouts are written by
// src/render/volume/gpu.rs.

// A volume (uniform, 176 bytes).
struct VolParams {
    centre: vec4<f32>,    // xyz centre (world), w scene scale (m)
    axis0: vec4<f32>,     // local x axis (world, unit), w half extent (m)
    axis1: vec4<f32>,
    axis2: vec4<f32>,
    lay: vec4<u32>,       // entry axis e, lateral j, lateral k, 1 when the entry face is negative
    dims: vec4<u32>,      // slab G-buffer side, projector side, tile side (texels), seed
    counts: vec4<u32>,    // photon capacity, slabs, exit-face mask (bit per face code), photons seeded
    splat: vec4<f32>,     // overlap, max anisotropy, spread, flux scale (progressive mode)
    bounds_lo: vec4<f32>, // scene box (world), for the projector march; w density photons
    bounds_hi: vec4<f32>,
    // This frame's ranges of the trace list (level 0's live list): start and count entering
    // slab 0, start and count the projectors march (src/volume/progressive.rs).
    progress: vec4<u32>,
}

// One probe: a slab's G_near / G_far or a projector (uniform, dynamic offset, 256-byte stride).
struct VolStep {
    clip_from_world: mat4x4<f32>,
    plane: vec4<f32>,     // stored depth = dot(plane.xyz, p) + plane.w
    info: vec4<u32>,      // slab index or face code (6: photons deposited inside), layer, 0, 0
}

// A photon (64 bytes): the seed's table 2 (tile lives in the hit record).
struct VolPhoton {
    pos: vec4<f32>,    // world position, w path length since the last specular event (m)
    dir: vec4<f32>,    // world unit direction, w bitcast flags
    flux: vec4<f32>,   // rgb flux (lm), w total path length inside the volume (m)
    normal: vec4<f32>, // normal of the last surface hit, w length travelled in the current medium
}

// A photon on its receiver (64 bytes); zero flux: nothing to draw.
struct VolHit {
    pos: vec4<f32>,    // world, w path length since the last specular event
    normal: vec4<f32>, // receiver normal facing the photon, w receiver area of its texel (m^2)
    dir: vec4<f32>,    // world direction, w bitcast set and texel (vol_pack_texel)
    flux: vec4<f32>,   // rgb flux (lm)
}

const F_MEDIUM: u32 = 1u;       // P_med: inside a dielectric
const F_CONTRIB: u32 = 2u;      // changed direction at a specular surface
const F_TERMINATED: u32 = 4u;
// (flags >> 4) & 15: how the photon ended.
const END_ALIVE: u32 = 0u;
// 1 + face code: left through that face (an exit face).
const END_DEPOSIT: u32 = 8u;    // contributive photon stopped on a diffuse surface inside
const END_GONE: u32 = 9u;       // absorbed, culled, or not contributive

const MAT_DIFFUSE: u32 = 0u;
const MAT_DIELECTRIC: u32 = 1u;
const MAT_CONDUCTOR: u32 = 2u;

// Counter words (after the per-level live counts; `VOLUME_COUNTERS` in passes.rs).
const CNT: u32 = 72u;
const C_ENTERED: u32 = 0u;     // f32 bits: luminous flux seeded (written by the CPU)
const C_SPLATTED: u32 = 1u;    // f32 bits: luminous flux of the photons given a receiver
const C_HITS: u32 = 2u;        // photons given a receiver beyond an exit face
const C_DEPOSITS: u32 = 3u;    // photons stopped on a diffuse surface inside
const C_MISSED: u32 = 4u;      // contributive photons whose projector found no receiver
const C_CULLED: u32 = 5u;      // contributive photons through a culling face
const C_TIR: u32 = 6u;
const C_NAN: u32 = 7u;         // non-finite states caught
const C_BACKWARD: u32 = 8u;    // photons leaving a slab towards the entry face
const C_SPECULAR_OUT: u32 = 9u; // projector hits on specular receivers (not drawn)
const C_STEP_LIMIT: u32 = 10u; // marches stopped by the step limit
const C_REFRACTED: u32 = 11u;
const C_REFLECTED: u32 = 12u;
const C_IGNORED: u32 = 13u;    // transmissive hits the media rules ignored
const C_ABSORBED: u32 = 14u;   // non-contributive photons stopped on diffuse surfaces
const C_LEFT_INSIDE: u32 = 15u; // photons leaving the volume still inside a dielectric (P_med)
const C_LEFT_INSIDE_LM: u32 = 16u; // f32 bits: their luminous flux
const C_HOP_LIMIT_LM: u32 = 17u; // f32 bits: luminous flux of the photons the slab-hop cap stopped

// Density tiles (section 3.4's grid, made adaptive). Each of the 7 sets (the 6 projector faces,
// then the deposits on the slab texel grid) holds levels of tiles, coarsest first: side
// T = dims.z texels, then T / 2, T / 4, .. down to 1 texel, each level as large as the larger
// G-buffer needs. A hit counts in every level; its splat takes the density of the finest tile
// holding at least `bounds_lo.w` photons (`CausticsVolume::density_photons`).
fn vol_tile_levels() -> u32 {
    return firstLeadingBit(max(vp.dims.z, 1u)) + 1u;
}

fn vol_tile_side(l: u32) -> u32 {
    return max(vp.dims.z >> l, 1u);
}

fn vol_tiles_per_row(res: u32, side: u32) -> u32 {
    return (res + side - 1u) / side;
}

fn vol_level_words(l: u32) -> u32 {
    let t = vol_tiles_per_row(max(vp.dims.x, vp.dims.y), vol_tile_side(l));
    return t * t;
}

fn vol_set_words() -> u32 {
    var s = 0u;
    for (var l = 0u; l < vol_tile_levels(); l += 1u) {
        s += vol_level_words(l);
    }
    return s;
}

// The tile of `texel` in level `l` of set `tset` (set 6, the deposits, on the slab grid).
fn vol_tile_index(tset: u32, l: u32, texel: vec2<u32>) -> u32 {
    var o = tset * vol_set_words();
    for (var m = 0u; m < l; m += 1u) {
        o += vol_level_words(m);
    }
    let side = vol_tile_side(l);
    let per_row = vol_tiles_per_row(select(vp.dims.y, vp.dims.x, tset == 6u), side);
    return o + (texel.y / side) * per_row + texel.x / side;
}

// A hit's set and texel in one word: set in bits 0-2, x in 3-16, y in 17-30.
fn vol_pack_texel(tset: u32, texel: vec2<u32>) -> u32 {
    return tset | (min(texel.x, 16383u) << 3u) | (min(texel.y, 16383u) << 17u);
}

fn vol_unpack_set(code: u32) -> u32 {
    return code & 7u;
}

fn vol_unpack_texel(code: u32) -> vec2<u32> {
    return vec2((code >> 3u) & 16383u, (code >> 17u) & 16383u);
}

fn vol_axis(i: u32) -> vec3<f32> {
    if i == 0u {
        return vp.axis0.xyz;
    }
    if i == 1u {
        return vp.axis1.xyz;
    }
    return vp.axis2.xyz;
}

fn vol_half() -> vec3<f32> {
    return vec3(vp.axis0.w, vp.axis1.w, vp.axis2.w);
}

fn vol_local(p: vec3<f32>) -> vec3<f32> {
    let d = p - vp.centre.xyz;
    return vec3(dot(d, vp.axis0.xyz), dot(d, vp.axis1.xyz), dot(d, vp.axis2.xyz));
}

fn vol_local_dir(d: vec3<f32>) -> vec3<f32> {
    return vec3(dot(d, vp.axis0.xyz), dot(d, vp.axis1.xyz), dot(d, vp.axis2.xyz));
}

fn vol_world(q: vec3<f32>) -> vec3<f32> {
    return vp.centre.xyz + q.x * vp.axis0.xyz + q.y * vp.axis1.xyz + q.z * vp.axis2.xyz;
}

fn vol_world_dir(q: vec3<f32>) -> vec3<f32> {
    return q.x * vp.axis0.xyz + q.y * vp.axis1.xyz + q.z * vp.axis2.xyz;
}

fn vol_finite3(v: vec3<f32>) -> bool {
    return all(v == v) && all(abs(v) <= vec3(3.0e38));
}

// Twin of projector_texel_area (src/volume/splat.rs).
fn vol_texel_area(z: f32, half_axis: f32, half_a: f32, half_b: f32, res: u32, ray: vec3<f32>, axis: vec3<f32>, normal: vec3<f32>) -> f32 {
    let r = f32(max(res, 1u));
    let hi = max(half_axis, 1e-9);
    let plane = (2.0 * half_a * z / (hi * r)) * (2.0 * half_b * z / (hi * r));
    let a = plane * abs(dot(ray, axis)) / max(abs(dot(ray, normal)), 1e-3);
    if !(abs(a) <= 3.0e38) {
        return 0.0;
    }
    return max(a, 0.0);
}

// Twin of volume_splat_axes (src/volume/splat.rs): the two semi-axes.
fn vol_splat_axes(dir: vec3<f32>, normal: vec3<f32>, area_per_photon: f32, overlap: f32, path_length: f32, spread: f32, max_anisotropy: f32, r_min_in: f32) -> mat2x3<f32> {
    var n = vec3(0.0, 1.0, 0.0);
    let nl = length(normal);
    if nl > 0.0 && nl <= 3.0e38 {
        n = normal / nl;
    }
    var r_min = 1e-9;
    if abs(r_min_in) <= 3.0e38 {
        r_min = max(r_min_in, 1e-9);
    }
    let want = sqrt(max(overlap, 0.0) * max(area_per_photon, 0.0) / OPTICS_PI);
    var cap = max(max(spread, 0.0) * max(path_length, 0.0), r_min);
    if !(cap <= 3.0e38) {
        cap = r_min;
    }
    var r = r_min;
    if want <= 3.0e38 {
        r = clamp(want, r_min, cap);
    }
    var d = vec3(0.0);
    let dl = length(dir);
    if vol_finite3(dir) && dl > 0.0 && dl <= 3.0e38 {
        d = dir / dl;
    }
    let proj = d - n * dot(d, n);
    let pl = length(proj);
    var t1: vec3<f32>;
    var t2: vec3<f32>;
    if pl > 1e-4 && pl <= 3.0e38 {
        t1 = proj / pl;
        t2 = normalize(cross(n, t1));
    } else {
        let b = optics_orthonormal_basis(n);
        t1 = b[0];
        t2 = b[1];
    }
    let c = abs(dot(d, n));
    var max_a = 1.0;
    if max_anisotropy <= 3.0e38 {
        max_a = max(max_anisotropy, 1.0);
    }
    var stretch = max_a;
    if c > 0.0 {
        stretch = clamp(1.0 / c, 1.0, max_a);
    }
    let s = sqrt(stretch);
    return mat2x3<f32>(t1 * (r * s), t2 * (r / s));
}
