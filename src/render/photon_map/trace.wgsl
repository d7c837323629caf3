// The photon map's trace (seed 001 section 3.1 with the shared tracer of src/render/trace/):
// one thread per photon; photon k of light l starts at R2 point k of the light's parameter
// square (rotated every frame), carries power · weight / N, goes through any number of
// specular events up to the bounce limit (conductors: Schlick Fresnel; dielectrics: reflect
// or refract with the exact Fresnel probability, flux unchanged, TIR always reflects;
// Beer-Lambert inside media) and is stored at its first diffuse hit after at least one
// specular event. Photons whose first hit is diffuse are direct light (not a caustic) and are
// dropped, as in the reference tracer. Long chains as the reference tracer follows them: after
// OPTICS_ROULETTE_DEPTH specular events a path survives each further one with probability
// optics_roulette_survival (its throughput, at least 0.05) and carries flux / q when it does
// (unbiased; a clear-glass path keeps throughput 1 and always survives); the flux still in
// flight at the bounce limit is counted (C_FLUX_MAX_DEPTH), never silently dropped.
// Concatenated after the tracer's WGSL and photon.wgsl.

struct PmParams {
    world_from_clip: mat4x4<f32>,
    clip_from_world: mat4x4<f32>,
    // The other eye's clip_from_world (stereo reuse; the right eye reads the left's buffer).
    other_clip_from_world: mat4x4<f32>,
    eye: vec4<f32>,      // xyz camera position, w scene scale (ray offsets)
    view: vec4<f32>,     // width, height (px), r² of this frame (m²), normal threshold
    emit: vec4<u32>,     // photons per light, lights, max bounces, capacity
    frame: vec4<u32>,    // R2 rotation x, y, frame seed, flags (FLAG_*)
    gather: vec4<f32>,   // weight of this frame in the mean (1 / i), the frame i, specular-event budget of the frame, surface tolerance (FLAG_VALIDATE)
    lens: vec4<f32>,     // focal lengths fx, fy (px); z 1 for a perspective camera (footprint floor); w the first frame's radius (m)
    forward: vec4<f32>,  // the camera's forward axis (xyz), w photons a pixel's gather aims at with FLAG_DENSITY
    other_eye: vec4<f32>, // the left eye's position (xyz), for a right eye that reuses
}

const FLAG_ACCUMULATE: u32 = 1u; // blend into the running mean (else replace it)
const FLAG_FROZEN: u32 = 2u;     // gather nothing: write the mean as it is
const FLAG_SHARED: u32 = 4u;     // workgroup-shared cooperative gather (algorithm 1)
const FLAG_MIRRORS: u32 = 8u;    // pixels on mirrors gather at their reflected point
const FLAG_REUSE: u32 = 16u;     // this view is a right eye: reuse the left eye's gathers
const FLAG_VALIDATE: u32 = 32u;  // a receiver moved: restart pixels whose eye distance changed
const FLAG_DENSITY: u32 = 64u;   // accum holds the photon density of this view's last frame

@group(0) @binding(9) var<uniform> params: PmParams;
@group(0) @binding(10) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(11) var<storage, read_write> header: array<atomic<u32>>;

// What one photon's path came to. Its counts are summed per workgroup first: one global
// atomic per workgroup and counter instead of one per photon, and one slot reservation per
// workgroup for the stored photons.
struct PathEnd {
    // 0 nothing, 1 emitted and stored (`pos`..`n` hold it), 2 emitted and not stored.
    state: u32,
    // Outcome counters: C_DIRECT, C_MISSED, C_MAX_DEPTH, C_NAN, C_ROULETTE, C_BUDGET_STOPPED as
    // 1 << (k), TIR count in bits 8+.
    counts: u32,
    pos: vec3<f32>,
    d: vec3<f32>,
    flux: vec3<f32>,
    n: vec3<f32>,
    // Luminous flux (lm) striking the first caster, deposited at the diffuse hit (stored or
    // past the capacity), in flight at the bounce limit or the event budget (C_FLUX_*).
    energy: vec3<f32>,
    // Specular events traced.
    events: u32,
}

const END_DIRECT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_MAX_DEPTH: u32 = 4u;
const END_NAN: u32 = 8u;
const END_ROULETTE: u32 = 16u;
const END_BUDGET: u32 = 32u;
// Roulette's uniforms come from the photon's key with this bit set in the event index, apart
// from the Fresnel choices' (optics_hash_unit(key, bounces)).
const ROULETTE_STREAM: u32 = 0x10000u;

