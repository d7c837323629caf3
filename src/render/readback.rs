//! Tool-side readback of a view's caustics buffer and AAPS counters (headless renders, tests,
//! the report). Only on request: no frame ever waits for it. The copy is recorded after the
//! composite and mapped when the GPU finishes; the main world picks it up frames later.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferUsages, Extent3d, MapMode, TexelCopyBufferInfo,
    TexelCopyBufferLayout, TexelCopyTextureInfo,
};
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::{ExtractSchedule, RenderApp};

use super::CausticImage;
use super::aaps::view::{AapsViewState, SPLAT_GUARD_SPLATS};
use super::image_space::view::ImageSpaceViewState;
use super::photon_map::view::PhotonMapViewState;
use super::volume::gpu::CNT;
use super::volume::view::{VolumeStore, VolumeViewState};
use super::{ExtractedCaustics, ViewCausticsBuffer};

/// Number of AAPS counter words read back (`C_*` in src/render/aaps/common.wgsl).
pub const COUNTER_WORDS: usize = 32;
/// Words of the AAPS splat buffer's tail read back (after the counters): the last splat inside
/// the capacity, then the guard region past it.
pub const GUARD_WORDS: usize = (1 + SPLAT_GUARD_SPLATS as usize) * 16;
/// Counter words past a technique's first 32, read back after the guard words (the photon
/// map's event-budget words, `C_EVENTS..` in src/render/photon_map/photon.wgsl).
pub const EXTRA_WORDS: usize = 4;
/// Words read back after the image: counters, the splat guard, the extra counters.
const TAIL_WORDS: usize = COUNTER_WORDS + GUARD_WORDS + EXTRA_WORDS;

#[derive(Default)]
struct State {
    /// Frames asked for in the main world since its last extraction.
    requested: u32,
    /// Frames asked for and extracted, not copied yet: one copy per render frame until none is
    /// left, so no request is lost when the main world runs ahead of the render world.
    to_copy: u32,
    /// Copies in flight, oldest first (one per requested frame).
    pending: std::collections::VecDeque<(Buffer, UVec2, u32, Arc<AtomicBool>)>,
    /// Also copy the photon map's stored photons (tests).
    photons: bool,
}

/// A readback result.
#[derive(Clone, Debug)]
pub struct CausticsSnapshot {
    /// The caustics buffer, lux.
    pub image: CausticImage,
    /// The AAPS counters of the same frame (zeros for other techniques).
    pub counters: [u32; COUNTER_WORDS],
    /// The AAPS splat buffer's tail: its last splat inside the capacity (16 words), then the
    /// guard region past it (zeros unless something wrote past the capacity). Zeros for other
    /// techniques.
    pub splat_guard: [u32; GUARD_WORDS],
    /// The photon map's counter words past its first 32 (`C_EVENTS`, `C_BUDGET_STOPPED`;
    /// zeros for other techniques).
    pub extra: [u32; EXTRA_WORDS],
    /// The caustics buffer's alpha per pixel (the photon map marks pixels showing a mirror
    /// with -1).
    pub alpha: Vec<f32>,
    /// With [`CausticsReadback::read_photons`]: the photon map's photon buffer as traced
    /// (32-byte records, `optics::PHOTON_BYTES`; the first `min(counters[1], capacity)` hold
    /// this frame's photons). Empty otherwise.
    pub photons: Vec<u8>,
}

/// Shared between the main and render worlds.
#[derive(Resource, Clone, Default)]
pub struct CausticsReadback(Arc<Mutex<State>>);

impl CausticsReadback {
    /// Ask for this frame's caustics buffer of the (first) caustics view: the render of the
    /// state this main-world frame extracts (asking every frame gives every frame's, in order).
    /// A request waits for the extraction: with pipelined rendering the render world draws the
    /// previous frame while the main world runs, and a request it took at once would show the
    /// previous frame's state.
    pub fn request(&self) {
        if let Ok(mut s) = self.0.lock() {
            s.requested = s.requested.saturating_add(1);
        }
    }

    /// Copy the photon map's photons with every readback from now on (tests).
    pub fn read_photons(&self) {
        if let Ok(mut s) = self.0.lock() {
            s.photons = true;
        }
    }

    /// Readbacks requested or in flight and not yet polled.
    pub fn pending(&self) -> usize {
        self.0
            .lock()
            .map_or(0, |s| s.pending.len() + (s.requested + s.to_copy) as usize)
    }

    /// The oldest snapshot not yet polled, once the GPU has delivered it.
    pub fn poll(&self) -> Option<CausticsSnapshot> {
        let mut s = self.0.lock().ok()?;
        let (_, _, _, ready) = s.pending.front()?;
        if !ready.load(Ordering::Acquire) {
            return None;
        }
        let (buffer, size, row, _) = s.pending.pop_front()?;
        let (w, h, row) = (size.x as usize, size.y as usize, row as usize);
        let data = buffer.slice(..).get_mapped_range().to_vec();
        buffer.unmap();
        let f = |i: usize| f32::from_le_bytes(data[i..i + 4].try_into().unwrap());
        let mut image = CausticImage::new(w as u32, h as u32);
        let mut alpha = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let at = y * row + x * 16;
                image.data[y * w + x] = Vec3::new(f(at), f(at + 4), f(at + 8));
                alpha[y * w + x] = f(at + 12);
            }
        }
        let photons = data
            .get(row * h + TAIL_WORDS * 4..)
            .unwrap_or_default()
            .to_vec();
        let word = |i: usize| {
            let at = row * h + 4 * i;
            u32::from_le_bytes(data[at..at + 4].try_into().unwrap())
        };
        let counters = std::array::from_fn(word);
        let splat_guard = std::array::from_fn(|i| word(COUNTER_WORDS + i));
        let extra = std::array::from_fn(|i| word(COUNTER_WORDS + GUARD_WORDS + i));
        Some(CausticsSnapshot {
            image,
            counters,
            splat_guard,
            extra,
            alpha,
            photons,
        })
    }
}

