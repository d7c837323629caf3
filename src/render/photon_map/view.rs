//! Per-view state of the photon map: its buffers, the progressive frame count and what resets
//! it, and the uniforms of each frame.

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::ExtractedView;

use crate::optics::{PHOTON_BYTES, SCAN_BLOCK, pcg_hash, progressive_radius2};
use crate::render::ExtractedCaustics;
use crate::render::temporal::TemporalAccumulation;
use crate::render::trace::scene::TraceSceneBuffers;
use crate::{CausticsTechnique, PhotonMapSettings};

/// Words of the header buffer: counters (0..32, read back), the grid's layout (32..50) and the
/// event-budget counters (50..54, read back).
pub const HEADER_WORDS: u64 = 64;
/// First of the event-budget counter words (`C_EVENTS` in photon.wgsl).
pub const EXTRA_COUNTERS_AT: u64 = 50;
/// Header word: photons stored by the trace (`H_COUNT` in photon.wgsl).
pub const H_COUNT: usize = 1;
/// Header words of the grid's layout (`H_*` in photon.wgsl): X, Y, Z.
pub const H_DIMS: usize = 40;
/// Header word: cell doublings.
pub const H_SHIFT: usize = 44;
/// Header words: the origin, f32 bits.
pub const H_ORIGIN: usize = 45;
/// Header word: the cell size, f32 bits.
pub const H_CELL: usize = 48;
/// Header word: 1 / cell size, f32 bits.
pub const H_INV: usize = 49;
/// Units per lumen of the header's luminous-flux counters (64-bit fixed point, low word then
/// high word; `C_FLUX_*` and `PM_FLUX_SCALE` in photon.wgsl): 1/65 536 lm, rounded
/// stochastically per workgroup, and 2^64 units (2.8e14 lm) per frame before a sum wraps.
pub const FLUX_SCALE: f64 = 65_536.0;
/// Bytes of the per-view uniforms (`PmParams` in trace.wgsl).
pub const PARAMS_BYTES: u64 = 3 * 64 + 8 * 16;

const FLAG_ACCUMULATE: u32 = 1;
const FLAG_FROZEN: u32 = 2;
const FLAG_SHARED: u32 = 4;
const FLAG_MIRRORS: u32 = 8;
const FLAG_REUSE: u32 = 16;
const FLAG_VALIDATE: u32 = 32;
const FLAG_DENSITY: u32 = 64;

/// What decides the buffers' sizes; a change reallocates them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhotonMapKey {
    /// View size, pixels.
    pub size: UVec2,
    /// Photons the buffers hold (photons per light × lights).
    pub capacity: u32,
    /// Grid budget, cells.
    pub budget: u32,
}

/// Frames of the shared temporal stage's history (`render::temporal`): through a change of
/// the scene, which restarts the progressive mean, a running mean of at most this many frames
/// where the caustic did not change; on a still view the history fades once the progressive
/// mean holds this many frames.
pub const HISTORY_FRAMES: u32 = 32;

/// The width of the stage's history clamp after a change of the scene, standard errors of the
/// 3x3 mean ([`TemporalAccumulation::clamp_sigma`]; AAPS asks for the stage's default,
/// `temporal::DEFAULT_CLAMP_SIGMA`). A change restarts the progressive mean at the first
/// frame's radius, so the estimate the history is judged against is blurred by its radius,
/// not only noisy: at the default the clamp dropped history that was right.
/// Measured on the sliding ball (`a_moving_caster_leaves_no_trail`, RMSE against converged
/// references over the still run's): 1.68x at 1, 1.46x at 2, 1.45x at 3, 1.42x at 4, 1.41x
/// with no clamp; no trail and no ghost at 4 (a surface that moved still drops its history).
pub const CLAMP_SIGMA: f32 = 4.0;

/// À-trous iterations of the stage's spatial filter over the photon map's output
/// ([`TemporalAccumulation::spatial_passes`]).
pub const SPATIAL_PASSES: u32 = 2;

