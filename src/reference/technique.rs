//! The `Reference` technique in the app: runs the CPU tracer on a background task whenever
//! the scene, the camera or the settings change, and hands the image to the render world,
//! which uploads it into the view's caustics buffer.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use bevy::camera::Projection;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on, poll_once};
use glam::Affine3A;

use super::{CausticImage, TraceSettings, TraceStats, trace};
use crate::components::{Caustics, CausticsTechnique};
use crate::render::CausticsCpuImage;
use crate::scene::{CameraProjection, CausticsScene, TraceCamera};

/// The latest reference image of a camera (main world), with the scene generation it was
/// traced from. Extracted to the render world and uploaded when `serial` changes.
#[derive(Component, Clone, Debug)]
pub struct CausticsReferenceImage {
    /// Irradiance, lux.
    pub image: Arc<CausticImage>,
    /// Photon accounting of the render.
    pub stats: TraceStats,
    /// Increases with every new image.
    pub serial: u64,
    /// Wall-clock seconds the trace took.
    pub seconds: f64,
}

/// Progress of the reference render of a camera.
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub enum ReferenceStatus {
    /// Nothing to trace (no caustic light or no caster): nothing runs.
    #[default]
    Inactive,
    /// A trace is running on a background task.
    Tracing,
    /// The image for the current scene and camera is in `CausticsReferenceImage`.
    Ready,
}

/// Photons traced so far by the running reference render of a camera, and the total.
#[derive(Component, Clone, Debug)]
pub struct ReferenceProgress {
    /// Photons done (updated from the worker threads).
    pub done: Arc<AtomicU64>,
    /// Photons in this render.
    pub total: u64,
}

impl ReferenceProgress {
    /// Fraction done in [0, 1].
    pub fn fraction(&self) -> f64 {
        if self.total == 0 {
            1.0
        } else {
            self.done.load(Ordering::Relaxed) as f64 / self.total as f64
        }
    }
}

#[derive(Component)]
struct ReferenceTask {
    key: RenderKey,
    task: Task<(CausticImage, TraceStats, f64)>,
}

#[derive(Component, Clone, PartialEq)]
struct RenderKey {
    generation: u64,
    camera: TraceCamera,
    photons: u64,
    seed: u64,
}

/// The plain camera of a Bevy camera, if its size is known.
pub fn trace_camera(
    camera: &Camera,
    projection: &Projection,
    transform: &GlobalTransform,
) -> Option<TraceCamera> {
    let size = camera.physical_viewport_size()?;
    let projection = match projection {
        Projection::Perspective(p) => CameraProjection::Perspective { fov_y: p.fov },
        Projection::Orthographic(o) => CameraProjection::Orthographic {
            height: o.area.height(),
        },
        _ => return None,
    };
    let world_from_view: Affine3A = transform.affine();
    Some(TraceCamera {
        world_from_view,
        projection,
        width: size.x,
        height: size.y,
    })
}

#[allow(clippy::type_complexity)]
fn run_reference(
    mut commands: Commands,
    scene: Res<CausticsScene>,
    mut serial: Local<u64>,
    mut cameras: Query<(
        Entity,
        &Caustics,
        &Camera,
        &Projection,
        &GlobalTransform,
        Option<&RenderKey>,
        Option<&mut ReferenceTask>,
        Option<&mut ReferenceStatus>,
    )>,
) {
    for (entity, caustics, camera, projection, gt, done_key, task, status) in &mut cameras {
        if caustics.technique != CausticsTechnique::Reference {
            continue;
        }
        let mut e = commands.entity(entity);
        if !scene.is_active() {
            if status.as_deref() != Some(&ReferenceStatus::Inactive) {
                e.remove::<(
                    CausticsReferenceImage,
                    CausticsCpuImage,
                    ReferenceTask,
                    RenderKey,
                )>()
                .insert(ReferenceStatus::Inactive);
            }
            continue;
        }
        let Some(cam) = trace_camera(camera, projection, gt) else {
            continue;
        };
        let key = RenderKey {
            generation: scene.generation,
            camera: cam,
            photons: caustics.quality.photons_per_light(),
            seed: caustics.seed,
        };
        if let Some(mut t) = task {
            if let Some((image, stats, seconds)) = block_on(poll_once(&mut t.task)) {
                *serial += 1;
                let k = t.key.clone();
                let image = Arc::new(image);
                e.remove::<ReferenceTask>().insert((
                    CausticsCpuImage {
                        image: image.clone(),
                        serial: *serial,
                    },
                    CausticsReferenceImage {
                        image,
                        stats,
                        serial: *serial,
                        seconds,
                    },
                    k,
                    ReferenceStatus::Ready,
                ));
            } else if t.key == key {
                continue;
            }
            // A stale task is dropped (cancelled) below by the new one.
        }
        if done_key == Some(&key) {
            continue;
        }
        let scene = scene.clone();
        let photons = key.photons;
        let seed = key.seed;
        let progress = ReferenceProgress {
            done: Arc::new(AtomicU64::new(0)),
            total: photons * scene.lights.len() as u64,
        };
        let done = progress.done.clone();
        let task = AsyncComputeTaskPool::get().spawn(async move {
            let start = std::time::Instant::now();
            let lights: Vec<_> = scene.lights.iter().map(|(_, l)| *l).collect();
            let settings = TraceSettings {
                photons_per_light: photons,
                seed,
                ..default()
            };
            let report = |n: u64, _total: u64| done.store(n, Ordering::Relaxed);
            let out = trace(&scene.tlas, &lights, &cam, &settings, Some(&report));
            (out.image, out.stats, start.elapsed().as_secs_f64())
        });
        e.insert((
            ReferenceTask { key, task },
            ReferenceStatus::Tracing,
            progress,
        ));
    }
}

pub(crate) fn plugin(app: &mut App) {
    app.add_systems(
        PostUpdate,
        run_reference.in_set(crate::CausticsSystems::Technique),
    );
}
