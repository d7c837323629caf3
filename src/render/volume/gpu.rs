//! GPU state of caustics volumes (render world): the scene's triangles for the probes, and per
//! volume the photon levels (one per slab boundary, so a differential update restarts from any
//! slab), the live lists, the final states, the receiver hits, the density tiles, the slab and
//! projector G-buffers, and the change signatures that decide what re-runs.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::sync::atomic::AtomicBool;

use bevy::prelude::*;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferInitDescriptor, BufferUsages, Extent3d, Texture,
    TextureDescriptor, TextureDimension, TextureUsages, TextureView, TextureViewDescriptor,
    TextureViewDimension,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use glam::{Affine3A, Mat4, Vec3, Vec4};

use super::pipelines::{GBUFFER_DEPTH_FORMAT, GBUFFER_FORMAT};
use crate::components::CausticsVolume;
use crate::optics;
use crate::scene::CausticsScene;
use crate::scene::gpu::material_rows;
use crate::volume::{
    VolumeFrame, VolumeRun, face_code, progressive_order, progressive_scale, seed_photons,
};

/// Stride of the probe uniforms (dynamic offsets).
pub const PROBE_STRIDE: u64 = 256;
/// Words of the counts buffer: live counts per level (<= 65), then the counters at `CNT`.
pub const COUNT_WORDS: u64 = 104;
/// First counter word (`CNT` in common.wgsl).
pub const CNT: u64 = 72;
/// Bytes of `VolParams`.
const PARAMS: u64 = 176;
/// Bytes of a photon / hit record.
const RECORD: u64 = 64;

/// The scene's triangles in world space for the probes, and what the signatures need.
pub struct VolumeScene {
    /// `CausticsScene::generation` it was built from.
    pub generation: u64,
    /// Its `CausticsScene::caustic_generation` (image space's history restarts on it).
    pub caustic_generation: u64,
    /// 6 `vec4` per triangle: (position, instance) and normal per corner.
    pub tris: Buffer,
    /// 3 `vec4` per instance ([`material_rows`]).
    pub materials: Buffer,
    /// Triangles.
    pub tri_count: u32,
    /// World box of everything (projector march range).
    pub bounds: (Vec3, Vec3),
    /// Largest extent of the scene, metres.
    pub scale: f32,
    /// The caustic lights.
    pub lights: Vec<crate::scene::TraceLight>,
    /// Their main-world entities, in the same order.
    pub light_entities: Vec<Entity>,
    /// Their signature (a light change re-runs every slab).
    pub light_sig: u64,
}

impl VolumeScene {
    /// GPU bytes held (`render::memory`).
    pub fn gpu_bytes(&self) -> u64 {
        crate::render::memory::buffer_bytes([&self.tris, &self.materials])
    }

    /// Flatten every instance's triangles into world space (degenerate and non-finite
    /// triangles left out).
    pub fn build(device: &RenderDevice, scene: &CausticsScene) -> Self {
        let mut tris: Vec<f32> = Vec::new();
        let mut mats: Vec<f32> = Vec::new();
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        for (index, inst) in scene.tlas.instances.iter().enumerate() {
            mats.extend(material_rows(&inst.surface).iter().flatten());
            let g = &inst.blas.geometry;
            for tri in &g.indices {
                let p = tri.map(|i| {
                    g.positions
                        .get(i as usize)
                        .map_or(Vec3::NAN, |v| inst.world_from_local.transform_point3(*v))
                });
                let geo = (p[1] - p[0]).cross(p[2] - p[0]);
                if !p.iter().all(|v| v.is_finite())
                    || geo.length_squared().partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater)
                {
                    continue;
                }
                let gn = geo.normalize();
                for (c, v) in p.iter().enumerate() {
                    let n = g
                        .normals
                        .as_ref()
                        .and_then(|ns| ns.get(tri[c] as usize))
                        .map(|n| inst.normal_matrix * *n)
                        .and_then(|n| n.try_normalize())
                        .unwrap_or(gn);
                    tris.extend([v.x, v.y, v.z, index as f32, n.x, n.y, n.z, 0.0]);
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
            }
        }
        if tris.is_empty() {
            tris.extend([0.0; 24]);
            lo = Vec3::ZERO;
            hi = Vec3::ZERO;
        }
        if mats.is_empty() {
            mats.extend([0.0; 12]);
        }
        let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let tri_count = if scene.tlas.instances.is_empty() {
            0
        } else {
            (tris.len() / 24) as u32
        };
        Self {
            generation: scene.generation,
            caustic_generation: scene.caustic_generation,
            tris: device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some("caustics:buffer:volume_tris"),
                contents: &bytes(&tris),
                usage: BufferUsages::STORAGE,
            }),
            materials: device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some("caustics:buffer:volume_materials"),
                contents: &bytes(&mats),
                usage: BufferUsages::STORAGE,
            }),
            tri_count,
            bounds: (lo, hi),
            scale: (hi - lo).max_element().max(1e-3),
            lights: scene.lights.iter().map(|(_, l)| *l).collect(),
            light_entities: scene.lights.iter().map(|(e, _)| *e).collect(),
            light_sig: debug_hash(&scene.lights.iter().map(|(_, l)| *l).collect::<Vec<_>>()),
        }
    }
}

