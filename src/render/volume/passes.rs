//! The caustics-volume passes, in `Core3d` after the prepass (splats need the view depth) and
//! before the composite. The first volume view of a frame runs each volume's scheduled
//! [`VolumeRun`] (slab G-buffers and propagation from the first changed slab on, or the next
//! progressive batch through every slab, then the projectors over the run's range); every
//! volume view then splats the visible volumes and blurs them into its caustics buffer. No
//! GPU-to-CPU copy: live counts drive the indirect dispatches on the GPU.

use std::sync::LazyLock;
use std::sync::atomic::Ordering;

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupEntry, ComputePassDescriptor, LoadOp, Operations, PipelineCache,
    RenderPassColorAttachment, RenderPassDepthStencilAttachment, RenderPassDescriptor, StoreOp,
    TextureView,
};
use bevy::render::renderer::{RenderContext, ViewQuery};

use super::gpu::{CNT, PROBE_STRIDE, VolumeGpu, tile_bytes};
use super::pipelines::VolumePipelines;
use super::view::{VolumeStore, VolumeViewFrame, VolumeViewState};
use crate::render::span::SpanSettle;
use crate::render::{CausticsDispatchLog, ViewCausticsBuffer};
use crate::volume::VolumeRun;

/// Most slabs a volume can have (the validator's bound).
pub const MAX_SLABS: usize = 64;

/// Span and log names of slab k's propagation (`caustics/volume/slab<k+1>`) and G-buffers
/// (`caustics/volume/slab<k+1>_gbuffer`), k < [`MAX_SLABS`].
pub static SLAB_PASSES: LazyLock<Vec<(&'static str, &'static str)>> = LazyLock::new(|| {
    (1..=MAX_SLABS)
        .map(|k| {
            let a: &'static str = Box::leak(format!("caustics/volume/slab{k}").into_boxed_str());
            let b: &'static str =
                Box::leak(format!("caustics/volume/slab{k}_gbuffer").into_boxed_str());
            (a, b)
        })
        .collect()
});

/// G-buffer of projector face f (`caustics/volume/projector<f>_gbuffer`, f = face code).
pub const PROJECTOR_GBUFFER_PASSES: [&str; 6] = [
    "caustics/volume/projector0_gbuffer",
    "caustics/volume/projector1_gbuffer",
    "caustics/volume/projector2_gbuffer",
    "caustics/volume/projector3_gbuffer",
    "caustics/volume/projector4_gbuffer",
    "caustics/volume/projector5_gbuffer",
];
/// Projector march, density tiles (every exit face and the deposits).
pub const PROJECT_PASS: &str = "caustics/volume/project";
/// Splats into the view's volume target.
pub const SPLAT_PASS: &str = "caustics/volume/splat";
/// Depth- and normal-aware blur into the caustics buffer.
pub const BLUR_PASS: &str = "caustics/volume/blur";

/// Every pass name, for diagnostics readers.
pub fn all_passes() -> Vec<&'static str> {
    let mut v = Vec::new();
    for (a, b) in SLAB_PASSES.iter() {
        v.push(*b);
        v.push(*a);
    }
    v.extend(PROJECTOR_GBUFFER_PASSES);
    v.extend([PROJECT_PASS, SPLAT_PASS, BLUR_PASS]);
    v
}

/// Counters read into diagnostics (`render/caustics/volume/<name>`), word after `CNT`.
pub const VOLUME_COUNTERS: [(&str, u64); 8] = [
    ("caustics/volume/hits", 2),
    ("caustics/volume/deposits", 3),
    ("caustics/volume/missed", 4),
    ("caustics/volume/culled", 5),
    ("caustics/volume/tir", 6),
    ("caustics/volume/nan_guards", 7),
    ("caustics/volume/backward", 8),
    ("caustics/volume/step_limit", 10),
];

/// One `VolStep` of the probe uniforms (selected by a dynamic offset).
fn probe_binding(v: &VolumeGpu) -> bevy::render::render_resource::BindingResource<'_> {
    bevy::render::render_resource::BindingResource::Buffer(
        bevy::render::render_resource::BufferBinding {
            buffer: &v.probes,
            offset: 0,
            size: core::num::NonZeroU64::new(96),
        },
    )
}

