//! Caustics volumes on lavapipe, continued: progressive mode (seed 000 section 3.5) against the
//! full update, and the volume gizmos' colours at the lines' projected positions.

use bevy_caustics::headless::{RenderJob, RenderReport, run};
use bevy_caustics::reference::compare;
use bevy_caustics::render::volume::gizmo::GIZMO_PASS;
use bevy_caustics::volume::{VolumeGizmoKind, volume_gizmo_segments};
use bevy_caustics::{CausticsTechnique, CausticsVolume, CausticsVolumeGizmos, scenes};
use glam::{Affine3A, Vec3};

use crate::{GPU, require_gpu, scene};

fn glass_sphere(
    frames: u32,
    settings: CausticsVolume,
    hook: Option<fn(&mut bevy::prelude::World)>,
) -> RenderReport {
    run(RenderJob {
        scene: scene("glass_sphere"),
        technique: CausticsTechnique::Volume,
        width: 128,
        height: 128,
        frames,
        volume: settings,
        hook,
        ..Default::default()
    })
    .expect("render")
}

/// The measured frames' pass lists, and how often `name` was dispatched in all of them (the
/// first list also holds the frames between the camera's spawning and the first measured one).
const SLAB1: &str = "caustics/volume/slab1";

fn dispatches(r: &RenderReport, name: &str) -> usize {
    r.frame_passes
        .iter()
        .flatten()
        .filter(|p| *p == name)
        .count()
}

/// Index of the last frame list holding `name`.
fn last_with(r: &RenderReport, name: &str) -> Option<usize> {
    r.frame_passes
        .iter()
        .rposition(|f| f.iter().any(|p| p == name))
}

/// Progressive mode: a pool of 20 000 photons in batches of 5 000 runs the slabs and the
/// projectors exactly four times and then nothing but the splats; the accumulated result is the full
/// update's (the same photons: the same receivers, hit for hit); a partial accumulation, scaled
/// by photons / traced, already estimates the full energy.
#[test]
fn volume_progressive_mode_converges_to_the_full_update() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let base = CausticsVolume {
        photons: 20_000,
        ..Default::default()
    };
    let full = glass_sphere(8, base.clone(), None);
    let prog = glass_sphere(
        10,
        CausticsVolume {
            progressive: 5_000,
            ..base.clone()
        },
        None,
    );
    let (fc, pc) = (full.volume.clone().unwrap(), prog.volume.clone().unwrap());
    for (n, f) in prog.frame_passes.iter().enumerate() {
        println!("progressive frame {n}: {f:?}");
    }
    assert_eq!(dispatches(&full, SLAB1), 1, "{:?}", full.frame_passes);
    // No gizmo component: no gizmo pass.
    assert_eq!(dispatches(&full, GIZMO_PASS), 0);
    // Four batches: every slab and the projectors four times, then only the splats.
    for pass in [SLAB1, "caustics/volume/slab3", "caustics/volume/project"] {
        assert_eq!(
            dispatches(&prog, pass),
            4,
            "{pass}: {:?}",
            prog.frame_passes
        );
    }
    let last = last_with(&prog, SLAB1).unwrap();
    assert!(
        last + 3 < prog.frame_passes.len(),
        "{:?}",
        prog.frame_passes
    );
    for f in &prog.frame_passes[last + 1..] {
        assert!(
            f.iter().all(|p| p.ends_with("/splat")
                || p.ends_with("/blur")
                || p.ends_with("/composite")),
            "{f:?}"
        );
    }
    let (fi, pi) = (full.caustics.unwrap(), prog.caustics.unwrap());
    assert!(pi.all_finite());
    let m = compare(&pi, &fi, None).expect("same size");
    println!(
        "progressive 4 x 5000 vs full 20000: energy {:+.4} %, RMSE {:.2} lx, FLIP {:.4}; hits {} vs {}, splatted {:.1} vs {:.1} lm",
        m.energy_error * 100.0,
        m.rmse,
        m.flip,
        pc.hits,
        fc.hits,
        pc.splatted_lm,
        fc.splatted_lm
    );
    assert_eq!(
        pc.hits, fc.hits,
        "the same photons reach the same receivers"
    );
    assert!((pc.splatted_lm / fc.splatted_lm - 1.0).abs() < 1e-4);
    assert!(m.energy_error.abs() < 1e-3, "{}", m.energy_error);
    assert_eq!(pc.nan_guards, 0);

    // 40 batches of 500: read back part-way (the job stops after 4 + a few frames).
    let part = glass_sphere(
        4,
        CausticsVolume {
            progressive: 500,
            ..base
        },
        None,
    );
    let c = part.volume.clone().unwrap();
    let img = part.caustics.unwrap();
    assert!(img.all_finite());
    let m = compare(&img, &fi, None).expect("same size");
    let traced = c.hits as f64 / fc.hits as f64;
    println!(
        "progressive 500/frame, part-way: {:.0} % of the hits, energy vs full {:+.2} %, RMSE {:.1} lx, FLIP {:.4}",
        traced * 100.0,
        m.energy_error * 100.0,
        m.rmse,
        m.flip
    );
    assert!(traced > 0.02 && traced < 0.9, "not part-way: {traced}");
    assert!(m.energy_error.abs() < 0.10, "{}", m.energy_error);
    assert!(c.splatted_lm <= c.entered_lm * (1.0 + 1e-5), "{c:?}");
}

