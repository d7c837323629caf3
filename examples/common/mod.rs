//! What the examples share and a game would not need: a window, or offscreen rendering to a
//! PNG without a display; an orbit camera; a line of help with the frame rate.
//!
//! `DefaultPlugins` here is Bevy's `DefaultPlugins` with a titled window. On a machine with no
//! display (no `DISPLAY` or `WAYLAND_DISPLAY`) it is Bevy's `DefaultPlugins` without winit: the
//! cameras render into an image, the time step is fixed (1/30 s), and after
//! `CAUSTICS_EXAMPLE_FRAMES` frames (default 20) the image is written to `<example>.png` (or
//! into `CAUSTICS_EXAMPLE_OUT`, a folder) and the app exits. `CAUSTICS_EXAMPLE_SIZE=WxH`
//! sets the offscreen size (default 640x360); the tests use both. Offscreen, the inspector
//! window is closed unless `CAUSTICS_EXAMPLE_INSPECTOR=1`.
//!
//! With a display, `CAUSTICS_EXAMPLE_SIZE` sets the window's size, and
//! `CAUSTICS_EXAMPLE_SCRIPT` runs a scripted game loop in the window (screenshots, resizes,
//! camera and scene changes at given frames: `script.rs`), as the window tests do.

#![allow(dead_code)]

mod script;

use std::time::Duration;

use bevy::app::{AppExit, PluginGroupBuilder, ScheduleRunnerPlugin};
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::diagnostic::{DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll, MouseScrollUnit};
use bevy::prelude::*;
use bevy::render::render_resource::PipelineCache;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::render::{Render, RenderApp, RenderPlugin, RenderSystems};
use bevy::time::TimeUpdateStrategy;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use bevy_caustics::inspector::CausticsInspector;
use bevy_caustics::render::readback::CausticsReadback;
use bevy_egui::input::EguiWantsInput;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};

/// True when a window can be opened.
pub fn has_display() -> bool {
    std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some()
}

/// The example's name (its executable's).
pub fn example_name() -> String {
    std::env::current_exe()
        .ok()
        .and_then(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .map(|s| s.split('-').next().unwrap_or(&s).to_string())
        .unwrap_or_else(|| "example".into())
}

/// Bevy's `DefaultPlugins`, with a window, or rendering offscreen to a PNG (see the module).
pub struct DefaultPlugins;

impl PluginGroup for DefaultPlugins {
    fn build(self) -> PluginGroupBuilder {
        let name = example_name();
        let group = bevy::DefaultPlugins.build();
        if has_display() {
            // `CAUSTICS_EXAMPLE_SIZE` sets the window's size too (the window tests).
            let size = std::env::var_os("CAUSTICS_EXAMPLE_SIZE")
                .map_or(UVec2::new(1280, 720), |_| offscreen_size());
            return group
                .set(WindowPlugin {
                    primary_window: Some(Window {
                        title: format!("bevy_caustics: {name}"),
                        resolution: (size.x, size.y).into(),
                        ..default()
                    }),
                    ..default()
                })
                .add(script::WindowScript { name });
        }
        group
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<WinitPlugin>()
            .add(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
            .add(Offscreen { name })
    }
}

/// Offscreen rendering to a PNG (no display).
struct Offscreen {
    name: String,
}

#[derive(Resource)]
struct OffscreenTarget {
    image: Handle<Image>,
    path: std::path::PathBuf,
    frames: u32,
    seen: u32,
    shot: bool,
    saved: Option<Result<(), String>>,
    summary: Option<String>,
}

impl Plugin for Offscreen {
    fn build(&self, app: &mut App) {
        let frames = std::env::var("CAUSTICS_EXAMPLE_FRAMES")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20);
        let dir = std::env::var_os("CAUSTICS_EXAMPLE_OUT")
            .map(std::path::PathBuf::from)
            .unwrap_or_default();
        let path = dir.join(format!("{}.png", self.name));
        app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 30.0,
        )))
        .insert_resource(OffscreenTarget {
            image: Handle::default(),
            path,
            frames,
            seen: 0,
            shot: false,
            saved: None,
            summary: None,
        })
        .add_systems(PreStartup, create_target)
        .add_systems(Startup, inspector_only_on_request)
        .add_systems(Update, dark_caustics_on_request)
        .add_systems(Last, (retarget_cameras, count_and_shoot).chain());
        let pending = PipelinesPending::default();
        app.insert_resource(pending.clone());
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app.insert_resource(pending).add_systems(
                Render,
                count_pending_pipelines.in_set(RenderSystems::Cleanup),
            );
        }
    }
}