/// A colour attachment cleared to zero and stored.
fn cleared(view: &TextureView) -> Option<RenderPassColorAttachment<'_>> {
    Some(RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: Operations {
            load: LoadOp::Clear(Default::default()),
            store: StoreOp::Store,
        },
    })
}

/// A render pass with colour targets only.
pub(super) fn colour_pass<'a>(
    label: &'static str,
    color_attachments: &'a [Option<RenderPassColorAttachment<'a>>],
) -> RenderPassDescriptor<'a> {
    RenderPassDescriptor {
        label: Some(label),
        color_attachments,
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    }
}

#[allow(clippy::too_many_arguments)]
fn raster_gbuffer(
    ctx: &mut RenderContext,
    settle: &SpanSettle,
    pipeline: &bevy::render::render_resource::RenderPipeline,
    group: &bevy::render::render_resource::BindGroup,
    color: &TextureView,
    depth: &TextureView,
    far: bool,
    probe: u32,
    tri_count: u32,
    name: &'static str,
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("caustics_volume_gbuffer"),
        color_attachments: &[cleared(color)],
        depth_stencil_attachment: Some(RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(Operations {
                load: LoadOp::Clear(if far { 0.0 } else { 1.0 }),
                store: StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let span = diagnostics.pass_span(&mut pass, name);
    settle.settle(&mut pass);
    if tri_count > 0 {
        pass.set_render_pipeline(pipeline);
        pass.set_bind_group(0, group, &[probe * PROBE_STRIDE as u32]);
        pass.draw(0..tri_count * 3, 0..1);
    }
    span.end(&mut pass);
}

/// Run `run` on volume `v`: slabs from `run.first_slab` on (none when it is `slabs`), then
/// the projectors over `run.project`.
#[allow(clippy::too_many_arguments)]
fn update_volume(
    ctx: &mut RenderContext,
    settle: &SpanSettle,
    v: &VolumeGpu,
    run: VolumeRun,
    store: &VolumeStore,
    pipelines: &VolumePipelines,
    cache: &PipelineCache,
    log: &CausticsDispatchLog,
) -> bool {
    let Some(scene) = &store.scene else {
        return false;
    };
    let [Some(propagate), Some(write_args), Some(project)] =
        pipelines.compute.map(|id| cache.get_compute_pipeline(id))
    else {
        return false;
    };
    let (Some(near), Some(far)) = (
        cache.get_render_pipeline(pipelines.gbuffer_near),
        cache.get_render_pipeline(pipelines.gbuffer_far),
    ) else {
        return false;
    };
    let device = ctx.render_device().clone();
    let main = device.create_bind_group(
        "caustics:bind_group:volume",
        &cache.get_bind_group_layout(&pipelines.compute_layout),
        &BindGroupEntries::sequential((
            v.params.as_entire_binding(),
            probe_binding(v),
            scene.materials.as_entire_binding(),
            v.states.as_entire_binding(),
            v.live.as_entire_binding(),
            v.counts.as_entire_binding(),
            v.finals.as_entire_binding(),
            v.hits.as_entire_binding(),
            v.tiles.as_entire_binding(),
            &v.slab_array,
            &v.cube_array,
        )),
    );
    let args = device.create_bind_group(
        "caustics:bind_group:volume_args",
        &cache.get_bind_group_layout(&pipelines.args_layout),
        &[BindGroupEntry {
            binding: 0,
            resource: v.args.as_entire_binding(),
        }],
    );
    let gbuffer = device.create_bind_group(
        "caustics:bind_group:volume_gbuffer",
        &cache.get_bind_group_layout(&pipelines.gbuffer_layout),
        &BindGroupEntries::with_indices((
            (0, v.params.as_entire_binding()),
            (1, probe_binding(v)),
            (2, scene.tris.as_entire_binding()),
        )),
    );
    let slabs = v.key.slabs;
    if run.restarts() {
        ctx.command_encoder().clear_buffer(&v.finals, 0, None);
    }
    for k in run.first_slab..slabs {
        let (prop_name, gbuf_name) = SLAB_PASSES[(k as usize).min(MAX_SLABS - 1)];
        raster_gbuffer(
            ctx,
            settle,
            near,
            &gbuffer,
            &v.slab_layers[2 * k as usize],
            &v.slab_depth,
            false,
            2 * k,
            scene.tri_count,
            gbuf_name,
        );
        raster_gbuffer(
            ctx,
            settle,
            far,
            &gbuffer,
            &v.slab_layers[2 * k as usize + 1],
            &v.slab_depth,
            true,
            2 * k + 1,
            scene.tri_count,
            gbuf_name,
        );
        log.record(gbuf_name);
        if k + 1 < slabs {
            ctx.command_encoder()
                .clear_buffer(&v.counts, (k as u64 + 1) * 4, Some(4));
        }
        let offset = (2 * k) * PROBE_STRIDE as u32;
        {
            let encoder = ctx.command_encoder();
            let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
                label: Some("caustics_volume_args"),
                timestamp_writes: None,
            });
            pass.set_pipeline(write_args);
            pass.set_bind_group(0, &main, &[offset]);
            pass.set_bind_group(1, &args, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let diagnostics = ctx.diagnostic_recorder();
        let diagnostics = diagnostics.as_deref();
        let encoder = ctx.command_encoder();
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some("caustics_volume_propagate"),
            timestamp_writes: None,
        });
        let span = diagnostics.pass_span(&mut pass, prop_name);
        settle.settle(&mut pass);
        pass.set_pipeline(propagate);
        pass.set_bind_group(0, &main, &[offset]);
        pass.dispatch_workgroups_indirect(&v.args, k as u64 * 12);
        span.end(&mut pass);
        drop(pass);
        log.record(prop_name);
    }
    // Projectors: G-buffers of the exit faces, then the march and the density tiles.
    for face in 0..6u32 {
        if v.exit_mask & (1 << face) == 0 {
            continue;
        }
        raster_gbuffer(
            ctx,
            settle,
            near,
            &gbuffer,
            &v.cube_layers[face as usize],
            &v.cube_depth,
            false,
            2 * slabs + face,
            scene.tri_count,
            PROJECTOR_GBUFFER_PASSES[face as usize],
        );
        log.record(PROJECTOR_GBUFFER_PASSES[face as usize]);
    }
    if run.project.0 == 0 {
        // A new projection of the trace list: hits, tiles and the projectors' counters are
        // recounted (a later progressive batch adds to them).
        let encoder = ctx.command_encoder();
        encoder.clear_buffer(&v.hits, 0, None);
        encoder.clear_buffer(&v.tiles, 0, Some(tile_bytes(&v.key)));
        encoder.clear_buffer(&v.counts, (CNT + 1) * 4, Some(4 * 4));
    }
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let encoder = ctx.command_encoder();
    let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
        label: Some("caustics_volume_project"),
        timestamp_writes: None,
    });
    let span = diagnostics.pass_span(&mut pass, PROJECT_PASS);
    settle.settle(&mut pass);
    pass.set_pipeline(project);
    let groups = run
        .project
        .1
        .saturating_sub(run.project.0)
        .div_ceil(64)
        .clamp(1, 65535);
    for face in 0..7u32 {
        if face < 6 && v.exit_mask & (1 << face) == 0 {
            continue;
        }
        pass.set_bind_group(0, &main, &[(2 * slabs + face) * PROBE_STRIDE as u32]);
        pass.dispatch_workgroups(groups, 1, 1);
    }
    span.end(&mut pass);
    drop(pass);
    log.record(PROJECT_PASS);
    true
}

