//! What a caster's shape allows light to do: whether a ray that leaves its surface after a
//! reflection can meet the same surface again. Image space follows further mirror reflections
//! only in scenes where one can (`render::image_space`).

use std::collections::HashMap;

use glam::Vec3;

use super::bvh::MeshGeometry;

/// The most triangle-vertex plane tests [`MeshGeometry::reflects_onto_itself`] makes before it
/// answers "maybe" (true): a 4096-triangle closed mesh of 2050 vertices is about 8.4 M.
const MAX_PLANE_TESTS: usize = 1 << 24;

impl MeshGeometry {
    /// Whether a ray reflected off this surface may meet it again: false for a flat mesh (every
    /// vertex in one plane) and for a closed convex one (every edge shared by two triangles once
    /// vertices are welded by position, and every vertex on one side of every triangle's
    /// plane), whose outside light can only leave; true otherwise (a ring, a bowl, a
    /// heightfield), and when the mesh is too large to test (more than 2^24 plane tests).
    /// Degenerate triangles are skipped; no triangle at all is flat.
    pub fn reflects_onto_itself(&self) -> bool {
        let (lo, hi) = self
            .positions
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let size = (hi - lo).max_element();
        if !size.is_finite() || size <= 0.0 {
            return false;
        }
        let eps = 1e-4 * size;
        let (welded, points) = self.welded(1e-5 * size);
        let planes: Vec<(Vec3, f32)> = self
            .indices
            .iter()
            .filter_map(|t| {
                let [a, b, c] = t.map(|i| self.positions.get(i as usize).copied());
                let (a, b, c) = (a?, b?, c?);
                let n = (b - a).cross(c - a).try_normalize()?;
                Some((n, n.dot(a)))
            })
            .collect();
        if planes.len().saturating_mul(points.len()) > MAX_PLANE_TESTS {
            return true;
        }
        let one_side = |&(n, d): &(Vec3, f32)| {
            let (mut above, mut below) = (false, false);
            for p in &points {
                let s = n.dot(*p) - d;
                above |= s > eps;
                below |= s < -eps;
            }
            (above, below)
        };
        let sides: Vec<(bool, bool)> = planes.iter().map(one_side).collect();
        if sides.iter().all(|&(a, b)| !a && !b) {
            return false;
        }
        let convex = sides.iter().all(|&(a, b)| !(a && b));
        !(convex && closed(&self.indices, &welded))
    }

    /// Vertex ids welded by position (a grid of cell `cell`) and the distinct points.
    fn welded(&self, cell: f32) -> (Vec<u32>, Vec<Vec3>) {
        let mut ids = HashMap::new();
        let mut points = Vec::new();
        let welded = self
            .positions
            .iter()
            .map(|p| {
                let key = (*p / cell).round().as_ivec3().to_array();
                *ids.entry(key).or_insert_with(|| {
                    points.push(*p);
                    points.len() as u32 - 1
                })
            })
            .collect();
        (welded, points)
    }
}

/// Every edge of the triangles (vertex ids through `welded`) is shared by exactly two of them.
fn closed(indices: &[[u32; 3]], welded: &[u32]) -> bool {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in indices {
        let Some(v) = t
            .iter()
            .map(|&i| welded.get(i as usize).copied())
            .collect::<Option<Vec<u32>>>()
        else {
            return false;
        };
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&n| n == 2)
}
