// WGSL twins of the optics core (src/optics): the same formulas, the same guards, tested
// against the Rust functions on lavapipe (tests/gpu.rs, wgsl_optics_match_rust).

const OPTICS_PI: f32 = 3.14159265358979;

// fresnel_dielectric (src/optics/fresnel.rs): exact unpolarised reflectance, eta = n_i / n_t.
fn optics_fresnel_dielectric(cos_i_in: f32, eta_in: f32) -> f32 {
    var eta = eta_in;
    if !(eta > 0.0) || eta > 3.0e38 {
        eta = 1.0;
    }
    if eta == 1.0 {
        return 0.0;
    }
    let cos_i = min(abs(cos_i_in), 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let s_den = eta * cos_i + cos_t;
    let p_den = cos_i + eta * cos_t;
    if s_den <= 1.17549435e-38 || p_den <= 1.17549435e-38 {
        return 1.0;
    }
    let rs = (eta * cos_i - cos_t) / s_den;
    let rp = (cos_i - eta * cos_t) / p_den;
    return clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// dielectric_eta (src/optics/fresnel.rs): n_i / n_t at a dielectric of index `ior`. Thick:
// 1 / ior entering, ior leaving. Thin-walled (glTF thickness 0): air on both sides, so 1 / ior
// from either side and never total internal reflection. Non-finite or below-1 ior: 1.
fn optics_dielectric_eta(ior_in: f32, entering: bool, thin: bool) -> f32 {
    var ior = 1.0;
    if ior_in <= 3.0e38 {
        ior = max(ior_in, 1.0);
    }
    return select(ior, 1.0 / ior, thin || entering);
}

// reflect (src/optics/mod.rs).
fn optics_reflect(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let r = d - 2.0 * dot(d, n) * n;
    let l = length(r);
    return select(-d, r / l, l > 0.0);
}

// refract (src/optics/mod.rs); w = 1 when refracted, w = 0 on total internal reflection.
fn optics_refract(d: vec3<f32>, n: vec3<f32>, eta: f32) -> vec4<f32> {
    let n_f = select(n, -n, dot(d, n) > 0.0);
    let cos_i = clamp(-dot(d, n_f), 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return vec4(0.0);
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let t = eta * d + (eta * cos_i - cos_t) * n_f;
    let l = length(t);
    return vec4(select(d, t / l, l > 0.0), 1.0);
}

fn optics_copysign(x: f32, s: f32) -> f32 {
    return select(abs(x), -abs(x), s < 0.0 || (s == 0.0 && bitcast<u32>(s) == 0x80000000u));
}

// equal_area_square_to_sphere (src/optics/aaps.rs): Clarberg's octahedral equal-area map.
fn optics_equal_area_square_to_sphere(uv: vec2<f32>) -> vec3<f32> {
    let p = clamp(uv, vec2(0.0), vec2(1.0)) * 2.0 - 1.0;
    let au = abs(p.x);
    let av = abs(p.y);
    let d = 1.0 - (au + av);
    let r = 1.0 - abs(d);
    var phi = 0.0;
    if r > 0.0 {
        phi = (OPTICS_PI / 4.0) * ((av - au) / r + 1.0);
    }
    let f = r * sqrt(max(2.0 - r * r, 0.0));
    let z = optics_copysign(1.0 - r * r, d);
    let v = vec3(f * optics_copysign(cos(phi), p.x), f * optics_copysign(sin(phi), p.y), z);
    let l = length(v);
    return select(vec3(0.0, 0.0, 1.0), v / l, l > 0.0);
}

// floor_square (src/optics/aaps.rs).
fn optics_floor_square(d: f32) -> u32 {
    if !(d > 0.0) || d > 3.0e38 {
        return 0u;
    }
    let k = u32(floor(sqrt(min(d, 16777216.0))));
    return k * k;
}


// photon_count (src/optics/aaps.rs): floor(d), at most 2^24.
fn optics_photon_count(d: f32) -> u32 {
    if !(d > 0.0) || d > 3.0e38 {
        return 0u;
    }
    return u32(floor(min(d, 16777216.0)));
}

// fresnel_schlick (src/optics/fresnel.rs).
fn optics_fresnel_schlick(cos_i: f32, f0: vec3<f32>) -> vec3<f32> {
    let c = 1.0 - min(abs(cos_i), 1.0);
    let c5 = c * c * c * c * c;
    return clamp(f0 + (vec3(1.0) - f0) * c5, vec3(0.0), vec3(1.0));
}

// beer_lambert (src/optics/mod.rs); a distance >= 3e38 means a clear medium.
fn optics_beer_lambert(color: vec3<f32>, dist: f32, len: f32) -> vec3<f32> {
    if !(dist > 0.0) || dist >= 3.0e38 || !(len > 0.0) {
        return vec3(1.0);
    }
    let x = min(len / dist, 1.0e6);
    let c = clamp(color, vec3(0.0), vec3(1.0));
    return pow(c, vec3(x));
}

// ROULETTE_DEPTH (src/optics/mod.rs): specular events after which Russian roulette may end a
// path.
const OPTICS_ROULETTE_DEPTH: u32 = 8u;

// roulette_survival (src/optics/mod.rs): the path's throughput max(flux) / flux0, clamped to
// [0.05, 1]; a zero flux0 or a non-finite ratio gives 0.05.
fn optics_roulette_survival(flux: vec3<f32>, flux0: f32) -> f32 {
    if flux0 == 0.0 {
        return 0.05;
    }
    let q = max(max(flux.x, flux.y), flux.z) / flux0;
    if !(abs(q) <= 3.40282347e38) {
        return 0.05;
    }
    return clamp(q, 0.05, 1.0);
}

// pcg_hash (src/optics/sampling.rs): PCG-RXS-M-XS, Jarzynski and Olano 2020.
fn optics_pcg_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// hash_unit (src/optics/sampling.rs): uniform in [0, 1) for the pair (a, b).
fn optics_hash_unit(a: u32, b: u32) -> f32 {
    return f32(optics_pcg_hash(a ^ optics_pcg_hash(b)) >> 8u) * (1.0 / 16777216.0);
}

// spot_attenuation (src/optics/sampling.rs), with the cosines precomputed.
fn optics_spot_attenuation(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let scale = 1.0 / max(cos_inner - cos_outer, 1.0e-4);
    let a = clamp(cos_angle * scale - cos_outer * scale, 0.0, 1.0);
    return a * a;
}

// orthonormal_basis (src/optics/sampling.rs): Duff et al. 2017. Returns (t, b) as two columns.
fn optics_orthonormal_basis(n: vec3<f32>) -> mat2x3<f32> {
    let sign = select(1.0, -1.0, n.z < 0.0 || (n.z == 0.0 && bitcast<u32>(n.z) == 0x80000000u));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(
        vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3(b, sign + n.y * n.y * a, -n.y),
    );
}

// offset_ray_origin (src/optics/offset.rs): Wächter and Binder, scaled by the scene size.
fn optics_offset_ray_origin(p: vec3<f32>, n: vec3<f32>, scene_scale: f32) -> vec3<f32> {
    var s = 1.0;
    if scene_scale > 0.0 && scene_scale < 3.0e38 {
        s = clamp(scene_scale, 1.0e-6, 1.0e6);
    }
    let origin_band = s / 32.0;
    let float_scale = s / 65536.0;
    var out = p;
    for (var i = 0; i < 3; i += 1) {
        let of_i = i32(256.0 * n[i]);
        let bits = bitcast<i32>(p[i]);
        let shifted = select(bits + of_i, bits - of_i, p[i] < 0.0);
        let p_i = bitcast<f32>(shifted);
        if abs(p[i]) < origin_band {
            out[i] = p[i] + float_scale * n[i];
        } else if abs(p_i) <= 3.4028235e38 {
            out[i] = p_i;
        }
    }
    return out;
}

// transfer_to_plane (src/optics/aaps.rs): where the ray (o, d) meets the plane through p with
// normal n; w = 1 on success, w = 0 (and p) when parallel or not finite.
fn optics_transfer_to_plane(o: vec3<f32>, d: vec3<f32>, p: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    let den = dot(d, n);
    if !(abs(den) >= 1.0e-12) || abs(den) > 3.0e38 {
        return vec4(p, 0.0);
    }
    let t = dot(p - o, n) / den;
    let q = o + d * t;
    if !(all(abs(q) <= vec3(3.4028235e38))) {
        return vec4(p, 0.0);
    }
    return vec4(q, 1.0);
}

struct OpticsSplat {
    a: vec3<f32>,
    b: vec3<f32>,
    clamped: bool,
}

fn optics_finite3(v: vec3<f32>) -> vec3<f32> {
    return select(vec3(0.0), v, all(abs(v) <= vec3(3.4028235e38)));
}

// splat_from_differentials (src/optics/aaps.rs): the ellipse with the second moments of the
// parallelogram (du, dv) in the plane of n, anisotropy <= max_aniso, semi-axes in [lo, hi].
fn optics_splat_from_differentials(du: vec3<f32>, dv: vec3<f32>, n_in: vec3<f32>, max_aniso: f32, lo_in: f32, hi_in: f32) -> OpticsSplat {
    let ln = length(n_in);
    let n = select(vec3(0.0, 1.0, 0.0), n_in / ln, ln > 0.0 && ln < 3.0e38);
    let tb = optics_orthonormal_basis(n);
    let t = tb[0];
    let b = tb[1];
    let du_f = optics_finite3(du);
    let dv_f = optics_finite3(dv);
    let p = vec2(dot(du_f, t), dot(du_f, b));
    let q = vec2(dot(dv_f, t), dot(dv_f, b));
    let m00 = p.x * p.x + q.x * q.x;
    let m01 = p.x * p.y + q.x * q.y;
    let m11 = p.y * p.y + q.y * q.y;
    let tr = m00 + m11;
    let disc = sqrt(max((m00 - m11) * (m00 - m11) * 0.25 + m01 * m01, 0.0));
    let l1 = max(0.5 * tr + disc, 0.0);
    let l2 = max(0.5 * tr - disc, 0.0);
    var axis = vec2(1.0, 0.0);
    if abs(m01) > 1.0e-30 {
        let v = vec2(l1 - m11, m01);
        let lv = length(v);
        axis = select(vec2(1.0, 0.0), v / lv, lv > 0.0 && lv < 3.0e38);
    } else if m00 < m11 {
        axis = vec2(0.0, 1.0);
    }
    var ra = sqrt(l1);
    var rb = sqrt(l2);
    let lo = max(lo_in, 0.0);
    var hi = 3.4028235e38;
    if hi_in < 3.0e38 && hi_in >= lo {
        hi = hi_in;
    }
    var aniso = 3.4028235e38;
    if max_aniso < 3.0e38 {
        aniso = max(max_aniso, 1.0);
    }
    let orig_a = ra;
    let orig_b = rb;
    ra = select(hi, clamp(ra, lo, hi), ra <= 3.4028235e38);
    rb = select(lo, clamp(rb, lo, hi), rb <= 3.4028235e38);
    rb = min(max(rb, ra / aniso), ra);
    let a3 = t * axis.x + b * axis.y;
    let b3 = cross(n, a3);
    return OpticsSplat(a3 * ra, b3 * rb, ra != orig_a || rb != orig_b);
}

fn optics_nonneg(x: f32) -> f32 {
    return select(0.0, max(x, 0.0), abs(x) <= 3.4028235e38);
}

// suggested_density (src/optics/aaps.rs): D' = D A / A_t + v g.
fn optics_suggested_density(d: f32, area: f32, target_area: f32, variance: f32, gain: f32) -> f32 {
    var ratio = 1.0;
    if target_area > 0.0 && target_area <= 3.4028235e38 {
        ratio = optics_nonneg(area) / target_area;
    }
    let out = optics_nonneg(d) * ratio + optics_nonneg(variance) * optics_nonneg(gain);
    return select(3.4028235e38, out, out <= 3.4028235e38);
}

// blend_density (src/optics/aaps.rs) with unit neighbour weights: `previous` holds the previous
// densities of the texel and its neighbours (the first `count`).
fn optics_blend_density(suggested: f32, previous: array<f32, 5>, count: u32, w_t_in: f32, min_density: f32, max_density: f32) -> f32 {
    var w_t = 1.0;
    if abs(w_t_in) <= 3.4028235e38 {
        w_t = clamp(w_t_in, 0.0, 1.0);
    }
    var sw = 0.0;
    var sd = 0.0;
    for (var i = 0u; i < min(count, 5u); i += 1u) {
        let d = previous[i];
        if abs(d) <= 3.4028235e38 {
            sw += 1.0;
            sd += d;
        }
    }
    let spatial = select(suggested, sd / sw, sw > 0.0);
    let lo = max(min_density, 1.0);
    var hi = 3.4028235e38;
    if max_density <= 3.4028235e38 && max_density >= lo {
        hi = max_density;
    }
    let d = clamp(w_t * suggested + (1.0 - w_t) * spatial, lo, min(hi, 16777216.0));
    return f32(max(max(optics_floor_square(d), optics_floor_square(lo)), 1u));
}

// budget_split (src/optics/aaps.rs): (floor, scale) of the frame's budget.
fn optics_budget_split(budget_in: f32, share_in: f32, sum: f32, contributing: u32, idle: u32, min_density: f32) -> vec2<f32> {
    var share = 0.0;
    if abs(share_in) <= 3.4028235e38 {
        share = clamp(share_in, 0.0, 1.0);
    }
    var budget = 0.0;
    if abs(budget_in) <= 3.4028235e38 {
        budget = max(budget_in, 0.0);
    }
    let lo = f32(optics_floor_square(max(min_density, 1.0)));
    let rest = max(budget - lo * f32(idle), 0.0);
    var floor_d = 0.0;
    if contributing > 0u {
        floor_d = share * rest / f32(contributing);
    }
    let adaptive = (1.0 - share) * rest;
    var scale = 1.0;
    if abs(sum) <= 3.4028235e38 && sum > adaptive {
        scale = adaptive / sum;
    }
    return vec2(floor_d, scale);
}

// budget_density (src/optics/aaps.rs).
fn optics_budget_density(d_in: f32, contributing: bool, floor_d: f32, scale: f32, min_density: f32, max_density: f32) -> f32 {
    var d = 0.0;
    if abs(d_in) <= 3.4028235e38 {
        d = max(d_in, 0.0);
    }
    var out = d * scale;
    if contributing {
        out = max(out, floor_d);
    }
    if max_density > 0.0 {
        out = min(out, max_density);
    }
    out = max(out, f32(optics_floor_square(max(min_density, 1.0))));
    return select(16777216.0, min(out, 16777216.0), abs(out) <= 3.4028235e38);
}

// r2_point (src/optics/image_space.rs): R2 sequence in 0.32 fixed point, rotated.
fn optics_r2_point(n: u32, rotation: vec2<u32>) -> vec2<f32> {
    let x = n * 3242174889u + rotation.x;
    let y = n * 2447445414u + rotation.y;
    return vec2(f32(x >> 8u), f32(y >> 8u)) * (1.0 / 16777216.0);
}

// march_crossing (src/optics/image_space.rs): seed 003 eq. 2.
fn optics_march_crossing(zr0: f32, zr1: f32, zs0: f32, zs1: f32) -> f32 {
    let z = vec4(zr0, zr1, zs0, zs1);
    if !(all(z == z) && all(abs(z) <= vec4(3.4e38))) {
        return 1.0;
    }
    let den = (zr1 - zr0) - (zs1 - zs0);
    let u = (zs0 - zr0) / den;
    if u == u && abs(u) <= 3.0e38 {
        return clamp(u, 0.0, 1.0);
    }
    return 1.0;
}

// classify_reprojection (src/optics/image_space.rs): 0 plane, 1 concave, 2 convex.
fn optics_classify_reprojection(z_ray: f32, z_scene: f32, thickness: f32) -> u32 {
    let finite = z_ray == z_ray && z_scene == z_scene && abs(z_ray) <= 3.4e38 && abs(z_scene) <= 3.4e38;
    if !finite {
        return 1u;
    }
    let tol = max(thickness, 0.0) * abs(z_scene);
    if abs(z_ray - z_scene) <= tol {
        return 0u;
    }
    return select(2u, 1u, z_ray < z_scene);
}

// inside_layers (src/optics/image_space.rs): 0 inside, 1 back, 2 front, 3 lost.
fn optics_inside_layers(z_ray: f32, z_front: f32, z_back: f32) -> u32 {
    let z = vec3(z_ray, z_front, z_back);
    let finite = all(z == z) && all(abs(z) <= vec3(3.4e38));
    let back = z_back > 0.0;
    if !finite || z_front <= 0.0 || (back && z_front > z_back) {
        return 3u;
    }
    if back && z_ray >= z_back {
        return 1u;
    }
    return select(0u, 2u, z_ray <= z_front);
}

// photon_flux_scale (src/optics/image_space.rs).
fn optics_photon_flux_scale(texels: f32, samples: f32) -> f32 {
    if samples >= 1.0 && abs(texels) <= 3.4e38 && samples <= 3.4e38 {
        return texels / samples;
    }
    return 0.0;
}

// fixed_point_word (src/optics/image_space.rs): x = word, y = 1 when clamped.
fn optics_fixed_point_word(e: f32, scale: f32, u: f32) -> vec2<u32> {
    if !(e == e && e >= 0.0 && e <= 3.4e38) {
        return vec2(0u, select(1u, 0u, e == 0.0));
    }
    let v = floor(e * scale + clamp(u, 0.0, 1.0));
    if v >= 4294967040.0 {
        return vec2(4294967040u, 1u);
    }
    return vec2(u32(v), 0u);
}

// fixed_point_value (src/optics/image_space.rs): a 64-bit sum of words in lux.
fn optics_fixed_point_value(lo: u32, hi: u32, scale: f32) -> f32 {
    return f32(hi) * (4294967296.0 / scale) + f32(lo) / scale;
}

// svgf_weight (src/optics/image_space.rs): SVGF's edge-stopping weight.
fn optics_svgf_weight(dz: f32, dz_scaled: f32, n_dot: f32, sigma_n: f32, dl: f32, l_sigma: f32) -> f32 {
    let wz = abs(dz) / (abs(dz_scaled) + 1.0e-6);
    let wl = abs(dl) / (abs(l_sigma) + 1.0e-6);
    let wn = pow(clamp(n_dot, 0.0, 1.0), max(sigma_n, 0.0));
    let w = exp(-(wz + wl)) * wn;
    return select(0.0, w, w == w && w <= 3.4e38);
}

// pixel_footprint_area (src/optics/footprint.rs): A_p = cos^3(alpha) d^2 / (f_x f_y cos θ_s).
fn optics_pixel_footprint_area(distance: f32, cos_alpha: f32, cos_surface: f32, focal: vec2<f32>) -> f32 {
    if !(distance > 0.0) || distance > 3.4e38 {
        return 0.0;
    }
    let ca = min(abs(cos_alpha), 1.0);
    let omega = ca * ca * ca / (max(focal.x, 1.0e-6) * max(focal.y, 1.0e-6));
    let cs = clamp(abs(cos_surface), 1.0e-4, 1.0);
    let a = omega * distance * distance / cs;
    return select(3.4028235e38, a, a <= 3.4e38);
}

// density_radius (src/optics/photon_map.rs): the radius holding `photons` photons at `density`
// (photons per m² per frame), r = sqrt(k / (π ρ)), within [0.25, 2] x r1
// (optics::DENSITY_RADIUS_RANGE); photons <= 0 or NaN, or r1 not positive and finite: r1; no
// density (or a radius that overflows): the range's top.
fn optics_density_radius(r1: f32, density: f32, photons: f32) -> f32 {
    if !(photons > 0.0) || !(r1 > 0.0) || !(r1 <= 3.4e38) {
        return r1;
    }
    let r = sqrt(photons / (OPTICS_PI * density));
    if density > 0.0 && r <= 3.4e38 {
        return clamp(r, r1 * 0.25, r1 * 2.0);
    }
    return r1 * 2.0;
}
