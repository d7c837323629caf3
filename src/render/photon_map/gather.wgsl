// The photon map's gather (seed 001 section 3.2): per caustics-camera pixel, the point and
// normal from the depth prepass and the deferred G-buffer, then every photon of the 9 row
// ranges of its 3x3x3 cells within r (no k-nearest heap) whose normal agrees with the pixel's,
// weighted by the normalised Epanechnikov kernel (optics::gather_kernel). With FLAG_ACCUMULATE
// the result is blended into the running mean of the progressive frames. Appended to
// trace.wgsl (same module and bindings).

@group(0) @binding(12) var<storage, read> sorted: array<Photon>;
@group(0) @binding(13) var<storage, read> cells: array<u32>;
// Per pixel: rgb the mean irradiance (lux) over the accumulated frames, w the distance from
// the eye to the pixel's point, negative where the pixel shows a mirror; then, from
// `pixel_count()` on, per pixel x the frames in its mean and y the mean photon density its
// gathers found over them (photons per m² per frame; pixel_radius).
@group(0) @binding(14) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(15) var view_depth: texture_depth_2d;
@group(0) @binding(16) var gbuffer: texture_2d<u32>;
@group(0) @binding(17) var out_caustics: texture_storage_2d<rgba32float, write>;
// A right eye's left eye's `accum` (a 16-byte dummy for other views).
@group(0) @binding(18) var<storage, read> left_accum: array<vec4<f32>>;

// Pixel to world through the prepass depth (reverse-Z NDC); w = 0 where nothing was drawn.
fn pixel_point(p: vec2<i32>, size: vec2<f32>) -> vec4<f32> {
    let z = textureLoad(view_depth, p, 0);
    if !(z > 0.0) {
        return vec4(0.0);
    }
    let ndc = vec2((f32(p.x) + 0.5) / size.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / size.y * 2.0);
    let h = params.world_from_clip * vec4(ndc, z, 1.0);
    let x = h.xyz / h.w;
    return select(vec4(0.0), vec4(x, 1.0), finite3(x) && h.w != 0.0);
}

struct GatherResult {
    e: vec3<f32>,
    visited: u32,
    used: u32,
    rejected: u32,
}

// The centre cell of x's neighbourhood: its cell clamped into the grid (optics::GridLayout::rows);
// w = 0: empty grid or a non-finite x.
fn gather_centre(x: vec3<f32>) -> vec4<u32> {
    let dims = grid_dims();
    if any(dims < vec3(3u)) {
        return vec4(0u);
    }
    let origin = vec3(bitcast<f32>(atomicLoad(&header[H_ORIGIN])), bitcast<f32>(atomicLoad(&header[H_ORIGIN + 1u])), bitcast<f32>(atomicLoad(&header[H_ORIGIN + 2u])));
    let inv = bitcast<f32>(atomicLoad(&header[H_INV]));
    let f = floor((x - origin) * inv);
    if !finite3(f) {
        return vec4(0u);
    }
    let c = clamp(f, vec3(0.0), vec3<f32>(dims - vec3(1u)));
    return vec4(vec3<u32>(c), 1u);
}

fn grid_dims() -> vec3<u32> {
    return vec3(atomicLoad(&header[H_DIMS]), atomicLoad(&header[H_DIMS + 1u]), atomicLoad(&header[H_DIMS + 2u]));
}

// The cells within `reach` of centre c, cut at the grid's faces: [lo, hi] per axis.
struct GatherBox {
    lo: vec3<u32>,
    hi: vec3<u32>,
}

fn gather_box(c: vec3<u32>, reach: u32) -> GatherBox {
    let m = vec3(clamp(reach, 1u, GATHER_MAX_REACH));
    var b: GatherBox;
    b.lo = max(c, m) - m;
    b.hi = min(c + m, grid_dims() - vec3(1u));
    return b;
}

// Row k of box b (rows along x, k over y then z): the cell range [first, last).
fn gather_row(b: GatherBox, k: u32) -> vec2<u32> {
    let dims = grid_dims();
    let ny = b.hi.y - b.lo.y + 1u;
    let y = b.lo.y + k % ny;
    let z = b.lo.z + k / ny;
    let first = (z * dims.y + y) * dims.x + b.lo.x;
    return vec2(first, first + b.hi.x - b.lo.x + 1u);
}

