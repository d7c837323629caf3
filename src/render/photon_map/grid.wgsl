// The hash-grid build of seed 001 section 3.1 on the GPU: bounds (integer atomics over
// order-preserving float bits), the layout (one thread), the count per cell, a two-level
// prefix sum (workgroup scans of 1024 cells + one scan of the block sums; no single-pass
// look-back, which needs forward progress that WebGPU does not promise), and the scatter.
// The WGSL twin of `optics::build_grid` (src/optics/photon_map.rs), tested for exact equality.
// Its own module (after photon.wgsl) and bindings (group 0); the entry points run in the order of
// `GRID_ENTRIES` in src/render/photon_map/pipelines.rs.
//
// After `scatter`, `cells[c]` is the first sorted photon of cell c and `cells[X·Y·Z]` their
// count: the scan leaves each cell's end, and the scatter's atomic decrements bring it down to
// the start.

struct GridParams {
    r: f32,        // the gather radius of the grid (the first frame's), metres
    inv_r: f32,    // 1 / r as the CPU computed it
    budget: u32,   // cells at most
    capacity: u32, // photons the buffers hold
}

@group(0) @binding(0) var<uniform> grid_params: GridParams;
@group(0) @binding(1) var<storage, read> photons: array<Photon>;
@group(0) @binding(2) var<storage, read_write> sorted: array<Photon>;
@group(0) @binding(3) var<storage, read_write> header: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> cells: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> blocks: array<u32>;
@group(0) @binding(6) var<storage, read_write> photon_cell: array<u32>;

const SCAN_THREADS: u32 = 256u;
const SCAN_ITEMS: u32 = 4u;      // cells per thread of a block: 1024 per block
const TOP_ITEMS: u32 = 8u;       // block sums per thread of the top scan: 2048 blocks

var<workgroup> scan_shared: array<u32, 256>;

fn sortable_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_sortable_bits(u: u32) -> f32 {
    return select(bitcast<f32>(~u), bitcast<f32>(u & 0x7fffffffu), (u & 0x80000000u) != 0u);
}

// Hillis-Steele over the workgroup's 256 thread totals: the sum of the totals of the threads
// before `lid`. Every invocation must call it (barriers).
fn threads_exclusive_scan(lid: u32, total: u32) -> u32 {
    scan_shared[lid] = total;
    workgroupBarrier();
    for (var off = 1u; off < SCAN_THREADS; off *= 2u) {
        var add = 0u;
        if lid >= off {
            add = scan_shared[lid - off];
        }
        workgroupBarrier();
        scan_shared[lid] += add;
        workgroupBarrier();
    }
    return scan_shared[lid] - total;
}

fn grid_stored() -> u32 {
    return atomicLoad(&header[H_STORED]);
}

fn grid_dims() -> vec3<u32> {
    return vec3(atomicLoad(&header[H_DIMS]), atomicLoad(&header[H_DIMS + 1u]), atomicLoad(&header[H_DIMS + 2u]));
}

// optics::GridLayout::cell_of + linear.
fn grid_key(p: vec3<f32>, dims: vec3<u32>) -> u32 {
    let origin = vec3(bitcast<f32>(atomicLoad(&header[H_ORIGIN])), bitcast<f32>(atomicLoad(&header[H_ORIGIN + 1u])), bitcast<f32>(atomicLoad(&header[H_ORIGIN + 2u])));
    let inv = bitcast<f32>(atomicLoad(&header[H_INV]));
    let hi = vec3<f32>(max(dims, vec3(1u)) - vec3(1u));
    let f = clamp(floor((p - origin) * inv), vec3(0.0), hi);
    let c = vec3<u32>(f);
    return (c.z * dims.y + c.y) * dims.x + c.x;
}

// The workgroup's bounds first (workgroup atomics), then one global atomic per axis and
// workgroup instead of one per photon.
var<workgroup> wg_bounds: array<atomic<u32>, 6>;

@compute @workgroup_size(64)
fn grid_bounds(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    if lid < 6u {
        atomicStore(&wg_bounds[lid], 0u);
    }
    workgroupBarrier();
    let i = flat_index(gid, groups, 64u);
    let n = min(atomicLoad(&header[H_COUNT]), grid_params.capacity);
    if i < n {
        let p = photons[i].pos;
        for (var a = 0u; a < 3u; a += 1u) {
            let s = sortable_bits(p[a]);
            atomicMax(&wg_bounds[a], ~s);
            atomicMax(&wg_bounds[3u + a], s);
        }
    }
    workgroupBarrier();
    if lid < 6u {
        let v = atomicLoad(&wg_bounds[lid]);
        if v != 0u {
            atomicMax(&header[select(H_MAX + lid - 3u, H_MIN + lid, lid < 3u)], v);
        }
    }
}

