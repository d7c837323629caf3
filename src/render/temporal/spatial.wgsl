// The shared temporal stage's spatial filter (src/render/temporal/mod.rs): after `accumulate`
// has combined this frame's estimate with the history, a few à-trous iterations (Dammertz et
// al. 2010) smooth the output where it is noisy and keep its edges, as SVGF's filter does
// (Schied et al. 2017, eq. 3-5: `optics_svgf_weight`), on irradiance in lux. The history stays
// unfiltered: only the caustics buffer shows the filtered output, so the blur never feeds back.
// Appended to optics.wgsl.
//
// `spatial_prep` gives each pixel the smaller of two estimates of the standard deviation of
// the output's luminance (docs/temporal.md, "The spatial filter", has the measurements):
// - from its change since the last frame: a running mean of N frames moves by (x - mean) / N,
//   so N E[Δ²] is σ² / N, the variance of the mean (E[Δ²] over the 3x3 neighbourhood; N = the
//   prior's frames plus the estimate's). A caustic's shape does not enter it; but where the
//   history was dropped (a caster moved) the output jumped by the caustic's motion too, and
//   alone it blurred the photon map's moved caustic (sliding ball 145 -> 218 lx);
// - from this frame's estimate of k frames: its 3x3 luminance variance times k / N. Alone it
//   holds the caustic's shape and blurred the still focus (105.7 -> 176 lx).
// `spatial_atrous` is one 5x5 B3 iteration at a step of 1, 2, 4, ... pixels with depth and
// luminance edge stopping. Its luminance term uses the smaller deviation of the two pixels
// (image space's symmetric rule, src/render/image_space/svgf.wgsl): a dark, quiet pixel and
// its bright, noisy neighbour reject each other, so the filter moves no energy out of a
// caustic. Pixels whose buffer alpha differs in sign (a mirror's reflected caustic against a
// surface's own) never mix. The deviation is carried through the iterations
// (Σ w² dev_q² / (Σ w)²); the last iteration writes the buffer's alpha back.

struct SpatialParams {
    size: vec2<u32>,
    step: u32,
    flags: u32,
    // Frames this frame's estimate covers.
    k: f32,
    // Luminance edge stopping, in deviations; depth edge stopping, in depth gradients.
    sigma_l: f32,
    sigma_z: f32,
    pad: f32,
}

const SPATIAL_LAST: u32 = 1u;

@group(0) @binding(0) var<uniform> sp: SpatialParams;
// spatial_prep: the stage's output; spatial_atrous: the last iteration's (a: the deviation).
@group(0) @binding(1) var src: texture_2d<f32>;
// spatial_prep: the stage's last output (last frame's, unfiltered); spatial_atrous: the
// stage's output (its alpha is the buffer's).
@group(0) @binding(2) var aux: texture_2d<f32>;
// The prior the output averaged in (a: its frames).
@group(0) @binding(3) var prior: texture_2d<f32>;
// This frame's depth (reverse-Z NDC, 0 where nothing was drawn).
@group(0) @binding(4) var depth: texture_2d<f32>;
@group(0) @binding(5) var dst: texture_storage_2d<rgba32float, write>;
// This frame's estimate (the caustics buffer as the technique left it).
@group(0) @binding(6) var estimate: texture_2d<f32>;

fn spatial_lum(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

fn spatial_clean(c: vec4<f32>) -> vec4<f32> {
    return select(vec4(0.0), c, all(c == c) && all(abs(c) <= vec4(3.0e38)));
}

fn spatial_inside(q: vec2<i32>) -> bool {
    return all(q >= vec2(0)) && all(q < vec2<i32>(sp.size));
}

fn depth_at(q: vec2<i32>) -> f32 {
    return textureLoad(depth, clamp(q, vec2(0), vec2<i32>(sp.size) - 1), 0).r;
}

@compute @workgroup_size(8, 8)
fn spatial_prep(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if !spatial_inside(p) {
        return;
    }
    var d2 = 0.0;
    var s1 = 0.0;
    var s2 = 0.0;
    var m = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = p + vec2(dx, dy);
            if !spatial_inside(q) {
                continue;
            }
            let d = spatial_lum(spatial_clean(textureLoad(src, q, 0)).rgb)
                - spatial_lum(spatial_clean(textureLoad(aux, q, 0)).rgb);
            let l = spatial_lum(spatial_clean(textureLoad(estimate, q, 0)).rgb);
            d2 += d * d;
            s1 += l;
            s2 += l * l;
            m += 1.0;
        }
    }
    let k = max(sp.k, 1.0);
    let n = max(spatial_clean(textureLoad(prior, p, 0)).a, 0.0) + k;
    let mu = s1 / max(m, 1.0);
    let spatial_var = max(s2 / max(m, 1.0) - mu * mu, 0.0) * k / n;
    let dev = sqrt(min(n * d2 / max(m, 1.0), spatial_var));
    textureStore(dst, p, vec4(spatial_clean(textureLoad(src, p, 0)).rgb, dev));
}

@compute @workgroup_size(8, 8)
fn spatial_atrous(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if !spatial_inside(p) {
        return;
    }
    let cp = spatial_clean(textureLoad(src, p, 0));
    let marker = textureLoad(aux, p, 0).a;
    let zp = textureLoad(depth, p, 0).r;
    var out = cp.rgb;
    var dev = cp.a;
    if zp > 0.0 {
        // Reverse-Z NDC depth is affine in screen space on a plane: its gradient predicts a
        // neighbour's depth on the same surface.
        let grad = 0.5 * vec2(depth_at(p + vec2(1, 0)) - depth_at(p - vec2(1, 0)), depth_at(p + vec2(0, 1)) - depth_at(p - vec2(0, 1)));
        let b3 = array<f32, 3>(0.375, 0.25, 0.0625);
        let s = i32(sp.step);
        let lp = spatial_lum(cp.rgb);
        var sum = cp.rgb;
        var sum_v = cp.a * cp.a;
        var wsum = 1.0;
        for (var dy = -2; dy <= 2; dy += 1) {
            for (var dx = -2; dx <= 2; dx += 1) {
                let q = p + vec2(dx, dy) * s;
                if (dx == 0 && dy == 0) || !spatial_inside(q) {
                    continue;
                }
                let zq = textureLoad(depth, q, 0).r;
                if zq <= 0.0 || (textureLoad(aux, q, 0).a < 0.0) != (marker < 0.0) {
                    continue;
                }
                let cq = spatial_clean(textureLoad(src, q, 0));
                let off = vec2<f32>(vec2(dx, dy) * s);
                let dz_scaled = sp.sigma_z * max(abs(dot(grad, off)), 1.0e-3 * zp);
                let h = b3[abs(dx)] * b3[abs(dy)] / (b3[0] * b3[0]);
                let l_sigma = sp.sigma_l * min(cp.a, cq.a);
                let w = h * optics_svgf_weight(zp - zq, dz_scaled, 1.0, 0.0, lp - spatial_lum(cq.rgb), l_sigma);
                sum += w * cq.rgb;
                sum_v += w * w * cq.a * cq.a;
                wsum += w;
            }
        }
        out = sum / wsum;
        dev = sqrt(sum_v) / wsum;
    }
    let last = (sp.flags & SPATIAL_LAST) != 0u;
    textureStore(dst, p, vec4(out, select(dev, marker, last)));
}
