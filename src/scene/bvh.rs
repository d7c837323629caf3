//! Two-level CPU BVH: one BLAS per mesh asset (built once, in object space) and a TLAS over
//! the instances (rebuilt when an instance moves; cheap, it holds one box per instance).
//!
//! Built with `obvhs` (PLOC builder, Meister et al.), chosen because it builds in parallel,
//! gives a plain BVH2 node array we can flatten for the GPU, and is MIT/Apache like us.
//! Triangles are intersected with our own Möller-Trumbore so degenerate triangles and
//! watertightness are handled the way the optics core documents.

use std::sync::Arc;
use std::time::Duration;

use glam::{Affine3A, Mat3, Vec2, Vec3};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, ray::Ray, ray::RayHit};
use obvhs_glam::Vec3A as OVec3A;

use super::model::Surface;

fn ov(v: Vec3) -> OVec3A {
    OVec3A::new(v.x, v.y, v.z)
}

/// Triangle mesh geometry in object space.
#[derive(Clone, Debug, Default)]
pub struct MeshGeometry {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Optional per-vertex normals (smooth shading of specular events).
    pub normals: Option<Vec<Vec3>>,
    /// Triangles as vertex index triples.
    pub indices: Vec<[u32; 3]>,
}

/// One triangle, stored in BVH order.
#[derive(Clone, Copy, Debug)]
struct Tri {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Index into `MeshGeometry::indices`.
    source: u32,
}

/// A bottom-level BVH over one mesh.
pub struct Blas {
    /// The geometry it was built from.
    pub geometry: Arc<MeshGeometry>,
    bvh: Option<Bvh2>,
    tris: Vec<Tri>,
    /// Object-space bounds (min, max).
    pub bounds: (Vec3, Vec3),
    /// Triangles left out because they have zero area or non-finite vertices.
    pub degenerate_triangles: u32,
}

/// A closest hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the (unit) world ray.
    pub t: f32,
    /// Instance index in the TLAS.
    pub instance: u32,
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// Barycentrics (u, v) of v1 and v2.
    pub bary: Vec2,
}

