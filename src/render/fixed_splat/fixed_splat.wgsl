// Additive splats without float blending (`render::fixed_splat`): a splat's fragment adds its
// irradiance to a per-pixel 64-bit fixed-point sum with u32 atomics instead of blending into an
// `Rgba32Float` target (which needs `FLOAT32_BLENDABLE`). Group 1, fragment stage. The words
// are image space's photon-map words (`optics_fixed_point_word`, twin of
// `optics::fixed_point_word`) rounded to nearest; integer sums are exact and
// independent of the order fragments run in. resolve.wgsl turns them back into floats.
// Concatenated after optics.wgsl.

@group(1) @binding(0) var<storage, read_write> fixed_splats: array<atomic<u32>>;

const FIXED_SPLAT_SCALE: f32 = 256.0; // optics::FIXED_POINT_SCALE

// Add `e` (lux, rgb) to the pixel `px` of a target `width` pixels wide (six words per pixel:
// the low and the high word of each channel).
fn fixed_splat_add(px: vec2<u32>, width: u32, e: vec3<f32>) {
    let base = 6u * (px.y * width + px.x);
    for (var c = 0u; c < 3u; c += 1u) {
        let w = optics_fixed_point_word(e[c], FIXED_SPLAT_SCALE, 0.5).x;
        if w == 0u {
            continue;
        }
        let old = atomicAdd(&fixed_splats[base + 2u * c], w);
        if old + w < old {
            atomicAdd(&fixed_splats[base + 2u * c + 1u], 1u);
        }
    }
}
