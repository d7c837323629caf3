// Cascaded image-space photon tracing (seed 003 sections 3.1 to 3.3): `trace` starts photons
// at R2 sample points of a light's caster-front RSM layer, reflects or refracts them
// (Fresnel as a probability, Beer-Lambert inside media, a second refraction at the
// caster-back layer), marches them through the light's opaque depth, reprojects the end into
// the camera (plane / concave / convex), marches on in the camera's depth, tests the normal
// and adds E = Φ / A_p (the exact pixel footprint) to the photon map in 64-bit fixed point.
// `resolve` turns the photon map into irradiance (lux) and clears it, and stores the view's
// depth and normal for the denoiser. Concatenated after optics.wgsl and
// gbuffer.wgsl by pipelines.rs.

struct SpaceView {
    clip_from_view: mat4x4<f32>,
    view_from_clip: mat4x4<f32>,
    view_from_world: mat4x4<f32>,
    world_from_view: mat4x4<f32>,
    size: vec4<f32>,  // width, height (pixels or texels), f_x, f_y (pixels)
    eye: vec4<f32>,   // xyz eye (orthographic: the view's origin), w: near distance, 0 orthographic
}

struct IsParams {
    camera: SpaceView,
    prev_clip_from_world: mat4x4<f32>,
    frame: vec4<u32>,   // frame, rotation x, rotation y, flags (FLAG_*)
    knobs: vec4<f32>,   // thickness, luminance cutoff, scene scale (m), stride (texels)
    svgf: vec4<f32>,    // alpha colour, alpha moments, history cap, sigma_z
    svgf2: vec4<f32>,   // sigma_n, sigma_l, internal events (ImageSpaceSettings), 0
    hiz: vec4<u32>,     // camera levels, RSM levels, words per RSM plane, first RSM plane's word
    cam_mips: array<vec4<u32>, 4>,  // word offset of camera level L (L < 16)
    rsm_mips: array<vec4<u32>, 4>,  // word offset of RSM level L within a plane
}

struct IsLight {
    view: SpaceView,
    flux: vec4<f32>,    // rgb: photon flux before the texel's cos^3 and spot factors; w: photons
    spot: vec4<f32>,    // xyz spot axis, w: cos inner
    misc: vec4<f32>,    // cos outer, kind (0 dir, 1 point, 2 spot), RSM side, first layer
    cube: vec4<f32>,    // this cube face (+X, -X, +Y, -Y, +Z, -Z; -1: one map), entry of face 0
}

// An entry of the lights buffer read whole (LIGHT_STRIDE, 512 bytes).
struct IsLightSlot {
    l: IsLight,
    pad: array<vec4<f32>, 10>,
}

const FLAG_DENOISE: u32 = 1u;
const FLAG_RESET: u32 = 2u;
const FLAG_HISTORY: u32 = 4u;   // the pass writes the colour history (step uniform)
const FLAG_LAST: u32 = 8u;      // the pass writes the caustics buffer (step uniform)
const FLAG_HIZ: u32 = 16u;      // the marches use the nearest-depth pyramids
const FLAG_STILL_VIEW: u32 = 32u; // the camera did not move: SVGF's colour mean has no floor

@group(0) @binding(0) var<uniform> params: IsParams;
@group(0) @binding(1) var<uniform> light: IsLight;
@group(0) @binding(2) var rsm: texture_2d_array<f32>;
@group(0) @binding(3) var view_depth: texture_depth_2d;
@group(0) @binding(4) var gbuffer: texture_2d<u32>;
@group(0) @binding(5) var<storage, read> mats: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> map: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(8) var src_a: texture_2d<f32>;
@group(0) @binding(9) var src_b: texture_2d<f32>;
@group(0) @binding(10) var src_c: texture_2d<f32>;
@group(0) @binding(11) var src_d: texture_2d<f32>;
@group(0) @binding(12) var out_a: texture_storage_2d<rgba32float, write>;
@group(0) @binding(13) var out_b: texture_storage_2d<rgba32float, write>;
@group(0) @binding(14) var out_c: texture_storage_2d<rgba32float, write>;
@group(0) @binding(16) var<storage, read_write> hiz: array<f32>;
@group(0) @binding(15) var<uniform> pass_step: vec4<u32>;  // step (px), flags (FLAG_*), iteration, 0
@group(0) @binding(17) var<storage, read> faces: array<IsLightSlot>;  // every light's entry

