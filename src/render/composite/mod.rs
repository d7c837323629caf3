//! The composite pass: adds `albedo / π · E · exposure` into the lit HDR image.
//!
//! Runs in `Core3d` after `deferred_lighting` and before `main_opaque_pass_3d` (the slot SSR
//! uses), so forward and transparent passes, TAA and bloom see caustics as lighting. Only views
//! with an [`ExtractedCaustics`] and a filled [`ViewCausticsBuffer`] run it; shadow views and
//! views without `Caustics` never match its `ViewQuery`.

use bevy::asset::{embedded_asset, load_embedded_asset};
use bevy::core_pipeline::FullscreenShader;
use bevy::core_pipeline::core_3d::main_opaque_pass_3d;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::pbr::deferred::deferred_lighting;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, BlendComponent,
    BlendFactor, BlendOperation, BlendState, BufferInitDescriptor, BufferUsages,
    CachedRenderPipelineId, ColorTargetState, ColorWrites, FragmentState, PipelineCache,
    RenderPassDescriptor, RenderPipelineDescriptor, ShaderStages, SpecializedRenderPipeline,
    SpecializedRenderPipelines, TextureFormat, TextureSampleType, binding_types,
};
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::{GpuResourceAppExt, Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

use super::aaps::view::AapsFrame;
use super::image_space::view::ImageSpaceFrame;
use super::photon_map::view::PhotonMapFrame;
use super::volume::view::VolumeViewFrame;
use super::{CausticsDispatchLog, ExtractedCaustics, ViewCausticsBuffer};
use crate::components::CausticsTechnique;

/// GPU time span and dispatch-log name of this pass.
pub const COMPOSITE_PASS: &str = "caustics/composite";

/// The composite pipeline's shared objects.
#[derive(Resource)]
pub struct CompositePipeline {
    layout: BindGroupLayoutDescriptor,
    fragment: Handle<Shader>,
    fullscreen: FullscreenShader,
}

/// The specialised pipeline of a view.
#[derive(Component, Deref)]
pub struct CompositePipelineId(CachedRenderPipelineId);

fn init_composite_pipeline(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    fullscreen: Res<FullscreenShader>,
) {
    let layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:composite",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::FRAGMENT,
            (
                binding_types::texture_2d(TextureSampleType::Uint),
                binding_types::texture_2d(TextureSampleType::Float { filterable: false }),
                binding_types::uniform_buffer_sized(false, None),
            ),
        ),
    );
    commands.insert_resource(CompositePipeline {
        layout,
        fragment: load_embedded_asset!(asset_server.as_ref(), "composite.wgsl"),
        fullscreen: fullscreen.clone(),
    });
}

impl SpecializedRenderPipeline for CompositePipeline {
    type Key = TextureFormat;

    fn specialize(&self, format: TextureFormat) -> RenderPipelineDescriptor {
        let add = BlendComponent {
            src_factor: BlendFactor::One,
            dst_factor: BlendFactor::One,
            operation: BlendOperation::Add,
        };
        let keep = BlendComponent {
            src_factor: BlendFactor::Zero,
            dst_factor: BlendFactor::One,
            operation: BlendOperation::Add,
        };
        RenderPipelineDescriptor {
            label: Some("caustics:pipeline:composite".into()),
            layout: vec![self.layout.clone()],
            vertex: self.fullscreen.to_vertex_state(),
            fragment: Some(FragmentState {
                shader: self.fragment.clone(),
                targets: vec![Some(ColorTargetState {
                    format,
                    blend: Some(BlendState {
                        color: add,
                        alpha: keep,
                    }),
                    write_mask: ColorWrites::ALL,
                })],
                ..default()
            }),
            ..default()
        }
    }
}

pub(crate) fn prepare_composite_pipelines(
    mut commands: Commands,
    cache: Res<PipelineCache>,
    pipeline: Res<CompositePipeline>,
    mut pipelines: ResMut<SpecializedRenderPipelines<CompositePipeline>>,
    views: Query<(Entity, &ExtractedView), With<ExtractedCaustics>>,
) {
    for (entity, view) in &views {
        let id = pipelines.specialize(&cache, &pipeline, view.target_format);
        commands.entity(entity).insert(CompositePipelineId(id));
    }
}

