//! Work follows change: a view whose inputs stayed the same for
//! [`crate::Caustics::settle_frames`] frames keeps its caustics buffer and dispatches nothing.
//!
//! [`track_settle`] (render world, `PrepareViews`, every caustics view) compares what the
//! view's caustics depend on with the last frame: the gathered scene's generation (it changes
//! when a caustic light, a caster, a receiver or a material changes), the camera's
//! `clip_from_world`, the viewport size, the technique and its settings, the photon budget and
//! the stereo pairing. [`ViewSettle::still`] counts the frames in a row it stayed the same; once
//! it reaches `settle_frames` the techniques skip their passes ([`ViewSettle::keep`]) and the
//! caustics buffer, which persists between frames, holds the last result. What each technique
//! re-runs on each kind of change is tabled in its module doc and the README.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::view::ExtractedView;

use super::ExtractedCaustics;
use super::trace::scene::ExtractedCausticsScene;
use crate::{
    AapsSettings, CausticsStereo, CausticsTechnique, ImageSpaceSettings, PhotonMapSettings,
};

/// What a view's caustics depend on (compared frame to frame).
#[derive(Clone, PartialEq)]
struct SettleKey {
    generation: u64,
    clip_from_world: [u32; 16],
    size: UVec2,
    technique: CausticsTechnique,
    aaps: AapsSettings,
    image_space: ImageSpaceSettings,
    photon_map: PhotonMapSettings,
    stereo: Option<CausticsStereo>,
    photons_per_light: u64,
}

/// Per caustics view (render world): how long its inputs have stayed the same.
#[derive(Component, Default)]
pub struct ViewSettle {
    key: Option<SettleKey>,
    /// Frames in a row, before this one, with the same inputs (0 on a frame that changed).
    pub still: u32,
    /// This frame may keep the last result: `settle_frames > 0` and `still >= settle_frames`.
    pub keep: bool,
    /// The technique kept its last result this frame (set by its prepare system; the
    /// composite then draws the buffer without a pass of the technique having run).
    kept: AtomicBool,
}

impl ViewSettle {
    /// Record that the technique dispatches nothing this frame and the buffer holds its
    /// last result.
    pub fn mark_kept(&self) {
        self.kept.store(true, Ordering::Relaxed);
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
pub fn track_settle(
    mut commands: Commands,
    scene: Option<Res<ExtractedCausticsScene>>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&mut ViewSettle>,
    )>,
) {
    let generation = scene.map_or(0, |s| s.0.generation);
    for (entity, caustics, camera, view, settle) in &mut views {
        let key = SettleKey {
            generation,
            clip_from_world: super::clip_from_world(view)
                .to_cols_array()
                .map(f32::to_bits),
            size: camera.physical_viewport_size.unwrap_or_default(),
            technique: caustics.technique,
            aaps: caustics.aaps.clone(),
            image_space: caustics.image_space.clone(),
            photon_map: caustics.photon_map.clone(),
            stereo: caustics.stereo,
            photons_per_light: caustics.photons_per_light,
        };
        let Some(mut settle) = settle else {
            commands.entity(entity).insert(ViewSettle {
                key: Some(key),
                still: 0,
                keep: false,
                kept: AtomicBool::new(false),
            });
            continue;
        };
        if settle.key.as_ref() == Some(&key) {
            settle.still = settle.still.saturating_add(1);
        } else {
            settle.key = Some(key);
            settle.still = 0;
        }
        settle.keep = caustics.settle_frames > 0 && settle.still >= caustics.settle_frames;
        settle.kept.store(false, Ordering::Relaxed);
    }
}
