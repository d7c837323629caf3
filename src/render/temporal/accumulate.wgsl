// The shared temporal stage (src/render/temporal/mod.rs): this frame's estimate of a view's
// caustic irradiance (lux, the caustics buffer as the technique left it) combined with the
// view's history. Knows no technique.
//
// The estimate covers `k` frames (params.k): 1 for a technique that shows each frame alone,
// more for one that keeps its own mean (the photon map's progressive frames since its last
// restart). Per pixel the stage keeps a prior P of n_P frames and the last output L:
// - a fresh estimate (k = 1) first folds the last output into the prior (P = L, n_P += k of
//   the last run), so a technique of single frames gets a running mean;
// - an estimate that continues its own mean (k > 1) keeps the prior as it was;
// - the output is (n_P P + k E) / (n_P + k), with n_P at most max_history - k, so a
//   technique's own mean takes over as it grows.
// On a frame in which the scene changed, and on the max_history frames after it (`FLAG_CLAMP`),
// a prior whose luminance lies outside the estimate's 3x3 neighbourhood mean ± gamma standard
// errors of that mean (sigma / sqrt(9); the window of Karis's and Salvi's TAA history clamp,
// on irradiance, narrowed to the noise of the mean: with sigma itself a noisy single frame's
// window reached down to 0 and a caustic moving 1 cm a frame trailed 2 to 3 frames), is
// clamped into it and keeps at most `clamped_history` frames (0: dropped), so a moved caustic leaves no
// ghost while an unchanged one keeps its history. The test goes on after the change because a
// technique that restarts its own mean judges badly on its first frames (a wide window) and
// better as its mean grows, while the prior can weigh for max_history frames. A view in which
// the scene has not changed for max_history frames is not tested: the estimates differ by noise
// only, and the mean converges.
//
// A caustic moves with its caster, and the view's depth says nothing of that motion. On a frame
// in which the scene changed where a caustic can and the camera did not move (`FLAG_MOTION`;
// not on the frames after it, where a still caustic's noise alone would pick shifts),
// `motion` first matches each 8x8 tile of the estimate against the last output shifted by up
// to MOTION_RADIUS pixels (block matching, the sum of absolute differences of the luminance
// of MOTION_BLOCK² blocks, which a noisy estimate disturbs less than single pixels; whole
// pixels, then half and quarter pixels around the best, bilinear), and `accumulate` takes the
// tile's history from where it matched best (Catmull-Rom). A shift is taken only when it fits
// better than none by MOTION_MARGIN, so noise does not move a caustic that stood still; the
// clamp then judges the shifted history in a window MOTION_CLAMP_WIDEN times as wide.

struct TemporalParams {
    size: vec2<u32>,
    flags: u32,
    k: f32,
    k_last: f32,
    max_history: f32,
    gamma: f32,
    clamped_history: f32,
    depth_tolerance: f32,
    // With FLAG_REPROJECT: last frame's clip_from_world times this frame's world_from_clip.
    reproject: mat4x4<f32>,
}

const FLAG_RESET: u32 = 1u;
const FLAG_CLAMP: u32 = 2u;
const FLAG_SURFACES: u32 = 4u;
const FLAG_REPROJECT: u32 = 8u;
const FLAG_MOTION: u32 = 16u;

// Side of a motion tile (px), the largest shift searched (px) and the share by which a shift
// must lower the tile's difference below that of no shift.
const MOTION_TILE: u32 = 8u;
const MOTION_RADIUS: i32 = 2;
const MOTION_SHIFTS: u32 = 25u; // (2 MOTION_RADIUS + 1)^2
const MOTION_MARGIN: f32 = 0.02;
// Side of the blocks whose luminance sums the tile's cost compares (px). Sliding ball,
// against converged references: single pixels AAPS 1.18x its still RMSE and the photon map
// 1.42x, 2x2 blocks 1.09x and 1.37x, 4x4 blocks 1.22x and 1.49x.
const MOTION_BLOCK: u32 = 2u;
// The clamp's window is this many times wider for a history taken from a matched shift: the
// resampled history differs from the estimate by its interpolation as well as by noise.
const MOTION_CLAMP_WIDEN: f32 = 3.0;

