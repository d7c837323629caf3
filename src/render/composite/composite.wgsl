// Adds caustic light to the lit HDR image: L = albedo / pi * E * exposure. A pixel whose
// caustics-buffer alpha is negative shows a mirror: its value is F * albedo' * E of the point
// the mirror reflects, and the composite adds it with albedo 1.
//
// E comes from the view's caustics buffer (lux, linear RGB). The diffuse albedo is decoded
// from Bevy's deferred G-buffer (bevy_pbr deferred_gbuffer_from_pbr_input): .r holds
// pow(base_color, 1/2.2) and perceptual roughness as unorm4x8, .b holds reflectance, metallic,
// occlusion and clearcoat, .a the octahedral normal and 8 flag bits (bit 0: unlit). The diffuse
// albedo of a metallic-workflow surface is base_color * (1 - metallic). Unlit pixels and
// pixels without geometry receive nothing. Blending is additive (One, One).

#import bevy_core_pipeline::fullscreen_vertex_shader::FullscreenVertexOutput

struct CompositeParams {
    exposure: f32,
    white_albedo: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var gbuffer: texture_2d<u32>;
@group(0) @binding(1) var caustics: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: CompositeParams;

const INV_PI: f32 = 0.31830988618379067;
const UNLIT_BIT: u32 = 1u;
const MAX_RADIANCE: f32 = 6.0e4; // Rgba16Float's largest finite value is 65504.

@fragment
fn fragment(in: FullscreenVertexOutput) -> @location(0) vec4<f32> {
    let p = vec2<i32>(floor(in.position.xy));
    let g = textureLoad(gbuffer, p, 0);
    let c = textureLoad(caustics, p, 0);
    let e = c.rgb;
    let flags = (g.a >> 24u) & 0xFFu;
    let empty = all(g == vec4<u32>(0u));
    var albedo = pow(unpack4x8unorm(g.r).rgb, vec3(2.2)) * (1.0 - unpack4x8unorm(g.b).g);
    // Alpha -1: a pixel showing a mirror, whose value already holds the reflected surface's
    // albedo and the mirror's Fresnel (the photon map's caustics seen in mirrors).
    if params.white_albedo != 0u || c.a < 0.0 {
        albedo = vec3(1.0);
    }
    if empty || (flags & UNLIT_BIT) != 0u {
        albedo = vec3(0.0);
    }
    var l = albedo * INV_PI * e * params.exposure;
    // Guard (stiff suite: every case's GPU readback): a NaN or infinity in the buffer must
    // not poison the frame.
    let finite = all(l == l) && all(abs(l) <= vec3(3.0e38));
    l = select(vec3(0.0), min(l, vec3(MAX_RADIANCE)), finite);
    return vec4(l, 0.0);
}
