//! Several jobs in one app, one after another ([`run_all`]): a Bevy app costs a second or two
//! to start on lavapipe, so a suite of many small renders (the stiff cases) shares one. Between
//! jobs the finished job's scene, cameras, fitted volumes and stage go, as a game's level does,
//! and the next job loads its scene into the same renderer.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::Duration;

use bevy::app::{AppExit, ScheduleRunnerPlugin};
use bevy::asset::AssetPlugin;
use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

use super::check::check_job;
use super::job::{
    Job, JobCamera, JobScene, Phase, RenderJob, Shared, conclude, drive, loading, start,
};
use super::report::RenderReport;
use super::stage::{StageLayout, StagePart};
use super::volume::{FittedVolume, VolumeTemplate, VolumesFitted};
use crate::render::losses::CausticsLossCounters;
use crate::{CausticsDispatchLog, CausticsPlugin, CausticsTechnique, CausticsWarnings};

/// The jobs still to render after the current one.
#[derive(Resource, Default)]
pub(super) struct Queue(pub(super) VecDeque<RenderJob>);

/// Render `jobs` in one app, in order: one result per job rendered. A job that fails (a scene
/// that does not load, a GPU error) ends the batch: its error is the last result and the jobs
/// after it have none. The jobs must agree on what the app is built with (window, device
/// limits and features, forward rendering, marked lights, photon readback) and their scenes
/// must lie in one folder (the asset root); a job that does not is an error, as is a window
/// job in a batch of more than one.
pub fn run_all(mut jobs: Vec<RenderJob>) -> Vec<Result<RenderReport, String>> {
    let refused = first_refused(&jobs);
    if let Some((i, _)) = &refused {
        jobs.truncate(*i);
    }
    let mut results = if jobs.is_empty() {
        Vec::new()
    } else {
        run_app(jobs)
    };
    release_freed_memory();
    results.extend(refused.map(|(_, e)| Err(e)));
    results
}

/// Give the memory a finished app freed back to the system. glibc's malloc keeps freed memory
/// in its heaps, and a process that starts app after app (the GPU tests start well over a
/// hundred in one) grows by that as well as by what Bevy's deferred path on lavapipe keeps
/// (`docs/testing.md`). Measured on the sample-model and stiff tests in one process: peak
/// resident 10.6 GB against 11.0 without. Elsewhere (not glibc) nothing.
fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: glibc's `malloc_trim` only returns free pages of its heaps to the system; it
        // takes each heap's lock and is safe to call from any thread at any time.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// The first job of `jobs` that cannot be rendered in their app, and why.
fn first_refused(jobs: &[RenderJob]) -> Option<(usize, String)> {
    let first = jobs.first()?;
    let first_dir = checked_dir(first);
    jobs.iter().enumerate().find_map(|(i, job)| {
        let alike = job.window == first.window
            && (!job.window || jobs.len() == 1)
            && job.webgpu_limits == first.webgpu_limits
            && job.disabled_features == first.disabled_features
            && job.forward == first.forward
            && job.mark_lights == first.mark_lights
            && job.read_photons == first.read_photons;
        let error = match (checked_dir(job), &first_dir) {
            (Err(e), _) => e,
            (Ok(d), Ok(f)) if d != *f => format!(
                "{}: a batch's scenes lie in one folder ({})",
                job.scene.display(),
                f.display()
            ),
            _ if !alike => format!(
                "{}: a batch's jobs are built alike (window, limits, features, forward, \
                 lights, photon readback), and a window renders one job",
                job.scene.display()
            ),
            _ => return None,
        };
        Some((i, error))
    })
}

/// Render `job`. Errors are one line, meant for the user; the sizes are checked first
/// ([`check_job`] against `job.limits`).
pub fn run(job: RenderJob) -> Result<RenderReport, String> {
    run_all(vec![job])
        .pop()
        .unwrap_or_else(|| Err("internal error: no result".into()))
}

/// The folder of `job`'s scene (the asset root), once the file and the job's sizes pass.
fn checked_dir(job: &RenderJob) -> Result<PathBuf, String> {
    if !job.scene.is_file() {
        return Err(format!("scene file not found: {}", job.scene.display()));
    }
    let ext = job
        .scene
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext != "gltf" && ext != "glb" {
        return Err(format!(
            "not a glTF file (.gltf or .glb): {}",
            job.scene.display()
        ));
    }
    check_job(job, &job.limits.clone().unwrap_or_default())?;
    // The asset root is the glTF's folder (its buffers and images resolve against it), as an
    // absolute path: relative to the working directory, whatever Bevy's own asset root is.
    let scene = std::fs::canonicalize(&job.scene)
        .map_err(|e| format!("cannot open {}: {e}", job.scene.display()))?;
    Ok(scene.parent().map(|p| p.to_path_buf()).unwrap_or_default())
}

