//! Pixel footprints and irradiance from photon flux (seed 003 section 3.3).

use glam::Vec3;

/// Guard (stiff suite: "light at 89.9 degrees", "camera 1e4 m away").
/// Smallest surface cosine a footprint is computed with: at more grazing view angles the
/// footprint is clamped to `1 / MIN_SURFACE_COS` times the perpendicular area (a 1e4x
/// stretch), so irradiance never divides by zero. Callers count the clamps.
pub const MIN_SURFACE_COS: f32 = 1e-4;

/// Intrinsics of a pinhole camera in pixels: the focal lengths `f_x = (w / 2) / tan(θ_x / 2)`
/// and `f_y = (h / 2) / tan(θ_y / 2)` that appear in seed 003's footprint formula.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFocal {
    /// Horizontal focal length, pixels.
    pub fx: f32,
    /// Vertical focal length, pixels.
    pub fy: f32,
}

impl PixelFocal {
    /// From a vertical field of view (radians) and the target size in pixels, square pixels.
    pub fn from_fov_y(fov_y: f32, width: u32, height: u32) -> Self {
        let _ = width;
        let f = 0.5 * height.max(1) as f32 / (0.5 * fov_y.clamp(1e-4, 3.1)).tan();
        Self { fx: f, fy: f }
    }
}

/// World-space area covered by one pixel of a perspective camera on a surface.
///
/// Seed 003 section 3.3 (after Kim 2019) gives, on the optical axis,
/// `A_p = (2 d tan(θ_x/2) / w)(2 d tan(θ_y/2) / h) = d^2 / (f_x f_y)`: the pixel's area
/// perpendicular to the eye ray at distance `d`, and eq. (3) multiplies the irradiance by
/// `<-d, n>`. We use the physically exact form for any pixel, on or off axis:
///
/// `A_p = Ω_p d^2 / cos θ_s`, with the pixel solid angle `Ω_p = cos^3 α / (f_x f_y)`,
///
/// where `α` is the angle between the eye ray and the camera's forward axis (`cos_alpha`) and
/// `θ_s` the angle between the eye ray and the surface normal (`cos_surface`). On the axis
/// (`α = 0`) it is exactly the seed's `A_p / <-d, n>`; off the axis the seed's form
/// overestimates the area by `1 / cos^3 α` (9 % at the corner of a 45-degree view), which the
/// report would otherwise show as a vignette of missing energy.
///
/// Guards: `cos_surface` below [`MIN_SURFACE_COS`] is clamped; a zero or non-finite distance
/// gives area 0 (callers must not deposit then); focal lengths are floored at 1e-6.
#[inline]
pub fn pixel_footprint_area(
    distance: f32,
    cos_alpha: f32,
    cos_surface: f32,
    focal: PixelFocal,
) -> f32 {
    if !distance.is_finite() || distance <= 0.0 {
        return 0.0;
    }
    let ca = cos_alpha.abs().min(1.0);
    let omega = ca * ca * ca / (focal.fx.max(1e-6) * focal.fy.max(1e-6));
    let cs = cos_surface.abs().clamp(MIN_SURFACE_COS, 1.0);
    let a = omega * distance * distance / cs;
    if a.is_finite() { a } else { f32::MAX }
}

/// World-space area of one pixel of an orthographic camera whose pixels measure
/// `pixel_w x pixel_h` metres, on a surface at angle `θ_s` to the (parallel) eye rays:
/// `A_p = pixel_w pixel_h / cos θ_s`. Same guard as [`pixel_footprint_area`].
#[inline]
pub fn ortho_footprint_area(pixel_w: f32, pixel_h: f32, cos_surface: f32) -> f32 {
    let cs = cos_surface.abs().clamp(MIN_SURFACE_COS, 1.0);
    (pixel_w.abs() * pixel_h.abs() / cs).min(f32::MAX)
}

/// Irradiance (W/m^2, or lux when the flux is in lumens) that a photon of `flux` adds to a
/// pixel whose footprint is `area`: `E = Φ / A_p` (seed 003 eq. 3 with `A_p` the footprint on
/// the surface, so the cosine is inside the area). Zero for a zero, negative or non-finite
/// area; a non-finite flux gives zero.
#[inline]
pub fn irradiance_from_flux(flux: Vec3, area: f32) -> Vec3 {
    if !(area.is_finite() && area > 0.0 && flux.is_finite()) {
        return Vec3::ZERO;
    }
    let e = flux / area;
    if e.is_finite() { e } else { Vec3::ZERO }
}

/// Irradiance on a surface lit by a parallel beam of perpendicular irradiance `e_perp`
/// (Bevy's `DirectionalLight::illuminance`) at incidence `cos_theta`: `E = E_perp cos θ`.
#[inline]
pub fn beam_irradiance(e_perp: f32, cos_theta: f32) -> f32 {
    e_perp * cos_theta.clamp(0.0, 1.0)
}

/// Lambertian radiance leaving a diffuse surface of `albedo` under irradiance `e`:
/// `L = albedo / π · E`. The composite pass multiplies this by the view exposure.
#[inline]
pub fn lambert_radiance(albedo: Vec3, e: Vec3) -> Vec3 {
    albedo * e * core::f32::consts::FRAC_1_PI
}
