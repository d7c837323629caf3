// Caustics-volume compute passes (seed 000 sections 3.2 to 3.4): `propagate` marches the live
// photons of one slab in texture space against its G_near / G_far, `write_args` sizes the next
// slab's indirect dispatch, `project` marches the photons of one exit face against the
// projector G-buffers (or takes the photons deposited inside) and fills the density tiles.
// Concatenated after optics.wgsl and common.wgsl by src/render/volume/pipelines.rs.

@group(0) @binding(0) var<uniform> vp: VolParams;
@group(0) @binding(1) var<uniform> probe: VolStep;
@group(0) @binding(2) var<storage, read> materials: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> states: array<VolPhoton>;
@group(0) @binding(4) var<storage, read_write> live: array<u32>;
@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> finals: array<VolPhoton>;
@group(0) @binding(7) var<storage, read_write> hits: array<VolHit>;
@group(0) @binding(8) var<storage, read_write> tiles: array<atomic<u32>>;
@group(0) @binding(9) var slab_gbuf: texture_2d_array<f32>;
@group(0) @binding(10) var cube_gbuf: texture_2d_array<f32>;

struct Args {
    x: u32,
    y: u32,
    z: u32,
}
@group(1) @binding(0) var<storage, read_write> args: array<Args>;

fn count(c: u32) {
    atomicAdd(&counts[CNT + c], 1u);
}

fn count_add_f32(c: u32, v: f32) {
    if !(abs(v) <= 3.0e38) {
        return;
    }
    let i = CNT + c;
    var old = atomicLoad(&counts[i]);
    for (var k = 0u; k < 256u; k += 1u) {
        let r = atomicCompareExchangeWeak(&counts[i], old, bitcast<u32>(bitcast<f32>(old) + v));
        if r.exchanged {
            return;
        }
        old = r.old_value;
    }
}

fn rand01(state: ptr<function, u32>) -> f32 {
    *state = optics_pcg_hash(*state);
    return f32(*state >> 8u) / 16777216.0;
}

// A G-buffer texel: depth (m), normal (world), instance; `valid` false where nothing was drawn.
struct GSample {
    valid: bool,
    depth: f32,
    normal: vec3<f32>,
    inst: u32,
}

fn decode(t: vec4<f32>) -> GSample {
    var s: GSample;
    s.valid = t.w != 0.0 && abs(t.x) <= 3.0e38;
    s.depth = t.x;
    let nz = sign(t.w) * sqrt(max(1.0 - t.y * t.y - t.z * t.z, 0.0));
    s.normal = vec3(t.y, t.z, nz);
    s.inst = u32(max(abs(t.w) - 1.0, 0.0));
    return s;
}

fn slab_texel(q: vec3<f32>) -> vec2<i32> {
    let h = vol_half();
    let res = f32(vp.dims.x);
    let u = q[vp.lay.y] / h[vp.lay.y];
    let v = q[vp.lay.z] / h[vp.lay.z];
    let x = (u * 0.5 + 0.5) * res;
    let y = (0.5 - v * 0.5) * res;
    let m = i32(vp.dims.x) - 1;
    return clamp(vec2<i32>(floor(vec2(x, y))), vec2(0), vec2(m));
}

fn entry_sign() -> f32 {
    return select(1.0, -1.0, vp.lay.w != 0u);
}

// Slab depth w of a local point (0 on the entry face).
fn depth_of(q: vec3<f32>) -> f32 {
    return vol_half()[vp.lay.x] - entry_sign() * q[vp.lay.x];
}

// Exit of the local box [lo, hi] from q along d: (t, code) with code 2 axis + (1 when through
// the low side).
fn box_exit(q: vec3<f32>, d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    var best = 3.0e38;
    var code = 0u;
    for (var i = 0u; i < 3u; i += 1u) {
        if d[i] > 0.0 {
            let t = (hi[i] - q[i]) / d[i];
            if t < best {
                best = t;
                code = 2u * i;
            }
        } else if d[i] < 0.0 {
            let t = (lo[i] - q[i]) / d[i];
            if t < best {
                best = t;
                code = 2u * i + 1u;
            }
        }
    }
    return vec2(max(best, 0.0), f32(code));
}

