//! The AAPS core (seed 004, van Casteren, sections 2.3.1, 3.1, 3.2, 3.3): the equal-area
//! direction mapping, the sum quadtree and its task walk, the density update, photon energy,
//! photon differential transfer and the anisotropic splat ellipse. Plain Rust; the GPU
//! technique's WGSL twins are tested against these.

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4};

use glam::{UVec2, Vec2, Vec3};

use super::pcg_hash;

/// Clarberg's octahedral equal-area map from the unit square to the unit sphere (seed 004
/// section 3.1.2: "a function that takes two parameters and returns a normalized direction,
/// equally distributing the inputs"; never latitude-longitude, which crowds the poles).
///
/// With `(u, v) = 2 uv - 1`, `d = 1 - |u| - |v|`, `r = 1 - |d|`, `φ = π/4 ((|v| - |u|)/r + 1)`:
/// `z = sign(d)(1 - r²)`, `x = sign(u) r sqrt(2 - r²) cos φ`, `y = sign(v) r sqrt(2 - r²) sin φ`.
/// Equal cells of the square map to equal solid angles (4π / cells). Inputs are clamped to
/// the square.
pub fn equal_area_square_to_sphere(uv: Vec2) -> Vec3 {
    let p = uv.clamp(Vec2::ZERO, Vec2::ONE) * 2.0 - Vec2::ONE;
    let (au, av) = (p.x.abs(), p.y.abs());
    let d = 1.0 - (au + av);
    let r = 1.0 - d.abs();
    let phi = if r > 0.0 {
        FRAC_PI_4 * ((av - au) / r + 1.0)
    } else {
        0.0
    };
    let f = r * (2.0 - r * r).max(0.0).sqrt();
    let z = (1.0 - r * r).copysign(d);
    let v = Vec3::new(f * phi.cos().copysign(p.x), f * phi.sin().copysign(p.y), z);
    v.try_normalize().unwrap_or(Vec3::Z)
}

/// Inverse of [`equal_area_square_to_sphere`].
pub fn equal_area_sphere_to_square(dir: Vec3) -> Vec2 {
    let d = dir.try_normalize().unwrap_or(Vec3::Z);
    let r = (1.0 - d.z.abs()).max(0.0).sqrt();
    let phi = d.y.abs().atan2(d.x.abs());
    let mut v = r * phi / FRAC_PI_2;
    let mut u = r - v;
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    let p = Vec2::new(u.copysign(d.x), v.copysign(d.y));
    ((p + Vec2::ONE) * 0.5).clamp(Vec2::ZERO, Vec2::ONE)
}

/// The photons a density-texture texel of density `d` sends: the largest square not above
/// `d` (seed 004 section 3.1.2: "a leaf of the quadtree always contains a square number").
/// Non-finite or negative densities send nothing.
pub fn floor_square(d: f32) -> u32 {
    if !d.is_finite() || d <= 0.0 {
        return 0;
    }
    let k = d.min(16_777_216.0).sqrt().floor() as u32;
    k * k
}

/// The photons a texel of density `d` sends: `floor(d)`, at most 2^24. Non-finite or negative
/// densities send nothing. (Ours: the thesis rounds down to a square because its samples sit on a
/// `k x k` grid; [`leaf_sample_uv`] places any count, so the budget's densities are not rounded
/// down by up to `2 sqrt(d)` photons.)
pub fn photon_count(d: f32) -> u32 {
    if !d.is_finite() || d <= 0.0 {
        return 0;
    }
    d.min(16_777_216.0).floor() as u32
}

/// A sum quadtree over a square, power-of-two density texture (seed 004 sections 2.3.1 and
/// 3.1.5: every node holds the sum of the photon counts of the leaves below it).
#[derive(Clone, Debug, PartialEq)]
pub struct SumQuadtree {
    /// `levels[0]` are the leaves (photons per texel, [`photon_count`]), `levels.last()` the root.
    pub levels: Vec<Vec<u32>>,
    /// Side of the leaf level.
    pub size: u32,
}

