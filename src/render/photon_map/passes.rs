//! The photon-map passes of one view, in `Core3d` after the deferred lighting (the gather
//! reads the view's depth and G-buffer) and before the composite: trace, grid build, gather.
//! Each records a GPU span and its name in the dispatch log. A frozen progressive mean (after
//! `max_frames`) runs only the gather pass, which then copies the mean.

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, ComputePassDescriptor, ComputePipeline, PipelineCache,
};
use bevy::render::renderer::{RenderContext, ViewQuery};

use super::pipelines::{GRID_ENTRIES, PhotonMapPipelines, grid_dispatches};
use super::view::{PhotonMapFrame, PhotonMapStereo, PhotonMapViewState};
use crate::render::photon_groups;
use crate::render::span::SpanSettle;
use crate::render::temporal::{self, TemporalPipelines, ViewTemporal};
use crate::render::trace::scene::TraceSceneBuffers;
use crate::render::trace::{TraceSpecialization, wanted_features};
use crate::render::{CausticsDispatchLog, ViewCausticsBuffer};

/// Emit and trace; photons stored at their first diffuse hit after a specular one.
pub const TRACE_PASS: &str = "caustics/photon_map/trace";
/// Bounds, layout, count, prefix sum and scatter.
pub const GRID_PASS: &str = "caustics/photon_map/grid";
/// Per-pixel gather into the progressive mean and the caustics buffer.
pub const GATHER_PASS: &str = "caustics/photon_map/gather";
/// The gather of the right eye of a stereo pair (from the left eye's grid, reusing its
/// gathers where both eyes see the same point).
pub const GATHER_RIGHT_PASS: &str = "caustics/photon_map/gather_right";
/// Every pass, in order.
pub const ALL_PASSES: [&str; 4] = [TRACE_PASS, GRID_PASS, GATHER_PASS, GATHER_RIGHT_PASS];

/// Counters read into diagnostics (`render/caustics/photon_map/<name>`), by header word
/// (`C_*` in photon.wgsl).
pub const PHOTON_MAP_COUNTERS: [(&str, u64); 12] = [
    ("caustics/photon_map/emitted", 0),
    ("caustics/photon_map/stored", 1),
    ("caustics/photon_map/overflow", 4),
    ("caustics/photon_map/max_depth", 5),
    ("caustics/photon_map/roulette", 31),
    ("caustics/photon_map/nan_guards", 7),
    ("caustics/photon_map/grid_cells", 8),
    ("caustics/photon_map/coarsened", 9),
    ("caustics/photon_map/gathered", 12),
    ("caustics/photon_map/gathered_max", 13),
    ("caustics/photon_map/events", 50),
    ("caustics/photon_map/budget_stopped", 51),
];

fn compute_pass(
    ctx: &mut RenderContext,
    settle: &SpanSettle,
    name: &'static str,
    stages: &[(&ComputePipeline, &BindGroup, [u32; 3])],
) {
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let encoder = ctx.command_encoder();
    let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
        label: Some(name),
        timestamp_writes: None,
    });
    let span = diagnostics.pass_span(&mut pass, name);
    settle.settle(&mut pass);
    for (pipeline, group, groups) in stages {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, *group, &[]);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }
    span.end(&mut pass);
}

