//! The AAPS passes of one view, in `Core3d` after the prepass (the splats need the view depth)
//! and before the composite. No CPU readback: the photon and splat counts stay on the GPU and
//! drive the indirect dispatches and draws.

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::prelude::*;
use bevy::render::diagnostic::{DiagnosticsRecorder, RecordDiagnostics};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupEntry, BindingResource, BufferBinding,
    ComputePassDescriptor, ComputePipeline, Extent3d, LoadOp, Operations, PipelineCache,
    RenderPassColorAttachment, RenderPassDescriptor, RenderPipeline, StoreOp, TexelCopyTextureInfo,
    TextureView,
};
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};

use super::pipelines::AapsPipelines;
use super::view::{AapsFrame, AapsStereo, AapsViewState, LEVEL_STRIDE};
use crate::render::fixed_splat::{self, FixedSplatPipelines};
use crate::render::settle::ViewSettle;
use crate::render::span::SpanSettle;
use crate::render::temporal::{self, TemporalPipelines, ViewTemporal};
use crate::render::trace::scene::TraceSceneBuffers;
use crate::render::trace::{TraceFeatures, TraceSpecialization, wanted_features};
use crate::render::{CausticsDispatchLog, ViewCausticsBuffer};

/// GPU span and log names of the passes.
pub const TASK_PASS: &str = "caustics/aaps/task_buffer";
/// Emit and trace (with the argument writers).
pub const TRACE_PASS: &str = "caustics/aaps/trace";
/// Plain splats.
pub const SPLAT_PASS: &str = "caustics/aaps/splat";
/// Small splats into the MSAA target, resolved into the caustics buffer.
pub const SPLAT_MSAA_PASS: &str = "caustics/aaps/splat_msaa";
/// Variance and density update.
pub const UPDATE_PASS: &str = "caustics/aaps/update";
/// Every AAPS pass, in order.
pub const ALL_PASSES: [&str; 5] = [
    TASK_PASS,
    TRACE_PASS,
    SPLAT_MSAA_PASS,
    SPLAT_PASS,
    UPDATE_PASS,
];

/// Names of the counters read into diagnostics (`render/caustics/aaps/<name>`), with their word
/// in the `accum` buffer (`C_*` in common.wgsl).
pub const COUNTERS: [(&str, u64); 14] = [
    ("caustics/aaps/tasks", 0),
    ("caustics/aaps/photons_emitted", 1),
    ("caustics/aaps/splats_plain", 3),
    ("caustics/aaps/splats_msaa", 4),
    ("caustics/aaps/splat_overflow", 5),
    ("caustics/aaps/culled_frustum", 6),
    ("caustics/aaps/culled_size", 7),
    ("caustics/aaps/dropped", 8),
    ("caustics/aaps/clamped", 9),
    ("caustics/aaps/nan_guards", 10),
    ("caustics/aaps/photon_overflow", 14),
    ("caustics/aaps/max_depth", 11),
    ("caustics/aaps/events", 29),
    ("caustics/aaps/budget_stopped", 30),
];