/// Pipelines queued or compiling in the render world's cache. A pipeline waits for its shader
/// asset, which loads on another thread (longer on a loaded machine), and a frame drawn before
/// its pipelines are ready misses what they draw (the inspector's images, egui): the offscreen
/// picture is taken at least [`AFTER_LAST_PIPELINE`] frames after the last one was ready.
#[derive(Resource, Clone, Default)]
struct PipelinesPending(std::sync::Arc<std::sync::atomic::AtomicUsize>);

/// Frames between the last pipeline ready and the offscreen picture.
const AFTER_LAST_PIPELINE: u32 = 4;

fn count_pending_pipelines(cache: Res<PipelineCache>, pending: Res<PipelinesPending>) {
    let n = cache.waiting_pipelines().count();
    pending.0.store(n, std::sync::atomic::Ordering::Relaxed);
}

/// Offscreen, the inspector window stays closed (its timings change from run to run) unless
/// `CAUSTICS_EXAMPLE_INSPECTOR=1`.
fn inspector_only_on_request(inspector: Option<ResMut<CausticsInspector>>) {
    if let Some(mut i) = inspector {
        i.open = std::env::var("CAUSTICS_EXAMPLE_INSPECTOR").is_ok_and(|v| v == "1");
    }
}

/// `CAUSTICS_EXAMPLE_DARK=1` scales every caustic light to 0; `CAUSTICS_EXAMPLE_HIDDEN=1`
/// sets every camera's debug view to `Hidden` (the tests show that the golden comparison sees
/// the caustics, and that both give the frame without them).
fn dark_caustics_on_request(
    mut lights: Query<&mut bevy_caustics::CausticLight>,
    mut cameras: Query<&mut bevy_caustics::Caustics>,
) {
    let on = |k: &str| std::env::var(k).is_ok_and(|v| v == "1");
    if on("CAUSTICS_EXAMPLE_DARK") {
        for mut l in &mut lights {
            if l.intensity_scale != 0.0 {
                l.intensity_scale = 0.0;
            }
        }
    }
    if on("CAUSTICS_EXAMPLE_HIDDEN") {
        for mut c in &mut cameras {
            if c.debug_view != bevy_caustics::CausticsDebugView::Hidden {
                c.debug_view = bevy_caustics::CausticsDebugView::Hidden;
            }
        }
    }
}

fn offscreen_size() -> UVec2 {
    std::env::var("CAUSTICS_EXAMPLE_SIZE")
        .ok()
        .and_then(|s| {
            let (w, h) = s.split_once('x')?;
            Some(UVec2::new(w.parse().ok()?, h.parse().ok()?))
        })
        .unwrap_or(UVec2::new(640, 360))
        .clamp(UVec2::splat(16), UVec2::splat(4096))
}

fn create_target(mut images: ResMut<Assets<Image>>, mut target: ResMut<OffscreenTarget>) {
    let size = offscreen_size();
    let mut image = Image::new_fill(
        Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        &[0, 0, 0, 255],
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::default(),
    );
    image.texture_descriptor.usage = TextureUsages::TEXTURE_BINDING
        | TextureUsages::COPY_DST
        | TextureUsages::COPY_SRC
        | TextureUsages::RENDER_ATTACHMENT;
    target.image = images.add(image);
}

/// Every camera renders into the offscreen image. Bevy's `camera_system` recomputes a camera's
/// target size only when the camera is added, its projection changes or its image changes,
/// not when `RenderTarget` is replaced: the projection is marked changed too.
fn retarget_cameras(
    mut commands: Commands,
    target: Res<OffscreenTarget>,
    mut cameras: Query<(Entity, Option<&RenderTarget>, &mut Projection), With<Camera3d>>,
) {
    for (e, t, mut projection) in &mut cameras {
        if !matches!(t, Some(RenderTarget::Image(_))) {
            commands
                .entity(e)
                .insert(RenderTarget::Image(target.image.clone().into()));
            projection.set_changed();
        }
    }
}

