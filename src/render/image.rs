//! The caustic irradiance image on the CPU: what a readback of a caustics buffer gives and
//! what a CPU technique uploads into one. EXR in and out is a tool (`reference::exr`).

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