fn set_end(p: ptr<function, VolPhoton>, end: u32) {
    var f = bitcast<u32>((*p).dir.w);
    f = (f & 0xFu) | (end << 4u);
    if end != END_ALIVE {
        f |= F_TERMINATED;
    }
    (*p).dir.w = bitcast<f32>(f);
}

// Interactions a photon inside a dielectric may have in one slab (outside one: two).
const VOL_SEGMENTS: u32 = 16u;

// Where (ray parameter) the photon's signed depth below a surface, `s0` at `t0` and `s1` at
// `t1` (each against the surface of its own column, so a sloped surface is found when the
// photon crosses it sideways), changes sign; -1 when it does not.
fn crossing(s0: f32, s1: f32, t0: f32, t1: f32) -> f32 {
    if !((s0 < 0.0 && s1 >= 0.0) || (s0 > 0.0 && s1 <= 0.0)) {
        return -1.0;
    }
    let ds = s1 - s0;
    if !(abs(ds) > 0.0) {
        return t1;
    }
    return clamp(t0 - s0 / ds * (t1 - t0), t0, t1);
}

fn flags_of(p: VolPhoton) -> u32 {
    return bitcast<u32>(p.dir.w);
}

// Section 3.3's material rules at a hit with (unit) normal n of instance inst. The photon's
// position is already on the surface. Returns 0: ignored (keep marching), 1: new direction,
// 2: terminated.
fn interact(p: ptr<function, VolPhoton>, n: vec3<f32>, inst: u32, rng: ptr<function, u32>) -> u32 {
    let m0 = materials[3u * inst];
    let kind = bitcast<u32>(m0.x);
    let d = (*p).dir.xyz;
    var flags = flags_of(*p);
    let c = dot(n, d);
    let n_f = select(n, -n, c > 0.0);
    if kind == MAT_DIFFUSE {
        (*p).normal = vec4(n_f, (*p).normal.w);
        if (flags & F_CONTRIB) != 0u {
            count(C_DEPOSITS);
            set_end(p, END_DEPOSIT);
        } else {
            count(C_ABSORBED);
            set_end(p, END_GONE);
        }
        return 2u;
    }
    if kind == MAT_CONDUCTOR {
        (*p).flux = vec4((*p).flux.xyz * optics_fresnel_schlick(-dot(d, n_f), materials[3u * inst + 2u].xyz), (*p).flux.w);
        (*p).dir = vec4(optics_reflect(d, n_f), bitcast<f32>(flags | F_CONTRIB));
        (*p).normal = vec4(n_f, (*p).normal.w);
        (*p).pos.w = 0.0;
        count(C_REFLECTED);
        return 1u;
    }
    // Dielectric: the P_med and hemisphere rules (optics::media_interface; the depth test
    // "between G_near and G_far" is the caller's). A thin wall has air on both sides: no
    // medium to enter or leave, so it is an interface whichever face the photon meets (a pane
    // lit on its back, a closed thin shell's far wall), 1 / ior from either, never TIR.
    let inside = (flags & F_MEDIUM) != 0u;
    let enter = !inside && c < 0.0;
    let exit = inside && c > 0.0;
    let thin = m0.z > 0.5;
    if !enter && !exit && !(thin && abs(c) > 0.0) {
        count(C_IGNORED);
        return 0u;
    }
    let eta = optics_dielectric_eta(m0.y, enter, thin);
    if exit {
        // Beer-Lambert over the length travelled inside.
        let att = optics_beer_lambert(materials[3u * inst + 1u].xyz, m0.w, (*p).normal.w);
        (*p).flux = vec4((*p).flux.xyz * att, (*p).flux.w);
    }
    let r = optics_fresnel_dielectric(-dot(d, n_f), eta);
    var t = vec4(d, 1.0);
    if !thin {
        t = optics_refract(d, n_f, eta);
    }
    var nd: vec3<f32>;
    if r >= 1.0 || t.w == 0.0 {
        count(C_TIR);
        nd = optics_reflect(d, n_f);
    } else if rand01(rng) < r {
        count(C_REFLECTED);
        nd = optics_reflect(d, n_f);
    } else {
        count(C_REFRACTED);
        nd = t.xyz;
        // The boundary's transmission tint (row 2; white for clear glass).
        (*p).flux = vec4((*p).flux.xyz * materials[3u * inst + 2u].xyz, (*p).flux.w);
        if !thin {
            flags ^= F_MEDIUM;
            (*p).normal.w = 0.0;
        }
    }
    (*p).dir = vec4(nd, bitcast<f32>(flags | F_CONTRIB));
    (*p).normal = vec4(n_f, (*p).normal.w);
    (*p).pos.w = 0.0;
    return 1u;
}

