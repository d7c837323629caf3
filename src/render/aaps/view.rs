//! Per-view AAPS state: the task buffer (density atlas, quadtree, accumulators), the splat
//! buffer, the indirect arguments, the caustics history for the variance, and the parameters.

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferInitDescriptor, BufferUsages, Extent3d, Texture,
    TextureDescriptor, TextureDimension, TextureUsages, TextureView, TextureViewDescriptor,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::ExtractedView;

use crate::components::{AapsSettings, CausticsTechnique};
use crate::optics::uniform_density;
use crate::render::temporal::TemporalAccumulation;
use crate::render::trace::scene::TraceSceneBuffers;
use crate::render::{CAUSTICS_BUFFER_FORMAT, ExtractedCaustics};

/// Bytes of the `accum` buffer before the per-texel entries (`ACCUM_TEXELS` words).
pub const ACCUM_HEADER_WORDS: u64 = 32;
/// Splats (64 bytes each) of zeros after the splat buffer's capacity, inside its binding: a
/// write past the capacity would land there, and the headless readback checks it stays zero
/// (every splat the trace writes has a non-zero irradiance).
pub const SPLAT_GUARD_SPLATS: u64 = 4;
/// The splat capacity the device can bind: the requested one, less what would push the buffer
/// with its guard region past the storage-binding and buffer size limits (lavapipe: 128 MiB,
/// 2 097 148 splats, the default of `AapsSettings::splat_capacity`).
pub fn splat_capacity(requested: u32, limits: &bevy::render::render_resource::WgpuLimits) -> u32 {
    let max_bytes = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let max = (max_bytes / 64).saturating_sub(SPLAT_GUARD_SPLATS).max(1);
    (requested as u64).clamp(1, max) as u32
}

/// Photons a view traces at most: the budget of every light plus the minimum density of every
/// texel. The budget scaling keeps the total under it, so nothing the task buffer asks for is
/// ever cut (cut photons would lose energy).
pub fn photon_capacity(budget_per_light: u64, lights: u32, tile: u32, min_density: f32) -> u32 {
    let min_sq = crate::optics::floor_square(min_density) as u64;
    (budget_per_light.saturating_mul(lights as u64)
        + min_sq * (tile as u64 * tile as u64) * lights as u64)
        .min(u32::MAX as u64 / 2) as u32
}

/// Stride of the per-level quadtree uniforms (the minimum uniform offset alignment).
pub const LEVEL_STRIDE: u64 = 256;

/// What forces the task buffer to start over.
#[derive(Clone, Debug, PartialEq)]
pub struct StateKey {
    /// Atlas side, tile side, tiles per row, lights.
    pub atlas: [u32; 4],
    /// Splat capacity.
    pub splat_capacity: u32,
    /// Viewport size.
    pub size: UVec2,
    /// Photon budget per light.
    pub budget_per_light: u64,
    /// Adaptive or frozen.
    pub adaptive: bool,
    /// Minimum and maximum density.
    pub min_max: [u32; 2],
    /// Small-splat MSAA target present.
    pub msaa: bool,
    /// Fixed-point splats (no `FLOAT32_BLENDABLE`, `render::fixed_splat`).
    pub fixed: bool,
}

/// The per-view GPU state of AAPS (render world).
#[derive(Component)]
pub struct AapsViewState {
    /// Layout key.
    pub key: StateKey,
    /// Quadtree levels, leaves first (u32).
    pub quadtree: Buffer,
    /// Density atlas (f32) and the update's scratch copy.
    pub density: [Buffer; 2],
    /// Counters and per-texel accumulators.
    pub accum: Buffer,
    /// Splats (64 bytes each).
    pub splats: Buffer,
    /// Indirect arguments (16 u32).
    pub args: Buffer,
    /// `AapsParams` uniform.
    pub params: Buffer,
    /// `world_from_clip` uniform (splat depth test).
    pub world_from_clip: Buffer,
    /// Per-level quadtree uniforms, `LEVEL_STRIDE` apart.
    pub levels: Buffer,
    /// Number of reduce steps (levels above the leaves).
    pub reduce_steps: u32,
    /// Previous frame's caustics buffer.
    pub history: (Texture, TextureView),
    /// 4x multisampled target of the small splats, if small-splat MSAA is on.
    pub msaa: Option<(Texture, TextureView)>,
    /// The fixed-point accumulator of the splats, without `FLOAT32_BLENDABLE`.
    pub fixed: Option<Buffer>,
    /// The previous frame's `clip_from_world` (variance reprojection), once there is one.
    pub prev_clip_from_world: Option<Mat4>,
    /// The settings in use (sanitised).
    pub settings: AapsSettings,
    /// Photon budget of the frame (all lights).
    pub budget: f64,
    /// Photon capacity (tasks traced at most).
    pub photon_capacity: u32,
    /// Frames traced: the key of the frame's sample rotation
    /// ([`crate::optics::frame_rotation`]).
    pub frame: u32,
}