/// What decides a volume's buffer sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolumeKey {
    /// Photon capacity.
    pub capacity: u32,
    /// Effective slab count (after LOD).
    pub slabs: u32,
    /// Slab G-buffer side.
    pub gbuffer: u32,
    /// Projector G-buffer side.
    pub projector: u32,
    /// Density tile side.
    pub tile: u32,
}

/// Change signatures (section 3.5's differential updates).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Signatures {
    /// Frame, faces and settings of the volume.
    pub volume: u64,
    /// The lights.
    pub lights: u64,
    /// The instances touching each slab.
    pub slabs: Vec<u64>,
    /// The whole scene (receivers outside the volume: projectors only).
    pub generation: u64,
}

/// One volume on the GPU.
pub struct VolumeGpu {
    /// The main-world entity.
    pub entity: Entity,
    /// Sizes.
    pub key: VolumeKey,
    /// Geometry.
    pub frame: VolumeFrame,
    /// Exit faces, bit per face code.
    pub exit_mask: u32,
    /// `VolParams`.
    pub params: Buffer,
    /// `VolStep` entries: slab k near 2k, far 2k + 1, projector face f at 2 slabs + f,
    /// deposits at 2 slabs + 6.
    pub probes: Buffer,
    /// Photon states per level (slabs levels of `capacity`).
    pub states: Buffer,
    /// Live photon indices per level.
    pub live: Buffer,
    /// Live counts per level and counters.
    pub counts: Buffer,
    /// Final state of every photon.
    pub finals: Buffer,
    /// Receiver hit of every photon.
    pub hits: Buffer,
    /// Photons per density tile (7 sets).
    pub tiles: Buffer,
    /// Indirect dispatch arguments per slab.
    pub args: Buffer,
    /// G_near / G_far of every slab (layers 2k, 2k + 1).
    pub slab_gbuffer: Texture,
    /// One view per slab layer.
    pub slab_layers: Vec<TextureView>,
    /// All slab layers.
    pub slab_array: TextureView,
    /// Projector G-buffers (layer = face code).
    pub cube_gbuffer: Texture,
    /// One view per face.
    pub cube_layers: Vec<TextureView>,
    /// All faces.
    pub cube_array: TextureView,
    /// Depth attachment of the slab passes.
    pub slab_depth: TextureView,
    /// Depth attachment of the projector passes.
    pub cube_depth: TextureView,
    /// Last signatures.
    pub sig: Signatures,
    /// First slab touched by changes not run yet (`slabs`: projectors only); `None`: none.
    pub change: Option<u32>,
    /// This frame's update (`volume::progressive::schedule_run`); `None`: nothing re-runs.
    pub run: Option<VolumeRun>,
    /// Set by the passes when they ran `run`.
    pub ran: AtomicBool,
    /// Photons seeded (the capacity used), and those carrying flux (the trace list).
    pub seeded: (u32, u32),
    /// Trace-list entries traced in the current accumulation (progressive mode).
    pub traced: u32,
    /// In some caustics camera's frustum (or culling off).
    pub visible: bool,
}

