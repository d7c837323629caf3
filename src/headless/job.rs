use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use bevy::app::AppExit;
use bevy::asset::{LoadState, RenderAssetUsages, UntypedHandle};
use bevy::camera::{Hdr, RenderTarget};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::diagnostic::{DiagnosticsStore, FrameCount};
use bevy::light::{DirectionalLight, PointLight, SpotLight};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};

use super::adapter::{decode_f16_rgba, tonemap_preview, unpad_rows};
use super::counters::{AapsCounters, ImageSpaceCounters, PhotonMapCounters, decode_photons};
use super::load_error::{LoaderPanicCapture, load_failure_reason, report_load_failures_of};
use super::report::{PassSamples, RenderReport, sample_pass_times};
use crate::limits::CausticsLimits;
use crate::reference::{CausticImage, CausticsReferenceImage, ReferenceProgress, ReferenceStatus};
use crate::{Caustics, CausticsDispatchLog, CausticsQuality, CausticsTechnique};

/// One render.
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// The glTF (`.gltf` or `.glb`) to render.
    pub scene: PathBuf,
    /// Technique.
    pub technique: CausticsTechnique,
    /// Target width, pixels.
    pub width: u32,
    /// Target height, pixels.
    pub height: u32,
    /// Photons per light (None: the `Medium` preset).
    pub photons: Option<u64>,
    /// Frames rendered and measured once the caustics are ready.
    pub frames: u32,
    /// The first this many of `frames` are left out of the pass times (render diagnostics
    /// arrive a few frames late, and AAPS's task buffer adapts from a uniform start).
    /// Default 3.
    pub warmup_frames: u32,
    /// Seed.
    pub seed: u64,
    /// Open a window instead of rendering offscreen (needs a display).
    pub window: bool,
    /// Render to a linear `Rgba16Float` target without tone mapping, and render a twin camera
    /// without `Caustics`, so the composite can be checked exactly (tests).
    pub linear: bool,
    /// Print progress to stderr.
    pub progress: bool,
    /// Camera exposure as EV100 (None: Bevy's default, `Exposure::BLENDER`, EV100 9.7). Sunlit
    /// scenes of 10 000 lux look right around 13.
    pub ev100: Option<f32>,
    /// Called once on the world right after the scene spawned and the camera was added: a
    /// hook to add or change entities (tests use it to feed invalid component values).
    pub hook: Option<fn(&mut World)>,
    /// Called on the world at every measured frame with the frame's index (stress tests).
    pub per_frame: Option<fn(&mut World, u32)>,
    /// Called once on the app after its plugins are added, before it runs (tests add
    /// render-world systems with it). In a batch ([`super::run_all`]) the first job's applies
    /// to the whole app.
    pub app_hook: Option<fn(&mut App)>,
    /// Give every light of the scene a `CausticLight` (default true).
    pub mark_lights: bool,
    /// Insert `DefaultOpaqueRendererMethod::forward()` after the plugin (which otherwise makes
    /// deferred the default): receivers rendered forward get no caustic and a warning (tests).
    /// Default false.
    pub forward: bool,
    /// The device maxima the job's sizes are checked against ([`super::check_job`]). Default None:
    /// the WebGPU default device's ([`CausticsLimits::default`]); the command-line renderer
    /// sets the adapter's.
    pub limits: Option<CausticsLimits>,
    /// Settings of the `aaps` technique. Default: `AapsSettings::default()`.
    pub aaps: crate::AapsSettings,
    /// Read the caustics buffer back at every measured frame into
    /// [`RenderReport::frame_caustics`] (temporal tests). Default false.
    pub every_frame: bool,
    /// Settings of the `image_space` technique. Default: `ImageSpaceSettings::default()`.
    pub image_space: crate::ImageSpaceSettings,
    /// Settings of the `photon_map` technique. Default: `PhotonMapSettings::default()`.
    pub photon_map: crate::PhotonMapSettings,
    /// Render a stereo pair with this eye separation (metres): the scene's camera moved half
    /// of it to the left is the left eye, a second camera half of it to the right the right
    /// eye (`CausticsStereo`); the caustics buffer and counters read back are the right
    /// eye's, the frame the left eye's. Default None.
    pub stereo: Option<f32>,
    /// Technique `photon_map`: read the last frame's stored photons back into
    /// [`RenderReport::photon_map_photons`] (tests). Default false.
    pub read_photons: bool,
    /// Technique `volume`: the settings of the volumes fitted around the casters (one per
    /// light) when the scene declares none; its box and faces are ignored.
    pub volume: crate::CausticsVolume,
    /// [`crate::Caustics::settle_frames`] of the camera. Default 16 (the component's default).
    pub settle_frames: u32,
    /// Start the renderer with WebGPU's default limits (`WgpuLimits::default()`: 8 storage
    /// buffers and 4 storage textures per stage, 128 MiB bindings) instead of the adapter's
    /// own. Default false.
    pub webgpu_limits: bool,
    /// Adapter features to leave off the device (tests force the techniques' fallbacks with
    /// `FLOAT32_BLENDABLE` and `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`). Default empty.
    pub disabled_features: bevy::render::settings::WgpuFeatures,
    /// Put the model on a stage ([`super::stage`]): once it has spawned, add a sun, a floor
    /// below its bounds and a camera framing it (the glTF's own cameras are left off; its
    /// lights stay). For the many models that come with no light, camera or floor. The
    /// exposure is [`super::stage::STAGE_EV100`] unless `ev100` is set. Default false.
    pub stage: bool,
}

