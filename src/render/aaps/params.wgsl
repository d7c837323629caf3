// The per-view AAPS parameters (written by src/render/aaps/view.rs, `AapsParams::bytes`).
struct AapsParams {
    clip_from_world: mat4x4<f32>,
    prev_clip_from_world: mat4x4<f32>,
    camera: vec4<f32>,   // xyz eye position, w scene scale (m)
    viewport: vec4<f32>, // width, height (px), 1 if prev_clip_from_world is valid, splat scale
    atlas: vec4<u32>,    // atlas side, tile side, tiles per row, lights
    caps: vec4<u32>,     // splat capacity, photon capacity, max bounces, small-splat MSAA on
    density: vec4<f32>,  // target area (px), variance gain, w_t, min density
    limits: vec4<f32>,   // max density (0: none), photon budget, cull solid angle (sr, 0: off), max anisotropy
    splat: vec4<f32>,    // MSAA threshold (px), min radius, max radius (m), 1: drop large splats
    budget: vec4<f32>,   // budget floor share, point splat area (px), specular-event budget of the frame, frame index (bitcast u32: the sample rotation)
}

// A splat (64 bytes). Also the photon record of the variance pass (seed 004 section 3.1.5):
// world position, atlas texel and energy fraction live in it.
struct AapsSplat {
    center: vec4<f32>, // xyz world position, w bitcast atlas texel index
    a: vec4<f32>,      // major semi-axis (world), w bitcast 1 for a small (MSAA) splat, 2 for a point
    b: vec4<f32>,      // minor semi-axis (world), w energy fraction of its texel
    e: vec4<f32>,      // irradiance (lux) rgb, w projected area (px)
}

// Projection of a world point to pixel coordinates (x right, y down); w <= 0: behind the eye.
fn aaps_to_pixel(m: mat4x4<f32>, p: vec3<f32>, size: vec2<f32>) -> vec3<f32> {
    let c = m * vec4(p, 1.0);
    if !(c.w > 0.0) {
        return vec3(-1.0, -1.0, 0.0);
    }
    let ndc = c.xy / c.w;
    return vec3((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y, c.w);
}
