//! The image-space optics core at its extremes, the RSM views, and the settings' validation.

use bevy_caustics::optics::*;
use bevy_caustics::render::image_space::view::{rsm_light, rsm_sources};
use bevy_caustics::render::trace::scene::GpuLight;
use glam::{Vec3, Vec4};

/// Eq. 2: the crossing of two linear segments, exact in the middle, guarded at the extremes.
#[test]
fn march_crossing_is_exact_and_guarded() {
    // Ray 1 → 3, surface 2 → 2: crossing at u = 0.5.
    assert!((march_crossing(1.0, 3.0, 2.0, 2.0) - 0.5).abs() < 1e-6);
    // Surface sloping too: ray 0 → 4, surface 1 → 2 meet at u = 1/3.
    assert!((march_crossing(0.0, 4.0, 1.0, 2.0) - 1.0 / 3.0).abs() < 1e-6);
    // Parallel, NaN and infinite input: the later step.
    assert_eq!(march_crossing(1.0, 2.0, 1.0, 2.0), 1.0);
    assert_eq!(march_crossing(f32::NAN, 2.0, 1.0, 2.0), 1.0);
    assert_eq!(march_crossing(1.0, f32::INFINITY, 1.0, 2.0), 1.0);
    // Outside the step: clamped.
    assert_eq!(march_crossing(0.0, 1.0, -5.0, -5.0), 0.0);
}

#[test]
fn reprojection_cases() {
    assert_eq!(classify_reprojection(10.0, 10.1, 0.02), Reprojection::Plane);
    assert_eq!(
        classify_reprojection(5.0, 10.0, 0.02),
        Reprojection::Concave
    );
    assert_eq!(
        classify_reprojection(15.0, 10.0, 0.02),
        Reprojection::Convex
    );
    assert_eq!(
        classify_reprojection(f32::NAN, 10.0, 0.02),
        Reprojection::Concave
    );
    assert_eq!(
        classify_reprojection(1.0, f32::INFINITY, 0.02),
        Reprojection::Concave
    );
    // Zero thickness: only an exact match is a plane.
    assert_eq!(classify_reprojection(10.0, 10.0, 0.0), Reprojection::Plane);
    assert_eq!(classify_reprojection(10.0, 10.0, -1.0), Reprojection::Plane);
}

/// A photon inside a caster against the light's two layers: inside between them, back at or
/// past the back, front at or before the front; an empty back is an open medium; an empty
/// front, crossed layers or a non-finite depth are lost.
#[test]
fn inside_layers_cases() {
    use InsideLayers::*;
    assert_eq!(inside_layers(2.0, 1.0, 3.0), Inside);
    assert_eq!(inside_layers(3.0, 1.0, 3.0), Back);
    assert_eq!(inside_layers(1e30, 1.0, 3.0), Back);
    assert_eq!(inside_layers(1.0, 1.0, 3.0), Front);
    assert_eq!(inside_layers(-5.0, 1.0, 3.0), Front);
    // A caster one float thick: the ray is at one of its layers.
    assert_eq!(inside_layers(1.0, 1.0, 1.0), Back);
    // Open medium (no back layer): inside below the front, whatever the depth.
    assert_eq!(inside_layers(1e30, 1.0, 0.0), Inside);
    assert_eq!(inside_layers(0.5, 1.0, -1.0), Front);
    // Lost: no front, crossed layers, non-finite depths.
    assert_eq!(inside_layers(2.0, 0.0, 3.0), Lost);
    assert_eq!(inside_layers(2.0, 4.0, 3.0), Lost);
    assert_eq!(inside_layers(f32::NAN, 1.0, 3.0), Lost);
    assert_eq!(inside_layers(2.0, 1.0, f32::INFINITY), Lost);
    assert_eq!(inside_layers(f32::INFINITY, 1.0, 3.0), Lost);
}