fn advance(p: ptr<function, VolPhoton>, len: f32) {
    (*p).pos.w += len;
    (*p).flux.w += len;
    if (flags_of(*p) & F_MEDIUM) != 0u {
        (*p).normal.w += len;
    }
}

// Leave the volume through face `code`: to its projector when contributive and an exit face.
fn leave(p: ptr<function, VolPhoton>, code: u32, i: u32) {
    let flags = flags_of(*p);
    if (flags & F_MEDIUM) != 0u {
        // Still inside a dielectric: no surface let it out, so its direction is not the one
        // it would leave with. Counted (a closed object's path ended without its last events).
        count(C_LEFT_INSIDE);
        count_add_f32(C_LEFT_INSIDE_LM, dot((*p).flux.xyz, vec3(0.2126, 0.7152, 0.0722)));
    }
    let exit_face = (vp.counts.z & (1u << code)) != 0u;
    if (flags & F_CONTRIB) != 0u {
        if exit_face {
            set_end(p, 1u + code);
        } else {
            count(C_CULLED);
            set_end(p, END_GONE);
        }
    } else {
        set_end(p, END_GONE);
    }
    finals[i] = *p;
}

// The march of one photon through slab `j` (box `lo`..`hi`, local coordinates) against the
// slab's G_near / G_far, from `*q_io` along `*dq_io`, with its interactions. Returns true when
// the path ended there (`*p_out` holds the final state); false when it flies on to the slab's
// boundary from `*q_io` along `*dq_io`.
fn march_slab(p_out: ptr<function, VolPhoton>, q_io: ptr<function, vec3<f32>>, dq_io: ptr<function, vec3<f32>>, rng: ptr<function, u32>, j: u32, lo: vec3<f32>, hi: vec3<f32>, eps: f32) -> bool {
    var p = *p_out;
    var q = *q_io;
    var dq = *dq_io;
    let h = vol_half();
    let res = f32(vp.dims.x);
    // One slab texel, local units.
    let texel_w = 2.0 * max(h[vp.lay.y], h[vp.lay.z]) / res;
    let near_layer = 2u * j;
    let far_layer = near_layer + 1u;
    // Interactions in this slab. Outside a dielectric: 0, marching against G_near; 1, against
    // G_far after the first interaction (the seed's "second interaction for thin objects");
    // 2, done. Inside one (P_med), the next surface is whichever of the column's G_near and
    // G_far the march crosses, up to VOL_SEGMENTS interactions: the seed stops after two, so a
    // photon totally reflected once inside a gem flew on through its far side and lit the
    // floor where the gem sends light back up (+8 % of the caustic on an open brilliant).
    var phase = 0u;
    for (var segment = 0u; segment < VOL_SEGMENTS; segment += 1u) {
        let exit = box_exit(q, dq, lo, hi);
        let t_end = exit.x;
        let inside = (flags_of(p) & F_MEDIUM) != 0u;
        if (phase >= 2u && !inside) || t_end <= 0.0 {
            break;
        }
        let span = max(abs(dq[vp.lay.y]) / h[vp.lay.y], abs(dq[vp.lay.z]) / h[vp.lay.z]) * t_end * 0.5 * res;
        let limit = 4u * vp.dims.x;
        var n = u32(clamp(ceil(span), 1.0, f32(limit))) + 1u;
        if span > f32(limit) {
            count(C_STEP_LIMIT);
        }
        var prev_w = depth_of(q);
        var prev_t = 0.0;
        var restarted = false;
        let px0 = slab_texel(q);
        var prev_gn = decode(textureLoad(slab_gbuf, px0, near_layer, 0));
        var prev_gf = decode(textureLoad(slab_gbuf, px0, far_layer, 0));
        for (var k = 1u; k <= n; k += 1u) {
            let t = t_end * f32(k) / f32(n);
            let qs = q + dq * t;
            let ws = depth_of(qs);
            let px = slab_texel(qs);
            let gn = decode(textureLoad(slab_gbuf, px, near_layer, 0));
            let gf = decode(textureLoad(slab_gbuf, px, far_layer, 0));
            var hit = false;
            var hit_depth = 0.0;
            var g: GSample;
            var th_inside = -1.0;
            if inside {
                // The nearer of the two surfaces the step crosses (not the one just left),
                // each compared with its own column's depth at both ends of the step.
                var tn = -1.0;
                var tf = -1.0;
                // A jump of the surface's depth between the two columns larger than a steep
                // (4:1) slope is another surface taking its place (the slab planes clip objects,
                // so a column's near or far surface changes identity), not a crossing.
                let jump = 4.0 * texel_w + abs(ws - prev_w);
                if gn.valid && prev_gn.valid && abs(gn.depth - prev_gn.depth) <= jump {
                    tn = crossing(prev_w - prev_gn.depth, ws - gn.depth, prev_t, t);
                }
                if gf.valid && prev_gf.valid && abs(gf.depth - prev_gf.depth) <= jump {
                    tf = crossing(prev_w - prev_gf.depth, ws - gf.depth, prev_t, t);
                }
                if tf > eps && (tn <= eps || tf < tn) {
                    g = gf;
                    th_inside = tf;
                } else if tn > eps {
                    g = gn;
                    th_inside = tn;
                }
                hit = th_inside >= 0.0;
                hit_depth = g.depth;
            } else if phase == 0u && gn.valid && ws >= gn.depth {
                // Crossed this column's near surface since the last sample, or lies inside
                // the near-far shell (entered from the side).
                let in_shell = gf.valid && ws <= gf.depth + eps;
                if prev_w < gn.depth || in_shell {
                    hit = true;
                    hit_depth = gn.depth;
                    g = gn;
                }
            } else if phase == 1u && gf.valid {
                let a = prev_w - gf.depth;
                let b = ws - gf.depth;
                if (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0) {
                    hit = true;
                    hit_depth = gf.depth;
                    g = gf;
                }
            }
            if hit {
                // The point of the segment at the surface's depth.
                let dw = ws - prev_w;
                var th = t;
                if th_inside >= 0.0 {
                    th = th_inside;
                } else if abs(dw) > 0.0 {
                    th = clamp(prev_t + (hit_depth - prev_w) / dw * (t - prev_t), prev_t, t);
                }
                let qh = q + dq * th;
                let nl = length(g.normal);
                var p2 = p;
                p2.pos = vec4(vol_world(qh), p.pos.w);
                advance(&p2, th);
                let r = interact(&p2, g.normal / max(nl, 1e-20), g.inst, rng);
                if r == 0u {
                    prev_w = ws;
                    prev_t = t;
                    prev_gn = gn;
                    prev_gf = gf;
                    continue;
                }
                p = p2;
                if r == 2u {
                    *p_out = p;
                    return true;
                }
                q = qh;
                dq = vol_local_dir(p.dir.xyz);
                let l2 = length(dq);
                if !(l2 > 0.0) || !vol_finite3(dq) {
                    count(C_NAN);
                    set_end(&p, END_GONE);
                    *p_out = p;
                    return true;
                }
                dq /= l2;
                phase += 1u;
                restarted = true;
                break;
            }
            prev_w = ws;
            prev_t = t;
            prev_gn = gn;
            prev_gf = gf;
        }
        if !restarted {
            break;
        }
    }
    *p_out = p;
    *q_io = q;
    *dq_io = dq;
    return false;
}

