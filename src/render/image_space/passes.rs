//! The image-space passes, in `Core3d` after the deferred lighting (they read the view's
//! depth and G-buffer) and before the composite: per light the three RSM layers, the photon
//! trace, then the resolve and (with `denoise`) SVGF's temporal, variance and à-trous passes
//! into the caustics buffer. Each pass records a GPU span and its name in the dispatch log.

use bevy::core_pipeline::prepass::ViewPrepassTextures;
use std::sync::atomic::Ordering;

use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BufferBinding, ComputePassDescriptor, ComputePipeline, LoadOp,
    Operations, PipelineCache, RenderPassColorAttachment, RenderPassDepthStencilAttachment,
    RenderPassDescriptor, StoreOp, TextureView,
};
use bevy::render::renderer::{RenderContext, ViewQuery};

use super::pipelines::ImageSpacePipelines;
use super::view::{
    COUNTER_WORDS, ImageSpaceFrame, ImageSpaceScene, ImageSpaceViewState, LIGHT_STRIDE,
    SMALL_STRIDE,
};
use crate::render::span::SpanSettle;
use crate::render::temporal::{self, TemporalPipelines, ViewTemporal};
use crate::render::{CausticsDispatchLog, ViewCausticsBuffer, photon_groups};

/// The RSM layers (opaque, caster front, caster back); the spans time the first light's.
pub const RSM_PASSES: [&str; 3] = [
    "caustics/image_space/rsm_opaque",
    "caustics/image_space/rsm_front",
    "caustics/image_space/rsm_back",
];
/// The nearest-depth pyramids (with `hi_z`).
pub const HIZ_PASS: &str = "caustics/image_space/hiz";
/// Photon generation, both marches and the deposit.
pub const TRACE_PASS: &str = "caustics/image_space/trace";
/// Photon map to irradiance, depth and normal for the denoiser.
pub const RESOLVE_PASS: &str = "caustics/image_space/resolve";
/// SVGF temporal accumulation.
pub const TEMPORAL_PASS: &str = "caustics/image_space/temporal";
/// SVGF variance.
pub const VARIANCE_PASS: &str = "caustics/image_space/variance";
/// SVGF à-trous iterations.
pub const ATROUS_PASS: &str = "caustics/image_space/atrous";

/// Every pass, for diagnostics readers.
pub const ALL_PASSES: [&str; 9] = [
    RSM_PASSES[0],
    RSM_PASSES[1],
    RSM_PASSES[2],
    HIZ_PASS,
    TRACE_PASS,
    RESOLVE_PASS,
    TEMPORAL_PASS,
    VARIANCE_PASS,
    ATROUS_PASS,
];

/// Counters read into diagnostics (`render/caustics/image_space/<name>`), by word (`C_*` in
/// trace.wgsl).
pub const IMAGE_SPACE_COUNTERS: [(&str, u64); 19] = [
    ("caustics/image_space/emitted", 0),
    ("caustics/image_space/empty", 1),
    ("caustics/image_space/dim", 2),
    ("caustics/image_space/light_hits", 3),
    ("caustics/image_space/light_misses", 4),
    ("caustics/image_space/plane", 5),
    ("caustics/image_space/concave", 6),
    ("caustics/image_space/convex", 7),
    ("caustics/image_space/camera_hits", 8),
    ("caustics/image_space/misses", 9),
    ("caustics/image_space/normal_rejects", 10),
    ("caustics/image_space/tir", 11),
    ("caustics/image_space/clamped", 12),
    ("caustics/image_space/nan_guards", 13),
    ("caustics/image_space/inside", 14),
    ("caustics/image_space/direct", 15),
    ("caustics/image_space/trapped", 16),
    ("caustics/image_space/mirror_chain", 17),
    ("caustics/image_space/mirror_cap", 18),
];

/// The textures of one compute pass: four sampled inputs, three storage outputs.
struct Slots<'a> {
    src: [&'a TextureView; 4],
    out: [&'a TextureView; 3],
}

struct Ctx<'a> {
    state: &'a ImageSpaceViewState,
    pipelines: &'a ImageSpacePipelines,
    cache: &'a PipelineCache,
    depth: &'a TextureView,
    gbuffer: &'a TextureView,
    materials: &'a bevy::render::render_resource::Buffer,
    settle: &'a SpanSettle,
}

