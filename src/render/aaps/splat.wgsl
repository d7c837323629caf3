// AAPS splat rasterisation (seed 004 sections 3.1.3, 3.3.3, 3.3.4, 5.1.3): instanced quads
// pulled from the splat buffer, ellipse discard, per-pixel depth test against the view depth
// with a 1 % margin, additive blending into the caustics buffer. `vs_small`/`fs_small` draw the
// small-splat list (stored from the end of the buffer) into a 4x multisampled target with
// per-sample shading.

@group(0) @binding(0) var<uniform> params: AapsParams;
@group(0) @binding(1) var<storage, read> splats: array<AapsSplat>;
@group(0) @binding(2) var view_depth: texture_depth_2d;
@group(0) @binding(3) var<uniform> world_from_clip: mat4x4<f32>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) q: vec2<f32>,
    @location(1) world: vec3<f32>,
    @location(2) @interpolate(flat) e: vec3<f32>,
}

struct VOutSample {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(perspective, sample) q: vec2<f32>,
    @location(1) @interpolate(perspective, sample) world: vec3<f32>,
    @location(2) @interpolate(flat) e: vec3<f32>,
}

fn quad_corner(vi: u32) -> vec2<f32> {
    let c = array<vec2<f32>, 6>(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    return c[vi % 6u];
}

fn splat_vertex(s: AapsSplat, vi: u32) -> VOut {
    let q = quad_corner(vi);
    let world = s.center.xyz + q.x * s.a.xyz + q.y * s.b.xyz;
    var out: VOut;
    out.pos = params.clip_from_world * vec4(world, 1.0);
    out.q = q;
    out.world = world;
    out.e = s.e.xyz;
    return out;
}

@vertex
fn vs_big(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOut {
    return splat_vertex(splats[ii], vi);
}

@vertex
fn vs_small(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOutSample {
    let v = splat_vertex(splats[params.caps.x - 1u - ii], vi);
    return VOutSample(v.pos, v.q, v.world, v.e);
}

// Section 3.3.4: visible when the splat point's distance from the eye is within 1 % of the
// scene's at this pixel.
fn depth_visible(frag: vec4<f32>, world: vec3<f32>) -> bool {
    let size = vec2<f32>(textureDimensions(view_depth));
    let px = vec2<i32>(clamp(floor(frag.xy), vec2(0.0), size - 1.0));
    let depth = textureLoad(view_depth, px, 0);
    let ndc = vec2((frag.x / size.x) * 2.0 - 1.0, 1.0 - (frag.y / size.y) * 2.0);
    let h = world_from_clip * vec4(ndc, depth, 1.0);
    if !(abs(h.w) > 0.0) {
        return false;
    }
    let scene = distance(h.xyz / h.w, params.camera.xyz);
    let here = distance(world, params.camera.xyz);
    return abs(here - scene) <= 0.01 * scene;
}

@fragment
fn fs_big(in: VOut) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world) {
        discard;
    }
    return vec4(in.e, 0.0);
}

@fragment
fn fs_small(in: VOutSample, @builtin(sample_index) sample: u32) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world) {
        discard;
    }
    return vec4(in.e, 0.0);
}
