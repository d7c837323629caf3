//! The image-space technique on lavapipe: closed forms, energy against the CPU reference, the
//! denoiser's worth (less flicker, lower error), no smearing after a light moves, and nothing
//! dispatched without work. 128² targets, 65 536 photons per light, 256² RSMs.

use bevy::prelude::*;
use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::compare;
use bevy_caustics::{CausticsTechnique, ImageSpaceSettings};

use super::{
    GPU, closed_form_cases, closed_form_error, reference, require_gpu, scene, spot_away_scene,
};

/// Frames before the caustics buffer is read (the denoiser's history saturates at 1 / α = 5
/// frames; 16 give it three time constants).
const FRAMES: u32 = 16;
/// Photons per light and frame.
const PHOTONS: u64 = 1 << 16;

pub(crate) fn settings(denoise: bool) -> ImageSpaceSettings {
    ImageSpaceSettings {
        rsm_resolution: 256,
        denoise,
        ..Default::default()
    }
}

pub(crate) fn image_space(job: RenderJob) -> RenderReport {
    let name = job.scene.display().to_string();
    run(RenderJob {
        technique: CausticsTechnique::ImageSpace,
        width: 128,
        height: 128,
        photons: Some(PHOTONS),
        ..job
    })
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Mean caustic irradiance over the interior of the lit region of `mirror_wall` and
/// `glass_slab` within 10 % of the closed form after 16 frames.
#[test]
fn image_space_closed_forms() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    for case in closed_form_cases() {
        let (desc, expect) = (&case.0, case.4);
        let report = image_space(RenderJob {
            scene: scene(&desc.name),
            frames: FRAMES,
            image_space: settings(true),
            ..Default::default()
        });
        let (mean, px, err) = closed_form_error(&case, report.caustics.as_ref().expect("caustics"));
        println!(
            "{}: image-space mean {mean:.1} lx over {px} px after {FRAMES} frames, closed form {expect:.1} lx, error {:+.2} %, {:?}, passes {:?}",
            desc.name,
            err * 100.0,
            report.image_space,
            report.pass_ms
        );
        assert!(err.abs() < 0.10, "{}: {:+.2} %", desc.name, err * 100.0);
    }
}

/// Total caustic energy of `glass_sphere` (two refractions through the caster-back layer),
/// `ring` (a point light inside a mirror ring: six cube-face RSMs) and `pool` (camera under
/// water) within 10 % of the CPU reference; RMSE and FLIP printed for the note. `ring` at the
/// default 1024² maps and 2^18 photons within 5 % (issue 29): a tenth of its caustic takes two
/// mirror reflections, the second often in another cube face (`mirror_chain` in trace.wgsl).
#[test]
fn image_space_energy_matches_reference() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    for name in ["glass_sphere", "ring", "pool"] {
        let report = image_space(RenderJob {
            scene: scene(name),
            frames: FRAMES,
            image_space: settings(true),
            ..Default::default()
        });
        let img = report.caustics.expect("caustics");
        let m = compare(&img, &reference(name), None).expect("same size");
        println!(
            "{name}: energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}, {:?}, passes {:?}",
            m.energy_error * 100.0,
            m.rmse,
            m.flip,
            report.image_space,
            report.pass_ms
        );
        assert!(
            m.energy_error.abs() < 0.10,
            "{name}: {:+.2} %",
            m.energy_error * 100.0
        );
    }
    let report = run(RenderJob {
        scene: scene("ring"),
        technique: CausticsTechnique::ImageSpace,
        width: 128,
        height: 128,
        frames: FRAMES,
        photons: Some(1 << 18),
        ..Default::default()
    })
    .expect("ring");
    let img = report.caustics.expect("caustics");
    let m = compare(&img, &reference("ring"), None).expect("same size");
    let counters = report.image_space.expect("counters");
    println!(
        "ring, 1024² maps, 2^18 photons: energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}, {} further mirror reflections",
        m.energy_error * 100.0,
        m.rmse,
        m.flip,
        counters.mirror_chain
    );
    assert!(counters.mirror_chain > 0, "{counters:?}");
    assert!(m.energy_error.abs() < 0.05, "ring: {m:?}");
}