/// Count frames from the first caustics camera on; then take the screenshot and a readback of
/// the caustics buffer, write the PNG, print a summary of the caustics and exit.
fn count_and_shoot(
    mut commands: Commands,
    mut target: ResMut<OffscreenTarget>,
    cameras: Query<(), With<bevy_caustics::Caustics>>,
    readback: Res<CausticsReadback>,
    pending: Res<PipelinesPending>,
    mut exit: MessageWriter<AppExit>,
) {
    if cameras.is_empty() {
        target.seen += 1;
        if target.seen > 3000 {
            error!("no caustics camera after 3000 frames");
            exit.write(AppExit::error());
        }
        return;
    }
    if target.shot {
        target.seen += 1;
        if target.seen > 600 {
            error!(
                "no {} 600 frames after the screenshot was asked for",
                if target.saved.is_none() {
                    "screenshot"
                } else {
                    "caustics readback"
                }
            );
            exit.write(AppExit::error());
            return;
        }
        if target.summary.is_none()
            && let Some(snap) = readback.poll()
        {
            let finite = snap.image.all_finite();
            let max = snap
                .image
                .data
                .iter()
                .map(|v| v.max_element())
                .fold(0.0f32, f32::max);
            target.summary = Some(format!(
                "caustics: finite={finite} max={max:.0} lx sum={:.3e}",
                snap.image.sum().element_sum()
            ));
        }
        if let (Some(saved), Some(summary)) = (&target.saved, &target.summary) {
            match saved {
                Ok(()) => {
                    println!("wrote {}", target.path.display());
                    println!("{summary}");
                    exit.write(AppExit::Success);
                }
                Err(e) => {
                    error!("cannot write {}: {e}", target.path.display());
                    exit.write(AppExit::error());
                }
            }
            target.saved = None;
        }
        return;
    }
    target.frames = target.frames.saturating_sub(1);
    if pending.0.load(std::sync::atomic::Ordering::Relaxed) > 0 {
        // Same frame count as ever when everything compiled in time (the goldens, the
        // showcase's clock); later, the picture waits for the last pipeline, plus frames for
        // what it draws to reach the screen.
        target.frames = target.frames.max(AFTER_LAST_PIPELINE);
    }
    if target.frames > 0 {
        return;
    }
    target.shot = true;
    target.seen = 0;
    readback.request();
    let path = target.path.clone();
    commands
        .spawn(Screenshot::image(target.image.clone()))
        .observe(
            move |ev: On<ScreenshotCaptured>, mut target: ResMut<OffscreenTarget>| {
                target.saved = Some(save_rgb_png(&ev.image, &path));
            },
        );
}

/// Write a captured screenshot as an RGB PNG (the offscreen render and the window script).
pub(crate) fn save_rgb_png(image: &Image, path: &std::path::Path) -> Result<(), String> {
    image
        .clone()
        .try_into_dynamic()
        .map_err(|e| e.to_string())
        .and_then(|i| i.to_rgb8().save(path).map_err(|e| e.to_string()))
}

/// An orbit camera: left drag orbits around `focus`, right drag pans, the wheel zooms. Input
/// the egui panel wants is left to it.
#[derive(Component, Clone, Debug)]
pub struct OrbitCamera {
    /// The point looked at.
    pub focus: Vec3,
    /// Distance from `focus`, metres.
    pub distance: f32,
    /// Yaw around +Y, radians.
    pub yaw: f32,
    /// Pitch above the horizon, radians.
    pub pitch: f32,
}

impl OrbitCamera {
    /// Looking from `eye` at `focus`.
    pub fn looking_at(eye: Vec3, focus: Vec3) -> Self {
        let d = eye - focus;
        let distance = d.length().max(1e-3);
        Self {
            focus,
            distance,
            yaw: d.x.atan2(d.z),
            pitch: (d.y / distance).clamp(-1.0, 1.0).asin(),
        }
    }

    /// The camera's transform.
    pub fn transform(&self) -> Transform {
        let rot = Quat::from_euler(EulerRot::YXZ, self.yaw, -self.pitch, 0.0);
        let eye = self.focus + rot * Vec3::Z * self.distance;
        Transform::from_translation(eye).looking_at(self.focus, Vec3::Y)
    }
}

/// The orbit camera and the help line.
pub struct Controls {
    /// The help line.
    pub help: &'static str,
}

impl Controls {
    /// With this help line (the mouse controls and F1 are added in front).
    pub fn new(help: &'static str) -> Self {
        Self { help }
    }
}

