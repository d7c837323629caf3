// Closest-hit traversal of the two-level BVH flattened by `src/scene/gpu.rs` (GpuBvh): the
// WGSL twin of `Tlas::closest_hit` (src/scene/bvh.rs), tested against it on lavapipe.
//
// Conventions: rays are world space with a unit direction; t is the world distance. Instances
// transform the ray into object space without renormalising, so t stays the world distance.
// Triangles use the same Möller-Trumbore test and the same relative determinant epsilon as the
// CPU (`intersect_triangle`). The bindings below are group 0, bindings 0 to 4.

@group(0) @binding(0) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bvh_instances: array<BvhInstance>;
@group(0) @binding(3) var<storage, read> tlas_nodes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> tlas_prims: array<u32>;

struct BvhInstance {
    row0: vec4<f32>,
    row1: vec4<f32>,
    row2: vec4<f32>,
    root: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

struct BvhHit {
    t: f32,
    instance: u32,   // 0xffffffff: miss
    triangle: u32,   // index in the mesh
    uv: vec2<f32>,
    slot: u32,       // index in bvh_triangles (BVH order), for per-triangle data
}

const BVH_INVALID: u32 = 0xffffffffu;
const BVH_STACK: u32 = 64u;
// Distance reported for a miss (finite, so no infinity ever reaches a buffer).
const BVH_FAR: f32 = 3.0e38;

fn bvh_inv_dir(d: vec3<f32>) -> vec3<f32> {
    // Zero components give a huge finite inverse of the right sign (like obvhs' safe_inverse).
    let big = 1.0e30;
    return vec3(
        select(1.0 / d.x, select(big, -big, d.x < 0.0), abs(d.x) < 1.0e-30),
        select(1.0 / d.y, select(big, -big, d.y < 0.0), abs(d.y) < 1.0e-30),
        select(1.0 / d.z, select(big, -big, d.z < 0.0), abs(d.z) < 1.0e-30),
    );
}

// Entry distance of a ray into a box, or +inf if it misses within [tmin, tmax].
fn bvh_box(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv: vec3<f32>, tmin: f32, tmax: f32) -> f32 {
    let t0 = (lo - o) * inv;
    let t1 = (hi - o) * inv;
    let tn = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), max(min(t0.z, t1.z), tmin));
    let tf = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), min(max(t0.z, t1.z), tmax));
    return select(BVH_FAR, tn, tn <= tf);
}

// Möller-Trumbore; returns (t, u, v) with t = +inf on a miss.
fn bvh_triangle(o: vec3<f32>, d: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, tmin: f32, tmax: f32) -> vec3<f32> {
    let miss = vec3(BVH_FAR, 0.0, 0.0);
    let p = cross(d, e2);
    let det = dot(e1, p);
    let scale = length(e1) * length(p);
    if !(abs(det) > 1.0e-12 * scale) || scale == 0.0 {
        return miss;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return miss;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return miss;
    }
    let t = dot(e2, q) * inv;
    if t > tmin && t < tmax {
        return vec3(t, u, v);
    }
    return miss;
}

fn bvh_node_lo(i: u32) -> vec4<f32> { return bvh_nodes[2u * i]; }
fn bvh_node_hi(i: u32) -> vec4<f32> { return bvh_nodes[2u * i + 1u]; }

// Shared by both levels: test a node `(lo, hi)` and return (prim_count, first_index), or
// (BVH_INVALID, 0) when the ray misses its box within [tmin, tmax].
fn bvh_visit(lo: vec4<f32>, hi: vec4<f32>, o: vec3<f32>, inv: vec3<f32>, tmin: f32, tmax: f32) -> vec2<u32> {
    if bvh_box(lo.xyz, hi.xyz, o, inv, tmin, tmax) > 2.0e38 {
        return vec2(BVH_INVALID, 0u);
    }
    return vec2(bitcast<u32>(lo.w), bitcast<u32>(hi.w));
}

// Push the two children of an inner node (children are at first and first + 1).
fn bvh_push_children(stack: ptr<function, array<u32, BVH_STACK>>, sp: ptr<function, u32>, first: u32) {
    if *sp + 2u <= BVH_STACK {
        (*stack)[*sp] = first;
        (*stack)[*sp + 1u] = first + 1u;
        *sp += 2u;
    }
}

// Closest hit inside one instance's BLAS; updates `best` when closer.
fn bvh_blas(inst_index: u32, o_world: vec3<f32>, d_world: vec3<f32>, tmin: f32, best: ptr<function, BvhHit>) {
    let inst = bvh_instances[inst_index];
    if inst.root == BVH_INVALID {
        return;
    }
    let p = vec4(o_world, 1.0);
    let v = vec4(d_world, 0.0);
    let o = vec3(dot(inst.row0, p), dot(inst.row1, p), dot(inst.row2, p));
    let d = vec3(dot(inst.row0, v), dot(inst.row1, v), dot(inst.row2, v));
    let inv = bvh_inv_dir(d);
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    stack[0] = inst.root;
    sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let n = stack[sp];
        let v = bvh_visit(bvh_node_lo(n), bvh_node_hi(n), o, inv, tmin, (*best).t);
        let count = v.x;
        let first = v.y;
        if count == BVH_INVALID {
            continue;
        }
        if count == 0u {
            bvh_push_children(&stack, &sp, first);
            continue;
        }
        for (var k = 0u; k < count; k += 1u) {
            let tri = first + k;
            let a = bvh_triangles[3u * tri];
            let e1 = bvh_triangles[3u * tri + 1u].xyz;
            let e2 = bvh_triangles[3u * tri + 2u].xyz;
            let h = bvh_triangle(o, d, a.xyz, e1, e2, tmin, (*best).t);
            if h.x < (*best).t {
                (*best).t = h.x;
                (*best).instance = inst_index;
                (*best).triangle = bitcast<u32>(a.w);
                (*best).uv = h.yz;
                (*best).slot = tri;
            }
        }
    }
}

// Closest hit along the world ray (o, d) in (tmin, tmax).
fn bvh_closest_hit(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> BvhHit {
    var best = BvhHit(tmax, BVH_INVALID, 0u, vec2(0.0), 0u);
    if arrayLength(&tlas_nodes) < 2u {
        return best;
    }
    let inv = bvh_inv_dir(d);
    var stack: array<u32, BVH_STACK>;
    var sp = 1u;
    stack[0] = 0u;
    while sp > 0u {
        sp -= 1u;
        let n = stack[sp];
        let v = bvh_visit(tlas_nodes[2u * n], tlas_nodes[2u * n + 1u], o, inv, tmin, best.t);
        let count = v.x;
        let first = v.y;
        if count == BVH_INVALID {
            continue;
        }
        if count == 0u {
            bvh_push_children(&stack, &sp, first);
            continue;
        }
        for (var k = 0u; k < count; k += 1u) {
            bvh_blas(tlas_prims[first + k], o, d, tmin, &best);
        }
    }
    if best.instance == BVH_INVALID {
        best.t = BVH_FAR;
    }
    return best;
}