@group(0) @binding(0) var<uniform> params: TemporalParams;
// This frame's estimate (the caustics buffer).
@group(0) @binding(1) var current: texture_2d<f32>;
// The prior (rgb, a its frames) and the last output (rgb, a the estimate's alpha).
@group(0) @binding(2) var prior_in: texture_2d<f32>;
@group(0) @binding(3) var last_in: texture_2d<f32>;
@group(0) @binding(4) var prior_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var last_out: texture_storage_2d<rgba32float, write>;
// The view's depth this frame (reverse-Z NDC), and the depth the history belongs to.
@group(0) @binding(6) var view_depth: texture_depth_2d;
@group(0) @binding(7) var depth_in: texture_2d<f32>;
@group(0) @binding(8) var depth_out: texture_storage_2d<r32float, write>;
// Per motion tile (row-major, ceil(size / MOTION_TILE)): the shift from the tile's pixels to
// where their history lies, pixels (`pack2x16float`).
@group(0) @binding(9) var<storage, read_write> tile_motion: array<u32>;

fn lum(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Guard: a NaN or infinity in any input reads as 0.
fn clean(c: vec4<f32>) -> vec4<f32> {
    return select(vec4(0.0), c, all(c == c) && all(abs(c) <= vec4(3.0e38)));
}

// Luminance mean of the estimate over the 3x3 around `p`, and that mean's standard error
// (the neighbourhood's standard deviation over the square root of its pixel count).
fn neighbourhood(p: vec2<i32>) -> vec2<f32> {
    var s = 0.0;
    var s2 = 0.0;
    var k = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = p + vec2(dx, dy);
            if any(q < vec2(0)) || any(q >= vec2<i32>(params.size)) {
                continue;
            }
            let l = lum(clean(textureLoad(current, q, 0)).rgb);
            s += l;
            s2 += l * l;
            k += 1.0;
        }
    }
    let mu = s / max(k, 1.0);
    return vec2(mu, sqrt(max(s2 / max(k, 1.0) - mu * mu, 0.0) / max(k, 1.0)));
}

// The prior's colour clamped to luminance `c` (its own colour where it has one). Guard: a
// colour is scaled by at most MAX_RESCALE, so a luminance near the smallest floats neither
// overflows the scale nor makes 0 x inf a NaN (seen: image space with three à-trous
// iterations showed NaN pixels); a darker colour gives way to the next.
const MAX_RESCALE: f32 = 1.0e30;
fn with_luminance(prior: vec3<f32>, now: vec3<f32>, c: f32) -> vec3<f32> {
    let hl = lum(prior);
    let l = lum(now);
    if hl > 0.0 && c <= hl * MAX_RESCALE {
        return prior * (c / hl);
    }
    if l > 0.0 && c <= l * MAX_RESCALE {
        return now * (c / l);
    }
    return vec3(c);
}

// With a moved camera: where last frame's view showed the surface of pixel `p` (depth `z`,
// reverse-Z NDC), as (pixel x, pixel y, that surface's depth there); x < 0 when it was off
// screen or `p` shows no surface. Irradiance belongs to the place, so the history follows the
// surface (the camera's own motion, no motion vectors of moving objects).
fn reprojected(p: vec2<i32>, z: f32) -> vec3<f32> {
    if !(z > 0.0) {
        return vec3(-1.0);
    }
    let size = vec2<f32>(params.size);
    let ndc = vec2((f32(p.x) + 0.5) / size.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / size.y * 2.0);
    let c = params.reproject * vec4(ndc, z, 1.0);
    if !(c.w > 0.0) {
        return vec3(-1.0);
    }
    let n = c.xyz / c.w;
    let q = vec2((n.x + 1.0) * 0.5 * size.x, (1.0 - n.y) * 0.5 * size.y);
    if !(all(q >= vec2(0.0)) && all(q < size)) {
        return vec3(-1.0);
    }
    return vec3(q, n.z);
}

// Whether depths `a` and `b` (reverse-Z NDC) are of one surface.
fn same_surface(a: f32, b: f32) -> bool {
    return abs(a - b) <= params.depth_tolerance * max(a, b);
}

var<workgroup> shift_cost: array<f32, MOTION_SHIFTS>;
var<workgroup> shift_best: vec2<f32>;

