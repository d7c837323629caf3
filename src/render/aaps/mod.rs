//! The `Aaps` technique (seed 004, adaptive anisotropic photon scattering) on the GPU without
//! ray-tracing hardware: compute-shader photon tracing through the scene BVH, anisotropic
//! splats rasterised into the caustics buffer, and a task buffer that adapts each light's ray
//! density every frame.
//!
//! Render-world only. Per frame and view (see [`passes`]): quadtree build from the density
//! atlas, emit + trace (indirect dispatch sized on the GPU), splat (indirect draws, small-splat
//! MSAA), variance by reprojection and the density update. Nothing is dispatched for a view
//! whose technique is not `Aaps`, or when no caustic light reaches a caster.
//!
//! **Work follows change** (`render::settle`; the dispatch log of each row is checked by
//! `tests/gpu/change.rs`):
//!
//! | what changed | what re-runs |
//! | --- | --- |
//! | nothing, for `Caustics::settle_frames` frames | nothing: the caustics buffer keeps the mean the temporal stage reached (`render::temporal`; each traced frame rotates its sample pattern, so the mean gathers independent photons) |
//! | the camera moved | task buffer, trace, splats, density update (culling, splat sizes and the task buffer's variance follow the view) |
//! | a light moved | everything |
//! | a caster moved | everything |
//! | a receiver moved | everything |
//! | a material changed | everything |

pub mod passes;
pub mod pipelines;
pub mod view;

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::render_resource::{TextureFormat, TextureFormatFeatureFlags, WgpuFeatures};
use bevy::render::renderer::{RenderAdapter, RenderDevice};
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

/// What the adapter offers AAPS (render world).
#[derive(Resource, Clone, Debug, Default)]
pub struct AapsSupport {
    /// `Rgba32Float` can be multisampled 4x, resolved and blended (small-splat MSAA).
    pub msaa: bool,
    /// Splats add into fixed-point atomics instead of blending (no `FLOAT32_BLENDABLE`;
    /// `render::fixed_splat`).
    pub fixed: bool,
}

/// What AAPS needs of the GPU, as a list of what is missing. (Without `FLOAT32_BLENDABLE` it
/// falls back to fixed-point splats, `render::fixed_splat`.)
pub fn missing_aaps_capabilities(storage_buffers: u32) -> Vec<String> {
    let mut missing = Vec::new();
    if storage_buffers < 8 {
        missing.push(format!(
            "max_storage_buffers_per_shader_stage >= 8 (have {storage_buffers})"
        ));
    }
    missing
}

/// Render-app part; called from [`crate::render::build`] after the capability gate.
/// Returns whether AAPS is on.
pub(crate) fn build(app: &mut App) -> bool {
    super::losses::register(
        app,
        &[
            super::losses::LossCounter {
                path: "render/caustics/aaps/budget_stopped",
                what: "AAPS paths stopped in a frame by the per-frame event budget (AapsSettings::bounce_budget): their light is missing from the caustic; raise the budget or lower the photon count",
                share_of: None,
            },
            super::losses::LossCounter {
                path: "render/caustics/aaps/max_depth",
                what: "AAPS paths ended in a frame at AapsSettings::max_bounces specular events (their flux is counted as lost)",
                share_of: None,
            },
        ],
    );
    let fixed = app
        .get_sub_app(RenderApp)
        .and_then(|r| r.world().get_resource::<super::fixed_splat::FixedSplats>())
        .is_some_and(|f| f.0);
    let (storage, msaa) = {
        let Some(render_app) = app.get_sub_app(RenderApp) else {
            return false;
        };
        let w = render_app.world();
        let (Some(device), Some(adapter)) = (
            w.get_resource::<RenderDevice>(),
            w.get_resource::<RenderAdapter>(),
        ) else {
            return false;
        };
        let f = adapter.get_texture_format_features(TextureFormat::Rgba32Float);
        let msaa = f.flags.sample_count_supported(4)
            && f.flags
                .contains(TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
            && device
                .features()
                .contains(WgpuFeatures::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
        (device.limits().max_storage_buffers_per_shader_stage, msaa)
    };
    let missing = missing_aaps_capabilities(storage);
    if !missing.is_empty() {
        warn!(
            "bevy_caustics: the Aaps technique is disabled: the GPU lacks {}",
            missing.join(", ")
        );
        return false;
    }
    if !msaa {
        warn!(
            "bevy_caustics: small-splat MSAA is off: Rgba32Float cannot be multisampled 4x and resolved here; small splats are drawn with the plain ones"
        );
    }
    // The MSAA pass blends its samples, so fixed-point splats draw every splat plainly.
    let msaa = msaa && !fixed;
    let shaders = {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        pipelines::AapsShaders {
            compute: shaders.add(Shader::from_wgsl(
                pipelines::compute_source(),
                "bevy_caustics/aaps_compute.wgsl",
            )),
            splat: shaders.add(Shader::from_wgsl(
                pipelines::splat_source(),
                "bevy_caustics/aaps_splat.wgsl",
            )),
        }
    };
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return false;
    };
    render_app
        .insert_resource(shaders)
        .insert_resource(AapsSupport { msaa, fixed })
        .add_systems(RenderStartup, pipelines::init_aaps_pipelines)
        .add_systems(
            Render,
            (
                view::prepare_aaps_views,
                pipelines::queue_aaps_trace_variant,
            )
                .in_set(RenderSystems::PrepareResources)
                .after(super::trace::prepare_trace_scene),
        )
        .add_systems(
            Core3d,
            passes::aaps_passes
                .in_set(Core3dSystems::MainPass)
                .after(deferred_lighting)
                .before(super::composite::composite_caustics),
        );
    true
}
