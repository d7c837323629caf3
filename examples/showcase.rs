//! The showcase: a glass ball focusing sunlight onto a floor, caustics by AAPS on the GPU.
//!
//! With a display it opens a window; without one (no `DISPLAY` / `WAYLAND_DISPLAY`) it renders
//! offscreen and writes `showcase.png`.
//!
//! `cargo run --release --example showcase`

use std::path::PathBuf;

use bevy_caustics::headless::{RenderJob, find_adapter, run};

fn main() {
    bevy_caustics::headless::quiet_headless_environment();
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/glass_sphere.gltf");
    let window =
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if let Err(e) = find_adapter() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    let job = RenderJob {
        scene,
        technique: bevy_caustics::CausticsTechnique::Aaps,
        width: 512,
        height: 512,
        photons: Some(1 << 18),
        // Offscreen: let the task buffer adapt for a few frames, then keep the last one.
        frames: if window { 100_000 } else { 12 },
        window,
        progress: true,
        ev100: Some(13.0),
        // The thesis's performance culling: splats over 0.05 sr (seen from their last
        // interaction) are dropped; on this scene that costs 0.5 % of the caustic's energy
        // and keeps lavapipe's fill rate in check at 512².
        aaps: bevy_caustics::AapsSettings {
            drop_large_splats: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let (w, h) = (job.width, job.height);
    match run(job) {
        Ok(report) if !window => {
            if let Err(e) = image::save_buffer(
                "showcase.png",
                &report.frame_rgba8,
                w,
                h,
                image::ColorType::Rgba8,
            ) {
                eprintln!("error: cannot write showcase.png: {e}");
                std::process::exit(2);
            }
            println!(
                "wrote showcase.png ({} photons, {} splats per frame on {}; GPU ms per pass {:?})",
                report.photons_traced, report.photons_in_view, report.adapter, report.pass_ms
            );
        }
        Ok(_) => {}
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
