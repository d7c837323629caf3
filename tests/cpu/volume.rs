//! Caustics-volume groundwork (seed 000): the media-interface rule and `CausticsVolume::fit`.

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
