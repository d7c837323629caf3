//! The caustics-volume pipelines (created in `RenderStartup`): the compute module
//! (`propagate`, `write_args`, `project`), the raster module (G-buffers and splats) and the
//! blur.

use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, BlendComponent, BlendFactor, BlendOperation,
    BlendState, CachedComputePipelineId, CachedRenderPipelineId, ColorTargetState, ColorWrites,
    CompareFunction, ComputePipelineDescriptor, DepthStencilState, FragmentState, PipelineCache,
    RenderPipelineDescriptor, ShaderStages, TextureFormat, TextureSampleType, VertexState,
    binding_types,
};
use bevy::shader::Shader;

use crate::render::CAUSTICS_BUFFER_FORMAT;

/// Format of the G-buffers: depth along the probe axis, normal x, y, ±(instance + 1).
pub const GBUFFER_FORMAT: TextureFormat = TextureFormat::Rgba32Float;
/// Depth attachment of the G-buffer passes.
pub const GBUFFER_DEPTH_FORMAT: TextureFormat = TextureFormat::Depth32Float;

/// WGSL of the compute module.
pub fn compute_source() -> String {
    [
        include_str!("../optics.wgsl"),
        include_str!("common.wgsl"),
        include_str!("propagate.wgsl"),
    ]
    .join("\n")
}

/// WGSL of the raster module.
pub fn raster_source() -> String {
    [
        include_str!("../optics.wgsl"),
        include_str!("common.wgsl"),
        crate::render::fixed_splat::fragment_source(),
        include_str!("raster.wgsl"),
    ]
    .join("\n")
}

/// Shader handles, added to `Assets<Shader>` by the plugin.
#[derive(Resource, Clone)]
pub struct VolumeShaders {
    /// Compute module.
    pub compute: Handle<Shader>,
    /// G-buffer and splat module.
    pub raster: Handle<Shader>,
    /// Blur.
    pub blur: Handle<Shader>,
}

/// Layouts and pipeline ids.
#[derive(Resource)]
pub struct VolumePipelines {
    /// Group 0 of the compute passes.
    pub compute_layout: BindGroupLayoutDescriptor,
    /// Group 1 (indirect arguments) of `write_args`.
    pub args_layout: BindGroupLayoutDescriptor,
    /// G-buffer passes.
    pub gbuffer_layout: BindGroupLayoutDescriptor,
    /// Splat pass.
    pub splat_layout: BindGroupLayoutDescriptor,
    /// Blur pass.
    pub blur_layout: BindGroupLayoutDescriptor,
    /// `propagate`, `write_args`, `project`.
    pub compute: [CachedComputePipelineId; 3],
    /// G-buffer keeping the nearest surface (G_near, projectors).
    pub gbuffer_near: CachedRenderPipelineId,
    /// G-buffer keeping the farthest surface (G_far).
    pub gbuffer_far: CachedRenderPipelineId,
    /// Splats into the volume target.
    pub splat: CachedRenderPipelineId,
    /// Blur into the caustics buffer.
    pub blur: CachedRenderPipelineId,
}

