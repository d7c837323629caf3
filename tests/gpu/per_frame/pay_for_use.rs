//! The `pay_for_use` tests that check what happened in a given frame (see `per_frame`).

use crate::{GPU, require_gpu, scene};
use bevy_caustics::CausticsTechnique;
use bevy_caustics::headless::{RenderJob, run};

use crate::pay_for_use::*;

/// 100 switches of the camera's technique, one per frame, through AAPS, the photon map, image
/// space and volumes, starting and ending on volumes (`glass_sphere`, 32²). Every technique's
/// count is non-zero while it runs; at the end each is exactly what it was before the switching,
/// and the techniques no camera uses hold nothing.
#[test]
fn switching_techniques_frees_their_memory() {
    use bevy::prelude::World;
    use bevy_caustics::{Caustics, CausticsTechnique as T};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    fn per_frame(world: &mut World, n: u32) {
        let cycle = [T::Aaps, T::PhotonMap, T::ImageSpace, T::Volume];
        let technique = if (SETTLE..SETTLE + SWITCHES).contains(&n) {
            cycle[((n - SETTLE) % 4) as usize]
        } else {
            T::Volume
        };
        for mut c in world.query::<&mut Caustics>().iter_mut(world) {
            if c.technique != technique {
                c.technique = technique;
            }
        }
    }
    let report = run(RenderJob {
        scene: scene("glass_sphere"),
        technique: CausticsTechnique::Volume,
        width: 32,
        height: 32,
        photons: Some(4096),
        frames: 2 * SETTLE + SWITCHES + SETTLE,
        per_frame: Some(per_frame),
        ..Default::default()
    })
    .expect("render");
    let frames = &report.frame_gpu_bytes;
    let start = &frames[SETTLE as usize - 1];
    let end = frames.last().expect("frames");
    let peak = |name: &str| frames.iter().map(|f| f[name]).max().unwrap_or(0);
    println!("start {start:?}");
    println!("end   {end:?}");
    println!(
        "peaks while switching: trace {}, aaps {}, photon_map {}, image_space {}, volume {}, \
         temporal {}",
        peak("trace"),
        peak("aaps"),
        peak("photon_map"),
        peak("image_space"),
        peak("volume"),
        peak("temporal")
    );
    for name in [
        "trace",
        "aaps",
        "photon_map",
        "image_space",
        "volume",
        "temporal",
    ] {
        assert!(
            peak(name) > 0,
            "{name} never held memory: the count misses it"
        );
    }
    assert!(
        start["volume"] > 0 && start["caustics_buffer"] > 0,
        "{start:?}"
    );
    // Volumes use no temporal stage: its histories exist only while another technique runs.
    for name in ["trace", "aaps", "photon_map", "image_space", "temporal"] {
        assert_eq!(start[name], 0, "{name} held before it was used: {start:?}");
    }
    assert_eq!(start, end, "100 switches changed the memory held");
    assert!(report.caustics.expect("caustics").all_finite());
}