/// What the progressive mean is of: any change starts it again. The scene enters by its
/// caustic generation (`scene::change`): a mover outside the caustic light's reach or a light
/// jittering within tolerance keeps the mean, and a moved receiver restarts only the pixels
/// whose visible surface moved (`FLAG_VALIDATE`).
#[derive(Clone, Debug, PartialEq)]
struct Accumulating {
    caustic_generation: u64,
    clip_from_world: [u32; 16],
    settings: PhotonMapSettings,
    per_light: u32,
    radius: u32,
}

impl Accumulating {
    /// Whether the per-pixel photon density a mean of `self` left in `accum` sizes the gathers
    /// of `now` (`PhotonMapSettings::gather_photons`): through a change of the scene, not of
    /// the camera, the settings or the photon count.
    fn keeps_density(&self, now: &Self) -> bool {
        self.clip_from_world == now.clip_from_world
            && self.settings == now.settings
            && self.per_light == now.per_light
    }
}

/// The photon map of one view (render world).
#[derive(Component)]
pub struct PhotonMapViewState {
    /// Sizes.
    pub key: PhotonMapKey,
    /// The settings in use (sanitized).
    pub settings: PhotonMapSettings,
    /// `PmParams`.
    pub params: Buffer,
    /// `GridParams` of grid.wgsl.
    pub grid_params: Buffer,
    /// Photons as traced.
    pub photons: Buffer,
    /// Photons sorted by cell.
    pub sorted: Buffer,
    /// Counters and the grid's layout ([`HEADER_WORDS`]).
    pub header: Buffer,
    /// `startIdx`: budget + 1 words.
    pub cells: Buffer,
    /// The scan's block sums.
    pub blocks: Buffer,
    /// Each photon's cell, from the count pass.
    pub photon_cell: Buffer,
    /// Per pixel: the running mean (rgb) and the eye distance (w); then per pixel the frames
    /// in its mean (x) and the mean photon density its gathers found, photons per m² per frame
    /// (y; [`PhotonMapSettings::gather_photons`]).
    pub accum: Buffer,
    /// The scene's receiver generation of the last frame that ran.
    receivers: u64,
    /// Photons per light this frame.
    pub per_light: u32,
    /// Lights in the table.
    pub lights: u32,
    /// The progressive frame shown (1-based; 0 before the first).
    pub frame: u32,
    /// Frames traced since the state was created (the sampling seed).
    pub serial: u32,
    /// This frame's gather radius, metres.
    pub radius: f32,
    /// Whether this frame traces and builds (false when the mean is frozen, or for a right
    /// eye that shares its left eye's photons).
    pub traces: bool,
    /// A 16-byte buffer bound where a view has no left eye's mean to read.
    pub dummy: Buffer,
    /// The frozen mean is in the caustics buffer: later frozen frames dispatch nothing.
    pub frozen_shown: bool,
    /// Last frame was to show the frozen mean (shown once its passes ran).
    pub frozen_pending: bool,
    accumulating: Option<Accumulating>,
}

impl PhotonMapViewState {
    /// Whether the density its last mean left in `accum` sizes the gathers of `now`
    /// ([`Accumulating::keeps_density`]).
    fn keeps_density(&self, now: &Accumulating) -> bool {
        self.accumulating
            .as_ref()
            .is_some_and(|a| a.keeps_density(now))
    }

    /// GPU bytes held (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        crate::render::memory::buffer_bytes([
            &self.params,
            &self.grid_params,
            &self.photons,
            &self.sorted,
            &self.header,
            &self.cells,
            &self.blocks,
            &self.photon_cell,
            &self.accum,
            &self.dummy,
        ])
    }
}

/// On the right eye of a [`crate::CausticsStereo`] pair: the render-world view of its left
/// eye, whose photons, grid (and, with `reuse`, gathered irradiance) it uses this frame.
#[derive(Component, Clone, Copy, Debug)]
pub struct PhotonMapStereo {
    /// The left eye's view entity.
    pub left: Entity,
    /// Whether pixels the left eye also sees take its irradiance.
    pub reuse: bool,
}

/// What the right eye of a pair needs of its left eye.
#[derive(Clone, Copy)]
struct LeftEye {
    entity: Entity,
    clip_from_world: Mat4,
    eye: Vec3,
}

/// Marks a view whose photon-map passes run this frame.
#[derive(Component)]
pub struct PhotonMapFrame;

