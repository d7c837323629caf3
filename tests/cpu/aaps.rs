//! The AAPS core (seed 004): equal-area map, quadtree, density update, splats.

use super::*;

#[test]
fn equal_area_mapping_round_trips_and_is_equal_area() {
    let mut rng = Pcg32::new(23, 1);
    for _ in 0..20_000 {
        let d = uniform_sphere(rng.next_vec2());
        let back = equal_area_square_to_sphere(equal_area_sphere_to_square(d));
        assert!((back - d).length() < 2e-4, "{d} -> {back}");
        let uv = rng.next_vec2();
        let again = equal_area_sphere_to_square(equal_area_square_to_sphere(uv));
        assert!((again - uv).length() < 2e-4, "{uv} -> {again}");
    }
    // Equal area: uniform directions fall evenly into the cells of the square.
    let cells = 8usize;
    let n = 2_000_000usize;
    let mut hist = vec![0u32; cells * cells];
    for _ in 0..n {
        let uv = equal_area_sphere_to_square(uniform_sphere(rng.next_vec2()));
        let (x, y) = (
            ((uv.x * cells as f32) as usize).min(cells - 1),
            ((uv.y * cells as f32) as usize).min(cells - 1),
        );
        hist[y * cells + x] += 1;
    }
    let mean = n as f32 / (cells * cells) as f32;
    let worst = hist
        .iter()
        .map(|&h| (h as f32 / mean - 1.0).abs())
        .fold(0.0, f32::max);
    println!(
        "equal-area map: worst cell deviates {:.2} % from the mean",
        worst * 100.0
    );
    assert!(worst < 0.03);
    for uv in [
        Vec2::ZERO,
        Vec2::ONE,
        Vec2::new(0.5, 0.5),
        Vec2::new(-3.0, 9.0),
        Vec2::splat(f32::NAN),
    ] {
        assert!(equal_area_square_to_sphere(uv).is_finite());
    }
}

#[test]
fn quadtree_walk_covers_every_photon_once() {
    let size = 16u32;
    let mut rng = Pcg32::new(5, 5);
    let density: Vec<f32> = (0..size * size).map(|_| rng.next_f32() * 40.0).collect();
    let tree = SumQuadtree::build(&density, size).unwrap();
    let expect: u32 = density.iter().map(|d| floor_square(*d)).sum();
    assert_eq!(tree.total(), expect);
    let mut seen = std::collections::HashSet::new();
    let mut per_texel = vec![0u32; (size * size) as usize];
    for task in 0..tree.total() {
        let (texel, sample, count) = tree.walk(task).unwrap();
        assert!(sample < count);
        assert!(seen.insert((texel, sample)), "task {task} repeats a photon");
        per_texel[(texel.y * size + texel.x) as usize] += 1;
        let uv = leaf_sample_uv(texel, sample, count, size);
        assert!(
            (uv * size as f32).floor() == texel.as_vec2(),
            "sample outside its texel"
        );
    }
    for (i, d) in density.iter().enumerate() {
        assert_eq!(per_texel[i], floor_square(*d));
    }
    assert!(tree.walk(tree.total()).is_none());
    assert!(SumQuadtree::build(&density[..100], 10).is_none());
    assert_eq!(floor_square(4.0), 4);
    assert_eq!(floor_square(8.9), 4);
    assert_eq!(floor_square(9.0), 9);
    assert_eq!(floor_square(f32::NAN), 0);
    assert_eq!(floor_square(-1.0), 0);
}

#[test]
fn density_update_and_energy() {
    // D' = D A / A_t + v g.
    assert_eq!(suggested_density(16.0, 2.0, 4.0, 3.0, 2.0), 14.0);
    assert!(suggested_density(16.0, 2.0, 0.0, 0.0, 0.0).is_finite());
    assert!(suggested_density(f32::NAN, f32::INFINITY, 1.0, 1.0, 1.0).is_finite());
    // Blend, at least 4, a square.
    let prev = [
        (1.0, 16.0),
        (1.0, 16.0),
        (1.0, 16.0),
        (1.0, 16.0),
        (1.0, 16.0),
    ];
    assert_eq!(blend_density(36.0, &prev, 0.5, 4.0, f32::INFINITY), 25.0);
    assert_eq!(blend_density(0.0, &prev, 1.0, 4.0, f32::INFINITY), 4.0);
    assert_eq!(blend_density(1e9, &[], 1.0, 4.0, 100.0), 100.0);
    // Energy: every photon of every partition sums back to the light's power.
    let power = Vec3::new(1000.0, 500.0, 10.0);
    let (parts, photons) = (64u32, 9u32);
    let e = photon_energy(power, parts, photons) * (parts * photons) as f32;
    assert!((e - power).length() < 1e-2);
    assert_eq!(photon_energy(power, 0, 9), Vec3::ZERO);
}