fn shift_of(i: u32) -> vec2<f32> {
    let side = u32(2 * MOTION_RADIUS + 1);
    return vec2(f32(i % side), f32(i / side)) - f32(MOTION_RADIUS);
}

// Luminance of the last output at pixel position `x` (pixel centres at .5), bilinear; 0 off
// screen.
fn last_lum(x: vec2<f32>) -> f32 {
    let f = x - 0.5;
    let i = vec2<i32>(floor(f));
    let t = f - floor(f);
    let size = vec2<i32>(params.size);
    var c = 0.0;
    for (var k = 0; k < 4; k += 1) {
        let o = vec2(k & 1, k >> 1);
        let q = i + o;
        if all(q >= vec2(0)) && all(q < size) {
            let w = mix(1.0 - t, t, vec2<f32>(o));
            c += w.x * w.y * lum(clean(textureLoad(last_in, q, 0)).rgb);
        }
    }
    return c;
}

// Sum over the tile's MOTION_BLOCK² pixel blocks of |Σ lum(estimate) - Σ lum(last output
// shifted by `s` px)|: a 2x2 block's sum has half a pixel's relative noise, so a noisy
// estimate still tells a shift from none.
fn tile_cost(tile: vec2<u32>, s: vec2<f32>) -> f32 {
    var c = 0.0;
    let size = vec2<i32>(params.size);
    let blocks = MOTION_TILE / MOTION_BLOCK; // per side
    for (var b = 0u; b < blocks * blocks; b += 1u) {
        let corner = vec2<i32>(tile * MOTION_TILE + MOTION_BLOCK * vec2(b % blocks, b / blocks));
        var d = 0.0;
        for (var i = 0u; i < MOTION_BLOCK * MOTION_BLOCK; i += 1u) {
            let p = corner + vec2<i32>(vec2(i % MOTION_BLOCK, i / MOTION_BLOCK));
            if all(p < size) {
                let now = lum(clean(textureLoad(current, p, 0)).rgb);
                d += now - last_lum(vec2<f32>(p) + 0.5 - s);
            }
        }
        c += abs(d);
    }
    return c;
}

// The best of `count` costs (the first on a tie).
fn best_cost(count: u32) -> u32 {
    var best = 0u;
    for (var i = 1u; i < count; i += 1u) {
        if shift_cost[i] < shift_cost[best] {
            best = i;
        }
    }
    return best;
}

// One workgroup per motion tile, coarse to fine: MOTION_SHIFTS threads score the whole-pixel
// shifts, then 9 score the best one and its neighbours half a pixel away, then a quarter. The
// shift is kept when it fits better than none by MOTION_MARGIN (else none).
@compute @workgroup_size(32)
fn motion(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li < MOTION_SHIFTS {
        shift_cost[li] = tile_cost(wg.xy, shift_of(li));
    }
    workgroupBarrier();
    let still = shift_cost[(MOTION_SHIFTS - 1u) / 2u];
    if li == 0u {
        shift_best = shift_of(best_cost(MOTION_SHIFTS));
    }
    workgroupBarrier();
    for (var step = 0.5; step > 0.2; step *= 0.5) {
        let centre = shift_best;
        workgroupBarrier();
        if li < 9u {
            let o = vec2(f32(li % 3u), f32(li / 3u)) - 1.0;
            shift_cost[li] = tile_cost(wg.xy, centre + step * o);
        }
        workgroupBarrier();
        if li == 0u {
            let b = best_cost(9u);
            shift_best = centre + step * (vec2(f32(b % 3u), f32(b / 3u)) - 1.0);
            if !(shift_cost[b] < (1.0 - MOTION_MARGIN) * still) {
                shift_best = vec2(0.0);
            }
        }
        workgroupBarrier();
    }
    if li == 0u {
        let tiles = (params.size + MOTION_TILE - 1u) / MOTION_TILE;
        tile_motion[wg.y * tiles.x + wg.x] = pack2x16float(shift_best);
    }
}

// The shift of pixel `p`'s tile (`motion`'s result), pixels.
fn moved_by(p: vec2<i32>) -> vec2<f32> {
    let tiles = (params.size + MOTION_TILE - 1u) / MOTION_TILE;
    let t = vec2<u32>(p) / MOTION_TILE;
    return unpack2x16float(tile_motion[t.y * tiles.x + t.x]);
}

