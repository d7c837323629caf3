// AAPS emit and trace (seed 004 sections 2.3.1, 3.1.2, 3.2.1, 3.3.1, 3.3.2, 3.3.5): one thread
// per task id walks the density quadtree to its texel and sample (optics::leaf_sample_uv),
// emits a photon with two differential rays, traces it through the BVH (split once at the first
// dielectric into its Fresnel-weighted halves, then every later dielectric interaction chosen
// by Fresnel probability with the flux unchanged, the differentials following the chosen
// branch), and at the first diffuse hit appends an anisotropic splat.
//
// Why not the thesis's "the previous interaction repeats": a path that refracted into a gem and
// must reflect many times inside it before it leaves loses R^k of its energy at every repeat
// (43 % of a brilliant's caustic). Choosing by Fresnel probability keeps the expected energy of
// every path (unbiased Russian roulette on the branch, TIR still always reflects).

struct Path {
    o: vec3<f32>,
    d: vec3<f32>,
    ou: vec3<f32>,
    du: vec3<f32>,
    ov: vec3<f32>,
    dv: vec3<f32>,
    flux: vec3<f32>,
    seg_start: vec3<f32>,
    medium: u32,
    bounces: u32,
    // 0: may still split; 1: the refracted half, 2: the reflected half of the split.
    split: u32,
    // The photon's task id: the key of its random branch choices.
    task: u32,
}

// Barycentrics of a world point in the plane of triangle `slot` (extrapolated outside it):
// the differential rays are updated "as if they hit the same triangle" (section 3.3.2).
fn plane_barycentrics(inst: BvhInstance, slot: u32, p: vec3<f32>) -> vec2<f32> {
    let q = object_point(inst, p) - bvh_tri(slot, 0u).xyz;
    let e1 = bvh_tri(slot, 1u).xyz;
    let e2 = bvh_tri(slot, 2u).xyz;
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let d20 = dot(q, e1);
    let d21 = dot(q, e2);
    let den = d00 * d11 - d01 * d01;
    if !(abs(den) > 0.0) || abs(den) > 3.0e38 {
        return vec2(1.0 / 3.0);
    }
    let uv = vec2(d11 * d20 - d01 * d21, d00 * d21 - d01 * d20) / den;
    return select(vec2(1.0 / 3.0), uv, finite3(vec3(uv, 0.0)));
}

// A differential ray's shading normal, on the same side as the main ray's `ns_f`. Guard: far
// outside the triangle the extrapolated normal can turn over; the main normal is used then.
fn differential_normal(inst: BvhInstance, slot: u32, p: vec3<f32>, ns_f: vec3<f32>) -> vec3<f32> {
    var n = shading_normal(inst, slot, plane_barycentrics(inst, slot, p));
    n = select(n, -n, dot(n, ns_f) < 0.0);
    return select(ns_f, n, dot(n, ns_f) > 0.5);
}