/// All passes of the view.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn aaps_passes(
    view: ViewQuery<(
        &ViewCausticsBuffer,
        &ViewPrepassTextures,
        &AapsViewState,
        &AapsFrame,
        Option<&AapsStereo>,
        Option<&ViewSettle>,
        Option<&ViewTemporal>,
    )>,
    states: Query<&AapsViewState>,
    temporal_pipelines: Option<Res<TemporalPipelines>>,
    scene: Option<Res<TraceSceneBuffers>>,
    pipelines: Res<AapsPipelines>,
    cache: Res<PipelineCache>,
    log: Res<CausticsDispatchLog>,
    settle: Res<SpanSettle>,
    specialization: Option<Res<TraceSpecialization>>,
    fixed: Option<Res<FixedSplatPipelines>>,
    mut ctx: RenderContext,
) {
    let (buffer, prepass, state, _, stereo, view_settle, temporal) = view.into_inner();
    // The shared temporal stage, once the technique's work is recorded.
    let blend = |ctx: &mut RenderContext, depth| {
        if let (Some(t), Some(p)) = (temporal, temporal_pipelines.as_deref()) {
            temporal::accumulate(ctx, (&cache, p, &settle), t, (buffer, depth), &log);
        }
    };
    // Fixed-point splats (no FLOAT32_BLENDABLE): the accumulator and its resolve.
    let fixed = match (&state.fixed, fixed.as_deref()) {
        (Some(accumulator), Some(p)) => Some(FixedSplat {
            pipelines: p,
            cache: &cache,
            accumulator,
        }),
        (Some(_), None) => return,
        (None, _) => None,
    };
    let Some(scene) = scene else {
        return;
    };
    let Some(depth) = prepass.depth_view() else {
        return;
    };
    let ready = temporal::ready(temporal, temporal_pipelines.as_deref(), &cache);
    let features = wanted_features(&scene, specialization.as_deref());
    let Some(frame) = frame_pipelines(&cache, &pipelines, features, state.msaa.is_some(), ready)
    else {
        return;
    };
    let (splat, splat_msaa, trace) = (frame.splat, frame.splat_msaa, frame.trace);
    let [
        leaves,
        reduce,
        trace_args,
        draw_args,
        variance,
        update,
        scale,
    ] = frame.compute;
    let groups = bind_groups(
        ctx.render_device(),
        &cache,
        &pipelines,
        &scene,
        state,
        buffer,
        depth,
    );
    let [atlas, ..] = state.key.atlas;
    let texel_groups = (atlas * atlas).div_ceil(64);
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();

    // The right eye of a stereo pair: the left eye's splats (this frame's, drawn with the
    // left eye's arguments) with its own projection and depth; no trace.
    if let Some(left) = stereo.and_then(|s| states.get(s.left).ok())
        && left.key.splat_capacity == state.key.splat_capacity
    {
        let group = ctx.render_device().create_bind_group(
            "caustics:bind_group:aaps_splat_right",
            &cache.get_bind_group_layout(&pipelines.splat_layout),
            &BindGroupEntries::sequential((
                state.params.as_entire_binding(),
                left.splats.as_entire_binding(),
                depth,
                state.world_from_clip.as_entire_binding(),
            )),
        );
        splat_passes(
            &mut ctx,
            (diagnostics, &settle),
            (state, &left.args),
            buffer,
            (splat, splat_msaa),
            &group,
            fixed.as_ref(),
            &log,
        );
        blend(&mut ctx, depth);
        view_settle.inspect(|s| s.mark_ran());
        return;
    }

    copy_to_history(&mut ctx, buffer, state);
    ctx.command_encoder().clear_buffer(&state.accum, 0, None);

    task_buffer_pass(
        &mut ctx,
        (diagnostics, &settle),
        state,
        &groups,
        [leaves, reduce, trace_args],
        texel_groups,
    );
    log.record(TASK_PASS);

    // Emit and trace, then the draw and variance arguments.
    {
        let encoder = ctx.command_encoder();
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_aaps_trace"),
            timestamp_writes: None,
        });
        let span = diagnostics.pass_span(&mut pass, TRACE_PASS);
        settle.settle(&mut pass);
        pass.set_pipeline(trace);
        pass.set_bind_group(0, &groups.trace, &[]);
        pass.dispatch_workgroups_indirect(&state.args, 0);
        span.end(&mut pass);
    }
    {
        let encoder = ctx.command_encoder();
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_aaps_draw_args"),
            timestamp_writes: None,
        });
        pass.set_pipeline(draw_args);
        pass.set_bind_group(0, &groups.main, &[0]);
        pass.set_bind_group(1, &groups.args, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    log.record(TRACE_PASS);

    splat_passes(
        &mut ctx,
        (diagnostics, &settle),
        (state, &state.args),
        buffer,
        (splat, splat_msaa),
        &groups.splat,
        fixed.as_ref(),
        &log,
    );

    // Next frame's distribution: variance by reprojection, D' and the blend, the budget.
    if state.settings.adaptive {
        let encoder = ctx.command_encoder();
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_aaps_update"),
            timestamp_writes: None,
        });
        let span = diagnostics.pass_span(&mut pass, UPDATE_PASS);
        settle.settle(&mut pass);
        pass.set_bind_group(0, &groups.main, &[0]);
        pass.set_pipeline(variance);
        pass.dispatch_workgroups_indirect(&state.args, 4 * 4);
        pass.set_pipeline(update);
        pass.dispatch_workgroups(texel_groups, 1, 1);
        pass.set_pipeline(scale);
        pass.dispatch_workgroups(texel_groups, 1, 1);
        span.end(&mut pass);
        log.record(UPDATE_PASS);
    }
    for (name, word) in COUNTERS {
        diagnostics.record_u32(
            ctx.command_encoder(),
            &state.accum.slice(word * 4..word * 4 + 4),
            name,
        );
    }
    blend(&mut ctx, depth);
    view_settle.inspect(|s| s.mark_ran());
}

/// The pipelines of one AAPS frame.
struct FramePipelines<'a> {
    /// `[leaves, reduce, trace_args, draw_args, variance, update, scale]`.
    compute: [&'a ComputePipeline; 7],
    /// The scene's specialised tracer.
    trace: &'a ComputePipeline,
    splat: &'a RenderPipeline,
    splat_msaa: Option<&'a RenderPipeline>,
}