impl SumQuadtree {
    /// Build from a `size x size` density texture (row-major); `size` must be a power of two
    /// (other sizes return `None`). Sums saturate instead of overflowing.
    pub fn build(density: &[f32], size: u32) -> Option<Self> {
        if !size.is_power_of_two() || density.len() != (size * size) as usize {
            return None;
        }
        let mut levels = vec![
            density
                .iter()
                .map(|d| photon_count(*d))
                .collect::<Vec<u32>>(),
        ];
        let mut s = size;
        while s > 1 {
            let prev = levels.last().unwrap();
            let h = s / 2;
            let mut next = vec![0u32; (h * h) as usize];
            for y in 0..h {
                for x in 0..h {
                    let at = |dx: u32, dy: u32| prev[((2 * y + dy) * s + 2 * x + dx) as usize];
                    next[(y * h + x) as usize] = at(0, 0)
                        .saturating_add(at(1, 0))
                        .saturating_add(at(0, 1))
                        .saturating_add(at(1, 1));
                }
            }
            levels.push(next);
            s = h;
        }
        Some(Self { levels, size })
    }

    /// Photons the whole tree sends.
    pub fn total(&self) -> u32 {
        self.levels.last().map_or(0, |r| r[0])
    }

    /// The walk of one thread (seed 004 figure 15): from the root, pick the child whose prefix
    /// range holds `task` (children in the order (0,0), (1,0), (0,1), (1,1)), subtract the
    /// skipped counts, repeat to the leaf. Returns the texel, the sample index inside it and
    /// the leaf's sample count; `None` for `task >= total`.
    pub fn walk(&self, task: u32) -> Option<(UVec2, u32, u32)> {
        if task >= self.total() {
            return None;
        }
        let mut rest = task;
        let mut pos = UVec2::ZERO;
        let mut side = 1u32;
        for level in self.levels.iter().rev().skip(1) {
            side *= 2;
            let mut chosen = None;
            for off in [
                UVec2::new(0, 0),
                UVec2::new(1, 0),
                UVec2::new(0, 1),
                UVec2::new(1, 1),
            ] {
                let c = pos * 2 + off;
                let n = level[(c.y * side + c.x) as usize];
                if rest < n {
                    chosen = Some(c);
                    break;
                }
                rest -= n;
            }
            pos = chosen?;
        }
        let count = self.levels[0][(pos.y * self.size + pos.x) as usize];
        Some((pos, rest, count))
    }
}

/// The R2 sequence's steps (Roberts 2018: `1/g`, `1/g^2` with `g^3 = g + 1`) in 0.32 fixed
/// point, so that `n a mod 1` is exact for every sample index.
pub const R2_STEP: [u32; 2] = [3_242_174_889, 2_447_445_414];

/// Where sample `sample` of a leaf lies in the unit square of the whole texture (`size x size`
/// texels): [`leaf_sample_uv_rotated`] without a frame rotation.
pub fn leaf_sample_uv(texel: UVec2, sample: u32, size: u32) -> Vec2 {
    leaf_sample_uv_rotated(texel, sample, size, [0, 0])
}

/// The rotation of frame `frame`'s sample patterns (two [`pcg_hash`]es of the frame index):
/// AAPS adds it to every texel's shift, so each frame traces an independent set of photons
/// and the temporal stage's mean gathers them (issue 28). WGSL twin `quadtree_frame_rotation`.
pub fn frame_rotation(frame: u32) -> [u32; 2] {
    let h = pcg_hash(frame ^ 0x2c1b_3c6d);
    [h, pcg_hash(h ^ 0x297a_2d39)]
}

