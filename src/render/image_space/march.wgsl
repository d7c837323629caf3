// Image space's marches (seed 003 sections 3.1 and 3.2): the nearest-depth pyramids and their
// build pass, a world segment projected into a view, the linear and hierarchical marches
// through a view's depth, and the march that finds a further mirror in the light's
// caster-front layer. Concatenated after trace.wgsl (its bindings and `scene_depth`) by
// pipelines.rs.

// Hi-Z: nearest-depth pyramids in one buffer. Plane 0 is the camera's view depth; plane
// 1 + 2 l (2 + 2 l) light l's opaque (caster-back) layer. Empty texels hold 3e38.
const HIZ_EMPTY: f32 = 3.0e38;

fn hiz_size(plane: u32, level: u32) -> vec2<u32> {
    var size0 = vec2<u32>(params.camera.size.xy);
    if plane > 0u {
        size0 = vec2(u32(light_res()));
    }
    let step = (1u << level) - 1u;
    return max((size0 + vec2(step)) >> vec2(level), vec2(1u));
}

// The RSM side (the light uniform holds it; the camera passes read it from hiz.w's plane).
fn light_res() -> f32 {
    return light.misc.z;
}

fn hiz_offset(plane: u32, level: u32) -> u32 {
    if plane == 0u {
        return params.cam_mips[level / 4u][level % 4u];
    }
    return params.hiz.w + (plane - 1u) * params.hiz.z + params.rsm_mips[level / 4u][level % 4u];
}

fn hiz_fetch(plane: u32, level: u32, cell: vec2<i32>) -> f32 {
    let size = hiz_size(plane, level);
    let c = clamp(vec2<u32>(max(cell, vec2(0))), vec2(0u), size - 1u);
    return hiz[hiz_offset(plane, level) + c.y * size.x + c.x];
}

// One level of one plane: level 0 from the depth (camera) or the RSM layer, the others the
// minimum of 2x2 cells of the level below. pass_step = (level, plane, _, _).
@compute @workgroup_size(8, 8)
fn hiz_build(@builtin(global_invocation_id) gid: vec3<u32>) {
    let level = pass_step.x;
    let plane = pass_step.y;
    let size = hiz_size(plane, level);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let p = vec2<i32>(gid.xy);
    var z = HIZ_EMPTY;
    if level == 0u {
        if plane == 0u {
            let d = camera_depth(p);
            z = select(HIZ_EMPTY, d, d > 0.0);
        } else {
            let l = (plane - 1u) / 2u;
            let layer = i32(3u * l + select(0u, 2u, (plane - 1u) % 2u == 1u));
            let t = textureLoad(rsm, p, layer, 0);
            z = select(HIZ_EMPTY, t.x, t.w != 0.0);
        }
    } else {
        for (var k = 0; k < 4; k += 1) {
            z = min(z, hiz_fetch(plane, level - 1u, 2 * p + vec2(k & 1, k >> 1)));
        }
    }
    hiz[hiz_offset(plane, level) + gid.y * size.x + gid.x] = z;
}

struct MarchResult {
    hit: bool,
    pos: vec3<f32>,   // the crossing (hit) or the last point inside the view (miss)
    px: vec2<i32>,
    inside: bool,     // the start was inside the view
}

// A world segment projected into view v: pixel ends s0, s1, 1/w ends k0, k1 and view-space
// ends over w q0, q1 (all linear along the projected segment), and the part [a, b] of it
// whose pixel stays inside the viewport. `ok` is false when none does.
struct Segment {
    ok: bool,
    s0: vec2<f32>,
    s1: vec2<f32>,
    k0: f32,
    k1: f32,
    q0: vec3<f32>,
    q1: vec3<f32>,
    a: f32,
    b: f32,
}

