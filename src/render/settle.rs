//! Work follows change: a view whose inputs stayed the same while its technique filled the
//! caustics buffer [`crate::Caustics::settle_frames`] times keeps that buffer and dispatches
//! nothing.
//!
//! [`track_settle`] (render world, `PrepareViews`, every caustics view) compares what the
//! view's caustics depend on with the last frame: the gathered scene's generation (it changes
//! when a caustic light, a caster, a receiver or a material changes), the camera's
//! `clip_from_world`, the viewport size, the technique and its settings, the photon budget, the
//! stereo pairing, and which caustics buffer the view has. [`ViewSettle::still`] counts the
//! frames since the last change **in which the technique's passes ran** (each technique's pass
//! system calls [`ViewSettle::mark_ran`] once it has recorded all of its work into the buffer);
//! once it reaches `settle_frames` the techniques skip their passes ([`ViewSettle::keep`]) and
//! the caustics buffer, which persists between frames, holds the last result.
//!
//! Counting frames that ran, not frames that passed, is what makes a kept buffer a filled one.
//! A window's first frames compile the pipelines asynchronously: the passes return early, no
//! work is recorded, and a view counted as still by elapsed frames settled on an empty buffer
//! (issue 27: the README's app lost its caustic for good after `settle_frames` frames in a
//! window). The same holds for a buffer made anew (a resize, a camera whose render entity was
//! re-synced): its serial is part of the key. What each technique re-runs on each kind of
//! change is tabled in its module doc and docs/performance.md.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::view::ExtractedView;

use super::trace::scene::ExtractedCausticsScene;
use super::{ExtractedCaustics, ViewCausticsBuffer};
use crate::{
    AapsSettings, CausticsStereo, CausticsTechnique, ImageSpaceSettings, PhotonMapSettings,
};

/// What a view's caustics depend on (compared frame to frame).
#[derive(Clone, PartialEq)]
struct SettleKey {
    generation: u64,
    caustic_generation: u64,
    clip_from_world: [u32; 16],
    size: UVec2,
    technique: CausticsTechnique,
    aaps: AapsSettings,
    image_space: ImageSpaceSettings,
    photon_map: PhotonMapSettings,
    stereo: Option<CausticsStereo>,
    photons_per_light: u64,
    /// The caustics buffer's serial (0: none yet, or one of another size is to be replaced).
    buffer: u64,
}

/// What changed in a view's inputs since the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SettleChange {
    /// Nothing.
    #[default]
    None,
    /// Only the gathered scene, in a way that cannot change a caustic (`scene::change`: a
    /// receiver moved out of the caustic light's reach, a light jittered within tolerance):
    /// only pixels whose surface moved are new.
    Surfaces,
    /// Only the gathered scene, in a way that can change a caustic (a light, a caster, a
    /// receiver in the caustic light's reach, a material).
    Scene,
    /// The camera, the viewport, the technique or its settings, the stereo pairing or the
    /// caustics buffer (or the view is new).
    View,
}

/// Per caustics view (render world): how long its inputs have stayed the same.
#[derive(Component, Default)]
pub struct ViewSettle {
    key: Option<SettleKey>,
    /// Frames, before this one, in which the technique's passes ran with the same inputs
    /// (0 on a frame that changed).
    pub still: u32,
    /// The technique's passes ran last frame (they filled the buffer).
    pub last_ran: bool,
    /// This frame may keep the last result: `settle_frames > 0` and `still >= settle_frames`.
    pub keep: bool,
    /// What changed since the last frame (the temporal stage keeps its history through a
    /// change of the scene alone, and drops it on any other).
    pub change: SettleChange,
    /// With [`SettleChange::View`]: only the camera's `clip_from_world` changed (the scene at
    /// most as [`SettleChange::Surfaces`]), so a history can be reprojected rather than
    /// dropped.
    pub camera_only: bool,
    /// The technique kept its last result this frame (set by its prepare system; the
    /// composite then draws the buffer without a pass of the technique having run).
    kept: AtomicBool,
    /// The technique's passes recorded all of their work this frame ([`Self::mark_ran`]).
    ran: AtomicBool,
}

