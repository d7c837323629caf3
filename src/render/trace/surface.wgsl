// The scene's surfaces and lights for every BVH photon tracer (AAPS, the photon map): binding
// 8 of group 0 (bvh.wgsl holds 0 to 2, the packed scene with its normals and materials), the
// light table of src/render/trace/scene.rs,
// surface normals at a hit, the tracer's guarded reflection and refraction, and emission from
// a light's parameter square. Concatenated after bvh.wgsl and optics.wgsl
// (`trace::tracer_source`).

@group(0) @binding(8) var<storage, read> lights: array<GpuLight>;

// One light (80 bytes, `GpuLight` in src/render/trace/scene.rs).
struct GpuLight {
    position: vec4<f32>, // xyz: point/spot position or the directional grid's corner; w kind
    axis: vec4<f32>,     // xyz: travel direction (directional) or spot axis; w cos outer
    side_u: vec4<f32>,   // directional grid edge along u; w cos inner
    side_v: vec4<f32>,   // directional grid edge along v
    power: vec4<f32>,    // rgb: power over the whole parameter square (lm or lux m^2)
}

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;

const MAT_DIFFUSE: u32 = 0u;
const MAT_DIELECTRIC: u32 = 1u;
const MAT_CONDUCTOR: u32 = 2u;

const INVALID: u32 = 0xffffffffu;
const TRACE_PI: f32 = 3.14159265358979;

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3(3.0e38));
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

fn object_point(inst: BvhInstance, p: vec3<f32>) -> vec3<f32> {
    let q = vec4(p, 1.0);
    return vec3(dot(inst.row0, q), dot(inst.row1, q), dot(inst.row2, q));
}

// World normal of an object-space normal: the transpose of local_from_world's linear part.
fn world_normal(inst: BvhInstance, n: vec3<f32>) -> vec3<f32> {
    let w = inst.row0.xyz * n.x + inst.row1.xyz * n.y + inst.row2.xyz * n.z;
    let l = length(w);
    return select(vec3(0.0), w / l, l > 0.0 && l < 3.0e38);
}

// Interpolated shading normal of triangle `slot` at barycentrics (u, v), world space.
fn shading_normal(inst: BvhInstance, slot: u32, uv: vec2<f32>) -> vec3<f32> {
    let n = bvh_normal(slot, 0u) * (1.0 - uv.x - uv.y) + bvh_normal(slot, 1u) * uv.x
        + bvh_normal(slot, 2u) * uv.y;
    return world_normal(inst, n.xyz);
}

// reflect_guarded (src/reference/tracer.rs): about the shading normal unless that sends the
// ray into the surface, then about the geometric normal.
fn reflect_guarded(d: vec3<f32>, ns_f: vec3<f32>, ng_f: vec3<f32>) -> vec3<f32> {
    let r = optics_reflect(d, ns_f);
    return select(optics_reflect(d, ng_f), r, dot(r, ng_f) > 0.0);
}

// Refraction with the tracer's geometric-normal fallback; w = 0 when both fail (TIR).
fn refract_guarded(d: vec3<f32>, ns_f: vec3<f32>, ng_f: vec3<f32>, eta: f32) -> vec4<f32> {
    let t = optics_refract(d, ns_f, eta);
    if t.w > 0.0 && dot(t.xyz, ng_f) < 0.0 {
        return t;
    }
    return optics_refract(d, ng_f, eta);
}

// A ray's hit, as the tracers see it: the point, the material kind, both normals and both
// normals turned towards the ray's side.
struct SurfaceHit {
    pos: vec3<f32>,
    kind: u32,
    ng: vec3<f32>,
    // false: a non-finite point or a degenerate triangle (count it, stop the path).
    ok: bool,
    ng_f: vec3<f32>,
    entering: bool,
    ns_f: vec3<f32>,
}

fn surface_hit(hit: BvhHit, o: vec3<f32>, d: vec3<f32>) -> SurfaceHit {
    var s: SurfaceHit;
    s.pos = o + d * hit.t;
    s.kind = bitcast<u32>(scene_material(hit.instance, 0u).x);
    let inst = bvh_instances[hit.instance];
    s.ng = world_normal(inst, cross(bvh_tri(hit.slot, 1u).xyz, bvh_tri(hit.slot, 2u).xyz));
    var ns = shading_normal(inst, hit.slot, hit.uv);
    s.ok = finite3(s.pos) && any(s.ng != vec3(0.0));
    if all(ns == vec3(0.0)) {
        ns = s.ng;
    }
    s.entering = dot(d, s.ng) < 0.0;
    s.ng_f = select(-s.ng, s.ng, s.entering);
    s.ns_f = select(ns, -ns, dot(d, ns) > 0.0);
    return s;
}

// A photon leaving a light: origin, direction and the weight of the light's distribution at
// parameter `uv` in [0, 1)^2 (the spot cone; 1 otherwise). Directional lights: a point of the
// origin grid, travelling along the axis; point and spot lights: the equal-area mapping of the
// square onto the sphere (seed 004 section 3.2.1).
struct Emission {
    o: vec3<f32>,
    weight: f32,
    d: vec3<f32>,
}

fn light_emit(light: GpuLight, uv: vec2<f32>) -> Emission {
    var e: Emission;
    e.weight = 1.0;
    let kind = bitcast<u32>(light.position.w);
    if kind == LIGHT_DIRECTIONAL {
        e.o = light.position.xyz + uv.x * light.side_u.xyz + uv.y * light.side_v.xyz;
        e.d = light.axis.xyz;
    }
#ifdef TRACE_POINT_LIGHTS
    else {
        e.o = light.position.xyz;
        e.d = optics_equal_area_square_to_sphere(uv);
        if kind == LIGHT_SPOT {
            e.weight = optics_spot_attenuation(dot(e.d, light.axis.xyz), light.side_u.w, light.axis.w);
        }
    }
#endif
    return e;
}

// A thread's share of the frame's specular-event budget (`bounce_budget` of AAPS and the photon
// map), which bounds a trace's cost whatever the scene's chains of internal reflections: the
// thread takes events from the technique's shared count in chunks of 1, 2, 4, then 8, so a
// path of a few events wastes at most about one and a long path pays one atomic per eight;
// a thread gives back what it did not use when it ends (`left`). At the call site, with the
// shared count `granted`:
//     event_take(&b) || event_grant(&b, atomicAdd(&granted, b.next), budget)
// When the budget binds, the paths of the dispatch's later threads stop first.
struct EventBudget {
    left: u32,
    next: u32,
    used: u32,
}

fn event_budget() -> EventBudget {
    return EventBudget(0u, 1u, 0u);
}

// One event from the events this thread already holds.
fn event_take(b: ptr<function, EventBudget>) -> bool {
    if (*b).left == 0u {
        return false;
    }
    (*b).left -= 1u;
    (*b).used += 1u;
    return true;
}

// The shared count stood at `old` before this thread added `(*b).next` to it: hold what is left
// of the budget up to that and take one event; false once the frame's budget is spent.
fn event_grant(b: ptr<function, EventBudget>, old: u32, budget: u32) -> bool {
    if old >= budget {
        return false;
    }
    (*b).left = min((*b).next, budget - old);
    (*b).next = min(2u * (*b).next, 8u);
    return event_take(b);
}
