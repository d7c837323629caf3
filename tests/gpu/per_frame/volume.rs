//! The `volume` tests that check what happened in a given frame (see `per_frame`).

use crate::{GPU, require_gpu, scene};
use bevy_caustics::headless::{RenderJob, run};
use bevy_caustics::{CausticsTechnique, CausticsVolume, scenes};
use glam::Vec3;

use crate::volume::*;

/// Section 3.5's differential updates: with a glass slab in slab 1 of 3 and a glass cube in
/// slab 3, nothing re-runs while nothing changes; moving the cube re-runs slab 3 and the
/// projectors only (the passes of every frame are counted); turning the light re-runs all.
#[test]
fn volume_differential_updates_count_passes() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_vol_{}", std::process::id()));
    let mut desc = scenes::glass_sphere();
    desc.name = "two_casters".into();
    desc.nodes.retain(|n| n.name != "ball");
    let g = desc.material("glass2", scenes::glass(1.5, 0.2), false);
    desc.add(
        "upper",
        scenes::geometry::cuboid(Vec3::new(1.0, 0.2, 1.0)),
        g,
        Vec3::new(0.0, 2.0, 0.0),
    );
    desc.add(
        "lower",
        scenes::geometry::cuboid(Vec3::splat(0.2)),
        g,
        Vec3::new(0.0, 1.0, 0.0),
    );
    scenes::gltf::write_gltf(&desc, &dir).unwrap();
    let report = run(RenderJob {
        scene: dir.join("two_casters.gltf"),
        technique: CausticsTechnique::Volume,
        width: 64,
        height: 64,
        frames: 10,
        per_frame: Some(move_lower_caster),
        volume: CausticsVolume {
            slabs: 3,
            photons: 10_000,
            ..Default::default()
        },
        ..Default::default()
    })
    .expect("render");
    let slab = |f: &Vec<String>, k: u32| f.iter().any(|p| p == &format!("caustics/volume/slab{k}"));
    let project = |f: &Vec<String>| f.iter().any(|p| p == "caustics/volume/project");
    for (n, f) in report.frame_passes.iter().enumerate() {
        println!("frame {n}: {f:?}");
    }
    let frames = &report.frame_passes;
    // Frames 1 to 3: the first full run is over and nothing changed.
    for f in &frames[1..4] {
        assert!(!project(f) && !(1..=3).any(|k| slab(f, k)), "{f:?}");
    }
    // After the caster moved (frame 4) and before the light turns (frame 7).
    let moved: Vec<_> = frames[4..7].iter().collect();
    assert!(moved.iter().any(|f| slab(f, 3) && project(f)), "{moved:?}");
    assert!(
        moved.iter().all(|f| !slab(f, 1) && !slab(f, 2)),
        "{moved:?}"
    );
    // The light turned: every slab again.
    let turned: Vec<_> = frames[7..].iter().collect();
    assert!(
        turned
            .iter()
            .any(|f| slab(f, 1) && slab(f, 2) && slab(f, 3)),
        "{turned:?}"
    );
    assert!(report.caustics.unwrap().all_finite());
}

/// Stereo (two cameras 6.4 cm apart, `CausticsStereo`): each volume propagates once per frame
/// for both eyes (its slab passes run at most once a frame) and each eye splats it into its
/// own caustics buffer (the splat pass runs twice a frame); the right eye's buffer has
/// caustics.
#[test]
fn volume_stereo_propagates_once() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let report = run(RenderJob {
        scene: scene("glass_sphere"),
        technique: CausticsTechnique::Volume,
        width: 64,
        height: 64,
        frames: 6,
        stereo: Some(0.064),
        volume: CausticsVolume {
            photons: 20_000,
            ..Default::default()
        },
        ..Default::default()
    })
    .expect("render");
    let count = |f: &Vec<String>, p: &str| f.iter().filter(|q| q.as_str() == p).count();
    let mut propagated = 0;
    for (n, f) in report.frame_passes.iter().enumerate() {
        assert!(count(f, "caustics/volume/slab1") <= 1, "frame {n}: {f:?}");
        assert!(count(f, "caustics/volume/project") <= 1, "frame {n}: {f:?}");
        // Both eyes splat every rendered frame (the first list holds the frames since the
        // cameras spawned: one composite per eye and frame).
        let splats = count(f, "caustics/volume/splat");
        assert_eq!(splats, count(f, "caustics/composite"), "frame {n}: {f:?}");
        if n > 0 {
            assert_eq!(splats, 2, "frame {n}: {f:?}");
        }
        propagated += count(f, "caustics/volume/slab1");
    }
    let img = report.caustics.expect("the right eye's caustics");
    println!(
        "stereo volume: slab passes in {propagated} of {} frames, right-eye energy {:.0}",
        report.frame_passes.len(),
        img.sum().x
    );
    assert!(img.all_finite() && img.sum().x > 0.0);
}
