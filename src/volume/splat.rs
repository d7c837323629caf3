//! Density estimate and oriented splats of caustics volumes (seed 000 section 3.4). Written
//! once here; `src/render/volume/common.wgsl` has the WGSL twins (`vol_texel_area`,
//! `vol_splat_axes`), tested against these in `tests/gpu/volume.rs`.

use glam::Vec3;

use crate::optics::orthonormal_basis;

/// Receiver area (m²) seen by one texel of a projector (seed 000 section 3.4; the frustum of
/// [`super::VolumeFrame::projector`]): at axis distance `z` the texel spans
/// `2 h_a z / (h_i res)` by `2 h_b z / (h_i res)` on the plane normal to the face axis; a
/// surface of normal `n` hit along the unit ray `r` from the centre covers
/// `A_plane |r . axis| / |r . n|` of it. Guards: the cosine is at least 1e-3 (grazing
/// receivers), non-finite inputs give 0.
#[allow(clippy::too_many_arguments)]
pub fn projector_texel_area(
    z: f32,
    half_axis: f32,
    half_a: f32,
    half_b: f32,
    res: u32,
    ray: Vec3,
    axis: Vec3,
    normal: Vec3,
) -> f32 {
    let res = res.max(1) as f32;
    let hi = half_axis.max(1e-9);
    let plane = (2.0 * half_a * z / (hi * res)) * (2.0 * half_b * z / (hi * res));
    let a = plane * ray.dot(axis).abs() / ray.dot(normal).abs().max(1e-3);
    if a.is_finite() { a.max(0.0) } else { 0.0 }
}

/// The oriented splat of one photon (seed 000 section 3.4): "orthogonal basis ... from the
/// surface normal at the intersection, the projection of the intersection direction at the
/// plane defined by the surface normal and the third vector is the cross product". The disc
/// covers `overlap` photons' share of the tile (`π r² = overlap · area_per_photon`), its
/// radius kept in `[r_min, max(r_min, spread · path_length)]` (the path length from the last
/// specular event bounds how far a photon's beam can have spread), and it is stretched along
/// the projected direction by `s = sqrt(min(1 / |cos θ|, max_anisotropy))` and shrunk across
/// by `1 / s` (area kept). Returns the two semi-axes (world vectors); the splat's irradiance is
/// `flux / (π |a| |b|)`. Guards: the direction is normalised (zero or non-finite: none);
/// zero or non-finite inputs give a disc of radius `r_min`
/// (itself at least 1e-9 m) in the surface plane; a direction along the normal uses any
/// tangent.
#[allow(clippy::too_many_arguments)]
pub fn volume_splat_axes(
    dir: Vec3,
    normal: Vec3,
    area_per_photon: f32,
    overlap: f32,
    path_length: f32,
    spread: f32,
    max_anisotropy: f32,
    r_min: f32,
) -> (Vec3, Vec3) {
    let n = normal.try_normalize().unwrap_or(Vec3::Y);
    let r_min = if r_min.is_finite() {
        r_min.max(1e-9)
    } else {
        1e-9
    };
    let want = (overlap.max(0.0) * area_per_photon.max(0.0) / core::f32::consts::PI).sqrt();
    let cap = (spread.max(0.0) * path_length.max(0.0)).max(r_min);
    let r = if want.is_finite() {
        want.clamp(r_min, if cap.is_finite() { cap } else { r_min })
    } else {
        r_min
    };
    let d = dir.try_normalize().unwrap_or(Vec3::ZERO);
    let proj = d - n * d.dot(n);
    // A direction within 1e-4 rad of the normal has no usable projection (rounding decides
    // it): the disc is round there anyway, take the normal's basis.
    let (t1, t2) = if proj.length() > 1e-4 {
        let t1 = proj.normalize();
        (t1, n.cross(t1).normalize())
    } else {
        orthonormal_basis(n)
    };
    let cos = d.dot(n).abs();
    let max_a = if max_anisotropy.is_finite() {
        max_anisotropy.max(1.0)
    } else {
        1.0
    };
    let stretch = if cos > 0.0 {
        (1.0 / cos).clamp(1.0, max_a)
    } else {
        max_a
    };
    let s = stretch.sqrt();
    (t1 * (r * s), t2 * (r / s))
}