/// One app for `jobs` (checked by [`run_all`]), built for the first.
fn run_app(mut jobs: Vec<RenderJob>) -> Vec<Result<RenderReport, String>> {
    let job = jobs.remove(0);
    let dir = checked_dir(&job).unwrap_or_default();
    let shared = Shared::default();
    let mut app = App::new();
    add_renderer(&mut app, &job, &dir);
    // No `DefaultOpaqueRendererMethod::deferred()` here: the plugin makes it the default.
    app.add_plugins((RenderDiagnosticsPlugin, CausticsPlugin));
    if job.forward {
        app.insert_resource(DefaultOpaqueRendererMethod::forward());
    }
    app.insert_resource(loading(&job))
        .insert_resource(Job(job.clone()))
        .insert_resource(Queue(jobs.into()))
        .insert_resource(shared.clone())
        .init_resource::<Phase>()
        .add_systems(Startup, start)
        .insert_resource(VolumeTemplate(
            job.technique == CausticsTechnique::Volume,
            job.volume.clone(),
        ))
        .init_resource::<VolumesFitted>()
        .add_systems(
            Update,
            (super::stage::stage, drive, super::volume::fit_volumes).chain(),
        );
    if job.mark_lights {
        app.add_systems(Update, crate::mark_every_light);
    }
    if let Some(hook) = job.app_hook {
        hook(&mut app);
    }
    super::render_watch::watch_render_world(&mut app, &shared);
    app.run();
    let Ok(mut o) = shared.0.lock() else {
        return vec![Err("internal error: poisoned state".to_string())];
    };
    let last = conclude(&mut o, job.window);
    let mut results = std::mem::take(&mut o.done);
    results.push(last);
    results
}

/// Bevy's plugins for `job` (its first job's settings, for a batch): offscreen and frame by
/// frame unless it opens a window, assets from `dir`.
fn add_renderer(app: &mut App, job: &RenderJob, dir: &std::path::Path) {
    let log = super::tool_log_plugin();
    let asset = AssetPlugin {
        file_path: dir.to_string_lossy().into_owned(),
        ..default()
    };
    let mut wgpu = bevy::render::settings::WgpuSettings::default();
    if job.webgpu_limits {
        wgpu.constrained_limits = Some(bevy::render::settings::WgpuLimits::default());
    }
    if !job.disabled_features.is_empty() {
        wgpu.disabled_features = Some(job.disabled_features);
        wgpu.features.remove(job.disabled_features);
    }
    let render = RenderPlugin {
        render_creation: wgpu.into(),
        synchronous_pipeline_compilation: true,
        ..default()
    };
    if job.window {
        app.add_plugins(DefaultPlugins.set(asset).set(render).set(log));
    } else {
        app.add_plugins(
            DefaultPlugins
                .set(asset)
                .set(render)
                .set(log)
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: ExitCondition::DontExit,
                    ..default()
                })
                .disable::<WinitPlugin>()
                // Frame by frame: the render world runs after the main world's frame, not
                // beside its next one, so each frame's dispatch log and readbacks are its own
                // however loaded the machine is.
                .disable::<PipelinedRenderingPlugin>(),
        )
        .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(
            1.0 / 240.0,
        )));
    }
}

/// Queued once a job has finished: the next job starts (or the app exits after the last).
pub(super) fn next_job(world: &mut World) {
    let Some(job) = world.resource_mut::<Queue>().0.pop_front() else {
        world.write_message(AppExit::Success);
        return;
    };
    let shared = world.resource::<Shared>().clone();
    if let Ok(mut o) = shared.0.lock() {
        o.close_job();
    }
    clear_job(world);
    world.insert_resource(VolumeTemplate(
        job.technique == CausticsTechnique::Volume,
        job.volume.clone(),
    ));
    world.insert_resource(loading(&job));
    world.insert_resource(Job(job));
    let _ = world.run_system_cached(start);
}

/// What the finished job left: its scene (with the glTF's lights and cameras), its cameras, the
/// volumes fitted for it, its stage; and the per-job state of the app's resources.
fn clear_job(world: &mut World) {
    let gone: Vec<Entity> = world
        .query_filtered::<Entity, Or<(
            With<JobScene>,
            With<JobCamera>,
            With<FittedVolume>,
            With<StagePart>,
        )>>()
        .iter(world)
        .collect();
    for e in gone {
        if let Ok(e) = world.get_entity_mut(e) {
            e.despawn();
        }
    }
    world.remove_resource::<StageLayout>();
    world.insert_resource(VolumesFitted::default());
    world.insert_resource(Phase::default());
    world.resource_mut::<CausticsWarnings>().messages.clear();
    if let Some(mut losses) = world.get_resource_mut::<CausticsLossCounters>() {
        losses.messages.clear();
    }
    world.resource::<CausticsDispatchLog>().take();
}
