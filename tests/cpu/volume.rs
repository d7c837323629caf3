//! Caustics volumes (seed 000) in plain Rust: the media-interface rule, `CausticsVolume::fit`,
//! seeding, the frame with its slab probes and projectors, the splat footprint, LOD, glTF extras
//! and validation.

use super::*;

/// Seed 000 section 3.3, case by case: the medium-interface rule of caustics volumes.
#[test]
fn volume_media_interface_rules() {
    use MediaInterface::*;
    let down = Vec3::NEG_Y;
    let up_normal = Vec3::Y;
    // "if P_med is false, and the surface normal at the interface lies in the opposite
    // hemisphere as the photon direction ... entering the denser medium".
    assert_eq!(media_interface(false, down, up_normal, true), Enter);
    // "if P_med is true ... if the surface normal lies in the same hemisphere as the photon
    // direction, then we assume the photon is exiting the denser medium".
    assert_eq!(media_interface(true, down, -up_normal, true), Exit);
    // "if the surface normal tests fail, the interface is ignored and the photon is assumed
    // to remain in the original medium": in air meeting a back face, inside meeting a front face.
    assert_eq!(media_interface(false, down, -up_normal, true), Ignore);
    assert_eq!(media_interface(true, down, up_normal, true), Ignore);
    // "The photon might be passing behind the object": outside the G_near..G_far depths.
    assert_eq!(media_interface(false, down, up_normal, false), Ignore);
    assert_eq!(media_interface(true, down, -up_normal, false), Ignore);
    // Extremes: a photon exactly in the surface plane, a zero normal, NaN.
    assert_eq!(media_interface(false, Vec3::X, up_normal, true), Ignore);
    assert_eq!(media_interface(true, Vec3::X, up_normal, true), Ignore);
    assert_eq!(media_interface(false, down, Vec3::ZERO, true), Ignore);
    assert_eq!(media_interface(false, Vec3::NAN, up_normal, true), Ignore);
    // Grazing but not parallel still decides by the sign.
    let graze = Vec3::new(1.0, -1e-6, 0.0).normalize();
    assert_eq!(media_interface(false, graze, up_normal, true), Enter);
}

/// `CausticsVolume::fit`: the casters' box is inside the volume, the entry face looks at the
/// light, and degenerate inputs still give a valid volume.
#[test]
fn volume_fit_holds_the_casters_and_faces_the_light() {
    use bevy_caustics::{CausticsVolume, VolumeFace};
    let cases = [
        (
            (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 0.3, 0.5)),
            Vec3::NEG_Y,
        ),
        (
            (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 0.3, 0.5)),
            Vec3::new(1.0, -1.0, 0.2),
        ),
        ((Vec3::splat(1e4), Vec3::splat(1e4 + 1e-3)), Vec3::Y),
        ((Vec3::ZERO, Vec3::ZERO), Vec3::ZERO),
        (
            (Vec3::splat(f32::NAN), Vec3::ONE),
            Vec3::new(0.0, f32::NAN, 0.0),
        ),
    ];
    for ((lo, hi), dir) in cases {
        let (v, t) = CausticsVolume::fit((lo, hi), dir, 0.1);
        assert!(v.size.is_finite() && v.size.min_element() >= 1e-3, "{v:?}");
        assert!(t.translation.is_finite() && t.rotation.is_finite());
        assert_eq!(v.entry, VolumeFace::PosY);
        assert_eq!(v.exit.len(), 6, "every face but none culls: {:?}", v.exit);
        assert!(v.size.min_element() >= 0.25 * v.size.max_element() * 0.999);
        let travel = dir.try_normalize().unwrap_or(Vec3::NEG_Y);
        let entry_world = t.rotation * VolumeFace::PosY.normal();
        assert!(
            entry_world.dot(travel) < -0.9999,
            "entry {entry_world} light {travel}"
        );
        if lo.is_finite() {
            for i in 0..8 {
                let c = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let local = t.rotation.inverse() * (c - t.translation);
                assert!(
                    local
                        .abs()
                        .cmple(v.size * 0.5 + 1e-3 * (1.0 + c.abs().max_element()))
                        .all(),
                    "corner {c} outside {v:?}"
                );
            }
        }
    }
}

