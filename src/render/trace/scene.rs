//! The GPU scene shared by the BVH techniques (AAPS, the photon map): the flattened two-level
//! BVH with its normals and material table (uploaded only when the gathered scene changes and
//! a camera uses one of them), and the light table.

use bevy::prelude::*;
use bevy::render::render_resource::{Buffer, BufferInitDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;
use glam::Vec3;

use crate::optics;
use crate::scene::{CausticsScene, GpuBvh, Tlas, TraceLight};

/// One light on the GPU (80 bytes; `GpuLight` in surface.wgsl).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuLight {
    /// Point/spot position, or the corner of a directional light's origin grid.
    pub position: Vec3,
    /// 0 directional, 1 point, 2 spot.
    pub kind: u32,
    /// Directional: travel direction. Spot: axis.
    pub axis: Vec3,
    /// Spot: cosine of the outer angle.
    pub cos_outer: f32,
    /// Directional grid edge along the first parameter.
    pub side_u: Vec3,
    /// Spot: cosine of the inner angle.
    pub cos_inner: f32,
    /// Directional grid edge along the second parameter.
    pub side_v: Vec3,
    /// Power over the whole parameter square, per channel: lm (point/spot, over the sphere)
    /// or lux · m² (directional, over the grid).
    pub power: Vec3,
}

impl GpuLight {
    /// The 80 bytes of the GPU layout.
    pub fn bytes(&self) -> Vec<u8> {
        let f = [
            self.position.x,
            self.position.y,
            self.position.z,
            f32::from_bits(self.kind),
            self.axis.x,
            self.axis.y,
            self.axis.z,
            self.cos_outer,
            self.side_u.x,
            self.side_u.y,
            self.side_u.z,
            self.cos_inner,
            self.side_v.x,
            self.side_v.y,
            self.side_v.z,
            0.0,
            self.power.x,
            self.power.y,
            self.power.z,
            0.0,
        ];
        f.iter().flat_map(|v| v.to_le_bytes()).collect()
    }
}

/// The bounding sphere of the casters (specular instances), if any.
pub fn caster_sphere(tlas: &Tlas) -> Option<(Vec3, f32)> {
    let (lo, hi) = tlas.bounds_where(|i| i.surface.is_specular())?;
    Some(((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-9)))
}

/// Whether `light` can reach a caster: a directional or point light always can (if there is
/// one); a spot light only when its outer cone meets the casters' bounding sphere.
pub fn reaches_casters(light: &TraceLight, tlas: &Tlas) -> bool {
    let Some((c, r)) = caster_sphere(tlas) else {
        return false;
    };
    match *light {
        TraceLight::Directional { .. } | TraceLight::Point { .. } => true,
        TraceLight::Spot {
            position,
            direction,
            outer_angle,
            ..
        } => {
            let to_c = c - position;
            let dist = to_c.length();
            if dist <= r {
                return true;
            }
            let Some(axis) = direction.try_normalize() else {
                return false;
            };
            let angle = axis.dot(to_c / dist).clamp(-1.0, 1.0).acos();
            angle <= outer_angle.clamp(0.0, core::f32::consts::PI) + (r / dist).asin()
        }
    }
}

/// The GPU light table: one entry per light that reaches a caster, in order, with the
/// entity of each. A directional light's origin grid is the square of side `2r` around the
/// casters' bounding sphere (centre `c`, radius `r`), perpendicular to the light, placed
/// before the whole scene (like the reference tracer's disc).
pub fn gpu_lights(tlas: &Tlas, lights: &[(Entity, TraceLight)]) -> Vec<(Entity, GpuLight)> {
    let Some((c, r)) = caster_sphere(tlas) else {
        return Vec::new();
    };
    let scene_radius = tlas.bounds_where(|_| true).map_or(r, |(lo, hi)| {
        ((hi - lo) * 0.5).length() + (c - (lo + hi) * 0.5).length()
    });
    let mut out = Vec::new();
    for (e, light) in lights {
        if !reaches_casters(light, tlas) {
            continue;
        }
        let l = match *light {
            TraceLight::Directional {
                direction,
                illuminance,
            } => {
                let Some(d) = direction.try_normalize() else {
                    continue;
                };
                let (t, b) = optics::orthonormal_basis(d);
                let start = c - d * (scene_radius * 2.0 + r);
                GpuLight {
                    position: start - t * r - b * r,
                    kind: 0,
                    axis: d,
                    cos_outer: -1.0,
                    side_u: t * 2.0 * r,
                    cos_inner: -1.0,
                    side_v: b * 2.0 * r,
                    power: illuminance * 4.0 * r * r,
                }
            }
            TraceLight::Point { position, flux } => GpuLight {
                position,
                kind: 1,
                axis: Vec3::Z,
                cos_outer: -1.0,
                side_u: Vec3::ZERO,
                cos_inner: -1.0,
                side_v: Vec3::ZERO,
                power: flux,
            },
            TraceLight::Spot {
                position,
                direction,
                flux,
                inner_angle,
                outer_angle,
            } => GpuLight {
                position,
                kind: 2,
                axis: direction.try_normalize().unwrap_or(Vec3::NEG_Z),
                cos_outer: outer_angle.cos(),
                side_u: Vec3::ZERO,
                cos_inner: inner_angle.cos(),
                side_v: Vec3::ZERO,
                power: flux,
            },
        };
        if l.power.is_finite() && l.position.is_finite() && l.side_u.is_finite() {
            out.push((*e, l));
        }
    }
    out
}

