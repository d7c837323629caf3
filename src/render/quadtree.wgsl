// The AAPS task-buffer quadtree walk: WGSL twin of `SumQuadtree::walk` (src/optics/aaps.rs),
// tested against it on lavapipe (tests/gpu.rs, wgsl_quadtree_walk_matches_rust).

// leaf_sample_uv (src/optics/aaps.rs): sample `sample` of texel `texel` of a `size x size`
// texture, the R2 Kronecker set rotated per texel, in 0.32 fixed point (bit-exact with Rust).
fn quadtree_leaf_sample_uv(texel: vec2<u32>, sample: u32, size: u32) -> vec2<f32> {
    return quadtree_leaf_sample_uv_rotated(texel, sample, size, vec2(0u));
}

// frame_rotation (src/optics/aaps.rs): the rotation of a frame's sample patterns.
fn quadtree_frame_rotation(frame: u32) -> vec2<u32> {
    let h = optics_pcg_hash(frame ^ 0x2c1b3c6du);
    return vec2(h, optics_pcg_hash(h ^ 0x297a2d39u));
}

// leaf_sample_uv_rotated (src/optics/aaps.rs): the same, shifted by the frame's `rotation`.
fn quadtree_leaf_sample_uv_rotated(texel: vec2<u32>, sample: u32, size: u32, rotation: vec2<u32>) -> vec2<f32> {
    let id = texel.y * size + texel.x;
    let h = optics_pcg_hash((id * 2654435761u) ^ 0x5bd1e995u);
    let shift = vec2(h, optics_pcg_hash(h ^ 0x68e31da4u)) + rotation;
    let step = vec2(3242174889u, 2447445414u);
    let x = shift + sample * step + (step >> vec2(1u));
    let cell = vec2<f32>(x >> vec2(8u)) * (1.0 / 16777216.0);
    return (vec2<f32>(texel) + cell) / f32(max(size, 1u));
}

// Read-write so the AAPS build passes can share the binding (group 0, binding 7).
@group(0) @binding(7) var<storage, read_write> qt_levels: array<u32>;

// SumQuadtree::walk (src/optics/aaps.rs) over a tree stored level by level from the leaves
// (`size x size`) to the root (1 x 1), concatenated in `qt_levels` (group 0, binding 7). Returns (texel.x, texel.y,
// sample in the leaf, samples in the leaf), or count 0 for a task past the total.
fn quadtree_walk(size: u32, task: u32) -> vec4<u32> {
    // Offsets of each level: level k has (size >> k)^2 entries.
    var offsets: array<u32, 16>;
    var n_levels = 0u;
    var off = 0u;
    var s = size;
    loop {
        offsets[n_levels] = off;
        off += s * s;
        n_levels += 1u;
        if s <= 1u || n_levels >= 16u {
            break;
        }
        s = s / 2u;
    }
    let total = qt_levels[offsets[n_levels - 1u]];
    if task >= total {
        return vec4(0u);
    }
    var rest = task;
    var pos = vec2(0u);
    var side = 1u;
    for (var l = i32(n_levels) - 2; l >= 0; l -= 1) {
        side *= 2u;
        var found = false;
        for (var k = 0u; k < 4u; k += 1u) {
            let c = pos * 2u + vec2(k & 1u, k >> 1u);
            let n = qt_levels[offsets[l] + c.y * side + c.x];
            if rest < n {
                pos = c;
                found = true;
                break;
            }
            rest -= n;
        }
        if !found {
            return vec4(0u);
        }
    }
    let count = qt_levels[pos.y * size + pos.x];
    return vec4(pos.x, pos.y, rest, count);
}
