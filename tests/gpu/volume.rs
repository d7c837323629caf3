//! Caustics volumes on lavapipe: closed forms and energy, error against the CPU reference for
//! 1 to 3 slabs, differential updates counted pass by pass, frustum culling, stress.

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::compare;
use bevy_caustics::{CausticsTechnique, CausticsVolume, scenes};
use glam::Vec3;

use super::{GPU, closed_form_cases, closed_form_error, reference, require_gpu, scene};

fn volume(
    path: std::path::PathBuf,
    size: u32,
    frames: u32,
    settings: CausticsVolume,
) -> RenderReport {
    run(RenderJob {
        scene: path.clone(),
        technique: CausticsTechnique::Volume,
        width: size,
        height: size,
        frames,
        volume: settings,
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A volume fitted around `mirror_wall`'s mirror and one around `glass_slab`'s slab: mean
/// caustic irradiance over the interior of the lit region within 10 % of the closed form, and
/// no energy created (flux splatted <= flux entering the volume).
#[test]
fn volume_closed_forms_and_energy() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    for case in closed_form_cases() {
        let (desc, expect) = (&case.0, case.4);
        let report = volume(scene(&desc.name), 128, 4, CausticsVolume::default());
        let (mean, px, err) = closed_form_error(&case, report.caustics.as_ref().expect("caustics"));
        let c = report.volume.clone().expect("counters");
        println!(
            "{}: volume mean {mean:.1} lx over {px} px, closed form {expect:.1} lx, error {:+.2} %, {c:?}, {:?}",
            desc.name,
            err * 100.0,
            report.pass_ms
        );
        assert!(err.abs() < 0.10, "{}: {:+.2} %", desc.name, err * 100.0);
        assert!(
            c.entered_lm > 0.0 && c.splatted_lm <= c.entered_lm * (1.0 + 1e-5),
            "{c:?}"
        );
        assert_eq!(c.nan_guards, 0);
    }
    two_suns_are_counted_once();
}

/// `glass_slab` with its sun split into two suns of half the illuminance each: the CLI fits a
/// volume per light, each carrying its own light (`CausticsVolume::light`), so the floor gets
/// the one sun's closed form (each volume seeding every light counted both twice: +100 %).
fn two_suns_are_counted_once() {
    use bevy_caustics::scenes::LightKind;
    let case = &closed_form_cases()[1];
    let mut desc = case.0.clone();
    let sun = desc.lights[0].clone();
    let LightKind::Directional { lux } = sun.kind else {
        panic!("glass_slab's light is a sun")
    };
    let half = LightKind::Directional { lux: lux * 0.5 };
    desc.lights = vec![
        bevy_caustics::scenes::LightDesc {
            kind: half,
            ..sun.clone()
        },
        bevy_caustics::scenes::LightDesc {
            name: "sun 2".into(),
            kind: half,
            ..sun
        },
    ];
    let dir = std::env::temp_dir().join(format!("bevy_caustics_two_suns_{}", std::process::id()));
    bevy_caustics::scenes::gltf::write_gltf(&desc, &dir).unwrap();
    let report = volume(
        dir.join("glass_slab.gltf"),
        128,
        4,
        CausticsVolume::default(),
    );
    let _ = std::fs::remove_dir_all(&dir);
    let (mean, px, err) = closed_form_error(case, report.caustics.as_ref().expect("caustics"));
    println!(
        "glass_slab, two half suns: volume mean {mean:.1} lx over {px} px, closed form {:.1} lx, error {:+.2} %",
        case.4,
        err * 100.0
    );
    assert!(err.abs() < 0.10, "two suns: {:+.2} %", err * 100.0);
}

/// `glass_sphere` in a fitted volume with 1, 2 and 3 slabs: total caustic energy within 10 %
/// of the CPU reference; RMSE and FLIP printed for the note. With the default 3 slabs, FLIP
/// over the pixels the caustic lights (`flip_caustic`) at most 0.10 (issue 29 item 3; the
/// adaptive density tiles and splat overlap 16: 0.088, was 0.102 with the fixed grid of 4 and
/// overlap 4). The brilliant-cut gem in its closed room (IOR 2.4, spot) against its cached
/// reference: energy within 10 %, FLIP over the caustic at most 0.32 (0.304; 0.327 before;
/// its sparkles need far more than 80 000 photons: the 0.10 is not met there).
#[test]
fn volume_glass_sphere_against_reference() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let sphere = reference("glass_sphere");
    for slabs in [1, 2, 3] {
        let report = volume(
            scene("glass_sphere"),
            128,
            4,
            CausticsVolume {
                slabs,
                ..Default::default()
            },
        );
        let img = report.caustics.expect("caustics");
        assert!(img.all_finite());
        let m = compare(&img, &sphere, None).expect("same size");
        let c = report.volume.clone().expect("counters");
        println!(
            "glass_sphere, {slabs} slab(s): energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}, over the caustic {:.4}, {c:?}",
            m.energy_error * 100.0,
            m.rmse,
            m.flip,
            m.flip_caustic,
        );
        assert!(
            m.energy_error.abs() < 0.10,
            "{slabs} slabs: {}",
            m.energy_error
        );
        assert!(c.splatted_lm <= c.entered_lm * (1.0 + 1e-5), "{c:?}");
        if slabs == 3 {
            assert!(m.flip_caustic <= 0.10, "glass_sphere: {m:?}");
        }
    }
    let gem = scenes::closed::gem_room();
    let dir = std::env::temp_dir().join(format!("bevy_caustics_gem_{}", std::process::id()));
    scenes::gltf::write_gltf(&gem, &dir).unwrap();
    let report = volume(dir.join("gem_room.gltf"), 128, 4, CausticsVolume::default());
    let m = compare(
        &report.caustics.expect("caustics"),
        &reference("gem_room"),
        None,
    )
    .unwrap();
    println!(
        "gem_room: energy error {:+.2} %, RMSE {:.1} lx, FLIP {:.4}, over the caustic {:.4}",
        m.energy_error * 100.0,
        m.rmse,
        m.flip,
        m.flip_caustic,
    );
    assert!(m.energy_error.abs() < 0.10, "gem_room: {m:?}");
    assert!(m.flip_caustic <= 0.32, "gem_room: {m:?}");
}

pub(crate) fn move_lower_caster(world: &mut bevy::prelude::World, frame: u32) {
    use bevy::prelude::*;
    if frame == 4 {
        let mut q = world.query::<(&Name, &mut Transform)>();
        for (name, mut t) in q.iter_mut(world) {
            if name.as_str() == "lower" {
                t.translation.x += 0.05;
            }
        }
    }
    if frame == 7 {
        let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
        for mut t in q.iter_mut(world) {
            t.rotate_x(0.02);
        }
    }
}

fn look_up(world: &mut bevy::prelude::World) {
    use bevy::prelude::*;
    let mut q = world.query_filtered::<&mut Transform, With<bevy_caustics::Caustics>>();
    for mut t in q.iter_mut(world) {
        t.look_to(Vec3::Y, Vec3::Z);
    }
}

/// Section 3.5: with frustum culling on, a volume outside the camera's frustum dispatches
/// nothing (the camera looks at the sky above `glass_sphere`).
#[test]
fn volume_outside_frustum_dispatches_nothing() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let looking_up = |frustum_cull: bool| {
        run(RenderJob {
            scene: scene("glass_sphere"),
            technique: CausticsTechnique::Volume,
            width: 32,
            height: 32,
            frames: 4,
            hook: Some(look_up),
            volume: CausticsVolume {
                frustum_cull,
                ..Default::default()
            },
            ..Default::default()
        })
        .expect("render")
    };
    let report = looking_up(true);
    println!("passes {:?}", report.passes);
    assert!(report.passes.is_empty(), "{:?}", report.passes);
    // The same view with culling off runs the volume.
    let report = looking_up(false);
    assert!(
        report.passes.iter().any(|p| p == "caustics/volume/slab1"),
        "{:?}",
        report.passes
    );
}

