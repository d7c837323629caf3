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
        assert_eq!(
            (v.entry, v.exit.as_slice()),
            (VolumeFace::PosY, &[VolumeFace::NegY][..])
        );
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