/// The system.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn photon_map_passes(
    view: ViewQuery<(
        &ViewCausticsBuffer,
        &ViewPrepassTextures,
        &PhotonMapViewState,
        &PhotonMapFrame,
        Option<&PhotonMapStereo>,
        Option<&crate::render::settle::ViewSettle>,
        Option<&ViewTemporal>,
    )>,
    states: Query<&PhotonMapViewState>,
    temporal_pipelines: Option<Res<TemporalPipelines>>,
    scene: Option<Res<TraceSceneBuffers>>,
    pipelines: Option<Res<PhotonMapPipelines>>,
    cache: Res<PipelineCache>,
    log: Res<CausticsDispatchLog>,
    settle: Res<SpanSettle>,
    specialization: Option<Res<TraceSpecialization>>,
    mut ctx: RenderContext,
) {
    let (buffer, prepass, state, _, stereo, view_settle, temporal) = view.into_inner();
    let Some(pipelines) = pipelines else {
        return;
    };
    // A right eye gathers from its left eye's photons and grid.
    let left = stereo.and_then(|s| states.get(s.left).ok());
    let src = left.unwrap_or(state);
    let Some(scene) = scene else {
        return;
    };
    let (Some(depth), Some(gbuffer)) = (prepass.depth_view(), prepass.deferred_view()) else {
        return;
    };
    let features = wanted_features(&scene, specialization.as_deref());
    let (Some(trace), Some(gather)) = (
        pipelines
            .trace
            .get(features)
            .and_then(|id| cache.get_compute_pipeline(id)),
        cache.get_compute_pipeline(pipelines.gather),
    ) else {
        return;
    };
    let Some(grid) = pipelines
        .grid
        .iter()
        .map(|id| cache.get_compute_pipeline(*id))
        .collect::<Option<Vec<_>>>()
    else {
        return;
    };
    let b = &scene.buffers;
    let trace_group = ctx.render_device().create_bind_group(
        "caustics:bind_group:photon_map_trace",
        &cache.get_bind_group_layout(&pipelines.trace_layout),
        &BindGroupEntries::with_indices((
            (0, b[0].as_entire_binding()),
            (1, b[1].as_entire_binding()),
            (2, b[2].as_entire_binding()),
            (8, b[3].as_entire_binding()),
            (9, state.params.as_entire_binding()),
            (10, state.photons.as_entire_binding()),
            (11, state.header.as_entire_binding()),
        )),
    );
    let gather_group = ctx.render_device().create_bind_group(
        "caustics:bind_group:photon_map_gather",
        &cache.get_bind_group_layout(&pipelines.gather_layout),
        &BindGroupEntries::with_indices((
            (0, b[0].as_entire_binding()),
            (1, b[1].as_entire_binding()),
            (2, b[2].as_entire_binding()),
            (9, state.params.as_entire_binding()),
            (11, state.header.as_entire_binding()),
            (12, src.sorted.as_entire_binding()),
            (13, src.cells.as_entire_binding()),
            (14, state.accum.as_entire_binding()),
            (15, depth),
            (16, gbuffer),
            (17, &buffer.view),
            (
                18,
                left.filter(|_| stereo.is_some_and(|s| s.reuse))
                    .map_or(&state.dummy, |l| &l.accum)
                    .as_entire_binding(),
            ),
        )),
    );
    if let Some(left) = left {
        // Its own counters, the left eye's grid layout (header words 32..64).
        let encoder = ctx.command_encoder();
        encoder.clear_buffer(&state.header, 0, None);
        encoder.copy_buffer_to_buffer(&left.header, 128, &state.header, 128, Some(128));
    }
    if state.traces {
        let grid_group = ctx.render_device().create_bind_group(
            "caustics:bind_group:photon_map_grid",
            &cache.get_bind_group_layout(&pipelines.grid_layout),
            &BindGroupEntries::sequential((
                state.grid_params.as_entire_binding(),
                state.photons.as_entire_binding(),
                state.sorted.as_entire_binding(),
                state.header.as_entire_binding(),
                state.cells.as_entire_binding(),
                state.blocks.as_entire_binding(),
                state.photon_cell.as_entire_binding(),
            )),
        );
        let encoder = ctx.command_encoder();
        encoder.clear_buffer(&state.header, 0, None);
        let photons = state.per_light * state.lights;
        let sizes = grid_dispatches(state.key.capacity, state.key.budget + 1);
        let stages: Vec<_> = grid
            .iter()
            .zip(sizes)
            .map(|(p, n)| (*p, &grid_group, n))
            .collect();
        debug_assert_eq!(stages.len(), GRID_ENTRIES.len());
        encoder.clear_buffer(&state.cells, 0, None);
        compute_pass(
            &mut ctx,
            &settle,
            TRACE_PASS,
            &[(trace, &trace_group, photon_groups(photons))],
        );
        log.record(TRACE_PASS);
        compute_pass(&mut ctx, &settle, GRID_PASS, &stages);
        log.record(GRID_PASS);
    }
    let size = state.key.size;
    let name = if left.is_some() {
        GATHER_RIGHT_PASS
    } else {
        GATHER_PASS
    };
    compute_pass(
        &mut ctx,
        &settle,
        name,
        &[(
            gather,
            &gather_group,
            [size.x.div_ceil(8), size.y.div_ceil(8), 1],
        )],
    );
    log.record(name);
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    for (name, word) in PHOTON_MAP_COUNTERS {
        let at = word * 4;
        diagnostics.record_u32(ctx.command_encoder(), &state.header.slice(at..at + 4), name);
    }
    // The shared temporal stage, once the gather wrote this frame's mean.
    if let (Some(t), Some(p)) = (temporal, temporal_pipelines.as_deref()) {
        temporal::accumulate(&mut ctx, (&cache, p, &settle), t, (buffer, depth), &log);
    }
    view_settle.inspect(|s| s.mark_ran());
}
