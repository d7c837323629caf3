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

// The prior's colour clamped to luminance `c` (its own colour where it has one).
fn with_luminance(prior: vec3<f32>, now: vec3<f32>, c: f32) -> vec3<f32> {
    let hl = lum(prior);
    let l = lum(now);
    if hl > 0.0 {
        return prior * (c / hl);
    }
    if l > 0.0 {
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
    let stored = clean(textureLoad(prior_in, h, 0));
    var prior = stored.rgb;
    var n = max(stored.a, 0.0);
    if (params.flags & FLAG_RESET) != 0u {
        prior = vec3(0.0);
        n = 0.0;
    } else if k <= 1.0 {
        prior = clean(textureLoad(last_in, h, 0)).rgb;
        n += max(params.k_last, 1.0);
    }
    if other {
        n = 0.0;
    }
    textureStore(depth_out, p, vec4(z, 0.0, 0.0, 0.0));
    if n > 0.0 && (params.flags & FLAG_CLAMP) != 0u {
        let ms = neighbourhood(p);
        let hl = lum(prior);
        let c = clamp(hl, max(ms.x - params.gamma * ms.y, 0.0), ms.x + params.gamma * ms.y);
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
