//! The caustic irradiance image on the CPU: EXR in and out.

use std::path::Path;

use glam::Vec3;

/// A caustic irradiance buffer on the CPU: linear RGB per pixel, row-major from the top-left,
/// in the light's units (lux for Bevy lights).
#[derive(Clone, Debug, PartialEq)]
pub struct CausticImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels.
    pub data: Vec<Vec3>,
}

impl CausticImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![Vec3::ZERO; (width * height) as usize],
        }
    }

    /// Pixel at (x, y).
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.data[(y * self.width + x) as usize]
    }

    /// Sum over pixels, per channel.
    pub fn sum(&self) -> glam::DVec3 {
        self.data.iter().map(|v| v.as_dvec3()).sum()
    }

    /// True if every value is finite.
    pub fn all_finite(&self) -> bool {
        self.data.iter().all(|v| v.is_finite())
    }

    /// Write as a float32 RGB OpenEXR file.
    pub fn write_exr(&self, path: impl AsRef<Path>) -> Result<(), String> {
        let w = self.width as usize;
        exr::prelude::write_rgb_file(path.as_ref(), w, self.height as usize, |x, y| {
            let v = self.data[y * w + x];
            (v.x, v.y, v.z)
        })
        .map_err(|e| format!("cannot write {}: {e}", path.as_ref().display()))
    }

    /// Read the first RGB(A) layer of an OpenEXR file.
    pub fn read_exr(path: impl AsRef<Path>) -> Result<Self, String> {
        let img = exr::prelude::read_first_rgba_layer_from_file(
            path.as_ref(),
            |size, _| CausticImage::new(size.0 as u32, size.1 as u32),
            |img: &mut CausticImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let i = pos.1 * img.width as usize + pos.0;
                img.data[i] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| format!("cannot read {}: {e}", path.as_ref().display()))?;
        Ok(img.layer_data.channel_data.pixels)
    }

    /// Mean over the pixels inside the rectangle `[x0, x1) x [y0, y1)`.
    pub fn mean_in(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec3 {
        let mut s = glam::DVec3::ZERO;
        let mut n = 0u64;
        for y in y0..y1.min(self.height) {
            for x in x0..x1.min(self.width) {
                s += self.get(x, y).as_dvec3();
                n += 1;
            }
        }
        if n == 0 {
            Vec3::ZERO
        } else {
            (s / n as f64).as_vec3()
        }
    }
}
