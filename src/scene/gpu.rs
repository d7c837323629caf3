//! The two-level BVH flattened into plain arrays for the GPU (the WGSL twin of
//! [`super::Tlas::closest_hit`] is `src/render/bvh.wgsl`).
//!
//! Layout (std430, everything 16-byte aligned):
//! - `nodes`: two `vec4<f32>` per node, `(min.xyz, bitcast<f32>(prim_count))` and
//!   `(max.xyz, bitcast<f32>(first_index))`; every BLAS's nodes follow each other, child and
//!   leaf indices are made global.
//! - `triangles`: three `vec4<f32>` per triangle, `(v0, bitcast(index in mesh))`, `(e1, 0)`,
//!   `(e2, 0)`, in BVH order.
//! - `instances`: [`GpuInstance`], the world-to-object transform as three rows plus the root node
//!   of its BLAS.
//! - `tlas_nodes` (same encoding, leaves index `tlas_prims`) and `tlas_prims` (instance index).
//!
//! On the GPU these seven arrays are packed into three storage buffers ([`GpuBvh::packed`]), so a
//! tracer fits WebGPU's default of 8 storage buffers per shader stage with room for its own:
//! - **nodes**: a header `vec4<u32>(tlas nodes, first prim word, first BLAS node word, 0)`,
//!   then the TLAS nodes, the TLAS prims (four `u32` per `vec4`), then the BLAS nodes;
//! - **triangles**: six `vec4` per triangle, the three above and the three vertex normals;
//! - **instances**: seven `vec4` per instance (112 bytes), the [`GpuInstance`] and the three
//!   material rows ([`material_rows`]).

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec2;

use super::{Blas, Surface, Tlas};

/// One instance on the GPU (64 bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct GpuInstance {
    /// Rows of the 3x4 world-to-object matrix: `p_local = row_i . (p, 1)`.
    pub local_from_world: [[f32; 4]; 3],
    /// Index of its BLAS's root node in `nodes`, or `u32::MAX` for an empty BLAS.
    pub root: u32,
    /// Padding.
    pub pad: [u32; 3],
}

/// The flattened scene.
#[derive(Clone, Debug, Default)]
pub struct GpuBvh {
    /// BLAS nodes of every mesh.
    pub nodes: Vec<[f32; 4]>,
    /// Triangles of every mesh.
    pub triangles: Vec<[f32; 4]>,
    /// Instances, in TLAS instance order.
    pub instances: Vec<GpuInstance>,
    /// TLAS nodes.
    pub tlas_nodes: Vec<[f32; 4]>,
    /// TLAS leaf slots to instance indices.
    pub tlas_prims: Vec<u32>,
    /// Vertex shading normals of every triangle (object space).
    pub normals: Vec<[f32; 4]>,
    /// Material of every instance.
    pub materials: Vec<[f32; 4]>,
}

/// Material kinds on the GPU.
pub const GPU_DIFFUSE: u32 = 0;
/// A dielectric interface.
pub const GPU_DIELECTRIC: u32 = 1;
/// A conductor mirror.
pub const GPU_CONDUCTOR: u32 = 2;

/// The three `vec4` rows of a surface: `(kind, ior, thin, attenuation distance)`,
/// `(attenuation colour, 0)`, `(albedo, f0 or a dielectric's transmission tint, 0)`. A clear medium's distance is `3e38`
/// (finite, so no infinity reaches a buffer).
pub fn material_rows(surface: &Surface) -> [[f32; 4]; 3] {
    let k = |k: u32| f32::from_bits(k);
    match *surface {
        Surface::Diffuse { albedo } => [
            [k(GPU_DIFFUSE), 1.0, 0.0, 3e38],
            [1.0, 1.0, 1.0, 0.0],
            [albedo.x, albedo.y, albedo.z, 0.0],
        ],
        Surface::Dielectric {
            ior,
            attenuation_color: c,
            attenuation_distance,
            thin,
            tint,
        } => [
            [
                k(GPU_DIELECTRIC),
                ior,
                if thin { 1.0 } else { 0.0 },
                if attenuation_distance.is_finite() {
                    attenuation_distance.min(3e38)
                } else {
                    3e38
                },
            ],
            [c.x, c.y, c.z, 0.0],
            [tint.x, tint.y, tint.z, 0.0],
        ],
        Surface::Conductor { f0 } => [
            [k(GPU_CONDUCTOR), 1.0, 0.0, 3e38],
            [1.0, 1.0, 1.0, 0.0],
            [f0.x, f0.y, f0.z, 0.0],
        ],
    }
}

