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

