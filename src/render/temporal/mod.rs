//! The temporal stage shared by the techniques (issue 28): a view's caustics buffer, as a
//! technique left it this frame, blended into a per-pixel history, and the blend written back
//! over the buffer. It knows no technique: one asks for it by putting a
//! [`TemporalAccumulation`] on its view (its prepare system, render world) and calling
//! [`accumulate`] at the end of its passes.
//!
//! A technique's estimate covers [`TemporalAccumulation::frames`] frames: 1 for one that
//! shows each frame alone (AAPS), which then gets a running mean over at most
//! [`TemporalAccumulation::max_history`] frames (then an exponential mean of that length);
//! more for one that keeps its own mean (the photon map's progressive frames since it last
//! restarted), whose prior from before its restart then fades as its own mean grows
//! (`accumulate.wgsl` has the rule). The view's [`ViewSettle::change`] decides what the
//! history is worth:
//!
//! | change since the last frame | history |
//! | --- | --- |
//! | none | kept whole: the new estimate differs from it by noise only |
//! | the scene only (a light, a caster, a receiver or a material) | taken from where the caustic moved (each [`MOTION_TILE`]² tile's best-fitting shift of the last output, to a quarter pixel, when it fits 2 % better than none), then dropped per pixel where it lies outside the estimate's 3x3 luminance mean ± [`TemporalAccumulation::clamp_sigma`] standard errors of that mean (3 times as wide for a shifted history; [`CLAMPED_HISTORY`]), kept elsewhere; tested again on each of the next [`TemporalAccumulation::max_history`] frames |
//! | the camera alone (the scene at most as above without a caustic change) | reprojected: each pixel takes the history of the pixel that showed its surface last frame (its world position through last frame's `clip_from_world`), dropped where that was off screen or showed another surface (depth) |
//! | the viewport, the settings, the buffer | dropped |
//!
//! So a light that jitters or a far object that moves keeps the history where the caustic did
//! not change, a caustic that moves with its caster keeps its history (`docs/temporal.md`, "A
//! moving caster"), and a moved caustic leaves no ghost. A view that settles
//! ([`crate::Caustics::settle_frames`]) keeps the output it reached.
//!
//! Cost: 72 bytes per pixel (two of each of the `Rgba32Float` prior and last output and the
//! `R32Float` depth, read one frame and written the next) and 4 bytes per motion tile, one
//! compute dispatch reading 12 texels per pixel (up to 32 where a shifted history is
//! resampled), and one copy of the view-sized output into the caustics buffer per frame; on a
//! frame in which a caustic changed, one more dispatch (41 shifts x 64 bilinear reads per tile).
//!
//! A technique may ask for a spatial filter over the output
//! ([`TemporalAccumulation::spatial_passes`], `spatial.wgsl`): à-trous iterations with SVGF's
//! depth and luminance edge stopping on the output's deviation, the history left unfiltered
//! (`docs/temporal.md`, "The spatial filter"). It costs [`SPATIAL_BYTES_PER_PIXEL`] and one
//! view-sized dispatch for its preparation and one per iteration.

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};

use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer,
    BufferDescriptor, BufferUsages, CachedComputePipelineId, ComputePassDescriptor,
    ComputePipeline, ComputePipelineDescriptor, Extent3d, PipelineCache, ShaderStages,
    StorageTextureAccess, TexelCopyTextureInfo, Texture, TextureFormat, TextureSampleType,
    TextureUsages, TextureView, binding_types,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue};
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

use super::settle::{SettleChange, ViewSettle};
use super::span::SpanSettle;
use super::{CausticsDispatchLog, ExtractedCaustics, ViewCausticsBuffer};
use crate::CausticsTechnique;
use bevy::render::view::ExtractedView;

/// GPU span and dispatch-log name of the stage.
pub const TEMPORAL_PASS: &str = "caustics/temporal";

/// The default width of the history clamp, standard errors of the 3x3 mean
/// ([`TemporalAccumulation::clamp_sigma`]).
pub const DEFAULT_CLAMP_SIGMA: f32 = 1.0;