fn push_nodes(
    out: &mut Vec<[f32; 4]>,
    nodes: &[obvhs::bvh2::node::Bvh2Node],
    node_base: u32,
    leaf_base: u32,
) {
    for n in nodes {
        let (min, max) = (n.aabb.min, n.aabb.max);
        let first = if n.prim_count == 0 {
            n.first_index + node_base
        } else {
            n.first_index + leaf_base
        };
        out.push([min.x, min.y, min.z, f32::from_bits(n.prim_count)]);
        out.push([max.x, max.y, max.z, f32::from_bits(first)]);
    }
}

impl GpuBvh {
    /// Flatten `tlas`; each BLAS shared by several instances is stored once.
    pub fn from_tlas(tlas: &Tlas) -> Self {
        let mut out = GpuBvh::default();
        let mut roots: HashMap<*const Blas, u32> = HashMap::new();
        for inst in &tlas.instances {
            let key = Arc::as_ptr(&inst.blas);
            let root = *roots.entry(key).or_insert_with(|| {
                let nodes = inst.blas.nodes();
                if nodes.is_empty() {
                    return u32::MAX;
                }
                let node_base = (out.nodes.len() / 2) as u32;
                let tri_base = (out.triangles.len() / 3) as u32;
                push_nodes(&mut out.nodes, nodes, node_base, tri_base);
                for (v0, e1, e2, src) in inst.blas.triangles_bvh_order() {
                    out.triangles.push([v0.x, v0.y, v0.z, f32::from_bits(src)]);
                    out.triangles.push([e1.x, e1.y, e1.z, 0.0]);
                    out.triangles.push([e2.x, e2.y, e2.z, 0.0]);
                    for bary in [Vec2::ZERO, Vec2::X, Vec2::Y] {
                        let n = inst.blas.normals(src, bary).1;
                        out.normals.push([n.x, n.y, n.z, 0.0]);
                    }
                }
                node_base
            });
            out.materials.extend(material_rows(&inst.surface));
            let m = inst.local_from_world;
            let (x, y, z, t) = (
                m.matrix3.x_axis,
                m.matrix3.y_axis,
                m.matrix3.z_axis,
                m.translation,
            );
            out.instances.push(GpuInstance {
                local_from_world: [
                    [x.x, y.x, z.x, t.x],
                    [x.y, y.y, z.y, t.y],
                    [x.z, y.z, z.z, t.z],
                ],
                root: if inst.normal_matrix == glam::Mat3::ZERO {
                    u32::MAX
                } else {
                    root
                },
                pad: [0; 3],
            });
        }
        let (nodes, prims) = tlas.nodes_and_prims();
        push_nodes(&mut out.tlas_nodes, nodes, 0, 0);
        out.tlas_prims = prims.to_vec();
        out
    }

    /// The three storage buffers of the GPU (module doc): nodes, triangles, instances. Each is
    /// at least 16 bytes (storage bindings may not be empty).
    pub fn packed(&self) -> [Vec<u8>; 3] {
        let word = |v: f32| v.to_le_bytes();
        let tlas_nodes = (self.tlas_nodes.len() / 2) as u32;
        let prim_base = 1 + self.tlas_nodes.len() as u32;
        let blas_base = prim_base + self.tlas_prims.len().div_ceil(4) as u32;
        let mut nodes: Vec<u8> = [tlas_nodes, prim_base, blas_base, 0]
            .iter()
            .flat_map(|u| u.to_le_bytes())
            .collect();
        nodes.extend(self.tlas_nodes.iter().flatten().flat_map(|&v| word(v)));
        let mut prims: Vec<u8> = self
            .tlas_prims
            .iter()
            .flat_map(|u| u.to_le_bytes())
            .collect();
        prims.resize(prims.len().div_ceil(16) * 16, 0);
        nodes.extend(prims);
        nodes.extend(self.nodes.iter().flatten().flat_map(|&v| word(v)));
        let mut triangles = Vec::with_capacity(self.triangles.len() * 32);
        for (tri, normals) in self.triangles.chunks(3).zip(self.normals.chunks(3)) {
            for v in tri.iter().chain(normals) {
                triangles.extend(v.iter().flat_map(|&x| word(x)));
            }
        }
        triangles.resize(triangles.len().max(16), 0);
        let mut instances = Vec::with_capacity(self.instances.len() * 112);
        for (inst, mat) in self
            .instance_bytes()
            .chunks(64)
            .zip(self.materials.chunks(3))
        {
            instances.extend_from_slice(inst);
            instances.extend(mat.iter().flatten().flat_map(|&x| word(x)));
        }
        instances.resize(instances.len().max(112), 0);
        [nodes, triangles, instances]
    }

    /// `instances` as raw bytes.
    pub fn instance_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.instances.len() * 64);
        for i in &self.instances {
            for r in &i.local_from_world {
                for c in r {
                    b.extend_from_slice(&c.to_le_bytes());
                }
            }
            for u in [i.root, 0, 0, 0] {
                b.extend_from_slice(&u.to_le_bytes());
            }
        }
        b
    }
}