impl Ctx<'_> {
    fn group(&self, ctx: &RenderContext, slots: Slots) -> BindGroup {
        let s = self.state;
        let small = |b| BufferBinding {
            buffer: b,
            offset: 0,
            size: std::num::NonZeroU64::new(SMALL_STRIDE),
        };
        ctx.render_device().create_bind_group(
            "caustics:bind_group:image_space",
            &self
                .cache
                .get_bind_group_layout(&self.pipelines.compute_layout),
            &BindGroupEntries::sequential((
                s.params.as_entire_binding(),
                BufferBinding {
                    buffer: &s.lights,
                    offset: 0,
                    size: std::num::NonZeroU64::new(LIGHT_STRIDE),
                },
                &s.rsm.1,
                self.depth,
                self.gbuffer,
                self.materials.as_entire_binding(),
                s.map.as_entire_binding(),
                s.counters.as_entire_binding(),
                slots.src[0],
                slots.src[1],
                slots.src[2],
                slots.src[3],
                slots.out[0],
                slots.out[1],
                slots.out[2],
                small(&s.steps),
                s.hiz.as_entire_binding(),
                s.lights.as_entire_binding(),
            )),
        )
    }
}

fn compute_pass(
    ctx: &mut RenderContext,
    settle: &SpanSettle,
    name: &'static str,
    pipeline: &ComputePipeline,
    group: &BindGroup,
    dispatches: &[([u32; 2], [u32; 3])],
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
    pass.set_pipeline(pipeline);
    for (offsets, groups) in dispatches {
        pass.set_bind_group(0, group, offsets);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }
    span.end(&mut pass);
}

