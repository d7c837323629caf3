// The resolve of fixed-point splats (fixed_splat.wgsl): each pixel's three 64-bit sums back to
// lux (`optics_fixed_point_value`), written over the target (alpha 0), one thread per pixel.
// Concatenated after optics.wgsl.

@group(0) @binding(0) var<storage, read> fixed_splats: array<u32>;
@group(0) @binding(1) var resolved: texture_storage_2d<rgba32float, write>;

const FIXED_SPLAT_SCALE: f32 = 256.0; // optics::FIXED_POINT_SCALE

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(resolved);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let base = 6u * (id.y * size.x + id.x);
    var e = vec3(0.0);
    for (var c = 0u; c < 3u; c += 1u) {
        e[c] = optics_fixed_point_value(fixed_splats[base + 2u * c], fixed_splats[base + 2u * c + 1u], FIXED_SPLAT_SCALE);
    }
    textureStore(resolved, vec2<i32>(id.xy), vec4(e, 0.0));
}