// The box of slab `j` in the volume's local coordinates (rows: min, max).
fn slab_bounds(j: u32) -> mat2x3<f32> {
    let h = vol_half();
    let e = vp.lay.x;
    let s = entry_sign();
    let thick = 2.0 * h[e] / f32(vp.counts.y);
    let qa = s * (h[e] - thick * f32(j + 1u));
    let qb = s * (h[e] - thick * f32(j));
    var lo = -h;
    var hi = h;
    lo[e] = min(qa, qb);
    hi[e] = max(qa, qb);
    return mat2x3(lo, hi);
}

@compute @workgroup_size(64)
fn propagate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slab = probe.info.x;
    let cap = vp.counts.x;
    let slabs = vp.counts.y;
    // Slab 0 takes this frame's range of the trace list; later slabs their live lists.
    var n = atomicLoad(&counts[slab]);
    var at = slab * cap + gid.x;
    if slab == 0u {
        n = vp.progress.y;
        at = vp.progress.x + gid.x;
    }
    if gid.x >= n || gid.x >= cap || at >= cap * slabs {
        return;
    }
    let i = live[at];
    if i >= cap {
        return;
    }
    var p = states[slab * cap + i];
    var rng = optics_pcg_hash(i ^ optics_pcg_hash(slab * 0x9e3779b9u + vp.dims.w));
    let h = vol_half();
    let e = vp.lay.x;
    let s = entry_sign();
    let thick = 2.0 * h[e] / f32(slabs);
    let first = slab_bounds(slab);
    var q = clamp(vol_local(p.pos.xyz), first[0], first[1]);
    var dq = vol_local_dir(p.dir.xyz);
    let dl = length(dq);
    if !vol_finite3(q) || !(dl > 0.0) || !(dl <= 3.0e38) || !vol_finite3(p.flux.xyz) {
        count(C_NAN);
        set_end(&p, END_GONE);
        finals[i] = p;
        return;
    }
    dq /= dl;
    let eps = max(1e-6 * vp.centre.w, 1e-4 * thick);
    let entry_code = 2u * e + vp.lay.w;
    // The slab marched: this dispatch's, or an earlier one the photon turned back into (their
    // G-buffers are drawn before this slab's). The seed carries photons forward only: light
    // turned back inside a gem flew straight out of the volume, and never reached the facets
    // that send part of it down again.
    var j = slab;
    for (var hop = 0u; hop < 4u * slabs + 4u; hop += 1u) {
        let b = slab_bounds(j);
        q = clamp(q, b[0], b[1]);
        if march_slab(&p, &q, &dq, &rng, j, b[0], b[1], eps) {
            finals[i] = p;
            return;
        }
        // Fly to the slab's boundary.
        let exit = box_exit(q, dq, b[0], b[1]);
        q += dq * exit.x;
        advance(&p, exit.x);
        p.pos = vec4(vol_world(q), p.pos.w);
        p.dir = vec4(vol_world_dir(dq), p.dir.w);
        let code = u32(exit.y);
        if code / 2u != e {
            leave(&p, code, i);
            return;
        }
        if -s * dq[e] > 0.0 {
            // Deeper (towards the face opposite the entry).
            if j < slab {
                j += 1u;
                continue;
            }
            if slab + 1u < slabs {
                states[(slab + 1u) * cap + i] = p;
                let at = atomicAdd(&counts[slab + 1u], 1u);
                live[(slab + 1u) * cap + at] = i;
                return;
            }
            leave(&p, entry_code ^ 1u, i);
            return;
        }
        if j == 0u {
            leave(&p, entry_code, i);
            return;
        }
        // Back towards the entry across an inner boundary: on in the slab before.
        count(C_BACKWARD);
        j -= 1u;
    }
    // Still in flight after the last hop: dropped, counted with its flux.
    count(C_STEP_LIMIT);
    count_add_f32(C_HOP_LIMIT_LM, dot(p.flux.xyz, vec3(0.2126, 0.7152, 0.0722)));
    set_end(&p, END_GONE);
    finals[i] = p;
}