// Append the splat of a photon that reached a diffuse surface (sections 3.1.2, 3.3.5).
fn deposit(path: ptr<function, Path>, pos: vec3<f32>, pu: vec3<f32>, pv: vec3<f32>, ng_f: vec3<f32>, texel: u32, texel_energy: f32) {
    let scale = params.camera.w;
    let s = optics_splat_from_differentials((pu - pos) * params.viewport.w, (pv - pos) * params.viewport.w, ng_f, params.limits.w, params.splat.y, params.splat.z);
    if s.clamped {
        atomicAdd(&accum[C_CLAMPED], 1u);
    }
    let area = TRACE_PI * length(s.a) * length(s.b);
    let flux = (*path).flux;
    if !(area > 0.0) || !finite3(flux) {
        atomicAdd(&accum[C_NAN], 1u);
        return;
    }
    // The camera must see the lit side.
    if dot(params.camera.xyz - pos, ng_f) <= 0.0 {
        atomicAdd(&accum[C_CULL_FRUSTUM], 1u);
        return;
    }
    // Solid angle seen from the last specular interaction (section 3.3.5).
    // Splats above the threshold do not steer the density (they would ask for unbounded
    // photons at grazing angles); with `drop_large_splats` they are culled as well.
    let seg = distance(pos, (*path).seg_start);
    let large = params.limits.z > 0.0 && area > params.limits.z * seg * seg;
    if large && params.splat.w != 0.0 {
        atomicAdd(&accum[C_CULL_SIZE], 1u);
        return;
    }
    // Frustum: culled when all four corners are outside one clip plane.
    var all_out = vec4<bool>(true);
    var behind = true;
    for (var k = 0u; k < 4u; k += 1u) {
        let sa = select(-1.0, 1.0, (k & 1u) == 0u);
        let sb = select(-1.0, 1.0, (k & 2u) == 0u);
        let c = params.clip_from_world * vec4(pos + sa * s.a + sb * s.b, 1.0);
        behind = behind && c.w <= 0.0;
        all_out = all_out & vec4((c.x < -c.w), (c.x > c.w), (c.y < -c.w), (c.y > c.w));
    }
    if behind || any(all_out) {
        atomicAdd(&accum[C_CULL_FRUSTUM], 1u);
        return;
    }
    let size = params.viewport.xy;
    let p0 = aaps_to_pixel(params.clip_from_world, pos, size);
    let pa = aaps_to_pixel(params.clip_from_world, pos + s.a, size);
    let pb = aaps_to_pixel(params.clip_from_world, pos + s.b, size);
    var area_px = 1.0e9;
    if p0.z > 0.0 && pa.z > 0.0 && pb.z > 0.0 {
        let x = pa.xy - p0.xy;
        let y = pb.xy - p0.xy;
        area_px = TRACE_PI * abs(x.x * y.y - x.y * y.x);
    }
    let e = flux / area;
    if !finite3(e) {
        atomicAdd(&accum[C_NAN], 1u);
        return;
    }
    let cap = params.caps.x;
    let slot = atomicAdd(&accum[C_RESERVED], 1u);
    if slot >= cap {
        atomicAdd(&accum[C_OVERFLOW], 1u);
        return;
    }
    // Point splats (AapsSettings::point_splat_area) go to the plain list as one-pixel quads.
    let point = area_px < params.budget.y;
    let small = !point && params.caps.w != 0u && area_px < params.splat.x;
    var idx = 0u;
    if small {
        idx = cap - 1u - atomicAdd(&accum[C_SMALL], 1u);
    } else {
        idx = atomicAdd(&accum[C_BIG], 1u);
    }
    let frac = select(0.0, luminance(flux) / texel_energy, texel_energy > 0.0);
    splats[idx] = AapsSplat(
        vec4(pos, bitcast<f32>(texel)),
        vec4(s.a, bitcast<f32>(select(select(0u, 2u, point), 1u, small))),
        vec4(s.b, frac),
        vec4(e, area_px),
    );
    if !large {
        // Summed per run of threads on the same texel by `trace` (one atomic per run).
        t_area += min(area_px, 1.0e6);
        t_n += 1u;
    }
}