/// The scene in GPU buffers (render world), rebuilt when the gathered scene's generation
/// changes and a camera uses a BVH technique.
#[derive(Resource)]
pub struct TraceSceneBuffers {
    /// Generation of the scene uploaded.
    pub generation: u64,
    /// Its `CausticsScene::caustic_generation` (histories restart on it).
    pub caustic_generation: u64,
    /// Its `CausticsScene::receiver_generation` (pixels whose surface moved restart).
    pub receiver_generation: u64,
    /// Nodes (the TLAS, its prims and every BLAS behind a header), triangles with their
    /// normals, instances with their materials ([`GpuBvh::packed`]), and lights: bindings 0, 1,
    /// 2 and 8 of every tracer.
    pub buffers: [Buffer; 4],
    /// Lights in the table.
    pub lights: u32,
    /// Extent of the scene, metres (ray offsets).
    pub scene_scale: f32,
    /// The casters' bounding sphere: centre and radius, metres.
    pub casters: (Vec3, f32),
    /// Whether any instance is a mirror (a conductor): cameras may see caustics in it.
    pub has_mirrors: bool,
    /// What the tracer must handle (its pipelines' variant).
    pub features: super::TraceFeatures,
}

/// The render world's copy of the gathered scene.
#[derive(Resource, Clone, Default)]
pub struct ExtractedCausticsScene(pub CausticsScene);

impl TraceSceneBuffers {
    /// Flatten and upload `scene`; `None` when no caustic light reaches a caster (nothing for
    /// a photon tracer to do).
    pub fn upload(device: &RenderDevice, scene: &CausticsScene) -> Option<Self> {
        let lights = gpu_lights(&scene.tlas, &scene.lights);
        if lights.is_empty() {
            return None;
        }
        let bvh = GpuBvh::from_tlas(&scene.tlas);
        let mut light_bytes: Vec<u8> = lights.iter().flat_map(|(_, l)| l.bytes()).collect();
        light_bytes.resize(light_bytes.len().max(80), 0);
        let [nodes, triangles, instances] = bvh.packed();
        let contents = [nodes, triangles, instances, light_bytes];
        let names = [
            "caustics:trace:nodes",
            "caustics:trace:triangles",
            "caustics:trace:instances",
            "caustics:trace:lights",
        ];
        let buffers = std::array::from_fn(|i| {
            device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some(names[i]),
                contents: &contents[i],
                usage: BufferUsages::STORAGE,
            })
        });
        let scene_scale = scene
            .tlas
            .bounds_where(|_| true)
            .map_or(1.0, |(lo, hi)| (hi - lo).max_element());
        Some(Self {
            generation: scene.generation,
            caustic_generation: scene.caustic_generation,
            receiver_generation: scene.receiver_generation,
            buffers,
            lights: lights.len() as u32,
            scene_scale,
            casters: caster_sphere(&scene.tlas).unwrap_or((Vec3::ZERO, 1.0)),
            has_mirrors: scene
                .tlas
                .instances
                .iter()
                .any(|i| matches!(i.surface, crate::scene::Surface::Conductor { .. })),
            features: super::TraceFeatures {
                dielectrics: scene
                    .tlas
                    .instances
                    .iter()
                    .any(|i| matches!(i.surface, crate::scene::Surface::Dielectric { .. })),
                point_lights: lights.iter().any(|(_, l)| l.kind != 0),
                caster_chains: false,
            },
        })
    }
}
