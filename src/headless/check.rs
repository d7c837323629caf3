//! The sizes of a render job against the device's maxima ([`crate::limits`]).

use super::RenderJob;
use crate::limits::{CausticsLimits, MAX_FRAMES};

/// Check the sizes of `job` against `limits` (see [`crate::limits`]): the image side and
/// pixels, the frames, the photons of its technique, and the AAPS and volume settings that
/// size memory or work. An error is one line naming the option and its maximum.
pub fn check_job(job: &RenderJob, limits: &CausticsLimits) -> Result<(), String> {
    let side = limits.max_image_side;
    if job.width == 0 || job.height == 0 || job.width > side || job.height > side {
        return Err(format!(
            "image size {}x{} is outside 1..={side} on each side",
            job.width, job.height
        ));
    }
    let pixels = job.width as u64 * job.height as u64;
    if pixels > limits.max_view_pixels {
        return Err(format!(
            "image size {}x{} has {pixels} pixels; this GPU allows {}",
            job.width, job.height, limits.max_view_pixels
        ));
    }
    if job.frames == 0 || job.frames > MAX_FRAMES {
        return Err(format!(
            "--frames {} is outside 1..={MAX_FRAMES}",
            job.frames
        ));
    }
    if let Some(p) = job.photons {
        let max = limits.max_photons(job.technique);
        if p > max {
            return Err(format!(
                "--photons {p} is above the {} technique's maximum on this GPU, {max}",
                job.technique.name()
            ));
        }
    }
    // The components' own checks; a job refuses what a component would clamp.
    let refused = |option: &str, fixes: Vec<crate::components::validate::Fix>| match fixes.first() {
        Some((field, detail)) => Err(format!(
            "{option} {field}: {}",
            detail.replace("clamped to", "the nearest accepted value is")
        )),
        None => Ok(()),
    };
    refused(
        "--aaps",
        crate::components::validate::sanitize_aaps(&mut job.aaps.clone(), limits),
    )?;
    refused(
        "--volume",
        crate::components::validate::sanitize_volume(&mut job.volume.clone(), limits),
    )?;
    Ok(())
}