/// Queue the pipelines the first time a camera uses volumes (in `PrepareResources`): an app
/// that never does creates none of them.
pub(crate) fn queue_volume_pipelines(
    mut commands: Commands,
    shaders: Res<VolumeShaders>,
    cache: Res<PipelineCache>,
    fixed: Option<Res<crate::render::fixed_splat::FixedSplats>>,
    existing: Option<Res<VolumePipelines>>,
    views: Query<&crate::render::ExtractedCaustics>,
) {
    if existing.is_some()
        || !views
            .iter()
            .any(|c| c.technique == crate::CausticsTechnique::Volume)
    {
        return;
    }
    let fixed = fixed.is_some_and(|f| f.0);
    use binding_types::*;
    let ro = || storage_buffer_read_only_sized(false, None);
    let rw = || storage_buffer_sized(false, None);
    let array = || texture_2d_array(TextureSampleType::Float { filterable: false });
    let compute_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, None),
                uniform_buffer_sized(true, None),
                ro(),
                rw(),
                rw(),
                rw(),
                rw(),
                rw(),
                rw(),
                array(),
                array(),
            ),
        ),
    );
    let args_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume_args",
        &BindGroupLayoutEntries::sequential(ShaderStages::COMPUTE, (rw(),)),
    );
    let gbuffer_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume_gbuffer",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::VERTEX_FRAGMENT,
            (
                (0, uniform_buffer_sized(false, None)),
                (1, uniform_buffer_sized(true, None)),
                (2, ro()),
            ),
        ),
    );
    let splat_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume_splat",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::VERTEX_FRAGMENT,
            (
                (0, uniform_buffer_sized(false, None)),
                (3, uniform_buffer_sized(false, None)),
                (4, ro()),
                (5, ro()),
                (6, texture_depth_2d()),
            ),
        ),
    );
    let blur_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume_blur",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::FRAGMENT,
            (
                texture_2d(TextureSampleType::Float { filterable: false }),
                texture_depth_2d(),
                texture_2d(TextureSampleType::Uint),
                uniform_buffer_sized(false, None),
            ),
        ),
    );
    let compute = ["propagate", "write_args", "project"].map(|entry| {
        let mut layout = vec![compute_layout.clone()];
        if entry == "write_args" {
            layout.push(args_layout.clone());
        }
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(format!("caustics:pipeline:volume_{entry}").into()),
            layout,
            shader: shaders.compute.clone(),
            entry_point: Some(entry.into()),
            ..default()
        })
    });
    let gbuffer = |label: &'static str, compare: CompareFunction| {
        cache.queue_render_pipeline(RenderPipelineDescriptor {
            label: Some(label.into()),
            layout: vec![gbuffer_layout.clone()],
            vertex: VertexState {
                shader: shaders.raster.clone(),
                entry_point: Some("vs_gbuffer".into()),
                ..default()
            },
            fragment: Some(FragmentState {
                shader: shaders.raster.clone(),
                entry_point: Some("fs_gbuffer".into()),
                targets: vec![Some(ColorTargetState {
                    format: GBUFFER_FORMAT,
                    blend: None,
                    write_mask: ColorWrites::ALL,
                })],
                ..default()
            }),
            depth_stencil: Some(DepthStencilState {
                format: GBUFFER_DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(compare),
                stencil: default(),
                bias: default(),
            }),
            ..default()
        })
    };
    let gbuffer_near = gbuffer(
        "caustics:pipeline:volume_gbuffer_near",
        CompareFunction::Less,
    );
    let gbuffer_far = gbuffer(
        "caustics:pipeline:volume_gbuffer_far",
        CompareFunction::Greater,
    );
    let splat = splat_pipeline(&cache, &shaders, &splat_layout, fixed);
    let blur = cache.queue_render_pipeline(RenderPipelineDescriptor {
        label: Some("caustics:pipeline:volume_blur".into()),
        layout: vec![blur_layout.clone()],
        vertex: VertexState {
            shader: shaders.blur.clone(),
            entry_point: Some("vs_full".into()),
            ..default()
        },
        fragment: Some(FragmentState {
            shader: shaders.blur.clone(),
            entry_point: Some("fs_blur".into()),
            targets: vec![Some(ColorTargetState {
                format: CAUSTICS_BUFFER_FORMAT,
                blend: None,
                write_mask: ColorWrites::ALL,
            })],
            ..default()
        }),
        ..default()
    });
    commands.insert_resource(VolumePipelines {
        compute_layout,
        args_layout,
        gbuffer_layout,
        splat_layout,
        blur_layout,
        compute,
        gbuffer_near,
        gbuffer_far,
        splat,
        blur,
    });
}

/// The splat pipeline: additive blending into the view's volume target, or without
/// `FLOAT32_BLENDABLE` (`fixed`) fixed-point atomics in group 1 (`render::fixed_splat`).
fn splat_pipeline(
    cache: &PipelineCache,
    shaders: &VolumeShaders,
    splat_layout: &BindGroupLayoutDescriptor,
    fixed: bool,
) -> CachedRenderPipelineId {
    let add = BlendComponent {
        src_factor: BlendFactor::One,
        dst_factor: BlendFactor::One,
        operation: BlendOperation::Add,
    };
    // Without FLOAT32_BLENDABLE the splats add into fixed-point atomics (group 1) and write
    // nothing to the target (`render::fixed_splat`).
    let (layout, entry, blend, write_mask) = if fixed {
        (
            vec![
                splat_layout.clone(),
                crate::render::fixed_splat::fragment_layout(),
            ],
            "fs_splat_fixed",
            None,
            ColorWrites::empty(),
        )
    } else {
        (
            vec![splat_layout.clone()],
            "fs_splat",
            Some(BlendState {
                color: add,
                alpha: add,
            }),
            ColorWrites::ALL,
        )
    };
    cache.queue_render_pipeline(RenderPipelineDescriptor {
        label: Some("caustics:pipeline:volume_splat".into()),
        layout,
        vertex: VertexState {
            shader: shaders.raster.clone(),
            entry_point: Some("vs_splat".into()),
            ..default()
        },
        fragment: Some(FragmentState {
            shader: shaders.raster.clone(),
            entry_point: Some(entry.into()),
            targets: vec![Some(ColorTargetState {
                format: CAUSTICS_BUFFER_FORMAT,
                blend,
                write_mask,
            })],
            ..default()
        }),
        ..default()
    })
}