/// The Hi-Z march finds the same caustics as the linear march: `mirror_wall` within 10 % of
/// its closed form, `glass_sphere` and `ring` within 10 % of the reference's energy; the trace
/// pass's median GPU time with each is printed for the note.
#[test]
fn image_space_hi_z_matches_linear() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let [mirror, _] = closed_form_cases();
    for name in ["mirror_wall", "glass_sphere", "ring"] {
        let mut ms = [0.0; 2];
        for (k, hi_z) in [false, true].into_iter().enumerate() {
            let report = image_space(RenderJob {
                scene: scene(name),
                frames: FRAMES,
                image_space: ImageSpaceSettings {
                    hi_z,
                    ..settings(true)
                },
                ..Default::default()
            });
            let trace = report.pass_ms["caustics/image_space/trace"];
            let hiz = report.pass_ms.get("caustics/image_space/hiz").copied();
            ms[k] = trace + hiz.unwrap_or(0.0);
            let img = report.caustics.expect("caustics");
            if hi_z {
                assert!(hiz.is_some(), "{name}: no Hi-Z pass timed");
                if name == "mirror_wall" {
                    let (_, _, err) = closed_form_error(&mirror, &img);
                    println!("{name} (Hi-Z): closed-form error {:+.2} %", err * 100.0);
                    assert!(err.abs() < 0.10, "{name}: {:+.2} %", err * 100.0);
                } else {
                    let m = compare(&img, &reference(name), None).expect("same size");
                    println!(
                        "{name} (Hi-Z): energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}",
                        m.energy_error * 100.0,
                        m.rmse,
                        m.flip
                    );
                    assert!(m.energy_error.abs() < 0.10, "{name}: {m:?}");
                }
            }
        }
        println!(
            "{name}: trace (+ pyramids) {:.2} ms linear, {:.2} ms Hi-Z: {:.2}x",
            ms[0],
            ms[1],
            ms[0] / ms[1]
        );
    }
}

/// Tilt the sun 8 degrees away at the first measured frame and back at frame 12.
pub(crate) fn tilt_sun(world: &mut World, frame: u32) {
    let angle = match frame {
        0 => 8f32.to_radians(),
        12 => -8f32.to_radians(),
        _ => return,
    };
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        // About its own x axis: a light shines along its local -z.
        t.rotate_local_x(angle);
    }
}

/// No pass without work: an empty scene, a spot light aimed away from every caster, zero
/// photons.
#[test]
fn image_space_dispatches_nothing_without_work() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_is_{}", std::process::id()));
    for (path, photons) in [
        (scene("empty"), PHOTONS),
        (spot_away_scene(&dir), PHOTONS),
        (scene("glass_sphere"), 0),
    ] {
        let report = run(RenderJob {
            scene: path.clone(),
            technique: CausticsTechnique::ImageSpace,
            width: 32,
            height: 32,
            photons: Some(photons),
            frames: 4,
            image_space: settings(true),
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            report.passes.is_empty(),
            "{}: {:?}",
            path.display(),
            report.passes
        );
    }
}