impl PhotonMapViewState {
    fn new(device: &RenderDevice, key: PhotonMapKey, settings: PhotonMapSettings) -> Self {
        let buffer = |label: &'static str, size: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let storage = BufferUsages::STORAGE;
        let traced = BufferUsages::STORAGE | BufferUsages::COPY_SRC;
        let cleared = BufferUsages::STORAGE | BufferUsages::COPY_DST | BufferUsages::COPY_SRC;
        let uniform = BufferUsages::UNIFORM | BufferUsages::COPY_DST;
        let cap = u64::from(key.capacity.max(1));
        let cell_words = u64::from(key.budget) + 1;
        let pixels = u64::from(key.size.x) * u64::from(key.size.y);
        Self {
            key,
            settings,
            params: buffer("caustics:photon_map:params", PARAMS_BYTES, uniform),
            grid_params: buffer("caustics:photon_map:grid_params", 16, uniform),
            photons: buffer("caustics:photon_map:photons", cap * PHOTON_BYTES, traced),
            sorted: buffer("caustics:photon_map:sorted", cap * PHOTON_BYTES, storage),
            header: buffer("caustics:photon_map:header", HEADER_WORDS * 4, cleared),
            cells: buffer("caustics:photon_map:cells", cell_words * 4, cleared),
            blocks: buffer(
                "caustics:photon_map:blocks",
                cell_words.div_ceil(u64::from(SCAN_BLOCK)) * 4,
                storage,
            ),
            photon_cell: buffer("caustics:photon_map:photon_cell", cap * 4, storage),
            accum: buffer("caustics:photon_map:accum", pixels * 32, storage),
            receivers: 0,
            per_light: 0,
            lights: 0,
            frame: 0,
            serial: 0,
            radius: 0.0,
            traces: false,
            frozen_shown: false,
            frozen_pending: false,
            dummy: buffer("caustics:photon_map:dummy", 16, storage),
            accumulating: None,
        }
    }
}

/// The first frame's gather radius (and the grid's cell size) for `settings` in a scene whose
/// casters' bounding sphere has radius `caster_radius`; at least 1e-6 m.
pub fn base_radius(settings: &PhotonMapSettings, caster_radius: f32) -> f32 {
    let r = settings.radius * caster_radius;
    if r.is_finite() { r.max(1e-6) } else { 1e-6 }
}