#[derive(Resource)]
struct Help(&'static str);

impl Plugin for Controls {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<FrameTimeDiagnosticsPlugin>() {
            app.add_plugins(FrameTimeDiagnosticsPlugin::default());
        }
        app.insert_resource(Help(self.help))
            .add_systems(Update, orbit)
            .add_systems(
                PostUpdate,
                place_orbit_cameras.before(TransformSystems::Propagate),
            );
        if has_display() {
            app.add_systems(EguiPrimaryContextPass, help_line);
        }
    }
}

fn orbit(
    mut cameras: Query<&mut OrbitCamera>,
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    egui: Option<Res<EguiWantsInput>>,
) {
    if egui.is_some_and(|e| e.wants_any_pointer_input()) {
        return;
    }
    let wheel = match scroll.unit {
        MouseScrollUnit::Line => scroll.delta.y,
        MouseScrollUnit::Pixel => scroll.delta.y / 40.0,
    };
    for mut c in &mut cameras {
        if buttons.pressed(MouseButton::Left) {
            c.yaw -= motion.delta.x * 0.006;
            c.pitch = (c.pitch + motion.delta.y * 0.006).clamp(-1.5, 1.5);
        }
        if buttons.pressed(MouseButton::Right) {
            let t = c.transform();
            let k = c.distance * 0.0015;
            c.focus += (t.left() * motion.delta.x + t.up() * motion.delta.y) * k;
        }
        if wheel != 0.0 {
            c.distance = (c.distance * 0.9f32.powf(wheel)).clamp(0.05, 1.0e4);
        }
    }
}

fn place_orbit_cameras(mut cameras: Query<(&OrbitCamera, &mut Transform), Changed<OrbitCamera>>) {
    for (c, mut t) in &mut cameras {
        *t = c.transform();
    }
}

fn help_line(
    mut contexts: EguiContexts,
    help: Res<Help>,
    diagnostics: Res<DiagnosticsStore>,
) -> Result {
    let fps = diagnostics
        .get(&FrameTimeDiagnosticsPlugin::FPS)
        .and_then(|d| d.smoothed())
        .map_or("–".to_string(), |f| format!("{f:.0}"));
    egui::Area::new(egui::Id::new("caustics_help"))
        .anchor(egui::Align2::CENTER_BOTTOM, [0.0, -8.0])
        .show(contexts.ctx_mut()?, |ui| {
            ui.label(
                egui::RichText::new(format!(
                    "{fps} fps · left drag: orbit · right drag: pan · wheel: zoom · F1: inspector · {}",
                    help.0
                ))
                .color(egui::Color32::WHITE)
                .background_color(egui::Color32::from_black_alpha(160)),
            );
        });
    Ok(())
}

/// `CAUSTICS_EXAMPLE_WORLD_INSPECTOR=1` adds bevy-inspector-egui's world inspector beside the
/// caustics inspector, both on one `EguiPlugin` (add this after `CausticsInspectorPlugin`,
/// which adds the `EguiPlugin`). Every 10 frames the example prints which of the two windows
/// the primary egui context shows (`egui windows: contexts=1 world_inspector=true
/// caustics=true`), for the test that runs them together.
pub struct WorldInspectorOnRequest;

impl Plugin for WorldInspectorOnRequest {
    fn build(&self, app: &mut App) {
        if std::env::var("CAUSTICS_EXAMPLE_WORLD_INSPECTOR").is_ok_and(|v| v == "1") {
            app.add_plugins(bevy_inspector_egui::quick::WorldInspectorPlugin::new())
                .add_systems(Last, report_egui_windows);
        }
    }
}

fn report_egui_windows(
    mut contexts: Query<&mut bevy_egui::EguiContext, With<bevy_egui::PrimaryEguiContext>>,
    all: Query<(), With<bevy_egui::EguiContext>>,
    mut frame: Local<u32>,
) {
    *frame += 1;
    if !(*frame).is_multiple_of(10) {
        return;
    }
    for mut ctx in &mut contexts {
        let ctx = ctx.get_mut();
        let shown = |title: &str| {
            let layer = egui::LayerId::new(egui::Order::Middle, egui::Id::new(title));
            ctx.memory(|m| m.areas().is_visible(&layer))
        };
        let (world, caustics) = (shown("World Inspector"), shown("Caustics"));
        println!(
            "egui windows: contexts={} world_inspector={world} caustics={caustics}",
            all.iter().count()
        );
    }
}
