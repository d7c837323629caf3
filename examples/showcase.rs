//! The showcase: a glass ball focusing sunlight onto a floor, with reference caustics.
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
        width: 512,
        height: 512,
        photons: Some(1 << 20),
        frames: if window { 100_000 } else { 8 },
        window,
        progress: true,
        ev100: Some(13.0),
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
                "wrote showcase.png ({} photons traced in {:.2} s on {}; composite {:?} ms)",
                report.photons_traced, report.reference_seconds, report.adapter, report.pass_ms
            );
        }
        Ok(_) => {}
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