// Catmull-Rom weights of the four texels around a sample at fraction `t` past the second.
fn catmull_rom(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return vec4(
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    );
}

// `tex` at pixel position `x` (pixel centres at .5), Catmull-Rom (sharp: a history resampled on
// every frame of a moving caustic blurs less than bilinear), edges clamped, kept >= 0 and finite.
fn resampled(tex: texture_2d<f32>, x: vec2<f32>) -> vec4<f32> {
    let f = x - 0.5;
    let i = vec2<i32>(floor(f));
    let wx = catmull_rom(f.x - floor(f.x));
    let wy = catmull_rom(f.y - floor(f.y));
    let hi = vec2<i32>(params.size) - 1;
    var c = vec4(0.0);
    for (var y = 0; y < 4; y += 1) {
        for (var x = 0; x < 4; x += 1) {
            let q = clamp(i + vec2(x - 1, y - 1), vec2(0), hi);
            c += wx[x] * wy[y] * clean(textureLoad(tex, q, 0));
        }
    }
    return clean(vec4(max(c.rgb, vec3(0.0)), max(c.a, 0.0)));
}

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) gid: vec3<u32>) {
    if any(gid.xy >= params.size) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let now = clean(textureLoad(current, p, 0));
    let k = max(params.k, 1.0);
    let z = textureLoad(view_depth, p, 0);
    // Where this pixel's history lies, and whether it belongs to another surface.
    var h = p;
    var other = false;
    if (params.flags & FLAG_REPROJECT) != 0u {
        let r = reprojected(p, z);
        if r.x < 0.0 {
            other = true;
        } else {
            h = vec2<i32>(floor(r.xy));
            other = !same_surface(r.z, textureLoad(depth_in, h, 0).r);
        }
    } else if (params.flags & FLAG_SURFACES) != 0u {
        // The scene's geometry changed (a receiver moved, even one out of the caustic light's
        // reach): a pixel whose depth moved shows another surface.
        other = !same_surface(z, textureLoad(depth_in, p, 0).r);
    }
    // The caustic moved with its caster: the history lies where the tile matched, on the same
    // surface.
    var shift = vec2(0.0);
    if (params.flags & FLAG_MOTION) != 0u {
        shift = moved_by(p);
        let m = vec2<i32>(floor(vec2<f32>(p) + 0.5 - shift));
        if all(m >= vec2(0)) && all(m < vec2<i32>(params.size)) {
            other = other || !same_surface(z, textureLoad(depth_in, m, 0).r);
        } else {
            shift = vec2(0.0);
        }
    }
    let x = vec2<f32>(h) + 0.5 - shift;
    var stored = clean(textureLoad(prior_in, h, 0));
    if any(shift != vec2(0.0)) {
        stored = resampled(prior_in, x);
    }
    var prior = stored.rgb;
    var n = max(stored.a, 0.0);
    if (params.flags & FLAG_RESET) != 0u {
        prior = vec3(0.0);
        n = 0.0;
    } else if k <= 1.0 {
        prior = clean(textureLoad(last_in, h, 0)).rgb;
        if any(shift != vec2(0.0)) {
            prior = resampled(last_in, x).rgb;
        }
        n += max(params.k_last, 1.0);
    }
    if other {
        n = 0.0;
    }
    textureStore(depth_out, p, vec4(z, 0.0, 0.0, 0.0));
    if n > 0.0 && (params.flags & FLAG_CLAMP) != 0u {
        let ms = neighbourhood(p);
        let hl = lum(prior);
        let gamma = params.gamma * select(1.0, MOTION_CLAMP_WIDEN, any(shift != vec2(0.0)));
        let c = clamp(hl, max(ms.x - gamma * ms.y, 0.0), ms.x + gamma * ms.y);
        if c != hl {
            prior = with_luminance(prior, now.rgb, c);
            n = min(n, params.clamped_history);
        }
    }
    n = min(n, max(params.max_history - k, 0.0));
    let combined = (n * prior + k * now.rgb) / (n + k);
    textureStore(prior_out, p, vec4(prior, n));
    textureStore(last_out, p, vec4(combined, now.a));
}