impl Default for RenderJob {
    fn default() -> Self {
        Self {
            scene: PathBuf::new(),
            technique: CausticsTechnique::Reference,
            width: 256,
            height: 256,
            photons: None,
            frames: 8,
            warmup_frames: 3,
            seed: 1,
            window: false,
            linear: false,
            progress: false,
            ev100: None,
            hook: None,
            per_frame: None,
            app_hook: None,
            mark_lights: true,
            forward: false,
            limits: None,
            aaps: Default::default(),
            image_space: Default::default(),
            photon_map: Default::default(),
            read_photons: false,
            stereo: None,
            every_frame: false,
            volume: Default::default(),
            settle_frames: 16,
            webgpu_limits: false,
            disabled_features: bevy::render::settings::WgpuFeatures::empty(),
            stage: false,
        }
    }
}

#[derive(Resource, Clone)]
pub(super) struct Job(pub(super) RenderJob);

#[derive(Resource, Clone, Default)]
pub(super) struct Shared(pub(super) Arc<Mutex<Outcome>>);

#[derive(Default)]
pub(super) struct Outcome {
    /// The results of a batch's jobs finished before this one ([`super::batch`]).
    pub(super) done: Vec<Result<RenderReport, String>>,
    pub(super) error: Option<String>,
    pub(super) report: RenderReport,
    twin_raw: Vec<u8>,
    snapshot: Option<crate::render::readback::CausticsSnapshot>,
    finished: bool,
    pass_samples: PassSamples,
}

#[derive(Resource, Default, PartialEq, Debug, Clone, Copy)]
pub(super) enum Phase {
    #[default]
    Loading,
    Spawned(u32),
    Tracing,
    Measuring(u32),
    Finishing(u32),
}

#[derive(Resource)]
pub(super) struct Handles {
    scene: Handle<bevy::gltf::Gltf>,
    /// The glTF's `Scene0` (fails alone when the glTF has no scene).
    root: UntypedHandle,
    target: Handle<Image>,
    twin: Option<Handle<Image>>,
    right: Option<Handle<Image>>,
    /// The frame the job started in.
    started: u32,
}

/// Held while the scene loads: a panicking loader is told in our error line, not printed.
#[derive(Resource)]
pub(super) struct LoadingScene(LoaderPanicCapture);

/// The job's scene (the glTF's nodes are its children).
#[derive(Component)]
pub(super) struct JobScene;

#[derive(Component)]
pub(super) struct MainCamera;

#[derive(Component)]
pub(super) struct TwinCamera;

/// Every camera the job spawned (main, right eye, twin): switched off once the readbacks of
/// the last measured frame are taken, so the frames spent waiting for them render nothing.
#[derive(Component)]
pub(super) struct JobCamera;

/// While `job`'s scene loads: a glTF the loader refuses is the job's error, in one line (the
/// asset server's own ERROR about it, once per handle, with a backtrace under RUST_BACKTRACE,
/// stays quiet), and a panicking loader is told in that line.
pub(super) fn loading(job: &RenderJob) -> LoadingScene {
    report_load_failures_of(&asset_name(&job.scene));
    LoadingScene(LoaderPanicCapture::start())
}

