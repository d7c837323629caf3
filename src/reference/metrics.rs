//! Image metrics between two caustic buffers: RMSE, mean FLIP, relative energy error.
//!
//! All three are computed over the *receiver pixels*: a mask of the pixels where the camera
//! sees a diffuse surface (or, without a mask, every pixel).

use glam::Vec3;

use super::CausticImage;
use crate::optics::{PixelFocal, luminance};
use crate::scene::{CameraProjection, TraceCamera};

/// The metrics the report and the CLI print.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ImageMetrics {
    /// Root mean square error of the luminance of irradiance, lux.
    pub rmse: f64,
    /// RMSE divided by the mean reference luminance (dimensionless).
    pub relative_rmse: f64,
    /// Mean LDR-FLIP error in [0, 1] (see [`flip_mean`] for the tone mapping).
    pub flip: f64,
    /// Mean LDR-FLIP error over the pixels the caustic lights ([`caustic_lit`]: reference
    /// luminance at least [`LIT_FRACTION`] of its 99th percentile), same tone mapping as
    /// `flip`: how sharp and how bright the caustic itself is, not the dark floor around it.
    pub flip_caustic: f64,
    /// `(sum test - sum ref) / sum ref` of luminance: the relative total-energy error.
    pub energy_error: f64,
    /// Pixels compared.
    pub pixels: u64,
}

fn in_mask(mask: Option<&[bool]>, i: usize) -> bool {
    mask.is_none_or(|m| m.get(i).copied().unwrap_or(false))
}

/// Compare `test` against `reference` over `mask` (true = receiver pixel).
///
/// Returns `None` if the sizes differ.
pub fn compare(
    test: &CausticImage,
    reference: &CausticImage,
    mask: Option<&[bool]>,
) -> Option<ImageMetrics> {
    if test.width != reference.width || test.height != reference.height {
        return None;
    }
    let mut se = 0.0f64;
    let (mut st, mut sr) = (0.0f64, 0.0f64);
    let mut n = 0u64;
    for (i, (t, r)) in test.data.iter().zip(&reference.data).enumerate() {
        if !in_mask(mask, i) {
            continue;
        }
        let lt = finite_lum(*t);
        let lr = finite_lum(*r);
        se += (lt - lr) * (lt - lr);
        st += lt;
        sr += lr;
        n += 1;
    }
    let rmse = if n > 0 { (se / n as f64).sqrt() } else { 0.0 };
    let mean_ref = if n > 0 { sr / n as f64 } else { 0.0 };
    let flip = flip_map(test, reference, mask);
    let lit = caustic_lit(reference, mask);
    Some(ImageMetrics {
        rmse,
        relative_rmse: if mean_ref > 0.0 { rmse / mean_ref } else { 0.0 },
        flip: masked_mean(&flip, mask),
        flip_caustic: masked_mean(&flip, Some(&lit)),
        energy_error: if sr > 0.0 {
            (st - sr) / sr
        } else if st > 0.0 {
            1.0
        } else {
            0.0
        },
        pixels: n,
    })
}

fn finite_lum(v: Vec3) -> f64 {
    let l = luminance(v) as f64;
    if l.is_finite() { l } else { 0.0 }
}

/// Mean FLIP (Andersson et al. 2020, the `nv-flip` crate) between two irradiance buffers.
///
/// FLIP compares displayable images, so both are mapped the same way first: divided by the
/// reference's 99th-percentile luminance over the mask (so the brightest 1 % of the
/// reference saturates), clamped to [0, 1] and sRGB-encoded. Pixels outside the mask are set
/// to black in both. The mean is over the masked pixels, at the default 67 pixels per degree.
pub fn flip_mean(test: &CausticImage, reference: &CausticImage, mask: Option<&[bool]>) -> f64 {
    masked_mean(&flip_map(test, reference, mask), mask)
}

/// Share of the reference's 99th-percentile luminance from which a pixel counts as lit by
/// the caustic ([`caustic_lit`]).
pub const LIT_FRACTION: f32 = 0.01;

