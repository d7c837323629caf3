//! Fresnel reflectance for dielectrics and conductors.

use glam::Vec3;

/// Exact unpolarised Fresnel reflectance of a dielectric interface.
///
/// `cos_i` is the cosine between the incident direction and the normal (either sign; its
/// absolute value is used), `eta = n_i / n_t`. With `cos_t` from Snell's law,
///
/// `r_s = (eta cos_i - cos_t) / (eta cos_i + cos_t)`,
/// `r_p = (cos_i - eta cos_t) / (cos_i + eta cos_t)` (both divided through by `n_t`),
/// `R = (r_s^2 + r_p^2) / 2`.
///
/// Returns 1 under total internal reflection and 0 for `eta = 1` (no interface). Used by every technique to choose reflect or
/// refract (seed 003 section 3.2 compares noise against this factor; seed 004 section 3.3.1
/// splits by it; seed 000 section 3.3 refracts "with Fresnel").
///
/// Guards: `cos_i` is clamped to [0, 1]; a non-positive or non-finite `eta` is treated as 1
/// (no interface); the grazing limit `cos_i = 0` gives R = 1 without dividing by zero.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let eta = if eta.is_finite() && eta > 0.0 {
        eta
    } else {
        1.0
    };
    if eta == 1.0 {
        // Guard (stiff suite: "IOR 1.0"). No interface (IOR 1): nothing reflects, even at grazing incidence where rounding
        // would otherwise report total internal reflection.
        return 0.0;
    }
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let s_den = eta * cos_i + cos_t;
    let p_den = cos_i + eta * cos_t;
    if s_den <= f32::MIN_POSITIVE || p_den <= f32::MIN_POSITIVE {
        return 1.0;
    }
    let rs = (eta * cos_i - cos_t) / s_den;
    let rp = (cos_i - eta * cos_t) / p_den;
    (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0)
}

/// The relative index `eta = n_i / n_t` a photon meets at a dielectric surface of index `ior`
/// (relative to air), written once for every tracer (the CPU reference and each GPU
/// technique; the WGSL twin is `optics_dielectric_eta` in `src/render/optics.wgsl`).
///
/// - Thick (a closed volume, glTF `KHR_materials_volume` with `thickness > 0`): `1 / ior`
///   entering from air, `ior` leaving into air, where total internal reflection can happen.
/// - Thin-walled (glTF `KHR_materials_transmission` without a volume, `thickness = 0`): the
///   wall has air on both sides, so light meets the air-to-glass ratio `1 / ior` from either
///   side: the same Fresnel reflectance front and back, and never total internal reflection
///   (`eta <= 1`, so [`fresnel_dielectric`] stays below 1 short of exactly grazing
///   incidence). Without this a photon inside a closed thin shell, or a single-sided pane
///   seen from its back, would use `eta = ior` and be totally reflected beyond 41.8 degrees
///   at IOR 1.5 (issue 32): trapped in thin shells until the bounce cap.
///
/// `entering` is true when the photon arrives on the side the geometric normal faces (from
/// outside a closed mesh); it is ignored for a thin wall.
///
/// Guards: a non-finite `ior` or one below 1 is treated as 1 (no interface, `eta = 1`), as
/// the materials' `max(ior, 1)`.
#[inline]
pub fn dielectric_eta(ior: f32, entering: bool, thin: bool) -> f32 {
    let ior = if ior.is_finite() { ior.max(1.0) } else { 1.0 };
    if thin || entering { 1.0 / ior } else { ior }
}

/// Fresnel transmittance of a dielectric interface computed from the *transmitted* field
/// (not as `1 - R`), so `R + T = 1` is a real test of energy conservation:
///
/// `t_s = 2 eta cos_i / (eta cos_i + cos_t)`, `t_p = 2 eta cos_i / (cos_i + eta cos_t)`,
/// `T = (cos_t / (eta cos_i)) (t_s^2 + t_p^2) / 2`.
///
/// Zero under total internal reflection and at grazing incidence; 1 for `eta = 1`.
#[inline]
pub fn fresnel_dielectric_transmittance(cos_i: f32, eta: f32) -> f32 {
    let eta = if eta.is_finite() && eta > 0.0 {
        eta
    } else {
        1.0
    };
    if eta == 1.0 {
        return 1.0;
    }
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 || cos_i <= f32::MIN_POSITIVE {
        return 0.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let ts = 2.0 * eta * cos_i / (eta * cos_i + cos_t);
    let tp = 2.0 * eta * cos_i / (cos_i + eta * cos_t);
    (cos_t / (eta * cos_i) * 0.5 * (ts * ts + tp * tp)).clamp(0.0, 1.0)
}

/// The critical angle's cosine for `eta = n_i / n_t > 1`: beyond it (smaller `cos_i`) light is
/// totally reflected. Returns 0 (no critical angle) when `eta <= 1`.
#[inline]
pub fn critical_cos(eta: f32) -> f32 {
    if eta <= 1.0 {
        0.0
    } else {
        (1.0 - 1.0 / (eta * eta)).max(0.0).sqrt()
    }
}

/// Conductor (mirror, metal) reflectance by Schlick's approximation with the normal-incidence
/// reflectance `f0` per channel: `F = f0 + (1 - f0)(1 - cos_i)^5`.
///
/// This is the metallic-workflow reflectance Bevy's `StandardMaterial` uses for `metallic = 1`
/// (`f0 = base_color`), so a glTF mirror keeps the colour its author gave it.
/// Clamped to [0, 1] per channel.
#[inline]
pub fn fresnel_schlick(cos_i: f32, f0: Vec3) -> Vec3 {
    let c = 1.0 - cos_i.abs().min(1.0);
    let c5 = c * c * c * c * c;
    (f0 + (Vec3::ONE - f0) * c5).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Exact unpolarised reflectance of a conductor with complex relative index `eta + i k`
/// (e.g. silver at 550 nm: eta 0.06, k 3.6): the classical formula
/// `R_s = (a^2 + b^2 - 2a cos + cos^2) / (a^2 + b^2 + 2a cos + cos^2)`,
/// `R_p = R_s (a^2 + b^2 - 2a sin tan + sin^2 tan^2) / (a^2 + b^2 + 2a sin tan + sin^2 tan^2)`,
/// with `2a^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2) + eta^2 - k^2 - sin^2` and
/// `2b^2 = sqrt(..) - (eta^2 - k^2 - sin^2)`.
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_i.abs().clamp(1e-6, 1.0);
    let sin2 = 1.0 - cos_i * cos_i;
    let e2k2 = eta * eta - k * k - sin2;
    let root = (e2k2 * e2k2 + 4.0 * eta * eta * k * k).max(0.0).sqrt();
    let a2 = (0.5 * (root + e2k2)).max(0.0);
    let b2 = (0.5 * (root - e2k2)).max(0.0);
    let a = a2.sqrt();
    let rs_num = a2 + b2 - 2.0 * a * cos_i + cos_i * cos_i;
    let rs_den = a2 + b2 + 2.0 * a * cos_i + cos_i * cos_i;
    let rs = rs_num / rs_den.max(f32::MIN_POSITIVE);
    let st = sin2 / cos_i; // sin * tan
    let rp_num = a2 + b2 - 2.0 * a * st + st * st;
    let rp_den = a2 + b2 + 2.0 * a * st + st * st;
    let rp = rs * rp_num / rp_den.max(f32::MIN_POSITIVE);
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}