fn spawn_volume(world: &mut bevy::prelude::World, v: CausticsVolume, at: Vec3) {
    world.spawn((v, bevy::prelude::Transform::from_translation(at)));
}

fn graze_entry(world: &mut bevy::prelude::World) {
    use bevy::prelude::*;
    // The sun travels almost exactly along the entry face (1e-4 rad into it).
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        *t = Transform::default().looking_to(Vec3::new(-1e-4, -1.0, 0.0), Vec3::X);
    }
    side_entry_volume(
        world,
        vec![
            bevy_caustics::VolumeFace::NegY,
            bevy_caustics::VolumeFace::NegX,
        ],
    );
}

fn parallel_entry(world: &mut bevy::prelude::World) {
    side_entry_volume(world, vec![bevy_caustics::VolumeFace::NegY]);
}

/// A 1.2 m volume around `glass_sphere`'s ball whose entry face is +X (the sun travels down).
fn side_entry_volume(world: &mut bevy::prelude::World, exit: Vec<bevy_caustics::VolumeFace>) {
    spawn_volume(
        world,
        CausticsVolume {
            size: Vec3::splat(1.2),
            entry: bevy_caustics::VolumeFace::PosX,
            exit,
            ..Default::default()
        },
        Vec3::new(0.0, 1.0, 0.0),
    );
}