/// The volume of the gizmo test: in view, entry +Y, exit -Y, the rest culling, 3 slabs.
fn gizmo_volume() -> CausticsVolume {
    CausticsVolume {
        size: Vec3::new(1.2, 1.0, 1.2),
        ..Default::default()
    }
}

/// Above the floor (y 0.3 to 1.3), and buried under it (y -1.3 to -0.3).
const ABOVE: Vec3 = Vec3::new(0.0, 0.8, 0.0);
const BURIED: Vec3 = Vec3::new(0.0, -0.8, 0.0);

/// Outlines inset by 20 % so neighbouring faces' lines lie several pixels apart at 128 x 128.
fn gizmo_settings(depth_test: bool) -> CausticsVolumeGizmos {
    CausticsVolumeGizmos {
        depth_test,
        inset: 0.2,
        ..Default::default()
    }
}

fn add_gizmos(world: &mut bevy::prelude::World, at: Vec3, depth_test: bool) {
    use bevy::prelude::*;
    world.spawn((gizmo_volume(), Transform::from_translation(at)));
    let cams: Vec<Entity> = world
        .query_filtered::<Entity, With<bevy_caustics::Caustics>>()
        .iter(world)
        .collect();
    for c in cams {
        world.entity_mut(c).insert(gizmo_settings(depth_test));
    }
}

fn gizmos_above_no_depth_test(world: &mut bevy::prelude::World) {
    add_gizmos(world, ABOVE, false);
}

fn gizmos_buried_depth_test(world: &mut bevy::prelude::World) {
    add_gizmos(world, BURIED, true);
}

fn gizmos_buried_no_depth_test(world: &mut bevy::prelude::World) {
    add_gizmos(world, BURIED, false);
}

/// Pixel of a world point in the scene's camera (Bevy: -Z forward, NDC y up, pixel y down).
fn pixel(cam: &bevy_caustics::scene::TraceCamera, p: Vec3) -> Option<glam::Vec2> {
    let v = cam.world_from_view.inverse().transform_point3(p);
    let bevy_caustics::scene::CameraProjection::Perspective { fov_y } = cam.projection else {
        return None;
    };
    if v.z >= -1e-3 {
        return None;
    }
    let t = (fov_y * 0.5).tan();
    let aspect = cam.width as f32 / cam.height as f32;
    let ndc = glam::Vec2::new(v.x / (-v.z * t * aspect), v.y / (-v.z * t));
    Some(glam::Vec2::new(
        (ndc.x * 0.5 + 0.5) * cam.width as f32,
        (0.5 - ndc.y * 0.5) * cam.height as f32,
    ))
}