impl Outcome {
    /// Files the finished job's result with the batch's and starts the next job's outcome
    /// (the adapter, recorded once as the renderer starts, stays).
    pub(super) fn close_job(&mut self) {
        let result = conclude(self, false);
        let mut fresh = Outcome {
            done: std::mem::take(&mut self.done),
            ..Default::default()
        };
        fresh.done.push(result);
        fresh.report.adapter = std::mem::take(&mut self.report.adapter);
        fresh.report.driver = std::mem::take(&mut self.report.driver);
        *self = fresh;
    }
}

/// The finished (or failed) job's result: its error, or the report with each pass's median
/// time.
pub(super) fn conclude(o: &mut Outcome, window: bool) -> Result<RenderReport, String> {
    if let Some(e) = o.error.take() {
        return Err(e);
    }
    if !o.finished && !window {
        // Bevy quits on a wgpu validation or out-of-memory error (its default
        // RenderErrorHandler); a render that stopped early is an error, never a result.
        return Err(
            "the renderer stopped before the frame was finished (a GPU error? see the log above)"
                .into(),
        );
    }
    let samples = std::mem::take(&mut o.pass_samples.passes);
    for (k, mut v) in samples {
        v.sort_by(f64::total_cmp);
        if !v.is_empty() {
            o.report.pass_ms.insert(k, v[v.len() / 2]);
        }
    }
    Ok(std::mem::take(&mut o.report))
}

pub(super) fn start(
    mut commands: Commands,
    job: Res<Job>,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    frames: Res<FrameCount>,
) {
    let name = asset_name(&job.0.scene);
    let scene = assets.load(name.clone());
    let root = assets.load(GltfAssetLabel::Scene(0).from_asset(name));
    commands.spawn((JobScene, WorldAssetRoot(root.clone())));
    let format = if job.0.linear {
        TextureFormat::Rgba16Float
    } else {
        TextureFormat::Rgba8UnormSrgb
    };
    let mut target_image = |format| {
        let mut image = Image::new_fill(
            Extent3d {
                width: job.0.width,
                height: job.0.height,
                depth_or_array_layers: 1,
            },
            TextureDimension::D2,
            &[0u8; 8][..format_bytes(format)],
            format,
            RenderAssetUsages::default(),
        );
        image.texture_descriptor.usage = TextureUsages::TEXTURE_BINDING
            | TextureUsages::COPY_DST
            | TextureUsages::COPY_SRC
            | TextureUsages::RENDER_ATTACHMENT;
        images.add(image)
    };
    let target = target_image(format);
    let twin = job.0.linear.then(|| target_image(format));
    let right = job.0.stereo.map(|_| target_image(format));
    commands.insert_resource(Handles {
        scene,
        root: root.untyped(),
        target,
        twin,
        right,
        started: frames.0,
    });
}