@compute @workgroup_size(1)
fn write_args() {
    let slab = probe.info.x;
    var n = atomicLoad(&counts[slab]);
    if slab == 0u {
        n = vp.progress.y;
    }
    args[slab] = Args(min((n + 63u) / 64u, 65535u), 1u, 1u);
}

// ---- Projectors (section 3.4) ----

fn cube_axes(i: u32) -> vec2<u32> {
    if i == 0u {
        return vec2(1u, 2u);
    }
    if i == 1u {
        return vec2(2u, 0u);
    }
    return vec2(0u, 1u);
}

struct CubeSample {
    g: GSample,
    z: f32,        // the point's distance along its face axis
    layer: u32,
    texel: vec2<i32>,
}

fn cube_sample(p: vec3<f32>) -> CubeSample {
    let q = vol_local(p);
    let h = vol_half();
    let r = q / h;
    var i = 0u;
    if abs(r.y) > abs(r.x) && abs(r.y) >= abs(r.z) {
        i = 1u;
    } else if abs(r.z) > abs(r.x) && abs(r.z) > abs(r.y) {
        i = 2u;
    }
    let neg = r[i] < 0.0;
    let sgn = select(1.0, -1.0, neg);
    let ab = cube_axes(i);
    let ri = max(abs(r[i]), 1e-20);
    let xn = r[ab.x] / ri;
    let yn = sgn * r[ab.y] / ri;
    let res = f32(vp.dims.y);
    let m = i32(vp.dims.y) - 1;
    var out: CubeSample;
    out.layer = 2u * i + u32(neg);
    out.texel = clamp(vec2<i32>(floor(vec2((xn * 0.5 + 0.5) * res, (0.5 - yn * 0.5) * res))), vec2(0), vec2(m));
    out.z = abs(q[i]);
    out.g = decode(textureLoad(cube_gbuf, out.texel, out.layer, 0));
    // Layers of faces without a projector were cleared: nothing there.
    out.g.valid = out.g.valid && (vp.counts.z & (1u << out.layer)) != 0u;
    return out;
}

