//! The `motion` tests that check what happened in a given frame (see `per_frame`).

use crate::{GPU, require_gpu};
use bevy::prelude::*;

use crate::motion::*;

/// Bevy's TAA on the camera (issue 28, item 4): AAPS on `glass_sphere` (128², 2^16 photons)
/// with the cube circling, so the caustics are traced every frame, with and without
/// `TemporalAntiAliasing`. Over the pixels the caustic lights (irradiance above a tenth of its
/// brightest), in the last 8 frames shown:
/// - the caustic is not clamped away: its added luminance (the frame less the same view with
///   the composite hidden) with TAA is within 10 % of that without;
/// - it does not flicker: the frame-to-frame change `Σ|ΔY| / ΣY` with TAA is at most 0.01,
///   and no more than without TAA.
#[test]
fn taa_keeps_the_caustic_and_does_not_flicker() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let (plain, caustics) = shown_frames(read_every_frame);
    let (taa, _) = shown_frames(with_taa);
    let (base, _) = shown_frames(hidden);
    let lum: Vec<f64> = caustics
        .data
        .iter()
        .map(|c| bevy_caustics::optics::luminance(*c) as f64)
        .collect();
    let max = lum.iter().cloned().fold(0.0, f64::max);
    let region: Vec<usize> = (0..lum.len()).filter(|&i| lum[i] > 0.1 * max).collect();
    assert!(region.len() >= 20, "{} caustic pixels", region.len());
    let sum = |f: &Vec<f64>| region.iter().map(|&i| f[i]).sum::<f64>();
    let mean = |fs: &[Vec<f64>]| fs.iter().map(sum).sum::<f64>() / fs.len() as f64;
    let flicker = |fs: &[Vec<f64>]| {
        fs.windows(2)
            .map(|w| {
                region
                    .iter()
                    .map(|&i| (w[1][i] - w[0][i]).abs())
                    .sum::<f64>()
                    / sum(&w[1])
            })
            .sum::<f64>()
            / (fs.len() - 1) as f64
    };
    let added = [mean(&plain) - mean(&base), mean(&taa) - mean(&base)];
    let change = [flicker(&plain), flicker(&taa)];
    println!(
        "TAA: {} caustic pixels; added luminance without TAA {:.3}, with {:.3} ({:.3}x); \
         flicker without {:.4}, with {:.4}, hidden {:.4}",
        region.len(),
        added[0],
        added[1],
        added[1] / added[0],
        change[0],
        change[1],
        flicker(&base)
    );
    assert!(added[0] > 0.0, "no caustic on screen: {added:?}");
    assert!((added[1] / added[0] - 1.0).abs() <= 0.1, "{added:?}");
    assert!(change[1] <= 0.01 && change[1] <= change[0], "{change:?}");
}
