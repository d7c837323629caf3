// The inspector's live images (src/inspector/images.rs): a view's caustics buffer, or one
// field of the AAPS task buffer's atlas, colour-mapped on a log scale into an rgba16float
// image that egui samples. Runs only while the panel shows the image.

struct InspectParams {
    // x, y: the legend's range, low and high (lux, or the field's units), both > 0; z: the
    // first word of the tile set (projector tiles).
    range: vec4<f32>,
    // x: what (0 caustics buffer, 1 density, 2 projected area, 3 variance, 4 slab G-buffer
    // layer, 5 projector density tiles, 6 the photon map's per-pixel mean, 7 the photon map's
    // grid occupancy); y: atlas or tile-grid side; z, w: source texture width, height.
    what: vec4<u32>,
}

// The caustics buffer, or a volume's slab G-buffer layer.
@group(0) @binding(0) var caustics: texture_2d<f32>;
// The AAPS density atlas, a volume's density tiles (u32 counts), the photon map's per-pixel
// mean (vec4 per pixel) or its header (u32 words; `accum` is then startIdx).
@group(0) @binding(1) var<storage, read> density: array<f32>;
@group(0) @binding(2) var<storage, read> accum: array<u32>;
@group(0) @binding(3) var<uniform> params: InspectParams;
@group(0) @binding(4) var out: texture_storage_2d<rgba16float, write>;

// Where the per-texel accumulators start in `accum` (ACCUM_TEXELS in aaps/common.wgsl).
const ACCUM_TEXELS: u32 = 32u;

// ramp (src/inspector/model.rs): five stops, dark blue to red.
fn ramp(t_in: f32) -> vec3<f32> {
    var stops = array<vec3<f32>, 5>(
        vec3(0.05, 0.03, 0.35),
        vec3(0.0, 0.55, 0.9),
        vec3(0.1, 0.85, 0.2),
        vec3(0.95, 0.85, 0.05),
        vec3(0.8, 0.05, 0.02),
    );
    let t = select(0.0, clamp(t_in, 0.0, 1.0), t_in == t_in);
    let x = t * 4.0;
    let i = min(u32(floor(x)), 3u);
    return mix(stops[i], stops[i + 1u], x - f32(i));
}

// log_scale (src/inspector/model.rs).
fn log_scale(v: f32, lo: f32, hi: f32) -> f32 {
    if !(v > lo) || !(hi > lo) {
        return 0.0;
    }
    let t = log(v / lo) / log(hi / lo);
    return select(1.0, clamp(t, 0.0, 1.0), abs(t) <= 3.0e38);
}

@compute @workgroup_size(8, 8, 1)
fn colour_map(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(size);
    var v = 0.0;
    var zero = false;
    if params.what.x == 4u {
        // G-buffer texel: (depth, n.x, n.y, ±(instance + 1)), the sign that of n.z; 0: empty.
        let src = vec2<u32>(uv * vec2<f32>(params.what.zw));
        let g = textureLoad(caustics, min(src, params.what.zw - 1u), 0);
        let nz = sign(g.w) * sqrt(max(1.0 - g.y * g.y - g.z * g.z, 0.0));
        let c = select(vec3(g.y, g.z, nz) * 0.5 + 0.5, vec3(0.0), g.w == 0.0);
        textureStore(out, id.xy, vec4(c, 1.0));
        return;
    }
    if params.what.x == 0u {
        let src = vec2<u32>(uv * vec2<f32>(params.what.zw));
        let e = textureLoad(caustics, min(src, params.what.zw - 1u), 0).rgb;
        v = dot(e, vec3(0.2126, 0.7152, 0.0722));
        zero = !(v > 0.0);
    } else if params.what.x == 6u {
        let src = min(vec2<u32>(uv * vec2<f32>(params.what.zw)), params.what.zw - 1u);
        let i = 4u * (src.y * params.what.z + src.x);
        v = dot(vec3(density[i], density[i + 1u], density[i + 2u]), vec3(0.2126, 0.7152, 0.0722));
        zero = !(v > 0.0);
    } else if params.what.x == 7u {
        // H_DIMS (photon_map/photon.wgsl): X, Y, Z; the image spans x and z, summing over y.
        let dims = vec3(bitcast<u32>(density[40]), bitcast<u32>(density[41]), bitcast<u32>(density[42]));
        if all(dims > vec3(0u)) {
            let c = min(vec2<u32>(uv * vec2<f32>(dims.xz)), dims.xz - 1u);
            for (var y = 0u; y < min(dims.y, 4096u); y += 1u) {
                let cell = (c.y * dims.y + y) * dims.x + c.x;
                v += f32(accum[cell + 1u] - accum[cell]);
            }
        }
        zero = !(v > 0.0);
    } else if params.what.x == 5u {
        let a = max(params.what.y, 1u);
        let t = min(vec2<u32>(uv * f32(a)), vec2(a - 1u));
        v = f32(bitcast<u32>(density[u32(params.range.z) + t.y * a + t.x]));
        zero = !(v > 0.0);
    } else {
        let a = max(params.what.y, 1u);
        let t = min(vec2<u32>(uv * f32(a)), vec2(a - 1u));
        let i = t.y * a + t.x;
        let n = accum[ACCUM_TEXELS + 4u * i + 1u];
        if params.what.x == 1u {
            v = density[i];
        } else if params.what.x == 2u {
            v = select(0.0, bitcast<f32>(accum[ACCUM_TEXELS + 4u * i]) / f32(n), n > 0u);
        } else {
            v = bitcast<f32>(accum[ACCUM_TEXELS + 4u * i + 2u]);
        }
        zero = !(v > 0.0);
    }
    let c = select(ramp(log_scale(v, params.range.x, params.range.y)), vec3(0.0), zero);
    textureStore(out, id.xy, vec4(c, 1.0));
}
