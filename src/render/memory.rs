//! The GPU memory each technique holds: the bytes of the buffers and textures it created,
//! summed in the render world after the resources are prepared, every frame, and shared with
//! the main world ([`CausticsGpuMemory`]). A technique's per-view state exists only on views
//! that use it and its shared resources only while some view does, so a camera that switches
//! technique frees the old one's memory (tested: 100 switches leave the count where it
//! started). The main world also publishes the counts as diagnostics
//! `caustics/gpu_bytes/<name>`.
//!
//! The names: `caustics_buffer` (every caustics camera's irradiance texture), `trace` (the
//! BVH scene shared by AAPS and the photon map), `aaps`, `photon_map`, `image_space` (its
//! per-view maps and its rasterised scene), `volume` (the volumes and their views).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use bevy::render::render_resource::Buffer;
use bevy::render::{Render, RenderApp, RenderSystems};

use super::ViewCausticsBuffer;
use super::aaps::view::AapsViewState;
use super::image_space::view::{ImageSpaceScene, ImageSpaceViewState};
use super::photon_map::view::PhotonMapViewState;
use super::trace::scene::TraceSceneBuffers;
use super::volume::view::{VolumeStore, VolumeViewState};

/// The names counted, in a fixed order.
pub const MEMORY_NAMES: [&str; 7] = [
    "caustics_buffer",
    "trace",
    "aaps",
    "photon_map",
    "image_space",
    "volume",
    "temporal",
];

/// Bytes of GPU memory per name of [`MEMORY_NAMES`], as of the last rendered frame; shared by
/// the main and render worlds.
#[derive(Resource, Clone, Default, Debug)]
pub struct CausticsGpuMemory(Arc<Mutex<BTreeMap<&'static str, u64>>>);

impl CausticsGpuMemory {
    /// The bytes per name (every name present, 0 when nothing is held).
    pub fn bytes(&self) -> BTreeMap<&'static str, u64> {
        let held = self.0.lock().map(|m| m.clone()).unwrap_or_default();
        MEMORY_NAMES
            .iter()
            .map(|n| (*n, held.get(n).copied().unwrap_or(0)))
            .collect()
    }

    /// All of it.
    pub fn total(&self) -> u64 {
        self.bytes().values().sum()
    }

    fn set(&self, bytes: BTreeMap<&'static str, u64>) {
        if let Ok(mut m) = self.0.lock() {
            *m = bytes;
        }
    }
}

/// Bytes of a texture: every mip level, layer and sample (depth formats count their copy
/// size, 4 bytes where the format has none).
pub fn texture_bytes(t: &wgpu::Texture) -> u64 {
    let format = t.format();
    let block = format
        .block_copy_size(None)
        .or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)))
        .unwrap_or(4) as u64;
    let (bw, bh) = format.block_dimensions();
    let mips: u64 = (0..t.mip_level_count())
        .map(|m| {
            let w = (t.width() >> m).max(1).div_ceil(bw) as u64;
            let h = (t.height() >> m).max(1).div_ceil(bh) as u64;
            w * h * block
        })
        .sum();
    mips * t.depth_or_array_layers() as u64 * t.sample_count() as u64
}

/// Bytes of buffers.
pub fn buffer_bytes<'a>(buffers: impl IntoIterator<Item = &'a Buffer>) -> u64 {
    buffers.into_iter().map(|b| b.size()).sum()
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn measure(
    memory: Res<CausticsGpuMemory>,
    buffers: Query<&ViewCausticsBuffer>,
    trace: Option<Res<TraceSceneBuffers>>,
    aaps: Query<&AapsViewState>,
    photon_map: Query<&PhotonMapViewState>,
    image_space: (Query<&ImageSpaceViewState>, Option<Res<ImageSpaceScene>>),
    volume: (Query<&VolumeViewState>, Option<Res<VolumeStore>>),
    temporal: Query<&super::temporal::ViewTemporal>,
) {
    let mut m = BTreeMap::new();
    m.insert(
        "caustics_buffer",
        buffers.iter().map(|b| texture_bytes(&b.texture)).sum(),
    );
    m.insert("trace", trace.map_or(0, |t| buffer_bytes(&t.buffers)));
    m.insert("aaps", aaps.iter().map(AapsViewState::gpu_bytes).sum());
    m.insert(
        "photon_map",
        photon_map.iter().map(PhotonMapViewState::gpu_bytes).sum(),
    );
    let (views, scene) = image_space;
    m.insert(
        "image_space",
        views
            .iter()
            .map(ImageSpaceViewState::gpu_bytes)
            .sum::<u64>()
            + scene.map_or(0, |s| s.scene.gpu_bytes()),
    );
    let (views, store) = volume;
    m.insert(
        "volume",
        views.iter().map(VolumeViewState::gpu_bytes).sum::<u64>()
            + store.map_or(0, |s| s.gpu_bytes()),
    );
    m.insert(
        "temporal",
        temporal
            .iter()
            .map(super::temporal::ViewTemporal::gpu_bytes)
            .sum(),
    );
    memory.set(m);
}

fn path(name: &str) -> DiagnosticPath {
    DiagnosticPath::new(format!("caustics/gpu_bytes/{name}"))
}

fn publish(memory: Res<CausticsGpuMemory>, mut diagnostics: Diagnostics) {
    for (name, bytes) in memory.bytes() {
        diagnostics.add_measurement(&path(name), || bytes as f64);
    }
}

pub(crate) fn build(app: &mut App) {
    let memory = CausticsGpuMemory::default();
    for name in MEMORY_NAMES {
        app.register_diagnostic(Diagnostic::new(path(name)).with_suffix(" B"));
    }
    app.insert_resource(memory.clone())
        .add_systems(Last, publish);
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app
            .insert_resource(memory)
            .add_systems(Render, measure.in_set(RenderSystems::PrepareBindGroups));
    }
}