fn trace_photon(i: u32) -> PathEnd {
    var end: PathEnd;
    let per_light = params.emit.x;
    if per_light == 0u || i >= per_light * params.emit.y {
        return end;
    }
    let light = lights[i / per_light];
    let k = i % per_light;
    let e = light_emit(light, optics_r2_point(k, params.frame.xy));
    var flux = light.power.xyz * (e.weight / f32(per_light));
    if !finite3(flux) || all(flux <= vec3(0.0)) {
        return end;
    }
    // The emitted flux's largest channel: roulette's throughput is relative to it.
    let flux0 = max(max(flux.x, flux.y), flux.z);
    end.state = 2u;
    let scale = params.eye.w;
    let key = i * 0x9e3779b9u + params.frame.z;
    var o = e.o;
    var d = e.d;
    var medium = INVALID;
    var bounces = 0u;
    var tir = 0u;
    var events = event_budget();
    let budget = u32(params.gather.z);
    // max_bounces <= 128 specular events (PhotonMapSettings::sanitized), then the diffuse one.
    for (var guard = 0u; guard < 130u; guard += 1u) {
        let hit = bvh_closest_hit(o, d, 0.0, BVH_FAR);
        if hit.instance == BVH_INVALID {
            if bounces == 0u {
                end.counts |= END_MISSED;
            }
            break;
        }
#ifdef TRACE_DIELECTRICS
        if medium != INVALID {
            let mm = scene_material(medium, 0u);
            flux *= optics_beer_lambert(scene_material(medium, 1u).xyz, mm.w, hit.t);
        }
#endif
        let s = surface_hit(hit, o, d);
        if !s.ok || !finite3(flux) {
            end.counts |= END_NAN;
            break;
        }
        if s.kind == MAT_DIFFUSE {
            if bounces == 0u {
                end.counts |= END_DIRECT;
            } else {
                end.state = 1u;
                end.pos = s.pos;
                end.d = d;
                end.flux = flux;
                end.n = s.ng_f;
                end.energy.y = luminance(flux);
            }
            break;
        }
        if bounces == 0u {
            end.energy.x = luminance(flux);
        }
        if bounces >= params.emit.z {
            end.counts |= END_MAX_DEPTH;
            end.energy.z = luminance(flux);
            break;
        }
        // Russian roulette (the reference tracer's rule and depth, optics::roulette_survival):
        // unbiased, the survivors carry the flux of the ended paths.
        if bounces >= OPTICS_ROULETTE_DEPTH {
            let q = optics_roulette_survival(flux, flux0);
            if optics_hash_unit(key, bounces | ROULETTE_STREAM) >= q {
                end.counts |= END_ROULETTE;
                break;
            }
            flux /= q;
        }
        if !(event_take(&events) || event_grant(&events, atomicAdd(&header[C_EVENTS_GRANTED], events.next), budget)) {
            // The frame's event budget is spent: the flux in flight is counted, not lost.
            end.counts |= END_BUDGET;
            end.energy.z = luminance(flux);
            break;
        }
        bounces += 1u;
        if s.kind == MAT_CONDUCTOR {
            flux *= optics_fresnel_schlick(-dot(d, s.ns_f), scene_material(hit.instance, 2u).xyz);
            d = reflect_guarded(d, s.ns_f, s.ng_f);
            o = optics_offset_ray_origin(s.pos, s.ng_f, scale);
            continue;
        }
#ifdef TRACE_DIELECTRICS
        // Dielectric: reflect with the Fresnel probability (unbiased, flux unchanged).
        let m0 = scene_material(hit.instance, 0u);
        // A thin wall has air on both sides: 1 / ior from either, never TIR.
        let thin = m0.z > 0.5;
        let eta = optics_dielectric_eta(m0.y, s.entering, thin);
        let r = optics_fresnel_dielectric(-dot(d, s.ns_f), eta);
        var t = vec4(d, 1.0);
        if !thin {
            t = refract_guarded(d, s.ns_f, s.ng_f, eta);
        }
        var refract = false;
        if r >= 1.0 || t.w == 0.0 {
            tir += 1u;
        } else {
            refract = optics_hash_unit(key, bounces) >= r;
        }
        if refract {
            // The boundary's transmission tint (row 2; white for clear glass).
            flux *= scene_material(hit.instance, 2u).xyz;
            d = t.xyz;
            if !thin {
                medium = select(INVALID, hit.instance, s.entering);
            }
            o = optics_offset_ray_origin(s.pos, -s.ng_f, scale);
        } else {
            d = reflect_guarded(d, s.ns_f, s.ng_f);
            o = optics_offset_ray_origin(s.pos, s.ng_f, scale);
        }
#else
        // A scene without dielectrics has no other specular kind.
        break;
#endif
    }
    end.counts |= min(tir, 0xffffffu) << 8u;
    end.events = events.used;
    if events.left != 0u {
        atomicSub(&header[C_EVENTS_GRANTED], events.left);
    }
    return end;
}

