//! Open any glTF with caustics on: every light becomes a caustic light (with shadows), the
//! glTF's glass (KHR_materials_transmission, KHR_materials_volume) and mirrors cast caustics as
//! they are. The glTF's first camera is used if it has one, else one looking at the scene. A
//! model that brings no light (most sample models) stands on the headless renderer's stage: a
//! 10 000 lux sun and a floor below it.
//!
//! `cargo run --release --example gltf_viewer -- PATH.gltf` (default: the glass sphere test
//! scene; without a display it writes gltf_viewer.png). A file that is missing or that the
//! glTF loader refuses prints one line (the path and the loader's reason) and exits with 2.

mod common;

use std::path::PathBuf;

use bevy::asset::{LoadState, UntypedHandle};
use bevy::camera::Exposure;
use bevy::camera::primitives::Aabb;
use bevy::gltf::Gltf;
use bevy::prelude::*;
use bevy_caustics::CausticsInspectorPlugin;
use bevy_caustics::headless::{
    LoaderPanicCapture, STAGE_SUN_LUX, StageLayout, StagePart, build_stage, load_failure_reason,
    report_load_failures_of,
};
use bevy_caustics::mark_every_light;
use bevy_caustics::prelude::*;
use clap::Parser;
use common::{Controls, DefaultPlugins, OrbitCamera};

/// Open a glTF with caustics on: every light becomes a caustic light (with shadows), the
/// glTF's glass and mirrors cast caustics as they are; its first camera is used if it has
/// one, else one looking at the scene. A model without lights gets a sun and a floor.
///
/// Without a display (no DISPLAY or WAYLAND_DISPLAY) it renders offscreen and writes
/// gltf_viewer.png: CAUSTICS_EXAMPLE_SIZE=WxH (pixels, default 640x360),
/// CAUSTICS_EXAMPLE_FRAMES=N (frames, default 20), CAUSTICS_EXAMPLE_OUT=DIR (default: the
/// working directory). A file that is missing or that the glTF loader refuses prints one line
/// and exits with status 2.
#[derive(Parser, Debug)]
#[command(name = "gltf_viewer")]
struct Cli {
    /// The glTF (.gltf or .glb) to open, relative to the working directory; its buffers and
    /// textures load from its folder.
    #[arg(
        value_name = "PATH.gltf",
        default_value_os_t = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/glass_sphere.gltf")
    )]
    path: PathBuf,
}

fn main() -> AppExit {
    // Before any thread: no "XDG_RUNTIME_DIR is invalid" lines from the drivers.
    bevy_caustics::headless::quiet_headless_environment();
    let given = Cli::parse().path;
    let path = match std::fs::canonicalize(&given) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: cannot open {}: {e}", given.display());
            std::process::exit(2);
        }
    };
    // The glTF's folder is the asset root: its buffers and textures load from there.
    let folder = path.parent().map(|p| p.to_string_lossy().into_owned());
    let asset = AssetPlugin {
        file_path: folder.unwrap_or_default(),
        ..default()
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // A file the loader refuses is told in one line by `refused`, not by the asset server.
    report_load_failures_of(&name);
    let log = bevy_caustics::headless::tool_log_plugin();
    App::new()
        .add_plugins((
            DefaultPlugins.set(asset).set(log),
            CausticsPlugin,
            CausticsInspectorPlugin,
        ))
        .add_plugins(Controls::new("the scene's lights cast caustics"))
        .insert_resource(ScenePath { given, name })
        .add_systems(Startup, load)
        .add_systems(
            Update,
            (
                refused,
                stage_unlit_model,
                mark_every_light,
                caustics_camera,
            )
                .chain(),
        )
        .run()
}

#[derive(Resource)]
struct ScenePath {
    /// The path as given on the command line.
    given: PathBuf,
    /// Its file name: the asset path in its folder.
    name: String,
}

/// The glTF and its first scene, watched until both loaded (a panicking loader is told in
/// our line meanwhile).
#[derive(Resource)]
struct SceneHandles([UntypedHandle; 2], LoaderPanicCapture);

fn load(mut commands: Commands, path: Res<ScenePath>, assets: Res<AssetServer>) {
    // Capture before the load starts: the loader runs on another thread at once, and a panic
    // there before the capture printed Bevy's backtrace (seen on a loaded machine).
    let capture = LoaderPanicCapture::start();
    let gltf: Handle<Gltf> = assets.load(path.name.clone());
    let scene = assets.load(GltfAssetLabel::Scene(0).from_asset(path.name.clone()));
    commands.insert_resource(SceneHandles(
        [gltf.untyped(), scene.clone().untyped()],
        capture,
    ));
    commands.spawn(WorldAssetRoot(scene));
}

/// A glTF the loader refuses: one line, the path and the loader's reason, and exit status 2.
fn refused(
    mut commands: Commands,
    handles: Option<Res<SceneHandles>>,
    path: Res<ScenePath>,
    assets: Res<AssetServer>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(handles) = handles else {
        return;
    };
    let states = handles.0.each_ref().map(|h| assets.load_state(h));
    if let Some(LoadState::Failed(e)) = states.iter().find(|s| s.is_failed()) {
        eprintln!(
            "error: cannot load {}: {}",
            path.given.display(),
            load_failure_reason(e)
        );
        exit.write(AppExit::from_code(2));
    }
    if states.iter().all(|s| s.is_loaded() || s.is_failed()) {
        commands.remove_resource::<SceneHandles>();
    }
}

/// A model that brings no light (most sample models: no light, camera or floor) goes on the
/// headless renderer's stage, as `render --stage` puts it: a 10 000 lux sun and a floor below
/// it, said once on stdout. Waits, as the camera does, until the scene has spawned.
#[allow(clippy::type_complexity)]
fn stage_unlit_model(
    mut commands: Commands,
    lights: Query<(), Or<(With<DirectionalLight>, With<PointLight>, With<SpotLight>)>>,
    meshes: Query<(&Mesh3d, &GlobalTransform), Without<StagePart>>,
    (mut mesh_assets, mut materials): (ResMut<Assets<Mesh>>, ResMut<Assets<StandardMaterial>>),
    path: Res<ScenePath>,
    mut frames: Local<u32>,
) {
    if *frames >= 3 || meshes.is_empty() {
        return;
    }
    *frames += 1;
    if *frames < 3 || !lights.is_empty() {
        return;
    }
    if build_stage(
        &mut commands,
        &meshes,
        &mut mesh_assets,
        &mut materials,
        16.0 / 9.0,
    )
    .is_ok()
    {
        println!(
            "{} has no lights: it stands on a stage (a {STAGE_SUN_LUX} lux sun and a floor)",
            path.given.display()
        );
    }
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
    stage: Option<Res<StageLayout>>,
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
    } else if let Some(stage) = stage {
        let focus = (stage.bounds.0 + stage.bounds.1) * 0.5;
        commands.spawn((
            Camera3d::default(),
            components,
            OrbitCamera::looking_at(stage.camera.translation, focus),
        ));
    } else if *frames > 30 && lo.x <= hi.x {
        let size = (hi - lo).length().max(0.1);
        commands.spawn((
            Camera3d::default(),
            components,
            OrbitCamera::looking_at(focus + Vec3::new(0.5, 0.6, 1.0) * size, focus),
        ));
    }
}
