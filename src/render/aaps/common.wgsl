// Bindings and counters shared by the AAPS compute passes (group 0; the shared tracer,
// src/render/trace/, holds 0 to 6 and 8, quadtree.wgsl binding 7). Concatenated after the
// tracer's WGSL, quadtree.wgsl and params.wgsl by src/render/aaps/pipelines.rs.

@group(0) @binding(9) var<uniform> params: AapsParams;
@group(0) @binding(10) var<storage, read_write> splats: array<AapsSplat>;
@group(0) @binding(11) var<storage, read_write> accum: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> density: array<f32>;
@group(0) @binding(13) var<storage, read_write> density_next: array<f32>;
@group(0) @binding(14) var caustics_now: texture_2d<f32>;
@group(0) @binding(15) var caustics_prev: texture_2d<f32>;

// Counters (u32 words of `accum`; `AapsStats` in src/render/aaps/mod.rs reads the same).
const C_TASKS: u32 = 0u;          // photons the quadtree asks for
const C_EMITTED: u32 = 1u;        // photons traced
const C_RESERVED: u32 = 2u;       // splat slots asked for
const C_BIG: u32 = 3u;            // splats in the plain list
const C_SMALL: u32 = 4u;          // splats in the MSAA list
const C_OVERFLOW: u32 = 5u;       // splats that did not fit
const C_CULL_FRUSTUM: u32 = 6u;   // splats outside the frustum or facing away
const C_CULL_SIZE: u32 = 7u;      // splats above the solid-angle threshold
const C_DROPPED: u32 = 8u;        // photons whose first hit is not a caster
const C_CLAMPED: u32 = 9u;        // splats whose axes were clamped
const C_NAN: u32 = 10u;           // non-finite values caught
const C_MAX_DEPTH: u32 = 11u;     // paths stopped at max bounces
const C_DENSITY_SUM: u32 = 12u;   // f32 bits: sum of the new densities
const C_TIR: u32 = 13u;           // total internal reflections
const C_PHOTON_OVERFLOW: u32 = 14u; // photons past the photon capacity
const C_SPLIT: u32 = 15u;         // photons split at a dielectric
const C_FLUX_CASTER: u32 = 16u;   // 4 words, f32 bits: luminous flux striking casters (first hit)
const C_FLUX_DEPOSITED: u32 = 20u; // 4 words, f32 bits: flux reaching a diffuse surface (before culling)
const C_FLUX_MAX_DEPTH: u32 = 24u; // 4 words, f32 bits: flux in flight at max bounces or when the event budget ran out
const C_CONTRIBUTING: u32 = 28u;  // texels with an accepted splat (density update)
const C_EVENTS: u32 = 29u;        // specular events traced (reflections, refractions)
const C_BUDGET_STOPPED: u32 = 30u; // paths stopped by the frame's event budget (flux in C_FLUX_MAX_DEPTH)
const C_EVENTS_GRANTED: u32 = 31u; // event budget handed out (chunks of 1, 2, 4, then 8 per thread)
const ACCUM_TEXELS: u32 = 32u;    // per texel: area sum (f32 bits), accepted count, variance (f32 bits), 0

fn accum_add_f32(i: u32, v: f32) {
    if !(abs(v) <= 3.0e38) {
        return;
    }
    var old = atomicLoad(&accum[i]);
    // A failed exchange (but for a spurious failure of the weak one) means another thread's
    // succeeded, so k contenders need about k tries. The hot words see one add per workgroup
    // (trace, density_update): a few thousand resident workgroups on the widest GPUs.
    for (var k = 0u; k < 4096u; k += 1u) {
        let r = atomicCompareExchangeWeak(&accum[i], old, bitcast<u32>(bitcast<f32>(old) + v));
        if r.exchanged {
            return;
        }
        old = r.old_value;
    }
}

fn accum_f32(i: u32) -> f32 {
    return bitcast<f32>(atomicLoad(&accum[i]));
}

// The light index of an atlas texel (or a value >= lights for an unused tile).
fn atlas_tile(texel: vec2<u32>) -> u32 {
    let tile = params.atlas.y;
    return (texel.y / tile) * params.atlas.z + texel.x / tile;
}