fn gather_rows(b: GatherBox) -> u32 {
    return (b.hi.y - b.lo.y + 1u) * (b.hi.z - b.lo.z + 1u);
}

fn gather_photon(p: Photon, x: vec3<f32>, n: vec3<f32>, r2: f32, g: ptr<function, GatherResult>) {
    let v = p.pos - x;
    let d2 = dot(v, v);
    if d2 < r2 {
        if dot(oct_decode(p.normal), n) >= params.view.w {
            (*g).used += 1u;
            (*g).e += p.flux * gather_kernel(d2, r2);
        } else {
            (*g).rejected += 1u;
        }
    }
}

// The radius of pixel idx at point x seen from the eye: this frame's progressive radius, scaled
// with FLAG_DENSITY from the first frame's (lens.w) to the pixel's own (optics::density_radius
// of the photon density its earlier frames found, accum's y, for forward.w photons:
// PhotonMapSettings::gather_photons), then optics::gather_radius with the pixel footprint.
fn pixel_radius(x: vec3<f32>, n: vec3<f32>, idx: u32) -> f32 {
    var r = sqrt(params.view.z);
    let r1 = params.lens.w;
    if (params.frame.w & FLAG_DENSITY) != 0u && params.forward.w > 0.0 && r1 > 0.0 {
        let c = accum[pixel_count() + idx];
        if c.x >= 1.0 {
            r *= optics_density_radius(r1, c.y, params.forward.w) / r1;
        }
    }
    let cell = bitcast<f32>(atomicLoad(&header[H_CELL]));
    var area = 0.0;
    if params.lens.z != 0.0 {
        let to = x - params.eye.xyz;
        let dist = length(to);
        let cos_alpha = dot(to / dist, params.forward.xyz);
        let cos_surface = dot(n, -to / dist);
        area = optics_pixel_footprint_area(dist, cos_alpha, cos_surface, params.lens.xy);
    }
    return gather_radius(r, area, cell);
}

// optics::gather: every photon of the row ranges of x's neighbourhood within radius r.
fn gather_at(x: vec3<f32>, n: vec3<f32>, r: f32) -> GatherResult {
    var g: GatherResult;
    let c = gather_centre(x);
    if c.w == 0u {
        return g;
    }
    let r2 = r * r;
    let b = gather_box(c.xyz, gather_reach(r, bitcast<f32>(atomicLoad(&header[H_INV]))));
    for (var k = 0u; k < gather_rows(b); k += 1u) {
        let row = gather_row(b, k);
        let a = cells[row.x];
        let e = cells[row.y];
        g.visited += e - a;
        for (var i = a; i < e; i += 1u) {
            gather_photon(sorted[i], x, n, r2, &g);
        }
    }
    return g;
}

fn count_gather(g: GatherResult) {
    atomicAdd(&header[C_PIXELS], 1u);
    atomicAdd(&header[C_VISITED], g.visited);
    atomicAdd(&header[C_USED], g.used);
    atomicAdd(&header[C_NORMAL_REJECTS], g.rejected);
    atomicMax(&header[C_USED_MAX], g.used);
    atomicMax(&header[C_VISITED_MAX], g.visited);
}