/// The frame's pipelines once every pass of the frame can run, `None` while any compiles: a
/// frame without its small splats (`msaa`: the view draws them), or one the temporal stage did
/// not take (`temporal_ready`), would be kept in the settled mean.
fn frame_pipelines<'a>(
    cache: &'a PipelineCache,
    pipelines: &AapsPipelines,
    features: TraceFeatures,
    msaa: bool,
    temporal_ready: bool,
) -> Option<FramePipelines<'a>> {
    let splat_msaa = pipelines
        .splat_msaa
        .and_then(|id| cache.get_render_pipeline(id));
    if !temporal_ready || (msaa && splat_msaa.is_none()) {
        return None;
    }
    let compute: Vec<_> = pipelines
        .compute
        .iter()
        .map(|id| cache.get_compute_pipeline(*id))
        .collect::<Option<_>>()?;
    Some(FramePipelines {
        compute: compute.try_into().ok()?,
        trace: cache.get_compute_pipeline(pipelines.trace.get(features)?)?,
        splat: cache.get_render_pipeline(pipelines.splat)?,
        splat_msaa,
    })
}

/// The task buffer: quadtree leaves from the density atlas, reduction to the root, and the
/// trace dispatch size from the root (`[leaves, reduce, trace_args]`).
fn task_buffer_pass(
    ctx: &mut RenderContext,
    (diagnostics, settle): (Option<&DiagnosticsRecorder>, &SpanSettle),
    state: &AapsViewState,
    groups: &Groups,
    [leaves, reduce, trace_args]: [&bevy::render::render_resource::ComputePipeline; 3],
    texel_groups: u32,
) {
    let atlas = state.key.atlas[0];
    let encoder = ctx.command_encoder();
    let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
        label: Some("caustics_aaps_task_buffer"),
        timestamp_writes: None,
    });
    let span = diagnostics.pass_span(&mut pass, TASK_PASS);
    settle.settle(&mut pass);
    pass.set_pipeline(leaves);
    pass.set_bind_group(0, &groups.main, &[0]);
    pass.dispatch_workgroups(texel_groups, 1, 1);
    pass.set_pipeline(reduce);
    for k in 0..state.reduce_steps {
        let n = (atlas >> (k + 1)).max(1);
        pass.set_bind_group(0, &groups.main, &[(k as u64 * LEVEL_STRIDE) as u32]);
        pass.dispatch_workgroups((n * n).div_ceil(64), 1, 1);
    }
    pass.set_pipeline(trace_args);
    pass.set_bind_group(0, &groups.main, &[0]);
    pass.set_bind_group(1, &groups.args, &[]);
    pass.dispatch_workgroups(1, 1, 1);
    span.end(&mut pass);
}

/// The bind groups of a view's passes.
struct Groups {
    /// The task buffer, variance and density passes (no scene).
    main: BindGroup,
    /// The trace: the scene, the quadtree, the splats and the counters.
    trace: BindGroup,
    /// The indirect arguments (group 1 of the argument writers).
    args: BindGroup,
    /// The splat passes.
    splat: BindGroup,
}

/// The view's bind groups ([`Groups`]).
fn bind_groups(
    device: &RenderDevice,
    cache: &PipelineCache,
    pipelines: &AapsPipelines,
    scene: &TraceSceneBuffers,
    state: &AapsViewState,
    buffer: &ViewCausticsBuffer,
    depth: &TextureView,
) -> Groups {
    let b = &scene.buffers;
    let main: BindGroup = device.create_bind_group(
        "caustics:bind_group:aaps",
        &cache.get_bind_group_layout(&pipelines.compute_layout),
        &BindGroupEntries::with_indices((
            (7, state.quadtree.as_entire_binding()),
            (9, state.params.as_entire_binding()),
            (10, state.splats.as_entire_binding()),
            (11, state.accum.as_entire_binding()),
            (12, state.density[0].as_entire_binding()),
            (13, state.density[1].as_entire_binding()),
            (14, &buffer.view),
            (15, &state.history.1),
            (
                16,
                BindingResource::Buffer(BufferBinding {
                    buffer: &state.levels,
                    offset: 0,
                    size: Some(core::num::NonZeroU64::new(16).unwrap()),
                }),
            ),
        )),
    );
    let trace = device.create_bind_group(
        "caustics:bind_group:aaps_trace",
        &cache.get_bind_group_layout(&pipelines.trace_layout),
        &BindGroupEntries::with_indices((
            (0, b[0].as_entire_binding()),
            (1, b[1].as_entire_binding()),
            (2, b[2].as_entire_binding()),
            (7, state.quadtree.as_entire_binding()),
            (8, b[3].as_entire_binding()),
            (9, state.params.as_entire_binding()),
            (10, state.splats.as_entire_binding()),
            (11, state.accum.as_entire_binding()),
        )),
    );
    let args = device.create_bind_group(
        "caustics:bind_group:aaps_args",
        &cache.get_bind_group_layout(&pipelines.args_layout),
        &[BindGroupEntry {
            binding: 0,
            resource: state.args.as_entire_binding(),
        }],
    );
    let splat_group = device.create_bind_group(
        "caustics:bind_group:aaps_splat",
        &cache.get_bind_group_layout(&pipelines.splat_layout),
        &BindGroupEntries::sequential((
            state.params.as_entire_binding(),
            state.splats.as_entire_binding(),
            depth,
            state.world_from_clip.as_entire_binding(),
        )),
    );
    Groups {
        main,
        trace,
        args,
        splat: splat_group,
    }
}

