//! The `Volume` technique (seed 000, caustics volumes) on the GPU: photons seeded on each
//! volume's entry face, slab G-buffers rasterised by orthographic probes (no ray tracing),
//! texture-space propagation chained by indirect dispatches, exit-face projectors, density
//! tiles, oriented splats and a depth- and normal-aware blur into the caustics buffer.
//!
//! Render-world only. Per frame (see [`passes`]): only what changed re-runs (section 3.5), the
//! splats and the blur are drawn for every volume camera. Nothing runs for a view whose
//! technique is not `Volume`, without a volume, without a caustic light, or for a volume
//! outside every volume camera's frustum.
//!
//! **Work follows change** (section 3.5's differential updates and `render::settle`; the
//! dispatch log of each row is checked by `tests/gpu/change.rs`):
//!
//! | what changed | what re-runs |
//! | --- | --- |
//! | nothing, for `Caustics::settle_frames` frames | nothing: the caustics buffer keeps the last splats (before that: splat and blur) |
//! | the camera moved | splat, blur |
//! | a light moved | every slab, the projectors, splat, blur |
//! | a caster moved | the slabs from the caster's on, the projectors, splat, blur |
//! | a receiver moved | the slabs whose G-buffers see it (none for a floor below the slabs), the projectors, splat, blur |
//! | a material changed | the slabs from its caster's on, the projectors, splat, blur |

pub mod gizmo;
pub mod gpu;
pub mod passes;
pub mod pipelines;
pub mod view;

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderSystems};
use bevy::shader::Shader;

use crate::components::CausticsVolume;
use view::{ExtractedVolumes, VolumeStore};

fn extract_volumes(
    mut commands: Commands,
    volumes: Extract<Query<(Entity, &CausticsVolume, &GlobalTransform)>>,
) {
    commands.insert_resource(ExtractedVolumes(
        volumes
            .iter()
            .map(|(e, v, t)| (e, v.clone(), t.affine()))
            .collect(),
    ));
}

/// Render-app part; called from [`crate::render::build`] when AAPS (whose scene extraction
/// and float-blending requirement it shares) is available.
pub(crate) fn build(app: &mut App) {
    let shaders = {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        pipelines::VolumeShaders {
            compute: shaders.add(Shader::from_wgsl(
                pipelines::compute_source(),
                "bevy_caustics/volume_compute.wgsl",
            )),
            raster: shaders.add(Shader::from_wgsl(
                pipelines::raster_source(),
                "bevy_caustics/volume_raster.wgsl",
            )),
            blur: shaders.add(Shader::from_wgsl(
                [include_str!("../gbuffer.wgsl"), include_str!("blur.wgsl")].join("\n"),
                "bevy_caustics/volume_blur.wgsl",
            )),
        }
    };
    gizmo::build(app);
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(shaders)
        .init_resource::<VolumeStore>()
        .add_systems(ExtractSchedule, extract_volumes)
        .add_systems(
            Render,
            (pipelines::queue_volume_pipelines, view::prepare_volumes)
                .in_set(RenderSystems::PrepareResources)
                .after(super::prepare_caustics_buffers)
                .after(super::trace::prepare_trace_scene),
        )
        .add_systems(
            Core3d,
            passes::volume_passes
                .in_set(Core3dSystems::MainPass)
                .after(deferred_lighting)
                .before(super::composite::composite_caustics),
        );
}