impl Blas {
    /// Build the BLAS of `geometry`. Degenerate triangles (zero area, out-of-range indices or
    /// non-finite positions) are skipped and counted.
    pub fn build(geometry: Arc<MeshGeometry>) -> Self {
        let mut tris = Vec::with_capacity(geometry.indices.len());
        let mut degenerate = 0;
        let n = geometry.positions.len() as u32;
        for (i, idx) in geometry.indices.iter().enumerate() {
            if idx.iter().any(|&k| k >= n) {
                degenerate += 1;
                continue;
            }
            let [a, b, c] = idx.map(|k| geometry.positions[k as usize]);
            let (e1, e2) = (b - a, c - a);
            let area2 = e1.cross(e2).length();
            // Stiff suite "degenerate and zero-area triangles": skipped and counted.
            let valid =
                a.is_finite() && b.is_finite() && c.is_finite() && area2.is_finite() && area2 > 0.0;
            if !valid {
                degenerate += 1;
                continue;
            }
            tris.push(Tri {
                v0: a,
                e1,
                e2,
                source: i as u32,
            });
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &tris {
            for p in [t.v0, t.v0 + t.e1, t.v0 + t.e2] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if tris.is_empty() {
            lo = Vec3::ZERO;
            hi = Vec3::ZERO;
        }
        let bvh = if tris.is_empty() {
            None
        } else {
            let boxes: Vec<Aabb> = tris
                .iter()
                .map(|t| {
                    let (a, b, c) = (t.v0, t.v0 + t.e1, t.v0 + t.e2);
                    Aabb::new(ov(a.min(b).min(c)), ov(a.max(b).max(c)))
                })
                .collect();
            let bvh = obvhs::bvh2::builder::build_bvh2(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            );
            // Reorder triangles into BVH order so leaves index them directly.
            tris = bvh
                .primitive_indices
                .iter()
                .map(|&i| tris[i as usize])
                .collect();
            Some(bvh)
        };
        Self {
            geometry,
            bvh,
            tris,
            bounds: (lo, hi),
            degenerate_triangles: degenerate,
        }
    }

    /// The BVH2 nodes (obvhs layout: inner nodes have `prim_count == 0` and their children at
    /// `first_index` and `first_index + 1`; leaves index [`Blas::triangles_bvh_order`]).
    pub fn nodes(&self) -> &[obvhs::bvh2::node::Bvh2Node] {
        self.bvh.as_ref().map_or(&[], |b| &b.nodes)
    }

    /// Triangles in BVH order as `(v0, v1 - v0, v2 - v0, index in the mesh)`.
    pub fn triangles_bvh_order(&self) -> impl Iterator<Item = (Vec3, Vec3, Vec3, u32)> + '_ {
        self.tris.iter().map(|t| (t.v0, t.e1, t.e2, t.source))
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Closest hit of an object-space ray `(o, d)` in `(tmin, tmax)`; `d` need not be unit.
    /// Returns `(t, triangle, bary)`.
    pub fn intersect(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<(f32, u32, Vec2)> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(ov(o), ov(d), tmin, tmax);
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(ray, &mut hit, |r, id| {
            let tri = &self.tris[id];
            intersect_triangle(o, d, tri.v0, tri.e1, tri.e2, r.tmin, r.tmax)
                .map_or(f32::INFINITY, |(t, _)| t)
        });
        if !found {
            return None;
        }
        // Recompute the barycentrics of the closest triangle only.
        let tri = &self.tris[hit.primitive_id as usize];
        let (t, uv) = intersect_triangle(o, d, tri.v0, tri.e1, tri.e2, tmin, tmax)?;
        Some((t, tri.source, uv))
    }

    /// Object-space geometric normal (unnormalised cross product direction, unit length) and
    /// interpolated shading normal of triangle `tri` at `bary`.
    pub fn normals(&self, tri: u32, bary: Vec2) -> (Vec3, Vec3) {
        let idx = self.geometry.indices[tri as usize];
        let p = idx.map(|k| self.geometry.positions[k as usize]);
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let ns = match &self.geometry.normals {
            Some(n) if n.len() == self.geometry.positions.len() => {
                let w = 1.0 - bary.x - bary.y;
                let s = n[idx[0] as usize] * w
                    + n[idx[1] as usize] * bary.x
                    + n[idx[2] as usize] * bary.y;
                let s = s.normalize_or_zero();
                if s == Vec3::ZERO { ng } else { s }
            }
            _ => ng,
        };
        (ng, ns)
    }
}

/// Möller-Trumbore ray/triangle test with `e1 = v1 - v0`, `e2 = v2 - v0`. Rejects rays parallel
/// to the plane (|det| below a relative epsilon) and any non-finite result.
#[inline]
pub fn intersect_triangle(
    o: Vec3,
    d: Vec3,
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, Vec2)> {
    let p = d.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length() * p.length();
    // Parallel to the plane (or a NaN determinant): no hit.
    if det.is_nan() || det.abs() <= 1e-12 * scale || scale == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    if t.is_finite() && t > tmin && t < tmax {
        Some((t, Vec2::new(u, v)))
    } else {
        None
    }
}

/// A placed mesh.
#[derive(Clone)]
pub struct Instance {
    /// Shared BLAS of the mesh asset.
    pub blas: Arc<Blas>,
    /// Object to world.
    pub world_from_local: Affine3A,
    /// World to object.
    pub local_from_world: Affine3A,
    /// Transforms object normals to world (inverse transpose).
    pub normal_matrix: Mat3,
    /// How it interacts with light.
    pub surface: Surface,
    /// A caller id (the entity bits in the ECS path).
    pub id: u64,
}

impl Instance {
    /// Place `blas` with `world_from_local`. A singular transform (zero scale) gives an
    /// instance that is never hit.
    pub fn new(blas: Arc<Blas>, world_from_local: Affine3A, surface: Surface, id: u64) -> Self {
        let det = world_from_local.matrix3.determinant();
        let (local_from_world, normal_matrix) = if det.is_finite() && det.abs() > 1e-30 {
            let inv = world_from_local.inverse();
            (inv, Mat3::from(inv.matrix3).transpose())
        } else {
            (Affine3A::from_scale(Vec3::ZERO), Mat3::ZERO)
        };
        Self {
            blas,
            world_from_local,
            local_from_world,
            normal_matrix,
            surface,
            id,
        }
    }

    /// World-space bounds (min, max).
    pub fn world_bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.blas.bounds;
        let mut a = Vec3::splat(f32::INFINITY);
        let mut b = Vec3::splat(f32::NEG_INFINITY);
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let w = self.world_from_local.transform_point3(c);
            a = a.min(w);
            b = b.max(w);
        }
        (a, b)
    }

