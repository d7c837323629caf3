// What the photon map's two modules (the tracer's trace + gather, and the grid build) share:
// the stored photon, the header's words and the packing helpers. Twins in
// src/optics/photon_map.rs.

// A stored photon (32 bytes, optics::PHOTON_BYTES).
struct Photon {
    pos: vec3<f32>,
    dir: u32,       // incoming direction (travel), octahedral (optics::oct_encode)
    flux: vec3<f32>,
    normal: u32,    // receiver normal facing the photon's side, octahedral
}

// Header words 0..32: counters (read back; `PhotonMapCounters` in src/headless/counters.rs).
const C_EMITTED: u32 = 0u;        // photons leaving the lights with flux
const H_COUNT: u32 = 1u;          // photons stored by the trace (may exceed the capacity)
const C_DIRECT: u32 = 2u;         // first hit diffuse: direct light, not a caustic
const C_MISSED: u32 = 3u;         // hit nothing
const C_OVERFLOW: u32 = 4u;       // photons past the capacity (dropped)
const C_MAX_DEPTH: u32 = 5u;      // stopped at the bounce limit
const C_TIR: u32 = 6u;            // total internal reflections
const C_NAN: u32 = 7u;            // non-finite states caught
const C_CELLS: u32 = 8u;          // grid cells X·Y·Z
const C_SHIFT: u32 = 9u;          // cell doublings forced by the budget (0: cell = r)
const C_PIXELS: u32 = 10u;        // pixels gathered
const C_VISITED: u32 = 11u;       // photons distance-tested, summed over pixels
const C_USED: u32 = 12u;          // photons within r that passed the normal test, summed
const C_USED_MAX: u32 = 13u;      // the most used at one pixel
const C_NORMAL_REJECTS: u32 = 14u; // photons within r rejected by the normal test
const C_SHARED_TILES: u32 = 15u;  // 8x8 tiles gathered through workgroup memory
const C_FALLBACK_TILES: u32 = 16u; // tiles that asked for it but whose cells differ
const C_MIRROR_PIXELS: u32 = 17u; // pixels on mirrors gathered at their reflected point
const C_STEREO_REUSED: u32 = 18u; // right-eye pixels taken from the left eye
const C_STEREO_PIXELS: u32 = 19u; // right-eye pixels considered for reuse
const C_VISITED_MAX: u32 = 20u;   // the most visited at one pixel
const C_DIMS: u32 = 21u;          // 3 words: X, Y, Z
const C_FRAME: u32 = 24u;         // the progressive frame shown (1-based)
// Luminous flux, 64-bit fixed point (low word, then high word; PM_FLUX_SCALE units per lm):
const C_FLUX_CASTER: u32 = 25u;    // 2 words: striking the casters (photons' first hits)
const C_FLUX_DEPOSITED: u32 = 27u; // 2 words: reaching a diffuse surface after a specular event
const C_FLUX_MAX_DEPTH: u32 = 29u; // 2 words: in flight when a path reached the bounce limit or the event budget
const C_ROULETTE: u32 = 31u;       // paths ended by Russian roulette

// Units per lumen of the flux counters (`FLUX_SCALE` in src/render/photon_map/view.rs).
const PM_FLUX_SCALE: f32 = 65536.0;

// Header words 32..64: the grid's layout (written by grid_setup).
const H_STORED: u32 = 32u;  // min(count, capacity)
const H_MIN: u32 = 33u;     // 3 words: !sortable(min) (zero-initialised atomicMax finds the minimum)
const H_MAX: u32 = 36u;     // 3 words: sortable(max)
const H_DIMS: u32 = 40u;    // 3 words: X, Y, Z (0 when empty)
const H_CELLS: u32 = 43u;   // X·Y·Z
const H_SHIFT: u32 = 44u;   // cell doublings
const H_ORIGIN: u32 = 45u;  // 3 words, f32 bits
const H_CELL: u32 = 48u;    // f32 bits
const H_INV: u32 = 49u;     // f32 bits

// Header words 50..54: the event budget's counters (read back; EXTRA_COUNTERS_AT in view.rs).
const C_EVENTS: u32 = 50u;          // specular events traced (reflections, refractions)
const C_BUDGET_STOPPED: u32 = 51u;  // paths stopped by the frame's event budget (flux in C_FLUX_MAX_DEPTH)
const C_EVENTS_GRANTED: u32 = 52u;  // event budget handed out (chunks of 1, 2, 4, then 8 per thread)

// 1D index of a 2D dispatch of `width`-wide workgroups.
fn flat_index(gid: vec3<u32>, groups: vec3<u32>, width: u32) -> u32 {
    return gid.y * groups.x * width + gid.x;
}

// optics::oct_encode.
fn oct_encode(n_in: vec3<f32>) -> u32 {
    let l = length(n_in);
    var n = select(vec3(0.0, 0.0, 1.0), n_in / l, l > 0.0 && l < 3.0e38);
    var v = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        let s = select(vec2(-1.0), vec2(1.0), v >= vec2(0.0));
        v = (vec2(1.0) - abs(v.yx)) * s;
    }
    return pack2x16snorm(v);
}

// optics::oct_decode.
fn oct_decode(w: u32) -> vec3<f32> {
    let v = unpack2x16snorm(w);
    var n = vec3(v, 1.0 - abs(v.x) - abs(v.y));
    let t = max(-n.z, 0.0);
    n = vec3(n.xy + select(vec2(t), vec2(-t), n.xy >= vec2(0.0)), n.z);
    let l = length(n);
    return select(vec3(0.0, 0.0, 1.0), n / l, l > 0.0);
}

// optics::gather_kernel: Epanechnikov, normalised over the disc of radius sqrt(r2).
fn gather_kernel(d2: f32, r2: f32) -> f32 {
    if !(r2 > 0.0) || !(r2 <= 3.4e38) || !(d2 < r2) {
        return 0.0;
    }
    return 2.0 / (3.14159265358979 * r2) * (1.0 - d2 / r2);
}

// optics::MAX_GATHER_REACH: the most cells a gather reaches from its centre cell per axis.
const GATHER_MAX_REACH: u32 = 4u;

// optics::gather_radius: the progressive radius, floored at the pixel footprint's disc,
// capped at GATHER_MAX_REACH cells.
fn gather_radius(r_in: f32, footprint_area: f32, cell_in: f32) -> f32 {
    var fp = 0.0;
    if footprint_area > 0.0 && footprint_area <= 3.4e38 {
        fp = sqrt(footprint_area * 0.318309886183791);
    }
    let cell = select(0.0, max(cell_in, 0.0), abs(cell_in) <= 3.4e38);
    let r = select(0.0, max(r_in, 0.0), abs(r_in) <= 3.4e38);
    return min(max(r, fp), cell * f32(GATHER_MAX_REACH));
}

// optics::gather_reach: the cells a gather of radius r reaches, ceil(r / cell) in
// [1, GATHER_MAX_REACH] (NaN: 1).
fn gather_reach(r: f32, inv_cell: f32) -> u32 {
    let m = ceil(r * inv_cell);
    if m > 1.0 {
        return min(u32(min(m, 16.0)), GATHER_MAX_REACH);
    }
    return 1u;
}