/// History frames a pixel keeps after its history was clamped (the scene changed there): none.
/// With 4, image space's caustic took more than 8 frames to come back after the sun turned
/// 8 degrees and back (RMSE 444 lx at the 8th frame against 227 settled): a technique that
/// restarts its own mean has few frames to outweigh a clamped prior.
pub const CLAMPED_HISTORY: f32 = 0.0;

/// Bytes per pixel of a view's histories: two each of the prior, the last output and the
/// depth they belong to.
pub const TEMPORAL_BYTES_PER_PIXEL: u64 = 2 * (16 + 16 + 4);

/// Bytes per pixel of a view's spatial filter, when it has one: two `Rgba32Float` scratch
/// outputs.
pub const SPATIAL_BYTES_PER_PIXEL: u64 = 2 * 16;

/// A pixel whose depth changed by more than this share on a frame in which the scene's
/// geometry changed shows another surface: its history is dropped (and the photon map
/// restarts its mean there when its eye distance changed by as much).
pub const SURFACE_DEPTH_TOLERANCE: f32 = 0.02;

const FLAG_RESET: u32 = 1;
const FLAG_CLAMP: u32 = 2;
const FLAG_SURFACES: u32 = 4;
const FLAG_REPROJECT: u32 = 8;
const FLAG_MOTION: u32 = 16;

/// Side of a caustic-motion tile, pixels (`MOTION_TILE` in `accumulate.wgsl`).
pub const MOTION_TILE: u32 = 8;

/// Bytes of the stage's parameters (`TemporalParams` in `accumulate.wgsl`).
const PARAMS_BYTES: u64 = 112;

/// A technique's request for the stage on a view (render world; inserted by its prepare
/// system each frame it runs). It holds while the view's technique is its `owner`.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct TemporalAccumulation {
    /// The technique that asked (another technique on the view drops the history).
    pub owner: CausticsTechnique,
    /// Frames in the running mean, at least 1 (1: no accumulation, the buffer as drawn).
    pub max_history: u32,
    /// The history clamp's width on a frame in which the scene changed, in standard errors
    /// of the current frame's 3x3 luminance mean (its standard deviation over 3).
    pub clamp_sigma: f32,
    /// Frames the technique's estimate of this frame covers (at least 1; 1 for a single
    /// frame, `n` for a mean of the last `n` frames that the technique keeps itself).
    pub frames: u32,
    /// À-trous iterations of the spatial filter over the output (`spatial.wgsl`), at most
    /// [`MAX_SPATIAL_PASSES`]; 0: none (the output as accumulated). Each costs one view-sized
    /// dispatch of 25 taps; with any, one preparation dispatch more, and the view holds two
    /// more `Rgba32Float` textures.
    pub spatial_passes: u32,
}

/// The most à-trous iterations of the spatial filter (steps 1, 2, 4 pixels).
pub const MAX_SPATIAL_PASSES: u32 = 3;

/// The spatial filter's luminance edge stopping, in standard deviations of the output
/// (SVGF's sigma_l is 4). Measured on the photon map's `glass_sphere` (still / sliding ball,
/// lux): 1 gave 94.0 / 135.5, 2 gave 82.3 / 130.5, 4 gave 75.8 / 145.9 (`docs/temporal.md`).
pub const SPATIAL_SIGMA_L: f32 = 2.0;

/// The spatial filter's depth edge stopping, in depth gradients (SVGF's sigma_z).
pub const SPATIAL_SIGMA_Z: f32 = 1.0;

/// Bytes of the spatial filter's parameters per iteration (`SpatialParams` in `spatial.wgsl`).
const SPATIAL_PARAMS_BYTES: u64 = 32;

/// A view's spatial filter: two scratch outputs in turn, and one parameter buffer for the
/// preparation and each iteration.
struct SpatialTargets {
    /// `Rgba32Float`: the output so far (rgb) and its luminance deviation (a).
    scratch: [(Texture, TextureView); 2],
    params: Vec<Buffer>,
}

