//! The volume gizmo pass (debug view): every extracted [`crate::CausticsVolume`]'s lines
//! ([`volume_gizmo_segments`]) drawn into the view target after tone mapping, for cameras with
//! [`CausticsVolumeGizmos`]. Views without the component, or frames without a volume, run
//! nothing.

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::core_pipeline::tonemapping::tonemapping;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::extract_component::ExtractComponentPlugin;
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer, BufferDescriptor,
    BufferUsages, CachedRenderPipelineId, ColorTargetState, ColorWrites, FragmentState, LoadOp,
    Operations, PipelineCache, PrimitiveState, PrimitiveTopology, RenderPassColorAttachment,
    RenderPipelineDescriptor, ShaderStages, StoreOp, TextureFormat, VertexState, binding_types,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

use super::view::ExtractedVolumes;
use crate::components::CausticsVolumeGizmos;
use crate::render::CausticsDispatchLog;
use crate::volume::volume_gizmo_segments;

/// Span and log name of the pass.
pub const GIZMO_PASS: &str = "caustics/volume/gizmos";
/// Format of the view target the lines are drawn into: a `Caustics` camera requires `Hdr`,
/// whose main textures are `Rgba16Float` (other views are skipped).
const TARGET_FORMAT: TextureFormat = TextureFormat::Rgba16Float;
/// Margin of the depth test, a fraction of the distance.
const DEPTH_MARGIN: f32 = 0.005;

/// Per-view state: the line vertices and the view's uniforms.
#[derive(Component)]
pub struct VolumeGizmoView {
    /// Two `vec4` per vertex: position, linear colour.
    pub vertices: Buffer,
    /// Vertices it holds room for.
    pub capacity: u32,
    /// Vertices this frame.
    pub count: u32,
    /// `GizmoParams`.
    pub params: Buffer,
}

#[derive(Resource)]
struct GizmoPipeline {
    layout: BindGroupLayoutDescriptor,
    id: CachedRenderPipelineId,
}

#[derive(Resource)]
struct GizmoShader(Handle<Shader>);

fn init_gizmo_pipeline(
    mut commands: Commands,
    cache: Res<PipelineCache>,
    shader: Res<GizmoShader>,
) {
    use binding_types::{storage_buffer_read_only_sized, texture_depth_2d, uniform_buffer_sized};
    let layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:volume_gizmos",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::VERTEX_FRAGMENT,
            (
                uniform_buffer_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                texture_depth_2d(),
            ),
        ),
    );
    let id = cache.queue_render_pipeline(RenderPipelineDescriptor {
        label: Some("caustics:pipeline:volume_gizmos".into()),
        layout: vec![layout.clone()],
        vertex: VertexState {
            shader: shader.0.clone(),
            entry_point: Some("vs_line".into()),
            ..default()
        },
        fragment: Some(FragmentState {
            shader: shader.0.clone(),
            entry_point: Some("fs_line".into()),
            targets: vec![Some(ColorTargetState {
                format: TARGET_FORMAT,
                blend: None,
                write_mask: ColorWrites::ALL,
            })],
            ..default()
        }),
        primitive: PrimitiveState {
            topology: PrimitiveTopology::LineList,
            ..default()
        },
        ..default()
    });
    commands.insert_resource(GizmoPipeline { layout, id });
}

