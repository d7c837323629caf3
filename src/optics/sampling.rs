//! Deterministic random numbers and the light-sampling mappings of the reference tracer.

use core::f32::consts::{PI, TAU};
use glam::{Vec2, Vec3};

/// A small deterministic generator (PCG-XSH-RR 64/32). Each photon seeds its own stream from
/// `(seed, light, photon index)` so results do not depend on thread scheduling.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A stream for `(seed, stream)`; different streams are decorrelated.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: 0,
            inc: (splitmix64(stream) << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(splitmix64(seed));
        r.next_u32();
        r
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniforms in [0, 1).
    pub fn next_vec2(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// SplitMix64 finaliser, used to hash seeds.
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E3779B97F4A7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D049BB133111EB);
    x ^ (x >> 31)
}

/// Uniform point on the unit disc (Shirley-Chiu concentric map: area preserving, so the
/// photon density over a directional light's disc is uniform).
pub fn concentric_disc(u: Vec2) -> Vec2 {
    let a = 2.0 * u - Vec2::ONE;
    if a.x == 0.0 && a.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.x.abs() > a.y.abs() {
        (a.x, (PI / 4.0) * (a.y / a.x))
    } else {
        (a.y, PI / 2.0 - (PI / 4.0) * (a.x / a.y))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Uniform direction on the unit sphere (pdf `1 / 4π`).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction inside a cone of half-angle `acos(cos_max)` around +Z
/// (pdf `1 / (2π (1 - cos_max))`).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_max = cos_max.clamp(-1.0, 1.0);
    let z = 1.0 - u.x * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Solid angle of a cone: `2π (1 - cos_max)`.
pub fn cone_solid_angle(cos_max: f32) -> f32 {
    TAU * (1.0 - cos_max.clamp(-1.0, 1.0))
}

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al. 2017, branchless,
/// stable for every `n` including `-Z`).
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Rotate a direction given around +Z into the frame whose +Z is `axis`.
pub fn to_world(local: Vec3, axis: Vec3) -> Vec3 {
    let (t, b) = orthonormal_basis(axis);
    t * local.x + b * local.y + axis * local.z
}

/// Bevy's spot-light cone attenuation (`bevy_pbr` `lighting.wgsl`): with
/// `scale = 1 / max(cos_inner - cos_outer, 1e-4)` and `offset = -cos_outer scale`,
/// `a = saturate(cos_angle scale + offset)^2`. Bevy applies no cone normalisation: a spot's
/// intensity is `lumens / 4π` candela on its axis, like a point light.
pub fn spot_attenuation(cos_angle: f32, inner_angle: f32, outer_angle: f32) -> f32 {
    let cos_outer = outer_angle.cos();
    let cos_inner = inner_angle.cos();
    let scale = 1.0 / (cos_inner - cos_outer).max(1e-4);
    let offset = -cos_outer * scale;
    let a = (cos_angle * scale + offset).clamp(0.0, 1.0);
    a * a
}

/// A stateless 32-bit hash (PCG-RXS-M-XS, Jarzynski and Olano 2020, "Hash Functions for GPU
/// Rendering"): one GPU thread's random decision without a stored generator. WGSL twin
/// `optics_pcg_hash` (`src/render/optics.wgsl`), tested bit for bit.
#[inline]
pub fn pcg_hash(x: u32) -> u32 {
    let state = x.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// A uniform number in [0, 1) for the pair `(a, b)` (e.g. photon and bounce): the top 24 bits
/// of `pcg_hash(a ^ pcg_hash(b))`, exact in f32. AAPS's Fresnel choice after its one split
/// (seed 004 section 3.3.1, extended). WGSL twin `optics_hash_unit`.
#[inline]
pub fn hash_unit(a: u32, b: u32) -> f32 {
    (pcg_hash(a ^ pcg_hash(b)) >> 8) as f32 * (1.0 / 16_777_216.0)
}