/// A view's histories (render world).
#[derive(Component)]
pub struct ViewTemporal {
    size: UVec2,
    /// `Rgba32Float`: the prior (rgb) and its frames; two, read and written in turn.
    prior: [(Texture, TextureView); 2],
    /// `Rgba32Float`: the last output (rgb) and the estimate's alpha; two, in turn.
    last: [(Texture, TextureView); 2],
    /// `R32Float`: the view's depth (reverse-Z NDC) the history belongs to; two, in turn.
    depth: [(Texture, TextureView); 2],
    params: Buffer,
    /// Per [`MOTION_TILE`] tile: where its history lies (`accumulate.wgsl`'s `motion`).
    tile_motion: Buffer,
    /// This frame's `FLAG_*` bits.
    flags: AtomicU32,
    /// The history read next.
    read: AtomicUsize,
    /// The next run drops the history (set by a change, cleared by a run).
    reset: AtomicBool,
    /// The next run drops the history of pixels whose surface moved (set by a change of the
    /// scene's geometry, cleared by a run).
    surfaces: AtomicBool,
    /// Runs left that test the history against the estimate: [`TemporalAccumulation::
    /// max_history`] from the last change of the scene (the frames its prior can still weigh).
    probation: AtomicU32,
    /// Frames of this frame's estimate (f32 bits), and of the last run's.
    k: AtomicU32,
    k_last: AtomicU32,
    /// The camera's `clip_from_world` of the last frame (the one the history belongs to).
    clip_from_world: Mat4,
    /// With [`TemporalAccumulation::spatial_passes`] above 0.
    spatial: Option<SpatialTargets>,
}

impl ViewTemporal {
    /// GPU bytes held (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        let pixels = self.size.x as u64 * self.size.y as u64;
        let spatial = self.spatial.as_ref().map_or(0, |s| {
            pixels * SPATIAL_BYTES_PER_PIXEL + s.params.iter().map(|b| b.size()).sum::<u64>()
        });
        pixels * TEMPORAL_BYTES_PER_PIXEL + self.params.size() + self.tile_motion.size() + spatial
    }

    fn spatial_passes(&self) -> u32 {
        self.spatial
            .as_ref()
            .map_or(0, |s| s.params.len() as u32 - 1)
    }
}

/// The stage's pipeline.
#[derive(Resource)]
pub struct TemporalPipelines {
    layout: BindGroupLayoutDescriptor,
    accumulate: CachedComputePipelineId,
    motion: CachedComputePipelineId,
    spatial_layout: BindGroupLayoutDescriptor,
    spatial_prep: CachedComputePipelineId,
    spatial_atrous: CachedComputePipelineId,
}

#[derive(Resource)]
struct TemporalShader {
    accumulate: Handle<Shader>,
    spatial: Handle<Shader>,
}

/// Register the stage (render app); called from [`crate::render::build`].
pub(crate) fn build(app: &mut App) {
    let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
    let shader = TemporalShader {
        accumulate: shaders.add(Shader::from_wgsl(
            include_str!("accumulate.wgsl"),
            "bevy_caustics/temporal_accumulate.wgsl",
        )),
        spatial: shaders.add(Shader::from_wgsl(
            [include_str!("../optics.wgsl"), include_str!("spatial.wgsl")].join("\n"),
            "bevy_caustics/temporal_spatial.wgsl",
        )),
    };
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(shader)
        .add_systems(RenderStartup, init_pipelines)
        .add_systems(
            Render,
            prepare_temporal.in_set(RenderSystems::PrepareBindGroups),
        );
}