/// The lines of every volume for each gizmo view, written on the GPU.
pub(crate) fn prepare_volume_gizmos(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    volumes: Option<Res<ExtractedVolumes>>,
    mut views: Query<(
        Entity,
        &CausticsVolumeGizmos,
        &ExtractedView,
        Option<&mut VolumeGizmoView>,
    )>,
) {
    let volumes = volumes.as_deref().map_or(&[][..], |v| v.0.as_slice());
    for (entity, settings, view, state) in &mut views {
        let mut data: Vec<f32> = Vec::new();
        for (_, volume, affine) in volumes {
            for s in
                volume_gizmo_segments(affine, volume, settings.inset, settings.show_slab_planes)
            {
                let c = settings.colour(s.kind).to_linear();
                for p in [s.a, s.b] {
                    data.extend([p.x, p.y, p.z, 1.0]);
                    data.extend([c.red, c.green, c.blue, c.alpha]);
                }
            }
        }
        let count = (data.len() / 8) as u32;
        if count == 0 {
            commands.entity(entity).remove::<VolumeGizmoView>();
            continue;
        }
        let mut fresh = None;
        let state = match state {
            Some(s) if s.capacity >= count => s.into_inner(),
            _ => {
                let capacity = count.next_power_of_two();
                fresh = Some(VolumeGizmoView {
                    vertices: device.create_buffer(&BufferDescriptor {
                        label: Some("caustics:buffer:volume_gizmo_vertices"),
                        size: capacity as u64 * 32,
                        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    capacity,
                    count,
                    params: device.create_buffer(&BufferDescriptor {
                        label: Some("caustics:buffer:volume_gizmo_params"),
                        size: 80,
                        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                });
                fresh.as_mut().unwrap()
            }
        };
        state.count = count;
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        queue.write_buffer(&state.vertices, 0, &bytes);
        let clip = crate::render::clip_from_world(view);
        let test = [settings.depth_test as u32 as f32, DEPTH_MARGIN, 0.0, 0.0];
        let params: Vec<u8> = clip
            .to_cols_array()
            .into_iter()
            .chain(test)
            .flat_map(|v| v.to_le_bytes())
            .collect();
        queue.write_buffer(&state.params, 0, &params);
        if let Some(s) = fresh {
            commands.entity(entity).insert(s);
        }
    }
}

/// Draw the lines into the tone-mapped target.
fn volume_gizmo_pass(
    view: ViewQuery<(&ViewTarget, &ViewPrepassTextures, &VolumeGizmoView)>,
    pipeline: Res<GizmoPipeline>,
    cache: Res<PipelineCache>,
    log: Res<CausticsDispatchLog>,
    settle: Res<crate::render::span::SpanSettle>,
    mut ctx: RenderContext,
) {
    let (target, prepass, state) = view.into_inner();
    let Some(depth) = prepass.depth.as_ref() else {
        return;
    };
    // The pipeline is built for the HDR target and a single-sampled depth (Caustics' needs).
    if target.main_texture_format() != TARGET_FORMAT || depth.texture.texture.sample_count() != 1 {
        return;
    }
    let Some(render) = cache.get_render_pipeline(pipeline.id) else {
        return;
    };
    let group = ctx.render_device().create_bind_group(
        "caustics:bind_group:volume_gizmos",
        &cache.get_bind_group_layout(&pipeline.layout),
        &BindGroupEntries::sequential((
            state.params.as_entire_binding(),
            state.vertices.as_entire_binding(),
            &depth.texture.default_view,
        )),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    // The tone-mapped image is loaded and kept; the lines are drawn on top. (Not
    // `ViewTarget::get_color_attachment`: tone mapping wrote the texture directly, so its
    // attachment's first call would clear it.)
    let mut pass = ctx.begin_tracked_render_pass(super::passes::colour_pass(
        "caustics_volume_gizmos",
        &[Some(RenderPassColorAttachment {
            view: target.main_texture_view(),
            depth_slice: None,
            resolve_target: None,
            ops: Operations {
                load: LoadOp::Load,
                store: StoreOp::Store,
            },
        })],
    ));
    let span = diagnostics.pass_span(&mut pass, GIZMO_PASS);
    settle.settle(&mut pass);
    pass.set_render_pipeline(render);
    pass.set_bind_group(0, &group, &[]);
    pass.draw(0..state.count, 0..1);
    span.end(&mut pass);
    log.record(GIZMO_PASS);
}

/// Main- and render-app parts.
pub(crate) fn build(app: &mut App) {
    app.add_plugins(ExtractComponentPlugin::<CausticsVolumeGizmos>::default());
    let shader = app
        .world_mut()
        .resource_mut::<Assets<Shader>>()
        .add(Shader::from_wgsl(
            include_str!("gizmo.wgsl"),
            "bevy_caustics/volume_gizmo.wgsl",
        ));
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(GizmoShader(shader))
        .add_systems(RenderStartup, init_gizmo_pipeline)
        .add_systems(
            Render,
            prepare_volume_gizmos.in_set(RenderSystems::PrepareResources),
        )
        .add_systems(
            Core3d,
            volume_gizmo_pass
                .in_set(Core3dSystems::PostProcess)
                .after(tonemapping),
        );
}