// Add `v` lm (>= 0) to the 64-bit fixed-point counter at header words `at` (low) and `at + 1`
// (high), PM_FLUX_SCALE units per lm rounded stochastically with `u` (unbiased). Returns
// false, adding nothing, for a negative or non-finite `v`.
fn add_flux(at: u32, v: f32, u: f32) -> bool {
    if !(v >= 0.0 && v <= 3.0e38) {
        return false;
    }
    // Below 2^60 units; an integer in f32, so the split into words is exact.
    let x = min(floor(v * PM_FLUX_SCALE + clamp(u, 0.0, 1.0)), 1.0e18);
    let hi = floor(x * (1.0 / 4294967296.0));
    let lo = u32(x - hi * 4294967296.0);
    var carry = 0u;
    if lo != 0u {
        let old = atomicAdd(&header[at], lo);
        carry = select(0u, 1u, old + lo < old);
    }
    let h = u32(hi) + carry;
    if h != 0u {
        atomicAdd(&header[at + 1u], h);
    }
    return true;
}

// Workgroup sums: emitted, stored, direct, missed, max depth, NaN, roulette, budget stopped,
// TIR, events; and the luminous flux of each photon (on casters, deposited, at the cap or the
// budget), summed by a tree.
var<workgroup> wg_counts: array<atomic<u32>, 10>;
var<workgroup> wg_base: u32;
var<workgroup> wg_energy: array<vec3<f32>, 64>;

@compute @workgroup_size(64)
fn pm_trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    if lid < 10u {
        atomicStore(&wg_counts[lid], 0u);
    }
    workgroupBarrier();
    let end = trace_photon(flat_index(gid, groups, 64u));
    var local = 0u;
    if end.state != 0u {
        atomicAdd(&wg_counts[0], 1u);
    }
    if end.state == 1u {
        local = atomicAdd(&wg_counts[1], 1u);
    }
    for (var k = 0u; k < 6u; k += 1u) {
        if (end.counts & (1u << k)) != 0u {
            atomicAdd(&wg_counts[2u + k], 1u);
        }
    }
    if (end.counts >> 8u) != 0u {
        atomicAdd(&wg_counts[8], end.counts >> 8u);
    }
    if end.events != 0u {
        atomicAdd(&wg_counts[9], end.events);
    }
    wg_energy[lid] = end.energy;
    workgroupBarrier();
    for (var half = 32u; half > 0u; half >>= 1u) {
        if lid < half {
            wg_energy[lid] += wg_energy[lid + half];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        let stored = atomicLoad(&wg_counts[1]);
        let base = atomicAdd(&header[H_COUNT], stored);
        wg_base = base;
        let cap = params.emit.w;
        let over = select(0u, base + stored - max(base, cap), base + stored > cap);
        let words = array<u32, 10>(C_EMITTED, 0u, C_DIRECT, C_MISSED, C_MAX_DEPTH, C_NAN, C_ROULETTE, C_BUDGET_STOPPED, C_TIR, C_EVENTS);
        for (var k = 0u; k < 10u; k += 1u) {
            let v = atomicLoad(&wg_counts[k]);
            if k != 1u && v != 0u {
                atomicAdd(&header[words[k]], v);
            }
        }
        if over != 0u {
            atomicAdd(&header[C_OVERFLOW], over);
        }
        let flux_words = array<u32, 3>(C_FLUX_CASTER, C_FLUX_DEPOSITED, C_FLUX_MAX_DEPTH);
        let e = wg_energy[0];
        let group = wid.y * groups.x + wid.x;
        for (var k = 0u; k < 3u; k += 1u) {
            if e[k] != 0.0 && !add_flux(flux_words[k], e[k], optics_hash_unit(group, params.frame.z + k)) {
                atomicAdd(&header[C_NAN], 1u);
            }
        }
    }
    workgroupBarrier();
    if end.state == 1u {
        let slot = wg_base + local;
        if slot < params.emit.w {
            photons[slot] = Photon(end.pos, oct_encode(end.d), end.flux, oct_encode(end.n));
        }
    }
}