/// R2 points fill the square evenly: every cell of a 16x16 grid gets 4 ± 2 of 1024 points,
/// for any rotation, and points past 2^24 stay distinct.
#[test]
fn r2_points_are_low_discrepancy() {
    for rot in [[0u32, 0], [0x9e37_79b9, 0x7f4a_7c15], [u32::MAX, 1]] {
        let mut cells = [0u32; 256];
        for n in 0..1024u32 {
            let p = r2_point(n, rot);
            assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
            cells[(p.y * 16.0) as usize * 16 + (p.x * 16.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| (2..=6).contains(&c)), "{cells:?}");
    }
    let a = r2_point((1 << 24) + 1, [0, 0]);
    let b = r2_point((1 << 24) + 2, [0, 0]);
    assert_ne!(a, b);
}

#[test]
fn fixed_point_words_are_unbiased_and_clamped() {
    // Far below the resolution: the mean over uniform u is still e · scale.
    let e = 0.001f32;
    let n = 10_000;
    let sum: u64 = (0..n)
        .map(|i| fixed_point_word(e, FIXED_POINT_SCALE, (i as f32 + 0.5) / n as f32).0 as u64)
        .sum();
    let mean = sum as f64 / n as f64;
    assert!((mean - 0.256).abs() < 0.01, "{mean}");
    assert_eq!(fixed_point_word(0.0, 256.0, 0.5), (0, false));
    assert_eq!(fixed_point_word(-1.0, 256.0, 0.5), (0, true));
    assert_eq!(fixed_point_word(f32::NAN, 256.0, 0.5), (0, true));
    assert_eq!(fixed_point_word(f32::INFINITY, 256.0, 0.5), (0, true));
    assert!(fixed_point_word(1e30, 256.0, 0.5).1);
}

#[test]
fn svgf_weight_extremes() {
    assert_eq!(svgf_weight(0.0, 1.0, 1.0, 128.0, 0.0, 1.0), 1.0);
    assert_eq!(svgf_weight(0.0, 1.0, -1.0, 128.0, 0.0, 1.0), 0.0);
    assert_eq!(svgf_weight(f32::NAN, 1.0, 1.0, 128.0, 0.0, 1.0), 0.0);
    let w = svgf_weight(1e30, 0.0, 1.0, 128.0, 1e30, 0.0);
    assert!(w.is_finite() && w >= 0.0);
    assert!(svgf_weight(0.1, 1.0, 0.99, 128.0, 0.0, 1.0) < 1.0);
}

#[test]
fn light_cones() {
    // A sphere of radius 1 at distance 2: half angle 30 degrees, towards it.
    let (axis, half) = cone_around_sphere(Vec3::ZERO, Vec3::new(0.0, -2.0, 0.0), 1.0, 1.5, Vec3::X);
    assert!((axis - Vec3::NEG_Y).length() < 1e-6);
    assert!((half - 30f32.to_radians()).abs() < 1e-5);
    // Inside the sphere, degenerate and non-finite: the cap, never NaN.
    for (c, r) in [
        (Vec3::ZERO, 1.0),
        (Vec3::new(0.1, 0.0, 0.0), 1.0),
        (Vec3::X, f32::NAN),
    ] {
        let (a, h) = cone_around_sphere(Vec3::ZERO, c, r, f32::INFINITY, Vec3::ZERO);
        assert!(a.is_normalized() && h.is_finite() && h <= 80f32.to_radians() + 1e-6);
    }
    assert!(photon_flux_scale(65536.0, 0.0) == 0.0);
    assert_eq!(photon_flux_scale(65536.0, 16384.0), 4.0);
}

fn point(position: Vec3) -> GpuLight {
    GpuLight {
        position,
        kind: 1,
        axis: Vec3::NEG_Y,
        cos_outer: -1.0,
        side_u: Vec3::ZERO,
        cos_inner: -1.0,
        side_v: Vec3::ZERO,
        power: Vec3::splat(1000.0),
    }
}

/// A point light inside its casters' sphere gets six cube faces; outside, one cone. The
/// photon flux of a cube face integrates to the light's power over the face's solid angle.
#[test]
fn rsm_views_cover_the_casters() {
    let casters = (Vec3::ZERO, 1.0);
    assert_eq!(
        rsm_sources(&[point(Vec3::new(0.97, 0.4, 0.0))], casters).len(),
        6
    );
    let far = rsm_sources(&[point(Vec3::new(0.0, 10.0, 0.0))], casters);
    assert_eq!(far.len(), 1);
    assert!(far[0].1.is_none());
    // Cube face: Σ over texels of cos³α / f² = 4π / 6 (the flux per photon times photons).
    let face = rsm_light(&point(Vec3::ZERO), Some(3), casters, (Vec3::ZERO, 5.0), 64);
    let f = face.view.size.z;
    assert!((f - 32.0).abs() < 1e-3, "{f}");
    let mut omega = 0.0f64;
    for y in 0..64 {
        for x in 0..64 {
            let u = (x as f32 + 0.5 - 32.0) / f;
            let v = (y as f32 + 0.5 - 32.0) / f;
            let cos = 1.0 / (1.0 + u * u + v * v).sqrt();
            omega += (cos * cos * cos / (f * f)) as f64;
        }
    }
    assert!(
        (omega - 4.0 * std::f64::consts::PI / 6.0).abs() < 2e-3,
        "{omega}"
    );
    assert_eq!(face.view.eye, Vec4::new(0.0, 0.0, 0.0, face.view.eye.w));
}

/// Which casters make image space follow a further mirror (`TRACE_CASTER_CHAINS`): a ray
/// reflected off a flat or a closed convex mesh (a capped cylinder, a gem) cannot meet it
/// again; off a ring, an open bowl, a torus or a wavy height field it can; a mesh too large
/// to test answers "can".
#[test]
fn caster_shapes_that_reflect_onto_themselves() {
    use bevy_caustics::scene::bvh::MeshGeometry;
    use bevy_caustics::scenes::geometry as g;
    let cases: [(&str, MeshGeometry, bool); 9] = [
        ("quad", g::quad(1.0, 1.0), false),
        ("cuboid", g::cuboid(Vec3::new(1.0, 0.1, 2.0)), false),
        ("uv sphere", g::uv_sphere(0.5, 32, 16), false),
        (
            "brilliant (flat facets, split vertices)",
            g::brilliant(1.0),
            false,
        ),
        ("ring", g::ring(1.0, 0.25, 256), true),
        ("capped cylinder", g::cylinder(1.0, 0.5, 64), false),
        ("torus", g::torus(1.0, 0.25, 32, 16), true),
        (
            "wavy height field",
            g::height_field(
                2.0,
                16,
                |x, z| 0.1 * (3.0 * x).sin() * z.cos(),
                |_, _| glam::Vec2::ZERO,
            ),
            true,
        ),
        (
            "flat height field",
            g::height_field(2.0, 16, |_, _| 0.0, |_, _| glam::Vec2::ZERO),
            false,
        ),
    ];
    for (name, mesh, expected) in cases {
        assert_eq!(mesh.reflects_onto_itself(), expected, "{name}");
    }
    // An open bowl (half a sphere): every vertex behind every facet's plane, but open.
    let mut bowl = g::uv_sphere(0.5, 32, 16);
    let keep: Vec<[u32; 3]> = bowl
        .indices
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&i| bowl.positions[i as usize].y <= 1e-4))
        .collect();
    bowl.indices = keep;
    assert!(bowl.reflects_onto_itself(), "open bowl");
    // Too large to test (2^24 plane tests): answered "can", never a long wait.
    let big = g::uv_sphere(0.5, 512, 256);
    let t0 = std::time::Instant::now();
    assert!(big.reflects_onto_itself(), "large sphere");
    println!("large sphere answered in {:?}", t0.elapsed());
    // Degenerate input: no triangles, a point, NaN positions.
    let empty = MeshGeometry {
        positions: vec![],
        normals: None,
        indices: vec![],
    };
    assert!(!empty.reflects_onto_itself());
    let nan = MeshGeometry {
        positions: vec![Vec3::NAN; 3],
        normals: None,
        indices: vec![[0, 1, 2]],
    };
    assert!(!nan.reflects_onto_itself());
}
