// SVGF (Schied et al. 2017) over the photon map, as section 3.3 of seed 003 uses it:
// `temporal` reprojects last frame's history with the camera's previous clip_from_world (a
// 2x2 bilinear tap, each tap tested for depth and normal; none valid is a disocclusion),
// blends colour and luminance moments with max(alpha, 1 / history) (colour: 1 / history alone
// once the view and its caustics stand, FLAG_STILL_VIEW); `variance` turns the
// moments into a variance (a 7x7 bilateral estimate while the history is under
// SHORT_HISTORY frames); `atrous_prep` + `atrous` are one 5x5 B3 à-trous iteration with
// depth, normal and luminance edge stopping (optics_svgf_weight) on a 3x3-prefiltered
// variance, with symmetric weights (see `atrous`), the first iteration only on a short
// history. Irradiance in lux throughout: no albedo to demodulate, no clamp to [0, 1].
// Appended to trace.wgsl (same bindings).

// History length (frames) under which the variance is estimated spatially and the à-trous
// filter runs one iteration only (`atrous`).
const SHORT_HISTORY: f32 = 4.0;

fn lum(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

fn view_size() -> vec2<i32> {
    return vec2<i32>(params.camera.size.xy);
}

fn in_view(q: vec2<i32>) -> bool {
    return all(q >= vec2(0)) && all(q < view_size());
}

fn clean(c: vec4<f32>) -> vec4<f32> {
    return select(vec4(0.0), c, all(c == c) && all(abs(c) <= vec4(3.0e38)));
}

@compute @workgroup_size(8, 8)
fn temporal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if !in_view(p) {
        return;
    }
    let raw = clean(textureLoad(src_a, p, 0)).rgb;
    let z = camera_depth(p);
    let n = gbuffer_normal(p);
    if z <= 0.0 || n.w == 0.0 {
        textureStore(out_a, p, vec4(0.0));
        textureStore(out_b, p, vec4(0.0));
        return;
    }
    var hist = vec3(0.0);
    var moments = vec2(0.0);
    var h = 0.0;
    if (params.frame.w & FLAG_RESET) == 0u {
        let x = unproject(params.camera, vec2<f32>(p) + 0.5, z);
        let c = params.prev_clip_from_world * vec4(x, 1.0);
        if c.w > 0.0 {
            let pp = ndc_to_px(c.xy / c.w, params.camera.size.xy) - 0.5;
            let base = vec2<i32>(floor(pp));
            let f = pp - floor(pp);
            var wsum = 0.0;
            for (var k = 0; k < 4; k += 1) {
                let o = vec2(k & 1, k >> 1);
                let q = base + o;
                if !in_view(q) {
                    continue;
                }
                let zn = textureLoad(src_d, q, 0);
                // Depth within 5 % of the expected previous depth (c.w is the view depth of
                // a perspective camera), normals within 25 degrees.
                if zn.x <= 0.0 || abs(zn.x - c.w) > 0.05 * c.w || dot(zn.yzw, n.xyz) < 0.9 {
                    continue;
                }
                let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
                let hc = clean(textureLoad(src_b, q, 0));
                let hm = clean(textureLoad(src_c, q, 0));
                hist += w * hc.rgb;
                moments += w * hm.xy;
                h += w * hm.z;
                wsum += w;
            }
            if wsum > 1.0e-4 {
                hist /= wsum;
                moments /= wsum;
                h = floor(h / wsum + 0.5);
            } else {
                h = 0.0;
            }
        }
    }
    h = min(h + 1.0, params.svgf.z);
    // While the camera moves, the colour blend keeps its floor alpha (a reprojected history
    // blurs a little every frame); once the view and the caustics stand (a caustic change
    // resets the history) the history is the plain mean of up to `history_cap` unfiltered
    // frames, so something moving elsewhere does not keep the caustic flickering at alpha's
    // noise.
    let still = (params.frame.w & FLAG_STILL_VIEW) != 0u;
    let a = max(select(params.svgf.x, 0.0, still), 1.0 / h);
    let am = max(params.svgf.y, 1.0 / h);
    let l = lum(raw);
    let col = mix(hist, raw, a);
    let m = mix(moments, vec2(l, l * l), am);
    textureStore(out_a, p, vec4(col, h));
    textureStore(out_b, p, vec4(m, h, 0.0));
}