// optics::GridLayout::fit, one thread.
@compute @workgroup_size(1)
fn grid_setup() {
    let n = min(atomicLoad(&header[H_COUNT]), grid_params.capacity);
    atomicStore(&header[H_STORED], n);
    atomicStore(&header[H_CELLS], 0u);
    for (var a = 0u; a < 3u; a += 1u) {
        atomicStore(&header[H_DIMS + a], 0u);
    }
    atomicStore(&header[H_CELL], bitcast<u32>(grid_params.r));
    atomicStore(&header[H_INV], bitcast<u32>(grid_params.inv_r));
    if n == 0u {
        return;
    }
    var lo: vec3<f32>;
    var hi: vec3<f32>;
    for (var a = 0u; a < 3u; a += 1u) {
        lo[a] = from_sortable_bits(~atomicLoad(&header[H_MIN + a]));
        hi[a] = from_sortable_bits(atomicLoad(&header[H_MAX + a]));
    }
    if !all(lo <= hi) {
        return;
    }
    for (var shift = 0u; shift < 127u; shift += 1u) {
        let s = bitcast<f32>((127u + shift) << 23u);
        let si = bitcast<f32>((127u - shift) << 23u);
        let cell = grid_params.r * s;
        let inv = grid_params.inv_r * si;
        let origin = lo - vec3(cell);
        let f = floor((hi - origin) * inv) + vec3(2.0);
        let d = max(f, vec3(3.0));
        if all(abs(f) <= vec3(3.0e38)) && all(abs(origin) <= vec3(3.0e38)) && d.x * d.y * d.z <= f32(grid_params.budget) {
            let dims = vec3<u32>(d);
            for (var a = 0u; a < 3u; a += 1u) {
                atomicStore(&header[H_DIMS + a], dims[a]);
                atomicStore(&header[H_ORIGIN + a], bitcast<u32>(origin[a]));
            }
            atomicStore(&header[H_CELLS], dims.x * dims.y * dims.z);
            atomicStore(&header[C_CELLS], dims.x * dims.y * dims.z);
            for (var a = 0u; a < 3u; a += 1u) {
                atomicStore(&header[C_DIMS + a], dims[a]);
            }
            atomicStore(&header[H_SHIFT], shift);
            atomicStore(&header[C_SHIFT], shift);
            atomicStore(&header[H_CELL], bitcast<u32>(cell));
            atomicStore(&header[H_INV], bitcast<u32>(inv));
            return;
        }
    }
}

@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups, 64u);
    if i >= grid_stored() || atomicLoad(&header[H_CELLS]) == 0u {
        return;
    }
    let key = grid_key(photons[i].pos, grid_dims());
    photon_cell[i] = key;
    atomicAdd(&cells[key], 1u);
}

// Inclusive scan of 1024 cells per workgroup; the block's total goes to `blocks`.
@compute @workgroup_size(256)
fn grid_scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(num_workgroups) groups: vec3<u32>) {
    let block = wid.y * groups.x + wid.x;
    let base = block * SCAN_THREADS * SCAN_ITEMS + lid * SCAN_ITEMS;
    let len = arrayLength(&cells);
    var v: array<u32, 4>;
    var sum = 0u;
    for (var k = 0u; k < SCAN_ITEMS; k += 1u) {
        let i = base + k;
        var x = 0u;
        if i < len {
            x = atomicLoad(&cells[i]);
        }
        sum += x;
        v[k] = sum;
    }
    let before = threads_exclusive_scan(lid, sum);
    for (var k = 0u; k < SCAN_ITEMS; k += 1u) {
        let i = base + k;
        if i < len {
            atomicStore(&cells[i], v[k] + before);
        }
    }
    if lid == SCAN_THREADS - 1u {
        blocks[block] = before + sum;
    }
}

// Exclusive scan of the block totals, one workgroup (at most 2048 blocks).
@compute @workgroup_size(256)
fn grid_scan_top(@builtin(local_invocation_index) lid: u32) {
    let len = arrayLength(&blocks);
    let base = lid * TOP_ITEMS;
    var v: array<u32, 8>;
    var sum = 0u;
    for (var k = 0u; k < TOP_ITEMS; k += 1u) {
        let i = base + k;
        var x = 0u;
        if i < len {
            x = blocks[i];
        }
        v[k] = sum;
        sum += x;
    }
    let before = threads_exclusive_scan(lid, sum);
    for (var k = 0u; k < TOP_ITEMS; k += 1u) {
        let i = base + k;
        if i < len {
            blocks[i] = v[k] + before;
        }
    }
}

// Add each block's offset: `cells` becomes the inclusive prefix sum (each cell's end).
@compute @workgroup_size(256)
fn grid_scan_add(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(num_workgroups) groups: vec3<u32>) {
    let block = wid.y * groups.x + wid.x;
    let add = blocks[block];
    let base = block * SCAN_THREADS * SCAN_ITEMS + lid * SCAN_ITEMS;
    let len = arrayLength(&cells);
    for (var k = 0u; k < SCAN_ITEMS; k += 1u) {
        let i = base + k;
        if i < len {
            atomicAdd(&cells[i], add);
        }
    }
}

// Each photon takes the last free slot of its cell; afterwards `cells[c]` is the cell's start.
@compute @workgroup_size(64)
fn grid_scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups, 64u);
    if i >= grid_stored() || atomicLoad(&header[H_CELLS]) == 0u {
        return;
    }
    let slot = atomicSub(&cells[photon_cell[i]], 1u) - 1u;
    sorted[slot] = photons[i];
}