/// Create, resize or reset each photon-map view's state and write its uniforms; mark the
/// views whose passes run this frame.
#[allow(clippy::type_complexity)]
pub fn prepare_photon_map_views(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    scene: Option<Res<TraceSceneBuffers>>,
    limits: Option<Res<crate::limits::CausticsLimits>>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&mut PhotonMapViewState>,
        Option<&crate::render::settle::ViewSettle>,
    )>,
) {
    let limits = limits.map(|l| l.clone()).unwrap_or_default();
    // Left eyes of stereo pairs that run the photon map, by pair.
    let lefts: std::collections::HashMap<u32, LeftEye> = views
        .iter()
        .filter(|(_, c, ..)| c.technique == CausticsTechnique::PhotonMap)
        .filter_map(|(entity, c, _, view, ..)| {
            let s = c.stereo.filter(|s| s.eye == crate::StereoEye::Left)?;
            let left = LeftEye {
                entity,
                clip_from_world: crate::render::clip_from_world(view),
                eye: view.world_from_view.translation(),
            };
            Some((s.pair, left))
        })
        .collect();
    for (entity, caustics, camera, view, state, settle) in &mut views {
        let mut e = commands.entity(entity);
        let size = camera.physical_viewport_size.unwrap_or_default();
        let mine = caustics.technique == CausticsTechnique::PhotonMap;
        let per_light = caustics
            .photons_per_light
            .min(limits.max_photons(CausticsTechnique::PhotonMap)) as u32;
        let active = mine
            && per_light > 0
            && size.x > 0
            && size.y > 0
            && scene.as_ref().is_some_and(|s| s.lights > 0);
        if !active {
            e.remove::<PhotonMapFrame>();
            if caustics.technique == CausticsTechnique::PhotonMap {
                e.remove::<TemporalAccumulation>();
            }
            if state.is_some() && !mine {
                e.remove::<PhotonMapViewState>();
            }
            continue;
        }
        let scene = scene.as_ref().unwrap();
        let settings = caustics.photon_map.sanitized();
        let max_total = (limits.max_binding_bytes / PHOTON_BYTES).min(u64::from(u32::MAX));
        let capacity = (u64::from(per_light) * u64::from(scene.lights)).min(max_total) as u32;
        let key = PhotonMapKey {
            size,
            capacity,
            budget: settings.max_grid_cells,
        };
        let mut fresh = None;
        let reused = matches!(&state, Some(s) if s.key == key);
        let state = match state {
            Some(s) if s.key == key => s.into_inner(),
            _ => {
                fresh = Some(PhotonMapViewState::new(&device, key, settings.clone()));
                fresh.as_mut().unwrap()
            }
        };
        state.settings = settings.clone();
        state.per_light = per_light;
        state.lights = scene.lights;
        let clip_from_world = crate::render::clip_from_world(view);
        let r0 = base_radius(&settings, scene.casters.1);
        let now = Accumulating {
            caustic_generation: scene.caustic_generation,
            clip_from_world: clip_from_world.to_cols_array().map(f32::to_bits),
            settings: settings.clone(),
            per_light,
            radius: r0.to_bits(),
        };
        let density_ok = reused && state.keeps_density(&now);
        if state.accumulating.as_ref() != Some(&now) {
            state.frame = 0;
            state.frozen_shown = false;
            state.frozen_pending = false;
            state.accumulating = Some(now);
        }
        // A receiver moved that keeps the mean: a frozen mean goes on (the moved pixels
        // restart and need frames), and this frame validates every pixel's surface.
        let receivers_moved = state.receivers != scene.receiver_generation;
        state.receivers = scene.receiver_generation;
        if receivers_moved {
            state.frozen_shown = false;
            state.frozen_pending = false;
        }
        // Whether last frame's passes ran (`render::settle`): while the pipelines compile they
        // return early, and a frame that did not run neither counts in the progressive mean
        // nor shows the frozen one.
        let last_ran = settle.is_none_or(|s| s.last_ran);
        if state.frozen_pending && last_ran {
            state.frozen_shown = true;
        }
        let frozen = settings.progressive && state.frame >= settings.max_frames && !receivers_moved;
        // Work follows change (`render::settle`): a frozen mean already shown, or without
        // progressive mode nothing changed for `settle_frames` frames: the caustics buffer
        // keeps it.
        let kept = if settings.progressive {
            frozen && state.frozen_shown && settle.is_some()
        } else {
            crate::render::settle::keeps(settle)
        };
        if kept {
            if let Some(s) = settle {
                s.mark_kept();
            }
            e.remove::<PhotonMapFrame>();
            continue;
        }
        state.frozen_pending = frozen;
        if !frozen {
            state.frame = if !settings.progressive {
                1
            } else if state.frame == 0 || last_ran {
                state.frame + 1
            } else {
                // Trace this sample again: the last one never ran.
                state.frame
            };
            state.serial = state.serial.wrapping_add(1);
        }
        let left = caustics
            .stereo
            .filter(|s| s.eye == crate::StereoEye::Right)
            .and_then(|s| lefts.get(&s.pair).copied());
        state.traces = !frozen && left.is_none();
        let r2 = if settings.progressive {
            progressive_radius2(r0 * r0, state.frame, settings.alpha)
        } else {
            r0 * r0
        };
        state.radius = r2.sqrt();
        let reuse = left.is_some() && settings.stereo_reuse;
        // A right eye that reuses gathers pixel by pixel (its tiles are not uniform).
        let mut flags = 0;
        for (on, flag) in [
            (frozen, FLAG_FROZEN),
            (state.frame > 1, FLAG_ACCUMULATE),
            (settings.shared_memory && !reuse, FLAG_SHARED),
            (settings.mirrors && scene.has_mirrors, FLAG_MIRRORS),
            (reuse, FLAG_REUSE),
            (receivers_moved, FLAG_VALIDATE),
            (density_ok && settings.gather_photons > 0.0, FLAG_DENSITY),
        ] {
            if on {
                flags |= flag;
            }
        }
        let other = left.map_or((clip_from_world, Vec3::ZERO), |l| {
            (l.clip_from_world, l.eye)
        });
        write_uniforms(
            &queue,
            state,
            (scene, view),
            [clip_from_world, other.0],
            other.1,
            (r0, r2),
            flags,
        );
        let state_frame = state.frame.max(1);
        match left {
            Some(l) => e.insert(PhotonMapStereo {
                left: l.entity,
                reuse,
            }),
            None => e.remove::<PhotonMapStereo>(),
        };
        if let Some(s) = fresh.take() {
            e.insert(s);
        }
        e.insert(PhotonMapFrame);
        // The shared temporal stage keeps a history through a change of the scene (which
        // restarts the progressive mean); it fades as the new mean grows.
        if settings.progressive {
            e.insert(TemporalAccumulation {
                owner: CausticsTechnique::PhotonMap,
                max_history: HISTORY_FRAMES,
                clamp_sigma: CLAMP_SIGMA,
                frames: state_frame,
                spatial_passes: SPATIAL_PASSES,
            });
        } else {
            e.remove::<TemporalAccumulation>();
        }
    }
}