/// Where sample `sample` of a leaf lies in the unit square of the whole texture (`size x size`
/// texels): point `sample` of the R2 Kronecker set
/// `frac(s + r + (i + 1/2) (1/g, 1/g^2))`, shifted by `s`, a per-texel Cranley-Patterson
/// rotation (two [`pcg_hash`]es of the texel index), and by `r`, the frame's `rotation`
/// ([`frame_rotation`]), both in 0.32 fixed point.
///
/// Ours, not the thesis's `k x k` grid of cell centres: that grid is the same lattice in every
/// texel, and it beats against the pixel grid as concentric moiré rings around a focus. The R2
/// set is low-discrepancy for any count (so densities need not be squares, [`photon_count`]),
/// and the per-texel rotation makes neighbouring texels' patterns independent; each point is
/// uniform over its texel (so a photon's energy `power / count` is unbiased), whatever the
/// rotation. For one rotation it is fixed per texel (a texel's first `n` points are the same
/// whatever its count). Exact in 0.32 fixed point (wrapping integer arithmetic), so the WGSL
/// twin `quadtree_leaf_sample_uv_rotated` gives the same bits.
pub fn leaf_sample_uv_rotated(texel: UVec2, sample: u32, size: u32, rotation: [u32; 2]) -> Vec2 {
    let id = texel.y.wrapping_mul(size).wrapping_add(texel.x);
    let h = pcg_hash(id.wrapping_mul(2_654_435_761) ^ 0x5bd1_e995);
    let shift = [
        h.wrapping_add(rotation[0]),
        pcg_hash(h ^ 0x68e3_1da4).wrapping_add(rotation[1]),
    ];
    let step = |k: usize| {
        // (i + 1/2) a = i a + a / 2, all mod 2^32.
        let x = shift[k]
            .wrapping_add(sample.wrapping_mul(R2_STEP[k]))
            .wrapping_add(R2_STEP[k] >> 1);
        // Top 24 bits: exact in f32, in [0, 1).
        (x >> 8) as f32 * (1.0 / 16_777_216.0)
    };
    (texel.as_vec2() + Vec2::new(step(0), step(1))) / size.max(1) as f32
}

/// The suggested density of seed 004 section 3.1.5 (after Yang and Ouyang):
/// `D' = D A / A_t + v g`, with `A` the average projected splat area, `A_t` the target area,
/// `v` the variance and `g` the variance gain. Guards: a non-positive or non-finite target
/// area is treated as `A` (no area term), non-finite inputs as 0.
pub fn suggested_density(d: f32, area: f32, target_area: f32, variance: f32, gain: f32) -> f32 {
    let f = |x: f32| if x.is_finite() { x.max(0.0) } else { 0.0 };
    let (d, area, v, g) = (f(d), f(area), f(variance), f(gain));
    let ratio = if target_area.is_finite() && target_area > 0.0 {
        area / target_area
    } else {
        1.0
    };
    let out = d * ratio + v * g;
    if out.is_finite() { out } else { f32::MAX }
}

/// Temporal and spatial blend of seed 004 section 3.1.5:
/// `D_final = w_t D' + (1 - w_t) Σ w_i D_i / Σ w_i` over the previous densities of the texel
/// and its four neighbours, then clamped to `[min_density, max_density]` (the thesis keeps at
/// least 4 samples so no region stops being sampled) and rounded down to a square.
pub fn blend_density(
    suggested: f32,
    previous: &[(f32, f32)],
    w_t: f32,
    min_density: f32,
    max_density: f32,
) -> f32 {
    let w_t = if w_t.is_finite() {
        w_t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let (mut sw, mut sd) = (0.0f32, 0.0f32);
    for &(w, d) in previous {
        if w.is_finite() && w > 0.0 && d.is_finite() {
            sw += w;
            sd += w * d;
        }
    }
    let spatial = if sw > 0.0 { sd / sw } else { suggested };
    let min = min_density.max(1.0);
    let max = if max_density.is_finite() && max_density >= min {
        max_density
    } else {
        f32::MAX
    };
    let d = (w_t * suggested + (1.0 - w_t) * spatial).clamp(min, max.min(16_777_216.0));
    floor_square(d).max(floor_square(min)).max(1) as f32
}

/// Energy of one photon (seed 004 section 3.2.1): the light's power split equally over the
/// density texture's partitions, then over the photons of the partition. Zero if either count
/// is zero.
pub fn photon_energy(light_power: Vec3, partitions: u32, photons_in_partition: u32) -> Vec3 {
    if partitions == 0 || photons_in_partition == 0 {
        return Vec3::ZERO;
    }
    light_power / partitions as f32 / photons_in_partition as f32
}

/// Transfer a differential ray `(o, d)` to the plane through `p` with normal `n` (Igehy's
/// transfer, seed 004 section 3.3.2: differentials are "updated as if they intersect the same
/// triangle as the main ray"). Returns the point, or `p` itself when the ray is parallel to the
/// plane (guard; the caller counts it).
pub fn transfer_to_plane(o: Vec3, d: Vec3, p: Vec3, n: Vec3) -> (Vec3, bool) {
    let den = d.dot(n);
    if den.abs() < 1e-12 || !den.is_finite() {
        return (p, false);
    }
    let t = (p - o).dot(n) / den;
    let q = o + d * t;
    if q.is_finite() { (q, true) } else { (p, false) }
}

/// An anisotropic splat: the ellipse `{c + s a + t b : s² + t² <= 1}` on a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Major semi-axis (world space, in the surface plane).
    pub a: Vec3,
    /// Minor semi-axis, perpendicular to `a`.
    pub b: Vec3,
}