// The light view the light-space marches step in, and its first RSM layer: the dispatch's
// light, or the cube face a mirror chain has moved into (`enter_face_of`).
var<private> face_view: SpaceView;
var<private> face_base: u32;

// Counter words (`IMAGE_SPACE_COUNTERS` in src/render/image_space/passes.rs).
const C_EMITTED: u32 = 0u;      // samples on a caster texel, traced
const C_EMPTY: u32 = 1u;        // samples on a texel without a caster
const C_DIM: u32 = 2u;          // samples under the luminance cutoff
const C_LIGHT_HITS: u32 = 3u;   // light-space marches that ended on a receiver
const C_LIGHT_MISSES: u32 = 4u; // light-space marches that left the map
const C_PLANE: u32 = 5u;
const C_CONCAVE: u32 = 6u;
const C_CONVEX: u32 = 7u;
const C_CAMERA_HITS: u32 = 8u;  // photons deposited
const C_MISSES: u32 = 9u;       // photons lost: off screen or no surface found
const C_NORMAL: u32 = 10u;      // normal-test rejects
const C_TIR: u32 = 11u;         // total internal reflections inside a caster (followed)
const C_CLAMPED: u32 = 12u;     // fixed-point words clamped
const C_NAN: u32 = 13u;         // non-finite states caught
const C_INSIDE: u32 = 14u;      // photons that landed inside a medium (no back face on the way)
const C_CAMERA_DIRECT: u32 = 15u; // deposits straight from the light march (plane case)
const C_TRAPPED: u32 = 16u;     // photons inside a caster not followed out (event cap, silhouette)
const C_MIRROR_CHAIN: u32 = 17u; // reflections off a further mirror after a caster's outside reflected
const C_MIRROR_CAP: u32 = 18u;   // photons still meeting a mirror after MIRROR_EVENTS of them (dropped)

// Further mirror reflections followed after a reflection off a caster's outside (the light's
// caster-front layer marched): a bulb inside the mirror `ring` sends 10.2 % of its caustic
// through two (the CPU reference with 1 specular event against 256), none through three.
const MIRROR_EVENTS: u32 = 4u;

const FIXED_SCALE: f32 = 256.0;  // FIXED_POINT_SCALE in src/optics/image_space.rs

fn finite3(v: vec3<f32>) -> bool {
    return all(v == v) && all(abs(v) <= vec3(3.0e38));
}

