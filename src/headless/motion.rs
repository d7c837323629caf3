//! Scenes that move, for the motion tests and the report's moving scene (issue 28): movers to
//! pass as [`super::RenderJob::per_frame`], and the two measures of a run read back at every
//! frame (`every_frame`): the RMSE against a reference per frame, and the flicker.
//!
//! Indices are those of [`super::RenderReport::frame_caustics`]: index `i >= 2` shows the state
//! after `per_frame(i - 2)` (`motion::readback_shows_the_frame_it_was_asked_in` pins this).

use std::ops::Range;

use bevy::prelude::*;

use crate::optics::luminance;
use crate::reference::{CausticImage, compare};

/// The frames measured: indices 16 to 23 of `frame_caustics` (frames 17 to 24, past the default
/// `settle_frames`, 16).
pub const MEASURED: Range<usize> = 16..24;

/// How far [`slide_ball`] moves the ball each frame, metres.
pub const SLIDE_STEP: f32 = 0.01;

/// The slide steps of the ball in the state `frame_caustics[index]` shows under [`slide_ball`].
pub fn slide_steps(index: usize) -> u32 {
    index.saturating_sub(2) as u32
}

/// The offset of the ball (metres along +x) in the state `frame_caustics[index]` shows under
/// [`slide_ball`].
pub fn slide_offset(index: usize) -> f32 {
    SLIDE_STEP * slide_steps(index) as f32
}

/// Marks the cube of [`circle_cube`].
#[derive(Component)]
pub struct Circling;

/// A 0.3 m grey diffuse cube at `at`, tagged with `marker`.
pub fn spawn_cube(world: &mut World, marker: impl Component, at: Vec3) {
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(0.3, 0.3, 0.3));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial::from_color(Color::srgb(0.7, 0.7, 0.7)));
    world.spawn((
        marker,
        Mesh3d(mesh),
        MeshMaterial3d(material),
        Transform::from_translation(at),
    ));
}

/// Unrelated motion: a 0.3 m diffuse cube on the floor of `glass_sphere`, circling the ball's
/// caustic 2.5 m away, 0.05 rad a frame (no caster, outside every path of caustic light).
pub fn circle_cube(world: &mut World, frame: u32) {
    let angle = 0.05 * frame as f32;
    let at = Vec3::new(2.5 * angle.cos(), 0.15, 2.5 * angle.sin() - 0.5);
    if frame == 0 {
        spawn_cube(world, Circling, at);
        return;
    }
    let mut q = world.query_filtered::<&mut Transform, With<Circling>>();
    for mut t in q.iter_mut(world) {
        t.translation = at;
    }
}

/// Unrelated motion: the sun turning 1e-5 rad about its own x axis and back, every frame.
pub fn jitter_sun(world: &mut World, frame: u32) {
    let angle = if frame.is_multiple_of(2) { 1e-5 } else { -1e-5 };
    let mut q = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
    for mut t in q.iter_mut(world) {
        t.rotate_local_x(angle);
    }
}

/// Moves every entity named `ball` (the caster of `glass_sphere`) by `dx` metres along +x.
/// Returns how many it moved.
pub fn move_ball(world: &mut World, dx: f32) -> usize {
    let mut q = world.query::<(&Name, &mut Transform)>();
    let mut moved = 0;
    for (name, mut t) in q.iter_mut(world) {
        if name.as_str() == "ball" {
            t.translation.x += dx;
            moved += 1;
        }
    }
    moved
}

/// A moving caster: the ball slides [`SLIDE_STEP`] along +x every frame after the first, so
/// its caustic moves with it ([`slide_offset`] tells where it is at each readback).
pub fn slide_ball(world: &mut World, frame: u32) {
    if frame > 0 {
        move_ball(world, SLIDE_STEP);
    }
}

/// Relative change between consecutive frames: `Σ|L_t − L_{t−1}| / Σ L_t` of luminance.
pub fn frame_change(a: &CausticImage, b: &CausticImage) -> f64 {
    let (mut d, mut s) = (0.0f64, 0.0f64);
    for (x, y) in a.data.iter().zip(&b.data) {
        let lx = luminance(*x) as f64;
        let ly = luminance(*y) as f64;
        d += (lx - ly).abs();
        s += ly;
    }
    d / s.max(1e-30)
}

/// The mean RMSE (lux) over [`MEASURED`] of `frames[i]` against `reference(i)`.
pub fn mean_rmse<'a>(
    frames: &[CausticImage],
    reference: impl Fn(usize) -> &'a CausticImage,
) -> f64 {
    let n = MEASURED.len() as f64;
    MEASURED
        .map(|i| compare(&frames[i], reference(i), None).map_or(f64::NAN, |m| m.rmse))
        .sum::<f64>()
        / n
}

/// The mean flicker over [`MEASURED`]: [`frame_change`] of each frame against the one before.
pub fn mean_flicker(frames: &[CausticImage]) -> f64 {
    let n = MEASURED.len() as f64;
    MEASURED
        .map(|i| frame_change(&frames[i], &frames[i - 1]))
        .sum::<f64>()
        / n
}