// Follow one path to its diffuse hit; a split stores the reflected branch in `pending`.
fn run_path(path: ptr<function, Path>, pending: ptr<function, Path>, has_pending: ptr<function, bool>, events: ptr<function, EventBudget>, texel: u32, texel_energy: f32) {
    let scale = params.camera.w;
    let max_bounces = params.caps.z;
    // max_bounces <= 128 specular hits (AapsSettings::sanitized), then the diffuse one.
    for (var guard = 0u; guard < 130u; guard += 1u) {
        let hit = bvh_closest_hit((*path).o, (*path).d, 0.0, BVH_FAR);
        if hit.instance == BVH_INVALID {
            if (*path).bounces == 0u {
                atomicAdd(&accum[C_DROPPED], 1u);
            }
            return;
        }
        let m0 = scene_material(hit.instance, 0u);
        let kind = bitcast<u32>(m0.x);
        if (*path).bounces == 0u && kind == MAT_DIFFUSE {
            // Section 3.1.2: a photon whose first hit is not a caster is discarded.
            atomicAdd(&accum[C_DROPPED], 1u);
            return;
        }
        if (*path).bounces == 0u {
            t_flux.x += flux_finite(luminance((*path).flux));
        }
#ifdef TRACE_DIELECTRICS
        if (*path).medium != INVALID {
            let mm = scene_material((*path).medium, 0u);
            (*path).flux *= optics_beer_lambert(scene_material((*path).medium, 1u).xyz, mm.w, hit.t);
        }
#endif
        let sh = surface_hit(hit, (*path).o, (*path).d);
        if !sh.ok {
            atomicAdd(&accum[C_NAN], 1u);
            return;
        }
        let inst = bvh_instances[hit.instance];
        let pos = sh.pos;
        let ng = sh.ng;
        let d = (*path).d;
        let entering = sh.entering;
        let ng_f = sh.ng_f;
        let ns_f = sh.ns_f;
        let tu = optics_transfer_to_plane((*path).ou, (*path).du, pos, ng);
        let tv = optics_transfer_to_plane((*path).ov, (*path).dv, pos, ng);
        if tu.w == 0.0 || tv.w == 0.0 {
            atomicAdd(&accum[C_CLAMPED], 1u);
        }
        if kind == MAT_DIFFUSE {
            t_flux.y += flux_finite(luminance((*path).flux));
            deposit(path, pos, tu.xyz, tv.xyz, ng_f, texel, texel_energy);
            return;
        }
        if (*path).bounces >= max_bounces {
            atomicAdd(&accum[C_MAX_DEPTH], 1u);
            t_flux.z += flux_finite(luminance((*path).flux));
            return;
        }
        let budget = u32(params.budget.z);
        if !(event_take(events) || event_grant(events, atomicAdd(&accum[C_EVENTS_GRANTED], (*events).next), budget)) {
            // The frame's event budget is spent: the flux in flight is counted, not lost.
            atomicAdd(&accum[C_BUDGET_STOPPED], 1u);
            t_flux.z += flux_finite(luminance((*path).flux));
            return;
        }
        let nu = differential_normal(inst, hit.slot, tu.xyz, ns_f);
        let nv = differential_normal(inst, hit.slot, tv.xyz, ns_f);
        (*path).bounces += 1u;
        (*path).seg_start = pos;
        (*path).ou = tu.xyz;
        (*path).ov = tv.xyz;
        if kind == MAT_CONDUCTOR {
            (*path).flux *= optics_fresnel_schlick(-dot(d, ns_f), scene_material(hit.instance, 2u).xyz);
            (*path).d = reflect_guarded(d, ns_f, ng_f);
            (*path).du = reflect_guarded((*path).du, nu, ng_f);
            (*path).dv = reflect_guarded((*path).dv, nv, ng_f);
            (*path).o = optics_offset_ray_origin(pos, ng_f, scale);
            continue;
        }
#ifdef TRACE_DIELECTRICS
        // Dielectric.
        // A thin wall has air on both sides: 1 / ior from either, never TIR.
        let thin = m0.z > 0.5;
        let eta = optics_dielectric_eta(m0.y, entering, thin);
        let r = optics_fresnel_dielectric(-dot(d, ns_f), eta);
        var t = vec4(d, 1.0);
        if !thin {
            t = refract_guarded(d, ns_f, ng_f, eta);
        }
        var refract = true;
        if r >= 1.0 || t.w == 0.0 {
            // Total internal reflection: reflect, whatever the split state says.
            atomicAdd(&accum[C_TIR], 1u);
            refract = false;
        } else if (*path).split == 0u {
            if r > 0.0 {
                // Section 3.3.1: split once; the reflected half waits in `pending`.
                atomicAdd(&accum[C_SPLIT], 1u);
                *pending = *path;
                (*pending).flux *= r;
                (*pending).split = 2u;
                (*pending).d = reflect_guarded(d, ns_f, ng_f);
                (*pending).du = reflect_guarded((*path).du, nu, ng_f);
                (*pending).dv = reflect_guarded((*path).dv, nv, ng_f);
                (*pending).o = optics_offset_ray_origin(pos, ng_f, scale);
                *has_pending = true;
                (*path).split = 1u;
                (*path).flux *= 1.0 - r;
            }
        } else {
            // After the split: reflect with probability r, flux unchanged (unbiased).
            refract = optics_hash_unit((*path).task, (*path).bounces | ((*path).split << 8u)) >= r;
        }
        if refract {
            // The boundary's transmission tint (row 2; white for clear glass).
            (*path).flux *= scene_material(hit.instance, 2u).xyz;
            (*path).d = t.xyz;
            if !thin {
                let tdu = refract_guarded((*path).du, nu, ng_f, eta);
                let tdv = refract_guarded((*path).dv, nv, ng_f, eta);
                (*path).du = select(t.xyz, tdu.xyz, tdu.w > 0.0);
                (*path).dv = select(t.xyz, tdv.xyz, tdv.w > 0.0);
                (*path).medium = select(INVALID, hit.instance, entering);
            }
            (*path).o = optics_offset_ray_origin(pos, -ng_f, scale);
        } else {
            (*path).d = reflect_guarded(d, ns_f, ng_f);
            (*path).du = reflect_guarded((*path).du, nu, ng_f);
            (*path).dv = reflect_guarded((*path).dv, nv, ng_f);
            (*path).o = optics_offset_ray_origin(pos, ng_f, scale);
        }
#else
        // A scene without dielectrics has no other specular kind.
        return;
#endif
    }
}