impl VolumeGpu {
    /// GPU bytes held (`render::memory`): the buffers and the three layered textures (the layer
    /// views share them).
    pub fn gpu_bytes(&self) -> u64 {
        use crate::render::memory::{buffer_bytes, texture_bytes};
        buffer_bytes([
            &self.params,
            &self.probes,
            &self.states,
            &self.live,
            &self.counts,
            &self.finals,
            &self.hits,
            &self.tiles,
            &self.args,
        ]) + [&*self.slab_gbuffer, &*self.cube_gbuffer]
            .into_iter()
            .chain([self.slab_depth.texture(), self.cube_depth.texture()])
            .map(texture_bytes)
            .sum::<u64>()
    }
}

fn storage(device: &RenderDevice, label: &'static str, size: u64, extra: BufferUsages) -> Buffer {
    device.create_buffer(&BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

fn layered(
    device: &RenderDevice,
    label: &'static str,
    side: u32,
    layers: u32,
) -> (Texture, Vec<TextureView>, TextureView) {
    let texture = device.create_texture(&TextureDescriptor {
        label: Some(label),
        size: Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: TextureDimension::D2,
        format: GBUFFER_FORMAT,
        usage: TextureUsages::RENDER_ATTACHMENT | TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let views = (0..layers)
        .map(|l| {
            texture.create_view(&TextureViewDescriptor {
                dimension: Some(TextureViewDimension::D2),
                base_array_layer: l,
                array_layer_count: Some(1),
                ..default()
            })
        })
        .collect();
    let all = texture.create_view(&TextureViewDescriptor {
        dimension: Some(TextureViewDimension::D2Array),
        ..default()
    });
    (texture, views, all)
}

fn depth(device: &RenderDevice, side: u32) -> TextureView {
    device
        .create_texture(&TextureDescriptor {
            label: Some("caustics:texture:volume_depth"),
            size: Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: TextureDimension::D2,
            format: GBUFFER_DEPTH_FORMAT,
            usage: TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&TextureViewDescriptor::default())
}

/// Counters of one density-tile set (`vol_set_words` in common.wgsl): levels of side
/// `tile`, `tile / 2`, .. 1 texel, coarsest first, each `(larger G-buffer side / side)²`.
pub fn tile_set_words(key: &VolumeKey) -> u64 {
    let res = key.gbuffer.max(key.projector);
    let mut side = key.tile.max(1);
    let mut words = 0;
    loop {
        words += (res.div_ceil(side) as u64).pow(2);
        if side == 1 {
            return words;
        }
        side /= 2;
    }
}

/// Bytes of the density tiles: 7 sets (6 projector faces and the deposits) of u32 counters.
pub fn tile_bytes(key: &VolumeKey) -> u64 {
    7 * tile_set_words(key) * 4
}

impl VolumeGpu {
    /// Allocate everything for `key`.
    pub fn new(device: &RenderDevice, entity: Entity, key: VolumeKey, frame: VolumeFrame) -> Self {
        let cap = key.capacity as u64;
        let levels = key.slabs as u64;
        let (slab_gbuffer, slab_layers, slab_array) = layered(
            device,
            "caustics:texture:volume_slabs",
            key.gbuffer,
            2 * key.slabs,
        );
        let (cube_gbuffer, cube_layers, cube_array) = layered(
            device,
            "caustics:texture:volume_projectors",
            key.projector,
            6,
        );
        Self {
            entity,
            key,
            frame,
            exit_mask: 0,
            params: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:buffer:volume_params"),
                size: PARAMS,
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            probes: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:buffer:volume_probes"),
                size: PROBE_STRIDE * (2 * levels + 7),
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            states: storage(
                device,
                "caustics:buffer:volume_states",
                levels * cap * RECORD,
                BufferUsages::empty(),
            ),
            live: storage(
                device,
                "caustics:buffer:volume_live",
                levels * cap * 4,
                BufferUsages::empty(),
            ),
            counts: storage(
                device,
                "caustics:buffer:volume_counts",
                COUNT_WORDS * 4,
                BufferUsages::COPY_SRC,
            ),
            finals: storage(
                device,
                "caustics:buffer:volume_finals",
                cap * RECORD,
                BufferUsages::empty(),
            ),
            hits: storage(
                device,
                "caustics:buffer:volume_hits",
                cap * RECORD,
                BufferUsages::empty(),
            ),
            tiles: storage(
                device,
                "caustics:buffer:volume_tiles",
                tile_bytes(&key),
                BufferUsages::empty(),
            ),
            args: device.create_buffer(&BufferDescriptor {
                label: Some("caustics:buffer:volume_args"),
                size: 12 * levels.max(1),
                usage: BufferUsages::STORAGE | BufferUsages::INDIRECT,
                mapped_at_creation: false,
            }),
            slab_gbuffer,
            slab_layers,
            slab_array,
            cube_gbuffer,
            cube_layers,
            cube_array,
            slab_depth: depth(device, key.gbuffer),
            cube_depth: depth(device, key.projector),
            sig: Signatures::default(),
            change: Some(0),
            run: None,
            ran: AtomicBool::new(false),
            seeded: (0, 0),
            traced: 0,
            visible: false,
        }
    }

    /// Write `VolParams` (but its per-frame part, [`Self::write_run`]) and the probe entries.
    pub fn write_uniforms(
        &self,
        queue: &RenderQueue,
        scene: &VolumeScene,
        volume: &CausticsVolume,
    ) {
        let f = &self.frame;
        let mut b: Vec<u8> = Vec::with_capacity(PARAMS as usize);
        let mut fl = |v: f32| b.extend_from_slice(&v.to_le_bytes());
        for v in [f.centre.x, f.centre.y, f.centre.z, scene.scale] {
            fl(v);
        }
        for i in 0..3 {
            let a = f.axes.col(i);
            for v in [a.x, a.y, a.z, f.half[i]] {
                fl(v);
            }
        }
        let u = |v: u32| f32::from_bits(v);
        for v in [
            u(f.e as u32),
            u(f.j as u32),
            u(f.k as u32),
            u((f.s < 0.0) as u32),
            u(self.key.gbuffer),
            u(self.key.projector),
            u(self.key.tile),
            u(0x2545_f491),
            u(self.key.capacity),
            u(self.key.slabs),
            u(self.exit_mask),
            u(self.seeded.0),
        ] {
            fl(v);
        }
        // splat.w, the flux scale, is written by `write_run` below.
        for v in [volume.splat_overlap, 16.0, 0.5, 1.0] {
            fl(v);
        }
        let (lo, hi) = scene.bounds;
        let k = volume.density_photons.max(1) as f32;
        for v in [lo.x, lo.y, lo.z, k, hi.x, hi.y, hi.z, 0.0] {
            fl(v);
        }
        queue.write_buffer(&self.params, 0, &b);
        self.write_run(queue);

        let far = {
            let (lo, hi) = scene.bounds;
            let mut d: f32 = 0.0;
            for c in 0..8 {
                let p = Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                d = d.max((p - f.centre).length());
            }
            d * 1.01 + 1e-3
        };
        let n = self.key.slabs;
        let mut probes = vec![0u8; (PROBE_STRIDE * (2 * n as u64 + 7)) as usize];
        let mut put = |index: u32, m: Mat4, plane: Vec4, info: [u32; 4]| {
            let at = index as usize * PROBE_STRIDE as usize;
            let mut w = Vec::with_capacity(96);
            for v in m.to_cols_array() {
                w.extend_from_slice(&v.to_le_bytes());
            }
            for v in plane.to_array() {
                w.extend_from_slice(&v.to_le_bytes());
            }
            for v in info {
                w.extend_from_slice(&v.to_le_bytes());
            }
            probes[at..at + w.len()].copy_from_slice(&w);
        };
        for k in 0..n {
            let m = f.slab_clip_from_world(k);
            put(2 * k, m, f.depth_plane(), [k, 2 * k, 0, 0]);
            put(2 * k + 1, m, f.depth_plane(), [k, 2 * k + 1, 0, 0]);
        }
        for face in 0..6 {
            let (m, plane) = f.projector(face, far);
            put(2 * n + face, m, plane, [face, face, 0, 0]);
        }
        put(2 * n + 6, Mat4::IDENTITY, Vec4::ZERO, [6, 0, 0, 0]);
        queue.write_buffer(&self.probes, 0, &probes);
    }

    /// The per-frame part of `VolParams`: the splats' flux scale (`splat.w`,
    /// [`progressive_scale`] once this frame's run is done) and this frame's trace and project
    /// ranges of the trace list (`progress`).
    pub fn write_run(&self, queue: &RenderQueue) {
        let after = self.run.map_or(self.traced, |r| r.traced_after);
        let scale = progressive_scale(self.seeded.1, after);
        queue.write_buffer(&self.params, 124, &scale.to_le_bytes());
        let (trace, project) = self.run.map_or(((0, 0), (0, 0)), |r| (r.trace, r.project));
        let words = [
            trace.0,
            trace.1.saturating_sub(trace.0),
            project.0,
            project.1.saturating_sub(project.0),
        ];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        queue.write_buffer(&self.params, 160, &bytes);
    }

    /// Seed the entry face (section 3.4) into level 0: the states, the trace list (the photons
    /// carrying flux, in index order, or in [`progressive_order`] when `volume.progressive` is
    /// on) and its length; the other counts and counters are zeroed. Sets [`Self::seeded`].
    pub fn seed(
        &mut self,
        queue: &RenderQueue,
        world_from_volume: &Affine3A,
        volume: &CausticsVolume,
        lights: &[crate::scene::TraceLight],
    ) -> Vec<usize> {
        let photons = seed_photons(
            world_from_volume,
            volume.size,
            volume.entry,
            lights,
            self.key.capacity,
        );
        let mut states = Vec::with_capacity(photons.len() * RECORD as usize);
        let mut live: Vec<u32> = Vec::new();
        let mut entered = 0.0;
        for (i, p) in photons.iter().enumerate() {
            let flags: u32 = if p.terminated { 4 | (9 << 4) } else { 0 };
            for v in [
                p.position.x,
                p.position.y,
                p.position.z,
                0.0,
                p.direction.x,
                p.direction.y,
                p.direction.z,
                f32::from_bits(flags),
                p.flux.x,
                p.flux.y,
                p.flux.z,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ] {
                states.extend_from_slice(&v.to_le_bytes());
            }
            if !p.terminated {
                live.push(i as u32);
                entered += optics::luminance(p.flux);
            }
        }
        if volume.progressive > 0 && (volume.progressive as usize) < live.len() {
            live = progressive_order(&live);
        }
        if !states.is_empty() {
            queue.write_buffer(&self.states, 0, &states);
        }
        if !live.is_empty() {
            let bytes: Vec<u8> = live.iter().flat_map(|i| i.to_le_bytes()).collect();
            queue.write_buffer(&self.live, 0, &bytes);
        }
        let mut counts = vec![0u8; (COUNT_WORDS * 4) as usize];
        counts[0..4].copy_from_slice(&(live.len() as u32).to_le_bytes());
        let at = (CNT * 4) as usize;
        counts[at..at + 4].copy_from_slice(&entered.to_le_bytes());
        queue.write_buffer(&self.counts, 0, &counts);
        self.seeded = (photons.len() as u32, live.len() as u32);
        crate::volume::lights_shut_out(&photons, lights)
    }
}

/// Hash of anything `Debug` (settings and lights are small).
pub fn debug_hash(v: &impl core::fmt::Debug) -> u64 {
    let mut h = DefaultHasher::new();
    format!("{v:?}").hash(&mut h);
    h.finish()
}

/// Per-slab signatures: every instance touching slab k (its id, transform, surface, mesh)
/// is hashed into slab k.
pub fn slab_signatures(frame: &VolumeFrame, scene: &CausticsScene) -> Vec<u64> {
    let mut hashers: Vec<DefaultHasher> = (0..frame.slabs).map(|_| DefaultHasher::new()).collect();
    for inst in &scene.tlas.instances {
        let (lo, hi) = inst.world_bounds();
        let Some((k0, k1)) = frame.slabs_touched(lo, hi) else {
            continue;
        };
        let mut h = DefaultHasher::new();
        inst.id.hash(&mut h);
        for v in inst.world_from_local.to_cols_array() {
            v.to_bits().hash(&mut h);
        }
        format!("{:?}", inst.surface).hash(&mut h);
        (std::sync::Arc::as_ptr(&inst.blas) as usize).hash(&mut h);
        let v = h.finish();
        for k in k0..=k1 {
            v.hash(&mut hashers[k as usize]);
        }
    }
    hashers.into_iter().map(|h| h.finish()).collect()
}

/// The exit mask of a volume: bit per face code.
pub fn exit_mask(volume: &CausticsVolume) -> u32 {
    let culled: u32 = volume
        .culling
        .iter()
        .fold(0, |m, f| m | (1 << face_code(*f)));
    volume.exit.iter().fold(0, |m, f| m | (1 << face_code(*f))) & !culled
}