fn slab_boundary(world: &mut bevy::prelude::World) {
    // glass_slab's glass spans y in [0.9, 1.1]; three slabs of 0.2 m from y = 1.3 put slab
    // boundaries exactly on its top and bottom faces.
    spawn_volume(
        world,
        CausticsVolume {
            size: Vec3::new(1.6, 0.6, 1.6),
            slabs: 3,
            exit: vec![bevy_caustics::VolumeFace::NegY],
            ..Default::default()
        },
        Vec3::new(0.0, 1.0, 0.0),
    );
}

fn empty_volume(world: &mut bevy::prelude::World) {
    spawn_volume(world, CausticsVolume::default(), Vec3::new(10.0, 5.0, 10.0));
}

/// Stress: photons exactly parallel to the entry face and 1e-4 rad off it, a caster whose
/// faces lie on slab boundaries, an empty volume, 1 and 16 slabs (IOR 4.0 and the other stiff
/// cases run through volumes in `stiff::stiff_cases_volume`): finite caustics, no NaN
/// guard fired, no energy created, no panic, no validation error (the runner fails on one).
#[test]
fn volume_stress_cases() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    type Hook = Option<fn(&mut bevy::prelude::World)>;
    let cases: [(&str, &str, Hook, u32); 6] = [
        (
            "parallel to the entry face",
            "glass_sphere",
            Some(parallel_entry),
            3,
        ),
        (
            "1e-4 rad off the entry face",
            "glass_sphere",
            Some(graze_entry),
            3,
        ),
        (
            "caster on slab boundaries",
            "glass_slab",
            Some(slab_boundary),
            3,
        ),
        ("empty volume", "glass_sphere", Some(empty_volume), 3),
        ("1 slab", "glass_sphere", None, 1),
        ("16 slabs", "glass_sphere", None, 16),
    ];
    for (what, name, hook, slabs) in cases {
        let report = run(RenderJob {
            scene: scene(name),
            technique: CausticsTechnique::Volume,
            width: 64,
            height: 64,
            frames: 4,
            hook,
            volume: CausticsVolume {
                slabs,
                photons: 20_000,
                ..Default::default()
            },
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{what}: {e}"));
        let img = report.caustics.expect("caustics");
        let total: f64 = img.data.iter().map(|p| p.x as f64).sum();
        println!("{what}: {:?}, image sum {total:.0}", report.volume);
        assert!(img.all_finite(), "{what}");
        let c = report.volume.as_ref().expect("volume counters");
        assert_eq!(c.nan_guards, 0, "{what}: {c:?}");
        assert!(
            c.splatted_lm <= c.entered_lm * (1.0 + 1e-5),
            "{what}: {c:?}"
        );
    }
}

/// The seed's Cornell-box scenes (`assets/scenes/cornell_*`) render with the volume their glTF
/// `extras` declare (its exit faces leave out the top: no `PosY` projector runs, where a fitted
/// volume would have one): light enters, caustics are finite, no energy is created.
#[test]
fn volume_cornell_scenes_use_their_gltf_volumes() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    for name in [
        "cornell_diamond",
        "cornell_ring",
        "cornell_ball",
        "cornell_blocks",
    ] {
        let report = volume(scene(name), 48, 4, CausticsVolume::default());
        let c = report.volume.clone().expect("counters");
        println!("{name}: {c:?}");
        assert!(report.caustics.unwrap().all_finite(), "{name}");
        assert!(
            report
                .passes
                .iter()
                .any(|p| p == "caustics/volume/projector3_gbuffer")
                && !report
                    .passes
                    .iter()
                    .any(|p| p == "caustics/volume/projector2_gbuffer"),
            "{name}: {:?}",
            report.passes
        );
        assert!(c.entered_lm > 0.0 && c.hits > 0, "{name}: {c:?}");
        assert!(
            c.splatted_lm <= c.entered_lm * (1.0 + 1e-5),
            "{name}: {c:?}"
        );
        assert_eq!(c.nan_guards, 0, "{name}");
    }
}
