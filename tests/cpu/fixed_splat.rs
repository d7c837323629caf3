//! The fixed-point words shared by image space's photon map and the blend-free splats
//! (`render::fixed_splat`): rounded to nearest, 64-bit sums with carries decode to the sum of
//! the values within half a unit per word.

use bevy_caustics::optics::{FIXED_POINT_SCALE, fixed_point_value, fixed_point_word};

fn add(sum: &mut (u32, u32), v: f32) {
    let (w, _) = fixed_point_word(v, FIXED_POINT_SCALE, 0.5);
    let (low, carry) = sum.0.overflowing_add(w);
    sum.0 = low;
    sum.1 = sum.1.wrapping_add(carry as u32);
}

#[test]
fn fixed_point_sums_carry_into_the_high_word() {
    // A million fragments of 5000 lux: 1.28e12 units, past 2^32 many times over.
    let mut sum = (0u32, 0u32);
    for _ in 0..1_000_000 {
        add(&mut sum, 5000.0);
    }
    let total = fixed_point_value(sum.0, sum.1, FIXED_POINT_SCALE) as f64;
    assert!((total - 5.0e9).abs() <= 5.0e9 * 1e-6, "{total}");
    // Many values off the grid: rounded to nearest, within half a unit per fragment.
    let mut sum = (0u32, 0u32);
    let v = 0.123_456_7f32;
    for _ in 0..100_000 {
        add(&mut sum, v);
    }
    let total = fixed_point_value(sum.0, sum.1, FIXED_POINT_SCALE) as f64;
    let exact = v as f64 * 100_000.0;
    assert!(
        (total - exact).abs() <= 100_000.0 * 0.5 / FIXED_POINT_SCALE as f64,
        "{total} vs {exact}"
    );
    // The extremes decode finite.
    assert!(fixed_point_value(u32::MAX, u32::MAX, FIXED_POINT_SCALE).is_finite());
    assert_eq!(fixed_point_value(0, 0, FIXED_POINT_SCALE), 0.0);
}
