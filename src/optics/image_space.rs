//! The image-space photon tracer's optics (seed 003, cascaded image-space photon tracing):
//! the low-discrepancy sample points over a reflective shadow map, the exact termination of a
//! depth-buffer march (eq. 2), the three reprojection cases, where a photon inside a caster
//! meets its layers, the light cone of a point light, the fixed-point photon-map encoding and
//! SVGF's edge-stopping weight. The WGSL twins are in
//! src/render/optics.wgsl (`optics_is_*`), tested against these in tests/gpu/twins.rs.

use glam::{Vec2, Vec3};

use super::R2_STEP;

/// Sample point `n` of the R2 low-discrepancy sequence in `[0, 1)²`, rotated by `rotation`
/// (a Cranley-Patterson shift in 0.32 fixed point, new every frame), with the steps of
/// [`R2_STEP`] (the same sequence as AAPS's texel samples).
///
/// Section 3.1 samples the RSM with "blue noise, a low-discrepancy sequence"; the reference
/// code (birt-caustics) uses a tiled 16x16 white-noise texture. R2 has the lowest
/// discrepancy of the additive recurrences and is exact in integer arithmetic (`n · a mod 1`
/// in 0.32 fixed point), so the GPU twin gives bit-identical points for any `n < 2^32`,
/// where an `f32` product would lose every fractional bit past `n = 2^24`.
#[inline]
pub fn r2_point(n: u32, rotation: [u32; 2]) -> Vec2 {
    let x = n.wrapping_mul(R2_STEP[0]).wrapping_add(rotation[0]);
    let y = n.wrapping_mul(R2_STEP[1]).wrapping_add(rotation[1]);
    Vec2::new(
        (x >> 8) as f32 * (1.0 / 16_777_216.0),
        (y >> 8) as f32 * (1.0 / 16_777_216.0),
    )
}

/// Where between two march steps the ray meets the depth buffer (seed 003 eq. 2): with view
/// depths `zr0, zr1` of the ray and `zs0, zs1` of the samples beneath at steps `t_n` and
/// `t_{n+1}`, both linear in `u ∈ [0, 1]`, the crossing is
/// `u' = (zs0 − zr0) / ((zr1 − zr0) − (zs1 − zs0))`.
///
/// Guards: parallel segments (zero denominator) or non-finite input give 1 (the later step,
/// where the march saw the ray behind the surface); the result is clamped to `[0, 1]`.
#[inline]
pub fn march_crossing(zr0: f32, zr1: f32, zs0: f32, zs1: f32) -> f32 {
    if !(zr0.is_finite() && zr1.is_finite() && zs0.is_finite() && zs1.is_finite()) {
        return 1.0;
    }
    let den = (zr1 - zr0) - (zs1 - zs0);
    let u = (zs0 - zr0) / den;
    if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// The three cases of a light-space march's end reprojected into the camera (seed 003
/// section 3.2, figure 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reprojection {
    /// The end lies on the surface the camera sees there: a hit.
    Plane = 0,
    /// The end floats in front of the camera's surface: march on in the camera's depth.
    Concave = 1,
    /// The end is hidden behind the camera's surface: the photon is lost.
    Convex = 2,
}

/// Classify a reprojected end at camera view depth `z_ray` over a camera depth sample
/// `z_scene`, with `thickness` as a fraction of the sample's depth (the plane case's
/// tolerance). Non-finite depths (no geometry) count as concave: the march goes on and finds
/// nothing.
#[inline]
pub fn classify_reprojection(z_ray: f32, z_scene: f32, thickness: f32) -> Reprojection {
    if !(z_ray.is_finite() && z_scene.is_finite()) {
        return Reprojection::Concave;
    }
    let tol = thickness.max(0.0) * z_scene.abs();
    if (z_ray - z_scene).abs() <= tol {
        Reprojection::Plane
    } else if z_ray < z_scene {
        Reprojection::Concave
    } else {
        Reprojection::Convex
    }
}

/// Where a photon inside a closed caster stands against the light's two caster layers at one
/// texel (ours, past seed 003's one interface plus the exit; issue 29): inside while its view
/// depth along the light lies between the caster-front layer (`z_front`, the surface nearest
/// the light) and the caster-back layer (`z_back`, the nearest surface facing away). A closed
/// convex caster's every boundary point is in one of the two, so a photon reflected inside it
/// leaves the interval exactly where it meets the glass again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InsideLayers {
    /// Between the layers: still in the medium.
    Inside = 0,
    /// At or past the caster-back layer: meets a surface facing away from the light.
    Back = 1,
    /// At or before the caster-front layer: meets a surface facing the light.
    Front = 2,
    /// The front layer is empty (depth `<= 0`) or a depth is not finite: the photon crossed
    /// the caster's silhouette, where the layers cannot tell where it met the glass.
    Lost = 3,
}