fn write_uniforms(
    queue: &RenderQueue,
    state: &PhotonMapViewState,
    (scene, view): (&TraceSceneBuffers, &ExtractedView),
    [clip_from_world, other_clip_from_world]: [Mat4; 2],
    other_eye: Vec3,
    (r0, r2): (f32, f32),
    flags: u32,
) {
    let s = &state.settings;
    let f32s = |b: &mut Vec<u8>, v: &[f32]| b.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    let u32s = |b: &mut Vec<u8>, v: &[u32]| b.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    let mut b = Vec::with_capacity(PARAMS_BYTES as usize);
    f32s(&mut b, &clip_from_world.inverse().to_cols_array());
    f32s(&mut b, &clip_from_world.to_cols_array());
    f32s(&mut b, &other_clip_from_world.to_cols_array());
    let eye = view.world_from_view.translation();
    f32s(&mut b, &[eye.x, eye.y, eye.z, scene.scene_scale]);
    let size = state.key.size.as_vec2();
    f32s(&mut b, &[size.x, size.y, r2, s.normal_threshold]);
    u32s(
        &mut b,
        &[
            state.per_light,
            state.lights,
            s.max_bounces,
            state.key.capacity,
        ],
    );
    let serial = state.serial;
    let rotation = [
        pcg_hash(serial.wrapping_mul(2) ^ 0x5bd1_e995),
        pcg_hash(serial.wrapping_mul(2) + 1),
    ];
    u32s(
        &mut b,
        &[
            rotation[0],
            rotation[1],
            pcg_hash(serial ^ 0x2545_f491),
            flags,
        ],
    );
    let frame = state.frame.max(1);
    // The frame's specular-event budget (PhotonMapSettings::bounce_budget).
    let events = (state.per_light as f64 * state.lights as f64 * s.bounce_budget as f64)
        .clamp(1.0, 2.0e9)
        .ceil();
    f32s(
        &mut b,
        &[
            1.0 / frame as f32,
            frame as f32,
            events as f32,
            crate::render::temporal::SURFACE_DEPTH_TOLERANCE,
        ],
    );
    let p = view.clip_from_view;
    let perspective = p.w_axis.w == 0.0;
    f32s(
        &mut b,
        &[
            0.5 * size.x * p.x_axis.x,
            0.5 * size.y * p.y_axis.y,
            if perspective { 1.0 } else { 0.0 },
            r0,
        ],
    );
    let forward = view.world_from_view.forward();
    f32s(&mut b, &[forward.x, forward.y, forward.z, s.gather_photons]);
    f32s(&mut b, &[other_eye.x, other_eye.y, other_eye.z, 0.0]);
    debug_assert_eq!(b.len() as u64, PARAMS_BYTES);
    queue.write_buffer(&state.params, 0, &b);
    let mut g = Vec::with_capacity(16);
    f32s(&mut g, &[r0, 1.0 / r0]);
    u32s(&mut g, &[state.key.budget, state.key.capacity]);
    queue.write_buffer(&state.grid_params, 0, &g);
}