/// The pass.
#[allow(clippy::type_complexity)]
pub fn composite_caustics(
    view: ViewQuery<(
        &ViewTarget,
        &ViewPrepassTextures,
        &ViewCausticsBuffer,
        &ExtractedCamera,
        &ExtractedCaustics,
        &CompositePipelineId,
        Option<&AapsFrame>,
        Option<&VolumeViewFrame>,
        Option<&ImageSpaceFrame>,
        Option<&PhotonMapFrame>,
        Option<&crate::render::settle::ViewSettle>,
    )>,
    cache: Res<PipelineCache>,
    pipeline: Res<CompositePipeline>,
    log: Res<CausticsDispatchLog>,
    settle: Res<crate::render::span::SpanSettle>,
    mut ctx: RenderContext,
) {
    let (
        target,
        prepass,
        buffer,
        camera,
        caustics,
        id,
        aaps,
        volume,
        image_space,
        photon_map,
        view_settle,
    ) = view.into_inner();
    let (Some(render_pipeline), Some(gbuffer)) =
        (cache.get_render_pipeline(**id), prepass.deferred_view())
    else {
        return;
    };
    let filled = match caustics.technique {
        // The image is not in the buffer yet (size mismatch while the view resizes).
        CausticsTechnique::Reference => buffer.uploaded != 0,
        // AAPS fills it this frame, or has nothing to do.
        CausticsTechnique::Aaps => aaps.is_some(),
        // Volumes fill it this frame, or none is visible.
        CausticsTechnique::Volume => volume.is_some(),
        // Image-space tracing fills it this frame, or no light reaches a caster.
        CausticsTechnique::ImageSpace => image_space.is_some(),
        // The photon map fills it this frame, or no light reaches a caster.
        CausticsTechnique::PhotonMap => photon_map.is_some(),
    } || view_settle.is_some_and(|s| s.kept());
    if !filled || caustics.hidden {
        return;
    }
    let mut params = [0u8; 16];
    params[0..4].copy_from_slice(&camera.exposure.to_le_bytes());
    params[4..8].copy_from_slice(&(caustics.white_albedo as u32).to_le_bytes());
    let uniform = ctx
        .render_device()
        .create_buffer_with_data(&BufferInitDescriptor {
            label: Some("caustics:buffer:composite_params"),
            contents: &params,
            usage: BufferUsages::UNIFORM,
        });
    let bind_group = ctx.render_device().create_bind_group(
        "caustics:bind_group:composite",
        &cache.get_bind_group_layout(&pipeline.layout),
        &BindGroupEntries::sequential((gbuffer, &buffer.view, uniform.as_entire_binding())),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("caustics_composite"),
        // Load and store: the lit image is kept and caustics are blended on top.
        color_attachments: &[Some(target.get_color_attachment())],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let span = diagnostics.pass_span(&mut pass, COMPOSITE_PASS);
    settle.settle(&mut pass);
    pass.set_render_pipeline(render_pipeline);
    pass.set_bind_group(0, &bind_group, &[]);
    pass.draw(0..3, 0..1);
    span.end(&mut pass);
    log.record(COMPOSITE_PASS);
}

pub(super) fn build(app: &mut App) {
    embedded_asset!(app, "composite.wgsl");
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .init_gpu_resource::<SpecializedRenderPipelines<CompositePipeline>>()
        .add_systems(RenderStartup, init_composite_pipeline)
        .add_systems(
            Render,
            prepare_composite_pipelines.in_set(RenderSystems::Prepare),
        )
        .add_systems(
            Core3d,
            composite_caustics
                .in_set(Core3dSystems::MainPass)
                // Needs the lit image; must land before forward passes read the screen.
                .after(deferred_lighting)
                .before(main_opaque_pass_3d),
        );
}