fn segment_distance(p: glam::Vec2, a: glam::Vec2, b: glam::Vec2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Render the gizmos of the volume at `at`; per role, the lines whose projected midpoint is
/// checkable (in the image, away from other roles' lines) and those of them showing the role's
/// colour in the midpoint's 3 x 3 pixels (8-bit sRGB, +-2 per channel).
fn gizmo_midpoints(
    hook: fn(&mut bevy::prelude::World),
    at: Vec3,
    depth_test: bool,
) -> std::collections::HashMap<VolumeGizmoKind, (u32, u32)> {
    let report = glass_sphere(4, CausticsVolume::default(), Some(hook));
    // Once per frame, as the splats.
    let (g, splats) = (
        dispatches(&report, GIZMO_PASS),
        dispatches(&report, "caustics/volume/splat"),
    );
    assert!(
        g >= 3 && g.abs_diff(splats) <= 1,
        "{:?}",
        report.frame_passes
    );
    let settings = gizmo_settings(depth_test);
    let segs = volume_gizmo_segments(
        &Affine3A::from_translation(at),
        &gizmo_volume(),
        settings.inset,
        true,
    );
    let (_, _, cam) = scenes::glass_sphere().to_trace(128, 128);
    let projected: Vec<_> = segs
        .iter()
        .filter_map(|s| Some((pixel(&cam, s.a)?, pixel(&cam, s.b)?, s.kind)))
        .collect();
    let rgba = &report.frame_rgba8;
    assert_eq!(rgba.len(), 128 * 128 * 4);
    if let Some(out) = std::env::var_os("BEVY_CAUSTICS_TEST_PNG") {
        image::save_buffer(out, rgba, 128, 128, image::ColorType::Rgba8).expect("png");
    }
    let mut checked = std::collections::HashMap::<VolumeGizmoKind, (u32, u32)>::new();
    for &(a, b, kind) in &projected {
        let mid = (a + b) * 0.5;
        if a.distance(b) < 6.0 || mid.min_element() < 2.0 || mid.max_element() > 125.0 {
            continue;
        }
        if projected
            .iter()
            .any(|&(c, d, k)| k != kind && segment_distance(mid, c, d) < 3.0)
        {
            continue;
        }
        let c = settings.colour(kind).to_srgba();
        let want = [c.red, c.green, c.blue].map(|v| (v * 255.0).round() as i32);
        let mut found = false;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y) = (mid.x as i32 + dx, mid.y as i32 + dy);
                let i = ((y * 128 + x) * 4) as usize;
                if (0..3).all(|c| (rgba[i + c] as i32 - want[c]).abs() <= 2) {
                    found = true;
                }
            }
        }
        let e = checked.entry(kind).or_default();
        e.0 += 1;
        e.1 += found as u32;
    }
    checked
}

const ROLES: [VolumeGizmoKind; 4] = [
    VolumeGizmoKind::Entry,
    VolumeGizmoKind::Exit,
    VolumeGizmoKind::Culling,
    VolumeGizmoKind::SlabPlane,
];

/// Gizmos: each line's projected midpoint shows the colour of its role (entry, exit,
/// culling, slab plane) exactly, after tone mapping; a volume buried under the floor shows its
/// lines through it without the depth test and none of them with it. The gizmo pass runs in every frame with the component
/// (and in none without it: the progressive test), as often as the splats.
#[test]
fn volume_gizmos_draw_each_role_in_its_colour() {
    let _g = GPU.slot();
    if !require_gpu() {
        return;
    }
    let seen = gizmo_midpoints(gizmos_above_no_depth_test, ABOVE, false);
    println!("gizmo midpoints checked / matching, per role, depth test off: {seen:?}");
    for kind in ROLES {
        let (n, ok) = seen.get(&kind).copied().unwrap_or_default();
        assert!(n >= 2, "{kind:?}: only {n} lines checkable");
        assert_eq!(ok, n, "{kind:?}: {ok} of {n} midpoints show the colour");
    }
    // Under the floor: every checkable line shows through without the depth test, none with it.
    let through = gizmo_midpoints(gizmos_buried_no_depth_test, BURIED, false);
    let buried = gizmo_midpoints(gizmos_buried_depth_test, BURIED, true);
    println!("gizmo midpoints under the floor, depth test off: {through:?}, on: {buried:?}");
    let sum = |m: &std::collections::HashMap<VolumeGizmoKind, (u32, u32)>| {
        m.values().fold((0, 0), |a, v| (a.0 + v.0, a.1 + v.1))
    };
    let (n_off, ok_off) = sum(&through);
    let (n_on, ok_on) = sum(&buried);
    assert!(n_off >= 5 && ok_off == n_off, "{through:?}");
    assert!(n_on == n_off && ok_on == 0, "{buried:?}");
}
