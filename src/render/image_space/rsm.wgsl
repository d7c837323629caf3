// Reflective shadow maps of the image-space technique (seed 003 section 3, figure 4): the
// scene's triangles (pulled from the shared world-space triangle buffer) rasterised from a
// caustic light into three layers of an Rgba32Float array, each texel holding
// (view depth along the light's axis, normal x, normal y, ±(instance + 1)) with the sign
// carrying normal z, and w = 0 where the layer is empty:
// - `fs_opaque`: the nearest receiver (casters are transparent to the marches);
// - `fs_front`: the nearest caster surface facing the light (where photons start), a thin
//   wall's either face;
// - `fs_back`: the nearest caster surface facing away from the light (where a photon
//   refracted into a closed object leaves it or reflects back inside; the paper stops at one
//   interface).
// Concatenated after optics.wgsl by src/render/image_space/pipelines.rs.

struct RsmView {
    clip_from_world: mat4x4<f32>,
    view_from_world: mat4x4<f32>,
    eye: vec4<f32>,   // xyz eye, w: 1 perspective, 0 orthographic
    axis: vec4<f32>,  // xyz viewing direction
}

@group(0) @binding(0) var<uniform> rsm: RsmView;
@group(0) @binding(1) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> mats: array<vec4<f32>>;

struct ROut {
    @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) inst: u32,
}

// Triangle t, corner c: tris[6 t + 2 c] = (position, instance), tris[6 t + 2 c + 1] = normal.
@vertex
fn vs_rsm(@builtin(vertex_index) vi: u32) -> ROut {
    let t = vi / 3u;
    let c = vi % 3u;
    let p = tris[6u * t + 2u * c];
    let n = tris[6u * t + 2u * c + 1u];
    var out: ROut;
    out.pos = rsm.clip_from_world * vec4(p.xyz, 1.0);
    out.world = p.xyz;
    out.normal = n.xyz;
    out.inst = u32(max(p.w, 0.0));
    return out;
}

// 0 opaque, 1 caster front, 2 caster back; w = 0 when the fragment is not in that layer.
fn rsm_texel(in: ROut, layer: u32) -> vec4<f32> {
    let kind = bitcast<u32>(mats[3u * in.inst].x);
    let caster = kind != 0u;
    let depth = -(rsm.view_from_world * vec4(in.world, 1.0)).z;
    let l = length(in.normal);
    var n = vec3(0.0, 1.0, 0.0);
    if l > 0.0 && l <= 3.0e38 {
        n = in.normal / l;
    }
    var dir = rsm.axis.xyz;
    if rsm.eye.w > 0.5 {
        dir = normalize(in.world - rsm.eye.xyz);
    }
    var facing = dot(n, dir) < 0.0;
    // A mirror reflects on both sides: its front layer faces the light either way, and it has
    // no back layer (nothing enters it). A thin wall (glTF thickness 0) has air on both sides:
    // lit on either face it is a front (turned to face the light), and its faces turned away
    // stay in the back layer (a closed thin shell's far wall; the trace tells a single sheet,
    // its own back, from it).
    let thin = kind == 1u && mats[3u * in.inst].z > 0.5;
    if (kind == 2u || (thin && layer == 1u)) && !facing {
        n = -n;
        facing = true;
    }
    var keep = !caster;
    if layer == 1u {
        keep = caster && facing;
    } else if layer == 2u {
        keep = caster && !facing && kind != 2u;
    }
    let id = f32(in.inst) + 1.0;
    return select(vec4(0.0), vec4(depth, n.x, n.y, select(-id, id, n.z >= 0.0)), keep);
}

struct FOut {
    @location(0) texel: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

// Fragments outside the layer are written at depth 1 (behind everything) and lose the test.
fn layer_out(in: ROut, layer: u32) -> FOut {
    let t = rsm_texel(in, layer);
    return FOut(t, select(1.0, in.pos.z, t.w != 0.0));
}

@fragment
fn fs_opaque(in: ROut) -> FOut {
    return layer_out(in, 0u);
}

@fragment
fn fs_front(in: ROut) -> FOut {
    return layer_out(in, 1u);
}

@fragment
fn fs_back(in: ROut) -> FOut {
    return layer_out(in, 2u);
}