/// `CausticsVolume::fit_point`: a bulb far away gets the box facing it; one beside or just over
/// a wide caster (the `ring` scene's) gets the casters' box with the face it stands over as
/// entry; one inside the casters' box gets none. Whatever it returns has the light over its
/// entry face and holds the casters, so seeding gives the light's photons flux.
#[test]
fn volume_fit_point_keeps_the_light_over_the_entry() {
    use bevy_caustics::CausticsVolume;
    use bevy_caustics::scene::TraceLight;
    use bevy_caustics::volume::{lights_shut_out, seed_photons};
    let ring = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.25, 1.0));
    let cases = [
        (ring, Vec3::new(0.0, 20.0, 3.0), true),
        (ring, Vec3::new(0.97, 0.4, 0.0), true),
        (ring, Vec3::new(3.0, 0.1, 0.0), true),
        (ring, Vec3::new(0.5, 0.1, 0.0), false),
        (
            (Vec3::splat(1e4), Vec3::splat(1e4 + 1e-3)),
            Vec3::ZERO,
            true,
        ),
    ];
    for ((lo, hi), light, fits) in cases {
        let fit = CausticsVolume::fit_point((lo, hi), light, 0.1);
        assert_eq!(fit.is_some(), fits, "light {light}: {fit:?}");
        let Some((v, t)) = fit else { continue };
        assert!(v.light_over_entry(&t, light), "light {light}: {v:?} {t:?}");
        let inv = t.compute_affine().inverse();
        for c in [
            lo,
            hi,
            Vec3::new(lo.x, hi.y, lo.z),
            Vec3::new(hi.x, lo.y, hi.z),
        ] {
            let local = inv.transform_point3(c);
            let slack = 1e-3 * (1.0 + c.abs().max_element());
            assert!(
                local.abs().cmple(v.size * 0.5 + slack).all(),
                "{c} outside {v:?}"
            );
        }
        let bulb = TraceLight::Point {
            position: light,
            flux: Vec3::splat(1000.0),
        };
        let photons = seed_photons(&t.compute_affine(), v.size, v.entry, &[bulb], 1024);
        assert!(
            lights_shut_out(&photons, &[bulb]).is_empty(),
            "light {light}"
        );
    }
    // The box fitted facing away from the ring's bulb, which `fit` gives, shuts it out, and
    // that is what the volume's run-time warning reports; a dark bulb is not reported.
    let (v, t) = CausticsVolume::fit(ring, Vec3::NEG_X, 0.1);
    let (bulb, dark) = [1000.0, 0.0]
        .map(|f| TraceLight::Point {
            position: Vec3::new(0.97, 0.4, 0.0),
            flux: Vec3::splat(f),
        })
        .into();
    let photons = seed_photons(&t.compute_affine(), v.size, v.entry, &[bulb, dark], 1024);
    assert_eq!(lights_shut_out(&photons, &[bulb, dark]), vec![0]);
}