/// Last frame's result becomes the history of the variance pass.
fn copy_to_history(ctx: &mut RenderContext, buffer: &ViewCausticsBuffer, state: &AapsViewState) {
    ctx.command_encoder().copy_texture_to_texture(
        TexelCopyTextureInfo {
            texture: &buffer.texture,
            mip_level: 0,
            origin: Default::default(),
            aspect: Default::default(),
        },
        TexelCopyTextureInfo {
            texture: &state.history.0,
            mip_level: 0,
            origin: Default::default(),
            aspect: Default::default(),
        },
        Extent3d {
            width: buffer.size.x,
            height: buffer.size.y,
            depth_or_array_layers: 1,
        },
    );
}

/// The fixed-point fallback of a view's splats (`render::fixed_splat`).
struct FixedSplat<'a> {
    pipelines: &'a FixedSplatPipelines,
    cache: &'a PipelineCache,
    accumulator: &'a bevy::render::render_resource::Buffer,
}

/// The splat passes: small splats into the MSAA target resolved into the caustics buffer
/// (overwriting it), then the plain splats blended on top (clearing it first when there was no
/// MSAA pass). With `fixed`, the plain splats add into its accumulator instead, resolved over
/// the caustics buffer (there is no MSAA pass then).
#[allow(clippy::too_many_arguments)]
fn splat_passes(
    ctx: &mut RenderContext,
    (diagnostics, settle): (Option<&DiagnosticsRecorder>, &SpanSettle),
    (state, args): (&AapsViewState, &bevy::render::render_resource::Buffer),
    buffer: &ViewCausticsBuffer,
    (splat, splat_msaa): (&RenderPipeline, Option<&RenderPipeline>),
    splat_group: &BindGroup,
    fixed: Option<&FixedSplat>,
    log: &CausticsDispatchLog,
) {
    let fixed_group = fixed.map(|f| {
        ctx.command_encoder().clear_buffer(f.accumulator, 0, None);
        fixed_splat::fragment_group(ctx.render_device(), f.cache, f.pipelines, f.accumulator)
    });
    let mut cleared = false;
    if let (Some(pipeline), Some((_, msaa_view))) = (splat_msaa, &state.msaa) {
        let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
            label: Some("caustics_aaps_splat_msaa"),
            color_attachments: &[Some(RenderPassColorAttachment {
                view: msaa_view,
                depth_slice: None,
                resolve_target: Some(&buffer.view),
                ops: Operations {
                    load: LoadOp::Clear(Default::default()),
                    store: StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let span = diagnostics.pass_span(&mut pass, SPLAT_MSAA_PASS);
        settle.settle(&mut pass);
        pass.set_render_pipeline(pipeline);
        pass.set_bind_group(0, splat_group, &[]);
        pass.draw_indirect(args, 12 * 4);
        span.end(&mut pass);
        cleared = true;
        log.record(SPLAT_MSAA_PASS);
    }
    {
        let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
            label: Some("caustics_aaps_splat"),
            color_attachments: &[Some(RenderPassColorAttachment {
                view: &buffer.view,
                depth_slice: None,
                resolve_target: None,
                ops: Operations {
                    load: if cleared {
                        LoadOp::Load
                    } else {
                        LoadOp::Clear(Default::default())
                    },
                    store: StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let span = diagnostics.pass_span(&mut pass, SPLAT_PASS);
        settle.settle(&mut pass);
        pass.set_render_pipeline(splat);
        pass.set_bind_group(0, splat_group, &[]);
        if let Some(group) = &fixed_group {
            pass.set_bind_group(1, group, &[]);
        }
        pass.draw_indirect(args, 8 * 4);
        span.end(&mut pass);
    }
    if let Some(f) = fixed {
        fixed_splat::resolve(
            ctx,
            f.cache,
            f.pipelines,
            f.accumulator,
            &buffer.view,
            buffer.size,
        );
    }
    log.record(SPLAT_PASS);
}