#[allow(clippy::type_complexity)]
fn copy_for_readback(
    view: ViewQuery<(
        &ViewCausticsBuffer,
        &ExtractedCaustics,
        Option<&AapsViewState>,
        Option<&VolumeViewState>,
        Option<&ImageSpaceViewState>,
        Option<&PhotonMapViewState>,
    )>,
    volumes: Option<Res<VolumeStore>>,
    readback: Res<CausticsReadback>,
    mut ctx: RenderContext,
) {
    let (buffer, caustics, aaps, volume, image_space, photon_map) = view.into_inner();
    // A stereo pair is read back through its right eye.
    if caustics
        .stereo
        .is_some_and(|s| s.eye == crate::StereoEye::Left)
    {
        return;
    }
    let Ok(mut s) = readback.0.lock() else {
        return;
    };
    if s.to_copy == 0 {
        return;
    }
    s.to_copy -= 1;
    let row = (buffer.size.x * 16).div_ceil(256) * 256;
    let image_bytes = row as u64 * buffer.size.y as u64;
    let photons = photon_map.filter(|_| s.photons).map(|p| &p.photons);
    let staging = ctx.render_device().create_buffer(&BufferDescriptor {
        label: Some("caustics:readback"),
        size: image_bytes + (TAIL_WORDS * 4) as u64 + photons.map_or(0, |p| p.size()),
        usage: BufferUsages::MAP_READ | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let encoder = ctx.command_encoder();
    encoder.copy_texture_to_buffer(
        TexelCopyTextureInfo {
            texture: &buffer.texture,
            mip_level: 0,
            origin: Default::default(),
            aspect: Default::default(),
        },
        TexelCopyBufferInfo {
            buffer: &staging,
            layout: TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(buffer.size.y),
            },
        },
        Extent3d {
            width: buffer.size.x,
            height: buffer.size.y,
            depth_or_array_layers: 1,
        },
    );
    if let Some(state) = aaps {
        encoder.copy_buffer_to_buffer(
            &state.accum,
            0,
            &staging,
            image_bytes,
            Some((COUNTER_WORDS * 4) as u64),
        );
        encoder.copy_buffer_to_buffer(
            &state.splats,
            (state.key.splat_capacity as u64 - 1) * 64,
            &staging,
            image_bytes + (COUNTER_WORDS * 4) as u64,
            Some((GUARD_WORDS * 4) as u64),
        );
    }
    // The volume technique: the counters of the view's first visible volume.
    if let (Some(state), Some(store)) = (volume, volumes.as_ref())
        && let Some(v) = state.visible.first().and_then(|&i| store.volumes.get(i))
    {
        encoder.copy_buffer_to_buffer(
            &v.counts,
            CNT * 4,
            &staging,
            image_bytes,
            Some((COUNTER_WORDS * 4) as u64),
        );
    }
    if let Some(state) = image_space {
        encoder.copy_buffer_to_buffer(
            &state.counters,
            0,
            &staging,
            image_bytes,
            Some((COUNTER_WORDS * 4) as u64),
        );
    }
    if let Some(state) = photon_map {
        encoder.copy_buffer_to_buffer(
            &state.header,
            0,
            &staging,
            image_bytes,
            Some((COUNTER_WORDS * 4) as u64),
        );
        encoder.copy_buffer_to_buffer(
            &state.header,
            super::photon_map::view::EXTRA_COUNTERS_AT * 4,
            &staging,
            image_bytes + ((COUNTER_WORDS + GUARD_WORDS) * 4) as u64,
            Some((EXTRA_WORDS * 4) as u64),
        );
    }
    if let Some(p) = photons {
        let at = image_bytes + (TAIL_WORDS * 4) as u64;
        encoder.copy_buffer_to_buffer(p, 0, &staging, at, Some(p.size()));
    }
    let ready = Arc::new(AtomicBool::new(false));
    let flag = ready.clone();
    encoder.map_buffer_on_submit(&staging, MapMode::Read, .., move |r| {
        if r.is_ok() {
            flag.store(true, Ordering::Release);
        }
    });
    s.pending.push_back((staging, buffer.size, row, ready));
}

/// Extraction: the main world's requests of the frame just finished become copies of this
/// render (the main world waits while this runs).
fn extract_requests(readback: Res<CausticsReadback>) {
    if let Ok(mut s) = readback.0.lock() {
        s.to_copy = s.to_copy.saturating_add(s.requested);
        s.requested = 0;
    }
}

pub(super) fn build(app: &mut App) {
    let readback = CausticsReadback::default();
    app.insert_resource(readback.clone());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(readback)
        .add_systems(ExtractSchedule, extract_requests)
        .add_systems(
            Core3d,
            copy_for_readback
                .in_set(Core3dSystems::MainPass)
                .after(super::composite::composite_caustics),
        );
}
