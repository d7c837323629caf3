//! Robust ray-origin offsetting, scale independent.

use glam::Vec3;

/// Guard (stiff suite: "caster 1e-3 m", "caster 1e4 m").
/// Offset a surface point `p` along the geometric normal `n` (pointing to the side the new ray
/// leaves on) so that the new ray cannot re-hit the surface it starts on.
///
/// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing
/// Gems, chapter 6): the offset is a fixed number of ULPs of each coordinate, so it works the
/// same for scenes at 1e-3 m and at 1e4 m. Near the origin, where ULPs vanish, the paper adds
/// a small absolute offset (1/65536 inside |x| < 1/32 for unit-sized scenes); we scale both
/// constants by `scene_scale` (the scene's extent in metres, clamped to [1e-6, 1e6]) so a
/// millimetre-sized caster is not stepped over.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3, scene_scale: f32) -> Vec3 {
    let s = if scene_scale.is_finite() {
        scene_scale.clamp(1e-6, 1e6)
    } else {
        1.0
    };
    let origin_band: f32 = s / 32.0;
    let float_scale: f32 = s / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = [
        (INT_SCALE * n.x) as i32,
        (INT_SCALE * n.y) as i32,
        (INT_SCALE * n.z) as i32,
    ];
    let pa = p.to_array();
    let na = n.to_array();
    let mut out = [0.0f32; 3];
    for i in 0..3 {
        let bits = pa[i].to_bits() as i32;
        let shifted = if pa[i] < 0.0 {
            bits.wrapping_sub(of_i[i])
        } else {
            bits.wrapping_add(of_i[i])
        };
        let p_i = f32::from_bits(shifted as u32);
        out[i] = if pa[i].abs() < origin_band {
            pa[i] + float_scale * na[i]
        } else if p_i.is_finite() {
            p_i
        } else {
            pa[i]
        };
    }
    Vec3::from_array(out)
}
