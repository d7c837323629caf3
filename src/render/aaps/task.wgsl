// The AAPS task buffer (seed 004 sections 2.3.1 and 3.1.5): quadtree build, indirect arguments,
// variance by reprojection, density update and budget scaling. Bindings: common.wgsl, plus
// the per-level uniform below and the argument buffer in group 1.

struct QtLevel {
    src: u32,
    dst: u32,
    dst_size: u32,
    pad: u32,
}

@group(0) @binding(16) var<uniform> qt_level: QtLevel;
// [0..3) trace dispatch, [4..7) variance dispatch, [8..12) plain draw, [12..16) MSAA draw.
@group(1) @binding(0) var<storage, read_write> args: array<u32>;

fn texel_valid(i: u32) -> bool {
    let a = params.atlas.x;
    return atlas_tile(vec2(i % a, i / a)) < params.atlas.w;
}

@compute @workgroup_size(64)
fn qt_leaves(@builtin(global_invocation_id) id: vec3<u32>) {
    let a = params.atlas.x;
    if id.x >= a * a {
        return;
    }
    qt_levels[id.x] = select(0u, optics_photon_count(density[id.x]), texel_valid(id.x));
}

fn add_sat(x: u32, y: u32) -> u32 {
    return select(x + y, 0xffffffffu, x > 0xffffffffu - y);
}

@compute @workgroup_size(64)
fn qt_reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = qt_level.dst_size;
    if id.x >= n * n {
        return;
    }
    let x = id.x % n;
    let y = id.x / n;
    let s = 2u * n;
    let i = qt_level.src + 2u * y * s + 2u * x;
    let sum = add_sat(add_sat(qt_levels[i], qt_levels[i + 1u]), add_sat(qt_levels[i + s], qt_levels[i + s + 1u]));
    qt_levels[qt_level.dst + id.x] = sum;
}

fn dispatch_for(threads: u32, at: u32) {
    let groups = (threads + 63u) / 64u;
    let x = min(groups, 65535u);
    args[at] = x;
    args[at + 1u] = select(1u, (groups + x - 1u) / max(x, 1u), x > 0u);
    args[at + 2u] = 1u;
}

@compute @workgroup_size(1)
fn write_trace_args() {
    var off = 0u;
    var s = params.atlas.x;
    while s > 1u {
        off += s * s;
        s /= 2u;
    }
    let total = qt_levels[off];
    let n = min(total, params.caps.y);
    atomicStore(&accum[C_TASKS], total);
    atomicStore(&accum[C_PHOTON_OVERFLOW], total - n);
    dispatch_for(n, 0u);
}

@compute @workgroup_size(1)
fn write_draw_args() {
    let big = atomicLoad(&accum[C_BIG]);
    let small = atomicLoad(&accum[C_SMALL]);
    args[8] = 6u;
    args[9] = big;
    args[10] = 0u;
    args[11] = 0u;
    args[12] = 6u;
    args[13] = small;
    args[14] = 0u;
    args[15] = 0u;
    dispatch_for(big + small, 4u);
}

fn record_index(i: u32) -> u32 {
    let big = atomicLoad(&accum[C_BIG]);
    return select(params.caps.x - 1u - (i - big), i, i < big);
}

// Section 3.1.5: the difference between the caustics value at a photon's pixel now and at
// its reprojected pixel in the previous frame, as a relative squared difference in [0, 1],
// weighted by the photon's energy fraction of its texel. 0 when it cannot be found.
@compute @workgroup_size(64)
fn variance(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = (wid.y * nwg.x + wid.x) * 64u + lid;
    let used = atomicLoad(&accum[C_BIG]) + atomicLoad(&accum[C_SMALL]);
    if i >= used || params.viewport.z == 0.0 {
        return;
    }
    let s = splats[record_index(i)];
    let size = params.viewport.xy;
    let now = aaps_to_pixel(params.clip_from_world, s.center.xyz, size);
    let before = aaps_to_pixel(params.prev_clip_from_world, s.center.xyz, size);
    let inside = now.z > 0.0 && before.z > 0.0 && all(now.xy >= vec2(0.0)) && all(now.xy < size)
        && all(before.xy >= vec2(0.0)) && all(before.xy < size);
    if !inside {
        return;
    }
    let lc = luminance(textureLoad(caustics_now, vec2<i32>(now.xy), 0).rgb);
    let lp = luminance(textureLoad(caustics_prev, vec2<i32>(before.xy), 0).rgb);
    let m = max(max(lc, lp), 1.0e-20);
    let rel = (lc - lp) / m;
    let v = select(0.0, rel * rel, abs(rel) <= 1.0);
    accum_add_f32(ACCUM_TEXELS + 4u * bitcast<u32>(s.center.w) + 2u, v * s.b.w);
}