fn cube_hit(c: CubeSample, thickness: f32) -> bool {
    return c.g.valid && c.z >= c.g.depth && c.z - c.g.depth <= thickness;
}

// Record photon `i` on its receiver at `texel` of tile set `tset` (receiver area `texel_area`
// m^2), counted in every level of the set's density tiles.
fn record_hit(i: u32, p: VolPhoton, pos: vec3<f32>, n: vec3<f32>, tset: u32, texel: vec2<u32>, texel_area: f32) {
    var hit: VolHit;
    hit.pos = vec4(pos, p.pos.w);
    hit.normal = vec4(n, texel_area);
    hit.dir = vec4(p.dir.xyz, bitcast<f32>(vol_pack_texel(tset, texel)));
    hit.flux = vec4(p.flux.xyz, 0.0);
    hits[i] = hit;
    for (var l = 0u; l < vol_tile_levels(); l += 1u) {
        atomicAdd(&tiles[vol_tile_index(tset, l, texel)], 1u);
    }
    let lm = dot(p.flux.xyz, vec3(0.2126, 0.7152, 0.0722));
    splatted_lm += select(0.0, lm, abs(lm) <= 3.0e38);
}

// The flux this thread recorded (lm), summed over the workgroup by `project` before one
// float compare-exchange on C_SPLATTED: one per photon serialised a wide GPU.
var<private> splatted_lm: f32;
var<workgroup> wg_splatted: array<f32, 64>;

@compute @workgroup_size(64)
fn project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    project_photon(gid.x);
    wg_splatted[lid] = splatted_lm;
    workgroupBarrier();
    for (var half = 32u; half > 0u; half >>= 1u) {
        if lid < half {
            wg_splatted[lid] += wg_splatted[lid + half];
        }
        workgroupBarrier();
    }
    if lid == 0u && wg_splatted[0] != 0.0 {
        count_add_f32(C_SPLATTED, wg_splatted[0]);
    }
}

