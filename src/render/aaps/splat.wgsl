// AAPS splat rasterisation (seed 004 sections 3.1.3, 3.3.3, 3.3.4, 5.1.3): instanced quads
// pulled from the splat buffer, ellipse discard, per-pixel depth test against the view depth
// with a 1 % margin, additive blending into the caustics buffer. `vs_small`/`fs_small` draw the
// small-splat list (stored from the end of the buffer) into a 4x multisampled target with
// per-sample shading. Point splats (flag 2 in `a.w`, under `AapsSettings::point_splat_area`)
// are drawn as a quad inside the one pixel that holds their centre, with their whole flux.

@group(0) @binding(0) var<uniform> params: AapsParams;
@group(0) @binding(1) var<storage, read> splats: array<AapsSplat>;
@group(0) @binding(2) var view_depth: texture_depth_2d;
@group(0) @binding(3) var<uniform> world_from_clip: mat4x4<f32>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) q: vec2<f32>,
    @location(1) world: vec3<f32>,
    @location(2) @interpolate(flat) e: vec3<f32>,
    // Point splats: the splat plane's normal (w = 1); ellipses: w = 0.
    @location(3) @interpolate(flat) plane: vec4<f32>,
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
    var out: VOut;
    out.e = s.e.xyz;
    out.plane = vec4(0.0);
    if bitcast<u32>(s.a.w) == 2u {
        // A point splat: a quad of 0.8 px around the centre of the pixel holding the splat's
        // centre, so it covers exactly that pixel; irradiance E area_px puts its whole flux there.
        let size = params.viewport.xy;
        let p = aaps_to_pixel(params.clip_from_world, s.center.xyz, size);
        let px = floor(p.xy) + 0.5 + 0.4 * q;
        let ndc = vec2(px.x / size.x * 2.0 - 1.0, 1.0 - px.y / size.y * 2.0);
        // Behind the eye: a degenerate quad outside the clip volume.
        out.pos = select(vec4(2.0, 2.0, 2.0, 1.0), vec4(ndc, 0.5, 1.0), p.z > 0.0);
        out.q = vec2(0.0);
        out.world = s.center.xyz;
        out.e = s.e.xyz * max(s.e.w, 0.0);
        out.plane = vec4(normalize(cross(s.a.xyz, s.b.xyz)), 1.0);
        return out;
    }
    let world = s.center.xyz + q.x * s.a.xyz + q.y * s.b.xyz;
    out.pos = params.clip_from_world * vec4(world, 1.0);
    out.q = q;
    out.world = world;
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

// The scene point seen through pixel `frag` (world, w = 1); w = 0 when it cannot be found.
fn scene_point(frag: vec4<f32>) -> vec4<f32> {
    let size = vec2<f32>(textureDimensions(view_depth));
    let px = vec2<i32>(clamp(floor(frag.xy), vec2(0.0), size - 1.0));
    let depth = textureLoad(view_depth, px, 0);
    let ndc = vec2((frag.x / size.x) * 2.0 - 1.0, 1.0 - (frag.y / size.y) * 2.0);
    let h = world_from_clip * vec4(ndc, depth, 1.0);
    if !(abs(h.w) > 0.0) {
        return vec4(0.0);
    }
    return vec4(h.xyz / h.w, 1.0);
}

// Section 3.3.4: visible when the splat point's distance from the eye is within 1 % of the
// scene's at this pixel. A point splat's centre is not on this pixel's ray, so for it the
// scene point's distance from the splat's plane is tested instead (within 1 % of the view
// distance; along the ray it would reject points on a floor seen at a grazing angle).
fn depth_visible(frag: vec4<f32>, world: vec3<f32>, plane: vec4<f32>) -> bool {
    let p = scene_point(frag);
    if p.w == 0.0 {
        return false;
    }
    let scene = distance(p.xyz, params.camera.xyz);
    if plane.w > 0.0 {
        return abs(dot(p.xyz - world, plane.xyz)) <= 0.01 * scene;
    }
    let here = distance(world, params.camera.xyz);
    return abs(here - scene) <= 0.01 * scene;
}

@fragment
fn fs_big(in: VOut) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world, in.plane) {
        discard;
    }
    return vec4(in.e, 0.0);
}

// The plain splat without float blending: the same value added in fixed point (group 1,
// src/render/fixed_splat/), nothing written to the target.
@fragment
fn fs_big_fixed(in: VOut) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world, in.plane) {
        discard;
    }
    let width = textureDimensions(view_depth).x;
    fixed_splat_add(vec2<u32>(in.pos.xy), width, in.e);
    return vec4(0.0);
}

@fragment
fn fs_small(in: VOutSample, @builtin(sample_index) sample: u32) -> @location(0) vec4<f32> {
    if dot(in.q, in.q) > 1.0 || !depth_visible(in.pos, in.world, vec4(0.0)) {
        discard;
    }
    return vec4(in.e, 0.0);
}