// The sum of D' over the atlas, reduced per workgroup: one float compare-exchange per 64
// texels on the single C_DENSITY_SUM word, not one per texel (a wide GPU serialised those).
var<workgroup> wg_density: array<f32, 64>;

@compute @workgroup_size(64)
fn density_update(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    wg_density[lid] = density_update_texel(id.x);
    workgroupBarrier();
    for (var half = 32u; half > 0u; half >>= 1u) {
        if lid < half {
            wg_density[lid] += wg_density[lid + half];
        }
        workgroupBarrier();
    }
    if lid == 0u && wg_density[0] != 0.0 {
        accum_add_f32(C_DENSITY_SUM, wg_density[0]);
    }
}

// Section 3.1.5: D' = D A / A_t + v g, blended with the texel's and its four neighbours'
// previous densities (inside the light's tile), clamped, rounded down to a square.
// Of texel i, written to density_next; returns it (0 past the atlas or outside a tile).
fn density_update_texel(i: u32) -> f32 {
    let a = params.atlas.x;
    if i >= a * a {
        return 0.0;
    }
    if !texel_valid(i) {
        density_next[i] = 0.0;
        return 0.0;
    }
    let base = ACCUM_TEXELS + 4u * i;
    let n = atomicLoad(&accum[base + 1u]);
    let area = select(0.0, accum_f32(base) / f32(n), n > 0u);
    let v = accum_f32(base + 2u);
    let sent = f32(optics_photon_count(density[i]));
    if n > 0u {
        atomicAdd(&accum[C_CONTRIBUTING], 1u);
    }
    let suggested = optics_suggested_density(sent, area, params.density.x, v, params.density.y);
    let x = i % a;
    let y = i / a;
    let tile = params.atlas.y;
    var prev: array<f32, 5>;
    prev[0] = density[i];
    var count = 1u;
    let offs = array<vec2<i32>, 4>(vec2(-1, 0), vec2(1, 0), vec2(0, -1), vec2(0, 1));
    for (var k = 0u; k < 4u; k += 1u) {
        let q = vec2<i32>(i32(x), i32(y)) + offs[k];
        if q.x < 0 || q.y < 0 || q.x >= i32(a) || q.y >= i32(a) {
            continue;
        }
        let qu = vec2<u32>(q);
        if qu.x / tile != x / tile || qu.y / tile != y / tile {
            continue;
        }
        prev[count] = density[qu.y * a + qu.x];
        count += 1u;
    }
    let d = optics_blend_density(suggested, prev, count, params.density.z, params.density.w, params.limits.x);
    density_next[i] = d;
    return select(0.0, d, abs(d) <= 3.0e38);
}

// The frame's photon budget (ours, optics::budget_split): a floor of `params.budget.x` of it
// over the texels whose photons reached a visible receiver, the rest by D', scaled down.
@compute @workgroup_size(64)
fn density_scale(@builtin(global_invocation_id) id: vec3<u32>) {
    let a = params.atlas.x;
    if id.x >= a * a {
        return;
    }
    if !texel_valid(id.x) {
        density[id.x] = 0.0;
        return;
    }
    let contributing = atomicLoad(&accum[C_CONTRIBUTING]);
    let texels = params.atlas.y * params.atlas.y * params.atlas.w;
    let split = optics_budget_split(params.limits.y, params.budget.x, accum_f32(C_DENSITY_SUM), contributing, texels - min(contributing, texels), params.density.w);
    let here = atomicLoad(&accum[ACCUM_TEXELS + 4u * id.x + 1u]) > 0u;
    density[id.x] = optics_budget_density(density_next[id.x], here, split.x, split.y, params.density.w, params.limits.x);
}