/// Light that reflects inside glass (issue 29 item 2), at the default 1024² maps, the raw
/// photon map of the fourth frame:
/// - the brilliant in the closed gem room (IOR 2.4: most light entering the crown is totally
///   reflected by the pavilion, many paths take dozens of reflections): the caustic energy in
///   view within 10 % of the CPU reference's, which holds the room's closed form to 1 %
///   (tests/cpu/energy.rs); the photons left inside under 20 % of those traced, and no loss
///   warning;
/// - the absorbing slab: the floor's mean irradiance under the slab within 10 % of the
///   Beer-Lambert closed form with every even number of internal reflections;
/// - with `internal_events` 0 (the seed's one interface plus the exit) the gem loses most of
///   its light, and the plugin says so once, naming the techniques that follow it.
#[test]
fn image_space_follows_light_inside_glass() {
    use bevy_caustics::reference::{TraceSettings, plane_region_mean, trace};
    use bevy_caustics::scenes::{self, closed};
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bevy_caustics_inside_{}", std::process::id()));
    let run_inside = |desc: &scenes::SceneDesc, internal_events: u32, rsm_resolution: u32| {
        scenes::gltf::write_gltf(desc, &dir).unwrap();
        image_space(RenderJob {
            scene: dir.join(format!("{}.gltf", desc.name)),
            frames: 4,
            // The trace's own light: SVGF is held to its energy by the other tests.
            image_space: ImageSpaceSettings {
                internal_events,
                rsm_resolution,
                denoise: false,
                ..Default::default()
            },
            ..Default::default()
        })
    };
    let events = ImageSpaceSettings::default().internal_events;

    let gem = closed::gem_room();
    let (tlas, lights, cam) = gem.to_trace(128, 128);
    let settings = TraceSettings {
        photons_per_light: 1 << 20,
        ..Default::default()
    };
    let reference = trace(&tlas, &lights, &cam, &settings, None).image;
    let report = run_inside(&gem, events, 1024);
    let c = report.image_space.clone().expect("counters");
    let m = compare(report.caustics.as_ref().unwrap(), &reference, None).unwrap();
    let trapped = c.trapped as f64 / c.photons_emitted.max(1) as f64;
    println!(
        "gem_room: energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}; {} internal reflections, {:.1} % of photons left inside; trace {:.1} ms; loss warnings {:?}",
        m.energy_error * 100.0,
        m.rmse,
        m.flip,
        c.tir,
        trapped * 100.0,
        report.pass_ms["caustics/image_space/trace"],
        report.loss_warnings
    );
    assert!(m.energy_error.abs() < 0.10, "gem_room: {m:?}");
    assert!(trapped < 0.2 && c.nan_guards == 0, "{c:?}");
    assert!(
        report.loss_warnings.is_empty(),
        "{:?}",
        report.loss_warnings
    );

    let slab = closed::absorbing_slab();
    let report = run_inside(&slab, events, 1024);
    let img = report.caustics.as_ref().unwrap();
    let (_, _, cam) = slab.to_trace(128, 128);
    let under = |p: glam::Vec3| p.x.abs() < 0.4 && p.z.abs() < 0.4;
    let (mean, px) = plane_region_mean(img, &cam, glam::Vec3::Y, 0.0, under);
    let expect = bevy_caustics::optics::luminance(closed::absorbing_slab_power());
    let err = mean / expect - 1.0;
    println!(
        "absorbing_slab: floor under the slab {mean:.1} lx over {px} px, closed form {expect:.1} lx, error {:+.2} %",
        err * 100.0
    );
    assert!(
        px > 200 && err.abs() < 0.10,
        "absorbing_slab: {err} over {px} px"
    );

    let report = run_inside(&gem, 0, 256);
    let c = report.image_space.clone().expect("counters");
    let m = compare(report.caustics.as_ref().unwrap(), &reference, None).unwrap();
    println!(
        "gem_room, internal_events 0: energy error {:+.2} %, {} of {} photons left inside; loss warnings {:?}",
        m.energy_error * 100.0,
        c.trapped,
        c.photons_emitted,
        report.loss_warnings
    );
    assert!(c.trapped * 5 > c.photons_emitted, "{c:?}");
    let named = report
        .loss_warnings
        .iter()
        .filter(|w| w.contains("PhotonMap"));
    assert_eq!(named.count(), 1, "{:?}", report.loss_warnings);
}
