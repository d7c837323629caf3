//! Which changes can change a caustic (`scene::change`, issue 28 item 3): light tolerances
//! at tiny angles, and the caustic light's reach on `glass_sphere` (ball of radius 0.5 at
//! (0, 1, 0), sun straight down, caustic around the origin on the floor).

use std::time::Instant;

use bevy_caustics::scene::TraceLight;
use bevy_caustics::scene::change::{
    self, CausticReach, LIGHT_MOVE_TOLERANCE, LIGHT_TURN_TOLERANCE, REACH_SHARE,
};
use bevy_caustics::scenes;
use glam::{Quat, Vec3};

fn sun(direction: Vec3, lux: f32) -> TraceLight {
    TraceLight::Directional {
        direction,
        illuminance: Vec3::splat(lux),
    }
}

#[test]
fn angles_are_exact_where_acos_rounds_to_zero() {
    let d = Vec3::NEG_Y;
    for angle in [1e-7f32, 1e-5, 1e-4, 0.1, 3.0] {
        let t = Quat::from_rotation_x(angle) * d;
        let got = change::angle_between(d, t);
        assert!((got / angle - 1.0).abs() < 1e-3, "{angle}: {got}");
    }
    assert_eq!(change::angle_between(d, d), 0.0);
    // Degenerate input counts as turned.
    assert_eq!(change::angle_between(Vec3::ZERO, d), core::f32::consts::PI);
    assert_eq!(
        change::angle_between(Vec3::splat(f32::NAN), d),
        core::f32::consts::PI
    );
}

#[test]
fn lights_drift_only_past_their_tolerances() {
    let d = Vec3::NEG_Y;
    let base = sun(d, 1e5);
    let turn = |a: f32| sun(Quat::from_rotation_x(a) * d, 1e5);
    assert!(!change::light_drifted(&base, &turn(1e-5), 10.0));
    assert!(!change::light_drifted(
        &base,
        &turn(0.5 * LIGHT_TURN_TOLERANCE),
        10.0
    ));
    assert!(change::light_drifted(
        &base,
        &turn(2.0 * LIGHT_TURN_TOLERANCE),
        10.0
    ));
    assert!(!change::light_drifted(&base, &sun(d, 1e5 * 1.0005), 10.0));
    assert!(change::light_drifted(&base, &sun(d, 1e5 * 1.01), 10.0));
    assert!(change::light_drifted(&base, &sun(d, f32::NAN), 10.0));
    // Off, on: a change; off, off: none.
    assert!(change::light_drifted(&sun(d, 0.0), &sun(d, 1.0), 10.0));
    assert!(!change::light_drifted(&sun(d, 0.0), &sun(d, 0.0), 10.0));
    let point = |x: f32| TraceLight::Point {
        position: Vec3::new(x, 2.0, 0.0),
        flux: Vec3::splat(800.0),
    };
    let extent = 10.0;
    assert!(!change::light_drifted(
        &point(0.0),
        &point(0.5 * LIGHT_MOVE_TOLERANCE * extent),
        extent
    ));
    assert!(change::light_drifted(
        &point(0.0),
        &point(2.0 * LIGHT_MOVE_TOLERANCE * extent),
        extent
    ));
    assert!(change::light_drifted(&point(0.0), &base, extent));
    // By key: added, removed, drifted.
    let a = [(1u32, base)];
    assert!(!change::lights_drifted(&a, &[(1, turn(1e-5))], extent));
    assert!(change::lights_drifted(&a, &[(2, base)], extent));
    assert!(change::lights_drifted(&a, &[], extent));
    assert!(change::lights_drifted(&a, &[(1, base), (2, base)], extent));
}

fn cube_at(c: Vec3, half: f32) -> (Vec3, Vec3) {
    (c - Vec3::splat(half), c + Vec3::splat(half))
}

#[test]
fn reach_holds_the_caustic_paths_and_nothing_else() {
    let desc = scenes::glass_sphere();
    let (tlas, lights, _) = desc.to_trace(16, 16);
    let keyed: Vec<(u32, TraceLight)> = lights.into_iter().map(|l| (0, l)).collect();
    let t = Instant::now();
    let reach = CausticReach::trace(&tlas, &keyed);
    println!(
        "reach: {} segments in {:.2} ms",
        reach.segment_count(),
        t.elapsed().as_secs_f64() * 1e3
    );
    // The motion test's circling cube (0.3 m, 2.5 m around (0, 0, -0.5)), every position.
    let mut worst = 0.0f32;
    for frame in 0..126 {
        let a = 0.05 * frame as f32;
        let c = Vec3::new(2.5 * a.cos(), 0.15, 2.5 * a.sin() - 0.5);
        worst = worst.max(reach.share_through(cube_at(c, 0.15)));
    }
    println!("circling cube: at most {worst:.4} of the caustic flux");
    assert!(worst < REACH_SHARE, "{worst}");
    // The focus under the ball and a box between the sun and the ball are in reach.
    let focus = reach.share_through(cube_at(Vec3::new(0.0, 0.1, 0.0), 0.2));
    let above = reach.share_through((Vec3::new(-0.2, 2.0, -0.2), Vec3::new(0.2, 2.4, 0.2)));
    let floor = reach.share_through((Vec3::new(-20.0, -0.01, -20.0), Vec3::new(20.0, 0.01, 20.0)));
    println!("focus {focus:.3}, above the ball {above:.3}, floor {floor:.3}");
    assert!(focus > 0.1, "{focus}");
    assert!(above > 0.03, "{above}");
    assert!(floor > 0.8, "{floor}");
    // Far away, or on the sun's side but off the ball's shadow: out of reach.
    assert_eq!(
        reach.share_through(cube_at(Vec3::new(0.0, 30.0, 30.0), 0.5)),
        0.0
    );
    // Degenerate inputs: no lights, no casters, an inverted box.
    let empty = CausticReach::trace::<u32>(&tlas, &[]);
    assert_eq!(empty.share_through(cube_at(Vec3::ZERO, 1.0)), 0.0);
    let (floor_only, lights, _) = scenes::empty().to_trace(16, 16);
    let keyed: Vec<(u32, TraceLight)> = lights.into_iter().map(|l| (0, l)).collect();
    let none = CausticReach::trace(&floor_only, &keyed);
    assert_eq!(none.segment_count(), 0);
    assert_eq!(reach.share_through((Vec3::ONE, -Vec3::ONE)), 0.0);
}

#[test]
fn instance_changes_tell_casters_from_receivers() {
    let desc = scenes::glass_sphere();
    let (a, _, _) = desc.to_trace(16, 16);
    let (b, _, _) = desc.to_trace(16, 16);
    // Rebuilt from the same description: new BLAS, so every instance reads as changed; the
    // ball is a caster, the floor a receiver.
    let all = change::changed_instances(&a, &b);
    assert!(all.casters);
    assert_eq!(all.receivers.len(), 2);
    let same = change::changed_instances(&a, &a);
    assert_eq!(same, change::InstanceChanges::default());
    let none = change::changed_instances(&a, &bevy_caustics::scene::Tlas::default());
    assert!(none.casters && none.receivers.len() == 1);
}
