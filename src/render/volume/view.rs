//! Per-frame preparation of caustics volumes: LOD, frustum culling, what changed since the last
//! update (section 3.5's differential updates) and the per-view splat targets.

use std::sync::atomic::Ordering;

use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferUsages, TextureUsages, TextureView, TextureViewDescriptor,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::ExtractedView;
use glam::Affine3A;

use super::gpu::{
    Signatures, VolumeGpu, VolumeKey, VolumeScene, debug_hash, exit_mask, slab_signatures,
};
use crate::components::{CausticsTechnique, CausticsVolume, VolumeFace};
use crate::render::ExtractedCaustics;
use crate::render::trace::scene::ExtractedCausticsScene;
use crate::scene::TraceLight;
use crate::volume::{VolumeFrame, schedule_run};

/// The main world's volumes (entity, settings, world from volume).
#[derive(Resource, Default, Clone)]
pub struct ExtractedVolumes(pub Vec<(Entity, CausticsVolume, Affine3A)>);

/// Every volume's GPU state and the scene's triangles.
#[derive(Resource, Default)]
pub struct VolumeStore {
    /// Volumes, in extraction order.
    pub volumes: Vec<VolumeGpu>,
    /// Triangles and materials.
    pub scene: Option<VolumeScene>,
    /// The view that runs this frame's updates (the first caustics-volume view).
    pub updater: Option<Entity>,
    /// (volume, light) pairs already warned about: the light's photons cannot enter.
    pub shut_out_warned: Vec<(Entity, Entity)>,
}

/// Per-view state of the `Volume` technique.
#[derive(Component)]
pub struct VolumeViewState {
    /// Splat target, the view's size.
    pub target: TextureView,
    /// Its size.
    pub size: UVec2,
    /// `ViewParams`.
    pub params: Buffer,
    /// Blur radius and sigma.
    pub blur: Buffer,
    /// Indices into [`VolumeStore::volumes`] visible here.
    pub visible: Vec<usize>,
    /// The fixed-point accumulator of the splats, without `FLOAT32_BLENDABLE`
    /// (`render::fixed_splat`).
    pub fixed: Option<Buffer>,
}

impl VolumeViewState {
    /// GPU bytes held (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        crate::render::memory::texture_bytes(self.target.texture())
            + crate::render::memory::buffer_bytes(
                [&self.params, &self.blur].into_iter().chain(&self.fixed),
            )
    }
}

impl VolumeStore {
    /// GPU bytes held by every volume and the scene (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        self.volumes.iter().map(VolumeGpu::gpu_bytes).sum::<u64>()
            + self.scene.as_ref().map_or(0, VolumeScene::gpu_bytes)
    }
}

/// Marker: the view draws volume splats this frame.
#[derive(Component)]
pub struct VolumeViewFrame;

/// Effective slab count (section 3.5's level of detail): beyond `lod_distance` volume
/// diagonals from the nearest camera, halved for every doubling of the distance.
pub fn lod_slabs(slabs: u32, lod_distance: f32, diagonal: f32, distance: f32) -> u32 {
    if lod_distance.is_nan()
        || lod_distance <= 0.0
        || diagonal.is_nan()
        || diagonal <= 0.0
        || !distance.is_finite()
    {
        return slabs.max(1);
    }
    let ratio = distance / (lod_distance * diagonal);
    if ratio <= 1.0 {
        return slabs.max(1);
    }
    let halvings = (ratio.log2().floor() as u32 + 1).min(31);
    (slabs >> halvings).max(1)
}

/// Photons a volume traces (its buffers' capacity): its budget, bounded so that the photon
/// levels (64 bytes per photon per slab) fit one storage binding of `max_binding_bytes`, and by
/// one dispatch of the 1-D passes (65 535 workgroups of 64: [`MAX_PHOTONS_PER_DISPATCH`]). The
/// entry face is divided among the photons traced, so the energy does not depend on the bound.
/// At least 1.
pub fn photon_capacity(photons: i32, slabs: u32, max_binding_bytes: u64) -> u32 {
    let per_photon = 64 * slabs.max(1) as u64;
    (photons.max(0) as u64)
        .min(max_binding_bytes / per_photon)
        .min(MAX_PHOTONS_PER_DISPATCH as u64)
        .max(1) as u32
}

/// Photons one dispatch of the propagation or projector pass covers (65 535 × 64).
pub const MAX_PHOTONS_PER_DISPATCH: u32 = 65_535 * 64;