/// Seed 000 §3.4: photons spread evenly over the entry face carry the light's irradiance on
/// it: the total is E⊥ cos θ A for a directional light, and Φ Ω / 4π for a point light (Ω the
/// face's solid angle, closed form for a rectangle seen on its axis); the pool is split
/// equally between lights; light from behind the face gives nothing.
#[test]
fn volume_photons_carry_the_entry_face_irradiance() {
    use bevy_caustics::VolumeFace;
    use bevy_caustics::scene::TraceLight;
    use bevy_caustics::volume::seed_photons;
    use glam::{Affine3A, Quat};
    let sum =
        |v: &[bevy_caustics::volume::VolumePhoton]| v.iter().map(|p| p.flux.x as f64).sum::<f64>();
    let id = Affine3A::IDENTITY;
    let e = 1000.0;
    for deg in [0.0f32, 30.0, 89.0] {
        let a = deg.to_radians();
        let sun = TraceLight::Directional {
            direction: Vec3::new(a.sin(), -a.cos(), 0.0),
            illuminance: Vec3::splat(e),
        };
        let p = seed_photons(
            &id,
            Vec3::new(1.0, 0.5, 2.0),
            VolumeFace::PosY,
            &[sun],
            20_000,
        );
        let expect = e as f64 * (a.cos() as f64) * 2.0;
        assert!(
            (sum(&p) / expect - 1.0).abs() < 1e-4,
            "{deg}: {} vs {expect}",
            sum(&p)
        );
        assert!(
            p.iter()
                .all(|q| (q.position.y - 0.25).abs() < 1e-6 && !q.terminated)
        );
    }
    // From below: nothing enters through the top face.
    let under = TraceLight::Directional {
        direction: Vec3::Y,
        illuminance: Vec3::splat(e),
    };
    let p = seed_photons(&id, Vec3::ONE, VolumeFace::PosY, &[under], 1000);
    assert!(p.iter().all(|q| q.terminated && q.flux == Vec3::ZERO));
    // A point light on the axis of a 2 x 2 face, 0.5 m above it.
    let flux = 4000.0f32;
    let bulb = TraceLight::Point {
        position: Vec3::new(0.0, 1.0, 0.0),
        flux: Vec3::splat(flux),
    };
    let p = seed_photons(
        &id,
        Vec3::new(2.0, 1.0, 2.0),
        VolumeFace::PosY,
        &[bulb],
        250_000,
    );
    let (a, b, h) = (1.0f64, 1.0f64, 0.5f64);
    let omega = 4.0 * (a * b / ((a * a + h * h) * (b * b + h * h)).sqrt()).asin();
    let expect = flux as f64 * omega / (4.0 * std::f64::consts::PI);
    let err = sum(&p) / expect - 1.0;
    println!(
        "point light through a face: {} lm vs {expect:.2} lm ({:+.4} %)",
        sum(&p),
        err * 100.0
    );
    assert!(err.abs() < 1e-3);
    // Two lights share the pool equally; a scaled, rotated volume scales the area.
    let sun = TraceLight::Directional {
        direction: Vec3::NEG_Y,
        illuminance: Vec3::splat(e),
    };
    let two = seed_photons(&id, Vec3::ONE, VolumeFace::PosY, &[sun, bulb], 10_000);
    // Each light gets the same grid, as close to half the pool as a grid allows.
    assert!(
        two.len().is_multiple_of(2) && two.len() <= 10_000 && two.len() >= 9_800,
        "{}",
        two.len()
    );
    let half = two.len() / 2;
    assert!(two[..half].iter().all(|q| q.direction == Vec3::NEG_Y));
    assert!(two[half..].iter().all(|q| q.direction != Vec3::NEG_Y));
    let m = Affine3A::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_rotation_y(0.7),
        Vec3::new(5.0, 1.0, -3.0),
    );
    let p = seed_photons(&m, Vec3::ONE, VolumeFace::PosY, &[sun], 10_000);
    assert!((sum(&p) / (e as f64 * 4.0) - 1.0).abs() < 1e-4);
    // Guards: no photons, no lights, a degenerate box, a NaN transform.
    assert!(seed_photons(&id, Vec3::ONE, VolumeFace::PosY, &[sun], 0).is_empty());
    assert!(seed_photons(&id, Vec3::ONE, VolumeFace::PosY, &[], 100).is_empty());
    assert!(seed_photons(&id, Vec3::ZERO, VolumeFace::PosY, &[sun], 100).is_empty());
    let nan = Affine3A::from_translation(Vec3::NAN);
    assert!(
        seed_photons(&nan, Vec3::ONE, VolumeFace::PosY, &[sun], 100)
            .iter()
            .all(|q| q.flux.is_finite())
    );
}

fn frames() -> Vec<(glam::Affine3A, Vec3, bevy_caustics::VolumeFace, u32)> {
    use bevy_caustics::VolumeFace::*;
    use glam::{Affine3A, Quat};
    let mut v = Vec::new();
    for (i, face) in [PosX, NegX, PosY, NegY, PosZ, NegZ].into_iter().enumerate() {
        let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.3 * i as f32, -0.7, 1.1 * i as f32);
        let scale = Vec3::new(1.0, 2.0, 0.5) * (1.0 + i as f32);
        let t = Vec3::new(1.0, -2.0, 3.0) * i as f32;
        v.push((
            Affine3A::from_scale_rotation_translation(scale, rot, t),
            Vec3::new(0.4, 1.2, 0.8),
            face,
            1 + i as u32,
        ));
    }
    // Extreme scales.
    v.push((
        Affine3A::from_translation(Vec3::splat(1e4)),
        Vec3::splat(1e-3),
        PosY,
        3,
    ));
    v.push((Affine3A::IDENTITY, Vec3::splat(1e4), NegZ, 16));
    v
}

