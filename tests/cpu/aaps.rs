//! The AAPS core (seed 004): equal-area map, quadtree, density update, splats.

use super::*;
use glam::UVec2;

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
    let expect: u32 = density.iter().map(|d| photon_count(*d)).sum();
    assert_eq!(tree.total(), expect);
    let mut seen = std::collections::HashSet::new();
    let mut per_texel = vec![0u32; (size * size) as usize];
    for task in 0..tree.total() {
        let (texel, sample, count) = tree.walk(task).unwrap();
        assert!(sample < count);
        assert!(seen.insert((texel, sample)), "task {task} repeats a photon");
        per_texel[(texel.y * size + texel.x) as usize] += 1;
        let uv = leaf_sample_uv(texel, sample, size);
        assert!(
            (uv * size as f32).floor() == texel.as_vec2(),
            "sample outside its texel"
        );
    }
    for (i, d) in density.iter().enumerate() {
        assert_eq!(per_texel[i], photon_count(*d));
    }
    assert!(tree.walk(tree.total()).is_none());
    assert!(SumQuadtree::build(&density[..100], 10).is_none());
    assert_eq!(floor_square(4.0), 4);
    assert_eq!(floor_square(8.9), 4);
    assert_eq!(floor_square(9.0), 9);
    assert_eq!(floor_square(f32::NAN), 0);
    assert_eq!(floor_square(-1.0), 0);
    assert_eq!(photon_count(8.9), 8);
    assert_eq!(photon_count(0.5), 0);
    assert_eq!(photon_count(f32::NAN), 0);
    assert_eq!(photon_count(f32::INFINITY), 0);
    assert_eq!(photon_count(-3.0), 0);
    assert_eq!(photon_count(1e30), 16_777_216);
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
        budget_floor_share: 2.0,
        point_splat_area: f32::NAN,
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
            "splat_capacity",
            "budget_floor_share",
            "point_splat_area"
        ]
    );
    assert_eq!(bad.atlas_resolution, 128);
    assert_eq!(bad.target_area, 19.0);
    assert_eq!(bad.temporal_weight, 1.0);
    assert_eq!(bad.min_density, 1.0);
    assert_eq!(bad.budget_floor_share, 1.0);
    assert_eq!(bad.point_splat_area, 1.0);
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

/// The leaf samples (R2 set, rotated per texel): inside their texel for any count, the same on
/// every call, spread evenly (every cell of a 4 x 4 grid holds 2 to 6 of 64 samples; a white-noise
/// set fails this), and not the same lattice in neighbouring texels (the moiré of a grid).
#[test]
fn leaf_samples_are_low_discrepancy_and_rotated_per_texel() {
    let size = 64u32;
    for count in [1u32, 2, 3, 7, 16, 64, 1000, 1 << 20] {
        for texel in [UVec2::ZERO, UVec2::new(63, 0), UVec2::new(17, 40)] {
            for sample in [0, count / 2, count - 1] {
                let uv = leaf_sample_uv(texel, sample, size);
                assert!(
                    (uv * size as f32).floor() == texel.as_vec2(),
                    "count {count}, sample {sample} outside texel {texel}: {uv}"
                );
                assert_eq!(uv, leaf_sample_uv(texel, sample, size));
            }
        }
    }
    let local =
        |texel: UVec2, i: u32| leaf_sample_uv(texel, i, size) * size as f32 - texel.as_vec2();
    for texel in [UVec2::ZERO, UVec2::new(5, 9), UVec2::new(63, 63)] {
        let mut cells = [0u32; 16];
        let mut mean = Vec2::ZERO;
        for i in 0..64 {
            let p = local(texel, i);
            mean += p / 64.0;
            cells[((p.y * 4.0) as usize).min(3) * 4 + ((p.x * 4.0) as usize).min(3)] += 1;
        }
        assert!(
            cells.iter().all(|c| (2..=6).contains(c)),
            "{texel}: {cells:?}"
        );
        assert!(
            (mean - Vec2::splat(0.5)).length() < 0.05,
            "{texel}: mean {mean}"
        );
    }
    // Neighbouring texels: different rotations (a grid would repeat the same offsets).
    let (a, b) = (local(UVec2::new(10, 10), 0), local(UVec2::new(11, 10), 0));
    assert!((a - b).length() > 1e-3, "{a} {b}");
    let mut offsets: Vec<u32> = (0..256)
        .map(|x| (local(UVec2::new(x % 64, x / 64), 0).x * 64.0) as u32)
        .collect();
    offsets.sort_unstable();
    offsets.dedup();
    assert!(
        offsets.len() > 40,
        "first samples' x fall in {} of 64 bins",
        offsets.len()
    );
}

