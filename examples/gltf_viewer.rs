//! Open any glTF with caustics on: every light becomes a caustic light (with shadows), the
//! glTF's glass (KHR_materials_transmission, KHR_materials_volume) and mirrors cast caustics as
//! they are. The glTF's first camera is used if it has one, else one looking at the scene.
//!
//! `cargo run --release --example gltf_viewer -- PATH.gltf` (default: the glass sphere test
//! scene; without a display it writes gltf_viewer.png)

mod common;

use std::path::PathBuf;

use bevy::camera::Exposure;
use bevy::camera::primitives::Aabb;
use bevy::prelude::*;
use bevy_caustics::CausticsInspectorPlugin;
use bevy_caustics::mark_every_light;
use bevy_caustics::prelude::*;
use common::{Controls, DefaultPlugins, OrbitCamera};

fn main() -> AppExit {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/glass_sphere.gltf")
        });
    let path = match std::fs::canonicalize(&path) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: cannot open {}: {e}", path.display());
            std::process::exit(2);
        }
    };
    // The glTF's folder is the asset root: its buffers and textures load from there.
    let folder = path.parent().map(|p| p.to_string_lossy().into_owned());
    let asset = AssetPlugin {
        file_path: folder.unwrap_or_default(),
        ..default()
    };
    App::new()
        .add_plugins((
            DefaultPlugins.set(asset),
            CausticsPlugin,
            CausticsInspectorPlugin,
        ))
        .add_plugins(Controls::new("the scene's lights cast caustics"))
        .insert_resource(ScenePath(path))
        .add_systems(Startup, load)
        .add_systems(Update, (mark_every_light, caustics_camera))
        .run()
}

#[derive(Resource)]
struct ScenePath(PathBuf);

fn load(mut commands: Commands, path: Res<ScenePath>, assets: Res<AssetServer>) {
    let name = path.0.file_name().map(|n| n.to_string_lossy().into_owned());
    let scene = assets.load(GltfAssetLabel::Scene(0).from_asset(name.unwrap_or_default()));
    commands.spawn(WorldAssetRoot(scene));
}

/// The glTF's camera gets caustics and the orbit controls; without one, a camera is added
/// looking at the meshes' bounds. Both wait until the scene has been spawned for a few frames,
/// so transforms have propagated and the meshes have their bounds.
#[allow(clippy::type_complexity)]
fn caustics_camera(
    mut commands: Commands,
    cameras: Query<(Entity, &GlobalTransform), (With<Camera3d>, Without<Caustics>)>,
    with_caustics: Query<(), With<Caustics>>,
    meshes: Query<(&GlobalTransform, &Aabb), With<Mesh3d>>,
    mut frames: Local<u32>,
) {
    if !with_caustics.is_empty() || meshes.is_empty() {
        return;
    }
    *frames += 1;
    if *frames < 3 {
        return;
    }
    let (lo, hi) = meshes
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), (t, b)| {
            let c = t.transform_point(b.center.into());
            let r = (t.affine().matrix3 * Vec3::from(b.half_extents)).abs();
            (lo.min(c - r), hi.max(c + r))
        });
    let focus = if lo.x <= hi.x {
        (lo + hi) * 0.5
    } else {
        Vec3::ZERO
    };
    let components = (Caustics::default(), Msaa::Off, Exposure { ev100: 13.0 });
    if let Some((e, t)) = cameras.iter().next() {
        let eye = t.translation();
        commands
            .entity(e)
            .insert((components, OrbitCamera::looking_at(eye, focus)));
    } else if *frames > 30 && lo.x <= hi.x {
        let size = (hi - lo).length().max(0.1);
        commands.spawn((
            Camera3d::default(),
            components,
            OrbitCamera::looking_at(focus + Vec3::new(0.5, 0.6, 1.0) * size, focus),
        ));
    }
}