/// All volume passes of one view.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn volume_passes(
    view: ViewQuery<(
        Entity,
        &ViewCausticsBuffer,
        &ViewPrepassTextures,
        &VolumeViewState,
        &VolumeViewFrame,
        Option<&crate::render::settle::ViewSettle>,
    )>,
    store: Res<VolumeStore>,
    pipelines: Option<Res<VolumePipelines>>,
    cache: Res<PipelineCache>,
    log: Res<CausticsDispatchLog>,
    settle: Res<SpanSettle>,
    fixed: Option<Res<crate::render::fixed_splat::FixedSplatPipelines>>,
    mut ctx: RenderContext,
) {
    let (entity, buffer, prepass, state, _, view_settle) = view.into_inner();
    let Some(pipelines) = pipelines else {
        return;
    };
    // Work follows change (`render::settle`): no volume updates and nothing else changed for
    // `settle_frames` frames: the caustics buffer keeps the last splats.
    let updating = store.volumes.iter().any(|v| v.run.is_some() && v.visible);
    if !updating && crate::render::settle::keeps(view_settle) {
        return;
    }
    // Fixed-point splats (no FLOAT32_BLENDABLE): the accumulator and its resolve.
    let fixed = match (&state.fixed, fixed.as_deref()) {
        (Some(accumulator), Some(p)) => Some((p, accumulator)),
        (Some(_), None) => return,
        (None, _) => None,
    };
    let (Some(depth), Some(gbuffer)) = (prepass.depth_view(), prepass.deferred_view()) else {
        return;
    };
    let (Some(splat), Some(blur)) = (
        cache.get_render_pipeline(pipelines.splat),
        cache.get_render_pipeline(pipelines.blur),
    ) else {
        return;
    };
    if store.updater == Some(entity) {
        for v in &store.volumes {
            if let (Some(run), true) = (v.run, v.visible)
                && update_volume(&mut ctx, &settle, v, run, &store, &pipelines, &cache, &log)
            {
                v.ran.store(true, Ordering::Release);
            }
        }
    }
    let device = ctx.render_device().clone();
    {
        let groups: Vec<_> = state
            .visible
            .iter()
            .filter_map(|&i| store.volumes.get(i))
            .map(|v| {
                (
                    device.create_bind_group(
                        "caustics:bind_group:volume_splat",
                        &cache.get_bind_group_layout(&pipelines.splat_layout),
                        &BindGroupEntries::with_indices((
                            (0, v.params.as_entire_binding()),
                            (3, state.params.as_entire_binding()),
                            (4, v.hits.as_entire_binding()),
                            (5, v.tiles.as_entire_binding()),
                            (6, depth),
                        )),
                    ),
                    v.key.capacity,
                )
            })
            .collect();
        let fixed_group = fixed.map(|(p, accumulator)| {
            ctx.command_encoder().clear_buffer(accumulator, 0, None);
            crate::render::fixed_splat::fragment_group(&device, &cache, p, accumulator)
        });
        let diagnostics = ctx.diagnostic_recorder();
        let diagnostics = diagnostics.as_deref();
        let mut pass = ctx.begin_tracked_render_pass(colour_pass(
            "caustics_volume_splat",
            &[cleared(&state.target)],
        ));
        let span = diagnostics.pass_span(&mut pass, SPLAT_PASS);
        settle.settle(&mut pass);
        pass.set_render_pipeline(splat);
        if let Some(group) = &fixed_group {
            pass.set_bind_group(1, group, &[]);
        }
        for (group, capacity) in &groups {
            pass.set_bind_group(0, group, &[]);
            pass.draw(0..6, 0..*capacity);
        }
        span.end(&mut pass);
        drop(pass);
        if let Some((p, accumulator)) = fixed {
            crate::render::fixed_splat::resolve(
                &mut ctx,
                &cache,
                p,
                accumulator,
                &state.target,
                state.size,
            );
        }
    }
    log.record(SPLAT_PASS);
    {
        let group = device.create_bind_group(
            "caustics:bind_group:volume_blur",
            &cache.get_bind_group_layout(&pipelines.blur_layout),
            &BindGroupEntries::sequential((
                &state.target,
                depth,
                gbuffer,
                state.blur.as_entire_binding(),
            )),
        );
        let diagnostics = ctx.diagnostic_recorder();
        let diagnostics = diagnostics.as_deref();
        let mut pass = ctx.begin_tracked_render_pass(colour_pass(
            "caustics_volume_blur",
            &[cleared(&buffer.view)],
        ));
        let span = diagnostics.pass_span(&mut pass, BLUR_PASS);
        settle.settle(&mut pass);
        pass.set_render_pipeline(blur);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
        span.end(&mut pass);
    }
    log.record(BLUR_PASS);
    if let Some(v) = state.visible.first().and_then(|&i| store.volumes.get(i)) {
        let diagnostics = ctx.diagnostic_recorder();
        let diagnostics = diagnostics.as_deref();
        for (name, word) in VOLUME_COUNTERS {
            let at = (CNT + word) * 4;
            diagnostics.record_u32(ctx.command_encoder(), &v.counts.slice(at..at + 4), name);
        }
    }
    view_settle.inspect(|s| s.mark_ran());
}