/// Classify view depth `z_ray` between layer depths `z_front` and `z_back` (`<= 0`: empty).
/// An empty back layer under a front one is an open medium (a water surface without a
/// bottom): inside below the front. A front layer behind the back one (crossed layers of two
/// casters) is lost as well.
#[inline]
pub fn inside_layers(z_ray: f32, z_front: f32, z_back: f32) -> InsideLayers {
    let finite = z_ray.is_finite() && z_front.is_finite() && z_back.is_finite();
    let back = z_back > 0.0;
    if !finite || z_front <= 0.0 || (back && z_front > z_back) {
        InsideLayers::Lost
    } else if back && z_ray >= z_back {
        InsideLayers::Back
    } else if z_ray <= z_front {
        InsideLayers::Front
    } else {
        InsideLayers::Inside
    }
}

/// The cone from a point light at `apex` that holds the casters' bounding sphere
/// (`centre`, `radius`): its axis and half angle, at most `max_half_angle` (a spot light's
/// outer angle; a point light's RSM is capped at 80 degrees, where a perspective map still
/// resolves its edge). Photons outside it cannot start a specular path, as in the reference
/// tracer. An apex inside the sphere, or a degenerate sphere, gives the cap around
/// `fallback_axis` (or the direction to the centre when there is one).
pub fn cone_around_sphere(
    apex: Vec3,
    centre: Vec3,
    radius: f32,
    max_half_angle: f32,
    fallback_axis: Vec3,
) -> (Vec3, f32) {
    let cap = if max_half_angle.is_finite() {
        max_half_angle.clamp(1e-4, 80f32.to_radians())
    } else {
        80f32.to_radians()
    };
    let to = centre - apex;
    let dist = to.length();
    let fallback = fallback_axis.try_normalize().unwrap_or(Vec3::NEG_Y);
    let Some(axis) = to.try_normalize() else {
        return (fallback, cap);
    };
    if !(radius.is_finite() && dist.is_finite()) || dist <= radius {
        return (axis, cap);
    }
    (
        (axis),
        (radius / dist).clamp(0.0, 1.0).asin().clamp(1e-4, cap),
    )
}

/// Scale of a texel's flux for one photon: `texels / samples` (section 3.1: "the sampled flux
/// must be scaled by the ratio of the RSM resolution to the total number of samples"). Zero
/// samples give 0.
#[inline]
pub fn photon_flux_scale(texels: f32, samples: f32) -> f32 {
    if samples >= 1.0 && texels.is_finite() && samples.is_finite() {
        texels / samples
    } else {
        0.0
    }
}

/// Units per lux of the photon map's fixed-point words (and of the fixed-point splats of
/// `render::fixed_splat`): 1/256 lux resolution, 2^56 / 256 ≈ 2.8e14 lux per pixel before a
/// 64-bit word wraps.
pub const FIXED_POINT_SCALE: f32 = 256.0;

/// One photon's irradiance `e` (lux, ≥ 0) in the photon map's fixed point with stochastic
/// rounding (`floor(e · scale + u)`, `u` uniform in `[0, 1)`: unbiased, so photons far below
/// the resolution still add up). Returns the word and whether it was clamped (non-finite or
/// negative input gives 0, above `u32::MAX` units is clamped: both counted by the caller).
#[inline]
pub fn fixed_point_word(e: f32, scale: f32, u: f32) -> (u32, bool) {
    if !(e.is_finite() && e >= 0.0) {
        return (0, e != 0.0);
    }
    let v = (e * scale + u.clamp(0.0, 1.0)).floor();
    if v >= 4_294_967_040.0 {
        (4_294_967_040, true)
    } else {
        (v as u32, false)
    }
}

/// The value in lux of a 64-bit sum of [`fixed_point_word`]s, low word `lo`, high word `hi`.
#[inline]
pub fn fixed_point_value(lo: u32, hi: u32, scale: f32) -> f32 {
    hi as f32 * (4_294_967_296.0 / scale) + lo as f32 / scale
}

/// SVGF's edge-stopping weight between pixels p and q (Schied et al. 2017 eq. 3-5):
/// `w = exp(−|z_p − z_q| / (σ_z |∇z · (p − q)| + ε) − |l_p − l_q| / (σ_l √Var(l_p) + ε))
/// · max(0, n_p · n_q)^σ_n`, with `dz_scaled = σ_z |∇z · (p − q)|` precomputed and
/// `l_sigma = σ_l √Var` (ε = 1e-6 in both). Non-finite input gives 0.
#[inline]
pub fn svgf_weight(
    dz: f32,
    dz_scaled: f32,
    n_dot: f32,
    sigma_n: f32,
    dl: f32,
    l_sigma: f32,
) -> f32 {
    let wz = dz.abs() / (dz_scaled.abs() + 1e-6);
    let wl = dl.abs() / (l_sigma.abs() + 1e-6);
    let wn = n_dot.clamp(0.0, 1.0).powf(sigma_n.max(0.0));
    let w = (-(wz + wl)).exp() * wn;
    if w.is_finite() { w } else { 0.0 }
}