impl AapsViewState {
    /// GPU bytes held (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        use crate::render::memory::{buffer_bytes, texture_bytes};
        buffer_bytes(
            [
                &self.quadtree,
                &self.accum,
                &self.splats,
                &self.args,
                &self.params,
                &self.world_from_clip,
                &self.levels,
            ]
            .into_iter()
            .chain(&self.density)
            .chain(&self.fixed),
        ) + texture_bytes(&self.history.0)
            + self.msaa.as_ref().map_or(0, |m| texture_bytes(&m.0))
    }
}

/// Marks a view whose AAPS passes run this frame (render world).
#[derive(Component)]
pub struct AapsFrame;

/// On the right eye of a [`crate::CausticsStereo`] pair whose left eye runs AAPS: the left
/// eye's view entity. The right eye traces nothing; it rasterises the left eye's splats with
/// its own projection and depth ("one trace, splats per eye"). Splats the left eye culled by
/// its frustum are missing along the right eye's outer edge (a strip as wide as the eyes'
/// parallax).
#[derive(Component, Clone, Copy, Debug)]
pub struct AapsStereo {
    /// The left eye's view entity.
    pub left: Entity,
}

/// The atlas layout for `lights` tiles of side `tile`: (atlas side, tile, tiles per row).
pub fn atlas_layout(tile: u32, lights: u32) -> (u32, u32, u32) {
    let per_row = (lights.max(1) as f32).sqrt().ceil() as u32;
    let mut tile = tile.max(8);
    while (tile * per_row).next_power_of_two() > 4096 && tile > 8 {
        tile /= 2;
    }
    ((tile * per_row).next_power_of_two(), tile, per_row)
}

fn storage(device: &RenderDevice, label: &'static str, size: u64, extra: BufferUsages) -> Buffer {
    device.create_buffer(&BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST | BufferUsages::COPY_SRC | extra,
        mapped_at_creation: false,
    })
}

fn target(
    device: &RenderDevice,
    label: &'static str,
    size: UVec2,
    samples: u32,
) -> (Texture, TextureView) {
    let usage = if samples > 1 {
        TextureUsages::RENDER_ATTACHMENT
    } else {
        TextureUsages::TEXTURE_BINDING | TextureUsages::COPY_DST
    };
    let texture = device.create_texture(&TextureDescriptor {
        label: Some(label),
        size: Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: TextureDimension::D2,
        format: CAUSTICS_BUFFER_FORMAT,
        usage,
        view_formats: &[],
    });
    let view = texture.create_view(&TextureViewDescriptor::default());
    (texture, view)
}