/// The slab probes (seed 000 section 3.2): slab k's orthographic clip space maps its entry
/// plane to z = 0, its exit plane to z = 1, the lateral faces to x, y = ±1; the depth plane
/// gives the slab depth w; local/world round trip.
#[test]
fn volume_frame_slab_probes() {
    use bevy_caustics::volume::VolumeFrame;
    for (affine, size, entry, slabs) in frames() {
        let f = VolumeFrame::new(&affine, size, entry, slabs);
        let tol = 1e-4 * (1.0 + f.half.max_element() + f.centre.abs().max_element());
        // f32 resolves world points to ulp(|centre|): clip coordinates are only that precise
        // relative to the box (a 1 mm box 10 km away: a factor of 2).
        let clip_tol =
            1e-3 + 8.0 * f32::EPSILON * f.centre.abs().max_element() / f.half.min_element();
        let t = f.thickness();
        for k in 0..slabs {
            let m = f.slab_clip_from_world(k);
            for (a, b, w) in [
                (0.0, 0.0, t * k as f32),
                (1.0, -1.0, t * (k + 1) as f32),
                (-1.0, 1.0, t * (k as f32 + 0.5)),
            ] {
                let mut q = Vec3::ZERO;
                q[f.j] = a * f.half[f.j];
                q[f.k] = b * f.half[f.k];
                q[f.e] = f.s * (f.half[f.e] - w);
                let p = f.world(q);
                assert!((f.local(p) - q).abs().max_element() <= tol, "{q} {p}");
                assert!((f.depth(q) - w).abs() <= tol);
                let plane = f.depth_plane();
                assert!((plane.truncate().dot(p) + plane.w - w).abs() <= tol * 10.0);
                let c = m * p.extend(1.0);
                let z = (w - t * k as f32) / t;
                let want = glam::Vec3::new(a, b, z);
                assert!(
                    (c.truncate() / c.w - want).abs().max_element() < clip_tol,
                    "slab {k}: {c} vs {want}"
                );
            }
        }
    }
}

/// The projectors (section 3.4): every point outside the box lies in the frustum of the face
/// of largest |q_i| / h_i, in front of its near plane; points on the face are on the near
/// plane; the stored depth is |q_i|.
#[test]
fn volume_frame_projectors_partition_the_outside() {
    use bevy_caustics::volume::VolumeFrame;
    let mut rng = Pcg32::new(7, 1);
    for (affine, size, entry, slabs) in frames() {
        let f = VolumeFrame::new(&affine, size, entry, slabs);
        if 8.0 * f32::EPSILON * f.centre.abs().max_element() > 1e-3 * f.half.min_element() {
            // Beyond f32's resolution relative to the box (covered by the slab test).
            continue;
        }
        let far = 50.0 * f.half.max_element();
        for _ in 0..500 {
            let dir = Vec3::new(
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0 - 1.0,
            );
            let r = dir / f.half;
            let i = if r.x.abs() >= r.y.abs() && r.x.abs() >= r.z.abs() {
                0
            } else if r.y.abs() >= r.z.abs() {
                1
            } else {
                2
            };
            let code = 2 * i as u32 + (r[i] < 0.0) as u32;
            // Scale so the point is outside the box, between 1 and 10 times its face distance.
            let s = (1.0 + 9.0 * rng.next_f32()) / (r[i].abs().max(1e-6));
            let q = dir * s;
            let p = f.world(q);
            let (m, plane) = f.projector(code, far);
            let c = m * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            assert!(c.w > 0.0, "behind the projector");
            assert!(
                ndc.x.abs() <= 1.0 + 1e-3 && ndc.y.abs() <= 1.0 + 1e-3,
                "face {code}: {ndc}"
            );
            assert!(ndc.z >= -1e-3 && ndc.z <= 1.0 + 1e-3, "face {code}: {ndc}");
            let depth = plane.truncate().dot(p) + plane.w;
            assert!((depth - q[i].abs()).abs() <= 1e-3 * (1.0 + q[i].abs()));
        }
        // A point on face +e's centre is on that projector's near plane.
        let mut q = Vec3::ZERO;
        q[f.e] = f.half[f.e];
        let code = 2 * f.e as u32;
        let c = f.projector(code, far).0 * f.world(q).extend(1.0);
        assert!((c.z / c.w).abs() < 1e-3, "{c}");
    }
}