fn init_pipelines(mut commands: Commands, cache: Res<PipelineCache>, shader: Res<TemporalShader>) {
    use binding_types::*;
    let float = TextureSampleType::Float { filterable: false };
    let layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:temporal",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, None),
                texture_2d(float),
                texture_2d(float),
                texture_2d(float),
                texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                texture_depth_2d(),
                texture_2d(float),
                texture_storage_2d(TextureFormat::R32Float, StorageTextureAccess::WriteOnly),
                storage_buffer_sized(false, None),
            ),
        ),
    );
    let spatial_layout = BindGroupLayoutDescriptor::new(
        "caustics:bind_group_layout:temporal_spatial",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, None),
                texture_2d(float),
                texture_2d(float),
                texture_2d(float),
                texture_2d(float),
                texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                texture_2d(float),
            ),
        ),
    );
    let pipeline =
        |name: &'static str, layout: &BindGroupLayoutDescriptor, shader: &Handle<Shader>| {
            cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(format!("caustics:pipeline:temporal_{name}").into()),
                layout: vec![layout.clone()],
                shader: shader.clone(),
                entry_point: Some(name.into()),
                ..default()
            })
        };
    commands.insert_resource(TemporalPipelines {
        accumulate: pipeline("accumulate", &layout, &shader.accumulate),
        motion: pipeline("motion", &layout, &shader.accumulate),
        spatial_prep: pipeline("spatial_prep", &spatial_layout, &shader.spatial),
        spatial_atrous: pipeline("spatial_atrous", &spatial_layout, &shader.spatial),
        layout,
        spatial_layout,
    });
}

fn history_texture(
    device: &RenderDevice,
    label: &'static str,
    size: UVec2,
) -> (Texture, TextureView) {
    let usage =
        TextureUsages::TEXTURE_BINDING | TextureUsages::STORAGE_BINDING | TextureUsages::COPY_SRC;
    let texture = super::view_texture(device, label, size, usage);
    let view = texture.create_view(&default());
    (texture, view)
}

fn depth_history(device: &RenderDevice, size: UVec2) -> (Texture, TextureView) {
    let usage = TextureUsages::TEXTURE_BINDING | TextureUsages::STORAGE_BINDING;
    let texture = super::view_texture_of(
        device,
        "caustics_temporal_depth",
        size,
        TextureFormat::R32Float,
        usage,
    );
    let view = texture.create_view(&default());
    (texture, view)
}

impl SpatialTargets {
    fn new(device: &RenderDevice, size: UVec2, passes: u32) -> Self {
        Self {
            scratch: [0, 1].map(|_| history_texture(device, "caustics_temporal_spatial", size)),
            params: (0..=passes)
                .map(|_| {
                    device.create_buffer(&BufferDescriptor {
                        label: Some("caustics_temporal_spatial_params"),
                        size: SPATIAL_PARAMS_BYTES,
                        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    })
                })
                .collect(),
        }
    }

    /// Write the preparation's and each iteration's parameters.
    fn write_params(&self, queue: &RenderQueue, size: UVec2, k: f32) {
        let last = self.params.len() - 1;
        for (i, buffer) in self.params.iter().enumerate() {
            let step = if i == 0 { 0u32 } else { 1 << (i - 1) };
            let flags = u32::from(i == last && i > 0);
            let mut bytes = Vec::with_capacity(SPATIAL_PARAMS_BYTES as usize);
            for v in [size.x, size.y, step, flags] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            for v in [k, SPATIAL_SIGMA_L, SPATIAL_SIGMA_Z, 0.0] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            queue.write_buffer(buffer, 0, &bytes);
        }
    }
}

