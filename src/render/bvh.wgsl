// Closest-hit traversal of the two-level BVH flattened by `src/scene/gpu.rs` (GpuBvh): the
// WGSL twin of `Tlas::closest_hit` (src/scene/bvh.rs), tested against it on lavapipe.
//
// Conventions: rays are world space with a unit direction; t is the world distance. Instances
// transform the ray into object space without renormalising, so t stays the world distance.
// Triangles use the same Möller-Trumbore test and the same relative determinant epsilon as the
// CPU (`intersect_triangle`). The bindings below are group 0, bindings 0 to 2: the scene
// packed into three buffers (`GpuBvh::packed`, src/scene/gpu.rs), so a tracer fits WebGPU's
// default 8 storage buffers per stage.
//
// bvh_nodes: header vec4<u32>(TLAS nodes, first prim vec4, first BLAS node vec4, 0), the TLAS
//   nodes (two vec4 each), the TLAS prims (four u32 per vec4), the BLAS nodes.
// bvh_triangles: six vec4 per triangle (BVH order): (v0, index in mesh), e1, e2, and the three
//   vertex normals (object space).
// bvh_instances: the world-to-object rows, the BLAS root and the three material rows.

@group(0) @binding(0) var<storage, read> bvh_nodes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> bvh_triangles: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> bvh_instances: array<BvhInstance>;

struct BvhInstance {
    row0: vec4<f32>,
    row1: vec4<f32>,
    row2: vec4<f32>,
    root: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
    // (kind, ior, thin, attenuation distance), (attenuation colour, 0), (albedo or f0, 0).
    mat: array<vec4<f32>, 3>,
}

// Row `k` (0 to 2) of triangle `slot`'s corners and edges, (v0, e1, e2).
fn bvh_tri(slot: u32, k: u32) -> vec4<f32> { return bvh_triangles[6u * slot + k]; }
// Vertex normal `k` (0 to 2) of triangle `slot`, object space.
fn bvh_normal(slot: u32, k: u32) -> vec4<f32> { return bvh_triangles[6u * slot + 3u + k]; }
// Material row `k` (0 to 2) of instance `i`.
fn scene_material(i: u32, k: u32) -> vec4<f32> { return bvh_instances[i].mat[k]; }

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

fn bvh_header() -> vec4<u32> { return bitcast<vec4<u32>>(bvh_nodes[0]); }

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
// `base` is the first BLAS node's vec4 (the header's z).
fn bvh_blas(inst_index: u32, base: u32, o_world: vec3<f32>, d_world: vec3<f32>, tmin: f32, best: ptr<function, BvhHit>) {
    let root = bvh_instances[inst_index].root;
    if root == BVH_INVALID {
        return;
    }
    let row0 = bvh_instances[inst_index].row0;
    let row1 = bvh_instances[inst_index].row1;
    let row2 = bvh_instances[inst_index].row2;
    let p = vec4(o_world, 1.0);
    let v = vec4(d_world, 0.0);
    let o = vec3(dot(row0, p), dot(row1, p), dot(row2, p));
    let d = vec3(dot(row0, v), dot(row1, v), dot(row2, v));
    let inv = bvh_inv_dir(d);
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    stack[0] = root;
    sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let n = stack[sp];
        let v = bvh_visit(bvh_nodes[base + 2u * n], bvh_nodes[base + 2u * n + 1u], o, inv, tmin, (*best).t);
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
            let a = bvh_tri(tri, 0u);
            let e1 = bvh_tri(tri, 1u).xyz;
            let e2 = bvh_tri(tri, 2u).xyz;
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
    let header = bvh_header();
    if header.x == 0u {
        return best;
    }
    let inv = bvh_inv_dir(d);
    var stack: array<u32, BVH_STACK>;
    var sp = 1u;
    stack[0] = 0u;
    while sp > 0u {
        sp -= 1u;
        let n = stack[sp];
        let v = bvh_visit(bvh_nodes[1u + 2u * n], bvh_nodes[2u + 2u * n], o, inv, tmin, best.t);
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
            let slot = first + k;
            let prim = bitcast<vec4<u32>>(bvh_nodes[header.y + slot / 4u])[slot % 4u];
            bvh_blas(prim, header.z, o, d, tmin, &best);
        }
    }
    if best.instance == BVH_INVALID {
        best.t = BVH_FAR;
    }
    return best;
}
