// Caustics-volume rasterisation (seed 000): `vs_gbuffer`/`fs_gbuffer` draw the scene's
// triangles (pulled from a storage buffer) into a slab probe's G_near / G_far or a projector's
// G-buffer: stored depth along the probe axis, normal, instance; `vs_splat`/`fs_splat` draw the
// oriented splats of the photons on their receivers into the view's volume target with a depth
// test. Concatenated after optics.wgsl and common.wgsl by src/render/volume/pipelines.rs.

@group(0) @binding(0) var<uniform> vp: VolParams;
@group(0) @binding(1) var<uniform> probe: VolStep;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;

struct ViewParams {
    clip_from_world: mat4x4<f32>,
    world_from_clip: mat4x4<f32>,
    eye: vec4<f32>,  // xyz eye, w radians per pixel (2 / (P11 height))
}
@group(0) @binding(3) var<uniform> view: ViewParams;
@group(0) @binding(4) var<storage, read> hits: array<VolHit>;
@group(0) @binding(5) var<storage, read> tiles: array<u32>;
@group(0) @binding(6) var view_depth: texture_depth_2d;

struct GOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) inst: f32,
}

// Triangle t, corner c: tris[6 t + 2 c] = (position, instance), tris[6 t + 2 c + 1] = normal.
@vertex
fn vs_gbuffer(@builtin(vertex_index) vi: u32) -> GOut {
    let t = vi / 3u;
    let c = vi % 3u;
    let p = tris[6u * t + 2u * c];
    let n = tris[6u * t + 2u * c + 1u];
    var out: GOut;
    out.pos = probe.clip_from_world * vec4(p.xyz, 1.0);
    out.world = p.xyz;
    out.normal = n.xyz;
    out.inst = p.w;
    return out;
}

@fragment
fn fs_gbuffer(in: GOut) -> @location(0) vec4<f32> {
    let depth = dot(probe.plane.xyz, in.world) + probe.plane.w;
    let l = length(in.normal);
    var n = vec3(0.0, 1.0, 0.0);
    if l > 0.0 && l <= 3.0e38 {
        n = in.normal / l;
    }
    let id = in.inst + 1.0;
    return vec4(depth, n.x, n.y, select(-id, id, n.z >= 0.0));
}

struct SOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) q: vec2<f32>,
    @location(1) world: vec3<f32>,
    @location(2) @interpolate(flat) e: vec3<f32>,
}

fn quad_corner(vi: u32) -> vec2<f32> {
    let c = array<vec2<f32>, 6>(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    return c[vi % 6u];
}

// Receiver area per photon around a hit (section 3.4's density estimate, made adaptive): the
// area of its tile over the photons in it, from the finest level whose tile holds at least
// `density photons` (bounds_lo.w), else the coarsest. `texel_area`: the hit's texel (m^2).
fn area_per_photon(code: u32, texel_area: f32) -> f32 {
    let tset = vol_unpack_set(code);
    let texel = vol_unpack_texel(code);
    let want = u32(max(vp.bounds_lo.w, 1.0));
    let levels = vol_tile_levels();
    for (var k = 0u; k < levels; k += 1u) {
        let l = levels - 1u - k;
        let n = tiles[vol_tile_index(tset, l, texel)];
        if n >= want || l == 0u {
            let side = f32(vol_tile_side(l));
            return texel_area * side * side / f32(max(n, 1u));
        }
    }
    return texel_area;
}

// Section 3.4: "quads with a circular texture ... adjusted according to the ray length and
// density estimate", oriented by the receiver normal and the projected direction.
@vertex
fn vs_splat(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> SOut {
    let h = hits[ii];
    var out: SOut;
    out.pos = vec4(2.0, 2.0, 2.0, 1.0);
    out.q = vec2(0.0);
    out.world = vec3(0.0);
    out.e = vec3(0.0);
    if all(h.flux.xyz == vec3(0.0)) || !vol_finite3(h.pos.xyz) {
        return out;
    }
    let per_photon = area_per_photon(bitcast<u32>(h.dir.w), h.normal.w);
    let dist = distance(h.pos.xyz, view.eye.xyz);
    // At least a pixel wide, so no splat falls between the pixel centres.
    let r_min = max(0.75 * dist * view.eye.w, 1e-6 * vp.centre.w);
    let ax = vol_splat_axes(h.dir.xyz, h.normal.xyz, per_photon, vp.splat.x, h.pos.w, vp.splat.z, vp.splat.y, r_min);
    let area = OPTICS_PI * length(ax[0]) * length(ax[1]);
    if !(area > 0.0) {
        return out;
    }
    let q = quad_corner(vi);
    let world = h.pos.xyz + q.x * ax[0] + q.y * ax[1];
    out.pos = view.clip_from_world * vec4(world, 1.0);
    out.q = q;
    out.world = world;
    // splat.w: progressive mode's photons / traced (1 once everything is traced).
    out.e = h.flux.xyz * vp.splat.w / area;
    return out;
}

// Visible when the splat point's distance from the eye is within 1 % of the scene's there.
fn depth_visible(frag: vec4<f32>, world: vec3<f32>) -> bool {
    let size = vec2<f32>(textureDimensions(view_depth));
    let px = vec2<i32>(clamp(floor(frag.xy), vec2(0.0), size - 1.0));
    let depth = textureLoad(view_depth, px, 0);
    let ndc = vec2((frag.x / size.x) * 2.0 - 1.0, 1.0 - (frag.y / size.y) * 2.0);
    let hw = view.world_from_clip * vec4(ndc, depth, 1.0);
    if !(abs(hw.w) > 0.0) {
        return false;
    }
    let scene = distance(hw.xyz / hw.w, view.eye.xyz);
    let here = distance(world, view.eye.xyz);
    return abs(here - scene) <= 0.01 * scene;
}

@fragment
fn fs_splat(in: SOut) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world) {
        discard;
    }
    return vec4(in.e, 0.0);
}

// The splat without float blending: the same value added in fixed point (group 1,
// src/render/fixed_splat/), nothing written to the target.
@fragment
fn fs_splat_fixed(in: SOut) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world) {
        discard;
    }
    fixed_splat_add(vec2<u32>(in.pos.xy), textureDimensions(view_depth).x, in.e);
    return vec4(0.0);
}