/// The frame rotation (issue 28): a texel's samples stay inside it and evenly spread for any
/// frame, and one sample's position over 256 frames covers its texel uniformly (each cell of
/// a 4 x 4 grid holds 8 to 24 of 256; the same sample every frame would fill one cell), so the
/// temporal stage's mean gathers independent photons.
#[test]
fn frame_rotation_moves_every_sample_over_its_texel() {
    let size = 64u32;
    let texel = UVec2::new(17, 40);
    let local = |i: u32, frame: u32| {
        leaf_sample_uv_rotated(texel, i, size, frame_rotation(frame)) * size as f32
            - texel.as_vec2()
    };
    for frame in [0u32, 1, 2, 1000, u32::MAX] {
        let mut cells = [0u32; 16];
        for i in 0..64 {
            let p = local(i, frame);
            assert!(p.min_element() >= 0.0 && p.max_element() < 1.0, "{p}");
            cells[((p.y * 4.0) as usize).min(3) * 4 + ((p.x * 4.0) as usize).min(3)] += 1;
        }
        assert!(
            cells.iter().all(|c| (2..=6).contains(c)),
            "frame {frame}: {cells:?}"
        );
    }
    let mut cells = [0u32; 16];
    for frame in 0..256 {
        let p = local(0, frame);
        cells[((p.y * 4.0) as usize).min(3) * 4 + ((p.x * 4.0) as usize).min(3)] += 1;
    }
    assert!(cells.iter().all(|c| (8..=24).contains(c)), "{cells:?}");
    assert_eq!(
        leaf_sample_uv(texel, 5, size),
        leaf_sample_uv_rotated(texel, 5, size, [0, 0])
    );
}

/// The budget: a floor of `share` over the contributing texels, the rest by D' scaled down; the
/// texels' photons never exceed the budget once it covers the idle texels' minimum, the floor
/// grows with the budget, share 0 is the thesis's scaling, and bad input stays finite.
#[test]
fn budget_split_spends_the_budget() {
    let mut rng = Pcg32::new(3, 9);
    let n = 4096usize;
    // A quarter contributes; D' from 4 to 400.
    let texels: Vec<(f32, bool)> = (0..n)
        .map(|i| (4.0 + rng.next_f32() * 396.0, i % 4 == 0))
        .collect();
    let sum: f32 = texels.iter().map(|t| t.0).sum();
    let contributing = texels.iter().filter(|t| t.1).count() as u32;
    let idle = n as u32 - contributing;
    let mut last_floor = 0.0;
    for budget in [1u32 << 16, 1 << 18, 1 << 20, 1 << 22] {
        for share in [0.0f32, 0.5, 1.0] {
            let (floor, scale) = budget_split(budget as f32, share, sum, contributing, idle, 4.0);
            assert!(floor.is_finite() && scale.is_finite() && (0.0..=1.0).contains(&scale));
            let photons: u64 = texels
                .iter()
                .map(|&(d, c)| photon_count(budget_density(d, c, floor, scale, 4.0, 0.0)) as u64)
                .sum();
            assert!(
                photons <= budget as u64,
                "budget {budget}, share {share}: {photons}"
            );
            if share == 0.5 {
                assert!(floor > last_floor, "the floor grows with the budget");
                last_floor = floor;
                // Every contributing texel gets at least the floor.
                for &(d, c) in &texels {
                    if c {
                        assert!(budget_density(d, c, floor, scale, 4.0, 0.0) >= floor);
                    }
                }
            }
            if share == 0.0 {
                assert_eq!(floor, 0.0);
            }
            if budget == 1 << 22 && share == 0.0 {
                // Under budget the thesis's densities pass unchanged.
                assert_eq!(scale, 1.0);
            }
        }
    }
    // Idle texels' minimum alone above the budget: no floor, everything at the minimum.
    let (floor, scale) = budget_split(1000.0, 0.5, sum, contributing, idle, 4.0);
    assert_eq!((floor, scale), (0.0, 0.0));
    assert_eq!(budget_density(300.0, true, floor, scale, 4.0, 0.0), 4.0);
    // Guards.
    let (f, s) = budget_split(f32::NAN, f32::INFINITY, f32::NAN, 0, u32::MAX, f32::NAN);
    assert!(f.is_finite() && s.is_finite());
    assert!(budget_density(f32::NAN, true, 1e30, f32::INFINITY, 4.0, 0.0).is_finite());
    assert_eq!(budget_density(-5.0, false, 0.0, 1.0, 4.0, 0.0), 4.0);
    assert_eq!(budget_density(500.0, true, 1000.0, 1.0, 4.0, 300.0), 300.0);
}