impl Splat {
    /// Area `π |a| |b|`.
    pub fn area(&self) -> f32 {
        core::f32::consts::PI * self.a.length() * self.b.length()
    }

    /// Anisotropy `|a| / |b|` (>= 1).
    pub fn anisotropy(&self) -> f32 {
        self.a.length() / self.b.length().max(f32::MIN_POSITIVE)
    }
}

/// The splat ellipse from a photon's two differential offsets on the receiving surface
/// (`du`, `dv`: where the two perturbed photons landed minus where the photon landed, seed 004
/// section 3.3.2), projected into the surface plane of normal `n`.
///
/// The offsets span a parallelogram; the ellipse with the same second moments has the singular
/// vectors of `[du dv]` as axes. Its anisotropy is limited to `max_anisotropy` by growing the
/// minor axis (seed 004 section 3.1.2: "their anisotropy is limited ... by reshaping them"), and
/// its semi-axes are kept within `[min_radius, max_radius]` (guards against zero and huge
/// splats; the caller counts clamps through the returned flag).
pub fn splat_from_differentials(
    du: Vec3,
    dv: Vec3,
    n: Vec3,
    max_anisotropy: f32,
    min_radius: f32,
    max_radius: f32,
) -> (Splat, bool) {
    let n = n.try_normalize().unwrap_or(Vec3::Y);
    let (t, b) = super::orthonormal_basis(n);
    let proj = |v: Vec3| {
        let v = if v.is_finite() { v } else { Vec3::ZERO };
        Vec2::new(v.dot(t), v.dot(b))
    };
    let (p, q) = (proj(du), proj(dv));
    // Symmetric 2x2 M = P P^T with P = [p q]; its eigenvectors are the axes, sqrt(eigenvalues)
    // the semi-axis lengths.
    let (m00, m01, m11) = (
        p.x * p.x + q.x * q.x,
        p.x * p.y + q.x * q.y,
        p.y * p.y + q.y * q.y,
    );
    let tr = m00 + m11;
    let disc = ((m00 - m11) * (m00 - m11) * 0.25 + m01 * m01)
        .max(0.0)
        .sqrt();
    let (l1, l2) = ((0.5 * tr + disc).max(0.0), (0.5 * tr - disc).max(0.0));
    let axis = if m01.abs() > 1e-30 {
        Vec2::new(l1 - m11, m01).normalize_or(Vec2::X)
    } else if m00 >= m11 {
        Vec2::X
    } else {
        Vec2::Y
    };
    let (mut ra, mut rb) = (l1.sqrt(), l2.sqrt());
    let lo = min_radius.max(0.0);
    let hi = if max_radius.is_finite() && max_radius >= lo {
        max_radius
    } else {
        f32::MAX
    };
    let aniso = if max_anisotropy.is_finite() {
        max_anisotropy.max(1.0)
    } else {
        f32::MAX
    };
    let orig = (ra, rb);
    ra = if ra.is_finite() { ra.clamp(lo, hi) } else { hi };
    rb = if rb.is_finite() { rb.clamp(lo, hi) } else { lo };
    rb = rb.max(ra / aniso).min(ra);
    let clamped = (ra, rb) != orig;
    let a3 = t * axis.x + b * axis.y;
    let b3 = n.cross(a3);
    (
        Splat {
            a: a3 * ra,
            b: b3 * rb,
        },
        clamped,
    )
}