// Pixel (x right, y down) of an NDC point.
fn ndc_to_px(ndc: vec2<f32>, size: vec2<f32>) -> vec2<f32> {
    return vec2((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * size;
}

fn px_to_ndc(px: vec2<f32>, size: vec2<f32>) -> vec2<f32> {
    let uv = px / size;
    return vec2(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
}

// The world point of view v at pixel `px` and view depth `z` (> 0).
fn unproject(v: SpaceView, px: vec2<f32>, z: f32) -> vec3<f32> {
    let ndc = px_to_ndc(px, v.size.xy);
    // Two finite depths for orthographic, perspective and infinite reverse-Z projections.
    let a = v.view_from_clip * vec4(ndc, 0.5, 1.0);
    let b = v.view_from_clip * vec4(ndc, 1.0, 1.0);
    let pa = a.xyz / a.w;
    let pb = b.xyz / b.w;
    let s = (-z - pa.z) / (pb.z - pa.z);
    let pv = mix(pa, pb, s);
    return (v.world_from_view * vec4(pv, 1.0)).xyz;
}

// The camera's view depth at pixel p (-1 where nothing was drawn).
fn camera_depth(p: vec2<i32>) -> f32 {
    let d = textureLoad(view_depth, p, 0);
    if !(d > 0.0) {
        return -1.0;
    }
    let ndc = px_to_ndc(vec2<f32>(p) + 0.5, params.camera.size.xy);
    let v = params.camera.view_from_clip * vec4(ndc, d, 1.0);
    let z = -v.z / v.w;
    return select(-1.0, z, z > 0.0 && z <= 3.0e38);
}

fn gbuffer_normal(p: vec2<i32>) -> vec4<f32> {
    return gbuffer_decode_normal(textureLoad(gbuffer, p, 0));
}

fn rsm_normal(t: vec4<f32>) -> vec3<f32> {
    let z = sqrt(max(1.0 - t.y * t.y - t.z * t.z, 0.0));
    return normalize(vec3(t.y, t.z, select(-z, z, t.w > 0.0)));
}

// Depth of the surface under pixel p in a march: mode 0 the camera; 1 the light's opaque
// layer; 2 the light's caster-back layer; 3 its caster-front layer (no Hi-Z pyramid: marched
// linearly only). -1 where there is none.
fn scene_depth(mode: u32, p: vec2<i32>) -> f32 {
    if mode == 0u {
        return camera_depth(p);
    }
    let layer = i32(face_base) + select(select(0, 2, mode == 2u), 1, mode == 3u);
    let t = textureLoad(rsm, p, layer, 0);
    return select(-1.0, t.x, t.w != 0.0);
}

#ifdef TRACE_DIELECTRICS
// Where a photon inside a closed caster meets it again (optics_inside_layers) or a receiver.
const IN_VIEW_LEFT: u32 = 0u;   // left the light's view (or t_max) still inside
const IN_BACK: u32 = 1u;        // a surface facing away from the light
const IN_FRONT: u32 = 2u;       // a surface facing the light
const IN_LOST: u32 = 3u;        // a silhouette or another caster's layers: cannot follow
const IN_RECEIVER: u32 = 4u;    // a receiver inside the medium (a pool's floor)

// The inside march steps as on a map of this side (`march_inside`).
const INSIDE_STEP_BASE: f32 = 256.0;

struct InsideHit {
    kind: u32,
    pos: vec3<f32>,
    px: vec2<i32>,
}

// Depth of caster layer `layer` (1 front, 2 back) of the light at texel p if instance `inst`
// drew it there, else -1.
fn own_layer_depth(p: vec2<i32>, layer: i32, inst: u32) -> f32 {
    let t = textureLoad(rsm, p, i32(light.misc.w) + layer, 0);
    let own = t.w != 0.0 && u32(abs(t.w)) - 1u == inst;
    return select(-1.0, t.x, own);
}

// From o inside caster `inst` along d: march the light's depth (linear steps, as `march`)
// until the photon leaves the interval between the caster's front and back layers, or
// crosses the opaque layer (a receiver in the medium), refined by eq. 2 on the layer crossed.
fn march_inside(v: SpaceView, inst: u32, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> InsideHit {
    var h: InsideHit;
    h.kind = IN_VIEW_LEFT;
    h.pos = o;
    h.px = vec2(-1);
    let g = project_segment(v, o, d, t_max);
    if !g.ok {
        return h;
    }
    let size = vec2<i32>(v.size.xy);
    // The step of a 256-texel map at any map side: the layers' depths are exact at every step
    // and the crossing is refined between two, so finer steps add little. Gem room, 1024²
    // maps, 64 internal events, lavapipe: texel steps 3558 ms trace, energy -9.2 %; these
    // 1113 ms, -8.1 %.
    let n = segment_steps_flat(g, max(params.knobs.w, v.size.x / INSIDE_STEP_BASE));
    var s_prev = g.a;
    var zr_prev = segment_depth(g, g.a);
    var p = vec2<i32>(floor(mix(g.s0, g.s1, g.a)));
    var zs_prev = vec3(own_layer_depth(p, 1, inst), own_layer_depth(p, 2, inst), scene_depth(1u, p));
    var p_prev = p;
    for (var i = 1u; i <= n; i += 1u) {
        let s = mix(g.a, g.b, f32(i) / f32(n));
        let zr = segment_depth(g, s);
        p = clamp(vec2<i32>(floor(mix(g.s0, g.s1, s))), vec2(0), size - 1);
        // Front, back and opaque depth under the step.
        let zs = vec3(own_layer_depth(p, 1, inst), own_layer_depth(p, 2, inst), scene_depth(1u, p));
        var kind = optics_inside_layers(zr, zs.x, zs.y);
        if zs.z > 0.0 && zr >= zs.z && (zs.y <= 0.0 || zs.z <= zs.y) && (kind == 0u || kind == IN_LOST) {
            // A receiver inside the medium (a pool's floor) before any way out.
            kind = IN_RECEIVER;
        } else if kind == IN_LOST && zs_prev.x > 0.0 && zs_prev.y > 0.0 {
            // Across the silhouette: the glass it met stands nearly along the light, between
            // the last texel's layers; take the layer nearer the photon there, and its normal.
            kind = select(IN_FRONT, IN_BACK, zs_prev.y - zr_prev < zr_prev - zs_prev.x);
            h.kind = kind;
            h.pos = segment_point(v, g, s_prev);
            h.px = p_prev;
            return h;
        }
        let k = select(select(0, 1, kind == IN_BACK), 2, kind == IN_RECEIVER);
        if kind != 0u {
            let u = optics_march_crossing(zr_prev, zr, select(zs[k], zs_prev[k], zs_prev[k] > 0.0), zs[k]);
            h.kind = kind;
            h.pos = segment_point(v, g, mix(s_prev, s, select(u, 1.0, kind == IN_LOST)));
            h.px = p;
            return h;
        }
        s_prev = s;
        zr_prev = zr;
        zs_prev = zs;
        p_prev = p;
    }
    h.pos = segment_point(v, g, g.b);
    h.px = p;
    return h;
}
#endif

// Camera pixel and view depth of a world point (px.x < 0 when behind the camera).
fn camera_project(x: vec3<f32>) -> vec3<f32> {
    let h = params.camera.clip_from_view * (params.camera.view_from_world * vec4(x, 1.0));
    if !(h.w > 0.0) {
        return vec3(-1.0, -1.0, -1.0);
    }
    let px = ndc_to_px(h.xy / h.w, params.camera.size.xy);
    let z = -(params.camera.view_from_world * vec4(x, 1.0)).z;
    return vec3(px, z);
}

fn add_word(at: u32, w: u32) {
    let old = atomicAdd(&map[at], w);
    if old + w < old {
        atomicAdd(&map[at + 1u], 1u);
    }
}

// E = Φ / A_p at the camera pixel holding x, after the normal test; 64-bit fixed point.
fn deposit(x: vec3<f32>, d: vec3<f32>, flux: vec3<f32>, seed: u32) {
    let c = camera_project(x);
    let size = params.camera.size.xy;
    if c.x < 0.0 || c.y < 0.0 || c.x >= size.x || c.y >= size.y {
        atomicAdd(&counters[C_MISSES], 1u);
        return;
    }
    let p = vec2<i32>(floor(c.xy));
    let n = gbuffer_normal(p);
    if n.w == 0.0 {
        atomicAdd(&counters[C_MISSES], 1u);
        return;
    }
    if dot(-d, n.xyz) < 0.0 {
        atomicAdd(&counters[C_NORMAL], 1u);
        return;
    }
    let eye = params.camera.eye.xyz;
    let to = x - eye;
    let dist = length(to);
    let forward = -normalize(params.camera.world_from_view[2].xyz);
    let cos_alpha = dot(to / dist, forward);
    let cos_surface = dot(n.xyz, -to / dist);
    let area = optics_pixel_footprint_area(dist, cos_alpha, cos_surface, params.camera.size.zw);
    let e = flux / area;
    if !(area > 0.0) || !finite3(e) {
        atomicAdd(&counters[C_NAN], 1u);
        return;
    }
    let base = 6u * (u32(p.y) * u32(size.x) + u32(p.x));
    for (var ch = 0u; ch < 3u; ch += 1u) {
        let w = optics_fixed_point_word(e[ch], FIXED_SCALE, optics_hash_unit(seed, ch + 11u));
        if w.y != 0u {
            atomicAdd(&counters[C_CLAMPED], 1u);
        }
        if w.x != 0u {
            add_word(base + 2u * ch, w.x);
        }
    }
    atomicAdd(&counters[C_CAMERA_HITS], 1u);
}

// From a point x in flight along d: the cascade's camera stage (section 3.2).
fn camera_stage(x: vec3<f32>, d: vec3<f32>, flux: vec3<f32>, light_hit: bool, seed: u32, t_max: f32) {
    let c = camera_project(x);
    let size = params.camera.size.xy;
    let on_screen = c.x >= 0.0 && c.y >= 0.0 && c.x < size.x && c.y < size.y;
    if on_screen {
        let zs = camera_depth(vec2<i32>(floor(c.xy)));
        let kind = optics_classify_reprojection(c.z, zs, params.knobs.x);
        if zs > 0.0 {
            atomicAdd(&counters[C_PLANE + kind], 1u);
        }
        if kind == 0u && zs > 0.0 && light_hit {
            atomicAdd(&counters[C_CAMERA_DIRECT], 1u);
            deposit(x, d, flux, seed);
            return;
        }
        if kind == 2u && zs > 0.0 {
            return;
        }
    }
    // Second chance: march the camera's depth from x.
    let m = march(params.camera, 0u, x, d, t_max);
    if !m.hit {
        atomicAdd(&counters[C_MISSES], 1u);
        return;
    }
    deposit(m.pos, d, flux, seed);
}

#ifdef TRACE_DIELECTRICS
// Through a thin wall (air on both sides, no bending) from `o` along `d`: the far wall of a
// closed thin shell (the caster-back layer, nearer than any receiver) passes `1 - F` again,
// 1 / ior, straight (the thick exit's rule: the reflected part is dropped). A single sheet lit
// on its back is its own back layer at the start texel (same instance, same depth): nothing
// more. Returns the ray's new origin.
fn thin_far_wall(v: SpaceView, texel: vec2<i32>, front: vec4<f32>, inst: u32, o: vec3<f32>, d: vec3<f32>, flux: ptr<function, vec3<f32>>, t_max: f32, scale: f32) -> vec3<f32> {
    let own = textureLoad(rsm, texel, i32(light.misc.w) + 2, 0);
    if own.w != 0.0 && u32(abs(own.w)) - 1u == inst && abs(own.x - front.x) <= 1.0e-4 * max(abs(front.x), 1.0) {
        return o;
    }
    let to_back = march(v, 2u, o, d, t_max);
    if !to_back.hit {
        return o;
    }
    let to_floor = march(v, 1u, o, d, t_max);
    if to_floor.hit && distance(o, to_floor.pos) <= distance(o, to_back.pos) {
        return o;
    }
    let back = textureLoad(rsm, to_back.px, i32(light.misc.w) + 2, 0);
    if back.w == 0.0 {
        return o;
    }
    let mb = mats[3u * (u32(abs(back.w)) - 1u)];
    if mb.z <= 0.5 {
        return o;  // a thick object's back face: its front was never crossed
    }
    let nb = rsm_normal(back);
    *flux *= 1.0 - optics_fresnel_dielectric(abs(dot(d, nb)), optics_dielectric_eta(mb.y, true, true));
    // The far wall's transmission tint (row 2; white for clear glass).
    *flux *= mats[3u * (u32(abs(back.w)) - 1u) + 2u].xyz;
    return optics_offset_ray_origin(to_back.pos, select(nb, -nb, dot(d, nb) < 0.0), scale);
}
#endif

#ifdef TRACE_CASTER_CHAINS
// Switch the marches to the face of the dispatch's cube that holds x (a light with one map:
// nothing). Returns whether the face changed.
fn enter_face_of(x: vec3<f32>) -> bool {
    if light.cube.x < 0.0 {
        return false;
    }
    let r = x - light.view.eye.xyz;
    let a = abs(r);
    var f = select(4u, 5u, r.z < 0.0);
    if a.x >= a.y && a.x >= a.z {
        f = select(0u, 1u, r.x < 0.0);
    } else if a.y >= a.z {
        f = select(2u, 3u, r.y < 0.0);
    }
    let entry = u32(light.cube.y) + f;
    if 3u * entry == face_base || entry >= arrayLength(&faces) {
        return false;
    }
    face_view = faces[entry].l.view;
    face_base = 3u * entry;
    return true;
}

// Where a photon that reflected off a caster's outside ends: its march through the light's
// opaque layer, unless the light's caster-front layer holds a mirror before that receiver,
// met from its front (a crossing the ray leaves from, at its own start, is stepped over):
// there it reflects (Schlick with the mirror's F0) and marches on, up to MIRROR_EVENTS times
// (the photon is dropped, and counted, if it meets one more). A ray that leaves a cube face's
// view before a receiver or a mirror goes on in the face it enters (a ring's second mirror
// often lies in another face). A dielectric met there is passed, as before: one event on a
// caster's outside. `dropped` ends the photon.
struct ChainEnd {
    m: MarchResult,
    dropped: bool,
}

fn mirror_chain(o_in: vec3<f32>, d: ptr<function, vec3<f32>>, flux: ptr<function, vec3<f32>>, t_max: f32, scale: f32) -> ChainEnd {
    var end: ChainEnd;
    end.dropped = false;
    var o = o_in;
    var leg = o_in;
    var events = 0u;
    for (var guard = 0u; guard < 4u * MIRROR_EVENTS + 8u; guard += 1u) {
        let left = t_max - distance(leg, o);
        end.m = march(face_view, 1u, o, *d, left);
        let reach = select(left, distance(o, end.m.pos), end.m.hit);
        if reach <= 0.0 {
            return end;
        }
        let c = march_front(face_view, o, *d, reach);
        if !c.hit {
            // Left this face's view first: on in the face the ray enters.
            let past = c.pos + *d * (1.0e-4 * scale);
            if !end.m.hit && distance(o, c.pos) < 0.999 * reach && enter_face_of(past) {
                o = past;
                continue;
            }
            return end;
        }
        let t = textureLoad(rsm, c.px, i32(face_base) + 1, 0);
        let nc = rsm_normal(t);
        if t.w == 0.0 || dot(*d, nc) >= 0.0 {
            // Leaving a surface (the ray's own start), not meeting one: step past it.
            o = c.pos + *d * (1.0e-3 * scale);
            continue;
        }
        let ci = u32(abs(t.w)) - 1u;
        if bitcast<u32>(mats[3u * ci].x) != 2u {
            return end;
        }
        if events == MIRROR_EVENTS {
            atomicAdd(&counters[C_MIRROR_CAP], 1u);
            end.dropped = true;
            return end;
        }
        events += 1u;
        atomicAdd(&counters[C_MIRROR_CHAIN], 1u);
        *flux *= optics_fresnel_schlick(abs(dot(*d, nc)), mats[3u * ci + 2u].xyz);
        *d = optics_reflect(*d, nc);
        o = optics_offset_ray_origin(c.pos, select(nc, -nc, dot(*d, nc) < 0.0), scale);
        leg = o;
    }
    return end;
}
#endif

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 64u + gid.x;
    let photons = u32(light.flux.w);
    if i >= photons {
        return;
    }
    face_view = light.view;
    face_base = u32(light.misc.w);
    let res = light.misc.z;
    let uv = optics_r2_point(i, params.frame.yz);
    let texel = vec2<i32>(min(uv * res, vec2(res - 1.0)));
    let front = textureLoad(rsm, texel, i32(light.misc.w) + 1, 0);
    if front.w == 0.0 {
        atomicAdd(&counters[C_EMPTY], 1u);
        return;
    }
    let v = light.view;
    let p = unproject(v, uv * res, front.x);
    var dir_in = -normalize(v.world_from_view[2].xyz);
    var flux = light.flux.rgb;
    if v.eye.w > 0.0 {
        dir_in = normalize(p - v.eye.xyz);
        // Texel solid angle cos^3(alpha) / (f_x f_y) (f in the flux) and the spot cone.
        let cos_a = max(dot(dir_in, -normalize(v.world_from_view[2].xyz)), 0.0);
        var f = cos_a * cos_a * cos_a;
        if light.misc.y > 1.5 {
            f *= optics_spot_attenuation(dot(dir_in, light.spot.xyz), light.spot.w, light.misc.x);
        }
        if f < params.knobs.y {
            atomicAdd(&counters[C_DIM], 1u);
            return;
        }
        flux *= f;
    }
    if !finite3(p) || !finite3(dir_in) {
        atomicAdd(&counters[C_NAN], 1u);
        return;
    }
    atomicAdd(&counters[C_EMITTED], 1u);
    let seed = optics_pcg_hash(i ^ optics_pcg_hash(params.frame.x * 0x9E3779B9u + u32(light.misc.w)));
    let inst = u32(abs(front.w)) - 1u;
    let m0 = mats[3u * inst];
    let kind = bitcast<u32>(m0.x);
    let n = rsm_normal(front);
    let cos_i = abs(dot(dir_in, n));
    let scale = params.knobs.z;
    let t_max = 4.0 * scale;
    var d = dir_in;
    var inside = false;
    var thin_through = false;
    var reflected = false;
    // Without a dielectric in the scene (shader def TRACE_DIELECTRICS off) every caster is a
    // mirror: no Fresnel split, refraction, caster-back march or Beer-Lambert is compiled.
#ifdef TRACE_DIELECTRICS
    if kind == 2u {
#endif
        d = optics_reflect(dir_in, n);
        flux *= optics_fresnel_schlick(cos_i, mats[3u * inst + 2u].xyz);
        reflected = true;
#ifdef TRACE_DIELECTRICS
    } else {
        // The light's first hit comes from air (the front layer): 1 / ior, thin or thick.
        let eta = optics_dielectric_eta(m0.y, true, m0.z > 0.5);
        let fr = optics_fresnel_dielectric(cos_i, eta);
        if optics_hash_unit(seed, 1u) < fr {
            d = optics_reflect(dir_in, n);
            reflected = true;
        } else if m0.z > 0.5 {
            d = dir_in;  // thin sheet: no bending
            thin_through = true;
            flux *= mats[3u * inst + 2u].xyz;  // the boundary's transmission tint
        } else {
            let t = optics_refract(dir_in, n, eta);
            d = t.xyz;
            inside = true;
            flux *= mats[3u * inst + 2u].xyz;  // the boundary's transmission tint
        }
    }
#endif
    let side = select(n, -n, dot(d, n) < 0.0);
    var o = optics_offset_ray_origin(p, side, scale);
#ifdef TRACE_DIELECTRICS
    if inside {
        // Inside the medium: the photon meets the caster's layers again, or a receiver inside
        // it (a pool's floor). Each meeting refracts out with probability 1 - F, else (and on
        // total internal reflection) reflects and goes on, up to `internal_events` times.
        let atten = mats[3u * inst + 1u].xyz;
        let events = u32(params.svgf2.z);
        for (var e = 0u; ; e += 1u) {
            let h = march_inside(v, inst, o, d, t_max);
            flux *= optics_beer_lambert(atten, m0.w, distance(o, h.pos));
            if h.kind == IN_RECEIVER {
                atomicAdd(&counters[C_INSIDE], 1u);
                atomicAdd(&counters[C_LIGHT_HITS], 1u);
                camera_stage(h.pos, d, flux, true, seed, t_max);
                return;
            }
            if h.kind == IN_VIEW_LEFT {
                // Left the light's view inside the medium: the camera may still see the rest.
                atomicAdd(&counters[C_LIGHT_MISSES], 1u);
                camera_stage(h.pos, d, flux, false, seed, t_max);
                return;
            }
            if h.kind == IN_LOST {
                atomicAdd(&counters[C_TRAPPED], 1u);
                return;
            }
            let nb = rsm_normal(textureLoad(rsm, h.px, i32(light.misc.w) + i32(h.kind == IN_BACK) + 1, 0));
            // Leaving a thick medium (only thick casters refract inside): ior.
            let eta_out = optics_dielectric_eta(m0.y, false, false);
            let t = optics_refract(d, nb, eta_out);
            var fr = 1.0;
            if t.w == 0.0 {
                atomicAdd(&counters[C_TIR], 1u);
            } else {
                fr = optics_fresnel_dielectric(abs(dot(d, nb)), eta_out);
            }
            if optics_hash_unit(seed, 20u + e) < fr {
                if e >= events {
                    atomicAdd(&counters[C_TRAPPED], 1u);
                    return;
                }
                d = optics_reflect(d, nb);
                o = optics_offset_ray_origin(h.pos, select(nb, -nb, dot(d, nb) < 0.0), scale);
                continue;
            }
            flux *= mats[3u * inst + 2u].xyz;  // the exit's transmission tint
            d = t.xyz;
            o = optics_offset_ray_origin(h.pos, select(nb, -nb, dot(d, nb) < 0.0), scale);
            break;
        }
    }
#endif
#ifdef TRACE_DIELECTRICS
    if thin_through {
        o = thin_far_wall(v, texel, front, inst, o, d, &flux, t_max, scale);
    }
#endif
    var m: MarchResult;
#ifdef TRACE_CASTER_CHAINS
    if reflected {
        let chain = mirror_chain(o, &d, &flux, t_max, scale);
        if chain.dropped {
            return;
        }
        m = chain.m;
    } else {
        m = march(v, 1u, o, d, t_max);
    }
#else
    m = march(v, 1u, o, d, t_max);
#endif
    atomicAdd(&counters[select(C_LIGHT_MISSES, C_LIGHT_HITS, m.hit)], 1u);
    camera_stage(m.pos, d, flux, m.hit, seed, t_max);
}

// The photon map in lux (out_a), cleared for the next frame; the view's depth and normal
// (out_b: view depth or -1, normal xyz) for the denoiser.
@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<u32>(params.camera.size.xy);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let base = 6u * (gid.y * size.x + gid.x);
    var e = vec3(0.0);
    for (var ch = 0u; ch < 3u; ch += 1u) {
        let lo = atomicExchange(&map[base + 2u * ch], 0u);
        let hi = atomicExchange(&map[base + 2u * ch + 1u], 0u);
        e[ch] = optics_fixed_point_value(lo, hi, FIXED_SCALE);
    }
    textureStore(out_a, p, vec4(e, 0.0));
    let z = camera_depth(p);
    let n = gbuffer_normal(p);
    textureStore(out_b, p, vec4(select(-1.0, z, n.w != 0.0), n.xyz));
}