// The segment from o along d (unit, world) for at most `t_max_in` metres in view v, clipped
// to the near plane and the viewport (Liang-Barsky).
fn project_segment(v: SpaceView, o: vec3<f32>, d: vec3<f32>, t_max_in: f32) -> Segment {
    var g: Segment;
    g.ok = false;
    let size = v.size.xy;
    let p0 = (v.view_from_world * vec4(o, 1.0)).xyz;
    let dv = (v.view_from_world * vec4(d, 0.0)).xyz;
    var t_max = t_max_in;
    let near = v.eye.w;
    if near > 0.0 {
        if -p0.z < near {
            return g;
        }
        // Clip to the near plane.
        if dv.z > 0.0 {
            t_max = min(t_max, (-near - p0.z) / dv.z * 0.999);
        }
    }
    let p1 = p0 + dv * t_max;
    let h0 = v.clip_from_view * vec4(p0, 1.0);
    let h1 = v.clip_from_view * vec4(p1, 1.0);
    g.k0 = 1.0 / h0.w;
    g.k1 = 1.0 / h1.w;
    g.s0 = ndc_to_px(h0.xy * g.k0, size);
    g.s1 = ndc_to_px(h1.xy * g.k1, size);
    if !(all(g.s0 == g.s0) && all(g.s1 == g.s1) && g.k0 > 0.0 && g.k1 > 0.0) {
        return g;
    }
    // Liang-Barsky: the part of [0, 1] whose pixel stays inside [0, size).
    g.a = 0.0;
    g.b = 1.0;
    let ds = g.s1 - g.s0;
    let hi = size - vec2(1.0e-3);
    for (var i = 0; i < 2; i += 1) {
        if abs(ds[i]) < 1.0e-12 {
            if g.s0[i] < 0.0 || g.s0[i] > hi[i] {
                return g;
            }
        } else {
            let ta = (0.0 - g.s0[i]) / ds[i];
            let tb = (hi[i] - g.s0[i]) / ds[i];
            g.a = max(g.a, min(ta, tb));
            g.b = min(g.b, max(ta, tb));
        }
    }
    g.q0 = p0 * g.k0;
    g.q1 = p1 * g.k1;
    g.ok = g.a <= g.b;
    return g;
}

// View depth of the segment at parameter s.
fn segment_depth(g: Segment, s: f32) -> f32 {
    return -mix(g.q0, g.q1, s).z / mix(g.k0, g.k1, s);
}

// World point of the segment at parameter s.
fn segment_point(v: SpaceView, g: Segment, s: f32) -> vec3<f32> {
    let pv = mix(g.q0, g.q1, s) / mix(g.k0, g.k1, s);
    return (v.world_from_view * vec4(pv, 1.0)).xyz;
}

// Linear steps over [a, b]: `stride` pixels each, and small enough in depth that no step
// moves the ray by more than half the thickness (a ray nearly along the view axis crosses few
// pixels but much depth, and would jump through every surface).
fn segment_steps(g: Segment) -> u32 {
    let stride = max(params.knobs.w, 1.0);
    let len = length(g.s1 - g.s0) * (g.b - g.a);
    let za = segment_depth(g, g.a);
    let zb = segment_depth(g, g.b);
    let thick = params.knobs.x;
    let n_depth = abs(zb - za) / max(0.5 * thick * max(min(za, zb), 1.0e-4), 1.0e-9);
    return u32(clamp(ceil(max(len / stride, n_depth)), 1.0, 16384.0));
}

// Steps of `stride` pixels over [a, b] with no depth limit (a march that tests an interval,
// not a thin surface, and refines the crossing on the layer between two steps).
fn segment_steps_flat(g: Segment, stride: f32) -> u32 {
    let len = length(g.s1 - g.s0) * (g.b - g.a);
    return u32(clamp(ceil(len / max(stride, 1.0)), 1.0, 16384.0));
}

// A march from o that has found nothing yet.
fn march_start(o: vec3<f32>) -> MarchResult {
    var r: MarchResult;
    r.hit = false;
    r.pos = o;
    r.px = vec2(-1);
    r.inside = false;
    return r;
}

