// The depth- and normal-aware Gaussian of seed 000 section 3.4 ("a Gaussian kernel is applied
// to smoothen the result"), applied to the volumes' splats and written into the caustics
// buffer. Weights: Gaussian in pixels, times a relative depth term, times a normal term from
// Bevy's deferred G-buffer (octahedral normal in the low 24 bits of .a); pixels without
// geometry take no part. The weights are normalised, so a smooth field keeps its mean.
// Concatenated after src/render/gbuffer.wgsl by src/render/volume/mod.rs.

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var view_depth: texture_depth_2d;
@group(0) @binding(2) var gbuffer: texture_2d<u32>;
@group(0) @binding(3) var<uniform> blur: vec4<f32>; // radius (px), sigma (px), 0, 0

struct FOut {
    @builtin(position) pos: vec4<f32>,
}

@vertex
fn vs_full(@builtin(vertex_index) vi: u32) -> FOut {
    let uv = vec2(f32((vi << 1u) & 2u), f32(vi & 2u));
    return FOut(vec4(uv * 2.0 - 1.0, 0.0, 1.0));
}

fn gnormal(p: vec2<i32>) -> vec4<f32> {
    return gbuffer_decode_normal(textureLoad(gbuffer, p, 0));
}

@fragment
fn fs_blur(in: FOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(floor(in.pos.xy));
    let e0 = textureLoad(src, p, 0);
    let r = i32(blur.x);
    let n0 = gnormal(p);
    if r <= 0 || n0.w == 0.0 {
        return select(vec4(0.0), e0, all(e0 == e0));
    }
    let size = vec2<i32>(textureDimensions(src));
    let d0 = textureLoad(view_depth, p, 0);
    let s2 = 2.0 * blur.y * blur.y;
    var sum = vec3(0.0);
    var wsum = 0.0;
    for (var dy = -r; dy <= r; dy += 1) {
        for (var dx = -r; dx <= r; dx += 1) {
            let q = p + vec2(dx, dy);
            if any(q < vec2(0)) || any(q >= size) {
                continue;
            }
            let nq = gnormal(q);
            if nq.w == 0.0 {
                continue;
            }
            let dq = textureLoad(view_depth, q, 0);
            // Reverse-Z depth is proportional to 1 / distance: compare relatively.
            let rel = abs(dq - d0) / max(max(dq, d0), 1e-30);
            let w = exp(-f32(dx * dx + dy * dy) / s2) * exp(-(rel * rel) / 0.0004) * pow(max(dot(nq.xyz, n0.xyz), 0.0), 16.0);
            let e = textureLoad(src, q, 0).rgb;
            if w > 0.0 && all(e == e) && all(abs(e) <= vec3(3.0e38)) {
                sum += w * e;
                wsum += w;
            }
        }
    }
    if !(wsum > 0.0) {
        return vec4(0.0);
    }
    return vec4(sum / wsum, 0.0);
}
