//! The image metrics the report, the CLI and the GPU tests compare with: RMSE, FLIP, energy,
//! and FLIP over the pixels the caustic lights.

use bevy_caustics::reference::{CausticImage, compare};
use glam::Vec3;

#[test]
fn metrics_behave() {
    let mut a = CausticImage::new(32, 32);
    for (i, p) in a.data.iter_mut().enumerate() {
        *p = Vec3::splat(((i * 37) % 101) as f32);
    }
    let m = compare(&a, &a, None).unwrap();
    assert_eq!((m.rmse, m.energy_error), (0.0, 0.0));
    assert!(m.flip < 1e-6);
    let mut b = a.clone();
    for p in &mut b.data {
        *p *= 1.1;
    }
    let m = compare(&b, &a, None).unwrap();
    assert!((m.energy_error - 0.1).abs() < 1e-4);
    assert!(m.rmse > 0.0 && m.flip > 0.0);
    assert!(compare(&CausticImage::new(2, 2), &a, None).is_none());
}

/// FLIP over the caustic: only the pixels the reference's caustic lights count, so a spot
/// smeared into its dark surround scores worse there than over the whole image.
#[test]
fn flip_over_the_caustic() {
    use bevy_caustics::reference::metrics::caustic_lit;
    let square = |lo: usize, hi: usize, inside: f32| {
        let mut img = CausticImage::new(64, 64);
        for (i, p) in img.data.iter_mut().enumerate() {
            let (x, y) = (i % 64, i / 64);
            let hit = (lo..hi).contains(&x) && (lo..hi).contains(&y);
            *p = Vec3::splat(if hit { inside } else { 0.1 });
        }
        img
    };
    // An 8 x 8 px spot of 1000 lx on a 0.1 lx floor (below `LIT_FRACTION`, 1 %, of the
    // spot: not lit).
    let r = square(28, 36, 1000.0);
    let lit = caustic_lit(&r, None);
    assert_eq!(lit.iter().filter(|l| **l).count(), 64);
    // The same energy spread over 24 x 24 px.
    let t = square(20, 44, 0.1 + 64.0 * 1000.0 / 576.0);
    let m = compare(&t, &r, None).unwrap();
    assert!(m.flip_caustic > 2.0 * m.flip, "{m:?}");
    assert!(m.flip_caustic > 0.3, "{m:?}");
    assert_eq!(compare(&r, &r, None).unwrap().flip_caustic, 0.0);
    assert!(
        caustic_lit(&CausticImage::new(8, 8), None)
            .iter()
            .all(|l| !l)
    );
}