/// How the frame's photon budget is spent (ours; seed 004 leaves the total to the target area
/// alone): a floor of `share` of the budget spread evenly over the *contributing* texels (those
/// whose photons reached a visible receiver last frame), the rest following the thesis's
/// density `D'`, scaled down when it would spend more.
///
/// Why a floor: `D' = D A / A_t` sends photons where splats are large and takes them from a
/// focus, where splats are sub-pixel. There the pixel error comes from how many photons land in
/// each pixel, so a focus left at the minimum density keeps its error at every budget (RMSE on
/// `glass_sphere` 165 / 163 / 163 lx at 2^16 / 2^18 / 2^20 photons). The floor grows with the
/// budget, and only texels that deliver light get it: texels that miss every caster, or whose
/// light leaves the view, stay at the minimum.
///
/// `budget` is the frame's photon budget, `sum` the sum of the blended densities `D'` over all
/// texels, `contributing` and `idle` the counts of contributing and other texels. The idle
/// texels' minimum comes out of the budget first. Returns `(floor, scale)` for
/// [`budget_density`]: `floor = share B' / contributing`, `scale = min(1, (1 - share) B' / sum)`
/// with `B' = max(budget - idle floor_square(min), 0)`, so the texels' total is at most the
/// budget whenever the budget covers the idle texels' minimum.
pub fn budget_split(
    budget: f32,
    share: f32,
    sum: f32,
    contributing: u32,
    idle: u32,
    min_density: f32,
) -> (f32, f32) {
    let share = if share.is_finite() {
        share.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let budget = if budget.is_finite() {
        budget.max(0.0)
    } else {
        0.0
    };
    let lo = floor_square(min_density.max(1.0)) as f32;
    let rest = (budget - lo * idle as f32).max(0.0);
    let floor = if contributing > 0 {
        share * rest / contributing as f32
    } else {
        0.0
    };
    let adaptive = (1.0 - share) * rest;
    let scale = if sum.is_finite() && sum > adaptive {
        adaptive / sum
    } else {
        1.0
    };
    (floor, scale)
}

/// A texel's density under the budget ([`budget_split`]): `max(floor, scale D')` for a
/// contributing texel, `scale D'` for the others, at most `max_density` (0: none), at least the
/// minimum's square. Not rounded: the texel sends [`photon_count`] photons.
pub fn budget_density(
    d: f32,
    contributing: bool,
    floor: f32,
    scale: f32,
    min_density: f32,
    max_density: f32,
) -> f32 {
    let d = if d.is_finite() { d.max(0.0) } else { 0.0 };
    let mut out = d * scale;
    if contributing {
        out = out.max(floor);
    }
    if max_density > 0.0 {
        out = out.min(max_density);
    }
    let out = out.max(floor_square(min_density.max(1.0)) as f32);
    if out.is_finite() {
        out.min(16_777_216.0)
    } else {
        16_777_216.0
    }
}

/// The starting (and, for a frozen task buffer, the permanent) uniform density: the budget
/// spread evenly over `texels`, at least `min_density`, at most `max_density` (0: none),
/// rounded down to a square.
pub fn uniform_density(budget: f64, texels: u32, min_density: f32, max_density: f32) -> f32 {
    let per = if texels == 0 {
        0.0
    } else {
        (budget / texels as f64) as f32
    };
    let mut d = per.max(min_density.max(1.0));
    if max_density > 0.0 && max_density.is_finite() {
        d = d.min(max_density.max(min_density.max(1.0)));
    }
    floor_square(d).max(1) as f32
}