// Writes the filtered (colour, variance) of the last pass: into the caustics buffer (alpha 0)
// when FLAG_LAST, else into the next ping-pong texture; the colour history when FLAG_HISTORY.
fn filter_out(p: vec2<i32>, c: vec3<f32>, var_: f32) {
    let v = vec4(c, max(var_, 0.0));
    if (pass_step.y & FLAG_LAST) != 0u {
        textureStore(out_a, p, vec4(c, 0.0));
    } else {
        textureStore(out_a, p, v);
    }
    if (pass_step.y & FLAG_HISTORY) != 0u {
        textureStore(out_b, p, vec4(c, textureLoad(src_c, p, 0).z));
    }
}

@compute @workgroup_size(8, 8)
fn variance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if !in_view(p) {
        return;
    }
    let acc = textureLoad(src_a, p, 0);
    let mom = textureLoad(src_c, p, 0);
    let zn = textureLoad(src_d, p, 0);
    if zn.x <= 0.0 {
        filter_out(p, vec3(0.0), 0.0);
        return;
    }
    if mom.z >= SHORT_HISTORY {
        filter_out(p, acc.rgb, mom.y - mom.x * mom.x);
        return;
    }
    // Short history: a 7x7 bilateral estimate of the moments (depth and normal only).
    var c = vec3(0.0);
    var m = vec2(0.0);
    var wsum = 0.0;
    for (var dy = -3; dy <= 3; dy += 1) {
        for (var dx = -3; dx <= 3; dx += 1) {
            let q = p + vec2(dx, dy);
            if !in_view(q) {
                continue;
            }
            let zq = textureLoad(src_d, q, 0);
            if zq.x <= 0.0 {
                continue;
            }
            let dz = abs(zq.x - zn.x) / (params.svgf.w * 0.02 * zn.x * length(vec2(f32(dx), f32(dy))) + 1.0e-6);
            let w = exp(-dz) * pow(clamp(dot(zq.yzw, zn.yzw), 0.0, 1.0), params.svgf2.x);
            if !(w > 0.0) {
                continue;
            }
            c += w * clean(textureLoad(src_a, q, 0)).rgb;
            m += w * clean(textureLoad(src_c, q, 0)).xy;
            wsum += w;
        }
    }
    if !(wsum > 0.0) {
        filter_out(p, acc.rgb, 0.0);
        return;
    }
    // The colour stays this pixel's: the bilateral estimate is for the variance only (a 7x7
    // mean of a sparse photon map would spread a focus that the variance-guided à-trous keeps).
    c = acc.rgb;
    m /= wsum;
    // Falcor raises this by 4 / h; on sparse photon maps that spreads a fresh caustic over
    // the whole à-trous footprint after every reset, so the spatial estimate is kept as is.
    filter_out(p, c, m.y - m.x * m.x);
}

// The à-trous weight from pixel q (the source) to pixel p: B3 kernel h, then SVGF's depth,
// normal and luminance terms, with q's depth gradient and the smaller of the two pixels'
// luminance deviations (`aux` = (0, σ_l √Var prefiltered, dz/dx, dz/dy) of each): the rule
// is symmetric, w(q → p) = w(p → q) but for the depth gradient's pixel.
fn atrous_weight(o: vec2<i32>, zq: vec4<f32>, zp: vec4<f32>, cq: vec3<f32>, cp: vec3<f32>, aux_q: vec4<f32>, aux_p: vec4<f32>) -> f32 {
    let s = f32(pass_step.x);
    let off = vec2<f32>(o) * s;
    let b3 = array<f32, 3>(0.375, 0.25, 0.0625);
    let h = b3[abs(o.x)] * b3[abs(o.y)] / (b3[0] * b3[0]);
    let dz_scaled = params.svgf.w * max(abs(dot(aux_q.zw, off)), 1.0e-3 * zq.x);
    let l_sigma = min(aux_q.y, aux_p.y);
    return h * optics_svgf_weight(zp.x - zq.x, dz_scaled, dot(zp.yzw, zq.yzw), params.svgf2.x, lum(cp) - lum(cq), l_sigma);
}

