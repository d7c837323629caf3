//! The image-space pipelines (created in `RenderStartup`): the RSM raster module (three
//! layers) and the compute module (`trace`, `resolve`, and SVGF's `temporal`, `variance`,
//! `atrous`), all compute passes on one bind-group layout.

use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedComputePipelineId,
    CachedRenderPipelineId, ColorTargetState, ColorWrites, CompareFunction,
    ComputePipelineDescriptor, DepthStencilState, FragmentState, PipelineCache,
    RenderPipelineDescriptor, ShaderStages, StorageTextureAccess, TextureFormat, TextureSampleType,
    VertexState, binding_types,
};
use bevy::shader::Shader;

/// Format of the RSM layers: view depth along the light's axis, normal x, y, ±(instance + 1).
pub const RSM_FORMAT: TextureFormat = TextureFormat::Rgba32Float;
/// Depth attachment of the RSM passes.
pub const RSM_DEPTH_FORMAT: TextureFormat = TextureFormat::Depth32Float;
/// Format of the denoiser's textures.
pub const SVGF_FORMAT: TextureFormat = TextureFormat::Rgba32Float;

/// WGSL of the compute module.
pub fn compute_source() -> String {
    [
        include_str!("../optics.wgsl"),
        include_str!("../gbuffer.wgsl"),
        include_str!("trace.wgsl"),
        include_str!("march.wgsl"),
        include_str!("svgf.wgsl"),
    ]
    .join("\n")
}

/// WGSL of the RSM raster module.
pub fn rsm_source() -> String {
    [include_str!("../optics.wgsl"), include_str!("rsm.wgsl")].join("\n")
}

/// Shader handles, added to `Assets<Shader>` by the plugin.
#[derive(Resource, Clone)]
pub struct ImageSpaceShaders {
    /// Compute module.
    pub compute: Handle<Shader>,
    /// RSM raster module.
    pub rsm: Handle<Shader>,
}

/// The compute entry points but the trace, in [`ImageSpacePipelines::compute`] order.
pub const COMPUTE_ENTRIES: [&str; 6] = [
    "resolve",
    "temporal",
    "variance",
    "atrous_prep",
    "atrous",
    "hiz_build",
];

/// Layouts and pipeline ids.
#[derive(Resource)]
pub struct ImageSpacePipelines {
    /// Group 0 of every compute pass.
    pub compute_layout: BindGroupLayoutDescriptor,
    /// Group 0 of the RSM passes.
    pub rsm_layout: BindGroupLayoutDescriptor,
    /// [`COMPUTE_ENTRIES`].
    pub compute: [CachedComputePipelineId; 6],
    /// `trace`, specialised by the scene (`render::trace::TraceFeatures`: without a
    /// dielectric, no refraction, Fresnel split, caster-back march or Beer-Lambert), queued by
    /// `queue_image_space_trace_variant` the first time a scene needs the variant.
    pub trace: crate::render::trace::TraceVariants,
    /// Opaque, caster-front and caster-back RSM layers.
    pub rsm: [CachedRenderPipelineId; 3],
}

/// Create the layouts and queue the pipelines but the trace at `RenderStartup` (the trace is
/// queued per scene variant by [`queue_image_space_trace_variant`]). Queued lazily on first
/// use, the RSM pipelines sometimes became ready a frame later than the compute ones, which
/// shifted the first traced frame between otherwise identical runs.
pub(crate) fn init_image_space_pipelines(
    mut commands: Commands,
    shaders: Res<ImageSpaceShaders>,
    cache: Res<PipelineCache>,
) {
    use binding_types::*;
    let tex = || texture_2d(TextureSampleType::Float { filterable: false });
    let out = || texture_storage_2d(SVGF_FORMAT, StorageTextureAccess::WriteOnly);
    let compute_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:image_space",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, None),
                uniform_buffer_sized(true, None),
                texture_2d_array(TextureSampleType::Float { filterable: false }),
                texture_depth_2d(),
                texture_2d(TextureSampleType::Uint),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                tex(),
                tex(),
                tex(),
                tex(),
                out(),
                out(),
                out(),
                uniform_buffer_sized(true, None),
                storage_buffer_sized(false, None),
                storage_buffer_read_only_sized(false, None),
            ),
        ),
    );
    let rsm_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:image_space_rsm",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer_sized(true, None),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
            ),
        ),
    );
    let compute = COMPUTE_ENTRIES.map(|entry| {
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(format!("caustics:pipeline:image_space_{entry}").into()),
            layout: vec![compute_layout.clone()],
            shader: shaders.compute.clone(),
            entry_point: Some(entry.into()),
            ..default()
        })
    });
    let rsm = ["fs_opaque", "fs_front", "fs_back"].map(|entry| {
        cache.queue_render_pipeline(RenderPipelineDescriptor {
            label: Some(format!("caustics:pipeline:image_space_rsm_{entry}").into()),
            layout: vec![rsm_layout.clone()],
            vertex: VertexState {
                shader: shaders.rsm.clone(),
                entry_point: Some("vs_rsm".into()),
                ..default()
            },
            fragment: Some(FragmentState {
                shader: shaders.rsm.clone(),
                entry_point: Some(entry.into()),
                targets: vec![Some(ColorTargetState {
                    format: RSM_FORMAT,
                    blend: None,
                    write_mask: ColorWrites::ALL,
                })],
                ..default()
            }),
            depth_stencil: Some(DepthStencilState {
                format: RSM_DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(CompareFunction::Less),
                stencil: default(),
                bias: default(),
            }),
            ..default()
        })
    });
    commands.insert_resource(ImageSpacePipelines {
        compute_layout,
        rsm_layout,
        compute,
        rsm,
        trace: Default::default(),
    });
}

/// Queue the `trace` variant the scene needs (in `PrepareResources`).
pub(crate) fn queue_image_space_trace_variant(
    pipelines: Option<ResMut<ImageSpacePipelines>>,
    shaders: Res<ImageSpaceShaders>,
    cache: Res<PipelineCache>,
    scene: Option<Res<super::view::ImageSpaceScene>>,
    specialization: Option<Res<crate::render::trace::TraceSpecialization>>,
) {
    let (Some(mut pipelines), Some(scene)) = (pipelines, scene) else {
        return;
    };
    let features = trace_features(&scene, specialization.as_deref());
    let layout = pipelines.compute_layout.clone();
    pipelines
        .trace
        .get_or_queue(features, &cache, |shader_defs| ComputePipelineDescriptor {
            label: Some("caustics:pipeline:image_space_trace".into()),
            layout: vec![layout],
            shader: shaders.compute.clone(),
            shader_defs,
            entry_point: Some("trace".into()),
            ..default()
        });
}

/// The trace variant for `scene`: its dielectrics and whether a reflected photon may meet a
/// caster again (the light kinds share one code path), or everything when specialisation is
/// off.
pub fn trace_features(
    scene: &super::view::ImageSpaceScene,
    specialization: Option<&crate::render::trace::TraceSpecialization>,
) -> crate::render::trace::TraceFeatures {
    if specialization.is_some_and(|s| !s.0) {
        crate::render::trace::TraceFeatures::ALL
    } else {
        crate::render::trace::TraceFeatures {
            dielectrics: scene.dielectrics,
            point_lights: true,
            caster_chains: scene.mirror_chains,
        }
    }
}
