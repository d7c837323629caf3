//! The scene BVH (obvhs) against brute force, and degenerate triangles.

use super::*;

/// An intersection written independently of `scene::bvh::intersect_triangle` (which is
/// Möller-Trumbore in f32): the ray meets the triangle's plane in f64, and the point is inside
/// when it lies on the inner side of all three edges (edge functions, Pineda). `None` for rays
/// parallel to the plane, behind the origin, or outside.
fn plane_edge_hit(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f64> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let n = (b - a).cross(c - a);
    let den = n.dot(d);
    if n.length_squared() == 0.0 || den.abs() < 1e-12 * n.length() {
        return None;
    }
    let t = n.dot(a - o) / den;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let p = o + d * t;
    let e0 = (b - a).cross(p - a).dot(n);
    let e1 = (c - b).cross(p - b).dot(n);
    let e2 = (a - c).cross(p - c).dot(n);
    (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0).then_some(t)
}

#[test]
fn bvh_matches_brute_force() {
    let desc = scenes::glass_sphere();
    let (tlas, _, _) = desc.to_trace(16, 16);
    let mut rng = Pcg32::new(11, 0);
    let mut hits = 0;
    let mut near_edge = 0;
    for _ in 0..2000 {
        let o = Vec3::new(
            rng.next_f32() * 4.0 - 2.0,
            rng.next_f32() * 3.0,
            rng.next_f32() * 4.0 - 2.0,
        );
        let d = uniform_sphere(rng.next_vec2());
        let bvh = tlas.closest_hit(o, d, 0.0, f32::INFINITY, |_| false);
        // Brute force over every triangle of every instance, with the independent test.
        let mut best: Option<(f64, u32)> = None;
        for (ii, inst) in tlas.instances.iter().enumerate() {
            let g = &inst.blas.geometry;
            for t in &g.indices {
                let [a, b, c] = t.map(|k| {
                    inst.world_from_local
                        .transform_point3(g.positions[k as usize])
                });
                if let Some(tt) = plane_edge_hit(o, d, a, b, c)
                    && best.is_none_or(|x| tt < x.0)
                {
                    best = Some((tt, ii as u32));
                }
            }
        }
        match (bvh, best) {
            (Some(h), Some((t, i))) => {
                hits += 1;
                let t = t as f32;
                assert!((h.t - t).abs() <= 1e-4 * t.max(1.0), "t {} vs {}", h.t, t);
                assert_eq!(h.instance, i, "ray {o} {d}");
            }
            (None, None) => {}
            // A ray through a shared edge or vertex may be caught by one test and slip past
            // the other by rounding (f32 vs f64): allowed, but at most 4 rays in 2000.
            (a, b) => {
                near_edge += 1;
                assert!(near_edge <= 4, "BVH {a:?} vs independent test {b:?}");
            }
        }
    }
    assert!(hits > 500);
    // Closed-form hits: straight down onto the floor (y = 0) outside the ball's shadow, from
    // any height, t = height; straight down through the ball's centre line 0.3 m off axis, the
    // first hit is the ball's top at y = 1 + sqrt(0.5² - 0.3²) within the mesh's flattening.
    for k in 0..500 {
        let (x, z) = (rng.next_f32() * 30.0 - 15.0, rng.next_f32() * 30.0 - 15.0);
        if x * x + z * z < 0.6 * 0.6 {
            continue;
        }
        let h = 1e-3 + k as f32 * 0.02;
        let hit = tlas
            .closest_hit(Vec3::new(x, h, z), Vec3::NEG_Y, 0.0, f32::INFINITY, |_| {
                false
            })
            .expect("floor");
        assert!(
            (hit.t - h).abs() <= 1e-5 * h.max(1.0),
            "floor at t {} vs {h}",
            hit.t
        );
        assert_eq!(hit.instance, 0);
    }
    let top = 1.0 + (0.25f32 - 0.09).sqrt();
    let hit = tlas
        .closest_hit(
            Vec3::new(0.3, 5.0, 0.0),
            Vec3::NEG_Y,
            0.0,
            f32::INFINITY,
            |_| false,
        )
        .expect("ball");
    assert_eq!(hit.instance, 1);
    // A chord of the 96-gon lies inside the circle by at most r (1 - cos(π/96)) = 2.7e-4 m.
    assert!(
        (5.0 - hit.t - top).abs() < 1e-3,
        "ball top at {} vs {top}",
        5.0 - hit.t
    );
}

#[test]
fn degenerate_triangles_are_skipped() {
    use bevy_caustics::scene::{Blas, MeshGeometry};
    use std::sync::Arc;
    let g = MeshGeometry {
        positions: vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::X * 2.0,
            Vec3::Y,
            Vec3::splat(f32::NAN),
        ],
        normals: None,
        indices: vec![[0, 1, 2], [0, 0, 0], [0, 1, 3], [0, 1, 4], [0, 1, 99]],
    };
    let b = Blas::build(Arc::new(g));
    assert_eq!(b.triangle_count(), 1);
    assert_eq!(b.degenerate_triangles, 4);
    let empty = Blas::build(Arc::new(MeshGeometry::default()));
    assert!(empty.intersect(Vec3::ZERO, Vec3::X, 0.0, 1.0).is_none());
}