/// The pixels of `mask` that the caustic lights: reference luminance at least
/// [`LIT_FRACTION`] of the reference's 99th-percentile luminance over the mask (none when
/// the reference is dark).
pub fn caustic_lit(reference: &CausticImage, mask: Option<&[bool]>) -> Vec<bool> {
    let p99 = p99_luminance(reference, mask);
    reference
        .data
        .iter()
        .enumerate()
        .map(|(i, v)| in_mask(mask, i) && p99 > 0.0 && finite_lum(*v) as f32 >= LIT_FRACTION * p99)
        .collect()
}

fn p99_luminance(reference: &CausticImage, mask: Option<&[bool]>) -> f32 {
    let mut lums: Vec<f32> = reference
        .data
        .iter()
        .enumerate()
        .filter(|(i, _)| in_mask(mask, *i))
        .map(|(_, v)| finite_lum(*v) as f32)
        .collect();
    if lums.is_empty() {
        return 0.0;
    }
    lums.sort_by(f32::total_cmp);
    lums[((lums.len() - 1) as f32 * 0.99) as usize]
}

/// Per-pixel FLIP error with the tone mapping of [`flip_mean`].
fn flip_map(test: &CausticImage, reference: &CausticImage, mask: Option<&[bool]>) -> Vec<f32> {
    let p99 = p99_luminance(reference, mask);
    let scale = if p99 > 0.0 { 1.0 / p99 } else { 1.0 };
    let encode = |img: &CausticImage| -> Vec<u8> {
        let mut out = Vec::with_capacity(img.data.len() * 3);
        for (i, v) in img.data.iter().enumerate() {
            let v = if in_mask(mask, i) && v.is_finite() {
                *v * scale
            } else {
                Vec3::ZERO
            };
            for c in v.to_array() {
                out.push((srgb_encode(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8);
            }
        }
        out
    };
    let (w, h) = (reference.width, reference.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &encode(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &encode(test));
    nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
}

fn masked_mean(values: &[f32], mask: Option<&[bool]>) -> f64 {
    let (mut s, mut n) = (0.0f64, 0u64);
    for (i, e) in values.iter().enumerate() {
        if in_mask(mask, i) {
            s += *e as f64;
            n += 1;
        }
    }
    if n > 0 { s / n as f64 } else { 0.0 }
}

/// The sRGB transfer function.
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Mean luminance of the irradiance over the pixels whose eye ray meets the plane `n . x = d`
/// inside `inside`, and their number (closed-form checks).
pub fn plane_region_mean(
    img: &CausticImage,
    cam: &TraceCamera,
    n: Vec3,
    d: f32,
    inside: impl Fn(Vec3) -> bool,
) -> (f32, usize) {
    let CameraProjection::Perspective { fov_y } = cam.projection else {
        return (0.0, 0);
    };
    let focal = PixelFocal::from_fov_y(fov_y, cam.width, cam.height);
    let eye = cam.position();
    let (mut sum, mut count) = (0.0f64, 0usize);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let local = Vec3::new(
                (x as f32 + 0.5 - 0.5 * cam.width as f32) / focal.fx,
                -(y as f32 + 0.5 - 0.5 * cam.height as f32) / focal.fy,
                -1.0,
            );
            let dir = cam.world_from_view.transform_vector3(local).normalize();
            let t = (d - n.dot(eye)) / n.dot(dir);
            if t > 0.0 && inside(eye + dir * t) {
                sum += luminance(img.get(x, y)) as f64;
                count += 1;
            }
        }
    }
    ((sum / count.max(1) as f64) as f32, count)
}

/// Mean FLIP between two 8-bit sRGB images of `w` x `h` pixels (RGB, 3 bytes a pixel), as
/// the example tests compare a render with its golden image.
pub fn flip_mean_rgb8(test: &[u8], reference: &[u8], w: u32, h: u32) -> f64 {
    let r = nv_flip::FlipImageRgb8::with_data(w, h, reference);
    let t = nv_flip::FlipImageRgb8::with_data(w, h, test);
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
    if err.is_empty() {
        return 0.0;
    }
    err.iter().map(|e| *e as f64).sum::<f64>() / err.len() as f64
}