/// The system.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn image_space_passes(
    view: ViewQuery<(
        &ViewCausticsBuffer,
        &ViewPrepassTextures,
        &ImageSpaceViewState,
        &ImageSpaceFrame,
        Option<&crate::render::settle::ViewSettle>,
        Option<&ViewTemporal>,
    )>,
    scene: Option<Res<ImageSpaceScene>>,
    temporal_pipelines: Option<Res<TemporalPipelines>>,
    pipelines: Option<Res<ImageSpacePipelines>>,
    specialization: Option<Res<crate::render::trace::TraceSpecialization>>,
    cache: Res<PipelineCache>,
    log: Res<CausticsDispatchLog>,
    settle: Res<SpanSettle>,
    mut ctx: RenderContext,
) {
    let (buffer, prepass, state, _, view_settle, temporal) = view.into_inner();
    let (Some(scene), Some(pipelines)) = (scene, pipelines) else {
        return;
    };
    let (Some(depth), Some(gbuffer)) = (prepass.depth_view(), prepass.deferred_view()) else {
        return;
    };
    let compute: Option<Vec<&ComputePipeline>> = pipelines
        .compute
        .iter()
        .map(|id| cache.get_compute_pipeline(*id))
        .collect();
    let rsm: Option<Vec<_>> = pipelines
        .rsm
        .iter()
        .map(|id| cache.get_render_pipeline(*id))
        .collect();
    // The scene's specialised trace (none this frame while it compiles).
    let trace = pipelines
        .trace
        .get(super::pipelines::trace_features(
            &scene,
            specialization.as_deref(),
        ))
        .and_then(|id| cache.get_compute_pipeline(id));
    let (Some(compute), Some(rsm), Some(trace)) = (compute, rsm, trace) else {
        return;
    };
    // The RSMs only when the scene changed since they were drawn (not on camera moves).
    let generation = scene.scene.generation;
    if state.rsm_drawn.load(Ordering::Relaxed) != generation {
        rsm_passes(
            &mut ctx,
            &settle,
            state,
            scene.as_ref(),
            &pipelines,
            &cache,
            &rsm,
        );
        for name in RSM_PASSES {
            log.record(name);
        }
        state.rsm_drawn.store(generation, Ordering::Relaxed);
    }
    let c = Ctx {
        state,
        pipelines: &pipelines,
        cache: &cache,
        depth,
        gbuffer,
        materials: &scene.scene.materials,
        settle: &settle,
    };
    let d_in = &state.dummy_in;
    let d_out = &state.dummy_out;
    let full = [
        state.key.size.x.div_ceil(8),
        state.key.size.y.div_ceil(8),
        1,
    ];
    ctx.command_encoder().clear_buffer(&state.counters, 0, None);
    // Trace: one dispatch per light.
    let group = c.group(
        &ctx,
        Slots {
            src: [d_in, d_in, d_in, d_in],
            out: [&d_out[0], &d_out[1], &d_out[2]],
        },
    );
    let per_light: Vec<_> = scene
        .lights
        .iter()
        .enumerate()
        .map(|(l, (_, face))| {
            let n = if face.is_some() {
                state.photons.div_ceil(6)
            } else {
                state.photons
            };
            ([(l as u64 * LIGHT_STRIDE) as u32, 0], photon_groups(n))
        })
        .collect();
    if state.settings.hi_z {
        let h = state.hiz_layout;
        let mut dispatches = Vec::new();
        for plane in 0..h.planes {
            let size0 = if plane == 0 {
                state.key.size
            } else {
                UVec2::splat(state.key.rsm)
            };
            for level in 0..h.levels(plane) {
                let size = (size0 + UVec2::splat((1 << level) - 1)) >> level;
                let step = (super::view::HizLayout::step(plane, level) * SMALL_STRIDE) as u32;
                dispatches.push(([0, step], [size.x.div_ceil(8), size.y.div_ceil(8), 1]));
            }
        }
        compute_pass(&mut ctx, &settle, HIZ_PASS, compute[5], &group, &dispatches);
        log.record(HIZ_PASS);
    }
    compute_pass(&mut ctx, &settle, TRACE_PASS, trace, &group, &per_light);
    log.record(TRACE_PASS);
    let parity = (state.frame & 1) as usize;
    let (cur, prev) = (parity, 1 - parity);
    let denoise = state.settings.denoise;
    // Resolve: the raw photon map (or straight into the caustics buffer).
    let raw_out = if denoise { &state.raw.1 } else { &buffer.view };
    let group = c.group(
        &ctx,
        Slots {
            src: [d_in, d_in, d_in, d_in],
            out: [raw_out, &state.zn[cur].1, &d_out[2]],
        },
    );
    compute_pass(
        &mut ctx,
        &settle,
        RESOLVE_PASS,
        compute[0],
        &group,
        &[([0, 0], full)],
    );
    log.record(RESOLVE_PASS);
    if denoise {
        svgf_passes(&mut ctx, &c, &compute, buffer, (cur, prev), full, &log);
    }
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    for (name, word) in IMAGE_SPACE_COUNTERS {
        let at = word * 4;
        diagnostics.record_u32(
            ctx.command_encoder(),
            &state.counters.slice(at..at + 4),
            name,
        );
    }
    debug_assert!(IMAGE_SPACE_COUNTERS.len() as u64 <= COUNTER_WORDS);
    // The shared temporal stage, once SVGF wrote this frame's output.
    if let (Some(t), Some(p)) = (temporal, temporal_pipelines.as_deref()) {
        temporal::accumulate(&mut ctx, (&cache, p, &settle), t, (buffer, depth), &log);
    }
    view_settle.inspect(|s| s.mark_ran());
}