impl ViewTemporal {
    fn new(device: &RenderDevice, size: UVec2, spatial_passes: u32) -> Self {
        let texture = |label| history_texture(device, label, size);
        Self {
            size,
            prior: [0, 1].map(|_| texture("caustics_temporal_prior")),
            last: [0, 1].map(|_| texture("caustics_temporal_last")),
            depth: [0, 1].map(|_| depth_history(device, size)),
            params: device.create_buffer(&BufferDescriptor {
                label: Some("caustics_temporal_params"),
                size: PARAMS_BYTES,
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            tile_motion: device.create_buffer(&BufferDescriptor {
                label: Some("caustics_temporal_tile_motion"),
                size: 4 * u64::from(size.x.div_ceil(MOTION_TILE) * size.y.div_ceil(MOTION_TILE)),
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            flags: AtomicU32::new(0),
            read: AtomicUsize::new(0),
            reset: AtomicBool::new(true),
            surfaces: AtomicBool::new(false),
            probation: AtomicU32::new(0),
            k: AtomicU32::new(1f32.to_bits()),
            k_last: AtomicU32::new(1f32.to_bits()),
            clip_from_world: Mat4::IDENTITY,
            spatial: (spatial_passes > 0)
                .then(|| SpatialTargets::new(device, size, spatial_passes)),
        }
    }
}

/// Create (or resize) the histories of every view that asks for the stage, note this frame's
/// change and write the parameters; drop the histories of views that no longer ask.
#[allow(clippy::type_complexity)]
pub fn prepare_temporal(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut views: Query<(
        Entity,
        Option<&TemporalAccumulation>,
        Option<&ExtractedCaustics>,
        Option<&ViewCausticsBuffer>,
        Option<&ViewSettle>,
        Option<&mut ViewTemporal>,
        &ExtractedView,
    )>,
) {
    for (entity, request, caustics, buffer, settle, temporal, view) in &mut views {
        let owned = request
            .zip(caustics)
            .filter(|(r, c)| r.owner == c.technique)
            .map(|(r, _)| r);
        let (Some(request), Some(buffer)) = (owned, buffer) else {
            if temporal.is_some() {
                commands.entity(entity).remove::<ViewTemporal>();
            }
            continue;
        };
        let mut fresh = None;
        let passes = request.spatial_passes.min(MAX_SPATIAL_PASSES);
        let fits = |t: &ViewTemporal| t.size == buffer.size && t.spatial_passes() == passes;
        let new = !temporal.as_ref().is_some_and(|t| fits(t));
        let temporal = match temporal {
            Some(t) if fits(&t) => t.into_inner(),
            _ => {
                fresh = Some(ViewTemporal::new(&device, buffer.size, passes));
                fresh.as_mut().unwrap()
            }
        };
        let now = super::clip_from_world(view);
        let reproject = note_change(temporal, request, settle, new);
        let caustic_changed = settle.is_some_and(|s| s.change == SettleChange::Scene);
        let flags = if temporal.reset.load(Ordering::Relaxed) {
            FLAG_RESET
        } else {
            let on = |b: bool, f: u32| if b { f } else { 0 };
            on(temporal.probation.load(Ordering::Relaxed) > 0, FLAG_CLAMP)
                | on(temporal.surfaces.load(Ordering::Relaxed), FLAG_SURFACES)
                | on(reproject, FLAG_REPROJECT)
                | on(caustic_changed && !reproject, FLAG_MOTION)
        };
        temporal.flags.store(flags, Ordering::Relaxed);
        let k = request.frames.max(1) as f32;
        temporal.k.store(k.to_bits(), Ordering::Relaxed);
        // Last frame's clip from this frame's clip, in f64 (a reverse-Z projection's inverse
        // loses digits in f32).
        let reprojection =
            (temporal.clip_from_world.as_dmat4() * now.as_dmat4().inverse()).as_mat4();
        temporal.clip_from_world = now;
        let bytes = params_bytes(buffer.size, flags, k, temporal, request, reprojection);
        queue.write_buffer(&temporal.params, 0, &bytes);
        if let Some(s) = &temporal.spatial {
            s.write_params(&queue, buffer.size, k);
        }
        if let Some(t) = fresh {
            commands.entity(entity).insert(t);
        }
    }
}

/// Note this frame's change in `temporal`; true when the history is to be reprojected (the
/// camera alone moved, and there is a history).
fn note_change(
    temporal: &ViewTemporal,
    request: &TemporalAccumulation,
    settle: Option<&ViewSettle>,
    fresh: bool,
) -> bool {
    match settle.map_or(SettleChange::View, |s| s.change) {
        SettleChange::None => false,
        SettleChange::Surfaces => {
            temporal.surfaces.store(true, Ordering::Relaxed);
            false
        }
        SettleChange::Scene => {
            temporal
                .probation
                .store(request.max_history.max(1), Ordering::Relaxed);
            temporal.surfaces.store(true, Ordering::Relaxed);
            false
        }
        SettleChange::View if !fresh && settle.is_some_and(|s| s.camera_only) => true,
        SettleChange::View => {
            temporal.reset.store(true, Ordering::Relaxed);
            temporal.probation.store(0, Ordering::Relaxed);
            false
        }
    }
}

/// The stage's parameters (`TemporalParams` in `accumulate.wgsl`).
fn params_bytes(
    size: UVec2,
    flags: u32,
    k: f32,
    temporal: &ViewTemporal,
    request: &TemporalAccumulation,
    reprojection: Mat4,
) -> Vec<u8> {
    let clamp_sigma = if request.clamp_sigma.is_finite() {
        request.clamp_sigma.max(0.0)
    } else {
        0.0
    };
    let mut bytes = Vec::with_capacity(PARAMS_BYTES as usize);
    for v in [size.x, size.y, flags] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in [
        k,
        f32::from_bits(temporal.k_last.load(Ordering::Relaxed)),
        request.max_history.max(1) as f32,
        clamp_sigma,
        CLAMPED_HISTORY,
        SURFACE_DEPTH_TOLERANCE,
    ] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.resize(48, 0);
    for v in reprojection.to_cols_array() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes
}

/// Whether a view's stage can run this frame: it has none, or its pipeline is compiled. A
/// technique whose history is the stage's alone (AAPS) runs nothing while the stage compiles:
/// a frame it traced that the stage did not take would still count towards settling, and the
/// view would keep a mean short of those frames (test
/// `per_frame::change::a_view_settles_on_every_frame_it_counted`). The photon map and image
/// space need not wait: they pass their own mean with its frame count, which loses no frame
/// (measured at stop 48 with the stage held 10 frames: their kept buffers were identical to
/// the unheld runs').
pub fn ready(
    temporal: Option<&ViewTemporal>,
    pipelines: Option<&TemporalPipelines>,
    cache: &PipelineCache,
) -> bool {
    temporal.is_none_or(|t| pipelines.is_some_and(|p| p.compiled(cache, t).is_some()))
}

/// The stage's compiled pipelines.
struct Compiled<'a> {
    accumulate: &'a ComputePipeline,
    motion: &'a ComputePipeline,
    /// The spatial filter's preparation and iteration, where the view has one.
    spatial: Option<[&'a ComputePipeline; 2]>,
}

impl TemporalPipelines {
    /// Every pipeline the view's stage runs, once all are compiled.
    fn compiled<'a>(&self, cache: &'a PipelineCache, view: &ViewTemporal) -> Option<Compiled<'a>> {
        let spatial = match view.spatial {
            Some(_) => Some([
                cache.get_compute_pipeline(self.spatial_prep)?,
                cache.get_compute_pipeline(self.spatial_atrous)?,
            ]),
            None => None,
        };
        Some(Compiled {
            accumulate: cache.get_compute_pipeline(self.accumulate)?,
            motion: cache.get_compute_pipeline(self.motion)?,
            spatial,
        })
    }
}

/// Combine the caustics buffer with the view's history and write the output back over it (one
/// dispatch and one copy, span [`TEMPORAL_PASS`]). Does nothing while the pipeline compiles
/// (AAPS checks [`ready`] first; the photon map's and image space's buffers then show their own
/// mean).
pub fn accumulate(
    ctx: &mut RenderContext,
    (cache, pipelines, span): (&PipelineCache, &TemporalPipelines, &SpanSettle),
    temporal: &ViewTemporal,
    (buffer, depth): (&ViewCausticsBuffer, &TextureView),
    log: &CausticsDispatchLog,
) {
    let Some(compiled) = pipelines.compiled(cache, temporal) else {
        return;
    };
    if temporal.size != buffer.size {
        return;
    }
    let r = temporal.read.load(Ordering::Relaxed) & 1;
    let w = 1 - r;
    let group = ctx.render_device().create_bind_group(
        "caustics:bind_group:temporal",
        &cache.get_bind_group_layout(&pipelines.layout),
        &BindGroupEntries::sequential((
            temporal.params.as_entire_binding(),
            &buffer.view,
            &temporal.prior[r].1,
            &temporal.last[r].1,
            &temporal.prior[w].1,
            &temporal.last[w].1,
            depth,
            &temporal.depth[r].1,
            &temporal.depth[w].1,
            temporal.tile_motion.as_entire_binding(),
        )),
    );
    let spatial = temporal.spatial.as_ref().map(|s| {
        spatial_bind_groups(
            ctx.render_device(),
            cache,
            pipelines,
            (temporal, w),
            buffer,
            s,
        )
    });
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    {
        let mut pass = ctx
            .command_encoder()
            .begin_compute_pass(&ComputePassDescriptor {
                label: Some("caustics_temporal"),
                timestamp_writes: None,
            });
        let s = diagnostics.pass_span(&mut pass, TEMPORAL_PASS);
        span.settle(&mut pass);
        pass.set_bind_group(0, &group, &[]);
        if temporal.flags.load(Ordering::Relaxed) & FLAG_MOTION != 0 {
            pass.set_pipeline(compiled.motion);
            let (x, y) = (buffer.size.x, buffer.size.y);
            pass.dispatch_workgroups(x.div_ceil(MOTION_TILE), y.div_ceil(MOTION_TILE), 1);
        }
        let groups = (buffer.size.x.div_ceil(8), buffer.size.y.div_ceil(8));
        pass.set_pipeline(compiled.accumulate);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
        if let (Some(bind_groups), Some([prep, atrous])) = (&spatial, compiled.spatial) {
            for (i, group) in bind_groups.iter().enumerate() {
                pass.set_pipeline(if i == 0 { prep } else { atrous });
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
        }
        s.end(&mut pass);
    }
    let texture = |t| TexelCopyTextureInfo {
        texture: t,
        mip_level: 0,
        origin: Default::default(),
        aspect: Default::default(),
    };
    // The filtered output where the view has a spatial filter (its last iteration's scratch).
    let shown = match &temporal.spatial {
        Some(s) => &s.scratch[(s.params.len() - 1) % 2].0,
        None => &temporal.last[w].0,
    };
    ctx.command_encoder().copy_texture_to_texture(
        texture(shown),
        texture(&buffer.texture),
        Extent3d {
            width: buffer.size.x,
            height: buffer.size.y,
            depth_or_array_layers: 1,
        },
    );
    log.record(TEMPORAL_PASS);
    temporal.read.store(w, Ordering::Relaxed);
    temporal
        .k_last
        .store(temporal.k.load(Ordering::Relaxed), Ordering::Relaxed);
    temporal.reset.store(false, Ordering::Relaxed);
    temporal.surfaces.store(false, Ordering::Relaxed);
    let probation = temporal.probation.load(Ordering::Relaxed);
    temporal
        .probation
        .store(probation.saturating_sub(1), Ordering::Relaxed);
}

/// The spatial filter's bind groups, in dispatch order: the preparation (the stage's output
/// into scratch 0), then each iteration from one scratch into the other; `w` is the history
/// index this frame writes.
fn spatial_bind_groups(
    device: &RenderDevice,
    cache: &PipelineCache,
    pipelines: &TemporalPipelines,
    (temporal, w): (&ViewTemporal, usize),
    buffer: &ViewCausticsBuffer,
    spatial: &SpatialTargets,
) -> Vec<BindGroup> {
    let layout = cache.get_bind_group_layout(&pipelines.spatial_layout);
    let (output, previous) = (&temporal.last[w].1, &temporal.last[1 - w].1);
    let (prior, depth) = (&temporal.prior[w].1, &temporal.depth[w].1);
    let scratch = |i: usize| &spatial.scratch[i % 2].1;
    spatial
        .params
        .iter()
        .enumerate()
        .map(|(i, params)| {
            // The preparation reads this frame's output and last frame's; an iteration reads
            // the last scratch, and the output for the buffer's alpha.
            let (src, aux) = if i == 0 {
                (output, previous)
            } else {
                (scratch(i - 1), output)
            };
            device.create_bind_group(
                "caustics:bind_group:temporal_spatial",
                &layout,
                &BindGroupEntries::sequential((
                    params.as_entire_binding(),
                    src,
                    aux,
                    prior,
                    depth,
                    scratch(i),
                    &buffer.view,
                )),
            )
        })
        .collect()
}