// Perspective-correct DDA (McGuire and Mara 2014) from o along d (unit, world) for at most
// `t_max` metres through view v's depth (mode, see scene_depth): 1/w, P/w and the pixel
// position are linear along the projected segment, which is clipped to the near plane and
// the viewport; steps of `stride` pixels; a step ending behind a surface by less than
// `thickness` of its depth is a crossing, refined by eq. 2 (optics_march_crossing).
fn march(v: SpaceView, mode: u32, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> MarchResult {
    var r = march_start(o);
    let g = project_segment(v, o, d, t_max);
    if !g.ok {
        return r;
    }
    r.inside = g.a == 0.0;
    if (params.frame.w & FLAG_HIZ) != 0u {
        var plane = 0u;
        var levels = params.hiz.x;
        if mode != 0u {
            plane = 1u + 2u * (face_base / 3u) + select(0u, 1u, mode == 2u);
            levels = params.hiz.y;
        }
        return march_hiz(v, plane, levels, r, g);
    }
    return march_linear(v, mode, r, g, segment_steps(g), 0.0);
}

// `n` linear steps over segment g through view v's depth (mode, see scene_depth): a step
// that ends behind a surface by at most `thickness` of its depth plus `step_slack` times the
// step's own depth change, after one in front of it (or over nothing), is a crossing, refined
// by eq. 2 (optics_march_crossing). A miss ends at the segment's end.
fn march_linear(v: SpaceView, mode: u32, r_in: MarchResult, g: Segment, n: u32, step_slack: f32) -> MarchResult {
    var r = r_in;
    let size = v.size.xy;
    let thick = params.knobs.x;
    var s_prev = g.a;
    var zr_prev = segment_depth(g, g.a);
    var px_prev = vec2<i32>(floor(mix(g.s0, g.s1, g.a)));
    var zs_prev = scene_depth(mode, px_prev);
    for (var i = 1u; i <= n; i += 1u) {
        let s = mix(g.a, g.b, f32(i) / f32(n));
        let zr = segment_depth(g, s);
        let px = clamp(vec2<i32>(floor(mix(g.s0, g.s1, s))), vec2(0), vec2<i32>(size) - 1);
        let zs = scene_depth(mode, px);
        let slack = step_slack * abs(zr - zr_prev) + thick * zs;
        if zs > 0.0 && zr >= zs && zr - zs <= slack && (zs_prev <= 0.0 || zr_prev <= zs_prev) {
            let zsp = select(zs, zs_prev, zs_prev > 0.0);
            let u = optics_march_crossing(zr_prev, zr, zsp, zs);
            r.hit = true;
            r.pos = segment_point(v, g, mix(s_prev, s, u));
            r.px = px;
            return r;
        }
        s_prev = s;
        zr_prev = zr;
        zs_prev = zs;
        px_prev = px;
    }
    r.pos = segment_point(v, g, g.b);
    r.px = px_prev;
    return r;
}

// The hierarchical march (Uludag 2014; here a conservative variant valid for rays in any
// direction): the cell of the current level holding the ray's pixel is skipped whole when
// the ray's depth over its part of the segment (exact: depth is monotonic along it) stays in
// front of the cell's nearest surface, and the march climbs a level; otherwise it descends,
// and at level 0 tests the pixel: a hit when the ray reaches the pixel's depth inside it and
// entered no deeper than the thickness behind it (eq. 2 with a flat pixel).
fn march_hiz(v: SpaceView, plane: u32, levels: u32, r_in: MarchResult, g: Segment) -> MarchResult {
    var r = r_in;
    let s0 = g.s0;
    let s1 = g.s1;
    let a = g.a;
    let b = g.b;
    let ds = s1 - s0;
    let len = max(length(ds), 1.0e-6);
    let eps = 1.0e-3 / len;
    let thick = params.knobs.x;
    var s = a;
    var level = min(2u, levels - 1u);
    for (var iter = 0u; iter < 4096u; iter += 1u) {
        if s >= b {
            break;
        }
        let scale = f32(1u << level);
        let p = mix(s0, s1, s);
        let cell = vec2<i32>(floor(p / scale));
        var s_exit = b;
        for (var i = 0; i < 2; i += 1) {
            if ds[i] > 1.0e-9 {
                s_exit = min(s_exit, (f32(cell[i] + 1) * scale - s0[i]) / ds[i]);
            } else if ds[i] < -1.0e-9 {
                s_exit = min(s_exit, (f32(cell[i]) * scale - s0[i]) / ds[i]);
            }
        }
        s_exit = clamp(s_exit, s, b);
        let z_in = segment_depth(g, s);
        let z_out = segment_depth(g, s_exit);
        let nearest = hiz_fetch(plane, level, cell);
        if max(z_in, z_out) < nearest {
            s = s_exit + eps;
            level = min(level + 1u, levels - 1u);
            continue;
        }
        if level > 0u {
            level -= 1u;
            continue;
        }
        let zs = nearest;
        if zs < HIZ_EMPTY && z_out >= zs && z_in <= zs * (1.0 + thick) {
            let u = clamp((zs - z_in) / (z_out - z_in), 0.0, 1.0);
            let sc = select(mix(s, s_exit, u), s, !(u == u));
            r.hit = true;
            r.pos = segment_point(v, g, sc);
            r.px = cell;
            return r;
        }
        s = s_exit + eps;
        level = min(1u, levels - 1u);
    }
    let e = min(s, b);
    r.pos = segment_point(v, g, e);
    r.px = vec2<i32>(floor(mix(s0, s1, e)));
    return r;
}

#ifdef TRACE_CASTER_CHAINS
// `march_front` steps as on a map of this side.
const FRONT_STEP_BASE: f32 = 64.0;

// Where a ray that left a caster's outside meets the light's caster-front layer (a further
// mirror): steps as on a 64-texel map (the layer has no pyramid; at 1024² a texel-by-texel
// march tripled `mirror_wall`'s trace), a crossing where the ray passes from in front of the
// layer (or an empty texel) to behind it by less than the step's own depth change plus the
// thickness, refined by eq. 2.
fn march_front(v: SpaceView, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> MarchResult {
    var r = march_start(o);
    let g = project_segment(v, o, d, t_max);
    if !g.ok {
        return r;
    }
    let n = segment_steps_flat(g, max(params.knobs.w, v.size.x / FRONT_STEP_BASE));
    return march_linear(v, 3u, r, g, n, 1.0);
}
#endif