// Blend this frame's irradiance into the pixel's running mean and write the caustics buffer.
// `mirror`: the value is a mirror pixel's `F · albedo · E` (its own albedo is already in it),
// marked by alpha -1 for the composite (src/render/composite/composite.wgsl).
// `density_in`: the photons per m² this frame's gather found (their running mean sizes the
// pixel's later gathers with FLAG_DENSITY, pixel_radius).
fn resolve_pixel(p: vec2<i32>, e_in: vec3<f32>, dist: f32, mirror: bool, density_in: f32) {
    let idx = u32(p.y) * u32(params.view.x) + u32(p.x);
    let count_at = pixel_count() + idx;
    let e = select(vec3(0.0), e_in, finite3(e_in));
    let density = select(0.0, density_in, density_in >= 0.0 && density_in <= 3.4e38);
    var mean = e;
    var density_mean = density;
    var n = 1.0;
    if (params.frame.w & FLAG_ACCUMULATE) != 0u {
        let prev = accum[idx];
        // A receiver moved this frame (outside the caustic light's reach, or the whole mean
        // would have restarted): a pixel whose visible surface moved starts its mean again.
        let moved = (params.frame.w & FLAG_VALIDATE) != 0u
            && (abs(abs(prev.w) - dist) > params.gather.w * dist || (prev.w < 0.0) != mirror);
        if !moved {
            let c = accum[count_at];
            n = c.x + 1.0;
            mean = prev.xyz + (e - prev.xyz) / n;
            density_mean = c.y + (density - c.y) / n;
        }
    }
    // w: the eye distance, negative on a mirror pixel (kept for the frozen mean).
    accum[idx] = vec4(mean, select(dist, -dist, mirror));
    accum[count_at] = vec4(n, density_mean, 0.0, 0.0);
    textureStore(out_caustics, p, vec4(mean, select(1.0, -1.0, mirror)));
}

// Caustics seen in a mirror: if the camera ray through x first hits a mirror at x, follow its
// reflections (Schlick F per mirror) to the diffuse point they show and gather there, with the
// footprint of the whole path. Returns `F · albedo · E` in rgb and w = 1, or w = 0 when the
// pixel does not show a mirror (or the path ends on glass, the sky or the bounce limit).
fn mirror_term(x: vec3<f32>) -> vec4<f32> {
    let eye = params.eye.xyz;
    let to = x - eye;
    let dist = length(to);
    if !(dist > 0.0) {
        return vec4(0.0);
    }
    var d = to / dist;
    let cos_alpha = dot(d, params.forward.xyz);
    var hit = bvh_closest_hit(eye, d, 0.0, BVH_FAR);
    // The pixel shows the mirror only if the ray meets it at the pixel's depth.
    if hit.instance == BVH_INVALID || abs(hit.t - dist) > 0.01 * dist + 1.0e-4 * params.eye.w {
        return vec4(0.0);
    }
    var s = surface_hit(hit, eye, d);
    if s.kind != MAT_CONDUCTOR || !s.ok {
        return vec4(0.0);
    }
    var f = vec3(1.0);
    var travelled = hit.t;
    for (var bounce = 0u; bounce < params.emit.z; bounce += 1u) {
        f *= optics_fresnel_schlick(-dot(d, s.ns_f), scene_material(hit.instance, 2u).xyz);
        let o = optics_offset_ray_origin(s.pos, s.ng_f, params.eye.w);
        d = reflect_guarded(d, s.ns_f, s.ng_f);
        hit = bvh_closest_hit(o, d, 0.0, BVH_FAR);
        if hit.instance == BVH_INVALID {
            return vec4(0.0);
        }
        travelled += hit.t;
        s = surface_hit(hit, o, d);
        if !s.ok || s.kind == MAT_DIELECTRIC {
            return vec4(0.0);
        }
        if s.kind == MAT_DIFFUSE {
            let n = s.ng_f;
            let area = optics_pixel_footprint_area(travelled, cos_alpha, dot(n, -d), params.lens.xy);
            let cell = bitcast<f32>(atomicLoad(&header[H_CELL]));
            let r = gather_radius(sqrt(params.view.z), select(0.0, area, params.lens.z != 0.0), cell);
            let g = gather_at(s.pos, n, r);
            count_gather(g);
            atomicAdd(&header[C_MIRROR_PIXELS], 1u);
            let albedo = scene_material(hit.instance, 2u).xyz;
            return vec4(f * albedo * g.e, 1.0);
        }
    }
    return vec4(0.0);
}

