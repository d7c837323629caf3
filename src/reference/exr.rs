//! OpenEXR in and out of a [`CausticImage`] (the tools' file format for irradiance).

use std::path::Path;

use glam::Vec3;

use super::CausticImage;

impl CausticImage {
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
}