/// SVGF: temporal (raw → filter[1], moments), variance (filter[1] → filter[0]), then
/// the à-trous iterations ping-ponging, the last one into the caustics buffer.
fn svgf_passes(
    ctx: &mut RenderContext,
    c: &Ctx,
    compute: &[&ComputePipeline],
    buffer: &ViewCausticsBuffer,
    (cur, prev): (usize, usize),
    full: [u32; 3],
    log: &CausticsDispatchLog,
) {
    let s = c.state;
    let d_in = &s.dummy_in;
    let d_out = &s.dummy_out;
    let group = c.group(
        ctx,
        Slots {
            src: [
                &s.raw.1,
                &s.history[prev].1,
                &s.moments[prev].1,
                &s.zn[prev].1,
            ],
            out: [&s.filter[1].1, &s.moments[cur].1, &d_out[2]],
        },
    );
    compute_pass(
        ctx,
        c.settle,
        TEMPORAL_PASS,
        compute[1],
        &group,
        &[([0, 0], full)],
    );
    log.record(TEMPORAL_PASS);
    let n = s.settings.atrous_iterations;
    let target =
        |k: u32, i: usize| -> &TextureView { if k == n { &buffer.view } else { &s.filter[i].1 } };
    let history = |k: u32| -> &TextureView {
        if k == super::view::history_step(n, s.still_view) {
            &s.history[cur].1
        } else {
            &d_out[1]
        }
    };
    let group = c.group(
        ctx,
        Slots {
            src: [&s.filter[1].1, d_in, &s.moments[cur].1, &s.zn[cur].1],
            out: [target(0, 0), history(0), &d_out[2]],
        },
    );
    compute_pass(
        ctx,
        c.settle,
        VARIANCE_PASS,
        compute[2],
        &group,
        &[([0, 0], full)],
    );
    log.record(VARIANCE_PASS);
    if n == 0 {
        return;
    }
    // Iteration i reads filter[i % 2] and writes filter[(i + 1) % 2] (or the buffer): first
    // each pixel's luminance deviation and depth gradient into `aux`, then the gather.
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let groups: Vec<[BindGroup; 2]> = (1..=n)
        .map(|k| {
            let i = (k - 1) as usize;
            let input = &s.filter[i % 2].1;
            let prep = Slots {
                src: [input, d_in, d_in, &s.zn[cur].1],
                out: [&d_out[0], &d_out[1], &s.aux.1],
            };
            let gather = Slots {
                src: [input, &s.aux.1, &s.moments[cur].1, &s.zn[cur].1],
                out: [target(k, (i + 1) % 2), history(k), &d_out[2]],
            };
            [c.group(ctx, prep), c.group(ctx, gather)]
        })
        .collect();
    let encoder = ctx.command_encoder();
    let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
        label: Some(ATROUS_PASS),
        timestamp_writes: None,
    });
    let span = diagnostics.pass_span(&mut pass, ATROUS_PASS);
    c.settle.settle(&mut pass);
    for (k, stages) in groups.iter().enumerate() {
        let offsets = [0, ((k as u64 + 1) * SMALL_STRIDE) as u32];
        for (j, group) in stages.iter().enumerate() {
            pass.set_pipeline(compute[3 + j]);
            pass.set_bind_group(0, group, &offsets);
            pass.dispatch_workgroups(full[0], full[1], full[2]);
        }
    }
    span.end(&mut pass);
    log.record(ATROUS_PASS);
}

/// The three layers of every light's RSM.
fn rsm_passes(
    ctx: &mut RenderContext,
    settle: &SpanSettle,
    state: &ImageSpaceViewState,
    scene: &ImageSpaceScene,
    pipelines: &ImageSpacePipelines,
    cache: &PipelineCache,
    rsm: &[&bevy::render::render_resource::RenderPipeline],
) {
    let group = ctx.render_device().create_bind_group(
        "caustics:bind_group:image_space_rsm",
        &cache.get_bind_group_layout(&pipelines.rsm_layout),
        &BindGroupEntries::sequential((
            BufferBinding {
                buffer: &state.rsm_views,
                offset: 0,
                size: std::num::NonZeroU64::new(SMALL_STRIDE),
            },
            scene.scene.tris.as_entire_binding(),
            scene.scene.materials.as_entire_binding(),
        )),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    for l in 0..scene.lights.len() {
        for (layer, pipeline) in rsm.iter().enumerate() {
            let view = &state.rsm_layers[3 * l + layer];
            let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
                label: Some("caustics_image_space_rsm"),
                color_attachments: &[Some(RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: Operations {
                        load: LoadOp::Clear(Default::default()),
                        store: StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(RenderPassDepthStencilAttachment {
                    view: &state.rsm_depth,
                    depth_ops: Some(Operations {
                        load: LoadOp::Clear(1.0),
                        store: StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let span = (l == 0).then(|| diagnostics.pass_span(&mut pass, RSM_PASSES[layer]));
            if l == 0 {
                settle.settle(&mut pass);
            }
            if scene.scene.tri_count > 0 {
                pass.set_render_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[(l as u64 * SMALL_STRIDE) as u32]);
                pass.draw(0..scene.scene.tri_count * 3, 0..1);
            }
            if let Some(span) = span {
                span.end(&mut pass);
            }
        }
    }
}