// The right eye of a stereo pair: the left eye's mean where the left eye sees the same point.
// x is reprojected into the left view and the left means are interpolated bilinearly from the
// 4 pixels around it; each tap's point must lie where x does (its distance from the left eye
// within 2 % of x's: one pixel's footprint at grazing angles stays within it), else the pixel
// gathers itself (an edge or a disocclusion). w = 1 when reused. Both eyes have the same size.
fn stereo_reuse(x: vec3<f32>) -> vec4<f32> {
    atomicAdd(&header[C_STEREO_PIXELS], 1u);
    let c = params.other_clip_from_world * vec4(x, 1.0);
    if !(c.w > 0.0) {
        return vec4(0.0);
    }
    let ndc = c.xy / c.w;
    let size = params.view.xy;
    let pf = vec2((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y) - 0.5;
    if !all(pf >= vec2(0.0)) || !all(pf <= size - 1.0) {
        return vec4(0.0);
    }
    let base = vec2<u32>(floor(pf));
    let f = pf - floor(pf);
    let d = distance(x, params.other_eye.xyz);
    var sum = vec3(0.0);
    for (var k = 0u; k < 4u; k += 1u) {
        let o = vec2(k & 1u, k >> 1u);
        let q = min(base + o, vec2<u32>(size) - 1u);
        let a = left_accum[q.y * u32(size.x) + q.x];
        if !(a.w > 0.0) || abs(a.w - d) > 0.02 * d || !finite3(a.xyz) {
            return vec4(0.0);
        }
        let w = select(1.0 - f.x, f.x, o.x == 1u) * select(1.0 - f.y, f.y, o.y == 1u);
        sum += w * a.xyz;
    }
    atomicAdd(&header[C_STEREO_REUSED], 1u);
    return vec4(sum, 1.0);
}

// Store a value that is already a mean (a reused left-eye pixel) without blending.
fn store_pixel(p: vec2<i32>, e: vec3<f32>, dist: f32) {
    let idx = u32(p.y) * u32(params.view.x) + u32(p.x);
    accum[idx] = vec4(e, dist);
    accum[pixel_count() + idx] = vec4(params.gather.y, 0.0, 0.0, 0.0);
    textureStore(out_caustics, p, vec4(e, 1.0));
}

// This pixel's value: its own gather, or for a pixel showing a mirror, the mirror's term.
fn resolve_gathered(q: PixelInput, g: GatherResult) {
    if (params.frame.w & FLAG_MIRRORS) != 0u {
        let m = mirror_term(q.x);
        if m.w != 0.0 {
            resolve_pixel(q.p, m.xyz, distance(q.x, params.eye.xyz), true, 0.0);
            return;
        }
    }
    count_gather(g);
    let density = f32(g.used) / max(OPTICS_PI * q.r * q.r, 1e-30);
    resolve_pixel(q.p, g.e, distance(q.x, params.eye.xyz), false, density);
}

// Algorithm 1 of the seed, generalised to an 8x8 tile: when every pixel of the tile that has a
// surface falls into the same centre cell, the tile loads the photons of its 9 row ranges into
// workgroup memory together, 256 at a time, and each pixel tests them from there.
const TILE_PHOTONS: u32 = 256u;
var<workgroup> tile_photons: array<Photon, 256>;
var<workgroup> tile_min: atomic<u32>;
var<workgroup> tile_max: atomic<u32>;
var<workgroup> tile_key: u32;
var<workgroup> tile_range: vec2<u32>;
// PixelInput::key of a pixel whose gather reaches past the 3x3x3 (sorts just under INVALID).
const WIDE: u32 = 0xfffffffeu;

struct PixelInput {
    p: vec2<i32>,
    // false: outside the view or no surface (resolved to zero).
    ok: bool,
    x: vec3<f32>,
    r: f32,
    n: vec3<f32>,
    // The linear index of the centre cell of its neighbourhood (INVALID: none; WIDE: it
    // reaches past the 3x3x3, so its tile gathers pixel by pixel).
    key: u32,
}

fn pixel_input(gid: vec2<u32>) -> PixelInput {
    var q: PixelInput;
    q.p = vec2<i32>(gid);
    q.key = INVALID;
    let size = params.view.xy;
    if f32(q.p.x) >= size.x || f32(q.p.y) >= size.y {
        return q;
    }
    let x = pixel_point(q.p, size);
    let n = gbuffer_decode_normal(textureLoad(gbuffer, q.p, 0));
    if x.w == 0.0 || n.w == 0.0 {
        return q;
    }
    q.ok = true;
    q.x = x.xyz;
    q.n = n.xyz;
    q.r = pixel_radius(q.x, q.n, u32(q.p.y) * u32(size.x) + u32(q.p.x));
    let c = gather_centre(q.x);
    if c.w != 0u {
        let dims = grid_dims();
        q.key = (c.z * dims.y + c.y) * dims.x + c.x;
        // A footprint wider than the cell reaches further than the tile's shared 3x3x3.
        if gather_reach(q.r, bitcast<f32>(atomicLoad(&header[H_INV]))) > 1u {
            q.key = WIDE;
        }
    }
    return q;
}

fn pixel_count() -> u32 {
    return u32(params.view.x) * u32(params.view.y);
}

fn in_view(p: vec2<i32>) -> bool {
    return f32(p.x) < params.view.x && f32(p.y) < params.view.y;
}

// The cooperative gather of one tile whose pixels share the centre cell `key`.
fn gather_shared(q: PixelInput, key: u32, lid: u32) -> GatherResult {
    var g: GatherResult;
    let dims = grid_dims();
    let c = vec3(key % dims.x, (key / dims.x) % dims.y, key / (dims.x * dims.y));
    let r2 = q.r * q.r;
    let b = gather_box(c, 1u);
    for (var k = 0u; k < gather_rows(b); k += 1u) {
        if lid == 0u {
            let row = gather_row(b, k);
            tile_range = vec2(cells[row.x], cells[row.y]);
        }
        let range = workgroupUniformLoad(&tile_range);
        for (var base = range.x; base < range.y; base += TILE_PHOTONS) {
            let n = min(TILE_PHOTONS, range.y - base);
            for (var j = lid; j < n; j += 64u) {
                tile_photons[j] = sorted[base + j];
            }
            workgroupBarrier();
            if q.ok {
                g.visited += n;
                for (var i = 0u; i < n; i += 1u) {
                    gather_photon(tile_photons[i], q.x, q.n, r2, &g);
                }
            }
            workgroupBarrier();
        }
    }
    return g;
}

@compute @workgroup_size(8, 8)
fn pm_gather(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let size = params.view.xy;
    let p = vec2<i32>(gid.xy);
    let idx = u32(p.y) * u32(size.x) + u32(p.x);
    if idx == 0u {
        atomicStore(&header[C_FRAME], u32(params.gather.y));
    }
    if (params.frame.w & FLAG_FROZEN) != 0u {
        if in_view(p) {
            let a = accum[idx];
            textureStore(out_caustics, p, vec4(a.xyz, select(1.0, -1.0, a.w < 0.0)));
        }
        return;
    }
    let q = pixel_input(gid.xy);
    if (params.frame.w & FLAG_SHARED) != 0u {
        // Uniform control flow: every invocation reaches the barriers.
        if lid == 0u {
            atomicStore(&tile_min, INVALID);
            atomicStore(&tile_max, 0u);
        }
        workgroupBarrier();
        if q.ok {
            atomicMin(&tile_min, q.key);
            atomicMax(&tile_max, q.key);
        }
        workgroupBarrier();
        if lid == 0u {
            let lo = atomicLoad(&tile_min);
            let hi = atomicLoad(&tile_max);
            // One centre cell for the whole tile (and at least one pixel with a surface).
            tile_key = select(INVALID, lo, lo == hi && lo != WIDE);
            if lo == hi && lo < WIDE {
                atomicAdd(&header[C_SHARED_TILES], 1u);
            } else if lo != INVALID {
                atomicAdd(&header[C_FALLBACK_TILES], 1u);
            }
        }
        let key = workgroupUniformLoad(&tile_key);
        if key != INVALID {
            let g = gather_shared(q, key, lid);
            if q.ok {
                resolve_gathered(q, g);
            } else if in_view(q.p) {
                resolve_pixel(q.p, vec3(0.0), 0.0, false, 0.0);
            }
            return;
        }
    }
    if !in_view(q.p) {
        return;
    }
    if !q.ok {
        resolve_pixel(q.p, vec3(0.0), 0.0, false, 0.0);
        return;
    }
    if (params.frame.w & FLAG_REUSE) != 0u {
        let s = stereo_reuse(q.x);
        if s.w != 0.0 {
            store_pixel(q.p, s.xyz, distance(q.x, params.eye.xyz));
            return;
        }
    }
    resolve_gathered(q, gather_at(q.x, q.n, q.r));
}