/// Decide, per volume, what to re-run; allocate and seed as needed.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn prepare_volumes(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    extracted: Option<Res<ExtractedVolumes>>,
    scene: Option<Res<ExtractedCausticsScene>>,
    mut store: ResMut<VolumeStore>,
    limits: Res<crate::limits::CausticsLimits>,
    fixed: Option<Res<crate::render::fixed_splat::FixedSplats>>,
    mut views: Query<(
        Entity,
        &ExtractedCaustics,
        &ExtractedCamera,
        &ExtractedView,
        Option<&mut VolumeViewState>,
    )>,
) {
    let fixed = fixed.is_some_and(|f| f.0);
    let cams: Vec<(Entity, Mat4, Vec3)> = views
        .iter()
        .filter(|(_, c, cam, ..)| {
            c.technique == CausticsTechnique::Volume
                && cam
                    .physical_viewport_size
                    .is_some_and(|s| s.x > 0 && s.y > 0)
        })
        .map(|(e, _, _, view, _)| {
            let clip = crate::render::clip_from_world(view);
            (e, clip, view.world_from_view.translation())
        })
        .collect();
    let volumes: &[(Entity, CausticsVolume, Affine3A)] =
        extracted.as_deref().map_or(&[], |e| e.0.as_slice());
    let scene = scene.filter(|s| !cams.is_empty() && s.0.is_active() && !s.0.lights.is_empty());
    let Some(scene) = scene else {
        store.volumes.clear();
        store.scene = None;
        store.updater = None;
        for (e, c, ..) in &views {
            let mut e = commands.entity(e);
            e.remove::<VolumeViewFrame>();
            if c.technique != CausticsTechnique::Volume {
                e.remove::<VolumeViewState>();
            }
        }
        return;
    };
    let scene = &scene.0;
    if store.scene.as_ref().map(|s| s.generation) != Some(scene.generation) {
        store.scene = Some(VolumeScene::build(&device, scene));
    }
    let max_bytes = limits.max_binding_bytes;
    let mut next: Vec<VolumeGpu> = Vec::new();
    let mut old: Vec<VolumeGpu> = std::mem::take(&mut store.volumes);
    let vs = store.scene.as_ref().unwrap();
    let mut shut_out = Vec::new();
    for (entity, volume, affine) in volumes {
        if volume.photons <= 0 {
            continue;
        }
        let base = VolumeFrame::new(affine, volume.size, volume.entry, volume.slabs);
        let diagonal = 2.0 * base.half.length();
        let nearest = cams
            .iter()
            .map(|(_, _, eye)| eye.distance(base.centre))
            .fold(f32::INFINITY, f32::min);
        let slabs = lod_slabs(volume.slabs.max(1), volume.lod_distance, diagonal, nearest);
        let frame = VolumeFrame::new(affine, volume.size, volume.entry, slabs);
        let capacity = photon_capacity(volume.photons, slabs, max_bytes);
        let key = VolumeKey {
            capacity,
            slabs,
            gbuffer: limits.volume_gbuffer_side(volume.gbuffer_resolution, slabs),
            projector: limits.volume_projector_side(volume.projector_resolution),
            tile: volume.tile_size.clamp(1, 64),
        };
        let mut gpu = match old.iter().position(|g| g.entity == *entity && g.key == key) {
            Some(i) => old.swap_remove(i),
            None => VolumeGpu::new(&device, *entity, key, frame),
        };
        if gpu.ran.swap(false, Ordering::AcqRel)
            && let Some(run) = gpu.run.take()
        {
            gpu.change = None;
            gpu.traced = run.traced_after;
        }
        gpu.frame = frame;
        gpu.exit_mask = exit_mask(volume);
        gpu.visible =
            !volume.frustum_cull || cams.iter().any(|(_, clip, _)| !frame.outside_frustum(clip));
        let volume_sig = debug_hash(&(
            frame,
            gpu.exit_mask,
            volume.photons,
            volume.splat_overlap.to_bits(),
            volume.density_photons,
            volume.entry,
            volume.progressive,
            volume.light,
        ));
        // The per-slab hashes walk every instance: only when the scene or the volume changed.
        let slab_sigs = if volume_sig == gpu.sig.volume && scene.generation == gpu.sig.generation {
            gpu.sig.slabs.clone()
        } else {
            slab_signatures(&frame, scene)
        };
        let sig = Signatures {
            volume: volume_sig,
            lights: vs.light_sig,
            slabs: slab_sigs,
            generation: scene.generation,
        };
        let first_change = if sig.volume != gpu.sig.volume
            || sig.lights != gpu.sig.lights
            || sig.slabs.len() != gpu.sig.slabs.len()
        {
            Some(0)
        } else if let Some(k) = (0..sig.slabs.len()).find(|&k| sig.slabs[k] != gpu.sig.slabs[k]) {
            Some(if volume.differential { k as u32 } else { 0 })
        } else if sig.generation != gpu.sig.generation {
            Some(if volume.differential { slabs } else { 0 })
        } else {
            None
        };
        if first_change == Some(0) && (sig.volume != gpu.sig.volume || sig.lights != gpu.sig.lights)
        {
            let (ids, lights) = carried_lights(vs, volume);
            if let Some(l) = volume.light.filter(|_| lights.is_empty()) {
                shut_out.push((*entity, l, None));
            }
            for i in gpu.seed(&queue, affine, volume, &lights) {
                shut_out.push((*entity, ids[i], Some(volume.entry)));
            }
        }
        if let Some(k) = first_change {
            gpu.change = Some(gpu.change.map_or(k, |p| p.min(k)));
        }
        let (_, live) = gpu.seeded;
        gpu.run = schedule_run(gpu.change, slabs, live, gpu.traced, volume.progressive);
        if first_change.is_some() {
            gpu.write_uniforms(&queue, vs, volume);
        } else if gpu.run.is_some() {
            gpu.write_run(&queue);
        }
        gpu.sig = sig;
        next.push(gpu);
    }
    store.volumes = next;
    warn_shut_out(&mut store.shut_out_warned, shut_out);
    store.updater = cams.first().map(|c| c.0);

    for (entity, caustics, camera, _, state) in &mut views {
        let mut e = commands.entity(entity);
        let size = camera.physical_viewport_size.unwrap_or_default();
        let Some((_, clip, eye)) = cams.iter().find(|c| c.0 == entity) else {
            e.remove::<VolumeViewFrame>();
            if caustics.technique != CausticsTechnique::Volume {
                e.remove::<VolumeViewState>();
            }
            continue;
        };
        let visible: Vec<usize> = store
            .volumes
            .iter()
            .enumerate()
            .filter(|(_, g)| g.visible)
            .map(|(i, _)| i)
            .collect();
        if visible.is_empty() {
            e.remove::<VolumeViewFrame>();
            continue;
        }
        let mut fresh = None;
        let state = match state {
            Some(s) if s.size == size => s.into_inner(),
            _ => {
                fresh = Some(new_view_state(&device, size, fixed));
                fresh.as_mut().unwrap()
            }
        };
        state.visible = visible;
        queue.write_buffer(&state.params, 0, &view_params(*clip, *eye, size));
        let r = volumes
            .iter()
            .map(|v| v.1.blur_radius)
            .max()
            .unwrap_or(0)
            .min(8) as f32;
        let blur: Vec<u8> = [r, (r * 0.5).max(0.5), 0.0, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        queue.write_buffer(&state.blur, 0, &blur);
        if let Some(s) = fresh {
            e.insert(s);
        }
        e.insert(VolumeViewFrame);
    }
}

/// The lights `volume` carries (all of them, or its [`CausticsVolume::light`]) and their
/// entities.
fn carried_lights(vs: &VolumeScene, volume: &CausticsVolume) -> (Vec<Entity>, Vec<TraceLight>) {
    vs.light_entities
        .iter()
        .zip(&vs.lights)
        .filter(|(e, _)| volume.light.is_none_or(|l| l == **e))
        .unzip()
}

/// One warning per (volume, light) whose light cannot enter the volume: its entry face (none:
/// the volume's `light` is no caustic light).
fn warn_shut_out(
    warned: &mut Vec<(Entity, Entity)>,
    shut_out: Vec<(Entity, Entity, Option<VolumeFace>)>,
) {
    for (volume, light, entry) in shut_out {
        if warned.contains(&(volume, light)) {
            continue;
        }
        warned.push((volume, light));
        let Some(entry) = entry else {
            warn!(
                "caustics volume {volume}: CausticsVolume::light is {light}, which is not a \
                 caustic light (no CausticLight, or gone): the volume carries no light"
            );
            continue;
        };
        warn!(
            "caustics volume {volume}: none of light {light}'s light enters through its entry \
             face {entry:?} (the light is behind that face's plane, inside the box, or turned \
             away); place the volume so the light stands over its entry face \
             (CausticsVolume::fit_point), or use AAPS"
        );
    }
}

/// `ViewParams` (raster.wgsl): clip_from_world, world_from_clip, eye and radians per pixel.
fn view_params(clip: Mat4, eye: Vec3, size: UVec2) -> Vec<u8> {
    let p11 = clip.y_axis.y.abs().max(1e-9);
    let per_pixel = 2.0 / (p11 * size.y.max(1) as f32);
    clip.to_cols_array()
        .into_iter()
        .chain(clip.inverse().to_cols_array())
        .chain([eye.x, eye.y, eye.z, per_pixel])
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

fn new_view_state(device: &RenderDevice, size: UVec2, fixed: bool) -> VolumeViewState {
    // Storage: the fixed-point fallback's resolve writes it.
    let storage = if fixed {
        TextureUsages::STORAGE_BINDING
    } else {
        TextureUsages::empty()
    };
    let target = crate::render::view_texture(
        device,
        "caustics:texture:volume_splats",
        size,
        TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING | storage,
    )
    .create_view(&TextureViewDescriptor::default());
    let uniform = |label: &'static str, size: u64| {
        device.create_buffer(&BufferDescriptor {
            label: Some(label),
            size,
            usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    VolumeViewState {
        target,
        size,
        params: uniform("caustics:buffer:volume_view", 144),
        blur: uniform("caustics:buffer:volume_blur", 16),
        visible: Vec::new(),
        fixed: fixed.then(|| {
            crate::render::fixed_splat::accumulator(device, "caustics:volume:fixed_splats", size)
        }),
    }
}