/// Which slabs a box touches (differential updates): inside one slab, across a boundary,
/// outside the volume, non-finite.
#[test]
fn volume_frame_slabs_touched() {
    use bevy_caustics::VolumeFace;
    use bevy_caustics::volume::VolumeFrame;
    let f = VolumeFrame::new(
        &glam::Affine3A::from_translation(Vec3::new(0.0, 1.0, 0.0)),
        Vec3::new(2.0, 3.0, 2.0),
        VolumeFace::PosY,
        3,
    );
    // Slabs of 1 m from y = 2.5 down: [2.5, 1.5], [1.5, 0.5], [0.5, -0.5].
    let b = |lo: f32, hi: f32| (Vec3::new(-0.1, lo, -0.1), Vec3::new(0.1, hi, 0.1));
    let t = |(lo, hi): (Vec3, Vec3)| f.slabs_touched(lo, hi);
    assert_eq!(t(b(1.7, 2.2)), Some((0, 0)));
    assert_eq!(t(b(-0.4, 0.2)), Some((2, 2)));
    assert_eq!(t(b(0.9, 1.6)), Some((0, 1)));
    assert_eq!(t(b(-3.0, 9.0)), Some((0, 2)));
    assert_eq!(t(b(3.0, 4.0)), None);
    assert_eq!(t((Vec3::NAN, Vec3::ONE)), None);
    assert_eq!(
        t((Vec3::new(5.0, 1.0, 0.0), Vec3::new(6.0, 1.2, 0.1))),
        None
    );
}

/// Section 3.5's slab LOD: full count up to the distance, halved per doubling beyond, at
/// least one slab; off when the distance is 0 or inputs are not finite.
#[test]
fn volume_photon_capacity() {
    use bevy_caustics::render::volume::view::{MAX_PHOTONS_PER_DISPATCH, photon_capacity};
    let big = u64::MAX;
    assert_eq!(photon_capacity(20_000, 3, big), 20_000);
    // One dispatch of 65 535 workgroups of 64 bounds the budget (the validator allows 2^24).
    assert_eq!(photon_capacity(1 << 24, 1, big), MAX_PHOTONS_PER_DISPATCH);
    assert_eq!(MAX_PHOTONS_PER_DISPATCH, 4_194_240);
    // 128 MiB bindings (wgpu's default limit), 64 bytes per photon per slab.
    assert_eq!(photon_capacity(1 << 24, 1, 128 << 20), 2_097_152);
    assert_eq!(photon_capacity(1 << 24, 16, 128 << 20), 131_072);
    // Zero or negative budgets still get one slot; zero slabs count as one.
    assert_eq!(photon_capacity(0, 3, big), 1);
    assert_eq!(photon_capacity(-5, 3, big), 1);
    assert_eq!(photon_capacity(100, 0, big), 100);
    assert_eq!(photon_capacity(100, 3, 0), 1);
}

#[test]
fn volume_lod_slabs() {
    use bevy_caustics::render::volume::view::lod_slabs;
    assert_eq!(lod_slabs(8, 8.0, 1.0, 7.9), 8);
    assert_eq!(lod_slabs(8, 8.0, 1.0, 8.1), 4);
    assert_eq!(lod_slabs(8, 8.0, 1.0, 16.1), 2);
    assert_eq!(lod_slabs(8, 8.0, 1.0, 32.1), 1);
    assert_eq!(lod_slabs(8, 8.0, 1.0, 1e30), 1);
    assert_eq!(lod_slabs(8, 0.0, 1.0, 1e30), 8);
    assert_eq!(lod_slabs(8, 8.0, f32::NAN, 100.0), 8);
    assert_eq!(lod_slabs(0, 8.0, 1.0, 1.0), 1);
}

/// The oriented splat (section 3.4): area `overlap x area per photon` when unclamped, axes in
/// the surface plane and orthogonal, stretched along the projected direction by at most
/// sqrt(max anisotropy); guards at zero, huge and non-finite inputs.
#[test]
fn volume_splat_footprint() {
    use bevy_caustics::volume::volume_splat_axes;
    use core::f32::consts::PI;
    let n = Vec3::Y;
    // (direction, expected major / minor axis ratio = min(1 / cos, 16)).
    for (dir, ratio) in [
        (Vec3::NEG_Y, 1.0),
        (Vec3::new(1.0, -1.0, 0.0).normalize(), 2f32.sqrt()),
        (Vec3::new(1.0, -1e-6, 0.0).normalize(), 16.0),
    ] {
        let (a, b) = volume_splat_axes(dir, n, 1e-4, 4.0, 10.0, 0.5, 16.0, 1e-6);
        let area = PI * a.length() * b.length();
        assert!((area / 4e-4 - 1.0).abs() < 1e-4, "{area}");
        assert!(a.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && a.dot(b).abs() < 1e-9);
        assert!((a.length() / b.length() - ratio).abs() < 1e-3 * ratio);
        // The major axis follows the projected direction.
        if ratio > 1.0 {
            assert!(a.normalize().dot(Vec3::X) > 0.999);
        }
    }
    // The path-length cap, the minimum radius, and guards.
    let (a, _) = volume_splat_axes(Vec3::NEG_Y, n, 1.0, 4.0, 0.01, 0.5, 16.0, 1e-6);
    assert!((a.length() - 0.005).abs() < 1e-6);
    for (d, nn, area, len, rmin) in [
        (Vec3::ZERO, Vec3::ZERO, 0.0, 0.0, 0.0),
        (Vec3::NAN, Vec3::NAN, f32::NAN, f32::NAN, f32::NAN),
        (Vec3::Y, Vec3::Y, f32::INFINITY, f32::INFINITY, 1e-3),
        (Vec3::splat(1e30), Vec3::X, 1e30, 1e30, 1e30),
    ] {
        let (a, b) = volume_splat_axes(d, nn, area, 4.0, len, 0.5, 16.0, rmin);
        assert!(a.is_finite() && b.is_finite(), "{d} {nn}: {a} {b}");
        assert!(a.length() > 0.0 && b.length() > 0.0);
    }
}