// What one thread adds to the shared counters, summed over its workgroup by `trace` before
// any global atomic: every photon adding its flux to the same few words with a float
// compare-exchange loop serialised a wide GPU (44 ms of trace on an H200 at 2^18 photons, and
// values dropped at the loop's cap); lavapipe's 8-wide subgroups on 2 cores never showed it.
var<private> t_flux: vec3<f32>; // lm: reaching a caster, deposited, in flight at the cap or budget
var<private> t_area: f32;       // pixel areas of this thread's non-large splats (all one texel)
var<private> t_n: u32;          // their count
var<private> t_emitted: u32;    // 1 when the thread emitted a photon
var<workgroup> wg_sum: array<vec4<f32>, 64>;
var<workgroup> wg_emitted: array<u32, 64>;
var<workgroup> wg_texel: array<u32, 64>;
var<workgroup> wg_area: array<f32, 64>;
var<workgroup> wg_n: array<u32, 64>;

// A finite flux, else 0 (as accum_add_f32 skips a non-finite value).
fn flux_finite(v: f32) -> f32 {
    return select(0.0, v, abs(v) <= 3.0e38);
}

@compute @workgroup_size(64)
fn trace(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let group = wid.y * nwg.x + wid.x;
    let texel = trace_task(group * 64u + lid);
    wg_sum[lid] = vec4(t_flux, 0.0);
    wg_emitted[lid] = t_emitted;
    wg_texel[lid] = select(INVALID, texel, t_n != 0u);
    wg_area[lid] = t_area;
    wg_n[lid] = t_n;
    workgroupBarrier();
    // Consecutive tasks share a quadtree leaf: the first thread of each run of one texel adds
    // the run's areas and count.
    let mine = wg_texel[lid];
    if mine != INVALID && (lid == 0u || wg_texel[lid - 1u] != mine) {
        var area = 0.0;
        var n = 0u;
        for (var j = lid; j < 64u; j += 1u) {
            if wg_texel[j] != mine {
                break;
            }
            area += wg_area[j];
            n += wg_n[j];
        }
        accum_add_f32(ACCUM_TEXELS + 4u * mine, area);
        atomicAdd(&accum[ACCUM_TEXELS + 4u * mine + 1u], n);
    }
    for (var half = 32u; half > 0u; half >>= 1u) {
        if lid < half {
            wg_sum[lid] += wg_sum[lid + half];
            wg_emitted[lid] += wg_emitted[lid + half];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        // Workgroups spread over the 4 words of each flux counter.
        let slot4 = group & 3u;
        let s = wg_sum[0];
        if s.x != 0.0 {
            accum_add_f32(C_FLUX_CASTER + slot4, s.x);
        }
        if s.y != 0.0 {
            accum_add_f32(C_FLUX_DEPOSITED + slot4, s.y);
        }
        if s.z != 0.0 {
            accum_add_f32(C_FLUX_MAX_DEPTH + slot4, s.z);
        }
        if wg_emitted[0] != 0u {
            atomicAdd(&accum[C_EMITTED], wg_emitted[0]);
        }
    }
}

// One task: emit its photon and follow its paths. Returns the task's texel (INVALID when it
// emits nothing); its sums go to the t_* privates.
fn trace_task(task: u32) -> u32 {
    let limit = min(atomicLoad(&accum[C_TASKS]), params.caps.y);
    if task >= limit {
        return INVALID;
    }
    let w = quadtree_walk(params.atlas.x, task);
    if w.w == 0u {
        return INVALID;
    }
    let light_index = atlas_tile(w.xy);
    if light_index >= params.atlas.w {
        return INVALID;
    }
    t_emitted = 1u;
    let tile = params.atlas.y;
    let local = w.xy % vec2(tile);
    // Each frame rotates the pattern: the temporal stage's mean gathers independent photons.
    let frame = bitcast<u32>(params.budget.w);
    let uv = quadtree_leaf_sample_uv_rotated(local, w.z, tile, quadtree_frame_rotation(frame));
    // Differentials: the spacing of the texel's samples, 1 / sqrt(count) of a texel, along each
    // parameter (inwards at the square's far edges), so splats shrink as the density grows and
    // their overlap stays the same.
    let delta = 1.0 / (f32(tile) * sqrt(f32(max(w.w, 1u))));
    let uv_u = vec2(select(uv.x + delta, uv.x - delta, uv.x + delta > 1.0), uv.y);
    let uv_v = vec2(uv.x, select(uv.y + delta, uv.y - delta, uv.y + delta > 1.0));
    let light = lights[light_index];
    // Section 3.2.1: power / partitions / photons in the partition.
    let texel_power = light.power.xyz / f32(tile * tile);
    var path: Path;
    path.flux = texel_power / f32(w.w);
    path.medium = INVALID;
    path.bounces = 0u;
    path.split = 0u;
    // The branch choices' key: the task and the frame.
    path.task = task ^ optics_pcg_hash(frame);
    // The differential rays leave the light at the neighbouring parameters.
    let e = light_emit(light, uv);
    let eu = light_emit(light, uv_u);
    let ev = light_emit(light, uv_v);
    path.o = e.o;
    path.d = e.d;
    path.ou = eu.o;
    path.du = eu.d;
    path.ov = ev.o;
    path.dv = ev.d;
    path.flux *= e.weight;
    path.seg_start = path.o;
    let texel = w.y * params.atlas.x + w.x;
    if all(path.flux <= vec3(0.0)) {
        return texel;
    }
    let texel_energy = luminance(texel_power);
    var pending: Path;
    var has_pending = false;
    var events = event_budget();
    run_path(&path, &pending, &has_pending, &events, texel, texel_energy);
    if has_pending {
        var none = false;
        run_path(&pending, &path, &none, &events, texel, texel_energy);
    }
    if events.used != 0u {
        atomicAdd(&accum[C_EVENTS], events.used);
    }
    if events.left != 0u {
        atomicSub(&accum[C_EVENTS_GRANTED], events.left);
    }
    return texel;
}