// Pass 1 of an à-trous iteration: per pixel its luminance deviation (σ_l times the root of the
// 3x3 Gaussian of the variance) and depth gradient, into out_c.
@compute @workgroup_size(8, 8)
fn atrous_prep(@builtin(global_invocation_id) gid: vec3<u32>) {
    let q = vec2<i32>(gid.xy);
    if !in_view(q) {
        return;
    }
    let zq = textureLoad(src_d, q, 0);
    if zq.x <= 0.0 {
        textureStore(out_c, q, vec4(0.0));
        return;
    }
    var v = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let r = clamp(q + vec2(dx, dy), vec2(0), view_size() - 1);
            let k = select(0.5, 1.0, dx == 0) * select(0.5, 1.0, dy == 0) * 0.25;
            v += k * clean(textureLoad(src_a, r, 0)).w;
        }
    }
    let zx = textureLoad(src_d, clamp(q + vec2(1, 0), vec2(0), view_size() - 1), 0).x
        - textureLoad(src_d, clamp(q - vec2(1, 0), vec2(0), view_size() - 1), 0).x;
    let zy = textureLoad(src_d, clamp(q + vec2(0, 1), vec2(0), view_size() - 1), 0).x
        - textureLoad(src_d, clamp(q - vec2(0, 1), vec2(0), view_size() - 1), 0).x;
    textureStore(out_c, q, vec4(0.0, params.svgf2.y * sqrt(max(v, 0.0)), zx * 0.5, zy * 0.5));
}

// Pass 2: pixel p gathers its 5x5 neighbourhood with the symmetric weights (src_b: the prep
// pass's data), normalised by their sum. SVGF's own rule, p's deviation alone, is not
// symmetric: on a sparse photon map a dark, quiet pixel rejects its bright neighbour while
// the bright, noisy pixel averages in the dark ones, and the caustic loses energy (-25 % on
// `ring`); with the smaller deviation of the two, both reject each other and the total stays
// within a few percent. Variance: Σ w² var_q / (Σ w)².
@compute @workgroup_size(8, 8)
fn atrous(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    if !in_view(p) {
        return;
    }
    let zp = textureLoad(src_d, p, 0);
    if zp.x <= 0.0 {
        filter_out(p, vec3(0.0), 0.0);
        return;
    }
    let cp = clean(textureLoad(src_a, p, 0));
    // A short history's variance is the 7x7 spatial estimate, which on a sparse photon map
    // holds the caustic's own contrast: the later, wider iterations would spread a fresh
    // caustic over their footprint (a caster moving every frame resets the history every frame:
    // the sliding ball 466 lx with all five iterations, 148 with one; a still caustic is
    // unchanged). One iteration until the history holds SHORT_HISTORY frames.
    if pass_step.z > 1u && textureLoad(src_c, p, 0).z < SHORT_HISTORY {
        filter_out(p, cp.rgb, cp.w);
        return;
    }
    let s = i32(pass_step.x);
    let aux_p = textureLoad(src_b, p, 0);
    var sum = cp.rgb;
    var sum_v = cp.w;
    var wsum = 1.0;
    for (var dy = -2; dy <= 2; dy += 1) {
        for (var dx = -2; dx <= 2; dx += 1) {
            if dx == 0 && dy == 0 {
                continue;
            }
            let q = p + vec2(dx, dy) * s;
            if !in_view(q) {
                continue;
            }
            let zq = textureLoad(src_d, q, 0);
            if zq.x <= 0.0 {
                continue;
            }
            let aux_q = textureLoad(src_b, q, 0);
            let cq = clean(textureLoad(src_a, q, 0));
            // q sees p at the opposite offset.
            let w = atrous_weight(-vec2(dx, dy), zq, zp, cq.rgb, cp.rgb, aux_q, aux_p);
            sum += w * cq.rgb;
            sum_v += w * w * cq.w;
            wsum += w;
        }
    }
    filter_out(p, sum / wsum, sum_v / (wsum * wsum));
}
