//! Render-world plumbing: the per-view caustics buffer, the extraction of the camera settings
//! and of the technique's result, and the log of dispatched passes.
//!
//! The caustics buffer is a per-view `Rgba32Float` texture of caustic irradiance (lux, linear,
//! RGB; alpha unused). 32-bit floats, because focused sunlight exceeds f16's 65 504 lux.
//! Every technique writes it, the composite reads it.

pub mod aaps;
pub mod composite;
pub mod fixed_splat;
pub mod image;
pub mod image_space;
pub mod losses;
pub mod memory;
pub mod photon_map;
pub mod readback;
pub mod settle;
pub mod span;
pub mod temporal;
pub mod trace;
pub mod volume;

use std::sync::{Arc, Mutex};

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_resource::{
    Extent3d, Origin3d, TexelCopyBufferLayout, TexelCopyTextureInfo, Texture, TextureAspect,
    TextureDescriptor, TextureDimension, TextureFormat, TextureUsages, TextureView,
    TextureViewDescriptor,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::sync_component::SyncComponent;
use bevy::render::{Render, RenderApp, RenderSystems};

pub use self::image::CausticImage;
use crate::components::{
    AapsSettings, Caustics, CausticsDebugView, CausticsStereo, CausticsTechnique,
    ImageSpaceSettings, PhotonMapSettings,
};

/// Format of the caustics buffer.
pub const CAUSTICS_BUFFER_FORMAT: TextureFormat = TextureFormat::Rgba32Float;

/// The names of the caustics passes dispatched, shared by the main and render worlds. Each
/// pass adds its name when it records GPU work; tools drain it (see
/// [`CausticsDispatchLog::take`]). Empty for a scene that needs no pass. A game that never
/// drains it holds at most [`CausticsDispatchLog::CAPACITY`] names (the oldest go first).
#[derive(Resource, Clone, Default, Debug)]
pub struct CausticsDispatchLog(Arc<Mutex<Vec<&'static str>>>);

impl CausticsDispatchLog {
    /// Names kept at most: hundreds of frames of every pass, 64 KiB.
    pub const CAPACITY: usize = 4096;

    /// Record that `pass` was dispatched.
    pub fn record(&self, pass: &'static str) {
        if let Ok(mut v) = self.0.lock() {
            if v.len() >= Self::CAPACITY {
                v.drain(..Self::CAPACITY / 2);
            }
            v.push(pass);
        }
    }

    /// Everything recorded since the last call.
    pub fn take(&self) -> Vec<&'static str> {
        self.0
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }
}

/// The render-world copy of a camera's [`Caustics`] and of its technique's CPU result.
#[derive(Component, Clone, Debug)]
pub struct ExtractedCaustics {
    /// The technique.
    pub technique: CausticsTechnique,
    /// AAPS settings (the camera's [`AapsSettings`] or the defaults).
    pub aaps: AapsSettings,
    /// Image-space settings (the camera's [`ImageSpaceSettings`] or the defaults).
    pub image_space: ImageSpaceSettings,
    /// Photon-map settings (the camera's [`PhotonMapSettings`] or the defaults).
    pub photon_map: PhotonMapSettings,
    /// The camera's [`CausticsStereo`], if it is one eye of a pair.
    pub stereo: Option<CausticsStereo>,
    /// Photon budget per light (the quality preset).
    pub photons_per_light: u64,
    /// Composite as if albedo were 1.
    pub white_albedo: bool,
    /// Run the technique but composite nothing ([`CausticsDebugView::Hidden`]).
    pub hidden: bool,
    /// The reference image to upload, with its serial.
    pub reference: Option<(Arc<CausticImage>, u64)>,
    /// [`Caustics::settle_frames`].
    pub settle_frames: u32,
}

/// An irradiance image made on the CPU for a camera (the `Reference` technique of the `tools`
/// feature makes one), shown as its caustics when its technique is
/// [`CausticsTechnique::Reference`]. Extracted and uploaded when `serial` changes.
#[derive(Component, Clone, Debug)]
pub struct CausticsCpuImage {
    /// Irradiance, lux, the size of the camera's viewport.
    pub image: Arc<CausticImage>,
    /// Increases with every new image.
    pub serial: u64,
}

impl SyncComponent for Caustics {
    type Target = (ExtractedCaustics, ViewCausticsBuffer);
}

impl ExtractComponent for Caustics {
    type QueryData = (
        &'static Caustics,
        Option<&'static CausticsCpuImage>,
        Option<&'static AapsSettings>,
        Option<&'static ImageSpaceSettings>,
        Option<&'static PhotonMapSettings>,
        Option<&'static CausticsStereo>,
    );
    type QueryFilter = ();
    type Out = ExtractedCaustics;

    fn extract_component(
        (c, reference, aaps, image_space, photon_map, stereo): (
            &Caustics,
            Option<&CausticsCpuImage>,
            Option<&AapsSettings>,
            Option<&ImageSpaceSettings>,
            Option<&PhotonMapSettings>,
            Option<&CausticsStereo>,
        ),
    ) -> Option<Self::Out> {
        let reference = reference.map(|r| (r.image.clone(), r.serial));
        // Nothing to composite for the reference technique before its first image: the view
        // carries no caustics components, and no pass runs.
        if c.technique == CausticsTechnique::Reference && reference.is_none() {
            return None;
        }
        Some(ExtractedCaustics {
            technique: c.technique,
            aaps: aaps.cloned().unwrap_or_default(),
            image_space: image_space.cloned().unwrap_or_default(),
            photon_map: photon_map.cloned().unwrap_or_default(),
            stereo: stereo.copied(),
            photons_per_light: c.quality.photons_per_light(),
            white_albedo: c.debug_view == CausticsDebugView::WhiteAlbedo,
            hidden: c.debug_view == CausticsDebugView::Hidden,
            reference,
            settle_frames: c.settle_frames,
        })
    }
}

/// A view's caustics buffer.
#[derive(Component)]
pub struct ViewCausticsBuffer {
    /// The texture (`TEXTURE_BINDING | STORAGE_BINDING | COPY_DST | COPY_SRC`).
    pub texture: Texture,
    /// Its default view.
    pub view: TextureView,
    /// Size in pixels.
    pub size: UVec2,
    /// Serial of the reference image in it (0: none).
    pub uploaded: u64,
    /// This texture's serial, unique in the process (from 1): a view that gets a new buffer
    /// has nothing kept in it (`render::settle`).
    pub serial: u64,
}

/// The next [`ViewCausticsBuffer::serial`].
static BUFFER_SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Workgroups of 64 for `n` threads (one per photon) as a 2D grid, at most 65 535 along x;
/// the shaders rebuild the index as `y · groups.x · 64 + x`.
pub fn photon_groups(n: u32) -> [u32; 3] {
    let groups = n.div_ceil(64).max(1);
    let x = groups.min(65_535);
    [x, groups.div_ceil(x), 1]
}

/// A view's clip-from-world matrix (the extracted one, else projection × inverse view).
pub(crate) fn clip_from_world(view: &bevy::render::view::ExtractedView) -> Mat4 {
    view.clip_from_world
        .unwrap_or_else(|| view.clip_from_view * view.world_from_view.affine().inverse())
}

/// A view-sized `Rgba32Float` texture (the caustics buffer, the volumes' splat target).
pub(crate) fn view_texture(
    device: &RenderDevice,
    label: &'static str,
    size: UVec2,
    usage: TextureUsages,
) -> bevy::render::render_resource::Texture {
    view_texture_of(device, label, size, CAUSTICS_BUFFER_FORMAT, usage)
}

/// A view-sized 2D texture of `format`.
pub(crate) fn view_texture_of(
    device: &RenderDevice,
    label: &'static str,
    size: UVec2,
    format: bevy::render::render_resource::TextureFormat,
    usage: TextureUsages,
) -> bevy::render::render_resource::Texture {
    device.create_texture(&TextureDescriptor {
        label: Some(label),
        size: Extent3d {
            width: size.x,
            height: size.y,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The plugin's render-world systems of one frame, outside extraction and the passes: settle
/// tracking, the caustics buffers, the scene uploads, every technique's view preparation and
/// pipeline variants, the volume gizmos, the composite's pipeline and the memory count, in
/// their schedule order. The CPU benchmark (`frame_cpu_render_static`) runs this on a render
/// world after the renderer's own frames; the plugin adds the same systems to `Render`.
#[doc(hidden)]
pub fn add_frame_systems_for_bench(schedule: &mut bevy::ecs::schedule::Schedule) {
    schedule.add_systems(
        (
            settle::track_settle,
            prepare_caustics_buffers,
            trace::prepare_trace_scene,
            aaps::view::prepare_aaps_views,
            aaps::pipelines::queue_aaps_trace_variant,
            image_space::view::prepare_image_space_scene,
            image_space::pipelines::queue_image_space_trace_variant,
            image_space::view::prepare_image_space_views,
            photon_map::pipelines::queue_photon_map_pipelines,
            photon_map::pipelines::queue_photon_map_trace_variant,
            photon_map::view::prepare_photon_map_views,
            volume::pipelines::queue_volume_pipelines,
            volume::view::prepare_volumes,
            volume::gizmo::prepare_volume_gizmos,
            temporal::prepare_temporal,
            composite::prepare_composite_pipelines,
            memory::measure,
        )
            .chain(),
    );
}

/// Create (or resize) each caustics view's buffer and upload a new reference image.
pub(crate) fn prepare_caustics_buffers(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        Option<&mut ViewCausticsBuffer>,
    )>,
) {
    for (entity, caustics, camera, buffer) in &mut views {
        let Some(size) = camera.physical_viewport_size else {
            continue;
        };
        if size.x == 0 || size.y == 0 {
            continue;
        }
        let mut new_buffer = None;
        let buffer = match buffer {
            Some(b) if b.size == size => b.into_inner(),
            _ => {
                let texture = view_texture(
                    &device,
                    "caustics_buffer",
                    size,
                    TextureUsages::TEXTURE_BINDING
                        | TextureUsages::STORAGE_BINDING
                        | TextureUsages::RENDER_ATTACHMENT
                        | TextureUsages::COPY_DST
                        | TextureUsages::COPY_SRC,
                );
                let view = texture.create_view(&TextureViewDescriptor::default());
                new_buffer = Some(ViewCausticsBuffer {
                    texture,
                    view,
                    size,
                    uploaded: 0,
                    serial: BUFFER_SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
                });
                new_buffer.as_mut().unwrap()
            }
        };
        if let Some((image, serial)) = caustics
            .reference
            .as_ref()
            .filter(|_| caustics.technique == CausticsTechnique::Reference)
            && *serial != buffer.uploaded
            && image.width == size.x
            && image.height == size.y
        {
            upload(&queue, &buffer.texture, image);
            buffer.uploaded = *serial;
        }
        if let Some(b) = new_buffer.take() {
            commands.entity(entity).insert(b);
        }
    }
}

/// Copy a CPU image into a caustics buffer. Guard: non-finite values become 0.
pub fn upload(queue: &RenderQueue, texture: &Texture, image: &CausticImage) {
    let mut bytes = Vec::with_capacity(image.data.len() * 16);
    for v in &image.data {
        let v = crate::optics::finite_or_zero(*v);
        for c in [v.x, v.y, v.z, 0.0f32] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    queue.write_texture(
        TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: Origin3d::ZERO,
            aspect: TextureAspect::All,
        },
        &bytes,
        TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(image.width * 16),
            rows_per_image: Some(image.height),
        },
        Extent3d {
            width: image.width,
            height: image.height,
            depth_or_array_layers: 1,
        },
    );
}

/// Render-app part of the plugin: extraction, buffers, composite.
pub(crate) fn build(app: &mut App, log: CausticsDispatchLog) {
    app.add_plugins(ExtractComponentPlugin::<Caustics>::default());
    composite::build(app);
    // Each technique checks what it needs of the GPU itself and warns when it cannot run.
    fixed_splat::build(app);
    aaps::build(app);
    trace::build(app);
    volume::build(app);
    image_space::build(app);
    photon_map::build(app);
    readback::build(app);
    span::build(app);
    temporal::build(app);
    memory::build(app);
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app.insert_resource(log).add_systems(
        Render,
        (
            settle::track_settle.in_set(RenderSystems::PrepareViews),
            prepare_caustics_buffers.in_set(RenderSystems::PrepareResources),
        ),
    );
}

#[cfg(test)]
mod tests {
    use super::CausticsDispatchLog;

    /// A game never drains the log: an hour of frames holds no more than its capacity, and a
    /// tool that drains every frame sees every name.
    #[test]
    fn dispatch_log_is_bounded() {
        let log = CausticsDispatchLog::default();
        for _ in 0..216_000 {
            log.record("caustics/aaps/trace");
        }
        let kept = log.take();
        assert!(!kept.is_empty() && kept.len() <= CausticsDispatchLog::CAPACITY);
        log.record("a");
        log.record("b");
        assert_eq!(log.take(), ["a", "b"]);
        assert!(log.take().is_empty());
    }
}