// Project one photon of this frame's range onto the face's receivers (or record its deposit).
fn project_photon(g: u32) {
    // This frame's range of the trace list (every photon that carried flux in).
    if g >= vp.progress.w || vp.progress.z + g >= vp.counts.x {
        return;
    }
    let i = live[vp.progress.z + g];
    if i >= vp.counts.x {
        return;
    }
    let p = finals[i];
    let flags = flags_of(p);
    let end = (flags >> 4u) & 15u;
    let face = probe.info.x;
    let h = vol_half();
    let scale = vp.centre.w;
    if face == 6u {
        // Deposits inside the volume: their tile is on the slab texel grid.
        if end != END_DEPOSIT {
            return;
        }
        let q = vol_local(p.pos.xyz);
        let px = vec2<u32>(slab_texel(q));
        let res = f32(vp.dims.x);
        let texel = (2.0 * h[vp.lay.y] / res) * (2.0 * h[vp.lay.z] / res);
        let a = texel / max(abs(dot(p.normal.xyz, vol_axis(vp.lay.x))), 1e-3);
        count(C_HITS);
        record_hit(i, p, p.pos.xyz, p.normal.xyz, 6u, px, a);
        return;
    }
    if end != 1u + face {
        return;
    }
    let d = p.dir.xyz;
    // March to the scene box's far side.
    let lo = vp.bounds_lo.xyz - vec3(1e-3 * scale);
    let hi = vp.bounds_hi.xyz + vec3(1e-3 * scale);
    let inv = 1.0 / d;
    let t0 = (lo - p.pos.xyz) * inv;
    let t1 = (hi - p.pos.xyz) * inv;
    let tmax_v = max(t0, t1);
    var t_max = min(min(tmax_v.x, tmax_v.y), tmax_v.z);
    if !(t_max > 0.0) || !(t_max <= 3.0e38) {
        count(C_MISSED);
        return;
    }
    let res = f32(vp.dims.y);
    let limit = 8u * vp.dims.y + 64u;
    var t = 0.0;
    var prev_t = 0.0;
    var found = false;
    var thickness = 0.0;
    for (var k = 0u; k < limit; k += 1u) {
        let x = p.pos.xyz + d * t;
        let q = vol_local(x);
        // One texel at this distance (the smallest of the face's two texel sides).
        let r = q / h;
        let m = max(max(abs(r.x), abs(r.y)), abs(r.z));
        let st = max(0.75 * 2.0 * m * min(min(h.x, h.y), h.z) / res, 1e-5 * scale);
        prev_t = t;
        t = min(t + st, t_max);
        thickness = max(2.0 * st, 1e-4 * scale);
        let c = cube_sample(p.pos.xyz + d * t);
        if cube_hit(c, thickness) {
            found = true;
            break;
        }
        if t >= t_max {
            break;
        }
        if k + 1u == limit {
            count(C_STEP_LIMIT);
        }
    }
    if !found {
        count(C_MISSED);
        return;
    }
    // Bisection to the surface.
    var a = prev_t;
    var b = t;
    for (var k = 0u; k < 8u; k += 1u) {
        let mid = 0.5 * (a + b);
        if cube_hit(cube_sample(p.pos.xyz + d * mid), thickness) {
            b = mid;
        } else {
            a = mid;
        }
    }
    let pos = p.pos.xyz + d * b;
    let c = cube_sample(pos);
    if !c.g.valid {
        count(C_MISSED);
        return;
    }
    let m0 = materials[3u * c.g.inst];
    if bitcast<u32>(m0.x) != MAT_DIFFUSE {
        count(C_SPECULAR_OUT);
        return;
    }
    var n = c.g.normal / max(length(c.g.normal), 1e-20);
    n = select(n, -n, dot(n, d) > 0.0);
    let ai = c.layer / 2u;
    let ab = cube_axes(ai);
    let ray = normalize(pos - vp.centre.xyz);
    let axis = vol_axis(ai) * select(1.0, -1.0, (c.layer & 1u) != 0u);
    let texel = vol_texel_area(c.z, h[ai], h[ab.x], h[ab.y], vp.dims.y, ray, axis, n);
    var q = p;
    q.pos.w += b;
    count(C_HITS);
    record_hit(i, q, pos, n, c.layer, vec2<u32>(c.texel), texel);
}