/// The scene's path for the asset server: its file name (the asset root is its folder).
fn asset_name(scene: &std::path::Path) -> String {
    scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn format_bytes(f: TextureFormat) -> usize {
    if f == TextureFormat::Rgba16Float {
        8
    } else {
        4
    }
}

#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(super) fn drive(
    mut commands: Commands,
    job: Res<Job>,
    shared: Res<Shared>,
    mut phase: ResMut<Phase>,
    handles: Res<Handles>,
    assets: Res<AssetServer>,
    mut cameras: Query<
        (&mut Camera, &GlobalTransform, &Projection),
        (Without<MainCamera>, Without<TwinCamera>),
    >,
    lights: Query<(), Or<(With<DirectionalLight>, With<PointLight>, With<SpotLight>)>>,
    main: Query<
        (
            Option<&ReferenceStatus>,
            Option<&CausticsReferenceImage>,
            Option<&ReferenceProgress>,
        ),
        With<MainCamera>,
    >,
    diagnostics: Res<DiagnosticsStore>,
    (log, memory): (
        Res<CausticsDispatchLog>,
        Res<crate::render::memory::CausticsGpuMemory>,
    ),
    readback: Res<crate::render::readback::CausticsReadback>,
    (warnings, losses): (
        Res<crate::CausticsWarnings>,
        Option<Res<crate::render::losses::CausticsLossCounters>>,
    ),
    frames: Res<FrameCount>,
    (fitted, layout): (
        Res<super::volume::VolumesFitted>,
        Option<Res<super::stage::StageLayout>>,
    ),
    mut exit: MessageWriter<AppExit>,
) {
    let fail = |msg: String, exit: &mut MessageWriter<AppExit>| {
        if let Ok(mut o) = shared.0.lock() {
            o.error.get_or_insert(msg);
        }
        exit.write(AppExit::error());
    };
    if shared.0.lock().is_ok_and(|o| o.error.is_some()) {
        exit.write(AppExit::error()); // set by the render world: a pipeline that failed
        return;
    }
    match *phase {
        Phase::Loading => match scene_loaded(&assets, &handles, &job.0, frames.0 - handles.started)
        {
            Err(msg) => fail(msg, &mut exit),
            Ok(true) => {
                commands.remove_resource::<LoadingScene>();
                *phase = Phase::Spawned(0);
            }
            Ok(false) => {}
        },
        Phase::Spawned(n) => {
            // Give the scene a few frames to spawn.
            if n < 3 {
                *phase = Phase::Spawned(n + 1);
                return;
            }
            if job.0.stage && layout.is_none() {
                // The stage is being built (or failed: `stage` has told the error).
                return;
            }
            let layout = layout.as_deref();
            match spawn_cameras(
                &mut commands,
                &job.0,
                &handles,
                &mut cameras,
                &lights,
                layout,
            ) {
                Ok(()) => {
                    // The camera renders from this frame on: the first measured frame's log
                    // holds everything its technique ran since (a volume propagates at once).
                    log.take();
                    // The camera's first frame (a readback shows the frame it was asked in).
                    if job.0.every_frame && job.0.technique != CausticsTechnique::Reference {
                        readback.request();
                    }
                    *phase = Phase::Tracing;
                }
                Err(e) => fail(e, &mut exit),
            }
        }
        Phase::Tracing => {
            let Ok((status, _, progress)) = main.single() else {
                return;
            };
            if job.0.technique == CausticsTechnique::Volume && !fitted.done {
                return;
            }
            if job.0.technique != CausticsTechnique::Reference {
                // With `every_frame`, its second frame (the first was asked for as the
                // camera spawned).
                if job.0.every_frame {
                    readback.request();
                }
                if job.0.read_photons {
                    readback.read_photons();
                }
                *phase = Phase::Measuring(0);
                return;
            }
            match status {
                Some(ReferenceStatus::Ready) | Some(ReferenceStatus::Inactive) => {
                    if job.0.progress && progress.is_some() {
                        eprintln!("bevy_caustics: reference photons traced: 100%");
                    }
                    log.take();
                    *phase = Phase::Measuring(0);
                }
                _ => {
                    if let Some(p) =
                        progress.filter(|_| job.0.progress && frames.0.is_multiple_of(60))
                    {
                        eprintln!(
                            "bevy_caustics: reference photons traced: {:.0}% of {}",
                            p.fraction() * 100.0,
                            p.total
                        );
                    }
                }
            }
        }
        Phase::Measuring(n) => {
            if let Some(f) = job.0.per_frame {
                commands.queue(move |world: &mut World| f(world, n));
            }
            let mut o = shared.0.lock().expect("state");
            // Diagnostics arrive a few frames late: sample after a warm-up.
            if n >= job.0.warmup_frames {
                sample_pass_times(&diagnostics, &mut o.pass_samples);
            }
            let frame: Vec<String> = log.take().into_iter().map(String::from).collect();
            for p in &frame {
                if !o.report.passes.iter().any(|q| q == p) {
                    o.report.passes.push(p.clone());
                }
            }
            o.report.frame_passes.push(frame);
            let bytes: BTreeMap<String, u64> = memory
                .bytes()
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect();
            o.report.gpu_bytes = bytes.clone();
            o.report.frame_gpu_bytes.push(bytes);
            if job.0.every_frame && job.0.technique != CausticsTechnique::Reference {
                while let Some(snap) = readback.poll() {
                    o.report.frame_counters.push(snap.counters.to_vec());
                    o.report.frame_caustics.push(snap.image);
                }
                if n + 1 < job.0.frames.max(4) {
                    readback.request();
                }
            }
            if n + 1 >= job.0.frames.max(4) && !job.0.window {
                if job.0.technique != CausticsTechnique::Reference {
                    readback.request();
                }
                read_back_targets(&mut commands, &handles);
                *phase = Phase::Finishing(0);
            } else {
                *phase = Phase::Measuring(n + 1);
            }
        }
        Phase::Finishing(n) => {
            if finishing(&mut commands, &job.0, &shared, &handles, &readback) && n < 600 {
                *phase = Phase::Finishing(n + 1);
                return;
            }
            let mut o = shared.0.lock().expect("state");
            let reference = main.single().ok().and_then(|(_, image, _)| image);
            finish_report(&job.0, &mut o, &warnings, reference);
            o.report.loss_warnings = losses.map_or(Vec::new(), |l| l.messages.clone());
            o.finished = true;
            // The next job of a batch, or the end.
            commands.queue(super::batch::next_job);
        }
    }
}

