// Caustics-volume gizmos: line segments (pulled from a storage buffer, two vertices each:
// world position, linear colour) drawn into the tone-mapped view target, optionally hidden
// behind the scene's depth prepass. Loaded by src/render/volume/gizmo.rs.

struct GizmoParams {
    clip_from_world: mat4x4<f32>,
    test: vec4<f32>, // x: 1 to depth-test, y: margin (fraction of the distance)
}
@group(0) @binding(0) var<uniform> params: GizmoParams;
@group(0) @binding(1) var<storage, read> vertices: array<vec4<f32>>;
@group(0) @binding(2) var view_depth: texture_depth_2d;

struct LOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) colour: vec4<f32>,
}

// Vertex v: vertices[2 v] = (position, 1), vertices[2 v + 1] = colour.
@vertex
fn vs_line(@builtin(vertex_index) vi: u32) -> LOut {
    var out: LOut;
    out.pos = params.clip_from_world * vec4(vertices[2u * vi].xyz, 1.0);
    out.colour = vertices[2u * vi + 1u];
    return out;
}

@fragment
fn fs_line(in: LOut) -> @location(0) vec4<f32> {
    if params.test.x > 0.5 {
        let size = vec2<f32>(textureDimensions(view_depth));
        let px = vec2<i32>(clamp(floor(in.pos.xy), vec2(0.0), size - 1.0));
        let scene = textureLoad(view_depth, px, 0);
        // Reverse-Z: larger is nearer; z ~ 1 / distance, so the margin is relative.
        if in.pos.z * (1.0 + params.test.y) < scene {
            discard;
        }
    }
    return in.colour;
}