#[test]
fn differentials_and_splats() {
    let (q, ok) = transfer_to_plane(
        Vec3::new(0.1, 5.0, 0.0),
        Vec3::new(0.0, -1.0, 0.1).normalize(),
        Vec3::ZERO,
        Vec3::Y,
    );
    assert!(ok && q.y.abs() < 1e-5);
    let (_, ok) = transfer_to_plane(Vec3::Y, Vec3::X, Vec3::ZERO, Vec3::Y);
    assert!(!ok, "parallel ray must be reported");
    // Orthogonal offsets 2 and 0.5: semi-axes 2 and 0.5, area π.
    let (s, clamped) =
        splat_from_differentials(Vec3::X * 2.0, Vec3::Z * 0.5, Vec3::Y, 100.0, 0.0, 1e9);
    assert!(!clamped);
    assert!((s.a.length() - 2.0).abs() < 1e-4 && (s.b.length() - 0.5).abs() < 1e-4);
    assert!((s.area() - std::f32::consts::PI).abs() < 1e-3);
    assert!(s.a.dot(Vec3::Y).abs() < 1e-5 && s.a.dot(s.b).abs() < 1e-4);
    // Anisotropy clamp: 4:1 limited to 2:1 by growing the minor axis.
    let (s, clamped) =
        splat_from_differentials(Vec3::X * 2.0, Vec3::Z * 0.5, Vec3::Y, 2.0, 0.0, 1e9);
    assert!(clamped && (s.anisotropy() - 2.0).abs() < 1e-3);
    // Zero, huge and NaN differentials stay finite and inside the radius limits.
    for (du, dv) in [
        (Vec3::ZERO, Vec3::ZERO),
        (Vec3::X * 1e30, Vec3::Z),
        (Vec3::splat(f32::NAN), Vec3::X),
    ] {
        let (s, _) = splat_from_differentials(du, dv, Vec3::Y, 8.0, 1e-4, 10.0);
        assert!(
            s.a.is_finite() && s.b.is_finite() && s.area().is_finite(),
            "{du} {dv}"
        );
        assert!(s.a.length() <= 10.0 + 1e-3 && s.b.length() >= 1e-4 * 0.999);
    }
}

/// `AapsSettings` out of range: every bad field is clamped and reported once by name.
#[test]
fn aaps_settings_are_sanitized() {
    use bevy_caustics::AapsSettings;
    use bevy_caustics::components::validate::sanitize_aaps;
    let mut ok = AapsSettings::default();
    assert!(sanitize_aaps(&mut ok, &Default::default()).is_empty());
    let mut bad = AapsSettings {
        atlas_resolution: 100,
        target_area: f32::NAN,
        temporal_weight: 3.0,
        min_density: 0.0,
        splat_scale: -1.0,
        max_anisotropy: 0.5,
        max_bounces: 0,
        splat_capacity: 0,
        ..Default::default()
    };
    let fixes = sanitize_aaps(&mut bad, &Default::default());
    let fields: Vec<&str> = fixes.iter().map(|f| f.0).collect();
    assert_eq!(
        fields,
        [
            "atlas_resolution",
            "target_area",
            "temporal_weight",
            "min_density",
            "splat_scale",
            "max_anisotropy",
            "max_bounces",
            "splat_capacity"
        ]
    );
    assert_eq!(bad.atlas_resolution, 128);
    assert_eq!(bad.target_area, 19.0);
    assert_eq!(bad.temporal_weight, 1.0);
    assert_eq!(bad.min_density, 1.0);
    assert!(
        sanitize_aaps(&mut bad, &Default::default()).is_empty(),
        "a clamped value is valid"
    );
}

/// The splat capacity fits the device's binding with the guard region after it (the guard
/// catches writes past the capacity, `aaps_splat_buffer_overflow_is_counted`).
#[test]
fn splat_capacity_fits_the_binding_with_its_guard() {
    use bevy::render::render_resource::WgpuLimits;
    use bevy_caustics::render::aaps::view::{SPLAT_GUARD_SPLATS, splat_capacity};
    let limits = WgpuLimits::default();
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let default = bevy_caustics::AapsSettings::default().splat_capacity;
    let cap = splat_capacity(default, &limits);
    assert!((cap as u64 + SPLAT_GUARD_SPLATS) * 64 <= max);
    assert_eq!(cap as u64, max / 64 - SPLAT_GUARD_SPLATS);
    assert_eq!(splat_capacity(64, &limits), 64);
    assert_eq!(splat_capacity(0, &limits), 1);
    assert_eq!(splat_capacity(u32::MAX, &limits), cap);
}
