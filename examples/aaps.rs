//! AAPS, the default technique (adaptive anisotropic photon scattering): a glass ball and a
//! mirror ring under the sun. The inspector opens on the task buffer: the photon density per
//! atlas texel, which adapts every frame to where splats are large or noisy.
//!
//! Keys: 1 / 2 / 3 photon budget Low / Medium / High; Space turns adaptation on and off.
//!
//! `cargo run --release --example aaps` (without a display it writes aaps.png)

mod common;

use bevy::camera::Exposure;
use bevy::prelude::*;
use bevy_caustics::CausticsInspectorPlugin;
use bevy_caustics::inspector::{InspectorImages, LiveKind};
use bevy_caustics::prelude::*;
use common::{Controls, DefaultPlugins, OrbitCamera};

fn main() -> AppExit {
    App::new()
        .add_plugins((DefaultPlugins, CausticsPlugin, CausticsInspectorPlugin))
        .add_plugins(common::WorldInspectorOnRequest)
        .add_plugins(Controls::new(
            "1/2/3: photon budget · space: adaptive on/off",
        ))
        .add_systems(Startup, setup)
        .add_systems(Update, (keys, show_task_buffer))
        .run()
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.spawn((
        Camera3d::default(),
        Caustics {
            technique: CausticsTechnique::Aaps,
            quality: CausticsQuality::Medium,
            ..default()
        },
        AapsSettings::default(),
        Msaa::Off,
        Exposure { ev100: 13.0 },
        Name::new("camera"),
        OrbitCamera::looking_at(Vec3::new(0.0, 3.0, 3.5), Vec3::new(0.3, 0.2, 0.0)),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 10_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        CausticLight::default(),
        Name::new("sun"),
        Transform::from_xyz(-1.5, 4.0, 1.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.4).mesh().uv(64, 32))),
        MeshMaterial3d(materials.add(StandardMaterial {
            specular_transmission: 1.0,
            ior: 1.5,
            thickness: 0.8,
            perceptual_roughness: 0.02,
            ..default()
        })),
        Transform::from_xyz(-0.6, 0.9, 0.0),
        Name::new("glass ball"),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Extrusion::new(Annulus::new(0.42, 0.45), 0.25))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.95, 0.95, 0.95),
            metallic: 1.0,
            perceptual_roughness: 0.05,
            ..default()
        })),
        Transform::from_xyz(0.9, 0.125, 0.0)
            .with_rotation(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)),
        Name::new("mirror ring"),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.8, 0.8, 0.8))),
        Name::new("floor"),
    ));
}

fn keys(keys: Res<ButtonInput<KeyCode>>, mut cameras: Query<(&mut Caustics, &mut AapsSettings)>) {
    for (mut c, mut a) in &mut cameras {
        for (key, quality) in [
            (KeyCode::Digit1, CausticsQuality::Low),
            (KeyCode::Digit2, CausticsQuality::Medium),
            (KeyCode::Digit3, CausticsQuality::High),
        ] {
            if keys.just_pressed(key) {
                c.quality = quality;
            }
        }
        if keys.just_pressed(KeyCode::Space) {
            a.adaptive = !a.adaptive;
        }
    }
}

/// Open the inspector on the task buffer's density, once.
fn show_task_buffer(mut images: ResMut<InspectorImages>, mut done: Local<bool>) {
    if *done || images.images.is_empty() {
        return;
    }
    for i in &mut images.images {
        i.shown = i.kind == LiveKind::Density;
    }
    *done = true;
}
