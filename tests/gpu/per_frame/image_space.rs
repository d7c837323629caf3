//! The `image_space` tests that check what happened in a given frame (see `per_frame`).

use crate::{GPU, reference, require_gpu, scene};
use bevy::prelude::*;
use bevy_caustics::ImageSpaceSettings;
use bevy_caustics::headless::RenderJob;
use bevy_caustics::headless::motion::frame_change;
use bevy_caustics::reference::{CausticImage, compare};

use crate::image_space::*;

/// Denoising pays and does not smear, on `glass_sphere` (a still camera):
/// - the mean frame-to-frame relative change of the caustics buffer over the last 8 frames is
///   at least 4x lower with SVGF than without (`settle_frames` 0: every frame is traced, so
///   the frames differ by what each technique's noise and filter leave, not by nothing);
/// - the RMSE against the reference at frame 16 is lower with SVGF than without;
/// - after the sun moves back to its place (frame 12, from 8 degrees away), the RMSE against
///   the reference falls below 1.5x the settled RMSE within the 8 following frames.
#[test]
fn image_space_denoising_pays_and_does_not_smear() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let reference = reference("glass_sphere");
    let runs: Vec<Vec<CausticImage>> = [true, false]
        .map(|denoise| {
            image_space(RenderJob {
                scene: scene("glass_sphere"),
                frames: 24,
                every_frame: true,
                settle_frames: 0,
                image_space: settings(denoise),
                ..Default::default()
            })
            .frame_caustics
        })
        .into();
    let mut change = [0.0f64; 2];
    let mut rmse16 = [0.0f64; 2];
    for (k, frames) in runs.iter().enumerate() {
        assert!(frames.len() >= 20, "{} frames read back", frames.len());
        let n = frames.len();
        change[k] = (n - 8..n)
            .map(|i| frame_change(&frames[i], &frames[i - 1]))
            .sum::<f64>()
            / 8.0;
        rmse16[k] = compare(&frames[15], &reference, None).unwrap().rmse;
    }
    // What a view that settles at the default `settle_frames` (16) keeps.
    let settled = rmse16[0];
    println!(
        "frame-to-frame change: SVGF {:.4}, raw {:.4} ({:.1}x less); RMSE at frame 16: SVGF {:.1} lx, raw {:.1} lx; settled {settled:.1} lx",
        change[0],
        change[1],
        change[1] / change[0],
        rmse16[0],
        rmse16[1]
    );
    assert!(change[1] > 0.0, "the raw frames are identical: {change:?}");
    assert!(change[0] * 4.0 <= change[1], "{change:?}");
    assert!(rmse16[0] < rmse16[1], "{rmse16:?}");

    let moved = image_space(RenderJob {
        scene: scene("glass_sphere"),
        frames: 21,
        every_frame: true,
        per_frame: Some(tilt_sun),
        image_space: settings(true),
        ..Default::default()
    })
    .frame_caustics;
    assert!(moved.len() >= 21, "{} frames read back", moved.len());
    let after: Vec<f64> = (13..21)
        .map(|i| compare(&moved[i], &reference, None).unwrap().rmse)
        .collect();
    let before = compare(&moved[11], &reference, None).unwrap().rmse;
    println!(
        "sun moved back at frame 12: RMSE before {before:.1} lx, frames 13..20 {after:.1?}, settled {settled:.1} lx"
    );
    // The move shows (a frame right after it is far from the reference; the readback may
    // trail the main world by a frame) and passes within the 8 frames.
    let shown = after[..3].iter().position(|&e| e > 1.5 * settled);
    assert!(shown.is_some(), "{after:?} vs settled {settled}");
    assert!(
        after[shown.unwrap()..].iter().any(|&e| e < 1.5 * settled),
        "{after:?} vs settled {settled}"
    );
    // What the reset buys: the same move with the history kept.
    let kept = image_space(RenderJob {
        scene: scene("glass_sphere"),
        frames: 21,
        every_frame: true,
        per_frame: Some(tilt_sun),
        image_space: ImageSpaceSettings {
            reset_on_change: false,
            ..settings(true)
        },
        ..Default::default()
    })
    .frame_caustics;
    let kept: Vec<f64> = (13..21.min(kept.len()))
        .map(|i| compare(&kept[i], &reference, None).unwrap().rmse)
        .collect();
    println!("without the reset: frames 13..20 {kept:.1?}");
}