/// The receiver area of a projector texel: the on-axis closed form, the cosine clamp, guards.
#[test]
fn volume_projector_texel_area() {
    use bevy_caustics::volume::projector_texel_area;
    let ax = Vec3::Z;
    // On axis at z = 2 with h = (1, 0.5, 1), 100 px: (2 * 1 * 2 / 100) * (2 * 0.5 * 2 / 100).
    let a = projector_texel_area(2.0, 1.0, 1.0, 0.5, 100, ax, ax, -ax);
    assert!((a - 0.04 * 0.02).abs() < 1e-9, "{a}");
    // A receiver tilted 60 degrees: twice the area.
    let n = Vec3::new(0.0, 3f32.sqrt() / 2.0, -0.5);
    let b = projector_texel_area(2.0, 1.0, 1.0, 0.5, 100, ax, ax, n);
    assert!((b / a - 2.0).abs() < 1e-4);
    // Grazing: clamped at 1000x.
    let c = projector_texel_area(2.0, 1.0, 1.0, 0.5, 100, ax, ax, Vec3::X);
    assert!((c / a - 1000.0).abs() < 1e-2);
    assert_eq!(
        projector_texel_area(f32::NAN, 1.0, 1.0, 1.0, 0, ax, ax, ax),
        0.0
    );
    assert!(projector_texel_area(1e20, 1e-20, 1e20, 1e20, 1, ax, ax, ax) == 0.0);
}

/// A glTF node declares a volume through `extras` (docs/volumes.md).
#[test]
fn volume_from_gltf_extras() {
    use bevy_caustics::VolumeFace;
    use bevy_caustics::headless::volume_from_extras;
    let v = volume_from_extras(
        r#"{"caustics_volume": {"size": [2, 1, 3], "slabs": 4, "photons": 5000,
            "entry": "NegZ", "exit": ["PosZ", "+X"], "culling": ["NegY"],
            "projector_resolution": 128, "gbuffer_resolution": 64, "progressive": 2500}}"#,
    )
    .expect("parsed");
    assert_eq!(v.size, Vec3::new(2.0, 1.0, 3.0));
    assert_eq!((v.slabs, v.photons), (4, 5000));
    assert_eq!(v.entry, VolumeFace::NegZ);
    assert_eq!(v.exit, vec![VolumeFace::PosZ, VolumeFace::PosX]);
    assert_eq!(v.culling, vec![VolumeFace::NegY]);
    assert_eq!((v.projector_resolution, v.gbuffer_resolution), (128, 64));
    assert_eq!(v.progressive, 2500);
    assert!(volume_from_extras(r#"{"other": 1}"#).is_none());
    assert!(volume_from_extras("not json").is_none());
}

/// The volume's settings are validated with one fix per bad field.
#[test]
fn volume_settings_are_clamped() {
    use bevy_caustics::CausticsVolume;
    use bevy_caustics::components::validate::sanitize_volume;
    let mut v = CausticsVolume {
        gbuffer_resolution: 1,
        tile_size: 0,
        density_photons: 0,
        splat_overlap: f32::NAN,
        blur_radius: 99,
        lod_distance: -1.0,
        ..Default::default()
    };
    let fields: Vec<_> = sanitize_volume(&mut v, &Default::default())
        .iter()
        .map(|f| f.0)
        .collect();
    assert_eq!(
        fields,
        [
            "gbuffer_resolution",
            "tile_size",
            "density_photons",
            "splat_overlap",
            "blur_radius",
            "lod_distance"
        ]
    );
    assert!(sanitize_volume(&mut v, &Default::default()).is_empty());
}