/// The last measured frame's render targets (the view and the linear twin), read back once.
fn read_back_targets(commands: &mut Commands, handles: &Handles) {
    commands
        .spawn(Readback::texture(handles.target.clone()))
        .observe(
            |ev: On<ReadbackComplete>, shared: Res<Shared>, mut commands: Commands| {
                if let Ok(mut o) = shared.0.lock() {
                    o.report.frame_rgba8 = ev.data.clone();
                }
                // A readback repeats every frame until its entity goes.
                commands.entity(ev.entity).despawn();
            },
        );
    if let Some(twin) = &handles.twin {
        commands.spawn(Readback::texture(twin.clone())).observe(
            |ev: On<ReadbackComplete>, shared: Res<Shared>, mut commands: Commands| {
                if let Ok(mut o) = shared.0.lock() {
                    o.twin_raw = ev.data.clone();
                }
                commands.entity(ev.entity).despawn();
            },
        );
    }
}

/// Stage `Finishing`: takes the readbacks of the last measured frame as they arrive; `true`
/// while some are still to come. Once the caustics are in, the job's cameras go off: they have
/// nothing left to render for this job.
fn finishing(
    commands: &mut Commands,
    job: &RenderJob,
    shared: &Shared,
    handles: &Handles,
    readback: &crate::render::readback::CausticsReadback,
) -> bool {
    let gpu = job.technique != CausticsTechnique::Reference;
    let Ok(mut o) = shared.0.lock() else {
        return false;
    };
    if gpu {
        while let Some(snap) = readback.poll() {
            if job.every_frame {
                o.report.frame_counters.push(snap.counters.to_vec());
                o.report.frame_caustics.push(snap.image.clone());
            }
            o.snapshot = Some(snap);
        }
    }
    let caustics_in = o.snapshot.is_some() && readback.pending() == 0;
    let twin_in = handles.twin.is_none() || !o.twin_raw.is_empty();
    let frames_in = !o.report.frame_rgba8.is_empty() && twin_in;
    if gpu && caustics_in {
        commands.queue(|world: &mut World| {
            let mut q = world.query_filtered::<&mut Camera, With<JobCamera>>();
            for mut cam in q.iter_mut(world) {
                cam.is_active = false;
            }
        });
    }
    !frames_in || (gpu && !caustics_in)
}

/// Stage `Loading`: `Ok(true)` once the glTF and its scene are loaded; `Err` with one line if
/// the loader refused the file (the path and its reason) or it took over 3000 frames.
fn scene_loaded(
    assets: &AssetServer,
    handles: &Handles,
    job: &RenderJob,
    frame: u32,
) -> Result<bool, String> {
    let states = [
        assets.load_state(&handles.scene),
        assets.load_state(&handles.root),
    ];
    if let Some(LoadState::Failed(e)) = states.iter().find(|s| s.is_failed()) {
        return Err(format!(
            "cannot load {}: {}",
            job.scene.display(),
            load_failure_reason(e)
        ));
    }
    if frame > 3000 {
        return Err(format!("timed out loading {}", job.scene.display()));
    }
    Ok(states.iter().all(LoadState::is_loaded))
}

