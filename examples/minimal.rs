//! The smallest game with caustics: the README's usage snippet, a floor and a glass ball.
//!
//! `cargo run --release --example minimal`
//!
//! tests/cpu/readme.rs keeps everything below the `use common::DefaultPlugins` line identical
//! to the README's snippet.

mod common;
// The examples' `DefaultPlugins` is Bevy's, or, without a display, Bevy's rendering offscreen
// to minimal.png (examples/common). In a game, leave this line out.
use common::DefaultPlugins;

use bevy::camera::Exposure;
use bevy::prelude::*;
use bevy_caustics::prelude::*;

fn main() {
    App::new()
        // CausticsPlugin makes deferred the default opaque method: the composite reads the
        // diffuse albedo from the deferred G-buffer.
        .add_plugins((DefaultPlugins, CausticsPlugin))
        .add_systems(Startup, setup)
        .run();
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    // Caustics requires Hdr and the deferred prepasses; they are added for you.
    commands.spawn((
        Camera3d::default(),
        Caustics::default(),
        Msaa::Off,
        // A sunlit scene: 10 000 lux wants an exposure of about EV100 13.
        Exposure { ev100: 13.0 },
        Transform::from_xyz(0.0, 2.2, 3.2).looking_at(Vec3::new(0.0, 0.4, 0.0), Vec3::Y),
    ));
    // A caustic light: the sun, 10 000 lux, with shadows (the shadow removes the light the
    // glass redirects; the caustic adds it back where it lands).
    commands.spawn((
        DirectionalLight {
            illuminance: 10_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        CausticLight::default(),
        Transform::from_xyz(-1.0, 4.0, 0.5).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    // Glass (StandardMaterial with specular_transmission > 0, e.g. glTF
    // KHR_materials_transmission) and mirrors (metallic >= 0.9, roughness <= 0.2) cast
    // caustics as they are. `CausticMaterial` overrides the guess per mesh.
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.5).mesh().uv(64, 32))),
        MeshMaterial3d(materials.add(StandardMaterial {
            specular_transmission: 1.0,
            ior: 1.5,
            thickness: 1.0,
            perceptual_roughness: 0.02,
            ..default()
        })),
        Transform::from_xyz(0.0, 1.0, 0.0),
    ));
    // Everything else is a diffuse receiver.
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.8, 0.8, 0.8))),
    ));
}