impl ViewSettle {
    /// Record that the technique dispatches nothing this frame and the buffer holds its
    /// last result.
    pub fn mark_kept(&self) {
        self.kept.store(true, Ordering::Relaxed);
    }

    /// Record that the technique's passes recorded all of their work into the caustics buffer
    /// this frame (called by the pass system at its end, never on an early return).
    pub fn mark_ran(&self) {
        self.ran.store(true, Ordering::Relaxed);
    }

    /// Whether the technique kept its last result this frame.
    pub fn kept(&self) -> bool {
        self.kept.load(Ordering::Relaxed)
    }
}

/// Whether the view keeps this frame (it has a [`ViewSettle`] and nothing changed for
/// `settle_frames` frames); when it does, it is marked kept for the composite.
pub fn keeps(settle: Option<&ViewSettle>) -> bool {
    settle.is_some_and(|s| {
        if s.keep {
            s.mark_kept();
        }
        s.keep
    })
}

/// Update every caustics view's [`ViewSettle`].
#[allow(clippy::type_complexity)]
pub fn track_settle(
    mut commands: Commands,
    scene: Option<Res<ExtractedCausticsScene>>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&ViewCausticsBuffer>,
        Option<&mut ViewSettle>,
    )>,
) {
    let generation = scene.as_ref().map_or(0, |s| s.0.generation);
    let caustic_generation = scene.map_or(0, |s| s.0.caustic_generation);
    for (entity, caustics, camera, view, buffer, settle) in &mut views {
        let size = camera.physical_viewport_size.unwrap_or_default();
        let key = SettleKey {
            generation,
            caustic_generation,
            clip_from_world: super::clip_from_world(view)
                .to_cols_array()
                .map(f32::to_bits),
            size,
            technique: caustics.technique,
            aaps: caustics.aaps.clone(),
            image_space: caustics.image_space.clone(),
            photon_map: caustics.photon_map.clone(),
            stereo: caustics.stereo,
            photons_per_light: caustics.photons_per_light,
            // A buffer of another size is replaced this frame (`prepare_caustics_buffers`).
            buffer: buffer.filter(|b| b.size == size).map_or(0, |b| b.serial),
        };
        let Some(mut settle) = settle else {
            commands.entity(entity).insert(ViewSettle {
                key: Some(key),
                still: 0,
                last_ran: false,
                keep: false,
                change: SettleChange::View,
                camera_only: false,
                kept: AtomicBool::new(false),
                ran: AtomicBool::new(false),
            });
            continue;
        };
        let ran = settle.ran.swap(false, Ordering::Relaxed);
        settle.last_ran = ran;
        settle.camera_only = settle.key.as_ref().is_some_and(|k| {
            key.buffer != 0
                && k.clip_from_world != key.clip_from_world
                && k.caustic_generation == key.caustic_generation
                && SettleKey {
                    generation: key.generation,
                    clip_from_world: key.clip_from_world,
                    ..k.clone()
                } == key
        });
        settle.change = match &settle.key {
            Some(k) if *k == key && key.buffer != 0 => SettleChange::None,
            Some(k)
                if key.buffer != 0
                    && SettleKey {
                        generation: key.generation,
                        caustic_generation: key.caustic_generation,
                        ..k.clone()
                    } == key =>
            {
                if k.caustic_generation == key.caustic_generation {
                    SettleChange::Surfaces
                } else {
                    SettleChange::Scene
                }
            }
            _ => SettleChange::View,
        };
        if settle.change == SettleChange::None {
            if ran {
                settle.still = settle.still.saturating_add(1);
            }
        } else {
            settle.key = Some(key);
            settle.still = 0;
        }
        settle.keep = caustics.settle_frames > 0 && settle.still >= caustics.settle_frames;
        settle.kept.store(false, Ordering::Relaxed);
    }
}