    fn hittable(&self) -> bool {
        self.normal_matrix != Mat3::ZERO && self.blas.triangle_count() > 0
    }
}

/// The top level: instances and a BVH over their world bounds.
#[derive(Default)]
pub struct Tlas {
    /// All instances.
    pub instances: Vec<Instance>,
    bvh: Option<Bvh2>,
}

impl Tlas {
    /// Build over `instances`.
    pub fn build(instances: Vec<Instance>) -> Self {
        let boxes: Vec<Aabb> = instances
            .iter()
            .map(|i| {
                if i.hittable() {
                    let (a, b) = i.world_bounds();
                    Aabb::new(ov(a), ov(b))
                } else {
                    Aabb::new(ov(Vec3::splat(f32::MAX)), ov(Vec3::splat(f32::MAX)))
                }
            })
            .collect();
        let bvh = (!boxes.is_empty()).then(|| {
            obvhs::bvh2::builder::build_bvh2(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        });
        Self { instances, bvh }
    }

    /// Closest hit along the world ray `(o, d)` (d unit) in `(tmin, tmax)`, skipping instances
    /// for which `skip` returns true.
    pub fn closest_hit(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        skip: impl Fn(&Instance) -> bool,
    ) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(ov(o), ov(d), tmin, tmax);
        let mut rh = RayHit::none();
        let mut found: Option<Hit> = None;
        bvh.ray_traverse(ray, &mut rh, |r, id| {
            let inst_index = bvh.primitive_indices[id];
            let inst = &self.instances[inst_index as usize];
            if !inst.hittable() || skip(inst) {
                return f32::INFINITY;
            }
            let lo = inst.local_from_world.transform_point3(o);
            let ld = inst.local_from_world.transform_vector3(d);
            match inst.blas.intersect(lo, ld, r.tmin, r.tmax) {
                Some((t, tri, bary)) => {
                    if found.is_none_or(|f| t < f.t) {
                        found = Some(Hit {
                            t,
                            instance: inst_index,
                            triangle: tri,
                            bary,
                        });
                    }
                    t
                }
                None => f32::INFINITY,
            }
        });
        found
    }

    /// The TLAS nodes (same layout as [`Blas::nodes`]) and the instance index of each leaf
    /// primitive slot.
    pub fn nodes_and_prims(&self) -> (&[obvhs::bvh2::node::Bvh2Node], &[u32]) {
        self.bvh
            .as_ref()
            .map_or((&[], &[]), |b| (&b.nodes, &b.primitive_indices))
    }

    /// World geometric normal and shading normal at a hit (unit; same side as the mesh's
    /// winding-order normal).
    pub fn hit_normals(&self, hit: &Hit) -> (Vec3, Vec3) {
        let inst = &self.instances[hit.instance as usize];
        let (ng, ns) = inst.blas.normals(hit.triangle, hit.bary);
        let ng = (inst.normal_matrix * ng).normalize_or_zero();
        let ns = (inst.normal_matrix * ns).normalize_or_zero();
        (ng, if ns == Vec3::ZERO { ng } else { ns })
    }

    /// World bounds of the instances that satisfy `filter`, or `None` if none.
    pub fn bounds_where(&self, filter: impl Fn(&Instance) -> bool) -> Option<(Vec3, Vec3)> {
        let mut out: Option<(Vec3, Vec3)> = None;
        for i in self.instances.iter().filter(|i| i.hittable() && filter(i)) {
            let (a, b) = i.world_bounds();
            out = Some(match out {
                Some((lo, hi)) => (lo.min(a), hi.max(b)),
                None => (a, b),
            });
        }
        out
    }
}
