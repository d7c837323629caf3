//! Caustics volumes (seed 000): a box around a glass block and a gem, marched slab by slab
//! against rasterised G-buffers, with the volume's faces and slab planes drawn as gizmos. The
//! work is redone only when something inside the volume changes: here the gem turns.
//!
//! Keys: G gizmos on/off; Space stops and starts the gem (watch the passes in the inspector:
//! a still volume only splats). The inspector opens on the volume's slab G-buffer and its
//! projector's density tiles.
//!
//! `cargo run --release --example volumes` (without a display it writes volumes.png)

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
        .add_plugins(Controls::new("G: gizmos · space: stop/start the gem"))
        .add_systems(Startup, setup)
        .add_systems(Update, (keys, turn_gem, show_volume_buffers))
        .run()
}

#[derive(Component)]
struct Gem;

#[derive(Resource)]
struct Turning(bool);

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.insert_resource(Turning(true));
    commands.spawn((
        Camera3d::default(),
        Caustics {
            technique: CausticsTechnique::Volume,
            ..default()
        },
        CausticsVolumeGizmos::default(),
        Msaa::Off,
        Exposure { ev100: 13.0 },
        Name::new("camera"),
        OrbitCamera::looking_at(Vec3::new(2.2, 2.8, 3.4), Vec3::new(0.0, 0.4, 0.0)),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 10_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        CausticLight::default(),
        // Straight down, so the volume's top face (its entry) faces the sun.
        Transform::from_xyz(0.0, 5.0, 0.0).looking_at(Vec3::ZERO, Vec3::Z),
    ));
    // The volume: a 2.4 x 1.6 x 1.6 m box from the floor up, entered from the top, projected
    // through the bottom onto the floor.
    commands.spawn((
        CausticsVolume {
            size: Vec3::new(2.4, 1.6, 1.6),
            slabs: 4,
            ..default()
        },
        Transform::from_xyz(0.0, 0.85, 0.0),
        Name::new("caustics volume"),
    ));
    let glass = |materials: &mut Assets<StandardMaterial>, ior: f32| {
        materials.add(StandardMaterial {
            specular_transmission: 1.0,
            ior,
            thickness: 0.5,
            perceptual_roughness: 0.02,
            ..default()
        })
    };
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.6, 0.2, 0.6))),
        MeshMaterial3d(glass(&mut materials, 1.5)),
        Transform::from_xyz(-0.6, 1.1, 0.0).with_rotation(Quat::from_rotation_z(0.3)),
        Name::new("glass block"),
    ));
    commands.spawn((
        Gem,
        Mesh3d(
            meshes.add(
                Sphere::new(0.3)
                    .mesh()
                    .ico(1)
                    .unwrap()
                    .with_duplicated_vertices()
                    .with_computed_flat_normals(),
            ),
        ),
        MeshMaterial3d(glass(&mut materials, 2.42)),
        Transform::from_xyz(0.6, 1.0, 0.0).with_scale(Vec3::new(1.0, 0.6, 1.0)),
        Name::new("gem"),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.8, 0.8, 0.8))),
        Name::new("floor"),
    ));
}

fn keys(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    mut turning: ResMut<Turning>,
    cameras: Query<(Entity, Has<CausticsVolumeGizmos>), With<Caustics>>,
) {
    if keys.just_pressed(KeyCode::Space) {
        turning.0 = !turning.0;
    }
    if keys.just_pressed(KeyCode::KeyG) {
        for (e, has) in &cameras {
            if has {
                commands.entity(e).remove::<CausticsVolumeGizmos>();
            } else {
                commands.entity(e).insert(CausticsVolumeGizmos::default());
            }
        }
    }
}

fn turn_gem(time: Res<Time>, turning: Res<Turning>, mut gems: Query<&mut Transform, With<Gem>>) {
    if !turning.0 {
        return;
    }
    for mut t in &mut gems {
        t.rotate_y(time.delta_secs() * 0.4);
    }
}

/// Open the inspector on the volume's buffers, once: the first slab's G_near (what the slab
/// march sees) and the density tiles of the exit face's projector (-Y, the floor).
fn show_volume_buffers(mut images: ResMut<InspectorImages>, mut done: Local<bool>) {
    if *done || images.images.is_empty() {
        return;
    }
    for i in &mut images.images {
        i.shown = matches!(i.kind, LiveKind::SlabGBuffer | LiveKind::ProjectorTiles);
    }
    images.slab_layer = 2;
    images.face = 3;
    *done = true;
}