/// Stage `Spawned`: the glTF's camera (deactivated) gives its projection and transform to the
/// job's camera, with the job's technique, exposure and target; plus the twin camera without
/// caustics for linear jobs, and the job's hook.
#[allow(clippy::type_complexity)]
fn spawn_cameras(
    commands: &mut Commands,
    job: &RenderJob,
    handles: &Handles,
    cameras: &mut Query<
        (&mut Camera, &GlobalTransform, &Projection),
        (Without<MainCamera>, Without<TwinCamera>),
    >,
    lights: &Query<(), Or<(With<DirectionalLight>, With<PointLight>, With<SpotLight>)>>,
    stage: Option<&super::stage::StageLayout>,
) -> Result<(), String> {
    let (mut projection, gt) = if let Some(stage) = stage {
        // The glTF's own cameras stay off: the stage's frames the model.
        for (mut cam, _, _) in cameras.iter_mut() {
            cam.is_active = false;
        }
        (
            Projection::Perspective(stage.projection.clone()),
            GlobalTransform::from(stage.camera),
        )
    } else {
        let Some((mut cam, gt, projection)) = cameras.iter_mut().next() else {
            return Err(format!(
                "{} has no camera (--stage adds one)",
                job.scene.display()
            ));
        };
        cam.is_active = false;
        (projection.clone(), *gt)
    };
    if lights.is_empty() {
        return Err(format!(
            "{} has no lights (KHR_lights_punctual; --stage adds a sun)",
            job.scene.display()
        ));
    }
    if let Projection::Perspective(p) = &mut projection {
        p.aspect_ratio = job.width as f32 / job.height as f32;
    }
    let caustics =
        Caustics {
            technique: job.technique,
            quality: job.photons.map_or(CausticsQuality::Medium, |photons| {
                CausticsQuality::Custom { photons }
            }),
            seed: job.seed,
            settle_frames: job.settle_frames,
            ..default()
        };
    let exposure = super::stage::job_exposure(job);
    let tonemapping = if job.linear {
        Tonemapping::None
    } else {
        Tonemapping::default()
    };
    let mut transform = gt.compute_transform();
    let centre = transform;
    if let Some(sep) = job.stereo {
        transform.translation -= transform.rotation * Vec3::X * (0.5 * sep);
    }
    let mut main = commands.spawn((
        job.aaps.clone(),
        job.image_space.clone(),
        job.photon_map.clone(),
        MainCamera,
        JobCamera,
        Camera3d::default(),
        Camera {
            order: 1,
            ..default()
        },
        Hdr,
        Msaa::Off,
        projection.clone(),
        transform,
        tonemapping,
        exposure,
        caustics.clone(),
    ));
    if !job.window {
        main.insert(RenderTarget::Image(handles.target.clone().into()));
    }
    if let (Some(sep), Some(right)) = (job.stereo, &handles.right) {
        main.insert(crate::CausticsStereo {
            eye: crate::StereoEye::Left,
            pair: 0,
        });
        let mut t = centre;
        t.translation += t.rotation * Vec3::X * (0.5 * sep);
        commands.spawn((
            job.aaps.clone(),
            job.image_space.clone(),
            job.photon_map.clone(),
            JobCamera,
            Camera3d::default(),
            Camera {
                order: 3,
                ..default()
            },
            RenderTarget::Image(right.clone().into()),
            Hdr,
            Msaa::Off,
            projection.clone(),
            t,
            tonemapping,
            exposure,
            caustics.clone(),
            crate::CausticsStereo {
                eye: crate::StereoEye::Right,
                pair: 0,
            },
        ));
    }

    if let Some(twin) = &handles.twin {
        commands.spawn((
            TwinCamera,
            JobCamera,
            Camera3d::default(),
            Camera {
                order: 2,
                ..default()
            },
            RenderTarget::Image(twin.clone().into()),
            Hdr,
            Msaa::Off,
            bevy::core_pipeline::prepass::DeferredPrepass,
            bevy::core_pipeline::prepass::DepthPrepass,
            projection,
            transform,
            tonemapping,
            exposure,
        ));
    }
    if let Some(hook) = job.hook {
        commands.queue(move |world: &mut World| hook(world));
    }
    Ok(())
}

