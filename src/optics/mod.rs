//! The optics core: every formula the CPU reference and the GPU techniques share.
//!
//! Plain Rust on `glam`, no Bevy render types. Each function cites its equation and the seed
//! section it implements (`shared/seeds/`), guards its degenerate inputs, and never returns NaN
//! or infinity for finite inputs. The WGSL twins of these functions live in `src/render/` and
//! are tested against them.
//!
//! Conventions:
//! - Directions are unit vectors pointing *along* the travel of light.
//! - A normal passed to [`reflect`] / [`refract`] may face either side; the functions orient it.
//! - `eta` is the ratio `n_incident / n_transmitted`.

mod aaps;
mod footprint;
mod fresnel;
mod image_space;
mod media;
mod offset;
mod photon_map;
mod sampling;

pub use aaps::*;
pub use footprint::*;
pub use fresnel::*;
pub use image_space::*;
pub use media::*;
pub use offset::*;
pub use photon_map::*;
pub use sampling::*;

use glam::Vec3;

/// Mirror reflection of direction `d` about normal `n`: `r = d - 2 (d·n) n`.
///
/// Works for a normal on either side. The result is renormalised so long chains of
/// reflections do not drift off the unit sphere.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    let r = d - 2.0 * d.dot(n) * n;
    r.try_normalize().unwrap_or(-d)
}

/// Snell refraction of the unit direction `d` through a surface with unit normal `n`
/// (either side), with relative index `eta = n_i / n_t`.
///
/// `t = eta d + (eta cos_i - cos_t) n_f` with `n_f` the normal facing against `d`,
/// `cos_t = sqrt(1 - eta^2 (1 - cos_i^2))` (Snell's law). Returns `None` on total internal
/// reflection (`eta^2 (1 - cos_i^2) >= 1`).
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let n_f = if d.dot(n) > 0.0 { -n } else { n };
    let cos_i = (-d.dot(n_f)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let t = eta * d + (eta * cos_i - cos_t) * n_f;
    Some(t.try_normalize().unwrap_or(d))
}

/// Beer-Lambert transmittance over a path of `length` metres through a medium that keeps
/// `attenuation_color` of the light after `attenuation_distance` metres (the glTF
/// `KHR_materials_volume` / Bevy `StandardMaterial` convention):
/// `T = c^(length / distance)` per channel, i.e. `exp(-sigma length)` with
/// `sigma = -ln(c) / distance`.
///
/// Guards: a distance from 3e38 up (`f32::MAX`, infinity) or not positive means a clear
/// medium (T = 1), as in the WGSL twin `optics_beer_lambert`; a colour
/// channel of 0 gives T = 0 for any positive length; colours are clamped to [0, 1].
#[inline]
pub fn beer_lambert(attenuation_color: Vec3, attenuation_distance: f32, length: f32) -> Vec3 {
    if !(attenuation_distance > 0.0 && attenuation_distance < 3.0e38) || length <= 0.0 {
        return Vec3::ONE;
    }
    let x = (length / attenuation_distance).min(1e6);
    let c = attenuation_color.clamp(Vec3::ZERO, Vec3::ONE);
    Vec3::new(c.x.powf(x), c.y.powf(x), c.z.powf(x))
}

/// Specular events after which Russian roulette ([`roulette_survival`]) may end a path: the
/// reference tracer's default `TraceSettings::roulette_depth` and the photon map's trace
/// (`OPTICS_ROULETTE_DEPTH` in src/render/optics.wgsl). 8: a clear-glass path keeps its
/// flux (throughput 1, it always survives), so roulette only shortens the chains that have
/// already lost most of their flux (metals, absorbing media), and no short caustic path pays
/// the variance of it.
pub const ROULETTE_DEPTH: u32 = 8;

/// Survival probability of Russian roulette (the reference tracer after
/// `TraceSettings::roulette_depth` specular events, the photon map's trace after
/// [`ROULETTE_DEPTH`]) for a path carrying `flux` that left its light with largest channel
/// `flux0`: the path's throughput (largest channel), clamped to [0.05, 1]. A survivor carries
/// `flux / q` (unbiased). Guard: a zero or non-finite `flux0` (a photon of no flux) survives
/// with 0.05. WGSL twin: `optics_roulette_survival`.
#[inline]
pub fn roulette_survival(flux: Vec3, flux0: f32) -> f32 {
    let q = flux.max_element() / flux0;
    if q.is_finite() {
        q.clamp(0.05, 1.0)
    } else {
        0.05
    }
}

/// A finite-or-zero guard: returns `v` if every component is finite, else zero.
/// The tracers count how often this fires.
#[inline]
pub fn finite_or_zero(v: Vec3) -> Vec3 {
    if v.is_finite() { v } else { Vec3::ZERO }
}

/// Luminance of linear Rec.709 RGB (the weights Bevy uses).
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
