//! The `aaps` tests that check what happened in a given frame (see `per_frame`).

use crate::{GPU, reference, require_gpu, scene};
use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, run};
use bevy_caustics::reference::compare;

/// Stereo (two cameras 6.4 cm apart, `CausticsStereo`): the photons are traced once per frame
/// (the left eye's task buffer, trace and update) and both eyes splat them (the splat pass runs
/// twice a frame); the right eye's caustics, drawn from the left eye's splats with its own
/// projection, carry the reference's energy within 5 % (the eyes are 1.5 px from the reference
/// camera at 128²).
#[test]
fn aaps_stereo_traces_once() {
    use bevy_caustics::render::aaps::passes::{SPLAT_PASS, TASK_PASS, TRACE_PASS};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let report = run(RenderJob {
        scene: scene("glass_sphere"),
        technique: CausticsTechnique::Aaps,
        width: 128,
        height: 128,
        photons: Some(1 << 18),
        frames: 12,
        stereo: Some(0.064),
        ..Default::default()
    })
    .expect("render");
    // One trace per rendered frame: the first list holds two (the frame the cameras spawned
    // in and the next), every other one. Tracing per eye would give about 26 here.
    let all: Vec<&String> = report.frame_passes.iter().flatten().collect();
    let count = |p: &str| all.iter().filter(|q| q.as_str() == p).count();
    let (tasks, traces, splats) = (count(TASK_PASS), count(TRACE_PASS), count(SPLAT_PASS));
    let frames = report.frame_passes.len();
    println!("stereo: {frames} frames, {tasks} task buffers, {traces} traces, {splats} splats");
    assert_eq!(
        traces,
        frames + 1,
        "{traces} traces in {frames} frames: {:?}",
        report.frame_passes
    );
    assert_eq!(tasks, traces, "{:?}", report.frame_passes);
    assert_eq!(splats, 2 * traces, "{:?}", report.frame_passes);
    let m = compare(
        report.caustics.as_ref().expect("right eye"),
        &reference("glass_sphere"),
        None,
    )
    .expect("same size");
    println!(
        "AAPS stereo, right eye from the left eye's splats: energy {:+.2} %, RMSE {:.1} lx, FLIP {:.4}",
        m.energy_error * 100.0,
        m.rmse,
        m.flip
    );
    assert!(
        m.energy_error.abs() < 0.05,
        "{:+.2} %",
        m.energy_error * 100.0
    );
}