/// Stage `Finishing`: the report from the readbacks (caustics buffer and counters, frame, twin
/// frame) or the reference image, with the pass times of the clock the adapter has.
fn finish_report(
    job: &RenderJob,
    o: &mut Outcome,
    warnings: &crate::CausticsWarnings,
    reference: Option<&CausticsReferenceImage>,
) {
    let (w, h) = (job.width, job.height);
    o.report.technique = job.technique.name().to_string();
    o.report.size = [w, h];
    o.report.warnings = warnings.messages.clone();
    // Prefer GPU timestamps; fall back to CPU spans where the adapter has none.
    let gpu = o.pass_samples.passes.keys().any(|k| k.ends_with("@gpu"));
    let clock = if gpu { "gpu" } else { "cpu" };
    o.report.timing = clock.to_string();
    o.report.frame_ms = o
        .pass_samples
        .frame_totals
        .remove(clock)
        .unwrap_or_default();
    o.pass_samples.passes = std::mem::take(&mut o.pass_samples.passes)
        .into_iter()
        .filter_map(|(k, v)| {
            k.strip_suffix(&format!("@{clock}"))
                .map(|p| (p.to_string(), v))
        })
        .collect();
    if job.technique == CausticsTechnique::Volume
        && let Some(snap) = o.snapshot.take()
    {
        let v = super::volume::VolumeCounters::from_words(&snap.counters);
        o.report.photons_traced = v.hits;
        o.report.volume = Some(v);
        o.report.caustics = Some(snap.image);
    } else if job.technique == CausticsTechnique::ImageSpace
        && let Some(snap) = o.snapshot.take()
    {
        let c = ImageSpaceCounters::from_words(&snap.counters);
        if let Some(line) = c.lost_summary() {
            warn!("{line}");
        }
        o.report.photons_traced = c.photons_emitted;
        o.report.photons_in_view = c.camera_hits;
        o.report.image_space = Some(c);
        o.report.caustics = Some(snap.image);
    } else if job.technique == CausticsTechnique::PhotonMap
        && let Some(snap) = o.snapshot.take()
    {
        let c = PhotonMapCounters::from_snapshot(&snap);
        if let Some(line) = c.lost_summary() {
            warn!("{line}");
        }
        o.report.photons_traced = c.photons_emitted;
        o.report.photons_in_view = c.photons_stored;
        o.report.photon_map_photons = decode_photons(&snap.photons, c.photons_stored as usize);
        o.report.caustics_alpha = snap.alpha.clone();
        o.report.photon_map = Some(c);
        o.report.caustics = Some(snap.image);
    } else if let Some(snap) = o.snapshot.take() {
        let c = AapsCounters::from_snapshot(&snap);
        if let Some(line) = c.lost_summary() {
            warn!("{line}");
        }
        o.report.photons_traced = c.photons_emitted;
        o.report.photons_in_view = c.splats;
        o.report.aaps = Some(c);
        o.report.caustics = Some(snap.image);
    } else if job.technique != CausticsTechnique::Reference {
        o.error
            .get_or_insert("the caustics buffer readback did not arrive".to_string());
    } else if let Some(img) = reference {
        o.report.caustics = Some((*img.image).clone());
        o.report.photons_traced = img.stats.photons_emitted;
        o.report.photons_in_view = img.stats.photons_in_view;
        o.report.reference_seconds = img.seconds;
        o.report.reference_stats = Some(img.stats.clone());
    } else {
        o.report.caustics = Some(CausticImage::new(w, h));
    }
    let bytes = format_bytes(if job.linear {
        TextureFormat::Rgba16Float
    } else {
        TextureFormat::Rgba8UnormSrgb
    });
    let data = unpad_rows(&o.report.frame_rgba8, w, h, bytes);
    if job.linear {
        o.report.linear_with = decode_f16_rgba(&data);
        o.report.linear_without = decode_f16_rgba(&unpad_rows(&o.twin_raw, w, h, 8));
        o.report.frame_rgba8 = o
            .report
            .linear_with
            .iter()
            .flat_map(|p| tonemap_preview(*p))
            .collect();
    } else {
        o.report.frame_rgba8 = data;
    }
    o.report.exposure = super::stage::job_exposure(job).exposure();
    if o.report.frame_rgba8.len() != (w * h * 4) as usize {
        o.error
            .get_or_insert("the frame readback did not arrive".to_string());
    }
}