impl AapsViewState {
    fn new(device: &RenderDevice, key: StateKey, settings: AapsSettings) -> Self {
        let [atlas, tile, per_row, lights] = key.atlas;
        let texels = (atlas as u64) * (atlas as u64);
        let mut levels_words = 0u64;
        let mut offsets = Vec::new();
        let mut s = atlas;
        loop {
            offsets.push((levels_words as u32, s));
            levels_words += (s as u64) * (s as u64);
            if s <= 1 {
                break;
            }
            s /= 2;
        }
        let mut level_bytes = vec![0u8; (LEVEL_STRIDE * offsets.len().max(1) as u64) as usize];
        for k in 1..offsets.len() {
            let at = (k - 1) * LEVEL_STRIDE as usize;
            for (i, v) in [offsets[k - 1].0, offsets[k].0, offsets[k].1, 0]
                .iter()
                .enumerate()
            {
                level_bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
        let budget_per_light = key.budget_per_light as f64;
        let start = uniform_density(
            budget_per_light,
            tile * tile,
            settings.min_density,
            settings.max_density,
        );
        let mut density = Vec::with_capacity(texels as usize * 4);
        for i in 0..texels {
            let (x, y) = ((i % atlas as u64) as u32, (i / atlas as u64) as u32);
            let valid = (y / tile) * per_row + x / tile < lights && x / tile < per_row;
            density.extend_from_slice(&(if valid { start } else { 0.0f32 }).to_le_bytes());
        }
        let budget = budget_per_light * lights as f64;
        let photon_capacity =
            photon_capacity(key.budget_per_light, lights, tile, settings.min_density);
        let density_buf = device.create_buffer_with_data(&BufferInitDescriptor {
            label: Some("caustics:aaps:density"),
            contents: &density,
            usage: BufferUsages::STORAGE | BufferUsages::COPY_DST | BufferUsages::COPY_SRC,
        });
        Self {
            quadtree: storage(
                device,
                "caustics:aaps:quadtree",
                levels_words * 4,
                BufferUsages::empty(),
            ),
            density: [
                density_buf,
                storage(
                    device,
                    "caustics:aaps:density_next",
                    texels * 4,
                    BufferUsages::empty(),
                ),
            ],
            accum: storage(
                device,
                "caustics:aaps:accum",
                (ACCUM_HEADER_WORDS + 4 * texels) * 4,
                BufferUsages::empty(),
            ),
            splats: storage(
                device,
                "caustics:aaps:splats",
                (key.splat_capacity as u64 + SPLAT_GUARD_SPLATS) * 64,
                BufferUsages::empty(),
            ),
            args: storage(device, "caustics:aaps:args", 64, BufferUsages::INDIRECT),
            params: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:aaps:params"),
                size: PARAMS_BYTES as u64,
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            world_from_clip: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:aaps:world_from_clip"),
                size: 64,
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            levels: device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some("caustics:aaps:levels"),
                contents: &level_bytes,
                usage: BufferUsages::UNIFORM,
            }),
            reduce_steps: offsets.len() as u32 - 1,
            history: target(device, "caustics:aaps:history", key.size, 1),
            msaa: key
                .msaa
                .then(|| target(device, "caustics:aaps:msaa", key.size, 4)),
            fixed: key.fixed.then(|| {
                crate::render::fixed_splat::accumulator(
                    device,
                    "caustics:aaps:fixed_splats",
                    key.size,
                )
            }),
            prev_clip_from_world: None,
            frame: 0,
            settings,
            budget,
            photon_capacity,
            key,
        }
    }
}

/// Size of `AapsParams` in bytes.
pub const PARAMS_BYTES: usize = 256;

/// The bytes of `AapsParams` (params.wgsl).
#[allow(clippy::too_many_arguments)]
pub fn params_bytes(
    clip_from_world: Mat4,
    prev: Option<Mat4>,
    eye: Vec3,
    scene_scale: f32,
    size: UVec2,
    state: &AapsViewState,
) -> Vec<u8> {
    let s = &state.settings;
    let mut b = Vec::with_capacity(PARAMS_BYTES);
    let mut f = |v: f32| b.extend_from_slice(&v.to_le_bytes());
    for v in clip_from_world.to_cols_array() {
        f(v);
    }
    for v in prev.unwrap_or(clip_from_world).to_cols_array() {
        f(v);
    }
    for v in [eye.x, eye.y, eye.z, scene_scale] {
        f(v);
    }
    for v in [
        size.x as f32,
        size.y as f32,
        prev.is_some() as u32 as f32,
        s.splat_scale,
    ] {
        f(v);
    }
    let u = |v: u32| f32::from_bits(v);
    let [atlas, tile, per_row, lights] = state.key.atlas;
    for v in [u(atlas), u(tile), u(per_row), u(lights)] {
        f(v);
    }
    for v in [
        u(state.key.splat_capacity),
        u(state.photon_capacity),
        u(s.max_bounces),
        u(state.msaa.is_some() as u32),
    ] {
        f(v);
    }
    for v in [
        s.target_area,
        s.variance_gain,
        s.temporal_weight,
        s.min_density,
    ] {
        f(v);
    }
    for v in [
        s.max_density,
        state.budget as f32,
        s.cull_solid_angle,
        s.max_anisotropy,
    ] {
        f(v);
    }
    // Splat radius guards relative to the scene size (stiff suite: 1e-3 m and 1e4 m).
    for v in [
        s.msaa_threshold,
        scene_scale * 1e-7,
        scene_scale * 4.0,
        s.drop_large_splats as u32 as f32,
    ] {
        f(v);
    }
    // The frame's specular-event budget (AapsSettings::bounce_budget), an integer < 2^31.
    let events = (state.budget * s.bounce_budget as f64)
        .clamp(1.0, 2.0e9)
        .ceil();
    for v in [
        s.budget_floor_share,
        s.point_splat_area,
        events as f32,
        u(state.frame),
    ] {
        f(v);
    }
    b
}

/// Create, resize or reset each AAPS view's state and write its parameters; mark the views
/// whose passes run this frame.
#[allow(clippy::type_complexity)]
pub fn prepare_aaps_views(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    scene: Option<Res<TraceSceneBuffers>>,
    support: Res<super::AapsSupport>,
    limits: Res<crate::limits::CausticsLimits>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&mut AapsViewState>,
        Option<&crate::render::settle::ViewSettle>,
    )>,
) {
    // Left eyes of stereo pairs that run AAPS, by pair.
    let lefts: std::collections::HashMap<u32, Entity> = views
        .iter()
        .filter(|(_, c, ..)| c.technique == CausticsTechnique::Aaps)
        .filter_map(|(entity, c, ..)| {
            let s = c.stereo.filter(|s| s.eye == crate::StereoEye::Left)?;
            Some((s.pair, entity))
        })
        .collect();
    for (entity, caustics, camera, view, state, settle) in &mut views {
        let mut e = commands.entity(entity);
        match caustics
            .stereo
            .filter(|s| s.eye == crate::StereoEye::Right)
            .and_then(|s| lefts.get(&s.pair))
        {
            Some(&left) => e.insert(AapsStereo { left }),
            None => e.remove::<AapsStereo>(),
        };
        let size = camera.physical_viewport_size.unwrap_or_default();
        // A zero photon budget (quality `Custom { photons: 0 }`) runs nothing.
        let active = caustics.technique == CausticsTechnique::Aaps
            && caustics.photons_per_light > 0
            && size.x > 0
            && size.y > 0
            && scene.as_ref().is_some_and(|s| s.lights > 0);
        if !active {
            e.remove::<AapsFrame>();
            if caustics.technique == CausticsTechnique::Aaps {
                e.remove::<TemporalAccumulation>();
            }
            if state.is_some() && caustics.technique != CausticsTechnique::Aaps {
                e.remove::<AapsViewState>();
            }
            continue;
        }
        // Nothing changed for `settle_frames` frames: the task buffer has settled and the
        // caustics buffer holds what a new trace would give (`render::settle`).
        if state.is_some() && crate::render::settle::keeps(settle) {
            e.remove::<AapsFrame>();
            continue;
        }
        let scene = scene.as_ref().unwrap();
        let settings = caustics.aaps.sanitized_for(&limits);
        let (atlas, tile, per_row) = atlas_layout(settings.atlas_resolution, scene.lights);
        let budget_per_light = caustics.photons_per_light.min(limits.max_aaps_photons);
        // A photon draws at most two splats (it splits once, section 3.3.1), so the splat
        // buffer never needs more than twice the photons the view can trace.
        let needed =
            2 * photon_capacity(budget_per_light, scene.lights, tile, settings.min_density);
        let key = StateKey {
            atlas: [atlas, tile, per_row, scene.lights],
            splat_capacity: splat_capacity(
                settings.splat_capacity.min(needed.max(1)),
                &device.limits(),
            ),
            size,
            budget_per_light,
            adaptive: settings.adaptive,
            min_max: [
                settings.min_density.to_bits(),
                settings.max_density.to_bits(),
            ],
            msaa: support.msaa && settings.msaa_threshold > 0.0,
            fixed: support.fixed,
        };
        let mut fresh = None;
        let state = match state {
            Some(s) if s.key == key => {
                let s = s.into_inner();
                s.settings = settings;
                s
            }
            _ => {
                fresh = Some(AapsViewState::new(&device, key, settings));
                fresh.as_mut().unwrap()
            }
        };
        // The sample rotation moves on after a frame that traced: while a pipeline compiles
        // the passes return early (`render::settle`), and the sample they did not draw is the
        // next frame's, so a view settles on the same samples however late its pipelines are.
        if state.prev_clip_from_world.is_some() && settle.is_none_or(|s| s.last_ran) {
            state.frame = state.frame.wrapping_add(1);
        }
        let clip_from_world = crate::render::clip_from_world(view);
        let eye = view.world_from_view.translation();
        let bytes = params_bytes(
            clip_from_world,
            state.prev_clip_from_world,
            eye,
            scene.scene_scale,
            size,
            state,
        );
        queue.write_buffer(&state.params, 0, &bytes);
        let inv: Vec<u8> = clip_from_world
            .inverse()
            .to_cols_array()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        queue.write_buffer(&state.world_from_clip, 0, &inv);
        state.prev_clip_from_world = Some(clip_from_world);
        e.insert((
            AapsFrame,
            TemporalAccumulation {
                owner: CausticsTechnique::Aaps,
                max_history: state.settings.history_frames,
                clamp_sigma: state.settings.history_clamp,
                frames: 1,
                spatial_passes: 0,
            },
        ));
        if let Some(s) = fresh {
            e.insert(s);
        }
    }
}
